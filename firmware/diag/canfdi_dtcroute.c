/*
 * canfdi_dtcroute.c — monitor results to trouble codes; the manual is the
 * header.
 */
#include "diag/canfdi_dtcroute.h"

#include "core/canfdi_count.h"
#include "core/canfdi_intrin.h"
#include "diag/canfdi_diagnosis.h"

/* The DTCs of a step are collected as bit masks (bit = DTC table index). */
CANFDI_STATIC_ASSERT(CANFDI_CFG_DTC_MAX_DTCS <= 32U, dtc_indices_fit_the_mask);
CANFDI_STATIC_ASSERT(CANFDI_FAULT_COUNT <= 32U, fault_ids_fit_the_mask);

/* The fault ids a verdict is routed for: 1 .. CANFDI_FAULT_COUNT - 1 (id 0
 * names no fault). */
#define FAULT_IDS \
  (((CANFDI_FAULT_COUNT >= 32U) ? UINT32_MAX : ((UINT32_C(1) << (CANFDI_FAULT_COUNT & 31U)) - 1U)) & ~UINT32_C(1))

void canfdi_dtcroute_default_cfg(canfdi_dtcroute_cfg_t *cfg)
{
  if (cfg != NULL) {
    cfg->p2135_steps = 500U;
    cfg->verdicts_per_step = CANFDI_DTCROUTE_VERDICTS_PER_STEP;
  }
}

static uint8_t index_of(const canfdi_dtc_t *dtc, uint32_t code)
{
  const int32_t i = (code != 0U) ? canfdi_dtc_find(dtc, code) : -CANFDI_EINVAL;
  return (i >= 0) ? (uint8_t)i : (uint8_t)CANFDI_DTC_NONE;
}

int32_t canfdi_dtcroute_init(canfdi_dtcroute_t *r, const canfdi_dtcroute_cfg_t *cfg,
                             const canfdi_dtc_t *dtc)
{
  int32_t rc = -CANFDI_EINVAL;
  if (r != NULL) {
    r->initialised = false;
    if ((cfg != NULL) && (dtc != NULL) && (dtc->table != NULL) && (cfg->p2135_steps >= 1U) &&
        (cfg->verdicts_per_step >= 1U) && (cfg->verdicts_per_step <= 32U)) {
      uint32_t f;
      uint32_t j;
      r->cfg = *cfg;
      r->comm_faults = 0U;
      r->comm_dtcs = 0U;
      r->other_faults = 0U;
      for (f = 0U; f < CANFDI_FAULT_COUNT; f++) {
        for (j = 0U; j < CANFDI_CATALOGUE_MAX_DTCS; j++) {
          r->fault_dtc[f][j] = index_of(dtc, canfdi_catalogue_fault[f].dtc[j]);
        }
        if (f == 0U) {
          /* no fault */
        } else if (canfdi_catalogue_fault[f].kind == CANFDI_KIND_COMMUNICATION) {
          r->comm_faults |= CANFDI_FAULT_BIT(f);
          r->comm_dtcs |= (r->fault_dtc[f][0] != CANFDI_DTC_NONE) ? (UINT32_C(1) << r->fault_dtc[f][0]) : 0U;
        } else {
          r->other_faults |= CANFDI_FAULT_BIT(f);
        }
      }
      r->s3_dtcs = 0U;
      for (j = 0U; j < (uint32_t)CANFDI_RX_MON_COUNT; j++) {
        r->com_dtc[j] = index_of(dtc, canfdi_rx_monitor_dtc(j));
        r->s3_dtcs |= (r->com_dtc[j] != CANFDI_DTC_NONE) ? (UINT32_C(1) << r->com_dtc[j]) : 0U;
      }
      r->p2135_dtc = index_of(dtc, CANFDI_DTC_P2135);
      r->p2135_n = 0U;
      r->faults = 0U;
      r->agg_last_valid = false;
      r->src1_valid = false;
      r->comm_valid = false;
      r->comm_tf = 0U;
      r->changes_out = dtc->changes;
      for (j = 0U; j < CANFDI_DTCROUTE_S3_SETS; j++) {
        r->s3_quiet[j] = false;
        r->s3_act[j] = 0U;
        r->s3_n[j] = 0U;
      }
      r->s3_next = 0U;
      r->diag = (canfdi_dtcroute_diag_t){0};
      r->initialised = true;
      rc = CANFDI_OK;
    }
  }
  return rc;
}

/* The number of bits set in x. */
static uint32_t bit_count(uint32_t x)
{
  uint32_t n = 0U;
  uint32_t rest;
  for (rest = x; rest != 0U; rest &= rest - 1U) {
    n++;
  }
  return n;
}

/* Source 1: the DTCs of the faults with a verdict, as two DTC masks (a DTC
 * fails if any fault that feeds it fails, else passes if any passes), and
 * how many DTCs have one. A function of the two fault masks alone: kept
 * while they stay the same (most steps). */
static void combine_faults(canfdi_dtcroute_t *r, uint32_t failed, uint32_t passed)
{
  if (!r->src1_valid || (failed != r->src1_in_fail) || (passed != r->src1_in_pass)) {
    uint32_t fm = 0U;
    uint32_t pm = 0U;
    uint32_t n = 0U;
    uint32_t x = failed | passed;
    while (x != 0U) {
      const uint32_t f = (uint32_t)canfdi_ctz32(x);
      const uint32_t fbit = CANFDI_FAULT_BIT(f);
      uint32_t dm = 0U;
      uint32_t j;
      x &= x - 1U;
      for (j = 0U; j < CANFDI_CATALOGUE_MAX_DTCS; j++) {
        const uint8_t idx = r->fault_dtc[f][j];
        dm |= (idx != CANFDI_DTC_NONE) ? (UINT32_C(1) << idx) : 0U;
      }
      if ((failed & fbit) != 0U) {
        fm |= dm;
      } else {
        pm |= dm;
      }
    }
    pm &= ~fm;
    n = bit_count(fm | pm);
    r->src1_in_fail = failed;
    r->src1_in_pass = passed;
    r->src1_fail = fm;
    r->src1_pass = pm;
    r->src1_n = n;
    r->src1_valid = true;
  }
}

/* Source 2: P2135 from the persistence of an unisolated disagreement, into
 * the DTC masks *fm / *pm (it overrides source 1's verdict of that DTC). */
static void p2135(canfdi_dtcroute_t *r, const canfdi_dtcroute_in_t *in, uint32_t *fm, uint32_t *pm)
{
  const uint32_t bit = UINT32_C(1) << r->p2135_dtc;
  if (in->corr_not_isolated) {
    if (r->p2135_n < r->cfg.p2135_steps) {
      r->p2135_n++;
    } else {
      *fm |= bit;
      *pm &= ~bit;
    }
  } else if (in->corr_tested) {
    r->p2135_n = 0U;
    *pm |= bit;
    *fm &= ~bit;
  } else {
    /* the correlation channel is invalid: not tested */
  }
}

/* What report() did with a report (bit flags). */
#define REP_REJECTED 1U /* the memory refused it */
#define REP_NOOP 2U     /* a pass that changes nothing, not given */

/* One report to the memory; a pass that would change nothing
 * (canfdi_dtc_pass_is_noop: most reports of a step) is counted without the
 * call, which would return at once. Returns REP_* flags. */
static uint32_t report(canfdi_dtcroute_t *r, canfdi_dtc_t *dtc, uint8_t idx, canfdi_deb_report_t rep,
                       const canfdi_dtc_ff_t *ff)
{
  uint32_t out = 0U;
  canfdi_count_inc(&r->diag.reports);
  if (canfdi_dtc_pass_is_noop(dtc, idx, rep)) {
    out = REP_NOOP; /* answered: the status stands */
  } else if (canfdi_dtc_report(dtc, idx, rep, ff) < 0) {
    canfdi_count_inc(&r->diag.reports_rejected);
    out = REP_REJECTED;
  } else {
    /* taken */
  }
  return out;
}

/* Source 3's remembered passes no longer hold. */
static void s3_forget(canfdi_dtcroute_t *r)
{
  uint32_t k;
  for (k = 0U; k < CANFDI_DTCROUTE_S3_SETS; k++) {
    r->s3_quiet[k] = false;
  }
}

/* The lowest k set bits of x (all of x when it has k or fewer). */
static uint32_t lowest_bits(uint32_t x, uint32_t k)
{
  uint32_t out = 0U;
  uint32_t rest = x;
  uint32_t n;
  for (n = 0U; (n < k) && (rest != 0U); n++) {
    out |= rest & ~(rest - 1U); /* the lowest set bit (rest != 0) */
    rest &= rest - 1U;
  }
  return out;
}

/* Sources 1-2: the DTC masks fm / pm (n_agg DTCs). To a memory that has
 * not changed since the last report, only the DTCs whose verdict changed
 * are given; the others are counted as given (the header: a verdict given
 * again to its DTC changes nothing). At most cfg.verdicts_per_step are
 * given, failures first: the rest stay due, and are given in the next
 * steps (their last-reported bits are left clear, so they still differ).
 * Returns the reports refused. */
static int32_t report_verdicts(canfdi_dtcroute_t *r, canfdi_dtc_t *dtc, uint32_t fm, uint32_t pm, uint32_t n_agg,
                               const canfdi_dtc_ff_t *ff)
{
  int32_t rc = 0;
  uint32_t due = fm | pm;
  uint32_t x;
  uint32_t left;
  uint32_t given = 0U;
  if (r->agg_last_valid && dtc->cycle_active) {
    due &= (fm ^ r->agg_last_fail) | (pm ^ r->agg_last_pass);
  }
  x = due;
  left = 0U;
  if (due != 0U) {
    /* most steps have none due */
    x = lowest_bits(due & fm, r->cfg.verdicts_per_step);
    x |= lowest_bits(due & ~fm, (uint32_t)r->cfg.verdicts_per_step - bit_count(x));
    left = due & ~x;
  }
  if ((x & r->s3_dtcs) != 0U) {
    /* a code source 3 feeds gets a verdict (never in the product) */
    s3_forget(r);
  }
  if ((x & r->comm_dtcs) != 0U) {
    r->comm_valid = false; /* likewise */
  }
  /* in DTC table order: the lowest index first (a DTC beyond the memory's
   * table has no index, so every DTC in the masks is one of its DTCs) */
  while (x != 0U) {
    const uint32_t idx = (uint32_t)canfdi_ctz32(x);
    x &= x - 1U;
    if (idx < (uint32_t)dtc->n_dtcs) {
      const uint32_t f = report(r, dtc, (uint8_t)idx,
                                (((fm >> idx) & 1U) != 0U) ? CANFDI_DEB_REPORT_FAILED : CANFDI_DEB_REPORT_PASSED, ff);
      rc += ((f & REP_REJECTED) != 0U) ? 1 : 0;
      given++;
    }
  }
  canfdi_count_add(&r->diag.reports, (n_agg - given) - bit_count(left));
  r->agg_last_fail = fm & ~left;
  r->agg_last_pass = pm & ~left;
  r->agg_last_valid = (rc == 0);
  return rc;
}

/* Source 3: the monitors' reports, one per DTC they feed. A step with
 * the same monitors passing, none failing, as a remembered pass whose
 * reports were all passes that changed nothing (one of
 * CANFDI_DTCROUTE_S3_SETS monitor sets: the monitors of the 10 ms frames
 * run in one step of ten, the others in every step), to a memory
 * unchanged since, is that pass again: counted as given. Returns the
 * reports refused. */
static int32_t report_monitors(canfdi_dtcroute_t *r, canfdi_dtc_t *dtc, const canfdi_rx_report_t *com,
                               const canfdi_dtc_ff_t *ff)
{
  int32_t rc = 0;
  const uint32_t act = com->prefailed | com->prepassed;
  uint32_t hit = CANFDI_DTCROUTE_S3_SETS;
  uint32_t k;
  if (!dtc->cycle_active) {
    s3_forget(r); /* every report is refused */
  }
  for (k = 0U; (k < CANFDI_DTCROUTE_S3_SETS) && (com->prefailed == 0U); k++) {
    hit = (r->s3_quiet[k] && (act == r->s3_act[k])) ? k : hit;
  }
  if (hit < CANFDI_DTCROUTE_S3_SETS) {
    canfdi_count_add(&r->diag.reports, r->s3_n[hit]);
  } else {
    /* combined per DTC: several monitors share U1A50/U1A51, whose
     * debouncer must see one report per step (a failure dominates); the
     * DTCs collected as bits, then reported in table order (lowest index
     * first) */
    uint32_t touched = 0U;
    uint32_t bits_failed = 0U;
    uint32_t n = 0U;
    uint32_t noops = 0U;
    uint32_t j;
    for (j = 0U; (j < (uint32_t)CANFDI_RX_MON_COUNT) && ((act >> j) != 0U); j++) {
      const uint32_t bit = UINT32_C(1) << j;
      const uint8_t idx = r->com_dtc[j];
      if (((act & bit) != 0U) && (idx != CANFDI_DTC_NONE)) {
        touched |= UINT32_C(1) << idx;
        if ((com->prefailed & bit) != 0U) {
          bits_failed |= UINT32_C(1) << idx;
        }
      }
    }
    /* a code with a verdict of sources 1-2 (never in the product): that
     * verdict is due again in the next step (a report changes its own code
     * only, so the others' verdicts still hold) */
    r->agg_last_fail &= ~touched;
    r->agg_last_pass &= ~touched;
    while (touched != 0U) {
      const uint32_t low = touched & ~(touched - 1U); /* the lowest set bit */
      const uint32_t idx = (uint32_t)canfdi_ctz32(low);
      touched &= touched - 1U;
      if (idx < (uint32_t)dtc->n_dtcs) {
        const uint32_t f = report(r, dtc, (uint8_t)idx,
                                  ((bits_failed & low) != 0U) ? CANFDI_DEB_REPORT_PREFAILED
                                                              : CANFDI_DEB_REPORT_PREPASSED,
                                  ff);
        rc += ((f & REP_REJECTED) != 0U) ? 1 : 0;
        noops += ((f & REP_NOOP) != 0U) ? 1U : 0U;
        n++;
      }
    }
    if (noops == n) {
      /* remembered in place of the older set */
      k = r->s3_next;
      r->s3_next = (uint8_t)((k + 1U) % CANFDI_DTCROUTE_S3_SETS);
      r->s3_quiet[k] = true;
      r->s3_act[k] = act;
      r->s3_n[k] = n;
    } else {
      /* a report moved a debouncer (a PREFAILED may move one without
       * moving `changes`): no remembered pass holds, and a communication
       * fault's testFailed may have moved */
      s3_forget(r);
      r->comm_valid = false;
    }
  }
  return rc;
}

int32_t canfdi_dtcroute_step(canfdi_dtcroute_t *r, canfdi_dtc_t *dtc,
                             const canfdi_dtcroute_in_t *in)
{
  int32_t rc = -CANFDI_EINVAL;
  if ((r != NULL) && r->initialised && (dtc != NULL) && (in != NULL) && (in->com != NULL)) {
    /* the manager's own findings fail */
    const uint32_t failed = (in->failed | in->mgr_detected) & FAULT_IDS;
    uint32_t fm;
    uint32_t pm;
    uint32_t n_agg;
    rc = 0;
    if (dtc->changes != r->changes_out) {
      /* the memory changed outside the routing since its last step (a
       * clear, a cycle, aging, a restored image): no verdict or pass given
       * before holds */
      r->agg_last_valid = false;
      s3_forget(r);
      r->comm_valid = false;
    }
    combine_faults(r, failed, (in->passed & ~failed) & FAULT_IDS);
    fm = r->src1_fail;
    pm = r->src1_pass;
    n_agg = r->src1_n;
    if (r->p2135_dtc != CANFDI_DTC_NONE) {
      const uint32_t bit = UINT32_C(1) << r->p2135_dtc;
      const bool had = ((fm | pm) & bit) != 0U;
      p2135(r, in, &fm, &pm);
      n_agg += (!had && (((fm | pm) & bit) != 0U)) ? 1U : 0U;
    }
    rc += report_verdicts(r, dtc, fm, pm, n_agg, in->ff);
    /* Source 3: the input supervision's monitors (raw per-step results) */
    rc += report_monitors(r, dtc, in->com, in->ff);
    r->changes_out = dtc->changes;
    canfdi_count_inc(&r->diag.steps);
  }
  return rc;
}

uint32_t canfdi_dtcroute_manager_faults(canfdi_dtcroute_t *r, const canfdi_dtc_t *dtc, uint32_t failed,
                                        uint32_t passed)
{
  uint32_t bits = 0U;
  if ((r != NULL) && r->initialised && (dtc != NULL)) {
    /* the communication faults: their codes' testFailed, read again only
     * when one of those codes may have changed: a report to one of them
     * that was not a pass changing nothing, or a change of the memory
     * outside the routing (its `changes` is not where the routing's last
     * step left it) */
    if (!r->comm_valid || (dtc->changes != r->changes_out)) {
      uint32_t x = r->comm_faults;
      uint32_t c = 0U;
      while (x != 0U) {
        const uint32_t f = (uint32_t)canfdi_ctz32(x);
        const uint8_t idx = r->fault_dtc[f][0];
        const uint8_t st = ((idx != CANFDI_DTC_NONE) && (dtc->table != NULL) && (idx < dtc->n_dtcs))
                               ? canfdi_dtc_status_at(dtc, idx)
                               : 0U;
        x &= x - 1U;
        c |= ((st & CANFDI_DTC_ST_TF) != 0U) ? CANFDI_FAULT_BIT(f) : 0U;
      }
      r->comm_tf = c;
      r->comm_valid = true;
    }
    /* the others: FAILED sets, PASSED clears (disjoint), NONE keeps */
    bits = (r->faults | (failed & r->other_faults)) & ~(passed & r->other_faults);
    bits = (bits & ~r->comm_faults) | r->comm_tf;
    r->faults = bits;
  }
  return bits;
}

canfdi_dtcroute_diag_t canfdi_dtcroute_diag(const canfdi_dtcroute_t *r)
{
  canfdi_dtcroute_diag_t d = {0};
  if (r != NULL) {
    d = r->diag;
  }
  return d;
}
