# canfdi — the one entry point. `make help` lists the targets (mk/help.mk).
#
# Areas add their own rules in fragments (mk/*.mk, dbc/dbc.mk,
# host_sim/host_sim.mk, bench/bench.mk) and hook into the stable targets
# through TEST_STEPS, ALL_STEPS and BENCH_STEPS.

SHELL := /bin/bash
.DEFAULT_GOAL := all
BUILD ?= build
VENV := .venv
PY := $(CURDIR)/$(VENV)/bin/python
# pytest runs that make -j may start side by side (make test's TEST_JOBS):
# each with a temporary directory of its own, named after its target, under
# $(BUILD)/pytest (an order-only prerequisite of those targets).
PYTEST_OWN_TMP = -p no:cacheprovider -q --basetemp=$(CURDIR)/$(BUILD)/pytest/$@
# Compilers and the flags of every build flavour, each defined once.
include mk/flags.mk

# Firmware sources (the port layer is built per target, not here).
FW_SRC := $(sort $(shell find firmware -name '*.c' -not -path 'firmware/port/*' 2>/dev/null))
FW_HDR := $(sort $(shell find firmware -name '*.h' -not -path 'firmware/port/*' 2>/dev/null))
FW_HOST_OBJ := $(FW_SRC:%.c=$(BUILD)/host/%.o)

# Extra sources linked into every unit test (e.g. the host_sim plant
# library), and their host objects.
UNIT_EXTRA_SRC :=
UNIT_EXTRA_OBJ = $(UNIT_EXTRA_SRC:%.c=$(BUILD)/host/%.o)
TEST_STEPS :=
ALL_STEPS :=
BENCH_STEPS :=

-include $(sort $(filter-out mk/flags.mk mk/unit.mk,$(wildcard mk/*.mk))) \
         $(wildcard dbc/dbc.mk host_sim/host_sim.mk bench/bench.mk tests/ref/ref.mk)
# The unit tests link what the fragments add to UNIT_EXTRA_SRC: read last.
include mk/unit.mk

.PHONY: all deps test unit demo firmware bench clean help
# Keep object files of test programs between runs.
.SECONDARY:

$(BUILD)/pytest:
	@mkdir -p $@

# CANFDI_DEPS_DONE=1: make test's own steps, after its deps ran once.
deps:
	@$(if $(CANFDI_DEPS_DONE),:,bash tools/deps.sh)

all: $(UNIT_BIN) $(ALL_STEPS)

$(BUILD)/host/%.o: %.c
	@mkdir -p $(@D)
	$(CC) $(HOST_CFLAGS) $(SRC_CFLAGS_$<) -MMD -MP -c $< -o $@

# The steps run one after another, each in a make of its own, so that the
# time of each is printed as it passes (and kept in $(BUILD)/test-times.txt):
# the first failing step stops the run with its own error. Within a step,
# make builds and runs independent targets TEST_JOBS at a time, and so do
# the runners of the unit programs, SIL scenarios and reference programs
# (tools/run-each); default one per core, TEST_JOBS=1 for one at a time.
TEST_JOBS ?= $(shell nproc 2>/dev/null || echo 1)
test: deps
	@set -e; mkdir -p $(BUILD); : > $(BUILD)/test-times.txt; t_all=$$(date +%s); \
	 for s in unit $(TEST_STEPS); do t0=$$(date +%s); \
	   $(MAKE) -j$(TEST_JOBS) --no-print-directory CANFDI_DEPS_DONE=1 $$s; \
	   printf 'make test: %-24s passed in %4d s\n' "$$s" $$(( $$(date +%s) - t0 )) | tee -a $(BUILD)/test-times.txt; \
	 done; \
	 printf 'make test: all steps passed in %d s\n' $$(( $$(date +%s) - t_all )) | tee -a $(BUILD)/test-times.txt

demo: deps
	@$(MAKE) --no-print-directory demo-run

firmware:
	@$(MAKE) --no-print-directory firmware-run

bench: deps $(BENCH_STEPS)

clean:
	rm -rf $(BUILD)

-include $(shell find $(BUILD) -name '*.d' 2>/dev/null)
