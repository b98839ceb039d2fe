# mk/demo.mk — `make demo` (-> demo-run): the foundation detectors on a
# synthetic signal with injected changes (tools/signal_demo/signal_demo.c).
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

.PHONY: demo-run
demo-run: $(BUILD)/demo/signal_demo
	@$(BUILD)/demo/signal_demo
