"""The fleet picture from canfdi-fleet's Parquet tables (docs/fleet.md), and its HTML report.

analyse(out) works on the tables alone:
  codes per 1000 operating hours   drives in which a code was found, per 1000 h of the drives
                                   replayed (fleet-wide per code, and per vehicle and code)
  parameter trends                 per vehicle and estimated parameter: one value per drive (the
                                   median of its track's windows), a least-squares line over
                                   calendar time; the parameter is *drifting* when the slope is
                                   at least 3 standard errors from zero and the line moves by more
                                   than the estimator's stated accuracy (SYSTEMATIC) over the drives
  projected crossing               where the line reaches the firmware's threshold for that
                                   parameter (the replay core's calibration, THRESHOLDS): a time
                                   with a standard deviation from the fit's covariance (delta
                                   method) and the estimator's accuracy over the slope, reported
                                   as +/- 2 sigma; remaining useful life = crossing - last drive
  workshop list                    a code confirmed in the vehicle's memory or found in its last
                                   drive, an intermittent code found in two or more drives, or a
                                   drifting parameter whose crossing can come within HORIZON_DAYS
"""
from __future__ import annotations

import base64
import html
import io
import json
import math
import subprocess
from pathlib import Path
from typing import Any

from .fleet_task import PARAMS

#: the estimators' stated accuracy (docs/requirements.md, 12: R_A and Psi 2 %, J 5 %, M_c 3 %,
#: throttle R 2 %, K 3 %, spring 10 %; the friction's is not stated: taken as the spring's)
SYSTEMATIC = {"R_A": 0.02, "Psi": 0.02, "J": 0.05, "M_c": 0.03, "thr_R": 0.02, "thr_K": 0.03,
              "spring": 0.10, "friction": 0.10}
HORIZON_DAYS = 30.0
MIN_DRIVES = 3
Z_DRIFT = 3.0


def thresholds() -> dict[str, tuple[float, float]]:
    """(positive, negative) relative threshold of each parameter, from the replay core's header."""
    from .replay import _core_binary
    out = subprocess.run([str(_core_binary()), "/dev/null"], capture_output=True, text=True, check=True).stdout
    t = json.loads(out.splitlines()[0])["thr_pos"]
    pos, neg = t["dcm_pos"] + t["thr_pos"], t["dcm_neg"] + t["thr_neg"]
    return {p: (float(pos[i]), float(neg[i])) for i, p in enumerate(PARAMS)}


def _fit(x: list[float], y: list[float]) -> dict[str, float] | None:
    n = len(x)
    if n < MIN_DRIVES:
        return None
    mx, my = sum(x) / n, sum(y) / n
    sxx = sum((a - mx) ** 2 for a in x)
    if sxx <= 0:
        return None
    b = sum((a - mx) * (c - my) for a, c in zip(x, y)) / sxx
    a0 = my - b * mx
    s2 = sum((c - a0 - b * a) ** 2 for a, c in zip(x, y)) / max(1, n - 2)
    s2 = max(s2, 1e-10)
    var_b = s2 / sxx
    var_a = s2 * (1.0 / n + mx * mx / sxx)
    cov_ab = -mx * s2 / sxx
    return {"a": a0, "b": b, "var_a": var_a, "var_b": var_b, "cov_ab": cov_ab, "s": math.sqrt(s2), "n": n}


def analyse(out: Path) -> dict[str, Any]:
    from .fleet import read_table
    logs = read_table(out, "logs")
    events = read_table(out, "dtc_events")
    tracks = read_table(out, "param_tracks")
    thr = thresholds()
    ok = logs[logs["status"] == "ok"]
    total_h = float(ok["operating_h"].sum()) if len(ok) else 0.0
    veh_h = {v: float(g["operating_h"].sum()) for v, g in ok.groupby("vehicle")}
    per_code: dict[str, dict[str, Any]] = {}
    per_vehicle_code: dict[str, dict[str, int]] = {}
    first_drive: dict[str, dict[str, int]] = {}
    for r in events.sort_values(["vehicle", "drive_seq"]).itertuples():
        pc = per_code.setdefault(r.code, {"code": r.code, "description": r.description, "drives": 0, "vehicles": set()})
        pc["drives"] += 1
        pc["vehicles"].add(r.vehicle)
        per_vehicle_code.setdefault(r.vehicle, {}).setdefault(r.code, 0)
        per_vehicle_code[r.vehicle][r.code] += 1
        first_drive.setdefault(r.vehicle, {}).setdefault(r.code, int(r.drive_seq))
    codes = sorted(({**v, "vehicles": sorted(v["vehicles"]),
                     "per_1000h": 1000.0 * v["drives"] / total_h if total_h else None} for v in per_code.values()),
                   key=lambda c: -c["per_1000h"] if c["per_1000h"] else 0)
    # the memory after each vehicle's last drive: the last event per code (its status at the end of that drive)
    last_seq = {v: int(g["drive_seq"].max()) for v, g in logs.groupby("vehicle")}
    trends = []
    if len(tracks):
        starts = {(r.vehicle, int(r.drive_seq)): r.start for r in logs.itertuples()}
        per_drive = (tracks.groupby(["vehicle", "drive_seq", "parameter"])["deviation"]
                     .agg(["median", "std", "count"]).reset_index())
        for (veh, par), g in per_drive.groupby(["vehicle", "parameter"]):
            g = g.sort_values("drive_seq")
            t_first = min(starts[(veh, int(s))] for s in g["drive_seq"])
            if t_first is None or str(t_first) == "NaT":
                continue
            x = [(starts[(veh, int(s))] - t_first).total_seconds() / 86400.0 for s in g["drive_seq"]]
            y = [float(v) for v in g["median"]]
            f = _fit(x, y)
            if f is None:
                continue
            span = max(x) - min(x)
            z = abs(f["b"]) / math.sqrt(f["var_b"]) if f["var_b"] > 0 else math.inf
            moved = abs(f["b"]) * span
            drifting = z >= Z_DRIFT and moved > SYSTEMATIC[par]
            pos, neg = thr[par]
            limit = pos if f["b"] > 0 else -neg
            tr = {"vehicle": veh, "parameter": par, "drives": f["n"], "slope_per_day": f["b"], "z": z,
                  "moved": moved, "last": y[-1], "fit_last": f["a"] + f["b"] * x[-1], "threshold": limit,
                  "drifting": drifting, "x": x, "y": y, "seq": [int(s) for s in g["drive_seq"]],
                  "first_start": t_first.isoformat(), "last_start": (t_first + _days(x[-1])).isoformat(),
                  "fit": f, "crossing": None}
            if drifting:
                t = (limit - f["a"]) / f["b"]
                da, db = -1.0 / f["b"], -(limit - f["a"]) / f["b"] ** 2
                var = da * da * f["var_a"] + db * db * f["var_b"] + 2 * da * db * f["cov_ab"]
                sig = math.sqrt(max(var, 0.0) + (SYSTEMATIC[par] / abs(f["b"])) ** 2)
                h_per_day = veh_h.get(veh, 0.0) / max(span, 1e-9)
                tr["crossing"] = {
                    "time": (t_first + _days(t)).isoformat(timespec="minutes"), "days_from_first": t,
                    "sigma_days": sig, "rul_days": t - x[-1], "rul_h": (t - x[-1]) * h_per_day,
                    "crossed": (f["a"] + f["b"] * x[-1] - limit) * (1 if f["b"] > 0 else -1) >= 0}
            trends.append(tr)
    drifting = sorted((t for t in trends if t["drifting"]), key=lambda t: t["crossing"]["rul_days"])
    rank: dict[str, dict[str, Any]] = {}
    for t in drifting:
        rank.setdefault(t["vehicle"], t)
    ranking = [{"vehicle": v, "parameter": t["parameter"], "rul_days": t["crossing"]["rul_days"],
                "sigma_days": t["crossing"]["sigma_days"], "slope_pct_per_week": 700.0 * t["slope_per_day"],
                "last_pct": 100.0 * t["last"], "threshold_pct": 100.0 * t["threshold"],
                "crossed": t["crossing"]["crossed"]} for v, t in rank.items()]
    workshop: dict[str, list[str]] = {}
    for veh, seqs in sorted(per_vehicle_code.items()):
        ev_v = events[events["vehicle"] == veh]
        for code, n in sorted(seqs.items()):
            last = ev_v[ev_v["code"] == code].sort_values("drive_seq").iloc[-1]
            if bool(last["confirmed"]) or int(last["drive_seq"]) == last_seq.get(veh):
                workshop.setdefault(veh, []).append(
                    f"{code} {'confirmed' if bool(last['confirmed']) else 'found'} (found in {n} drive(s), "
                    f"first in drive {first_drive[veh][code] + 1}): {last['description']}")
            elif n >= 2:
                workshop.setdefault(veh, []).append(f"{code} intermittent: found in {n} drives")
    for t in drifting:
        c = t["crossing"]
        if c["crossed"] or c["rul_days"] - 2 * c["sigma_days"] <= HORIZON_DAYS:
            when = ("already past it" if c["crossed"] else
                    f"crossing projected {c['time'][:10]} (in {c['rul_days']:.0f} ± {2 * c['sigma_days']:.0f} days)")
            workshop.setdefault(t["vehicle"], []).append(
                f"{t['parameter']} drifting {700 * t['slope_per_day']:+.2f} %/week, now {100 * t['fit_last']:+.1f} % "
                f"(threshold {100 * t['threshold']:+.0f} %): {when}")
    return {"operating_h": total_h, "vehicle_h": veh_h, "logs": len(logs), "logs_ok": len(ok),
            "failed": logs[logs["status"] == "failed"][["vehicle", "drive_seq", "file", "reason"]].to_dict("records"),
            "vehicles": sorted(logs["vehicle"].unique().tolist()), "codes": codes,
            "per_vehicle_code": per_vehicle_code, "first_drive": first_drive, "trends": trends,
            "drifting": drifting, "ranking": ranking, "workshop": workshop,
            "firmware": sorted(logs["firmware"].dropna().unique().tolist())}


def _days(d: float) -> Any:
    import datetime as dt
    return dt.timedelta(days=d)


# ------------------------------------------------------------------ HTML
def _png(fig: Any) -> str:
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=90, bbox_inches="tight")
    import matplotlib.pyplot as plt
    plt.close(fig)
    return f'<img src="data:image/png;base64,{base64.b64encode(buf.getvalue()).decode()}">'


def _trend_fig(t: dict[str, Any]) -> str:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    f, c = t["fit"], t["crossing"]
    fig, ax = plt.subplots(figsize=(4.6, 2.6))
    ax.plot(t["x"], [100 * v for v in t["y"]], "o", color="#1f4e79", ms=4, label="per drive")
    x_end = max(t["x"][-1], c["days_from_first"] + 2 * c["sigma_days"]) if c else t["x"][-1]
    xs = [0.0, x_end]
    ax.plot(xs, [100 * (f["a"] + f["b"] * x) for x in xs], "-", color="#1f4e79", lw=1, label="trend")
    ax.axhline(100 * t["threshold"], color="#b00", lw=1, ls="--", label="threshold")
    if c:
        ax.axvspan(c["days_from_first"] - 2 * c["sigma_days"], c["days_from_first"] + 2 * c["sigma_days"],
                   color="#f4b183", alpha=0.4, label="crossing ±2σ")
        ax.axvline(c["days_from_first"], color="#c55a11", lw=1)
    ax.set_xlabel(f"days since {t['first_start'][:10]}")
    ax.set_ylabel(f"{t['parameter']} deviation [%]")
    ax.set_title(f"{t['vehicle']} {t['parameter']}", fontsize=10)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, loc="best")
    return _png(fig)


def _codes_fig(a: dict[str, Any]) -> str:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    codes = a["codes"]
    fig, ax = plt.subplots(figsize=(6, 0.45 * max(2, len(codes)) + 0.8))
    ax.barh([c["code"] for c in codes][::-1], [c["per_1000h"] for c in codes][::-1], color="#1f4e79")
    ax.set_xlabel("drives with the code per 1000 operating hours")
    ax.grid(axis="x", alpha=0.3)
    return _png(fig)


CSS = """body{font-family:system-ui,sans-serif;margin:24px;color:#222;max-width:1200px}
h1{font-size:22px}h2{font-size:18px;border-bottom:1px solid #ccc;margin-top:28px}
table{border-collapse:collapse;font-size:13px}td,th{border:1px solid #ccc;padding:3px 7px;text-align:right}
th{background:#eef}td.l,th.l{text-align:left}.bad{background:#fdd}.warn{background:#ffe9c7}
.grid{display:flex;flex-wrap:wrap;gap:8px}.small{font-size:12px;color:#555}"""


def write_report(out: Path, path: Path) -> dict[str, Any]:
    a = analyse(out)
    run = {}
    try:
        run = json.loads((out / "fleet_run.json").read_text(encoding="utf-8"))
    except (OSError, ValueError):
        pass
    e = html.escape
    h: list[str] = [f"<!doctype html><html><head><meta charset='utf-8'><title>canfdi fleet report</title>"
                    f"<style>{CSS}</style></head><body>"]
    h.append("<h1>canfdi fleet report</h1>")
    h.append(f"<p>{len(a['vehicles'])} vehicles, {a['logs']} logs ({a['logs_ok']} replayed, {len(a['failed'])} failed), "
             f"{a['operating_h']:.2f} operating hours; firmware {e(', '.join(a['firmware']))}. "
             f"Tables: <code>{e(str(out / 'parquet'))}</code> (docs/fleet.md).</p>")
    h.append("<h2>Vehicles that need a workshop visit</h2>")
    if a["workshop"]:
        h.append("<table><tr><th class=l>vehicle</th><th class=l>why</th></tr>")
        for v, why in sorted(a["workshop"].items()):
            h.append(f"<tr><td class=l>{e(v)}</td><td class=l>{'<br>'.join(e(w) for w in why)}</td></tr>")
        h.append("</table>")
    else:
        h.append("<p>none</p>")
    h.append("<h2>Trouble codes per 1000 operating hours</h2>")
    if a["codes"]:
        h.append(_codes_fig(a))
        h.append("<table><tr><th class=l>code</th><th class=l>description</th><th>drives</th><th>per 1000 h</th>"
                 "<th class=l>vehicles</th></tr>")
        for c in a["codes"]:
            h.append(f"<tr><td class=l>{e(c['code'])}</td><td class=l>{e(c['description'])}</td><td>{c['drives']}</td>"
                     f"<td>{c['per_1000h']:.0f}</td><td class=l>{e(', '.join(c['vehicles']))}</td></tr>")
        h.append("</table>")
        allc = [c["code"] for c in a["codes"]]
        h.append("<p class=small>By vehicle (drives with the code per 1000 h of that vehicle's drives):</p>"
                 "<table><tr><th class=l>vehicle</th><th>hours</th>" + "".join(f"<th>{e(c)}</th>" for c in allc) + "</tr>")
        for v in a["vehicles"]:
            row = a["per_vehicle_code"].get(v, {})
            hv = a["vehicle_h"].get(v, 0.0)
            cells = "".join((f"<td class=bad>{1000.0 * row[c] / hv:.0f}</td>" if row.get(c) and hv else "<td></td>")
                            for c in allc)
            h.append(f"<tr><td class=l>{e(v)}</td><td>{hv:.2f}</td>{cells}</tr>")
        h.append("</table>")
    else:
        h.append("<p>no trouble code in any drive</p>")
    h.append("<h2>Vehicles ranked by parameter drift</h2>")
    h.append("<p class=small>Per vehicle its most urgent drifting parameter (slope ≥ 3 standard errors and a change "
             "larger than the estimator's stated accuracy), soonest projected threshold crossing first.</p>")
    if a["ranking"]:
        h.append("<table><tr><th>#</th><th class=l>vehicle</th><th class=l>parameter</th><th>now [%]</th>"
                 "<th>threshold [%]</th><th>drift [%/week]</th><th>remaining useful life [days]</th></tr>")
        for i, r in enumerate(a["ranking"], 1):
            rul = "crossed" if r["crossed"] else f"{r['rul_days']:.0f} ± {2 * r['sigma_days']:.0f}"
            cls = " class=bad" if r["crossed"] else (" class=warn" if r["rul_days"] <= HORIZON_DAYS else "")
            h.append(f"<tr{cls}><td>{i}</td><td class=l>{e(r['vehicle'])}</td><td class=l>{e(r['parameter'])}</td>"
                     f"<td>{r['last_pct']:+.1f}</td><td>{r['threshold_pct']:+.0f}</td>"
                     f"<td>{r['slope_pct_per_week']:+.2f}</td><td>{rul}</td></tr>")
        h.append("</table>")
    else:
        h.append("<p>no drifting parameter</p>")
    h.append("<h2>Trends and projected threshold crossings</h2><div class=grid>")
    for t in a["drifting"][:40]:
        h.append(_trend_fig(t))
    h.append("</div>")
    if a["failed"]:
        h.append("<h2>Logs that could not be replayed</h2><table><tr><th class=l>vehicle</th><th>drive</th>"
                 "<th class=l>file</th><th class=l>reason</th></tr>")
        for f in a["failed"]:
            h.append(f"<tr class=bad><td class=l>{e(f['vehicle'])}</td><td>{int(f['drive_seq']) + 1}</td>"
                     f"<td class=l>{e(str(f['file']))}</td><td class=l>{e(str(f['reason']))}</td></tr>")
        h.append("</table>")
    if run:
        h.append(f"<p class=small>Run: {run.get('logs')} logs, {run.get('replayed')} replayed, "
                 f"{run.get('finished_before')} finished before, {run.get('wall_s')} s wall.</p>")
    h.append("</body></html>\n")
    path.write_text("".join(h), encoding="utf-8")
    return a
