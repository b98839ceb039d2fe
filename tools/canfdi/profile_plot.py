"""canfdi-profile-plot: draw a profile file (``profile <file.csv>``, host_sim/SCENARIO.md) as one PNG.

One panel per quantity the file has, on a shared time axis: motor speed
(rad/s), load torque (N m), throttle angle (deg, with the limp-home angle
and the end stops), and the two bridge supplies (V). When the drive-profile
generator's summary lies beside the file (same name, .json; tools/drive),
its events are marked: hard tip-ins (green) and tip-outs (red) on the angle,
parking manoeuvres (shaded) on the speed, engine starts (cranking) on the
supplies.

    canfdi-profile-plot build/drive/wltc3_10min_s1.csv -o build/drive/wltc3_10min_s1.png
"""
from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from .profile_csv import ProfileError, read  # noqa: E402

LIMP_HOME_DEG = 6.5   # host_sim's default thr_limp_home_deg (docs/design.md)
PANELS = (("speed_rad_s", "motor speed [rad/s]"), ("load_Nm", "load torque [N m]"),
          ("angle_deg", "throttle angle [deg]"), ("supplies", "supply [V]"))


def build_figure(path: Path, title: str, t_from: float | None, t_to: float | None):
    prof = read(path)
    summary_path = path.with_suffix(".json")
    events = json.loads(summary_path.read_text()).get("events", {}) if summary_path.is_file() else {}
    lo = t_from if t_from is not None else 0.0
    hi = t_to if t_to is not None else prof.t_last_us * 1e-6
    idx = [i for i, t in enumerate(prof.t_us) if lo <= t * 1e-6 <= hi]
    if not idx:
        raise ProfileError(f"{path}: no row between {lo:g} and {hi:g} s")
    t = [prof.t_us[i] * 1e-6 for i in idx]
    panels = [(k, label) for k, label in PANELS
              if k in prof.columns or (k == "supplies" and any(s in prof.columns for s in ("dcm_supply_V", "thr_supply_V")))]
    fig, axes = plt.subplots(len(panels), 1, figsize=(13, 2.2 * len(panels) + 0.8), sharex=True, squeeze=False)
    within = lambda xs: [x for x in xs if lo <= x <= hi]  # noqa: E731
    for ax, (key, label) in zip(axes[:, 0], panels):
        if key == "supplies":
            for name, color in (("dcm_supply_V", "tab:blue"), ("thr_supply_V", "tab:orange")):
                if name in prof.columns:
                    target = ax if name == "dcm_supply_V" or "dcm_supply_V" not in prof.columns else ax.twinx()
                    target.plot(t, [prof.columns[name][i] for i in idx], color=color, lw=0.8, label=name)
                    target.set_ylabel(name.replace("_V", " [V]"), color=color)
            for c in within(events.get("crank_s", [])):
                ax.axvline(c, color="grey", ls=":", lw=0.8)
        else:
            ax.plot(t, [prof.columns[key][i] for i in idx], lw=0.8, color="k")
            ax.set_ylabel(label)
        if key == "speed_rad_s":
            ax.axhline(0.0, color="grey", lw=0.5)
            for a, b in events.get("manoeuvre_s", []):
                if b >= lo and a <= hi:
                    ax.axvspan(max(a, lo), min(b, hi), color="tab:purple", alpha=0.15)
        if key == "load_Nm":
            ax.axhline(0.0, color="grey", lw=0.5)
        if key == "angle_deg":
            ax.axhline(LIMP_HOME_DEG, color="tab:blue", ls="--", lw=0.7, label="limp-home")
            ax.set_ylim(-3, 93)
            for x in within(events.get("tip_in_s", [])):
                ax.axvline(x, color="tab:green", lw=0.6, alpha=0.7)
            for x in within(events.get("tip_out_s", [])):
                ax.axvline(x, color="tab:red", lw=0.6, alpha=0.7)
        ax.grid(True, alpha=0.3)
    axes[-1, 0].set_xlabel("time [s]")
    fig.suptitle(title)
    fig.tight_layout()
    return fig, len(idx)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="canfdi-profile-plot", description=__doc__.split("\n\n")[0])
    ap.add_argument("profile", type=Path, metavar="CSV", help="profile file (host_sim/SCENARIO.md)")
    ap.add_argument("-o", "--output", type=Path, metavar="PNG", help="PNG to write (default: CSV with .png)")
    ap.add_argument("--title", help="figure title (default: the file's name)")
    ap.add_argument("--from", dest="t_from", type=float, metavar="S", help="start, seconds")
    ap.add_argument("--to", dest="t_to", type=float, metavar="S", help="end, seconds")
    a = ap.parse_args(argv)
    out = a.output if a.output is not None else a.profile.with_suffix(".png")
    try:
        fig, n = build_figure(a.profile, a.title or f"drive profile {a.profile.name}", a.t_from, a.t_to)
    except (ProfileError, OSError, ValueError) as e:
        print(f"canfdi-profile-plot: {e}", file=sys.stderr)
        return 2
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=90)
    print(f"canfdi-profile-plot: {n} rows of {a.profile}; wrote {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
