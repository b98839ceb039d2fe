/*
 * test_count.c — the saturating counters (core/canfdi_count.h) and the
 * compile-time Q constants (core/canfdi_qconst.h).
 *
 * Counters: every width counts up by one, stops at its maximum and stays
 * there however often it is incremented; sums saturate instead of wrapping.
 * Q constants: compared with values computed here by a different route
 * (long double arithmetic, rounded half up), zero LSB tolerance, and pi's
 * rational against the digits of pi.
 */
#include <check.h>
#include <math.h>

#include "core/canfdi_count.h"
#include "core/canfdi_qconst.h"
#include "unit_main.h"

START_TEST(test_inc32_counts_and_saturates)
{
  uint32_t c = 0U;
  uint32_t i;
  for (i = 0U; i < 1000U; i++) {
    canfdi_count_inc(&c);
  }
  ck_assert_uint_eq(c, 1000U);
  c = UINT32_MAX - 2U;
  for (i = 0U; i < 10U; i++) {
    canfdi_count_inc(&c);
  }
  ck_assert_uint_eq(c, UINT32_MAX);
}
END_TEST

START_TEST(test_add32_saturates)
{
  uint32_t c = 5U;
  canfdi_count_add(&c, 7U);
  ck_assert_uint_eq(c, 12U);
  c = UINT32_MAX - 10U;
  canfdi_count_add(&c, 10U);
  ck_assert_uint_eq(c, UINT32_MAX);
  c = UINT32_MAX - 10U;
  canfdi_count_add(&c, 11U);
  ck_assert_uint_eq(c, UINT32_MAX);
  canfdi_count_add(&c, UINT32_MAX);
  ck_assert_uint_eq(c, UINT32_MAX);
  ck_assert_uint_eq(canfdi_count_sum(3U, 4U), 7U);
  ck_assert_uint_eq(canfdi_count_sum(UINT32_MAX, 1U), UINT32_MAX);
  ck_assert_uint_eq(canfdi_count_sum(0x80000000U, 0x80000000U), UINT32_MAX);
  ck_assert_uint_eq(canfdi_count_sum(0x7FFFFFFFU, 0x80000000U), UINT32_MAX);
}
END_TEST

START_TEST(test_inc16_inc8_saturate)
{
  uint16_t a = 0U;
  uint8_t b = 0U;
  uint32_t i;
  for (i = 0U; i < 70000U; i++) {
    canfdi_count_inc16(&a);
    canfdi_count_inc8(&b);
    if (i == 99U) {
      ck_assert_uint_eq(a, 100U);
      ck_assert_uint_eq(b, 100U);
    }
  }
  ck_assert_uint_eq(a, UINT16_MAX);
  ck_assert_uint_eq(b, UINT8_MAX);
}
END_TEST

/* Round half up of x * 2^frac, by long double arithmetic. */
static long long ref_q(long double x, int frac)
{
  return (long long)floorl(x * ldexpl(1.0L, frac) + 0.5L);
}

START_TEST(test_qconst_values)
{
  ck_assert_int_eq(CANFDI_Q16_ONE, 65536);
  ck_assert_int_eq(CANFDI_Q24_ONE, 16777216);
  ck_assert_int_eq(CANFDI_Q16_MILLI(1200), ref_q(1.2L, 16));
  ck_assert_int_eq(CANFDI_Q16_MILLI(4750), ref_q(4.75L, 16));
  ck_assert_int_eq(CANFDI_Q16_MILLI(-250), ref_q(-0.25L, 16));
  ck_assert_int_eq(CANFDI_Q16_MILLI(52), ref_q(0.052L, 16));
  ck_assert_int_eq(CANFDI_Q16(1, 3), ref_q(1.0L / 3.0L, 16));
  ck_assert_int_eq(CANFDI_Q16(-1, 3), ref_q(-1.0L / 3.0L, 16));
  ck_assert_int_eq(CANFDI_Q24(383, 1000), ref_q(0.383L, 24));
  /* saturation instead of wrap */
  ck_assert_int_eq(CANFDI_Q16(40000, 1), INT32_MAX);
  ck_assert_int_eq(CANFDI_Q16(-40000, 1), INT32_MIN);
}
END_TEST

START_TEST(test_qconst_degrees)
{
  const long double pi = 3.14159265358979323846264338327950288L;
  int d;
  /* pi's rational within 1e-10 relative */
  ck_assert(fabsl((long double)CANFDI_PI_NUM / (long double)CANFDI_PI_DEN - pi) < 1e-9L);
  ck_assert_int_eq(CANFDI_Q16_DEG(90, 1), ref_q(pi / 2.0L, 16));
  ck_assert_int_eq(CANFDI_Q16_DEG(180, 1), ref_q(pi, 16));
  ck_assert_int_eq(CANFDI_Q16_DEG(360, 1), ref_q(2.0L * pi, 16));
  ck_assert_int_eq(CANFDI_Q16_DEG(-7, 1), ref_q(-7.0L * pi / 180.0L, 16));
  ck_assert_int_eq(CANFDI_Q16_DEG(65, 10), ref_q(6.5L * pi / 180.0L, 16));
  /* pi / 2 per 4 V: the TPS slope */
  ck_assert_int_eq(CANFDI_Q16_DEG(90, 4), ref_q(pi / 8.0L, 16));
  /* every whole degree in the throttle's travel and beyond */
  for (d = -400; d <= 400; d++) {
    ck_assert_int_eq(CANFDI_Q16_DEG(d, 1),
                     ref_q((long double)d * pi / 180.0L, 16));
  }
}
END_TEST

static Suite *make_suite(void)
{
  Suite *s = suite_create("count");
  TCase *tc = tcase_create("counters");
  tcase_add_test(tc, test_inc32_counts_and_saturates);
  tcase_add_test(tc, test_add32_saturates);
  tcase_add_test(tc, test_inc16_inc8_saturate);
  suite_add_tcase(s, tc);
  tc = tcase_create("qconst");
  tcase_add_test(tc, test_qconst_values);
  tcase_add_test(tc, test_qconst_degrees);
  suite_add_tcase(s, tc);
  return s;
}

CANFDI_UNIT_MAIN(make_suite)
