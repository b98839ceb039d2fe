/*
 * canfdi_app.h — the supervisor application: one 1 ms step over statically
 * allocated state that closes both control loops, supervises its inputs and
 * both plants, names the fault, remembers it and keeps the plants safe.
 *
 * The port's interface (docs/architecture.md). Nothing else crosses the
 * boundary: the same core
 * runs in SIL (tests/sil), on SocketCAN (port/linux) and on a
 * microcontroller (port/cortexm).
 *   power-up      canfdi_app_power_up(app, cal, now_us, image, len): a cold
 *                 start with the DTC memory's NVM image (or none), and a
 *                 new operation cycle; canfdi_app_init is the same without
 *                 an image
 *   frames in     canfdi_app_rx_frame() for every received CAN frame (any
 *                 id; the input supervision judges it, except UdsPhysReq
 *                 0x7E0 and UdsFuncReq 0x7DF: the diagnostic server's)
 *   1 ms step     canfdi_app_step() writes the frames to send in this step
 *                 into the caller's buffer (CANFDI_APP_MAX_TX frames)
 *   NVM           canfdi_app_nvm_image() for a periodic store while
 *                 running (when canfdi_app_nvm_changes() moved);
 *                 canfdi_app_power_down() ends the operation cycle and
 *                 gives the image to store before power is cut
 *   timing        canfdi_app_deadline_miss(), canfdi_app_port_timing()
 *   replay        canfdi_app_set_applied(): the commands another controller
 *                 applied (a recorded vehicle), for the next step's models
 * A tester's requests act through canfdi_app_new_cycle() and
 * canfdi_app_clear_dtc(); the DTC memory is read through canfdi_app_dtc().
 *
 * The step is a sequence of stages; each stage is a module with its own
 * configuration, counters and manual, and the stages pass narrow structs:
 *   1. input supervision  canfdi_rx: validated inputs and the U-code
 *                         monitors; the nominal load stands in for a lost
 *                         load feed-forward
 *   2. vote               canfdi_limit range checks of TPS1/TPS2, then
 *                         canfdi_vote over TPS1, TPS2 and the throttle
 *                         observer's angle of the previous step
 *   3. control            ctrl_dcm (speed), ctrl_thr (position) plus the
 *                         estimators' excitation, in the mode the actuator
 *                         manager set last step
 *   4. detection          parity_dcm, parity_thr (residuals), est_dcm,
 *                         est_thr (parameters; their RLS updates are
 *                         decimated inside the modules), the actuator
 *                         monitors (detect/canfdi_actmon)
 *   5. symptoms           canfdi_app_sym: the symptom vector
 *   6. diagnosis          canfdi_diagnosis: a verdict per fault id
 *   7. trouble codes      canfdi_dtcroute: verdicts, the manager's own
 *                         findings and the U-code monitors into the DTC
 *                         memory, with a freeze frame of the key signals
 *   8. fault tolerance    canfdi_actmgr: bridges, limp-home, degradation
 *   9. outputs            canfdi_app_out: actuators every step, residuals
 *                         10 ms, status / diagnosis / self-diagnostics /
 *                         DTC / parameters 100 ms, DTC status changes on
 *                         change
 *  10. diagnostic server  canfdi_app_uds (uds/canfdi_uds.h): a tester's
 *                         request answered from this step's values, at
 *                         most one ISO-TP frame (UdsPhysResp 0x7E8); its
 *                         decisions (actuator test references, spring
 *                         check release, estimator resets, monitoring
 *                         frames off, ECU reset) act in the next step
 * Feedback (canfdi_app_fb_t): what the last step decided and this step
 * obeys. The models use the commands the manager applied over the interval
 * that ends with this step's samples; the observer's angle is not offered
 * to the vote while the diagnosis holds a persistent throttle armature
 * symptom (its velocity rests on the armature equation); an estimator is
 * not fed while an input of its equations is known bad (U_A: the UAC
 * symptom or a latched U_A offset) or its plant is not driven (throttle
 * de-energised, no valid position, no motor current). A fed-again
 * estimator restarts with a covariance reset and its parameter symptoms
 * stay invalid until it has re-converged. A plant's inputs that come back
 * from an interruption (a timeout, a rejected frame or sample: not VALID
 * for a step) restart its parity equations, and its model rules are held
 * for cal.rearm_steps from then on (the gate's rearm; the diagnosis'
 * "Re-arming"): the plant may have moved meanwhile, and the residuals of
 * the restarted equations need that long to leave a transient. A sample
 * that is VALID but not fresh (its frame late, within the timeout), or
 * that came with another in one step (a frame early: the models see two
 * steps' change in one), restarts nothing: the models step on the last
 * sample, which under acceleration reads as a shaft that stopped and then
 * jumped, so the speed-step check compares only consecutive steps with
 * one new sample each and the model rules are held for
 * cal.late_hold_steps.
 *
 * Start-up: no drive is energised before its plant's inputs were valid once
 * (the sensor node may boot after this ECU, cal.rx.first_timeout_us); the
 * actuator manager holds it off (canfdi_actmgr.h, hold-off).
 *
 * Time: the port's microsecond clock (now_us, uint32_t) may wrap every
 * 71.6 minutes; supervision windows use its differences. Time stamps (the
 * freeze frames, the degradation records) use the uptime in ms kept from
 * it (core/canfdi_uptime.h), right for years.
 *
 * Setpoints (docs/design.md, "Setpoint supervision"): the vehicle's
 * SetpointDcm / SetpointThr are E2E protected and judged by canfdi_rx like
 * the sensor frames; while one is in error the last accepted value is
 * used (SUBSTITUTED, at most 50 ms after its acceptance), then (INVALID)
 * the speed reference is 0 (the motor braked to standstill) and the
 * position reference cal.ctrl_thr.limp_home_rad_q16; U1A50 (timeout) or
 * U1A51 (rejected frames); no degradation state changes.
 *
 * Load: the firmware has no torque sensor; the vehicle sends the load it
 * knows it applies with the speed setpoint (SpDcmLoad). It is the parity
 * equations' load input, the estimator's known load offset (relative to
 * cal.load_nom_Nm_q16, which est_dcm's mc_nom includes), and the lumped M_c
 * deviation's reference. Lost or rejected: cal.load_nom_Nm_q16. An
 * unknown share of the load still looks like friction: r2..r4 follow their
 * mean over load_tau_s, the lumped M_c does not.
 *
 * Scaling and overflow: all signals Q16.16 SI (see the modules); the
 * application adds only the modules' conversions and saturating
 * arithmetic (core/canfdi_fixp.h). Counters saturate.
 *
 * Cost per canfdi_app_step, executed instructions measured on QEMU with
 * -icount (SysTick), arm-none-eabi-gcc 12 -Os, `make bench-pil` (tests/pil;
 * build/bench/pil.json), the 24 000 steps of the SIL demo:
 *                          min      mean     max
 *   Cortex-M3 (an385)      15 343   16 879   20 670
 *   Cortex-M4 (an386)      15 343   16 881   20 667
 *   Cortex-M0 (microbit)   30 180   34 019   43 222
 * and at most 21 286 (M4) / 48 290 (M0) over the PIL scenarios. On both
 * that is a step with two RLS updates (the DC motor's and the throttle's
 * mechanical one) as the throttle's estimator is made alert again after
 * dcm_ia_offset's fault (step 3021; the M0's RLS arithmetic is three times
 * the M4's); the step where the first verdicts reach the trouble codes
 * (step 2100 of every scenario, 20 745 to 20 918 on the M4) and the DC
 * motor's matching while its fault's code is stored come close: the DTC
 * routing gives at most four verdicts a step
 * (CANFDI_DTCROUTE_VERDICTS_PER_STEP), so the twenty codes that are due
 * at once then are spread over five steps, and the two components'
 * matchings have slots of their own (below). Where the instructions go,
 * per module, per slot of the rate schedule and in the costliest steps:
 * `make bench-pil-profile`
 * (tests/pil/pil_profile.py; its split is summarised in
 * docs/requirements.md, requirement 1). A 1 ms step needs a Cortex-M4 of
 * roughly 35 MHz or more with margin (the worst step at ~1.2 cycles per
 * instruction: 26 MHz for the whole millisecond); on a Cortex-M0 at
 * 48 MHz it does not fit (the M0 builds its 32x32->64 products from 16-bit
 * halves, core/canfdi_fixp.h, and runs ~2.1 times the M4's count).
 * Host (x86-64, gcc -O2, callgrind): `make sil-bench`. The same run shows
 * the ECU's frames bit-identical between the host build and the target
 * builds. With a tester's requests in flight (`make pil-test`, the SIL log
 * of tests/sil/scenarios/uds_workshop.scn): at most 18 800 (M4) / 39 500
 * (M0) in those steps; the clear's effect comes one step later (above).
 * Stated worst case, whatever the step receives: 38 000 instructions on
 * the M4, 85 000 on the M0 (the PIL scenarios' maxima, 21 286 / 48 290,
 * with margin). `make pil-cost` checks it on hostile input: the
 * fuzz_app_rx inputs (random frames, identifiers, lengths, E2E errors,
 * jittered steps) run on QEMU; rejected and implausible input costs less
 * than the models running on valid data.
 * Rate schedule (docs/architecture.md, "Rate schedule"): a 10 ms frame of
 * CANFDI_APP_FRAME_SLOTS 1 ms slots (app->slot). Every step: input
 * supervision, vote, control, gates, parity residuals and the estimators'
 * SVFs (their RLS updates decimated: est_dcm armature on slots 1 and 6,
 * mechanical on 2 and 7, CANFDI_APP_SLOT_EST_DCM; est_thr electrical on
 * the even slots, mechanical and fast test on the odd ones,
 * CANFDI_APP_SLOT_EST_THR), actuator monitors, symptom vector (its
 * filters are 1 ms filters), the diagnosis' flags, symptom persistence
 * and hard rules (canfdi_diagnosis_step_hard), DTC routing (it takes
 * one-step events: a rejected frame, a timeout, the manager's findings),
 * actuator manager, outputs, server. Once every cal.diag_period_steps
 * (default 10) for each component: its model rules' matching
 * (canfdi_diagnosis_step_comp), the DC motor's in slot
 * CANFDI_APP_SLOT_DIAG, the throttle's in slot 4 (below), the isolation
 * count converted from 1 ms steps at init (rounded up); between its runs a
 * component's verdicts hold. A model-based fault is named up to one period
 * later than unscheduled; the hard rules' faults at the same step.
 * Memory: sizeof(canfdi_app_t) is printed by `canfdi-sil --sizes` (host);
 * all of the application's RAM, static: 11 080 bytes on Cortex-M (740 of
 * them the diagnostic server, uds/canfdi_uds.h, 1 224 the calibration
 * copy); the application image's static RAM and worst-case stack per core
 * are `make footprint`'s (11 592 B and 2 000 B on the Cortex-M0). No heap.
 */
#ifndef CANFDI_APP_H
#define CANFDI_APP_H

#include "app/canfdi_app_cal.h"
#include "app/canfdi_app_out.h"
#include "app/canfdi_app_test.h"
#include "comm/canfdi_rx.h"
#include "comm/canfdi_tx.h"
#include "core/canfdi_common.h"
#include "core/canfdi_uptime.h"
#include "ctrl/canfdi_ctrl_dcm.h"
#include "ctrl/canfdi_ctrl_thr.h"
#include "ctrl/canfdi_excite.h"
#include "detect/canfdi_actmon.h"
#include "detect/canfdi_limit.h"
#include "diag/canfdi_diagnosis.h"
#include "diag/canfdi_dtc.h"
#include "diag/canfdi_dtcroute.h"
#include "diag/canfdi_symptoms.h"
#include "ft/canfdi_actmgr.h"
#include "ft/canfdi_vote.h"
#include "model/canfdi_est_dcm.h"
#include "model/canfdi_est_thr.h"
#include "model/canfdi_parity_dcm.h"
#include "model/canfdi_parity_thr.h"
#include "uds/canfdi_uds.h"

/* The scheduled frames and one ISO-TP frame of the diagnostic server: a
 * step that sends two actuators, a slow frame and a DTC event may also
 * answer a tester, so the bound grows by that one frame. */
#define CANFDI_APP_MAX_TX (CANFDI_TX_MAX_FRAMES_PER_STEP + 1U)

/* The rate schedule's frame: CANFDI_APP_FRAME_SLOTS 1 ms steps (10 ms);
 * the DC motor's model rules are matched in slot CANFDI_APP_SLOT_DIAG of
 * every cal.diag_period_steps, the throttle's in a slot of its own (below;
 * see the header, rate schedule). */
#define CANFDI_APP_FRAME_SLOTS 10U
#define CANFDI_APP_SLOT_DIAG 0U
/* The model rules are matched per component (canfdi_diagnosis_step_comp):
 * the DC motor's in slot CANFDI_APP_SLOT_DIAG, the throttle's in the first
 * slot from diag_period_steps * 2 / 5 on that holds no update of a locked
 * estimator but the throttle's cheaper electrical one (4 at the default
 * period of 10; 2, 3 and 4 at periods 4, 5 and 8; slot 0, shared with the
 * DC motor's, at periods 1 and 2, where no other slot is free). One
 * matching costs about 1 400 instructions on the M4 with symptoms present
 * (`make bench-pil-profile`): split, neither slot carries both. */
#define CANFDI_APP_SLOT_DIAG_THR_NUM 2U
#define CANFDI_APP_SLOT_DIAG_THR_DEN 5U
/* The estimators' RLS updates on fixed slots (canfdi_est_thr_align,
 * canfdi_est_dcm_align). The throttle's electrical update on the slots
 * with slot mod decim = CANFDI_APP_SLOT_EST_THR (the even ones at its
 * decim of 2), its mechanical update and fast test (the costlier) on the
 * odd ones, never with the model rules' matching in slot
 * CANFDI_APP_SLOT_DIAG. The DC motor's armature update on the slots with
 * slot mod decim = CANFDI_APP_SLOT_EST_DCM and its mechanical update one
 * slot later (slots 1, 2, 6 and 7 at its decim of 5): never in the
 * matching's slot, where the trouble codes of a new verdict are stored and
 * sent. (Of the phases that avoid slot 0, this one keeps the envelope
 * bench's verdicts: slots 2, 3, 7, 8 named P1A21 for one more incipient
 * R_A ramp in 4 112 runs, docs/requirements.md.) An estimator counts from its
 * own start instead when its decim does not divide cal.diag_period_steps
 * (the intervals would vary). */
#define CANFDI_APP_SLOT_EST_THR 0U
#define CANFDI_APP_SLOT_EST_DCM 1U
#define CANFDI_APP_EST_UNLOCKED 0xFFU

/* The NVM image: a 4-byte header (CANFDI_APP_IMAGE_TAG, version, the
 * security attempt counter, 0) before the DTC memory's image. */
#define CANFDI_APP_IMAGE_TAG 0xA5U
#define CANFDI_APP_IMAGE_VERSION 1U
#define CANFDI_APP_IMAGE_HEADER_BYTES 4U
#define CANFDI_APP_IMAGE_MAX_BYTES (CANFDI_APP_IMAGE_HEADER_BYTES + CANFDI_DTC_IMAGE_MAX_BYTES)

/* canfdi_app_power_up: the NVM image was rejected; the memory starts cleared. */
#define CANFDI_APP_IMAGE_REJECTED 1

/* Monotone self-diagnostics, saturating at UINT32_MAX (EcuSelfDiag). */
typedef struct {
  uint32_t steps;
  uint32_t deadline_misses;   /* reported by the port */
  uint32_t saturations;       /* controller outputs limited + tx values limited */
  uint32_t estimator_resets;  /* est_dcm + est_thr + parity resets */
  uint32_t frames_rejected;   /* length, CRC, counter, implausible (rx) */
  uint32_t frames_unknown;    /* identifiers the rx does not supervise */
  uint32_t frames_sent;
  uint32_t dtc_reports_rejected;
} canfdi_app_diag_t;

/* What the last step decided and this step obeys (see the header). */
typedef struct {
  canfdi_actmgr_out_t mgr; /* commands applied over the interval ending now, states */
  uint32_t faults;         /* fault bits the manager acted on */
  bool thr_arm_symptom;    /* persistent throttle armature symptom: model not voted */
  bool dcm_sensor_bad;     /* a DC-motor sensor known bad: its estimator is not fed */
  bool thr_no_current;     /* throttle motor draws no current: its estimator is not fed */
  bool dcm_detected;       /* the diagnosis showed a DC-motor symptom */
  bool thr_detected;       /* ... a throttle symptom */
  uint16_t thr_pos_lag;    /* steps both position residuals stayed past a
                            * quarter of their bands with one sign
                            * (saturating): the valve lags or leads the model */
} canfdi_app_fb_t;

/* The DC motor's check of what it has learnt, made once per power cycle at
 * the first step that is learnt with r1 valid again (R_A's fast learning
 * after power-up has ended, canfdi_parity_dcm.h) and r2 or r3 evaluated
 * for at least the diagnosis' sym_on_steps (a channel that has just become
 * valid reads 0 until then): r2 and r3 hold no R_A (r3 only in current
 * swings), so a symptom on either there means the plant was faulty in the
 * window R_A and the estimates were learnt from. The fault is then in
 * them: an I_A offset or a flux loss moves the learnt R_A by -R dI / I or
 * -dPsi w / I and r1 reads zero, the pattern of a friction rise, which at
 * one operating point no measurement separates from them. Until the check
 * is made, and for the rest of the power cycle once it found a fault, the
 * model rules are not tested (CANFDI_SYM_F_DCM_UNLEARNT): not tested,
 * never guessed. */
#define CANFDI_APP_LEARN_PENDING 0U /* not made yet */
#define CANFDI_APP_LEARN_CLEAN 1U   /* made: r2 and r3 quiet */
#define CANFDI_APP_LEARN_FAULT 2U   /* made: a fault was learnt in */

/* Which plant's models run and learn; state, not counters. */
typedef struct {
  bool in_ok;     /* the plant's inputs VALID this step: parity equations run */
  bool fresh;     /* ... and a new sample of them arrived since the last step */
  bool started;   /* in_ok was true once since power-up: the drive may be energised */
  bool est_on;    /* the estimator was fed this step */
  bool est_restart; /* this step the estimator's covariance was boosted or
                     * reset: its memory starts again */
  bool learnt;      /* DC motor: the armature and the mechanical estimates
                     * have both converged once since power-up (a restart
                     * that keeps the estimates keeps it); until then the
                     * DC motor's model rules are not tested
                     * (CANFDI_SYM_F_DCM_UNLEARNT) */
  uint8_t learn_check; /* DC motor: CANFDI_APP_LEARN_* */
  uint8_t learn_seen;  /* DC motor: consecutive steps r2 or r3 was
                        * evaluated (saturating at UINT8_MAX) */
  uint16_t rearm;   /* steps the model rules stay held after the inputs
                     * came back or a sample was late
                     * (CANFDI_SYM_F_DCM_REARM / _THR_REARM) */
} canfdi_app_gate_t;

/*
 * What the actuators really got when another controller drove them
 * (canfdi_app_set_applied: a replay of a recorded vehicle, whose ECU's
 * actuator frames say what was applied). For one step.
 */
typedef struct {
  bool dcm_known;                /* dcm is the DC-motor command applied */
  canfdi_actmgr_dcm_cmd_t dcm;
  bool thr_known;                /* thr is the throttle command applied */
  canfdi_actmgr_thr_cmd_t thr;
  bool thr_ref_known;            /* the throttle was driven to this application's
                                  * position reference (the setpoint plus this
                                  * application's excitation) */
} canfdi_app_applied_t;

typedef struct {
  canfdi_app_cal_t cal; /* copy; the modules point into it */
  canfdi_rx_t rx;
  canfdi_tx_t tx;
  canfdi_ctrl_dcm_t ctrl_dcm;
  canfdi_ctrl_thr_t ctrl_thr;
  canfdi_excite_t excite_dcm;
  canfdi_excite_t excite_thr;
  canfdi_app_test_t test;  /* when the test signals run */
  canfdi_parity_dcm_t parity_dcm;
  canfdi_parity_thr_t parity_thr;
  canfdi_est_dcm_t est_dcm;
  canfdi_est_thr_t est_thr;
  canfdi_limit_t tps_range[2];
  canfdi_vote_t vote;
  canfdi_actmon_t actmon;
  canfdi_app_sym_t sym_state;
  canfdi_actmgr_t actmgr;
  canfdi_diagnosis_t diagnosis;
  canfdi_dtc_t dtc;
  canfdi_dtcroute_t dtcroute;
  canfdi_app_out_t out;
  canfdi_uds_t uds;
  canfdi_uds_act_t uds_act; /* the server's decisions of the last step, for this one */
  canfdi_uptime_t uptime;
  /* results of this step's stages */
  canfdi_vote_out_t vote_out;
  canfdi_actmon_out_t actmon_out;
  canfdi_symptoms_t sym;
  canfdi_app_gate_t dcm;
  canfdi_app_gate_t thr;
  canfdi_app_fb_t fb;   /* of the last step, for this one */
  canfdi_app_applied_t applied; /* for the next step, if applied_set */
  bool applied_set;     /* canfdi_app_set_applied was called since the last step */
  canfdi_app_diag_t diag;
  uint8_t slot;         /* this step's slot: steps since power-up modulo
                         * cal.diag_period_steps */
  uint8_t slot_diag_thr; /* the throttle's matching slot for this period
                          * (CANFDI_APP_SLOT_DIAG_THR_NUM) */
  uint8_t est_k[2];     /* the DC motor's (0) and the throttle's (1)
                         * estimator: this step's step of its schedule,
                         * modulo its decim (CANFDI_APP_EST_UNLOCKED: it
                         * counts from its own start) */
  bool running;         /* a step has run since power-up */
  bool reset_requested; /* ECUReset answered: the port powers down and up */
  bool initialised;
} canfdi_app_t;

/*
 * Copies cal, initialises every module, starts an operation cycle of a
 * cleared DTC memory: canfdi_app_power_up without an image. Returns
 * CANFDI_OK or -CANFDI_EINVAL (a module refused its configuration; app
 * unusable). Cost: init time only (divisions).
 */
int32_t canfdi_app_init(canfdi_app_t *app, const canfdi_app_cal_t *cal, uint32_t now_us);

/*
 * Cold start: canfdi_app_init, then the DTC memory and the SecurityAccess
 * attempt counter from image[0..len-1] (a canfdi_app_power_down image, or
 * a bare canfdi_dtc_serialize image of version 1 or 2 stored by an earlier
 * firmware; none when len is 0 or image NULL) and a new operation cycle. Returns CANFDI_OK,
 * CANFDI_APP_IMAGE_REJECTED (the image was not usable; the memory starts
 * cleared and the app runs) or -CANFDI_EINVAL (calibration refused).
 */
int32_t canfdi_app_power_up(canfdi_app_t *app, const canfdi_app_cal_t *cal, uint32_t now_us,
                            const uint8_t *image, uint32_t len);

/*
 * Power-down (ignition off, shutdown): ends the operation cycle and writes
 * the NVM image (the header above, then the DTC memory's image) into
 * image[0..cap-1] for the port to store. Returns its length (> 0),
 * -CANFDI_ERANGE (cap too small: CANFDI_APP_IMAGE_MAX_BYTES always
 * suffices) or -CANFDI_EINVAL. The app
 * must be powered up again before the next step.
 */
int32_t canfdi_app_power_down(canfdi_app_t *app, uint8_t *image, uint32_t cap);

/* The DTC memory's image now (a periodic store while running; the cycle
 * goes on). Returns the length or a negative error as power_down. */
int32_t canfdi_app_nvm_image(const canfdi_app_t *app, uint8_t *image, uint32_t cap);

/* Changes to the DTC memory's persistent state so far (wraps; store when it
 * differs from the value at the last store). 0 for NULL. */
uint32_t canfdi_app_nvm_changes(const canfdi_app_t *app);

/* A new operation cycle without a restart (ignition off and on while the
 * ECU stays powered). Returns CANFDI_OK or -CANFDI_EINVAL. */
int32_t canfdi_app_new_cycle(canfdi_app_t *app);

/* ClearDiagnosticInformation: group is a DTC, a group of canfdi_dtc_clear
 * or CANFDI_DTC_GROUP_ALL. Returns the canfdi_dtc_clear result. */
int32_t canfdi_app_clear_dtc(canfdi_app_t *app, uint32_t group);

/* One received frame (forwarded to the input supervision). Returns the
 * canfdi_rx_frame result. Cost: see canfdi_rx.h. */
int32_t canfdi_app_rx_frame(canfdi_app_t *app, uint32_t id, const uint8_t *data, uint8_t dlc,
                            uint32_t now_us);

/*
 * Replay: the commands the actuators held over the interval that ends with
 * the next step's samples, when another controller applied them (the
 * recorded ECU's DcmActuator / ThrActuator frames), and whether the
 * throttle was driven to this application's position reference. Call
 * between two steps; it acts on the next step only (every later step uses
 * this application's own commands again unless it is called again).
 *   dcm known    the manager's record of the last step's DC-motor command
 *                (the feedback and the bridge check's history,
 *                canfdi_actmgr_set_applied) becomes applied->dcm;
 *   dcm unknown  recorded as not driving: the bridge check and the U_A
 *                command monitor (actmon UAC) are not judged;
 *   thr known    the throttle's models and actuator monitors use
 *                applied->thr;
 *   thr unknown  the throttle's parity equations, its estimator and its
 *                actuator monitors do not run, and the throttle model is
 *                not offered to the vote (they need the voltage applied);
 *                they restart when it is known again;
 *   thr_ref_known false: the tracking monitor (throttle not following its
 *                reference) is not judged: the reference the throttle was
 *                driven to is not this application's (e.g. the recording
 *                started after the recorded ECU's power-up, so the phase of
 *                its excitation is unknown).
 * The DC motor's parity equations and estimator use the measured U_A and
 * need no command. The controllers, the manager's decisions and the frames
 * sent stay this application's own (a controller the manager makes track
 * tracks the command applied). Returns
 * CANFDI_OK or -CANFDI_EINVAL (NULL argument, app not initialised). O(1).
 */
int32_t canfdi_app_set_applied(canfdi_app_t *app, const canfdi_app_applied_t *applied);

/* One 1 ms step at now_us; writes the frames to send into out[0..n-1]
 * (out holds CANFDI_APP_MAX_TX). Returns n >= 0 or -CANFDI_EINVAL. */
int32_t canfdi_app_step(canfdi_app_t *app, uint32_t now_us, canfdi_tx_frame_t *out);

/* The port reports a missed 1 ms deadline. */
void canfdi_app_deadline_miss(canfdi_app_t *app);

/*
 * The port reports the timing of the step it just ran: step_us, the
 * execution time of canfdi_app_step (and the sending of its frames, as the
 * port measures it), and cycle_us, the time between the starts of this step
 * and the previous one. The app keeps the maximum of each and sends it in
 * the next EcuStatus (StsStepTimeMax, StsCycleTimeMax, saturating at 4095
 * us), then starts a new maximum. A port that never calls this (SIL,
 * lockstep) sends 0 for both, so its frames do not depend on the host's
 * speed. No-op on NULL. Cost O(1).
 */
void canfdi_app_port_timing(canfdi_app_t *app, uint32_t step_us, uint32_t cycle_us);

/* An ECUReset was answered (its response has left with the frames of the
 * step that set this): the port stores the image of canfdi_app_power_down
 * and powers the application up again from it, as after a power cycle.
 * False for NULL. */
bool canfdi_app_reset_requested(const canfdi_app_t *app);

/* The trouble-code memory, read-only (NULL for NULL). */
const canfdi_dtc_t *canfdi_app_dtc(const canfdi_app_t *app);

/* The uptime in ms (core/canfdi_uptime.h); 0 for NULL. */
uint64_t canfdi_app_uptime_ms(const canfdi_app_t *app);

const canfdi_app_diag_t *canfdi_app_diag(const canfdi_app_t *app);

#endif /* CANFDI_APP_H */
