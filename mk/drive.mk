# mk/drive.mk — fault-free driving from a published drive cycle: profile
# CSVs made by tools/drive from the WLTC class 3 trace of the wltp package
# (docs/driving.md), driven through the SIL rig.
#
#   make drive-profiles  $(BUILD)/drive/*.csv and their *.json summaries
#   make drive-plot      $(BUILD)/drive/wltc3_10min_s1.png: the 10-minute
#                        profile over time (canfdi-profile-plot)
#   make drive-unit      pytest tests/drive: the generator, and the plants
#                        following its profile (part of `make test`)
#   make drive-test      the 11.5-minute drive, both plants, expect no_dtc
#                        (tests/sil/scenarios/drive_wltc3_10min.scn, also in
#                        make sil-test)
#                        until the firmware stops raising false codes on it,
#                        so not in `make test`
#   make drive-long      ten one-hour drives, seeds 1..10, two of them -7 degC
#                        cold starts (tests/sil/drive/*.scn), release build;
#                        a bench (about 4 min on two cores)
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

.PHONY: drive-profiles drive-plot drive-unit drive-test drive-long
drive-profiles: $(DRIVE_CSV)

$(DRIVE_DIR)/wltc3_10min_s1.png: $(DRIVE_DIR)/wltc3_10min_s1.csv tools/canfdi/profile_plot.py
	$(PY) -m canfdi.profile_plot $< -o $@

drive-plot: $(DRIVE_DIR)/wltc3_10min_s1.png

drive-unit: deps $(BUILD)/bin/canfdi-sim $(DRIVE_DIR)/wltc3_10min_s1.csv
	CANFDI_SIM=$(CURDIR)/$(BUILD)/bin/canfdi-sim $(PY) -m pytest tests/drive -q

TEST_STEPS += drive-unit

drive-test: $(BUILD)/bin/canfdi-sil drive-profiles
	@bash tests/sil/run_scenarios.sh $(BUILD)/bin/canfdi-sil tests/sil/scenarios/drive_wltc3_10min.scn

drive-long: $(BUILD)/bench/canfdi-sil-rel drive-profiles
	@bash tests/sil/run_scenarios.sh $(BUILD)/bench/canfdi-sil-rel $(sort $(wildcard tests/sil/drive/*.scn))

# scenarios that drive a profile need it made first
sil-test: $(DRIVE_DIR)/wltc3_10min_s1_dcm.csv $(DRIVE_DIR)/wltc3_10min_s1.csv
