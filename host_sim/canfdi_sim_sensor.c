/* canfdi_sim_sensor.c — see canfdi_sim_sensor.h. */
#include "canfdi_sim_sensor.h"

#include <math.h>

#include "core/canfdi_common.h"

int canfdi_sim_sensor_init(canfdi_sim_sensor_t *s, const canfdi_sim_sensor_cfg_t *cfg,
                           uint64_t seed, uint32_t stream)
{
  int rc = CANFDI_OK;
  if ((s == NULL) || (cfg == NULL) || !isfinite(cfg->min) || !isfinite(cfg->max) ||
      !isfinite(cfg->gain) || !isfinite(cfg->offset) || !isfinite(cfg->sigma) ||
      !(cfg->max > cfg->min) || (cfg->sigma < 0.0)) {
    rc = -CANFDI_EINVAL;
  } else {
    s->cfg = *cfg;
    canfdi_sim_rng_init(&s->rng, seed, stream);
    s->lsb = (cfg->max - cfg->min) / (double)CANFDI_SIM_ADC_CODES;
    s->last_analog = 0.0;
    s->last_code = 0U;
    s->diag.clips = 0U;
  }
  return rc;
}

double canfdi_sim_sensor_sample(canfdi_sim_sensor_t *s, double x, double fault_gain,
                                double fault_offset)
{
  const double top = (double)(CANFDI_SIM_ADC_CODES - 1U);
  double analog = (s->cfg.gain * (1.0 + fault_gain) * x) + s->cfg.offset + fault_offset;
  double noisy = analog;
  double pos;
  uint16_t code;

  /* The generator is drawn only when noise is configured; every channel has
   * its own stream, so this does not shift any other channel's noise. */
  if (s->cfg.sigma > 0.0) {
    noisy += s->cfg.sigma * canfdi_sim_rng_gauss(&s->rng);
  }
  pos = floor(((noisy - s->cfg.min) / s->lsb) + 0.5);
  if (!(pos >= 0.0)) { /* also catches NaN */
    pos = 0.0;
    s->diag.clips++;
  } else if (pos > top) {
    pos = top;
    s->diag.clips++;
  } else {
    /* in range */
  }
  code = (uint16_t)pos;
  s->last_analog = analog;
  s->last_code = code;
  return canfdi_sim_sensor_value_of_code(s, code);
}

double canfdi_sim_sensor_value_of_code(const canfdi_sim_sensor_t *s, uint16_t code)
{
  uint16_t c = code;
  if (c > (CANFDI_SIM_ADC_CODES - 1U)) {
    c = (uint16_t)(CANFDI_SIM_ADC_CODES - 1U);
  }
  return s->cfg.min + ((double)c * s->lsb);
}
