"""canfdi-fleet: the canfdi-replay diagnosis over every drive of a fleet, on Dask.

Every log is one task on a Dask cluster (a local one of worker processes by
default, or --scheduler ADDRESS). A vehicle's logs run in time order, each
starting from the DTC memory (the NVM image) its previous drive left, so
operation cycles, pending/confirmed and aging behave as in the vehicle;
different vehicles run in parallel. Results go to OUT/parquet/ (tables
partitioned by vehicle and date, docs/fleet.md) and the fleet report to
OUT/fleet_report.html.
"""
from __future__ import annotations

import argparse
import csv
import datetime as dt
import glob
import json
import logging
import os
import re
import shutil
import sys
import time
from pathlib import Path
from typing import Any

from .fleet_task import TASK_VERSION, process_log

EXIT_OK, EXIT_FAILED_LOGS, EXIT_USAGE = 0, 1, 2
LOG_SUFFIXES = (".log", ".log.gz", ".asc", ".asc.gz", ".blf", ".trc", ".trc.gz", ".mf4", ".mf4.gz", ".csv.gz")
STAMP = re.compile(r"(\d{8}T\d{6}|\d{4}-\d{2}-\d{2}T\d{2}[-:]\d{2}[-:]\d{2})")
TABLES = ("logs", "dtc_events", "param_tracks", "residual_stats")

EPILOG = """\
inputs (any mix):
  DIR                every log below DIR (.log .log.gz .asc .blf .trc .mf4, also .gz);
                     the vehicle is the log's folder name, the start time the
                     YYYYmmddTHHMMSS (or YYYY-mm-ddTHH-MM-SS) in its file name
  'GLOB'             the same for the files a glob names (quote it)
  MANIFEST.csv       a CSV with the columns vehicle,start,file (start ISO 8601,
                     file relative to the manifest's folder): the vehicle and
                     start of every log, whatever the files are called

examples:
  canfdi-fleet fleet/manifest.csv -o out            # a local Dask cluster, 2 workers here
  canfdi-fleet /data/loggers -o out --workers 8
  canfdi-fleet 'logs/V0*/*.log.gz' -o out --scheduler tcp://10.0.0.5:8786
  canfdi-fleet fleet/ -o out --force                # redo every log

What is written (docs/fleet.md):
  OUT/parquet/{logs,dtc_events,param_tracks,residual_stats}/vehicle=V/date=D/part-0.parquet
  OUT/fleet_report.html   codes per 1000 h, drift ranking, projected threshold
                          crossings, the vehicles that need a workshop
  OUT/fleet_run.json      this run: logs done, cached, failed (with the reason)
  OUT/work/               per-log results and NVM images (what a rerun reuses)

A rerun with the same inputs gives the same tables; a log whose bytes, starting
memory, firmware and DBC are unchanged is not replayed again (--force does).
Progress goes to stderr. Exit status: 0 every log replayed, 1 some logs failed
(each listed with its reason; the others are done), 2 bad usage.

Another cluster (--scheduler): every worker needs this repository (the same
build/bin/canfdi-replay-core, `make all`) and the logs and OUT under the same
paths (a shared file system).
"""


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="canfdi-fleet",
        description="Replay every drive of a fleet through the canfdi supervisor (canfdi-replay per log, "
                    "the DTC memory carried from drive to drive), write the results as Parquet and the fleet "
                    "report: codes per 1000 operating hours, drifting parameters and when they cross their "
                    "thresholds, the vehicles that need a workshop visit.",
        epilog=EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("inputs", nargs="+", metavar="INPUT", help="directories, globs or a manifest CSV")
    p.add_argument("-o", "--output", type=Path, required=True, metavar="OUT", help="results directory")
    c = p.add_argument_group("cluster")
    c.add_argument("--scheduler", metavar="ADDRESS",
                   help="an existing Dask scheduler (e.g. tcp://host:8786); default: a local cluster")
    c.add_argument("--workers", type=int, default=None, metavar="N",
                   help="worker processes of the local cluster (default: the CPUs, %d here)" % (os.cpu_count() or 1))
    p.add_argument("--force", action="store_true", help="replay every log again, even if finished before")
    p.add_argument("--report", type=Path, metavar="FILE", help="the HTML report (default OUT/fleet_report.html)")
    p.add_argument("--no-report", action="store_true", help="tables only")
    p.add_argument("-q", "--quiet", action="store_true", help="no progress lines")
    return p


# ------------------------------------------------------------------ inputs
class InputError(Exception):
    pass


def _is_log(path: Path) -> bool:
    n = path.name.lower()
    return path.is_file() and n.endswith(LOG_SUFFIXES)


def _start_of(path: Path) -> str | None:
    m = STAMP.search(path.name)
    if not m:
        return None
    s = m.group(1)
    for fmt in ("%Y%m%dT%H%M%S", "%Y-%m-%dT%H-%M-%S", "%Y-%m-%dT%H:%M:%S"):
        try:
            return dt.datetime.strptime(s, fmt).isoformat(timespec="seconds")
        except ValueError:
            continue
    return None


def _is_manifest(path: Path) -> bool:
    if path.suffix.lower() != ".csv" or not path.is_file():
        return False
    with path.open(newline="", encoding="utf-8", errors="replace") as f:
        head = f.readline().strip().lower().replace(" ", "")
    return {"vehicle", "file"} <= set(head.split(","))


def discover(inputs: list[str]) -> list[dict[str, Any]]:
    """Every log with its vehicle and start time; a path named twice counts once."""
    logs: dict[str, dict[str, Any]] = {}

    def add(path: Path, vehicle: str, start: str | None) -> None:
        key = str(path.resolve())
        logs.setdefault(key, {"vehicle": vehicle, "start": start, "path": key})

    for item in inputs:
        p = Path(item)
        if _is_manifest(p):
            with p.open(newline="", encoding="utf-8") as f:
                for n, row in enumerate(csv.DictReader(f), start=2):
                    veh, fil = (row.get("vehicle") or "").strip(), (row.get("file") or "").strip()
                    if not veh or not fil:
                        raise InputError(f"{p}:{n}: a row needs a vehicle and a file")
                    start = (row.get("start") or "").strip() or None
                    if start:
                        try:
                            start = dt.datetime.fromisoformat(start).isoformat(timespec="seconds")
                        except ValueError:
                            raise InputError(f"{p}:{n}: start {start!r} is not an ISO 8601 time") from None
                    f_path = Path(fil) if Path(fil).is_absolute() else p.parent / fil
                    add(f_path, veh, start)   # a missing file is a failed task, not a usage error
        elif p.is_dir():
            for f_path in sorted(q for q in p.rglob("*") if _is_log(q)):
                add(f_path, f_path.parent.name, _start_of(f_path))
        elif p.is_file():
            add(p, p.parent.name, _start_of(p))
        else:
            hits = sorted(glob.glob(item, recursive=True))
            if not hits:
                raise InputError(f"{item}: no such file, directory or matching file")
            for h in hits:
                if _is_log(Path(h)):
                    add(Path(h), Path(h).parent.name, _start_of(Path(h)))
    return list(logs.values())


def chains(logs: list[dict[str, Any]]) -> dict[str, list[dict[str, Any]]]:
    """Per vehicle, its logs in time order (then by name; a log without a start time last)."""
    out: dict[str, list[dict[str, Any]]] = {}
    for lg in logs:
        out.setdefault(lg["vehicle"], []).append(lg)
    for v in out.values():
        v.sort(key=lambda lg: (lg["start"] is None, lg["start"] or "", lg["path"]))
    return dict(sorted(out.items()))


# ------------------------------------------------------------------ the run
def _client(a: argparse.Namespace) -> tuple[Any, Any]:
    from dask.distributed import Client, LocalCluster
    if a.scheduler:
        return Client(a.scheduler), None
    n = a.workers or os.cpu_count() or 1
    cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True, host="127.0.0.1",
                           dashboard_address=None, silence_logs=logging.ERROR)
    return Client(cluster), cluster


def run_tasks(vehicles: dict[str, list[dict[str, Any]]], out: Path, a: argparse.Namespace) -> list[dict[str, Any]]:
    from dask.distributed import as_completed
    client, cluster = _client(a)
    try:
        futures = []
        for veh, lgs in vehicles.items():
            prev = None
            for seq, lg in enumerate(lgs):
                job = {**lg, "seq": seq, "out": str(out), "force": a.force}
                # the key names the task; the previous drive's future is its input (the chain)
                prev = client.submit(process_log, job, prev, key=f"canfdi-fleet-{veh}-{seq:04d}", pure=False)
                futures.append(prev)
        results = []
        n, failed, cached, t0 = len(futures), 0, 0, time.perf_counter()
        for fut in as_completed(futures):
            r = fut.result()
            results.append(r)
            failed += r["status"] == "failed"
            cached += bool(r.get("cached"))
            if not a.quiet:
                what = (f"FAILED: {r['reason']}" if r["status"] == "failed" else
                        ("finished before" if r.get("cached") else
                         (", ".join(r["rows"]["logs"][0]["codes"]) or "no code")))
                print(f"canfdi-fleet: [{len(results)}/{n}] {r['vehicle']} drive {r['seq'] + 1} "
                      f"({r.get('start') or Path(r['path']).name}): {what}  "
                      f"[{time.perf_counter() - t0:.1f} s, {failed} failed, {cached} finished before]",
                      file=sys.stderr, flush=True)
        return sorted(results, key=lambda r: (r["vehicle"], r["seq"]))
    finally:
        client.close()
        if cluster is not None:
            cluster.close()


# ------------------------------------------------------------------ Parquet
def schemas() -> dict[str, Any]:
    import pyarrow as pa
    ts = pa.timestamp("us")
    common = [("vehicle", pa.string()), ("date", pa.string()), ("drive_seq", pa.int32()), ("start", ts),
              ("file", pa.string()), ("log_sha256", pa.string()), ("firmware", pa.string()),
              ("dbc_sha256", pa.string())]
    f64, i64, s = pa.float64(), pa.int64(), pa.string()
    return {
        "logs": pa.schema(common + [
            ("status", s), ("reason", s), ("verdict", s), ("codes", pa.list_(s)), ("codes_n", pa.int32()),
            ("start_mode", s), ("duration_s", f64), ("operating_h", f64), ("frames", i64), ("bad_lines", i64),
            ("gaps", i64), ("time_stamps_back", i64), ("frames_rejected", i64), ("error_frames", i64),
            ("bus_load_mean_pct", f64), ("bus_load_max_pct", f64), ("not_judged_monitors", pa.list_(s)),
            ("not_judged_s", f64), ("recorded_ecu_frames", i64), ("recorded_ecu_identical", i64),
            ("nvm_in_sha256", s), ("nvm_out_sha256", s)]),
        "dtc_events": pa.schema(common + [
            ("code", s), ("description", s), ("first_failed_s", f64), ("time", ts), ("status", pa.int32()),
            ("occurrence", pa.int32()), ("confirmed", pa.bool_()), ("confidence_pct", pa.int32()),
            ("degradation_dcm", s), ("degradation_thr", s), ("ff_time_s", f64), ("ff_speed_rad_s", f64),
            ("ff_ia_A", f64), ("ff_ua_V", f64), ("ff_thr_angle_deg", f64), ("ff_supply_V", f64),
            ("ff_deg_dcm", s), ("ff_deg_thr", s)]),
        "param_tracks": pa.schema(common + [
            ("t_s", f64), ("time", ts), ("parameter", s), ("unit", s), ("deviation", f64),
            ("deviation_sigma", f64), ("estimate", f64), ("samples", pa.int32())]),
        "residual_stats": pa.schema(common + [
            ("residual", s), ("samples", i64), ("mean", f64), ("std", f64), ("max_abs", f64),
            ("over_threshold_fraction", f64)]),
    }


def _table(rows: list[dict[str, Any]], schema: Any) -> Any:
    import pyarrow as pa
    fixed = []
    for r in rows:
        d = {}
        for f in schema:
            v = r.get(f.name)
            if pa.types.is_timestamp(f.type) and isinstance(v, str):
                v = dt.datetime.fromisoformat(v)
            d[f.name] = v
        fixed.append(d)
    return pa.Table.from_pylist(fixed, schema=schema)


def write_parquet(results: list[dict[str, Any]], out: Path) -> dict[str, int]:
    """Every table rewritten whole from the results (sorted): the same results, the same tables.
    Hive partitioning vehicle=/date=, one file per partition (part-0.parquet)."""
    import pyarrow.dataset as ds
    base = out / "parquet"
    counts = {}
    for name, schema in schemas().items():
        rows = [row for r in results for row in r["rows"][name]]
        table = _table(rows, schema)
        d = base / name
        if d.exists():
            shutil.rmtree(d)
        d.mkdir(parents=True)
        if table.num_rows:
            ds.write_dataset(table, d, format="parquet", partitioning=["vehicle", "date"],
                             partitioning_flavor="hive", basename_template="part-{i}.parquet",
                             existing_data_behavior="overwrite_or_ignore", use_threads=False)
        counts[name] = table.num_rows
    return counts


def read_table(out: Path, name: str) -> Any:
    """A table back as pandas (the partition columns restored as strings)."""
    import pyarrow.dataset as ds
    d = out / "parquet" / name
    if not any(d.rglob("*.parquet")):
        return _table([], schemas()[name]).to_pandas()
    import pyarrow as pa
    part = ds.partitioning(pa.schema([("vehicle", pa.string()), ("date", pa.string())]), flavor="hive")
    return ds.dataset(d, format="parquet", partitioning=part).to_table().to_pandas()


# ------------------------------------------------------------------ main
def main(argv: list[str] | None = None) -> int:
    a = build_parser().parse_args(argv)
    if a.workers is not None and a.workers < 1:
        print("canfdi-fleet: --workers must be at least 1", file=sys.stderr)
        return EXIT_USAGE
    from .replay import _core_binary
    if not _core_binary().exists():
        print(f"canfdi-fleet: {_core_binary()} is missing: build it with `make all`", file=sys.stderr)
        return EXIT_USAGE
    try:
        logs = discover(a.inputs)
    except InputError as e:
        print(f"canfdi-fleet: {e}", file=sys.stderr)
        return EXIT_USAGE
    if not logs:
        print("canfdi-fleet: no log in the inputs", file=sys.stderr)
        return EXIT_USAGE
    out: Path = a.output.resolve()
    out.mkdir(parents=True, exist_ok=True)
    vehicles = chains(logs)
    if not a.quiet:
        where = a.scheduler or f"a local cluster of {a.workers or os.cpu_count() or 1} worker process(es)"
        print(f"canfdi-fleet: {len(logs)} logs of {len(vehicles)} vehicles on {where}", file=sys.stderr)
    t0 = time.perf_counter()
    results = run_tasks(vehicles, out, a)
    wall = time.perf_counter() - t0
    counts = write_parquet(results, out)
    failed = [{"vehicle": r["vehicle"], "drive": r["seq"] + 1, "file": r["path"], "reason": r["reason"]}
              for r in results if r["status"] == "failed"]
    op_h = sum(r["rows"]["logs"][0].get("operating_h") or 0.0 for r in results)
    run = {"schema": "canfdi-fleet-run/1", "task_version": TASK_VERSION, "logs": len(results),
           "vehicles": len(vehicles), "replayed": sum(1 for r in results if not r.get("cached") and r["status"] == "ok"),
           "finished_before": sum(1 for r in results if r.get("cached")), "failed": failed,
           "operating_h": op_h, "wall_s": round(wall, 3), "rows": counts,
           "workers": None if a.scheduler else (a.workers or os.cpu_count() or 1), "scheduler": a.scheduler}
    (out / "fleet_run.json").write_text(json.dumps(run, indent=1) + "\n", encoding="utf-8")
    if not a.no_report:
        from .fleet_report import write_report
        report = a.report or (out / "fleet_report.html")
        write_report(out, report)
        if not a.quiet:
            print(f"canfdi-fleet: report {report}", file=sys.stderr)
    for f in failed:
        print(f"canfdi-fleet: FAILED {f['vehicle']} drive {f['drive']} {f['file']}: {f['reason']}", file=sys.stderr)
    print(f"canfdi-fleet: {len(results)} logs of {len(vehicles)} vehicles, {op_h:.2f} operating hours: "
          f"{run['replayed']} replayed, {run['finished_before']} finished before, {len(failed)} failed "
          f"({wall:.1f} s); tables in {out / 'parquet'}")
    return EXIT_FAILED_LOGS if failed else EXIT_OK


if __name__ == "__main__":
    sys.exit(main())
