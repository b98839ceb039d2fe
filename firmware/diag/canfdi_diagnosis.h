/*
 * canfdi_diagnosis.h — fault-symptom reasoning (Isermann, Fault-Diagnosis
 * Systems, 2006, ch. 15-17): from the symptom vector of one 1 ms step
 * (diag/canfdi_symptoms.h) decide which catalogue fault is present, name it
 * with a confidence, and report a verdict per catalogue fault id for the
 * trouble-code memory.
 *
 * The knowledge is one data file, dbc/diag_rules.csv (one rule per row,
 * with a note on why), from which diag/gen/canfdi_diag_rules.c is
 * generated (`make dbc-gen`); two kinds of rules:
 *  - Hard rules on the signal-based flags (range checks, 2-out-of-3 vote,
 *    actuator monitors and manager): a fault is FAILED when its required
 *    flags are all present (persistently) and none of its forbidden flags
 *    is; confidence 100 %. A rule cannot run while any of its `untested`
 *    raw flags is set this step (its input is INVALID: never received or
 *    lost): it then reports nothing, so the trouble code's
 *    testNotCompletedThisOperationCycle stays set (ISO 14229-1) instead of
 *    a pass judged from a stale range result. These monitors have their own
 *    physics and debouncing; a fired hard rule also masks the model-based
 *    rules of its component, because the fault it names breaks the models'
 *    assumptions (a dead bridge makes U_A = 0, an open TPS invalidates CORR
 *    and POSk, an open motor collapses every throttle estimate).
 *  - Model rules: per fault a pattern of expected symptom signs over the
 *    component's symptom channels (below), each entry one of
 *        '+' '-' '0' : supporting: counts in the confidence,
 *        'P' 'N' 'Z' : necessary: must hold (and counts twice),
 *        '.'         : don't care.
 *    A bipolar rule (sensor offsets) matches the pattern or its negation
 *    (a sensor offset may have either sign); the polarity is chosen per
 *    evaluation, the one with the higher confidence.
 * The patterns are the parity structure of model/canfdi_parity_{dcm,thr}.h
 * checked against the measured fault-symptom table (bench/bench_symptoms.c,
 * build/bench/symptoms.json): tests/dbc/test_diagnosis_rules.py reads the
 * data file and the firmware's thresholds and fails when a rule disagrees
 * with the measured symptoms or another rule would fit them too. '.' marks
 * a symptom that is intermittent (e.g. r3 for R_A up: out of band 95 % of
 * the time with zero mean, the J dR/Psi dI/dt term of the transients) or
 * depends on the operating point.
 *
 * Symptom channels (per component, 10 slots; normalised so that 1.0 is the
 * threshold):
 *   DC motor   0 r1  1 r2  2 r3  3 r4           (residual / band)
 *              4 R_A 5 Psi 6 RAX 7 M_c           (relative deviation / cfg
 *                                                 threshold, + and - sides
 *                                                 separately)
 *              6 RAX: the share of r1 that the R_A estimate explains
 *                (canfdi_symptoms.h; derived, 1.0 = half)
 *              8 J/Psi: dev(J) - dev(Psi)        (derived; / cfg threshold)
 *              9 UAC: measured U_A - command     (detect/canfdi_actmon.h)
 *   throttle   0 CORR 1 ARM 2 POS1 3 POS2        (residual / band)
 *              4 R 5 K 6 spring 7 friction       (relative deviation; spring
 *                                                 and friction from the
 *                                                 estimator's fast test)
 *              8, 9 unused
 * Why the two derived DC-motor channels. In the armature equation a U_A
 * offset dU and an omega offset -dU/Psi are the same term, and R_A up gives
 * the same r1/r4 signs in steady state: the parameter estimates separate
 * R_A (R_A moves, Psi does not) from the sensor offsets (Psi moves by
 * dU/(Psi w), R_A does not), and UAC separates U_A from omega (only a U_A
 * sensor fault makes the measurement disagree with the command). A
 * speed-sensor GAIN scales dw/dt, which the mechanical estimator sees
 * through J/Psi (J -9.3 %, Psi -4.8 % at +5 %), while a speed OFFSET leaves
 * dw/dt and J/Psi alone (J and Psi both -10.9 %). J/Psi alone is not enough
 * for a gain: the mechanical estimator can move J by itself (a PRBS step
 * into the 48 V clamp read J -2.2 % with every residual in band), and a
 * real gain g also unbalances the armature equation (r1 = -Psi g w, at
 * least 2.7 x the r1 band from 50 rad/s on), so its rule needs r1. Limit: a
 * gain drifting slower than the parity equations' R_A tracker (ra_tau 60 s)
 * can be absorbed into R_A and then stays "detected, not isolated". Without
 * a valid UAC channel a U_A offset and an omega offset stay "detected, not
 * isolated": physics, not a tuning choice. The throttle's spring and
 * friction rules keep K at zero as necessary: the electrical estimate of K
 * dips by 10 % for ~0.6 s after a motor R +10 % step, and the armature
 * current then no longer measures the torque the nominal model assumes.
 *
 * Symptom persistence (per channel and per flag). Ternary from the
 * normalised value x: |x| >= on -> sign(x); |x| < off -> 0; in between the
 * present sign is kept (hysteresis). The channel's state changes only after
 * the new value held for sym_on_steps (to +/-) or sym_off_steps (to 0)
 * consecutive steps. An invalid channel is "unknown" at once and restarts
 * at 0. Flags likewise with flag_on_steps / flag_off_steps. For matching,
 * a channel at 0 whose persistence is running toward +/- counts as
 * unknown (it confirms no zero): residuals of one fault cross their bands
 * some ms apart (flux down: r4 ~25 ms after r1..r3), and in between the
 * pattern would read as another fault's (I_A offset, r4 = 0). Likewise a
 * channel at 0 confirms a zero only after its value stayed below `off`
 * for sym_off_steps (a channel that becomes valid starts settled, as its
 * state starts at 0): a value in the hysteresis band [off, on) is neither
 * a symptom nor its absence. A slow I_A offset ramp moves r1 (-R dI) and
 * r2/r3 (Psi dI) together with r2/r3 crossing first, while r1 hovers at
 * -0.8..-0.93: read as a zero, that r1 would make the pattern friction up
 * (r1 Z), whose hypothesis needs r1 clearly zero.
 *
 * Matching (each step, per component without a fired hard rule):
 *  - detected = some channel persistently +/-.
 *  - Not detected: every model fault whose necessary channels are all valid
 *    is PASSED; the others NONE (not tested).
 *  - Detected: a rule is a CANDIDATE if every necessary entry is valid and
 *    holds. Its confidence is the weighted fraction of matching entries
 *    over its valid non-don't-care entries, weight w = clamp(|x|, 1, cap)
 *    for a channel showing +/- and 1 for a channel showing 0, doubled for
 *    necessary entries: a large unexpected symptom counts against a rule in
 *    proportion to its size (Isermann's approximate reasoning with symptom
 *    strength). The best candidate wins if its confidence >= conf_min and
 *    it leads the second candidate by >= margin points; it is ISOLATED once
 *    it has won isolate_steps consecutive steps, and reported FAILED in
 *    every step it stays isolated. Otherwise "detected, not isolated": no
 *    FAILED; every model fault of the component NONE (single-fault
 *    reasoning cannot clear the others while a symptom is unexplained).
 *    For the throttle, a persistent CORR symptom that is not isolated sets
 *    corr_not_isolated: the application reports P2135 (dtcs.csv has it
 *    without a fault id).
 *  - Learnt estimates (DC motor). While CANFDI_SYM_F_DCM_UNLEARNT is set
 *    (the armature and the mechanical estimates have not both converged
 *    since power-up, or since a replay's start mid-drive), no model rule of
 *    the DC motor is tested: detected symptoms stay "detected, not
 *    isolated" and a quiet component passes nothing. The rules read r1
 *    against the estimated R_A and the parameter channels against
 *    estimates that, before excitation has separated them, can put a flux
 *    loss into the friction estimate: a replay cut 0.8 s before a ramped
 *    flux loss at 20 rad/s named friction (P1A12), then, with a gate on the
 *    armature estimate alone, an I_A offset (P1A20). A later restart that
 *    keeps the estimates (an input timeout or a sensor fault healed) does
 *    not clear it: a sensor fault whose symptom pauses the learning must
 *    stay isolable. The application also keeps the flag set for the
 *    power cycle when r2 or r3 showed a symptom as the DC motor became
 *    learnt: the fault was then learnt into R_A and the estimates
 *    (canfdi_app.h, CANFDI_APP_LEARN_FAULT).
 *  - Re-arming (both components). While CANFDI_SYM_F_DCM_REARM or
 *    _THR_REARM is set (the component's inputs came back from an
 *    interruption, or one of its samples was late, less than the
 *    calibration's hold time ago, app/canfdi_app.h), its model rules are
 *    held the same way. The parity
 *    equations restart on the first samples after the interruption: when
 *    the plant moved meanwhile (a sensor node that restarted shows the
 *    motor at rest where it ran, and the drive then accelerates it with
 *    the bridge saturated), their filters start in the middle of a
 *    transient and the residuals stay out of their bands for some 100 ms
 *    after the restart's own settling; judged, their decay (r2 back in
 *    band first, r1 last) read as a speed-sensor offset.
 *  - The flux gate (DC motor). A developing flux loss moves the residuals
 *    in fixed ratios (canfdi_symptoms.h dcm_fx_q16), so early in a ramp
 *    one of them leaves its band alone: r1 at high speed and low current
 *    (a speed-sensor offset's or gain's pattern), r2/r3 at low speed and
 *    high current (friction's), r1..r3 without r4 where Psi w = R_A I_A
 *    (an I_A offset's). A residual's zero is evidence against a flux loss
 *    only while the flux loss that explains the residuals beyond their
 *    thresholds would have put it at `off` or above for sym_on_steps (as
 *    long as that flux loss would need to make it a symptom, plus as many
 *    steps as the prediction had been below `off` since it last held above
 *    it that long, at most 1000 (1 s, the load tracking: the residual has
 *    to follow the flux loss out of its own tracked mean; fx_blind,
 *    fx_low). For the gated rules (every
 *    DC-motor rule except flux's own and those that require a symptom on a
 *    channel the flux rule expects at zero: R_A up through the R_A
 *    estimate, U_A offset through UAC) such zeros do not count (neither
 *    confirmed nor contradicting: the rule is not yet a candidate if it
 *    needs one). The gate opens when the estimates exclude a flux loss:
 *    both estimators have had par_memory_updates updates since the
 *    symptoms appeared and a necessary parameter entry of the flux rule
 *    (Psi -, J/Psi +) is seen at zero or with the other sign.
 *  - A residual against a flux loss (DC motor). A flux loss dPsi moves
 *    r1 by -dPsi w (not tracked) and r4 by dPsi (R_A I_A - Psi w) / Psi
 *    minus that term's mean over the load tracking; a residual at or above
 *    the zero level with a sign no such loss can give it (r4: beyond what
 *    the tracking can add where the operating point moves back through its
 *    tracked mean; CANFDI_SYM_F_DCM_FX_CONTRA, app/canfdi_app_sym.c;
 *    persistent like a symptom, fx_contra) rules the flux rule out,
 *    whatever its supporting entries score. At low speed and high current
 *    (R_A I_A > Psi w) a flux loss moves r4 against r1 and a speed-sensor
 *    offset moves it with r1, while the estimates within their first
 *    memory after the symptoms (Psi -, J/Psi +) would name the flux loss
 *    for the offset.
 *  - An r1 too small for a speed gain (DC motor). A speed-sensor gain
 *    moves J/Psi by about its own size and r1 by Psi g w; while r1 is
 *    below a quarter of what the gain J/Psi implies would give
 *    (CANFDI_SYM_F_DCM_GAIN_CONTRA, app/canfdi_app_sym.h; persistent like
 *    a symptom) the speed-gain rule is ruled out, whatever its entries
 *    score: the mechanical estimate can swing J/Psi past its 2 % threshold
 *    in a test burst by itself, and next to an r1 held at its threshold
 *    by a slow R_A creep that pattern read as a gain.
 *  - A fault with both a hard and a model rule (14, 15, 19, 20): FAILED if
 *    either fires; PASSED only if both tests ran and passed.
 *  - Hard-rule faults are PASSED while their condition is false (the flag
 *    producers latch their failures: vote isolation, manager bridge state).
 * Communication faults (ids 22..31) stay NONE (canfdi_rx reports them).
 * Detection delays per fault, measured in closed loop: tests/sil/README.md
 * and `make bench-detection` (build/bench/detection.json).
 *
 * Latency budget (defaults): a symptom needs 20 steps, the decision 20
 * more, overlapping by one: FAILED in the 39th step (sym_on + isolate - 1)
 * after the slowest NECESSARY symptom crossed its threshold for good; a
 * flag-based fault in the 10th step (flag_on). The DTC memory's "direct" debounce class qualifies each
 * report at once, so this is the whole debouncing between the detectors and
 * the testFailed bit. Parameter-based rules wait for the estimators
 * (memory ~0.5 s DC motor, 0.4 s throttle electrical, ~0.3 s for the
 * throttle's fast spring/friction test).
 *
 * Scaling and overflow. Inputs Q16.16. Parameter deviations are normalised
 * by multiplying with a reciprocal threshold computed at init
 * (canfdi_div_s32_qn, Q16.16), a 64-bit product rounded half up and
 * saturated (canfdi_mul_s32_qn); the J/Psi difference saturates. Weights
 * are Q16.16 in [1, 2 cap] with cap <= 16, at most 10 per rule: sums
 * < 2^22, times 100 < 2^29: the percentage is an unsigned 32-bit division,
 * truncated. No rounding elsewhere; nothing wraps.
 *
 * Cost per canfdi_diagnosis_step: 20 channel updates (9 with a 32x32->64
 * multiply; a settled channel below its zero level is one inline test),
 * 11 flag updates, the 12 hard rules (mask tests) only when the persistent
 * flags or the untested symptom flags changed (canfdi_diagnosis_hard_t),
 * the verdicts combined as bit masks, and for a component with a symptom
 * its 7 model rules x <= 2 polarities: mask tests for candidacy, then for a
 * candidate a weighted sum over its seen channels and one 32-bit division
 * (<= 28 per step). The patterns are compiled to bit masks
 * at init (canfdi_diagnosis_rule_t), so the step never parses text.
 * canfdi_diagnosis_step_hard leaves out the model rules' matching,
 * canfdi_diagnosis_step_comp does it for some components. In the
 * application (each component's matching in one step of ten, the rest in
 * every step; `make bench-pil-profile`, dcm_ia_offset scenario, QEMU -icount,
 * arm-none-eabi-gcc -Os) this module's own code took 2 260 instructions
 * per step on average on Cortex-M4 and 3 040 on Cortex-M0 (instruction
 * counts, not cycles). Code (`make footprint`, the application image,
 * ROM tables included): 5.3 kB (M4), 5.8 kB (M0). Stack (-fstack-usage,
 * M0): diagnosis_step 152 bytes (update_channels inline), calling
 * channel_move (40).
 * Memory: sizeof(canfdi_diagnosis_t) = 820 bytes on a 32-bit target (the
 * configuration copy, the thresholds' reciprocals, the channel and flag
 * persistence, the normalised values, the compiled rules, the weights, the
 * results, the hard rules' last verdicts, the flux gate's counters, the
 * diagnostics and the state). No heap, no globals besides const tables, no
 * floating point; reentrant per instance.
 */
#ifndef CANFDI_DIAGNOSIS_H
#define CANFDI_DIAGNOSIS_H

#include "core/canfdi_common.h"
#include "catalogue/canfdi_catalogue.h"
#include "diag/canfdi_symptoms.h"
#include "diag/gen/canfdi_diag_rules.h"

#define CANFDI_DIAG_REPORT_FAILED ((int8_t)1)
#define CANFDI_DIAG_REPORT_PASSED ((int8_t)-1)
#define CANFDI_DIAG_REPORT_NONE ((int8_t)0)

#define CANFDI_DIAG_N_COMP 2U   /* [0] DC motor, [1] throttle */
/* Every component's bit (canfdi_diagnosis_step_comp). */
#define CANFDI_DIAG_ALL_COMP ((1U << CANFDI_DIAG_N_COMP) - 1U)
#define CANFDI_DIAG_N_CH 10U    /* symptom channels per component */
#define CANFDI_DIAG_N_FLAGS 11U /* flag bits 0..10 of canfdi_symptoms_t.flags */

/* DC-motor channel indices (0..3 are CANFDI_SYM_DCM_R1..R4). */
#define CANFDI_DIAG_CH_DCM_RA 4U
#define CANFDI_DIAG_CH_DCM_PSI 5U
#define CANFDI_DIAG_CH_DCM_RAX 6U
#define CANFDI_DIAG_CH_DCM_MC 7U
#define CANFDI_DIAG_CH_DCM_JPSI 8U
#define CANFDI_DIAG_CH_DCM_UAC 9U
/* Throttle channel indices (0..3 are CANFDI_SYM_THR_CORR..POS2). */
#define CANFDI_DIAG_CH_THR_R 4U
#define CANFDI_DIAG_CH_THR_K 5U
#define CANFDI_DIAG_CH_THR_SPRING 6U
#define CANFDI_DIAG_CH_THR_FRICTION 7U

/* Persistent symptom value of a channel (canfdi_diagnosis_symptom). */
#define CANFDI_DIAG_SYM_NEG ((int8_t)-1)
#define CANFDI_DIAG_SYM_ZERO ((int8_t)0)
#define CANFDI_DIAG_SYM_POS ((int8_t)1)
#define CANFDI_DIAG_SYM_UNKNOWN ((int8_t)2) /* channel not valid */

/*
 * Calibration (copied at init). Domain, else -CANFDI_EINVAL:
 * 0 < off <= on <= 16.0; 1.0 <= weight_cap <= 16.0; step counts 1..10000;
 * par_fresh_updates 0..10000 (0: every parameter 0 counts at once);
 * par_memory_updates 0..10000;
 * conf_min 0..100; margin 0..100; every parameter threshold and jpsi in
 * [0.001, 10.0] (0.1 % .. 1000 %).
 */
typedef struct {
  int32_t on_q16;         /* |x| at/above: symptom +/- (1.0 = the threshold) */
  int32_t off_q16;        /* |x| below: symptom 0 (hysteresis) */
  int32_t weight_cap_q16; /* largest weight of one symptom */
  uint16_t sym_on_steps;  /* persistence of a channel to become +/- */
  uint16_t sym_off_steps; /* ... to return to 0 */
  uint16_t flag_on_steps;
  uint16_t flag_off_steps;
  uint16_t isolate_steps; /* consecutive wins before ISOLATED */
  uint8_t conf_min_pct;   /* the winner's confidence at least */
  uint8_t margin_pct;     /* the winner's lead over the second candidate */
  /* relative parameter deviation (Q16.16, 0.08 = 8 %) at which the channel
   * is +1.0 / -1.0; separate sides because some deviations are physical in
   * one direction (a cold winding: R_A down to -11 % of the warm value) */
  int32_t dcm_par_pos_q16[CANFDI_SYM_N_PAR];
  int32_t dcm_par_neg_q16[CANFDI_SYM_N_PAR];
  int32_t thr_par_pos_q16[CANFDI_SYM_N_PAR];
  int32_t thr_par_neg_q16[CANFDI_SYM_N_PAR];
  int32_t jpsi_q16;       /* |dev(J) - dev(Psi)| at which J/Psi is +-1.0 */
  uint16_t par_fresh_updates; /* estimator updates after a symptom before a
                               * parameter channel's 0 counts as absence */
  uint16_t par_memory_updates; /* ... before an estimate reflects only the
                                * data since (the estimators' memory): from
                                * then on the estimates may exclude a flux
                                * loss (the flux gate, header) */
} canfdi_diagnosis_cfg_t;

/* Result per component. */
typedef struct {
  uint8_t isolated;       /* fault id, 0 = none */
  uint8_t confidence_pct; /* of the isolated fault (hard rule: 100) */
  uint8_t best;           /* best candidate this step (0 = none) */
  uint8_t best_pct;
  uint8_t second;         /* runner-up candidate (0 = none) */
  uint8_t second_pct;
  bool detected;          /* a persistent symptom or flag */
  bool not_isolated;      /* detected, nothing isolated */
} canfdi_diagnosis_result_t;

/* Monotone counters, saturating at UINT32_MAX; only init zeroes them. */
typedef struct {
  uint32_t steps;
  uint32_t isolations;       /* a fault became ISOLATED (model rules) */
  uint32_t hard_fires;       /* a hard rule started to fire */
  uint32_t unisolated_steps; /* component-steps detected but not isolated */
  uint32_t rejected;         /* step calls with NULL or an unbound instance */
} canfdi_diagnosis_diag_t;

/* A model rule compiled to channel bit masks (init; internal). */
typedef struct {
  uint16_t care; /* entries that are not don't-care */
  uint16_t nec;  /* necessary entries */
  uint16_t pos;  /* expected + (for polarity +1 and positive refs) */
  uint16_t neg;  /* expected - */
  uint16_t zero; /* expected 0 */
  uint16_t ref_a; /* entries whose sign follows the component's ref 'a' */
  uint16_t ref_b; /* ... ref 'b' */
} canfdi_diagnosis_rule_t;


typedef struct {
  int8_t state; /* CANFDI_DIAG_SYM_* */
  int8_t cand;  /* candidate value being timed */
  uint16_t n;   /* consecutive steps of cand */
  uint16_t quiet; /* consecutive steps below off, saturating at sym_off_steps */
} canfdi_diagnosis_pers_t;

/* One verdict per fault as bits (bit i: catalogue fault id i): has a test
 * (else "no such test"), passed, failed; a bit in has alone is "not tested".
 * Masks, not an array of verdicts: a step combines them in a few word
 * operations instead of a loop over the faults. */
typedef struct {
  uint32_t has;
  uint32_t pass;
  uint32_t fail;
} canfdi_diagnosis_vmask_t;

/* The hard rules' verdicts are a function of two words: the persistent
 * flags and the symptom flags that mark rules untested. A step whose words
 * equal the last ones takes the last verdicts (most steps) instead of
 * evaluating the rules again. */
typedef struct {
  canfdi_diagnosis_vmask_t v; /* the verdicts for the words below */
  uint32_t flags;             /* persistent flags (bit i: flag i present) */
  uint32_t untested;          /* symptom flags & hard_untested */
  uint8_t any;                /* bit c: a hard rule of component c fired */
  bool valid;                 /* the above hold; false after a reset */
} canfdi_diagnosis_hard_t;

typedef struct {
  canfdi_diagnosis_cfg_t cfg;
  int32_t inv_pos_q16[CANFDI_DIAG_N_COMP][CANFDI_SYM_N_PAR]; /* 1 / threshold */
  int32_t inv_neg_q16[CANFDI_DIAG_N_COMP][CANFDI_SYM_N_PAR];
  int32_t inv_jpsi_q16;
  canfdi_diagnosis_pers_t ch[CANFDI_DIAG_N_COMP][CANFDI_DIAG_N_CH];
  canfdi_diagnosis_pers_t flag[CANFDI_DIAG_N_FLAGS];
  int32_t x_q16[CANFDI_DIAG_N_COMP][CANFDI_DIAG_N_CH]; /* this step, normalised */
  canfdi_diagnosis_result_t res[CANFDI_DIAG_N_COMP];
  canfdi_diagnosis_rule_t rule[CANFDI_DIAG_N_RULES];
  uint32_t w_q16[CANFDI_DIAG_N_CH]; /* weights of the component being ranked */
  uint16_t obs_pos;  /* observed masks of that component */
  uint16_t obs_neg;
  uint16_t obs_zero;
  uint16_t obs_zero_fx; /* obs_zero without the residual zeros a flux loss
                         * would not have disturbed (flux-gated rules) */
  uint16_t fx_low[CANFDI_SYM_N_RES];   /* DC motor: steps the prediction was
                                        * low since it last held above off */
  uint16_t fx_blind[CANFDI_SYM_N_RES]; /* DC motor: steps a residual's zero
                                        * stays no evidence against a flux
                                        * loss, <= sym_on_steps + 1000 */
  canfdi_diagnosis_pers_t fx_contra; /* DC motor: a residual's sign rules out
                                       * a flux loss (persistent) */
  canfdi_diagnosis_pers_t gain_contra; /* DC motor: r1 too small for the speed
                                        * gain J/Psi implies (persistent) */
  uint32_t fx_gated; /* bit i: model rule i is flux-gated */
  uint8_t flux_rule; /* index of the flux rule (CANFDI_DIAG_N_RULES: none) */
  uint8_t gain_rule; /* index of the speed-gain rule (likewise) */
  int8_t ref[CANFDI_DIAG_N_COMP][2]; /* operating-point signs of this step */
  uint16_t win_n[CANFDI_DIAG_N_COMP]; /* consecutive wins of res.best */
  bool latched[CANFDI_DIAG_N_COMP];   /* res.isolated came from the model rules */
  uint16_t fresh[CANFDI_DIAG_N_COMP][2]; /* estimator updates (A, B) since the
                                          * component's symptoms appeared,
                                          * <= max(par_fresh_updates,
                                          * par_memory_updates) */
  uint8_t win_id[CANFDI_DIAG_N_COMP];
  bool held[CANFDI_DIAG_N_COMP]; /* this step the component's model rules are
                                  * not tested: DC motor CANFDI_SYM_F_DCM_UNLEARNT
                                  * or _DCM_REARM, throttle _THR_REARM */
  canfdi_diagnosis_vmask_t mv_last; /* model verdicts of the last full step */
  canfdi_diagnosis_hard_t hard;      /* the hard rules' verdicts, kept while
                                      * their inputs stay the same */
  uint32_t hard_untested;            /* the symptom flags any hard rule's
                                      * untested mask names */
  bool corr_not_isolated;
  bool initialised;
  uint32_t failed_mask; /* bit i: fault i FAILED this step */
  uint32_t passed_mask; /* bit i: fault i PASSED this step */
  canfdi_diagnosis_diag_t diag;
} canfdi_diagnosis_t;

/*
 * Defaults: on 1.0, off 0.8; cap 4; symptom persistence 20 ms on / 50 ms
 * off; flags 10 ms / 10 ms; isolation 20 ms; conf_min 50 %, margin 10
 * points; a parameter's zero counts after 12 updates of its estimator
 * since the symptoms appeared (60 ms of the DC motor's armature
 * estimator, 24 ms of the throttle's electrical one), and the flux gate
 * opens after 100. Parameter thresholds (+ / -): DC motor R_A +8 % / -20 % (the
 * cold winding is -11 %), Psi 2.5 % / 2.5 % (sigma 0.01 %; a 2 V U_A
 * offset moves it 6.9 %), J 5 % / 5 %, M_c 3 % / 10 % (+50 % friction is
 * +4.2 % of the lumped M_c at the 1.2 N m load); J/Psi 2 % (a +5 % speed
 * gain gives -4.7 %). Throttle R +8 % / -20 %, K 10 % / 10 %, spring
 * +20 % / -10 %, friction +8 % / -30 % (fast structured test; the
 * argument is at the values in canfdi_diagnosis.c). NULL ignored.
 */
void canfdi_diagnosis_default_cfg(canfdi_diagnosis_cfg_t *cfg);

/* CANFDI_OK or -CANFDI_EINVAL (NULL or out of domain). O(1). */
int32_t canfdi_diagnosis_cfg_check(const canfdi_diagnosis_cfg_t *cfg);

/*
 * Validate and copy cfg, precompute the reciprocals (divisions: not for the
 * 1 ms path), reset. CANFDI_OK or -CANFDI_EINVAL (then d is unbound: step
 * reports NONE everywhere, counted in diag.rejected).
 */
int32_t canfdi_diagnosis_init(canfdi_diagnosis_t *d, const canfdi_diagnosis_cfg_t *cfg);

/* Forget every symptom, persistence and isolation (a tester clear or a new
 * operation cycle); counters kept. No-op on NULL or unbound. O(1). */
void canfdi_diagnosis_reset(canfdi_diagnosis_t *d);

/*
 * One 1 ms step. report[id] for every catalogue fault id
 * 0..CANFDI_FAULT_COUNT-1: CANFDI_DIAG_REPORT_FAILED, _PASSED or _NONE
 * (see the header comment; ids 0 and 22..31 always NONE). report must hold
 * CANFDI_FAULT_COUNT entries and is written completely (all NONE on a NULL
 * or unbound d or a NULL s; NULL report: nothing written).
 */
void canfdi_diagnosis_step(canfdi_diagnosis_t *d, const canfdi_symptoms_t *s, int8_t report[]);

/*
 * A step without the model rules' matching, between full steps (the
 * application's rate schedule, app/canfdi_app.h): the flags' and the
 * symptom channels' persistence and the hard rules on this step's symptom
 * vector, as in a full step; the model rules' matching, results and
 * verdicts are those of the last full step (its model verdicts reported
 * again), except that a hard rule firing in a component clears the
 * component's result and model verdicts as a full step would. Symptoms
 * thus persist in 1 ms steps whatever the schedule; only the isolation
 * (isolate_steps consecutive wins) counts full steps. A schedule that
 * makes every step full is the unscheduled diagnosis. Cost: the
 * persistence, the hard rules and the report, without the matching.
 */
void canfdi_diagnosis_step_hard(canfdi_diagnosis_t *d, const canfdi_symptoms_t *s, int8_t report[]);

/*
 * A step that is full for the components in the bit mask `components` (bit
 * c: component c, CANFDI_DIAG_COMP_DCM / _THR; other bits ignored) and a
 * step of the hard rules for the others: each component's matching,
 * result, isolation count and model verdicts are its own, so the
 * application can match the two components in different steps of its
 * rate schedule and spread the matching's cost. CANFDI_DIAG_ALL_COMP is
 * canfdi_diagnosis_step, 0 canfdi_diagnosis_step_hard (the same bits).
 */
void canfdi_diagnosis_step_comp(canfdi_diagnosis_t *d, const canfdi_symptoms_t *s, int8_t report[],
                                uint32_t components);

/*
 * The fault isolated now in `component` (CANFDI_COMPONENT_DC_MOTOR or
 * _THROTTLE of canfdi_catalogue.h), 0 for none / NULL / another component;
 * *confidence_pct (if non-NULL) its confidence 0..100.
 */
uint8_t canfdi_diagnosis_isolated(const canfdi_diagnosis_t *d, uint8_t component,
                                  uint8_t *confidence_pct);

/* The full result of `component` (NULL for NULL d or another component). */
const canfdi_diagnosis_result_t *canfdi_diagnosis_result(const canfdi_diagnosis_t *d,
                                                         uint8_t component);

/* Throttle: TPS1/TPS2 disagreement (CORR persistent) not isolated to a
 * sensor: report P2135. false for NULL. */
bool canfdi_diagnosis_corr_not_isolated(const canfdi_diagnosis_t *d);

/* Bitset of the faults FAILED in the last step (bit i = fault id i): the
 * report's FAILED entries, for the trouble codes and the actuator manager.
 * 0 for NULL, and after a rejected step. */
uint32_t canfdi_diagnosis_failed_mask(const canfdi_diagnosis_t *d);

/* Bitset of the faults PASSED in the last step: the report's PASSED
 * entries (disjoint from the failed mask). 0 for NULL, and after a
 * rejected step. */
uint32_t canfdi_diagnosis_passed_mask(const canfdi_diagnosis_t *d);

/* Persistent symptom of a channel (CANFDI_DIAG_SYM_*; UNKNOWN for bad
 * arguments), for logs and tests. */
int8_t canfdi_diagnosis_symptom(const canfdi_diagnosis_t *d, uint8_t component, uint8_t channel);

/* The normalised value of a channel in the last step (1.0 = its threshold,
 * Q16.16; 0 while the channel is invalid or for bad arguments): how close
 * a symptom that has not crossed is, e.g. for a suspicion that only a test
 * signal can confirm or clear (canfdi_app_test.h). */
int32_t canfdi_diagnosis_value_q16(const canfdi_diagnosis_t *d, uint8_t component, uint8_t channel);

/* Diagnostics snapshot (zero for NULL). */
canfdi_diagnosis_diag_t canfdi_diagnosis_diag(const canfdi_diagnosis_t *d);

#endif /* CANFDI_DIAGNOSIS_H */
