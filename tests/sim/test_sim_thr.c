/*
 * test_sim_thr.c — throttle valve plant (host_sim/canfdi_sim_thr.h):
 * limp-home, stroke under the stand-in controller, end stops, stiction,
 * potentiometers, electrical time constant.
 */
#include <check.h>
#include <math.h>
#include <stdio.h>

#include "canfdi_sim.h"
#include "canfdi_sim_refctl.h"
#include "canfdi_sim_thr.h"
#include "core/canfdi_common.h"
#include "unit_main.h"

#define RAD_PER_DEG 0.017453292519943295

static canfdi_sim_thr_in_t cmd(double u_V, bool enable)
{
  canfdi_sim_thr_in_t in;
  in.u_cmd_V = u_V;
  in.enable = enable;
  return in;
}

/* ---- limp-home ---------------------------------------------------------- */

static const double lh_start_deg[] = {0.0, 2.0, 6.5, 7.0, 20.0, 45.0, 89.0, 90.0};

/* Rest band around theta_LH: where |T_spring| <= T_c, i.e. for the tanh
 * pretension |d| <= delta atanh(T_c / P) (k_s d is negligible there). */
static double rest_band_deg(const canfdi_sim_thr_params_t *p)
{
  return p->lh_width_deg * atanh(p->friction_Nm / p->pretension_Nm);
}

START_TEST(unpowered_valve_settles_at_limp_home)
{
  canfdi_sim_thr_params_t p;
  canfdi_sim_thr_t v;
  canfdi_sim_thr_fx_t fx;
  canfdi_sim_thr_in_t in = cmd(0.0, false);
  unsigned k;
  double band;

  canfdi_sim_thr_default_params(&p);
  band = rest_band_deg(&p);
  ck_assert_int_eq(canfdi_sim_thr_init(&v, &p), CANFDI_OK);
  ck_assert_int_eq(canfdi_sim_thr_set_state(&v, lh_start_deg[_i], 0.0), CANFDI_OK);
  canfdi_sim_thr_fx_none(&fx);
  for (k = 0U; k < 1000U; k++) {
    canfdi_sim_thr_step(&v, &in, &fx);
    ck_assert_msg((v.theta_rad >= 0.0) && (v.theta_rad <= (p.max_deg * RAD_PER_DEG)),
                  "left the stops: %g deg", canfdi_sim_thr_angle_deg(&v));
  }
  printf("thr limp-home from %5.1f deg: %.4f deg after 1 s (theta_LH %.1f, rest band +-%.3f)\n",
         lh_start_deg[_i], canfdi_sim_thr_angle_deg(&v), p.limp_home_deg, band);
  ck_assert_msg(fabs(canfdi_sim_thr_angle_deg(&v) - p.limp_home_deg) <= band + 1e-9,
                "rests at %.4f deg", canfdi_sim_thr_angle_deg(&v));
  ck_assert_msg(fabs(v.w_rad_s) < 1e-300, "still moving: %g rad/s", v.w_rad_s);
  ck_assert_msg(fabs(v.i_A) < 1e-300, "current while off: %g", v.i_A);
}
END_TEST

START_TEST(shorted_motor_also_returns_home)
{
  /* Bridge enabled at 0 V: the motor brakes on its EMF but the spring still
   * wins; slower than high impedance. */
  canfdi_sim_thr_params_t p;
  canfdi_sim_thr_t v;
  canfdi_sim_thr_fx_t fx;
  canfdi_sim_thr_in_t in = cmd(0.0, true);
  unsigned k;
  canfdi_sim_thr_default_params(&p);
  ck_assert_int_eq(canfdi_sim_thr_init(&v, &p), CANFDI_OK);
  ck_assert_int_eq(canfdi_sim_thr_set_state(&v, 60.0, 0.0), CANFDI_OK);
  canfdi_sim_thr_fx_none(&fx);
  for (k = 0U; k < 3000U; k++) {
    canfdi_sim_thr_step(&v, &in, &fx);
  }
  ck_assert_msg(fabs(canfdi_sim_thr_angle_deg(&v) - p.limp_home_deg) <= rest_band_deg(&p) + 1e-9,
                "rests at %.4f deg", canfdi_sim_thr_angle_deg(&v));
}
END_TEST

/* ---- stroke under the stand-in controller -------------------------------- */

typedef struct {
  double from_deg;
  double to_deg;
} stroke_t;

static const stroke_t strokes[] = {{10.0, 80.0}, {80.0, 10.0}, {6.5, 45.0}};

START_TEST(stroke_under_reference_controller)
{
  const stroke_t *s = &strokes[_i];
  canfdi_sim_cfg_t cfg;
  static canfdi_sim_t sim;
  canfdi_sim_refctl_cfg_t ccfg;
  canfdi_sim_refctl_t ctl;
  canfdi_sim_in_t in;
  unsigned k;
  int settled_ms = -1;
  int t90_ms = -1;
  double peak = 0.0;
  const double max_deg = 90.0;

  canfdi_sim_default_cfg(&cfg);
  /* Realistic sensor noise: 3 mV on each potentiometer (~0.07 deg). */
  cfg.sigma[CANFDI_SIM_S_THR_TPS1] = 0.003;
  cfg.sigma[CANFDI_SIM_S_THR_TPS2] = 0.003;
  ck_assert_int_eq(canfdi_sim_init(&sim, &cfg), CANFDI_OK);
  canfdi_sim_refctl_default(&ccfg, &cfg);
  canfdi_sim_refctl_init(&ctl, &ccfg);
  in.dcm.load_Nm = 0.0;
  for (k = 0U; k < 1000U; k++) { /* settle at the start angle */
    canfdi_sim_refctl_step(&ctl, 0.0, s->from_deg, &sim.meas, &in);
    canfdi_sim_step(&sim, &in);
  }
  ck_assert_msg(fabs(canfdi_sim_thr_angle_deg(&sim.thr) - s->from_deg) < 0.5, "start %g",
                canfdi_sim_thr_angle_deg(&sim.thr));
  for (k = 1U; k <= 400U; k++) {
    double a;
    canfdi_sim_refctl_step(&ctl, 0.0, s->to_deg, &sim.meas, &in);
    canfdi_sim_step(&sim, &in);
    a = canfdi_sim_thr_angle_deg(&sim.thr);
    ck_assert_msg((a >= 0.0) && (a <= max_deg), "outside the end stops: %g", a);
    if ((s->to_deg > s->from_deg) ? (a - s->to_deg > peak) : (s->to_deg - a > peak)) {
      peak = fabs(a - s->to_deg);
    }
    if ((t90_ms < 0) && (fabs(a - s->from_deg) >= 0.9 * fabs(s->to_deg - s->from_deg))) {
      t90_ms = (int)k;
    }
    if (fabs(a - s->to_deg) <= 1.0) {
      if (settled_ms < 0) {
        settled_ms = (int)k;
      }
    } else {
      settled_ms = -1; /* left the band again: not settled yet */
    }
  }
  printf("thr stroke %.1f -> %.1f deg: 90 %% of the stroke after %d ms, within +-1 deg from "
         "%d ms on, overshoot %.2f deg\n",
         s->from_deg, s->to_deg, t90_ms, settled_ms, peak);
  /* Acceptance: full stroke in under 100 ms (settled within 1 deg). */
  ck_assert_msg((settled_ms > 0) && (settled_ms < 100), "settled after %d ms", settled_ms);
}
END_TEST

/* ---- end stops ------------------------------------------------------------ */

START_TEST(end_stops_are_hard)
{
  canfdi_sim_thr_params_t p;
  canfdi_sim_thr_t v;
  canfdi_sim_thr_fx_t fx;
  canfdi_sim_thr_in_t in = cmd(13.5, true);
  unsigned k;
  const double max_rad = 90.0 * RAD_PER_DEG;

  canfdi_sim_thr_default_params(&p);
  ck_assert_int_eq(canfdi_sim_thr_init(&v, &p), CANFDI_OK);
  canfdi_sim_thr_fx_none(&fx);
  for (k = 0U; k < 300U; k++) {
    canfdi_sim_thr_step(&v, &in, &fx);
    ck_assert_msg(v.theta_rad <= max_rad, "beyond 90 deg: %.9g", canfdi_sim_thr_angle_deg(&v));
  }
  ck_assert_msg(fabs(v.theta_rad - max_rad) < 1e-15, "not on the stop: %.9g",
                canfdi_sim_thr_angle_deg(&v));
  ck_assert_msg(fabs(v.w_rad_s) < 1e-300, "moving on the stop");
  ck_assert_uint_ge(v.diag.stop_hits, 1U);
  in.u_cmd_V = -13.5;
  for (k = 0U; k < 300U; k++) {
    canfdi_sim_thr_step(&v, &in, &fx);
    ck_assert_msg(v.theta_rad >= 0.0, "below 0 deg: %.9g", canfdi_sim_thr_angle_deg(&v));
  }
  ck_assert_msg(fabs(v.theta_rad) < 1e-300, "not on the closed stop: %.9g",
                canfdi_sim_thr_angle_deg(&v));
  /* Pressed into the stop the motor sees a locked rotor: I = U/R. */
  ck_assert_msg(fabs(v.i_A - (-13.5 / p.r_ohm)) < 1e-9, "stall current %g", v.i_A);
}
END_TEST

/* ---- stiction ------------------------------------------------------------- */

START_TEST(stiction_holds_inside_friction_band)
{
  canfdi_sim_thr_params_t p;
  canfdi_sim_thr_t v;
  canfdi_sim_thr_fx_t fx;
  double u_hold;
  double theta0;
  unsigned k;
  int sgn;

  canfdi_sim_thr_default_params(&p);
  ck_assert_int_eq(canfdi_sim_thr_init(&v, &p), CANFDI_OK);
  canfdi_sim_thr_fx_none(&fx);
  for (sgn = -1; sgn <= 1; sgn += 2) {
    canfdi_sim_thr_in_t in;
    ck_assert_int_eq(canfdi_sim_thr_set_state(&v, 40.0, 0.0), CANFDI_OK);
    theta0 = v.theta_rad;
    /* Torque balance with the spring plus/minus 80 % of the friction. */
    u_hold = (p.r_ohm / p.k_Nm_A) *
             (canfdi_sim_thr_spring_Nm(&v, theta0, 1.0) + (0.8 * (double)sgn * p.friction_Nm));
    in = cmd(u_hold, true);
    /* Let the current settle first (L/R = 1 ms) with the valve held. */
    fx.jammed = true;
    for (k = 0U; k < 20U; k++) {
      canfdi_sim_thr_step(&v, &in, &fx);
    }
    fx.jammed = false;
    for (k = 0U; k < 500U; k++) {
      canfdi_sim_thr_step(&v, &in, &fx);
    }
    ck_assert_msg(fabs(v.theta_rad - theta0) < 1e-300, "crept by %g deg",
                  (v.theta_rad - theta0) / RAD_PER_DEG);
    /* 120 % of the friction breaks away. */
    in.u_cmd_V = (p.r_ohm / p.k_Nm_A) *
                 (canfdi_sim_thr_spring_Nm(&v, theta0, 1.0) + (1.2 * (double)sgn * p.friction_Nm));
    for (k = 0U; k < 50U; k++) {
      canfdi_sim_thr_step(&v, &in, &fx);
    }
    ck_assert_msg(((v.theta_rad - theta0) * (double)sgn) > 1e-4, "did not break away (%d)", sgn);
  }
}
END_TEST

/* ---- electrical --------------------------------------------------------- */

START_TEST(locked_current_time_constant)
{
  /* Jammed valve: a pure R-L circuit, tau = L/R = 1 ms, sampled at 1 ms. */
  canfdi_sim_thr_params_t p;
  canfdi_sim_thr_t v;
  canfdi_sim_thr_fx_t fx;
  canfdi_sim_thr_in_t in = cmd(6.0, true);
  unsigned k;
  double worst = 0.0;

  canfdi_sim_thr_default_params(&p);
  ck_assert_int_eq(canfdi_sim_thr_init(&v, &p), CANFDI_OK);
  canfdi_sim_thr_fx_none(&fx);
  fx.jammed = true;
  for (k = 1U; k <= 8U; k++) {
    const double i_ref = (6.0 / p.r_ohm) * (1.0 - exp(-(double)k * 1e-3 * p.r_ohm / p.l_H));
    canfdi_sim_thr_step(&v, &in, &fx);
    worst = fmax(worst, fabs(v.i_A - i_ref) / (6.0 / p.r_ohm));
  }
  printf("thr R-L step (tau 1 ms) vs exact: max error %.2e of I_ss\n", worst);
  /* RK4 at lambda h = 0.1: local error ~(0.1)^5/120 ~ 1e-7 per sub-step. */
  ck_assert_msg(worst < 1e-6, "error %.3e", worst);
}
END_TEST

START_TEST(potentiometers_have_opposite_slopes)
{
  double a;
  ck_assert_msg(fabs(canfdi_sim_thr_tps1_V(0.0) - 0.5) < 1e-12, "TPS1(0)");
  ck_assert_msg(fabs(canfdi_sim_thr_tps1_V(90.0) - 4.5) < 1e-12, "TPS1(90)");
  ck_assert_msg(fabs(canfdi_sim_thr_tps2_V(0.0) - 4.5) < 1e-12, "TPS2(0)");
  ck_assert_msg(fabs(canfdi_sim_thr_tps2_V(90.0) - 0.5) < 1e-12, "TPS2(90)");
  for (a = 0.0; a <= 90.0; a += 7.5) {
    ck_assert_msg(fabs(canfdi_sim_thr_tps1_V(a) + canfdi_sim_thr_tps2_V(a) - 5.0) < 1e-12,
                  "sum at %g deg", a);
  }
}
END_TEST

START_TEST(invalid_parameters_rejected)
{
  canfdi_sim_thr_params_t p;
  canfdi_sim_thr_t v;
  canfdi_sim_thr_default_params(&p);
  p.limp_home_deg = 95.0;
  ck_assert_int_eq(canfdi_sim_thr_init(&v, &p), -CANFDI_EINVAL);
  canfdi_sim_thr_default_params(&p);
  p.supply_V = 17.0;
  ck_assert_int_eq(canfdi_sim_thr_init(&v, &p), -CANFDI_EINVAL);
  canfdi_sim_thr_default_params(&p);
  ck_assert_int_eq(canfdi_sim_thr_init(&v, &p), CANFDI_OK);
  ck_assert_int_eq(canfdi_sim_thr_set_state(&v, 91.0, 0.0), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_sim_thr_set_state(&v, -1.0, 0.0), -CANFDI_EINVAL);
}
END_TEST

static Suite *make_suite(void)
{
  Suite *s = suite_create("sim_thr");
  TCase *tc = tcase_create("limp_home");
  tcase_add_loop_test(tc, unpowered_valve_settles_at_limp_home, 0,
                      (int)(sizeof lh_start_deg / sizeof lh_start_deg[0]));
  tcase_add_test(tc, shorted_motor_also_returns_home);
  suite_add_tcase(s, tc);
  tc = tcase_create("stroke");
  tcase_add_loop_test(tc, stroke_under_reference_controller, 0,
                      (int)(sizeof strokes / sizeof strokes[0]));
  suite_add_tcase(s, tc);
  tc = tcase_create("mechanics");
  tcase_add_test(tc, end_stops_are_hard);
  tcase_add_test(tc, stiction_holds_inside_friction_band);
  suite_add_tcase(s, tc);
  tc = tcase_create("electrical");
  tcase_add_test(tc, locked_current_time_constant);
  tcase_add_test(tc, potentiometers_have_opposite_slopes);
  tcase_add_test(tc, invalid_parameters_rejected);
  suite_add_tcase(s, tc);
  return s;
}

CANFDI_UNIT_MAIN(make_suite)
