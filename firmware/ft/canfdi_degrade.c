/*
 * canfdi_degrade.c — degradation ratchet; the rules are in the header.
 */
#include "ft/canfdi_degrade.h"

CANFDI_STATIC_ASSERT(CANFDI_DEGRADE_LOG_LEN >= 1U && CANFDI_DEGRADE_LOG_LEN <= 255U,
                     degrade_log_len_fits_uint8);
CANFDI_STATIC_ASSERT(CANFDI_DEG_NORMAL < CANFDI_DEG_DEGRADED &&
                         CANFDI_DEG_DEGRADED < CANFDI_DEG_FAIL_SAFE &&
                         CANFDI_DEG_FAIL_SAFE < CANFDI_DEG_FAIL_SILENT,
                     degrade_states_ordered_by_safety);

static void transition(canfdi_degrade_t *d, uint8_t to, uint8_t reason, uint64_t now_ms)
{
  canfdi_degrade_transition_t *e = &d->log[d->log_head];
  e->t_ms = now_ms;
  e->from = d->state;
  e->to = to;
  e->reason = reason;
  e->pad_ = 0U;
  d->log_head = (uint8_t)((d->log_head + 1U) % CANFDI_DEGRADE_LOG_LEN);
  if (d->log_count < CANFDI_DEGRADE_LOG_LEN) {
    d->log_count = (uint8_t)(d->log_count + 1U);
  } else {
    canfdi_count_inc(&d->diag.log_overwrites);
  }
  d->state = to;
  d->reason = reason;
  d->since_ms = now_ms;
  canfdi_count_inc(&d->diag.transitions);
}

int32_t canfdi_degrade_init(canfdi_degrade_t *d)
{
  int32_t rc = -CANFDI_EINVAL;
  if (d != NULL) {
    uint32_t i;
    d->state = CANFDI_DEG_NORMAL;
    d->reason = CANFDI_FAULT_NONE;
    d->log_head = 0U;
    d->log_count = 0U;
    d->since_ms = 0U;
    for (i = 0U; i < CANFDI_DEGRADE_LOG_LEN; i++) {
      d->log[i].t_ms = 0U;
      d->log[i].from = 0U;
      d->log[i].to = 0U;
      d->log[i].reason = 0U;
      d->log[i].pad_ = 0U;
    }
    d->diag.transitions = 0U;
    d->diag.escalations = 0U;
    d->diag.ignored_relax = 0U;
    d->diag.clears = 0U;
    d->diag.clears_refused = 0U;
    d->diag.rejected = 0U;
    d->diag.log_overwrites = 0U;
    rc = CANFDI_OK;
  }
  return rc;
}

int32_t canfdi_degrade_request(canfdi_degrade_t *d, uint8_t state, uint8_t reason,
                               uint64_t now_ms)
{
  int32_t rc = -CANFDI_EINVAL;
  if (d != NULL) {
    CANFDI_ASSERT(d->state <= CANFDI_DEGRADE_STATE_MAX);
    if (state > CANFDI_DEGRADE_STATE_MAX) {
      canfdi_count_inc(&d->diag.rejected);
    } else {
      if (state > d->state) {
        transition(d, state, reason, now_ms);
        canfdi_count_inc(&d->diag.escalations);
      } else if (state < d->state) {
        canfdi_count_inc(&d->diag.ignored_relax);
      } else {
        /* Re-assertion of the present state: the usual case every step. */
      }
      rc = (int32_t)d->state;
    }
  }
  return rc;
}

int32_t canfdi_degrade_clear(canfdi_degrade_t *d, uint8_t cause, bool fault_present,
                             uint64_t now_ms)
{
  int32_t rc = -CANFDI_EINVAL;
  if (d != NULL) {
    if ((cause != CANFDI_DEGRADE_CLEAR_TESTER) && (cause != CANFDI_DEGRADE_CLEAR_NEW_CYCLE)) {
      canfdi_count_inc(&d->diag.rejected);
    } else if (fault_present) {
      canfdi_count_inc(&d->diag.clears_refused);
      rc = CANFDI_DEGRADE_CLEAR_REFUSED;
    } else {
      if (d->state != CANFDI_DEG_NORMAL) {
        transition(d, CANFDI_DEG_NORMAL, cause, now_ms);
      }
      canfdi_count_inc(&d->diag.clears);
      rc = CANFDI_OK;
    }
  }
  return rc;
}

uint8_t canfdi_degrade_state(const canfdi_degrade_t *d)
{
  return (d != NULL) ? d->state : (uint8_t)CANFDI_DEG_FAIL_SAFE;
}

uint8_t canfdi_degrade_reason(const canfdi_degrade_t *d)
{
  return (d != NULL) ? d->reason : (uint8_t)CANFDI_FAULT_NONE;
}

uint64_t canfdi_degrade_since_ms(const canfdi_degrade_t *d)
{
  return (d != NULL) ? d->since_ms : 0U;
}

int32_t canfdi_degrade_log_get(const canfdi_degrade_t *d, uint32_t age,
                               canfdi_degrade_transition_t *out)
{
  int32_t rc = -CANFDI_EINVAL;
  if ((d != NULL) && (out != NULL)) {
    if (age >= (uint32_t)d->log_count) {
      rc = -CANFDI_ENODATA;
    } else {
      /* head points past the latest entry; step back age + 1 (mod LEN). */
      const uint32_t idx =
          ((uint32_t)d->log_head + CANFDI_DEGRADE_LOG_LEN - 1U - age) % CANFDI_DEGRADE_LOG_LEN;
      *out = d->log[idx];
      rc = CANFDI_OK;
    }
  }
  return rc;
}

canfdi_degrade_diag_t canfdi_degrade_diag(const canfdi_degrade_t *d)
{
  canfdi_degrade_diag_t z = {0U, 0U, 0U, 0U, 0U, 0U, 0U};
  return (d != NULL) ? d->diag : z;
}
