# mk/diagrules.mk — the diagnosis rule table (firmware/diag/canfdi_diagnosis.c)
# checked against the MEASURED fault-symptom table: `make test` first runs
# the symptom bench (bench/bench_symptoms.c, ~20 s) and then requires every
# rule to agree with it (tests/dbc/test_diagnosis_rules.py; without the
# table, `make dbc-test` skips that file).
.PHONY: diag-rules-test
diag-rules-test: deps
	@mkdir -p $(BUILD)
	@$(MAKE) --no-print-directory bench-symptoms >$(BUILD)/bench-symptoms.log 2>&1 || \
	  { cat $(BUILD)/bench-symptoms.log; exit 1; }
	CANFDI_REQUIRE_SYMPTOMS=1 $(PY) -m pytest tests/dbc/test_diagnosis_rules.py -q -p no:cacheprovider

TEST_STEPS += diag-rules-test
