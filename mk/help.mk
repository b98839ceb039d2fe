# mk/help.mk — `make help`: every target a person runs, grouped, one line
# each; the README's "Make targets" table is the longer version.
#
#   make help-test   pytest tests/make: every `make X` README.md documents is
#                    listed by `make help` and is a target of the Makefile;
#                    `make format` formats exactly the files named (part of
#                    `make test`)
# A new target a person runs gets its line here.

define HELP_TEXT
canfdi make targets (README.md: "Make targets"; options as VAR=value)

Setup and build
  make deps                 install missing Debian packages and the Python venv (idempotent)
  make all                  build the host libraries, unit tests, tools, canfdi-ecu/-sim/-sil
  make firmware             cross-compile for Cortex-M4 and Cortex-M0+, check no heap/float/dead code
  make clean                remove $(BUILD)/

Demonstrations
  make demo                 the demo: HIL on vcan0 where it can run, else SIL; timeline + PNG
  make demo-sil             the demo in one process (SIL), without vcan
  make demo-signal          the signal-based detectors alone on a synthetic signal
  make hil                  the HIL demo: canfdi-ecu + canfdi-sim in lockstep on vcan0
  make demo-fleet           a small synthetic fleet through canfdi-fleet: Parquet and the HTML fleet report

Tests (`make test` runs those marked *)
  make test                 everything CI checks, each step timed (TEST_JOBS=N: N at a time within a step; default one per core)
  make unit               * firmware unit tests, libcheck, ASan/UBSan, C99, x86-64 (CK_FORK=yes isolates)
  make unit-c11           * the same unit tests built as C11
  make unit-m32           * the same unit tests built for 32-bit x86 (ILP32, like the targets)
  make layer-check        * every firmware #include against the ranks of firmware/layers.txt
  make layers-test        * the layer checker on synthetic trees
  make help-test          * this list against README.md and the Makefile; make format
  make ref-test           * fixed-point modules against their double-precision Eigen references
  make firmware-guard     * the checks of `make firmware` on the Cortex-M images
  make pil-test           * PIL on QEMU (Cortex-M3, M4, M0): ECU frames bit for bit vs SIL, instructions per step
  make footprint          * flash/RAM per module and worst-case stack of the application image
  make size-check         * every struct size a header or doc states ("sizeof(canfdi_x_t) = N") against the Cortex-M4/M0 builds
  make pil-cost           * the fuzz inputs on QEMU (M4, M0): no step over the stated worst case in instructions
  make firmware-guard-negative * the guard rejects injected defects (double, float, malloc, dead code)
  make dbc-check          * the committed generated codecs and tables match dbc/
  make dbc-test           * pytest tests/dbc: the CAN database, codecs, E2E, catalogue
  make diag-rules-test    * the diagnosis rules against the measured fault-symptom table
  make sim-unit           * the plant simulator's libcheck tests (tests/sim/test_*.c)
  make sim-test           * sim-unit, then pytest tests/sim (canfdi-sim command line, lockstep)
  make sil-test           * the SIL scenarios (tests/sil/scenarios)
  make sil-matrix         * every catalogue fault in every mode (tests/sil/matrix)
  make sil-pending          the scenarios that do not pass yet (tests/sil/pending)
  make sil-matrix-pending   the matrix scenarios that do not pass yet
  make sil-envelope       * faults away from the nominal point (tests/sil/envelope), oppoint checks
  make sil-envelope-pending the envelope scenarios that do not pass yet
  make sil-long             hours of simulated time, -O2 build (tests/sil/long)
  make drive-unit         * pytest tests/drive: the drive-profile generator, the plants following it
  make drive-test           the 11.5-minute WLTC drive in SIL, both plants (also in sil-test)
  make drive-long           ten 1-hour WLTC drives (seeds 1..10, two -7 degC cold starts), -O2 build
  make tools-test         * pytest tests/tools: canfdi-inject, -watch, -scenario, -plot
  make vcan-test          * the vcan sandbox's self-test (tools/vcan-run)
  make hil-test           * the HIL tests inside the sandbox (tests/hil, vcan tests of tests/sim)
  make replay-test        * canfdi-replay on SIL and HIL recordings, every log format, bad input (tests/replay)
  make fleet-test         * canfdi-fleet on a small synthetic fleet: Dask, rerun, failed files, carried memory, Parquet
  make fleet-acceptance     a 20 x 10 synthetic fleet against its truth (FLEET_SEED=1): detection drive, false codes, RUL, memory
  make fuzz-test          * replay the fuzz corpora and regressions, then fuzz each harness 12 s (tests/fuzz)
  make static-check       * cppcheck + MISRA C:2012 addon and clang-tidy clang-analyzer-* over firmware/ (docs/misra.md)

Benchmarks (figures on stdout and in $(BUILD)/bench/*.json; never fail on a figure)
  make bench                all of the following
  make bench-foundation     detector cost (host instructions) and Cortex-M code size per module
  make bench-sim            simulated seconds per wall second, both plants
  make bench-symptoms       the measured fault-symptom table
  make bench-longrun        10 fault-free simulated hours: residuals against their bands
  make bench-detection      detection delay, isolation, false alarms, smallest detected change
  make bench-envelope       every fault x mode at every envelope point: verdicts, confusion matrix
  make bench-driveability   what the test signals cost the driver: speed/angle deviation, on-time share
  make sil-bench            host instructions per canfdi_app_step
  make bench-hil            lockstep steps/s and real-time deadline misses in the vcan sandbox
  make bench-pil            PIL figures incl. the demo, and the RLS update vs textbook float/double/FPU
  make bench-pil-profile    where the step's instructions go on QEMU M4/M0: per module, per slot, costliest steps
  make bench-replay         canfdi-replay on a one-hour log against python-can reading/decoding it
  make bench-replay-settle  the settling time of a mid-drive log: SIL recordings cut and replayed
  make bench-replay-jitter  SIL fault recordings re-stamped with jitter and clock drift, replayed
  make bench-replay-long    the SIL scenarios longer than make test replays, from power-up, frame for frame
  make bench-fleet          canfdi-fleet on the 20 x 10 fleet with 1 and 2 local workers: operating hours per wall second

Drive profiles (docs/driving.md)
  make drive-profiles       the WLTC class 3 drive profiles, $(BUILD)/drive/*.csv (+ .json summaries)
  make drive-plot           $(BUILD)/drive/wltc3_10min_s1.png: the 10-minute profile over time

Hostile input (tests/fuzz/README.md)
  make fuzz                 every libFuzzer harness for FUZZ_SECONDS (60) each; FUZZ_HARNESSES="uds nvm" for some
  make fuzz-build           build the harnesses (build/fuzz/fuzz_*)

Code
  make dbc-gen              regenerate the C codecs and tables after editing dbc/
  make format FILES="..."   clang-format (.clang-format) the named C files only
  make print-VAR            print a make variable, e.g. make -s print-HOST_CFLAGS
  make help                 this list
endef

.PHONY: help help-test
help:
	$(info $(HELP_TEXT))@:

help-test: deps
	$(PY) -m pytest -p no:cacheprovider tests/make -q

TEST_STEPS += help-test
