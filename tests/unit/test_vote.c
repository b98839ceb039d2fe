/*
 * test_vote.c — unit tests of firmware/ft/canfdi_vote: the voltage to angle
 * conversion, every row of the decision table (each combination of input
 * validity and pairwise agreement), isolation after exactly the debounce
 * time, no isolation for shorter transient disagreements, latching and
 * clearing.
 *
 * Inputs are built in angles (double) and turned into potentiometer
 * voltages with the inverse of the design calibration (0.5 V + 4 V per
 * 90 deg for TPS1, 4.5 V - 4 V per 90 deg for TPS2). Expected angles come
 * from the table re-stated below (mean, median, one source, held) computed
 * in double from the intended angles. Tolerance: 4 LSB of Q16.16 (6e-5
 * rad): the voltage is rounded to Q16.16 (0.5 LSB of V, times 0.39 rad/V)
 * and the conversion and the mean round once each (0.5 LSB), far below any
 * agreement tolerance, and far above nothing that could hide a wrong row
 * (rows differ by >= 0.015 rad = 983 LSB).
 */
#include <check.h>
#include <math.h>
#include <stdint.h>

#include "ft/canfdi_vote.h"
#include "unit_main.h"

#define Q16(x) ((int32_t)lround((x) * 65536.0))
#define TOL_LSB 4

static const double k_pi = 3.14159265358979323846;
static double gain_rad_per_V(void) { return (k_pi / 2.0) / 4.0; }

static const double TOL_TPS = 0.02;   /* rad (~1.1 deg) */
static const double TOL_MODEL = 0.05; /* rad (~2.9 deg) */

static canfdi_vote_cfg_t design_cfg(uint16_t n_tps, uint16_t n_model)
{
  canfdi_vote_cfg_t c;
  c.tps1.zero_V_q16 = Q16(0.5);
  c.tps1.slope_V_rad_q16 = Q16(1.0 / gain_rad_per_V());
  c.tps2.zero_V_q16 = Q16(4.5);
  c.tps2.slope_V_rad_q16 = -Q16(1.0 / gain_rad_per_V());
  c.tol_tps_rad_q16 = Q16(TOL_TPS);
  c.tol_model_rad_q16 = Q16(TOL_MODEL);
  c.isolate_steps_tps = n_tps;
  c.isolate_steps_model = n_model;
  return c;
}

static canfdi_vote_in_t make_in(double th1, double th2, double thm, bool v1, bool v2, bool vm)
{
  canfdi_vote_in_t in;
  in.tps1_V_q16 = Q16(0.5 + th1 / gain_rad_per_V());
  in.tps2_V_q16 = Q16(4.5 - th2 / gain_rad_per_V());
  in.model_rad_q16 = Q16(thm);
  in.tps1_valid = v1;
  in.tps2_valid = v2;
  in.model_valid = vm;
  in.model_no_blame = false;
  return in;
}

static void assert_angle(int32_t got_q16, double want_rad)
{
  const int32_t want = Q16(want_rad);
  const int32_t diff = got_q16 - want;
  ck_assert_msg((diff <= TOL_LSB) && (diff >= -TOL_LSB), "angle %ld LSB, want %ld", (long)got_q16,
                (long)want);
}

/* ---------------------------------------------------------------- config */

START_TEST(test_cfg_domain)
{
  /* each case breaks one field of a valid config */
  canfdi_vote_cfg_t c = design_cfg(10U, 20U);
  canfdi_vote_t v;
  switch (_i) {
  case 0: break; /* valid */
  case 1: c.tps1.slope_V_rad_q16 = 0; break;
  case 2: c.tps1.slope_V_rad_q16 = -c.tps1.slope_V_rad_q16; break; /* TPS1 must rise */
  case 3: c.tps2.slope_V_rad_q16 = 0; break;
  case 4: c.tps2.slope_V_rad_q16 = -c.tps2.slope_V_rad_q16; break; /* TPS2 must fall */
  case 5: c.tol_tps_rad_q16 = 0; break;
  case 6: c.tol_model_rad_q16 = -5; break;
  case 7: c.isolate_steps_tps = 0U; break;
  case 8: c.isolate_steps_model = 0U; break;
  case 9: c.isolate_steps_tps = 32768U; break;
  case 10: c.isolate_steps_model = 32767U; break; /* valid upper end */
  default: break;
  }
  if ((_i == 0) || (_i == 10)) {
    ck_assert_int_eq(canfdi_vote_init(&v, &c), CANFDI_OK);
  } else {
    canfdi_vote_in_t in = make_in(0.3, 0.3, 0.3, true, true, true);
    canfdi_vote_out_t out;
    ck_assert_int_eq(canfdi_vote_init(&v, &c), -CANFDI_EINVAL);
    ck_assert_int_eq(canfdi_vote_step(&v, &in, &out), -CANFDI_EINVAL);
    ck_assert_uint_eq(out.status, CANFDI_VOTE_INVALID);
    ck_assert(!out.valid);
  }
}
END_TEST

START_TEST(test_null_args)
{
  canfdi_vote_cfg_t c = design_cfg(3U, 3U);
  canfdi_vote_t v;
  canfdi_vote_in_t in = make_in(0.3, 0.3, 0.3, true, true, true);
  canfdi_vote_out_t out;
  ck_assert_int_eq(canfdi_vote_init(NULL, &c), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_vote_init(&v, NULL), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_vote_init(&v, &c), CANFDI_OK);
  ck_assert_int_eq(canfdi_vote_step(NULL, &in, &out), -CANFDI_EINVAL);
  ck_assert_uint_eq(out.excluded_mask, 7U);
  ck_assert_int_eq(canfdi_vote_step(&v, NULL, &out), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_vote_step(&v, &in, NULL), -CANFDI_EINVAL);
  canfdi_vote_clear(NULL);
  ck_assert_uint_eq(canfdi_vote_diag(NULL).steps, 0U);
  ck_assert_uint_eq(canfdi_vote_diag(&v).steps, 0U);
}
END_TEST

/* ------------------------------------------------------------ conversion */

START_TEST(test_conversion)
{
  /* 0..90 deg in 1 deg steps, both sensors, against the double formula */
  const double th = (double)_i * k_pi / 180.0;
  const double v1 = 0.5 + th / gain_rad_per_V();
  const double v2 = 4.5 - th / gain_rad_per_V();
  const canfdi_vote_cfg_t c = design_cfg(1U, 1U);
  canfdi_vote_t v;
  canfdi_vote_out_t out;
  canfdi_vote_in_t in = make_in(th, th, th, true, true, true);
  in.tps1_V_q16 = Q16(v1);
  in.tps2_V_q16 = Q16(v2);
  ck_assert_int_eq(canfdi_vote_init(&v, &c), CANFDI_OK);
  ck_assert_int_eq(canfdi_vote_step(&v, &in, &out), CANFDI_OK);
  assert_angle(out.theta_rad_q16[CANFDI_VOTE_SRC_TPS1], th);
  assert_angle(out.theta_rad_q16[CANFDI_VOTE_SRC_TPS2], th);
}
END_TEST

START_TEST(test_conversion_saturates)
{
  /* voltages far outside the sensors' range saturate instead of wrapping */
  const canfdi_vote_cfg_t c = design_cfg(1U, 1U);
  canfdi_vote_t v;
  canfdi_vote_out_t out;
  canfdi_vote_in_t in = make_in(0.0, 0.0, 0.0, false, false, false);
  in.tps1_V_q16 = INT32_MAX;
  in.tps2_V_q16 = INT32_MAX;
  ck_assert_int_eq(canfdi_vote_init(&v, &c), CANFDI_OK);
  ck_assert_int_eq(canfdi_vote_step(&v, &in, &out), CANFDI_OK);
  ck_assert_int_gt(out.theta_rad_q16[CANFDI_VOTE_SRC_TPS1], 0);
  ck_assert_int_lt(out.theta_rad_q16[CANFDI_VOTE_SRC_TPS2], 0);
  in.tps1_V_q16 = INT32_MIN;
  in.tps2_V_q16 = INT32_MIN;
  ck_assert_int_eq(canfdi_vote_step(&v, &in, &out), CANFDI_OK);
  ck_assert_int_lt(out.theta_rad_q16[CANFDI_VOTE_SRC_TPS1], 0);
  ck_assert_int_gt(out.theta_rad_q16[CANFDI_VOTE_SRC_TPS2], 0);
}
END_TEST

/* -------------------------------------------------------- decision table */

/* What the angle should be, from the intended angles. */
typedef enum { E_MEAN12, E_MEDIAN, E_T1, E_T2, E_M, E_HELD } expect_angle_t;

typedef struct {
  const char *name;
  bool v1, v2, vm;           /* input validity */
  double d1, d2, dm;         /* offsets from the base angle, rad */
  expect_angle_t angle;
  canfdi_vote_status_t status;
  uint8_t outlier;           /* mask */
  uint8_t used;              /* mask */
} row_t;

#define T1 CANFDI_VOTE_BIT_TPS1
#define T2 CANFDI_VOTE_BIT_TPS2
#define MM CANFDI_VOTE_BIT_MODEL

/* Offsets realise each agreement pattern with TOL_TPS 0.02, TOL_MODEL 0.05
 * (pattern in the comment: a12 a1m a2m). */
static const row_t rows[] = {
    /* three available */
    {"3: 111", true, true, true, 0.0, 0.005, -0.01, E_MEAN12, CANFDI_VOTE_THREE, 0U, T1 | T2},
    {"3: 100", true, true, true, 0.0, 0.01, 0.2, E_MEAN12, CANFDI_VOTE_THREE, MM, T1 | T2},
    {"3: 110", true, true, true, 0.0, 0.015, -0.04, E_MEAN12, CANFDI_VOTE_THREE, 0U, T1 | T2},
    {"3: 101", true, true, true, 0.015, 0.0, -0.04, E_MEAN12, CANFDI_VOTE_THREE, 0U, T1 | T2},
    {"3: 011", true, true, true, -0.03, 0.03, 0.0, E_MEDIAN, CANFDI_VOTE_THREE, 0U, T1 | T2 | MM},
    {"3: 010", true, true, true, 0.0, 0.2, 0.03, E_T1, CANFDI_VOTE_THREE, T2, T1 | MM},
    {"3: 001", true, true, true, -0.3, 0.0, 0.04, E_T2, CANFDI_VOTE_THREE, T1, T2 | MM},
    {"3: 000", true, true, true, 0.0, 0.2, -0.2, E_HELD, CANFDI_VOTE_DISAGREE, 0U, 0U},
    /* two available, each pair, agree and disagree */
    {"2: T1T2 agree", true, true, false, 0.0, 0.019, 0.9, E_MEAN12, CANFDI_VOTE_TWO, 0U, T1 | T2},
    {"2: T1T2 differ", true, true, false, 0.0, 0.021, 0.0, E_HELD, CANFDI_VOTE_DISAGREE, 0U, 0U},
    {"2: T1M agree", true, false, true, 0.0, 0.9, 0.049, E_T1, CANFDI_VOTE_TWO, 0U, T1 | MM},
    {"2: T1M differ", true, false, true, 0.0, 0.0, 0.051, E_HELD, CANFDI_VOTE_DISAGREE, 0U, 0U},
    {"2: T2M agree", false, true, true, 0.9, 0.0, -0.049, E_T2, CANFDI_VOTE_TWO, 0U, T2 | MM},
    {"2: T2M differ", false, true, true, 0.0, 0.0, -0.051, E_HELD, CANFDI_VOTE_DISAGREE, 0U, 0U},
    /* one available (the others' values are garbage on purpose) */
    {"1: T1", true, false, false, 0.0, 0.7, -0.7, E_T1, CANFDI_VOTE_SINGLE, 0U, T1},
    {"1: T2", false, true, false, 0.7, 0.0, -0.7, E_T2, CANFDI_VOTE_SINGLE, 0U, T2},
    {"1: M", false, false, true, 0.7, -0.7, 0.0, E_M, CANFDI_VOTE_SINGLE, 0U, MM},
    /* none */
    {"0", false, false, false, 0.0, 0.0, 0.0, E_HELD, CANFDI_VOTE_INVALID, 0U, 0U},
};
#define N_ROWS ((int)(sizeof rows / sizeof rows[0]))

static double median3d(double a, double b, double c)
{
  const double lo = fmin(a, fmin(b, c));
  const double hi = fmax(a, fmax(b, c));
  return a + b + c - lo - hi;
}

START_TEST(test_decision_table)
{
  /* each row at two base angles (near closed and near open) */
  const row_t *r = &rows[_i / 2];
  const double base = ((_i % 2) == 0) ? 0.12 : 1.3;
  const double held = 0.77;
  const double t1 = base + r->d1;
  const double t2 = base + r->d2;
  const double tm = base + r->dm;
  const canfdi_vote_cfg_t c = design_cfg(50U, 50U);
  canfdi_vote_t v;
  canfdi_vote_in_t in;
  canfdi_vote_out_t out;
  double want = held;
  const uint8_t valid_mask = (uint8_t)((r->v1 ? T1 : 0U) | (r->v2 ? T2 : 0U) | (r->vm ? MM : 0U));

  ck_assert_int_eq(canfdi_vote_init(&v, &c), CANFDI_OK);
  /* a first, agreeing step establishes the held angle */
  in = make_in(held, held, held, true, true, true);
  ck_assert_int_eq(canfdi_vote_step(&v, &in, &out), CANFDI_OK);
  ck_assert_uint_eq(out.status, CANFDI_VOTE_THREE);

  in = make_in(t1, t2, tm, r->v1, r->v2, r->vm);
  ck_assert_int_eq(canfdi_vote_step(&v, &in, &out), CANFDI_OK);
  switch (r->angle) {
  case E_MEAN12: want = 0.5 * (t1 + t2); break;
  case E_MEDIAN: want = median3d(t1, t2, tm); break;
  case E_T1: want = t1; break;
  case E_T2: want = t2; break;
  case E_M: want = tm; break;
  case E_HELD: want = held; break;
  default: break;
  }
  ck_assert_msg(out.status == (uint8_t)r->status, "%s: status %u", r->name, out.status);
  assert_angle(out.angle_rad_q16, want);
  ck_assert_msg(out.outlier_mask == r->outlier, "%s: outlier %u", r->name, out.outlier_mask);
  ck_assert_msg(out.used_mask == r->used, "%s: used %u", r->name, out.used_mask);
  ck_assert_uint_eq(out.excluded_mask, 7U & (uint8_t)~valid_mask);
  ck_assert_uint_eq(out.n_available, (r->v1 ? 1U : 0U) + (r->v2 ? 1U : 0U) + (r->vm ? 1U : 0U));
  ck_assert(out.valid == ((r->status == CANFDI_VOTE_THREE) || (r->status == CANFDI_VOTE_TWO)));
  ck_assert_uint_eq(out.isolated_mask, 0U);
  ck_assert_uint_eq(out.newly_isolated, 0U);
  assert_angle(out.theta_rad_q16[0], t1);
  assert_angle(out.theta_rad_q16[1], t2);
  assert_angle(out.theta_rad_q16[2], tm);
}
END_TEST

START_TEST(test_held_before_first_decision)
{
  /* before any decided vote the held angle is 0 */
  const canfdi_vote_cfg_t c = design_cfg(5U, 5U);
  canfdi_vote_t v;
  canfdi_vote_in_t in = make_in(0.4, 0.8, 0.0, true, true, false);
  canfdi_vote_out_t out;
  ck_assert_int_eq(canfdi_vote_init(&v, &c), CANFDI_OK);
  ck_assert_int_eq(canfdi_vote_step(&v, &in, &out), CANFDI_OK);
  ck_assert_uint_eq(out.status, CANFDI_VOTE_DISAGREE);
  ck_assert_int_eq(out.angle_rad_q16, 0);
  ck_assert_uint_eq(canfdi_vote_diag(&v).disagree_steps, 1U);
}
END_TEST

/* ------------------------------------------------------------- isolation */

typedef struct {
  uint8_t src;      /* source index that goes bad */
  uint16_t n;       /* its isolation steps */
} iso_case_t;

static const iso_case_t iso_cases[] = {
    {CANFDI_VOTE_SRC_TPS1, 1U},  {CANFDI_VOTE_SRC_TPS1, 2U},  {CANFDI_VOTE_SRC_TPS1, 37U},
    {CANFDI_VOTE_SRC_TPS2, 1U},  {CANFDI_VOTE_SRC_TPS2, 5U},  {CANFDI_VOTE_SRC_TPS2, 200U},
    {CANFDI_VOTE_SRC_MODEL, 1U}, {CANFDI_VOTE_SRC_MODEL, 4U}, {CANFDI_VOTE_SRC_MODEL, 150U},
};
#define N_ISO ((int)(sizeof iso_cases / sizeof iso_cases[0]))

/* Inputs with source `bad` off by `off` rad (the others agree at th). */
static canfdi_vote_in_t with_bad(uint8_t bad, double th, double off)
{
  return make_in(th + ((bad == CANFDI_VOTE_SRC_TPS1) ? off : 0.0),
                 th + ((bad == CANFDI_VOTE_SRC_TPS2) ? off : 0.0),
                 th + ((bad == CANFDI_VOTE_SRC_MODEL) ? off : 0.0), true, true, true);
}

static canfdi_vote_cfg_t iso_cfg(const iso_case_t *k)
{
  /* the other class gets a different count so a mix-up would show */
  return (k->src == CANFDI_VOTE_SRC_MODEL) ? design_cfg(3U, k->n) : design_cfg(k->n, 7U);
}

START_TEST(test_isolation_exact_time)
{
  const iso_case_t *k = &iso_cases[_i];
  const uint8_t bit = (uint8_t)(1U << k->src);
  const canfdi_vote_cfg_t c = iso_cfg(k);
  canfdi_vote_t v;
  canfdi_vote_in_t in;
  canfdi_vote_out_t out;
  uint32_t step;

  ck_assert_int_eq(canfdi_vote_init(&v, &c), CANFDI_OK);
  /* healthy phase */
  for (step = 0U; step < 10U; step++) {
    in = with_bad(k->src, 0.3 + 0.01 * step, 0.0);
    ck_assert_int_eq(canfdi_vote_step(&v, &in, &out), CANFDI_OK);
    ck_assert_uint_eq(out.outlier_mask, 0U);
  }
  /* the source drifts out of agreement, the valve moving: isolated on
   * exactly the n-th outlier step, not before */
  for (step = 1U; step <= k->n; step++) {
    in = with_bad(k->src, 0.4 + 0.001 * step, 0.25);
    ck_assert_int_eq(canfdi_vote_step(&v, &in, &out), CANFDI_OK);
    ck_assert_uint_eq(out.status, CANFDI_VOTE_THREE);
    ck_assert_uint_eq(out.outlier_mask, bit);
    if (step < k->n) {
      ck_assert_uint_eq(out.isolated_mask, 0U);
      ck_assert_uint_eq(out.newly_isolated, 0U);
    } else {
      ck_assert_uint_eq(out.isolated_mask, bit);
      ck_assert_uint_eq(out.newly_isolated, bit);
    }
    /* the output never follows the outlier */
    assert_angle(out.angle_rad_q16, 0.4 + 0.001 * step);
  }
  ck_assert_uint_eq(canfdi_vote_diag(&v).isolations, 1U);
  /* from the next step on it is excluded: two-way vote of the others */
  in = with_bad(k->src, 0.5, 0.25);
  ck_assert_int_eq(canfdi_vote_step(&v, &in, &out), CANFDI_OK);
  ck_assert_uint_eq(out.status, CANFDI_VOTE_TWO);
  ck_assert_uint_eq(out.excluded_mask, bit);
  ck_assert_uint_eq(out.newly_isolated, 0U);
  ck_assert(out.valid);
  assert_angle(out.angle_rad_q16, 0.5);
  /* latched: agreeing again does not re-admit it */
  in = with_bad(k->src, 0.5, 0.0);
  ck_assert_int_eq(canfdi_vote_step(&v, &in, &out), CANFDI_OK);
  ck_assert_uint_eq(out.isolated_mask, bit);
  ck_assert_uint_eq(out.status, CANFDI_VOTE_TWO);
  /* until cleared */
  canfdi_vote_clear(&v);
  ck_assert_int_eq(canfdi_vote_step(&v, &in, &out), CANFDI_OK);
  ck_assert_uint_eq(out.isolated_mask, 0U);
  ck_assert_uint_eq(out.status, CANFDI_VOTE_THREE);
  ck_assert_uint_eq(canfdi_vote_diag(&v).clears, 1U);
}
END_TEST

START_TEST(test_transient_never_isolates)
{
  /* bursts of n - 1 outlier steps separated by one agreeing step, 300
   * times: no isolation (the count is of consecutive steps) */
  const iso_case_t *k = &iso_cases[_i];
  const canfdi_vote_cfg_t c = iso_cfg(k);
  canfdi_vote_t v;
  canfdi_vote_in_t in;
  canfdi_vote_out_t out;
  uint32_t burst;
  uint32_t step;

  ck_assert_int_eq(canfdi_vote_init(&v, &c), CANFDI_OK);
  for (burst = 0U; burst < 300U; burst++) {
    for (step = 1U; step < k->n; step++) {
      in = with_bad(k->src, 0.6, (burst % 2U) ? 0.3 : -0.3);
      ck_assert_int_eq(canfdi_vote_step(&v, &in, &out), CANFDI_OK);
      ck_assert_uint_eq(out.outlier_mask, 1U << k->src);
    }
    in = with_bad(k->src, 0.6, 0.0);
    ck_assert_int_eq(canfdi_vote_step(&v, &in, &out), CANFDI_OK);
    ck_assert_uint_eq(out.isolated_mask, 0U);
  }
  ck_assert_uint_eq(canfdi_vote_diag(&v).isolations, 0U);
  ck_assert_uint_eq(canfdi_vote_diag(&v).outlier_steps, 300U * (k->n - 1U));
}
END_TEST

START_TEST(test_no_isolation_without_evidence)
{
  /* Disagreement without a majority (two available, or the ambiguous and
   * all-disagree rows) never isolates anybody, however long it lasts; an
   * invalid input is excluded, not isolated. */
  const canfdi_vote_cfg_t c = design_cfg(2U, 2U);
  canfdi_vote_t v;
  canfdi_vote_in_t in;
  canfdi_vote_out_t out;
  uint32_t step;
  ck_assert_int_eq(canfdi_vote_init(&v, &c), CANFDI_OK);
  for (step = 0U; step < 100U; step++) {
    switch (step % 4U) {
    case 0U: in = make_in(0.3, 0.5, 0.0, true, true, false); break;   /* 2: disagree */
    case 1U: in = make_in(0.27, 0.33, 0.3, true, true, true); break;  /* 3: 011 */
    case 2U: in = make_in(0.3, 0.5, 0.1, true, true, true); break;    /* 3: 000 */
    default: in = make_in(2.0, 0.3, 0.3, false, true, true); break;   /* T1 invalid */
    }
    ck_assert_int_eq(canfdi_vote_step(&v, &in, &out), CANFDI_OK);
    ck_assert_uint_eq(out.outlier_mask, 0U);
  }
  ck_assert_uint_eq(out.isolated_mask, 0U);
  ck_assert_uint_eq(canfdi_vote_diag(&v).isolations, 0U);
  ck_assert_uint_eq(canfdi_vote_diag(&v).disagree_steps, 50U);
}
END_TEST

START_TEST(test_model_without_blame)
{
  /* The model near one sensor with the sensors apart: without
   * model_no_blame the far sensor is the outlier and is isolated; with it
   * the median of three closes the loop, nobody blamed, however long. */
  canfdi_vote_in_t in = make_in(0.30, 0.40, 0.31, true, true, true);
  canfdi_vote_t v;
  canfdi_vote_out_t out;
  uint32_t k;
  {
    const canfdi_vote_cfg_t c = design_cfg(2U, 2U);
    ck_assert_int_eq(canfdi_vote_init(&v, &c), CANFDI_OK);
  }
  in.model_no_blame = true;
  for (k = 0U; k < 50U; k++) {
    ck_assert_int_eq(canfdi_vote_step(&v, &in, &out), CANFDI_OK);
    ck_assert_uint_eq(out.status, CANFDI_VOTE_THREE);
    ck_assert(out.valid);
    ck_assert_uint_eq(out.outlier_mask, 0U);
    assert_angle(out.angle_rad_q16, 0.31);
  }
  ck_assert_uint_eq(out.isolated_mask, 0U);
  in.model_no_blame = false;
  for (k = 0U; k < 2U; k++) {
    ck_assert_int_eq(canfdi_vote_step(&v, &in, &out), CANFDI_OK);
    ck_assert_uint_eq(out.outlier_mask, T2);
  }
  ck_assert_uint_eq(out.isolated_mask, T2);
}
END_TEST

START_TEST(test_second_fault_after_isolation)
{
  /* TPS2 isolated; then TPS1 and the model disagree -> DISAGREE (no tie
   * breaker is left); then TPS1 invalid -> SINGLE with the model. */
  const canfdi_vote_cfg_t c = design_cfg(3U, 3U);
  canfdi_vote_t v;
  canfdi_vote_in_t in;
  canfdi_vote_out_t out;
  uint32_t step;
  ck_assert_int_eq(canfdi_vote_init(&v, &c), CANFDI_OK);
  for (step = 0U; step < 3U; step++) {
    in = with_bad(CANFDI_VOTE_SRC_TPS2, 0.5, 0.2);
    ck_assert_int_eq(canfdi_vote_step(&v, &in, &out), CANFDI_OK);
  }
  ck_assert_uint_eq(out.isolated_mask, T2);
  in = make_in(0.5, 0.5, 0.7, true, true, true);
  ck_assert_int_eq(canfdi_vote_step(&v, &in, &out), CANFDI_OK);
  ck_assert_uint_eq(out.status, CANFDI_VOTE_DISAGREE);
  assert_angle(out.angle_rad_q16, 0.5); /* held from the last decided vote */
  ck_assert(!out.valid);
  in = make_in(0.5, 0.5, 0.7, false, true, true);
  ck_assert_int_eq(canfdi_vote_step(&v, &in, &out), CANFDI_OK);
  ck_assert_uint_eq(out.status, CANFDI_VOTE_SINGLE);
  ck_assert_uint_eq(out.excluded_mask, T1 | T2);
  assert_angle(out.angle_rad_q16, 0.7);
  ck_assert(!out.valid);
}
END_TEST

static Suite *make_suite(void)
{
  Suite *s = suite_create("vote");
  TCase *tc;

  tc = tcase_create("config");
  tcase_add_loop_test(tc, test_cfg_domain, 0, 11);
  tcase_add_test(tc, test_null_args);
  suite_add_tcase(s, tc);

  tc = tcase_create("conversion");
  tcase_add_loop_test(tc, test_conversion, 0, 91);
  tcase_add_test(tc, test_conversion_saturates);
  suite_add_tcase(s, tc);

  tc = tcase_create("decision_table");
  tcase_add_loop_test(tc, test_decision_table, 0, 2 * N_ROWS);
  tcase_add_test(tc, test_held_before_first_decision);
  suite_add_tcase(s, tc);

  tc = tcase_create("isolation");
  tcase_add_loop_test(tc, test_isolation_exact_time, 0, N_ISO);
  tcase_add_loop_test(tc, test_transient_never_isolates, 0, N_ISO);
  tcase_add_test(tc, test_no_isolation_without_evidence);
  tcase_add_test(tc, test_model_without_blame);
  tcase_add_test(tc, test_second_fault_after_isolation);
  suite_add_tcase(s, tc);
  return s;
}

CANFDI_UNIT_MAIN(make_suite)
