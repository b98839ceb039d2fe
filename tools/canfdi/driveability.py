"""What the ECU's test signals cost the driver: twin SIL runs of one drive.

`canfdi-sil --responses FILE` writes one 17-byte record per 1 ms step (host
byte order): the plant's speed (double, rad/s), the valve angle (double,
rad) and a flag byte (bit 0/1: the DC motor's/throttle's test-signal
scheduler ON, i.e. a burst; bit 2/3: its excitation generator gated on;
bit 4/5: its setpoint inside the product's enabling window). Two runs of the same
scenario with the same seed, one with the test signals allowed
(`--test-signals on`, the product) and one with them suppressed
(`--test-signals off`), see the same setpoints and the same plant noise;
everything that differs between them is caused by the test signals.
`compare` reduces a pair to the driveability figures (docs/driving.md,
"What the test signals cost the driver").
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np

RECORD = np.dtype([("w", "<f8"), ("th", "<f8"), ("flags", "u1")])
STEP_S = 1e-3
DCM_BURST, THR_BURST, DCM_APPLIED, THR_APPLIED, DCM_WINDOW, THR_WINDOW = (1 << b for b in range(6))


def read(path: str | Path) -> np.ndarray:
    """The records of one --responses file."""
    return np.fromfile(path, dtype=RECORD)


def _rms(x: np.ndarray) -> float:
    return float(math.sqrt(float(np.mean(x * x)))) if x.size else 0.0


def _share(flags: np.ndarray, bit: int) -> float:
    return float(np.mean((flags & bit) != 0)) if flags.size else 0.0


def _sums(d: np.ndarray, on: np.ndarray) -> dict:
    """Sums that let several drives be pooled (sum of squares, counts)."""
    return {"n": int(d.size), "sq": float(np.sum(d * d)), "n_on": int(np.sum(on)), "sq_on": float(np.sum(d[on] ** 2))}


def compare(with_: np.ndarray, without: np.ndarray) -> dict:
    """Driveability figures of a twin pair (with the test signals, without).

    speed: deviation w_with - w_without in rad/s; angle: in degrees. RMS and
    largest |deviation| over the whole drive, the RMS inside and outside the
    with-run's bursts; the first step at which the twins differ, and whether
    that is at or after the first burst (the twins are bit-identical until a
    test signal acts). Shares are fractions of the drive's steps.
    """
    if with_.size != without.size:
        raise ValueError(f"twins of different length: {with_.size} and {without.size} steps")
    fl = with_["flags"]
    out: dict = {"steps": int(with_.size), "duration_s": with_.size * STEP_S}
    first_burst = np.flatnonzero(fl & (DCM_BURST | THR_BURST))
    first_burst_k = int(first_burst[0]) if first_burst.size else None
    differ = np.flatnonzero((with_["w"] != without["w"]) | (with_["th"] != without["th"]))
    first_diff_k = int(differ[0]) if differ.size else None
    out["first_burst_s"] = None if first_burst_k is None else first_burst_k * STEP_S
    out["first_difference_s"] = None if first_diff_k is None else first_diff_k * STEP_S
    out["identical_until_first_burst"] = first_diff_k is None or (
        first_burst_k is not None and first_diff_k >= first_burst_k)
    for name, d, burst, applied, window in (
        ("speed", with_["w"] - without["w"], DCM_BURST, DCM_APPLIED, DCM_WINDOW),
        ("angle", np.degrees(with_["th"] - without["th"]), THR_BURST, THR_APPLIED, THR_WINDOW),
    ):
        on = (fl & burst) != 0
        k_max = int(np.argmax(np.abs(d))) if d.size else 0
        out[name] = {
            "unit": "rad/s" if name == "speed" else "deg",
            "rms": _rms(d),
            "max_abs": float(abs(d[k_max])) if d.size else 0.0,
            "max_at_s": k_max * STEP_S,
            "rms_in_bursts": _rms(d[on]),
            "rms_outside_bursts": _rms(d[~on]),
            "burst_share": _share(fl, burst),
            "applied_share": _share(fl, applied),
            "window_share": _share(fl, window),
            "bursts": int(np.sum(np.diff(on.astype(np.int8), prepend=0) == 1)),
            "sums": _sums(d, on),
        }
    return out


def pool(pairs: list[dict]) -> dict:
    """The figures of several drives as one drive cycle (time-weighted)."""
    res: dict = {"duration_s": sum(p["duration_s"] for p in pairs)}
    for name in ("speed", "angle"):
        n = sum(p[name]["sums"]["n"] for p in pairs)
        sq = sum(p[name]["sums"]["sq"] for p in pairs)
        n_on = sum(p[name]["sums"]["n_on"] for p in pairs)
        sq_on = sum(p[name]["sums"]["sq_on"] for p in pairs)
        res[name] = {
            "unit": pairs[0][name]["unit"] if pairs else "",
            "rms": math.sqrt(sq / n) if n else 0.0,
            "max_abs": max((p[name]["max_abs"] for p in pairs), default=0.0),
            "rms_in_bursts": math.sqrt(sq_on / n_on) if n_on else 0.0,
            "burst_share": n_on / n if n else 0.0,
            "applied_share": (sum(p[name]["applied_share"] * p[name]["sums"]["n"] for p in pairs) / n) if n else 0.0,
            "window_share": (sum(p[name]["window_share"] * p[name]["sums"]["n"] for p in pairs) / n) if n else 0.0,
            "bursts": sum(p[name]["bursts"] for p in pairs),
        }
    return res
