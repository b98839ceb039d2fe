# bench/bench.mk — benchmarks (make bench). They print and record figures and
# never fail on a figure, only when they cannot run. The harnesses link the
# host release objects of the firmware, $(FW_REL_OBJ) (mk/demo.mk).

$(BUILD)/bench/bench_foundation: $(BUILD)/rel/bench/bench_foundation.o $(FW_REL_OBJ)
	@mkdir -p $(@D)
	$(CC) -o $@ $^

.PHONY: bench-foundation
# The Cortex-M objects give the per-module code size; build what compiles
# (a module that does not cross-compile is `make firmware`'s to report).
bench-foundation: $(BUILD)/bench/bench_foundation
	@$(MAKE) --no-print-directory -k $(foreach c,$(TGT_CORES),$(call tgt_fw_obj,$(c))) >/dev/null 2>&1 || \
	  echo "bench: some Cortex-M objects did not build; code sizes incomplete"
	$(PY) bench/foundation_report.py --exe $< --out $(BUILD)/bench/foundation.json \
	  --target-dir $(BUILD)/target

BENCH_STEPS += bench-foundation
