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
  }
}

int32_t canfdi_app_sym_init(canfdi_app_sym_t *m, const canfdi_app_sym_cfg_t *cfg)
{
  int32_t rc = -CANFDI_EINVAL;
  if ((m != NULL) && (cfg != NULL) && (cfg->dcm_w_on_rad_s_q16 > 0) && (cfg->dcm_i_on_A_q16 > 0) &&
      (cfg->thr_u_on_V_q16 > 0) && (cfg->thr_i_on_A_q16 > 0)) {
    m->cfg = *cfg;
    m->dcm_ref[0] = 0;
    m->dcm_ref[1] = 0;
    m->thr_ref[0] = 0;
    m->thr_ref[1] = 0;
    m->mech_hold = cfg->mech_settle_steps;
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

/* (est - nom) / nom in Q16.16, saturating; both in the same Q format. */
static int32_t pdev_q16(int32_t est, int32_t nom)
{
  return (nom != 0) ? canfdi_div_s32_qn(canfdi_sub_s32_sat(est, nom), nom, 16U) : 0;
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
  s->thr_rn_valid = ((pt != NULL) && in->thr_in_ok) ? pt->valid : 0U;
}

static void dcm_parameters(const canfdi_app_sym_t *m, const canfdi_app_sym_in_t *in, canfdi_symptoms_t *s)
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
  s->dcm_pdev_q16[CANFDI_SYM_DCM_P_RA] = pdev_q16(canfdi_est_dcm_ra_q16(e), c->ra_nom_q16);
  s->dcm_pdev_q16[CANFDI_SYM_DCM_P_PSI] = pdev_q16(canfdi_est_dcm_psi_q16(e), c->psi_nom_q16);
  s->dcm_pdev_q16[CANFDI_SYM_DCM_P_J] = pdev_q16(canfdi_est_dcm_j_q24(e), c->j_nom_q24);
  s->dcm_pdev_q16[CANFDI_SYM_DCM_P_FRICTION] =
      (c->mc_nom_q16 != 0) ? canfdi_div_s32_qn(canfdi_sub_s32_sat(mf0, mf0_nom), c->mc_nom_q16, 16U) : 0;
  s->dcm_pdev_valid = !in->dcm_est_on ? 0U
                                      : (uint8_t)((canfdi_est_dcm_arm_converged(e) ? 0x03U : 0U) | mech);
}

static void thr_parameters(const canfdi_app_sym_in_t *in, canfdi_symptoms_t *s)
{
  const canfdi_est_thr_t *e = in->est_thr;
  s->thr_pdev_q16[CANFDI_SYM_THR_P_R] = pdev_q16(canfdi_est_thr_r_q16(e), e->cfg.r_nom_q16);
  s->thr_pdev_q16[CANFDI_SYM_THR_P_K] = pdev_q16(canfdi_est_thr_k_q16(e), e->cfg.k_nom_q16);
  s->thr_pdev_q16[CANFDI_SYM_THR_P_SPRING] = canfdi_est_thr_fast_spring_dev_q16(e);
  s->thr_pdev_q16[CANFDI_SYM_THR_P_FRICTION] = canfdi_est_thr_fast_friction_dev_q16(e);
  s->thr_pdev_valid = !in->thr_est_on ? 0U
                                      : (uint8_t)((canfdi_est_thr_el_converged(e) ? 0x03U : 0U) |
                                                  (canfdi_est_thr_fast_valid(e) ? 0x0CU : 0U));
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
  return f;
}

void canfdi_app_sym_build(canfdi_app_sym_t *m, const canfdi_app_sym_in_t *in, canfdi_symptoms_t *s)
{
  CANFDI_ASSERT((m != NULL) && (in != NULL) && (s != NULL) && (in->est_dcm != NULL) &&
                (in->est_thr != NULL) && (in->actmon != NULL));
  references(m, in, s);
  residuals(in, s);
  dcm_parameters(m, in, s);
  thr_parameters(in, s);
  s->flags = flags(in);
  s->dcm_ua_cmd_rn_q16 = in->actmon->dcm_uac_rn_q16;
}
