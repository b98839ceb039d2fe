/*
 * canfdi_dtcroute.c — monitor results to trouble codes; the manual is the
 * header.
 */
#include "diag/canfdi_dtcroute.h"

#include <string.h>

#include "core/canfdi_count.h"
#include "core/canfdi_intrin.h"
#include "diag/canfdi_diagnosis.h"

/* Source 3 collects the DTCs it reports as a bit mask. */
CANFDI_STATIC_ASSERT(CANFDI_CFG_DTC_MAX_DTCS <= 32U, dtc_indices_fit_the_mask);

void canfdi_dtcroute_default_cfg(canfdi_dtcroute_cfg_t *cfg)
{
  if (cfg != NULL) {
    cfg->p2135_steps = 500U;
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
    if ((cfg != NULL) && (dtc != NULL) && (dtc->table != NULL) && (cfg->p2135_steps >= 1U)) {
      uint32_t f;
      uint32_t j;
      r->cfg = *cfg;
      for (f = 0U; f < CANFDI_FAULT_COUNT; f++) {
        for (j = 0U; j < CANFDI_CATALOGUE_MAX_DTCS; j++) {
          r->fault_dtc[f][j] = index_of(dtc, canfdi_catalogue_fault[f].dtc[j]);
        }
      }
      for (j = 0U; j < (uint32_t)CANFDI_RX_MON_COUNT; j++) {
        r->com_dtc[j] = index_of(dtc, canfdi_rx_monitor_dtc(j));
      }
      r->p2135_dtc = index_of(dtc, CANFDI_DTC_P2135);
      r->p2135_n = 0U;
      r->faults = 0U;
      r->agg_last_valid = false;
      r->changes_last = 0U;
      r->diag = (canfdi_dtcroute_diag_t){0};
      r->initialised = true;
      rc = CANFDI_OK;
    }
  }
  return rc;
}

/* Source 1: per DTC the combined verdict of the faults that feed it;
 * returns how many DTCs have one. */
static uint32_t combine_faults(const canfdi_dtcroute_t *r, const canfdi_dtcroute_in_t *in, int8_t *agg)
{
  uint32_t f;
  uint32_t j;
  uint32_t n = 0U;
  for (f = 1U; f < CANFDI_FAULT_COUNT; f++) {
    int8_t v = in->report[f];
    if ((in->mgr_detected & CANFDI_FAULT_BIT(f)) != 0U) {
      v = CANFDI_DIAG_REPORT_FAILED;
    }
    if (v != CANFDI_DIAG_REPORT_NONE) {
      for (j = 0U; j < CANFDI_CATALOGUE_MAX_DTCS; j++) {
        const uint8_t idx = r->fault_dtc[f][j];
        if ((idx != CANFDI_DTC_NONE) && (agg[idx] != CANFDI_DIAG_REPORT_FAILED)) {
          n += (agg[idx] == CANFDI_DIAG_REPORT_NONE) ? 1U : 0U;
          agg[idx] = v;
        }
      }
    }
  }
  return n;
}

/* Source 2: P2135 from the persistence of an unisolated disagreement. */
static void p2135(canfdi_dtcroute_t *r, const canfdi_dtcroute_in_t *in, int8_t *agg)
{
  if (r->p2135_dtc != CANFDI_DTC_NONE) {
    if (in->corr_not_isolated) {
      if (r->p2135_n < r->cfg.p2135_steps) {
        r->p2135_n++;
      } else {
        agg[r->p2135_dtc] = CANFDI_DIAG_REPORT_FAILED;
      }
    } else if (in->corr_tested) {
      r->p2135_n = 0U;
      agg[r->p2135_dtc] = CANFDI_DIAG_REPORT_PASSED;
    } else {
      /* the correlation channel is invalid: not tested */
    }
  }
}

/* One report to the memory; a pass that would change nothing
 * (canfdi_dtc_pass_is_noop: most reports of a step) is counted without the
 * call, which would return at once. */
static int32_t report(canfdi_dtcroute_t *r, canfdi_dtc_t *dtc, uint8_t idx, canfdi_deb_report_t rep,
                      const canfdi_dtc_ff_t *ff)
{
  int32_t rejected = 0;
  canfdi_count_inc(&r->diag.reports);
  if (canfdi_dtc_pass_is_noop(dtc, idx, rep)) {
    /* answered: the status stands */
  } else if (canfdi_dtc_report(dtc, idx, rep, ff) < 0) {
    canfdi_count_inc(&r->diag.reports_rejected);
    rejected = 1;
  } else {
    /* taken */
  }
  return rejected;
}

int32_t canfdi_dtcroute_step(canfdi_dtcroute_t *r, canfdi_dtc_t *dtc,
                             const canfdi_dtcroute_in_t *in)
{
  int32_t rc = -CANFDI_EINVAL;
  if ((r != NULL) && r->initialised && (dtc != NULL) && (in != NULL) && (in->report != NULL) &&
      (in->com != NULL)) {
    int8_t agg[CANFDI_CFG_DTC_MAX_DTCS];
    uint32_t n_agg;
    uint32_t act;
    uint32_t touched = 0U;
    uint32_t failed = 0U;
    uint32_t j;
    rc = 0;
    (void)memset(agg, CANFDI_DIAG_REPORT_NONE, sizeof agg);
    n_agg = combine_faults(r, in, agg);
    if (r->p2135_dtc != CANFDI_DTC_NONE) {
      const bool had = (agg[r->p2135_dtc] != CANFDI_DIAG_REPORT_NONE);
      p2135(r, in, agg);
      n_agg += (!had && (agg[r->p2135_dtc] != CANFDI_DIAG_REPORT_NONE)) ? 1U : 0U;
    }
    if (r->agg_last_valid && dtc->cycle_active && (dtc->changes == r->changes_last) &&
        (memcmp(agg, r->agg_last, sizeof agg) == 0)) {
      /* the same verdicts to an unchanged memory: nothing would change
       * (the header); counted as given (a DTC beyond the memory's table
       * has no index, so every entry counted is one of its DTCs) */
      canfdi_count_add(&r->diag.reports, n_agg);
    } else {
      for (j = 0U; j < (uint32_t)dtc->n_dtcs; j++) {
        if (agg[j] != CANFDI_DIAG_REPORT_NONE) {
          rc += report(r, dtc, (uint8_t)j,
                       (agg[j] > 0) ? CANFDI_DEB_REPORT_FAILED : CANFDI_DEB_REPORT_PASSED, in->ff);
        }
      }
      (void)memcpy(r->agg_last, agg, sizeof agg);
      r->agg_last_valid = (rc == 0);
    }
    r->changes_last = dtc->changes;
    /* Source 3: the input supervision's monitors (raw per-step results),
     * combined per DTC: several monitors share U1A50/U1A51, whose
     * debouncer must see one report per step (a failure dominates). The
     * DTCs to report are collected as bits, then reported in table order
     * (lowest index first). */
    act = in->com->prefailed | in->com->prepassed;
    for (j = 0U; (j < (uint32_t)CANFDI_RX_MON_COUNT) && ((act >> j) != 0U); j++) {
      const uint32_t bit = UINT32_C(1) << j;
      const uint8_t idx = r->com_dtc[j];
      if (((act & bit) != 0U) && (idx != CANFDI_DTC_NONE)) {
        touched |= UINT32_C(1) << idx;
        if ((in->com->prefailed & bit) != 0U) {
          failed |= UINT32_C(1) << idx;
        }
      }
    }
    while (touched != 0U) {
      const uint32_t low = touched & ~(touched - 1U); /* the lowest set bit */
      const uint32_t idx = 31U - canfdi_clz32(low);
      touched &= touched - 1U;
      if (idx < (uint32_t)dtc->n_dtcs) {
        rc += report(r, dtc, (uint8_t)idx,
                     ((failed & low) != 0U) ? CANFDI_DEB_REPORT_PREFAILED : CANFDI_DEB_REPORT_PREPASSED, in->ff);
      }
    }
    canfdi_count_inc(&r->diag.steps);
  }
  return rc;
}

uint32_t canfdi_dtcroute_manager_faults(canfdi_dtcroute_t *r, const canfdi_dtc_t *dtc,
                                        const int8_t *report_v)
{
  uint32_t bits = 0U;
  if ((r != NULL) && r->initialised && (dtc != NULL) && (report_v != NULL)) {
    uint32_t f;
    bits = r->faults;
    for (f = 1U; f < CANFDI_FAULT_COUNT; f++) {
      if (canfdi_catalogue_fault[f].kind == CANFDI_KIND_COMMUNICATION) {
        const uint8_t idx = r->fault_dtc[f][0];
        const uint8_t st =
            ((idx != CANFDI_DTC_NONE) && (dtc->table != NULL) && (idx < dtc->n_dtcs)) ? canfdi_dtc_status_at(dtc, idx) : 0U;
        if ((st & CANFDI_DTC_ST_TF) != 0U) {
          bits |= CANFDI_FAULT_BIT(f);
        } else {
          bits &= ~CANFDI_FAULT_BIT(f);
        }
      } else if (report_v[f] == CANFDI_DIAG_REPORT_FAILED) {
        bits |= CANFDI_FAULT_BIT(f);
      } else if (report_v[f] == CANFDI_DIAG_REPORT_PASSED) {
        bits &= ~CANFDI_FAULT_BIT(f);
      } else {
        /* not tested: keep */
      }
    }
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
