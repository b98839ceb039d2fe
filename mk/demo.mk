# mk/demo.mk — `make demo` (-> demo-run): the SIL demo (tests/sil,
# tests/sil/scenarios/demo.scn): the firmware application against the
# host_sim plants, a fault-free phase and then a sequence of injected
# faults, the technician's timeline on stdout and a PNG plot
# ($(BUILD)/demo/canfdi-demo.png, tools/canfdi/plot.py).
# `make demo-signal`: the foundation detectors on a synthetic signal with
# injected changes (tools/signal_demo/signal_demo.c).
# Built with the project warnings, without sanitizers, against the host
# release objects of the firmware defined here (also used by bench/bench.mk).

# Host release build of the firmware: -O2, no sanitizers, CANFDI_ASSERT off,
# as on a target. Shared with the benchmarks (bench/bench.mk).
REL_CFLAGS := $(WARN_C) -O2 -g -Ifirmware -I$(BUILD)/gen
FW_REL_OBJ := $(FW_SRC:%.c=$(BUILD)/rel/%.o)

$(BUILD)/rel/%.o: %.c
	@mkdir -p $(@D)
	$(CC) $(REL_CFLAGS) -MMD -MP -c $< -o $@


$(BUILD)/demo/signal_demo: $(BUILD)/rel/tools/signal_demo/signal_demo.o $(FW_REL_OBJ)
	@mkdir -p $(@D)
	$(CC) -o $@ $^ -lm

.PHONY: demo-run demo-signal
demo-signal: $(BUILD)/demo/signal_demo
	@$(BUILD)/demo/signal_demo

DEMO_DIR := $(BUILD)/demo
DEMO_SCN := tests/sil/scenarios/demo.scn
# The demo's verdict lines are informative: a failed expectation is shown,
# the plot is still written (`make sil-test` is the gate).
demo-run: $(BUILD)/bin/canfdi-sil
	@mkdir -p $(DEMO_DIR)
	@$(BUILD)/bin/canfdi-sil -s $(DEMO_SCN) -o $(DEMO_DIR)/canfdi-demo.csv -D 5 -l $(DEMO_DIR)/canfdi-demo.log \
	  | tee $(DEMO_DIR)/canfdi-demo.txt; true
	@PYTHONPATH=tools $(PY) -m canfdi.plot $(DEMO_DIR)/canfdi-demo.csv -s $(DEMO_SCN) \
	  --timeline $(DEMO_DIR)/canfdi-demo.txt -o $(DEMO_DIR)/canfdi-demo.png \
	  --title "canfdi SIL demo ($(DEMO_SCN))" >/dev/null
	@echo "demo: timeline $(DEMO_DIR)/canfdi-demo.txt, trace $(DEMO_DIR)/canfdi-demo.csv,"
	@echo "      bus log $(DEMO_DIR)/canfdi-demo.log (candump -L)"
	@echo "demo: plot written to $(DEMO_DIR)/canfdi-demo.png"
