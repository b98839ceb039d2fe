#!/usr/bin/env python3
"""Foundation bench: cost per call of the detectors and fixed-point ops.

Runs the harness (bench/bench_foundation.c, built -O2 without sanitizers)
under valgrind's callgrind, reads the call graph, and reports for each
measured function the inclusive instruction count (Ir) per call, summed over
every call site: Ir(calls) / number of calls. Host x86-64 instructions are a
portable, noise-free proxy for relative cost, not Cortex-M cycles.

Also reads the per-module code size of the cross-compiled objects
($(BUILD)/target/<core>/obj/firmware/**.o) and the guard images, if built.

Writes the figures to --out (JSON) and prints a table. A figure never fails
the run; only a harness or valgrind that cannot run does (exit 1).
"""
from __future__ import annotations

import argparse
import json
import re
import subprocess
import sys
from pathlib import Path

# (label, function) measured per call; the harness calls each N times.
DETECTORS = [
    ("limit", "canfdi_limit_step"),
    ("trend", "canfdi_trend_step"),
    ("adapt", "canfdi_adapt_step"),
    ("debounce", "canfdi_debounce_step"),
    ("meanvar", "canfdi_meanvar_step"),
    ("cusum", "canfdi_cusum_step"),
]
# Inline ops are measured through a noinline wrapper (bench_*): the figure
# includes a call, a return and the argument loads (~5 Ir).
FIXP = [
    ("q31_mul_rnd (inline)", "bench_q31_mul_rnd"),
    ("mul_s64_q31 (inline)", "bench_mul_s64_q31"),
    ("q15_div", "canfdi_q15_div"),
    ("q31_div", "canfdi_q31_div"),
    ("div_s32_qn", "canfdi_div_s32_qn"),
    ("isqrt_u32", "canfdi_isqrt_u32"),
    ("isqrt_u64", "canfdi_isqrt_u64"),
    ("q31_sqrt", "canfdi_q31_sqrt"),
]


def parse_callgrind(path: Path, caller_file: str) -> dict[str, list[int]]:
    """Map callee name -> [calls, inclusive Ir of those calls].

    Only calls made from functions of `caller_file` (the harness) count, so
    that e.g. canfdi_debounce_step called inside canfdi_limit_step is not
    averaged into the debounce figure. Expects an uncompressed file
    (--compress-strings=no --compress-pos=no): a `calls=<n> <target>` line is
    followed by `<position> <Ir>`, the inclusive cost of those calls.
    """
    edges: dict[str, list[int]] = {}
    fl = ""
    fn_file = ""
    callee = None
    pending = 0
    expect_cost = False
    with path.open(encoding="utf-8", errors="replace") as fh:
        for line in fh:
            if expect_cost:
                parts = line.split()
                ir = int(parts[1]) if len(parts) > 1 else 0
                if fn_file.endswith(caller_file):
                    # Callgrind suffixes recursion levels ("'2"); merge them.
                    name = re.sub(r"'\d+$", "", callee or "?")
                    acc = edges.setdefault(name, [0, 0])
                    acc[0] += pending
                    acc[1] += ir
                expect_cost = False
            elif line.startswith("fl="):
                fl = line[3:].strip()
            elif line.startswith("fn="):
                fn_file = fl
            elif line.startswith("cfn="):
                callee = line[4:].strip()
            elif line.startswith("calls="):
                pending = int(line[6:].split()[0])
                expect_cost = True
    return edges


def measure(exe: Path, out_dir: Path) -> dict[str, list[int]]:
    cg = out_dir / "callgrind.foundation.out"
    cmd = [
        "valgrind", "--tool=callgrind", f"--callgrind-out-file={cg}",
        "--compress-strings=no", "--compress-pos=no", str(exe),
    ]
    res = subprocess.run(cmd, capture_output=True, text=True, check=False)
    if res.returncode != 0:
        sys.stderr.write(res.stdout + res.stderr)
        raise SystemExit(f"bench: {' '.join(cmd)} failed ({res.returncode})")
    print(res.stdout.strip())
    return parse_callgrind(cg, "bench/bench_foundation.c")


def arm_size(files: list[Path], tool: str) -> dict[str, dict[str, int]]:
    """Berkeley sizes (text incl. rodata, data, bss) per file."""
    if not files:
        return {}
    res = subprocess.run([tool, *map(str, files)], capture_output=True, text=True, check=False)
    sizes: dict[str, dict[str, int]] = {}
    for line in res.stdout.splitlines()[1:]:
        parts = line.split()
        if len(parts) >= 6 and parts[0].isdigit():
            sizes[parts[5]] = {"text": int(parts[0]), "data": int(parts[1]), "bss": int(parts[2])}
    return sizes


def module_sizes(target_dir: Path, tool: str) -> dict[str, dict[str, dict[str, int]]]:
    out: dict[str, dict[str, dict[str, int]]] = {}
    if not target_dir.is_dir():
        return out
    for core_dir in sorted(p for p in target_dir.iterdir() if p.is_dir()):
        fw = core_dir / "obj" / "firmware"
        objs = sorted(fw.rglob("*.o")) if fw.is_dir() else []
        per = {}
        for path, s in arm_size(objs, tool).items():
            per[str(Path(path).relative_to(fw).with_suffix(""))] = s
        elf = core_dir / "canfdi.elf"
        if elf.is_file():
            per.update({"(guard image)": s for s in arm_size([elf], tool).values()})
        if per:
            out[core_dir.name] = per
    return out


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--exe", type=Path, required=True, help="bench harness")
    ap.add_argument("--out", type=Path, required=True, help="JSON to write")
    ap.add_argument("--target-dir", type=Path, default=Path("build/target"))
    ap.add_argument("--size-tool", default="arm-none-eabi-size")
    args = ap.parse_args()
    args.out.parent.mkdir(parents=True, exist_ok=True)

    edges = measure(args.exe, args.out.parent)

    def table(entries: list[tuple[str, str]]) -> dict[str, dict[str, object]]:
        res: dict[str, dict[str, object]] = {}
        for label, fn in entries:
            calls, ir = edges.get(fn, [0, 0])
            res[label] = {
                "function": fn,
                "calls": calls,
                "ir_per_call": round(ir / calls, 1) if calls else None,
            }
        return res

    report = {
        "what": "mean host instructions (callgrind Ir, inclusive) per call, "
                "x86-64 gcc -O2, on a seeded noisy 1 kHz signal with steps, "
                "a drift and spikes (bench/bench_foundation.c)",
        "note": "inclusive of callees: limit includes its debouncer, trend its "
                "limit check and debouncer; cusum runs on an in-control residual "
                "with short shifts; inline fixp ops include a call and return",
        "detectors": table(DETECTORS),
        "fixp": table(FIXP),
        "target_code_size_bytes": module_sizes(args.target_dir, args.size_tool),
    }
    args.out.write_text(json.dumps(report, indent=2) + "\n", encoding="utf-8")

    print(f"== foundation bench: {report['what']}")
    print(f"   ({report['note']})")
    for title in ("detectors", "fixp"):
        print(f"  {title}:")
        for label, r in report[title].items():
            ir = r["ir_per_call"]
            fig = f"{ir:10.1f} Ir/call" if ir is not None else "  (not measured: module absent)"
            print(f"    {label:22s} {fig}   {r['function']} x{r['calls']}")
    sizes = report["target_code_size_bytes"]
    if sizes:
        print("  Cortex-M code size per module, bytes (text / data / bss; objects "
              "before --gc-sections):")
        cores = list(sizes)
        names = sorted({m for c in cores for m in sizes[c]})
        print("    " + f"{'module':28s}" + "".join(f"{c:>22s}" for c in cores))
        for m in names:
            cells = []
            for c in cores:
                s = sizes[c].get(m)
                cells.append(f"{s['text']:>10d} /{s['data']:>4d} /{s['bss']:>4d}" if s else f"{'-':>22s}")
            print("    " + f"{m:28s}" + "".join(f"{x:>22s}" for x in cells))
    else:
        print("  (no Cortex-M objects: run `make firmware` for code sizes)")
    print(f"  written: {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
