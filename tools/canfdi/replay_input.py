"""Recorded logs of every format python-can reads, as candump text for the replay core.

candump ``.log`` files (also ``.log.gz``) go to the C core as they are: it
reads them itself, fast. Every other format python-can reads (Vector ASC
and BLF, PCAN TRC, CSV, ASAM MDF4 through asammdf, and their ``.gz``) is
read here frame by frame with python-can's reader and written as candump
text into a pipe (a FIFO the core opens like a file), so a log is never
held in memory.

Bad input never stops the replay: a text format's reader that raises on a
line is resumed after that line (the line is reported with its number); a
binary reader that raises ends that file, reported with the number of
frames read before. Frames python-can returns are written as they are: the
core counts CAN FD, remote and error frames and never feeds them to the
supervisor. A negative or non-finite time stamp is reported and skipped.

    fmt = log_format(Path("run.blf"))            # 'blf'
    for line, where in candump_lines(Path("run.blf"), problems): ...
"""
from __future__ import annotations

import gzip
import io
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Iterator, TextIO

import can

#: Suffixes of the formats python-can reads, without ".gz".
PYCAN_FORMATS = {".asc": "asc", ".blf": "blf", ".trc": "trc", ".csv": "csv", ".mf4": "mf4"}
CANDUMP_SUFFIXES = (".log", ".candump")
TEXT_FORMATS = ("asc", "trc", "csv")
CAN_ERR_FLAG = 0x20000000


class LogFormatError(ValueError):
    """The file is not a log this tool can read; str() names file and reason."""


@dataclass
class Problems:
    """What reading met, as 'file:line: reason' lines (the first few kept)."""
    items: list[tuple[str, int, str]] = field(default_factory=list)  # (file, line or -1, reason)
    count: int = 0
    keep: int = 100

    def add(self, path: Path, line: int, why: str) -> None:
        self.count += 1
        if len(self.items) < self.keep:
            self.items.append((str(path), line, why))


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


class _CountingLines:
    """A text file as an iterator of lines that counts them (for python-can's text readers)."""

    def __init__(self, f: TextIO) -> None:
        self.f = f
        self.n = 0

    def __iter__(self) -> "_CountingLines":
        return self

    def __next__(self) -> str:
        line = next(self.f)
        self.n += 1
        return line

    def readline(self) -> str:
        line = self.f.readline()
        if line:
            self.n += 1
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


_TEXT_READERS: dict[str, type] = {"asc": can.ASCReader, "trc": can.TRCReader, "csv": can.CSVReader}


def _text_messages(path: Path, fmt: str, gz: bool, problems: Problems) -> Iterator[can.Message]:
    """A text log through python-can's reader, resumed after every line it raises on."""
    raw: TextIO = gzip.open(path, "rt", encoding="utf-8", errors="replace") if gz \
        else open(path, encoding="utf-8", errors="replace")
    lines = _CountingLines(raw)
    cls = _TEXT_READERS[fmt]
    try:
        reader = cls(lines)
        while True:
            try:
                for msg in reader:
                    yield msg
                return
            except (ValueError, IndexError, KeyError, TypeError, OverflowError) as e:
                problems.add(path, lines.n, f"python-can's {cls.__name__} cannot read this line "
                             f"({type(e).__name__}: {e}); skipped")
            except (OSError, EOFError, gzip.BadGzipFile) as e:
                problems.add(path, lines.n, f"read error, the rest of the file is lost: {e}")
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


def _binary_messages(path: Path, fmt: str, problems: Problems) -> Iterator[can.Message]:
    n = 0
    try:
        reader = can.BLFReader(path) if fmt == "blf" else can.LogReader(path)
    except Exception as e:  # noqa: BLE001 — any reader failure is a message, never a crash
        problems.add(path, -1, f"python-can cannot open it as {fmt.upper()}: {type(e).__name__}: {e}")
        return
    try:
        for msg in reader:
            n += 1
            yield msg
    except Exception as e:  # noqa: BLE001 — a damaged binary log ends here, reported
        problems.add(path, -1, f"python-can's reader stopped after frame {n}: {type(e).__name__}: {e}; "
                     f"the rest of the file is not read")
    finally:
        try:
            reader.stop()
        except Exception:  # noqa: BLE001 — closing a broken reader must not raise
            pass


def messages(path: Path, fmt: str, problems: Problems) -> Iterator[can.Message]:
    """Every frame python-can reads from a non-candump log; problems reported, never raised."""
    _, gz = _suffixes(path)
    if fmt in TEXT_FORMATS:
        return _text_messages(path, fmt, gz, problems)
    return _binary_messages(path, fmt, problems)


def write_candump(msgs: Iterator[can.Message], out: io.TextIOBase | TextIO, path: Path, problems: Problems,
                  progress: Callable[[int], None] | None = None) -> int:
    """Writes msgs as candump text; returns the frames written."""
    n = 0
    for i, msg in enumerate(msgs, 1):
        line = candump_line(msg)
        if line is None:
            problems.add(path, -1, f"frame {i}: time stamp {msg.timestamp!r} is negative, not finite or "
                         f"beyond the year 33658; skipped")
            continue
        out.write(line)
        n += 1
        if progress is not None and (n & 0x3FFF) == 0:
            progress(n)
    return n
