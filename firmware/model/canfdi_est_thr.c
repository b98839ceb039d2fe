/*
 * canfdi_est_thr.c — throttle parameter estimator; see canfdi_est_thr.h.
 */
#include "model/canfdi_est_thr.h"

#include "core/canfdi_count.h"
#include "core/canfdi_fixp.h"
#include "core/canfdi_qconst.h"

/* torque bound of the fast test, N m (4x the valve's largest, K x 10 A) */
#define FAST_TQ_MAX_Q16 (16 * CANFDI_Q16_ONE)
#define HALF_T_Q31 CANFDI_Q31_RATIO(CANFDI_CFG_STEP_US, 2000000)

void canfdi_est_thr_default_cfg(canfdi_est_thr_cfg_t *cfg)
{
  CANFDI_ASSERT(cfg != NULL);
  cfg->svf.order = 3U;
  cfg->svf.omega_c_rad_s = 300;
  cfg->svf.outputs = 0U; /* each filter's own set at init */
  cfg->decim = 2U;
  cfg->forget_q31 = CANFDI_Q31_RATIO(5, 1000);
  cfg->mech_forget_q31 = CANFDI_Q31_RATIO(5, 10000);
  cfg->p0_q16 = 100 * CANFDI_Q16_ONE;
  cfg->trace_max_q16 = 1000 * CANFDI_Q16_ONE;
  cfg->excite_min_q16 = CANFDI_Q16_MILLI(1);
  cfg->excite_shift = 6U;
  cfg->conv_updates = 1000U;
  cfg->sign_band_q16 = CANFDI_Q16_MILLI(300);
  cfg->limp_band_q16 = CANFDI_Q16_DEG(2, 1);
  cfg->i_limit_q16 = CANFDI_Q16_MILLI(9900);
  cfg->holdoff_steps = 40U;
  cfg->r_nom_q16 = CANFDI_Q16_MILLI(1500);
  cfg->l_nom_q24 = CANFDI_Q24(15, 10000);
  cfg->k_nom_q16 = CANFDI_Q16_MILLI(383);
  cfg->u0_nom_q16 = 0;
  cfg->j_nom_q24 = CANFDI_Q24(21, 10000);
  cfg->b_nom_q24 = CANFDI_Q24(88, 10000);
  cfg->spring_nom_q24 = CANFDI_Q24(87, 1000);
  cfg->pretension_nom_q16 = CANFDI_Q16_MILLI(396);
  cfg->friction_nom_q16 = CANFDI_Q16_MILLI(284);
  cfg->limp_home_q16 = CANFDI_Q16_DEG(65, 10);
  cfg->fast_shift = 6U;
  cfg->fast_min_updates = 100U;
  cfg->fast_sep_min_q16 = CANFDI_Q16_MILLI(250);
  cfg->fast_stale_steps = 500U;
  cfg->fast_pair_steps = 300U;
}

/* EW mean m += (x - m) 2^-shift, Q32; rounded. Scaling and overflow: the
 * fast test's products are squares in [0, 2^62] or below 2^52 in
 * magnitude (|c|, |r| <= 16 N m, clamped in fast_update; s any int32_t),
 * and so is each mean (a convex combination of them, rounded), so x - m
 * and the sum stay inside int64_t: no saturation can act, and none is
 * paid for (five of these every mechanical update). */
static int64_t ew_q32(int64_t m, int64_t x, unsigned shift)
{
  return m + canfdi_asr64_rnd(x - m, shift);
}

/* One update of the fast structured test on the SVF outputs (header). */
static void fast_update(canfdi_est_thr_t *e, int32_t i_q16, int32_t a_q16, int32_t da_q16, int32_t d2a_q16,
                        int32_t s_q16)
{
  const canfdi_est_thr_cfg_t *c = &e->cfg;
  const unsigned sh = c->fast_shift;
  /* nominal spring torque c, Q16.16 N m */
  const int32_t cs = canfdi_clamp_s32(
      canfdi_add_s32_sat(canfdi_mul_s32_qn(c->spring_nom_q24, canfdi_sub_s32_sat(a_q16, c->limp_home_q16), 24U),
                         c->pretension_nom_q16),
      -FAST_TQ_MAX_Q16, FAST_TQ_MAX_Q16);
  int64_t r = (int64_t)canfdi_mul_s32_qn(c->k_nom_q16, i_q16, 16U);
  int32_t r_q16;
  r -= (int64_t)canfdi_mul_s32_qn(c->j_nom_q24, d2a_q16, 24U);
  r -= (int64_t)canfdi_mul_s32_qn(c->b_nom_q24, da_q16, 24U);
  r -= (int64_t)cs;
  r -= (int64_t)canfdi_mul_s32_qn(c->friction_nom_q16, s_q16, 16U);
  r_q16 = canfdi_sat_s64_to_s32(r);
  r_q16 = canfdi_clamp_s32(r_q16, -FAST_TQ_MAX_Q16, FAST_TQ_MAX_Q16);
  e->f_cc_q32 = ew_q32(e->f_cc_q32, canfdi_smull32(cs, cs), sh);
  e->f_cs_q32 = ew_q32(e->f_cs_q32, canfdi_smull32(cs, s_q16), sh);
  e->f_ss_q32 = ew_q32(e->f_ss_q32, canfdi_smull32(s_q16, s_q16), sh);
  e->f_cr_q32 = ew_q32(e->f_cr_q32, canfdi_smull32(cs, r_q16), sh);
  e->f_sr_q32 = ew_q32(e->f_sr_q32, canfdi_smull32(s_q16, r_q16), sh);
  e->f_n = (e->f_n < UINT16_MAX) ? (uint16_t)(e->f_n + 1U) : e->f_n;
  e->f_age = 0U;
  if (s_q16 > 0) {
    e->f_open_age = 0U;
  }
  e->f_paired = (s_q16 > 0) || (e->f_open_age <= c->fast_pair_steps);
  canfdi_count_inc(&e->diag.fast_updates);
  {
    /* Q32 -> Q24: |c|, |r| <= 16 N m, |s| <= 1: every product < 2^61 */
    const int64_t cc = canfdi_asr64_rnd(e->f_cc_q32, 8U);
    const int64_t cx = canfdi_asr64_rnd(e->f_cs_q32, 8U);
    const int64_t ss = canfdi_asr64_rnd(e->f_ss_q32, 8U);
    const int64_t cr = canfdi_asr64_rnd(e->f_cr_q32, 8U);
    const int64_t sr = canfdi_asr64_rnd(e->f_sr_q32, 8U);
    const int64_t ccss = canfdi_asr64_rnd(cc * ss, 16U); /* Q32 */
    const int64_t det = canfdi_sub_s64_sat(ccss, canfdi_asr64_rnd(cx * cx, 16U)); /* Q32 */
    e->f_sep = (ccss > 0) && (det > 0) &&
               (det >= canfdi_asr64_rnd(ccss * (int64_t)c->fast_sep_min_q16, 16U));
    if (e->f_sep) {
      const int64_t an = canfdi_sub_s64_sat(ss * cr, cx * sr); /* Q48 */
      const int64_t bn = canfdi_sub_s64_sat(cc * sr, cx * cr);
      /* Q48 / Q32 = Q16 */
      const int32_t b_q16 = canfdi_div_s64_sat_s32(bn, det);
      e->f_spring_dev_q16 = canfdi_div_s64_sat_s32(an, det);
      e->f_fric_dev_q16 = (c->friction_nom_q16 > 0) ? canfdi_div_s32_qn(b_q16, c->friction_nom_q16, 16U) : 0;
    }
  }
}

static void rls_cfg_common(canfdi_rls_cfg_t *rc, const canfdi_est_thr_cfg_t *cfg, uint8_t n)
{
  unsigned i;
  rc->n_params = n;
  rc->forget_q31 = cfg->forget_q31;
  rc->p0_q16 = cfg->p0_q16;
  rc->trace_max_q16 = cfg->trace_max_q16;
  rc->excite_min_q16 = cfg->excite_min_q16;
  rc->excite_shift = cfg->excite_shift;
  rc->excite_mask = 0U;
  for (i = 0U; i < CANFDI_CFG_RLS_MAX_PARAMS; i++) {
    rc->phi_shift[i] = 0;
    rc->theta0_q16[i] = 0;
  }
}

static void seed_nominal(canfdi_est_thr_t *e)
{
  const canfdi_est_thr_cfg_t *c = &e->cfg;
  /* (P - k_s theta_LH): Q24 x Q16 -> Q16 with a 24-bit rounding shift */
  const int32_t p_eff_q16 =
      canfdi_sub_s32_sat(c->pretension_nom_q16, canfdi_mul_s32_qn(c->spring_nom_q24, c->limp_home_q16, 24U));
  canfdi_rls_set_theta_qn(&e->el, 0U, c->r_nom_q16, 16U);
  canfdi_rls_set_theta_qn(&e->el, 1U, c->l_nom_q24, 24U);
  canfdi_rls_set_theta_qn(&e->el, 2U, c->k_nom_q16, 16U);
  canfdi_rls_set_theta_qn(&e->el, 3U, c->u0_nom_q16, 16U);
  /* x / K: Q24 (or Q16) / Q16 * 2^16 keeps the numerator's format */
  canfdi_rls_set_theta_qn(&e->mech, 0U, canfdi_div_s32_qn(c->j_nom_q24, c->k_nom_q16, 16U), 24U);
  canfdi_rls_set_theta_qn(&e->mech, 1U, canfdi_div_s32_qn(c->b_nom_q24, c->k_nom_q16, 16U), 24U);
  canfdi_rls_set_theta_qn(&e->mech, 2U, canfdi_div_s32_qn(c->spring_nom_q24, c->k_nom_q16, 16U), 24U);
  canfdi_rls_set_theta_qn(&e->mech, 3U, canfdi_div_s32_qn(p_eff_q16, c->k_nom_q16, 16U), 16U);
  canfdi_rls_set_theta_qn(&e->mech, 4U, canfdi_div_s32_qn(c->friction_nom_q16, c->k_nom_q16, 16U), 16U);
}

/* One of the estimator's filters, with the shared configuration and the
 * outputs this module reads of it. */
static int32_t svf_init_outputs(canfdi_svf_t *f, const canfdi_svf_cfg_t *shared, unsigned outputs)
{
  canfdi_svf_cfg_t c = *shared;
  c.outputs = (uint8_t)outputs;
  return canfdi_svf_init(f, &c);
}

int32_t canfdi_est_thr_init(canfdi_est_thr_t *e, const canfdi_est_thr_cfg_t *cfg)
{
  int32_t out = -CANFDI_EINVAL;
  if ((e != NULL) && (cfg != NULL) && (cfg->svf.order == 3U) && (cfg->decim >= 1U) && (cfg->decim <= 100U) &&
      (cfg->k_nom_q16 > 0) && (cfg->sign_band_q16 >= 0) && (cfg->limp_band_q16 >= 0) && (cfg->i_limit_q16 >= 0) &&
      (cfg->holdoff_steps >= 1U) && (cfg->holdoff_steps <= 1000U) && (cfg->fast_shift >= 1U) &&
      (cfg->fast_shift <= 12U) && (cfg->fast_sep_min_q16 >= 0) && (cfg->fast_sep_min_q16 <= CANFDI_Q16_ONE)) {
    canfdi_rls_cfg_t re;
    canfdi_rls_cfg_t rm;
    rls_cfg_common(&re, cfg, 4U);
    re.y_shift = CANFDI_EST_THR_SHIFT_U;
    re.phi_shift[0] = CANFDI_EST_THR_SHIFT_I;
    re.phi_shift[1] = CANFDI_EST_THR_SHIFT_DI;
    re.phi_shift[2] = CANFDI_EST_THR_SHIFT_DA;
    re.phi_shift[3] = 0;
    re.excite_mask = 0x5U; /* i and dtheta/dt must both vary */
    rls_cfg_common(&rm, cfg, 5U);
    rm.forget_q31 = cfg->mech_forget_q31;
    rm.y_shift = CANFDI_EST_THR_SHIFT_I;
    rm.phi_shift[0] = CANFDI_EST_THR_SHIFT_D2A;
    rm.phi_shift[1] = CANFDI_EST_THR_SHIFT_DA;
    rm.phi_shift[2] = CANFDI_EST_THR_SHIFT_A;
    rm.phi_shift[3] = 0;
    rm.phi_shift[4] = 0;
    rm.excite_mask = 0x6U; /* dtheta/dt and theta: sustained motion */
    if ((svf_init_outputs(&e->svf_u, &cfg->svf, CANFDI_SVF_OUT_Y | CANFDI_SVF_OUT_DY) == CANFDI_OK) &&
        (svf_init_outputs(&e->svf_i, &cfg->svf, CANFDI_SVF_OUT_Y | CANFDI_SVF_OUT_DY) == CANFDI_OK) &&
        (svf_init_outputs(&e->svf_a, &cfg->svf, CANFDI_SVF_OUT_ALL) == CANFDI_OK) &&
        (svf_init_outputs(&e->svf_s, &cfg->svf, CANFDI_SVF_OUT_Y) == CANFDI_OK) && (canfdi_rls_init(&e->el, &re) == CANFDI_OK) &&
        (canfdi_rls_init(&e->mech, &rm) == CANFDI_OK)) {
      e->cfg = *cfg;
      e->has_run = false;
      e->diag.steps = 0U;
      e->diag.el_updates = 0U;
      e->diag.mech_updates = 0U;
      e->diag.mech_lh_skips = 0U;
      e->diag.mech_still_skips = 0U;
      e->diag.clip_skips = 0U;
      e->diag.resets = 0U;
      e->diag.fast_updates = 0U;
      canfdi_est_thr_reset(e, false);
      e->diag.resets = 0U;
      out = CANFDI_OK;
    }
  }
  return out;
}

void canfdi_est_thr_reset(canfdi_est_thr_t *e, bool keep_theta)
{
  CANFDI_ASSERT(e != NULL);
  canfdi_rls_reset(&e->el, keep_theta);
  canfdi_rls_reset(&e->mech, keep_theta);
  if (!keep_theta) {
    seed_nominal(e);
  }
  e->phase = 0U;
  e->started = false;
  e->since_clip = 0U;
  e->moving = 0U;
  e->last_dir = 0;
  e->el_since_reset = 0U;
  e->mech_since_reset = 0U;
  e->f_cc_q32 = 0;
  e->f_cs_q32 = 0;
  e->f_ss_q32 = 0;
  e->f_cr_q32 = 0;
  e->f_sr_q32 = 0;
  e->f_spring_dev_q16 = 0;
  e->f_fric_dev_q16 = 0;
  e->f_n = 0U;
  e->f_age = UINT16_MAX;
  e->f_open_age = UINT16_MAX;
  e->f_sep = false;
  e->f_paired = false;
  canfdi_count_inc(&e->diag.resets);
}

/* Friction sign s (Q16.16: +1, -1, or 0 inside the dead band) from the
 * filtered velocity of the previous step, and the motion state: moving
 * counts the steps in one direction beyond the band. */
static int32_t est_thr_motion(canfdi_est_thr_t *e)
{
  const int32_t v = canfdi_svf_dy_q16(&e->svf_a);
  int32_t s = 0;
  int8_t dir;
  if (v > e->cfg.sign_band_q16) {
    s = CANFDI_Q16_ONE;
  } else if (v < -e->cfg.sign_band_q16) {
    s = -CANFDI_Q16_ONE;
  } else {
    /* inside the dead band: unknown, 0 */
  }
  dir = (s > 0) ? (int8_t)1 : ((s < 0) ? (int8_t)-1 : (int8_t)0);
  if ((dir == 0) || (dir != e->last_dir)) {
    e->moving = 0U;
  } else if (e->moving < UINT16_MAX) {
    e->moving = (uint16_t)(e->moving + 1U);
  } else {
    /* saturated counter */
  }
  e->last_dir = dir;
  return s;
}

/* since_clip: steps since the last current sample at or beyond i_limit. */
static void est_thr_clip(canfdi_est_thr_t *e, int32_t i_q16)
{
  if ((e->cfg.i_limit_q16 > 0) && ((i_q16 >= e->cfg.i_limit_q16) || (i_q16 <= -e->cfg.i_limit_q16))) {
    e->since_clip = 0U;
  } else if (e->since_clip < UINT16_MAX) {
    e->since_clip = (uint16_t)(e->since_clip + 1U);
  } else {
    /* saturated counter */
  }
}

/* The electrical update (phase 0), skipped during the clip hold-off. */
static void est_thr_el_update(canfdi_est_thr_t *e)
{
  if (e->since_clip < e->cfg.holdoff_steps) {
    canfdi_count_inc(&e->diag.clip_skips);
  } else {
    int32_t phi[4];
    const int32_t y = canfdi_add_s32_sat(canfdi_svf_y_q16(&e->svf_u),
                                         canfdi_mul_s32_qn(canfdi_svf_dy_q16(&e->svf_u), HALF_T_Q31, 31U));
    phi[0] = canfdi_svf_y_q16(&e->svf_i);
    phi[1] = canfdi_svf_dy_q16(&e->svf_i);
    phi[2] = canfdi_svf_dy_q16(&e->svf_a);
    phi[3] = CANFDI_Q16_ONE;
    if (canfdi_rls_update(&e->el, phi, y)) {
      e->updated |= CANFDI_EST_THR_UPD_EL;
      e->el_since_reset += (e->el_since_reset < UINT32_MAX) ? 1U : 0U;
      canfdi_count_inc(&e->diag.el_updates);
    }
  }
}

/* The mechanical update and the fast test (phase 1), behind the validity
 * gates of the header: clip hold-off, limp-home band, steady motion. */
static void est_thr_mech_update(canfdi_est_thr_t *e)
{
  const int32_t a = canfdi_svf_y_q16(&e->svf_a);
  if (e->since_clip < e->cfg.holdoff_steps) {
    canfdi_count_inc(&e->diag.clip_skips);
  } else if (a <= canfdi_add_s32_sat(e->cfg.limp_home_q16, e->cfg.limp_band_q16)) {
    canfdi_count_inc(&e->diag.mech_lh_skips);
  } else if (e->moving < e->cfg.holdoff_steps) {
    canfdi_count_inc(&e->diag.mech_still_skips);
  } else {
    int32_t phi[5];
    fast_update(e, canfdi_svf_y_q16(&e->svf_i), a, canfdi_svf_dy_q16(&e->svf_a), canfdi_svf_d2y_q16(&e->svf_a),
                canfdi_svf_y_q16(&e->svf_s));
    phi[0] = canfdi_svf_d2y_q16(&e->svf_a);
    phi[1] = canfdi_svf_dy_q16(&e->svf_a);
    phi[2] = a;
    phi[3] = CANFDI_Q16_ONE;
    phi[4] = canfdi_svf_y_q16(&e->svf_s);
    if (canfdi_rls_update(&e->mech, phi, canfdi_svf_y_q16(&e->svf_i))) {
      e->updated |= CANFDI_EST_THR_UPD_MECH;
      e->mech_since_reset += (e->mech_since_reset < UINT32_MAX) ? 1U : 0U;
      canfdi_count_inc(&e->diag.mech_updates);
    }
  }
}

void canfdi_est_thr_boost(canfdi_est_thr_t *e)
{
  CANFDI_ASSERT(e != NULL);
  canfdi_rls_boost(&e->el);
  canfdi_rls_boost(&e->mech);
}

uint8_t canfdi_est_thr_updated(const canfdi_est_thr_t *e)
{
  return e->updated;
}

void canfdi_est_thr_align(canfdi_est_thr_t *e, uint32_t k)
{
  CANFDI_ASSERT(e != NULL);
  e->phase = canfdi_phase_before(k, e->cfg.decim);
}

void canfdi_est_thr_step(canfdi_est_thr_t *e, int32_t u_q16, int32_t i_q16, int32_t angle_q16)
{
  CANFDI_ASSERT(e != NULL);
  e->updated = 0U;
  if (!e->started) {
    canfdi_svf_reset(&e->svf_u, u_q16);
    canfdi_svf_reset(&e->svf_i, i_q16);
    canfdi_svf_reset(&e->svf_a, angle_q16);
    canfdi_svf_reset(&e->svf_s, 0);
    e->started = true;
  } else {
    const int32_t s = est_thr_motion(e);
    est_thr_clip(e, i_q16);
    canfdi_svf_step(&e->svf_u, u_q16);
    canfdi_svf_step(&e->svf_i, i_q16);
    canfdi_svf_step(&e->svf_a, angle_q16);
    canfdi_svf_step(&e->svf_s, s);
    e->f_age = (e->f_age < UINT16_MAX) ? (uint16_t)(e->f_age + 1U) : e->f_age;
    e->f_open_age = (e->f_open_age < UINT16_MAX) ? (uint16_t)(e->f_open_age + 1U) : e->f_open_age;
    e->phase = (uint8_t)(e->phase + 1U);
    if (e->phase >= e->cfg.decim) {
      e->phase = 0U;
    }
    if (e->phase == 0U) {
      est_thr_el_update(e);
    }
    /* the mechanical update one step later (same step when decim == 1) */
    if (e->phase == ((e->cfg.decim > 1U) ? 1U : 0U)) {
      est_thr_mech_update(e);
    }
  }
  e->has_run = true;
  canfdi_count_inc(&e->diag.steps);
}

int32_t canfdi_est_thr_r_q16(const canfdi_est_thr_t *e)
{
  return canfdi_rls_theta_qn(&e->el, 0U, 16U);
}

int32_t canfdi_est_thr_l_q24(const canfdi_est_thr_t *e)
{
  return canfdi_rls_theta_qn(&e->el, 1U, 24U);
}

int32_t canfdi_est_thr_k_q16(const canfdi_est_thr_t *e)
{
  return canfdi_rls_theta_qn(&e->el, 2U, 16U);
}

int32_t canfdi_est_thr_u0_q16(const canfdi_est_thr_t *e)
{
  return canfdi_rls_theta_qn(&e->el, 3U, 16U);
}

static int32_t k_for_mech_q16(const canfdi_est_thr_t *e)
{
  return canfdi_est_thr_el_converged(e) ? canfdi_est_thr_k_q16(e) : e->cfg.k_nom_q16;
}

/* Scaling: Q16.16 K x Q24 (or Q16) ratio, rounded shift by 16, saturated. */
int32_t canfdi_est_thr_j_q24(const canfdi_est_thr_t *e)
{
  return canfdi_mul_s32_qn(k_for_mech_q16(e), canfdi_rls_theta_qn(&e->mech, 0U, 24U), 16U);
}

int32_t canfdi_est_thr_b_q24(const canfdi_est_thr_t *e)
{
  return canfdi_mul_s32_qn(k_for_mech_q16(e), canfdi_rls_theta_qn(&e->mech, 1U, 24U), 16U);
}

int32_t canfdi_est_thr_spring_q24(const canfdi_est_thr_t *e)
{
  return canfdi_mul_s32_qn(k_for_mech_q16(e), canfdi_rls_theta_qn(&e->mech, 2U, 24U), 16U);
}

/* P = K th3 + k_s theta_LH (Q24 x Q16 -> Q16 with a 24-bit shift) */
int32_t canfdi_est_thr_pretension_q16(const canfdi_est_thr_t *e)
{
  const int32_t p_eff = canfdi_mul_s32_qn(k_for_mech_q16(e), canfdi_rls_theta_qn(&e->mech, 3U, 16U), 16U);
  return canfdi_add_s32_sat(p_eff, canfdi_mul_s32_qn(canfdi_est_thr_spring_q24(e), e->cfg.limp_home_q16, 24U));
}

int32_t canfdi_est_thr_friction_q16(const canfdi_est_thr_t *e)
{
  return canfdi_mul_s32_qn(k_for_mech_q16(e), canfdi_rls_theta_qn(&e->mech, 4U, 16U), 16U);
}

int32_t canfdi_est_thr_fast_spring_dev_q16(const canfdi_est_thr_t *e)
{
  return e->f_spring_dev_q16;
}

int32_t canfdi_est_thr_fast_friction_dev_q16(const canfdi_est_thr_t *e)
{
  return e->f_fric_dev_q16;
}

bool canfdi_est_thr_fast_valid(const canfdi_est_thr_t *e)
{
  return e->f_sep && (e->f_n >= e->cfg.fast_min_updates) && (e->f_age <= e->cfg.fast_stale_steps);
}

bool canfdi_est_thr_fast_paired(const canfdi_est_thr_t *e)
{
  return canfdi_est_thr_fast_valid(e) && e->f_paired;
}

bool canfdi_est_thr_has_run(const canfdi_est_thr_t *e)
{
  return e->has_run;
}

bool canfdi_est_thr_excited(const canfdi_est_thr_t *e)
{
  return canfdi_rls_excited(&e->el);
}

bool canfdi_est_thr_el_converged(const canfdi_est_thr_t *e)
{
  return e->el_since_reset >= e->cfg.conv_updates;
}

bool canfdi_est_thr_mech_converged(const canfdi_est_thr_t *e)
{
  return e->mech_since_reset >= e->cfg.conv_updates;
}

const canfdi_rls_t *canfdi_est_thr_el_rls(const canfdi_est_thr_t *e)
{
  return &e->el;
}

const canfdi_rls_t *canfdi_est_thr_mech_rls(const canfdi_est_thr_t *e)
{
  return &e->mech;
}

const canfdi_est_thr_diag_t *canfdi_est_thr_diag(const canfdi_est_thr_t *e)
{
  return &e->diag;
}
