# mk/fleet.mk — canfdi-fleet: the replay over a fleet's drives on Dask
# (tools/canfdi/fleet*.py, docs/fleet.md).
#
#   make fleet-test         pytest tests/fleet: a small synthetic fleet end to
#                           end, rerun, a failed file, carried memory = one
#                           long replay, Parquet read by pandas/pyarrow/DuckDB/
#                           Polars (part of make test)
#   make fleet-acceptance   the fleet acceptance (docs/fleet.md) on a 20 x 10 fleet of 60 s
#                           drives (FLEET_SEED=1): per vehicle found/missed/
#                           false, drive error, RUL vs truth, memory chain =
#                           long replay = vehicle ECU
#                           ($(BUILD)/bench/fleet_acceptance_s$(FLEET_SEED).json)
#   make bench-fleet        the same fleet with 1 and 2 local workers: wall
#                           time, operating hours per wall second
#                           ($(BUILD)/bench/fleet.json; make bench)
#   make demo-fleet         a small fleet, its run and the report
#                           ($(BUILD)/fleet/demo/out/fleet_report.html)

FLEET_SEED ?= 1
FLEET_BINS := $(BUILD)/bin/canfdi-replay-core $(BUILD)/bench/canfdi-sil-rel
FLEET_ACC_DIR := $(BUILD)/fleet/acceptance_s$(FLEET_SEED)
FLEET_GEN := $(PY) -m canfdi.fleet_gen
FLEET_RUN := $(PY) -m canfdi.fleet

.PHONY: fleet-test fleet-acceptance bench-fleet demo-fleet
fleet-test: deps $(FLEET_BINS) $(BUILD)/bin/canfdi-sil
	$(PY) -m pytest tests/fleet -q

# 20 vehicles x 10 drives of 60 s (3.3 operating hours), generated once per seed
$(FLEET_ACC_DIR)/fleet/truth.json: $(FLEET_BINS) tools/canfdi/fleet_gen.py
	@rm -rf $(FLEET_ACC_DIR)/fleet
	$(FLEET_GEN) -q -o $(FLEET_ACC_DIR)/fleet --vehicles 20 --drives 10 --duration 60 --seed $(FLEET_SEED)

fleet-acceptance: deps $(FLEET_ACC_DIR)/fleet/truth.json
	$(FLEET_RUN) -q $(FLEET_ACC_DIR)/fleet/manifest.csv -o $(FLEET_ACC_DIR)/out --workers 2
	$(PY) -m canfdi.fleet_acceptance $(FLEET_ACC_DIR)/fleet $(FLEET_ACC_DIR)/out \
	  --json $(BUILD)/bench/fleet_acceptance_s$(FLEET_SEED).json

bench-fleet: deps $(FLEET_ACC_DIR)/fleet/truth.json
	$(PY) -m canfdi.fleet_bench $(FLEET_ACC_DIR)/fleet $(BUILD)/bench/fleet.json

BENCH_STEPS += bench-fleet

demo-fleet: deps $(FLEET_BINS)
	@rm -rf $(BUILD)/fleet/demo
	$(FLEET_GEN) -q -o $(BUILD)/fleet/demo/fleet --vehicles 8 --drives 8 --duration 60 --seed 3
	-$(FLEET_RUN) $(BUILD)/fleet/demo/fleet/manifest.csv -o $(BUILD)/fleet/demo/out
	@echo "demo-fleet: report $(BUILD)/fleet/demo/out/fleet_report.html"

TEST_STEPS += fleet-test
