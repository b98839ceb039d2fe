"""The reports of canfdi-replay: the JSON report's schema and contents (hashes,
firmware id, freeze frames, evidence), two logs as two drives with the
trouble-code memory carried across, the HTML report in a real browser
(headless Chromium: it decodes every image, and a screenshot shows more
than a blank page), the command line."""
from __future__ import annotations

import hashlib
import json
import re
import shutil
import subprocess
from pathlib import Path

import pytest

from conftest import CORE, ROOT, SCENARIOS, make_sil_log, run_replay, undocumented_keys

CHROMIUM = shutil.which("chromium-headless-shell") or shutil.which("chromium")


@pytest.fixture(scope="module")
def demo_log() -> Path:
    """The demo scenario: four faults one after the other, 24 s."""
    return make_sil_log(ROOT / "tests" / "sil" / "scenarios" / "demo.scn")


def test_json_report(demo_log: Path, tmp_path: Path) -> None:
    rc, doc, out, _ = run_replay([str(demo_log)], tmp_path)
    assert rc == 1 and doc is not None
    assert doc["schema"] == "canfdi-replay/1"
    fw = subprocess.run([str(CORE), "--fw-id"], capture_output=True, text=True, check=True).stdout.strip()
    assert doc["firmware"]["id"] == fw and fw.startswith("fw-sha256:")
    # the identification the ECU reports (UDS DIDs F195, F182), from the firmware's defaults
    src = (ROOT / "firmware" / "uds" / "canfdi_uds.c").read_text()
    ident = re.search(r"canfdi_uds_ident_t ident = \{\s*\{([^}]*)\},\s*\{([^}]*)\}", src)
    assert ident is not None
    sw, cal = ("".join(re.findall(r"'(.)'", g)).rstrip() for g in ident.groups())
    assert (doc["firmware"]["sw_version"], doc["firmware"]["calibration_id"]) == (sw, cal) and sw
    assert not undocumented_keys(doc), "keys the schema does not name"
    assert doc["dbc"]["sha256"] == hashlib.sha256((ROOT / "dbc" / "canfdi.dbc").read_bytes()).hexdigest()
    lg = doc["logs"][0]
    assert lg["sha256"] == hashlib.sha256(demo_log.read_bytes()).hexdigest()
    assert [f["code"] for f in doc["dtcs"]] == ["P0121", "P1A10", "P1A30", "P0222"]
    for f in doc["dtcs"]:
        assert set(f) >= {"code", "first_failed_s", "status", "freeze_frame", "confidence_pct", "evidence",
                          "status_bits", "occurrence", "recorded_ecu_first_failed_s"}
        assert f["status"] & 0x09 == 0x09  # confirmed, still failing at the end of the demo
        assert f["status_bits"]["CDTC"] == 1
        assert f["freeze_frame"]["time_s"] == pytest.approx(f["first_failed_s"], abs=0.0015)
        assert f["recorded_ecu_first_failed_s"] == pytest.approx(f["first_failed_s"])
        assert f["confidence_pct"] is not None and 50 <= f["confidence_pct"] <= 100
        assert f["evidence"]["rules"], f["code"]
    p1a10 = next(f for f in doc["dtcs"] if f["code"] == "P1A10")
    dcm = p1a10["evidence"]["components"][0]
    assert dcm["result"]["isolated"] == 1 and dcm["symptoms"]["R_A"] == "+"
    assert p1a10["evidence"]["parameter_deviation_pct"]["R_A"] > 8.0  # above the +8 % threshold
    p1a30 = next(f for f in doc["dtcs"] if f["code"] == "P1A30")
    assert "plausibility" in p1a30["confidence_basis"]
    # from power-up, only the DC motor's model rules wait: until its estimates have converged
    # (about 2 s of the key-on test burst) and what they learnt is checked (the learning check,
    # firmware/app/canfdi_app.h) they are not tested, on the ECU and in the replay alike
    assert [n["monitor"] for n in doc["not_judged"]] == ["dcm_models", "dcm_cmd"]
    for n in doc["not_judged"]:
        spans = n["spans"]
        assert spans[0]["from_s"] == 0.0 and "not converged" in spans[0]["why"], n
        assert len(spans) == 1 or (len(spans) == 2 and "not checked yet" in spans[1]["why"]
                                   and spans[1]["from_s"] == pytest.approx(spans[0]["to_s"], abs=0.002)), n
        assert 1.0 < spans[-1]["to_s"] < 3.0, n
    assert doc["data_quality"][0]["bus_load_pct"]["mean"] > 30.0
    assert doc["exit_status"] == 1


def test_two_drives_carry_the_memory(tmp_path: Path) -> None:
    """The second log is a new operation cycle of the same supervisor: the code confirmed in the
    first drive stays stored (no longer failed in this cycle) and a new one is found. The second
    recording's ECU started with an empty memory (another SIL run), so its frames are not the
    replay's: that log is judged as a mid-drive start."""
    from conftest import MATRIX, recorded_first_failed
    first = make_sil_log(next(s for s in SCENARIOS if s.stem == "tps1_open"))
    second = make_sil_log(next(s for s in MATRIX if s.stem == "dcm_ia_sensor_offset_intermittent"))
    rc, doc, out, _ = run_replay([str(first), str(second)], tmp_path)
    assert rc == 1 and doc is not None
    assert [(f["log"], f["code"]) for f in doc["dtcs"]] == [(0, "P0122"), (1, "P1A20")]
    p0122, p1a20 = doc["dtcs"]
    assert p0122["first_failed_s"] == pytest.approx(recorded_first_failed(first)["P0122"])
    assert p0122["status"] & 0x08 and not p0122["status"] & 0x02  # confirmed, not failed this cycle
    assert p1a20["first_failed_s"] >= doc["logs"][1]["settled_from_s"]
    assert doc["logs"][0]["start"] == "power-up"
    assert doc["logs"][1]["start"] == "mid-drive"
    assert doc["logs"][1]["recorded_ecu"]["first_difference"]["t"] == pytest.approx(0.0, abs=0.01)


def test_html_report_in_a_browser(demo_log: Path, tmp_path: Path) -> None:
    # make deps installs chromium-headless-shell: without it this test fails
    # rather than pass without having looked at the page
    assert CHROMIUM is not None, "no headless Chromium: run make deps (chromium-headless-shell)"
    html = tmp_path / "report.html"
    rc, doc, _, _ = run_replay([str(demo_log), "--html", str(html)], tmp_path)
    assert rc == 1 and html.exists()
    text = html.read_text()
    assert "src=\"http" not in text and "href=\"http" not in text  # self-contained
    n_img = text.count("<img ")
    assert n_img >= 4
    for heading in ("Trouble codes", "Timeline", "Residuals against their thresholds", "Parameter estimates",
                    "Evidence", "Not judged", "Data quality"):
        assert f">{heading}" in text
    for row in ("bad or unparsable lines", "gaps in the log", "rejected input frames", "missing input frames",
                "error frames", "bus load"):
        assert f"<td>{row}</td>" in text, row
    assert text.count('alt="bus load"') == 1 and "dcm degraded" in text  # the degradation at each code
    base = [str(CHROMIUM), "--headless", "--no-sandbox", "--disable-gpu", "--hide-scrollbars"]
    dom = subprocess.run(base + ["--dump-dom", html.as_uri()], capture_output=True, text=True, timeout=120).stdout
    m = re.search(r'data-images-ok="(\d+)"', dom)
    assert m and int(m.group(1)) == n_img, "the browser did not decode every image"
    shot = tmp_path / "shot.png"
    subprocess.run(base + [f"--screenshot={shot}", "--window-size=1200,2400", html.as_uri()],
                   capture_output=True, timeout=120)
    assert shot.exists()
    from PIL import Image
    with Image.open(shot) as im:
        colors = im.convert("RGB").getcolors(maxcolors=1 << 20)
    assert colors is not None and len(colors) > 50  # text and plots, not a blank page


def test_command_line(tmp_path: Path) -> None:
    from canfdi import replay
    help_text = replay.build_parser().format_help()
    for word in ("--json", "--html", "--map", "-c CHANNEL", "--bitrate", "--start", "--settle", "exit status"):
        assert word in help_text
    rc, _, _, err = run_replay([str(tmp_path / "x.log"), "--settle", "-1"], tmp_path)
    assert rc == 2
    rc, _, _, err = run_replay([str(ROOT / "README.md")], tmp_path, core=tmp_path / "no-core")
    assert rc == 2
    log = make_sil_log(next(s for s in SCENARIOS if s.stem == "tps1_open"))
    rc, _, _, err = run_replay([str(log)], tmp_path, core=tmp_path / "no-core")
    assert rc == 2 and "make all" in err
    r = subprocess.run([str(ROOT / ".venv" / "bin" / "canfdi-replay"), "-q", str(log)], capture_output=True,
                       text=True, timeout=120)
    assert r.returncode == 1
    assert r.stdout.splitlines()[-1] == "result: 1 trouble code found: P0122"
    assert r.stderr == ""  # no progress bar when stderr is not a terminal


def _stderr_on_a_terminal(args: list[str]) -> tuple[int, str]:
    """canfdi-replay with its stderr on a pseudo-terminal: (exit status, what the terminal got)."""
    import os
    import pty
    import select
    master, slave = pty.openpty()
    try:
        p = subprocess.Popen([str(ROOT / ".venv" / "bin" / "canfdi-replay"), "-q", *args],
                             stdout=subprocess.DEVNULL, stderr=slave)
        os.close(slave)
        got = b""
        while True:
            ready, _, _ = select.select([master], [], [], 120)
            if not ready:
                p.kill()
                raise AssertionError("canfdi-replay hung")
            try:
                chunk = os.read(master, 65536)
            except OSError:  # the terminal closed: the process is gone
                break
            if not chunk:
                break
            got += chunk
        return p.wait(timeout=120), got.decode(errors="replace")
    finally:
        os.close(master)


def test_progress_bar_on_a_terminal(tmp_path: Path) -> None:
    """On a terminal a progress bar (over the bytes of a candump log the core reads, over the frames
    of a format converted through python-can) is drawn on stderr and cleared at the end;
    --no-progress draws none (and none off a terminal: test_command_line)."""
    import can
    log = make_sil_log(next(s for s in SCENARIOS if s.stem == "tps1_open"))
    asc = tmp_path / "run.asc"
    with can.Logger(str(asc)) as w:
        for msg in can.LogReader(str(log)):
            w.on_message_received(msg)
    for path, unit in ((log, "B/s"), (asc, "frames")):
        rc, term = _stderr_on_a_terminal([str(path)])
        assert rc == 1
        assert "replay:" in term and unit in term and term.endswith("\r"), term
        rc, term = _stderr_on_a_terminal(["--no-progress", str(path)])
        assert rc == 1 and term == "", term


def test_closed_stdout(tmp_path: Path) -> None:
    """The reader of the timeline goes away (`canfdi-replay LOG | head -0`): no traceback, the
    exit status still says what was found, the JSON report is still written."""
    log = make_sil_log(next(s for s in SCENARIOS if s.stem == "tps1_open"))
    js = tmp_path / "r.json"
    p = subprocess.Popen([str(ROOT / ".venv" / "bin" / "canfdi-replay"), str(log), "--json", str(js)],
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    assert p.stdout is not None and p.stderr is not None
    p.stdout.close()
    err = p.stderr.read()
    assert p.wait(timeout=120) == 1, err
    assert "Traceback" not in err and "BrokenPipe" not in err, err
    assert [f["code"] for f in json.loads(js.read_text())["dtcs"]] == ["P0122"]
