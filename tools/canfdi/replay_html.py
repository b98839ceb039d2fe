"""The HTML report of canfdi-replay: one self-contained file, the plots inline.

Sections: the logs and the firmware that judged them, the trouble codes
found (with the recorded ECU's times), the trouble-code timeline with the
spans that could not be judged, residuals against their thresholds,
parameter estimates over the log (their drift is what wears), degradation
states, the fault-symptom evidence behind each code, what could not be
judged and why, and the log's data quality. Plots are drawn with
matplotlib (Agg) and embedded as base64 PNG; no file or network is
referenced. A small script marks the body with the number of images the
browser decoded (data-images-ok), which the tests read.
"""
from __future__ import annotations

import base64
import html
import io
from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402  (the backend first)

from .replay_report import (DCM_CHANNELS, MONITORS, THR_CHANNELS, LogState, Report,  # noqa: E402
                            _tf_intervals, status_text, where)

RES_NAMES = ("dcm r1", "dcm r2", "dcm r3", "dcm r4", "thr CORR", "thr ARM", "thr POS1", "thr POS2")
PAR_NAMES = ("R_A", "Ψ", "J", "friction M_c", "thr motor R", "thr K", "spring", "thr friction")
EST_UNITS = ("Ω", "V s", "kg m²", "N m", "Ω", "N m/A", "N m", "N m")
CSS = """
body{font-family:system-ui,sans-serif;margin:1.5em;max-width:1200px;color:#222}
h1{font-size:1.5em}h2{font-size:1.2em;border-bottom:1px solid #ccc;margin-top:1.6em}
table{border-collapse:collapse;margin:.5em 0}td,th{border:1px solid #ccc;padding:3px 7px;font-size:.9em;
vertical-align:top}th{background:#f2f2f2;text-align:left}.found{background:#fde8e8}.ok{color:#186a18}
.warn{color:#a04000}code{font-size:.9em}img{max-width:100%;border:1px solid #eee}.small{font-size:.85em;color:#555}
"""
SCRIPT = ("<script>window.addEventListener('load',function(){var n=0;for(var i=0;i<document.images.length;i++)"
          "{var m=document.images[i];if(m.complete&&m.naturalWidth>0)n++;}"
          "document.body.setAttribute('data-images-ok',n);});</script>")


def _png(fig: Any) -> str:
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=90, bbox_inches="tight")
    plt.close(fig)
    return "data:image/png;base64," + base64.b64encode(buf.getvalue()).decode("ascii")


def _shade_untested(ax: Any, lg: LogState, monitors: tuple[str, ...]) -> None:
    labelled = False
    for m in monitors:
        for s in lg.untested_spans(m):
            ax.axvspan(s.t0, s.t1, color="#999999", alpha=0.15, lw=0,
                       label=None if labelled else "not judged")
            labelled = True


def _timeline_png(report: Report, lg: LogState) -> str:
    codes = sorted(set(lg.dtc_rep) | set(lg.dtc_ecu),
                   key=lambda c: min([t for t, st, _ in lg.dtc_rep.get(c, []) + lg.dtc_ecu.get(c, []) if st & 1]
                                     or [1e18]))
    codes = [c for c in codes if any(st & 1 for _, st, _ in lg.dtc_rep.get(c, []) + lg.dtc_ecu.get(c, []))]
    n = max(len(codes), 1)
    fig, (ax, ax2) = plt.subplots(2, 1, figsize=(11, 1.2 + 0.45 * n + 1.6), sharex=True,
                                  gridspec_kw={"height_ratios": [0.45 * n + 0.6, 1.4]})
    t0 = float(lg.eof.get("first_t", 0.0))
    for y, code in enumerate(codes):
        for a, b in _tf_intervals(lg.dtc_rep.get(code, []), lg.end_t):
            ax.broken_barh([(a, max(b - a, 0.002))], (y - 0.3, 0.6), color="#c0392b")
        for a, _ in _tf_intervals(lg.dtc_ecu.get(code, []), lg.end_t):
            ax.plot([a], [y], marker="v", color="#1f4e99", ms=8)
    ax.set_yticks(range(len(codes)))
    ax.set_yticklabels(codes)
    ax.set_ylim(-0.7, n - 0.3)
    _shade_untested(ax, lg, ("dcm_models", "thr_models"))
    ax.set_title("trouble codes: testFailed in the replay (bars), first testFailed of the recorded ECU (▼); "
                 "grey: models not judged", fontsize=9)
    if not codes:
        ax.text(0.5, 0.5, "no trouble code", transform=ax.transAxes, ha="center")
    # degradation
    for key, off, col in (("dcm", 0.0, "#8e44ad"), ("thr", 0.08, "#16a085")):
        ts, vs = [], []
        for d in lg.deg:
            ts.append(d["t"])
            vs.append(("normal", "degraded", "fail_safe", "fail_silent").index(d[key]) + off)
        if ts:
            ts.append(lg.end_t)
            vs.append(vs[-1])
            ax2.step(ts, vs, where="post", color=col, label=f"{key} degradation")
    ax2.set_yticks([0, 1, 2, 3])
    ax2.set_yticklabels(["normal", "degraded", "fail_safe", "fail_silent"], fontsize=8)
    ax2.set_xlabel("log time [s]")
    ax2.legend(loc="upper left", fontsize=8)
    ax2.set_xlim(t0, lg.end_t)
    return _png(fig)


def _residuals_png(report: Report, lg: LogState) -> str | None:
    if not lg.samples:
        return None
    t = [s["t"] for s in lg.samples]
    fig, axes = plt.subplots(2, 1, figsize=(11, 5.2), sharex=True)
    for half, ax in enumerate(axes):
        for k in range(4):
            i = 4 * half + k
            ys = [s["r"][i] if (s["rv"][half] >> k) & 1 else float("nan") for s in lg.samples]
            ax.plot(t, ys, lw=0.8, label=RES_NAMES[i])
        ax.axhline(1.0, color="k", ls="--", lw=0.8)
        ax.axhline(-1.0, color="k", ls="--", lw=0.8)
        ax.set_ylabel("residual / threshold")
        _shade_untested(ax, lg, ("dcm_models",) if half == 0 else ("thr_models",))
        ax.legend(loc="upper left", fontsize=8, ncol=5)
        lim = max([abs(y) for s in lg.samples for y in s["r"][4 * half:4 * half + 4]] + [1.5])
        ax.set_ylim(-min(lim * 1.1, 34), min(lim * 1.1, 34))
    axes[0].set_title("parity residuals against their thresholds (±1; the largest |r| of each sample interval)",
                      fontsize=9)
    axes[1].set_xlabel("log time [s]")
    return _png(fig)


def _params_png(report: Report, lg: LogState) -> str | None:
    if not lg.samples:
        return None
    th = report.hdr.get("thr_pos", {})
    t = [s["t"] for s in lg.samples]
    fig, axes = plt.subplots(2, 4, figsize=(11, 4.8), sharex=True)
    for i, ax in enumerate(axes.flat):
        half, k = divmod(i, 4)
        ys = [100.0 * s["p"][i] if (s["pv"][half] >> k) & 1 else float("nan") for s in lg.samples]
        ax.plot(t, ys, lw=0.9, color="#2c3e50")
        pos = th.get("dcm_pos" if half == 0 else "thr_pos", [None] * 4)[k]
        neg = th.get("dcm_neg" if half == 0 else "thr_neg", [None] * 4)[k]
        if pos is not None:
            ax.axhline(100.0 * pos, color="#c0392b", ls="--", lw=0.8)
            ax.axhline(-100.0 * neg, color="#c0392b", ls="--", lw=0.8)
        last = next((s["e"][i] for s in reversed(lg.samples)), None)
        ax.set_title(f"{PAR_NAMES[i]} (last {last:.4g} {EST_UNITS[i]})" if last is not None else PAR_NAMES[i],
                     fontsize=8)
        _shade_untested(ax, lg, ("dcm_models",) if half == 0 else ("thr_models",))
        ax.tick_params(labelsize=7)
        if k == 0:
            ax.set_ylabel("deviation from nominal [%]", fontsize=8)
    fig.suptitle("parameter estimates: relative deviation from nominal, thresholds dashed "
                 "(blank: not converged or not fed)", fontsize=9)
    return _png(fig)


def _busload_png(lg: LogState, bitrate: int) -> str | None:
    if len(lg.bus) < 2:
        return None
    fig, ax = plt.subplots(figsize=(11, 2.0))
    ax.plot([b["t"] for b in lg.bus], [100.0 * b["bits"] / bitrate for b in lg.bus], lw=0.8, label="bus load")
    ax.set_ylabel("bus load [%]")
    ax.set_xlabel("log time [s]")
    for a, b in lg.gaps[:200]:
        ax.axvspan(a, b, color="#e67e22", alpha=0.4, lw=0)
    ax.set_title(f"bus load per second at {bitrate // 1000} kbit/s (orange: gaps in the log)", fontsize=9)
    return _png(fig)


def _esc(x: Any) -> str:
    return html.escape(str(x))


def _table(head: list[str], rows: list[list[Any]], cls: list[str] | None = None) -> str:
    out = ["<table><tr>" + "".join(f"<th>{_esc(h)}</th>" for h in head) + "</tr>"]
    for i, r in enumerate(rows):
        c = f' class="{cls[i]}"' if cls and cls[i] else ""
        out.append(f"<tr{c}>" + "".join(f"<td>{x}</td>" for x in r) + "</tr>")
    out.append("</table>")
    return "\n".join(out)


def _evidence_html(f: dict[str, Any]) -> str:
    ev = f.get("evidence") or {}
    if not ev:
        return "<p class=small>no symptom snapshot</p>"
    parts = [f"<h3>{_esc(f['code'])} at {f['first_testfailed_s']:.3f} s: {_esc(f['description'])}</h3>"]
    conf = f"{f['confidence_pct']} %" if f["confidence_pct"] is not None else "-"
    parts.append(f"<p>confidence {conf} ({_esc(f['confidence_basis'])})</p>")
    rules = ev.get("rules", [])
    if rules:
        parts.append(_table(["fault", "rule", "pattern / required flags", "note"],
                            [[_esc(r["fault"]), _esc(r["kind"]),
                              f"<code>{_esc(r.get('pattern') or r.get('required') or '')}</code>"
                              + (f" not <code>{_esc(r['forbidden'])}</code>" if r.get("forbidden") else ""),
                              _esc(r.get("note", ""))] for r in rules]))
    for comp in ev.get("components", []):
        names = DCM_CHANNELS if comp["component"] == "dc_motor" else THR_CHANNELS
        names = [n for n in names if n != "-"]
        res = comp["result"]
        parts.append(f"<p class=small>{_esc(comp['component'])}: isolated fault {res['isolated']} "
                     f"({res['conf']} %), best candidate {res['best']} ({res['best_pct']} %), runner-up "
                     f"{res['second']} ({res['second_pct']} %)</p>")
        parts.append(_table(["channel"] + list(names),
                            [["symptom"] + [_esc(comp["symptoms"][n]) for n in names],
                             ["value / threshold"] + [f"{comp['normalised'][n]:+.2f}" for n in names]]))
    if ev.get("flags"):
        parts.append(f"<p>signal-based symptoms present: {_esc(', '.join(ev['flags']))}</p>")
    return "\n".join(parts)


def write_html(report: Report, doc: dict[str, Any], path: Path) -> None:
    bitrate = int(doc["data_quality"][0]["bus_load_pct"]["bitrate"]) if doc["data_quality"] else 1_000_000
    h: list[str] = ["<!DOCTYPE html><html lang=en><head><meta charset=utf-8>",
                    "<title>canfdi-replay report</title>", f"<style>{CSS}</style></head><body>",
                    "<h1>canfdi-replay: diagnosis of a recorded CAN log</h1>"]
    codes = sorted({f["code"] for f in doc["dtcs"]})
    h.append(f"<p><b>{'Trouble codes found: ' + ', '.join(codes) if codes else 'No trouble code found.'}</b> "
             f"Firmware {_esc(doc['firmware']['sw_version'])} ({_esc(doc['firmware']['id'])}), calibration "
             f"{_esc(doc['firmware']['calibration_id'])} ({_esc(doc['firmware']['calibration'])}); "
             f"DBC {_esc(doc['dbc'].get('path', ''))} sha256 {_esc(doc['dbc'].get('sha256', '')[:16])}…</p>")
    h.append("<h2>Logs</h2>")
    rows = []
    for lj in doc["logs"]:
        re = lj["recorded_ecu"]
        agree = (f"{re['identical']} of {re['frames']} ECU frames identical" if lj["start"] == "power-up"
                 and re["frames"] else ("not compared (starts after the ECU's power-up)" if re["frames"]
                                        else "no ECU frames"))
        rows.append([_esc(lj["path"]), _esc(lj["format"]), f"{lj['frames']}", f"{lj['first_s']:.3f}–{lj['last_s']:.3f}",
                     _esc(lj["clock"]), _esc(lj["channel"]), _esc(lj["start"]),
                     f"{lj['settled_from_s']:.3f}" if lj["settled_from_s"] is not None else "-",
                     _esc(agree), f"<code>{_esc(lj['sha256'][:16])}…</code>"])
    h.append(_table(["file", "format", "frames", "time [s]", "time base", "channel", "start",
                     "judged from [s]", "recorded ECU", "sha256"], rows))
    if doc.get("map"):
        m = doc["map"]
        h.append(f"<p>Mapped with {_esc(m['path'])} (other DBC {_esc(m['dbc'])}); checks not applied: "
                 f"{_esc('; '.join(f'{k}: {v}' for k, v in m.get('codes_not_applied', {}).items()))}</p>")
    h.append("<h2>Trouble codes</h2>")
    if doc["dtcs"]:
        rows = []
        for f in doc["dtcs"]:
            deg = f["degradation"] or {}
            ff = f["freeze_frame"] or {}
            rec = f["recorded_ecu_first_failed_s"]
            rows.append([f"<b>{_esc(f['code'])}</b>", _esc(f["description"]), f"{f['first_failed_s']:.3f}",
                         _esc(status_text(f["status"])) + f" (0x{f['status']:02X})" if f["status"] is not None else "-",
                         f"dcm {_esc(deg.get('dcm', '?'))}, thr {_esc(deg.get('thr', '?'))}",
                         f"{f['confidence_pct']} %" if f["confidence_pct"] is not None else "-",
                         f"{rec:.3f}" if rec is not None else "-",
                         _esc(", ".join(f"{k} {v:.4g}" if isinstance(v, float) else f"{k} {v}"
                                        for k, v in ff.items()))])
        h.append(_table(["code", "description", "first failed [s]", "status at the end", "degradation",
                         "confidence", "recorded ECU [s]", "freeze frame"], rows, ["found"] * len(rows)))
    else:
        h.append("<p class=ok>The replay found no trouble code in the judged spans.</p>")
    for r in doc["recorded_ecu_only"]:
        h.append(f"<p class=warn>The recorded ECU reported {_esc(r['code'])} at {r['first_failed_s']:.3f} s; "
                 f"the replay did not find it: {_esc(r['why'])}</p>")
    for lg in report.logs:
        h.append(f"<h2>Timeline{'' if len(report.logs) == 1 else ' of ' + _esc(lg.path)}</h2>")
        h.append(f'<img alt="trouble-code timeline" src="{_timeline_png(report, lg)}">')
        img = _residuals_png(report, lg)
        if img:
            h.append("<h2>Residuals against their thresholds</h2>")
            h.append(f'<img alt="residuals" src="{img}">')
        img = _params_png(report, lg)
        if img:
            h.append("<h2>Parameter estimates</h2>")
            h.append(f'<img alt="parameter estimates" src="{img}">')
    if doc["dtcs"]:
        h.append("<h2>Evidence: which residuals, estimates and rules named each code</h2>")
        for f in doc["dtcs"]:
            h.append(_evidence_html(f))
    h.append("<h2>Not judged</h2>")
    if doc["not_judged"]:
        rows = [[str(n["log"]), _esc(n["monitor"]), _esc(MONITORS.get(n["monitor"], n["what"])),
                 _esc(", ".join(n["codes"])), f"{n['seconds']:.3f} s ({100 * n['fraction']:.1f} %)",
                 "<br>".join(f"{s['from_s']:.3f}–{s['to_s']:.3f}: {_esc(s['why'])}" for s in n["spans"][:8])
                 + (f"<br>… {n['span_count'] - 8} more" if n["span_count"] > 8 else "")]
                for n in doc["not_judged"]]
        h.append(_table(["log", "monitor", "what", "codes", "time", "spans"], rows))
    else:
        h.append("<p class=ok>Every monitor was judged over every log.</p>")
    h.append("<h2>Data quality</h2>")
    for dq, lg in zip(doc["data_quality"], report.logs):
        def at(line: int, fmt: str = lg.fmt) -> str:
            return where(fmt, line)
        items = [["bad or unparsable lines", f"{dq['bad_line_count']}" + "".join(
            f"<br>{at(b['line'])}: {_esc(b['why'])} <code>{_esc(b['text'])}</code>" for b in dq["bad_lines"][:20])],
                 ["truncated / read errors", _esc("; ".join(f"{at(r['line'])}: {r['why']}" for r in dq["read_errors"])
                                                   or ("truncated" if dq["truncated"] else "none"))],
                 ["gaps in the log", f"{dq['gap_count']}" + "".join(
                     f"<br>{g['from_s']:.3f}–{g['to_s']:.3f} s" for g in dq["gaps"][:20])],
                 ["time stamps going back", f"{dq['time_stamps_back']}" + "".join(
                     f"<br>{at(b['line'])} by {b['by_s'] * 1e3:.3f} ms" for b in dq["time_stamps_back_first"][:5])
                  + "".join(f"<br>{at(b['line'])}: back {b['back_s']:.3f} s, re-based" for b in dq["rebased"])],
                 ["time stamps out of sequence", f"{dq['time_stamp_outliers']}" + "".join(
                     f"<br>{at(o['line'])}: stamped {o['stamp_s']:.6f} s, taken at {o['at_s']:.3f} s"
                     for o in dq["time_stamp_outliers_first"][:5])],
                 ["rejected input frames", _esc("; ".join(
                     f"{n}: " + ", ".join(f"{k} {v}" for k, v in d.items() if v)
                     for n, d in dq["rejected_frames"].items() if any(d.values())) or "none")],
                 ["missing input frames", _esc("; ".join(
                     f"{m['frame']} {'never received' if m['never_received'] else 'missing'} "
                     f"{m['from_s']:.3f}–{m['to_s']:.3f} s" for m in dq["missing_frames"][:20]) or "none")],
                 ["error frames", f"{dq['error_frames']}" + "".join(
                     f"<br>{at(e['line'])} at {e['at_s']:.3f} s" for e in dq["error_frames_first"][:5])],
                 ["CAN FD / remote / 29-bit frames", f"{dq['fd_frames']} / {dq['remote_frames']} / "
                                                     f"{dq['extended_frames']} (never fed to the supervisor)"],
                 ["other channels", _esc(", ".join(f"{k}: {v['frames']} frames from {at(v['first_line'])}"
                                                   for k, v in dq["other_channels"].items()) or "none")],
                 ["identifiers not in the DBC", _esc(", ".join(f"0x{k} ({v})" if not k.startswith("x") else
                                                               f"0x{k[1:]} 29-bit ({v})"
                                                               for k, v in list(dq["unknown_ids"].items())[:30])
                                                     or "none")],
                 ["recorded commands with a bad CRC", f"{dq['recorded_commands_bad_crc']}"],
                 ["recorded EcuDtc frames failing E2E (forged or corrupted, not taken as the ECU's)",
                  f"{dq.get('recorded_ecu_dtc_frames_failing_e2e', 0)}"],
                 ["bus load", f"mean {dq['bus_load_pct']['mean']:.1f} %, max {dq['bus_load_pct']['max']:.1f} % "
                              f"({_esc(dq['bus_load_pct']['note'])})"]]
        if len(report.logs) > 1:
            h.append(f"<h3>{_esc(lg.path)}</h3>")
        h.append(_table(["", ""], items))
        img = _busload_png(lg, bitrate)
        if img:
            h.append(f'<img alt="bus load" src="{img}">')
    h.append(f"<p class=small>canfdi-replay, report schema {_esc(doc['schema'])}.</p>")
    h.append(SCRIPT + "</body></html>\n")
    path.write_text("\n".join(h), encoding="utf-8")
