/*
 * canfdi_pi.h — discrete PI(D) controller in fixed point with output limits,
 * anti-windup by conditional integration, bumpless tracking of the applied
 * output, an integration band and a filtered derivative on the measurement.
 *
 * Control law, per step k (T = CANFDI_CFG_STEP_US):
 *   e_k  = r_k - y_k
 *   P_k  = kp e_k
 *   I_k  = I_(k-1) + ki T e_k         (backward Euler: the current error
 *                                      acts at once; see "Anti-windup")
 *   D_k  = a D_(k-1) - c (y_k - y_(k-1)),  a = tau / (tau + T),
 *                                          c = kd / (tau + T)
 *   u_k  = sat(ff_k + P_k + I_k + D_k)   limited to [out_min, out_max]
 * D is the backward-difference derivative of -y through a first-order
 * low-pass of time constant tau (kd s / (tau s + 1) discretised by backward
 * Euler): on the measurement only, so a setpoint step gives no derivative
 * kick, and the filter bounds the gain on sensor noise to kd / (tau + T)
 * per unit step of y. kd = 0 makes it a PI (D stays 0, tau is ignored).
 * ff is a feed-forward added before the limiter, so the limiter and the
 * anti-windup see the whole output.
 *
 * Anti-windup (cfg.anti_windup):
 *   CANFDI_PI_AW_CLAMP (the default, conditional integration): the increment
 *     ki T e_k is rejected when the output with it would exceed a limit and
 *     the increment points further beyond that limit, or when the caller
 *     holds that direction (hold, below). Then I is limited to
 *     [min(out_min - ff, 0), max(out_max - ff, 0)], so that I alone
 *     (P = D = 0) can never ask for more than the limits on top of ff; this
 *     also bleeds I off when the limits shrink (a sagging supply). Zero is
 *     kept inside the range: a feed-forward that saturates the output by
 *     itself (e.g. a velocity feed-forward during a ramp) must not drag I
 *     to the opposite sign, which would be windup once ff drops.
 *     Chosen over back-calculation because it needs no extra tuning
 *     parameter (the tracking time constant), has no rounding-sensitive
 *     feedback path in fixed point, and reacts within the step; the
 *     deep-saturation case back-calculation is good at is covered by the
 *     integrator limit and by tracking.
 *   CANFDI_PI_AW_NONE: increments are never rejected and I is not limited
 *     (only the 64-bit accumulator saturates). For comparisons in tests;
 *     not for products.
 * Holding (canfdi_pi_step_q16 argument hold): CANFDI_PI_HOLD_UP rejects
 *   positive increments, CANFDI_PI_HOLD_DOWN negative ones. A cascade uses it
 *   to stop the outer integrator while the inner loop is saturated in the
 *   direction the outer loop pushes (the outer output alone is not limited).
 * Integration band (cfg.i_band_q16 > 0): the error is integrated only while
 *   |e| <= band. A position loop uses it so that large moves are driven by
 *   P and D alone and I only removes the residual (friction) error near the
 *   target; 0 disables the band.
 * Tracking (canfdi_pi_track_q16): when the output that reached the plant
 *   differs from the computed one (the actuator manager froze it, switched
 *   bridges or drives a substitute), the caller reports the applied value and
 *   I is set so that ff + P + I + D of the last step equals it; the next step
 *   then continues from the applied output instead of jumping (bumpless
 *   transfer). In CLAMP mode the next step limits I as above.
 *
 * Scaling and overflow. Reference, measurement, feed-forward, limits and
 * output are Q16.16 (int32_t) in the units of the loop (e.g. rad/s in, A
 * out). Gains are given in physical units in Q16.16: kp [out/in], ki
 * [out/(in s)], kd [out s/in]; init converts them:
 *   ki T    -> Q8.24 int32 (rounded; ki T < 128 per step, always true
 *              for steps up to 3.9 ms because ki < 32768 /s in Q16.16;
 *              the relative error of the conversion is < 2^-25 / (ki T),
 *              i.e. < 1 % for ki T >= 3e-6),
 *   a       -> Q31 (rounded; 0 <= a < 1),
 *   c       -> Q16.16 (rounded; must fit: kd / (tau + T) < 32768).
 * The terms P, I, D and their sum are int64_t with 32 fraction bits
 * (Q31.32): kp e and c dy are exact Q16.16 x Q16.16 products
 * (|.| <= 2^62, e and dy saturated to int32 first), ki T e is a Q8.24 x
 * Q16.16 = Q.40 product rounded half up to Q.32, a D is canfdi_mul_s64_q31
 * (rounded half up). Every 64-bit addition saturates (canfdi_add_s64_sat);
 * that is unreachable for outputs in the Q16.16 range. The sum is rounded
 * half up to Q16.16 and then limited; a limited output counts in
 * diag.sat_hi / sat_lo. The integrator keeps 32 fraction bits (2^-16 of an
 * output LSB), so a 1-LSB error still integrates for ki T >= 2^-17
 * (ki >= 0.008 /s at 1 ms); below that the increment rounds to 0.
 *
 * Cost of canfdi_pi_step_q16: straight-line code with 2 (PI) or 5 (PID)
 * 32x32->64 multiplies (__aeabi_lmul on M0+) and ~8 saturating 64-bit
 * additions; no division. Measured executed instructions (arm-none-eabi-gcc
 * 12 -Os, QEMU mps2-an386 -icount, SysTick; 4000 calls each with reference
 * and measurement uniformly random in +-20 and feed-forward in +-1, limits
 * +-10, kp 1, ki 100 /s (PID: kd 0.01 s, filter 2 ms, band 1); min / mean
 * / max incl. call overhead; the M0+ code runs on the emulated M4, so these
 * are instruction counts, not cycles):
 *                      Cortex-M4          Cortex-M0+
 *   PI  (kd = 0)       266 / 283 / 301    613 / 718 / 771
 *   PID (kd, band)     288 / 314 / 362    760 / 861 / 986
 * Stack 72 bytes (+12 for canfdi_add_s64_sat), -fstack-usage, M0+.
 * canfdi_pi_init does up to four 64-bit divisions (not for the 1 ms path).
 * Code 1586 bytes (M0+, -Os). Memory: sizeof(canfdi_pi_t) = 96 bytes on a
 * 32-bit target (int64 alignment), caller-owned; no heap, no globals,
 * reentrant per instance.
 */
#ifndef CANFDI_PI_H
#define CANFDI_PI_H

#include "core/canfdi_common.h"

/* Anti-windup method (canfdi_pi_cfg_t.anti_windup). */
#define CANFDI_PI_AW_CLAMP 0U /* conditional integration + integrator limit */
#define CANFDI_PI_AW_NONE 1U  /* none: comparisons only */

/* Hold directions (canfdi_pi_step_q16 argument hold), may be OR-ed. */
#define CANFDI_PI_HOLD_NONE 0U
#define CANFDI_PI_HOLD_UP 1U   /* reject positive integrator increments */
#define CANFDI_PI_HOLD_DOWN 2U /* reject negative integrator increments */

typedef struct {
  int32_t kp_q16;      /* proportional gain, out per in */
  int32_t ki_q16;      /* integral gain, out per (in s); 0 = no integral */
  int32_t kd_q16;      /* derivative gain, out s per in; 0 = PI */
  uint32_t kd_tau_us;  /* derivative low-pass time constant (0 = none) */
  int32_t i_band_q16;  /* integrate only while |e| <= band; 0 = always */
  int32_t out_min_q16; /* initial output limits (canfdi_pi_set_limits) */
  int32_t out_max_q16;
  uint8_t anti_windup; /* CANFDI_PI_AW_* */
} canfdi_pi_cfg_t;

/* Diagnostics counters: monotone, saturating at UINT32_MAX
 * (core/canfdi_count.h); init clears them, nothing else does. No decision
 * of the firmware depends on them. */
typedef struct {
  uint32_t steps;     /* canfdi_pi_step_q16 calls */
  uint32_t sat_hi;    /* steps whose output was limited to out_max */
  uint32_t sat_lo;    /* steps whose output was limited to out_min */
  uint32_t int_holds; /* increments rejected (anti-windup or hold) */
  uint32_t tracks;    /* canfdi_pi_track_q16 calls */
  uint32_t resets;    /* canfdi_pi_reset_q16 calls (init counts as none) */
} canfdi_pi_diag_t;

typedef struct {
  /* converted configuration */
  int32_t kp_q16;
  int32_t kit_q24;     /* ki T per step, Q8.24 */
  int32_t da_q31;      /* derivative filter pole a */
  int32_t dc_q16;      /* kd / (tau + T) */
  int32_t i_band_q16;
  int32_t out_min_q16;
  int32_t out_max_q16;
  uint8_t anti_windup;
  bool primed;         /* y_prev holds a real measurement */
  /* state */
  int32_t y_prev_q16;  /* measurement of the last step */
  int32_t out_q16;     /* output of the last step (limited) */
  int8_t sat;          /* -1, 0, +1: last output limited low / not / high */
  int64_t i_q32;       /* integrator I, Q31.32 */
  int64_t d_q32;       /* derivative term D, Q31.32 */
  int64_t pdf_q32;     /* ff + P + D of the last step (for tracking) */
  canfdi_pi_diag_t diag;
} canfdi_pi_t;

/*
 * Validates cfg, converts the gains and resets the controller: I = D = 0,
 * output 0, no previous measurement (the first step takes no derivative).
 * Returns CANFDI_OK, or -CANFDI_EINVAL (pi and cfg untouched otherwise) for
 * a NULL pointer, out_min > out_max, i_band < 0, an unknown anti_windup,
 * kd < 0, or a gain whose converted form does not fit (|ki T| >= 128,
 * kd / (tau + T) >= 32768, kd_tau_us > 2^31 - 1).
 * Gains may be negative (a loop with a negative plant gain) except kd.
 * Cost: two 64-bit divisions; init time only.
 */
int32_t canfdi_pi_init(canfdi_pi_t *pi, const canfdi_pi_cfg_t *cfg);

/*
 * Changes the output limits from the next step on (e.g. +-supply voltage
 * every step). The integrator is not touched here; in CLAMP mode the next
 * step limits it. Returns CANFDI_OK or -CANFDI_EINVAL (limits unchanged)
 * if lo > hi. Cost: two compares.
 */
int32_t canfdi_pi_set_limits_q16(canfdi_pi_t *pi, int32_t lo_q16, int32_t hi_q16);

/*
 * One step: reference r, measurement y, feed-forward ff (all Q16.16), hold
 * as CANFDI_PI_HOLD_*; returns the limited output u (Q16.16), also kept for
 * canfdi_pi_out_q16. Cannot fail by contract (pi from a successful init).
 * Cost: see the header comment.
 */
int32_t canfdi_pi_step_q16(canfdi_pi_t *pi, int32_t ref_q16, int32_t meas_q16, int32_t ff_q16,
                           uint32_t hold);

/*
 * Bumpless tracking: the plant received u_applied (Q16.16) instead of the
 * last output. Sets I = u_applied - (ff + P + D of the last step) (the next
 * step limits it in CLAMP mode as described above) and makes u_applied the
 * last output.
 * Call it after canfdi_pi_step_q16 of the same step. Cannot fail by
 * contract. Cost: a few 64-bit adds.
 */
void canfdi_pi_track_q16(canfdi_pi_t *pi, int32_t u_applied_q16);

/*
 * Restart: I = u0, D = 0, last output u0, previous measurement y0 (so the
 * next step sees no derivative kick). With r = y0 and ff = 0 the next output
 * is u0. Cannot fail by contract. Cost: a few stores.
 */
void canfdi_pi_reset_q16(canfdi_pi_t *pi, int32_t u0_q16, int32_t meas0_q16);

/* Output of the last step (or the value set by track/reset), Q16.16. */
int32_t canfdi_pi_out_q16(const canfdi_pi_t *pi);

/* The integrator I rounded half up to Q16.16 and saturated. */
int32_t canfdi_pi_integral_q16(const canfdi_pi_t *pi);

/* Saturation of the last step: +1 limited to out_max, -1 to out_min, 0 not
 * limited. */
int32_t canfdi_pi_saturation(const canfdi_pi_t *pi);

/* The diagnostics counters (pointer into *pi). */
const canfdi_pi_diag_t *canfdi_pi_diag(const canfdi_pi_t *pi);

#endif /* CANFDI_PI_H */
