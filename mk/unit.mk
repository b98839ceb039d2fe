# mk/unit.mk — the libcheck unit tests of the firmware (tests/unit/test_*.c),
# in three flavours that build the same test programs from the same sources
# (firmware, plus what fragments add to UNIT_EXTRA_SRC: the host_sim plant
# library, the host NVM port), each with its own objects:
#
#   make unit       -std=c99, x86-64, ASan + UBSan (HOST_CFLAGS; the host
#                   objects are shared with SIL and the tools)
#   make unit-c11   -std=c11, otherwise the same (HOST_C11_CFLAGS)
#   make unit-m32   -m32: the 32-bit x86 ABI, ILP32 like the Cortex-M
#                   targets (long and pointers are 32 bits), ASan + UBSan
#                   (HOST_M32_CFLAGS; needs gcc-multilib and the i386
#                   libcheck of `make deps`)
#
# All three are part of `make test`. The Makefile reads this file after every
# other fragment, so that UNIT_EXTRA_SRC is complete here.
#
# libcheck runs each test in a forked child by default; under ASan a fork
# costs several ms, which made a table-driven suite take a minute. Tests
# run in-process (a crash still fails the program, with the sanitizer's
# report); `make unit CK_FORK=yes` isolates every test again.
CK_FORK ?= no

# $(call run_check_programs,NAME,PROGRAMS): run the programs TEST_JOBS at a
# time (the Makefile: one per core by default), each one's output printed
# whole as it ends; fail, naming them, if any failed (tools/run-each).
run_check_programs = CK_FORK=$(CK_FORK) CK_DEFAULT_TIMEOUT=600 tools/run-each $(1) $(TEST_JOBS) -- $(2)

UNIT_SRC := $(sort $(wildcard tests/unit/test_*.c))
UNIT_BIN := $(UNIT_SRC:tests/unit/%.c=$(BUILD)/unit/%)

# What each flavour promises, checked by tests/unit/test_flavour.c: the C
# standard (__STDC_VERSION__), the widths of pointers and long.
UNIT_EXPECT = -DCANFDI_UNIT_STDC=$(1) -DCANFDI_UNIT_PTR_BITS=$(2) -DCANFDI_UNIT_LONG_BITS=$(3)
UNIT_EXPECT_unit := $(call UNIT_EXPECT,199901L,64,64)
UNIT_EXPECT_c11 := $(call UNIT_EXPECT,201112L,64,64)
UNIT_EXPECT_m32 := $(call UNIT_EXPECT,199901L,32,32)

$(BUILD)/unit/%.o: tests/unit/%.c
	@mkdir -p $(@D)
	$(CC) $(HOST_CFLAGS) $(UNIT_CFLAGS) $(UNIT_EXPECT_unit) $(SRC_CFLAGS_$<) -MMD -MP -c $< -o $@

$(BUILD)/unit/%: $(BUILD)/unit/%.o $(FW_HOST_OBJ) $(UNIT_EXTRA_OBJ)
	$(CC) $(SAN) -o $@ $^ $(CHECK_LIBS) -lm

unit: deps $(UNIT_BIN)
	@$(call run_check_programs,unit,$(UNIT_BIN))

# The other flavours: $(call UNIT_FLAVOUR,NAME,CFLAGS_VAR,LDFLAGS_VAR) builds every
# object under $(BUILD)/unit-NAME/obj and the programs in $(BUILD)/unit-NAME.
# UNIT_SKIP_NAME: programs a flavour cannot build, each with the reason.
define UNIT_FLAVOUR
UNIT_BIN_$(1) := $$(filter-out $$(UNIT_SKIP_$(1):%=$$(BUILD)/unit-$(1)/%),$$(UNIT_SRC:tests/unit/%.c=$$(BUILD)/unit-$(1)/%))
UNIT_LIB_OBJ_$(1) := $$(patsubst %.c,$$(BUILD)/unit-$(1)/obj/%.o,$$(FW_SRC) $$(UNIT_EXTRA_SRC))

$$(BUILD)/unit-$(1)/obj/%.o: %.c
	@mkdir -p $$(@D)
	$$(CC) $$($(2)) $$(SRC_CFLAGS_$$<) -MMD -MP -c $$< -o $$@

$$(BUILD)/unit-$(1)/obj/tests/unit/%.o: tests/unit/%.c
	@mkdir -p $$(@D)
	$$(CC) $$($(2)) $$(UNIT_CFLAGS) $$(UNIT_EXPECT_$(1)) $$(SRC_CFLAGS_$$<) -MMD -MP -c $$< -o $$@

$$(BUILD)/unit-$(1)/%: $$(BUILD)/unit-$(1)/obj/tests/unit/%.o $$(UNIT_LIB_OBJ_$(1))
	$$(CC) $$($(3)) $$(SAN) -o $$@ $$^ $$(CHECK_LIBS) -lm

.PHONY: unit-$(1)
unit-$(1): deps $$(UNIT_BIN_$(1))
	@$$(call run_check_programs,unit-$(1),$$(UNIT_BIN_$(1)))

TEST_STEPS += unit-$(1)
endef

# test_fixp, test_rx and test_tx compute their exact reference values with
# __int128, which gcc does not offer on 32-bit x86; the firmware code they
# test (core/canfdi_fixp, comm/canfdi_rx, comm/canfdi_tx) is still built
# -m32 and runs under the other programs (test_app drives all three).
UNIT_SKIP_m32 := test_fixp test_rx test_tx

$(eval $(call UNIT_FLAVOUR,c11,HOST_C11_CFLAGS,))
$(eval $(call UNIT_FLAVOUR,m32,HOST_M32_CFLAGS,HOST_M32_LDFLAGS))
