/*
 * canfdi_uptime.c — millisecond uptime from a wrapping microsecond clock;
 * the manual is the header.
 */
#include "core/canfdi_uptime.h"

#define US_PER_MS 1000U
#define SUBTRACT_MAX_MS 4U /* up to this many whole ms by subtraction */

void canfdi_uptime_init(canfdi_uptime_t *t, uint32_t now_us)
{
  CANFDI_ASSERT(t != NULL);
  t->ms = 0U;
  t->last_us = now_us;
  t->frac_us = 0U;
}

uint64_t canfdi_uptime_advance(canfdi_uptime_t *t, uint32_t now_us)
{
  uint32_t acc;
  uint32_t whole = 0U;
  CANFDI_ASSERT(t != NULL);
  /* elapsed modulo 2^32 plus the remainder: frac_us < 1000, so the sum
   * wraps only when nearly 2^32 us elapsed; then compute in two parts */
  acc = now_us - t->last_us;
  t->last_us = now_us;
  if (acc > (UINT32_MAX - t->frac_us)) {
    whole = acc / US_PER_MS;
    acc = (acc % US_PER_MS) + t->frac_us;
  } else {
    acc += t->frac_us;
  }
  if (acc < (SUBTRACT_MAX_MS * US_PER_MS)) {
    while (acc >= US_PER_MS) {
      acc -= US_PER_MS;
      whole++;
    }
  } else {
    whole += acc / US_PER_MS;
    acc %= US_PER_MS;
  }
  t->frac_us = acc;
  t->ms += (uint64_t)whole;
  return t->ms;
}

uint64_t canfdi_uptime_ms(const canfdi_uptime_t *t)
{
  CANFDI_ASSERT(t != NULL);
  return t->ms;
}
