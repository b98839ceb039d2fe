/*
 * test_tps.c — unit tests of firmware/model/canfdi_tps (the characteristic
 * of a throttle-position potentiometer).
 *
 * What is proven: the default pair is the datasheet line (0.5 V + 4 V per
 * 90 deg rising, 4.5 V - 4 V per 90 deg falling), checked in both
 * directions against a double-precision evaluation of that line over the
 * whole travel and beyond, with a sum of 5 V at every angle; the voltage ->
 * angle conversion is the documented fixed-point expression bit for bit;
 * both slopes convert and round-trip; the domain is enforced; extreme
 * inputs saturate instead of wrapping.
 */
#include <check.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "core/canfdi_fixp.h"
#include "model/canfdi_tps.h"
#include "unit_main.h"

#define ONE 65536
#define PI 3.14159265358979323846

static double q16d(int32_t x)
{
  return (double)x / 65536.0;
}

static int32_t q16(double x)
{
  return (int32_t)lround(x * 65536.0);
}

/* The datasheet line of the default pair, in double. */
static double v_line(int sensor, double theta)
{
  const double span = 4.0 * theta / (PI / 2.0);
  return (sensor == 1) ? 0.5 + span : 4.5 - span;
}

static double theta_line(int sensor, double v)
{
  return ((sensor == 1) ? (v - 0.5) : (4.5 - v)) * (PI / 2.0) / 4.0;
}

START_TEST(test_default_is_datasheet_line)
{
  canfdi_tps_cal_t c1;
  canfdi_tps_cal_t c2;
  canfdi_tps_cal_default(&c1, &c2);
  ck_assert_int_eq(c1.zero_V_q16, ONE / 2);
  ck_assert_int_eq(c2.zero_V_q16, 9 * ONE / 2);
  /* 8 / pi V/rad, exactly rounded, and exactly complementary */
  ck_assert_int_eq(c1.slope_V_rad_q16, q16(8.0 / PI));
  ck_assert_int_eq(c2.slope_V_rad_q16, -c1.slope_V_rad_q16);
  ck_assert_int_eq(canfdi_tps_cal_check(&c1), CANFDI_OK);
  ck_assert_int_eq(canfdi_tps_cal_check(&c2), CANFDI_OK);
  canfdi_tps_cal_default(NULL, &c2); /* NULL skipped */
  canfdi_tps_cal_default(&c1, NULL);
}
END_TEST

/* Voltage -> angle against the line over 0 .. 5 V (1 mV steps), both
 * sensors: within 1 LSB (the rounding of the result plus the < 1.2e-7 rad
 * of the Q8.24 reciprocal). */
START_TEST(test_voltage_to_angle)
{
  canfdi_tps_cal_t c[2];
  canfdi_tps_t t[2];
  int s;
  canfdi_tps_cal_default(&c[0], &c[1]);
  for (s = 0; s < 2; s++) {
    ck_assert_int_eq(canfdi_tps_init(&t[s], &c[s]), CANFDI_OK);
  }
  for (s = 0; s < 2; s++) {
    double worst = 0.0;
    for (int mv = 0; mv <= 5000; mv++) {
      const int32_t v = q16((double)mv / 1000.0);
      const int32_t th = canfdi_tps_V_to_rad_q16(&t[s], v);
      const double err = fabs(q16d(th) - theta_line(s + 1, q16d(v))) * 65536.0;
      worst = (err > worst) ? err : worst;
    }
    ck_assert_msg(worst <= 1.0, "TPS%d: worst %.3f LSB", s + 1, worst);
  }
  /* the datasheet points: 0, 45 and 90 deg */
  ck_assert_int_eq(canfdi_tps_V_to_rad_q16(&t[0], ONE / 2), 0);
  ck_assert_int_eq(canfdi_tps_V_to_rad_q16(&t[1], 9 * ONE / 2), 0);
  ck_assert_int_le(abs(canfdi_tps_V_to_rad_q16(&t[0], 5 * ONE / 2) - q16(PI / 4.0)), 1);
  ck_assert_int_le(abs(canfdi_tps_V_to_rad_q16(&t[1], 5 * ONE / 2) - q16(PI / 4.0)), 1);
  ck_assert_int_le(abs(canfdi_tps_V_to_rad_q16(&t[0], 9 * ONE / 2) - q16(PI / 2.0)), 1);
  ck_assert_int_le(abs(canfdi_tps_V_to_rad_q16(&t[1], ONE / 2) - q16(PI / 2.0)), 1);
  /* below the zero of a rising sensor: a negative angle */
  ck_assert_int_lt(canfdi_tps_V_to_rad_q16(&t[0], 0), 0);
  ck_assert_int_lt(canfdi_tps_V_to_rad_q16(&t[1], 5 * ONE), 0);
}
END_TEST

/* The documented arithmetic, bit for bit: (V - zero) or (zero - V) times
 * 1 / |slope| in Q8.24, rounded half up to Q16.16. */
START_TEST(test_voltage_to_angle_exact_expression)
{
  canfdi_tps_cal_t c[2];
  canfdi_tps_t t[2];
  canfdi_tps_cal_default(&c[0], &c[1]);
  ck_assert_int_eq(canfdi_tps_init(&t[0], &c[0]), CANFDI_OK);
  ck_assert_int_eq(canfdi_tps_init(&t[1], &c[1]), CANFDI_OK);
  const int32_t inv = canfdi_div_s32_qn(ONE, c[0].slope_V_rad_q16, 24U);
  ck_assert_int_eq(t[0].rad_per_V_q24, inv);
  ck_assert_int_eq(t[1].rad_per_V_q24, inv);
  for (int32_t v = -ONE; v <= 6 * ONE; v += 97) {
    ck_assert_int_eq(canfdi_tps_V_to_rad_q16(&t[0], v),
                     canfdi_mul_s32_qn(canfdi_sub_s32_sat(v, c[0].zero_V_q16), inv, 24U));
    ck_assert_int_eq(canfdi_tps_V_to_rad_q16(&t[1], v),
                     canfdi_mul_s32_qn(canfdi_sub_s32_sat(c[1].zero_V_q16, v), inv, 24U));
  }
}
END_TEST

/* Angle -> voltage against the line from -10 to 100 deg, both sensors,
 * the pair's sum, and the round trip. */
START_TEST(test_angle_to_voltage_and_round_trip)
{
  canfdi_tps_cal_t c[2];
  canfdi_tps_t t[2];
  canfdi_tps_cal_default(&c[0], &c[1]);
  ck_assert_int_eq(canfdi_tps_init(&t[0], &c[0]), CANFDI_OK);
  ck_assert_int_eq(canfdi_tps_init(&t[1], &c[1]), CANFDI_OK);
  for (int deci_deg = -100; deci_deg <= 1000; deci_deg++) {
    const int32_t th = q16((double)deci_deg / 10.0 * PI / 180.0);
    const int32_t v1 = canfdi_tps_rad_to_V_q16(&c[0], th);
    const int32_t v2 = canfdi_tps_rad_to_V_q16(&c[1], th);
    /* slope error of the Q16.16 slope (< 0.5 LSB/rad) times |theta| <= 2
     * rad, plus the rounding: within 2 LSB of the line */
    ck_assert_double_le(fabs(q16d(v1) - v_line(1, q16d(th))) * 65536.0, 2.0);
    ck_assert_double_le(fabs(q16d(v2) - v_line(2, q16d(th))) * 65536.0, 2.0);
    ck_assert_int_le(abs(v1 + v2 - 5 * ONE), 1);
    ck_assert_int_le(abs(canfdi_tps_V_to_rad_q16(&t[0], v1) - th), 1);
    ck_assert_int_le(abs(canfdi_tps_V_to_rad_q16(&t[1], v2) - th), 1);
  }
}
END_TEST

START_TEST(test_domain)
{
  canfdi_tps_cal_t c;
  canfdi_tps_t t;
  canfdi_tps_t keep;
  ck_assert_int_eq(canfdi_tps_cal_check(NULL), -CANFDI_EINVAL);
  canfdi_tps_cal_default(&c, NULL);
  ck_assert_int_eq(canfdi_tps_init(NULL, &c), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_tps_init(&t, NULL), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_tps_init(&t, &c), CANFDI_OK);
  keep = t;
  /* zero 0 .. 5 V */
  c.zero_V_q16 = -1;
  ck_assert_int_eq(canfdi_tps_cal_check(&c), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_tps_init(&t, &c), -CANFDI_EINVAL);
  ck_assert_mem_eq(&t, &keep, sizeof t); /* untouched on error */
  c.zero_V_q16 = 5 * ONE + 1;
  ck_assert_int_eq(canfdi_tps_cal_check(&c), -CANFDI_EINVAL);
  c.zero_V_q16 = 5 * ONE;
  ck_assert_int_eq(canfdi_tps_cal_check(&c), CANFDI_OK);
  c.zero_V_q16 = 0;
  ck_assert_int_eq(canfdi_tps_cal_check(&c), CANFDI_OK);
  /* 0.1 <= |slope| <= 10 V/rad, either sign */
  const int32_t lo = canfdi_div_s32_qn(ONE, 10, 0U); /* 0.1 V/rad */
  const int32_t slopes_ok[] = {lo, -lo, 10 * ONE, -10 * ONE, ONE};
  const int32_t slopes_bad[] = {0, lo - 1, -(lo - 1), 10 * ONE + 1, -10 * ONE - 1, INT32_MIN, INT32_MAX};
  for (size_t i = 0; i < sizeof slopes_ok / sizeof slopes_ok[0]; i++) {
    c.slope_V_rad_q16 = slopes_ok[i];
    ck_assert_int_eq(canfdi_tps_cal_check(&c), CANFDI_OK);
    ck_assert_int_eq(canfdi_tps_init(&t, &c), CANFDI_OK);
  }
  for (size_t i = 0; i < sizeof slopes_bad / sizeof slopes_bad[0]; i++) {
    c.slope_V_rad_q16 = slopes_bad[i];
    ck_assert_int_eq(canfdi_tps_cal_check(&c), -CANFDI_EINVAL);
    ck_assert_int_eq(canfdi_tps_init(&t, &c), -CANFDI_EINVAL);
  }
}
END_TEST

/* Extreme inputs saturate (the shallowest slope gives the steepest
 * conversion, 10 rad/V) instead of wrapping, for both slope signs. */
START_TEST(test_saturation_at_extremes)
{
  canfdi_tps_cal_t c;
  canfdi_tps_t up;
  canfdi_tps_t down;
  canfdi_tps_t dflt[2];
  canfdi_tps_cal_t cd[2];
  c.zero_V_q16 = 5 * ONE / 2;
  c.slope_V_rad_q16 = canfdi_div_s32_qn(ONE, 10, 0U);
  ck_assert_int_eq(canfdi_tps_init(&up, &c), CANFDI_OK);
  c.slope_V_rad_q16 = -c.slope_V_rad_q16;
  ck_assert_int_eq(canfdi_tps_init(&down, &c), CANFDI_OK);
  ck_assert_int_eq(canfdi_tps_V_to_rad_q16(&up, INT32_MAX), INT32_MAX);
  ck_assert_int_eq(canfdi_tps_V_to_rad_q16(&up, INT32_MIN), INT32_MIN);
  ck_assert_int_eq(canfdi_tps_V_to_rad_q16(&down, INT32_MAX), INT32_MIN);
  ck_assert_int_eq(canfdi_tps_V_to_rad_q16(&down, INT32_MIN), INT32_MAX);
  /* angle -> voltage with the steepest slope: the product saturates, the
   * sum with the (positive) zero saturates at the top and stays the
   * saturated product plus the zero at the bottom: never wraps */
  c.slope_V_rad_q16 = 10 * ONE;
  ck_assert_int_eq(canfdi_tps_rad_to_V_q16(&c, INT32_MAX), INT32_MAX);
  ck_assert_int_eq(canfdi_tps_rad_to_V_q16(&c, INT32_MIN), INT32_MIN + c.zero_V_q16);
  c.slope_V_rad_q16 = -10 * ONE;
  ck_assert_int_eq(canfdi_tps_rad_to_V_q16(&c, INT32_MAX), INT32_MIN + c.zero_V_q16);
  ck_assert_int_eq(canfdi_tps_rad_to_V_q16(&c, INT32_MIN), INT32_MAX);
  /* the default pair over the whole int32_t range: monotone, no wrap */
  canfdi_tps_cal_default(&cd[0], &cd[1]);
  ck_assert_int_eq(canfdi_tps_init(&dflt[0], &cd[0]), CANFDI_OK);
  ck_assert_int_eq(canfdi_tps_init(&dflt[1], &cd[1]), CANFDI_OK);
  int32_t prev0 = INT32_MIN;
  int32_t prev1 = INT32_MAX;
  for (int64_t v = INT32_MIN; v <= INT32_MAX; v += 65537 * 97) {
    const int32_t a0 = canfdi_tps_V_to_rad_q16(&dflt[0], (int32_t)v);
    const int32_t a1 = canfdi_tps_V_to_rad_q16(&dflt[1], (int32_t)v);
    ck_assert_int_ge(a0, prev0);
    ck_assert_int_le(a1, prev1);
    prev0 = a0;
    prev1 = a1;
  }
}
END_TEST

static Suite *make_suite(void)
{
  Suite *s = suite_create("tps");
  TCase *tc;

  tc = tcase_create("characteristic");
  tcase_add_test(tc, test_default_is_datasheet_line);
  tcase_add_test(tc, test_voltage_to_angle);
  tcase_add_test(tc, test_voltage_to_angle_exact_expression);
  tcase_add_test(tc, test_angle_to_voltage_and_round_trip);
  suite_add_tcase(s, tc);

  tc = tcase_create("domain");
  tcase_add_test(tc, test_domain);
  tcase_add_test(tc, test_saturation_at_extremes);
  suite_add_tcase(s, tc);
  return s;
}

CANFDI_UNIT_MAIN(make_suite)
