/*
 * canfdi_rls.h — recursive least squares with exponential forgetting in the
 * UD-factorised form of Bierman and Thornton, in integer arithmetic.
 *
 * Model. y(k) = phi(k)^T theta + e(k) for up to CANFDI_CFG_RLS_MAX_PARAMS
 * parameters. Each update minimises sum_k lambda^(N-k) e(k)^2 (Isermann,
 * Fault-Diagnosis Systems, ch. 9; Ljung & Soederstroem for the UD form).
 *
 * Why UD. Plain covariance RLS updates P directly; with 32-bit numbers
 * P - P phi phi^T P / (lambda + phi^T P phi) loses symmetry and positive
 * definiteness within minutes. Here P = U D U^T (U unit upper triangular,
 * D diagonal) and the update (Bierman's measurement update with forgetting)
 * multiplies each d_j by alpha_(j-1) / (alpha_j lambda) with
 * alpha_j = alpha_(j-1) + f_j^2 d_j > 0: every d_j stays positive by
 * construction, so P stays positive definite whatever the rounding. d_j is
 * additionally floored at 2^-60 (counted in diag.saturations; never seen in
 * the tests).
 *
 * Number representation. D spans many decades (P0 ~ 1e4 at start, ~1e-4
 * when converged, ~1e4 again while forgetting without excitation), and the
 * entries of U, the gain and the parameters differ by orders of magnitude
 * too. Every internal quantity is therefore a canfdi_rls_xf_t: a 32-bit
 * mantissa m with 2^29 <= |m| < 2^30 (or m == 0) and its own exponent e,
 * value m * 2^e — a per-element exponent ("block floating point" with block
 * size 1), implemented with integer operations only: products are 64-bit
 * (|m1 m2| < 2^60), sums are aligned in 64 bits with 32 guard bits,
 * quotients use canfdi_div_s32_qn, and every result is renormalised with
 * rounding to nearest (ties away from zero). Relative precision ~2^-30 per
 * operation; exponents are clamped to +-2^16 (unreachable with the trace
 * bound below). No float, no division by a run-time zero (alpha >= lambda).
 *
 * Normalisation. Regressors and output enter as Q16.16 in physical units.
 * Each has a power-of-two normalising shift s (cfg): the RLS works on
 * phi_norm_i = phi_i 2^-s_i and y_norm = y 2^-s_y, chosen by the caller so
 * that the normalised signals are O(1). Because the representation carries
 * exponents, this costs nothing and loses nothing; it matters for the
 * meaning of P0 = p0 I, of the trace bound and of the excitation threshold,
 * which are all in normalised units. The physical parameter is
 * theta_i = theta_norm_i 2^(s_y - s_i).
 *
 * Wind-up protection (two mechanisms, both counted):
 *  1. Excitation gate. Each update first measures the excitation of every
 *     regressor: the squared deviation of the normalised regressor from
 *     its running mean, (phi_norm_i - mean_i)^2, averaged by a first-order
 *     filter with time constant 2^excite_shift updates (the means use the
 *     same constant). The excitation is the SMALLEST of these mean-square
 *     deviations over the regressors selected by excite_mask (constant
 *     regressors must be left out). If it is below excite_min, the update
 *     is skipped entirely: neither theta nor P change, and in particular no
 *     forgetting is applied (diag.skipped). Why: at a constant operating
 *     point the data hold information about one direction only; forgetting
 *     would inflate P in all others (wind-up) and a later disturbance would
 *     throw the estimate around. Skipping keeps the last good estimate and
 *     covariance. Why the minimum and not the sum: in closed loop one
 *     regressor can stay busy on noise (e.g. a current driven by a
 *     controller's reaction to sensor noise) while another carries nothing
 *     but noise (a velocity at standstill); a summed measure would open the
 *     gate and let that parameter drift on noise correlations.
 *  2. Trace bound. After each update, if trace(P) > trace_max, D is
 *     scaled by trace_max / trace(P) (diag.trace_clips). This catches
 *     partial excitation (some regressors vary, others do not), where the
 *     gate opens and forgetting inflates the unexcited directions. Scaling
 *     D keeps U, so P keeps its shape and stays positive definite.
 *
 * Cost per update with n parameters, in xf operations (mul/add/div, each
 * one 64-bit multiply or add plus a renormalisation):
 *   excitation: 5n;  prediction error: 2n;  f = U^T phi and g = D f:
 *   n(n-1) + n;  Bierman loop: n divisions + 5n + 4 n(n-1)/2;  parameter
 *   update: 2n + 1;  trace bound: n(n-1) + 2n, plus n + 1 when clipping.
 *   Total ~ 3 n^2 + 14 n xf operations + n divisions: ~ 50 for n = 3,
 *   ~ 180 for n = 6. A skipped update costs the excitation measure and the
 *   prediction error only (7 n).
 * Measured executed instructions per call (arm-none-eabi-gcc 12 -Os, QEMU
 * mps2-an386 -icount, SysTick; 2000 calls with random regressors of
 * magnitude <= 1, gate always open; the loop counts are data-independent,
 * so the mean is close to the worst case), mean / max:
 *               Cortex-M4          Cortex-M0+ code
 *   n = 3       11.3 k / 11.5 k    20.3 k / 20.6 k
 *   n = 4       17.1 k / 17.3 k    30.3 k / 30.7 k
 *   n = 5       23.8 k / 24.0 k    42.0 k / 42.5 k
 *   n = 6       31.6 k / 31.9 k    55.4 k / 56.0 k
 *   skipped update (n = 3): 1.35 k (M4), 2.29 k (M0+)
 * i.e. ~230 (M4) and ~400 (M0+) instructions per xf operation: too much
 * for every 1 ms step on a 48 MHz M0+ (n = 3 takes 0.42 ms), which is why
 * the estimators decimate the update (every 2..5 steps) and never run two
 * updates in one step.
 * Memory: sizeof(canfdi_rls_t) = 432 bytes with the default
 * CANFDI_CFG_RLS_MAX_PARAMS = 6 on a 32-bit target (8 bytes per xf:
 * n(n-1)/2 for U, 4n for theta, D and the excitation filters, 4 scalars;
 * 8n for the running means; the cfg copy). Caller-owned, no heap, no
 * globals; an update uses ~32 n_max + 64 bytes of stack.
 */
#ifndef CANFDI_RLS_H
#define CANFDI_RLS_H

#include "core/canfdi_common.h"
#include "core/canfdi_fixp.h"


#define CANFDI_RLS_N_U ((CANFDI_CFG_RLS_MAX_PARAMS * (CANFDI_CFG_RLS_MAX_PARAMS - 1U)) / 2U)

/* A number m * 2^e with 2^29 <= |m| < 2^30, or m == 0 (see above). */
typedef struct {
  int32_t m;
  int32_t e;
} canfdi_rls_xf_t;

typedef struct {
  uint8_t n_params;                          /* 1 .. CANFDI_CFG_RLS_MAX_PARAMS */
  int8_t phi_shift[CANFDI_CFG_RLS_MAX_PARAMS]; /* s_i: phi_norm = phi 2^-s_i, -32..32 */
  int8_t y_shift;                            /* s_y, -32..32 */
  canfdi_q31_t forget_q31;     /* 1 - lambda in Q31, 0 (no forgetting) .. 0.5 */
  int32_t p0_q16;              /* initial P = p0 I, normalised units, > 0 */
  int32_t trace_max_q16;       /* trace bound, normalised units, >= n p0 */
  int32_t excite_min_q16;      /* gate threshold, mean-square normalised
                                * deviation (Q16.16, >= 0; 0: always update) */
  uint8_t excite_shift;        /* time constant 2^k updates, 1..16 */
  uint16_t excite_mask;        /* bit i: regressor i counts for the gate;
                                * 0 selects all */
  int32_t theta0_q16[CANFDI_CFG_RLS_MAX_PARAMS]; /* initial physical theta */
} canfdi_rls_cfg_t;

/* Diagnostics counters: monotone, saturating at UINT32_MAX
 * (core/canfdi_count.h); init clears them, nothing else does. No decision
 * of the firmware depends on them. */
typedef struct {
  uint32_t updates;     /* updates applied */
  uint32_t skipped;     /* updates skipped by the excitation gate */
  uint32_t trace_clips; /* times D was scaled down to the trace bound */
  uint32_t resets;      /* canfdi_rls_reset calls (init counts as none) */
  uint32_t boosts;      /* canfdi_rls_boost calls */
  uint32_t saturations; /* d_j floored at 2^-60 */
} canfdi_rls_diag_t;

typedef struct {
  canfdi_rls_cfg_t cfg;
  canfdi_rls_xf_t lambda;     /* lambda and 1 / lambda */
  canfdi_rls_xf_t inv_lambda;
  canfdi_rls_xf_t trace_max;
  canfdi_rls_xf_t excite_min;
  canfdi_rls_xf_t theta[CANFDI_CFG_RLS_MAX_PARAMS]; /* normalised */
  canfdi_rls_xf_t d[CANFDI_CFG_RLS_MAX_PARAMS];
  canfdi_rls_xf_t u[CANFDI_RLS_N_U]; /* strict upper triangle, column-wise:
                                      * u_ij (i < j) at j (j - 1) / 2 + i */
  int64_t mean[CANFDI_CFG_RLS_MAX_PARAMS]; /* running means of phi, Q32.32 */
  canfdi_rls_xf_t excite[CANFDI_CFG_RLS_MAX_PARAMS]; /* filtered mean-square
                                                      * deviation per regressor */
  canfdi_rls_xf_t err;        /* last a-priori error, normalised */
  bool primed;                /* means initialised from a first sample */
  bool excited;               /* last gate decision */
  canfdi_rls_diag_t diag;
} canfdi_rls_t;

/*
 * Validates cfg and resets (theta = theta0, P = p0 I).
 * Returns CANFDI_OK or -CANFDI_EINVAL (NULL, n out of range, shift out of
 * -32..32, forget outside [0, 0.5], p0 <= 0, trace_max < n p0, excite_min
 * < 0, excite_shift outside 1..16, excite_mask bits at or above n); *r is
 * unchanged on error.
 * Cost: one division and O(n^2) stores.
 */
int32_t canfdi_rls_init(canfdi_rls_t *r, const canfdi_rls_cfg_t *cfg);

/*
 * Restart: P = p0 I, and theta = theta0 unless keep_theta (a covariance
 * reset: keep the estimate, make it alert again — the usual reaction to a
 * detected change). Re-primes the excitation measure. Cannot fail.
 */
void canfdi_rls_reset(canfdi_rls_t *r, bool keep_theta);

/*
 * Covariance boost: P = p0 I, everything else kept (theta, the excitation
 * measure and its gate decision). The reaction to a change that the
 * caller detected while the signals are moving: the estimate becomes alert
 * at once, without the excitation measure's re-priming delay of
 * canfdi_rls_reset. Cannot fail. Cost: O(n^2) stores.
 */
void canfdi_rls_boost(canfdi_rls_t *r);

/*
 * One sample: regressors phi_q16[0..n-1] and output y_q16, Q16.16 physical.
 * Returns true if the update was applied, false if the excitation gate
 * skipped it. Cannot fail by contract. Cost: see above.
 */
bool canfdi_rls_update(canfdi_rls_t *r, const int32_t phi_q16[], int32_t y_q16);

/* Physical theta_i in Q(frac) (frac 0..31), rounded, saturated to the
 * int32_t range (not counted: the read-out is const; compare with
 * INT32_MIN/MAX). i >= n or frac > 31 gives 0. */
int32_t canfdi_rls_theta_qn(const canfdi_rls_t *r, unsigned i, unsigned frac);

/* Overwrite theta_i (physical, Q(frac)); e.g. to seed from a known value. */
void canfdi_rls_set_theta_qn(canfdi_rls_t *r, unsigned i, int32_t value, unsigned frac);

/* Last a-priori prediction error y - phi^T theta, physical Q16.16. */
int32_t canfdi_rls_err_q16(const canfdi_rls_t *r);

/* Covariance entry P_ij (normalised units) in Q(frac), saturated; and the
 * trace of P in Q16.16. O(n) and O(n^2) xf operations: diagnostics, not the
 * 1 ms path. */
int32_t canfdi_rls_cov_qn(const canfdi_rls_t *r, unsigned i, unsigned j, unsigned frac);
int32_t canfdi_rls_trace_q16(const canfdi_rls_t *r);

/* D element j as mantissa/exponent (tests and the reference comparison). */
canfdi_rls_xf_t canfdi_rls_d(const canfdi_rls_t *r, unsigned j);

/* Excitation (the smallest filtered mean-square normalised deviation over
 * the gated regressors) in Q16.16, and the last gate decision. */
int32_t canfdi_rls_excitation_q16(const canfdi_rls_t *r);
bool canfdi_rls_excited(const canfdi_rls_t *r);

/*
 * Self-check (as o1heap's do_invariants_hold): every d_j > 0 and
 * normalised, every xf normalised, trace(P) <= trace_max (1 + 2^-20).
 * O(n^2). For tests and a periodic background check.
 */
bool canfdi_rls_invariants_hold(const canfdi_rls_t *r);

const canfdi_rls_diag_t *canfdi_rls_diag(const canfdi_rls_t *r);

#endif /* CANFDI_RLS_H */
