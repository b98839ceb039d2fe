"""canfdi-drive-profile: a fault-free driver profile for the plants, from the
WLTC class 3 drive cycle (UNECE GTR 15), as a profile CSV for
``profile <file.csv>`` (host_sim/SCENARIO.md).

The vehicle's speed trace comes from the wltp package (drive.wltc). It is
mapped to the DC motor (a traction drive: speed and load torque) and to the
throttle (an accelerator-pedal interpretation), and what the cycle lacks is
added: parking manoeuvres with reversals, standstill, a cold start and the
warm-up, start-stop restarts, supply sag under load, charging in cruise and
regeneration. docs/driving.md states every formula and constant and why.

    canfdi-drive-profile --duration 600 --seed 1 --trips 1,4,5,8 --manoeuvres 1 \
        -o build/drive/wltc3_10min_s1.csv

The stochastic parts (driver variation of each micro-trip, stop lengths,
where the manoeuvres go, their speeds, the road grade, the battery's state)
come from one seeded generator: the same options give the same file byte for
byte, another seed another drive. The generator refuses to write a profile
the plants could not follow (``check``): the motor's voltage and current
within the drive's rating at the supply in force, every value within the
profile file's ranges.
"""
from __future__ import annotations

import argparse
import json
import math
import sys
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np

from . import wltc

DT = 0.01            # s: the generator's internal time step
OUT_DT = 0.1         # s: the profile's row spacing (steps and fast supply events get their own rows)
STEP_S = 0.001       # s: a step is two rows this far apart (one simulator step)


# ---- the models and their constants (docs/driving.md) ------------------------------------------------

@dataclass(frozen=True)
class Vehicle:
    """A representative mid-size car of WLTC class 3 (this project's choice)."""
    mass_kg: float = 1500.0
    rot_factor: float = 1.03          # rotating masses as extra translational mass
    f0_N: float = 130.0               # road load f0 + f1 v + f2 v^2
    f1_N_s_m: float = 0.9
    f2_N_s2_m2: float = 0.42
    v_roll_m_s: float = 0.1           # f0 fades in over this speed (tanh) so the load is smooth through 0
    grade_max: float = 0.03           # road grade, rise/run, at most
    grade_periods_s: tuple[float, float] = (240.0, 600.0)
    brake_handover_s: float = 0.3     # the brakes take the load over from the motor at a stop (and back)
    force_full_N: float = 4500.0      # full-load tractive force at low speed (the pedal's 100 %)
    power_full_W: float = 90e3        # full-load power (the pedal's 100 % above ~20 m/s)
    g: float = 9.81


@dataclass(frozen=True)
class Drive:
    """The host_sim DC motor (docs/design.md) and the firmware's current limit."""
    psi_Vs: float = 0.33
    ra_cold_ohm: float = 1.35         # at 20 degC
    alpha_per_K: float = 0.0039
    winding_max_C: float = 80.0       # R_A for the voltage check: the warmest winding a drive reaches
    mf0_Nm: float = 0.11
    mf1_Nms: float = 0.36e-3
    j_kgm2: float = 1.92e-3
    i_max_A: float = 20.0             # canfdi_ctrl_dcm_cal_default: ia_max
    torque_share: float = 0.6         # the rated load torque is this share of psi * i_max
    voltage_headroom: float = 0.85    # the armature voltage a profile may need, as a share of the supply
    speed_scale_max: float = 1.03     # the driver's largest speed factor (Plan), for the speed mapping

    @property
    def torque_rated_Nm(self) -> float:
        return self.torque_share * self.psi_Vs * self.i_max_A

    @property
    def ra_hot_ohm(self) -> float:
        return self.ra_cold_ohm * (1.0 + self.alpha_per_K * (self.winding_max_C - 20.0))


@dataclass(frozen=True)
class Bus48:
    """The 48 V battery of the drive's bridge supply."""
    u_oc_cold: tuple[float, float] = (44.5, 46.0)   # open-circuit voltage at key-on (weak, part-charged), seeded
    u_oc_charged: float = 48.5
    tau_charge_s: float = 900.0
    r_int_cold_ohm: float = 0.30      # internal resistance, cold -> warm battery
    r_int_warm_ohm: float = 0.18
    tau_battery_s: float = 1200.0
    u_charge: float = 52.0            # charger set point in cruise
    u_min: float = 36.0
    u_max: float = 54.0
    tau_bus_s: float = 0.05           # bus capacitance: the voltage moves this smoothly
    cruise_speed_m_s: float = 15.0    # charging in cruise: above this speed ...
    cruise_accel_m_s2: float = 0.15   # ... and below this |acceleration|
    tau_charge_flag_s: float = 2.0


@dataclass(frozen=True)
class Net12:
    """The 12 V board net of the throttle's bridge supply (alternator, starter)."""
    u_battery_cold: float = 12.1
    u_battery_warm: float = 12.4
    u_engine_off_drop: float = 0.25   # loads on the battery while the engine is stopped
    u_charge_cold: float = 14.6       # temperature-compensated regulator, cold -> warm
    u_charge_warm: float = 14.1
    tau_warm_s: float = 600.0
    crank_cold: tuple[float, float, float, float] = (8.0, 0.05, 9.5, 1.0)   # dip V, s, then V, s
    crank_warm: tuple[float, float, float, float] = (9.2, 0.03, 10.8, 0.35)
    crank_recover_s: float = 0.5


@dataclass(frozen=True)
class Throttle:
    closed_deg: float = 2.0           # tip-out and overrun: the closed position above the stop
    idle_warm_deg: float = 4.0        # warm idle: below limp-home (6.5 deg)
    idle_cold_deg: float = 8.0        # cold idle: above limp-home
    tau_warm_s: float = 240.0         # engine warm-up
    wot_deg: float = 90.0             # wide open: the valve's end stop
    rate_deg_s: float = 0.0           # > 0: the angle moves at most this fast (no steps)
    dense_deg_per_sample: float = 0.5 # faster than this per DT, every sample goes into the file
    gamma: float = 1.5                # progressive pedal map
    tau_pedal_s: float = 0.25         # the driver's foot
    a_tip_in: tuple[float, float] = (0.9, 1.1)      # m/s^2: harder than this floors the pedal (seeded per drive)
    a_tip_out: tuple[float, float] = (0.7, 0.9)     # m/s^2: braking harder than this snaps it shut
    tip_min_s: float = 0.8
    lift_late_s: float = 1.0          # before a hard tip-out the foot holds the pedal this long
    lift_after_tip_in_prob: float = 0.5   # chance of a full lift-off when a hard acceleration ends
    lift_s: tuple[float, float] = (0.4, 1.2)
    idle_speed_m_s: float = 3.0       # below this a decelerating car idles instead of cutting fuel


@dataclass(frozen=True)
class Plan:
    duration_s: float = 600.0
    seed: int = 1
    trips: tuple[int, ...] = ()       # 1-based micro-trips of the cycle in driving order (empty: all), repeated
    manoeuvre_prob: float = 0.35      # chance of a parking manoeuvre at a stop
    key_on_idle_s: float = 12.0       # cold start: standstill after key-on
    crank_at_s: float = 0.5
    time_stretch: tuple[float, float] = (0.94, 1.06)   # driver variation per micro-trip
    speed_scale: tuple[float, float] = (0.97, 1.03)
    stop_scale: tuple[float, float] = (0.7, 1.3)
    stop_min_s: float = 3.0
    start_stop_after_s: float = 300.0  # the engine stops at long stops once warm
    start_stop_min_stop_s: float = 12.0
    hill_hold_prob: float = 0.3       # a stop held by the motor on the grade (else the brakes hold)
    reverse_kmh: tuple[float, float] = (4.0, 12.0)
    creep_kmh: tuple[float, float] = (2.0, 5.0)


@dataclass
class Profile:
    t_s: np.ndarray
    v_m_s: np.ndarray
    a_m_s2: np.ndarray
    speed_rad_s: np.ndarray
    load_Nm: np.ndarray
    angle_deg: np.ndarray
    dcm_supply_V: np.ndarray
    thr_supply_V: np.ndarray
    i_motor_A: np.ndarray
    u_needed_V: np.ndarray
    force_N: np.ndarray               # tractive force on the motor's side (after the brakes' share)
    grade: np.ndarray
    steps: list[int]                  # angle steps: between sample k and k + 1
    dense: np.ndarray                 # samples written at DT, not only every OUT_DT
    info: dict = field(default_factory=dict)


class ProfileError(ValueError):
    """A plan the generator cannot make, or a profile the plants could not follow."""


# ---- building blocks -------------------------------------------------------------------------------------

def pchip(x: np.ndarray, y: np.ndarray, xi: np.ndarray, flat_ends: bool = False) -> np.ndarray:
    """Monotone piecewise-cubic Hermite interpolation (Fritsch-Carlson): no overshoot,
    so a speed trace stays at 0 where it stops and never dips below it. flat_ends: zero
    slope at both ends (a micro-trip leaves and reaches standstill without a jump in
    acceleration)."""
    h = np.diff(x)
    d = np.diff(y) / h
    m = np.zeros_like(y)
    for k in range(1, len(y) - 1):
        if d[k - 1] * d[k] > 0.0:
            w1, w2 = 2.0 * h[k] + h[k - 1], h[k] + 2.0 * h[k - 1]
            m[k] = (w1 + w2) / (w1 / d[k - 1] + w2 / d[k])
    m[0], m[-1] = (d[0] if len(d) else 0.0), (d[-1] if len(d) else 0.0)
    if len(d) and d[0] * m[0] <= 0.0:
        m[0] = 0.0
    if len(d) and d[-1] * m[-1] <= 0.0:
        m[-1] = 0.0
    if flat_ends:
        m[0] = m[-1] = 0.0
    k = np.clip(np.searchsorted(x, xi, side="right") - 1, 0, len(x) - 2)
    t = (xi - x[k]) / h[k]
    h00, h10 = 2 * t**3 - 3 * t**2 + 1, t**3 - 2 * t**2 + t
    h01, h11 = -2 * t**3 + 3 * t**2, t**3 - t**2
    return h00 * y[k] + h10 * h[k] * m[k] + h01 * y[k + 1] + h11 * h[k] * m[k + 1]


def smooth_move(v0: float, v1: float, a_peak: float) -> np.ndarray:
    """Speed from v0 to v1 with a raised-cosine acceleration of peak a_peak, at DT."""
    dv = v1 - v0
    if dv == 0.0:
        return np.array([v0])
    T = math.pi * abs(dv) / (2.0 * a_peak)
    n = max(2, int(math.ceil(T / DT)))
    s = np.linspace(0.0, 1.0, n + 1)
    return v0 + dv * (1.0 - np.cos(math.pi * s)) / 2.0


def lowpass(x: np.ndarray, tau_s: float) -> np.ndarray:
    """First-order lag, discretised exactly at DT (starts at x[0])."""
    if tau_s <= 0.0:
        return x.copy()
    k = 1.0 - math.exp(-DT / tau_s)
    y = np.empty_like(x)
    acc = x[0]
    for i, xi in enumerate(x):
        acc += k * (xi - acc)
        y[i] = acc
    return y


def runs(mask: np.ndarray) -> list[tuple[int, int]]:
    """[start, end) index pairs of the True runs of a boolean array."""
    m = np.concatenate(([False], mask, [False])).astype(np.int8)
    d = np.diff(m)
    return list(zip(np.flatnonzero(d == 1), np.flatnonzero(d == -1)))


# ---- the drive: vehicle speed with stops, trips and manoeuvres -------------------------------------------

@dataclass
class _Track:
    v: list[np.ndarray] = field(default_factory=list)
    n: int = 0
    stops: list[tuple[int, int, bool]] = field(default_factory=list)    # [start, end), hill-hold
    manoeuvres: list[tuple[int, int, str]] = field(default_factory=list)
    trips: list[tuple[int, int, int]] = field(default_factory=list)      # [start, end), cycle trip index

    def add(self, v: np.ndarray) -> tuple[int, int]:
        self.v.append(np.asarray(v, dtype=float))
        start = self.n
        self.n += len(v)
        return start, self.n

    def stop(self, seconds: float, hold: bool) -> None:
        a, b = self.add(np.zeros(max(1, int(round(seconds / DT)))))
        self.stops.append((a, b, hold))


def _manoeuvre(rng: np.random.Generator, plan: Plan, tr: _Track) -> None:
    """Parking: reverse out, stop, forward, and a rocking reversal through zero
    (forward creep straight into reverse creep and back to a stop)."""
    kmh = wltc.KMH
    a_pk = float(rng.uniform(0.6, 1.0))
    v_rev = -float(rng.uniform(*plan.reverse_kmh)) * kmh
    v_fwd = float(rng.uniform(*plan.creep_kmh)) * kmh
    v_rock = float(rng.uniform(*plan.creep_kmh)) * kmh
    start = tr.n
    # reverse out of the space
    tr.add(smooth_move(0.0, v_rev, a_pk)[1:])
    tr.add(np.full(int(rng.uniform(1.5, 4.0) / DT), v_rev))
    tr.add(smooth_move(v_rev, 0.0, a_pk)[1:])
    tr.stop(float(rng.uniform(0.8, 2.0)), False)
    # forward, then straight back through zero, then stop
    tr.add(smooth_move(0.0, v_fwd, a_pk)[1:])
    tr.add(np.full(int(rng.uniform(1.0, 2.5) / DT), v_fwd))
    tr.add(smooth_move(v_fwd, -v_rock, 0.5 * a_pk)[1:])
    tr.add(np.full(int(rng.uniform(0.5, 1.5) / DT), -v_rock))
    tr.add(smooth_move(-v_rock, 0.0, a_pk)[1:])
    tr.manoeuvres.append((start, tr.n, "park"))


def _speed_track(rng: np.random.Generator, plan: Plan, cycle: wltc.Cycle) -> _Track:
    all_trips = wltc.trips(cycle)
    order = list(plan.trips) if plan.trips else [t.index for t in all_trips]
    for i in order:
        if not 1 <= i <= len(all_trips):
            raise ProfileError(f"trip {i}: the cycle has micro-trips 1..{len(all_trips)}")
    tr = _Track()
    tr.stop(plan.key_on_idle_s, bool(rng.random() < plan.hill_hold_prob))
    k = 0
    while tr.n * DT < plan.duration_s:
        trip = all_trips[order[k % len(order)] - 1]
        if k > 0:
            stop = max(plan.stop_min_s, trip.stop_before_s * float(rng.uniform(*plan.stop_scale)))
            if rng.random() < plan.manoeuvre_prob:
                tr.stop(0.4 * stop, False)
                _manoeuvre(rng, plan, tr)
                tr.stop(0.6 * stop, bool(rng.random() < plan.hill_hold_prob))
            else:
                tr.stop(stop, bool(rng.random() < plan.hill_hold_prob))
        v1 = trip.speeds(cycle)
        stretch = float(rng.uniform(*plan.time_stretch))
        scale = float(rng.uniform(*plan.speed_scale))
        x = np.arange(len(v1)) * stretch
        xi = np.arange(0.0, x[-1] + 1e-9, DT)
        v = np.maximum(pchip(x, v1 * scale, xi, flat_ends=True), 0.0)
        v[0] = v[-1] = 0.0
        a, b = tr.add(v[1:-1])
        tr.trips.append((a, b, trip.index))
        k += 1
    # standing at the end until the duration is covered
    tr.stop(max(plan.stop_min_s, plan.duration_s - tr.n * DT + 2.0), False)
    return tr


# ---- the mapping ----------------------------------------------------------------------------------------

def road_force(veh: Vehicle, v: np.ndarray, a: np.ndarray, grade: np.ndarray) -> np.ndarray:
    """Tractive force the wheels must give: inertia + road load + grade (N); negative when braking."""
    m_eff = veh.mass_kg * veh.rot_factor
    road = veh.f0_N * np.tanh(v / veh.v_roll_m_s) + veh.f1_N_s_m * v + veh.f2_N_s2_m2 * v * np.abs(v)
    return m_eff * a + road + veh.mass_kg * veh.g * np.sin(np.arctan(grade))


def motor_current(drv: Drive, w: np.ndarray, alpha: np.ndarray, load: np.ndarray) -> np.ndarray:
    """Armature current for the speed, acceleration and load: the mechanical equation solved for I."""
    friction = drv.mf0_Nm * np.tanh(w / 1.0) + drv.mf1_Nms * w
    return (drv.j_kgm2 * alpha + friction + load) / drv.psi_Vs


def _reference(drv: Drive, veh: Vehicle, cycle: wltc.Cycle) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    """The reference drive of the speed mapping: the base cycle Drive.speed_scale_max faster, up
    the steepest grade. Returns (v, a, load on the rated scale, the force scale's |F| peak)."""
    t = np.arange(0.0, cycle.duration_s + 1e-9, DT)
    v = pchip(np.arange(len(cycle.v_m_s), dtype=float), cycle.v_m_s, t) * drv.speed_scale_max
    a = np.gradient(v, DT)
    f = road_force(veh, v, a, np.full_like(v, veh.grade_max))
    f_peak = float(np.abs(f).max())
    return v, a, drv.torque_rated_Nm * f / f_peak, f_peak


def _reference_bus(drv: Drive, bus: Bus48, v: np.ndarray, a: np.ndarray, load: np.ndarray, k: float) -> np.ndarray:
    """Bus voltage on the reference drive at speed scale k: the weak cold battery (lowest
    open-circuit voltage, cold internal resistance) sagging with the motor's power."""
    u_oc = bus.u_oc_cold[0]
    i_m = motor_current(drv, k * v, k * a, load)
    return u_oc - bus.r_int_cold_ohm * np.maximum((drv.psi_Vs * k * v + drv.ra_cold_ohm * i_m) * i_m / u_oc, 0.0)


def reference_share(drv: Drive, veh: Vehicle, bus: Bus48, cycle: wltc.Cycle, k: float) -> float:
    """The largest share of the bus voltage the reference drive needs at speed scale k, with the
    warmest winding and the current's magnitude: psi w + R_hot (J |alpha| + M_F0 + M_F1 w + |M_L|) / psi."""
    v, a, load, _ = _reference(drv, veh, cycle)
    u = _reference_bus(drv, bus, v, a, load, k)
    i_abs = (drv.j_kgm2 * k * np.abs(a) + drv.mf0_Nm + drv.mf1_Nms * k * v + np.abs(load)) / drv.psi_Vs
    moving = v > 0.5
    return float(((drv.psi_Vs * k * v + drv.ra_hot_ohm * i_abs)[moving] / u[moving]).max())


def speed_scale(drv: Drive, veh: Vehicle, bus: Bus48, cycle: wltc.Cycle) -> tuple[float, float, float]:
    """rad/s per m/s: the largest motor speed per vehicle speed at which the reference drive
    (_reference) needs at most voltage_headroom of the bus voltage at every instant
    (reference_share). Returns (scale, the force scale's |F| peak, the lowest bus voltage)."""
    v, a, load, f_peak = _reference(drv, veh, cycle)
    moving = v > 0.5
    r = drv.ra_hot_ohm
    k = drv.voltage_headroom * bus.u_oc_cold[0] / (drv.psi_Vs * float(v.max()))
    u = _reference_bus(drv, bus, v, a, load, k)
    for _ in range(50):    # the bus sags with the current the speed needs: a fixed point, reached in a few passes
        u = _reference_bus(drv, bus, v, a, load, k)
        # psi k v + R (J k |a| + mf0 + mf1 k v + |load|) / psi <= headroom u, solved for k per sample
        i_rest = (np.abs(load) + drv.mf0_Nm) / drv.psi_Vs
        per_k = drv.psi_Vs * v + r * (drv.mf1_Nms * v + drv.j_kgm2 * np.abs(a)) / drv.psi_Vs
        k_new = float(((drv.voltage_headroom * u[moving] - r * i_rest[moving]) / per_k[moving]).min())
        if abs(k_new - k) < 1e-12:
            break
        k = k_new
    return k, f_peak, float(u.min())


def generate(plan: Plan, veh: Vehicle = Vehicle(), drv: Drive = Drive(), bus: Bus48 = Bus48(),
             net: Net12 = Net12(), thr: Throttle = Throttle()) -> Profile:
    if plan.duration_s <= 0.0 or plan.duration_s > 1e5:
        raise ProfileError(f"duration {plan.duration_s:g} s: must be in (0, 100000]")
    if not 0.0 <= plan.manoeuvre_prob <= 1.0:
        raise ProfileError(f"manoeuvre probability {plan.manoeuvre_prob:g}: must be in [0, 1]")
    cycle = wltc.trace()
    rng = np.random.default_rng(plan.seed)
    tr = _speed_track(rng, plan, cycle)
    v = np.concatenate(tr.v)
    n = len(v)
    t = np.arange(n) * DT
    a = np.gradient(v, DT)

    # road grade: two slow sinusoids, seeded phases
    p1, p2 = veh.grade_periods_s
    ph = rng.uniform(0.0, 2.0 * math.pi, 2)
    share = float(rng.uniform(0.3, 0.7))
    grade = veh.grade_max * (share * np.sin(2 * math.pi * t / p1 + ph[0]) +
                             (1.0 - share) * np.sin(2 * math.pi * t / p2 + ph[1]))
    force = road_force(veh, v, a, grade)
    hold = np.ones(n)
    for s0, s1, hill in tr.stops:
        if not hill:
            hold[s0:s1] = 0.0          # the brakes hold the car: no torque on the motor ...
    force = force * lowpass(hold, veh.brake_handover_s)   # ... once they have taken it over

    k_w, f_ref, u_low = speed_scale(drv, veh, bus, cycle)
    f_peak = max(f_ref, float(np.abs(force).max()))
    k_t = drv.torque_rated_Nm / f_peak
    w = k_w * v
    alpha = k_w * a
    load = k_t * force
    i_m = motor_current(drv, w, alpha, load)

    # engine: cranks at key-on; once warm it stops at long stops and cranks again before moving off
    cranks: list[tuple[float, bool]] = [(plan.crank_at_s, True)]
    engine_off = np.zeros(n, dtype=bool)
    engine_off[: int(plan.crank_at_s / DT)] = True
    for s0, s1, _ in tr.stops:
        if s0 * DT >= plan.start_stop_after_s and (s1 - s0) * DT >= plan.start_stop_min_stop_s and s1 < n - 1:
            off0, on = s0 + int(2.0 / DT), s1 - int(1.5 / DT)
            engine_off[off0:on] = True
            cranks.append((on * DT, False))

    # 12 V net
    warm = np.exp(-t / net.tau_warm_s)
    u12_run = net.u_charge_warm + (net.u_charge_cold - net.u_charge_warm) * warm
    u12_batt = net.u_battery_warm + (net.u_battery_cold - net.u_battery_warm) * warm - net.u_engine_off_drop
    u12 = np.where(engine_off, u12_batt, u12_run)
    dense = np.zeros(n, dtype=bool)
    for tc, cold in cranks:
        dip, dip_s, hold_v, hold_s = net.crank_cold if cold else net.crank_warm
        k0 = int(round(tc / DT))
        k1, k2 = k0 + max(1, int(round(dip_s / DT))), k0 + int(round((dip_s + hold_s) / DT))
        k3 = k2 + int(round(net.crank_recover_s / DT))
        u12[k0:k1] = dip
        u12[k1:k2] = hold_v
        if k3 > k2:
            u12[k2:k3] = hold_v + (u12_run[k2:k3] - hold_v) * np.linspace(0.0, 1.0, k3 - k2)
        engine_off[k0:k2] = True       # cranking: no driving
        dense[max(0, k0 - 2):min(n, k3 + 2)] = True

    # 48 V bus: open-circuit voltage recovering while charged, internal resistance falling as the
    # battery warms, sag when motoring, rise when regenerating, the charger's set point in cruise
    u_oc0 = float(rng.uniform(*bus.u_oc_cold))
    u_oc = bus.u_oc_charged + (u_oc0 - bus.u_oc_charged) * np.exp(-t / bus.tau_charge_s)
    r_int = bus.r_int_warm_ohm + (bus.r_int_cold_ohm - bus.r_int_warm_ohm) * np.exp(-t / bus.tau_battery_s)
    u_arm = drv.psi_Vs * w + drv.ra_cold_ohm * i_m
    i_bus = u_arm * i_m / u_oc
    cruise = ((v > bus.cruise_speed_m_s) & (np.abs(a) < bus.cruise_accel_m_s2)).astype(float)
    charging = lowpass(cruise, bus.tau_charge_flag_s)
    u48 = u_oc - r_int * i_bus
    u48 = u48 + charging * np.maximum(bus.u_charge - u48, 0.0)
    u48 = lowpass(np.clip(u48, bus.u_min, bus.u_max), bus.tau_bus_s)

    # throttle: idle (cold -> warm), the pedal map from the power demand, overrun closed;
    # hard accelerations floor the pedal (steps to wide open), hard braking snaps it shut
    idle = thr.idle_warm_deg + (thr.idle_cold_deg - thr.idle_warm_deg) * np.exp(-t / thr.tau_warm_s)
    speed = np.abs(v)
    drive_pos = (force * v > 0.0) & (speed > 0.05)
    f_full = np.minimum(veh.force_full_N, veh.power_full_W / np.maximum(speed, 1e-3))
    pedal = np.where(drive_pos, np.clip(np.abs(force) / f_full, 0.0, 1.0), 0.0)
    overrun = (force * v < 0.0) & (speed > thr.idle_speed_m_s)
    target = np.where(overrun, thr.closed_deg, idle + (thr.wot_deg - idle) * pedal**thr.gamma)
    a_tip = float(rng.uniform(*thr.a_tip_in))
    a_out = float(rng.uniform(*thr.a_tip_out))
    min_n = int(thr.tip_min_s / DT)
    tip_ins = [(s0, max(s1, min(n, s0 + min_n))) for s0, s1 in runs((a >= a_tip) & (v > 0.0) & ~engine_off)]
    # a tip-out: the foot leaves the pedal at once where the car goes from driving into an
    # overrun that brakes hard; the throttle stays closed until that braking ends
    hard = (a <= -a_out) & (v > thr.idle_speed_m_s)
    tip_outs = []
    for s0, s1 in runs(overrun):
        h = np.flatnonzero(hard[s0:s1])
        if len(h):
            tip_outs.append((s0, s0 + int(h[-1]) + 1))
    # some drivers lift off completely when a hard acceleration ends (a tip-out from wide open),
    # hold the pedal released for a moment, then press again (the lag towards the map)
    lifts = []
    for s0, s1 in tip_ins:
        if s1 < n and rng.random() < thr.lift_after_tip_in_prob:
            lifts.append((s1, min(n, s1 + int(float(rng.uniform(*thr.lift_s)) / DT))))
    override = np.full(n, np.nan)
    for s0, s1 in tip_outs + lifts:
        override[s0:s1] = thr.closed_deg
    for s0, s1 in tip_ins:
        override[s0:s1] = thr.wot_deg
    # the driver's foot: a first-order lag towards the target; a hard event sets the angle at once
    # (a step at its start) and the foot lets go smoothly at its end
    angle = np.empty(n)
    lag = 1.0 - math.exp(-DT / thr.tau_pedal_s)
    acc = float(target[0])
    for k in range(n):
        o = override[k]
        acc = o if o == o else acc + lag * (target[k] - acc)
        angle[k] = acc
    # a driver who brakes hard lifts off late: the foot stays where it was until the braking
    # begins, then leaves the pedal at once (the step to closed)
    n_react = int(round(thr.lift_late_s / DT))
    for s0, _ in tip_outs:
        k0 = s0 - n_react
        if k0 > 0 and np.isnan(override[k0:s0]).all():
            angle[k0:s0] = angle[k0]
    tip_outs = sorted(tip_outs + lifts)
    steps = [s0 - 1 for s0, _ in sorted(tip_ins + tip_outs)
             if s0 > 0 and abs(angle[s0] - angle[s0 - 1]) > 1.0]
    if thr.rate_deg_s > 0.0:
        # a rate-limited pedal (e.g. an ECU's filter): no steps, the angle ramps
        step = thr.rate_deg_s * DT
        for k in range(1, n):
            angle[k] = angle[k - 1] + min(step, max(-step, angle[k] - angle[k - 1]))
        steps = []

    # where the angle moves fast (a release after a tip-in, a rate-limited step) every sample is
    # written: a row every OUT_DT would turn the motion into a slower chord
    fast = np.abs(np.diff(angle, prepend=angle[0])) > thr.dense_deg_per_sample
    dense |= fast | np.roll(fast, -1)

    u_needed = drv.psi_Vs * w + drv.ra_hot_ohm * i_m
    prof = Profile(t, v, a, w, load, angle, u48, u12, i_m, u_needed, force, grade, steps, dense)
    prof.info = summary(prof, tr, plan, cycle, drv, k_w, k_t, f_peak, u_low, cranks, tip_ins, tip_outs,
                        a_tip, a_out, engine_off)
    check(prof, drv)
    return prof


# ---- checks and summary -----------------------------------------------------------------------------------

def check(p: Profile, drv: Drive) -> None:
    """Refuse a profile the plants could not follow or the simulator would refuse."""
    lim = {"speed_rad_s": (p.speed_rad_s, -400.0, 400.0), "angle_deg": (p.angle_deg, 0.0, 90.0),
           "load_Nm": (p.load_Nm, -10.0, 10.0), "dcm_supply_V": (p.dcm_supply_V, 0.0, 80.0),
           "thr_supply_V": (p.thr_supply_V, 0.0, 16.0)}
    for name, (x, lo, hi) in lim.items():
        if not np.isfinite(x).all() or x.min() < lo or x.max() > hi:
            raise ProfileError(f"{name} leaves [{lo:g}, {hi:g}]: {x.min():g} .. {x.max():g}")
    if np.abs(p.load_Nm).max() > drv.torque_rated_Nm + 1e-9:
        raise ProfileError(f"load {np.abs(p.load_Nm).max():.3f} N m beyond the rating {drv.torque_rated_Nm:.3f}")
    if np.abs(p.i_motor_A).max() > drv.i_max_A:
        raise ProfileError(f"motor current {np.abs(p.i_motor_A).max():.2f} A beyond the limit {drv.i_max_A:g} A")
    ratio = np.abs(p.u_needed_V) / p.dcm_supply_V
    if ratio.max() > drv.voltage_headroom + 1e-9:
        k = int(ratio.argmax())
        raise ProfileError(f"at {p.t_s[k]:.2f} s the motor needs {p.u_needed_V[k]:.1f} V of a {p.dcm_supply_V[k]:.1f} V "
                           f"supply (more than {drv.voltage_headroom:.0%})")


def _count_reversals(v: np.ndarray) -> tuple[int, int]:
    """Changes of travel direction (with or without a stop between) and those straight through zero."""
    sign = np.sign(np.where(np.abs(v) > 1e-6, v, 0.0))
    moving = np.flatnonzero(sign != 0)
    rev = through = 0
    for i, j in zip(moving[:-1], moving[1:]):
        if sign[i] != sign[j]:
            rev += 1
            through += int(j - i <= 2)
    return rev, through


def summary(p: Profile, tr: _Track, plan: Plan, cycle: wltc.Cycle, drv: Drive, k_w: float, k_t: float,
            f_peak: float, u_low: float, cranks: list, tip_ins: list, tip_outs: list, a_tip: float,
            a_out: float, engine_off: np.ndarray) -> dict:
    rev, through = _count_reversals(p.v_m_s)
    stand = np.abs(p.v_m_s) < 1e-6
    q = p.speed_rad_s * p.load_Nm
    rng_ = lambda x: [round(float(x.min()), 3), round(float(x.max()), 3)]  # noqa: E731
    return {
        "cycle": cycle.name, "source": cycle.source, "seed": plan.seed, "duration_s": round(float(p.t_s[-1]), 2),
        "plan": {"trips": list(plan.trips) or "all", "manoeuvre_prob": plan.manoeuvre_prob,
                 "trips_driven": [i for _, _, i in tr.trips]},
        "mapping": {"speed_rad_s_per_m_s": round(k_w, 4), "load_Nm_per_N": k_t, "force_peak_N": round(f_peak, 1),
                    "torque_rated_Nm": round(drv.torque_rated_Nm, 3), "bus_low_V": round(u_low, 2),
                    "top_speed_rad_s": round(k_w * float(cycle.v_m_s.max()) * drv.speed_scale_max, 2),
                    "tip_in_m_s2": round(a_tip, 3), "tip_out_m_s2": round(a_out, 3)},
        "ranges": {"speed_rad_s": rng_(p.speed_rad_s), "vehicle_kmh": rng_(p.v_m_s * 3.6),
                   "load_Nm": rng_(p.load_Nm), "angle_deg": rng_(p.angle_deg), "dcm_supply_V": rng_(p.dcm_supply_V),
                   "thr_supply_V": rng_(p.thr_supply_V), "motor_current_A": rng_(p.i_motor_A),
                   "voltage_share": round(float((np.abs(p.u_needed_V) / p.dcm_supply_V).max()), 3)},
        "counts": {"tip_ins": len(tip_ins), "tip_outs": len(tip_outs), "stops": len(tr.stops),
                   "hill_holds": sum(1 for s in tr.stops if s[2]), "manoeuvres": len(tr.manoeuvres),
                   "reversals": rev, "reversals_through_zero": through, "engine_starts": len(cranks),
                   "angle_steps": len(p.steps)},
        "seconds": {"standstill": round(float(stand.sum() * DT), 1),
                    "reverse": round(float((p.v_m_s < -1e-6).sum() * DT), 1),
                    "wide_open": round(float((p.angle_deg >= p.angle_deg.max() - 0.1).sum() * DT), 1),
                    "below_limp_home": round(float((p.angle_deg < 6.5).sum() * DT), 1),
                    "engine_off": round(float(engine_off.sum() * DT), 1)},
        "quadrants_s": {"forward_motoring": round(float(((p.speed_rad_s > 0.5) & (q > 0)).sum() * DT), 1),
                        "forward_braking": round(float(((p.speed_rad_s > 0.5) & (q < 0)).sum() * DT), 1),
                        "reverse_motoring": round(float(((p.speed_rad_s < -0.5) & (q > 0)).sum() * DT), 1),
                        "reverse_braking": round(float(((p.speed_rad_s < -0.5) & (q < 0)).sum() * DT), 1)},
        "events": {"tip_in_s": [round(float(p.t_s[s]), 2) for s, _ in tip_ins],
                   "tip_out_s": [round(float(p.t_s[s]), 2) for s, _ in tip_outs],
                   "manoeuvre_s": [[round(float(p.t_s[s]), 2), round(float(p.t_s[e - 1]), 2)] for s, e, _ in tr.manoeuvres],
                   "crank_s": [round(float(c), 2) for c, _ in cranks]},
    }


# ---- output -----------------------------------------------------------------------------------------------

COLUMNS = ("speed_rad_s", "load_Nm", "angle_deg", "dcm_supply_V", "thr_supply_V")
FORMATS = ("%.3f", "%.4f", "%.3f", "%.3f", "%.3f")


def rows(p: Profile) -> list[tuple[int, list[float]]]:
    """(time in ms, values) of every row: every OUT_DT, every DT where the supplies or the angle
    move fast, and each angle step as two rows STEP_S apart (the old value, then the new one)."""
    n = len(p.t_s)
    every = int(round(OUT_DT / DT))
    idx = set(range(0, n, every)) | set(np.flatnonzero(p.dense).tolist()) | {n - 1}
    idx |= set(p.steps) | {k + 1 for k in p.steps if k + 1 < n}
    cols = [getattr(p, c) for c in COLUMNS]
    out = {int(round(k * DT * 1000)): [float(c[k]) for c in cols] for k in sorted(idx)}
    for k in p.steps:
        if k + 1 >= n:
            continue
        t_ms = int(round(k * DT * 1000)) + int(round(STEP_S * 1000))
        vals = [float(c[k] + (c[k + 1] - c[k]) * STEP_S / DT) for c in cols]
        vals[COLUMNS.index("angle_deg")] = float(p.angle_deg[k + 1])
        out[t_ms] = vals
    return sorted(out.items())


def write_csv(p: Profile, path: Path, columns: tuple[str, ...] = COLUMNS) -> int:
    """Writes the profile (the named columns, in COLUMNS order); returns the number of rows."""
    path.parent.mkdir(parents=True, exist_ok=True)
    info = p.info
    pick = [COLUMNS.index(c) for c in COLUMNS if c in columns]
    lines = [f"# canfdi drive profile: {info['cycle']} from {info['source']}, seed {info['seed']}",
             f"# plan {json.dumps(info['plan'], separators=(',', ':'))}",
             f"# mapping {json.dumps(info['mapping'], separators=(',', ':'))}",
             "# written by tools/drive (canfdi-drive-profile); the mapping is in docs/driving.md",
             "t_s," + ",".join(COLUMNS[i] for i in pick)]
    body = rows(p)
    for t_ms, vals in body:
        lines.append(f"{t_ms / 1000:.3f}," + ",".join(FORMATS[i] % vals[i] for i in pick))
    path.write_text("\n".join(lines) + "\n")
    return len(body)


def _trips(text: str) -> tuple[int, ...]:
    try:
        return tuple(int(x) for x in text.split(",") if x.strip())
    except ValueError:
        raise argparse.ArgumentTypeError(f"'{text}' is not a comma list of trip numbers") from None


def _columns(text: str) -> tuple[str, ...]:
    names = tuple(x.strip() for x in text.split(",") if x.strip())
    bad = [c for c in names if c not in COLUMNS]
    if bad or not names:
        raise argparse.ArgumentTypeError(f"'{text}': a comma list of {', '.join(COLUMNS)}")
    return names


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="canfdi-drive-profile", description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("-o", "--output", type=Path, required=True, metavar="CSV", help="profile CSV to write")
    ap.add_argument("--duration", type=float, default=600.0, metavar="S", help="at least this long (default 600)")
    ap.add_argument("--seed", type=int, default=1, help="seed of the driver variation and placement (default 1)")
    ap.add_argument("--trips", type=_trips, default=(), metavar="LIST",
                    help="micro-trips of the cycle to drive, 1-based, comma list, repeated (default: all in order)")
    ap.add_argument("--manoeuvres", type=float, default=Plan.manoeuvre_prob, metavar="P",
                    help=f"chance of a parking manoeuvre at a stop (default {Plan.manoeuvre_prob})")
    ap.add_argument("--columns", type=_columns, default=COLUMNS, metavar="LIST",
                    help="write only these columns (default all: " + ",".join(COLUMNS) + "); the others stay "
                         "the scenario's own, e.g. the motor's side alone")
    ap.add_argument("--wot", type=float, default=Throttle.wot_deg, metavar="DEG",
                    help=f"the angle of a floored pedal (default {Throttle.wot_deg:g}: the valve's end stop)")
    ap.add_argument("--angle-rate", type=float, default=0.0, metavar="DEG_PER_S",
                    help="limit the angle's rate (default 0: none, tip-ins and tip-outs are steps); "
                         "to tell a step's effect from the angle's")
    ap.add_argument("--summary", type=Path, metavar="JSON", help="write the summary here (default: CSV with .json)")
    a = ap.parse_args(argv)
    plan = Plan(duration_s=a.duration, seed=a.seed, trips=a.trips, manoeuvre_prob=a.manoeuvres)
    if not (Throttle.idle_cold_deg < a.wot <= 90.0) or a.angle_rate < 0.0:
        print(f"canfdi-drive-profile: --wot {a.wot:g} must be in ({Throttle.idle_cold_deg:g}, 90] and "
              f"--angle-rate {a.angle_rate:g} not negative", file=sys.stderr)
        return 2
    try:
        p = generate(plan, thr=Throttle(wot_deg=a.wot, rate_deg_s=a.angle_rate))
    except (ProfileError, wltc.CycleError) as e:
        print(f"canfdi-drive-profile: {e}", file=sys.stderr)
        return 2
    nrows = write_csv(p, a.output, a.columns)
    js = a.summary if a.summary is not None else a.output.with_suffix(".json")
    js.write_text(json.dumps({"plan_options": asdict(plan), **p.info}, indent=1) + "\n")
    c = p.info["counts"]
    print(f"canfdi-drive-profile: {a.output}: {p.t_s[-1]:.1f} s, {nrows} rows; {c['tip_ins']} tip-ins, "
          f"{c['tip_outs']} tip-outs, {c['stops']} stops, {c['reversals']} reversals, {c['engine_starts']} engine "
          f"starts; summary {js}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
