"""make bench-replay-jitter: canfdi-replay on fault recordings stamped as a real logger stamps them.

Every SIL fault scenario whose run is all on the bus (tests/sil/scenarios
and tests/sil/matrix with a fault line, at most 60 s) is recorded, its time
stamps re-made by tests/replay/conftest.py's jitter_log (a seeded uniform
jitter on every frame, the logger's clock drifting against the sensor
nodes', the file's order kept) and replayed with --clock timestamps. The
replay's findings are compared with the codes the recorded ECU reported
(decoded from the log by canfdi.timeline): same, missed (the ECU's, not
found) and wrong extra (found, not the ECU's), summed over the logs; also
the logs with exactly the ECU's codes, the logs replayed frame for frame,
the seconds the model monitors were not judged for a late or early sensor
frame ("re-arming") and the grid's moves. Prints a table and writes
build/bench/replay_jitter.json; never fails on a figure.

    python bench/bench_replay_jitter.py --out build/bench/replay_jitter.json [--core BIN]
"""
from __future__ import annotations

import argparse
import json
import re
import subprocess
import sys
import tempfile
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tools"))
sys.path.insert(0, str(ROOT / "tests" / "replay"))

from canfdi.replay_report import Report  # noqa: E402
from conftest import MATRIX, SCENARIOS, jitter_log, make_sil_log, recorded_first_failed, replayable  # noqa: E402

CORE = ROOT / "build" / "bin" / "canfdi-replay-core"
#: (jitter +-us, logger clock drift ppm); (0, 0) is the recording's own time stamps (moved to an epoch)
CONDITIONS = ((0, 0), (10, 0), (200, 0), (300, 100), (300, -100))
MODEL_MONITORS = ("dcm_models", "dcm_cmd", "thr_models", "thr_tracking")


def fault_scenarios() -> list[Path]:
    return [s for s in SCENARIOS + MATRIX
            if replayable(s) and re.search(r"^\s*fault\s", s.read_text(), re.M)]


def replay(core: Path, log: Path) -> Report:
    r = subprocess.run([str(core), "--clock", "timestamps", str(log)], capture_output=True, text=True,
                       check=True)
    rep = Report()
    for line in r.stdout.splitlines():
        rep.feed(json.loads(line))
    return rep


def one(core: Path, log: Path, jitter_us: int, ppm: int, seed: int, tmp: Path) -> dict[str, Any]:
    jit = jitter_log(log, tmp / f"{log.stem}.{jitter_us}.{ppm}.log", jitter_us, ppm, seed)
    rep = replay(core, jit)
    jit.unlink()
    want = set(recorded_first_failed(log))
    found = {f["code"] for f in rep.findings()}
    lg = rep.logs[0]
    rearm = sum(s.t1 - s.t0 for m in MODEL_MONITORS for s in lg.untested_spans(m) if s.why.startswith("re-arming"))
    return {"log": log.stem, "same": sorted(want & found), "missed": sorted(want - found),
            "wrong": sorted(found - want), "frame_for_frame": lg.agree.get("mismatched") == 0,
            "rearming_s": round(rearm, 3), "grid_moves": int(lg.eof.get("grid_moves", 0))}


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--out", type=Path, required=True)
    p.add_argument("--core", type=Path, default=CORE, help="the replay core (default: build/bin/canfdi-replay-core)")
    a = p.parse_args(argv)
    scns = fault_scenarios()
    with ThreadPoolExecutor(max_workers=2) as ex:
        logs = list(ex.map(make_sil_log, scns))
    result: dict[str, Any] = {"core": str(a.core), "fault_logs": len(logs),
                              "incipient": sum("incipient" in s.stem for s in scns), "conditions": []}
    with tempfile.TemporaryDirectory() as tmp:
        for jitter_us, ppm in CONDITIONS:
            with ThreadPoolExecutor(max_workers=2) as ex:
                runs = list(ex.map(lambda il: one(a.core, il[1], jitter_us, ppm, il[0] + 1, Path(tmp)),
                                   enumerate(logs)))
            result["conditions"].append({
                "jitter_us": jitter_us, "ppm": ppm,
                "same": sum(len(r["same"]) for r in runs), "missed": sum(len(r["missed"]) for r in runs),
                "wrong": sum(len(r["wrong"]) for r in runs),
                "logs_right": sum(not r["missed"] and not r["wrong"] for r in runs),
                "logs_frame_for_frame": sum(r["frame_for_frame"] for r in runs),
                "rearming_s": round(sum(r["rearming_s"] for r in runs), 1),
                "grid_moves": sum(r["grid_moves"] for r in runs),
                "differing": [r for r in runs if r["missed"] or r["wrong"]]})
    a.out.parent.mkdir(parents=True, exist_ok=True)
    a.out.write_text(json.dumps(result, indent=1) + "\n")
    print(f"bench-replay-jitter: {len(logs)} SIL fault recordings ({result['incipient']} incipient), "
          f"re-stamped and replayed with --clock timestamps ({a.core.name})")
    print(f"  {'jitter us':>9} {'ppm':>5} {'same':>5} {'missed':>6} {'wrong':>5} {'logs right':>10} "
          f"{'frame=frame':>11} {'re-arming s':>11} {'moves':>6}")
    for c in result["conditions"]:
        print(f"  {c['jitter_us']:9d} {c['ppm']:5d} {c['same']:5d} {c['missed']:6d} {c['wrong']:5d} "
              f"{c['logs_right']:10d} {c['logs_frame_for_frame']:11d} {c['rearming_s']:11.1f} {c['grid_moves']:6d}")
    print(f"  (same / missed / wrong extra: codes against the recorded ECU's, summed over the logs; "
          f"re-arming s: model monitors not judged for a late or early sensor frame, summed)")
    print(f"  written {a.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
