/*
 * canfdi_count.h — the one saturating counter of canfdi.
 *
 * Every diagnostics struct of the firmware (the `diag` member of each
 * instance) holds monotone counters: they only ever grow, and a counter
 * that reaches its type's maximum stays there (o1heap's "never decreased").
 * A wrapping counter would read as "nothing happened" after 2^32 events (49.7
 * days of 1 ms steps); a saturated one reads as "at least this many".
 *
 * Contract: a diagnostics counter is never read to take a decision (a
 * saturated or wrapped counter would change behaviour after weeks of
 * operation); state that steers behaviour is kept in state fields of its
 * own with a stated range. State counters whose definition saturates (the
 * DTC memory's occurrence and operation-cycle counters, ISO 14229-1) use
 * the same helpers.
 *
 * Scaling and overflow: unsigned integers, no fixed-point format; every
 * function saturates at the type's maximum and never wraps. Cost: one
 * compare and one add each (inline). Cannot fail by contract (NULL is a
 * caller error caught by CANFDI_ASSERT on hosts).
 */
#ifndef CANFDI_COUNT_H
#define CANFDI_COUNT_H

#include "core/canfdi_common.h"

/* *c += 1, saturating at UINT32_MAX. */
static CANFDI_ALWAYS_INLINE void canfdi_count_inc(uint32_t *c)
{
  CANFDI_ASSERT(c != NULL);
  if (*c < UINT32_MAX) {
    *c += 1U;
  }
}

/* *c += n, saturating at UINT32_MAX. */
static inline void canfdi_count_add(uint32_t *c, uint32_t n)
{
  CANFDI_ASSERT(c != NULL);
  *c = (*c > (UINT32_MAX - n)) ? UINT32_MAX : (*c + n);
}

/* a + b, saturating at UINT32_MAX (for sums of counters). */
static inline uint32_t canfdi_count_sum(uint32_t a, uint32_t b)
{
  return (a > (UINT32_MAX - b)) ? UINT32_MAX : (a + b);
}

/* *c += 1, saturating at UINT16_MAX. */
static inline void canfdi_count_inc16(uint16_t *c)
{
  CANFDI_ASSERT(c != NULL);
  if (*c < UINT16_MAX) {
    *c = (uint16_t)(*c + 1U);
  }
}

/* *c += 1, saturating at UINT8_MAX. */
static inline void canfdi_count_inc8(uint8_t *c)
{
  CANFDI_ASSERT(c != NULL);
  if (*c < UINT8_MAX) {
    *c = (uint8_t)(*c + 1U);
  }
}

#endif /* CANFDI_COUNT_H */
