"""canfdi-fleet-gen: a synthetic fleet of recorded drives with slowly developing faults.

N vehicles x M drives. Every drive is a canfdi-sil run (the firmware and the
plants in lockstep, -O2 build build/bench/canfdi-sil-rel when it is there)
whose bus is recorded as a candump log (gzip), the way a data logger in the
vehicle records it; the vehicle's ECU keeps its DTC memory from one drive to
the next (canfdi-sil --nvm-in/--nvm-out), as a vehicle's ECU does through its
NVM. Everything is drawn from --seed: the same seed gives the same fleet,
byte for byte.

Faults develop over calendar time: a fault's magnitude is
rate x (time - onset), zero before its onset, and each drive runs with the
magnitude of its own start time (constant through the drive). Kinds:

  ra_creep          dcm_ra_up abrupt <m>: R_A +m (P1A10)
  spring_weak       thr_spring_weak abrupt <m>: return spring -m (P1B10)
  tps_intermittent  thr_tps1_open intermittent, dropouts of L ms every 7 s
                    (a connector going bad, P0122)

A kind's threshold is the smallest magnitude at which this firmware sets
the code in one drive of the drive template, measured here with
canfdi-sil by bisection (R_A and spring to 0.005, the dropout to 1 ms).
The firmware's calibration threshold on the estimated parameter (R_A
+8 %, spring -10 %, from the replay core's header) is written beside it:
the estimators read R_A about 1.5 % and the spring about 3 % beyond the
injected change, so the code comes at a smaller injected change than the
calibration's figure.

The crossing of a fault is the time its magnitude reaches the threshold, and
its crossing drive the first drive that starts at or after it. Written
beside the logs:

  OUT/<vehicle>/<vehicle>_<YYYYmmddTHHMMSS>.log.gz   the drives
  OUT/manifest.csv     vehicle,start,file (canfdi-fleet's manifest form)
  OUT/truth.json       per vehicle: its faults (kind, code, parameter,
                       threshold, onset, rate per day, crossing time and
                       drive, the magnitude of every drive) and drives
  OUT/truth/<vehicle>.ecu.nvm   the vehicle ECU's DTC memory after its
                       last drive (canfdi_app_power_down image)
"""
from __future__ import annotations

import argparse
import csv
import datetime as dt
import gzip
import json
import os
import random
import shutil
import subprocess
import sys
import tempfile
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Any

from . import REPO_ROOT

SIL_REL = REPO_ROOT / "build" / "bench" / "canfdi-sil-rel"
SIL_HOST = REPO_ROOT / "build" / "bin" / "canfdi-sil"
CORE = REPO_ROOT / "build" / "bin" / "canfdi-replay-core"
DTCS = REPO_ROOT / "dbc" / "dtcs.csv"
EPOCH = dt.datetime(2025, 3, 3, 0, 0, 0)
TPS_PERIOD_S = 7.0

#: parameter index in the core's p/e arrays and its threshold in the core's hdr
KINDS: dict[str, dict[str, Any]] = {
    "ra_creep": {"fault": "dcm_ra_up", "code": "P1A10", "parameter": "R_A", "unit": "rel",
                 "hdr": ("dcm_pos", 0), "per_drive": (0.02, 0.03)},
    "spring_weak": {"fault": "thr_spring_weak", "code": "P1B10", "parameter": "spring", "unit": "rel",
                    "hdr": ("thr_neg", 2), "per_drive": (0.03, 0.045)},
    "tps_intermittent": {"fault": "thr_tps1_open", "code": "P0122", "parameter": "TPS1 dropout", "unit": "ms",
                         "hdr": None, "per_drive": (4.0, 6.0)},
}
#: the share of each kind in a fleet; the rest is fault-free
SHARES = (("ra_creep", 0.25), ("spring_weak", 0.2), ("tps_intermittent", 0.15))
DRIVE_GAP_DAYS = (1.5, 3.5)


def sil_binary() -> Path:
    env = os.environ.get("CANFDI_SIL")
    if env:
        return Path(env)
    return SIL_REL if SIL_REL.exists() else SIL_HOST


def calibration_thresholds() -> dict[str, float]:
    """The firmware's parameter thresholds as the replay core reports them (its hdr event)."""
    out = subprocess.run([str(CORE), "/dev/null"], capture_output=True, text=True, check=True).stdout
    hdr = json.loads(out.splitlines()[0])
    return {k: float(hdr["thr_pos"][v["hdr"][0]][v["hdr"][1]]) for k, v in KINDS.items() if v["hdr"]}


def scenario(duration_s: float, rng: random.Random, fault_line: str) -> str:
    """One drive: warm motor, a cruise with a speed change, load, a moving throttle (the test rig's
    drive template, varied per drive)."""
    base = rng.uniform(85.0, 115.0)
    t_step = rng.uniform(0.25, 0.45) * duration_s
    lines = [
        f"duration {duration_s:g}",
        f"seed {rng.randrange(1, 2**31)}",
        "noise dcm_ua 0.05", "noise dcm_ia 0.02", "noise dcm_speed 0.2",
        "noise thr_tps1 0.003", "noise thr_tps2 0.003", "noise thr_i 0.01",
        f"init dcm_winding {52.3 + rng.uniform(-1.0, 1.0):.2f}",
        f"speed const {base:.1f}",
        f"speed step {t_step:.2f} {rng.choice((-1, 1)) * rng.uniform(10.0, 20.0):.1f}",
        f"load const {rng.uniform(1.0, 1.4):.2f}",
        f"angle const {rng.uniform(20.0, 30.0):.1f}",
        f"angle sine 1 {duration_s:g} 8 0.5",
    ]
    if fault_line:
        lines.append(fault_line)
    return "\n".join(lines) + "\n"


def fault_line(kind: str, magnitude: float) -> str:
    if magnitude <= 0:
        return ""
    k = KINDS[kind]
    if kind == "tps_intermittent":
        return f"fault 5 {k['fault']} intermittent 1 {TPS_PERIOD_S:g} {magnitude / 1000.0 / TPS_PERIOD_S:.6f}"
    return f"fault 0 {k['fault']} abrupt {magnitude:.5f}"


def _run_sil(scn_text: str, log: Path | None, nvm_in: Path | None, nvm_out: Path | None,
             tmp: Path, name: str) -> None:
    scn = tmp / f"{name}.scn"
    scn.write_text(scn_text, encoding="ascii")
    cmd = [str(sil_binary()), "-q", "-t", str(DTCS), "-s", str(scn)]
    if log is not None:
        cmd += ["-l", str(log)]
    if nvm_in is not None:
        cmd += ["--nvm-in", str(nvm_in)]
    if nvm_out is not None:
        cmd += ["--nvm-out", str(nvm_out)]
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode not in (0, 1):  # 1: a code the scenario does not expect (it expects nothing)
        raise RuntimeError(f"canfdi-sil failed ({r.returncode}): {r.stderr.strip()}")


def _codes(log: Path) -> set[str]:
    out = subprocess.run([str(CORE), str(log)], capture_output=True, text=True, check=True).stdout
    codes = set()
    for line in out.splitlines():
        e = json.loads(line)
        if e["ev"] == "dtc" and e["src"] == "replay" and e["status"] & 1:
            codes.add(e["code"])
    return codes


#: bisection grid per kind: (step, largest multiple tried)
GRID = {"ra_creep": (0.005, 64), "spring_weak": (0.005, 64), "tps_intermittent": (1.0, 64)}


def measure_threshold(kind: str, duration_s: float, tmp: Path) -> float:
    """The smallest magnitude (on the kind's grid) that sets the kind's code in one drive of the
    template (a fixed draw of it, full duration), by bisection."""
    step, top = GRID[kind]
    code = KINDS[kind]["code"]

    def sets(k: int) -> bool:
        rng = random.Random(12345)
        log = tmp / f"cal-{kind}-{k}.log"
        _run_sil(scenario(duration_s, rng, fault_line(kind, k * step)), log, None, None, tmp, f"cal-{kind}-{k}")
        try:
            return code in _codes(log)
        finally:
            log.unlink()
    lo, hi = 0, top  # lo does not set it, hi does
    if not sets(hi):
        raise RuntimeError(f"{kind}: no {code} even at {hi * step:g}")
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if sets(mid):
            hi = mid
        else:
            lo = mid
    return round(hi * step, 6)


def plan_fleet(n_vehicles: int, n_drives: int, seed: int, duration_s: float,
               thr: dict[str, float]) -> list[dict[str, Any]]:
    rng = random.Random(seed)
    kinds: list[str | None] = []
    for kind, share in SHARES:
        kinds += [kind] * max(1, round(share * n_vehicles)) if n_vehicles >= 4 else []
    kinds = kinds[:n_vehicles]
    kinds += [None] * (n_vehicles - len(kinds))
    rng.shuffle(kinds)
    vehicles = []
    for v in range(n_vehicles):
        vid = f"V{v + 1:03d}"
        t = EPOCH + dt.timedelta(days=rng.uniform(0, 3))
        starts = []
        for _ in range(n_drives):
            day = t.replace(hour=0, minute=0, second=0)
            starts.append(day + dt.timedelta(hours=rng.uniform(6.5, 19.0)))
            t = day + dt.timedelta(days=rng.uniform(*DRIVE_GAP_DAYS))
        starts = [s.replace(microsecond=0) for s in starts]
        faults = []
        kind = kinds[v]
        if kind is not None:
            k = KINDS[kind]
            span_days = (starts[-1] - starts[0]).total_seconds() / 86400.0
            per_day_drive = span_days / max(1, n_drives - 1)
            rate = rng.uniform(*k["per_drive"]) / per_day_drive          # magnitude per day
            threshold = thr[kind]
            # the crossing anywhere from the 2nd drive to ~30 % past the last one
            cross = starts[0] + dt.timedelta(days=rng.uniform(0.12, 1.3) * span_days)
            onset = cross - dt.timedelta(days=threshold / rate)
            mags = [max(0.0, rate * (s - onset).total_seconds() / 86400.0) for s in starts]
            if kind == "tps_intermittent":
                mags = [float(round(m)) for m in mags]
            crossing_drive = next((i for i, m in enumerate(mags) if m >= threshold), None)
            faults.append({
                "kind": kind, "fault": k["fault"], "code": k["code"], "parameter": k["parameter"],
                "unit": k["unit"], "threshold": threshold, "onset": onset.isoformat(timespec="seconds"),
                "rate_per_day": rate, "crossing_time": cross.isoformat(timespec="seconds"),
                "crossing_drive": crossing_drive, "magnitudes": mags,
            })
        drives = []
        for i, s in enumerate(starts):
            line = "".join(fault_line(f["kind"], f["magnitudes"][i]) for f in faults)
            drives.append({"index": i, "start": s.isoformat(timespec="seconds"),
                           "file": f"{vid}/{vid}_{s.strftime('%Y%m%dT%H%M%S')}.log.gz",
                           "duration_s": duration_s, "scenario": scenario(duration_s, rng, line)})
        vehicles.append({"vehicle": vid, "faults": faults, "drives": drives})
    return vehicles


def generate_vehicle(v: dict[str, Any], out: Path, tmp_root: Path) -> None:
    tmp = Path(tempfile.mkdtemp(prefix=v["vehicle"] + "-", dir=tmp_root))
    try:
        nvm_prev: Path | None = None
        for d in v["drives"]:
            dst = out / d["file"]
            dst.parent.mkdir(parents=True, exist_ok=True)
            raw = tmp / f"d{d['index']}.log"
            nvm = tmp / f"d{d['index']}.nvm"
            _run_sil(d["scenario"], raw, nvm_prev, nvm, tmp, f"d{d['index']}")
            with raw.open("rb") as f, open(dst, "wb") as fo:
                # mtime 0 and no name in the header: the same drive gives the same bytes
                with gzip.GzipFile(filename="", mode="wb", fileobj=fo, compresslevel=1, mtime=0) as g:
                    shutil.copyfileobj(f, g, 1 << 20)
            raw.unlink()
            nvm_prev = nvm
        (out / "truth").mkdir(exist_ok=True)
        if nvm_prev is not None:
            shutil.copyfile(nvm_prev, out / "truth" / f"{v['vehicle']}.ecu.nvm")
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="canfdi-fleet-gen", description=__doc__.split("\n\n")[0],
                                epilog="The fleet's faults, thresholds and crossings: OUT/truth.json "
                                       "(docs/fleet.md).")
    p.add_argument("-o", "--output", type=Path, required=True, metavar="DIR", help="fleet directory to write")
    p.add_argument("--vehicles", type=int, default=20, metavar="N", help="vehicles (default 20)")
    p.add_argument("--drives", type=int, default=10, metavar="M", help="drives per vehicle (default 10)")
    p.add_argument("--duration", type=float, default=60.0, metavar="S",
                   help="simulated seconds per drive (default 60)")
    p.add_argument("--seed", type=int, default=1, help="seed of everything drawn (default 1)")
    p.add_argument("-j", "--jobs", type=int, default=os.cpu_count() or 1,
                   help="vehicles simulated at once (default: the CPUs)")
    p.add_argument("-q", "--quiet", action="store_true", help="no progress on stderr")
    return p


def main(argv: list[str] | None = None) -> int:
    a = build_parser().parse_args(argv)
    if a.vehicles < 1 or a.drives < 1 or not 10.0 <= a.duration <= 3600.0:
        print("canfdi-fleet-gen: --vehicles and --drives >= 1, --duration 10..3600 s", file=sys.stderr)
        return 2
    for b in (sil_binary(), CORE):
        if not b.exists():
            print(f"canfdi-fleet-gen: {b} is missing: build it with `make all`", file=sys.stderr)
            return 2
    out: Path = a.output
    out.mkdir(parents=True, exist_ok=True)
    tmp_root = Path(tempfile.mkdtemp(prefix="canfdi-fleet-gen-"))
    try:
        cal = calibration_thresholds()
        with ThreadPoolExecutor(max_workers=max(1, a.jobs)) as ex:
            futs = {k: ex.submit(measure_threshold, k, a.duration, tmp_root) for k in KINDS}
            thr = {k: f.result() for k, f in futs.items()}
        vehicles = plan_fleet(a.vehicles, a.drives, a.seed, a.duration, thr)
        done = 0
        with ThreadPoolExecutor(max_workers=max(1, a.jobs)) as ex:
            futs = [ex.submit(generate_vehicle, v, out, tmp_root) for v in vehicles]
            for f in futs:
                f.result()
                done += 1
                if not a.quiet:
                    print(f"canfdi-fleet-gen: {done}/{len(vehicles)} vehicles", file=sys.stderr)
    finally:
        shutil.rmtree(tmp_root, ignore_errors=True)
    with (out / "manifest.csv").open("w", newline="", encoding="utf-8") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(["vehicle", "start", "file"])
        for v in vehicles:
            for d in v["drives"]:
                w.writerow([v["vehicle"], d["start"], d["file"]])
    truth = {
        "schema": "canfdi-fleet-truth/1", "seed": a.seed, "vehicles_n": a.vehicles, "drives_n": a.drives,
        "drive_duration_s": a.duration,
        "thresholds": {k: {"value": thr[k], "unit": KINDS[k]["unit"], "parameter": KINDS[k]["parameter"],
                           "defined_by": "the smallest magnitude that sets the code in one drive of the drive "
                                         "template, measured with canfdi-sil by bisection",
                           "calibration_threshold": cal.get(k),
                           "calibration_defined_by": ("the firmware's diagnosis threshold on the estimated "
                                                      "parameter's relative deviation (canfdi_app_default_cal, "
                                                      "the replay core's hdr)") if k in cal else None}
                       for k in KINDS},
        "vehicles": [{"vehicle": v["vehicle"], "faults": v["faults"],
                      "drives": [{k: d[k] for k in ("index", "start", "file", "duration_s")} for d in v["drives"]]}
                     for v in vehicles],
    }
    (out / "truth.json").write_text(json.dumps(truth, indent=1) + "\n", encoding="utf-8")
    if not a.quiet:
        print(f"canfdi-fleet-gen: {a.vehicles} vehicles x {a.drives} drives in {out} "
              f"(manifest.csv, truth.json)", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
