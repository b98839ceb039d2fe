/*
 * test_trend.c — unit tests of firmware/detect/canfdi_trend.
 *
 * References are the closed forms stated in canfdi_trend.h, evaluated in
 * double precision with the exact alpha = T / (tau + T) (not the Q31 one),
 * so the tolerances below also cover the quantisation of alpha.
 *
 * Tolerances (output LSBs = units/s * 2^rate_frac_bits):
 *  - 1 LSB: output rounding (0.5) plus state rounding. y1 and y2 carry 16
 *    fraction bits; each rounding of alpha*e is <= 2^-17 units, contracted
 *    by (1 - alpha) each step, so y1 is off by <= 2^-17 / alpha and d1 by
 *    <= 2 * 2^-17 * 10^6/T = 0.016 units/s; the Q31 alpha has a relative
 *    error <= 2^-31 (tau + T) / T, below 1e-6 of the peak for tau <= 1 s.
 *  - Ramps of a slope that is not a whole number of units per step are
 *    staircases: the ripple bound q * alpha / T (q = 1 unit) is added.
 */
#include <check.h>
#include <limits.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>

#include "detect/canfdi_trend.h"
#include "unit_main.h"

#define T_S ((double)CANFDI_CFG_STEP_US * 1e-6)
#define STEPS_PER_S ((int64_t)(1000000U / CANFDI_CFG_STEP_US))

static canfdi_trend_cfg_t make_cfg(uint8_t order, uint32_t tau_us, uint8_t frac)
{
  canfdi_trend_cfg_t c = {0};
  c.order = order;
  c.tau_us = tau_us;
  c.rate_frac_bits = frac;
  /* limits that never trigger unless a test sets its own */
  c.rate_limit.max_enabled = true;
  c.rate_limit.min_enabled = true;
  c.rate_limit.max_set = INT32_MAX;
  c.rate_limit.max_clear = INT32_MAX;
  c.rate_limit.min_set = INT32_MIN;
  c.rate_limit.min_clear = INT32_MIN;
  c.rate_limit.deb.failed_threshold = 1;
  c.rate_limit.deb.passed_threshold = -1;
  c.rate_limit.deb.prefailed_step = 1U;
  c.rate_limit.deb.prepassed_step = 1U;
  return c;
}

static double alpha_of(uint32_t tau_us)
{
  return (double)CANFDI_CFG_STEP_US / ((double)tau_us + (double)CANFDI_CFG_STEP_US);
}

/* floor(a / b) for b > 0 */
static int64_t floor_div(int64_t a, int64_t b)
{
  int64_t q = a / b;
  if ((a % b != 0) && (a < 0)) {
    q -= 1;
  }
  return q;
}

/* ---------------------------------------------------------------- config */

START_TEST(test_config)
{
  canfdi_trend_cfg_t c = make_cfg(1, 10000U, 0U);
  canfdi_trend_t t;
  ck_assert_int_eq(canfdi_trend_init(&t, &c), CANFDI_OK);
  c.tau_us = CANFDI_TREND_TAU_MAX_US;
  ck_assert_int_eq(canfdi_trend_init(&t, &c), CANFDI_OK);
  c.tau_us = 0U;
  ck_assert_int_eq(canfdi_trend_init(&t, &c), CANFDI_OK);
  c.tau_us = CANFDI_TREND_TAU_MAX_US + 1U;
  ck_assert_int_eq(canfdi_trend_init(&t, &c), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_trend_step(&t, 5), -CANFDI_EINVAL); /* unbound */
  c.tau_us = UINT32_MAX;
  ck_assert_int_eq(canfdi_trend_cfg_check(&c), -CANFDI_EINVAL);
  c = make_cfg(0, 10000U, 0U);
  ck_assert_int_eq(canfdi_trend_cfg_check(&c), -CANFDI_EINVAL);
  c = make_cfg(3, 10000U, 0U);
  ck_assert_int_eq(canfdi_trend_cfg_check(&c), -CANFDI_EINVAL);
  c = make_cfg(2, 10000U, 16U);
  ck_assert_int_eq(canfdi_trend_cfg_check(&c), CANFDI_OK);
  c = make_cfg(2, 10000U, 17U);
  ck_assert_int_eq(canfdi_trend_cfg_check(&c), -CANFDI_EINVAL);
  c = make_cfg(2, 10000U, 0U);
  c.rate_limit.max_clear = 5;
  c.rate_limit.max_set = 4; /* clear above set */
  ck_assert_int_eq(canfdi_trend_cfg_check(&c), -CANFDI_EINVAL);
  c = make_cfg(2, 10000U, 0U);
  c.rate_limit.deb.prefailed_step = 0U;
  ck_assert_int_eq(canfdi_trend_cfg_check(&c), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_trend_cfg_check(NULL), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_trend_init(NULL, &c), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_trend_init(&t, NULL), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_trend_step(NULL, 0), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_trend_rate(NULL), 0);
  ck_assert_int_eq(canfdi_trend_filtered(NULL), 0);
  ck_assert_int_eq(canfdi_trend_status(NULL), CANFDI_DEB_UNDECIDED);
  canfdi_trend_reset(NULL);
}
END_TEST

/* ------------------------------------------------------------------ ramps */

typedef struct {
  uint8_t order;
  uint32_t tau_us;
  uint8_t frac;
  int64_t slope; /* units/s */
  int32_t x0;
} ramp_case_t;

static const ramp_case_t ramp_cases[] = {
    {1, 10000U, 0U, 1000, 0},              /* exactly 1 unit per step */
    {1, 10000U, 0U, -250000, 1000},
    {2, 20000U, 0U, 123000, -5000},
    {1, 0U, 0U, 5000, 7},                  /* pure difference quotient */
    {1, 1000000U, 8U, 37, 0},              /* staircase, slow */
    {2, 10000000U, 8U, 1, 0},              /* 1 unit/s: 1 LSB per 1000 steps */
    {2, 10000000U, 12U, -3, 100},
    {2, 50000U, 0U, 10000000, INT32_MIN},  /* full-range ramp from the bottom */
    {1, 50000U, 0U, -10000000, INT32_MAX}, /* and from the top */
};
#define N_RAMP_CASES ((int)(sizeof ramp_cases / sizeof ramp_cases[0]))

/* After the priming sample x0, a ramp of slope s: the rate error must stay
 * inside transient(k) + ripple + 1 LSB at every sample, where transient is
 * the closed form of the header, s (1-a)^k (order 1) or
 * s (1 + k a) (1-a)^k (order 2), k = samples since priming. At the end the
 * transient is negligible, so this is the convergence to the slope; the
 * filtered signal must trail x by s * tau (the stated delay). */
START_TEST(test_ramp)
{
  const ramp_case_t *r = &ramp_cases[_i];
  const canfdi_trend_cfg_t c = make_cfg(r->order, r->tau_us, r->frac);
  canfdi_trend_t t;
  const double a = alpha_of(r->tau_us);
  const double scale = ldexp(1.0, r->frac);
  const double ripple = ((r->slope % STEPS_PER_S) != 0) ? a / T_S : 0.0;
  const double settle = (r->order == 1U) ? 12.0 : 20.0;
  const int64_t n = (int64_t)ceil(settle / a) + 200;
  double worst = 0.0;
  double final_err = 0.0;
  int64_t k;
  int64_t x = r->x0;
  ck_assert_int_eq(canfdi_trend_init(&t, &c), CANFDI_OK);
  ck_assert_int_eq(canfdi_trend_step(&t, r->x0), CANFDI_DEB_UNDECIDED);
  ck_assert_int_eq(canfdi_trend_rate(&t), 0);
  for (k = 1; k <= n; k++) {
    const double decay = pow(1.0 - a, (double)k);
    const double trans = fabs((double)r->slope) * decay * ((r->order == 1U) ? 1.0 : 1.0 + (double)k * a);
    const double tol = (trans + ripple) * scale + 1.0;
    double err;
    x = (int64_t)r->x0 + floor_div(r->slope * k, STEPS_PER_S);
    ck_assert(x >= INT32_MIN && x <= INT32_MAX); /* test precondition */
    ck_assert_int_ge(canfdi_trend_step(&t, (int32_t)x), 0);
    err = (double)canfdi_trend_rate(&t) - (double)r->slope * scale;
    if (fabs(err) > tol) {
      ck_abort_msg("ramp case %d, k %lld: rate %d, expected %.3f +- %.3f", _i, (long long)k,
                   canfdi_trend_rate(&t), (double)r->slope * scale, tol);
    }
    if ((trans * scale < 0.5) && (fabs(err) > worst)) {
      worst = fabs(err); /* largest error once the transient is gone */
    }
    final_err = err;
  }
  /* converged: the last sample is within ripple + 1 LSB of the slope */
  ck_assert(fabs(final_err) <= ripple * scale + 1.0);
  /* delay: y1 trails the (continuous) ramp by s * tau; 1 unit for the
   * staircase, 1 for rounding, plus the order-1 transient of y1 */
  {
    const double lag = (double)r->slope * (double)r->tau_us * 1e-6;
    const double expect = (double)x - lag;
    const double tol_y = 2.0 + fabs(lag) * pow(1.0 - a, (double)n);
    ck_assert_msg(fabs((double)canfdi_trend_filtered(&t) - expect) <= tol_y,
                  "filtered %d, expected %.2f", canfdi_trend_filtered(&t), expect);
  }
  ck_assert_uint_eq(t.diag.rate_saturations, 0U);
  ck_assert_int_eq(canfdi_trend_status(&t), CANFDI_DEB_PASSED);
  printf("trend ramp %d: order %u tau %u us slope %lld units/s: settled error <= %.2f LSB "
         "(bound %.2f, LSB = 2^-%u units/s)\n",
         _i, (unsigned)r->order, (unsigned)r->tau_us, (long long)r->slope, worst, ripple * scale + 1.0,
         (unsigned)r->frac);
}
END_TEST

/* ------------------------------------------------------------------ steps */

typedef struct {
  uint8_t order;
  uint32_t tau_us;
  int32_t h;
  int32_t x0;
} step_case_t;

static const step_case_t step_cases[] = {
    {1, 20000U, 1000000, 0},        {1, 20000U, -1000000, 5},  {2, 20000U, 1000000, -7},
    {2, 5000U, -300000, 0},         {2, 100000U, 2000000, 0},  {1, 0U, 1000000, 0},
    {1, 200000U, 20000000, -1000000000},
};
#define N_STEP_CASES ((int)(sizeof step_cases / sizeof step_cases[0]))

/* Whole step response against the closed forms of the header:
 * order 1: (a h / T) (1-a)^j, order 2: (a^2 h / T) (j+1) (1-a)^j,
 * j = 0 at the sample of the step; tolerance 1 LSB + 1e-6 of the peak. */
START_TEST(test_step_response)
{
  const step_case_t *s = &step_cases[_i];
  const canfdi_trend_cfg_t c = make_cfg(s->order, s->tau_us, 0U);
  canfdi_trend_t t;
  const double a = alpha_of(s->tau_us);
  const double peak = fabs((double)s->h) * a / T_S;
  /* long enough for the tail, (j+1)(1-a)^j a < 1e-4 for order 2 */
  const int32_t n = (int32_t)ceil(((s->order == 1U) ? 8.0 : 14.0) / a) + 20;
  int32_t j;
  int32_t max_abs = 0;
  int32_t j_max = -1;
  double ref_max = 0.0;
  int32_t j_ref_max = -1;
  ck_assert_int_eq(canfdi_trend_init(&t, &c), CANFDI_OK);
  ck_assert_int_ge(canfdi_trend_step(&t, s->x0), 0);
  for (j = 0; j < n; j++) {
    const double d = pow(1.0 - a, (double)j);
    const double ref = (s->order == 1U) ? (double)s->h * a / T_S * d
                                        : (double)s->h * a * a / T_S * (double)(j + 1) * d;
    int32_t got;
    ck_assert_int_ge(canfdi_trend_step(&t, s->x0 + s->h), 0);
    got = canfdi_trend_rate(&t);
    ck_assert_msg(fabs((double)got - ref) <= 1.0 + 1e-6 * peak, "step case %d, j %d: %d vs %.3f", _i,
                  j, got, ref);
    if (abs(got) > max_abs) {
      max_abs = abs(got);
      j_max = j;
    }
    if (fabs(ref) > ref_max + 1e-9 * peak) {
      ref_max = fabs(ref);
      j_ref_max = j;
    }
  }
  /* the peak is where the filter puts it (order 1: at the step) */
  ck_assert_int_eq(j_max, j_ref_max);
  if (s->order == 1U) {
    ck_assert_int_eq(j_max, 0);
  }
  /* and decays to (nearly) zero */
  ck_assert_int_le(abs(canfdi_trend_rate(&t)), 1 + (int32_t)(peak * 1e-3));
}
END_TEST

/* ------------------------------------------------------------------ noise */

static uint32_t lcg_state;
static int32_t noise_uniform(int32_t amp)
{
  lcg_state = lcg_state * 1664525U + 1013904223U;
  return (int32_t)((lcg_state >> 8) % (uint32_t)(2 * amp + 1)) - amp;
}

/* Constant + uniform noise in [-A, A]: with rate limits at the header's
 * hard bound 2 A a / T (+1 LSB rounding) no sample may ever be flagged,
 * for either order, even with the most sensitive debounce (1 report). The
 * noise must nevertheless drive order 1 to a sizeable fraction of the
 * bound (otherwise the test would prove nothing). The measured rate RMS
 * must match sigma * sqrt(sum g[k]^2) of the filter's impulse response g,
 * computed here in double (5 %: statistical error with 2e5 samples). */
START_TEST(test_noise_no_alarm)
{
  const uint8_t order = (uint8_t)(1 + _i % 2);
  const uint32_t tau_us = (_i < 2) ? 20000U : 5000U;
  const int32_t amp = (_i < 2) ? 1000 : 30000;
  const int32_t level = (_i < 2) ? 123456 : -2000000;
  const double a = alpha_of(tau_us);
  const double bound = 2.0 * amp * a / T_S;
  canfdi_trend_cfg_t c = make_cfg(order, tau_us, 0U);
  canfdi_trend_t t;
  const int n = 200000;
  int k;
  double sum2 = 0.0;
  int32_t max_abs = 0;
  double g2 = 0.0;
  c.rate_limit.max_set = (int32_t)ceil(bound) + 1;
  c.rate_limit.max_clear = c.rate_limit.max_set;
  c.rate_limit.min_set = -c.rate_limit.max_set;
  c.rate_limit.min_clear = c.rate_limit.min_set;
  lcg_state = 99U + (uint32_t)_i;
  ck_assert_int_eq(canfdi_trend_init(&t, &c), CANFDI_OK);
  for (k = 0; k < n; k++) {
    ck_assert_int_ne(canfdi_trend_step(&t, level + noise_uniform(amp)), CANFDI_DEB_FAILED);
    if (k > 1000) {
      const int32_t r = canfdi_trend_rate(&t);
      sum2 += (double)r * (double)r;
      max_abs = (abs(r) > max_abs) ? abs(r) : max_abs;
    }
  }
  ck_assert_uint_eq(t.limit.diag.steps_violated, 0U);
  ck_assert_int_le(max_abs, (int32_t)ceil(bound) + 1);
  if (order == 1U) {
    ck_assert(max_abs > 0.4 * bound);
  }
  /* impulse response of the double-precision filter */
  {
    double y1 = 0.0;
    double y2 = 0.0;
    int j;
    for (j = 0; j < (int)(40.0 / a); j++) {
      const double x = (j == 0) ? 1.0 : 0.0;
      const double d1 = a / T_S * (x - y1);
      y1 += a * (x - y1);
      y2 += a * (d1 - y2);
      g2 += (order == 1U) ? d1 * d1 : y2 * y2;
    }
  }
  {
    const double sigma = sqrt(((double)(2 * amp + 1) * (2 * amp + 1) - 1.0) / 12.0);
    const double rms = sqrt(sum2 / (double)(n - 1001));
    const double expect = sigma * sqrt(g2);
    printf("trend noise: order %u tau %u us A %d: rate rms %.1f (theory %.1f), max %d, bound %.0f\n",
           (unsigned)order, (unsigned)tau_us, (int)amp, rms, expect, (int)max_abs, bound);
    ck_assert(fabs(rms / expect - 1.0) < 0.05);
  }
}
END_TEST

/* ------------------------------------------------------- limit violations */

typedef struct {
  uint8_t order;
  uint32_t tau_us;
  int64_t slope;
  int32_t limit; /* |rate| limit, units/s */
  int16_t f;     /* failed threshold (steps) */
} viol_case_t;

static const viol_case_t viol_cases[] = {
    {1, 10000U, 10000, 5001, 20}, {1, 10000U, -10000, 5001, 20}, {2, 30000U, 200000, 150001, 5},
    {2, 30000U, -200000, 150001, 1},
};
#define N_VIOL_CASES ((int)(sizeof viol_cases / sizeof viol_cases[0]))

/* A ramp steeper than the limit: the rate (closed form) crosses the limit
 * at sample k_c; with jump-up to 0 and step 1 the check must qualify FAILED
 * exactly at k_c + F - 1, on the right side. The ramp then stops; the rate
 * decays (closed form again) and drops below the clear level at k_d; the
 * check passes exactly ceil((F - P) / 1) samples later. */
START_TEST(test_limit_violation)
{
  const viol_case_t *v = &viol_cases[_i];
  canfdi_trend_cfg_t c = make_cfg(v->order, v->tau_us, 0U);
  canfdi_trend_t t;
  const double a = alpha_of(v->tau_us);
  const int32_t clear = v->limit - v->limit / 5;
  const int32_t kmax = (int32_t)(30.0 / a);
  int32_t k_c = -1;
  int32_t k;
  int64_t x = 0;
  c.rate_limit.max_set = v->limit;
  c.rate_limit.max_clear = clear;
  c.rate_limit.min_set = -v->limit;
  c.rate_limit.min_clear = -clear;
  c.rate_limit.deb.failed_threshold = v->f;
  c.rate_limit.deb.passed_threshold = -10;
  c.rate_limit.deb.jump_up = true;
  c.rate_limit.deb.jump_up_value = 0;
  /* crossing of the closed-form rate, with a margin for the 1-LSB error */
  for (k = 1; k < kmax && k_c < 0; k++) {
    const double d = pow(1.0 - a, (double)k);
    const double ref = fabs((double)v->slope) * (1.0 - d * ((v->order == 1U) ? 1.0 : 1.0 + (double)k * a));
    if (ref > (double)v->limit) {
      k_c = k;
      ck_assert(ref > (double)v->limit + 2.0);
    } else {
      ck_assert(ref < (double)v->limit - 2.0);
    }
  }
  ck_assert_int_gt(k_c, 0);
  ck_assert_int_eq(canfdi_trend_init(&t, &c), CANFDI_OK);
  ck_assert_int_ge(canfdi_trend_step(&t, 0), 0);
  for (k = 1; k < k_c + v->f - 1; k++) {
    x = floor_div(v->slope * k, STEPS_PER_S);
    ck_assert_int_ne(canfdi_trend_step(&t, (int32_t)x), CANFDI_DEB_FAILED);
  }
  x = floor_div(v->slope * k, STEPS_PER_S);
  ck_assert_int_eq(canfdi_trend_step(&t, (int32_t)x), CANFDI_DEB_FAILED);
  ck_assert_int_eq(canfdi_limit_failed_side(&t.limit),
                   (v->slope > 0) ? CANFDI_LIMIT_ABOVE_MAX : CANFDI_LIMIT_BELOW_MIN);
  /* hold x: the rate decays from its current value; the check passes after
   * the rate has been inside the clear level for 10 + F samples (from F
   * down to P = -10 with step 1). */
  {
    int32_t in_band = 0;
    int32_t j;
    for (j = 0; j < kmax; j++) {
      const int32_t st = canfdi_trend_step(&t, (int32_t)x);
      const int32_t r = canfdi_trend_rate(&t);
      if ((r < clear) && (r > -clear)) {
        in_band++;
      } else {
        ck_assert_int_eq(in_band, 0); /* a decaying rate does not come back */
      }
      if (in_band < v->f + 10) {
        ck_assert_int_eq(st, CANFDI_DEB_FAILED);
      } else {
        ck_assert_int_eq(st, CANFDI_DEB_PASSED);
        break;
      }
    }
    ck_assert_int_eq(in_band, v->f + 10);
  }
}
END_TEST

/* ---------------------------------------------------------------- extremes */

/* Full-scale alternation with tau = 0: the rate saturates, every step is
 * counted, the sign is right and nothing is undefined (UBSan). */
START_TEST(test_extreme_inputs)
{
  const uint8_t order = (uint8_t)(1 + _i % 2);
  const uint8_t frac = (_i < 2) ? 0U : 16U;
  const uint32_t tau = (_i < 2) ? 0U : CANFDI_TREND_TAU_MAX_US;
  canfdi_trend_cfg_t c = make_cfg(order, tau, frac);
  canfdi_trend_t t;
  int k;
  ck_assert_int_eq(canfdi_trend_init(&t, &c), CANFDI_OK);
  ck_assert_int_ge(canfdi_trend_step(&t, INT32_MIN), 0);
  for (k = 1; k <= 1000; k++) {
    const int32_t x = (k % 2) ? INT32_MAX : INT32_MIN;
    ck_assert_int_ge(canfdi_trend_step(&t, x), 0);
    ck_assert_int_ge(canfdi_trend_filtered(&t), INT32_MIN);
    if (_i == 0) {
      /* order 1, tau 0: rate = +-(2^32 - 1) units per 1 ms, saturated */
      ck_assert_int_eq(canfdi_trend_rate(&t), (x > 0) ? INT32_MAX : INT32_MIN);
    }
  }
  if (_i == 0) {
    ck_assert_uint_eq(t.diag.rate_saturations, 1000U);
  }
  /* constant at the top: the rate returns to 0 and y1 to INT32_MAX */
  canfdi_trend_reset(&t);
  for (k = 0; k < 100; k++) {
    ck_assert_int_ge(canfdi_trend_step(&t, INT32_MAX), 0);
  }
  ck_assert_int_eq(canfdi_trend_rate(&t), 0);
  ck_assert_int_eq(canfdi_trend_filtered(&t), INT32_MAX);
}
END_TEST

START_TEST(test_reset_reprimes)
{
  canfdi_trend_cfg_t c = make_cfg(2, 10000U, 0U);
  canfdi_trend_t t;
  int k;
  c.rate_limit.max_set = 100;
  c.rate_limit.max_clear = 100;
  ck_assert_int_eq(canfdi_trend_init(&t, &c), CANFDI_OK);
  for (k = 0; k < 50; k++) {
    (void)canfdi_trend_step(&t, k * 1000);
  }
  ck_assert_int_eq(canfdi_trend_status(&t), CANFDI_DEB_FAILED);
  canfdi_trend_reset(&t);
  ck_assert_int_eq(canfdi_trend_status(&t), CANFDI_DEB_UNDECIDED);
  /* a jump across reset is not a rate: the first sample only primes */
  ck_assert_int_eq(canfdi_trend_step(&t, -1000000), CANFDI_DEB_UNDECIDED);
  ck_assert_int_eq(canfdi_trend_rate(&t), 0);
  ck_assert_int_eq(canfdi_trend_filtered(&t), -1000000);
  ck_assert_int_eq(canfdi_trend_step(&t, -1000000), CANFDI_DEB_PASSED);
}
END_TEST

static Suite *make_suite(void)
{
  Suite *s = suite_create("trend");
  TCase *tc;

  tc = tcase_create("config");
  tcase_add_test(tc, test_config);
  suite_add_tcase(s, tc);

  tc = tcase_create("filter");
  tcase_add_loop_test(tc, test_ramp, 0, N_RAMP_CASES);
  tcase_add_loop_test(tc, test_step_response, 0, N_STEP_CASES);
  tcase_add_loop_test(tc, test_noise_no_alarm, 0, 4);
  suite_add_tcase(s, tc);

  tc = tcase_create("limits");
  tcase_add_loop_test(tc, test_limit_violation, 0, N_VIOL_CASES);
  tcase_add_test(tc, test_reset_reprimes);
  suite_add_tcase(s, tc);

  tc = tcase_create("extremes");
  tcase_add_loop_test(tc, test_extreme_inputs, 0, 4);
  suite_add_tcase(s, tc);
  return s;
}

CANFDI_UNIT_MAIN(make_suite)
