"""canfdi-plot: plot a recorded canfdi bus log as one PNG, from the frames alone.

Reads any python-can log of the canfdi bus (candump -L .log as recorded by
canfdi-scenario, canfdi-sil -l or candump; .asc, .blf, .trc, ... through
python-can), decodes it with cantools and dbc/canfdi.dbc and draws, on
SIMULATED time (canfdi.timeline: SimStep in lockstep, SimPlantStatus in
realtime, else the timestamps):

  DC motor speed     SetpointDcm and DcmSensor omega
  throttle angle     SetpointThr, TPS1 and TPS2 as angles (TPS1 = 0.5 V +
                     4 V theta/90 deg, TPS2 = 4.5 V - 4 V theta/90 deg) and
                     the plant's true angle (SimPlantStatus, when present)
  actuator commands  DcmActuator U_A and ThrActuator U
  residuals          EcuResidualDcm and EcuResidualThr, normalised: 1 = threshold
  parameters         EcuParamDcm R_A and Psi, EcuParamThr R; with
                     SimPlantStatus, the plant's winding resistance derived
                     from its winding temperature (host_sim's law, below)
  degradation        EcuStatus per subsystem
  power stage        EcuStatus active bridge and throttle limp-home

Fault injections (SimFaultInject, else the fault the plant reports in
SimPlantStatus) are drawn as magenta lines, the first report of each
trouble code (EcuDtc testFailed or confirmed) as red lines, listed with its
description under the plots.

R_A (plant) = 1.35 Ohm x (1 + 0.0039/K x (T_winding - 20 degC)): host_sim's
default winding law (host_sim/canfdi_sim_dcm.c, 20 degC ambient). It does
NOT contain injected resistance faults (dcm_ra_up models a resistance
outside the winding), and PstDcmWindingTemp has 1 degC resolution (0.4 %).
"""
from __future__ import annotations

import argparse
import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import can
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from . import scenario_file
from .catalogue import dtc_by_code
from .logio import ReadStats, read_log
from .timeline import (DEG_NAMES, ID_CLEAR, ID_DCM_ACT, ID_INJECT, ID_PLANT, ID_RES_DCM, ID_RES_THR,
                       ID_SP_DCM, ID_SP_THR, ID_STATUS, ID_STEP, ID_THR_ACT, Timeline, fault_name, load_db)

ID_DCM_SENS, ID_THR_SENS = 0x010, 0x011
ID_PRM_DCM, ID_PRM_THR = 0x320, 0x321
PLOTTED = frozenset({ID_DCM_SENS, ID_THR_SENS, ID_DCM_ACT, ID_THR_ACT, ID_SP_DCM, ID_SP_THR, ID_RES_DCM,
                     ID_RES_THR, ID_STATUS, ID_PRM_DCM, ID_PRM_THR, ID_PLANT, ID_INJECT, ID_CLEAR})
# host_sim's DC motor winding law (canfdi_sim_dcm_default_params)
RA_COLD_OHM, ALPHA_PER_K, AMBIENT_C = 1.35, 0.0039, 20.0
RES_CLIP = 4.0
PANEL_TITLES = (
    "DC motor speed: setpoint and response",
    "Throttle angle: setpoint and response",
    "Actuator commands (DcmActuator, ThrActuator)",
    "DC motor residuals / threshold (EcuResidualDcm)",
    "Throttle residuals / threshold (EcuResidualThr)",
    "Parameter estimates (EcuParamDcm, EcuParamThr)",
    "Degradation states (EcuStatus)",
    "Power stage and limp-home (EcuStatus)",
)
SCAN_AFTER_STATUS = 2000   # frames to look for a SimStep after the first SimPlantStatus

EPILOG = """\
examples:
  canfdi-plot build/demo/canfdi-hil-demo.log                 # -> build/demo/canfdi-hil-demo.png
  canfdi-plot run.log -o run.png --title "bench 3, run 12"
  canfdi-plot run.asc --from 7.5 --to 13                      # simulated seconds
  canfdi-sil -q -s my.scn -l my.log && canfdi-plot my.log -s my.scn

A line of a .log that does not parse is skipped and counted (file:line of
the first one on stderr); so is a frame that does not decode, and an ECU
frame that fails its E2E check (forged or corrupted: canfdi-watch).

exit status:
  0  the PNG was written (warnings about skipped lines go to stderr)
  1  nothing to plot: no canfdi frame in the log or in --from/--to, or the
     PNG could not be written
  2  bad usage, or the log cannot be read or holds no readable frame
"""


@dataclass
class Series:
    """Simulated times [s] and decoded signals of one frame ID."""
    t: list[float] = field(default_factory=list)
    v: dict[str, list[float]] = field(default_factory=dict)

    def add(self, t: float, sig: dict[str, Any]) -> None:
        self.t.append(t)
        for k, x in sig.items():
            self.v.setdefault(k, []).append(float(x))

    def __len__(self) -> int:
        return len(self.t)


@dataclass
class Marker:
    t_s: float
    label: str
    detail: str = ""


@dataclass
class PlotData:
    """What the plot needs, decoded from a log."""
    source: str
    series: dict[int, Series] = field(default_factory=dict)
    injections: list[Marker] = field(default_factory=list)   # SimFaultInject / SimFaultClear
    scenario_faults: list[Marker] = field(default_factory=list)  # fault lines of --scenario
    plant_faults: list[Marker] = field(default_factory=list)  # fault changes in SimPlantStatus
    dtcs: list[Marker] = field(default_factory=list)          # first report per code
    t_from: float | None = None
    t_to: float | None = None
    span: tuple[float, float] | None = None                    # simulated time of the frames kept
    read: ReadStats = field(default_factory=ReadStats)
    timeline: Timeline | None = None

    def s(self, fid: int) -> Series:
        return self.series.get(fid, Series())

    @property
    def frames_plotted(self) -> int:
        return sum(len(x) for x in self.series.values())


class LogError(Exception):
    """The log cannot be used at all; str() is one line for the user."""


def _origin(path: Path) -> can.Message | None:
    """The first SimPlantStatus of a realtime log (None for lockstep or without one).

    As canfdi-scenario does when it evaluates a realtime recording: frames
    before the sim's first status frame get negative simulated times.
    """
    status: can.Message | None = None
    after = 0
    for msg in read_log(path, ReadStats()):
        if msg.is_error_frame or msg.is_remote_frame or msg.is_extended_id:
            continue
        if msg.arbitration_id == ID_STEP:
            return None
        if status is not None:
            after += 1
            if after > SCAN_AFTER_STATUS:
                break
        elif msg.arbitration_id == ID_PLANT and len(msg.data) == 8:
            status = msg
    return status


def read_plot_data(path: Path, t_from: float | None = None, t_to: float | None = None) -> PlotData:
    """Decode every plotted frame of the log within [t_from, t_to] simulated seconds.

    LogError when the file cannot be opened or holds no readable frame.
    """
    if not path.is_file():
        raise LogError(f"cannot read {path}: no such file")
    try:
        with path.open("rb") as f:
            f.read(1)
    except OSError as e:
        raise LogError(f"cannot read {path}: {e.strerror or e}") from e
    db = load_db()
    msgs = {m.frame_id: m for m in db.messages if m.frame_id in PLOTTED}
    data = PlotData(str(path), t_from=t_from, t_to=t_to)
    tl = data.timeline = Timeline(db)
    status = _origin(path)
    if status is not None:
        tl.set_origin(status)
    lo = -float("inf") if t_from is None else t_from
    hi = float("inf") if t_to is None else t_to
    plant_fault = 0
    first = last = None
    for msg in read_log(path, data.read):
        tl.feed(msg)
        fid = msg.arbitration_id
        m = msgs.get(fid)
        if m is None or msg.is_error_frame or msg.is_remote_frame or msg.is_extended_id:
            continue
        if tl.last_rejected:
            continue     # an ECU frame that failed its E2E check: forged or corrupted, not plotted
        t = tl.now_us * 1e-6
        if t < lo:
            continue
        if t > hi:
            if t > hi + 1.0:
                break    # simulated time does not go back by a second: the rest is out of range
            continue
        if len(msg.data) != m.length:
            continue     # counted by the timeline
        try:
            sig = m.decode(bytes(msg.data), decode_choices=False)
        except Exception:  # noqa: BLE001 — counted by the timeline, never fatal
            continue
        first = t if first is None else first
        last = t
        if fid == ID_INJECT:
            delay = float(sig["InjStartDelay"])
            data.injections.append(Marker(t + delay, fault_name(int(sig["InjFaultId"])),
                                          f"magnitude {float(sig['InjMagnitude']):g}"))
        elif fid == ID_CLEAR:
            c = int(sig["ClrFaultId"])
            data.injections.append(Marker(t, "clear " + ("all" if c == 0 else fault_name(c))))
        elif fid == ID_PLANT:
            fault = int(sig["PstActiveFaultId"]) if int(sig["PstFaultActive"]) else 0
            if fault != plant_fault:
                data.plant_faults.append(Marker(t, fault_name(fault) if fault else "no fault acting"))
                plant_fault = fault
        data.series.setdefault(fid, Series()).add(t, sig)
    if data.read.frames == 0:
        first_err = f" (first: {data.read.first_error})" if data.read.first_error else ""
        raise LogError(f"{path} holds no readable frame{first_err}")
    descriptions = {d.code: d.description for d in dtc_by_code().values()}
    for rec in tl.dtcs.values():
        t_us = rec.first_reported_us
        if t_us >= 0 and lo <= t_us * 1e-6 <= hi:
            word = "testFailed" if rec.first_failed_us >= 0 else "confirmed"
            data.dtcs.append(Marker(t_us * 1e-6, rec.code, f"{word}  {descriptions.get(rec.code, '')}"))
    data.dtcs.sort(key=lambda mk: mk.t_s)
    if first is not None and last is not None:
        data.span = (first, last)
    return data


def _tps1_deg(v: float) -> float:
    return (v - 0.5) * 90.0 / 4.0


def _tps2_deg(v: float) -> float:
    return (4.5 - v) * 90.0 / 4.0


def _winding_ohm(temp_c: float) -> float:
    return RA_COLD_OHM / (1.0 + ALPHA_PER_K * (AMBIENT_C - 20.0)) * (1.0 + ALPHA_PER_K * (temp_c - 20.0))


def _clip(vals: list[float], lim: float) -> list[float]:
    return [max(-lim, min(lim, x)) for x in vals]


def _limits(vals: list[float], margin: float, lo: float, hi: float) -> tuple[float, float] | None:
    if not vals:
        return None
    return max(lo, min(vals) - margin), min(hi, max(vals) + margin)


def _note(ax: Axes, text: str) -> None:
    ax.text(0.5, 0.5, text, transform=ax.transAxes, ha="center", va="center", color="0.4", fontsize=10)


def build_figure(data: PlotData, title: str) -> Figure:
    """The figure of PANEL_TITLES (not saved; see save())."""
    fig = Figure(figsize=(13, 21))
    ax = fig.subplots(len(PANEL_TITLES), 1, sharex=True,
                      gridspec_kw={"height_ratios": [2, 2, 1.6, 1.9, 1.9, 1.8, 1.2, 0.9]})
    for a, t in zip(ax, PANEL_TITLES):
        a.set_title(t, fontsize=10, loc="left")
    sp_d, sp_t, sens_d, sens_t = data.s(ID_SP_DCM), data.s(ID_SP_THR), data.s(ID_DCM_SENS), data.s(ID_THR_SENS)
    act_d, act_t, plant = data.s(ID_DCM_ACT), data.s(ID_THR_ACT), data.s(ID_PLANT)

    # 0 speed
    if sp_d:
        ax[0].step(sp_d.t, sp_d.v["SpDcmSpeed"], "k--", lw=1, where="post", label="setpoint (SetpointDcm)")
    if sens_d:
        ax[0].plot(sens_d.t, sens_d.v["DcmOmega"], "C0", lw=0.8, label="measured (DcmSensor omega)")
    ax[0].set_ylabel("speed [rad/s]")

    # 1 angle
    ang: list[float] = []
    if sp_t:
        ax[1].step(sp_t.t, sp_t.v["SpThrAngle"], "k--", lw=1, where="post", label="setpoint (SetpointThr)")
        ang += sp_t.v["SpThrAngle"]
    if sens_t:
        a1 = [_tps1_deg(v) for v in sens_t.v["ThrTps1"]]
        a2 = [_tps2_deg(v) for v in sens_t.v["ThrTps2"]]
        ax[1].plot(sens_t.t, a1, "C1", lw=0.8, label="from TPS1")
        ax[1].plot(sens_t.t, a2, "C4", lw=0.8, alpha=0.8, label="from TPS2")
        if not ang:
            ang += a1
    if plant:
        ax[1].plot(plant.t, plant.v["PstThrAngle"], "C2:", lw=1.5, label="plant (SimPlantStatus)")
        ang += plant.v["PstThrAngle"]
    lim = _limits(ang, 8.0, -5.0, 95.0)
    if lim:
        ax[1].set_ylim(*lim)
    ax[1].set_ylabel("angle [deg]")

    # 2 actuators
    handles = []
    if act_d:
        handles += ax[2].plot(act_d.t, act_d.v["DcmUaCmd"], "C0", lw=0.6, label="DC motor U_A (left)")
    ax[2].set_ylabel("U_A [V]", color="C0")
    ax2b = ax[2].twinx()
    if act_t:
        handles += ax2b.plot(act_t.t, act_t.v["ThrUCmd"], "C1", lw=0.5, alpha=0.6, label="throttle U (right)")
    ax2b.set_ylabel("throttle U [V]", color="C1")
    if handles:
        ax[2].legend(handles=handles, loc="upper left", fontsize=8, ncol=2)

    # 3, 4 residuals
    for a, fid, names in ((ax[3], ID_RES_DCM, ("ResDcmR1", "ResDcmR2", "ResDcmR3", "ResDcmR4")),
                          (ax[4], ID_RES_THR, ("ResThrCorr", "ResThrTps1", "ResThrTps2", "ResThrCurrent"))):
        res = data.s(fid)
        for i, name in enumerate(names):
            if name in res.v:
                a.plot(res.t, _clip(res.v[name], RES_CLIP), lw=0.8, color=f"C{i}", label=name)
        for y in (-1.0, 1.0):
            a.axhline(y, color="r", lw=1.2, ls=":")
        a.set_ylim(-RES_CLIP - 0.2, RES_CLIP + 0.2)
        a.set_ylabel(f"r / threshold\n(clipped to +-{RES_CLIP:g})")
        if not res:
            _note(a, "no residual frames in the log")

    # 5 parameters
    pd_, pt_ = data.s(ID_PRM_DCM), data.s(ID_PRM_THR)
    handles = []
    if plant and "PstDcmWindingTemp" in plant.v:
        handles += ax[5].plot(plant.t, [_winding_ohm(x) for x in plant.v["PstDcmWindingTemp"]], "k--", lw=1,
                              label="R_A plant winding (from temperature; no injected faults)")
    if pd_:
        handles += ax[5].plot(pd_.t, pd_.v["PrmDcmRa"], "C0", lw=1, label="R_A estimate")
    if pt_:
        handles += ax[5].plot(pt_.t, pt_.v["PrmThrR"], "C1", lw=1, label="throttle R estimate")
    ax[5].set_ylabel("resistance [Ohm]")
    ohms = [x for s in (pd_.v.get("PrmDcmRa", []), pt_.v.get("PrmThrR", [])) for x in s if x > 0.2]
    lim = _limits(ohms, 0.15, 0.0, 8.0)
    if lim:
        ax[5].set_ylim(*lim)
    ax5b = ax[5].twinx()
    if pd_:
        handles += ax5b.plot(pd_.t, pd_.v["PrmDcmPsi"], "C2", lw=1, label="Psi estimate (right)")
        psi = [x for x in pd_.v["PrmDcmPsi"] if x > 0.05]
        lim = _limits(psi, 0.04, 0.0, 0.8)
        if lim:
            ax5b.set_ylim(*lim)
    ax5b.set_ylabel("Psi [V s]", color="C2")
    if handles:
        ax[5].legend(handles=handles, loc="upper left", fontsize=8, ncol=2)

    # 6 degradation, 7 bridge and limp-home
    st = data.s(ID_STATUS)
    if st:
        ax[6].step(st.t, st.v["StsDegStateDcm"], where="post", color="C0", label="DC motor")
        ax[6].step(st.t, [v + 0.05 for v in st.v["StsDegStateThr"]], where="post", color="C1", label="throttle")
        ax[7].step(st.t, st.v["StsActiveBridge"], where="post", color="C0", label="active bridge")
        _spans(ax[7], st.t, st.v["StsThrLimpHome"], "C1", "throttle limp-home")
    else:
        _note(ax[6], "no EcuStatus frames in the log")
    ax[6].set_yticks(range(4))
    ax[6].set_yticklabels(DEG_NAMES)
    ax[6].set_ylim(-0.3, 3.4)
    ax[7].set_yticks(range(3))
    ax[7].set_yticklabels(["none", "A", "B"])
    ax[7].set_ylim(-0.3, 2.4)
    ax[7].set_ylabel("bridge")
    ax[7].set_xlabel("simulated time [s]")

    # events
    faults = data.scenario_faults or data.injections or data.plant_faults
    for a in ax:
        for mk in faults:
            a.axvline(mk.t_s, color="m", lw=1, alpha=0.6)
        a.grid(True, alpha=0.3)
        if a not in (ax[2], ax[5]) and a.get_legend_handles_labels()[0]:
            a.legend(loc="upper left", fontsize=8, ncol=4)
    for mk in faults:
        ax[0].annotate(mk.label, (mk.t_s, 1.0), xycoords=("data", "axes fraction"), rotation=90, va="top",
                       ha="right", fontsize=8, color="m",
                       bbox={"fc": "white", "ec": "none", "alpha": 0.7, "pad": 1})
    for mk in data.dtcs:
        for a in (ax[3], ax[4], ax[6], ax[7]):
            a.axvline(mk.t_s, color="r", lw=0.8, alpha=0.5, ls="--")
        ax[6].annotate(mk.label, (mk.t_s, 1.0), xycoords=("data", "axes fraction"), rotation=90, va="top",
                       ha="left", fontsize=8, color="r")
    lo = data.t_from if data.t_from is not None else (data.span[0] if data.span else None)
    hi = data.t_to if data.t_to is not None else (data.span[1] if data.span else None)
    if lo is not None and hi is not None and hi > lo:
        ax[-1].set_xlim(lo - 0.01 * (hi - lo), hi + 0.01 * (hi - lo))

    lines = [f"{mk.t_s:8.3f} s  {mk.label:<6} {mk.detail}" for mk in data.dtcs]
    src = ("fault lines of the scenario" if data.scenario_faults else "fault injections (SimFaultInject)"
           if data.injections else "faults acting in the plant (SimPlantStatus: the first acting one only)")
    foot = [f"magenta: {src};  red: first report of a trouble code (EcuDtc testFailed/confirmed)"] + lines
    fig.suptitle(title)
    bottom = (0.15 + 0.14 * len(foot)) / 21.0
    fig.text(0.01, 0.005, "\n".join(foot), family="monospace", fontsize=8, va="bottom")
    fig.tight_layout(rect=(0.0, bottom, 1.0, 0.985))
    return fig


def _spans(ax: Axes, t: list[float], flag: list[float], color: str, label: str) -> None:
    """Shade where flag is 1 (each span until the next sample that clears it)."""
    start: float | None = None
    labelled = False
    for ti, f in zip(t, flag):
        if f and start is None:
            start = ti
        elif not f and start is not None:
            ax.axvspan(start, ti, color=color, alpha=0.25, label=None if labelled else label)
            labelled, start = True, None
    if start is not None and t:
        ax.axvspan(start, t[-1], color=color, alpha=0.25, label=None if labelled else label)


def save(fig: Figure, out: Path) -> None:
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=90)


def _range(text: str) -> float:
    try:
        return float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"'{text}' is not a number of seconds") from None


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="canfdi-plot", description=__doc__.split("\n\n")[0],
                                epilog=EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("log", type=Path, metavar="LOG", help="recorded log: .log (candump -L), .asc, .blf, .trc, ...")
    p.add_argument("-o", "--output", type=Path, metavar="PNG", help="PNG to write (default: LOG with .png)")
    p.add_argument("--title", help="figure title (default: the log's name)")
    p.add_argument("-s", "--scenario", type=Path, metavar="SCN",
                   help="scenario file of the run: its fault lines mark the injections (a canfdi-sil log "
                        "carries no SimFaultInject frames, and SimPlantStatus shows one fault at a time)")
    p.add_argument("--from", dest="t_from", type=_range, metavar="S", help="start, simulated seconds")
    p.add_argument("--to", dest="t_to", type=_range, metavar="S", help="end, simulated seconds")
    return p


def main(argv: list[str] | None = None) -> int:
    p = build_parser()
    a = p.parse_args(argv)
    if a.t_from is not None and a.t_to is not None and a.t_to <= a.t_from:
        p.error(f"--to {a.t_to:g} is not after --from {a.t_from:g}")
    scenario_faults: list[Marker] = []
    if a.scenario is not None:
        try:
            scn = scenario_file.parse(a.scenario)
        except (OSError, scenario_file.ScenarioError) as e:
            print(f"canfdi-plot: {e}", file=sys.stderr)
            return 2
        scenario_faults = [Marker(f.t_start_us * 1e-6, f.name, f.mode) for f in scn.faults]
    out: Path = a.output if a.output is not None else a.log.with_suffix(".png")
    try:
        data = read_plot_data(a.log, a.t_from, a.t_to)
    except LogError as e:
        print(f"canfdi-plot: {e}", file=sys.stderr)
        return 2
    lo = -float("inf") if a.t_from is None else a.t_from
    hi = float("inf") if a.t_to is None else a.t_to
    data.scenario_faults = [mk for mk in scenario_faults if lo <= mk.t_s <= hi]
    r, tl = data.read, data.timeline
    if r.bad_lines:
        print(f"canfdi-plot: {r.bad_lines} unreadable line(s) skipped (first: {r.first_error})", file=sys.stderr)
    if tl is not None and tl.stats.undecodable:
        print(f"canfdi-plot: {tl.stats.undecodable} frame(s) did not decode (first: {tl.stats.first_undecodable})",
              file=sys.stderr)
    if tl is not None and tl.stats.e2e_bad:
        print(f"canfdi-plot: not plotted: {tl.e2e_summary()}", file=sys.stderr)
    if data.frames_plotted == 0:
        where = "" if a.t_from is None and a.t_to is None else " in the range asked"
        print(f"canfdi-plot: {a.log}: no canfdi frame to plot{where} ({r.frames} frames read)", file=sys.stderr)
        return 1
    fig = build_figure(data, a.title if a.title is not None else f"canfdi bus log {a.log.name}")
    try:
        save(fig, out)
    except OSError as e:
        print(f"canfdi-plot: cannot write {out}: {e.strerror or e}", file=sys.stderr)
        return 1
    span = f"{data.span[0]:.3f}-{data.span[1]:.3f} s" if data.span else "-"
    print(f"canfdi-plot: {r.frames} frames, simulated {span}, {len(data.dtcs)} trouble code(s); wrote {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
