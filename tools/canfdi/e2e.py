"""E2E protection of the frames dbc/canfdi.dbc marks CanfdiE2E =
Crc8Counter4 (the 1 ms control frames, the setpoints, the ECU's status,
diagnosis and DTC frames); the Python twin of firmware/comm/canfdi_e2e.{h,c}
(same layout, same statuses).

Layout: byte 0 CRC-8 SAE J1850 (poly 0x1D, init 0xFF, xor-out 0xFF) over the
data ID (= CAN identifier, 2 bytes, low byte first) and bytes 1..7; the
rolling counter 0..15 in the low nibble of byte 1.

    data = bytearray(db.encode_message("DcmSensor", {...}))  # any CRC/counter
    protect(0x010, data, counter=k)                         # fills both in
    rx = E2EReceiver(0x010); rx.check(bytes(data))            # -> Status.INITIAL
"""
from __future__ import annotations

from enum import IntEnum
from typing import Any

FRAME_LEN = 8
CRC_BYTE = 0
COUNTER_BYTE = 1
COUNTER_MASK = 0x0F


def _make_table() -> list[int]:
    table = []
    for i in range(256):
        reg = i
        for _ in range(8):
            reg = ((reg << 1) ^ 0x1D) & 0xFF if reg & 0x80 else (reg << 1) & 0xFF
        table.append(reg)
    return table


_TABLE = _make_table()


def crc8_j1850(data: bytes, reg: int = 0xFF, final: bool = True) -> int:
    """CRC-8 SAE J1850; crc8_j1850(b'123456789') == 0x4B."""
    for b in data:
        reg = _TABLE[reg ^ b]
    return reg ^ 0xFF if final else reg


def frame_crc(data_id: int, frame: bytes) -> int:
    """E2E CRC of a frame: over data_id (low, high byte) and frame[1:]."""
    reg = crc8_j1850(bytes((data_id & 0xFF, (data_id >> 8) & 0xFF)), final=False)
    return crc8_j1850(bytes(frame[1:]), reg)


def protect(data_id: int, frame: bytearray, counter: int) -> bytearray:
    """Write counter (mod 16) into the low nibble of byte 1 and the CRC into byte 0."""
    if len(frame) != FRAME_LEN:
        raise ValueError(f"E2E frames have {FRAME_LEN} bytes, got {len(frame)}")
    frame[COUNTER_BYTE] = (frame[COUNTER_BYTE] & 0xF0) | (counter & COUNTER_MASK)
    frame[CRC_BYTE] = frame_crc(data_id, frame)
    return frame


def counter_of(frame: bytes) -> int:
    return frame[COUNTER_BYTE] & COUNTER_MASK


def is_valid(data_id: int, frame: bytes) -> bool:
    """Length and CRC right (the counter sequence needs an E2EReceiver)."""
    return len(frame) == FRAME_LEN and frame[CRC_BYTE] == frame_crc(data_id, frame)


class Status(IntEnum):
    """Same values as canfdi_e2e_status_t."""
    OK = 0
    OK_SOME_LOST = 1
    INITIAL = 2
    REPEATED = 3
    WRONG_SEQUENCE = 4
    WRONG_CRC = 5
    WRONG_LENGTH = 6
    NO_NEW_DATA = 7

    @property
    def usable(self) -> bool:
        return self in (Status.OK, Status.OK_SOME_LOST, Status.INITIAL)


class E2EReceiver:
    """The check state machine of canfdi_e2e_check (see canfdi_e2e.h)."""

    def __init__(self, data_id: int, max_delta: int = 1) -> None:
        if not 1 <= max_delta <= 15:
            raise ValueError("max_delta must be 1..15")
        self.data_id = data_id
        self.max_delta = max_delta
        self.last_counter = 0
        self.synced = False
        self.lost = 0

    def check(self, frame: bytes | None) -> Status:
        if frame is None:
            return Status.NO_NEW_DATA
        if len(frame) != FRAME_LEN:
            return Status.WRONG_LENGTH
        if frame[CRC_BYTE] != frame_crc(self.data_id, frame):
            return Status.WRONG_CRC
        counter = counter_of(frame)
        delta = (counter - self.last_counter) & COUNTER_MASK
        if not self.synced:
            status, self.lost = Status.INITIAL, 0
        elif delta == 0:
            status = Status.REPEATED
        elif delta == 1:
            status, self.lost = Status.OK, 0
        else:
            status = Status.OK_SOME_LOST if delta <= self.max_delta else Status.WRONG_SEQUENCE
            self.lost = delta - 1
        self.last_counter, self.synced = counter, True
        return status


def protected_ids(db: Any, sender: str | None = None) -> dict[int, str]:
    """Frame id -> name of every frame the DBC protects (attribute CanfdiE2E
    = Crc8Counter4), of one sending node if given (e.g. "ECU")."""
    out = {}
    for m in db.messages:
        a = m.dbc.attributes.get("CanfdiE2E") if m.dbc is not None else None
        value = None if a is None else a.value
        if value in (1, "Crc8Counter4") and (sender is None or sender in m.senders):
            out[m.frame_id] = m.name
    return out


def judge(rx: E2EReceiver, frame: bytes) -> tuple[Status, str]:
    """rx.check(frame) and, for a frame that may not be used, why (one line)."""
    last = rx.last_counter
    st = rx.check(frame)
    if st == Status.WRONG_LENGTH:
        why = f"length {len(frame)}, {FRAME_LEN} expected"
    elif st == Status.WRONG_CRC:
        why = f"wrong CRC 0x{frame[CRC_BYTE]:02X} (0x{frame_crc(rx.data_id, frame):02X} expected)"
    elif st == Status.REPEATED:
        why = f"counter {counter_of(frame)} repeated"
    elif st == Status.WRONG_SEQUENCE:
        why = f"counter jump {last} -> {counter_of(frame)}"
    else:
        why = ""
    return st, why
