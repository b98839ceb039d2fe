"""canfdi-scenario: run a scenario file on the bus (HIL) and judge its expect lines.

Starts canfdi-ecu (waits for its ready line), records the whole bus to a
candump .log with python-can's Logger, starts canfdi-sim with the scenario,
waits for it to finish, stops the ECU (SIGTERM, exit status 0 required),
lets the recorder drain (no frame for 0.5 s), then decodes the recording (canfdi.timeline) and judges
the scenario's expect lines exactly as canfdi-sil does (canfdi.expect), so a
SIL and a HIL run of one scenario print the same PASS/FAIL lines.

In lockstep the recording must be complete: SimStep indices 0..N-1 without a
gap and both actuator frames for every step; anything lost is an error. So
is an ECU frame that fails its E2E check (a forged or corrupted status,
diagnosis, trouble-code or actuator frame, canfdi.timeline): it is listed in
the timeline as such, never decoded, and the run fails.
"""
from __future__ import annotations

import argparse
import json
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from . import REPO_ROOT
from .busargs import BusOpenError, add_bus_args, open_bus
from .expect import Verdict, evaluate, summary_line
from .hil import ProcError, Proc, Recorder, fmt_rate, start_ecu, start_sim
from .logio import ReadStats, read_log
from .scenario_file import Scenario, ScenarioError, load
from .timeline import ID_DCM_ACT, ID_PLANT, ID_STEP, ID_THR_ACT, Timeline

BIN = REPO_ROOT / "build" / "bin"
#: How long the recorder may take to drain its queue after the run. The sim
#: does not wait for the recorder; in User-Mode Linux python-can reads ~2 k
#: frames/s while a lockstep bench makes ~4 k/s, so the kernel queue (64 MB,
#: about 100 k frames) holds the backlog and the drain can take minutes. A
#: loss still shows: SimStep indices must be contiguous.
DRAIN_MAX_S = 600.0
#: The sim built for the sandbox (UBSan only: ASan cannot start inside User-Mode Linux).
SIM_HIL = REPO_ROOT / "build" / "hil" / "canfdi-sim"
EPILOG = """\
examples:
  tools/vcan-run canfdi-scenario tests/sil/scenarios/tps1_open.scn
  canfdi-scenario -c vcan0 --realtime --json build/hil/x.json my.scn
  canfdi-scenario --no-start --log run.log my.scn    # ECU and sim already running

exit status: 0 every expectation met and the run was clean; 1 an expectation
failed, a program failed, frames were lost, or an ECU frame was forged or
corrupted (failed its E2E check); 2 bad usage or invalid scenario,
or a scenario only the SIL rig can run (cycle, clear, power_cycle or expect
freeze: ECU-side actions and reads that are not on the bus yet).
"""


@dataclass
class RunResult:
    """What a run produced besides the log; errors make it fail whatever the verdicts."""
    errors: list[str] = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)
    frames_recorded: int = 0
    wall_s: float = 0.0


def _progress(rec: Recorder, duration_s: float, done: Any, timeout_s: float, quiet: bool) -> bool:
    """Wait until done() while showing simulated time; False on the wall-clock timeout."""
    t0 = time.monotonic()
    bar = None
    if not quiet and sys.stderr.isatty():
        from tqdm import tqdm
        bar = tqdm(total=round(duration_s, 3), unit="s", desc="simulated", file=sys.stderr,
                   bar_format="{l_bar}{bar}| {n:.2f}/{total:.2f} s [{elapsed}<{remaining}]")
    next_line = t0 + 5.0
    try:
        while not done():
            now = time.monotonic()
            if now - t0 > timeout_s:
                return False
            if bar is not None:
                bar.n = min(rec.sim_time_s, duration_s)
                bar.refresh()
            elif not quiet and now >= next_line:
                print(f"canfdi-scenario: simulated {rec.sim_time_s:.2f} / {duration_s:g} s, {rec.frames} frames "
                      f"({fmt_rate(rec.frames, now - t0)})", file=sys.stderr, flush=True)
                next_line = now + 5.0
            time.sleep(0.1)
        if bar is not None:
            bar.n = min(rec.sim_time_s, duration_s)
            bar.refresh()
        return True
    finally:
        if bar is not None:
            bar.close()


def run_started(a: argparse.Namespace, scn: Scenario, rec: Recorder, res: RunResult) -> None:
    """ECU, then sim; wait for the sim; stop the ECU; drain. Problems go to res.errors."""
    lockstep = not a.realtime
    ecu: Proc | None = None
    sim: Proc | None = None
    try:
        ecu = start_ecu(a.ecu, a.channel, lockstep, a.nvm, a.ready_timeout)
        sim = start_sim(a.sim, a.channel, scn.path, lockstep, a.seed)
        if not _progress(rec, scn.duration_s, lambda: sim.poll() is not None, a.timeout, a.quiet):
            sim.kill()
            res.errors.append(f"canfdi-sim did not finish within {a.timeout:g} s wall clock "
                              f"(simulated {rec.sim_time_s:.3f} of {scn.duration_s:g} s); killed")
        elif sim.poll() != 0:
            res.errors.append(f"canfdi-sim exited with status {sim.poll()}: {sim.tail()}")
        # The ECU first: in realtime it keeps sending every 1 ms, so the bus
        # goes quiet only once it has stopped; in lockstep it is idle already.
        rc = ecu.stop()
        if rc != 0:
            res.errors.append(f"canfdi-ecu exited with status {rc} on SIGTERM: {ecu.tail()}")
        if not rec.wait_quiet(0.5, DRAIN_MAX_S):
            res.errors.append(f"the recorder was still draining {DRAIN_MAX_S:g} s after the sim and the ECU ended")
    except ProcError as e:
        res.errors.append(str(e))
    finally:
        for p in (sim, ecu):
            if p is not None:
                p.kill()


def run_no_start(a: argparse.Namespace, scn: Scenario, rec: Recorder, res: RunResult) -> None:
    """Record a run someone else started: until the scenario's simulated end, or the bus goes quiet."""
    def done() -> bool:
        if rec.last_step >= 0:
            return rec.last_step + 1 >= scn.steps
        if rec.sim_time_s >= scn.duration_s - 0.1:   # last SimPlantStatus of the run
            return True
        return rec.frames > 0 and rec.idle_s() > 2.0
    if not _progress(rec, scn.duration_s, done, a.timeout, a.quiet):
        res.errors.append(f"the run did not reach {scn.duration_s:g} s simulated within {a.timeout:g} s "
                          f"wall clock (reached {rec.sim_time_s:.3f} s, {rec.frames} frames)")
    rec.wait_quiet(0.5, DRAIN_MAX_S)


def check_complete(tl: Timeline, scn: Scenario, started: bool, lockstep: bool, res: RunResult) -> None:
    """Lost frames are errors, never silently judged: SimStep 0..N-1, two actuator frames per step."""
    s = tl.stats
    if lockstep and s.steps == 0:
        res.errors.append("no SimStep frame recorded in a lockstep run (is canfdi-sim --lockstep on this bus?)")
        return
    if s.steps == 0:
        return
    if s.step_gaps or s.step_repeats:
        res.errors.append(f"recording incomplete: {s.step_gaps} SimStep frame(s) lost, {s.step_repeats} "
                          f"repeated/out of order (first: {s.first_gap})")
    first = s.first_step
    if first != 0:
        (res.errors if started else res.warnings).append(f"recording starts at step {first}, not 0")
    if started and s.last_step + 1 != scn.steps:
        res.errors.append(f"recording ends at step {s.last_step}, the scenario has {scn.steps} steps")
    n = s.last_step - first + 1
    for fid, name in ((ID_DCM_ACT, "DcmActuator"), (ID_THR_ACT, "ThrActuator")):
        got = s.counts.get(fid, 0)
        if got != n:
            res.errors.append(f"recording incomplete: {got} {name} frames for {n} steps")


def result_json(scn: Scenario, tl: Timeline, verdicts: list[Verdict], res: RunResult, log: Path,
                mode: str) -> dict[str, Any]:
    def s(t: int) -> float | None:
        return t * 1e-6 if t >= 0 else None
    return {
        "scenario": str(scn.path), "mode": mode, "log": str(log),
        "passed": not res.errors and all(v.ok for v in verdicts),
        "expectations": [v.as_dict() for v in verdicts if v.line_no],
        "unexpected": [v.as_dict() for v in verdicts if not v.line_no],
        "codes": {r.code: {"testFailed_s": s(r.first_failed_us), "pending_s": s(r.first_pending_us),
                           "confirmed_s": s(r.first_confirmed_us)}
                  for r in tl.dtcs.values() if r.first_reported_us >= 0 or r.first_pending_us >= 0},
        "errors": res.errors, "warnings": res.warnings,
        "frames": tl.stats.frames, "undecodable": tl.stats.undecodable, "steps": tl.stats.steps,
        "e2e_failures": {f"0x{fid:03X}": per for fid, per in sorted(tl.stats.e2e_bad_by_id.items())},
        "simulated_s": tl.end_us * 1e-6, "wall_s": round(res.wall_s, 3),
    }


def evaluate_log(scn: Scenario, log: Path, res: RunResult, started: bool, lockstep: bool,
                 quiet: bool = False) -> tuple[Timeline, list[Verdict]]:
    """Decode the recording, print the timeline, judge; the verdict lines printed as canfdi-sil prints them."""
    rstats = ReadStats()
    msgs = list(read_log(log, rstats))
    tl = Timeline()
    if not any(m.arbitration_id == ID_STEP for m in msgs):
        status = next((m for m in msgs if m.arbitration_id == ID_PLANT and len(m.data) == 8), None)
        if status is not None:
            tl.set_origin(status)
    tl.feed_all(msgs)
    if rstats.bad_lines:
        res.errors.append(f"{rstats.bad_lines} unreadable line(s) in {log} (first: {rstats.first_error})")
    if tl.stats.undecodable:
        res.warnings.append(f"{tl.stats.undecodable} frame(s) did not decode (first: {tl.stats.first_undecodable})")
    if tl.stats.e2e_bad:
        res.errors.append(tl.e2e_summary())
    check_complete(tl, scn, started, lockstep, res)
    verdicts = evaluate(scn, tl)
    if not quiet:
        print(f"canfdi-scenario: {scn.path}, {scn.duration_s:g} s, {len(scn.faults)} fault(s); "
              f"{tl.stats.frames} frames in {log}")
        for f in scn.faults:
            print(f"  injects {f.name:<22} {f.mode:<12} from {f.t_start_us * 1e-6:8.3f} s")
        print("\n  time [s]  event")
        for ev in tl.events:
            print(ev.line())
        print()
    for v in verdicts:
        print(v.line)
    for w in res.warnings:
        print(f"WARN  {w}")
    for e in res.errors:
        print(f"ERROR {e}")
    return tl, verdicts


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="canfdi-scenario", description=__doc__.split("\n\n")[0],
                                epilog=EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("scenario", type=Path, help="scenario file (host_sim/SCENARIO.md)")
    add_bus_args(p)
    mode = p.add_mutually_exclusive_group()
    mode.add_argument("--lockstep", action="store_true", help="pace the plant by the ECU (default)")
    mode.add_argument("--realtime", action="store_true", help="both on a 1 ms monotonic clock")
    p.add_argument("--log", type=Path, metavar="FILE", help="recording (default build/hil/<scenario>.log)")
    p.add_argument("--json", type=Path, metavar="FILE", help="write the machine-readable result here")
    p.add_argument("--no-start", action="store_true", help="sim and ECU already running: record and judge only")
    p.add_argument("--ecu", type=Path, default=BIN / "canfdi-ecu", metavar="PATH",
                   help="canfdi-ecu program (default build/bin/canfdi-ecu)")
    p.add_argument("--sim", type=Path, default=SIM_HIL, metavar="PATH",
                   help="canfdi-sim program (default build/hil/canfdi-sim, the sandbox build)")
    p.add_argument("--seed", type=int, help="override the scenario's noise seed (canfdi-sim --seed)")
    p.add_argument("--nvm", type=Path, metavar="FILE", help="DTC memory file of the ECU (canfdi-ecu --nvm)")
    p.add_argument("--ready-timeout", type=float, default=10.0, metavar="S", help="wait for the ECU's ready line")
    p.add_argument("--timeout", type=float, metavar="S",
                   help="wall-clock limit of the run (default 60 s + 30 x the duration)")
    p.add_argument("--live", action="store_true",
                   help="print the timeline while the run goes (each frame decoded as it arrives)")
    p.add_argument("-q", "--quiet", action="store_true", help="no timeline or progress, verdicts only")
    return p


def main(argv: list[str] | None = None) -> int:
    a = build_parser().parse_args(argv)
    try:
        scn = load(a.scenario, a.sim)
    except ScenarioError as e:
        print(f"canfdi-scenario: {e}", file=sys.stderr)
        return 2
    if scn.sil_only:
        print(f"canfdi-scenario: {scn.sil_only[0]} needs the SIL rig: cycle/clear are not sent over the bus yet "
              "(nor power_cycle; freeze frames are not read over it; uds lines are the SIL rig's tester, "
              "canfdi-uds is the bus's); run it with canfdi-sil", file=sys.stderr)
        return 2
    if not a.no_start:
        for prog in (a.ecu, a.sim):
            if not prog.is_file():
                print(f"canfdi-scenario: {prog} not built (make {prog.relative_to(REPO_ROOT) if prog.is_relative_to(REPO_ROOT) else prog})",
                      file=sys.stderr)
                return 2
    if a.timeout is None:
        a.timeout = 60.0 + 30.0 * scn.duration_s
    log = a.log if a.log is not None else REPO_ROOT / "build" / "hil" / f"{a.scenario.stem}.log"
    res = RunResult()
    t0 = time.monotonic()
    try:
        bus = open_bus(a)
    except BusOpenError as e:
        print(f"canfdi-scenario: {e}", file=sys.stderr)
        return 1
    try:
        if a.live and not a.quiet:
            print("\n  time [s]  event (live)", flush=True)
        rec = Recorder(bus, log, live=a.live and not a.quiet)
        try:
            if a.no_start:
                run_no_start(a, scn, rec, res)
            else:
                run_started(a, scn, rec, res)
        finally:
            rec.close()
        if rec.error is not None:
            res.errors.append(f"recorder: {rec.error}")
        res.frames_recorded = rec.frames
    finally:
        bus.shutdown()
    res.wall_s = time.monotonic() - t0
    lockstep = not a.realtime and not a.no_start
    tl, verdicts = evaluate_log(scn, log, res, not a.no_start, lockstep, a.quiet or a.live)
    print(summary_line(verdicts + [Verdict(False, e, 0, "") for e in res.errors], str(scn.path))
          + f"  [{tl.stats.frames} frames, {res.wall_s:.1f} s wall, log {log}]")
    if a.json is not None:
        a.json.parent.mkdir(parents=True, exist_ok=True)
        mode = "lockstep" if tl.stats.steps else "realtime"
        a.json.write_text(json.dumps(result_json(scn, tl, verdicts, res, log, mode), indent=2) + "\n")
    return 0 if not res.errors and all(v.ok for v in verdicts) else 1


if __name__ == "__main__":
    sys.exit(main())
