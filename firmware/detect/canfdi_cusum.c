/*
 * canfdi_cusum.c — two-sided tabular CUSUM. The header is the manual
 * (formats, the overflow argument, restart options, cost).
 */
#include "detect/canfdi_cusum.h"

#include "core/canfdi_count.h"
#include "core/canfdi_qconst.h"

/* Bound on |S| from the header's overflow argument: H <= 2^46 before a step,
 * one update < 2^49. Checked as an invariant on every step. */
#define CUSUM_S_BOUND ((int64_t)1 << 50)

/* sigma-unit Q16 parameter times sigma (LSB, Q10) -> LSB, Q16, rounded half
 * up. p <= 2^24 * (2^32 - 1) < 2^56: exact in uint64_t. */
static int64_t scale_to_lsb_q16(uint32_t p_q16, uint32_t sigma_q10)
{
  const uint64_t prod = (uint64_t)p_q16 * (uint64_t)sigma_q10; /* Q26 */
  return (int64_t)((prod + (1U << 9)) >> 10);
}

static void rearm(canfdi_cusum_t *s)
{
  s->s_hi_q16 = s->s0_lsb_q16;
  s->s_lo_q16 = s->s0_lsb_q16;
  s->n_hi = 0U;
  s->n_lo = 0U;
  s->latched = false;
}

int canfdi_cusum_init(canfdi_cusum_t *s, const canfdi_cusum_cfg_t *cfg)
{
  int out = -CANFDI_EINVAL;
  if ((s != NULL) && (cfg != NULL) && (cfg->sigma_q10 > 0U) && (cfg->h_q16 > 0U) &&
      (cfg->k_q16 <= CANFDI_CUSUM_KH_MAX_Q16) && (cfg->h_q16 <= CANFDI_CUSUM_KH_MAX_Q16) &&
      (cfg->head_start_q16 < cfg->h_q16) &&
      ((cfg->restart == CANFDI_CUSUM_RESTART_AUTO) ||
       (cfg->restart == CANFDI_CUSUM_RESTART_LATCH))) {
    s->k_lsb_q16 = scale_to_lsb_q16(cfg->k_q16, cfg->sigma_q10);
    s->h_lsb_q16 = scale_to_lsb_q16(cfg->h_q16, cfg->sigma_q10);
    s->s0_lsb_q16 = scale_to_lsb_q16(cfg->head_start_q16, cfg->sigma_q10);
    s->mu0 = cfg->mu0;
    s->restart = (uint8_t)cfg->restart;
    s->step = 0U;
    s->alarm.side = CANFDI_CUSUM_NONE;
    s->alarm.alarm_step = 0U;
    s->alarm.n_nonzero = 0U;
    s->alarm.change_step = 0U;
    s->alarm.shift_q16 = 0;
    s->alarm.sum_q16 = 0;
    s->diag.alarms_hi = 0U;
    s->diag.alarms_lo = 0U;
    s->diag.restarts = 0U;
    s->diag.latched_samples = 0U;
    rearm(s);
    out = CANFDI_OK;
  }
  return out;
}

/* One side: S = max(0, S + inc); N counts the consecutive non-zero steps
 * (state, saturating at UINT32_MAX: see the header). */
static void accumulate(int64_t *sum, uint32_t *n, int64_t inc)
{
  const int64_t v = *sum + inc; /* |v| < 2^50, see header */
  if (v > 0) {
    *sum = v;
    if (*n < UINT32_MAX) {
      *n += 1U;
    }
  } else {
    *sum = 0;
    *n = 0U;
  }
}

static void record_alarm(canfdi_cusum_t *s, uint32_t side, int64_t sum, uint32_t n)
{
  /* n >= 1 because sum > H > 0 was reached on a non-zero run. */
  CANFDI_ASSERT(n > 0U);
  CANFDI_ASSERT(sum > 0);
  /* Montgomery's estimate of the new mean: mu0 +- (K + S/N), S/N rounded. */
  const uint64_t mean_excess = ((uint64_t)sum + (uint64_t)(n / 2U)) / (uint64_t)n;
  const int64_t shift = s->k_lsb_q16 + (int64_t)mean_excess; /* <= 2^51 */
  s->alarm.side = side;
  s->alarm.alarm_step = s->step;
  s->alarm.n_nonzero = n;
  s->alarm.change_step = s->step - n; /* modular by design */
  s->alarm.shift_q16 = (side == CANFDI_CUSUM_HI) ? shift : -shift;
  s->alarm.sum_q16 = sum;
  if (side == CANFDI_CUSUM_HI) {
    canfdi_count_inc(&s->diag.alarms_hi);
  } else {
    canfdi_count_inc(&s->diag.alarms_lo);
  }
}

uint32_t canfdi_cusum_step(canfdi_cusum_t *s, int32_t x)
{
  CANFDI_ASSERT(s != NULL);
  uint32_t side = CANFDI_CUSUM_NONE;
  s->step++; /* wraps by design */
  if (s->latched) {
    canfdi_count_inc(&s->diag.latched_samples);
  } else {
    /* e*2^16 by multiplication: exact (|e| < 2^32) and defined for e < 0. */
    const int64_t e_q16 = ((int64_t)x - (int64_t)s->mu0) * (int64_t)CANFDI_Q16_ONE;
    accumulate(&s->s_hi_q16, &s->n_hi, e_q16 - s->k_lsb_q16);
    accumulate(&s->s_lo_q16, &s->n_lo, -e_q16 - s->k_lsb_q16);
    CANFDI_ASSERT((s->s_hi_q16 < CUSUM_S_BOUND) && (s->s_lo_q16 < CUSUM_S_BOUND));

    if (s->s_hi_q16 > s->h_lsb_q16) {
      side |= CANFDI_CUSUM_HI;
    }
    if (s->s_lo_q16 > s->h_lsb_q16) {
      side |= CANFDI_CUSUM_LO;
    }
    /* The two increments add up to -2K <= 0 and both sums were <= H: at most
     * one of them can cross H on one sample. */
    CANFDI_ASSERT(side != (CANFDI_CUSUM_HI | CANFDI_CUSUM_LO));
    if (side == CANFDI_CUSUM_HI) {
      record_alarm(s, side, s->s_hi_q16, s->n_hi);
    } else if (side == CANFDI_CUSUM_LO) {
      record_alarm(s, side, s->s_lo_q16, s->n_lo);
    } else {
      /* no alarm */
    }
    if (side != CANFDI_CUSUM_NONE) {
      if (s->restart == (uint8_t)CANFDI_CUSUM_RESTART_AUTO) {
        rearm(s);
        canfdi_count_inc(&s->diag.restarts);
      } else {
        s->latched = true;
      }
    }
  }
  return side;
}

void canfdi_cusum_restart(canfdi_cusum_t *s)
{
  CANFDI_ASSERT(s != NULL);
  rearm(s);
  canfdi_count_inc(&s->diag.restarts);
}

bool canfdi_cusum_latched(const canfdi_cusum_t *s)
{
  CANFDI_ASSERT(s != NULL);
  return s->latched;
}

int64_t canfdi_cusum_sum_hi_q16(const canfdi_cusum_t *s)
{
  CANFDI_ASSERT(s != NULL);
  return s->s_hi_q16;
}

int64_t canfdi_cusum_sum_lo_q16(const canfdi_cusum_t *s)
{
  CANFDI_ASSERT(s != NULL);
  return s->s_lo_q16;
}

int64_t canfdi_cusum_threshold_q16(const canfdi_cusum_t *s)
{
  CANFDI_ASSERT(s != NULL);
  return s->h_lsb_q16;
}

uint32_t canfdi_cusum_step_index(const canfdi_cusum_t *s)
{
  CANFDI_ASSERT(s != NULL);
  return s->step;
}

canfdi_cusum_alarm_t canfdi_cusum_last_alarm(const canfdi_cusum_t *s)
{
  CANFDI_ASSERT(s != NULL);
  return s->alarm;
}

canfdi_cusum_diag_t canfdi_cusum_diag(const canfdi_cusum_t *s)
{
  CANFDI_ASSERT(s != NULL);
  return s->diag;
}
