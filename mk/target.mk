# mk/target.mk — the target build guard: `make firmware` (-> firmware-run).
#
# Cross-compiles every firmware module (firmware/**/*.c except port/, plus
# firmware/port/cortexm/*) and the entry point tests/target/guard_main.c for
# two no-FPU Cortex-M cores, links with --gc-sections against newlib-nano (so
# a stray malloc or double LINKS), then tests/target/fw_guard.sh inspects the
# images: no heap, no soft-float, every firmware function and every static
# inline reached from the entry point, no float/double keyword in firmware.
# Leaves $(BUILD)/target/<core>/canfdi.elf (+ .map) and prints text/data/bss.

# The toolchain and the flags (TGT_ARCH_<core>, TGT_CFLAGS, TGT_LDFLAGS) are
# in mk/flags.mk.
TGT_CORES := cortex-m4 cortex-m0plus

# Firmware sources generated outside firmware/ (e.g. a DBC codec under
# $(BUILD)/gen) may be appended here by their fragment.
FW_TARGET_EXTRA_SRC ?=
# The port's start-up code; its application loop and example board link
# into the footprint image (mk/pil.mk), not the guard image (which has its
# own main), and get the keyword check only.
TGT_PORT_APP_SRC := $(PIL_PORT_APP_SRC)
TGT_PORT_SRC := $(filter-out $(TGT_PORT_APP_SRC),$(sort $(wildcard firmware/port/cortexm/*.c)))
TGT_FW_SRC := $(FW_SRC) $(TGT_PORT_SRC) $(FW_TARGET_EXTRA_SRC)
TGT_FW_HDR := $(FW_HDR) $(sort $(wildcard firmware/port/cortexm/*.h))
TGT_MAIN := tests/target/guard_main.c
# Generated firmware headers (DBC codec, fault tables): their guard calls are
# generated as well, into $(TGT_GEN_CALLS), which guard_main.c includes.
TGT_GEN_HDR := $(sort $(shell find firmware -path '*/gen/*.h' -not -path 'firmware/port/*' 2>/dev/null))
TGT_GEN_CALLS := $(BUILD)/target/guard_generated.h
TGT_ELFS := $(foreach c,$(TGT_CORES),$(BUILD)/target/$(c)/canfdi.elf)
# Objects of the firmware proper, per core (the bench reads their sizes).
tgt_fw_obj = $(TGT_FW_SRC:%.c=$(BUILD)/target/$(1)/obj/%.o)

# The images must be relinked when a source file disappears, which no
# timestamp shows: this file changes exactly when the source list does.
TGT_SRCLIST := $(BUILD)/target/sources.txt
$(shell mkdir -p $(BUILD)/target && echo '$(TGT_FW_SRC)' | cmp -s - $(TGT_SRCLIST) || echo '$(TGT_FW_SRC)' > $(TGT_SRCLIST))

$(TGT_GEN_CALLS): tests/target/gen_guard_calls.pl $(TGT_GEN_HDR)
	@mkdir -p $(@D)
	perl tests/target/gen_guard_calls.pl $@ $(TGT_GEN_HDR)

define TGT_RULES
$(BUILD)/target/$(1)/obj/$(TGT_MAIN:.c=.o): $(TGT_GEN_CALLS)

$(BUILD)/target/$(1)/obj/%.o: %.c
	@mkdir -p $$(@D)
	$(ARM_CC) $(TGT_ARCH_$(1)) $(TGT_CFLAGS) -MMD -MP -c $$< -o $$@

$(BUILD)/target/$(1)/canfdi.elf: $(call tgt_fw_obj,$(1)) $(BUILD)/target/$(1)/obj/$(TGT_MAIN:.c=.o) $(TGT_LDSCRIPTS) $(TGT_SRCLIST)
	$(ARM_CC) $(TGT_ARCH_$(1)) $(TGT_LDFLAGS) -Wl,-Map,$$(@:.elf=.map) -o $$@ $$(filter %.o,$$^)
	@printf '%s\n' $(call tgt_fw_obj,$(1)) > $$@.objs
endef
$(foreach c,$(TGT_CORES),$(eval $(call TGT_RULES,$(c))))

.PHONY: firmware-run firmware-guard firmware-guard-negative
firmware-run: firmware-guard

firmware-guard: $(TGT_ELFS)
	@echo "== target images (bytes; text includes .rodata and the vector table)"
	@$(ARM_SIZE) $(TGT_ELFS)
	@bash tests/target/fw_guard.sh --nm $(ARM_NM) --main $(TGT_MAIN) \
	  --sources "$(TGT_FW_SRC)" --headers "$(TGT_FW_HDR)" \
	  --kw-only "$(sort $(wildcard firmware/port/linux/*.[ch])) $(TGT_PORT_APP_SRC)" \
	  $(foreach c,$(TGT_CORES),$(c)=$(BUILD)/target/$(c)/canfdi.elf)

# Proves the guard catches what it claims to (builds copies of the tree).
firmware-guard-negative:
	@bash tests/target/test_guard_negative.sh

TEST_STEPS += firmware-guard firmware-guard-negative
