/*
 * canfdi_testsched.h — when an intrusive test signal may run: the
 * scheduler of one plant's excitation (ctrl/canfdi_excite.h), so that the
 * parameter estimators learn from the driving first and the driver feels
 * a test signal only when the diagnosis needs one.
 *
 * Why. Recursive least squares learns a parameter only while the signals
 * move (model/canfdi_rls.h, excitation gate). Driving moves them most of
 * the time; a steady cruise or a held throttle does not. A test signal
 * that is always on keeps the estimates fresh but is felt as a permanent
 * dither. Production ECUs run intrusive checks sparingly and under
 * enabling conditions (e.g. a throttle spring check at key-on); this
 * module does the same for the estimators.
 *
 * A test burst starts (at most one at a time) for one of three reasons:
 *   NEED   the diagnosis of the plant has detected a symptom it cannot
 *          isolate yet (canfdi_diagnosis_result_t.not_isolated): the
 *          parameter evidence that tells the candidates apart needs
 *          excitation. The burst lasts while the need persists, at most
 *          need_max_steps.
 *   KEYON  the first opportunity after init (power-up), if cfg.keyon:
 *          the estimates are checked once per operation cycle.
 *   LEARN  the estimator has no converged estimate (it restarted, e.g.
 *          after a sensor fault healed): as KEYON, whenever the caller's
 *          `unlearnt` says so.
 *   LACK   the estimator has not been excited for lack_steps steps of
 *          enabled operation: its estimates are going stale (a slow drift
 *          of a parameter would go unseen). Lasts burst_steps.
 * A need during a KEYON or LACK burst extends it (up to need_max_steps).
 * After a burst the scheduler rests for rest_steps before the next one and
 * the lack count restarts; a new need may interrupt the rest (a fault
 * appeared), except while the need that outlasted a whole NEED burst
 * persists (EXHAUSTED: a symptom that cannot be isolated by physics, e.g. a
 * U_A offset without the command channel, does not keep the signal on for
 * ever; it gets another burst after the rest).
 *
 * Enabling conditions (the caller's `enabled`, e.g. the plant running in
 * normal degradation, away from its travel limits, the driver's demand
 * steady): while false a burst in progress stops (and the scheduler rests),
 * no burst starts and the lack count is held: steps outside the enabling
 * conditions neither count as lack nor as tested. The rest runs on time
 * (every step), enabled or not.
 * `excited` is the estimator's excitation-gate decision of this step (an
 * update applied, whatever moved the signals); it restarts the lack count.
 *
 * Counts are state with a stated range (they saturate at their cfg limit,
 * never wrap); `diag` holds monotone saturating counters for reporting
 * only (core/canfdi_count.h).
 *
 * Cost per canfdi_testsched_step: a few compares and increments, O(1), no
 * multiplication. Memory: sizeof(canfdi_testsched_t) = 64 bytes on a
 * 32-bit target, caller-owned. No heap, no globals.
 */
#ifndef CANFDI_TESTSCHED_H
#define CANFDI_TESTSCHED_H

#include "core/canfdi_common.h"

#define CANFDI_TESTSCHED_IDLE 0U
#define CANFDI_TESTSCHED_ON 1U
#define CANFDI_TESTSCHED_REST 2U

#define CANFDI_TESTSCHED_REASON_NONE 0U
#define CANFDI_TESTSCHED_REASON_NEED 1U
#define CANFDI_TESTSCHED_REASON_KEYON 2U
#define CANFDI_TESTSCHED_REASON_LACK 3U
#define CANFDI_TESTSCHED_REASON_LEARN 4U
#define CANFDI_TESTSCHED_N_REASONS 5U

typedef struct {
  uint32_t lack_steps;     /* enabled steps without excitation before a LACK burst, >= 1 */
  uint32_t burst_steps;    /* length of a KEYON or LACK burst, >= 1 */
  uint32_t need_max_steps; /* longest NEED burst, >= 1 */
  uint32_t rest_steps;     /* pause after any burst, >= 0 */
  bool keyon;              /* one burst at the first enabled step after init */
} canfdi_testsched_cfg_t;

typedef struct {
  uint32_t bursts[CANFDI_TESTSCHED_N_REASONS]; /* started, per reason (REASON_*; [0] unused) */
  uint32_t on_steps;    /* steps with the test signal on */
  uint32_t aborted;     /* bursts stopped because the enabling conditions fell */
} canfdi_testsched_diag_t;

typedef struct {
  canfdi_testsched_cfg_t cfg;
  uint32_t lack;     /* enabled steps since the last excitation, <= lack_steps */
  uint32_t n;        /* steps in the present ON or REST phase */
  uint8_t phase;     /* CANFDI_TESTSCHED_IDLE / ON / REST */
  uint8_t reason;    /* reason of the burst in progress or the last one */
  bool keyon_pending;
  bool exhausted;    /* the present need outlasted a NEED burst */
  bool initialised;
  canfdi_testsched_diag_t diag;
} canfdi_testsched_t;

/* Defaults at 1 ms: lack 60 s, burst 2.5 s (the estimators' convergence
 * count of 400 updates at 200 Hz fits), need at most 3 s, rest 10 s,
 * key-on burst on. */
void canfdi_testsched_default_cfg(canfdi_testsched_cfg_t *cfg);

/* CANFDI_OK, or -CANFDI_EINVAL (NULL, a zero lack/burst/need length). */
int32_t canfdi_testsched_init(canfdi_testsched_t *s, const canfdi_testsched_cfg_t *cfg);

/* One 1 ms step; returns whether the test signal is on in this step.
 * Cannot fail (an uninitialised scheduler stays off). */
bool canfdi_testsched_step(canfdi_testsched_t *s, bool enabled, bool excited, bool need, bool unlearnt);

#endif /* CANFDI_TESTSCHED_H */
