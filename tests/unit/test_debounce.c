/*
 * test_debounce.c — unit tests of firmware/core/canfdi_debounce.
 *
 * Expected step counts are derived from the counting rule in the header
 * (ceil(distance / step)), not copied from a run; a small reference model
 * written independently below checks long random report sequences.
 */
#include <check.h>
#include <limits.h>
#include <stdint.h>

#include "core/canfdi_debounce.h"
#include "unit_main.h"

static int32_t ceil_div(int32_t a, int32_t b)
{
  return (a + b - 1) / b; /* a >= 0, b > 0 */
}

static canfdi_debounce_cfg_t plain_cfg(int16_t f, int16_t p, uint16_t up, uint16_t down)
{
  canfdi_debounce_cfg_t c = {0};
  c.failed_threshold = f;
  c.passed_threshold = p;
  c.prefailed_step = up;
  c.prepassed_step = down;
  return c;
}

/* ---------------------------------------------------------------- config */

typedef struct {
  int16_t f, p;
  uint16_t up, down;
  bool ju;
  int16_t juv;
  bool jd;
  int16_t jdv;
  int32_t expect;
} cfg_case_t;

static const cfg_case_t cfg_cases[] = {
    /* valid, including every end of the domain */
    {10, -10, 1, 1, false, 0, false, 0, CANFDI_OK},
    {1, -1, 1, 1, false, 0, false, 0, CANFDI_OK},
    {INT16_MAX, INT16_MIN, 32767U, 32767U, false, 0, false, 0, CANFDI_OK},
    {10, -10, 1, 1, true, -10, true, 10, CANFDI_OK},
    {10, -10, 1, 1, true, 10, true, -10, CANFDI_OK},
    {10, -10, 1, 1, false, 11, false, -11, CANFDI_OK}, /* disabled jumps unchecked */
    /* thresholds of the wrong sign */
    {0, -10, 1, 1, false, 0, false, 0, -CANFDI_EINVAL},
    {-1, -10, 1, 1, false, 0, false, 0, -CANFDI_EINVAL},
    {10, 0, 1, 1, false, 0, false, 0, -CANFDI_EINVAL},
    {10, 1, 1, 1, false, 0, false, 0, -CANFDI_EINVAL},
    /* steps out of 1..32767 */
    {10, -10, 0, 1, false, 0, false, 0, -CANFDI_EINVAL},
    {10, -10, 1, 0, false, 0, false, 0, -CANFDI_EINVAL},
    {10, -10, 32768U, 1, false, 0, false, 0, -CANFDI_EINVAL},
    {10, -10, 1, UINT16_MAX, false, 0, false, 0, -CANFDI_EINVAL},
    /* enabled jump values outside [passed, failed] threshold */
    {10, -10, 1, 1, true, 11, false, 0, -CANFDI_EINVAL},
    {10, -10, 1, 1, true, -11, false, 0, -CANFDI_EINVAL},
    {10, -10, 1, 1, false, 0, true, 11, -CANFDI_EINVAL},
    {10, -10, 1, 1, false, 0, true, -11, -CANFDI_EINVAL},
};
#define N_CFG_CASES ((int)(sizeof cfg_cases / sizeof cfg_cases[0]))

START_TEST(test_cfg_table)
{
  const cfg_case_t *k = &cfg_cases[_i];
  canfdi_debounce_cfg_t c = plain_cfg(k->f, k->p, k->up, k->down);
  canfdi_debounce_t d;
  c.jump_up = k->ju;
  c.jump_up_value = k->juv;
  c.jump_down = k->jd;
  c.jump_down_value = k->jdv;
  ck_assert_int_eq(canfdi_debounce_cfg_check(&c), k->expect);
  ck_assert_int_eq(canfdi_debounce_init(&d, &c), k->expect);
  if (k->expect != CANFDI_OK) {
    /* a rejected instance stays unusable */
    ck_assert_int_eq(canfdi_debounce_step(&d, CANFDI_DEB_REPORT_PREFAILED), -CANFDI_EINVAL);
    ck_assert_int_eq(canfdi_debounce_fdc(&d), 0);
  }
}
END_TEST

START_TEST(test_null_arguments)
{
  canfdi_debounce_cfg_t c = plain_cfg(3, -3, 1, 1);
  canfdi_debounce_t d;
  ck_assert_int_eq(canfdi_debounce_cfg_check(NULL), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_debounce_init(NULL, &c), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_debounce_init(&d, NULL), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_debounce_step(NULL, CANFDI_DEB_REPORT_FAILED), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_debounce_status(NULL), CANFDI_DEB_UNDECIDED);
  ck_assert_int_eq(canfdi_debounce_counter(NULL), 0);
  ck_assert_int_eq(canfdi_debounce_fdc(NULL), 0);
  canfdi_debounce_reset(NULL);
  canfdi_debounce_start_cycle(NULL);
}
END_TEST

START_TEST(test_unknown_report_rejected)
{
  canfdi_debounce_cfg_t c = plain_cfg(3, -3, 1, 1);
  canfdi_debounce_t d;
  ck_assert_int_eq(canfdi_debounce_init(&d, &c), CANFDI_OK);
  ck_assert_int_eq(canfdi_debounce_step(&d, CANFDI_DEB_REPORT_PREFAILED), CANFDI_DEB_UNDECIDED);
  ck_assert_int_eq(canfdi_debounce_step(&d, (canfdi_deb_report_t)4), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_debounce_step(&d, (canfdi_deb_report_t)-1), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_debounce_counter(&d), 1);
  ck_assert_uint_eq(d.diag.rejected_reports, 2U);
}
END_TEST

/* ---------------------------------------------------------------- timing */

typedef struct {
  int16_t f, p;
  uint16_t up, down;
} timing_case_t;

static const timing_case_t timing_cases[] = {
    {10, -10, 1, 1},   {10, -10, 3, 3},  {10, -10, 10, 10}, {10, -10, 11, 11},
    {127, -128, 2, 5}, {5, -100, 1, 7},  {1, -1, 1, 1},     {100, -1, 33, 1},
    {INT16_MAX, INT16_MIN, 32767U, 32767U}, {INT16_MAX, INT16_MIN, 1000U, 999U},
};
#define N_TIMING_CASES ((int)(sizeof timing_cases / sizeof timing_cases[0]))

/* From 0: FAILED on PREFAILED report number ceil(F / up), not one earlier;
 * then from F: PASSED on PREPASSED report number ceil((F - P) / down), the
 * status staying FAILED until then (Dem: only a qualified pass clears it). */
START_TEST(test_qualification_step_counts)
{
  const timing_case_t *k = &timing_cases[_i];
  const canfdi_debounce_cfg_t c = plain_cfg(k->f, k->p, k->up, k->down);
  canfdi_debounce_t d;
  const int32_t n_fail = ceil_div(k->f, k->up);
  const int32_t n_pass = ceil_div((int32_t)k->f - k->p, k->down);
  int32_t n;
  ck_assert_int_eq(canfdi_debounce_init(&d, &c), CANFDI_OK);
  for (n = 1; n < n_fail; n++) {
    ck_assert_int_eq(canfdi_debounce_step(&d, CANFDI_DEB_REPORT_PREFAILED), CANFDI_DEB_UNDECIDED);
    ck_assert_int_eq(canfdi_debounce_counter(&d), n * k->up);
  }
  ck_assert_int_eq(canfdi_debounce_step(&d, CANFDI_DEB_REPORT_PREFAILED), CANFDI_DEB_FAILED);
  ck_assert_int_eq(canfdi_debounce_counter(&d), k->f); /* clipped at F */
  ck_assert_int_eq(canfdi_debounce_fdc(&d), 127);
  /* more PREFAILED: stays clipped */
  ck_assert_int_eq(canfdi_debounce_step(&d, CANFDI_DEB_REPORT_PREFAILED), CANFDI_DEB_FAILED);
  ck_assert_int_eq(canfdi_debounce_counter(&d), k->f);
  for (n = 1; n < n_pass; n++) {
    ck_assert_int_eq(canfdi_debounce_step(&d, CANFDI_DEB_REPORT_PREPASSED), CANFDI_DEB_FAILED);
    ck_assert_int_eq(canfdi_debounce_counter(&d), k->f - n * k->down);
    ck_assert(d.test_failed);
  }
  ck_assert_int_eq(canfdi_debounce_step(&d, CANFDI_DEB_REPORT_PREPASSED), CANFDI_DEB_PASSED);
  ck_assert_int_eq(canfdi_debounce_counter(&d), k->p);
  ck_assert_int_eq(canfdi_debounce_fdc(&d), -128);
  ck_assert(!d.test_failed);
  ck_assert(d.test_failed_this_cycle);
  ck_assert_uint_eq(d.diag.failed_qualifications, 1U);
  ck_assert_uint_eq(d.diag.passed_qualifications, 1U);
}
END_TEST

/* FAILED / PASSED reports qualify on the spot, from anywhere. */
START_TEST(test_direct_reports)
{
  const timing_case_t *k = &timing_cases[_i];
  const canfdi_debounce_cfg_t c = plain_cfg(k->f, k->p, k->up, k->down);
  canfdi_debounce_t d;
  ck_assert_int_eq(canfdi_debounce_init(&d, &c), CANFDI_OK);
  ck_assert_int_eq(canfdi_debounce_step(&d, CANFDI_DEB_REPORT_FAILED), CANFDI_DEB_FAILED);
  ck_assert_int_eq(canfdi_debounce_counter(&d), k->f);
  ck_assert_int_eq(canfdi_debounce_step(&d, CANFDI_DEB_REPORT_PREPASSED), CANFDI_DEB_FAILED);
  ck_assert_int_eq(canfdi_debounce_step(&d, CANFDI_DEB_REPORT_PASSED), CANFDI_DEB_PASSED);
  ck_assert_int_eq(canfdi_debounce_counter(&d), k->p);
  ck_assert_int_eq(canfdi_debounce_step(&d, CANFDI_DEB_REPORT_FAILED), CANFDI_DEB_FAILED);
}
END_TEST

/* ------------------------------------------------------------------ jumps */

typedef struct {
  bool jump;
  int16_t value;
} jump_case_t;

static const jump_case_t jump_cases[] = {
    {false, 0}, {true, 0}, {true, -5}, {true, 5}, {true, -20}, {true, 20},
};
#define N_JUMP_CASES ((int)(sizeof jump_cases / sizeof jump_cases[0]))

/* After a qualified pass (counter at P), a PREFAILED stream qualifies after
 * ceil((F - start) / up) reports, start = jump_up_value if jump up is on and
 * P < value, else P. */
START_TEST(test_jump_up)
{
  const jump_case_t *k = &jump_cases[_i];
  canfdi_debounce_cfg_t c = plain_cfg(20, -20, 3, 2);
  canfdi_debounce_t d;
  int32_t n;
  int32_t start;
  int32_t expect_n;
  c.jump_up = k->jump;
  c.jump_up_value = k->value;
  ck_assert_int_eq(canfdi_debounce_init(&d, &c), CANFDI_OK);
  ck_assert_int_eq(canfdi_debounce_step(&d, CANFDI_DEB_REPORT_PASSED), CANFDI_DEB_PASSED);
  start = (k->jump && (c.passed_threshold < k->value)) ? k->value : c.passed_threshold;
  expect_n = ceil_div(c.failed_threshold - start, c.prefailed_step);
  if (expect_n < 1) {
    expect_n = 1; /* jump value == F: the jump plus one step qualifies */
  }
  for (n = 1; n < expect_n; n++) {
    ck_assert_int_eq(canfdi_debounce_step(&d, CANFDI_DEB_REPORT_PREFAILED), CANFDI_DEB_PASSED);
    ck_assert_int_eq(canfdi_debounce_counter(&d), start + n * c.prefailed_step);
  }
  ck_assert_int_eq(canfdi_debounce_step(&d, CANFDI_DEB_REPORT_PREFAILED), CANFDI_DEB_FAILED);
  /* jump up never acts on PREPASSED */
  ck_assert_int_eq(canfdi_debounce_step(&d, CANFDI_DEB_REPORT_PREPASSED), CANFDI_DEB_FAILED);
  ck_assert_int_eq(canfdi_debounce_counter(&d), c.failed_threshold - c.prepassed_step);
}
END_TEST

START_TEST(test_jump_down)
{
  const jump_case_t *k = &jump_cases[_i];
  canfdi_debounce_cfg_t c = plain_cfg(20, -20, 2, 3);
  canfdi_debounce_t d;
  int32_t n;
  int32_t start;
  int32_t expect_n;
  c.jump_down = k->jump;
  c.jump_down_value = k->value;
  ck_assert_int_eq(canfdi_debounce_init(&d, &c), CANFDI_OK);
  ck_assert_int_eq(canfdi_debounce_step(&d, CANFDI_DEB_REPORT_FAILED), CANFDI_DEB_FAILED);
  start = (k->jump && (c.failed_threshold > k->value)) ? k->value : c.failed_threshold;
  expect_n = ceil_div(start - c.passed_threshold, c.prepassed_step);
  for (n = 1; n < expect_n; n++) {
    ck_assert_int_eq(canfdi_debounce_step(&d, CANFDI_DEB_REPORT_PREPASSED), CANFDI_DEB_FAILED);
    ck_assert_int_eq(canfdi_debounce_counter(&d), start - n * c.prepassed_step);
  }
  ck_assert_int_eq(canfdi_debounce_step(&d, CANFDI_DEB_REPORT_PREPASSED), CANFDI_DEB_PASSED);
  ck_assert_int_eq(canfdi_debounce_step(&d, CANFDI_DEB_REPORT_PREFAILED), CANFDI_DEB_PASSED);
  ck_assert_int_eq(canfdi_debounce_counter(&d), c.passed_threshold + c.prefailed_step);
}
END_TEST

/* The jump acts only while the counter is on the far side of the value:
 * a counter already above the jump-up value just steps. */
START_TEST(test_jump_only_from_below)
{
  canfdi_debounce_cfg_t c = plain_cfg(20, -20, 1, 1);
  canfdi_debounce_t d;
  c.jump_up = true;
  c.jump_up_value = 0;
  ck_assert_int_eq(canfdi_debounce_init(&d, &c), CANFDI_OK);
  (void)canfdi_debounce_step(&d, CANFDI_DEB_REPORT_PREFAILED);
  (void)canfdi_debounce_step(&d, CANFDI_DEB_REPORT_PREFAILED);
  (void)canfdi_debounce_step(&d, CANFDI_DEB_REPORT_PREPASSED); /* 1 */
  (void)canfdi_debounce_step(&d, CANFDI_DEB_REPORT_PREFAILED);
  ck_assert_int_eq(canfdi_debounce_counter(&d), 2);
  (void)canfdi_debounce_step(&d, CANFDI_DEB_REPORT_PREPASSED);
  (void)canfdi_debounce_step(&d, CANFDI_DEB_REPORT_PREPASSED);
  (void)canfdi_debounce_step(&d, CANFDI_DEB_REPORT_PREPASSED); /* -1 */
  ck_assert_int_eq(canfdi_debounce_counter(&d), -1);
  (void)canfdi_debounce_step(&d, CANFDI_DEB_REPORT_PREFAILED); /* jump to 0, +1 */
  ck_assert_int_eq(canfdi_debounce_counter(&d), 1);
}
END_TEST

/* -------------------------------------------------------- FDC and flags */

/* FDC over every counter value of two configurations: endpoints, sign,
 * monotonicity and the truncation rule of the header. */
START_TEST(test_fdc_sweep)
{
  static const int16_t fs[] = {7, 127, 128, 1000, INT16_MAX};
  static const int16_t ps[] = {-9, -128, -129, -1, INT16_MIN};
  canfdi_debounce_cfg_t c = plain_cfg(fs[_i], ps[_i], 1, 1);
  canfdi_debounce_t d;
  int32_t prev = -129;
  int32_t cnt;
  ck_assert_int_eq(canfdi_debounce_init(&d, &c), CANFDI_OK);
  (void)canfdi_debounce_step(&d, CANFDI_DEB_REPORT_PASSED);
  for (cnt = c.passed_threshold; cnt <= c.failed_threshold; cnt++) {
    const int32_t fdc = canfdi_debounce_fdc(&d);
    const int32_t expect = (cnt >= 0) ? (cnt * 127) / c.failed_threshold
                                      : -((-cnt * 128) / -(int32_t)c.passed_threshold);
    ck_assert_int_eq(canfdi_debounce_counter(&d), cnt);
    ck_assert_int_eq(fdc, expect);
    ck_assert_int_ge(fdc, prev);
    ck_assert((cnt >= 0) ? (fdc >= 0) : (fdc <= 0));
    prev = fdc;
    (void)canfdi_debounce_step(&d, CANFDI_DEB_REPORT_PREFAILED);
  }
  ck_assert_int_eq(prev, 127);
}
END_TEST

START_TEST(test_flags_and_cycles)
{
  canfdi_debounce_cfg_t c = plain_cfg(2, -2, 1, 1);
  canfdi_debounce_t d;
  ck_assert_int_eq(canfdi_debounce_init(&d, &c), CANFDI_OK);
  ck_assert(!d.test_failed && !d.test_failed_this_cycle && d.test_not_completed_this_cycle);
  (void)canfdi_debounce_step(&d, CANFDI_DEB_REPORT_PREFAILED);
  ck_assert(!d.test_failed && d.test_not_completed_this_cycle); /* not qualified yet */
  (void)canfdi_debounce_step(&d, CANFDI_DEB_REPORT_PREFAILED);
  ck_assert(d.test_failed && d.test_failed_this_cycle && !d.test_not_completed_this_cycle);
  /* new cycle: counter restarts, bit 1 cleared, bit 6 set, bit 0 kept */
  canfdi_debounce_start_cycle(&d);
  ck_assert_int_eq(canfdi_debounce_counter(&d), 0);
  ck_assert(d.test_failed && !d.test_failed_this_cycle && d.test_not_completed_this_cycle);
  ck_assert_int_eq(canfdi_debounce_status(&d), CANFDI_DEB_FAILED);
  (void)canfdi_debounce_step(&d, CANFDI_DEB_REPORT_PREPASSED);
  (void)canfdi_debounce_step(&d, CANFDI_DEB_REPORT_PREPASSED);
  ck_assert(!d.test_failed && !d.test_failed_this_cycle && !d.test_not_completed_this_cycle);
  ck_assert_int_eq(canfdi_debounce_status(&d), CANFDI_DEB_PASSED);
  /* fail again in the same cycle */
  (void)canfdi_debounce_step(&d, CANFDI_DEB_REPORT_FAILED);
  ck_assert(d.test_failed && d.test_failed_this_cycle);
  ck_assert_uint_eq(d.diag.failed_qualifications, 2U);
  ck_assert_uint_eq(d.diag.passed_qualifications, 1U);
  /* reset: as after init, diagnostics kept */
  canfdi_debounce_reset(&d);
  ck_assert_int_eq(canfdi_debounce_status(&d), CANFDI_DEB_UNDECIDED);
  ck_assert_int_eq(canfdi_debounce_counter(&d), 0);
  ck_assert(!d.test_failed && !d.test_failed_this_cycle && d.test_not_completed_this_cycle);
  ck_assert_uint_eq(d.diag.failed_qualifications, 2U);
}
END_TEST

/* Repeated qualification in the same direction is counted once. */
START_TEST(test_qualification_counted_on_change)
{
  canfdi_debounce_cfg_t c = plain_cfg(1, -1, 1, 1);
  canfdi_debounce_t d;
  int i;
  ck_assert_int_eq(canfdi_debounce_init(&d, &c), CANFDI_OK);
  for (i = 0; i < 5; i++) {
    (void)canfdi_debounce_step(&d, CANFDI_DEB_REPORT_PREFAILED);
  }
  ck_assert_uint_eq(d.diag.failed_qualifications, 1U);
  for (i = 0; i < 2 * 70000; i++) { /* saturating counters */
    (void)canfdi_debounce_step(&d, (i & 1) ? CANFDI_DEB_REPORT_FAILED : CANFDI_DEB_REPORT_PASSED);
  }
  ck_assert_uint_eq(d.diag.failed_qualifications, UINT16_MAX);
  ck_assert_uint_eq(d.diag.passed_qualifications, UINT16_MAX);
}
END_TEST

/* ------------------------------------------------ reference model check */

static uint32_t lcg_state;
static uint32_t lcg(void)
{
  lcg_state = lcg_state * 1664525U + 1013904223U;
  return lcg_state >> 8;
}

/* Independent model: 64-bit counter, explicit clamping, status latch. */
typedef struct {
  int64_t c;
  int status;
} ref_t;

static void ref_step(ref_t *r, const canfdi_debounce_cfg_t *cfg, canfdi_deb_report_t rep)
{
  if (rep == CANFDI_DEB_REPORT_PREFAILED) {
    if (cfg->jump_up && r->c < cfg->jump_up_value) {
      r->c = cfg->jump_up_value;
    }
    r->c += cfg->prefailed_step;
  } else if (rep == CANFDI_DEB_REPORT_PREPASSED) {
    if (cfg->jump_down && r->c > cfg->jump_down_value) {
      r->c = cfg->jump_down_value;
    }
    r->c -= cfg->prepassed_step;
  } else if (rep == CANFDI_DEB_REPORT_FAILED) {
    r->c = cfg->failed_threshold;
  } else {
    r->c = cfg->passed_threshold;
  }
  r->c = (r->c > cfg->failed_threshold) ? cfg->failed_threshold : r->c;
  r->c = (r->c < cfg->passed_threshold) ? cfg->passed_threshold : r->c;
  if (r->c == cfg->failed_threshold) {
    r->status = CANFDI_DEB_FAILED;
  } else if (r->c == cfg->passed_threshold) {
    r->status = CANFDI_DEB_PASSED;
  }
}

/* A random valid configuration: small thresholds and steps, or (big) the
 * extremes of the int16 domain; jumps on or off, anywhere in the band. */
static void random_cfg(canfdi_debounce_cfg_t *c, bool big)
{
  c->failed_threshold = (int16_t)(big ? INT16_MAX - (int32_t)(lcg() % 100U) : 1 + (int32_t)(lcg() % 30U));
  c->passed_threshold = (int16_t)(big ? INT16_MIN + (int32_t)(lcg() % 100U) : -1 - (int32_t)(lcg() % 30U));
  c->prefailed_step = (uint16_t)(big ? 1U + lcg() % 32767U : 1U + lcg() % 12U);
  c->prepassed_step = (uint16_t)(big ? 1U + lcg() % 32767U : 1U + lcg() % 12U);
  c->jump_up = (lcg() & 1U) != 0U;
  c->jump_down = (lcg() & 1U) != 0U;
  c->jump_up_value = (int16_t)(c->passed_threshold +
                               (int32_t)(lcg() % (uint32_t)(c->failed_threshold - c->passed_threshold + 1)));
  c->jump_down_value = (int16_t)(c->passed_threshold +
                                 (int32_t)(lcg() % (uint32_t)(c->failed_threshold - c->passed_threshold + 1)));
}

START_TEST(test_random_against_reference)
{
  int cfg_i;
  lcg_state = 12345U + (uint32_t)_i;
  for (cfg_i = 0; cfg_i < 200; cfg_i++) {
    canfdi_debounce_cfg_t c;
    canfdi_debounce_t d;
    ref_t r = {0, CANFDI_DEB_UNDECIDED};
    int n;
    /* mostly small configurations (frequent qualifications), sometimes the
     * extremes of the int16 domain */
    random_cfg(&c, (lcg() % 4U) == 0U);
    ck_assert_int_eq(canfdi_debounce_init(&d, &c), CANFDI_OK);
    for (n = 0; n < 500; n++) {
      const uint32_t u = lcg() % 16U;
      /* runs of the same report, with occasional sure results */
      const canfdi_deb_report_t rep = (u == 0U)   ? CANFDI_DEB_REPORT_FAILED
                                      : (u == 1U) ? CANFDI_DEB_REPORT_PASSED
                                      : ((lcg() % 8U) < (uint32_t)((n / 40) % 2 ? 6 : 2))
                                          ? CANFDI_DEB_REPORT_PREFAILED
                                          : CANFDI_DEB_REPORT_PREPASSED;
      const int32_t st = canfdi_debounce_step(&d, rep);
      ref_step(&r, &c, rep);
      ck_assert_int_eq(canfdi_debounce_counter(&d), r.c);
      ck_assert_int_eq(st, r.status);
      ck_assert(d.test_failed == (r.status == CANFDI_DEB_FAILED));
    }
  }
}
END_TEST

/* Every field of two instances equal. */
static bool deb_eq(const canfdi_debounce_t *a, const canfdi_debounce_t *b)
{
  return (a->cfg == b->cfg) && (a->counter == b->counter) && (a->status == b->status) &&
         (a->test_failed == b->test_failed) && (a->test_failed_this_cycle == b->test_failed_this_cycle) &&
         (a->test_not_completed_this_cycle == b->test_not_completed_this_cycle) &&
         (a->diag.failed_qualifications == b->diag.failed_qualifications) &&
         (a->diag.passed_qualifications == b->diag.passed_qualifications) &&
         (a->diag.rejected_reports == b->diag.rejected_reports);
}

/* canfdi_debounce_report (a settled pass answered inline) against
 * canfdi_debounce_step on two copies: the same result and the same state
 * after every report, through random configurations, reports and cycles;
 * and where canfdi_debounce_pass_is_noop holds, the full step changes
 * nothing and returns PASSED. Both answers are seen many times. */
START_TEST(test_report_inline_pass)
{
  int cfg_i;
  uint32_t noops = 0U;
  uint32_t passes_not_noop = 0U;
  lcg_state = 777U + (uint32_t)_i;
  for (cfg_i = 0; cfg_i < 200; cfg_i++) {
    canfdi_debounce_cfg_t c;
    canfdi_debounce_t a;
    canfdi_debounce_t b;
    int n;
    random_cfg(&c, false);
    ck_assert_int_eq(canfdi_debounce_init(&a, &c), CANFDI_OK);
    ck_assert_int_eq(canfdi_debounce_init(&b, &c), CANFDI_OK);
    for (n = 0; n < 400; n++) {
      const uint32_t u = lcg() % 32U;
      const canfdi_deb_report_t rep = (u == 0U)   ? CANFDI_DEB_REPORT_FAILED
                                      : (u == 1U) ? CANFDI_DEB_REPORT_PASSED
                                      : (u < 6U)  ? CANFDI_DEB_REPORT_PREFAILED
                                                  : CANFDI_DEB_REPORT_PREPASSED;
      const bool noop = canfdi_debounce_pass_is_noop(&a, rep);
      const canfdi_debounce_t before = a;
      const int32_t sa = canfdi_debounce_report(&a, rep);
      const int32_t sb = canfdi_debounce_step(&b, rep);
      ck_assert_int_eq(sa, sb);
      ck_assert(deb_eq(&a, &b));
      if (noop) {
        noops++;
        ck_assert_int_eq(sb, (int32_t)CANFDI_DEB_PASSED);
        ck_assert(deb_eq(&b, &before));
      } else if ((rep == CANFDI_DEB_REPORT_PASSED) || (rep == CANFDI_DEB_REPORT_PREPASSED)) {
        passes_not_noop++;
      }
      if ((lcg() % 97U) == 0U) {
        canfdi_debounce_start_cycle(&a);
        canfdi_debounce_start_cycle(&b);
      }
    }
  }
  ck_assert_uint_gt(noops, 1000U);
  ck_assert_uint_gt(passes_not_noop, 1000U);
  ck_assert(!canfdi_debounce_pass_is_noop(NULL, CANFDI_DEB_REPORT_PASSED));
}
END_TEST

static Suite *make_suite(void)
{
  Suite *s = suite_create("debounce");
  TCase *tc;

  tc = tcase_create("config");
  tcase_add_loop_test(tc, test_cfg_table, 0, N_CFG_CASES);
  tcase_add_test(tc, test_null_arguments);
  tcase_add_test(tc, test_unknown_report_rejected);
  suite_add_tcase(s, tc);

  tc = tcase_create("timing");
  tcase_add_loop_test(tc, test_qualification_step_counts, 0, N_TIMING_CASES);
  tcase_add_loop_test(tc, test_direct_reports, 0, N_TIMING_CASES);
  suite_add_tcase(s, tc);

  tc = tcase_create("jump");
  tcase_add_loop_test(tc, test_jump_up, 0, N_JUMP_CASES);
  tcase_add_loop_test(tc, test_jump_down, 0, N_JUMP_CASES);
  tcase_add_test(tc, test_jump_only_from_below);
  suite_add_tcase(s, tc);

  tc = tcase_create("status");
  tcase_add_loop_test(tc, test_fdc_sweep, 0, 5);
  tcase_add_test(tc, test_flags_and_cycles);
  tcase_add_test(tc, test_qualification_counted_on_change);
  suite_add_tcase(s, tc);

  tc = tcase_create("reference");
  tcase_add_loop_test(tc, test_random_against_reference, 0, 4);
  tcase_add_loop_test(tc, test_report_inline_pass, 0, 4);
  suite_add_tcase(s, tc);
  return s;
}

CANFDI_UNIT_MAIN(make_suite)
