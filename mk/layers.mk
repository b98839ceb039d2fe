# mk/layers.mk — the include layers of firmware/: the ranks are written once,
# in firmware/layers.txt; tools/check_layers.py checks every quoted include
# of firmware/**/*.{c,h} against them (Python 3, standard library only).
#
#   make layer-check   the check on the tree: one line per violation
#                      (file:line, include, both folders and ranks, rule),
#                      exit 1; else one summary line (part of `make test`)
#   make layers-test   pytest tests/layers: the checker on synthetic trees
#                      (upward, same-rank, unknown folder, clean; part of
#                      `make test`)

.PHONY: layer-check layers-test
layer-check:
	@python3 tools/check_layers.py

layers-test: deps
	$(PY) -m pytest -p no:cacheprovider tests/layers -q

TEST_STEPS += layer-check layers-test
