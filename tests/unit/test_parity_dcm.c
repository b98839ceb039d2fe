/*
 * test_parity_dcm.c — structured parity residuals of the DC motor
 * (firmware/model/canfdi_parity_dcm.h) driven by the host_sim plant and its
 * reference speed controller.
 *
 * What is proven (figures are printed, so a run documents itself):
 *  - fault-free operation with setpoint steps and a sine keeps every valid
 *    residual inside its band (the margin is printed as max |r| / threshold);
 *  - each sensor offset of 2 % of full scale (U_A 1.2 V of 60 V, I_A 0.6 A
 *    of 30 A, w 8 rad/s of 400 rad/s), a 2 % speed gain error and the
 *    parametric faults R_A +10 %, Psi -10 %, friction +20 % and a load
 *    0.2 N m above the input move the residuals the structure table of the
 *    header predicts beyond the band with the predicted sign, while the
 *    residual decoupled from that fault stays inside its band;
 *  - the adaptive R_A absorbs a warm-up (1.35 -> ~1.5 Ohm) without leaving
 *    the band, a fixed R_A does not, and an abrupt +10 % R_A afterwards
 *    stays visible (the tracker freezes);
 *  - configuration checks, reset, set_ra and extreme inputs (no UB under
 *    the sanitizers; saturation is counted).
 * Noise model (on top of the 12-bit ADCs of host_sim): sigma U_A 0.05 V,
 * I_A 0.02 A, w 0.2 rad/s. Operating point: Isermann's motor at 100 rad/s
 * with a 1.2 N m load (~4 A).
 */
#include <check.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "canfdi_sim.h"
#include "canfdi_sim_refctl.h"
#include "gen/canfdi_faults.h"
#include "core/canfdi_common.h"
#include "model/canfdi_parity_dcm.h"
#include "unit_main.h"
#include "unit_q16.h"

#define N_RES CANFDI_PARITY_DCM_N_RES
#define LOAD_NM 1.2
#define W_REF 100.0

static const char *const res_name[N_RES] = {"r1[V]", "r2[Nm]", "r3[Nm]", "r4[V]"};

/* ---- a closed-loop run ---------------------------------------------------- */

typedef struct {
  double sum[N_RES];
  double sum2[N_RES];
  double max_rn[N_RES];
  long n[N_RES];
  long exceed[N_RES];
} win_t;

static void win_clear(win_t *w)
{
  memset(w, 0, sizeof(*w));
}

static void win_add(win_t *w, const canfdi_parity_dcm_out_t *o)
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
  double m = win_mean(w, j);
  return (w->n[j] > 1) ? sqrt(fmax(0.0, (w->sum2[j] / (double)w->n[j]) - (m * m))) : 0.0;
}

#define PROFILE_SINE 0U  /* 100 + 10 sin(2 pi 0.5 t) rad/s */
#define PROFILE_STEPS 1U /* sine plus +-20 rad/s steps every second */

typedef struct {
  uint64_t seed;
  unsigned profile;
  bool thermal;
  double cth_J_K;        /* thermal capacitance (0: default) */
  double init_temp_C;    /* winding temperature at start (< -100: ambient) */
  int fault_id;          /* < 0: none */
  double fault_mag;
  double t_fault_s;
  double load_offset_Nm; /* true load minus the load given to the residuals */
  double t_end_s;
  double t_eval_s;       /* evaluation starts (after R_A learning) */
  double t_skip_s;       /* skipped after the fault onset */
  bool split;            /* windows pre/post t_fault_s (else all "pre") */
} run_t;

typedef struct {
  win_t pre;
  win_t post;
  double ra_at_fault;
  double ra_end;
  double ra_true_end;
  double max_ra_err; /* |R_A estimate - true R_A| after learning */
} run_res_t;

static void sim_cfg(canfdi_sim_cfg_t *cfg, const run_t *r)
{
  canfdi_sim_default_cfg(cfg);
  cfg->dcm.thermal = r->thermal;
  if (r->cth_J_K > 0.0) {
    cfg->dcm.cth_J_K = r->cth_J_K;
  }
  cfg->sigma[CANFDI_SIM_S_DCM_UA] = 0.05;
  cfg->sigma[CANFDI_SIM_S_DCM_IA] = 0.02;
  cfg->sigma[CANFDI_SIM_S_DCM_SPEED] = 0.2;
  cfg->seed = r->seed;
}

static double speed_ref(unsigned profile, double t)
{
  double w = W_REF + (10.0 * sin(2.0 * 3.141592653589793 * 0.5 * t));
  if (profile == PROFILE_STEPS) {
    w += ((long)floor(t) % 2L == 0L) ? 20.0 : -20.0;
  }
  return w;
}

static canfdi_sim_t g_sim; /* ~2.5 kB: keep it off the stack */

static void run_closed_loop(const run_t *r, canfdi_parity_dcm_t *p, run_res_t *res)
{
  canfdi_sim_cfg_t cfg;
  canfdi_sim_refctl_cfg_t rcfg;
  canfdi_sim_refctl_t ctl;
  const long n_end = lround(r->t_end_s * 1000.0);
  long k;
  sim_cfg(&cfg, r);
  ck_assert_int_eq(canfdi_sim_init(&g_sim, &cfg), CANFDI_OK);
  canfdi_sim_refctl_default(&rcfg, &cfg);
  canfdi_sim_refctl_init(&ctl, &rcfg);
  ck_assert_int_eq(canfdi_sim_dcm_set_state(&g_sim.dcm, LOAD_NM / 0.33, speed_ref(r->profile, 0.0),
                                            (r->init_temp_C < -100.0) ? cfg.dcm.ambient_C
                                                                      : r->init_temp_C),
                   CANFDI_OK);
  canfdi_sim_resample(&g_sim);
  if (r->fault_id >= 0) {
    canfdi_sim_fault_spec_t spec;
    ck_assert_int_eq(canfdi_sim_fault_spec_make(&spec, (uint8_t)r->fault_id,
                                                CANFDI_SIM_MODE_ABRUPT, r->t_fault_s, r->fault_mag,
                                                0.0, 0.0, 0.0),
                     CANFDI_OK);
    ck_assert_int_eq(canfdi_sim_add_fault(&g_sim, &spec), CANFDI_OK);
  }
  win_clear(&res->pre);
  win_clear(&res->post);
  res->ra_at_fault = 0.0;
  res->max_ra_err = 0.0;
  for (k = 0L; k < n_end; k++) {
    const double t = (double)k * 1e-3;
    const double t_next = (double)(k + 1L) * 1e-3;
    canfdi_sim_in_t in;
    canfdi_parity_dcm_in_t pin;
    const canfdi_parity_dcm_out_t *o;
    in.dcm.load_Nm = LOAD_NM + r->load_offset_Nm;
    canfdi_sim_refctl_step(&ctl, speed_ref(r->profile, t), 10.0, &g_sim.meas, &in);
    canfdi_sim_step(&g_sim, &in);
    pin.u_V_q16 = q16(g_sim.meas.value[CANFDI_SIM_S_DCM_UA]);
    pin.i_A_q16 = q16(g_sim.meas.value[CANFDI_SIM_S_DCM_IA]);
    pin.w_rad_s_q16 = q16(g_sim.meas.value[CANFDI_SIM_S_DCM_SPEED]);
    pin.load_Nm_q16 = q16(LOAD_NM);
    o = canfdi_parity_dcm_step(p, &pin);
    ck_assert_ptr_nonnull(o);
    if (t_next >= r->t_eval_s) {
      const double ra_err = fabs(((double)o->ra_hat_ohm_q24 / 16777216.0) - g_sim.dcm.ra_ohm);
      if (!r->split || (t_next < r->t_fault_s)) {
        win_add(&res->pre, o);
        res->ra_at_fault = (double)o->ra_hat_ohm_q24 / 16777216.0;
        if (ra_err > res->max_ra_err) {
          res->max_ra_err = ra_err;
        }
      } else if (t_next >= r->t_fault_s + r->t_skip_s) {
        if (res->post.n[0] + res->post.n[1] == 0L) {
          res->ra_at_fault = (double)o->ra_hat_ohm_q24 / 16777216.0; /* if no pre window */
        }
        win_add(&res->post, o);
      } else {
        /* onset transient: not evaluated */
      }
    }
  }
  res->ra_end = (double)canfdi_parity_dcm_out(p)->ra_hat_ohm_q24 / 16777216.0;
  res->ra_true_end = g_sim.dcm.ra_ohm;
}

static canfdi_parity_dcm_cfg_t g_cfg;
static canfdi_parity_dcm_t g_p;

static void init_default(void)
{
  canfdi_parity_dcm_default_cfg(&g_cfg);
  ck_assert_int_eq(canfdi_parity_dcm_init(&g_p, &g_cfg), CANFDI_OK);
}

static void base_run(run_t *r)
{
  memset(r, 0, sizeof(*r));
  r->seed = 11U;
  r->profile = PROFILE_SINE;
  r->thermal = false;
  r->init_temp_C = -200.0;
  r->fault_id = -1;
  r->t_end_s = 12.0;
  r->t_eval_s = 3.0; /* R_A learning (20 blocks) is over after ~2.1 s */
  r->t_fault_s = 7.0;
  r->t_skip_s = 0.3;
}

/* ---- configuration ------------------------------------------------------- */

START_TEST(default_cfg_valid)
{
  canfdi_parity_dcm_cfg_t c;
  canfdi_parity_dcm_default_cfg(&c);
  ck_assert_int_eq(canfdi_parity_dcm_cfg_check(&c), CANFDI_OK);
  ck_assert_int_eq(canfdi_parity_dcm_cfg_check(NULL), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_parity_dcm_init(NULL, &c), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_parity_dcm_init(&g_p, NULL), -CANFDI_EINVAL);
  ck_assert_ptr_null(canfdi_parity_dcm_step(&g_p, NULL));
  canfdi_parity_dcm_default_cfg(NULL); /* no-op */
}
END_TEST

/* One field broken per case: each must be rejected, and init must leave
 * the instance unbound (step refuses it). */
static void break_cfg(canfdi_parity_dcm_cfg_t *c, int i)
{
  switch (i) {
  case 0: c->ra_ohm_q24 = 0; break;
  case 1: c->la_H_q24 = 0; break;
  case 2: c->psi_Vs_q24 = 1; break;
  case 3: c->j_kgm2_q24 = -5; break;
  case 4: c->mf1_Nms_q24 = -1; break;
  case 5: c->mf0_Nm_q24 = INT32_MAX; break;
  case 6: c->omega_c_rad_s = 10; break;
  case 7: c->omega_c_rad_s = 1001; break;
  case 8: c->w_band_rad_s_q16 = 0; break;
  case 9: c->band[2].base = 0; break;
  case 10: c->band[1].max = c->band[1].base - 1; break;
  case 11: c->ra_block_steps = 5U; break;
  case 12: c->ra_tau_s = 0U; break;
  case 13: c->ra_i_min_A_q16 = 0; break;
  case 14: c->ra_min_ohm_q24 = c->ra_ohm_q24 + 1; break;
  case 15: c->ra_max_ohm_q24 = c->ra_ohm_q24 - 1; break;
  case 16: c->ra_gate_q16 = 0; break;
  case 17: c->load_tau_s = CANFDI_PARITY_DCM_TAU_MAX_S + 1U; break;
  case 18: c->unc_ra_ohm_q24 = -1; break;
  case 19: c->unc_la_H_q24 = c->la_H_q24 + 1; break;
  case 20: c->unc_j_kgm2_q24 = -1; break;
  default: c->ra_rate_max_ohm_s_q24 = -1; break;
  }
}

START_TEST(invalid_cfg_rejected)
{
  canfdi_parity_dcm_cfg_t c;
  canfdi_parity_dcm_in_t in = {0, 0, 0, 0};
  canfdi_parity_dcm_default_cfg(&c);
  ck_assert_int_eq(canfdi_parity_dcm_init(&g_p, &c), CANFDI_OK);
  break_cfg(&c, _i);
  ck_assert_int_eq(canfdi_parity_dcm_cfg_check(&c), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_parity_dcm_init(&g_p, &c), -CANFDI_EINVAL);
  ck_assert_ptr_null(canfdi_parity_dcm_step(&g_p, &in));
  ck_assert_ptr_null(canfdi_parity_dcm_out(&g_p));
  ck_assert_int_eq(canfdi_parity_dcm_set_ra(&g_p, 1 << 24), -CANFDI_EINVAL);
}
END_TEST

START_TEST(tracking_off_accepts_odd_tracker_fields)
{
  canfdi_parity_dcm_cfg_t c;
  canfdi_parity_dcm_default_cfg(&c);
  c.ra_track = 0U;
  c.ra_block_steps = 0U; /* irrelevant when not tracking */
  ck_assert_int_eq(canfdi_parity_dcm_cfg_check(&c), CANFDI_OK);
}
END_TEST

/* ---- fault-free operation ------------------------------------------------ */

START_TEST(fault_free_inside_band)
{
  run_t r;
  run_res_t res;
  unsigned j;
  const canfdi_parity_dcm_diag_t *d;
  base_run(&r);
  r.profile = (_i == 0) ? PROFILE_SINE : PROFILE_STEPS;
  r.seed = 21U + (uint64_t)_i;
  r.t_end_s = 20.0;
  init_default();
  run_closed_loop(&r, &g_p, &res);
  d = canfdi_parity_dcm_diag(&g_p);
  printf("dcm fault-free (%s): R_A est %.4f (true %.4f), max |dR_A| %.4f Ohm\n",
         (_i == 0) ? "sine" : "steps", res.ra_end, res.ra_true_end, res.max_ra_err);
  for (j = 0U; j < N_RES; j++) {
    printf("  %-7s mean %+.5f sigma %.5f  max|r|/thr %.2f  (n %ld)\n", res_name[j],
           win_mean(&res.pre, j), win_sd(&res.pre, j), res.pre.max_rn[j], res.pre.n[j]);
    /* r2..r4 stay valid at 80..130 rad/s; every residual must have been
     * evaluated over nearly the whole window. */
    ck_assert_msg(res.pre.n[j] > 16000L, "%s evaluated only %ld times", res_name[j],
                  res.pre.n[j]);
    ck_assert_msg(res.pre.exceed[j] == 0L, "%s left its band %ld times (max %.2f)", res_name[j],
                  res.pre.exceed[j], res.pre.max_rn[j]);
  }
  /* Learning from the 1.52 Ohm start value converged to the cold 1.35. */
  ck_assert_msg(res.max_ra_err < 0.02, "R_A error %.4f", res.max_ra_err);
  ck_assert_uint_eq(d->res_saturations, 0U);
  ck_assert_uint_gt(d->ra_updates, 100U);
}
END_TEST

/* ---- faults: the structure table ----------------------------------------- */

/* expected per residual: +1/-1 beyond the band with that sign, 0 decoupled
 * (must stay inside the band), 2 weakly coupled (not asserted). */
typedef struct {
  const char *name;
  int fault_id;
  double magnitude;
  double load_offset_Nm;
  int expect[N_RES];
} fault_case_t;

static const fault_case_t fault_cases[] = {
    {"U_A offset +1.2 V", CANFDI_FAULT_DCM_UA_SENSOR_OFFSET, 1.2, 0.0, {+1, 0, 2, +1}},
    {"U_A offset -1.2 V", CANFDI_FAULT_DCM_UA_SENSOR_OFFSET, -1.2, 0.0, {-1, 0, 2, -1}},
    {"I_A offset +0.6 A", CANFDI_FAULT_DCM_IA_SENSOR_OFFSET, 0.6, 0.0, {-1, +1, +1, 0}},
    {"I_A offset -0.6 A", CANFDI_FAULT_DCM_IA_SENSOR_OFFSET, -0.6, 0.0, {+1, -1, -1, 0}},
    {"w offset +8 rad/s", CANFDI_FAULT_DCM_SPEED_SENSOR_OFFSET, 8.0, 0.0, {-1, 2, 0, -1}},
    {"w offset -8 rad/s", CANFDI_FAULT_DCM_SPEED_SENSOR_OFFSET, -8.0, 0.0, {+1, 2, 0, +1}},
    {"w gain +2 %", CANFDI_FAULT_DCM_SPEED_SENSOR_GAIN, 0.02, 0.0, {-1, 2, 0, -1}},
    {"R_A +10 %", CANFDI_FAULT_DCM_RA_UP, 0.1, 0.0, {+1, 0, 2, +1}},
    {"Psi -10 %", CANFDI_FAULT_DCM_FLUX_DOWN, 0.1, 0.0, {-1, +1, +1, -1}},
    /* r4 sees friction through (R/Psi) f (M_F0 + M_F1 w) = 0.12 V at +20 %:
     * one band; asserted at the catalogue's +50 % */
    {"friction +20 %", CANFDI_FAULT_DCM_FRICTION_UP, 0.2, 0.0, {0, +1, +1, 2}},
    {"friction +50 %", CANFDI_FAULT_DCM_FRICTION_UP, 0.5, 0.0, {0, +1, +1, +1}},
    {"load +0.2 N m", -1, 0.0, 0.2, {0, +1, +1, +1}},
};

START_TEST(fault_moves_predicted_residuals)
{
  const fault_case_t *fc = &fault_cases[_i];
  run_t r;
  run_res_t res;
  unsigned j;
  base_run(&r);
  r.seed = 100U + (uint64_t)_i;
  r.fault_id = fc->fault_id;
  r.fault_mag = fc->magnitude;
  r.split = true;
  init_default();
  if (fabs(fc->load_offset_Nm) > 0.0) {
    /* the load "fault": the true load is above the input throughout; the
     * whole evaluated run is the post window */
    r.load_offset_Nm = fc->load_offset_Nm;
    r.t_fault_s = r.t_eval_s; /* everything after learning is "post" */
  }
  run_closed_loop(&r, &g_p, &res);
  printf("dcm fault %-18s:", fc->name);
  for (j = 0U; j < N_RES; j++) {
    const double sd = win_sd(&res.pre, j);
    printf("  %s %+.4f (%+.0f sd, %3.0f %% out)", res_name[j], win_mean(&res.post, j),
           (sd > 0.0) ? (win_mean(&res.post, j) - win_mean(&res.pre, j)) / sd : 0.0,
           (res.post.n[j] > 0) ? 100.0 * (double)res.post.exceed[j] / (double)res.post.n[j] : 0.0);
  }
  printf("  R_A %.4f->%.4f\n", res.ra_at_fault, res.ra_end);
  (void)fflush(stdout);
  for (j = 0U; j < N_RES; j++) {
    const double m = win_mean(&res.post, j);
    ck_assert_msg(res.post.n[j] > 3000L, "%s: %s evaluated %ld times", fc->name, res_name[j],
                  res.post.n[j]);
    if ((fc->expect[j] == 1) || (fc->expect[j] == -1)) {
      /* beyond the band on average and most of the time, with the sign */
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
      /* weakly coupled: reported only */
    }
  }
  /* The R_A tracker must not absorb a fault: the gate froze it. */
  ck_assert_msg(fabs(res.ra_end - res.ra_at_fault) < 0.005, "%s: R_A moved %.4f -> %.4f",
                fc->name, res.ra_at_fault, res.ra_end);
}
END_TEST

/* ---- warm-up and the adaptive R_A ---------------------------------------- */

/*
 * A 2 h warm-up at 1 kHz is 7.2 million plant steps: too slow for a unit
 * test under the sanitizers. The thermal capacitance is divided by 10
 * (tau_th ~43 min -> ~4.3 min, the same 1.35 -> ~1.5 Ohm rise in ~12 min
 * instead of ~2 h), and the tracker's time scales with it (tau 6 s
 * instead of 60 s, rate bound 5 mOhm/s instead of 0.5): the separation of
 * time scales (tracker ~20 x faster than the drift, fault step ~1000 x
 * faster than the tracker) is the same as with the real time constants.
 */
#define WARM_SCALE 10.0

START_TEST(warm_up_absorbed_fault_still_seen)
{
  run_t r;
  run_res_t res;
  unsigned j;
  const bool tracking = (_i == 0);
  base_run(&r);
  r.seed = 31U;
  r.thermal = true;
  r.cth_J_K = 2000.0 / WARM_SCALE;
  r.t_end_s = 15.0 * 60.0 + 40.0;
  r.t_fault_s = 15.0 * 60.0;
  r.t_skip_s = 0.3;
  r.fault_id = tracking ? (int)CANFDI_FAULT_DCM_RA_UP : -1;
  r.split = tracking;
  r.fault_mag = 0.1;
  canfdi_parity_dcm_default_cfg(&g_cfg);
  g_cfg.ra_tau_s = (uint32_t)lround(60.0 / WARM_SCALE);
  g_cfg.ra_rate_max_ohm_s_q24 = (int32_t)lround(0.0005 * WARM_SCALE * 16777216.0);
  if (!tracking) {
    g_cfg.ra_track = 0U;
    g_cfg.ra_ohm_q24 = (int32_t)lround(1.35 * 16777216.0); /* right when cold */
  }
  ck_assert_int_eq(canfdi_parity_dcm_init(&g_p, &g_cfg), CANFDI_OK);
  run_closed_loop(&r, &g_p, &res);
  printf("dcm warm-up x%.0f (%s): true R_A 1.35 -> %.4f Ohm; estimate %.4f at the fault, max "
         "|error| %.4f Ohm before it\n",
         WARM_SCALE, tracking ? "tracking" : "fixed R_A", res.ra_true_end, res.ra_at_fault,
         res.max_ra_err);
  for (j = 0U; j < N_RES; j++) {
    printf("  %-7s warm-up max|r|/thr %.2f (%ld out)", res_name[j], res.pre.max_rn[j],
           res.pre.exceed[j]);
    if (tracking) {
      printf("  after R_A +10 %%: mean %+.4f, %.0f %% out", win_mean(&res.post, j),
             (res.post.n[j] > 0) ? 100.0 * (double)res.post.exceed[j] / (double)res.post.n[j]
                                 : 0.0);
    }
    printf("\n");
  }
  (void)fflush(stdout);
  ck_assert_msg(res.ra_true_end > 1.47, "the warm-up did not happen: %.4f", res.ra_true_end);
  if (tracking) {
    for (j = 0U; j < N_RES; j++) {
      ck_assert_msg(res.pre.exceed[j] == 0L, "warm-up: %s left the band (max %.2f)", res_name[j],
                    res.pre.max_rn[j]);
    }
    ck_assert_msg(res.max_ra_err < 0.01, "tracker lag %.4f Ohm", res.max_ra_err);
    /* abrupt +10 %: r1 and r4 out for the whole 40 s; the tracker frozen */
    ck_assert_msg(res.post.exceed[0] * 100L > res.post.n[0] * 99L, "r1 out only %ld/%ld",
                  res.post.exceed[0], res.post.n[0]);
    ck_assert_msg(res.post.exceed[3] * 100L > res.post.n[3] * 99L, "r4 out only %ld/%ld",
                  res.post.exceed[3], res.post.n[3]);
    ck_assert_msg(fabs(res.ra_end - res.ra_at_fault) < 0.005, "R_A absorbed the fault: %.4f",
                  res.ra_end);
  } else {
    /* without tracking the same warm-up drives r1 and r4 out of the band */
    ck_assert_msg(res.pre.exceed[0] > 1000L, "fixed R_A: r1 out %ld", res.pre.exceed[0]);
    ck_assert_msg(res.pre.exceed[3] > 1000L, "fixed R_A: r4 out %ld", res.pre.exceed[3]);
  }
}
END_TEST

/* ---- load as a slowly varying unknown ------------------------------------ */

START_TEST(load_tracking_keeps_decoupling)
{
  run_t r;
  run_res_t res;
  base_run(&r);
  r.seed = 41U;
  r.load_offset_Nm = 0.3; /* the input is 0.3 N m below the true load */
  r.t_end_s = 20.0;
  canfdi_parity_dcm_default_cfg(&g_cfg);
  g_cfg.load_tau_s = 1U;
  ck_assert_int_eq(canfdi_parity_dcm_init(&g_p, &g_cfg), CANFDI_OK);
  r.t_eval_s = 12.0; /* > 3 tau after the start of evaluation of r2..r4 */
  run_closed_loop(&r, &g_p, &res);
  printf("dcm load tracking (tau 1 s, load 0.3 N m above input): r2 %+.4f r3 %+.4f r4 %+.4f, "
         "max |r|/thr %.2f %.2f %.2f\n",
         win_mean(&res.pre, 1), win_mean(&res.pre, 2), win_mean(&res.pre, 3), res.pre.max_rn[1],
         res.pre.max_rn[2], res.pre.max_rn[3]);
  ck_assert_int_eq(res.pre.exceed[1] + res.pre.exceed[2] + res.pre.exceed[3], 0);
  ck_assert_int_eq(res.pre.exceed[0], 0);
}
END_TEST

/* ---- reset, set_ra, extremes --------------------------------------------- */

/*
 * The uncertainty bands (header, "Thresholds"): in steady state only the
 * dR terms remain, threshold = base + dR |I| for r1 and base + dR |z| / Psi
 * (+ the tiny M_F1 w term) for r4, r2 exactly base: the bands stay tight.
 * In a current ramp the dL term adds dL |dI/dt|. Inputs are noise-free
 * synthetic samples; the SVFs are exact for a constant and converge to a
 * ramp's slope within ~5/wc, so the expected values hold to a few LSB
 * (steady) and to 5 % of the slope term (ramp, 100 ms = 10/wc after its
 * start).
 */
START_TEST(uncertainty_band_tight_steady_wide_transient)
{
  const double R = 1.52, psi = 0.33, i0 = 4.0, w0 = 100.0, ml = 1.2;
  double base1, base2, base4, dR, dL, z, thr1, thr2, thr4, slope;
  canfdi_parity_dcm_in_t in;
  const canfdi_parity_dcm_out_t *o = NULL;
  unsigned k;
  init_default(); /* first: the bases below are the defaults' */
  base1 = fq16(g_cfg.band[0].base);
  base2 = fq16(g_cfg.band[1].base);
  base4 = fq16(g_cfg.band[3].base);
  dR = (double)g_cfg.unc_ra_ohm_q24 / 16777216.0;
  dL = (double)g_cfg.unc_la_H_q24 / 16777216.0;
  ck_assert(dR > 0.0);
  ck_assert(dL > 0.0);
  in.u_V_q16 = q16(R * i0 + psi * w0);
  in.i_A_q16 = q16(i0);
  in.w_rad_s_q16 = q16(w0);
  in.load_Nm_q16 = q16(ml);
  for (k = 0U; k < 500U; k++) {
    o = canfdi_parity_dcm_step(&g_p, &in);
  }
  z = ml + (double)g_cfg.mf0_Nm_q24 / 16777216.0; /* w > w_band: sgn 1 */
  thr1 = fq16(o->thr_q16[0]);
  thr2 = fq16(o->thr_q16[1]);
  thr4 = fq16(o->thr_q16[3]);
  ck_assert_msg(fabs(thr1 - (base1 + dR * i0)) < 3.0 / 65536.0, "r1 band %.5f, expected %.5f", thr1,
                base1 + dR * i0);
  ck_assert_msg(fabs(thr2 - base2) < 1.0 / 65536.0, "r2 band %.5f, expected base %.5f", thr2, base2);
  /* r4: dR (z + M_F1 w) / Psi, M_F1 w = 0.036 N m */
  {
    const double e4 = base4 + dR * (z + 0.36e-3 * w0) / psi;
    ck_assert_msg(fabs(thr4 - e4) < 3.0 / 65536.0, "r4 band %.5f, expected %.5f", thr4, e4);
  }
  /* every band tight in steady state: at most base + 1.5 dR-terms at 4 A */
  ck_assert(thr1 < 1.5 * base1);
  /* a 2 %-of-full-scale I_A offset (0.6 A) moves r1 by R 0.6 = 0.91 V: far
   * outside the steady band */
  ck_assert(R * 0.6 > 5.0 * thr1);

  /* Current ramp 0 -> 10 A at 100 A/s with only dL: r1 band = base + dL dI */
  g_cfg.unc_ra_ohm_q24 = 0;
  g_cfg.unc_j_kgm2_q24 = 0;
  ck_assert_int_eq(canfdi_parity_dcm_init(&g_p, &g_cfg), CANFDI_OK);
  slope = 100.0;
  for (k = 0U; k <= 100U; k++) {
    const double i = slope * 1e-3 * (double)k;
    in.i_A_q16 = q16(i);
    in.u_V_q16 = q16(R * i + ((double)g_cfg.la_H_q24 / 16777216.0) * slope + psi * w0);
    o = canfdi_parity_dcm_step(&g_p, &in);
  }
  thr1 = fq16(o->thr_q16[0]);
  thr2 = fq16(o->thr_q16[1]);
  ck_assert_msg(fabs(thr1 - (base1 + dL * slope)) < 0.05 * dL * slope, "r1 band in ramp %.6f, expected %.6f",
                thr1, base1 + dL * slope);
  ck_assert_msg(fabs(thr2 - base2) < 1.0 / 65536.0, "r2 band %.5f (dJ = 0)", thr2);
  init_default(); /* g_cfg restored for the next test */
}
END_TEST

START_TEST(reset_restarts_settling_keeps_ra)
{
  canfdi_parity_dcm_in_t in = {q16(38.0), q16(4.0), q16(100.0), q16(1.2)};
  const canfdi_parity_dcm_out_t *o = NULL;
  unsigned k;
  init_default();
  ck_assert_int_eq(canfdi_parity_dcm_set_ra(&g_p, (int32_t)lround(1.40 * 16777216.0)), CANFDI_OK);
  ck_assert_int_eq(canfdi_parity_dcm_set_ra(&g_p, (int32_t)lround(9.0 * 16777216.0)), CANFDI_OK);
  ck_assert_int_eq(canfdi_parity_dcm_out(&g_p)->ra_hat_ohm_q24, g_cfg.ra_max_ohm_q24);
  ck_assert_int_eq(canfdi_parity_dcm_set_ra(&g_p, 0), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_parity_dcm_set_ra(NULL, 1 << 24), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_parity_dcm_set_ra(&g_p, (int32_t)lround(1.40 * 16777216.0)), CANFDI_OK);
  /* Constant inputs: consistent with R_A = (38 - 33) / 4 = 1.25 Ohm. */
  for (k = 1U; k <= g_cfg.settle_steps; k++) {
    o = canfdi_parity_dcm_step(&g_p, &in);
    ck_assert_ptr_nonnull(o);
    /* r2, r3 valid once settled (|w| >= w_band from the start); r1 and r4
     * wait for the R_A learning phase */
    ck_assert_uint_eq(o->valid, (k == g_cfg.settle_steps) ? 0x06U : 0U);
  }
  /* the first block holds unsettled samples and is rejected */
  for (k = 0U; k < ((unsigned)g_cfg.ra_learn_blocks + 1U) * g_cfg.ra_block_steps; k++) {
    o = canfdi_parity_dcm_step(&g_p, &in);
  }
  ck_assert_uint_eq(o->valid, 0x0FU);
  /* 20 blocks of a quarter of the error: 0.15 * 0.75^20 = 0.5 mOhm left */
  ck_assert_msg(fabs(((double)o->ra_hat_ohm_q24 / 16777216.0) - 1.25) < 0.002, "R_A %.5f",
                (double)o->ra_hat_ohm_q24 / 16777216.0);
  {
    const int32_t ra_before = o->ra_hat_ohm_q24;
    canfdi_parity_dcm_reset(&g_p);
    ck_assert_uint_eq(canfdi_parity_dcm_out(&g_p)->valid, 0U);
    ck_assert_uint_eq(canfdi_parity_dcm_diag(&g_p)->resets, 1U);
    ck_assert_int_eq(canfdi_parity_dcm_out(&g_p)->ra_hat_ohm_q24, ra_before);
    /* after a reset R_A is learnt again: r1/r4 wait past the settling */
    for (k = 1U; k <= 2U * g_cfg.settle_steps; k++) {
      o = canfdi_parity_dcm_step(&g_p, &in);
    }
    ck_assert_uint_eq(o->valid, 0x06U);
    /* a restart during that learning restarts it; once it has finished, a
     * restart keeps it finished: r1/r4 valid again right after settling */
    canfdi_parity_dcm_restart(&g_p);
    for (k = 1U; k <= 2U * g_cfg.settle_steps; k++) {
      o = canfdi_parity_dcm_step(&g_p, &in);
    }
    ck_assert_uint_eq(o->valid, 0x06U);
    for (k = 0U; k < ((unsigned)g_cfg.ra_learn_blocks + 1U) * g_cfg.ra_block_steps; k++) {
      o = canfdi_parity_dcm_step(&g_p, &in);
    }
    ck_assert_uint_eq(o->valid, 0x0FU);
    canfdi_parity_dcm_restart(&g_p);
    ck_assert_uint_eq(canfdi_parity_dcm_diag(&g_p)->resets, 3U);
    for (k = 1U; k <= g_cfg.settle_steps; k++) {
      o = canfdi_parity_dcm_step(&g_p, &in);
    }
    ck_assert_uint_eq(o->valid, 0x0FU);
  }
  canfdi_parity_dcm_reset(NULL);
  canfdi_parity_dcm_restart(NULL);
}
END_TEST

/* Late load (header): a change of the known load makes r2..r4 invalid for
 * exactly load_hold_steps steps, from the step that carries the new value;
 * r1 (no M_L) stays valid; 0 disables; the first sample only records the
 * load (no hold at start-up). */
START_TEST(late_load_holds_r2_r4)
{
  canfdi_parity_dcm_in_t in = {q16(38.0), q16(4.0), q16(100.0), q16(1.2)};
  const canfdi_parity_dcm_out_t *o = NULL;
  unsigned k;
  canfdi_parity_dcm_default_cfg(&g_cfg);
  g_cfg.ra_track = 0U;
  g_cfg.load_hold_steps = 113U;
  ck_assert_int_eq(canfdi_parity_dcm_init(&g_p, &g_cfg), CANFDI_OK);
  for (k = 0U; k < 200U; k++) {
    o = canfdi_parity_dcm_step(&g_p, &in);
  }
  ck_assert_uint_eq(o->valid, 0x0FU);
  ck_assert_uint_eq(canfdi_parity_dcm_diag(&g_p)->load_holds, 0U);
  in.load_Nm_q16 = q16(1.6);
  for (k = 1U; k <= 113U; k++) {
    o = canfdi_parity_dcm_step(&g_p, &in);
    ck_assert_uint_eq(o->valid, 0x01U);
  }
  o = canfdi_parity_dcm_step(&g_p, &in);
  ck_assert_uint_eq(o->valid, 0x0FU);
  ck_assert_uint_eq(canfdi_parity_dcm_diag(&g_p)->load_holds, 1U);
  /* off: the same change leaves validity alone */
  g_cfg.load_hold_steps = 0U;
  ck_assert_int_eq(canfdi_parity_dcm_init(&g_p, &g_cfg), CANFDI_OK);
  for (k = 0U; k < 200U; k++) {
    o = canfdi_parity_dcm_step(&g_p, &in);
  }
  in.load_Nm_q16 = q16(1.2);
  o = canfdi_parity_dcm_step(&g_p, &in);
  ck_assert_uint_eq(o->valid, 0x0FU);
  init_default();
}
END_TEST

START_TEST(extreme_inputs_saturate)
{
  static const int32_t vals[] = {INT32_MIN, -1, 0, 1, INT32_MAX, -2000000000, 2000000000};
  const unsigned nv = (unsigned)(sizeof(vals) / sizeof(vals[0]));
  unsigned k;
  uint32_t lcg = 12345U;
  init_default();
  for (k = 0U; k < 20000U; k++) {
    canfdi_parity_dcm_in_t in;
    const canfdi_parity_dcm_out_t *o;
    unsigned j;
    lcg = (lcg * 1103515245U) + 12345U;
    in.u_V_q16 = vals[(lcg >> 8) % nv];
    in.i_A_q16 = vals[(lcg >> 12) % nv];
    in.w_rad_s_q16 = vals[(lcg >> 16) % nv];
    in.load_Nm_q16 = vals[(lcg >> 20) % nv];
    o = canfdi_parity_dcm_step(&g_p, &in);
    ck_assert_ptr_nonnull(o);
    for (j = 0U; j < N_RES; j++) {
      ck_assert_int_gt(o->thr_q16[j], 0);
      ck_assert_int_le(o->thr_q16[j], g_cfg.band[j].max);
    }
    ck_assert_int_ge(o->ra_hat_ohm_q24, g_cfg.ra_min_ohm_q24);
    ck_assert_int_le(o->ra_hat_ohm_q24, g_cfg.ra_max_ohm_q24);
  }
  ck_assert_uint_gt(canfdi_parity_dcm_diag(&g_p)->res_saturations, 0U);
  ck_assert_uint_eq(canfdi_parity_dcm_diag(&g_p)->steps, 20000U);
}
END_TEST

static Suite *make_suite(void)
{
  Suite *s = suite_create("parity_dcm");
  TCase *tc;

  tc = tcase_create("config");
  tcase_add_test(tc, default_cfg_valid);
  tcase_add_loop_test(tc, invalid_cfg_rejected, 0, 22);
  tcase_add_test(tc, tracking_off_accepts_odd_tracker_fields);
  suite_add_tcase(s, tc);

  tc = tcase_create("fault_free");
  tcase_set_timeout(tc, 120);
  tcase_add_loop_test(tc, fault_free_inside_band, 0, 2);
  tcase_add_test(tc, uncertainty_band_tight_steady_wide_transient);
  tcase_add_test(tc, load_tracking_keeps_decoupling);
  suite_add_tcase(s, tc);

  tc = tcase_create("structure");
  tcase_set_timeout(tc, 300);
  tcase_add_loop_test(tc, fault_moves_predicted_residuals, 0,
                      (int)(sizeof(fault_cases) / sizeof(fault_cases[0])));
  suite_add_tcase(s, tc);

  tc = tcase_create("adaptive_ra");
  tcase_set_timeout(tc, 600);
  tcase_add_loop_test(tc, warm_up_absorbed_fault_still_seen, 0, 2);
  suite_add_tcase(s, tc);

  tc = tcase_create("robustness");
  tcase_add_test(tc, reset_restarts_settling_keeps_ra);
  tcase_add_test(tc, late_load_holds_r2_r4);
  tcase_add_test(tc, extreme_inputs_saturate);
  suite_add_tcase(s, tc);
  return s;
}

CANFDI_UNIT_MAIN(make_suite)
