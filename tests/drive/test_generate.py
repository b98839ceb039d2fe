"""The drive-profile generator (tools/drive, docs/driving.md): the cycle from the
wltp package, the mapping, reproducibility per seed, the plants' limits, the
driving the issue asks for (tip-ins, tip-outs, reversals, stops, cold start,
supply sag), and the profile file it writes."""
from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from canfdi import REPO_ROOT
from canfdi.profile_csv import read
from drive import wltc
from drive.generate import (COLUMNS, Bus48, Drive, Plan, ProfileError, Throttle, Vehicle, check, generate, main,
                            reference_share, road_force, speed_scale, write_csv)

SHORT = REPO_ROOT / "build" / "drive" / "wltc3_10min_s1.csv"
LIMP_HOME_DEG = 6.5


@pytest.fixture(scope="module")
def short_plan_profile():
    return generate(Plan(duration_s=600.0, seed=1, trips=(1, 4, 5, 8), manoeuvre_prob=1.0))


def test_cycle_comes_from_the_package_and_checks_out() -> None:
    import wltp.cycles.class3 as src
    c = wltc.trace()
    assert c.source.startswith("wltp ")
    assert Path(src.__file__).resolve().parts[-3:] == ("wltp", "cycles", "class3.py")
    assert len(c.v_m_s) == 1801 and c.duration_s == 1800.0
    assert max(c.v_m_s) * 3.6 == pytest.approx(131.3)
    assert sum(c.v_m_s) * 3.6 == pytest.approx(83758.6, abs=0.05)     # the package's own checksum
    trips = wltc.trips(c)
    assert len(trips) == 8
    assert all(c.v_m_s[t.start_s] == 0.0 and c.v_m_s[t.end_s] == 0.0 for t in trips)
    assert all((c.v_m_s[t.start_s + 1:t.end_s] > 0.0).all() for t in trips)
    assert max(trips[-1].speeds(c)) * 3.6 == pytest.approx(131.3)     # the extra-high phase is the last


def test_same_seed_same_file_other_seed_other_drive(tmp_path: Path) -> None:
    plan = Plan(duration_s=400.0, seed=7, trips=(1, 2), manoeuvre_prob=0.5)
    a, b = tmp_path / "a.csv", tmp_path / "b.csv"
    write_csv(generate(plan), a)
    write_csv(generate(plan), b)
    assert a.read_bytes() == b.read_bytes()
    c = tmp_path / "c.csv"
    write_csv(generate(Plan(duration_s=400.0, seed=8, trips=(1, 2), manoeuvre_prob=0.5)), c)
    assert c.read_bytes() != a.read_bytes()


def test_mapping_formulas(short_plan_profile) -> None:
    p = short_plan_profile
    veh, drv = Vehicle(), Drive()
    k_w = p.info["mapping"]["speed_rad_s_per_m_s"]
    k_t = p.info["mapping"]["load_Nm_per_N"]
    # speed: w = k v; load: M = k_T F, F = m_eff a + f0 tanh(v / v0) + f1 v + f2 v|v| + m g sin(atan(grade))
    np.testing.assert_allclose(p.speed_rad_s, p.v_m_s * k_w, rtol=1e-3, atol=1e-9)
    np.testing.assert_allclose(p.load_Nm, p.force_N * k_t, rtol=1e-12, atol=1e-12)
    # moving, and the brakes' handover after the last stop over (5 s = 16 time constants)
    last_stop = np.maximum.accumulate(np.where(np.abs(p.v_m_s) < 1e-6, p.t_s, -np.inf))
    moving = (np.abs(p.v_m_s) > 1.0) & (p.t_s - last_stop > 16 * veh.brake_handover_s)
    assert moving.sum() > 0.5 * len(p.t_s)
    f = road_force(veh, p.v_m_s, p.a_m_s2, p.grade)
    np.testing.assert_allclose(p.force_N[moving], f[moving], rtol=1e-6, atol=1e-6)
    assert np.abs(p.grade).max() <= veh.grade_max + 1e-12
    # the load is scaled so the largest force is the drive's rated torque
    assert np.abs(p.load_Nm).max() == pytest.approx(drv.torque_rated_Nm, rel=1e-9) or \
        np.abs(p.force_N).max() < p.info["mapping"]["force_peak_N"]
    assert drv.torque_rated_Nm == pytest.approx(0.6 * 0.33 * 20.0)


def test_speed_scale_is_the_largest_the_supply_allows() -> None:
    """At the returned scale the reference drive needs exactly the headroom share of the bus
    somewhere; 1 % faster it would need more."""
    drv, veh, bus = Drive(), Vehicle(), Bus48()
    c = wltc.trace()
    k, f_peak, u_low = speed_scale(drv, veh, bus, c)
    assert reference_share(drv, veh, bus, c, k) == pytest.approx(drv.voltage_headroom, abs=1e-6)
    assert reference_share(drv, veh, bus, c, 1.01 * k) > drv.voltage_headroom
    assert 40.0 < u_low < bus.u_oc_cold[0]
    top = k * max(c.v_m_s) * drv.speed_scale_max
    assert 50.0 < top < bus.u_oc_cold[0] / drv.psi_Vs        # below the no-load speed of the weakest battery
    assert f_peak > Vehicle().mass_kg * 1.5                   # the cycle's hardest acceleration, up the grade


def test_profile_respects_the_plants(short_plan_profile) -> None:
    p, drv = short_plan_profile, Drive()
    check(p, drv)                                    # raises if not
    assert np.abs(p.i_motor_A).max() <= drv.i_max_A * drv.torque_share + 1.0
    assert (np.abs(p.u_needed_V) / p.dcm_supply_V).max() <= drv.voltage_headroom
    assert 0.0 <= p.angle_deg.min() and p.angle_deg.max() <= 90.0
    assert np.abs(p.speed_rad_s).max() <= 400.0


def test_check_refuses_what_the_plants_cannot_follow(short_plan_profile) -> None:
    p = short_plan_profile
    k = int(np.argmax(p.speed_rad_s))
    saved = p.dcm_supply_V[k]
    p.dcm_supply_V[k] = 20.0            # a supply the motor's speed there needs more than 85 % of
    try:
        with pytest.raises(ProfileError, match="the motor needs"):
            check(p, Drive())
    finally:
        p.dcm_supply_V[k] = saved
    saved = p.load_Nm[k]
    p.load_Nm[k] = 4.5
    try:
        with pytest.raises(ProfileError, match="beyond the rating"):
            check(p, Drive())
    finally:
        p.load_Nm[k] = saved


def test_bad_plans_are_refused() -> None:
    with pytest.raises(ProfileError, match="trip 9"):
        generate(Plan(duration_s=100.0, trips=(9,)))
    with pytest.raises(ProfileError, match="duration"):
        generate(Plan(duration_s=0.0))
    with pytest.raises(ProfileError, match="manoeuvre probability"):
        generate(Plan(duration_s=100.0, manoeuvre_prob=1.5))


def _steps(prof, column: str, min_jump: float) -> list[tuple[float, float, float]]:
    """(time, before, after) of each jump of more than min_jump between rows 1 ms apart."""
    x, t = prof.columns[column], prof.t_us
    return [(t[i] * 1e-6, x[i - 1], x[i]) for i in range(1, len(t))
            if t[i] - t[i - 1] <= 1000 and abs(x[i] - x[i - 1]) > min_jump]


def test_short_profile_file_has_the_driving_asked_for() -> None:
    """The 10-minute profile `make drive-profiles` writes, read back as the simulator reads it:
    the counts come from the file, not from the generator's summary."""
    if not SHORT.is_file():
        pytest.fail(f"{SHORT} missing: make drive-profiles")
    prof = read(SHORT)
    assert prof.names == list(COLUMNS)
    assert prof.t_last_us >= 690_000_000
    thr = Throttle()
    steps = _steps(prof, "angle_deg", 20.0)
    tip_ins = [s for s in steps if s[2] == thr.wot_deg]
    tip_outs = [s for s in steps if s[2] == thr.closed_deg]
    assert len(tip_ins) >= 3, steps
    assert len(tip_outs) >= 2 and any(s[1] == thr.wot_deg for s in tip_outs), steps   # wide open -> closed
    w = np.array(prof.columns["speed_rad_s"])
    t = np.array(prof.t_us) * 1e-6
    moving = np.flatnonzero(np.abs(w) > 1e-6)
    reversals = [(t[i], t[j]) for i, j in zip(moving[:-1], moving[1:]) if np.sign(w[i]) != np.sign(w[j])]
    through_zero = [r for r in reversals if r[1] - r[0] <= 0.15]
    assert len(reversals) >= 4 and len(through_zero) >= 1, reversals
    standstill = np.abs(w) < 1e-6
    starts = np.flatnonzero(np.diff(standstill.astype(int)) == 1)
    assert len(starts) >= 6                                  # stops
    assert w.max() > 0.8 * Drive().psi_Vs ** -1 * 40.0 * 0.85 and w.min() < -3.0
    load = np.array(prof.columns["load_Nm"])
    assert load.max() > 2.0 and load.min() < -2.0            # motoring and braking
    angle = np.array(prof.columns["angle_deg"])
    idle = angle[standstill]
    assert idle.min() < LIMP_HOME_DEG < idle.max()          # cold idle above limp-home, warm idle below
    u12 = np.array(prof.columns["thr_supply_V"])
    u48 = np.array(prof.columns["dcm_supply_V"])
    assert u12.min() < 9.0 and u12.max() > 14.0              # cranking dip, charging
    assert u48.min() < 46.0 and u48.max() > 51.0             # weak battery and sag, charging
    assert u12[0] < 12.5 and u48[0] < 46.5                   # cold start: engine off, weak battery


def test_cli_writes_profile_and_summary(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "p.csv"
    assert main(["--duration", "200", "--seed", "3", "--trips", "1", "--manoeuvres", "1",
                 "--columns", "speed_rad_s,load_Nm", "-o", str(out)]) == 0
    prof = read(out)
    assert prof.names == ["speed_rad_s", "load_Nm"]
    s = json.loads(out.with_suffix(".json").read_text())
    assert s["seed"] == 3 and s["counts"]["manoeuvres"] >= 1
    assert math.isclose(s["mapping"]["torque_rated_Nm"], 3.96)
    assert "canfdi-drive-profile:" in capsys.readouterr().out
    with pytest.raises(SystemExit):
        main(["--trips", "x", "-o", str(out)])
    with pytest.raises(SystemExit):
        main(["--columns", "rpm", "-o", str(out)])
    assert main(["--trips", "0", "-o", str(out)]) == 2
    assert main(["--wot", "95", "-o", str(out)]) == 2


def test_wot_and_angle_rate_options(tmp_path: Path) -> None:
    """--wot moves a floored pedal below the end stop; --angle-rate turns the steps into ramps."""
    base = ["--duration", "300", "--seed", "2", "--trips", "1", "-o"]
    assert main(base + [str(tmp_path / "a.csv"), "--wot", "85"]) == 0
    a = read(tmp_path / "a.csv")
    assert max(a.columns["angle_deg"]) == 85.0 and _steps(a, "angle_deg", 20.0)
    assert main(base + [str(tmp_path / "b.csv"), "--angle-rate", "300"]) == 0
    b = read(tmp_path / "b.csv")
    assert not _steps(b, "angle_deg", 1.0) and max(b.columns["angle_deg"]) == 90.0
    ang, t = b.columns["angle_deg"], b.t_us
    rate = max(abs(ang[i] - ang[i - 1]) / ((t[i] - t[i - 1]) * 1e-6) for i in range(1, len(t)))
    assert rate <= 300.0 + 1e-6
