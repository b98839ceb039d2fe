#!/usr/bin/env bash
# tests/sil/bench_step.sh BIN JSON SCENARIO... — host instructions per
# canfdi_app_step (x86-64, the compiler flags of BIN), measured by callgrind
# with collection switched on inside canfdi_app_step only; mean over every
# step of each scenario. Prints a line per scenario and writes JSON.
set -eu
bin=$1; json=$2; shift 2
command -v valgrind >/dev/null || { echo "sil-bench: valgrind not found"; exit 0; }
mkdir -p "$(dirname "$json")"
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
echo "[" > "$json"; first=1
for s in "$@"; do
  valgrind --tool=callgrind --toggle-collect=canfdi_app_step \
    --callgrind-out-file="$tmp/cg.out" "$bin" -q -s "$s" >/dev/null 2>"$tmp/err" || true
  ir=$(sed -n 's/.*Collected : \([0-9]*\).*/\1/p' "$tmp/err")
  steps=$(awk '/^duration/ {printf "%d", $2 * 1000 + 0.5}' "$s")
  per=$(( ir / steps ))
  echo "sil-bench: $s: $per host instructions per canfdi_app_step (mean of $steps steps, callgrind)"
  [ $first -eq 1 ] || echo "," >> "$json"; first=0
  printf '  {"scenario": "%s", "steps": %d, "instructions": %d, "instructions_per_step": %d}' \
    "$s" "$steps" "$ir" "$per" >> "$json"
done
printf '\n]\n' >> "$json"
echo "sil-bench: wrote $json"
