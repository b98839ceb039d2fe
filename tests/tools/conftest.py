"""Shared fixtures of the tools tests: SIL logs made by canfdi-sil, lockstep
replays of them, unique virtual-bus channels. Nothing here needs vcan."""
from __future__ import annotations

import re
import subprocess
import threading
import time
import uuid
from dataclasses import dataclass
from pathlib import Path
from typing import Iterable, Iterator

import can
import pytest

from canfdi import REPO_ROOT
from canfdi.logio import read_log
from canfdi.timeline import ID_STEP, load_db

SIL = REPO_ROOT / "build" / "bin" / "canfdi-sil"
SCN_DIR = REPO_ROOT / "tests" / "sil" / "scenarios"
VERDICT = re.compile(r"^(PASS|FAIL)  ")


@dataclass(frozen=True)
class SilRun:
    scenario: Path
    log: Path
    stdout: str

    @property
    def rel(self) -> Path:
        """The scenario path as canfdi-sil was given it (and prints it)."""
        return self.scenario.relative_to(REPO_ROOT)

    @property
    def verdict_lines(self) -> list[str]:
        return [ln for ln in self.stdout.splitlines() if VERDICT.match(ln)]


@pytest.fixture(scope="session")
def sil_run(tmp_path_factory: pytest.TempPathFactory):
    """sil_run('tps1_open') -> SilRun, one canfdi-sil run per scenario and session."""
    if not SIL.is_file():
        pytest.fail(f"{SIL} not built: make build/bin/canfdi-sil")
    out_dir = tmp_path_factory.mktemp("sil")
    cache: dict[str, SilRun] = {}

    def run(name: str, scn: Path | None = None) -> SilRun:
        if name not in cache:
            path = scn if scn is not None else SCN_DIR / f"{name}.scn"
            log = out_dir / f"{name}.log"
            r = subprocess.run([str(SIL), "-q", "-s", str(path.relative_to(REPO_ROOT)), "-l", str(log)],
                               cwd=REPO_ROOT, capture_output=True, text=True, timeout=120)
            assert r.returncode in (0, 1), r.stderr
            cache[name] = SilRun(path, log, r.stdout)
        return cache[name]
    return run


def as_lockstep(msgs: Iterable[can.Message], drop_steps: frozenset[int] = frozenset()) -> Iterator[can.Message]:
    """A SIL log as a lockstep HIL bus carries it: SimStep(k) after the plant's
    frames of step k, before the ECU's (the lockstep protocol of
    host_sim/canfdi_sim_rig.h and host_sim/SCENARIO.md)."""
    db = load_db()
    step_msg = db.get_message_by_frame_id(ID_STEP)
    ecu_ids = {m.frame_id for m in db.messages if "ECU" in m.senders}
    k_done = -1
    for msg in msgs:
        k = round(msg.timestamp * 1000)
        if msg.arbitration_id in ecu_ids and k > k_done:
            for j in range(k_done + 1, k + 1):
                if j not in drop_steps:
                    yield can.Message(timestamp=j * 1e-3, arbitration_id=ID_STEP, is_extended_id=False,
                                      data=step_msg.encode({"SimStepIndex": j}))
            k_done = k
        yield msg


@pytest.fixture(autouse=True)
def _in_repo(monkeypatch: pytest.MonkeyPatch) -> None:
    """Scenario paths are given relative to the checkout, as canfdi-sil prints them."""
    monkeypatch.chdir(REPO_ROOT)


@pytest.fixture
def channel() -> str:
    """A virtual-bus channel name no other test uses."""
    return f"canfdi-test-{uuid.uuid4().hex[:8]}"


def wait_receivers(channel: str, n: int, timeout_s: float = 10.0) -> None:
    """Block until n buses listen on a python-can virtual channel."""
    from can.interfaces import virtual
    t_end = time.monotonic() + timeout_s
    while time.monotonic() < t_end:
        with virtual.channels_lock:
            if len(virtual.channels.get(channel, [])) >= n:
                return
        time.sleep(0.01)
    raise TimeoutError(f"no {n} listeners on virtual channel {channel}")


class Replayer(threading.Thread):
    """Send frames on a virtual channel once the tool under test listens (in-process 'bus')."""

    def __init__(self, channel: str, msgs: Iterable[can.Message], listeners: int = 2, pace_every: int = 2000) -> None:
        super().__init__(daemon=True)
        self.channel, self.msgs, self.listeners, self.pace_every = channel, list(msgs), listeners, pace_every
        self.bus = can.Bus(interface="virtual", channel=channel, receive_own_messages=False)
        self.sent = 0

    def run(self) -> None:
        try:
            wait_receivers(self.channel, self.listeners)
            for i, m in enumerate(self.msgs):
                self.bus.send(can.Message(arbitration_id=m.arbitration_id, data=m.data, is_extended_id=False,
                                          dlc=m.dlc))
                self.sent += 1
                if self.pace_every and i % self.pace_every == 0:
                    time.sleep(0.001)   # let the receiver's thread run
        finally:
            self.bus.shutdown()


def sil_msgs(log: Path) -> list[can.Message]:
    return list(read_log(log))


def forge_ecu_frames(msgs: list[can.Message], actuator: bool = True) -> list[can.Message]:
    """A node forging the ECU's identifiers into a SIL log of tps1_open.scn
    (P0122 at 3.009 s), each frame inserted right after the ECU's own frame
    of that identifier:
      1.0 s  EcuDiagnosis, right ID, wrong CRC: com fault#102 at 193 %
      1.2 s  DcmActuator, right CRC, its own counter (8 ahead): bridge B
      1.5 s  EcuDtc, wrong CRC: P0222 confirmed
      2.0 s  EcuStatus x3, right CRC, a second counter sequence (8 ahead of
             the ECU's, +1 each): fail_safe, bridge none, limp-home
      2.5 s  EcuDtc x2, the same: U1A00 testFailed and confirmed
    Returns the new list; the ECU's frames are untouched."""
    from canfdi import e2e
    db = load_db()
    diag, dtc, sts, act = (db.get_message_by_name(n) for n in ("EcuDiagnosis", "EcuDtc", "EcuStatus", "DcmActuator"))

    def frame(m, crc_ok: bool, counter: int, **sig: float) -> bytearray:
        vals = {s.name: 0 for s in m.signals}
        vals.update(sig)
        data = e2e.protect(m.frame_id, bytearray(m.encode(vals, strict=False)), counter)
        if not crc_ok:
            data[0] ^= 0x5A
        return data

    dtc_sts = dict(DtcStsTestFailed=1, DtcStsTestFailedThisOpCycle=1, DtcStsConfirmed=1, DtcStsFailedSinceClear=1)
    # (from s, id, how many, right CRC?, signals)
    plan = [(1.0, 0x301, 1, False, dict(DiagComFaultId=102, DiagComConfidence=193)),
            (1.5, 0x310, 1, False, dict(DtcCode=0x022200, DtcCount=1, **dtc_sts)),
            (2.0, 0x300, 3, True, dict(StsDegStateDcm=2, StsDegStateThr=2, StsActiveBridge=0, StsThrLimpHome=1)),
            (2.5, 0x310, 2, True, dict(DtcCode=0xDA0000, DtcCount=1, **dtc_sts))]
    if actuator:
        plan.append((1.2, 0x020, 1, True, dict(DcmBridgeSel=2, DcmEnable=1, DcmUaCmd=10.0)))
    msg_of = {0x300: sts, 0x301: diag, 0x310: dtc, 0x020: act}
    left = {i: p[2] for i, p in enumerate(plan)}
    own: dict[int, int] = {}       # a forger's next counter per id
    out: list[can.Message] = []
    for m in msgs:
        out.append(m)
        fid = m.arbitration_id
        for i, (t0, pid, _, crc_ok, sig) in enumerate(plan):
            if pid != fid or left[i] == 0 or m.timestamp < t0:
                continue
            ctr = own.setdefault(i, (e2e.counter_of(bytes(m.data)) + 8) & 0x0F)
            own[i] = ctr + 1
            left[i] -= 1
            out.append(can.Message(timestamp=m.timestamp, arbitration_id=fid, is_extended_id=False,
                                   data=frame(msg_of[fid], crc_ok, ctr, **sig), channel=m.channel))
    assert not any(left.values()), left
    return out
