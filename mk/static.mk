# mk/static.mk — static analysis of the firmware (docs/misra.md):
#
#   make static-check   (make test) cppcheck with its MISRA C:2012 addon
#                       (tools/static/cppcheck.sh) and clang-tidy's
#                       clang-analyzer-* checks (tools/static/clang_tidy.sh)
#                       over firmware/ but the Linux port; fails on a finding
#                       that is not a deviation of docs/misra.md
#                       (tools/static/misra.supp, tools/static/tidy.baseline).
#                       Logs in $(BUILD)/static/. About 1 min.

# The two tools as targets of their own: make -j (make test's TEST_JOBS)
# runs them side by side.
.PHONY: static-check static-cppcheck static-tidy
static-cppcheck: deps
	@bash tools/static/cppcheck.sh $(BUILD)/static
static-tidy: deps
	@bash tools/static/clang_tidy.sh $(BUILD)/static
static-check: static-cppcheck static-tidy

TEST_STEPS += static-check
