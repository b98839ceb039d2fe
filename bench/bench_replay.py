"""make bench-replay: canfdi-replay against what a user would otherwise run on a log.

On the same one-hour candump recording (bench/replay_1h.scn, written by the
release SIL runner), one after the other in one run, each pinned to one core
(taskset -c 0) in a process of its own:

  replay      canfdi-replay LOG --json (the full diagnosis: the C core with
              the firmware, and the Python front end folding its events)
  read        python-can's LogReader merely reading the file
  decode      LogReader + cantools decoding every frame of dbc/canfdi.dbc

For each: frames per second and times real time (log seconds per second),
on the wall clock and on the CPU time the process and its children used
(the machine may be shared: the CPU figure is the one-core figure), and
the replay's speed-up over the other two from the same run, and whether the
replay is the recorded run (the recording starts at the ECU's power-up:
every recorded ECU frame identical, the same codes at the same times).
Prints a table and writes build/bench/replay.json; never fails on a figure.

    python bench/bench_replay.py --log build/bench/replay-1h.log --out build/bench/replay.json
"""
from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PY = ROOT / ".venv" / "bin" / "python"
REPLAY = ROOT / ".venv" / "bin" / "canfdi-replay"

READ = """
import can, sys
n = 0
for m in can.LogReader(sys.argv[1]):
    n += 1
print(n)
"""
DECODE = """
import can, cantools, sys
db = cantools.database.load_file(sys.argv[2])
ids = {m.frame_id for m in db.messages}
n = d = 0
for m in can.LogReader(sys.argv[1]):
    n += 1
    if m.arbitration_id in ids and not m.is_error_frame and not m.is_remote_frame:
        try:
            db.decode_message(m.arbitration_id, m.data)
            d += 1
        except Exception:
            pass
print(n, d)
"""


def timed(cmd: list[str]) -> tuple[float, float, str]:
    """(wall s, CPU s of the child and its children, stdout) of one command pinned to core 0."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.monotonic()
    r = subprocess.run(["taskset", "-c", "0", *cmd], capture_output=True, text=True)
    wall = time.monotonic() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if r.returncode not in (0, 1):
        raise RuntimeError(f"{cmd[0]} failed ({r.returncode}): {r.stderr.strip()[-500:]}")
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return wall, cpu, r.stdout


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--log", type=Path, required=True, help="the candump recording (one hour)")
    p.add_argument("--out", type=Path, required=True, help="JSON result")
    a = p.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmp:
        js = Path(tmp) / "replay.json"
        wall_r, cpu_r, out = timed([str(REPLAY), "-q", "--no-progress", "--json", str(js), str(a.log)])
        doc = json.loads(js.read_text())
    lg = doc["logs"][0]
    frames = int(lg["frames"])
    log_s = float(lg["last_s"]) - float(lg["first_s"]) + 0.001
    wall_p, cpu_p, out_p = timed([str(PY), "-c", READ, str(a.log)])
    wall_d, cpu_d, out_d = timed([str(PY), "-c", DECODE, str(a.log), str(ROOT / "dbc" / "canfdi.dbc")])
    assert int(out_p.split()[0]) == frames == int(out_d.split()[0]), "the three did not read the same frames"
    rows = {
        "replay": {"what": "canfdi-replay --json (full diagnosis, candump input)", "wall_s": wall_r, "cpu_s": cpu_r},
        "read": {"what": "python-can LogReader reading the file", "wall_s": wall_p, "cpu_s": cpu_p},
        "decode": {"what": "python-can LogReader + cantools decode_message", "wall_s": wall_d, "cpu_s": cpu_d,
                   "frames_decoded": int(out_d.split()[1])},
    }
    for r in rows.values():
        r["frames_per_s_wall"] = frames / r["wall_s"]
        r["frames_per_s_cpu"] = frames / r["cpu_s"]
        r["x_real_time_wall"] = log_s / r["wall_s"]
        r["x_real_time_cpu"] = log_s / r["cpu_s"]
    result = {
        "log": str(a.log), "frames": frames, "log_seconds": round(log_s, 3),
        "log_bytes": a.log.stat().st_size, "pinned_to_core": 0,
        "findings": [f["code"] for f in doc["dtcs"]],
        # the recording starts at the recorded ECU's power-up: the replay is that run frame for frame
        "start": lg["start"], "recorded_ecu": lg["recorded_ecu"],
        "codes_as_recorded": not doc["recorded_ecu_only"] and all(
            f["recorded_ecu_first_failed_s"] is not None and abs(f["recorded_ecu_first_failed_s"] - f["first_failed_s"])
            < 1e-6 for f in doc["dtcs"]),
        "rows": rows,
        "replay_over_read_cpu": cpu_p / cpu_r, "replay_over_read_wall": wall_p / wall_r,
        "replay_over_decode_cpu": cpu_d / cpu_r, "replay_over_decode_wall": wall_d / wall_r,
        "goals": {"faster_than_read": cpu_r < cpu_p and wall_r < wall_p,
                  "at_least_300x_real_time_on_one_core": log_s / cpu_r >= 300.0},
        "load_average": os.getloadavg(),
    }
    a.out.parent.mkdir(parents=True, exist_ok=True)
    a.out.write_text(json.dumps(result, indent=1) + "\n")
    print(f"bench-replay: {frames} frames, {log_s:.0f} s of log ({a.log.stat().st_size / 1e6:.0f} MB), "
          f"one core each, load average {os.getloadavg()[0]:.1f}")
    print(f"  {'':8} {'wall s':>8} {'cpu s':>8} {'frames/s (cpu)':>15} {'x real time (cpu)':>18} "
          f"{'x real time (wall)':>19}")
    for k, r in rows.items():
        print(f"  {k:8} {r['wall_s']:8.1f} {r['cpu_s']:8.1f} {r['frames_per_s_cpu']:15,.0f} "
              f"{r['x_real_time_cpu']:18.0f} {r['x_real_time_wall']:19.0f}   {r['what']}")
    print(f"  replay / read: {result['replay_over_read_cpu']:.1f}x faster (cpu), "
          f"{result['replay_over_read_wall']:.1f}x (wall); replay / decode: {result['replay_over_decode_cpu']:.1f}x "
          f"(cpu), {result['replay_over_decode_wall']:.1f}x (wall); findings {', '.join(result['findings'])}")
    ecu = result["recorded_ecu"]
    print(f"  start {result['start']}: recorded ECU {ecu['identical']} of its {ecu['frames']} frames identical, "
          f"codes {'as' if result['codes_as_recorded'] else 'NOT as'} the recorded ECU's at the same times")
    print(f"  written {a.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
