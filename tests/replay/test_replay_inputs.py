"""What canfdi-replay reads: every python-can format gives the candump log's
diagnosis; bad input (garbage and truncated lines, time stamps going back,
gaps, CAN FD, error and remote frames, unknown ids, several channels,
damaged or foreign files, the test logs of python-can and cantools) gets a
message with the file and line and the rest of the log is still judged,
never a crash or a hang. The damaged inputs also run through the ASan/UBSan
build of the core."""
from __future__ import annotations

import ast
import gzip
import io
import itertools
import json
import subprocess
import tarfile
import time
from pathlib import Path

import can
import pytest

from conftest import (CORE, CORE_ASAN, ROOT, SCENARIOS, make_sil_log, recorded_first_failed, run_replay,
                      undocumented_keys)

SDIST = ROOT / ".deps" / "sdist"
LOG_SUFFIXES = (".asc", ".blf", ".trc", ".csv", ".log", ".mf4", ".gz")


@pytest.fixture(scope="module")
def ia_log() -> Path:
    """dcm_ia_offset: the recorded ECU names P1A20 (once, from power-up)."""
    return make_sil_log(next(s for s in SCENARIOS if s.stem == "dcm_ia_offset"))


@pytest.fixture(scope="module")
def nominal_log() -> Path:
    return make_sil_log(next(s for s in SCENARIOS if s.stem == "nominal_setpoints"))


@pytest.fixture(scope="module")
def reference(ia_log: Path, tmp_path_factory: pytest.TempPathFactory) -> dict:
    rc, doc, _, _ = run_replay([str(ia_log)], tmp_path_factory.mktemp("ref"))
    assert rc == 1 and doc is not None
    want = recorded_first_failed(ia_log)
    assert list(want) == ["P1A20"]
    assert [(f["code"], f["first_failed_s"]) for f in doc["dtcs"]] == [("P1A20", pytest.approx(want["P1A20"]))]
    return doc


def _findings(doc: dict) -> list[tuple[str, float]]:
    return [(f["code"], round(f["first_failed_s"], 6)) for f in doc["dtcs"]]


def _line_no(lines: list[str], text: str) -> int:
    return next(n for n, line in enumerate(lines, 1) if line == text)


# ------------------------------------------------------------ formats

@pytest.mark.parametrize("suffix", [".asc", ".blf", ".trc", ".csv", ".mf4", ".log.gz", ".asc.gz"])
def test_every_format_gives_the_same_diagnosis(suffix: str, ia_log: Path, reference: dict, tmp_path: Path) -> None:
    """The candump recording written by python-can's own writers in another format."""
    out = tmp_path / f"run{suffix}"
    if suffix == ".log.gz":
        out.write_bytes(gzip.compress(ia_log.read_bytes()))
    else:
        with can.Logger(str(out)) as w:
            for msg in can.LogReader(str(ia_log)):
                w.on_message_received(msg)
    rc, doc, text, err = run_replay([str(out)], tmp_path)
    assert doc is not None, err
    assert rc == 1
    assert _findings(doc) == _findings(reference)
    lg = doc["logs"][0]
    assert lg["start"] == "power-up"
    assert lg["recorded_ecu"]["identical"] == lg["recorded_ecu"]["frames"] > 0
    assert len(lg["sha256"]) == 64
    assert lg["format"] == ("candump" if suffix == ".log.gz" else suffix.split(".")[1])


def _write_with(path: Path, src: Path, extra: dict[int, can.Message]) -> None:
    """src's frames written by python-can's writer for path's suffix, extra[k] before the k-th."""
    with can.Logger(str(path)) as w:
        for k, msg in enumerate(can.LogReader(str(src))):
            if k in extra:
                w.on_message_received(extra[k])
            w.on_message_received(msg)


@pytest.mark.parametrize("fmt", ["asc", "trc", "csv"])
def test_text_formats_report_the_files_own_lines(fmt: str, ia_log: Path, reference: dict, tmp_path: Path) -> None:
    """A line python-can's reader passes over (ASC, TRC) or raises on (CSV) is reported with its
    number, and so are the frames the core counts (an error frame, a frame of another channel):
    each is on the line of the file it came from, not of the candump text the core reads."""
    out = tmp_path / f"run.{fmt}"
    t = 0.5
    if fmt == "trc":  # python-can's TRC writer writes no error frames: a frame of another channel
        odd = can.Message(timestamp=t, arbitration_id=0x10, is_extended_id=False, data=bytes(8), channel=1)
    else:
        odd = can.Message(timestamp=t, is_error_frame=True, channel=0)
    _write_with(out, ia_log, {2000: odd})
    lines = out.read_text().splitlines(keepends=True)
    bad_at = 300
    lines.insert(bad_at - 1, "this is no frame\n")
    out.write_text("".join(lines))
    odd_at = next(n for n, line in enumerate(lines, 1)
                  if ("ErrorFrame" in line or ",1,0,\n" in line or " DT  2 " in line))
    rc, doc, text, err = run_replay([str(out)], tmp_path)
    assert doc is not None and rc == 1, err
    assert _findings(doc) == _findings(reference)
    dq = doc["data_quality"][0]
    assert [(b["line"], b["text"]) for b in dq["bad_lines"]] == [(bad_at, "this is no frame")]
    if fmt == "trc":
        assert dq["other_channels"] == {"2": {"frames": 1, "first_line": odd_at}}
    else:
        assert [e["line"] for e in dq["error_frames_first"]] == [odd_at]
    assert f"(first: line {bad_at}: python-can's" in text


def test_binary_formats_count_frames(ia_log: Path, tmp_path: Path) -> None:
    """BLF has no lines: what the core reports is at the frame's number in the file."""
    out = tmp_path / "run.blf"
    _write_with(out, ia_log, {2000: can.Message(timestamp=0.5, is_error_frame=True, channel=0)})
    rc, doc, text, err = run_replay([str(out)], tmp_path)
    assert doc is not None and rc == 1, err
    assert [e["line"] for e in doc["data_quality"][0]["error_frames_first"]] == [2001]
    assert doc["logs"][0]["lines"] == doc["logs"][0]["frames"]  # one line per frame


# ------------------------------------------------------------ damaged candump text

def test_bad_lines_are_reported_and_the_rest_judged(ia_log: Path, reference: dict, tmp_path: Path) -> None:
    lines = ia_log.read_text().splitlines(keepends=True)

    def at(i: int) -> str:
        """The time stamp of the line the new one goes before."""
        return lines[i][:19]

    # (index to insert before, text, what the report must say)
    bad = [(5, "garbage that is no frame\n", "no '(timestamp)'"),
           (100, f"{at(100)} vcan0 01G#00\n", "identifier"),
           (200, f"{at(200)} vcan0 010#0011223\n", "odd number of data digits"),
           (300, f"{at(300)} vcan0 010#001122334455667788\n", "more than 8 data bytes"),
           (400, f"{at(400)} vcan0 900#00\n", "above 0x7FF"),
           (500, f"{at(500)[:-1]} vcan0 010#00\n", "not closed"),
           (600, f"{at(600)} vcan0 010#00 trailing words\n", "unexpected text"),
           (700, "x" * 3000 + "\n", "longer than 1024"),
           (800, f"{at(800)} vcan0 0\x0010#00\n", "NUL byte")]
    noise = [(900, f"{at(900)} vcan0 010##1" + "00" * 12 + "\n"),      # CAN FD, our id
             (950, f"{at(950)} vcan0 20000080#0000000000000000\n"),     # error frame
             (1000, f"{at(1000)} vcan0 010#R8\n"),                      # remote frame
             (1050, f"{at(1050)} vcan0 00000010#0000000000000000\n"),   # 29-bit id 0x10
             (1100, f"{at(1100)} vcan0 555#00\n"),                      # not in the DBC
             (1150, f"{at(1150)} can1 010#0000000000000000\n"),         # another channel
             (1151, f"{at(1150)} can1 011#0000000000000000 R\n"),
             (1200, "(0000000001.500000) vcan0 555#01\n")]               # stamped 1.2 s ahead
    for i, t in sorted([(i, t) for i, t, _ in bad] + noise, key=lambda x: x[0], reverse=True):
        lines.insert(i, t)
    lines.append("(0000000005.000000) vcan0 010#00112")  # truncated last line, no newline
    log = tmp_path / "damaged.log"
    log.write_text("".join(lines))
    all_lines = log.read_text().split("\n")
    rc, doc, out, err = run_replay([str(log)], tmp_path)
    assert doc is not None and rc == 1, err
    # the diagnosis is untouched: none of the noise reached the supervisor as a frame of its own
    assert _findings(doc) == _findings(reference)
    assert doc["logs"][0]["recorded_ecu"]["differing"] == 0
    dq = doc["data_quality"][0]
    assert dq["bad_line_count"] == len(bad) + 1
    reported = {b["line"]: b["why"] for b in dq["bad_lines"]}
    for _, t, why in bad:
        no = _line_no(all_lines, t.rstrip("\n"))
        assert no in reported and why in reported[no], (no, reported.get(no), why)
    assert len(all_lines) in reported  # the truncated last line
    assert dq["fd_frames"] == 1 and dq["error_frames"] == 1 and dq["remote_frames"] == 1
    assert dq["extended_frames"] == 1 and dq["unknown_ids"] == {"555": 2, "x10": 1}
    assert dq["other_channels"] == {"can1": {"frames": 2, "first_line": _line_no(all_lines, noise[5][1].rstrip("\n"))}}
    assert dq["gap_count"] == 0 and dq["time_stamp_outliers"] == 1
    assert dq["time_stamp_outliers_first"][0]["line"] == _line_no(all_lines, noise[7][1].rstrip("\n"))
    assert "bad line(s) (first: line 6:" in out
    assert not undocumented_keys(doc), "keys the schema does not name"


def test_channel_option_and_auto_choice(ia_log: Path, tmp_path: Path) -> None:
    """Two channels: the first carrying a DBC frame is judged unless -c names another."""
    log = tmp_path / "two.log"
    with log.open("w") as f:
        f.write("(0000000000.000000) can7 123#00\n")  # not in the DBC: does not choose
        for line in ia_log.read_text().splitlines():
            f.write(line + "\n")
            f.write(line.replace(" vcan0 ", " can9 ")[:-2] + "00\n")  # a damaged copy
    rc, doc, _, _ = run_replay([str(log)], tmp_path)
    assert doc is not None and doc["logs"][0]["channel"] == "vcan0" and rc == 1
    assert doc["data_quality"][0]["other_channels"]["can9"]["frames"] > 20000
    rc2, doc2, _, _ = run_replay(["-c", "can9", str(log)], tmp_path)
    assert doc2 is not None and doc2["logs"][0]["channel"] == "can9"
    assert doc2["logs"][0]["start"] == "mid-drive"  # its ECU frames are not the replay's


def test_time_stamps_going_back(nominal_log: Path, tmp_path: Path) -> None:
    """Small steps back (merged loggers) are counted; a jump back (two logs concatenated)
    re-bases the rest, which is still judged."""
    lines = nominal_log.read_text().splitlines(keepends=True)
    i = next(k for k in range(1000, 2000) if lines[k][:19] != lines[k + 1][:19])
    lines[i], lines[i + 1] = lines[i + 1], lines[i]
    log = tmp_path / "back.log"
    log.write_text("".join(lines[:40000] + lines[:20000]))
    rc, doc, out, _ = run_replay([str(log)], tmp_path)
    assert doc is not None
    dq = doc["data_quality"][0]
    assert dq["time_stamps_back"] >= 2
    assert [r["line"] for r in dq["rebased"]] == [40001]
    first_part = float(lines[39999][1:lines[39999].index(")")])
    assert doc["logs"][0]["last_s"] > first_part + 3.0  # the second part went on after the first


def test_gap_in_the_log_is_not_judged(nominal_log: Path, tmp_path: Path) -> None:
    """No frame at all for 100 ms: the supervisor's timeouts in the gap are not findings;
    the gap and what could not be judged are reported."""
    log = tmp_path / "gap.log"
    with nominal_log.open() as f, log.open("w") as g:
        for line in f:
            if not 6.0 <= float(line[1:line.index(")")]) < 6.1:
                g.write(line)
    rc, doc, out, _ = run_replay([str(log)], tmp_path)
    assert doc is not None
    assert rc == 0 and doc["dtcs"] == [], out
    dq = doc["data_quality"][0]
    assert dq["gap_count"] == 1
    assert dq["gaps"][0]["from_s"] == pytest.approx(5.999) and dq["gaps"][0]["to_s"] == pytest.approx(6.1)
    spans = {n["monitor"]: n["spans"] for n in doc["not_judged"]}
    assert any(s["from_s"] <= 6.0 and s["to_s"] >= 6.1 for s in spans["com_dcm"])
    assert any(s["to_s"] >= 11.0 and "gap" in s["why"] for s in spans["dcm_models"])


def test_frame_missing_on_the_bus(nominal_log: Path, tmp_path: Path) -> None:
    """ThrSensor stops for 200 ms while everything else goes on: the timeout is judged and
    found, the throttle models are not judged while the frame is missing."""
    log = tmp_path / "thr_lost.log"
    with nominal_log.open() as f, log.open("w") as g:
        for line in f:
            if not (" 011#" in line and 8.0 <= float(line[1:line.index(")")]) < 8.2):
                g.write(line)
    rc, doc, _, _ = run_replay([str(log)], tmp_path)
    assert doc is not None and rc == 1
    assert [f["code"] for f in doc["dtcs"]] == ["U1A01"]
    assert 8.0 < doc["dtcs"][0]["first_failed_s"] < 8.02
    spans = {n["monitor"]: n["spans"] for n in doc["not_judged"]}
    assert any(s["from_s"] <= 8.01 and s["to_s"] >= 8.19 and "ThrSensor" in s["why"] for s in spans["thr_models"])
    missing = doc["data_quality"][0]["missing_frames"]
    assert any(m["frame"] == "ThrSensor" and not m["never_received"] for m in missing)


def test_jump_forward_does_not_hang(nominal_log: Path, tmp_path: Path) -> None:
    """The log goes on ten years later: a gap; at most 60 s of it is stepped, the rest skipped."""
    lines = nominal_log.read_text().splitlines(keepends=True)
    later = [line.replace("(00000000", "(03153600", 1) for line in lines[-200:]]
    log = tmp_path / "jump.log"
    log.write_text("".join(lines[:20000] + later))
    t0 = time.monotonic()
    rc, doc, _, _ = run_replay([str(log)], tmp_path)
    assert time.monotonic() - t0 < 60
    assert doc is not None and doc["data_quality"][0]["gap_count"] == 1
    assert doc["logs"][0]["last_s"] > 315360000.0
    assert doc["dtcs"] == []


@pytest.mark.parametrize("core", [CORE, CORE_ASAN], ids=["release", "asan"])
def test_damaged_files(core: Path, ia_log: Path, tmp_path: Path) -> None:
    gz = gzip.compress(ia_log.read_bytes())
    cut = tmp_path / "cut.log.gz"
    cut.write_bytes(gz[: len(gz) * 2 // 3])
    rc, doc, out, err = run_replay([str(cut)], tmp_path, core=core)
    assert doc is not None, err
    dq = doc["data_quality"][0]
    assert dq["truncated"] and dq["read_errors"]
    assert doc["logs"][0]["frames"] > 5000  # what was there was judged
    junk = tmp_path / "junk.log"
    junk.write_bytes(bytes((i * 7919 + 13) % 256 for i in range(200_000)))
    rc, doc, out, err = run_replay([str(junk)], tmp_path, core=core)
    assert rc == 3 and doc is not None and doc["data_quality"][0]["bad_line_count"] > 100
    empty = tmp_path / "empty.log"
    empty.write_text("")
    rc, doc, out, err = run_replay([str(empty)], tmp_path, core=core)
    assert rc == 3 and "nothing could be judged" in err
    for head in (b"LOGG", b"XXXX"):  # BLF's signature, or not even that
        blf = tmp_path / "junk.blf"
        blf.write_bytes(head + bytes(range(256)) * 10)
        rc, doc, out, err = run_replay([str(blf)], tmp_path, core=core)
        assert rc == 3 and doc is not None and doc["data_quality"][0]["bad_lines"]


@pytest.mark.parametrize("suffix", [".asc", ".trc", ".csv", ".blf", ".mf4"])
def test_truncated_files_of_every_format(suffix: str, ia_log: Path, tmp_path: Path) -> None:
    """A file of each python-can format cut at two thirds: a message with the file and the line (the
    cut last line of a text format; a BLF file shorter than its header says: truncated; an MF4 file
    asammdf cannot open), what was there judged, no traceback on stderr."""
    full = tmp_path / f"full{suffix}"
    _write_with(full, ia_log, {})
    data = full.read_bytes()
    cut = tmp_path / f"cut{suffix}"
    at = len(data) * 2 // 3
    if suffix in (".asc", ".trc"):
        # inside the data bytes of the line at two thirds (the last quarter of its columns), so
        # that where the cut falls does not depend on the header's length (the TRC header holds
        # the file's path); every cut inside a line: test_a_last_line_cut_anywhere_is_reported
        start = data.rfind(b"\n", 0, at) + 1
        end = data.find(b"\n", at)
        at = start + (end - start) * 3 // 4
    cut.write_bytes(data[:at])
    js = tmp_path / "r.json"
    r = subprocess.run([str(ROOT / ".venv" / "bin" / "canfdi-replay"), "--no-progress", "--json", str(js), str(cut)],
                       capture_output=True, text=True, timeout=120)  # a process of its own: stderr to its end
    rc, text, err = r.returncode, r.stdout, r.stderr
    assert "Traceback" not in err and "Exception ignored" not in err, err
    doc = json.loads(js.read_text())
    dq = doc["data_quality"][0]
    if suffix == ".mf4":
        assert rc == 3 and "cannot open it as MF4" in dq["bad_lines"][0]["why"]
        return
    assert rc == 1 and doc["logs"][0]["frames"] > 10000
    if suffix == ".blf":
        assert dq["truncated"] and dq["bad_lines"][0]["why"].startswith("truncated:")
        assert "the frames after frame" in text
    else:
        last = cut.read_bytes().count(b"\n") + 1
        assert [b["line"] for b in dq["bad_lines"]] == [last], dq["bad_lines"]


def test_unusable_arguments(tmp_path: Path) -> None:
    rc, doc, _, err = run_replay([str(tmp_path / "missing.log")], tmp_path)
    assert rc == 2 and "no such file" in err
    rc, _, _, err = run_replay([str(tmp_path)], tmp_path)
    assert rc == 2 and "is a directory" in err
    odd = tmp_path / "data.xyz"
    odd.write_text("hello\n")
    rc, _, _, err = run_replay([str(odd)], tmp_path)
    assert rc == 2 and "unknown log format" in err


# ------------------------------------------------------------ other projects' test logs

def _sdist_members(name: str) -> list[tuple[str, bytes]]:
    tgz = sorted(SDIST.glob(f"{name}-*.tar.gz"))
    assert tgz, f"{SDIST}: no {name} sdist (make deps downloads it)"
    with tarfile.open(tgz[-1]) as t:
        return [(m.name, t.extractfile(m).read()) for m in t.getmembers()  # type: ignore[union-attr]
                if m.isfile()]


def test_python_can_test_logs(tmp_path: Path) -> None:
    """Every log file of python-can's own test data: read, judged, nothing raised; in its ASC and
    TRC files (well-formed, with headers, comments, events and bus states besides the frames) no
    line is reported as bad and every frame python-can reads is replayed."""
    files = [(n, b) for n, b in _sdist_members("python_can") if "/test/data/" in n and n.endswith(LOG_SUFFIXES)]
    assert len(files) >= 15
    seen_fd = seen_err = 0
    for name, data in files:
        p = tmp_path / Path(name).name
        p.write_bytes(data)
        t0 = time.monotonic()
        rc, doc, out, err = run_replay([str(p)], tmp_path, core=CORE_ASAN)
        assert time.monotonic() - t0 < 60, name
        assert "Traceback" not in err and "runtime error" not in err and "AddressSanitizer" not in err, (name, err)
        if rc == 2:  # a file python-can cannot read as its suffix says: a message, no crash
            assert err.startswith("canfdi-replay:"), (name, err)
            continue
        assert rc in (0, 1, 3) and doc is not None, (name, rc, err)
        if name.endswith((".asc", ".trc", ".asc.gz")):
            assert doc["data_quality"][0]["bad_lines"] == [], name
            assert doc["logs"][0]["frames"] == sum(1 for _ in can.LogReader(str(p))), name
        seen_fd += doc["data_quality"][0]["fd_frames"]
        seen_err += doc["data_quality"][0]["error_frames"]
    assert seen_fd > 0 and seen_err > 0


def test_cantools_test_log_lines(tmp_path: Path) -> None:
    """The log lines of cantools' logreader tests (candump, candump -l, ASCII variants): a
    candump -L line is a frame, every other line a bad line with its number and reason."""
    src = next(b for n, b in _sdist_members("cantools") if n.endswith("tests/test_logreader.py"))
    strings = [n.value for n in ast.walk(ast.parse(src)) if isinstance(n, ast.Constant) and isinstance(n.value, str)]
    lines = [s for s in itertools.chain.from_iterable(x.splitlines() for x in strings)
             if "can" in s and any(c.isdigit() for c in s) and s.strip() and not s.strip().startswith("#")]
    assert len(lines) >= 40
    p = tmp_path / "cantools_lines.log"
    p.write_text("\n".join(lines) + "\n")
    rc, doc, out, err = run_replay([str(p)], tmp_path, core=CORE_ASAN)
    assert doc is not None, err
    lg, dq = doc["logs"][0], doc["data_quality"][0]
    assert lg["lines"] == len(lines)
    assert lg["frames"] > 0 and dq["bad_line_count"] > 0
    assert lg["frames"] + dq["bad_line_count"] == len(lines)
    assert all(b["why"] for b in dq["bad_lines"])


# ------------------------------------------------------------ E2E of recorded frames

def _t(line: str) -> float:
    return float(line[1:line.index(")")])


def test_recorded_setpoints_are_judged_like_the_ecu(nominal_log: Path, tmp_path: Path) -> None:
    """The recorded setpoints go through the replayed input supervision, E2E
    included: SetpointThr with a wrong CRC from 6.0 to 6.3 s (a corrupted
    vehicle link) is rejected and found as U1A51 once debounced (the sixth
    bad frame after a clean run: the frame class counts from -6 by 2), when
    the angle held since 5.99 s turns invalid; SetpointDcm missing from 8.0
    to 8.1 s is U1A50 when the last accepted one is 50 ms old; the rejected
    frames are in the data quality. The replayed supervisor then drives the
    valve otherwise than the recorded ECU did (it took the setpoints): the
    tracking monitor is not judged for that, no P2119."""
    log = tmp_path / "sp.log"
    n_bad = 0
    with nominal_log.open() as f, log.open("w") as g:
        for line in f:
            t = _t(line)
            if " 101#" in line and 6.0 <= t < 6.3:
                head, data = line.rstrip("\n").split("#")
                line = f"{head}#{int(data[:2], 16) ^ 0x10:02X}{data[2:]}\n"
                n_bad += 1
            if " 100#" in line and 8.0 <= t < 8.1:
                continue
            g.write(line)
    assert n_bad == 30
    rc, doc, out, _ = run_replay([str(log)], tmp_path)
    assert doc is not None and rc == 1, out
    found = {f["code"]: f["first_failed_s"] for f in doc["dtcs"]}
    assert set(found) == {"U1A50", "U1A51"}, found
    assert found["U1A51"] == pytest.approx(6.05, abs=1e-6)       # frames at 6.00 .. 6.05
    assert found["U1A50"] == pytest.approx(8.04, abs=1e-6)       # last one at 7.99
    rej = doc["data_quality"][0]["rejected_frames"]
    assert rej["SetpointThr"]["crc"] == 30 and rej["SetpointDcm"]["timeouts"] == 1
    assert rej["SetpointDcm"]["crc"] == 0 and rej["SetpointThr"]["counter"] == 0
    spans = {n["monitor"]: n["spans"] for n in doc["not_judged"]}
    assert any(s["from_s"] <= 6.1 and "otherwise than the replay" in s["why"] for s in spans["thr_tracking"])


def test_forged_recorded_ecu_dtc_frames_are_not_the_ecus(ia_log: Path, reference: dict, tmp_path: Path) -> None:
    """EcuDtc frames another node put on the ECU's identifier (a wrong CRC;
    a right CRC in a second counter sequence) claiming P0222 and U1A00: the
    replay's diagnosis is the reference's, the recorded ECU is never said to
    have reported them, the frames are counted in the data quality."""
    from canfdi import e2e
    from canfdi.timeline import load_db
    dtc = load_db().get_message_by_name("EcuDtc")

    def forged(counter: int, code: int, crc_ok: bool) -> str:
        vals = {s.name: 0 for s in dtc.signals}
        vals.update(DtcCode=code, DtcStsTestFailed=1, DtcStsConfirmed=1, DtcStsFailedSinceClear=1, DtcCount=1)
        data = e2e.protect(0x310, bytearray(dtc.encode(vals)), counter)
        if not crc_ok:
            data[0] ^= 0x01
        return bytes(data).hex().upper()

    log = tmp_path / "forged.log"
    plan = [(1.0, 0x022200, False), (1.5, 0xDA0000, True), (1.6, 0xDA0000, True)]
    own = None
    with ia_log.open() as f, log.open("w") as g:
        for line in f:
            g.write(line)
            if " 310#" in line and plan and _t(line) >= plan[0][0]:
                t0, code, crc_ok = plan.pop(0)
                ctr = int(line.split("#")[1][3], 16)        # the low nibble of byte 1
                if not crc_ok:
                    counter = (ctr + 8) & 15
                else:                                        # its own sequence, 8 ahead of the ECU's
                    own = (ctr + 8) & 15 if own is None else (own + 1) & 15
                    counter = own
                g.write(line.split("#")[0] + "#" + forged(counter, code, crc_ok) + "\n")
    assert not plan
    rc, doc, out, _ = run_replay([str(log)], tmp_path)
    assert doc is not None and rc == 1
    assert [(f["code"], f["first_failed_s"]) for f in doc["dtcs"]] == [(f["code"], f["first_failed_s"])
                                                                       for f in reference["dtcs"]]
    assert not any(r["code"] in ("P0222", "U1A00") for r in doc["recorded_ecu_only"])
    assert "P0222" not in out and "U1A00" not in out
    # the wrong CRC; two forged in sequence and the ECU's frame after each
    assert doc["data_quality"][0]["recorded_ecu_dtc_frames_failing_e2e"] == 5
    assert "5 recorded EcuDtc frame(s) forged or corrupted" in out


@pytest.mark.parametrize("suffix", [".asc", ".trc", ".csv"])
def test_a_last_line_cut_anywhere_is_reported(suffix: str, tmp_path: Path) -> None:
    """A text log cut at every byte of its last frame line: the line gives its whole frame (cut
    after the data bytes) or is reported by its number and gives none (a line cut after its time
    stamp or identifier reads like an event line to the ASC reader, one cut inside its last data
    byte gives a wrong byte, one cut between bytes too few); never a frame lost or changed
    without a word."""
    from canfdi.replay_input import Problems, numbered_messages, write_candump

    full = tmp_path / f"full{suffix}"
    with can.Logger(str(full)) as w:
        for i in range(6):
            w.on_message_received(can.Message(timestamp=1.0 + i * 0.01, arbitration_id=0x100 + i, channel=0,
                                              data=bytes(range(i, i + 8)), is_extended_id=False))
    data = full.read_bytes()
    whole = [(pos, bytes(m.data)) for pos, m in numbered_messages(full, suffix[1:], Problems())]
    assert len(whole) == 6
    last_no = whole[-1][0]  # the last frame's line (an ASC trailer follows it)
    end = sum(len(ln) for ln in data.splitlines(keepends=True)[:last_no - 1])
    stop = data.find(b"\n", end)
    whole_at = stop - 1 if data[stop - 1:stop] == b"\r" else stop  # the line's text ends here (CR LF or LF)
    for at in range(end, stop + 1):  # from whole_at on: the whole line without its line end
        if not data[end:at].strip():
            continue  # only the line's leading blanks: a whole file of five frames
        cut = tmp_path / f"cut{suffix}"
        cut.write_bytes(data[:at])
        problems = Problems()
        out = io.StringIO()
        n = write_candump(numbered_messages(cut, suffix[1:], problems), out, cut, problems, suffix[1:])
        lines = [p[1] for p in problems.items]
        if at >= whole_at:  # a whole last line without a line end (some tools write none): read
            assert n == 6 and not lines, (problems.items, out.getvalue())
            assert out.getvalue().splitlines()[-1].endswith(whole[-1][1].hex().upper()), out.getvalue()
        else:
            assert n == 5 and lines == [last_no], (at, data[end:at], problems.items)


def test_last_lines_without_a_line_end(tmp_path: Path) -> None:
    """ASC in decimal bytes: a last frame line without a line end may end inside its last byte
    ("255" cut to "25" is a whole byte): reported, its frame not used. An event line at the end
    without a line end holds no frame by design: nothing reported."""
    from canfdi.replay_input import Problems, numbered_messages, write_candump

    head = ("date Sun Nov 29 20:00:00.000 2026\nbase dec  timestamps absolute\ninternal events logged\n"
            "Begin Triggerblock Sun Nov 29 20:00:00.000 2026\n 0.000000 Start of measurement\n")
    rows = "".join(f" {0.01 * (i + 1):.6f} 1  256             Rx   d 8 1 2 3 4 5 6 7 255\n" for i in range(4))
    cases = [(" 0.050000 1  256             Rx   d 8 1 2 3 4 5 6 7 25", 4, [6 + 4]),
             (" 0.050000 1  256             Rx   d 8 1 2 3 4 5 6 7", 4, [6 + 4]),
             (" 0.050000 Start of measurement", 4, []),
             ("End TriggerBlock", 4, [])]
    for last, frames, bad in cases:
        f = tmp_path / "dec.asc"
        f.write_text(head + rows + last)
        problems = Problems()
        n = write_candump(numbered_messages(f, "asc", problems), io.StringIO(), f, problems, "asc")
        assert (n, [p[1] for p in problems.items]) == (frames, bad), (last, problems.items)
