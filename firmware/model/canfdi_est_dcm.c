/*
 * canfdi_est_dcm.c — DC motor parameter estimator; see canfdi_est_dcm.h.
 */
#include "model/canfdi_est_dcm.h"

#include "core/canfdi_count.h"
#include "core/canfdi_fixp.h"
#include "core/canfdi_qconst.h"

/* T / 2 in Q31 (the half-sample correction of the ZOH voltage) */
#define HALF_T_Q31 CANFDI_Q31_RATIO(CANFDI_CFG_STEP_US, 2000000)

void canfdi_est_dcm_default_cfg(canfdi_est_dcm_cfg_t *cfg)
{
  CANFDI_ASSERT(cfg != NULL);
  cfg->svf.order = 2U;
  cfg->svf.omega_c_rad_s = 200;
  cfg->svf.outputs = 0U; /* each filter's own set at init */
  cfg->decim = 5U;
  cfg->forget_q31 = CANFDI_Q31_RATIO(1, 100);
  cfg->p0_q16 = 100 * CANFDI_Q16_ONE;
  cfg->trace_max_q16 = 1000 * CANFDI_Q16_ONE;
  cfg->excite_min_q16 = CANFDI_Q16(2, 10000);
  cfg->excite_min_mech_q16 = CANFDI_Q16(3, 10000);
  cfg->excite_shift = 6U;
  cfg->conv_updates = 400U;
  cfg->ra_nom_q16 = CANFDI_Q16_MILLI(1520);
  cfg->la_nom_q24 = CANFDI_Q24(682, 100000);
  cfg->psi_nom_q16 = CANFDI_Q16_MILLI(330);
  cfg->j_nom_q24 = CANFDI_Q24(192, 100000);
  cfg->mf1_nom_q24 = CANFDI_Q24(36, 100000);
  cfg->mc_nom_q16 = CANFDI_Q16_MILLI(1310);
  cfg->load_hold_steps = 0U;
}

static void rls_cfg_common(canfdi_rls_cfg_t *rc, const canfdi_est_dcm_cfg_t *cfg)
{
  unsigned i;
  rc->n_params = 3U;
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

/* Seeds both estimators with the nominal parameters at full resolution. */
static void seed_nominal(canfdi_est_dcm_t *e)
{
  const canfdi_est_dcm_cfg_t *c = &e->cfg;
  canfdi_rls_set_theta_qn(&e->arm, 0U, c->ra_nom_q16, 16U);
  canfdi_rls_set_theta_qn(&e->arm, 1U, c->la_nom_q24, 24U);
  canfdi_rls_set_theta_qn(&e->arm, 2U, c->psi_nom_q16, 16U);
  /* J / Psi etc.: Q24 / Q16 * 2^16 -> Q24 */
  canfdi_rls_set_theta_qn(&e->mech, 0U, canfdi_div_s32_qn(c->j_nom_q24, c->psi_nom_q16, 16U), 24U);
  canfdi_rls_set_theta_qn(&e->mech, 1U, canfdi_div_s32_qn(c->mf1_nom_q24, c->psi_nom_q16, 16U), 24U);
  canfdi_rls_set_theta_qn(&e->mech, 2U, canfdi_div_s32_qn(c->mc_nom_q16, c->psi_nom_q16, 16U), 16U);
}

/* One of the estimator's filters, with the shared configuration and the
 * outputs this module reads of it. */
static int32_t svf_init_outputs(canfdi_svf_t *f, const canfdi_svf_cfg_t *shared, unsigned outputs)
{
  canfdi_svf_cfg_t c = *shared;
  c.outputs = (uint8_t)outputs;
  return canfdi_svf_init(f, &c);
}

int32_t canfdi_est_dcm_init(canfdi_est_dcm_t *e, const canfdi_est_dcm_cfg_t *cfg)
{
  int32_t out = -CANFDI_EINVAL;
  if ((e != NULL) && (cfg != NULL) && (cfg->decim >= 1U) && (cfg->decim <= 100U) &&
      (cfg->psi_nom_q16 > 0)) {
    canfdi_rls_cfg_t ra;
    canfdi_rls_cfg_t rm;
    rls_cfg_common(&ra, cfg);
    ra.y_shift = CANFDI_EST_DCM_SHIFT_U;
    ra.phi_shift[0] = CANFDI_EST_DCM_SHIFT_I;
    ra.phi_shift[1] = CANFDI_EST_DCM_SHIFT_DI;
    ra.phi_shift[2] = CANFDI_EST_DCM_SHIFT_W;
    ra.excite_mask = 0x5U; /* I_A and w must both vary (dI/dt follows I_A) */
    rls_cfg_common(&rm, cfg);
    rm.y_shift = CANFDI_EST_DCM_SHIFT_I;
    rm.phi_shift[0] = CANFDI_EST_DCM_SHIFT_DW;
    rm.phi_shift[1] = CANFDI_EST_DCM_SHIFT_W;
    rm.phi_shift[2] = 0;
    rm.excite_mask = 0x3U; /* dw/dt and w; not the constant */
    rm.excite_min_q16 = cfg->excite_min_mech_q16;
    if ((svf_init_outputs(&e->svf_u, &cfg->svf, CANFDI_SVF_OUT_Y | CANFDI_SVF_OUT_DY) == CANFDI_OK) &&
        (svf_init_outputs(&e->svf_i, &cfg->svf, CANFDI_SVF_OUT_Y | CANFDI_SVF_OUT_DY) == CANFDI_OK) &&
        (svf_init_outputs(&e->svf_w, &cfg->svf, CANFDI_SVF_OUT_Y | CANFDI_SVF_OUT_DY) == CANFDI_OK) &&
        (svf_init_outputs(&e->svf_l, &cfg->svf, CANFDI_SVF_OUT_Y) == CANFDI_OK) && (canfdi_rls_init(&e->arm, &ra) == CANFDI_OK) &&
        (canfdi_rls_init(&e->mech, &rm) == CANFDI_OK)) {
      e->cfg = *cfg;
      e->has_run = false;
      e->diag.steps = 0U;
      e->diag.arm_updates = 0U;
      e->diag.mech_updates = 0U;
      e->diag.resets = 0U;
      e->diag.load_hold_skips = 0U;
      e->dload_q16 = 0;
      e->load_hold = 0U;
      canfdi_est_dcm_reset(e, false);
      e->diag.resets = 0U;
      out = CANFDI_OK;
    }
  }
  return out;
}

void canfdi_est_dcm_reset(canfdi_est_dcm_t *e, bool keep_theta)
{
  CANFDI_ASSERT(e != NULL);
  canfdi_rls_reset(&e->arm, keep_theta);
  canfdi_rls_reset(&e->mech, keep_theta);
  if (!keep_theta) {
    seed_nominal(e);
  }
  e->phase = 0U;
  e->started = false;
  /* the known load offset is an input, kept across resets */
  e->arm_since_reset = 0U;
  e->mech_since_reset = 0U;
  canfdi_count_inc(&e->diag.resets);
}

/* Psi for the mechanical conversion: the estimate once it has converged
 * (the armature estimator keeps it positive near the nominal value). */
static int32_t psi_for_mech_q16(const canfdi_est_dcm_t *e)
{
  return canfdi_est_dcm_arm_converged(e) ? canfdi_est_dcm_psi_q16(e) : e->cfg.psi_nom_q16;
}

void canfdi_est_dcm_set_load_offset(canfdi_est_dcm_t *e, int32_t dload_q16)
{
  CANFDI_ASSERT(e != NULL);
  if (dload_q16 != e->dload_q16) {
    e->load_hold = e->cfg.load_hold_steps;
  }
  e->dload_q16 = dload_q16;
}

void canfdi_est_dcm_boost(canfdi_est_dcm_t *e)
{
  CANFDI_ASSERT(e != NULL);
  canfdi_rls_boost(&e->arm);
  canfdi_rls_boost(&e->mech);
}

uint8_t canfdi_est_dcm_updated(const canfdi_est_dcm_t *e)
{
  return e->updated;
}

void canfdi_est_dcm_align(canfdi_est_dcm_t *e, uint32_t k)
{
  CANFDI_ASSERT(e != NULL);
  e->phase = canfdi_phase_before(k, e->cfg.decim);
}

void canfdi_est_dcm_step(canfdi_est_dcm_t *e, int32_t ua_q16, int32_t ia_q16, int32_t w_q16)
{
  CANFDI_ASSERT(e != NULL);
  e->updated = 0U;
  if (!e->started) {
    canfdi_svf_reset(&e->svf_u, ua_q16);
    canfdi_svf_reset(&e->svf_i, ia_q16);
    canfdi_svf_reset(&e->svf_w, w_q16);
    canfdi_svf_reset(&e->svf_l, e->dload_q16);
    e->started = true;
  } else {
    canfdi_svf_step(&e->svf_u, ua_q16);
    canfdi_svf_step(&e->svf_i, ia_q16);
    canfdi_svf_step(&e->svf_w, w_q16);
    canfdi_svf_step(&e->svf_l, e->dload_q16);
    e->phase = (uint8_t)(e->phase + 1U);
    if (e->phase >= e->cfg.decim) {
      e->phase = 0U;
    }
    if (e->phase == 0U) {
      int32_t phi[3];
      const int32_t y = canfdi_add_s32_sat(canfdi_svf_y_q16(&e->svf_u),
                                           canfdi_mul_s32_qn(canfdi_svf_dy_q16(&e->svf_u), HALF_T_Q31, 31U));
      phi[0] = canfdi_svf_y_q16(&e->svf_i);
      phi[1] = canfdi_svf_dy_q16(&e->svf_i);
      phi[2] = canfdi_svf_y_q16(&e->svf_w);
      if (canfdi_rls_update(&e->arm, phi, y)) {
        e->updated |= CANFDI_EST_DCM_UPD_ARM;
        e->arm_since_reset += (e->arm_since_reset < UINT32_MAX) ? 1U : 0U;
        canfdi_count_inc(&e->diag.arm_updates);
      }
    }
    /* the mechanical update one step later (same step when decim == 1) */
    if ((e->phase == ((e->cfg.decim > 1U) ? 1U : 0U)) && (e->load_hold > 0U)) {
      canfdi_count_inc(&e->diag.load_hold_skips);
    } else if (e->phase == ((e->cfg.decim > 1U) ? 1U : 0U)) {
      int32_t phi[3];
      phi[0] = canfdi_svf_dy_q16(&e->svf_w);
      phi[1] = canfdi_svf_y_q16(&e->svf_w);
      /* The known load change, filtered like I_A, moves to the output side
       * as the current it needs: y = I_f - dM_L,f / Psi (Psi as used for
       * the read-outs). Scaling: Q16.16 N m / Q16.16 V s -> Q16.16 A,
       * saturating division and subtraction. */
      const int32_t y = canfdi_sub_s32_sat(
          canfdi_svf_y_q16(&e->svf_i),
          canfdi_div_s32_qn(canfdi_svf_y_q16(&e->svf_l), psi_for_mech_q16(e), 16U));
      phi[2] = CANFDI_Q16_ONE;
      if (canfdi_rls_update(&e->mech, phi, y)) {
        e->updated |= CANFDI_EST_DCM_UPD_MECH;
        e->mech_since_reset += (e->mech_since_reset < UINT32_MAX) ? 1U : 0U;
        canfdi_count_inc(&e->diag.mech_updates);
      }
    }
  }
  if (e->load_hold > 0U) {
    e->load_hold = (uint16_t)(e->load_hold - 1U);
  }
  e->has_run = true;
  canfdi_count_inc(&e->diag.steps);
}

int32_t canfdi_est_dcm_ra_q16(const canfdi_est_dcm_t *e)
{
  return canfdi_rls_theta_qn(&e->arm, 0U, 16U);
}

int32_t canfdi_est_dcm_la_q24(const canfdi_est_dcm_t *e)
{
  return canfdi_rls_theta_qn(&e->arm, 1U, 24U);
}

int32_t canfdi_est_dcm_psi_q16(const canfdi_est_dcm_t *e)
{
  return canfdi_rls_theta_qn(&e->arm, 2U, 16U);
}


/* Scaling: Q16.16 Psi x Q24 ratio, rounded shift by 16 -> Q24, saturated. */
int32_t canfdi_est_dcm_j_q24(const canfdi_est_dcm_t *e)
{
  return canfdi_mul_s32_qn(psi_for_mech_q16(e), canfdi_rls_theta_qn(&e->mech, 0U, 24U), 16U);
}

int32_t canfdi_est_dcm_mf1_q24(const canfdi_est_dcm_t *e)
{
  return canfdi_mul_s32_qn(psi_for_mech_q16(e), canfdi_rls_theta_qn(&e->mech, 1U, 24U), 16U);
}

/* The lumped M_c: the estimated constant plus the known load offset it
 * excludes (saturating). */
int32_t canfdi_est_dcm_mc_q16(const canfdi_est_dcm_t *e)
{
  return canfdi_add_s32_sat(
      canfdi_mul_s32_qn(psi_for_mech_q16(e), canfdi_rls_theta_qn(&e->mech, 2U, 16U), 16U),
      e->dload_q16);
}

bool canfdi_est_dcm_has_run(const canfdi_est_dcm_t *e)
{
  return e->has_run;
}

bool canfdi_est_dcm_excited(const canfdi_est_dcm_t *e)
{
  return canfdi_rls_excited(&e->arm);
}

bool canfdi_est_dcm_arm_converged(const canfdi_est_dcm_t *e)
{
  return e->arm_since_reset >= e->cfg.conv_updates;
}

bool canfdi_est_dcm_mech_converged(const canfdi_est_dcm_t *e)
{
  return e->mech_since_reset >= e->cfg.conv_updates;
}

const canfdi_rls_t *canfdi_est_dcm_arm_rls(const canfdi_est_dcm_t *e)
{
  return &e->arm;
}

const canfdi_rls_t *canfdi_est_dcm_mech_rls(const canfdi_est_dcm_t *e)
{
  return &e->mech;
}

const canfdi_est_dcm_diag_t *canfdi_est_dcm_diag(const canfdi_est_dcm_t *e)
{
  return &e->diag;
}
