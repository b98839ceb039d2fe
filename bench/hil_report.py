"""bench/hil_report.py RAW_DIR OUT.json — the HIL figures of bench/hil_bench.sh
(statistics written by canfdi-ecu and canfdi-sim) as one JSON file and a
short table on stdout. Prints figures; never fails a test run."""
from __future__ import annotations

import json
import platform
import sys
from pathlib import Path


def load(raw: Path, name: str) -> dict:
    p = raw / f"{name}.json"
    return json.loads(p.read_text()) if p.exists() else {}


def main(argv: list[str]) -> int:
    if len(argv) != 3:
        print(__doc__, file=sys.stderr)
        return 2
    raw, out = Path(argv[1]), Path(argv[2])
    res: dict = {"where": "tools/vcan-run (User-Mode Linux unless the host has vcan)",
                 "host": platform.node(), "lockstep": {}, "realtime": {}}
    for name in ("lockstep", "lockstep-rec"):
        sim, ecu = load(raw, f"{name}-sim"), load(raw, f"{name}-ecu")
        if sim:
            res["lockstep"][name.replace("-", "_")] = {
                "recorder": "candump -L (whole bus)" if name.endswith("rec") else "none",
                "steps": sim.get("steps"), "wall_s": sim.get("wall_s"),
                "steps_per_s": sim.get("steps_per_s"), "ecu_wait_us": sim.get("wait_us"),
                "ecu_step_us": ecu.get("step_us"), "lockstep_gaps": ecu.get("lockstep_gaps")}
    sim, ecu = load(raw, "realtime-sim"), load(raw, "realtime-ecu")
    if ecu:
        res["realtime"] = {
            "run_s": ecu.get("run_s"), "ecu_steps": ecu.get("steps"),
            "ecu_deadline_misses": ecu.get("deadline_misses"),
            "ecu_skipped_periods": ecu.get("skipped_periods"),
            "ecu_latency_us": ecu.get("latency_us"), "ecu_step_us": ecu.get("step_us"),
            "sim_steps": sim.get("steps"), "sim_late_steps": sim.get("late_steps"),
            "sim_late_us_max": sim.get("late_us_max"),
            "frames_rejected": ecu.get("frames_rejected")}
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(res, indent=2) + "\n")
    print(f"bench-hil: {out}")
    for k, v in res["lockstep"].items():
        print(f"  lockstep ({v['recorder']}): {v['steps_per_s']} steps/s "
              f"({v['steps']} steps in {v['wall_s']} s), ECU answer mean {v['ecu_wait_us']['mean']} us")
    rt = res["realtime"]
    if rt:
        lat, st = rt["ecu_latency_us"] or {}, rt["ecu_step_us"] or {}
        print(f"  realtime {rt['run_s']} s: ECU {rt['ecu_steps']} steps, deadline misses "
              f"{rt['ecu_deadline_misses']}, wake-up latency p50 {lat.get('p50')} / p99.9 "
              f"{lat.get('p999')} / max {lat.get('max')} us, step time p99.9 {st.get('p999')} us; "
              f"sim late steps {rt['sim_late_steps']} (max {rt['sim_late_us_max']} us)")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
