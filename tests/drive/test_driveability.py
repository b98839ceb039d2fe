"""The twins of `make bench-driveability` differ only by what the test signals do.

canfdi-sil drives the start of the 11.5-minute drive (build/drive/wltc3_10min_s1.csv,
the scenario of tests/sil/scenarios/drive_wltc3_10min.scn, its seed and noise)
with the test signals allowed (`--test-signals on`) and suppressed (`off`).
Until the first burst the two runs must be the same bit for bit: the
deviation canfdi.driveability computes is exactly 0, and the bus logs are
byte-identical, so every deviation the bench reports is the test signals'
own. After the first burst (the throttle's key-on burst, about 13.5 s in)
the twins part, and the suppressed run never applies an excitation.
"""
from __future__ import annotations

import filecmp
import os
import re
import subprocess
from pathlib import Path

import pytest

from canfdi import REPO_ROOT
from canfdi import driveability as dv

SIL = Path(os.environ.get("CANFDI_SIL", REPO_ROOT / "build" / "bin" / "canfdi-sil"))
BASE = REPO_ROOT / "tests" / "sil" / "scenarios" / "drive_wltc3_10min.scn"
PROFILE = REPO_ROOT / "build" / "drive" / "wltc3_10min_s1.csv"
QUIET_S = 13.0  # the key-on burst needs the valve's reference above 10 deg: 13.46 s into this drive


def scenario(d: Path, duration_s: float) -> Path:
    """The drive's scenario cut to duration_s, its profile by absolute path."""
    lines = []
    for ln in BASE.read_text().splitlines():
        if ln.startswith("duration"):
            ln = f"duration {duration_s:g}"
        elif ln.startswith("profile"):
            ln = f"profile {PROFILE}"
        elif ln.startswith("expect"):
            continue
        lines.append(ln)
    lines.append(f"expect {duration_s:g} no_dtc")
    p = d / f"drive_{duration_s:g}s.scn"
    p.write_text("\n".join(lines) + "\n")
    return p


def twins(d: Path, duration_s: float) -> dict:
    if not SIL.is_file():
        pytest.fail(f"{SIL} not built: make build/bin/canfdi-sil")
    if not PROFILE.is_file():
        pytest.fail(f"{PROFILE} missing: make drive-profiles")
    scn = scenario(d, duration_s)
    out = {}
    for mode in ("on", "off"):
        resp, log = d / f"{mode}.bin", d / f"{mode}.log"
        p = subprocess.run([str(SIL), "-q", "-s", str(scn), "--test-signals", mode, "--responses", str(resp),
                            "-l", str(log)], capture_output=True, text=True, timeout=300, cwd=REPO_ROOT)
        assert p.returncode == 0, p.stdout + p.stderr
        out[mode] = (dv.read(resp), log)
    return out


def test_no_burst_no_deviation(tmp_path: Path) -> None:
    t = twins(tmp_path, QUIET_S)
    (on, log_on), (off, log_off) = t["on"], t["off"]
    assert on.size == off.size == round(QUIET_S * 1000)
    f = dv.compare(on, off)
    assert f["first_burst_s"] is None, "a burst started: shorten QUIET_S"
    assert f["first_difference_s"] is None
    for q in ("speed", "angle"):
        assert f[q]["rms"] == 0.0 and f[q]["max_abs"] == 0.0
        assert f[q]["burst_share"] == 0.0 and f[q]["applied_share"] == 0.0
    assert filecmp.cmp(log_on, log_off, shallow=False), "the bus logs of the twins differ"


def test_twins_part_at_the_first_burst(tmp_path: Path) -> None:
    t = twins(tmp_path, 20.0)
    on, off = t["on"][0], t["off"][0]
    f = dv.compare(on, off)
    assert f["first_burst_s"] is not None and f["first_burst_s"] >= QUIET_S
    assert f["identical_until_first_burst"]
    assert f["first_difference_s"] is not None and f["first_difference_s"] >= f["first_burst_s"]
    assert f["angle"]["max_abs"] > 0.5                        # the +-3 deg sine moved the valve
    assert f["angle"]["burst_share"] > 0.0
    # the suppressed twin runs the same schedule but applies nothing
    flags = off["flags"]
    assert not (flags & (dv.DCM_APPLIED | dv.THR_APPLIED)).any()
    assert (flags & dv.THR_BURST).any()


def test_unknown_mode_is_a_usage_error(tmp_path: Path) -> None:
    if not SIL.is_file():
        pytest.fail(f"{SIL} not built: make build/bin/canfdi-sil")
    p = subprocess.run([str(SIL), "-q", "-s", str(scenario(tmp_path, 1.0)), "--test-signals", "maybe"],
                       capture_output=True, text=True, timeout=60, cwd=REPO_ROOT)
    assert p.returncode == 2 and re.search(r"--test-signals wants on, off or always", p.stderr)
