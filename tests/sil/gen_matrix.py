#!/usr/bin/env python3
"""tests/sil/gen_matrix.py -- the SIL fault matrix: every catalogue fault in
every meaningful mode, each against its detection budget (docs/requirements.md).

    .venv/bin/python tests/sil/gen_matrix.py                 # write the scenarios
    .venv/bin/python tests/sil/gen_matrix.py --report build/bin/canfdi-sil
                                                            # + run them, write README

Reads dbc/faults.csv (ids, allowed modes, DTC, degradation) and dbc/dtcs.csv,
and writes tests/sil/matrix/<fault>_<mode>.scn for each fault x allowed mode
that no single-fault scenario in tests/sil/scenarios/ already covers. The
expectations come from the catalogue row and the budget classes below (the
budgets of docs/requirements.md); they are never fitted to an observed delay. A scenario the
firmware does not meet yet goes to tests/sil/matrix_pending/ with the SAME
expectations (PENDING below: one line of reason each, from what was observed).

--report BIN runs every generated scenario with its own seed and with --seed 2
and 3, and writes tests/sil/matrix/README.md (rules, results, pending list).
"""

import argparse
import csv
import math
import os
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
SIL = ROOT / "tests" / "sil"
OUT = SIL / "matrix"
OUT_PENDING = SIL / "matrix_pending"
EXISTING = SIL / "scenarios"

T0 = 3.0                    # fault start, s (as the existing scenarios)
RAMP = 2.0                  # incipient: default magnitude reached after 2 s
SEED_BASE = 300             # file seeds 300, 301, ... (scenarios/ use 21..124)
REPORT_SEEDS = (None, 2, 3)  # None = the file's seed

# ---------------------------------------------------------------------------
# Budget classes. budget = abrupt detection budget [s] after the injection
# (first testFailed/confirmed of every expected code). `inter` = intermittent
# shape (period s, duty): its on-phase is at least the budget, so the first
# on-phase alone is a fair test of the abrupt budget.
CLASSES = {
    "comm": dict(
        budget=0.007, inter=(1.0, 0.3),
        reason="requirement: communication faults within the debounce time + 3 frame "
               "cycles; canfdi_rx: timeout after 4 missed 1 ms cycles (direct DTC "
               "debounce); counter/CRC/length/implausible: the DTC's frame debouncer "
               "qualifies on the 3rd bad frame (threshold 6, step 2, canfdi_dtc.c) "
               "-> at most 4 + 3 = 7 ms"),
    "range": dict(
        budget=0.013, inter=(1.0, 0.3),
        reason="requirement: out-of-range faults within the debounce time + 3 frame "
               "cycles; TPS range flag persistence 10 ms (diagnosis flag_on) "
               "-> 10 + 3 = 13 ms"),
    "double_loss": dict(
        budget=0.013, inter=(1.0, 0.3), failsafe_within=0.200,
        reason="both TPS out of range: each code within the out-of-range budget "
               "(13 ms); requirement: limp-home (thr fail_safe) within 200 ms of a "
               "double sensor loss"),
    "offset": dict(
        budget=0.100, inter=(2.0, 0.5),
        reason="requirement: sensor offsets of 2 % of full scale within 100 ms (the "
               "DC-motor defaults are 0.8-1.7 % FS; the scenarios/ offsets at 1 % FS "
               "carry the same 100 ms); TPS abrupt written at 2 % FS (0.1 V)"),
    "gain": dict(
        budget=1.0, inter=(2.0, 0.5),
        reason="a sensor gain error is a relative change of the sensor's "
               "characteristic, not an offset: the parametric requirement, "
               "10-20 % changes within 1 s (as scenarios/dcm_speed_gain.scn)"),
    "parametric": dict(
        budget=1.0, inter=(2.0, 0.5),
        reason="requirement: parametric changes of 10-20 % within 1 s (the catalogue's "
               "default magnitudes are 10-100 %, i.e. at least as large)"),
    "bridge_a": dict(
        budget=0.010, inter=(1.0, 0.3),
        reason="requirement: switchover within 5 ms of detection; the manager detects a "
               "dead bridge from 3 consecutive samples + lag 1 (canfdi_actmgr.h): "
               "switch and P1A30 within 10 ms (as scenarios/bridge_a_dead.scn); "
               "switch time and speed dip read from the trace"),
    "bridges": dict(
        budget=0.020, inter=(1.0, 0.3),
        reason="A fails first (10 ms, switch to B), then B fails its own check "
               "(another 10 ms): P1A30 and P1A31 within 20 ms, drive off (as "
               "scenarios/bridges_dead.scn)"),
    "thr_actuator": dict(
        budget=0.500, inter=(2.0, 0.3),
        reason="no canfdi requirement for a dead or jammed throttle actuator; the "
               "production figure for throttle plausibility monitors "
               "(200-500 ms, docs/requirements.md), as scenarios/thr_motor_open.scn and "
               "thr_jammed.scn; intermittent on-phase 0.6 s >= the budget"),
}

FAULT_CLASS = {
    "dcm_ra_up": "parametric", "dcm_flux_down": "parametric",
    "dcm_friction_up": "parametric",
    "dcm_ia_sensor_offset": "offset", "dcm_speed_sensor_gain": "gain",
    "dcm_speed_sensor_offset": "offset", "dcm_ua_sensor_offset": "offset",
    "dcm_bridge_a_dead": "bridge_a", "dcm_bridges_dead": "bridges",
    "thr_tps1_open": "range", "thr_tps1_short": "range",
    "thr_tps2_open": "range", "thr_tps2_short": "range",
    "thr_tps1_drift": "offset", "thr_tps2_drift": "offset",
    "thr_spring_weak": "parametric", "thr_friction_up": "parametric",
    "thr_motor_r_up": "parametric",
    "thr_motor_open": "thr_actuator", "thr_jammed": "thr_actuator",
    "thr_tps_both_lost": "double_loss",
}
for _n in ("timeout", "counter", "crc", "length", "implausible"):
    FAULT_CLASS["com_dcm_" + _n] = "comm"
    FAULT_CLASS["com_thr_" + _n] = "comm"

# Codes expected besides the catalogue's dtc column, with the reason.
EXTRA_DTCS = {
    "dcm_bridges_dead": (["P1A30"], "the manager sees A fail first and switches "
                         "to B before B fails: P1A30 precedes P1A31 (as "
                         "scenarios/bridges_dead.scn)"),
}

# Magnitude other than the catalogue default, with the reason.
MAGNITUDE = {
    ("thr_tps2_drift", "abrupt"): (0.1, "2 % of the 5 V full scale: the offset "
                                   "requirement's size (mirrors scenarios/tps1_offset_2pct.scn)"),
}

# Mode semantics.
MODE_RULES = {
    "abrupt": "fully on at 3 s; every expected code within 3 s + the class budget; "
              "the catalogue's degradation of the faulty subsystem (the other one "
              "normal) at the end.",
    "incipient": "continuous faults only: the default magnitude is reached by a "
                 "linear ramp over 2 s (3..5 s). The default magnitude is the "
                 "catalogue's detectable level; it is crossed at the end of the "
                 "ramp, so the code is due by 3 s + 2 s + the class budget (an "
                 "upper bound: the firmware may see it earlier, at a smaller "
                 "magnitude). Degradation as abrupt at the end.",
    "intermittent": "on for `duty` of every `period` from 3 s. Binary and comm "
                    "faults: period 1 s, duty 0.3 (throttle actuator: 2 s, 0.3 so "
                    "that the 0.6 s on-phase covers the 500 ms budget). Continuous "
                    "faults: period 2 s, duty 0.5 -- a 1 s on-phase is as long as "
                    "the slowest class budget (parametric 1 s), so the estimators "
                    "and residual filters can settle within one on-phase (a shorter "
                    "on-phase than the budget would not test the budget), and the 1 s "
                    "off-phase lets them return to nominal before the next one. The code is due within the "
                    "class budget of the FIRST on-phase; the degradation is "
                    "checked at the end of every off-phase (50 ms before the next "
                    "on-phase): it must stay latched (degraded/fail_safe never "
                    "returns to normal without a clear), and stay normal for "
                    "parametric faults.",
}

COMMON = "every scenario also expects no code and both subsystems normal before " \
         "the fault (2.999 s / 2.95 s), and the rig fails any code no expect line names."

# Scenarios the firmware does not meet yet: name -> one-line reason (observed).
PENDING: dict[str, str] = {}

SETUP = """noise dcm_ua 0.05
noise dcm_ia 0.02
noise dcm_speed 0.2
noise thr_tps1 0.003
noise thr_tps2 0.003
noise thr_i 0.01
init dcm_winding 52.3
speed const 100
load const 1.2
angle const 25
angle sine 1 {dur:g} 8 0.5
"""


def read_csv(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def subsystem(row):
    if row["component"] == "dc_motor":
        return "dcm"
    if row["component"] == "throttle":
        return "thr"
    return {"DcmSensor": "dcm", "ThrSensor": "thr"}[row["quantity"]]


def covered_by_existing():
    """(fault, mode) -> file, from single-fault scenarios in scenarios/.
    The dtc_*.scn scenarios use a fault only as a tool to drive the
    trouble-code memory (status bits, cycles); they check no detection
    budget or degradation, so they cover nothing here."""
    cov = {}
    for p in sorted(EXISTING.glob("*.scn")):
        if p.name.startswith("dtc_"):
            continue
        faults = []
        for line in p.read_text().splitlines():
            w = line.split("#", 1)[0].split()
            if len(w) >= 4 and w[0] == "fault":
                faults.append((w[2], w[3]))
        if len(faults) == 1:
            cov.setdefault(faults[0], p.name)
    return cov


def fmt(t):
    return f"{t:.3f}"


def build(row, mode, seed):
    name = row["name"]
    cls_name = FAULT_CLASS[name]
    cls = CLASSES[cls_name]
    budget = cls["budget"]
    sub = subsystem(row)
    other = "thr" if sub == "dcm" else "dcm"
    deg = row["degradation"]
    codes = row["dtc"].split("+") + EXTRA_DTCS.get(name, ([], ""))[0]
    mag, _ = MAGNITUDE.get((name, mode), (float(row["default_magnitude"]), ""))
    mag_s = f"{mag:g}"

    deg_checks = []
    extra = []
    if mode == "abrupt":
        fault = f"fault {T0:g} {name} abrupt {mag_s}"
        due = T0 + budget
        dur = 6.0 if budget < 1.0 else 8.0
        deg_checks = [dur - 0.3]
        shape = f"abrupt {mag_s}"
    elif mode == "incipient":
        fault = f"fault {T0:g} {name} incipient {mag_s} {RAMP:g}"
        due = T0 + RAMP + budget
        dur = max(8.0, math.ceil(due) + 2.0)
        deg_checks = [dur - 0.3]
        shape = f"incipient {mag_s} over {RAMP:g} s"
    else:
        period, duty = cls["inter"]
        assert period * duty >= budget, name
        fault = f"fault {T0:g} {name} intermittent {mag_s} {period:g} {duty:g}"
        due = T0 + budget
        dur = 6.0 if period <= 1.0 else 8.0
        k = 1
        while T0 + k * period - 0.05 < dur:
            deg_checks.append(T0 + k * period - 0.05)
            k += 1
        shape = f"intermittent {mag_s}, period {period:g} s, duty {duty:g}"
    if "failsafe_within" in cls:
        extra.append(f"expect {fmt(T0 + cls['failsafe_within'])} degradation {sub} fail_safe"
                     f"   # limp-home within {cls['failsafe_within'] * 1000:.0f} ms")

    lines = [
        f"# {name}_{mode}.scn -- generated by tests/sil/gen_matrix.py; do not edit.",
        f"# {name} (id {row['id']}) {shape} at {T0:g} s: {'+'.join(codes)} by "
        f"{fmt(due)} s ({cls_name} budget {budget * 1000:g} ms"
        + (f" after the end of the {RAMP:g} s ramp" if mode == "incipient" else
           " of the first on-phase" if mode == "intermittent" else "")
        + f"), {sub} {deg}, {other} normal.",
        f"duration {dur:g}",
        f"seed {seed}",
        SETUP.format(dur=dur).rstrip("\n"),
        fault,
        f"expect {fmt(T0 - 0.001)} no_dtc",
        f"expect {fmt(T0 - 0.05)} degradation dcm normal",
        f"expect {fmt(T0 - 0.05)} degradation thr normal",
    ]
    lines += [f"expect {fmt(due)} dtc {c}" for c in codes]
    lines += extra
    for t in deg_checks:
        lines.append(f"expect {fmt(t)} degradation {sub} {deg}")
        lines.append(f"expect {fmt(t)} degradation {other} normal")
    return dict(name=name, mode=mode, cls=cls_name, codes=codes, due=due,
                budget=budget, sub=sub, deg=deg, text="\n".join(lines) + "\n",
                key=f"{name}_{mode}")


def generate():
    faults = [r for r in read_csv(ROOT / "dbc" / "faults.csv") if r["name"] != "none"]
    dtcs = {r["code"] for r in read_csv(ROOT / "dbc" / "dtcs.csv")}
    cov = covered_by_existing()
    for d in (OUT, OUT_PENDING):
        d.mkdir(exist_ok=True)
        for p in d.glob("*.scn"):
            p.unlink()
    out, covered = [], []
    seed = SEED_BASE
    for row in faults:
        assert row["name"] in FAULT_CLASS, f"no budget class for {row['name']}"
        for mode in row["modes"].split("|"):
            if (row["name"], mode) in cov:
                covered.append((row["name"], mode, cov[(row["name"], mode)]))
                continue
            s = build(row, mode, seed)
            seed += 1
            for c in s["codes"]:
                assert c in dtcs, f"{c} not in dtcs.csv"
            s["pending"] = s["key"] in PENDING
            s["path"] = (OUT_PENDING if s["pending"] else OUT) / (s["key"] + ".scn")
            s["path"].write_text(s["text"])
            out.append(s)
    unknown = set(PENDING) - {s["key"] for s in out}
    assert not unknown, f"PENDING names no generated scenario: {unknown}"
    return out, covered


# ---------------------------------------------------------------------------
PASS_DTC = re.compile(r"^(PASS|FAIL)\s+\S+: dtc (\S+) .* at ([\d.]+) s \((\d+) ms after")
UNEXP = re.compile(r"^FAIL\s+\S+: unexpected trouble code (\S+) at ([\d.]+) s")


def run_one(bin_, path, seed, trace=None):
    cmd = [bin_, "-q", "-s", str(path)]
    if seed is not None:
        cmd += ["--seed", str(seed)]
    if trace:
        cmd += ["-o", trace]
    for attempt in range(30):  # the binary may be relinked under us: wait
        try:
            p = subprocess.run(cmd, capture_output=True, text=True)
            if p.returncode != 2 or attempt >= 2:
                return p.returncode, p.stdout + p.stderr
        except OSError:
            if attempt == 29:
                raise
        time.sleep(2.0)
    return p.returncode, p.stdout + p.stderr


def trace_figures(bin_, s, seed):
    """Bridge switch time and speed dip / limp-home time, from the trace."""
    if s["cls"] not in ("bridge_a", "bridges", "double_loss"):
        return ""
    with tempfile.TemporaryDirectory() as td:
        tr = os.path.join(td, "t.csv")
        run_one(bin_, s["path"], seed, tr)
        with open(tr, newline="") as f:
            rows = list(csv.DictReader(f))
    after = [r for r in rows if float(r["t_s"]) >= T0 - 1e-9]
    if s["cls"] == "double_loss":
        off = next((float(r["t_s"]) for r in after if r["thr_enable"] == "0"), None)
        return f"motor off {1000 * (off - T0):.0f} ms" if off is not None else "motor never off"
    t = [float(r["t_s"]) for r in after]
    br = [r["bridge"] for r in after]
    sw = next((t[i] for i in range(len(t)) if br[i] != br[0]), None)
    txt = f"A->B {1000 * (sw - T0):.0f} ms" if sw is not None else "no switch"
    if s["cls"] == "bridges":
        off = next((t[i] for i in range(len(t)) if br[i] == "0"), None)
        return txt + (f", drive off {1000 * (off - T0):.0f} ms" if off is not None else ", never off")
    # speed dip: speed at the injection minus its minimum over the next 50 ms
    # (the ECU's +-5 rad/s PRBS speed excitation stays on)
    v = [float(r["speed"]) for r in after if float(r["t_s"]) <= T0 + 0.05]
    return txt + f", speed dip {v[0] - min(v):.1f} rad/s"


def report(bin_, scns, covered):
    results = {}
    t_start = time.monotonic()
    for s in scns:
        runs = []
        for seed in REPORT_SEEDS:
            rc, txt = run_one(bin_, s["path"], seed)
            delays = {}
            fails = []
            for line in txt.splitlines():
                m = PASS_DTC.match(line)
                if m:
                    delays.setdefault(m.group(2), []).append(int(m.group(4)))
                if line.startswith("FAIL "):
                    fails.append(line.split(": ", 1)[1] if ": " in line else line)
            runs.append(dict(seed=seed, rc=rc, delays=delays, fails=fails,
                             fig=trace_figures(bin_, s, seed)))
        results[s["key"]] = runs
    wall = time.monotonic() - t_start
    return results, wall


def fmt_delays(runs, codes):
    parts = []
    for c in codes:
        ds = [d for r in runs for d in r["delays"].get(c, [])]
        if ds:
            parts.append(f"{c} {min(ds)}-{max(ds)} ms" if min(ds) != max(ds)
                         else f"{c} {ds[0]} ms")
        else:
            parts.append(f"{c} -")
    return ", ".join(parts)


def write_readme(scns, covered, results, wall, single_wall):
    L = ["# tests/sil/matrix -- the SIL fault matrix (generated)", "",
         "Generated by `tests/sil/gen_matrix.py` from `dbc/faults.csv` and "
         "`dbc/dtcs.csv`; do not edit the `.scn` files or this README by hand:",
         "", "```",
         ".venv/bin/python tests/sil/gen_matrix.py                 # scenarios only",
         ".venv/bin/python tests/sil/gen_matrix.py --report build/bin/canfdi-sil  # + run, README",
         "bash tests/sil/run_scenarios.sh build/bin/canfdi-sil tests/sil/matrix/*.scn",
         "bash tests/sil/run_scenarios.sh build/bin/canfdi-sil tests/sil/matrix_pending/*.scn",
         "```", "",
         "One scenario per catalogue fault x allowed mode that no single-fault "
         "scenario in `tests/sil/scenarios/` covers (those are listed at the end). "
         "Setup as `scenarios/dcm_flux_down.scn`: sensor noise, warm winding "
         "(52.3 C), speed 100 rad/s, load 1.2 N m, angle 25 deg + 8 deg 0.5 Hz sine; "
         "fault at 3 s; magnitude = the catalogue default unless noted.", "",
         "## Budget rules", "",
         "| class | abrupt budget | faults | why |", "|---|---|---|---|"]
    for cn, c in CLASSES.items():
        fs = ", ".join(f for f, k in FAULT_CLASS.items() if k == cn)
        L.append(f"| {cn} | {c['budget'] * 1000:g} ms | {fs} | {c['reason']} |")
    L += ["", "Modes:", ""]
    for m, r in MODE_RULES.items():
        L.append(f"- **{m}**: {r}")
    L.append(f"- {COMMON[0].upper() + COMMON[1:]}")
    for n, (codes, why) in EXTRA_DTCS.items():
        L.append(f"- {n} also expects {', '.join(codes)}: {why}.")
    for (n, m), (v, why) in MAGNITUDE.items():
        L.append(f"- {n} {m}: magnitude {v:g}: {why}.")
    L += ["", "## Results", "",
          f"SIL, default calibration; seeds: the file's and {', '.join(str(s) for s in REPORT_SEEDS if s)}. "
          "Delay = first testFailed/confirmed after the injection (min-max over the seeds); "
          "due = the expectation's deadline after 3 s.", "",
          "| scenario | class | expected codes: delay | due | degradation | verdict (file, 2, 3) |",
          "|---|---|---|---|---|---|"]
    for s in scns:
        runs = results[s["key"]]
        verdict = " ".join("pass" if r["rc"] == 0 else "FAIL" for r in runs)
        figs = "; ".join(sorted({r["fig"] for r in runs if r["fig"]}))
        deg = f"{s['sub']} {s['deg']}" + (f" ({figs})" if figs else "")
        where = "matrix_pending/" if s["pending"] else ""
        L.append(f"| {where}{s['key']} | {s['cls']} | {fmt_delays(runs, s['codes'])} | "
                 f"{1000 * (s['due'] - T0):g} ms | {deg} | {verdict} |")
    n_pass = sum(1 for s in scns if not s["pending"])
    n_ok = sum(1 for s in scns if not s["pending"] and all(r["rc"] == 0 for r in results[s["key"]]))
    L += ["", f"{len(scns)} generated: {n_pass} in `matrix/` ({n_ok} pass with all three seeds), "
          f"{len(scns) - n_pass} in `matrix_pending/`. Wall time of `run_scenarios.sh` over "
          f"`matrix/*.scn` (one seed): {single_wall:.1f} s; this report (3 seeds, traces): {wall:.1f} s.",
          "", "## Pending (expectations unchanged; the firmware does not meet them yet)", ""]
    if not PENDING:
        L.append("None.")
    for k, why in PENDING.items():
        runs = results.get(k, [])
        L.append(f"- `{k}`: {why}")
        for r in runs:
            if r["fails"]:
                L.append(f"  - seed {r['seed'] or 'of the file'}: " + "; ".join(r["fails"]))
    L += ["", "## Covered by tests/sil/scenarios/ (not generated)", ""]
    for n, m, f in covered:
        L.append(f"- {n} {m}: `scenarios/{f}`")
    (OUT / "README.md").write_text("\n".join(L) + "\n")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--report", metavar="BIN", help="run the scenarios with BIN, write README.md")
    a = ap.parse_args()
    scns, covered = generate()
    print(f"gen_matrix: {len(scns)} scenarios "
          f"({sum(not s['pending'] for s in scns)} matrix/, "
          f"{sum(s['pending'] for s in scns)} matrix_pending/), "
          f"{len(covered)} fault x mode covered by scenarios/")
    if not a.report:
        return 0
    t = time.monotonic()
    subprocess.run(["bash", str(SIL / "run_scenarios.sh"), a.report]
                   + [str(s["path"]) for s in scns if not s["pending"]],
                   capture_output=True, text=True)
    single_wall = time.monotonic() - t
    results, wall = report(a.report, scns, covered)
    write_readme(scns, covered, results, wall, single_wall)
    bad = [s["key"] for s in scns if not s["pending"]
           and any(r["rc"] != 0 for r in results[s["key"]])]
    print(f"gen_matrix: report written; {len(bad)} non-pending scenario(s) failing"
          + (": " + ", ".join(bad) if bad else ""))
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
