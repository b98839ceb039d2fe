# tests/ref/ref.mk — the double-precision (MIL) reference programs: C++17 with
# Eigen, each comparing a fixed-point firmware module with its double twin on
# the same (simulated) inputs. Every tests/ref/ref_*.cpp becomes
# $(BUILD)/ref/ref_*; `make ref-test` (part of `make test`) runs them all.
# Each prints its figures, ends with "N passed, N failed" and exits non-zero
# on a failure. Host only.

REF_SRC := $(sort $(wildcard tests/ref/ref_*.cpp))
REF_BIN := $(REF_SRC:tests/ref/%.cpp=$(BUILD)/ref/%)
REF_HDR := $(wildcard tests/ref/*.hpp)
# REF_CXXFLAGS (C++17, ASan/UBSan, Eigen): mk/flags.mk.

$(BUILD)/ref/%: tests/ref/%.cpp $(REF_HDR) $(FW_HOST_OBJ) $(UNIT_EXTRA_OBJ)
	@mkdir -p $(@D)
	$(CXX) $(REF_CXXFLAGS) -o $@ $< $(FW_HOST_OBJ) $(UNIT_EXTRA_OBJ) -lm

.PHONY: ref-test
ref-test: deps $(REF_BIN)
	@tools/run-each ref-test $(TEST_JOBS) -- $(REF_BIN)

TEST_STEPS += ref-test
ALL_STEPS += $(REF_BIN)

