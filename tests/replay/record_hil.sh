#!/usr/bin/env bash
# record_hil.sh OUTDIR SCENARIO... — inside the vcan sandbox (tools/vcan-run):
# canfdi-scenario runs each scenario in lockstep on vcan0 (canfdi-ecu and
# the sandbox build of canfdi-sim) and records the bus to OUTDIR/<name>.log,
# the recordings tests/replay/test_replay_hil.py replays. Exit status: the
# first failing run's.
set -u
out=$1; shift
mkdir -p "$out"
cd "$(dirname "$0")/../.."
rc=0
for scn in "$@"; do
  name=$(basename "$scn" .scn)
  if ! .venv/bin/canfdi-scenario -q --log "$out/$name.log" --json "$out/$name.json" "$scn"; then
    echo "record_hil: canfdi-scenario $scn failed" >&2
    [ "$rc" -ne 0 ] || rc=1
  fi
done
exit "$rc"
