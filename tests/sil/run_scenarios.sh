#!/usr/bin/env bash
# tests/sil/run_scenarios.sh BIN SCENARIO... — run each scenario through the
# SIL rig, SIL_JOBS at a time (default: one per core), show its verdict
# lines as it ends, and end with "sil: N passed, N failed" (tools/run-each).
# Exit status 1 if any scenario failed.
set -u
bin=$1; shift
exec "$(dirname "$0")/../../tools/run-each" sil "${SIL_JOBS:-$(nproc 2>/dev/null || echo 1)}" "$bin" -q -s -- "$@"
