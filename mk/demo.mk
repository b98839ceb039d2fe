# mk/demo.mk — `make demo` (-> demo-run): the HIL demo where vcan can run,
# else the SIL demo, both on tests/sil/scenarios/demo.scn (a fault-free
# phase, then a sequence of injected faults), the technician's timeline on
# stdout and a PNG plot of setpoints and responses, actuator commands,
# residuals against thresholds, parameter estimates and states
# ($(BUILD)/demo/canfdi-demo.png).
#   demo-run   `tools/vcan-run true` decides (~2 s: it boots the sandbox
#              once); where it cannot run, one line says why (its reason)
#              and the SIL demo runs instead.
#   demo-hil   `make hil` (canfdi-ecu + canfdi-sim in lockstep on vcan0,
#              bus log $(BUILD)/demo/canfdi-hil-demo.log), then canfdi-plot
#              (tools/canfdi/logplot.py) draws the PNG from that log (and
#              the scenario's fault lines: the sim gets the faults in the
#              scenario, not as SimFaultInject frames).
#   demo-sil   the firmware application against the host_sim plants in one
#              process (canfdi-sil); CSV trace, timeline, bus log, PNG from
#              the trace (tools/canfdi/plot.py).
# `make demo-signal`: the foundation detectors on a synthetic signal with
# injected changes (tools/signal_demo/signal_demo.c).
# Built with the project warnings, without sanitizers, against the host
# release objects of the firmware defined here (also used by bench/bench.mk).

# Host release build of the firmware (REL_CFLAGS: -O2, no sanitizers,
# CANFDI_ASSERT off, as on a target). Shared with the benchmarks
# (bench/bench.mk).
FW_REL_OBJ := $(FW_SRC:%.c=$(BUILD)/rel/%.o)

$(BUILD)/rel/%.o: %.c
	@mkdir -p $(@D)
	$(CC) $(REL_CFLAGS) $(SRC_CFLAGS_$<) -MMD -MP -c $< -o $@


$(BUILD)/demo/signal_demo: $(BUILD)/rel/tools/signal_demo/signal_demo.o $(FW_REL_OBJ)
	@mkdir -p $(@D)
	$(CC) -o $@ $^ -lm

.PHONY: demo-run demo-hil demo-sil demo-signal
demo-signal: $(BUILD)/demo/signal_demo
	@$(BUILD)/demo/signal_demo

DEMO_DIR := $(BUILD)/demo
DEMO_SCN := tests/sil/scenarios/demo.scn
DEMO_PNG := $(DEMO_DIR)/canfdi-demo.png
# The demo's verdict lines are informative: a failed expectation is shown,
# the plot is still written (`make sil-test` and `make hil-test` are the gates).
demo-run:
	@mkdir -p $(DEMO_DIR)
	@if why=$$($(VCAN_RUN) --timeout 60 true 2>&1 >/dev/null); then \
	  $(MAKE) --no-print-directory demo-hil; \
	else \
	  why=$$(printf '%s\n' "$$why" | grep -m1 . | sed 's/^vcan-run: *\(error: *\)\?//'); \
	  echo "demo: no vcan here (tools/vcan-run: $${why:-it failed}); running the SIL demo instead"; \
	  $(MAKE) --no-print-directory demo-sil; \
	fi

# A HIL run that ends without a bus log (the sandbox failed) falls back to
# the SIL demo too; one that wrote a log is plotted whatever its verdict.
demo-hil:
	@mkdir -p $(DEMO_DIR)
	@rm -f $(HIL_DEMO_LOG)
	@$(MAKE) --no-print-directory hil; rc=$$?; \
	if [ ! -s $(HIL_DEMO_LOG) ]; then \
	  echo "demo: the HIL run wrote no bus log (exit $$rc); running the SIL demo instead"; \
	  exec $(MAKE) --no-print-directory demo-sil; \
	fi; \
	[ $$rc -eq 0 ] || echo "demo: the HIL run ended with exit $$rc (make hil-test is the gate); plotting its log"; \
	$(VENV)/bin/canfdi-plot $(HIL_DEMO_LOG) -s $(DEMO_SCN) -o $(DEMO_PNG) --title "canfdi HIL demo on vcan0 ($(DEMO_SCN))"
	@echo "demo: plot written to $(DEMO_PNG)"

demo-sil: $(BUILD)/bin/canfdi-sil
	@mkdir -p $(DEMO_DIR)
	@$(BUILD)/bin/canfdi-sil -s $(DEMO_SCN) -o $(DEMO_DIR)/canfdi-demo.csv -D 5 -l $(DEMO_DIR)/canfdi-demo.log \
	  | tee $(DEMO_DIR)/canfdi-demo.txt; true
	@PYTHONPATH=tools $(PY) -m canfdi.plot $(DEMO_DIR)/canfdi-demo.csv -s $(DEMO_SCN) \
	  --timeline $(DEMO_DIR)/canfdi-demo.txt -o $(DEMO_PNG) \
	  --title "canfdi SIL demo ($(DEMO_SCN))" >/dev/null
	@echo "demo: timeline $(DEMO_DIR)/canfdi-demo.txt, trace $(DEMO_DIR)/canfdi-demo.csv,"
	@echo "      bus log $(DEMO_DIR)/canfdi-demo.log (candump -L)"
	@echo "demo: plot written to $(DEMO_PNG)"
