"""What a replay found: the core's event stream (tools/replay/README.md) folded into a report.

A trouble code is a *finding* at the first log time at which its
testFailed bit is set in the replay while one of its monitors is judged
(see CODE_MONITORS): a code that fails during a settling time or a gap in
the log and still fails afterwards is found when the monitor is judged
again; one that only failed while nothing could be judged is listed with
the monitor's span under ``not_judged``, never as a finding.

The JSON report (``Report.to_json``) has this schema (version
``canfdi-replay/1``; times are seconds on each log's own time base;
tests/replay/test_replay_report.py checks that every key of a report is
named here):

    schema        "canfdi-replay/1"
    tool          the program that wrote it ("canfdi-replay")
    firmware      {id: a hash of the firmware's sources ("fw-sha256:..."),
                   sw_version: the software version the ECU reports (UDS DID
                   F195), calibration: the calibration the replay runs
                   (canfdi_app_default_cal), calibration_id: its id (DID F182)}
    dbc           {path, sha256} of dbc/canfdi.dbc
    map           null; with --map {path, sha256, dbc, dbc_sha256 (the other
                  bus's DBC), inputs {input: its source}, codes_not_applied
                  {code: why}, models_not_judged {plant: why}}
    settle_s      the settling time after a mid-drive start or a gap
    logs          per log, in command-line order: [{index, path, format
                  (candump asc blf trc csv mf4), sha256 (of the file), lines
                  (candump lines the core read: a text format's lines up to its
                  last frame, BLF/MF4 frames), frames, steps, first_s, last_s,
                  clock (timestamps, simstep), grid_moves (timestamps clock:
                  times the step grid followed the sensor frames,
                  tools/replay/README.md), channel, start (power-up, mid-drive),
                  start_decided_by (frames, option), settled_from_s (the models
                  judged from here), recorded_ecu {frames, identical, differing,
                  recorded_only, replay_only, first_difference {t, id,
                  recorded, replay} | null}}]
    dtcs          one per trouble code the replay found, by log and time:
                  [{code ("P0122"), description, log (index),
                  first_failed_s (the finding: the first time its testFailed
                  bit is set while one of its monitors is judged),
                  first_testfailed_s (when that testFailed bit rose: earlier
                  only when it rose in a span not judged), status_at_finding
                  (UDS status byte then), status (the status byte at the end of
                  the last log), status_bits {TF, TFTOC, PDTC, CDTC, TNCSLC,
                  TFSLC, TNCTOC, WIR} of it, occurrence, freeze_frame (SI units,
                  the core's "mem" event) | null, confidence_pct | null,
                  confidence_basis, degradation {dcm, thr} at the finding,
                  evidence {components [{component, symptoms, normalised,
                  fired, result}], flags, residuals_over_threshold,
                  parameter_deviation_pct, rules [{fault, kind, pattern,
                  required, forbidden, note}]}, recorded_ecu_first_failed_s |
                  null}]
    recorded_ecu_only  codes the recorded ECU reported that the replay did not
                  find: [{code, log, first_failed_s, judged (its monitors were
                  judged there), why}]
    not_judged    per log and monitor with spans not judged: [{log, monitor,
                  what, codes, spans [{from_s, to_s, why}] (the first 200),
                  span_count, seconds, fraction (of the log)}]
    data_quality  per log: [{log, bad_line_count, bad_lines [{line, why, text}]
                  (line: the file's line; for BLF and MF4 the frame's number;
                  -1 the file as a whole), read_errors [{line, why}], truncated,
                  gaps [{from_s, to_s, seconds}], gap_count, time_stamps_back,
                  time_stamps_back_first [{line, at_s, by_s}], rebased [{line,
                  at_s, back_s}], time_stamp_outliers, time_stamp_outliers_first
                  [{line, at_s, stamp_s}], rejected_frames {frame: {length, crc,
                  counter, implausible, timeouts}}, accepted_frames {frame: n},
                  error_frames, error_frames_first [{line, at_s}], fd_frames,
                  fd_first_line, remote_frames, extended_frames, other_channels
                  {name: {frames, first_line}}, unknown_ids {hex id ("x" prefix:
                  29-bit): frames}, recorded_commands_bad_crc,
                  recorded_ecu_dtc_frames_failing_e2e (forged or corrupted
                  EcuDtc frames, not taken as the ECU's), simstep_rejected,
                  bus_load_pct {bitrate, mean, max, note}, missing_frames
                  [{frame, from_s, to_s, never_received}], rx_errors_per_second
                  [{t, frame, length, crc, counter, implausible, timeouts}] (the
                  first 200)}]
    exit_status   1 a code found, else 0 (canfdi-replay exits 3 instead of 0
                  when nothing could be judged)
"""
from __future__ import annotations

import csv
import json
import re
from dataclasses import dataclass, field
from typing import Any

from . import REPO_ROOT
from .catalogue import dtc_by_code, load_dtcs, load_faults

SCHEMA = "canfdi-replay/1"
DIAG_RULES_CSV = REPO_ROOT / "dbc" / "diag_rules.csv"

#: The monitors of the core (its "mon" events) and the codes they judge.
#: P2119 (jam) has two: the model rule and the tracking monitor's hard rule.
MONITORS: dict[str, str] = {
    "com_dcm": "DcmSensor frame checks (timeout, counter, CRC, length, range)",
    "com_thr": "ThrSensor frame checks (timeout, counter, CRC, length, range)",
    "com_sp": "SetpointDcm and SetpointThr frame checks (timeout, counter, CRC, length, range)",
    "tps_range": "TPS1/TPS2 range checks",
    "dcm_models": "DC-motor parity equations and parameter estimator",
    "dcm_cmd": "DC-motor power-stage check and U_A against the command",
    "thr_models": "throttle parity equations, estimator, 2-out-of-3 vote with the model, actuator monitors",
    "thr_tracking": "throttle tracking monitor (the valve follows its position reference)",
}
CODE_MONITORS: dict[str, tuple[str, ...]] = {
    **{c: ("com_dcm",) for c in ("U1A00", "U1A10", "U1A20", "U1A30", "U1A40")},
    **{c: ("com_thr",) for c in ("U1A01", "U1A11", "U1A21", "U1A31", "U1A41")},
    **{c: ("com_sp",) for c in ("U1A50", "U1A51")},
    **{c: ("tps_range",) for c in ("P0122", "P0123", "P0222", "P0223")},
    **{c: ("dcm_models",) for c in ("P1A10", "P1A11", "P1A12", "P1A20", "P1A21")},
    **{c: ("dcm_cmd",) for c in ("P1A22", "P1A30", "P1A31")},
    **{c: ("thr_models",) for c in ("P0121", "P0221", "P2135", "P0638", "P1B10", "P2101", "P2100")},
    "P2119": ("thr_models", "thr_tracking"),
}
#: The input frames a communication monitor judges: where one of them is
#: not in the recording at all, the monitor is not judged (its timeout
#: would say nothing about the bus). The setpoints share their codes, so
#: both must be there.
MONITOR_FRAMES: dict[str, tuple[str, ...]] = {"com_dcm": ("DcmSensor",), "com_thr": ("ThrSensor",),
                                              "com_sp": ("SetpointDcm", "SetpointThr")}
STATUS_BITS = ("TF", "TFTOC", "PDTC", "CDTC", "TNCSLC", "TFSLC", "TNCTOC", "WIR")
DCM_CHANNELS = ("r1", "r2", "r3", "r4", "R_A", "Psi", "J", "M_c", "J/Psi", "UAC")
THR_CHANNELS = ("CORR", "ARM", "POS1", "POS2", "R", "K", "spring", "friction", "-", "-")
SYMPTOMS_H = REPO_ROOT / "firmware" / "diag" / "canfdi_symptoms.h"


def load_flag_names(path=SYMPTOMS_H) -> dict[int, str]:
    """Bit number -> name of the firmware's symptom flags, read from the
    header that defines them (CANFDI_SYM_F_<NAME> (1UL << <bit>)), so the
    report names exactly the flags of the firmware it replays."""
    names: dict[int, str] = {}
    pat = re.compile(r"#define\s+CANFDI_SYM_F_(\w+)\s+\(1UL\s*<<\s*(\d+)\)")
    for m in pat.finditer(path.read_text(encoding="utf-8")):
        names[int(m.group(2))] = m.group(1)
    return names


FLAG_NAMES = load_flag_names()
SYM_TEXT = {-1: "-", 0: "0", 1: "+", 2: "?"}
DEG_NAMES = ("normal", "degraded", "fail_safe", "fail_silent")


def status_text(st: int) -> str:
    """What a technician reads of a status byte."""
    if st & 0x08:
        return "confirmed" if st & 0x01 else "stored"
    if st & 0x04:
        return "pending" if st & 0x01 else "pending, passed"
    return "testFailed" if st & 0x01 else "passed"


def where(fmt: str, line: int) -> str:
    """A place in a log as a person reads it: "line N", for BLF and MF4 (no lines) "frame N"."""
    if line < 0:
        return "the file"
    return f"{'frame' if fmt in ('blf', 'mf4') else 'line'} {line}"


def status_bits(st: int) -> dict[str, int]:
    return {name: (st >> i) & 1 for i, name in enumerate(STATUS_BITS)}


def _rules() -> dict[str, list[dict[str, str]]]:
    out: dict[str, list[dict[str, str]]] = {}
    with DIAG_RULES_CSV.open(newline="", encoding="utf-8") as f:
        for row in csv.DictReader(f):
            out.setdefault(row["fault"], []).append(row)
    return out


@dataclass
class Span:
    t0: float
    t1: float
    why: str


@dataclass
class LogState:
    """Everything the events said about one log."""
    index: int
    path: str = ""
    fmt: str = "candump"
    sha256: str = ""
    clock: str = ""
    channel: str = ""
    start: str = ""
    start_decided_by: str = ""
    settle_until: float = 0.0
    eof: dict[str, Any] = field(default_factory=dict)
    agree: dict[str, Any] = field(default_factory=dict)
    mismatch: dict[str, Any] | None = None
    dtc_rep: dict[str, list[tuple[float, int, int]]] = field(default_factory=dict)
    dtc_ecu: dict[str, list[tuple[float, int, int]]] = field(default_factory=dict)
    why_at: dict[tuple[str, float], dict[str, Any]] = field(default_factory=dict)
    mon: dict[str, list[tuple[float, bool, str]]] = field(default_factory=dict)
    deg: list[dict[str, Any]] = field(default_factory=list)
    iso: list[dict[str, Any]] = field(default_factory=list)
    samples: list[dict[str, Any]] = field(default_factory=list)
    frames: list[dict[str, Any]] = field(default_factory=list)
    rxq: list[dict[str, Any]] = field(default_factory=list)
    bus: list[dict[str, Any]] = field(default_factory=list)
    gaps: list[tuple[float, float]] = field(default_factory=list)
    bad: list[dict[str, Any]] = field(default_factory=list)
    back: list[dict[str, Any]] = field(default_factory=list)
    rebase: list[dict[str, Any]] = field(default_factory=list)
    errframes: list[dict[str, Any]] = field(default_factory=list)
    outliers: list[dict[str, Any]] = field(default_factory=list)
    fd: list[dict[str, Any]] = field(default_factory=list)
    readerr: list[dict[str, Any]] = field(default_factory=list)
    input_problems: list[tuple[str, int, str, str]] = field(default_factory=list)
    input_problem_count: int = 0
    input_truncated: bool = False

    @property
    def last_t(self) -> float:
        return float(self.eof.get("last_t", 0.0))

    @property
    def end_t(self) -> float:
        """The end of the last step (spans close here)."""
        return self.last_t + 0.001

    def tested_spans(self, monitor: str) -> list[tuple[float, float]]:
        if any(self.never_received(f) for f in MONITOR_FRAMES.get(monitor, ())):
            return []
        ev = self.mon.get(monitor, [])
        out = []
        for i, (t, tested, _) in enumerate(ev):
            t1 = ev[i + 1][0] if i + 1 < len(ev) else self.end_t
            if tested and t1 > t:
                out.append((t, t1))
        return out

    def never_received(self, frame: str) -> bool:
        """The input frame is not in the recording at all (a logger's filter, a mapped bus)."""
        rx = self.eof.get("rx", {}).get(frame)
        return rx is not None and not any(f["received"] for f in self.frames if f["name"] == frame)

    def untested_spans(self, monitor: str) -> list[Span]:
        first = float(self.eof.get("first_t", 0.0))
        frame = next((f for f in MONITOR_FRAMES.get(monitor, ()) if self.never_received(f)), None)
        if frame:
            return [Span(first, self.end_t, f"{frame} is not in the recording (its timeout says nothing "
                                            f"about the bus)")]
        ev = self.mon.get(monitor, [])
        out: list[Span] = []
        if ev and ev[0][0] > first:
            out.append(Span(first, ev[0][0], "deciding whether the log starts at the recorded ECU's power-up"))
        for i, (t, tested, why) in enumerate(ev):
            t1 = ev[i + 1][0] if i + 1 < len(ev) else self.end_t
            if not tested and t1 > t:
                if out and out[-1].why == why and abs(out[-1].t1 - t) < 1e-9:
                    out[-1].t1 = t1
                else:
                    out.append(Span(t, t1, why))
        if not ev and self.eof.get("steps", 0):
            out.append(Span(first, self.end_t, "the log ended before it could be judged"))
        return out


def _tf_intervals(series: list[tuple[float, int, int]], end: float) -> list[tuple[float, float]]:
    out = []
    on: float | None = None
    for t, st, _ in series:
        if st & 1 and on is None:
            on = t
        elif not st & 1 and on is not None:
            out.append((on, t))
            on = None
    if on is not None:
        out.append((on, end))
    return out


def _first_overlap(a: list[tuple[float, float]], b: list[tuple[float, float]]) -> float | None:
    best: float | None = None
    for a0, a1 in a:
        for b0, b1 in b:
            lo, hi = max(a0, b0), min(a1, b1)
            if lo < hi or (lo == hi and a0 == a1):
                best = lo if best is None else min(best, lo)
    return best


def _state_at(series: list[dict[str, Any]], t: float) -> dict[str, Any] | None:
    last = None
    for e in series:
        if e["t"] > t + 1e-9:
            break
        last = e
    return last


class Report:
    """Fold events with feed(); then findings(), not_judged(), to_json()."""

    def __init__(self) -> None:
        self.hdr: dict[str, Any] = {}
        self.logs: list[LogState] = []
        self.memory: dict[str, dict[str, Any]] = {}
        self.end: dict[str, Any] = {}
        self.power_cycles: list[dict[str, Any]] = []
        self._last_rise: tuple[int, str, float] | None = None
        self.map_info: dict[str, Any] | None = None
        self.dbc: dict[str, str] = {}

    def log(self, i: int) -> LogState:
        while len(self.logs) <= i:
            self.logs.append(LogState(index=len(self.logs)))
        return self.logs[i]

    # ------------------------------------------------------------ events
    def feed(self, e: dict[str, Any]) -> None:
        kind = e["ev"]
        if kind == "hdr":
            self.hdr = e
            return
        if kind == "mem":
            self.memory[e["code"]] = e
            return
        if kind == "end":
            self.end = e
            return
        if kind in ("power_cycle", "nvm_in"):
            self.power_cycles.append(e)
            return
        if kind == "why":
            if self._last_rise is not None:
                i, code, t = self._last_rise
                self.log(i).why_at[(code, t)] = e
            return
        lg = self.log(int(e.get("file", 0)))
        if kind == "s":
            lg.samples.append(e)
        elif kind == "bus":
            lg.bus.append(e)
        elif kind == "dtc":
            series = lg.dtc_rep if e["src"] == "replay" else lg.dtc_ecu
            s = series.setdefault(e["code"], [])
            prev = s[-1][1] if s else 0
            s.append((e["t"], e["status"], e["occ"]))
            if e["src"] == "replay" and e["status"] & 1 and not prev & 1:
                self._last_rise = (lg.index, e["code"], e["t"])
        elif kind == "mon":
            lg.mon.setdefault(e["mon"], []).append((e["t"], bool(e["tested"]), e.get("why", "")))
        elif kind == "deg":
            lg.deg.append(e)
        elif kind == "iso":
            lg.iso.append(e)
        elif kind == "file":
            lg.path = lg.path or e["name"]
        elif kind == "clock":
            lg.clock = e["clock"]
        elif kind == "channel":
            lg.channel = e["name"]
        elif kind == "start":
            lg.start = e["mode"]
            lg.start_decided_by = e["decided_by"]
            lg.settle_until = float(e["settle_until"])
        elif kind == "eof":
            lg.eof = e
            if e.get("channel"):
                lg.channel = e["channel"]
        elif kind == "agree":
            lg.agree = e
        elif kind == "mismatch":
            lg.mismatch = e
        elif kind == "frame":
            lg.frames.append(e)
        elif kind == "rxq":
            lg.rxq.append(e)
        elif kind == "gap":
            lg.gaps.append((e["t0"], e["t1"]))
        elif kind == "bad":
            lg.bad.append(e)
        elif kind == "back":
            lg.back.append(e)
        elif kind == "rebase":
            lg.rebase.append(e)
        elif kind == "errframe":
            lg.errframes.append(e)
        elif kind == "outlier":
            lg.outliers.append(e)
        elif kind == "fd":
            lg.fd.append(e)
        elif kind == "readerr":
            lg.readerr.append(e)
        else:
            pass  # progress and future events

    # ------------------------------------------------------------ results
    def judged_spans(self, lg: LogState, code: str) -> list[tuple[float, float]]:
        spans: list[tuple[float, float]] = []
        for m in CODE_MONITORS.get(code, ()):
            spans.extend(lg.tested_spans(m))
        return spans

    def not_applied_codes(self) -> dict[str, str]:
        """Codes whose checks cannot apply to the whole recording (mapped inputs)."""
        if not self.map_info:
            return {}
        return dict(self.map_info.get("codes_not_applied", {}))

    def findings(self) -> list[dict[str, Any]]:
        out = []
        dtcs = dtc_by_code()
        faults = load_faults()
        rules = _rules()
        na = self.not_applied_codes()
        for lg in self.logs:
            for code, series in lg.dtc_rep.items():
                if code in na:
                    continue
                tf = _tf_intervals(series, lg.end_t)
                t = _first_overlap(tf, self.judged_spans(lg, code))
                if t is None:
                    continue
                rise = max((a for a, _ in tf if a <= t + 1e-9), default=t)
                why = lg.why_at.get((code, rise), {})
                st_now = [s for s in series if s[0] <= t + 1e-9]
                d = dtcs.get(code)
                ecu = _tf_intervals(lg.dtc_ecu.get(code, []), lg.end_t)
                deg = _state_at(lg.deg, t)
                f = {
                    "code": code,
                    "description": d.description if d else "",
                    "log": lg.index,
                    "first_failed_s": round(t, 6),
                    "first_testfailed_s": round(rise, 6),
                    "status_at_finding": st_now[-1][1] if st_now else None,
                    "degradation": {"dcm": deg["dcm"], "thr": deg["thr"]} if deg else None,
                    "recorded_ecu_first_failed_s": round(ecu[0][0], 6) if ecu else None,
                }
                f.update(self._confidence(code, why, faults))
                f["evidence"] = self._evidence(code, why, rules, faults)
                mem = self.memory.get(code)
                f["status"] = mem["status"] if mem else None
                f["status_bits"] = status_bits(mem["status"]) if mem else None
                f["occurrence"] = mem["occ"] if mem else None
                f["freeze_frame"] = mem["ff"] if mem else None
                out.append(f)
        out.sort(key=lambda f: (f["log"], f["first_failed_s"], f["code"]))
        return out

    def _confidence(self, code: str, why: dict[str, Any], faults: Any) -> dict[str, Any]:
        d = dtc_by_code().get(code)
        ids = d.fault_ids if d else ()
        if code.startswith("U"):
            return {"confidence_pct": 100, "confidence_basis": "frame check of the input supervision"}
        if not ids:
            return {"confidence_pct": None, "confidence_basis": "detected, not isolated to a sensor"}
        comp = 0 if faults[ids[0]].component == "dc_motor" else 1
        res = why.get("res", [{}, {}])[comp] if why else {}
        if res.get("isolated") in ids:
            return {"confidence_pct": res.get("conf"),
                    "confidence_basis": "fault-symptom reasoning: the isolated fault's confidence "
                                        "(a hard rule is 100 %)"}
        mgr = why.get("mgr_detected", 0) if why else 0
        if any(mgr >> i & 1 for i in ids):
            return {"confidence_pct": 100, "confidence_basis": "the actuator manager's plausibility check"}
        flags = why.get("faults", 0) if why else 0
        if any(flags >> i & 1 for i in ids):
            return {"confidence_pct": 100, "confidence_basis": "hard rule"}
        return {"confidence_pct": None, "confidence_basis": "no isolation recorded at the first failure"}

    def _evidence(self, code: str, why: dict[str, Any], rules: dict[str, list[dict[str, str]]],
                  faults: Any) -> dict[str, Any]:
        if not why:
            return {}
        d = dtc_by_code().get(code)
        ids = d.fault_ids if d else ()
        ev: dict[str, Any] = {}
        comps = []
        for c, names in ((0, DCM_CHANNELS), (1, THR_CHANNELS)):
            sym = why["sym"][c]
            x = why["x"][c]
            fired = [f"{names[i]} {SYM_TEXT.get(sym[i], '?')} ({x[i]:+.2f})" for i in range(len(names))
                     if names[i] != "-" and sym[i] in (-1, 1)]
            comps.append({"component": ("dc_motor", "throttle")[c],
                          "symptoms": {names[i]: SYM_TEXT.get(sym[i], "?") for i in range(len(names))
                                       if names[i] != "-"},
                          "normalised": {names[i]: round(x[i], 3) for i in range(len(names)) if names[i] != "-"},
                          "fired": fired, "result": why["res"][c]})
        ev["components"] = comps
        ev["flags"] = [FLAG_NAMES.get(i, f"flag{i}") for i, s in enumerate(why.get("flag_sym", [])) if s in (1, -1)]
        ev["residuals_over_threshold"] = {n: round(v, 3) for n, v in
                                          zip(("dcm r1", "dcm r2", "dcm r3", "dcm r4", "thr CORR", "thr ARM",
                                               "thr POS1", "thr POS2"), why["rn"]) if abs(v) >= 1.0}
        ev["parameter_deviation_pct"] = {n: round(100 * v, 2) for n, v in
                                         zip(("R_A", "Psi", "J", "M_c", "thr R", "thr K", "spring", "friction"),
                                             why["pd"])}
        ev["rules"] = [{"fault": faults[i].name, "kind": r["kind"], "pattern": r["pattern"],
                        "required": r["required"], "forbidden": r["forbidden"], "note": r["note"]}
                       for i in ids for r in rules.get(faults[i].name, [])]
        if code.startswith("U"):
            ev["rules"] = [{"fault": faults[i].name, "kind": "frame check",
                            "note": "input supervision (comm/canfdi_rx.h): three bad frames qualify"}
                           for i in ids]
        return ev

    def recorded_only(self) -> list[dict[str, Any]]:
        """Codes the recorded ECU reported that the replay did not find, and why."""
        found = {(f["log"], f["code"]) for f in self.findings()}
        out = []
        for lg in self.logs:
            for code, series in lg.dtc_ecu.items():
                tf = _tf_intervals(series, lg.end_t)
                if not tf or (lg.index, code) in found:
                    continue
                t = tf[0][0]
                untested = [s for m in CODE_MONITORS.get(code, ()) for s in lg.untested_spans(m)
                            if s.t0 <= t + 1e-9 or s.t1 >= t]
                judged = bool(self.judged_spans(lg, code))
                why = "; ".join(sorted({s.why for s in untested})) or "the replay did not find it"
                out.append({"code": code, "log": lg.index, "first_failed_s": round(t, 6),
                            "judged": judged and not untested, "why": why})
        return out

    def not_judged(self) -> list[dict[str, Any]]:
        out = []
        na = self.not_applied_codes()
        for lg in self.logs:
            dur = max(lg.end_t - float(lg.eof.get("first_t", 0.0)), 1e-9)
            for m in MONITORS:
                spans = lg.untested_spans(m)
                if not spans:
                    continue
                secs = sum(s.t1 - s.t0 for s in spans)
                out.append({"log": lg.index, "monitor": m, "what": MONITORS[m],
                            "codes": sorted(c for c, ms in CODE_MONITORS.items() if m in ms),
                            "spans": [{"from_s": round(s.t0, 6), "to_s": round(s.t1, 6), "why": s.why}
                                      for s in spans[:200]],
                            "span_count": len(spans),
                            "seconds": round(secs, 3), "fraction": round(secs / dur, 4)})
            for code, why in na.items():
                out.append({"log": lg.index, "monitor": "not applicable", "what": why, "codes": [code],
                            "spans": [{"from_s": round(float(lg.eof.get("first_t", 0.0)), 6),
                                       "to_s": round(lg.end_t, 6), "why": why}],
                            "span_count": 1, "seconds": round(dur, 3), "fraction": 1.0})
        return out

    def data_quality(self, bitrate: int) -> list[dict[str, Any]]:
        out = []
        for lg in self.logs:
            eo = lg.eof
            loads = [100.0 * b["bits"] / bitrate for b in lg.bus] if lg.bus else []
            rx = eo.get("rx", {})
            dq = {
                "log": lg.index,
                "bad_line_count": int(eo.get("bad_lines", 0)) + lg.input_problem_count,
                "bad_lines": [{"line": b["line"], "why": b["why"], "text": b["text"]} for b in lg.bad]
                + [{"line": ln, "why": why, "text": text} for _, ln, why, text in lg.input_problems],
                "read_errors": [{"line": r["line"], "why": r["why"]} for r in lg.readerr],
                "truncated": bool(eo.get("truncated", False)) or bool(lg.readerr) or lg.input_truncated,
                "gaps": [{"from_s": a, "to_s": b, "seconds": round(b - a, 6)} for a, b in lg.gaps],
                "gap_count": int(eo.get("gaps", 0)),
                "time_stamps_back": int(eo.get("back", 0)),
                "time_stamps_back_first": [{"line": b["line"], "at_s": b["t"], "by_s": b["back_us"] * 1e-6}
                                           for b in lg.back[:20]],
                "rebased": [{"line": b["line"], "at_s": b["t"], "back_s": b["back_us"] * 1e-6} for b in lg.rebase],
                "time_stamp_outliers": int(eo.get("outliers", 0)),
                "time_stamp_outliers_first": [{"line": o["line"], "at_s": o["t"], "stamp_s": o["stamp_s"]}
                                              for o in lg.outliers],
                "rejected_frames": {name: {k: v for k, v in d.items() if k != "accepted"} for name, d in rx.items()},
                "accepted_frames": {name: d.get("accepted", 0) for name, d in rx.items()},
                "error_frames": int(eo.get("error_frames", 0)),
                "error_frames_first": [{"line": e["line"], "at_s": e["t"]} for e in lg.errframes],
                "fd_frames": int(eo.get("fd_frames", 0)), "fd_first_line": int(eo.get("fd_line", 0)),
                "remote_frames": int(eo.get("remote_frames", 0)),
                "extended_frames": int(eo.get("ext_frames", 0)),
                "other_channels": {k: {"frames": v[0], "first_line": v[1]}
                                   for k, v in eo.get("other_channels", {}).items()},
                "unknown_ids": eo.get("unknown_ids", {}),
                "recorded_commands_bad_crc": int(eo.get("cmd_bad_crc", 0)),
                "recorded_ecu_dtc_frames_failing_e2e": int(eo.get("rec_e2e_bad", 0)),
                "simstep_rejected": int(eo.get("simstep_bad", 0)),
                "bus_load_pct": {"bitrate": bitrate, "mean": round(sum(loads) / len(loads), 2) if loads else 0.0,
                                 "max": round(max(loads), 2) if loads else 0.0,
                                 "note": "nominal frame bits without stuffing, per second of log time"},
                "missing_frames": self._missing(lg),
                "rx_errors_per_second": [{k: v for k, v in e.items() if k not in ("ev", "file")}
                                         for e in lg.rxq[:200]],
            }
            out.append(dq)
        return out

    def _missing(self, lg: LogState) -> list[dict[str, Any]]:
        """Spans in which an input frame of the supervisor was not received (timeout or never)."""
        out: list[dict[str, Any]] = []
        state: dict[str, tuple[bool, float, bool]] = {}
        for e in lg.frames:
            state_prev = state.get(e["name"])
            if state_prev is not None and not state_prev[0]:
                out.append({"frame": e["name"], "from_s": state_prev[1], "to_s": e["t"],
                            "never_received": not state_prev[2]})
            state[e["name"]] = (e["ok"], e["t"], e["received"])
        for name, (ok, t, rec) in state.items():
            if not ok:
                out.append({"frame": name, "from_s": t, "to_s": lg.end_t, "never_received": not rec})
        return out

    def exit_status(self) -> int:
        return 1 if self.findings() else 0

    def to_json(self, bitrate: int, tool: str) -> dict[str, Any]:
        findings = self.findings()
        return {
            "schema": SCHEMA,
            "tool": tool,
            "firmware": {"id": self.hdr.get("fw", ""), "sw_version": self.hdr.get("sw_version", ""),
                         "calibration": "canfdi_app_default_cal",
                         "calibration_id": self.hdr.get("calibration_id", "")},
            "dbc": self.dbc,
            "map": self.map_info,
            "logs": [self._log_json(lg) for lg in self.logs],
            "dtcs": findings,
            "recorded_ecu_only": self.recorded_only(),
            "not_judged": self.not_judged(),
            "data_quality": self.data_quality(bitrate),
            "settle_s": self.hdr.get("settle_s"),
            "exit_status": 1 if findings else 0,
        }

    def _log_json(self, lg: LogState) -> dict[str, Any]:
        a = lg.agree
        return {
            "index": lg.index, "path": lg.path, "format": lg.fmt, "sha256": lg.sha256,
            "lines": lg.eof.get("lines"), "frames": lg.eof.get("frames"), "steps": lg.eof.get("steps"),
            "first_s": lg.eof.get("first_t"), "last_s": lg.eof.get("last_t"), "clock": lg.clock,
            "grid_moves": lg.eof.get("grid_moves", 0),
            "channel": lg.channel, "start": lg.start, "start_decided_by": lg.start_decided_by,
            "settled_from_s": lg.settle_until if lg.start == "mid-drive" else lg.eof.get("first_t"),
            "recorded_ecu": {
                "frames": a.get("recorded_ecu_frames"), "identical": a.get("matched"),
                "differing": a.get("mismatched"), "recorded_only": a.get("recorded_only"),
                "replay_only": a.get("replay_only"),
                "first_difference": ({k: v for k, v in lg.mismatch.items() if k not in ("ev", "file")}
                                     if lg.mismatch else None)},
        }


def dumps(doc: dict[str, Any]) -> str:
    return json.dumps(doc, indent=1, sort_keys=False) + "\n"


def all_codes_mapped() -> list[str]:
    """Codes of dbc/dtcs.csv without a monitor (must be none)."""
    return [d.code for d in load_dtcs() if d.code not in CODE_MONITORS]
