/*
 * test_meanvar.c — unit tests of canfdi_meanvar (recursive mean/variance
 * with exponential forgetting).
 *
 * Acceptance point (docs/requirements.md): the fixed-point estimator agrees with a
 * double-precision computation of the SAME recursion with the SAME quantised
 * alpha, within stated tolerances in LSB, across the full input range,
 * without overflow (UBSan would abort on any signed overflow).
 *
 * Tolerances, checked on every sample (a = alpha_q31 / 2^31, u = 2^-53 the
 * unit round-off of double, D = running max of |x - mean| so far):
 *   mean: |m_fix - m_dbl| <= 2^-33/a          fixed point: half a Q32 LSB
 *                                             rounded per step, forgotten
 *                                             at rate a (see the header)
 *                           + 2^-33/a + 2^-31 double: half an ulp at 2^20
 *                                             per step, plus a*(2u*2^21)
 *   var:  |V_fix - V_dbl| <= df(2D + df) + 2^-21/a        fixed point
 *                           + dr(2D + dr) + u D^2 (4 + 1/a)  double
 *         with df = 2^-11 + 2^-33/a (Q10 rounding of d plus mean error) and
 *         dr = 2^-31 + 2^-33/a + u D (the double's mean error and rounding
 *         of x - m). Both bounds get 1 % slack for second-order terms.
 * The test also prints the measured maxima and the ratio to the bound.
 */
#include <check.h>
#include <math.h>
#include <stdio.h>

#include "detect/canfdi_meanvar.h"
#include "unit_main.h"

/* ck_assert reports every passing check to the parent process (a system
 * call); inside loops of 10^5 samples use this, which only reports failure. */
#define CHECK(cond)                                         \
  do {                                                      \
    if (!(cond)) {                                          \
      ck_abort_msg("%s:%d: %s", __FILE__, __LINE__, #cond); \
    }                                                       \
  } while (0)

/* ---- deterministic generator (splitmix64) ------------------------------ */

static uint64_t rng_state;

static uint64_t rng_next(void)
{
  uint64_t z = (rng_state += 0x9E3779B97F4A7C15ULL);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  return z ^ (z >> 31);
}

/* Uniform integer in [lo, hi] (bias of modulo reduction < 2^-40: harmless). */
static int32_t rng_int(int32_t lo, int32_t hi)
{
  const uint64_t span = (uint64_t)((int64_t)hi - (int64_t)lo) + 1U;
  return (int32_t)((int64_t)lo + (int64_t)(rng_next() % span));
}

/* ---- data sets covering the full input range ---------------------------- */

#define XMAX CANFDI_MEANVAR_X_MAX
#define PI 3.14159265358979323846
#define N_SAMPLES 60000 /* 6 time constants at lambda = 0.9999 */

enum {
  DS_UNIFORM,      /* uniform over [-2^20, 2^20] */
  DS_ALTERNATE,    /* +-(2^20 - 1), full-scale alternation */
  DS_NOISE_TOP,    /* +-2 LSB noise on 2^20 - 2 */
  DS_NOISE_BOTTOM, /* +-2 LSB noise on -2^20 + 2 */
  DS_CONSTANT,     /* constant at the upper limit */
  DS_STEPS,        /* random levels incl. the extremes, +-8 LSB noise */
  DS_SINE,         /* full-scale sine with +-1 LSB noise */
  DS_COUNT
};

static const char *const ds_name[DS_COUNT] = {"uniform", "alternate", "noise@top", "noise@bottom",
                                              "constant", "steps", "sine"};

static int32_t ds_sample(int ds, int k)
{
  static const int32_t levels[] = {-XMAX, -(XMAX / 2), 0, XMAX / 3, XMAX / 2, XMAX};
  static int32_t level;
  int32_t x = 0;
  switch (ds) {
  case DS_UNIFORM:
    x = rng_int(-XMAX, XMAX);
    break;
  case DS_ALTERNATE:
    x = ((k & 1) != 0) ? (XMAX - 1) : -(XMAX - 1);
    break;
  case DS_NOISE_TOP:
    x = XMAX - 2 + rng_int(-2, 2);
    break;
  case DS_NOISE_BOTTOM:
    x = -XMAX + 2 + rng_int(-2, 2);
    break;
  case DS_CONSTANT:
    x = XMAX;
    break;
  case DS_STEPS:
    /* A new level every 2500 samples, from the extremes inward; noise
     * clipped so the data stay inside the range (no saturation here). */
    if ((k % 2500) == 0) {
      level = levels[rng_int(0, (int32_t)(sizeof levels / sizeof levels[0]) - 1)];
    }
    x = level + rng_int(-8, 8);
    x = (x > XMAX) ? XMAX : ((x < -XMAX) ? -XMAX : x);
    break;
  case DS_SINE:
  default:
    x = (int32_t)lround((double)(XMAX - 1) * sin(2.0 * PI * (double)k / 5000.0)) +
        rng_int(-1, 1);
    break;
  }
  return x;
}

/* lambda = 0.9, 0.99, 0.999, 0.9999 -> alpha = 1/10 ... 1/10000 in Q31 */
static const int32_t alpha_den[] = {10, 100, 1000, 10000};
#define N_ALPHA ((int)(sizeof alpha_den / sizeof alpha_den[0]))

/* ---- reference: the same recursion in double ---------------------------- */

typedef struct {
  double m, v;
  int n;
} ref_t;

static void ref_step(ref_t *r, double a, double x)
{
  if (r->n == 0) {
    r->m = x;
    r->v = 0.0;
  } else {
    r->m = r->m + a * (x - r->m);
    const double d = x - r->m;
    r->v = r->v + a * (d * d - r->v);
  }
  r->n++;
}

/* ---- tests -------------------------------------------------------------- */

START_TEST(test_init_rejects_bad_args)
{
  canfdi_meanvar_t s;
  ck_assert_int_eq(canfdi_meanvar_init(NULL, CANFDI_Q31_RATIO(1, 100)), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_meanvar_init(&s, 0), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_meanvar_init(&s, -1), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_meanvar_init(&s, CANFDI_Q31_MIN), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_meanvar_init(&s, 1), CANFDI_OK);
  ck_assert_int_eq(canfdi_meanvar_init(&s, CANFDI_Q31_MAX), CANFDI_OK);
  ck_assert_uint_eq(canfdi_meanvar_count(&s), 0U);
}
END_TEST

/* The first sample initialises (no transient); a constant input is then
 * reproduced exactly, for every alpha and across the range. */
START_TEST(test_first_sample_and_constant_exact)
{
  static const int32_t xs[] = {0, 1, -1, 12345, -777777, XMAX, -XMAX};
  canfdi_meanvar_t s;
  for (int a = 0; a < N_ALPHA; a++) {
    for (size_t i = 0; i < sizeof xs / sizeof xs[0]; i++) {
      CHECK((canfdi_meanvar_init(&s, CANFDI_Q31_RATIO(1, alpha_den[a]))) == (CANFDI_OK));
      for (int k = 0; k < 1000; k++) {
        canfdi_meanvar_step(&s, xs[i]);
        CHECK((canfdi_meanvar_mean(&s)) == (xs[i]));
        CHECK(canfdi_meanvar_mean_q32(&s) == (int64_t)xs[i] * ((int64_t)1 << 32));
        CHECK(canfdi_meanvar_var_q20(&s) == 0U);
        CHECK((canfdi_meanvar_std_q10(&s)) == (0U));
      }
      CHECK((canfdi_meanvar_count(&s)) == (1000U));
    }
  }
}
END_TEST

/* The acceptance test: fixed point vs double, same recursion, same alpha. */
START_TEST(test_matches_double_reference)
{
  const int ds = _i / N_ALPHA;
  const int32_t alpha_q31 = CANFDI_Q31_RATIO(1, alpha_den[_i % N_ALPHA]);
  const double a = ldexp((double)alpha_q31, -31); /* exact */
  const double u = ldexp(1.0, -53);
  const double eps_m_fix = ldexp(1.0, -33) / a;
  const double eps_m_ref = ldexp(1.0, -33) / a + ldexp(1.0, -31);
  const double tol_m = 1.01 * (eps_m_fix + eps_m_ref);

  canfdi_meanvar_t s;
  ref_t r = {0.0, 0.0, 0};
  CHECK((canfdi_meanvar_init(&s, alpha_q31)) == (CANFDI_OK));
  rng_state = (uint64_t)0x5EEDU + (uint64_t)(unsigned)_i;

  double dmax = 0.0, err_m_max = 0.0, err_v_max = 0.0, ratio_v_max = 0.0, rel_v_max = 0.0;
  for (int k = 0; k < N_SAMPLES; k++) {
    const int32_t x = ds_sample(ds, k);
    canfdi_meanvar_step(&s, x);
    ref_step(&r, a, (double)x);

    const double d = fabs((double)x - r.m);
    dmax = (d > dmax) ? d : dmax;
    const double df = ldexp(1.0, -11) + eps_m_fix;
    const double dr = eps_m_ref + u * dmax;
    const double tol_v = 1.01 * (df * (2.0 * dmax + df) + ldexp(1.0, -21) / a +
                                 dr * (2.0 * dmax + dr) + u * dmax * dmax * (4.0 + 1.0 / a));

    const double m_fix = ldexp((double)canfdi_meanvar_mean_q32(&s), -32);
    const double v_fix = ldexp((double)canfdi_meanvar_var_q20(&s), -20);
    const double err_m = fabs(m_fix - r.m);
    const double err_v = fabs(v_fix - r.v);
    if (err_m > tol_m) {
      ck_abort_msg("%s a=1/%d k=%d: mean error %.3g LSB > tol %.3g", ds_name[ds],
                   (int)alpha_den[_i % N_ALPHA], k, err_m, tol_m);
    }
    if (err_v > tol_v) {
      ck_abort_msg("%s a=1/%d k=%d: var error %.3g LSB^2 > tol %.3g (V=%.6g)", ds_name[ds],
                   (int)alpha_den[_i % N_ALPHA], k, err_v, tol_v, r.v);
    }
    /* Rounded accessors agree with the full-precision ones. */
    CHECK(fabs((double)canfdi_meanvar_mean(&s) - m_fix) <= 0.5);
    CHECK(fabs((double)canfdi_meanvar_var(&s) - v_fix) <= 0.5 + 1e-3); /* + double rounding of v_fix */
    err_m_max = (err_m > err_m_max) ? err_m : err_m_max;
    err_v_max = (err_v > err_v_max) ? err_v : err_v_max;
    ratio_v_max = (err_v / tol_v > ratio_v_max) ? err_v / tol_v : ratio_v_max;
    if (r.v >= 1.0) {
      rel_v_max = (err_v / r.v > rel_v_max) ? err_v / r.v : rel_v_max;
    }
  }
  /* Never clipped: these data stay inside the range. */
  CHECK((canfdi_meanvar_diag(&s).input_saturations) == (0U));
  printf("meanvar %-12s lambda=1-1/%-5d max|dmean| %.2e LSB (tol %.2e)  max|dvar| %.2e LSB^2 "
         "(%.0f%% of tol)  max rel dvar %.1e\n",
         ds_name[ds], (int)alpha_den[_i % N_ALPHA], err_m_max, tol_m, err_v_max,
         100.0 * ratio_v_max, rel_v_max);
}
END_TEST

/* std_q10 is the exact floor square root of the Q20 variance. */
START_TEST(test_std_is_floor_sqrt)
{
  canfdi_meanvar_t s;
  CHECK((canfdi_meanvar_init(&s, CANFDI_Q31_RATIO(1, 50))) == (CANFDI_OK));
  rng_state = 42U;
  for (int k = 0; k < 20000; k++) {
    /* Noise amplitude sweeps from 1 LSB to full scale. */
    const int32_t amp = (int32_t)1 << (k / 1000 % 21);
    canfdi_meanvar_step(&s, rng_int(-amp, amp));
    const uint64_t v = canfdi_meanvar_var_q20(&s);
    const uint64_t sd = canfdi_meanvar_std_q10(&s);
    CHECK(sd * sd <= v);
    CHECK((sd + 1U) * (sd + 1U) > v);
  }
}
END_TEST

/* Out-of-range samples are clipped to +-2^20 and counted; in-range ones
 * (including the limits) are not; the estimates equal those of the clipped
 * stream. */
START_TEST(test_input_saturation)
{
  static const int32_t xs[] = {INT32_MAX, XMAX, XMAX + 1, INT32_MIN, -XMAX,
                               -XMAX - 1, 0,   5000000,  -5000000};
  static const int clipped[] = {1, 0, 1, 1, 0, 1, 0, 1, 1};
  canfdi_meanvar_t s, ref;
  CHECK((canfdi_meanvar_init(&s, CANFDI_Q31_RATIO(1, 10))) == (CANFDI_OK));
  CHECK((canfdi_meanvar_init(&ref, CANFDI_Q31_RATIO(1, 10))) == (CANFDI_OK));
  uint32_t expect = 0U;
  for (int rep = 0; rep < 100; rep++) {
    for (size_t i = 0; i < sizeof xs / sizeof xs[0]; i++) {
      canfdi_meanvar_step(&s, xs[i]);
      canfdi_meanvar_step(&ref, (xs[i] > XMAX) ? XMAX : ((xs[i] < -XMAX) ? -XMAX : xs[i]));
      expect += (uint32_t)clipped[i];
      CHECK((canfdi_meanvar_diag(&s).input_saturations) == (expect));
      CHECK(canfdi_meanvar_mean_q32(&s) == canfdi_meanvar_mean_q32(&ref));
      CHECK(canfdi_meanvar_var_q20(&s) == canfdi_meanvar_var_q20(&ref));
      CHECK(canfdi_meanvar_mean(&s) >= -XMAX && canfdi_meanvar_mean(&s) <= XMAX);
      /* Variance can never exceed the largest squared deviation (2^21)^2. */
      CHECK(canfdi_meanvar_var(&s) <= ((uint64_t)1 << 42));
    }
  }
  CHECK((canfdi_meanvar_diag(&ref).input_saturations) == (0U));
}
END_TEST

/* Worst case for the internal ranges: alternating extremes with the
 * smallest and the largest alpha. UBSan guards the arithmetic; the
 * variance must approach the exact (2^20)^2-ish level, not wrap. */
START_TEST(test_extreme_alpha_no_overflow)
{
  static const int32_t alphas[] = {1, CANFDI_Q31_MAX};
  canfdi_meanvar_t s;
  for (size_t i = 0; i < 2U; i++) {
    CHECK((canfdi_meanvar_init(&s, alphas[i])) == (CANFDI_OK));
    for (int k = 0; k < 10000; k++) {
      canfdi_meanvar_step(&s, ((k & 1) != 0) ? INT32_MAX : INT32_MIN);
      CHECK(canfdi_meanvar_var(&s) <= ((uint64_t)1 << 42));
    }
  }
  /* alpha ~ 1: mean follows x, the deviation from the updated mean is tiny */
  CHECK(canfdi_meanvar_var(&s) <= 1U);
  CHECK((canfdi_meanvar_mean(&s)) == (XMAX));
}
END_TEST

/* reset forgets: the next sample re-initialises; resets are counted. */
START_TEST(test_reset)
{
  canfdi_meanvar_t s;
  ck_assert_int_eq(canfdi_meanvar_init(&s, CANFDI_Q31_RATIO(1, 100)), CANFDI_OK);
  for (int k = 0; k < 500; k++) {
    canfdi_meanvar_step(&s, ((k & 1) != 0) ? 1000 : -1000);
  }
  ck_assert(canfdi_meanvar_var(&s) > 500000U);
  canfdi_meanvar_reset(&s);
  ck_assert_uint_eq(canfdi_meanvar_count(&s), 0U);
  ck_assert_uint_eq(canfdi_meanvar_diag(&s).resets, 1U);
  canfdi_meanvar_step(&s, -4321);
  ck_assert_int_eq(canfdi_meanvar_mean(&s), -4321);
  ck_assert(canfdi_meanvar_var_q20(&s) == 0U);
  ck_assert_uint_eq(canfdi_meanvar_count(&s), 1U);
  canfdi_meanvar_reset(&s);
  ck_assert_uint_eq(canfdi_meanvar_diag(&s).resets, 2U);
}
END_TEST

static Suite *make_suite(void)
{
  Suite *su = suite_create("meanvar");
  TCase *tc = tcase_create("api");
  tcase_add_test(tc, test_init_rejects_bad_args);
  tcase_add_test(tc, test_reset);
  suite_add_tcase(su, tc);

  tc = tcase_create("exactness");
  tcase_add_test(tc, test_first_sample_and_constant_exact);
  tcase_add_test(tc, test_std_is_floor_sqrt);
  suite_add_tcase(su, tc);

  tc = tcase_create("double_reference");
  tcase_set_timeout(tc, 60);
  tcase_add_loop_test(tc, test_matches_double_reference, 0, DS_COUNT * N_ALPHA);
  suite_add_tcase(su, tc);

  tc = tcase_create("range");
  tcase_add_test(tc, test_input_saturation);
  tcase_add_test(tc, test_extreme_alpha_no_overflow);
  suite_add_tcase(su, tc);
  return su;
}

CANFDI_UNIT_MAIN(make_suite)
