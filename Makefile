# canfdi — the one entry point. `make help` lists the targets.
#
# Areas add their own rules in fragments (mk/*.mk, dbc/dbc.mk,
# host_sim/host_sim.mk, bench/bench.mk) and hook into the stable targets
# through TEST_STEPS, ALL_STEPS and BENCH_STEPS.

SHELL := /bin/bash
.DEFAULT_GOAL := all
BUILD ?= build
VENV := .venv
PY := $(CURDIR)/$(VENV)/bin/python
CC := gcc
CXX := g++

# Warnings for every C file we build, host or target (README.md, conventions
# for contributors; docs/requirements.md).
WARN_C := -std=c99 -Wall -Wextra -Werror -pedantic -Wconversion \
          -Wsign-conversion -Wdouble-promotion -Wfloat-equal -Wshadow \
          -Wstrict-prototypes -Wmissing-prototypes -Wundef
SAN := -fsanitize=address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer
# Host build of the firmware core, used by unit tests, SIL and tools.
HOST_CFLAGS := $(WARN_C) -O1 -g $(SAN) -Ifirmware -I$(BUILD)/gen \
               -include assert.h '-DCANFDI_ASSERT(x)=assert(x)'
CHECK_LIBS := $(shell pkg-config --libs check 2>/dev/null || echo -lcheck -lsubunit -lm -lrt -lpthread)

# Firmware sources (the port layer is built per target, not here).
FW_SRC := $(sort $(shell find firmware -name '*.c' -not -path 'firmware/port/*' 2>/dev/null))
FW_HOST_OBJ := $(FW_SRC:%.c=$(BUILD)/host/%.o)

# Extra objects linked into every unit test (e.g. the host_sim plant library).
UNIT_EXTRA_OBJ :=
TEST_STEPS :=
ALL_STEPS :=
BENCH_STEPS :=

-include $(sort $(wildcard mk/*.mk)) $(wildcard dbc/dbc.mk host_sim/host_sim.mk bench/bench.mk tests/ref/ref.mk)

UNIT_SRC := $(sort $(wildcard tests/unit/test_*.c))
# libcheck runs each test in a forked child by default; under ASan a fork
# costs several ms, about a minute for a table-driven suite. Tests run
# in-process (a crash still fails the program, with the sanitizer's
# report); `make unit CK_FORK=yes` isolates every test.
CK_FORK ?= no
UNIT_BIN := $(UNIT_SRC:tests/unit/%.c=$(BUILD)/unit/%)

.PHONY: all deps test unit demo firmware bench clean help
# Keep object files of test programs between runs.
.SECONDARY:

help:
	@echo "canfdi make targets:"
	@echo "  make deps      install Debian packages and the Python venv (idempotent)"
	@echo "  make demo      run the demonstration (see README)"
	@echo "  make test      everything CI checks: unit tests under ASan/UBSan, target guard, ..."
	@echo "  make firmware  cross-compile for Cortex-M4 and Cortex-M0+, check no heap/float"
	@echo "  make bench     print and record figures under $(BUILD)/bench/"
	@echo "  make all       build host libraries, unit tests and tools"
	@echo "  make clean     remove $(BUILD)/"

deps:
	@bash tools/deps.sh

all: $(UNIT_BIN) $(ALL_STEPS)

$(BUILD)/host/%.o: %.c
	@mkdir -p $(@D)
	$(CC) $(HOST_CFLAGS) -MMD -MP -c $< -o $@

$(BUILD)/unit/%.o: tests/unit/%.c
	@mkdir -p $(@D)
	$(CC) $(HOST_CFLAGS) -Itests/unit -Ihost_sim $(shell pkg-config --cflags check 2>/dev/null) -MMD -MP -c $< -o $@

$(BUILD)/unit/%: $(BUILD)/unit/%.o $(FW_HOST_OBJ) $(UNIT_EXTRA_OBJ)
	$(CC) $(SAN) -o $@ $^ $(CHECK_LIBS) -lm

unit: deps $(UNIT_BIN)
	@set -e; fails=0; for t in $(UNIT_BIN); do \
	  echo "== $$t"; \
	  if ! CK_FORK=$(CK_FORK) CK_DEFAULT_TIMEOUT=600 $$t; then fails=$$((fails+1)); fi; \
	done; \
	if [ $$fails -ne 0 ]; then echo "unit: $$fails test program(s) failed"; exit 1; fi

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
