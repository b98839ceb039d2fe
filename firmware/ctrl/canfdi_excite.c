/*
 * canfdi_excite.c — PRBS and sinusoidal excitation; see canfdi_excite.h.
 */
#include "ctrl/canfdi_excite.h"

#include "core/canfdi_count.h"
#include "core/canfdi_fixp.h"

#define EXC_LFSR_MASK 0x7FFFU

/* sin(pi/2 * i / 64) in Q15 (rounded; 32767 for 1.0), i = 0..64. */
static const int16_t exc_quarter_sin_q15[65] = {
    0,     804,   1608,  2410,  3212,  4011,  4808,  5602,  6393,  7179,  7962,  8739,  9512,
    10278, 11039, 11793, 12539, 13279, 14010, 14732, 15446, 16151, 16846, 17530, 18204, 18868,
    19519, 20159, 20787, 21403, 22005, 22594, 23170, 23731, 24279, 24811, 25329, 25832, 26319,
    26790, 27245, 27683, 28105, 28510, 28898, 29268, 29621, 29956, 30273, 30571, 30852, 31113,
    31356, 31580, 31785, 31971, 32137, 32285, 32412, 32521, 32609, 32678, 32728, 32757, 32767,
};

int32_t canfdi_excite_sin_q15(uint32_t phase)
{
  const uint32_t quadrant = phase >> 30;
  uint32_t pos = (phase >> 14) & 0xFFFFU; /* position in the quadrant, 16 bits */
  uint32_t idx;
  uint32_t frac;
  int32_t v;
  if ((quadrant & 1U) != 0U) {
    pos = 0x10000U - pos; /* mirror: sin(pi/2 + x) = sin(pi/2 - x); 1..0x10000 */
  }
  idx = pos >> 10;   /* 0..64 */
  frac = pos & 0x3FFU;
  v = (int32_t)exc_quarter_sin_q15[idx];
  if (frac != 0U) {
    /* idx <= 63 here; the table rises, so the difference is >= 0 and the
     * product < 2^10 * 2^10. Rounded half up. */
    const uint32_t diff =
        (uint32_t)((int32_t)exc_quarter_sin_q15[idx + 1U] - (int32_t)exc_quarter_sin_q15[idx]);
    v += (int32_t)(((diff * frac) + 512U) >> 10);
  }
  return (quadrant >= 2U) ? -v : v;
}

int32_t canfdi_excite_init(canfdi_excite_t *e, const canfdi_excite_cfg_t *cfg)
{
  int32_t out = CANFDI_OK;
  const uint32_t t_us = (uint32_t)CANFDI_CFG_STEP_US;
  uint32_t bit_steps = 1U;
  uint32_t inc = 0U;

  if ((e == NULL) || (cfg == NULL)) {
    out = -CANFDI_EINVAL;
  } else if ((cfg->prbs_amp_q16 < 0) || (cfg->sine_amp_q16 < 0) ||
             ((cfg->prbs_amp_q16 > 0) && (cfg->prbs_bit_us < ((t_us + 1U) / 2U))) ||
             ((cfg->sine_amp_q16 > 0) && (cfg->sine_period_us < (2U * t_us)))) {
    out = -CANFDI_EINVAL;
  } else {
    /* Bit period rounded to whole steps, at least one. */
    bit_steps = (cfg->prbs_bit_us + (t_us / 2U)) / t_us;
    bit_steps = (bit_steps == 0U) ? 1U : bit_steps;
    if (cfg->sine_amp_q16 > 0) {
      /* round(2^32 T / period); period >= 2T, so the result is <= 2^31. */
      inc = (uint32_t)((((uint64_t)t_us << 32) + ((uint64_t)cfg->sine_period_us / 2U)) /
                       (uint64_t)cfg->sine_period_us);
    }
  }
  if (out == CANFDI_OK) {
    e->cfg = *cfg;
    e->bit_steps = bit_steps;
    e->bit_count = 0U;
    e->phase_inc = inc;
    e->phase = 0U;
    e->lfsr = (uint16_t)(((cfg->prbs_seed & EXC_LFSR_MASK) == 0U) ? 1U
                                                                   : (cfg->prbs_seed & EXC_LFSR_MASK));
    e->want = false;
    e->prbs_on = false;
    e->sine_on = false;
    e->out_q16 = 0;
    e->diag.steps = 0U;
    e->diag.prbs_bits = 0U;
    e->diag.active_steps = 0U;
  }
  return out;
}

void canfdi_excite_enable(canfdi_excite_t *e, bool on)
{
  e->want = on;
}

/* One LFSR shift: x^15 + x^14 + 1, new bit 0 = bit 14 XOR bit 13. */
static uint16_t exc_lfsr_next(uint16_t s)
{
  const uint32_t fb = (((uint32_t)s >> 14) ^ ((uint32_t)s >> 13)) & 1U;
  return (uint16_t)((((uint32_t)s << 1) | fb) & EXC_LFSR_MASK);
}

int32_t canfdi_excite_step_q16(canfdi_excite_t *e)
{
  int32_t y = 0;
  int32_t prbs = 0;

  if (e->want && !e->sine_on) {
    /* Switching on while the sine rests: its period starts now (an upward
     * zero crossing), so a test burst is not delayed by up to a period
     * waiting for the free-running phase. */
    e->phase = 0U;
  }
  if (e->bit_count == 0U) {
    /* A bit edge: the gate may change; the LFSR shifts and its new bit 0
     * is this bit's value. */
    e->prbs_on = e->want && (e->cfg.prbs_amp_q16 > 0);
    e->lfsr = exc_lfsr_next(e->lfsr);
    canfdi_count_inc(&e->diag.prbs_bits);
  }
  e->bit_count++;
  if (e->bit_count >= e->bit_steps) {
    e->bit_count = 0U;
  }
  if (e->prbs_on) {
    prbs = ((e->lfsr & 1U) != 0U) ? e->cfg.prbs_amp_q16 : -e->cfg.prbs_amp_q16;
  }

  if (e->phase < e->phase_inc) {
    /* First sample of a period (upward zero crossing). */
    e->sine_on = e->want && (e->cfg.sine_amp_q16 > 0);
  }
  if (e->sine_on) {
    y = canfdi_mul_s32_qn(e->cfg.sine_amp_q16, canfdi_excite_sin_q15(e->phase), 15U);
  }
  e->phase += e->phase_inc; /* wraps modulo 2^32 by design: one period */

  y = canfdi_add_s32_sat(y, prbs);
  if (e->prbs_on || e->sine_on) {
    canfdi_count_inc(&e->diag.active_steps);
  }
  e->out_q16 = y;
  canfdi_count_inc(&e->diag.steps);
  return y;
}

bool canfdi_excite_active(const canfdi_excite_t *e)
{
  return e->prbs_on || e->sine_on;
}

const canfdi_excite_diag_t *canfdi_excite_diag(const canfdi_excite_t *e)
{
  return &e->diag;
}
