/*
 * canfdi_actmon.c — actuator monitors; the manual is the header.
 */
#include "detect/canfdi_actmon.h"

#include "core/canfdi_count.h"
#include "core/canfdi_fixp.h"
#include "core/canfdi_qconst.h"

void canfdi_actmon_default_cfg(canfdi_actmon_cfg_t *cfg)
{
  if (cfg != NULL) {
    cfg->track_alpha_q16 = CANFDI_Q16(1, 500);
    cfg->track_thr_rad_q16 = CANFDI_Q16_MILLI(50);
    cfg->track_slew_rad_q16 = CANFDI_Q16_MILLI(6);
    cfg->open_u_min_V_q16 = 3 * CANFDI_Q16_ONE;
    cfg->open_i_max_A_q16 = CANFDI_Q16_MILLI(50);
    cfg->uac_alpha_q16 = CANFDI_Q16(1, 8);
    cfg->uac_thr_V_q16 = CANFDI_Q16_MILLI(500);
    cfg->uac_headroom_V_q16 = 2 * CANFDI_Q16_ONE;
  }
}

static bool alpha_ok(int32_t a) { return (a > 0) && (a <= CANFDI_Q16_ONE); }

int32_t canfdi_actmon_init(canfdi_actmon_t *m, const canfdi_actmon_cfg_t *cfg)
{
  int32_t rc = -CANFDI_EINVAL;
  if (m != NULL) {
    m->initialised = false;
    if ((cfg != NULL) && alpha_ok(cfg->track_alpha_q16) && (cfg->track_thr_rad_q16 > 0) &&
        (cfg->track_slew_rad_q16 > 0) &&
        (cfg->open_u_min_V_q16 > 0) && (cfg->open_i_max_A_q16 > 0) &&
        alpha_ok(cfg->uac_alpha_q16) && (cfg->uac_thr_V_q16 > 0) &&
        (cfg->uac_headroom_V_q16 >= 0)) {
      m->cfg = *cfg;
      m->track_err_rad_q16 = 0;
      m->track_exp_rad_q16 = 0;
      m->track_exp_valid = false;
      m->uac_V_q16 = 0;
      m->diag = (canfdi_actmon_diag_t){0};
      m->initialised = true;
      rc = CANFDI_OK;
    }
  }
  return rc;
}

/* x += alpha (u - x), saturating. */
static int32_t lowpass(int32_t x, int32_t u, int32_t alpha_q16)
{
  return canfdi_add_s32_sat(x, canfdi_mul_s32_qn(canfdi_sub_s32_sat(u, x), alpha_q16, 16U));
}

/* How far the valve lags the slowest trajectory it may take to its
 * reference: the expected angle moves towards the reference by at most
 * track_slew per step; while it is on its way a valve ahead of it (faster
 * than the slowest) lags by nothing and takes it along (the expectation
 * restarts where the valve got to), one behind it lags by the distance;
 * once it has arrived the lag is the distance either way. Restarted at
 * the measured angle while not judged. */
static int32_t track_lag(canfdi_actmon_t *m, const canfdi_actmon_in_t *in)
{
  const canfdi_actmon_cfg_t *c = &m->cfg;
  int32_t lag = 0;
  if (in->thr_angle_valid && in->thr_enabled && m->track_exp_valid) {
    const int32_t to_ref = canfdi_sub_s32_sat(in->thr_ref_rad_q16, m->track_exp_rad_q16);
    const int32_t move = canfdi_clamp_s32(to_ref, -c->track_slew_rad_q16, c->track_slew_rad_q16);
    int32_t rest;
    int32_t e;
    m->track_exp_rad_q16 = canfdi_add_s32_sat(m->track_exp_rad_q16, move);
    rest = canfdi_sub_s32_sat(in->thr_ref_rad_q16, m->track_exp_rad_q16);
    e = canfdi_sub_s32_sat(m->track_exp_rad_q16, in->thr_angle_rad_q16);
    if (rest > 0) {
      lag = (e > 0) ? e : 0; /* on the way up: behind if below */
    } else if (rest < 0) {
      lag = (e < 0) ? canfdi_q31_abs(e) : 0; /* on the way down: behind if above */
    } else {
      lag = canfdi_q31_abs(e); /* arrived: the distance either way */
    }
    if ((lag == 0) && (rest != 0)) {
      /* a valve ahead of the expectation: the slowest trajectory restarts
       * where it is (up to the reference), so a reference that turns back
       * (a blip of the pedal) is judged from where the valve got to */
      m->track_exp_rad_q16 = (rest > 0) ? canfdi_clamp_s32(in->thr_angle_rad_q16, m->track_exp_rad_q16, in->thr_ref_rad_q16)
                                        : canfdi_clamp_s32(in->thr_angle_rad_q16, in->thr_ref_rad_q16, m->track_exp_rad_q16);
    }
  } else if (in->thr_angle_valid) {
    m->track_exp_rad_q16 = in->thr_angle_rad_q16;
    m->track_exp_valid = true;
  } else {
    m->track_exp_valid = false;
  }
  return lag;
}

static void step_thr(canfdi_actmon_t *m, const canfdi_actmon_in_t *in, canfdi_actmon_out_t *out)
{
  const canfdi_actmon_cfg_t *c = &m->cfg;
  const int32_t err = track_lag(m, in);
  m->track_err_rad_q16 = lowpass(m->track_err_rad_q16, err, c->track_alpha_q16);
  out->thr_track_err_rad_q16 = m->track_err_rad_q16;
  out->thr_not_following = in->thr_angle_valid && in->thr_enabled &&
                           (m->track_err_rad_q16 > c->track_thr_rad_q16);
  out->thr_no_current = in->thr_enabled && (canfdi_q31_abs(in->thr_u_cmd_V_q16) > c->open_u_min_V_q16) &&
                        in->thr_i_valid && (canfdi_q31_abs(in->thr_i_A_q16) < c->open_i_max_A_q16);
  if (out->thr_not_following) {
    canfdi_count_inc(&m->diag.not_following_steps);
  }
  if (out->thr_no_current) {
    canfdi_count_inc(&m->diag.no_current_steps);
  }
}

static void step_uac(canfdi_actmon_t *m, const canfdi_actmon_in_t *in, canfdi_actmon_out_t *out)
{
  const canfdi_actmon_cfg_t *c = &m->cfg;
  const bool judged = in->dcm_enabled && in->dcm_bridge_settled && in->dcm_ua_valid &&
                      in->dcm_supply_valid &&
                      (canfdi_q31_abs(in->dcm_u_cmd_V_q16) <
                       canfdi_sub_s32_sat(in->dcm_supply_V_q16, c->uac_headroom_V_q16));
  out->dcm_uac_valid = judged;
  if (judged) {
    m->uac_V_q16 = lowpass(m->uac_V_q16, canfdi_sub_s32_sat(in->dcm_ua_V_q16, in->dcm_u_cmd_V_q16),
                           c->uac_alpha_q16);
    out->dcm_uac_rn_q16 = canfdi_div_s32_qn(m->uac_V_q16, c->uac_thr_V_q16, 16U);
    out->dcm_uac_V_q16 = m->uac_V_q16;
    canfdi_count_inc(&m->diag.uac_judged_steps);
  } else {
    out->dcm_uac_rn_q16 = 0;
    out->dcm_uac_V_q16 = 0;
  }
}

int32_t canfdi_actmon_step(canfdi_actmon_t *m, const canfdi_actmon_in_t *in,
                           canfdi_actmon_out_t *out)
{
  int32_t rc = -CANFDI_EINVAL;
  if (out != NULL) {
    *out = (canfdi_actmon_out_t){0};
  }
  if ((m != NULL) && m->initialised && (in != NULL) && (out != NULL)) {
    step_thr(m, in, out);
    step_uac(m, in, out);
    canfdi_count_inc(&m->diag.steps);
    rc = CANFDI_OK;
  } else if ((m != NULL) && m->initialised) {
    canfdi_count_inc(&m->diag.rejected);
  } else {
    /* nothing to count on */
  }
  return rc;
}

canfdi_actmon_diag_t canfdi_actmon_diag(const canfdi_actmon_t *m)
{
  canfdi_actmon_diag_t d = {0};
  if (m != NULL) {
    d = m->diag;
  }
  return d;
}
