"""canfdi-replay: run the canfdi supervisor over a recorded CAN log and say what is wrong.

The firmware application itself (the C core build/bin/canfdi-replay-core,
the same code as on the ECU) is stepped on the log's own time base and fed
the recorded input frames (sensors and setpoints) through the same input
supervision, E2E checks included; where its models need the voltage the
actuators held, it takes the recorded ECU's actuator commands. What the
recorded ECU reported comes from its EcuDtc frames that pass their E2E
check (CRC, counter); a forged or corrupted one is counted, never taken. The result is a timeline (log time, trouble code,
status, degradation, confidence, description), what could not be judged
and why, the log's data quality, and optionally a JSON and an HTML report.

Several logs are consecutive drives of one vehicle: the trouble-code
memory is carried across, as through the ECU's NVM. --nvm-in/--nvm-out
carry it across separate runs (one run per drive: canfdi-fleet).
"""
from __future__ import annotations

import argparse
import hashlib
import json
import os
import subprocess
import sys
import tempfile
import threading
import time
from dataclasses import dataclass
from pathlib import Path
from typing import IO, Any

from . import DBC_PATH, REPO_ROOT
from .catalogue import dtc_by_code
from .replay_input import LogFormatError, Problems, log_format, numbered_messages, write_candump
from .replay_report import Report, dumps, status_text, where

CORE = REPO_ROOT / "build" / "bin" / "canfdi-replay-core"
DEFAULT_BITRATE = 1_000_000
EXIT_NONE, EXIT_FOUND, EXIT_USAGE, EXIT_NOTHING = 0, 1, 2, 3

EPILOG = """\
examples:
  canfdi-replay run.log                         # candump (also .log.gz): timeline on stdout
  canfdi-replay drive.blf --json r.json --html r.html
  canfdi-replay day1.asc day2.asc               # two drives, the code memory carried across
  canfdi-replay --map vehicle.map vehicle.mf4   # another bus's frames mapped onto the inputs
  canfdi-replay -c can1 --start mid-drive cut.log
  canfdi-replay --nvm-out d1.nvm day1.asc; canfdi-replay --nvm-in d1.nvm day2.asc   # = day1.asc day2.asc

time base: a step of the supervisor every 1 ms of log time, the frames
stamped at or before a step's time going in before it; a lockstep HIL
recording (SimStep frames) is stepped as canfdi-ecu --lockstep steps.
Times are seconds in the log: from its first frame, or the time stamps
themselves when they start below 1e6 s.

start: a log that begins at the recorded ECU's power-up (its first frames
equal the replay's, counters and all) is judged from the first step and
must reproduce the recorded ECU's codes frame for frame; any other log is
judged after a settling time (--settle, default %(settle)s s) and without the
throttle's tracking monitor, whose reference the recording does not carry
(nor while the recorded ECU's throttle command differs from the replay's:
it followed other setpoints).

exit status:
  0  no trouble code found
  1  at least one trouble code found (the timeline and --json say which)
  2  bad usage, or a log that cannot be read at all
  3  no trouble code found, but the logs held no input frame of the
     supervisor: nothing could be judged
"""


@dataclass
class LogIn:
    path: Path
    fmt: str
    direct: bool      # the core reads the file itself
    core_path: str    # what the core opens (the file, or a FIFO)


def _sha256(path: Path) -> str:
    h = hashlib.sha256()
    with path.open("rb") as f:
        for chunk in iter(lambda: f.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


def _core_binary() -> Path:
    return Path(os.environ.get("CANFDI_REPLAY_CORE", str(CORE)))


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="canfdi-replay",
        description="Replay recorded CAN logs through the canfdi supervisor (the firmware's own code) and "
                    "report the trouble codes it finds, when they started and how sure the diagnosis is.",
        epilog=EPILOG % {"settle": 5.0}, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("logs", nargs="+", metavar="LOG", type=Path,
                   help="recorded logs: candump .log (and .log.gz), .asc, .blf, .trc, .csv, .mf4; "
                        "several are consecutive drives")
    p.add_argument("--json", metavar="FILE", type=Path, help="write the JSON report (schema: the docstring of tools/canfdi/replay_report.py)")
    p.add_argument("--html", metavar="FILE", type=Path,
                   help="write the HTML report: one self-contained file with the plots inline")
    p.add_argument("--map", metavar="FILE", type=Path,
                   help="map another DBC's frames and signals onto the supervisor's inputs "
                        "(format: the docstring of tools/canfdi/replay_map.py; example: tests/replay/data/vehicle.map)")
    g = p.add_argument_group("bus (python-can's flags)")
    g.add_argument("-c", "--channel", help="the channel in the log to judge (default: the first channel "
                                           "carrying a frame of dbc/canfdi.dbc)")
    g.add_argument("-b", "--bitrate", type=int, default=DEFAULT_BITRATE,
                   help=f"bit rate of the recorded bus, for the bus load (default {DEFAULT_BITRATE})")
    t = p.add_argument_group("judgement")
    t.add_argument("--start", choices=("auto", "power-up", "mid-drive"), default="auto",
                   help="where the log starts (default auto: from the recorded ECU's frames)")
    t.add_argument("--settle", type=float, default=None, metavar="S",
                   help="seconds the models are not judged after a mid-drive start or a gap (default 5)")
    t.add_argument("--gap", type=float, default=0.010, metavar="S",
                   help="no frame at all for longer than S seconds is a gap in the log (default 0.010; with "
                        "--map at least three periods of the slowest mapped message)")
    t.add_argument("--clock", choices=("auto", "timestamps", "simstep"), default="auto",
                   help="time base (default auto: SimStep frames if the log has them, else time stamps)")
    m = p.add_argument_group("trouble-code memory (the ECU's NVM image)")
    m.add_argument("--nvm-in", metavar="FILE", type=Path,
                   help="power up with the DTC memory image in FILE (written by --nvm-out after the previous "
                        "drive) instead of a cleared memory")
    m.add_argument("--nvm-out", metavar="FILE", type=Path,
                   help="after the last log, power down (the operation cycle ends) and write the DTC memory "
                        "image to FILE: the next run's --nvm-in")
    o = p.add_argument_group("output")
    o.add_argument("-q", "--quiet", action="store_true", help="only the findings and the result line")
    o.add_argument("--no-progress", action="store_true", help="no progress bar (it is off anyway when "
                                                              "stderr is not a terminal)")
    o.add_argument("--plot-every", type=float, default=None, metavar="S",
                   help="sample interval of the HTML plots (default: about 2000 samples over the logs)")
    return p


class _Progress:
    """A tqdm bar on stderr, off when stderr is not a terminal: over the bytes of the logs when
    the core reads them all itself, else over the frames converted (their total is not known)."""

    def __init__(self, total: int, enabled: bool, by_frames: bool) -> None:
        self.bar = None
        self.by_frames = by_frames
        self.frames: dict[int, int] = {}
        if enabled and sys.stderr.isatty():
            from tqdm import tqdm
            self.bar = tqdm(total=None if by_frames else total, unit="frames" if by_frames else "B",
                            unit_scale=True, desc="replay", file=sys.stderr, leave=False)

    def at(self, file_index: int, nbytes: int, sizes: list[int]) -> None:
        if self.bar is not None and not self.by_frames:
            self.bar.n = sum(sizes[:file_index]) + nbytes
            self.bar.refresh()

    def frames_at(self, file_index: int, n: int) -> None:
        if self.bar is not None and self.by_frames:
            self.frames[file_index] = n
            self.bar.n = sum(self.frames.values())
            self.bar.refresh()

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()


def _feed_fifos(logs: list[LogIn], problems: list[Problems], core: subprocess.Popen[bytes],
                mapper: Any, errors: list[str], prog: _Progress) -> None:
    """Writes every non-direct log as candump text into its FIFO, in order."""
    for i, lg in enumerate(logs):
        if lg.direct:
            continue
        fd = -1
        while fd < 0:
            try:
                fd = os.open(lg.core_path, os.O_WRONLY | os.O_NONBLOCK)
            except OSError:
                if core.poll() is not None:
                    return
                time.sleep(0.005)
        os.set_blocking(fd, True)
        try:
            with os.fdopen(fd, "w", encoding="ascii", buffering=1 << 20) as out:
                n = 0
                if mapper is not None:
                    n = mapper.write(lg.path, lg.fmt, out, problems[i])
                elif lg.fmt != "candump":
                    n = write_candump(numbered_messages(lg.path, lg.fmt, problems[i]), out, lg.path, problems[i],
                                      lg.fmt, progress=lambda k, i=i: prog.frames_at(i, k))
                if n == 0 and problems[i].count == 0:
                    problems[i].add(lg.path, -1, "no frame in it" if mapper is None else
                                    "no frame of the map's messages in it")
        except BrokenPipeError:
            errors.append(f"{lg.path}: the replay core stopped reading")
            return
        except Exception as e:  # noqa: BLE001 — reported, the replay of the others goes on
            errors.append(f"{lg.path}: {type(e).__name__}: {e}")


def run(a: argparse.Namespace, report: Report) -> int:
    """Runs the core over the logs and folds its events into report; returns the core's status."""
    core_bin = _core_binary()
    if not core_bin.exists():
        print(f"canfdi-replay: {core_bin} is missing: build it with `make all`", file=sys.stderr)
        return EXIT_USAGE
    mapper = None
    if a.map is not None:
        from .replay_map import MapError, Mapper
        try:
            mapper = Mapper.load(a.map)
        except MapError as e:
            print(f"canfdi-replay: {e}", file=sys.stderr)
            return EXIT_USAGE
        report.map_info = mapper.info()
    logs: list[LogIn] = []
    tmp = tempfile.TemporaryDirectory(prefix="canfdi-replay-")
    try:
        for i, path in enumerate(a.logs):
            fmt = log_format(path)
            direct = fmt == "candump" and mapper is None
            core_path = str(path)
            if not direct:
                core_path = os.path.join(tmp.name, f"log{i}.fifo")
                os.mkfifo(core_path)
            logs.append(LogIn(path, fmt, direct, core_path))
    except LogFormatError as e:
        tmp.cleanup()
        print(f"canfdi-replay: {e}", file=sys.stderr)
        return EXIT_USAGE
    try:
        return _run_core(a, report, core_bin, logs, mapper)
    finally:
        tmp.cleanup()


def _run_core(a: argparse.Namespace, report: Report, core_bin: Path, logs: list[LogIn], mapper: Any) -> int:
    total_s = 0.0
    sizes = [lg.path.stat().st_size for lg in logs]
    every = a.plot_every
    if getattr(a, "samples_every", None):
        every = a.samples_every  # canfdi-fleet: the samples for its parameter tracks, no HTML
    elif a.html is None:
        every = 0.0
    elif every is None:
        # about 2000 samples for a log of the size's duration (~45 bytes per frame, ~4.5 frames per ms)
        total_s = sum(sizes) / 45.0 / 4500.0
        every = max(0.01, round(total_s / 2000.0, 3))
    # a mapped bus has no ECU of this firmware whose power-up could be reproduced
    start = "mid-drive" if mapper is not None and a.start == "auto" else a.start
    gap_ms = max(2, round(a.gap * 1000), mapper.min_gap_ms() if mapper is not None else 0)
    cmd = [str(core_bin), "--start", start, "--clock", a.clock, "--gap-ms", str(gap_ms),
           "--every-ms", str(round(every * 1000)), "--progress"]
    if a.settle is not None:
        cmd += ["--settle-ms", str(round(a.settle * 1000))]
    if a.channel:
        cmd += ["--channel", a.channel]
    if getattr(a, "nvm_in", None) is not None:
        cmd += ["--nvm-in", str(a.nvm_in)]
    if getattr(a, "nvm_out", None) is not None:
        cmd += ["--nvm-out", str(a.nvm_out)]
    if mapper is not None:
        cmd += mapper.core_args()
    cmd += [lg.core_path for lg in logs]
    problems = [Problems() for _ in logs]
    errors: list[str] = []
    hashes: dict[int, str] = {}

    def hash_all() -> None:
        for i, lg in enumerate(logs):
            hashes[i] = _sha256(lg.path)
        report.dbc = {"path": str(DBC_PATH.relative_to(REPO_ROOT)), "sha256": _sha256(DBC_PATH)}

    hasher = threading.Thread(target=hash_all, daemon=True)
    hasher.start()
    prog = _Progress(sum(sizes), not a.no_progress, by_frames=any(not lg.direct for lg in logs))
    core = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    feeder = None
    if any(not lg.direct for lg in logs):
        feeder = threading.Thread(target=_feed_fifos, args=(logs, problems, core, mapper, errors, prog),
                                  daemon=True)
        feeder.start()
    assert core.stdout is not None and core.stderr is not None
    err_chunks: list[bytes] = []
    err_reader = threading.Thread(target=lambda: err_chunks.append(core.stderr.read()), daemon=True)  # type: ignore[union-attr]
    err_reader.start()
    try:
        for raw in core.stdout:
            e = json.loads(raw)
            if e["ev"] == "p":
                prog.at(int(e["file"]), int(e["bytes"]), sizes)
                continue
            report.feed(e)
    finally:
        prog.close()
    rc = core.wait()
    err_reader.join()
    if feeder is not None:
        feeder.join()
    hasher.join()
    for i, lg in enumerate(logs):
        st = report.log(i)
        st.path = str(lg.path)
        st.fmt = lg.fmt
        st.sha256 = hashes.get(i, "")
        st.input_problems = problems[i].items
        st.input_problem_count = problems[i].count
        st.input_truncated = problems[i].truncated
    for msg in errors:
        print(f"canfdi-replay: {msg}", file=sys.stderr)
    stderr = b"".join(err_chunks).decode(errors="replace").strip()
    if rc != 0:
        print(f"canfdi-replay: the replay core failed (exit {rc}): {stderr}", file=sys.stderr)
        return EXIT_USAGE
    if stderr:
        print(stderr, file=sys.stderr)
    return 0


def _fmt_t(t: float) -> str:
    return f"{t:10.3f}"


def print_timeline(report: Report, a: argparse.Namespace, out: IO[str]) -> None:
    descs = dtc_by_code()
    findings = report.findings()
    for lg in report.logs:
        eo = lg.eof
        if not a.quiet:
            ag = lg.agree
            print(f"canfdi-replay: {lg.path} ({lg.fmt}, {eo.get('frames', 0)} frames, "
                  f"{eo.get('first_t', 0):.3f}-{eo.get('last_t', 0):.3f} s, time base {lg.clock or '-'}, "
                  f"channel {lg.channel or '-'}), firmware {report.hdr.get('sw_version', '?')} "
                  f"({report.hdr.get('fw', '?')}, calibration {report.hdr.get('calibration_id', '?')})", file=out)
            if lg.start == "power-up":
                print(f"  start: at the recorded ECU's power-up ({lg.start_decided_by}); judged from the first step",
                      file=out)
            elif lg.start:
                print(f"  start: after the recorded ECU's power-up ({lg.start_decided_by}); models judged from "
                      f"{lg.settle_until:.3f} s (settling time {report.hdr.get('settle_s', 0):g} s), the tracking "
                      f"monitor not at all", file=out)
            if ag.get("recorded_ecu_frames") and lg.start == "mid-drive":
                print(f"  recorded ECU: {ag.get('recorded_ecu_frames')} frames, not compared frame by frame (its "
                      f"counters and controller states run since its power-up)", file=out)
            elif ag.get("recorded_ecu_frames"):
                same = ag.get("matched", 0)
                n = ag.get("recorded_ecu_frames", 0)
                line = f"  recorded ECU: {same} of its {n} frames identical to the replay's"
                if lg.mismatch:
                    line += f" (first difference at {lg.mismatch['t']:.3f} s, id 0x{lg.mismatch['id']:03X})"
                print(line, file=out)
            else:
                print("  recorded ECU: none of its frames in the log (no commands: the models that need them "
                      "are not judged)", file=out)
            print(f"\n  {'time [s]':>10}  {'code':5}  {'status':12} {'degradation':29} {'conf':>5}  description",
                  file=out)
        rows = []
        for f in findings:
            if f["log"] != lg.index:
                continue
            deg = f["degradation"] or {}
            conf = f"{f['confidence_pct']} %" if f["confidence_pct"] is not None else "-"
            st = f["status_at_finding"]
            rows.append((f["first_failed_s"], f"  {_fmt_t(f['first_failed_s'])}  {f['code']:5}  "
                         f"{status_text(st) if st is not None else '':12} "
                         f"{'dcm ' + deg.get('dcm', '?') + ', thr ' + deg.get('thr', '?'):29} {conf:>5}  "
                         f"{f['description']}"))
        if not a.quiet:
            # later status changes of the codes found, and degradation changes
            found = {f["code"] for f in findings if f["log"] == lg.index}
            for code in sorted(found):
                first = next(f["first_failed_s"] for f in findings if f["log"] == lg.index and f["code"] == code)
                prev = None
                for t, st, _ in lg.dtc_rep.get(code, []):
                    key = (st & 0x01, st & 0x08)
                    if t > first and prev is not None and key != prev:
                        rows.append((t, f"  {_fmt_t(t)}  {code:5}  {status_text(st):12}"))
                    prev = key
            last = None
            judged = lg.tested_spans("dcm_models") + lg.tested_spans("thr_models")
            for d in lg.deg:
                key = (d["dcm"], d["thr"], d["bridge"], d["limp"])
                if last is not None and key != last and any(a <= d["t"] < b for a, b in judged):
                    rows.append((d["t"], f"  {_fmt_t(d['t'])}  {'':5}  {'':12} dcm {d['dcm']}, thr {d['thr']}"
                                 f"{', bridge ' + 'NAB'[d['bridge']] if d['bridge'] < 3 else ''}"
                                 f"{', limp-home' if d['limp'] else ''}"))
                last = key
        for _, line in sorted(rows, key=lambda r: r[0]):
            print(line, file=out)
        if not rows and not a.quiet:
            print("  (no trouble code)", file=out)
        if not a.quiet:
            _print_not_judged(report, lg.index, out)
            _print_quality(report, lg.index, a.bitrate, out)
            _print_recorded(report, lg.index, out, descs)
            print("", file=out)
    codes = sorted({f["code"] for f in findings})
    if codes:
        print(f"result: {len(codes)} trouble code{'s' if len(codes) > 1 else ''} found: {', '.join(codes)}", file=out)
    else:
        print("result: no trouble code found", file=out)


def _print_not_judged(report: Report, i: int, out: IO[str]) -> None:
    items = [n for n in report.not_judged() if n["log"] == i]
    if not items:
        print("  every monitor judged over the whole log", file=out)
        return
    print("  not judged:", file=out)
    for n in items:
        sp = n["spans"]
        whys = sorted({s["why"] for s in sp})
        where = (f"{sp[0]['from_s']:.3f}-{sp[0]['to_s']:.3f} s" if n["span_count"] == 1
                 else f"{n['span_count']} spans, {n['seconds']:.3f} s")
        print(f"    {n['monitor']:12} ({', '.join(n['codes'])}): {where}: {'; '.join(whys)}", file=out)


def _print_quality(report: Report, i: int, bitrate: int, out: IO[str]) -> None:
    dq = report.data_quality(bitrate)[i]
    fmt = report.logs[i].fmt
    parts = []
    if dq["bad_line_count"]:
        first = dq["bad_lines"][0]
        parts.append(f"{dq['bad_line_count']} bad line(s) (first: {where(fmt, first['line'])}: {first['why']})")
    if dq["read_errors"]:
        parts.append(f"read error at {where(fmt, dq['read_errors'][0]['line'])}: {dq['read_errors'][0]['why']}")
    if dq["gap_count"]:
        parts.append(f"{dq['gap_count']} gap(s) in the log (first {dq['gaps'][0]['from_s']:.3f}-"
                     f"{dq['gaps'][0]['to_s']:.3f} s)")
    if dq["time_stamps_back"]:
        parts.append(f"{dq['time_stamps_back']} time stamp(s) going back")
    if dq["time_stamp_outliers"]:
        first = dq["time_stamp_outliers_first"][0]
        parts.append(f"{dq['time_stamp_outliers']} time stamp(s) out of sequence, taken at the current time "
                     f"(first: {where(fmt, first['line'])})")
    for name, rej in dq["rejected_frames"].items():
        bad = {k: v for k, v in rej.items() if v}
        if bad:
            parts.append(f"{name} " + ", ".join(f"{k} {v}" for k, v in bad.items()))
    if dq.get("recorded_ecu_dtc_frames_failing_e2e"):
        parts.append(f"{dq['recorded_ecu_dtc_frames_failing_e2e']} recorded EcuDtc frame(s) forged or corrupted "
                     f"(E2E check failed; not taken as the recorded ECU's)")
    for key, label in (("error_frames", "error frames"), ("fd_frames", "CAN FD frames (not fed)"),
                       ("remote_frames", "remote frames"), ("extended_frames", "29-bit frames")):
        if dq[key]:
            parts.append(f"{dq[key]} {label}")
    for name, oc in dq["other_channels"].items():
        parts.append(f"channel {name}: {oc['frames']} frames not judged (first: {where(fmt, oc['first_line'])}; "
                     f"choose with -c)")
    if dq["unknown_ids"]:
        parts.append(f"{len(dq['unknown_ids'])} identifier(s) not in dbc/canfdi.dbc")
    for m in dq["missing_frames"]:
        parts.append(f"{m['frame']} {'never received' if m['never_received'] else 'missing'} "
                     f"{m['from_s']:.3f}-{m['to_s']:.3f} s")
    bl = dq["bus_load_pct"]
    parts.append(f"bus load mean {bl['mean']:.1f} %, max {bl['max']:.1f} % at {bitrate // 1000} kbit/s")
    print("  data quality: " + "; ".join(parts[:12]) + (f"; ... ({len(parts) - 12} more, see --json)"
                                                        if len(parts) > 12 else ""), file=out)


def _print_recorded(report: Report, i: int, out: IO[str], descs: Any) -> None:
    lg = report.logs[i]
    findings = {f["code"]: f for f in report.findings() if f["log"] == i}
    lines = []
    for f in findings.values():
        r = f["recorded_ecu_first_failed_s"]
        if r is not None:
            same = "same time" if abs(r - f["first_testfailed_s"]) < 5e-7 else f"replay {f['first_testfailed_s']:.3f} s"
            lines.append(f"{f['code']} at {r:.3f} s ({same})")
    for r in report.recorded_only():
        if r["log"] == i:
            lines.append(f"{r['code']} at {r['first_failed_s']:.3f} s, not found by the replay: {r['why']}")
    if lines:
        print("  recorded ECU reported: " + "; ".join(lines), file=out)
    elif lg.dtc_ecu:
        print("  recorded ECU reported: no trouble code", file=out)


def main(argv: list[str] | None = None) -> int:
    a = build_parser().parse_args(argv)
    if a.settle is not None and not 0 <= a.settle <= 3600:
        print("canfdi-replay: --settle must be 0..3600 s", file=sys.stderr)
        return EXIT_USAGE
    if not 0.002 <= a.gap <= 3600:
        print("canfdi-replay: --gap must be 0.002..3600 s", file=sys.stderr)
        return EXIT_USAGE
    if a.bitrate <= 0:
        print("canfdi-replay: --bitrate must be positive", file=sys.stderr)
        return EXIT_USAGE
    report = Report()
    rc = run(a, report)
    if rc != 0:
        return rc
    try:
        print_timeline(report, a, sys.stdout)
        sys.stdout.flush()
    except BrokenPipeError:
        # the reader of the timeline went away (`| head`): the reports are still written
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
    doc = report.to_json(a.bitrate, "canfdi-replay")
    if a.json is not None:
        try:
            a.json.write_text(dumps(doc), encoding="utf-8")
        except OSError as e:
            print(f"canfdi-replay: cannot write {a.json}: {e}", file=sys.stderr)
            return EXIT_USAGE
    if a.html is not None:
        from .replay_html import write_html
        try:
            write_html(report, doc, a.html)
        except OSError as e:
            print(f"canfdi-replay: cannot write {a.html}: {e}", file=sys.stderr)
            return EXIT_USAGE
    if doc["dtcs"]:
        return EXIT_FOUND
    if not any(lg.eof.get("steps") for lg in report.logs) or all(
            not any(f["ok"] for f in lg.frames) for lg in report.logs):
        print("canfdi-replay: no input frame of the supervisor in the log(s): nothing could be judged",
              file=sys.stderr)
        return EXIT_NOTHING
    return EXIT_NONE


if __name__ == "__main__":
    sys.exit(main())
