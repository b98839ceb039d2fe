/*
 * canfdi_limit.c — limit checking with hysteresis; the manual is the header.
 */
#include "detect/canfdi_limit.h"

#include "core/canfdi_count.h"

int32_t canfdi_limit_cfg_check(const canfdi_limit_cfg_t *cfg)
{
  int32_t out = -CANFDI_EINVAL;
  if ((cfg != NULL) && (cfg->max_enabled || cfg->min_enabled) &&
      (canfdi_debounce_cfg_check(&cfg->deb) == CANFDI_OK)) {
    bool ok = true;
    if (cfg->max_enabled && (cfg->max_clear > cfg->max_set)) {
      ok = false;
    }
    if (cfg->min_enabled && (cfg->min_clear < cfg->min_set)) {
      ok = false;
    }
    /* Both sides: the clear levels must leave an in-band region, so that
     * one x can never be ABOVE and BELOW at once. */
    if (cfg->max_enabled && cfg->min_enabled && (cfg->min_clear >= cfg->max_clear)) {
      ok = false;
    }
    if (ok) {
      out = CANFDI_OK;
    }
  }
  return out;
}

int32_t canfdi_limit_init(canfdi_limit_t *l, const canfdi_limit_cfg_t *cfg)
{
  int32_t out = -CANFDI_EINVAL;
  if (l != NULL) {
    l->cfg = NULL;
    l->symptom = (uint8_t)CANFDI_LIMIT_IN_BAND;
    l->failed_side = (uint8_t)CANFDI_LIMIT_IN_BAND;
    l->diag.above_events = 0U;
    l->diag.below_events = 0U;
    l->diag.steps_violated = 0U;
    if ((canfdi_limit_cfg_check(cfg) == CANFDI_OK) &&
        (canfdi_debounce_init(&l->deb, &cfg->deb) == CANFDI_OK)) {
      l->cfg = cfg;
      out = CANFDI_OK;
    }
  }
  return out;
}

int32_t canfdi_limit_step(canfdi_limit_t *l, int32_t x)
{
  int32_t out = -CANFDI_EINVAL;
  if ((l != NULL) && (l->cfg != NULL)) {
    const canfdi_limit_cfg_t *cfg = l->cfg;
    bool above = (l->symptom == (uint8_t)CANFDI_LIMIT_ABOVE_MAX);
    bool below = (l->symptom == (uint8_t)CANFDI_LIMIT_BELOW_MIN);
    canfdi_limit_symptom_t s = CANFDI_LIMIT_IN_BAND;
    if (cfg->max_enabled) {
      above = above ? (x >= cfg->max_clear) : (x > cfg->max_set);
    }
    if (cfg->min_enabled) {
      below = below ? (x <= cfg->min_clear) : (x < cfg->min_set);
    }
    /* min_clear < max_clear: ABOVE needs x >= max_clear > min_clear, which
     * clears or forbids BELOW, and vice versa. */
    CANFDI_ASSERT(!(above && below));
    if (above) {
      s = CANFDI_LIMIT_ABOVE_MAX;
      if (l->symptom != (uint8_t)CANFDI_LIMIT_ABOVE_MAX) {
        canfdi_count_inc(&l->diag.above_events);
      }
    } else if (below) {
      s = CANFDI_LIMIT_BELOW_MIN;
      if (l->symptom != (uint8_t)CANFDI_LIMIT_BELOW_MIN) {
        canfdi_count_inc(&l->diag.below_events);
      }
    } else {
      s = CANFDI_LIMIT_IN_BAND;
    }
    l->symptom = (uint8_t)s;
    if (s != CANFDI_LIMIT_IN_BAND) {
      canfdi_count_inc(&l->diag.steps_violated);
    }
    out = canfdi_debounce_report(&l->deb, (s == CANFDI_LIMIT_IN_BAND) ? CANFDI_DEB_REPORT_PREPASSED
                                                                      : CANFDI_DEB_REPORT_PREFAILED);
    CANFDI_ASSERT(out >= 0);
    /* A PREFAILED report that leaves the counter at the failed threshold is
     * the one that qualifies (or keeps) FAILED: remember its side. */
    if ((s != CANFDI_LIMIT_IN_BAND) && (l->deb.counter == cfg->deb.failed_threshold)) {
      l->failed_side = (uint8_t)s;
    }
  }
  return out;
}

void canfdi_limit_reset(canfdi_limit_t *l)
{
  if ((l != NULL) && (l->cfg != NULL)) {
    l->symptom = (uint8_t)CANFDI_LIMIT_IN_BAND;
    l->failed_side = (uint8_t)CANFDI_LIMIT_IN_BAND;
    canfdi_debounce_reset(&l->deb);
  }
}

static canfdi_limit_symptom_t to_symptom(uint8_t v)
{
  canfdi_limit_symptom_t s = CANFDI_LIMIT_IN_BAND;
  if (v == (uint8_t)CANFDI_LIMIT_ABOVE_MAX) {
    s = CANFDI_LIMIT_ABOVE_MAX;
  } else if (v == (uint8_t)CANFDI_LIMIT_BELOW_MIN) {
    s = CANFDI_LIMIT_BELOW_MIN;
  } else {
    s = CANFDI_LIMIT_IN_BAND;
  }
  return s;
}

canfdi_limit_symptom_t canfdi_limit_symptom(const canfdi_limit_t *l)
{
  return (l != NULL) ? to_symptom(l->symptom) : CANFDI_LIMIT_IN_BAND;
}

canfdi_deb_status_t canfdi_limit_status(const canfdi_limit_t *l)
{
  return (l != NULL) ? canfdi_debounce_status(&l->deb) : CANFDI_DEB_UNDECIDED;
}

canfdi_limit_symptom_t canfdi_limit_failed_side(const canfdi_limit_t *l)
{
  return (l != NULL) ? to_symptom(l->failed_side) : CANFDI_LIMIT_IN_BAND;
}
