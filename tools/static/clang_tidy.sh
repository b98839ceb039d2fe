#!/usr/bin/env bash
# tools/static/clang_tidy.sh — clang-tidy's static analyzer checks
# (clang-analyzer-*) over the firmware (make static-check). Built as the
# host tests build it: C99, CANFDI_ASSERT as assert(), so the analyzer
# knows the invariants the code asserts. Exit status 1 on a finding whose
# "file: check" is not in tools/static/tidy.baseline (each reviewed in
# docs/misra.md, "Analyzer findings"). Scope as tools/static/cppcheck.sh.
# Excluded: clang-analyzer-security.insecureAPI.DeprecatedOrUnsafeBufferHandling
# (it asks for memcpy_s/memset_s, C11 Annex K, which newlib has not).
set -euo pipefail
cd "$(dirname "$0")/../.."
out=${1:-build/static}
mkdir -p "$out"
mapfile -t src < <(find firmware -name '*.c' -not -path 'firmware/port/linux/*' | LC_ALL=C sort)
checks='-*,clang-analyzer-*,-clang-analyzer-security.insecureAPI.DeprecatedOrUnsafeBufferHandling'
clang-tidy -quiet -checks="$checks" "${src[@]}" -- -std=c99 -Ifirmware \
  -include assert.h '-DCANFDI_ASSERT(x)=assert(x)' > "$out/clang-tidy.log" 2>"$out/clang-tidy.err" || true
if grep -q 'error:' "$out/clang-tidy.log"; then
  grep 'error:' "$out/clang-tidy.log" >&2
  echo "clang-tidy: compile errors (above)" >&2
  exit 1
fi
sed -n "s|^$PWD/\([^:]*\):[0-9]*:[0-9]*: warning: .* \[\(clang-analyzer-[^]]*\)\]$|\1: \2|p" "$out/clang-tidy.log" \
  | LC_ALL=C sort -u > "$out/clang-tidy.found"
new=$(grep -vxF -f <(grep -v '^#' tools/static/tidy.baseline) "$out/clang-tidy.found" || true)
if [ -n "$new" ]; then
  echo "$new" | while read -r l; do grep -F "${l%%:*}" "$out/clang-tidy.log" | grep -F "[${l##* }]" >&2; done
  echo "clang-tidy: new analyzer finding(s) above ($out/clang-tidy.log): fix, or review in docs/misra.md and tools/static/tidy.baseline" >&2
  exit 1
fi
echo "clang-tidy clang-analyzer-*: no finding outside tools/static/tidy.baseline (${#src[@]} files)"
