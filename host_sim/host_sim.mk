# host_sim/host_sim.mk — the plant simulator: the plant library (linked into
# every unit test and into the SIL runner), the `canfdi-sim` CLI, its pytest
# checks and the simulation-rate benchmark.
#
#   make $(BUILD)/bin/canfdi-sim   the CLI (part of `make all`; ASan/UBSan)
#   make $(BUILD)/hil/canfdi-sim   the CLI for User-Mode Linux (UBSan only, -O2)
#   make sim-unit                  the libcheck tests of the plant library
#                                  (tests/sim/test_*.c, ASan/UBSan)
#   make sim-test                  sim-unit, then pytest tests/sim (part of
#                                  `make test`)
#   make bench-sim                 $(BUILD)/bench/sim.json (part of `make bench`)

# The library: every host_sim/*.c except the CLI's main, plus the generated
# fault table and PLANT codec. Built with HOST_CFLAGS (strict warnings,
# ASan/UBSan) by the top Makefile's $(BUILD)/host/%.o rule.
# The CLI's SocketCAN I/O (canfdi_sim_can.c) is Linux-only and not part of
# the library either.
SIM_MAIN_SRC := host_sim/canfdi_sim_main.c
SIM_CAN_SRC := host_sim/canfdi_sim_can.c
SIM_LIB_SRC := $(filter-out $(SIM_MAIN_SRC) $(SIM_CAN_SRC),$(sort $(wildcard host_sim/*.c))) \
               $(sort $(wildcard host_sim/gen/*.c))
SIM_LIB_OBJ := $(SIM_LIB_SRC:%.c=$(BUILD)/host/%.o)
SIM_CLI := $(BUILD)/bin/canfdi-sim
SIM_E2E_SRC := firmware/comm/canfdi_e2e.c

UNIT_EXTRA_SRC += $(SIM_LIB_SRC)

# getopt_long/clock_gettime and SocketCAN (ppoll, the socket API): feature
# macros per source (SRC_CFLAGS_, mk/flags.mk).
SRC_CFLAGS_$(SIM_MAIN_SRC) := -D_GNU_SOURCE
SRC_CFLAGS_$(SIM_CAN_SRC) := -D_GNU_SOURCE

$(SIM_CLI): $(BUILD)/host/$(SIM_MAIN_SRC:.c=.o) $(BUILD)/host/$(SIM_CAN_SRC:.c=.o) $(SIM_LIB_OBJ) $(BUILD)/host/$(SIM_E2E_SRC:.c=.o)
	@mkdir -p $(@D)
	$(CC) $(SAN) -o $@ $^ -lm

ALL_STEPS += $(SIM_CLI)

# The same CLI for User-Mode Linux (tools/vcan-run): ASan cannot map its
# shadow memory in UML's smaller address space ("Shadow memory range
# interleaves with an existing memory mapping"), so this build keeps the
# strict warnings and UBSan only, at -O2 (lockstep speed; REL_UBSAN_CFLAGS).
# The HIL bench runs this one inside the sandbox.
SIM_CLI_HIL := $(BUILD)/hil/canfdi-sim
$(SIM_CLI_HIL): $(SIM_MAIN_SRC) $(SIM_CAN_SRC) $(SIM_LIB_SRC) $(SIM_E2E_SRC) $(wildcard host_sim/*.h host_sim/gen/*.h)
	@mkdir -p $(@D)
	$(CC) $(REL_UBSAN_CFLAGS) $(SRC_CFLAGS_$(SIM_MAIN_SRC)) -o $@ $(filter %.c,$^) -lm

ALL_STEPS += $(SIM_CLI_HIL)

# The plant library's unit tests: libcheck programs built and linked like
# the firmware's (mk/unit.mk: the shared main tests/unit/unit_main.h, the
# host objects), in $(BUILD)/sim/.
SIM_UNIT_SRC := $(sort $(wildcard tests/sim/test_*.c))
SIM_UNIT_BIN := $(SIM_UNIT_SRC:tests/sim/%.c=$(BUILD)/sim/%)

$(BUILD)/sim/%.o: tests/sim/%.c
	@mkdir -p $(@D)
	$(CC) $(HOST_CFLAGS) $(UNIT_CFLAGS) $(SRC_CFLAGS_$<) -MMD -MP -c $< -o $@

$(BUILD)/sim/%: $(BUILD)/sim/%.o $(FW_HOST_OBJ) $(UNIT_EXTRA_OBJ)
	$(CC) $(SAN) -o $@ $^ $(CHECK_LIBS) -lm

ALL_STEPS += $(SIM_UNIT_BIN)

.PHONY: sim-unit sim-test bench-sim
sim-unit: deps $(SIM_UNIT_BIN)
	@$(call run_check_programs,sim-unit,$(SIM_UNIT_BIN))

# tests/sim/test_canfdi_sim_can.py runs the UML build on vcan0 and skips
# (saying why) where there is none: run it through tools/vcan-run.
sim-test: deps sim-unit $(SIM_CLI) $(SIM_CLI_HIL)
	CANFDI_SIM=$(CURDIR)/$(SIM_CLI) CANFDI_SIM_HIL=$(CURDIR)/$(SIM_CLI_HIL) $(PY) -m pytest tests/sim -q

TEST_STEPS += sim-test

# Benchmark: the same sources in the release build (REL_CFLAGS), one
# translation unit each, linked directly (not the ASan objects above).
SIM_BENCH := $(BUILD)/bench/bench_sim
$(SIM_BENCH): bench/bench_sim.c $(SIM_LIB_SRC) $(SIM_E2E_SRC) $(wildcard host_sim/*.h)
	@mkdir -p $(@D)
	$(CC) $(REL_CFLAGS) -Ihost_sim -o $@ $(filter %.c,$^) -lm

bench-sim: $(SIM_BENCH)
	@$(SIM_BENCH) $(BUILD)/bench/sim.json

BENCH_STEPS += bench-sim
