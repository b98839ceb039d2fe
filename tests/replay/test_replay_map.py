"""canfdi-replay --map: a recording of another bus (tests/replay/data/vehicle.dbc:
the drive's voltage in mV, current in mA, speed in rpm, the supply every
10 ms, the applied command) diagnosed through a map onto the supervisor's
inputs. The vehicle's log is made here from a SIL recording, re-encoded with
cantools in the other bus's frames."""
from __future__ import annotations

import math
from pathlib import Path

import cantools
import can
import pytest

from conftest import ROOT, make_sil_log, run_replay, undocumented_keys

DATA = Path(__file__).resolve().parent / "data"
OURS = cantools.database.load_file(str(ROOT / "dbc" / "canfdi.dbc"))
VEHICLE = cantools.database.load_file(str(DATA / "vehicle.dbc"))


def vehicle_log(src: Path, dst: Path, every_ms: int = 1, silent: tuple[float, float] | None = None) -> Path:
    """The SIL recording's DC-motor frames as the vehicle's bus would carry them: MotorFb and
    DriveCmd every `every_ms`, Supply every 10 ms; no MotorFb in the `silent` span."""
    k = 0
    with dst.open("w") as out:
        for m in can.LogReader(str(src)):
            quiet = silent is not None and silent[0] <= m.timestamp < silent[1]
            stamp = f"({m.timestamp:017.6f}) can2 "
            if m.arbitration_id == 0x010:
                k += 1
                d = OURS.decode_message(0x010, m.data)
                if k % every_ms == 0 and not quiet:
                    data = VEHICLE.encode_message("MotorFb", {
                        "ArmVoltage": 2 * round(d["DcmUa"] * 500), "ArmCurrent": round(d["DcmIa"] * 1000),
                        "SpeedRpm": d["DcmOmega"] * 60 / (2 * math.pi)})
                    out.write(f"{stamp}123#{data.hex().upper()}\n")
                if k % 10 == 0:
                    out.write(f"{stamp}124#{VEHICLE.encode_message('Supply', {'BusVoltage': d['DcmUsupply']}).hex().upper()}\n")
            elif m.arbitration_id == 0x020 and k % every_ms == 0:
                d = OURS.decode_message(0x020, m.data, decode_choices=False)
                data = VEHICLE.encode_message("DriveCmd", {"CmdVoltage": d["DcmUaCmd"], "CmdBridge": d["DcmBridgeSel"],
                                                           "CmdEnable": d["DcmEnable"]})
                out.write(f"{stamp}125#{data.hex().upper()}\n")
    return dst


@pytest.fixture(scope="module")
def late_log() -> Path:
    """I_A sensor offset at 9 s (the ECU: P1A20 at 9.051 s), 11 s."""
    return make_sil_log(DATA / "dcm_ia_late.scn")


def test_mapped_bus_at_1_ms(late_log: Path, tmp_path: Path) -> None:
    log = vehicle_log(late_log, tmp_path / "vehicle.log")
    rc, doc, out, err = run_replay(["--map", str(DATA / "vehicle.map"), str(log)], tmp_path)
    assert doc is not None, err
    assert rc == 1
    assert [f["code"] for f in doc["dtcs"]] == ["P1A20"]
    assert 9.0 < doc["dtcs"][0]["first_failed_s"] < 9.2
    lg = doc["logs"][0]
    assert lg["start"] == "mid-drive" and lg["channel"] == "can2"
    m = doc["map"]
    assert set(m["codes_not_applied"]) == {"U1A10", "U1A20", "U1A30"}
    assert m["models_not_judged"] == {}
    assert "MotorFb.SpeedRpm" in m["inputs"]["DcmOmega"]
    judged = {n["monitor"]: n for n in doc["not_judged"]}
    assert "ThrSensor is not in the recording" in judged["com_thr"]["spans"][0]["why"]
    assert any(n["monitor"] == "not applicable" and n["codes"] == ["U1A20"] for n in doc["not_judged"])
    assert not undocumented_keys(doc), "keys the schema does not name"


def test_mapped_bus_bad_lines_and_places(late_log: Path, tmp_path: Path) -> None:
    """The other bus's candump log with a line that is no frame and an error frame: the line is
    reported with its number, the error frame is never made into an input, the diagnosis stands;
    a frame of another channel is counted at its own line."""
    log = vehicle_log(late_log, tmp_path / "vehicle.log")
    lines = log.read_text().splitlines(keepends=True)
    stamp = lines[999][:19]
    lines[999:999] = ["not a frame\n", f"{stamp} can2 20000080#0000000000000000\n"]
    lines[3000:3000] = [f"{lines[3000][:19]} can7 123#{lines[3000].split('#')[1]}"]
    log.write_text("".join(lines))
    rc, doc, out, err = run_replay(["--map", str(DATA / "vehicle.map"), str(log)], tmp_path)
    assert doc is not None and rc == 1, err
    assert [f["code"] for f in doc["dtcs"]] == ["P1A20"]
    dq = doc["data_quality"][0]
    assert [(b["line"], b["text"]) for b in dq["bad_lines"]] == [(1000, "not a frame")]
    assert dq["error_frames"] == 0
    assert dq["other_channels"] == {"can7": {"frames": 1, "first_line": 3001}}


def test_mapped_bus_at_10_ms(late_log: Path, tmp_path: Path) -> None:
    """At 10 ms the models cannot be judged (they need 1 ms samples), the frame checks can:
    no timeout while the frames come, a timeout when MotorFb stops for 100 ms while the rest of
    the bus goes on."""
    (tmp_path / "vehicle.dbc").write_text((DATA / "vehicle.dbc").read_text())
    map10 = tmp_path / "vehicle10.map"  # the map states the rate the log has
    map10.write_text("".join(line.replace(" unit V", " unit V rate 10").replace("unit A", "unit A rate 10")
                             .replace("unit rad/s", "unit rad/s rate 10").replace("CmdBridge", "CmdBridge rate 10")
                             .replace("CmdEnable", "CmdEnable rate 10")
                             for line in (DATA / "vehicle.map").read_text().splitlines(keepends=True)))
    log = vehicle_log(late_log, tmp_path / "vehicle10.log", every_ms=10)
    rc, doc, out, err = run_replay(["--map", str(map10), str(log)], tmp_path)
    assert doc is not None, err
    assert rc == 0 and doc["dtcs"] == []
    assert set(doc["map"]["models_not_judged"]) == {"dcm"}
    dcm = next(n for n in doc["not_judged"] if n["monitor"] == "dcm_models")
    assert "10 ms" in dcm["spans"][-1]["why"] and dcm["fraction"] == 1.0
    log2 = vehicle_log(late_log, tmp_path / "vehicle10s.log", every_ms=10, silent=(6.0, 6.1))
    rc, doc, out, err = run_replay(["--map", str(map10), str(log2)], tmp_path)
    assert doc is not None and rc == 1
    assert [f["code"] for f in doc["dtcs"]] == ["U1A00"]
    assert 6.03 < doc["dtcs"][0]["first_failed_s"] < 6.07  # four missed 10 ms frames


@pytest.mark.parametrize("text,message", [
    ("DcmUa = MotorFb.ArmVoltage unit V\n", "no 'dbc = FILE' line"),
    ("dbc = vehicle.dbc\nFoo = MotorFb.ArmVoltage unit V\n", ":2: 'Foo' is not an input"),
    ("dbc = vehicle.dbc\nDcmUa = MotorFb.ArmVoltage unit mV\n", ":2: DcmUa is in 'V'"),
    ("dbc = vehicle.dbc\nDcmUa = MotorFb.ArmVoltage scale x unit V\n", ":2: scale 'x' is not a number"),
    ("dbc = vehicle.dbc\nDcmUa = MotorFb.Nope unit V\n", ":2: message MotorFb of vehicle.dbc has no signal"),
    ("dbc = vehicle.dbc\nDcmUa = Nope.ArmVoltage unit V\n", ":2: no message 'Nope'"),
    ("dbc = vehicle.dbc\nDcmUa = MotorFb.ArmVoltage scale 0.001 unit V\n", "DcmSensor is mapped but not DcmIa"),
    ("dbc = vehicle.dbc\nDcmUa = MotorFb.ArmVoltage unit V\nDcmUa = MotorFb.ArmVoltage unit V\n",
     ":3: DcmUa is mapped twice"),
    ("dbc = missing.dbc\nDcmUa = MotorFb.ArmVoltage unit V\n", "cannot load the other DBC"),
    # found by fuzzing (tests/fuzz/regress/py_readers): a traceback, not a message
    ("dbc = vehicle\0.dbc\nDcmUa = MotorFb.ArmVoltage unit V\n", ":1: bad DBC path"),
])
def test_bad_map_files(text: str, message: str, late_log: Path, tmp_path: Path) -> None:
    (tmp_path / "vehicle.dbc").write_text((DATA / "vehicle.dbc").read_text())
    mp = tmp_path / "bad.map"
    mp.write_text(text)
    rc, doc, out, err = run_replay(["--map", str(mp), str(late_log)], tmp_path)
    assert rc == 2 and message in err and str(mp) in err, err


def test_scale_and_offset(tmp_path: Path) -> None:
    """An input is scale x (the other DBC's physical value) + offset, in the unit the map states;
    const gives a value the bus does not carry. The frame made is dbc/canfdi.dbc's, E2E-protected."""
    import io

    from canfdi.replay_input import Problems
    from canfdi.replay_map import Mapper
    (tmp_path / "vehicle.dbc").write_text((DATA / "vehicle.dbc").read_text())
    mp = tmp_path / "offset.map"
    mp.write_text("dbc = vehicle.dbc\n"
                  "DcmUa      = MotorFb.ArmVoltage scale 0.001 offset 0.5 unit V\n"
                  "DcmIa      = MotorFb.ArmCurrent scale -0.001 offset -1 unit A\n"
                  "DcmOmega   = MotorFb.SpeedRpm   scale 0.104719755 unit rad/s\n"
                  "DcmUsupply = const 48 unit V\n")
    m = Mapper.load(mp)
    data = VEHICLE.encode_message("MotorFb", {"ArmVoltage": 12000, "ArmCurrent": 2500, "SpeedRpm": 955.0})
    log = tmp_path / "one.log"
    log.write_text(f"(0000000001.000000) can0 123#{data.hex().upper()}\n")
    out = io.StringIO()
    assert m.write(log, "candump", out, Problems()) == 1
    frame = can.Message(arbitration_id=int(out.getvalue().split()[2].split("#")[0], 16),
                        data=bytes.fromhex(out.getvalue().split("#")[1]))
    d = OURS.decode_message(frame.arbitration_id, frame.data)
    assert frame.arbitration_id == OURS.get_message_by_name("DcmSensor").frame_id
    assert d["DcmUa"] == pytest.approx(12.5, abs=0.01)      # 12000 mV x 0.001 + 0.5
    assert d["DcmIa"] == pytest.approx(-3.5, abs=0.01)      # 2500 mA x -0.001 - 1
    assert d["DcmOmega"] == pytest.approx(100.0, abs=0.05)  # 955 rpm
    assert d["DcmUsupply"] == pytest.approx(48.0, abs=0.1)
    assert "x 0.001 + 0.5 V" in m.info()["inputs"]["DcmUa"] and "const 48" in m.info()["inputs"]["DcmUsupply"]
