"""The ECU process on a bus it does not control: raw frames from can-utils,
floods of random traffic, live tools, restarts with its NVM file."""
from __future__ import annotations

import contextlib
import io
import json
import shutil
import subprocess
import threading
import time
from pathlib import Path

import can
import pytest

from hilutil import CHANNEL, ECU, OUT, SCN, SIM, read_frames

from canfdi import e2e, inject, scenario_run, watch
from canfdi.hil import Proc, Recorder, start_ecu, start_sim
from canfdi.timeline import load_db

DB = load_db()
SELF_DIAG = DB.get_message_by_name("EcuSelfDiag")
STATUS = DB.get_message_by_name("EcuStatus")
DTC = DB.get_message_by_name("EcuDtc")
STEP = DB.get_message_by_name("SimStep")
NOMINAL = SCN / "nominal_setpoints.scn"


class Monitor(can.Listener):
    """Where the bench is now: a second bus with kernel filters for SimStep
    and DcmSensor only, so it keeps up where the full Recorder lags (in the
    sandbox python-can reads ~2 k frames/s, the bench makes ~4 k/s)."""

    def __init__(self) -> None:
        super().__init__()
        self.step = -1
        self.dcm: bytes = b""
        self.bus = can.Bus(interface="socketcan", channel=CHANNEL,
                           can_filters=[{"can_id": 0x611, "can_mask": 0x7FF},
                                        {"can_id": 0x010, "can_mask": 0x7FF}])
        self.notifier = can.Notifier(self.bus, [self], timeout=0.1)

    def on_message_received(self, m: can.Message) -> None:
        if m.arbitration_id == STEP.frame_id and len(m.data) == 8:
            self.step = int(STEP.decode(bytes(m.data))["SimStepIndex"])
        elif m.arbitration_id == 0x010:
            self.dcm = bytes(m.data)

    def wait_step(self, k: int, proc: Proc, timeout_s: float = 60.0) -> None:
        t_end = time.monotonic() + timeout_s
        while self.step < k:
            assert proc.poll() is None, f"{proc.name} ended before step {k}: {proc.tail()}"
            assert time.monotonic() < t_end, f"bench stuck at step {self.step}"
            time.sleep(0.005)

    def close(self) -> None:
        self.notifier.stop()
        self.bus.shutdown()


class Bench:
    """canfdi-ecu + canfdi-sim (lockstep unless told) + a full Recorder + a
    Monitor; everything is stopped and closed whatever happens."""

    def __init__(self, log: Path, scenario: Path, duration: str, lockstep: bool = True,
                 nvm: Path | None = None) -> None:
        self.log = log
        self.ecu = start_ecu(ECU, CHANNEL, lockstep=lockstep, nvm=nvm)
        self.bus = can.Bus(interface="socketcan", channel=CHANNEL)
        self.rec = Recorder(self.bus, log)
        self.mon = Monitor()
        self.sim = start_sim(SIM, CHANNEL, scenario, lockstep=lockstep, extra=("-d", duration))

    def finish(self) -> None:
        """The sim ends by itself; then the ECU (exit 0 required); drain."""
        assert self.sim.popen.wait(timeout=300) == 0, self.sim.tail()
        assert self.ecu.stop() == 0, self.ecu.tail()
        assert self.rec.wait_quiet(0.5, 600.0), "recorder still draining after 600 s"

    def close(self) -> None:
        self.sim.kill()
        self.ecu.kill()
        self.mon.close()
        self.rec.close()
        self.bus.shutdown()

    def __enter__(self) -> "Bench":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def decoded(log: Path, msg) -> list[dict]:
    return [msg.decode(bytes(m.data), decode_choices=False)
            for m in read_frames(log) if m.arbitration_id == msg.frame_id]


def cansend(frame: str) -> None:
    r = subprocess.run(["cansend", CHANNEL, frame], stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                       text=True, timeout=30)
    assert r.returncode == 0, r.stdout


def test_cansend_crc_and_counter_are_judged() -> None:
    """A DcmSensor frame with a corrupted CRC and one with a repeated rolling
    counter, sent with can-utils cansend into a running lockstep bench, are
    rejected by the input supervision (EcuSelfDiag.SdgFramesRejected counts
    them) and, single frames, qualify no trouble code."""
    log = OUT / "cansend.log"
    with Bench(log, NOMINAL, "4") as b:
        b.mon.wait_step(1000, b.sim)
        good = b.mon.dcm
        cansend("010#" + (bytes([good[0] ^ 0xFF]) + good[1:]).hex().upper())   # CRC wrong
        b.mon.wait_step(2000, b.sim)
        cansend("010#" + b.mon.dcm.hex().upper())     # valid CRC, counter repeated
        b.finish()
    sd = decoded(log, SELF_DIAG)
    rejected = [s["SdgFramesRejected"] for s in sd]
    assert rejected[0] == 0
    assert rejected == sorted(rejected), "a monotone counter went down"
    assert 2 <= rejected[-1] <= 4, rejected[-1]
    failed = [d for d in decoded(log, DTC) if d["DtcCode"] != 0 and (d["DtcStsTestFailed"] or d["DtcStsConfirmed"])]
    assert failed == [], failed


def test_flood_of_bad_traffic_for_10_s() -> None:
    """Random identifiers, lengths and data (cangen, as fast as the bus
    takes) plus wrong-length and random frames on the ECU's own identifiers,
    for 10 s, while ECU and sim run in real time: the ECU keeps stepping,
    keeps sending its status, and exits 0 on SIGTERM."""
    if shutil.which("cangen") is None:
        pytest.fail("cangen (can-utils) not installed: make deps")
    stats = OUT / "flood-ecu.json"
    stats.unlink(missing_ok=True)
    ecu = start_ecu(ECU, CHANNEL, lockstep=False, extra=("--stats", str(stats)))
    sim = start_sim(SIM, CHANNEL, NOMINAL, lockstep=False, extra=("-d", "14"))
    mon = can.Bus(interface="socketcan", channel=CHANNEL,
                  can_filters=[{"can_id": STATUS.frame_id, "can_mask": 0x7FF},
                               {"can_id": SELF_DIAG.frame_id, "can_mask": 0x7FF}])
    floods = []
    try:
        time.sleep(2.0)
        floods = [subprocess.Popen(["timeout", "10", "cangen", CHANNEL, "-g", "0", "-i", *args],
                                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
                  for args in (["-I", "r", "-L", "r", "-D", "r"],          # anything
                               ["-I", "010", "-L", "r", "-D", "r"],        # DcmSensor, any length
                               ["-I", "011", "-L", "r", "-D", "r"],
                               ["-I", "100", "-L", "r", "-D", "r"],        # setpoints
                               ["-I", "611", "-L", "r", "-D", "r"])]      # SimStep in realtime
        for f in floods:
            f.wait(timeout=30)
        assert ecu.poll() is None, f"canfdi-ecu died during the flood: {ecu.tail()}"
        # after the flood: status frames keep coming, alive counter advancing
        alive = []
        t_end = time.monotonic() + 10.0
        while len(alive) < 5 and time.monotonic() < t_end:
            m = mon.recv(timeout=1.0)
            # the monitor's queue still holds flood frames; cangen's random
            # identifiers hit 0x300 too, with any length: only frames that
            # pass the E2E check are the ECU's (its counter is the alive counter)
            if m is not None and m.arbitration_id == STATUS.frame_id and e2e.is_valid(STATUS.frame_id, bytes(m.data)):
                alive.append(STATUS.decode(bytes(m.data))["EcuStatusCounter"])
        assert len(alive) == 5, "EcuStatus stopped after the flood"
        assert len(set(alive)) > 1, alive
        sim.popen.wait(timeout=120)
        assert ecu.stop() == 0, ecu.tail()
    finally:
        for f in floods:
            f.kill()
        sim.kill()
        ecu.kill()
        mon.shutdown()
    st = json.loads(stats.read_text())
    assert st["frames_rejected"] > 0
    assert st["steps"] > 1000


def test_watch_live_sees_an_injected_fault() -> None:
    """canfdi-inject sends a fault by its catalogue name into a running
    lockstep bench; canfdi-watch on the live bus exits 0 for --expect and 1
    for --forbid of the same code."""
    results: dict[str, int] = {}

    def run_watch(key: str, argv: list[str]) -> None:
        results[key] = watch.main(["-c", CHANNEL, "-q", "--timeout", "120", *argv])
    threads = [threading.Thread(target=run_watch, args=("expect", ["--expect", "P0122", "--within", "3.5"])),
               threading.Thread(target=run_watch, args=("forbid", ["--forbid", "P0122", "--within", "3.5"]))]
    for t in threads:
        t.start()
    time.sleep(1.0)   # both watchers have their sockets open
    log = OUT / "inject.log"
    with Bench(log, NOMINAL, "4") as b:
        b.mon.wait_step(1000, b.sim)
        assert inject.main(["-c", CHANNEL, "fault", "thr_tps1_open"]) == 0
        b.finish()
    for t in threads:
        t.join(timeout=150)
    assert results == {"expect": 0, "forbid": 1}
    # the watch on the recorded log says the same
    assert watch.main(["--log", str(log), "-q", "--expect", "P0122", "--within", "3.5"]) == 0
    assert watch.main(["--log", str(log), "-q", "--forbid", "P0122"]) == 1


def first_dtc(log: Path, code: int) -> dict:
    return next(d for d in decoded(log, DTC) if d["DtcCode"] == code)


def test_dtc_memory_survives_a_restart() -> None:
    """Operation cycles at system level: run 1 confirms P0122 (TPS1 open)
    and the ECU stores its memory at SIGTERM; run 2, fault-free, with the
    same NVM file reports P0122 still confirmed but not failed in the new
    cycle, and the occurrence counter unchanged."""
    nvm = OUT / "restart.nvm"
    nvm.unlink(missing_ok=True)
    p0122 = 0x012200
    logs = []
    for run, scn, dur in ((1, SCN / "tps1_open.scn", "4"), (2, NOMINAL, "2")):
        log = OUT / f"restart-{run}.log"
        with Bench(log, scn, dur, nvm=nvm) as b:
            b.finish()
        logs.append(log)
    end1 = [d for d in decoded(logs[0], DTC) if d["DtcCode"] == p0122][-1]
    assert end1["DtcStsConfirmed"] == 1 and end1["DtcStsTestFailedThisOpCycle"] == 1
    start2 = first_dtc(logs[1], p0122)
    assert start2["DtcStsConfirmed"] == 1, start2
    assert start2["DtcStsTestFailedThisOpCycle"] == 0, start2
    assert start2["DtcStsNotCompletedThisOpCycle"] == 1 or start2["DtcStsTestFailed"] == 0, start2
    assert start2["DtcOccurrence"] == end1["DtcOccurrence"], (start2, end1)
    end2 = [d for d in decoded(logs[1], DTC) if d["DtcCode"] == p0122][-1]
    assert end2["DtcStsTestFailed"] == 0 and end2["DtcStsConfirmed"] == 1, end2


def forged(name: str, counter: int, crc_ok: bool, **sig: float) -> str:
    """A frame of the ECU's for cansend: encoded by cantools, E2E protected
    with `counter`, its CRC made wrong unless crc_ok."""
    m = DB.get_message_by_name(name)
    vals = {s.name: 0 for s in m.signals}
    vals.update(sig)
    data = e2e.protect(m.frame_id, bytearray(m.encode(vals, strict=False)), counter)
    if not crc_ok:
        data[0] ^= 0x5A
    return f"{m.frame_id:03X}#{bytes(data).hex().upper()}"


def latest_counter(bus: can.BusABC, fid: int) -> int:
    """The E2E counter of the ECU's newest valid frame `fid` on a bus that
    receives only the ECU's slow frames: its queue is drained at once (a
    few frames a second), so the value is at most a frame old."""
    last = None
    t_end = time.monotonic() + 5.0
    while time.monotonic() < t_end:
        m = bus.recv(timeout=0.0 if last is not None else 0.2)
        if m is None:
            if last is not None:
                return e2e.counter_of(last)
            continue
        if m.arbitration_id == fid and e2e.is_valid(fid, bytes(m.data)):
            last = bytes(m.data)
    raise AssertionError(f"no valid frame 0x{fid:03X} of the ECU within 5 s")


def test_forged_ecu_frames_are_flagged_live_and_in_the_recording(capsys: pytest.CaptureFixture[str]) -> None:
    """A second node on the bus forges the ECU's identifiers with can-utils
    while a lockstep bench runs fault-free: EcuDiagnosis and EcuDtc with a
    wrong CRC (com fault#102 at 193 %, P0222 confirmed), EcuStatus and EcuDtc
    with a right CRC and a counter 8 ahead of the ECU's (limp-home, U1A00).
    canfdi-watch on the live bus and on the recording, and canfdi-scenario
    judging the recording, report each as forged or corrupted and show none
    of it as a diagnosis, status change or trouble code; the ECU's own frames
    still decode (no code: the run is fault-free)."""
    results: dict[str, int] = {}

    def run_watch() -> None:
        # until 7.5 s of the 8 s run: the forged frames go out after 1.5 s
        # plus however long reading the ECU's counters takes, in which the
        # lockstep bench runs on (over 2 s of the run on a loaded machine)
        results["live"] = watch.main(["-c", CHANNEL, "--duration", "7.5", "--timeout", "120"])
    t = threading.Thread(target=run_watch)
    t.start()
    time.sleep(1.0)   # the watcher's socket is open
    log = OUT / "forged.log"
    dtc = dict(DtcStsTestFailed=1, DtcStsConfirmed=1, DtcStsFailedSinceClear=1, DtcCount=1)
    slow = can.Bus(interface="socketcan", channel=CHANNEL,
                   can_filters=[{"can_id": 0x300, "can_mask": 0x7FF}, {"can_id": 0x310, "can_mask": 0x7FF}])
    try:
        with Bench(log, NOMINAL, "8") as b:
            b.mon.wait_step(1000, b.sim)
            cansend(forged("EcuDiagnosis", 0, False, DiagComFaultId=102, DiagComConfidence=193))
            cansend(forged("EcuDtc", 0, False, DtcCode=0x022200, **dtc))
            b.mon.wait_step(1500, b.sim)
            # a second sequence: 8 ahead of the ECU's newest frame (never in
            # step with it), sent at once from this socket (starting cansend
            # takes most of a second in the sandbox: the ECU's counter moves on)
            for name, sig in (("EcuStatus", dict(StsThrLimpHome=1, StsDegStateThr=2)),
                              ("EcuDtc", dict(DtcCode=0xDA0000, **dtc))):
                fid = DB.get_message_by_name(name).frame_id
                frame = forged(name, latest_counter(slow, fid) + 8, True, **sig)
                slow.send(can.Message(arbitration_id=fid, data=bytes.fromhex(frame.split("#")[1]),
                                      is_extended_id=False))
            b.finish()
    finally:
        slow.shutdown()
    t.join(timeout=150)
    live = capsys.readouterr().out
    rec = io.StringIO()
    with contextlib.redirect_stdout(rec):
        results["log"] = watch.main(["--log", str(log)])
        scn = scenario_run.load(NOMINAL, SIM)
        res = scenario_run.RunResult()
        scenario_run.evaluate_log(scn, log, res, started=True, lockstep=True)
    assert results == {"live": 1, "log": 1}, live + rec.getvalue()
    for out in (live, rec.getvalue()):
        assert "0x301 EcuDiagnosis forged or corrupted: wrong CRC" in out, out
        assert "0x310 EcuDtc forged or corrupted: wrong CRC" in out, out
        assert "0x300 EcuStatus forged or corrupted: counter jump" in out, out
        assert "0x310 EcuDtc forged or corrupted: counter jump" in out, out
        for claim in ("fault#102", "193 %", "P0222", "U1A00", "limp-home ON", "-> fail_safe"):
            assert claim not in out, (claim, out)
    assert any("ECU frame(s) forged or corrupted" in e for e in res.errors), res.errors
