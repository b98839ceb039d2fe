"""Recorded logs of every format python-can reads, as candump text for the replay core.

candump ``.log`` files (also ``.log.gz``) go to the C core as they are: it
reads them itself, fast. Every other format python-can reads (Vector ASC
and BLF, PCAN TRC, CSV, ASAM MDF4 through asammdf, and their ``.gz``) is
read here frame by frame with python-can's reader and written as candump
text into a pipe (a FIFO the core opens like a file), so a log is never
held in memory.

Bad input never stops the replay: a text format's reader that raises on a
line is resumed after that line (the line is reported with its number); a
line python-can's ASC or TRC reader passes over without a frame is
reported with its number too, unless it is one the format holds besides
frames (blank lines, comments, the ASC header and trigger-block lines,
ASC events with a time stamp that are not CAN frames: statistics, chip
states, ...; TRC bus states and warnings); a binary reader that raises ends that file, reported with
the number of frames read before, and a BLF file shorter than its header
states is reported as truncated (python-can's reader ends there without a
word). Frames python-can returns are written as they are: the core counts
CAN FD, remote and error frames and never feeds them to the supervisor. A
classic frame with fewer data bytes than its DLC (python-can's ASC reader
makes one of a line cut in its data) and a negative or non-finite time
stamp are reported and skipped.

Each frame goes into the pipe at its place in the file: a text log's frame
on the candump line of the same number (the lines between are written
blank, which the core skips), a binary log's N-th frame on line N. The
line numbers the core reports (error and CAN FD frames, time stamps going
back, other channels) are therefore the file's own lines, or for BLF and
MF4, which have no lines, the frame's number in the file.

    fmt = log_format(Path("run.blf"))            # 'blf'
    for pos, msg in numbered_messages(Path("run.blf"), fmt, problems): ...
"""
from __future__ import annotations

import contextlib
import gc
import gzip
import io
import logging
import math
import os
import re
import sys
import traceback
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, Callable, Iterator, TextIO

if TYPE_CHECKING:  # python-can (with asammdf and pandas) is imported only to convert a non-candump log
    import can

#: Suffixes of the formats python-can reads, without ".gz".
PYCAN_FORMATS = {".asc": "asc", ".blf": "blf", ".trc": "trc", ".csv": "csv", ".mf4": "mf4"}
CANDUMP_SUFFIXES = (".log", ".candump")
TEXT_FORMATS = ("asc", "trc", "csv")
BINARY_FORMATS = ("blf", "mf4")
CAN_ERR_FLAG = 0x20000000


class LogFormatError(ValueError):
    """The file is not a log this tool can read; str() names file and reason."""


@dataclass
class Problems:
    """What reading met, as 'file:line: reason' lines (the first few kept)."""
    items: list[tuple[str, int, str, str]] = field(default_factory=list)  # (file, line or -1, reason, text)
    count: int = 0
    keep: int = 100
    truncated: bool = False  # the rest of the file could not be read

    def add(self, path: Path, line: int, why: str, text: str = "") -> None:
        """text: the line's first 80 characters, when it has one."""
        self.count += 1
        if len(self.items) < self.keep:
            self.items.append((str(path), line, why, text.rstrip("\r\n")[:80]))


def _suffixes(path: Path) -> tuple[str, bool]:
    """(format suffix, gzip-compressed)."""
    suf = [s.lower() for s in path.suffixes]
    gz = bool(suf) and suf[-1] == ".gz"
    if gz:
        suf = suf[:-1]
    return (suf[-1] if suf else ""), gz


def _sniff_candump(path: Path, gz: bool) -> bool:
    opener: Callable[..., Any] = gzip.open if gz else open
    try:
        with opener(path, "rt", encoding="ascii", errors="replace") as f:
            for _ in range(20):
                line = f.readline()
                if not line:
                    return False
                s = line.strip()
                if s and not s.startswith("#"):
                    return s.startswith("(") and ")" in s
    except (OSError, EOFError, gzip.BadGzipFile):
        return False
    return False


def log_format(path: Path) -> str:
    """'candump', 'asc', 'blf', 'trc', 'csv' or 'mf4'; LogFormatError otherwise.

    By suffix (a trailing .gz allowed); a file with another suffix is taken
    as candump when its first line looks like one.
    """
    if not path.exists():
        raise LogFormatError(f"{path}: no such file")
    if path.is_dir():
        raise LogFormatError(f"{path}: is a directory")
    suf, gz = _suffixes(path)
    if suf in CANDUMP_SUFFIXES:
        return "candump"
    if suf in PYCAN_FORMATS:
        if gz and suf in (".blf", ".mf4"):
            raise LogFormatError(f"{path}: python-can does not read compressed {suf} files; "
                                 f"decompress it first (gunzip)")
        return PYCAN_FORMATS[suf]
    if _sniff_candump(path, gz):
        return "candump"
    raise LogFormatError(f"{path}: unknown log format '{suf or path.name}' (candump .log, .asc, .blf, .trc, "
                         f".csv, .mf4, optionally .gz)")


def _chan(msg: can.Message) -> str:
    c = msg.channel
    s = "can" if c is None or c == "" else str(c)
    s = "".join(ch if ch.isalnum() or ch in "_-.:" else "_" for ch in s)
    return s[:15] or "can"


def candump_line(msg: can.Message) -> str | None:
    """One message as a candump -L line; None when its time stamp is unusable."""
    ts = float(msg.timestamp)
    if not math.isfinite(ts) or ts < 0.0 or ts >= 1e12:
        return None
    us = round(ts * 1e6)
    stamp = f"({us // 1_000_000:010d}.{us % 1_000_000:06d}) {_chan(msg)} "
    if msg.is_error_frame:
        return stamp + f"{CAN_ERR_FLAG | (msg.arbitration_id & 0x1FFFFFFF):08X}#{bytes(msg.data)[:8].hex().upper()}\n"
    ident = f"{msg.arbitration_id:08X}" if msg.is_extended_id else f"{msg.arbitration_id & 0x7FF:03X}"
    if msg.is_remote_frame:
        return stamp + f"{ident}#R{min(msg.dlc, 15):X}\n"
    data = bytes(msg.data).hex().upper()
    if msg.is_fd:
        flags = (1 if msg.bitrate_switch else 0) | (2 if msg.error_state_indicator else 0)
        return stamp + f"{ident}##{flags:X}{data}\n"
    return stamp + f"{ident}#{data[:16]}\n"


#: A line of an ASC file that holds no CAN frame by design: its header, comments, trigger
#: blocks, and events with a time stamp that are not CAN frames (statistics, chip states, ...).
_ASC_NOT_A_FRAME = re.compile(r"(//|date\s|base\s|(no\s+)?internal\s+events|begin\s+triggerblock|"
                              r"end\s+triggerblock)", re.IGNORECASE)
#: A TRC line that is a bus status by design: a warning or status event (v1.1/1.3 "Warng", v2.x
#: "ST", "EC", "EV"), or v1.0's bus information on identifier FFFFFFFF.
_TRC_STATUS = frozenset(("Warng", "ST", "EC", "EV", "FFFFFFFF"))
_ASC_STAMPED = re.compile(r"\d+\.\d+\s")
#: python-can's own test: a line its ASCReader reads as a CAN frame.
_ASC_FRAME = re.compile(r"\d+\.\d+\s+(\d+\s+(\w+\s+(Tx|Rx)|ErrorFrame)|CANFD)", re.ASCII | re.IGNORECASE)


def _frame_expected(fmt: str, line: str, n: int) -> bool:
    """The line should give a frame (a line of the format's other kinds does not)."""
    s = line.strip()
    if not s:
        return fmt == "csv"          # python-can's CSV reader raises on a blank line: reported there
    if fmt == "asc":
        if _ASC_NOT_A_FRAME.match(s):
            return False
        return not _ASC_STAMPED.match(s) or bool(_ASC_FRAME.match(s))
    if fmt == "trc":
        return not s.startswith(";") and not _TRC_STATUS.intersection(s.split()[1:5])
    return n > 1                     # csv: the header line


#: An ASC frame line cut after its time stamp, channel, identifier or a part of its direction:
#: it reads as an event line (no frame, no word) to python-can's ASC reader.
_ASC_CUT_FRAME = re.compile(r"\d+\.\d+(\s+\d+(\s+[0-9A-Fa-f]+x?(\s+[RT]x?)?)?)?", re.ASCII)


def _cut_line(fmt: str, line: str, expected: bool) -> bool:
    """The file ends inside this line (it has no line end; `expected`: _frame_expected's answer):
    a line that should hold a frame (some tools write no line end after the last line, so a
    whole line is judged by what it gave: a frame line that gives no frame was cut; one that
    gives a frame, see _cut_in_a_byte). An ASC frame line cut after its time stamp, channel or
    identifier counts too: the reader takes it for an event line. An event, status, comment or
    header line at the end is not reported."""
    s = line.strip()
    return bool(s) and (expected or (fmt == "asc" and bool(_ASC_CUT_FRAME.fullmatch(s))))


def _cut_in_a_byte(fmt: str, line: str, msg: can.Message, base: str) -> bool:
    """A classic data frame read from a last line without a line end that may end inside its last
    data byte, which python-can reads as a whole byte with a wrong value ("0C" cut to "0" is
    0x00); a cut between bytes gives too few bytes (short_data). The last data byte ends the line
    in TRC and in ASC unless ASC's trailing columns ("Length = ...") follow; a hex byte is two
    digits, a decimal one ("base dec") one to three, so there a line that ends in a byte cannot
    be told from a cut one. CAN FD, remote and error frames are not the supervisor's input."""
    if (fmt not in ("asc", "trc") or msg.is_fd or msg.is_remote_frame or msg.is_error_frame
            or len(msg.data) == 0):
        return False
    cols = line.split()
    dec = fmt == "asc" and base.lower().startswith("dec")
    try:
        last = int(cols[-1], 10 if dec else 16)
    except ValueError:
        return False  # the line ends in another column (ASC's "Length = ..."): its data are whole
    if last != msg.data[-1] or (fmt == "asc" and "Length" in cols):
        return False
    return dec or len(cols[-1]) < 2


_CUT_WHY = "the file ends inside this line (no line end): the log is cut here; no frame is read from it"
_CUT_BYTE_WHY = ("the file ends inside this line (no line end), maybe inside its last data byte: the log is cut "
                 "here; its frame is not used")

_SKIPPED_WHY = {
    "asc": "python-can's ASCReader reads no frame from this line; skipped",
    "trc": "python-can's TRCReader reads no frame from this line (an error frame or another event type it "
           "does not read, or too few columns); skipped",
    "csv": "python-can's CSVReader reads no frame from this line; skipped",
}


class _CountingLines:
    """A text file as an iterator of lines that counts them (for python-can's text readers), and
    reports the lines that should hold a frame but gave none.

    python-can's text readers read a line and yield its frame before they read the next one, so
    a line that should give a frame (_frame_expected) and is still pending when the next line is
    read was passed over: it goes to `skipped`. The reader's caller clears the pending line when
    a frame comes (`gave_frame`) or when it reports the line itself (`reported`)."""

    def __init__(self, f: TextIO, fmt: str, skipped: Callable[[int, str, str], None]) -> None:
        self.f = f
        self.n = 0
        self.fmt = fmt
        self.skipped = skipped
        self.pending = 0
        self.pending_text = ""
        self.pending_why = ""
        self.last = ""
        self.cut = False  # the current line has no line end (the file's last)

    def _seen(self, line: str) -> None:
        self.flush()
        self.n += 1
        self.last = line
        self.cut = not line.endswith("\n")
        expected = _frame_expected(self.fmt, line, self.n)
        cut = self.cut and _cut_line(self.fmt, line, expected)
        if cut or expected:
            self.pending = self.n
            self.pending_text = line
            self.pending_why = _CUT_WHY if cut else _SKIPPED_WHY[self.fmt]

    def flush(self) -> None:
        if self.pending:
            self.skipped(self.pending, self.pending_why, self.pending_text)
            self.pending = 0

    def report_frame(self, why: str) -> None:
        """The current line gave a frame that is not used: reported with `why`."""
        self.pending, self.pending_text, self.pending_why = self.n, self.last, why
        self.flush()

    def gave_frame(self) -> None:
        if self.pending == self.n:
            self.pending = 0

    reported = gave_frame

    def __iter__(self) -> "_CountingLines":
        return self

    def __next__(self) -> str:
        line = next(self.f)
        self._seen(line)
        return line

    def readline(self) -> str:
        line = self.f.readline()
        if line:
            self._seen(line)
        return line

    def read(self, size: int = -1) -> str:
        return self.f.read(size)

    def close(self) -> None:
        self.f.close()


class _FakeHeader:
    """CSVReader skips its first line; on a resume that line is not data."""

    def __init__(self, inner: _CountingLines) -> None:
        self.inner = inner
        self.given = False

    def __iter__(self) -> "_FakeHeader":
        return self

    def __next__(self) -> str:
        if not self.given:
            self.given = True
            return "timestamp,arbitration_id,extended,remote,error,dlc,data\n"
        return next(self.inner)

    def close(self) -> None:
        self.inner.close()


def _text_reader(fmt: str) -> type:
    """python-can's reader class of a text format (imported here: a candump log needs none of it)."""
    import can

    return {"asc": can.ASCReader, "trc": can.TRCReader, "csv": can.CSVReader}[fmt]


#: python-can's TRC reader logs the lines it cannot parse as warnings; they are reported here
#: with their numbers instead.
logging.getLogger("can.io.trc").setLevel(logging.ERROR)


@contextlib.contextmanager
def _quiet_destructors(collect: bool) -> Iterator[None]:
    """Opening a damaged file leaves a half-built reader whose destructor may raise (asammdf's MDF
    object does); that failure is reported as the file's problem, the destructor's exception would
    only print a traceback. When the open raises, the reader is freed here, with the exception
    hook silenced: the frames of the traceback are cleared (they hold it) and, where the reader
    keeps reference cycles (collect: asammdf), a collection runs. Only a failed open pays for that
    collection, which walks every object of the process (0.2 s in a large one)."""
    old = sys.unraisablehook
    sys.unraisablehook = lambda _u: None
    try:
        yield
    except BaseException as e:
        seen: set[int] = set()
        x: BaseException | None = e
        while x is not None and id(x) not in seen:  # the frames of the exceptions it came from hold it too
            seen.add(id(x))
            traceback.clear_frames(x.__traceback__)
            x = x.__cause__ or x.__context__
        if collect:
            gc.collect()
        raise
    finally:
        sys.unraisablehook = old


def _text_messages(path: Path, fmt: str, gz: bool, problems: Problems) -> Iterator[tuple[int, can.Message]]:
    """A text log through python-can's reader, resumed after every line it raises on: (line, frame)."""
    raw: TextIO = gzip.open(path, "rt", encoding="utf-8", errors="replace") if gz \
        else open(path, encoding="utf-8", errors="replace")
    lines = _CountingLines(raw, fmt, lambda n, why, text: problems.add(path, n, why, text))
    cls = _text_reader(fmt)
    try:
        reader = cls(lines)
        while True:
            try:
                for msg in reader:
                    if lines.cut and _cut_in_a_byte(fmt, lines.last, msg, str(getattr(reader, "base", "hex"))):
                        lines.report_frame(_CUT_BYTE_WHY)  # its last byte may be wrong
                        continue
                    lines.gave_frame()
                    yield lines.n, msg
                lines.flush()
                return
            except (ValueError, IndexError, KeyError, TypeError, OverflowError) as e:
                lines.reported()
                why = f"python-can's {cls.__name__} cannot read this line ({type(e).__name__}: {e})"
                problems.add(path, lines.n, f"{_CUT_WHY} ({why})" if lines.cut else f"{why}; skipped", lines.last)
            except (OSError, EOFError, gzip.BadGzipFile) as e:
                lines.reported()
                problems.add(path, lines.n, f"read error, the rest of the file is lost: {e}")
                problems.truncated = True
                return
            # resume after the bad line with the reader's state (base, start time)
            state = {k: v for k, v in vars(reader).items() if k != "file"}
            src: Any = _FakeHeader(lines) if fmt == "csv" else lines
            reader = cls(src)
            vars(reader).update(state)
            if fmt in ("asc", "trc"):
                reader._extract_header = lambda: None  # the header was read before the bad line
    finally:
        raw.close()


def _binary_messages(path: Path, fmt: str, problems: Problems) -> Iterator[tuple[int, can.Message]]:
    import can  # see _text_reader

    n = 0
    try:
        with _quiet_destructors(collect=fmt != "blf"):
            reader = can.BLFReader(path) if fmt == "blf" else can.LogReader(path)
    except Exception as e:  # noqa: BLE001 — any reader failure is a message, never a crash
        problems.add(path, -1, f"python-can cannot open it as {fmt.upper()}: {type(e).__name__}: {e}")
        return
    try:
        for msg in reader:
            n += 1
            yield n, msg
        # python-can's BLF reader ends without a word where a cut file ends; its header knows the size
        stated = int(getattr(reader, "file_size", 0) or 0) if fmt == "blf" else 0
        size = os.path.getsize(path)
        if size < stated:
            problems.add(path, -1, f"truncated: {size} of the {stated} bytes its header states; the frames "
                         f"after frame {n} are lost")
            problems.truncated = True
    except Exception as e:  # noqa: BLE001 — a damaged binary log ends here, reported
        problems.add(path, -1, f"python-can's reader stopped after frame {n}: {type(e).__name__}: {e}; "
                     f"the rest of the file is not read")
        problems.truncated = True
    finally:
        try:
            reader.stop()
        except Exception:  # noqa: BLE001 — closing a broken reader must not raise
            pass


def numbered_messages(path: Path, fmt: str, problems: Problems) -> Iterator[tuple[int, can.Message]]:
    """Every frame python-can reads from a non-candump log with its place in the file (its line in
    a text format, its number in BLF and MF4); problems reported, never raised."""
    _, gz = _suffixes(path)
    if fmt in TEXT_FORMATS:
        return _text_messages(path, fmt, gz, problems)
    return _binary_messages(path, fmt, problems)


def messages(path: Path, fmt: str, problems: Problems) -> Iterator[can.Message]:
    """Every frame python-can reads from a non-candump log; problems reported, never raised."""
    return (msg for _, msg in numbered_messages(path, fmt, problems))


def short_data(msg: can.Message) -> bool:
    """A classic data frame with fewer data bytes than its DLC 0..8 says (python-can's ASC reader
    makes one of a line cut in its data: "d 8 A" is one byte, 0x0A)."""
    return (not msg.is_fd and not msg.is_remote_frame and not msg.is_error_frame and msg.dlc <= 8
            and len(msg.data) < msg.dlc)


class PlacedWriter:
    """Writes candump lines into the core's pipe, each on the line of the given number (the lines
    between blank), so that the core's line numbers are the file's (see the module docstring)."""

    def __init__(self, out: io.TextIOBase | TextIO) -> None:
        self.out = out
        self.lines = 0

    def write(self, pos: int, line: str) -> None:
        if pos - 1 > self.lines:
            self.out.write("\n" * (pos - 1 - self.lines))
            self.lines = pos - 1
        self.out.write(line)
        self.lines += 1


def write_candump(msgs: Iterator[tuple[int, can.Message]], out: io.TextIOBase | TextIO, path: Path,
                  problems: Problems, fmt: str, progress: Callable[[int], None] | None = None) -> int:
    """Writes numbered_messages() as candump text, each frame at its place; returns the frames written."""
    w = PlacedWriter(out)
    n = 0
    for pos, msg in msgs:
        where = (f"frame {pos}", -1) if fmt in BINARY_FORMATS else ("frame", pos)
        if short_data(msg):
            problems.add(path, where[1], f"{where[0]}: {len(msg.data)} data bytes, its DLC says {msg.dlc} (a cut "
                         f"line?); skipped")
            continue
        line = candump_line(msg)
        if line is None:
            problems.add(path, where[1], f"{where[0]}: time stamp {msg.timestamp!r} is negative, not finite or "
                         f"beyond the year 33658; skipped")
            continue
        w.write(pos, line)
        n += 1
        if progress is not None and (n & 0x3FFF) == 0:
            progress(n)
    return n
