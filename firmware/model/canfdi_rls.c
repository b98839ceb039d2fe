/*
 * canfdi_rls.c — UD-factorised RLS with forgetting; see canfdi_rls.h for the
 * number formats, their ranges and the precision kept.
 */
#include "model/canfdi_rls.h"

#include "core/canfdi_count.h"
#include "core/canfdi_intrin.h"

#define NMAX CANFDI_CFG_RLS_MAX_PARAMS

typedef canfdi_rls_pf_t pf_t;
typedef canfdi_rls_xf_t xf_t;

/* Block mantissas (regressors, U columns, theta, the gain vector) stay
 * within +-2^30, so that a product of two is below 2^60 and a sum of up to
 * eight of them fits an int64_t. A block is renormalised only when it
 * leaves [2^28, 2^30] (BLK_LO .. BLK_MAX). */
#define BLK_MAX ((int32_t)1 << 30)
#define BLK_LO ((uint32_t)1 << 28)
/* Finest exponent of a U column: entries carry 2^-30 absolute resolution at
 * least (the unit diagonal dominates f and P below that). */
#define U_EMIN (-30)
/* Smallest D element: d_j c0 >= about 2^-61 (see the header). */
#define D_FLOOR_REL 60
/* Exponent window of c0 (the D elements move against it, exactly). */
#define C0_EMIN (-100)
#define C0_EMAX 200
#define C0_SHIFT 128
/* The gate's normalised regressor (Q23) is clipped to +-(2^30 - 1), i.e.
 * +-128, and its deviation from the mean to +-2^30. */
#define GATE_Z_MAX (((int32_t)1 << 30) - 1)
#define GATE_DEV_MAX ((int32_t)1 << 30)
/* The regressor block's fixed format: phi_q16 2^(10 - s) (Q26 normalised,
 * exact for s <= 10), used whenever every |phi_norm| < 16; and the shifts
 * for which it is defined (a left shift of 0..30 bits). */
#define X_FIX_E (-26)
#define X_SHIFT_MIN (-20)
#define X_SHIFT_MAX 10

CANFDI_STATIC_ASSERT(CANFDI_CFG_RLS_MAX_PARAMS >= 1U, rls_max_params_positive);
CANFDI_STATIC_ASSERT(CANFDI_CFG_RLS_MAX_PARAMS <= 7U, rls_max_params_fit_int64_sums);
#if defined(__arm__)
/* The size the header states for the default configuration (32-bit ARM). */
CANFDI_STATIC_ASSERT((CANFDI_CFG_RLS_MAX_PARAMS != 6U) || (sizeof(canfdi_rls_t) == 352U), rls_size_as_stated);
#endif

/* ------------------------------------------------------------------------ */
/* Positive floats (m / 2^32) 2^e, m in [2^31, 2^32)                        */
/* ------------------------------------------------------------------------ */

static const pf_t PF_ZERO = {0U, 0};

/* Leading zeros of x when x >= 2^30 (0 or 1): one CLZ where it exists, a
 * shift and an XOR elsewhere (the same value). */
static inline __attribute__((always_inline)) uint32_t lz01(uint32_t x)
{
#if defined(__ARM_FEATURE_CLZ)
  return canfdi_clz32(x);
#else
  return (x >> 31) ^ 1U;
#endif
}

/* m 2^e (any m) as a pf; m == 0 gives PF_ZERO. Exact. */
static pf_t pf_make(uint32_t m, int32_t e)
{
  pf_t r = PF_ZERO;
  if (m != 0U) {
    const unsigned lz = canfdi_clz32(m);
    r.m = m << lz;
    r.e = (e + 32) - (int32_t)lz;
  }
  return r;
}

/*
 * v 2^e (v != 0) as a pf: its top 32 bits, truncated (relative error
 * below 2^-31). Cost: one or two CLZ and three shifts.
 */
static inline __attribute__((always_inline)) pf_t pf_from_u64(uint64_t v, int32_t e)
{
  pf_t r;
  const uint32_t hi = (uint32_t)(v >> 32);
  const uint32_t lo = (uint32_t)v;
  if (hi != 0U) {
    const unsigned s = canfdi_clz32(hi);
    r.m = (hi << s) | ((lo >> 1) >> (31U - s));
    r.e = (e + 64) - (int32_t)s;
  } else {
    const unsigned s = canfdi_clz32(lo);
    r.m = lo << s;
    r.e = (e + 32) - (int32_t)s;
  }
  return r;
}

/*
 * a b for normalised a, b (not zero). Scaling and overflow: the 64-bit
 * product of the mantissas lies in [2^62, 2^64); its top 32 bits are kept
 * (one more bit when it is below 2^63), truncated: relative error below
 * 2^-31. Exponents add (they stay far inside int32_t: see the header's
 * range statement). Cost: UMULL, CLZ and five ALU instructions.
 */
static inline __attribute__((always_inline)) pf_t pf_mul(pf_t a, pf_t b)
{
  const uint64_t p = canfdi_umull32(a.m, b.m);
  const uint32_t hi = (uint32_t)(p >> 32);
  const uint32_t s = lz01(hi);
  pf_t r;
  r.m = (hi << s) | (((uint32_t)p >> 31) & s);
  r.e = (a.e + b.e) - (int32_t)s;
  return r;
}

/*
 * a + b for normalised a, b (not zero). Scaling and overflow: the smaller
 * addend is aligned to the larger one (its bits below the larger one's last
 * are dropped) and a carry out of 32 bits shifts the sum down one bit
 * (dropped): error below 2 ulp.
 */
static inline __attribute__((always_inline)) pf_t pf_add(pf_t a, pf_t b)
{
  const bool swap = (b.e > a.e);
  const uint32_t hm = swap ? b.m : a.m;
  const uint32_t lm = swap ? a.m : b.m;
  const int32_t he = swap ? b.e : a.e;
  const uint32_t d = (uint32_t)(he - (swap ? a.e : b.e));
  const uint32_t l = (d < 32U) ? (lm >> d) : 0U;
  const uint64_t s = (uint64_t)hm + l;
  pf_t r;
  if (s > 0xFFFFFFFFU) {
    r.m = (uint32_t)(s >> 1);
    r.e = he + 1;
  } else {
    r.m = (uint32_t)s;
    r.e = he;
  }
  return r;
}

/* a < b for pf values (zero allowed). */
static bool pf_lt(pf_t a, pf_t b)
{
  bool lt;
  if ((a.m == 0U) || (b.m == 0U)) {
    lt = (b.m != 0U);
  } else {
    lt = (a.e < b.e) || ((a.e == b.e) && (a.m < b.m));
  }
  return lt;
}

/*
 * 1 / a for a > 0: q 2^(1 - e - 32) with q ~ 2^63 / m (canfdi_recip_q63:
 * from below, within 2^-30.4), normalised. Cost: two table loads, three
 * 32x32->64 multiplies.
 */
static pf_t pf_recip(pf_t a)
{
  const uint32_t q = canfdi_recip_q63(a.m);
  pf_t r;
  CANFDI_ASSERT(a.m >= 0x80000000U);
  r.m = q;
  r.e = 1 - a.e;
  if (q < 0x80000000U) {
    r.m = q << 1;
    r.e -= 1;
  }
  return r;
}

/* ------------------------------------------------------------------------ */
/* Signed numbers for the read-outs (not on the update's path)              */
/* ------------------------------------------------------------------------ */

/* v 2^e as an xf (mantissa 2^29 <= |m| < 2^30), rounded half up on the
 * magnitude. */
static xf_t xf_make(int64_t v, int32_t e)
{
  xf_t r = {0, 0};
  if (v != 0) {
    const bool neg = (v < 0);
    const uint64_t mag = neg ? ((uint64_t)(-(v + 1)) + 1U) : (uint64_t)v;
    const unsigned z = canfdi_clz64(mag); /* 0 only for 2^63 (INT64_MIN) */
    const uint64_t t = (z == 0U) ? (mag >> 1) : (mag << (z - 1U)); /* top bit at 62 */
    const int32_t et = (e - (int32_t)z) + 1;
    uint32_t m = (uint32_t)(t >> 33) + (uint32_t)((t >> 32) & 1U);
    r.e = et + 33;
    if (m == 0x40000000U) {
      m = 0x20000000U;
      r.e += 1;
    }
    r.m = neg ? -(int32_t)m : (int32_t)m;
  }
  return r;
}

static xf_t xf_mul(xf_t a, xf_t b)
{
  return xf_make((int64_t)a.m * (int64_t)b.m, a.e + b.e);
}

/* a + b, the smaller operand aligned with 32 guard bits (rounded). */
static xf_t xf_add(xf_t a, xf_t b)
{
  xf_t r;
  if (a.m == 0) {
    r = b;
  } else if (b.m == 0) {
    r = a;
  } else {
    const xf_t hi = (a.e >= b.e) ? a : b;
    const xf_t lo = (a.e >= b.e) ? b : a;
    const int32_t d = hi.e - lo.e;
    const int64_t lo64 = canfdi_asr64_rnd((int64_t)lo.m * 4294967296LL, (unsigned)((d > 63) ? 63 : d));
    r = xf_make((int64_t)hi.m * 4294967296LL + lo64, hi.e - 32);
  }
  return r;
}

static xf_t xf_from_pf(pf_t a, bool neg)
{
  const int64_t v = (int64_t)a.m;
  return xf_make(neg ? -v : v, a.e - 32);
}

/* round(a 2^frac), saturated to int32_t. */
static int32_t xf_to_s32(xf_t a, int32_t frac)
{
  const int32_t sh = a.e + frac;
  int32_t y = 0;
  if (a.m != 0) {
    if (sh >= 0) {
      y = canfdi_shl32_sat(a.m, (unsigned)((sh > 31) ? 31 : sh));
    } else {
      y = canfdi_asr32_rnd(a.m, (unsigned)((-sh > 32) ? 32 : -sh));
    }
  }
  return y;
}

/* ------------------------------------------------------------------------ */
/* Blocks                                                                   */
/* ------------------------------------------------------------------------ */

/* Where column j of U starts in u[]: j (j - 1) / 2, written so that j = 0
 * does not wrap j - 1 (well defined for unsigned, but the fuzz build's
 * sanitizer flags every wrap that is not by design). */
static unsigned u_base(unsigned j)
{
  return (j == 0U) ? 0U : ((j * (j - 1U)) / 2U);
}

static unsigned u_idx(unsigned i, unsigned j)
{
  CANFDI_ASSERT(i < j);
  return u_base(j) + i;
}

static uint32_t mag32(int32_t x)
{
  return (x < 0) ? (0U - (uint32_t)x) : (uint32_t)x;
}

/* |x| for x >= 0 and |x| - 1 for x < 0: the bits a block's OR needs (a
 * value is within +-2^30 iff this is below 2^30, -2^30 aside). One EOR. */
static inline __attribute__((always_inline)) uint32_t magbits(int32_t x)
{
  return (uint32_t)x ^ (uint32_t)canfdi_asr32(x, 31U);
}

/* floor(x 2^-k) for k in 0..31: one ASR (canfdi_asr32 without its clamp). */
static inline __attribute__((always_inline)) int32_t asr_k(int32_t x, unsigned k)
{
  return (x >= 0) ? (x >> k) : (-1 - ((-1 - x) >> k));
}

/* round(x 2^-k), half up, for k in 1..31 (canfdi_asr32_rnd, always
 * inline: an ASR, an LSR, an AND and an ADD). */
static inline __attribute__((always_inline)) int32_t asr_rnd(int32_t x, unsigned k)
{
  return asr_k(x, k) + (int32_t)(((uint32_t)x >> (k - 1U)) & 1U);
}

/* v[0..n-1] *= 2^-k with rounding (k >= 1; k > 31 clears: |v| < 2^31
 * rounds to 0, as canfdi_asr32_rnd gives). Scaling: the block's exponent
 * rises by k; the caller adds it. The shift inline (asr_rnd): a block
 * shifts in the updates after a covariance reset or boost, entry by
 * entry. */
static void blk_shr(int32_t v[], unsigned n, unsigned k)
{
  unsigned i;
  for (i = 0U; i < n; i++) {
    v[i] = (k < 32U) ? asr_rnd(v[i], k) : 0;
  }
}

/*
 * Keeps a block v[0..n-1] with exponent *e in its format, given acc, the OR
 * of magbits() of its entries: above 2^30 it is shifted down one bit
 * (rounded half up; entries are below 2^31 on entry: the callers' updates
 * add at most 2^27 to entries within 2^30), below 2^28 it is shifted up so
 * that its largest magnitude lies in [2^29, 2^30), or until *e reaches emin
 * (exact). In between it is left alone: the block keeps 28 to 30 bits.
 */
static void blk_fit(int32_t v[], unsigned n, uint32_t acc, int32_t *e, int32_t emin)
{
  unsigned i;
  if (acc >= (uint32_t)BLK_MAX) {
    blk_shr(v, n, 1U);
    *e += 1;
  } else if ((acc != 0U) && (acc < BLK_LO) && (*e > emin)) {
    int32_t k = (int32_t)canfdi_clz32(acc) - 2; /* acc < 2^28: k >= 2 */
    if (k > (*e - emin)) {
      k = *e - emin;
    }
    for (i = 0U; i < n; i++) {
      v[i] = v[i] * ((int32_t)1 << (unsigned)k); /* |v| 2^k < 2^30: exact */
    }
    *e -= k;
  } else {
    /* in range */
  }
}

static uint32_t blk_bits(const int32_t v[], unsigned n)
{
  uint32_t acc = 0U;
  unsigned i;
  for (i = 0U; i < n; i++) {
    acc |= magbits(v[i]);
  }
  return acc;
}

/* ------------------------------------------------------------------------ */

/* trace of the stored factors: sum_j d_j (1 + sum_i u_ij^2); trace(P) is
 * this times c0. */
static pf_t rls_trace_stored(const canfdi_rls_t *r)
{
  const unsigned n = r->cfg.n_params;
  pf_t tr = PF_ZERO;
  unsigned i;
  unsigned j;
  for (j = 0U; j < n; j++) {
    uint64_t s2 = 0U;
    pf_t c = pf_make(1U, 0);
    pf_t t;
    for (i = 0U; i < j; i++) {
      const int64_t u = r->u[u_idx(i, j)];
      s2 += (uint64_t)(u * u);
    }
    if (s2 != 0U) {
      c = pf_add(c, pf_from_u64(s2, 2 * (int32_t)r->u_e[j]));
    }
    t = pf_mul(r->d[j], c);
    tr = (tr.m == 0U) ? t : pf_add(tr, t);
  }
  return tr;
}

int32_t canfdi_rls_init(canfdi_rls_t *r, const canfdi_rls_cfg_t *cfg)
{
  int32_t out = -CANFDI_EINVAL;
  if ((r != NULL) && (cfg != NULL) && (cfg->n_params >= 1U) && (cfg->n_params <= NMAX) &&
      (cfg->forget_q31 >= 0) && (cfg->forget_q31 <= ((int32_t)1 << 30)) && (cfg->p0_q16 > 0) &&
      (cfg->excite_min_q16 >= 0) && (cfg->excite_min_q16 <= CANFDI_RLS_EXCITE_MIN_MAX_Q16) &&
      (cfg->excite_shift >= 1U) && (cfg->excite_shift <= 16U) &&
      (((unsigned)cfg->excite_mask >> cfg->n_params) == 0U) && (cfg->y_shift >= -32) && (cfg->y_shift <= 32) &&
      ((int64_t)cfg->trace_max_q16 >= (int64_t)cfg->n_params * (int64_t)cfg->p0_q16)) {
    bool ok = true;
    unsigned i;
    for (i = 0U; i < cfg->n_params; i++) {
      if ((cfg->phi_shift[i] < -32) || (cfg->phi_shift[i] > 32)) {
        ok = false;
      }
    }
    if (ok) {
      for (i = 0U; i < CANFDI_RLS_N_U; i++) {
        r->u[i] = 0; /* the columns beyond n too: a defined state */
      }
      r->cfg = *cfg;
      r->inv_lambda = pf_recip(pf_make((uint32_t)((int64_t)2147483648LL - (int64_t)cfg->forget_q31), -31));
      r->trb_grow = pf_mul(r->inv_lambda, pf_make(0x80000800U, -31)); /* (1 + 2^-20) */
      r->trace_max = pf_make((uint32_t)cfg->trace_max_q16, -16);
      r->fixed_x = true;
      for (i = 0U; i < cfg->n_params; i++) {
        if ((cfg->phi_shift[i] < X_SHIFT_MIN) || (cfg->phi_shift[i] > X_SHIFT_MAX)) {
          r->fixed_x = false;
        }
      }
      r->clog2n = 0U;
      while ((1U << r->clog2n) < cfg->n_params) {
        r->clog2n++;
      }
      r->diag.updates = 0U;
      r->diag.skipped = 0U;
      r->diag.trace_clips = 0U;
      r->diag.resets = 0U;
      r->diag.boosts = 0U;
      r->diag.saturations = 0U;
      canfdi_rls_reset(r, false);
      r->diag.resets = 0U;
      out = CANFDI_OK;
    }
  }
  return out;
}

/* P = p0 I: c0 = 1, D = p0, U = I (column exponents at their floor; the
 * entries of the n columns cleared, the others are never read and stay as
 * canfdi_rls_init left them). The trace bound is the stored factors'
 * trace, summed as rls_trace_stored sums it (the same bits): with U = I
 * each column's term is d_j (d_j times the pf 1 is exact), so the sum is
 * p0 added n - 1 times, without the squares (a covariance reset or boost
 * costs about half as much). */
static void rls_p0(canfdi_rls_t *r)
{
  const unsigned n = r->cfg.n_params;
  const pf_t d0 = pf_make((uint32_t)r->cfg.p0_q16, -16);
  const unsigned nu = u_base(n);
  pf_t tr = d0;
  unsigned i;
  r->c0 = pf_make(1U, 0);
  for (i = 0U; i < NMAX; i++) {
    r->d[i] = (i < n) ? d0 : PF_ZERO;
    r->u_e[i] = (int16_t)U_EMIN;
  }
  for (i = 0U; i < nu; i++) {
    r->u[i] = 0;
  }
  for (i = 1U; i < n; i++) {
    tr = pf_add(tr, d0);
  }
  r->trb = tr;
}

void canfdi_rls_reset(canfdi_rls_t *r, bool keep_theta)
{
  unsigned i;
  CANFDI_ASSERT(r != NULL);
  rls_p0(r);
  for (i = 0U; i < NMAX; i++) {
    r->mean[i] = 0;
    r->excite[i] = 0;
  }
  if (!keep_theta) {
    for (i = 0U; i < NMAX; i++) {
      r->theta[i] = 0;
    }
    r->theta_e = CANFDI_RLS_THETA_EMIN;
    for (i = 0U; i < r->cfg.n_params; i++) {
      canfdi_rls_set_theta_qn(r, i, r->cfg.theta0_q16[i], 16U);
    }
  }
  r->err = PF_ZERO;
  r->err_neg = false;
  r->primed = false;
  r->excited = false;
  canfdi_count_inc(&r->diag.resets);
}

void canfdi_rls_boost(canfdi_rls_t *r)
{
  CANFDI_ASSERT(r != NULL);
  /* P = p0 I as canfdi_rls_reset, nothing else touched */
  rls_p0(r);
  canfdi_count_inc(&r->diag.boosts);
}

/* The gated regressors as a bit mask (excite_mask, or all when 0). */
static unsigned rls_gate_mask(const canfdi_rls_t *r)
{
  const unsigned m = r->cfg.excite_mask;
  return (m != 0U) ? m : ((1U << r->cfg.n_params) - 1U);
}

/* The gate's measure in Q46: the minimum over the gated regressors. */
static int64_t rls_excitation_q46(const canfdi_rls_t *r)
{
  int64_t m = INT64_MAX;
  unsigned mask = rls_gate_mask(r);
  unsigned i = 0U;
  while (mask != 0U) {
    if (((mask & 1U) != 0U) && (r->excite[i] < m)) {
      m = r->excite[i];
    }
    mask >>= 1;
    i++;
  }
  return m;
}

/*
 * floor(x / 2^k) for k in 1..31 on the two 32-bit halves (a run-time
 * 64-bit shift is a libgcc call on ARMv6-M). Scaling and overflow: format-
 * agnostic, cannot overflow. Rounding: floor.
 */
static inline __attribute__((always_inline)) int64_t asr64_k(int64_t x, unsigned k)
{
  const uint64_t u = (uint64_t)x;
  const uint32_t hi = (uint32_t)(u >> 32);
  const uint32_t lo = ((uint32_t)u >> k) | (hi << (32U - k));
  const int32_t h = asr_k(canfdi_wrap_u32_to_s32(hi), k);
  return canfdi_wrap_u64_to_s64(((uint64_t)(uint32_t)h << 32) | lo);
}

/* The gate's normalised regressor phi_q16 2^(7 - s) in Q23, clipped to
 * +-(2^30 - 1) (i.e. +-128): a left shift with saturation or a right shift
 * rounded half up. */
static int32_t gate_z(int32_t p, int32_t s)
{
  const int32_t l = 7 - s;
  int32_t z;
  if (l >= 0) {
    const int32_t lim = (l > 30) ? 0 : (GATE_Z_MAX >> (unsigned)l);
    const int32_t pc = (p > lim) ? lim : ((p < -lim) ? -lim : p);
    z = pc * ((int32_t)1 << (unsigned)((l > 30) ? 0 : l));
  } else {
    z = canfdi_asr32_rnd(p, (unsigned)-l); /* |z| <= 2^30 */
    z = (z > GATE_Z_MAX) ? GATE_Z_MAX : ((z < -GATE_Z_MAX) ? -GATE_Z_MAX : z);
  }
  return z;
}

/*
 * The regressors as one block x[i] 2^ex (normalised units, |x| <= 2^30) and
 * x^T theta (one exact 64-bit sum: products below 2^60); returns ex.
 * Fixed format when the configuration allows it and every |phi_norm| < 16:
 * x = phi_q16 2^(10 - s) exactly, ex = -26. Otherwise a dynamic block, the
 * largest in [2^29, 2^30]: phi_i 2^-(16 + s_i) is shifted exactly (left) or
 * rounded half up (right, when regressors differ by more than 2^30 in
 * normalised size: the small one keeps fewer bits, see the header).
 */
static int32_t rls_block(const canfdi_rls_t *r, const int32_t phi_q16[], int32_t x[], int64_t *xt, bool *xfix)
{
  const unsigned n = r->cfg.n_params;
  int32_t ex = X_FIX_E;
  int64_t acc = 0;
  bool fits;
  uint32_t over = r->fixed_x ? 0U : 1U;
  unsigned i;
  if (over == 0U) {
    for (i = 0U; i < n; i++) {
      const int32_t p = phi_q16[i];
      const int32_t sh = (int32_t)r->cfg.phi_shift[i]; /* -20..10 */
      const uint32_t o = magbits(p) >> (unsigned)(20 + sh); /* |p| 2^(10 - s) > 2^30 */
      const int32_t v = (o == 0U) ? (p * ((int32_t)1 << (unsigned)(10 - sh))) : 0;
      over |= o;
      x[i] = v;
      acc += canfdi_smull32(r->theta[i], v);
    }
  }
  fits = (over == 0U);
  if (!fits) {
    int32_t top = INT32_MIN;
    acc = 0;
    for (i = 0U; i < n; i++) {
      const uint32_t m = mag32(phi_q16[i]);
      if (m != 0U) {
        const int32_t t = (16 - (int32_t)canfdi_clz32(m)) - (int32_t)r->cfg.phi_shift[i];
        top = (t > top) ? t : top;
      }
    }
    ex = (top == INT32_MIN) ? 0 : (top - 30);
    for (i = 0U; i < n; i++) {
      const int32_t p = phi_q16[i];
      const int32_t l = (-16 - (int32_t)r->cfg.phi_shift[i]) - ex; /* left shift */
      int32_t v = 0;
      if (p == 0) {
        /* its shift may exceed 31 (only a nonzero regressor bounds it) */
      } else if (l >= 0) {
        v = p * ((int32_t)1 << (unsigned)l); /* < 2^30 by choice of ex */
      } else {
        v = canfdi_asr32_rnd(p, (unsigned)-l);
      }
      x[i] = v;
      acc += canfdi_smull32(r->theta[i], v);
    }
  }
  *xt = acc;
  *xfix = fits;
  return ex;
}

/*
 * Excitation measure and gate; updates the running means of the gated
 * regressors (the others are never read). The normalised regressor z in
 * Q23 (gate_z; from the block when it has the fixed format: round(x / 8),
 * the same value) is clipped to +-(2^30 - 1) (+-128 normalised). Scaling
 * and overflow: z and its mean (a convex combination of such values,
 * rounded half up: dead zone 2^(k-24) normalised, which adds at most
 * 2^(2k-48) to the measure) give a deviation below 2^31; it is clipped to
 * +-2^30, so its square (Q46) stays below 2^60 and the filtered measure
 * too (floor: at most 2^-46 low).
 */
static bool rls_gate(canfdi_rls_t *r, const int32_t phi_q16[], const int32_t x[], bool xfix)
{
  const unsigned k = r->cfg.excite_shift;
  unsigned mask = rls_gate_mask(r);
  int64_t m = INT64_MAX;
  unsigned i;
  if (!r->primed) {
    for (i = 0U; i < r->cfg.n_params; i++) {
      r->mean[i] = xfix ? asr_rnd(x[i], 3U) : gate_z(phi_q16[i], r->cfg.phi_shift[i]);
      r->excite[i] = 0;
    }
    r->primed = true;
  }
  i = 0U;
  while (mask != 0U) {
    if ((mask & 1U) != 0U) {
      const int32_t z = xfix ? asr_rnd(x[i], 3U) : gate_z(phi_q16[i], r->cfg.phi_shift[i]);
      int32_t dev = z - r->mean[i];
      int64_t ex = r->excite[i];
      r->mean[i] += asr_rnd(dev, k);
      dev = (dev > GATE_DEV_MAX) ? GATE_DEV_MAX : ((dev < -GATE_DEV_MAX) ? -GATE_DEV_MAX : dev);
      ex += asr64_k(canfdi_smull32(dev, dev) - ex, k);
      r->excite[i] = ex;
      m = (ex < m) ? ex : m;
    }
    mask >>= 1;
    i++;
  }
  return (r->cfg.excite_min_q16 == 0) || (m >= ((int64_t)r->cfg.excite_min_q16 * 1073741824LL));
}

/*
 * The prediction error y_norm - x^T theta as a float with sign (r->err,
 * r->err_neg), from xt = x^T theta 2^-(theta_e + ex). Scaling and overflow:
 * xt is aligned to y 2^16 (16 guard bits below y's last bit, floor), the
 * difference below 2^49. When the sum carries bits above that
 * format (theta or x beyond their usual range) the signed xf path takes
 * over (rounded to 30 bits).
 */
static void rls_error(canfdi_rls_t *r, int64_t xt, int32_t ex, int32_t y_q16)
{
  const int32_t ey = -32 - (int32_t)r->cfg.y_shift; /* y 2^16 */
  const int32_t d = ey - (r->theta_e + ex);
  if (d >= 1) {
    const int64_t v = ((int64_t)y_q16 * 65536) - ((d <= 31) ? asr64_k(xt, (unsigned)d) : canfdi_asr64(xt, (unsigned)d));
    r->err_neg = (v < 0);
    r->err = (v == 0) ? PF_ZERO : pf_from_u64(r->err_neg ? ((uint64_t)(-(v + 1)) + 1U) : (uint64_t)v, ey);
  } else {
    const xf_t e = xf_add(xf_make(y_q16, -16 - (int32_t)r->cfg.y_shift), xf_make(-xt, r->theta_e + ex));
    r->err_neg = (e.m < 0);
    r->err = pf_make(mag32(e.m), e.e);
  }
}

/* trunc(m 2^-s) with the sign mask neg (0 or all ones), for a mantissa
 * m < 2^32 and s >= 1 (|result| <= 2^31 - 1); s > 31 gives 0. Truncation
 * toward zero (one unit of the multiplier at most). */
static inline __attribute__((always_inline)) int32_t fix_mul(uint32_t m, int32_t s, uint32_t neg)
{
  const uint32_t v = (s <= 31) ? (m >> (unsigned)s) : 0U;
  CANFDI_ASSERT(s >= 1);
  return canfdi_wrap_u32_to_s32((v ^ neg) - neg);
}

/* The out-of-format part of blk_fit: called only when acc is outside
 * [2^28, 2^30) (or the exponent could still fall). */
static inline __attribute__((always_inline)) void blk_keep(int32_t v[], unsigned n, uint32_t acc, int32_t *e,
                                                          int32_t emin)
{
  if ((acc >= (uint32_t)BLK_MAX) || ((acc < BLK_LO) && (acc != 0U) && (*e > emin))) {
    blk_fit(v, n, acc, e, emin);
  }
}

/*
 * Bierman's update of column j >= 1 (f_j != 0): for i < j
 * u_ij += b_i mu_j (mu_j = -f_j / a_j = -h, multiplier mm) and
 * b_i += u_ij g_j (old u_ij; multiplier gg). Scaling and overflow: the gain
 * block b[] 2^eb keeps every partial sum below 2^30 (see rls_apply); each
 * multiplier is an int32_t (shift >= 1), so an update adds less than 2^29
 * to an entry within 2^30. A column whose update would need a larger
 * multiplier is shifted down in the same loop (its exponent rises); the
 * column is then kept in format (blk_keep). Rounding: half up in every
 * product (canfdi_mla_hi_rnd) and shift; the multipliers are truncated.
 */
static void rls_column(int32_t col[], unsigned j, int16_t *col_e, uint32_t hm, int32_t he, uint32_t gm, int32_t ge,
                       uint32_t neg, int32_t b[], int32_t eb)
{
  int32_t ue = (int32_t)*col_e;
  const int32_t s = (ue - eb) - he;
  const int32_t gg = fix_mul(gm, (eb - ue) - ge, neg);
  uint32_t acc = 0U;
  unsigned i;
  if (s >= 1) {
    const int32_t mm = fix_mul(hm, s, ~neg);
    for (i = 0U; i < j; i++) {
      const int32_t uo = col[i];
      const int32_t un = canfdi_mla_hi_rnd(uo, b[i], mm);
      col[i] = un;
      acc |= magbits(un);
      b[i] = canfdi_mla_hi_rnd(b[i], uo, gg);
    }
  } else {
    /* the column outgrows its format: shifted down so that the
     * multiplier fits (s = 1); b takes the old entries */
    const unsigned sh = (unsigned)(1 - s);
    const int32_t mm = fix_mul(hm, 1, ~neg);
    ue += 1 - s;
    for (i = 0U; i < j; i++) {
      const int32_t uo = col[i];
      const int32_t un = canfdi_mla_hi_rnd((sh > 31U) ? 0 : asr_rnd(uo, sh), b[i], mm);
      col[i] = un;
      acc |= magbits(un);
      b[i] = canfdi_mla_hi_rnd(b[i], uo, gg);
    }
  }
  blk_keep(col, j, acc, &ue, U_EMIN);
  *col_e = (int16_t)ue;
}

/* theta += b k (k = e / a_n = km 2^(ke - 32), km in [2^30, 2^32)). Scaling:
 * the block rises first when the update would exceed it (a block of zeros
 * carries the lowest exponent, so it takes the update's format); then kept
 * in format. Rounding half up. */
static void rls_theta_update(canfdi_rls_t *r, const int32_t b[], int32_t eb, uint32_t km, int32_t ke, uint32_t kneg)
{
  const unsigned n = r->cfg.n_params;
  int32_t s = (r->theta_e - eb) - ke;
  int32_t kk;
  uint32_t acc = 0U;
  unsigned i;
  if (s < 1) {
    blk_shr(r->theta, n, (unsigned)(1 - s));
    r->theta_e += 1 - s;
    s = 1;
  }
  kk = fix_mul(km, s, kneg);
  for (i = 0U; i < n; i++) {
    const int32_t t = canfdi_mla_hi_rnd(r->theta[i], b[i], kk);
    r->theta[i] = t;
    acc |= magbits(t);
  }
  blk_keep(r->theta, n, acc, &r->theta_e, CANFDI_RLS_THETA_EMIN);
}

/*
 * Trace bound (P scaled through c0) and the exponent window of c0. An
 * update cannot raise trace(P) by more than 1 / lambda (trace(P') <=
 * trace(P) / lambda), so trb grows by that, and 2^-20 more for the
 * rounding of the factors, per update; the exact trace is computed only
 * when trb reaches trace_max.
 */
static void rls_bound(canfdi_rls_t *r)
{
  unsigned j;
  r->trb = pf_mul(r->trb, r->trb_grow);
  if (pf_lt(r->trace_max, r->trb)) {
    const pf_t s = rls_trace_stored(r);
    pf_t tr = pf_mul(s, r->c0);
    if (pf_lt(r->trace_max, tr)) {
      r->c0 = pf_mul(r->trace_max, pf_recip(s));
      tr = pf_mul(s, r->c0);
      canfdi_count_inc(&r->diag.trace_clips);
    }
    r->trb = tr;
  }
  if ((r->c0.e < C0_EMIN) || (r->c0.e > C0_EMAX)) {
    const int32_t k = (r->c0.e < C0_EMIN) ? C0_SHIFT : -C0_SHIFT;
    r->c0.e += k;
    for (j = 0U; j < r->cfg.n_params; j++) {
      r->d[j].e -= k;
    }
  }
}

/* The high word of the 64-bit product of two unsigned 32-bit numbers. */
static inline __attribute__((always_inline)) uint32_t umulhi(uint32_t a, uint32_t b)
{
  return canfdi_umulhi32(a, b);
}

/* Column j's g = d_j f_j (normalised) and h = f_j / alpha_j (the high word
 * of the mantissa product, >= 2^30), for the multipliers. */
typedef struct {
  uint32_t gm;
  int32_t ge;
  uint32_t hm;
  int32_t he;
} rls_gh_t;

/*
 * The scalar part of column j for f_j = fm 2^(fe - 32) (normalised, not 0):
 * g and h into *o, then w = g h, rho = 1 / (1 + w) = alpha_j / alpha_(j+1),
 * d_j *= rho (floored at 2^d_floor_e) and inv *= rho (inv = im 2^(ie - 32)
 * = 1 / alpha_j). For w < 1 (the common case: v = 1 + w in [1, 2) needs no
 * alignment) rho is a Q32 fraction from one division and one Newton step
 * (2^-29 at worst, below 2^-31 on average); else v and rho are pf.
 */
static inline __attribute__((always_inline)) void rls_step(canfdi_rls_t *r, unsigned j, uint32_t fm, int32_t fe,
                                                          uint32_t *im, int32_t *ie, int32_t d_floor_e, rls_gh_t *o)
{
  const pf_t dj = r->d[j];
  pf_t dn;
  uint32_t wh;
  int32_t k;
  {
    const uint64_t pg = canfdi_umull32(dj.m, fm);
    const uint32_t gh = (uint32_t)(pg >> 32);
    const uint32_t sg = lz01(gh);
    o->gm = (gh << sg) | (((uint32_t)pg >> 31) & sg);
    o->ge = (dj.e + fe) - (int32_t)sg;
  }
  o->hm = umulhi(fm, *im);
  o->he = fe + *ie;
  wh = umulhi(o->gm, o->hm); /* w = wh 2^(ge + he - 32), wh >= 2^29 */
  k = 1 - (o->ge + o->he);
  if (k >= 1) {
    const uint32_t v = 0x80000000U + ((k < 32) ? (wh >> (unsigned)k) : 0U);
    uint32_t q = canfdi_recip_q63(v);
    q = (q < 0x80000000U) ? 0x80000000U : q;
    {
      const uint64_t pd = canfdi_umull32(dj.m, q);
      const uint32_t dh = (uint32_t)(pd >> 32);
      const uint32_t sd = lz01(dh);
      dn.m = (dh << sd) | (((uint32_t)pd >> 31) & sd);
      dn.e = dj.e - (int32_t)sd;
    }
    {
      const uint64_t pi = canfdi_umull32(*im, q);
      const uint32_t ih = (uint32_t)(pi >> 32);
      const uint32_t si = lz01(ih);
      *im = (ih << si) | (((uint32_t)pi >> 31) & si);
      *ie -= (int32_t)si;
    }
  } else {
    const unsigned sw = canfdi_clz32(wh);
    const pf_t one = {0x80000000U, 1};
    const pf_t wf = {wh << sw, (o->ge + o->he) - (int32_t)sw};
    const pf_t v = pf_add(one, wf);
    const pf_t rho = pf_recip(v);
    const pf_t inv = {*im, *ie};
    const pf_t ni = pf_mul(inv, rho);
    dn = pf_mul(dj, rho);
    *im = ni.m;
    *ie = ni.e;
  }
  if (dn.e < d_floor_e) {
    dn.m = 0x80000000U;
    dn.e = d_floor_e;
    canfdi_count_inc(&r->diag.saturations);
  }
  r->d[j] = dn;
}

/* f from a 64-bit sum: |acc| < 7 2^60, not 0; fm normalised, *fe its
 * exponent for acc 2^e; returns the sign as a mask. */
static inline __attribute__((always_inline)) uint32_t rls_f(int64_t acc, int32_t e, uint32_t *fm, int32_t *fe)
{
  const uint32_t neg = (acc < 0) ? 0xFFFFFFFFU : 0U;
  const uint64_t mag = (neg != 0U) ? ((uint64_t)(-(acc + 1)) + 1U) : (uint64_t)acc;
  const uint32_t mh = (uint32_t)(mag >> 32);
  if (mh != 0U) {
    const unsigned sf = canfdi_clz32(mh); /* >= 1 */
    *fm = (mh << sf) | ((uint32_t)mag >> (32U - sf));
    *fe = (e + 64) - (int32_t)sf;
  } else {
    const unsigned sf = canfdi_clz32((uint32_t)mag);
    *fm = (uint32_t)mag << sf;
    *fe = (e + 32) - (int32_t)sf;
  }
  return neg;
}

/*
 * One applied update on the regressor block x 2^ex (the error is in r), in
 * one pass over the columns (Bierman's measurement update in ratio form).
 * With alpha_0 = lambda / c0 and alpha_(j+1) = alpha_j + d_j f_j^2, the pass
 * carries inv = 1 / alpha_j: per column j, f_j = x_j + sum_(i<j) u_ij x_i
 * (one 64-bit sum: the products are below 2^60, x_j 2^-u_e below 2^60),
 * g_j = d_j f_j (f's sign), h = f_j inv, w = g_j h = d_j f_j^2 / alpha_j,
 * rho = 1 / (1 + w) = alpha_j / alpha_(j+1); then d_j *= rho, inv *= rho
 * (rls_step), the column update (rls_column) and b_j = g_j, so that b ends
 * as U g (in the block b[] 2^eb) and the gain is b / alpha_n = b inv. The
 * scale c0 becomes c0 / lambda = 1 / alpha_0 (forgetting). Column 0 has no U
 * entries: f_0 = x_0.
 * Gain block: b_i = sum_(k >= i) u_ik g_k < n 2^(30 + max(u_e + g.e)),
 * so eb = max(u_e + g.e) + ceil(log2 n) keeps it below 2^30; eb follows
 * the maximum column by column (b[0..j-1] shifted down, rounded, when a
 * column raises it). Column 0 counts with u_e = -30.
 */
static __attribute__((noinline)) void rls_apply(canfdi_rls_t *r, const int32_t x[], int32_t ex)
{
  const unsigned n = r->cfg.n_params;
  const int32_t hd = (int32_t)r->clog2n;
  int32_t b[NMAX];
  int32_t eb = INT32_MIN;
  const pf_t c0 = pf_mul(r->c0, r->inv_lambda); /* 1 / alpha_0, the new c0 */
  const int32_t d_floor_e = -D_FLOOR_REL - c0.e;
  uint32_t im = c0.m; /* inv = 1 / alpha_j */
  int32_t ie = c0.e;
  int32_t *col = r->u;
  unsigned i;
  unsigned j;
  r->c0 = c0;
  b[0] = 0;
  if (x[0] != 0) {
    rls_gh_t o;
    uint32_t fm;
    int32_t fe;
    const uint32_t neg = rls_f(x[0], ex, &fm, &fe);
    rls_step(r, 0U, fm, fe, &im, &ie, d_floor_e, &o);
    eb = (o.ge + U_EMIN) + hd;
    b[0] = fix_mul(o.gm, (32 + eb) - o.ge, neg);
  }
  for (j = 1U; j < n; j++) {
    const int32_t ue = (int32_t)r->u_e[j];
    int64_t acc;
    if (ue <= 0) {
      acc = canfdi_smull32(x[j], (int32_t)1 << (unsigned)-ue); /* ue >= -30 */
    } else {
      acc = canfdi_asr64_rnd(x[j], (unsigned)ue);
    }
    for (i = 0U; i < j; i++) {
      acc += canfdi_smull32(col[i], x[i]);
    }
    b[j] = 0;
    if (acc != 0) {
      rls_gh_t o;
      uint32_t fm;
      int32_t fe;
      const uint32_t neg = rls_f(acc, ue + ex, &fm, &fe);
      int32_t c;
      rls_step(r, j, fm, fe, &im, &ie, d_floor_e, &o);
      c = (ue + o.ge) + hd;
      if (eb == INT32_MIN) {
        eb = c;
      } else if (c > eb) {
        blk_shr(b, j, (unsigned)(c - eb));
        eb = c;
      } else {
        /* the block holds it */
      }
      rls_column(col, j, &r->u_e[j], o.hm, o.he, o.gm, o.ge, neg, b, eb);
      b[j] = fix_mul(o.gm, (32 + eb) - o.ge, neg);
    }
    col = &col[j];
  }
  if ((r->err.m != 0U) && (eb != INT32_MIN)) {
    rls_theta_update(r, b, eb, umulhi(r->err.m, im), r->err.e + ie, r->err_neg ? 0xFFFFFFFFU : 0U);
  }
  rls_bound(r);
}

bool canfdi_rls_update(canfdi_rls_t *r, const int32_t phi_q16[], int32_t y_q16)
{
  int32_t x[NMAX];
  int64_t xt;
  int32_t ex;
  bool xfix;
  bool go;
  CANFDI_ASSERT((r != NULL) && (phi_q16 != NULL));
  CANFDI_ASSERT((r->cfg.n_params >= 1U) && (r->cfg.n_params <= NMAX) && ((rls_gate_mask(r) >> r->cfg.n_params) == 0U));
  ex = rls_block(r, phi_q16, x, &xt, &xfix);
  go = rls_gate(r, phi_q16, x, xfix);
  rls_error(r, xt, ex, y_q16);
  r->excited = go;
  if (go) {
    rls_apply(r, x, ex);
    canfdi_count_inc(&r->diag.updates);
  } else {
    canfdi_count_inc(&r->diag.skipped);
  }
  return go;
}

/* ------------------------------------------------------------------------ */
/* Read-outs                                                                */
/* ------------------------------------------------------------------------ */

int32_t canfdi_rls_theta_qn(const canfdi_rls_t *r, unsigned i, unsigned frac)
{
  int32_t y = 0;
  CANFDI_ASSERT(r != NULL);
  if ((i < r->cfg.n_params) && (frac <= 31U)) {
    const int32_t x = r->theta[i];
    const int32_t e = (r->theta_e + (int32_t)r->cfg.y_shift) - (int32_t)r->cfg.phi_shift[i];
    if (mag32(x) > (uint32_t)BLK_MAX) {
      /* beyond the block's bound (canfdi_rls_invariants_hold: never):
       * normalised first, rounded to 30 bits */
      y = xf_to_s32(xf_make(x, e), (int32_t)frac);
    } else if (x != 0) {
      /* |x| <= 2^30: xf_make would normalise x 2^e exactly, so x 2^t
       * rounded (half up) or saturated here is the same value; it runs
       * several times a step */
      const int32_t t = e + (int32_t)frac;
      if (t >= 0) {
        y = canfdi_shl32_sat(x, (unsigned)((t > 31) ? 31 : t));
      } else if (t >= -31) {
        y = asr_rnd(x, (unsigned)-t);
      } else {
        /* |x 2^t| <= 1/4: rounds to 0 */
      }
    } else {
      /* 0 */
    }
  }
  return y;
}

void canfdi_rls_set_theta_qn(canfdi_rls_t *r, unsigned i, int32_t value, unsigned frac)
{
  CANFDI_ASSERT(r != NULL);
  if ((i < r->cfg.n_params) && (frac <= 31U)) {
    const unsigned n = r->cfg.n_params;
    const int32_t ev = -(int32_t)frac + (int32_t)r->cfg.phi_shift[i] - (int32_t)r->cfg.y_shift;
    const uint32_t m = mag32(value);
    uint32_t others = 0U;
    unsigned k;
    for (k = 0U; k < n; k++) {
      others |= (k == i) ? 0U : mag32(r->theta[k]);
    }
    r->theta[i] = 0;
    if (m != 0U) {
      const int32_t top = (32 - (int32_t)canfdi_clz32(m)) + ev; /* |value| < 2^top */
      int32_t sh;
      if (others == 0U) {
        r->theta_e = top - 30;
      } else if (top > (r->theta_e + 30)) {
        blk_shr(r->theta, n, (unsigned)(top - 30 - r->theta_e));
        r->theta_e = top - 30;
      } else {
        /* fits the block */
      }
      sh = ev - r->theta_e;
      if (sh >= 0) {
        const uint32_t v = m << (unsigned)sh; /* < 2^30 */
        r->theta[i] = (value < 0) ? -(int32_t)v : (int32_t)v;
      } else {
        r->theta[i] = canfdi_asr32_rnd(value, (unsigned)-sh);
      }
    } else if (others == 0U) {
      r->theta_e = CANFDI_RLS_THETA_EMIN; /* a block of zeros */
    } else {
      /* the others keep the format */
    }
    blk_fit(r->theta, n, blk_bits(r->theta, n), &r->theta_e, CANFDI_RLS_THETA_EMIN);
  }
}

int32_t canfdi_rls_err_q16(const canfdi_rls_t *r)
{
  xf_t e;
  CANFDI_ASSERT(r != NULL);
  e = xf_from_pf(r->err, r->err_neg);
  e.e += (int32_t)r->cfg.y_shift;
  return xf_to_s32(e, 16);
}

int32_t canfdi_rls_cov_qn(const canfdi_rls_t *r, unsigned i, unsigned j, unsigned frac)
{
  int32_t y = 0;
  CANFDI_ASSERT(r != NULL);
  if ((i < r->cfg.n_params) && (j < r->cfg.n_params) && (frac <= 31U)) {
    /* P_ij = sum_{k >= max(i,j)} u_ik d_k u_jk c0, u_kk = 1 */
    const unsigned k0 = (i > j) ? i : j;
    const xf_t one = xf_make(1, 0);
    xf_t s = {0, 0};
    unsigned k;
    for (k = k0; k < r->cfg.n_params; k++) {
      const xf_t uik = (i == k) ? one : xf_make(r->u[u_idx(i, k)], r->u_e[k]);
      const xf_t ujk = (j == k) ? one : xf_make(r->u[u_idx(j, k)], r->u_e[k]);
      s = xf_add(s, xf_mul(xf_mul(uik, ujk), xf_from_pf(r->d[k], false)));
    }
    y = xf_to_s32(xf_mul(s, xf_from_pf(r->c0, false)), (int32_t)frac);
  }
  return y;
}

int32_t canfdi_rls_trace_q16(const canfdi_rls_t *r)
{
  CANFDI_ASSERT(r != NULL);
  return xf_to_s32(xf_mul(xf_from_pf(rls_trace_stored(r), false), xf_from_pf(r->c0, false)), 16);
}

canfdi_rls_xf_t canfdi_rls_d(const canfdi_rls_t *r, unsigned j)
{
  xf_t z = {0, 0};
  CANFDI_ASSERT(r != NULL);
  if (j < r->cfg.n_params) {
    z = xf_mul(xf_from_pf(r->d[j], false), xf_from_pf(r->c0, false));
  }
  return z;
}

int32_t canfdi_rls_excitation_q16(const canfdi_rls_t *r)
{
  int64_t m;
  CANFDI_ASSERT(r != NULL);
  m = rls_excitation_q46(r);
  return (m == INT64_MAX) ? 0 : (int32_t)canfdi_asr64_rnd(m, 30U); /* <= 2^30 */
}

bool canfdi_rls_excited(const canfdi_rls_t *r)
{
  CANFDI_ASSERT(r != NULL);
  return r->excited;
}

static bool blk_ok(const int32_t v[], unsigned n)
{
  bool ok = true;
  unsigned i;
  for (i = 0U; i < n; i++) {
    ok = ok && (mag32(v[i]) <= (uint32_t)BLK_MAX);
  }
  return ok;
}

bool canfdi_rls_invariants_hold(const canfdi_rls_t *r)
{
  bool ok = (r != NULL);
  if (ok) {
    const unsigned n = r->cfg.n_params;
    unsigned j;
    const pf_t lim = pf_add(r->trace_max, pf_make(r->trace_max.m, r->trace_max.e - 52)); /* (1 + 2^-20) */
    ok = (r->c0.m >= 0x80000000U) && blk_ok(r->theta, n);
    for (j = 0U; j < n; j++) {
      ok = ok && (r->d[j].m >= 0x80000000U) && (r->u_e[j] >= U_EMIN) && blk_ok(&r->u[u_base(j)], j);
    }
    ok = ok && !pf_lt(lim, pf_mul(rls_trace_stored(r), r->c0));
  }
  return ok;
}

const canfdi_rls_diag_t *canfdi_rls_diag(const canfdi_rls_t *r)
{
  CANFDI_ASSERT(r != NULL);
  return &r->diag;
}
