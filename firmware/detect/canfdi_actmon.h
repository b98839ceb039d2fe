/*
 * canfdi_actmon.h — the actuator monitors: three plausibility checks of an
 * actuator against what it was told to do (Isermann, Fault-Diagnosis
 * Systems, ch. 7: limit checking of a signal relation).
 *
 *   monitor           symptom                              judged while
 *   THR tracking      the throttle lags the slowest        the vote is valid and
 *                     trajectory to its position           the throttle is
 *                     reference, low-passed, above         energised
 *                     track_thr
 *   THR no current    voltage applied, no motor current:   energised, |u_cmd| >
 *                     an open motor circuit                open_u_min, current valid
 *   DCM U_A command   the measured armature voltage U_A    the bridge drives
 *   (UAC)             against the bridge command held over unclamped (|u_cmd| <
 *                     the same interval, low-passed and    supply - headroom), no
 *                     divided by uac_thr                   bridge switch, no bridge
 *                                                          fault, U_A and supply valid
 * Only a U_A sensor fault (or a bridge fault, which the actuator manager
 * names) makes U_A and the command disagree: in the armature equation a
 * U_A offset and a speed-sensor offset are the same term, and UAC is the one
 * signal that tells them apart. The throttle's open circuit and jam are
 * hard symptoms of the diagnosis (diag/canfdi_diagnosis.h); UAC is a
 * symptom channel with sign.
 *
 * The tracking monitor compares the angle with an expected angle that
 * moves towards the reference at track_slew per step, the slowest slew a
 * healthy valve has anywhere in the envelope with a margin, not with the
 * reference itself: a tip-in to wide open (10 -> 80 deg takes the valve
 * 48 ms at 13.5 V, 84 ms at 9 V, docs/envelope.md) is a large reference
 * error for tens of ms that says nothing about the valve. While the
 * expected angle is on its way the lag counts only for a valve behind it
 * (a valve faster than the slowest lags by nothing, and the expected
 * angle restarts where that valve got to, so a pedal blip that turns the
 * reference back mid-stroke is judged from there); once it has arrived
 * (a steady or slow reference) the lag is |angle - ref|.
 * While not judged the expected angle restarts at the measured angle, so a
 * start-up with the setpoint already at wide open is the same stroke.
 *
 * The commands in the input are those the actuator manager applied over
 * the interval that ends with this step's samples (its output of the last
 * step); the angle reference is this step's. The module keeps two filter
 * states (tracking error, UAC); the UAC filter holds its value while UAC is
 * not judged and is valid again at once (the filter's memory is of judged
 * samples only).
 *
 * Scaling and overflow: Q16.16 SI (rad, V, A). Filters x += alpha (u - x)
 * with saturating subtraction/addition and a rounded Q16.16 product
 * (canfdi_mul_s32_qn); |.| saturates (|INT32_MIN| -> INT32_MAX); the UAC
 * ratio by canfdi_div_s32_qn (saturating, rounded). No wrap anywhere.
 *
 * Cost per canfdi_actmon_step: two filter updates (one 32x32->64 multiply
 * each), one saturating division when UAC is judged, ~20 compares; no loop.
 * Memory: sizeof(canfdi_actmon_t) = 68 bytes on a 32-bit target (the
 * configuration copy, two filter states, the expected angle and its flag,
 * the diagnostics).
 * Stack < 32 bytes. No heap.
 */
#ifndef CANFDI_ACTMON_H
#define CANFDI_ACTMON_H

#include "core/canfdi_common.h"

/* Configuration (copied at init; domain checked there). */
typedef struct {
  int32_t track_alpha_q16;    /* (0, 1]: low-pass of |angle - ref| per step */
  int32_t track_thr_rad_q16;  /* > 0: filtered error that means "not following" */
  int32_t track_slew_rad_q16; /* > 0: the expected angle's largest move per step */
  int32_t open_u_min_V_q16;   /* > 0: |command| at which a current must flow */
  int32_t open_i_max_A_q16;   /* > 0: |current| below which none flows */
  int32_t uac_alpha_q16;      /* (0, 1]: low-pass of U_A - command per step */
  int32_t uac_thr_V_q16;      /* > 0: filtered U_A - command that is 1.0 */
  int32_t uac_headroom_V_q16; /* >= 0: judged while |command| < supply - headroom */
} canfdi_actmon_cfg_t;

/* One step's inputs. */
typedef struct {
  int32_t thr_angle_rad_q16;  /* voted throttle angle of this step */
  int32_t thr_ref_rad_q16;    /* the position controller's reference of this step */
  bool thr_angle_valid;       /* the vote is valid */
  int32_t thr_i_A_q16;        /* throttle motor current */
  bool thr_i_valid;
  bool thr_enabled;           /* throttle energised over the last interval */
  int32_t thr_u_cmd_V_q16;    /* its voltage command over the last interval */
  int32_t dcm_ua_V_q16;       /* measured armature voltage */
  bool dcm_ua_valid;
  int32_t dcm_supply_V_q16;   /* measured bridge supply */
  bool dcm_supply_valid;
  bool dcm_enabled;           /* DC motor bridge driving over the last interval */
  int32_t dcm_u_cmd_V_q16;    /* its command over the last interval */
  bool dcm_bridge_settled;    /* no bridge switch and no fault the manager detected */
} canfdi_actmon_in_t;

typedef struct {
  bool thr_not_following;        /* tracking monitor: symptom present */
  bool thr_no_current;           /* open-circuit monitor: symptom present */
  bool dcm_uac_valid;            /* UAC judged this step */
  int32_t dcm_uac_rn_q16;        /* filtered (U_A - command) / uac_thr; 0 when not judged */
  int32_t dcm_uac_V_q16;         /* filtered U_A - command, V; 0 when not judged */
  int32_t thr_track_err_rad_q16; /* the filtered tracking error */
} canfdi_actmon_out_t;

/* Monotone counters, saturating at UINT32_MAX; only init zeroes them. */
typedef struct {
  uint32_t steps;
  uint32_t not_following_steps; /* steps with the tracking symptom */
  uint32_t no_current_steps;    /* steps with the open-circuit symptom */
  uint32_t uac_judged_steps;    /* steps UAC was judged */
  uint32_t rejected;            /* calls with invalid arguments */
} canfdi_actmon_diag_t;

typedef struct {
  canfdi_actmon_cfg_t cfg;
  int32_t track_err_rad_q16; /* filter state */
  int32_t track_exp_rad_q16; /* expected angle (valid with track_exp_valid) */
  int32_t uac_V_q16;         /* filter state */
  canfdi_actmon_diag_t diag;
  bool track_exp_valid;
  bool initialised;
} canfdi_actmon_t;

/*
 * Defaults of the product (the plants of docs/design.md):
 *   tracking: alpha 1/500 per step (~0.5 s), threshold 0.05 rad, expected
 *     slew 6 mrad per 1 ms step (6 rad/s, 41 % of the 14.6 rad/s a healthy
 *     valve reaches on a 9 V supply): any stroke of a healthy valve lags
 *     by nothing, a valve held 10 deg away from a steady reference crosses
 *     0.05 rad after ~0.17 s, one stuck at the start of a 70 deg stroke
 *     after ~0.1 s more than at a steady reference;
 *   open circuit: 3 V applied, below 0.05 A (the motor's 1.5 Ohm draws 2 A);
 *   UAC: alpha 1/8 per step (~8 ms), threshold 0.5 V (~40 sigma of the
 *     filtered 50 mV sensor noise, a quarter of the catalogue's default
 *     2 V U_A offset), headroom 2 V below the supply.
 * Cannot fail for non-NULL.
 */
void canfdi_actmon_default_cfg(canfdi_actmon_cfg_t *cfg);

/* Validates cfg (domains above) and zeroes the filters and counters.
 * Returns CANFDI_OK or -CANFDI_EINVAL (m unusable then). Cost: O(1). */
int32_t canfdi_actmon_init(canfdi_actmon_t *m, const canfdi_actmon_cfg_t *cfg);

/* One step (see the table). Writes *out completely. Returns CANFDI_OK or
 * -CANFDI_EINVAL for a NULL argument or an unusable instance (then *out, if
 * non-NULL, reports no symptom and nothing judged). Cost: see the header. */
int32_t canfdi_actmon_step(canfdi_actmon_t *m, const canfdi_actmon_in_t *in,
                           canfdi_actmon_out_t *out);

/* Diagnostics snapshot (zeros for NULL). Cost: O(1). */
canfdi_actmon_diag_t canfdi_actmon_diag(const canfdi_actmon_t *m);

#endif /* CANFDI_ACTMON_H */
