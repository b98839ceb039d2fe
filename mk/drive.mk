# mk/drive.mk — fault-free driving from a published drive cycle: profile
# CSVs made by tools/drive from the WLTC class 3 trace of the wltp package
# (docs/driving.md), driven through the SIL rig.
#
#   make drive-profiles  $(BUILD)/drive/*.csv and their *.json summaries
#   make drive-plot      $(BUILD)/drive/wltc3_10min_s1.png: the 10-minute
#                        profile over time (canfdi-profile-plot)
#   make drive-unit      pytest tests/drive: the generator, the plants
#                        following its profile, and the twins of
#                        bench-driveability bit-identical until a test signal
#                        acts (part of `make test`)
#   make drive-test      the 11.5-minute drive, both plants, expect no_dtc
#                        (tests/sil/scenarios/drive_wltc3_10min.scn, also in
#                        make sil-test)
#                        until the firmware stops raising false codes on it,
#                        so not in `make test`
#   make drive-long      ten one-hour drives, seeds 1..10, two of them -7 degC
#                        cold starts (tests/sil/drive/*.scn), release build;
#                        a bench (about 4 min on two cores)
#   make bench-driveability  what the test signals cost the driver: twin runs
#                        of fault-free drives (11.5 min and three one-hour
#                        WLTC drives, one a -7 degC cold start) with the test
#                        signals allowed and suppressed (canfdi-sil
#                        --test-signals on/off), RMS and largest speed and
#                        angle deviation, on-time share per plant, and the
#                        former permanent dither for comparison;
#                        $(BUILD)/bench/driveability.json and a table
#                        (bench/bench_driveability.py; DRIVEABILITY_JOBS
#                        cores, ~12 runs of up to 1 h simulated)
#
# The motor's side of the 11.5-minute drive alone (the throttle held) runs
# in `make sil-test` (tests/sil/scenarios/drive_dcm_10min.scn). The scenario
# files name their profiles as ../../../build/drive/NAME.csv, i.e. the
# default BUILD.

DRIVE_DIR := $(BUILD)/drive
DRIVE_SRC := tools/drive/generate.py tools/drive/wltc.py requirements.txt
# name -> generator options (canfdi-drive-profile --help)
DRIVE_SHORT := --duration 600 --seed 1 --trips 1,4,5,8 --manoeuvres 1
DRIVE_ARGS_wltc3_10min_s1 := $(DRIVE_SHORT)
DRIVE_ARGS_wltc3_10min_s1_dcm := $(DRIVE_SHORT) --columns speed_rad_s,load_Nm,dcm_supply_V
# one hour each, seeds 1..10 (ten simulated hours; 4 and 10 are the -7 degC cold starts)
DRIVE_SEEDS := 1 2 3 4 5 6 7 8 9 10
$(foreach s,$(DRIVE_SEEDS),$(eval DRIVE_ARGS_wltc3_1h_s$(s) := --duration 3600 --seed $(s)))
DRIVE_NAMES := wltc3_10min_s1 wltc3_10min_s1_dcm $(DRIVE_SEEDS:%=wltc3_1h_s%)
DRIVE_CSV := $(DRIVE_NAMES:%=$(DRIVE_DIR)/%.csv)

$(DRIVE_DIR)/%.csv: $(DRIVE_SRC) | deps
	@mkdir -p $(@D)
	$(PY) -m drive.generate $(DRIVE_ARGS_$*) -o $@

.PHONY: drive-profiles drive-plot drive-unit drive-test drive-long bench-driveability
drive-profiles: $(DRIVE_CSV)

$(DRIVE_DIR)/wltc3_10min_s1.png: $(DRIVE_DIR)/wltc3_10min_s1.csv tools/canfdi/profile_plot.py
	$(PY) -m canfdi.profile_plot $< -o $@

drive-plot: $(DRIVE_DIR)/wltc3_10min_s1.png

drive-unit: deps $(BUILD)/bin/canfdi-sim $(BUILD)/bin/canfdi-sil $(DRIVE_DIR)/wltc3_10min_s1.csv
	CANFDI_SIM=$(CURDIR)/$(BUILD)/bin/canfdi-sim CANFDI_SIL=$(CURDIR)/$(BUILD)/bin/canfdi-sil \
	  $(PY) -m pytest tests/drive -q

TEST_STEPS += drive-unit

drive-test: $(BUILD)/bin/canfdi-sil drive-profiles
	@bash tests/sil/run_scenarios.sh $(BUILD)/bin/canfdi-sil tests/sil/scenarios/drive_wltc3_10min.scn

drive-long: $(BUILD)/bench/canfdi-sil-rel drive-profiles
	@bash tests/sil/run_scenarios.sh $(BUILD)/bench/canfdi-sil-rel $(sort $(wildcard tests/sil/drive/*.scn))

DRIVEABILITY_JOBS ?= 2
DRIVEABILITY_CSV := $(DRIVE_DIR)/wltc3_10min_s1.csv $(DRIVE_DIR)/wltc3_1h_s1.csv $(DRIVE_DIR)/wltc3_1h_s2.csv \
  $(DRIVE_DIR)/wltc3_1h_s4.csv
bench-driveability: $(BUILD)/bench/canfdi-sil-rel $(DRIVEABILITY_CSV)
	$(PY) bench/bench_driveability.py --sil $< --out $(BUILD)/bench/driveability.json \
	  --work $(BUILD)/bench/driveability --jobs $(DRIVEABILITY_JOBS)

BENCH_STEPS += bench-driveability

# scenarios that drive a profile need it made first
sil-test: $(DRIVE_DIR)/wltc3_10min_s1_dcm.csv $(DRIVE_DIR)/wltc3_10min_s1.csv
