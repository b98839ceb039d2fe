/*
 * canfdi_adapt.c — adaptive residual threshold; the manual is the header.
 */
#include "detect/canfdi_adapt.h"

#include "core/canfdi_count.h"

CANFDI_STATIC_ASSERT((CANFDI_CFG_STEP_US >= 100U) && (CANFDI_CFG_STEP_US <= 1000000U), adapt_step_range);
CANFDI_STATIC_ASSERT((1000000U % CANFDI_CFG_STEP_US) == 0U, adapt_step_divides_1s);

#define STEPS_PER_S ((int64_t)(1000000U / CANFDI_CFG_STEP_US))
#define FRAC 16U

int32_t canfdi_adapt_cfg_check(const canfdi_adapt_cfg_t *cfg)
{
  int32_t out = -CANFDI_EINVAL;
  if ((cfg != NULL) && (cfg->base >= 0) && (cfg->max >= cfg->base) && (cfg->gain >= 0) &&
      (cfg->tau_us <= CANFDI_ADAPT_TAU_MAX_US) && (cfg->gain_frac_bits <= CANFDI_ADAPT_GAIN_FRAC_MAX)) {
    out = CANFDI_OK;
  }
  return out;
}

static void clear_filter(canfdi_adapt_t *a, int32_t base)
{
  a->f_q16 = 0;
  a->u_prev = 0;
  a->threshold = base;
  a->primed = false;
}

int32_t canfdi_adapt_init(canfdi_adapt_t *a, const canfdi_adapt_cfg_t *cfg)
{
  int32_t out = -CANFDI_EINVAL;
  if (a != NULL) {
    a->cfg = NULL;
    a->alpha_q31 = 0;
    a->diag.rate_saturations = 0U;
    a->diag.cap_hits = 0U;
    clear_filter(a, 0);
    if (canfdi_adapt_cfg_check(cfg) == CANFDI_OK) {
      const int32_t step_us = (int32_t)CANFDI_CFG_STEP_US;
      /* T + tau <= 1.01e8 fits int32_t; tau == 0 gives 1 - 2^-31. */
      a->alpha_q31 = canfdi_div_s32_qn(step_us, step_us + (int32_t)cfg->tau_us, 31U);
      CANFDI_ASSERT(a->alpha_q31 > 0);
      a->threshold = cfg->base;
      a->cfg = cfg;
      out = CANFDI_OK;
    }
  }
  return out;
}

int32_t canfdi_adapt_excitation(const canfdi_adapt_t *a)
{
  return (a != NULL) ? canfdi_sat_s64_to_s32(canfdi_asr64_rnd(a->f_q16, FRAC)) : 0;
}

int32_t canfdi_adapt_step(canfdi_adapt_t *a, int32_t u)
{
  int32_t out = -CANFDI_EINVAL;
  if ((a != NULL) && (a->cfg != NULL)) {
    const canfdi_adapt_cfg_t *cfg = a->cfg;
    if (a->primed) {
      /* |du| < 2^32; |du| 10^6/T is compared before it is formed, so that
       * the product that is formed fits 32 bits (a 64-bit product is a
       * libgcc call on ARMv6-M) */
      int64_t du = (int64_t)u - (int64_t)a->u_prev;
      int64_t rate;
      du = (du < 0) ? -du : du;
      if (du > (INT32_MAX / STEPS_PER_S)) {
        rate = INT32_MAX;
        canfdi_count_inc(&a->diag.rate_saturations);
      } else {
        rate = (int64_t)((int32_t)du * (int32_t)STEPS_PER_S);
      }
      /* f and rate * 2^16 are in [0, 2^47): the difference cannot overflow
       * and a rounded step of alpha < 1 does not overshoot, so f >= 0. */
      a->f_q16 += canfdi_mul_s64_q31((rate * ((int64_t)1 << FRAC)) - a->f_q16, a->alpha_q31);
      CANFDI_ASSERT(a->f_q16 >= 0);
      {
        const int32_t add = canfdi_mul_s32_qn(canfdi_adapt_excitation(a), cfg->gain, cfg->gain_frac_bits);
        int32_t thr = canfdi_add_s32_sat(cfg->base, add);
        if (thr > cfg->max) {
          thr = cfg->max;
          canfdi_count_inc(&a->diag.cap_hits);
        }
        a->threshold = thr;
      }
    } else {
      a->primed = true;
      a->threshold = cfg->base;
    }
    a->u_prev = u;
    out = a->threshold;
  }
  return out;
}

bool canfdi_adapt_exceeds(const canfdi_adapt_t *a, int32_t residual)
{
  bool ex = false;
  if ((a != NULL) && (a->cfg != NULL)) {
    const int64_t r = (int64_t)residual;
    ex = ((r < 0) ? -r : r) > (int64_t)a->threshold;
  }
  return ex;
}

int32_t canfdi_adapt_threshold(const canfdi_adapt_t *a)
{
  return (a != NULL) ? a->threshold : 0;
}

void canfdi_adapt_reset(canfdi_adapt_t *a)
{
  if ((a != NULL) && (a->cfg != NULL)) {
    clear_filter(a, a->cfg->base);
  }
}
