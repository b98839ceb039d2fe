/*
 * test_app_out.c — the output frames of a step (app/canfdi_app_out.h):
 * on-change and cyclic EcuDtc frames, the EcuStatus port timing that
 * starts anew after each frame, and the actuator frames every step. Frames
 * are decoded with the tester codec generated from the DBC.
 */
#include <check.h>
#include <string.h>

#include "app/canfdi_app_out.h"
#include "canfdi_sil_msg.h"
#include "core/canfdi_qconst.h"
#include "unit_main.h"

static canfdi_app_out_t o;
static canfdi_tx_t tx;
static canfdi_dtc_t dtc;
static canfdi_parity_dcm_t pd;
static canfdi_parity_thr_t pt;
static canfdi_est_dcm_t ed;
static canfdi_est_thr_t et;
static canfdi_diagnosis_t dg;
static canfdi_actmgr_out_t mgr;
static canfdi_app_out_src_t src;

static void setup(void)
{
  canfdi_parity_dcm_cfg_t pdc;
  canfdi_parity_thr_cfg_t ptc;
  canfdi_est_dcm_cfg_t edc;
  canfdi_est_thr_cfg_t etc;
  canfdi_diagnosis_cfg_t dgc;
  canfdi_parity_dcm_default_cfg(&pdc);
  canfdi_parity_thr_default_cfg(&ptc);
  canfdi_est_dcm_default_cfg(&edc);
  canfdi_est_thr_default_cfg(&etc);
  canfdi_diagnosis_default_cfg(&dgc);
  ck_assert_int_eq(canfdi_parity_dcm_init(&pd, &pdc), CANFDI_OK);
  ck_assert_int_eq(canfdi_parity_thr_init(&pt, &ptc), CANFDI_OK);
  ck_assert_int_eq(canfdi_est_dcm_init(&ed, &edc), CANFDI_OK);
  ck_assert_int_eq(canfdi_est_thr_init(&et, &etc), CANFDI_OK);
  ck_assert_int_eq(canfdi_diagnosis_init(&dg, &dgc), CANFDI_OK);
  ck_assert_int_eq(canfdi_dtc_init(&dtc, canfdi_dtc_defaults, (uint8_t)CANFDI_DTC_COUNT), CANFDI_OK);
  ck_assert_int_eq(canfdi_dtc_cycle_start(&dtc), CANFDI_OK);
  ck_assert_int_eq(canfdi_tx_init(&tx), CANFDI_OK);
  canfdi_app_out_init(&o, &dtc);
  memset(&mgr, 0, sizeof mgr);
  mgr.dcm.enable = true;
  mgr.dcm.bridge = CANFDI_ACTMGR_BRIDGE_A;
  mgr.dcm.u_cmd_V_q16 = 12 * CANFDI_Q16_ONE;
  memset(&src, 0, sizeof src);
  src.mgr = &mgr;
  src.parity_dcm = &pd;
  src.parity_thr = &pt;
  src.est_dcm = &ed;
  src.est_thr = &et;
  src.diagnosis = &dg;
  src.dtc = &dtc;
}

static void fail_code(uint32_t code)
{
  canfdi_dtc_ff_t ff;
  memset(&ff, 0, sizeof ff);
  /* returns the status byte (>= 0) */
  ck_assert_int_ge(canfdi_dtc_report(&dtc, (uint8_t)canfdi_dtc_find(&dtc, code), CANFDI_DEB_REPORT_FAILED, &ff), 0);
}

static void pass_code(uint32_t code)
{
  canfdi_dtc_ff_t ff;
  memset(&ff, 0, sizeof ff);
  ck_assert_int_ge(canfdi_dtc_report(&dtc, (uint8_t)canfdi_dtc_find(&dtc, code), CANFDI_DEB_REPORT_PASSED, &ff), 0);
}

typedef struct {
  uint32_t cyclic[64];
  unsigned n_cyclic;
  uint32_t change[64];
  unsigned n_change;
  unsigned n_status;
} seen_t;

static void run(uint32_t steps, seen_t *s)
{
  uint32_t k;
  memset(s, 0, sizeof *s);
  for (k = 0U; k < steps; k++) {
    canfdi_tx_frame_t out[CANFDI_TX_MAX_FRAMES_PER_STEP];
    const int32_t n = canfdi_app_out_step(&o, &tx, &src, out);
    int32_t i;
    ck_assert_int_ge(n, 2);
    ck_assert_uint_eq(out[0].id, CANFDI_SIL_MSG_DCM_ACTUATOR_FRAME_ID);
    for (i = 0; i < n; i++) {
      struct canfdi_sil_msg_ecu_dtc_t m;
      if (out[i].id == CANFDI_SIL_MSG_ECU_STATUS_FRAME_ID) {
        s->n_status++;
      }
      if ((out[i].id != CANFDI_SIL_MSG_ECU_DTC_FRAME_ID) ||
          (canfdi_sil_msg_ecu_dtc_unpack(&m, out[i].data, out[i].dlc) != 0)) {
        continue;
      }
      if ((m.dtc_tx_reason != 0U) && (s->n_change < 64U)) {
        s->change[s->n_change++] = m.dtc_code;
      } else if ((m.dtc_tx_reason == 0U) && (s->n_cyclic < 64U)) {
        s->cyclic[s->n_cyclic++] = m.dtc_code;
      }
    }
  }
}

/* Each status change goes out once, on change; the cyclic frame rotates
 * over the stored codes in table order. */
START_TEST(test_dtc_frames)
{
  seen_t s;
  setup();
  run(300U, &s);
  ck_assert_uint_eq(s.n_change, 0U);
  ck_assert_uint_eq(s.n_cyclic, 3U);
  ck_assert_uint_eq(s.cyclic[0], 0U); /* nothing stored: code 0 */
  fail_code(CANFDI_DTC_P0122);
  fail_code(CANFDI_DTC_P1A20);
  run(600U, &s);
  ck_assert_uint_eq(s.n_change, 2U);
  ck_assert_uint_eq(s.change[0], CANFDI_DTC_P0122); /* table order */
  ck_assert_uint_eq(s.change[1], CANFDI_DTC_P1A20);
  ck_assert_uint_eq(s.n_cyclic, 6U);
  for (unsigned i = 0U; i < 6U; i++) {
    ck_assert_uint_eq(s.cyclic[i], ((o.rr_frames - 6U + i) % 2U == 0U) ? CANFDI_DTC_P0122 : CANFDI_DTC_P1A20);
  }
  ck_assert_uint_eq(o.diag.dtc_events, 2U);
}
END_TEST

/* More changes in one step than the queue holds (it sends one a step):
 * every change goes out, once, in the next steps; a change undone before
 * its turn is not sent. */
START_TEST(test_dtc_burst_not_lost)
{
  seen_t s;
  const unsigned n = 12U; /* > CANFDI_CFG_TX_DTC_QUEUE */
  unsigned i;
  unsigned k;
  setup();
  run(10U, &s);
  for (i = 0U; i < n; i++) {
    fail_code(dtc.table[i].dtc);
  }
  run(1U, &s);
  ck_assert_uint_ge(o.diag.dtc_queue_full, 1U); /* the rest wait */
  run(100U, &s);
  ck_assert_uint_eq(s.n_change, n - 1U); /* the first went out in the step before */
  for (i = 1U; i < n; i++) {
    unsigned hits = 0U;
    for (k = 0U; k < s.n_change; k++) {
      hits += (s.change[k] == dtc.table[i].dtc) ? 1U : 0U;
    }
    ck_assert_msg(hits == 1U, "code %06x sent %u times", dtc.table[i].dtc, hits);
  }
  ck_assert_uint_eq(o.diag.dtc_events, n);
  /* a second burst (passes: no storage, no displacement); after one step
   * 8 are queued (one of them sent) and 4 wait; then the tester clears:
   * the queued ones go out as they were queued, then every code whose
   * status is no longer the one sent (the first burst's 12 and the 8
   * queued); the 4 waiting are back to the status sent and never go out */
  for (i = 0U; i < n; i++) {
    pass_code(dtc.table[n + i].dtc);
  }
  run(1U, &s);
  ck_assert_uint_eq(s.n_change, 1U);
  ck_assert(o.dtc_behind);
  ck_assert_int_eq(canfdi_dtc_clear(&dtc, CANFDI_DTC_GROUP_ALL), CANFDI_OK);
  run(100U, &s);
  ck_assert_uint_eq(s.n_change, (CANFDI_CFG_TX_DTC_QUEUE - 1U) + n + CANFDI_CFG_TX_DTC_QUEUE);
  for (k = 0U; k < s.n_change; k++) {
    for (i = n + CANFDI_CFG_TX_DTC_QUEUE; i < (2U * n); i++) {
      ck_assert_uint_ne(s.change[k], dtc.table[i].dtc);
    }
  }
  ck_assert(!o.dtc_behind);
}
END_TEST

/* While the queue is full, a code that changes in every step does not
 * hold back the others: its changes and theirs go out in turn (round
 * robin from one after the last queued), each waiting change within a
 * pass over the codes. */
START_TEST(test_dtc_changes_take_turns)
{
  seen_t s;
  const unsigned n = 12U;
  unsigned i;
  unsigned k;
  unsigned flaps = 0U;
  bool seen_last = false;
  setup();
  run(10U, &s);
  for (i = 0U; i < n; i++) {
    fail_code(dtc.table[i].dtc);
  }
  /* code 0 changes every step (failed, passed, failed, ...) while the
   * burst waits: before, the lowest index was looked at first every step */
  for (k = 0U; k < 40U; k++) {
    if ((k % 2U) == 0U) {
      pass_code(dtc.table[0].dtc);
    } else {
      fail_code(dtc.table[0].dtc);
    }
    run(1U, &s);
    for (i = 0U; i < s.n_change; i++) {
      flaps += (s.change[i] == dtc.table[0].dtc) ? 1U : 0U;
      seen_last = seen_last || (s.change[i] == dtc.table[n - 1U].dtc);
    }
  }
  ck_assert_msg(seen_last, "the last code of the burst never went out in 40 steps");
  ck_assert_uint_ge(flaps, 2U); /* the flapping code goes out too */
}
END_TEST

/* A memory loaded before the first step is announced; the composer
 * initialised after the load would not. */
START_TEST(test_loaded_memory_announced)
{
  seen_t s;
  setup();
  fail_code(CANFDI_DTC_P0222);
  run(10U, &s);
  ck_assert_uint_eq(s.n_change, 1U);
  ck_assert_uint_eq(s.change[0], CANFDI_DTC_P0222);
}
END_TEST

/* EcuStatus carries the largest port timing since the previous one, then
 * starts anew. */
START_TEST(test_port_timing)
{
  seen_t s;
  setup();
  canfdi_app_out_port_timing(&o, 300U, 1000U);
  canfdi_app_out_port_timing(&o, 120U, 1700U);
  ck_assert_uint_eq(o.step_time_max_us, 300U);
  ck_assert_uint_eq(o.cycle_time_max_us, 1700U);
  run(100U, &s);
  ck_assert_uint_eq(s.n_status, 1U);
  ck_assert_uint_eq(o.step_time_max_us, 0U);
  ck_assert_uint_eq(o.cycle_time_max_us, 0U);
}
END_TEST

static Suite *make_suite(void)
{
  Suite *s = suite_create("app_out");
  TCase *tc = tcase_create("frames");
  tcase_add_test(tc, test_dtc_frames);
  tcase_add_test(tc, test_dtc_burst_not_lost);
  tcase_add_test(tc, test_dtc_changes_take_turns);
  tcase_add_test(tc, test_loaded_memory_announced);
  tcase_add_test(tc, test_port_timing);
  suite_add_tcase(s, tc);
  return s;
}

CANFDI_UNIT_MAIN(make_suite)
