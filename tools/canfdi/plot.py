"""Plot a canfdi SIL trace (``canfdi-sil -o trace.csv``) as one PNG.

Panels, sharing the time axis: motor speed setpoint and response; throttle
angle setpoint and response; the ECU's normalised parity residuals
(EcuResidualDcm/Thr, 1.0 = threshold) against the +-1 band; parameter
estimates (EcuParamDcm/Thr) with the true R_A; degradation states. Fault
injections (``fault`` lines of the scenario) are drawn as vertical lines,
trouble codes from the SIL timeline (``--timeline``) as labelled markers.

Example::

    canfdi-sil -s tests/sil/scenarios/demo.scn -o trace.csv -D 5 | tee timeline.txt
    python -m canfdi.plot trace.csv -s tests/sil/scenarios/demo.scn \
        --timeline timeline.txt -o demo.png
"""

from __future__ import annotations

import argparse
import csv
import re
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

DEG_NAMES = ["normal", "degraded", "fail_safe", "fail_silent"]
_EVENT = re.compile(r"^\s+(\d+\.\d+)\s+([PCBU][0-9A-F]{4})\s+(testFailed|confirmed|stored|passed)\b")


def read_trace(path: Path) -> dict[str, list[float]]:
    cols: dict[str, list[float]] = {}
    with path.open(newline="") as f:
        for row in csv.DictReader(f):
            for k, v in row.items():
                cols.setdefault(k, []).append(float(v))
    if not cols:
        raise SystemExit(f"plot: {path} holds no rows")
    return cols


def read_faults(path: Path | None) -> list[tuple[float, str]]:
    faults: list[tuple[float, str]] = []
    if path is None:
        return faults
    for line in path.read_text().splitlines():
        tok = line.split("#", 1)[0].split()
        if len(tok) >= 3 and tok[0] == "fault":
            faults.append((float(tok[1]), tok[2]))
    return faults


def read_events(path: Path | None) -> list[tuple[float, str, str]]:
    events: list[tuple[float, str, str]] = []
    if path is None:
        return events
    for line in path.read_text().splitlines():
        m = _EVENT.match(line)
        if m and m.group(3) in ("testFailed", "confirmed"):
            events.append((float(m.group(1)), m.group(2), m.group(3)))
    return events


def plot(trace: dict[str, list[float]], faults: list[tuple[float, str]],
         events: list[tuple[float, str, str]], out: Path, title: str) -> None:
    t = trace["t_s"]
    fig, ax = plt.subplots(5, 1, figsize=(13, 15), sharex=True,
                           gridspec_kw={"height_ratios": [2, 2, 2.4, 2, 1.2]})
    ax[0].plot(t, trace["sp_speed"], "k--", lw=1, label="setpoint")
    ax[0].plot(t, trace["speed"], "C0", lw=1, label="speed (plant)")
    ax[0].set_ylabel("motor speed [rad/s]")
    ax[1].plot(t, trace["sp_angle_deg"], "k--", lw=1, label="setpoint")
    ax[1].plot(t, trace["angle_deg"], "C1", lw=1, label="angle (plant)")
    ax[1].set_ylabel("throttle angle [deg]")
    res = [("rn_dcm1", "dcm r1"), ("rn_dcm2", "dcm r2"), ("rn_dcm3", "dcm r3"), ("rn_dcm4", "dcm r4"),
           ("rn_thr_corr", "thr corr"), ("rn_thr_tps1", "thr pos1"), ("rn_thr_tps2", "thr pos2"),
           ("rn_thr_arm", "thr arm")]
    for i, (col, lab) in enumerate(res):
        ax[2].plot(t, [max(-4.0, min(4.0, v)) for v in trace[col]], lw=0.8, color=f"C{i}", label=lab)
    for y in (-1.0, 1.0):
        ax[2].axhline(y, color="r", lw=1.2, ls=":")
    ax[2].set_ylim(-4.2, 4.2)
    ax[2].set_ylabel("residual / threshold\n(clipped to +-4)")
    ax[3].plot(t, trace["ra_true"], "k--", lw=1, label="R_A true (plant)")
    ax[3].plot(t, trace["ra_est"], "C0", lw=1, label="R_A estimate (ECU)")
    ax[3].plot(t, trace["thr_r_est"], "C1", lw=1, label="throttle R estimate (ECU)")
    ax3b = ax[3].twinx()
    ax3b.plot(t, trace["psi_est"], "C2", lw=1, label="Psi estimate (ECU)")
    ax3b.set_ylabel("Psi [V s]", color="C2")
    ax[3].set_ylabel("resistance [Ohm]")
    ax[3].set_ylim(1.0, 2.4)
    ax3b.set_ylim(0.2, 0.4)
    ax[4].step(t, trace["deg_dcm"], where="post", color="C0", label="DC motor")
    ax[4].step(t, [v + 0.05 for v in trace["deg_thr"]], where="post", color="C1", label="throttle")
    ax[4].set_yticks(range(4))
    ax[4].set_yticklabels(DEG_NAMES)
    ax[4].set_ylim(-0.3, 3.3)
    ax[4].set_ylabel("degradation")
    ax[4].set_xlabel("time [s]")
    for a in ax:
        for tf, name in faults:
            a.axvline(tf, color="m", lw=1, alpha=0.6)
        a.grid(True, alpha=0.3)
        a.legend(loc="upper left", fontsize=8, ncol=4)
    for tf, name in faults:
        ax[0].annotate(name, (tf, 1.0), xycoords=("data", "axes fraction"), rotation=90, va="top",
                       ha="right", fontsize=8, color="m")
    seen: set[str] = set()
    for te, code, _kind in events:
        if code in seen:
            continue
        seen.add(code)
        ax[4].axvline(te, color="r", lw=0.8, alpha=0.5)
        ax[4].annotate(code, (te, 3.1), rotation=90, va="top", ha="left", fontsize=8, color="r")
    fig.suptitle(title)
    fig.tight_layout()
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=90)


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("trace", type=Path, help="CSV written by canfdi-sil -o")
    p.add_argument("-s", "--scenario", type=Path, help="scenario file (fault injection times)")
    p.add_argument("--timeline", type=Path, help="stdout of canfdi-sil (trouble-code events)")
    p.add_argument("-o", "--output", type=Path, default=Path("canfdi-sil.png"), help="PNG to write")
    p.add_argument("--title", default="canfdi SIL run", help="figure title")
    a = p.parse_args(argv)
    plot(read_trace(a.trace), read_faults(a.scenario), read_events(a.timeline), a.output, a.title)
    print(f"plot: wrote {a.output}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
