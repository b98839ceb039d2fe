#!/usr/bin/env python3
"""The step's cost on hostile input (`make pil-cost`, mk/pil.mk).

fuzz_app_rx's inputs (the directories given, plus at most --found-max files
of --found, the inputs `make fuzz` / fuzz-test found) are written out by the
harness itself as one log (tests/fuzz/fuzz_export.h: every frame it feeds,
every step, a reset before each input); each machine's PIL_COST image
(tests/pil/pil_step.c) runs that log on QEMU and counts the executed
instructions of every canfdi_app_step. A machine passes when its image ran
every step of the log and no step cost more than the machine's bound (the
stated worst case of firmware/app/canfdi_app.h).

Prints one line per machine; writes --json; exits 1 when a machine fails,
2 when the check cannot run.
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
from pathlib import Path

STEP_MARK = "FFFFFFFF#"
RESET_MARK = "FFFFFFFE#"


def files_of(d: Path) -> list[Path]:
    return sorted(p for p in d.iterdir() if p.is_file() and not p.name.startswith(".")) if d.is_dir() else []


def parse_pil(out: str) -> dict[str, int]:
    """The image's 'pil: steps ...' and 'pil: cost_inputs ...' lines as numbers."""
    r: dict[str, int] = {}
    for line in out.splitlines():
        w = line.split()
        if line.startswith("pil: steps") or line.startswith("pil: cost_inputs"):
            for k, v in zip(w[1::2], w[2::2]):
                try:
                    r[k] = int(v)
                except ValueError:
                    pass
    return r


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--export", required=True, help="the fuzz_app_rx export tool (fuzz-export-app-rx)")
    ap.add_argument("--work", required=True, type=Path, help="working directory (the log goes there)")
    ap.add_argument("--json", required=True, type=Path, help="figures out")
    ap.add_argument("--found", type=Path, help="directory of inputs the fuzzer found (optional)")
    ap.add_argument("--found-max", type=int, default=300, help="at most this many of them (name order)")
    ap.add_argument("--machine", action="append", default=[], required=True,
                    help="NAME:QEMU_MACHINE:CORE:ELF:BOUND (instructions per step)")
    ap.add_argument("--timeout", type=int, default=600, help="seconds per QEMU run")
    ap.add_argument("inputs", nargs="+", type=Path, help="input directories (corpus, regressions)")
    a = ap.parse_args()

    inputs: list[Path] = []
    sources: dict[str, int] = {}
    for d in a.inputs:
        fs = files_of(d)
        inputs += fs
        sources[str(d)] = len(fs)
    if a.found is not None:
        fs = files_of(a.found)[:max(0, a.found_max)]
        inputs += fs
        sources[str(a.found)] = len(fs)
    if not inputs:
        print("pil-cost: no inputs", file=sys.stderr)
        return 2
    a.work.mkdir(parents=True, exist_ok=True)
    log = a.work / "pil.log"
    r = subprocess.run([a.export, str(log)] + [str(p) for p in inputs], capture_output=True, text=True)
    if r.returncode != 0:
        print(f"pil-cost: the export failed (rc {r.returncode}): {r.stderr.strip()[-500:]}", file=sys.stderr)
        return 2
    steps = resets = 0
    with open(log) as f:
        for line in f:
            if line.endswith(STEP_MARK + "\n"):
                steps += 1
            elif line.endswith(RESET_MARK + "\n"):
                resets += 1
    if resets != len(inputs):
        print(f"pil-cost: the log holds {resets} inputs of {len(inputs)}", file=sys.stderr)
        return 2

    failed = 0
    results = []
    for spec in a.machine:
        name, qemu_m, core, elf, bound_s = spec.split(":")
        bound = int(bound_s)
        cmd = ["timeout", str(a.timeout), "qemu-system-arm", "-M", qemu_m, "-nographic", "-icount", "shift=6",
               "-semihosting-config", "enable=on,target=native", "-kernel", os.path.abspath(elf)]
        p = subprocess.run(cmd, cwd=a.work, capture_output=True, text=True)
        v = parse_pil(p.stdout)
        problems = []
        if p.returncode != 0:
            problems.append("the image did not end within the timeout" if p.returncode == 124
                            else f"the image ended with rc {p.returncode}: {p.stdout.strip()[-200:]}")
        if v.get("steps") != steps:
            problems.append(f"{v.get('steps')} steps run of the log's {steps}")
        if v.get("cost_inputs") != len(inputs):
            problems.append(f"{v.get('cost_inputs')} inputs run of {len(inputs)}")
        if v.get("differ", 0) != 0:
            problems.append(f"{v.get('differ')} steps returned an error")
        mx = v.get("max")
        if mx is None or mx > bound:
            worst = inputs[v["max_input"]] if "max_input" in v and v["max_input"] < len(inputs) else None
            problems.append(f"a step cost {mx} instructions, over the stated {bound}"
                            + (f" (input {worst})" if worst else ""))
        ok = not problems
        failed += not ok
        res = {"machine": name, "core": core, "qemu": qemu_m, "inputs": len(inputs), "steps": v.get("steps"),
               "min": v.get("min"), "mean": v.get("mean"), "max": mx, "bound": bound,
               "max_input": str(inputs[v["max_input"]]) if "max_input" in v and v["max_input"] < len(inputs)
               else None, "ok": ok, "problems": problems}
        results.append(res)
        if ok:
            print(f"pil-cost: pass {name} ({core}): {len(inputs)} hostile inputs, {steps} steps: instructions "
                  f"per step min {v['min']} mean {v['mean']} max {mx} <= stated {bound} "
                  f"({100.0 * mx / bound:.0f} %)")
        else:
            print(f"pil-cost: FAIL {name} ({core}): " + "; ".join(problems))
    a.json.parent.mkdir(parents=True, exist_ok=True)
    a.json.write_text(json.dumps({"sources": sources, "steps": steps, "machines": results}, indent=1) + "\n")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
