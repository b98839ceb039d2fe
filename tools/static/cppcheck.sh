#!/usr/bin/env bash
# tools/static/cppcheck.sh — cppcheck with its MISRA C:2012 addon over the
# firmware (make static-check). Exit status 1 on any finding not in
# tools/static/misra.supp (each deviation justified in docs/misra.md).
# Scope: every firmware C file but firmware/port/linux (the host program
# canfdi-ecu, POSIX, not target code); always the whole set, in one run:
# findings in headers are reported once per run, so a partial run differs.
# Rule texts: cppcheck has none of its own (MISRA's are licensed); with
# CPPCHECK_RULE_TEXTS=file the messages carry them, else rule numbers only.
set -euo pipefail
cd "$(dirname "$0")/../.."
out=${1:-build/static}
mkdir -p "$out"
texts=()
[ -n "${CPPCHECK_RULE_TEXTS:-}" ] && texts=(--rule-texts="$CPPCHECK_RULE_TEXTS")
# the addon reads its options from a JSON file
printf '{"script": "misra", "args": [%s]}\n' \
  "$([ ${#texts[@]} -gt 0 ] && printf '"%s"' "${texts[0]}")" > "$out/misra.json"
mapfile -t src < <(find firmware -name '*.c' -not -path 'firmware/port/linux/*' | LC_ALL=C sort)
cppcheck --addon="$out/misra.json" --std=c99 --platform=unix32 -q -Ifirmware \
  -UCANFDI_CONFIG_HEADER --max-configs=1 --inline-suppr \
  --suppressions-list=tools/static/misra.supp --error-exitcode=1 \
  --template='{file}:{line}: {severity}: {message} [{id}]' "${src[@]}" 2>&1 | tee "$out/cppcheck.log"
rc=${PIPESTATUS[0]}
if [ "$rc" -ne 0 ]; then
  echo "cppcheck: new finding(s) above ($out/cppcheck.log): fix, or justify in docs/misra.md and tools/static/misra.supp" >&2
  exit 1
fi
echo "cppcheck + MISRA addon: no finding outside docs/misra.md (${#src[@]} files)"
