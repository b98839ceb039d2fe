/*
 * canfdi_meanvar.h — recursive mean and variance with exponential forgetting
 * (Isermann, Fault-Diagnosis Systems, ch. 7: signal-model based change
 * detection). One instance follows one signal; the mean and variance it
 * delivers feed limit checks on the variance and the CUSUM change detector
 * (canfdi_cusum.h takes sigma in the same Q10 format as
 * canfdi_meanvar_std_q10 returns).
 *
 * Recursion, with alpha = 1 - lambda (lambda: forgetting factor):
 *
 *   mean(k) = mean(k-1) + alpha * (x(k) - mean(k-1))
 *   var(k)  = var(k-1)  + alpha * ((x(k) - mean(k))^2 - var(k-1))
 *
 * i.e. Isermann's form with the deviation taken from the *updated* mean.
 * The first sample after init/reset sets mean = x(0), var = 0, so there is no
 * start-up transient from zero. Effective memory ~ 1/alpha samples. For an
 * i.i.d. input of variance s^2 the stationary expectation of var(k) is
 * s^2 * 2 (1 - alpha)^2 / (2 - alpha) (0.985 s^2 at lambda = 0.99): the
 * estimator is slightly biased low, which is immaterial for alpha << 1.
 *
 * Scaling and overflow (all arithmetic exact or rounded half up, no wrap):
 *   - input x: int32_t in LSB of the monitored signal, limited to
 *     [-CANFDI_MEANVAR_X_MAX, +CANFDI_MEANVAR_X_MAX] = +-2^20. Samples beyond
 *     are saturated to the limit and counted in diag.input_saturations.
 *   - mean: int64_t, LSB with 32 fraction bits (|mean_q32| <= 2^52). The
 *     update adds round(alpha * (x*2^32 - mean)) (canfdi_mul_s64_q31); a
 *     rounded fraction of the distance never overshoots, so the mean stays
 *     inside [min x, max x] and never leaves +-2^20.
 *   - d = x - mean(k) rounded to 10 fraction bits: |d| <= 2^21 LSB, so
 *     |d_q10| <= 2^31 and d_q10^2 <= 2^62 fits int64_t.
 *   - var: int64_t, LSB^2 with 20 fraction bits, 0 <= var_q20 <= 2^62; the
 *     difference d^2 - var lies in [-2^62, 2^62], alpha times it is rounded
 *     half up by canfdi_mul_s64_q31. var stays >= 0 for the same
 *     no-overshoot reason as the mean.
 *   (Why 10 and 20 fraction bits: a variance with 16 fraction bits would
 *   have a dead zone of 2^-17/alpha LSB^2 = 0.08 LSB^2 at lambda = 0.9999,
 *   as large as the variance of one LSB of quantisation noise. The headroom
 *   that the +-2^20 input limit leaves in 64 bits gives d 10 and var 20
 *   fraction bits, a dead zone 16 times smaller.)
 *
 * Accuracy versus the exact recursion with the same (quantised) alpha,
 * a = alpha_q31 / 2^31, derived from the per-step rounding errors, each of
 * which the contraction (1 - a) forgets geometrically:
 *   |mean error| <= 2^-33 / a LSB   (half an LSB of Q32 per step, summed
 *                                    over ~1/a steps): 1.2e-6 LSB at
 *                                    lambda = 0.9999, 1.2e-9 LSB at 0.9.
 *   |var error|  <= delta * (2 D + delta) + 2^-21 / a   LSB^2,
 *       where D = max |x - mean| over the history and
 *       delta = 2^-11 + 2^-33 / a is the error of d (its rounding to Q10
 *       plus the mean error). E.g. lambda = 0.9999: noise of +-1 LSB ->
 *       <= 0.006 LSB^2; full-scale data (D = 2^21) -> <= 2.1e3 LSB^2, i.e.
 *       a relative error <= 1e-8 of a full-scale variance.
 * The tests (tests/unit/test_meanvar.c) check these bounds sample by sample
 * against a double-precision run of the same recursion, over the full input
 * range, for lambda 0.9 ... 0.9999. Useful alpha: the bounds stay
 * meaningful down to alpha ~ 2^-20 (lambda ~ 1 - 1e-6); any alpha in
 * [2^-31, 1) is accepted and safe from overflow.
 *
 * Cost per canfdi_meanvar_step: two canfdi_mul_s64_q31 and one 64x64->64
 * multiply (d^2); no division, no loop, same path for every sample after
 * the first. Measured (gcc -Os, instructions executed per call, QEMU
 * -icount): Cortex-M0+ code 380 instructions (five __aeabi_lmul calls),
 * i.e. about 500 cycles with a single-cycle multiplier; Cortex-M4 110.
 * canfdi_meanvar_std_q10 costs one canfdi_isqrt_u64: 1150 instructions on
 * M0+, 490 on M4 — call it when sigma is needed, not every step.
 * Other accessors: a few instructions. RAM: sizeof(canfdi_meanvar_t) =
 * 32 bytes per instance (caller-owned). Stack: a few words.
 */
#ifndef CANFDI_MEANVAR_H
#define CANFDI_MEANVAR_H

#include "core/canfdi_common.h"
#include "core/canfdi_fixp.h"

/* Input limit in LSB: samples are saturated to +-CANFDI_MEANVAR_X_MAX. */
#define CANFDI_MEANVAR_X_MAX ((int32_t)1 << 20)

/* Diagnostics counters: monotone, saturating at UINT32_MAX
 * (core/canfdi_count.h); init clears them, nothing else does. No decision
 * of the firmware depends on them. */
typedef struct {
  uint32_t input_saturations; /* samples clipped to +-CANFDI_MEANVAR_X_MAX */
  uint32_t resets;            /* canfdi_meanvar_reset calls */
} canfdi_meanvar_diag_t;

/* Instance state; fields are private, use the accessors. */
typedef struct {
  int64_t mean_q32;         /* LSB, 32 fraction bits */
  int64_t var_q20;          /* LSB^2, 20 fraction bits, >= 0 */
  canfdi_q31_t alpha_q31;   /* 1 - lambda, in (0, 1) */
  uint32_t n_samples;       /* since init/reset, saturating at UINT32_MAX */
  canfdi_meanvar_diag_t diag;
} canfdi_meanvar_t;

/*
 * Prepare an instance. alpha_q31 = 1 - lambda in Q31, 0 < alpha_q31 (e.g.
 * CANFDI_Q31_RATIO(1, 100) for lambda = 0.99). Clears the estimates and the
 * diagnostics. Returns CANFDI_OK, or -CANFDI_EINVAL for a NULL instance or
 * alpha_q31 <= 0 (the instance is then left untouched).
 * Cost: constant, a few stores.
 */
int canfdi_meanvar_init(canfdi_meanvar_t *s, canfdi_q31_t alpha_q31);

/*
 * Forget the estimates; the next sample re-initialises mean and variance
 * (as after init). Counts diag.resets. Cannot fail by contract (s != NULL).
 * Cost: constant.
 */
void canfdi_meanvar_reset(canfdi_meanvar_t *s);

/*
 * Feed one sample x (LSB). Saturates |x| to CANFDI_MEANVAR_X_MAX (counted).
 * Cannot fail by contract (s != NULL, initialised). Cost: see header.
 */
void canfdi_meanvar_step(canfdi_meanvar_t *s, int32_t x);

/* Samples since init/reset (saturating); 0 means the estimates are void. */
uint32_t canfdi_meanvar_count(const canfdi_meanvar_t *s);

/* Mean rounded half up to whole LSB; 0 before the first sample. */
int32_t canfdi_meanvar_mean(const canfdi_meanvar_t *s);

/* Mean at full precision: LSB with 32 fraction bits (|value| <= 2^52). */
int64_t canfdi_meanvar_mean_q32(const canfdi_meanvar_t *s);

/* Variance at full precision: LSB^2 with 20 fraction bits (<= 2^62). */
uint64_t canfdi_meanvar_var_q20(const canfdi_meanvar_t *s);

/* Variance rounded half up to whole LSB^2 (<= 2^42). */
uint64_t canfdi_meanvar_var(const canfdi_meanvar_t *s);

/*
 * Standard deviation in LSB with 10 fraction bits: floor(sqrt(var_q20)),
 * exact to the floor (error in [0, 2^-10) LSB on top of the variance's).
 * Value <= 2^31. Cost: one canfdi_isqrt_u64.
 */
uint32_t canfdi_meanvar_std_q10(const canfdi_meanvar_t *s);

/* The diagnostics counters. */
canfdi_meanvar_diag_t canfdi_meanvar_diag(const canfdi_meanvar_t *s);

#endif /* CANFDI_MEANVAR_H */
