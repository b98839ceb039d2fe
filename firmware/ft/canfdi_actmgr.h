/*
 * canfdi_actmgr.h — the fault-tolerant actuator manager (Isermann ch. 18–19):
 * sits between the controllers and the actuator frames, and decides per
 * 1 ms step which power stage drives the DC motor, whether the throttle is
 * energised, and the degradation state of both subsystems.
 *
 * Inputs per step (canfdi_actmgr_in_t, plus the throttle vote of this step
 * from ft/canfdi_vote.h): the controllers' voltage commands, the validated
 * armature-voltage and supply measurements, the diagnosis result as a
 * bitset of confirmed/isolated fault ids (bit i = catalogue fault id i,
 * CANFDI_FAULT_BIT), the start-up hold-offs, an application fail-silent
 * request and the time.
 * Outputs (canfdi_actmgr_out_t): per subsystem the actuator command (enable,
 * bridge select, voltage after the manager), the degradation state and its
 * reason, "controller must track" with the value to track, and the faults
 * the manager detected itself (to be reported to the DTC memory).
 *
 * ---------------------------------------------------------------- DC motor
 * Bridge A is primary, B the hot stand-by. A bridge is "failed" when
 *   - diagnosis confirms dcm_bridge_a_dead (A) or dcm_bridges_dead (A and
 *     B), or
 *   - the built-in plausibility check below qualifies it failed.
 * Failures latch until canfdi_actmgr_clear(). Decision, every step:
 *   A ok                -> bridge A, enable 1          (state per catalogue)
 *   A failed, B ok      -> bridge B, enable 1, DEGRADED (dcm_bridge_a_dead)
 *   A and B failed      -> bridge NONE, enable 0, command 0,
 *                          FAIL_SAFE (dcm_bridges_dead): drive off.
 * The switch to B happens in the same step as the decision that A failed
 * (0 steps of delay). Bumpless transfer: B receives the controller's own
 * output of that step (no jump in the command), and "must track" is
 * raised in that step with track_V_q16 = that command, so a controller
 * that re-initialises its states on an actuator change (filters,
 * integrator by back-calculation) starts from the applied value. The
 * windup gathered in the few steps A delivered nothing stays in the
 * integrator; it helps recover the speed dip and is part of the measured
 * figures below. Any other DC-motor fault in the bitset requests the
 * catalogue's degradation for it (e.g. com_dcm_timeout -> FAIL_SAFE ->
 * drive off; sensor offsets -> DEGRADED, drive continues).
 *
 * Plausibility check of the active bridge (detects a dead bridge without
 * waiting for diagnosis). The bridge is an averaged-PWM voltage source, so
 * the measured terminal voltage U_A follows the command with the loop's
 * transport delay: the measurement taken at step k shows the command
 * applied at step k - L, L the lag (1 in lockstep SIL: command, plant step,
 * sample). The manager keeps its last CANFDI_ACTMGR_UA_HIST applied
 * commands. At step k, over the lag window L = lag_min..lag_max:
 *   - the check is EVALUATED only if, for every L in the window, the same
 *     bridge was selected and enabled and the expected voltage
 *     u_exp(L) = clamp(u_cmd(k - L), -supply, +supply) (no clamp while the
 *     supply measurement is invalid) has |u_exp| >= check_min;
 *     and U_A is valid and dcm_ua_sensor_offset is not confirmed;
 *   - the measurement is EXPLAINED if for some L in the window
 *       sign(u_exp) * U_A >= deliver_ratio * |u_exp|
 *     i.e. the bridge delivered at least that fraction of what it was told;
 *   - evaluated and explained -> PREPASSED, evaluated and not explained ->
 *     PREFAILED, to that bridge's debouncer, which counts CONSECUTIVE
 *     PREFAILED steps (as in canfdi_vote.h); bridge_fail_steps of them mark
 *     the bridge failed. Not evaluated -> nothing (the count holds).
 * Detection time: a bridge that dies while driving |u| >= check_min is
 * failed on the bridge_fail_steps-th consecutive sample that shows it
 * (once it is dead no command in the window explains a ~0 V sample), and
 * the switch is in that same step. With the defaults (window 1..1, 3
 * steps) and lockstep (lag 1): bridge A dies at t0, the samples at t0 + 1,
 * + 2, + 3 ms show 0 V, B drives from t0 + 3 ms. Measured with the
 * host_sim plants (test_actmgr.c, closed loop, 100 rad/s, 1 N m load,
 * U_A ~ 39 V): 3 ms of 0 V, speed dip 8.7 rad/s (8.7 %), back within
 * 1 rad/s 19 ms after the fault, overshoot 3.0 rad/s; both bridges dead:
 * drive off 6 ms after the fault.
 * Why it does not fire in normal transients: within the window the
 * measurement equals one of the commands up to noise and quantisation
 * (the averaged bridge has no dynamics of its own), and deliver_ratio 0.5
 * leaves room for a 2 V U_A sensor offset (dcm_ua_sensor_offset's default)
 * at check_min 6 V: 6 - 2 = 4 V >= 3 V. Commands that change sign or size
 * by a lot between steps are matched by the lag they belong to; a
 * measurement lag outside the window would make single steps PREFAILED,
 * which the consecutive count absorbs unless the command keeps jumping.
 * Not detectable: a bridge that dies while commanded below check_min
 * (e.g. at standstill); it is detected as soon as the command rises.
 *
 * ---------------------------------------------------------------- throttle
 * Target state, the safest of (reasons recorded in this priority order):
 *   1. confirmed throttle faults in the bitset: the catalogue's degradation
 *      (jam, motor open, both TPS lost, frame timeout/counter/CRC/length/
 *      implausible -> FAIL_SAFE; TPS range/drift -> DEGRADED; parametric ->
 *      NORMAL);
 *   2. both TPS excluded from the vote (input invalid or isolated) ->
 *      FAIL_SAFE at once (reason thr_tps_both_lost);
 *   3. the vote not valid (DISAGREE, SINGLE, INVALID) for vote_loss_steps
 *      consecutive steps -> FAIL_SAFE (reason TPS_DISAGREE or VOTE_LOST);
 *   4. one TPS excluded -> DEGRADED (fail-operational: voting continues
 *      with the other sensor and the model); reason: the confirmed fault of
 *      that sensor if there is one, else its drift fault id if the vote
 *      isolated it, else TPS1/TPS2_INVALID;
 *   5. the model isolated by the vote -> DEGRADED (MODEL_ISOLATED: the tie
 *      breaker is lost).
 * FAIL_SAFE or FAIL_SILENT = limp-home: enable 0, command 0 (the motor is
 * de-energised and the return spring takes the valve to its limp-home
 * angle), held until canfdi_actmgr_clear() succeeds (the degradation
 * ratchet, ft/canfdi_degrade.h). Otherwise enable 1 and the controller's
 * command, limited to +-thr_u_max.
 *
 * Start-up hold-off (dcm_hold_off, thr_hold_off): the application holds a
 * drive off until its plant's inputs were valid once (a sensor node may
 * boot after this ECU). While held off the actuator is off, enable 0 and
 * command 0, without a degradation (no fault, no state change); the bridge
 * selection stays as decided, "must track" is raised with 0 and the
 * controller mode is TRACK (the controller may run; it tracks 0). The
 * history of applied commands records the drive as off, so the bridge
 * check never judges a held-off bridge.
 *
 * Both subsystems: the application's fail_silent request -> FAIL_SILENT
 * (reason FAIL_SILENT), actuators off. Commands are limited to +-u_max
 * (then "must track" is raised too, counted as a clamp). "Must track"
 * (track = 1, track_V_q16 = the command actually applied, 0 when off) is
 * raised whenever the applied command differs from the controller's or a
 * bridge switch happens: the controller then sets its integrator so its
 * output equals track_V_q16 (back-calculation), which is both anti-windup
 * and bumpless transfer. The same information as a controller mode of
 * ctrl/canfdi_ctrl_mode.h: *_ctrl_mode = CANFDI_CTRL_OFF when the actuator
 * is off, CANFDI_CTRL_TRACK (u_track = track_V_q16) when track is raised,
 * else CANFDI_CTRL_RUN; the application passes it on unchanged.
 *
 * Reasons recorded in the degradation states: catalogue fault ids, or the
 * CANFDI_ACTMGR_REASON_* codes below (>= 0x80, no catalogue id exists).
 *
 * Clearing: canfdi_actmgr_clear(subsystems, cause, faults) calls
 * canfdi_degrade_clear per subsystem with fault_present = "a fault of this
 * subsystem with a catalogue degradation above NORMAL is in `faults`"; if
 * accepted it also forgets the subsystem's latches (failed bridges, the
 * debouncers, self-detected faults). The caller clears the vote
 * (canfdi_vote_clear) in the same breath for the throttle.
 *
 * Scaling and overflow: voltages Q16.16 V. Limits by canfdi_clamp_s32.
 * deliver_ratio (Q16.16, 0 < r < 1) x |u_exp| (< 2^31) -> 64-bit product
 * rounded to Q16.16 (canfdi_mul_s32_qn), cannot saturate since r < 1;
 * sign(u_exp) * U_A by saturating negate (canfdi_q31_neg). No wrap, no
 * rounding elsewhere.
 *
 * Cost per canfdi_actmgr_step(): the plausibility window (<= 4 entries, one
 * 64-bit multiply each), 2 debouncer steps, two scans of the fault bitset
 * up to its highest set bit (a table read per set bit), <= 2 degradation
 * requests. Measured executed instructions (arm-none-eabi-gcc 12 -Os, QEMU
 * mps2-an386 -icount, min/mean/max incl. call overhead):
 *                                       Cortex-M0+ code    Cortex-M4
 *   4000 random steps (sparse faults,   374 / 446 / 786    251 / 306 / 543
 *   random votes, dead-bridge samples)
 *   worst case: all 31 fault bits set,  1095 / 1158 / 1222 944 / 1000 / 1057
 *   window 1..4, a clear every 2nd step
 * Code: 2278 bytes (M0+). Stack: 80 bytes (-fstack-usage, M0+) plus
 * callees (<= 40).
 * Memory: sizeof(canfdi_actmgr_t) = 544 bytes on a 32-bit target (two
 * degradation states 2 x 176, three debouncers, two debounce configs,
 * history 4 x 8, config, diagnostics). The instance holds pointers into
 * itself (debouncer configs): do not copy it after init. No heap.
 */
#ifndef CANFDI_ACTMGR_H
#define CANFDI_ACTMGR_H

#include "catalogue/canfdi_catalogue.h"
#include "core/canfdi_common.h"
#include "ctrl/canfdi_ctrl_mode.h"
#include "core/canfdi_debounce.h"
#include "ft/canfdi_degrade.h"
#include "ft/canfdi_vote.h"

/* Bridge selection, numbered as DcmBridgeSel / StsActiveBridge in the DBC. */
#define CANFDI_ACTMGR_BRIDGE_NONE 0U
#define CANFDI_ACTMGR_BRIDGE_A 1U
#define CANFDI_ACTMGR_BRIDGE_B 2U

/* Applied commands remembered for the plausibility window (RAM 8 B each). */
#define CANFDI_ACTMGR_UA_HIST 4U

/* Subsystem masks for canfdi_actmgr_clear(). */
#define CANFDI_ACTMGR_SUB_DCM 0x01U
#define CANFDI_ACTMGR_SUB_THR 0x02U

/* Reasons without a catalogue fault id (>= 0x80, below the clear causes). */
#define CANFDI_ACTMGR_REASON_TPS_DISAGREE 0x80U   /* no agreeing pair, no tie breaker */
#define CANFDI_ACTMGR_REASON_VOTE_LOST 0x81U      /* fewer than two sources */
#define CANFDI_ACTMGR_REASON_TPS1_INVALID 0x82U   /* TPS1 input invalid, not (yet) named */
#define CANFDI_ACTMGR_REASON_TPS2_INVALID 0x83U
#define CANFDI_ACTMGR_REASON_MODEL_ISOLATED 0x84U
#define CANFDI_ACTMGR_REASON_FAIL_SILENT 0x85U    /* application request */

/* Which catalogue faults belong to which subsystem (comm faults by frame). */
#define CANFDI_ACTMGR_DCM_FAULTS                                                \
  (CANFDI_FAULT_BIT(CANFDI_FAULT_DCM_RA_UP) |                                   \
   CANFDI_FAULT_BIT(CANFDI_FAULT_DCM_FLUX_DOWN) |                               \
   CANFDI_FAULT_BIT(CANFDI_FAULT_DCM_FRICTION_UP) |                             \
   CANFDI_FAULT_BIT(CANFDI_FAULT_DCM_IA_SENSOR_OFFSET) |                        \
   CANFDI_FAULT_BIT(CANFDI_FAULT_DCM_SPEED_SENSOR_GAIN) |                       \
   CANFDI_FAULT_BIT(CANFDI_FAULT_DCM_SPEED_SENSOR_OFFSET) |                     \
   CANFDI_FAULT_BIT(CANFDI_FAULT_DCM_UA_SENSOR_OFFSET) |                        \
   CANFDI_FAULT_BIT(CANFDI_FAULT_DCM_BRIDGE_A_DEAD) |                           \
   CANFDI_FAULT_BIT(CANFDI_FAULT_DCM_BRIDGES_DEAD) |                            \
   CANFDI_FAULT_BIT(CANFDI_FAULT_COM_DCM_TIMEOUT) |                             \
   CANFDI_FAULT_BIT(CANFDI_FAULT_COM_DCM_COUNTER) |                             \
   CANFDI_FAULT_BIT(CANFDI_FAULT_COM_DCM_CRC) |                                 \
   CANFDI_FAULT_BIT(CANFDI_FAULT_COM_DCM_LENGTH) |                              \
   CANFDI_FAULT_BIT(CANFDI_FAULT_COM_DCM_IMPLAUSIBLE))
#define CANFDI_ACTMGR_THR_FAULTS                                                \
  (CANFDI_FAULT_BIT(CANFDI_FAULT_THR_TPS1_OPEN) |                               \
   CANFDI_FAULT_BIT(CANFDI_FAULT_THR_TPS1_SHORT) |                              \
   CANFDI_FAULT_BIT(CANFDI_FAULT_THR_TPS2_OPEN) |                               \
   CANFDI_FAULT_BIT(CANFDI_FAULT_THR_TPS2_SHORT) |                              \
   CANFDI_FAULT_BIT(CANFDI_FAULT_THR_TPS1_DRIFT) |                              \
   CANFDI_FAULT_BIT(CANFDI_FAULT_THR_TPS2_DRIFT) |                              \
   CANFDI_FAULT_BIT(CANFDI_FAULT_THR_SPRING_WEAK) |                             \
   CANFDI_FAULT_BIT(CANFDI_FAULT_THR_FRICTION_UP) |                             \
   CANFDI_FAULT_BIT(CANFDI_FAULT_THR_MOTOR_R_UP) |                              \
   CANFDI_FAULT_BIT(CANFDI_FAULT_THR_MOTOR_OPEN) |                              \
   CANFDI_FAULT_BIT(CANFDI_FAULT_THR_JAMMED) |                                  \
   CANFDI_FAULT_BIT(CANFDI_FAULT_THR_TPS_BOTH_LOST) |                           \
   CANFDI_FAULT_BIT(CANFDI_FAULT_COM_THR_TIMEOUT) |                             \
   CANFDI_FAULT_BIT(CANFDI_FAULT_COM_THR_COUNTER) |                             \
   CANFDI_FAULT_BIT(CANFDI_FAULT_COM_THR_CRC) |                                 \
   CANFDI_FAULT_BIT(CANFDI_FAULT_COM_THR_LENGTH) |                              \
   CANFDI_FAULT_BIT(CANFDI_FAULT_COM_THR_IMPLAUSIBLE))

/* Configuration (copied at init; domain checked there). */
typedef struct {
  int32_t dcm_u_max_V_q16;         /* > 0: command limit, V */
  int32_t dcm_check_min_V_q16;     /* > 0: |expected U_A| the check needs, V */
  int32_t dcm_deliver_ratio_q16;   /* (0, 1) in Q16.16: delivered fraction */
  uint8_t dcm_lag_min_steps;       /* 1..CANFDI_ACTMGR_UA_HIST */
  uint8_t dcm_lag_max_steps;       /* lag_min..CANFDI_ACTMGR_UA_HIST */
  uint16_t dcm_bridge_fail_steps;  /* 1..32767 consecutive implausible steps */
  int32_t thr_u_max_V_q16;         /* > 0: command limit, V */
  uint16_t thr_vote_loss_steps;    /* 1..32767 consecutive invalid votes */
} canfdi_actmgr_cfg_t;

typedef struct {
  int32_t dcm_u_ctrl_V_q16;  /* speed controller output, V */
  int32_t dcm_ua_V_q16;      /* measured armature voltage of this step, V */
  int32_t dcm_supply_V_q16;  /* measured bridge supply, V */
  bool dcm_ua_valid;         /* from input supervision (fresh, in range) */
  bool dcm_supply_valid;
  int32_t thr_u_ctrl_V_q16;  /* position controller output, V */
  uint32_t faults;           /* confirmed/isolated fault ids, bit i = id i */
  bool fail_silent;          /* application request for both subsystems */
  bool dcm_hold_off;         /* DC motor not to be energised yet (start-up) */
  bool thr_hold_off;         /* throttle not to be energised yet (start-up) */
  uint64_t now_ms;           /* uptime for the degradation records */
} canfdi_actmgr_in_t;

typedef struct {
  bool enable;
  uint8_t bridge;       /* CANFDI_ACTMGR_BRIDGE_*; NONE when off */
  int32_t u_cmd_V_q16;  /* 0 when off */
} canfdi_actmgr_dcm_cmd_t;

typedef struct {
  bool enable;
  int32_t u_cmd_V_q16;  /* 0 when off */
} canfdi_actmgr_thr_cmd_t;

typedef struct {
  canfdi_actmgr_dcm_cmd_t dcm;
  canfdi_actmgr_thr_cmd_t thr;
  uint8_t dcm_state;        /* CANFDI_DEG_*, StsDegStateDcm */
  uint8_t thr_state;        /* CANFDI_DEG_*, StsDegStateThr */
  uint8_t dcm_reason;       /* reason of the present DC-motor state */
  uint8_t thr_reason;
  bool dcm_track;           /* speed controller must track dcm_track_V_q16 */
  bool thr_track;           /* position controller must track thr_track_V_q16 */
  int32_t dcm_track_V_q16;
  int32_t thr_track_V_q16;
  uint8_t dcm_ctrl_mode;    /* the same as a CANFDI_CTRL_* mode for the */
  uint8_t thr_ctrl_mode;    /* controllers: OFF / TRACK / RUN (see above) */
  bool thr_limp_home;       /* StsThrLimpHome */
  bool bridge_switched;     /* the DC motor changed bridge in this step */
  uint32_t detected;        /* fault-id bits the manager detected itself */
} canfdi_actmgr_out_t;

/* Monotone counters, saturating at UINT32_MAX; only init zeroes them. */
typedef struct {
  uint32_t steps;
  uint32_t bridge_switches;     /* A -> B switches */
  uint32_t drive_offs;          /* steps entering DC-motor drive off */
  uint32_t limp_homes;          /* steps entering throttle limp-home */
  uint32_t ua_implausible;      /* PREFAILED plausibility steps */
  uint32_t dcm_clamps;          /* steps the DC-motor command was limited */
  uint32_t thr_clamps;
  uint32_t clears;              /* accepted subsystem clears */
  uint32_t clears_refused;
  uint32_t rejected;            /* calls with invalid arguments */
} canfdi_actmgr_diag_t;

typedef struct {
  int32_t u_V_q16;
  uint8_t bridge;
  bool enable;
} canfdi_actmgr_hist_t;

typedef struct {
  canfdi_actmgr_cfg_t cfg;
  canfdi_debounce_cfg_t bridge_deb_cfg;
  canfdi_debounce_cfg_t vote_deb_cfg;
  canfdi_debounce_t bridge_deb[2];  /* [0] A, [1] B */
  canfdi_debounce_t vote_deb;       /* "vote not valid" */
  canfdi_degrade_t dcm_deg;
  canfdi_degrade_t thr_deg;
  canfdi_actmgr_hist_t hist[CANFDI_ACTMGR_UA_HIST]; /* ring of applied commands */
  uint8_t hist_head;                /* next entry to write */
  uint8_t hist_count;
  uint8_t active_bridge;            /* of the last step */
  bool bridge_failed[2];
  bool thr_off;                     /* limp-home in the last step */
  bool initialised;
  uint32_t detected;
  canfdi_actmgr_diag_t diag;
} canfdi_actmgr_t;

/*
 * Defaults for the plants of docs/design.md: dcm_u_max 60 V and
 * thr_u_max 16 V (the ranges of DcmUaCmd / ThrUCmd in the DBC; the bridges
 * clamp to their supply themselves), check_min 6 V, deliver_ratio 0.5,
 * lag window 1..1 (lockstep SIL), bridge_fail_steps 3,
 * thr_vote_loss_steps 20 (20 ms; well inside the 200 ms limp-home budget
 * and longer than a frame or two of jitter). Cannot fail for non-NULL.
 */
void canfdi_actmgr_default_cfg(canfdi_actmgr_cfg_t *cfg);

/*
 * Validate cfg (domains above) and reset m: bridge A, nothing failed, both
 * subsystems NORMAL, empty history, diagnostics 0. Returns CANFDI_OK or
 * -CANFDI_EINVAL (m unusable then). Cost: O(1).
 */
int32_t canfdi_actmgr_init(canfdi_actmgr_t *m, const canfdi_actmgr_cfg_t *cfg);

/*
 * One manager step (rules in the header comment). vote is this step's
 * result of canfdi_vote_step. Writes *out completely. Returns CANFDI_OK, or
 * -CANFDI_EINVAL for a NULL argument or an unusable instance; then *out
 * (if non-NULL) commands both actuators off (the safe side), states
 * FAIL_SAFE, and nothing else changes. Cost: see the header comment.
 */
int32_t canfdi_actmgr_step(canfdi_actmgr_t *m, const canfdi_actmgr_in_t *in,
                           const canfdi_vote_out_t *vote, canfdi_actmgr_out_t *out);

/*
 * Clear the subsystems in `subsystems` (CANFDI_ACTMGR_SUB_* mask) for
 * `cause` (CANFDI_DEGRADE_CLEAR_TESTER or _NEW_CYCLE) given the confirmed
 * faults now. Returns the mask of subsystems now NORMAL and forgotten
 * (>= 0), or -CANFDI_EINVAL (NULL, unusable, unknown cause or mask).
 * Cost: O(1) plus a scan of the bitset.
 */
int32_t canfdi_actmgr_clear(canfdi_actmgr_t *m, uint32_t subsystems, uint8_t cause,
                            uint32_t faults, uint64_t now_ms);

/*
 * The DC-motor command the bridge really held over the last step, when
 * another controller applied it (a replay of a recorded vehicle: the
 * recorded ECU's DcmActuator frame): replaces the newest entry of the
 * history of applied commands, so that the plausibility check of the next
 * step judges the measured U_A against what the bridge got. dcm NULL: the
 * command is not known; the entry is recorded as not driving, so the check
 * is not evaluated over a window that contains it (never judged on a
 * guess). Call between two steps; before the first step there is no entry
 * and nothing changes. Returns CANFDI_OK or -CANFDI_EINVAL (NULL m,
 * unusable instance). Cost: O(1).
 */
int32_t canfdi_actmgr_set_applied(canfdi_actmgr_t *m, const canfdi_actmgr_dcm_cmd_t *dcm);

/* The degradation states, for their logs and counters (NULL for NULL). */
const canfdi_degrade_t *canfdi_actmgr_degrade_dcm(const canfdi_actmgr_t *m);
const canfdi_degrade_t *canfdi_actmgr_degrade_thr(const canfdi_actmgr_t *m);

/* Diagnostics snapshot (zero for NULL). Cost: O(1). */
canfdi_actmgr_diag_t canfdi_actmgr_diag(const canfdi_actmgr_t *m);

#endif /* CANFDI_ACTMGR_H */
