#!/usr/bin/env python3
"""tests/pil/pil_profile.py — where the instructions of canfdi_app_step go
on an emulated Cortex-M (`make bench-pil-profile`, mk/pil.mk).

Runs a PIL image (tests/pil/pil_step.c) on QEMU with the translation and
execution trace on (-d in_asm,exec,nochain: every translated block with its
instructions, every executed block by address) and counts, from the entry of
canfdi_app_step to the first block of the harness after it, the executed
instructions per function, per firmware module (the source file the
function is defined in, from the image's debug information) and per step.
The counts are the same instructions the PIL rig measures with SysTick
(tests/pil/run_pil.sh), split up; functions inlined into another count as
that one.

Prints the modules by mean instructions per step, the mean and the largest
step per slot of the rate schedule (the step number modulo 10 from the
first step), and the costliest steps split by module and by function;
--json writes the
same.

Usage: pil_profile.py --elf ELF --machine QEMU_MACHINE --run-dir DIR
                      [--json OUT] [--name NAME] [--top N]
DIR holds the log as pil.log (as run_pil.sh prepares it).
"""
import argparse
import bisect
import collections
import heapq
import json
import os
import re
import subprocess
import sys

SLOTS = 10


def symbols(elf):
    """[(start, size, name, module)] of the image's functions, sorted."""
    out = subprocess.run(["arm-none-eabi-nm", "-n", "-S", "-l", "--defined-only", elf],
                         capture_output=True, text=True, check=True).stdout
    syms = []
    for line in out.splitlines():
        parts = line.split(None, 4)
        if len(parts) < 4 or parts[2] not in "tTwW":
            continue
        start, size, name = int(parts[0], 16) & ~1, int(parts[1], 16), parts[3]
        where = parts[4] if len(parts) > 4 else ""
        path = where.rsplit(":", 1)[0] if where else ""
        module = "libc/libgcc"
        if "/firmware/" in path or path.startswith("firmware/"):
            module = "firmware/" + path.split("firmware/", 1)[1].rsplit(".", 1)[0]
        elif path.endswith("tests/pil/pil_step.c"):
            module = "harness"
        syms.append((start, size, name, module))
    syms.sort()
    return syms


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--elf", required=True)
    ap.add_argument("--machine", required=True, help="QEMU machine (mps2-an386, microbit, ...)")
    ap.add_argument("--run-dir", required=True, help="directory holding pil.log")
    ap.add_argument("--json", help="write the figures here (merged with what the file holds)")
    ap.add_argument("--name", default="", help="a name for this run in the JSON")
    ap.add_argument("--top", type=int, default=3, help="costliest steps to split up")
    ap.add_argument("--top-functions", type=int, default=20,
                    help="functions listed per costliest step (JSON; the output prints the first 8)")
    a = ap.parse_args()

    syms = symbols(a.elf)
    starts = [s[0] for s in syms]
    entry = next(s[0] for s in syms if s[2] == "canfdi_app_step")

    def where(addr):
        i = bisect.bisect_right(starts, addr) - 1
        if i >= 0 and addr < syms[i][0] + max(syms[i][1], 2):
            return syms[i][2], syms[i][3]
        return "?", "libc/libgcc"

    cmd = ["qemu-system-arm", "-M", a.machine, "-nographic", "-icount", "shift=6",
           "-semihosting-config", "enable=on,target=native", "-kernel", os.path.abspath(a.elf),
           "-d", "in_asm,exec,nochain", "-D", "/dev/stdout"]
    proc = subprocess.Popen(cmd, cwd=a.run_dir, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True,
                            bufsize=1 << 20)
    re_ins = re.compile(r"^0x([0-9a-f]+):")
    re_tr = re.compile(r"^Trace \d+: 0x[0-9a-f]+ \[[0-9a-f]+/([0-9a-f]+)/")
    tb = {}  # block start -> (instructions, function, module)
    pending = None
    in_step = False
    step = -1
    cur = collections.Counter()
    per_fn = collections.Counter()
    per_mod = collections.Counter()
    totals = []
    top = []

    def close_step():
        t = sum(cur.values())
        totals.append(t)
        mods = collections.Counter()
        fns = collections.Counter()
        for (f, m), n in cur.items():
            mods[m] += n
            fns[f] += n
            per_fn[f] += n
            per_mod[m] += n
        item = (t, step, dict(mods), dict(fns.most_common(a.top_functions)))
        if len(top) < a.top:
            heapq.heappush(top, item)
        elif t > top[0][0]:
            heapq.heapreplace(top, item)

    for line in proc.stdout:
        if line.startswith("Trace"):
            m = re_tr.match(line)
            if not m:
                continue
            pc = int(m.group(1), 16)
            info = tb.get(pc)
            if pc == entry:
                if in_step:
                    close_step()
                in_step = True
                step += 1
                cur = collections.Counter()
            elif in_step and info is not None and info[2] == "harness":
                close_step()
                in_step = False
            if in_step and info is not None:
                cur[(info[1], info[2])] += info[0]
        elif line.startswith("IN:"):
            pending = []
        elif pending is not None and line.startswith("0x"):
            m = re_ins.match(line)
            if m:
                pending.append(int(m.group(1), 16))
        elif pending and not line.strip():
            f, mod = where(pending[0])
            tb[pending[0]] = (len(pending), f, mod)
            pending = None
    proc.wait()
    if not totals:
        sys.exit("pil_profile: no canfdi_app_step ran (is pil.log in %s?)" % a.run_dir)

    n = len(totals)
    slot = collections.defaultdict(list)
    for k, t in enumerate(totals):
        slot[k % SLOTS].append(t)
    res = {
        "machine": a.machine, "elf": a.elf, "steps": n,
        "mean": round(sum(totals) / n), "max": max(totals), "max_step": totals.index(max(totals)),
        "modules": {m: round(v / n) for m, v in per_mod.most_common()},
        "functions": {f: round(v / n) for f, v in per_fn.most_common(40)},
        "slots": {str(s): {"mean": round(sum(v) / len(v)), "max": max(v)} for s, v in sorted(slot.items())},
        "costliest_steps": [{"step": k, "instructions": t, "modules": dict(sorted(mods.items(), key=lambda x: -x[1])),
                             "functions": fns}
                            for t, k, mods, fns in sorted(top, reverse=True)],
    }
    print(f"pil-profile: {a.name or a.run_dir} on {a.machine}: {n} steps, mean {res['mean']}, "
          f"max {res['max']} (step {res['max_step']})")
    print("  instructions per step by module (mean):")
    for m, v in list(res["modules"].items())[:25]:
        print(f"    {v:7d}  {m}")
    print("  per slot of the 10 ms frame (mean / max): " +
          "  ".join(f"{s}: {v['mean']}/{v['max']}" for s, v in res["slots"].items()))
    for c in res["costliest_steps"]:
        parts = ", ".join(f"{m.replace('firmware/', '')} {v}" for m, v in list(c["modules"].items())[:8])
        print(f"  step {c['step']} (slot {c['step'] % SLOTS}): {c['instructions']}: {parts}")
        fparts = ", ".join(f"{f} {v}" for f, v in list(c["functions"].items())[:8])
        print(f"    functions: {fparts}")
    if a.json:
        doc = {}
        if os.path.exists(a.json):
            with open(a.json) as f:
                doc = json.load(f)
        doc[(a.name or os.path.basename(a.run_dir.rstrip("/"))) + ":" + a.machine] = res
        with open(a.json, "w") as f:
            json.dump(doc, f, indent=1)


if __name__ == "__main__":
    main()
