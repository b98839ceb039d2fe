/*
 * canfdi_svf.c — state-variable filter; see canfdi_svf.h for the manual.
 */
#include "model/canfdi_svf.h"

#include "core/canfdi_count.h"
#include "core/canfdi_fixp.h"

/* h = wc T / 2 = wc * STEP_US / 2e6. */
#define SVF_H_DEN 2000000U
/* init's exact arithmetic needs (p + q)^3 < 2^60 (see the header). */
#define SVF_PQ_LIMIT (1U << 20)
/* Normalised states beyond +-2^47 (2^15 units in Q31.32) saturate every
 * output because wc >= 1; clamping there keeps x * wc inside int64_t. */
#define SVF_V_CLAMP ((int64_t)1 << 47)

static uint64_t svf_gcd_u64(uint64_t a, uint64_t b)
{
  uint64_t x = a;
  uint64_t y = b;
  while (y != 0U) {
    const uint64_t r = x % y;
    x = y;
    y = r;
  }
  return x;
}

/*
 * round(num * 2^31 / den) for |num| < den < 2^62, by binary long division
 * (no 64-bit division, no float), rounded to nearest (ties away from zero),
 * saturated to INT32_MAX (a quotient within half an LSB of 1).
 * Scaling and overflow: the remainder stays < den < 2^62, so r << 1 fits.
 */
static int32_t svf_ratio_q31(int64_t num, uint64_t den)
{
  const bool neg = (num < 0);
  uint64_t r = neg ? (uint64_t)(-num) : (uint64_t)num;
  uint64_t quot = 0U;
  unsigned i;
  CANFDI_ASSERT(r < den);
  for (i = 0U; i < 31U; i++) {
    r <<= 1;
    quot <<= 1;
    if (r >= den) {
      r -= den;
      quot |= 1U;
    }
  }
  if ((r << 1) >= den) {
    quot += 1U;
  }
  if (quot > (uint64_t)INT32_MAX) {
    quot = (uint64_t)INT32_MAX;
  }
  return neg ? -(int32_t)quot : (int32_t)quot;
}

/*
 * The Q16.16 value of wc^k * v (v normalised Q31.32, k = 0..2), rounded half
 * up and saturated. Scaling and overflow: v is first clamped to +-2^47 (see
 * SVF_V_CLAMP) and again after each multiply by wc < 2^15, so every product
 * stays below 2^62.
 */
static int32_t svf_out_q16(int64_t v, int32_t wc, unsigned k, uint32_t *sat)
{
  int64_t x = v;
  unsigned i;
  int32_t y;
  for (i = 0U; i < k; i++) {
    if (x > SVF_V_CLAMP) {
      x = SVF_V_CLAMP;
    } else if (x < -SVF_V_CLAMP) {
      x = -SVF_V_CLAMP;
    } else {
      /* in range */
    }
    x *= (int64_t)wc;
  }
  x = canfdi_asr64_rnd(x, 16U);
  y = canfdi_sat_s64_to_s32(x);
  if ((int64_t)y != x) {
    canfdi_count_inc(sat);
  }
  return y;
}

int32_t canfdi_svf_init(canfdi_svf_t *f, const canfdi_svf_cfg_t *cfg)
{
  int32_t out = -CANFDI_EINVAL;
  if ((f != NULL) && (cfg != NULL) && ((cfg->order == 2U) || (cfg->order == 3U)) &&
      (cfg->omega_c_rad_s >= 1) && (cfg->omega_c_rad_s <= 32767)) {
    uint64_t p = (uint64_t)cfg->omega_c_rad_s * (uint64_t)CANFDI_CFG_STEP_US;
    uint64_t q = SVF_H_DEN;
    const uint64_t g = svf_gcd_u64(p, q);
    p /= g;
    q /= g;
    if ((p <= q) && ((p + q) < SVF_PQ_LIMIT)) {
      /* G_ij = p A_ij / (p + q)^n with A = q^(n-1) adj(I - hM)(h = p/q):
       * every term is an exact integer below 2^62 (p, q < 2^20). */
      const int64_t pi = (int64_t)p;
      const int64_t qi = (int64_t)q;
      int64_t a[CANFDI_SVF_MAX_ORDER][CANFDI_SVF_MAX_ORDER] = {{0}};
      uint64_t den = (p + q) * (p + q);
      unsigned i;
      unsigned j;
      if (cfg->order == 2U) {
        a[0][0] = qi + 2 * pi;
        a[0][1] = pi;
        a[1][0] = -pi;
        a[1][1] = qi;
      } else {
        den *= (p + q);
        a[0][0] = qi * qi + 3 * pi * qi + 3 * pi * pi;
        a[0][1] = pi * qi + 3 * pi * pi;
        a[0][2] = pi * pi;
        a[1][0] = -pi * pi;
        a[1][1] = qi * qi + 3 * pi * qi;
        a[1][2] = pi * qi;
        a[2][0] = -pi * qi;
        a[2][1] = -3 * pi * qi - pi * pi;
        a[2][2] = qi * qi;
      }
      f->cfg = *cfg;
      for (i = 0U; i < CANFDI_SVF_MAX_ORDER; i++) {
        for (j = 0U; j < CANFDI_SVF_MAX_ORDER; j++) {
          f->g_q31[i][j] = (a[i][j] == 0) ? 0 : svf_ratio_q31(pi * a[i][j], den);
        }
      }
      f->diag.steps = 0U;
      f->diag.resets = 0U;
      f->diag.out_saturations = 0U;
      canfdi_svf_reset(f, 0);
      f->diag.resets = 0U;
      out = CANFDI_OK;
    }
  }
  return out;
}

void canfdi_svf_reset(canfdi_svf_t *f, int32_t x0_q16)
{
  unsigned i;
  CANFDI_ASSERT(f != NULL);
  for (i = 0U; i < CANFDI_SVF_MAX_ORDER; i++) {
    f->v_q32[i] = 0;
  }
  f->v_q32[0] = (int64_t)x0_q16 * 65536;
  f->u_prev_q16 = x0_q16;
  f->y_q16 = x0_q16;
  f->dy_q16 = 0;
  f->d2y_q16 = 0;
  canfdi_count_inc(&f->diag.resets);
}

void canfdi_svf_step(canfdi_svf_t *f, int32_t x_q16)
{
  int64_t w[CANFDI_SVF_MAX_ORDER];
  int64_t s;
  unsigned n;
  unsigned i;
  unsigned j;
  CANFDI_ASSERT(f != NULL);
  n = f->cfg.order;
  CANFDI_ASSERT((n == 2U) || (n == 3U));

  /* w = 2 M v(k) + b (u(k) + u(k+1)), Q31.32. The input sum is exact:
   * |u(k) + u(k+1)| < 2^32, times 2^16 < 2^48. */
  s = ((int64_t)f->u_prev_q16 + (int64_t)x_q16) * 65536;
  s = canfdi_sub_s64_sat(s, canfdi_shl64_sat(f->v_q32[0], 1U));
  if (n == 2U) {
    w[0] = canfdi_shl64_sat(f->v_q32[1], 1U);
    s = canfdi_sub_s64_sat(s, canfdi_shl64_sat(f->v_q32[1], 2U));
    w[1] = s;
  } else {
    const int64_t v12 = canfdi_add_s64_sat(f->v_q32[1], f->v_q32[2]);
    w[0] = canfdi_shl64_sat(f->v_q32[1], 1U);
    w[1] = canfdi_shl64_sat(f->v_q32[2], 1U);
    /* 6 (v2 + v3) = 4 (v2 + v3) + 2 (v2 + v3) */
    s = canfdi_sub_s64_sat(s, canfdi_shl64_sat(v12, 2U));
    s = canfdi_sub_s64_sat(s, canfdi_shl64_sat(v12, 1U));
    w[2] = s;
  }

  /* v(k+1) = v(k) + G w */
  for (i = 0U; i < n; i++) {
    int64_t dv = 0;
    for (j = 0U; j < n; j++) {
      dv = canfdi_add_s64_sat(dv, canfdi_mul_s64_q31(w[j], f->g_q31[i][j]));
    }
    f->v_q32[i] = canfdi_add_s64_sat(f->v_q32[i], dv);
  }
  f->u_prev_q16 = x_q16;

  f->y_q16 = svf_out_q16(f->v_q32[0], f->cfg.omega_c_rad_s, 0U, &f->diag.out_saturations);
  f->dy_q16 = svf_out_q16(f->v_q32[1], f->cfg.omega_c_rad_s, 1U, &f->diag.out_saturations);
  if (n == 2U) {
    /* f_2(k+1) = u(k+1) - v1 - 2 v2 (normalised second derivative) */
    s = canfdi_sub_s64_sat((int64_t)x_q16 * 65536, f->v_q32[0]);
    s = canfdi_sub_s64_sat(s, canfdi_shl64_sat(f->v_q32[1], 1U));
  } else {
    s = f->v_q32[2];
  }
  f->d2y_q16 = svf_out_q16(s, f->cfg.omega_c_rad_s, 2U, &f->diag.out_saturations);
  canfdi_count_inc(&f->diag.steps);
}

int32_t canfdi_svf_y_q16(const canfdi_svf_t *f)
{
  CANFDI_ASSERT(f != NULL);
  return f->y_q16;
}

int32_t canfdi_svf_dy_q16(const canfdi_svf_t *f)
{
  CANFDI_ASSERT(f != NULL);
  return f->dy_q16;
}

int32_t canfdi_svf_d2y_q16(const canfdi_svf_t *f)
{
  CANFDI_ASSERT(f != NULL);
  return f->d2y_q16;
}

const canfdi_svf_diag_t *canfdi_svf_diag(const canfdi_svf_t *f)
{
  CANFDI_ASSERT(f != NULL);
  return &f->diag;
}
