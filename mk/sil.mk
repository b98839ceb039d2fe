# mk/sil.mk — software in the loop: the firmware application against the
# host_sim plants in one process, through the DBC codecs.
#
#   make $(BUILD)/bin/canfdi-sil   the SIL runner (part of `make all`)
#   make sil-test                  every tests/sil/scenarios/*.scn except the
#                                  demo; prints "N passed, N failed"
#                                  (part of `make test`)
#   make sil-pending               the scenarios known not to pass yet
#                                  (tests/sil/pending/*.scn; not in make test)
#   make sil-long                  hours of simulated time (tests/sil/long),
#                                  with the -O2 build; not in make test
#   make sil-bench                 instructions per canfdi_app_step
#                                  ($(BUILD)/bench/sil.json; make bench)
#
# The rig's side of the bus (setpoint frames in, actuator / diagnostic
# frames out) uses a tester codec generated here from dbc/canfdi.dbc without
# a node filter (pack and unpack of every message); the plant side uses
# host_sim's PLANT codec, the firmware its ECU codec.

SIL_GEN_DIR := $(BUILD)/gen/sil
SIL_GEN_C := $(SIL_GEN_DIR)/canfdi_sil_msg.c
SIL_GEN_H := $(SIL_GEN_DIR)/canfdi_sil_msg.h
SIL_GEN_OBJ := $(BUILD)/host/sil/canfdi_sil_msg.o
SIL_SRC := tests/sil/canfdi_sil.c
SIL_OBJ := $(BUILD)/host/$(SIL_SRC:.c=.o)
SIL_BIN := $(BUILD)/bin/canfdi-sil
# host_sim.mk is read after mk/*.mk, so its SIM_LIB_OBJ is not known yet
# where a prerequisite list is expanded: the same list, formed here.
# (The CLI's main and its SocketCAN I/O are not part of the library.)
SIL_SIM_OBJ := $(patsubst %.c,$(BUILD)/host/%.o,$(filter-out host_sim/canfdi_sim_main.c host_sim/canfdi_sim_can.c,\
                 $(sort $(wildcard host_sim/*.c))) $(sort $(wildcard host_sim/gen/*.c)))
SIL_SCN := $(sort $(filter-out tests/sil/scenarios/demo.scn,$(wildcard tests/sil/scenarios/*.scn)))
SIL_PENDING := $(sort $(wildcard tests/sil/pending/*.scn))

$(SIL_GEN_H): $(SIL_GEN_C)
$(SIL_GEN_C): dbc/canfdi.dbc
	@mkdir -p $(@D)
	$(PY) -m cantools generate_c_source --database-name canfdi_sil_msg -o $(@D) $< >/dev/null

$(SIL_GEN_OBJ): $(SIL_GEN_C)
	@mkdir -p $(@D)
	$(CC) $(HOST_CFLAGS) -c $< -o $@

$(SIL_OBJ): $(SIL_GEN_H)
$(SIL_OBJ): HOST_CFLAGS += -Ihost_sim -I$(SIL_GEN_DIR) -D_POSIX_C_SOURCE=200809L

$(SIL_BIN): $(SIL_OBJ) $(SIL_GEN_OBJ) $(FW_HOST_OBJ) $(SIL_SIM_OBJ)
	@mkdir -p $(@D)
	$(CC) $(SAN) -o $@ $^ -lm

ALL_STEPS += $(SIL_BIN)

# Unit tests of the application loop without plants (libcheck, ASan/UBSan).
SIL_UNIT := $(BUILD)/sil/test_app
$(BUILD)/sil/test_app.o: tests/sil/test_app.c
	@mkdir -p $(@D)
	$(CC) $(HOST_CFLAGS) -Itests/unit $(shell pkg-config --cflags check 2>/dev/null) -MMD -MP -c $< -o $@
$(SIL_UNIT): $(BUILD)/sil/test_app.o $(FW_HOST_OBJ)
	$(CC) $(SAN) -o $@ $^ $(CHECK_LIBS) -lm

ALL_STEPS += $(SIL_UNIT)

.PHONY: sil-test sil-pending
sil-test: $(SIL_BIN) $(SIL_UNIT)
	@CK_FORK=no $(SIL_UNIT)
	@bash tests/sil/run_scenarios.sh $(SIL_BIN) $(SIL_SCN)

sil-pending: $(SIL_BIN)
	-@bash tests/sil/run_scenarios.sh $(SIL_BIN) $(SIL_PENDING)

TEST_STEPS += sil-test

# Instructions per canfdi_app_step on the host: the rig built like the
# release firmware objects (-O2, no sanitizers: valgrind cannot run ASan
# binaries), run under callgrind with collection only inside the step.
SIL_REL_BIN := $(BUILD)/bench/canfdi-sil-rel
$(SIL_REL_BIN): $(SIL_SRC) $(SIL_GEN_C) $(FW_SRC) $(filter-out host_sim/canfdi_sim_main.c host_sim/canfdi_sim_can.c,$(wildcard host_sim/*.c)) $(wildcard host_sim/gen/*.c)
	@mkdir -p $(@D)
	$(CC) $(WARN_C) -O2 -g -D_POSIX_C_SOURCE=200809L -Ifirmware -I$(BUILD)/gen -Ihost_sim -I$(SIL_GEN_DIR) -o $@ $(filter %.c,$^) -lm

.PHONY: sil-bench
sil-bench: $(SIL_REL_BIN)
	@bash tests/sil/bench_step.sh $(SIL_REL_BIN) $(BUILD)/bench/sil.json \
	  tests/sil/scenarios/nominal_setpoints.scn tests/sil/scenarios/demo.scn

BENCH_STEPS += sil-bench

.PHONY: sil-long
sil-long: $(SIL_REL_BIN)
	@bash tests/sil/run_scenarios.sh $(SIL_REL_BIN) $(sort $(wildcard tests/sil/long/*.scn))

# PIL-lite: the application cross-compiled (-Os, as `make firmware`) for
# each core, run on QEMU mps2-an386 (Cortex-M4; the M0+ code runs on the
# same core, so its figures are instruction counts) with -icount, fed the
# frames of the SIL demo's bus log: instructions per canfdi_app_step from
# SysTick, and the ECU's frames compared bit for bit with the host run.
# Semihosting (rdimon) reads the log: a test harness, not firmware.
SIL_PIL_LOG := build/demo/canfdi-demo.log
# (mk/target.mk is read after this file: its variables are used in recipes
# only, where they are expanded late; prerequisites name files directly.)
SIL_PIL_CORES := cortex-m4 cortex-m0plus
SIL_PIL_ELFS := $(foreach c,$(SIL_PIL_CORES),$(BUILD)/pil/pil_step_$(c).elf)
$(BUILD)/pil/pil_step_%.elf: tests/sil/pil_step.c $(FW_SRC) firmware/port/cortexm/canfdi_startup.c firmware/port/cortexm/canfdi_cortexm.ld
	@mkdir -p $(@D)
	$(ARM_CC) $(TGT_ARCH_$*) $(TGT_CFLAGS) -nostartfiles --specs=rdimon.specs -Wl,--gc-sections \
	  -Wl,-T,$(TGT_LDSCRIPT) -o $@ $(filter %.c,$^)

.PHONY: sil-pil
sil-pil: $(SIL_BIN) $(SIL_PIL_ELFS)
	@mkdir -p $(dir $(SIL_PIL_LOG))
	@$(SIL_BIN) -q -s tests/sil/scenarios/demo.scn -l $(SIL_PIL_LOG) >/dev/null
	@set -e; for c in $(SIL_PIL_CORES); do echo "== $$c code"; \
	  qemu-system-arm -M mps2-an386 -nographic -icount shift=6 \
	    -semihosting-config enable=on,target=native -kernel $(BUILD)/pil/pil_step_$$c.elf; done
