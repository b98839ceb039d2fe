#!/usr/bin/env bash
# tests/sil/run_scenarios.sh BIN SCENARIO... — run each scenario through the
# SIL rig, show its verdict lines, and end with "N passed, N failed".
# Exit status 1 if any scenario failed.
set -u
bin=$1; shift
pass=0; fail=0; failed=()
for s in "$@"; do
  if out=$("$bin" -q -s "$s" 2>&1); then
    pass=$((pass+1)); echo "ok    $s"
  else
    fail=$((fail+1)); failed+=("$s"); echo "FAIL  $s"
  fi
  printf '%s\n' "$out" | sed 's/^/      /'
done
echo "sil: $pass passed, $fail failed"
[ "$fail" -eq 0 ]
