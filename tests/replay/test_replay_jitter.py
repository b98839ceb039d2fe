"""canfdi-replay --clock timestamps on SIL recordings re-stamped as a real logger stamps them
(conftest.jitter_log: a seeded jitter on every frame's time stamp, the logger's clock drifting
against the sensor nodes'). The step grid follows the sensor frames, so each DcmSensor and
ThrSensor frame still falls into a step of its own: the replay is the recorded run frame for frame,
names the recorded ECU's codes, and judges the models as on the recording's own time stamps."""
from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from conftest import cut_log, jitter_log, run_replay

#: Jitter on every frame (uniform, +-) and the logger clock's drift used below.
JITTER_US = 300
PPM = 100
STEP_S = 1e-3
#: Half a step: a step's time is where its sensor frames are expected, within half a step of them.
HALF_STEP_S = 500e-6
#: The monitors of the models (what a late or early sensor frame holds: "re-arming").
MODEL_MONITORS = ("dcm_models", "dcm_cmd", "thr_models", "thr_tracking")

#: Fault recordings, abrupt and incipient, DC motor and throttle, with the drift each is stamped with
#: (a fast and a slow logger clock).
FAULTS = [
    ("dcm_ia_offset", PPM),
    ("dcm_flux_down", -PPM),
    ("tps1_open", PPM),
    ("thr_friction_up", -PPM),
    ("dcm_friction_up_incipient", PPM),
    ("dcm_speed_sensor_gain_incipient", -PPM),
    ("thr_spring_weak_incipient", PPM),
]


def log_of(sil_logs: dict[Path, Path], stem: str) -> Path:
    return next(v for k, v in sil_logs.items() if k.stem == stem)


def replay_ts(log: Path, tmp: Path) -> dict[str, Any]:
    rc, doc, _, err = run_replay(["--clock", "timestamps", str(log)], tmp)
    assert doc is not None, err
    assert doc["exit_status"] == rc
    return doc


def model_gaps(doc: dict[str, Any]) -> dict[str, tuple[float, list[str]]]:
    """Per model monitor: seconds not judged and the reasons."""
    return {n["monitor"]: (n["seconds"], sorted({s["why"] for s in n["spans"]}))
            for n in doc["not_judged"] if n["monitor"] in MODEL_MONITORS}


@pytest.mark.parametrize("stem,ppm", FAULTS)
def test_jittered_fault_log_gives_the_recorded_codes(stem: str, ppm: int, sil_logs: dict[Path, Path],
                                                     tmp_path: Path) -> None:
    """+-300 us of jitter on every frame and a logger clock 100 ppm fast or slow: the replay is still the
    recorded run frame for frame, and names the codes of the un-jittered recording. Its times are the
    logger's: a code comes at the un-jittered time t stretched by the drift (|ppm| t), moved by the
    first frame's jitter (the log's time origin, up to 300 us) and by at most half a step (where the
    step's sensor frames are expected); against the recorded ECU's EcuDtc frame in the same log (its
    own stamp jittered by up to 300 us), no drift term."""
    log = log_of(sil_logs, stem)
    plain = replay_ts(log, tmp_path)
    jit = replay_ts(jitter_log(log, tmp_path / "jit.log", JITTER_US, ppm, seed=len(stem)), tmp_path)
    want = {f["code"]: f["first_failed_s"] for f in plain["dtcs"]}
    got = {f["code"]: f["first_failed_s"] for f in jit["dtcs"]}
    assert want, f"{stem}: the recording has no code"
    assert set(got) == set(want), f"{stem}: jittered {got}, plain {want}"
    for f in jit["dtcs"]:
        t = want[f["code"]]
        tol = abs(ppm) * 1e-6 * t + JITTER_US * 1e-6 + HALF_STEP_S
        assert f["first_failed_s"] == pytest.approx(t, abs=tol), f"{stem} {f['code']}"
        assert f["first_failed_s"] == pytest.approx(f["recorded_ecu_first_failed_s"],
                                                    abs=JITTER_US * 1e-6 + HALF_STEP_S), f"{stem} {f['code']}"
    lg = jit["logs"][0]
    ecu = lg["recorded_ecu"]
    assert lg["clock"] == "timestamps" and lg["start"] == "power-up"
    assert ecu["frames"] == plain["logs"][0]["recorded_ecu"]["frames"]
    assert ecu["identical"] == ecu["frames"] and ecu["differing"] == 0 and ecu["replay_only"] == 0, ecu
    assert jit["recorded_ecu_only"] == []


@pytest.mark.parametrize("stem", ["nominal_load_steps", "nominal_setpoints"])
def test_jittered_fault_free_log_gives_no_code(stem: str, sil_logs: dict[Path, Path], tmp_path: Path) -> None:
    log = jitter_log(log_of(sil_logs, stem), tmp_path / "jit.log", JITTER_US, PPM, seed=7)
    doc = replay_ts(log, tmp_path)
    assert doc["dtcs"] == [] and doc["exit_status"] == 0
    assert doc["logs"][0]["recorded_ecu"]["differing"] == 0


def test_jittered_log_keeps_the_models_judged(sil_logs: dict[Path, Path], tmp_path: Path) -> None:
    """No sensor frame of the jittered log is taken as late or early: from power-up the models wait
    only for the DC motor's estimates to converge, as on the recording's own time stamps (never
    "re-arming"); cut mid-drive, they are judged from the end of the settling time to the end of the
    log (the tracking monitor never is mid-drive: the recorded ECU's excitation phase is not in the
    log)."""
    log = log_of(sil_logs, "nominal_load_steps")  # 20 s
    jit = jitter_log(log, tmp_path / "jit.log", JITTER_US, PPM, seed=3)
    plain_gaps = model_gaps(replay_ts(log, tmp_path))
    jit_gaps = model_gaps(replay_ts(jit, tmp_path))
    assert set(jit_gaps) == set(plain_gaps) == {"dcm_models", "dcm_cmd"}
    for m, (secs, whys) in jit_gaps.items():
        assert whys == plain_gaps[m][1] and all(("not converged" in w) or ("not checked yet" in w) for w in whys), \
            (m, whys)
        assert secs == pytest.approx(plain_gaps[m][0], abs=0.002), m

    cut = cut_log(log, tmp_path / "cut.log", 0.4)
    doc = replay_ts(jitter_log(cut, tmp_path / "cutjit.log", JITTER_US, -PPM, seed=4), tmp_path)
    lg = doc["logs"][0]
    assert lg["start"] == "mid-drive"
    settled, end = lg["settled_from_s"], lg["last_s"]
    assert end - settled > 14.0
    for n in doc["not_judged"]:
        if n["monitor"] not in MODEL_MONITORS or n["monitor"] == "thr_tracking":
            continue
        late = [s for s in n["spans"] if s["to_s"] > settled + STEP_S]  # the first step from then on
        assert late == [], f"{n['monitor']} not judged after the settling time: {late}"
        assert not any("re-arming" in s["why"] for s in n["spans"])


def test_grid_follows_the_drift_only(sil_logs: dict[Path, Path], tmp_path: Path) -> None:
    """The step grid moves when the logger's clock drifts against the sensor nodes' (each move by
    GRID_MOVE_US = 100 us or more of the accumulated drift), so the replay runs as many steps as the
    un-jittered recording: the steps are the sensor nodes' 1 ms, not the logger's. It does not move on
    the recording's own time stamps nor on a small jitter without drift."""
    log = log_of(sil_logs, "dcm_friction_up_incipient")  # 8 s
    plain = replay_ts(log, tmp_path)
    assert plain["logs"][0]["grid_moves"] == 0
    small = replay_ts(jitter_log(log, tmp_path / "small.log", 10, 0, seed=5), tmp_path)
    assert small["logs"][0]["grid_moves"] == 0
    assert small["logs"][0]["steps"] == plain["logs"][0]["steps"]
    for ppm in (1000, -1000):
        doc = replay_ts(jitter_log(log, tmp_path / "drift.log", 50, ppm, seed=6), tmp_path)
        lg = doc["logs"][0]
        drift_us = abs(ppm) * 1e-6 * plain["logs"][0]["last_s"] * 1e6  # 8 ms
        assert drift_us / 500 <= lg["grid_moves"] <= drift_us / 100 + 2, (ppm, lg["grid_moves"])
        assert lg["steps"] == plain["logs"][0]["steps"], ppm
        assert lg["recorded_ecu"]["differing"] == 0, ppm
        assert [f["code"] for f in doc["dtcs"]] == [f["code"] for f in plain["dtcs"]]
