/*
 * canfdi_app_sym.c — the symptom vector from the detection stage; the
 * manual is the header.
 */
#include "app/canfdi_app_sym.h"

#include "catalogue/canfdi_catalogue.h"
#include "core/canfdi_fixp.h"
#include "detect/canfdi_limit.h"
#include "ft/canfdi_vote.h"

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

static void dcm_parameters(const canfdi_app_sym_in_t *in, canfdi_symptoms_t *s)
{
  const canfdi_est_dcm_t *e = in->est_dcm;
  const canfdi_est_dcm_cfg_t *c = &e->cfg;
  const int32_t mc_ref = canfdi_add_s32_sat(c->mc_nom_q16, in->load_offset_Nm_q16);
  s->dcm_pdev_q16[CANFDI_SYM_DCM_P_RA] = pdev_q16(canfdi_est_dcm_ra_q16(e), c->ra_nom_q16);
  s->dcm_pdev_q16[CANFDI_SYM_DCM_P_PSI] = pdev_q16(canfdi_est_dcm_psi_q16(e), c->psi_nom_q16);
  s->dcm_pdev_q16[CANFDI_SYM_DCM_P_J] = pdev_q16(canfdi_est_dcm_j_q24(e), c->j_nom_q24);
  s->dcm_pdev_q16[CANFDI_SYM_DCM_P_FRICTION] =
      (c->mc_nom_q16 != 0)
          ? canfdi_div_s32_qn(canfdi_sub_s32_sat(canfdi_est_dcm_mc_q16(e), mc_ref), c->mc_nom_q16, 16U)
          : 0;
  s->dcm_pdev_valid = !in->dcm_est_on ? 0U
                                      : (uint8_t)((canfdi_est_dcm_arm_converged(e) ? 0x03U : 0U) |
                                                  (canfdi_est_dcm_mech_converged(e) ? 0x0CU : 0U));
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

void canfdi_app_sym_build(const canfdi_app_sym_in_t *in, canfdi_symptoms_t *s)
{
  CANFDI_ASSERT((in != NULL) && (s != NULL) && (in->est_dcm != NULL) && (in->est_thr != NULL) &&
                (in->actmon != NULL));
  residuals(in, s);
  dcm_parameters(in, s);
  thr_parameters(in, s);
  s->flags = flags(in);
  s->dcm_ua_cmd_rn_q16 = in->actmon->dcm_uac_rn_q16;
}
