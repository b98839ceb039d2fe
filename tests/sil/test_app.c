/*
 * test_app.c — unit tests of the application loop (firmware/app/canfdi_app.h)
 * without plants: the frame ports, the output schedule, the reaction to lost
 * inputs and the self-diagnostics. The closed-loop behaviour is tested by
 * the SIL scenarios (tests/sil/scenarios).
 */
#include <check.h>
#include <stdlib.h>
#include <string.h>

#include "app/canfdi_app.h"
#include "unit_main.h"

static canfdi_app_t app; /* ~9 kB: static, as on a target */
static canfdi_app_cal_t cal;

START_TEST(test_init_args)
{
  canfdi_tx_frame_t out[CANFDI_APP_MAX_TX];
  canfdi_app_default_cal(&cal);
  ck_assert_int_eq(canfdi_app_init(NULL, &cal, 0U), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_app_init(&app, NULL, 0U), -CANFDI_EINVAL);
  /* a module must refuse its part of the calibration, and the app with it */
  cal.vote.tps1_rad_per_V_q16 = -cal.vote.tps1_rad_per_V_q16;
  ck_assert_int_eq(canfdi_app_init(&app, &cal, 0U), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_app_step(&app, 1000U, out), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_app_rx_frame(&app, 0x10U, NULL, 0U, 0U), -CANFDI_EINVAL);
  canfdi_app_default_cal(&cal);
  ck_assert_int_eq(canfdi_app_init(&app, &cal, 0U), CANFDI_OK);
  ck_assert_int_eq(canfdi_app_step(&app, 1000U, NULL), -CANFDI_EINVAL);
  ck_assert_ptr_null(canfdi_app_dtc(NULL));
  ck_assert_ptr_null(canfdi_app_diag(NULL));
}
END_TEST

/* Per step: the two actuator frames first; the slow frames at their DBC
 * periods (EcuStatus 100 ms, EcuResidualDcm 10 ms), never more than
 * CANFDI_APP_MAX_TX frames. */
START_TEST(test_output_schedule)
{
  canfdi_tx_frame_t out[CANFDI_APP_MAX_TX];
  uint32_t k;
  uint32_t n_status = 0U;
  uint32_t n_res = 0U;
  canfdi_app_default_cal(&cal);
  ck_assert_int_eq(canfdi_app_init(&app, &cal, 0U), CANFDI_OK);
  for (k = 1U; k <= 1000U; k++) {
    const int32_t n = canfdi_app_step(&app, k * 1000U, out);
    int32_t i;
    ck_assert_int_ge(n, 2);
    ck_assert_int_le(n, (int32_t)CANFDI_APP_MAX_TX);
    ck_assert_uint_eq(out[0].id, 0x020U);
    ck_assert_uint_eq(out[1].id, 0x021U);
    for (i = 0; i < n; i++) {
      ck_assert_uint_eq(out[i].dlc, 8U);
      n_status += (out[i].id == 0x300U) ? 1U : 0U;
      n_res += (out[i].id == 0x200U) ? 1U : 0U;
    }
  }
  ck_assert_uint_eq(n_status, 10U);
  ck_assert_uint_eq(n_res, 100U);
  ck_assert_uint_eq(canfdi_app_diag(&app)->steps, 1000U);
}
END_TEST

/* No sensor frame ever arrives: after the startup timeout both U-codes
 * fail, the DC motor goes fail-safe with the drive off, and the throttle
 * (no valid position) is de-energised. */
START_TEST(test_no_sensor_frames)
{
  canfdi_tx_frame_t out[CANFDI_APP_MAX_TX];
  uint32_t k;
  int32_t st;
  canfdi_app_default_cal(&cal);
  ck_assert_int_eq(canfdi_app_init(&app, &cal, 0U), CANFDI_OK);
  for (k = 1U; k <= 200U; k++) {
    ck_assert_int_ge(canfdi_app_step(&app, k * 1000U, out), 2);
  }
  st = canfdi_dtc_status(canfdi_app_dtc(&app),
                         (uint8_t)canfdi_dtc_find(canfdi_app_dtc(&app), CANFDI_DTC_U1A00));
  ck_assert_int_ge(st, 0);
  ck_assert_uint_ne((uint32_t)st & CANFDI_DTC_ST_TF, 0U);
  st = canfdi_dtc_status(canfdi_app_dtc(&app),
                         (uint8_t)canfdi_dtc_find(canfdi_app_dtc(&app), CANFDI_DTC_U1A01));
  ck_assert_uint_ne((uint32_t)st & CANFDI_DTC_ST_TF, 0U);
  ck_assert(!app.mgr_out.dcm.enable);
  ck_assert_uint_eq(app.mgr_out.dcm_state, CANFDI_DEG_FAIL_SAFE);
  ck_assert(!app.mgr_out.thr.enable);
  ck_assert_uint_eq(app.mgr_out.thr_state, CANFDI_DEG_FAIL_SAFE);
  /* a sensor-frame DTC is never confirmed without its monitor failing */
  st = canfdi_dtc_status(canfdi_app_dtc(&app),
                         (uint8_t)canfdi_dtc_find(canfdi_app_dtc(&app), CANFDI_DTC_U1A20));
  ck_assert_uint_eq((uint32_t)st & CANFDI_DTC_ST_TF, 0U);
}
END_TEST

/* Frames the supervision rejects are counted in the self-diagnostics;
 * deadline misses reported by the port too; both only grow. */
START_TEST(test_self_diagnostics)
{
  canfdi_tx_frame_t out[CANFDI_APP_MAX_TX];
  uint8_t d[8];
  uint32_t k;
  memset(d, 0x55, sizeof d);
  canfdi_app_default_cal(&cal);
  ck_assert_int_eq(canfdi_app_init(&app, &cal, 0U), CANFDI_OK);
  for (k = 1U; k <= 10U; k++) {
    /* DcmSensor with a wrong length, ThrSensor with a wrong CRC (0x55...) */
    ck_assert_int_eq(canfdi_app_rx_frame(&app, 0x010U, d, 7U, k * 1000U), CANFDI_RX_BAD_LENGTH);
    ck_assert_int_eq(canfdi_app_rx_frame(&app, 0x011U, d, 8U, k * 1000U), CANFDI_RX_BAD_CRC);
    ck_assert_int_eq(canfdi_app_rx_frame(&app, 0x7FFU, d, 8U, k * 1000U), CANFDI_RX_UNKNOWN_ID);
    ck_assert_int_ge(canfdi_app_step(&app, k * 1000U, out), 2);
  }
  ck_assert_uint_eq(canfdi_app_diag(&app)->frames_rejected, 20U);
  canfdi_app_deadline_miss(&app);
  canfdi_app_deadline_miss(&app);
  canfdi_app_deadline_miss(NULL);
  ck_assert_uint_eq(canfdi_app_diag(&app)->deadline_misses, 2U);
  ck_assert_uint_ge(canfdi_app_diag(&app)->frames_sent, 20U);
}
END_TEST

static Suite *make_suite(void)
{
  Suite *s = suite_create("app");
  TCase *tc = tcase_create("ports");
  tcase_add_test(tc, test_init_args);
  tcase_add_test(tc, test_output_schedule);
  suite_add_tcase(s, tc);
  tc = tcase_create("supervision");
  tcase_add_test(tc, test_no_sensor_frames);
  tcase_add_test(tc, test_self_diagnostics);
  suite_add_tcase(s, tc);
  return s;
}

CANFDI_UNIT_MAIN(make_suite)
