# mk/hil.mk — hardware in the loop over SocketCAN: canfdi-ecu (firmware/port/
# linux) and canfdi-sim --can (host_sim) as processes on vcan0, driven by the
# Python tools (tools/canfdi), through the vcan sandbox tools/vcan-run where
# the host kernel has no SocketCAN (User-Mode Linux, ~1.5 s to boot).
#
#   make hil         the HIL demo: sim, ECU, the demo's fault sequence, the
#                    live timeline (tests/hil/demo.sh)
#   make hil-test    tests/hil and the vcan tests of tests/sim, one pytest
#                    inside one sandbox (part of `make test`)
#   make bench-hil   $(BUILD)/bench/hil.json: lockstep steps/s in the sandbox,
#                    realtime deadline misses and latency over 60 s
#
# The binaries that run in the sandbox are UBSan or release builds: ASan
# cannot run in User-Mode Linux (its shadow range lies above the UML
# process's address space; see mk/ecu.mk).

VCAN_RUN := $(CURDIR)/tools/vcan-run
HIL_ECU := $(BUILD)/bin/canfdi-ecu
HIL_ECU_REL := $(BUILD)/bin/canfdi-ecu-rel
HIL_SIM := $(BUILD)/hil/canfdi-sim
HIL_BINS := $(HIL_ECU) $(HIL_ECU_REL) $(HIL_SIM) $(BUILD)/bin/canfdi-sil

.PHONY: bench-hil
bench-hil: deps $(HIL_ECU_REL) $(HIL_SIM)
	@$(VCAN_RUN) --timeout 600 bench/hil_bench.sh $(BUILD)/bench/hil $(HIL_ECU_REL) $(HIL_SIM)
	@$(PY) bench/hil_report.py $(BUILD)/bench/hil $(BUILD)/bench/hil.json

BENCH_STEPS += bench-hil

# The HIL tests: one pytest inside one sandbox (starting Python there costs
# seconds): tests/hil (scenarios shared with SIL, bit-identity with SIL,
# raw frames from can-utils, floods, live tools, NVM across restarts, bus
# faults: interface down/up, slcan error frames and bus-off, sensor node
# restart, forged ECU identifiers; tests/hil/README.md) and
# the vcan tests of tests/sim (canfdi-sim's lockstep protocol).
# CANFDI_HIL_REQUIRED=1: a missing vcan0 fails instead of skipping.
# The SIL twins of the scenarios tests/hil/test_scenarios.py compares frame
# by frame (SHARED there) are made here on the host: canfdi-sil is an ASan
# build, which cannot run in the sandbox.
HIL_SHARED := tps1_open dcm_ra_up bridge_a_dead tps_both_lost supply_profile
HIL_SIL_LOGS := $(HIL_SHARED:%=$(BUILD)/hil/test/%-sil.log)
$(BUILD)/hil/test/%-sil.log: tests/sil/scenarios/%.scn $(BUILD)/bin/canfdi-sil
	@mkdir -p $(@D)
	@$(BUILD)/bin/canfdi-sil -q -s $< -l $@ >/dev/null
# a scenario's profile file (`profile`) is part of it
$(BUILD)/hil/test/supply_profile-sil.log: tests/sil/scenarios/supply_profile.csv

# Two sandboxes, each one pytest: the lockstep scenarios (tests/hil/
# test_scenarios.py) and the rest (the bus, bus faults, UDS, the simulator's
# vcan tests). A User-Mode Linux sandbox runs on one CPU, so make -j (make
# test's TEST_JOBS) runs the two side by side, each on a core of its own.
# They write different files of build/hil/test/ and have their own pytest
# temporary directories.
HIL_PYTEST = @$(VCAN_RUN) --timeout 1800 env CANFDI_HIL_REQUIRED=1 \
	  CANFDI_SIM=$(CURDIR)/$(BUILD)/bin/canfdi-sim CANFDI_SIM_HIL=$(CURDIR)/$(HIL_SIM) PYTHONDONTWRITEBYTECODE=1 \
	  $(PY) -m pytest $(PYTEST_OWN_TMP)
.PHONY: hil-test hil-test-lockstep hil-test-bus hil
hil-test-lockstep: deps $(HIL_BINS) $(HIL_SIL_LOGS) | $(BUILD)/pytest
	$(HIL_PYTEST) tests/hil/test_scenarios.py
hil-test-bus: deps $(HIL_BINS) | $(BUILD)/pytest
	$(HIL_PYTEST) tests/hil --ignore=tests/hil/test_scenarios.py tests/sim/test_canfdi_sim_can.py
hil-test: hil-test-lockstep hil-test-bus

TEST_STEPS += hil-test

# The HIL demo: canfdi-ecu and canfdi-sim in lockstep on vcan0, the demo's
# fault sequence (tests/sil/scenarios/demo.scn), the timeline printed live by
# canfdi-scenario as the frames arrive, the bus recorded to
# $(BUILD)/demo/canfdi-hil-demo.log.
HIL_DEMO_LOG := $(BUILD)/demo/canfdi-hil-demo.log
hil: deps $(HIL_BINS)
	@mkdir -p $(BUILD)/demo
	@echo "hil: canfdi-ecu + canfdi-sim on vcan0 (lockstep), $(DEMO_SCN); sandbox: tools/vcan-run"
	@$(VCAN_RUN) --timeout 900 $(CURDIR)/$(VENV)/bin/canfdi-scenario --live --log $(HIL_DEMO_LOG) \
	  --json $(BUILD)/demo/canfdi-hil-demo.json $(DEMO_SCN)
	@echo "hil: bus log $(HIL_DEMO_LOG) (candump -L; cantools decode dbc/canfdi.dbc < it)"
