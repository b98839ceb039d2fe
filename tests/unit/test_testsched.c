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
  cfg.gap_steps = 5U;
  cfg.backoff_steps = 200U;
  cfg.backoff_max_steps = 800U;
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
  canfdi_testsched_default_cfg(&c);
  c.backoff_steps = 0U;
  ck_assert_int_eq(canfdi_testsched_init(&ts, &c), -CANFDI_EINVAL);
  canfdi_testsched_default_cfg(&c);
  c.backoff_max_steps = c.backoff_steps - 1U;
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
  ck_assert_uint_eq(run(2U, true, true, false, false), 0U);
  ck_assert_uint_eq(ts.phase, CANFDI_TESTSCHED_REST);
  /* a new fault interrupts the rest once gap_steps have passed */
  ck_assert_uint_eq(run(cfg.gap_steps - 2U, true, true, true, false), 0U);
  ck_assert(canfdi_testsched_step(&ts, true, true, true, false));
  ck_assert_uint_eq(ts.diag.bursts[CANFDI_TESTSCHED_REASON_NEED], 2U);
}
END_TEST

/* A new need right after the key-on burst starts a NEED burst after the
 * gap, not after the rest. */
START_TEST(test_new_need_after_keyon_starts_at_once)
{
  setup_cfg(true);
  /* the key-on burst, and the step that ends it */
  ck_assert_uint_eq(run(cfg.burst_steps + 1U, true, true, false, false), cfg.burst_steps);
  /* the need appears: the gap, then a NEED burst (the rest is far longer) */
  ck_assert_uint_eq(run(cfg.gap_steps - 1U, true, true, true, false), 0U);
  ck_assert(canfdi_testsched_step(&ts, true, true, true, false));
  ck_assert_uint_eq(ts.reason, CANFDI_TESTSCHED_REASON_NEED);
  /* it is owed need_max_steps: on for all of them */
  ck_assert_uint_eq(run(cfg.need_max_steps, true, true, true, false), cfg.need_max_steps - 1U);
}
END_TEST

/* A need that appears near the end of the key-on burst still gets its
 * whole need_max_steps (extending the burst), not the key-on's remainder
 * followed by the rest. */
START_TEST(test_late_need_in_keyon_gets_its_share)
{
  setup_cfg(true);
  ck_assert_uint_eq(run(cfg.burst_steps - 3U, true, true, false, false), cfg.burst_steps - 3U);
  ck_assert_uint_eq(run(cfg.need_max_steps, true, true, true, false), cfg.need_max_steps);
  ck_assert_uint_eq(ts.diag.bursts[CANFDI_TESTSCHED_REASON_KEYON], 1U);
  /* now unresolved: off for the back-off */
  ck_assert_uint_eq(run(cfg.backoff_steps - 1U, true, true, true, false), 0U);
  ck_assert_uint_eq(ts.diag.unresolved, 1U);
}
END_TEST

/* A need a complete NEED burst does not resolve is not retried within the
 * back-off, however long it lasts; then once more, and the next back-off
 * is twice as long. */
START_TEST(test_unresolved_need_backs_off)
{
  uint32_t k;
  setup_cfg(false);
  /* need_max_steps on; the next step ends the burst */
  ck_assert_uint_eq(run(cfg.need_max_steps + 1U, true, true, true, false), cfg.need_max_steps);
  ck_assert_uint_eq(ts.diag.unresolved, 1U);
  /* off for the back-off (the rest long over), also at the lack burst's
   * time: a lack burst is not extended by the need */
  ck_assert_uint_eq(run(cfg.backoff_steps - 2U, true, true, true, false), 0U);
  ck_assert_uint_eq(ts.diag.bursts[CANFDI_TESTSCHED_REASON_NEED], 1U);
  /* the back-off runs out: owed need_max_steps again */
  ck_assert_uint_eq(run(2U + cfg.need_max_steps, true, true, true, false), cfg.need_max_steps);
  ck_assert_uint_eq(ts.diag.bursts[CANFDI_TESTSCHED_REASON_NEED], 2U);
  ck_assert_uint_eq(ts.diag.unresolved, 2U);
  /* the second back-off is doubled */
  ck_assert_uint_eq(run(2U * cfg.backoff_steps - 4U, true, true, true, false), 0U);
  for (k = 0U; (k < 10U) && !canfdi_testsched_step(&ts, true, true, true, false); k++) {
  }
  ck_assert_uint_le(k, 3U);
  ck_assert_uint_eq(ts.diag.bursts[CANFDI_TESTSCHED_REASON_NEED], 3U);
}
END_TEST

/* The back-off grows to backoff_max_steps and no further. */
START_TEST(test_backoff_capped)
{
  setup_cfg(false);
  (void)run(20000U, true, true, true, false);
  /* back-offs 200, 400, 800, 800, ... */
  ck_assert_uint_eq(ts.backoff_len, cfg.backoff_max_steps);
  ck_assert_uint_ge(ts.diag.unresolved, 20000U / (cfg.backoff_max_steps + cfg.need_max_steps));
  ck_assert_uint_le(ts.diag.unresolved, 3U + (20000U / cfg.backoff_max_steps));
}
END_TEST

/* The need falling ends the back-off: the next need is a new one. */
START_TEST(test_need_falling_ends_backoff)
{
  setup_cfg(false);
  ck_assert_uint_eq(run(cfg.need_max_steps + 1U, true, true, true, false), cfg.need_max_steps);
  ck_assert_uint_eq(run(cfg.gap_steps, true, true, true, false), 0U);
  ck_assert_uint_eq(run(1U, true, true, false, false), 0U); /* isolated or gone */
  ck_assert(canfdi_testsched_step(&ts, true, true, true, false));
  ck_assert_uint_eq(ts.backoff_len, cfg.backoff_steps);
}
END_TEST

/* A NEED burst stopped by the enabling conditions keeps its share: the
 * need resumes after the gap and has need_max_steps in all. */
START_TEST(test_aborted_need_keeps_share)
{
  setup_cfg(false);
  ck_assert_uint_eq(run(10U, true, true, true, false), 10U);
  ck_assert_uint_eq(run(3U, false, true, true, false), 0U);
  ck_assert_uint_eq(ts.diag.aborted, 1U);
  ck_assert_uint_eq(run(100U, true, true, true, false), cfg.need_max_steps - 10U);
  ck_assert_uint_eq(ts.diag.unresolved, 1U);
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
 * need_max / (need_max + backoff) of the time. */
START_TEST(test_share_bounded)
{
  const uint32_t n = 10000U;
  uint32_t on;
  setup_cfg(false);
  on = run(n, true, true, true, false);
  ck_assert_uint_le(on, (n * cfg.need_max_steps) / (cfg.need_max_steps + cfg.backoff_steps) + cfg.need_max_steps);
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
  tcase_add_test(tc, test_new_need_after_keyon_starts_at_once);
  tcase_add_test(tc, test_late_need_in_keyon_gets_its_share);
  tcase_add_test(tc, test_unresolved_need_backs_off);
  tcase_add_test(tc, test_backoff_capped);
  tcase_add_test(tc, test_need_falling_ends_backoff);
  tcase_add_test(tc, test_aborted_need_keeps_share);
  tcase_add_test(tc, test_need_extends_keyon);
  tcase_add_test(tc, test_abort_when_disabled);
  tcase_add_test(tc, test_unlearnt_burst);
  tcase_add_test(tc, test_share_bounded);
  suite_add_tcase(s, tc);
  return s;
}

CANFDI_UNIT_MAIN(make_suite)
