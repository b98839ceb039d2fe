#!/usr/bin/env bash
# test_guard_negative.sh — proves the target build guard (`make firmware`)
# rejects what it claims to reject, and accepts the unmodified tree.
#
# Copies the source tree (without build/, .venv/, .git/) to a temporary
# directory, builds it once as is (must pass), then for each case copies that
# built tree again, injects one defect into the copy and runs `make firmware`
# there, which must FAIL with the expected message. Nothing in the real tree
# is touched. Cases:
#   double-keyword   a `double` computation inside a firmware function that the
#                    entry point reaches (source check + soft-float check);
#   float-literal    floating point without the keyword (int * 1.5): only the
#                    symbol check can see it;
#   malloc           a heap allocation in a firmware function;
#   uncalled-func    a new public firmware function the entry point ignores;
#   uncalled-inline  a new static inline in a firmware header, ditto.
# Prints `N passed, N failed`; exit status 1 if any case failed.
set -uo pipefail
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
JOBS=$(nproc 2>/dev/null || echo 2)
TMP=$(mktemp -d "${TMPDIR:-/tmp}/canfdi-guard-neg.XXXXXX")
trap 'rm -rf "$TMP"' EXIT

passed=0
failed=0
ok() { echo "  ok   $1"; passed=$((passed + 1)); }
nok() { echo "  FAIL $1"; failed=$((failed + 1)); }

copy_tree() { # src dst [with-build]
  mkdir -p "$2"
  local ex=(--exclude=./.git --exclude=./.venv)
  [ "${3:-}" = with-build ] || ex+=(--exclude=./build)
  tar -C "$1" "${ex[@]}" -cf - . | tar -C "$2" -xpf -
  # Fragments may name the venv's interpreter; share it, never modify it.
  [ -e "$ROOT/.venv" ] && ln -s "$ROOT/.venv" "$2/.venv"
  return 0
}

run_fw() { # dir log -> exit status of make firmware
  make -C "$1" -j"$JOBS" --no-print-directory firmware >"$2" 2>&1
}

# A public, non-static function defined in a firmware .c file (not port/),
# preferring the fixed-point core, which every detector uses. Prints "file func".
pick_function() {
  local f hit
  for f in $(cd "$1" && { ls firmware/core/*.c 2>/dev/null; find firmware -name '*.c' -not -path 'firmware/port/*' | sort; }); do
    hit=$(perl -0777 -ne '
      s{/\*.*?\*/}{}gs; s{//[^\n]*}{}g;
      while (/^((?:[A-Za-z_][\w \t\*]*\s)?)(canfdi_\w+)\s*\([^;{}]*\)\s*\{/mg) {
        next if $1 =~ /\bstatic\b/;
        print "$2\n"; last }' "$1/$f")
    if [ -n "$hit" ]; then echo "$f $hit"; return 0; fi
  done
  return 1
}

# Insert C statement(s) as the first statement of function $3 in file $2
# (relative to tree $1).
inject_stmt() {
  STMT=$4 perl -0777 -i -pe '
    BEGIN { $fn = shift @ARGV }
    s{^((?:[A-Za-z_][\w \t\*]*\s)?\Q$fn\E\s*\([^;{}]*\)\s*\{)}{$1\n  $ENV{STMT}\n}m
      or die "inject: $fn not found\n"' "$3" "$1/$2"
}

# Case runner: name, expected-regex..., with the injection done by a function.
expect_fail() { # name log regex...
  local name=$1 log=$2; shift 2
  local re missing=()
  for re in "$@"; do
    grep -Eq -- "$re" "$log" || missing+=("$re")
  done
  if ((${#missing[@]})); then
    nok "$name: make firmware failed, but without: ${missing[*]}"
    sed 's/^/       | /' "$log" | tail -n 15
  else
    ok "$name: rejected: $(grep -m1 'FAIL' "$log" | sed 's/^fw_guard: FAIL: //' | cut -c1-150)"
  fi
}

echo "== target guard negative test (tree copies under $TMP)"
BASE=$TMP/base
copy_tree "$ROOT" "$BASE"
if run_fw "$BASE" "$TMP/base.log"; then
  ok "unmodified tree: make firmware passes"
else
  nok "unmodified tree: make firmware fails (nothing below is meaningful)"
  sed 's/^/       | /' "$TMP/base.log" | tail -n 25
  echo "$passed passed, $failed failed"
  exit 1
fi

read -r FILE FUNC <<<"$(pick_function "$BASE")"
if [ -z "${FUNC:-}" ]; then
  nok "no public firmware function found to inject into"
  echo "$passed passed, $failed failed"
  exit 1
fi
echo "   injecting into $FUNC() in $FILE"

run_case() { # name setup-function expected-regex...
  local name=$1 setup=$2; shift 2
  local dir=$TMP/$name log=$TMP/$name.log
  copy_tree "$BASE" "$dir" with-build
  if ! "$setup" "$dir" >"$log" 2>&1; then
    nok "$name: could not inject the defect"; sed 's/^/       | /' "$log"; return
  fi
  if run_fw "$dir" "$log"; then
    nok "$name: make firmware PASSED on a defective tree"
    sed 's/^/       | /' "$log" | tail -n 10
  else
    expect_fail "$name" "$log" "$@"
  fi
  rm -rf "$dir"
}

# A volatile keeps the computation from being folded away at -Os.
setup_double() {
  inject_stmt "$1" "$FILE" "$FUNC" \
    '{ static volatile double canfdi_neg_d = 3.0; canfdi_neg_d = canfdi_neg_d * 1.5 + 0.25; }'
}
setup_literal() {
  inject_stmt "$1" "$FILE" "$FUNC" \
    '{ static volatile int32_t canfdi_neg_i = 3; canfdi_neg_i = (int32_t)(canfdi_neg_i * 1.5); }'
}
setup_malloc() {
  perl -0777 -i -pe 's{^}{#include <stdlib.h>\n}' "$1/$FILE" &&
    inject_stmt "$1" "$FILE" "$FUNC" \
      '{ static void *volatile canfdi_neg_p; canfdi_neg_p = malloc(16U); free(canfdi_neg_p); }'
}
setup_uncalled_func() {
  printf '%s\n' '' 'int32_t canfdi_neg_uncalled(int32_t x);' \
    'int32_t canfdi_neg_uncalled(int32_t x) { return x + 1; }' >>"$1/$FILE"
}
setup_uncalled_inline() {
  # Before the include guard's closing #endif of the common header.
  perl -0777 -i -pe '
    s{(.*)(\n#endif)}{$1\nstatic inline int32_t canfdi_neg_inline(int32_t x) { return x; }\n$2}s
      or die "no #endif\n"' "$1/firmware/core/canfdi_common.h"
}

run_case double-keyword setup_double \
  'soft-float helper\(s\).*__aeabi_d' 'float/double keyword in firmware source' "$FILE:[0-9]+:.*double"
run_case float-literal setup_literal \
  'cortex-m4: soft-float helper\(s\).*__aeabi_(i2d|dmul|d2iz)' \
  'cortex-m0plus: soft-float helper\(s\)' "<- .*$(basename "$FILE" .c)\.o"
run_case malloc setup_malloc \
  'cortex-m4: heap function\(s\).*malloc' 'cortex-m0plus: heap function\(s\).*malloc'
run_case uncalled-func setup_uncalled_func \
  'cortex-m4: .*not called from tests/target/guard_main\.c: .*canfdi_neg_uncalled' \
  'cortex-m0plus: .*not called from tests/target/guard_main\.c: .*canfdi_neg_uncalled'
run_case uncalled-inline setup_uncalled_inline \
  'static inline function\(s\) not referenced in tests/target/guard_main\.c: canfdi_neg_inline'

echo "$passed passed, $failed failed"
((failed == 0))
