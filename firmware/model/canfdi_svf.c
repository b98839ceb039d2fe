/*
 * canfdi_svf.c — state-variable filter; see canfdi_svf.h for the manual.
 */
#include "model/canfdi_svf.h"

#include "core/canfdi_count.h"
#include "core/canfdi_fixp.h"
#include "core/canfdi_intrin.h"

/* h = wc T / 2 = wc * STEP_US / 2e6. */
#define SVF_H_DEN 2000000U
/* init's exact arithmetic needs (p + q)^3 < 2^60 (see the header). */
#define SVF_PQ_LIMIT (1U << 20)
/* Normalised states beyond +-2^47 (2^15 units in Q31.32) saturate every
 * output because wc >= 1; clamping there keeps x * wc inside int64_t. */
#define SVF_V_CLAMP_LOG2 47U
/* The normalised states' bound, 2^50 (canfdi_svf_step): never reached. */
#define SVF_V_BOUND_LOG2 50U

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

int32_t canfdi_svf_init(canfdi_svf_t *f, const canfdi_svf_cfg_t *cfg)
{
  int32_t out = -CANFDI_EINVAL;
  if ((f != NULL) && (cfg != NULL) && ((cfg->order == 2U) || (cfg->order == 3U)) &&
      ((cfg->outputs & ~CANFDI_SVF_OUT_ALL) == 0U) && (cfg->omega_c_rad_s >= 1) && (cfg->omega_c_rad_s <= 32767)) {
    uint64_t p = (uint64_t)cfg->omega_c_rad_s * (uint64_t)CANFDI_CFG_STEP_US;
    uint64_t q = SVF_H_DEN;
    const uint64_t g = svf_gcd_u64(p, q);
    p /= g;
    q /= g;
    if ((p <= q) && ((p + q) < SVF_PQ_LIMIT)) {
      /* The last row of G: G_nj = p A_nj / (p + q)^n with
       * A = q^(n-1) adj(I - hM) (h = p/q); every term is an exact integer
       * below 2^62 (p, q < 2^20). The step needs no other row. */
      const int64_t pi = (int64_t)p;
      const int64_t qi = (int64_t)q;
      int64_t a[CANFDI_SVF_MAX_ORDER] = {0};
      uint64_t den = (p + q) * (p + q);
      unsigned j;
      if (cfg->order == 2U) {
        a[0] = -pi;
        a[1] = qi;
      } else {
        den *= (p + q);
        a[0] = -pi * qi;
        a[1] = -3 * pi * qi - pi * pi;
        a[2] = qi * qi;
      }
      f->cfg = *cfg;
      if (f->cfg.outputs == 0U) {
        f->cfg.outputs = CANFDI_SVF_OUT_ALL;
      }
      for (j = 0U; j < CANFDI_SVF_MAX_ORDER; j++) {
        f->g_q31[j] = (a[j] == 0) ? 0 : svf_ratio_q31(pi * a[j], den);
      }
      /* h = p / q in Q31; h = 1 (wc T / 2 = 1) saturates to 1 - 2^-31 */
      f->h_q31 = (p == q) ? INT32_MAX : svf_ratio_q31(pi, q);
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

/*
 * round(a g / 2^31), half up, for |a| < 2^56 and a Q31 g: canfdi_mul_s64_q31
 * without its saturation, which cannot act in this range (|result| < 2^56).
 * a = ah 2^32 + al (ah the floor, al in [0, 2^32)): 2 ah g is exact and
 * adding it does not change the rounding of al g / 2^31.
 * Cost: SMULL and UMULL with a sign fix on ARMv7-M, inline, as a call
 * costs more than the work; on ARMv6-M one call that builds both
 * products from 16-bit halves (canfdi_mul_s56_q31_rnd_h16, the same bits;
 * libgcc's 64x64 multiply costs about twice as much).
 */
static inline __attribute__((always_inline)) int64_t svf_mul_q31(int64_t a, int32_t g)
{
#if defined(__ARM_ARCH_6M__)
  return canfdi_mul_s56_q31_rnd_h16(a, g);
#else
  /* the high word read as signed is floor(a / 2^32): |ah| < 2^24 */
  const int32_t ah = canfdi_wrap_u32_to_s32((uint32_t)((uint64_t)a >> 32));
  const uint32_t al = (uint32_t)((uint64_t)a & 0xFFFFFFFFU);
  const int64_t hi = canfdi_smull32(ah, g); /* |hi| < 2^55 */
  /* al g with al unsigned: the unsigned product less al 2^32 for a
   * negative g, modulo 2^64 by design (exact as a signed value: |al g| <
   * 2^63; tests/fuzz/ignorelist.txt) */
  const uint64_t alg = canfdi_umull32(al, (uint32_t)g) - ((g < 0) ? ((uint64_t)al << 32) : 0U);
  const int64_t lo = canfdi_asr64_rnd(canfdi_wrap_u64_to_s64(alg), 31U);
  return (2 * hi) + lo;
#endif
}

/* x clipped to [-2^e, 2^e], e in 32..62. x lies in [-2^e, 2^e) exactly
 * when its high word (signed) lies in [-2^(e-32), 2^(e-32)): a range test
 * of one word (the compiler makes it one add and one compare) decides the
 * common case, where two 64-bit compares take six instructions (some
 * sixty clips a step); the rest is compared in full. */
static inline __attribute__((always_inline)) int64_t svf_clip(int64_t x, unsigned e)
{
  const int64_t b = (int64_t)1 << e;
  const int32_t hi = canfdi_wrap_u32_to_s32((uint32_t)((uint64_t)x >> 32));
  const int32_t h = (int32_t)1 << (e - 32U);
  int64_t y = x;
  if ((hi < -h) || (hi >= h)) {
    y = (x > b) ? b : ((x < -b) ? -b : x);
  }
  return y;
}

/* x limited to +-2^50 (see svf_state_add): in range always (see the
 * header). */
static inline __attribute__((always_inline)) int64_t svf_bound(int64_t x)
{
  return svf_clip(x, SVF_V_BOUND_LOG2);
}

/*
 * The Q16.16 value of wc^k v (v normalised Q31.32, k = 0, 1, 2), rounded
 * half up and saturated (counted in *sat). Scaling and overflow: v is
 * clamped to +-2^47 (SVF_V_CLAMP_LOG2: beyond it every output saturates, as
 * wc >= 1) before each multiply by wc < 2^15, so every product stays below
 * 2^62. One function per k: a loop over a run-time k costs more than the
 * work.
 */
static inline __attribute__((always_inline)) int32_t svf_out_k0(int64_t v, uint32_t *sat)
{
  /* saturated when x does not fit 32 bits (canfdi_sat_s64_to_s32's own
   * test, which the compiler shares; a 64-bit compare of y with x costs
   * more) */
  const int64_t x = canfdi_asr64_rnd(v, 16U);
  const int32_t y = canfdi_sat_s64_to_s32(x);
  if (!canfdi_s64_fits_s32(x)) {
    canfdi_count_inc(sat);
  }
  return y;
}

/* c wc for |c| <= 2^47 (the clamp) and wc in 1..32767: exact. On
 * ARMv6-M from 32-bit multiplies (canfdi_mul_s48_u15_h16), not libgcc's
 * 64x64 multiply. */
static inline __attribute__((always_inline)) int64_t svf_mul_wc(int64_t c, int32_t wc)
{
#if defined(__ARM_ARCH_6M__)
  return canfdi_mul_s48_u15_h16(c, wc);
#else
  return c * (int64_t)wc;
#endif
}

static inline int32_t svf_out_k1(int64_t v, int32_t wc, uint32_t *sat)
{
  return svf_out_k0(svf_mul_wc(svf_clip(v, SVF_V_CLAMP_LOG2), wc), sat);
}

static inline int32_t svf_out_k2(int64_t v, int32_t wc, uint32_t *sat)
{
  const int64_t x = svf_clip(svf_mul_wc(svf_clip(v, SVF_V_CLAMP_LOG2), wc), SVF_V_CLAMP_LOG2);
  return svf_out_k0(svf_mul_wc(x, wc), sat);
}

/*
 * The step with plain 64-bit sums. Scaling and overflow: the normalised
 * states of the (stable, non-expansive) filter stay below the input range,
 * |v_i| <= L1_i 2^47 with the L1 norms of the state impulse responses at
 * most 1 (v_1), 0.74 (v_2, n = 2), 0.55 and 0.63 (v_2, v_3, n = 3) over the
 * whole wc domain; svf_bound keeps them within 2^50 whatever happens, so
 * |w_n| < 2^54 and |w_i| < 2^51 (i < n). G's last row over h in (0, 1]:
 * n = 3, |G_31| = h^2 / (1 + h)^3 <= 1/8, |G_32| = h^2 (3 + h) / (1 + h)^3
 * <= 1/2, G_33 = h / (1 + h)^3 < 0.15; n = 2, both entries h^2 / (1 + h)^2
 * and h / (1 + h)^2 <= 1/4. So |dv_n| < 2^52, each back substitution
 * w_i + dv_(i+1) stays below 2^53 and its product too: every operand is
 * within svf_mul_q31's 2^56, nothing below can overflow, and the result is
 * the same as with saturating sums.
 */
void canfdi_svf_step(canfdi_svf_t *f, int32_t x_q16)
{
  const int32_t wc = f->cfg.omega_c_rad_s;
  const int64_t v0 = f->v_q32[0];
  const int64_t v1 = f->v_q32[1];
  /* the input sum u(k) + u(k+1) is exact: < 2^32, times 2^16 < 2^48 */
  const int64_t us = ((int64_t)f->u_prev_q16 + (int64_t)x_q16) * 65536;
  int64_t d2;
  CANFDI_ASSERT(f != NULL);
  CANFDI_ASSERT((f->cfg.order == 2U) || (f->cfg.order == 3U));
  if (f->cfg.order == 2U) {
    /* w = (2 v2, u(k) + u(k+1) - 2 v1 - 4 v2); dv2 from G's last row,
     * dv1 = h (w1 + dv2) (the first row of (I - hM) dv = h w) */
    const int64_t w0 = 2 * v1;
    const int64_t w1 = us - (2 * v0) - (4 * v1);
    const int64_t dv1 = svf_mul_q31(w0, f->g_q31[0]) + svf_mul_q31(w1, f->g_q31[1]);
    const int64_t n1 = svf_bound(v1 + dv1);
    const int64_t n0 = svf_bound(v0 + svf_mul_q31(w0 + dv1, f->h_q31));
    f->v_q32[0] = n0;
    f->v_q32[1] = n1;
    /* f_2(k+1) = u(k+1) - v1 - 2 v2 (normalised second derivative) */
    d2 = ((int64_t)x_q16 * 65536) - n0 - (2 * n1);
  } else {
    const int64_t v2 = f->v_q32[2];
    /* w = (2 v2, 2 v3, u(k) + u(k+1) - 2 v1 - 6 (v2 + v3)); dv3 from G's
     * last row, then dv2 = h (w2 + dv3) and dv1 = h (w1 + dv2) (the first
     * two rows of (I - hM) dv = h w) */
    const int64_t w0 = 2 * v1;
    const int64_t w1 = 2 * v2;
    const int64_t s12 = v1 + v2;
    /* - 6 (v2 + v3) as - 2 (v1 + v2 + v3) - 4 (v2 + v3), the same sum: at
     * -Os GCC turns a 64-bit product by 6 into a libgcc call on ARMv6-M */
    const int64_t w2 = (us - (2 * (v0 + s12))) - (4 * s12);
    const int64_t dv2 =
        (svf_mul_q31(w0, f->g_q31[0]) + svf_mul_q31(w1, f->g_q31[1])) + svf_mul_q31(w2, f->g_q31[2]);
    const int64_t dv1 = svf_mul_q31(w1 + dv2, f->h_q31);
    const int64_t n2 = svf_bound(v2 + dv2);
    const int64_t n1 = svf_bound(v1 + dv1);
    const int64_t n0 = svf_bound(v0 + svf_mul_q31(w0 + dv1, f->h_q31));
    f->v_q32[0] = n0;
    f->v_q32[1] = n1;
    f->v_q32[2] = n2;
    d2 = n2;
  }
  f->u_prev_q16 = x_q16;
  if ((f->cfg.outputs & CANFDI_SVF_OUT_Y) != 0U) {
    f->y_q16 = svf_out_k0(f->v_q32[0], &f->diag.out_saturations);
  }
  if ((f->cfg.outputs & CANFDI_SVF_OUT_DY) != 0U) {
    f->dy_q16 = svf_out_k1(f->v_q32[1], wc, &f->diag.out_saturations);
  }
  if ((f->cfg.outputs & CANFDI_SVF_OUT_D2Y) != 0U) {
    f->d2y_q16 = svf_out_k2(d2, wc, &f->diag.out_saturations);
  }
  canfdi_count_inc(&f->diag.steps);
}

int32_t canfdi_svf_y_q16(const canfdi_svf_t *f)
{
  CANFDI_ASSERT((f != NULL) && ((f->cfg.outputs & CANFDI_SVF_OUT_Y) != 0U));
  return f->y_q16;
}

int32_t canfdi_svf_dy_q16(const canfdi_svf_t *f)
{
  CANFDI_ASSERT((f != NULL) && ((f->cfg.outputs & CANFDI_SVF_OUT_DY) != 0U));
  return f->dy_q16;
}

int32_t canfdi_svf_d2y_q16(const canfdi_svf_t *f)
{
  CANFDI_ASSERT((f != NULL) && ((f->cfg.outputs & CANFDI_SVF_OUT_D2Y) != 0U));
  return f->d2y_q16;
}

const canfdi_svf_diag_t *canfdi_svf_diag(const canfdi_svf_t *f)
{
  CANFDI_ASSERT(f != NULL);
  return &f->diag;
}
