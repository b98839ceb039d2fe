"""canfdi-plot (canfdi.logplot): a PNG of a bus log from its frames alone.

The log is canfdi-sil's of the demo scenario (conftest.sil_run); the panels
are checked on the figure build_figure() returns, not on pixels.
"""
from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

from canfdi import REPO_ROOT
from canfdi.logplot import PANEL_TITLES, build_figure, main, read_plot_data
from canfdi.timeline import ID_RES_DCM, ID_STATUS

DEMO_SCN = REPO_ROOT / "tests" / "sil" / "scenarios" / "demo.scn"
PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


@pytest.fixture(scope="module")
def demo_log(sil_run) -> Path:
    return sil_run("demo").log


def _sil_first_codes(scn: Path) -> list[tuple[str, float]]:
    """(code, time) of each code's first testFailed/confirmed line in
    canfdi-sil's printed timeline, in time order."""
    sil = REPO_ROOT / "build" / "bin" / "canfdi-sil"
    out = subprocess.run([str(sil), "-s", str(scn.relative_to(REPO_ROOT))], cwd=REPO_ROOT,
                         capture_output=True, text=True, timeout=120).stdout
    first: dict[str, float] = {}
    for m in re.finditer(r"^\s+(\d+\.\d+)\s+([PCBU][0-9A-F]{4}) (?:testFailed|confirmed)", out, re.M):
        first.setdefault(m.group(2), float(m.group(1)))
    return sorted(first.items(), key=lambda kv: kv[1])


def _titles(fig) -> list[str]:
    return [a.get_title(loc="left") for a in fig.axes if a.get_title(loc="left")]


def test_png_with_all_panels(demo_log: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "demo.png"
    assert main([str(demo_log), "-o", str(out), "--title", "demo"]) == 0
    assert out.stat().st_size > 50_000
    assert out.read_bytes()[:8] == PNG_MAGIC
    assert f"wrote {out}" in capsys.readouterr().out

    data = read_plot_data(demo_log)
    fig = build_figure(data, "demo")
    assert _titles(fig) == list(PANEL_TITLES)
    assert fig.get_suptitle() == "demo"
    by_title = {a.get_title(loc="left"): a for a in fig.axes if a.get_title(loc="left")}
    labels = {t: [ln.get_label() for ln in a.get_lines()] for t, a in by_title.items()}
    assert "measured (DcmSensor omega)" in labels[PANEL_TITLES[0]]
    assert {"from TPS1", "from TPS2", "setpoint (SetpointThr)"} <= set(labels[PANEL_TITLES[1]])
    assert {"ResDcmR1", "ResDcmR4"} <= set(labels[PANEL_TITLES[3]])
    assert {"ResThrCorr", "ResThrCurrent"} <= set(labels[PANEL_TITLES[4]])
    assert "R_A estimate" in labels[PANEL_TITLES[5]]
    # +-1 threshold lines on both residual panels
    for t in PANEL_TITLES[3:5]:
        ys = {tuple(ln.get_ydata()) for ln in by_title[t].get_lines() if ln.get_label().startswith("_")}
        assert (1.0, 1.0) in ys and (-1.0, -1.0) in ys
    # the demo's trouble codes, at the times canfdi-sil's own timeline gives
    assert [(mk.label, round(mk.t_s, 3)) for mk in data.dtcs] == _sil_first_codes(DEMO_SCN)
    assert [mk.label for mk in data.dtcs] == ["P0121", "P1A10", "P1A30", "P0222"]
    texts = {t.get_text() for t in by_title[PANEL_TITLES[6]].texts}
    assert {"P0121", "P1A10", "P1A30", "P0222"} <= texts
    # degradation: both subsystems end degraded / fail_safe
    st = data.s(ID_STATUS)
    assert st.v["StsDegStateDcm"][-1] == 1 and st.v["StsDegStateThr"][-1] == 2
    assert st.v["StsActiveBridge"][-1] == 2


def test_scenario_marks_every_fault(demo_log: Path, tmp_path: Path) -> None:
    out = tmp_path / "demo.png"
    assert main([str(demo_log), "-o", str(out), "-s", str(DEMO_SCN)]) == 0
    assert out.stat().st_size > 0


def test_from_to_limits_the_range(demo_log: Path, tmp_path: Path) -> None:
    data = read_plot_data(demo_log, 10.0, 14.0)
    assert data.span is not None
    assert 10.0 <= data.span[0] < 10.02 and 13.98 < data.span[1] <= 14.0
    for series in data.series.values():
        assert all(10.0 <= t <= 14.0 for t in series.t)
    assert [mk.label for mk in data.dtcs] == ["P1A10"]
    res = data.s(ID_RES_DCM)
    assert 380 <= len(res) <= 402   # 10 ms frames over 4 s
    fig = build_figure(data, "range")
    lo, hi = fig.axes[0].get_xlim()
    assert 9.9 <= lo <= 10.0 and 14.0 <= hi <= 14.1
    out = tmp_path / "range.png"
    assert main([str(demo_log), "-o", str(out), "--from", "10", "--to", "14"]) == 0
    assert out.read_bytes()[:8] == PNG_MAGIC


def test_range_without_frames(demo_log: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main([str(demo_log), "-o", str(tmp_path / "x.png"), "--from", "100", "--to", "200"]) == 1
    assert "no canfdi frame to plot in the range asked" in capsys.readouterr().err
    assert not (tmp_path / "x.png").exists()


def test_bad_range_is_usage_error(demo_log: Path, capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as e:
        main([str(demo_log), "--from", "5", "--to", "4"])
    assert e.value.code == 2
    assert "--to 4 is not after --from 5" in capsys.readouterr().err


def test_corrupted_lines_are_counted(demo_log: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    lines = demo_log.read_text().splitlines(keepends=True)[:20000]
    lines[5] = "this is not a frame\n"
    lines[700] = lines[700][:17] + "\n"          # cut mid-line
    lines.append(lines[-1][:33])                  # truncated last line (odd hex), no newline
    bad = tmp_path / "bad.log"
    bad.write_text("".join(lines))
    out = tmp_path / "bad.png"
    assert main([str(bad), "-o", str(out)]) == 0
    err = capsys.readouterr().err
    assert f"3 unreadable line(s) skipped (first: {bad}:6: " in err
    assert "Traceback" not in err
    assert out.stat().st_size > 0


@pytest.mark.parametrize("content", [b"\x00\xff garbage \x13\n" * 50, b""])
def test_unreadable_log_exit_2(tmp_path: Path, content: bytes) -> None:
    bad = tmp_path / "junk.log"
    bad.write_bytes(content)
    r = subprocess.run([sys.executable, "-m", "canfdi.logplot", str(bad), "-o", str(tmp_path / "j.png")],
                       capture_output=True, text=True, cwd=REPO_ROOT, env={**os.environ, "PYTHONPATH": str(REPO_ROOT / "tools")},
                       timeout=60)
    assert r.returncode == 2
    assert r.stderr.startswith(f"canfdi-plot: {bad} holds no readable frame")
    if content:
        assert f"(first: {bad}:1: " in r.stderr
    assert "Traceback" not in r.stderr
    assert not (tmp_path / "j.png").exists()


def test_missing_log_exit_2(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main([str(tmp_path / "nope.log")]) == 2
    assert capsys.readouterr().err == f"canfdi-plot: cannot read {tmp_path / 'nope.log'}: no such file\n"


def test_help_names_the_options(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as e:
        main(["--help"])
    assert e.value.code == 0
    out = capsys.readouterr().out
    for flag in ("LOG", "-o", "--title", "--from", "--to", "exit status"):
        assert flag in out
