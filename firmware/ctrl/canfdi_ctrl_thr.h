/*
 * canfdi_ctrl_thr.h — position control of the electronic throttle valve:
 * angle setpoint and measured (voted) angle in, motor voltage command out.
 *
 * Control law, per 1 ms step:
 *   r   = clamp(theta*, angle_min, angle_max) -> rate limit (optional)
 *         + excitation
 *   e   = r - theta
 *   u   = PID(r, theta) + (R/K) (T_spring(r) + T_fric(e)) [+ u_vel while
 *         the rate limiter ramps], limited to +-min(supply, u_max)
 *   T_spring(r) = k_s (r - theta_LH) + P sat((r - theta_LH) / band)
 *   T_fric(e)   = T_c sign(e) if |e| > deadband, else 0
 *   u_vel       = +-(K + (R/K) B + kd) rate_max
 * The feed-forward is the static torque balance of the valve converted to a
 * voltage through the stalled motor (u = R i, T = K i): the spring with its
 * limp-home pretension P (the sign function is made a linear ramp over
 * +-pretension_band, as the two springs of a real valve meet over a small
 * angle — a hard sign would chatter when the setpoint is at limp-home) and
 * the Coulomb friction in the direction of the commanded motion (the sign
 * of the error); inside the dead band the friction term is 0 so that
 * sensor noise at rest does not toggle +-(R/K) T_c (= +-1.1 V nominal). The
 * PID then only sees the dynamic part and the model errors. spring_comp /
 * friction_comp switch the two terms off (tests, commissioning).
 * Velocity feed-forward (velocity_ff, only while a rate-limited setpoint
 * ramps): the back-EMF K w*, the viscous torque (R/K) B w*, and kd w*,
 * which turns the derivative on the measurement into a derivative on the
 * error for the ramp (otherwise -kd w alone asks for 25 V against a
 * 10 rad/s ramp and the valve lags ~4.3 deg; with it 0.8 deg, measured).
 *
 * PID (canfdi_pi.h): derivative on the measured angle through a first-order
 * filter (no setpoint kick), conditional-integration anti-windup, and an
 * integration band: the integrator runs only within +-i_band of the target,
 * so a stroke (which saturates the output for tens of ms) cannot wind it
 * up and it only removes the residual error of the compensation (friction
 * spread, spring error) near the target. Keep kp i_band above the residual
 * the integrator has to hold (a few volts), or an integrator left over from
 * one target can hold the valve outside the band of the next.
 *
 * Gain design (defaults, canfdi_ctrl_thr_cal_default). The valve from u to
 * theta is, with L/R = 1 ms neglected, (K/R) / (s (J s + B + K^2/R)):
 * J 0.0021 kg m^2, damping B + K^2/R = 0.107 N m s (tau_m = 19.7 ms).
 * Placing the three closed-loop poles of the PID loop at -w0 (w0 =
 * 120 rad/s): kp = 3 J w0^2 R/K = 356 V/rad, kd = (3 J w0 - B - K^2/R) R/K =
 * 2.55 V s/rad, and ki = J w0^3 R/K = 14.2 kV/(rad s) — reduced to
 * 3 kV/(rad s) with a 1 deg band, because near the target the loop is not
 * linear (Coulomb friction: a high ki turns stick-slip into "hunting") and
 * the integrator only needs to remove the compensation's residual (against
 * the simulator, 3 kV with a 3 deg band takes twice as long to settle to
 * +-0.1 deg, and 6 kV is not better). Derivative filter 2 ms. J and L enter only here (the cal struct carries what the
 * control law uses).
 * Measured against the host_sim valve (tests/unit/test_ctrl_thr.c, sensor
 * noise as in nominal.scn, three seeds): 10 -> 80 deg settles within
 * +-1 deg in 81 ms (overshoot <= 0.03 deg), 80 -> 10 deg in 58 ms, never on
 * a stop; holding at 12 angles from 2 to 87 deg (limp-home included):
 * |mean e| <= 0.04 deg, peak |e| <= 0.053 deg, command noise sd 1.2 V
 * (from the 0.05 deg angle noise through P and the filtered D). Without the
 * spring term the mean |e| 60..260 ms after a step rises from 0.06 to
 * 0.09..0.11 deg; without the friction term the mean |e| when tracking a
 * 1 Hz +-10 deg sine rises from 0.25 to 0.30 deg.
 *
 * Modes (canfdi_ctrl_mode.h): RUN; FREEZE holds the last output and TRACK
 * outputs in.u_track_V_q16, the PID tracks it (bumpless); OFF outputs 0 V
 * (the caller disables the bridge; the spring returns the valve to
 * limp-home) and restarts the PID and the rate limiter from the measured
 * angle.
 *
 * Scaling and overflow. Angles in rad, voltages in V, torques in N m, all
 * Q16.16. The feed-forward torque is a sum of exact Q16.16 x Q16.16
 * products in int64_t (Q32.32), rounded half up to Q16.16 with saturation;
 * R/K and P/band are precomputed in Q16.16 (rounded; init rejects values
 * that do not fit: R/K < 32768, P/band < 32768 N m/rad); so is u_vel
 * (saturating). The voltage is (R/K) x T, one more exact product rounded
 * to Q16.16. Every addition saturates. PID: see canfdi_pi.h.
 *
 * Cost per canfdi_ctrl_thr_step: one canfdi_pi_step_q16 with D, 3 32x32->64
 * multiplies for the feed-forward, compares; no division. Measured executed
 * instructions (arm-none-eabi-gcc 12 -Os, QEMU mps2-an386 -icount, SysTick;
 * default cal, 4000 calls with setpoint and angle uniformly random in
 * 0 .. 1.5 rad, 12 V supply; min / mean / max): RUN Cortex-M4
 * 443 / 484 / 534, Cortex-M0+ code 948 / 1003 / 1106; all four modes at
 * random Cortex-M4 102 / 403 / 580, Cortex-M0+ code 131 / 797 / 1160 (the
 * minimum is OFF). Stack 64 bytes + canfdi_pi_step_q16's 84 (M0+). Code
 * 1974 bytes (M0+). init: two
 * canfdi_div_s32_qn, one 64-bit division and canfdi_pi_init (init time
 * only). Memory: sizeof(canfdi_ctrl_thr_t) = 240 bytes on a 32-bit target,
 * caller-owned; no heap, no globals.
 */
#ifndef CANFDI_CTRL_THR_H
#define CANFDI_CTRL_THR_H

#include "core/canfdi_common.h"
#include "ctrl/canfdi_ctrl_mode.h"
#include "ctrl/canfdi_pi.h"

/* Calibration: nominal valve (shaft-referred), compensation, gains, limits.
 * Q16.16 in SI units unless the name says otherwise. */
typedef struct {
  /* nominal plant (docs/design.md, Bosch DV-E5 class) */
  int32_t r_ohm_q16;                 /* motor circuit resistance R, > 0 */
  int32_t k_Nm_A_q16;                /* motor constant K (= back-EMF V s/rad), > 0 */
  int32_t spring_Nm_rad_q16;         /* return spring k_s, >= 0 */
  int32_t pretension_Nm_q16;         /* spring pretension P at limp-home, >= 0 */
  int32_t friction_Nm_q16;           /* Coulomb friction T_c, >= 0 */
  int32_t b_Nms_q16;                 /* viscous friction B, >= 0 (velocity ff) */
  int32_t limp_home_rad_q16;         /* limp-home angle theta_LH */
  /* compensation */
  int32_t pretension_band_rad_q16;   /* sign() ramp half-width, > 0 */
  int32_t friction_deadband_rad_q16; /* |e| at or below: no friction term, >= 0 */
  bool spring_comp;                  /* feed-forward of T_spring(r) */
  bool friction_comp;                /* feed-forward of T_fric(e) */
  bool velocity_ff;                  /* (K + R B/K + kd) dr/dt while the rate
                                        limiter ramps */
  /* PID */
  int32_t kp_V_rad_q16;              /* V per rad */
  int32_t ki_V_rad_s_q16;            /* V per (rad s) */
  int32_t kd_V_s_rad_q16;            /* V per rad/s */
  uint32_t kd_tau_us;                /* derivative filter time constant */
  int32_t i_band_rad_q16;            /* integrate within +-band; 0 = always */
  /* limits */
  int32_t angle_min_rad_q16;         /* setpoint range (inside the stops) */
  int32_t angle_max_rad_q16;
  int32_t u_max_V_q16;               /* voltage limit besides the supply, > 0 */
  int32_t rate_max_rad_s_q16;        /* setpoint rate limit; 0 = none */
} canfdi_ctrl_thr_cal_t;

typedef struct {
  int32_t angle_ref_rad_q16;   /* setpoint theta* */
  int32_t excite_rad_q16;      /* added after clamp and rate limit */
  int32_t angle_rad_q16;       /* measured (voted) angle */
  int32_t supply_V_q16;        /* validated bridge supply */
  int32_t u_track_V_q16;       /* applied voltage in TRACK mode */
  uint8_t mode;                /* CANFDI_CTRL_* */
} canfdi_ctrl_thr_in_t;

typedef struct {
  int32_t u_V_q16;             /* motor voltage command */
  int32_t u_ff_V_q16;          /* its feed-forward part */
  int32_t angle_ref_rad_q16;   /* reference used (limited + excitation) */
  int32_t u_limit_V_q16;       /* voltage limit of this step */
  int32_t u_sat;               /* +1/-1: limited high/low this step, else 0 */
} canfdi_ctrl_thr_out_t;

/* Diagnostics counters: monotone, saturating at UINT32_MAX
 * (core/canfdi_count.h); init clears them, nothing else does. No decision
 * of the firmware depends on them. The PID keeps its own
 * (canfdi_ctrl_thr_pi_diag). */
typedef struct {
  uint32_t steps;        /* canfdi_ctrl_thr_step calls */
  uint32_t ref_clamped;  /* setpoints outside [angle_min, angle_max] */
  uint32_t rate_limited; /* steps whose setpoint was rate limited */
  uint32_t u_limited;    /* steps whose output was limited */
  uint32_t held_steps;   /* FREEZE or TRACK steps */
  uint32_t off_steps;    /* OFF steps */
} canfdi_ctrl_thr_diag_t;

typedef struct {
  canfdi_ctrl_thr_cal_t cal;
  int32_t r_over_k_q16;     /* R / K, V per N m */
  int32_t pre_slope_q16;    /* P / band, N m per rad */
  int32_t dref_max_q16;     /* rate_max T, rad per step */
  int32_t u_vel_q16;        /* (K + R B/K + kd) rate_max, V (velocity ff) */
  int32_t ref_lim_q16;      /* limited setpoint */
  bool ref_primed;          /* ref_lim holds a value (first step: no ramp) */
  canfdi_ctrl_thr_out_t out;
  canfdi_pi_t pid;
  canfdi_ctrl_thr_diag_t diag;
} canfdi_ctrl_thr_t;

/*
 * The nominal calibration: the valve of docs/design.md (K 0.383, R 1.5,
 * B 0.0088, spring 0.087, pretension 0.396, friction 0.284, limp-home
 * 6.5 deg; J 0.0021 and L 1.5 mH enter through the gains, see above),
 * pretension band 0.1 deg, friction dead band 0.2 deg, both compensations
 * and the velocity feed-forward on, the gains above, i_band 1 deg, setpoint
 * range 0.5..88 deg, u_max 16 V, no rate limit (fastest strokes; the
 * velocity feed-forward acts only once a rate is set). Cannot fail by
 * contract.
 */
void canfdi_ctrl_thr_cal_default(canfdi_ctrl_thr_cal_t *cal);

/*
 * Validates cal and starts: PID at 0, the setpoint limiter primed by the
 * first step (it starts at the measured angle). Returns CANFDI_OK or
 * -CANFDI_EINVAL (c untouched) for NULL, non-positive R, K, u_max or
 * pretension band, negative spring, pretension, friction, B, dead band or
 * rate, angle_min > angle_max, R/K or P/band not representable, or gains
 * canfdi_pi_init rejects. Cost: init time only.
 */
int32_t canfdi_ctrl_thr_init(canfdi_ctrl_thr_t *c, const canfdi_ctrl_thr_cal_t *cal);

/*
 * One 1 ms step; fills *out (may be NULL) and returns the voltage command
 * (Q16.16 V). An unknown mode counts as OFF. Cannot fail by contract.
 */
int32_t canfdi_ctrl_thr_step(canfdi_ctrl_thr_t *c, const canfdi_ctrl_thr_in_t *in,
                             canfdi_ctrl_thr_out_t *out);

/* The static feed-forward voltage (R/K) (T_spring(r) + T_fric(e)) for a
 * reference r and an error e, as the step computes it (tests, diagnosis:
 * the expected holding voltage). Cannot fail by contract. */
int32_t canfdi_ctrl_thr_ff_q16(const canfdi_ctrl_thr_t *c, int32_t ref_rad_q16, int32_t err_rad_q16);

/* The diagnostics counters (pointer into *c). */
const canfdi_ctrl_thr_diag_t *canfdi_ctrl_thr_diag(const canfdi_ctrl_thr_t *c);

/* The counters of the PID. */
const canfdi_pi_diag_t *canfdi_ctrl_thr_pi_diag(const canfdi_ctrl_thr_t *c);

#endif /* CANFDI_CTRL_THR_H */
