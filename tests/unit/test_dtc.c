/*
 * test_dtc.c — unit tests of firmware/diag/canfdi_dtc (trouble-code memory).
 *
 * The status sequences are written down from the ISO 14229-1 bit
 * definitions (each expected byte is derived by hand in the comment next to
 * it, bit by bit), not recorded from a run. Displacement cases are derived
 * from the policy stated in the header. The product table is checked
 * against dbc/dtcs.csv and the generated catalogue, not against itself.
 */
#include <check.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "catalogue/canfdi_catalogue.h"
#include "diag/canfdi_dtc.h"
#include "unit_main.h"

#define TF CANFDI_DTC_ST_TF
#define TFTOC CANFDI_DTC_ST_TFTOC
#define PDTC CANFDI_DTC_ST_PDTC
#define CDTC CANFDI_DTC_ST_CDTC
#define TNCSLC CANFDI_DTC_ST_TNCSLC
#define TFSLC CANFDI_DTC_ST_TFSLC
#define TNCTOC CANFDI_DTC_ST_TNCTOC
#define WIR CANFDI_DTC_ST_WIR

static canfdi_dtc_t mem; /* ~1 KB: static, as the firmware would have it */
static canfdi_dtc_t mem2;

static canfdi_dtc_ff_t make_ff(int32_t seed)
{
  canfdi_dtc_ff_t ff;
  ff.time_ms = (uint32_t)seed * 1000U + 7U;
  ff.omega_q16 = seed * 65536;
  ff.ia_q16 = -seed * 3000 - 1;
  ff.ua_q16 = seed * 12345;
  ff.thr_angle_q16 = -seed;
  ff.supply_q16 = INT32_MIN + seed;
  ff.deg_dcm = (uint8_t)(seed & 3);
  ff.deg_thr = (uint8_t)((seed >> 2) & 3);
  return ff;
}

static bool ff_equal(const canfdi_dtc_ff_t *a, const canfdi_dtc_ff_t *b)
{
  return (a->time_ms == b->time_ms) && (a->omega_q16 == b->omega_q16) && (a->ia_q16 == b->ia_q16) &&
         (a->ua_q16 == b->ua_q16) && (a->thr_angle_q16 == b->thr_angle_q16) &&
         (a->supply_q16 == b->supply_q16) && (a->deg_dcm == b->deg_dcm) && (a->deg_thr == b->deg_thr);
}

static canfdi_dtc_def_t def_row(uint32_t dtc, uint8_t prio, uint8_t n, uint8_t m, uint8_t k, bool wir)
{
  canfdi_dtc_def_t d;
  d.dtc = dtc;
  d.deb = &canfdi_dtc_deb_direct;
  d.priority = prio;
  d.group = 1U;
  d.confirm_cycles = n;
  d.heal_cycles = m;
  d.aging_cycles = k;
  d.warning_indicator = wir;
  return d;
}

static int32_t report(canfdi_dtc_t *m, uint8_t i, canfdi_deb_report_t r, const canfdi_dtc_ff_t *ff)
{
  return canfdi_dtc_report(m, i, r, ff);
}

static void do_fail(canfdi_dtc_t *m, uint8_t i)
{
  ck_assert_int_ge(report(m, i, CANFDI_DEB_REPORT_FAILED, NULL), 0);
}

static void do_pass(canfdi_dtc_t *m, uint8_t i)
{
  ck_assert_int_ge(report(m, i, CANFDI_DEB_REPORT_PASSED, NULL), 0);
}

static uint8_t st(const canfdi_dtc_t *m, uint8_t i)
{
  const int32_t s = canfdi_dtc_status(m, i);
  ck_assert_int_ge(s, 0);
  return (uint8_t)s;
}

/* ------------------------------------------------------------- table */

/* dbc/dtcs.csv: code,uds_dtc_hex,severity,fault_ids,description */
START_TEST(test_defaults_match_csv)
{
  FILE *fp = fopen("dbc/dtcs.csv", "r");
  char line[512];
  unsigned row = 0U;
  ck_assert_msg(fp != NULL, "run from the repository root (dbc/dtcs.csv)");
  ck_assert_ptr_nonnull(fgets(line, sizeof line, fp)); /* header */
  while (fgets(line, sizeof line, fp) != NULL) {
    char code[16];
    char sev[40];
    unsigned long hex = 0UL;
    ck_assert_int_eq(sscanf(line, "%15[^,],0x%lx,%39[^,],", code, &hex, sev), 3);
    ck_assert_uint_lt(row, CANFDI_DTC_COUNT);
    const canfdi_dtc_def_t *d = &canfdi_dtc_defaults[row];
    ck_assert_uint_eq(d->dtc, hex);
    ck_assert_uint_eq(canfdi_catalogue_dtc[row], hex);
    if (strcmp(sev, "check_immediately") == 0) {
      ck_assert_uint_eq(d->priority, 1U);
      ck_assert(d->warning_indicator);
    } else if (strcmp(sev, "check_at_next_halt") == 0) {
      ck_assert_uint_eq(d->priority, 2U);
      ck_assert(d->warning_indicator);
    } else {
      ck_assert_str_eq(sev, "maintenance_only");
      ck_assert_uint_eq(d->priority, 3U);
      ck_assert(!d->warning_indicator);
    }
    /* per-frame checks U1A1x..U1A4x and U1A51 (a rejected setpoint frame)
     * count frames; everything else (the timeouts U1A0x, U1A50 too) is
     * reported already qualified */
    const bool frame = (strncmp(code, "U1A", 3) == 0) &&
                       (((code[3] >= '1') && (code[3] <= '4')) || (strcmp(code, "U1A51") == 0));
    ck_assert_ptr_eq(d->deb, frame ? &canfdi_dtc_deb_frame : &canfdi_dtc_deb_direct);
    ck_assert_uint_eq(d->confirm_cycles, 1U);
    ck_assert_uint_eq(d->heal_cycles, 3U);
    ck_assert_uint_eq(d->aging_cycles, 40U);
    row++;
  }
  fclose(fp);
  ck_assert_uint_eq(row, CANFDI_DTC_COUNT);
}
END_TEST

START_TEST(test_defaults_group_is_component)
{
  ck_assert_int_eq(canfdi_dtc_init(&mem, canfdi_dtc_defaults, (uint8_t)CANFDI_DTC_COUNT), CANFDI_OK);
  for (unsigned f = 1U; f < CANFDI_FAULT_COUNT; f++) {
    for (unsigned k = 0U; k < CANFDI_CATALOGUE_MAX_DTCS; k++) {
      const uint32_t dtc = canfdi_catalogue_fault[f].dtc[k];
      if (dtc != 0U) {
        const int32_t i = canfdi_dtc_find(&mem, dtc);
        ck_assert_int_ge(i, 0);
        ck_assert_uint_eq(canfdi_dtc_defaults[i].group, canfdi_catalogue_fault[f].component);
      }
    }
  }
  /* P2135 has no fault of its own: a throttle code */
  ck_assert_uint_eq(canfdi_dtc_defaults[canfdi_dtc_find(&mem, CANFDI_DTC_P2135)].group,
                    CANFDI_COMPONENT_THROTTLE);
}
END_TEST

START_TEST(test_init_state)
{
  ck_assert_int_eq(canfdi_dtc_init(&mem, canfdi_dtc_defaults, (uint8_t)CANFDI_DTC_COUNT), CANFDI_OK);
  for (uint8_t i = 0U; i < CANFDI_DTC_COUNT; i++) {
    ck_assert_uint_eq(st(&mem, i), 0x50U);
  }
  ck_assert(!mem.cycle_active);
  ck_assert(canfdi_dtc_invariants_hold(&mem));
  ck_assert_uint_eq(CANFDI_DTC_STATUS_AVAILABILITY_MASK, 0xFFU);
  ck_assert_uint_eq(canfdi_dtc_count_by_mask(&mem, TF | PDTC | CDTC | WIR), 0U);
}
END_TEST

typedef struct {
  const char *what;
  canfdi_dtc_def_t bad;
  uint8_t n;
} bad_init_t;

START_TEST(test_init_rejects)
{
  static const canfdi_debounce_cfg_t bad_deb = {0, 0, 0U, 0U, 0, 0, false, false};
  canfdi_dtc_def_t t[3];
  t[0] = def_row(0x010100U, 1U, 1U, 1U, 1U, true);
  t[1] = def_row(0x010200U, 1U, 1U, 1U, 1U, true);
  t[2] = def_row(0x010300U, 1U, 1U, 1U, 1U, true);
  ck_assert_int_eq(canfdi_dtc_init(&mem, t, 3U), CANFDI_OK);

  const bad_init_t cases[] = {
      {"dtc 0", def_row(0U, 1U, 1U, 1U, 1U, true), 3U},
      {"dtc 0xFFFFFF (the all-groups value)", def_row(0xFFFFFFU, 1U, 1U, 1U, 1U, true), 3U},
      {"dtc > 3 bytes", def_row(0x1000000U, 1U, 1U, 1U, 1U, true), 3U},
      {"duplicate", def_row(0x010100U, 1U, 1U, 1U, 1U, true), 3U},
      {"priority 0", def_row(0x010400U, 0U, 1U, 1U, 1U, true), 3U},
      {"N 0", def_row(0x010400U, 1U, 0U, 1U, 1U, true), 3U},
      {"M 0", def_row(0x010400U, 1U, 1U, 0U, 1U, true), 3U},
      {"K < M", def_row(0x010400U, 1U, 1U, 3U, 2U, true), 3U},
  };
  for (size_t c = 0U; c < sizeof cases / sizeof cases[0]; c++) {
    canfdi_dtc_def_t tb[3] = {t[0], t[1], cases[c].bad};
    ck_assert_msg(canfdi_dtc_init(&mem, tb, cases[c].n) == -CANFDI_EINVAL, "%s", cases[c].what);
    /* an unbound memory refuses everything */
    ck_assert_int_eq(canfdi_dtc_cycle_start(&mem), -CANFDI_EINVAL);
    ck_assert_int_eq(canfdi_dtc_report(&mem, 0U, CANFDI_DEB_REPORT_FAILED, NULL), -CANFDI_EINVAL);
    ck_assert_int_eq(canfdi_dtc_status(&mem, 0U), -CANFDI_EINVAL);
    ck_assert(!canfdi_dtc_invariants_hold(&mem));
  }
  canfdi_dtc_def_t tb[3] = {t[0], t[1], t[2]};
  tb[2].deb = &bad_deb;
  ck_assert_int_eq(canfdi_dtc_init(&mem, tb, 3U), -CANFDI_EINVAL);
  tb[2].deb = NULL;
  ck_assert_int_eq(canfdi_dtc_init(&mem, tb, 3U), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_dtc_init(&mem, t, 0U), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_dtc_init(&mem, NULL, 3U), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_dtc_init(NULL, t, 3U), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_dtc_init(&mem, canfdi_dtc_defaults, (uint8_t)(CANFDI_CFG_DTC_MAX_DTCS + 1U)),
                   -CANFDI_EINVAL);
  /* K = 0 (never age) is valid with any M */
  tb[2] = def_row(0x010300U, 1U, 1U, 5U, 0U, true);
  ck_assert_int_eq(canfdi_dtc_init(&mem, tb, 3U), CANFDI_OK);
}
END_TEST

/* ----------------------------------------------- ISO 14229-1 sequences */

/*
 * Events: S cycle start, E cycle end, F qualified failed (FAILED report),
 * P qualified passed (PASSED report), C ClearDiagnosticInformation(all),
 * c clear(this DTC number), g clear_group(its group), x a FAILED report
 * outside an operation cycle (rejected). DTC 0 is under test; DTC 1 is
 * never reported and must stay 0x50 (TNCSLC|TNCTOC) throughout.
 */
typedef struct {
  const char *name;
  uint8_t n, m, k; /* confirmation, healing, aging thresholds */
  bool wir;
  const char *events;
  uint8_t expect[40];
} seq_case_t;

static const seq_case_t seq_cases[] = {
    {"pass, fail, heal after M=3, age after K=5", 1U, 3U, 5U, true,
     "SPESFFPESPESPESPESPESPES",
     {0x50, /* S: 0x50 stays (TNCSLC|TNCTOC) */
      0x00, /* P: completed and passed: TNCSLC=0, TNCTOC=0 */
      0x00, /* E: nothing pending */
      0x40, /* S: TNCTOC=1 */
      0xAF, /* F: TF|TFTOC|PDTC|TFSLC, N=1 -> CDTC, warning -> WIR; TNCTOC=0 */
      0xAF, /* F again: no change */
      0xAE, /* P: TF=0 */
      0xAE, /* E: failed this cycle: PDTC stays */
      0xEC, /* S: TFTOC=0, TNCTOC=1 */
      0xAC, /* P: TNCTOC=0 */
      0xA8, /* E: healthy cycle 1: PDTC=0 */
      0xE8, 0xA8, 0xA8, /* S P E: healthy 2 */
      0xE8, 0xA8, 0x28, /* S P E: healthy 3 = M: WIR=0 */
      0x68, 0x28, 0x28, /* healthy 4 */
      0x68, 0x28, 0x20, /* healthy 5 = K: aged, CDTC=0; TFSLC stays */
      0x60}},           /* S */
    {"untested cycles neither heal nor clear pending", 1U, 3U, 5U, true, "SFESESESPE",
     {0x50, 0xAF, 0xAF,
      0xED, /* S: TF stays (last result), TFTOC=0, TNCTOC=1 */
      0xED, /* E: not completed: PDTC stays */
      0xED, 0xED, 0xED,
      0xAC, /* P: TF=0, TNCTOC=0 */
      0xA8}}, /* E: healthy: PDTC=0 */
    {"two-trip confirmation N=2", 2U, 3U, 5U, true, "SFPESF",
     {0x50,
      0x27, /* F: TF|TFTOC|PDTC|TFSLC; one failed cycle < N: no CDTC, no WIR */
      0x26, 0x26,
      0x64, /* S: TFTOC=0, TNCTOC=1 */
      0xAF}}, /* F: second failed cycle: CDTC, WIR */
    {"N=2 restarts after a passing cycle", 2U, 3U, 5U, true, "SFESPESFESF",
     {0x50, 0x27, 0x27, 0x65, /* S: TF kept */
      0x24, /* P */
      0x20, /* E: healthy: PDTC=0, failed-cycle count restarts */
      0x60,
      0x27, /* F: failed cycle 1 again: no CDTC */
      0x27, 0x65,
      0xAF}}, /* F: failed cycle 2: CDTC, WIR */
    {"clear all, clear one, then test again", 1U, 3U, 5U, true, "SFCFPCPES",
     {0x50, 0xAF,
      0x50, /* C: back to TNCSLC|TNCTOC */
      0xAF, 0xAE,
      0x50,  /* C */
      0x00,  /* P */
      0x00, 0x40}},
    {"clear by DTC number", 1U, 3U, 5U, true, "SFcF", {0x50, 0xAF, 0x50, 0xAF}},
    {"clear by group", 1U, 3U, 5U, true, "SFgF", {0x50, 0xAF, 0x50, 0xAF}},
    {"no warning indicator, M=1, K=2", 1U, 1U, 2U, false, "SFPESPESPE",
     {0x50,
      0x2F, /* F: TF|TFTOC|PDTC|CDTC|TFSLC, no WIR */
      0x2E, 0x2E, 0x6C, 0x2C,
      0x28, /* E: healthy 1: PDTC=0 */
      0x68, 0x28,
      0x20}}, /* E: healthy 2 = K: aged */
    {"K=0 never ages", 1U, 1U, 0U, true, "SFPESPESPESPE",
     {0x50, 0xAF, 0xAE, 0xAE, 0xEC, 0xAC,
      0x28, /* E: healthy 1 = M: WIR=0, PDTC=0 */
      0x68, 0x28, 0x28, 0x68, 0x28, 0x28}},
    {"re-failure sets WIR again and restarts aging", 1U, 1U, 3U, true, "SFPESPESFPESPESPESPE",
     {0x50, 0xAF, 0xAE, 0xAE, 0xEC, 0xAC,
      0x28, /* E: healed (M=1), healthy 1 */
      0x68,
      0xAF, /* F: CDTC still set -> WIR again; healthy count back to 0 */
      0xAE, 0xAE, 0xEC, 0xAC,
      0x28, /* healthy 1 */
      0x68, 0x28, 0x28, /* healthy 2 */
      0x68, 0x28, 0x20}}, /* healthy 3 = K: aged (one cycle later than without the restart) */
    {"cycle start while active ends the cycle first", 1U, 1U, 5U, true, "SFPESPS",
     {0x50, 0xAF, 0xAE, 0xAE, 0xEC, 0xAC,
      0x68}}, /* S: implicit end (healthy 1: PDTC=0, WIR=0), then TNCTOC=1 */
    {"reports outside a cycle are rejected", 1U, 3U, 5U, true, "xSFEx",
     {0x50, 0x50, 0xAF, 0xAF, 0xAF}},
    {"a failure that persists across cycles", 1U, 3U, 5U, true, "SFESF",
     {0x50, 0xAF, 0xAF, 0xED,
      0xAF}}, /* F: TFTOC=1, TNCTOC=0 */
};
#define N_SEQ_CASES ((int)(sizeof seq_cases / sizeof seq_cases[0]))

START_TEST(test_status_sequences)
{
  const seq_case_t *c = &seq_cases[_i];
  canfdi_dtc_def_t t[2];
  t[0] = def_row(0x123400U, 2U, c->n, c->m, c->k, c->wir);
  t[1] = def_row(0x123500U, 2U, 1U, 1U, 1U, true);
  t[1].group = 2U;
  ck_assert_int_eq(canfdi_dtc_init(&mem, t, 2U), CANFDI_OK);
  const size_t n = strlen(c->events);
  for (size_t e = 0U; e < n; e++) {
    const char ev = c->events[e];
    int32_t rc = CANFDI_OK;
    switch (ev) {
    case 'S': rc = canfdi_dtc_cycle_start(&mem); break;
    case 'E': rc = canfdi_dtc_cycle_end(&mem); break;
    case 'F': rc = report(&mem, 0U, CANFDI_DEB_REPORT_FAILED, NULL); break;
    case 'P': rc = report(&mem, 0U, CANFDI_DEB_REPORT_PASSED, NULL); break;
    case 'C': rc = canfdi_dtc_clear(&mem, CANFDI_DTC_GROUP_ALL); break;
    case 'c': rc = canfdi_dtc_clear(&mem, 0x123400U); break;
    case 'g': rc = canfdi_dtc_clear_group(&mem, 1U) == 1 ? CANFDI_OK : -1; break;
    case 'x': rc = (report(&mem, 0U, CANFDI_DEB_REPORT_FAILED, NULL) == -CANFDI_EINVAL) ? CANFDI_OK : -1; break;
    default: ck_abort_msg("bad event"); break;
    }
    ck_assert_msg(rc >= 0, "%s: event %zu '%c' returned %d", c->name, e, ev, (int)rc);
    ck_assert_msg(st(&mem, 0U) == c->expect[e], "%s: after event %zu '%c' status 0x%02X, expected 0x%02X",
                  c->name, e, ev, st(&mem, 0U), c->expect[e]);
    ck_assert_msg(st(&mem, 1U) == 0x50U, "%s: bystander changed", c->name);
    ck_assert(canfdi_dtc_invariants_hold(&mem));
  }
}
END_TEST

START_TEST(test_cycle_end_without_start)
{
  canfdi_dtc_def_t t[1] = {def_row(0x123400U, 2U, 1U, 1U, 1U, true)};
  ck_assert_int_eq(canfdi_dtc_init(&mem, t, 1U), CANFDI_OK);
  ck_assert_int_eq(canfdi_dtc_cycle_end(&mem), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_dtc_cycle_start(&mem), CANFDI_OK);
  ck_assert_int_eq(canfdi_dtc_cycle_end(&mem), CANFDI_OK);
  ck_assert_int_eq(canfdi_dtc_cycle_end(&mem), -CANFDI_EINVAL);
  /* rejected reports: no cycle, bad index, bad report kind */
  ck_assert_int_eq(report(&mem, 0U, CANFDI_DEB_REPORT_FAILED, NULL), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_dtc_cycle_start(&mem), CANFDI_OK);
  ck_assert_int_eq(report(&mem, 1U, CANFDI_DEB_REPORT_FAILED, NULL), -CANFDI_EINVAL);
  ck_assert_int_eq(report(&mem, 0U, (canfdi_deb_report_t)7, NULL), -CANFDI_EINVAL);
  ck_assert_uint_eq(mem.diag.rejected_reports, 3U);
  ck_assert_uint_eq(st(&mem, 0U), 0x50U);
}
END_TEST

/* ------------------------------------------------------------ debounce */

START_TEST(test_frame_class_counts_reports)
{
  /* U1A10 (rolling counter, DC motor frame) uses the frame class: failed
   * at +6 with +2 per bad frame -> the 3rd bad frame in a row from 0. */
  ck_assert_int_eq(canfdi_dtc_init(&mem, canfdi_dtc_defaults, (uint8_t)CANFDI_DTC_COUNT), CANFDI_OK);
  const uint8_t i = (uint8_t)canfdi_dtc_find(&mem, CANFDI_DTC_U1A10);
  ck_assert_int_eq(canfdi_dtc_cycle_start(&mem), CANFDI_OK);
  ck_assert_int_eq(report(&mem, i, CANFDI_DEB_REPORT_PREFAILED, NULL), 0x50);
  ck_assert_int_eq(report(&mem, i, CANFDI_DEB_REPORT_PREFAILED, NULL), 0x50);
  ck_assert_int_eq(canfdi_dtc_fdc(&mem, i), (int8_t)(4 * 127 / 6));
  ck_assert_int_eq(report(&mem, i, CANFDI_DEB_REPORT_PREFAILED, NULL), 0xAF);
  ck_assert_int_eq(canfdi_dtc_fdc(&mem, i), 127);
  /* from +6, six good frames (-1 each) reach 0, the 12th reaches -6 */
  for (int k = 0; k < 11; k++) {
    ck_assert_int_eq(report(&mem, i, CANFDI_DEB_REPORT_PREPASSED, NULL), 0xAF);
  }
  ck_assert_int_eq(report(&mem, i, CANFDI_DEB_REPORT_PREPASSED, NULL), 0xAE);
  ck_assert_int_eq(canfdi_dtc_fdc(&mem, i), -128);
  /* alternating bad/good frames (ratio 1/2 > 1/3): +2 -1 per pair */
  int reports = 0;
  while ((st(&mem, i) & TF) == 0U) {
    report(&mem, i, CANFDI_DEB_REPORT_PREFAILED, NULL);
    report(&mem, i, CANFDI_DEB_REPORT_PREPASSED, NULL);
    reports += 2;
    ck_assert_int_lt(reports, 100);
  }
  /* from -6: after p pairs the counter is -6 + p before the bad frame of
   * pair p+1 adds 2; it reaches 6 in pair p = 11 (-6 + 10 + 2 = 6) */
  ck_assert_int_eq(reports, 2 * 11);
  /* FAILED/PASSED qualify at once whatever the class */
  ck_assert_int_eq(report(&mem, i, CANFDI_DEB_REPORT_PASSED, NULL), 0xAE);
  ck_assert_int_eq(report(&mem, i, CANFDI_DEB_REPORT_FAILED, NULL), 0xAF);
  ck_assert_int_eq(canfdi_dtc_fdc(&mem, 200U), 0);
}
END_TEST

START_TEST(test_direct_class_qualifies_each_report)
{
  canfdi_dtc_def_t t[1] = {def_row(0x123400U, 2U, 1U, 1U, 1U, true)};
  ck_assert_int_eq(canfdi_dtc_init(&mem, t, 1U), CANFDI_OK);
  ck_assert_int_eq(canfdi_dtc_cycle_start(&mem), CANFDI_OK);
  for (int k = 0; k < 5; k++) {
    ck_assert_int_eq(report(&mem, 0U, CANFDI_DEB_REPORT_PREFAILED, NULL) & (int32_t)TF, (int32_t)TF);
    ck_assert_int_eq(report(&mem, 0U, CANFDI_DEB_REPORT_PREPASSED, NULL) & (int32_t)TF, 0);
  }
}
END_TEST

/* ------------------------------------------- freeze frame, occurrence */

static uint8_t occurrence_of(const canfdi_dtc_t *m, uint32_t dtc)
{
  canfdi_dtc_record_t r;
  ck_assert_int_eq(canfdi_dtc_read_record(m, dtc, &r), CANFDI_OK);
  return r.occurrence;
}

START_TEST(test_freeze_frame_first_failure)
{
  canfdi_dtc_def_t t[2] = {def_row(0x123400U, 2U, 1U, 1U, 2U, true), def_row(0x123500U, 2U, 1U, 1U, 2U, true)};
  const canfdi_dtc_ff_t ff1 = make_ff(1);
  const canfdi_dtc_ff_t ff2 = make_ff(2);
  const canfdi_dtc_ff_t ff3 = make_ff(3);
  canfdi_dtc_record_t r;
  ck_assert_int_eq(canfdi_dtc_init(&mem, t, 2U), CANFDI_OK);
  ck_assert_int_eq(canfdi_dtc_cycle_start(&mem), CANFDI_OK);
  /* no entry before the first failure */
  ck_assert_int_eq(canfdi_dtc_read_record(&mem, 0x123400U, &r), -CANFDI_ENODATA);
  ck_assert_uint_eq(r.status, 0x50U);
  ck_assert_uint_eq(r.occurrence, 0U);
  ck_assert_uint_eq(canfdi_dtc_occurrence(&mem, 0U), 0U);
  ck_assert_uint_eq(canfdi_dtc_occurrence(&mem, 2U), 0U);   /* bad index */
  ck_assert_uint_eq(canfdi_dtc_occurrence(NULL, 0U), 0U);
  ck_assert(!r.ff_valid);
  /* a pass does not store anything */
  report(&mem, 0U, CANFDI_DEB_REPORT_PASSED, &ff1);
  ck_assert_int_eq(canfdi_dtc_read_record(&mem, 0x123400U, &r), -CANFDI_ENODATA);
  report(&mem, 0U, CANFDI_DEB_REPORT_FAILED, &ff1);
  report(&mem, 0U, CANFDI_DEB_REPORT_FAILED, &ff2); /* still failed */
  report(&mem, 0U, CANFDI_DEB_REPORT_PASSED, &ff2);
  report(&mem, 0U, CANFDI_DEB_REPORT_FAILED, &ff3); /* re-failure */
  ck_assert_int_eq(canfdi_dtc_cycle_start(&mem), CANFDI_OK);
  report(&mem, 0U, CANFDI_DEB_REPORT_PASSED, &ff3);
  report(&mem, 0U, CANFDI_DEB_REPORT_FAILED, &ff3); /* next cycle */
  ck_assert_int_eq(canfdi_dtc_read_record(&mem, 0x123400U, &r), CANFDI_OK);
  ck_assert_uint_eq(r.dtc, 0x123400U);
  ck_assert_uint_eq(r.status, st(&mem, 0U));
  ck_assert(r.ff_valid);
  ck_assert(ff_equal(&r.ff, &ff1));
  ck_assert_uint_eq(r.occurrence, 3U);
  ck_assert_uint_eq(canfdi_dtc_occurrence(&mem, 0U), 3U);
  ck_assert_uint_eq(canfdi_dtc_occurrence(&mem, 1U), 0U);
  /* a clear frees the entry; the next failure stores the new snapshot */
  ck_assert_int_eq(canfdi_dtc_clear(&mem, 0x123400U), CANFDI_OK);
  ck_assert_int_eq(canfdi_dtc_read_record(&mem, 0x123400U, &r), -CANFDI_ENODATA);
  report(&mem, 0U, CANFDI_DEB_REPORT_FAILED, &ff2);
  ck_assert_int_eq(canfdi_dtc_read_record(&mem, 0x123400U, &r), CANFDI_OK);
  ck_assert(ff_equal(&r.ff, &ff2));
  ck_assert_uint_eq(r.occurrence, 1U);
  ck_assert_uint_eq(canfdi_dtc_occurrence(&mem, 0U), 1U);
  /* aging (K=2) frees it as well */
  report(&mem, 0U, CANFDI_DEB_REPORT_PASSED, NULL);
  for (int c = 0; c < 3; c++) {
    ck_assert_int_eq(canfdi_dtc_cycle_start(&mem), CANFDI_OK);
    report(&mem, 0U, CANFDI_DEB_REPORT_PASSED, NULL);
  }
  ck_assert_int_eq(canfdi_dtc_cycle_end(&mem), CANFDI_OK);
  ck_assert_int_eq(canfdi_dtc_read_record(&mem, 0x123400U, &r), -CANFDI_ENODATA);
  ck_assert_uint_eq(mem.diag.aged, 1U);
  ck_assert_int_eq(canfdi_dtc_cycle_start(&mem), CANFDI_OK);
  report(&mem, 0U, CANFDI_DEB_REPORT_FAILED, &ff3);
  ck_assert_int_eq(canfdi_dtc_read_record(&mem, 0x123400U, &r), CANFDI_OK);
  ck_assert(ff_equal(&r.ff, &ff3));
  /* a failure reported without a snapshot has no valid freeze frame */
  report(&mem, 1U, CANFDI_DEB_REPORT_FAILED, NULL);
  ck_assert_int_eq(canfdi_dtc_read_record(&mem, 0x123500U, &r), CANFDI_OK);
  ck_assert(!r.ff_valid);
  ck_assert_int_eq(r.ff.omega_q16, 0);
  ck_assert_int_eq(canfdi_dtc_read_record(&mem, 0x999900U, &r), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_dtc_read_record(&mem, 0x123500U, NULL), -CANFDI_EINVAL);
}
END_TEST

/* Occurrence = number of testFailed 0->1 transitions while stored. */
typedef struct {
  const char *events; /* F, P, S (cycle start) */
  uint8_t occurrence;
} occ_case_t;

static const occ_case_t occ_cases[] = {
    {"F", 1U},          {"FFF", 1U},          {"FPF", 2U},      {"FPFPF", 3U},
    {"FPPPF", 2U},      {"FSF", 1U},          {"FSSSF", 1U},    {"FPSF", 2U},
    {"FSPF", 2U},       {"FPFFFPF", 3U},
};

START_TEST(test_occurrence_counter)
{
  const occ_case_t *c = &occ_cases[_i];
  canfdi_dtc_def_t t[1] = {def_row(0x123400U, 2U, 1U, 3U, 0U, true)};
  ck_assert_int_eq(canfdi_dtc_init(&mem, t, 1U), CANFDI_OK);
  ck_assert_int_eq(canfdi_dtc_cycle_start(&mem), CANFDI_OK);
  for (const char *e = c->events; *e != '\0'; e++) {
    if (*e == 'F') {
      do_fail(&mem, 0U);
    } else if (*e == 'P') {
      do_pass(&mem, 0U);
    } else {
      ck_assert_int_eq(canfdi_dtc_cycle_start(&mem), CANFDI_OK);
    }
  }
  ck_assert_msg(occurrence_of(&mem, 0x123400U) == c->occurrence, "%s", c->events);
}
END_TEST

START_TEST(test_occurrence_saturates)
{
  canfdi_dtc_def_t t[1] = {def_row(0x123400U, 2U, 1U, 3U, 0U, true)};
  ck_assert_int_eq(canfdi_dtc_init(&mem, t, 1U), CANFDI_OK);
  ck_assert_int_eq(canfdi_dtc_cycle_start(&mem), CANFDI_OK);
  for (int k = 0; k < 300; k++) {
    do_fail(&mem, 0U);
    do_pass(&mem, 0U);
    ck_assert_uint_eq(occurrence_of(&mem, 0x123400U), (k + 1 < 255) ? (unsigned)(k + 1) : 255U);
  }
}
END_TEST

/* ------------------------------------------------------------ capacity */

#define CAP CANFDI_CFG_DTC_MAX_ENTRIES
#define CAP_DTCS (CAP + 4U)
static canfdi_dtc_def_t cap_table[CAP_DTCS];

/* Entries: CAP - n_special fillers (priority 1, active: never a candidate
 * for anyone), then the specials in storage order (so they are the newest
 * and "oldest" is decided among them). Then DTC `newcomer` fails. */
typedef struct {
  const char *name;
  uint8_t new_prio;
  uint8_t n_special;
  uint8_t prio[3];
  bool active[3];
  int victim; /* index into the specials, -1 = not stored */
} disp_case_t;

static const disp_case_t disp_cases[] = {
    {"equal lowest priority: passive before active", 2U, 2U, {3U, 3U}, {true, false}, 1},
    {"equal lowest priority, both active: oldest", 2U, 2U, {3U, 3U}, {true, true}, 0},
    {"lower priority first, even when active", 2U, 2U, {2U, 3U}, {false, true}, 1},
    {"equal priority active is never displaced", 2U, 1U, {2U}, {true}, -1},
    {"equal priority passive: oldest", 2U, 2U, {2U, 2U}, {false, false}, 0},
    {"higher priority is never displaced", 2U, 1U, {1U}, {false}, -1},
    {"top priority newcomer takes the lowest", 1U, 3U, {2U, 3U, 2U}, {true, false, false}, 1},
    {"lowest priority newcomer, nothing lower", 3U, 2U, {3U, 2U}, {true, false}, -1},
    {"three passive equals: oldest", 3U, 3U, {3U, 3U, 3U}, {false, false, true}, 0},
};
#define N_DISP_CASES ((int)(sizeof disp_cases / sizeof disp_cases[0]))

START_TEST(test_displacement)
{
  const disp_case_t *c = &disp_cases[_i];
  const uint8_t n_fill = (uint8_t)(CAP - c->n_special);
  const uint8_t newcomer = (uint8_t)CAP;
  for (uint8_t i = 0U; i < CAP_DTCS; i++) {
    cap_table[i] = def_row(0x100000U + (uint32_t)i * 256U, 1U, 1U, 3U, 40U, true);
  }
  for (uint8_t s = 0U; s < c->n_special; s++) {
    cap_table[n_fill + s].priority = c->prio[s];
  }
  cap_table[newcomer].priority = c->new_prio;
  ck_assert_int_eq(canfdi_dtc_init(&mem, cap_table, (uint8_t)CAP_DTCS), CANFDI_OK);
  ck_assert_int_eq(canfdi_dtc_cycle_start(&mem), CANFDI_OK);
  for (uint8_t i = 0U; i < CAP; i++) {
    do_fail(&mem, i);
    if ((i >= n_fill) && !c->active[i - n_fill]) {
      do_pass(&mem, i);
    }
  }
  ck_assert_uint_eq(mem.diag.overflows, 0U);
  const canfdi_dtc_ff_t ff = make_ff(42);
  report(&mem, newcomer, CANFDI_DEB_REPORT_FAILED, &ff);
  ck_assert_uint_eq(mem.diag.overflows, 1U);
  canfdi_dtc_record_t r;
  if (c->victim < 0) {
    ck_assert_uint_eq(mem.diag.not_stored, 1U);
    ck_assert_uint_eq(mem.diag.displacements, 0U);
    /* the bits are set, confirmation needs an entry */
    ck_assert_uint_eq(st(&mem, newcomer), TF | TFTOC | PDTC | TFSLC);
    ck_assert_int_eq(canfdi_dtc_read_record(&mem, cap_table[newcomer].dtc, &r), -CANFDI_ENODATA);
    for (uint8_t i = 0U; i < CAP; i++) {
      ck_assert_uint_ne(st(&mem, i) & CDTC, 0U);
    }
  } else {
    const uint8_t v = (uint8_t)(n_fill + c->victim);
    ck_assert_uint_eq(mem.diag.not_stored, 0U);
    ck_assert_uint_eq(mem.diag.displacements, 1U);
    ck_assert_uint_eq(st(&mem, newcomer), 0xAFU);
    ck_assert_int_eq(canfdi_dtc_read_record(&mem, cap_table[newcomer].dtc, &r), CANFDI_OK);
    ck_assert(ff_equal(&r.ff, &ff));
    /* the displaced DTC keeps its bits except CDTC and WIR */
    const uint8_t was = c->active[c->victim] ? 0xAFU : 0xAEU;
    ck_assert_uint_eq(st(&mem, v), was & (uint8_t)~(CDTC | WIR));
    ck_assert_int_eq(canfdi_dtc_read_record(&mem, cap_table[v].dtc, &r), -CANFDI_ENODATA);
    for (uint8_t i = 0U; i < CAP; i++) {
      if (i != v) {
        ck_assert_int_eq(canfdi_dtc_read_record(&mem, cap_table[i].dtc, &r), CANFDI_OK);
      }
    }
  }
  ck_assert(canfdi_dtc_invariants_hold(&mem));
}
END_TEST

START_TEST(test_not_stored_retries_later)
{
  for (uint8_t i = 0U; i < CAP_DTCS; i++) {
    cap_table[i] = def_row(0x100000U + (uint32_t)i * 256U, 2U, 1U, 3U, 40U, true);
  }
  ck_assert_int_eq(canfdi_dtc_init(&mem, cap_table, (uint8_t)CAP_DTCS), CANFDI_OK);
  ck_assert_int_eq(canfdi_dtc_cycle_start(&mem), CANFDI_OK);
  for (uint8_t i = 0U; i < CAP; i++) {
    do_fail(&mem, i);
  }
  const uint8_t late = (uint8_t)CAP;
  do_fail(&mem, late);
  ck_assert_uint_eq(mem.diag.not_stored, 1U);
  /* a persisting failure does not retry (or count) on every report */
  for (int k = 0; k < 10; k++) {
    do_fail(&mem, late);
  }
  ck_assert_uint_eq(mem.diag.not_stored, 1U);
  ck_assert_uint_eq(mem.diag.overflows, 1U);
  /* room appears; the next failure transition stores and confirms */
  ck_assert_int_eq(canfdi_dtc_clear(&mem, cap_table[0].dtc), CANFDI_OK);
  do_fail(&mem, late);
  ck_assert_uint_eq(st(&mem, late) & CDTC, 0U); /* no transition yet */
  do_pass(&mem, late);
  do_fail(&mem, late);
  ck_assert_uint_eq(st(&mem, late), 0xAFU);
  /* the first failure of the next cycle also retries */
  do_fail(&mem, 0U); /* takes nothing: full again -> not stored */
  ck_assert_uint_eq(mem.diag.not_stored, 2U);
  ck_assert_int_eq(canfdi_dtc_clear(&mem, cap_table[1].dtc), CANFDI_OK);
  ck_assert_int_eq(canfdi_dtc_cycle_start(&mem), CANFDI_OK);
  do_fail(&mem, 0U);
  ck_assert_uint_eq(st(&mem, 0U), 0xAFU);
  ck_assert(canfdi_dtc_invariants_hold(&mem));
}
END_TEST

START_TEST(test_capacity_with_product_table)
{
  /* Every DTC of the product table fails once, in table order, and stays
   * failed: the CAP entries end up holding check_immediately DTCs (an
   * active DTC is displaced only by a higher priority), the rest are
   * displaced or not stored. */
  ck_assert_int_eq(canfdi_dtc_init(&mem, canfdi_dtc_defaults, (uint8_t)CANFDI_DTC_COUNT), CANFDI_OK);
  ck_assert_int_eq(canfdi_dtc_cycle_start(&mem), CANFDI_OK);
  unsigned n_prio1 = 0U;
  for (uint8_t i = 0U; i < CANFDI_DTC_COUNT; i++) {
    do_fail(&mem, i);
    n_prio1 += (canfdi_dtc_defaults[i].priority == 1U) ? 1U : 0U;
  }
  ck_assert(canfdi_dtc_invariants_hold(&mem));
  unsigned stored = 0U;
  unsigned stored_prio1 = 0U;
  for (uint8_t i = 0U; i < CANFDI_DTC_COUNT; i++) {
    canfdi_dtc_record_t r;
    if (canfdi_dtc_read_record(&mem, canfdi_dtc_defaults[i].dtc, &r) == CANFDI_OK) {
      stored++;
      stored_prio1 += (canfdi_dtc_defaults[i].priority == 1U) ? 1U : 0U;
      ck_assert_uint_ne(r.status & CDTC, 0U);
    } else {
      ck_assert_uint_eq(r.status & CDTC, 0U);
    }
  }
  ck_assert_uint_eq(stored, CAP);
  ck_assert_uint_eq(stored_prio1, (n_prio1 < CAP) ? n_prio1 : CAP);
  ck_assert_uint_eq(canfdi_dtc_count_by_mask(&mem, CDTC), CAP);
  ck_assert_uint_eq(canfdi_dtc_count_by_mask(&mem, TF), CANFDI_DTC_COUNT);
  ck_assert_uint_eq(mem.diag.overflows, CANFDI_DTC_COUNT - CAP);
  ck_assert_uint_eq(mem.diag.displacements + mem.diag.not_stored, CANFDI_DTC_COUNT - CAP);
}
END_TEST

/* ------------------------------------------------------------ queries */

START_TEST(test_queries_by_mask)
{
  ck_assert_int_eq(canfdi_dtc_init(&mem, canfdi_dtc_defaults, (uint8_t)CANFDI_DTC_COUNT), CANFDI_OK);
  ck_assert_int_eq(canfdi_dtc_cycle_start(&mem), CANFDI_OK);
  do_fail(&mem, 0U);                    /* 0xAF */
  do_fail(&mem, 3U);
  do_pass(&mem, 3U);                    /* 0xAE */
  do_pass(&mem, 5U);                    /* 0x00 */
  do_fail(&mem, 6U);                    /* maintenance: 0x2F */
  ck_assert_uint_eq(canfdi_dtc_count_by_mask(&mem, TF), 2U);
  ck_assert_uint_eq(canfdi_dtc_count_by_mask(&mem, CDTC), 3U);
  ck_assert_uint_eq(canfdi_dtc_count_by_mask(&mem, WIR), 2U);
  ck_assert_uint_eq(canfdi_dtc_count_by_mask(&mem, 0x00U), 0U);
  ck_assert_uint_eq(canfdi_dtc_count_by_mask(&mem, TNCSLC), CANFDI_DTC_COUNT - 4U);
  /* every mask: iteration, count and a brute force over status() agree */
  for (unsigned mask = 0U; mask < 256U; mask++) {
    unsigned brute = 0U;
    for (uint8_t i = 0U; i < CANFDI_DTC_COUNT; i++) {
      brute += ((st(&mem, i) & mask) != 0U) ? 1U : 0U;
    }
    ck_assert_uint_eq(canfdi_dtc_count_by_mask(&mem, (uint8_t)mask), brute);
    uint16_t cursor = 0U;
    uint32_t dtc = 0U;
    uint8_t status = 0U;
    unsigned seen = 0U;
    int32_t prev = -1;
    while (canfdi_dtc_next_by_mask(&mem, (uint8_t)mask, &cursor, &dtc, &status) == 1) {
      const int32_t i = canfdi_dtc_find(&mem, dtc);
      ck_assert_int_gt(i, prev); /* table order, no repeats */
      prev = i;
      ck_assert_uint_eq(status, st(&mem, (uint8_t)i));
      ck_assert_uint_ne(status & mask, 0U);
      seen++;
    }
    ck_assert_uint_eq(seen, brute);
    /* a finished iterator stays finished */
    ck_assert_int_eq(canfdi_dtc_next_by_mask(&mem, (uint8_t)mask, &cursor, &dtc, &status), 0);
  }
  uint16_t cur = 0U;
  uint32_t d = 0U;
  uint8_t s = 0U;
  ck_assert_int_eq(canfdi_dtc_next_by_mask(&mem, 0xFFU, NULL, &d, &s), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_dtc_next_by_mask(&mem, 0xFFU, &cur, NULL, &s), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_dtc_next_by_mask(NULL, 0xFFU, &cur, &d, &s), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_dtc_find(&mem, 0x999999U), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_dtc_find(&mem, CANFDI_DTC_U1A51), (int32_t)CANFDI_DTC_COUNT - 1);
  ck_assert_int_eq(canfdi_dtc_status(&mem, (uint8_t)CANFDI_DTC_COUNT), -CANFDI_EINVAL);
  ck_assert_uint_eq(canfdi_dtc_count_by_mask(NULL, 0xFFU), 0U);
  ck_assert_int_eq(canfdi_dtc_clear(&mem, 0x999999U), -CANFDI_EINVAL);
  /* clear by group: only the comm codes go back to 0x50 */
  do_fail(&mem, (uint8_t)canfdi_dtc_find(&mem, CANFDI_DTC_U1A00));
  const int32_t n_com = canfdi_dtc_clear_group(&mem, CANFDI_COMPONENT_COMM);
  ck_assert_int_eq(n_com, 12); /* U1A00..U1A41 and the setpoints' U1A50, U1A51 */
  ck_assert_uint_eq(st(&mem, (uint8_t)canfdi_dtc_find(&mem, CANFDI_DTC_U1A00)), 0x50U);
  ck_assert_uint_eq(st(&mem, 0U), 0xAFU);
  ck_assert_int_eq(canfdi_dtc_clear_group(&mem, 77U), 0);
}
END_TEST

/* ------------------------------------------------------------ image */

static uint8_t img[CANFDI_DTC_IMAGE_MAX_BYTES + 64U];
static uint8_t img2[CANFDI_DTC_IMAGE_MAX_BYTES + 64U];

static bool same_state(const canfdi_dtc_t *a, const canfdi_dtc_t *b)
{
  bool ok = a->n_dtcs == b->n_dtcs;
  for (uint8_t i = 0U; ok && (i < a->n_dtcs); i++) {
    canfdi_dtc_record_t ra;
    canfdi_dtc_record_t rb;
    const int32_t ca = canfdi_dtc_read_record(a, a->table[i].dtc, &ra);
    const int32_t cb = canfdi_dtc_read_record(b, a->table[i].dtc, &rb);
    ok = (ca == cb) && (ra.status == rb.status) && (ra.occurrence == rb.occurrence) &&
         (ra.ff_valid == rb.ff_valid) && ff_equal(&ra.ff, &rb.ff) &&
         (a->dtc[i].failed_cycles == b->dtc[i].failed_cycles) &&
         (a->dtc[i].healthy_cycles == b->dtc[i].healthy_cycles);
  }
  return ok;
}

/* A deterministic pseudo-random history over the product table. */
static uint32_t rng_state;
static uint32_t rng(void)
{
  rng_state = rng_state * 1664525U + 1013904223U;
  return rng_state >> 8;
}

/* fail_pct: share of reports that are FAILED/PREFAILED (else PASSED/
 * PREPASSED), so that healing and aging happen in the fuzz. */
/*
 * A pass report, checked against what the debouncer and the pass
 * transition do with it: canfdi_dtc_report answers a pass that changes
 * nothing without running them (pass_again), and must give the same state
 * as running them.
 */
static void pass_report_checked(canfdi_dtc_t *m, uint8_t i, canfdi_deb_report_t kind, const canfdi_dtc_ff_t *ff)
{
  canfdi_debounce_t d = m->dtc[i].deb;
  const canfdi_debounce_t *got = &m->dtc[i].deb;
  const uint8_t s0 = m->dtc[i].status;
  const uint32_t changes0 = m->changes;
  const uint8_t pass_bits = (uint8_t)(CANFDI_DTC_ST_TF | CANFDI_DTC_ST_TNCSLC | CANFDI_DTC_ST_TNCTOC);
  uint8_t want;
  ck_assert_int_ge(canfdi_debounce_step(&d, kind), 0);
  ck_assert_int_ge(canfdi_dtc_report(m, i, kind, ff), 0);
  ck_assert_int_eq(got->counter, d.counter);
  ck_assert_uint_eq(got->status, d.status);
  ck_assert(got->test_failed == d.test_failed);
  ck_assert(got->test_failed_this_cycle == d.test_failed_this_cycle);
  ck_assert(got->test_not_completed_this_cycle == d.test_not_completed_this_cycle);
  ck_assert_uint_eq(got->diag.passed_qualifications, d.diag.passed_qualifications);
  ck_assert_uint_eq(got->diag.failed_qualifications, d.diag.failed_qualifications);
  want = (d.counter <= d.cfg->passed_threshold) ? (uint8_t)(s0 & (uint8_t)~pass_bits) : s0;
  ck_assert_uint_eq(m->dtc[i].status, want);
  ck_assert_uint_eq(m->changes, changes0 + ((want != s0) ? 1U : 0U));
}

static void random_history(canfdi_dtc_t *m, uint32_t seed, int steps, uint32_t fail_pct)
{
  uint8_t before[CANFDI_CFG_DTC_MAX_DTCS];
  uint32_t changes_before;
  rng_state = seed;
  ck_assert_int_eq(canfdi_dtc_cycle_start(m), CANFDI_OK);
  for (int k = 0; k < steps; k++) {
    for (uint8_t j = 0U; j < m->n_dtcs; j++) {
      before[j] = m->dtc[j].status;
    }
    changes_before = m->changes;
    const uint32_t r = rng() % 100U;
    const uint8_t i = (uint8_t)(rng() % m->n_dtcs);
    if (r < 3U) {
      ck_assert_int_eq(canfdi_dtc_cycle_start(m), CANFDI_OK);
    } else if (r < 4U) {
      ck_assert_int_eq(canfdi_dtc_clear(m, m->table[i].dtc), CANFDI_OK);
    } else {
      const canfdi_dtc_ff_t ff = make_ff((int32_t)k);
      const bool bad = (rng() % 100U) < fail_pct;
      const bool sure = (rng() & 1U) != 0U;
      const canfdi_deb_report_t kind = bad ? (sure ? CANFDI_DEB_REPORT_FAILED : CANFDI_DEB_REPORT_PREFAILED)
                                           : (sure ? CANFDI_DEB_REPORT_PASSED : CANFDI_DEB_REPORT_PREPASSED);
      if (bad) {
        ck_assert_int_ge(canfdi_dtc_report(m, i, kind, &ff), 0);
      } else {
        pass_report_checked(m, i, kind, &ff);
      }
    }
    ck_assert(canfdi_dtc_invariants_hold(m));
    /* a status byte changes only with `changes` (the header's contract) */
    if (m->changes == changes_before) {
      for (uint8_t j = 0U; j < m->n_dtcs; j++) {
        ck_assert_uint_eq(m->dtc[j].status, before[j]);
      }
    }
  }
  ck_assert_int_eq(canfdi_dtc_cycle_end(m), CANFDI_OK);
}

START_TEST(test_image_round_trip)
{
  ck_assert_int_eq(canfdi_dtc_init(&mem, canfdi_dtc_defaults, (uint8_t)CANFDI_DTC_COUNT), CANFDI_OK);
  random_history(&mem, 1234U + (uint32_t)_i, 3000, 40U);
  const int32_t len = canfdi_dtc_serialize(&mem, img, sizeof img);
  ck_assert_int_gt(len, (int32_t)CANFDI_DTC_IMAGE_HEADER_BYTES);
  ck_assert_int_le(len, (int32_t)CANFDI_DTC_IMAGE_MAX_BYTES);
  ck_assert_int_eq(canfdi_dtc_init(&mem2, canfdi_dtc_defaults, (uint8_t)CANFDI_DTC_COUNT), CANFDI_OK);
  ck_assert_int_eq(canfdi_dtc_deserialize(&mem2, img, (uint32_t)len), CANFDI_OK);
  ck_assert(same_state(&mem, &mem2));
  ck_assert(canfdi_dtc_invariants_hold(&mem2));
  ck_assert_int_eq(canfdi_dtc_serialize(&mem2, img2, sizeof img2), len);
  ck_assert_mem_eq(img, img2, (size_t)len);
  /* the loaded memory continues like the original */
  random_history(&mem, 99U, 500, 30U);
  random_history(&mem2, 99U, 500, 30U);
  ck_assert(same_state(&mem, &mem2));
  /* too small a buffer */
  ck_assert_int_eq(canfdi_dtc_serialize(&mem, img, CANFDI_DTC_IMAGE_HEADER_BYTES), -CANFDI_ERANGE);
}
END_TEST

START_TEST(test_image_full_size_bound)
{
  /* every DTC non-default and every entry used: the stated maximum */
  ck_assert_int_eq(canfdi_dtc_init(&mem, canfdi_dtc_defaults, (uint8_t)CANFDI_DTC_COUNT), CANFDI_OK);
  ck_assert_int_eq(canfdi_dtc_cycle_start(&mem), CANFDI_OK);
  for (uint8_t i = 0U; i < CANFDI_DTC_COUNT; i++) {
    do_fail(&mem, i);
  }
  ck_assert_int_eq(canfdi_dtc_serialize(&mem, img, sizeof img), (int32_t)CANFDI_DTC_IMAGE_MAX_BYTES);
  ck_assert_int_eq(canfdi_dtc_serialize(&mem, img, CANFDI_DTC_IMAGE_MAX_BYTES - 1U), -CANFDI_ERANGE);
  /* a fresh memory is just the header */
  ck_assert_int_eq(canfdi_dtc_init(&mem, canfdi_dtc_defaults, (uint8_t)CANFDI_DTC_COUNT), CANFDI_OK);
  ck_assert_int_eq(canfdi_dtc_serialize(&mem, img, sizeof img), (int32_t)CANFDI_DTC_IMAGE_HEADER_BYTES);
}
END_TEST

/* Layout written down from the header, independently of serialize(). */
static uint8_t *w24(uint8_t *p, uint32_t v)
{
  p[0] = (uint8_t)(v >> 16);
  p[1] = (uint8_t)(v >> 8);
  p[2] = (uint8_t)v;
  return p + 3;
}

static uint8_t *w32(uint8_t *p, uint32_t v)
{
  p[0] = (uint8_t)(v >> 24);
  return w24(p + 1, v);
}

static uint8_t *w_record(uint8_t *p, uint32_t dtc, uint8_t status, uint8_t fc, uint8_t hc)
{
  p = w24(p, dtc);
  p[0] = status;
  p[1] = fc;
  p[2] = hc;
  return p + 3;
}

/* An entry of a version 1 image (4-byte time stamp), as stored by earlier
 * firmware: still read. */
static uint8_t *w_entry(uint8_t *p, uint32_t dtc, uint8_t occ, uint32_t order, uint8_t flags, int32_t v)
{
  p = w24(p, dtc);
  *p++ = occ;
  p = w32(p, order);
  *p++ = flags;
  p = w32(p, 1000U);              /* time_ms */
  p = w32(p, (uint32_t)v);        /* omega */
  p = w32(p, (uint32_t)(v + 1));  /* ia */
  p = w32(p, 0xFFFFFFFFU);        /* ua = -1 */
  p = w32(p, 0x80000000U);        /* thr_angle = INT32_MIN */
  p = w32(p, 0x7FFFFFFFU);        /* supply = INT32_MAX */
  *p++ = 2U;
  *p++ = 3U;
  return p;
}

/* An entry of a version 2 image: the time stamp in 8 bytes. */
static uint8_t *w_entry_v2(uint8_t *p, uint32_t dtc, uint8_t occ, uint32_t order, uint8_t flags,
                           uint64_t time_ms, int32_t v)
{
  p = w24(p, dtc);
  *p++ = occ;
  p = w32(p, order);
  *p++ = flags;
  p = w32(p, (uint32_t)(time_ms >> 32));
  p = w32(p, (uint32_t)time_ms);
  p = w32(p, (uint32_t)v);        /* omega */
  p = w32(p, (uint32_t)(v + 1));  /* ia */
  p = w32(p, 0xFFFFFFFFU);        /* ua = -1 */
  p = w32(p, 0x80000000U);        /* thr_angle = INT32_MIN */
  p = w32(p, 0x7FFFFFFFU);        /* supply = INT32_MAX */
  *p++ = 2U;
  *p++ = 3U;
  return p;
}

START_TEST(test_image_layout_by_hand)
{
  uint8_t *p = img;
  *p++ = 1U;
  *p++ = 2U; /* records */
  *p++ = 1U; /* entries */
  *p++ = 0U;
  p = w_record(p, CANFDI_DTC_P0122, 0xAEU, 1U, 0U);
  p = w_record(p, CANFDI_DTC_P1A10, 0x00U, 0U, 0U);
  p = w_entry(p, CANFDI_DTC_P0122, 4U, 17U, 1U, 5000);
  ck_assert_int_eq(canfdi_dtc_init(&mem, canfdi_dtc_defaults, (uint8_t)CANFDI_DTC_COUNT), CANFDI_OK);
  ck_assert_int_eq(canfdi_dtc_deserialize(&mem, img, (uint32_t)(p - img)), CANFDI_OK);
  canfdi_dtc_record_t r;
  ck_assert_int_eq(canfdi_dtc_read_record(&mem, CANFDI_DTC_P0122, &r), CANFDI_OK);
  ck_assert_uint_eq(r.status, 0xAEU);
  ck_assert_uint_eq(r.occurrence, 4U);
  ck_assert(r.ff_valid);
  ck_assert_uint_eq(r.ff.time_ms, 1000U);
  ck_assert_int_eq(r.ff.omega_q16, 5000);
  ck_assert_int_eq(r.ff.ia_q16, 5001);
  ck_assert_int_eq(r.ff.ua_q16, -1);
  ck_assert_int_eq(r.ff.thr_angle_q16, INT32_MIN);
  ck_assert_int_eq(r.ff.supply_q16, INT32_MAX);
  ck_assert_uint_eq(r.ff.deg_dcm, 2U);
  ck_assert_uint_eq(r.ff.deg_thr, 3U);
  ck_assert_uint_eq(st(&mem, (uint8_t)canfdi_dtc_find(&mem, CANFDI_DTC_P1A10)), 0x00U);
  ck_assert_uint_eq(st(&mem, (uint8_t)canfdi_dtc_find(&mem, CANFDI_DTC_P0123)), 0x50U);
  ck_assert_uint_eq(mem.next_order, 18U);
  /* and serialize() writes exactly these bytes back, as version 2 (the
   * time stamp in 8 bytes) */
  p = img;
  *p++ = 2U;
  *p++ = 2U;
  *p++ = 1U;
  *p++ = 0U;
  p = w_record(p, CANFDI_DTC_P0122, 0xAEU, 1U, 0U);
  p = w_record(p, CANFDI_DTC_P1A10, 0x00U, 0U, 0U);
  p = w_entry_v2(p, CANFDI_DTC_P0122, 4U, 17U, 1U, 1000U, 5000);
  ck_assert_int_eq(canfdi_dtc_serialize(&mem, img2, sizeof img2), (int32_t)(p - img));
  ck_assert_mem_eq(img, img2, (size_t)(p - img));
}
END_TEST

/* Version 2: a time stamp beyond 2^32 ms (49.7 days of operation) comes
 * back whole, and the image survives serialize -> deserialize unchanged. */
START_TEST(test_image_v2_time_beyond_32_bits)
{
  const uint64_t t = (UINT64_C(3) << 32) + 12345U;
  uint8_t *p = img;
  canfdi_dtc_record_t r;
  *p++ = 2U;
  *p++ = 1U;
  *p++ = 1U;
  *p++ = 0U;
  p = w_record(p, CANFDI_DTC_P0122, 0xAEU, 1U, 0U);
  p = w_entry_v2(p, CANFDI_DTC_P0122, 1U, 3U, 1U, t, -7);
  ck_assert_int_eq(canfdi_dtc_init(&mem, canfdi_dtc_defaults, (uint8_t)CANFDI_DTC_COUNT), CANFDI_OK);
  ck_assert_int_eq(canfdi_dtc_deserialize(&mem, img, (uint32_t)(p - img)), CANFDI_OK);
  ck_assert_int_eq(canfdi_dtc_read_record(&mem, CANFDI_DTC_P0122, &r), CANFDI_OK);
  ck_assert(r.ff.time_ms == t);
  ck_assert_int_eq(r.ff.omega_q16, -7);
  ck_assert_int_eq(r.ff.supply_q16, INT32_MAX);
  ck_assert_int_eq(canfdi_dtc_serialize(&mem, img2, sizeof img2), (int32_t)(p - img));
  ck_assert_mem_eq(img, img2, (size_t)(p - img));
}
END_TEST

typedef struct {
  const char *name;
  int kind;
} bad_img_t;

static const bad_img_t bad_imgs[] = {
    {"version 3", 0},
    {"reserved byte", 1},
    {"one byte short", 2},
    {"one byte long", 3},
    {"duplicate record", 4},
    {"duplicate entry", 5},
    {"occurrence 0", 6},
    {"unknown flag bit", 7},
    {"TF without TFSLC", 8},
    {"entry without TFSLC", 9},
    {"empty buffer", 10},
    {"TNCTOC with TFTOC", 11},
};

START_TEST(test_image_rejects)
{
  const bad_img_t *c = &bad_imgs[_i];
  uint8_t *p = img;
  uint32_t len;
  *p++ = 1U;
  *p++ = 2U;
  *p++ = 1U;
  *p++ = 0U;
  p = w_record(p, CANFDI_DTC_P0122, 0xAEU, 1U, 0U);
  p = w_record(p, CANFDI_DTC_P0222, 0xAFU, 1U, 0U);
  p = w_entry(p, CANFDI_DTC_P0122, 1U, 0U, 1U, 7);
  len = (uint32_t)(p - img);
  switch (c->kind) {
  case 0: img[0] = 3U; break;
  case 1: img[3] = 1U; break;
  case 2: len--; break;
  case 3: len++; break;
  case 4: w24(img + 4U + 6U, CANFDI_DTC_P0122); break;
  case 5:
    img[2] = 2U;
    p = w_entry(p, CANFDI_DTC_P0122, 1U, 1U, 0U, 7);
    len = (uint32_t)(p - img);
    break;
  case 6: img[4U + 12U + 3U] = 0U; break;
  case 7: img[4U + 12U + 8U] = 3U; break;
  case 8: img[4U + 3U] = 0x01U | 0x08U; break;
  case 9: img[4U + 3U] = 0x00U; break;
  case 10: len = 0U; break;
  case 11: img[4U + 3U] = 0xEEU; break;
  default: break;
  }
  ck_assert_int_eq(canfdi_dtc_init(&mem, canfdi_dtc_defaults, (uint8_t)CANFDI_DTC_COUNT), CANFDI_OK);
  /* dirty the memory first: a rejected image must leave defaults */
  random_history(&mem, 5U, 300, 40U);
  ck_assert_msg(canfdi_dtc_deserialize(&mem, img, len) == -CANFDI_EINVAL, "%s accepted", c->name);
  ck_assert_uint_eq(mem.diag.image_rejected, 1U);
  for (uint8_t i = 0U; i < CANFDI_DTC_COUNT; i++) {
    ck_assert_uint_eq(st(&mem, i), 0x50U);
  }
  ck_assert_uint_eq(canfdi_dtc_count_by_mask(&mem, 0xFFU), CANFDI_DTC_COUNT);
  ck_assert(canfdi_dtc_invariants_hold(&mem));
}
END_TEST

START_TEST(test_image_table_change_and_capacity)
{
  /* unknown DTCs are dropped, the rest loads */
  uint8_t *p = img;
  *p++ = 1U;
  *p++ = 2U;
  *p++ = 2U;
  *p++ = 0U;
  p = w_record(p, 0x0A0B00U, 0xAFU, 1U, 0U); /* not in the table */
  p = w_record(p, CANFDI_DTC_P0122, 0xAFU, 1U, 0U);
  p = w_entry(p, 0x0A0B00U, 1U, 0U, 1U, 1);
  p = w_entry(p, CANFDI_DTC_P0122, 1U, 1U, 1U, 2);
  ck_assert_int_eq(canfdi_dtc_init(&mem, canfdi_dtc_defaults, (uint8_t)CANFDI_DTC_COUNT), CANFDI_OK);
  ck_assert_int_eq(canfdi_dtc_deserialize(&mem, img, (uint32_t)(p - img)), CANFDI_OK);
  ck_assert_uint_eq(mem.diag.image_dropped, 2U);
  ck_assert_uint_eq(st(&mem, (uint8_t)canfdi_dtc_find(&mem, CANFDI_DTC_P0122)), 0xAFU);
  ck_assert_uint_eq(canfdi_dtc_count_by_mask(&mem, CDTC), 1U);

  /* more entries than this build holds: the extra ones are dropped and
   * their DTCs lose CDTC/WIR (confirmation needs an entry) */
  const uint8_t n_extra = (uint8_t)(CAP + 2U);
  ck_assert_uint_le(n_extra, CANFDI_DTC_COUNT);
  p = img;
  *p++ = 1U;
  *p++ = n_extra;
  *p++ = n_extra;
  *p++ = 0U;
  for (uint8_t i = 0U; i < n_extra; i++) {
    p = w_record(p, canfdi_dtc_defaults[i].dtc, canfdi_dtc_defaults[i].warning_indicator ? 0xAFU : 0x2FU, 1U, 0U);
  }
  for (uint8_t i = 0U; i < n_extra; i++) {
    p = w_entry(p, canfdi_dtc_defaults[i].dtc, 1U, i, 1U, i);
  }
  ck_assert_int_eq(canfdi_dtc_init(&mem, canfdi_dtc_defaults, (uint8_t)CANFDI_DTC_COUNT), CANFDI_OK);
  ck_assert_int_eq(canfdi_dtc_deserialize(&mem, img, (uint32_t)(p - img)), CANFDI_OK);
  ck_assert_uint_eq(mem.diag.image_dropped, 2U);
  ck_assert_uint_eq(canfdi_dtc_count_by_mask(&mem, CDTC), CAP);
  ck_assert_uint_eq(canfdi_dtc_count_by_mask(&mem, TF), n_extra);
  ck_assert_uint_eq(st(&mem, (uint8_t)(n_extra - 1U)) & (CDTC | WIR), 0U);
  ck_assert(canfdi_dtc_invariants_hold(&mem));

  /* not while a cycle is active */
  ck_assert_int_eq(canfdi_dtc_cycle_start(&mem), CANFDI_OK);
  ck_assert_int_eq(canfdi_dtc_deserialize(&mem, img, (uint32_t)(p - img)), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_dtc_deserialize(&mem, NULL, 4U), -CANFDI_EINVAL);
}
END_TEST

/* ------------------------------------------------------------ fuzz */

START_TEST(test_random_histories_keep_invariants)
{
  /* small custom table with N=2 and short healing/aging so that every
   * branch is reached; invariants are checked after every event inside
   * random_history; the image round trip is checked at every cycle end */
  canfdi_dtc_def_t t[CAP + 3U];
  for (uint8_t i = 0U; i < CAP + 3U; i++) {
    t[i] = def_row(0x200000U + i, (uint8_t)(1U + (i % 3U)), (uint8_t)(1U + (i % 2U)), 2U,
                   (uint8_t)((i % 4U) == 0U ? 0U : 3U), (i % 5U) != 0U);
  }
  ck_assert_int_eq(canfdi_dtc_init(&mem, t, (uint8_t)(CAP + 3U)), CANFDI_OK);
  for (uint32_t round = 0U; round < 200U; round++) {
    random_history(&mem, 777U + round, 60, 15U);
    const int32_t len = canfdi_dtc_serialize(&mem, img, sizeof img);
    ck_assert_int_gt(len, 0);
    ck_assert_int_eq(canfdi_dtc_init(&mem2, t, (uint8_t)(CAP + 3U)), CANFDI_OK);
    ck_assert_int_eq(canfdi_dtc_deserialize(&mem2, img, (uint32_t)len), CANFDI_OK);
    ck_assert(same_state(&mem, &mem2));
  }
  /* every code path was exercised */
  ck_assert_uint_gt(mem.diag.displacements, 0U);
  ck_assert_uint_gt(mem.diag.aged, 0U);
  ck_assert_uint_gt(mem.diag.overflows, 0U);
}
END_TEST

static Suite *make_suite(void)
{
  Suite *s = suite_create("dtc");
  TCase *tc = tcase_create("table");
  tcase_add_test(tc, test_defaults_match_csv);
  tcase_add_test(tc, test_defaults_group_is_component);
  tcase_add_test(tc, test_init_state);
  tcase_add_test(tc, test_init_rejects);
  suite_add_tcase(s, tc);

  tc = tcase_create("status_bits");
  tcase_add_loop_test(tc, test_status_sequences, 0, N_SEQ_CASES);
  tcase_add_test(tc, test_cycle_end_without_start);
  suite_add_tcase(s, tc);

  tc = tcase_create("debounce");
  tcase_add_test(tc, test_frame_class_counts_reports);
  tcase_add_test(tc, test_direct_class_qualifies_each_report);
  suite_add_tcase(s, tc);

  tc = tcase_create("freeze_frame_occurrence");
  tcase_add_test(tc, test_freeze_frame_first_failure);
  tcase_add_loop_test(tc, test_occurrence_counter, 0, (int)(sizeof occ_cases / sizeof occ_cases[0]));
  tcase_add_test(tc, test_occurrence_saturates);
  suite_add_tcase(s, tc);

  tc = tcase_create("capacity");
  tcase_add_loop_test(tc, test_displacement, 0, N_DISP_CASES);
  tcase_add_test(tc, test_not_stored_retries_later);
  tcase_add_test(tc, test_capacity_with_product_table);
  suite_add_tcase(s, tc);

  tc = tcase_create("queries");
  tcase_add_test(tc, test_queries_by_mask);
  suite_add_tcase(s, tc);

  tc = tcase_create("image");
  tcase_add_loop_test(tc, test_image_round_trip, 0, 4);
  tcase_add_test(tc, test_image_full_size_bound);
  tcase_add_test(tc, test_image_layout_by_hand);
  tcase_add_test(tc, test_image_v2_time_beyond_32_bits);
  tcase_add_loop_test(tc, test_image_rejects, 0, (int)(sizeof bad_imgs / sizeof bad_imgs[0]));
  tcase_add_test(tc, test_image_table_change_and_capacity);
  suite_add_tcase(s, tc);

  tc = tcase_create("fuzz");
  tcase_add_test(tc, test_random_histories_keep_invariants);
  tcase_set_timeout(tc, 120);
  suite_add_tcase(s, tc);
  return s;
}

CANFDI_UNIT_MAIN(make_suite)
