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
#include "comm/canfdi_e2e.h"
#include "gen/canfdi_sim_msg.h"
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
  cal.tps1.slope_V_rad_q16 = -cal.tps1.slope_V_rad_q16;
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

/* The throttle's matching slot per diag_period_steps (canfdi_app.h): the
 * first from period * 2 / 5 on that is not the DC motor's and holds no
 * update of a locked estimator (the DC motor's two of every five, on
 * slots 1 and 2 of five; the throttle's mechanical one, on the odd
 * slots), else the DC motor's slot 0. */
START_TEST(test_matching_slots)
{
  static const uint8_t want[11] = {0U, 0U, 0U, 1U, 2U, 3U, 2U, 2U, 4U, 3U, 4U};
  uint8_t p;
  for (p = 1U; p <= CANFDI_APP_FRAME_SLOTS; p++) {
    const uint8_t dd = 5U;
    const uint8_t dt = 2U;
    const uint8_t s = want[p];
    canfdi_app_default_cal(&cal);
    ck_assert_uint_eq(cal.est_dcm.decim, dd);
    ck_assert_uint_eq(cal.est_thr.decim, dt);
    cal.diag_period_steps = p;
    ck_assert_int_eq(canfdi_app_init(&app, &cal, 0U), CANFDI_OK);
    ck_assert_msg(app.slot_diag_thr == s, "period %u: slot %u, not %u", p, app.slot_diag_thr, s);
    ck_assert_uint_lt(s, p);
    if (s != CANFDI_APP_SLOT_DIAG) {
      ck_assert_msg(((p % dt) != 0U) || ((s % dt) == 0U), "period %u: the throttle's mechanical update", p);
      ck_assert_msg(((p % dd) != 0U) || (((s % dd) != 1U) && ((s % dd) != 2U)), "period %u: the DC motor's", p);
    }
  }
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

/* No sensor frame ever arrives: during the first-reception window
 * (cal.rx.first_timeout_us) no U-code and the drives are held off; after it
 * both U-codes fail, the DC motor goes fail-safe with the drive off, and
 * the throttle (no valid position) is de-energised. */
START_TEST(test_no_sensor_frames)
{
  canfdi_tx_frame_t out[CANFDI_APP_MAX_TX];
  uint32_t k;
  int32_t st;
  canfdi_app_default_cal(&cal);
  ck_assert_int_eq(canfdi_app_init(&app, &cal, 0U), CANFDI_OK);
  ck_assert_uint_ge(cal.rx.first_timeout_us, 100000U);
  for (k = 1U; k < (cal.rx.first_timeout_us / 1000U); k++) {
    ck_assert_int_ge(canfdi_app_step(&app, k * 1000U, out), 2);
    ck_assert_uint_eq(canfdi_dtc_count_by_mask(canfdi_app_dtc(&app), (uint8_t)CANFDI_DTC_ST_TF), 0U);
    ck_assert(!app.fb.mgr.dcm.enable);
    ck_assert(!app.fb.mgr.thr.enable);
  }
  for (; k <= (cal.rx.first_timeout_us / 1000U) + 200U; k++) {
    ck_assert_int_ge(canfdi_app_step(&app, k * 1000U, out), 2);
  }
  st = canfdi_dtc_status(canfdi_app_dtc(&app),
                         (uint8_t)canfdi_dtc_find(canfdi_app_dtc(&app), CANFDI_DTC_U1A00));
  ck_assert_int_ge(st, 0);
  ck_assert_uint_ne((uint32_t)st & CANFDI_DTC_ST_TF, 0U);
  st = canfdi_dtc_status(canfdi_app_dtc(&app),
                         (uint8_t)canfdi_dtc_find(canfdi_app_dtc(&app), CANFDI_DTC_U1A01));
  ck_assert_uint_ne((uint32_t)st & CANFDI_DTC_ST_TF, 0U);
  ck_assert(!app.fb.mgr.dcm.enable);
  ck_assert_uint_eq(app.fb.mgr.dcm_state, CANFDI_DEG_FAIL_SAFE);
  ck_assert(!app.fb.mgr.thr.enable);
  ck_assert_uint_eq(app.fb.mgr.thr_state, CANFDI_DEG_FAIL_SAFE);
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

/* Little-endian unsigned field of an 8-byte frame (the DBC's @1+). */
static uint32_t field_le(const canfdi_tx_frame_t *f, unsigned start, unsigned len)
{
  uint64_t v = 0U;
  for (unsigned i = 0U; i < 8U; i++) {
    v |= (uint64_t)f->data[i] << (8U * i);
  }
  return (uint32_t)((v >> start) & ((UINT64_C(1) << len) - 1U));
}

/* EcuSelfDiag goes out every 100 ms (first at step 13 after init) with the
 * supervisor's counters, counting frames up to the step that sends it: one
 * DcmSensor with a wrong length raises SdgFramesRejected by exactly 1, one
 * unknown identifier SdgFramesUnknown by exactly 1. */
START_TEST(test_self_diag_frame)
{
  canfdi_tx_frame_t out[CANFDI_APP_MAX_TX];
  uint8_t d[8];
  uint32_t k;
  uint32_t n_sdg = 0U;
  uint32_t last_k = 0U;
  uint32_t rej[10];
  uint32_t unk[10];
  memset(d, 0, sizeof d);
  canfdi_app_default_cal(&cal);
  ck_assert_int_eq(canfdi_app_init(&app, &cal, 0U), CANFDI_OK);
  for (k = 1U; k <= 1000U; k++) {
    int32_t n;
    if (k == 114U) { /* just before the second EcuSelfDiag */
      ck_assert_int_eq(canfdi_app_rx_frame(&app, 0x010U, d, 7U, k * 1000U), CANFDI_RX_BAD_LENGTH);
      ck_assert_int_eq(canfdi_app_rx_frame(&app, 0x7FFU, d, 8U, k * 1000U), CANFDI_RX_UNKNOWN_ID);
    }
    if (k == 514U) { /* two unknown ids (one a flagged/extended value) */
      ck_assert_int_eq(canfdi_app_rx_frame(&app, 0x123U, d, 8U, k * 1000U), CANFDI_RX_UNKNOWN_ID);
      ck_assert_int_eq(canfdi_app_rx_frame(&app, 0x80000010U, d, 8U, k * 1000U),
                       CANFDI_RX_UNKNOWN_ID);
    }
    n = canfdi_app_step(&app, k * 1000U, out);
    ck_assert_int_le(n, (int32_t)CANFDI_APP_MAX_TX);
    for (int32_t i = 0; i < n; i++) {
      if (out[i].id == 0x302U) {
        ck_assert_uint_eq(out[i].dlc, 8U);
        ck_assert_uint_eq(k % 100U, 14U);
        ck_assert(n_sdg < 10U);
        if (n_sdg > 0U) {
          ck_assert_uint_eq(k - last_k, 100U);
        }
        rej[n_sdg] = field_le(&out[i], 0U, 16U);
        unk[n_sdg] = field_le(&out[i], 16U, 16U);
        ck_assert_uint_eq(field_le(&out[i], 48U, 8U), canfdi_app_diag(&app)->estimator_resets);
        ck_assert_uint_eq(field_le(&out[i], 56U, 8U),
                          canfdi_app_diag(&app)->dtc_reports_rejected);
        last_k = k;
        n_sdg++;
      }
    }
  }
  ck_assert_uint_eq(n_sdg, 10U);
  ck_assert_uint_eq(rej[0], 0U);
  ck_assert_uint_eq(unk[0], 0U);
  ck_assert_uint_eq(rej[1], rej[0] + 1U);
  ck_assert_uint_eq(unk[1], unk[0] + 1U);
  ck_assert_uint_eq(rej[5], rej[1]);
  ck_assert_uint_eq(unk[5], unk[4] + 2U);
  ck_assert_uint_eq(unk[9], 3U);
  ck_assert_uint_eq(canfdi_app_diag(&app)->frames_unknown, 3U);
}
END_TEST

/* The counters saturate at their field's maximum (and count it). */
START_TEST(test_self_diag_saturates)
{
  static canfdi_tx_t tx;
  const canfdi_tx_self_diag_t v = {70000U, UINT32_MAX, 65535U, 256U, 1000U};
  canfdi_tx_frame_t f;
  ck_assert_int_eq(canfdi_tx_init(&tx), CANFDI_OK);
  ck_assert_int_eq(canfdi_tx_encode_self_diag(&tx, &v, &f), CANFDI_OK);
  ck_assert_uint_eq(f.id, 0x302U);
  ck_assert_uint_eq(field_le(&f, 0U, 16U), 65535U);
  ck_assert_uint_eq(field_le(&f, 16U, 16U), 65535U);
  ck_assert_uint_eq(field_le(&f, 32U, 16U), 65535U);
  ck_assert_uint_eq(field_le(&f, 48U, 8U), 255U);
  ck_assert_uint_eq(field_le(&f, 56U, 8U), 255U);
  ck_assert_uint_eq(tx.diag.saturations, 4U);
  ck_assert_int_eq(canfdi_tx_encode_self_diag(&tx, NULL, &f), -CANFDI_EINVAL);
}
END_TEST

/* Port timing: the maximum since the last EcuStatus goes out in the next
 * one (StsStepTimeMax bits 41..51, StsCycleTimeMax 52..62, in 2 us units),
 * then a new maximum starts; never reported (SIL, lockstep): 0. */
START_TEST(test_port_timing)
{
  canfdi_tx_frame_t out[CANFDI_APP_MAX_TX];
  uint32_t k;
  uint32_t n_sts = 0U;
  canfdi_app_default_cal(&cal);
  ck_assert_int_eq(canfdi_app_init(&app, &cal, 0U), CANFDI_OK);
  canfdi_app_port_timing(NULL, 1U, 1U);
  for (k = 1U; k <= 304U; k++) {
    const int32_t n = canfdi_app_step(&app, k * 1000U, out);
    for (int32_t i = 0; i < n; i++) {
      if (out[i].id == 0x300U) {
        const uint32_t step = 2U * field_le(&out[i], 41U, 11U);
        const uint32_t cycle = 2U * field_le(&out[i], 52U, 11U);
        ck_assert_uint_eq(k % 100U, 4U);
        if (k == 104U) {
          ck_assert_uint_eq(step, 250U);
          ck_assert_uint_eq(cycle, 1500U);
        } else if (k == 304U) {
          ck_assert_uint_eq(step, 4094U); /* saturated */
          ck_assert_uint_eq(cycle, 1000U);
        } else {
          ck_assert_uint_eq(step, 0U);
          ck_assert_uint_eq(cycle, 0U);
        }
        n_sts++;
      }
    }
    if (k == 50U) {
      canfdi_app_port_timing(&app, 250U, 1000U);
    } else if (k == 60U) {
      canfdi_app_port_timing(&app, 120U, 1500U);
    } else if (k == 250U) {
      canfdi_app_port_timing(&app, 9000U, 1000U);
    } else {
      /* not reported */
    }
  }
  ck_assert_uint_eq(n_sts, 4U);
}
END_TEST

/* SetpointDcm with raw speed and load, packed by the generated codec and
 * E2E protected in its own sequence (sp_e2e, started by the test). */
static canfdi_e2e_tx_t sp_e2e;

static void send_sp_dcm(int16_t speed_raw, int16_t load_raw, uint32_t now_us)
{
  uint8_t d[8];
  struct canfdi_sim_msg_setpoint_dcm_t m;
  memset(&m, 0, sizeof m);
  m.sp_dcm_speed = speed_raw;
  m.sp_dcm_load = load_raw;
  ck_assert_int_eq(canfdi_sim_msg_setpoint_dcm_pack(d, &m, 8U), 8);
  ck_assert_int_eq(canfdi_e2e_protect(&sp_e2e, d, 8U), CANFDI_OK);
  (void)canfdi_app_rx_frame(&app, 0x100U, d, 8U, now_us);
}

/* The load the models get: the estimator's known offset from the nominal
 * load (0 = nominal), within 1 LSB of the 0.001 N m raw value. */
static int32_t dload_q16(void) { return app.est_dcm.dload_q16; }

/* The vehicle's load feed-forward reaches the models; before the first
 * frame, after a timeout (50 ms) and when out of range (+-10 N m) the
 * nominal load stands in, and a rejected load does not cost the speed. */
START_TEST(test_load_feed_forward)
{
  canfdi_tx_frame_t out[CANFDI_APP_MAX_TX];
  int32_t d07;
  uint32_t k;
  canfdi_app_default_cal(&cal);
  d07 = (int32_t)((700 * 65536 + 500) / 1000) - cal.load_nom_Nm_q16;
  ck_assert_int_eq(canfdi_app_init(&app, &cal, 0U), CANFDI_OK);
  canfdi_e2e_tx_init(&sp_e2e, 0x100U);
  ck_assert_int_eq(canfdi_app_step(&app, 1000U, out) >= 2, 1);
  ck_assert_int_eq(dload_q16(), 0);
  for (k = 2U; k <= 100U; k++) {
    if ((k % 10U) == 0U) {
      send_sp_dcm(2500, 700, k * 1000U); /* 50 rad/s, 0.7 N m */
    }
    (void)canfdi_app_step(&app, k * 1000U, out);
  }
  ck_assert_uint_eq(app.rx.in[CANFDI_RX_IN_SP_DCM_LOAD].quality, CANFDI_RX_VALID);
  ck_assert_int_le(abs(dload_q16() - d07), 1);
  /* frames stop: nominal after the 50 ms timeout */
  for (k = 101U; k <= 200U; k++) {
    (void)canfdi_app_step(&app, k * 1000U, out);
  }
  ck_assert_uint_eq(app.rx.in[CANFDI_RX_IN_SP_DCM_LOAD].quality, CANFDI_RX_SUBSTITUTED);
  ck_assert_int_eq(dload_q16(), 0);
  /* implausible load (12 N m), plausible speed: load nominal, speed taken */
  send_sp_dcm(-1000, 12000, 201000U);
  (void)canfdi_app_step(&app, 201000U, out);
  ck_assert_int_eq(dload_q16(), 0);
  ck_assert_uint_eq(app.rx.in[CANFDI_RX_IN_SP_DCM_SPEED].quality, CANFDI_RX_VALID);
  ck_assert_int_eq(app.rx.in[CANFDI_RX_IN_SP_DCM_SPEED].value_q16, -20 * 65536);
  /* a plausible load again: taken at once (setpoints recover after 1) */
  send_sp_dcm(-1000, -300, 202000U);
  (void)canfdi_app_step(&app, 202000U, out);
  ck_assert_int_le(abs(dload_q16() - ((int32_t)((-300 * 65536 - 500) / 1000) - cal.load_nom_Nm_q16)), 1);
}
END_TEST

static Suite *make_suite(void)
{
  Suite *s = suite_create("app");
  TCase *tc = tcase_create("ports");
  tcase_add_test(tc, test_init_args);
  tcase_add_test(tc, test_matching_slots);
  tcase_add_test(tc, test_output_schedule);
  suite_add_tcase(s, tc);
  tc = tcase_create("supervision");
  tcase_add_test(tc, test_no_sensor_frames);
  tcase_add_test(tc, test_self_diagnostics);
  tcase_add_test(tc, test_self_diag_frame);
  tcase_add_test(tc, test_self_diag_saturates);
  tcase_add_test(tc, test_port_timing);
  tcase_add_test(tc, test_load_feed_forward);
  suite_add_tcase(s, tc);
  return s;
}

CANFDI_UNIT_MAIN(make_suite)
