/*
 * canfdi_svf.h — state-variable filter (SVF): a low-pass filter whose states
 * are the filtered signal and its first and second time derivatives.
 *
 * Why. Parameter estimation and parity equations need dI/dt, dw/dt and
 * d2theta/dt2 of noisy sampled signals. Isermann (Fault-Diagnosis Systems,
 * ch. 9/10 and appendix) obtains them from state-variable filters and
 * filters every signal of one equation with the same filter: the filter is
 * linear and time-invariant, so the filtered signals satisfy the same
 * differential equation as the raw ones and the equation stays valid.
 *
 * Continuous-time model. A chain of n integrators (n = 2 or 3) closed to the
 * characteristic polynomial (s / wc + 1)^n — the binomial (critically damped)
 * filter: no overshoot, so a step never produces a derivative of the wrong
 * sign, at the price of a less sharp cut-off than a Butterworth filter.
 *   G(s) = Y(s) / U(s) = 1 / (s / wc + 1)^n,  dy = s G u,  d2y = s^2 G u.
 * Internally the states are normalised, v_i = y^(i-1) / wc^(i-1), so that all
 * of them carry the size of the signal itself:
 *   v_i' = wc v_(i+1)                                  (i < n)
 *   v_n' = wc (u - v_1 - 2 v_2)                        (n = 2)
 *   v_n' = wc (u - v_1 - 3 v_2 - 3 v_3)                (n = 3)
 *
 * Discretisation: the trapezoidal rule (Tustin / bilinear transform) applied
 * to the integrator chain, with T = CANFDI_CFG_STEP_US and h = wc T / 2:
 *   v(k+1) = v(k) + h (f(k) + f(k+1)),   f = M v + b u   (the model above)
 * solved for the increment: dv = G w with
 *   G = h (I - h M)^-1,   w = 2 M v(k) + b (u(k) + u(k+1)).
 * M holds small integers, so w costs only shifts and adds. Only the last
 * row of G is applied: it gives dv_n, and the first n - 1 rows of
 * (I - h M) dv = h w, dv_i - h dv_(i+1) = h w_i, give the others by back
 * substitution, dv_i = h (w_i + dv_(i+1)): 2n - 1 products instead of n^2,
 * the same increment in exact arithmetic. That row and h are precomputed
 * by init in integer arithmetic from the exact rational h (no float, not
 * even at init). Consequences, all tested:
 *   - DC gain exactly 1 (a constant input gives y = u, dy = d2y = 0 in
 *     steady state, independent of the rounding of G);
 *   - a ramp of slope a gives dy -> a exactly (up to the rounding of G,
 *     ~1e-8 relative) and y -> u - n a / wc, the continuous lag;
 *   - a sinusoid of frequency w sees exactly the continuous response at the
 *     warped frequency w_a = (2 / T) tan(w T / 2), i.e. G(j w_a),
 *     s G(j w_a), (s^2 G)(j w_a) with s = j w_a;
 *   - the output includes the current sample (the rule is implicit in u):
 *     y(k+1) depends on u(k+1). No extra delay.
 * For n = 2 the second derivative is not a state: d2y is the model's
 * f_2(k+1) * wc = wc^2 (u - v_1 - 2 v_2), which passes some of the raw input
 * (high-pass, like any 2nd derivative of a 2nd-order filter). Use n = 3 when
 * d2y matters (e.g. the throttle's mechanical equation).
 *
 * Choosing wc. Place it above the plant's useful bandwidth and well below the
 * sampling rate; a typical value is 50..500 rad/s at 1 ms. The derivatives
 * amplify white measurement noise by ~wc (dy) and ~wc^2 (d2y).
 *
 * Scaling and overflow. Input and outputs are Q16.16 (int32_t) in the
 * signal's unit, unit/s and unit/s^2. The normalised states are int64_t with
 * 32 fraction bits (Q31.32): the input enters exactly (a Q16.16 value shifted
 * by 16), and rounding errors of the state update stay ~2^-33 per step, far
 * below the Q16.16 output LSB. G's last row and h are Q31 (|G_nj| < 1
 * because h <= 1; h = 1, wc T = 2, is held as 1 - 2^-31), applied with
 * a rounded 64 x Q31 product (round half up). State additions saturate
 * (canfdi_add_s64_sat) — unreachable for inputs in Q16.16 range, because
 * |v_i| stays within a few times the input range. The outputs are rounded
 * half up to Q16.16 and saturate to INT32_MIN/MAX (e.g. d2y of a step of a
 * large signal at a high wc); each saturated output increments
 * diag.out_saturations.
 *
 * Domain of the configuration (init returns -CANFDI_EINVAL otherwise):
 *   order 2 or 3; outputs within CANFDI_SVF_OUT_ALL; omega_c_rad_s >= 1 (integer rad/s) with h = wc T / 2 <= 1,
 *   i.e. wc <= 2000 rad/s at T = 1 ms (about 2/3 of the Nyquist frequency
 *   pi / T; near it Tustin's frequency warping dominates);
 *   wc <= 32767; and, with h = p / q reduced to lowest terms,
 *   p + q < 2^20 (true for T = 1 ms or 0.5 ms and any allowed wc; init's
 *   exact integer arithmetic needs (p + q)^3 < 2^60).
 *
 * Cost per canfdi_svf_step (n = order): 2n - 1 rounded products of a
 * 64-bit state difference and a Q31 gain (3 or 5; each a SMULL and a UMULL
 * on ARMv7-M, one call that builds both from 16-bit halves on ARMv6-M),
 * plain 64-bit sums under the state bound of canfdi_svf.c (its clips
 * decided on the high word), and per output computed (cfg.outputs) a
 * rounding with up to two products by wc (none for y, one for dy, two for
 * d2y; on ARMv6-M three 32-bit multiplies each). Measured executed
 * instructions per call in the application (`make bench-pil-profile`,
 * dcm_ia_offset: the eleven order-3 and four order-2 filters with their
 * output sets, wc 100-300): ~190 on the Cortex-M4; on the Cortex-M0 ~210
 * in the step itself and its 3 or 5 products' calls, 52 instructions each
 * (Thumb-1 assembly, core/canfdi_fixp.c).
 * canfdi_svf_init: a gcd (64-bit modulo, a few iterations) and n + 1
 * 31-step long divisions, < 10 k instructions; not for the 1 ms path.
 * Memory: sizeof(canfdi_svf_t) = 80 bytes on a 32-bit target, caller-owned.
 * No heap, no globals, reentrant per instance.
 */
#ifndef CANFDI_SVF_H
#define CANFDI_SVF_H

#include "core/canfdi_common.h"

/* Largest supported order. */
#define CANFDI_SVF_MAX_ORDER 3U

/* The outputs a step computes (canfdi_svf_cfg_t.outputs). */
#define CANFDI_SVF_OUT_Y 0x01U
#define CANFDI_SVF_OUT_DY 0x02U
#define CANFDI_SVF_OUT_D2Y 0x04U
#define CANFDI_SVF_OUT_ALL 0x07U

typedef struct {
  uint8_t order;         /* 2 or 3 */
  uint8_t outputs;       /* CANFDI_SVF_OUT_* the caller reads; 0 means all.
                          * A step computes only these (the states always):
                          * an output is a rounding, clamps and up to two
                          * 64-bit products, and most users read two of
                          * the three */
  int32_t omega_c_rad_s; /* corner frequency wc, integer rad/s, 1..2000 at 1 ms */
} canfdi_svf_cfg_t;

/* Diagnostics counters: monotone, saturating at UINT32_MAX
 * (core/canfdi_count.h); init clears them, nothing else does. No decision
 * of the firmware depends on them. */
typedef struct {
  uint32_t steps;           /* canfdi_svf_step calls */
  uint32_t resets;          /* canfdi_svf_reset calls (init counts as none) */
  uint32_t out_saturations; /* outputs clipped to the Q16.16 range */
} canfdi_svf_diag_t;

typedef struct {
  canfdi_svf_cfg_t cfg;
  int32_t g_q31[CANFDI_SVF_MAX_ORDER]; /* the last row of G = h (I - hM)^-1 */
  int32_t h_q31;                       /* h = wc T / 2 */
  int64_t v_q32[CANFDI_SVF_MAX_ORDER]; /* normalised states y, y'/wc, y''/wc^2, Q31.32 */
  int32_t u_prev_q16; /* last input u(k) */
  int32_t y_q16;      /* outputs of the last step */
  int32_t dy_q16;
  int32_t d2y_q16;
  canfdi_svf_diag_t diag;
} canfdi_svf_t;

/*
 * Validates cfg, precomputes G and resets the filter to steady state at 0.
 * Returns CANFDI_OK, or -CANFDI_EINVAL for a NULL pointer or a cfg outside
 * the domain above (then *f is left unchanged).
 * Cost: see the header comment; integer arithmetic only.
 */
int32_t canfdi_svf_init(canfdi_svf_t *f, const canfdi_svf_cfg_t *cfg);

/*
 * Steady state at x0: y = x0, all derivatives 0, previous input x0 (so a
 * following step with input x0 changes nothing). Use it to start a filter on
 * the first measurement instead of letting it ramp up from 0.
 * Cannot fail by contract (f must come from a successful init). Cost: O(n).
 */
void canfdi_svf_reset(canfdi_svf_t *f, int32_t x0_q16);

/*
 * One step of CANFDI_CFG_STEP_US with the new sample x(k+1) (Q16.16).
 * Cannot fail by contract; saturation is counted, not reported.
 */
void canfdi_svf_step(canfdi_svf_t *f, int32_t x_q16);

/* Outputs after the last step (or reset): filtered signal (same unit), first
 * derivative (unit/s) and second derivative (unit/s^2), all Q16.16. Only
 * the outputs of cfg.outputs are computed: reading another is an invariant
 * violation (CANFDI_ASSERT; it reads the value of the last reset).
 * Cost: a load each. */
int32_t canfdi_svf_y_q16(const canfdi_svf_t *f);
int32_t canfdi_svf_dy_q16(const canfdi_svf_t *f);
int32_t canfdi_svf_d2y_q16(const canfdi_svf_t *f);

/* The diagnostics counters (pointer into *f). */
const canfdi_svf_diag_t *canfdi_svf_diag(const canfdi_svf_t *f);

#endif /* CANFDI_SVF_H */
