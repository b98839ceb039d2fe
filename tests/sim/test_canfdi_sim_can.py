"""canfdi-sim on SocketCAN (--can): real-time pacing recorded by candump,
the lockstep protocol against a stand-in ECU (lockstep_responder.py), fault
injection and setpoint override frames, the ECU timeout, clean shutdown.

Needs a `vcan0`: run inside the sandbox (`tools/vcan-run .venv/bin/python -m
pytest tests/sim`); elsewhere these tests skip and say why. The binary is
$CANFDI_SIM_HIL or build/hil/canfdi-sim (UBSan only: ASan cannot run in
User-Mode Linux)."""
from __future__ import annotations

import json
import os
import re
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import can
import cantools
import pytest

from conftest import DBC, ROOT, SCENARIOS
from lockstep_responder import Responder

sys.path.insert(0, str(ROOT / "tools"))
from canfdi.e2e import E2EReceiver, Status  # noqa: E402
from canfdi.hil import vcan_unavailable  # noqa: E402

CHANNEL = os.environ.get("CAN_CHANNEL", "vcan0")
DCM, THR, SP_DCM, SP_THR, STATUS, STEP = 0x010, 0x011, 0x100, 0x101, 0x610, 0x611
ACT_DCM, ACT_THR = 0x020, 0x021


NO_VCAN = vcan_unavailable(CHANNEL)
needs_vcan = pytest.mark.skipif(NO_VCAN is not None, reason=str(NO_VCAN))


def _sim() -> Path:
    env = os.environ.get("CANFDI_SIM_HIL")
    path = Path(env) if env else ROOT / "build" / "hil" / "canfdi-sim"
    if not path.exists():
        pytest.fail(f"{path} not built (run `make {path.relative_to(ROOT)}`)")
    return path


def run_sim(*args: str, timeout: float = 120) -> subprocess.CompletedProcess:
    proc = subprocess.run([str(_sim()), *args], cwd=ROOT, capture_output=True, text=True,
                          timeout=timeout)
    assert proc.returncode >= 0, f"killed by signal {-proc.returncode}: {proc.stderr}"
    assert "runtime error" not in proc.stderr, proc.stderr
    return proc


@pytest.fixture(scope="module")
def db() -> cantools.database.Database:
    return cantools.database.load_file(str(DBC))


@pytest.fixture
def responder():
    """A stand-in ECU thread on its own bus; yields a factory."""
    started: list[tuple[Responder, threading.Thread, can.BusABC]] = []

    def _start(**kw) -> Responder:
        bus = can.Bus(interface="socketcan", channel=CHANNEL)
        r = Responder(bus, **kw)
        t = threading.Thread(target=r.run, daemon=True)
        t.start()
        started.append((r, t, bus))
        return r

    yield _start
    for r, t, bus in started:
        r.stop.set()
        t.join(timeout=5)
        bus.shutdown()


def steps_of(record: list[can.Message]) -> list[list[int]]:
    """Splits the recorded bus into steps: the frames up to and including
    each SimStep's two actuator answers."""
    steps, cur = [], []
    for m in record:
        cur.append(m.arbitration_id)
        if m.arbitration_id == ACT_THR:
            steps.append(cur)
            cur = []
    return steps


def test_can_open_error_names_the_interface() -> None:
    # Runs anywhere: without SocketCAN or without the device the message
    # names the interface and points at the sandbox.
    sim = str(_sim())
    proc = subprocess.run([sim, "--can", "nosuchcan0", "-d", "0.01"], cwd=ROOT,
                          capture_output=True, text=True, timeout=60)
    assert proc.returncode == 1, proc.stderr
    assert re.search(r"canfdi-sim: cannot open nosuchcan0: .*\(no .*run under tools/vcan-run\)",
                     proc.stderr), proc.stderr


def test_can_options_need_can() -> None:
    sim = str(_sim())
    proc = subprocess.run([sim, "-s", str(SCENARIOS / "nominal.scn"), "--lockstep"], cwd=ROOT,
                          capture_output=True, text=True, timeout=60)
    assert proc.returncode == 2 and "need --can" in proc.stderr


@needs_vcan
def test_realtime_alone_candump(tmp_path: Path, db) -> None:
    """1 s of real time: 1000 DcmSensor/ThrSensor frames with valid E2E, the
    setpoints every 10 ms, SimPlantStatus every 100 ms in realtime mode, as
    candump records them, and the same frames in the sim's own log."""
    dump = tmp_path / "candump.log"
    stats = tmp_path / "stats.json"
    own = tmp_path / "sim.log"
    with open(dump, "w") as f:
        cd = subprocess.Popen(["candump", "-L", CHANNEL], stdout=f)
        try:
            time.sleep(0.5)
            proc = run_sim("--can", CHANNEL, "--realtime", "-d", "1", "--stats", str(stats),
                           "-l", str(own))
            time.sleep(0.3)
        finally:
            cd.send_signal(signal.SIGINT)
            cd.wait(timeout=10)
    assert proc.returncode == 0, proc.stderr
    assert f"canfdi-sim: ready on {CHANNEL} (realtime)" in proc.stderr
    msgs = list(can.LogReader(str(dump)))
    counts: dict[int, int] = {}
    rx = {DCM: E2EReceiver(DCM), THR: E2EReceiver(THR)}
    for m in msgs:
        counts[m.arbitration_id] = counts.get(m.arbitration_id, 0) + 1
        decoded = db.decode_message(m.arbitration_id, m.data)  # every frame decodes
        if m.arbitration_id in rx:
            assert rx[m.arbitration_id].check(bytes(m.data)) in (Status.OK, Status.INITIAL)
        if m.arbitration_id == STATUS:
            assert decoded["PstSimMode"] in ("realtime", 1)
    assert counts == {DCM: 1000, THR: 1000, SP_DCM: 100, SP_THR: 100, STATUS: 10}, counts
    st = json.loads(stats.read_text())
    assert st["steps"] == 1000 and st["mode"] == "realtime" and st["frames_tx"] == 2210
    assert len(own.read_text().splitlines()) == 2210


@needs_vcan
def test_lockstep_protocol_order(tmp_path: Path, responder) -> None:
    """Per step: setpoints (every 10th), DcmSensor, ThrSensor, SimPlantStatus
    (every 100th), SimStep(k); then the ECU's two actuator frames; nothing
    else and no step missing."""
    r = responder()
    stats = tmp_path / "stats.json"
    log = tmp_path / "sim.log"
    proc = run_sim("--can", CHANNEL, "-s", str(SCENARIOS / "nominal.scn"), "-d", "0.3",
                   "--stats", str(stats), "-l", str(log))
    assert proc.returncode == 0, proc.stderr
    assert f"canfdi-sim: ready on {CHANNEL} (lockstep)" in proc.stderr
    time.sleep(0.3)
    assert r.step_indices == list(range(300))
    steps = steps_of(r.record)
    assert len(steps) == 300
    for k, ids in enumerate(steps):
        want = ([SP_DCM, SP_THR] if k % 10 == 0 else []) + [DCM, THR] + \
               ([STATUS] if k % 100 == 0 else []) + [STEP, ACT_DCM, ACT_THR]
        assert ids == want, (k, [hex(i) for i in ids])
    st = json.loads(stats.read_text())
    assert st["steps"] == 300 and st["mode"] == "lockstep" and st["frames_rx"] == 600
    assert st["wait_us"]["max"] >= st["wait_us"]["mean"] > 0
    # the sim's log: the same frames, received ones stamped with their step
    lines = log.read_text().splitlines()
    assert len(lines) == sum(len(s) for s in steps)
    assert lines[0].startswith(f"(0000000000.000000) {CHANNEL} 100#")
    assert re.match(rf"\(0000000000\.299000\) {CHANNEL} 021#", lines[-1])


@needs_vcan
def test_lockstep_injection_and_override(tmp_path: Path, responder, db) -> None:
    """SimFaultInject (thr_tps1_open, delay 50 ms) and SetpointDcm
    (123 rad/s, 0.5 N m) sent at step 20: the fault acts from 70 ms, the sim
    repeats the override every 10 ms from step 30 on and reports the fault."""
    r = responder(inject_at=20)
    proc = run_sim("--can", CHANNEL, "-s", str(SCENARIOS / "nominal.scn"), "-d", "0.2")
    assert proc.returncode == 0, proc.stderr
    time.sleep(0.3)
    assert "0.020 s: inject thr_tps1_open abrupt magnitude 1 from 0.070 s" in proc.stderr
    assert "0.020 s: setpoint override: speed 123 rad/s, load 0.5 N m" in proc.stderr
    k = 0  # frames before SimStep(k) belong to step k
    tps1 = {}
    sp = {}
    status = {}
    for m in r.record:
        i = m.arbitration_id
        if i == STEP:
            k += 1
        elif i == THR:
            tps1[k] = db.decode_message(i, m.data)["ThrTps1"]
        elif i == SP_DCM:
            sp[k] = db.decode_message(i, m.data)
        elif i == STATUS:
            status[k] = db.decode_message(i, m.data, decode_choices=False)
    # the sim's setpoints are E2E protected, one sequence per identifier, the
    # override included (it sends it on in its own sequence)
    from canfdi import e2e
    rx = {i: e2e.E2EReceiver(i) for i in (SP_DCM, SP_THR)}
    sent = [m for m in r.record if m.arbitration_id in rx and not any(m is o for o in r.own)]
    got = [rx[m.arbitration_id].check(bytes(m.data)) for m in sent]
    assert got[:2] == [e2e.Status.INITIAL, e2e.Status.INITIAL] and set(got[2:]) == {e2e.Status.OK}, got
    assert all(v["SpDcmSpeed"] != pytest.approx(123.0) for s, v in sp.items() if s <= 20)
    assert all(v["SpDcmSpeed"] == pytest.approx(123.0) and v["SpDcmLoad"] == pytest.approx(0.5)
               for s, v in sp.items() if s >= 30)
    assert all(v > 0.5 for s, v in tps1.items() if s < 69)
    assert all(v < 0.1 for s, v in tps1.items() if s >= 71)
    assert status[100]["PstActiveFaultId"] == 10 and status[100]["PstFaultActive"] == 1
    assert status[100]["PstSimMode"] == 0


@needs_vcan
def test_lockstep_ecu_timeout() -> None:
    proc = run_sim("--can", CHANNEL, "-s", str(SCENARIOS / "nominal.scn"), "--ecu-timeout", "0.3")
    assert proc.returncode == 1
    assert (f"canfdi-sim: no actuator frames from the ECU for step 0 within 0.3 s "
            f"(is canfdi-ecu --lockstep running on {CHANNEL}?)") in proc.stderr


@needs_vcan
def test_sigterm_stops_cleanly(tmp_path: Path) -> None:
    """Built-in vehicle, no duration: runs until SIGTERM, then exits 0 with
    its summary and stats."""
    stats = tmp_path / "stats.json"
    p = subprocess.Popen([str(_sim()), "--can", CHANNEL, "--realtime", "--stats", str(stats)],
                         cwd=ROOT, stderr=subprocess.PIPE, text=True)
    assert p.stderr is not None
    assert "ready on" in p.stderr.readline()
    time.sleep(0.5)
    p.send_signal(signal.SIGTERM)
    err = p.stderr.read()
    assert p.wait(timeout=10) == 0, err
    assert "stopped by signal" in err
    assert json.loads(stats.read_text())["steps"] > 100
