"""canfdi-inject: frames round-trip through the DBC; the CLI on python-can's
virtual interface; usage errors exit 2 with a helpful message."""
from __future__ import annotations

import subprocess
import sys

import can
import pytest

from canfdi import REPO_ROOT
from canfdi.catalogue import MODES, load_faults
from canfdi.inject import UsageError, clear_frame, fault_frame, main, setpoint_frames
from canfdi.timeline import load_db

DB = load_db()


def decode(msg: can.Message) -> dict:
    return DB.decode_message(msg.arbitration_id, bytes(msg.data), decode_choices=False)


@pytest.mark.parametrize("fault", load_faults()[1:], ids=lambda f: f.name)
def test_every_fault_round_trips_in_each_allowed_mode(fault) -> None:
    for mode in fault.modes:
        kw = {"ramp_s": 4.0} if mode == "incipient" else {"period_s": 1.5, "duty_pct": 20.0} \
            if mode == "intermittent" else {}
        fr = fault_frame(fault.name, mode, None, delay_s=0.25, **kw)
        assert fr.msg.arbitration_id == 0x600 and len(fr.msg.data) == 8
        s = decode(fr.msg)
        assert s["InjFaultId"] == fault.id
        assert s["InjMode"] == MODES.index(mode)
        assert s["InjMagnitude"] == pytest.approx(fault.default_magnitude, abs=1e-3)
        assert s["InjStartDelay"] == pytest.approx(0.25, abs=0.005)
        if mode == "incipient":
            assert s["InjRampOrPeriod"] == pytest.approx(4.0)
        if mode == "intermittent":
            assert (s["InjRampOrPeriod"], s["InjDuty"]) == (pytest.approx(1.5), 20)


def test_mode_not_allowed_and_missing_shape_parameters() -> None:
    with pytest.raises(UsageError, match="cannot be incipient"):
        fault_frame("thr_tps1_open", "incipient", ramp_s=1.0)
    with pytest.raises(UsageError, match="--ramp"):
        fault_frame("dcm_ra_up", "incipient")
    with pytest.raises(UsageError, match="--period"):
        fault_frame("dcm_ra_up", "intermittent", period_s=1.0)
    with pytest.raises(UsageError, match="smaller than or equal to 32.767"):
        fault_frame("dcm_ra_up", magnitude=40.0)


def test_clear_and_setpoints_round_trip() -> None:
    assert decode(clear_frame().msg) == {"ClrFaultId": 0}
    assert decode(clear_frame("thr_jammed").msg) == {"ClrFaultId": 20}
    dcm, thr = setpoint_frames(speed=-120.5, load=1.25, angle=33.3)
    s = decode(dcm.msg)
    assert (s["SpDcmSpeed"], s["SpDcmLoad"]) == (pytest.approx(-120.5), pytest.approx(1.25))
    assert decode(thr.msg)["SpThrAngle"] == pytest.approx(33.3, abs=0.002)
    with pytest.raises(UsageError, match="speed and load together"):
        setpoint_frames(speed=100.0)
    # E2E protected like the vehicle's: right CRC over the data ID, the counter given
    from canfdi import e2e
    for fr in (dcm, thr):
        data = bytes(fr.msg.data)
        assert e2e.is_valid(fr.msg.arbitration_id, data) and e2e.counter_of(data) == 0
    (thr7,) = setpoint_frames(angle=10.0, counter=7)
    assert e2e.is_valid(0x101, bytes(thr7.msg.data)) and e2e.counter_of(bytes(thr7.msg.data)) == 7
    with pytest.raises(UsageError, match="0..15"):
        setpoint_frames(angle=10.0, counter=16)


def test_cli_sends_on_virtual_bus(channel: str, capsys: pytest.CaptureFixture[str]) -> None:
    with can.Bus(interface="virtual", channel=channel) as rx:
        assert main(["-i", "virtual", "-c", channel, "fault", "dcm_ia_sensor_offset",
                     "--mode", "incipient", "--magnitude", "0.6", "--ramp", "2", "--delay", "1"]) == 0
        assert main(["-i", "virtual", "-c", channel, "clear", "all"]) == 0
        assert main(["-i", "virtual", "-c", channel, "setpoint", "--angle", "12"]) == 0
        got = [rx.recv(timeout=2.0) for _ in range(3)]
    assert [m.arbitration_id for m in got if m is not None] == [0x600, 0x601, 0x101]
    s = decode(got[0])
    assert (s["InjFaultId"], s["InjMode"], s["InjMagnitude"], s["InjRampOrPeriod"], s["InjStartDelay"]) == \
        (4, 1, pytest.approx(0.6), pytest.approx(2.0), pytest.approx(1.0))
    assert decode(got[2])["SpThrAngle"] == pytest.approx(12.0)
    out = capsys.readouterr().out
    assert "inject dcm_ia_sensor_offset (4) incipient magnitude 0.6 A over 2 s" in out
    assert "[600#" in out


@pytest.mark.parametrize("argv,needle", [
    (["fault", "thr_tps1_opn"], "unknown fault 'thr_tps1_opn'; did you mean thr_tps1_open"),
    (["fault", "thr_jammed", "--mode", "incipient", "--ramp", "1"], "cannot be incipient"),
    (["fault"], "give a NAME"),
    (["clear", "nosuch"], "unknown fault 'nosuch'"),
    (["setpoint"], "give --speed and --load"),
    ([], "nothing to do"),
])
def test_cli_usage_errors_exit_2(argv: list[str], needle: str, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["-i", "virtual", "-c", "unused"] + argv) == 2
    err = capsys.readouterr().err
    assert needle in err and "Traceback" not in err


def test_cli_bus_that_cannot_open_exits_1_with_hint(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["-i", "socketcan", "-c", "canfdi-nosuch0", "clear"]) == 1
    err = capsys.readouterr().err
    assert "cannot open socketcan channel canfdi-nosuch0" in err and "tools/vcan-run" in err


def test_list_and_installed_console_script() -> None:
    exe = REPO_ROOT / ".venv" / "bin" / "canfdi-inject"
    cmd = [str(exe)] if exe.exists() else [sys.executable, "-m", "canfdi.inject"]
    r = subprocess.run(cmd + ["--list"], capture_output=True, text=True, timeout=60)
    assert r.returncode == 0
    for f in load_faults()[1:]:
        assert f.name in r.stdout
    assert exe.exists(), "console scripts missing: run make deps"
