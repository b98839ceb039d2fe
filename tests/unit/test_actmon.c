/*
 * test_actmon.c — the actuator monitors (detect/canfdi_actmon.h): each
 * symptom appears when, and only when, its conditions hold; the filters'
 * time constants; the UAC monitor holds its filter while not judged; bad
 * arguments and configurations are refused.
 */
#include <check.h>

#include "core/canfdi_qconst.h"
#include "detect/canfdi_actmon.h"
#include "unit_main.h"

static canfdi_actmon_t m;
static canfdi_actmon_cfg_t cfg;

/* A throttle following its reference and a DC motor whose U_A equals the
 * command: no symptom. */
static canfdi_actmon_in_t healthy(void)
{
  canfdi_actmon_in_t in;
  in.thr_angle_rad_q16 = CANFDI_Q16_DEG(20, 1);
  in.thr_ref_rad_q16 = CANFDI_Q16_DEG(20, 1);
  in.thr_angle_valid = true;
  in.thr_i_A_q16 = CANFDI_Q16_MILLI(800);
  in.thr_i_valid = true;
  in.thr_enabled = true;
  in.thr_u_cmd_V_q16 = 4 * CANFDI_Q16_ONE;
  in.dcm_ua_V_q16 = 30 * CANFDI_Q16_ONE;
  in.dcm_ua_valid = true;
  in.dcm_supply_V_q16 = 48 * CANFDI_Q16_ONE;
  in.dcm_supply_valid = true;
  in.dcm_enabled = true;
  in.dcm_u_cmd_V_q16 = 30 * CANFDI_Q16_ONE;
  in.dcm_bridge_settled = true;
  return in;
}

static void setup(void)
{
  canfdi_actmon_default_cfg(&cfg);
  ck_assert_int_eq(canfdi_actmon_init(&m, &cfg), CANFDI_OK);
}

START_TEST(test_healthy_no_symptom)
{
  canfdi_actmon_in_t in = healthy();
  canfdi_actmon_out_t out;
  uint32_t k;
  setup();
  for (k = 0U; k < 5000U; k++) {
    ck_assert_int_eq(canfdi_actmon_step(&m, &in, &out), CANFDI_OK);
    ck_assert(!out.thr_not_following);
    ck_assert(!out.thr_no_current);
    ck_assert(out.dcm_uac_valid);
    ck_assert_int_eq(out.dcm_uac_rn_q16, 0);
  }
  ck_assert_uint_eq(canfdi_actmon_diag(&m).steps, 5000U);
  ck_assert_uint_eq(canfdi_actmon_diag(&m).uac_judged_steps, 5000U);
}
END_TEST

/* A valve held 10 deg away from its reference: the filtered error crosses
 * 0.05 rad after ~0.17 s (alpha 1/500 per step), not before 0.1 s; the
 * symptom needs a valid vote and an energised throttle. */
START_TEST(test_tracking)
{
  canfdi_actmon_in_t in = healthy();
  canfdi_actmon_out_t out;
  uint32_t k;
  uint32_t first = 0U;
  setup();
  in.thr_angle_rad_q16 = CANFDI_Q16_DEG(30, 1);
  for (k = 1U; (k <= 1000U) && (first == 0U); k++) {
    (void)canfdi_actmon_step(&m, &in, &out);
    if (out.thr_not_following) {
      first = k;
    }
  }
  ck_assert_uint_ge(first, 100U);
  ck_assert_uint_le(first, 250U);
  ck_assert_int_gt(out.thr_track_err_rad_q16, cfg.track_thr_rad_q16);
  in.thr_angle_valid = false;
  (void)canfdi_actmon_step(&m, &in, &out);
  ck_assert(!out.thr_not_following);
  in.thr_angle_valid = true;
  in.thr_enabled = false;
  (void)canfdi_actmon_step(&m, &in, &out);
  ck_assert(!out.thr_not_following);
  /* an error of either sign counts */
  setup();
  in = healthy();
  in.thr_angle_rad_q16 = CANFDI_Q16_DEG(10, 1);
  for (k = 0U; k < 400U; k++) {
    (void)canfdi_actmon_step(&m, &in, &out);
  }
  ck_assert(out.thr_not_following);
}
END_TEST

/* Drives a stroke: the reference jumps from `from` to `to` deg at step 1
 * (with the vote valid from step 0, or from the jump if `start_up`); the
 * valve leaves `from` at `rate_mrad` per step (0: stuck) and stops at
 * `to`. Returns the first step with the tracking symptom (0: none in
 * `steps`). */
static uint32_t stroke(int32_t from, int32_t to, int32_t rate_mrad, bool start_up, uint32_t steps)
{
  canfdi_actmon_in_t in = healthy();
  canfdi_actmon_out_t out;
  int32_t angle = CANFDI_Q16_DEG(from, 1);
  const int32_t target = CANFDI_Q16_DEG(to, 1);
  const int32_t d = CANFDI_Q16_MILLI(rate_mrad);
  uint32_t k;
  uint32_t first = 0U;
  setup();
  in.thr_angle_rad_q16 = angle;
  in.thr_ref_rad_q16 = angle;
  if (!start_up) {
    (void)canfdi_actmon_step(&m, &in, &out);
  }
  in.thr_ref_rad_q16 = target;
  for (k = 1U; (k <= steps) && (first == 0U); k++) {
    (void)canfdi_actmon_step(&m, &in, &out);
    if (out.thr_not_following) {
      first = k;
    }
    if (target > angle) {
      angle = ((target - angle) > d) ? (angle + d) : target;
    } else {
      angle = ((angle - target) > d) ? (angle - d) : target;
    }
    in.thr_angle_rad_q16 = angle;
  }
  return first;
}

/* A healthy valve does not lag a tip-in or tip-out of any size at the
 * slowest slew it has in the envelope (14.6 rad/s on 9 V, 14.6 mrad per
 * step), nor a start-up with the setpoint already at wide open; one
 * stuck at the start of the stroke, or one slower than the expected
 * trajectory (3 rad/s), is not following within ~0.3 s. */
START_TEST(test_tracking_strokes)
{
  ck_assert_uint_eq(stroke(10, 80, 15, false, 3000U), 0U);
  ck_assert_uint_eq(stroke(80, 10, 15, false, 3000U), 0U);
  ck_assert_uint_eq(stroke(1, 88, 15, false, 3000U), 0U);
  ck_assert_uint_eq(stroke(88, 1, 25, false, 3000U), 0U);
  ck_assert_uint_eq(stroke(7, 80, 15, true, 3000U), 0U);
  {
    const uint32_t stuck = stroke(10, 80, 0, false, 3000U);
    ck_assert_uint_gt(stuck, 20U);
    ck_assert_uint_le(stuck, 300U);
  }
  {
    const uint32_t stuck = stroke(80, 10, 0, false, 3000U);
    ck_assert_uint_gt(stuck, 20U);
    ck_assert_uint_le(stuck, 300U);
  }
  {
    const uint32_t slow = stroke(10, 80, 3, false, 3000U);
    ck_assert_uint_gt(slow, 20U);
    ck_assert_uint_le(slow, 400U);
  }
}
END_TEST

/* A pedal blip: the reference leaves 88 deg for 2 deg for 120 ms and
 * returns; the valve (25 rad/s) gets near 2 deg and comes back. Judged
 * from where the valve got to, not from where the slowest trajectory
 * would be: no symptom. The same blip with the valve stuck is one. */
static uint32_t blip(int32_t rate_mrad)
{
  canfdi_actmon_in_t in = healthy();
  canfdi_actmon_out_t out;
  int32_t angle = CANFDI_Q16_DEG(88, 1);
  const int32_t d = CANFDI_Q16_MILLI(rate_mrad);
  uint32_t k;
  uint32_t first = 0U;
  setup();
  for (k = 1U; (k <= 2000U) && (first == 0U); k++) {
    const int32_t ref = ((k >= 100U) && (k < 220U)) ? CANFDI_Q16_DEG(2, 1) : CANFDI_Q16_DEG(88, 1);
    in.thr_ref_rad_q16 = ref;
    in.thr_angle_rad_q16 = angle;
    (void)canfdi_actmon_step(&m, &in, &out);
    if (out.thr_not_following) {
      first = k;
    }
    if (ref > angle) {
      angle = ((ref - angle) > d) ? (angle + d) : ref;
    } else {
      angle = ((angle - ref) > d) ? (angle - d) : ref;
    }
  }
  return first;
}

START_TEST(test_tracking_blip)
{
  ck_assert_uint_eq(blip(25), 0U);
  ck_assert_uint_eq(blip(15), 0U);
  ck_assert_uint_gt(blip(0), 100U);
}
END_TEST

/* Voltage applied, no current: an open motor circuit, at once; not with a
 * small command, not with an invalid current, not when de-energised. */
START_TEST(test_no_current)
{
  canfdi_actmon_in_t in = healthy();
  canfdi_actmon_out_t out;
  setup();
  in.thr_i_A_q16 = CANFDI_Q16_MILLI(10);
  (void)canfdi_actmon_step(&m, &in, &out);
  ck_assert(out.thr_no_current);
  in.thr_u_cmd_V_q16 = -4 * CANFDI_Q16_ONE;
  in.thr_i_A_q16 = -CANFDI_Q16_MILLI(10);
  (void)canfdi_actmon_step(&m, &in, &out);
  ck_assert(out.thr_no_current);
  in.thr_u_cmd_V_q16 = 2 * CANFDI_Q16_ONE;
  (void)canfdi_actmon_step(&m, &in, &out);
  ck_assert(!out.thr_no_current);
  in.thr_u_cmd_V_q16 = 4 * CANFDI_Q16_ONE;
  in.thr_i_valid = false;
  (void)canfdi_actmon_step(&m, &in, &out);
  ck_assert(!out.thr_no_current);
  in.thr_i_valid = true;
  in.thr_enabled = false;
  (void)canfdi_actmon_step(&m, &in, &out);
  ck_assert(!out.thr_no_current);
  ck_assert_uint_eq(canfdi_actmon_diag(&m).no_current_steps, 2U);
}
END_TEST

/* UAC: a 2 V offset on U_A reads 4.0 (threshold 0.5 V) after the filter has
 * settled (alpha 1/8: within 1 % after 40 steps), with its sign; judged
 * only while the bridge drives unclamped; the filter holds otherwise. */
START_TEST(test_uac)
{
  canfdi_actmon_in_t in = healthy();
  canfdi_actmon_out_t out;
  uint32_t k;
  int32_t held;
  setup();
  in.dcm_ua_V_q16 = in.dcm_u_cmd_V_q16 - (2 * CANFDI_Q16_ONE);
  for (k = 0U; k < 60U; k++) {
    (void)canfdi_actmon_step(&m, &in, &out);
  }
  ck_assert(out.dcm_uac_valid);
  ck_assert_int_lt(out.dcm_uac_rn_q16, -CANFDI_Q16_MILLI(3960));
  ck_assert_int_ge(out.dcm_uac_rn_q16, -4 * CANFDI_Q16_ONE);
  held = out.dcm_uac_rn_q16;
  /* command near the supply: the bridge may clamp, not judged */
  in.dcm_u_cmd_V_q16 = 47 * CANFDI_Q16_ONE;
  in.dcm_ua_V_q16 = 0;
  (void)canfdi_actmon_step(&m, &in, &out);
  ck_assert(!out.dcm_uac_valid);
  ck_assert_int_eq(out.dcm_uac_rn_q16, 0);
  in = healthy();
  in.dcm_bridge_settled = false;
  (void)canfdi_actmon_step(&m, &in, &out);
  ck_assert(!out.dcm_uac_valid);
  in.dcm_bridge_settled = true;
  in.dcm_ua_valid = false;
  (void)canfdi_actmon_step(&m, &in, &out);
  ck_assert(!out.dcm_uac_valid);
  in.dcm_ua_valid = true;
  in.dcm_enabled = false;
  (void)canfdi_actmon_step(&m, &in, &out);
  ck_assert(!out.dcm_uac_valid);
  /* judged again: the filter continues from where it was held */
  in = healthy();
  in.dcm_ua_V_q16 = in.dcm_u_cmd_V_q16 - (2 * CANFDI_Q16_ONE);
  (void)canfdi_actmon_step(&m, &in, &out);
  ck_assert(out.dcm_uac_valid);
  ck_assert_int_le(out.dcm_uac_rn_q16, held); /* one more step toward -4.0 */
  ck_assert_int_gt(out.dcm_uac_rn_q16, held - CANFDI_Q16_MILLI(2));
}
END_TEST

START_TEST(test_bad_arguments)
{
  canfdi_actmon_in_t in = healthy();
  canfdi_actmon_out_t out;
  canfdi_actmon_cfg_t bad;
  canfdi_actmon_default_cfg(&bad);
  bad.track_alpha_q16 = 0;
  ck_assert_int_eq(canfdi_actmon_init(&m, &bad), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_actmon_step(&m, &in, &out), -CANFDI_EINVAL);
  ck_assert(!out.thr_not_following && !out.thr_no_current && !out.dcm_uac_valid);
  canfdi_actmon_default_cfg(&bad);
  bad.uac_alpha_q16 = CANFDI_Q16_ONE + 1;
  ck_assert_int_eq(canfdi_actmon_init(&m, &bad), -CANFDI_EINVAL);
  canfdi_actmon_default_cfg(&bad);
  bad.uac_thr_V_q16 = 0;
  ck_assert_int_eq(canfdi_actmon_init(&m, &bad), -CANFDI_EINVAL);
  canfdi_actmon_default_cfg(&bad);
  bad.track_slew_rad_q16 = 0;
  ck_assert_int_eq(canfdi_actmon_init(&m, &bad), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_actmon_init(&m, NULL), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_actmon_init(NULL, &cfg), -CANFDI_EINVAL);
  setup();
  ck_assert_int_eq(canfdi_actmon_step(&m, NULL, &out), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_actmon_step(&m, &in, NULL), -CANFDI_EINVAL);
  ck_assert_uint_eq(canfdi_actmon_diag(&m).rejected, 2U);
  ck_assert_uint_eq(canfdi_actmon_diag(NULL).steps, 0U);
  /* extreme inputs saturate, never wrap */
  in.thr_angle_rad_q16 = INT32_MAX;
  in.thr_ref_rad_q16 = INT32_MIN;
  in.dcm_ua_V_q16 = INT32_MIN;
  for (uint32_t k = 0U; k < 3000U; k++) {
    ck_assert_int_eq(canfdi_actmon_step(&m, &in, &out), CANFDI_OK);
    ck_assert_int_ge(out.thr_track_err_rad_q16, 0);
  }
  ck_assert(out.thr_not_following);
  ck_assert_int_lt(out.dcm_uac_rn_q16, 0);
}
END_TEST

static Suite *make_suite(void)
{
  Suite *s = suite_create("actmon");
  TCase *tc = tcase_create("monitors");
  tcase_add_test(tc, test_healthy_no_symptom);
  tcase_add_test(tc, test_tracking);
  tcase_add_test(tc, test_tracking_strokes);
  tcase_add_test(tc, test_tracking_blip);
  tcase_add_test(tc, test_no_current);
  tcase_add_test(tc, test_uac);
  suite_add_tcase(s, tc);
  tc = tcase_create("errors");
  tcase_add_test(tc, test_bad_arguments);
  suite_add_tcase(s, tc);
  return s;
}

CANFDI_UNIT_MAIN(make_suite)
