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
# Compilers and the flags of every build flavour, each defined once.
include mk/flags.mk

# Firmware sources (the port layer is built per target, not here).
FW_SRC := $(sort $(shell find firmware -name '*.c' -not -path 'firmware/port/*' 2>/dev/null))
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

deps:
	@bash tools/deps.sh

all: $(UNIT_BIN) $(ALL_STEPS)

$(BUILD)/host/%.o: %.c
	@mkdir -p $(@D)
	$(CC) $(HOST_CFLAGS) $(SRC_CFLAGS_$<) -MMD -MP -c $< -o $@

test: deps unit $(TEST_STEPS)
	@echo "make test: all steps passed"

demo: deps
	@$(MAKE) --no-print-directory demo-run

firmware:
	@$(MAKE) --no-print-directory firmware-run

bench: deps $(BENCH_STEPS)

clean:
	rm -rf $(BUILD)

-include $(shell find $(BUILD) -name '*.d' 2>/dev/null)
