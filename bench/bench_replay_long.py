"""make bench-replay-long: canfdi-replay from power-up on the SIL scenarios too long for make test.

tests/replay replays every SIL scenario whose run is all on the bus and at
most 60 s long (tests/replay/conftest.py). The longer ones (drives of ten
minutes, resistance creeps over half an hour, the freeze frame after more
than an hour) are recorded here by the release SIL runner, one at a time,
and replayed with canfdi-replay (candump input, the full diagnosis). Each
must be the recorded run frame for frame: a power-up start, every recorded
ECU frame identical to the replay's, and the replay's codes exactly the
recorded ECU's at the same times. Prints a table (DIFFERS and what, for
a recording that is not) and writes build/bench/replay_long.json
(all_frame_for_frame); like every bench, never fails on what it measures.

    python bench/bench_replay_long.py --sil build/bench/canfdi-sil-rel --out build/bench/replay_long.json
"""
from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tools"))
sys.path.insert(0, str(ROOT / "tests" / "replay"))

from canfdi.logio import read_log  # noqa: E402
from canfdi.timeline import Timeline  # noqa: E402
from conftest import MAX_DURATION_S, SCENARIOS, duration_s, has_ecu_actions  # noqa: E402

REPLAY = ROOT / ".venv" / "bin" / "canfdi-replay"


def long_scenarios() -> list[Path]:
    """The SIL scenarios all on the bus that tests/replay leaves out for their length."""
    return [s for s in SCENARIOS if not has_ecu_actions(s) and duration_s(s) > MAX_DURATION_S]


def check(scn: Path, sil: Path, tmp: Path) -> dict:
    log = tmp / f"{scn.stem}.log"
    js = tmp / f"{scn.stem}.json"
    subprocess.run([str(sil), "-q", "-s", str(scn), "-l", str(log)], stdout=subprocess.DEVNULL, check=True,
                   cwd=ROOT)
    t0 = time.monotonic()
    r = subprocess.run([str(REPLAY), "-q", "--no-progress", "--json", str(js), str(log)], capture_output=True,
                       text=True)
    wall = time.monotonic() - t0
    try:
        if r.returncode not in (0, 1):
            return {"scenario": scn.name, "ok": False, "problems": [f"exit {r.returncode}: {r.stderr.strip()}"]}
        doc = json.loads(js.read_text())
        tl = Timeline().feed_all(read_log(log))
    finally:
        log.unlink(missing_ok=True)
    lg = doc["logs"][0]
    ecu = lg["recorded_ecu"]
    want = {c: round(d.first_failed_us * 1e-6, 6) for c, d in tl.dtcs.items() if d.first_failed_us >= 0}
    got = {f["code"]: f["first_failed_s"] for f in doc["dtcs"]}
    problems = []
    if lg["start"] != "power-up":
        problems.append(f"start {lg['start']}")
    if not (ecu["frames"] and ecu["identical"] == ecu["frames"] and ecu["replay_only"] == 0):
        problems.append(f"recorded ECU frames {ecu}")
    if set(got) != set(want) or any(abs(got[c] - want[c]) > 1e-6 for c in want):
        problems.append(f"codes {got} != recorded {want}")
    return {"scenario": scn.name, "ok": not problems, "problems": problems, "log_s": lg["last_s"],
            "frames": lg["frames"], "recorded_ecu_frames": ecu["frames"], "identical": ecu["identical"],
            "codes": got, "recorded_codes": want, "replay_wall_s": round(wall, 2)}


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--sil", type=Path, required=True, help="the SIL runner that records the scenarios")
    p.add_argument("--out", type=Path, required=True)
    a = p.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmp:
        rows = [check(s, a.sil, Path(tmp)) for s in long_scenarios()]
    result = {"scenarios": len(rows), "all_frame_for_frame": all(r["ok"] for r in rows), "runs": rows}
    a.out.parent.mkdir(parents=True, exist_ok=True)
    a.out.write_text(json.dumps(result, indent=1) + "\n")
    print(f"bench-replay-long: {len(rows)} SIL recordings longer than {MAX_DURATION_S:g} s, replayed from power-up")
    for r in rows:
        if "frames" in r:
            print(f"  {r['scenario']:32} {r['log_s']:8.0f} s {r['frames']:9d} frames  ECU frames "
                  f"{r['identical']}/{r['recorded_ecu_frames']} identical  codes "
                  f"{', '.join(f'{c} {t:.3f}' for c, t in sorted(r['codes'].items())) or 'none'}"
                  f"{'' if r['ok'] else '  DIFFERS: ' + '; '.join(r['problems'])}")
        else:
            print(f"  {r['scenario']:32} FAILED: {'; '.join(r['problems'])}")
    print(f"  written {a.out}")
    print("  every recording replays frame for frame" if result["all_frame_for_frame"]
          else "  NOT every recording replays frame for frame")
    return 0


if __name__ == "__main__":
    sys.exit(main())
