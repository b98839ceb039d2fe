/*
 * canfdi_dtcroute.h — from monitor results to trouble codes: routes each
 * step's verdicts into the DTC memory (diag/canfdi_dtc.h), and latches the
 * faults the actuator manager acts on.
 *
 * Sources per step, reported in this order:
 *   1. the diagnosis' verdict per catalogue fault (its failed and passed
 *      masks, canfdi_diagnosis_failed_mask / _passed_mask), overridden by
 *      FAILED for the faults the actuator manager detected itself in the
 *      last step; a DTC fed by several faults (P0122: TPS1 open and both
 *      TPS lost) fails if any of them reports FAILED and passes only if
 *      none fails and one passes; reported in DTC table order;
 *   2. P2135 (TPS1/TPS2 correlation), which has no fault id: FAILED once
 *      the diagnosis has held a TPS disagreement it could not isolate to
 *      one sensor for p2135_steps consecutive steps; PASSED while the
 *      correlation channel is valid and no disagreement persists (the
 *      count restarts); not tested while the channel is invalid (the count
 *      holds). A drift the vote isolates (P0121/P0221) within p2135_steps
 *      is not a P2135;
 *   3. the input supervision's monitors (canfdi_rx report of the step),
 *      each to its U-code (monitors without a code skipped), in DTC table
 *      order; the monitors that share a code (the setpoints': U1A50 for
 *      both timeouts, U1A51 for the rest) are combined into one report
 *      per step, PREFAILED if any of them saw its symptom, else PREPASSED
 *      if any ran (one report per step is what the debouncer counts).
 * The DTC table index of every fault, monitor and of P2135 is looked up
 * once at init (a linear search per code), so a step costs no search.
 * Sources 1 and 2 give PASSED or FAILED, which the DTC memory's debouncer
 * takes at once. A verdict given again to its DTC, in the same operation
 * cycle and with no clear in between, changes nothing: a second FAILED
 * finds the code failed, stored or not (a code displaced from the memory is
 * not stored again before its next failure), a second PASSED finds it
 * passed. So a step gives only the DTCs whose verdict changed, and counts
 * the others as reported (most steps give none), as long as nothing else
 * touched those codes since: nothing outside the routing changed the memory
 * (its `changes` counter, which every status, clear, cycle and restored
 * image moves, is where the routing's last step left it), and source 3 did
 * not report to the code (never in the product: the diagnosis gives no
 * verdict for the communication faults and the manager detects none of
 * them, so the U-codes are source 3's alone; such a code's verdict is due
 * again in the next step, the others' still hold). The routing's own reports
 * to other codes do not count: a report changes its own code only, and a
 * displacement only the victim's CDTC and WIR, which no pass test reads.
 * Budget: a step gives at most cfg.verdicts_per_step of these DTCs
 * (CANFDI_DTCROUTE_VERDICTS_PER_STEP = 4 in the product), the failures
 * first, then the passes, each in table order; the others stay due and
 * are given in the next steps, with the verdict they have then. Why: after
 * a tester's clear, a new operation cycle, or at the first verdicts after
 * power-up, every DTC with a verdict is due at once (about twenty), and
 * giving them in one step, each with its status change and its on-change
 * EcuDtc frame, costs about 5 000 instructions more than a quiet step on a
 * Cortex-M4, and makes it the costliest 1 ms step of the application.
 * Given four per step, the last of twenty reaches the memory 4 ms later. A
 * failure waits only when more than four DTCs fail in the same step.
 * Source 3's PREPASSED reports step their codes' debouncers towards the
 * pass threshold; once a step's reports are all passes that change nothing
 * (canfdi_dtc_pass_is_noop), a later step with the same monitors passing
 * and none failing is the same step again, and is counted as reported
 * without them, under the same condition (nothing outside the routing
 * changed the memory, sources 1-2 gave none of its codes a verdict). Two
 * such passes are remembered (CANFDI_DTCROUTE_S3_SETS), because the
 * monitors of the 10 ms frames run in one step of ten and the set
 * alternates; both are also forgotten when a pass moves a debouncer (a
 * PREFAILED may move one without moving `changes`), so every code a
 * remembered pass touched still sits where that pass left it.
 * tests/unit/test_dtcroute.c checks all of this against a reference that
 * reports every verdict and monitor every step (but the DTCs over the
 * budget, which it keeps per DTC in arrays), with budgets of 1, 2, 4 and
 * 32.
 *
 * Faults for the manager (canfdi_dtcroute_manager_faults): a communication
 * fault while its trouble code has testFailed (qualified by the DTC memory's
 * debouncing); any other fault latched from a FAILED verdict of the
 * diagnosis until a PASSED one (not tested keeps it).
 *
 * Why masks. Both run every step, and a step's verdicts rarely differ from
 * the last step's: with the verdicts as bit masks (faults, and DTCs by
 * table index) the steady state is a few word compares. A pass over the
 * 32 faults' verdicts (int8_t per fault) in both functions, and the
 * diagnosis writing them, cost about 900 instructions per step more on a
 * Cortex-M4 (`make pil-test`, dcm_ia_offset: mean 20 709 against 19 788).
 *
 * Scaling and overflow: no arithmetic besides the persistence count
 * (uint16_t, stops at p2135_steps) and the saturating counters.
 * Cost per canfdi_dtcroute_step: source 1's DTC masks only when the fault
 * masks differ from the last step's (then two table reads per fault with a
 * verdict); a report per DTC whose verdict changed, or per DTC with a
 * verdict when the memory changed, verdicts_per_step at most (each a
 * canfdi_dtc_report; a pass that would change nothing,
 * canfdi_dtc_pass_is_noop, is counted without the call); for source 3 a
 * few compares in the steady state, else the monitor bits up to the highest one set (20 at most) and one
 * report per DTC they feed (collected as a bit mask, reported lowest
 * index first).
 * manager_faults: a few mask operations, and a status read per
 * communication fault when one of their codes may have changed since the
 * last read (a report to one of them that was not a pass changing nothing,
 * or a change of the memory outside the routing).
 * Memory: sizeof(canfdi_dtcroute_t) = 188 bytes on a 32-bit target (the
 * index tables 64 + 20, the fault masks, source 1's last inputs and
 * masks, the last reported masks, source 3's two remembered passes and
 * its DTC mask, the communication faults' testFailed, state, config,
 * diagnostics). No heap.
 */
#ifndef CANFDI_DTCROUTE_H
#define CANFDI_DTCROUTE_H

#include "catalogue/canfdi_catalogue.h"
#include "comm/canfdi_rx.h"
#include "core/canfdi_common.h"
#include "diag/canfdi_dtc.h"

/* Source 3's remembered quiet passes: two monitor sets (the monitors of
 * the 10 ms frames run in one step of ten, the 1 ms ones in every step). */
#define CANFDI_DTCROUTE_S3_SETS 2U

/* The product's budget of verdicts given per step (see the header). */
#define CANFDI_DTCROUTE_VERDICTS_PER_STEP 4U

typedef struct {
  uint16_t p2135_steps; /* 1..65535: unisolated disagreement until P2135 fails */
  uint8_t verdicts_per_step; /* 1..32: sources 1-2's DTCs given per step at most */
} canfdi_dtcroute_cfg_t;

/* One step's verdicts. */
typedef struct {
  uint32_t failed;             /* fault bits the diagnosis reports FAILED */
  uint32_t passed;             /* fault bits it reports PASSED (disjoint) */
  uint32_t mgr_detected;       /* fault bits the manager detected itself (last step) */
  bool corr_not_isolated;      /* TPS disagreement persistent, not isolated */
  bool corr_tested;            /* the TPS correlation channel is valid */
  const canfdi_rx_report_t *com; /* the input supervision's monitors of this step */
  const canfdi_dtc_ff_t *ff;   /* snapshot stored with a first failure */
} canfdi_dtcroute_in_t;

/* Monotone counters, saturating at UINT32_MAX; only init zeroes them. */
typedef struct {
  uint32_t steps;
  uint32_t reports;          /* reports given to the DTC memory */
  uint32_t reports_rejected; /* reports the DTC memory refused (no cycle, bad index) */
} canfdi_dtcroute_diag_t;

typedef struct {
  canfdi_dtcroute_cfg_t cfg;
  uint8_t fault_dtc[CANFDI_FAULT_COUNT][CANFDI_CATALOGUE_MAX_DTCS]; /* DTC index or NONE */
  uint8_t com_dtc[CANFDI_RX_MON_COUNT];                            /* DTC index or NONE */
  uint8_t p2135_dtc;                                               /* DTC index or NONE */
  uint16_t p2135_n;   /* steps the disagreement stayed unisolated */
  uint32_t faults;    /* latched fault bits for the manager */
  uint32_t comm_faults;  /* fault bits of kind communication */
  uint32_t other_faults; /* the other fault bits (ids >= 1) */
  uint32_t src1_in_fail; /* source 1's fault masks as last combined */
  uint32_t src1_in_pass;
  uint32_t src1_fail;    /* their DTC masks (bit = table index) */
  uint32_t src1_pass;
  uint32_t src1_n;       /* DTCs with a verdict among them */
  uint32_t agg_last_fail; /* sources 1-2 as last reported: failed DTCs */
  uint32_t agg_last_pass; /* and passed DTCs */
  uint32_t changes_out;  /* dtc->changes at the end of the last step */
  uint32_t comm_tf;      /* the communication faults with testFailed */
  uint32_t comm_dtcs;    /* the communication faults' DTCs (bit = table index) */
  uint32_t s3_act[CANFDI_DTCROUTE_S3_SETS]; /* source 3: the monitors of a remembered pass */
  uint32_t s3_n[CANFDI_DTCROUTE_S3_SETS];   /* the reports that pass gave */
  bool s3_quiet[CANFDI_DTCROUTE_S3_SETS];   /* it holds: passes only, none changed anything */
  uint8_t s3_next;       /* the set the next quiet pass replaces */
  uint32_t s3_dtcs;      /* the DTCs source 3 feeds (bit = table index) */
  bool src1_valid;
  bool agg_last_valid;
  bool comm_valid;
  canfdi_dtcroute_diag_t diag;
  bool initialised;
} canfdi_dtcroute_t;

/* The product's P2135 persistence: 500 steps (500 ms; production ECUs
 * report P2135 within 200..500 ms, docs/requirements.md). Cannot fail for
 * non-NULL. */
void canfdi_dtcroute_default_cfg(canfdi_dtcroute_cfg_t *cfg);

/*
 * Validates cfg and builds the index tables against the table of dtc (an
 * initialised memory; a code missing from it is not routed). Latched
 * faults and counters 0. Returns CANFDI_OK or -CANFDI_EINVAL. Cost: O(faults
 * x DTCs) compares, at init only.
 */
int32_t canfdi_dtcroute_init(canfdi_dtcroute_t *r, const canfdi_dtcroute_cfg_t *cfg,
                             const canfdi_dtc_t *dtc);

/*
 * Reports this step's verdicts to dtc (sources 1-3 above). Returns the
 * number of reports the DTC memory refused (>= 0; also counted), or
 * -CANFDI_EINVAL for a NULL argument or an unusable instance.
 */
int32_t canfdi_dtcroute_step(canfdi_dtcroute_t *r, canfdi_dtc_t *dtc,
                             const canfdi_dtcroute_in_t *in);

/*
 * Updates and returns the fault bits for the manager (bit i = catalogue
 * fault id i): communication faults from their DTC's testFailed, the others
 * latched from the diagnosis' masks (failed sets, passed clears, neither
 * keeps; the two are disjoint). 0 for a NULL argument. Cost: see the
 * header.
 */
uint32_t canfdi_dtcroute_manager_faults(canfdi_dtcroute_t *r, const canfdi_dtc_t *dtc, uint32_t failed,
                                        uint32_t passed);

/* Diagnostics snapshot (zeros for NULL). */
canfdi_dtcroute_diag_t canfdi_dtcroute_diag(const canfdi_dtcroute_t *r);

#endif /* CANFDI_DTCROUTE_H */
