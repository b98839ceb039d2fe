/*
 * test_testsched.c — the scheduler of the intrusive test signal
 * (firmware/diag/canfdi_testsched).
 *
 * Each test drives one scheduler step by step with the inputs of a
 * situation (enabled, excited, need, unlearnt) and checks when the signal
 * is on, for how long, and why; the counts come from the configuration,
 * never from an observed run.
 */
#include <check.h>

#include "diag/canfdi_testsched.h"
#include "unit_main.h"

static canfdi_testsched_t ts;
static canfdi_testsched_cfg_t cfg;

static void setup_cfg(bool keyon)
{
  cfg.lack_steps = 100U;
  cfg.burst_steps = 20U;
  cfg.need_max_steps = 50U;
  cfg.rest_steps = 30U;
  cfg.keyon = keyon;
  ck_assert_int_eq(canfdi_testsched_init(&ts, &cfg), CANFDI_OK);
}

/* Steps with the same inputs; returns how many of them had the signal on. */
static uint32_t run(uint32_t n, bool enabled, bool excited, bool need, bool unlearnt)
{
  uint32_t on = 0U;
  uint32_t k;
  for (k = 0U; k < n; k++) {
    on += canfdi_testsched_step(&ts, enabled, excited, need, unlearnt) ? 1U : 0U;
  }
  return on;
}

START_TEST(test_rejects_bad_cfg)
{
  canfdi_testsched_cfg_t c;
  canfdi_testsched_default_cfg(&c);
  ck_assert_int_eq(canfdi_testsched_init(&ts, &c), CANFDI_OK);
  ck_assert_int_eq(canfdi_testsched_init(NULL, &c), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_testsched_init(&ts, NULL), -CANFDI_EINVAL);
  c.burst_steps = 0U;
  ck_assert_int_eq(canfdi_testsched_init(&ts, &c), -CANFDI_EINVAL);
  canfdi_testsched_default_cfg(&c);
  c.lack_steps = 0U;
  ck_assert_int_eq(canfdi_testsched_init(&ts, &c), -CANFDI_EINVAL);
  canfdi_testsched_default_cfg(&c);
  c.need_max_steps = 0U;
  ck_assert_int_eq(canfdi_testsched_init(&ts, &c), -CANFDI_EINVAL);
  /* an uninitialised or NULL scheduler stays off */
  ck_assert(!canfdi_testsched_step(NULL, true, false, true, true));
}
END_TEST

/* Key-on: one burst of burst_steps at the first enabled step, then rest. */
START_TEST(test_keyon_burst_once)
{
  setup_cfg(true);
  ck_assert_uint_eq(run(10U, false, false, false, false), 0U); /* not enabled: waits */
  ck_assert_uint_eq(run(cfg.burst_steps, true, true, false, false), cfg.burst_steps);
  ck_assert_uint_eq(ts.diag.bursts[CANFDI_TESTSCHED_REASON_KEYON], 1U);
  ck_assert_uint_eq(run(500U, true, true, false, false), 0U); /* excited: no lack burst */
  ck_assert_uint_eq(ts.diag.bursts[CANFDI_TESTSCHED_REASON_KEYON], 1U);
}
END_TEST

/* Lack of excitation: a burst after lack_steps enabled steps without it;
 * steps outside the enabling conditions do not count. */
START_TEST(test_lack_counts_enabled_steps_only)
{
  uint32_t k;
  setup_cfg(false);
  for (k = 0U; k < cfg.lack_steps - 1U; k++) {
    ck_assert(!canfdi_testsched_step(&ts, true, false, false, false));
    ck_assert(!canfdi_testsched_step(&ts, false, false, false, false));
  }
  ck_assert(canfdi_testsched_step(&ts, true, false, false, false));
  ck_assert_uint_eq(ts.reason, CANFDI_TESTSCHED_REASON_LACK);
  /* the burst lasts burst_steps, the starting step included */
  ck_assert_uint_eq(run(cfg.burst_steps, true, false, false, false), cfg.burst_steps - 1U);
}
END_TEST

/* Excitation from driving restarts the lack count: no burst ever. */
START_TEST(test_natural_excitation_suffices)
{
  uint32_t k;
  uint32_t on = 0U;
  setup_cfg(false);
  for (k = 0U; k < 10000U; k++) {
    on += canfdi_testsched_step(&ts, true, (k % (cfg.lack_steps / 2U)) == 0U, false, false) ? 1U : 0U;
  }
  ck_assert_uint_eq(on, 0U);
}
END_TEST

/* A need starts a burst at once and keeps it while it lasts. */
START_TEST(test_need_burst_follows_need)
{
  setup_cfg(false);
  ck_assert_uint_eq(run(10U, true, true, false, false), 0U);
  ck_assert_uint_eq(run(30U, true, true, true, false), 30U);
  ck_assert_uint_eq(ts.reason, CANFDI_TESTSCHED_REASON_NEED);
  /* isolated: the need ends, so does the burst */
  ck_assert_uint_eq(run(5U, true, true, false, false), 0U);
  ck_assert_uint_eq(ts.phase, CANFDI_TESTSCHED_REST);
  /* a new fault may interrupt the rest */
  ck_assert(canfdi_testsched_step(&ts, true, true, true, false));
}
END_TEST

/* A need the longest burst does not resolve: off for the rest, however
 * long the need lasts, then one more burst. */
START_TEST(test_exhausted_need_rests)
{
  setup_cfg(false);
  /* need_max_steps on; the next step ends the burst */
  ck_assert_uint_eq(run(cfg.need_max_steps + 1U, true, true, true, false), cfg.need_max_steps);
  ck_assert(ts.exhausted);
  /* the rest runs out (its last step returns to idle) */
  ck_assert_uint_eq(run(cfg.rest_steps, true, true, true, false), 0U);
  ck_assert_uint_eq(run(cfg.need_max_steps + 1U, true, true, true, false), cfg.need_max_steps);
  ck_assert_uint_eq(ts.diag.bursts[CANFDI_TESTSCHED_REASON_NEED], 2U);
}
END_TEST

/* A need during a key-on burst extends it up to need_max_steps. */
START_TEST(test_need_extends_keyon)
{
  setup_cfg(true);
  ck_assert_uint_eq(run(cfg.need_max_steps + 10U, true, true, true, false), cfg.need_max_steps);
  ck_assert_uint_eq(ts.reason, CANFDI_TESTSCHED_REASON_KEYON);
}
END_TEST

/* The enabling conditions falling stop a burst at once. */
START_TEST(test_abort_when_disabled)
{
  setup_cfg(true);
  ck_assert_uint_eq(run(5U, true, true, false, false), 5U);
  ck_assert(!canfdi_testsched_step(&ts, false, true, false, false));
  ck_assert_uint_eq(ts.diag.aborted, 1U);
  ck_assert_uint_eq(ts.phase, CANFDI_TESTSCHED_REST);
}
END_TEST

/* An estimator without a converged estimate gets a burst (LEARN). */
START_TEST(test_unlearnt_burst)
{
  setup_cfg(false);
  ck_assert_uint_eq(run(cfg.burst_steps, true, true, false, true), cfg.burst_steps);
  ck_assert_uint_eq(ts.reason, CANFDI_TESTSCHED_REASON_LEARN);
  /* still unlearnt after the rest: another burst (one step ends the burst,
   * rest_steps the rest) */
  ck_assert_uint_eq(run(1U + cfg.rest_steps, true, true, false, true), 0U);
  ck_assert(canfdi_testsched_step(&ts, true, true, false, true));
  ck_assert_uint_eq(ts.diag.bursts[CANFDI_TESTSCHED_REASON_LEARN], 2U);
}
END_TEST

/* Bounded share: with the need always present, the signal is on at most
 * need_max / (need_max + rest) of the time. */
START_TEST(test_share_bounded)
{
  const uint32_t n = 10000U;
  uint32_t on;
  setup_cfg(false);
  on = run(n, true, true, true, false);
  ck_assert_uint_le(on, (n * cfg.need_max_steps) / (cfg.need_max_steps + cfg.rest_steps) + cfg.need_max_steps);
  ck_assert_uint_eq(ts.diag.on_steps, on);
}
END_TEST

static Suite *make_suite(void)
{
  Suite *s = suite_create("testsched");
  TCase *tc = tcase_create("schedule");
  tcase_add_test(tc, test_rejects_bad_cfg);
  tcase_add_test(tc, test_keyon_burst_once);
  tcase_add_test(tc, test_lack_counts_enabled_steps_only);
  tcase_add_test(tc, test_natural_excitation_suffices);
  tcase_add_test(tc, test_need_burst_follows_need);
  tcase_add_test(tc, test_exhausted_need_rests);
  tcase_add_test(tc, test_need_extends_keyon);
  tcase_add_test(tc, test_abort_when_disabled);
  tcase_add_test(tc, test_unlearnt_burst);
  tcase_add_test(tc, test_share_bounded);
  suite_add_tcase(s, tc);
  return s;
}

CANFDI_UNIT_MAIN(make_suite)
