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
