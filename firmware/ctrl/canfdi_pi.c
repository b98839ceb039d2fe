/*
 * canfdi_pi.c — PI(D) controller in fixed point; see canfdi_pi.h.
 */
#include "ctrl/canfdi_pi.h"

#include "core/canfdi_count.h"
#include "core/canfdi_fixp.h"

#define PI_US_PER_S 1000000U

/* The gain conversions in init keep their products below 2^63 for steps
 * shorter than ~1 s. */
CANFDI_STATIC_ASSERT((CANFDI_CFG_STEP_US > 0U) && (CANFDI_CFG_STEP_US < (1UL << 20)),
                     pi_step_us_in_range);

/* Q16.16 -> Q31.32 (exact; |x| * 2^16 < 2^47). */
static int64_t pi_q16_to_q32(int32_t x)
{
  return (int64_t)x * 65536;
}

/*
 * round(num / den), ties away from zero, for num >= 0 and den > 0 in
 * uint64_t. Scaling and overflow: the caller keeps num + den / 2 < 2^64.
 * Cost: one 64/64 division (__aeabi_uldivmod); init time only.
 */
static uint64_t pi_div_rnd_u64(uint64_t num, uint64_t den)
{
  return (num + (den / 2U)) / den;
}

/*
 * Signed gain g (Q16.16) times an unsigned scale factor mul, divided by den,
 * rounded: round(g * mul / den) as int64_t. Scaling and overflow: the caller
 * keeps |g| * mul < 2^63 (|g| <= 2^31 and mul <= 2^31 here).
 */
static int64_t pi_scale_gain(int32_t g, uint64_t mul, uint64_t den)
{
  const bool neg = (g < 0);
  const uint64_t mag = neg ? (uint64_t)(-(int64_t)g) : (uint64_t)g;
  const uint64_t q = pi_div_rnd_u64(mag * mul, den);
  return neg ? -(int64_t)q : (int64_t)q;
}

/* State of a restart at output u0 with previous measurement y0. */
static void pi_restart(canfdi_pi_t *pi, int32_t u0_q16, int32_t meas0_q16)
{
  pi->i_q32 = pi_q16_to_q32(u0_q16);
  pi->d_q32 = 0;
  pi->pdf_q32 = 0;
  pi->y_prev_q16 = meas0_q16;
  pi->primed = true;
  pi->out_q16 = u0_q16;
  pi->sat = 0;
}

int32_t canfdi_pi_init(canfdi_pi_t *pi, const canfdi_pi_cfg_t *cfg)
{
  int32_t out = CANFDI_OK;
  /* T in microseconds; the config guarantees a positive step. */
  const uint64_t t_us = (uint64_t)CANFDI_CFG_STEP_US;
  int64_t kit = 0;
  int64_t dc = 0;
  uint64_t da = 0U;

  if ((pi == NULL) || (cfg == NULL)) {
    out = -CANFDI_EINVAL;
  } else if ((cfg->out_min_q16 > cfg->out_max_q16) || (cfg->i_band_q16 < 0) ||
             (cfg->kd_q16 < 0) || (cfg->kd_tau_us > (uint32_t)INT32_MAX) ||
             ((cfg->anti_windup != CANFDI_PI_AW_CLAMP) && (cfg->anti_windup != CANFDI_PI_AW_NONE))) {
    out = -CANFDI_EINVAL;
  } else {
    const uint64_t tau_t_us = (uint64_t)cfg->kd_tau_us + t_us;
    /* ki T in Q8.24: ki_q16 * T_us * 2^8 / 10^6; |ki| T_us 2^8 < 2^59. */
    kit = pi_scale_gain(cfg->ki_q16, t_us * 256U, PI_US_PER_S);
    /* a = tau / (tau + T) in Q31: tau * 2^31 < 2^62. */
    da = pi_div_rnd_u64((uint64_t)cfg->kd_tau_us << 31, tau_t_us);
    /* c = kd / (tau + T) in Q16.16: kd_q16 * 10^6 < 2^51. */
    dc = pi_scale_gain(cfg->kd_q16, PI_US_PER_S, tau_t_us);
    if ((kit > INT32_MAX) || (kit < -INT32_MAX) || (dc > INT32_MAX) ||
        (da > (uint64_t)INT32_MAX)) {
      out = -CANFDI_EINVAL;
    }
  }
  if (out == CANFDI_OK) {
    pi->kp_q16 = cfg->kp_q16;
    pi->kit_q24 = (int32_t)kit;
    pi->da_q31 = (int32_t)da;
    pi->dc_q16 = (int32_t)dc;
    pi->i_band_q16 = cfg->i_band_q16;
    pi->out_min_q16 = cfg->out_min_q16;
    pi->out_max_q16 = cfg->out_max_q16;
    pi->anti_windup = cfg->anti_windup;
    pi->diag.steps = 0U;
    pi->diag.sat_hi = 0U;
    pi->diag.sat_lo = 0U;
    pi->diag.int_holds = 0U;
    pi->diag.tracks = 0U;
    pi->diag.resets = 0U;
    pi_restart(pi, 0, 0);
    pi->primed = false; /* the first step takes no derivative */
  }
  return out;
}

int32_t canfdi_pi_set_limits_q16(canfdi_pi_t *pi, int32_t lo_q16, int32_t hi_q16)
{
  int32_t out = CANFDI_OK;
  if (lo_q16 > hi_q16) {
    out = -CANFDI_EINVAL;
  } else {
    pi->out_min_q16 = lo_q16;
    pi->out_max_q16 = hi_q16;
  }
  return out;
}

/* Whether the integrator increment inc must be rejected (see the header). */
static bool pi_reject(const canfdi_pi_t *pi, int64_t inc, int64_t u_tent, uint32_t hold)
{
  bool rej = false;
  if (inc > 0) {
    rej = ((hold & CANFDI_PI_HOLD_UP) != 0U) ||
          ((pi->anti_windup == CANFDI_PI_AW_CLAMP) && (u_tent > pi_q16_to_q32(pi->out_max_q16)));
  } else if (inc < 0) {
    rej = ((hold & CANFDI_PI_HOLD_DOWN) != 0U) ||
          ((pi->anti_windup == CANFDI_PI_AW_CLAMP) && (u_tent < pi_q16_to_q32(pi->out_min_q16)));
  } else {
    /* nothing to integrate */
  }
  return rej;
}

int32_t canfdi_pi_step_q16(canfdi_pi_t *pi, int32_t ref_q16, int32_t meas_q16, int32_t ff_q16,
                           uint32_t hold)
{
  const int32_t e = canfdi_sub_s32_sat(ref_q16, meas_q16);
  const int64_t ff = pi_q16_to_q32(ff_q16);
  const int64_t p = canfdi_smull32(pi->kp_q16, e); /* Q32.32, |p| <= 2^62 */
  const int32_t dy = pi->primed ? canfdi_sub_s32_sat(meas_q16, pi->y_prev_q16) : 0;
  const int64_t e64 = (int64_t)e;
  int64_t inc = 0;
  int64_t i_new;
  int64_t u;
  int32_t u_q16;

  /* D = a D - c dy; c dy is an exact Q32.32 product (|.| <= 2^62). A PI
   * (c = 0) keeps D = 0 and skips the multiplies. */
  if (pi->dc_q16 != 0) {
    pi->d_q32 = canfdi_sub_s64_sat(canfdi_mul_s64_q31(pi->d_q32, pi->da_q31),
                                   canfdi_smull32(pi->dc_q16, dy));
  }
  pi->y_prev_q16 = meas_q16;
  pi->primed = true;
  pi->pdf_q32 = canfdi_add_s64_sat(canfdi_add_s64_sat(ff, p), pi->d_q32);

  if ((pi->i_band_q16 == 0) ||
      ((e64 <= (int64_t)pi->i_band_q16) && (e64 >= -(int64_t)pi->i_band_q16))) {
    /* Q8.24 x Q16.16 = Q.40, rounded to Q.32. */
    inc = canfdi_asr64_rnd(canfdi_smull32(pi->kit_q24, e), 8U);
  }
  i_new = canfdi_add_s64_sat(pi->i_q32, inc);
  if (pi_reject(pi, inc, canfdi_add_s64_sat(pi->pdf_q32, i_new), hold)) {
    i_new = pi->i_q32;
    canfdi_count_inc(&pi->diag.int_holds);
  }
  if (pi->anti_windup == CANFDI_PI_AW_CLAMP) {
    /* I alone must not exceed the limits on top of ff: I in
     * [min(min - ff, 0), max(max - ff, 0)]. Zero stays inside so that a
     * feed-forward that saturates the output on its own never drags I
     * the other way (it would be a wound-up integrator when ff returns).
     * Both bounds are exact int64 (|.| < 2^48) and lo <= 0 <= hi. */
    int64_t lo = pi_q16_to_q32(pi->out_min_q16) - ff;
    int64_t hi = pi_q16_to_q32(pi->out_max_q16) - ff;
    lo = (lo < 0) ? lo : 0;
    hi = (hi > 0) ? hi : 0;
    if (i_new > hi) {
      i_new = hi;
    } else if (i_new < lo) {
      i_new = lo;
    } else {
      /* inside */
    }
  }
  pi->i_q32 = i_new;

  u = canfdi_add_s64_sat(pi->pdf_q32, pi->i_q32);
  u_q16 = canfdi_sat_s64_to_s32(canfdi_asr64_rnd(u, 16U));
  pi->sat = 0;
  if (u_q16 > pi->out_max_q16) {
    u_q16 = pi->out_max_q16;
    pi->sat = 1;
    canfdi_count_inc(&pi->diag.sat_hi);
  } else if (u_q16 < pi->out_min_q16) {
    u_q16 = pi->out_min_q16;
    pi->sat = -1;
    canfdi_count_inc(&pi->diag.sat_lo);
  } else {
    /* inside the limits */
  }
  pi->out_q16 = u_q16;
  canfdi_count_inc(&pi->diag.steps);
  return u_q16;
}

void canfdi_pi_track_q16(canfdi_pi_t *pi, int32_t u_applied_q16)
{
  pi->i_q32 = canfdi_sub_s64_sat(pi_q16_to_q32(u_applied_q16), pi->pdf_q32);
  pi->out_q16 = u_applied_q16;
  canfdi_count_inc(&pi->diag.tracks);
}

void canfdi_pi_reset_q16(canfdi_pi_t *pi, int32_t u0_q16, int32_t meas0_q16)
{
  pi_restart(pi, u0_q16, meas0_q16);
  canfdi_count_inc(&pi->diag.resets);
}

int32_t canfdi_pi_out_q16(const canfdi_pi_t *pi)
{
  return pi->out_q16;
}

int32_t canfdi_pi_integral_q16(const canfdi_pi_t *pi)
{
  return canfdi_sat_s64_to_s32(canfdi_asr64_rnd(pi->i_q32, 16U));
}

int32_t canfdi_pi_saturation(const canfdi_pi_t *pi)
{
  return (int32_t)pi->sat;
}

const canfdi_pi_diag_t *canfdi_pi_diag(const canfdi_pi_t *pi)
{
  return &pi->diag;
}
