"""canfdi-scenario without vcan: the scenario reader, process start/stop with
stub programs, and the whole record-and-judge path with --no-start on the
virtual interface fed by a lockstep replay of a SIL log."""
from __future__ import annotations

import json
import stat
import sys
from pathlib import Path

import pytest

from canfdi.hil import ProcError, start_ecu, start_sim
from canfdi.scenario_file import ScenarioError, check_with_c, parse
from canfdi.scenario_run import main

from conftest import Replayer, as_lockstep, forge_ecu_frames, sil_msgs

STUB_ECU = """#!{py}
import signal, sys, time
mode = "{mode}"
signal.signal(signal.SIGTERM, lambda *a: sys.exit(0))   # before 'ready', as canfdi-ecu must
if mode == "exit":
    print("canfdi-ecu: cannot open vcan0: No such device", file=sys.stderr); sys.exit(1)
if mode == "ready":
    print("canfdi-ecu: ready on vcan0 (lockstep)", file=sys.stderr, flush=True)
while True:
    time.sleep(0.05)
"""


def stub(tmp_path: Path, name: str, mode: str) -> Path:
    """An executable that behaves like canfdi-ecu in one way (mode)."""
    p = tmp_path / name
    p.write_text(STUB_ECU.format(py=sys.executable, mode=mode))
    p.chmod(p.stat().st_mode | stat.S_IXUSR)
    return p


def write(tmp_path: Path, text: str) -> Path:
    p = tmp_path / "t.scn"
    p.write_text(text)
    return p


@pytest.mark.parametrize("text,needle", [
    ("fault 1 dcm_ra_up abrupt 0.2\n", "no duration"),
    ("duration 5\nfault 1 dcm_ra_upp abrupt 0.2\n", "t.scn:2: unknown fault 'dcm_ra_upp'"),
    ("duration 5\nfault 1 thr_jammed incipient 1 2\n", "t.scn:2: fault thr_jammed cannot be incipient"),
    ("duration 5\n\nexpect 3 dtc P9999\n", "t.scn:3: unknown trouble code 'P9999'"),
    ("duration 5\nexpect 6 no_dtc\n", "t.scn:2: expectation after the end"),
    ("duration 5\nexpect 3 degradation dcm broken\n", "t.scn:2: degradation 'broken' must be"),
    ("duration 5\nwobble 3\n", "t.scn:2: unknown directive 'wobble'"),
    ("duration 5\nexpect 1 dtc_status P0122 TF=2\n", "t.scn:2: status bits 'TF=2': TF must be 0 or 1"),
    ("duration 5\nexpect 1 dtc_status P0122 TF=1,\n", "t.scn:2: status bits 'TF=1,': TF must be 0 or 1"),
    ("duration 5\nexpect 1 dtc_status P0122 XX=1\n", "t.scn:2: status bits 'XX=1': expected NAME=0"),
    ("duration 5\nexpect 1 dtc_status P0122 TF=1,TF=0\n", "t.scn:2: status bits 'TF=1,TF=0': TF named twice"),
    ("duration 5\nexpect 1 dtc_status P0122 0x1FF\n", "t.scn:2: status byte '0x1FF' must be"),
    ("duration 5\nexpect 1 occurrence P0122 256\n", "t.scn:2: occurrence '256' must be an integer 0..255"),
    ("duration 5\nexpect 1 freeze P0122 rpm 1 2\n", "t.scn:2: unknown freeze-frame signal 'rpm'"),
    ("duration 5\nexpect 1 freeze P0122 time 2 1\n", "t.scn:2: freeze max .1. below min .2."),
    ("duration 5\ncycle 5\n", "t.scn:2: action at or after the end"),
    ("duration 5\ncycle 2\nclear 1\n", "t.scn:3: clear at 1 s is before the previous"),
    ("duration 5\nclear 1 P9999\n", "t.scn:2: unknown trouble code 'P9999'"),
    ("duration 5\npower_cycle 1 2\n", "t.scn:2: power_cycle <t>"),
    ("duration 5\nuds 1 phys\n", "t.scn:2: too few arguments"),
    ("duration 5\nuds 1 can 3E 00\n", "t.scn:2: addressing 'can'"),
    ("duration 5\nuds 1 phys 3E 0\n", "t.scn:2: '0' is not a hex byte"),
    ("duration 5\nuds 1 phys expect 7E\n", "t.scn:2: uds: no request bytes"),
    ("duration 5\nuds 1 phys 3E expect\n", "t.scn:2: expect what"),
    ("duration 5\nuds 1 phys 3E expect none 00\n", "t.scn:2: nothing may follow"),
    ("duration 5\nuds 1 func 22 D1 00 D1 01 D1 02 D1\n", "t.scn:2: a functional request is one single frame"),
    ("duration 5\nuds 2 phys 3E 00\nuds 1 phys 3E 00\n", "t.scn:3: uds at 1 s is before"),
    ("duration 5\nuds 5 phys 3E 00\n", "t.scn:2: uds request at or after the end"),
])
def test_scenario_errors_name_file_and_line(tmp_path: Path, text: str, needle: str) -> None:
    with pytest.raises(ScenarioError, match=needle.replace("(", r"\(")):
        parse(write(tmp_path, text))


def test_dtc_directives_parse_like_c(tmp_path: Path) -> None:
    text = ("duration 5\ncycle 1\nclear 2\nclear 2 P0122\nclear 2.5 all\npower_cycle 3.0004\n"
            "expect 1 dtc_status P0122 TF=1,WIR=0,TNCTOC=1\nexpect 1 dtc_status U1A01 0xaf\n"
            "expect 2 occurrence P0122 3\nexpect 3 freeze P0122 thr_angle -1 25.5\n")
    p = write(tmp_path, text)
    scn = parse(p)
    assert [(a.kind, a.t_us, a.code, a.line) for a in scn.actions] == [
        ("cycle", 1000000, "", 2), ("clear", 2000000, "", 3), ("clear", 2000000, "P0122", 4),
        ("clear", 2500000, "", 5), ("power_cycle", 3000400, "", 6)]
    e = scn.expects
    assert (e[0].mask, e[0].value, e[1].mask, e[1].value) == (0xC1, 0x41, 0xFF, 0xAF)
    assert (e[2].kind, e[2].lo, e[3].arg2, e[3].lo, e[3].hi) == ("occurrence", 3.0, "thr_angle", -1.0, 25.5)
    assert [w.split(": ")[-1] for w in scn.sil_only] == ["cycle", "clear", "clear", "clear", "power_cycle",
                                                         "expect freeze"]
    assert check_with_c(p) is None
    # bus-only expectations: nothing SIL-only
    assert not parse(write(tmp_path, "duration 5\nexpect 1 dtc_status P0122 TF=0\n")).sil_only


def test_uds_lines_parse_like_c(tmp_path: Path) -> None:
    p = write(tmp_path, "duration 5\nuds 1 phys 3E 00 expect 7E 00\nuds 2 func 3E 80 expect none\n"
                        "uds 2.5 phys 19 02 ff expect 59 02 FF .. *\nuds 3 phys 22 F1 95\n")
    scn = parse(p)
    u = scn.uds
    assert [(x.line, x.t_us, x.functional, x.request.hex()) for x in u] == [
        (2, 1000000, False, "3e00"), (3, 2000000, True, "3e80"), (4, 2500000, False, "1902ff"), (5, 3000000, False, "22f195")]
    assert u[0].matches(bytes([0x7E, 0x00])) and not u[0].matches(bytes([0x7E, 0x00, 0x00]))
    assert u[1].none and not u[1].matches(b"\x7e\x00")
    assert u[2].any_tail and u[2].matches(bytes([0x59, 0x02, 0xFF, 0x01, 0x22, 0x00, 0x2F]))
    assert not u[2].matches(bytes([0x59, 0x02, 0xFF]))
    assert not u[3].judged and u[3].matches(b"")
    assert [w.split(": ")[-1] for w in scn.sil_only] == ["uds"] * 4
    assert check_with_c(p) is None


def test_sil_only_scenario_refused_exit_2(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["tests/sil/scenarios/dtc_new_cycle.scn"]) == 2
    err = capsys.readouterr().err
    assert "dtc_new_cycle.scn:" in err and ": cycle needs the SIL rig: cycle/clear are not sent over the bus yet" in err
    assert main([str(write(tmp_path, "duration 5\nexpect 1 freeze P0122 time 0 1\n"))]) == 2
    assert "t.scn:2: expect freeze needs the SIL rig" in capsys.readouterr().err


def test_scenario_parts_and_c_parser_agree(tmp_path: Path) -> None:
    scn = parse(Path("tests/sil/scenarios/tps_both_lost.scn"))
    assert scn.duration_us > 0 and scn.faults[0].name == "thr_tps_both_lost"
    assert {e.kind for e in scn.expects} >= {"dtc", "degradation"}
    assert check_with_c(Path("tests/sil/scenarios/tps_both_lost.scn")) is None
    msg = check_with_c(write(tmp_path, "duration 5\nfault 1 dcm_ra_upp abrupt 0.2\n"))
    assert msg is None or "unknown fault 'dcm_ra_upp'" in msg   # None when canfdi-sim is not built


def test_ecu_ready_handshake_and_sigterm(tmp_path: Path) -> None:
    ecu = start_ecu(stub(tmp_path, "ecu", "ready"), "vcan0", ready_timeout_s=10)
    assert ecu.poll() is None and ecu.lines == ["canfdi-ecu: ready on vcan0 (lockstep)"]
    assert ecu.stop() == 0


def test_ecu_exit_and_silence_are_clear_errors(tmp_path: Path) -> None:
    with pytest.raises(ProcError, match="exited with status 1 before it was ready: canfdi-ecu: cannot open vcan0"):
        start_ecu(stub(tmp_path, "ecu1", "exit"), "vcan0")
    with pytest.raises(ProcError, match="did not say 'canfdi-ecu: ready on ...' within 0.5 s; killed"):
        start_ecu(stub(tmp_path, "ecu2", "silent"), "vcan0", ready_timeout_s=0.5)
    with pytest.raises(ProcError, match="cannot start canfdi-ecu"):
        start_ecu(tmp_path / "missing", "vcan0")


def test_started_run_with_stub_programs(tmp_path: Path, channel: str, capsys: pytest.CaptureFixture[str]) -> None:
    """ECU ready, sim runs and exits 0, ECU stopped with SIGTERM -> nothing recorded is an error, not a hang."""
    sim = tmp_path / "sim"
    sim.write_text("#!/bin/sh\nsleep 0.3\nexit 0\n")
    sim.chmod(0o755)
    js = tmp_path / "r.json"
    rc = main(["tests/sil/scenarios/tps1_open.scn", "-i", "virtual", "-c", channel, "-q",
               "--ecu", str(stub(tmp_path, "ecu", "ready")), "--sim", str(sim),
               "--log", str(tmp_path / "r.log"), "--json", str(js)])
    assert rc == 1
    res = json.loads(js.read_text())
    assert res["errors"] == ["no SimStep frame recorded in a lockstep run (is canfdi-sim --lockstep on this bus?)"]
    assert "ERROR no SimStep" in capsys.readouterr().out


def test_sim_command_line(tmp_path: Path) -> None:
    args = tmp_path / "args"
    sim = tmp_path / "sim"
    sim.write_text(f'#!/bin/sh\necho "$@" > {args}\n')
    sim.chmod(0o755)
    p = start_sim(sim, "vcan3", Path("x.scn"), lockstep=False, seed=7)
    p.popen.wait(timeout=10)
    assert args.read_text().split() == ["--can", "vcan3", "-s", "x.scn", "--realtime", "-q", "--seed", "7"]


def run_no_start(channel: str, log_msgs: list, tmp_path: Path, scn: str, drop=frozenset()) -> tuple[int, dict]:
    rp = Replayer(channel, as_lockstep(log_msgs, drop), listeners=2)
    rp.start()
    js = tmp_path / "r.json"
    rc = main([scn, "--no-start", "-i", "virtual", "-c", channel, "--log", str(tmp_path / "rec.log"),
               "--json", str(js), "--timeout", "120"])
    rp.join(timeout=60)
    return rc, json.loads(js.read_text())


@pytest.mark.parametrize("name", ["tps1_open", "bridge_a_dead"])
def test_no_start_records_and_judges_like_sil(sil_run, channel: str, tmp_path: Path, name: str,
                                              capsys: pytest.CaptureFixture[str]) -> None:
    run = sil_run(name)
    rc, res = run_no_start(channel, sil_msgs(run.log), tmp_path, str(run.rel))
    out = capsys.readouterr().out
    assert rc == 0, out
    assert [ln for ln in out.splitlines() if ln.startswith(("PASS ", "FAIL "))] == run.verdict_lines
    assert res["passed"] and res["mode"] == "lockstep" and not res["errors"]
    assert res["steps"] == parse(run.rel).steps
    assert all(e["ok"] for e in res["expectations"])
    # the recording is a candump log python-can and cantools can read
    import can
    assert sum(1 for _ in can.LogReader(tmp_path / "rec.log")) == res["frames"]


def test_no_start_lost_steps_are_an_error(sil_run, channel: str, tmp_path: Path,
                                          capsys: pytest.CaptureFixture[str]) -> None:
    run = sil_run("tps1_open")
    rc, res = run_no_start(channel, sil_msgs(run.log), tmp_path, str(run.rel), frozenset({1500, 1501}))
    assert rc == 1
    assert any("2 SimStep frame(s) lost" in e for e in res["errors"])
    assert "ERROR recording incomplete: 2 SimStep frame(s) lost" in capsys.readouterr().out


def test_no_start_forged_ecu_frames_fail_the_run(sil_run, channel: str, tmp_path: Path,
                                                 capsys: pytest.CaptureFixture[str]) -> None:
    """A node forging the ECU's status, diagnosis and trouble-code frames on
    the bus of a run (wrong CRC; right CRC, second counter sequence): the
    timeline lists each as forged or corrupted and shows none of it as a
    diagnosis, degradation or code; the run fails with an error naming the
    frames, whatever its expectations say."""
    run = sil_run("tps1_open")
    rc, res = run_no_start(channel, forge_ecu_frames(sil_msgs(run.log), actuator=False), tmp_path, str(run.rel))
    out = capsys.readouterr().out
    assert rc == 1, out
    assert all(e["ok"] for e in res["expectations"]) and not res["unexpected"]
    assert [e for e in res["errors"] if "forged or corrupted" in e] == res["errors"]
    assert res["errors"][0].startswith("12 ECU frame(s) forged or corrupted (E2E check failed, not decoded): "
                                       "0x300 EcuStatus 6 (counter 6); 0x301 EcuDiagnosis 1 (CRC 1); "
                                       "0x310 EcuDtc 5 (CRC 1, counter 4)")
    assert res["e2e_failures"] == {"0x300": {"counter": 6}, "0x301": {"CRC": 1}, "0x310": {"CRC": 1, "counter": 4}}
    assert set(res["codes"]) == {"P0122"}
    assert "0x301 EcuDiagnosis forged or corrupted: wrong CRC" in out
    assert "0x300 EcuStatus forged or corrupted: counter jump" in out
    for claim in ("fault#102", "193 %", "P0222", "U1A00", "limp-home ON", "-> fail_safe"):
        assert claim not in out, claim
    assert "ERROR 12 ECU frame(s) forged or corrupted" in out


def test_missing_programs_and_bad_scenario_exit_2(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["tests/sil/scenarios/tps1_open.scn", "--ecu", str(tmp_path / "nope")]) == 2
    assert "not built" in capsys.readouterr().err
    assert main([str(write(tmp_path, "duration 5\nexpect 1 dtc P9999\n"))]) == 2
    assert "t.scn:2: unknown trouble code" in capsys.readouterr().err
