"""Shared helpers of the canfdi-replay tests (tests/replay, `make replay-test`).

Recordings: every SIL scenario's bus log, written by canfdi-sil -l here
(build/replay/test/sil/), and the lockstep HIL recordings `make
replay-test` makes in the vcan sandbox with canfdi-scenario
(build/replay/test/hil/, tests/replay/record_hil.sh). What the recorded
ECU reported is read from the recordings with canfdi.timeline (the
tester's decoding with cantools), independently of the replay.
"""
from __future__ import annotations

import contextlib
import functools
import io
import json
import os
import random
import re
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Any

import pytest

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "tools"))

from canfdi import replay  # noqa: E402
from canfdi.logio import read_log  # noqa: E402
from canfdi.timeline import Timeline  # noqa: E402

CORE = ROOT / "build" / "bin" / "canfdi-replay-core"
CORE_ASAN = ROOT / "build" / "bin" / "canfdi-replay-core-asan"
SIL = ROOT / "build" / "bin" / "canfdi-sil"
OUT = ROOT / "build" / "replay" / "test"
HIL_OUT = OUT / "hil"
SCENARIOS = sorted(p for p in (ROOT / "tests" / "sil" / "scenarios").glob("*.scn") if p.name != "demo.scn")
MATRIX = sorted((ROOT / "tests" / "sil" / "matrix").glob("*.scn"))
#: ECU-side lines of the SIL rig that never reach the bus (host_sim/SCENARIO.md)
ECU_ACTIONS = re.compile(r"^\s*(cycle|clear|power_cycle)\b", re.M)
#: Longer than this (simulated seconds) is left to `make sil-test` alone.
MAX_DURATION_S = 60.0
#: Monitors judged from the first frame on (frame checks, range checks): no settling.
NO_SETTLING = {"com_dcm", "com_thr", "tps_range"}
#: The HIL recordings tests/replay/record_hil.sh makes (scenario paths; REPLAY_HIL_SCN of mk/replay.mk).
HIL_SCENARIOS = ("tests/sil/matrix/dcm_ia_sensor_offset_intermittent.scn", "tests/sil/scenarios/tps1_open.scn",
                 "tests/sil/scenarios/dcm_ra_up.scn")


def duration_s(scn: Path) -> float:
    m = re.search(r"^\s*duration\s+(\S+)", scn.read_text(), re.M)
    return float(m.group(1)) if m else 0.0


def has_ecu_actions(scn: Path) -> bool:
    return bool(ECU_ACTIONS.search(scn.read_text()))


def replayable(scn: Path) -> bool:
    """Everything of the run is on the bus, and it is short enough for make test."""
    return not has_ecu_actions(scn) and duration_s(scn) <= MAX_DURATION_S


def sil_log_path(scn: Path) -> Path:
    return OUT / "sil" / f"{scn.parent.name}_{scn.stem}.log"


def make_sil_log(scn: Path) -> Path:
    log = sil_log_path(scn)
    if not log.exists() or log.stat().st_mtime < max(scn.stat().st_mtime, SIL.stat().st_mtime):
        log.parent.mkdir(parents=True, exist_ok=True)
        tmp = log.with_suffix(".tmp")
        subprocess.run([str(SIL), "-q", "-s", str(scn), "-l", str(tmp)], stdout=subprocess.DEVNULL,
                       stderr=subprocess.PIPE, check=False, cwd=ROOT)
        tmp.replace(log)
    return log


@pytest.fixture(scope="session")
def sil_logs() -> dict[Path, Path]:
    """Every replayable SIL scenario's bus log (scenarios and matrix)."""
    scns = [s for s in SCENARIOS + MATRIX if replayable(s)]
    with ThreadPoolExecutor(max_workers=2) as ex:
        logs = list(ex.map(make_sil_log, scns))
    return dict(zip(scns, logs))


@contextlib.contextmanager
def core_env(core: Path):
    old = os.environ.get("CANFDI_REPLAY_CORE")
    os.environ["CANFDI_REPLAY_CORE"] = str(core)
    try:
        yield
    finally:
        if old is None:
            os.environ.pop("CANFDI_REPLAY_CORE", None)
        else:
            os.environ["CANFDI_REPLAY_CORE"] = old


def run_replay(args: list[str], tmp: Path, core: Path = CORE) -> tuple[int, dict[str, Any] | None, str, str]:
    """canfdi-replay in this process: (exit status, JSON report or None, stdout, stderr)."""
    js = tmp / f"report{len(list(tmp.glob('report*.json')))}.json"
    out, err = io.StringIO(), io.StringIO()
    with core_env(core), contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        rc = replay.main([*args, "--json", str(js), "--no-progress"])
    doc = json.loads(js.read_text()) if js.exists() else None
    return rc, doc, out.getvalue(), err.getvalue()


@functools.lru_cache(maxsize=None)
def recorded_ecu(log: Path) -> Timeline:
    """The recorded ECU's trouble codes, decoded by canfdi.timeline from the log itself."""
    return Timeline().feed_all(read_log(log))


def recorded_first_failed(log: Path) -> dict[str, float]:
    tl = recorded_ecu(log)
    return {c: r.first_failed_us * 1e-6 for c, r in tl.dtcs.items() if r.first_failed_us >= 0}


def recorded_active_after(log: Path, t_s: float, code: str) -> bool:
    """The code's testFailed bit is set in the recorded ECU's frames at some time >= t_s."""
    rec = recorded_ecu(log).dtcs.get(code)
    if rec is None:
        return False
    t_us = round(t_s * 1e6)
    at = rec.state_at(t_us)
    return bool((at is not None and at[1] & 1) or any(h[0] >= t_us and h[1] & 1 for h in rec.history))


#: Report keys whose values are keyed by data (frame, code, input, channel names), not by the schema.
DATA_KEYED = {"inputs", "codes_not_applied", "models_not_judged", "rejected_frames", "accepted_frames",
              "other_channels", "unknown_ids", "symptoms", "normalised", "result", "residuals_over_threshold",
              "parameter_deviation_pct", "freeze_frame"}


def undocumented_keys(doc: Any) -> set[str]:
    """Keys of a JSON report that the schema in tools/canfdi/replay_report.py does not name."""
    from canfdi import replay_report
    named = set(re.findall(r"[A-Za-z_][A-Za-z0-9_]*", replay_report.__doc__ or ""))
    out: set[str] = set()

    def walk(x: Any) -> None:
        if isinstance(x, dict):
            for k, v in x.items():
                if k not in named:
                    out.add(k)
                if k not in DATA_KEYED:
                    walk(v)
        elif isinstance(x, list):
            for v in x:
                walk(v)
    walk(doc)
    return out


def cut_log(src: Path, dst: Path, t_from: float) -> Path:
    """The lines of a candump log from time stamp t_from on (a recording started mid-run)."""
    with src.open() as f, dst.open("w") as g:
        for line in f:
            if float(line[1:line.index(")")]) >= t_from - 1e-9:
                g.write(line)
    return dst


def jitter_log(src: Path, dst: Path, jitter_us: int, ppm: int = 0, seed: int = 1,
               base_us: int = 1_700_000_000_000_000) -> Path:
    """A candump log as a real logger would have stamped it: every frame's time stamp moved by a seeded
    uniform jitter of +-jitter_us, the logger's clock running ppm parts per million fast (negative: slow)
    against the sensor nodes' from base_us (epoch microseconds), and the stamps never decreasing (the
    file's order is the bus's: a frame that drew an earlier stamp than the one before takes that one's)."""
    rng = random.Random(seed)
    prev = None
    with src.open() as f, dst.open("w") as g:
        for line in f:
            close = line.index(")")
            sec, _, frac = line[1:close].partition(".")
            t = int(sec) * 1_000_000 + int(frac.ljust(6, "0")[:6])
            n = base_us + t + (t * ppm) // 1_000_000 + rng.randint(-jitter_us, jitter_us)
            if prev is not None and n < prev:
                n = prev
            prev = n
            g.write(f"({n // 1_000_000:010d}.{n % 1_000_000:06d}){line[close + 1:]}")
    return dst
