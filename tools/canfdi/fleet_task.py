"""One canfdi-fleet task: one log of one vehicle through canfdi-replay, with the DTC memory (the
NVM image) the vehicle's previous drive left, and the rows of the fleet's Parquet tables
(docs/fleet.md) made of what the replay found.

A task is keyed by everything its result depends on: the log's bytes, the NVM image it starts
from, the firmware id, the DBC and the task's own settings (TASK_VERSION). A finished task's
result is kept in OUT/work/<vehicle>/<seq>.json with its image (<seq>.nvm); the same key again
returns it without replaying (unless forced), so a rerun redoes only what changed and what
follows it in the vehicle's chain. A log that cannot be replayed is a failed task with its reason;
the vehicle's memory goes on to the next drive unchanged, as if the drive had not been recorded.
"""
from __future__ import annotations

import contextlib
import datetime as dt
import hashlib
import io
import json
import math
import os
import shutil
import statistics
import subprocess
import time
from pathlib import Path
from typing import Any

from . import DBC_PATH

#: bump when the rows a task makes change (a cached result of another version is redone)
TASK_VERSION = "canfdi-fleet-task/2"
SAMPLE_S = 0.1          # the core's sample interval ("s" events)
TRACK_WINDOW_S = 5.0    # the parameter tracks' down-sampling window
BITRATE = 1_000_000
PARAMS = ("R_A", "Psi", "J", "M_c", "thr_R", "thr_K", "spring", "friction")
PARAM_UNITS = ("ohm", "V*s", "kg*m^2", "N*m", "ohm", "N*m/A", "N*m/rad", "N*m")
RESIDUALS = ("dcm_r1", "dcm_r2", "dcm_r3", "dcm_r4", "thr_CORR", "thr_ARM", "thr_POS1", "thr_POS2")


def sha256_file(path: Path) -> str:
    h = hashlib.sha256()
    with path.open("rb") as f:
        for chunk in iter(lambda: f.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


def firmware_id() -> str:
    from .replay import _core_binary
    return subprocess.run([str(_core_binary()), "--fw-id"], capture_output=True, text=True,
                          check=True).stdout.strip()


def _bit(masks: list[int], i: int) -> bool:
    return bool(masks[i // 4] >> (i % 4) & 1)


def _tracks(samples: list[dict[str, Any]], settle_until: float) -> list[dict[str, Any]]:
    """Down-sampled parameter estimates: per window and parameter the median of the valid samples,
    their spread (sample standard deviation) as the uncertainty, and how many there were."""
    win: dict[tuple[int, int], list[tuple[float, float]]] = {}
    for e in samples:
        t = float(e["t"])
        if t < settle_until:
            continue
        w = int(t // TRACK_WINDOW_S)
        for i in range(len(PARAMS)):
            if _bit(e["pv"], i):
                win.setdefault((w, i), []).append((float(e["p"][i]), float(e["e"][i])))
    rows = []
    for (w, i), vals in sorted(win.items()):
        devs = [v[0] for v in vals]
        rows.append({
            "t_s": round((w + 0.5) * TRACK_WINDOW_S, 3), "parameter": PARAMS[i], "unit": PARAM_UNITS[i],
            "deviation": statistics.median(devs),
            "deviation_sigma": statistics.stdev(devs) if len(devs) > 1 else None,
            "estimate": statistics.median(v[1] for v in vals), "samples": len(vals),
        })
    return rows


def _residual_stats(samples: list[dict[str, Any]]) -> list[dict[str, Any]]:
    rows = []
    for i, name in enumerate(RESIDUALS):
        vals = [float(e["r"][i]) for e in samples if e["rv"][i // 4] >> (i % 4) & 1]
        n = len(vals)
        rows.append({
            "residual": name, "samples": n,
            "mean": statistics.fmean(vals) if n else None,
            "std": statistics.pstdev(vals) if n else None,
            "max_abs": max(abs(v) for v in vals) if n else None,
            "over_threshold_fraction": (sum(1 for v in vals if abs(v) >= 1.0) / n) if n else None,
        })
    return rows


def _common(job: dict[str, Any], log_sha: str, fw: str, dbc_sha: str) -> dict[str, Any]:
    start = dt.datetime.fromisoformat(job["start"]) if job.get("start") else None
    return {"vehicle": job["vehicle"], "date": start.date().isoformat() if start else "unknown",
            "drive_seq": job["seq"], "start": start, "file": job["path"], "log_sha256": log_sha,
            "firmware": fw, "dbc_sha256": dbc_sha}


def _replay(job: dict[str, Any], nvm_in: str | None, nvm_out: Path) -> tuple[int, str, Any, dict[str, Any]]:
    """Runs canfdi-replay's core over the log; returns (rc, messages, report, json doc)."""
    from .replay import build_parser, run
    from .replay_report import Report
    args = [job["path"], "-q", "--no-progress", "--nvm-out", str(nvm_out)]
    if nvm_in:
        args += ["--nvm-in", nvm_in]
    a = build_parser().parse_args(args)
    a.samples_every = SAMPLE_S
    report = Report()
    err = io.StringIO()
    with contextlib.redirect_stderr(err):
        rc = run(a, report)
    doc = report.to_json(BITRATE, "canfdi-fleet") if rc == 0 else {}
    return rc, err.getvalue().strip(), report, doc


def process_log(job: dict[str, Any], prev: dict[str, Any] | None) -> dict[str, Any]:
    """The task: job = {vehicle, seq, start (ISO or None), path, out, force}; prev = the result of
    the vehicle's previous drive (None for its first). Never raises: a failure is a result."""
    t0 = time.perf_counter()
    out = Path(job["out"]) / "work" / job["vehicle"]
    out.mkdir(parents=True, exist_ok=True)
    res_path = out / f"{job['seq']:04d}.json"
    nvm_path = out / f"{job['seq']:04d}.nvm"
    nvm_in = prev.get("nvm_out") if prev else None
    base = {"vehicle": job["vehicle"], "seq": job["seq"], "start": job.get("start"), "path": job["path"],
            "nvm_in": nvm_in}
    try:
        fw = firmware_id()
        dbc_sha = sha256_file(DBC_PATH)
        log_sha = sha256_file(Path(job["path"]))
    except (OSError, subprocess.CalledProcessError) as e:
        return _failed(base, job, nvm_in, nvm_path, res_path, f"{type(e).__name__}: {e}", "", "", "", t0)
    nvm_in_sha = sha256_file(Path(nvm_in)) if nvm_in else ""
    key = hashlib.sha256(json.dumps([TASK_VERSION, log_sha, nvm_in_sha, fw, dbc_sha, SAMPLE_S,
                                     TRACK_WINDOW_S, job.get("start"), job["vehicle"], job["path"]]).encode()
                         ).hexdigest()
    if not job.get("force") and res_path.exists():
        try:
            old = json.loads(res_path.read_text(encoding="utf-8"))
            if old.get("key") == key and (old.get("nvm_out") is None or Path(old["nvm_out"]).exists()):
                old["cached"] = True
                old["elapsed_s"] = round(time.perf_counter() - t0, 3)
                return old
        except (OSError, ValueError):
            pass
    tmp_nvm = nvm_path.with_suffix(".nvm.tmp")
    try:
        rc, msgs, report, doc = _replay(job, nvm_in, tmp_nvm)
    except Exception as e:  # noqa: BLE001 — a task reports, never raises
        rc, msgs, report, doc = 2, f"{type(e).__name__}: {e}", None, {}
    lg = report.logs[0] if report is not None and report.logs else None
    if rc != 0 or lg is None or not tmp_nvm.exists():
        return _failed(base, job, nvm_in, nvm_path, res_path, msgs or f"the replay failed (exit {rc})",
                       fw, dbc_sha, log_sha, t0, key)
    if not lg.eof.get("frames"):
        # nothing could be read from the file: for a fleet, an unusable file (canfdi-replay says
        # "nothing judged"); the memory is not touched, as for any failed file
        tmp_nvm.unlink()
        why = f"no CAN frame could be read from the log (format {lg.fmt}"
        why += f", {lg.input_problem_count} input problem(s))" if lg.input_problem_count else ")"
        return _failed(base, job, nvm_in, nvm_path, res_path, why + (f": {msgs}" if msgs else ""),
                       fw, dbc_sha, log_sha, t0, key)
    os.replace(tmp_nvm, nvm_path)
    common = _common(job, log_sha, fw, dbc_sha)
    start: dt.datetime | None = common["start"]
    eof = lg.eof
    first_t, last_t = float(eof.get("first_t", 0.0)), float(eof.get("last_t", 0.0))
    duration = max(0.0, last_t - first_t + 0.001) if eof.get("steps") else 0.0
    dq = doc["data_quality"][0]
    not_judged = [n for n in doc["not_judged"] if n["log"] == 0]
    judged_any = any(f["ok"] for f in lg.frames) and bool(eof.get("steps"))
    codes = sorted({f["code"] for f in doc["dtcs"]})
    rej = {k: sum(v.values()) for k, v in dq["rejected_frames"].items()}
    summary = {
        **common, "status": "ok", "reason": "",
        "verdict": "codes found" if codes else ("no code" if judged_any else "not judged"),
        "codes": codes, "codes_n": len(codes),
        "start_mode": lg.start, "duration_s": round(duration, 3), "operating_h": duration / 3600.0,
        "frames": int(eof.get("frames", 0)), "bad_lines": int(dq["bad_line_count"]),
        "gaps": int(dq["gap_count"]), "time_stamps_back": int(dq["time_stamps_back"]),
        "frames_rejected": int(sum(rej.values())), "error_frames": int(dq["error_frames"]),
        "bus_load_mean_pct": float(dq["bus_load_pct"]["mean"]), "bus_load_max_pct": float(dq["bus_load_pct"]["max"]),
        "not_judged_monitors": sorted({n["monitor"] for n in not_judged}),
        "not_judged_s": round(sum(n["seconds"] for n in not_judged), 3),
        "recorded_ecu_frames": int(lg.agree.get("recorded_ecu_frames") or 0),
        "recorded_ecu_identical": int(lg.agree.get("matched") or 0),
        "nvm_in_sha256": nvm_in_sha, "nvm_out_sha256": sha256_file(nvm_path),
    }
    events = []
    for f in doc["dtcs"]:
        ff = f.get("freeze_frame") or {}
        ev = {**common, "code": f["code"], "description": f["description"],
              "first_failed_s": f["first_failed_s"],
              "time": start + dt.timedelta(seconds=f["first_failed_s"]) if start else None,
              "status": f["status"], "occurrence": f["occurrence"],
              "confirmed": bool(f["status"] is not None and f["status"] & 0x08),
              "confidence_pct": f["confidence_pct"],
              "degradation_dcm": (f["degradation"] or {}).get("dcm"),
              "degradation_thr": (f["degradation"] or {}).get("thr")}
        for k in ("time_s", "speed_rad_s", "ia_A", "ua_V", "thr_angle_deg", "supply_V"):
            ev[f"ff_{k}"] = ff.get(k)
        ev["ff_deg_dcm"], ev["ff_deg_thr"] = ff.get("deg_dcm"), ff.get("deg_thr")
        events.append(ev)
    tracks = [{**common, **r, "time": start + dt.timedelta(seconds=r["t_s"]) if start else None}
              for r in _tracks(lg.samples, lg.settle_until if lg.start == "mid-drive" else first_t)]
    resid = [{**common, **r} for r in _residual_stats(lg.samples)]
    result = {**base, "key": key, "status": "ok", "reason": "", "cached": False,
              "nvm_out": str(nvm_path), "memory": {c: {"status": m["status"], "occ": m["occ"]}
                                                     for c, m in sorted(report.memory.items())},
              "rows": {"logs": [summary], "dtc_events": events, "param_tracks": tracks, "residual_stats": resid},
              "elapsed_s": round(time.perf_counter() - t0, 3)}
    _store(res_path, result)
    return result


def _failed(base: dict[str, Any], job: dict[str, Any], nvm_in: str | None, nvm_path: Path, res_path: Path,
            reason: str, fw: str, dbc_sha: str, log_sha: str, t0: float, key: str = "") -> dict[str, Any]:
    # the memory goes on unchanged to the vehicle's next drive
    nvm_out = None
    if nvm_in:
        shutil.copyfile(nvm_in, nvm_path)
        nvm_out = str(nvm_path)
    elif nvm_path.exists():
        nvm_path.unlink()
    reason = " ".join(reason.split())[:500]
    summary = {**_common(job, log_sha, fw, dbc_sha), "status": "failed", "reason": reason, "verdict": "failed",
               "codes": [], "codes_n": 0, "not_judged_monitors": []}
    result = {**base, "key": key, "status": "failed", "reason": reason, "cached": False, "nvm_out": nvm_out,
              "memory": {}, "rows": {"logs": [summary], "dtc_events": [], "param_tracks": [], "residual_stats": []},
              "elapsed_s": round(time.perf_counter() - t0, 3)}
    if key:
        _store(res_path, result)
    return result


def _store(path: Path, result: dict[str, Any]) -> None:
    tmp = path.with_suffix(".json.tmp")
    tmp.write_text(json.dumps(result, default=_json_default, sort_keys=True) + "\n", encoding="utf-8")
    os.replace(tmp, path)
    # what a cached result gives back is what was stored
    result.update(json.loads(path.read_text(encoding="utf-8")))


def _json_default(o: Any) -> Any:
    if isinstance(o, dt.datetime):
        return o.isoformat()
    if isinstance(o, float) and not math.isfinite(o):
        return None
    raise TypeError(type(o).__name__)
