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
    cfg->gap_steps = 100U;
    cfg->backoff_steps = 60000U;
    cfg->backoff_max_steps = 480000U;
    cfg->keyon = true;
  }
}

int32_t canfdi_testsched_init(canfdi_testsched_t *s, const canfdi_testsched_cfg_t *cfg)
{
  int32_t rc = -CANFDI_EINVAL;
  if ((s != NULL) && (cfg != NULL) && (cfg->lack_steps > 0U) && (cfg->burst_steps > 0U) &&
      (cfg->need_max_steps > 0U) && (cfg->backoff_steps > 0U) && (cfg->backoff_max_steps >= cfg->backoff_steps)) {
    *s = (canfdi_testsched_t){0};
    s->cfg = *cfg;
    s->phase = CANFDI_TESTSCHED_IDLE;
    s->reason = CANFDI_TESTSCHED_REASON_NONE;
    s->backoff_len = cfg->backoff_steps;
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

/* The need as the scheduler sees it (header, contract on a need): a need
 * falling forgets its share and its back-off; a back-off running out
 * owes the need need_max_steps again. Returns whether the need is owed
 * test signal this step. */
static bool owed(canfdi_testsched_t *s, bool need)
{
  if (!need) {
    s->need_n = 0U;
    s->backoff = 0U;
    s->backoff_len = s->cfg.backoff_steps;
  } else if (s->backoff > 0U) {
    s->backoff--;
    if (s->backoff == 0U) {
      s->need_n = 0U;
    }
  } else {
    /* owed, or unresolved just now (on() starts the back-off) */
  }
  return need && (s->backoff == 0U) && (s->need_n < s->cfg.need_max_steps);
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

/* ON, from its second step: a NEED burst lasts while the need is owed
 * test signal, a KEYON, LEARN or LACK burst burst_steps and longer while a
 * need is owed. */
static void on(canfdi_testsched_t *s, bool due)
{
  const uint32_t min_n = (s->reason == CANFDI_TESTSCHED_REASON_NEED) ? 0U : s->cfg.burst_steps;
  if ((s->n >= min_n) && !due) {
    enter(s, CANFDI_TESTSCHED_REST);
    s->lack = 0U;
  }
}

/* A step with the signal on: count it, and the need's share; a need that
 * has had need_max_steps is unresolved and starts its back-off. */
static void count_on(canfdi_testsched_t *s, bool due)
{
  canfdi_count_inc(&s->n);
  canfdi_count_inc(&s->diag.on_steps);
  if (due) {
    s->need_n++;
    if (s->need_n >= s->cfg.need_max_steps) {
      canfdi_count_inc(&s->diag.unresolved);
      s->backoff = s->backoff_len;
      s->backoff_len = (s->backoff_len <= (s->cfg.backoff_max_steps / 2U)) ? (s->backoff_len * 2U)
                                                                           : s->cfg.backoff_max_steps;
    }
  }
}

bool canfdi_testsched_step(canfdi_testsched_t *s, bool enabled, bool excited, bool need, bool unlearnt)
{
  bool out = false;
  if ((s != NULL) && s->initialised) {
    const bool due = owed(s, need);
    if (s->phase == CANFDI_TESTSCHED_REST) {
      if (s->n < s->cfg.rest_steps) {
        s->n++;
      }
      if (enabled && due && (s->n >= s->cfg.gap_steps)) {
        start(s, CANFDI_TESTSCHED_REASON_NEED);
      } else if (s->n >= s->cfg.rest_steps) {
        enter(s, CANFDI_TESTSCHED_IDLE);
        s->lack = 0U;
      } else {
        /* rests */
      }
    } else if (!enabled) {
      if (s->phase == CANFDI_TESTSCHED_ON) {
        canfdi_count_inc(&s->diag.aborted);
        enter(s, CANFDI_TESTSCHED_REST);
      }
    } else if (s->phase == CANFDI_TESTSCHED_IDLE) {
      idle(s, excited, due, unlearnt);
    } else {
      on(s, due);
    }
    out = (s->phase == CANFDI_TESTSCHED_ON);
    if (out) {
      count_on(s, due);
    }
  }
  return out;
}
