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
 * A test burst starts (at most one at a time) for one of four reasons:
 *   NEED   the diagnosis of the plant has detected a symptom it cannot
 *          isolate yet (canfdi_diagnosis_result_t.not_isolated): the
 *          parameter evidence that tells the candidates apart needs
 *          excitation. The burst lasts while the need persists.
 *   KEYON  the first opportunity after init (power-up), if cfg.keyon:
 *          the estimates are checked once per operation cycle.
 *   LEARN  the estimator has no converged estimate (it restarted, e.g.
 *          after a sensor fault healed): as KEYON, whenever the caller's
 *          `unlearnt` says so.
 *   LACK   the estimator has not been excited for lack_steps steps of
 *          enabled operation: its estimates are going stale (a slow drift
 *          of a parameter would go unseen). Lasts burst_steps.
 * A KEYON, LEARN or LACK burst lasts burst_steps, longer while a need
 * persists.
 *
 * The contract on a need (a step with `need`; one need lasts from the step
 * `need` rises to the step it falls):
 *   - A need is owed need_max_steps steps of test signal: the ON steps
 *     while it is present, of whatever burst and over however many bursts
 *     (a burst stopped by the enabling conditions keeps its share).
 *   - Until it has had them, a need starts a NEED burst at the first
 *     enabled step at least gap_steps after the end of the last burst (or
 *     after the rest, if that is shorter): the rest after a KEYON, LEARN
 *     or LACK burst does not hold it back (a fault that appears just after
 *     key-on is tested at once).
 *   - A need still present after its need_max_steps is UNRESOLVED: the
 *     signal cannot isolate it (a symptom no fault explains, e.g. an R_A
 *     estimate below the warm calibration on a cold start). It is then
 *     ignored (it neither starts nor extends a burst) for a back-off,
 *     backoff_steps the first time, doubled after each unresolved retry up
 *     to backoff_max_steps; after the back-off it is owed need_max_steps
 *     again. So an unexplainable need costs at most need_max_steps per
 *     back-off, not a burst after every rest.
 *     The back-off runs on time (every step), enabled or not.
 *   - The need falling (isolated, or the symptom gone) ends the back-off
 *     and the retries: the next need is a new one. The scheduler sees one
 *     boolean per plant, so a further symptom that appears while an
 *     unresolved need persists is not a new need until the need falls.
 * After any burst the scheduler rests for rest_steps before a KEYON,
 * LEARN or LACK burst, and the lack count restarts; only a need that is
 * owed test signal may start a burst during the rest (after gap_steps).
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
 * multiplication. Memory: sizeof(canfdi_testsched_t) = 88 bytes on a
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
  uint32_t need_max_steps; /* test signal owed to one need, >= 1 */
  uint32_t rest_steps;     /* pause after any burst before a KEYON/LEARN/LACK burst */
  uint32_t gap_steps;      /* pause after any burst before a NEED burst (the rest's end ends it too) */
  uint32_t backoff_steps;  /* first back-off of an unresolved need, >= 1 */
  uint32_t backoff_max_steps; /* longest back-off (doubling), >= backoff_steps */
  bool keyon;              /* one burst at the first enabled step after init */
} canfdi_testsched_cfg_t;

typedef struct {
  uint32_t bursts[CANFDI_TESTSCHED_N_REASONS]; /* started, per reason (REASON_*; [0] unused) */
  uint32_t on_steps;    /* steps with the test signal on */
  uint32_t aborted;     /* bursts stopped because the enabling conditions fell */
  uint32_t unresolved;  /* needs found unresolved (back-offs started) */
} canfdi_testsched_diag_t;

typedef struct {
  canfdi_testsched_cfg_t cfg;
  uint32_t lack;     /* enabled steps since the last excitation, <= lack_steps */
  uint32_t n;        /* steps in the present ON or REST phase */
  uint32_t need_n;   /* test-signal steps the present need has had, <= need_max_steps */
  uint32_t backoff;  /* steps left of the back-off, 0 = none */
  uint32_t backoff_len; /* length of the next back-off */
  uint8_t phase;     /* CANFDI_TESTSCHED_IDLE / ON / REST */
  uint8_t reason;    /* reason of the burst in progress or the last one */
  bool keyon_pending;
  bool initialised;
  canfdi_testsched_diag_t diag;
} canfdi_testsched_t;

/* Defaults at 1 ms: lack 60 s, burst 2.5 s (the estimators' convergence
 * count of 400 updates at 200 Hz fits), 3 s owed to a need, rest 10 s,
 * gap 0.1 s, back-off 60 s doubling up to 480 s, key-on burst on. */
void canfdi_testsched_default_cfg(canfdi_testsched_cfg_t *cfg);

/* CANFDI_OK, or -CANFDI_EINVAL (NULL, a zero lack/burst/need/back-off
 * length, backoff_max < backoff). */
int32_t canfdi_testsched_init(canfdi_testsched_t *s, const canfdi_testsched_cfg_t *cfg);

/* One 1 ms step; returns whether the test signal is on in this step.
 * Cannot fail (an uninitialised scheduler stays off). */
bool canfdi_testsched_step(canfdi_testsched_t *s, bool enabled, bool excited, bool need, bool unlearnt);

#endif /* CANFDI_TESTSCHED_H */
