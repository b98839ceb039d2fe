/*
 * canfdi_rls.h — recursive least squares with exponential forgetting in the
 * UD-factorised form of Bierman and Thornton, in integer arithmetic.
 *
 * Model. y(k) = phi(k)^T theta + e(k) for up to CANFDI_CFG_RLS_MAX_PARAMS
 * parameters (at most 7: the 64-bit sums below are sized for it). Each
 * update minimises sum_k lambda^(N-k) e(k)^2 (Isermann, Fault-Diagnosis
 * Systems, ch. 9; Ljung & Soederstroem for the UD form).
 *
 * Why UD. Plain covariance RLS updates P directly; with 32-bit numbers
 * P - P phi phi^T P / (lambda + phi^T P phi) loses symmetry and positive
 * definiteness within minutes. Here P = U D U^T c0 (U unit upper
 * triangular, D diagonal, c0 > 0 a scale) and the update is Bierman's
 * measurement update: with f = U^T phi, g = D f, alpha_0 = lambda / c0 and
 * alpha_(j+1) = alpha_j + f_j g_j, every d_j is multiplied by
 * rho_j = alpha_j / alpha_(j+1) in (0, 1]: D stays positive by
 * construction, so P stays positive definite whatever the rounding. d_j c0
 * is additionally floored at about 2^-61 (counted in diag.saturations;
 * never seen in the tests).
 *
 * The update in one pass over the columns (ratio form). The pass carries
 * inv = 1 / alpha_j: per column, f_j = phi_j + sum_(i<j) u_ij phi_i, then
 * g_j = d_j f_j, h = f_j inv, w = g_j h = d_j f_j^2 / alpha_j,
 * rho_j = 1 / (1 + w); d_j *= rho_j, inv *= rho_j; the U column
 * (u_ij += b_i mu_j with mu_j = -h, b_i += u_ij g_j) and b_j = g_j, so that
 * b ends as U g = P phi / c0 and the gain is b inv. Each column takes one
 * reciprocal of 1 + w (core/canfdi_intrin.h canfdi_recip_q63: a seed table,
 * one Newton step, no division instruction: the same bits on every core).
 *
 * Forgetting in one multiply. P / lambda is c0 / lambda: the scale absorbs
 * the forgetting (c0 <- c0 / lambda = 1 / alpha_0 on every applied update),
 * so D is never swept by 1/lambda. The trace bound scales c0 as well
 * (below). c0 and the d_j move against each other by powers of two when
 * c0 leaves [2^-100, 2^200] (exact).
 *
 * Number formats (what is kept, and why it is enough):
 *   - D and c0: positive numbers (m / 2^32) 2^e with a 32-bit mantissa m in
 *     [2^31, 2^32) and an exponent each (canfdi_rls_pf_t): D spans many
 *     decades (P0 ~ 1e4 at start, ~1e-4 converged, ~1e4 again while
 *     forgetting without excitation, and 2^24 between its elements when
 *     the regressors are badly scaled) and needs this in every element.
 *     Products keep the top 32 bits of the 64-bit product (truncated:
 *     2^-31 relative); normalisation is one CLZ or a one-bit test.
 *   - Within an update: f_j, inv, rho_j and g_j in that form too; h and w
 *     as the high words of their products (30 bits at least); the
 *     reciprocal within 2^-30.4 from below.
 *   - U: int32_t mantissas |u| <= 2^30 with one exponent per column (>= -30,
 *     so an entry keeps 2^-30 absolute resolution at least), renormalised
 *     only when the column's largest entry leaves [2^28, 2^30]: 28 to 30
 *     bits relative to it.
 *   - theta: one block, int32_t mantissas |theta| <= 2^30 with a shared
 *     exponent (normalised units), kept the same way: 28 to 30 bits
 *     relative to the largest |theta|.
 *   - the regressors of one update: x_i = phi_q16_i 2^(10 - s_i) (Q26
 *     normalised, exact) when every shift is in -20..10 and every
 *     |phi_norm| < 16; otherwise one block with a shift of its own, the
 *     largest in [2^29, 2^30] (30 bits relative to it).
 *   - the gain b = U g: one block, |b| < 2^30, its exponent from the bound
 *     n 2^(30 + max(u_e + g.e)) (ceil(log2 n) bits of headroom), raised
 *     column by column as the maximum grows.
 *   - the multipliers of the U, gain and theta updates: int32_t, truncated
 *     (one unit); every product with a block mantissa is a 32x32->64
 *     multiply-accumulate rounded half up to its high word
 *     (canfdi_mla_hi_rnd: one SMLAL on ARMv7-M).
 *   No float, no division, no saturation on the update's path: every
 *   format is chosen from a bound so that nothing can overflow, and a block
 *   that would be exceeded is shifted first (its exponent rises). On
 *   ARMv6-M (Cortex-M0) the 32x32->64 products are built from 16-bit
 *   halves and CLZ from a plain-C fallback (core/canfdi_intrin.h), with the
 *   same results.
 *   Precision kept (tests/unit/test_rls.c, tests/ref/ref_rls.cpp, against
 *   a covariance RLS in double fed the same Q16.16 samples): theta within
 *   ~1.2e-6 of max(1, |theta|), P within ~3e-5 of sqrt(P_ii P_jj) (both
 *   set by the read-out's resolution), for n = 1..6, gated or not, through
 *   the trace bound, over 200 000 updates, after a sudden parameter change,
 *   and with regressors whose normalised sizes span 2^-6..2^6 (theta
 *   within 4.1e-6 there: the gain block's spread costs its small elements
 *   bits).
 *   Range: normalised regressors and outputs of any size the Q16.16 inputs
 *   and shifts give; the excitation measure sees each regressor through a
 *   +-128 normalised window, so it saturates at 2^14 (and excite_min is
 *   limited to 2^14).
 *
 * Normalisation. Regressors and output enter as Q16.16 in physical units.
 * Each has a power-of-two normalising shift s (cfg): the RLS works on
 * phi_norm_i = phi_i 2^-s_i and y_norm = y 2^-s_y, chosen by the caller so
 * that the normalised signals are O(1): the blocks above then keep their
 * full precision (and the regressors their fixed format). The shifts
 * define the meaning of P0 = p0 I, of the trace bound and of the
 * excitation threshold, which are all in normalised units. The physical
 * parameter is theta_i = theta_norm_i 2^(s_y - s_i).
 *
 * Wind-up protection (two mechanisms, both counted):
 *  1. Excitation gate. Each update first measures the excitation of every
 *     regressor selected by excite_mask (constant regressors must be left
 *     out): the squared deviation of the normalised regressor from its
 *     running mean, (phi_norm_i - mean_i)^2, averaged by a first-order
 *     filter with time constant 2^excite_shift updates (the means use the
 *     same constant). Formats: the normalised regressor in Q23, clipped to
 *     +-128, its mean in Q23 (32 bits, rounded half up: the mean's dead
 *     zone, 2^(k-24) normalised for a time constant 2^k, adds at most
 *     2^(2k-48) to the measure), the deviation clipped to +-128 and the
 *     measure in Q46 (64 bits, floor). The excitation is the SMALLEST of
 *     these mean-square deviations. If it is below excite_min, the update
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
 *  2. Trace bound. After each update, if trace(P) > trace_max, P is
 *     scaled by trace_max / trace(P) through c0 (diag.trace_clips). This
 *     catches partial excitation (some regressors vary, others do not),
 *     where the gate opens and forgetting inflates the unexcited
 *     directions. Scaling keeps U and the ratios of D, so P keeps its shape
 *     and stays positive definite. An update cannot raise trace(P) by more
 *     than 1 / lambda, so a bound of the trace is carried and multiplied by
 *     (1 / lambda)(1 + 2^-20) per update (the 2^-20 covers the rounding of
 *     the factors); the exact trace (n (n - 1) / 2 squares) is computed
 *     only when that bound reaches trace_max, i.e. only near the bound and
 *     every ln(trace_max / trace(P)) / (1 - lambda) updates otherwise.
 *
 * Cost per update with n parameters: the gate a 32-bit mean and a 64-bit
 * measure per gated regressor (about 45 instructions on ARMv7-M); O(n^2)
 * 32x32->64 multiply-accumulates (f = U^T phi: n(n-1)/2, the column pass:
 * n(n-1), theta and the error: 2n); per column eight 32x32->64 products
 * (g, h, w, three for the reciprocal, d, inv), two table loads, the
 * normalisation of f and three shifts for the multipliers.
 * Measured executed instructions per call (arm-none-eabi-gcc 12 -Os, QEMU
 * -icount, SysTick; `make bench-pil`: bench/bench_rls_pil.c, 2000 calls,
 * n = 4, four regressors uniform in [-1, 1), gate open): mean (max)
 * 1 268 (1 775) on Cortex-M3, 1 267 (1 776) on Cortex-M4,
 * 3 642 (4 991) on Cortex-M0; the textbook covariance RLS takes
 * 4 963 in software float and 7 136 in software double on the
 * M3 and 358 on the M4F's FPU (the README's figures table; one run's
 * figures in $(BUILD)/bench/pil.json). The maxima are the rare paths: the
 * first updates after a reset (w >= 1) and the updates that compute the
 * exact trace. A skipped update costs the gate, the regressor block and
 * the prediction error only.
 * Memory: sizeof(canfdi_rls_t) = 352 bytes with the default
 * CANFDI_CFG_RLS_MAX_PARAMS = 6 on a 32-bit target (asserted in
 * canfdi_rls.c on the target builds): 4 bytes per U entry and theta, 8 per
 * D element, 12 per regressor for the gate's mean and measure, the cfg
 * copy. Caller-owned, no heap, no globals; an update uses about 450 bytes
 * of stack with n_max = 6 (440 on the Cortex-M0: canfdi_rls_update 144,
 * its column pass 200, the exact trace 96; tests/pil/footprint.py measures
 * the worst case). The reciprocal's seed table is 1028 bytes of flash
 * (core/canfdi_fixp.c).
 */
#ifndef CANFDI_RLS_H
#define CANFDI_RLS_H

#include "core/canfdi_common.h"
#include "core/canfdi_fixp.h"


#define CANFDI_RLS_N_U ((CANFDI_CFG_RLS_MAX_PARAMS * (CANFDI_CFG_RLS_MAX_PARAMS - 1U)) / 2U)

/* Largest excitation threshold (Q16.16, 2^14): the measure saturates there. */
#define CANFDI_RLS_EXCITE_MIN_MAX_Q16 ((int32_t)1 << 30)
/* Lowest exponent of the theta block (a block of zeros keeps its own). */
#define CANFDI_RLS_THETA_EMIN (-1000000)

/* A signed number m 2^e with 2^29 <= |m| < 2^30, or m == 0: the read-out
 * form of canfdi_rls_d(). */
typedef struct {
  int32_t m;
  int32_t e;
} canfdi_rls_xf_t;

/* A positive number (m / 2^32) 2^e with 2^31 <= m < 2^32, i.e. in
 * [2^(e-1), 2^e), or m == 0 (internal). */
typedef struct {
  uint32_t m;
  int32_t e;
} canfdi_rls_pf_t;

typedef struct {
  uint8_t n_params;                          /* 1 .. CANFDI_CFG_RLS_MAX_PARAMS */
  int8_t phi_shift[CANFDI_CFG_RLS_MAX_PARAMS]; /* s_i: phi_norm = phi 2^-s_i, -32..32 */
  int8_t y_shift;                            /* s_y, -32..32 */
  canfdi_q31_t forget_q31;     /* 1 - lambda in Q31, 0 (no forgetting) .. 0.5 */
  int32_t p0_q16;              /* initial P = p0 I, normalised units, > 0 */
  int32_t trace_max_q16;       /* trace bound, normalised units, >= n p0 */
  int32_t excite_min_q16;      /* gate threshold, mean-square normalised
                                * deviation (Q16.16, 0 .. 2^14; 0: always
                                * update) */
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
  uint32_t trace_clips; /* times P was scaled down to the trace bound */
  uint32_t resets;      /* canfdi_rls_reset calls (init counts as none) */
  uint32_t boosts;      /* canfdi_rls_boost calls */
  uint32_t saturations; /* d_j c0 floored at about 2^-61 */
} canfdi_rls_diag_t;

typedef struct {
  canfdi_rls_cfg_t cfg;
  int32_t theta[CANFDI_CFG_RLS_MAX_PARAMS]; /* normalised theta_i = theta[i] 2^theta_e */
  int32_t theta_e;
  int32_t u[CANFDI_RLS_N_U]; /* strict upper triangle, column-wise: u_ij (i < j)
                              * = u[j (j - 1) / 2 + i] 2^u_e[j] */
  int16_t u_e[CANFDI_CFG_RLS_MAX_PARAMS];
  canfdi_rls_pf_t d[CANFDI_CFG_RLS_MAX_PARAMS]; /* P = U D U^T c0 */
  canfdi_rls_pf_t c0;            /* the common scale of D: P = U D U^T c0 */
  canfdi_rls_pf_t inv_lambda;    /* 1 / lambda, from cfg */
  canfdi_rls_pf_t trb_grow;      /* (1 / lambda) (1 + 2^-20): trb's growth per update */
  canfdi_rls_pf_t trace_max;
  canfdi_rls_pf_t trb;           /* upper bound of trace(P) */
  int64_t excite[CANFDI_CFG_RLS_MAX_PARAMS]; /* filtered squared normalised deviation, Q46 */
  int32_t mean[CANFDI_CFG_RLS_MAX_PARAMS];   /* running means of the normalised phi, Q23 */
  canfdi_rls_pf_t err;        /* last a-priori error |e| (normalised) and its sign */
  bool err_neg;
  bool primed;                /* means initialised from a first sample */
  bool excited;               /* last gate decision */
  uint8_t clog2n;             /* ceil(log2 n) */
  bool fixed_x;               /* every shift in X_SHIFT_MIN..X_SHIFT_MAX: the
                               * regressor block may take the fixed format */
  canfdi_rls_diag_t diag;
} canfdi_rls_t;

/*
 * Validates cfg and resets (theta = theta0, P = p0 I).
 * Returns CANFDI_OK or -CANFDI_EINVAL (NULL, n out of range, shift out of
 * -32..32, forget outside [0, 0.5], p0 <= 0, trace_max < n p0, excite_min
 * < 0, excite_shift outside 1..16, excite_mask bits at or above n); *r is
 * unchanged on error.
 * Cost: one reciprocal and O(n^2) stores.
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
 * Self-check (as o1heap's do_invariants_hold): every d_j and c0 > 0 and
 * normalised, every block within 2^30, trace(P) <= trace_max (1 + 2^-20).
 * O(n^2). For tests and a periodic background check.
 */
bool canfdi_rls_invariants_hold(const canfdi_rls_t *r);

const canfdi_rls_diag_t *canfdi_rls_diag(const canfdi_rls_t *r);

#endif /* CANFDI_RLS_H */
