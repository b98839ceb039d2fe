# mk/pil.mk — processor in the loop: the application cross-compiled (-Os,
# as `make firmware`) for three Cortex-M machines QEMU emulates, fed the bus
# logs of SIL scenarios (recorded by the host build with canfdi-sil -l).
#
#   make pil-test    every ECU frame of every step compared bit for bit with
#                    the host SIL run (fails on one bit), instructions per
#                    canfdi_app_step (min/mean/max and which step) per
#                    scenario and machine into $(BUILD)/bench/pil.json;
#                    prints "N passed, N failed" (part of `make test`)
#   make bench-pil   the same over PIL_BENCH_SCN (the demo too), plus the RLS
#                    bench: canfdi_rls_update, n = 4, against the textbook
#                    covariance RLS in float and double and with the M4F FPU
#                    (bench/bench_rls_pil.c; part of `make bench`)
#   make footprint   flash/RAM per module of the application image, worst-case
#                    stack from -fstack-usage and the call graph, checked
#                    against the linker script's stack
#                    ($(BUILD)/bench/footprint.json; part of `make test`)
#
# Machines (tests/pil/README.md): name, core, QEMU machine, linker script,
# SysTick counts per instruction (numerator denominator) with -icount
# shift=6 (one instruction every 64 ns).
PIL_MACHINES := m3 m4 m0
PIL_m3 := cortex-m3 mps2-an385 $(TGT_LDSCRIPT) 8 5
PIL_m4 := cortex-m4 mps2-an386 $(TGT_LDSCRIPT) 8 5
PIL_m0 := cortex-m0 microbit $(TGT_LDSCRIPT_NRF51) 128 125
pil_core = $(word 1,$(PIL_$(1)))
pil_qemu = $(word 2,$(PIL_$(1)))
pil_ld = $(word 3,$(PIL_$(1)))
pil_num = $(word 4,$(PIL_$(1)))
pil_den = $(word 5,$(PIL_$(1)))

# The scenarios of `make pil-test`: short ones that cover a DC-motor model
# fault (estimators and parity equations to a DTC), a throttle sensor fault
# (vote, limp-home), a communication fault (CRC) and a parameter change
# found by the estimator, and a workshop session of UDS requests (the step's
# cost with a diagnostic request or response in flight is reported on its
# own line); bench-pil adds the demo (the step-cost reference
# of firmware/app/canfdi_app.h).
PIL_SCN := tests/sil/scenarios/dcm_ia_offset.scn tests/sil/scenarios/tps1_short.scn \
           tests/sil/scenarios/thr_crc.scn tests/sil/scenarios/dcm_friction_up.scn \
           tests/sil/scenarios/uds_workshop.scn
PIL_BENCH_SCN := $(PIL_SCN) tests/sil/scenarios/demo.scn

# mk/sil.mk and mk/target.mk are read after this file: the SIL runner and
# the port's loop are named here directly.
PIL_SIL_BIN := $(BUILD)/bin/canfdi-sil
PIL_PORT_APP_SRC := firmware/port/cortexm/canfdi_cortexm_main.c firmware/port/cortexm/canfdi_board_none.c
PIL_DIR := $(BUILD)/pil
PIL_ELFS := $(foreach m,$(PIL_MACHINES),$(PIL_DIR)/pil_step_$(m).elf)

# Every firmware header is a prerequisite: a struct or an inline function
# changed in a header must rebuild the images that PIL measures.
PIL_FW_HDR := $(FW_HDR) $(sort $(wildcard firmware/port/cortexm/*.h))

define PIL_RULES
$(PIL_DIR)/pil_step_$(1).elf: tests/pil/pil_step.c $(FW_SRC) firmware/port/cortexm/canfdi_startup.c $(TGT_LDSCRIPTS) \
    $(PIL_FW_HDR)
	@mkdir -p $$(@D)
	$(ARM_CC) $(TGT_ARCH_$(call pil_core,$(1))) $(TGT_CFLAGS) -DBENCH_TICKS_NUM=$(call pil_num,$(1))U \
	  -DBENCH_TICKS_DEN=$(call pil_den,$(1))U --specs=rdimon.specs $(call tgt_link,$(call pil_ld,$(1))) \
	  -o $$@ $$(filter %.c,$$^)
endef
$(foreach m,$(PIL_MACHINES),$(eval $(call PIL_RULES,$(m))))

PIL_MACHINE_ARGS = $(foreach m,$(PIL_MACHINES),$(m):$(call pil_qemu,$(m)):$(call pil_core,$(m)):$(PIL_DIR)/pil_step_$(m).elf)

.PHONY: pil-test bench-pil
pil-test: $(PIL_SIL_BIN) $(PIL_ELFS)
	@bash tests/pil/run_pil.sh --sil $(PIL_SIL_BIN) --json $(BUILD)/bench/pil.json --work $(PIL_DIR)/run \
	  --machines "$(PIL_MACHINE_ARGS)" $(PIL_SCN)

TEST_STEPS += pil-test

# The RLS bench: one image per (implementation, machine).
RLS_PIL_DIR := $(BUILD)/bench/rls
RLS_PIL_VARIANTS := fixed:m3 fixed:m4 fixed:m0 float:m3 double:m3 float:m4f
PIL_m4f := cortex-m4f mps2-an386 $(TGT_LDSCRIPT) 8 5
rls_impl = $(if $(filter fixed,$(1)),FIX,$(if $(filter float,$(1)),FLOAT,DOUBLE))
define RLS_PIL_RULES
$(RLS_PIL_DIR)/rls_$(1)_$(2).elf: bench/bench_rls_pil.c firmware/model/canfdi_rls.c firmware/core/canfdi_fixp.c \
    firmware/port/cortexm/canfdi_startup.c $(TGT_LDSCRIPTS) $(wildcard firmware/model/canfdi_rls.h firmware/core/*.h)
	@mkdir -p $$(@D)
	$(ARM_CC) $(TGT_ARCH_$(call pil_core,$(2))) $(TGT_CFLAGS) -DBENCH_IMPL_$(call rls_impl,$(1)) \
	  -DBENCH_TICKS_NUM=$(call pil_num,$(2)) -DBENCH_TICKS_DEN=$(call pil_den,$(2)) --specs=rdimon.specs \
	  $(call tgt_link,$(call pil_ld,$(2))) -o $$@ $$(filter %.c,$$^)
endef
$(foreach v,$(RLS_PIL_VARIANTS),$(eval $(call RLS_PIL_RULES,$(word 1,$(subst :, ,$(v))),$(word 2,$(subst :, ,$(v))))))
RLS_PIL_ELFS := $(foreach v,$(RLS_PIL_VARIANTS),$(RLS_PIL_DIR)/rls_$(subst :,_,$(v)).elf)
RLS_PIL_ARGS = $(foreach v,$(RLS_PIL_VARIANTS),$(v):$(call pil_qemu,$(word 2,$(subst :, ,$(v)))):$(RLS_PIL_DIR)/rls_$(subst :,_,$(v)).elf)

bench-pil: $(PIL_SIL_BIN) $(PIL_ELFS) $(RLS_PIL_ELFS)
	@bash tests/pil/run_pil.sh --sil $(PIL_SIL_BIN) --json $(BUILD)/bench/pil.json --work $(PIL_DIR)/run \
	  --machines "$(PIL_MACHINE_ARGS)" --rls "$(RLS_PIL_ARGS)" $(PIL_BENCH_SCN)

BENCH_STEPS += bench-pil

# Where the instructions of canfdi_app_step go: the M4 and M0 PIL images run
# with QEMU's execution trace on a fault scenario of each plant, split per
# function and firmware module, per slot of the rate schedule and for the
# costliest steps (tests/pil/pil_profile.py; $(BUILD)/bench/pil_profile.json).
# A few minutes: a bench, not a test.
PIL_PROFILE_SCN := tests/sil/scenarios/dcm_ia_offset.scn tests/sil/scenarios/thr_crc.scn
.PHONY: bench-pil-profile
bench-pil-profile: $(PIL_SIL_BIN) $(PIL_ELFS)
	@rm -f $(BUILD)/bench/pil_profile.json; mkdir -p $(BUILD)/bench
	@set -e; for scn in $(PIL_PROFILE_SCN); do \
	  n=$$(basename $$scn .scn); d=$(PIL_DIR)/profile/$$n; mkdir -p $$d; \
	  $(PIL_SIL_BIN) -q -s $$scn -l $$d/pil.log >/dev/null || test -s $$d/pil.log; \
	  for m in m4:$(call pil_qemu,m4) m0:$(call pil_qemu,m0); do \
	    python3 tests/pil/pil_profile.py --elf $(PIL_DIR)/pil_step_$${m%%:*}.elf --machine $${m#*:} \
	      --run-dir $$d --name $$n --json $(BUILD)/bench/pil_profile.json; \
	  done; done

BENCH_STEPS += bench-pil-profile

# The step's cost on hostile input: fuzz_app_rx's inputs (its corpus, its
# regressions and, at most PIL_COST_FOUND of them, what `make fuzz` or
# fuzz-test found: build/fuzz/found/app_rx) written out as one log by the
# harness itself (tests/fuzz/fuzz_export.h) and run on the M4 and the M0
# (tests/pil/pil_step.c built with PIL_COST): every step's instructions
# against the stated worst case of firmware/app/canfdi_app.h,
# PIL_COST_BOUND_<machine>. Fails when a step costs more; figures in
# $(BUILD)/bench/pil_cost.json.
PIL_COST_MACHINES := m4 m0
PIL_COST_BOUND_m4 := 38000
PIL_COST_BOUND_m0 := 85000
PIL_COST_FOUND ?= 300
PIL_COST_ELFS := $(foreach m,$(PIL_COST_MACHINES),$(PIL_DIR)/pil_cost_$(m).elf)
PIL_EXPORT := $(PIL_DIR)/fuzz-export-app-rx
define PIL_COST_RULES
$(PIL_DIR)/pil_cost_$(1).elf: tests/pil/pil_step.c $(FW_SRC) firmware/port/cortexm/canfdi_startup.c $(TGT_LDSCRIPTS) \
    $(PIL_FW_HDR)
	@mkdir -p $$(@D)
	$(ARM_CC) $(TGT_ARCH_$(call pil_core,$(1))) $(TGT_CFLAGS) -DPIL_COST -DBENCH_TICKS_NUM=$(call pil_num,$(1))U \
	  -DBENCH_TICKS_DEN=$(call pil_den,$(1))U --specs=rdimon.specs $(call tgt_link,$(call pil_ld,$(1))) \
	  -o $$@ $$(filter %.c,$$^)
endef
$(foreach m,$(PIL_COST_MACHINES),$(eval $(call PIL_COST_RULES,$(m))))
# The harness as a plain program (no libFuzzer, no sanitizers; the
# firmware with CANFDI_ASSERT on, like the host tests).
$(PIL_EXPORT): $(FUZZ_DIR)/fuzz_export_main.c $(FUZZ_DIR)/fuzz_app_rx.c $(FUZZ_DIR)/fuzz_export.h $(FUZZ_RANGES_C) \
    $(FUZZ_CODEC_DIR)/canfdi_rp_msg.c $(FW_SRC) $(FW_HDR)
	@mkdir -p $(@D)
	$(CC) $(WARN_C) -O2 -DFUZZ_EXPORT_LOG $(FW_INC) $(HOST_ASSERT) -I$(FUZZ_DIR) -I$(FUZZ_CODEC_DIR) \
	  -o $@ $(filter %.c,$^) -lm

.PHONY: pil-cost
pil-cost: $(PIL_EXPORT) $(PIL_COST_ELFS)
	@python3 tests/pil/pil_cost.py --export $(PIL_EXPORT) --work $(PIL_DIR)/cost --json $(BUILD)/bench/pil_cost.json \
	  --found $(FUZZ_OUT)/found/app_rx --found-max $(PIL_COST_FOUND) \
	  $(foreach m,$(PIL_COST_MACHINES),--machine $(m):$(call pil_qemu,$(m)):$(call pil_core,$(m)):$(PIL_DIR)/pil_cost_$(m).elf:$(PIL_COST_BOUND_$(m))) \
	  $(FUZZ_DIR)/corpus/app_rx $(FUZZ_DIR)/regress/app_rx

TEST_STEPS += pil-cost

# Footprint: the application image per machine (the port's loop on the
# empty board), every object compiled with -fstack-usage and
# -fcallgraph-info=su; tests/pil/footprint.py reads the map and the graph.
FP_DIR := $(BUILD)/footprint
FP_SRC := $(FW_SRC) firmware/port/cortexm/canfdi_startup.c $(PIL_PORT_APP_SRC)
FP_RAM_m3 := 4194304
FP_RAM_m4 := 4194304
FP_RAM_m0 := 16384
fp_obj = $(FP_SRC:%.c=$(FP_DIR)/$(1)/obj/%.o)
define FP_RULES
$(FP_DIR)/$(1)/obj/%.o: %.c
	@mkdir -p $$(@D)
	@$(ARM_CC) $(TGT_ARCH_$(call pil_core,$(1))) $(TGT_CFLAGS) -MMD -MP -fstack-usage -fcallgraph-info=su -c $$< -o $$@
$(FP_DIR)/$(1)/canfdi_app.elf: $(call fp_obj,$(1)) $(TGT_LDSCRIPTS)
	$(ARM_CC) $(TGT_ARCH_$(call pil_core,$(1))) --specs=nano.specs --specs=nosys.specs \
	  $(call tgt_link,$(call pil_ld,$(1))) -Wl,-Map,$$(@:.elf=.map) -o $$@ $$(filter %.o,$$^)
endef
$(foreach m,$(PIL_MACHINES),$(eval $(call FP_RULES,$(m))))
# header dependencies of the footprint objects (a changed struct rebuilds them)
-include $(foreach m,$(PIL_MACHINES),$(call fp_obj,$(m):.o=.d))

.PHONY: footprint
footprint: $(foreach m,$(PIL_MACHINES),$(FP_DIR)/$(m)/canfdi_app.elf)
	@rm -f $(BUILD)/bench/footprint.json; mkdir -p $(BUILD)/bench
	@set -e; for m in $(PIL_MACHINES); do \
	  case $$m in m0) ram=$(FP_RAM_m0); ld=$(TGT_LDSCRIPT_NRF51);; *) ram=$(FP_RAM_m4); ld=$(TGT_LDSCRIPT);; esac; \
	  python3 tests/pil/footprint.py --machine $$m --elf $(FP_DIR)/$$m/canfdi_app.elf --map $(FP_DIR)/$$m/canfdi_app.map \
	    --ci-dir $(FP_DIR)/$$m/obj --ld $$ld --ram-size $$ram --json $(BUILD)/bench/footprint.json; done

TEST_STEPS += footprint

# The struct sizes the headers and docs state ("sizeof(canfdi_x_t) = N"),
# against the Cortex-M4 and M0 builds: a struct that grows fails here until
# its statement follows (tests/pil/sizes.py).
.PHONY: size-check
size-check:
	@python3 tests/pil/sizes.py --cc $(ARM_CC) --cflags "$(TGT_CFLAGS) -mfloat-abi=soft" \
	  --core $(call pil_core,m4) --core $(call pil_core,m0)

TEST_STEPS += size-check
