/*
 * test_degrade.c — unit tests of firmware/ft/canfdi_degrade: the ratchet
 * (every from/to pair), the clear rule (every cause x fault_present x
 * state), the transition log, and a property test: random request/clear
 * sequences from a seeded PRNG never lower the state without an accepted
 * clear, and every transition is logged with its reason and time.
 * Expected values come from the rules in the header, re-stated here as a
 * small reference model, not from a run of the module.
 */
#include <check.h>
#include <stdint.h>

#include "ft/canfdi_degrade.h"
#include "unit_main.h"

/* xorshift64*: a fixed, documented PRNG so failures reproduce. */
static uint64_t rng_state;
static void rng_seed(uint64_t s) { rng_state = (s != 0U) ? s : 0x9E3779B97F4A7C15ULL; }
static uint32_t rng_u32(void)
{
  rng_state ^= rng_state >> 12;
  rng_state ^= rng_state << 25;
  rng_state ^= rng_state >> 27;
  return (uint32_t)((rng_state * 0x2545F4914F6CDD1DULL) >> 32);
}

/* Bring a fresh instance to state s by one request (reason 7, time 100). */
static void reach(canfdi_degrade_t *d, uint8_t s)
{
  ck_assert_int_eq(canfdi_degrade_init(d), CANFDI_OK);
  if (s != CANFDI_DEG_NORMAL) {
    ck_assert_int_eq(canfdi_degrade_request(d, s, 7U, 100U), (int32_t)s);
  }
}

/* ------------------------------------------------------------ ratchet */

START_TEST(test_ratchet_pairs)
{
  /* _i enumerates every (from, to) in 0..3 x 0..3 */
  const uint8_t from = (uint8_t)(_i / 4);
  const uint8_t to = (uint8_t)(_i % 4);
  canfdi_degrade_t d;
  canfdi_degrade_diag_t before;
  canfdi_degrade_diag_t after;
  canfdi_degrade_transition_t t;
  const uint8_t expect = (to > from) ? to : from;
  int32_t rc;

  reach(&d, from);
  before = canfdi_degrade_diag(&d);
  rc = canfdi_degrade_request(&d, to, 12U, 5000U);
  after = canfdi_degrade_diag(&d);
  ck_assert_int_eq(rc, expect);
  ck_assert_uint_eq(canfdi_degrade_state(&d), expect);
  ck_assert_uint_eq(after.ignored_relax - before.ignored_relax, (to < from) ? 1U : 0U);
  ck_assert_uint_eq(after.escalations - before.escalations, (to > from) ? 1U : 0U);
  ck_assert_uint_eq(after.transitions - before.transitions, (to > from) ? 1U : 0U);
  if (to > from) {
    ck_assert_int_eq(canfdi_degrade_log_get(&d, 0U, &t), CANFDI_OK);
    ck_assert_uint_eq(t.from, from);
    ck_assert_uint_eq(t.to, to);
    ck_assert_uint_eq(t.reason, 12U);
    ck_assert_uint_eq(t.t_ms, 5000U);
    ck_assert_uint_eq(canfdi_degrade_reason(&d), 12U);
    ck_assert_uint_eq(canfdi_degrade_since_ms(&d), 5000U);
  } else if (from != CANFDI_DEG_NORMAL) {
    /* no new transition: the reason and time of the old one stay */
    ck_assert_uint_eq(canfdi_degrade_reason(&d), 7U);
    ck_assert_uint_eq(canfdi_degrade_since_ms(&d), 100U);
  } else {
    ck_assert_uint_eq(canfdi_degrade_reason(&d), CANFDI_FAULT_NONE);
  }
}
END_TEST

START_TEST(test_request_invalid)
{
  canfdi_degrade_t d;
  reach(&d, CANFDI_DEG_DEGRADED);
  ck_assert_int_eq(canfdi_degrade_request(&d, 4U, 1U, 1U), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_degrade_request(&d, 255U, 1U, 1U), -CANFDI_EINVAL);
  ck_assert_uint_eq(canfdi_degrade_state(&d), CANFDI_DEG_DEGRADED);
  ck_assert_uint_eq(canfdi_degrade_diag(&d).rejected, 2U);
  ck_assert_int_eq(canfdi_degrade_request(NULL, 1U, 1U, 1U), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_degrade_init(NULL), -CANFDI_EINVAL);
  /* a caller that lost its instance must act safely */
  ck_assert_uint_eq(canfdi_degrade_state(NULL), CANFDI_DEG_FAIL_SAFE);
  ck_assert_uint_eq(canfdi_degrade_reason(NULL), CANFDI_FAULT_NONE);
  ck_assert_uint_eq(canfdi_degrade_since_ms(NULL), 0U);
  ck_assert_uint_eq(canfdi_degrade_diag(NULL).transitions, 0U);
}
END_TEST

/* -------------------------------------------------------------- clear */

static const uint8_t clear_causes[] = {CANFDI_DEGRADE_CLEAR_TESTER, CANFDI_DEGRADE_CLEAR_NEW_CYCLE,
                                       0x00U, 0x80U, 0xFFU};
#define N_CAUSES 5

START_TEST(test_clear_rule)
{
  /* _i enumerates state (4) x cause (5) x fault_present (2) */
  const uint8_t s = (uint8_t)(_i / (N_CAUSES * 2));
  const uint8_t cause = clear_causes[(_i / 2) % N_CAUSES];
  const bool present = (_i % 2) != 0;
  const bool cause_ok =
      (cause == CANFDI_DEGRADE_CLEAR_TESTER) || (cause == CANFDI_DEGRADE_CLEAR_NEW_CYCLE);
  canfdi_degrade_t d;
  canfdi_degrade_diag_t g;
  canfdi_degrade_transition_t t;
  int32_t rc;

  reach(&d, s);
  rc = canfdi_degrade_clear(&d, cause, present, 9000U);
  g = canfdi_degrade_diag(&d);
  if (!cause_ok) {
    ck_assert_int_eq(rc, -CANFDI_EINVAL);
    ck_assert_uint_eq(canfdi_degrade_state(&d), s);
    ck_assert_uint_eq(g.rejected, 1U);
  } else if (present) {
    ck_assert_int_eq(rc, CANFDI_DEGRADE_CLEAR_REFUSED);
    ck_assert_uint_eq(canfdi_degrade_state(&d), s);
    ck_assert_uint_eq(g.clears_refused, 1U);
    ck_assert_uint_eq(g.clears, 0U);
  } else {
    ck_assert_int_eq(rc, CANFDI_OK);
    ck_assert_uint_eq(canfdi_degrade_state(&d), CANFDI_DEG_NORMAL);
    ck_assert_uint_eq(g.clears, 1U);
    if (s != CANFDI_DEG_NORMAL) {
      ck_assert_int_eq(canfdi_degrade_log_get(&d, 0U, &t), CANFDI_OK);
      ck_assert_uint_eq(t.from, s);
      ck_assert_uint_eq(t.to, CANFDI_DEG_NORMAL);
      ck_assert_uint_eq(t.reason, cause);
      ck_assert_uint_eq(t.t_ms, 9000U);
      ck_assert_uint_eq(canfdi_degrade_reason(&d), cause);
    } else {
      /* nothing to log when already NORMAL */
      ck_assert_int_eq(canfdi_degrade_log_get(&d, 0U, &t), -CANFDI_ENODATA);
    }
  }
}
END_TEST

START_TEST(test_escalate_after_clear)
{
  /* After a clear the ratchet starts from NORMAL again. */
  canfdi_degrade_t d;
  reach(&d, CANFDI_DEG_FAIL_SAFE);
  ck_assert_int_eq(canfdi_degrade_clear(&d, CANFDI_DEGRADE_CLEAR_NEW_CYCLE, false, 10U), CANFDI_OK);
  ck_assert_int_eq(canfdi_degrade_request(&d, CANFDI_DEG_DEGRADED, 4U, 11U), CANFDI_DEG_DEGRADED);
  ck_assert_int_eq(canfdi_degrade_request(&d, CANFDI_DEG_NORMAL, 0U, 12U), CANFDI_DEG_DEGRADED);
  ck_assert_int_eq(canfdi_degrade_clear(NULL, CANFDI_DEGRADE_CLEAR_TESTER, false, 0U),
                   -CANFDI_EINVAL);
}
END_TEST

/* ---------------------------------------------------------------- log */

START_TEST(test_log_ring)
{
  /* 3 transitions per clear cycle; run past the ring length several times. */
  canfdi_degrade_t d;
  canfdi_degrade_transition_t t;
  uint32_t n = 0U;
  uint32_t k;
  uint32_t age;
  const uint32_t total = 3U * CANFDI_DEGRADE_LOG_LEN + 2U;
  ck_assert_int_eq(canfdi_degrade_init(&d), CANFDI_OK);
  ck_assert_int_eq(canfdi_degrade_log_get(&d, 0U, &t), -CANFDI_ENODATA);
  for (k = 0U; n < total; k++) {
    const uint8_t to = (uint8_t)((k % 4U) + 1U); /* 1, 2, 3, then clear */
    if ((k % 4U) == 3U) {
      ck_assert_int_eq(canfdi_degrade_clear(&d, CANFDI_DEGRADE_CLEAR_TESTER, false, k), 0);
    } else {
      ck_assert_int_eq(canfdi_degrade_request(&d, to, (uint8_t)k, k), (int32_t)to);
    }
    n++;
  }
  ck_assert_uint_eq(canfdi_degrade_diag(&d).transitions, total);
  ck_assert_uint_eq(canfdi_degrade_diag(&d).log_overwrites, total - CANFDI_DEGRADE_LOG_LEN);
  /* the newest entries, newest first: times k-1, k-2, ... */
  for (age = 0U; age < CANFDI_DEGRADE_LOG_LEN; age++) {
    ck_assert_int_eq(canfdi_degrade_log_get(&d, age, &t), CANFDI_OK);
    ck_assert_uint_eq(t.t_ms, k - 1U - age);
  }
  ck_assert_int_eq(canfdi_degrade_log_get(&d, CANFDI_DEGRADE_LOG_LEN, &t), -CANFDI_ENODATA);
  ck_assert_int_eq(canfdi_degrade_log_get(NULL, 0U, &t), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_degrade_log_get(&d, 0U, NULL), -CANFDI_EINVAL);
}
END_TEST

/* ----------------------------------------------------------- property */

/*
 * 200 seeds x 5000 random operations: a request for a random state 0..3 (a
 * quarter of them out of range 4..7), or (1 in 16) a clear with a random
 * cause and fault_present. Checked after every operation against the
 * reference model: the state equals the model's; it only decreases on an
 * accepted clear, and then to NORMAL; each transition is the newest log
 * entry with the right from/to/reason/time; the counters equal the model's.
 */
START_TEST(test_property_monotone)
{
  const uint32_t seed = (uint32_t)_i + 1U;
  canfdi_degrade_t d;
  uint8_t model = CANFDI_DEG_NORMAL;
  uint32_t transitions = 0U;
  uint32_t ignored = 0U;
  uint32_t rejected = 0U;
  uint32_t refused = 0U;
  uint32_t op;

  rng_seed(seed * 0x100000001B3ULL);
  ck_assert_int_eq(canfdi_degrade_init(&d), CANFDI_OK);
  for (op = 0U; op < 5000U; op++) {
    const uint32_t r = rng_u32();
    const uint8_t before = canfdi_degrade_state(&d);
    const uint8_t reason = (uint8_t)(r >> 24);
    canfdi_degrade_transition_t t;
    bool moved = false;
    if ((r & 15U) == 0U) {
      const uint8_t cause = ((r >> 4) & 1U) ? CANFDI_DEGRADE_CLEAR_TESTER
                                             : (((r >> 5) & 3U) == 0U ? 0x42U
                                                                      : CANFDI_DEGRADE_CLEAR_NEW_CYCLE);
      const bool present = ((r >> 8) & 1U) != 0U;
      const int32_t rc = canfdi_degrade_clear(&d, cause, present, op);
      if (cause == 0x42U) {
        ck_assert_int_eq(rc, -CANFDI_EINVAL);
        rejected++;
      } else if (present) {
        ck_assert_int_eq(rc, CANFDI_DEGRADE_CLEAR_REFUSED);
        refused++;
      } else {
        ck_assert_int_eq(rc, CANFDI_OK);
        moved = (model != CANFDI_DEG_NORMAL);
        model = CANFDI_DEG_NORMAL;
        if (moved) {
          ck_assert_int_eq(canfdi_degrade_log_get(&d, 0U, &t), CANFDI_OK);
          ck_assert_uint_eq(t.reason, cause);
        }
      }
    } else {
      const uint8_t s = (uint8_t)(((r >> 4) & 3U) + ((((r >> 6) & 3U) == 0U) ? 4U : 0U));
      const int32_t rc = canfdi_degrade_request(&d, s, reason, op);
      if (s > 3U) {
        ck_assert_int_eq(rc, -CANFDI_EINVAL);
        rejected++;
      } else {
        if (s > model) {
          model = s;
          moved = true;
          ck_assert_int_eq(canfdi_degrade_log_get(&d, 0U, &t), CANFDI_OK);
          ck_assert_uint_eq(t.reason, reason);
        } else if (s < model) {
          ignored++;
        }
        ck_assert_int_eq(rc, (int32_t)model);
      }
      /* a request never lowers the state */
      ck_assert_uint_ge(canfdi_degrade_state(&d), before);
    }
    if (moved) {
      transitions++;
      ck_assert_int_eq(canfdi_degrade_log_get(&d, 0U, &t), CANFDI_OK);
      ck_assert_uint_eq(t.from, before);
      ck_assert_uint_eq(t.to, model);
      ck_assert_uint_eq(t.t_ms, op);
      ck_assert_uint_eq(canfdi_degrade_since_ms(&d), op);
    }
    ck_assert_uint_eq(canfdi_degrade_state(&d), model);
  }
  ck_assert_uint_eq(canfdi_degrade_diag(&d).transitions, transitions);
  ck_assert_uint_eq(canfdi_degrade_diag(&d).ignored_relax, ignored);
  ck_assert_uint_eq(canfdi_degrade_diag(&d).rejected, rejected);
  ck_assert_uint_eq(canfdi_degrade_diag(&d).clears_refused, refused);
  ck_assert_uint_gt(transitions, 100U); /* the sequence exercised the ratchet */
}
END_TEST

static Suite *make_suite(void)
{
  Suite *s = suite_create("degrade");
  TCase *tc;

  tc = tcase_create("ratchet");
  tcase_add_loop_test(tc, test_ratchet_pairs, 0, 16);
  tcase_add_test(tc, test_request_invalid);
  suite_add_tcase(s, tc);

  tc = tcase_create("clear");
  tcase_add_loop_test(tc, test_clear_rule, 0, 4 * N_CAUSES * 2);
  tcase_add_test(tc, test_escalate_after_clear);
  suite_add_tcase(s, tc);

  tc = tcase_create("log");
  tcase_add_test(tc, test_log_ring);
  suite_add_tcase(s, tc);

  tc = tcase_create("property");
  tcase_add_loop_test(tc, test_property_monotone, 0, 200);
  suite_add_tcase(s, tc);
  return s;
}

CANFDI_UNIT_MAIN(make_suite)
