"""canfdi-inject: send fault injections, clears and setpoints to the simulated plant.

The frames (SimFaultInject 0x600, SimFaultClear 0x601, SetpointDcm 0x100,
SetpointThr 0x101) are encoded by cantools from dbc/canfdi.dbc — never packed
by hand — so a range the DBC does not allow is refused before anything is
sent. Fault names come from the catalogue (dbc/faults.csv) and are checked
against the modes the fault allows, as the scenario parser does.

The setpoints are E2E protected like the vehicle's (CRC-8 over the data ID
and bytes 1..7, the rolling counter given with --counter, default 0). A
frame from this tool is a second sender on the vehicle's identifier: the
ECU usually rejects it and the vehicle's next one as counter errors (two
frames in SdgFramesRejected, no trouble code), while the simulated plant
takes it as an override and sends it on in its own sequence 10 ms later.

The builders (fault_frame, clear_frame, setpoint_frames) are public so tests
and other tools can make the same frames without a bus.
"""
from __future__ import annotations

import argparse
import difflib
import sys
from dataclasses import dataclass

import can

from .busargs import BusOpenError, add_bus_args, open_bus
from .catalogue import MODES, Fault, fault_by_name, load_faults
from .e2e import protect, protected_ids
from .timeline import load_db

EPILOG = """\
examples:
  canfdi-inject --list
  canfdi-inject fault thr_tps1_open
  canfdi-inject fault dcm_ra_up --mode incipient --magnitude 0.2 --ramp 4
  canfdi-inject fault com_dcm_timeout --mode intermittent --period 1 --duty 20 --delay 0.5
  canfdi-inject -i socketcan -c vcan0 clear all
  canfdi-inject setpoint --speed 120 --load 1.2 --angle 30     # E2E protected, counter 0

exit status: 0 sent, 1 the bus could not be opened or the send failed,
2 bad usage (unknown fault, mode not allowed, value out of the DBC's range).
"""


class UsageError(ValueError):
    """Bad input a user can fix; the CLI prints it and exits 2."""


@dataclass(frozen=True)
class Frame:
    """An encoded frame plus the words that say what it means."""
    msg: can.Message
    text: str


def lookup_fault(name: str) -> Fault:
    """Catalogue fault by name; UsageError naming close matches otherwise."""
    f = fault_by_name().get(name)
    if f is None or f.id == 0:
        close = difflib.get_close_matches(name, [x.name for x in load_faults()[1:]], n=3, cutoff=0.5)
        hint = f"; did you mean {', '.join(close)}?" if close else ""
        raise UsageError(f"unknown fault '{name}'{hint} (canfdi-inject --list shows the catalogue)")
    return f


def _encode(name: str, signals: dict[str, float | int], counter: int = 0) -> can.Message:
    """Encoded by cantools; an E2E protected frame gets its CRC and counter."""
    db = load_db()
    m = db.get_message_by_name(name)
    e2e = m.frame_id in protected_ids(db)
    if e2e:
        signals = {**signals, f"{name}Crc": 0, f"{name}Counter": 0}
    try:
        data = m.encode(signals, scaling=True, strict=True)
    except Exception as e:  # noqa: BLE001 — cantools reports ranges with several exception types
        raise UsageError(f"{name}: {e}") from None
    if e2e:
        data = bytes(protect(m.frame_id, bytearray(data), counter))
    return can.Message(arbitration_id=m.frame_id, data=data, is_extended_id=False)


def fault_frame(name: str, mode: str = "abrupt", magnitude: float | None = None, ramp_s: float | None = None,
                period_s: float | None = None, duty_pct: float | None = None, delay_s: float = 0.0) -> Frame:
    """SimFaultInject for a catalogue fault; magnitude None = the catalogue's default."""
    f = lookup_fault(name)
    if mode not in MODES:
        raise UsageError(f"unknown mode '{mode}' ({', '.join(MODES)})")
    if mode not in f.modes:
        raise UsageError(f"fault {f.name} cannot be {mode} (allowed: {', '.join(f.modes)})")
    ramp_or_period, duty = 0.0, 0.0
    if mode == "incipient":
        if ramp_s is None or ramp_s <= 0:
            raise UsageError("incipient needs --ramp S > 0 (time to reach the magnitude)")
        ramp_or_period = ramp_s
    elif mode == "intermittent":
        if period_s is None or period_s <= 0 or duty_pct is None or not 0 < duty_pct <= 100:
            raise UsageError("intermittent needs --period S > 0 and --duty PCT in (0, 100]")
        ramp_or_period, duty = period_s, duty_pct
    if mode != "incipient" and ramp_s is not None:
        raise UsageError("--ramp applies to incipient faults only")
    if mode != "intermittent" and (period_s is not None or duty_pct is not None):
        raise UsageError("--period/--duty apply to intermittent faults only")
    mag = f.default_magnitude if magnitude is None else magnitude
    msg = _encode("SimFaultInject", {"InjFaultId": f.id, "InjMode": MODES.index(mode), "InjDuty": round(duty),
                                     "InjMagnitude": mag, "InjRampOrPeriod": ramp_or_period,
                                     "InjStartDelay": delay_s})
    text = f"inject {f.name} ({f.id}) {mode}"
    text += " (binary)" if f.is_binary else f" magnitude {mag:g} {f.unit}"
    if mode == "incipient":
        text += f" over {ramp_s:g} s"
    if mode == "intermittent":
        text += f" period {period_s:g} s duty {duty:g} %"
    if delay_s:
        text += f", starting {delay_s:g} s after reception"
    return Frame(msg, text)


def clear_frame(name: str = "all") -> Frame:
    """SimFaultClear for one fault, or all (id 0)."""
    fid = 0 if name in ("all", "none") else lookup_fault(name).id
    return Frame(_encode("SimFaultClear", {"ClrFaultId": fid}), "clear " + ("all faults" if fid == 0 else name))


def setpoint_frames(speed: float | None = None, load: float | None = None, angle: float | None = None,
                    counter: int = 0) -> list[Frame]:
    """SetpointDcm (speed and load travel together) and/or SetpointThr, E2E
    protected with the rolling counter `counter` (0..15)."""
    out: list[Frame] = []
    if not 0 <= counter <= 15:
        raise UsageError(f"--counter {counter}: the E2E counter is 0..15")
    if (speed is None) != (load is None):
        raise UsageError("SetpointDcm carries speed and load together: give both --speed and --load")
    if speed is not None and load is not None:
        out.append(Frame(_encode("SetpointDcm", {"SpDcmSpeed": speed, "SpDcmLoad": load}, counter),
                         f"setpoint motor speed {speed:g} rad/s, load {load:g} N m"))
    if angle is not None:
        out.append(Frame(_encode("SetpointThr", {"SpThrAngle": angle}, counter),
                         f"setpoint throttle angle {angle:g} deg"))
    if not out:
        raise UsageError("setpoint: give --speed and --load, and/or --angle")
    return out


def catalogue_text() -> str:
    lines = [f"{'id':>2}  {'name':<24} {'modes':<31} {'default':>8} {'unit':<5} {'DTC':<11} description"]
    for f in load_faults()[1:]:
        lines.append(f"{f.id:>2}  {f.name:<24} {'|'.join(f.modes):<31} {f.default_magnitude:>8g} {f.unit:<5} "
                     f"{'+'.join(f.dtcs):<11} {f.description}")
    return "\n".join(lines)


def _magnitude(s: str) -> float | None:
    if s == "default":
        return None
    try:
        return float(s)
    except ValueError:
        raise argparse.ArgumentTypeError(f"'{s}' is neither a number nor 'default'") from None


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="canfdi-inject", description=__doc__.split("\n\n")[0],
                                epilog=EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    add_bus_args(p)
    p.add_argument("--list", action="store_true", help="print the fault catalogue and exit")
    sub = p.add_subparsers(dest="cmd", metavar="{fault,clear,setpoint}")
    pf = sub.add_parser("fault", help="inject a catalogue fault (SimFaultInject)")
    pf.add_argument("name", nargs="?", help="fault name from dbc/faults.csv")
    pf.add_argument("--list", dest="fault_list", action="store_true", help="print the fault catalogue and exit")
    pf.add_argument("--mode", choices=MODES, default="abrupt", help="time shape (default abrupt)")
    pf.add_argument("--magnitude", type=_magnitude, default=None, metavar="X|default",
                    help="in the catalogue's unit (rel, A, V, ...); default: the catalogue's")
    pf.add_argument("--ramp", type=float, metavar="S", help="incipient: seconds to reach the magnitude")
    pf.add_argument("--period", type=float, metavar="S", help="intermittent: period in seconds")
    pf.add_argument("--duty", type=float, metavar="PCT", help="intermittent: percent of each period on")
    pf.add_argument("--delay", type=float, default=0.0, metavar="S", help="start S seconds after reception")
    pc = sub.add_parser("clear", help="clear one injected fault or all (SimFaultClear)")
    pc.add_argument("name", nargs="?", default="all", help="fault name or 'all' (default)")
    ps = sub.add_parser("setpoint", help="override the scenario's setpoints (SetpointDcm/SetpointThr)")
    ps.add_argument("--speed", type=float, metavar="RAD_S", help="motor speed setpoint [rad/s]")
    ps.add_argument("--load", type=float, metavar="NM", help="known load torque [N m] (with --speed)")
    ps.add_argument("--angle", type=float, metavar="DEG", help="throttle angle setpoint [deg]")
    ps.add_argument("--counter", type=int, default=0, metavar="N",
                    help="E2E rolling counter of the frames, 0..15 (default 0); the CRC is always right")
    return p


def main(argv: list[str] | None = None) -> int:
    p = build_parser()
    a = p.parse_args(argv)
    if a.list or getattr(a, "fault_list", False):
        print(catalogue_text())
        return 0
    try:
        if a.cmd == "fault":
            if a.name is None:
                raise UsageError("fault: which one? give a NAME (canfdi-inject --list)")
            frames = [fault_frame(a.name, a.mode, a.magnitude, a.ramp, a.period, a.duty, a.delay)]
        elif a.cmd == "clear":
            frames = [clear_frame(a.name)]
        elif a.cmd == "setpoint":
            frames = setpoint_frames(a.speed, a.load, a.angle, a.counter)
        else:
            p.print_usage(sys.stderr)
            raise UsageError("nothing to do: give fault, clear or setpoint (or --list)")
    except UsageError as e:
        print(f"canfdi-inject: {e}", file=sys.stderr)
        return 2
    try:
        with open_bus(a) as bus:
            for fr in frames:
                bus.send(fr.msg, timeout=1.0)
                print(f"canfdi-inject: sent on {a.interface} {a.channel}: {fr.text}  "
                      f"[{fr.msg.arbitration_id:03X}#{bytes(fr.msg.data).hex().upper()}]")
    except BusOpenError as e:
        print(f"canfdi-inject: {e}", file=sys.stderr)
        return 1
    except (can.CanError, OSError) as e:
        print(f"canfdi-inject: send failed on {a.interface} {a.channel}: {e}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
