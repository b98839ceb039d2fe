/*
 * test_limit.c — unit tests of firmware/detect/canfdi_limit.
 *
 * The hysteresis tests use a debouncer with failed threshold 1 / passed
 * threshold -1 / steps 1, so each sample's raw symptom is visible; the
 * debounce tests use realistic thresholds and expect the exact step counts
 * of the counting rule in canfdi_debounce.h.
 */
#include <check.h>
#include <limits.h>
#include <stdint.h>

#include "detect/canfdi_limit.h"
#include "unit_main.h"

static canfdi_debounce_cfg_t deb_cfg(int16_t f, int16_t p, uint16_t up, uint16_t down)
{
  canfdi_debounce_cfg_t c = {0};
  c.failed_threshold = f;
  c.passed_threshold = p;
  c.prefailed_step = up;
  c.prepassed_step = down;
  return c;
}

static canfdi_limit_cfg_t both_cfg(int32_t min_set, int32_t min_clear, int32_t max_clear, int32_t max_set)
{
  canfdi_limit_cfg_t c = {0};
  c.max_enabled = true;
  c.min_enabled = true;
  c.max_set = max_set;
  c.max_clear = max_clear;
  c.min_set = min_set;
  c.min_clear = min_clear;
  c.deb = deb_cfg(1, -1, 1, 1);
  return c;
}

/* ---------------------------------------------------------------- config */

typedef struct {
  bool min_en, max_en;
  int32_t min_set, min_clear, max_clear, max_set;
  int32_t expect;
} cfg_case_t;

static const cfg_case_t cfg_cases[] = {
    {true, true, -100, -90, 90, 100, CANFDI_OK},
    {true, true, -100, -100, 100, 100, CANFDI_OK},               /* no hysteresis */
    {true, true, INT32_MIN, INT32_MIN, INT32_MAX, INT32_MAX, CANFDI_OK},
    {true, true, 0, 0, 1, 1, CANFDI_OK},                         /* narrowest band */
    {false, true, 500, 1000, 0, 0, CANFDI_OK},                   /* disabled side unchecked */
    {true, false, 0, 0, 500, -1000, CANFDI_OK},
    {false, false, -100, -90, 90, 100, -CANFDI_EINVAL},          /* nothing to check */
    {false, true, 0, 0, 101, 100, -CANFDI_EINVAL},               /* max_clear > max_set */
    {true, false, -100, -101, 0, 0, -CANFDI_EINVAL},             /* min_clear < min_set */
    {true, true, -100, 10, 10, 100, -CANFDI_EINVAL},             /* no in-band region */
    {true, true, -100, 20, 10, 100, -CANFDI_EINVAL},
    {true, true, 0, 0, 0, 0, -CANFDI_EINVAL},
};
#define N_CFG_CASES ((int)(sizeof cfg_cases / sizeof cfg_cases[0]))

START_TEST(test_cfg_table)
{
  const cfg_case_t *k = &cfg_cases[_i];
  canfdi_limit_cfg_t c = both_cfg(k->min_set, k->min_clear, k->max_clear, k->max_set);
  canfdi_limit_t l;
  c.min_enabled = k->min_en;
  c.max_enabled = k->max_en;
  ck_assert_int_eq(canfdi_limit_cfg_check(&c), k->expect);
  ck_assert_int_eq(canfdi_limit_init(&l, &c), k->expect);
  if (k->expect != CANFDI_OK) {
    ck_assert_int_eq(canfdi_limit_step(&l, 0), -CANFDI_EINVAL);
  }
}
END_TEST

START_TEST(test_bad_debounce_and_null)
{
  canfdi_limit_cfg_t c = both_cfg(-10, -5, 5, 10);
  canfdi_limit_t l;
  c.deb.passed_threshold = 0;
  ck_assert_int_eq(canfdi_limit_init(&l, &c), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_limit_init(&l, NULL), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_limit_init(NULL, &c), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_limit_cfg_check(NULL), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_limit_step(NULL, 0), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_limit_symptom(NULL), CANFDI_LIMIT_IN_BAND);
  ck_assert_int_eq(canfdi_limit_status(NULL), CANFDI_DEB_UNDECIDED);
  ck_assert_int_eq(canfdi_limit_failed_side(NULL), CANFDI_LIMIT_IN_BAND);
  canfdi_limit_reset(NULL);
}
END_TEST

/* ------------------------------------------------------------- hysteresis */

/* (set, clear) pairs for the upper side; the lower side is mirrored. */
typedef struct {
  int32_t set, clear;
} hyst_case_t;

static const hyst_case_t hyst_cases[] = {
    {100, 90},          {100, 100},         {0, -1},          {1, 0},
    {-50, -1000},       {INT32_MAX - 1, INT32_MAX - 1},       {INT32_MAX - 1, 0},
    {INT32_MAX - 1, INT32_MIN + 2},
};
#define N_HYST_CASES ((int)(sizeof hyst_cases / sizeof hyst_cases[0]))

static int32_t sym(canfdi_limit_t *l, int32_t x)
{
  ck_assert_int_ge(canfdi_limit_step(l, x), 0);
  return (int32_t)canfdi_limit_symptom(l);
}

/* Upper side: set strictly above max_set, hold down to max_clear, clear
 * strictly below; probed at exactly +-1 LSB of both levels. */
START_TEST(test_upper_hysteresis)
{
  const hyst_case_t *k = &hyst_cases[_i];
  canfdi_limit_cfg_t c = both_cfg(0, 0, 0, 0);
  canfdi_limit_t l;
  c.min_enabled = false;
  c.max_set = k->set;
  c.max_clear = k->clear;
  ck_assert_int_eq(canfdi_limit_init(&l, &c), CANFDI_OK);
  ck_assert_int_eq(sym(&l, k->set), CANFDI_LIMIT_IN_BAND);
  ck_assert_int_eq(sym(&l, k->clear), CANFDI_LIMIT_IN_BAND);
  ck_assert_int_eq(sym(&l, k->set + 1), CANFDI_LIMIT_ABOVE_MAX);
  ck_assert_int_eq(sym(&l, k->set), CANFDI_LIMIT_ABOVE_MAX);
  ck_assert_int_eq(sym(&l, k->clear), CANFDI_LIMIT_ABOVE_MAX);
  ck_assert_int_eq(sym(&l, k->clear - 1), CANFDI_LIMIT_IN_BAND);
  ck_assert_int_eq(sym(&l, k->set), CANFDI_LIMIT_IN_BAND);
  ck_assert_int_eq(sym(&l, INT32_MAX), CANFDI_LIMIT_ABOVE_MAX);
  ck_assert_int_eq(sym(&l, INT32_MIN), CANFDI_LIMIT_IN_BAND);
  ck_assert_uint_eq(l.diag.above_events, 2U);
  ck_assert_uint_eq(l.diag.steps_violated, 4U);
  ck_assert_uint_eq(l.diag.below_events, 0U);
}
END_TEST

START_TEST(test_lower_hysteresis)
{
  const hyst_case_t *k = &hyst_cases[_i];
  /* mirror: min_set = -set, min_clear = -clear (both representable, since
   * the table avoids INT32_MIN in set and clear) */
  canfdi_limit_cfg_t c = both_cfg(0, 0, 0, 0);
  canfdi_limit_t l;
  const int32_t set = -k->set;
  const int32_t clear = -k->clear;
  c.max_enabled = false;
  c.min_set = set;
  c.min_clear = clear;
  ck_assert_int_eq(canfdi_limit_init(&l, &c), CANFDI_OK);
  ck_assert_int_eq(sym(&l, set), CANFDI_LIMIT_IN_BAND);
  ck_assert_int_eq(sym(&l, clear), CANFDI_LIMIT_IN_BAND);
  ck_assert_int_eq(sym(&l, set - 1), CANFDI_LIMIT_BELOW_MIN);
  ck_assert_int_eq(sym(&l, set), CANFDI_LIMIT_BELOW_MIN);
  ck_assert_int_eq(sym(&l, clear), CANFDI_LIMIT_BELOW_MIN);
  ck_assert_int_eq(sym(&l, clear + 1), CANFDI_LIMIT_IN_BAND);
  ck_assert_int_eq(sym(&l, set), CANFDI_LIMIT_IN_BAND);
  ck_assert_int_eq(sym(&l, INT32_MIN), CANFDI_LIMIT_BELOW_MIN);
  ck_assert_int_eq(sym(&l, INT32_MAX), CANFDI_LIMIT_IN_BAND);
  ck_assert_uint_eq(l.diag.below_events, 2U);
  ck_assert_uint_eq(l.diag.above_events, 0U);
}
END_TEST

/* Limits at the ends of int32: x can never exceed INT32_MAX or undercut
 * INT32_MIN, so these sides never trigger, and nothing overflows. */
START_TEST(test_extreme_limits)
{
  canfdi_limit_cfg_t c = both_cfg(INT32_MIN, INT32_MIN, INT32_MAX, INT32_MAX);
  canfdi_limit_t l;
  static const int32_t xs[] = {INT32_MIN, INT32_MAX, 0, -1, INT32_MIN + 1, INT32_MAX - 1};
  size_t i;
  ck_assert_int_eq(canfdi_limit_init(&l, &c), CANFDI_OK);
  for (i = 0; i < sizeof xs / sizeof xs[0]; i++) {
    ck_assert_int_eq(sym(&l, xs[i]), CANFDI_LIMIT_IN_BAND);
  }
  ck_assert_int_eq(canfdi_limit_status(&l), CANFDI_DEB_PASSED);
}
END_TEST

/* One sample can go from ABOVE straight to BELOW (and back). */
START_TEST(test_jump_across_band)
{
  canfdi_limit_cfg_t c = both_cfg(-100, -90, 90, 100);
  canfdi_limit_t l;
  ck_assert_int_eq(canfdi_limit_init(&l, &c), CANFDI_OK);
  ck_assert_int_eq(sym(&l, 101), CANFDI_LIMIT_ABOVE_MAX);
  ck_assert_int_eq(sym(&l, -101), CANFDI_LIMIT_BELOW_MIN);
  ck_assert_int_eq(canfdi_limit_failed_side(&l), CANFDI_LIMIT_BELOW_MIN);
  ck_assert_int_eq(sym(&l, -95), CANFDI_LIMIT_BELOW_MIN); /* hold */
  ck_assert_int_eq(sym(&l, 100), CANFDI_LIMIT_IN_BAND);   /* cleared, not set */
  ck_assert_int_eq(sym(&l, INT32_MAX), CANFDI_LIMIT_ABOVE_MAX);
  ck_assert_int_eq(sym(&l, INT32_MIN), CANFDI_LIMIT_BELOW_MIN);
  ck_assert_uint_eq(l.diag.above_events, 2U);
  ck_assert_uint_eq(l.diag.below_events, 2U);
}
END_TEST

/* --------------------------------------------------------------- debounce */

typedef struct {
  int16_t f, p;
  uint16_t up, down;
} deb_case_t;

static const deb_case_t deb_cases[] = {
    {100, -100, 1, 1}, {100, -20, 1, 1}, {10, -10, 3, 2}, {1, -1, 1, 1}, {500, -500, 7, 11},
};
#define N_DEB_CASES ((int)(sizeof deb_cases / sizeof deb_cases[0]))

static int32_t ceil_div(int32_t a, int32_t b)
{
  return (a + b - 1) / b;
}

/* A sustained violation qualifies FAILED after exactly ceil(F / up) steps
 * from a fresh start; a return into the band qualifies PASSED after exactly
 * ceil((F - P) / down) steps, the status staying FAILED until then. */
START_TEST(test_debounce_timing)
{
  const deb_case_t *k = &deb_cases[_i];
  canfdi_limit_cfg_t c = both_cfg(-1000, -900, 900, 1000);
  canfdi_limit_t l;
  int32_t n;
  const int32_t n_fail = ceil_div(k->f, k->up);
  const int32_t n_pass = ceil_div((int32_t)k->f - k->p, k->down);
  c.deb = deb_cfg(k->f, k->p, k->up, k->down);
  ck_assert_int_eq(canfdi_limit_init(&l, &c), CANFDI_OK);
  for (n = 1; n < n_fail; n++) {
    ck_assert_int_eq(canfdi_limit_step(&l, 1001), CANFDI_DEB_UNDECIDED);
  }
  ck_assert_int_eq(canfdi_limit_step(&l, 1001), CANFDI_DEB_FAILED);
  ck_assert_int_eq(canfdi_limit_failed_side(&l), CANFDI_LIMIT_ABOVE_MAX);
  /* inside the hysteresis band the symptom still holds: no pass counting */
  for (n = 0; n < 3 * n_pass; n++) {
    ck_assert_int_eq(canfdi_limit_step(&l, 900), CANFDI_DEB_FAILED);
  }
  for (n = 1; n < n_pass; n++) {
    ck_assert_int_eq(canfdi_limit_step(&l, 0), CANFDI_DEB_FAILED);
  }
  ck_assert_int_eq(canfdi_limit_step(&l, 0), CANFDI_DEB_PASSED);
  ck_assert_int_eq(canfdi_limit_failed_side(&l), CANFDI_LIMIT_ABOVE_MAX); /* history */
  ck_assert_uint_eq(l.deb.diag.failed_qualifications, 1U);
}
END_TEST

/* An intermittent violation with duty cycle d qualifies only if the
 * expected counter drift up*d - down*(1-d) is positive. Here: violated 1
 * step in 3 (d = 1/3). With up = 2, down = 1 the drift per 3 steps is 0 and
 * the counter stays in a bounded range (never fails); with up = 3 it grows
 * by 1 per period and fails after a computable number of periods. */
START_TEST(test_intermittent)
{
  canfdi_limit_cfg_t c = both_cfg(-1000, -900, 900, 1000);
  canfdi_limit_t l;
  int32_t n;
  int32_t expect_period;
  c.deb = deb_cfg(50, -50, 2, 1);
  ck_assert_int_eq(canfdi_limit_init(&l, &c), CANFDI_OK);
  for (n = 0; n < 3000; n++) {
    ck_assert_int_ne(canfdi_limit_step(&l, (n % 3 == 0) ? 2000 : 0), CANFDI_DEB_FAILED);
  }
  c.deb = deb_cfg(50, -50, 3, 1);
  ck_assert_int_eq(canfdi_limit_init(&l, &c), CANFDI_OK);
  /* counter after the violating step of period k (k = 0, 1, ...):
   * 3 + k (it is 3 after the first report, then +3 -1 -1 per period);
   * it reaches 50 in period 47. */
  expect_period = 50 - 3;
  for (n = 0; n < 3 * expect_period; n++) {
    ck_assert_int_ne(canfdi_limit_step(&l, (n % 3 == 0) ? 2000 : 0), CANFDI_DEB_FAILED);
  }
  ck_assert_int_eq(canfdi_limit_step(&l, 2000), CANFDI_DEB_FAILED);
}
END_TEST

START_TEST(test_reset)
{
  canfdi_limit_cfg_t c = both_cfg(-10, -5, 5, 10);
  canfdi_limit_t l;
  ck_assert_int_eq(canfdi_limit_init(&l, &c), CANFDI_OK);
  ck_assert_int_eq(canfdi_limit_step(&l, -11), CANFDI_DEB_FAILED);
  ck_assert_int_eq(canfdi_limit_failed_side(&l), CANFDI_LIMIT_BELOW_MIN);
  canfdi_limit_reset(&l);
  ck_assert_int_eq(canfdi_limit_symptom(&l), CANFDI_LIMIT_IN_BAND);
  ck_assert_int_eq(canfdi_limit_status(&l), CANFDI_DEB_UNDECIDED);
  ck_assert_int_eq(canfdi_limit_failed_side(&l), CANFDI_LIMIT_IN_BAND);
  /* the latch was forgotten: -7 (between set and clear) is now in band */
  ck_assert_int_eq(sym(&l, -7), CANFDI_LIMIT_IN_BAND);
  ck_assert_uint_eq(l.diag.below_events, 1U); /* counters survive */
}
END_TEST

/* The diagnostics counters saturate at UINT32_MAX (core/canfdi_count.h)
 * instead of wrapping to 0: set them next to the maximum and count on. */
START_TEST(test_counters_saturate)
{
  canfdi_limit_cfg_t c = both_cfg(-10, -5, 5, 10);
  canfdi_limit_t l;
  ck_assert_int_eq(canfdi_limit_init(&l, &c), CANFDI_OK);
  l.diag.above_events = UINT32_MAX - 1U;
  l.diag.below_events = UINT32_MAX;
  l.diag.steps_violated = UINT32_MAX - 1U;
  ck_assert_int_eq(sym(&l, 11), CANFDI_LIMIT_ABOVE_MAX);
  ck_assert_uint_eq(l.diag.above_events, UINT32_MAX);
  ck_assert_uint_eq(l.diag.steps_violated, UINT32_MAX);
  ck_assert_int_eq(sym(&l, 0), CANFDI_LIMIT_IN_BAND);
  ck_assert_int_eq(sym(&l, 11), CANFDI_LIMIT_ABOVE_MAX); /* a new event */
  ck_assert_uint_eq(l.diag.above_events, UINT32_MAX);
  ck_assert_int_eq(sym(&l, -11), CANFDI_LIMIT_BELOW_MIN);
  ck_assert_uint_eq(l.diag.below_events, UINT32_MAX);
  ck_assert_uint_eq(l.diag.steps_violated, UINT32_MAX);
  /* the symptom logic is unaffected by saturated counters */
  ck_assert_int_eq(sym(&l, -7), CANFDI_LIMIT_BELOW_MIN);
  ck_assert_int_eq(sym(&l, -4), CANFDI_LIMIT_IN_BAND);
}
END_TEST

static Suite *make_suite(void)
{
  Suite *s = suite_create("limit");
  TCase *tc;

  tc = tcase_create("config");
  tcase_add_loop_test(tc, test_cfg_table, 0, N_CFG_CASES);
  tcase_add_test(tc, test_bad_debounce_and_null);
  suite_add_tcase(s, tc);

  tc = tcase_create("hysteresis");
  tcase_add_loop_test(tc, test_upper_hysteresis, 0, N_HYST_CASES);
  tcase_add_loop_test(tc, test_lower_hysteresis, 0, N_HYST_CASES);
  tcase_add_test(tc, test_extreme_limits);
  tcase_add_test(tc, test_jump_across_band);
  suite_add_tcase(s, tc);

  tc = tcase_create("debounce");
  tcase_add_loop_test(tc, test_debounce_timing, 0, N_DEB_CASES);
  tcase_add_test(tc, test_intermittent);
  tcase_add_test(tc, test_reset);
  suite_add_tcase(s, tc);

  tc = tcase_create("counters");
  tcase_add_test(tc, test_counters_saturate);
  suite_add_tcase(s, tc);
  return s;
}

CANFDI_UNIT_MAIN(make_suite)
