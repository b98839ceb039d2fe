/*
 * test_uptime.c — the millisecond uptime (core/canfdi_uptime.h) against an
 * exact 64-bit reference: 1 ms steps past 72 minutes (the 32-bit
 * microsecond clock wraps at 71.6), a clock that starts just before its
 * wrap, irregular steps of random length, and single gaps up to 2^32 - 1 us.
 */
#include <check.h>

#include "core/canfdi_uptime.h"
#include "unit_main.h"

START_TEST(test_one_ms_steps_past_72_minutes)
{
  canfdi_uptime_t t;
  uint64_t k;
  canfdi_uptime_init(&t, 0U);
  ck_assert_uint_eq(canfdi_uptime_ms(&t), 0U);
  for (k = 1U; k <= UINT64_C(75) * 60U * 1000U; k++) {
    const uint32_t now_us = (uint32_t)(k * 1000U); /* wraps at 4294.967296 s */
    const uint64_t ms = canfdi_uptime_advance(&t, now_us);
    if (ms != k) {
      ck_abort_msg("step %llu: uptime %llu ms", (unsigned long long)k, (unsigned long long)ms);
    }
  }
  ck_assert_uint_eq(canfdi_uptime_ms(&t), UINT64_C(4500000));
}
END_TEST

START_TEST(test_clock_starting_near_its_wrap)
{
  canfdi_uptime_t t;
  uint32_t k;
  const uint32_t t0 = UINT32_MAX - 2500U;
  canfdi_uptime_init(&t, t0);
  for (k = 1U; k <= 10000U; k++) {
    ck_assert_uint_eq(canfdi_uptime_advance(&t, t0 + (k * 1000U)), k);
  }
}
END_TEST

static uint64_t g_rng = 0x1234567U;
static uint32_t rnd32(void)
{
  g_rng ^= g_rng << 13;
  g_rng ^= g_rng >> 7;
  g_rng ^= g_rng << 17;
  return (uint32_t)(g_rng >> 11);
}

START_TEST(test_irregular_steps)
{
  canfdi_uptime_t t;
  uint64_t true_us = 0U;
  uint32_t clock = 0xFFFF0000U;
  uint32_t k;
  canfdi_uptime_init(&t, clock);
  for (k = 0U; k < 200000U; k++) {
    /* mostly around a millisecond, sometimes long */
    const uint32_t r = rnd32();
    const uint32_t d = ((r & 0xFFU) == 0U) ? (r >> 4) : (900U + (r % 300U));
    clock += d;
    true_us += d;
    if (canfdi_uptime_advance(&t, clock) != (true_us / 1000U)) {
      ck_abort_msg("after %u steps: %llu ms, want %llu", k,
                   (unsigned long long)canfdi_uptime_ms(&t), (unsigned long long)(true_us / 1000U));
    }
  }
}
END_TEST

START_TEST(test_largest_gaps)
{
  canfdi_uptime_t t;
  canfdi_uptime_init(&t, 0U);
  ck_assert_uint_eq(canfdi_uptime_advance(&t, 999U), 0U);
  /* 2^32 - 1 us more: the remainder 999 plus the gap */
  ck_assert_uint_eq(canfdi_uptime_advance(&t, 998U), (UINT64_C(999) + UINT32_MAX) / 1000U);
  ck_assert_uint_eq(canfdi_uptime_advance(&t, 998U), (UINT64_C(999) + UINT32_MAX) / 1000U);
  ck_assert_uint_eq(canfdi_uptime_advance(&t, 998U + 5000U),
                    (UINT64_C(999) + UINT32_MAX + 5000U) / 1000U);
}
END_TEST

static Suite *make_suite(void)
{
  Suite *s = suite_create("uptime");
  TCase *tc = tcase_create("uptime");
  tcase_add_test(tc, test_one_ms_steps_past_72_minutes);
  tcase_add_test(tc, test_clock_starting_near_its_wrap);
  tcase_add_test(tc, test_irregular_steps);
  tcase_add_test(tc, test_largest_gaps);
  suite_add_tcase(s, tc);
  return s;
}

CANFDI_UNIT_MAIN(make_suite)
