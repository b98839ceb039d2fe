"""tools/canfdi/e2e.py against crccheck and the vectors of tests/unit/test_e2e.c."""
from __future__ import annotations

import random
import re
from itertools import combinations

import pytest
from crccheck.crc import Crc8SaeJ1850

from canfdi import e2e
from conftest import ROOT


def c_frame_vectors():
    """The frame vectors hard-coded in the C unit test, parsed from its source."""
    text = (ROOT / "tests/unit/test_e2e.c").read_text()
    found = re.findall(r'\{0x([0-9A-F]+)U, "([0-9A-F]{14})", 0x([0-9A-F]{2})U\}', text)
    assert len(found) >= 5
    return [(int(i, 16), bytes.fromhex(p), int(c, 16)) for i, p, c in found]


def test_check_value():
    assert e2e.crc8_j1850(b"123456789") == 0x4B == Crc8SaeJ1850.calc(b"123456789")


@pytest.mark.parametrize("data_id,payload,crc", c_frame_vectors())
def test_c_unit_test_vectors_agree_with_crccheck(data_id, payload, crc):
    assert Crc8SaeJ1850.calc(bytes((data_id & 0xFF, data_id >> 8)) + payload) == crc
    assert e2e.frame_crc(data_id, b"\x00" + payload) == crc


def test_random_frames_agree_with_crccheck():
    rnd = random.Random(1)
    for _ in range(5000):
        data_id = rnd.randrange(0x800)
        frame = bytearray(rnd.randbytes(8))
        e2e.protect(data_id, frame, rnd.randrange(16))
        want = Crc8SaeJ1850.calc(bytes((data_id & 0xFF, data_id >> 8)) + bytes(frame[1:]))
        assert frame[0] == want and e2e.is_valid(data_id, bytes(frame))


def test_hamming_distance_is_3_over_72_bits():
    """Every 1- and 2-bit error over the 9 protected bytes plus CRC is detected;
    some 3-bit error is not (the polynomial is primitive, not 2-factor)."""
    rnd = random.Random(2)
    data = bytes(rnd.randbytes(9))
    crc = Crc8SaeJ1850.calc(data)
    word = int.from_bytes(data + bytes((crc,)), "big")
    nbits = 80

    def undetected(err: int) -> bool:
        w = (word ^ err).to_bytes(10, "big")
        return Crc8SaeJ1850.calc(w[:9]) == w[9]

    for k in (1, 2):
        assert not any(undetected(sum(1 << p for p in c)) for c in combinations(range(nbits), k))
    assert any(undetected(sum(1 << p for p in c)) for c in combinations(range(nbits), 3))


def test_receiver_statuses():
    rx = e2e.E2EReceiver(0x010, max_delta=2)
    frames = [e2e.protect(0x010, bytearray(8), c) for c in range(16)]
    assert rx.check(bytes(frames[15])) is e2e.Status.INITIAL
    assert rx.check(bytes(frames[0])) is e2e.Status.OK            # wrap 15 -> 0
    assert rx.check(bytes(frames[0])) is e2e.Status.REPEATED
    assert rx.check(bytes(frames[2])) is e2e.Status.OK_SOME_LOST and rx.lost == 1
    assert rx.check(bytes(frames[6])) is e2e.Status.WRONG_SEQUENCE and rx.lost == 3
    assert rx.check(bytes(frames[7])) is e2e.Status.OK
    bad = bytearray(frames[8]); bad[3] ^= 0x10
    assert rx.check(bytes(bad)) is e2e.Status.WRONG_CRC
    assert rx.check(bytes(frames[8][:7])) is e2e.Status.WRONG_LENGTH
    assert rx.check(None) is e2e.Status.NO_NEW_DATA
    assert rx.check(bytes(frames[8])) is e2e.Status.OK
