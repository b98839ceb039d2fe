/*
 * canfdi_ctrl_dcm.c — DC motor speed control (cascade); see canfdi_ctrl_dcm.h.
 */
#include "ctrl/canfdi_ctrl_dcm.h"

#include "core/canfdi_count.h"
#include "core/canfdi_fixp.h"
#include "core/canfdi_qconst.h"

void canfdi_ctrl_dcm_cal_default(canfdi_ctrl_dcm_cal_t *cal)
{
  cal->ra_ohm_q16 = CANFDI_Q16_MILLI(1520);
  cal->psi_Vs_q16 = CANFDI_Q16_MILLI(330);
  cal->j_kgm2_q31 = CANFDI_Q31_RATIO(192, 100000);
  /* speed PI: kp = J w_cw / Psi = 1.92e-3 * 100 / 0.33, ki = kp w_cw / 4 */
  cal->speed_kp_A_s_rad_q16 = CANFDI_Q16(192 * 100, 33000);
  cal->speed_ki_A_rad_q16 = CANFDI_Q16(192 * 100 * 25, 33000);
  /* current PI: kp = L w_ci = 6.82e-3 * 500, ki = R w_ci = 1.52 * 500 */
  cal->cur_kp_V_A_q16 = CANFDI_Q16(682 * 5, 1000);
  cal->cur_ki_V_As_q16 = CANFDI_Q16(152 * 5, 1);
  cal->ia_max_A_q16 = CANFDI_Q16(20, 1);
  cal->u_max_V_q16 = CANFDI_Q16(48, 1);
  cal->speed_max_rad_s_q16 = CANFDI_Q16(350, 1);
  cal->accel_max_rad_s2_q16 = CANFDI_Q16(2000, 1);
  cal->current_loop = true;
  cal->anti_windup = CANFDI_PI_AW_CLAMP;
}

int32_t canfdi_ctrl_dcm_init(canfdi_ctrl_dcm_t *c, const canfdi_ctrl_dcm_cal_t *cal)
{
  int32_t out = CANFDI_OK;
  canfdi_pi_cfg_t sp;
  canfdi_pi_cfg_t cp;
  canfdi_pi_t spi;
  canfdi_pi_t cpi;
  int64_t dref = 0;
  int64_t i_acc = 0;

  if ((c == NULL) || (cal == NULL)) {
    out = -CANFDI_EINVAL;
  } else if ((cal->ra_ohm_q16 <= 0) || (cal->psi_Vs_q16 <= 0) || (cal->ia_max_A_q16 <= 0) ||
             (cal->u_max_V_q16 <= 0) || (cal->speed_max_rad_s_q16 <= 0) ||
             (cal->accel_max_rad_s2_q16 < 0) || (cal->j_kgm2_q31 < 0)) {
    out = -CANFDI_EINVAL;
  } else {
    sp.kp_q16 = cal->speed_kp_A_s_rad_q16;
    sp.ki_q16 = cal->speed_ki_A_rad_q16;
    sp.kd_q16 = 0;
    sp.kd_tau_us = 0U;
    sp.i_band_q16 = 0;
    sp.out_min_q16 = -cal->ia_max_A_q16;
    sp.out_max_q16 = cal->ia_max_A_q16;
    sp.anti_windup = cal->anti_windup; /* canfdi_pi_init validates it */
    cp = sp;
    cp.kp_q16 = cal->cur_kp_V_A_q16;
    cp.ki_q16 = cal->cur_ki_V_As_q16;
    cp.out_min_q16 = -cal->u_max_V_q16;
    cp.out_max_q16 = cal->u_max_V_q16;
    out = canfdi_pi_init(&spi, &sp);
    if (out == CANFDI_OK) {
      out = canfdi_pi_init(&cpi, &cp);
    }
    /* accel_max T in Q16.16: < 2^31 * 2^20 before the division. */
    dref = (((int64_t)cal->accel_max_rad_s2_q16 * (int64_t)CANFDI_CFG_STEP_US) + 500000) /
           1000000;
    if ((dref == 0) && (cal->accel_max_rad_s2_q16 > 0)) {
      dref = 1; /* a tiny rate still limits */
    }
    /* J accel / Psi: Q0.31 x Q16.16 = Q.47 (< 2^62), / Q16.16 -> Q.31,
     * rounded to Q16.16. */
    i_acc = ((int64_t)cal->j_kgm2_q31 * (int64_t)cal->accel_max_rad_s2_q16) /
            (int64_t)cal->psi_Vs_q16;
    i_acc = canfdi_asr64_rnd(i_acc, 15U);
  }
  if (out == CANFDI_OK) {
    c->cal = *cal;
    c->speed_pi = spi;
    c->cur_pi = cpi;
    c->dref_max_q16 = canfdi_sat_s64_to_s32(dref);
    c->inv_r_q16 = canfdi_div_s32_qn(CANFDI_Q16_ONE, cal->ra_ohm_q16, 16U);
    c->i_acc_q16 = canfdi_sat_s64_to_s32(i_acc);
    c->ref_lim_q16 = 0;
    c->out.ua_V_q16 = 0;
    c->out.ia_ref_A_q16 = 0;
    c->out.speed_ref_rad_s_q16 = 0;
    c->out.u_limit_V_q16 = 0;
    c->out.u_sat = 0;
    c->diag.steps = 0U;
    c->diag.rate_limited = 0U;
    c->diag.ref_clamped = 0U;
    c->diag.u_limited = 0U;
    c->diag.ia_limited = 0U;
    c->diag.model_steps = 0U;
    c->diag.held_steps = 0U;
    c->diag.off_steps = 0U;
  }
  return out;
}

/* a x b + c x d for Q16.16 operands, rounded half up to Q16.16, saturated.
 * Scaling and overflow: two exact Q32.32 products (|.| <= 2^62 each) added
 * with saturation. */
static int32_t dcm_mac2_q16(int32_t a, int32_t b, int32_t c, int32_t d)
{
  const int64_t s = canfdi_add_s64_sat(canfdi_smull32(a, b), canfdi_smull32(c, d));
  return canfdi_sat_s64_to_s32(canfdi_asr64_rnd(s, 16U));
}

/*
 * Moves the limited setpoint toward ref by at most dref_max (0 = jump) and
 * returns the acceleration feed-forward current of the move. The ramp
 * starts from the measured speed w instead when w lies between the limited
 * setpoint and ref: after the drive could not follow (a setpoint beyond its
 * reach, a load it could not hold), the limited setpoint does not first
 * have to ramp back through speeds the motor never reached.
 */
static int32_t dcm_rate_limit(canfdi_ctrl_dcm_t *c, int32_t ref_q16, int32_t w_q16)
{
  int32_t d;
  int32_t i_ff = 0;
  if ((ref_q16 < c->ref_lim_q16) && (w_q16 < c->ref_lim_q16)) {
    c->ref_lim_q16 = (w_q16 > ref_q16) ? w_q16 : ref_q16;
  } else if ((ref_q16 > c->ref_lim_q16) && (w_q16 > c->ref_lim_q16)) {
    c->ref_lim_q16 = (w_q16 < ref_q16) ? w_q16 : ref_q16;
  } else {
    /* the speed is behind the limited setpoint: ramp on from there */
  }
  d = canfdi_sub_s32_sat(ref_q16, c->ref_lim_q16);
  if ((c->dref_max_q16 > 0) && (d > c->dref_max_q16)) {
    c->ref_lim_q16 = canfdi_add_s32_sat(c->ref_lim_q16, c->dref_max_q16);
    i_ff = c->i_acc_q16;
    canfdi_count_inc(&c->diag.rate_limited);
  } else if ((c->dref_max_q16 > 0) && (d < -c->dref_max_q16)) {
    c->ref_lim_q16 = canfdi_sub_s32_sat(c->ref_lim_q16, c->dref_max_q16);
    i_ff = -c->i_acc_q16;
    canfdi_count_inc(&c->diag.rate_limited);
  } else {
    c->ref_lim_q16 = ref_q16;
  }
  return i_ff;
}

/* OFF: restart from the measured state, so that re-enabling gives no kick.
 * Returns the voltage command, 0. */
static int32_t dcm_off(canfdi_ctrl_dcm_t *c, const canfdi_ctrl_dcm_in_t *in)
{
  const int32_t w = in->speed_rad_s_q16;
  const int32_t w_max = c->cal.speed_max_rad_s_q16;
  c->ref_lim_q16 = canfdi_clamp_s32(w, -w_max, w_max);
  canfdi_pi_reset_q16(&c->speed_pi, 0, w);
  canfdi_pi_reset_q16(&c->cur_pi, 0, in->ia_A_q16);
  c->out.ia_ref_A_q16 = 0;
  c->out.speed_ref_rad_s_q16 = c->ref_lim_q16;
  c->out.u_sat = 0;
  canfdi_count_inc(&c->diag.off_steps);
  return 0;
}

/* FREEZE / TRACK: both PIs track the applied voltage (the speed PI through
 * the measured current, or the model current without the current loop) and
 * the rate limiter restarts from the measured speed. Returns the applied
 * voltage. */
static int32_t dcm_hold(canfdi_ctrl_dcm_t *c, const canfdi_ctrl_dcm_in_t *in, uint8_t mode, bool inner)
{
  const int32_t w = in->speed_rad_s_q16;
  const int32_t w_max = c->cal.speed_max_rad_s_q16;
  const int32_t u_app = (mode == CANFDI_CTRL_FREEZE) ? c->out.ua_V_q16 : in->u_track_V_q16;
  int32_t i_app = in->ia_A_q16;
  if (inner) {
    canfdi_pi_track_q16(&c->cur_pi, u_app);
  } else {
    /* Model current from U_A = R_nom i + Psi_nom w + (integrator). */
    const int32_t u_r = canfdi_sub_s32_sat(canfdi_sub_s32_sat(u_app, canfdi_pi_integral_q16(&c->cur_pi)),
                                           canfdi_mul_s32_qn(c->cal.psi_Vs_q16, w, 16U));
    i_app = canfdi_mul_s32_qn(u_r, c->inv_r_q16, 16U);
  }
  canfdi_pi_track_q16(&c->speed_pi, i_app);
  c->ref_lim_q16 = canfdi_clamp_s32(w, -w_max, w_max);
  c->out.u_sat = 0;
  canfdi_count_inc(&c->diag.held_steps);
  return u_app;
}

/* RUN (and the loops of FREEZE / TRACK before dcm_hold): rate limiter,
 * speed PI, feed-forward, current PI or its bypass, saturation flag.
 * Returns the voltage command; sets r, the reference the speed PI used. */
static int32_t dcm_loops(canfdi_ctrl_dcm_t *c, const canfdi_ctrl_dcm_in_t *in, int32_t ref, int32_t lim, bool inner,
                         int32_t *r)
{
  const canfdi_ctrl_dcm_cal_t *cal = &c->cal;
  const int32_t w = in->speed_rad_s_q16;
  const int32_t w_max = cal->speed_max_rad_s_q16;
  /* The voltage limit of the last step holds the speed integrator. */
  const bool aw = (cal->anti_windup == CANFDI_PI_AW_CLAMP);
  const uint32_t hold = (aw && (c->out.u_sat > 0))   ? CANFDI_PI_HOLD_UP
                        : (aw && (c->out.u_sat < 0)) ? CANFDI_PI_HOLD_DOWN
                                                     : CANFDI_PI_HOLD_NONE;
  const int32_t i_ff = dcm_rate_limit(c, ref, canfdi_clamp_s32(w, -w_max, w_max));
  int32_t i_ref;
  int32_t u_ff;
  int32_t u;
  *r = canfdi_add_s32_sat(c->ref_lim_q16, in->excite_rad_s_q16);
  i_ref = canfdi_pi_step_q16(&c->speed_pi, *r, w, i_ff, hold);
  if (canfdi_pi_saturation(&c->speed_pi) != 0) {
    canfdi_count_inc(&c->diag.ia_limited);
  }
  u_ff = dcm_mac2_q16(cal->ra_ohm_q16, i_ref, cal->psi_Vs_q16, w);
  if (inner) {
    u = canfdi_pi_step_q16(&c->cur_pi, i_ref, in->ia_A_q16, u_ff, CANFDI_PI_HOLD_NONE);
  } else {
    /* Bypass: the held current integrator carries the learned model error. */
    u = canfdi_clamp_s32(canfdi_add_s32_sat(u_ff, canfdi_pi_integral_q16(&c->cur_pi)), -lim, lim);
    canfdi_count_inc(&c->diag.model_steps);
  }
  c->out.u_sat = (u >= lim) ? 1 : ((u <= -lim) ? -1 : 0);
  if (lim == 0) {
    c->out.u_sat = 0; /* no supply: nothing to wind against in either direction */
  }
  if (c->out.u_sat != 0) {
    canfdi_count_inc(&c->diag.u_limited);
  }
  return u;
}

int32_t canfdi_ctrl_dcm_step(canfdi_ctrl_dcm_t *c, const canfdi_ctrl_dcm_in_t *in,
                             canfdi_ctrl_dcm_out_t *out)
{
  const canfdi_ctrl_dcm_cal_t *cal = &c->cal;
  const int32_t w_max = cal->speed_max_rad_s_q16;
  const bool inner = cal->current_loop && in->ia_valid;
  const uint8_t mode = (in->mode <= CANFDI_CTRL_OFF) ? in->mode : (uint8_t)CANFDI_CTRL_OFF;
  int32_t lim = (in->supply_V_q16 < cal->u_max_V_q16) ? in->supply_V_q16 : cal->u_max_V_q16;
  int32_t ref = in->speed_ref_rad_s_q16;
  int32_t u;

  lim = (lim > 0) ? lim : 0;
  (void)canfdi_pi_set_limits_q16(&c->cur_pi, -lim, lim); /* -lim <= lim: cannot fail */
  c->out.u_limit_V_q16 = lim;
  if ((ref > w_max) || (ref < -w_max)) {
    ref = canfdi_clamp_s32(ref, -w_max, w_max);
    canfdi_count_inc(&c->diag.ref_clamped);
  }
  if (mode == CANFDI_CTRL_OFF) {
    u = dcm_off(c, in);
  } else {
    int32_t r;
    u = dcm_loops(c, in, ref, lim, inner, &r);
    if ((mode == CANFDI_CTRL_FREEZE) || (mode == CANFDI_CTRL_TRACK)) {
      u = dcm_hold(c, in, mode, inner);
    }
    c->out.ia_ref_A_q16 = canfdi_pi_out_q16(&c->speed_pi);
    c->out.speed_ref_rad_s_q16 = r;
  }
  c->out.ua_V_q16 = u;
  canfdi_count_inc(&c->diag.steps);
  if (out != NULL) {
    *out = c->out;
  }
  return u;
}

const canfdi_ctrl_dcm_diag_t *canfdi_ctrl_dcm_diag(const canfdi_ctrl_dcm_t *c)
{
  return &c->diag;
}

const canfdi_pi_diag_t *canfdi_ctrl_dcm_pi_diag(const canfdi_ctrl_dcm_t *c, bool outer)
{
  return outer ? canfdi_pi_diag(&c->speed_pi) : canfdi_pi_diag(&c->cur_pi);
}
