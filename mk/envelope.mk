# mk/envelope.mk — the envelope fault matrix (docs/envelope.md): every
# catalogue fault at a grid of operating points that spans the envelope,
# judged against the observability table dbc/observability.csv.
#
#   make sil-envelope          pytest tests/sil/test_envelope.py (calculator
#                              against fault-free SIL traces, the table, the
#                              committed scenarios equal to what the
#                              generator writes), then the sampled scenarios
#                              tests/sil/envelope/*.scn (part of make test)
#   make sil-envelope-pending  tests/sil/envelope_pending/*.scn: right
#                              expectations the firmware does not meet yet
#   make bench-envelope        the full matrix, ENVELOPE_SEEDS noise seeds on
#                              ENVELOPE_JOBS cores: a table per point and a
#                              summary on stdout, $(BUILD)/bench/envelope.json
#                              (every run, the confusion matrix, the summary)
#                              and $(BUILD)/bench/envelope_confusion.png; the
#                              scenarios stay in $(BUILD)/bench/envelope_scn/.
#                              A bench: fails only when it cannot run
#                              (~1 min per seed on 2 cores here).
# The runners are named directly: sil.mk, which defines them, is read after
# this file. Regenerate the sampled set after editing dbc/ or the grid:
#   .venv/bin/python tests/sil/gen_envelope.py
ENVELOPE_JOBS ?= 2
ENVELOPE_SEEDS ?= 3
SIL_ENVELOPE := $(sort $(wildcard tests/sil/envelope/*.scn))
SIL_ENVELOPE_PENDING := $(sort $(wildcard tests/sil/envelope_pending/*.scn))

.PHONY: sil-envelope sil-envelope-pending bench-envelope
sil-envelope: $(BUILD)/bin/canfdi-sil
	CANFDI_SIL=$(CURDIR)/$< $(PY) -m pytest -p no:cacheprovider -q tests/sil/test_envelope.py
	@bash tests/sil/run_scenarios.sh $< $(SIL_ENVELOPE)

sil-envelope-pending: $(BUILD)/bin/canfdi-sil
	-@bash tests/sil/run_scenarios.sh $< $(SIL_ENVELOPE_PENDING)

bench-envelope: $(BUILD)/bench/canfdi-sil-rel
	$(PY) tests/sil/gen_envelope.py --bench $< --out $(BUILD)/bench/envelope.json \
	  --png $(BUILD)/bench/envelope_confusion.png --scn-dir $(BUILD)/bench/envelope_scn \
	  --jobs $(ENVELOPE_JOBS) --seeds $(ENVELOPE_SEEDS)

TEST_STEPS += sil-envelope
BENCH_STEPS += bench-envelope
