/*
 * test_adapt.c — unit tests of firmware/detect/canfdi_adapt.
 *
 * The scenario test follows the design rule in canfdi_adapt.h: a plant and
 * its model are first-order lags whose time constants differ (a model
 * error, not a fault). After a setpoint step du, sampled exactly (zero-order
 * hold), the residual r = y_plant - y_model obeys
 * |r[k]| <= |du| exp(-k T / tau_slow), so tau = tau_slow and
 * gain = tau + T (seconds, residual and u in the same unit) keep the
 * threshold above the transient, with base as the margin for noise and
 * rounding. Nothing is tuned to the data: every parameter comes from the
 * rule, and the same residual replayed in steady state must exceed base.
 */
#include <check.h>
#include <limits.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>

#include "detect/canfdi_adapt.h"
#include "unit_main.h"

#define T_S ((double)CANFDI_CFG_STEP_US * 1e-6)
#define STEPS_PER_S ((int64_t)(1000000U / CANFDI_CFG_STEP_US))

static canfdi_adapt_cfg_t make_cfg(int32_t base, int32_t max, int32_t gain, uint8_t frac, uint32_t tau)
{
  canfdi_adapt_cfg_t c;
  c.base = base;
  c.max = max;
  c.gain = gain;
  c.gain_frac_bits = frac;
  c.tau_us = tau;
  return c;
}

/* ---------------------------------------------------------------- config */

typedef struct {
  int32_t base, max, gain;
  uint8_t frac;
  uint32_t tau;
  int32_t expect;
} cfg_case_t;

static const cfg_case_t cfg_cases[] = {
    {100, 1000, 65536, 16U, 50000U, CANFDI_OK},
    {0, 0, 0, 0U, 0U, CANFDI_OK},
    {INT32_MAX, INT32_MAX, INT32_MAX, 62U, CANFDI_ADAPT_TAU_MAX_US, CANFDI_OK},
    {-1, 1000, 1, 0U, 0U, -CANFDI_EINVAL},
    {100, 99, 1, 0U, 0U, -CANFDI_EINVAL},
    {100, 1000, -1, 0U, 0U, -CANFDI_EINVAL},
    {100, 1000, 1, 63U, 0U, -CANFDI_EINVAL},
    {100, 1000, 1, 0U, CANFDI_ADAPT_TAU_MAX_US + 1U, -CANFDI_EINVAL},
    {100, 1000, 1, 0U, UINT32_MAX, -CANFDI_EINVAL},
};
#define N_CFG_CASES ((int)(sizeof cfg_cases / sizeof cfg_cases[0]))

START_TEST(test_cfg_table)
{
  const cfg_case_t *k = &cfg_cases[_i];
  const canfdi_adapt_cfg_t c = make_cfg(k->base, k->max, k->gain, k->frac, k->tau);
  canfdi_adapt_t a;
  ck_assert_int_eq(canfdi_adapt_cfg_check(&c), k->expect);
  ck_assert_int_eq(canfdi_adapt_init(&a, &c), k->expect);
  if (k->expect == CANFDI_OK) {
    ck_assert_int_eq(canfdi_adapt_threshold(&a), k->base);
  } else {
    ck_assert_int_eq(canfdi_adapt_step(&a, 0), -CANFDI_EINVAL);
    ck_assert(!canfdi_adapt_exceeds(&a, INT32_MIN));
  }
}
END_TEST

START_TEST(test_null)
{
  const canfdi_adapt_cfg_t c = make_cfg(1, 2, 3, 0U, 0U);
  canfdi_adapt_t a;
  ck_assert_int_eq(canfdi_adapt_cfg_check(NULL), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_adapt_init(NULL, &c), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_adapt_init(&a, NULL), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_adapt_step(NULL, 0), -CANFDI_EINVAL);
  ck_assert(!canfdi_adapt_exceeds(NULL, INT32_MAX));
  ck_assert_int_eq(canfdi_adapt_threshold(NULL), 0);
  ck_assert_int_eq(canfdi_adapt_excitation(NULL), 0);
  canfdi_adapt_reset(NULL);
}
END_TEST

/* -------------------------------------------------------------- scenario */

typedef struct {
  int32_t du;        /* setpoint step, units */
  double tau_p_s;    /* plant time constant */
  double tau_m_s;    /* model time constant */
  int32_t noise;     /* residual noise amplitude (uniform), < base */
} scen_case_t;

static const scen_case_t scen_cases[] = {
    {10000, 0.060, 0.040, 50}, {-20000, 0.060, 0.040, 50}, {5000, 0.100, 0.030, 20},
    {10000, 0.040, 0.060, 50}, {300000, 0.020, 0.025, 100},
};
#define N_SCEN_CASES ((int)(sizeof scen_cases / sizeof scen_cases[0]))

static uint32_t lcg_state;
static int32_t noise_uniform(int32_t amp)
{
  lcg_state = lcg_state * 1664525U + 1013904223U;
  return (int32_t)((lcg_state >> 8) % (uint32_t)(2 * amp + 1)) - amp;
}

/* During a setpoint step the threshold rises and the model-error transient
 * stays below it; the very same residual sequence, replayed once u has been
 * constant for long, exceeds the (base) threshold. */
START_TEST(test_setpoint_step)
{
  const scen_case_t *s = &scen_cases[_i];
  const double tau_slow = (s->tau_p_s > s->tau_m_s) ? s->tau_p_s : s->tau_m_s;
  const uint32_t tau_us = (uint32_t)lround(tau_slow * 1e6);
  const int32_t base = 4 * s->noise; /* margin for noise and rounding */
  /* gain = tau + T seconds, Q16 */
  const int32_t gain = (int32_t)ceil(((double)tau_us + (double)CANFDI_CFG_STEP_US) * 1e-6 * 65536.0);
  const canfdi_adapt_cfg_t c = make_cfg(base, INT32_MAX, gain, 16U, tau_us);
  canfdi_adapt_t a;
  enum { K0 = 200, N_TRANS = 1500, N_QUIET = 3000 };
  static int32_t resid[N_TRANS];
  const double cp = 1.0 - exp(-T_S / s->tau_p_s);
  const double cm = 1.0 - exp(-T_S / s->tau_m_s);
  double yp = 0.0;
  double ym = 0.0;
  int32_t thr_max = 0;
  int32_t peak_r = 0;
  int32_t exceed_transient = 0;
  int32_t exceed_steady = 0;
  int k;
  lcg_state = 7U + (uint32_t)_i;
  ck_assert_int_eq(canfdi_adapt_init(&a, &c), CANFDI_OK);
  /* at rest */
  for (k = 0; k < K0; k++) {
    ck_assert_int_eq(canfdi_adapt_step(&a, 0), base);
  }
  /* step at K0: u = du from now on; residual at K0 + j */
  for (k = 0; k < N_TRANS; k++) {
    const double u = (double)s->du;
    int32_t r;
    int32_t thr = canfdi_adapt_step(&a, s->du);
    ck_assert_int_ge(thr, base);
    r = (int32_t)lround(yp - ym) + noise_uniform(s->noise);
    resid[k] = r;
    if (canfdi_adapt_exceeds(&a, r)) {
      exceed_transient++;
    }
    thr_max = (thr > thr_max) ? thr : thr_max;
    peak_r = (abs(r) > peak_r) ? abs(r) : peak_r;
    /* exact ZOH discretisation of both lags */
    yp += cp * (u - yp);
    ym += cm * (u - ym);
  }
  ck_assert_int_eq(exceed_transient, 0);
  /* the threshold did rise, to about |du| (gain * alpha / T = 1) */
  ck_assert_int_ge(thr_max, base + abs(s->du) - 1);
  /* the transient is large compared with base: the test is not vacuous */
  ck_assert_int_gt(peak_r, 2 * base);
  /* quiet: u constant; the threshold decays back to base */
  for (k = 0; k < N_QUIET; k++) {
    (void)canfdi_adapt_step(&a, s->du);
  }
  ck_assert_int_eq(canfdi_adapt_threshold(&a), base);
  for (k = 0; k < N_TRANS; k++) {
    (void)canfdi_adapt_step(&a, s->du);
    if (canfdi_adapt_exceeds(&a, resid[k])) {
      exceed_steady++;
    }
  }
  ck_assert_int_gt(exceed_steady, 0);
  printf("adapt step du %d, tau_p %.0f ms, tau_m %.0f ms: residual peak %d, threshold peak %d, "
         "base %d; exceedances: transient %d, same residual in steady state %d\n",
         (int)s->du, s->tau_p_s * 1e3, s->tau_m_s * 1e3, (int)peak_r, (int)thr_max, (int)base,
         (int)exceed_transient, (int)exceed_steady);
}
END_TEST

/* ------------------------------------------------------------- responses */

/* Step of u: the threshold follows the closed form
 * base + gain * (a du / T) (1-a)^j at every sample (tolerance: 1 u-unit/s
 * of excitation rounding times gain, plus 1 LSB). */
START_TEST(test_step_closed_form)
{
  static const int32_t dus[] = {1000, -70000, 1, 2000000};
  const int32_t du = dus[_i];
  const uint32_t tau = 30000U;
  const canfdi_adapt_cfg_t c = make_cfg(10, INT32_MAX, 3 * 256 + 64, 8U, tau); /* gain 3.25 */
  canfdi_adapt_t a;
  const double al = (double)CANFDI_CFG_STEP_US / ((double)tau + (double)CANFDI_CFG_STEP_US);
  const double g = 3.25;
  int j;
  ck_assert_int_eq(canfdi_adapt_init(&a, &c), CANFDI_OK);
  ck_assert_int_eq(canfdi_adapt_step(&a, 0), 10);
  for (j = 0; j < 400; j++) {
    const double exc = fabs((double)du) * al / T_S * pow(1.0 - al, (double)j);
    const double ref = 10.0 + g * exc;
    const int32_t thr = canfdi_adapt_step(&a, du);
    ck_assert_msg(fabs((double)thr - ref) <= g * 0.5 + 1.0 + 1e-7 * ref, "j %d: %d vs %.2f", j, thr, ref);
    ck_assert(fabs((double)canfdi_adapt_excitation(&a) - exc) <= 0.5 + 1e-7 * exc);
  }
}
END_TEST

/* Ramp of u with slope s: the excitation settles at |s| and the threshold
 * at base + gain |s| (exact slopes: a whole number of units per step). */
START_TEST(test_ramp_settles)
{
  static const int64_t slopes[] = {1000, -5000, 250000};
  const int64_t s = slopes[_i];
  const canfdi_adapt_cfg_t c = make_cfg(0, INT32_MAX, 1, 4U, 10000U); /* gain 1/16 */
  canfdi_adapt_t a;
  int k;
  ck_assert_int_eq(canfdi_adapt_init(&a, &c), CANFDI_OK);
  for (k = 0; k < 2000; k++) {
    (void)canfdi_adapt_step(&a, (int32_t)(s * k / STEPS_PER_S));
  }
  ck_assert_int_eq(canfdi_adapt_excitation(&a), (int32_t)((s < 0) ? -s : s));
  /* round half up of |s| / 16 */
  ck_assert_int_eq(canfdi_adapt_threshold(&a), (int32_t)((((s < 0) ? -s : s) + 8) / 16));
}
END_TEST

START_TEST(test_gain_zero_and_cap)
{
  canfdi_adapt_cfg_t c = make_cfg(500, INT32_MAX, 0, 0U, 1000U);
  canfdi_adapt_t a;
  int k;
  ck_assert_int_eq(canfdi_adapt_init(&a, &c), CANFDI_OK);
  for (k = 0; k < 100; k++) {
    ck_assert_int_eq(canfdi_adapt_step(&a, (k % 2) ? 1000000 : -1000000), 500);
  }
  c = make_cfg(500, 800, 1, 0U, 1000U); /* gain 1 s: any step of 1 unit in 1 ms caps */
  ck_assert_int_eq(canfdi_adapt_init(&a, &c), CANFDI_OK);
  (void)canfdi_adapt_step(&a, 0);
  ck_assert_int_eq(canfdi_adapt_step(&a, 1000), 800);
  ck_assert_uint_eq(a.diag.cap_hits, 1U);
}
END_TEST

/* ------------------------------------------------- exceeds and extremes */

typedef struct {
  int32_t thr;
  int32_t r;
  bool expect;
} ex_case_t;

static const ex_case_t ex_cases[] = {
    {100, 100, false},  {100, 101, true},         {100, -100, false},       {100, -101, true},
    {0, 0, false},      {0, 1, true},             {0, -1, true},            {INT32_MAX, INT32_MAX, false},
    {INT32_MAX, INT32_MIN, true},                 {INT32_MAX - 1, INT32_MAX, true},
    {INT32_MAX - 1, -INT32_MAX, true},            {5, INT32_MIN, true},
};
#define N_EX_CASES ((int)(sizeof ex_cases / sizeof ex_cases[0]))

START_TEST(test_exceeds_boundaries)
{
  const ex_case_t *k = &ex_cases[_i];
  const canfdi_adapt_cfg_t c = make_cfg(k->thr, k->thr, 0, 0U, 0U);
  canfdi_adapt_t a;
  ck_assert_int_eq(canfdi_adapt_init(&a, &c), CANFDI_OK);
  ck_assert(canfdi_adapt_exceeds(&a, k->r) == k->expect);
}
END_TEST

/* Full-scale alternation of u: |du/dt| saturates (counted), the threshold
 * saturates at max, no undefined behaviour (UBSan). */
START_TEST(test_extreme_inputs)
{
  const canfdi_adapt_cfg_t c = make_cfg(INT32_MAX / 2, INT32_MAX, INT32_MAX, (uint8_t)(_i * 20), 0U);
  canfdi_adapt_t a;
  int k;
  ck_assert_int_eq(canfdi_adapt_init(&a, &c), CANFDI_OK);
  ck_assert_int_eq(canfdi_adapt_step(&a, INT32_MIN), INT32_MAX / 2);
  for (k = 1; k <= 100; k++) {
    const int32_t thr = canfdi_adapt_step(&a, (k % 2) ? INT32_MAX : INT32_MIN);
    ck_assert_int_ge(thr, INT32_MAX / 2);
    if (_i < 2) { /* gain >= 2^31 / 2^20 per unit/s: saturated */
      ck_assert_int_eq(thr, INT32_MAX);
    }
  }
  ck_assert_uint_eq(a.diag.rate_saturations, 100U);
  ck_assert_int_eq(canfdi_adapt_excitation(&a), INT32_MAX);
  canfdi_adapt_reset(&a);
  ck_assert_int_eq(canfdi_adapt_threshold(&a), INT32_MAX / 2);
  ck_assert_int_eq(canfdi_adapt_step(&a, INT32_MAX), INT32_MAX / 2); /* primes only */
  ck_assert_int_eq(canfdi_adapt_excitation(&a), 0);
}
END_TEST

static Suite *make_suite(void)
{
  Suite *s = suite_create("adapt");
  TCase *tc;

  tc = tcase_create("config");
  tcase_add_loop_test(tc, test_cfg_table, 0, N_CFG_CASES);
  tcase_add_test(tc, test_null);
  suite_add_tcase(s, tc);

  tc = tcase_create("scenario");
  tcase_add_loop_test(tc, test_setpoint_step, 0, N_SCEN_CASES);
  suite_add_tcase(s, tc);

  tc = tcase_create("response");
  tcase_add_loop_test(tc, test_step_closed_form, 0, 4);
  tcase_add_loop_test(tc, test_ramp_settles, 0, 3);
  tcase_add_test(tc, test_gain_zero_and_cap);
  suite_add_tcase(s, tc);

  tc = tcase_create("extremes");
  tcase_add_loop_test(tc, test_exceeds_boundaries, 0, N_EX_CASES);
  tcase_add_loop_test(tc, test_extreme_inputs, 0, 4);
  suite_add_tcase(s, tc);
  return s;
}

CANFDI_UNIT_MAIN(make_suite)
