"""canfdi-uds without a bus: its command line, the DTC naming, the key
(the same known answers as the firmware's unit test, tests/unit/test_uds.c)
and the generated udsoncan configuration against dbc/uds_dids.csv. The tool
on a bus is tested by tests/hil/test_uds.py."""
from __future__ import annotations

import csv
import subprocess
import sys

import pytest

from canfdi import REPO_ROOT, uds, uds_config, uds_key

# (seed, level, key): canfdi_uds_sec_key_default's answers, checked in C too
KEY_VECTORS = [(0x12345678, 1, 0x67FFB80F), (0xA4E25C5F, 1, 0x354BA250), (0x00000001, 2, 0xDCA97096)]


@pytest.mark.parametrize("seed,level,key", KEY_VECTORS)
def test_key_matches_the_firmware(seed: int, level: int, key: int) -> None:
    assert uds_key.key(seed, level) == key


def test_dtc_names_round_trip() -> None:
    rows = list(csv.DictReader(open(REPO_ROOT / "dbc" / "dtcs.csv", newline="")))
    assert len(rows) == len(uds_config.DTCS)
    for r in rows:
        dtc = int(r["uds_dtc_hex"], 16)
        assert uds.dtc_code(dtc) == r["code"]
        assert uds.code_to_dtc(r["code"]) == dtc
        assert uds_config.DTCS[dtc] == (r["code"], r["description"])
    with pytest.raises(ValueError, match="unknown trouble code"):
        uds.code_to_dtc("P9999")


def test_config_follows_the_did_table() -> None:
    rows = list(csv.DictReader(open(REPO_ROOT / "dbc" / "uds_dids.csv", newline="")))
    cfg = uds_config.client_config()
    assert cfg["standard_version"] == 2020
    assert sorted(cfg["data_identifiers"]) == sorted(int(r["did"], 16) for r in rows)
    sizes = {"ascii16": 16, "s32q16": 4, "s32q24": 4, "u8": 1, "u32": 4}
    for r in rows:
        codec = cfg["data_identifiers"][int(r["did"], 16)]
        assert len(codec) == sizes[r["format"]], r
    q16 = cfg["data_identifiers"][0xD100]
    assert q16.decode(bytes([0x00, 0x01, 0x80, 0x00])) == pytest.approx(1.5)
    assert q16.decode(q16.encode(-2.25)) == pytest.approx(-2.25)
    assert cfg["data_identifiers"][0xD202].decode(bytes([0x01, 0x00, 0x00, 0x00])) == pytest.approx(1.0)
    assert cfg["data_identifiers"][0xF195].decode(b"canfdi 14.0     ") == "canfdi 14.0"
    assert uds_config.SNAPSHOT_DIDS == [int(r["did"], 16) for r in sorted(
        (r for r in rows if r["freeze"]), key=lambda r: int(r["freeze"]))]
    assert sorted(cfg["input_output"]) == [0xD104, 0xD115]


def test_status_text_and_values() -> None:
    assert uds.status_text(0xAF) == "TF,TFTOC,PDTC,CDTC,TFSLC,WIR"
    assert uds.status_text(0) == "-"
    assert uds.fmt_value(0xD110, 0.5236) == "0.5236 rad (30.00 deg)"
    assert uds.fmt_value(0xD103, 48.0) == "48 V"


def test_help_has_examples_and_bus_flags() -> None:
    r = subprocess.run([sys.executable, "-m", "canfdi.uds", "--help"], capture_output=True, text=True,
                       cwd=REPO_ROOT / "tools", timeout=60)
    assert r.returncode == 0
    for s in ("-i INTERFACE", "-c CHANNEL", "-b BITRATE", "examples:", "canfdi-uds -c vcan0 freeze P0122",
              "actuator angle 30"):
        assert s in r.stdout, s


def test_bus_error_is_exit_2(capsys: pytest.CaptureFixture[str]) -> None:
    assert uds.main(["-i", "socketcan", "-c", "nosuchcan9", "info"]) == 2
    assert "canfdi-uds: cannot open socketcan channel nosuchcan9" in capsys.readouterr().err
