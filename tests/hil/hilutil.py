"""Helpers of the HIL tests (tests/hil): paths, one cached canfdi-scenario run
per scenario, log readers, the SIL twin of a run. See conftest.py."""
from __future__ import annotations

import json
import os
import subprocess
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import can

ROOT = Path(__file__).resolve().parents[2]
OUT = ROOT / "build" / "hil" / "test"
SCN = ROOT / "tests" / "sil" / "scenarios"
ECU = ROOT / "build" / "bin" / "canfdi-ecu"
SIM = ROOT / "build" / "hil" / "canfdi-sim"
SIL = ROOT / "build" / "bin" / "canfdi-sil"
CHANNEL = os.environ.get("CANFDI_HIL_CHANNEL", "vcan0")

#: ECU-transmitted identifiers (DBC node ECU): the stream SIL and HIL
#: lockstep must produce bit for bit.
ECU_IDS = {0x020, 0x021, 0x200, 0x201, 0x300, 0x301, 0x302, 0x310, 0x320, 0x321}


def have_vcan(channel: str = CHANNEL) -> str | None:
    """None if `channel` is a usable SocketCAN interface, else why not."""
    from canfdi.hil import vcan_unavailable
    return vcan_unavailable(channel)


@dataclass
class Run:
    """One canfdi-scenario run: exit status, its --json result, the log."""
    rc: int
    result: dict[str, Any]
    log: Path


_runs: dict[str, Run] = {}


def run_scenario(name: str, *extra: str) -> Run:
    """canfdi-scenario (lockstep) on tests/sil/scenarios/<name>.scn, in-process.
    Cached per (name, extra): several tests look at the same run."""
    from canfdi import scenario_run
    key = " ".join((name,) + extra)
    if key not in _runs:
        tag = name + ("-" + "-".join(e.strip("-").replace("/", "_") for e in extra) if extra else "")
        log, js = OUT / f"{tag}.log", OUT / f"{tag}.json"
        js.unlink(missing_ok=True)
        rc = scenario_run.main([str(SCN / f"{name}.scn"), "-c", CHANNEL, "--lockstep", "-q",
                                "--log", str(log), "--json", str(js), "--ecu", str(ECU),
                                "--sim", str(SIM), *extra])
        result = json.loads(js.read_text()) if js.exists() else {}
        _runs[key] = Run(rc, result, log)
    return _runs[key]


def read_frames(log: Path) -> list[can.Message]:
    from canfdi.logio import ReadStats, read_log
    st = ReadStats()
    msgs = list(read_log(log, st))
    assert st.bad_lines == 0, f"{log}: {st.bad_lines} unreadable lines (first: {st.first_error})"
    return msgs


def ecu_stream(log: Path) -> list[tuple[int, bytes]]:
    return [(m.arbitration_id, bytes(m.data)) for m in read_frames(log) if m.arbitration_id in ECU_IDS]


def sil_log(name: str) -> Path:
    """canfdi-sil's bus log of the same scenario. `make hil-test` writes it on
    the host before entering the sandbox (canfdi-sil is an ASan build, and
    ASan cannot run in User-Mode Linux); made here when this runs where it
    can (a host with vcan)."""
    log = OUT / f"{name}-sil.log"
    if not log.exists():
        r = subprocess.run([str(SIL), "-q", "-s", str(SCN / f"{name}.scn"), "-l", str(log)],
                           cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        assert r.returncode == 0, (f"{log} missing and canfdi-sil failed here (run `make hil-test`, which "
                                   f"makes it on the host): {r.stdout[-500:]}")
    return log
