/*
 * canfdi_trend.h — trend checking: the rate of change of a signal from a
 * filtered derivative, checked against rate limits with hysteresis and
 * Dem-style debouncing (Isermann, Fault-Diagnosis Systems, ch. 7.1).
 *
 * Units. The input x is an int32_t in the caller's engineering unit (mA,
 * mrad, ...); the rate is reported in that unit per second with
 * `rate_frac_bits` fraction bits (0: plain units/s; 8: units/s * 256, for
 * slopes of a fraction of one unit per second). The rate limits in
 * cfg->rate_limit are in that same format. Every int32_t input is valid.
 *
 * Filter. T = CANFDI_CFG_STEP_US, tau = cfg->tau_us, and
 * alpha = T / (tau + T) (in Q31, computed at init). Stage 1 is a first-order
 * low-pass, stage 2 (order 2 only) a second one on the derivative:
 *   y1[k] = y1[k-1] + alpha * (x[k] - y1[k-1])
 *   d1[k] = (y1[k] - y1[k-1]) / T             = alpha/T * (x[k] - y1[k-1])
 *   order 1: rate[k] = d1[k]
 *   order 2: rate[k] = y2[k] = y2[k-1] + alpha * (d1[k] - y2[k-1])
 * Transfer function from x to rate:
 *   G1(z) = (alpha/T) (1 - z^-1) / (1 - (1-alpha) z^-1)       ~ s / (1 + tau s)
 *   G2(z) = (alpha^2/T) (1 - z^-1) / (1 - (1-alpha) z^-1)^2   ~ s / (1 + tau s)^2
 * Gain: exactly 1 for a ramp (d1 and y2 converge to the slope s, because a
 * low-pass stage has unit DC gain); |G(jw)| ~ w for w << 1/tau, and the
 * corner frequency is f_c = 1 / (2 pi tau) (tau = 15.9 ms for 10 Hz). Above
 * it G1 is flat at alpha/T ~ 1/tau, G2 falls with 1/w.
 * Delay: each stage lags a ramp by exactly T (1 - alpha) / alpha = tau, so
 * the filtered signal (canfdi_trend_filtered) trails x by s * tau and the
 * rate is a tau (order 1) or 2 tau (order 2) delayed view of the slope; from
 * rest, the error after k samples of a ramp is s (1-alpha)^(k+1) (order 1)
 * or s (1 + (k+1) alpha) (1-alpha)^(k+1) (order 2).
 * Step of height h at sample 0 (after the first, priming, sample):
 *   order 1: rate[k] = (alpha h / T) (1-alpha)^k, peak alpha h / T at k = 0;
 *   order 2: rate[k] = (alpha^2 h / T) (k+1) (1-alpha)^k, peak at
 *            k ~ tau/T - 1 of about h / (e tau) (within 3 % for tau >= 20 T).
 * Noise: for |noise| <= A the rate never exceeds 2 A alpha / T in magnitude
 * (both orders: d1 is alpha/T times a difference of two values within the
 * noise band, and stage 2 is a convex average of d1), so rate limits above
 * that bound cannot be tripped by bounded noise around a constant. For
 * white noise of standard deviation sigma, order 1 gives a rate standard
 * deviation of sigma (alpha / T) sqrt(2 / (2 - alpha)) ~ sigma / tau and
 * order 2 about sigma / tau * sqrt(alpha) / 2 (alpha << 1; e.g. 9x less at
 * tau = 20 ms, 14x at 50 ms) — the reason to prefer order 2 on noisy
 * signals, at the price of twice the delay.
 *
 * Scaling and overflow. y1 and y2 are int64_t with 16 extra fraction bits
 * (CANFDI_TREND_FRAC): |x| * 2^16 < 2^47, so |x - y1| < 2^48 and
 * alpha * (x - y1) is formed with canfdi_mul_s64_q31 (exact 64-bit product
 * halves, rounded half up); y1 stays within the range of past inputs (a
 * rounded step of alpha < 1 never overshoots its target). With 16 fraction
 * bits a slope of 1 unit/s, i.e. 0.001 units per 1 ms step, moves y1 by 65
 * LSBs per step, so slow trends are not lost to rounding (the state's rate
 * quantum is 2^-16 units per step, 0.015 units/s at 1 ms). d1 in Q16
 * units/s is (y1[k] - y1[k-1]) * (10^6 / T): < 2^48 * 10^4 < 2^62 for any
 * T >= 100 us; y2 stays within the range of past d1, and the difference
 * d1 - y2 is a saturating subtract. The rate output is rounded half up to
 * rate_frac_bits and saturates to int32_t (counted in diag.rate_saturations;
 * e.g. a full-scale step with a short tau). Input quantisation: a signal
 * whose LSB is q adds a ripple of at most q alpha / T to the rate (a
 * staircase instead of a ramp), so choose tau so that this is below the
 * rate resolution that matters.
 *
 * Start-up: the first sample after init or reset only primes y1 (no startup
 * transient); the rate is 0 and nothing is reported to the debouncer until
 * the second sample.
 *
 * Cost, worst case per canfdi_trend_step() (order 2): 5 signed 32x32->64
 * multiplies (2 per canfdi_mul_s64_q31, 1 for the 10^6/T scale; libgcc
 * __aeabi_lmul on Cortex-M0+), two 64-bit shifts by rate_frac_bits (libgcc
 * on M0+), about 10 64-bit add/sub/compare, then one canfdi_limit_step.
 * Measured (arm-none-eabi-gcc 12 -Os, QEMU -icount, 2000 calls incl.
 * full-scale inputs), rate check and debouncing included: order 2 at most
 * 549 instructions on Cortex-M0 (mean 533), 232 on Cortex-M4 (mean 213);
 * order 1 at most 394 (M0) and 187 (M4). Stack: about 110 bytes worst
 * chain on M0+ (48 here + 32 in canfdi_mul_s64_q31 + 28 in __aeabi_lmul;
 * the rate check needs 32). Code: 800 bytes (M0+) plus limit, debounce and
 * libgcc. RAM per instance: sizeof(canfdi_trend_t) = 80 bytes on a 32-bit
 * ARM target (two 64-bit states 16, alpha 4, rate 4, flag, config pointer
 * 4, embedded limit checker 36, diagnostics 4, 8-byte alignment); the
 * configuration (40 bytes) is caller-owned, normally const.
 */
#ifndef CANFDI_TREND_H
#define CANFDI_TREND_H

#include "core/canfdi_common.h"
#include "core/canfdi_fixp.h"
#include "detect/canfdi_limit.h"

/* Extra fraction bits of the filter states. */
#define CANFDI_TREND_FRAC 16U
/* Largest time constant accepted by init: 100 s. */
#define CANFDI_TREND_TAU_MAX_US 100000000U
/* Largest rate_frac_bits: the state's own fraction bits. */
#define CANFDI_TREND_RATE_FRAC_MAX CANFDI_TREND_FRAC

/*
 * Configuration, caller-owned; the instance keeps a pointer to it (and to
 * rate_limit inside it), so it must outlive the instance and stay unchanged.
 */
typedef struct {
  uint32_t tau_us;               /* time constant of each stage, 0..CANFDI_TREND_TAU_MAX_US */
  uint8_t order;                 /* 1 or 2 low-pass stages, see above */
  uint8_t rate_frac_bits;        /* 0..16, fraction bits of the rate and its limits */
  canfdi_limit_cfg_t rate_limit; /* limits on the rate, units/s * 2^rate_frac_bits */
} canfdi_trend_cfg_t;

/* Diagnostics counters: monotone, saturating at UINT32_MAX
 * (core/canfdi_count.h); init clears them, nothing else does. No decision
 * of the firmware depends on them. */
typedef struct {
  uint32_t rate_saturations; /* steps whose rate did not fit int32_t */
} canfdi_trend_diag_t;

/* Instance, caller-owned; fields are read-only for the caller. */
typedef struct {
  const canfdi_trend_cfg_t *cfg;
  int64_t y1_q16;          /* stage 1: low-pass of x, units * 2^16 */
  int64_t y2_q16;          /* stage 2: low-pass of d1, units/s * 2^16 */
  canfdi_q31_t alpha_q31;  /* T / (tau + T) */
  int32_t rate;            /* units/s * 2^rate_frac_bits, last step */
  bool primed;             /* y1 holds a sample */
  canfdi_limit_t limit;    /* rate limit check with debouncing */
  canfdi_trend_diag_t diag;
} canfdi_trend_t;

/* Check cfg against the domains above (rate_limit as canfdi_limit_cfg_check).
 * Returns CANFDI_OK or -CANFDI_EINVAL. O(1). */
int32_t canfdi_trend_cfg_check(const canfdi_trend_cfg_t *cfg);

/* Bind t to cfg, compute alpha, clear the filter (unprimed), rate 0.
 * Returns CANFDI_OK or -CANFDI_EINVAL (NULL, invalid cfg; then t stays
 * unbound and step() rejects it). Cost: one canfdi_div_s32_qn. */
int32_t canfdi_trend_init(canfdi_trend_t *t, const canfdi_trend_cfg_t *cfg);

/* Filter one sample x (any int32_t), update the rate and check it.
 * Returns the qualified status of the rate check (canfdi_deb_status_t,
 * >= 0), or -CANFDI_EINVAL for NULL/unbound t. Cost: see above. */
int32_t canfdi_trend_step(canfdi_trend_t *t, int32_t x);

/* Unprime the filter and restart the rate check (canfdi_limit_reset);
 * counters kept. No-op on NULL/unbound. O(1). */
void canfdi_trend_reset(canfdi_trend_t *t);

/* Rate of the last step, units/s * 2^rate_frac_bits; 0 for NULL. O(1). */
int32_t canfdi_trend_rate(const canfdi_trend_t *t);

/* Stage-1 low-pass of x (units, rounded half up; lags a ramp by tau);
 * 0 for NULL. O(1). */
int32_t canfdi_trend_filtered(const canfdi_trend_t *t);

/* Qualified status of the rate check; UNDECIDED for NULL. O(1). */
canfdi_deb_status_t canfdi_trend_status(const canfdi_trend_t *t);

#endif /* CANFDI_TREND_H */
