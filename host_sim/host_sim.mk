# host_sim/host_sim.mk — the plant simulator: the plant library (linked into
# every unit test and into SIL later), the `canfdi-sim` CLI, its pytest
# checks and the simulation-rate benchmark.
#
#   make $(BUILD)/bin/canfdi-sim   the CLI (part of `make all`)
#   make sim-test                  pytest tests/sim (part of `make test`)
#   make bench-sim                 $(BUILD)/bench/sim.json (part of `make bench`)

# The library: every host_sim/*.c except the CLI's main, plus the generated
# fault table and PLANT codec. Built with HOST_CFLAGS (strict warnings,
# ASan/UBSan) by the top Makefile's $(BUILD)/host/%.o rule.
SIM_MAIN_SRC := host_sim/canfdi_sim_main.c
SIM_LIB_SRC := $(filter-out $(SIM_MAIN_SRC),$(sort $(wildcard host_sim/*.c))) \
               $(sort $(wildcard host_sim/gen/*.c))
SIM_LIB_OBJ := $(SIM_LIB_SRC:%.c=$(BUILD)/host/%.o)
SIM_CLI := $(BUILD)/bin/canfdi-sim
SIM_E2E_SRC := firmware/comm/canfdi_e2e.c

UNIT_EXTRA_OBJ += $(SIM_LIB_OBJ)

# The plant tests include the library headers by name.
# getopt_long/clock_gettime: the pre-included assert.h fixes feature macros
# before the file can define them, so define them here.
$(BUILD)/host/$(SIM_MAIN_SRC:.c=.o): HOST_CFLAGS += -D_GNU_SOURCE

$(SIM_CLI): $(BUILD)/host/$(SIM_MAIN_SRC:.c=.o) $(SIM_LIB_OBJ) $(BUILD)/host/$(SIM_E2E_SRC:.c=.o)
	@mkdir -p $(@D)
	$(CC) $(SAN) -o $@ $^ -lm

ALL_STEPS += $(SIM_CLI)

.PHONY: sim-test bench-sim
sim-test: deps $(SIM_CLI)
	CANFDI_SIM=$(CURDIR)/$(SIM_CLI) $(PY) -m pytest tests/sim -q

TEST_STEPS += sim-test

# Benchmark: the same sources at -O2, no sanitizers, one translation unit
# each, linked directly (not the ASan objects above).
SIM_BENCH := $(BUILD)/bench/bench_sim
$(SIM_BENCH): bench/bench_sim.c $(SIM_LIB_SRC) $(SIM_E2E_SRC) $(wildcard host_sim/*.h)
	@mkdir -p $(@D)
	$(CC) $(WARN_C) -O2 -Ifirmware -Ihost_sim -o $@ $(filter %.c,$^) -lm

bench-sim: $(SIM_BENCH)
	@$(SIM_BENCH) $(BUILD)/bench/sim.json

BENCH_STEPS += bench-sim
