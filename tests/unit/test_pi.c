/*
 * test_pi.c — unit tests of canfdi_pi (PI(D) with anti-windup and tracking).
 *
 * Exact behaviour is checked on hand-computed sequences: the gains are
 * chosen so that their fixed-point forms are exact (kp 0.5, ki T 0.125,
 * derivative pole 0.5), so every expected output below follows from the
 * header's arithmetic by hand, rounding included (half up: +0.5 LSB -> +1,
 * -0.5 LSB -> 0). A random comparison against a double-precision model of
 * the same law bounds the arithmetic error at 1 LSB of the Q16.16 output.
 */
#include <check.h>
#include <math.h>
#include <stdlib.h>

#include "ctrl/canfdi_pi.h"
#include "unit_main.h"

#define ONE 65536 /* 1.0 in Q16.16 */

/* A PI with kp 0.5, ki 125 /s (ki T = 0.125 exactly at T = 1 ms), limits
 * +-4, conditional integration, no band, no D. */
static canfdi_pi_cfg_t base_cfg(void)
{
  canfdi_pi_cfg_t c;
  c.kp_q16 = ONE / 2;
  c.ki_q16 = 125 * ONE;
  c.kd_q16 = 0;
  c.kd_tau_us = 0U;
  c.i_band_q16 = 0;
  c.out_min_q16 = -4 * ONE;
  c.out_max_q16 = 4 * ONE;
  c.anti_windup = CANFDI_PI_AW_CLAMP;
  return c;
}

static canfdi_pi_t make_pi(const canfdi_pi_cfg_t *c)
{
  canfdi_pi_t pi;
  ck_assert_int_eq(canfdi_pi_init(&pi, c), CANFDI_OK);
  return pi;
}

/* ---- configuration ---------------------------------------------------- */

static void bad_cfg(int i, canfdi_pi_cfg_t *c)
{
  switch (i) {
  case 0: c->out_min_q16 = c->out_max_q16 + 1; break;
  case 1: c->i_band_q16 = -1; break;
  case 2: c->kd_q16 = -1; break;
  case 3: c->anti_windup = 7U; break;
  case 4: c->kd_q16 = 33 * ONE; c->kd_tau_us = 0U; break; /* kd / T = 33000 */
  case 5: c->kd_tau_us = 0x80000000U; break;
  default: break;
  }
}
#define N_BAD_CFG 6

START_TEST(test_cfg_rejected)
{
  canfdi_pi_cfg_t c = base_cfg();
  canfdi_pi_t pi;
  bad_cfg(_i, &c);
  ck_assert_int_eq(canfdi_pi_init(&pi, &c), -CANFDI_EINVAL);
}
END_TEST

START_TEST(test_cfg_null_and_limits)
{
  canfdi_pi_cfg_t c = base_cfg();
  canfdi_pi_t pi = make_pi(&c);
  ck_assert_int_eq(canfdi_pi_init(NULL, &c), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_pi_init(&pi, NULL), -CANFDI_EINVAL);
  /* Extremes that fit: the largest ki (ki T = 32.8 at 1 ms) and
   * kd / (tau + T) just below 32768. */
  c.ki_q16 = INT32_MAX;
  c.kd_q16 = 32 * ONE;
  ck_assert_int_eq(canfdi_pi_init(&pi, &c), CANFDI_OK);
  /* Negative gains are allowed (negative plant gain). */
  c = base_cfg();
  c.kp_q16 = -ONE;
  c.ki_q16 = -10 * ONE;
  ck_assert_int_eq(canfdi_pi_init(&pi, &c), CANFDI_OK);
  ck_assert_int_eq(canfdi_pi_set_limits_q16(&pi, 2, 1), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_pi_set_limits_q16(&pi, 1, 1), CANFDI_OK);
}
END_TEST

/* ---- exact sequences ---------------------------------------------------- */

START_TEST(test_p_rounding)
{
  canfdi_pi_cfg_t c = base_cfg();
  canfdi_pi_t pi;
  c.ki_q16 = 0;
  pi = make_pi(&c);
  /* 0.5 x 1 LSB = 0.5 LSB -> 1 (half up); 0.5 x -1 LSB = -0.5 -> 0. */
  ck_assert_int_eq(canfdi_pi_step_q16(&pi, 1, 0, 0, 0U), 1);
  ck_assert_int_eq(canfdi_pi_step_q16(&pi, 0, 1, 0, 0U), 0);
  ck_assert_int_eq(canfdi_pi_step_q16(&pi, 3, 0, 0, 0U), 2);  /* 1.5 -> 2 */
  ck_assert_int_eq(canfdi_pi_step_q16(&pi, 0, 3, 0, 0U), -1); /* -1.5 -> -1 */
  /* Feed-forward adds before the limiter. */
  ck_assert_int_eq(canfdi_pi_step_q16(&pi, ONE, 0, ONE, 0U), ONE + ONE / 2);
  ck_assert_int_eq(canfdi_pi_step_q16(&pi, ONE, 0, 4 * ONE, 0U), 4 * ONE);
  ck_assert_int_eq(canfdi_pi_saturation(&pi), 1);
}
END_TEST

START_TEST(test_pi_sequence)
{
  canfdi_pi_cfg_t c = base_cfg();
  canfdi_pi_t pi = make_pi(&c);
  /* e = 1.0: u_k = 0.5 + 0.125 k (backward Euler: the first step already
   * integrates). */
  for (int k = 1; k <= 8; k++) {
    ck_assert_int_eq(canfdi_pi_step_q16(&pi, ONE, 0, 0, 0U), ONE / 2 + k * (ONE / 8));
  }
  ck_assert_int_eq(canfdi_pi_integral_q16(&pi), ONE);
}
END_TEST

START_TEST(test_pi_sub_lsb_integration)
{
  /* e = 3 LSB: P = 1.5 LSB, I grows 0.375 LSB per step; the integrator keeps
   * the fraction, so the output steps up although each increment is < 1 LSB:
   * 1.875 -> 2, 2.25 -> 2, 2.625 -> 3, 3.0 -> 3, 3.375 -> 3, 3.75 -> 4. */
  static const int32_t expect[6] = {2, 2, 3, 3, 3, 4};
  canfdi_pi_cfg_t c = base_cfg();
  canfdi_pi_t pi = make_pi(&c);
  for (int k = 0; k < 6; k++) {
    ck_assert_int_eq(canfdi_pi_step_q16(&pi, 3, 0, 0, 0U), expect[k]);
  }
}
END_TEST

START_TEST(test_derivative_sequence)
{
  /* kd_q16 131, tau = T = 1 ms: a = 0.5 exactly, c = kd / 2 ms = 131 * 500
   * = 65500 LSB per unit step. A measurement step of 1.0 at step 2 gives
   * D = -65500, then halves: -32750, -16375, -8187.5 -> -8187 (half up). A
   * setpoint step gives nothing (derivative on the measurement). */
  static const int32_t expect[6] = {0, -65500, -32750, -16375, -8187, -4094};
  canfdi_pi_cfg_t c = base_cfg();
  canfdi_pi_t pi;
  c.kp_q16 = 0;
  c.ki_q16 = 0;
  c.kd_q16 = 131;
  c.kd_tau_us = 1000U;
  pi = make_pi(&c);
  ck_assert_int_eq(canfdi_pi_step_q16(&pi, 0, 0, 0, 0U), expect[0]);
  for (int k = 1; k < 6; k++) {
    ck_assert_int_eq(canfdi_pi_step_q16(&pi, 5 * ONE, ONE, 0, 0U), expect[k]);
  }
  /* The first step after init takes no derivative even at a large value. */
  pi = make_pi(&c);
  ck_assert_int_eq(canfdi_pi_step_q16(&pi, 0, 3 * ONE, 0, 0U), 0);
}
END_TEST

/* ---- saturation and anti-windup --------------------------------------- */

START_TEST(test_limits_and_counters)
{
  canfdi_pi_cfg_t c = base_cfg();
  canfdi_pi_t pi;
  c.kp_q16 = 2 * ONE;
  c.ki_q16 = 0;
  c.out_min_q16 = -ONE;
  c.out_max_q16 = ONE;
  pi = make_pi(&c);
  ck_assert_int_eq(canfdi_pi_step_q16(&pi, ONE, 0, 0, 0U), ONE);
  ck_assert_int_eq(canfdi_pi_step_q16(&pi, -ONE, 0, 0, 0U), -ONE);
  ck_assert_int_eq(canfdi_pi_saturation(&pi), -1);
  ck_assert_int_eq(canfdi_pi_step_q16(&pi, ONE / 4, 0, 0, 0U), ONE / 2);
  ck_assert_int_eq(canfdi_pi_saturation(&pi), 0);
  ck_assert_uint_eq(canfdi_pi_diag(&pi)->sat_hi, 1U);
  ck_assert_uint_eq(canfdi_pi_diag(&pi)->sat_lo, 1U);
  ck_assert_uint_eq(canfdi_pi_diag(&pi)->steps, 3U);
  /* Limits changed at run time act at the next step. */
  ck_assert_int_eq(canfdi_pi_set_limits_q16(&pi, -ONE / 8, ONE / 8), CANFDI_OK);
  ck_assert_int_eq(canfdi_pi_step_q16(&pi, ONE / 4, 0, 0, 0U), ONE / 8);
}
END_TEST

/*
 * Pure integrator (kp 0, ki T 0.125), limits +-1, e = +1 for 20 steps, then
 * e = -1. CLAMP: I reaches exactly 1.0 at step 8 and stays (12 increments
 * rejected); the first negative error brings the output down at once
 * (0.875). NONE: I reaches 2.5 and the output stays at +1 for 12 more steps
 * (2.5 - 0.125 k > 1 for k < 12), the windup delay.
 */
START_TEST(test_conditional_integration)
{
  canfdi_pi_cfg_t c = base_cfg();
  canfdi_pi_t pa;
  canfdi_pi_t pn;
  int k;
  c.kp_q16 = 0;
  c.out_min_q16 = -ONE;
  c.out_max_q16 = ONE;
  pa = make_pi(&c);
  c.anti_windup = CANFDI_PI_AW_NONE;
  pn = make_pi(&c);
  for (k = 1; k <= 20; k++) {
    const int32_t expect = (k < 8) ? k * (ONE / 8) : ONE;
    ck_assert_int_eq(canfdi_pi_step_q16(&pa, ONE, 0, 0, 0U), expect);
    ck_assert_int_eq(canfdi_pi_step_q16(&pn, ONE, 0, 0, 0U), expect);
  }
  ck_assert_int_eq(canfdi_pi_integral_q16(&pa), ONE);
  ck_assert_int_eq(canfdi_pi_integral_q16(&pn), 20 * (ONE / 8));
  ck_assert_uint_eq(canfdi_pi_diag(&pa)->int_holds, 12U);
  ck_assert_uint_eq(canfdi_pi_diag(&pn)->int_holds, 0U);
  for (k = 1; k <= 14; k++) {
    const int32_t ua = canfdi_pi_step_q16(&pa, -ONE, 0, 0, 0U);
    const int32_t un = canfdi_pi_step_q16(&pn, -ONE, 0, 0, 0U);
    ck_assert_int_eq(ua, ONE - k * (ONE / 8));
    ck_assert_int_eq(un, (k <= 12) ? ONE : (20 - k) * (ONE / 8));
  }
}
END_TEST

START_TEST(test_integrator_limit_with_ff)
{
  /* CLAMP keeps I in [min - ff, max - ff]: with ff = 3 and max = 4, I stops
   * at 1 (ki T = 1 per step: the first increment reaches the limit exactly,
   * the following ones are rejected). */
  canfdi_pi_cfg_t c = base_cfg();
  canfdi_pi_t pi;
  c.kp_q16 = 0;
  c.ki_q16 = 1000 * ONE; /* ki T = 1 per step */
  pi = make_pi(&c);
  for (int k = 0; k < 5; k++) {
    (void)canfdi_pi_step_q16(&pi, ONE, 0, 3 * ONE, 0U);
  }
  ck_assert_int_eq(canfdi_pi_integral_q16(&pi), ONE);
  ck_assert_int_eq(canfdi_pi_out_q16(&pi), 4 * ONE);
  /* The limits shrink (supply sag): the next step bleeds I to the new
   * bound max - ff = 3.5 - 3 = 0.5 before forming the output. */
  ck_assert_int_eq(canfdi_pi_set_limits_q16(&pi, -ONE, 3 * ONE + ONE / 2), CANFDI_OK);
  ck_assert_int_eq(canfdi_pi_step_q16(&pi, 0, 0, 3 * ONE, 0U), 3 * ONE + ONE / 2);
  ck_assert_int_eq(canfdi_pi_integral_q16(&pi), ONE / 2);
}
END_TEST

/*
 * A feed-forward that saturates the output by itself (ff = 10 > max = 4,
 * e.g. a velocity feed-forward during a ramp) must not drag I negative: the
 * bound max - ff = -6 is replaced by 0: a positive I is bled to 0 (it would
 * push further into the limit), and when ff drops back the output is ff
 * alone, not ff - 6.
 * (Regression: with the bound max - ff, I went to -6 during a throttle ramp
 * and held the valve 2.5 deg short of its target.)
 */
START_TEST(test_integrator_limit_ff_saturating)
{
  canfdi_pi_cfg_t c = base_cfg();
  canfdi_pi_t pi;
  c.kp_q16 = 0;
  c.ki_q16 = 1000 * ONE; /* ki T = 1 per step */
  pi = make_pi(&c);
  (void)canfdi_pi_step_q16(&pi, ONE / 2, 0, 0, 0U); /* I = 0.5 */
  ck_assert_int_eq(canfdi_pi_integral_q16(&pi), ONE / 2);
  for (int k = 0; k < 5; k++) {
    ck_assert_int_eq(canfdi_pi_step_q16(&pi, 0, 0, 10 * ONE, 0U), 4 * ONE);
    ck_assert_int_eq(canfdi_pi_integral_q16(&pi), 0);
  }
  ck_assert_int_eq(canfdi_pi_step_q16(&pi, 0, 0, ONE, 0U), ONE);
  /* Symmetric below: ff = -10, min = -4. */
  for (int k = 0; k < 5; k++) {
    ck_assert_int_eq(canfdi_pi_step_q16(&pi, -ONE / 2, 0, -10 * ONE, 0U), -4 * ONE);
    ck_assert_int_eq(canfdi_pi_integral_q16(&pi), 0);
  }
}
END_TEST

START_TEST(test_hold)
{
  canfdi_pi_cfg_t c = base_cfg();
  canfdi_pi_t pi;
  c.kp_q16 = 0;
  pi = make_pi(&c);
  ck_assert_int_eq(canfdi_pi_step_q16(&pi, ONE, 0, 0, CANFDI_PI_HOLD_UP), 0);
  ck_assert_int_eq(canfdi_pi_step_q16(&pi, -ONE, 0, 0, CANFDI_PI_HOLD_UP), -ONE / 8);
  ck_assert_int_eq(canfdi_pi_step_q16(&pi, -ONE, 0, 0, CANFDI_PI_HOLD_DOWN), -ONE / 8);
  ck_assert_int_eq(canfdi_pi_step_q16(&pi, ONE, 0, 0, CANFDI_PI_HOLD_DOWN), 0);
  ck_assert_int_eq(
      canfdi_pi_step_q16(&pi, ONE, 0, 0, CANFDI_PI_HOLD_UP | CANFDI_PI_HOLD_DOWN), 0);
  ck_assert_uint_eq(canfdi_pi_diag(&pi)->int_holds, 3U);
}
END_TEST

START_TEST(test_band)
{
  canfdi_pi_cfg_t c = base_cfg();
  canfdi_pi_t pi;
  c.kp_q16 = 0;
  c.i_band_q16 = ONE;
  pi = make_pi(&c);
  ck_assert_int_eq(canfdi_pi_step_q16(&pi, ONE + 1, 0, 0, 0U), 0);      /* outside */
  ck_assert_int_eq(canfdi_pi_step_q16(&pi, ONE, 0, 0, 0U), ONE / 8);    /* |e| = band */
  ck_assert_int_eq(canfdi_pi_step_q16(&pi, -ONE - 1, 0, 0, 0U), ONE / 8);
  ck_assert_int_eq(canfdi_pi_step_q16(&pi, -ONE, 0, 0, 0U), 0);
}
END_TEST

/* ---- tracking and reset ------------------------------------------------ */

START_TEST(test_track_bumpless)
{
  canfdi_pi_cfg_t c = base_cfg();
  canfdi_pi_t pi = make_pi(&c);
  int32_t u;
  for (int k = 0; k < 5; k++) {
    (void)canfdi_pi_step_q16(&pi, ONE, 0, ONE / 4, 0U);
  }
  /* The manager froze the actuator at 0.3 (not the computed output). */
  canfdi_pi_track_q16(&pi, 19661);
  ck_assert_int_eq(canfdi_pi_out_q16(&pi), 19661);
  ck_assert_uint_eq(canfdi_pi_diag(&pi)->tracks, 1U);
  /* Same inputs: the next output continues from 0.3 by exactly one
   * integration increment (0.125), no jump back to the old output. */
  u = canfdi_pi_step_q16(&pi, ONE, 0, ONE / 4, 0U);
  ck_assert_int_eq(u, 19661 + ONE / 8);
  /* Tracking while the loop keeps running (several steps). */
  for (int k = 0; k < 10; k++) {
    (void)canfdi_pi_step_q16(&pi, ONE, 0, ONE / 4, 0U);
    canfdi_pi_track_q16(&pi, -ONE);
  }
  ck_assert_int_eq(canfdi_pi_step_q16(&pi, ONE, 0, ONE / 4, 0U), -ONE + ONE / 8);
}
END_TEST

START_TEST(test_reset)
{
  canfdi_pi_cfg_t c = base_cfg();
  canfdi_pi_t pi;
  c.kd_q16 = 131;
  c.kd_tau_us = 1000U;
  pi = make_pi(&c);
  for (int k = 0; k < 5; k++) {
    (void)canfdi_pi_step_q16(&pi, ONE, k * ONE, 0, 0U);
  }
  canfdi_pi_reset_q16(&pi, ONE + ONE / 2, 2 * ONE);
  ck_assert_int_eq(canfdi_pi_out_q16(&pi), ONE + ONE / 2);
  ck_assert_int_eq(canfdi_pi_integral_q16(&pi), ONE + ONE / 2);
  /* r = y0, ff = 0: output u0 exactly (no P, no derivative kick, no I). */
  ck_assert_int_eq(canfdi_pi_step_q16(&pi, 2 * ONE, 2 * ONE, 0, 0U), ONE + ONE / 2);
  ck_assert_uint_eq(canfdi_pi_diag(&pi)->resets, 1U);
}
END_TEST

/* ---- random comparison with a double model ---------------------------- */

static uint32_t rng = 12345U;
static uint32_t rnd(void)
{
  rng ^= rng << 13;
  rng ^= rng >> 17;
  rng ^= rng << 5;
  return rng;
}
static int32_t rnd_range(int32_t lo, int32_t hi)
{
  return lo + (int32_t)(rnd() % (uint32_t)(hi - lo + 1));
}

/*
 * The same law in double with the gains as init quantises them (ki T to
 * 2^-24, a to 2^-31, c to 2^-16), wide limits so the limiter is inactive.
 * The fixed-point output must be within 1 LSB: the only differences are the
 * final rounding (<= 0.5 LSB) and the 2^-32 rounding of each I and D update
 * (<= 2^-16 LSB per step, 500 steps).
 */
START_TEST(test_random_vs_double)
{
  for (int trial = 0; trial < 50; trial++) {
    canfdi_pi_cfg_t c = base_cfg();
    canfdi_pi_t pi;
    double i_d = 0.0;
    double d_d = 0.0;
    double y_prev = 0.0;
    double kit;
    double a;
    double cc;
    c.kp_q16 = rnd_range(-5 * ONE, 5 * ONE);
    c.ki_q16 = rnd_range(-200 * ONE, 200 * ONE);
    c.kd_q16 = rnd_range(0, ONE / 50);
    c.kd_tau_us = (uint32_t)rnd_range(0, 5000);
    c.out_min_q16 = INT32_MIN;
    c.out_max_q16 = INT32_MAX;
    pi = make_pi(&c);
    kit = round((double)c.ki_q16 * 1000.0 * 256.0 / 1e6) / 16777216.0;
    a = round((double)c.kd_tau_us * 2147483648.0 / ((double)c.kd_tau_us + 1000.0)) / 2147483648.0;
    cc = round((double)c.kd_q16 * 1e6 / ((double)c.kd_tau_us + 1000.0)) / 65536.0;
    for (int k = 0; k < 500; k++) {
      const int32_t r = rnd_range(-20 * ONE, 20 * ONE) / ((k % 7) + 1);
      const int32_t y = rnd_range(-20 * ONE, 20 * ONE) / ((k % 5) + 1);
      const int32_t ff = rnd_range(-ONE, ONE);
      const double e = ((double)r - (double)y) / ONE;
      double u_d;
      int32_t u;
      if (k > 0) {
        d_d = a * d_d - cc * ((double)y / ONE - y_prev);
      }
      y_prev = (double)y / ONE;
      i_d += kit * e;
      u_d = (double)ff / ONE + (double)c.kp_q16 / ONE * e + i_d + d_d;
      u = canfdi_pi_step_q16(&pi, r, y, ff, 0U);
      ck_assert_msg(fabs((double)u - u_d * ONE) <= 1.0, "trial %d step %d: %d vs %.3f", trial, k,
                    u, u_d * ONE);
    }
  }
}
END_TEST

/* Whatever the inputs, the output stays inside the limits and in CLAMP mode
 * the integrator inside [min(min - ff, 0), max(max - ff, 0)] (extreme
 * inputs, sanitizers on). */
START_TEST(test_random_extremes)
{
  static const int32_t pool[] = {INT32_MIN, INT32_MIN + 1, -ONE, -1, 0, 1, ONE, INT32_MAX - 1,
                                 INT32_MAX};
  const uint32_t n = (uint32_t)(sizeof pool / sizeof pool[0]);
  for (int trial = 0; trial < 40; trial++) {
    canfdi_pi_cfg_t c = base_cfg();
    canfdi_pi_t pi;
    c.kp_q16 = pool[rnd() % n];
    c.ki_q16 = rnd_range(-1000 * ONE, 1000 * ONE);
    c.kd_q16 = rnd_range(0, 30 * ONE);
    c.kd_tau_us = (uint32_t)rnd_range(0, 1000000);
    c.out_min_q16 = -rnd_range(0, 100 * ONE);
    c.out_max_q16 = rnd_range(0, 100 * ONE);
    c.anti_windup = (trial % 2 == 0) ? CANFDI_PI_AW_CLAMP : CANFDI_PI_AW_NONE;
    pi = make_pi(&c);
    for (int k = 0; k < 300; k++) {
      const int32_t ff = (k % 3 == 0) ? pool[rnd() % n] : rnd_range(-ONE, ONE);
      const int32_t u = canfdi_pi_step_q16(&pi, pool[rnd() % n], pool[rnd() % n], ff, rnd() % 4U);
      ck_assert_int_ge(u, c.out_min_q16);
      ck_assert_int_le(u, c.out_max_q16);
      if (c.anti_windup == CANFDI_PI_AW_CLAMP) {
        const int64_t i = canfdi_pi_integral_q16(&pi);
        const int64_t hi = (int64_t)c.out_max_q16 - ff;
        const int64_t lo = (int64_t)c.out_min_q16 - ff;
        ck_assert(i <= ((hi > 0) ? hi : 0) + 1);
        ck_assert(i >= ((lo < 0) ? lo : 0) - 1);
      }
      if (k % 50 == 49) {
        canfdi_pi_track_q16(&pi, pool[rnd() % n]);
      }
    }
  }
}
END_TEST

/* The diagnostics counters saturate at UINT32_MAX instead of wrapping, and
 * the control law does not depend on them. */
START_TEST(test_counters_saturate)
{
  const canfdi_pi_cfg_t c = base_cfg();
  canfdi_pi_t pi = make_pi(&c);
  canfdi_pi_t ref = make_pi(&c);
  const canfdi_pi_diag_t *d = canfdi_pi_diag(&pi);
  pi.diag.steps = UINT32_MAX - 1U;
  pi.diag.sat_hi = UINT32_MAX;
  pi.diag.int_holds = UINT32_MAX - 1U;
  pi.diag.tracks = UINT32_MAX;
  pi.diag.resets = UINT32_MAX;
  for (int k = 0; k < 3; k++) {
    /* e = 10: P alone saturates the output at +4, the increment is held */
    ck_assert_int_eq(canfdi_pi_step_q16(&pi, 10 * ONE, 0, 0, CANFDI_PI_HOLD_NONE),
                     canfdi_pi_step_q16(&ref, 10 * ONE, 0, 0, CANFDI_PI_HOLD_NONE));
  }
  ck_assert_uint_eq(d->steps, UINT32_MAX);
  ck_assert_uint_eq(d->sat_hi, UINT32_MAX);
  ck_assert_uint_eq(d->int_holds, UINT32_MAX);
  ck_assert_uint_eq(canfdi_pi_diag(&ref)->sat_hi, 3U);
  canfdi_pi_track_q16(&pi, ONE);
  canfdi_pi_reset_q16(&pi, 0, 0);
  ck_assert_uint_eq(d->tracks, UINT32_MAX);
  ck_assert_uint_eq(d->resets, UINT32_MAX);
}
END_TEST

static Suite *make_suite(void)
{
  Suite *s = suite_create("pi");
  TCase *tc;

  tc = tcase_create("config");
  tcase_add_loop_test(tc, test_cfg_rejected, 0, N_BAD_CFG);
  tcase_add_test(tc, test_cfg_null_and_limits);
  suite_add_tcase(s, tc);

  tc = tcase_create("exact");
  tcase_add_test(tc, test_p_rounding);
  tcase_add_test(tc, test_pi_sequence);
  tcase_add_test(tc, test_pi_sub_lsb_integration);
  tcase_add_test(tc, test_derivative_sequence);
  suite_add_tcase(s, tc);

  tc = tcase_create("saturation");
  tcase_add_test(tc, test_limits_and_counters);
  tcase_add_test(tc, test_conditional_integration);
  tcase_add_test(tc, test_integrator_limit_with_ff);
  tcase_add_test(tc, test_integrator_limit_ff_saturating);
  tcase_add_test(tc, test_hold);
  tcase_add_test(tc, test_band);
  suite_add_tcase(s, tc);

  tc = tcase_create("tracking");
  tcase_add_test(tc, test_track_bumpless);
  tcase_add_test(tc, test_reset);
  suite_add_tcase(s, tc);

  tc = tcase_create("random");
  tcase_add_test(tc, test_random_vs_double);
  tcase_add_test(tc, test_random_extremes);
  suite_add_tcase(s, tc);

  tc = tcase_create("counters");
  tcase_add_test(tc, test_counters_saturate);
  suite_add_tcase(s, tc);
  return s;
}

CANFDI_UNIT_MAIN(make_suite)
