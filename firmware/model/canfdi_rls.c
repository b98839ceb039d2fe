/*
 * canfdi_rls.c — UD-factorised RLS with forgetting; see canfdi_rls.h.
 */
#include "model/canfdi_rls.h"

#include "core/canfdi_count.h"

#define NMAX CANFDI_CFG_RLS_MAX_PARAMS

typedef canfdi_rls_xf_t xf_t;

/* Exponent clamp: far beyond any value the trace bound and the d floor
 * admit, and small enough that sums of two exponents never overflow. */
#define XF_EMAX 65536
#define XF_EMIN (-65536)
#define XF_MANT_HI ((int32_t)1 << 30) /* |m| < 2^30 */
#define XF_MANT_LO ((int32_t)1 << 29) /* |m| >= 2^29 */
/* d_j floor 2^-60 (normalised units) */
#define D_FLOOR_E (-89)

CANFDI_STATIC_ASSERT(CANFDI_CFG_RLS_MAX_PARAMS >= 1U, rls_max_params_positive);
CANFDI_STATIC_ASSERT(CANFDI_CFG_RLS_MAX_PARAMS <= 16U, rls_max_params_sane);

/* ------------------------------------------------------------------------ */
/* xf arithmetic                                                             */
/* ------------------------------------------------------------------------ */

static unsigned bitlen_u64(uint64_t x)
{
  uint64_t v = x;
  unsigned n = 0U;
  if ((v >> 32) != 0U) {
    n += 32U;
    v >>= 32;
  }
  if ((v >> 16) != 0U) {
    n += 16U;
    v >>= 16;
  }
  if ((v >> 8) != 0U) {
    n += 8U;
    v >>= 8;
  }
  if ((v >> 4) != 0U) {
    n += 4U;
    v >>= 4;
  }
  if ((v >> 2) != 0U) {
    n += 2U;
    v >>= 2;
  }
  if ((v >> 1) != 0U) {
    n += 1U;
    v >>= 1;
  }
  return n + (unsigned)v;
}

/*
 * v * 2^e as a normalised xf. Scaling and overflow: the magnitude is taken
 * in uint64_t (exact also for INT64_MIN), shifted to 30 significant bits
 * with rounding half up on the magnitude (to nearest, ties away from zero);
 * a carry to 2^30 renormalises. Exponent beyond XF_EMAX saturates the
 * magnitude, below XF_EMIN flushes to zero.
 */
static xf_t xf_make(int64_t v, int32_t e)
{
  xf_t r = {0, 0};
  if (v != 0) {
    const bool neg = (v < 0);
    uint64_t mag = neg ? ((uint64_t)(-(v + 1)) + 1U) : (uint64_t)v;
    const int32_t nb = (int32_t)bitlen_u64(mag);
    int32_t s = nb - 30;
    int32_t ex;
    if (s > 0) {
      mag = (mag >> (unsigned)s) + ((mag >> (unsigned)(s - 1)) & 1U);
      if (mag >= (uint64_t)XF_MANT_HI) {
        mag >>= 1;
        s += 1;
      }
    } else {
      mag <<= (unsigned)(-s);
    }
    ex = e + s;
    if (ex > XF_EMAX) {
      r.m = neg ? -(XF_MANT_HI - 1) : (XF_MANT_HI - 1);
      r.e = XF_EMAX;
    } else if (ex >= XF_EMIN) {
      r.m = neg ? -(int32_t)mag : (int32_t)mag;
      r.e = ex;
    } else {
      /* underflow: zero */
    }
  }
  return r;
}

static xf_t xf_mul(xf_t a, xf_t b)
{
  return xf_make((int64_t)a.m * (int64_t)b.m, a.e + b.e);
}

/* a + b: the larger-exponent operand is placed at 2^32 (exact, < 2^62), the
 * other aligned to it with a rounding shift; the sum fits in int64_t. */
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

static xf_t xf_neg(xf_t a)
{
  xf_t r = a;
  r.m = -a.m;
  return r;
}

static xf_t xf_sub(xf_t a, xf_t b)
{
  return xf_add(a, xf_neg(b));
}

/* a / b for b != 0: the mantissa quotient a.m 2^30 / b.m lies in
 * (2^28, 2^31) and is rounded by canfdi_div_s32_qn. */
static xf_t xf_div(xf_t a, xf_t b)
{
  xf_t r = {0, 0};
  CANFDI_ASSERT(b.m != 0);
  if ((a.m != 0) && (b.m != 0)) {
    r = xf_make(canfdi_div_s32_qn(a.m, b.m, 30U), a.e - b.e - 30);
  }
  return r;
}

/* a * 2^k */
static xf_t xf_ldexp(xf_t a, int32_t k)
{
  return (a.m == 0) ? a : xf_make(a.m, a.e + k);
}

static xf_t xf_from_s32(int32_t x, int32_t frac)
{
  return xf_make(x, -frac);
}

/* round(a 2^frac), saturated to int32_t; *sat set when clipped. */
static int32_t xf_to_s32(xf_t a, int32_t frac, bool *sat)
{
  const int32_t sh = a.e + frac;
  int32_t y = 0;
  *sat = false;
  if (a.m != 0) {
    if (sh >= 0) {
      y = canfdi_shl32_sat(a.m, (unsigned)((sh > 31) ? 31 : sh));
      *sat = (y == INT32_MAX) || (y == INT32_MIN);
    } else {
      y = canfdi_asr32_rnd(a.m, (unsigned)((-sh > 32) ? 32 : -sh));
    }
  }
  return y;
}

static bool xf_is_norm(xf_t a)
{
  const int32_t mag = (a.m < 0) ? -a.m : a.m;
  return (a.m == 0) || ((mag >= XF_MANT_LO) && (mag < XF_MANT_HI) && (a.e >= XF_EMIN) && (a.e <= XF_EMAX));
}

/* a > b */
static bool xf_gt(xf_t a, xf_t b)
{
  return xf_sub(a, b).m > 0;
}

/* ------------------------------------------------------------------------ */

static unsigned u_idx(unsigned i, unsigned j)
{
  CANFDI_ASSERT(i < j);
  return ((j * (j - 1U)) / 2U) + i;
}

/* trace(P) = sum_j d_j (1 + sum_{i<j} u_ij^2)  (P_ii = sum_{j>=i} u_ij^2 d_j) */
static xf_t rls_trace(const canfdi_rls_t *r)
{
  const unsigned n = r->cfg.n_params;
  xf_t tr = {0, 0};
  unsigned i;
  unsigned j;
  for (j = 0U; j < n; j++) {
    xf_t s = xf_make(1, 0);
    for (i = 0U; i < j; i++) {
      const xf_t u = r->u[u_idx(i, j)];
      s = xf_add(s, xf_mul(u, u));
    }
    tr = xf_add(tr, xf_mul(r->d[j], s));
  }
  return tr;
}

int32_t canfdi_rls_init(canfdi_rls_t *r, const canfdi_rls_cfg_t *cfg)
{
  int32_t out = -CANFDI_EINVAL;
  if ((r != NULL) && (cfg != NULL) && (cfg->n_params >= 1U) && (cfg->n_params <= NMAX) &&
      (cfg->forget_q31 >= 0) && (cfg->forget_q31 <= ((int32_t)1 << 30)) && (cfg->p0_q16 > 0) &&
      (cfg->excite_min_q16 >= 0) && (cfg->excite_shift >= 1U) && (cfg->excite_shift <= 16U) &&
      (((unsigned)cfg->excite_mask >> cfg->n_params) == 0U) &&
      (cfg->y_shift >= -32) && (cfg->y_shift <= 32) &&
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
      r->lambda = xf_make((int64_t)2147483648LL - (int64_t)cfg->forget_q31, -31);
      r->inv_lambda = xf_div(xf_make(1, 0), r->lambda);
      r->trace_max = xf_from_s32(cfg->trace_max_q16, 16);
      r->excite_min = xf_from_s32(cfg->excite_min_q16, 16);
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
  for (i = 0U; i < NMAX; i++) {
    if (i < r->cfg.n_params) {
      r->d[i] = xf_from_s32(r->cfg.p0_q16, 16);
      if (!keep_theta) {
        /* theta_norm = theta 2^(s_i - s_y) */
        r->theta[i] = xf_make(r->cfg.theta0_q16[i],
                              -16 + (int32_t)r->cfg.phi_shift[i] - (int32_t)r->cfg.y_shift);
      }
    } else {
      r->d[i] = xf_make(0, 0);
      r->theta[i] = xf_make(0, 0);
    }
    r->mean[i] = 0;
  }
  for (i = 0U; i < CANFDI_RLS_N_U; i++) {
    r->u[i] = xf_make(0, 0);
  }
  for (i = 0U; i < NMAX; i++) {
    r->excite[i] = xf_make(0, 0);
  }
  r->err = xf_make(0, 0);
  r->primed = false;
  r->excited = false;
  canfdi_count_inc(&r->diag.resets);
}

void canfdi_rls_boost(canfdi_rls_t *r)
{
  unsigned i;
  CANFDI_ASSERT(r != NULL);
  for (i = 0U; i < NMAX; i++) {
    r->d[i] = (i < r->cfg.n_params) ? xf_from_s32(r->cfg.p0_q16, 16) : xf_make(0, 0);
  }
  for (i = 0U; i < CANFDI_RLS_N_U; i++) {
    r->u[i] = xf_make(0, 0);
  }
  canfdi_count_inc(&r->diag.boosts);
}

static bool rls_gated(const canfdi_rls_t *r, unsigned i)
{
  return (r->cfg.excite_mask == 0U) || (((unsigned)r->cfg.excite_mask >> i) & 1U) != 0U;
}

/* The gate's measure: min over the gated regressors (see the header). */
static xf_t rls_excitation(const canfdi_rls_t *r)
{
  xf_t m = {0, 0};
  bool first = true;
  unsigned i;
  for (i = 0U; i < r->cfg.n_params; i++) {
    if (rls_gated(r, i) && (first || xf_gt(m, r->excite[i]))) {
      m = r->excite[i];
      first = false;
    }
  }
  return m;
}

/* Excitation measure and gate; updates the running means. */
static bool rls_gate(canfdi_rls_t *r, const int32_t phi_q16[])
{
  const unsigned n = r->cfg.n_params;
  const unsigned k = r->cfg.excite_shift;
  unsigned i;
  if (!r->primed) {
    for (i = 0U; i < n; i++) {
      r->mean[i] = (int64_t)phi_q16[i] * 65536;
      r->excite[i] = xf_make(0, 0);
    }
    r->primed = true;
  }
  for (i = 0U; i < n; i++) {
    /* deviation in Q32.32 physical (exact: |phi 2^16 - mean| < 2^48),
     * normalised by 2^-s_i through the exponent; then
     * excite_i += (dev^2 - excite_i) 2^-k */
    const int64_t dev = ((int64_t)phi_q16[i] * 65536) - r->mean[i];
    const xf_t dn = xf_make(dev, -32 - (int32_t)r->cfg.phi_shift[i]);
    r->excite[i] = xf_add(r->excite[i], xf_ldexp(xf_sub(xf_mul(dn, dn), r->excite[i]), -(int32_t)k));
    r->mean[i] += canfdi_asr64_rnd(dev, k);
  }
  return (r->cfg.excite_min_q16 == 0) || !xf_gt(r->excite_min, rls_excitation(r));
}

bool canfdi_rls_update(canfdi_rls_t *r, const int32_t phi_q16[], int32_t y_q16)
{
  const unsigned n = r->cfg.n_params;
  xf_t phi[NMAX];
  xf_t f[NMAX];
  xf_t g[NMAX];
  xf_t b[NMAX];
  xf_t e;
  unsigned i;
  unsigned j;
  bool go;
  CANFDI_ASSERT((r != NULL) && (phi_q16 != NULL));

  go = rls_gate(r, phi_q16);

  /* a-priori error in normalised units (also when skipping: diagnostics) */
  e = xf_from_s32(y_q16, 16 + (int32_t)r->cfg.y_shift);
  for (i = 0U; i < n; i++) {
    phi[i] = xf_from_s32(phi_q16[i], 16 + (int32_t)r->cfg.phi_shift[i]);
    e = xf_sub(e, xf_mul(r->theta[i], phi[i]));
  }
  r->err = e;
  r->excited = go;

  if (!go) {
    canfdi_count_inc(&r->diag.skipped);
  } else {
    xf_t alpha = r->lambda;
    xf_t inv_alpha = r->inv_lambda;
    xf_t scale;
    xf_t tr;
    /* f = U^T phi, g = D f */
    for (j = 0U; j < n; j++) {
      xf_t s = phi[j];
      for (i = 0U; i < j; i++) {
        s = xf_add(s, xf_mul(r->u[u_idx(i, j)], phi[i]));
      }
      f[j] = s;
      g[j] = xf_mul(r->d[j], s);
    }
    /* Bierman's update with forgetting */
    for (j = 0U; j < n; j++) {
      const xf_t alpha_new = xf_add(alpha, xf_mul(f[j], g[j]));
      const xf_t inv_new = xf_div(xf_make(1, 0), alpha_new);
      const xf_t mu = xf_neg(xf_mul(f[j], inv_alpha));
      xf_t dj = xf_mul(xf_mul(r->d[j], xf_mul(alpha, inv_new)), r->inv_lambda);
      if ((dj.m <= 0) || (dj.e < D_FLOOR_E)) {
        dj = xf_make(XF_MANT_LO, D_FLOOR_E);
        canfdi_count_inc(&r->diag.saturations);
      }
      r->d[j] = dj;
      b[j] = g[j];
      for (i = 0U; i < j; i++) {
        const unsigned ix = u_idx(i, j);
        const xf_t u_old = r->u[ix];
        r->u[ix] = xf_add(u_old, xf_mul(b[i], mu));
        b[i] = xf_add(b[i], xf_mul(u_old, g[j]));
      }
      alpha = alpha_new;
      inv_alpha = inv_new;
    }
    /* theta += b e / alpha_n */
    scale = xf_mul(e, inv_alpha);
    for (i = 0U; i < n; i++) {
      r->theta[i] = xf_add(r->theta[i], xf_mul(b[i], scale));
    }
    /* trace bound */
    tr = rls_trace(r);
    if (xf_gt(tr, r->trace_max)) {
      const xf_t c = xf_div(r->trace_max, tr);
      for (j = 0U; j < n; j++) {
        r->d[j] = xf_mul(r->d[j], c);
      }
      canfdi_count_inc(&r->diag.trace_clips);
    }
    canfdi_count_inc(&r->diag.updates);
  }
  return go;
}

int32_t canfdi_rls_theta_qn(const canfdi_rls_t *r, unsigned i, unsigned frac)
{
  int32_t y = 0;
  bool sat;
  CANFDI_ASSERT(r != NULL);
  if ((i < r->cfg.n_params) && (frac <= 31U)) {
    const xf_t t = xf_ldexp(r->theta[i], (int32_t)r->cfg.y_shift - (int32_t)r->cfg.phi_shift[i]);
    y = xf_to_s32(t, (int32_t)frac, &sat);
  }
  return y;
}

void canfdi_rls_set_theta_qn(canfdi_rls_t *r, unsigned i, int32_t value, unsigned frac)
{
  CANFDI_ASSERT(r != NULL);
  if ((i < r->cfg.n_params) && (frac <= 31U)) {
    r->theta[i] = xf_make(value, -(int32_t)frac + (int32_t)r->cfg.phi_shift[i] - (int32_t)r->cfg.y_shift);
  }
}

int32_t canfdi_rls_err_q16(const canfdi_rls_t *r)
{
  bool sat;
  CANFDI_ASSERT(r != NULL);
  return xf_to_s32(xf_ldexp(r->err, (int32_t)r->cfg.y_shift), 16, &sat);
}

int32_t canfdi_rls_cov_qn(const canfdi_rls_t *r, unsigned i, unsigned j, unsigned frac)
{
  int32_t y = 0;
  bool sat;
  CANFDI_ASSERT(r != NULL);
  if ((i < r->cfg.n_params) && (j < r->cfg.n_params) && (frac <= 31U)) {
    /* P_ij = sum_{k >= max(i,j)} u_ik d_k u_jk, u_kk = 1 */
    const unsigned k0 = (i > j) ? i : j;
    xf_t s = {0, 0};
    unsigned k;
    for (k = k0; k < r->cfg.n_params; k++) {
      const xf_t one = xf_make(1, 0);
      const xf_t uik = (i == k) ? one : r->u[u_idx(i, k)];
      const xf_t ujk = (j == k) ? one : r->u[u_idx(j, k)];
      s = xf_add(s, xf_mul(xf_mul(uik, ujk), r->d[k]));
    }
    y = xf_to_s32(s, (int32_t)frac, &sat);
  }
  return y;
}

int32_t canfdi_rls_trace_q16(const canfdi_rls_t *r)
{
  bool sat;
  CANFDI_ASSERT(r != NULL);
  return xf_to_s32(rls_trace(r), 16, &sat);
}

canfdi_rls_xf_t canfdi_rls_d(const canfdi_rls_t *r, unsigned j)
{
  xf_t z = {0, 0};
  CANFDI_ASSERT(r != NULL);
  return (j < r->cfg.n_params) ? r->d[j] : z;
}

int32_t canfdi_rls_excitation_q16(const canfdi_rls_t *r)
{
  bool sat;
  CANFDI_ASSERT(r != NULL);
  return xf_to_s32(rls_excitation(r), 16, &sat);
}

bool canfdi_rls_excited(const canfdi_rls_t *r)
{
  CANFDI_ASSERT(r != NULL);
  return r->excited;
}

bool canfdi_rls_invariants_hold(const canfdi_rls_t *r)
{
  bool ok = (r != NULL);
  if (ok) {
    const unsigned n = r->cfg.n_params;
    const xf_t slack = xf_ldexp(r->trace_max, -20);
    unsigned i;
    for (i = 0U; i < n; i++) {
      ok = ok && (r->d[i].m > 0) && xf_is_norm(r->d[i]) && xf_is_norm(r->theta[i]);
    }
    for (i = 0U; i < ((n * (n - 1U)) / 2U); i++) {
      ok = ok && xf_is_norm(r->u[i]);
    }
    ok = ok && !xf_gt(rls_trace(r), xf_add(r->trace_max, slack));
  }
  return ok;
}

const canfdi_rls_diag_t *canfdi_rls_diag(const canfdi_rls_t *r)
{
  CANFDI_ASSERT(r != NULL);
  return &r->diag;
}
