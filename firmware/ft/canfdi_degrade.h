/*
 * canfdi_degrade.h — the degradation state of one subsystem (DC motor drive,
 * throttle valve), a ratchet that only moves toward safety.
 *
 * States (the DBC's DegState value table, CANFDI_DEG_* of
 * catalogue/canfdi_catalogue.h; a larger number is safer):
 *   0 NORMAL       full function, full redundancy.
 *   1 DEGRADED     fail-operational: a redundant part is lost (bridge A,
 *                  one position sensor, the model vote) or a sensor is
 *                  substituted; the plant still runs.
 *   2 FAIL_SAFE    the actuator is de-energised (DC motor drive off,
 *                  throttle in limp-home on its return spring).
 *   3 FAIL_SILENT  as FAIL_SAFE, and the subsystem's own outputs must not
 *                  be trusted any more (the application stops reporting
 *                  for it); requested by the application, e.g. when the
 *                  ECU's own integrity is in doubt.
 *
 * Ratchet rule. canfdi_degrade_request(state, reason) moves to `state` only
 * if it is safer than the present state. A request for the present state
 * changes nothing and is not counted; a request for a less safe state is
 * ignored and counted (diag.ignored_relax): the fault that caused the
 * degradation may have disappeared (intermittent contact, a frame that
 * comes back), but the plant stays where it is safe until someone with
 * the authority to do so clears it.
 *
 * Clear rule (the ONLY way back to NORMAL). canfdi_degrade_clear(cause,
 * fault_present) returns the state to NORMAL iff
 *   (a) cause is CANFDI_DEGRADE_CLEAR_TESTER — a tester cleared the
 *       diagnostic memory (UDS 0x14 ClearDiagnosticInformation or a reset
 *       routine) — or CANFDI_DEGRADE_CLEAR_NEW_CYCLE — a new operation cycle
 *       starts (power-up / ignition-on), and
 *   (b) fault_present is false: the caller states that no fault that maps
 *       to this subsystem is currently confirmed (for the DTC memory: no
 *       such DTC has testFailed set after the clear or at the cycle start).
 * Otherwise the clear is refused, counted (diag.clears_refused) and the
 * state kept. So a DTC that healed (passed) during the last cycle returns
 * the subsystem to NORMAL at the next cycle start; a fault still present
 * keeps it degraded even across a tester clear — the monitor would
 * re-detect it within its debounce time anyway, and the plant must not be
 * re-energised for that time. There is no partial clear (FAIL_SAFE ->
 * DEGRADED): a cleared subsystem starts from NORMAL and escalates again on
 * the next step if a fault is still there.
 *
 * Reasons and times. Every transition is recorded with the state before
 * and after, its reason and the caller's time in ms. A reason below
 * CANFDI_FAULT_COUNT is a fault id of the catalogue; values from 0x80 up
 * are reasons without a catalogue id (see canfdi_actmgr.h) and
 * CANFDI_DEGRADE_CLEAR_* for a clear. The last CANFDI_DEGRADE_LOG_LEN
 * transitions are kept in a ring (oldest overwritten, counted in
 * diag.log_overwrites); canfdi_degrade_reason() / _since_ms() give the
 * reason and time of the transition into the present state.
 *
 * Time: the caller's uptime in ms (uint64_t, core/canfdi_uptime.h); only
 * stored, never compared.
 *
 * Scaling and overflow: no arithmetic besides the monotone counters, which
 * saturate at UINT32_MAX.
 * Cost per call: request O(1) (a few compares and, on a transition, 8
 * stores); clear O(1); log_get O(1). Measured executed instructions of
 * canfdi_degrade_request (arm-none-eabi-gcc 12 -Os, QEMU mps2-an386
 * -icount, 2000 random requests and clears, min/mean/max, call overhead
 * included): Cortex-M0+ code 23 / 38 / 76, Cortex-M4 14 / 27 / 62.
 * Code: 390 bytes (M0+). Stack: < 24 bytes.
 * Memory: sizeof(canfdi_degrade_t) = 176 bytes on a 32-bit target (8 log
 * entries of 16 bytes, 28 bytes of diagnostics, state/reason/time). No
 * heap, no globals.
 * Instances must not be copied while in use (no internal pointers here,
 * but the containing modules rely on that).
 */
#ifndef CANFDI_DEGRADE_H
#define CANFDI_DEGRADE_H

#include "catalogue/canfdi_catalogue.h"
#include "core/canfdi_common.h"
#include "core/canfdi_count.h"

/* Transitions kept in the log ring (RAM: 16 bytes each). */
#ifndef CANFDI_DEGRADE_LOG_LEN
#define CANFDI_DEGRADE_LOG_LEN 8U
#endif

/* Highest state value (the DBC table has 0..3). */
#define CANFDI_DEGRADE_STATE_MAX CANFDI_DEG_FAIL_SILENT

/* Clear causes; also the reason recorded for the transition to NORMAL. */
#define CANFDI_DEGRADE_CLEAR_TESTER 0xF0U
#define CANFDI_DEGRADE_CLEAR_NEW_CYCLE 0xF1U

/* canfdi_degrade_clear() result when the clear was refused (fault present). */
#define CANFDI_DEGRADE_CLEAR_REFUSED 1

typedef struct {
  uint64_t t_ms;  /* caller's uptime at the transition */
  uint8_t from;   /* CANFDI_DEG_* before */
  uint8_t to;     /* CANFDI_DEG_* after */
  uint8_t reason; /* fault id, manager reason or CANFDI_DEGRADE_CLEAR_* */
  uint8_t pad_;
} canfdi_degrade_transition_t;

/* Monotone counters, saturating at UINT32_MAX; only init zeroes them. */
typedef struct {
  uint32_t transitions;    /* every state change, escalations and clears */
  uint32_t escalations;    /* transitions toward safety */
  uint32_t ignored_relax;  /* requests for a less safe state, ignored */
  uint32_t clears;         /* accepted clears (also those already NORMAL) */
  uint32_t clears_refused; /* clears refused because a fault is present */
  uint32_t rejected;       /* calls with an invalid state or cause */
  uint32_t log_overwrites; /* log entries lost to the ring */
} canfdi_degrade_diag_t;

/* Instance, caller-owned; read it through the functions below. */
typedef struct {
  uint8_t state;      /* CANFDI_DEG_* */
  uint8_t reason;     /* reason of the transition into `state` */
  uint8_t log_head;   /* index of the next entry to write */
  uint8_t log_count;  /* valid entries, <= CANFDI_DEGRADE_LOG_LEN */
  uint64_t since_ms;  /* uptime at the transition into `state` */
  canfdi_degrade_transition_t log[CANFDI_DEGRADE_LOG_LEN];
  canfdi_degrade_diag_t diag;
} canfdi_degrade_t;

/*
 * State NORMAL, reason CANFDI_FAULT_NONE, since 0, empty log, diagnostics 0.
 * Returns CANFDI_OK, or -CANFDI_EINVAL for NULL. Cost: O(LOG_LEN) stores.
 */
int32_t canfdi_degrade_init(canfdi_degrade_t *d);

/*
 * Ask for `state` because of `reason` at time now_ms (ratchet rule above).
 * Returns the state after the call (0..3), or -CANFDI_EINVAL for NULL or
 * state > CANFDI_DEGRADE_STATE_MAX (counted in diag.rejected if d is
 * valid; nothing else changes). Cost: O(1).
 */
int32_t canfdi_degrade_request(canfdi_degrade_t *d, uint8_t state, uint8_t reason,
                               uint64_t now_ms);

/*
 * Clear to NORMAL (clear rule above). Returns CANFDI_OK when the state is
 * NORMAL after the call (a transition is logged if it was not),
 * CANFDI_DEGRADE_CLEAR_REFUSED when fault_present refused it, or
 * -CANFDI_EINVAL for NULL or an unknown cause (counted in diag.rejected).
 * Cost: O(1).
 */
int32_t canfdi_degrade_clear(canfdi_degrade_t *d, uint8_t cause, bool fault_present,
                             uint64_t now_ms);

/* Present state (CANFDI_DEG_*); CANFDI_DEG_FAIL_SAFE for NULL, the safe
 * answer for a caller that lost its instance. Cost: O(1). */
uint8_t canfdi_degrade_state(const canfdi_degrade_t *d);

/* Reason and time of the transition into the present state (NONE and 0
 * after init); CANFDI_FAULT_NONE / 0 for NULL. Cost: O(1). */
uint8_t canfdi_degrade_reason(const canfdi_degrade_t *d);
uint64_t canfdi_degrade_since_ms(const canfdi_degrade_t *d);

/*
 * Copy a logged transition: age 0 is the latest, age 1 the one before, ...
 * Returns CANFDI_OK, -CANFDI_ENODATA if fewer than age + 1 entries are
 * kept, -CANFDI_EINVAL for NULL. Cost: O(1).
 */
int32_t canfdi_degrade_log_get(const canfdi_degrade_t *d, uint32_t age,
                               canfdi_degrade_transition_t *out);

/* Diagnostics snapshot (all zero for NULL). Cost: O(1). */
canfdi_degrade_diag_t canfdi_degrade_diag(const canfdi_degrade_t *d);

#endif /* CANFDI_DEGRADE_H */
