/*
 * canfdi_testsched.c — scheduler of the intrusive test signal; the manual
 * is the header.
 */
#include "diag/canfdi_testsched.h"

#include "core/canfdi_count.h"

void canfdi_testsched_default_cfg(canfdi_testsched_cfg_t *cfg)
{
  if (cfg != NULL) {
    cfg->lack_steps = 60000U;
    cfg->burst_steps = 2500U;
    cfg->need_max_steps = 3000U;
    cfg->rest_steps = 10000U;
    cfg->keyon = true;
  }
}

int32_t canfdi_testsched_init(canfdi_testsched_t *s, const canfdi_testsched_cfg_t *cfg)
{
  int32_t rc = -CANFDI_EINVAL;
  if ((s != NULL) && (cfg != NULL) && (cfg->lack_steps > 0U) && (cfg->burst_steps > 0U) &&
      (cfg->need_max_steps > 0U)) {
    *s = (canfdi_testsched_t){0};
    s->cfg = *cfg;
    s->phase = CANFDI_TESTSCHED_IDLE;
    s->reason = CANFDI_TESTSCHED_REASON_NONE;
    s->keyon_pending = cfg->keyon;
    s->initialised = true;
    rc = CANFDI_OK;
  }
  return rc;
}

static void enter(canfdi_testsched_t *s, uint8_t phase)
{
  s->phase = phase;
  s->n = 0U;
}

static void start(canfdi_testsched_t *s, uint8_t reason)
{
  enter(s, CANFDI_TESTSCHED_ON);
  s->reason = reason;
  canfdi_count_inc(&s->diag.bursts[reason]);
  if (reason == CANFDI_TESTSCHED_REASON_KEYON) {
    s->keyon_pending = false;
  }
}

/* IDLE: count the lack of excitation, start a burst when one is due. */
static void idle(canfdi_testsched_t *s, bool excited, bool need, bool unlearnt)
{
  if (excited) {
    s->lack = 0U;
  } else if (s->lack < s->cfg.lack_steps) {
    s->lack++;
  } else {
    /* held at the limit */
  }
  if (s->keyon_pending) {
    start(s, CANFDI_TESTSCHED_REASON_KEYON);
  } else if (unlearnt) {
    start(s, CANFDI_TESTSCHED_REASON_LEARN);
  } else if (need) {
    start(s, CANFDI_TESTSCHED_REASON_NEED);
  } else if (s->lack >= s->cfg.lack_steps) {
    start(s, CANFDI_TESTSCHED_REASON_LACK);
  } else {
    /* nothing due */
  }
}

/* ON: a NEED burst lasts while needed, a KEYON or LACK burst burst_steps
 * and longer while a need persists; never longer than need_max_steps
 * (or burst_steps if that is longer). */
static void on(canfdi_testsched_t *s, bool need)
{
  const uint32_t min_n = (s->reason == CANFDI_TESTSCHED_REASON_NEED) ? 0U : s->cfg.burst_steps;
  const uint32_t max_n = (s->cfg.need_max_steps > min_n) ? s->cfg.need_max_steps : min_n;
  s->n++;
  if ((s->n >= min_n) && !need) {
    enter(s, CANFDI_TESTSCHED_REST);
    s->lack = 0U;
  } else if (s->n >= max_n) {
    /* still needed after the longest burst: not isolable with this signal */
    s->exhausted = need;
    enter(s, CANFDI_TESTSCHED_REST);
    s->lack = 0U;
  } else {
    /* continues */
  }
}

bool canfdi_testsched_step(canfdi_testsched_t *s, bool enabled, bool excited, bool need, bool unlearnt)
{
  bool out = false;
  if ((s != NULL) && s->initialised) {
    if (!need) {
      s->exhausted = false;
    }
    if ((s->phase == CANFDI_TESTSCHED_REST) && enabled && need && !s->exhausted) {
      start(s, CANFDI_TESTSCHED_REASON_NEED);
    } else if (s->phase == CANFDI_TESTSCHED_REST) {
      s->n++;
      if (s->n >= s->cfg.rest_steps) {
        enter(s, CANFDI_TESTSCHED_IDLE);
        s->lack = 0U;
      }
    } else if (!enabled) {
      if (s->phase == CANFDI_TESTSCHED_ON) {
        canfdi_count_inc(&s->diag.aborted);
        enter(s, CANFDI_TESTSCHED_REST);
      }
    } else if (s->phase == CANFDI_TESTSCHED_IDLE) {
      idle(s, excited, need, unlearnt);
    } else {
      on(s, need);
    }
    out = (s->phase == CANFDI_TESTSCHED_ON);
    if (out) {
      canfdi_count_inc(&s->diag.on_steps);
    }
  }
  return out;
}
