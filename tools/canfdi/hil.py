"""The pieces of a HIL run: start the ECU and the sim, record the bus.

Kept apart from the canfdi-scenario command so that each can be tested
without vcan (a stub program for the ready handshake, python-can's virtual
interface for the recorder) and reused by tests/hil.

    ecu = start_ecu(Path("build/bin/canfdi-ecu"), "vcan0", lockstep=True)
    rec = Recorder(bus, Path("build/hil/x.log"))
    sim = start_sim(Path("build/bin/canfdi-sim"), "vcan0", scn_path, lockstep=True)
    sim.popen.wait(); rec.wait_quiet(); ecu.stop(); rec.close()
"""
from __future__ import annotations

import signal
import socket
import subprocess
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO

import can

from .timeline import ID_PLANT, ID_STEP, Timeline, load_db

READY_PREFIX = "canfdi-ecu: ready on"
#: Socket receive buffer asked for: the sim does not wait for the recorder, and
#: in User-Mode Linux python-can reads only ~1 k frames/s, so the kernel queue
#: must hold a whole burst (64 MB ~ 300 k frames of ~200 bytes of skb each).
RCVBUF_BYTES = 64 * 1024 * 1024
SO_RCVBUFFORCE = getattr(socket, "SO_RCVBUFFORCE", 33)


def vcan_unavailable(channel: str = "vcan0") -> str | None:
    """None if `channel` is a usable SocketCAN interface here, else why not
    (one line, ending with what to do). Used to skip or fail vcan tests."""
    try:
        s = socket.socket(socket.PF_CAN, socket.SOCK_RAW, socket.CAN_RAW)
    except (OSError, AttributeError) as e:
        return f"no SocketCAN in this kernel ({getattr(e, 'strerror', e)}); run under tools/vcan-run"
    try:
        s.bind((channel,))
    except OSError as e:
        return f"cannot bind {channel}: {e.strerror}; run under tools/vcan-run"
    finally:
        s.close()
    return None


class ProcError(RuntimeError):
    """A program of the run failed; str() says which, how, and its last words."""


@dataclass
class Proc:
    """A started program whose stderr is drained by a thread (never blocks on a full pipe)."""
    name: str
    popen: subprocess.Popen[str]
    lines: list[str] = field(default_factory=list)
    ready: threading.Event = field(default_factory=threading.Event)
    ready_prefix: str = ""

    def _drain(self, pipe: IO[str]) -> None:
        for line in pipe:
            self.lines.append(line.rstrip("\n"))
            if self.ready_prefix and line.startswith(self.ready_prefix):
                self.ready.set()
        pipe.close()

    def start_drain(self) -> None:
        assert self.popen.stderr is not None
        threading.Thread(target=self._drain, args=(self.popen.stderr,), daemon=True,
                         name=f"{self.name}-stderr").start()

    def tail(self, n: int = 5) -> str:
        return " | ".join(self.lines[-n:]) if self.lines else "(nothing on stderr)"

    def poll(self) -> int | None:
        return self.popen.poll()

    def stop(self, timeout_s: float = 10.0) -> int:
        """SIGTERM, wait; SIGKILL after timeout_s (then ProcError). Returns the exit status."""
        if self.popen.poll() is None:
            self.popen.send_signal(signal.SIGTERM)
            try:
                self.popen.wait(timeout=timeout_s)
            except subprocess.TimeoutExpired:
                self.popen.kill()
                self.popen.wait()
                raise ProcError(f"{self.name} did not exit within {timeout_s:g} s of SIGTERM; killed "
                                f"(last stderr: {self.tail()})") from None
        return self.popen.returncode

    def kill(self) -> None:
        if self.popen.poll() is None:
            self.popen.kill()
            self.popen.wait()


def _spawn(name: str, cmd: list[str], ready_prefix: str = "") -> Proc:
    try:
        popen = subprocess.Popen(cmd, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                                 stderr=subprocess.PIPE, text=True, errors="replace")
    except OSError as e:
        raise ProcError(f"cannot start {name} ({cmd[0]}): {e}") from None
    p = Proc(name, popen, ready_prefix=ready_prefix)
    p.start_drain()
    return p


def wait_ready(p: Proc, timeout_s: float) -> None:
    """Block until p printed its ready line; ProcError if it exits or times out first."""
    t_end = time.monotonic() + timeout_s
    while not p.ready.wait(0.05):
        rc = p.poll()
        if rc is not None:
            time.sleep(0.05)  # let the drain thread catch the last lines
            raise ProcError(f"{p.name} exited with status {rc} before it was ready: {p.tail()}")
        if time.monotonic() > t_end:
            p.kill()
            raise ProcError(f"{p.name} did not say '{p.ready_prefix} ...' within {timeout_s:g} s; killed "
                            f"(last stderr: {p.tail()})")


def start_ecu(ecu: Path, channel: str, lockstep: bool = True, nvm: Path | None = None,
              ready_timeout_s: float = 10.0, extra: tuple[str, ...] = ()) -> Proc:
    """Start canfdi-ecu and return once its socket is bound and filtered (its ready line)."""
    cmd = [str(ecu), "-c", channel] + (["--lockstep"] if lockstep else [])
    cmd += (["--nvm", str(nvm)] if nvm is not None else []) + list(extra)
    p = _spawn("canfdi-ecu", cmd, READY_PREFIX)
    wait_ready(p, ready_timeout_s)
    return p


def start_sim(sim: Path, channel: str, scenario: Path, lockstep: bool = True, seed: int | None = None,
              extra: tuple[str, ...] = ()) -> Proc:
    """Start canfdi-sim on the bus; it exits by itself at the scenario's end."""
    cmd = [str(sim), "--can", channel, "-s", str(scenario), "--lockstep" if lockstep else "--realtime", "-q"]
    cmd += (["--seed", str(seed)] if seed is not None else []) + list(extra)
    return _spawn("canfdi-sim", cmd)


def raise_rcvbuf(bus: can.BusABC, size: int = RCVBUF_BYTES) -> int | None:
    """Enlarge the receive queue of a SocketCAN bus; the size obtained, None if no socket.

    SO_RCVBUFFORCE ignores net.core.rmem_max but needs CAP_NET_ADMIN (we have
    it inside the sandbox); SO_RCVBUF is the unprivileged fallback.
    """
    sock = getattr(bus, "socket", None)
    if not isinstance(sock, socket.socket):
        return None
    for opt in (SO_RCVBUFFORCE, socket.SO_RCVBUF):
        try:
            sock.setsockopt(socket.SOL_SOCKET, opt, size)
            break
        except OSError:
            continue
    return int(sock.getsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF))


class Recorder(can.Listener):
    """Everything on the bus into a log (can.Logger: candump for .log), plus progress.

    Tracks simulated time for the progress bar from SimStep (lockstep) or
    SimPlantStatus (realtime), decoding only those two IDs so the notifier
    thread keeps up.
    """

    def __init__(self, bus: can.BusABC, log_path: Path, rcvbuf: int = RCVBUF_BYTES,
                 live: bool = False) -> None:
        super().__init__()
        #: With live, every frame is also decoded into a Timeline and its new
        #: events are printed at once (the technician's live view; costs the
        #: decoding of every frame in the notifier thread).
        self.live_tl: Timeline | None = Timeline() if live else None
        self._live_printed = 0
        log_path.parent.mkdir(parents=True, exist_ok=True)
        self.bus = bus
        self.log_path = log_path
        self.rcvbuf = raise_rcvbuf(bus, rcvbuf)
        self.frames = 0
        self.last_step = -1
        self.sim_time_s = 0.0
        self.t_first = 0.0
        self.t_last = 0.0
        self.error: BaseException | None = None
        db = load_db()
        self._step_msg = db.get_message_by_frame_id(ID_STEP)
        self._pst_msg = db.get_message_by_frame_id(ID_PLANT)
        self.logger = can.Logger(str(log_path))
        self.notifier = can.Notifier(bus, [self.logger, self], timeout=0.1)

    def on_message_received(self, msg: can.Message) -> None:
        now = time.monotonic()
        if self.frames == 0:
            self.t_first = now
        self.frames += 1
        self.t_last = now
        if self.live_tl is not None:
            self.live_tl.feed(msg)
            events = self.live_tl.events
            while self._live_printed < len(events):
                print(events[self._live_printed].line(), flush=True)
                self._live_printed += 1
        try:
            if msg.arbitration_id == ID_STEP and len(msg.data) == 8:
                self.last_step = int(self._step_msg.decode(bytes(msg.data))["SimStepIndex"])
                self.sim_time_s = (self.last_step + 1) * 1e-3
            elif msg.arbitration_id == ID_PLANT and len(msg.data) == 8 and self.last_step < 0:
                self.sim_time_s = float(self._pst_msg.decode(bytes(msg.data))["PstSimTime"])
        except Exception:  # noqa: BLE001 — a broken frame is the timeline's business, not the recorder's
            pass

    def on_error(self, exc: Exception) -> None:
        self.error = exc

    def idle_s(self) -> float:
        """Wall-clock seconds since the last frame (since now if none yet)."""
        return time.monotonic() - self.t_last if self.frames else 0.0

    def wait_quiet(self, quiet_s: float = 0.5, max_s: float = 60.0) -> bool:
        """Let the queue drain: until no frame for quiet_s; False if still busy after max_s."""
        t_end = time.monotonic() + max_s
        mark = time.monotonic()
        while time.monotonic() < t_end:
            last = self.t_last if self.frames else mark
            if time.monotonic() - max(last, mark) >= quiet_s:
                return True
            time.sleep(0.05)
        return False

    def stop(self) -> None:
        """can.Listener's hook, called by the notifier for every listener: nothing to release."""

    def close(self) -> None:
        """Stop receiving and close the log (flushes it)."""
        self.notifier.stop()
        self.logger.stop()


def fmt_rate(frames: int, seconds: float) -> str:
    return f"{frames / seconds:.0f} frames/s" if seconds > 0 else "-"
