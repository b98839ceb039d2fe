"""canfdi-sim end to end: determinism, the candump log read back by
cantools and python-can with valid E2E counters and CRCs, communication
faults as defined, and clean errors on bad input."""
from __future__ import annotations

import csv
import subprocess
from collections import defaultdict
from pathlib import Path

import can
import cantools
import pytest
from crccheck.crc import Crc8SaeJ1850

from conftest import DBC, ROOT, SCENARIOS, RunFn

DCM_ID, THR_ID, STATUS_ID = 0x010, 0x011, 0x610


def e2e_crc(frame_id: int, data: bytes) -> int:
    """CRC-8 SAE J1850 over the data ID (low byte first) and bytes 1..7."""
    return Crc8SaeJ1850.calc(bytes([frame_id & 0xFF, frame_id >> 8]) + data[1:])


def simulate(run: RunFn, tmp_path: Path, scenario: str, *extra: str, tag: str = "a"):
    trace = tmp_path / f"{tag}.csv"
    log = tmp_path / f"{tag}.log"
    run(["-q", "-s", str(SCENARIOS / scenario), "-o", str(trace), "-l", str(log), *extra])
    return trace, log


def test_crc_reference_value() -> None:
    # The catalogue's check value: CRC-8 SAE J1850 of "123456789" is 0x4B.
    assert Crc8SaeJ1850.calc(b"123456789") == 0x4B


def test_help_and_fault_list(run: RunFn) -> None:
    out = run(["--help"]).stdout
    for flag in ("-s, --scenario", "-o, --output", "-l, --log", "--seed", "--duration",
                 "Examples:"):
        assert flag in out
    listing = run(["--list-faults"]).stdout
    names = [row["name"] for row in csv.DictReader(open(ROOT / "dbc" / "faults.csv"))]
    assert len(names) == 32
    for name in names:
        assert f" {name} " in listing


def test_same_seed_same_bytes_different_seed_different_noise(run: RunFn, tmp_path: Path) -> None:
    t1, l1 = simulate(run, tmp_path, "nominal.scn", "-d", "2", tag="a")
    t2, l2 = simulate(run, tmp_path, "nominal.scn", "-d", "2", tag="b")
    t3, _ = simulate(run, tmp_path, "nominal.scn", "-d", "2", "--seed", "99", tag="c")
    assert t1.read_bytes() == t2.read_bytes()
    assert l1.read_bytes() == l2.read_bytes()
    rows1 = list(csv.DictReader(open(t1)))
    rows3 = list(csv.DictReader(open(t3)))
    assert len(rows1) == len(rows3) == 2000
    # Noise differs: the measured current differs in most rows (sigma 0.02 A
    # is ~1.4 LSB, so identical readings happen but not often).
    differ = sum(r1["m_dcm_ia_A"] != r3["m_dcm_ia_A"] for r1, r3 in zip(rows1, rows3))
    assert differ > len(rows1) // 2
    # The scenario's own seed (1) given explicitly reproduces the run.
    t4, _ = simulate(run, tmp_path, "nominal.scn", "-d", "2", "--seed", "1", tag="d")
    assert t4.read_bytes() == t1.read_bytes()


def test_log_decodes_with_cantools_cli(run: RunFn, tmp_path: Path, python: str) -> None:
    _, log = simulate(run, tmp_path, "nominal.scn", "-d", "1")
    lines = log.read_text().splitlines()
    assert len(lines) == 2 * 1000 + 10  # two sensor frames per ms, status every 100 ms
    proc = subprocess.run([python, "-m", "cantools", "decode", "--single-line", str(DBC)],
                          input=log.read_text(), capture_output=True, text=True, check=True,
                          timeout=300)
    out = proc.stdout.splitlines()
    assert len(out) == len(lines)
    names = {"010": "DcmSensor(", "011": "ThrSensor(", "610": "SimPlantStatus("}
    for src, dec in zip(lines, out):
        frame_id = src.split()[2].split("#")[0]
        assert dec.startswith(src + " :: " + names[frame_id]), dec


def test_log_reads_with_python_can_and_e2e_is_valid(run: RunFn, tmp_path: Path) -> None:
    trace, log = simulate(run, tmp_path, "prbs_identification.scn", "-d", "3", "--epoch",
                          "1700000000")
    db = cantools.database.load_file(str(DBC))
    msgs = list(can.LogReader(str(log)))
    assert len(msgs) == 2 * 3000 + 30
    counters: dict[int, list[int]] = defaultdict(list)
    times: dict[int, list[float]] = defaultdict(list)
    for m in msgs:
        assert not m.is_extended_id and m.channel == "vcan0"
        times[m.arbitration_id].append(m.timestamp)
        if m.arbitration_id in (DCM_ID, THR_ID):
            data = bytes(m.data)
            assert m.dlc == 8
            assert data[0] == e2e_crc(m.arbitration_id, data), f"bad CRC at {m.timestamp}"
            counters[m.arbitration_id].append(data[1] & 0x0F)
    for fid in (DCM_ID, THR_ID):
        seq = counters[fid]
        assert len(seq) == 3000
        assert all((b - a) % 16 == 1 for a, b in zip(seq, seq[1:])), "counter not +1 mod 16"
        ts = times[fid]
        assert ts[0] == pytest.approx(1700000000.0)
        assert all(abs((b - a) - 0.001) < 1e-6 for a, b in zip(ts, ts[1:]))
    assert len(times[STATUS_ID]) == 30
    # The frames carry the trace's measured values (within one DBC LSB; the
    # codec truncates to the raw value below).
    rows = {r["t_s"]: r for r in csv.DictReader(open(trace))}
    checked = 0
    for m in msgs:
        t = f"{m.timestamp - 1700000000.0:.3f}"
        if m.arbitration_id == DCM_ID:
            sig = db.decode_message(m.arbitration_id, m.data)
            assert 0.0 <= float(rows[t]["m_dcm_speed_rad_s"]) - sig["DcmOmega"] < 0.1 + 1e-6
            assert 0.0 <= float(rows[t]["m_dcm_ia_A"]) - sig["DcmIa"] < 0.0075 + 1e-6
            checked += 1
        elif m.arbitration_id == THR_ID:
            sig = db.decode_message(m.arbitration_id, m.data)
            assert 0.0 <= float(rows[t]["m_thr_tps1_V"]) - sig["ThrTps1"] < 0.001 + 1e-6
            assert abs(sig["ThrTps1"] + sig["ThrTps2"] - 5.0) < 0.05  # opposite slopes
            checked += 1
        else:
            sig = db.decode_message(m.arbitration_id, m.data, decode_choices=False)
            assert sig["PstSimTime"] == pytest.approx(float(t), abs=1e-9)
            assert sig["PstSimMode"] == 2  # offline
    assert checked == 6000


def test_comm_faults_damage_exactly_their_frames(run: RunFn, tmp_path: Path) -> None:
    _, log = simulate(run, tmp_path, "comm_faults.scn")
    bad_crc = {DCM_ID: [], THR_ID: []}
    seen = defaultdict(list)
    for m in can.LogReader(str(log)):
        if m.arbitration_id in (DCM_ID, THR_ID):
            data = bytes(m.data)
            seen[m.arbitration_id].append(m.timestamp)
            if data[0] != e2e_crc(m.arbitration_id, data):
                bad_crc[m.arbitration_id].append(m.timestamp)
    # com_dcm_crc intermittent from 1 s, period 0.5 s, duty 0.2: bad CRC
    # exactly in [1 + 0.5 n, 1 + 0.5 n + 0.1)
    expected = [k / 1000 for k in range(1000, 5000) if (k - 1000) % 500 < 100]
    assert [round(t, 3) for t in bad_crc[DCM_ID]] == expected
    assert bad_crc[THR_ID] == []
    # com_thr_timeout abrupt at 3 s: ThrSensor stops, DcmSensor goes on
    assert round(max(seen[THR_ID]), 3) == 2.999
    assert len(seen[DCM_ID]) == 5000


def test_trace_columns_and_fault_column(run: RunFn, tmp_path: Path) -> None:
    trace, _ = simulate(run, tmp_path, "dcm_ra_up.scn", "-d", "5", "-D", "10")
    rows = list(csv.DictReader(open(trace)))
    assert len(rows) == 500
    for col in ("t_s", "sp_speed_rad_s", "dcm_winding_C", "dcm_ra_ohm", "thr_angle_deg",
                "m_thr_tps1_V", "faults"):
        assert col in rows[0]
    by_t = {r["t_s"]: r for r in rows}
    assert by_t["2.990"]["faults"] == ""
    assert by_t["3.010"]["faults"] == "dcm_ra_up"
    # incipient: R_A grows by 0.2/4 s relative from 3 s (winding at 52.3 C)
    r0 = float(by_t["2.990"]["dcm_ra_ohm"])
    r5 = float(by_t["4.990"]["dcm_ra_ohm"])
    assert r5 / r0 == pytest.approx(1.0 + 0.2 * 1.99 / 4.0, rel=2e-3)  # warming adds < 0.2 %


BAD = {
    "unknown_directive.scn": ("duration 1\nwobble 3\n", 2, "unknown directive"),
    "bad_number.scn": ("duration 1\nspeed step 0 fast\n", 2, "not a number"),
    "unknown_fault.scn": ("duration 2\n# c\nfault 1 dcm_ra_upp abrupt 0.2\n", 3, "unknown fault"),
    "mode_not_allowed.scn": ("duration 2\nfault 1 thr_jammed incipient 1 0.5\n", 2, "not allowed"),
    "range.scn": ("duration 2\nnoise thr_tps1 7\n", 2, "out of range"),
    "late_fault.scn": ("duration 2\nfault 3 dcm_ra_up abrupt 0.2\n", 2, "after the end"),
    "binary.scn": ("duration 1\nspeed const \x01\x02\n", 2, "non-printable"),
}


@pytest.mark.parametrize("name", sorted(BAD))
def test_bad_scenario_is_a_clean_error(run: RunFn, tmp_path: Path, name: str) -> None:
    text, line, needle = BAD[name]
    path = tmp_path / name
    path.write_text(text)
    proc = run(["-s", str(path), "-o", str(tmp_path / "t.csv")], check=False)
    assert proc.returncode == 2
    assert f"{path}:{line}: " in proc.stderr and needle in proc.stderr, proc.stderr
    assert not (tmp_path / "t.csv").exists()  # nothing written for bad input


@pytest.mark.parametrize("args,needle", [
    ([], "no scenario"),
    (["-s", "does/not/exist.scn"], "cannot open"),
    (["-s", str(SCENARIOS / "nominal.scn"), "--seed", "-3"], "--seed"),
    (["-s", str(SCENARIOS / "nominal.scn"), "-d", "0"], "--duration"),
    (["-s", str(SCENARIOS / "nominal.scn"), "--bogus"], "Try 'canfdi-sim --help'"),
    (["-s", str(SCENARIOS / "nominal.scn"), "extra"], "unexpected argument"),
])
def test_bad_usage_is_a_clean_error(run: RunFn, args: list[str], needle: str) -> None:
    proc = run(args, check=False)
    assert proc.returncode == 2
    assert needle in proc.stderr


def test_every_example_checks(run: RunFn) -> None:
    for scn in sorted(SCENARIOS.glob("*.scn")):
        out = run(["--check", "-s", str(scn)]).stdout
        assert "duration" in out
