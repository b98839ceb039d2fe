/*
 * test_parity_thr.c — throttle-valve residuals (firmware/model/
 * canfdi_parity_thr.h) driven by the host_sim valve and its reference
 * position controller.
 *
 * What is proven (figures printed):
 *  - fault-free operation (constant, sine and step setpoints) keeps every
 *    valid residual inside its band; the margin is printed;
 *  - a TPS1 or TPS2 offset of 2 % of the 5 V span (0.1 V, 2.25 deg), either
 *    sign, abrupt or drifting in over 3 s: CORR and the faulty sensor's
 *    position residual leave the band with the predicted sign, the healthy
 *    sensor's position residual and ARM stay inside, and the observer ends
 *    up trusting the healthy sensor (the third vote isolates);
 *  - motor resistance +20 % moves ARM with the predicted sign while CORR
 *    stays inside; a weak spring and doubled friction leave CORR and ARM
 *    (decoupled from the mechanics) inside; an open motor circuit moves ARM;
 *  - configuration checks, reset, forced source, extreme inputs.
 * Noise model on top of host_sim's 12-bit ADCs: sigma TPS 2 mV each,
 * motor current 5 mA.
 */
#include <check.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "canfdi_sim.h"
#include "canfdi_sim_refctl.h"
#include "gen/canfdi_faults.h"
#include "core/canfdi_common.h"
#include "model/canfdi_parity_thr.h"
#include "unit_main.h"
#include "unit_q16.h"

#define N_RES CANFDI_PARITY_THR_N_RES

static const char *const res_name[N_RES] = {"corr[V]", "arm[V]", "pos1[rad]", "pos2[rad]"};

typedef struct {
  double sum[N_RES];
  double sum2[N_RES];
  double max_rn[N_RES];
  long n[N_RES];
  long exceed[N_RES];
} win_t;

static void win_add(win_t *w, const canfdi_parity_thr_out_t *o)
{
  unsigned j;
  for (j = 0U; j < N_RES; j++) {
    if ((o->valid & (1U << j)) != 0U) {
      const double r = fq16(o->r_q16[j]);
      const double rn = fabs(fq16(o->rn_q16[j]));
      w->sum[j] += r;
      w->sum2[j] += r * r;
      w->n[j] += 1;
      if (rn > w->max_rn[j]) {
        w->max_rn[j] = rn;
      }
      if ((o->exceed & (1U << j)) != 0U) {
        w->exceed[j] += 1;
      }
    }
  }
}

static double win_mean(const win_t *w, unsigned j)
{
  return (w->n[j] > 0) ? w->sum[j] / (double)w->n[j] : 0.0;
}

static double win_sd(const win_t *w, unsigned j)
{
  const double m = win_mean(w, j);
  return (w->n[j] > 1) ? sqrt(fmax(0.0, (w->sum2[j] / (double)w->n[j]) - (m * m))) : 0.0;
}

#define PROF_CONST 0U /* 20 deg */
#define PROF_SINE 1U  /* 30 + 10 sin(2 pi 1 t) deg */
#define PROF_STEPS 2U /* 20 <-> 40 deg every 0.5 s */
#define PROF_BIG 3U   /* 10 <-> 70 deg every 1 s (strokes where the valve
                       * model's speed error matters: the position bands
                       * must widen with |dtheta/dt|) */

static double angle_ref(unsigned prof, double t)
{
  double a = 20.0;
  if (prof == PROF_SINE) {
    a = 30.0 + (10.0 * sin(2.0 * 3.141592653589793 * t));
  } else if (prof == PROF_STEPS) {
    a = (((long)floor(t / 0.5)) % 2L == 0L) ? 20.0 : 40.0;
  } else if (prof == PROF_BIG) {
    a = (((long)floor(t / 1.0)) % 2L == 0L) ? 10.0 : 70.0;
  } else {
    /* constant */
  }
  return a;
}

typedef struct {
  uint64_t seed;
  unsigned prof;
  int fault_id; /* < 0: none */
  double fault_mag;
  double ramp_s; /* > 0: incipient */
  double t_fault_s;
  double t_end_s;
  double t_eval_s;
  double t_skip_s;
} run_t;

typedef struct {
  win_t pre;
  win_t post;
  uint8_t src_end;
} run_res_t;

static canfdi_sim_t g_sim;
static canfdi_parity_thr_cfg_t g_cfg;
static canfdi_parity_thr_t g_p;

static void run_closed_loop(const run_t *r, run_res_t *res)
{
  canfdi_sim_cfg_t cfg;
  canfdi_sim_refctl_cfg_t rcfg;
  canfdi_sim_refctl_t ctl;
  const long n_end = lround(r->t_end_s * 1000.0);
  long k;
  canfdi_sim_default_cfg(&cfg);
  cfg.sigma[CANFDI_SIM_S_THR_TPS1] = 0.002;
  cfg.sigma[CANFDI_SIM_S_THR_TPS2] = 0.002;
  cfg.sigma[CANFDI_SIM_S_THR_I] = 0.005;
  cfg.seed = r->seed;
  ck_assert_int_eq(canfdi_sim_init(&g_sim, &cfg), CANFDI_OK);
  canfdi_sim_refctl_default(&rcfg, &cfg);
  canfdi_sim_refctl_init(&ctl, &rcfg);
  if (r->fault_id >= 0) {
    canfdi_sim_fault_spec_t spec;
    ck_assert_int_eq(canfdi_sim_fault_spec_make(&spec, (uint8_t)r->fault_id,
                                                (r->ramp_s > 0.0) ? CANFDI_SIM_MODE_INCIPIENT
                                                                  : CANFDI_SIM_MODE_ABRUPT,
                                                r->t_fault_s, r->fault_mag, r->ramp_s, 0.0, 0.0),
                     CANFDI_OK);
    ck_assert_int_eq(canfdi_sim_add_fault(&g_sim, &spec), CANFDI_OK);
  }
  memset(res, 0, sizeof(*res));
  for (k = 0L; k < n_end; k++) {
    const double t = (double)k * 1e-3;
    const double t_next = (double)(k + 1L) * 1e-3;
    canfdi_sim_in_t in;
    canfdi_parity_thr_in_t pin;
    const canfdi_parity_thr_out_t *o;
    in.dcm.load_Nm = 0.0;
    canfdi_sim_refctl_step(&ctl, 0.0, angle_ref(r->prof, t), &g_sim.meas, &in);
    canfdi_sim_step(&g_sim, &in);
    pin.tps1_V_q16 = q16(g_sim.meas.value[CANFDI_SIM_S_THR_TPS1]);
    pin.tps2_V_q16 = q16(g_sim.meas.value[CANFDI_SIM_S_THR_TPS2]);
    pin.i_A_q16 = q16(g_sim.meas.value[CANFDI_SIM_S_THR_I]);
    pin.u_V_q16 = q16(in.thr.u_cmd_V);
    pin.supply_V_q16 = q16(g_sim.meas.value[CANFDI_SIM_S_THR_SUPPLY]);
    pin.enabled = in.thr.enable;
    o = canfdi_parity_thr_step(&g_p, &pin);
    ck_assert_ptr_nonnull(o);
    if (t_next >= r->t_eval_s) {
      if ((r->fault_id < 0) || (t_next < r->t_fault_s)) {
        win_add(&res->pre, o);
      } else if (t_next >= r->t_fault_s + r->t_skip_s) {
        win_add(&res->post, o);
      } else {
        /* onset transient */
      }
    }
    res->src_end = o->src;
  }
}

static void init_default(void)
{
  canfdi_parity_thr_default_cfg(&g_cfg);
  ck_assert_int_eq(canfdi_parity_thr_init(&g_p, &g_cfg), CANFDI_OK);
}

static void base_run(run_t *r)
{
  memset(r, 0, sizeof(*r));
  r->seed = 5U;
  r->prof = PROF_SINE;
  r->fault_id = -1;
  r->t_fault_s = 4.0;
  r->t_end_s = 9.0;
  r->t_eval_s = 0.5;
  r->t_skip_s = 0.3;
}

/* ---- configuration ------------------------------------------------------- */

START_TEST(default_cfg_valid)
{
  canfdi_parity_thr_cfg_t c;
  canfdi_parity_thr_in_t in;
  memset(&in, 0, sizeof(in));
  canfdi_parity_thr_default_cfg(&c);
  ck_assert_int_eq(canfdi_parity_thr_cfg_check(&c), CANFDI_OK);
  ck_assert_int_eq(canfdi_parity_thr_cfg_check(NULL), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_parity_thr_init(NULL, &c), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_parity_thr_init(&g_p, NULL), -CANFDI_EINVAL);
  ck_assert_ptr_null(canfdi_parity_thr_step(&g_p, &in));
  ck_assert_int_eq(canfdi_parity_thr_force_source(&g_p, 0U), -CANFDI_EINVAL);
  canfdi_parity_thr_default_cfg(NULL);
}
END_TEST

static void break_cfg(canfdi_parity_thr_cfg_t *c, int i)
{
  switch (i) {
  case 0: c->tps1.slope_V_rad_q16 = 0; break;
  case 1: c->tps_min_V_q16 = c->tps_max_V_q16 + 1; break;
  case 2: c->i_max_A_q16 = 0; break;
  case 3: c->r_ohm_q24 = 0; break;
  case 4: c->k_Nm_A_q24 = 0; break;
  case 5: c->j_kgm2_q24 = 1; break;
  case 6: c->friction_Nm_q24 = -1; break;
  case 7: c->limp_home_rad_q16 = c->max_rad_q16 + 1; break;
  case 8: c->lh_width_rad_q16 = 0; break;
  case 9: c->omega_c_rad_s = 2000; break;
  case 10: c->obs_lambda_rad_s = 0; break;
  case 11: c->obs_emf_gain_q31 = -1; break;
  case 12: c->select_ratio = 0U; break;
  case 13: c->band[3].base = 0; break;
  case 14: c->res_tau_us = 20000000U; break;
  case 15: c->tps2.slope_V_rad_q16 = c->tps1.slope_V_rad_q16; break; /* not complementary */
  case 16: c->tps2.zero_V_q16 = 5 * 65536 + 1; break;
  default: c->max_rad_q16 = 5 * 65536; break;
  }
}

START_TEST(invalid_cfg_rejected)
{
  canfdi_parity_thr_cfg_t c;
  canfdi_parity_thr_in_t in;
  memset(&in, 0, sizeof(in));
  canfdi_parity_thr_default_cfg(&c);
  ck_assert_int_eq(canfdi_parity_thr_init(&g_p, &c), CANFDI_OK);
  break_cfg(&c, _i);
  ck_assert_int_eq(canfdi_parity_thr_cfg_check(&c), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_parity_thr_init(&g_p, &c), -CANFDI_EINVAL);
  ck_assert_ptr_null(canfdi_parity_thr_step(&g_p, &in));
  ck_assert_ptr_null(canfdi_parity_thr_out(&g_p));
}
END_TEST

/* ---- fault-free ---------------------------------------------------------- */

START_TEST(fault_free_inside_band)
{
  run_t r;
  run_res_t res;
  unsigned j;
  static const char *const prof_name[] = {"const 20 deg", "sine 30+-10 deg 1 Hz",
                                          "steps 20<->40 deg", "strokes 10<->70 deg"};
  base_run(&r);
  r.prof = (unsigned)_i;
  r.seed = 50U + (uint64_t)_i;
  r.t_end_s = 10.0;
  init_default();
  run_closed_loop(&r, &res);
  printf("thr fault-free (%s):\n", prof_name[_i]);
  for (j = 0U; j < N_RES; j++) {
    printf("  %-9s mean %+.5f sigma %.5f  max|r|/thr %.2f  (n %ld)\n", res_name[j],
           win_mean(&res.pre, j), win_sd(&res.pre, j), res.pre.max_rn[j], res.pre.n[j]);
  }
  (void)fflush(stdout);
  for (j = 0U; j < N_RES; j++) {
    /* ARM is not evaluable while the current sensor clips (big steps) */
    ck_assert_msg(res.pre.n[j] > ((j == CANFDI_PARITY_THR_ARM) ? 6000L : 9000L),
                  "%s evaluated only %ld times", res_name[j], res.pre.n[j]);
    ck_assert_msg(res.pre.exceed[j] == 0L, "%s left its band %ld times (max %.2f)", res_name[j],
                  res.pre.exceed[j], res.pre.max_rn[j]);
  }
  ck_assert_uint_eq(res.src_end, CANFDI_PARITY_THR_SRC_MEAN);
  ck_assert_uint_eq(canfdi_parity_thr_diag(&g_p)->coast_entries, 0U);
}
END_TEST

/* ---- faults --------------------------------------------------------------- */

typedef struct {
  const char *name;
  int fault_id;
  double magnitude;
  double ramp_s;
  unsigned prof;
  int expect[N_RES]; /* +1/-1 beyond with sign, 0 inside, 2 not asserted */
  int src;           /* expected source at the end, -1: not asserted */
} fault_case_t;

#define TPS1 CANFDI_FAULT_THR_TPS1_DRIFT
#define TPS2 CANFDI_FAULT_THR_TPS2_DRIFT

static const fault_case_t fault_cases[] = {
    {"TPS1 +0.1 V abrupt", TPS1, 0.1, 0.0, PROF_CONST, {+1, 0, +1, 0}, CANFDI_PARITY_THR_SRC_TPS2},
    {"TPS1 -0.1 V abrupt", TPS1, -0.1, 0.0, PROF_SINE, {-1, 0, -1, 0}, CANFDI_PARITY_THR_SRC_TPS2},
    {"TPS2 +0.1 V abrupt", TPS2, 0.1, 0.0, PROF_SINE, {+1, 0, 0, -1}, CANFDI_PARITY_THR_SRC_TPS1},
    {"TPS2 -0.1 V abrupt", TPS2, -0.1, 0.0, PROF_STEPS, {-1, 0, 0, +1}, CANFDI_PARITY_THR_SRC_TPS1},
    {"TPS1 +0.1 V in 3 s", TPS1, 0.1, 3.0, PROF_CONST, {+1, 0, +1, 0}, CANFDI_PARITY_THR_SRC_TPS2},
    {"TPS2 +0.1 V in 3 s", TPS2, 0.1, 3.0, PROF_SINE, {+1, 0, 0, -1}, CANFDI_PARITY_THR_SRC_TPS1},
    {"TPS1 -0.1 V in 3 s", TPS1, -0.1, 3.0, PROF_STEPS, {-1, 0, -1, 0}, CANFDI_PARITY_THR_SRC_TPS2},
    /* ARM moves by dR i: at a constant angle (i ~1.1 A) all the time */
    {"motor R +20 %", CANFDI_FAULT_THR_MOTOR_R_UP, 0.2, 0.0, PROF_CONST, {0, +1, 2, 2}, -1},
    {"spring -20 %", CANFDI_FAULT_THR_SPRING_WEAK, 0.2, 0.0, PROF_SINE, {0, 0, 2, 2}, -1},
    {"friction x2", CANFDI_FAULT_THR_FRICTION_UP, 1.0, 0.0, PROF_SINE, {0, 0, 2, 2}, -1},
    {"motor open", CANFDI_FAULT_THR_MOTOR_OPEN, 1.0, 0.0, PROF_SINE, {0, +1, 2, 2}, -1},
};

#define N_FAULT_CASES ((int)(sizeof(fault_cases) / sizeof(fault_cases[0])))

/* Each case runs with three noise seeds (loop index = case + n * seed). */
START_TEST(fault_moves_predicted_residuals)
{
  const fault_case_t *fc = &fault_cases[_i % N_FAULT_CASES];
  run_t r;
  run_res_t res;
  unsigned j;
  base_run(&r);
  r.seed = 200U + (uint64_t)_i;
  r.prof = fc->prof;
  r.fault_id = fc->fault_id;
  r.fault_mag = fc->magnitude;
  r.ramp_s = fc->ramp_s;
  /* incipient: evaluate once the drift is complete */
  r.t_skip_s = (r.ramp_s > 0.0) ? r.ramp_s + 0.5 : 0.3;
  r.t_end_s = r.t_fault_s + r.t_skip_s + 4.0;
  init_default();
  run_closed_loop(&r, &res);
  printf("thr fault %-20s:", fc->name);
  for (j = 0U; j < N_RES; j++) {
    const double sd = win_sd(&res.pre, j);
    printf("  %s %+.4f (%+.0f sd, %3.0f %% out, max %.1f)", res_name[j], win_mean(&res.post, j),
           (sd > 0.0) ? (win_mean(&res.post, j) - win_mean(&res.pre, j)) / sd : 0.0,
           (res.post.n[j] > 0) ? 100.0 * (double)res.post.exceed[j] / (double)res.post.n[j] : 0.0,
           res.post.max_rn[j]);
  }
  printf("  src %u\n", res.src_end);
  (void)fflush(stdout);
  for (j = 0U; j < N_RES; j++) {
    const double m = win_mean(&res.post, j);
    if ((fc->expect[j] == 1) || (fc->expect[j] == -1)) {
      ck_assert_msg(res.post.n[j] > 1000L, "%s: %s evaluated %ld times", fc->name, res_name[j],
                    res.post.n[j]);
      ck_assert_msg((double)fc->expect[j] * m > fq16(g_cfg.band[j].base),
                    "%s: %s mean %+.4f not beyond the band %.4f with sign %d", fc->name,
                    res_name[j], m, fq16(g_cfg.band[j].base), fc->expect[j]);
      ck_assert_msg(res.post.exceed[j] * 10L > res.post.n[j] * 9L,
                    "%s: %s out of band only %ld of %ld samples", fc->name, res_name[j],
                    res.post.exceed[j], res.post.n[j]);
    } else if (fc->expect[j] == 0) {
      ck_assert_msg(res.post.exceed[j] == 0L, "%s: decoupled %s left the band (max %.2f)",
                    fc->name, res_name[j], res.post.max_rn[j]);
    } else {
      /* not asserted */
    }
  }
  if (fc->src >= 0) {
    ck_assert_msg(res.src_end == (uint8_t)fc->src, "%s: observer trusts source %u, expected %d",
                  fc->name, res.src_end, fc->src);
  }
}
END_TEST

/* The onset of an abrupt TPS jump: the decoupled residuals must stay inside
 * from the very first sample (no transient allowance). */
START_TEST(tps_jump_no_transient_in_decoupled)
{
  run_t r;
  run_res_t res;
  base_run(&r);
  r.seed = 300U + (uint64_t)_i;
  r.prof = PROF_CONST;
  r.fault_id = (_i == 0) ? (int)TPS1 : (int)TPS2;
  r.fault_mag = 0.1;
  r.t_skip_s = 0.0;
  init_default();
  run_closed_loop(&r, &res);
  printf("thr TPS%d jump, from the onset: arm max|r|/thr %.2f, healthy pos max|r|/thr %.2f\n",
         _i + 1, res.post.max_rn[CANFDI_PARITY_THR_ARM],
         res.post.max_rn[(_i == 0) ? CANFDI_PARITY_THR_POS2 : CANFDI_PARITY_THR_POS1]);
  (void)fflush(stdout);
  ck_assert_int_eq(res.post.exceed[CANFDI_PARITY_THR_ARM], 0);
  ck_assert_int_eq(res.post.exceed[(_i == 0) ? CANFDI_PARITY_THR_POS2 : CANFDI_PARITY_THR_POS1], 0);
}
END_TEST

/* ---- robustness ----------------------------------------------------------- */

START_TEST(force_source_and_reset)
{
  canfdi_parity_thr_in_t in;
  const canfdi_parity_thr_out_t *o = NULL;
  unsigned k;
  init_default();
  in.tps1_V_q16 = q16(0.5 + (4.0 * 20.0 / 90.0));
  in.tps2_V_q16 = q16(4.5 - (4.0 * 20.0 / 90.0));
  in.i_A_q16 = q16(1.0);
  in.u_V_q16 = q16(1.5);
  in.supply_V_q16 = q16(13.5);
  in.enabled = true;
  ck_assert_int_eq(canfdi_parity_thr_force_source(&g_p, 4U), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_parity_thr_force_source(&g_p, CANFDI_PARITY_THR_SRC_TPS1), CANFDI_OK);
  o = canfdi_parity_thr_step(&g_p, &in);
  ck_assert_uint_eq(o->src, CANFDI_PARITY_THR_SRC_TPS1);
  for (k = 0U; k < g_cfg.release_steps; k++) {
    o = canfdi_parity_thr_step(&g_p, &in);
  }
  /* consistent sensors: back to the mean after release_steps */
  ck_assert_uint_eq(o->src, CANFDI_PARITY_THR_SRC_MEAN);
  ck_assert_uint_eq(o->valid, 0x0FU);
  /* the observer sits at the measured 20 deg (the spring needs 1.09 A;
   * 1 A is inside the friction band, so the valve model sticks) */
  ck_assert_msg(fabs(fq16(o->theta_hat_rad_q16) - (20.0 * 3.141592653589793 / 180.0)) < 2e-3,
                "theta_hat %.5f", fq16(o->theta_hat_rad_q16));
  /* TPS2 open: single-sensor feedback, CORR and POS2 not valid */
  in.tps2_V_q16 = 0;
  o = canfdi_parity_thr_step(&g_p, &in);
  ck_assert_uint_eq(o->src, CANFDI_PARITY_THR_SRC_TPS1);
  ck_assert_uint_eq(o->valid & 0x09U, 0U);
  /* bridge off: ARM not valid */
  in.enabled = false;
  o = canfdi_parity_thr_step(&g_p, &in);
  ck_assert_uint_eq(o->valid & 0x02U, 0U);
  canfdi_parity_thr_reset(&g_p);
  ck_assert_uint_eq(canfdi_parity_thr_out(&g_p)->valid, 0U);
  ck_assert_uint_eq(canfdi_parity_thr_diag(&g_p)->resets, 1U);
  canfdi_parity_thr_reset(NULL);
}
END_TEST

START_TEST(extreme_inputs_saturate)
{
  static const int32_t vals[] = {INT32_MIN, -1, 0, 1, INT32_MAX, 65536 * 3, -2000000000};
  const unsigned nv = (unsigned)(sizeof(vals) / sizeof(vals[0]));
  uint32_t lcg = 777U;
  unsigned k;
  init_default();
  for (k = 0U; k < 20000U; k++) {
    canfdi_parity_thr_in_t in;
    const canfdi_parity_thr_out_t *o;
    unsigned j;
    lcg = (lcg * 1103515245U) + 12345U;
    in.tps1_V_q16 = vals[(lcg >> 4) % nv];
    in.tps2_V_q16 = vals[(lcg >> 8) % nv];
    in.i_A_q16 = vals[(lcg >> 12) % nv];
    in.u_V_q16 = vals[(lcg >> 16) % nv];
    in.supply_V_q16 = vals[(lcg >> 20) % nv];
    in.enabled = ((lcg >> 24) & 1U) != 0U;
    o = canfdi_parity_thr_step(&g_p, &in);
    ck_assert_ptr_nonnull(o);
    ck_assert_int_ge(o->theta_hat_rad_q16, 0);
    ck_assert_int_le(o->theta_hat_rad_q16, g_cfg.max_rad_q16);
    for (j = 0U; j < N_RES; j++) {
      ck_assert_int_gt(o->thr_q16[j], 0);
    }
  }
  ck_assert_uint_eq(canfdi_parity_thr_diag(&g_p)->steps, 20000U);
}
END_TEST

static Suite *make_suite(void)
{
  Suite *s = suite_create("parity_thr");
  TCase *tc;

  tc = tcase_create("config");
  tcase_add_test(tc, default_cfg_valid);
  tcase_add_loop_test(tc, invalid_cfg_rejected, 0, 18);
  suite_add_tcase(s, tc);

  tc = tcase_create("fault_free");
  tcase_set_timeout(tc, 120);
  tcase_add_loop_test(tc, fault_free_inside_band, 0, 4);
  suite_add_tcase(s, tc);

  tc = tcase_create("structure");
  tcase_set_timeout(tc, 300);
  tcase_add_loop_test(tc, fault_moves_predicted_residuals, 0, 3 * N_FAULT_CASES);
  tcase_add_loop_test(tc, tps_jump_no_transient_in_decoupled, 0, 2);
  suite_add_tcase(s, tc);

  tc = tcase_create("robustness");
  tcase_add_test(tc, force_source_and_reset);
  tcase_add_test(tc, extreme_inputs_saturate);
  suite_add_tcase(s, tc);
  return s;
}

CANFDI_UNIT_MAIN(make_suite)
