/*
 * canfdi_adapt.h — adaptive threshold for residual evaluation (Isermann,
 * Fault-Diagnosis Systems, ch. 7.3: thresholds that grow with the
 * excitation, so that model errors during transients do not raise alarms
 * while the threshold stays tight in steady state).
 *
 *   threshold[k] = min(max, base + gain * f[k])
 *   f[k] = f[k-1] + alpha * (|u[k] - u[k-1]| / T - f[k-1])
 * u is the exciting input (a setpoint, a manipulated variable) in its own
 * unit, f the low-pass filtered |du/dt| in u-units per second, and
 * alpha = T / (tau + T) with T = CANFDI_CFG_STEP_US and tau = cfg->tau_us.
 * The threshold is in the residual's unit; gain is in residual units per
 * (u-unit/s), i.e. in seconds when residual and u share a unit, given as an
 * integer with gain_frac_bits fraction bits (Qm.n, n = 0..62). A residual r
 * exceeds the threshold when |r| > threshold (canfdi_adapt_exceeds).
 *
 * Choosing the parameters. After a step of height du at sample 0 the
 * threshold rises at once (same sample) by gain * alpha * du / T and decays
 * as (1-alpha)^k, which is >= exp(-k T / tau). If the residual transient of
 * the model error is bounded by |r[k]| <= c * |du| * exp(-k T / tau_r)
 * (e.g. c = 1 and tau_r = the slower time constant for two first-order lags
 * with a time-constant mismatch), then tau >= tau_r and
 * gain >= c * (tau + T) keep the threshold above the transient, with base
 * (noise, offsets) as the margin. For a ramp of slope s, f converges to |s|
 * as 1 - (1-alpha)^k, so the threshold settles at base + gain * |s|.
 *
 * Start-up: the first sample after init or reset only stores u (no
 * derivative yet); the threshold is base.
 *
 * Scaling and overflow. |u[k] - u[k-1]| < 2^32 is formed in int64_t and
 * scaled to u-units/s by 10^6/T (< 2^46 for T >= 100 us), then saturated
 * to INT32_MAX units/s (counted in diag.rate_saturations). f is an int64_t
 * with 16 fraction bits (f < 2^47), updated with canfdi_mul_s64_q31
 * (rounded half up; f never leaves [0, max input]). The product gain * f
 * uses f rounded to whole u-units/s and canfdi_mul_s32_qn (exact 64-bit
 * product, rounded half up, saturated), the sum with base saturates, then
 * the cap applies (counted in diag.cap_hits). Resolution: 1 u-unit/s of
 * excitation times gain, so pick the unit of u so that the rates that
 * matter are >> 1 unit/s (a setpoint in mrad/s stepping by 1 rad/s gives
 * 10^6 mrad/s^2 at 1 ms). The comparison in canfdi_adapt_exceeds is exact
 * for every int32_t residual (|INT32_MIN| formed in int64_t).
 *
 * Cost, worst case per canfdi_adapt_step(): 4 signed 32x32->64 multiplies
 * (1 for the 10^6/T scale, 2 in canfdi_mul_s64_q31, 1 in
 * canfdi_mul_s32_qn; __aeabi_lmul on Cortex-M0+), two 64-bit shifts by a
 * run-time amount (libgcc on M0+), about 10 64-bit add/compare. Measured
 * (arm-none-eabi-gcc 12 -Os, QEMU -icount, 2000 calls incl. full-scale
 * inputs): at most 408 instructions on Cortex-M0 (mean 394), 148 on
 * Cortex-M4 (mean 137). canfdi_adapt_exceeds: one 64-bit negate and
 * compare, 27 (M0) / 17 (M4) instructions. Stack: about 90 bytes worst
 * chain on M0+ (56 here + 28 in __aeabi_lmul). Code: 792 bytes (M0+).
 * RAM per instance:
 * sizeof(canfdi_adapt_t) = 40 bytes on a 32-bit ARM target (filter state 8,
 * alpha 4, previous u 4, threshold 4, flag 4, config pointer 4,
 * diagnostics 8, alignment); the configuration (20 bytes) is caller-owned.
 */
#ifndef CANFDI_ADAPT_H
#define CANFDI_ADAPT_H

#include "core/canfdi_common.h"
#include "core/canfdi_fixp.h"

/* Largest time constant accepted by init: 100 s. */
#define CANFDI_ADAPT_TAU_MAX_US 100000000U
/* Largest gain_frac_bits (the domain of canfdi_mul_s32_qn). */
#define CANFDI_ADAPT_GAIN_FRAC_MAX 62U

/* Configuration, caller-owned; the instance keeps a pointer to it. */
typedef struct {
  int32_t base;           /* threshold without excitation, residual units, >= 0 */
  int32_t max;            /* cap, residual units, >= base */
  int32_t gain;           /* residual units per (u-unit/s), * 2^gain_frac_bits, >= 0 */
  uint32_t tau_us;        /* low-pass time constant, 0..CANFDI_ADAPT_TAU_MAX_US */
  uint8_t gain_frac_bits; /* 0..62 */
} canfdi_adapt_cfg_t;

/* Diagnostics counters: monotone, saturating at UINT32_MAX
 * (core/canfdi_count.h); init clears them, nothing else does. No decision
 * of the firmware depends on them. */
typedef struct {
  uint32_t rate_saturations; /* |du/dt| above INT32_MAX u-units/s */
  uint32_t cap_hits;         /* steps where the threshold was capped at max */
} canfdi_adapt_diag_t;

/* Instance, caller-owned; fields are read-only for the caller. */
typedef struct {
  const canfdi_adapt_cfg_t *cfg;
  int64_t f_q16;          /* filtered |du/dt|, u-units/s * 2^16 */
  canfdi_q31_t alpha_q31; /* T / (tau + T) */
  int32_t u_prev;
  int32_t threshold;
  bool primed;
  canfdi_adapt_diag_t diag;
} canfdi_adapt_t;

/* Check cfg against the domains above. Returns CANFDI_OK or
 * -CANFDI_EINVAL. O(1). */
int32_t canfdi_adapt_cfg_check(const canfdi_adapt_cfg_t *cfg);

/* Bind a to cfg, compute alpha, unprime; threshold = base. Returns
 * CANFDI_OK or -CANFDI_EINVAL (NULL, invalid cfg; then a stays unbound and
 * step() rejects it). Cost: one canfdi_div_s32_qn. */
int32_t canfdi_adapt_init(canfdi_adapt_t *a, const canfdi_adapt_cfg_t *cfg);

/* Feed one sample of the exciting input u (any int32_t). Returns the
 * threshold for this step (>= 0, residual units), or -CANFDI_EINVAL for
 * NULL/unbound a. Cost: see above. */
int32_t canfdi_adapt_step(canfdi_adapt_t *a, int32_t u);

/* true when |residual| > the current threshold (false for NULL/unbound a).
 * Exact for every int32_t. Cost: O(1). */
bool canfdi_adapt_exceeds(const canfdi_adapt_t *a, int32_t residual);

/* Current threshold (base after init/reset); 0 for NULL. O(1). */
int32_t canfdi_adapt_threshold(const canfdi_adapt_t *a);

/* Filtered |du/dt|, u-units/s rounded half up and saturated; 0 for NULL. */
int32_t canfdi_adapt_excitation(const canfdi_adapt_t *a);

/* Unprime and clear the filter, threshold = base; counters kept. No-op on
 * NULL/unbound. O(1). */
void canfdi_adapt_reset(canfdi_adapt_t *a);

#endif /* CANFDI_ADAPT_H */
