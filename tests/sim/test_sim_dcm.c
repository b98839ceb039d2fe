/*
 * test_sim_dcm.c — DC motor drive plant (host_sim/canfdi_sim_dcm.h) and the
 * integrator (canfdi_sim_ode.h) against analytic solutions.
 */
#include <check.h>
#include <math.h>
#include <stdio.h>

#include "canfdi_sim_dcm.h"
#include "canfdi_sim_ode.h"
#include "core/canfdi_common.h"
#include "unit_main.h"

static canfdi_sim_dcm_params_t cold_params(void)
{
  canfdi_sim_dcm_params_t p;
  canfdi_sim_dcm_default_params(&p);
  p.thermal = false; /* analytic checks need a constant R_A */
  return p;
}

static canfdi_sim_dcm_in_t drive(double u_V, double load_Nm)
{
  canfdi_sim_dcm_in_t in;
  in.u_cmd_V = u_V;
  in.bridge = CANFDI_SIM_BRIDGE_A;
  in.enable = true;
  in.load_Nm = load_Nm;
  return in;
}

static void run(canfdi_sim_dcm_t *m, const canfdi_sim_dcm_in_t *in, unsigned steps)
{
  canfdi_sim_dcm_fx_t fx;
  unsigned k;
  canfdi_sim_dcm_fx_none(&fx);
  for (k = 0U; k < steps; k++) {
    canfdi_sim_dcm_step(m, in, &fx);
  }
}

/* ---- steady state ------------------------------------------------------ */

typedef struct {
  double u_V;
  double load_Nm;
  double fan_Nms;
} ss_case_t;

/* Voltages and loads spanning no-load, nominal (~4 A at ~100 rad/s), a fan
 * load and reverse rotation. */
static const ss_case_t ss_cases[] = {
    {38.4, 1.2, 0.0}, {24.0, 0.5, 0.0}, {12.0, 0.0, 0.0}, {40.0, 0.3, 0.008}, {-30.0, -0.8, 0.0},
};

START_TEST(steady_state_matches_analytic)
{
  const ss_case_t *c = &ss_cases[_i];
  canfdi_sim_dcm_params_t p = cold_params();
  canfdi_sim_dcm_t m;
  canfdi_sim_dcm_in_t in = drive(c->u_V, c->load_Nm);
  double dir;
  double w_ref;
  double i_ref;
  double ew;
  double ei;

  p.load_k_fan_Nms = c->fan_Nms;
  ck_assert_int_eq(canfdi_sim_dcm_init(&m, &p), CANFDI_OK);
  run(&m, &in, 3000U); /* 3 s: > 100 times the slowest time constant (~20 ms) */
  /* J dw/dt = 0 and L dI/dt = 0 with Coulomb friction opposing rotation:
   * w = (Psi U / R - M_F0 dir - M_L) / (Psi^2 / R + M_F1 + k_fan). */
  dir = (c->u_V > 0.0) ? 1.0 : -1.0;
  w_ref = ((p.psi_Vs * c->u_V / p.ra_cold_ohm) - (p.mf0_Nm * dir) - c->load_Nm) /
          ((p.psi_Vs * p.psi_Vs / p.ra_cold_ohm) + p.mf1_Nms + c->fan_Nms);
  i_ref = (c->u_V - (p.psi_Vs * w_ref)) / p.ra_cold_ohm;
  ew = fabs(m.w_rad_s - w_ref) / fabs(w_ref);
  ei = fabs(m.i_A - i_ref) / fabs(i_ref);
  printf("dcm steady state U=%g V M_L=%g N m: w %.6f (analytic %.6f, err %.2e), "
         "I %.6f (analytic %.6f, err %.2e)\n",
         c->u_V, c->load_Nm, m.w_rad_s, w_ref, ew, m.i_A, i_ref, ei);
  /* Acceptance: within 0.5 %. */
  ck_assert_msg(ew < 0.005, "speed error %.3e", ew);
  ck_assert_msg(ei < 0.005, "current error %.3e", ei);
}
END_TEST

START_TEST(nominal_load_draws_a_few_amperes)
{
  /* docs/design.md: at ~100 rad/s the nominal load must draw a few amperes so
   * that resistance faults are observable (no-load current is ~0.4 A). */
  canfdi_sim_dcm_params_t p = cold_params();
  canfdi_sim_dcm_t m;
  canfdi_sim_dcm_in_t in = drive(38.4, 1.2);
  ck_assert_int_eq(canfdi_sim_dcm_init(&m, &p), CANFDI_OK);
  run(&m, &in, 2000U);
  ck_assert_msg((m.w_rad_s > 90.0) && (m.w_rad_s < 110.0), "w %g", m.w_rad_s);
  ck_assert_msg((m.i_A > 3.0) && (m.i_A < 6.0), "I %g", m.i_A);
  in.load_Nm = 0.0;
  run(&m, &in, 2000U);
  ck_assert_msg(m.i_A < 0.6, "no-load current %g", m.i_A);
}
END_TEST

/* ---- current time constant -------------------------------------------- */

/* Case 0: rotor held by stiction (Psi U/R < M_F0); case 1: huge inertia. */
START_TEST(current_step_time_constant)
{
  canfdi_sim_dcm_params_t p = cold_params();
  canfdi_sim_dcm_t m;
  canfdi_sim_dcm_fx_t fx;
  const double u = (_i == 0) ? 0.4 : 10.0;
  canfdi_sim_dcm_in_t in = drive(u, 0.0);
  const double tau = p.la_H / p.ra_cold_ohm;
  const double i_ss = u / p.ra_cold_ohm;
  double worst = 0.0;
  unsigned k;

  if (_i == 1) {
    p.j_kgm2 = 1e3; /* back-EMF after 20 ms ~ 2e-6 of U */
  }
  ck_assert_int_eq(canfdi_sim_dcm_init(&m, &p), CANFDI_OK);
  if (_i == 0) {
    ck_assert_msg(p.psi_Vs * i_ss < p.mf0_Nm, "case must stay below breakaway");
  }
  canfdi_sim_dcm_fx_none(&fx);
  for (k = 1U; k <= 20U; k++) {
    double tau_k;
    double e;
    canfdi_sim_dcm_step(&m, &in, &fx);
    /* Exact for a first-order response sampled at t_k: I = I_ss(1 - e^-t/tau). */
    tau_k = -((double)k * 1e-3) / log(1.0 - (m.i_A / i_ss));
    e = fabs(tau_k - tau) / tau;
    if (e > worst) {
      worst = e;
    }
  }
  if (_i == 0) {
    ck_assert_msg(fabs(m.w_rad_s) < 1e-300, "rotor moved: w = %g", m.w_rad_s);
  }
  printf("dcm current time constant (%s): L/R = %.4f ms, worst sample error %.2e\n",
         (_i == 0) ? "stiction-locked" : "J large", tau * 1e3, worst);
  /* Acceptance: within 2 %. */
  ck_assert_msg(worst < 0.02, "time constant error %.3e", worst);
}
END_TEST

/* ---- integrator accuracy ------------------------------------------------ */

START_TEST(rk4_matches_linear_motor_solution)
{
  /* Without Coulomb friction, load and warming the motor is linear:
   * x' = A x + b, x = (I, w). Its exact solution via Sylvester's formula for
   * a 2x2 matrix with distinct real eigenvalues l1, l2:
   * e^{At} = (e^{l1 t}(A - l2) - e^{l2 t}(A - l1)) / (l1 - l2). */
  canfdi_sim_dcm_params_t p = cold_params();
  canfdi_sim_dcm_t m;
  canfdi_sim_dcm_in_t in = drive(24.0, 0.0);
  canfdi_sim_dcm_fx_t fx;
  const double a11 = -p.ra_cold_ohm / p.la_H;
  const double a12 = -p.psi_Vs / p.la_H;
  const double a21 = p.psi_Vs / p.j_kgm2;
  const double a22 = -p.mf1_Nms / p.j_kgm2;
  const double tr = a11 + a22;
  const double det = (a11 * a22) - (a12 * a21);
  const double disc = (tr * tr / 4.0) - det;
  double l1;
  double l2;
  double i_ss;
  double w_ss;
  double worst_i = 0.0;
  double worst_w = 0.0;
  unsigned k;

  p.mf0_Nm = 0.0;
  ck_assert_msg(disc > 0.0, "expected real eigenvalues");
  l1 = (tr / 2.0) + sqrt(disc);
  l2 = (tr / 2.0) - sqrt(disc);
  w_ss = p.psi_Vs * 24.0 / ((p.psi_Vs * p.psi_Vs) + (p.ra_cold_ohm * p.mf1_Nms));
  i_ss = (24.0 - (p.psi_Vs * w_ss)) / p.ra_cold_ohm;
  ck_assert_int_eq(canfdi_sim_dcm_init(&m, &p), CANFDI_OK);
  /* Start spinning so the trajectory never enters the stiction band (whose
   * mode is decided per sub-step and is not part of the linear model). */
  ck_assert_int_eq(canfdi_sim_dcm_set_state(&m, 0.0, 50.0, p.ambient_C), CANFDI_OK);
  canfdi_sim_dcm_fx_none(&fx);
  for (k = 1U; k <= 300U; k++) {
    const double t = (double)k * 1e-3;
    const double e1 = exp(l1 * t);
    const double e2 = exp(l2 * t);
    /* deviation from steady state starts at (0 - i_ss, 50 - w_ss) */
    const double d0 = -i_ss;
    const double d1 = 50.0 - w_ss;
    const double m11 = ((e1 * (a11 - l2)) - (e2 * (a11 - l1))) / (l1 - l2);
    const double m12 = ((e1 * a12) - (e2 * a12)) / (l1 - l2);
    const double m21 = ((e1 * a21) - (e2 * a21)) / (l1 - l2);
    const double m22 = ((e1 * (a22 - l2)) - (e2 * (a22 - l1))) / (l1 - l2);
    const double i_ref = i_ss + (m11 * d0) + (m12 * d1);
    const double w_ref = w_ss + (m21 * d0) + (m22 * d1);
    canfdi_sim_dcm_step(&m, &in, &fx);
    worst_i = fmax(worst_i, fabs(m.i_A - i_ref));
    worst_w = fmax(worst_w, fabs(m.w_rad_s - w_ref));
  }
  printf("rk4 (h = %.0f us) vs exact linear motor over 300 ms: max |dI| %.2e A (%.1e of I_peak "
         "scale %.1f A), max |dw| %.2e rad/s (%.1e of w_ss)\n",
         CANFDI_SIM_SUBSTEP_S * 1e6, worst_i, worst_i / (24.0 / p.ra_cold_ohm),
         24.0 / p.ra_cold_ohm, worst_w, worst_w / w_ss);
  /* RK4 at |lambda h| <= 0.02 has a global error ~1e-9 relative; 1e-6
   * leaves margin but fails any second-order method (~1e-5) or Euler. */
  ck_assert_msg(worst_i / (24.0 / p.ra_cold_ohm) < 1e-6, "current error %.3e", worst_i);
  ck_assert_msg(worst_w / w_ss < 1e-6, "speed error %.3e", worst_w);
}
END_TEST

static void decay(const void *ctx, const double *x, double *dxdt)
{
  dxdt[0] = *(const double *)ctx * x[0];
}

START_TEST(rk4_local_error_is_fifth_order)
{
  /* x' = l x: one RK4 step multiplies by 1 + z + z^2/2 + z^3/6 + z^4/24,
   * z = l h; the error against e^z is z^5/120 + O(z^6). */
  const double l = -950.0; /* fastest plant eigenvalue, 1/s */
  double x = 1.0;
  const double z = l * CANFDI_SIM_SUBSTEP_S;
  double err;
  canfdi_sim_ode_rk4(decay, &l, &x, 1U, CANFDI_SIM_SUBSTEP_S);
  err = fabs(x - exp(z));
  ck_assert_msg(fabs(err - (fabs(z * z * z * z * z) / 120.0)) < 0.2 * (fabs(z * z * z * z * z) / 120.0),
                "local error %.3e vs z^5/120 %.3e", err, fabs(z * z * z * z * z) / 120.0);
}
END_TEST

/* ---- friction without chatter ------------------------------------------- */

START_TEST(coast_down_stops_without_chatter)
{
  canfdi_sim_dcm_params_t p = cold_params();
  canfdi_sim_dcm_t m;
  canfdi_sim_dcm_in_t in = drive(0.0, 0.0);
  canfdi_sim_dcm_fx_t fx;
  unsigned k;
  unsigned zero_steps = 0U;
  double prev;

  ck_assert_int_eq(canfdi_sim_dcm_init(&m, &p), CANFDI_OK);
  ck_assert_int_eq(canfdi_sim_dcm_set_state(&m, 0.0, 100.0, p.ambient_C), CANFDI_OK);
  in.enable = false; /* high impedance: coasting, only friction brakes */
  canfdi_sim_dcm_fx_none(&fx);
  prev = m.w_rad_s;
  for (k = 0U; k < 5000U; k++) {
    canfdi_sim_dcm_step(&m, &in, &fx);
    ck_assert_msg(m.w_rad_s >= 0.0, "speed reversed at step %u: %g", k, m.w_rad_s);
    ck_assert_msg(m.w_rad_s <= prev, "speed rose at step %u", k);
    if (m.w_rad_s < 1e-300) {
      zero_steps++;
    }
    prev = m.w_rad_s;
  }
  /* 100 rad/s against M_F0 = 0.11 N m, J = 1.92e-3 stops in < 2 s; from then
   * on the speed must be exactly 0 (no sign chatter around zero). */
  ck_assert_msg(zero_steps > 3000U, "only %u steps at rest", zero_steps);
  ck_assert_uint_eq(m.diag.stick_events, 1U);
}
END_TEST

START_TEST(breakaway_threshold)
{
  /* Breakaway needs Psi U / R > M_F0: U > 0.45 V with the cold R. */
  canfdi_sim_dcm_params_t p = cold_params();
  canfdi_sim_dcm_t m;
  const double u_break = p.mf0_Nm * p.ra_cold_ohm / p.psi_Vs;
  canfdi_sim_dcm_in_t in = drive(0.95 * u_break, 0.0);
  ck_assert_int_eq(canfdi_sim_dcm_init(&m, &p), CANFDI_OK);
  run(&m, &in, 1000U);
  ck_assert_msg(fabs(m.w_rad_s) < 1e-300, "moved below breakaway: %g", m.w_rad_s);
  in.u_cmd_V = 1.05 * u_break;
  run(&m, &in, 1000U);
  ck_assert_msg(m.w_rad_s > 0.01, "did not break away: %g", m.w_rad_s);
}
END_TEST

/* ---- bridges ------------------------------------------------------------ */

START_TEST(bridges_clamp_select_and_fail)
{
  canfdi_sim_dcm_params_t p = cold_params();
  canfdi_sim_dcm_t m;
  canfdi_sim_dcm_fx_t fx;
  canfdi_sim_dcm_in_t in = drive(100.0, 0.0);

  ck_assert_int_eq(canfdi_sim_dcm_init(&m, &p), CANFDI_OK);
  canfdi_sim_dcm_fx_none(&fx);
  canfdi_sim_dcm_step(&m, &in, &fx);
  ck_assert_msg(fabs(m.ua_V - p.supply_V) < 1e-12, "not clamped: %g", m.ua_V);
  ck_assert_uint_eq(m.diag.cmd_clamps, 1U);
  in.u_cmd_V = -100.0;
  canfdi_sim_dcm_step(&m, &in, &fx);
  ck_assert_msg(fabs(m.ua_V + p.supply_V) < 1e-12, "not clamped: %g", m.ua_V);

  in.u_cmd_V = 20.0;
  fx.bridge_dead[0] = true;
  canfdi_sim_dcm_step(&m, &in, &fx);
  ck_assert_msg(fabs(m.ua_V) < 1e-300, "dead bridge A delivered %g V", m.ua_V);
  in.bridge = CANFDI_SIM_BRIDGE_B;
  canfdi_sim_dcm_step(&m, &in, &fx);
  ck_assert_msg(fabs(m.ua_V - 20.0) < 1e-12, "bridge B delivered %g V", m.ua_V);
  fx.bridge_dead[1] = true;
  canfdi_sim_dcm_step(&m, &in, &fx);
  ck_assert_msg(fabs(m.ua_V) < 1e-300, "dead bridge B delivered %g V", m.ua_V);
}
END_TEST

START_TEST(disabled_bridge_is_high_impedance)
{
  canfdi_sim_dcm_params_t p = cold_params();
  canfdi_sim_dcm_t m;
  canfdi_sim_dcm_fx_t fx;
  canfdi_sim_dcm_in_t in = drive(38.4, 1.2);
  unsigned k;

  ck_assert_int_eq(canfdi_sim_dcm_init(&m, &p), CANFDI_OK);
  canfdi_sim_dcm_fx_none(&fx);
  run(&m, &in, 1000U);
  ck_assert_msg(m.i_A > 3.0, "not loaded: %g A", m.i_A);
  in.enable = false;
  in.load_Nm = 0.0;
  canfdi_sim_dcm_step(&m, &in, &fx);
  /* The free-wheeling diodes return L I^2/2 to the supply in ~L I/(U_s + E)
   * ~ 0.3 ms: the current is gone within the step and stays gone, and the
   * terminals show the back-EMF. */
  ck_assert_msg(fabs(m.i_A) < 1e-300, "current after disable %g", m.i_A);
  for (k = 0U; k < 50U; k++) {
    canfdi_sim_dcm_step(&m, &in, &fx);
    ck_assert_msg(fabs(m.i_A) < 1e-300, "current flowed while off: %g", m.i_A);
    ck_assert_msg(fabs(m.ua_V - (p.psi_Vs * m.w_rad_s)) < 1e-12, "terminal %g vs EMF %g", m.ua_V,
                  p.psi_Vs * m.w_rad_s);
  }
  in.enable = true;
  in.bridge = CANFDI_SIM_BRIDGE_NONE; /* no bridge selected: also off */
  canfdi_sim_dcm_step(&m, &in, &fx);
  ck_assert_msg(fabs(m.i_A) < 1e-300, "current with no bridge: %g", m.i_A);
}
END_TEST

/* ---- warm-up ------------------------------------------------------------ */

START_TEST(winding_warm_up_over_hours)
{
  canfdi_sim_dcm_params_t p;
  canfdi_sim_dcm_t m;
  canfdi_sim_dcm_fx_t fx;
  canfdi_sim_dcm_in_t in = drive(38.4, 1.2); /* nominal: ~4 A at ~100 rad/s */
  double r_prev;
  double t_reach = -1.0;
  double r_1h = 0.0;
  unsigned long k;
  const unsigned long two_hours = 7200000UL;

  canfdi_sim_dcm_default_params(&p);
  ck_assert_int_eq(canfdi_sim_dcm_init(&m, &p), CANFDI_OK);
  canfdi_sim_dcm_fx_none(&fx);
  ck_assert_msg(fabs(m.ra_ohm - 1.35) < 1e-12, "cold R_A %g", m.ra_ohm);
  r_prev = m.ra_ohm;
  for (k = 1UL; k <= two_hours; k++) {
    canfdi_sim_dcm_step(&m, &in, &fx);
    if ((k % 60000UL) == 0UL) { /* every minute */
      ck_assert_msg(m.ra_ohm >= r_prev, "R_A fell at %lu s", k / 1000UL);
      r_prev = m.ra_ohm;
      if ((t_reach < 0.0) && (m.ra_ohm >= 1.49)) {
        t_reach = (double)k * 1e-3;
      }
      if (k == 3600000UL) {
        r_1h = m.ra_ohm;
      }
    }
  }
  printf("dcm warm-up at %.2f A: R_A 1.350 -> %.4f Ohm after 1 h -> %.4f Ohm after 2 h "
         "(winding %.1f C); 1.49 Ohm reached after %.0f min\n",
         m.i_A, r_1h, m.ra_ohm, m.temp_C, t_reach / 60.0);
  /* The literature: about 1.35 -> 1.5 Ohm over 1-2 h. */
  ck_assert_msg((t_reach >= 3600.0) && (t_reach <= 7200.0), "1.49 Ohm reached at %g s", t_reach);
  ck_assert_msg(m.ra_ohm < 1.56, "overheated: R_A %g", m.ra_ohm);
}
END_TEST

START_TEST(invalid_parameters_rejected)
{
  canfdi_sim_dcm_params_t p;
  canfdi_sim_dcm_t m;
  canfdi_sim_dcm_default_params(&p);
  p.la_H = 0.0;
  ck_assert_int_eq(canfdi_sim_dcm_init(&m, &p), -CANFDI_EINVAL);
  canfdi_sim_dcm_default_params(&p);
  p.supply_V = 81.0;
  ck_assert_int_eq(canfdi_sim_dcm_init(&m, &p), -CANFDI_EINVAL);
  canfdi_sim_dcm_default_params(&p);
  p.mf0_Nm = NAN;
  ck_assert_int_eq(canfdi_sim_dcm_init(&m, &p), -CANFDI_EINVAL);
  canfdi_sim_dcm_default_params(&p);
  ck_assert_int_eq(canfdi_sim_dcm_init(&m, &p), CANFDI_OK);
  ck_assert_int_eq(canfdi_sim_dcm_set_state(&m, 0.0, INFINITY, 20.0), -CANFDI_EINVAL);
}
END_TEST

static Suite *make_suite(void)
{
  Suite *s = suite_create("sim_dcm");
  TCase *tc = tcase_create("analytic");
  tcase_add_loop_test(tc, steady_state_matches_analytic, 0, (int)(sizeof ss_cases / sizeof ss_cases[0]));
  tcase_add_test(tc, nominal_load_draws_a_few_amperes);
  tcase_add_loop_test(tc, current_step_time_constant, 0, 2);
  suite_add_tcase(s, tc);
  tc = tcase_create("integrator");
  tcase_add_test(tc, rk4_matches_linear_motor_solution);
  tcase_add_test(tc, rk4_local_error_is_fifth_order);
  suite_add_tcase(s, tc);
  tc = tcase_create("friction");
  tcase_add_test(tc, coast_down_stops_without_chatter);
  tcase_add_test(tc, breakaway_threshold);
  suite_add_tcase(s, tc);
  tc = tcase_create("bridges");
  tcase_add_test(tc, bridges_clamp_select_and_fail);
  tcase_add_test(tc, disabled_bridge_is_high_impedance);
  tcase_add_test(tc, invalid_parameters_rejected);
  suite_add_tcase(s, tc);
  tc = tcase_create("thermal");
  tcase_set_timeout(tc, 300);
  tcase_add_test(tc, winding_warm_up_over_hours);
  suite_add_tcase(s, tc);
  return s;
}

CANFDI_UNIT_MAIN(make_suite)
