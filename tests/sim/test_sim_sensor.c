/*
 * test_sim_sensor.c — seeded noise (canfdi_sim_rng.h), the sensor chain
 * with its 12-bit ADC (canfdi_sim_sensor.h), and determinism of the whole
 * plant (canfdi_sim.h).
 */
#include <check.h>
#include <math.h>
#include <string.h>

#include "canfdi_sim.h"
#include "canfdi_sim_rng.h"
#include "canfdi_sim_sensor.h"
#include "core/canfdi_common.h"
#include "unit_main.h"

START_TEST(rng_is_reproducible_and_seed_dependent)
{
  canfdi_sim_rng_t a;
  canfdi_sim_rng_t b;
  canfdi_sim_rng_t c;
  canfdi_sim_rng_t d;
  unsigned k;
  unsigned same_c = 0U;
  unsigned same_d = 0U;
  canfdi_sim_rng_init(&a, 42U, 3U);
  canfdi_sim_rng_init(&b, 42U, 3U);
  canfdi_sim_rng_init(&c, 43U, 3U);
  canfdi_sim_rng_init(&d, 42U, 4U);
  for (k = 0U; k < 1000U; k++) {
    const uint64_t x = canfdi_sim_rng_next(&a);
    ck_assert_uint_eq(x, canfdi_sim_rng_next(&b));
    same_c += (x == canfdi_sim_rng_next(&c)) ? 1U : 0U;
    same_d += (x == canfdi_sim_rng_next(&d)) ? 1U : 0U;
  }
  ck_assert_uint_eq(same_c, 0U);
  ck_assert_uint_eq(same_d, 0U);
}
END_TEST

START_TEST(gauss_has_unit_variance)
{
  /* n = 200000 samples: the standard error of the mean is 1/sqrt(n) = 0.0022
   * and of the variance sqrt(2/n) = 0.0032; 5 standard errors as bounds. */
  canfdi_sim_rng_t r;
  const unsigned n = 200000U;
  double sum = 0.0;
  double sq = 0.0;
  unsigned beyond3 = 0U;
  unsigned k;
  double mean;
  double var;
  canfdi_sim_rng_init(&r, 7U, 0U);
  for (k = 0U; k < n; k++) {
    const double g = canfdi_sim_rng_gauss(&r);
    sum += g;
    sq += g * g;
    beyond3 += (fabs(g) > 3.0) ? 1U : 0U;
  }
  mean = sum / (double)n;
  var = (sq / (double)n) - (mean * mean);
  ck_assert_msg(fabs(mean) < 5.0 * 0.0022, "mean %g", mean);
  ck_assert_msg(fabs(var - 1.0) < 5.0 * 0.0032, "variance %g", var);
  /* P(|g| > 3) = 0.0027: expect 540 +- 5 sqrt(540) */
  ck_assert_msg(abs((int)beyond3 - 540) < 120, "tail count %u", beyond3);
  for (k = 0U; k < 1000U; k++) {
    const double u = canfdi_sim_rng_uniform(&r);
    ck_assert_msg((u > 0.0) && (u < 1.0), "uniform %g", u);
  }
}
END_TEST

static canfdi_sim_sensor_cfg_t span(double lo, double hi, double sigma)
{
  canfdi_sim_sensor_cfg_t c;
  c.min = lo;
  c.max = hi;
  c.gain = 1.0;
  c.offset = 0.0;
  c.sigma = sigma;
  return c;
}

START_TEST(adc_quantises_to_12_bits)
{
  canfdi_sim_sensor_t s;
  canfdi_sim_sensor_cfg_t c = span(-30.0, 30.0, 0.0);
  const double lsb = 60.0 / 4096.0;
  double x;
  ck_assert_int_eq(canfdi_sim_sensor_init(&s, &c, 1U, 0U), CANFDI_OK);
  ck_assert_msg(fabs(s.lsb - lsb) < 1e-15, "lsb %g", s.lsb);
  /* zero is a code of a symmetric bipolar span */
  ck_assert_msg(fabs(canfdi_sim_sensor_sample(&s, 0.0, 0.0, 0.0)) < 1e-300, "zero");
  ck_assert_uint_eq(s.last_code, 2048U);
  for (x = -29.9; x < 29.9; x += 0.0371) {
    const double y = canfdi_sim_sensor_sample(&s, x, 0.0, 0.0);
    ck_assert_msg(fabs(y - x) <= (0.5 * lsb) + 1e-12, "x %g -> %g", x, y);
    ck_assert_msg(fabs(y - (-30.0 + ((double)s.last_code * lsb))) < 1e-12, "code/value mismatch");
  }
  ck_assert_uint_eq(s.diag.clips, 0U);
  (void)canfdi_sim_sensor_sample(&s, 100.0, 0.0, 0.0);
  ck_assert_uint_eq(s.last_code, 4095U);
  (void)canfdi_sim_sensor_sample(&s, -100.0, 0.0, 0.0);
  ck_assert_uint_eq(s.last_code, 0U);
  (void)canfdi_sim_sensor_sample(&s, NAN, 0.0, 0.0);
  ck_assert_uint_eq(s.last_code, 0U);
  ck_assert_uint_eq(s.diag.clips, 3U);
}
END_TEST

START_TEST(gain_offset_and_noise)
{
  canfdi_sim_sensor_t s;
  canfdi_sim_sensor_cfg_t c = span(-400.0, 400.0, 2.0);
  const unsigned n = 50000U;
  double sum = 0.0;
  double sq = 0.0;
  unsigned k;
  double mean;
  double sd;
  c.gain = 1.01;
  c.offset = 3.0;
  ck_assert_int_eq(canfdi_sim_sensor_init(&s, &c, 9U, 2U), CANFDI_OK);
  for (k = 0U; k < n; k++) {
    const double y = canfdi_sim_sensor_sample(&s, 100.0, 0.05, 1.5);
    sum += y;
    sq += y * y;
    ck_assert_msg(fabs(s.last_analog - ((1.01 * 1.05 * 100.0) + 3.0 + 1.5)) < 1e-12, "analog");
  }
  mean = sum / (double)n;
  sd = sqrt((sq / (double)n) - (mean * mean));
  /* mean within 5 standard errors (2/sqrt(n) = 0.009) plus the ADC's
   * half LSB; sigma within 3 % (the ADC adds lsb^2/12, 0.1 % here). */
  ck_assert_msg(fabs(mean - 110.555) < (5.0 * 0.009) + (0.5 * s.lsb), "mean %g", mean);
  ck_assert_msg(fabs(sd - 2.0) < 0.06, "sigma %g", sd);
}
END_TEST

START_TEST(invalid_sensor_config)
{
  canfdi_sim_sensor_t s;
  canfdi_sim_sensor_cfg_t c = span(5.0, 5.0, 0.0);
  ck_assert_int_eq(canfdi_sim_sensor_init(&s, &c, 1U, 0U), -CANFDI_EINVAL);
  c = span(0.0, 5.0, -0.1);
  ck_assert_int_eq(canfdi_sim_sensor_init(&s, &c, 1U, 0U), -CANFDI_EINVAL);
}
END_TEST

/* Runs the whole plant with noise on every sensor for 300 steps and
 * returns a checksum-free copy of all readings. */
static void run_plant(uint64_t seed, double *out, unsigned n_steps)
{
  static canfdi_sim_t sim;
  canfdi_sim_cfg_t cfg;
  canfdi_sim_in_t in;
  unsigned k;
  unsigned i;
  const double sig[CANFDI_SIM_N_SENSORS] = {0.05, 0.02, 0.3, 0.05, 0.003, 0.003, 0.01, 0.02};
  canfdi_sim_default_cfg(&cfg);
  memcpy(cfg.sigma, sig, sizeof sig);
  cfg.seed = seed;
  ck_assert_int_eq(canfdi_sim_init(&sim, &cfg), CANFDI_OK);
  in.dcm.u_cmd_V = 20.0;
  in.dcm.bridge = CANFDI_SIM_BRIDGE_A;
  in.dcm.enable = true;
  in.dcm.load_Nm = 0.3;
  in.thr.u_cmd_V = 3.0;
  in.thr.enable = true;
  for (k = 0U; k < n_steps; k++) {
    canfdi_sim_step(&sim, &in);
    for (i = 0U; i < CANFDI_SIM_N_SENSORS; i++) {
      out[(k * CANFDI_SIM_N_SENSORS) + i] = sim.meas.value[i];
    }
  }
}

START_TEST(plant_is_deterministic_per_seed)
{
  static double a[300U * CANFDI_SIM_N_SENSORS];
  static double b[300U * CANFDI_SIM_N_SENSORS];
  static double c[300U * CANFDI_SIM_N_SENSORS];
  unsigned i;
  unsigned differ = 0U;
  run_plant(1234U, a, 300U);
  run_plant(1234U, b, 300U);
  run_plant(1235U, c, 300U);
  ck_assert_msg(memcmp(a, b, sizeof a) == 0, "same seed, different readings");
  for (i = 0U; i < (300U * CANFDI_SIM_N_SENSORS); i++) {
    differ += (fabs(a[i] - c[i]) > 0.0) ? 1U : 0U;
  }
  /* With sigma of a few LSB nearly every reading differs between seeds. */
  ck_assert_msg(differ > (300U * CANFDI_SIM_N_SENSORS) / 2U, "only %u readings differ", differ);
}
END_TEST

static Suite *make_suite(void)
{
  Suite *s = suite_create("sim_sensor");
  TCase *tc = tcase_create("rng");
  tcase_add_test(tc, rng_is_reproducible_and_seed_dependent);
  tcase_add_test(tc, gauss_has_unit_variance);
  suite_add_tcase(s, tc);
  tc = tcase_create("adc");
  tcase_add_test(tc, adc_quantises_to_12_bits);
  tcase_add_test(tc, gain_offset_and_noise);
  tcase_add_test(tc, invalid_sensor_config);
  suite_add_tcase(s, tc);
  tc = tcase_create("determinism");
  tcase_add_test(tc, plant_is_deterministic_per_seed);
  suite_add_tcase(s, tc);
  return s;
}

CANFDI_UNIT_MAIN(make_suite)
