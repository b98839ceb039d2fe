/* canfdi_sim_profile.c — see canfdi_sim_profile.h. */
#include "canfdi_sim_profile.h"

#include <math.h>

#include "core/canfdi_common.h"

#define LFSR_PERIOD 32767U

void canfdi_sim_profile_init(canfdi_sim_profile_t *p, double lo, double hi)
{
  p->n = 0U;
  p->lo = lo;
  p->hi = hi;
}

static int64_t s_to_us(double t_s)
{
  return (int64_t)llround(t_s * 1e6);
}

/* One shift of the Fibonacci LFSR x^15 + x^14 + 1 (taps 15 and 14). */
static uint16_t lfsr_next(uint16_t s)
{
  const uint16_t bit = (uint16_t)(((s >> 14U) ^ (s >> 13U)) & 1U);
  return (uint16_t)(((uint16_t)(s << 1U) | bit) & 0x7FFFU);
}

int canfdi_sim_profile_add(canfdi_sim_profile_t *p, uint8_t kind, double t0_s, double t1_s,
                           double value, double bit_or_freq, uint32_t seed)
{
  int rc = CANFDI_OK;
  canfdi_sim_profile_comp_t c;
  const bool windowed = (kind == CANFDI_SIM_PROF_RAMP) || (kind == CANFDI_SIM_PROF_PRBS) ||
                        (kind == CANFDI_SIM_PROF_SINE);

  c.kind = kind;
  c.t0_us = 0;
  c.t1_us = INT64_MAX;
  c.bit_us = 1;
  c.value = value;
  c.freq_hz = 0.0;
  c.seed_state = 1U;
  c.state = 1U;
  c.bit = 0;
  if (p->n >= CANFDI_SIM_PROFILE_MAX) {
    rc = -CANFDI_ERANGE;
  } else if ((kind > CANFDI_SIM_PROF_SINE) || !isfinite(value)) {
    rc = -CANFDI_EINVAL;
  } else if ((kind != CANFDI_SIM_PROF_CONST) && (!isfinite(t0_s) || (t0_s < 0.0) || (t0_s > 1e9))) {
    rc = -CANFDI_EINVAL;
  } else if (windowed && (!isfinite(t1_s) || (t1_s > 1e9) || (s_to_us(t1_s) <= s_to_us(t0_s)))) {
    rc = -CANFDI_EINVAL;
  } else if ((kind == CANFDI_SIM_PROF_PRBS) &&
             (!isfinite(bit_or_freq) || (bit_or_freq < 1e-3) || (bit_or_freq > 1e6))) {
    rc = -CANFDI_EINVAL;
  } else if ((kind == CANFDI_SIM_PROF_SINE) &&
             (!isfinite(bit_or_freq) || !(bit_or_freq > 0.0) || (bit_or_freq > 1e6))) {
    rc = -CANFDI_EINVAL;
  } else {
    if (kind != CANFDI_SIM_PROF_CONST) {
      c.t0_us = s_to_us(t0_s);
    }
    if (windowed) {
      c.t1_us = s_to_us(t1_s);
    }
    if (kind == CANFDI_SIM_PROF_PRBS) {
      c.bit_us = s_to_us(bit_or_freq);
      c.seed_state = (uint16_t)((seed % LFSR_PERIOD) + 1U);
      c.state = c.seed_state;
    } else if (kind == CANFDI_SIM_PROF_SINE) {
      c.freq_hz = bit_or_freq;
    } else {
      /* no extra arguments */
    }
    p->comp[p->n] = c;
    p->n++;
  }
  return rc;
}

static double comp_eval(canfdi_sim_profile_comp_t *c, int64_t t_us)
{
  double v = 0.0;
  switch (c->kind) {
  case CANFDI_SIM_PROF_CONST:
    v = c->value;
    break;
  case CANFDI_SIM_PROF_STEP:
    v = (t_us >= c->t0_us) ? c->value : 0.0;
    break;
  case CANFDI_SIM_PROF_RAMP:
    if (t_us >= c->t1_us) {
      v = c->value;
    } else if (t_us > c->t0_us) {
      v = c->value * ((double)(t_us - c->t0_us) / (double)(c->t1_us - c->t0_us));
    } else {
      v = 0.0;
    }
    break;
  case CANFDI_SIM_PROF_PRBS:
    if ((t_us >= c->t0_us) && (t_us < c->t1_us)) {
      const int64_t bit = (t_us - c->t0_us) / c->bit_us;
      if (bit < c->bit) {
        c->bit = 0;
        c->state = c->seed_state;
      }
      while (c->bit < bit) {
        c->state = lfsr_next(c->state);
        c->bit++;
      }
      v = ((c->state & 1U) != 0U) ? c->value : -c->value;
    }
    break;
  default: /* CANFDI_SIM_PROF_SINE */
    if ((t_us >= c->t0_us) && (t_us < c->t1_us)) {
      const double two_pi = 6.283185307179586;
      v = c->value * sin(two_pi * c->freq_hz * ((double)(t_us - c->t0_us) * 1e-6));
    }
    break;
  }
  return v;
}

double canfdi_sim_profile_eval(canfdi_sim_profile_t *p, int64_t t_us)
{
  return canfdi_sim_profile_eval_plus(p, t_us, 0.0);
}

double canfdi_sim_profile_eval_plus(canfdi_sim_profile_t *p, int64_t t_us, double extra)
{
  double sum = extra;
  size_t i;
  for (i = 0U; i < p->n; i++) {
    sum += comp_eval(&p->comp[i], t_us);
  }
  if (sum > p->hi) {
    sum = p->hi;
  } else if (sum < p->lo) {
    sum = p->lo;
  } else {
    /* within range */
  }
  return sum;
}
