/*
 * canfdi_parity_dcm.c — structured parity residuals of the DC motor drive;
 * see canfdi_parity_dcm.h for the manual.
 */
#include "model/canfdi_parity_dcm.h"

#include "core/canfdi_count.h"
#include "core/canfdi_intrin.h"
#include "core/canfdi_qconst.h"

/* Fraction bits of the residual accumulator (Q23.40 in int64_t). */
#define PDCM_ACC_FRAC 40U
/* Fraction bits of the parameters. */
#define PDCM_PAR_FRAC 24U
/* Fraction bits of the SVF outputs per signal (Q16.16 scaled down). */
#define PDCM_FRAC_U 16U
#define PDCM_FRAC_I (16U - CANFDI_PARITY_DCM_I_PRESCALE)
#define PDCM_FRAC_W (16U - CANFDI_PARITY_DCM_W_PRESCALE)
#define PDCM_FRAC_Z 16U
/* |r1| used in the R_A least-squares sums: clamped to 64 V (2^22 in Q16.16)
 * so that N * |r1 * I| < 2^63 for every allowed block length. */
#define PDCM_R1_SUM_CLAMP ((int32_t)1 << 22)

/* ------------------------------------------------------------------------ */
/* Coefficients: value = m * 2^-f with |m| in [2^29, 2^31)                   */
/* ------------------------------------------------------------------------ */

/*
 * The coefficient (num * 2^-num_frac) / (den * 2^-den_frac), normalised so
 * that |m| is in [2^29, 2^31), i.e. ~30 significant bits whatever the size.
 * Scaling and overflow: both magnitudes are shifted up to [2^61, 2^62) (the
 * shift counts go into the exponent), then the mantissa is their quotient
 * in Q30 rounded half up (canfdi_div_u62_q30_rnd: exact, one 64/32
 * division). No 64-bit divide call. num == 0 or den <= 0 gives {0, 0}. A
 * value too large for f >= 0 saturates to {INT32_MAX, 0} (unreachable for
 * parameters inside the validated domain); a value below 2^-200 becomes 0.
 * Cost: a leading-zero count and one shift per operand, then the division
 * (two 32-bit divisions: UDIV on ARMv7-M, __aeabi_uidiv on ARMv6-M); run at
 * init and when an R_A block moves the estimate (four ratios then).
 */
static canfdi_parity_dcm_coef_t pdcm_coef_ratio(int64_t num, unsigned num_frac, int64_t den,
                                                unsigned den_frac)
{
  canfdi_parity_dcm_coef_t c = {0, 0U};
  if ((num != 0) && (den > 0)) {
    const bool neg = (num < 0);
    /* |num| without unsigned wrap-around: -(num + 1) fits int64 for every
     * num < 0 (INT64_MIN included) */
    uint64_t a = neg ? ((uint64_t)(-(num + 1)) + 1U) : (uint64_t)num;
    uint64_t b = (uint64_t)den;
    int32_t e = (int32_t)num_frac - (int32_t)den_frac; /* f = 30 + e after normalisation */
    uint64_t q;
    /* a and b into [2^61, 2^62) by one shift each (their leading one to
     * bit 61: two leading zeros), the exponent following */
    {
      const int32_t ka = (int32_t)canfdi_clz64(a) - 2; /* a != 0 */
      const int32_t kb = (int32_t)canfdi_clz64(b) - 2; /* b > 0 */
      const unsigned sa = (unsigned)((ka >= 0) ? ka : -ka);
      const unsigned sb = (unsigned)((kb >= 0) ? kb : -kb);
      a = (ka >= 0) ? (a << sa) : (a >> sa); /* right only for |num| >= 2^62 */
      b = (kb >= 0) ? (b << sb) : (b >> sb);
      e += ka - kb;
    }
    /* a / b in (1/2, 2): q = round(a / b * 2^30) in [2^29, 2^31]. */
    q = canfdi_div_u62_q30_rnd(a, b);
    if (q >= ((uint64_t)1U << 31)) {
      q >>= 1; /* exact: q was 2^31 */
      e -= 1;
    }
    e += 30;
    if (e < 0) {
      c.m = neg ? -INT32_MAX : INT32_MAX;
      c.f = 0U;
    } else if (e > 200) {
      c.m = 0;
      c.f = 0U;
    } else {
      c.m = neg ? -(int32_t)q : (int32_t)q;
      c.f = (uint8_t)e;
    }
  }
  return c;
}

/* A Q8.24 parameter as a coefficient (exact, not normalised). */
static canfdi_parity_dcm_coef_t pdcm_coef_q24(int32_t x_q24)
{
  canfdi_parity_dcm_coef_t c;
  c.m = x_q24;
  c.f = (uint8_t)PDCM_PAR_FRAC;
  return c;
}

/*
 * acc +- c * x, x with fx fraction bits, in the Q23.40 accumulator.
 * Scaling and overflow: |m * x| < 2^62 exactly in int64_t; aligned to Q40
 * by a round-half-up right shift (f + fx > 40) or a saturating left shift;
 * the sum saturates (canfdi_add_s64_sat / canfdi_sub_s64_sat).
 */
/* 35 times a step: always inline except on ARMv6-M (CANFDI_V7M_INLINE,
 * core/canfdi_fixp.h), where the product is a call anyway; on ARMv7-M a
 * call, its stacked arguments and saved registers cost about a third of
 * the work. */
static CANFDI_V7M_INLINE int64_t pdcm_mac(int64_t acc, canfdi_parity_dcm_coef_t c, int32_t x, unsigned fx, bool sub)
{
  const int64_t p = canfdi_smull32(c.m, x); /* SMULL; ARMv6-M: 16-bit halves */
  const int32_t s = (int32_t)c.f + (int32_t)fx - (int32_t)PDCM_ACC_FRAC;
  int64_t t;
  if ((s >= 1) && (s <= 31)) {
    /* the usual case, on the two 32-bit halves (a run-time 64-bit shift
     * is a branchy sequence on ARMv7-M and a libgcc call on ARMv6-M):
     * floor(p / 2^s) plus the last bit shifted out, as canfdi_asr64_rnd */
    const uint64_t u = (uint64_t)p;
    const uint32_t lo = (uint32_t)u;
    const uint32_t hi = (uint32_t)(u >> 32);
    const unsigned k = (unsigned)s;
    /* the high word's low k bits move down: masked first, so that the left
     * shift drops nothing */
    const uint32_t mask = ((uint32_t)1U << k) - 1U;
    const uint32_t rlo = (lo >> k) | ((hi & mask) << (32U - k));
    const int32_t rhi = canfdi_asr32(canfdi_wrap_u32_to_s32(hi), k);
    t = canfdi_wrap_u64_to_s64(((uint64_t)(uint32_t)rhi << 32) | rlo) + (int64_t)((lo >> (k - 1U)) & 1U);
  } else {
    t = (s >= 0) ? canfdi_asr64_rnd(p, (unsigned)s) : canfdi_shl64_sat(p, (unsigned)(-s));
  }
  return sub ? canfdi_sub_s64_sat(acc, t) : canfdi_add_s64_sat(acc, t);
}

/* A Q16.16 value into the Q40 accumulator (exact, saturating). */
static int64_t pdcm_add_q16(int64_t acc, int32_t x_q16, bool sub)
{
  const int64_t t = (int64_t)x_q16 * ((int64_t)1 << (PDCM_ACC_FRAC - 16U));
  return sub ? canfdi_sub_s64_sat(acc, t) : canfdi_add_s64_sat(acc, t);
}

/* The Q40 accumulator rounded half up to Q16.16, saturated; counts. */
static int32_t pdcm_acc_out(canfdi_parity_dcm_t *p, int64_t acc)
{
  const int64_t r = canfdi_asr64_rnd(acc, PDCM_ACC_FRAC - 16U);
  const int32_t y = canfdi_sat_s64_to_s32(r);
  if ((int64_t)y != r) {
    canfdi_count_inc(&p->diag.res_saturations);
  }
  return y;
}

/* The R_A-dependent coefficients (init and after each R_A update). */
static void pdcm_coef_ra(canfdi_parity_dcm_t *p)
{
  const canfdi_parity_dcm_cfg_t *c = p->cfg;
  const int64_t ra = (int64_t)p->ra_hat_ohm_q24;
  /* Q48 products of two Q24 values; each < 2^62, sums < 2^63. */
  p->k[CANFDI_PDCM_K_R] = pdcm_coef_q24(p->ra_hat_ohm_q24);
  p->k[CANFDI_PDCM_K_CI] =
      pdcm_coef_ratio(((int64_t)c->psi_Vs_q24 * c->psi_Vs_q24) + ((int64_t)c->mf1_Nms_q24 * ra),
                      48U, c->psi_Vs_q24, 24U);
  p->k[CANFDI_PDCM_K_CDI] =
      pdcm_coef_ratio(((int64_t)c->j_kgm2_q24 * ra) + ((int64_t)c->mf1_Nms_q24 * c->la_H_q24), 48U,
                      c->psi_Vs_q24, 24U);
  p->k[CANFDI_PDCM_K_RP] = pdcm_coef_ratio(ra, 24U, c->psi_Vs_q24, 24U);
}

/* ------------------------------------------------------------------------ */
/* Configuration                                                            */
/* ------------------------------------------------------------------------ */

static bool pdcm_in(int32_t x, int32_t lo, int32_t hi)
{
  return (x >= lo) && (x <= hi);
}

int32_t canfdi_parity_dcm_cfg_check(const canfdi_parity_dcm_cfg_t *cfg)
{
  int32_t out = CANFDI_OK;
  unsigned k;
  if (cfg == NULL) {
    out = -CANFDI_EINVAL;
  } else if (!pdcm_in(cfg->ra_ohm_q24, CANFDI_Q24(1, 1000), CANFDI_Q24(100, 1)) ||
             !pdcm_in(cfg->la_H_q24, CANFDI_Q24(1, 1000000), CANFDI_Q24(1, 1)) ||
             !pdcm_in(cfg->psi_Vs_q24, CANFDI_Q24(1, 100), CANFDI_Q24(10, 1)) ||
             !pdcm_in(cfg->j_kgm2_q24, CANFDI_Q24(1, 1000000), CANFDI_Q24(10, 1)) ||
             !pdcm_in(cfg->mf1_Nms_q24, 0, CANFDI_Q24(1, 1)) ||
             !pdcm_in(cfg->mf0_Nm_q24, 0, CANFDI_Q24(10, 1)) ||
             !pdcm_in(cfg->omega_c_rad_s, 20, 1000) ||
             !pdcm_in(cfg->w_band_rad_s_q16, 1, 100 * CANFDI_Q16_ONE)) {
    out = -CANFDI_EINVAL;
  } else if ((cfg->ra_track != 0U) &&
             ((cfg->ra_block_steps < 10U) || (cfg->ra_block_steps > 1000U) ||
              ((uint64_t)cfg->ra_tau_s * 1000000U <
               (uint64_t)cfg->ra_block_steps * (uint64_t)CANFDI_CFG_STEP_US) ||
              (cfg->ra_tau_s > CANFDI_PARITY_DCM_TAU_MAX_S) ||
              !pdcm_in(cfg->ra_i_min_A_q16, 1, 30 * CANFDI_Q16_ONE) ||
              !pdcm_in(cfg->ra_gate_q16, 1, 32 * CANFDI_Q16_ONE) ||
              !pdcm_in(cfg->ra_rate_max_ohm_s_q24, 0, CANFDI_Q24(1, 1)) ||
              !pdcm_in(cfg->ra_min_ohm_q24, CANFDI_Q24(1, 1000), cfg->ra_ohm_q24) ||
              !pdcm_in(cfg->ra_max_ohm_q24, cfg->ra_ohm_q24, CANFDI_Q24(100, 1)))) {
    out = -CANFDI_EINVAL;
  } else if (!pdcm_in(cfg->unc_ra_ohm_q24, 0, cfg->ra_ohm_q24) ||
             !pdcm_in(cfg->unc_la_H_q24, 0, cfg->la_H_q24) ||
             !pdcm_in(cfg->unc_j_kgm2_q24, 0, cfg->j_kgm2_q24)) {
    out = -CANFDI_EINVAL;
  } else if ((cfg->load_tau_s > CANFDI_PARITY_DCM_TAU_MAX_S) ||
             ((cfg->load_tau_s != 0U) &&
              ((uint64_t)cfg->load_tau_s * 1000000U < 10U * (uint64_t)CANFDI_CFG_STEP_US))) {
    out = -CANFDI_EINVAL;
  } else {
    for (k = 0U; k < CANFDI_PARITY_DCM_N_RES; k++) {
      if ((canfdi_adapt_cfg_check(&cfg->band[k]) != CANFDI_OK) || (cfg->band[k].base <= 0)) {
        out = -CANFDI_EINVAL;
      }
    }
  }
  return out;
}

/* ------------------------------------------------------------------------ */
/* Life cycle                                                               */
/* ------------------------------------------------------------------------ */

static void pdcm_clear_block(canfdi_parity_dcm_t *p)
{
  p->blk_ri = 0;
  p->blk_ii = 0;
  p->blk_rn = 0;
  p->blk_n = 0U;
  p->blk_invalid = false;
}

int32_t canfdi_parity_dcm_init(canfdi_parity_dcm_t *p, const canfdi_parity_dcm_cfg_t *cfg)
{
  int32_t out = canfdi_parity_dcm_cfg_check(cfg);
  if (p == NULL) {
    out = -CANFDI_EINVAL;
  }
  if (out == CANFDI_OK) {
    canfdi_svf_cfg_t sc;
    unsigned k;
    sc.order = 3U;
    sc.omega_c_rad_s = cfg->omega_c_rad_s;
    /* cfg was checked: none of these can fail. Each filter computes the
     * outputs the residuals read. */
    sc.outputs = (uint8_t)(CANFDI_SVF_OUT_Y | CANFDI_SVF_OUT_DY);
    out = canfdi_svf_init(&p->svf_u, &sc);
    out = (out == CANFDI_OK) ? canfdi_svf_init(&p->svf_z, &sc) : out;
    sc.outputs = CANFDI_SVF_OUT_ALL;
    out = (out == CANFDI_OK) ? canfdi_svf_init(&p->svf_i, &sc) : out;
    out = (out == CANFDI_OK) ? canfdi_svf_init(&p->svf_w, &sc) : out;
    for (k = 0U; (out == CANFDI_OK) && (k < CANFDI_PARITY_DCM_N_RES); k++) {
      out = canfdi_adapt_init(&p->thr[k], &cfg->band[k]);
    }
    if (out == CANFDI_OK) {
      p->cfg = cfg;
      p->ra_hat_ohm_q24 = cfg->ra_ohm_q24;
      p->k[CANFDI_PDCM_K_L] = pdcm_coef_ratio(cfg->la_H_q24, 24U, 1, 0U);
      p->k[CANFDI_PDCM_K_PSI] = pdcm_coef_ratio(cfg->psi_Vs_q24, 24U, 1, 0U);
      p->k[CANFDI_PDCM_K_J] = pdcm_coef_ratio(cfg->j_kgm2_q24, 24U, 1, 0U);
      p->k[CANFDI_PDCM_K_F1] = pdcm_coef_ratio(cfg->mf1_Nms_q24, 24U, 1, 0U);
      p->k[CANFDI_PDCM_K_CD2I] = pdcm_coef_ratio((int64_t)cfg->la_H_q24 * cfg->j_kgm2_q24, 48U,
                                                 cfg->psi_Vs_q24, 24U);
      p->k[CANFDI_PDCM_K_JP] = pdcm_coef_ratio(cfg->j_kgm2_q24, 24U, cfg->psi_Vs_q24, 24U);
      p->k[CANFDI_PDCM_K_FP] = pdcm_coef_ratio(cfg->mf1_Nms_q24, 24U, cfg->psi_Vs_q24, 24U);
      p->k[CANFDI_PDCM_K_LP] = pdcm_coef_ratio(cfg->la_H_q24, 24U, cfg->psi_Vs_q24, 24U);
      p->k[CANFDI_PDCM_K_INVB] = pdcm_coef_ratio(1, 0U, cfg->w_band_rad_s_q16, 16U);
      p->k[CANFDI_PDCM_K_IP] = pdcm_coef_ratio(1, 0U, cfg->psi_Vs_q24, 24U);
      p->k[CANFDI_PDCM_K_ONE] = pdcm_coef_ratio(1, 0U, 1, 0U);
      pdcm_coef_ra(p);
      if (cfg->ra_track != 0U) {
        const uint64_t blk_us = (uint64_t)cfg->ra_block_steps * (uint64_t)CANFDI_CFG_STEP_US;
        /* N T / tau <= 1 (checked) in Q31; rate * N T in Q24 (< 2^24 * 1000). */
        p->ra_gain_q31 = (canfdi_q31_t)canfdi_sat_s64_to_s32(
            (int64_t)((((uint64_t)blk_us << 31) + ((uint64_t)cfg->ra_tau_s * 500000U)) /
                      ((uint64_t)cfg->ra_tau_s * 1000000U)));
        p->ra_step_max_q24 = canfdi_sat_s64_to_s32(
            (int64_t)(((uint64_t)cfg->ra_rate_max_ohm_s_q24 * blk_us + 500000U) / 1000000U));
      } else {
        p->ra_gain_q31 = 0;
        p->ra_step_max_q24 = 0;
      }
      if (cfg->load_tau_s != 0U) {
        p->load_alpha_q31 = (canfdi_q31_t)canfdi_sat_s64_to_s32((int64_t)(
            (((uint64_t)CANFDI_CFG_STEP_US << 31) + ((uint64_t)cfg->load_tau_s * 500000U)) /
            ((uint64_t)cfg->load_tau_s * 1000000U)));
      } else {
        p->load_alpha_q31 = 0;
      }
      p->diag.steps = 0U;
      p->diag.resets = 0U;
      p->diag.res_saturations = 0U;
      p->diag.ra_updates = 0U;
      p->diag.ra_blocks_rejected = 0U;
      p->diag.ra_limit_hits = 0U;
      p->diag.load_holds = 0U;
      canfdi_parity_dcm_reset(p);
      p->diag.resets = 0U;
    }
  }
  if ((p != NULL) && (out != CANFDI_OK)) {
    p->cfg = NULL; /* unbound: step() and reset() refuse it */
  }
  return out;
}

void canfdi_parity_dcm_reset(canfdi_parity_dcm_t *p)
{
  unsigned k;
  if ((p != NULL) && (p->cfg != NULL)) {
    p->primed = false;
    p->settle = p->cfg->settle_steps;
    p->w_ok = 0U;
    p->load_hold = 0U;
    p->load_prev_q16 = 0;
    p->ra_learn_left = (p->cfg->ra_track != 0U) ? p->cfg->ra_learn_blocks : 0U;
    p->i_prev_q16 = 0;
    p->w_prev_q16 = 0;
    pdcm_clear_block(p);
    for (k = 0U; k < 3U; k++) {
      p->bias_q32[k] = 0;
    }
    for (k = 0U; k < CANFDI_PARITY_DCM_N_RES; k++) {
      canfdi_adapt_reset(&p->thr[k]);
      p->out.r_q16[k] = 0;
      p->out.rn_q16[k] = 0;
      p->out.thr_q16[k] = canfdi_adapt_threshold(&p->thr[k]);
    }
    p->out.valid = 0U;
    p->out.exceed = 0U;
    p->out.ra_hat_ohm_q24 = p->ra_hat_ohm_q24;
    p->out.ra_at_limit = false;
    canfdi_count_inc(&p->diag.resets);
  }
}

void canfdi_parity_dcm_restart(canfdi_parity_dcm_t *p)
{
  if ((p != NULL) && (p->cfg != NULL)) {
    const uint16_t left = p->ra_learn_left;
    canfdi_parity_dcm_reset(p);
    p->ra_learn_left = (left == 0U) ? 0U : p->ra_learn_left;
  }
}

int32_t canfdi_parity_dcm_set_ra(canfdi_parity_dcm_t *p, int32_t ra_ohm_q24)
{
  int32_t out = -CANFDI_EINVAL;
  if ((p != NULL) && (p->cfg != NULL) && pdcm_in(ra_ohm_q24, CANFDI_Q24(1, 1000), CANFDI_Q24(100, 1))) {
    p->ra_hat_ohm_q24 = ra_ohm_q24;
    if (p->cfg->ra_track != 0U) {
      p->ra_hat_ohm_q24 =
          canfdi_clamp_s32(ra_ohm_q24, p->cfg->ra_min_ohm_q24, p->cfg->ra_max_ohm_q24);
    }
    pdcm_coef_ra(p);
    pdcm_clear_block(p);
    p->out.ra_hat_ohm_q24 = p->ra_hat_ohm_q24;
    out = CANFDI_OK;
  }
  return out;
}

/* ------------------------------------------------------------------------ */
/* The step                                                                 */
/* ------------------------------------------------------------------------ */

/*
 * End of an R_A block: least-squares estimate of the remaining R_A error
 * from the block, dR = sum(r1 I) / sum(I^2), moved into R_A by the fraction
 * N T / tau, bounded by the thermal rate and the plausible range.
 * Scaling and overflow: the sums are Q32 in int64 (< 2^53, see the header);
 * dR comes from the normalising long division (30 significant bits) and is
 * rounded half up to Q24, saturated at +-128 Ohm; the step is a rounded Q31
 * multiply (or a rounded shift by 2 while learning) and the sum with R_A
 * saturates before the range clamp.
 */
static void pdcm_ra_block(canfdi_parity_dcm_t *p)
{
  const canfdi_parity_dcm_cfg_t *c = p->cfg;
  const int64_t i_min = (int64_t)c->ra_i_min_A_q16;
  const int64_t ii_min = i_min * i_min * (int64_t)c->ra_block_steps; /* < 2^62 */
  const bool learning = (p->ra_learn_left > 0U);
  /* gate on the block mean of r1 / threshold (noise peaks must not stop
   * the tracker; a fault moves the mean) */
  const int64_t gate = (int64_t)c->ra_gate_q16 * (int64_t)c->ra_block_steps;
  const bool bad = (p->blk_rn > gate) || (p->blk_rn < -gate);
  if ((bad && !learning) || p->blk_invalid || (p->blk_ii < ii_min)) {
    canfdi_count_inc(&p->diag.ra_blocks_rejected);
  } else {
    /* dR in Q24: both sums are Q32 (Q16.16 x Q16.16). */
    const canfdi_parity_dcm_coef_t q = pdcm_coef_ratio(p->blk_ri, 32U, p->blk_ii, 32U);
    const int32_t s = (int32_t)q.f - (int32_t)PDCM_PAR_FRAC;
    const int32_t dr_q24 = (s >= 0) ? canfdi_sat_s64_to_s32(canfdi_asr64_rnd((int64_t)q.m, (unsigned)s))
                                    : canfdi_shl32_sat(q.m, (unsigned)(-s));
    int32_t step;
    int32_t ra;
    bool hit = false;
    if (learning) {
      /* Start-up: no history tells warm-up from fault, so converge fast
       * (a quarter of the error per block) inside the plausible range. */
      step = canfdi_asr32_rnd(dr_q24, 2U);
      p->ra_learn_left = (uint16_t)(p->ra_learn_left - 1U);
    } else {
      step = canfdi_q31_mul_rnd(dr_q24, p->ra_gain_q31);
    }
    if (learning) {
      /* no rate bound while learning */
    } else if (step > p->ra_step_max_q24) {
      step = p->ra_step_max_q24;
      hit = true;
    } else if (step < -p->ra_step_max_q24) {
      step = -p->ra_step_max_q24;
      hit = true;
    } else {
      /* inside the thermal rate bound */
    }
    ra = canfdi_add_s32_sat(p->ra_hat_ohm_q24, step);
    p->out.ra_at_limit = (ra >= c->ra_max_ohm_q24) || (ra <= c->ra_min_ohm_q24);
    if (p->out.ra_at_limit) {
      hit = true;
    }
    ra = canfdi_clamp_s32(ra, c->ra_min_ohm_q24, c->ra_max_ohm_q24);
    if (hit) {
      canfdi_count_inc(&p->diag.ra_limit_hits);
    }
    if (ra != p->ra_hat_ohm_q24) {
      p->ra_hat_ohm_q24 = ra;
      pdcm_coef_ra(p);
    }
    canfdi_count_inc(&p->diag.ra_updates);
  }
  pdcm_clear_block(p);
}

/*
 * One uncertainty term |dr/dp| * dp of a band, in residual units Q16.16.
 * The sensitivity dr/dp arrives as a Q40 accumulator (built with pdcm_mac
 * from the same filtered signals as the residual).
 * Scaling and overflow: |acc| (saturating negate) is rounded half up to
 * Q16.16 and saturated (a sensitivity beyond 32767 residual units per
 * parameter unit only occurs far outside the signal ranges; the band is
 * capped by band.max anyway), then multiplied by dp (Q8.24, >= 0) with
 * canfdi_mul_s32_qn (exact 64-bit product, rounded half up, saturated).
 */
static int32_t pdcm_unc_term(int64_t acc, int32_t dp_q24)
{
  const int64_t a = (acc < 0) ? canfdi_sub_s64_sat(0, acc) : acc;
  const int32_t s_q16 = canfdi_sat_s64_to_s32(canfdi_asr64_rnd(a, PDCM_ACC_FRAC - 16U));
  return canfdi_mul_s32_qn(s_q16, dp_q24, PDCM_PAR_FRAC);
}

/*
 * The step, phase by phase. Each phase is a static function; the step
 * calls them in this order, which is the order of the contract (the state a
 * phase reads is what the phases before it left):
 *   1. pdcm_condition   interval means of I_A and w (SVF inputs), z
 *   2. pdcm_late_load   a change of the known load starts a hold
 *   3. pdcm_filter      the four SVFs (primed on the first sample)
 *   4. pdcm_residuals   r1 .. r4
 *   5. pdcm_uncertainty the uncertainty term of each band
 *   6. pdcm_validity    settle, the standstill region, the load hold
 *   7. pdcm_load_means  r2 .. r4 follow their mean (optional)
 *   8. pdcm_thresholds  bands, normalisation, exceed flags
 *   9. pdcm_ra_track    the R_A least-squares block
 */

/* SVF inputs of one sample. */
typedef struct {
  int32_t xi; /* interval mean of I_A, / 2^I_PRESCALE */
  int32_t xw; /* interval mean of w, / 2^W_PRESCALE */
  int32_t z;  /* M_L + M_F0 sgn(w), N m */
} pdcm_in_t;

/* Filtered signals of one step (SVF outputs, each in its own format). */
typedef struct {
  int32_t u_f;
  int32_t u_d;
  int32_t i_f;
  int32_t i_d;
  int32_t i_d2;
  int32_t w_f;
  int32_t w_d;
  int32_t w_d2;
  int32_t z_f;
  int32_t z_d;
} pdcm_sig_t;

/*
 * ZOH alignment: the measured U_A is the voltage held over the interval
 * that ends now; the interval means of I_A and w are approximated by the
 * mean of the two end samples. The SVF inputs of I and w are scaled down by
 * 2^PRESCALE in the same rounding step (range of the 2nd derivative).
 * z = M_L + M_F0 sgn(w): the known torques of the mechanical equation,
 * filtered by the same SVF; sgn is linear inside +-w_band.
 */
static pdcm_in_t pdcm_condition(canfdi_parity_dcm_t *p, const canfdi_parity_dcm_in_t *in)
{
  pdcm_in_t x;
  int32_t w_avg;
  int32_t sgn_q16;
  int64_t acc;
  if (!p->primed) {
    p->i_prev_q16 = in->i_A_q16;
    p->w_prev_q16 = in->w_rad_s_q16;
  }
  x.xi = canfdi_sat_s64_to_s32(canfdi_asr64_rnd((int64_t)in->i_A_q16 + p->i_prev_q16,
                                                1U + CANFDI_PARITY_DCM_I_PRESCALE));
  x.xw = canfdi_sat_s64_to_s32(canfdi_asr64_rnd((int64_t)in->w_rad_s_q16 + p->w_prev_q16,
                                                1U + CANFDI_PARITY_DCM_W_PRESCALE));
  w_avg = canfdi_sat_s64_to_s32(canfdi_asr64_rnd((int64_t)in->w_rad_s_q16 + p->w_prev_q16, 1U));
  p->i_prev_q16 = in->i_A_q16;
  p->w_prev_q16 = in->w_rad_s_q16;
  acc = pdcm_mac(0, p->k[CANFDI_PDCM_K_INVB], w_avg, 16U, false);
  sgn_q16 = canfdi_clamp_s32(canfdi_sat_s64_to_s32(canfdi_asr64_rnd(acc, PDCM_ACC_FRAC - 16U)),
                             -CANFDI_Q16_ONE, CANFDI_Q16_ONE);
  x.z = canfdi_add_s32_sat(in->load_Nm_q16, canfdi_mul_s32_qn(p->cfg->mf0_Nm_q24, sgn_q16, 24U));
  return x;
}

/* Late load: a change of the known load holds r2..r4 (header). */
static void pdcm_late_load(canfdi_parity_dcm_t *p, int32_t load_q16)
{
  if (p->primed && (load_q16 != p->load_prev_q16) && (p->cfg->load_hold_steps != 0U)) {
    p->load_hold = p->cfg->load_hold_steps;
    canfdi_count_inc(&p->diag.load_holds);
  }
  p->load_prev_q16 = load_q16;
}

/* The four SVFs, restarted on their first sample after init/reset. */
static pdcm_sig_t pdcm_filter(canfdi_parity_dcm_t *p, int32_t u_q16, const pdcm_in_t *x)
{
  pdcm_sig_t s;
  if (!p->primed) {
    canfdi_svf_reset(&p->svf_u, u_q16);
    canfdi_svf_reset(&p->svf_i, x->xi);
    canfdi_svf_reset(&p->svf_w, x->xw);
    canfdi_svf_reset(&p->svf_z, x->z);
    p->primed = true;
  }
  canfdi_svf_step(&p->svf_u, u_q16);
  canfdi_svf_step(&p->svf_i, x->xi);
  canfdi_svf_step(&p->svf_w, x->xw);
  canfdi_svf_step(&p->svf_z, x->z);
  s.u_f = canfdi_svf_y_q16(&p->svf_u);
  s.u_d = canfdi_svf_dy_q16(&p->svf_u);
  s.i_f = canfdi_svf_y_q16(&p->svf_i);
  s.i_d = canfdi_svf_dy_q16(&p->svf_i);
  s.i_d2 = canfdi_svf_d2y_q16(&p->svf_i);
  s.w_f = canfdi_svf_y_q16(&p->svf_w);
  s.w_d = canfdi_svf_dy_q16(&p->svf_w);
  s.w_d2 = canfdi_svf_d2y_q16(&p->svf_w);
  s.z_f = canfdi_svf_y_q16(&p->svf_z);
  s.z_d = canfdi_svf_dy_q16(&p->svf_z);
  return s;
}

/* The four residuals (header: the model) on the filtered signals. */
static void pdcm_residuals(canfdi_parity_dcm_t *p, const pdcm_sig_t *s, int32_t r[CANFDI_PARITY_DCM_N_RES])
{
  const canfdi_parity_dcm_coef_t *k = p->k;
  int64_t acc;
  /* r1 = U - R I - L dI - Psi w                                    [V] */
  acc = pdcm_add_q16(0, s->u_f, false);
  acc = pdcm_mac(acc, k[CANFDI_PDCM_K_R], s->i_f, PDCM_FRAC_I, true);
  acc = pdcm_mac(acc, k[CANFDI_PDCM_K_L], s->i_d, PDCM_FRAC_I, true);
  acc = pdcm_mac(acc, k[CANFDI_PDCM_K_PSI], s->w_f, PDCM_FRAC_W, true);
  r[0] = pdcm_acc_out(p, acc);
  /* r2 = Psi I - J dw - M_F1 w - z                                 [N m] */
  acc = pdcm_mac(0, k[CANFDI_PDCM_K_PSI], s->i_f, PDCM_FRAC_I, false);
  acc = pdcm_mac(acc, k[CANFDI_PDCM_K_J], s->w_d, PDCM_FRAC_W, true);
  acc = pdcm_mac(acc, k[CANFDI_PDCM_K_F1], s->w_f, PDCM_FRAC_W, true);
  acc = pdcm_add_q16(acc, s->z_f, true);
  r[1] = pdcm_acc_out(p, acc);
  /* r3 = cI I + cdI dI + cd2I d2I - (J/Psi) dU - (M_F1/Psi) U - z  [N m] */
  acc = pdcm_mac(0, k[CANFDI_PDCM_K_CI], s->i_f, PDCM_FRAC_I, false);
  acc = pdcm_mac(acc, k[CANFDI_PDCM_K_CDI], s->i_d, PDCM_FRAC_I, false);
  acc = pdcm_mac(acc, k[CANFDI_PDCM_K_CD2I], s->i_d2, PDCM_FRAC_I, false);
  acc = pdcm_mac(acc, k[CANFDI_PDCM_K_JP], s->u_d, PDCM_FRAC_U, true);
  acc = pdcm_mac(acc, k[CANFDI_PDCM_K_FP], s->u_f, PDCM_FRAC_U, true);
  acc = pdcm_add_q16(acc, s->z_f, true);
  r[2] = pdcm_acc_out(p, acc);
  /* r4 = U - cI w - cdI dw - cd2I d2w - (R/Psi) z - (L/Psi) dz     [V] */
  acc = pdcm_add_q16(0, s->u_f, false);
  acc = pdcm_mac(acc, k[CANFDI_PDCM_K_CI], s->w_f, PDCM_FRAC_W, true);
  acc = pdcm_mac(acc, k[CANFDI_PDCM_K_CDI], s->w_d, PDCM_FRAC_W, true);
  acc = pdcm_mac(acc, k[CANFDI_PDCM_K_CD2I], s->w_d2, PDCM_FRAC_W, true);
  acc = pdcm_mac(acc, k[CANFDI_PDCM_K_RP], s->z_f, PDCM_FRAC_Z, true);
  acc = pdcm_mac(acc, k[CANFDI_PDCM_K_LP], s->z_d, PDCM_FRAC_Z, true);
  r[3] = pdcm_acc_out(p, acc);
}

/* Uncertainty bands: first-order propagation of the stated parameter
 * uncertainties, sum over p of |dr/dp| dp on the filtered signals (the
 * partial derivatives of the four equations, see the header). */
static void pdcm_uncertainty(const canfdi_parity_dcm_t *p, const pdcm_sig_t *s,
                             int32_t unc[CANFDI_PARITY_DCM_N_RES])
{
  const canfdi_parity_dcm_coef_t *k = p->k;
  const int32_t dR = p->cfg->unc_ra_ohm_q24;
  const int32_t dL = p->cfg->unc_la_H_q24;
  const int32_t dJ = p->cfg->unc_j_kgm2_q24;
  int64_t sr;
  int64_t sl;
  int64_t sj;
  /* r1: dr/dR = -I, dr/dL = -dI */
  sr = pdcm_mac(0, k[CANFDI_PDCM_K_ONE], s->i_f, PDCM_FRAC_I, false);
  sl = pdcm_mac(0, k[CANFDI_PDCM_K_ONE], s->i_d, PDCM_FRAC_I, false);
  unc[0] = canfdi_add_s32_sat(pdcm_unc_term(sr, dR), pdcm_unc_term(sl, dL));
  /* r2: dr/dJ = -dw */
  sj = pdcm_mac(0, k[CANFDI_PDCM_K_ONE], s->w_d, PDCM_FRAC_W, false);
  unc[1] = pdcm_unc_term(sj, dJ);
  /* r3: dr/dR = (M_F1 I + J dI) / Psi, dr/dL = (M_F1 dI + J d2I) / Psi,
   *     dr/dJ = (R dI + L d2I - dU) / Psi */
  sr = pdcm_mac(0, k[CANFDI_PDCM_K_FP], s->i_f, PDCM_FRAC_I, false);
  sr = pdcm_mac(sr, k[CANFDI_PDCM_K_JP], s->i_d, PDCM_FRAC_I, false);
  sl = pdcm_mac(0, k[CANFDI_PDCM_K_FP], s->i_d, PDCM_FRAC_I, false);
  sl = pdcm_mac(sl, k[CANFDI_PDCM_K_JP], s->i_d2, PDCM_FRAC_I, false);
  sj = pdcm_mac(0, k[CANFDI_PDCM_K_RP], s->i_d, PDCM_FRAC_I, false);
  sj = pdcm_mac(sj, k[CANFDI_PDCM_K_LP], s->i_d2, PDCM_FRAC_I, false);
  sj = pdcm_mac(sj, k[CANFDI_PDCM_K_IP], s->u_d, PDCM_FRAC_U, true);
  unc[2] = canfdi_add_s32_sat(canfdi_add_s32_sat(pdcm_unc_term(sr, dR), pdcm_unc_term(sl, dL)),
                              pdcm_unc_term(sj, dJ));
  /* r4: dr/dR = -(M_F1 w + J dw + z) / Psi,
   *     dr/dL = -(M_F1 dw + J d2w + dz) / Psi, dr/dJ = -(R dw + L d2w) / Psi */
  sr = pdcm_mac(0, k[CANFDI_PDCM_K_FP], s->w_f, PDCM_FRAC_W, false);
  sr = pdcm_mac(sr, k[CANFDI_PDCM_K_JP], s->w_d, PDCM_FRAC_W, false);
  sr = pdcm_mac(sr, k[CANFDI_PDCM_K_IP], s->z_f, PDCM_FRAC_Z, false);
  sl = pdcm_mac(0, k[CANFDI_PDCM_K_FP], s->w_d, PDCM_FRAC_W, false);
  sl = pdcm_mac(sl, k[CANFDI_PDCM_K_JP], s->w_d2, PDCM_FRAC_W, false);
  sl = pdcm_mac(sl, k[CANFDI_PDCM_K_IP], s->z_d, PDCM_FRAC_Z, false);
  sj = pdcm_mac(0, k[CANFDI_PDCM_K_RP], s->w_d, PDCM_FRAC_W, false);
  sj = pdcm_mac(sj, k[CANFDI_PDCM_K_LP], s->w_d2, PDCM_FRAC_W, false);
  unc[3] = canfdi_add_s32_sat(canfdi_add_s32_sat(pdcm_unc_term(sr, dR), pdcm_unc_term(sl, dL)),
                              pdcm_unc_term(sj, dJ));
}

/*
 * Validity: the SVFs need settle steps after (re)start; r2..r4 hold only
 * while the Coulomb term is +-M_F0, i.e. outside +-w_band, and again settle
 * steps after re-entering that region (the filter still remembers the
 * stuck phase), and not during a late-load hold; r1 and r4 carry R_A: not
 * evaluable while it is being learnt. Returns the valid mask; counts the
 * settle and load-hold steps down.
 */
static uint8_t pdcm_validity(canfdi_parity_dcm_t *p, int32_t w_f)
{
  const canfdi_parity_dcm_cfg_t *c = p->cfg;
  const int32_t wb = canfdi_asr32_rnd(c->w_band_rad_s_q16, CANFDI_PARITY_DCM_W_PRESCALE);
  uint8_t valid = 0U;
  if (p->settle > 0U) {
    p->settle = (uint16_t)(p->settle - 1U);
  }
  if ((w_f >= wb) || (w_f <= -wb)) {
    p->w_ok = (p->w_ok < UINT16_MAX) ? (uint16_t)(p->w_ok + 1U) : p->w_ok;
  } else {
    p->w_ok = 0U;
  }
  if (p->settle == 0U) {
    const bool ra_ok = (p->ra_learn_left == 0U);
    valid = ra_ok ? 1U : 0U;
    if ((p->w_ok >= c->settle_steps) && (p->load_hold == 0U)) {
      valid |= ra_ok ? 0x0EU : 0x06U;
    }
  }
  if (p->load_hold > 0U) {
    p->load_hold = (uint16_t)(p->load_hold - 1U);
  }
  return valid;
}

/* Slowly varying load: r2..r4 follow their own mean (time constant
 * load_tau) while valid, so each keeps its decoupling. */
static void pdcm_load_means(canfdi_parity_dcm_t *p, uint8_t valid, int32_t r[CANFDI_PARITY_DCM_N_RES])
{
  unsigned j;
  if (p->load_alpha_q31 != 0) {
    for (j = 1U; j < CANFDI_PARITY_DCM_N_RES; j++) {
      if ((valid & (1U << j)) != 0U) {
        const int64_t d = canfdi_sub_s64_sat((int64_t)r[j] * 65536, p->bias_q32[j - 1U]);
        p->bias_q32[j - 1U] = canfdi_add_s64_sat(p->bias_q32[j - 1U], canfdi_mul_s64_q31(d, p->load_alpha_q31));
      }
      r[j] = canfdi_sub_s32_sat(r[j], canfdi_sat_s64_to_s32(canfdi_asr64_rnd(p->bias_q32[j - 1U], 16U)));
    }
  }
}

/* Thresholds: the adaptive hook (excitation: the filtered U_A) plus the
 * uncertainty band, capped at band.max; normalisation, flags, outputs. */
static void pdcm_thresholds(canfdi_parity_dcm_t *p, int32_t u_f, const int32_t r[CANFDI_PARITY_DCM_N_RES],
                            const int32_t unc[CANFDI_PARITY_DCM_N_RES], uint8_t valid)
{
  uint8_t exceed = 0U;
  unsigned j;
  for (j = 0U; j < CANFDI_PARITY_DCM_N_RES; j++) {
    const int32_t th = canfdi_clamp_s32(canfdi_add_s32_sat(canfdi_adapt_step(&p->thr[j], u_f), unc[j]), 0,
                                        p->cfg->band[j].max);
    const int64_t ra = ((int64_t)r[j] < 0) ? -(int64_t)r[j] : (int64_t)r[j];
    p->out.thr_q16[j] = th;
    p->out.r_q16[j] = r[j];
    p->out.rn_q16[j] = canfdi_div_s32_qn(r[j], th, 16U);
    if (((valid & (1U << j)) != 0U) && (ra > (int64_t)th)) {
      exceed |= (uint8_t)(1U << j);
    }
  }
  p->out.valid = valid;
  p->out.exceed = exceed;
}

/* Adaptive R_A: least squares of r1 against I over a block; a block is
 * used only if r1 was valid and below the gate throughout. */
static void pdcm_ra_track(canfdi_parity_dcm_t *p, int32_t i_f, int32_t r1)
{
  if (p->cfg->ra_track != 0U) {
    if (p->settle == 0U) {
      const int32_t i_q16 = canfdi_shl32_sat(i_f, CANFDI_PARITY_DCM_I_PRESCALE);
      const int32_t r1c = canfdi_clamp_s32(r1, -PDCM_R1_SUM_CLAMP, PDCM_R1_SUM_CLAMP);
      p->blk_rn = canfdi_add_s64_sat(p->blk_rn, (int64_t)p->out.rn_q16[0]);
      p->blk_ri = canfdi_add_s64_sat(p->blk_ri, canfdi_smull32(r1c, i_q16));
      p->blk_ii = canfdi_add_s64_sat(p->blk_ii, canfdi_smull32(i_q16, i_q16));
    } else {
      p->blk_invalid = true;
    }
    p->blk_n = (uint16_t)(p->blk_n + 1U);
    if (p->blk_n >= p->cfg->ra_block_steps) {
      pdcm_ra_block(p);
    }
  }
  p->out.ra_hat_ohm_q24 = p->ra_hat_ohm_q24;
}

const canfdi_parity_dcm_out_t *canfdi_parity_dcm_step(canfdi_parity_dcm_t *p,
                                                      const canfdi_parity_dcm_in_t *in)
{
  const canfdi_parity_dcm_out_t *out = NULL;
  if ((p != NULL) && (p->cfg != NULL) && (in != NULL)) {
    pdcm_in_t x;
    pdcm_sig_t s;
    int32_t r[CANFDI_PARITY_DCM_N_RES];
    int32_t unc[CANFDI_PARITY_DCM_N_RES];
    uint8_t valid;
    x = pdcm_condition(p, in);
    pdcm_late_load(p, in->load_Nm_q16);
    s = pdcm_filter(p, in->u_V_q16, &x);
    pdcm_residuals(p, &s, r);
    pdcm_uncertainty(p, &s, unc);
    valid = pdcm_validity(p, s.w_f);
    pdcm_load_means(p, valid, r);
    pdcm_thresholds(p, s.u_f, r, unc, valid);
    pdcm_ra_track(p, s.i_f, r[0]);
    canfdi_count_inc(&p->diag.steps);
    out = &p->out;
  }
  return out;
}

const canfdi_parity_dcm_out_t *canfdi_parity_dcm_out(const canfdi_parity_dcm_t *p)
{
  return ((p != NULL) && (p->cfg != NULL)) ? &p->out : NULL;
}

const canfdi_parity_dcm_diag_t *canfdi_parity_dcm_diag(const canfdi_parity_dcm_t *p)
{
  return (p != NULL) ? &p->diag : NULL;
}

canfdi_q31_t canfdi_parity_dcm_load_alpha_q31(const canfdi_parity_dcm_t *p)
{
  return ((p != NULL) && (p->cfg != NULL)) ? p->load_alpha_q31 : 0;
}

void canfdi_parity_dcm_default_cfg(canfdi_parity_dcm_cfg_t *cfg)
{
  unsigned k;
  /* Base thresholds: ~6 x the fault-free noise sigma measured with the
   * reference noise model (see the header), rounded up. */
  static const int32_t base_q16[CANFDI_PARITY_DCM_N_RES] = {
      CANFDI_Q16_MILLI(80),  /* r1 0.08 V */
      CANFDI_Q16_MILLI(20),  /* r2 0.02 N m */
      CANFDI_Q16_MILLI(20),  /* r3 0.02 N m */
      CANFDI_Q16_MILLI(120), /* r4 0.12 V */
  };
  if (cfg != NULL) {
    cfg->ra_ohm_q24 = CANFDI_Q24(152, 100);
    cfg->la_H_q24 = CANFDI_Q24(682, 100000);
    cfg->psi_Vs_q24 = CANFDI_Q24(33, 100);
    cfg->j_kgm2_q24 = CANFDI_Q24(192, 100000);
    cfg->mf1_Nms_q24 = CANFDI_Q24(36, 100000);
    cfg->mf0_Nm_q24 = CANFDI_Q24(11, 100);
    cfg->omega_c_rad_s = 100;
    cfg->w_band_rad_s_q16 = 2 * CANFDI_Q16_ONE;
    cfg->settle_steps = 60U;
    for (k = 0U; k < CANFDI_PARITY_DCM_N_RES; k++) {
      cfg->band[k].base = base_q16[k];
      cfg->band[k].max = 16 * base_q16[k];
      /* residual units per (V/s) of filtered U_A, 2^-20 resolution: the
       * transient model error grows with the rate of U_A. */
      cfg->band[k].gain = 0;
      cfg->band[k].gain_frac_bits = 20U;
      cfg->band[k].tau_us = 20000U;
    }
    cfg->ra_track = 1U;
    cfg->ra_block_steps = 100U;
    cfg->ra_tau_s = 60U;
    cfg->ra_i_min_A_q16 = CANFDI_Q16_ONE; /* 1 A */
    cfg->ra_gate_q16 = CANFDI_Q16_ONE;
    cfg->ra_learn_blocks = 20U;
    cfg->ra_rate_max_ohm_s_q24 = CANFDI_Q24(1, 2000); /* 0.5 mOhm/s = 1.8 Ohm/h */
    cfg->ra_min_ohm_q24 = CANFDI_Q24(100, 100);
    cfg->ra_max_ohm_q24 = CANFDI_Q24(200, 100);
    cfg->load_tau_s = 0U;
    cfg->load_hold_steps = 0U;
    /* Stated uncertainties (derivation in the header, "Thresholds"):
     * dR 10 mOhm = the tracker's lag bound, heating rate 0.17 mOhm/s times
     * ra_tau 60 s; dL 2 % and dJ 2 % = the identification class of the
     * parameters (the acceptance of canfdi_est_dcm, docs/requirements.md). */
    cfg->unc_ra_ohm_q24 = CANFDI_Q24(1, 100);
    cfg->unc_la_H_q24 = CANFDI_Q24(682 * 2, 10000000);
    cfg->unc_j_kgm2_q24 = CANFDI_Q24(192 * 2, 10000000);
  }
}
