/*
 * canfdi_debounce.h — counter-based event debouncing in the style of the
 * AUTOSAR Diagnostic Event Manager (Dem).
 *
 * A monitor (limit check, trend check, parity residual, plausibility test)
 * reports one raw result per test run: PREFAILED or PREPASSED when it sees a
 * symptom or its absence, FAILED or PASSED when it is already sure. This
 * module turns that stream into a qualified result that a trouble-code
 * memory can store. It is the one debouncer of canfdi: the detectors embed
 * it, and the DTC memory reuses it per event.
 *
 * Algorithm (one signed internal counter per instance):
 *   PREFAILED: if jump_up and counter < jump_up_value: counter = jump_up_value;
 *              then counter += prefailed_step, clipped at failed_threshold.
 *   PREPASSED: if jump_down and counter > jump_down_value:
 *              counter = jump_down_value; then counter -= prepassed_step,
 *              clipped at passed_threshold.
 *   FAILED:    counter = failed_threshold.   PASSED: counter = passed_threshold.
 *   The event qualifies FAILED when the counter reaches failed_threshold and
 *   PASSED when it reaches passed_threshold. Between the two the qualified
 *   status keeps its last value (Dem semantics: the UDS bit testFailed is
 *   cleared only by a qualified pass), and is UNDECIDED only until the first
 *   qualification after init or reset.
 * Naming follows AUTOSAR (ECUC DemDebounceCounterJumpUp/JumpDown): "jump up"
 * acts on a PREFAILED report while the counter is below the jump-up value
 * (typically 0, i.e. a fault that reappears after a good phase does not have
 * to climb out of the negative range first); "jump down" acts symmetrically
 * on PREPASSED while the counter is above the jump-down value. The jump is
 * followed by the normal step, as in Dem. Timing, for a counter starting at
 * c0 and a steady stream of PREFAILED reports (no jump, step s, threshold F):
 * the event qualifies FAILED on report number ceil((F - c0) / s); with jump
 * up to J (c0 < J) on report number ceil((F - J) / s).
 *
 * Fault detection counter (FDC): the Dem/UDS view of the counter, normalised
 * to -128..127: counter >= 0 maps to counter * 127 / failed_threshold,
 * counter < 0 to -(|counter| * 128 / |passed_threshold|), both truncated
 * toward zero, so FDC is 127 exactly at the failed and -128 exactly at the
 * passed threshold.
 *
 * Status flags for a trouble-code memory (plain booleans, named after the UDS
 * DTC status bits they feed):
 *   test_failed                    (bit 0) last qualified result was FAILED.
 *   test_failed_this_cycle         (bit 1) qualified FAILED at least once since
 *                                          the operation cycle started.
 *   test_not_completed_this_cycle  (bit 6) no qualified result yet this cycle.
 * canfdi_debounce_start_cycle() begins a new operation cycle (counter to 0,
 * bits 1 and 6 to their cycle-start values, bit 0 and status kept);
 * canfdi_debounce_reset() returns the instance to its state after init (as a
 * ClearDTC would), keeping the monotone diagnostics.
 *
 * Scaling and overflow: the counter is int16_t like Dem's (thresholds and
 * jump values int16_t, steps 1..32767); each update is formed in int32_t,
 * where counter +/- step cannot overflow (|result| < 2^16), then clipped to
 * [passed_threshold, failed_threshold], so the counter never wraps and never
 * leaves that interval (an asserted invariant). The FDC is formed from
 * magnitudes in uint32_t (|counter| * 128 <= 2^22), truncated. No rounding
 * anywhere else; no fixed-point format involved.
 *
 * Cost, worst case per canfdi_debounce_step(): about 12 compares and 3
 * adds/moves, no multiply, no divide. Measured (arm-none-eabi-gcc 12 -Os,
 * QEMU -icount, 2000 calls over all report kinds): at most 74 instructions
 * on Cortex-M0 (mean 59), 55 on Cortex-M4 (mean 40). Stack: 16 bytes
 * (-fstack-usage, M0+), no callees. FDC: one multiply and one unsigned
 * 32-bit division (__aeabi_uidiv on Cortex-M0+). Code: 476 bytes (M0+).
 * RAM per instance: sizeof(canfdi_debounce_t) = 16 bytes on a 32-bit target
 * (config pointer 4, counter 2, status and flags 4, diagnostics 6); the
 * config (14 bytes) is caller-owned and typically const in flash.
 */
#ifndef CANFDI_DEBOUNCE_H
#define CANFDI_DEBOUNCE_H

#include "core/canfdi_common.h"

/* Raw test result reported by a monitor; values as Dem_EventStatusType. */
typedef enum {
  CANFDI_DEB_REPORT_PASSED = 0,   /* sure: jump to passed_threshold */
  CANFDI_DEB_REPORT_FAILED = 1,   /* sure: jump to failed_threshold */
  CANFDI_DEB_REPORT_PREPASSED = 2, /* symptom absent this run: count down */
  CANFDI_DEB_REPORT_PREFAILED = 3  /* symptom present this run: count up */
} canfdi_deb_report_t;

/* Qualified status. Stored as uint8_t in the instance. */
typedef enum {
  CANFDI_DEB_UNDECIDED = 0, /* not qualified since init/reset */
  CANFDI_DEB_PASSED = 1,    /* last qualification: passed */
  CANFDI_DEB_FAILED = 2     /* last qualification: failed */
} canfdi_deb_status_t;

/*
 * Configuration (one "debounce class"), caller-owned; the instance keeps a
 * pointer, so it must outlive the instance and must not change after init.
 * Valid domain (checked by canfdi_debounce_cfg_check):
 *   failed_threshold 1..32767, passed_threshold -32768..-1,
 *   prefailed_step, prepassed_step 1..32767,
 *   jump values in [passed_threshold, failed_threshold] when enabled.
 */
typedef struct {
  int16_t failed_threshold;  /* > 0: counter value that qualifies FAILED */
  int16_t passed_threshold;  /* < 0: counter value that qualifies PASSED */
  uint16_t prefailed_step;   /* counter increment per PREFAILED report */
  uint16_t prepassed_step;   /* counter decrement per PREPASSED report */
  int16_t jump_up_value;     /* counter start on PREFAILED when below it */
  int16_t jump_down_value;   /* counter start on PREPASSED when above it */
  bool jump_up;              /* enable jump up (AUTOSAR DemDebounceCounterJumpUp) */
  bool jump_down;            /* enable jump down (DemDebounceCounterJumpDown) */
} canfdi_debounce_cfg_t;

/* Monotone counters, saturating at UINT16_MAX; never cleared after init. */
typedef struct {
  uint16_t failed_qualifications; /* status changes to FAILED */
  uint16_t passed_qualifications; /* status changes to PASSED */
  uint16_t rejected_reports;      /* step() calls with an unknown report */
} canfdi_debounce_diag_t;

/* Instance, caller-owned. The caller may read the fields (the status flags
 * are meant to be read directly) but writes them only through the functions
 * below. */
typedef struct {
  const canfdi_debounce_cfg_t *cfg;
  int16_t counter; /* internal debounce counter, in [passed, failed] threshold */
  uint8_t status;  /* canfdi_deb_status_t */
  bool test_failed;
  bool test_failed_this_cycle;
  bool test_not_completed_this_cycle;
  canfdi_debounce_diag_t diag;
} canfdi_debounce_t;

/*
 * Check a configuration against the domain stated above.
 * Returns CANFDI_OK or -CANFDI_EINVAL (NULL or out of domain).
 * Cost: a few compares. Used by the detectors that embed a debouncer.
 */
int32_t canfdi_debounce_cfg_check(const canfdi_debounce_cfg_t *cfg);

/*
 * Bind d to cfg and reset it: counter 0, status UNDECIDED,
 * test_not_completed_this_cycle true, other flags false, diagnostics 0.
 * Returns CANFDI_OK, or -CANFDI_EINVAL if d is NULL or cfg is invalid (then
 * d is left unbound and step() rejects it). Cost: as cfg_check.
 */
int32_t canfdi_debounce_init(canfdi_debounce_t *d, const canfdi_debounce_cfg_t *cfg);

/*
 * Process one raw report (see the algorithm above).
 * Returns the qualified status after this report (a canfdi_deb_status_t,
 * >= 0), or -CANFDI_EINVAL if d is NULL or not initialised, or the report is
 * not a canfdi_deb_report_t value (then nothing changes except the
 * rejected_reports counter). Cost: see the header comment.
 */
int32_t canfdi_debounce_step(canfdi_debounce_t *d, canfdi_deb_report_t report);

/*
 * Whether a pass (PASSED or PREPASSED) would change nothing: the counter on
 * the pass threshold, the status PASSED, test_failed and
 * test_not_completed_this_cycle clear. canfdi_debounce_step would then
 * write the same values back and return CANFDI_DEB_PASSED. false for NULL,
 * an unbound instance or any other report. Cost: a few compares, inline.
 */
static inline bool canfdi_debounce_pass_is_noop(const canfdi_debounce_t *d, canfdi_deb_report_t report)
{
  return ((report == CANFDI_DEB_REPORT_PASSED) || (report == CANFDI_DEB_REPORT_PREPASSED)) && (d != NULL) &&
         (d->cfg != NULL) && (d->counter == d->cfg->passed_threshold) &&
         (d->status == (uint8_t)CANFDI_DEB_PASSED) && !d->test_failed && !d->test_not_completed_this_cycle;
}

/*
 * canfdi_debounce_step with a pass that changes nothing answered inline
 * (CANFDI_DEB_PASSED, no call): the same result and the same state. Most
 * reports of a step are this one (a healthy monitor passes again).
 */
static inline int32_t canfdi_debounce_report(canfdi_debounce_t *d, canfdi_deb_report_t report)
{
  return canfdi_debounce_pass_is_noop(d, report) ? (int32_t)CANFDI_DEB_PASSED : canfdi_debounce_step(d, report);
}

/* New operation cycle: counter 0, test_failed_this_cycle false,
 * test_not_completed_this_cycle true; status and test_failed kept.
 * No-op on NULL or an unbound instance. Cost: O(1), a few stores. */
void canfdi_debounce_start_cycle(canfdi_debounce_t *d);

/* Back to the state after init (diagnostics kept). No-op on NULL or an
 * unbound instance. Cost: O(1). */
void canfdi_debounce_reset(canfdi_debounce_t *d);

/* Qualified status; CANFDI_DEB_UNDECIDED for NULL. Cost: O(1). */
canfdi_deb_status_t canfdi_debounce_status(const canfdi_debounce_t *d);

/* Internal counter, in [passed_threshold, failed_threshold]; 0 for NULL. */
int16_t canfdi_debounce_counter(const canfdi_debounce_t *d);

/* Fault detection counter -128..127 (see above); 0 for NULL or an unbound
 * instance. Cost: one multiply and one unsigned division. */
int8_t canfdi_debounce_fdc(const canfdi_debounce_t *d);

#endif /* CANFDI_DEBOUNCE_H */
