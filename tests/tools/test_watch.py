"""canfdi-watch on recorded logs and on a live (virtual) bus: output and exit status."""
from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from canfdi.watch import main

from conftest import Replayer, as_lockstep, sil_msgs


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
