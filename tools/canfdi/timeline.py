"""Turn a stream of CAN frames into the diagnostic timeline of a run.

Input: ``can.Message`` objects from a live bus or a recorded log. Output:
events a technician reads (trouble-code status changes with descriptions,
degradation and limp-home changes, bridge switchovers, isolated faults with
confidence, injected faults, residual summaries), plus the per-code first
times the expectations are judged on (expect.py), all on SIMULATED time.

Simulated time of a frame, in this order (all in integer microseconds so that
comparisons with scenario times are exact, as in canfdi-sil):

1. lockstep (SimStep 0x611 seen): SimStep(k) gets k ms; every plant,
   vehicle or tester frame after it feeds the next step and gets (k + 1) ms
   (canfdi-ecu's own rule for what it receives). The ECU's frames of step k
   get k ms: its step starts with DcmActuator/ThrActuator, which the sim
   waits for before SimStep(k + 1), so they always follow SimStep(k); its
   further frames of that step (EcuDtc, EcuStatus, ...) may reach the bus
   after the sim's next frames (seen in User-Mode Linux) and take the step
   of the latest actuator frame, not of the latest SimStep. A lockstep
   recording thus gives SIL's times exactly;
2. realtime (SimPlantStatus 0x610 seen): last PstSimTime + (timestamp -
   timestamp of that status frame);
3. otherwise timestamp - first timestamp, or the timestamp itself when the
   first one is below 1e6 s (already relative, e.g. a canfdi-sil log whose
   timestamps are simulated time).

Only the frames the timeline needs are decoded (with cantools and the DBC);
the 1 ms sensor frames are counted, not decoded. A 20 s SIL log (~89 k
frames) takes ~0.1 s here; reading the file costs more than the timeline.
A frame that does not decode is counted in ``stats.undecodable`` and never
stops the timeline.

The ECU's E2E protected frames (dbc/canfdi.dbc, CanfdiE2E: DcmActuator,
ThrActuator, EcuStatus, EcuDiagnosis, EcuDtc) are judged before anything is
read from them, with the ECU's own check (canfdi.e2e, one receiver per
identifier, one lost frame tolerated): a wrong length or CRC, a repeated
counter or a counter jump makes the frame "forged or corrupted". It is
counted (``stats.e2e_bad``), listed as an event of kind ``forged`` with its
identifier and the reason (the first FORGED_LISTED per identifier), and
never decoded: no diagnosis, status change, power-stage switch or trouble
code comes from it. A second node sending the ECU's identifiers shows as
counter errors (after each jump the check follows the frame just seen, so
the next frame of the other sequence jumps again); so does, once per
identifier, a restart of the ECU within one recording (its counters start
at 0 again).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Callable, Iterable

import can
import cantools
from cantools.database.can import Database

from . import DBC_PATH
from .catalogue import decode_dtc, dtc_by_code, load_faults
from .e2e import E2EReceiver, Status, judge, protected_ids

DEG_NAMES = ("normal", "degraded", "fail_safe", "fail_silent")
BRIDGE_NAMES = ("none", "A", "B")
US_PER_STEP = 1000
PST_WRAP_US = 16_777_216_000  # PstSimTime is 24 bit x 1 ms

ID_DCM_ACT, ID_THR_ACT = 0x020, 0x021
ID_RES_DCM, ID_RES_THR = 0x200, 0x201
ID_STATUS, ID_DIAG, ID_SELFDIAG, ID_DTC = 0x300, 0x301, 0x302, 0x310
ID_INJECT, ID_CLEAR, ID_PLANT, ID_STEP = 0x600, 0x601, 0x610, 0x611
ID_SP_DCM, ID_SP_THR = 0x100, 0x101
DECODED = frozenset({ID_DCM_ACT, ID_THR_ACT, ID_RES_DCM, ID_RES_THR, ID_STATUS, ID_DIAG, ID_SELFDIAG, ID_DTC,
                     ID_INJECT, ID_CLEAR, ID_PLANT, ID_STEP, ID_SP_DCM, ID_SP_THR})

#: Largest counter step of an ECU frame still taken (one lost frame), as
#: the ECU's own receivers (canfdi_rx_default_cfg).
E2E_MAX_DELTA = 2
#: Forged or corrupted frames listed as events per identifier; the rest
#: are counted.
FORGED_LISTED = 10
E2E_KIND = {Status.WRONG_CRC: "CRC", Status.WRONG_LENGTH: "length", Status.REPEATED: "counter",
            Status.WRONG_SEQUENCE: "counter"}

RESIDUALS = (("ResDcmR1", "dcm r1"), ("ResDcmR2", "dcm r2"), ("ResDcmR3", "dcm r3"), ("ResDcmR4", "dcm r4"),
             ("ResThrCorr", "thr corr"), ("ResThrTps1", "thr tps1"), ("ResThrTps2", "thr tps2"),
             ("ResThrCurrent", "thr current"))


def load_db() -> Database:
    """The project's DBC (cached per process: parsing costs ~50 ms)."""
    global _DB
    if _DB is None:
        db = cantools.database.load_file(str(DBC_PATH))
        assert isinstance(db, Database)
        _DB = db
    return _DB


_DB: Database | None = None


def fault_name(fault_id: int) -> str:
    faults = load_faults()
    return faults[fault_id].name if 0 <= fault_id < len(faults) else f"fault#{fault_id}"


def fmt_t(t_us: int) -> str:
    return f"{t_us * 1e-6:8.3f}"


@dataclass(frozen=True)
class Event:
    """One line of the timeline."""
    t_us: int
    kind: str          # dtc | degradation | bridge | limp_home | diagnosis | inject | plant | residuals | forged
    text: str
    code: str = ""     # trouble code for kind == 'dtc'

    def line(self) -> str:
        return f"  {fmt_t(self.t_us)}  {self.text}"


@dataclass
class DtcRecord:
    """What was seen of one trouble code; times in µs, -1 = never (like canfdi-sil)."""
    code: str
    status: int = 0
    first_failed_us: int = -1      # first testFailed
    first_pending_us: int = -1
    first_confirmed_us: int = -1
    # (t_us, status, occurrence) of each frame whose status or occurrence
    # differs from the previous frame's (the first frame too)
    history: list[tuple[int, int, int]] = field(default_factory=list)

    def state_at(self, t_us: int) -> tuple[int, int, int] | None:
        """(since_us, status, occurrence) of the last frame at or before t_us; None: not reported yet."""
        last = None
        for h in self.history:
            if h[0] > t_us:
                break
            last = h
        return last

    @property
    def first_reported_us(self) -> int:
        """testFailed, else confirmed: what `expect <t> dtc CODE` is judged on."""
        return self.first_failed_us if self.first_failed_us >= 0 else self.first_confirmed_us


@dataclass
class FrameStats:
    """Monotone counters of what the timeline met."""
    frames: int = 0
    decoded: int = 0
    undecodable: int = 0           # wrong length / bad content for a known ID
    unknown_id: int = 0            # not in the DBC
    error_frames: int = 0
    first_undecodable: str = ""
    steps: int = 0                 # SimStep frames
    first_step: int = -1
    last_step: int = -1
    step_gaps: int = 0             # SimStep indices skipped (lost frames)
    step_repeats: int = 0          # stale or duplicated indices
    first_gap: str = ""
    counts: dict[int, int] = field(default_factory=dict)   # frames per CAN ID
    e2e_checked: int = 0           # the ECU's E2E protected frames judged
    e2e_bad: int = 0               # ... that failed: forged or corrupted, not decoded
    e2e_bad_by_id: dict[int, dict[str, int]] = field(default_factory=dict)  # id -> CRC/counter/length -> n
    first_e2e_bad: str = ""


class Timeline:
    """Feed frames in bus order; read events, dtcs, degradation history, stats."""

    def __init__(self, db: Database | None = None, residual_window_s: float | None = None,
                 on_event: Callable[[Event], None] | None = None) -> None:
        self.db = db if db is not None else load_db()
        self._msg = {m.frame_id: m for m in self.db.messages}
        self._ecu_ids = frozenset(m.frame_id for m in self.db.messages if "ECU" in m.senders)
        self._e2e_names = protected_ids(self.db, "ECU")
        self._e2e = {fid: E2EReceiver(fid, E2E_MAX_DELTA) for fid in self._e2e_names}
        #: the last frame fed failed its E2E check and was not decoded
        self.last_rejected = False
        self._ecu_k = -1    # lockstep: the step of the ECU's latest actuator frame
        self.descriptions = {d.code: d.description for d in dtc_by_code().values()}
        self.on_event = on_event
        self.events: list[Event] = []
        self.dtcs: dict[str, DtcRecord] = {}          # in order of first report
        self.stats = FrameStats()
        self.deg_history: list[tuple[int, int, int]] = []   # (t_us, dcm, thr) at each change
        self.injections_us: list[int] = []            # SimFaultInject on the bus (+ delay)
        self.selfdiag: dict[str, Any] = {}
        self.now_us = 0
        self.start_us = -1
        self.last_us = -1
        self.lockstep = False
        self._t0: float | None = None
        self._pst: tuple[int, float] | None = None    # (PstSimTime µs, timestamp)
        self._pst_wraps = 0
        # Initial states as canfdi-sil assumes them (normal, bridge A, motor
        # energised, nothing isolated or injected), so only changes print.
        self._last: dict[str, Any] = {"dcm_deg": 0, "thr_deg": 0, "bridge": 1, "thr_en": 1, "limp": 0,
                                      "plant_fault": (0, 0, 0), "plant_limp": 0, "diag": (0, 0, 0)}
        self._res_window_us = int(round(residual_window_s * 1e6)) if residual_window_s else 0
        self._res_end_us = -1
        self._res_max: dict[str, float] = {}

    # -- time ------------------------------------------------------------
    def _sim_time(self, msg: can.Message) -> int:
        ts = float(msg.timestamp)
        if self._t0 is None:
            self._t0 = 0.0 if ts < 1e6 else ts
        if self.lockstep:
            k = self.stats.last_step
            fid = msg.arbitration_id
            if fid in (ID_DCM_ACT, ID_THR_ACT):
                self._ecu_k = k
            elif fid in self._ecu_ids:
                k = self._ecu_k if self._ecu_k >= 0 else k
            elif fid != ID_STEP:
                k += 1
            return k * US_PER_STEP
        if self._pst is not None:
            return self._pst[0] + round((ts - self._pst[1]) * 1e6)
        return round((ts - self._t0) * 1e6)

    def _step(self, k: int) -> None:
        s = self.stats
        if s.steps == 0:
            s.first_step = k
        elif k <= s.last_step:
            s.step_repeats += 1
            if not s.first_gap:
                s.first_gap = f"SimStep {k} after {s.last_step}"
            s.steps += 1
            return
        elif k > s.last_step + 1:
            s.step_gaps += k - s.last_step - 1
            if not s.first_gap:
                s.first_gap = f"SimStep {s.last_step + 1}..{k - 1} missing"
        s.steps += 1
        s.last_step = k
        self.lockstep = True

    # -- events ----------------------------------------------------------
    def _emit(self, t_us: int, kind: str, text: str, code: str = "") -> None:
        ev = Event(t_us, kind, text, code)
        self.events.append(ev)
        if self.on_event is not None:
            self.on_event(ev)

    def _bad(self, msg: can.Message, reason: str) -> None:
        self.stats.undecodable += 1
        if not self.stats.first_undecodable:
            self.stats.first_undecodable = f"0x{msg.arbitration_id:03X} [{msg.dlc}] {bytes(msg.data).hex()}: {reason}"

    def feed(self, msg: can.Message) -> None:
        """Account for one frame (any frame: unknown and broken ones are counted)."""
        st = self.stats
        st.frames += 1
        st.counts[msg.arbitration_id] = st.counts.get(msg.arbitration_id, 0) + 1
        self.last_rejected = False
        if msg.is_error_frame or msg.is_remote_frame:
            st.error_frames += msg.is_error_frame
            return
        fid = msg.arbitration_id
        m = self._msg.get(fid) if not msg.is_extended_id else None
        if m is None:
            st.unknown_id += 1
            return
        data = bytes(msg.data)
        rx = self._e2e.get(fid)
        if rx is not None:
            status, why = judge(rx, data)
            st.e2e_checked += 1
            if not status.usable:
                self._forged(fid, status, why, data, self._advance(msg))
                return
        if fid not in DECODED:
            self._advance(msg)
            return
        if len(data) != m.length:
            self._bad(msg, f"length {len(data)}, DBC says {m.length}")
            self._advance(msg)
            return
        try:
            sig = m.decode(data, decode_choices=False, scaling=True)
        except Exception as e:  # noqa: BLE001 — cantools raises several types
            self._bad(msg, str(e))
            self._advance(msg)
            return
        st.decoded += 1
        if fid == ID_STEP:
            self._step(int(sig["SimStepIndex"]))
        elif fid == ID_PLANT and not self.lockstep:
            pst = round(float(sig["PstSimTime"]) * 1000) * 1000
            if self._pst is not None and pst + self._pst_wraps * PST_WRAP_US < self._pst[0] - PST_WRAP_US // 2:
                self._pst_wraps += 1
            self._pst = (pst + self._pst_wraps * PST_WRAP_US, float(msg.timestamp))
        t = self._advance(msg)
        self._handle(fid, sig, t)

    def _forged(self, fid: int, status: Status, why: str, data: bytes, t: int) -> None:
        """An ECU frame that failed its E2E check: counted, listed, not decoded."""
        s = self.stats
        self.last_rejected = True
        per = s.e2e_bad_by_id.setdefault(fid, {})
        kind = E2E_KIND.get(status, "other")
        per[kind] = per.get(kind, 0) + 1
        s.e2e_bad += 1
        name = self._e2e_names[fid]
        if not s.first_e2e_bad:
            s.first_e2e_bad = f"0x{fid:03X} {name} [{len(data)}] {data.hex()} at {t * 1e-6:.3f} s: {why}"
        n = sum(per.values())
        if n <= FORGED_LISTED:
            self._emit(t, "forged", f"0x{fid:03X} {name} forged or corrupted: {why} (not decoded)")
            if n == FORGED_LISTED:
                self._emit(t, "forged", f"0x{fid:03X} {name}: further forged or corrupted frames "
                                        "are counted, not listed")

    def e2e_summary(self) -> str:
        """One line on the ECU frames that failed their E2E check ("" if none)."""
        s = self.stats
        if not s.e2e_bad:
            return ""
        parts = []
        for fid in sorted(s.e2e_bad_by_id):
            per = s.e2e_bad_by_id[fid]
            kinds = ", ".join(f"{k} {n}" for k, n in sorted(per.items()))
            parts.append(f"0x{fid:03X} {self._e2e_names[fid]} {sum(per.values())} ({kinds})")
        return (f"{s.e2e_bad} ECU frame(s) forged or corrupted (E2E check failed, not decoded): "
                + "; ".join(parts) + f"; first: {s.first_e2e_bad}")

    def set_origin(self, status: can.Message) -> None:
        """Realtime log known in advance: anchor time on its first SimPlantStatus.

        Live, frames before the first status frame can only be timed from the
        first frame seen; from a log, frames sent before the sim started (an
        ECU started first) get negative simulated times, which is the truth.
        """
        sig = self._msg[ID_PLANT].decode(bytes(status.data), decode_choices=False)
        self._pst = (round(float(sig["PstSimTime"]) * 1000) * 1000, float(status.timestamp))
        self._t0 = float(status.timestamp)

    def _advance(self, msg: can.Message) -> int:
        t = self._sim_time(msg)
        if self.start_us < 0:
            self.start_us = t
        self.now_us = t
        self.last_us = max(self.last_us, t)
        return t

    def _handle(self, fid: int, s: dict[str, Any], t: int) -> None:
        last = self._last
        if fid == ID_DTC:
            self._dtc(s, t)
        elif fid == ID_STATUS:
            dcm, thr = int(s["StsDegStateDcm"]), int(s["StsDegStateThr"])
            for sub, v in (("dcm", dcm), ("thr", thr)):
                if v != last[f"{sub}_deg"]:   # from normal, as canfdi-sil prints
                    self._emit(t, "degradation", f"degradation {sub}: {_deg(last[f'{sub}_deg'])} -> {_deg(v)}")
                    last[f"{sub}_deg"] = v
            if not self.deg_history or self.deg_history[-1][1:] != (dcm, thr):
                self.deg_history.append((t, dcm, thr))
            limp = int(s["StsThrLimpHome"])
            if limp != last["limp"]:
                self._emit(t, "limp_home", "ecu: throttle limp-home " + ("ON" if limp else "off"))
                last["limp"] = limp
        elif fid == ID_DCM_ACT:
            bridge = int(s["DcmBridgeSel"])
            if bridge != last["bridge"]:   # from A, as canfdi-sil prints
                new = _br(bridge) if bridge else "none (drive off)"
                self._emit(t, "bridge", f"dcm: power stage {_br(last['bridge'])} -> {new}")
                last["bridge"] = bridge
        elif fid == ID_THR_ACT:
            en = int(s["ThrEnable"])
            if en != last["thr_en"]:
                self._emit(t, "limp_home", "thr: motor " + ("energised" if en else "de-energised (spring -> limp-home)"))
                last["thr_en"] = en
        elif fid == ID_DIAG:
            ids = (int(s["DiagDcmFaultId"]), int(s["DiagThrFaultId"]), int(s["DiagComFaultId"]))
            conf = (int(s["DiagDcmConfidence"]), int(s["DiagThrConfidence"]), int(s["DiagComConfidence"]))
            for i, sub in enumerate(("dcm", "thr", "com")):
                if ids[i] != last["diag"][i]:
                    what = "nothing isolated" if ids[i] == 0 else f"{fault_name(ids[i])} ({conf[i]} % confidence)"
                    self._emit(t, "diagnosis", f"diagnosis {sub}: {what}")
            last["diag"] = ids
        elif fid == ID_PLANT:
            f = (int(s["PstActiveFaultId"]), int(s["PstFaultMode"]), int(s["PstFaultActive"]))
            if f != last["plant_fault"]:
                if f[0] == 0:
                    self._emit(t, "plant", "plant: no fault injected")
                else:
                    state = "acting" if f[2] else "injected, not acting (delay or off phase)"
                    self._emit(t, "plant", f"plant: {fault_name(f[0])} {_mode(f[1])} {state}")
                last["plant_fault"] = f
            limp = int(s["PstThrLimpHome"])
            if limp != last["plant_limp"]:
                self._emit(t, "limp_home", "plant: valve " + ("at limp-home (spring)" if limp else "driven"))
                last["plant_limp"] = limp
        elif fid == ID_INJECT:
            delay = float(s["InjStartDelay"])
            self.injections_us.append(t + round(delay * 1e6))
            self._emit(t, "inject", f"tester: inject {fault_name(int(s['InjFaultId']))} {_mode(int(s['InjMode']))} "
                                    f"magnitude {float(s['InjMagnitude']):g}" + (f" after {delay:g} s" if delay else ""))
        elif fid == ID_CLEAR:
            c = int(s["ClrFaultId"])
            self._emit(t, "inject", "tester: clear " + ("all faults" if c == 0 else fault_name(c)))
        elif fid in (ID_RES_DCM, ID_RES_THR) and self._res_window_us:
            self._residuals(s, t)
        elif fid == ID_SELFDIAG:
            self.selfdiag = dict(s)

    def _dtc(self, s: dict[str, Any], t: int) -> None:
        raw = int(s["DtcCode"])
        if raw == 0:
            return
        code = decode_dtc(raw)
        rec = self.dtcs.get(code)
        if rec is None:
            rec = self.dtcs[code] = DtcRecord(code)
        tf, pd, cf = int(s["DtcStsTestFailed"]), int(s["DtcStsPending"]), int(s["DtcStsConfirmed"])
        st = tf | int(s["DtcStsTestFailedThisOpCycle"]) << 1 | pd << 2 | cf << 3 \
            | int(s["DtcStsNotCompletedSinceClear"]) << 4 | int(s["DtcStsFailedSinceClear"]) << 5 \
            | int(s["DtcStsNotCompletedThisOpCycle"]) << 6 | int(s["DtcStsWarningIndicator"]) << 7
        if tf and rec.first_failed_us < 0:
            rec.first_failed_us = t
        if pd and rec.first_pending_us < 0:
            rec.first_pending_us = t
        if cf and rec.first_confirmed_us < 0:
            rec.first_confirmed_us = t
        occ = int(s["DtcOccurrence"])
        if not rec.history or rec.history[-1][1:] != (st, occ):
            rec.history.append((t, st, occ))
        if (st ^ rec.status) & 0x0D:
            word = ("confirmed" if tf else "stored") if cf else ("testFailed" if tf else "passed")
            if pd and not cf:
                word += "+pending"
            self._emit(t, "dtc", f"{code:<5} {word:<12} {self.descriptions.get(code, '')}", code)
        rec.status = st

    def _residuals(self, s: dict[str, Any], t: int) -> None:
        if self._res_end_us < 0:
            self._res_end_us = (t // self._res_window_us + 1) * self._res_window_us
        if t >= self._res_end_us:
            self.flush_residuals()
            self._res_end_us = (t // self._res_window_us + 1) * self._res_window_us
        for name, _ in RESIDUALS:
            if name in s:
                self._res_max[name] = max(self._res_max.get(name, 0.0), abs(float(s[name])))

    def flush_residuals(self) -> None:
        """Emit the summary of the window in progress (at its end time)."""
        if not self._res_max:
            return
        parts = []
        for name, label in RESIDUALS:
            if name in self._res_max:
                v = self._res_max[name]
                parts.append(f"{label} {v:.2f}{'*' if v >= 1.0 else ''}")
        t0 = self._res_end_us - self._res_window_us
        self._emit(self._res_end_us, "residuals",
                   f"max|r| {t0 * 1e-6:.1f}-{self._res_end_us * 1e-6:.1f} s (1 = threshold, * over): " + ", ".join(parts))
        self._res_max = {}

    # -- queries ---------------------------------------------------------
    @property
    def end_us(self) -> int:
        """Simulated time the run reached: one step after the last frame's time."""
        return self.last_us + US_PER_STEP if self.last_us >= 0 else 0

    def degradation_before(self, subsystem: str, t_us: int) -> str | None:
        """State in the last EcuStatus frame strictly before t_us (canfdi-sil's rule); None: none yet."""
        idx = 1 if subsystem == "dcm" else 2
        state = None
        for rec in self.deg_history:
            if rec[0] >= t_us:
                break
            state = _deg(rec[idx])
        return state

    def feed_all(self, msgs: Iterable[can.Message]) -> "Timeline":
        for msg in msgs:
            self.feed(msg)
        self.flush_residuals()
        return self


def _deg(v: int) -> str:
    return DEG_NAMES[v] if 0 <= v < len(DEG_NAMES) else "?"


def _br(v: int) -> str:
    return BRIDGE_NAMES[v] if 0 <= v < len(BRIDGE_NAMES) else "?"


def _mode(v: int) -> str:
    return ("abrupt", "incipient", "intermittent")[v] if 0 <= v < 3 else "?"
