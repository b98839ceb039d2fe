/*
 * canfdi_ctrl_thr.c — throttle position control; see canfdi_ctrl_thr.h.
 */
#include "ctrl/canfdi_ctrl_thr.h"

#include "core/canfdi_count.h"
#include "core/canfdi_fixp.h"
#include "core/canfdi_qconst.h"

void canfdi_ctrl_thr_cal_default(canfdi_ctrl_thr_cal_t *cal)
{
  cal->r_ohm_q16 = CANFDI_Q16_MILLI(1500);
  cal->k_Nm_A_q16 = CANFDI_Q16_MILLI(383);
  cal->spring_Nm_rad_q16 = CANFDI_Q16_MILLI(87);
  cal->pretension_Nm_q16 = CANFDI_Q16_MILLI(396);
  cal->friction_Nm_q16 = CANFDI_Q16_MILLI(284);
  cal->b_Nms_q16 = CANFDI_Q16(88, 10000);
  cal->limp_home_rad_q16 = CANFDI_Q16_DEG(65, 10);
  cal->pretension_band_rad_q16 = CANFDI_Q16_DEG(1, 10);
  cal->friction_deadband_rad_q16 = CANFDI_Q16_DEG(2, 10);
  cal->spring_comp = true;
  cal->friction_comp = true;
  cal->velocity_ff = true;
  cal->kp_V_rad_q16 = CANFDI_Q16(356, 1);
  cal->ki_V_rad_s_q16 = CANFDI_Q16(3000, 1);
  cal->kd_V_s_rad_q16 = CANFDI_Q16_MILLI(2550);
  cal->kd_tau_us = 2000U;
  cal->i_band_rad_q16 = CANFDI_Q16_DEG(1, 1);
  cal->angle_min_rad_q16 = CANFDI_Q16_DEG(5, 10);
  cal->angle_max_rad_q16 = CANFDI_Q16_DEG(88, 1);
  cal->u_max_V_q16 = CANFDI_Q16(16, 1);
  cal->rate_max_rad_s_q16 = 0;
}

int32_t canfdi_ctrl_thr_init(canfdi_ctrl_thr_t *c, const canfdi_ctrl_thr_cal_t *cal)
{
  int32_t out = CANFDI_OK;
  canfdi_pi_cfg_t pc;
  canfdi_pi_t pid;
  int32_t r_over_k = 0;
  int32_t pre_slope = 0;
  int64_t dref = 0;
  int32_t u_vel = 0;

  if ((c == NULL) || (cal == NULL)) {
    out = -CANFDI_EINVAL;
  } else if ((cal->r_ohm_q16 <= 0) || (cal->k_Nm_A_q16 <= 0) || (cal->u_max_V_q16 <= 0) ||
             (cal->pretension_band_rad_q16 <= 0) || (cal->spring_Nm_rad_q16 < 0) ||
             (cal->pretension_Nm_q16 < 0) || (cal->friction_Nm_q16 < 0) || (cal->b_Nms_q16 < 0) ||
             (cal->friction_deadband_rad_q16 < 0) || (cal->rate_max_rad_s_q16 < 0) ||
             (cal->angle_min_rad_q16 > cal->angle_max_rad_q16)) {
    out = -CANFDI_EINVAL;
  } else {
    r_over_k = canfdi_div_s32_qn(cal->r_ohm_q16, cal->k_Nm_A_q16, 16U);
    pre_slope = canfdi_div_s32_qn(cal->pretension_Nm_q16, cal->pretension_band_rad_q16, 16U);
    if ((r_over_k == INT32_MAX) || (pre_slope == INT32_MAX)) {
      out = -CANFDI_EINVAL; /* saturated: not representable */
    }
    pc.kp_q16 = cal->kp_V_rad_q16;
    pc.ki_q16 = cal->ki_V_rad_s_q16;
    pc.kd_q16 = cal->kd_V_s_rad_q16;
    pc.kd_tau_us = cal->kd_tau_us;
    pc.i_band_q16 = cal->i_band_rad_q16;
    pc.out_min_q16 = -cal->u_max_V_q16;
    pc.out_max_q16 = cal->u_max_V_q16;
    pc.anti_windup = CANFDI_PI_AW_CLAMP;
    if (out == CANFDI_OK) {
      out = canfdi_pi_init(&pid, &pc);
    }
    /* rate_max T in Q16.16: < 2^31 * 2^20 before the division. */
    dref = (((int64_t)cal->rate_max_rad_s_q16 * (int64_t)CANFDI_CFG_STEP_US) + 500000) / 1000000;
    if ((dref == 0) && (cal->rate_max_rad_s_q16 > 0)) {
      dref = 1;
    }
    /* (K + (R/K) B + kd) rate_max: V per rad/s terms in Q16.16, each product
     * rounded, the sum saturated (a huge kd x rate only saturates the
     * feed-forward, which the output limit clips anyway). */
    u_vel = canfdi_add_s32_sat(
        canfdi_add_s32_sat(cal->k_Nm_A_q16, canfdi_mul_s32_qn(r_over_k, cal->b_Nms_q16, 16U)),
        cal->kd_V_s_rad_q16);
    u_vel = canfdi_mul_s32_qn(u_vel, cal->rate_max_rad_s_q16, 16U);
  }
  if (out == CANFDI_OK) {
    c->cal = *cal;
    c->r_over_k_q16 = r_over_k;
    c->pre_slope_q16 = pre_slope;
    c->dref_max_q16 = canfdi_sat_s64_to_s32(dref);
    c->u_vel_q16 = u_vel;
    c->pid = pid;
    c->ref_lim_q16 = 0;
    c->ref_primed = false;
    c->out.u_V_q16 = 0;
    c->out.u_ff_V_q16 = 0;
    c->out.angle_ref_rad_q16 = 0;
    c->out.u_limit_V_q16 = 0;
    c->out.u_sat = 0;
    c->diag.steps = 0U;
    c->diag.ref_clamped = 0U;
    c->diag.rate_limited = 0U;
    c->diag.u_limited = 0U;
    c->diag.held_steps = 0U;
    c->diag.off_steps = 0U;
  }
  return out;
}

int32_t canfdi_ctrl_thr_ff_q16(const canfdi_ctrl_thr_t *c, int32_t ref_rad_q16, int32_t err_rad_q16)
{
  const canfdi_ctrl_thr_cal_t *cal = &c->cal;
  int64_t t = 0; /* torque, Q32.32 */
  if (cal->spring_comp) {
    const int32_t d = canfdi_sub_s32_sat(ref_rad_q16, cal->limp_home_rad_q16);
    const int64_t p = (int64_t)cal->pretension_Nm_q16 * 65536;
    int64_t pre = canfdi_smull32(c->pre_slope_q16, d); /* exact, |.| <= 2^62 */
    if (pre > p) {
      pre = p;
    } else if (pre < -p) {
      pre = -p;
    } else {
      /* on the ramp */
    }
    t = canfdi_add_s64_sat(canfdi_smull32(cal->spring_Nm_rad_q16, d), pre);
  }
  if (cal->friction_comp) {
    const int64_t tc = (int64_t)cal->friction_Nm_q16 * 65536;
    if (err_rad_q16 > cal->friction_deadband_rad_q16) {
      t = canfdi_add_s64_sat(t, tc);
    } else if (err_rad_q16 < -cal->friction_deadband_rad_q16) {
      t = canfdi_sub_s64_sat(t, tc);
    } else {
      /* at rest inside the dead band: no friction term */
    }
  }
  return canfdi_mul_s32_qn(c->r_over_k_q16, canfdi_sat_s64_to_s32(canfdi_asr64_rnd(t, 16U)), 16U);
}

/* Moves the limited setpoint toward ref by at most dref_max (0 = jump);
 * returns the direction of the move (+1, -1, 0 when it reached ref). */
static int32_t thr_rate_limit(canfdi_ctrl_thr_t *c, int32_t ref_q16)
{
  const int32_t d = canfdi_sub_s32_sat(ref_q16, c->ref_lim_q16);
  int32_t dir = 0;
  if ((c->dref_max_q16 > 0) && (d > c->dref_max_q16)) {
    c->ref_lim_q16 = canfdi_add_s32_sat(c->ref_lim_q16, c->dref_max_q16);
    dir = 1;
    canfdi_count_inc(&c->diag.rate_limited);
  } else if ((c->dref_max_q16 > 0) && (d < -c->dref_max_q16)) {
    c->ref_lim_q16 = canfdi_sub_s32_sat(c->ref_lim_q16, c->dref_max_q16);
    dir = -1;
    canfdi_count_inc(&c->diag.rate_limited);
  } else {
    c->ref_lim_q16 = ref_q16;
  }
  return dir;
}

int32_t canfdi_ctrl_thr_step(canfdi_ctrl_thr_t *c, const canfdi_ctrl_thr_in_t *in,
                             canfdi_ctrl_thr_out_t *out)
{
  const canfdi_ctrl_thr_cal_t *cal = &c->cal;
  const int32_t th = in->angle_rad_q16;
  const uint8_t mode = (in->mode <= CANFDI_CTRL_OFF) ? in->mode : (uint8_t)CANFDI_CTRL_OFF;
  const int32_t th_lim = canfdi_clamp_s32(th, cal->angle_min_rad_q16, cal->angle_max_rad_q16);
  int32_t lim = (in->supply_V_q16 < cal->u_max_V_q16) ? in->supply_V_q16 : cal->u_max_V_q16;
  int32_t ref = in->angle_ref_rad_q16;
  int32_t u;

  lim = (lim > 0) ? lim : 0;
  (void)canfdi_pi_set_limits_q16(&c->pid, -lim, lim); /* -lim <= lim: cannot fail */
  c->out.u_limit_V_q16 = lim;
  if ((ref > cal->angle_max_rad_q16) || (ref < cal->angle_min_rad_q16)) {
    ref = canfdi_clamp_s32(ref, cal->angle_min_rad_q16, cal->angle_max_rad_q16);
    canfdi_count_inc(&c->diag.ref_clamped);
  }
  if (!c->ref_primed) {
    c->ref_lim_q16 = th_lim; /* a rate-limited start moves from where it is */
    c->ref_primed = true;
  }

  if (mode == CANFDI_CTRL_OFF) {
    c->ref_lim_q16 = th_lim;
    canfdi_pi_reset_q16(&c->pid, 0, th);
    c->out.u_ff_V_q16 = 0;
    c->out.angle_ref_rad_q16 = th_lim;
    c->out.u_sat = 0;
    u = 0;
    canfdi_count_inc(&c->diag.off_steps);
  } else {
    const int32_t dir = thr_rate_limit(c, ref);
    const int32_t r = canfdi_add_s32_sat(c->ref_lim_q16, in->excite_rad_q16);
    int32_t u_ff = canfdi_ctrl_thr_ff_q16(c, r, canfdi_sub_s32_sat(r, th));
    if (cal->velocity_ff) {
      u_ff = canfdi_add_s32_sat(u_ff, (dir > 0) ? c->u_vel_q16 : ((dir < 0) ? -c->u_vel_q16 : 0));
    }
    u = canfdi_pi_step_q16(&c->pid, r, th, u_ff, CANFDI_PI_HOLD_NONE);
    c->out.u_sat = canfdi_pi_saturation(&c->pid);
    if (lim == 0) {
      c->out.u_sat = 0;
    }
    if (c->out.u_sat != 0) {
      canfdi_count_inc(&c->diag.u_limited);
    }
    if ((mode == CANFDI_CTRL_FREEZE) || (mode == CANFDI_CTRL_TRACK)) {
      const int32_t u_app = (mode == CANFDI_CTRL_FREEZE) ? c->out.u_V_q16 : in->u_track_V_q16;
      canfdi_pi_track_q16(&c->pid, u_app);
      c->ref_lim_q16 = th_lim;
      u = u_app;
      c->out.u_sat = 0;
      canfdi_count_inc(&c->diag.held_steps);
    }
    c->out.u_ff_V_q16 = u_ff;
    c->out.angle_ref_rad_q16 = r;
  }
  c->out.u_V_q16 = u;
  canfdi_count_inc(&c->diag.steps);
  if (out != NULL) {
    *out = c->out;
  }
  return u;
}

const canfdi_ctrl_thr_diag_t *canfdi_ctrl_thr_diag(const canfdi_ctrl_thr_t *c)
{
  return &c->diag;
}

const canfdi_pi_diag_t *canfdi_ctrl_thr_pi_diag(const canfdi_ctrl_thr_t *c)
{
  return canfdi_pi_diag(&c->pid);
}
