# mk/ecu.mk — canfdi-ecu, the supervisor as a Linux process on SocketCAN
# (firmware/port/linux/canfdi_ecu_*.c: the loop, command line, NVM and
# statistics; canfdi_socketcan.c; the host NVM port canfdi_nvm_file.c of
# mk/nvm.mk).
#
#   make $(BUILD)/bin/canfdi-ecu       UBSan build (UBSAN_CFLAGS: warnings
#                                      and asserts of HOST_CFLAGS; part of
#                                      `make all`)
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
# The libc feature macros come from the command line, per source
# (SRC_CFLAGS_, mk/flags.mk): _GNU_SOURCE for the main (ppoll,
# getopt_long), _DEFAULT_SOURCE for the socket driver (CMSG macros,
# nanosleep); the NVM file port's are in mk/nvm.mk.

ECU_BIN := $(BUILD)/bin/canfdi-ecu
ECU_ASAN_BIN := $(BUILD)/bin/canfdi-ecu-asan
ECU_REL_BIN := $(BUILD)/bin/canfdi-ecu-rel
ECU_PORT_SRC := firmware/port/linux/canfdi_ecu_main.c firmware/port/linux/canfdi_ecu_cli.c \
                firmware/port/linux/canfdi_ecu_nvm.c firmware/port/linux/canfdi_ecu_stats.c \
                firmware/port/linux/canfdi_socketcan.c firmware/port/linux/canfdi_nvm_file.c
SRC_CFLAGS_firmware/port/linux/canfdi_ecu_main.c := -D_GNU_SOURCE -pthread
SRC_CFLAGS_firmware/port/linux/canfdi_ecu_cli.c := -D_GNU_SOURCE
SRC_CFLAGS_firmware/port/linux/canfdi_ecu_nvm.c := -D_GNU_SOURCE -pthread
SRC_CFLAGS_firmware/port/linux/canfdi_ecu_stats.c := -D_GNU_SOURCE
SRC_CFLAGS_firmware/port/linux/canfdi_socketcan.c := -D_DEFAULT_SOURCE

$(BUILD)/ubsan/%.o: %.c
	@mkdir -p $(@D)
	$(CC) $(UBSAN_CFLAGS) $(SRC_CFLAGS_$<) -MMD -MP -c $< -o $@

ECU_UBSAN_OBJ := $(patsubst %.c,$(BUILD)/ubsan/%.o,$(ECU_PORT_SRC) $(FW_SRC))

$(ECU_BIN): $(ECU_UBSAN_OBJ)
	@mkdir -p $(@D)
	$(CC) $(UBSAN) -pthread -o $@ $^

# ASan + UBSan: the shared HOST_CFLAGS objects.
ECU_ASAN_OBJ := $(patsubst %.c,$(BUILD)/host/%.o,$(ECU_PORT_SRC))

$(ECU_ASAN_BIN): $(ECU_ASAN_OBJ) $(FW_HOST_OBJ)
	@mkdir -p $(@D)
	$(CC) $(SAN) -pthread -o $@ $^

# One translation unit per source, linked directly; the main's features
# serve the other port files too.
$(ECU_REL_BIN): $(ECU_PORT_SRC) $(FW_SRC) $(FW_HDR) $(wildcard firmware/port/linux/*.h)
	@mkdir -p $(@D)
	$(CC) $(REL_CFLAGS) $(SRC_CFLAGS_firmware/port/linux/canfdi_ecu_main.c) \
	  -o $@ $(filter %.c,$^)

ALL_STEPS += $(ECU_BIN) $(ECU_ASAN_BIN) $(ECU_REL_BIN)
