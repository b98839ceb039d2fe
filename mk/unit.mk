# mk/unit.mk — the libcheck unit tests (tests/unit/test_*.c), linked with the
# firmware and what fragments add to UNIT_EXTRA_SRC (the host_sim plant
# library, the host NVM port).
#
#   make unit       -std=c99, x86-64, ASan + UBSan (HOST_CFLAGS; the host
#                   objects are shared with SIL and the tools); part of
#                   `make test`
#
# The Makefile reads this file after every other fragment, so that
# UNIT_EXTRA_SRC is complete here.
#
# libcheck runs each test in a forked child by default; under ASan a fork
# costs several ms, which made a table-driven suite take a minute. Tests
# run in-process (a crash still fails the program, with the sanitizer's
# report); `make unit CK_FORK=yes` isolates every test again.
CK_FORK ?= no

# $(call run_check_programs,NAME,PROGRAMS): run each program, report how
# many failed, fail if any did.
run_check_programs = set -e; fails=0; for t in $(2); do \
	  echo "== $$t"; \
	  if ! CK_FORK=$(CK_FORK) CK_DEFAULT_TIMEOUT=600 $$t; then fails=$$((fails+1)); fi; \
	done; \
	if [ $$fails -ne 0 ]; then echo "$(1): $$fails test program(s) failed"; exit 1; fi

UNIT_SRC := $(sort $(wildcard tests/unit/test_*.c))
UNIT_BIN := $(UNIT_SRC:tests/unit/%.c=$(BUILD)/unit/%)

$(BUILD)/unit/%.o: tests/unit/%.c
	@mkdir -p $(@D)
	$(CC) $(HOST_CFLAGS) $(UNIT_CFLAGS) $(SRC_CFLAGS_$<) -MMD -MP -c $< -o $@

$(BUILD)/unit/%: $(BUILD)/unit/%.o $(FW_HOST_OBJ) $(UNIT_EXTRA_OBJ)
	$(CC) $(SAN) -o $@ $^ $(CHECK_LIBS) -lm

unit: deps $(UNIT_BIN)
	@$(call run_check_programs,unit,$(UNIT_BIN))
