#!/usr/bin/env bash
# Self-test of tools/vcan-run (make vcan-test). Prints one line per check and
# "vcan-run: N passed, N failed"; exits 1 if a check failed.
#
# Checks: exit status propagation (0, 3, 255, death by signal), stdout and
# stderr kept apart and byte-exact (100k lines each), arguments with spaces,
# quotes, newlines and globs, working directory with spaces, an environment
# variable with awkward characters, vcan0 up (ip -details), a cansend frame
# received by candump, python-can on vcan0 (if .venv exists), --timeout
# (exit 124, partial output delivered, nothing left behind), clear errors
# (exit 125) for impossible modes, and that no work directory or sandbox
# process is left behind after any run.
#
# Five sandboxes boot (three of them at the same time), ~15 s in all with the
# python-can check, in whichever mode vcan-run picks (CANFDI_VCAN applies).
set -u
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
VR=$ROOT/tools/vcan-run
pass=0 fail=0
ok() { # ok NAME CONDITION-EXIT-STATUS [DETAIL]
  if [ "$2" -eq 0 ]; then pass=$((pass + 1)); echo "ok   $1"
  else fail=$((fail + 1)); echo "FAIL $1${3:+: $3}"; fi
}
check() { local name=$1; shift; "$@" >/dev/null 2>&1; ok "$name" $?; }

T=$(mktemp -d /tmp/vcan-test.XXXXXX)
trap 'rm -rf "$T"' EXIT
# vcan-run makes its work directory under $TMPDIR: a private one shows
# whether it cleans up, and its path identifies the sandbox's processes.
mkdir "$T/tmp"
export TMPDIR=$T/tmp
D="$T/dir with spaces"
mkdir "$D"
leftovers() { # nothing in $TMPDIR, no process mentioning it
  [ -z "$(ls -A "$TMPDIR")" ] && ! pgrep -f "$TMPDIR/vcan-run" >/dev/null
}

# ---- boot A: everything that fits in one run; CMD exits 3.
cat > "$D/inner.sh" <<'EOF'
#!/bin/bash
out=$1; shift
printf '<%s>\n' "$@" > "$out/args.txt"
pwd > "$out/pwd.txt"
printf '%s' "$VCAN_TEST_VAR" > "$out/env.txt"
ip -details link show vcan0 > "$out/vcan0.txt" 2>&1
candump -n 1 -T 5000 vcan0 > "$out/candump.txt" 2>&1 &
sleep 0.3
cansend vcan0 123#DEADBEEF
wait
if [ -x "$VCAN_TEST_ROOT/.venv/bin/python" ]; then
  timeout 60 "$VCAN_TEST_ROOT/.venv/bin/python" -c "
import can
with can.Bus(interface='socketcan', channel='vcan0', receive_own_messages=True) as b:
    b.send(can.Message(arbitration_id=0x123, data=[1, 2, 3], is_extended_id=False))
    m = b.recv(2)
    print(hex(m.arbitration_id), bytes(m.data).hex(), m.channel)
" > "$out/pycan.txt" 2>&1
fi
seq 1 100000
seq 100001 200000 >&2
exit 3
EOF
chmod +x "$D/inner.sh"
ARGS=('a b' "it's" '"dq"' '$HOME' '' $'two\nlines' '*' 'back\slash' '  lead')
export VCAN_TEST_VAR=$'x y "q" \'s\' $PATH `cmd` \\ \n end'
export VCAN_TEST_ROOT=$ROOT
t0=$(date +%s.%N)
(cd "$D" && "$VR" ./inner.sh "$T" "${ARGS[@]}" > "$T/A.out" 2> "$T/A.err")
rc=$?
tA=$(awk -v a="$t0" -v b="$(date +%s.%N)" 'BEGIN { printf "%.1f", b - a }')
ok "exit status 3 propagated" $((rc != 3)) "got $rc; stderr: $(head -c 600 "$T/A.err")"
cmp -s <(seq 1 100000) "$T/A.out"; ok "stdout: 100000 lines, byte-exact" $? "$(wc -c < "$T/A.out") bytes"
cmp -s <(seq 100001 200000) "$T/A.err"; ok "stderr: 100000 lines, byte-exact, apart from stdout" $? "$(wc -c < "$T/A.err") bytes"
cmp -s <(printf '<%s>\n' "${ARGS[@]}") "$T/args.txt"; ok "arguments with spaces, quotes, newline, glob" $? "$(cat "$T/args.txt" 2>/dev/null)"
[ "$(cat "$T/pwd.txt" 2>/dev/null)" = "$D" ]; ok "working directory (with spaces) preserved" $? "$(cat "$T/pwd.txt" 2>/dev/null)"
[ "$(cat "$T/env.txt" 2>/dev/null)" = "$VCAN_TEST_VAR" ]; ok "environment variable preserved" $? "$(cat "$T/env.txt" 2>/dev/null)"
grep -q 'vcan0: <.*UP' "$T/vcan0.txt" 2>/dev/null && grep -q '^ *vcan ' "$T/vcan0.txt"
ok "vcan0 is a vcan interface and up" $? "$(cat "$T/vcan0.txt" 2>/dev/null)"
grep -q 'vcan0  123   \[4\]  DE AD BE EF' "$T/candump.txt" 2>/dev/null
ok "cansend frame received by candump" $? "$(cat "$T/candump.txt" 2>/dev/null)"
if [ -x "$ROOT/.venv/bin/python" ]; then
  [ "$(cat "$T/pycan.txt" 2>/dev/null)" = "0x123 010203 vcan0" ]
  ok "python-can socketcan send/receive on vcan0" $? "$(cat "$T/pycan.txt" 2>/dev/null)"
else
  echo "skip python-can check: $ROOT/.venv missing (make deps)"
fi
leftovers; ok "nothing left behind (work dir, processes)" $?

# ---- boots B, C, D at once: exit 255, death by SIGKILL, exit 0.
"$VR" sh -c 'exit 255' > "$T/B.out" 2>&1 & pB=$!
"$VR" sh -c 'kill -KILL $$' > "$T/C.out" 2>&1 & pC=$!
t0=$(date +%s.%N)
"$VR" -v true > "$T/D.out" 2> "$T/D.err"; rcD=$?
tD=$(awk -v a="$t0" -v b="$(date +%s.%N)" 'BEGIN { printf "%.1f", b - a }')
{ wait $pB; } 2>/dev/null; rcB=$?
{ wait $pC; } 2>/dev/null; rcC=$?
ok "exit status 0 propagated (true)" "$rcD" "got $rcD; $(cat "$T/D.err")"
ok "exit status 255 propagated" $((rcB != 255)) "got $rcB; $(head -c 600 "$T/B.out")"
ok "death by SIGKILL gives 137" $((rcC != 137)) "got $rcC; $(head -c 600 "$T/C.out")"
[ ! -s "$T/D.out" ] && [ ! -s "$T/B.out" ] && [ ! -s "$T/C.out" ]
ok "no console or kernel messages in CMD's output" $? "$(head -c 300 "$T/D.out" "$T/B.out" "$T/C.out")"
leftovers; ok "nothing left behind after 3 concurrent sandboxes" $?

# ---- boot E: --timeout.
t0=$(date +%s.%N)
"$VR" --timeout 4 sh -c 'echo started; sleep 60; echo never' > "$T/E.out" 2> "$T/E.err"; rcE=$?
tE=$(awk -v a="$t0" -v b="$(date +%s.%N)" 'BEGIN { printf "%.1f", b - a }')
ok "--timeout: exit 124" $((rcE != 124)) "got $rcE; $(cat "$T/E.err")"
grep -q 'timeout' "$T/E.err"; ok "--timeout: says so on stderr" $? "$(cat "$T/E.err")"
[ "$(cat "$T/E.out")" = started ]; ok "--timeout: output before the kill delivered" $? "$(cat "$T/E.out")"
awk -v t="$tE" 'BEGIN { exit !(t < 8) }'; ok "--timeout: returns promptly (${tE} s for 4 s)" $?
leftovers; ok "--timeout: no linux.uml process or work dir left" $? "$(pgrep -af "$TMPDIR/vcan-run")"

# ---- clear failures, no boot.
out=$(CANFDI_VCAN=uml CANFDI_UML=/nonexistent/linux.uml "$VR" true 2>&1); rc=$?
[ $rc -eq 125 ] && grep -q 'make deps' <<<"$out" && grep -q 'User-Mode Linux' <<<"$out"
ok "missing UML kernel: exit 125, says what to install" $? "rc $rc: $out"
out=$(CANFDI_VCAN=host "$VR" true 2>&1); rc=$?
if [ $rc -eq 0 ]; then
  echo "skip CANFDI_VCAN=host failure check: this host kernel has vcan"
else
  [ $rc -eq 125 ] && grep -q 'CANFDI_VCAN=host' <<<"$out" && grep -q 'modprobe vcan' <<<"$out"
  ok "CANFDI_VCAN=host without vcan: exit 125 with the reason" $? "rc $rc: $out"
fi
out=$(CANFDI_VCAN=bogus "$VR" true 2>&1); rc=$?
[ $rc -eq 125 ]; ok "bad CANFDI_VCAN: exit 125" $? "rc $rc: $out"
out=$("$VR" 2>&1); rc=$?
[ $rc -eq 125 ] && grep -q 'no command' <<<"$out"; ok "no command: exit 125 with usage" $? "rc $rc: $out"
"$VR" --help | grep -q 'Exit status'; ok "--help" $?
leftovers; ok "nothing left behind at the end" $?

echo "vcan-run: timings: 'vcan-run -v true' ${tD} s ($(grep -o 'boot to CMD.*' "$T/D.err" 2>/dev/null || echo "host mode")); boot A ${tA} s"
echo "vcan-run: $pass passed, $fail failed"
[ "$fail" -eq 0 ]
