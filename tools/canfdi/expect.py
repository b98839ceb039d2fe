"""Judge a scenario's ``expect`` lines against a timeline, exactly as canfdi-sil does.

The rules and the wording of the verdict lines are those of
tests/sil/canfdi_sil.c (see tests/sil/README.md), so that a HIL run and a SIL
run of the same scenario can be compared line by line:

- ``expect <t> dtc CODE [pending|confirmed]``: the first EcuDtc frame with
  testFailed (else confirmedDTC; or the named bit) is at or before t;
- ``expect <t> no_dtc``: no code with testFailed/confirmedDTC up to t;
- ``expect <t> degradation <dcm|thr> <state>``: the state in the last
  EcuStatus frame before t (canfdi-sil judges it after the step that reaches
  t, so that step's own frames do not count);
- ``expect <t> dtc_status CODE BITS``: the named status bits (TF, TFTOC,
  PDTC, CDTC, TNCSLC, TFSLC, TNCTOC, WIR or a byte 0xNN) in the last EcuDtc
  frame of the code at or before t; a code never reported has the cleared
  state 0x50 (the ECU sends an on-change frame on every status change);
- ``expect <t> occurrence CODE N``: DtcOccurrence of that frame (0 if never
  reported);
- ``expect <t> freeze ...`` is SIL-only (the rig reads the ECU's memory):
  judged here as a failure; canfdi-scenario refuses such a scenario first;
- implicitly, every code that appears and that no ``expect ... dtc`` line
  names fails ("the expected trouble code and no other").

    verdicts = evaluate(scn, timeline)
    print("\\n".join(v.line for v in verdicts))
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from .scenario_file import Scenario, bits_text
from .timeline import Timeline


CLEARED = 0x50   # TNCSLC | TNCTOC: the status after init and after a clear


@dataclass(frozen=True)
class Verdict:
    ok: bool
    text: str                  # canfdi-sil's message after 'PASS  file:line: '
    line_no: int               # scenario line, 0 for an implicit check
    where: str                 # 'file:line' or 'file'
    t_us: int = -1             # when the judged thing happened (-1 never/not applicable)
    code: str = ""

    @property
    def line(self) -> str:
        return f"{'PASS' if self.ok else 'FAIL'}  {self.where}: {self.text}"

    def as_dict(self) -> dict[str, Any]:
        return {"ok": self.ok, "line": self.line_no, "message": self.text,
                "t_s": self.t_us * 1e-6 if self.t_us >= 0 else None, "code": self.code or None}


def _fault_before(scn: Scenario, t_seen_us: int) -> int:
    """Start of the latest injection at or before t_seen, -1 if none (canfdi-sil's rule)."""
    starts = [f.t_start_us for f in scn.faults]
    if not starts or min(starts) > t_seen_us:
        return -1
    return max(s for s in starts if s <= t_seen_us)


def evaluate(scn: Scenario, tl: Timeline, label: str | None = None) -> list[Verdict]:
    """One Verdict per expect line (file order), then one per unexpected code."""
    name = label if label is not None else str(scn.path)
    out: list[Verdict] = []
    for e in scn.expects:
        where = f"{name}:{e.line}"
        te = e.t_us
        if e.kind == "dtc":
            rec = tl.dtcs.get(e.arg1)
            what = e.arg2 or "testFailed or confirmed"
            t_seen = -1
            if rec is not None:
                t_seen = {"confirmed": rec.first_confirmed_us, "pending": rec.first_pending_us}.get(
                    e.arg2, rec.first_reported_us)
            ok = 0 <= t_seen <= te
            if t_seen < 0:
                msg = f"dtc {e.arg1} {what} by {e.t_s:.3f} s: never seen"
            else:
                t_f = _fault_before(scn, t_seen)
                msg = f"dtc {e.arg1} {what} by {e.t_s:.3f} s: at {t_seen * 1e-6:.3f} s"
                if t_f >= 0:
                    msg += f" ({(t_seen - t_f) * 1e-3:.0f} ms after the fault at {t_f * 1e-6:.3f} s)"
            out.append(Verdict(ok, msg, e.line, where, t_seen, e.arg1))
        elif e.kind == "no_dtc":
            first, code = -1, ""
            for rec in tl.dtcs.values():
                tq = rec.first_reported_us
                if 0 <= tq <= te and (first < 0 or tq < first):
                    first, code = tq, rec.code
            if first < 0:
                out.append(Verdict(True, f"no trouble code up to {e.t_s:.3f} s", e.line, where))
            else:
                out.append(Verdict(False, f"no trouble code up to {e.t_s:.3f} s: {code} at {first * 1e-6:.3f} s",
                                   e.line, where, first, code))
        elif e.kind == "degradation":
            if tl.end_us < te:
                out.append(Verdict(False, "degradation: not evaluated (beyond the run?)", e.line, where))
                continue
            state = tl.degradation_before(e.arg1, te)
            msg = (f"degradation {e.arg1} at {e.t_s:.3f} s: {state if state is not None else 'no EcuStatus yet'}"
                   f" (expected {e.arg2})")
            out.append(Verdict(state == e.arg2, msg, e.line, where))
        elif e.kind in ("dtc_status", "occurrence"):
            rec = tl.dtcs.get(e.arg1)
            got = rec.state_at(te) if rec is not None else None
            if got is None:
                st, occ, src = CLEARED, 0, "never reported: cleared state assumed"
            else:
                st, occ, src = got[1], got[2], f"reported since {got[0] * 1e-6:.3f} s"
            if tl.end_us < te:
                out.append(Verdict(False, f"{e.kind}: not evaluated (beyond the run?)", e.line, where))
            elif e.kind == "dtc_status":
                msg = (f"dtc_status {e.arg1} at {e.t_s:.3f} s: {bits_text(e.mask, st)} (expected "
                       f"{bits_text(e.mask, e.value)}) [0x{st:02X} {src}]")
                out.append(Verdict(st & e.mask == e.value, msg, e.line, where, code=e.arg1))
            else:
                msg = f"occurrence {e.arg1} at {e.t_s:.3f} s: {occ} (expected {e.lo:.0f}) [{src}]"
                out.append(Verdict(occ == round(e.lo), msg, e.line, where, code=e.arg1))
        elif e.kind == "freeze":
            out.append(Verdict(False, f"freeze {e.arg1} {e.arg2} at {e.t_s:.3f} s: not observable on the bus "
                               "(SIL only: canfdi-sil reads the ECU's memory)", e.line, where, code=e.arg1))
    named = {e.arg1 for e in scn.expects if e.kind == "dtc"}
    desc = tl.descriptions
    for rec in tl.dtcs.values():
        t = rec.first_reported_us
        if t < 0 or rec.code in named:
            continue
        out.append(Verdict(False, f"unexpected trouble code {rec.code} at {t * 1e-6:.3f} s ({desc.get(rec.code, '')})",
                           0, name, t, rec.code))
    return out


def summary_line(verdicts: list[Verdict], label: str) -> str:
    failed = sum(not v.ok for v in verdicts)
    return f"{'PASSED' if failed == 0 else 'FAILED'}  {label} ({failed} check(s) failed)"
