# mk/fuzz.mk — libFuzzer harnesses over everything that reads bytes from
# outside (tests/fuzz/README.md, README "Hostile input"):
#
#   make fuzz [FUZZ_SECONDS=60] [FUZZ_HARNESSES="app_rx uds"]
#                      every harness (or those named) for FUZZ_SECONDS each,
#                      one after the other; new inputs go to
#                      $(BUILD)/fuzz/found/<harness>/, crashes to
#                      $(BUILD)/fuzz/crash/ (a crash fails the target)
#   make fuzz FUZZ_RUNS=10000000
#                      each harness until it has run that many inputs (no
#                      time limit); libFuzzer's pulse lines show progress
#   FUZZ_TIMEOUT=10    seconds one input may take before it counts as a
#                      hang (wall clock: a run at low priority beside other
#                      work can be starved that long, so give it 30 or more)
#   Every fuzzing run appends a line to $(BUILD)/bench/fuzz.tsv: harness,
#   commit, executions, seconds, executions per second, new inputs, result
#   (ok, crash, or interrupted: stopped by a signal).
#   make fuzz-test     (make test) replay every seed corpus and regression
#                      input, then fuzz each harness FUZZ_TEST_SECONDS (12)
#   make fuzz-build    build the harnesses only
#
# The harnesses: clang's libFuzzer with ASan and UBSan including the
# integer, shift and implicit-conversion groups, no recovery (a finding
# aborts). They drive the real modules, compiled here with these flags into
# $(BUILD)/fuzz/obj (never the host objects, which gcc builds). The
# sanitizer ignore list tests/fuzz/ignorelist.txt exempts, function by
# function and each with its reason, the arithmetic that wraps or truncates
# by design (CRCs, counters that wrap by intent, codec packing).
# The Python readers (the signal map, the scenario file, the log readers of
# canfdi-replay) have an atheris harness, tests/fuzz/py/fuzz_py_readers.py,
# run by the same targets as the harness `py_readers`.

FUZZ_CC ?= clang
FUZZ_SECONDS ?= 60
FUZZ_RUNS ?=
FUZZ_TIMEOUT ?= 10
FUZZ_TEST_SECONDS ?= 12
FUZZ_DIR := tests/fuzz
FUZZ_OUT := $(BUILD)/fuzz
FUZZ_ALL := app_rx uds isotp nvm candump scenario codec
# Python readers (atheris, in the project venv): run like the others.
FUZZ_PY := py_readers
FUZZ_CMD_py_readers = $(PY) $(FUZZ_DIR)/py/fuzz_py_readers.py
FUZZ_HARNESSES ?= $(FUZZ_ALL) $(FUZZ_PY)
FUZZ_SANITIZE := -fsanitize=fuzzer,address,undefined,integer,implicit-conversion \
                 -fno-sanitize-recover=all -fsanitize-ignorelist=$(FUZZ_DIR)/ignorelist.txt
FUZZ_CFLAGS := $(C_STD) -O1 -g -fno-omit-frame-pointer $(FUZZ_SANITIZE) $(FW_INC) $(HOST_ASSERT) \
               -Ihost_sim -Itools/replay -I$(FUZZ_DIR)

FUZZ_FW_OBJ := $(FW_SRC:%.c=$(FUZZ_OUT)/obj/%.o)
# Comparison tracing (-fsanitize-coverage=trace-cmp, part of
# -fsanitize=fuzzer) guides the fuzzer through the comparisons of code that
# parses bytes; in the layers that compute (model, detection, control,
# diagnosis, DTC routing, fault tolerance, outputs) it calls a hook on every
# comparison of every loop of every 1 ms step, and the stateful harnesses
# spent most of their time there. Those files keep edge coverage and every
# sanitizer; what reads bytes from outside keeps comparison tracing: the
# receive path, E2E and ISO-TP (comm/), the UDS server (uds/), the NVM
# loader and the DTC memory's image (diag/canfdi_nvm.c, diag/canfdi_dtc.c),
# the application's frame and UDS entry points (app/canfdi_app.c,
# app/canfdi_app_uds.c), host_sim, tools/replay and the harnesses.
FUZZ_CMP_SRC := $(filter firmware/uds/%,$(FW_SRC)) firmware/comm/canfdi_rx.c firmware/comm/canfdi_e2e.c \
                firmware/comm/canfdi_isotp.c firmware/diag/canfdi_nvm.c
FUZZ_NOCMP_OBJ := $(patsubst %.c,$(FUZZ_OUT)/obj/%.o,$(filter-out $(FUZZ_CMP_SRC),$(FW_SRC)))
$(FUZZ_NOCMP_OBJ): FUZZ_CFLAGS += -fno-sanitize-coverage=trace-cmp
FUZZ_SIM_SRC := $(filter-out host_sim/canfdi_sim_main.c host_sim/canfdi_sim_can.c,$(sort $(wildcard host_sim/*.c))) \
                $(sort $(wildcard host_sim/gen/*.c))
FUZZ_SIM_OBJ := $(FUZZ_SIM_SRC:%.c=$(FUZZ_OUT)/obj/%.o)
FUZZ_REPLAY_OBJ := $(FUZZ_OUT)/obj/tools/replay/replay_candump.o

# The DBC ranges of every signal (fuzz_app_rx): generated from the tester
# codec of mk/replay.mk (cantools, every message), compiled here.
# (mk/replay.mk is read after this file: its paths spelled out here, its
# rule makes them.)
FUZZ_RANGES_C := $(FUZZ_OUT)/gen/fuzz_ranges.c
FUZZ_CODEC_DIR := $(BUILD)/gen/replay
$(FUZZ_RANGES_C): $(FUZZ_CODEC_DIR)/canfdi_rp_msg.h $(FUZZ_DIR)/gen_ranges.py firmware/comm/gen/canfdi_msg.h
	@mkdir -p $(@D)
	python3 $(FUZZ_DIR)/gen_ranges.py $< $@ firmware/comm/gen/canfdi_msg.h
$(FUZZ_OUT)/obj/gen/fuzz_ranges.o: $(FUZZ_RANGES_C)
	@mkdir -p $(@D)
	$(FUZZ_CC) $(FUZZ_CFLAGS) -I$(FUZZ_CODEC_DIR) -c $< -o $@
$(FUZZ_OUT)/obj/replay/canfdi_rp_msg.o: $(FUZZ_CODEC_DIR)/canfdi_rp_msg.c
	@mkdir -p $(@D)
	$(FUZZ_CC) $(FUZZ_CFLAGS) -c $< -o $@
$(FUZZ_OUT)/obj/$(FUZZ_DIR)/fuzz_app_rx.o $(FUZZ_OUT)/obj/$(FUZZ_DIR)/fuzz_codec.o: $(FUZZ_RANGES_C)

# What each harness links besides its own source.
FUZZ_LINK_app_rx := $(FUZZ_OUT)/obj/gen/fuzz_ranges.o $(FUZZ_OUT)/obj/replay/canfdi_rp_msg.o $(FUZZ_OUT)/libfw.a
FUZZ_LINK_uds := $(FUZZ_OUT)/libfw.a
FUZZ_LINK_nvm := $(FUZZ_OUT)/libfw.a
FUZZ_LINK_isotp := $(FUZZ_OUT)/libfw.a
FUZZ_LINK_candump := $(FUZZ_REPLAY_OBJ)
FUZZ_LINK_codec := $(FUZZ_LINK_app_rx)
FUZZ_LINK_scenario := $(FUZZ_OUT)/libsim.a $(FUZZ_OUT)/libfw.a

FUZZ_BIN := $(FUZZ_ALL:%=$(FUZZ_OUT)/fuzz_%)

$(FUZZ_OUT)/obj/%.o: %.c $(FUZZ_DIR)/ignorelist.txt
	@mkdir -p $(@D)
	$(FUZZ_CC) $(FUZZ_CFLAGS) $(SRC_CFLAGS_$<) -MMD -MP -c $< -o $@

$(FUZZ_OUT)/libfw.a: $(FUZZ_FW_OBJ)
	@rm -f $@
	ar rcs $@ $^

$(FUZZ_OUT)/libsim.a: $(FUZZ_SIM_OBJ)
	@rm -f $@
	ar rcs $@ $^

define FUZZ_RULE
$(FUZZ_OUT)/fuzz_$(1): $(FUZZ_OUT)/obj/$(FUZZ_DIR)/fuzz_$(1).o $(FUZZ_LINK_$(1))
	$(FUZZ_CC) $(FUZZ_SANITIZE) -o $$@ $$^ -lm
endef
$(foreach h,$(FUZZ_ALL),$(eval $(call FUZZ_RULE,$(h))))

.PHONY: fuzz fuzz-test fuzz-build
fuzz-build: $(FUZZ_BIN)

# $(call fuzz_run,HARNESS,SECONDS[,RUNS]): replay the seeds and
# regressions, then fuzz for SECONDS (or, given RUNS, until RUNS inputs ran)
# from them; new inputs in $(FUZZ_OUT)/found/HARNESS, a line in
# $(BUILD)/bench/fuzz.tsv.
fuzz_run = set -eo pipefail; h=$(1); \
	mkdir -p $(FUZZ_OUT)/found/$$h $(FUZZ_OUT)/crash $(BUILD)/bench; \
	dirs=""; for d in $(FUZZ_DIR)/corpus/$$h $(FUZZ_DIR)/regress/$$h; do [ -d $$d ] && dirs="$$dirs $$d"; done; \
	echo "== fuzz_$$h: replay$$dirs"; \
	$(or $(FUZZ_CMD_$(1)),$(FUZZ_OUT)/fuzz_$(1)) -runs=0 $$dirs 2>$(FUZZ_OUT)/$$h.replay.log || { cat $(FUZZ_OUT)/$$h.replay.log; exit 1; }; \
	$(if $(3),limit="-runs=$(3)"; echo "== fuzz_$$h: $(3) executions";,limit="-max_total_time=$(2)"; echo "== fuzz_$$h: $(2) s";) \
	t0=$$(date +%s); rc=0; \
	$(or $(FUZZ_CMD_$(1)),$(FUZZ_OUT)/fuzz_$(1)) $$limit -print_final_stats=1 -timeout=$(FUZZ_TIMEOUT) -rss_limit_mb=1024 \
	  -artifact_prefix=$(FUZZ_OUT)/crash/$$h- $(FUZZ_OUT)/found/$$h $$dirs 2>&1 | tee $(FUZZ_OUT)/$$h.log | \
	  { $(if $(3),grep -a --line-buffered -E '^#[0-9]+[[:space:]]+pulse' || true,cat >/dev/null); } || rc=$$?; \
	stat() { grep -a -E "^stat::$$1:" $(FUZZ_OUT)/$$h.log | awk '{print $$2}'; }; \
	printf '%s\t%s\t%s\t%s\t%s\t%s\t%s\n' $$h "$$(git rev-parse --short HEAD 2>/dev/null || echo -)" \
	  "$$(stat number_of_executed_units)" $$(( $$(date +%s) - t0 )) "$$(stat average_exec_per_sec)" \
	  "$$(stat new_units_added)" $$(if [ $$rc = 0 ]; then echo ok; elif grep -aq 'run interrupted' $(FUZZ_OUT)/$$h.log; \
	  then echo interrupted; else echo crash; fi) >>$(BUILD)/bench/fuzz.tsv; \
	[ $$rc = 0 ] || { tail -60 $(FUZZ_OUT)/$$h.log; grep -aq 'run interrupted' $(FUZZ_OUT)/$$h.log && echo "fuzz_$$h: interrupted" || \
	  echo "fuzz_$$h: crash, input in $(FUZZ_OUT)/crash/"; exit 1; }; \
	{ printf 'fuzz_%s: ' $$h; grep -a -E '^(stat::number_of_executed_units|stat::average_exec_per_sec|stat::new_units_added)' $(FUZZ_OUT)/$$h.log | tr '\n' ' '; echo; }

fuzz: $(patsubst %,$(FUZZ_OUT)/fuzz_%,$(filter-out $(FUZZ_PY),$(FUZZ_HARNESSES)))
	@$(foreach h,$(FUZZ_HARNESSES),$(call fuzz_run,$(h),$(FUZZ_SECONDS),$(FUZZ_RUNS));)

# One target per harness, so that make -j (make test's TEST_JOBS) runs as
# many at a time: each still fuzzes FUZZ_TEST_SECONDS on a core of its own.
FUZZ_TEST_RUNS := $(addprefix fuzz-test-,$(FUZZ_ALL) $(FUZZ_PY))
.PHONY: $(FUZZ_TEST_RUNS)
$(FUZZ_TEST_RUNS): fuzz-test-%: deps $(FUZZ_BIN)
	@$(call fuzz_run,$*,$(FUZZ_TEST_SECONDS))
fuzz-test: $(FUZZ_TEST_RUNS)

TEST_STEPS += fuzz-test
