#!/usr/bin/env bash
# bench/hil_bench.sh OUT_DIR ECU SIM — HIL figures on vcan0; run it where vcan0
# exists (`make bench-hil` runs it through tools/vcan-run). Writes the raw
# statistics of both processes into OUT_DIR; bench/hil_report.py turns them
# into build/bench/hil.json. A benchmark: prints figures, fails only when a
# run could not be made at all.
#   1. lockstep: canfdi-ecu --lockstep against canfdi-sim --lockstep on
#      nominal_setpoints.scn (20 simulated s), nobody else on the bus:
#      steps per second of wall time (the sim's statistics).
#   2. the same with candump -L recording the whole bus (what a test does).
#   3. realtime: both at 1 kHz on CLOCK_MONOTONIC for RT_S (default 60) s,
#      the built-in nominal vehicle: the ECU's deadline misses, step time and
#      wake-up latency percentiles, the sim's late steps.
set -u
out=$1 ecu=$2 sim=$3
rt_s=${RT_S:-60}
scn=tests/sil/scenarios/nominal_setpoints.scn
mkdir -p "$out"
rm -f "$out"/*.json "$out"/*.err

wait_ready() { # file
  local i
  for i in $(seq 200); do grep -q 'ready on' "$1" 2>/dev/null && return 0; sleep 0.05; done
  echo "hil_bench: $(basename "$1" .err) did not get ready:" >&2; cat "$1" >&2; return 1
}

lockstep() { # name, record(0/1)
  local name=$1 rec=$2 e c=
  "$ecu" --lockstep -q --stats "$out/$name-ecu.json" 2>"$out/$name-ecu.err" & e=$!
  wait_ready "$out/$name-ecu.err" || return 1
  if [ "$rec" = 1 ]; then candump -r 33554432 -L vcan0 >"$out/$name.log" & c=$!; sleep 0.2; fi
  "$sim" --can vcan0 --lockstep -s "$scn" --stats "$out/$name-sim.json" 2>"$out/$name-sim.err" || {
    echo "hil_bench: sim failed:" >&2; cat "$out/$name-sim.err" >&2; kill "$e"; return 1; }
  [ -n "$c" ] && { sleep 0.5; kill "$c"; wait "$c" 2>/dev/null; }
  kill -TERM "$e"; wait "$e"
  grep -h 'done' "$out/$name-sim.err" | sed "s/^/  $name: /"
}

echo "hil_bench: lockstep, $scn" >&2
lockstep lockstep 0 || exit 1
lockstep lockstep-rec 1 || exit 1
echo "hil_bench: realtime, ${rt_s} s" >&2
"$ecu" -q --stats "$out/realtime-ecu.json" 2>"$out/realtime-ecu.err" & e=$!
wait_ready "$out/realtime-ecu.err" || exit 1
"$sim" --can vcan0 --realtime --duration "$rt_s" --stats "$out/realtime-sim.json" 2>"$out/realtime-sim.err" || {
  echo "hil_bench: sim failed:" >&2; cat "$out/realtime-sim.err" >&2; kill "$e"; exit 1; }
kill -TERM "$e"; wait "$e"
grep -h 'done' "$out/realtime-sim.err" | sed 's/^/  realtime: /'
exit 0
