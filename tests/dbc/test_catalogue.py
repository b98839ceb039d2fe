"""dbc/faults.csv and dbc/dtcs.csv, their readers and the generated tables."""
from __future__ import annotations

import re

import pytest

import gen_tables
from canfdi import catalogue
from conftest import ROOT

# The agreed catalogue (ids and names are fixed by the team agreement).
AGREED = ["none", "dcm_ra_up", "dcm_flux_down", "dcm_friction_up", "dcm_ia_sensor_offset",
          "dcm_speed_sensor_gain", "dcm_speed_sensor_offset", "dcm_ua_sensor_offset",
          "dcm_bridge_a_dead", "dcm_bridges_dead", "thr_tps1_open", "thr_tps1_short",
          "thr_tps2_open", "thr_tps2_short", "thr_tps1_drift", "thr_tps2_drift",
          "thr_spring_weak", "thr_friction_up", "thr_motor_r_up", "thr_motor_open", "thr_jammed",
          "thr_tps_both_lost", "com_dcm_timeout", "com_thr_timeout", "com_dcm_counter",
          "com_thr_counter", "com_dcm_crc", "com_thr_crc", "com_dcm_length", "com_thr_length",
          "com_dcm_implausible", "com_thr_implausible"]


def test_ids_and_names_as_agreed():
    assert [f.name for f in catalogue.load_faults()] == AGREED
    assert [f.id for f in catalogue.load_faults()] == list(range(len(AGREED)))


def test_generator_validation_accepts_the_files():
    faults, dtcs = gen_tables.load(ROOT)
    assert len(faults) == len(AGREED) and len(dtcs) == len(catalogue.load_dtcs())


def test_every_fault_dtc_exists_and_is_cross_referenced():
    dtcs = catalogue.dtc_by_code()
    for f in catalogue.load_faults():
        assert (f.dtcs == ()) == (f.id == 0), f.name
        for code in f.dtcs:
            assert code in dtcs, (f.name, code)
            assert f.id in dtcs[code].fault_ids, (f.name, code)
    for d in dtcs.values():
        for fid in d.fault_ids:
            assert d.code in catalogue.load_faults()[fid].dtcs


def test_fields_in_their_domains():
    for f in catalogue.load_faults():
        assert set(f.modes) <= set(catalogue.MODES) and f.modes, f.name
        assert f.degradation in catalogue.DEGRADATIONS
        assert f.component in gen_tables.COMPONENTS and f.kind in gen_tables.KINDS
        if f.id == 0:
            assert f.kind == "none" and f.degradation == "normal"
        elif f.is_binary:
            # binary faults ignore magnitude; a drift of "dead" has no meaning
            assert f.default_magnitude == 1 and "incipient" not in f.modes, f.name
        else:
            assert f.default_magnitude != 0 and "incipient" in f.modes, f.name
        assert f.component == {"dcm": "dc_motor", "thr": "throttle", "com": "comm",
                               "none": "none"}[f.name.split("_")[0]]


@pytest.mark.parametrize("code,value", [("P0122", 0x012200), ("P2135", 0x213500),
                                        ("U1A00", 0xDA0000), ("P1A10", 0x1A1000),
                                        ("C0035", 0x403500), ("B1234", 0x923400)])
def test_dtc_encoding(code, value):
    """SAE J2012: 2 bits letter (P=0, C=1, B=2, U=3), 2 bits digit, 3 hex digits."""
    assert catalogue.encode_dtc(code) == value == gen_tables.encode_dtc(code)
    assert catalogue.decode_dtc(value) == code


def test_dtc_hex_column_matches_encoding():
    for d in catalogue.load_dtcs():
        assert d.uds_dtc == catalogue.encode_dtc(d.code), d.code
    assert len({d.uds_dtc for d in catalogue.load_dtcs()}) == len(catalogue.load_dtcs())


def test_standard_codes_where_they_exist():
    by_name = catalogue.fault_by_name()
    expect = {"thr_tps1_open": ("P0122",), "thr_tps1_short": ("P0123",), "thr_tps2_open": ("P0222",),
              "thr_tps2_short": ("P0223",), "thr_friction_up": ("P0638",), "thr_motor_open": ("P2100",),
              "thr_motor_r_up": ("P2101",), "thr_jammed": ("P2119",),
              "thr_tps_both_lost": ("P0122", "P0222")}
    for name, codes in expect.items():
        assert by_name[name].dtcs == codes
    assert "P2135" in catalogue.dtc_by_code()


def test_generated_defines_match_csv():
    for path in ("host_sim/gen/canfdi_faults.h", "firmware/catalogue/canfdi_catalogue.h"):
        text = (ROOT / path).read_text()
        ids = {m[1]: int(m[2]) for m in re.finditer(r"#define CANFDI_FAULT_(\w+)\s+(\d+)U", text)}
        assert {k: v for k, v in ids.items() if k != "COUNT"} == \
            {f.name.upper(): f.id for f in catalogue.load_faults()}, path
        dtcs = {m[1]: int(m[2], 16) for m in re.finditer(r"#define CANFDI_DTC_([PCBU][0-3][0-9A-F]{3})\s+0x([0-9A-F]+)UL", text)}
        assert dtcs == {d.code: d.uds_dtc for d in catalogue.load_dtcs()}, path


def test_generator_rejects_broken_catalogue(tmp_path):
    """The generator's validation can fail: a DTC missing from dtcs.csv."""
    (tmp_path / "dbc").mkdir()
    faults = (ROOT / "dbc/faults.csv").read_text().replace(",P2119,", ",P2999,")
    (tmp_path / "dbc/faults.csv").write_text(faults)
    (tmp_path / "dbc/dtcs.csv").write_text((ROOT / "dbc/dtcs.csv").read_text())
    with pytest.raises(gen_tables.CatalogueError, match="P2999"):
        gen_tables.load(tmp_path)
    assert gen_tables.main(["--root", str(tmp_path), "--out", str(tmp_path / "out")]) == 1
