#!/usr/bin/env python3
"""tests/pil/pil_report.py — writes the PIL rig's JSON ($(BUILD)/bench/pil.json).

--steps: the per-(scenario, machine) results of tests/pil/run_pil.sh
(instructions per canfdi_app_step: min, mean, max and the step of the max;
frames that differ from the host build). --rls: the RLS bench's lines
(bench/bench_rls_pil.c). A section whose input is empty keeps what the file
already holds, so `make pil-test` and `make bench-pil` can share the file.
Prints the RLS figures side by side with their ratios (from the same run).
"""
import argparse
import json
import os


def read_tsv(path):
    if not path or not os.path.exists(path):
        return []
    with open(path) as f:
        return [line.rstrip("\n").split("\t") for line in f if line.strip()]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--steps")
    ap.add_argument("--rls")
    ap.add_argument("--out", required=True)
    a = ap.parse_args()
    doc = {}
    if os.path.exists(a.out):
        try:
            with open(a.out) as f:
                doc = json.load(f)
        except ValueError:
            doc = {}
    steps = read_tsv(a.steps)
    if steps:
        doc["steps"] = [
            {"scenario": r[0], "machine": r[1], "core": r[2], "qemu": r[3], "steps": int(r[4]),
             "instructions_min": int(r[5]), "instructions_mean": int(r[6]), "instructions_max": int(r[7]),
             "max_step": int(r[8]), "frames_differ": int(r[9]), "first_differing_step": int(r[10])}
            for r in steps]
        doc["steps_note"] = ("executed instructions per canfdi_app_step (QEMU -icount shift=6, SysTick), "
                             "arm-none-eabi-gcc -Os; frames_differ: steps whose ECU frames differ from "
                             "the host SIL run")
    rls = read_tsv(a.rls)
    if rls:
        rows = [{"impl": r[0], "machine": r[1], "qemu": r[2], "calls": int(r[3]), "instructions_min": int(r[4]),
                 "instructions_mean": int(r[5]), "instructions_max": int(r[6])} for r in rls]
        by = {(r["impl"], r["machine"]): r for r in rows}
        ref = by.get(("fixed", "m3"))
        ratios = {}
        if ref:
            for key, r in by.items():
                ratios["%s_%s_over_fixed_m3" % key] = round(r["instructions_mean"] / ref["instructions_mean"], 2)
        doc["rls_update_n4"] = {"runs": rows, "ratios_mean": ratios,
                                "note": "canfdi_rls_update n = 4 (fixed) vs the textbook covariance RLS "
                                        "(float, double; m4f: Cortex-M4 FPU, single precision), 2000 calls, "
                                        "bench/bench_rls_pil.c"}
        print("rls n=4, instructions per update (mean / max), ratio of means to fixed on M3:")
        for r in rows:
            print("  %-7s %-4s %7d / %7d   x%.2f" % (r["impl"], r["machine"], r["instructions_mean"],
                                                  r["instructions_max"],
                                                  r["instructions_mean"] / ref["instructions_mean"] if ref else 0))
    with open(a.out, "w") as f:
        json.dump(doc, f, indent=1)
        f.write("\n")
    print("pil: wrote %s" % a.out)


if __name__ == "__main__":
    main()
