# mk/detection.mk — the detection figures of docs/requirements.md (a bench:
# prints and records, never fails on a figure, only when it cannot run).
#
#   make bench-detection   $(BUILD)/bench/detection.json + tables on stdout:
#                          per catalogue scenario the first trouble code, its
#                          delay and isolation, the degradation reached; false
#                          alarms over DETECTION_HOURS fault-free simulated
#                          hours; the smallest R_A, I_A / TPS1 offset and
#                          friction change canfdi detects versus limit-check
#                          baselines; instructions per canfdi_app_step
#                          (reuses $(BUILD)/bench/sil.json, runs it if absent).
#
# Uses the release SIL runner of mk/sil.mk ($(SIL_REL_BIN); named directly
# here because sil.mk is read after this file). Options: bench/bench_detection.py -h.
# The release runner does ~150 simulated s per wall s per core here; the
# fault-free hours run twice (constant load, then load steps when the app
# passes nominal_load_steps.scn) in DETECTION_CHUNKS runs on DETECTION_JOBS
# cores: the whole bench took ~3.7 min wall with 2 x 10 h on 2 cores. On a
# slow machine e.g. `make bench-detection DETECTION_HOURS=1` (the JSON and
# stdout say how many hours were run). Generated scenarios are kept in
# $(BUILD)/bench/detection_scn/ to reproduce an alarm.
DETECTION_HOURS ?= 10
DETECTION_CHUNKS ?= 10
DETECTION_JOBS ?= 2

.PHONY: bench-detection
bench-detection: $(BUILD)/bench/canfdi-sil-rel
	$(PY) bench/bench_detection.py --sil $< --out $(BUILD)/bench/detection.json \
	  --sil-json $(BUILD)/bench/sil.json --hours $(DETECTION_HOURS) \
	  --chunks $(DETECTION_CHUNKS) --jobs $(DETECTION_JOBS)

BENCH_STEPS += bench-detection
