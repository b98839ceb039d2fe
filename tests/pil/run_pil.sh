#!/usr/bin/env bash
# tests/pil/run_pil.sh — the PIL rig's runner (mk/pil.mk: make pil-test,
# make bench-pil).
#   run_pil.sh --sil BIN --json OUT --work DIR --machines "NAME:QEMU:CORE:ELF ..."
#              [--rls "IMPL:MACHINE:QEMU:ELF ..."] SCENARIO...
# For every scenario: the host SIL run (BIN -l) records the bus log; every
# machine's image (tests/pil/pil_step.c) replays its frames on QEMU and
# compares the ECU's frames bit for bit. A run passes when every frame of
# every step is identical and the image ran to the end. With --rls, the RLS
# bench images run too. Writes OUT (JSON, tests/pil/pil_report.py) and
# prints "N passed, N failed"; exits 1 on a failure.
set -uo pipefail
sil=""; json=""; work=""; machines=""; rls=""
while (($#)); do
  case "$1" in
    --sil) sil=$2; shift 2 ;;
    --json) json=$2; shift 2 ;;
    --work) work=$2; shift 2 ;;
    --machines) machines=$2; shift 2 ;;
    --rls) rls=$2; shift 2 ;;
    *) break ;;
  esac
done
command -v qemu-system-arm >/dev/null || { echo "pil: qemu-system-arm not found (make deps)"; exit 2; }
mkdir -p "$work" "$(dirname "$json")"
results="$work/results.tsv"; : > "$results"
rlsres="$work/rls.tsv"; : > "$rlsres"
passed=0; failed=0
# An image runs a few seconds; one that has not ended after PIL_TIMEOUT
# seconds hangs (rc 124).
PIL_TIMEOUT=${PIL_TIMEOUT:-240}
qemu() { # machine elf -> stdout of the image
  timeout "$PIL_TIMEOUT" qemu-system-arm -M "$1" -nographic -icount shift=6 \
    -semihosting-config enable=on,target=native -kernel "$2"
}
for scn in "$@"; do
  name=$(basename "$scn" .scn)
  dir="$work/$name"; mkdir -p "$dir"
  if ! "$sil" -q -s "$scn" -l "$dir/pil.log" >/dev/null 2>&1 && [ ! -s "$dir/pil.log" ]; then
    echo "pil: FAIL $name: the SIL run wrote no log"; failed=$((failed + 1)); continue
  fi
  for m in $machines; do
    IFS=: read -r mname mqemu mcore melf <<<"$m"
    elf=$(readlink -f "$melf")
    out=$(cd "$dir" && qemu "$mqemu" "$elf" 2>&1); rc=$?
    line=$(grep '^pil: steps' <<<"$out" | tail -1)
    if [ -z "$line" ]; then
      echo "pil: FAIL $name on $mname ($mcore, $mqemu): no result (rc $rc): $(tail -2 <<<"$out" | tr '\n' ' ')"
      failed=$((failed + 1)); continue
    fi
    read -r _ _ steps _ mn _ mean _ mx _ mxs _ cmp _ diff _ first <<<"$line"
    ramline=$(grep '^pil: ram' <<<"$out" | tail -1)
    read -r _ _ _ _ _ _ _ ramfree <<<"$ramline"
    why="rc $rc"
    [ "$rc" -eq 124 ] && why="the image did not end within ${PIL_TIMEOUT} s"
    [ "$rc" -eq 3 ] && why="the stack ran into the heap ($ramline)"
    printf '%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\n' "$name" "$mname" "$mcore" "$mqemu" "$steps" \
      "$mn" "$mean" "$mx" "$mxs" "$diff" "$first" >> "$results"
    if [ "$rc" -eq 0 ] && [ "$diff" -eq 0 ] && [ "$cmp" -eq "$steps" ]; then
      printf 'pil: pass %-18s %-3s %-10s steps %6d  instructions per step min %6d mean %6d max %6d (step %d)  RAM never touched %s B\n' \
        "$name" "$mname" "$mcore" "$steps" "$mn" "$mean" "$mx" "$mxs" "${ramfree:-?}"
      udsline=$(grep '^pil: uds_steps' <<<"$out" | tail -1)
      if [ -n "$udsline" ]; then
        read -r _ _ us _ umx _ umxs <<<"$udsline"
        printf 'pil:      %-18s %-3s %-10s steps with a UDS request or response in flight %d: max %d (step %d)\n' \
          "$name" "$mname" "$mcore" "$us" "$umx" "$umxs"
      fi
      passed=$((passed + 1))
    else
      echo "pil: FAIL $name on $mname ($mcore): $diff of $cmp steps differ from the host build (first: step $first), $why"
      failed=$((failed + 1))
    fi
  done
done
# The comparison itself: one bit flipped in one ECU frame of the first
# scenario's log must make the first machine's run fail (else a broken
# comparison would pass everything).
if (($# > 0)) && [ -n "$machines" ]; then
  name=$(basename "$1" .scn); neg="$work/negative"; mkdir -p "$neg"
  # the 1000th EcuActuator-class frame (an ECU frame: id >= 0x020, not a
  # setpoint or plant frame), its last data bit inverted
  python3 - "$work/$name/pil.log" "$neg/pil.log" <<'PY'
import sys
n = 0
with open(sys.argv[1]) as f, open(sys.argv[2], "w") as g:
    for line in f:
        parts = line.split()
        ident, data = parts[2].split("#")
        if 0x200 <= int(ident, 16) < 0x600 and n < 1000:
            n += 1
            if n == 1000:
                data = data[:-1] + "%X" % (int(data[-1], 16) ^ 1)
                line = "%s %s %s#%s\n" % (parts[0], parts[1], ident, data)
        g.write(line)
PY
  IFS=: read -r mname mqemu mcore melf <<<"${machines%% *}"
  elf=$(readlink -f "$melf")
  out=$(cd "$neg" && qemu "$mqemu" "$elf" 2>&1)
  line=$(grep '^pil: steps' <<<"$out" | tail -1)
  read -r _ _ _ _ _ _ _ _ _ _ _ _ _ _ diff _ <<<"$line"
  if ! cmp -s "$neg/pil.log" "$work/$name/pil.log" && [ "${diff:-0}" -ge 1 ]; then
    echo "pil: pass negative check: one flipped bit in $name's log makes $mname report ${diff} differing step"
    passed=$((passed + 1))
  else
    echo "pil: FAIL negative check: a flipped bit in $name's log went unnoticed on $mname"
    failed=$((failed + 1))
  fi
fi
for v in $rls; do
  IFS=: read -r impl mname mqemu melf <<<"$v"
  line=$(qemu "$mqemu" "$melf" 2>&1 | grep '^rls-pil:' | tail -1)
  if [ -z "$line" ]; then
    echo "pil: FAIL rls bench $impl on $mname: no result"; failed=$((failed + 1)); continue
  fi
  read -r _ _ _ calls _ mn _ mean _ mx _ <<<"$line"
  printf '%s\t%s\t%s\t%s\t%s\t%s\t%s\n' "$impl" "$mname" "$mqemu" "$calls" "$mn" "$mean" "$mx" >> "$rlsres"
  echo "pil: rls bench $impl on $mname ($mqemu): $line"
done
python3 tests/pil/pil_report.py --steps "$results" --rls "$rlsres" --out "$json" || failed=$((failed + 1))
echo "$passed passed, $failed failed"
[ "$failed" -eq 0 ]
