"""make bench-replay-settle: the settling time canfdi-replay states, measured.

Every SIL scenario recording (tests/sil/scenarios and tests/sil/matrix whose
runs are all on the bus) is cut at several points mid-run and replayed with
settling times of 2..6 s. A run agrees when the replay's findings are
exactly the codes the recorded ECU had failing from the time each code is
judged on (the frame and range checks at once, the models after the
settling time), codes the replay lists as not fully judged aside. The
smallest settling time at which every run agrees is what the replay's
default (5 s) rests on. Prints a table and writes
build/bench/replay_settle.json; never fails on a figure.

    python bench/bench_replay_settle.py --sil build/bench/canfdi-sil-rel --out build/bench/replay_settle.json
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

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tools"))

from canfdi.logio import read_log  # noqa: E402
from canfdi.replay_report import CODE_MONITORS, Report  # noqa: E402
from canfdi.timeline import Timeline  # noqa: E402

CORE = ROOT / "build" / "bin" / "canfdi-replay-core"
CUTS = (0.3, 1.2, 2.2, 4.0, 6.0)
SETTLES = (2.0, 3.0, 4.0, 5.0, 6.0)
NO_SETTLING = {"com_dcm", "com_thr", "tps_range"}


def scenarios() -> list[Path]:
    out = []
    for p in sorted((ROOT / "tests" / "sil" / "scenarios").glob("*.scn")) + sorted(
            (ROOT / "tests" / "sil" / "matrix").glob("*.scn")):
        text = p.read_text()
        m = re.search(r"^\s*duration\s+(\S+)", text, re.M)
        if p.name == "demo.scn" or re.search(r"^\s*(cycle|clear|power_cycle)\b", text, re.M) or \
                not m or float(m.group(1)) > 60:
            continue
        out.append(p)
    return out


def active_after(tl: Timeline, code: str, t_s: float) -> bool:
    rec = tl.dtcs.get(code)
    if rec is None:
        return False
    t_us = round(t_s * 1e6)
    at = rec.state_at(t_us)
    return bool((at is not None and at[1] & 1) or any(h[0] >= t_us and h[1] & 1 for h in rec.history))


def replay(log: Path, settle_s: float) -> Report:
    r = subprocess.run([str(CORE), "--settle-ms", str(round(settle_s * 1000)), str(log)],
                       capture_output=True, text=True, check=True)
    rep = Report()
    for line in r.stdout.splitlines():
        rep.feed(json.loads(line))
    return rep


def judge(rep: Report, tl: Timeline, cut: float, settle: float) -> tuple[list[str], list[str]]:
    """(codes found that the ECU did not have failing, codes it had that were not found)."""
    def judged_from(code: str) -> float:
        return cut if set(CODE_MONITORS[code]) <= NO_SETTLING else cut + settle
    found = {f["code"] for f in rep.findings()}
    want = {c for c in set(found) | set(tl.dtcs) if active_after(tl, c, judged_from(c))}
    unjudged = {r["code"] for r in rep.recorded_only() if not r["judged"]}
    return sorted(found - want), sorted(want - found - unjudged)


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--sil", type=Path, required=True, help="the SIL runner that records the scenarios")
    p.add_argument("--out", type=Path, required=True)
    a = p.parse_args(argv)
    scns = scenarios()
    with tempfile.TemporaryDirectory() as tmp:
        def record(scn: Path) -> Path:
            log = Path(tmp) / f"{scn.parent.name}_{scn.stem}.log"
            subprocess.run([str(a.sil), "-q", "-s", str(scn), "-l", str(log)], stdout=subprocess.DEVNULL,
                           check=False, cwd=ROOT)
            return log
        with ThreadPoolExecutor(max_workers=2) as ex:
            logs = list(ex.map(record, scns))
        table = {s: {"runs": 0, "agree": 0, "differ": []} for s in SETTLES}
        for scn, log in zip(scns, logs):
            tl = Timeline().feed_all(read_log(log))
            lines = log.read_text().splitlines(keepends=True)
            dur = float(lines[-1][1:lines[-1].index(")")])
            for cut in CUTS:
                cut_log = Path(tmp) / "cut.log"
                cut_log.write_text("".join(x for x in lines if float(x[1:x.index(")")]) >= cut))
                for settle in SETTLES:
                    if cut + settle + 0.5 > dur:
                        continue
                    extra, missed = judge(replay(cut_log, settle), tl, cut, settle)
                    row = table[settle]
                    row["runs"] += 1
                    if extra or missed:
                        row["differ"].append({"scenario": scn.name, "cut_s": cut, "found_not_failing": extra,
                                              "failing_not_found": missed})
                    else:
                        row["agree"] += 1
            log.unlink()
    ok = [s for s in SETTLES if table[s]["runs"] and not table[s]["differ"]]
    result = {"cuts_s": CUTS, "scenarios": len(scns),
              "settling": {f"{s:g}": table[s] for s in SETTLES},
              "smallest_settling_all_agree_s": min(ok) if ok else None}
    a.out.parent.mkdir(parents=True, exist_ok=True)
    a.out.write_text(json.dumps(result, indent=1) + "\n")
    print(f"bench-replay-settle: {len(scns)} SIL recordings cut at {', '.join(f'{c:g}' for c in CUTS)} s")
    print(f"  {'settling s':>10} {'runs':>6} {'agree':>6}  first differences")
    for s in SETTLES:
        row = table[s]
        first = "; ".join(f"{d['scenario']} cut {d['cut_s']:g}: +{d['found_not_failing']} -{d['failing_not_found']}"
                          for d in row["differ"][:3])
        print(f"  {s:10g} {row['runs']:6d} {row['agree']:6d}  {first}")
    print(f"  every run agrees from a settling time of {result['smallest_settling_all_agree_s']} s "
          f"(the runs counted at each settling time are those whose log is long enough)")
    print(f"  written {a.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
