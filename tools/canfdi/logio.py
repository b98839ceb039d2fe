"""Read recorded CAN logs without letting one bad line end the analysis.

python-can's ``can.LogReader`` reads every format (.log/.asc/.blf/.trc/...),
but its candump reader raises on the first malformed line and the generator
cannot resume. A log copied off a bench or cut by a crash often has exactly
that (a truncated last line, a stray message), so candump ``.log`` files —
the format this project records — are parsed here line by line: a bad line
is counted and skipped. Other formats go through ``can.LogReader``; an error
there stops reading, is counted, and reported, never raised.

    stats = ReadStats()
    for msg in read_log(Path("run.log"), stats): ...
    stats.bad_lines, stats.first_error          # 0, ''
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Iterator

import can

CAN_ERR_FLAG = 0x20000000


@dataclass
class ReadStats:
    """What reading a log met; the counters only grow."""
    frames: int = 0
    bad_lines: int = 0
    first_error: str = ""          # 'file:line: reason' of the first bad line
    stopped_early: bool = False     # a non-candump reader failed part-way

    def bad(self, where: str, reason: str) -> None:
        self.bad_lines += 1
        if not self.first_error:
            self.first_error = f"{where}: {reason}"


def parse_candump_line(line: str) -> can.Message | None:
    """One candump -L line -> Message; None for blank lines; ValueError if malformed.

    Accepts classic data frames ``ID#DATA``, remote frames ``ID#R[len]``, FD
    frames ``ID##<flags>DATA`` and the optional trailing R/T direction flag.
    """
    tok = line.split()
    if not tok:
        return None
    if len(tok) == 4 and tok[3] in ("R", "T", "r", "t"):
        tok = tok[:3]
    if len(tok) != 3 or not (tok[0].startswith("(") and tok[0].endswith(")")):
        raise ValueError("not '(timestamp) channel ID#DATA'")
    ts = float(tok[0][1:-1])
    ident, sep, data = tok[2].partition("#")
    if not sep or not ident or len(ident) > 8:
        raise ValueError(f"bad frame '{tok[2]}'")
    can_id = int(ident, 16)
    is_fd = data.startswith("#")
    if is_fd:
        data = data[2:]
    if data[:1] in ("R", "r"):
        return can.Message(timestamp=ts, arbitration_id=can_id, is_extended_id=len(ident) > 3,
                           is_remote_frame=True, dlc=int(data[1:] or "0"), channel=tok[1])
    if len(data) % 2 or len(data) > (128 if is_fd else 16):
        raise ValueError(f"bad data '{data}'")
    payload = bytes.fromhex(data)
    if can_id & CAN_ERR_FLAG and len(ident) > 3:
        return can.Message(timestamp=ts, is_error_frame=True, channel=tok[1])
    return can.Message(timestamp=ts, arbitration_id=can_id & 0x1FFFFFFF, is_extended_id=len(ident) > 3,
                       is_fd=is_fd, data=payload, dlc=len(payload), channel=tok[1])


def read_log(path: Path, stats: ReadStats | None = None) -> Iterator[can.Message]:
    """Every frame of a recorded log, in file order; problems go to stats."""
    st = stats if stats is not None else ReadStats()
    if path.suffix.lower() == ".log":
        with path.open(encoding="ascii", errors="replace") as f:
            for n, line in enumerate(f, 1):
                try:
                    msg = parse_candump_line(line)
                except ValueError as e:
                    st.bad(f"{path}:{n}", str(e))
                    continue
                if msg is not None:
                    st.frames += 1
                    yield msg
        return
    try:
        for msg in can.LogReader(path):
            st.frames += 1
            yield msg
    except Exception as e:  # noqa: BLE001 — any reader failure ends the log, never the tool
        st.stopped_early = True
        st.bad(f"{path}: after frame {st.frames}", f"{type(e).__name__}: {e}")
