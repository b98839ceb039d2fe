"""The fault catalogue and the DTC table, read from dbc/faults.csv and dbc/dtcs.csv.

    from canfdi.catalogue import load_faults, load_dtcs
    faults = load_faults()                 # list indexed by fault id
    faults[10].name, faults[10].dtcs       # 'thr_tps1_open', ('P0122',)
    fault_by_name()["thr_jammed"].degradation  # 'fail_safe'
    dtc_by_code()["P0122"].uds_dtc         # 0x012200

Standard library only. dbc/gen_tables.py validates the same files when it
generates the C tables; tests/dbc checks that both readings agree.
"""
from __future__ import annotations

import csv
import re
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

from . import REPO_ROOT

FAULTS_CSV = REPO_ROOT / "dbc" / "faults.csv"
DTCS_CSV = REPO_ROOT / "dbc" / "dtcs.csv"

MODES = ("abrupt", "incipient", "intermittent")
DEGRADATIONS = ("normal", "degraded", "fail_safe", "fail_silent")


@dataclass(frozen=True)
class Fault:
    id: int
    name: str
    component: str          # none | dc_motor | throttle | comm
    kind: str               # none | parametric | sensor | actuator | communication
    quantity: str           # what it changes ('+' joins several)
    unit: str               # 'rel' relative change, a physical unit for offsets, '-' binary
    default_magnitude: float
    modes: tuple[str, ...]  # subset of MODES
    dtcs: tuple[str, ...]   # expected trouble codes, () for none
    degradation: str        # expected degradation state for a persistent fault
    description: str

    @property
    def is_binary(self) -> bool:
        """Binary faults (dead, open, jammed, lost, comm) ignore the magnitude."""
        return self.unit == "-"


@dataclass(frozen=True)
class Dtc:
    code: str               # e.g. 'P0122'
    uds_dtc: int            # ISO 14229-1 3-byte value, e.g. 0x012200
    severity: str
    fault_ids: tuple[int, ...]
    description: str


def encode_dtc(code: str, failure_type: int = 0) -> int:
    """3-byte UDS DTC of an SAE J2012 code: 'P0122' -> 0x012200, 'U1A00' -> 0xDA0000."""
    m = re.fullmatch(r"([PCBU])([0-3])([0-9A-F]{3})", code)
    if not m or not 0 <= failure_type <= 0xFF:
        raise ValueError(f"not a J2012 DTC: {code!r}")
    return ("PCBU".index(m.group(1)) << 22) | (int(m.group(2)) << 20) \
        | (int(m.group(3), 16) << 8) | failure_type


def decode_dtc(value: int) -> str:
    """Inverse of encode_dtc (the failure type byte is ignored): 0x012200 -> 'P0122'."""
    if not 0 <= value <= 0xFFFFFF:
        raise ValueError(f"not a 3-byte DTC: {value:#x}")
    return f"{'PCBU'[value >> 22]}{(value >> 20) & 3}{(value >> 8) & 0xFFF:03X}"


@lru_cache(maxsize=None)
def load_faults(path: Path = FAULTS_CSV) -> tuple[Fault, ...]:
    """All faults, indexed by id (ids run 0.. without gaps; checked)."""
    out = []
    with Path(path).open(newline="", encoding="utf-8") as f:
        for i, row in enumerate(csv.DictReader(f)):
            fault = Fault(
                id=int(row["id"]), name=row["name"], component=row["component"],
                kind=row["kind"], quantity=row["quantity"], unit=row["unit"],
                default_magnitude=float(row["default_magnitude"]),
                modes=tuple(row["modes"].split("|")),
                dtcs=tuple(row["dtc"].split("+")) if row["dtc"] else (),
                degradation=row["degradation"], description=row["description"])
            if fault.id != i:
                raise ValueError(f"{path}: fault ids must run 0.. without gaps (row {i})")
            out.append(fault)
    return tuple(out)


@lru_cache(maxsize=None)
def load_dtcs(path: Path = DTCS_CSV) -> tuple[Dtc, ...]:
    """All DTCs in file order."""
    with Path(path).open(newline="", encoding="utf-8") as f:
        return tuple(
            Dtc(code=row["code"], uds_dtc=int(row["uds_dtc_hex"], 16), severity=row["severity"],
                fault_ids=tuple(int(x) for x in row["fault_ids"].split("|")) if row["fault_ids"] else (),
                description=row["description"])
            for row in csv.DictReader(f))


def fault_by_name() -> dict[str, Fault]:
    return {f.name: f for f in load_faults()}


def dtc_by_code() -> dict[str, Dtc]:
    return {d.code: d for d in load_dtcs()}
