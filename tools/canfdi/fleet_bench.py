"""make bench-fleet: canfdi-fleet over one fleet with 1 and with 2 local Dask workers, side by side.

  python -m canfdi.fleet_bench FLEET_DIR OUT.json

Each run starts from nothing (--force, its own results directory) and is timed on the wall clock
from the command's start to its end (the local cluster's start and the Parquet and report writing
included). Figures: wall seconds, logs per second, operating hours diagnosed per wall second,
the speed-up of 2 workers over 1. Never fails on a figure.
"""
from __future__ import annotations

import json
import os
import platform
import shutil
import subprocess
import sys
import time
from pathlib import Path


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    fleet, out_json = Path(argv[0]), Path(argv[1])
    runs = []
    for workers in (1, 2):
        out = out_json.parent / f"fleet_bench_w{workers}"
        shutil.rmtree(out, ignore_errors=True)
        load0 = os.getloadavg()[0]
        t0 = time.perf_counter()
        r = subprocess.run([sys.executable, "-m", "canfdi.fleet", "-q", str(fleet / "manifest.csv"), "-o", str(out),
                            "--workers", str(workers), "--force"], capture_output=True, text=True)
        wall = time.perf_counter() - t0
        run = json.loads((out / "fleet_run.json").read_text(encoding="utf-8"))
        runs.append({"workers": workers, "exit": r.returncode, "wall_s": round(wall, 2),
                     "tasks_wall_s": run["wall_s"], "logs": run["logs"], "failed": len(run["failed"]),
                     "operating_h": round(run["operating_h"], 4),
                     "operating_h_per_wall_s": round(run["operating_h"] / wall, 4),
                     "realtime_factor": round(run["operating_h"] * 3600.0 / wall, 1),
                     "logs_per_s": round(run["logs"] / wall, 2),
                     "load_avg_1min_before_after": [round(load0, 2), round(os.getloadavg()[0], 2)]})
        print(f"bench-fleet: {workers} worker(s): {run['logs']} logs, {run['operating_h']:.2f} operating h in "
              f"{wall:.1f} s wall: {runs[-1]['operating_h_per_wall_s']:.3f} h per s "
              f"({runs[-1]['realtime_factor']:.0f}x real time)")
        shutil.rmtree(out, ignore_errors=True)
    speedup = runs[0]["wall_s"] / runs[1]["wall_s"] if runs[1]["wall_s"] else None
    doc = {"bench": "fleet", "fleet": str(fleet), "cpus": os.cpu_count(), "machine": platform.machine(),
           "runs": runs, "speedup_2_over_1": round(speedup, 2) if speedup else None,
           "note": "each run from nothing (--force), wall clock of the whole command incl. the local "
                   "cluster's start-up, Parquet and report; the machine is shared, figures depend on its load"}
    out_json.parent.mkdir(parents=True, exist_ok=True)
    out_json.write_text(json.dumps(doc, indent=1) + "\n", encoding="utf-8")
    print(f"bench-fleet: 2 workers / 1 worker speed-up {doc['speedup_2_over_1']} ({out_json})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
