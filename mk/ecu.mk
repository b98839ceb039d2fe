# mk/ecu.mk — canfdi-ecu, the supervisor as a Linux process on SocketCAN
# (firmware/port/linux/canfdi_ecu_*.c: the loop, command line, NVM and
# statistics; canfdi_socketcan.c; the host NVM port canfdi_nvm_file.c of
# mk/nvm.mk).
#
#   make $(BUILD)/bin/canfdi-ecu       UBSan build (warnings of HOST_CFLAGS,
#                                      asserts on; part of `make all`)
#   make $(BUILD)/bin/canfdi-ecu-asan  ASan + UBSan from the HOST_CFLAGS objects,
#                                      for hosts whose own kernel has vcan
#   make $(BUILD)/bin/canfdi-ecu-rel   -O2, no sanitizers: for timing figures
#                                      (latency on a sanitizer build means little)
#
# Why the default is not ASan: inside User-Mode Linux (tools/vcan-run on
# kernels without SocketCAN) a process's address space ends at 0x7fc0000000,
# below the shadow range ASan needs ([0x7fff8000, 0x10007fff8000)): every
# ASan binary aborts at start ("Shadow memory range interleaves with an
# existing memory mapping"). UBSan needs no shadow and runs there. Its
# objects live in $(BUILD)/ubsan/ (UBSAN_CFLAGS), usable by any host tool
# that has to run in the sandbox.
#
# The pre-included assert.h fixes the libc feature macros before a source
# file could define them, so they come from the command line: _GNU_SOURCE
# for the main (ppoll, getopt_long), _DEFAULT_SOURCE for the socket driver
# (CMSG macros, nanosleep), _POSIX_C_SOURCE for the NVM file port.

ECU_BIN := $(BUILD)/bin/canfdi-ecu
ECU_ASAN_BIN := $(BUILD)/bin/canfdi-ecu-asan
ECU_REL_BIN := $(BUILD)/bin/canfdi-ecu-rel
ECU_PORT_SRC := firmware/port/linux/canfdi_ecu_main.c firmware/port/linux/canfdi_ecu_cli.c \
                firmware/port/linux/canfdi_ecu_nvm.c firmware/port/linux/canfdi_ecu_stats.c \
                firmware/port/linux/canfdi_socketcan.c firmware/port/linux/canfdi_nvm_file.c
ECU_FEATURES_canfdi_ecu_main := -D_GNU_SOURCE -pthread
ECU_FEATURES_canfdi_ecu_cli := -D_GNU_SOURCE
ECU_FEATURES_canfdi_ecu_nvm := -D_GNU_SOURCE -pthread
ECU_FEATURES_canfdi_ecu_stats := -D_GNU_SOURCE
ECU_FEATURES_canfdi_socketcan := -D_DEFAULT_SOURCE
ECU_FEATURES_canfdi_nvm_file := -D_POSIX_C_SOURCE=200809L

UBSAN := -fsanitize=undefined -fno-sanitize-recover=all -fno-omit-frame-pointer
UBSAN_CFLAGS := $(WARN_C) -O1 -g $(UBSAN) -Ifirmware -I$(BUILD)/gen \
                -include assert.h '-DCANFDI_ASSERT(x)=assert(x)'

$(BUILD)/ubsan/%.o: %.c
	@mkdir -p $(@D)
	$(CC) $(UBSAN_CFLAGS) $(ECU_FEATURES_$(basename $(notdir $<))) -MMD -MP -c $< -o $@

ECU_UBSAN_OBJ := $(patsubst %.c,$(BUILD)/ubsan/%.o,$(ECU_PORT_SRC) $(FW_SRC))

$(ECU_BIN): $(ECU_UBSAN_OBJ)
	@mkdir -p $(@D)
	$(CC) $(UBSAN) -pthread -o $@ $^

# ASan + UBSan: the shared HOST_CFLAGS objects (the NVM file port's flags
# come from mk/nvm.mk, read after this file).
ECU_ASAN_OBJ := $(patsubst %.c,$(BUILD)/host/%.o,$(ECU_PORT_SRC))
$(BUILD)/host/firmware/port/linux/canfdi_ecu_main.o: HOST_CFLAGS += $(ECU_FEATURES_canfdi_ecu_main)
$(BUILD)/host/firmware/port/linux/canfdi_ecu_cli.o: HOST_CFLAGS += $(ECU_FEATURES_canfdi_ecu_cli)
$(BUILD)/host/firmware/port/linux/canfdi_ecu_nvm.o: HOST_CFLAGS += $(ECU_FEATURES_canfdi_ecu_nvm)
$(BUILD)/host/firmware/port/linux/canfdi_ecu_stats.o: HOST_CFLAGS += $(ECU_FEATURES_canfdi_ecu_stats)
$(BUILD)/host/firmware/port/linux/canfdi_socketcan.o: HOST_CFLAGS += $(ECU_FEATURES_canfdi_socketcan)

$(ECU_ASAN_BIN): $(ECU_ASAN_OBJ) $(FW_HOST_OBJ)
	@mkdir -p $(@D)
	$(CC) $(SAN) -pthread -o $@ $^

$(ECU_REL_BIN): $(ECU_PORT_SRC) $(FW_SRC) $(wildcard firmware/port/linux/*.h)
	@mkdir -p $(@D)
	$(CC) $(WARN_C) -O2 -g -D_GNU_SOURCE -pthread -Ifirmware -I$(BUILD)/gen \
	  -o $@ $(filter %.c,$^)

ALL_STEPS += $(ECU_BIN) $(ECU_ASAN_BIN) $(ECU_REL_BIN)
