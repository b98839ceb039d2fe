"""canfdi-watch on recorded logs and on a live (virtual) bus: output and exit status."""
from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from canfdi.watch import main

from conftest import Replayer, as_lockstep, forge_ecu_frames, sil_msgs


@pytest.mark.parametrize("args,rc,needle", [
    (["--expect", "P0122", "--within", "3.009"], 0, "PASS  P0122 appeared at 3.009 s"),
    (["--expect", "P0122", "--within", "3.008"], 1, "FAIL  P0122 did not appear within 3.008 s"),
    (["--expect", "P0123"], 1, "FAIL  P0123 never appeared"),
    (["--forbid", "P0222", "--forbid", "U1A01"], 0, "PASS  none of P0222, U1A01 appeared"),
    (["--forbid", "P0122"], 1, "FAIL  forbidden P0122 appeared at 3.009 s"),
    (["--expect", "P0122", "--forbid", "P0222", "--within", "5"], 0, "PASS  none of P0222 appeared"),
    (["--expect", "P0122", "--duration", "2"], 1, "FAIL  P0122 never appeared (watched 0.000-2.001 s)"),
])
def test_log_exit_status(sil_run, capsys: pytest.CaptureFixture[str], args: list[str], rc: int, needle: str) -> None:
    assert main(["--log", str(sil_run("tps1_open").log), "-q"] + args) == rc
    assert needle in capsys.readouterr().out


def test_log_timeline_for_a_technician(sil_run, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["--log", str(sil_run("tps_both_lost").log), "--residuals", "1"]) == 0
    out = capsys.readouterr().out
    assert "P0122 confirmed    Throttle position sensor A (TPS1) circuit low" in out
    assert "degradation thr: normal -> fail_safe" in out or "-> fail_safe" in out
    assert "thr: motor de-energised (spring -> limp-home)" in out
    assert "max|r|" in out and "frames from" in out


def test_usage_errors_exit_2(tmp_path: Path) -> None:
    r = subprocess.run([sys.executable, "-m", "canfdi.watch", "--log", str(tmp_path / "none.log")],
                       capture_output=True, text=True, timeout=60)
    assert r.returncode == 2 and "no such file" in r.stderr
    r = subprocess.run([sys.executable, "-m", "canfdi.watch", "--expect", "P9999"],
                       capture_output=True, text=True, timeout=60)
    assert r.returncode == 2 and "unknown trouble code" in r.stderr and "Traceback" not in r.stderr


def test_corrupted_log_counted_clear_message_no_traceback(sil_run, tmp_path: Path) -> None:
    lines = sil_run("tps1_open").log.read_text().splitlines()
    log = tmp_path / "cut.log"
    log.write_text("\n".join(lines[:5000] + ["\x00\x01 binary junk", "(12.5) vcan0 310#ZZ"] + lines[5000:]) + "\n")
    r = subprocess.run([sys.executable, "-m", "canfdi.watch", "--log", str(log), "-q", "--expect", "P0122"],
                       capture_output=True, text=True, timeout=60)
    assert r.returncode == 0, r.stdout + r.stderr
    assert "2 unreadable line(s) skipped (first: " in r.stderr and "cut.log:5001" in r.stderr
    assert "Traceback" not in r.stderr
    empty = tmp_path / "junk.log"
    empty.write_text("not a candump log\n")
    r = subprocess.run([sys.executable, "-m", "canfdi.watch", "--log", str(empty)],
                       capture_output=True, text=True, timeout=60)
    assert r.returncode == 1 and "holds no readable frame" in r.stderr and "Traceback" not in r.stderr


def test_live_virtual_bus(sil_run, channel: str, capsys: pytest.CaptureFixture[str]) -> None:
    rp = Replayer(channel, as_lockstep(sil_msgs(sil_run("tps1_open").log)), listeners=2)
    rp.start()
    rc = main(["-i", "virtual", "-c", channel, "--expect", "P0122", "--within", "3.013", "--timeout", "60"])
    rp.join(timeout=60)
    out = capsys.readouterr().out
    assert rc == 0, out
    assert "PASS  P0122 appeared at 3.009 s" in out
    assert "listening on virtual" in out


#: What the forged frames of forge_ecu_frames would have shown, decoded as
#: if they were the ECU's: none of it may appear.
FORGED_CLAIMS = ("fault#102", "193 %", "P0222", "U1A00", "power stage A -> B", "power stage A -> none",
                 "degradation dcm", "-> fail_safe", "limp-home ON")


def write_log(msgs, path: Path) -> Path:
    with path.open("w") as f:
        for m in msgs:
            f.write(f"({m.timestamp:.6f}) vcan0 {m.arbitration_id:03X}#{bytes(m.data).hex().upper()}\n")
    return path


def assert_flagged_not_decoded(out: str) -> None:
    """The forged frames are listed with identifier and reason, nothing of
    their content is shown; the ECU's own diagnosis still is."""
    assert "0x301 EcuDiagnosis forged or corrupted: wrong CRC" in out
    assert "0x310 EcuDtc forged or corrupted: wrong CRC" in out
    assert "0x300 EcuStatus forged or corrupted: counter jump" in out     # a second counter sequence
    assert "0x310 EcuDtc forged or corrupted: counter jump" in out
    for claim in FORGED_CLAIMS:
        assert claim not in out, claim
    assert "P0122 confirmed" in out and "diagnosis thr: thr_tps1_open (100 % confidence)" in out


def test_forged_ecu_frames_in_a_log_are_flagged(sil_run, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """A node forging the ECU's identifiers (EcuDiagnosis, EcuDtc with a wrong
    CRC; EcuStatus, EcuDtc with a right CRC but a second counter sequence; a
    DcmActuator out of sequence): every such frame is reported as forged or
    corrupted with its identifier and reason, never as a diagnosis, status
    change, power-stage switch or trouble code; the watch fails."""
    log = write_log(forge_ecu_frames(sil_msgs(sil_run("tps1_open").log)), tmp_path / "forged.log")
    assert main(["--log", str(log)]) == 1
    out = capsys.readouterr().out
    assert_flagged_not_decoded(out)
    assert "0x020 DcmActuator forged or corrupted: counter jump 0 -> 8" in out
    assert "FAIL  14 ECU frame(s) forged or corrupted (E2E check failed, not decoded): 0x020 DcmActuator 2 " in out
    # a check that holds still fails on the forged frames; -q keeps the verdicts
    assert main(["--log", str(log), "-q", "--forbid", "P0222"]) == 1
    out = capsys.readouterr().out
    assert "PASS  none of P0222 appeared" in out and "FAIL  14 ECU frame(s) forged or corrupted" in out
    # the untouched log passes
    assert main(["--log", str(sil_run("tps1_open").log), "-q", "--forbid", "P0222"]) == 0


def test_forged_ecu_frames_live_are_flagged(sil_run, channel: str, capsys: pytest.CaptureFixture[str]) -> None:
    msgs = forge_ecu_frames(sil_msgs(sil_run("tps1_open").log))
    rp = Replayer(channel, as_lockstep(msgs), listeners=2)
    rp.start()
    rc = main(["-i", "virtual", "-c", channel, "--duration", "5.9", "--timeout", "60"])
    rp.join(timeout=60)
    out = capsys.readouterr().out
    assert rc == 1, out
    assert_flagged_not_decoded(out)
