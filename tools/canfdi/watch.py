"""canfdi-watch: print the diagnostic timeline of the bus, live or from a recorded log.

Trouble codes with their descriptions and status (testFailed, pending,
confirmed), degradation changes per subsystem, bridge switchovers and
limp-home, isolated faults with confidence, injected faults, and with
--residuals a max-|r| summary every N seconds. Times are SIMULATED seconds
(see canfdi.timeline), so a lockstep run reads the same however slow the bus.

--expect/--forbid turn it into a check a test script can call.

Every E2E protected frame of the ECU (DcmActuator, ThrActuator, EcuStatus,
EcuDiagnosis, EcuDtc) is checked like the ECU checks its inputs (CRC over
the data ID and bytes 1..7, rolling counter): a frame that fails is printed
as "forged or corrupted" with its identifier and the reason and is never
decoded into a diagnosis, a status change or a trouble code.
"""
from __future__ import annotations

import argparse
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Iterator

import can

from .busargs import BusOpenError, add_bus_args, open_bus
from .hil import raise_rcvbuf
from .catalogue import dtc_by_code
from .logio import ReadStats, read_log
from .timeline import Event, Timeline

EPILOG = """\
examples:
  canfdi-watch                                   # live on the configured bus (vcan0)
  canfdi-watch --residuals 1 --duration 20
  canfdi-watch --log build/hil/tps1_open.log     # any python-can format: .log .asc .blf .trc ...
  canfdi-watch --expect P0122 --within 5         # exit 0 as soon as P0122 is reported
  canfdi-watch --forbid U1A00 --forbid U1A01 --duration 10
  canfdi-watch --log run.log --expect P0122 --forbid P0222 --within 6

"appears" means an EcuDtc frame with testFailed or confirmedDTC set. SECONDS
count simulated time from the first frame watched. With only --expect the
watch ends as soon as every expected code appeared; with --forbid it lasts
the whole --within (else --duration, else the log or until interrupted).

E2E: a frame on an ECU identifier with a wrong CRC or length, a repeated
counter or a counter jump (a second node sending the ECU's identifiers
shows as counter jumps) is listed as
  0x301 EcuDiagnosis forged or corrupted: wrong CRC 0x12 (0x9C expected) (not decoded)
and makes the watch fail. A restart of the ECU within the watch (counters
from 0 again) shows as one counter jump per identifier.

exit status:
  0  every --expect code appeared in time and no --forbid code appeared
     (or, without checks, the watch ended normally)
  1  an expected code did not appear in time, a forbidden one appeared,
     an ECU frame was forged or corrupted (failed its E2E check), the bus
     could not be opened, or the log held no readable frame
  2  bad usage: unknown trouble code, unreadable log file
"""


@dataclass
class Checks:
    """The --expect/--forbid judgement, fed as the timeline grows."""
    expect: list[str]
    forbid: list[str]
    within_us: int | None
    duration_us: int | None
    results: list[str] = field(default_factory=list)
    failed: bool = False

    def window_us(self) -> int | None:
        """How long the watch must last at most (relative sim time)."""
        if self.forbid and self.within_us is not None:
            return self.within_us if self.duration_us is None else min(self.within_us, self.duration_us)
        cands = [x for x in (self.within_us, self.duration_us) if x is not None]
        return min(cands) if cands else None

    def step(self, tl: Timeline) -> bool:
        """True when the verdict is known and the watch can stop."""
        start = tl.start_us
        for code in self.forbid:
            rec = tl.dtcs.get(code)
            if rec is not None and rec.first_reported_us >= 0:
                self.results.append(f"FAIL  forbidden {code} appeared at {rec.first_reported_us * 1e-6:.3f} s")
                self.failed = True
                return True
        seen = [tl.dtcs[c] for c in self.expect if c in tl.dtcs and tl.dtcs[c].first_reported_us >= 0]
        if self.within_us is not None:
            for rec in seen:
                if rec.first_reported_us - start > self.within_us:
                    self._missing(tl, [rec.code])
                    return True
            if tl.now_us - start > self.within_us and len(seen) < len(self.expect):
                self._missing(tl, [c for c in self.expect if c not in {r.code for r in seen}])
                return True
        if self.expect and len(seen) == len(self.expect) and not self.forbid:
            self._passed(tl)
            return True
        window = self.window_us()
        if window is not None and tl.now_us - start > window:
            self.finish(tl)
            return True
        return False

    def _missing(self, tl: Timeline, codes: list[str]) -> None:
        for c in codes:
            rec = tl.dtcs.get(c)
            late = f" (it came at {rec.first_reported_us * 1e-6:.3f} s)" if rec and rec.first_reported_us >= 0 else ""
            self.results.append(f"FAIL  {c} did not appear within {self.within_us * 1e-6:g} s "
                                f"of the start at {tl.start_us * 1e-6:.3f} s{late}")
        self.failed = True

    def _passed(self, tl: Timeline) -> None:
        for c in self.expect:
            rec = tl.dtcs[c]
            self.results.append(f"PASS  {c} appeared at {rec.first_reported_us * 1e-6:.3f} s "
                                f"({(rec.first_reported_us - tl.start_us) * 1e-3:.0f} ms after the start)")

    def finish(self, tl: Timeline) -> None:
        """End of input before a verdict: whatever is missing failed."""
        if self.failed or (self.results and not self.forbid):
            return
        missing = [c for c in self.expect if c not in tl.dtcs or tl.dtcs[c].first_reported_us < 0]
        if missing and self.within_us is not None:
            self._missing(tl, missing)
            return
        if missing:
            for c in missing:
                self.results.append(f"FAIL  {c} never appeared (watched {tl.start_us * 1e-6:.3f}-"
                                    f"{tl.now_us * 1e-6:.3f} s)")
            self.failed = True
            return
        if self.expect:
            self._passed(tl)
        if self.forbid:
            self.results.append(f"PASS  none of {', '.join(self.forbid)} appeared "
                                f"({tl.start_us * 1e-6:.3f}-{tl.now_us * 1e-6:.3f} s)")


def bus_frames(bus: can.BusABC, wall_timeout_s: float | None) -> Iterator[can.Message]:
    """Frames from a live bus until the wall-clock timeout (None: until interrupted)."""
    t_end = None if wall_timeout_s is None else time.monotonic() + wall_timeout_s
    while t_end is None or time.monotonic() < t_end:
        msg = bus.recv(timeout=0.2)
        if msg is not None:
            yield msg


def _codes(p: argparse.ArgumentParser, codes: list[str], flag: str) -> list[str]:
    known = dtc_by_code()
    for c in codes:
        if c not in known:
            p.error(f"{flag} {c}: unknown trouble code (see dbc/dtcs.csv)")
    return codes


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="canfdi-watch", description=__doc__.split("\n\n")[0],
                                epilog=EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    add_bus_args(p)
    p.add_argument("--log", type=Path, metavar="FILE", help="replay a recorded log instead of the live bus")
    p.add_argument("--expect", action="append", default=[], metavar="CODE", help="code that must appear (repeatable)")
    p.add_argument("--forbid", action="append", default=[], metavar="CODE", help="code that must not appear (repeatable)")
    p.add_argument("--within", type=float, metavar="SECONDS", help="deadline for --expect, simulated seconds")
    p.add_argument("--duration", type=float, metavar="S", help="stop after S simulated seconds")
    p.add_argument("--residuals", type=float, metavar="N", help="print a residual summary every N simulated seconds")
    p.add_argument("--timeout", type=float, metavar="S",
                   help="live bus: give up after S wall-clock seconds (default 10 x the window + 10 s, "
                        "none without --within/--duration)")
    p.add_argument("-q", "--quiet", action="store_true", help="print only the verdict lines")
    return p


def main(argv: list[str] | None = None) -> int:
    p = build_parser()
    a = p.parse_args(argv)
    checks = Checks(_codes(p, a.expect, "--expect"), _codes(p, a.forbid, "--forbid"),
                    None if a.within is None else round(a.within * 1e6),
                    None if a.duration is None else round(a.duration * 1e6))
    if a.log is not None and not a.log.is_file():
        print(f"canfdi-watch: cannot read {a.log}: no such file", file=sys.stderr)
        return 2

    def show(ev: Event) -> None:
        if not a.quiet:
            print(ev.line(), flush=True)

    tl = Timeline(residual_window_s=a.residuals, on_event=show)
    rstats = ReadStats()
    bus: can.BusABC | None = None
    try:
        if a.log is not None:
            frames: Iterator[can.Message] = read_log(a.log, rstats)
            source = str(a.log)
        else:
            bus = open_bus(a)
            # a lockstep bench outruns a Python reader (see canfdi.hil):
            # a deep kernel queue instead of lost frames
            raise_rcvbuf(bus)
            window = checks.window_us()
            timeout = a.timeout if a.timeout is not None else (
                None if window is None else 10 * window * 1e-6 + 10.0)
            frames = bus_frames(bus, timeout)
            source = f"{a.interface} {a.channel}"
            if not a.quiet:
                print(f"canfdi-watch: listening on {source}" + (f" for up to {timeout:g} s" if timeout else ""),
                      flush=True)
        done = False
        for msg in frames:
            tl.feed(msg)
            if checks.step(tl):
                done = True
                break
        tl.flush_residuals()
        if not done:
            checks.finish(tl)
    except BusOpenError as e:
        print(f"canfdi-watch: {e}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        checks.finish(tl)
    finally:
        if bus is not None:
            bus.shutdown()
    s = tl.stats
    if s.e2e_bad:
        checks.results.append(f"FAIL  {tl.e2e_summary()}")
        checks.failed = True
    if rstats.bad_lines:
        print(f"canfdi-watch: {rstats.bad_lines} unreadable line(s) skipped (first: {rstats.first_error})",
              file=sys.stderr)
    if s.undecodable:
        print(f"canfdi-watch: {s.undecodable} frame(s) did not decode (first: {s.first_undecodable})", file=sys.stderr)
    if not a.quiet:
        span = f"{tl.start_us * 1e-6:.3f}-{tl.now_us * 1e-6:.3f} s" if s.frames else "nothing"
        print(f"canfdi-watch: {s.frames} frames from {source}, simulated {span}"
              + (f", {s.unknown_id} with unknown IDs" if s.unknown_id else ""))
    for line in checks.results:
        print(line)
    if s.frames == 0 and a.log is not None:
        print(f"canfdi-watch: {a.log} holds no readable frame", file=sys.stderr)
        return 1
    return 1 if checks.failed else 0


if __name__ == "__main__":
    sys.exit(main())
