/*
 * test_dtcroute.c — routing of monitor results to trouble codes
 * (diag/canfdi_dtcroute.h) against the product DTC memory: a DTC fed by
 * several faults, the manager's own findings, P2135's persistence, the
 * U-code monitors, the faults latched for the manager, and bad arguments.
 */
#include <check.h>
#include <string.h>

#include "diag/canfdi_diagnosis.h"
#include "diag/canfdi_dtcroute.h"
#include "unit_main.h"

static canfdi_dtc_t dtc;
static canfdi_dtcroute_t r;
static canfdi_dtcroute_cfg_t cfg;
static int8_t report[CANFDI_FAULT_COUNT];
static canfdi_rx_report_t com;
static canfdi_dtc_ff_t ff;

static void setup(void)
{
  ck_assert_int_eq(canfdi_dtc_init(&dtc, canfdi_dtc_defaults, (uint8_t)CANFDI_DTC_COUNT), CANFDI_OK);
  ck_assert_int_eq(canfdi_dtc_cycle_start(&dtc), CANFDI_OK);
  canfdi_dtcroute_default_cfg(&cfg);
  ck_assert_int_eq(canfdi_dtcroute_init(&r, &cfg, &dtc), CANFDI_OK);
  memset(report, 0, sizeof report);
  memset(&com, 0, sizeof com);
  memset(&ff, 0, sizeof ff);
}

static canfdi_dtcroute_in_t in_of(uint32_t mgr, bool corr_ni, bool corr_tested)
{
  canfdi_dtcroute_in_t in;
  in.report = report;
  in.mgr_detected = mgr;
  in.corr_not_isolated = corr_ni;
  in.corr_tested = corr_tested;
  in.com = &com;
  in.ff = &ff;
  return in;
}

static uint8_t status_of(uint32_t code)
{
  const int32_t i = canfdi_dtc_find(&dtc, code);
  ck_assert_int_ge(i, 0);
  return (uint8_t)canfdi_dtc_status(&dtc, (uint8_t)i);
}

/* Every catalogue fault reaches its DTC(s): a FAILED verdict sets
 * testFailed after the DTC's debouncing. */
START_TEST(test_fault_reaches_its_codes)
{
  const uint32_t f = (uint32_t)_i + 1U;
  canfdi_dtcroute_in_t in;
  uint32_t k;
  uint32_t j;
  if (canfdi_catalogue_fault[f].kind == CANFDI_KIND_COMMUNICATION) {
    return; /* the input supervision's monitors: test_com_monitors */
  }
  setup();
  report[f] = CANFDI_DIAG_REPORT_FAILED;
  in = in_of(0U, false, false);
  for (k = 0U; k < 5U; k++) {
    ck_assert_int_eq(canfdi_dtcroute_step(&r, &dtc, &in), 0);
  }
  for (j = 0U; j < CANFDI_CATALOGUE_MAX_DTCS; j++) {
    const uint32_t code = canfdi_catalogue_fault[f].dtc[j];
    if (code != 0U) {
      ck_assert_msg((status_of(code) & CANFDI_DTC_ST_TF) != 0U, "fault %u code %06x", f, code);
    }
  }
}
END_TEST

/* The same verdicts in a steady state are not given twice, but are again
 * as soon as the memory changed: a code cleared by a tester while its
 * fault persists fails again in the next step, and one passing before a
 * new operation cycle passes in it (testNotCompletedThisOperationCycle
 * cleared). */
START_TEST(test_steady_verdicts_after_a_change)
{
  const uint32_t f = CANFDI_FAULT_DCM_IA_SENSOR_OFFSET;
  const uint32_t code = canfdi_catalogue_fault[f].dtc[0];
  const uint32_t g = CANFDI_FAULT_DCM_RA_UP;
  const uint32_t code_g = canfdi_catalogue_fault[g].dtc[0];
  canfdi_dtcroute_in_t in;
  uint32_t k;
  uint32_t reports0;
  setup();
  report[f] = CANFDI_DIAG_REPORT_FAILED;
  report[g] = CANFDI_DIAG_REPORT_PASSED;
  in = in_of(0U, false, false);
  for (k = 0U; k < 3U; k++) {
    ck_assert_int_eq(canfdi_dtcroute_step(&r, &dtc, &in), 0);
  }
  ck_assert_uint_ne(status_of(code) & CANFDI_DTC_ST_TF, 0U);
  reports0 = r.diag.reports;
  ck_assert_int_eq(canfdi_dtcroute_step(&r, &dtc, &in), 0);
  ck_assert_uint_eq(r.diag.reports, reports0 + 2U); /* counted as given */
  ck_assert_int_eq(canfdi_dtc_clear(&dtc, code), CANFDI_OK);
  ck_assert_uint_eq(status_of(code) & CANFDI_DTC_ST_TF, 0U);
  ck_assert_int_eq(canfdi_dtcroute_step(&r, &dtc, &in), 0);
  ck_assert_uint_ne(status_of(code) & CANFDI_DTC_ST_TF, 0U);
  ck_assert_int_eq(canfdi_dtc_cycle_end(&dtc), CANFDI_OK);
  ck_assert_int_eq(canfdi_dtc_cycle_start(&dtc), CANFDI_OK);
  ck_assert_uint_ne(status_of(code_g) & CANFDI_DTC_ST_TNCTOC, 0U);
  ck_assert_int_eq(canfdi_dtcroute_step(&r, &dtc, &in), 0);
  ck_assert_uint_eq(status_of(code_g) & CANFDI_DTC_ST_TNCTOC, 0U);
  ck_assert_uint_ne(status_of(code) & CANFDI_DTC_ST_TFTOC, 0U);
}
END_TEST

/* P0122 is fed by TPS1 open and both-TPS-lost: it fails if either fails,
 * passes only when none fails. */
START_TEST(test_shared_code)
{
  canfdi_dtcroute_in_t in = in_of(0U, false, false);
  setup();
  report[CANFDI_FAULT_THR_TPS1_OPEN] = CANFDI_DIAG_REPORT_PASSED;
  report[CANFDI_FAULT_THR_TPS_BOTH_LOST] = CANFDI_DIAG_REPORT_FAILED;
  (void)canfdi_dtcroute_step(&r, &dtc, &in);
  ck_assert_uint_ne(status_of(CANFDI_DTC_P0122) & CANFDI_DTC_ST_TF, 0U);
  report[CANFDI_FAULT_THR_TPS_BOTH_LOST] = CANFDI_DIAG_REPORT_NONE;
  (void)canfdi_dtcroute_step(&r, &dtc, &in);
  ck_assert_uint_eq(status_of(CANFDI_DTC_P0122) & CANFDI_DTC_ST_TF, 0U);
}
END_TEST

/* What the manager detected itself fails the fault's code even when the
 * diagnosis passes it. */
START_TEST(test_manager_findings)
{
  canfdi_dtcroute_in_t in = in_of(CANFDI_FAULT_BIT(CANFDI_FAULT_DCM_BRIDGE_A_DEAD), false, false);
  const uint32_t code = canfdi_catalogue_fault[CANFDI_FAULT_DCM_BRIDGE_A_DEAD].dtc[0];
  setup();
  report[CANFDI_FAULT_DCM_BRIDGE_A_DEAD] = CANFDI_DIAG_REPORT_PASSED;
  (void)canfdi_dtcroute_step(&r, &dtc, &in);
  ck_assert_uint_ne(status_of(code) & CANFDI_DTC_ST_TF, 0U);
}
END_TEST

/* P2135: FAILED only after p2135_steps consecutive unisolated steps; a
 * valid, undisturbed correlation channel passes it and restarts the count;
 * an invalid one neither passes nor restarts. */
START_TEST(test_p2135_persistence)
{
  canfdi_dtcroute_in_t ni = in_of(0U, true, true);
  canfdi_dtcroute_in_t ok = in_of(0U, false, true);
  canfdi_dtcroute_in_t untested = in_of(0U, false, false);
  uint32_t k;
  setup();
  for (k = 0U; k < cfg.p2135_steps; k++) {
    (void)canfdi_dtcroute_step(&r, &dtc, &ni);
  }
  ck_assert_uint_eq(status_of(CANFDI_DTC_P2135) & CANFDI_DTC_ST_TF, 0U);
  (void)canfdi_dtcroute_step(&r, &dtc, &untested);
  (void)canfdi_dtcroute_step(&r, &dtc, &ni);
  ck_assert_uint_ne(status_of(CANFDI_DTC_P2135) & CANFDI_DTC_ST_TF, 0U);
  (void)canfdi_dtcroute_step(&r, &dtc, &ok);
  ck_assert_uint_eq(status_of(CANFDI_DTC_P2135) & CANFDI_DTC_ST_TF, 0U);
  ck_assert_uint_eq(r.p2135_n, 0U);
  for (k = 0U; k < cfg.p2135_steps - 1U; k++) {
    (void)canfdi_dtcroute_step(&r, &dtc, &ni);
  }
  (void)canfdi_dtcroute_step(&r, &dtc, &ok);
  ck_assert_uint_eq(status_of(CANFDI_DTC_P2135) & CANFDI_DTC_ST_TF, 0U);
}
END_TEST

/* U-code monitors: PREFAILED reports debounce up to testFailed; monitors
 * of the setpoints report to U1A50 / U1A51. */
START_TEST(test_com_monitors)
{
  canfdi_dtcroute_in_t in = in_of(0U, false, false);
  uint32_t k;
  uint32_t qualified = 0U;
  setup();
  com.prefailed = UINT32_C(1) << CANFDI_RX_MON_DCM_CRC;
  com.prepassed = UINT32_C(1) << CANFDI_RX_MON_DCM_TIMEOUT;
  for (k = 1U; (k <= 100U) && (qualified == 0U); k++) {
    (void)canfdi_dtcroute_step(&r, &dtc, &in);
    if ((status_of(CANFDI_DTC_U1A20) & CANFDI_DTC_ST_TF) != 0U) {
      qualified = k;
    }
  }
  ck_assert_uint_gt(qualified, 1U); /* debounced, not immediate */
  ck_assert_uint_eq(status_of(CANFDI_DTC_U1A00) & CANFDI_DTC_ST_TF, 0U);
  ck_assert_uint_ne(r.com_dtc[CANFDI_RX_MON_THR_LENGTH], CANFDI_DTC_NONE);
  /* the setpoints' monitors: both timeouts to U1A50, the rest to U1A51 */
  for (k = CANFDI_RX_MON_SP_DCM_TIMEOUT; k < CANFDI_RX_MON_COUNT; k++) {
    const bool timeout = (k == CANFDI_RX_MON_SP_DCM_TIMEOUT) || (k == CANFDI_RX_MON_SP_THR_TIMEOUT);
    ck_assert_int_eq(r.com_dtc[k], canfdi_dtc_find(&dtc, timeout ? CANFDI_DTC_U1A50 : CANFDI_DTC_U1A51));
  }
}
END_TEST

/* Monitors that share a code (the setpoints') give its debouncer one
 * report per step, a failure dominating: a bad SetpointThr CRC every step
 * while the other setpoint monitors pass qualifies U1A51 after 3 steps
 * (the frame class: +2 per PREFAILED, threshold 6), exactly as the CRC
 * monitor alone would; reported one by one, the passes (-1 each) would
 * cancel it and it would never qualify. A timeout of one setpoint while
 * the other's passes is U1A50 at once (direct class). */
START_TEST(test_shared_com_code)
{
  canfdi_dtcroute_in_t in = in_of(0U, false, false);
  uint32_t k;
  uint32_t qualified = 0U;
  setup();
  com.prefailed = UINT32_C(1) << CANFDI_RX_MON_SP_THR_CRC;
  com.prepassed = (UINT32_C(1) << CANFDI_RX_MON_SP_DCM_CRC) | (UINT32_C(1) << CANFDI_RX_MON_SP_DCM_COUNTER) |
                  (UINT32_C(1) << CANFDI_RX_MON_SP_DCM_LENGTH) | (UINT32_C(1) << CANFDI_RX_MON_SP_DCM_RANGE) |
                  (UINT32_C(1) << CANFDI_RX_MON_SP_THR_LENGTH) | (UINT32_C(1) << CANFDI_RX_MON_SP_DCM_TIMEOUT) |
                  (UINT32_C(1) << CANFDI_RX_MON_SP_THR_TIMEOUT);
  for (k = 1U; (k <= 20U) && (qualified == 0U); k++) {
    ck_assert_int_eq(canfdi_dtcroute_step(&r, &dtc, &in), 0);
    if ((status_of(CANFDI_DTC_U1A51) & CANFDI_DTC_ST_TF) != 0U) {
      qualified = k;
    }
  }
  ck_assert_uint_eq(qualified, 3U);
  ck_assert_uint_eq(status_of(CANFDI_DTC_U1A50) & CANFDI_DTC_ST_TF, 0U);
  /* the frames come right again: passes heal it, one report per step */
  com.prefailed = 0U;
  com.prepassed |= UINT32_C(1) << CANFDI_RX_MON_SP_THR_CRC;
  for (k = 0U; k < 12U; k++) {
    ck_assert_int_eq(canfdi_dtcroute_step(&r, &dtc, &in), 0);
  }
  ck_assert_uint_eq(status_of(CANFDI_DTC_U1A51) & CANFDI_DTC_ST_TF, 0U);
  /* one setpoint frame lost, the other one arriving */
  com.prefailed = UINT32_C(1) << CANFDI_RX_MON_SP_THR_TIMEOUT;
  com.prepassed = UINT32_C(1) << CANFDI_RX_MON_SP_DCM_TIMEOUT;
  ck_assert_int_eq(canfdi_dtcroute_step(&r, &dtc, &in), 0);
  ck_assert_uint_ne(status_of(CANFDI_DTC_U1A50) & CANFDI_DTC_ST_TF, 0U);
  ck_assert_uint_eq(status_of(CANFDI_DTC_U1A00) & CANFDI_DTC_ST_TF, 0U);
}
END_TEST

/* The manager's faults: communication faults while their code has
 * testFailed, the others latched FAILED .. PASSED. */
START_TEST(test_manager_faults)
{
  canfdi_dtcroute_in_t in = in_of(0U, false, false);
  uint32_t bits;
  uint32_t k;
  setup();
  report[CANFDI_FAULT_DCM_RA_UP] = CANFDI_DIAG_REPORT_FAILED;
  bits = canfdi_dtcroute_manager_faults(&r, &dtc, report);
  ck_assert_uint_ne(bits & CANFDI_FAULT_BIT(CANFDI_FAULT_DCM_RA_UP), 0U);
  report[CANFDI_FAULT_DCM_RA_UP] = CANFDI_DIAG_REPORT_NONE;
  bits = canfdi_dtcroute_manager_faults(&r, &dtc, report);
  ck_assert_uint_ne(bits & CANFDI_FAULT_BIT(CANFDI_FAULT_DCM_RA_UP), 0U);
  report[CANFDI_FAULT_DCM_RA_UP] = CANFDI_DIAG_REPORT_PASSED;
  bits = canfdi_dtcroute_manager_faults(&r, &dtc, report);
  ck_assert_uint_eq(bits & CANFDI_FAULT_BIT(CANFDI_FAULT_DCM_RA_UP), 0U);
  /* a timeout DTC failing makes com_dcm_timeout a manager fault */
  memset(report, 0, sizeof report);
  com.prefailed = UINT32_C(1) << CANFDI_RX_MON_DCM_TIMEOUT;
  for (k = 0U; k < 100U; k++) {
    (void)canfdi_dtcroute_step(&r, &dtc, &in);
  }
  bits = canfdi_dtcroute_manager_faults(&r, &dtc, report);
  ck_assert_uint_ne(bits & CANFDI_FAULT_BIT(CANFDI_FAULT_COM_DCM_TIMEOUT), 0U);
  /* ... and it leaves with the DTC's testFailed */
  com.prefailed = 0U;
  com.prepassed = UINT32_C(1) << CANFDI_RX_MON_DCM_TIMEOUT;
  for (k = 0U; k < 200U; k++) {
    (void)canfdi_dtcroute_step(&r, &dtc, &in);
  }
  bits = canfdi_dtcroute_manager_faults(&r, &dtc, report);
  ck_assert_uint_eq(bits & CANFDI_FAULT_BIT(CANFDI_FAULT_COM_DCM_TIMEOUT), 0U);
}
END_TEST

START_TEST(test_bad_arguments)
{
  canfdi_dtcroute_in_t in;
  canfdi_dtcroute_cfg_t bad;
  setup();
  in = in_of(0U, false, false);
  bad.p2135_steps = 0U;
  ck_assert_int_eq(canfdi_dtcroute_init(&r, &bad, &dtc), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_dtcroute_step(&r, &dtc, &in), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_dtcroute_init(&r, &cfg, NULL), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_dtcroute_init(NULL, &cfg, &dtc), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_dtcroute_init(&r, &cfg, &dtc), CANFDI_OK);
  ck_assert_int_eq(canfdi_dtcroute_step(&r, NULL, &in), -CANFDI_EINVAL);
  in.report = NULL;
  ck_assert_int_eq(canfdi_dtcroute_step(&r, &dtc, &in), -CANFDI_EINVAL);
  ck_assert_uint_eq(canfdi_dtcroute_manager_faults(NULL, &dtc, report), 0U);
  /* outside an operation cycle the DTC memory refuses reports: counted */
  in = in_of(0U, false, true);
  ck_assert_int_eq(canfdi_dtc_cycle_end(&dtc), CANFDI_OK);
  ck_assert_int_eq(canfdi_dtcroute_step(&r, &dtc, &in), 1); /* the P2135 pass */
  ck_assert_uint_eq(canfdi_dtcroute_diag(&r).reports_rejected, 1U);
  ck_assert_uint_eq(canfdi_dtcroute_diag(NULL).reports, 0U);
}
END_TEST

static Suite *make_suite(void)
{
  Suite *s = suite_create("dtcroute");
  TCase *tc = tcase_create("routing");
  tcase_add_loop_test(tc, test_fault_reaches_its_codes, 0, (int)CANFDI_FAULT_COUNT - 1);
  tcase_add_test(tc, test_shared_code);
  tcase_add_test(tc, test_steady_verdicts_after_a_change);
  tcase_add_test(tc, test_manager_findings);
  tcase_add_test(tc, test_p2135_persistence);
  tcase_add_test(tc, test_com_monitors);
  tcase_add_test(tc, test_shared_com_code);
  tcase_add_test(tc, test_manager_faults);
  suite_add_tcase(s, tc);
  tc = tcase_create("errors");
  tcase_add_test(tc, test_bad_arguments);
  suite_add_tcase(s, tc);
  return s;
}

CANFDI_UNIT_MAIN(make_suite)
