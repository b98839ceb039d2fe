/*
 * test_svf.c — unit tests of canfdi_svf (state-variable filter).
 *
 * What is proven, against analytic results of the documented discretisation
 * (trapezoidal rule on the binomial integrator chain):
 *   - configuration domain (table of valid and invalid cfgs);
 *   - DC: a constant input gives y = u exactly and zero derivatives;
 *   - ramp: dy converges to the slope, y to u - n a / wc (continuous lag),
 *     d2y to 0;
 *   - sine: amplitude ratio and phase of y, dy and d2y equal the continuous
 *     responses G(j wa), jwa G(j wa), -wa^2 G(j wa) at the warped frequency
 *     wa = (2/T) tan(w T / 2);
 *   - the states are mutually consistent derivatives (trapezoid identity);
 *   - reset gives a steady state; outputs saturate (and count) instead of
 *     wrapping.
 * Tolerances are in output LSBs plus the state resolution scaled by wc^k
 * (the normalised states have 2^-32 resolution, so the k-th derivative is
 * resolved to wc^k 2^-32 units/s^k), each stated at its check.
 */
#include <check.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "model/canfdi_svf.h"
#include "unit_main.h"

#define CHECK(cond)                                         \
  do {                                                      \
    if (!(cond)) {                                          \
      ck_abort_msg("%s:%d: %s", __FILE__, __LINE__, #cond); \
    }                                                       \
  } while (0)

#define T_S ((double)CANFDI_CFG_STEP_US * 1e-6)
#define Q16 65536.0
#define PI_D 3.14159265358979323846

static int32_t to_q16(double x)
{
  return (int32_t)lround(x * Q16);
}

static double from_q16(int32_t x)
{
  return (double)x / Q16;
}

/* ---- configuration domain ---------------------------------------------- */

typedef struct {
  uint8_t order;
  int32_t wc;
  int32_t expect;
} cfg_case_t;

static const cfg_case_t cfg_cases[] = {
    {2U, 1, CANFDI_OK},     {3U, 1, CANFDI_OK},      {2U, 100, CANFDI_OK},
    {3U, 300, CANFDI_OK},   {3U, 2000, CANFDI_OK},   {2U, 2000, CANFDI_OK},
    {3U, 1999, CANFDI_OK},  {1U, 100, -CANFDI_EINVAL}, {4U, 100, -CANFDI_EINVAL},
    {0U, 100, -CANFDI_EINVAL}, {3U, 0, -CANFDI_EINVAL}, {3U, -5, -CANFDI_EINVAL},
    {3U, 2001, -CANFDI_EINVAL}, {2U, 40000, -CANFDI_EINVAL}, {2U, INT32_MAX, -CANFDI_EINVAL},
};

START_TEST(test_cfg_domain)
{
  const cfg_case_t *c = &cfg_cases[_i];
  canfdi_svf_t f;
  canfdi_svf_cfg_t cfg = {.order = c->order, .omega_c_rad_s = c->wc};
  ck_assert_int_eq(canfdi_svf_init(&f, &cfg), c->expect);
}
END_TEST

START_TEST(test_null_args)
{
  canfdi_svf_t f;
  canfdi_svf_cfg_t cfg = {.order = 3U, .omega_c_rad_s = 100};
  ck_assert_int_eq(canfdi_svf_init(NULL, &cfg), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_svf_init(&f, NULL), -CANFDI_EINVAL);
}
END_TEST

/* ---- steady state ------------------------------------------------------- */

typedef struct {
  uint8_t order;
  int32_t wc;
} fcfg_t;

static const fcfg_t fcfgs[] = {{2U, 20}, {2U, 100}, {2U, 800}, {3U, 20}, {3U, 100}, {3U, 300}, {3U, 2000}};
#define N_FCFG (sizeof fcfgs / sizeof fcfgs[0])

static void init_or_fail(canfdi_svf_t *f, uint8_t order, int32_t wc)
{
  canfdi_svf_cfg_t cfg = {.order = order, .omega_c_rad_s = wc};
  ck_assert_int_eq(canfdi_svf_init(f, &cfg), CANFDI_OK);
}

/* Steps until the binomial filter has settled to < 1e-12 of a unit step:
 * the slowest mode is e^-wc t times a polynomial of degree n-1. */
static long settle_steps(int32_t wc)
{
  return (long)(40.0 / ((double)wc * T_S)) + 10;
}

START_TEST(test_dc)
{
  const fcfg_t *c = &fcfgs[_i];
  const int32_t levels[] = {to_q16(12.5), to_q16(-33.3), to_q16(399.0), 1, -1, 0};
  canfdi_svf_t f;
  size_t li;
  init_or_fail(&f, c->order, c->wc);
  for (li = 0; li < sizeof levels / sizeof levels[0]; li++) {
    long k;
    const long n = settle_steps(c->wc);
    for (k = 0; k < n; k++) {
      canfdi_svf_step(&f, levels[li]);
    }
    /* DC gain is exactly 1 by construction; the rounding of the state
     * update leaves at most a few 2^-32 in the states: y within 1 LSB, dy
     * within 1 LSB + wc 2^-29, d2y within 1 LSB + wc^2 2^-29. */
    {
      const double wc = (double)c->wc;
      const double tol_y = 1.0 / Q16;
      const double tol_dy = 1.0 / Q16 + wc * ldexp(1.0, -29);
      const double tol_d2y = 1.0 / Q16 + wc * wc * ldexp(1.0, -29);
      CHECK(abs(canfdi_svf_y_q16(&f) - levels[li]) <= 1);
      CHECK(fabs(from_q16(canfdi_svf_dy_q16(&f))) <= tol_dy);
      CHECK(fabs(from_q16(canfdi_svf_d2y_q16(&f))) <= tol_d2y);
      (void)tol_y;
    }
  }
}
END_TEST

START_TEST(test_ramp)
{
  const fcfg_t *c = &fcfgs[_i];
  /* The increment is an integer number of LSBs per step so that the input
   * is an exact ramp (no quantisation noise). Slopes: +9.99 and -300 unit/s
   * (ramp rates of a speed and a current). */
  const int32_t inc_lsb[] = {655, -19661000 / 1000};
  size_t r;
  for (r = 0; r < 2; r++) {
    canfdi_svf_t f;
    const double a = (double)inc_lsb[r] / Q16 / T_S;
    const double wc = (double)c->wc;
    const long n = settle_steps(c->wc) * 2;
    int32_t u = 0;
    long k;
    init_or_fail(&f, c->order, c->wc);
    for (k = 0; k < n; k++) {
      u += inc_lsb[r];
      canfdi_svf_step(&f, u);
    }
    {
      const double y = from_q16(canfdi_svf_y_q16(&f));
      const double dy = from_q16(canfdi_svf_dy_q16(&f));
      const double d2y = from_q16(canfdi_svf_d2y_q16(&f));
      const double y_exp = from_q16(u) - (double)c->order * a / wc;
      /* dy: 1 output LSB + G's rounding (relative ~ 2^-31 / (wc T / 2) of
       * the slope, < 1e-6 even at wc = 20) + the state resolution. */
      const double tol_dy = 1.0 / Q16 + fabs(a) * 1e-6 + wc * ldexp(1.0, -29);
      const double tol_y = 2.0 / Q16 + fabs(a) / wc * 1e-6;
      const double tol_d2y = 1.0 / Q16 + wc * wc * ldexp(1.0, -28) + fabs(a) * wc * 1e-6;
      if (!(fabs(dy - a) <= tol_dy) || !(fabs(y - y_exp) <= tol_y) || !(fabs(d2y) <= tol_d2y)) {
        ck_abort_msg("order %u wc %d slope %g: y %.9g (exp %.9g) dy %.9g d2y %.9g", c->order, c->wc, a, y,
                     y_exp, dy, d2y);
      }
    }
  }
}
END_TEST

/* ---- sine: frequency response ------------------------------------------- */

typedef struct {
  uint8_t order;
  int32_t wc;
  double w; /* rad/s */
} sine_case_t;

static const sine_case_t sine_cases[] = {
    {2U, 100, 20.0}, {2U, 100, 100.0}, {2U, 100, 500.0}, {3U, 100, 30.0},
    {3U, 100, 100.0}, {3U, 100, 400.0}, {3U, 300, 300.0}, {3U, 1000, 1500.0},
};

/* Continuous binomial response (1 + s/wc)^-n at s = j wa. */
static void binom_resp(unsigned n, double wc, double wa, double *re, double *im)
{
  /* 1 + j x, x = wa / wc, raised to -n */
  const double x = wa / wc;
  const double mag = pow(1.0 + x * x, -0.5 * (double)n);
  const double ph = -(double)n * atan(x);
  *re = mag * cos(ph);
  *im = mag * sin(ph);
}

START_TEST(test_sine)
{
  const sine_case_t *c = &sine_cases[_i];
  const double wa = 2.0 / T_S * tan(c->w * T_S / 2.0);
  double A = 20.0;
  canfdi_svf_t f;
  /* Fit over whole periods after settling. */
  const long per = (long)lround(2.0 * PI_D / (c->w * T_S) * 50.0);
  const long n_settle = settle_steps(c->wc) * 2;
  double sy[3][2] = {{0}};
  double ss = 0.0;
  double cc = 0.0;
  double sc = 0.0;
  long k;
  init_or_fail(&f, c->order, c->wc);
  {
    /* amplitude such that d2y stays inside Q16.16 (max 20000 unit/s^2) */
    double re;
    double im;
    binom_resp(c->order, (double)c->wc, wa, &re, &im);
    A = fmin(A, 20000.0 / (wa * wa * hypot(re, im)));
  }
  for (k = 1; k <= n_settle + per; k++) {
    const double t = (double)k * T_S;
    canfdi_svf_step(&f, to_q16(A * sin(c->w * t)));
    if (k > n_settle) {
      const double s = sin(c->w * t);
      const double co = cos(c->w * t);
      const double out[3] = {from_q16(canfdi_svf_y_q16(&f)), from_q16(canfdi_svf_dy_q16(&f)),
                             from_q16(canfdi_svf_d2y_q16(&f))};
      int i;
      for (i = 0; i < 3; i++) {
        sy[i][0] += out[i] * s;
        sy[i][1] += out[i] * co;
      }
      ss += s * s;
      cc += co * co;
      sc += s * co;
    }
  }
  {
    double re;
    double im;
    int i;
    binom_resp(c->order, (double)c->wc, wa, &re, &im);
    for (i = 0; i < 3; i++) {
      /* expected complex gain: G, j wa G, -wa^2 G */
      double er = re;
      double ei = im;
      double mr;
      double mi;
      double eg;
      double mg;
      double dph;
      if (i == 1) {
        er = -wa * im;
        ei = wa * re;
      } else if (i == 2) {
        er = -wa * wa * re;
        ei = -wa * wa * im;
      }
      /* out = A (mr sin + mi cos) = A |H| sin(wt + ph): least squares on
       * the two regressors (normal equations, 2 x 2). */
      {
        const double det = ss * cc - sc * sc;
        mr = (cc * sy[i][0] - sc * sy[i][1]) / det / A;
        mi = (ss * sy[i][1] - sc * sy[i][0]) / det / A;
      }
      eg = hypot(er, ei);
      mg = hypot(mr, mi);
      dph = atan2(mi * er - mr * ei, mr * er + mi * ei);
      /* Tolerance: input quantisation (0.29 LSB rms white) and output
       * rounding (0.29 LSB rms) average out over 50 periods; allow 2 output
       * LSB plus the state resolution relative to the amplitude, and 1e-5
       * relative for the finite fit (the fit over whole periods is exact
       * for the periodic steady state up to the sampling of the period). */
      {
        const double wk = pow((double)c->wc, (double)i);
        const double tol_abs = (2.0 / Q16 + wk * ldexp(1.0, -29)) / A;
        const double tol = 2e-5 * eg + tol_abs;
        if (!(fabs(mg - eg) <= tol) || !(fabs(dph) <= 2e-5 + tol_abs / eg)) {
          ck_abort_msg("order %u wc %d w %g out %d: gain %.9g exp %.9g, phase err %.3g", c->order, c->wc,
                       c->w, i, mg, eg, dph);
        }
      }
    }
  }
}
END_TEST

/* ---- consistency, reset, saturation -------------------------------------- */

/* Noisy input: the trapezoid identity y(k+1) - y(k) = T/2 (dy(k) + dy(k+1))
 * holds for the states exactly; on the rounded outputs within ~1 LSB of y
 * plus T/2 * 2 LSB of dy. Same for dy and d2y when order is 3. */
START_TEST(test_trapezoid_identity)
{
  const fcfg_t *c = &fcfgs[_i];
  canfdi_svf_t f;
  uint32_t lcg = 12345U;
  int32_t y0;
  int32_t dy0;
  int32_t d2y0;
  long k;
  long checked = 0;
  init_or_fail(&f, c->order, c->wc);
  canfdi_svf_reset(&f, to_q16(5.0));
  y0 = canfdi_svf_y_q16(&f);
  dy0 = canfdi_svf_dy_q16(&f);
  d2y0 = canfdi_svf_d2y_q16(&f);
  for (k = 0; k < 5000; k++) {
    int32_t x;
    lcg = lcg * 1664525U + 1013904223U;
    /* noise +-2048 LSB, +-32 LSB at high wc where d2y ~ wc^2 noise clips */
    if (c->wc >= 1000) {
      x = to_q16(5.0 + 3.0 * sin((double)k * 0.01)) + (int32_t)(lcg >> 26) - 32;
    } else {
      x = to_q16(5.0 + 3.0 * sin((double)k * 0.01)) + (int32_t)(lcg >> 20) - 2048;
    }
    {
      const uint32_t sat0 = canfdi_svf_diag(&f)->out_saturations;
      canfdi_svf_step(&f, x);
      if (canfdi_svf_diag(&f)->out_saturations != sat0) {
        /* a clipped output breaks the identity by design; counted below */
        y0 = canfdi_svf_y_q16(&f);
        dy0 = canfdi_svf_dy_q16(&f);
        d2y0 = canfdi_svf_d2y_q16(&f);
        continue;
      }
    }
    checked++;
    {
      const double dyy = from_q16(canfdi_svf_y_q16(&f)) - from_q16(y0);
      const double tr = 0.5 * T_S * (from_q16(canfdi_svf_dy_q16(&f)) + from_q16(dy0));
      CHECK(fabs(dyy - tr) <= 1.0 / Q16 + T_S * 1.0 / Q16 + 1e-9);
      if (c->order == 3U) {
        const double ddy = from_q16(canfdi_svf_dy_q16(&f)) - from_q16(dy0);
        const double tr2 = 0.5 * T_S * (from_q16(canfdi_svf_d2y_q16(&f)) + from_q16(d2y0));
        CHECK(fabs(ddy - tr2) <= 1.0 / Q16 + T_S * 1.0 / Q16 + 1e-9);
      }
    }
    y0 = canfdi_svf_y_q16(&f);
    dy0 = canfdi_svf_dy_q16(&f);
    d2y0 = canfdi_svf_d2y_q16(&f);
  }
  /* (nearly) no step may be skipped */
  CHECK(checked >= 4990);
}
END_TEST

START_TEST(test_reset_steady)
{
  const fcfg_t *c = &fcfgs[_i];
  canfdi_svf_t f;
  const int32_t x0 = to_q16(-17.25);
  int k;
  init_or_fail(&f, c->order, c->wc);
  canfdi_svf_step(&f, to_q16(3.0));
  canfdi_svf_reset(&f, x0);
  ck_assert_uint_eq(canfdi_svf_diag(&f)->resets, 1U);
  for (k = 0; k < 100; k++) {
    canfdi_svf_step(&f, x0);
    CHECK(canfdi_svf_y_q16(&f) == x0);
    CHECK(canfdi_svf_dy_q16(&f) == 0);
    CHECK(canfdi_svf_d2y_q16(&f) == 0);
  }
  ck_assert_uint_eq(canfdi_svf_diag(&f)->steps, 101U);
}
END_TEST

START_TEST(test_saturation)
{
  /* A full-range step at wc = 2000, order 3: the first d2y is of order
   * wc^2 * 30000 >> 32767, so it must clip to INT32_MAX, not wrap, and the
   * counter must move; the filtered value must still settle exactly. */
  canfdi_svf_t f;
  int k;
  init_or_fail(&f, 3U, 2000);
  canfdi_svf_reset(&f, to_q16(-30000.0));
  canfdi_svf_step(&f, to_q16(30000.0));
  ck_assert_int_eq(canfdi_svf_d2y_q16(&f), INT32_MAX);
  ck_assert_uint_gt(canfdi_svf_diag(&f)->out_saturations, 0U);
  for (k = 0; k < 200; k++) {
    canfdi_svf_step(&f, to_q16(30000.0));
    CHECK(canfdi_svf_y_q16(&f) <= to_q16(30000.0) + 1);
  }
  CHECK(abs(canfdi_svf_y_q16(&f) - to_q16(30000.0)) <= 1);
}
END_TEST

/* The step response of the binomial filter has no overshoot: y rises
 * monotonically and dy keeps its sign (why the binomial form was chosen). */
START_TEST(test_step_monotone)
{
  const fcfg_t *c = &fcfgs[_i];
  canfdi_svf_t f;
  int32_t prev = 0;
  long k;
  init_or_fail(&f, c->order, c->wc);
  for (k = 0; k < settle_steps(c->wc); k++) {
    canfdi_svf_step(&f, to_q16(10.0));
    CHECK(canfdi_svf_y_q16(&f) >= prev);
    CHECK(canfdi_svf_y_q16(&f) <= to_q16(10.0));
    CHECK(canfdi_svf_dy_q16(&f) >= -1);
    prev = canfdi_svf_y_q16(&f);
  }
}
END_TEST

/* The diagnostics counters saturate at UINT32_MAX instead of wrapping. */
START_TEST(test_counters_saturate)
{
  canfdi_svf_t f;
  init_or_fail(&f, 3U, 2000);
  f.diag.steps = UINT32_MAX - 1U;
  f.diag.resets = UINT32_MAX;
  f.diag.out_saturations = UINT32_MAX - 1U;
  canfdi_svf_reset(&f, to_q16(-30000.0));
  canfdi_svf_step(&f, to_q16(30000.0));
  ck_assert_int_eq(canfdi_svf_d2y_q16(&f), INT32_MAX); /* clipped: counted */
  canfdi_svf_step(&f, to_q16(30000.0));
  ck_assert_uint_eq(canfdi_svf_diag(&f)->steps, UINT32_MAX);
  ck_assert_uint_eq(canfdi_svf_diag(&f)->resets, UINT32_MAX);
  ck_assert_uint_eq(canfdi_svf_diag(&f)->out_saturations, UINT32_MAX);
}
END_TEST

/* A filter that computes a subset of the outputs computes them exactly as
 * one that computes all three, and leaves the others at their reset
 * value; an unknown output bit is refused. */
START_TEST(test_output_subset)
{
  const fcfg_t *c = &fcfgs[_i];
  unsigned mask;
  for (mask = 1U; mask <= CANFDI_SVF_OUT_ALL; mask++) {
    canfdi_svf_t all;
    canfdi_svf_t sub;
    canfdi_svf_cfg_t cfg = {.order = c->order, .omega_c_rad_s = c->wc, .outputs = (uint8_t)mask};
    int k;
    init_or_fail(&all, c->order, c->wc);
    ck_assert_int_eq(canfdi_svf_init(&sub, &cfg), CANFDI_OK);
    canfdi_svf_reset(&all, 1000);
    canfdi_svf_reset(&sub, 1000);
    for (k = 0; k < 3000; k++) {
      const int32_t x = ((k / 500) % 2 == 0) ? (k * 37) : -(k * 53);
      canfdi_svf_step(&all, x);
      canfdi_svf_step(&sub, x);
      ck_assert_int_eq(sub.y_q16, ((mask & CANFDI_SVF_OUT_Y) != 0U) ? all.y_q16 : 1000);
      ck_assert_int_eq(sub.dy_q16, ((mask & CANFDI_SVF_OUT_DY) != 0U) ? all.dy_q16 : 0);
      ck_assert_int_eq(sub.d2y_q16, ((mask & CANFDI_SVF_OUT_D2Y) != 0U) ? all.d2y_q16 : 0);
      ck_assert_mem_eq(sub.v_q32, all.v_q32, sizeof sub.v_q32);
    }
  }
  {
    canfdi_svf_t f;
    canfdi_svf_cfg_t bad = {.order = c->order, .omega_c_rad_s = c->wc, .outputs = 0x08U};
    ck_assert_int_eq(canfdi_svf_init(&f, &bad), -CANFDI_EINVAL);
  }
}
END_TEST

static Suite *make_suite(void)
{
  Suite *s = suite_create("svf");
  TCase *tc;

  tc = tcase_create("config");
  tcase_add_loop_test(tc, test_output_subset, 0, (int)N_FCFG);
  tcase_add_loop_test(tc, test_cfg_domain, 0, (int)(sizeof cfg_cases / sizeof cfg_cases[0]));
  tcase_add_test(tc, test_null_args);
  suite_add_tcase(s, tc);

  tc = tcase_create("analytic");
  tcase_add_loop_test(tc, test_dc, 0, (int)N_FCFG);
  tcase_add_loop_test(tc, test_ramp, 0, (int)N_FCFG);
  tcase_add_loop_test(tc, test_sine, 0, (int)(sizeof sine_cases / sizeof sine_cases[0]));
  tcase_add_loop_test(tc, test_step_monotone, 0, (int)N_FCFG);
  suite_add_tcase(s, tc);

  tc = tcase_create("consistency");
  tcase_add_loop_test(tc, test_trapezoid_identity, 0, (int)N_FCFG);
  tcase_add_loop_test(tc, test_reset_steady, 0, (int)N_FCFG);
  tcase_add_test(tc, test_saturation);
  tcase_add_test(tc, test_counters_saturate);
  suite_add_tcase(s, tc);
  return s;
}

CANFDI_UNIT_MAIN(make_suite)
