"""Structure of dbc/canfdi.dbc: strictness, timing attributes, value tables,
E2E layout, identifiers and resolution."""
from __future__ import annotations

import re
import subprocess
import sys

import pytest

from conftest import DBC, ROOT, load_strict

NODES = {"ECU", "PLANT", "TESTER", "VEHICLE"}
E2E_ATTR = "CanfdiE2E"
# The agreed physical ranges of each sensor signal (12-bit ADC over them).
SENSOR_RANGES = {
    "DcmUa": (-60.0, 60.0), "DcmIa": (-30.0, 30.0), "DcmOmega": (-400.0, 400.0),
    "DcmUsupply": (0.0, 80.0), "ThrTps1": (0.0, 5.0), "ThrTps2": (0.0, 5.0),
    "ThrImot": (-10.0, 10.0), "ThrUsupply": (0.0, 16.0),
}
ADC_STEPS = 4096
# Frames canfdi requires (dbc/README.md), with their cycle in ms (None = event driven).
REQUIRED = {
    "DcmSensor": 1, "ThrSensor": 1, "DcmActuator": 1, "ThrActuator": 1,
    "SetpointDcm": 10, "SetpointThr": 10, "EcuResidualDcm": 10, "EcuResidualThr": 10,
    "EcuStatus": 100, "EcuDiagnosis": 100, "EcuDtc": 100, "EcuParamDcm": 100, "EcuParamThr": 100,
    "SimPlantStatus": 100, "SimFaultInject": None, "SimFaultClear": None,
    "UdsFuncReq": None, "UdsPhysReq": None, "UdsPhysResp": None,
}
# The E2E protected frames (dbc/README.md, "E2E protection"): the 1 ms
# control frames, the vehicle's setpoints (a corrupted throttle setpoint
# opens the valve) and the ECU's frames a tester or the vehicle acts on.
E2E_FRAMES = {"DcmSensor", "ThrSensor", "DcmActuator", "ThrActuator", "SetpointDcm", "SetpointThr",
              "EcuStatus", "EcuDiagnosis", "EcuDtc"}
# A signal is an enumeration if its name says so or it is a single bit.
ENUM_NAME = re.compile(r"(FaultId|State\w*|Mode|Bridge\w*|Sel|Enable|Valid|LimpHome|Reason|"
                       r"FaultActive|DtcCode|DtcSts\w+)$")


def attr(msg, name):
    a = msg.dbc.attributes.get(name)
    return None if a is None else a.value


def send_type(db, msg) -> str:
    definition = db.dbc.attribute_definitions["GenMsgSendType"]
    value = attr(msg, "GenMsgSendType")
    if value is None:
        return definition.default_value
    return definition.choices[value] if isinstance(value, int) else value


def test_strict_load_promotes_warnings(tmp_path):
    """The loader used here really fails on a problem (overlapping signals)."""
    bad = DBC.read_text().replace(" SG_ DcmSensorCounter : 8|4@1+", " SG_ DcmSensorCounter : 4|4@1+")
    assert bad != DBC.read_text()
    path = tmp_path / "bad.dbc"
    path.write_text(bad)
    with pytest.raises(Exception, match="overlap"):
        load_strict(path)


def test_cantools_dump_runs():
    res = subprocess.run([sys.executable, "-m", "cantools", "dump", str(DBC)],
                         capture_output=True, text=True, timeout=120)
    assert res.returncode == 0, res.stderr
    assert "DcmSensor" in res.stdout and res.stderr == ""


def test_nodes(db):
    assert {n.name for n in db.nodes} == NODES
    for m in db.messages:
        assert m.senders and set(m.senders) <= NODES, m.name
        for s in m.signals:
            assert s.receivers and set(s.receivers) <= NODES, (m.name, s.name)


def test_required_frames_and_cycles(db):
    names = {m.name for m in db.messages}
    assert set(REQUIRED) <= names
    for name, cycle in REQUIRED.items():
        assert db.get_message_by_name(name).cycle_time == cycle, name


def test_cycle_time_attribute_declared(db):
    defs = db.dbc.attribute_definitions
    assert defs["GenMsgCycleTime"].type_name == "INT"
    assert defs["GenMsgCycleTime"].default_value == 0
    assert "GenMsgSendType" in defs and E2E_ATTR in defs


def test_periodic_frames_have_explicit_cycle_time(db):
    for m in db.messages:
        periodic = send_type(db, m).startswith("Cyclic")
        explicit = attr(m, "GenMsgCycleTime")
        if periodic:
            assert explicit is not None and explicit > 0, f"{m.name}: no GenMsgCycleTime"
        else:
            assert explicit is None, f"{m.name}: event frame with a cycle time"


def test_standard_ids_and_priorities(db):
    for m in db.messages:
        assert not m.is_extended_frame and 0 <= m.frame_id <= 0x7FF, m.name
        assert m.length == 8, m.name
    fast = [m.frame_id for m in db.messages if m.cycle_time == 1]
    slow = [m.frame_id for m in db.messages if m.cycle_time != 1]
    assert max(fast) < min(slow), "1 ms control frames must win arbitration"
    uds = {m.frame_id: m for m in db.messages if m.name.startswith("Uds")}
    assert set(uds) == {0x7DF, 0x7E0, 0x7E8}
    assert uds[0x7E8].senders == ["ECU"] and uds[0x7E0].senders == ["TESTER"]


def signal_bits(s) -> set[int]:
    """The frame bits (byte * 8 + bit, bit 0 the LSB) a signal occupies."""
    if s.byte_order == "little_endian":
        return set(range(s.start, s.start + s.length))
    bits, pos = set(), s.start   # Motorola: from the MSB, 7..0 of a byte, then the next byte
    for _ in range(s.length):
        bits.add(pos)
        pos = pos + 15 if pos % 8 == 0 else pos - 1
    return bits


def test_e2e_layout_on_every_protected_frame(db):
    assert {m.name for m in db.messages if attr(m, E2E_ATTR) not in (None, 0)} == E2E_FRAMES
    for m in db.messages:
        if m.cycle_time == 1:
            assert m.name in E2E_FRAMES, f"{m.name}: every 1 ms control frame is protected"
        if m.name not in E2E_FRAMES:
            assert not any(s.name.endswith(("Crc", "Counter")) for s in m.signals), m.name
            continue
        crc = m.get_signal_by_name(m.name + "Crc")
        ctr = m.get_signal_by_name(m.name + "Counter")
        for s, start, length in ((crc, 0, 8), (ctr, 8, 4)):
            assert (s.start, s.length, s.byte_order, s.is_signed) == (start, length, "little_endian", False)
            assert (s.scale, s.offset) == (1, 0)
        assert "E2E protected" in (m.comment or ""), f"{m.name}: the comment states the protection"
        # the payload leaves byte 0 and the low nibble of byte 1 alone
        for s in m.signals:
            if s not in (crc, ctr):
                assert min(signal_bits(s)) >= 12, s.name


def test_e2e_frames_encode_and_check(db):
    """cantools encodes every protected frame with its header; e2e.protect
    fills it in and the Python receiver accepts a sequence of them."""
    from canfdi import e2e
    for name in E2E_FRAMES:
        m = db.get_message_by_name(name)
        rx = e2e.E2EReceiver(m.frame_id)
        for k in range(20):
            values = {s.name: (s.minimum if s.minimum is not None else 0) for s in m.signals}
            data = e2e.protect(m.frame_id, bytearray(m.encode(values, strict=False)), k)
            want = e2e.Status.INITIAL if k == 0 else e2e.Status.OK
            assert rx.check(bytes(data)) == want, name
            sig = m.decode(bytes(data), decode_choices=False)
            assert sig[name + "Counter"] == k % 16 and sig[name + "Crc"] == data[0]


def test_every_enumeration_has_a_value_table(db):
    for m in db.messages:
        for s in m.signals:
            if ENUM_NAME.search(s.name) or s.length == 1:
                assert s.choices, f"{m.name}.{s.name} has no VAL_ table"
            if s.choices:
                assert ENUM_NAME.search(s.name) or s.length == 1, f"{s.name}: unexpected VAL_"
                assert (s.scale, s.offset) == (1, 0)
                for v in s.choices:
                    assert s.minimum <= int(v) <= s.maximum, (s.name, v)


def test_shared_value_tables_agree(db):
    """The same enumeration has the same table wherever it appears."""
    groups = {"DegState": [], "Bridge": [], "FaultMode|InjMode": [], "LimpHome": [], "Enable": []}
    for m in db.messages:
        for s in m.signals:
            for key in groups:
                if re.search(key, s.name) and s.choices:
                    groups[key].append({int(k): str(v) for k, v in s.choices.items()})
    for key, tables in groups.items():
        assert len(tables) >= 2 and all(t == tables[0] for t in tables), key
    assert groups["DegState"][0] == {0: "normal", 1: "degraded", 2: "fail_safe", 3: "fail_silent"}
    assert groups["FaultMode|InjMode"][0] == {0: "abrupt", 1: "incipient", 2: "intermittent"}


def raw_limits(s):
    return (-(1 << (s.length - 1)), (1 << (s.length - 1)) - 1) if s.is_signed else (0, (1 << s.length) - 1)


def test_every_range_is_representable(db):
    for m in db.messages:
        for s in m.signals:
            lo, hi = raw_limits(s)
            phys = sorted((lo * s.scale + s.offset, hi * s.scale + s.offset))
            # a millionth of a step absorbs float noise; integer signals compare exactly
            eps = 0 if (s.scale, s.offset) == (1, 0) else abs(s.scale) * 1e-6
            assert phys[0] - eps <= s.minimum and s.maximum <= phys[1] + eps, (m.name, s.name)
            assert s.comment, (m.name, s.name)
        assert m.comment, m.name


def test_sensor_resolution_finer_than_adc_and_all_ones_implausible(db):
    for name, (lo, hi) in SENSOR_RANGES.items():
        s = db.get_message_by_name(name[:3] + "Sensor").get_signal_by_name(name)
        assert (s.minimum, s.maximum) == (lo, hi), name
        lsb = (hi - lo) / ADC_STEPS
        assert s.scale < lsb, f"{name}: DBC step {s.scale} not finer than ADC LSB {lsb}"
        assert not s.is_signed
        all_ones = ((1 << s.length) - 1) * s.scale + s.offset
        assert all_ones > hi, f"{name}: all-ones raw value {all_ones} would look plausible"


def test_fault_id_tables_match_catalogue(db):
    from canfdi.catalogue import load_faults
    want = {f.id: f.name for f in load_faults()}
    found = 0
    for m in db.messages:
        for s in m.signals:
            if s.name.endswith("FaultId"):
                found += 1
                assert {int(k): str(v) for k, v in s.choices.items()} == want, s.name
    assert found >= 5  # inject, clear, plant status, 3 x diagnosis


def test_dtc_table_matches_catalogue(db):
    from canfdi.catalogue import load_dtcs
    s = db.get_message_by_name("EcuDtc").get_signal_by_name("DtcCode")
    assert {int(k): str(v) for k, v in s.choices.items()} == {d.uds_dtc: d.code for d in load_dtcs()}
    # the DTC is big-endian as in UDS: bytes 3..5 of the frame read P0122 as 01 22 00
    # (bytes 0..1 carry the E2E header, index, count and reason)
    m = db.get_message_by_name("EcuDtc")
    values = {sig.name: 0 for sig in m.signals}
    values.update(DtcCode=0x012200, DtcStsTestFailed=1, DtcStsConfirmed=1, DtcOccurrence=5)
    frame = m.encode(values)
    assert frame[3:6] == bytes((0x01, 0x22, 0x00))
    assert frame[6] == 0x09  # byte 6 is the UDS status byte: testFailed | confirmedDTC
    assert frame[7] == 5
    # room for the product's codes: every DTC has an index below the field's top
    assert m.get_signal_by_name("DtcIndex").maximum + 1 >= len(load_dtcs())


def test_codec_roundtrip(db):
    """Every message encodes and decodes min, max, zero-ish and random values."""
    import random
    rnd = random.Random(7)
    for m in db.messages:
        samples = []
        for pick in ("min", "max", "mid", "rand", "rand", "rand"):
            values = {}
            for s in m.signals:
                if s.choices:
                    values[s.name] = rnd.choice(sorted(int(k) for k in s.choices))
                    continue
                if (s.scale, s.offset) == (1, 0):
                    # integer signal (up to 64 bits): stay in exact integer arithmetic
                    lo, hi = int(s.minimum), int(s.maximum)
                    values[s.name] = {"min": lo, "max": hi, "mid": (lo + hi) // 2}.get(pick) \
                        if pick != "rand" else rnd.randint(lo, hi)
                    continue
                if pick == "min":
                    v = s.minimum
                elif pick == "max":
                    v = s.maximum
                elif pick == "mid":
                    v = (s.minimum + s.maximum) / 2
                else:
                    v = rnd.uniform(s.minimum, s.maximum)
                # snap to the raw grid so the round trip is exact up to float noise
                values[s.name] = round((v - s.offset) / s.scale) * s.scale + s.offset
            samples.append(values)
        for values in samples:
            data = m.encode(values, scaling=True, strict=True)
            back = m.decode(data, decode_choices=False)
            for s in m.signals:
                # tolerance: 1e-6 of a step, i.e. float rounding of scale*raw+offset only
                assert back[s.name] == pytest.approx(values[s.name], abs=abs(s.scale) * 1e-6), \
                    (m.name, s.name)


def test_raw_limits_header_matches_cantools(db):
    """canfdi_raw_limits.h: raw_min is the smallest raw value whose physical
    value is >= min, raw_max the largest <= max (cantools does the scaling)."""
    text = (ROOT / "firmware/comm/gen/canfdi_raw_limits.h").read_text()
    limits = {m[1]: int(m[2]) for m in re.finditer(r"#define CANFDI_RAW_(\w+) \(?(-?\d+)U?\)?", text)}
    checked = 0
    for m in db.messages:
        for s in m.signals:
            if s.length > 32:
                continue
            base = re.sub(r"(?<=[a-z0-9])(?=[A-Z])", "_", m.name + "_" + s.name).upper().replace("__", "_")
            lo, hi = limits[base + "_MIN"], limits[base + "_MAX"]
            tlo, thi = raw_limits(s)
            phys = lambda r: r * s.scale + s.offset  # noqa: E731
            eps = abs(s.scale) * 1e-6
            assert phys(lo) >= s.minimum - eps and (lo == tlo or phys(lo - 1) < s.minimum - eps), base
            assert phys(hi) <= s.maximum + eps and (hi == thi or phys(hi + 1) > s.maximum + eps), base
            checked += 1
    assert checked == len(limits) // 2
