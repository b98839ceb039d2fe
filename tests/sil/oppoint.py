#!/usr/bin/env python3
"""tests/sil/oppoint.py -- steady-state operating points of the two plants and
the observability of every catalogue fault there (docs/envelope.md).

    .venv/bin/python tests/sil/oppoint.py dcm 100 1.2            # one DC-motor point
    .venv/bin/python tests/sil/oppoint.py dcm 20 2.1 --supply 36
    .venv/bin/python tests/sil/oppoint.py thr 25                 # one throttle point
    .venv/bin/python tests/sil/oppoint.py table                  # dbc/observability.csv, parsed

Plant equations (docs/design.md, host_sim/canfdi_sim_dcm.h, canfdi_sim_thr.h),
steady state (all derivatives zero):

  DC motor   U_A = R_A(T) I_A + Psi w,   Psi I_A = M_F0 sgn(w) + M_F1 w + M_L
             (at w = 0 the rotor sticks while |M_L| <= M_F0: I_A = 0; else
             the drive holds it with I_A = M_L / Psi)
  throttle   K i = T_spring(theta) + T_c s + B w,  u = R i + K w,
             T_spring = k_s (theta - theta_LH) + P tanh((theta - theta_LH) / delta)
             (s = sgn of the motion; at rest the friction torque lies anywhere
             in [-T_c, T_c], so the holding current is a band)

The plant parameters are the defaults of host_sim/SCENARIO.md's `param`
table (read from that file); the firmware's limits and detection thresholds
are FW below, each with the file that holds it (tests/sil/test_envelope.py
checks them against those files). Observability expressions come from
dbc/observability.csv; `evaluate` gives them the quantities of a point.
"""

import argparse
import ast
import csv
import math
import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
SCENARIO_MD = ROOT / "host_sim" / "SCENARIO.md"
OBS_CSV = ROOT / "dbc" / "observability.csv"

# Firmware limits and thresholds the observability table rests on:
# name -> (value, file, what). Units SI (V, A, rad/s, N m, rad, s), angles
# that the firmware writes in degrees are degrees here too (suffix _deg).
FW = {
    "dcm_u_max": (48.0, "firmware/ctrl/canfdi_ctrl_dcm.c", "armature voltage limit besides the supply"),
    "dcm_ia_max": (20.0, "firmware/ctrl/canfdi_ctrl_dcm.c", "current limit of the speed loop"),
    "dcm_speed_max": (350.0, "firmware/ctrl/canfdi_ctrl_dcm.c", "speed setpoint limit"),
    "dcm_prbs": (5.0, "firmware/app/canfdi_app_cal.c", "PRBS speed excitation amplitude"),
    "dcm_prbs_bit": (0.05, "firmware/app/canfdi_app_cal.c", "PRBS bit period, s"),
    "dcm_speed_bw": (100.0, "firmware/ctrl/canfdi_ctrl_dcm.h", "speed loop bandwidth w_cw, rad/s"),
    "dcm_speed_kp": (0.582, "firmware/ctrl/canfdi_ctrl_dcm.c", "speed PI kp = J w_cw / Psi, A/(rad/s)"),
    "dcm_cur_kp": (3.41, "firmware/ctrl/canfdi_ctrl_dcm.c", "current PI kp = L w_ci, V/A"),
    "dcm_test_w_min": (20.0, "firmware/app/canfdi_app_test.c", "test signal enabled from this |speed reference|, rad/s"),
    "dcm_test_w_max": (350.0, "firmware/app/canfdi_app_test.c", "test signal enabled up to this |speed reference|, rad/s"),
    "thr_test_min_deg": (10.0, "firmware/app/canfdi_app_test.c", "test signal enabled from this angle reference, deg"),
    "thr_test_max_deg": (80.0, "firmware/app/canfdi_app_test.c", "test signal enabled up to this angle reference, deg"),
    "test_burst": (2.5, "firmware/diag/canfdi_testsched.c", "length of a key-on or lack test burst, s"),
    "test_lack": (60.0, "firmware/diag/canfdi_testsched.c", "enabled time without excitation that starts a test burst, s"),
    "test_rest": (10.0, "firmware/diag/canfdi_testsched.c", "rest after a burst, s"),
    "thr_sine": (0.052, "firmware/app/canfdi_app_cal.c", "angle excitation amplitude, rad"),
    "thr_sine_period": (0.5, "firmware/app/canfdi_app_cal.c", "angle excitation period, s"),
    "r1_band": (0.08, "firmware/model/canfdi_parity_dcm.c", "r1 base band, V"),
    "r2_band": (0.02, "firmware/model/canfdi_parity_dcm.c", "r2 base band, N m"),
    "r3_band": (0.02, "firmware/model/canfdi_parity_dcm.c", "r3 base band, N m"),
    "r4_band": (0.12, "firmware/model/canfdi_parity_dcm.c", "r4 base band, V"),
    "unc_ra": (0.010, "firmware/model/canfdi_parity_dcm.c", "R_A uncertainty widening r1 by dR |I|, Ohm"),
    "w_band": (2.0, "firmware/model/canfdi_parity_dcm.c", "r2..r4 valid only while |w| >= w_band, rad/s"),
    "ra_i_min": (1.0, "firmware/model/canfdi_parity_dcm.c", "RMS current the R_A tracker needs, A"),
    "ra_max": (2.0, "firmware/model/canfdi_parity_dcm.c", "upper bound of the plausible R_A, Ohm"),
    "w_sign_on": (10.0, "firmware/app/canfdi_app_sym.c", "speed-sign reference threshold, rad/s"),
    "i_sign_on": (0.8, "firmware/app/canfdi_app_sym.c", "current-sign reference threshold, A"),
    "thr_i_sign_on": (0.1, "firmware/app/canfdi_app_sym.c", "throttle current-sign reference, A"),
    "mech_settle": (1.0, "firmware/app/canfdi_app_sym.c", "mechanical estimates held after a speed reversal, s"),
    "uac_thr": (0.5, "firmware/detect/canfdi_actmon.c", "U_A - command that is one band, V"),
    "uac_headroom": (2.0, "firmware/detect/canfdi_actmon.c", "UAC judged while |command| < supply - headroom, V"),
    "open_u_min": (3.0, "firmware/detect/canfdi_actmon.c", "|command| at which a throttle current must flow, V"),
    "open_i_max": (0.05, "firmware/detect/canfdi_actmon.c", "|current| below which none flows, A"),
    "track_thr": (0.05, "firmware/detect/canfdi_actmon.c", "filtered |angle - reference| = not following, rad"),
    "track_tau": (0.5, "firmware/detect/canfdi_actmon.c", "tracking low-pass, alpha 1/500 per 1 ms step, s"),
    "bridge_check_min": (6.0, "firmware/ft/canfdi_actmgr.c", "|expected U_A| the bridge check needs, V"),
    "par_ra_pos": (0.08, "firmware/diag/canfdi_diagnosis.c", "R_A deviation threshold, +"),
    "par_psi": (0.025, "firmware/diag/canfdi_diagnosis.c", "Psi deviation threshold"),
    "par_fric_pos": (0.03, "firmware/diag/canfdi_diagnosis.c", "friction deviation threshold (of mc_nom), +"),
    "mc_nom": (1.31, "firmware/model/canfdi_est_dcm.c", "nominal lumped M_c = M_F0 + M_L nominal, N m"),
    "jpsi": (0.02, "firmware/diag/canfdi_diagnosis.c", "J/Psi deviation threshold"),
    "par_thr_r_pos": (0.08, "firmware/diag/canfdi_diagnosis.c", "throttle R deviation threshold, +"),
    "par_spring_neg": (0.10, "firmware/diag/canfdi_diagnosis.c", "spring deviation threshold, -"),
    "par_thr_fric_pos": (0.08, "firmware/diag/canfdi_diagnosis.c", "throttle friction deviation threshold, +"),
    "corr_band": (0.01, "firmware/model/canfdi_parity_thr.c", "CORR base band, V"),
    "arm_band": (0.05, "firmware/model/canfdi_parity_thr.c", "ARM base band, V"),
    "pos_band": (0.012, "firmware/model/canfdi_parity_thr.c", "POS base band, rad"),
    "tps_min": (0.25, "firmware/app/canfdi_app_cal.c", "TPS in-range window low, V"),
    "tps_max": (4.75, "firmware/app/canfdi_app_cal.c", "TPS in-range window high, V"),
    "thr_sign_band": (0.3, "firmware/model/canfdi_est_thr.c", "friction-sign dead band of the valve speed, rad/s"),
    "thr_limp_band_deg": (2.0, "firmware/model/canfdi_est_thr.c", "mechanical gate around limp-home, deg"),
    "thr_holdoff": (0.04, "firmware/model/canfdi_est_thr.c", "one-way motion before a mechanical update (40 steps), s"),
    "thr_fast_memory": (0.3, "firmware/model/canfdi_est_thr.h", "memory of the fast mechanical test (shift 6 at ~200 updates/s), s"),
    "thr_angle_min_deg": (0.5, "firmware/ctrl/canfdi_ctrl_thr.c", "position reference lower clamp, deg"),
    "thr_angle_max_deg": (88.0, "firmware/ctrl/canfdi_ctrl_thr.c", "position reference upper clamp, deg"),
    "thr_u_max": (16.0, "firmware/ctrl/canfdi_ctrl_thr.c", "throttle voltage limit besides the supply, V"),
}


def fw(name):
    return FW[name][0]


# Constants of the plant model that are not `param`s (host_sim headers).
ALPHA_CU = 0.0039      # 1/K, host_sim/canfdi_sim_dcm.h (copper)
WINDING_C = 52.3       # the scenarios' warm start (`init dcm_winding 52.3`)
THR_DELTA_DEG = 0.1    # pretension regularisation, host_sim/canfdi_sim_thr.h
THR_MAX_DEG = 90.0     # end stop, host_sim/canfdi_sim_thr.h
TPS1 = (0.5, 4.0 / 90.0)   # V, V/deg (docs/design.md)
TPS2 = (4.5, -4.0 / 90.0)


def plant_params(path=SCENARIO_MD):
    """The `param` table of host_sim/SCENARIO.md: name -> default."""
    row = re.compile(r"^\|\s*`(\w+)`\s*\|\s*([-+0-9.eE]+)\s*\|")
    out = {}
    for line in Path(path).read_text().splitlines():
        m = row.match(line)
        if m:
            out[m.group(1)] = float(m.group(2))
    need = ("dcm_ra_cold_ohm", "dcm_psi_Vs", "dcm_mf0_Nm", "dcm_mf1_Nms", "dcm_ambient_C",
            "dcm_supply_V", "thr_r_ohm", "thr_k_Nm_A", "thr_b_Nms", "thr_spring_Nm_rad",
            "thr_pretension_Nm", "thr_friction_Nm", "thr_limp_home_deg", "thr_supply_V",
            "dcm_rth_K_W")
    missing = [n for n in need if n not in out]
    if missing:
        raise ValueError(f"{path}: param table lacks {', '.join(missing)}")
    return out


P = plant_params()


def ra_at(temp_c, p=P):
    """R_A at a winding temperature (R_20 chosen so that R(T_amb) = ra_cold)."""
    r20 = p["dcm_ra_cold_ohm"] / (1.0 + ALPHA_CU * (p["dcm_ambient_C"] - 20.0))
    return r20 * (1.0 + ALPHA_CU * (temp_c - 20.0))


RA_WARM = ra_at(WINDING_C)


def dcm_test_enabled(w):
    """The ECU may run its PRBS test signal at speed reference w
    (firmware/app/canfdi_app_test.c): it does so on demand (a symptom not
    yet isolated, an unlearnt estimator), so where it is enabled the
    observability counts with it and where not, without."""
    return fw("dcm_test_w_min") <= abs(w) <= fw("dcm_test_w_max")


def thr_test_enabled(th_sp):
    """As dcm_test_enabled for the throttle's +-3 deg sine burst."""
    return fw("thr_test_min_deg") <= th_sp <= fw("thr_test_max_deg")


def dcm_point(w, load, supply=None, ra=RA_WARM, p=P):
    """Steady state of the DC motor at true speed w [rad/s] and load M_L [N m],
    with the PRBS test signal's current and command step where it is enabled."""
    psi, mf0, mf1 = p["dcm_psi_Vs"], p["dcm_mf0_Nm"], p["dcm_mf1_Nms"]
    supply = p["dcm_supply_V"] if supply is None else supply
    if w == 0.0:
        i_a = load / psi if abs(load) > mf0 else 0.0
    else:
        i_a = (mf0 * math.copysign(1.0, w) + mf1 * w + load) / psi
    u_a = ra * i_a + psi * w
    u_lim = min(supply, fw("dcm_u_max"))
    test = dcm_test_enabled(w)
    i_exc = dcm_excitation_current(p) if test else 0.0
    return dict(w=w, M_L=load, I=i_a, U=u_a, supply=supply, u_lim=u_lim,
                I_rms=math.hypot(i_a, i_exc), U_exc=dcm_excitation_command(ra) if test else 0.0,
                test=1 if test else 0,
                sat=abs(u_a) >= u_lim,
                uac=abs(u_a) < supply - fw("uac_headroom"),
                P_el=u_a * i_a, P_mech=psi * i_a * w,
                quadrant=("standstill" if w == 0.0 else
                          ("motoring" if i_a * w > 0 else "braking")))


def dcm_excitation_current(p=P):
    """RMS armature current of the ECU's PRBS speed excitation alone: each
    edge steps the speed reference by 2a; the speed loop (bandwidth w_cw,
    tau = 1/w_cw) accelerates the rotor with the current
    (J/Psi) (2a/tau) e^(-t/tau), whose square integrates to
    (J 2a / (Psi tau))^2 tau / 2; an edge comes with every other bit on
    average (bit period Tb): mean i^2 = (J 2a / (Psi tau))^2 tau / (4 Tb)."""
    a, tb, tau = fw("dcm_prbs"), fw("dcm_prbs_bit"), 1.0 / fw("dcm_speed_bw")
    peak = p["dcm_j_kgm2"] * 2 * a / (p["dcm_psi_Vs"] * tau)
    return peak * math.sqrt(tau / (4 * tb))


def dcm_excitation_command(ra=RA_WARM):
    """Armature command at a PRBS edge on top of the operating point: the
    speed PI steps the current reference by kp_w 2a, the current PI answers
    with kp_i times that plus the feed-forward R i_ref."""
    di = fw("dcm_speed_kp") * 2 * fw("dcm_prbs")
    return (fw("dcm_cur_kp") + ra) * di


def dcm_speed_max(load, supply=None, p=P, ra=RA_WARM):
    """Highest steady speed (forward) the voltage limit allows at a load."""
    psi, mf0, mf1 = p["dcm_psi_Vs"], p["dcm_mf0_Nm"], p["dcm_mf1_Nms"]
    supply = p["dcm_supply_V"] if supply is None else supply
    u_lim = min(supply, fw("dcm_u_max"))
    # U = ra (mf0 + mf1 w + M_L) / psi + psi w  -> linear in w
    return (u_lim - ra * (mf0 + load) / psi) / (ra * mf1 / psi + psi)


def dcm_continuous_current(p=P):
    """Current whose steady winding temperature puts R_A at the firmware's
    plausible bound ra_max: I^2 R(T) R_th = T - T_amb."""
    r_max = fw("ra_max")
    r20 = p["dcm_ra_cold_ohm"] / (1.0 + ALPHA_CU * (p["dcm_ambient_C"] - 20.0))
    t = 20.0 + (r_max / r20 - 1.0) / ALPHA_CU
    return math.sqrt((t - p["dcm_ambient_C"]) / (p["dcm_rth_K_W"] * r_max)), t


def thr_spring(theta_deg, p=P):
    d = math.radians(theta_deg - p["thr_limp_home_deg"])
    return p["thr_spring_Nm_rad"] * d + p["thr_pretension_Nm"] * math.tanh(d / math.radians(THR_DELTA_DEG))


def thr_point(theta_deg, w=0.0, supply=None, p=P):
    """Throttle at angle theta [deg] moving at w [rad/s] (0: at rest).
    i is the current that balances the spring (friction averaged out over
    a back-and-forth motion); i_lo..i_hi the band friction allows (at rest)
    or the current of the present motion direction (moving)."""
    k, r, tc, b = p["thr_k_Nm_A"], p["thr_r_ohm"], p["thr_friction_Nm"], p["thr_b_Nms"]
    supply = p["thr_supply_V"] if supply is None else supply
    ts = thr_spring(theta_deg)
    i = (ts + b * w) / k
    if w == 0.0:
        i_lo, i_hi = (ts - tc) / k, (ts + tc) / k
    else:
        i_lo = i_hi = (ts + b * w + tc * math.copysign(1.0, w)) / k
    u = r * i + k * w
    tps1 = TPS1[0] + TPS1[1] * theta_deg
    tps2 = TPS2[0] + TPS2[1] * theta_deg
    u_lim = min(supply, fw("thr_u_max"))
    return dict(th=theta_deg, th_dot=w, T_spring=ts, i=i, i_lo=i_lo, i_hi=i_hi, u=u,
                supply=supply, u_lim=u_lim, sat=abs(r * max(abs(i_lo), abs(i_hi)) + k * w) >= u_lim,
                tps1=tps1, tps2=tps2)


def thr_slew_max(supply=None, p=P, theta_deg=45.0):
    """Top valve speed [rad/s] with the full supply applied (K w = U - R i
    with K i = spring + friction + B w): the physical tip-in rate."""
    k, r, tc, b = p["thr_k_Nm_A"], p["thr_r_ohm"], p["thr_friction_Nm"], p["thr_b_Nms"]
    supply = p["thr_supply_V"] if supply is None else supply
    u = min(supply, fw("thr_u_max"))
    ts = thr_spring(theta_deg)
    # u = r (ts + tc + b w) / k + k w
    return (u - r * (ts + tc) / k) / (r * b / k + k)


# ---------------------------------------------------------------------------
# Expressions of dbc/observability.csv: a tiny safe language.
_ALLOWED = (ast.Expression, ast.BoolOp, ast.And, ast.Or, ast.UnaryOp, ast.Not, ast.USub,
            ast.BinOp, ast.Add, ast.Sub, ast.Mult, ast.Div, ast.Compare, ast.Lt, ast.LtE,
            ast.Gt, ast.GtE, ast.Eq, ast.NotEq, ast.Name, ast.Load, ast.Constant, ast.Call)
FUNCS = {"abs": abs, "min": min, "max": max}

# Quantities an expression may use, with their meaning (docs/envelope.md).
VARS = {
    "w": "DC-motor true speed, rad/s",
    "I": "armature current, A (steady state)",
    "I_rms": "RMS armature current with the ECU's PRBS test signal where it is enabled, A",
    "U_exc": "armature command step of a PRBS edge where the test signal is enabled (else 0), V",
    "test": "1 where the test signal is enabled (a symptom starts it there): DC motor |w| 20..350 rad/s, throttle reference 10..80 deg",
    "burst": "1 while the throttle's KEYON or LACK test burst runs",
    "U": "armature voltage, V (steady state)",
    "M_L": "load torque, N m",
    "uac": "1 while the U_A-command channel is judged: |U| < supply - 2 V",
    "oneway": "s the motor has turned one way with |w| >= 10 rad/s",
    "th": "valve angle, deg",
    "th_dot": "valve speed, rad/s (reference motion incl. the test signal where it is enabled)",
    "th_sp": "the driver's angle setpoint (clamped to 0.5..88 deg), deg",
    "moving": "1 while the last 2 s hold the fast test's 0.3 s memory of one-way motion beyond 0.3 rad/s that has lasted 40 ms",
    "moving_away": "as moving, counting only motion more than 2 deg from limp-home",
    "i": "throttle motor current that balances the spring, A",
    "tps1": "TPS1 true voltage, V",
    "tps2": "TPS2 true voltage, V",
    "stuck_err": "largest |reference - angle at the fault start| over the last 0.5 s (a valve stuck there), rad",
    "always": "1",
}


class ExprError(ValueError):
    pass


def compile_expr(text, where="expression"):
    """Parse one expression, refusing anything but arithmetic, comparisons,
    and/or/not, abs/min/max and the names of VARS."""
    try:
        tree = ast.parse(text.strip(), mode="eval")
    except SyntaxError as e:
        raise ExprError(f"{where}: cannot parse {text!r}: {e.msg}") from None
    for node in ast.walk(tree):
        if not isinstance(node, _ALLOWED):
            raise ExprError(f"{where}: {type(node).__name__} not allowed in {text!r}")
        if isinstance(node, ast.Name) and node.id not in VARS and node.id not in FUNCS:
            raise ExprError(f"{where}: unknown name {node.id!r} in {text!r} "
                            f"(known: {', '.join(sorted(VARS))})")
        if isinstance(node, ast.Call) and (not isinstance(node.func, ast.Name) or node.func.id not in FUNCS):
            raise ExprError(f"{where}: only abs/min/max may be called in {text!r}")
    return compile(tree, where, "eval")


def evaluate(code, quantities):
    env = dict(FUNCS)
    env.update(quantities)
    env["always"] = 1
    return bool(eval(code, {"__builtins__": {}}, env))


def load_observability(path=OBS_CSV, faults=None):
    """dbc/observability.csv -> {fault: row with compiled 'obs', 'iso' and
    'tolerated' [(code, compiled condition)]}. Checks every catalogue fault
    has one row and every expression parses."""
    rows = {}
    with open(path, newline="") as f:
        for n, r in enumerate(csv.DictReader(row for row in f if not row.startswith("#")), 2):
            where = f"{path.name if hasattr(path, 'name') else path}: {r['fault']}"
            if r["fault"] in rows:
                raise ExprError(f"{where}: duplicated")
            r["obs_code"] = compile_expr(r["observable_if"], where + " observable_if")
            r["iso_code"] = compile_expr(r["isolable_if"], where + " isolable_if")
            tol = []
            for part in filter(None, (s.strip() for s in r.get("tolerated", "").split(";"))):
                code, _, cond = part.partition(" if ")
                if not re.fullmatch(r"[PCBU][0-9A-F]{4}", code.strip()):
                    raise ExprError(f"{where}: tolerated entry {part!r} is not 'CODE [if EXPR]'")
                cond = cond.strip() or "always"
                tol.append((code.strip(), compile_expr(cond, where + " tolerated"), cond))
            r["tolerated_codes"] = tol
            rows[r["fault"]] = r
    if faults is not None:
        missing = [f for f in faults if f not in rows]
        extra = [f for f in rows if f not in faults]
        if missing or extra:
            raise ExprError(f"{path}: no row for {missing}; rows for unknown faults {extra}")
    return rows


def _fmt(d):
    return "  ".join(f"{k}={v:.4g}" if isinstance(v, float) else f"{k}={v}" for k, v in d.items())


def main(argv=None):
    ap = argparse.ArgumentParser(
        description="Steady-state operating point of the DC motor or the throttle "
                    "(plant equations of docs/design.md, parameters of host_sim/SCENARIO.md) "
                    "and which catalogue faults are observable there (dbc/observability.csv).",
        epilog="Examples: oppoint.py dcm 100 1.2 | oppoint.py dcm 0 0 | oppoint.py thr 85 "
               "| oppoint.py limits | oppoint.py table")
    sub = ap.add_subparsers(dest="cmd", required=True)
    d = sub.add_parser("dcm", help="DC-motor point: speed [rad/s] and load [N m]")
    d.add_argument("speed", type=float)
    d.add_argument("load", type=float)
    d.add_argument("--supply", type=float, default=None, help="bridge supply [V] (default 48)")
    t = sub.add_parser("thr", help="throttle point: angle [deg], optional valve speed [rad/s]")
    t.add_argument("angle", type=float)
    t.add_argument("--speed", type=float, default=0.0)
    t.add_argument("--supply", type=float, default=None, help="bridge supply [V] (default 13.5)")
    sub.add_parser("limits", help="the envelope's physical limits (docs/envelope.md)")
    sub.add_parser("table", help="parse dbc/observability.csv and print it")
    a = ap.parse_args(argv)
    if a.cmd == "dcm":
        if not -400 <= a.speed <= 400 or not -10 <= a.load <= 10:
            ap.error("speed must lie in +-400 rad/s and load in +-10 N m (the simulator's ranges)")
        q = dcm_point(a.speed, a.load, a.supply)
        print(_fmt(q))
        q.update(oneway=100.0 if abs(a.speed) >= fw("w_sign_on") else 0.0)
        rows = load_observability()
        for name, r in rows.items():
            if name.startswith("dcm_"):
                print(f"  {name:26s} {classify(r, q)}")
    elif a.cmd == "thr":
        if not 0 <= a.angle <= 90:
            ap.error("angle must lie in 0..90 deg")
        q = thr_point(a.angle, a.speed, a.supply)
        print(_fmt(q))
        test = thr_test_enabled(a.angle)
        away = abs(a.angle - P["thr_limp_home_deg"]) >= fw("thr_limp_band_deg")
        moving = test or abs(a.speed) >= fw("thr_sign_band")
        q.update(test=1 if test else 0, burst=1 if test else 0,
                 moving=1 if moving else 0, moving_away=1 if (moving and away) else 0,
                 th_sp=a.angle, stuck_err=fw("thr_sine") if test else 0.0)
        rows = load_observability()
        how = "valve moving with the test signal" if test else "no test signal at this angle"
        for name, r in rows.items():
            if name.startswith("thr_"):
                print(f"  {name:26s} {classify(r, q)}  ({how})")
    elif a.cmd == "limits":
        for k, v in limits().items():
            print(f"{k:34s} {v:.4g}")
    else:
        for name, r in load_observability().items():
            print(f"{name:24s} observable if {r['observable_if']:40s} isolable if {r['isolable_if']}")
    return 0


def classify(row, q):
    if evaluate(row["iso_code"], q):
        return "isolable"
    if evaluate(row["obs_code"], q):
        return "observable"
    return "not_observable"


def limits():
    """The envelope's physical limits (docs/envelope.md)."""
    i_cont, t_cont = dcm_continuous_current()
    psi, mf0, mf1 = P["dcm_psi_Vs"], P["dcm_mf0_Nm"], P["dcm_mf1_Nms"]
    return {
        "R_A warm [Ohm]": RA_WARM,
        "continuous current [A]": i_cont,
        "winding at continuous current [C]": t_cont,
        "continuous load at 20 rad/s [N m]": psi * i_cont - mf0 - mf1 * 20.0,
        "peak torque at ia_max [N m]": psi * fw("dcm_ia_max"),
        "PRBS excitation current RMS [A]": dcm_excitation_current(),
        "PRBS edge command step [V]": dcm_excitation_command(),
        "speed max, no load, 48 V limit [rad/s]": dcm_speed_max(0.0),
        "speed max, 1.2 N m, 48 V [rad/s]": dcm_speed_max(1.2),
        "speed max, 0.6 N m, 48 V [rad/s]": dcm_speed_max(0.6),
        "speed max, 1.2 N m, 36 V [rad/s]": dcm_speed_max(1.2, 36.0),
        "speed max, no load, 80 V bridge [rad/s]": (80.0 - RA_WARM * mf0 / psi) / (RA_WARM * mf1 / psi + psi),
        "voltage for 400 rad/s no load [V]": dcm_point(400.0, 0.0)["U"],
        "throttle slew 13.5 V [rad/s]": thr_slew_max(),
        "throttle slew 9 V [rad/s]": thr_slew_max(9.0),
        "throttle 10->80 deg at 13.5 V [ms]": 1000 * math.radians(70) / thr_slew_max(),
        "throttle 10->80 deg at 9 V [ms]": 1000 * math.radians(70) / thr_slew_max(9.0),
        "TPS2 drift 0.3 V leaves range below [deg]": (TPS2[0] + 0.3 - fw("tps_max")) / -TPS2[1],
        "TPS1 drift 0.3 V leaves range above [deg]": (fw("tps_max") - 0.3 - TPS1[0]) / TPS1[1],
    }


if __name__ == "__main__":
    sys.exit(main())
