# mk/static.mk — static analysis of the firmware (docs/misra.md):
#
#   make static-check   (make test) cppcheck with its MISRA C:2012 addon
#                       (tools/static/cppcheck.sh) and clang-tidy's
#                       clang-analyzer-* checks (tools/static/clang_tidy.sh)
#                       over firmware/ but the Linux port; fails on a finding
#                       that is not a deviation of docs/misra.md
#                       (tools/static/misra.supp, tools/static/tidy.baseline).
#                       Logs in $(BUILD)/static/. About 1 min.

.PHONY: static-check
static-check: deps
	@bash tools/static/cppcheck.sh $(BUILD)/static
	@bash tools/static/clang_tidy.sh $(BUILD)/static

TEST_STEPS += static-check
