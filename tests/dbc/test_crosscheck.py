"""The C side (canfdi_e2e.c and both generated codecs, built by harness.c with
the project's flags) against the Python side (cantools, tools/canfdi/e2e.py)."""
from __future__ import annotations

import random

import pytest

from crccheck.crc import Crc8SaeJ1850

from canfdi import e2e

# The four protected frames: who packs them in C, the raw signals the
# harness takes (in order), and which side unpacks.
FRAMES = {
    "dcm_sensor": ("DcmSensor", ["DcmUa", "DcmIa", "DcmOmega", "DcmUsupply"]),
    "thr_sensor": ("ThrSensor", ["ThrTps1", "ThrTps2", "ThrImot", "ThrUsupply"]),
    "dcm_actuator": ("DcmActuator", ["DcmBridgeSel", "DcmEnable", "DcmUaCmd"]),
    "thr_actuator": ("ThrActuator", ["ThrEnable", "ThrUCmd"]),
}


@pytest.mark.parametrize("variant", ["harness", "harness_bitwise"])
def test_c_crc_matches_crccheck(variant, request):
    harness = request.getfixturevalue(variant)
    rnd = random.Random(3)
    cases = []
    for _ in range(3000):
        data_id = rnd.randrange(0x800)
        frame = rnd.randbytes(rnd.randrange(1, 9))
        cases.append((data_id, frame))
    out = harness([f"crc {i} {f.hex() if f else ''}" for i, f in cases])
    for (data_id, frame), got in zip(cases, out, strict=True):
        want = Crc8SaeJ1850.calc(bytes((data_id & 0xFF, data_id >> 8)) + frame[1:])
        assert int(got) == want == e2e.frame_crc(data_id, frame)


def test_c_check_state_machine_matches_python(harness):
    """A random stream of good, repeated, skipping, corrupted, short and
    missing frames yields the same status and lost count in C and Python."""
    rnd = random.Random(4)
    for max_delta in (1, 3, 15):
        data_id = 0x011
        rx = e2e.E2EReceiver(data_id, max_delta)
        lines, want = [f"init {data_id} {max_delta}"], ["ok"]
        counter = rnd.randrange(16)
        for _ in range(2000):
            event = rnd.choice(["ok"] * 6 + ["repeat", "skip", "crc", "short", "none", "id"])
            if event == "ok":
                counter = (counter + 1) & 15
            elif event == "skip":
                counter = (counter + rnd.randrange(2, 16)) & 15
            frame = e2e.protect(data_id if event != "id" else 0x010, bytearray(rnd.randbytes(8)), counter)
            if event == "crc":
                frame[rnd.randrange(8)] ^= 1 << rnd.randrange(8)
            if event == "short":
                frame = frame[:rnd.randrange(1, 8)]
            if event == "none":
                lines.append("chk -")
                st = rx.check(None)
            else:
                lines.append(f"chk {bytes(frame).hex()}")
                st = rx.check(bytes(frame))
            want.append(f"{int(st)} {rx.lost}")
        assert harness(lines) == want


def test_c_codecs_match_cantools(db, harness):
    """Random raw values: the C sender's packed+protected bytes equal
    cantools' encoding protected in Python, and the C receiver unpacks them."""
    rnd = random.Random(5)
    for cname, (mname, signals) in FRAMES.items():
        msg = db.get_message_by_name(mname)
        frames, tx_lines = [], []
        for _ in range(300):
            # half the frames near the plausibility edges, where the limits matter
            raw = {s.name: rnd.randrange(1 << s.length) if rnd.random() < 0.5 else
                   min((1 << s.length) - 1, max(0, round((rnd.choice((s.minimum, s.maximum)) - s.offset)
                                                       / s.scale) + rnd.randint(-2, 2)))
                   for s in msg.signals}
            counter = rnd.randrange(16)
            data = bytearray(msg.encode(raw, scaling=False, strict=False))
            e2e.protect(msg.frame_id, data, counter)
            assert e2e.is_valid(msg.frame_id, bytes(data))
            frames.append(bytes(data))
            tx_lines.append(f"tx {cname} {counter} " + " ".join(str(raw[s]) for s in signals))
        assert harness(tx_lines) == [f.hex() for f in frames], mname
        back = harness([f"rx {cname} {f.hex()}" for f in frames])
        outcomes = set()
        for data, line in zip(frames, back, strict=True):
            decoded = msg.decode(data, scaling=False, decode_choices=False)
            fields = [int(x) for x in line.split()]
            assert fields[:len(msg.signals)] == [decoded[s.name] for s in msg.signals], mname
            if mname.endswith("Sensor"):
                # the C raw-limit check agrees with cantools' physical [min, max]
                phys = msg.decode(data, decode_choices=False)
                # a millionth of a step absorbs float noise (0.24 - 10.24 != -10.0)
                want = all(s.minimum - 1e-6 * s.scale <= phys[s.name] <= s.maximum + 1e-6 * s.scale
                           for s in msg.signals)
                assert fields[-1] == int(want), (mname, phys)
                outcomes.add(want)
        if mname.endswith("Sensor"):
            assert outcomes == {True, False}, "the sample must exercise both verdicts"
