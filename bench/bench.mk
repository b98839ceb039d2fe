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

# ---------------------------------------------------------------------------
# Model layer: the measured fault-symptom table and the long
# fault-free run. Closed-loop host_sim plants + the four fixed-point model
# modules, all -O2 without sanitizers (project warnings, -Werror).
#   make bench-symptoms   $(BUILD)/bench/symptoms.json + table on stdout
#   make bench-longrun    $(BUILD)/bench/longrun.json, 10 simulated hours
# `make bench` runs both.
# Options of the programs: bench_symptoms -h, bench_longrun -h.

# Firmware objects the model modules need (core, detect, model) and the
# host_sim plant library, as release objects in one archive: the linker
# takes only what the benches reference.
MODEL_BENCH_FW_OBJ := $(filter $(BUILD)/rel/firmware/core/% $(BUILD)/rel/firmware/detect/% \
                        $(BUILD)/rel/firmware/model/%,$(FW_REL_OBJ))
MODEL_BENCH_SIM_OBJ := $(SIM_LIB_SRC:%.c=$(BUILD)/rel/%.o)
MODEL_BENCH_LIB := $(BUILD)/rel/bench/libmodel_bench.a
MODEL_BENCH_COMMON_OBJ := $(BUILD)/rel/bench/bench_model_common.o
MODEL_BENCH_MAIN_OBJ := $(BUILD)/rel/bench/bench_symptoms.o $(BUILD)/rel/bench/bench_longrun.o

$(MODEL_BENCH_COMMON_OBJ) $(MODEL_BENCH_MAIN_OBJ): REL_CFLAGS += -Ihost_sim

$(MODEL_BENCH_LIB): $(MODEL_BENCH_FW_OBJ) $(MODEL_BENCH_SIM_OBJ)
	@mkdir -p $(@D)
	rm -f $@
	ar rcs $@ $^

$(BUILD)/bench/bench_symptoms $(BUILD)/bench/bench_longrun: $(BUILD)/bench/%: $(BUILD)/rel/bench/%.o \
    $(MODEL_BENCH_COMMON_OBJ) $(MODEL_BENCH_LIB)
	@mkdir -p $(@D)
	$(CC) -o $@ $^ -lm

# Simulated hours of `make bench-longrun` (and so of `make bench`): the
# full 10 h take ~2-3 min of wall time here (~220-310 simulated s per wall
# s with both plants and all four modules), well under the ~10 min budget,
# so `make bench` runs the acceptance duration. On a slow machine use e.g.
# `make bench MODEL_LONGRUN_H=1`; the run then says (stdout and JSON) that
# it is shorter than the acceptance run.
MODEL_LONGRUN_H ?= 10

.PHONY: bench-symptoms bench-longrun
bench-symptoms: $(BUILD)/bench/bench_symptoms
	$< -o $(BUILD)/bench/symptoms.json

bench-longrun: $(BUILD)/bench/bench_longrun
	$< -H $(MODEL_LONGRUN_H) -o $(BUILD)/bench/longrun.json

BENCH_STEPS += bench-symptoms bench-longrun

# ---------------------------------------------------------------------------
# canfdi-replay's throughput (bench/bench_replay.py): on one one-hour candump
# recording, the full diagnosis against python-can's LogReader reading it and
# LogReader + cantools decoding it, side by side in one run, each on one
# core. The recording (~760 MB, bench/replay_1h.scn) is written once by the
# release SIL runner.
REPLAY_BENCH_LOG := $(BUILD)/bench/replay-1h.log
$(REPLAY_BENCH_LOG): bench/replay_1h.scn $(SIL_REL_BIN)
	@mkdir -p $(@D)
	@$(SIL_REL_BIN) -q -s $< -l $@.tmp >/dev/null && mv $@.tmp $@

.PHONY: bench-replay
bench-replay: deps $(REPLAY_BENCH_LOG) $(REPLAY_BIN)
	@$(PY) bench/bench_replay.py --log $(REPLAY_BENCH_LOG) --out $(BUILD)/bench/replay.json

BENCH_STEPS += bench-replay

# The settling time canfdi-replay states for a log that starts mid-drive,
# measured (bench/bench_replay_settle.py): every SIL recording cut at five
# points, replayed with settling times of 2..6 s, the findings against the
# recorded ECU's failing codes ($(BUILD)/bench/replay_settle.json, ~5 min).
.PHONY: bench-replay-settle
bench-replay-settle: deps $(SIL_REL_BIN) $(REPLAY_BIN)
	@$(PY) bench/bench_replay_settle.py --sil $(SIL_REL_BIN) --out $(BUILD)/bench/replay_settle.json

BENCH_STEPS += bench-replay-settle

# canfdi-replay on logger time stamps (bench/bench_replay_jitter.py): every
# SIL fault recording re-stamped with a seeded jitter on every frame (10,
# 200, 300 us) and a drifting logger clock (+-100 ppm), replayed with
# --clock timestamps; codes against the recorded ECU's (same, missed, wrong
# extra) ($(BUILD)/bench/replay_jitter.json, ~1 min).
.PHONY: bench-replay-jitter
bench-replay-jitter: deps $(BUILD)/bin/canfdi-sil $(REPLAY_BIN)
	@$(PY) bench/bench_replay_jitter.py --out $(BUILD)/bench/replay_jitter.json

BENCH_STEPS += bench-replay-jitter

# canfdi-replay from power-up on the SIL scenarios too long for make test
# (bench/bench_replay_long.py): each recorded by the release SIL runner and
# replayed, frame for frame and code for code against the recorded ECU
# ($(BUILD)/bench/replay_long.json, ~6 min).
.PHONY: bench-replay-long
bench-replay-long: deps $(SIL_REL_BIN) $(REPLAY_BIN) $(DRIVE_DIR)/wltc3_10min_s1_dcm.csv $(DRIVE_DIR)/wltc3_10min_s1.csv
	@$(PY) bench/bench_replay_long.py --sil $(SIL_REL_BIN) --out $(BUILD)/bench/replay_long.json

BENCH_STEPS += bench-replay-long
