"""The bus-fault rig of tests/hil/test_busfault.py: the ECU on a bus of its
own that can fail, a clock line that cannot, a fault-insertion unit that
keeps the lockstep bench going while the ECU is off the bus, an slcan
adapter on a pty for error frames and bus-off, and the readers of the
recorded bench.

Topology (all inside the vcan sandbox, which is root and has can-gw and
slcan loaded; tools/vcan-run):

    canfdi-sim --lockstep, candump, UDS tester, the FIU      vcan0 (bench)
        |  cangw both ways (vcan1) or the slcan adapter (canN on a pty)
    canfdi-ecu --lockstep -c vcan1|canN --clock vcan2         the ECU's bus
    the FIU's ticks (SimStep) while the ECU is off the bus    vcan2 (clock)

In lockstep the plant is the clock: the ECU steps on SimStep frames and the
plant waits for the ECU's two actuator frames. SimStep is the rig's clock,
not a frame of the vehicle's bus, so while the ECU's bus is down (or
bus-off, or its sensor node gone) the fault-insertion unit (Fiu) ticks the
ECU on the clock line for every step the plant makes and hands the plant
the ECU's last actuator frames, held as a real power stage holds its last
command. The ECU then lives through the outage as it would in a vehicle:
its loop keeps stepping, nothing reaches it, nothing it sends gets out.
Entry and exit are clean (no frame of a step goes half through): the Fiu
stops the bench at a step, changes the bus, and restarts the step.

Everything here uses raw CAN sockets (struct can_frame), not python-can:
inside User-Mode Linux python-can manages ~2 k frames/s, the Fiu and the
adapter must keep up with a lockstep bench.
"""
from __future__ import annotations

import fcntl
import os
import select
import socket
import struct
import subprocess
import termios
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import pytest

from hilutil import CHANNEL, ECU, OUT, SIM

from canfdi.hil import Proc, start_ecu, start_sim

BENCH = CHANNEL            # the plant, the tester, the recorder
ECU_BUS = "vcan1"          # the ECU's own bus when it is a vcan behind cangw
CLOCK = "vcan2"            # the rig's clock line (made here)
ID_STEP, ID_ACT_DCM, ID_ACT_THR = 0x611, 0x020, 0x021
ID_STATUS, ID_DIAG, ID_SELFDIAG, ID_DTC = 0x300, 0x301, 0x302, 0x310
ACTUATORS = (ID_ACT_DCM, ID_ACT_THR)
CAN_FMT = "=IB3x8s"
CAN_EFF_FLAG, CAN_RTR_FLAG, CAN_ERR_FLAG = 0x80000000, 0x40000000, 0x20000000
SOL_CAN_RAW, CAN_RAW_FILTER, CAN_RAW_ERR_FILTER = 101, 1, 2
SO_RCVBUFFORCE = 33
N_SLCAN = 17
SIOCGIFNAME = 0x8910


def sh(*cmd: str) -> str:
    r = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=30)
    assert r.returncode == 0, f"{' '.join(cmd)}: {r.stdout.strip()}"
    return r.stdout


def link_up(ifname: str) -> bool:
    return (int(Path(f"/sys/class/net/{ifname}/flags").read_text(), 0) & 1) == 1


def need_net_admin(modules: tuple[str, ...] = ("can_gw", "slcan")) -> None:
    """The rig changes interfaces (ip link, cangw, slcan): it needs root and
    the kernel modules tools/vcan-run loads. Elsewhere (a PC's own vcan0 as
    a normal user) the tests skip, or fail under CANFDI_HIL_REQUIRED=1."""
    why = None
    missing = [m for m in modules if not Path(f"/sys/module/{m}").exists()]
    if os.geteuid() != 0:
        why = "the bus-fault rig needs root (ip link, cangw, slcan): run under tools/vcan-run"
    elif missing:
        why = f"kernel modules {', '.join(missing)} not loaded (tools/vcan-run loads them)"
    if why is not None:
        if os.environ.get("CANFDI_HIL_REQUIRED") == "1":
            pytest.fail(why)
        pytest.skip(why)
    if not Path(f"/sys/class/net/{CLOCK}").exists():
        sh("ip", "link", "add", "dev", CLOCK, "type", "vcan")
    for ifn in (BENCH, ECU_BUS, CLOCK):
        if not link_up(ifn):
            sh("ip", "link", "set", "up", ifn)


def gw(on: bool, clock_by_fiu: bool = False) -> None:
    """cangw rules between the bench and the ECU's vcan1, both ways, with
    local echo so that every socket on the far side sees the frame;
    clock_by_fiu: SimStep does not pass (the Fiu relays it, mode relay)."""
    sh("cangw", "-F")
    if on:
        flt = ["-f", f"{ID_STEP:03X}~7FF"] if clock_by_fiu else []
        sh("cangw", "-A", "-s", BENCH, "-d", ECU_BUS, "-e", *flt)
        sh("cangw", "-A", "-s", ECU_BUS, "-d", BENCH, "-e")


def can_sock(ifname: str, ids: list[int] | None = None, rcvbuf: int = 0, err_mask: int = 0) -> socket.socket:
    """Raw CAN socket on ifname; ids: kernel filter (None: everything, []:
    nothing, for a sender); err_mask: error classes to receive."""
    s = socket.socket(socket.PF_CAN, socket.SOCK_RAW, socket.CAN_RAW)
    if ids is not None:
        flt = b"".join(struct.pack("=II", i, 0x7FF | CAN_EFF_FLAG | CAN_RTR_FLAG) for i in ids)
        s.setsockopt(SOL_CAN_RAW, CAN_RAW_FILTER, flt)
    if err_mask:
        s.setsockopt(SOL_CAN_RAW, CAN_RAW_ERR_FILTER, struct.pack("=I", err_mask))
    if rcvbuf:
        s.setsockopt(socket.SOL_SOCKET, SO_RCVBUFFORCE, rcvbuf)
    s.bind((ifname,))
    return s


def pack(can_id: int, data: bytes) -> bytes:
    return struct.pack(CAN_FMT, can_id, len(data), bytes(data).ljust(8, b"\0"))


def unpack(raw: bytes) -> tuple[int, bytes]:
    can_id, n, data = struct.unpack(CAN_FMT, raw[:16])
    return can_id, data[:n]


def step_of(data: bytes) -> int:
    return int.from_bytes(data[:4], "little")


class Fiu(threading.Thread):
    """Fault-insertion unit of the lockstep bench (see the module text).

    pass: watches SimStep and the ECU's actuator frames on the bench;
    cut:  for every SimStep(k) of the plant, ticks the ECU with SimStep(k)
          on the clock line and sends the plant the ECU's last actuator
          frames (held);
    hold: lets the next SimStep go unanswered: the bench stops there;
    relay: a restarted plant counts its steps from 0 again, which the ECU
          ignores as stale: every SimStep(j) is passed on as a tick
          SimStep(j + offset) on the clock line (after its frames, which
          the ECU handles first).
    """

    def __init__(self, bench: str = BENCH, clock: str = CLOCK) -> None:
        super().__init__(daemon=True, name="fiu")
        self.rx = can_sock(bench, [ID_STEP, *ACTUATORS], rcvbuf=8 << 20)
        self.clk = can_sock(clock, [])
        self.lock = threading.Lock()
        self.stop_evt = threading.Event()
        self.held_evt = threading.Event()
        self.mode = "pass"
        self.step = -1                  # last SimStep seen on the bench
        self.after: set[int] = set()    # actuator ids seen since it
        self.last_act: dict[int, bytes] = {}
        self.t_last = time.monotonic()
        self.held_at = -1
        self.offset = 0
        self.last_tick = -1
        self.hold_when: Callable[[int], bool] | None = None
        self.ticks = 0                  # clock ticks sent
        self.supplied = 0               # held actuator frames sent
        self.error: BaseException | None = None
        self.start()

    # -- the thread
    def run(self) -> None:
        try:
            while not self.stop_evt.is_set():
                r, _, _ = select.select([self.rx], [], [], 0.05)
                if not r:
                    continue
                can_id, data = unpack(self.rx.recv(16))
                with self.lock:
                    self.t_last = time.monotonic()
                    if can_id == ID_STEP and len(data) == 8:
                        self.step = step_of(data)
                        self.after = set()
                        if self.mode == "cut":
                            self._tick(self.step)
                            self._supply(set(ACTUATORS))
                        elif self.mode == "relay":
                            if self.hold_when is not None and self.hold_when(self.step):
                                self.mode = "hold"
                                self.held_at = self.step
                                self.held_evt.set()
                            else:
                                self._tick(self.step + self.offset)
                        elif self.mode == "hold":
                            self.held_at = self.step
                            self.held_evt.set()
                    elif can_id in ACTUATORS:
                        self.after.add(can_id)
                        self.last_act[can_id] = data
        except BaseException as e:  # noqa: BLE001 — reported by the test
            self.error = e

    def _tick(self, k: int) -> None:
        self.clk.send(pack(ID_STEP, k.to_bytes(4, "little") + bytes(4)))
        self.ticks += 1
        self.last_tick = k

    def free_run(self, first: int, n: int) -> int:
        """With no plant on the bus: tick the ECU n times from step `first`,
        one a millisecond. Returns the last step ticked."""
        for k in range(first, first + n):
            with self.lock:
                self._tick(k)
            time.sleep(0.001)
        return first + n - 1

    def relay(self, offset: int, hold_when: Callable[[int], bool] | None = None) -> None:
        """Relay the plant's SimStep(j) as tick j + offset; hold (the bench
        stops, the step not ticked) at the first j for which hold_when(j)."""
        with self.lock:
            self.mode = "relay"
            self.offset = offset
            self.hold_when = hold_when
            self.held_evt.clear()
            self.step = -1
            self.after = set()

    def _supply(self, ids: set[int]) -> None:
        # sent on the watching socket: its own frames do not come back to it
        for i in sorted(ids):
            self.rx.send(pack(i, self.last_act[i]))
            self.supplied += 1

    # -- the test's side
    def wait_step(self, k: int, alive: list[Proc], timeout_s: float = 120.0) -> None:
        t_end = time.monotonic() + timeout_s
        while self.step < k:
            self.check(alive)
            assert time.monotonic() < t_end, f"bench stuck at step {self.step} (waiting for {k})"
            time.sleep(0.005)

    def check(self, alive: list[Proc]) -> None:
        assert self.error is None, f"FIU thread failed: {self.error!r}"
        for p in alive:
            assert p.poll() is None, f"{p.name} ended (exit {p.poll()}): {p.tail()}"

    def settle(self, quiet_s: float = 0.3, timeout_s: float = 10.0) -> None:
        t_end = time.monotonic() + timeout_s
        while time.monotonic() - self.t_last < quiet_s:
            assert time.monotonic() < t_end, "the bench did not stop after the cut"
            time.sleep(0.02)

    def cut(self, action: Callable[[], None]) -> int:
        """Take the ECU off the bus with action(); from then on keep its
        clock and the plant's held commands. Returns the step of the cut."""
        assert self.step >= 0 and len(self.last_act) == 2, "cut before the bench runs"
        with self.lock:
            self.mode = "cutting"
        action()
        self.settle()
        with self.lock:
            k = self.step
            self.mode = "cut"
            self._tick(k)                          # stale for the ECU if it ran k already
            self._supply(set(ACTUATORS) - self.after)
        return k

    def restore(self, action: Callable[[], None], timeout_s: float = 30.0) -> int:
        """Stop the bench at the plant's next step, put the ECU back with
        action(), restart that step through the bus. Returns that step."""
        with self.lock:
            self.held_evt.clear()
            self.mode = "hold"
        assert self.held_evt.wait(timeout_s), "the bench did not reach the next step"
        action()
        with self.lock:
            self.mode = "pass"
            k = self.held_at
            self._tick(k)
        return k

    def close(self) -> None:
        self.stop_evt.set()
        self.join(timeout=5)
        self.rx.close()
        self.clk.close()


class SlcanAdapter(threading.Thread):
    """The 'firmware' of a serial-line CAN adapter, on the master side of a
    pty whose slave carries the kernel's slcan line discipline: the ECU's
    interface canN is a real can-dev driver. The adapter is the ECU's
    transceiver on the bench: frames the ECU consumes go from the bench to
    the pty as slcan text, everything the ECU sends comes back onto the
    bench. It can report bus errors ('e'), error states ('s'), and go
    bus-off (it then forwards nothing either way, as a controller off the
    bus neither sends nor receives)."""

    def __init__(self, ids_to_ecu: list[int], bench: str = BENCH) -> None:
        super().__init__(daemon=True, name="slcan-adapter")
        self.master, self.slave = os.openpty()
        attrs = termios.tcgetattr(self.slave)
        attrs[0] = attrs[1] = attrs[3] = 0          # raw: no echo, no CR/LF mapping
        termios.tcsetattr(self.slave, termios.TCSANOW, attrs)
        fcntl.ioctl(self.slave, termios.TIOCSETD, struct.pack("i", N_SLCAN))
        self.ifname = fcntl.ioctl(self.slave, SIOCGIFNAME, bytes(16)).split(b"\0")[0].decode()
        sh("ip", "link", "set", "up", self.ifname)
        self.bench = can_sock(bench, ids_to_ecu, rcvbuf=8 << 20)
        self.stop_evt = threading.Event()
        self.forwarding = True
        self.buf = b""
        self.to_ecu = self.from_ecu = self.dropped = 0
        self.error: BaseException | None = None
        self.start()

    def run(self) -> None:
        try:
            while not self.stop_evt.is_set():
                r, _, _ = select.select([self.bench, self.master], [], [], 0.05)
                if self.bench in r:
                    can_id, data = unpack(self.bench.recv(16))
                    if self.forwarding:
                        os.write(self.master, b"t%03X%d%s\r" % (can_id & 0x7FF, len(data), data.hex().upper().encode()))
                        self.to_ecu += 1
                    else:
                        self.dropped += 1
                if self.master in r:
                    self.buf += os.read(self.master, 4096)
                    *lines, self.buf = self.buf.split(b"\r")
                    for ln in lines:
                        self._from_ecu(ln)
        except BaseException as e:  # noqa: BLE001 — reported by the test
            self.error = e

    def _from_ecu(self, ln: bytes) -> None:
        # the driver writes 't' + 3 hex id + dlc + data for a classic frame
        if len(ln) < 5 or ln[:1] != b"t":
            return
        if not self.forwarding:
            self.dropped += 1
            return
        n = ln[4] - 0x30
        self.bench.send(pack(int(ln[1:4], 16), bytes.fromhex(ln[5:5 + 2 * n].decode())))
        self.from_ecu += 1

    def report(self, text: str) -> None:
        """One slcan status line from the 'controller' to the driver, e.g.
        'e1a' (ACK error), 'sp128050' (error passive, rx 128 tx 50),
        'sb256256' (bus-off)."""
        os.write(self.master, text.encode() + b"\r")

    def close(self) -> None:
        self.stop_evt.set()
        self.join(timeout=5)
        self.bench.close()
        os.close(self.slave)       # the line discipline goes, and with it canN
        os.close(self.master)


@dataclass
class BusLog:
    """What a candump -L recording of the bench says, on simulated time (the
    last SimStep before each frame)."""
    dtc: list[tuple[int, dict]] = field(default_factory=list)      # (step, EcuDtc)
    status: list[tuple[int, dict]] = field(default_factory=list)   # (step, EcuStatus)
    diag: list[tuple[int, dict]] = field(default_factory=list)     # (step, EcuDiagnosis)
    plant: list[tuple[int, dict]] = field(default_factory=list)    # (step, SimPlantStatus)
    dcm: list[tuple[int, bytes]] = field(default_factory=list)     # (step, DcmSensor data)
    steps: int = 0
    errors: int = 0                                                # error frames

    def failed_codes(self, since: int = -1) -> set[int]:
        """Codes with testFailed or testFailedThisOperationCycle set in any
        EcuDtc frame from step `since` on."""
        return {d["DtcCode"] for k, d in self.dtc if k >= since and d["DtcCode"]
                and (d["DtcStsTestFailed"] or d["DtcStsTestFailedThisOpCycle"])}

    def last_dtc(self, code: int) -> tuple[int, dict] | None:
        got = [(k, d) for k, d in self.dtc if d["DtcCode"] == code]
        return got[-1] if got else None

    def first_failed(self, code: int) -> int | None:
        return next((k for k, d in self.dtc if d["DtcCode"] == code and d["DtcStsTestFailed"]), None)

    def deg_at(self, k: int) -> tuple[int, int] | None:
        got = [(s["StsDegStateDcm"], s["StsDegStateThr"]) for j, s in self.status if j <= k]
        return got[-1] if got else None


def read_bus(log: Path) -> BusLog:
    """Decode a candump -L log of the bench."""
    from canfdi.timeline import load_db
    db = load_db()
    msgs = {i: db.get_message_by_frame_id(i) for i in (ID_DTC, ID_STATUS, ID_DIAG, 0x610)}
    out = BusLog()
    k = -1
    for line in log.read_text().splitlines():
        parts = line.split()
        if len(parts) < 3 or "#" not in parts[2]:
            continue
        sid, _, hexdata = parts[2].partition("#")
        can_id = int(sid, 16)
        if len(sid) == 8 and can_id & CAN_ERR_FLAG:
            out.errors += 1
            continue
        data = bytes.fromhex(hexdata) if hexdata and not hexdata.startswith("R") else b""
        if can_id == ID_STEP and len(data) == 8:
            k = step_of(data)
            out.steps += 1
        elif can_id == 0x010 and len(data) == 8:
            out.dcm.append((k, data))
        elif can_id in msgs and len(data) == 8:
            d = msgs[can_id].decode(data, decode_choices=False)
            {ID_DTC: out.dtc, ID_STATUS: out.status, ID_DIAG: out.diag, 0x610: out.plant}[can_id].append((k, d))
    return out


class Candump:
    """candump -L of one interface into a file (C, keeps up with the bench)."""

    def __init__(self, ifname: str, path: Path, errors: bool = False) -> None:
        self.path = path
        path.unlink(missing_ok=True)
        self.f = path.open("w")
        args = ["candump", "-L", "-r", str(8 << 20)]
        self.p = subprocess.Popen(args + [ifname + (",0:0,#FFFFFFFF" if errors else "")],
                                  stdout=self.f, stderr=subprocess.DEVNULL)

    def stop(self, drain_s: float = 0.5) -> Path:
        # candump writes as it reads; let it catch up, then end it
        last, t_end = -1, time.monotonic() + 60
        while time.monotonic() < t_end:
            time.sleep(drain_s)
            size = self.path.stat().st_size
            if size == last:
                break
            last = size
        self.p.terminate()
        self.p.wait(timeout=10)
        self.f.close()
        return self.path


@dataclass
class Rig:
    """ECU (lockstep, --clock, NVM) + sim + FIU + candump of the bench; the
    test ends the run (finish) when it has seen what it wanted."""
    name: str
    ecu_iface: str
    scenario: Path
    nvm: Path | None = None
    extra_ecu: tuple[str, ...] = ()
    ecu: Proc | None = None
    sim: Proc | None = None
    fiu: Fiu | None = None
    dump: Candump | None = None
    stats: Path = field(init=False)

    def __post_init__(self) -> None:
        self.stats = OUT / f"{self.name}-ecu.json"
        self.stats.unlink(missing_ok=True)

    def start(self, relay: bool = False) -> "Rig":
        """relay: the ECU's clock comes from the Fiu only (with gw(True,
        clock_by_fiu=True))."""
        self.dump = Candump(BENCH, OUT / f"{self.name}.log")
        self.fiu = Fiu()
        if relay:
            self.fiu.relay(0)
        self.ecu = start_ecu(ECU, self.ecu_iface, lockstep=True, nvm=self.nvm,
                             extra=("--clock", CLOCK, "--stats", str(self.stats), *self.extra_ecu))
        self.sim = start_sim(SIM, BENCH, self.scenario, lockstep=True,
                             extra=("-d", "120", "--ecu-timeout", "60"))
        return self

    @property
    def procs(self) -> list[Proc]:
        return [p for p in (self.ecu, self.sim) if p is not None]

    def wait_s(self, t_s: float) -> None:
        assert self.fiu is not None
        self.fiu.wait_step(round(t_s * 1000), self.procs)

    def finish(self) -> tuple[BusLog, dict]:
        """Stop the sim, then the ECU: both must exit 0 on SIGTERM (the
        ECU must still be running)."""
        import json
        assert self.sim is not None and self.ecu is not None and self.dump is not None
        assert self.ecu.poll() is None, f"canfdi-ecu ended before SIGTERM: {self.ecu.tail()}"
        assert self.sim.stop() == 0, f"canfdi-sim: {self.sim.tail()}"
        assert self.ecu.stop() == 0, f"canfdi-ecu: {self.ecu.tail()}"
        log = read_bus(self.dump.stop())
        return log, json.loads(self.stats.read_text())

    def close(self) -> None:
        for p in self.procs:
            p.kill()
        if self.fiu is not None:
            self.fiu.close()
        if self.dump is not None and self.dump.p.poll() is None:
            self.dump.p.kill()
            self.dump.f.close()
