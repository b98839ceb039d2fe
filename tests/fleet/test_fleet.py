"""canfdi-fleet (`make fleet-test`): a small synthetic fleet (canfdi-fleet-gen, 4 vehicles x 4 drives of
30 s) through the command end to end on a local Dask cluster, a rerun, failed files, the DTC memory of
the chain of one-drive tasks against one long replay, the Parquet tables read by pandas, pyarrow,
DuckDB and Polars, and the report in a browser. The 20 x 10 acceptance run is `make fleet-acceptance`."""
from __future__ import annotations

import csv
import json
import re
import shutil
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "tools"))

from canfdi.fleet import TABLES, read_table  # noqa: E402
from canfdi.fleet_acceptance import check  # noqa: E402

PY = sys.executable
CHROMIUM = shutil.which("chromium-headless-shell") or shutil.which("chromium")


def fleet_cmd(args: list[str]) -> subprocess.CompletedProcess[str]:
    return subprocess.run([PY, "-m", "canfdi.fleet", *args], capture_output=True, text=True, timeout=600,
                          cwd=ROOT)


@pytest.fixture(scope="module")
def fleet(tmp_path_factory: pytest.TempPathFactory) -> Path:
    d = tmp_path_factory.mktemp("fleet") / "fleet"
    r = subprocess.run([PY, "-m", "canfdi.fleet_gen", "-q", "-o", str(d), "--vehicles", "4", "--drives", "4",
                        "--duration", "30", "--seed", "5"], capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr
    return d


@pytest.fixture(scope="module")
def run1(fleet: Path) -> tuple[Path, subprocess.CompletedProcess[str]]:
    out = fleet.parent / "out"
    r = fleet_cmd([str(fleet / "manifest.csv"), "-o", str(out), "--workers", "2"])
    return out, r


def tables(out: Path) -> dict[str, Any]:
    keys = {"logs": ["vehicle", "drive_seq"], "dtc_events": ["vehicle", "drive_seq", "code"],
            "param_tracks": ["vehicle", "drive_seq", "parameter", "t_s"],
            "residual_stats": ["vehicle", "drive_seq", "residual"]}
    return {t: read_table(out, t).sort_values(keys[t]).reset_index(drop=True) for t in TABLES}


def test_generator_is_deterministic(fleet: Path, tmp_path: Path) -> None:
    truth = json.loads((fleet / "truth.json").read_text())
    assert len(truth["vehicles"]) == 4 and all(len(v["drives"]) == 4 for v in truth["vehicles"])
    kinds = sorted(f["kind"] for v in truth["vehicles"] for f in v["faults"])
    assert kinds == ["ra_creep", "spring_weak", "tps_intermittent"]
    thr = truth["thresholds"]
    assert thr["ra_creep"]["calibration_threshold"] == pytest.approx(0.08, abs=1e-3)
    assert 0.0 < thr["ra_creep"]["value"] <= 0.1 and 0.0 < thr["spring_weak"]["value"] <= 0.15
    assert 1.0 <= thr["tps_intermittent"]["value"] <= 30.0
    # the same seed, the same bytes (one vehicle regenerated)
    again = tmp_path / "again"
    subprocess.run([PY, "-m", "canfdi.fleet_gen", "-q", "-o", str(again), "--vehicles", "4", "--drives", "4",
                    "--duration", "30", "--seed", "5", "-j", "1"], check=True, timeout=600)
    assert (again / "truth.json").read_text() == (fleet / "truth.json").read_text()
    f0 = truth["vehicles"][0]["drives"][-1]["file"]
    assert (again / f0).read_bytes() == (fleet / f0).read_bytes()


def test_end_to_end(fleet: Path, run1: tuple[Path, subprocess.CompletedProcess[str]]) -> None:
    out, r = run1
    assert r.returncode == 0, r.stderr
    assert "16 logs of 4 vehicles" in r.stdout
    assert "[16/16]" in r.stderr  # progress of the whole run
    t = tables(out)
    logs = t["logs"]
    assert len(logs) == 16 and set(logs["status"]) == {"ok"}
    assert set(logs["start_mode"]) == {"power-up"}  # every drive from the power-up of an ECU with its memory
    assert (logs["recorded_ecu_identical"] == logs["recorded_ecu_frames"]).all()
    for name, df in t.items():
        for col in ("firmware", "log_sha256", "dbc_sha256"):
            assert df[col].str.len().min() > 10, (name, col)
    # partitioned by vehicle and date
    parts = sorted(p.relative_to(out / "parquet" / "logs").parts[:2] for p in (out / "parquet" / "logs").rglob("*.parquet"))
    assert parts[0][0].startswith("vehicle=V001") and parts[0][1].startswith("date=2025-")
    assert len(t["param_tracks"]) > 0 and len(t["residual_stats"]) == 16 * 8
    ev = t["dtc_events"]
    assert {"ff_speed_rad_s", "ff_ia_A", "confirmed", "occurrence"} <= set(ev.columns)
    # the ground truth: every fault found within a drive of its crossing, no other code, memory = one long replay
    res = check(fleet, out, memory=True)
    s = res["summary"]
    assert s["missed"] == 0 and s["wrong_drive"] == 0 and s["false_codes"] == 0, res
    assert s["memory_equal_long"] == 4 and s["memory_equal_ecu"] == 4
    report = out / "fleet_report.html"
    text = report.read_text()
    assert "src=\"http" not in text and "href=\"http" not in text
    for heading in ("Vehicles that need a workshop visit", "Trouble codes per 1000 operating hours",
                    "Vehicles ranked by parameter drift", "Trends and projected threshold crossings"):
        assert heading in text


def test_rerun_is_idempotent_and_deterministic(fleet: Path, run1: tuple[Path, subprocess.CompletedProcess[str]]) -> None:
    out, r = run1
    assert r.returncode == 0
    first = tables(out)
    r2 = fleet_cmd([str(fleet / "manifest.csv"), "-o", str(out), "--workers", "1"])
    assert r2.returncode == 0 and "0 replayed, 16 finished before" in r2.stdout
    again = tables(out)
    forced_out = fleet.parent / "out_forced"
    r3 = fleet_cmd([str(fleet), "-o", str(forced_out), "--workers", "2", "--force", "--no-report"])  # the folder as input
    assert r3.returncode == 0 and "16 replayed" in r3.stdout
    forced = tables(forced_out)
    for name in TABLES:
        assert first[name].equals(again[name]), name
        a = first[name].drop(columns=["file"])
        b = forced[name].drop(columns=["file"])
        assert a.equals(b), name  # the manifest's and the folder's names of the files differ only in form


def test_failed_files_are_reported_and_the_others_done(fleet: Path, tmp_path: Path) -> None:
    rows = list(csv.DictReader((fleet / "manifest.csv").open()))
    v1 = [r for r in rows if r["vehicle"] == "V001"]
    v2 = [r for r in rows if r["vehicle"] == "V002"]
    bad = tmp_path / "broken.blf"
    bad.write_bytes(b"this is no BLF file" * 100)
    man = tmp_path / "manifest.csv"
    with man.open("w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["vehicle", "start", "file"])
        w.writerow(["V001", v1[0]["start"], str(fleet / v1[0]["file"])])
        w.writerow(["V001", "2025-03-20T08:00:00", str(bad)])
        w.writerow(["V001", "2025-03-21T08:00:00", str(tmp_path / "missing.log")])
        w.writerow(["V001", "2025-03-22T08:00:00", str(fleet / v1[1]["file"])])
        for r in v2:
            w.writerow(["V002", r["start"], str(fleet / r["file"])])
    out = tmp_path / "out"
    r = fleet_cmd([str(man), "-o", str(out), "--workers", "2"])
    assert r.returncode == 1, r.stdout + r.stderr
    run = json.loads((out / "fleet_run.json").read_text())
    failed = {Path(f["file"]).name: f["reason"] for f in run["failed"]}
    assert set(failed) == {"broken.blf", "missing.log"}
    assert "No such file" in failed["missing.log"]
    assert "no CAN frame could be read" in failed["broken.blf"]
    assert "FAILED V001 drive 2" in r.stderr and "FAILED V001 drive 3" in r.stderr
    logs = read_table(out, "logs").sort_values(["vehicle", "drive_seq"]).reset_index(drop=True)
    assert list(logs["status"]) == ["ok", "failed", "failed", "ok"] + ["ok"] * len(v2)
    # the vehicle's memory goes past the failed drives unchanged
    v1l = logs[logs["vehicle"] == "V001"]
    assert v1l.iloc[3]["nvm_in_sha256"] == v1l.iloc[0]["nvm_out_sha256"]
    assert (out / "fleet_report.html").read_text().count("could not be replayed") == 1


def test_parquet_readers(run1: tuple[Path, subprocess.CompletedProcess[str]]) -> None:
    out, _ = run1
    base = out / "parquet"
    import duckdb
    import pandas as pd
    import polars as pl
    import pyarrow.dataset as ds
    n_pd = len(pd.read_parquet(base / "logs"))
    n_pa = ds.dataset(base / "logs", format="parquet", partitioning="hive").count_rows()
    n_pl = pl.scan_parquet(str(base / "logs" / "**" / "*.parquet"), hive_partitioning=True).collect().height
    n_dd = duckdb.sql(f"select count(*) from read_parquet('{base}/logs/**/*.parquet', hive_partitioning=true)").fetchall()[0][0]
    assert n_pd == n_pa == n_pl == n_dd == 16
    v = duckdb.sql(f"select vehicle, sum(operating_h) h from read_parquet('{base}/logs/**/*.parquet', "
                   f"hive_partitioning=true) group by vehicle order by vehicle").fetchall()
    assert [x[0] for x in v] == ["V001", "V002", "V003", "V004"]
    tr = pl.scan_parquet(str(base / "param_tracks" / "**" / "*.parquet"), hive_partitioning=True) \
        .filter(pl.col("parameter") == "R_A").collect()
    assert tr.height > 0 and tr["deviation"].dtype == pl.Float64


def test_command_line(tmp_path: Path) -> None:
    from canfdi import fleet
    h = fleet.build_parser().format_help()
    for word in ("--scheduler", "--workers", "--force", "MANIFEST", "Exit status", "docs/fleet.md"):
        assert word in h
    r = fleet_cmd([str(tmp_path / "nothing*.log"), "-o", str(tmp_path / "o")])
    assert r.returncode == 2 and "no such file" in r.stderr
    man = tmp_path / "m.csv"
    man.write_text("vehicle,start,file\nV1,yesterday,a.log\n")
    r = fleet_cmd([str(man), "-o", str(tmp_path / "o")])
    assert r.returncode == 2 and "ISO 8601" in r.stderr


@pytest.mark.skipif(CHROMIUM is None, reason="no headless Chromium (make deps installs chromium-headless-shell)")
def test_report_in_a_browser(run1: tuple[Path, subprocess.CompletedProcess[str]], tmp_path: Path) -> None:
    out, _ = run1
    html = out / "fleet_report.html"
    base = [str(CHROMIUM), "--headless", "--no-sandbox", "--disable-gpu", "--hide-scrollbars"]
    shot = tmp_path / "shot.png"
    subprocess.run(base + [f"--screenshot={shot}", "--window-size=1200,2000", html.as_uri()],
                   capture_output=True, timeout=120)
    assert shot.exists()
    from PIL import Image
    with Image.open(shot) as im:
        colors = im.convert("RGB").getcolors(maxcolors=1 << 20)
    assert colors is not None and len(colors) > 50
    assert re.search(r"<img src=\"data:image/png;base64,", html.read_text())
