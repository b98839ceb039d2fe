"""canfdi-fleet's results on a synthetic fleet against the fleet's ground truth (canfdi-fleet-gen).

  python -m canfdi.fleet_acceptance FLEET_DIR OUT_DIR [--json FILE]

Checks, per vehicle (docs/fleet.md, "Acceptance"):
  found      every developing fault's code is found in that vehicle, first in the drive where its
             magnitude first reached the threshold, +/- 1 drive (a fault that has not reached it by
             the last drive counts as crossing in the drive after it)
  false      no code in a fault-free vehicle, no code other than its fault's in a faulty one
  rul        a drifting parameter's projected crossing (fleet report) within its stated +/- 2 sigma
             of the true crossing time
  memory     the DTC memory (NVM image) after the vehicle's last drive from the chain of one-drive
             tasks equals one canfdi-replay-core run over all its drives in sequence, and the
             vehicle ECU's own image (the generator's canfdi-sil runs)
Prints a table and the figures; exit 0 when every check passes, 1 otherwise.
"""
from __future__ import annotations

import argparse
import datetime as dt
import json
import subprocess
import sys
import tempfile
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Any

from .fleet_report import analyse

PARAM_OF = {"ra_creep": "R_A", "spring_weak": "spring"}


def long_replay(fleet: Path, v: dict[str, Any], tmp: Path) -> bytes:
    from .replay import _core_binary
    img = tmp / f"{v['vehicle']}.nvm"
    cmd = [str(_core_binary()), "--nvm-out", str(img)] + [str(fleet / d["file"]) for d in v["drives"]]
    subprocess.run(cmd, stdout=subprocess.DEVNULL, check=True)
    return img.read_bytes()


def check(fleet: Path, out: Path, memory: bool = True) -> dict[str, Any]:
    truth = json.loads((fleet / "truth.json").read_text(encoding="utf-8"))
    a = analyse(out)
    rows = []
    trends = {(t["vehicle"], t["parameter"]): t for t in a["trends"]}
    longs: dict[str, bytes] = {}
    if memory:
        with tempfile.TemporaryDirectory(prefix="canfdi-fleet-acc-") as td, ThreadPoolExecutor(2) as ex:
            futs = {v["vehicle"]: ex.submit(long_replay, fleet, v, Path(td)) for v in truth["vehicles"]}
            longs = {k: f.result() for k, f in futs.items()}
    for v in truth["vehicles"]:
        veh = v["vehicle"]
        n = len(v["drives"])
        found = a["first_drive"].get(veh, {})
        row: dict[str, Any] = {"vehicle": veh, "faults": [], "other_codes": [], "ok": True}
        expected = set()
        for f in v["faults"]:
            expected.add(f["code"])
            cross = f["crossing_drive"] if f["crossing_drive"] is not None else n
            first = found.get(f["code"])
            fr: dict[str, Any] = {"kind": f["kind"], "code": f["code"], "crossing_drive": f["crossing_drive"],
                                  "found_drive": first}
            if first is None:
                fr["detect"] = "not yet crossed, not found" if cross >= n else "MISSED"
                fr["drive_error"] = None
                fr["ok"] = cross >= n
            else:
                fr["drive_error"] = first - cross
                fr["ok"] = abs(first - cross) <= 1
                fr["detect"] = "found" if fr["ok"] else "found in the wrong drive"
            par = PARAM_OF.get(f["kind"])
            t = trends.get((veh, par)) if par else None
            if par:
                true_t = dt.datetime.fromisoformat(f["crossing_time"])
                if t is not None and t["drifting"]:
                    c = t["crossing"]
                    proj = dt.datetime.fromisoformat(c["time"])
                    err = (proj - true_t).total_seconds() / 86400.0
                    fr["rul"] = {"projected": c["time"], "true": f["crossing_time"], "error_days": round(err, 2),
                                 "two_sigma_days": round(2 * c["sigma_days"], 2),
                                 "within": abs(err) <= 2 * c["sigma_days"]}
                    fr["ok"] = fr["ok"] and fr["rul"]["within"]
                else:
                    fr["rul"] = {"projected": None, "true": f["crossing_time"],
                                 "why": "not drifting by the report's rule" if t else "no track"}
            row["faults"].append(fr)
            row["ok"] = row["ok"] and fr["ok"]
        row["other_codes"] = sorted(set(found) - expected)
        if row["other_codes"]:
            row["ok"] = False
        if memory:
            runs = sorted((out / "work" / veh).glob("*.nvm"))
            chain = runs[-1].read_bytes() if runs else b""
            ecu_p = fleet / "truth" / f"{veh}.ecu.nvm"
            row["memory_chain_eq_long"] = chain == longs[veh]
            row["memory_chain_eq_ecu"] = ecu_p.exists() and chain == ecu_p.read_bytes()
            row["ok"] = row["ok"] and row["memory_chain_eq_long"] and row["memory_chain_eq_ecu"]
        rows.append(row)
    faults = [f for r in rows for f in r["faults"]]
    ruls = [f["rul"] for f in faults if f.get("rul", {}).get("projected")]
    summary = {
        "vehicles": len(rows), "drives": truth["drives_n"], "seed": truth["seed"],
        "faults": len(faults), "found_in_window": sum(1 for f in faults if f["ok"] or f.get("detect") == "found"),
        "missed": sum(1 for f in faults if f["detect"] == "MISSED"),
        "wrong_drive": sum(1 for f in faults if f["detect"] == "found in the wrong drive"),
        "not_yet_crossed": sum(1 for f in faults if f["detect"].startswith("not yet")),
        "false_codes": sum(len(r["other_codes"]) for r in rows),
        "drive_errors": sorted(f["drive_error"] for f in faults if f["drive_error"] is not None),
        "rul_projected": len(ruls), "rul_within": sum(1 for r in ruls if r["within"]),
        "rul_errors_days": [r["error_days"] for r in ruls],
        "memory_equal_long": sum(1 for r in rows if r.get("memory_chain_eq_long")) if memory else None,
        "memory_equal_ecu": sum(1 for r in rows if r.get("memory_chain_eq_ecu")) if memory else None,
        "passed": all(r["ok"] for r in rows),
    }
    return {"summary": summary, "vehicles": rows, "thresholds": truth["thresholds"]}


def print_table(res: dict[str, Any]) -> None:
    print(f"{'vehicle':7} {'fault':17} {'code':5} {'cross':>5} {'found':>5} {'err':>4}  {'RUL error / 2σ [d]':18} "
          f"{'memory':8} other codes")
    for r in res["vehicles"]:
        mem = ("=" if r.get("memory_chain_eq_long") and r.get("memory_chain_eq_ecu") else "DIFFERS") \
            if "memory_chain_eq_long" in r else "-"
        other = ",".join(r["other_codes"]) or "-"
        if not r["faults"]:
            print(f"{r['vehicle']:7} {'(fault-free)':17} {'-':5} {'-':>5} {'-':>5} {'-':>4}  {'-':18} {mem:8} {other}")
        for f in r["faults"]:
            cd = "-" if f["crossing_drive"] is None else f["crossing_drive"] + 1
            fd = "-" if f["found_drive"] is None else f["found_drive"] + 1
            err = "-" if f["drive_error"] is None else f"{f['drive_error']:+d}"
            rul = f.get("rul") or {}
            rs = (f"{rul['error_days']:+.1f} / {rul['two_sigma_days']:.1f} {'ok' if rul['within'] else 'OUT'}"
                  if rul.get("projected") else (rul.get("why", "-")[:18] if rul else "-"))
            print(f"{r['vehicle']:7} {f['kind']:17} {f['code']:5} {cd!s:>5} {fd!s:>5} {err:>4}  {rs:18} {mem:8} {other}")
    s = res["summary"]
    print(f"faults {s['faults']}: in window {s['found_in_window']}, missed {s['missed']}, wrong drive "
          f"{s['wrong_drive']}, not yet crossed {s['not_yet_crossed']}; false codes {s['false_codes']}; "
          f"drive errors {s['drive_errors']}; RUL within 2σ {s['rul_within']}/{s['rul_projected']} "
          f"(errors {s['rul_errors_days']} d); memory chain = long replay {s['memory_equal_long']}/{s['vehicles']}, "
          f"= vehicle ECU {s['memory_equal_ecu']}/{s['vehicles']}: {'PASSED' if s['passed'] else 'FAILED'}")


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="python -m canfdi.fleet_acceptance", description=__doc__.split("\n\n")[0])
    p.add_argument("fleet", type=Path, help="the fleet directory (canfdi-fleet-gen -o)")
    p.add_argument("out", type=Path, help="canfdi-fleet's results directory (-o)")
    p.add_argument("--json", type=Path, help="write the figures here")
    p.add_argument("--no-memory", action="store_true", help="skip the long replays")
    a = p.parse_args(argv)
    res = check(a.fleet, a.out, memory=not a.no_memory)
    print_table(res)
    if a.json:
        a.json.parent.mkdir(parents=True, exist_ok=True)
        a.json.write_text(json.dumps(res, indent=1) + "\n", encoding="utf-8")
    return 0 if res["summary"]["passed"] else 1


if __name__ == "__main__":
    sys.exit(main())
