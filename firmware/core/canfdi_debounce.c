/*
 * canfdi_debounce.c — counter-based debouncing; the manual is the header.
 */
#include "core/canfdi_debounce.h"

#include "core/canfdi_count.h"

static bool jump_value_ok(bool enabled, int16_t value, const canfdi_debounce_cfg_t *cfg)
{
  return !enabled || ((value >= cfg->passed_threshold) && (value <= cfg->failed_threshold));
}

int32_t canfdi_debounce_cfg_check(const canfdi_debounce_cfg_t *cfg)
{
  int32_t out = -CANFDI_EINVAL;
  if ((cfg != NULL) && (cfg->failed_threshold > 0) && (cfg->passed_threshold < 0) &&
      (cfg->prefailed_step >= 1U) && (cfg->prefailed_step <= (uint16_t)INT16_MAX) &&
      (cfg->prepassed_step >= 1U) && (cfg->prepassed_step <= (uint16_t)INT16_MAX) &&
      jump_value_ok(cfg->jump_up, cfg->jump_up_value, cfg) &&
      jump_value_ok(cfg->jump_down, cfg->jump_down_value, cfg)) {
    out = CANFDI_OK;
  }
  return out;
}

/* The state after init/reset, diagnostics excluded. */
static void clear_state(canfdi_debounce_t *d)
{
  d->counter = 0;
  d->status = (uint8_t)CANFDI_DEB_UNDECIDED;
  d->test_failed = false;
  d->test_failed_this_cycle = false;
  d->test_not_completed_this_cycle = true;
}

int32_t canfdi_debounce_init(canfdi_debounce_t *d, const canfdi_debounce_cfg_t *cfg)
{
  int32_t out = -CANFDI_EINVAL;
  if (d != NULL) {
    d->cfg = NULL;
    d->diag.failed_qualifications = 0U;
    d->diag.passed_qualifications = 0U;
    d->diag.rejected_reports = 0U;
    clear_state(d);
    if (canfdi_debounce_cfg_check(cfg) == CANFDI_OK) {
      d->cfg = cfg;
      out = CANFDI_OK;
    }
  }
  return out;
}

/* Apply a qualification once the counter has been updated. */
static void qualify(canfdi_debounce_t *d)
{
  const canfdi_debounce_cfg_t *cfg = d->cfg;
  if (d->counter >= cfg->failed_threshold) {
    if (d->status != (uint8_t)CANFDI_DEB_FAILED) {
      canfdi_count_inc16(&d->diag.failed_qualifications);
    }
    d->status = (uint8_t)CANFDI_DEB_FAILED;
    d->test_failed = true;
    d->test_failed_this_cycle = true;
    d->test_not_completed_this_cycle = false;
  } else if (d->counter <= cfg->passed_threshold) {
    if (d->status != (uint8_t)CANFDI_DEB_PASSED) {
      canfdi_count_inc16(&d->diag.passed_qualifications);
    }
    d->status = (uint8_t)CANFDI_DEB_PASSED;
    d->test_failed = false;
    d->test_not_completed_this_cycle = false;
  } else {
    /* undecided this run: the last qualification stands */
  }
}

int32_t canfdi_debounce_step(canfdi_debounce_t *d, canfdi_deb_report_t report)
{
  int32_t out = -CANFDI_EINVAL;
  if ((d != NULL) && (d->cfg != NULL)) {
    const canfdi_debounce_cfg_t *cfg = d->cfg;
    /* int32_t: counter +/- a step of at most 32767 cannot overflow. */
    int32_t c = d->counter;
    bool known = true;
    switch (report) {
    case CANFDI_DEB_REPORT_PREFAILED:
      if (cfg->jump_up && (c < cfg->jump_up_value)) {
        c = cfg->jump_up_value;
      }
      c += (int32_t)cfg->prefailed_step;
      break;
    case CANFDI_DEB_REPORT_PREPASSED:
      if (cfg->jump_down && (c > cfg->jump_down_value)) {
        c = cfg->jump_down_value;
      }
      c -= (int32_t)cfg->prepassed_step;
      break;
    case CANFDI_DEB_REPORT_FAILED:
      c = cfg->failed_threshold;
      break;
    case CANFDI_DEB_REPORT_PASSED:
      c = cfg->passed_threshold;
      break;
    default:
      known = false;
      break;
    }
    if (known) {
      if (c > cfg->failed_threshold) {
        c = cfg->failed_threshold;
      } else if (c < cfg->passed_threshold) {
        c = cfg->passed_threshold;
      } else {
        /* inside the band */
      }
      d->counter = (int16_t)c;
      qualify(d);
      out = (int32_t)d->status;
    } else {
      canfdi_count_inc16(&d->diag.rejected_reports);
    }
    CANFDI_ASSERT((d->counter >= cfg->passed_threshold) && (d->counter <= cfg->failed_threshold));
  }
  return out;
}

void canfdi_debounce_start_cycle(canfdi_debounce_t *d)
{
  if ((d != NULL) && (d->cfg != NULL)) {
    d->counter = 0;
    d->test_failed_this_cycle = false;
    d->test_not_completed_this_cycle = true;
  }
}

void canfdi_debounce_reset(canfdi_debounce_t *d)
{
  if ((d != NULL) && (d->cfg != NULL)) {
    clear_state(d);
  }
}

canfdi_deb_status_t canfdi_debounce_status(const canfdi_debounce_t *d)
{
  canfdi_deb_status_t s = CANFDI_DEB_UNDECIDED;
  if (d != NULL) {
    if (d->status == (uint8_t)CANFDI_DEB_FAILED) {
      s = CANFDI_DEB_FAILED;
    } else if (d->status == (uint8_t)CANFDI_DEB_PASSED) {
      s = CANFDI_DEB_PASSED;
    } else {
      s = CANFDI_DEB_UNDECIDED;
    }
  }
  return s;
}

int16_t canfdi_debounce_counter(const canfdi_debounce_t *d)
{
  return (d != NULL) ? d->counter : (int16_t)0;
}

int8_t canfdi_debounce_fdc(const canfdi_debounce_t *d)
{
  int32_t fdc = 0;
  if ((d != NULL) && (d->cfg != NULL)) {
    const int32_t c = d->counter;
    if (c >= 0) {
      /* c <= failed_threshold, so the quotient is in 0..127. */
      fdc = (int32_t)(((uint32_t)c * 127U) / (uint32_t)d->cfg->failed_threshold);
    } else {
      /* |c| <= |passed_threshold| <= 32768, so the quotient is in 1..128
       * or 0; negate after dividing the magnitudes (truncation toward 0). */
      const uint32_t mag = (uint32_t)(-c);
      const uint32_t lim = (uint32_t)(-(int32_t)d->cfg->passed_threshold);
      fdc = -(int32_t)((mag * 128U) / lim);
    }
  }
  CANFDI_ASSERT((fdc >= INT8_MIN) && (fdc <= INT8_MAX));
  return (int8_t)fdc;
}
