/*
 * test_excite.c — unit tests of canfdi_excite (PRBS and sine excitation).
 *
 * What is proven: the LFSR is maximum-length (every non-zero 15-bit state
 * once per 32767 bits, 16384 ones), bits last exactly the configured number
 * of steps, enabling and disabling act only at bit edges / upward zero
 * crossings, the sine table interpolation is within 4 LSB (Q15) of libm,
 * and the PRBS spectrum follows the documented envelope sinc^2(pi f Tb)
 * (-3 dB at 0.443 / Tb, a null at 1 / Tb), computed from one full period by
 * DFT (for an m-sequence every non-zero line has the same power before the
 * hold, so the band averages below follow the envelope to within a few %).
 */
#include <check.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "ctrl/canfdi_excite.h"
#include "unit_main.h"

#define ONE 65536
#define TWO_PI 6.283185307179586

static canfdi_excite_cfg_t prbs_cfg(uint32_t bit_us)
{
  canfdi_excite_cfg_t c;
  memset(&c, 0, sizeof c);
  c.prbs_amp_q16 = 5 * ONE;
  c.prbs_bit_us = bit_us;
  c.prbs_seed = 0x1234U;
  return c;
}

START_TEST(test_cfg)
{
  canfdi_excite_t e;
  canfdi_excite_cfg_t c = prbs_cfg(20000U);
  ck_assert_int_eq(canfdi_excite_init(&e, &c), CANFDI_OK);
  ck_assert_int_eq(canfdi_excite_init(NULL, &c), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_excite_init(&e, NULL), -CANFDI_EINVAL);
  c.prbs_amp_q16 = -1;
  ck_assert_int_eq(canfdi_excite_init(&e, &c), -CANFDI_EINVAL);
  c = prbs_cfg(400U); /* below half a step */
  ck_assert_int_eq(canfdi_excite_init(&e, &c), -CANFDI_EINVAL);
  c = prbs_cfg(0U);
  c.prbs_amp_q16 = 0; /* no PRBS: the period does not matter */
  ck_assert_int_eq(canfdi_excite_init(&e, &c), CANFDI_OK);
  c.sine_amp_q16 = ONE;
  c.sine_period_us = 1999U; /* below 2 steps */
  ck_assert_int_eq(canfdi_excite_init(&e, &c), -CANFDI_EINVAL);
  c.sine_amp_q16 = -1;
  c.sine_period_us = 50000U;
  ck_assert_int_eq(canfdi_excite_init(&e, &c), -CANFDI_EINVAL);
  /* Disabled by default: output 0, nothing active. */
  c = prbs_cfg(20000U);
  ck_assert_int_eq(canfdi_excite_init(&e, &c), CANFDI_OK);
  for (int k = 0; k < 100; k++) {
    ck_assert_int_eq(canfdi_excite_step_q16(&e), 0);
  }
  ck_assert(!canfdi_excite_active(&e));
  ck_assert_uint_eq(canfdi_excite_diag(&e)->steps, 100U);
  ck_assert_uint_eq(canfdi_excite_diag(&e)->prbs_bits, 5U);
  ck_assert_uint_eq(canfdi_excite_diag(&e)->active_steps, 0U);
}
END_TEST

/* One bit per step: the sign sequence visits every non-zero state. */
START_TEST(test_lfsr_maximum_length)
{
  static uint8_t seen[32768];
  canfdi_excite_t e;
  canfdi_excite_cfg_t c = prbs_cfg(1000U);
  uint32_t ones = 0U;
  int64_t sum = 0;
  c.prbs_seed = (uint16_t)(_i * 9973); /* 0 (-> 1) and other seeds */
  memset(seen, 0, sizeof seen);
  ck_assert_int_eq(canfdi_excite_init(&e, &c), CANFDI_OK);
  canfdi_excite_enable(&e, true);
  for (uint32_t k = 0U; k < 32767U; k++) {
    const int32_t y = canfdi_excite_step_q16(&e);
    ck_assert(y == 5 * ONE || y == -5 * ONE);
    ck_assert_uint_ge(e.lfsr, 1U);
    ck_assert_uint_le(e.lfsr, 0x7FFFU);
    ck_assert_uint_eq(seen[e.lfsr], 0U);
    seen[e.lfsr] = 1U;
    ones += (y > 0) ? 1U : 0U;
    sum += y;
  }
  /* An m-sequence of degree 15 has 2^14 ones and 2^14 - 1 zeros. */
  ck_assert_uint_eq(ones, 16384U);
  ck_assert_int_eq(sum, 5 * ONE);
  /* Period: the next 32767 outputs repeat the first. */
  ck_assert_uint_eq(canfdi_excite_diag(&e)->prbs_bits, 32767U);
}
END_TEST

START_TEST(test_bit_period_and_gating)
{
  canfdi_excite_t e;
  canfdi_excite_cfg_t c = prbs_cfg(20400U); /* rounds to 20 steps */
  int32_t prev = 0;
  ck_assert_int_eq(canfdi_excite_init(&e, &c), CANFDI_OK);
  for (int k = 0; k < 7; k++) {
    (void)canfdi_excite_step_q16(&e);
  }
  /* Enabled mid-bit: nothing until the edge at step 20. */
  canfdi_excite_enable(&e, true);
  for (int k = 7; k < 20; k++) {
    ck_assert_int_eq(canfdi_excite_step_q16(&e), 0);
  }
  for (int k = 20; k < 2000; k++) {
    const int32_t y = canfdi_excite_step_q16(&e);
    ck_assert(y == 5 * ONE || y == -5 * ONE);
    if ((k % 20) != 0) {
      ck_assert_int_eq(y, prev); /* changes only at edges */
    }
    prev = y;
    if (k == 1005) {
      canfdi_excite_enable(&e, false);
      ck_assert(canfdi_excite_active(&e)); /* the current bit completes */
    }
    if (k == 1019) {
      break;
    }
  }
  ck_assert_int_eq(canfdi_excite_step_q16(&e), 0); /* step 1020: an edge */
  ck_assert(!canfdi_excite_active(&e));
}
END_TEST

/* DFT power at line m of an N-sample sequence x (Goertzel-free, direct). */
static double line_power(const double *x, long n, long m)
{
  double re = 0.0;
  double im = 0.0;
  for (long k = 0; k < n; k++) {
    const double ph = TWO_PI * (double)(((long long)m * k) % n) / (double)n;
    re += x[k] * cos(ph);
    im -= x[k] * sin(ph);
  }
  return (re * re + im * im) / ((double)n * (double)n);
}

/* Mean power of the lines m0 - 8 .. m0 + 8 (excluding DC). */
static double band_power(const double *x, long n, long m0)
{
  double p = 0.0;
  int cnt = 0;
  for (long m = m0 - 8; m <= m0 + 8; m++) {
    if (m > 0) {
      p += line_power(x, n, m);
      cnt++;
    }
  }
  return p / cnt;
}

/* Power envelope of a bit held for spb samples at x = f Tb. */
static double hold_env(double x, long spb)
{
  const double h = sin(3.141592653589793 * x) / ((double)spb * sin(3.141592653589793 * x / (double)spb));
  return h * h;
}

START_TEST(test_prbs_spectrum)
{
  /* Tb = 4 steps, one full period N = 4 * 32767 samples; line spacing
   * 1 / (N T). Frequencies as fractions of 1/Tb: line m = f Tb * 32767. */
  const long bits = 32767;
  const long spb = 4;
  const long n = bits * spb;
  double *x = malloc((size_t)n * sizeof *x);
  canfdi_excite_t e;
  canfdi_excite_cfg_t c = prbs_cfg(4000U);
  double p_low;
  double p_3db;
  double p_half;
  double p_null;
  ck_assert_ptr_nonnull(x);
  ck_assert_int_eq(canfdi_excite_init(&e, &c), CANFDI_OK);
  canfdi_excite_enable(&e, true);
  for (long k = 0; k < n; k++) {
    x[k] = (double)canfdi_excite_step_q16(&e) / (5.0 * ONE);
  }
  p_low = band_power(x, n, (long)(0.02 * (double)bits));
  p_3db = band_power(x, n, (long)(0.443 * (double)bits));
  p_half = band_power(x, n, (long)(0.26 * (double)bits));
  p_null = band_power(x, n, bits); /* f = 1 / Tb */
  free(x);
  /* The sampled PRBS is the bit sequence held for spb samples, so its
   * envelope is the discrete hold response (sin(pi x) / (spb sin(pi x /
   * spb)))^2 with x = f Tb, which tends to the documented sinc^2(pi x) as
   * the bits get long against the step (0.520 vs 0.501 at x = 0.443 for
   * spb = 4). Band averages of +-8 lines: 2 % tolerance. */
  ck_assert_msg(fabs(p_3db / p_low - hold_env(0.443, spb) / hold_env(0.02, spb)) < 0.02,
                "-3 dB point: %.3f", p_3db / p_low);
  ck_assert_msg(fabs(p_half / p_low - hold_env(0.26, spb) / hold_env(0.02, spb)) < 0.02,
                "-1 dB point: %.3f", p_half / p_low);
  ck_assert_msg(p_null / p_low < 1e-3, "null: %.2e", p_null / p_low);
  /* And the continuous envelope the header documents. */
  ck_assert(fabs(hold_env(0.443, 1000) - 0.501) < 0.002);
}
END_TEST

START_TEST(test_sine_table)
{
  int32_t worst = 0;
  for (uint32_t i = 0U; i < 200000U; i++) {
    const uint32_t ph = i * 21475U + (i >> 3) * 977U; /* covers the circle */
    const double ref = 32767.0 * sin(TWO_PI * (double)ph / 4294967296.0);
    const int32_t got = canfdi_excite_sin_q15(ph);
    const int32_t err = (int32_t)lround(fabs((double)got - ref));
    worst = (err > worst) ? err : worst;
    ck_assert_int_le(got, 32767);
    ck_assert_int_ge(got, -32767);
  }
  ck_assert_int_le(worst, 4);
  /* Exact at the quadrant points. */
  ck_assert_int_eq(canfdi_excite_sin_q15(0U), 0);
  ck_assert_int_eq(canfdi_excite_sin_q15(0x40000000U), 32767);
  ck_assert_int_eq(canfdi_excite_sin_q15(0x80000000U), 0);
  ck_assert_int_eq(canfdi_excite_sin_q15(0xC0000000U), -32767);
}
END_TEST

START_TEST(test_sine_output_and_gating)
{
  canfdi_excite_t e;
  canfdi_excite_cfg_t c;
  memset(&c, 0, sizeof c);
  c.sine_amp_q16 = 2 * ONE;
  c.sine_period_us = 50000U; /* 50 steps */
  ck_assert_int_eq(canfdi_excite_init(&e, &c), CANFDI_OK);
  for (int k = 0; k < 10; k++) {
    (void)canfdi_excite_step_q16(&e);
  }
  /* Enabled while the sine is off, mid-period of the free-running phase:
   * the sine starts at its zero crossing in that step (step 10). */
  canfdi_excite_enable(&e, true);
  for (int k = 10; k < 210; k++) {
    const double ref = 2.0 * sin(TWO_PI * (double)(k - 10) / 50.0);
    const double got = (double)canfdi_excite_step_q16(&e) / ONE;
    /* 4 LSB of Q15 on the amplitude, the phase drift of round(2^32/50)
     * over 4 periods (< 1e-8 rad), the output rounding. */
    ck_assert_msg(fabs(got - ref) < 2.0 * 4.0 / 32767.0 + 1e-4, "k %d: %f vs %f", k, got, ref);
    if (k == 130) {
      canfdi_excite_enable(&e, false); /* finishes the period (to 160) */
    }
    if (k == 135) {
      /* on again while the period runs: no restart, the period goes on */
      canfdi_excite_enable(&e, true);
    }
    if (k == 140) {
      canfdi_excite_enable(&e, false);
    }
    if (k == 159) {
      break;
    }
  }
  ck_assert_int_eq(canfdi_excite_step_q16(&e), 0);
  ck_assert(!canfdi_excite_active(&e));
  for (int k = 161; k < 173; k++) {
    ck_assert_int_eq(canfdi_excite_step_q16(&e), 0);
  }
  /* from rest again: phase 0 in the step of the enable, then rising */
  canfdi_excite_enable(&e, true);
  ck_assert_int_eq(canfdi_excite_step_q16(&e), 0);
  ck_assert(canfdi_excite_active(&e));
  ck_assert_int_gt(canfdi_excite_step_q16(&e), 0);
}
END_TEST

START_TEST(test_sum_saturates)
{
  canfdi_excite_t e;
  canfdi_excite_cfg_t c = prbs_cfg(1000U);
  c.prbs_amp_q16 = INT32_MAX;
  c.sine_amp_q16 = INT32_MAX;
  c.sine_period_us = 4000U;
  ck_assert_int_eq(canfdi_excite_init(&e, &c), CANFDI_OK);
  canfdi_excite_enable(&e, true);
  for (int k = 0; k < 1000; k++) {
    const int32_t y = canfdi_excite_step_q16(&e);
    (void)y; /* any value is in range by type; the sanitizers check the sum */
  }
  ck_assert_uint_eq(canfdi_excite_diag(&e)->active_steps, 1000U);
}
END_TEST

/* Diagnostics counters saturate at UINT32_MAX; bit_count (state) stays in
 * 0 .. bit_steps - 1 and the output does not depend on the counters. */
START_TEST(test_counters_saturate)
{
  canfdi_excite_t e;
  canfdi_excite_t ref;
  const canfdi_excite_cfg_t c = prbs_cfg(3000U);
  ck_assert_int_eq(canfdi_excite_init(&e, &c), CANFDI_OK);
  ck_assert_int_eq(canfdi_excite_init(&ref, &c), CANFDI_OK);
  canfdi_excite_enable(&e, true);
  canfdi_excite_enable(&ref, true);
  e.diag.steps = UINT32_MAX - 1U;
  e.diag.prbs_bits = UINT32_MAX - 1U;
  e.diag.active_steps = UINT32_MAX;
  for (int k = 0; k < 10; k++) {
    ck_assert_int_eq(canfdi_excite_step_q16(&e), canfdi_excite_step_q16(&ref));
    ck_assert_uint_lt(e.bit_count, e.bit_steps);
  }
  ck_assert_uint_eq(canfdi_excite_diag(&e)->steps, UINT32_MAX);
  ck_assert_uint_eq(canfdi_excite_diag(&e)->prbs_bits, UINT32_MAX);
  ck_assert_uint_eq(canfdi_excite_diag(&e)->active_steps, UINT32_MAX);
  ck_assert_uint_eq(canfdi_excite_diag(&ref)->prbs_bits, 4U); /* 10 steps of 3 */
}
END_TEST

static Suite *make_suite(void)
{
  Suite *s = suite_create("excite");
  TCase *tc;

  tc = tcase_create("config");
  tcase_add_test(tc, test_cfg);
  suite_add_tcase(s, tc);

  tc = tcase_create("prbs");
  tcase_set_timeout(tc, 120);
  tcase_add_loop_test(tc, test_lfsr_maximum_length, 0, 3);
  tcase_add_test(tc, test_bit_period_and_gating);
  tcase_add_test(tc, test_prbs_spectrum);
  suite_add_tcase(s, tc);

  tc = tcase_create("sine");
  tcase_add_test(tc, test_sine_table);
  tcase_add_test(tc, test_sine_output_and_gating);
  tcase_add_test(tc, test_sum_saturates);
  suite_add_tcase(s, tc);

  tc = tcase_create("counters");
  tcase_add_test(tc, test_counters_saturate);
  suite_add_tcase(s, tc);
  return s;
}

CANFDI_UNIT_MAIN(make_suite)
