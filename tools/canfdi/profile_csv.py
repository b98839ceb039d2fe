"""Profile files: the vehicle's quantities over time in CSV (host_sim/SCENARIO.md).

The Python twin of host_sim/canfdi_sim_csvprof.c: the same columns, ranges
and rules, and the same "file:line: message" wording, so that the HIL tools
refuse exactly what the simulator refuses. A scenario names such a file with
``profile <file.csv>``; the drive-profile generator (tools/drive) writes
them and ``canfdi-profile-plot`` draws them.

    prof = read(Path("build/drive/wltc3_10min_s1.csv"))
    prof.columns["speed_rad_s"][:3], prof.t_s[-1]

A header line names the columns: ``t_s`` first, then any of COLUMNS, each at
most once. Comment lines (``#``) and blank lines are allowed anywhere.
Times are rounded to whole microseconds; the first row is at 0 and every row
is later than the one before.
"""
from __future__ import annotations

import bisect
import math
from dataclasses import dataclass, field
from pathlib import Path

LINE_MAX = 256
MAX_TIME_S = 1e5
# name -> (low, high): the ranges of the scenario's profiles and params
COLUMNS: dict[str, tuple[float, float]] = {
    "speed_rad_s": (-400.0, 400.0),
    "angle_deg": (0.0, 90.0),
    "load_Nm": (-10.0, 10.0),
    "dcm_supply_V": (0.0, 80.0),
    "thr_supply_V": (0.0, 16.0),
}
SUPPLIES = ("dcm_supply_V", "thr_supply_V")
_NAMES = ", ".join(COLUMNS)


class ProfileError(ValueError):
    """'file:line: reason' (or 'file: reason'), as the C reader words it."""


@dataclass
class Profile:
    path: Path
    names: list[str] = field(default_factory=list)          # the quantity columns, in file order
    t_us: list[int] = field(default_factory=list)
    columns: dict[str, list[float]] = field(default_factory=dict)

    @property
    def t_s(self) -> list[float]:
        return [t * 1e-6 for t in self.t_us]

    @property
    def t_last_us(self) -> int:
        return self.t_us[-1]

    def at(self, name: str, t_s: float) -> float:
        """The column interpolated at t_s (holding before 0 and after the last row), as the simulator does."""
        col = self.columns[name]
        t_us = round(t_s * 1e6)
        i = bisect.bisect_right(self.t_us, t_us) - 1
        if i < 0:
            return col[0]
        if i >= len(col) - 1:
            return col[-1]
        t0, t1 = self.t_us[i], self.t_us[i + 1]
        return col[i] + (t_us - t0) / (t1 - t0) * (col[i + 1] - col[i])


def to_us(t_s: float) -> int:
    """Seconds -> whole µs, rounding half away from zero like C's llround."""
    return int(math.floor(abs(t_s) * 1e6 + 0.5)) * (1 if t_s >= 0 else -1)


def _num(tok: str) -> float | None:
    """A finite decimal number (as strtod reads it whole), else None."""
    if tok == "" or tok.strip() != tok or "_" in tok:
        return None
    try:
        v = float(tok)
    except ValueError:
        return None
    return v if math.isfinite(v) else None


def _fields(text: str) -> list[str]:
    return [f.strip(" \t") for f in text.split(",")]


def read(path: Path) -> Profile:
    """Read and check a profile file; ProfileError on the first problem."""
    try:
        data = path.read_bytes()
    except OSError as e:
        raise ProfileError(f"{path}: cannot open: {e.strerror or e}") from None
    prof = Profile(path)
    field_of: dict[str, int] = {}
    n_fields = 0
    header = False
    lines = data.split(b"\n")
    if lines and lines[-1] == b"":
        lines.pop()
    for n, raw in enumerate(lines, 1):
        where = f"{path}:{n}"
        if len(raw) > LINE_MAX + (1 if raw.endswith(b"\r") else 0):
            raise ProfileError(f"{where}: line longer than {LINE_MAX} characters")
        if raw.endswith(b"\r"):
            raw = raw[:-1]
        bad = next((c for c in raw if (c < 0x20 and c != 0x09) or c > 0x7E), None)
        if bad is not None:
            raise ProfileError(f"{where}: non-printable or non-ASCII character (byte 0x{bad:02X})")
        text = raw.decode("ascii")
        stripped = text.lstrip(" \t")
        if stripped == "" or stripped.startswith("#"):
            continue
        f = _fields(text)
        if not header:
            if f[0] != "t_s":
                raise ProfileError(f"{where}: header: the first column must be t_s (time in seconds), not '{f[0]}'")
            if len(f) < 2:
                raise ProfileError(f"{where}: header: no quantity after t_s ({_NAMES})")
            for i, name in enumerate(f[1:], 1):
                if name not in COLUMNS:
                    raise ProfileError(f"{where}: header: unknown column '{name}' ({_NAMES})")
                if name in field_of:
                    raise ProfileError(f"{where}: header: duplicate column '{name}'")
                field_of[name] = i
            prof.names = list(f[1:])
            prof.columns = {name: [] for name in prof.names}
            n_fields = len(f)
            header = True
            continue
        if len(f) != n_fields:
            raise ProfileError(f"{where}: {len(f)} fields, the header has {n_fields}")
        t = _num(f[0])
        if t is None:
            raise ProfileError(f"{where}: t_s '{f[0]}' is not a number")
        if not 0.0 <= t <= MAX_TIME_S:
            raise ProfileError(f"{where}: t_s {t:g} out of range [0, {MAX_TIME_S:g}]")
        t_us = to_us(t)
        if not prof.t_us and t_us != 0:
            raise ProfileError(f"{where}: the first row must be at t_s 0, not {t:g}")
        if prof.t_us and t_us <= prof.t_us[-1]:
            raise ProfileError(f"{where}: t_s {t:g} is not after the previous row's {prof.t_us[-1] * 1e-6:g} "
                               "(times must increase)")
        # in the C reader's order: the quantities by their fixed order, not the file's
        for name, (lo, hi) in COLUMNS.items():
            if name not in field_of:
                continue
            tok = f[field_of[name]]
            v = _num(tok)
            if v is None:
                raise ProfileError(f"{where}: {name} '{tok}' is not a number")
            if not lo <= v <= hi:
                raise ProfileError(f"{where}: {name} {v:g} out of range [{lo:g}, {hi:g}]")
            prof.columns[name].append(v)
        prof.t_us.append(t_us)
    if not header:
        raise ProfileError(f"{path}: no header line (t_s and at least one of {_NAMES})")
    if not prof.t_us:
        raise ProfileError(f"{path}: no data rows after the header")
    return prof
