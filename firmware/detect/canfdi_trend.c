/*
 * canfdi_trend.c — filtered derivative and rate-limit check; the manual is
 * the header.
 */
#include "detect/canfdi_trend.h"

#include "core/canfdi_count.h"

/* The rate scale 10^6 / T must be an exact integer, and small enough that
 * d1 = (y1[k] - y1[k-1]) * steps_per_s stays below 2^62 (see the header). */
CANFDI_STATIC_ASSERT((CANFDI_CFG_STEP_US >= 100U) && (CANFDI_CFG_STEP_US <= 1000000U), trend_step_range);
CANFDI_STATIC_ASSERT((1000000U % CANFDI_CFG_STEP_US) == 0U, trend_step_divides_1s);

#define STEPS_PER_S ((int64_t)(1000000U / CANFDI_CFG_STEP_US))

int32_t canfdi_trend_cfg_check(const canfdi_trend_cfg_t *cfg)
{
  int32_t out = -CANFDI_EINVAL;
  if ((cfg != NULL) && (cfg->tau_us <= CANFDI_TREND_TAU_MAX_US) &&
      ((cfg->order == 1U) || (cfg->order == 2U)) &&
      (cfg->rate_frac_bits <= CANFDI_TREND_RATE_FRAC_MAX) &&
      (canfdi_limit_cfg_check(&cfg->rate_limit) == CANFDI_OK)) {
    out = CANFDI_OK;
  }
  return out;
}

static void clear_filter(canfdi_trend_t *t)
{
  t->y1_q16 = 0;
  t->y2_q16 = 0;
  t->rate = 0;
  t->primed = false;
}

int32_t canfdi_trend_init(canfdi_trend_t *t, const canfdi_trend_cfg_t *cfg)
{
  int32_t out = -CANFDI_EINVAL;
  if (t != NULL) {
    t->cfg = NULL;
    t->diag.rate_saturations = 0U;
    t->alpha_q31 = 0;
    clear_filter(t);
    if ((canfdi_trend_cfg_check(cfg) == CANFDI_OK) &&
        (canfdi_limit_init(&t->limit, &cfg->rate_limit) == CANFDI_OK)) {
      /* T + tau <= 10^8 + 10^6 fits int32_t. tau == 0 gives alpha = 1,
       * which saturates to 1 - 2^-31: a pure difference quotient. */
      const int32_t step_us = (int32_t)CANFDI_CFG_STEP_US;
      t->alpha_q31 = canfdi_div_s32_qn(step_us, step_us + (int32_t)cfg->tau_us, 31U);
      CANFDI_ASSERT(t->alpha_q31 > 0);
      t->cfg = cfg;
      out = CANFDI_OK;
    }
  }
  return out;
}

int32_t canfdi_trend_step(canfdi_trend_t *t, int32_t x)
{
  int32_t out = -CANFDI_EINVAL;
  if ((t != NULL) && (t->cfg != NULL)) {
    const canfdi_trend_cfg_t *cfg = t->cfg;
    /* |x| * 2^16 <= 2^47: exact. */
    const int64_t x_q16 = (int64_t)x * ((int64_t)1 << CANFDI_TREND_FRAC);
    if (!t->primed) {
      t->y1_q16 = x_q16;
      t->y2_q16 = 0;
      t->rate = 0;
      t->primed = true;
      out = (int32_t)canfdi_limit_status(&t->limit);
    } else {
      /* Stage 1: |x_q16 - y1| < 2^48 since y1 stays within past inputs. */
      const int64_t dy1 = canfdi_mul_s64_q31(x_q16 - t->y1_q16, t->alpha_q31);
      /* |dy1| < 2^48, times 10^6/T <= 10^4: < 2^62, no overflow. */
      const int64_t d1 = dy1 * STEPS_PER_S;
      int64_t r_q16 = d1;
      int64_t r_out;
      t->y1_q16 += dy1;
      if (cfg->order == 2U) {
        t->y2_q16 += canfdi_mul_s64_q31(canfdi_sub_s64_sat(d1, t->y2_q16), t->alpha_q31);
        r_q16 = t->y2_q16;
      }
      r_out = canfdi_asr64_rnd(r_q16, CANFDI_TREND_FRAC - (unsigned)cfg->rate_frac_bits);
      t->rate = canfdi_sat_s64_to_s32(r_out);
      if ((int64_t)t->rate != r_out) {
        canfdi_count_inc(&t->diag.rate_saturations);
      }
      out = canfdi_limit_step(&t->limit, t->rate);
    }
  }
  return out;
}

void canfdi_trend_reset(canfdi_trend_t *t)
{
  if ((t != NULL) && (t->cfg != NULL)) {
    clear_filter(t);
    canfdi_limit_reset(&t->limit);
  }
}

int32_t canfdi_trend_rate(const canfdi_trend_t *t)
{
  return (t != NULL) ? t->rate : 0;
}

int32_t canfdi_trend_filtered(const canfdi_trend_t *t)
{
  /* y1 is within the int32 range of past inputs, rounding cannot leave it
   * (INT32_MAX * 2^16 rounds to INT32_MAX); saturate anyway for safety. */
  return (t != NULL) ? canfdi_sat_s64_to_s32(canfdi_asr64_rnd(t->y1_q16, CANFDI_TREND_FRAC)) : 0;
}

canfdi_deb_status_t canfdi_trend_status(const canfdi_trend_t *t)
{
  return (t != NULL) ? canfdi_limit_status(&t->limit) : CANFDI_DEB_UNDECIDED;
}
