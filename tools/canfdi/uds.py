"""canfdi-uds: a workshop scan tool for the canfdi ECU over UDS (ISO 14229-1:2020)
on ISO-TP (ISO 15765-2), with udsoncan and can-isotp on a python-can bus.

The client configuration (data identifiers with units, extended-data size,
DTC descriptions, CAN ids) is tools/canfdi/uds_config.py, generated from
dbc/uds_dids.csv, dbc/dtcs.csv and dbc/canfdi.dbc. Commands that need the
extended session and SecurityAccess (routine, actuator, reset) open them
first with the documented key (tools/canfdi/uds_key.py).
"""
from __future__ import annotations

import argparse
import importlib
import sys
import time
from contextlib import contextmanager
from typing import Any, Callable, Iterator

import can
import isotp
import udsoncan
from udsoncan.client import Client
from udsoncan.connections import PythonIsoTpConnection
from udsoncan.services import DiagnosticSessionControl, ECUReset, ReadDTCInformation

from . import uds_config, uds_key
from .busargs import BusOpenError, add_bus_args, open_bus

STATUS_BITS = ("TF", "TFTOC", "PDTC", "CDTC", "TNCSLC", "TFSLC", "TNCTOC", "WIR")
ROUTINE_STATUS = {0: "running", 1: "passed", 2: "failed", 3: "aborted"}
LIVE = [0xD100, 0xD101, 0xD102, 0xD103, 0xD104, 0xD105, 0xD110, 0xD111, 0xD112, 0xD113, 0xD114, 0xD115,
        0xD400, 0xD401, 0xD402, 0xD403]
EPILOG = """examples:
  canfdi-uds -c vcan0 info                     identification
  canfdi-uds -c vcan0 dtc                      stored codes, status, description
  canfdi-uds -c vcan0 dtc --mask 0x01          codes failing now (testFailed)
  canfdi-uds -c vcan0 freeze P0122             freeze frame and extended data of a code
  canfdi-uds -c vcan0 live                     live values with units
  canfdi-uds -c vcan0 live estimates           parameter estimates (also: residuals, counters)
  canfdi-uds -c vcan0 clear                    clear all codes (also: P0122, throttle, dc_motor, comm)
  canfdi-uds -c vcan0 routine estimator-reset --dcm    after a new motor
  canfdi-uds -c vcan0 routine spring-check     throttle return spring test
  canfdi-uds -c vcan0 actuator angle 30 --hold 3       throttle to 30 deg for 3 s
  canfdi-uds -c vcan0 actuator speed 50 --hold 3       motor at 50 rad/s for 3 s
  canfdi-uds -c vcan0 reset                    ECU hard reset
exit status: 0 done, 1 the ECU refused or did not answer, 2 usage or bus error"""

GROUPS = {"estimates": [d for d in uds_config.DIDS if 0xD200 <= d < 0xD300],
          "residuals": [d for d in uds_config.DIDS if 0xD300 <= d < 0xD400],
          "counters": [d for d in uds_config.DIDS if 0xD500 <= d < 0xD600] + [0xDF00],
          "live": LIVE}


def dtc_code(dtc: int) -> str:
    """3-byte UDS DTC -> P0122 (SAE J2012: two letter bits, then four digits)."""
    return "PCBU"[(dtc >> 22) & 3] + f"{(dtc >> 20) & 3}{(dtc >> 8) & 0xFFF:03X}"


def code_to_dtc(code: str) -> int:
    for dtc, (c, _) in uds_config.DTCS.items():
        if c == code.upper():
            return dtc
    raise ValueError(f"unknown trouble code {code} (see dbc/dtcs.csv)")


def status_text(st: int) -> str:
    return ",".join(n for i, n in enumerate(STATUS_BITS) if st & (1 << i)) or "-"


def fmt_value(did: int, v: Any) -> str:
    name, _, _, unit, _ = uds_config.DIDS[did]
    if isinstance(v, float):
        if unit == "rad":
            return f"{v:.4f} rad ({v * 57.29577951:.2f} deg)"
        return f"{v:.4g} {unit}".rstrip()
    return f"{v} {unit}".rstrip()


class Tester:
    """A udsoncan client on the ECU's physical ISO-TP connection."""

    def __init__(self, client: Client, key_fn: Callable[[int, int], int]) -> None:
        self.c = client
        self.key_fn = key_fn

    def unlock(self, level: int = 1) -> None:
        self.c.change_session(DiagnosticSessionControl.Session.extendedDiagnosticSession)
        r = self.c.request_seed(2 * level - 1)
        check(r, "SecurityAccess requestSeed")
        seed = int.from_bytes(r.service_data.seed, "big")
        if seed != 0:
            check(self.c.send_key(2 * level, self.key_fn(seed, level).to_bytes(4, "big")), "SecurityAccess sendKey")

    def keep_alive(self, seconds: float) -> None:
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            time.sleep(min(1.0, max(0.0, end - time.monotonic())))
            with self.c.suppress_positive_response:
                self.c.tester_present()


class Refused(RuntimeError):
    """The ECU answered negatively or not at all."""


def check(resp: udsoncan.Response, what: str) -> udsoncan.Response:
    if not resp.positive:
        raise Refused(f"{what}: negative response 0x{resp.code:02X} ({resp.code_name})")
    return resp


@contextmanager
def connect(a: argparse.Namespace) -> Iterator[Tester]:
    # only the ECU's responses: on a loaded bus a Python reader would lag
    # behind the cyclic traffic and miss the response's timing
    bus = open_bus(a, can_filters=[{"can_id": uds_config.RESP_ID, "can_mask": 0x7FF}])
    try:
        addr = isotp.Address(isotp.AddressingMode.Normal_11bits, txid=uds_config.REQ_ID, rxid=uds_config.RESP_ID)
        stack = isotp.CanStack(bus, address=addr, params={
            "tx_padding": uds_config.ISOTP_PADDING, "tx_data_length": 8, "tx_data_min_length": 8,
            "stmin": 0, "blocksize": 0, "rx_flowcontrol_timeout": 1000, "rx_consecutive_frame_timeout": 1000})
        conn = PythonIsoTpConnection(stack)
        cfg = uds_config.client_config()
        cfg["request_timeout"] = a.timeout
        cfg["p2_timeout"] = a.timeout
        # the ECU's P2 (50 ms) holds in real time; a lockstep bench runs
        # slower, so --timeout governs, not the session's announced timing
        cfg["use_server_timing"] = False
        with Client(conn, config=cfg) as client:
            yield Tester(client, load_key(a.key_module))
    finally:
        bus.shutdown()


def load_key(module: str | None) -> Callable[[int, int], int]:
    if module is None:
        return uds_key.key
    return importlib.import_module(module).key  # type: ignore[no-any-return]


# ------------------------------------------------------------------ commands

def cmd_info(t: Tester, a: argparse.Namespace) -> int:
    r = check(t.c.read_data_by_identifier([0xF195, 0xF182, 0xF18C]), "ReadDataByIdentifier")
    for did, v in r.service_data.values.items():
        print(f"  {uds_config.DIDS[did][4]:<60} {v}")
    return 0


def cmd_dtc(t: Tester, a: argparse.Namespace) -> int:
    r = check(t.c.get_dtc_by_status_mask(a.mask), "ReadDTCInformation 0x02")
    dtcs = r.service_data.dtcs
    avail = r.service_data.status_availability
    avail_byte = avail.get_byte_as_int() if avail is not None else 0
    print(f"{len(dtcs)} trouble code(s) with status & 0x{a.mask:02X} (availability mask 0x{avail_byte:02X})")
    for d in dtcs:
        st = d.status.get_byte_as_int()
        desc = uds_config.DTCS.get(d.id, ("?", "not in dbc/dtcs.csv"))[1]
        print(f"  {dtc_code(d.id)}  0x{st:02X} {status_text(st):<34} {desc}")
    return 0


def cmd_freeze(t: Tester, a: argparse.Namespace) -> int:
    dtc = code_to_dtc(a.code)
    r = check(t.c.get_dtc_snapshot_by_dtc_number(dtc, record_number=0xFF), "ReadDTCInformation 0x04")
    d = r.service_data.dtcs[0]
    st = d.status.get_byte_as_int()
    print(f"{a.code}  status 0x{st:02X} {status_text(st)}  {uds_config.DTCS[dtc][1]}")
    if not d.snapshots:
        print("  no freeze frame stored")
    record = None
    for snap in d.snapshots:
        if snap.record_number != record:
            record = snap.record_number
            print(f"  freeze frame (record {record}):")
        print(f"    {uds_config.DIDS[snap.did][0]:<14} {fmt_value(snap.did, snap.data)}")
    r = check(t.c.get_dtc_extended_data_by_dtc_number(dtc, record_number=0xFF, data_size=uds_config.EXT_DATA_SIZE),
              "ReadDTCInformation 0x06")
    for ext in r.service_data.dtcs[0].extended_data:
        name = uds_config.EXT_RECORDS.get(ext.record_number, (f"record 0x{ext.record_number:02X}", ""))[0]
        print(f"  {name:<16} {ext.raw_data[0] if ext.raw_data else '-'}")
    return 0


def cmd_clear(t: Tester, a: argparse.Namespace) -> int:
    group = uds_config.GROUPS.get(a.what.lower()) if a.what else uds_config.GROUPS["all"]
    if group is None:
        group = code_to_dtc(a.what)
    check(t.c.clear_dtc(group), "ClearDiagnosticInformation")
    print(f"cleared {a.what or 'all'} (group 0x{group:06X})")
    return 0


def cmd_live(t: Tester, a: argparse.Namespace) -> int:
    dids: list[int] = []
    for w in a.dids or ["live"]:
        dids += GROUPS[w] if w in GROUPS else [int(w, 16)]
    for n in range(a.repeat):
        if n:
            time.sleep(a.period)
            print()
        for i in range(0, len(dids), 8):
            r = check(t.c.read_data_by_identifier(dids[i:i + 8]), "ReadDataByIdentifier")
            for did, v in r.service_data.values.items():
                print(f"  0x{did:04X} {uds_config.DIDS[did][0]:<22} {fmt_value(did, v)}")
    return 0


def cmd_routine(t: Tester, a: argparse.Namespace) -> int:
    t.unlock()
    if a.routine == "estimator-reset":
        mask = (1 if a.dcm else 0) | (2 if a.thr else 0) or 3
        r = check(t.c.start_routine(0x0201, bytes([mask])), "RoutineControl start")
        done = r.service_data.routine_status_record[:1] == b"\x01"
        print(f"estimator reset ({'DC motor' if mask == 1 else 'throttle' if mask == 2 else 'both'}): "
              f"{'done' if done else 'not done'}")
        return 0
    check(t.c.start_routine(0x0202), "RoutineControl start")
    status = 0
    deadline = time.monotonic() + 5.0
    rec = b""
    while status == 0 and time.monotonic() < deadline:
        time.sleep(0.2)
        rec = check(t.c.get_routine_result(0x0202), "RoutineControl results").service_data.routine_status_record
        status = rec[0]
    ms = int.from_bytes(rec[1:3], "big") if len(rec) >= 3 else 0
    angle = int.from_bytes(rec[3:7], "big", signed=True) / 65536.0 if len(rec) >= 7 else 0.0
    print(f"spring check: {ROUTINE_STATUS.get(status, '?')}, return time {ms} ms, angle {angle * 57.29577951:.1f} deg")
    return 0 if status == 1 else 1


def cmd_actuator(t: Tester, a: argparse.Namespace) -> int:
    t.unlock()
    did = 0xD115 if a.what == "angle" else 0xD104
    value = a.value / 57.29577951 if a.what == "angle" else a.value
    r = check(t.c.io_control(did, control_param=3, values=[value]), "InputOutputControlByIdentifier")
    print(f"{uds_config.DIDS[did][0]} held at {fmt_value(did, r.service_data.decoded_data)} for {a.hold:g} s")
    t.keep_alive(a.hold)
    check(t.c.io_control(did, control_param=0), "returnControlToECU")
    print("control returned to the ECU")
    return 0


def cmd_reset(t: Tester, a: argparse.Namespace) -> int:
    t.c.change_session(DiagnosticSessionControl.Session.extendedDiagnosticSession)
    check(t.c.ecu_reset(ECUReset.ResetType.hardReset), "ECUReset")
    print("ECU reset")
    return 0


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="canfdi-uds", description=__doc__, epilog=EPILOG,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    add_bus_args(p)
    p.add_argument("--timeout", type=float, default=2.0, help="response timeout, s (default 2)")
    p.add_argument("--key-module", help="module whose key(seed, level) replaces canfdi.uds_key.key")
    sub = p.add_subparsers(dest="cmd", required=True)
    sub.add_parser("info", help="identification: software version, calibration id, serial")
    s = sub.add_parser("dtc", help="trouble codes by status mask, with status bits and description")
    s.add_argument("--mask", type=lambda x: int(x, 0), default=0x2F,
                   help="status mask (default 0x2F: failed now, this cycle, pending, confirmed or since clear)")
    s = sub.add_parser("freeze", help="freeze frame and extended data (occurrence, aging) of one code")
    s.add_argument("code", help="e.g. P0122")
    s = sub.add_parser("clear", help="clear one code, a group (dc_motor, throttle, comm) or all")
    s.add_argument("what", nargs="?", help="code or group (default: all)")
    s = sub.add_parser("live", help="read data identifiers as a table")
    s.add_argument("dids", nargs="*", help="DIDs in hex or groups: live, estimates, residuals, counters")
    s.add_argument("--repeat", type=int, default=1)
    s.add_argument("--period", type=float, default=1.0, help="s between repeats")
    s = sub.add_parser("routine", help="run a routine (extended session, unlocked)")
    s.add_argument("routine", choices=["estimator-reset", "spring-check"])
    s.add_argument("--dcm", action="store_true", help="estimator reset: the DC motor's")
    s.add_argument("--thr", action="store_true", help="estimator reset: the throttle's")
    s = sub.add_parser("actuator", help="actuator test: throttle angle (deg) or motor speed (rad/s)")
    s.add_argument("what", choices=["angle", "speed"])
    s.add_argument("value", type=float)
    s.add_argument("--hold", type=float, default=3.0, help="s before control returns to the ECU")
    sub.add_parser("reset", help="ECU hard reset (extended session; motor at rest)")
    return p


COMMANDS: dict[str, Callable[[Tester, argparse.Namespace], int]] = {
    "info": cmd_info, "dtc": cmd_dtc, "freeze": cmd_freeze, "clear": cmd_clear, "live": cmd_live,
    "routine": cmd_routine, "actuator": cmd_actuator, "reset": cmd_reset}


def main(argv: list[str] | None = None) -> int:
    a = build_parser().parse_args(argv)
    try:
        with connect(a) as t:
            return COMMANDS[a.cmd](t, a)
    except BusOpenError as e:
        print(f"canfdi-uds: {e}", file=sys.stderr)
        return 2
    except ValueError as e:
        print(f"canfdi-uds: {e}", file=sys.stderr)
        return 2
    except (Refused, udsoncan.exceptions.TimeoutException, udsoncan.exceptions.NegativeResponseException,
            udsoncan.exceptions.UnexpectedResponseException, udsoncan.exceptions.InvalidResponseException) as e:
        print(f"canfdi-uds: {e}", file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main())
