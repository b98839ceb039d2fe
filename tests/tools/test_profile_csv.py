"""Profile files (``profile <file.csv>``, host_sim/SCENARIO.md) in the Python
tools: canfdi.profile_csv reads and checks them like host_sim's C reader, with
the same file:line messages, and the scenario reader takes the directive."""
from __future__ import annotations

import subprocess
from pathlib import Path

import pytest

from canfdi.profile_csv import ProfileError, read
from canfdi.scenario_file import SIM_BIN, ScenarioError, parse

GOOD = """# a comment before the header
t_s, speed_rad_s ,load_Nm,angle_deg,dcm_supply_V,thr_supply_V\r
0,0,0,5,48,13.5\r

0.5,50,1.5,5,46,12.0
# a comment between rows
1.0,100,3,45,44,10
1.001,100,3,80,44,10
"""


def scenario(tmp_path: Path, csv: str, text: str = "duration 1\n\nprofile p.csv\n") -> Path:
    (tmp_path / "p.csv").write_bytes(csv.encode("latin-1"))
    p = tmp_path / "t.scn"
    p.write_text(text)
    return p


def c_message(scn: Path) -> str | None:
    """The C parser's verdict (canfdi-sim --check): its message, or None if it accepts the file."""
    r = subprocess.run([str(SIM_BIN), "--check", "-s", str(scn)], capture_output=True, text=True, timeout=30)
    if r.returncode == 0:
        return None
    assert r.returncode == 2, r.stderr
    return r.stderr.strip().removeprefix("canfdi-sim: ")


def test_good_profile_reads_and_interpolates(tmp_path: Path) -> None:
    scn = parse(scenario(tmp_path, GOOD))
    p = scn.profile
    assert p is not None and scn.profile_line == 3
    assert p.names == ["speed_rad_s", "load_Nm", "angle_deg", "dcm_supply_V", "thr_supply_V"]
    assert p.t_us == [0, 500000, 1000000, 1001000]
    assert p.columns["angle_deg"] == [5, 5, 45, 80]
    assert p.at("speed_rad_s", 0.25) == pytest.approx(25.0)
    assert p.at("dcm_supply_V", 0.75) == pytest.approx(45.0)
    assert p.at("angle_deg", 1.0005) == pytest.approx(62.5)
    assert p.at("thr_supply_V", 7.0) == 10.0          # holds after the last row
    if SIM_BIN.is_file():
        assert c_message(tmp_path / "t.scn") is None


BAD = [
    ("", "p.csv: no header line"),
    ("# only a comment\n\n", "p.csv: no header line"),
    ("time,speed_rad_s\n0,0\n", "p.csv:1: header: the first column must be t_s"),
    ("t_s\n0\n", "p.csv:1: header: no quantity after t_s"),
    ("t_s,speed\n0,0\n", "p.csv:1: header: unknown column 'speed'"),
    ("t_s,load_Nm,load_Nm\n0,0,0\n", "p.csv:1: header: duplicate column 'load_Nm'"),
    ("t_s,speed_rad_s\n", "p.csv: no data rows after the header"),
    ("t_s,speed_rad_s\n0.5,0\n2,0\n", "p.csv:2: the first row must be at t_s 0, not 0.5"),
    ("t_s,speed_rad_s\n0,0\n1,0\n1,0\n2,0\n", "p.csv:4: t_s 1 is not after the previous row's 1"),
    ("t_s,speed_rad_s\n0,0\n1.5,0\n# back\n1.2,0\n2,0\n", "p.csv:5: t_s 1.2 is not after the previous row's 1.5"),
    ("t_s,speed_rad_s\n0,0\n-1,0\n", "p.csv:3: t_s -1 out of range [0, 100000]"),
    ("t_s,speed_rad_s\n0,0\nx,0\n", "p.csv:3: t_s 'x' is not a number"),
    ("t_s,speed_rad_s\n0,0\n1,fast\n", "p.csv:3: speed_rad_s 'fast' is not a number"),
    ("t_s,speed_rad_s\n0,0\n1,nan\n", "p.csv:3: speed_rad_s 'nan' is not a number"),
    ("t_s,speed_rad_s\n0,0\n1,\n", "p.csv:3: speed_rad_s '' is not a number"),
    ("t_s,speed_rad_s\n0,0\n1,2,3\n", "p.csv:3: 3 fields, the header has 2"),
    ("t_s,speed_rad_s,load_Nm\n0,0\n", "p.csv:2: 2 fields, the header has 3"),
    ("t_s,speed_rad_s\n0,0\n1,401\n", "p.csv:3: speed_rad_s 401 out of range [-400, 400]"),
    ("t_s,angle_deg\n0,-0.5\n", "p.csv:2: angle_deg -0.5 out of range [0, 90]"),
    ("t_s,load_Nm\n0,-10.5\n", "p.csv:2: load_Nm -10.5 out of range [-10, 10]"),
    ("t_s,dcm_supply_V\n0,81\n", "p.csv:2: dcm_supply_V 81 out of range [0, 80]"),
    ("t_s,thr_supply_V\n0,17\n", "p.csv:2: thr_supply_V 17 out of range [0, 16]"),
    ("t_s,speed_rad_s\n0,0\n1,\xe9\n", "p.csv:3: non-printable or non-ASCII character (byte 0xE9)"),
    ("t_s,speed_rad_s\n0,0\n1," + "0" * 300 + "1\n", "p.csv:3: line longer than 256 characters"),
]


@pytest.mark.parametrize("csv,needle", BAD)
def test_bad_profile_names_file_line_and_scenario_line(tmp_path: Path, csv: str, needle: str) -> None:
    scn = scenario(tmp_path, csv)
    with pytest.raises(ScenarioError) as e:
        parse(scn)
    msg = str(e.value)
    assert msg.startswith(f"{tmp_path}/{needle}"), msg
    assert msg.endswith(f"(profile of {scn}:3)"), msg
    if SIM_BIN.is_file():
        assert c_message(scn) == msg


@pytest.mark.parametrize("text,needle", [
    ("duration 3\nprofile p.csv\n", "t.scn:2: profile {d}/p.csv ends at 2 s, before the end of the scenario"),
    ("duration 1\nprofile p.csv\nprofile p.csv\n", "t.scn:3: duplicate profile"),
    ("duration 1\nprofile\n", "t.scn:2: too few arguments to 'profile <file.csv>'"),
    ("duration 1\nprofile a.csv b.csv\n", "t.scn:2: too many arguments"),
    ("duration 1\nparam dcm_supply_V 40\nprofile p.csv\n",
     "t.scn:3: profile {d}/p.csv has a dcm_supply_V column and the scenario sets param dcm_supply_V"),
    ("duration 1\nprofile p.csv\nparam thr_supply_V 12\n",
     "t.scn:2: profile {d}/p.csv has a thr_supply_V column and the scenario sets param thr_supply_V"),
])
def test_bad_profile_use_names_the_scenario_line(tmp_path: Path, text: str, needle: str) -> None:
    scn = scenario(tmp_path, "t_s,dcm_supply_V,thr_supply_V\n0,48,13.5\n2,48,13.5\n", text)
    with pytest.raises(ScenarioError) as e:
        parse(scn)
    msg = str(e.value)
    assert msg.startswith(f"{tmp_path}/" + needle.format(d=tmp_path)), msg
    if SIM_BIN.is_file():
        assert c_message(scn) == msg


def test_missing_profile_file(tmp_path: Path) -> None:
    scn = tmp_path / "t.scn"
    scn.write_text("duration 1\nprofile nothere.csv\n")
    with pytest.raises(ScenarioError, match=r"nothere.csv: cannot open: No such file or directory \(profile of "):
        parse(scn)
    if SIM_BIN.is_file():
        assert c_message(scn) == f"{tmp_path}/nothere.csv: cannot open: No such file or directory (profile of {scn}:2)"
    with pytest.raises(ProfileError, match="cannot open"):
        read(tmp_path / "nothere.csv")
