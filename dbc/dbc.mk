# dbc/dbc.mk — the CAN database and everything generated from it.
#
#   make dbc-gen    regenerate codecs, fault/DTC tables and the DBC's fault-id
#                   and DTC value tables after editing dbc/canfdi.dbc,
#                   dbc/faults.csv or dbc/dtcs.csv (then commit the result)
#   make dbc-check  fail if any committed generated file differs from what
#                   the sources produce (part of `make test`)
#   make dbc-test   pytest checks of the database (part of `make test`)
#
# The generated C compiles warning-free under WARN_C (also -Wconversion,
# -Wsign-conversion, -pedantic), so no relaxed flags are needed for it.

.PHONY: dbc-gen dbc-check dbc-test

dbc-gen: deps
	@bash dbc/codegen.sh gen $(PY)

dbc-check: deps
	@bash dbc/codegen.sh check $(PY)

dbc-test: deps
	$(PY) -m pytest -p no:cacheprovider tests/dbc -q

TEST_STEPS += dbc-check dbc-test
