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

Tests (`make test` runs those marked *)
  make test                 everything CI checks (about 12 min from a fresh clone on 2 cores)
  make unit               * firmware unit tests, libcheck, ASan/UBSan, C99, x86-64 (CK_FORK=yes isolates)
  make unit-c11           * the same unit tests built as C11
  make unit-m32           * the same unit tests built for 32-bit x86 (ILP32, like the targets)
  make layer-check        * every firmware #include against the ranks of firmware/layers.txt
  make layers-test        * the layer checker on synthetic trees
  make help-test          * this list against README.md and the Makefile; make format
  make ref-test           * fixed-point modules against their double-precision Eigen references
  make firmware-guard     * the checks of `make firmware` on the Cortex-M images
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
  make sil-long             hours of simulated time, -O2 build (tests/sil/long)
  make tools-test         * pytest tests/tools: canfdi-inject, -watch, -scenario, -plot
  make vcan-test          * the vcan sandbox's self-test (tools/vcan-run)
  make hil-test           * the HIL tests inside the sandbox (tests/hil, vcan tests of tests/sim)

Benchmarks (figures on stdout and in $(BUILD)/bench/*.json; never fail on a figure)
  make bench                all of the following except sil-pil
  make bench-foundation     detector cost (host instructions) and Cortex-M code size per module
  make bench-sim            simulated seconds per wall second, both plants
  make bench-symptoms       the measured fault-symptom table
  make bench-longrun        10 fault-free simulated hours: residuals against their bands
  make bench-detection      detection delay, isolation, false alarms, smallest detected change
  make sil-bench            host instructions per canfdi_app_step
  make bench-hil            lockstep steps/s and real-time deadline misses in the vcan sandbox
  make sil-pil              instructions per step on QEMU (Cortex-M4/M0+ code), frames vs SIL
  make sil-pil-uds          the same with a tester's UDS requests in flight (uds_workshop.scn)

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
