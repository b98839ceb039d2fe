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
#                        (tests/sil/pending/drive_wltc3_10min.scn): pending
#                        until the firmware stops raising false codes on it,
#                        so not in `make test`
#   make drive-long      one hour per drive, several seeds, a -7 degC cold
#                        start (tests/sil/drive/*.scn), release build; a bench
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
DRIVE_ARGS_wltc3_1h_s1 := --duration 3600 --seed 1
DRIVE_ARGS_wltc3_1h_s2 := --duration 3600 --seed 2
DRIVE_ARGS_wltc3_1h_s3 := --duration 3600 --seed 3
DRIVE_ARGS_wltc3_1h_s4 := --duration 3600 --seed 4
DRIVE_NAMES := wltc3_10min_s1 wltc3_10min_s1_dcm wltc3_1h_s1 wltc3_1h_s2 wltc3_1h_s3 wltc3_1h_s4
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
	@bash tests/sil/run_scenarios.sh $(BUILD)/bin/canfdi-sil tests/sil/pending/drive_wltc3_10min.scn

drive-long: $(BUILD)/bench/canfdi-sil-rel drive-profiles
	@bash tests/sil/run_scenarios.sh $(BUILD)/bench/canfdi-sil-rel $(sort $(wildcard tests/sil/drive/*.scn))

# scenarios that drive a profile need it made first
sil-test: $(DRIVE_DIR)/wltc3_10min_s1_dcm.csv
sil-pending: $(DRIVE_DIR)/wltc3_10min_s1.csv
