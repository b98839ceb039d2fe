#!/usr/bin/env python3
"""tests/sil/gen_envelope.py -- the envelope fault matrix: every catalogue fault
in every allowed mode at a grid of operating points that spans the envelope
(docs/envelope.md), judged against the observability table dbc/observability.csv.

    .venv/bin/python tests/sil/gen_envelope.py            # write the sampled set
                                                         # (tests/sil/envelope/, _pending/)
    .venv/bin/python tests/sil/gen_envelope.py --grid     # the grid: each point's steady
                                                         # state and observability classes
    .venv/bin/python tests/sil/gen_envelope.py --bench build/bench/canfdi-sil-rel \\
        --out build/bench/envelope.json --png build/bench/envelope_confusion.png \\
        --jobs 2 --seeds 3                               # the full matrix (make bench-envelope)

Grid. DC-motor faults run over the DC-motor points (POINTS_DCM) with the
throttle at its nominal point; throttle faults over the throttle points
(POINTS_THR) with the motor nominal; communication faults at two points of
their subsystem. Each run: the fault-free lead-in to T0 = 3 s, then the
fault at its catalogue default magnitude in one allowed mode, shaped as
tests/sil/gen_matrix.py shapes it (its CLASSES budgets, FAULT_CLASS,
EXTRA_DTCS, ramp and intermittent period/duty are imported, not copied).

Observability class of a run (tests/sil/oppoint.py, dbc/observability.csv):
the point's quantities are evaluated every 10 ms while the fault is on
(incipient: from the end of its ramp; intermittent: in its on-phases);
`isolable` if the isolable_if condition holds without a break for at least
the fault's detection budget, else `observable` if observable_if does, else
`not_observable`.

Verdict of a run, from the runner's timeline (testFailed/confirmed lines;
expect lines are not used):
  wrong_code    a code named after the injection that is neither the fault's
                own (dbc/faults.csv dtc + EXTRA_DTCS) nor tolerated for it
                (observability.csv) -- the firmware must never do this;
  false_alarm   a code named before the injection, or any code in the
                fault-free run each point also gets (fault `none`);
  correct       the fault's own code named (delay: its first report);
  not_isolated  only tolerated codes named (e.g. P2135);
  missed        class isolable, none of the fault's codes named in the run;
  not_tested    class observable or not_observable and nothing named.
(first matching line wins.) `late` marks a correct run whose delay exceeds
the class budget (after the ramp for incipient faults).

Sampled set (make sil-envelope, part of make test): for every catalogue
fault one abrupt run at an isolable point other than the nominal one
(expect: its codes by T0 + budget, nothing before) and, where the grid has
one, one at a point where it is not observable (expect: no code at all).
Scenarios the firmware does not meet yet go to tests/sil/envelope_pending/
with the same expectations (PENDING below: one line of reason each, from
what was observed).
"""

import argparse
import concurrent.futures as cf
import json
import math
import os
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
SIL = ROOT / "tests" / "sil"
sys.path.insert(0, str(SIL))
sys.path.insert(0, str(ROOT / "bench"))
import gen_matrix as gm  # noqa: E402  budgets, classes, expected codes, mode shapes
import oppoint as op  # noqa: E402  steady state and observability
from bench_detection import DTC_LINE, DEG_LINE  # noqa: E402  the runner's timeline

OUT = SIL / "envelope"
OUT_PENDING = SIL / "envelope_pending"
T0 = gm.T0
RAMP = gm.RAMP
DT = 0.01                 # evaluation step of the observability conditions, s
MOTION_WINDOW = 2.0       # the throttle's mechanical evidence counts as present when
                          # this window holds the fast test's memory of motion, s
SEED_BASE = 600           # file seeds of the sampled set (matrix uses 300..)
BENCH_SEED_BASE = 1000    # file seeds of the bench's scenarios

NOISE = """noise dcm_ua 0.05
noise dcm_ia 0.02
noise dcm_speed 0.2
noise thr_tps1 0.003
noise thr_tps2 0.003
noise thr_i 0.01
init dcm_winding 52.3"""

# Operating points. `lines` are scenario directives of the point's subsystem
# ({dur} is the run's duration); `min_dur` a duration the point needs.
DCM_NOMINAL = ["speed const 100", "load const 1.2"]
THR_NOMINAL = ["angle const 25", "angle sine 1 {dur} 8 0.5"]
POINTS_DCM = {
    "fwd_motor": dict(lines=DCM_NOMINAL, nominal=True,
                      what="forward motoring, 100 rad/s, +1.2 N m (the nominal point)"),
    "rev_motor": dict(lines=["speed const -100", "load const -1.2"],
                      what="reverse motoring, -100 rad/s, -1.2 N m"),
    "fwd_brake": dict(lines=["speed const 100", "load const -1.2"],
                      what="forward braking, 100 rad/s, load -1.2 N m drives the motor"),
    "rev_brake": dict(lines=["speed const -100", "load const 1.2"],
                      what="reverse braking, -100 rad/s, load +1.2 N m"),
    "standstill": dict(lines=["speed const 0", "load const 0"],
                       what="standstill, no load (no test signal below 20 rad/s)"),
    "reversing": dict(lines=["speed sine 0 {dur} 60 0.1", "load const 1.2"], min_dur=12.0,
                      what="slow reversing sine 60 rad/s at 0.1 Hz through zero, +1.2 N m (all quadrants)"),
    "low_speed_high_load": dict(lines=["speed const 20", "load const 2.1"],
                                what="20 rad/s, 2.1 N m: 6.7 A, near the 6.9 A continuous rating"),
    "high_speed": dict(lines=["speed const 130", "load const 0.6", "param dcm_supply_V 60"],
                       what="130 rad/s, 0.6 N m, 60 V supply: the 48 V armature limit is the reach"),
    "low_supply": dict(lines=["speed const 80", "load const 1.2", "param dcm_supply_V 36"],
                       what="80 rad/s, 1.2 N m on a 36 V supply (UAC headroom 1.3 V)"),
}
POINTS_THR = {
    "mid": dict(lines=THR_NOMINAL, nominal=True,
                what="mid travel, 25 deg with the +-8 deg 0.5 Hz driver sine (the nominal point)"),
    "closed": dict(lines=["angle const 1"], what="closed, 1 deg (no test signal below 10 deg)"),
    "below_lh": dict(lines=["angle const 3.5"], what="below limp-home, 3.5 deg (limp-home 6.5 deg)"),
    "wide_open": dict(lines=["angle const 85"], what="wide open, 85 deg (no test signal above 80 deg)"),
    "tip_in": dict(lines=["angle const 10", f"angle step {T0:g} 70"],
                   what="tip-in: 10 -> 80 deg step at the fault time"),
    "tip_out": dict(lines=["angle const 80", f"angle step {T0:g} -70"],
                    what="tip-out: 80 -> 10 deg step at the fault time"),
    "creep": dict(lines=["angle const 10", "angle ramp 1 21 50"],
                  what="slow creep: ramp 10 -> 60 deg over 20 s (2.5 deg/s)"),
    "low_supply": dict(lines=THR_NOMINAL + ["param thr_supply_V 9"],
                       what="mid travel on a 9 V supply (sag)"),
}
COMM_POINTS = {"dcm": ["fwd_motor", "rev_brake"], "thr": ["mid", "wide_open"]}

# Sampled-set scenarios the firmware does not meet yet: key -> one line of
# reason (observed on the current firmware).
PENDING: dict[str, str] = {
}


# ---------------------------------------------------------------------------
# Profiles (host_sim/SCENARIO.md semantics) evaluated in Python.
def profile(lines, what, dur):
    comps = []
    for ln in lines:
        w = ln.format(dur=f"{dur:g}").split()
        if w[0] == what and w[1] != "fan":
            comps.append((w[1], [float(x) for x in w[2:]]))

    def f(t):
        v = 0.0
        for shape, a in comps:
            if shape == "const":
                v += a[0]
            elif shape == "step":
                v += a[1] if t >= a[0] else 0.0
            elif shape == "ramp":
                v += 0.0 if t < a[0] else (a[2] if t >= a[1] else a[2] * (t - a[0]) / (a[1] - a[0]))
            elif shape == "sine":
                v += a[2] * math.sin(2 * math.pi * a[3] * (t - a[0])) if a[0] <= t < a[1] else 0.0
            else:
                raise ValueError(f"profile shape {shape!r} not modelled")
        return v
    return f


def param(lines, name, default):
    for ln in lines:
        w = ln.split()
        if w[0] == "param" and w[1] == name:
            return float(w[2])
    return default


def dcm_series(lines, dur):
    """Quantities of a DC-motor point at every DT: list of (t, dict)."""
    sp, ld = profile(lines, "speed", dur), profile(lines, "load", dur)
    supply = param(lines, "dcm_supply_V", op.P["dcm_supply_V"])
    out, oneway, last = [], 0.0, None
    for k in range(int(round(dur / DT)) + 1):
        t = k * DT
        w = max(-400.0, min(400.0, sp(t)))
        q = op.dcm_point(w, max(-10.0, min(10.0, ld(t))), supply)
        s = 0 if abs(w) < op.fw("w_sign_on") else (1 if w > 0 else -1)
        oneway = oneway + DT if (s != 0 and s == last) else 0.0
        last = s
        q["oneway"] = oneway
        out.append((t, q))
    return out


class ThrTestBursts:
    """When the ECU's throttle test signal runs (diag/canfdi_testsched.h),
    as far as the observability can count on it: the key-on burst at the
    first enabled instant and a burst after test_lack of enabled operation
    without motion of the valve's own (the estimator not excited), then a
    rest during which the lack is not counted. Bursts on a symptom (NEED)
    are not counted: the faults whose
    isolation needs the valve to move (spring, friction, a jam) show no
    symptom while it holds still."""

    def __init__(self):
        self.keyon, self.lack, self.left, self.rest = True, 0.0, 0.0, 0.0

    def step(self, enabled, natural_motion):
        """One DT: returns whether a burst runs (the firmware's phases: on,
        rest on time whatever the enabling, idle counting the lack while
        enabled)."""
        if self.left > 0.0:
            if enabled:
                self.left -= DT
                if self.left <= 1e-9:
                    self.left, self.rest = 0.0, op.fw("test_rest")
                return True
            self.left, self.rest = 0.0, op.fw("test_rest")      # aborted
            return False
        if self.rest > 0.0:
            self.rest -= DT
            if self.rest <= 1e-9:
                self.rest, self.lack = 0.0, 0.0
            return False
        if enabled:
            if self.keyon:
                self.keyon, self.left = False, op.fw("test_burst")
                return True
            self.lack = 0.0 if natural_motion else self.lack + DT
            if self.lack >= op.fw("test_lack") - 1e-9:
                self.lack, self.left = 0.0, op.fw("test_burst")
                return True
        return False


def thr_series(lines, dur, t_jam_starts=()):
    """Quantities of a throttle point at every DT: the reference (setpoint
    clamped to the controller's range plus the ECU's +-3 deg 2 Hz test
    signal while a burst runs, ThrTestBursts), the valve following it at
    most at the physical slew rate of the supply, and `stuck_err` for a
    valve stuck at each time in t_jam_starts (the fault starts: the motion
    evidence restarts there too, it must postdate the fault)."""
    sp = profile(lines, "angle", dur)
    supply = param(lines, "thr_supply_V", op.P["thr_supply_V"])
    slew = math.degrees(op.thr_slew_max(supply)) * DT
    amp = math.degrees(op.fw("thr_sine"))
    per = op.fw("thr_sine_period")
    lo, hi = op.fw("thr_angle_min_deg"), op.fw("thr_angle_max_deg")
    win = int(round(per / DT))
    errs = []
    lh = op.P["thr_limp_home_deg"]
    band = op.fw("thr_limp_band_deg")
    mem_s = op.fw("thr_fast_memory")
    win_m = int(round(MOTION_WINDOW / DT))
    hold = op.fw("thr_holdoff")
    run, last_d = 0.0, 0
    out, th = [], None
    jam = None
    starts = sorted(t_jam_starts)
    mv, mva = [], []
    bursts = ThrTestBursts()
    sp_prev = None
    for k in range(int(round(dur / DT)) + 1):
        t = k * DT
        th_sp = min(hi, max(lo, max(0.0, min(90.0, sp(t)))))
        natural = sp_prev is not None and abs(math.radians(th_sp - sp_prev)) / DT >= op.fw("thr_sign_band")
        sp_prev = th_sp
        test = bursts.step(op.thr_test_enabled(th_sp), natural)
        ref = th_sp + (amp * math.sin(2 * math.pi * t / per) if test else 0.0)
        tgt = max(0.0, min(op.THR_MAX_DEG, ref))
        prev = th
        th = tgt if th is None else th + max(-slew, min(slew, tgt - th))
        w = 0.0 if prev is None else math.radians(th - prev) / DT
        q = op.thr_point(th, 0.0, supply)
        q["th_sp"] = th_sp
        q["th_dot"] = w
        q["test"] = 1 if op.thr_test_enabled(th_sp) else 0
        q["burst"] = 1 if test else 0
        # the fast test learns from one-way motion beyond the sign band once
        # it has lasted the hold-off (everywhere / outside the limp band);
        # its estimate is held while the valve rests: "moving" when the
        # last MOTION_WINDOW s hold the fast test's memory of such motion
        m = abs(w) >= op.fw("thr_sign_band")
        d = 0 if not m else (1 if w > 0 else -1)
        run = run + DT if (d != 0 and d == last_d) else (DT if d != 0 else 0.0)
        last_d = d
        learn = run >= hold - 1e-9
        mv.append(learn)
        mva.append(learn and abs(th - lh) >= band)
        q["moving"] = 1 if sum(mv[-win_m:]) * DT >= mem_s - 1e-9 else 0
        q["moving_away"] = 1 if sum(mva[-win_m:]) * DT >= mem_s - 1e-9 else 0
        if starts and t >= starts[0] - 1e-9:
            jam = th if prev is None else prev
            starts.pop(0)
            # the evidence must postdate the fault: motion before it shows
            # the healthy valve (the diagnosis' freshness, docs/envelope.md)
            mv[:] = [False] * len(mv)
            mva[:] = [False] * len(mva)
        errs.append(0.0 if jam is None else abs(math.radians(ref - jam)))
        q["stuck_err"] = max(errs[-win:])
        out.append((t, q))
    return out


# ---------------------------------------------------------------------------
def fault_on(mode, cls, dur):
    """Intervals [a, b) in which the fault acts at its default magnitude."""
    if mode == "abrupt":
        return [(T0, dur)]
    if mode == "incipient":
        return [(T0 + RAMP, dur)]
    period, duty = gm.CLASSES[cls]["inter"]
    iv, k = [], 0
    while T0 + k * period < dur:
        iv.append((T0 + k * period, min(dur, T0 + k * period + duty * period)))
        k += 1
    return iv


def classify(row, series, intervals, budget):
    """Longest unbroken stretch of each condition inside the fault-on
    intervals against the budget -> (isolable / observable / not_observable,
    the time the first isolable stretch has lasted the budget or None)."""
    need = max(budget, DT) - 1e-9
    best = {"iso": 0.0, "obs": 0.0}
    ready = None
    for a, b in intervals:
        run = {"iso": 0.0, "obs": 0.0}
        for t, q in series:
            if not (a - 1e-9 <= t < b - 1e-9):
                continue
            for key, code in (("iso", row["iso_code"]), ("obs", row["obs_code"])):
                if op.evaluate(code, q):
                    run[key] += DT
                    best[key] = max(best[key], run[key])
                    if key == "iso" and ready is None and run[key] >= need:
                        ready = t + DT
                else:
                    run[key] = 0.0
    if best["iso"] >= need:
        return "isolable", ready
    if best["obs"] >= need or best["iso"] >= need:
        return "observable", None
    return "not_observable", None


def tolerated_codes(row, series, intervals):
    """Tolerated codes whose condition holds at some instant while the fault
    is on, and those of them that are conditional (not `always`)."""
    codes, cond_codes = set(), set()
    for code, cond, text in row["tolerated_codes"]:
        for a, b in intervals:
            if any(a - 1e-9 <= t < b and op.evaluate(cond, q) for t, q in series):
                codes.add(code)
                if text != "always":
                    cond_codes.add(code)
    return sorted(codes), sorted(cond_codes)


def read_catalogue():
    faults = [r for r in gm.read_csv(ROOT / "dbc" / "faults.csv") if r["name"] != "none"]
    dtcs = {r["code"] for r in gm.read_csv(ROOT / "dbc" / "dtcs.csv")}
    obs = op.load_observability(faults=[r["name"] for r in faults])
    for r in faults:
        if r["name"] not in gm.FAULT_CLASS:
            raise SystemExit(f"gen_envelope: no budget class for {r['name']} (tests/sil/gen_matrix.py)")
    return faults, dtcs, obs


def duration(cls, mode, point):
    budget = gm.CLASSES[cls]["budget"]
    if mode == "abrupt":
        dur = 6.0 if budget < 1.0 else 8.0
    elif mode == "incipient":
        dur = max(8.0, math.ceil(T0 + RAMP + budget) + 2.0)
    else:
        dur = 6.0 if gm.CLASSES[cls]["inter"][0] <= 1.0 else 8.0
    return max(dur, point.get("min_dur", 0.0))


def build_run(row, mode, sub, pname, obs_row, dtcs, seed):
    """One run: scenario text, expected/tolerated codes, observability class."""
    name = row["name"]
    cls = gm.FAULT_CLASS.get(name, "parametric")  # "none": the longest lead-out
    budget = gm.CLASSES[cls]["budget"]
    points = POINTS_DCM if sub == "dcm" else POINTS_THR
    point = points[pname]
    dur = duration(cls, mode, point)
    dcm_lines = point["lines"] if sub == "dcm" else DCM_NOMINAL
    thr_lines = point["lines"] if sub == "thr" else THR_NOMINAL
    mag = float(row["default_magnitude"])
    if mode == "abrupt":
        fault = f"fault {T0:g} {name} abrupt {mag:g}"
    elif mode == "incipient":
        fault = f"fault {T0:g} {name} incipient {mag:g} {RAMP:g}"
    else:
        period, duty = gm.CLASSES[cls]["inter"]
        fault = f"fault {T0:g} {name} intermittent {mag:g} {period:g} {duty:g}"
    iv = fault_on(mode, cls, dur)
    series = (dcm_series(dcm_lines, dur) if sub == "dcm"
              else thr_series(thr_lines, dur, [a for a, _ in iv]))
    klass, ready = classify(obs_row, series, iv, budget)
    if klass != "isolable" and sub == "thr" and mode != "intermittent":
        # a fault that needs the valve to move, at a point that holds it
        # still, is found by the periodic test burst: run until one is over
        dur_long = math.ceil(op.fw("test_burst") + op.fw("test_rest") + op.fw("test_lack")
                             + max(budget, op.fw("test_burst"))) + 2.0
        iv_long = fault_on(mode, cls, dur_long)
        series_long = thr_series(thr_lines, dur_long, [a for a, _ in iv_long])
        k2, r2 = classify(obs_row, series_long, iv_long, budget)
        if k2 == "isolable":
            dur, iv, series, klass, ready = dur_long, iv_long, series_long, k2, r2
    codes = [c for c in row["dtc"].split("+") if c] + gm.EXTRA_DTCS.get(name, ([], ""))[0]
    tol, tol_cond = tolerated_codes(obs_row, series, iv)
    for c in codes + tol:
        if c not in dtcs:
            raise SystemExit(f"gen_envelope: {c} ({name}) not in dbc/dtcs.csv")
    due = T0 + (RAMP if mode == "incipient" else 0.0) + budget
    if ready is not None:
        # isolable only once the condition has held its budget (a test burst)
        due = max(due, ready)
    key = f"{name}_{mode}@{pname}"
    lines = [
        f"# {name}_{mode}_{pname}.scn -- generated by tests/sil/gen_envelope.py; do not edit.",
        f"# {name} (id {row['id']}) {mode} {mag:g} at {T0:g} s; point {sub} {pname}: {point['what']}.",
        f"# dbc/observability.csv class here: {klass}"
        + (f"; expected {'+'.join(codes)} by {due:.3f} s ({cls} budget {budget * 1000:g} ms)"
           if klass == "isolable" else "; expected: no trouble code" if klass == "not_observable"
           else "; detected-not-isolated is correct (no expect on the code)"),
        f"duration {dur:g}",
        f"seed {seed}",
        NOISE,
    ]
    lines += [ln.format(dur=f"{dur:g}") for ln in dcm_lines + thr_lines]
    if sub == "thr" and not point.get("nominal"):
        # the valve starts where the point holds it (not at limp-home), so
        # the lead-in has no full-travel stroke of its own
        th0 = max(0.0, min(90.0, profile(thr_lines, "angle", dur)(0.0)))
        lines.insert(lines.index(NOISE) + 1, f"init thr_angle {th0:g}")
    lines.append(fault)
    if klass == "isolable":
        lines.append(f"expect {T0 - 0.001:.3f} no_dtc")
        lines += [f"expect {due:.3f} dtc {c}" for c in codes]
    elif klass == "not_observable":
        lines.append(f"expect {dur:.3f} no_dtc")
    else:
        lines.append(f"expect {T0 - 0.001:.3f} no_dtc")
    return dict(key=key, fault=name, fault_id=int(row["id"]), mode=mode, sub=sub, point=pname,
                nominal=bool(point.get("nominal")), cls=cls, budget=budget, due=due,
                klass=klass, codes=codes, tolerated=tol, tolerated_cond=tol_cond, dur=dur,
                text="\n".join(lines) + "\n", file=f"{name}_{mode}_{pname}.scn")


def points_for(row):
    sub = gm.subsystem(row)
    if row["component"] == "comm":
        return sub, COMM_POINTS[sub]
    return sub, list(POINTS_DCM if sub == "dcm" else POINTS_THR)


def fault_free_run(sub, pname, seed):
    """The point without a fault: anything named is a false alarm of the
    operating point itself (e.g. of a tip-in)."""
    row = dict(name="none", id="0", dtc="", default_magnitude="0", component="none")
    r = build_run(row, "abrupt", sub, pname, FAULT_FREE_OBS, set(), seed)
    lines = [ln for ln in r["text"].splitlines() if not ln.startswith(("fault ", "expect ", "# "))]
    what = (POINTS_DCM if sub == "dcm" else POINTS_THR)[pname]["what"]
    r["text"] = "\n".join([f"# none_{pname}.scn -- generated by tests/sil/gen_envelope.py; do not edit.",
                           f"# fault-free at {sub} {pname}: {what}; expected: no trouble code."]
                          + lines) + f"\nexpect {r['dur']:.3f} no_dtc\n"
    r["file"] = f"none_{sub}_{pname}.scn"
    r["key"] = f"none@{sub}_{pname}"
    r["codes"] = []
    return r


FAULT_FREE_OBS = {"iso_code": op.compile_expr("0"), "obs_code": op.compile_expr("0"), "tolerated_codes": []}


def all_runs(faults, dtcs, obs):
    runs, seed = [], BENCH_SEED_BASE
    for sub, pts in (("dcm", POINTS_DCM), ("thr", POINTS_THR)):
        for pname in pts:
            runs.append(fault_free_run(sub, pname, seed))
            seed += 1
    for row in faults:
        sub, pts = points_for(row)
        for pname in pts:
            for mode in row["modes"].split("|"):
                runs.append(build_run(row, mode, sub, pname, obs[row["name"]], dtcs, seed))
                seed += 1
    return runs


# ---------------------------------------------------------------------------
def sampled(faults, dtcs, obs):
    """The make-test set: per fault one abrupt run at an isolable non-nominal
    point (spread over the points by fault id) and one where it is not
    observable, if the grid has such a point."""
    out, seed = [], SEED_BASE
    for row in faults:
        sub, pts = points_for(row)
        cands = [build_run(row, "abrupt", sub, p, obs[row["name"]], dtcs, 0) for p in pts]
        # a conditional tolerated code (a drifted TPS leaving its range) is
        # fine but cannot be written as an expectation: not sampled there
        iso = [c for c in cands if c["klass"] == "isolable" and not c["nominal"] and not c["tolerated_cond"]]
        blind = [c for c in cands if c["klass"] == "not_observable"]
        pick = []
        if iso:
            pick.append(iso[int(row["id"]) % len(iso)])
        if blind:
            pick.append(blind[int(row["id"]) % len(blind)])
        if not iso and not blind:
            raise SystemExit(f"gen_envelope: {row['name']}: no non-nominal point to sample")
        for c in pick:
            out.append(build_run(row, "abrupt", sub, c["point"], obs[row["name"]], dtcs, seed))
            seed += 1
    return out


def write_sampled(scns):
    for d in (OUT, OUT_PENDING):
        d.mkdir(exist_ok=True)
        for p in d.glob("*.scn"):
            p.unlink()
    keys = {s["file"][:-4] for s in scns}
    unknown = set(PENDING) - keys
    if unknown:
        raise SystemExit(f"gen_envelope: PENDING names no sampled scenario: {sorted(unknown)}")
    for s in scns:
        stem = s["file"][:-4]
        text = s["text"]
        if stem in PENDING:
            text = text.replace("; do not edit.\n", "; do not edit.\n# PENDING: " + PENDING[stem] + "\n", 1)
        ((OUT_PENDING if stem in PENDING else OUT) / s["file"]).write_text(text)


# ---------------------------------------------------------------------------
def run_one(bin_, path, seed):
    cmd = [bin_, "-s", str(path)] + (["--seed", str(seed)] if seed is not None else [])
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode not in (0, 1):
        raise RuntimeError(f"{' '.join(cmd)}: exit {p.returncode}\n{p.stdout[-2000:]}{p.stderr[-2000:]}")
    return p.stdout


def judge(run, out):
    """Verdict of one run from the runner's timeline."""
    before, after, first = set(), set(), {}
    degr = []
    for line in out.splitlines():
        m = DTC_LINE.match(line)
        if m and m.group(3) in ("testFailed", "confirmed"):
            t, code = float(m.group(1)), m.group(2)
            if t < T0:
                before.add(code)
            else:
                after.add(code)
                first.setdefault(code, t)
            continue
        m = DEG_LINE.match(line)
        if m:
            degr.append([float(m.group(1)), m.group(2), m.group(4)])
    own = [c for c in run["codes"] if c in after]
    wrong = sorted(c for c in after if c not in run["codes"] and c not in run["tolerated"])
    delay = min(first[c] for c in own) - T0 if own else None
    if run.get("fault") == "none":
        v = "false_alarm" if (before or after) else "correct"
    elif wrong:
        v = "wrong_code"
    elif before:
        v = "false_alarm"
    elif own:
        v = "correct"
    elif after:
        v = "not_isolated"
    elif run["klass"] == "isolable":
        v = "missed"
    else:
        v = "not_tested"
    late = (v == "correct" and delay is not None and
            delay > run["due"] - T0 + 1e-6)
    return dict(verdict=v, named=sorted(after), before=sorted(before), wrong=wrong,
                delay_s=None if delay is None else round(delay, 3), late=late,
                first={c: round(t - T0, 3) for c, t in sorted(first.items())}, degradation=degr)


VERDICTS = ("wrong_code", "false_alarm", "missed", "not_isolated", "correct", "not_tested")


def bench(bin_, scn_dir, n_seeds, jobs, out_json, out_png):
    faults, dtcs, obs = read_catalogue()
    t_start = time.monotonic()
    runs = all_runs(faults, dtcs, obs)
    scn_dir.mkdir(parents=True, exist_ok=True)
    for p in scn_dir.glob("*.scn"):
        p.unlink()
    for r in runs:
        (scn_dir / r["file"]).write_text(r["text"])
    seeds = [None] + list(range(2, n_seeds + 1))
    tasks = [(r, s) for r in runs for s in seeds]
    print(f"gen_envelope: {len(runs)} runs x {len(seeds)} seed(s) = {len(tasks)} on {jobs} core(s); "
          f"scenarios in {scn_dir}", file=sys.stderr)
    results = []
    done = 0
    with cf.ThreadPoolExecutor(max_workers=jobs) as ex:
        futs = {ex.submit(run_one, bin_, scn_dir / r["file"], s): (r, s) for r, s in tasks}
        for fu in cf.as_completed(futs):
            r, s = futs[fu]
            j = judge(r, fu.result())
            results.append(dict({k: r[k] for k in ("key", "fault", "mode", "sub", "point", "klass",
                                                   "codes", "tolerated", "cls", "budget", "file")},
                                seed=s, **j))
            done += 1
            if done % 50 == 0 or done == len(tasks):
                print(f"gen_envelope: {done}/{len(tasks)} runs, {time.monotonic() - t_start:.0f} s",
                      file=sys.stderr)
    order = {r["key"]: i for i, r in enumerate(runs)}
    results.sort(key=lambda x: (order[x["key"]], x["seed"] or 0))
    wall = time.monotonic() - t_start
    report = summarise(results, faults, wall, seeds, jobs)
    print_tables(results, report)
    out_json.parent.mkdir(parents=True, exist_ok=True)
    out_json.write_text(json.dumps(report, indent=1) + "\n")
    confusion_png(report, out_png)
    print(f"gen_envelope: wrote {out_json} and {out_png}")
    return 0


def summarise(results, faults, wall, seeds, jobs):
    counts = {v: 0 for v in VERDICTS}
    for r in results:
        counts[r["verdict"]] += 1
    names = ["none"] + [f["name"] for f in faults]
    cols = sorted({c for r in results for c in r["named"]}) + ["none"]
    conf = {n: {c: 0 for c in cols} for n in names}
    wrong_cells = set()
    for r in results:
        for c in r["named"] or ["none"]:
            conf[r["fault"]][c] += 1
            if c != "none" and c not in r["codes"] and c not in r["tolerated"]:
                wrong_cells.add((r["fault"], c))
    per_class = {}
    for r in results:
        per_class.setdefault(r["klass"], {v: 0 for v in VERDICTS})[r["verdict"]] += 1
    return dict(
        summary=dict(runs=len(results), seeds=[s if s is not None else "file" for s in seeds],
                     jobs=jobs, wall_s=round(wall, 1), verdicts=counts, by_class=per_class,
                     late=sum(1 for r in results if r["late"])),
        confusion=dict(rows=names, cols=cols, counts=conf,
                       wrong=sorted([list(x) for x in wrong_cells])),
        points=dict(dcm={k: v["what"] for k, v in POINTS_DCM.items()},
                    thr={k: v["what"] for k, v in POINTS_THR.items()}),
        runs=results)


def print_tables(results, report):
    by_point = {}
    for r in results:
        by_point.setdefault((r["sub"], r["point"]), []).append(r)
    for (sub, pt), rs in by_point.items():
        print(f"\n== {sub} {pt}: {(POINTS_DCM if sub == 'dcm' else POINTS_THR)[pt]['what']}")
        print(f"  {'fault':26s} {'mode':12s} {'class':14s} {'verdicts (seeds)':34s} named / delay")
        keys = []
        for r in rs:
            if (r["fault"], r["mode"]) not in keys:
                keys.append((r["fault"], r["mode"]))
        for f, m in keys:
            g = [r for r in rs if r["fault"] == f and r["mode"] == m]
            named = sorted({c for r in g for c in r["named"]})
            ds = [r["delay_s"] for r in g if r["delay_s"] is not None]
            dl = (f"{1000 * min(ds):.0f}-{1000 * max(ds):.0f} ms" if ds else "-")
            print(f"  {f:26s} {m:12s} {g[0]['klass']:14s} {' '.join(r['verdict'] for r in g):34s} "
                  f"{','.join(named) or '-'} / {dl}")
    s = report["summary"]
    print("\n== summary")
    wrong = [r for r in results if r["verdict"] == "wrong_code"]
    print(f"wrong_code runs: {len(wrong)}")
    for r in wrong:
        print(f"  {r['fault']:26s} {r['mode']:12s} @ {r['sub']} {r['point']:20s} seed {r['seed'] or 'file'}: "
              f"named {','.join(r['named'])} (wrong: {','.join(r['wrong'])})")
    for v in ("false_alarm", "missed"):
        rs = [r for r in results if r["verdict"] == v]
        print(f"{v} runs: {len(rs)}")
        for r in rs:
            print(f"  {r['fault']:26s} {r['mode']:12s} @ {r['sub']} {r['point']:20s} seed {r['seed'] or 'file'}: "
                  f"named {','.join(r['named']) or '-'}" + (f" before: {','.join(r['before'])}" if r["before"] else ""))
    print("verdicts: " + ", ".join(f"{k} {v}" for k, v in s["verdicts"].items())
          + f"; late (correct beyond the budget) {s['late']}")
    for k, v in s["by_class"].items():
        print(f"  class {k:15s} " + ", ".join(f"{a} {b}" for a, b in v.items() if b))
    print(f"{s['runs']} runs, seeds {s['seeds']}, {s['jobs']} job(s), {s['wall_s']} s wall")


def confusion_png(report, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    c = report["confusion"]
    rows, cols = c["rows"], c["cols"]
    wrong = {tuple(x) for x in c["wrong"]}
    m = [[c["counts"][r][k] for k in cols] for r in rows]
    fig, ax = plt.subplots(figsize=(1.0 + 0.55 * len(cols), 1.2 + 0.32 * len(rows)))
    mx = max(max(row) for row in m) or 1
    for i, r in enumerate(rows):
        for j, k in enumerate(cols):
            v = m[i][j]
            if not v:
                continue
            bad = (r, k) in wrong
            ax.add_patch(plt.Rectangle((j - 0.5, i - 0.5), 1, 1,
                                       color=("#d62728" if bad else "#1f77b4" if k != "none" else "#7f7f7f"),
                                       alpha=0.25 + 0.75 * v / mx))
            ax.text(j, i, str(v), ha="center", va="center", fontsize=7,
                    fontweight="bold" if bad else "normal")
    ax.set_xlim(-0.5, len(cols) - 0.5)
    ax.set_ylim(len(rows) - 0.5, -0.5)
    ax.set_xticks(range(len(cols)))
    ax.set_xticklabels(cols, rotation=90, fontsize=7)
    ax.set_yticks(range(len(rows)))
    ax.set_yticklabels(rows, fontsize=7)
    ax.set_xlabel("named code (testFailed/confirmed after the injection); none = nothing named")
    ax.set_ylabel("injected fault")
    s = report["summary"]["verdicts"]
    ax.set_title(f"envelope matrix: {report['summary']['runs']} runs; wrong_code {s['wrong_code']}, "
                 f"missed {s['missed']}, false_alarm {s['false_alarm']} (red: a code not expected "
                 f"for the fault)", fontsize=8)
    ax.grid(False)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=130)
    plt.close(fig)


def print_grid(faults, dtcs, obs):
    for sub, pts in (("dcm", POINTS_DCM), ("thr", POINTS_THR)):
        for pname, p in pts.items():
            print(f"{sub} {pname}: {p['what']}")
            ser = (dcm_series(p["lines"], 8.0) if sub == "dcm" else thr_series(p["lines"], 8.0))
            q = ser[int(T0 / DT)][1]
            keys = (("w", "M_L", "I", "U", "u_lim", "sat", "uac", "quadrant") if sub == "dcm"
                    else ("th", "i", "u", "tps1", "tps2", "moving"))
            print("  at 3 s: " + "  ".join(f"{k}={q[k]:.3g}" if isinstance(q[k], float) else f"{k}={q[k]}"
                                         for k in keys))
            cl = []
            for row in faults:
                if gm.subsystem(row) == sub and row["component"] != "comm":
                    cl.append(f"{row['name']}:{build_run(row, 'abrupt', sub, pname, obs[row['name']], dtcs, 0)['klass'][:3]}")
            print("  abrupt: " + " ".join(cl))


def main():
    ap = argparse.ArgumentParser(
        description="The envelope fault matrix (docs/envelope.md): writes the sampled make-test "
                    "scenarios (default), prints the grid (--grid), or runs the whole matrix as a "
                    "bench (--bench BIN).",
        formatter_class=argparse.RawDescriptionHelpFormatter, epilog=__doc__.split("\n\n", 1)[1])
    ap.add_argument("--grid", action="store_true", help="print each point's steady state and classes")
    ap.add_argument("--bench", metavar="BIN", help="run the full matrix with this canfdi-sil")
    ap.add_argument("--out", type=Path, default=ROOT / "build" / "bench" / "envelope.json",
                    help="the bench's JSON: every run, the confusion matrix, the summary")
    ap.add_argument("--png", type=Path, default=ROOT / "build" / "bench" / "envelope_confusion.png",
                    help="the confusion matrix as a picture")
    ap.add_argument("--scn-dir", type=Path, default=ROOT / "build" / "bench" / "envelope_scn",
                    help="where the bench writes its scenarios (kept to reproduce a run)")
    ap.add_argument("--jobs", type=int, default=2, help="parallel runner processes (default 2)")
    ap.add_argument("--seeds", type=int, default=3,
                    help="noise seeds per run: the file's, then --seed 2..N (default 3)")
    a = ap.parse_args()
    if a.jobs < 1 or a.seeds < 1:
        ap.error("--jobs and --seeds must be at least 1")
    try:
        faults, dtcs, obs = read_catalogue()
    except (op.ExprError, KeyError, ValueError) as e:
        ap.error(str(e))
    if a.grid:
        print_grid(faults, dtcs, obs)
        return 0
    if a.bench:
        if not os.access(a.bench, os.X_OK):
            ap.error(f"{a.bench}: not an executable SIL runner (make build/bench/canfdi-sil-rel)")
        return bench(a.bench, a.scn_dir, a.seeds, a.jobs, a.out, a.png)
    scns = sampled(faults, dtcs, obs)
    write_sampled(scns)
    n_p = sum(1 for s in scns if s["file"][:-4] in PENDING)
    print(f"gen_envelope: {len(scns)} sampled scenarios ({len(scns) - n_p} envelope/, "
          f"{n_p} envelope_pending/)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
