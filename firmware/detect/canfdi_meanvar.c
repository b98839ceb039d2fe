/*
 * canfdi_meanvar.c — recursive mean and variance with exponential
 * forgetting. The header is the manual (formats, error bounds, cost).
 */
#include "detect/canfdi_meanvar.h"

#include "core/canfdi_count.h"

/* x * 2^32 by multiplication: exact in int64_t for |x| <= 2^21, and unlike
 * a left shift defined for negative x. A 64-bit scale factor of this module
 * alone: core/canfdi_qconst.h holds the int32_t Q16.16 and Q8.24 constants. */
#define MEANVAR_ONE_Q32 ((int64_t)1 << 32)
#define MEANVAR_D_FRAC 10U  /* fraction bits of d = x - mean */
#define MEANVAR_V_FRAC 20U  /* fraction bits of the variance, 2 * D_FRAC */

CANFDI_STATIC_ASSERT(MEANVAR_V_FRAC == (2U * MEANVAR_D_FRAC), var_is_d_squared);

int canfdi_meanvar_init(canfdi_meanvar_t *s, canfdi_q31_t alpha_q31)
{
  int out = -CANFDI_EINVAL;
  if ((s != NULL) && (alpha_q31 > 0)) {
    s->mean_q32 = 0;
    s->var_q20 = 0;
    s->alpha_q31 = alpha_q31;
    s->n_samples = 0U;
    s->diag.input_saturations = 0U;
    s->diag.resets = 0U;
    out = CANFDI_OK;
  }
  return out;
}

void canfdi_meanvar_reset(canfdi_meanvar_t *s)
{
  CANFDI_ASSERT(s != NULL);
  s->mean_q32 = 0;
  s->var_q20 = 0;
  s->n_samples = 0U;
  canfdi_count_inc(&s->diag.resets);
}

void canfdi_meanvar_step(canfdi_meanvar_t *s, int32_t x)
{
  CANFDI_ASSERT(s != NULL);
  CANFDI_ASSERT(s->alpha_q31 > 0);
  const int32_t xc = canfdi_clamp_s32(x, -CANFDI_MEANVAR_X_MAX, CANFDI_MEANVAR_X_MAX);
  if (xc != x) {
    canfdi_count_inc(&s->diag.input_saturations);
  }
  const int64_t x_q32 = (int64_t)xc * MEANVAR_ONE_Q32; /* |x_q32| <= 2^52 */

  if (s->n_samples == 0U) {
    /* Start from the first sample: no transient from an arbitrary zero. */
    s->mean_q32 = x_q32;
    s->var_q20 = 0;
  } else {
    /* |x_q32 - mean| <= 2^53 since both lie in [-2^52, 2^52]. */
    s->mean_q32 += canfdi_mul_s64_q31(x_q32 - s->mean_q32, s->alpha_q31);
    /* Deviation from the updated mean, Q32 -> Q10 rounded: |d| <= 2^31. */
    const int64_t d_q10 = canfdi_asr64_rnd(x_q32 - s->mean_q32, 32U - MEANVAR_D_FRAC);
    const int64_t d2_q20 = d_q10 * d_q10; /* <= 2^62 */
    /* Both terms in [0, 2^62]: the difference cannot overflow. */
    s->var_q20 += canfdi_mul_s64_q31(d2_q20 - s->var_q20, s->alpha_q31);
  }
  CANFDI_ASSERT((s->mean_q32 >= -((int64_t)CANFDI_MEANVAR_X_MAX * MEANVAR_ONE_Q32)) &&
                (s->mean_q32 <= ((int64_t)CANFDI_MEANVAR_X_MAX * MEANVAR_ONE_Q32)));
  CANFDI_ASSERT((s->var_q20 >= 0) && (s->var_q20 <= ((int64_t)1 << 62)));
  if (s->n_samples < UINT32_MAX) {
    s->n_samples++;
  }
}

uint32_t canfdi_meanvar_count(const canfdi_meanvar_t *s)
{
  CANFDI_ASSERT(s != NULL);
  return s->n_samples;
}

int32_t canfdi_meanvar_mean(const canfdi_meanvar_t *s)
{
  CANFDI_ASSERT(s != NULL);
  /* |mean| <= 2^20 so the rounded value always fits. */
  return canfdi_sat_s64_to_s32(canfdi_asr64_rnd(s->mean_q32, 32U));
}

int64_t canfdi_meanvar_mean_q32(const canfdi_meanvar_t *s)
{
  CANFDI_ASSERT(s != NULL);
  return s->mean_q32;
}

uint64_t canfdi_meanvar_var_q20(const canfdi_meanvar_t *s)
{
  CANFDI_ASSERT(s != NULL);
  return (uint64_t)s->var_q20; /* invariant: var_q20 >= 0 */
}

uint64_t canfdi_meanvar_var(const canfdi_meanvar_t *s)
{
  CANFDI_ASSERT(s != NULL);
  return (uint64_t)canfdi_asr64_rnd(s->var_q20, MEANVAR_V_FRAC);
}

uint32_t canfdi_meanvar_std_q10(const canfdi_meanvar_t *s)
{
  CANFDI_ASSERT(s != NULL);
  /* sqrt of a Q20 value is Q10. */
  return canfdi_isqrt_u64((uint64_t)s->var_q20);
}

canfdi_meanvar_diag_t canfdi_meanvar_diag(const canfdi_meanvar_t *s)
{
  CANFDI_ASSERT(s != NULL);
  return s->diag;
}
