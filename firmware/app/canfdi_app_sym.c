/*
 * canfdi_app_sym.c — the symptom vector from the detection stage; the
 * manual is the header.
 */
#include "app/canfdi_app_sym.h"

#include "catalogue/canfdi_catalogue.h"
#include "core/canfdi_fixp.h"
#include "core/canfdi_qconst.h"
#include "detect/canfdi_limit.h"
#include "ft/canfdi_vote.h"

void canfdi_app_sym_default_cfg(canfdi_app_sym_cfg_t *cfg)
{
  if (cfg != NULL) {
    cfg->dcm_w_on_rad_s_q16 = 10 * CANFDI_Q16_ONE;
    cfg->dcm_i_on_A_q16 = CANFDI_Q16_MILLI(800);
    cfg->thr_u_on_V_q16 = CANFDI_Q16_ONE;
    cfg->thr_i_on_A_q16 = CANFDI_Q16_MILLI(100);
    cfg->mech_settle_steps = 1000U;
    cfg->w_jump_rad_s_q16 = CANFDI_Q16_MILLI(2500);
    cfg->w_jump_hold_steps = 50U;
    cfg->rax_quiet_steps = 50U; /* canfdi_diagnosis_default_cfg's sym_off_steps */
  }
}

int32_t canfdi_app_sym_init(canfdi_app_sym_t *m, const canfdi_app_sym_cfg_t *cfg)
{
  int32_t rc = -CANFDI_EINVAL;
  uint32_t i;
  if ((m != NULL) && (cfg != NULL) && (cfg->dcm_w_on_rad_s_q16 > 0) && (cfg->dcm_i_on_A_q16 > 0) &&
      (cfg->thr_u_on_V_q16 > 0) && (cfg->thr_i_on_A_q16 > 0) && (cfg->w_jump_rad_s_q16 > 0)) {
    m->cfg = *cfg;
    m->dcm_ref[0] = 0;
    m->dcm_ref[1] = 0;
    m->thr_ref[0] = 0;
    m->thr_ref[1] = 0;
    m->mech_hold = cfg->mech_settle_steps;
    m->w_prev_q16 = 0;
    m->w_prev_ok = false;
    m->jump_hold = 0U;
    m->jump = false;
    m->r1_mean_q32 = 0;
    m->e4_mean_q32 = 0;
    m->r1_est_q32 = 0;
    m->r1_est_w_q16 = 0;
    m->r1_quiet = 0U;
    for (i = 0U; i < CANFDI_APP_SYM_N_PDEV; i++) {
      m->pdev[i] = (canfdi_app_sym_quot_t){0, 0, 0};
    }
    rc = CANFDI_OK;
  }
  return rc;
}

/* The sign of x with hysteresis: counts from |x| >= on, 0 below on / 2. */
static int8_t ref_sign(int8_t prev, int32_t x, int32_t on)
{
  const int8_t s = (x >= 0) ? (int8_t)1 : (int8_t)-1;
  const int32_t mag = canfdi_q31_abs(x);
  int8_t out = 0;
  if (mag >= on) {
    out = s;
  } else if ((mag >= (on / 2)) && (prev == s)) {
    out = s;
  } else {
    /* too small to tell */
  }
  return out;
}

static void references(canfdi_app_sym_t *m, const canfdi_app_sym_in_t *in, canfdi_symptoms_t *s)
{
  const canfdi_app_sym_cfg_t *c = &m->cfg;
  const int8_t w = ref_sign(m->dcm_ref[0], in->dcm_w_rad_s_q16, c->dcm_w_on_rad_s_q16);
  if (w != m->dcm_ref[0]) {
    m->mech_hold = c->mech_settle_steps;
  } else if ((w == 0) && (m->mech_hold < c->mech_settle_steps)) {
    m->mech_hold = c->mech_settle_steps;
  } else if (m->mech_hold > 0U) {
    m->mech_hold--;
  } else {
    /* settled */
  }
  m->dcm_ref[0] = w;
  m->dcm_ref[1] = ref_sign(m->dcm_ref[1], in->dcm_i_A_q16, c->dcm_i_on_A_q16);
  m->thr_ref[0] = ref_sign(m->thr_ref[0], in->thr_u_V_q16, c->thr_u_on_V_q16);
  m->thr_ref[1] = ref_sign(m->thr_ref[1], in->thr_i_A_q16, c->thr_i_on_A_q16);
  s->dcm_ref[0] = m->dcm_ref[0];
  s->dcm_ref[1] = m->dcm_ref[1];
  s->thr_ref[0] = m->thr_ref[0];
  s->thr_ref[1] = m->thr_ref[1];
}

/* T in seconds, Q24 (the step of canfdi_config.h) */
#define STEP_S_Q24 ((int32_t)(((int64_t)CANFDI_CFG_STEP_US * 16777216 + 500000) / 1000000))

/* The speed-step plausibility of the header. Scaling: torque Q16.16 N m
 * (saturating sums); x T (Q24 s) / J (Q24 kg m^2): the product rounded to
 * Q16.16 N m s, divided by J in Q24 -> Q16.16 rad/s (saturating). */
static void speed_jump(canfdi_app_sym_t *m, const canfdi_app_sym_in_t *in, const canfdi_symptoms_t *s)
{
  const canfdi_est_dcm_cfg_t *c = &in->est_dcm->cfg;
  const bool ok = in->dcm_in_ok && in->dcm_fresh;
  bool jump_now = false;
  if (ok && m->w_prev_ok && (c->j_nom_q24 > 0)) {
    const int32_t mf0 = canfdi_sub_s32_sat(c->mc_nom_q16, in->load_nom_Nm_q16);
    int32_t torque = canfdi_sub_s32_sat(canfdi_mul_s32_qn(c->psi_nom_q16, in->dcm_i_A_q16, 16U),
                                        in->load_known_Nm_q16);
    if (m->dcm_ref[0] != 0) {
      torque = canfdi_sub_s32_sat(torque, (m->dcm_ref[0] > 0) ? mf0 : canfdi_q31_neg(mf0));
    }
    {
      const int32_t dw_exp = canfdi_div_s32_qn(canfdi_mul_s32_qn(torque, STEP_S_Q24, 24U), c->j_nom_q24, 24U);
      const int32_t dw = canfdi_sub_s32_sat(in->dcm_w_rad_s_q16, m->w_prev_q16);
      jump_now = canfdi_q31_abs(canfdi_sub_s32_sat(dw, dw_exp)) > m->cfg.w_jump_rad_s_q16;
    }
  }
  if (jump_now) {
    m->jump = true;
    m->jump_hold = m->cfg.w_jump_hold_steps;
  } else if (m->jump_hold > 0U) {
    m->jump_hold--;
  } else if (m->jump && ((s->dcm_rn_valid & 1U) != 0U) && (canfdi_q31_abs(s->dcm_rn_q16[0]) >= CANFDI_Q16_ONE)) {
    /* held while r1 stays out of its band */
  } else {
    m->jump = false;
  }
  m->w_prev_q16 = in->dcm_w_rad_s_q16;
  m->w_prev_ok = ok;
}

/* The UAC channel (canfdi_symptoms.h): while r1 is beyond its threshold,
 * (U_A - command) / (|r1| / 2), so that its scale follows r1's; else the
 * monitor's own normalisation. Scaling: Q16.16 V / Q16.16 V -> Q16.16
 * (saturating). */
static int32_t uac_channel(const canfdi_app_sym_in_t *in, const canfdi_symptoms_t *s)
{
  const canfdi_parity_dcm_out_t *pd = canfdi_parity_dcm_out(in->parity_dcm);
  int32_t x = in->actmon->dcm_uac_rn_q16;
  if (in->actmon->dcm_uac_valid && (pd != NULL) && ((s->dcm_rn_valid & 1U) != 0U) &&
      (canfdi_q31_abs(s->dcm_rn_q16[0]) >= CANFDI_Q16_ONE)) {
    x = canfdi_div_s32_qn(in->actmon->dcm_uac_V_q16, canfdi_q31_abs(pd->r_q16[0]) / 2, 16U);
  }
  return x;
}

/* num / den in Q16.16 (canfdi_div_s32_qn, saturating) for den != 0, the
 * quotient kept in *k while num and den stay the same. */
static int32_t div_kept_q16(canfdi_app_sym_quot_t *k, int32_t num, int32_t den)
{
  if ((num != k->num) || (den != k->den)) {
    k->q = canfdi_div_s32_qn(num, den, 16U);
    k->num = num;
    k->den = den;
  }
  return k->q;
}

/* (est - nom) / nom in Q16.16, saturating; both in the same Q format. */
static int32_t pdev_q16(canfdi_app_sym_quot_t *k, int32_t est, int32_t nom)
{
  return (nom != 0) ? div_kept_q16(k, canfdi_sub_s32_sat(est, nom), nom) : 0;
}

static void residuals(const canfdi_app_sym_in_t *in, canfdi_symptoms_t *s)
{
  const canfdi_parity_dcm_out_t *pd = canfdi_parity_dcm_out(in->parity_dcm);
  const canfdi_parity_thr_out_t *pt = canfdi_parity_thr_out(in->parity_thr);
  uint32_t i;
  for (i = 0U; i < CANFDI_SYM_N_RES; i++) {
    s->dcm_rn_q16[i] = (pd != NULL) ? pd->rn_q16[i] : 0;
    s->thr_rn_q16[i] = (pt != NULL) ? pt->rn_q16[i] : 0;
  }
  s->dcm_rn_valid = ((pd != NULL) && in->dcm_in_ok) ? pd->valid : 0U;
  s->thr_rn_valid = 0U;
  if ((pt != NULL) && in->thr_in_ok) {
    const uint8_t pos = (uint8_t)((1U << CANFDI_PARITY_THR_POS1) | (1U << CANFDI_PARITY_THR_POS2));
    s->thr_rn_valid = pt->valid;
    if (pt->no_ref) {
      /* POS1/POS2 no evidence while the observer has no angle of its own
       * (canfdi_parity_thr.h, no_ref): only the correlation is reported */
      s->thr_rn_valid = (uint8_t)(s->thr_rn_valid & (uint8_t)~pos);
    }
  }
}

static int32_t sgn_s32(int32_t x)
{
  return (x > 0) ? 1 : ((x < 0) ? -1 : 0);
}

/* r1 as the armature estimate sees it (RAX): the RLS with forgetting
 * lambda = 1 - forget weights its k-th last update by lambda^k, and a
 * boost or reset of its covariance drops the data before it, so the
 * estimate fits r1 averaged with those weights: on every armature update
 * W = lambda W + 1, mean += (r1 - mean) / W (W restarts at 0 with the
 * covariance; 1 / W falls from 1 to forget). An R_A change moves the
 * estimate by this mean / I_A, not by the r1 of this step: while R_A ramps
 * the estimate lags r1 by its memory (forget^-1 updates) times the ramp
 * rate, and compared with r1 itself an R_A ramp would read as unexplained.
 * Scaling: W Q16.16 (<= 1 / forget, 100 by default; Q16.16 holds 32767),
 * 1 / W in Q31 saturated at 1 - 2^-31; the mean in Q32 V as the other
 * means of this module. */
static void r1_est_mean(canfdi_app_sym_t *m, const canfdi_app_sym_in_t *in, const canfdi_symptoms_t *s)
{
  const canfdi_parity_dcm_out_t *pd = canfdi_parity_dcm_out(in->parity_dcm);
  if (in->dcm_est_restart) {
    m->r1_est_w_q16 = 0;
  }
  if ((pd != NULL) && in->dcm_in_ok && in->dcm_est_on && ((pd->valid & 1U) != 0U) &&
      ((s->dcm_upd & CANFDI_SYM_UPD_A) != 0U)) {
    const int32_t w = canfdi_add_s32_sat(
        canfdi_sub_s32_sat(m->r1_est_w_q16, canfdi_mul_s32_qn(m->r1_est_w_q16, in->est_dcm->cfg.forget_q31, 31U)),
        CANFDI_Q16_ONE);
    /* 1 / W in Q31: 2^47 / W_q16 (W >= 1), saturated below 1 */
    const canfdi_q31_t al = canfdi_div_s64_sat_s32((int64_t)1 << 47, w);
    const int64_t d = canfdi_sub_s64_sat((int64_t)pd->r_q16[0] * 65536, m->r1_est_q32);
    m->r1_est_q32 = canfdi_add_s64_sat(m->r1_est_q32, canfdi_mul_s64_q31(d, al));
    m->r1_est_w_q16 = w;
  }
}

/* RAX (canfdi_symptoms.h): (R_A,est - R_A,model) I_A / r1_est / 0.5, with
 * r1_est the r1 the estimate was fit on (r1_est_mean), while |r1| is
 * RAX_MIN_RN times its threshold or more and r1_est is beyond the
 * threshold with r1's sign; 0 once r1 has been below the diagnosis' zero
 * level for cfg.rax_quiet_steps (nothing to explain: r1's symptom is gone
 * by then; before, it may still be held by the diagnosis' hysteresis and
 * persistence, and a RAX zero next to it reads "the estimate does not
 * explain r1": an R_A creep whose r1 hovered at its threshold was named a
 * speed-sensor offset, tests/sil/scenarios/dcm_ra_creep_sine_speed.scn);
 * not valid otherwise (an incipient R_A rise first crosses the r1 band
 * while its estimate is still inside its spread: a "not explained" there
 * would name a speed offset);
 * valid while the armature estimate has converged and is fed. Scaling: the
 * model's R_A is Q24, taken to Q16.16; dR x I in Q16.16 V (rounded,
 * saturated); the quotient by r1_est in Q16.16 times 2. */
static void dcm_rax(canfdi_app_sym_t *m, const canfdi_app_sym_in_t *in, canfdi_symptoms_t *s)
{
  const canfdi_parity_dcm_out_t *pd = canfdi_parity_dcm_out(in->parity_dcm);
  const canfdi_est_dcm_t *e = in->est_dcm;
  s->dcm_rax_q16 = 0;
  if ((pd != NULL) && in->dcm_in_ok && ((pd->valid & 1U) != 0U) &&
      (canfdi_q31_abs(pd->rn_q16[0]) < CANFDI_APP_SYM_ZERO_RN)) {
    m->r1_quiet = (m->r1_quiet < m->cfg.rax_quiet_steps) ? (uint16_t)(m->r1_quiet + 1U) : m->r1_quiet;
  } else {
    m->r1_quiet = 0U;
  }
  if ((pd != NULL) && in->dcm_in_ok && in->dcm_est_on && canfdi_est_dcm_arm_converged(e) &&
      ((pd->valid & 1U) != 0U) && (pd->thr_q16[0] > 0)) {
    const int32_t a = canfdi_q31_abs(pd->r_q16[0]);
    const int32_t r1e = canfdi_sat_s64_to_s32(canfdi_asr64_rnd(m->r1_est_q32, 16U));
    if (m->r1_quiet >= m->cfg.rax_quiet_steps) {
      s->flags |= CANFDI_SYM_F_DCM_RAX_VALID; /* nothing to explain */
    } else if ((a >= canfdi_mul_s32_qn(pd->thr_q16[0], (int32_t)CANFDI_APP_SYM_RAX_MIN_RN * CANFDI_Q16_ONE, 16U)) &&
               (canfdi_q31_abs(r1e) >= pd->thr_q16[0]) && (sgn_s32(r1e) == sgn_s32(pd->r_q16[0]))) {
      const int32_t dr = canfdi_sub_s32_sat(canfdi_est_dcm_ra_q16(e), pd->ra_hat_ohm_q24 / 256);
      const int32_t du = canfdi_mul_s32_qn(dr, in->dcm_i_A_q16, 16U);
      s->dcm_rax_q16 = canfdi_mul_s32_qn(canfdi_div_s32_qn(du, r1e, 16U), 2 * CANFDI_Q16_ONE, 16U);
      s->flags |= CANFDI_SYM_F_DCM_RAX_VALID;
    } else {
      /* r1 not yet quiet for rax_quiet_steps (its symptom may be held),
       * r1 beyond its band by less than RAX_MIN_RN bands, or the data the
       * estimate was fit on not yet beyond it: an R_A change this small is
       * inside the estimate's own spread, so the estimate can neither
       * claim nor exclude it (not valid: '?') */
    }
  }
}

/* CANFDI_SYM_F_DCM_GAIN_CONTRA (the header, "Speed-gain magnitude").
 * Scaling: the J/Psi deviation Q16.16 (relative, saturating difference);
 * Psi (Q16.16 V s) x |x| -> Q16.16 V s, x |w| (Q16.16 rad/s) -> Q16.16 V,
 * each product rounded and saturated; the comparisons in Q16.16 V with
 * saturating doubling and quadrupling. */
static void dcm_gain_contra(const canfdi_app_sym_in_t *in, canfdi_symptoms_t *s)
{
  const canfdi_parity_dcm_out_t *pd = canfdi_parity_dcm_out(in->parity_dcm);
  const uint8_t need = (uint8_t)((1U << CANFDI_SYM_DCM_P_J) | (1U << CANFDI_SYM_DCM_P_PSI));
  if ((pd != NULL) && in->dcm_in_ok && ((pd->valid & 1U) != 0U) && ((s->dcm_pdev_valid & need) == need)) {
    const int32_t x = canfdi_q31_abs(canfdi_sub_s32_sat(s->dcm_pdev_q16[CANFDI_SYM_DCM_P_J],
                                                        s->dcm_pdev_q16[CANFDI_SYM_DCM_P_PSI]));
    const int32_t pred = canfdi_mul_s32_qn(canfdi_mul_s32_qn(in->est_dcm->cfg.psi_nom_q16, x, 16U),
                                           canfdi_q31_abs(in->dcm_w_rad_s_q16), 16U);
    const int32_t r1 = canfdi_q31_abs(pd->r_q16[0]);
    if ((pred >= canfdi_add_s32_sat(pd->thr_q16[0], pd->thr_q16[0])) &&
        (canfdi_mul_s32_qn(r1, 4 * CANFDI_Q16_ONE, 16U) < pred)) {
      s->flags |= CANFDI_SYM_F_DCM_GAIN_CONTRA;
    }
  }
}

/* CANFDI_SYM_F_DCM_FX_CONTRA (canfdi_symptoms.h): a residual at or above
 * the flux prediction's zero level with a sign no flux loss can give it.
 * r1 = -dPsi w is not tracked: its sign is -sgn(w) (and a flux loss leaves
 * it at 0 where w = 0). r4 = dPsi e4 / Psi minus its mean over the load
 * tracking: a growing loss gives it the sign of e4 = R_A I_A - Psi w, and
 * the tracking can add at most dPsi |e4_hp| / Psi of the other sign where
 * e4 moves back through its tracked mean (e4_hp against e4), with dPsi at
 * most max(|r1|, r1's threshold) / |w| (no bound at w = 0). r2 and r3
 * (dPsi I_A, tracked) are not judged: the current follows the load and the
 * accelerations, and no tracked mean of it is kept here. Scaling as in
 * dcm_flux_pred (dPsi Q28 V s, saturating). */
static bool dcm_flux_contra(const canfdi_app_sym_in_t *in, const canfdi_symptoms_t *s, int32_t e4, int32_t e4_hp)
{
  const canfdi_parity_dcm_out_t *pd = canfdi_parity_dcm_out(in->parity_dcm);
  const int32_t psi = in->est_dcm->cfg.psi_nom_q16;
  const int32_t w = in->dcm_w_rad_s_q16;
  bool c = false;
  if ((pd != NULL) && in->dcm_in_ok && (psi > 0)) {
    if (((s->dcm_rn_valid & 1U) != 0U) && (canfdi_q31_abs(pd->rn_q16[0]) >= CANFDI_APP_SYM_ZERO_RN) &&
        (sgn_s32(pd->r_q16[0]) != -sgn_s32(w))) {
      c = true;
    }
    if (((s->dcm_rn_valid & 8U) != 0U) && (canfdi_q31_abs(pd->rn_q16[3]) >= CANFDI_APP_SYM_ZERO_RN) &&
        (w != 0) && (sgn_s32(pd->r_q16[3]) != sgn_s32(e4))) {
      const int32_t sg4 = sgn_s32(e4);
      const int32_t opp = (sg4 == 0) ? canfdi_q31_abs(e4_hp) : (((sg4 * sgn_s32(e4_hp)) < 0) ? canfdi_q31_abs(e4_hp) : 0);
      const int32_t r1a = canfdi_q31_abs(pd->r_q16[0]);
      const int32_t d_max =
          canfdi_div_s32_qn((r1a > pd->thr_q16[0]) ? r1a : pd->thr_q16[0], canfdi_q31_abs(w), 28U);
      const int32_t bound = canfdi_div_s32_qn(canfdi_mul_s32_qn(d_max, opp, 28U), psi, 16U);
      c = c || (canfdi_q31_abs(pd->r_q16[3]) > bound);
    }
  }
  return c;
}

/* The flux-loss prediction of the header (canfdi_symptoms.h dcm_fx_q16). */
static void dcm_flux_pred(canfdi_app_sym_t *m, const canfdi_app_sym_in_t *in, canfdi_symptoms_t *s)
{
  const canfdi_parity_dcm_out_t *pd = canfdi_parity_dcm_out(in->parity_dcm);
  const int32_t psi = in->est_dcm->cfg.psi_nom_q16;
  int32_t sens[CANFDI_SYM_N_RES];
  int32_t sg[CANFDI_SYM_N_RES];
  int32_t r1_hp = 0;
  int32_t d_mech = 0; /* dPsi explaining r2..r4, Q28 V s */
  int32_t d_r1 = 0;   /* dPsi explaining r1's newer part */
  int32_t d_tot = 0;  /* dPsi explaining r1 as it is (the whole flux loss) */
  int32_t e4 = 0;     /* r4's signed sensitivity times Psi, V */
  int32_t e4_hp = 0;  /* e4 minus its own mean over the load tracking, V */
  bool any = false;
  bool ok = (pd != NULL) && in->dcm_in_ok && (psi > 0);
  uint32_t j;
  for (j = 0U; j < CANFDI_SYM_N_RES; j++) {
    s->dcm_fx_q16[j] = 0;
  }
  if (ok && ((s->dcm_rn_valid & 1U) != 0U)) {
    const canfdi_q31_t a = canfdi_parity_dcm_load_alpha_q31(in->parity_dcm);
    if (a != 0) {
      const int64_t d = canfdi_sub_s64_sat((int64_t)pd->r_q16[0] * 65536, m->r1_mean_q32);
      m->r1_mean_q32 = canfdi_add_s64_sat(m->r1_mean_q32, canfdi_mul_s64_q31(d, a));
      r1_hp = canfdi_sub_s32_sat(pd->r_q16[0], canfdi_sat_s64_to_s32(canfdi_asr64_rnd(m->r1_mean_q32, 16U)));
    } else {
      r1_hp = pd->r_q16[0];
    }
  }
  if (ok) {
    const int32_t ri = canfdi_mul_s32_qn(pd->ra_hat_ohm_q24 / 256, in->dcm_i_A_q16, 16U);
    const canfdi_q31_t a = canfdi_parity_dcm_load_alpha_q31(in->parity_dcm);
    e4 = canfdi_sub_s32_sat(ri, canfdi_mul_s32_qn(psi, in->dcm_w_rad_s_q16, 16U));
    if (a != 0) {
      const int64_t d = canfdi_sub_s64_sat((int64_t)e4 * 65536, m->e4_mean_q32);
      m->e4_mean_q32 = canfdi_add_s64_sat(m->e4_mean_q32, canfdi_mul_s64_q31(d, a));
      e4_hp = canfdi_sub_s32_sat(e4, canfdi_sat_s64_to_s32(canfdi_asr64_rnd(m->e4_mean_q32, 16U)));
    }
    sens[0] = canfdi_q31_abs(in->dcm_w_rad_s_q16);
    sens[1] = canfdi_q31_abs(in->dcm_i_A_q16);
    sens[2] = sens[1];
    sens[3] = canfdi_div_s32_qn(canfdi_q31_abs(e4), psi, 16U);
    sg[0] = -sgn_s32(in->dcm_w_rad_s_q16);
    sg[1] = sgn_s32(in->dcm_i_A_q16);
    sg[2] = sg[1];
    sg[3] = sgn_s32(e4);
    for (j = 0U; ok && (j < CANFDI_SYM_N_RES); j++) {
      if (((s->dcm_rn_valid & (1U << j)) != 0U) && (canfdi_q31_abs(pd->rn_q16[j]) >= CANFDI_APP_SYM_ZERO_RN)) {
        any = true;
        if ((sens[j] == 0) || (sgn_s32(pd->r_q16[j]) != sg[j])) {
          ok = false; /* no flux loss gives this residual */
        } else if (j == 0U) {
          d_r1 = canfdi_div_s32_qn(canfdi_q31_abs(r1_hp), sens[0], 28U);
          d_tot = canfdi_div_s32_qn(canfdi_q31_abs(pd->r_q16[0]), sens[0], 28U);
        } else {
          const int32_t dj = canfdi_div_s32_qn(canfdi_q31_abs(pd->r_q16[j]), sens[j], 28U);
          d_mech = (dj > d_mech) ? dj : d_mech;
        }
      }
    }
  }
  if (dcm_flux_contra(in, s, e4, e4_hp)) {
    s->flags |= CANFDI_SYM_F_DCM_FX_CONTRA;
  }
  if (ok && any) {
    const int32_t d_all = (d_r1 > d_mech) ? d_r1 : d_mech;
    for (j = 0U; j < CANFDI_SYM_N_RES; j++) {
      int32_t res = canfdi_mul_s32_qn((j == 0U) ? d_mech : d_all, sens[j], 28U);
      if (j == 3U) {
        /* r4 high-passed: the newer part of the loss times its
         * sensitivity, plus the whole loss times the sensitivity's own
         * change over the tracking time (signed, e4's sign positive) */
        const int32_t dt = (d_tot > d_all) ? d_tot : d_all;
        const int32_t chg = canfdi_mul_s32_qn(dt, canfdi_div_s32_qn(e4_hp, psi, 16U), 28U);
        res = canfdi_q31_abs(canfdi_add_s32_sat(res, (sg[3] < 0) ? canfdi_sub_s32_sat(0, chg) : chg));
      }
      s->dcm_fx_q16[j] = (pd->thr_q16[j] > 0) ? canfdi_div_s32_qn(res, pd->thr_q16[j], 16U) : INT32_MAX;
    }
    s->flags |= CANFDI_SYM_F_DCM_FX_VALID;
  }
}

static void dcm_parameters(canfdi_app_sym_t *m, const canfdi_app_sym_in_t *in, canfdi_symptoms_t *s)
{
  const canfdi_est_dcm_t *e = in->est_dcm;
  const canfdi_est_dcm_cfg_t *c = &e->cfg;
  const int32_t mf0_nom = canfdi_sub_s32_sat(c->mc_nom_q16, in->load_nom_Nm_q16);
  int32_t mf0 = canfdi_sub_s32_sat(canfdi_est_dcm_mc_q16(e), in->load_known_Nm_q16);
  uint8_t mech = canfdi_est_dcm_mech_converged(e) ? 0x0CU : 0U;
  if (m->dcm_ref[0] < 0) {
    mf0 = canfdi_q31_neg(mf0);
  }
  if ((m->dcm_ref[0] == 0) || (m->mech_hold > 0U)) {
    mech = 0U;
  }
  s->dcm_pdev_q16[CANFDI_SYM_DCM_P_RA] = pdev_q16(&m->pdev[0], canfdi_est_dcm_ra_q16(e), c->ra_nom_q16);
  s->dcm_pdev_q16[CANFDI_SYM_DCM_P_PSI] = pdev_q16(&m->pdev[1], canfdi_est_dcm_psi_q16(e), c->psi_nom_q16);
  s->dcm_pdev_q16[CANFDI_SYM_DCM_P_J] = pdev_q16(&m->pdev[2], canfdi_est_dcm_j_q24(e), c->j_nom_q24);
  s->dcm_pdev_q16[CANFDI_SYM_DCM_P_FRICTION] =
      (c->mc_nom_q16 != 0) ? div_kept_q16(&m->pdev[3], canfdi_sub_s32_sat(mf0, mf0_nom), c->mc_nom_q16) : 0;
  s->dcm_upd = in->dcm_est_on ? canfdi_est_dcm_updated(e) : 0U;
  s->dcm_pdev_valid = !in->dcm_est_on ? 0U
                                      : (uint8_t)((canfdi_est_dcm_arm_converged(e) ? 0x03U : 0U) | mech);
}

static void thr_parameters(canfdi_app_sym_t *m, const canfdi_app_sym_in_t *in, canfdi_symptoms_t *s)
{
  const canfdi_est_thr_t *e = in->est_thr;
  s->thr_pdev_q16[CANFDI_SYM_THR_P_R] = pdev_q16(&m->pdev[4], canfdi_est_thr_r_q16(e), e->cfg.r_nom_q16);
  s->thr_pdev_q16[CANFDI_SYM_THR_P_K] = pdev_q16(&m->pdev[5], canfdi_est_thr_k_q16(e), e->cfg.k_nom_q16);
  s->thr_pdev_q16[CANFDI_SYM_THR_P_SPRING] = canfdi_est_thr_fast_spring_dev_q16(e);
  s->thr_pdev_q16[CANFDI_SYM_THR_P_FRICTION] = canfdi_est_thr_fast_friction_dev_q16(e);
  s->thr_upd = in->thr_est_on ? canfdi_est_thr_updated(e) : 0U;
  /* the friction deviation only from a direction-paired solution (see
   * "Direction pairing" in canfdi_est_thr.h); the spring deviation of an
   * unpaired one still shows that the resisting torque changed, and with
   * friction unknown no rule can isolate on it: the need for a test burst */
  s->thr_pdev_valid =
      !in->thr_est_on ? 0U
                      : (uint8_t)((canfdi_est_thr_el_converged(e) ? 0x03U : 0U) |
                                  (canfdi_est_thr_fast_valid(e) ? (1U << CANFDI_SYM_THR_P_SPRING) : 0U) |
                                  (canfdi_est_thr_fast_paired(e) ? (1U << CANFDI_SYM_THR_P_FRICTION) : 0U));
}

static uint32_t flags(const canfdi_app_sym_in_t *in)
{
  static const uint32_t low[2] = {CANFDI_SYM_F_TPS1_LOW, CANFDI_SYM_F_TPS2_LOW};
  static const uint32_t high[2] = {CANFDI_SYM_F_TPS1_HIGH, CANFDI_SYM_F_TPS2_HIGH};
  static const uint32_t invalid[2] = {CANFDI_SYM_F_TPS1_INVALID, CANFDI_SYM_F_TPS2_INVALID};
  static const uint8_t vote_bit[2] = {CANFDI_VOTE_BIT_TPS1, CANFDI_VOTE_BIT_TPS2};
  static const uint32_t outlier[2] = {CANFDI_SYM_F_TPS1_OUTLIER, CANFDI_SYM_F_TPS2_OUTLIER};
  uint32_t f = 0U;
  uint32_t k;
  for (k = 0U; k < 2U; k++) {
    if (in->tps_range[k] == (uint8_t)CANFDI_LIMIT_BELOW_MIN) {
      f |= low[k];
    } else if (in->tps_range[k] == (uint8_t)CANFDI_LIMIT_ABOVE_MAX) {
      f |= high[k];
    } else {
      /* in band */
    }
    f |= in->tps_invalid[k] ? invalid[k] : 0U;
    f |= ((in->vote_isolated_mask & vote_bit[k]) != 0U) ? outlier[k] : 0U;
  }
  if ((in->mgr_detected & CANFDI_FAULT_BIT(CANFDI_FAULT_DCM_BRIDGE_A_DEAD)) != 0U) {
    f |= CANFDI_SYM_F_BRIDGE_A_DEAD;
  }
  if ((in->mgr_detected & CANFDI_FAULT_BIT(CANFDI_FAULT_DCM_BRIDGES_DEAD)) != 0U) {
    f |= CANFDI_SYM_F_BRIDGE_B_DEAD;
  }
  f |= in->actmon->thr_not_following ? CANFDI_SYM_F_THR_NOT_FOLLOWING : 0U;
  f |= in->actmon->thr_no_current ? CANFDI_SYM_F_THR_NO_CURRENT : 0U;
  f |= in->actmon->dcm_uac_valid ? CANFDI_SYM_F_DCM_UA_CMD_VALID : 0U;
  f |= in->dcm_learnt ? 0U : CANFDI_SYM_F_DCM_UNLEARNT;
  f |= in->dcm_rearm ? CANFDI_SYM_F_DCM_REARM : 0U;
  f |= in->thr_rearm ? CANFDI_SYM_F_THR_REARM : 0U;
  return f;
}

void canfdi_app_sym_build(canfdi_app_sym_t *m, const canfdi_app_sym_in_t *in, canfdi_symptoms_t *s)
{
  CANFDI_ASSERT((m != NULL) && (in != NULL) && (s != NULL) && (in->est_dcm != NULL) &&
                (in->est_thr != NULL) && (in->actmon != NULL));
  references(m, in, s);
  residuals(in, s);
  dcm_parameters(m, in, s);
  thr_parameters(m, in, s);
  s->flags = flags(in);
  speed_jump(m, in, s);
  s->flags |= m->jump ? CANFDI_SYM_F_DCM_W_JUMP : 0U;
  r1_est_mean(m, in, s);
  dcm_rax(m, in, s);
  dcm_gain_contra(in, s);
  dcm_flux_pred(m, in, s);
  s->dcm_ua_cmd_rn_q16 = uac_channel(in, s);
}
