#!/usr/bin/env bash
# fw_guard.sh — the target build guard's checks on linked Cortex-M images.
#
# Usage (normally from mk/target.mk via `make firmware`):
#   fw_guard.sh [--nm NM] --main tests/target/guard_main.c \
#               --sources "FW .c files" --headers "FW .h files" \
#               TARGET=ELF ...
# For each TARGET=ELF, ELF.objs must list the firmware object files linked
# into ELF (one per line; the entry point's object is not one of them) and
# ELF with .elf replaced by .map is the linker map (used to say who pulled a
# forbidden symbol in).
#
# Checks, all run (so one report shows every problem), exit 1 if any fails:
#  1. no heap function in the image (malloc, free, _sbrk, _malloc_r, ...);
#  2. no soft-float helper in the image (__aeabi_d*/__aeabi_f*, __aeabi_i2f,
#     __adddf3, __floatsidf, __extendsfdf2, ...). Integer helpers
#     (__aeabi_idiv, __aeabi_ldivmod, __aeabi_lmul, __aeabi_llsl, ...) are fine;
#  3. completeness: every global function defined in a firmware object is in
#     the image, i.e. the entry point calls it so --gc-sections did not hide it
#     from checks 1-2. Excluded: cantools-generated *_is_in_phys_range(), which
#     take a `double` by construction and must never be called in firmware
#     (dbc/README.md), so they must be garbage-collected, not linked;
#  4. every `static inline` function of a firmware header (also those declared
#     with the CANFDI_*INLINE macros) is referenced in the
#     entry point (inline code lands in the caller, so only a call checks it);
#  5. no `float`/`double` keyword in firmware sources outside comments and
#     string literals (the generated *_is_in_phys_range(double) lines are
#     excepted). Floating-point literals without the keyword (x * 1.5) are
#     caught by check 2, not here.
set -uo pipefail

NM=arm-none-eabi-nm
MAIN=""
SOURCES=""
HEADERS=""
KWONLY=""   # port sources not linked into the target image: keyword check only
TARGETS=()
while (($#)); do
  case "$1" in
    --nm) NM=$2; shift 2 ;;
    --main) MAIN=$2; shift 2 ;;
    --sources) SOURCES=$2; shift 2 ;;
    --headers) HEADERS=$2; shift 2 ;;
    --kw-only) KWONLY=$2; shift 2 ;;
    -h|--help) sed -n '2,30p' "$0"; exit 0 ;;
    -*) echo "fw_guard: unknown option $1" >&2; exit 2 ;;
    *) TARGETS+=("$1"); shift ;;
  esac
done
if [ -z "$MAIN" ] || ((${#TARGETS[@]} == 0)); then
  echo "fw_guard: usage: fw_guard.sh --main FILE --sources LIST --headers LIST TARGET=ELF ..." >&2
  exit 2
fi

fails=0
fail() { echo "fw_guard: FAIL: $*" >&2; fails=$((fails + 1)); }

# Heap: the allocator entry points of newlib (and their reentrant _r forms),
# its sbrk, and its internal state (__malloc_*).
HEAP_RE='^_?(malloc|free|calloc|realloc|reallocf|memalign|aligned_alloc|posix_memalign|valloc|pvalloc|mallinfo|mallopt|malloc_trim|malloc_usable_size|malloc_stats|sbrk|nano_malloc|nano_free)(_r)?$|^__malloc_'
# Soft-float: ARM EABI float/double helpers, their libgcc names (mode suffix
# sf/df/tf/xf/hf, e.g. __adddf3, __floatsidf, __fixdfdi, __extendsfdf2),
# complex helpers, the half-precision converters and the fixed-point-type
# (_Fract/_Accum) conversions from/to float or double (__gnu_fractdfsa, ...).
SOFTFP_RE='^__aeabi_(c?[fd]|u?[il]2[fd])|^__gnu_(f2h|h2f|d2h|h2d)|^__gnu_(sat)?fract(uns)?((sf|df)[a-z]+|[a-z]+(sf|df))[0-9]?$|^__[a-z]{2,}(sf|df|tf|xf|hf)([0-9]|[a-z]{2}[0-9]?)?$|^__(mul|div)(sc|dc|tc|xc)3$'

# Who made the linker pull a library member defining $sym (from the map).
pulled_by() {
  local map=$1 sym=$2
  [ -f "$map" ] || return 0
  awk -v s="($sym)" '
    /^Archive member included/ { on = 1; next }
    /^(Discarded input sections|Memory Configuration|Allocating common)/ { on = 0 }
    on && index($0, s) { sub(/^[ \t]+/, ""); print; exit }' "$map"
}

report_syms() { # kind elf map syms...
  local kind=$1 elf=$2 map=$3; shift 3
  local why=() s p
  for s in "$@"; do
    p=$(pulled_by "$map" "$s")
    [ -n "$p" ] && why+=("    $s <- $p")
  done
  fail "$kind: $* [in $elf]"
  if ((${#why[@]})); then
    printf '%s\n' "  first references (from the link map):" "${why[@]}" >&2
  fi
}

# Strip C comments (keeping line numbers) and blank string/char literals.
strip_c() {
  perl -0777 -pe '
    s{("(?:\\.|[^"\\\n])*")|(\x27(?:\\.|[^\x27\\\n])*\x27)|(/\*.*?\*/)|(//[^\n]*)}{
      defined $1 ? q("") : defined $2 ? q(0) : defined $3 ? join("", $3 =~ /\n/g) : ""
    }gse' "$1"
}

for spec in "${TARGETS[@]}"; do
  tgt=${spec%%=*}
  elf=${spec#*=}
  map=${elf%.elf}.map
  if [ ! -f "$elf" ] || [ ! -f "$elf.objs" ]; then
    fail "$tgt: missing $elf or $elf.objs (build it first)"
    continue
  fi
  all_syms=$("$NM" "$elf" | awk 'NF >= 2 { print $NF }' | sort -u)
  # shellcheck disable=SC2207
  heap=($(grep -E "$HEAP_RE" <<<"$all_syms"))
  # shellcheck disable=SC2207
  softfp=($(grep -E "$SOFTFP_RE" <<<"$all_syms"))
  ((${#heap[@]})) && report_syms "$tgt: heap function(s) linked" "$elf" "$map" "${heap[@]}"
  ((${#softfp[@]})) && report_syms "$tgt: soft-float helper(s) linked (floating point in firmware)" "$elf" "$map" "${softfp[@]}"

  elf_funcs=$("$NM" --defined-only "$elf" | awk '$2 == "T" { print $3 }' | sort -u)
  # shellcheck disable=SC2046
  fw_funcs=$("$NM" --defined-only -g $(cat "$elf.objs") 2>/dev/null |
    awk 'NF == 3 && $2 == "T" { print $3 }' | grep -v '_is_in_phys_range$' | sort -u)
  missing=$(comm -23 <(echo "$fw_funcs") <(echo "$elf_funcs") | grep -v '^$')
  if [ -n "$missing" ]; then
    fail "$tgt: firmware function(s) not in the image, not called from $MAIN: $(echo $missing)"
  fi
  nfw=$(grep -c . <<<"$fw_funcs")
  if ((${#heap[@]} == 0 && ${#softfp[@]} == 0)) && [ -z "$missing" ]; then
    echo "fw_guard: $tgt: no heap, no soft-float, all $nfw firmware functions linked"
  fi
done

# 4. static inline functions of the firmware headers, referenced in MAIN.
main_txt=$(strip_c "$MAIN")
ninl=0
unref=()
for h in $HEADERS; do
  while read -r fn; do
    [ -n "$fn" ] || continue
    ninl=$((ninl + 1))
    grep -qw -- "$fn" <<<"$main_txt" || unref+=("$fn ($h)")
  done < <(strip_c "$h" | perl -0777 -ne '
      s/__attribute__\s*\(\(.*?\)\)//gs;
      while (/\b(?:static\s+inline|inline\s+static|static\s+__inline__|static\s+__inline|static\s+CANFDI_\w*INLINE)\b[^;{}()]*?\b([A-Za-z_]\w*)\s*\(/g) { print "$1\n" }')
done
if ((${#unref[@]})); then
  fail "static inline function(s) not referenced in $MAIN: ${unref[*]}"
fi

# 5. float/double keywords in firmware sources.
kw=()
for f in $SOURCES $HEADERS $KWONLY; do
  while IFS= read -r hit; do
    kw+=("$f:$hit")
  done < <(strip_c "$f" | grep -nwE 'float|double' | grep -vE '_is_in_phys_range[[:space:]]*\([[:space:]]*double')
done
if ((${#kw[@]})); then
  fail "float/double keyword in firmware source (fixed point only):"
  printf '    %s\n' "${kw[@]}" >&2
fi

if ((fails)); then
  echo "fw_guard: $fails check(s) failed" >&2
  exit 1
fi
echo "fw_guard: $ninl static inline functions referenced; no float/double in $(echo $SOURCES $HEADERS $KWONLY | wc -w) firmware files"
exit 0
