"""The WLTC class 3 speed trace (UNECE GTR 15), read from the wltp package.

The trace is never typed into this repository: ``trace()`` takes it from the
data the ``wltp`` package ships (``wltp.cycles.class3``, its class 3b cycle:
vehicles with a maximum speed of 120 km/h or more; 1801 samples at 1 Hz,
0..1800 s, 131.3 km/h at most) and checks it against the checksum the package
stores with it (the sum of all speeds) and against the phase boundaries, so a
changed or damaged package is refused rather than silently driven.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

KMH = 1.0 / 3.6


class CycleError(RuntimeError):
    """The package's cycle data are not the WLTC class 3b trace this code expects."""


@dataclass(frozen=True)
class Cycle:
    name: str
    source: str                  # package and version the trace was read from
    v_m_s: np.ndarray            # speed at 1 Hz, t = 0, 1, ... s
    phases: list[tuple[int, int]]

    @property
    def duration_s(self) -> float:
        return float(len(self.v_m_s) - 1)


@dataclass(frozen=True)
class Trip:
    """A micro-trip: from the last standstill second before the vehicle moves
    to the first standstill second after it (speed 0 at both ends)."""
    index: int                   # 1-based, in cycle order
    start_s: int
    end_s: int
    stop_before_s: int           # standstill seconds before it in the cycle

    def speeds(self, c: Cycle) -> np.ndarray:
        return c.v_m_s[self.start_s:self.end_s + 1]


def trace() -> Cycle:
    """The WLTC class 3b trace from the installed wltp package, checked."""
    try:
        import wltp
        from wltp.cycles import class3
    except ImportError as e:  # pragma: no cover - make deps installs it
        raise CycleError(f"the wltp package is not installed ({e}); run make deps") from None
    data = class3.class_data_b()
    v_kmh = np.asarray(data["cycle"], dtype=float)
    if abs(float(v_kmh.sum()) - float(data["checksum"])) > 0.05:
        raise CycleError(f"wltp {wltp.__version__}: class 3b speed sum {v_kmh.sum():.1f} differs from its checksum "
                         f"{data['checksum']}")
    phases = [(int(a), int(b)) for a, b in data["parts"]]
    if len(v_kmh) != phases[-1][1] + 1 or phases[0][0] != 0:
        raise CycleError(f"wltp {wltp.__version__}: class 3b trace of {len(v_kmh)} samples does not match its "
                         f"phases {phases}")
    if v_kmh[0] != 0.0 or v_kmh[-1] != 0.0 or (v_kmh < 0.0).any():
        raise CycleError(f"wltp {wltp.__version__}: class 3b trace must start and end at standstill")
    return Cycle("WLTC class 3b (UNECE GTR 15)", f"wltp {wltp.__version__}", v_kmh * KMH, phases)


def trips(c: Cycle) -> list[Trip]:
    """The micro-trips of the cycle, in order."""
    v = c.v_m_s
    out: list[Trip] = []
    i, last_end = 0, 0
    while i < len(v):
        if v[i] > 0.0:
            j = i
            while j < len(v) and v[j] > 0.0:
                j += 1
            start, end = i - 1, min(j, len(v) - 1)
            out.append(Trip(len(out) + 1, start, end, start - last_end))
            last_end, i = end, j
        else:
            i += 1
    return out
