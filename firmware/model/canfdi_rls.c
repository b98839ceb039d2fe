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
 * eight of them fits an int64_t. */
#define BLK_MAX ((int32_t)1 << 30)
#define BLK_LO ((int32_t)1 << 29)
/* Finest exponent of a U column: entries carry 2^-30 absolute resolution at
 * least (the unit diagonal dominates f and P below that). */
#define U_EMIN (-30)
/* Smallest D element relative to the scale a0: 2^-60 (see the header). */
#define D_FLOOR_REL 60
/* Exponent window of a0 (the D elements move with it, exactly). */
#define A0_EMIN (-200)
#define A0_EMAX 100
#define A0_SHIFT 128

CANFDI_STATIC_ASSERT(CANFDI_CFG_RLS_MAX_PARAMS >= 1U, rls_max_params_positive);
CANFDI_STATIC_ASSERT(CANFDI_CFG_RLS_MAX_PARAMS <= 7U, rls_max_params_fit_int64_sums);
#if defined(__arm__)
/* The size the header states for the default configuration (32-bit ARM). */
CANFDI_STATIC_ASSERT((CANFDI_CFG_RLS_MAX_PARAMS != 6U) || (sizeof(canfdi_rls_t) == 368U), rls_size_as_stated);
#endif

/* ------------------------------------------------------------------------ */
/* Positive floats m 2^e, m in [2^31, 2^32) or 0                            */
/* ------------------------------------------------------------------------ */

static const pf_t PF_ZERO = {0U, 0};

static inline __attribute__((always_inline)) pf_t pf_make(uint32_t m, int32_t e)
{
  pf_t r = PF_ZERO;
  if (m != 0U) {
    const unsigned lz = canfdi_clz32(m);
    r.m = m << lz;
    r.e = e - (int32_t)lz;
  }
  return r;
}

/*
 * The normalised mantissa m (top bit set) with exponent e, plus one ulp
 * when the first dropped bit rb is set (rounding half up); a carry out of
 * 32 bits renormalises to 2^31 with e + 1.
 */
static inline __attribute__((always_inline)) pf_t pf_round(uint32_t m, int32_t e, uint32_t rb)
{
  pf_t r;
  r.m = m;
  r.e = e;
  if (rb != 0U) {
    if (m == UINT32_MAX) {
      r.m = 0x80000000U;
      r.e += 1;
    } else {
      r.m = m + 1U;
    }
  }
  return r;
}

/*
 * v 2^e rounded to 32 significant bits. Scaling and overflow: exact below
 * 2^32; above, rounded half up, a carry to 2^32 renormalises.
 */
static inline __attribute__((always_inline)) pf_t pf_from_u64(uint64_t v, int32_t e)
{
  pf_t r = PF_ZERO;
  const uint32_t hi = (uint32_t)(v >> 32);
  if (hi == 0U) {
    r = pf_make((uint32_t)v, e);
  } else {
    const unsigned lz = canfdi_clz32(hi);
    const unsigned sh = 32U - lz; /* 1..32: bits below the top 32 */
    const uint64_t t = v >> (sh - 1U);
    r = pf_round((uint32_t)(t >> 1), e + (int32_t)sh, (uint32_t)(t & 1U));
  }
  return r;
}

/*
 * a b. Scaling and overflow: the 64-bit product of two mantissas lies in
 * [2^62, 2^64); its top 32 bits are kept, rounded half up (a carry
 * renormalises). Relative error <= 2^-32. Exponents add (they stay far
 * inside int32_t: see the header's range statement).
 */
static inline __attribute__((always_inline)) pf_t pf_mul(pf_t a, pf_t b)
{
  pf_t r = PF_ZERO;
  if ((a.m != 0U) && (b.m != 0U)) {
    const uint64_t p = (uint64_t)a.m * (uint64_t)b.m;
    const uint32_t hi = (uint32_t)(p >> 32);
    if ((hi & 0x80000000U) == 0U) {
      r = pf_round((hi << 1) | (uint32_t)((p >> 31) & 1U), a.e + b.e + 31, (uint32_t)((p >> 30) & 1U));
    } else {
      r = pf_round(hi, a.e + b.e + 32, (uint32_t)((p >> 31) & 1U));
    }
  }
  return r;
}

/*
 * a + b. Scaling and overflow: the smaller addend is aligned to the larger
 * one's last bit (truncated: error < 1 ulp) and the 33-bit sum is
 * renormalised with rounding half up.
 */
static inline __attribute__((always_inline)) pf_t pf_add(pf_t a, pf_t b)
{
  pf_t r = a;
  if (a.m == 0U) {
    r = b;
  } else if (b.m != 0U) {
    const pf_t hi = (a.e >= b.e) ? a : b;
    const pf_t lo = (a.e >= b.e) ? b : a;
    const int32_t d = hi.e - lo.e;
    if (d < 32) {
      r = pf_from_u64((uint64_t)hi.m + (uint64_t)(lo.m >> (unsigned)d), hi.e);
    } else {
      r = hi;
    }
  }
  return r;
}

/* a < b */
static inline __attribute__((always_inline)) bool pf_lt(pf_t a, pf_t b)
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
 * 1 / a for a > 0: round(2^63 / m) 2^(-e-63). Scaling and overflow: a
 * 16-bit quotient (one 32-bit division) seeds one Newton-Raphson step,
 * q (2 - m q / 2^63), which leaves an error of a few units; the remainder
 * 2^63 - m q then corrects q to the exact floor, and the last step rounds
 * half up. m = 2^31 gives 2^32, stored as 2^31 2^(e'+1). Cost: one UDIV
 * (__aeabi_uidiv on ARMv6-M), three 32x32->64 multiplies, a few
 * corrections.
 */
static pf_t pf_recip(pf_t a)
{
  pf_t r = PF_ZERO;
  CANFDI_ASSERT(a.m != 0U);
  if (a.m != 0U) {
    const uint64_t one = (uint64_t)1 << 63;
    const uint32_t q0 = 0xFFFFFFFFU / ((a.m >> 16) + 1U); /* ~2^48 / m, < 2^17 */
    uint64_t q = (uint64_t)q0 << 15;                     /* ~2^63 / m, low */
    int64_t t = (int64_t)(one - (uint64_t)a.m * q);      /* > 0, < 2^49 */
    q += (q * (uint64_t)(t >> 20)) >> 43;
    t = canfdi_wrap_u64_to_s64(one - ((uint64_t)a.m * q));
    while (t < 0) {
      q -= 1U;
      t += (int64_t)a.m;
    }
    while (t >= (int64_t)a.m) {
      q += 1U;
      t -= (int64_t)a.m;
    }
    if ((uint64_t)t >= (uint64_t)((a.m + 1U) >> 1)) {
      q += 1U;
    }
    r = pf_from_u64(q, -a.e - 63);
  }
  return r;
}

/*
 * round(a 2^-s) as an int32_t multiplier with the sign neg, for s >= 2
 * (|result| <= 2^30). Scaling and overflow: the caller picks s so that the
 * product of the multiplier with a block mantissa lands in the target
 * block's format; s >= 2 keeps it below 2^30 + 1. Rounding half up on the
 * magnitude; s > 32 gives 0.
 */
static inline __attribute__((always_inline)) int32_t pf_to_fix(pf_t a, int32_t s, bool neg)
{
  uint32_t v = 0U;
  CANFDI_ASSERT(s >= 2);
  if ((s >= 2) && (s <= 31)) {
    v = (a.m >> (unsigned)s) + ((a.m >> (unsigned)(s - 1)) & 1U);
  } else if (s == 32) {
    v = a.m >> 31;
  } else {
    /* below half a unit: 0 */
  }
  return neg ? -(int32_t)v : (int32_t)v;
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
    const pf_t p = pf_from_u64(mag, e);
    const uint32_t m = (p.m >> 2) + ((p.m >> 1) & 1U);
    r.e = p.e + 2;
    r.m = (int32_t)((m == 0x40000000U) ? 0x20000000U : m);
    r.e += (m == 0x40000000U) ? 1 : 0;
    r.m = neg ? -r.m : r.m;
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
  return xf_make(neg ? -v : v, a.e);
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

/*
 * floor((x + 2^(k-1)) / 2^k) for k in 1..31 on the two 32-bit halves (a
 * run-time 64-bit shift is ~25 instructions on ARMv7-M and a libgcc call on
 * ARMv6-M; this is ~8). Scaling and overflow: |x| < 2^62, so the rounding
 * add cannot overflow. Rounding: half up.
 */
static inline int64_t asr64_rnd_k(int64_t x, unsigned k)
{
  const uint64_t u = (uint64_t)x + ((uint64_t)1 << (k - 1U));
  const uint32_t hi = (uint32_t)(u >> 32);
  const uint32_t lo = ((uint32_t)u >> k) | (hi << (32U - k));
  const int32_t h = canfdi_asr32(canfdi_wrap_u32_to_s32(hi), k);
  return canfdi_wrap_u64_to_s64(((uint64_t)(uint32_t)h << 32) | lo);
}

/* v[0..n-1] *= 2^-k with rounding (k >= 1; k > 31 clears). Scaling: the
 * block's exponent rises by k; the caller adds it. */
static void blk_shr(int32_t v[], unsigned n, unsigned k)
{
  unsigned i;
  for (i = 0U; i < n; i++) {
    v[i] = canfdi_asr32_rnd(v[i], k);
  }
}

/*
 * Renormalises a block v[0..n-1] with exponent *e so that its largest
 * magnitude lies in [2^29, 2^30], or *e reaches emin. Scaling and
 * overflow: entries below 2^31 on entry (the callers' sums stay below
 * 2^30 + 2^28); a right shift rounds half up, a left shift is exact.
 */
static void blk_norm(int32_t v[], unsigned n, int32_t *e, int32_t emin)
{
  uint32_t acc = 0U;
  unsigned i;
  for (i = 0U; i < n; i++) {
    acc |= mag32(v[i]);
  }
  if (acc > (uint32_t)BLK_MAX) {
    blk_shr(v, n, 1U);
    *e += 1;
  } else if ((acc != 0U) && (acc < (uint32_t)BLK_LO) && (*e > emin)) {
    int32_t k = (int32_t)canfdi_clz32(acc) - 2; /* acc < 2^30 */
    if (k > (*e - emin)) {
      k = *e - emin;
    }
    for (i = 0U; i < n; i++) {
      v[i] = v[i] * ((int32_t)1 << (unsigned)k); /* k <= 29 and |v| 2^k < 2^30: exact */
    }
    *e -= k;
  } else {
    /* in range */
  }
}

/* U column j (entries u_0j .. u_(j-1)j) */
static int32_t *u_col(canfdi_rls_t *r, unsigned j)
{
  return &r->u[u_base(j)];
}

static void u_col_norm(canfdi_rls_t *r, unsigned j)
{
  int32_t e = r->u_e[j];
  blk_norm(u_col(r, j), j, &e, U_EMIN);
  r->u_e[j] = (int16_t)e;
}

/* ------------------------------------------------------------------------ */

/* trace of the stored factors: sum_j d_j (1 + sum_i u_ij^2); trace(P) is
 * this / a0. */
static pf_t rls_trace_stored(const canfdi_rls_t *r)
{
  const unsigned n = r->cfg.n_params;
  pf_t tr = PF_ZERO;
  unsigned i;
  unsigned j;
  for (j = 0U; j < n; j++) {
    uint64_t s2 = 0U;
    pf_t c;
    for (i = 0U; i < j; i++) {
      const int64_t u = r->u[u_idx(i, j)];
      s2 += (uint64_t)(u * u);
    }
    c = pf_add(pf_make(1U, 0), pf_from_u64(s2, 2 * (int32_t)r->u_e[j]));
    tr = pf_add(tr, pf_mul(r->d[j], c));
  }
  return tr;
}

/* Exponent T such that the stored trace is below 2^T: d_j < 2^(e_j + 32),
 * 1 + sum_i u_ij^2 <= n max(1, 2^(2 u_e + 60)). */
static int32_t rls_trace_bound_exp(const canfdi_rls_t *r)
{
  const unsigned n = r->cfg.n_params;
  int32_t t = INT32_MIN;
  unsigned j;
  for (j = 0U; j < n; j++) {
    const int32_t ue = 2 * ((int32_t)r->u_e[j] - U_EMIN);
    const int32_t c = r->d[j].e + 32 + ue;
    t = (c > t) ? c : t;
  }
  return t + 2 * (int32_t)r->clog2n;
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
      r->cfg = *cfg;
      r->lambda = pf_make((uint32_t)((int64_t)2147483648LL - (int64_t)cfg->forget_q31), -31);
      r->trace_max = pf_make((uint32_t)cfg->trace_max_q16, -16);
      r->inv_trace_max = pf_recip(r->trace_max);
      r->clog2n = 0U;
      while ((1U << r->clog2n) < cfg->n_params) {
        r->clog2n++;
      }
      r->diag.updates = 0U;
      r->diag.skipped = 0U;
      r->diag.trace_clips = 0U;
      r->diag.resets = 0U;
      r->diag.saturations = 0U;
      canfdi_rls_reset(r, false);
      r->diag.resets = 0U;
      out = CANFDI_OK;
    }
  }
  return out;
}

void canfdi_rls_reset(canfdi_rls_t *r, bool keep_theta)
{
  unsigned i;
  CANFDI_ASSERT(r != NULL);
  r->a0 = pf_make(1U, 0);
  for (i = 0U; i < NMAX; i++) {
    r->d[i] = (i < r->cfg.n_params) ? pf_make((uint32_t)r->cfg.p0_q16, -16) : PF_ZERO;
    r->u_e[i] = (int16_t)U_EMIN;
    r->mean[i] = 0;
    r->excite[i] = 0;
  }
  for (i = 0U; i < CANFDI_RLS_N_U; i++) {
    r->u[i] = 0;
  }
  if (!keep_theta) {
    for (i = 0U; i < NMAX; i++) {
      r->theta[i] = 0;
    }
    r->theta_e = 0;
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
  unsigned i;
  CANFDI_ASSERT(r != NULL);
  /* P = p0 I as canfdi_rls_reset, nothing else touched */
  r->a0 = pf_make(1U, 0);
  for (i = 0U; i < NMAX; i++) {
    r->d[i] = (i < r->cfg.n_params) ? pf_make((uint32_t)r->cfg.p0_q16, -16) : PF_ZERO;
    r->u_e[i] = (int16_t)U_EMIN;
  }
  for (i = 0U; i < CANFDI_RLS_N_U; i++) {
    r->u[i] = 0;
  }
  canfdi_count_inc(&r->diag.boosts);
}

static bool rls_gated(const canfdi_rls_t *r, unsigned i)
{
  return (r->cfg.excite_mask == 0U) || (((unsigned)r->cfg.excite_mask >> i) & 1U) != 0U;
}

/* The gate's measure in Q48: the minimum over the gated regressors. */
static int64_t rls_excitation_q48(const canfdi_rls_t *r)
{
  int64_t m = INT64_MAX;
  unsigned i;
  for (i = 0U; i < r->cfg.n_params; i++) {
    if (rls_gated(r, i) && (r->excite[i] < m)) {
      m = r->excite[i];
    }
  }
  return m;
}

/*
 * Excitation measure and gate; updates the running means of the gated
 * regressors (the others are never read). Scaling and overflow: phi 2^16
 * and the mean in Q32.32 physical (|.| < 2^47, the deviation < 2^48); the
 * deviation normalised to Q24 (shift 8 + s_i, rounded half up) saturates
 * at +-128, so its square (Q48) stays below 2^62 and the filtered measure
 * below 2^14; the filters round half up.
 */
static bool rls_gate(canfdi_rls_t *r, const int32_t phi_q16[])
{
  const unsigned n = r->cfg.n_params;
  const unsigned k = r->cfg.excite_shift;
  int64_t m = INT64_MAX;
  unsigned i;
  for (i = 0U; i < n; i++) {
    if (rls_gated(r, i)) {
      const int64_t x = (int64_t)phi_q16[i] * 65536;
      const int32_t sh = 8 + (int32_t)r->cfg.phi_shift[i];
      int64_t dev;
      int64_t dn;
      int64_t ex;
      if (!r->primed) {
        r->mean[i] = x;
        r->excite[i] = 0;
      }
      dev = x - r->mean[i];
      r->mean[i] += asr64_rnd_k(dev, k);
      if ((sh >= 1) && (sh <= 31)) {
        dn = asr64_rnd_k(dev, (unsigned)sh);
      } else {
        dn = (sh >= 0) ? canfdi_asr64_rnd(dev, (unsigned)sh) : canfdi_shl64_sat(dev, (unsigned)-sh);
      }
      dn = (dn > INT32_MAX) ? INT32_MAX : ((dn < -INT32_MAX) ? -INT32_MAX : dn);
      ex = r->excite[i];
      ex += asr64_rnd_k(((int64_t)(int32_t)dn * (int32_t)dn) - ex, k);
      r->excite[i] = ex;
      m = (ex < m) ? ex : m;
    }
  }
  r->primed = true;
  return (r->cfg.excite_min_q16 == 0) || (m >= ((int64_t)r->cfg.excite_min_q16 * 4294967296LL));
}

/*
 * The regressors as one block x[i] 2^*ex (normalised units, |x| <= 2^30,
 * the largest in [2^29, 2^30]). Scaling and overflow: phi_i 2^-(16 + s_i)
 * is shifted exactly (left) or rounded half up (right, when regressors
 * differ by more than 2^30 in normalised size: the small one keeps fewer
 * bits, see the header).
 */
static void rls_phi_block(const canfdi_rls_t *r, const int32_t phi_q16[], int32_t x[], int32_t *ex)
{
  const unsigned n = r->cfg.n_params;
  int32_t top = INT32_MIN;
  unsigned i;
  for (i = 0U; i < n; i++) {
    const uint32_t m = mag32(phi_q16[i]);
    if (m != 0U) {
      const int32_t t = (32 - (int32_t)canfdi_clz32(m)) - 16 - (int32_t)r->cfg.phi_shift[i];
      top = (t > top) ? t : top;
    }
  }
  *ex = (top == INT32_MIN) ? 0 : (top - 30);
  for (i = 0U; i < n; i++) {
    const int32_t l = -16 - (int32_t)r->cfg.phi_shift[i] - *ex; /* left shift */
    if (phi_q16[i] == 0) {
      x[i] = 0; /* its shift may exceed 31 (only a nonzero regressor bounds it) */
    } else if (l >= 0) {
      const uint32_t m = mag32(phi_q16[i]) << (unsigned)l; /* < 2^30 by choice of ex */
      x[i] = (phi_q16[i] < 0) ? -(int32_t)m : (int32_t)m;
    } else {
      x[i] = canfdi_asr32_rnd(phi_q16[i], (unsigned)-l);
    }
  }
}

/*
 * y_norm - x^T theta as a float with sign. Scaling and overflow: x^T theta
 * is one exact 64-bit sum (products below 2^60); it is aligned to y 2^16
 * (16 guard bits below y's last bit) with rounding half up, the difference
 * below 2^49. When the sum carries bits above that format (theta or x
 * beyond their usual range) the signed xf path takes over (rounded to 30
 * bits).
 */
static pf_t rls_error(const canfdi_rls_t *r, const int32_t x[], int32_t ex, int32_t y_q16, bool *neg)
{
  const unsigned n = r->cfg.n_params;
  const int32_t ey = -32 - (int32_t)r->cfg.y_shift; /* y 2^16 */
  const int32_t d = ey - (r->theta_e + ex);
  int64_t acc = 0;
  pf_t out;
  unsigned i;
  for (i = 0U; i < n; i++) {
    acc += (int64_t)r->theta[i] * (int64_t)x[i];
  }
  if ((d >= 1) && (d <= 31)) {
    const int64_t v = ((int64_t)y_q16 * 65536) - asr64_rnd_k(acc, (unsigned)d);
    *neg = (v < 0);
    out = pf_from_u64(*neg ? (uint64_t)(-v) : (uint64_t)v, ey);
  } else if (d > 31) {
    const int64_t v = ((int64_t)y_q16 * 65536) - canfdi_asr64_rnd(acc, (unsigned)d);
    *neg = (v < 0);
    out = pf_from_u64(*neg ? (uint64_t)(-v) : (uint64_t)v, ey);
  } else {
    const xf_t e = xf_add(xf_make(y_q16, -16 - (int32_t)r->cfg.y_shift), xf_make(-acc, r->theta_e + ex));
    *neg = (e.m < 0);
    out = pf_make(mag32(e.m), e.e);
  }
  return out;
}

/* Inverses of a[1..n] with one reciprocal (prefix products, then back). */
static void rls_inverses(const pf_t a[], pf_t inv[], unsigned n)
{
  pf_t pre[NMAX + 1U];
  pf_t q;
  unsigned j;
  pre[1] = a[1];
  for (j = 2U; j <= n; j++) {
    pre[j] = pf_mul(pre[j - 1U], a[j]);
  }
  q = pf_recip(pre[n]);
  for (j = n; j >= 2U; j--) {
    inv[j] = pf_mul(q, pre[j - 1U]);
    q = pf_mul(q, a[j]);
  }
  inv[1] = q;
}

/*
 * f = U^T x (f_j = x_j + sum_i u_ij x_i, one 64-bit sum per column: the
 * products are below 2^60, x_j 2^-u_e below 2^60), g = D f (g has f's
 * sign: d > 0) and a[j + 1] = a[j] + f_j g_j.
 */
static void rls_forward(const canfdi_rls_t *r, const int32_t x[], int32_t ex, pf_t f[], bool fneg[], pf_t g[],
                        pf_t a[])
{
  const unsigned n = r->cfg.n_params;
  unsigned i;
  unsigned j;
  for (j = 0U; j < n; j++) {
    const int32_t *col = &r->u[u_base(j)];
    const int32_t ue = (int32_t)r->u_e[j];
    int64_t acc;
    if (ue <= 0) {
      acc = (int64_t)x[j] * (int64_t)((int32_t)1 << (unsigned)-ue); /* ue >= -30 */
    } else {
      acc = canfdi_asr64_rnd(x[j], (unsigned)ue);
    }
    for (i = 0U; i < j; i++) {
      acc += (int64_t)col[i] * (int64_t)x[i];
    }
    fneg[j] = (acc < 0);
    f[j] = pf_from_u64(fneg[j] ? ((uint64_t)(-(acc + 1)) + 1U) : (uint64_t)acc, ue + ex);
    g[j] = pf_mul(r->d[j], f[j]);
    a[j + 1U] = pf_add(a[j], pf_mul(g[j], f[j]));
  }
}

/*
 * Bierman's column pass: d_j *= a_j / a_(j+1); for i < j
 * u_ij += b_i mu_j (mu_j = -f_j / a_j) and b_i += u_ij g_j (old u_ij);
 * b_j = g_j. b ends as U g = P phi (stored scale), in the block b[] 2^eb.
 * Scaling and overflow: eb is chosen from a bound of |U g| so that every
 * partial sum stays below 2^29 and each multiplier is a rounded int32_t
 * below 2^30 (pf_to_fix with s >= 2); a column whose update would exceed
 * its format is shifted first (its exponent rises), then renormalised.
 * Rounding: half up in every product (canfdi_mla_hi_rnd).
 */
static void rls_columns(canfdi_rls_t *r, const pf_t f[], const bool fneg[], const pf_t g[], const pf_t a[],
                        const pf_t inv[], int32_t b[], int32_t eb)
{
  const unsigned n = r->cfg.n_params;
  unsigned i;
  unsigned j;
  for (j = 0U; j < n; j++) {
    pf_t dj;
    if ((j > 0U) && (g[j].m != 0U)) {
      int32_t *col = u_col(r, j);
      const pf_t mu = pf_mul(f[j], inv[j]);
      const int32_t s = (int32_t)r->u_e[j] - eb - 32 - mu.e;
      const int32_t gg = pf_to_fix(g[j], eb - 32 - (int32_t)r->u_e[j] - g[j].e, fneg[j]);
      if (s >= 2) {
        const int32_t mm = pf_to_fix(mu, s, !fneg[j]);
        for (i = 0U; i < j; i++) {
          const int32_t uo = col[i];
          col[i] = canfdi_mla_hi_rnd(uo, b[i], mm);
          b[i] = canfdi_mla_hi_rnd(b[i], uo, gg);
        }
      } else {
        /* the column outgrows its format: b first (old format), then the
         * column shifted so that the multiplier fits (s = 2) */
        int32_t bo[NMAX];
        int32_t mm;
        for (i = 0U; i < j; i++) {
          bo[i] = b[i];
          b[i] = canfdi_mla_hi_rnd(b[i], col[i], gg);
        }
        blk_shr(col, j, (unsigned)(2 - s));
        r->u_e[j] = (int16_t)(r->u_e[j] + (2 - s));
        mm = pf_to_fix(mu, 2, !fneg[j]);
        for (i = 0U; i < j; i++) {
          col[i] = canfdi_mla_hi_rnd(col[i], bo[i], mm);
        }
      }
      u_col_norm(r, j);
    }
    b[j] = (g[j].m != 0U) ? pf_to_fix(g[j], eb - g[j].e, fneg[j]) : 0;
    dj = pf_mul(pf_mul(r->d[j], a[j]), inv[j + 1U]);
    {
      pf_t fl = a[0];
      fl.e -= D_FLOOR_REL;
      if (pf_lt(dj, fl)) {
        dj = fl;
        canfdi_count_inc(&r->diag.saturations);
      }
    }
    r->d[j] = dj;
  }
}

/* theta += b k (k = e / a_n). Scaling: the block rises first when the
 * update would exceed it; then renormalised. Rounding half up. */
static void rls_theta_update(canfdi_rls_t *r, const int32_t b[], int32_t eb, pf_t k, bool kneg)
{
  const unsigned n = r->cfg.n_params;
  unsigned i;
  if (k.m != 0U) {
    int32_t s = r->theta_e - eb - 32 - k.e;
    int32_t kk;
    uint32_t any = 0U;
    for (i = 0U; i < n; i++) {
      any |= mag32(r->theta[i]);
    }
    if (any == 0U) {
      /* a block of zeros takes the update's format */
      r->theta_e -= s - 2;
      s = 2;
    } else if (s < 2) {
      blk_shr(r->theta, n, (unsigned)(2 - s));
      r->theta_e += 2 - s;
      s = 2;
    }
    kk = pf_to_fix(k, s, kneg);
    for (i = 0U; i < n; i++) {
      r->theta[i] = canfdi_mla_hi_rnd(r->theta[i], b[i], kk);
    }
    blk_norm(r->theta, n, &r->theta_e, CANFDI_RLS_THETA_EMIN);
  }
}

/* Trace bound (P scaled through a0) and the exponent window of a0. */
static void rls_bound(canfdi_rls_t *r)
{
  const pf_t lim = pf_mul(r->trace_max, r->a0);
  unsigned j;
  if (rls_trace_bound_exp(r) > (lim.e + 31)) {
    const pf_t tr = rls_trace_stored(r);
    if (pf_lt(lim, tr)) {
      r->a0 = pf_mul(tr, r->inv_trace_max);
      canfdi_count_inc(&r->diag.trace_clips);
    }
  }
  if ((r->a0.e < A0_EMIN) || (r->a0.e > A0_EMAX)) {
    const int32_t k = (r->a0.e < A0_EMIN) ? A0_SHIFT : -A0_SHIFT;
    r->a0.e += k;
    for (j = 0U; j < r->cfg.n_params; j++) {
      r->d[j].e += k;
    }
  }
}

/* One applied update on the regressor block x 2^ex (the error is in r). */
static void rls_apply(canfdi_rls_t *r, const int32_t x[], int32_t ex)
{
  const unsigned n = r->cfg.n_params;
  pf_t f[NMAX];
  pf_t g[NMAX];
  pf_t a[NMAX + 1U];
  pf_t inv[NMAX + 1U];
  bool fneg[NMAX];
  int32_t b[NMAX];
  int32_t eb = INT32_MIN;
  unsigned j;
  a[0] = pf_mul(r->a0, r->lambda); /* forgetting: P / lambda */
  rls_forward(r, x, ex, f, fneg, g, a);
  rls_inverses(a, inv, n);
  for (j = 0U; j < n; j++) {
    if (g[j].m != 0U) {
      const int32_t c = (int32_t)r->u_e[j] + g[j].e;
      eb = (c > eb) ? c : eb;
    }
  }
  eb = (eb == INT32_MIN) ? 0 : (eb + 33 + (int32_t)r->clog2n);
  rls_columns(r, f, fneg, g, a, inv, b, eb);
  rls_theta_update(r, b, eb, pf_mul(r->err, inv[n]), r->err_neg);
  r->a0 = a[0];
  rls_bound(r);
}

bool canfdi_rls_update(canfdi_rls_t *r, const int32_t phi_q16[], int32_t y_q16)
{
  int32_t x[NMAX];
  int32_t ex;
  bool go;
  CANFDI_ASSERT((r != NULL) && (phi_q16 != NULL));
  go = rls_gate(r, phi_q16);
  rls_phi_block(r, phi_q16, x, &ex);
  r->err = rls_error(r, x, ex, y_q16, &r->err_neg);
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
    const xf_t t = xf_make(r->theta[i], r->theta_e + (int32_t)r->cfg.y_shift - (int32_t)r->cfg.phi_shift[i]);
    y = xf_to_s32(t, (int32_t)frac);
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
    }
    blk_norm(r->theta, n, &r->theta_e, CANFDI_RLS_THETA_EMIN);
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

/* 1 / a0 as an xf: the factor from the stored factors to P. */
static xf_t rls_inv_a0(const canfdi_rls_t *r)
{
  return xf_from_pf(pf_recip(r->a0), false);
}

int32_t canfdi_rls_cov_qn(const canfdi_rls_t *r, unsigned i, unsigned j, unsigned frac)
{
  int32_t y = 0;
  CANFDI_ASSERT(r != NULL);
  if ((i < r->cfg.n_params) && (j < r->cfg.n_params) && (frac <= 31U)) {
    /* P_ij = sum_{k >= max(i,j)} u_ik d_k u_jk / a0, u_kk = 1 */
    const unsigned k0 = (i > j) ? i : j;
    const xf_t one = xf_make(1, 0);
    xf_t s = {0, 0};
    unsigned k;
    for (k = k0; k < r->cfg.n_params; k++) {
      const xf_t uik = (i == k) ? one : xf_make(r->u[u_idx(i, k)], r->u_e[k]);
      const xf_t ujk = (j == k) ? one : xf_make(r->u[u_idx(j, k)], r->u_e[k]);
      s = xf_add(s, xf_mul(xf_mul(uik, ujk), xf_from_pf(r->d[k], false)));
    }
    y = xf_to_s32(xf_mul(s, rls_inv_a0(r)), (int32_t)frac);
  }
  return y;
}

int32_t canfdi_rls_trace_q16(const canfdi_rls_t *r)
{
  CANFDI_ASSERT(r != NULL);
  return xf_to_s32(xf_mul(xf_from_pf(rls_trace_stored(r), false), rls_inv_a0(r)), 16);
}

canfdi_rls_xf_t canfdi_rls_d(const canfdi_rls_t *r, unsigned j)
{
  xf_t z = {0, 0};
  CANFDI_ASSERT(r != NULL);
  if (j < r->cfg.n_params) {
    z = xf_mul(xf_from_pf(r->d[j], false), rls_inv_a0(r));
  }
  return z;
}

int32_t canfdi_rls_excitation_q16(const canfdi_rls_t *r)
{
  int64_t m;
  CANFDI_ASSERT(r != NULL);
  m = rls_excitation_q48(r);
  return (m == INT64_MAX) ? 0 : (int32_t)canfdi_asr64_rnd(m, 32U); /* < 2^30 */
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
    pf_t lim = pf_mul(r->trace_max, r->a0);
    lim = pf_add(lim, pf_make(lim.m, lim.e - 20));
    ok = (r->a0.m >= 0x80000000U) && blk_ok(r->theta, n);
    for (j = 0U; j < n; j++) {
      ok = ok && (r->d[j].m >= 0x80000000U) && (r->u_e[j] >= U_EMIN) && blk_ok(&r->u[u_base(j)], j);
    }
    ok = ok && !pf_lt(lim, rls_trace_stored(r));
  }
  return ok;
}

const canfdi_rls_diag_t *canfdi_rls_diag(const canfdi_rls_t *r)
{
  CANFDI_ASSERT(r != NULL);
  return &r->diag;
}
