/*
 * canfdi_ctrl_dcm.h — speed control of the DC motor drive: setpoint w*,
 * validated w and I_A, supply voltage in; armature voltage command U_A out.
 *
 * Structure (a cascade; decided for this plant, see "Why a current loop"):
 *
 *   w* -> clamp +-speed_max -> rate limit (accel_max) -> + excitation = r
 *   speed PI:   i_ref = PI_w(r - w) + i_acc,  limited to +-ia_max        [A]
 *   current PI: U_A   = PI_i(i_ref - I_A) + R_nom i_ref + Psi_nom w,
 *               limited to +-min(supply, u_max)                          [V]
 *
 * The feed-forward R_nom i_ref + Psi_nom w is the inverse of the armature
 * equation at steady state (decoupling of the back-EMF), so the current PI
 * only corrects model errors (warm R_A, L dI/dt) and the speed PI sees an
 * almost pure torque actuator Psi i_ref. i_acc = +-J_nom accel_max / Psi_nom
 * while the rate limiter ramps (0 otherwise) is the current the ramp's
 * acceleration needs, so the ramp needs no integrator action: without it
 * the PI lags the ramp, its integrator charges and a 0 -> 100 rad/s step
 * overshoots by 8.6 % (measured; 0.7 % with it).
 * The rate limiter restarts from the measured speed when that lies between
 * the limited setpoint and the new setpoint: after the drive could not
 * follow (a setpoint beyond its reach, an overload), the limited setpoint
 * does not first ramp back through speeds the motor never reached.
 * Excitation (canfdi_excite) enters after the limiter, unfiltered.
 *
 * Why a current loop. With the motor of docs/design.md the electrical time
 * constant L/R = 6.82 mH / 1.52 Ohm = 4.5 ms is 4.5 steps at 1 ms, so a
 * current loop of ~500 rad/s bandwidth (time constant 2 ms, phase lost to
 * the sample-and-hold 500 rad/s x 0.5 ms = 14 deg) is feasible. It buys
 * (a) a current limit: a voltage-mode speed loop drives 48 V into the
 * standing motor on a speed step, i.e. 48 / 1.52 = 32 A, beyond the 30 A
 * span of the current sensor (an out-of-range symptom) and hard on the
 * bridges; here |I_A| stays within 2 % of ia_max (20 A by default); (b) a
 * speed loop whose plant is Psi / (J s) independent of R_A warm-up.
 * Fallback: if I_A is not valid (in.ia_valid false, e.g. the current sensor
 * is faulty) or cal.current_loop is false, the current PI is bypassed and
 * U_A = R_nom i_ref + Psi_nom w + (the current integrator, held at its last
 * value: it holds the learned R_A error). The speed loop keeps running
 * unchanged; the current limit then holds only as well as R_nom is right.
 *
 * Gain design (defaults in canfdi_ctrl_dcm_cal_default, Isermann's motor):
 *   current PI: kp = L w_ci, ki = R w_ci with w_ci = 500 rad/s (pole-zero
 *     cancellation of L/R): kp 3.41 V/A, ki 760 V/(A s);
 *   speed PI:   kp = J w_cw / Psi with w_cw = 100 rad/s (5x below w_ci),
 *     integral zero at w_cw / 4: kp 0.58 A/(rad/s), ki 14.5 A/rad.
 * Measured against the host_sim motor (tests/unit/test_ctrl_dcm.c, three
 * noise seeds, nominal load 1.2 N m, warm R_A): 0 -> 100 rad/s within 2 %
 * in 58 ms with 1.0..1.2 rad/s overshoot and 18 A peak (the 2000 rad/s^2
 * ramp takes 50 ms); without rate limit 90 ms, 2.4 rad/s, 20.4 A; a +0.5 N m
 * load step dips 1.9 rad/s and is back within 1 % after 50..54 ms; at
 * 100 rad/s the shaft speed has 0.05 rad/s sd (sensor noise 0.2 rad/s).
 *
 * Anti-windup: both PIs use conditional integration (canfdi_pi.h); in
 * addition the speed PI is held in the direction in which the voltage was
 * limited in the previous step (a voltage-limited current loop cannot
 * deliver more current, so the speed integrator must not ask for it). The
 * one-step delay of that hold is the price of computing the loops in
 * cascade order. After 1 s at an unreachable 200 rad/s, a setpoint of 100
 * is reached within 2 % in 38 ms; with cal.anti_windup = CANFDI_PI_AW_NONE
 * the speed is still 26 rad/s high after 1 s (measured).
 *
 * Modes (canfdi_ctrl_mode.h): RUN; FREEZE holds the last U_A and TRACK
 * outputs in.u_track_V_q16 — in both the current PI tracks the applied
 * voltage, the speed PI tracks the measured current (the model current
 * (U_A - Psi w - I_cur) / R_nom without a valid I_A), and the rate limiter
 * restarts from the measured speed, so RUN resumes without a jump; OFF
 * outputs 0 V and restarts both loops and the limiter from the measured
 * state (re-enabling picks a coasting motor up without a current kick).
 *
 * Scaling and overflow. Every signal is Q16.16 in SI units. The feed-forward
 * R i_ref + Psi w is formed of two exact Q16.16 x Q16.16 products in
 * int64_t (Q32.32), added and rounded half up to Q16.16 with saturation.
 * The rate limiter step accel_max T and i_acc = J accel_max / Psi (J in
 * Q0.31, a Q.47 product divided by Psi) are precomputed by init in Q16.16,
 * rounded; the limited setpoint moves by exactly that per step. 1/R_nom is
 * precomputed in Q16.16 (canfdi_div_s32_qn). The limits are formed with
 * 32-bit saturating arithmetic. The PIs: see canfdi_pi.h.
 *
 * Cost per canfdi_ctrl_dcm_step: two canfdi_pi_step_q16 (both PI, no D),
 * 2 32x32->64 multiplies for the feed-forward, compares; no division.
 * Measured executed instructions (arm-none-eabi-gcc 12 -Os, QEMU
 * mps2-an386 -icount, SysTick; default cal, 4000 calls with setpoint and
 * speed uniformly random in +-200 rad/s, I_A in +-20 A, 48 V supply; min /
 * mean / max, the M0+ code run on the emulated M4 as instruction counts):
 *                                  Cortex-M4          Cortex-M0+
 *   RUN with the current loop      628 / 683 / 734    1135 / 1212 / 1281
 *   all modes at random, no I_A    140 / 450 / 631     176 /  818 / 1172
 * Stack 88 bytes + canfdi_pi_step_q16's 84 (M0+, -fstack-usage); init uses
 * 296. Code 2000 bytes (M0+). canfdi_ctrl_dcm_init: two canfdi_pi_init and
 * three divisions (init time only). Memory: sizeof(canfdi_ctrl_dcm_t) =
 * 312 bytes on a 32-bit target, caller-owned; no heap, no globals.
 */
#ifndef CANFDI_CTRL_DCM_H
#define CANFDI_CTRL_DCM_H

#include "core/canfdi_common.h"
#include "ctrl/canfdi_ctrl_mode.h"
#include "ctrl/canfdi_pi.h"

/* Calibration: nominal plant, gains, limits (all Q16.16, SI units). */
typedef struct {
  int32_t ra_ohm_q16;               /* nominal R_A (feed-forward), > 0 */
  int32_t psi_Vs_q16;               /* nominal flux linkage Psi, > 0 */
  int32_t j_kgm2_q31;               /* nominal inertia (Q0.31), acceleration
                                       feed-forward; 0 = none */
  int32_t speed_kp_A_s_rad_q16;     /* speed PI: A per rad/s */
  int32_t speed_ki_A_rad_q16;       /* speed PI: A per rad */
  int32_t cur_kp_V_A_q16;           /* current PI: V per A */
  int32_t cur_ki_V_As_q16;          /* current PI: V per (A s) */
  int32_t ia_max_A_q16;             /* current limit (speed PI output), > 0 */
  int32_t u_max_V_q16;              /* voltage limit besides the supply, > 0 */
  int32_t speed_max_rad_s_q16;      /* setpoint limit, > 0 */
  int32_t accel_max_rad_s2_q16;     /* setpoint rate limit; 0 = none */
  bool current_loop;                /* false: always the model-based inner path */
  uint8_t anti_windup;              /* CANFDI_PI_AW_CLAMP; AW_NONE (comparisons
                                       only) also drops the cascade hold */
} canfdi_ctrl_dcm_cal_t;

typedef struct {
  int32_t speed_ref_rad_s_q16; /* setpoint w* */
  int32_t excite_rad_s_q16;    /* added after the rate limiter (canfdi_excite) */
  int32_t speed_rad_s_q16;     /* validated measured w */
  int32_t ia_A_q16;            /* validated armature current */
  int32_t supply_V_q16;        /* validated bridge supply (limit +-supply) */
  int32_t u_track_V_q16;       /* applied U_A in TRACK mode */
  bool ia_valid;               /* false: current PI bypassed (see above) */
  uint8_t mode;                /* CANFDI_CTRL_* */
} canfdi_ctrl_dcm_in_t;

typedef struct {
  int32_t ua_V_q16;            /* armature voltage command */
  int32_t ia_ref_A_q16;        /* current reference of the speed loop */
  int32_t speed_ref_rad_s_q16; /* reference the speed PI used (limited + excitation) */
  int32_t u_limit_V_q16;       /* the voltage limit of this step */
  int32_t u_sat;               /* +1/-1: U_A limited high/low this step, else 0 */
} canfdi_ctrl_dcm_out_t;

/* Diagnostics counters: monotone, saturating at UINT32_MAX
 * (core/canfdi_count.h); init clears them, nothing else does. No decision
 * of the firmware depends on them. The PIs keep their own
 * (canfdi_ctrl_dcm_pi_diag). */
typedef struct {
  uint32_t steps;           /* canfdi_ctrl_dcm_step calls */
  uint32_t rate_limited;    /* steps whose setpoint was rate limited */
  uint32_t ref_clamped;     /* steps whose setpoint exceeded speed_max */
  uint32_t u_limited;       /* steps whose U_A was limited */
  uint32_t ia_limited;      /* steps whose current reference was limited */
  uint32_t model_steps;     /* RUN steps on the model-based inner path */
  uint32_t held_steps;      /* FREEZE or TRACK steps */
  uint32_t off_steps;       /* OFF steps */
} canfdi_ctrl_dcm_diag_t;

typedef struct {
  canfdi_ctrl_dcm_cal_t cal;
  int32_t dref_max_q16;     /* accel_max T, rad/s per step */
  int32_t ref_lim_q16;      /* rate-limited setpoint */
  int32_t inv_r_q16;        /* 1 / R_nom, 1/Ohm (model current when tracking) */
  int32_t i_acc_q16;        /* J accel_max / Psi, A (acceleration feed-forward) */
  canfdi_ctrl_dcm_out_t out;
  canfdi_pi_t speed_pi;
  canfdi_pi_t cur_pi;
  canfdi_ctrl_dcm_diag_t diag;
} canfdi_ctrl_dcm_t;

/*
 * The nominal calibration for the motor of docs/design.md (R_A 1.52 Ohm warm,
 * Psi 0.33 V s, L_A 6.82 mH, J 1.92e-3 kg m^2) with the gains derived in
 * the header comment, ia_max 20 A, u_max 48 V, speed_max 350 rad/s,
 * accel_max 2000 rad/s^2 (the drive's reach at ia_max under nominal load is
 * ~2700 rad/s^2), current loop on. Cannot fail by contract.
 */
void canfdi_ctrl_dcm_cal_default(canfdi_ctrl_dcm_cal_t *cal);

/*
 * Validates cal and starts at rest (setpoint 0, loops at 0).
 * Returns CANFDI_OK or -CANFDI_EINVAL (c untouched) for NULL pointers,
 * non-positive R_A, Psi, ia_max, u_max or speed_max, a negative accel_max,
 * or gains canfdi_pi_init rejects. Cost: init time only.
 */
int32_t canfdi_ctrl_dcm_init(canfdi_ctrl_dcm_t *c, const canfdi_ctrl_dcm_cal_t *cal);

/*
 * One 1 ms step; fills *out (may be NULL) and returns U_A (Q16.16 V).
 * An unknown mode is treated as OFF (the safe side). A negative supply
 * counts as 0 V. Cannot fail by contract. Cost: see the header comment.
 */
int32_t canfdi_ctrl_dcm_step(canfdi_ctrl_dcm_t *c, const canfdi_ctrl_dcm_in_t *in,
                             canfdi_ctrl_dcm_out_t *out);

/* The diagnostics counters (pointer into *c). */
const canfdi_ctrl_dcm_diag_t *canfdi_ctrl_dcm_diag(const canfdi_ctrl_dcm_t *c);

/* The counters of the speed PI (outer == true) or of the current PI. */
const canfdi_pi_diag_t *canfdi_ctrl_dcm_pi_diag(const canfdi_ctrl_dcm_t *c, bool outer);

#endif /* CANFDI_CTRL_DCM_H */
