"""The SIL scenario files on the HIL bench (lockstep): each passes its expect
lines there too, and for the shared ones the ECU's frames are bit-identical
to SIL's and the trouble codes come at the same simulated times."""
from __future__ import annotations

import subprocess
import sys

import pytest

from hilutil import ROOT, ecu_stream, read_frames, run_scenario, sil_log

# fault-free; a sensor fault on each plant; a parametric fault; a lost sensor
# frame stream; bridge switchover; both throttle sensors lost (limp-home);
# fault-free with speed, load, angle and both supplies from a profile file
SCENARIOS = ["nominal_setpoints", "tps1_open", "dcm_ia_offset", "dcm_ra_up", "dcm_timeout",
             "bridge_a_dead", "tps_both_lost", "supply_profile"]
# run in SIL and HIL and compared frame by frame
SHARED = ["tps1_open", "dcm_ra_up", "bridge_a_dead", "tps_both_lost", "supply_profile"]
# of those, the ones with trouble codes to time
SHARED_FAULTY = [n for n in SHARED if n != "supply_profile"]


@pytest.mark.parametrize("name", SCENARIOS)
def test_scenario_passes_on_the_bus(name: str) -> None:
    r = run_scenario(name)
    assert r.result, f"{name}: no result written (exit {r.rc})"
    assert r.result["errors"] == [], r.result["errors"]
    failed = [e for e in r.result["expectations"] + r.result["unexpected"] if not e.get("ok")]
    assert failed == [], failed
    assert r.rc == 0


def test_fault_free_run_has_no_trouble_code() -> None:
    r = run_scenario("nominal_setpoints")
    assert r.result["codes"] == {}, r.result["codes"]


@pytest.mark.parametrize("name", SHARED)
def test_sil_and_hil_give_the_same_ecu_frames(name: str) -> None:
    """Lockstep on vcan and SIL in one process: the same ECU frames in the
    same order, byte for byte (so the same codes at the same times)."""
    hil = ecu_stream(run_scenario(name).log)
    sil = ecu_stream(sil_log(name))
    assert len(hil) == len(sil), f"{name}: {len(hil)} ECU frames on the bus, {len(sil)} in SIL"
    first = next((i for i, (a, b) in enumerate(zip(hil, sil)) if a != b), None)
    assert first is None, f"{name}: frame {first} differs: HIL {hil[first]} SIL {sil[first]}"


@pytest.mark.parametrize("name", SHARED_FAULTY)
def test_sil_and_hil_give_the_same_dtc_times(name: str) -> None:
    from canfdi.timeline import Timeline
    hil = run_scenario(name).result["codes"]
    tl = Timeline().feed_all(read_frames(sil_log(name)))
    sil = {r.code: r.first_failed_us * 1e-6 if r.first_failed_us >= 0 else None
           for r in tl.dtcs.values() if r.first_reported_us >= 0 or r.first_pending_us >= 0}
    assert hil, f"{name}: no trouble code on the bus"
    assert {c: v["testFailed_s"] for c, v in hil.items()} == pytest.approx(sil, abs=1e-9)


def test_limp_home_seen_in_plant_status() -> None:
    """Both TPS lost at 3 s: the plant reports the valve held by the spring
    (SimPlantStatus.PstThrLimpHome) within 200 ms."""
    from canfdi.timeline import load_db
    db = load_db()
    pst = db.get_message_by_name("SimPlantStatus")
    times = []
    for m in read_frames(run_scenario("tps_both_lost").log):
        if m.arbitration_id == pst.frame_id:
            s = pst.decode(bytes(m.data), decode_choices=False)
            times.append((s["PstSimTime"], s["PstThrLimpHome"]))
    before = [lh for t, lh in times if 1.0 <= t < 3.0]
    after = [t for t, lh in times if t >= 3.0 and lh == 1]
    assert before and not any(before), "valve should be driven before the fault"
    assert after and after[0] <= 3.2 + 1e-9, f"limp-home first reported at {after[:1]}"


def test_bridge_switchover_on_the_bus() -> None:
    """Stage A dies at 3 s: DcmActuator selects bridge B within 5 ms and the
    plant reports bridge B."""
    from canfdi.timeline import load_db
    db = load_db()
    act = db.get_message_by_name("DcmActuator")
    step = db.get_message_by_name("SimStep")
    k = -1
    switched_at = None
    for m in read_frames(run_scenario("bridge_a_dead").log):
        if m.arbitration_id == step.frame_id:
            k = step.decode(bytes(m.data))["SimStepIndex"]
        elif m.arbitration_id == act.frame_id and switched_at is None:
            if act.decode(bytes(m.data), decode_choices=False)["DcmBridgeSel"] == 2:
                switched_at = k
    assert switched_at is not None, "never switched to bridge B"
    assert 3000 <= switched_at <= 3005, f"switched at step {switched_at}"


def test_recording_decodes_with_cantools() -> None:
    """Interoperability: `cantools decode dbc/canfdi.dbc` reads the recording."""
    log = run_scenario("tps1_open").log
    with log.open() as f:
        r = subprocess.run([sys.executable, "-m", "cantools", "decode", "dbc/canfdi.dbc"], cwd=ROOT,
                           stdin=f, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    assert r.returncode == 0, r.stderr
    assert "EcuDtc(" in r.stdout and "DcmSensor(" in r.stdout and "SimStep(" in r.stdout
    assert "Unknown frame id" not in r.stdout
