/*
 * test_ctrl_thr.c — closed-loop tests of canfdi_ctrl_thr (fixed point)
 * against the host_sim throttle valve (double precision).
 *
 * Rig: the valve of docs/design.md (J 0.0021, B 0.0088, K 0.383, R 1.5 Ohm,
 * L 1.5 mH, spring 0.087 N m/rad, pretension 0.396 N m, Coulomb friction
 * 0.284 N m, limp-home 6.5 deg, stops at 0 and 90 deg), 13.5 V supply. The
 * controller gets the angle as the mean of the two potentiometers (as the
 * simulator's reference controller computes it; fault-free, this is what
 * the application's vote delivers) from the simulated sensors with noise as in
 * host_sim/scenarios/nominal.scn (TPS 3 mV each, i.e. 0.07 deg; supply
 * 10 mV; 12-bit ADC: 1.2 mV = 0.027 deg), converted to Q16.16 rad. Figures
 * are judged on the true angle. Closed-loop tests run three noise seeds.
 *
 * Physics behind the thresholds. Full stroke: at 13.5 V the valve
 * accelerates at up to ~1200 rad/s^2 and its speed is limited by the
 * back-EMF to ~(13.5 - R T_load / K) / K ~ 25 rad/s, so 70 deg (1.22 rad)
 * take ~60 ms plus ~10 ms to brake: a 10 -> 80 deg stroke settles within
 * +-1 deg in ~80 ms (measured), asserted < 100 ms (the requirement of
 * docs/requirements.md: "well under 100 ms"). Holding: the 0.07 deg sensor noise, halved by
 * averaging the two sensors, and the Coulomb friction band give a steady
 * error of a few hundredths of a degree; asserted |e| < 0.25 deg (peak)
 * and |mean| < 0.1 deg. Compensation: without the spring term the PID must
 * build up to (R/K) T_spring ~ 1.6..2 V by P and I after each move, without
 * the friction term (R/K) T_c = 1.1 V; both leave errors of tenths of a
 * degree for ~0.1..0.3 s — measured as the mean |e| 60..260 ms after each
 * step over a set of steps, asserted at least 30 % larger than with both
 * terms on (measured ~2x).
 */
#include <check.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "canfdi_sim.h" /* host_sim plant library (double precision) */
#include "canfdi_sim_refctl.h"
#include "ctrl/canfdi_ctrl_thr.h"
#include "unit_main.h"
#include "unit_q16.h"

#define SHOW(...) (void)(printf(__VA_ARGS__), fflush(stdout))

#define D2R 0.017453292519943295
#define TWO_PI 6.283185307179586
#define N_SEEDS 3
#define LH_DEG 6.5

static double dq(int32_t x)
{
  return (double)x / 65536.0;
}

typedef struct {
  canfdi_sim_cfg_t cfg;
  canfdi_sim_t sim;
  canfdi_sim_in_t pin;
  canfdi_ctrl_thr_cal_t cal;
  canfdi_ctrl_thr_t ctl;
  canfdi_ctrl_thr_in_t cin;
  canfdi_ctrl_thr_out_t cout;
  double amin; /* extremes of the true angle seen, deg */
  double amax;
} rig_t;

static void rig_init(rig_t *r, uint64_t seed, const canfdi_ctrl_thr_cal_t *cal, double start_deg)
{
  memset(r, 0, sizeof *r);
  canfdi_sim_default_cfg(&r->cfg);
  r->cfg.sigma[CANFDI_SIM_S_THR_TPS1] = 0.003;
  r->cfg.sigma[CANFDI_SIM_S_THR_TPS2] = 0.003;
  r->cfg.sigma[CANFDI_SIM_S_THR_I] = 0.01;
  r->cfg.sigma[CANFDI_SIM_S_THR_SUPPLY] = 0.01;
  r->cfg.seed = seed;
  ck_assert_int_eq(canfdi_sim_init(&r->sim, &r->cfg), 0);
  ck_assert_int_eq(canfdi_sim_thr_set_state(&r->sim.thr, start_deg, 0.0), 0);
  canfdi_sim_resample(&r->sim);
  if (cal != NULL) {
    r->cal = *cal;
  } else {
    canfdi_ctrl_thr_cal_default(&r->cal);
  }
  ck_assert_int_eq(canfdi_ctrl_thr_init(&r->ctl, &r->cal), CANFDI_OK);
  r->pin.dcm.enable = false;
  r->pin.thr.enable = true;
  r->cin.mode = CANFDI_CTRL_RUN;
  r->amin = 1e9;
  r->amax = -1e9;
}

static double angle_true(const rig_t *r)
{
  return canfdi_sim_thr_angle_deg(&r->sim.thr);
}

static void rig_step(rig_t *r, double ref_deg)
{
  const canfdi_sim_meas_t *m = &r->sim.meas;
  const double meas_deg = canfdi_sim_refctl_angle_deg(m->value[CANFDI_SIM_S_THR_TPS1],
                                                      m->value[CANFDI_SIM_S_THR_TPS2]);
  int32_t u;
  ck_assert(meas_deg >= 0.0); /* healthy sensors */
  r->cin.angle_ref_rad_q16 = q16(ref_deg * D2R);
  r->cin.angle_rad_q16 = q16(meas_deg * D2R);
  r->cin.supply_V_q16 = q16(m->value[CANFDI_SIM_S_THR_SUPPLY]);
  u = canfdi_ctrl_thr_step(&r->ctl, &r->cin, &r->cout);
  ck_assert_int_eq(u, r->cout.u_V_q16);
  r->pin.thr.u_cmd_V = dq(u);
  canfdi_sim_step(&r->sim, &r->pin);
  r->amin = fmin(r->amin, angle_true(r));
  r->amax = fmax(r->amax, angle_true(r));
}

typedef struct {
  double settle_s;  /* last entry into +-band, s after the step; < 0 never */
  double overshoot; /* beyond the target in the direction of the move, deg */
  double iae_mid;   /* mean |e| over 60..260 ms after the step, deg */
  double mean_end;  /* mean e over the last 200 ms, deg */
  double peak_end;  /* max |e| over the last 200 ms, deg */
  double u_sd_end;  /* standard deviation of u over the last 200 ms, V */
} step_fig_t;

static step_fig_t run_step(rig_t *r, double from_deg, double to_deg, double band, double dur_s)
{
  step_fig_t f = {-1.0, 0.0, 0.0, 0.0, 0.0, 0.0};
  const long n = lround(dur_s * 1000.0);
  const long n_end = 200;
  const double dir = (to_deg >= from_deg) ? 1.0 : -1.0;
  double s1 = 0.0;
  double su1 = 0.0;
  double su2 = 0.0;
  int n_mid = 0;
  for (long k = 0; k < n; k++) {
    double e;
    rig_step(r, to_deg);
    e = angle_true(r) - to_deg;
    f.overshoot = fmax(f.overshoot, dir * e);
    if (fabs(e) > band) {
      f.settle_s = -1.0;
    } else if (f.settle_s < 0.0) {
      f.settle_s = (double)(k + 1) * 1e-3;
    }
    if ((k >= 60) && (k < 260)) {
      f.iae_mid += fabs(e);
      n_mid++;
    }
    if (k >= n - n_end) {
      const double u = dq(r->cout.u_V_q16);
      s1 += e;
      su1 += u;
      su2 += u * u;
      f.peak_end = fmax(f.peak_end, fabs(e));
    }
  }
  f.iae_mid /= (n_mid > 0) ? (double)n_mid : 1.0;
  f.mean_end = s1 / (double)n_end;
  f.u_sd_end = sqrt(fmax(0.0, su2 / (double)n_end - (su1 / (double)n_end) * (su1 / (double)n_end)));
  return f;
}

/* ---- configuration and arithmetic ------------------------------------- */

static void bad_cal(int i, canfdi_ctrl_thr_cal_t *c)
{
  switch (i) {
  case 0: c->r_ohm_q16 = 0; break;
  case 1: c->k_Nm_A_q16 = -1; break;
  case 2: c->u_max_V_q16 = 0; break;
  case 3: c->pretension_band_rad_q16 = 0; break;
  case 4: c->spring_Nm_rad_q16 = -1; break;
  case 5: c->pretension_Nm_q16 = -1; break;
  case 6: c->friction_Nm_q16 = -1; break;
  case 7: c->friction_deadband_rad_q16 = -1; break;
  case 8: c->rate_max_rad_s_q16 = -1; break;
  case 9: c->angle_min_rad_q16 = c->angle_max_rad_q16 + 1; break;
  case 10: c->k_Nm_A_q16 = 1; break;            /* R/K = 98304: not representable */
  case 11: /* P/band = 65536 N m/rad: not representable */
    c->pretension_Nm_q16 = 65536;
    c->pretension_band_rad_q16 = 1;
    break;
  case 12: c->kd_V_s_rad_q16 = -1; break;       /* rejected by canfdi_pi_init */
  case 13: c->b_Nms_q16 = -1; break;
  default: break;
  }
}
#define N_BAD_CAL 14

START_TEST(test_cal_rejected)
{
  canfdi_ctrl_thr_cal_t cal;
  canfdi_ctrl_thr_t c;
  canfdi_ctrl_thr_cal_default(&cal);
  ck_assert_int_eq(canfdi_ctrl_thr_init(&c, &cal), CANFDI_OK);
  bad_cal(_i, &cal);
  ck_assert_int_eq(canfdi_ctrl_thr_init(&c, &cal), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_ctrl_thr_init(NULL, &cal), -CANFDI_EINVAL);
}
END_TEST

/*
 * The feed-forward against the formula in double with the nominal
 * parameters: (R/K)(k_s (r - LH) + P sat((r - LH)/band) + T_c dz(e)).
 * Tolerance 1 mV: the Q16.16 parameters are within 2^-17 of the decimal
 * values (relative 1e-4 for the smallest, k_s), the result within ~2 V.
 */
typedef struct {
  double r_deg;
  double e_deg;
} ff_case_t;
static const ff_case_t ff_cases[] = {
    {6.5, 0.0},  {6.55, 0.0}, {6.45, 0.0}, {6.6, 0.0},   {6.4, 0.0},  {80.0, 0.0},
    {80.0, 1.0}, {80.0, -1.0}, {80.0, 0.19}, {80.0, 0.21}, {0.5, -5.0}, {45.0, 0.0},
};

START_TEST(test_feedforward)
{
  canfdi_ctrl_thr_cal_t cal;
  canfdi_ctrl_thr_t c;
  const ff_case_t *fc = &ff_cases[_i];
  const double d = (fc->r_deg - LH_DEG) * D2R;
  const double band = 0.1 * D2R;
  double t = 0.087 * d + 0.396 * fmax(-1.0, fmin(1.0, d / band));
  double expect;
  int32_t got;
  if (fabs(fc->e_deg) > 0.2) {
    t += (fc->e_deg > 0.0) ? 0.284 : -0.284;
  }
  expect = 1.5 / 0.383 * t;
  canfdi_ctrl_thr_cal_default(&cal);
  ck_assert_int_eq(canfdi_ctrl_thr_init(&c, &cal), CANFDI_OK);
  got = canfdi_ctrl_thr_ff_q16(&c, q16(fc->r_deg * D2R), q16(fc->e_deg * D2R));
  ck_assert_msg(fabs(dq(got) - expect) < 1e-3, "r %.2f e %.2f: %.5f vs %.5f", fc->r_deg,
                fc->e_deg, dq(got), expect);
  /* Switched off, the terms vanish. */
  cal.spring_comp = false;
  cal.friction_comp = false;
  ck_assert_int_eq(canfdi_ctrl_thr_init(&c, &cal), CANFDI_OK);
  ck_assert_int_eq(canfdi_ctrl_thr_ff_q16(&c, q16(fc->r_deg * D2R), q16(fc->e_deg * D2R)), 0);
}
END_TEST

/* ---- closed loop ------------------------------------------------------- */

START_TEST(test_full_stroke)
{
  rig_t r;
  step_fig_t up;
  step_fig_t down;
  rig_init(&r, (uint64_t)_i + 1U, NULL, 10.0);
  (void)run_step(&r, 10.0, 10.0, 1.0, 0.3);
  up = run_step(&r, 10.0, 80.0, 1.0, 0.5);
  down = run_step(&r, 80.0, 10.0, 1.0, 0.5);
  SHOW("thr stroke (seed %d): 10->80 deg settles +-1 deg in %.0f ms (overshoot %.2f deg), "
       "80->10 in %.0f ms (%.2f deg); angle range %.2f..%.2f deg, stop hits %u\n",
       _i + 1, up.settle_s * 1e3, up.overshoot, down.settle_s * 1e3, down.overshoot, r.amin,
       r.amax, r.sim.thr.diag.stop_hits);
  ck_assert(up.settle_s > 0.0);
  ck_assert(up.settle_s < 0.100);
  ck_assert(down.settle_s > 0.0);
  ck_assert(down.settle_s < 0.100);
  ck_assert(up.overshoot < 1.0);
  ck_assert(down.overshoot < 1.0);
  /* Never on a stop. */
  ck_assert_uint_eq(r.sim.thr.diag.stop_hits, 0U);
  ck_assert(r.amin > 1.0);
  ck_assert(r.amax < 89.0);
}
END_TEST

/* Holding across the range, including around limp-home (where the spring
 * torque changes sign) and near both ends of the setpoint range. */
static const double hold_deg[] = {2.0, 5.0, 6.0, 6.5, 7.0, 8.0, 15.0, 30.0, 45.0, 60.0, 75.0, 87.0};
#define N_HOLD ((int)(sizeof hold_deg / sizeof hold_deg[0]))

START_TEST(test_hold_positions)
{
  rig_t r;
  double prev = 20.0;
  double worst_peak = 0.0;
  double worst_mean = 0.0;
  double worst_usd = 0.0;
  rig_init(&r, (uint64_t)_i + 1U, NULL, prev);
  for (int h = 0; h < N_HOLD; h++) {
    const double tgt = hold_deg[(h * 5 + _i) % N_HOLD]; /* a different order per seed */
    step_fig_t f = run_step(&r, prev, tgt, 1.0, 0.6);
    ck_assert_msg(fabs(f.mean_end) < 0.1, "hold %.1f: mean error %.3f deg", tgt, f.mean_end);
    ck_assert_msg(f.peak_end < 0.25, "hold %.1f: peak error %.3f deg", tgt, f.peak_end);
    worst_peak = fmax(worst_peak, f.peak_end);
    worst_mean = fmax(worst_mean, fabs(f.mean_end));
    worst_usd = fmax(worst_usd, f.u_sd_end);
    prev = tgt;
  }
  SHOW("thr hold %d positions 2..87 deg (seed %d): worst |mean e| %.3f deg, worst peak |e| "
       "%.3f deg, worst command noise sd %.2f V; stop hits %u\n",
       N_HOLD, _i + 1, worst_mean, worst_peak, worst_usd, r.sim.thr.diag.stop_hits);
  /* Command activity from sensor noise through P and the filtered D:
   * ~0.6 V expected (see the header of canfdi_ctrl_thr.h for the gains). */
  ck_assert(worst_usd < 1.5);
  ck_assert_uint_eq(r.sim.thr.diag.stop_hits, 0U);
}
END_TEST

/*
 * Compensation on vs off, same seeds, same setpoints.
 * Spring: a sequence of steps across the range and across limp-home; metric
 * the mean |e| over 60..260 ms after each step, averaged over the steps.
 * Without the spring term the PID must first build up (R/K) T_spring
 * (1.6..2 V; the pretension flips sign across limp-home) from P and I
 * after every move.
 * Friction: tracking a 1 Hz, +-10 deg sinusoid around 30 deg; metric the
 * mean |e| over 1.8 s. While the valve moves, Coulomb friction opposes it
 * with a torque that flips sign with the direction, which the integrator
 * cannot follow; without the friction term P must supply (R/K) T_c = 1.1 V,
 * i.e. an extra error of up to 1.1 V / kp = 0.18 deg while it moves.
 */
static const double comp_seq[] = {10.0, 80.0, 10.0, 45.0, 30.0, 7.0, 6.0, 20.0, 60.0, 59.0};
#define N_COMP ((int)(sizeof comp_seq / sizeof comp_seq[0]))

static canfdi_ctrl_thr_cal_t comp_cal(bool spring, bool fric)
{
  canfdi_ctrl_thr_cal_t cal;
  canfdi_ctrl_thr_cal_default(&cal);
  cal.spring_comp = spring;
  cal.friction_comp = fric;
  return cal;
}

static double comp_steps(bool spring, bool fric, uint64_t seed)
{
  rig_t r;
  const canfdi_ctrl_thr_cal_t cal = comp_cal(spring, fric);
  double sum = 0.0;
  rig_init(&r, seed, &cal, comp_seq[0]);
  (void)run_step(&r, comp_seq[0], comp_seq[0], 1.0, 0.3);
  for (int s = 1; s < N_COMP; s++) {
    step_fig_t f = run_step(&r, comp_seq[s - 1], comp_seq[s], 1.0, 0.4);
    sum += f.iae_mid;
  }
  ck_assert_uint_eq(r.sim.thr.diag.stop_hits, 0U);
  return sum / (double)(N_COMP - 1);
}

static double comp_sine(bool spring, bool fric, uint64_t seed)
{
  rig_t r;
  const canfdi_ctrl_thr_cal_t cal = comp_cal(spring, fric);
  double sum = 0.0;
  int n = 0;
  rig_init(&r, seed, &cal, 30.0);
  (void)run_step(&r, 30.0, 30.0, 1.0, 0.3);
  for (int k = 0; k < 2000; k++) {
    const double ref = 30.0 + 10.0 * sin(TWO_PI * (double)k * 1e-3);
    const double ref_next = 30.0 + 10.0 * sin(TWO_PI * (double)(k + 1) * 1e-3);
    rig_step(&r, ref);
    if (k >= 200) {
      sum += fabs(angle_true(&r) - ref_next);
      n++;
    }
  }
  return sum / (double)n;
}

START_TEST(test_spring_compensation)
{
  const uint64_t seed = (uint64_t)_i + 1U;
  const double both = comp_steps(true, true, seed);
  const double off = comp_steps(false, true, seed);
  SHOW("thr steps, mean |e| 60..260 ms after each (seed %d): %.3f deg with spring "
       "compensation, %.3f without\n",
       _i + 1, both, off);
  ck_assert(off > 1.25 * both);
}
END_TEST

START_TEST(test_friction_compensation)
{
  const uint64_t seed = (uint64_t)_i + 1U;
  const double both = comp_sine(true, true, seed);
  const double off = comp_sine(true, false, seed);
  SHOW("thr 1 Hz +-10 deg tracking, mean |e| (seed %d): %.3f deg with friction "
       "compensation, %.3f without\n",
       _i + 1, both, off);
  /* P alone would need an extra 0.18 deg while moving; the integrator
   * takes part of it over within each half period, so the measured mean
   * increase is ~0.05 deg (19 %): asserted as at least 0.02 deg and 10 %. */
  ck_assert(off > both + 0.02);
  ck_assert(off > 1.1 * both);
}
END_TEST

/* Setpoints beyond the range are clamped inside the stops. */
START_TEST(test_setpoint_clamp)
{
  rig_t r;
  rig_init(&r, 1U, NULL, 10.0);
  (void)run_step(&r, 10.0, 95.0, 1.0, 0.4);
  ck_assert(fabs(angle_true(&r) - 88.0) < 0.5);
  ck_assert_int_eq(r.cout.angle_ref_rad_q16, r.cal.angle_max_rad_q16);
  (void)run_step(&r, 88.0, -5.0, 1.0, 0.4);
  ck_assert(fabs(angle_true(&r) - 0.5) < 0.5);
  ck_assert_uint_eq(r.sim.thr.diag.stop_hits, 0U);
  ck_assert_uint_ge(canfdi_ctrl_thr_diag(&r.ctl)->ref_clamped, 800U);
}
END_TEST

/*
 * With a setpoint rate limit the valve follows the ramp. Without the
 * velocity feed-forward the P term must overcome the back-EMF K w*, the
 * viscous torque and, mostly, the derivative term -kd w (on the measured
 * angle), i.e. e ~ (K + (R/K) B + kd) w* / kp ~ 4.9 deg at 10 rad/s; with
 * it, only friction and model error remain.
 */
START_TEST(test_rate_limit_velocity_ff)
{
  double lag[2];
  for (int vff = 0; vff < 2; vff++) {
    rig_t r;
    canfdi_ctrl_thr_cal_t cal;
    canfdi_ctrl_thr_cal_default(&cal);
    cal.rate_max_rad_s_q16 = q16(10.0); /* 573 deg/s: 10 -> 80 in 122 ms */
    cal.velocity_ff = (vff != 0);
    rig_init(&r, 1U, &cal, 10.0);
    (void)run_step(&r, 10.0, 10.0, 1.0, 0.2);
    lag[vff] = 0.0;
    for (int k = 0; k < 100; k++) {
      rig_step(&r, 80.0);
      if (k >= 20) {
        lag[vff] = fmax(lag[vff], fabs(dq(r.cout.angle_ref_rad_q16) / D2R - angle_true(&r)));
      }
    }
    (void)run_step(&r, 10.0, 80.0, 1.0, 0.3);
    ck_assert(fabs(angle_true(&r) - 80.0) < 0.25);
    ck_assert_uint_gt(canfdi_ctrl_thr_diag(&r.ctl)->rate_limited, 100U);
  }
  SHOW("thr ramp 573 deg/s: max lag %.2f deg without, %.2f deg with velocity feed-forward\n",
       lag[0], lag[1]);
  ck_assert(lag[0] > 3.0);
  ck_assert(lag[0] < 7.0);
  ck_assert(lag[1] < 1.0);
}
END_TEST

/* ---- modes ---------------------------------------------------------------- */

START_TEST(test_off_limp_home_and_back)
{
  rig_t r;
  step_fig_t f;
  rig_init(&r, 2U, NULL, 30.0);
  (void)run_step(&r, 30.0, 30.0, 1.0, 0.3);
  r.cin.mode = CANFDI_CTRL_OFF;
  r.pin.thr.enable = false;
  for (int k = 0; k < 300; k++) {
    rig_step(&r, 30.0);
    ck_assert_int_eq(r.cout.u_V_q16, 0);
  }
  SHOW("thr off: the spring took the valve to %.2f deg\n", angle_true(&r));
  ck_assert(fabs(angle_true(&r) - LH_DEG) < 0.5);
  ck_assert_uint_eq(canfdi_ctrl_thr_diag(&r.ctl)->off_steps, 300U);
  r.cin.mode = CANFDI_CTRL_RUN;
  r.pin.thr.enable = true;
  f = run_step(&r, LH_DEG, 30.0, 1.0, 0.4);
  ck_assert(f.settle_s > 0.0);
  ck_assert(f.settle_s < 0.100);
  ck_assert(f.overshoot < 1.0);
}
END_TEST

/* Bumpless transfer, checked without sensor noise (only the ADC): the
 * property is the algorithm's; with noise the command moves by ~1 V from
 * step to step anyway. */
START_TEST(test_freeze_track)
{
  rig_t r;
  int32_t held;
  rig_init(&r, 3U, NULL, 40.0);
  for (unsigned i = 0U; i < CANFDI_SIM_N_SENSORS; i++) {
    r.sim.sensor[i].cfg.sigma = 0.0;
  }
  (void)run_step(&r, 40.0, 40.0, 1.0, 0.4);
  held = r.cout.u_V_q16;
  r.cin.mode = CANFDI_CTRL_FREEZE;
  for (int k = 0; k < 5; k++) {
    rig_step(&r, 40.0);
    ck_assert_int_eq(r.cout.u_V_q16, held);
  }
  r.cin.mode = CANFDI_CTRL_TRACK;
  r.cin.u_track_V_q16 = q16(-3.0);
  rig_step(&r, 40.0);
  ck_assert_int_eq(r.cout.u_V_q16, q16(-3.0));
  r.cin.mode = CANFDI_CTRL_RUN;
  rig_step(&r, 40.0);
  SHOW("thr held %.2f V, tracked -3 V, first output after resume %.2f V\n", dq(held),
       dq(r.cout.u_V_q16));
  /* Continues from the tracked -3 V (the valve barely moved in 1 ms): the
   * change is one step of P, I and D on a near-constant angle. Without
   * tracking it would jump back to the ~+1.8 V holding voltage. */
  ck_assert(fabs(dq(r.cout.u_V_q16) + 3.0) < 0.5);
  ck_assert_uint_eq(canfdi_ctrl_thr_diag(&r.ctl)->held_steps, 6U);
  ck_assert_uint_eq(canfdi_ctrl_thr_pi_diag(&r.ctl)->tracks, 6U);
  (void)run_step(&r, 40.0, 40.0, 1.0, 0.3);
  ck_assert(fabs(angle_true(&r) - 40.0) < 0.25);
}
END_TEST

START_TEST(test_excitation_and_supply)
{
  rig_t r;
  rig_init(&r, 1U, NULL, 20.0);
  (void)run_step(&r, 20.0, 20.0, 1.0, 0.2);
  r.cin.excite_rad_q16 = q16(1.0 * D2R);
  rig_step(&r, 20.0);
  ck_assert_int_eq(r.cout.angle_ref_rad_q16, q16(20.0 * D2R) + q16(1.0 * D2R));
  /* The supply is the limit: with 6 V measured the output stays within. */
  r.cin.excite_rad_q16 = 0;
  for (int k = 0; k < 100; k++) {
    const canfdi_sim_meas_t *m = &r.sim.meas;
    r.cin.angle_ref_rad_q16 = q16(80.0 * D2R);
    r.cin.angle_rad_q16 = q16(canfdi_sim_refctl_angle_deg(m->value[CANFDI_SIM_S_THR_TPS1],
                                                          m->value[CANFDI_SIM_S_THR_TPS2]) *
                              D2R);
    r.cin.supply_V_q16 = q16(6.0);
    (void)canfdi_ctrl_thr_step(&r.ctl, &r.cin, &r.cout);
    ck_assert(abs(r.cout.u_V_q16) <= q16(6.0));
    ck_assert_int_eq(r.cout.u_limit_V_q16, q16(6.0));
    r.pin.thr.u_cmd_V = dq(r.cout.u_V_q16);
    canfdi_sim_step(&r.sim, &r.pin);
  }
  ck_assert_uint_gt(canfdi_ctrl_thr_diag(&r.ctl)->u_limited, 0U);
}
END_TEST

static Suite *make_suite(void)
{
  Suite *s = suite_create("ctrl_thr");
  TCase *tc;

  tc = tcase_create("config");
  tcase_add_loop_test(tc, test_cal_rejected, 0, N_BAD_CAL);
  tcase_add_loop_test(tc, test_feedforward, 0, (int)(sizeof ff_cases / sizeof ff_cases[0]));
  suite_add_tcase(s, tc);

  tc = tcase_create("closed_loop");
  tcase_set_timeout(tc, 120);
  tcase_add_loop_test(tc, test_full_stroke, 0, N_SEEDS);
  tcase_add_loop_test(tc, test_hold_positions, 0, N_SEEDS);
  tcase_add_test(tc, test_setpoint_clamp);
  tcase_add_test(tc, test_rate_limit_velocity_ff);
  suite_add_tcase(s, tc);

  tc = tcase_create("compensation");
  tcase_set_timeout(tc, 120);
  tcase_add_loop_test(tc, test_spring_compensation, 0, N_SEEDS);
  tcase_add_loop_test(tc, test_friction_compensation, 0, N_SEEDS);
  suite_add_tcase(s, tc);

  tc = tcase_create("modes");
  tcase_set_timeout(tc, 120);
  tcase_add_test(tc, test_off_limp_home_and_back);
  tcase_add_test(tc, test_freeze_track);
  tcase_add_test(tc, test_excitation_and_supply);
  suite_add_tcase(s, tc);
  return s;
}

CANFDI_UNIT_MAIN(make_suite)
