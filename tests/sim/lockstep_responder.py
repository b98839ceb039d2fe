"""A stand-in ECU for testing `canfdi-sim --can --lockstep` without the
firmware: answers every SimStep(k) with DcmActuator then ThrActuator
(constant commands, packed with cantools from dbc/canfdi.dbc, E2E from
tools/canfdi/e2e.py) and records every frame it sees, in bus order.

    .venv/bin/python tests/sim/lockstep_responder.py -c vcan0 --steps 1000 &
    build/hil/canfdi-sim --can vcan0 -d 1

Options follow python-can (-i/--interface, -c/--channel). It can also send
a fault injection and a setpoint override (E2E protected, counter 0) before
answering a given step (--inject-at K), which the tests use to check that
the sim obeys them.
Prints `responder: ready on CHANNEL` on stderr once the bus is open.
"""
from __future__ import annotations

import argparse
import os
import signal
import sys
import threading
from dataclasses import dataclass, field
from pathlib import Path

import can
import cantools

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "tools"))
from canfdi.e2e import protect  # noqa: E402

DBC = ROOT / "dbc" / "canfdi.dbc"
SIM_STEP_ID = 0x611


@dataclass
class Responder:
    """Answers SimStep frames on `bus` until `stop` is set or `steps` answered."""

    bus: can.BusABC
    steps: int | None = None
    inject_at: int | None = None
    dcm_ua_V: float = 12.0
    thr_u_V: float = 1.0
    record: list[can.Message] = field(default_factory=list)
    own: list[can.Message] = field(default_factory=list)   # the frames it sent itself
    answered: int = 0
    step_indices: list[int] = field(default_factory=list)
    stop: threading.Event = field(default_factory=threading.Event)

    def __post_init__(self) -> None:
        self.db = cantools.database.load_file(str(DBC))
        self.dcm = self.db.get_message_by_name("DcmActuator")
        self.thr = self.db.get_message_by_name("ThrActuator")
        self.step_msg = self.db.get_message_by_name("SimStep")

    def _actuators(self, k: int) -> list[can.Message]:
        d = bytearray(self.dcm.encode({"DcmActuatorCrc": 0, "DcmActuatorCounter": 0,
                                       "DcmBridgeSel": 1, "DcmEnable": 1,
                                       "DcmUaCmd": self.dcm_ua_V}))
        t = bytearray(self.thr.encode({"ThrActuatorCrc": 0, "ThrActuatorCounter": 0,
                                       "ThrEnable": 1, "ThrUCmd": self.thr_u_V}))
        protect(self.dcm.frame_id, d, k)
        protect(self.thr.frame_id, t, k)
        return [can.Message(arbitration_id=self.dcm.frame_id, data=d, is_extended_id=False),
                can.Message(arbitration_id=self.thr.frame_id, data=t, is_extended_id=False)]

    def _injection(self) -> list[can.Message]:
        inj = self.db.get_message_by_name("SimFaultInject")
        sp = self.db.get_message_by_name("SetpointDcm")
        return [
            can.Message(arbitration_id=inj.frame_id, is_extended_id=False, data=inj.encode(
                {"InjFaultId": 10, "InjMode": 0, "InjDuty": 0, "InjMagnitude": 1.0,
                 "InjRampOrPeriod": 0.0, "InjStartDelay": 0.05})),
            can.Message(arbitration_id=sp.frame_id, is_extended_id=False, data=protect(sp.frame_id, bytearray(
                sp.encode({"SetpointDcmCrc": 0, "SetpointDcmCounter": 0, "SpDcmSpeed": 123.0, "SpDcmLoad": 0.5})),
                0)),
        ]

    def _send(self, msg: can.Message) -> None:
        self.bus.send(msg)
        self.record.append(msg)  # own frames are not looped back to this socket
        self.own.append(msg)

    def run(self) -> None:
        while not self.stop.is_set():
            msg = self.bus.recv(timeout=0.2)
            if msg is None:
                continue
            self.record.append(msg)
            if msg.arbitration_id != SIM_STEP_ID:
                continue
            k = int(self.step_msg.decode(msg.data)["SimStepIndex"])
            self.step_indices.append(k)
            if self.inject_at is not None and k == self.inject_at:
                for m in self._injection():
                    self._send(m)
            for m in self._actuators(k):
                self._send(m)
            self.answered += 1
            if self.steps is not None and self.answered >= self.steps:
                break


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("-i", "--interface", default=os.environ.get("CAN_INTERFACE", "socketcan"))
    ap.add_argument("-c", "--channel", default=os.environ.get("CAN_CHANNEL", "vcan0"))
    ap.add_argument("--steps", type=int, default=None, help="exit after answering N steps")
    ap.add_argument("--inject-at", type=int, default=None,
                    help="before answering step K send SimFaultInject thr_tps1_open (delay "
                         "50 ms) and SetpointDcm 123 rad/s, 0.5 N m")
    args = ap.parse_args(argv)
    with can.Bus(interface=args.interface, channel=args.channel) as bus:
        r = Responder(bus, steps=args.steps, inject_at=args.inject_at)
        signal.signal(signal.SIGTERM, lambda *_: r.stop.set())
        signal.signal(signal.SIGINT, lambda *_: r.stop.set())
        print(f"responder: ready on {args.channel}", file=sys.stderr, flush=True)
        r.run()
    print(f"responder: answered {r.answered} steps", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
