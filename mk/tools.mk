# mk/tools.mk — the Python tools package (tools/canfdi): inject, watch and
# scenario commands for the HIL bench, their timeline and expectation logic.
#
#   make tools-test   pytest tests/tools (no vcan needed: logs come from
#                     canfdi-sil, live buses are python-can's virtual
#                     interface); part of `make test`
#
# The console commands canfdi-inject / canfdi-watch / canfdi-scenario /
# canfdi-plot are installed into .venv/bin by `make deps` (tools/deps.sh
# reinstalls the editable package whenever tools/pyproject.toml changes).

.PHONY: tools-test
tools-test: $(BUILD)/bin/canfdi-sil
	$(PY) -m pytest tests/tools -q

TEST_STEPS += tools-test
