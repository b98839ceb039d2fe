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

/* report[] as the diagnosis' two masks (canfdi_diagnosis_failed_mask,
 * _passed_mask). */
static uint32_t mask_of(const int8_t rep[], int8_t v)
{
  uint32_t m = 0U;
  uint32_t f;
  for (f = 0U; f < CANFDI_FAULT_COUNT; f++) {
    m |= (rep[f] == v) ? CANFDI_FAULT_BIT(f) : 0U;
  }
  return m;
}

/* One step with this test's report[] as it is now. */
static int32_t route(canfdi_dtcroute_in_t *in)
{
  in->failed = mask_of(report, CANFDI_DIAG_REPORT_FAILED);
  in->passed = mask_of(report, CANFDI_DIAG_REPORT_PASSED);
  return canfdi_dtcroute_step(&r, &dtc, in);
}

static uint32_t manager(void)
{
  return canfdi_dtcroute_manager_faults(&r, &dtc, mask_of(report, CANFDI_DIAG_REPORT_FAILED),
                                        mask_of(report, CANFDI_DIAG_REPORT_PASSED));
}

static canfdi_dtcroute_in_t in_of(uint32_t mgr, bool corr_ni, bool corr_tested)
{
  canfdi_dtcroute_in_t in;
  in.failed = 0U;
  in.passed = 0U;
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
    ck_assert_int_eq(route(&in), 0);
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
    ck_assert_int_eq(route(&in), 0);
  }
  ck_assert_uint_ne(status_of(code) & CANFDI_DTC_ST_TF, 0U);
  reports0 = r.diag.reports;
  ck_assert_int_eq(route(&in), 0);
  ck_assert_uint_eq(r.diag.reports, reports0 + 2U); /* counted as given */
  ck_assert_int_eq(canfdi_dtc_clear(&dtc, code), CANFDI_OK);
  ck_assert_uint_eq(status_of(code) & CANFDI_DTC_ST_TF, 0U);
  ck_assert_int_eq(route(&in), 0);
  ck_assert_uint_ne(status_of(code) & CANFDI_DTC_ST_TF, 0U);
  ck_assert_int_eq(canfdi_dtc_cycle_end(&dtc), CANFDI_OK);
  ck_assert_int_eq(canfdi_dtc_cycle_start(&dtc), CANFDI_OK);
  ck_assert_uint_ne(status_of(code_g) & CANFDI_DTC_ST_TNCTOC, 0U);
  ck_assert_int_eq(route(&in), 0);
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
  (void)route(&in);
  ck_assert_uint_ne(status_of(CANFDI_DTC_P0122) & CANFDI_DTC_ST_TF, 0U);
  report[CANFDI_FAULT_THR_TPS_BOTH_LOST] = CANFDI_DIAG_REPORT_NONE;
  (void)route(&in);
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
  (void)route(&in);
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
    (void)route(&ni);
  }
  ck_assert_uint_eq(status_of(CANFDI_DTC_P2135) & CANFDI_DTC_ST_TF, 0U);
  (void)route(&untested);
  (void)route(&ni);
  ck_assert_uint_ne(status_of(CANFDI_DTC_P2135) & CANFDI_DTC_ST_TF, 0U);
  (void)route(&ok);
  ck_assert_uint_eq(status_of(CANFDI_DTC_P2135) & CANFDI_DTC_ST_TF, 0U);
  ck_assert_uint_eq(r.p2135_n, 0U);
  for (k = 0U; k < cfg.p2135_steps - 1U; k++) {
    (void)route(&ni);
  }
  (void)route(&ok);
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
    (void)route(&in);
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
    ck_assert_int_eq(route(&in), 0);
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
    ck_assert_int_eq(route(&in), 0);
  }
  ck_assert_uint_eq(status_of(CANFDI_DTC_U1A51) & CANFDI_DTC_ST_TF, 0U);
  /* one setpoint frame lost, the other one arriving */
  com.prefailed = UINT32_C(1) << CANFDI_RX_MON_SP_THR_TIMEOUT;
  com.prepassed = UINT32_C(1) << CANFDI_RX_MON_SP_DCM_TIMEOUT;
  ck_assert_int_eq(route(&in), 0);
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
  bits = manager();
  ck_assert_uint_ne(bits & CANFDI_FAULT_BIT(CANFDI_FAULT_DCM_RA_UP), 0U);
  report[CANFDI_FAULT_DCM_RA_UP] = CANFDI_DIAG_REPORT_NONE;
  bits = manager();
  ck_assert_uint_ne(bits & CANFDI_FAULT_BIT(CANFDI_FAULT_DCM_RA_UP), 0U);
  report[CANFDI_FAULT_DCM_RA_UP] = CANFDI_DIAG_REPORT_PASSED;
  bits = manager();
  ck_assert_uint_eq(bits & CANFDI_FAULT_BIT(CANFDI_FAULT_DCM_RA_UP), 0U);
  /* a timeout DTC failing makes com_dcm_timeout a manager fault */
  memset(report, 0, sizeof report);
  com.prefailed = UINT32_C(1) << CANFDI_RX_MON_DCM_TIMEOUT;
  for (k = 0U; k < 100U; k++) {
    (void)route(&in);
  }
  bits = manager();
  ck_assert_uint_ne(bits & CANFDI_FAULT_BIT(CANFDI_FAULT_COM_DCM_TIMEOUT), 0U);
  /* ... and it leaves with the DTC's testFailed */
  com.prefailed = 0U;
  com.prepassed = UINT32_C(1) << CANFDI_RX_MON_DCM_TIMEOUT;
  for (k = 0U; k < 200U; k++) {
    (void)route(&in);
  }
  bits = manager();
  ck_assert_uint_eq(bits & CANFDI_FAULT_BIT(CANFDI_FAULT_COM_DCM_TIMEOUT), 0U);
}
END_TEST

/* ---- the routing against a written-out reference ------------------------
 * The module keeps source 1's DTC masks while its inputs stay the same and
 * gives no report when the verdicts and the memory are unchanged. The
 * reference below has none of that: every step it combines each DTC's
 * verdict from the per-fault report (a failure dominating), applies P2135
 * and reports every DTC with a verdict and every monitor's code to a
 * second memory, except the DTCs over the step's budget
 * (cfg.verdicts_per_step): the reference keeps, per DTC, the verdict last
 * given to its memory (none after a change of that memory from outside,
 * or after a refused report), and of the DTCs whose verdict differs from
 * it gives the failures first, then the passes, each lowest index first,
 * up to the budget; the others wait (a monitor's report to a code makes
 * its verdict due again). Both memories must hold the same
 * status bytes and the routing must have counted the same reports after
 * every step, and the manager's faults must equal a
 * per-fault latch, over random verdicts that hold for random spans (so
 * that the steady state, its end and the memory's own changes, clears and
 * cycles, all occur), with budgets of 32 (never binding), 4 (the
 * product's), 2 and 1. As in the application, the verdicts of sources 1-2
 * are for faults other than the communication ones, whose codes source 3
 * feeds (the header). */

static uint32_t rng_state;

static uint32_t rnd(uint32_t n)
{
  rng_state = (rng_state * 1664525U) + 1013904223U;
  return (uint32_t)(((uint64_t)(rng_state >> 8) * n) >> 24);
}

/* A random fault id other than 0 and the communication faults. */
static uint32_t rnd_fault(void)
{
  uint32_t f;
  do {
    f = 1U + rnd(CANFDI_FAULT_COUNT - 1U);
  } while (canfdi_catalogue_fault[f].kind == CANFDI_KIND_COMMUNICATION);
  return f;
}

static uint8_t ref_index(const canfdi_dtc_t *m, uint32_t code)
{
  const int32_t i = (code != 0U) ? canfdi_dtc_find(m, code) : -1;
  return (i >= 0) ? (uint8_t)i : (uint8_t)CANFDI_DTC_NONE;
}

START_TEST(test_against_reference)
{
  static canfdi_dtc_t ref;
  uint32_t p2135_n = 0U;
  uint32_t latched = 0U;
  uint32_t step;
  uint32_t changed = 0U;
  uint32_t deferred = 0U;
  uint32_t ref_reports = 0U;
  int8_t given[CANFDI_CFG_DTC_MAX_DTCS];
  uint32_t ref_changes;
  bool ref_valid = false;
  static const uint8_t budgets[4] = {32U, CANFDI_DTCROUTE_VERDICTS_PER_STEP, 2U, 1U};
  setup();
  cfg.verdicts_per_step = budgets[_i % 4];
  ck_assert_int_eq(canfdi_dtcroute_init(&r, &cfg, &dtc), CANFDI_OK);
  rng_state = 12345U + (uint32_t)_i;
  ck_assert_int_eq(canfdi_dtc_init(&ref, canfdi_dtc_defaults, (uint8_t)CANFDI_DTC_COUNT), CANFDI_OK);
  ck_assert_int_eq(canfdi_dtc_cycle_start(&ref), CANFDI_OK);
  ref_changes = ref.changes;
  for (step = 0U; step < 6000U; step++) {
    canfdi_dtcroute_in_t in;
    int8_t agg[CANFDI_CFG_DTC_MAX_DTCS];
    uint32_t f;
    uint32_t j;
    uint32_t bits;
    /* new verdicts now and then: a few faults change, the rest hold */
    if (rnd(20U) == 0U) {
      const uint32_t k = 1U + rnd(4U);
      for (j = 0U; j < k; j++) {
        /* now and then a verdict for a communication fault, which the
         * product's diagnosis never gives: its U-code is then fed by
         * sources 1 and 3, and neither may skip a report of it */
        report[(rnd(16U) == 0U) ? (1U + rnd(CANFDI_FAULT_COUNT - 1U)) : rnd_fault()] = (int8_t)((int32_t)rnd(3U) - 1);
      }
      report[0] = (int8_t)((int32_t)rnd(3U) - 1); /* id 0 is never routed */
    }
    in = in_of((rnd(50U) == 0U) ? CANFDI_FAULT_BIT(rnd_fault()) : 0U, rnd(3U) != 0U, rnd(4U) != 0U);
    com.prefailed = (rnd(10U) == 0U) ? (UINT32_C(1) << rnd(CANFDI_RX_MON_COUNT)) : 0U;
    /* the monitors that ran: all of them in one step of ten (the 10 ms
     * frames' monitors with the others, as in the firmware), else one of
     * two subsets, so that the remembered passes see sets alternate and
     * return */
    com.prepassed = (((step % 10U) == 0U) ? ((UINT32_C(1) << CANFDI_RX_MON_COUNT) - 1U)
                                          : ((rnd(4U) == 0U) ? UINT32_C(0xA5A5A) : UINT32_C(0x00FFF))) &
                    ((UINT32_C(1) << CANFDI_RX_MON_COUNT) - 1U);
    com.prepassed &= ~com.prefailed;
    if (rnd(500U) == 0U) {
      /* the memory changes under the routing: a tester's clear */
      ck_assert_int_eq(canfdi_dtc_clear(&dtc, 0xFFFFFFU), canfdi_dtc_clear(&ref, 0xFFFFFFU));
    }
    if (rnd(1500U) == 0U) {
      (void)canfdi_dtc_cycle_end(&dtc);
      (void)canfdi_dtc_cycle_end(&ref);
      if (rnd(2U) == 0U) {
        (void)canfdi_dtc_cycle_start(&dtc);
        (void)canfdi_dtc_cycle_start(&ref);
      }
    }
    if (!dtc.cycle_active && (rnd(100U) == 0U)) {
      (void)canfdi_dtc_cycle_start(&dtc);
      (void)canfdi_dtc_cycle_start(&ref);
    }
    (void)route(&in);
    /* the reference: sources 1 and 2 */
    memset(agg, CANFDI_DIAG_REPORT_NONE, sizeof agg);
    for (f = 1U; f < CANFDI_FAULT_COUNT; f++) {
      const int8_t v = ((in.mgr_detected & CANFDI_FAULT_BIT(f)) != 0U) ? CANFDI_DIAG_REPORT_FAILED : report[f];
      for (j = 0U; (j < CANFDI_CATALOGUE_MAX_DTCS) && (v != CANFDI_DIAG_REPORT_NONE); j++) {
        const uint8_t idx = ref_index(&ref, canfdi_catalogue_fault[f].dtc[j]);
        if ((idx != CANFDI_DTC_NONE) && (agg[idx] != CANFDI_DIAG_REPORT_FAILED)) {
          agg[idx] = v;
        }
      }
    }
    {
      const uint8_t p = ref_index(&ref, CANFDI_DTC_P2135);
      if (in.corr_not_isolated) {
        if (p2135_n < cfg.p2135_steps) {
          p2135_n++;
        } else {
          agg[p] = CANFDI_DIAG_REPORT_FAILED;
        }
      } else if (in.corr_tested) {
        p2135_n = 0U;
        agg[p] = CANFDI_DIAG_REPORT_PASSED;
      } else {
        /* not tested */
      }
    }
    /* what the reference's memory was last given no longer holds after
     * a change from outside (a clear, a cycle) or a refused report */
    if (!ref_valid || (ref.changes != ref_changes) || !ref.cycle_active) {
      memset(given, CANFDI_DIAG_REPORT_NONE, sizeof given);
    }
    {
      /* the due DTCs over the budget wait: failures first, then passes */
      bool wait[CANFDI_CFG_DTC_MAX_DTCS];
      uint32_t budget = cfg.verdicts_per_step;
      int8_t pass;
      memset(wait, 0, sizeof wait);
      for (pass = CANFDI_DIAG_REPORT_FAILED; pass >= CANFDI_DIAG_REPORT_PASSED; pass -= 2) {
        for (j = 0U; j < (uint32_t)ref.n_dtcs; j++) {
          if ((agg[j] == pass) && (given[j] != agg[j])) {
            if (budget > 0U) {
              budget--;
            } else {
              wait[j] = true;
              deferred++;
            }
          }
        }
      }
      ref_valid = true;
      for (j = 0U; j < (uint32_t)ref.n_dtcs; j++) {
        given[j] = wait[j] ? CANFDI_DIAG_REPORT_NONE : agg[j];
        if ((agg[j] != CANFDI_DIAG_REPORT_NONE) && !wait[j]) {
          ref_reports++; /* given, or counted as given */
          if (canfdi_dtc_report(&ref, (uint8_t)j, (agg[j] > 0) ? CANFDI_DEB_REPORT_FAILED : CANFDI_DEB_REPORT_PASSED,
                                &ff) < 0) {
            ref_valid = false;
          }
        }
      }
    }
    /* source 3: per DTC, a failure of any of its monitors dominating */
    for (j = 0U; j < (uint32_t)ref.n_dtcs; j++) {
      uint32_t k;
      int8_t v = CANFDI_DIAG_REPORT_NONE;
      for (k = 0U; k < (uint32_t)CANFDI_RX_MON_COUNT; k++) {
        const uint32_t bit = UINT32_C(1) << k;
        if ((ref_index(&ref, canfdi_rx_monitor_dtc(k)) == j) && (((com.prefailed | com.prepassed) & bit) != 0U) &&
            (v != CANFDI_DIAG_REPORT_FAILED)) {
          v = ((com.prefailed & bit) != 0U) ? CANFDI_DIAG_REPORT_FAILED : CANFDI_DIAG_REPORT_PASSED;
        }
      }
      if (v != CANFDI_DIAG_REPORT_NONE) {
        (void)canfdi_dtc_report(&ref, (uint8_t)j, (v > 0) ? CANFDI_DEB_REPORT_PREFAILED : CANFDI_DEB_REPORT_PREPASSED,
                                &ff);
        /* a monitor's report to a code with a verdict given: that verdict
         * is due again */
        given[j] = CANFDI_DIAG_REPORT_NONE;
        ref_reports++;
      }
    }
    ref_changes = ref.changes;
    /* every verdict and monitor result counted once: given, or counted as
     * given (nothing changes), or waiting (not counted) */
    ck_assert_msg(r.diag.reports == ref_reports, "step %u: %u reports, reference %u", step, r.diag.reports,
                  ref_reports);
    for (j = 0U; j < (uint32_t)ref.n_dtcs; j++) {
      const uint8_t st = (uint8_t)canfdi_dtc_status(&dtc, (uint8_t)j);
      ck_assert_msg(st == (uint8_t)canfdi_dtc_status(&ref, (uint8_t)j), "step %u DTC %u: %02x, reference %02x", step, j,
                    st, (uint8_t)canfdi_dtc_status(&ref, (uint8_t)j));
      changed |= (st != 0U) ? 1U : 0U;
    }
    /* the manager's faults: communication from testFailed, others latched */
    bits = manager();
    for (f = 1U; f < CANFDI_FAULT_COUNT; f++) {
      if (canfdi_catalogue_fault[f].kind == CANFDI_KIND_COMMUNICATION) {
        const uint8_t idx = ref_index(&ref, canfdi_catalogue_fault[f].dtc[0]);
        const bool tf = (idx != CANFDI_DTC_NONE) && (((uint32_t)canfdi_dtc_status(&ref, idx) & CANFDI_DTC_ST_TF) != 0U);
        latched = tf ? (latched | CANFDI_FAULT_BIT(f)) : (latched & ~CANFDI_FAULT_BIT(f));
      } else if (report[f] == CANFDI_DIAG_REPORT_FAILED) {
        latched |= CANFDI_FAULT_BIT(f);
      } else if (report[f] == CANFDI_DIAG_REPORT_PASSED) {
        latched &= ~CANFDI_FAULT_BIT(f);
      } else {
        /* kept */
      }
    }
    ck_assert_msg(bits == latched, "step %u: manager faults %08x, reference %08x", step, bits, latched);
  }
  ck_assert_uint_ne(changed, 0U);
  ck_assert_uint_gt(r.diag.reports, 0U);
  /* a binding budget was reached (the clears and cycles make every
   * verdict due at once) */
  ck_assert((cfg.verdicts_per_step >= 32U) ? (deferred == 0U) : (deferred > 0U));
}
END_TEST

START_TEST(test_bad_arguments)
{
  canfdi_dtcroute_in_t in;
  canfdi_dtcroute_cfg_t bad;
  setup();
  in = in_of(0U, false, false);
  bad = cfg;
  bad.verdicts_per_step = 0U;
  ck_assert_int_eq(canfdi_dtcroute_init(&r, &bad, &dtc), -CANFDI_EINVAL);
  bad.verdicts_per_step = 33U;
  ck_assert_int_eq(canfdi_dtcroute_init(&r, &bad, &dtc), -CANFDI_EINVAL);
  bad.verdicts_per_step = 32U;
  ck_assert_int_eq(canfdi_dtcroute_init(&r, &bad, &dtc), CANFDI_OK);
  bad = cfg;
  bad.p2135_steps = 0U;
  ck_assert_int_eq(canfdi_dtcroute_init(&r, &bad, &dtc), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_dtcroute_step(&r, &dtc, &in), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_dtcroute_init(&r, &cfg, NULL), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_dtcroute_init(NULL, &cfg, &dtc), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_dtcroute_init(&r, &cfg, &dtc), CANFDI_OK);
  ck_assert_int_eq(canfdi_dtcroute_step(&r, NULL, &in), -CANFDI_EINVAL);
  in.com = NULL;
  ck_assert_int_eq(route(&in), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_dtcroute_step(&r, &dtc, NULL), -CANFDI_EINVAL);
  ck_assert_uint_eq(canfdi_dtcroute_manager_faults(NULL, &dtc, 0U, 0U), 0U);
  ck_assert_uint_eq(canfdi_dtcroute_manager_faults(&r, NULL, 0U, 0U), 0U);
  /* outside an operation cycle the DTC memory refuses reports: counted */
  in = in_of(0U, false, true);
  ck_assert_int_eq(canfdi_dtc_cycle_end(&dtc), CANFDI_OK);
  ck_assert_int_eq(route(&in), 1); /* the P2135 pass */
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
  tcase_add_loop_test(tc, test_against_reference, 0, 4);
  suite_add_tcase(s, tc);
  tc = tcase_create("errors");
  tcase_add_test(tc, test_bad_arguments);
  suite_add_tcase(s, tc);
  return s;
}

CANFDI_UNIT_MAIN(make_suite)
