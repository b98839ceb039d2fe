"""The plants follow the 10-minute drive profile (build/drive/wltc3_10min_s1.csv,
`make drive-profiles`): canfdi-sim offline, its stand-in controller closing the
loops, the profile's supplies applied to the bridges. What the generator
promises (docs/driving.md: setpoints within what the plants can follow) is
checked on the simulated plants: the motor keeps to the speed profile in both
directions and through zero, the valve follows the angle and reaches wide
open at its physical rate after each tip-in, and the supply sensors read the
profile's supplies."""
from __future__ import annotations

import csv
import os
import subprocess
from pathlib import Path

import numpy as np
import pytest

from canfdi import REPO_ROOT
from canfdi.profile_csv import read

SIM = Path(os.environ.get("CANFDI_SIM", REPO_ROOT / "build" / "bin" / "canfdi-sim"))
PROFILE = REPO_ROOT / "build" / "drive" / "wltc3_10min_s1.csv"
DURATION_S = 690.0
DT_TRACE = 0.01


@pytest.fixture(scope="module")
def run(tmp_path_factory: pytest.TempPathFactory):
    if not SIM.is_file():
        pytest.fail(f"{SIM} not built: make build/bin/canfdi-sim")
    if not PROFILE.is_file():
        pytest.fail(f"{PROFILE} missing: make drive-profiles")
    d = tmp_path_factory.mktemp("drive")
    scn = d / "drive.scn"
    scn.write_text(f"duration {DURATION_S:g}\nprofile {PROFILE}\n")
    trace = d / "trace.csv"
    subprocess.run([str(SIM), "-q", "-s", str(scn), "-o", str(trace), "-D", str(round(DT_TRACE * 1000))],
                   check=True, timeout=600)
    with trace.open(newline="") as f:
        rows = list(csv.DictReader(f))
    cols = {k: np.array([float(r[k]) for r in rows]) for k in rows[0] if k != "faults"}
    return read(PROFILE), cols


def test_motor_follows_the_speed_profile(run) -> None:
    prof, c = run
    t, sp, w = c["t_s"], c["sp_speed_rad_s"], c["dcm_speed_rad_s"]
    want = np.array([prof.at("speed_rad_s", x) for x in t])
    np.testing.assert_allclose(sp, want, atol=1e-3)          # the setpoint is the profile
    err = np.abs(w - sp)
    assert err.max() < 3.0, f"speed error {err.max():.2f} rad/s at {t[err.argmax()]:.2f} s"
    assert np.sqrt(np.mean(err**2)) < 0.5
    assert w.min() < -3.0 and w.max() > 60.0                  # both directions, motorway speed
    load = c["load_Nm"]
    assert ((w > 1.0) & (load < -1.0)).any() and ((w < -1.0) & (load > 0.2)).any()   # braking both ways


def test_valve_follows_the_angle_profile(run) -> None:
    prof, c = run
    t, sa, a = c["t_s"], c["sp_angle_deg"], c["thr_angle_deg"]
    steps = [prof.t_us[i] * 1e-6 for i in range(1, len(prof.t_us))
             if prof.t_us[i] - prof.t_us[i - 1] <= 1000
             and abs(prof.columns["angle_deg"][i] - prof.columns["angle_deg"][i - 1]) > 1.0]
    assert len(steps) >= 5
    settling = np.zeros(len(t), dtype=bool)
    for s in steps:
        settling |= (t >= s - 0.002) & (t < s + 0.3)
        k = int(np.searchsorted(t, s + 0.002))
        target = sa[k]
        reach = next((t[i] - s for i in range(k, len(t)) if abs(a[i] - target) < 2.0), None)
        assert reach is not None and reach < 0.15, f"step to {target:g} deg at {s:.3f} s: reached after {reach}"
    err = np.abs(a - sa)[~settling]
    assert err.max() < 3.0, f"angle error {err.max():.2f} deg"
    assert a.max() > 89.0 and a[t > 200].min() < 3.0          # wide open and closed


def test_supply_sensors_read_the_profile(run) -> None:
    prof, c = run
    t = c["t_s"][1:]
    # the supply in force over the step before the sample
    for col, name, lsb in (("m_dcm_supply_V", "dcm_supply_V", 80.0 / 4096), ("m_thr_supply_V", "thr_supply_V", 16.0 / 4096)):
        want = np.array([prof.at(name, x - 0.001) for x in t])
        err = np.abs(c[col][1:] - want)
        assert err.max() <= lsb, f"{name}: {err.max():.4f} V off at {t[err.argmax()]:.3f} s"
    assert c["m_thr_supply_V"].min() < 9.0 and c["m_dcm_supply_V"].max() > 51.0
