/*
 * canfdi_parity_thr.c — throttle-valve residuals: TPS correlation, armature
 * equation and model-versus-sensor position; see canfdi_parity_thr.h.
 */
#include "model/canfdi_parity_thr.h"

#include "core/canfdi_count.h"
#include "core/canfdi_qconst.h"

/* Bound on |omega_hat|: 2000 rad/s (Q32), far above any valve speed. */
#define PTHR_W_MAX_Q32 ((int64_t)2000 << 32)
/* theta_arm follows the TPS mean with 1/2^8 per step while they agree. */
#define PTHR_LEAK_SHIFT 8U
/* Consecutive steps with the bridge off and the valve at rest before it is
 * taken to be at the limp-home angle (the header, coasting): 0.1 s. A
 * returning valve is moving (the default one returns from full travel in
 * about 0.3 s) and stops only at the limp-home angle; a turning point of
 * its settling lasts a few steps. Short, so that the sensor is trusted
 * before the correlation code's persistence (0.5 s, P2135) runs out. */
#define PTHR_LH_SETTLE_STEPS 100U

/* ------------------------------------------------------------------------ */
/* Small helpers                                                            */
/* ------------------------------------------------------------------------ */

static bool pthr_in(int32_t x, int32_t lo, int32_t hi)
{
  return (x >= lo) && (x <= hi);
}

static int32_t pthr_abs(int32_t x)
{
  return canfdi_q31_abs(x);
}

static int64_t pthr_clamp64(int64_t x, int64_t lo, int64_t hi)
{
  return (x < lo) ? lo : ((x > hi) ? hi : x);
}

/* Q32 (int64) -> Q16.16, rounded half up, saturated. */
static int32_t pthr_q32_to_q16(int64_t x)
{
  return canfdi_sat_s64_to_s32(canfdi_asr64_rnd(x, 16U));
}

/* Q40 (int64) -> Q24 (int32), rounded half up, saturated. */
static CANFDI_ALWAYS_INLINE int32_t pthr_q40_to_q24(int64_t x)
{
  return canfdi_sat_s64_to_s32(canfdi_asr64_rnd(x, 16U));
}

/* Median of three (exact, no arithmetic). */
static int64_t pthr_median3_64(int64_t a, int64_t b, int64_t c)
{
  int64_t lo = (a < b) ? a : b;
  int64_t hi = (a < b) ? b : a;
  int64_t m = c;
  if (c < lo) {
    m = lo;
  } else if (c > hi) {
    m = hi;
  } else {
    /* c between a and b */
  }
  return m;
}

/*
 * First-order low-pass y += alpha (x - y) with a Q32 state.
 * Scaling and overflow: x Q16.16 widened exactly to Q32; the difference
 * saturates in int64; canfdi_mul_s64_q31 rounds half up. Output rounded to
 * Q16.16.
 */
static int32_t pthr_lp(int64_t *y_q32, int32_t x_q16, canfdi_q31_t alpha_q31)
{
  const int64_t d = canfdi_sub_s64_sat((int64_t)x_q16 * 65536, *y_q32);
  *y_q32 = canfdi_add_s64_sat(*y_q32, canfdi_mul_s64_q31(d, alpha_q31));
  return pthr_q32_to_q16(*y_q32);
}

/* round(a * 2^sh / b) for a >= 0, b > 0 in 64 bits (init only), saturated
 * to INT32_MAX. */
static int32_t pthr_ratio_init(uint64_t a, unsigned sh, uint64_t b)
{
  const uint64_t q = ((a << sh) + (b / 2U)) / b;
  return (q > (uint64_t)INT32_MAX) ? INT32_MAX : (int32_t)q;
}

/*
 * e^-x in Q30 for x = x_q16 / 2^16 >= 0 (init only): range reduction
 * x / 2^m < 1/2, a 12-term Taylor series in Q30 (int64, products < 2^60,
 * integer division by n), then m squarings. Relative error < 1e-8 for
 * x <= 32 (each squaring doubles the relative error of the series).
 */
static int64_t pthr_exp_neg_q30(int32_t x_q16)
{
  const int64_t one = (int64_t)1 << 30;
  int64_t t;
  int64_t term = one;
  int64_t sum = one;
  unsigned m = 0U;
  unsigned n;
  while ((m < 20U) && ((x_q16 >> m) > 32768)) {
    m++;
  }
  t = ((int64_t)x_q16 << 14) >> m; /* Q30, < 2^29 */
  for (n = 1U; n <= 12U; n++) {
    term = -((term * t) >> 30) / (int64_t)n;
    sum += term;
  }
  for (n = 0U; n < m; n++) {
    sum = (sum * sum + (one >> 1)) >> 30;
  }
  return sum;
}

/*
 * Weight beta of the interval mean of a first-order R-L current: with the
 * voltage and the back-EMF constant over the interval, the exact mean is
 * i_mean = i_k-1 + beta (i_k - i_k-1), beta = 1/(1 - e^-x) - 1/x, x = R T/L
 * (beta -> 1/2 for L >> R T: the trapezoid; beta = 0.582 for the throttle,
 * whose L/R equals the 1 ms step; beta = 1 for L = 0). Q31, init only.
 */
static canfdi_q31_t pthr_beta_q31(int32_t r_q24, int32_t l_q24)
{
  canfdi_q31_t beta = CANFDI_Q31_MAX;
  if (l_q24 > 0) {
    /* x in Q16: R T / L = R_q24 T_us 2^16 / (L_q24 1e6) */
    const uint64_t xq = (((uint64_t)r_q24 * CANFDI_CFG_STEP_US) << 16) /
                        ((uint64_t)l_q24 * 1000000U);
    if (xq < 655U) { /* x < 0.01: series 1/2 + x/12, exact to 1e-8 */
      beta = (canfdi_q31_t)((1LL << 30) + (int64_t)((xq << 15) / 12U));
    } else if (xq < (32U << 16)) {
      const int64_t a_q30 = pthr_exp_neg_q30((int32_t)xq);
      const int64_t b_q30 = (((int64_t)1 << 60) / (((int64_t)1 << 30) - a_q30)) -
                            (int64_t)(((uint64_t)1 << 46) / xq);
      beta = canfdi_sat_s64_to_s32(b_q30 * 2);
    } else { /* x >= 32: e^-x < 2e-14, beta = 1 - 1/x */
      beta = canfdi_sat_s64_to_s32(((int64_t)1 << 31) - (int64_t)(((uint64_t)1 << 47) / xq));
    }
  }
  return beta;
}

/* ------------------------------------------------------------------------ */
/* Configuration                                                            */
/* ------------------------------------------------------------------------ */

int32_t canfdi_parity_thr_cfg_check(const canfdi_parity_thr_cfg_t *cfg)
{
  int32_t out = CANFDI_OK;
  unsigned k;
  if (cfg == NULL) {
    out = -CANFDI_EINVAL;
  } else if ((canfdi_tps_cal_check(&cfg->tps1) != CANFDI_OK) ||
             (canfdi_tps_cal_check(&cfg->tps2) != CANFDI_OK) ||
             (cfg->tps2.slope_V_rad_q16 != -cfg->tps1.slope_V_rad_q16) ||
             !pthr_in(cfg->tps_min_V_q16, 0, cfg->tps_max_V_q16) ||
             !pthr_in(cfg->tps_max_V_q16, cfg->tps_min_V_q16, 10 * CANFDI_Q16_ONE) ||
             !pthr_in(cfg->i_max_A_q16, 1, 100 * CANFDI_Q16_ONE) ||
             !pthr_in(cfg->r_ohm_q24, CANFDI_Q24(1, 100), CANFDI_Q24(100, 1)) ||
             !pthr_in(cfg->l_H_q24, 0, CANFDI_Q24(1, 10)) ||
             !pthr_in(cfg->k_Nm_A_q24, CANFDI_Q24(1, 100), CANFDI_Q24(10, 1)) ||
             !pthr_in(cfg->j_kgm2_q24, CANFDI_Q24(1, 10000), CANFDI_Q24(1, 1)) ||
             !pthr_in(cfg->b_Nms_q24, 0, CANFDI_Q24(10, 1)) ||
             !pthr_in(cfg->spring_Nm_rad_q24, 0, CANFDI_Q24(10, 1)) ||
             !pthr_in(cfg->pretension_Nm_q24, 0, CANFDI_Q24(10, 1)) ||
             !pthr_in(cfg->friction_Nm_q24, 0, CANFDI_Q24(10, 1)) ||
             !pthr_in(cfg->max_rad_q16, CANFDI_Q16(1, 10), 4 * CANFDI_Q16_ONE) ||
             !pthr_in(cfg->limp_home_rad_q16, 0, cfg->max_rad_q16) ||
             !pthr_in(cfg->lh_width_rad_q16, CANFDI_Q16(1, 10000), CANFDI_Q16(1, 10)) ||
             !pthr_in(cfg->omega_c_rad_s, 20, 1000) ||
             !pthr_in(cfg->obs_lambda_rad_s, 1, 100) || (cfg->obs_emf_gain_q31 < 0) ||
             !pthr_in(cfg->stick_w_rad_s_q16, 0, CANFDI_Q16_ONE) ||
             !pthr_in(cfg->rest_w_rad_s_q16, 0, 100 * CANFDI_Q16_ONE) ||
             !pthr_in(cfg->jump_rad_q16, 0, CANFDI_Q16_ONE) ||
             (cfg->res_tau_us > 10000000U) || (cfg->select_ratio < 1U)) {
    out = -CANFDI_EINVAL;
  } else {
    for (k = 0U; k < CANFDI_PARITY_THR_N_RES; k++) {
      if ((canfdi_adapt_cfg_check(&cfg->band[k]) != CANFDI_OK) || (cfg->band[k].base <= 0)) {
        out = -CANFDI_EINVAL;
      }
    }
  }
  return out;
}

int32_t canfdi_parity_thr_init(canfdi_parity_thr_t *p, const canfdi_parity_thr_cfg_t *cfg)
{
  int32_t out = canfdi_parity_thr_cfg_check(cfg);
  if (p == NULL) {
    out = -CANFDI_EINVAL;
  }
  if (out == CANFDI_OK) {
    canfdi_svf_cfg_t sc;
    unsigned k;
    sc.order = 3U;
    sc.omega_c_rad_s = cfg->omega_c_rad_s;
    /* each filter computes the outputs the residuals read */
    sc.outputs = CANFDI_SVF_OUT_Y;
    out = canfdi_svf_init(&p->svf_u, &sc);
    sc.outputs = (uint8_t)(CANFDI_SVF_OUT_Y | CANFDI_SVF_OUT_DY);
    out = (out == CANFDI_OK) ? canfdi_svf_init(&p->svf_i, &sc) : out;
    sc.outputs = CANFDI_SVF_OUT_DY;
    out = (out == CANFDI_OK) ? canfdi_svf_init(&p->svf_th, &sc) : out;
    out = (out == CANFDI_OK) ? canfdi_tps_init(&p->tps[0], &cfg->tps1) : out;
    out = (out == CANFDI_OK) ? canfdi_tps_init(&p->tps[1], &cfg->tps2) : out;
    for (k = 0U; (out == CANFDI_OK) && (k < CANFDI_PARITY_THR_N_RES); k++) {
      out = canfdi_adapt_init(&p->thr[k], &cfg->band[k]);
    }
    if (out == CANFDI_OK) {
      const uint64_t t_us = (uint64_t)CANFDI_CFG_STEP_US;
      const uint64_t lam = (uint64_t)cfg->obs_lambda_rad_s;
      p->cfg = cfg;
      /* complementary pair: TPS1 + TPS2 is the sum of the zeros (<= 10 V) */
      p->tps_sum_V_q16 = canfdi_add_s32_sat(cfg->tps1.zero_V_q16, cfg->tps2.zero_V_q16);
      /* T/J in Q24 = T_us 2^48 / (1e6 J_q24); L/T in Q24 = L_q24 1e6 / T_us;
       * 1/K in Q24 = 2^48 / K_q24. All fit by the domain. */
      p->t_over_j_q24 = pthr_ratio_init(t_us, 48U, 1000000U * (uint64_t)cfg->j_kgm2_q24);
      p->l_over_t_q24 = pthr_ratio_init((uint64_t)cfg->l_H_q24 * 1000000U, 0U, t_us);
      p->inv_k_q24 = pthr_ratio_init(1U, 48U, (uint64_t)cfg->k_Nm_A_q24);
      p->inv_lhw_q16 = canfdi_div_s32_qn(CANFDI_Q16_ONE, cfg->lh_width_rad_q16, 16U);
      p->t_q31 = pthr_ratio_init(t_us, 31U, 1000000U);
      /* observer: double pole at 1 - lambda T: l1 = 2 lambda T, l2 = lambda^2 T */
      p->l1_q31 = pthr_ratio_init(2U * lam * t_us, 31U, 1000000U);
      p->l2_q16 = pthr_ratio_init(lam * lam * t_us, 16U, 1000000U);
      p->res_alpha_q31 = pthr_ratio_init(t_us, 31U, (uint64_t)cfg->res_tau_us + t_us);
      p->beta_q31 = pthr_beta_q31(cfg->r_ohm_q24, cfg->l_H_q24);
      p->diag.steps = 0U;
      p->diag.resets = 0U;
      p->diag.coast_entries = 0U;
      p->diag.selections = 0U;
      p->diag.releases = 0U;
      p->diag.current_clips = 0U;
      canfdi_parity_thr_reset(p);
      p->diag.resets = 0U;
    }
  }
  if ((p != NULL) && (out != CANFDI_OK)) {
    p->cfg = NULL;
  }
  return out;
}

void canfdi_parity_thr_reset(canfdi_parity_thr_t *p)
{
  unsigned k;
  if ((p != NULL) && (p->cfg != NULL)) {
    p->primed = false;
    p->settle = p->cfg->settle_steps;
    p->arm_ok = 0U;
    p->en_prev = false;
    p->i_prev_q16 = 0;
    p->th1_prev_q16 = 0;
    p->th2_prev_q16 = 0;
    p->ok_prev = 0U;
    p->th_arm_q32 = 0;
    p->th_arm_prev_q32 = 0;
    p->inc_prev_q32 = 0;
    p->th_hat_q32 = (int64_t)p->cfg->limp_home_rad_q16 * 65536;
    p->w_hat_q32 = 0;
    p->corr_q32 = 0;
    p->pos_q32[0] = 0;
    p->pos_q32[1] = 0;
    p->src = CANFDI_PARITY_THR_SRC_MEAN;
    p->cand = CANFDI_PARITY_THR_SRC_NONE;
    p->cand_n = 0U;
    p->in_band_n = 0U;
    p->off_n = 0U;
    p->unref = true;
    for (k = 0U; k < CANFDI_PARITY_THR_N_RES; k++) {
      canfdi_adapt_reset(&p->thr[k]);
      p->out.r_q16[k] = 0;
      p->out.rn_q16[k] = 0;
      p->out.thr_q16[k] = canfdi_adapt_threshold(&p->thr[k]);
    }
    p->out.valid = 0U;
    p->out.no_ref = false;
    p->out.exceed = 0U;
    p->out.src = p->src;
    p->out.theta_hat_rad_q16 = p->cfg->limp_home_rad_q16;
    p->out.omega_hat_rad_s_q16 = 0;
    p->out.theta1_rad_q16 = 0;
    p->out.theta2_rad_q16 = 0;
    canfdi_count_inc(&p->diag.resets);
  }
}

/* ------------------------------------------------------------------------ */
/* The valve observer                                                       */
/* ------------------------------------------------------------------------ */

/*
 * Prediction over one interval: mechanics driven by the interval-mean
 * current, friction with stiction, then the back-EMF velocity blended in,
 * then the angle (semi-implicit Euler) and the end stops.
 * Scaling and overflow: torques Q40 in int64 (Q24 parameter x Q16.16
 * signal, exact products < 2^62, saturating sums), reduced to Q24 (int32,
 * +-128 N m) before multiplying by T/J (Q24) -> Q48 -> Q32 rad/s. The
 * back-EMF voltage is formed in Q40 the same way and multiplied by 1/K.
 * States theta (rad) and omega (rad/s) are Q32 in int64; omega is bounded
 * to +-2000 rad/s and theta to [0, max].
 */
static void pthr_predict(canfdi_parity_thr_t *p, int32_t i_avg_q16, int32_t di_q16, int32_t u_q16,
                         bool emf_ok, int64_t *th_q32, int64_t *w_q32)
{
  const canfdi_parity_thr_cfg_t *c = p->cfg;
  const int64_t w0 = p->w_hat_q32;
  const int32_t w0_q16 = pthr_q32_to_q16(w0);
  const int32_t d_q16 = canfdi_sub_s32_sat(pthr_q32_to_q16(p->th_hat_q32), c->limp_home_rad_q16);
  const int32_t sat_q16 = canfdi_clamp_s32(canfdi_mul_s32_qn(d_q16, p->inv_lhw_q16, 16U),
                                           -CANFDI_Q16_ONE, CANFDI_Q16_ONE);
  const int64_t tc_q40 = (int64_t)c->friction_Nm_q24 * 65536;
  const int64_t stick_q32 = (int64_t)c->stick_w_rad_s_q16 * 65536;
  int64_t drive;
  int64_t w;
  int64_t th;
  drive = canfdi_smull32(c->k_Nm_A_q24, i_avg_q16);
  drive = canfdi_sub_s64_sat(drive, canfdi_smull32(c->b_Nms_q24, w0_q16));
  drive = canfdi_sub_s64_sat(drive, canfdi_smull32(c->spring_Nm_rad_q24, d_q16));
  drive = canfdi_sub_s64_sat(drive, canfdi_smull32(c->pretension_Nm_q24, sat_q16));
  if ((w0 < stick_q32) && (w0 > -stick_q32) && (drive <= tc_q40) && (drive >= -tc_q40)) {
    w = 0; /* stuck: friction holds the driving torque */
  } else {
    const bool up = (w0 >= stick_q32) || ((w0 > -stick_q32) && (drive > 0));
    const int64_t net = up ? canfdi_sub_s64_sat(drive, tc_q40) : canfdi_add_s64_sat(drive, tc_q40);
    const int64_t dw = canfdi_asr64_rnd(canfdi_smull32(p->t_over_j_q24, pthr_q40_to_q24(net)), 16U);
    w = canfdi_add_s64_sat(w0, dw);
    /* friction cannot reverse the motion within a step */
    if (((w0 > 0) && (w < 0)) || ((w0 < 0) && (w > 0))) {
      w = 0;
    }
  }
  if (emf_ok) {
    /* w_el = (U - R i - (L/T) di) / K: a velocity measurement from the
     * armature, independent of the potentiometers */
    int64_t emf = (int64_t)u_q16 * ((int64_t)1 << 24);
    int64_t w_el;
    emf = canfdi_sub_s64_sat(emf, canfdi_smull32(c->r_ohm_q24, i_avg_q16));
    emf = canfdi_sub_s64_sat(emf, canfdi_smull32(p->l_over_t_q24, di_q16));
    w_el = canfdi_asr64_rnd(canfdi_smull32(p->inv_k_q24, pthr_q40_to_q24(emf)), 16U);
    w = canfdi_add_s64_sat(w, canfdi_mul_s64_q31(canfdi_sub_s64_sat(w_el, w), c->obs_emf_gain_q31));
  }
  if (w > PTHR_W_MAX_Q32) {
    w = PTHR_W_MAX_Q32;
  } else if (w < -PTHR_W_MAX_Q32) {
    w = -PTHR_W_MAX_Q32;
  } else {
    /* in range */
  }
  th = canfdi_add_s64_sat(p->th_hat_q32, canfdi_mul_s64_q31(w, p->t_q31));
  if (th <= 0) {
    th = 0;
    w = (w < 0) ? 0 : w;
  } else if (th >= ((int64_t)c->max_rad_q16 * 65536)) {
    th = (int64_t)c->max_rad_q16 * 65536;
    w = (w > 0) ? 0 : w;
  } else {
    /* between the stops */
  }
  *th_q32 = th;
  *w_q32 = w;
}

/*
 * Which measurement corrects the observer (see the header: gated mean,
 * coasting, latched healthy sensor).
 */
static uint8_t pthr_source(canfdi_parity_thr_t *p, bool ok1, bool ok2, int32_t corr_q16,
                           int32_t rate_q16)
{
  const canfdi_parity_thr_cfg_t *c = p->cfg;
  uint8_t src = p->src;
  if (!ok1 && !ok2) {
    src = CANFDI_PARITY_THR_SRC_NONE;
  } else if (ok1 != ok2) {
    src = ok1 ? CANFDI_PARITY_THR_SRC_TPS1 : CANFDI_PARITY_THR_SRC_TPS2;
  } else if (!canfdi_adapt_exceeds(&p->thr[CANFDI_PARITY_THR_CORR], corr_q16)) {
    p->in_band_n = (p->in_band_n < UINT16_MAX) ? (uint16_t)(p->in_band_n + 1U) : p->in_band_n;
    if (pthr_abs(corr_q16) <= c->band[CANFDI_PARITY_THR_CORR].base) {
      p->unref = false; /* the sensors agree: the observer tracks them */
    }
    if ((src != CANFDI_PARITY_THR_SRC_MEAN) && (p->in_band_n >= c->release_steps)) {
      src = CANFDI_PARITY_THR_SRC_MEAN;
      canfdi_count_inc(&p->diag.releases);
    }
    p->cand_n = 0U;
  } else {
    p->in_band_n = 0U;
    if (src == CANFDI_PARITY_THR_SRC_MEAN) {
      src = CANFDI_PARITY_THR_SRC_NONE; /* coast on the model */
      p->cand_n = 0U;
      canfdi_count_inc(&p->diag.coast_entries);
    }
    if (src == CANFDI_PARITY_THR_SRC_NONE) {
      /* Trust the sensor the model agrees with, once the other clearly
       * disagrees, the valve is at rest and the evidence persisted. */
      const int32_t a1 = pthr_abs(p->out.r_q16[CANFDI_PARITY_THR_POS1]);
      const int32_t a2 = pthr_abs(p->out.r_q16[CANFDI_PARITY_THR_POS2]);
      const int64_t ratio = (int64_t)c->select_ratio;
      /* at rest, and with an angle of the observer's own (unref) */
      const bool decide = !p->unref && (pthr_abs(rate_q16) <= c->rest_w_rad_s_q16);
      uint8_t cand = CANFDI_PARITY_THR_SRC_NONE;
      if (decide && ((int64_t)a1 > ratio * a2) && (a1 > p->out.thr_q16[CANFDI_PARITY_THR_POS1])) {
        cand = CANFDI_PARITY_THR_SRC_TPS2;
      } else if (decide && ((int64_t)a2 > ratio * a1) &&
                 (a2 > p->out.thr_q16[CANFDI_PARITY_THR_POS2])) {
        cand = CANFDI_PARITY_THR_SRC_TPS1;
      } else {
        /* no clear evidence */
      }
      if ((cand != CANFDI_PARITY_THR_SRC_NONE) && (cand == p->cand)) {
        p->cand_n = (p->cand_n < UINT16_MAX) ? (uint16_t)(p->cand_n + 1U) : p->cand_n;
      } else {
        p->cand_n = (cand != CANFDI_PARITY_THR_SRC_NONE) ? 1U : 0U;
      }
      p->cand = cand;
      if ((cand != CANFDI_PARITY_THR_SRC_NONE) && (p->cand_n >= c->select_steps)) {
        src = cand;
        canfdi_count_inc(&p->diag.selections);
      }
    }
  }
  return src;
}

/* ------------------------------------------------------------------------ */
/* The step                                                                 */
/* ------------------------------------------------------------------------ */

/*
 * The step, phase by phase. Each phase is a static function; the step
 * calls them in this order, which is the order of the contract (the state a
 * phase reads is what the phases before it left):
 *   1. pthr_condition   sensor ranges, angles, TPS sum, applied voltage
 *   2. pthr_prime       the first sample after init/reset starts the state
 *   3. pthr_current     interval-mean current and its change
 *   4. pthr_corr        the correlation residual
 *   5. pthr_theta_arm   the jump-robust angle for dtheta/dt
 *   6. pthr_observe     the valve observer: predict, source, correct
 *   7. pthr_pos         the position residuals
 *   8. pthr_arm         the armature residual
 *   9. pthr_validity    settle and validity flags
 *  10. pthr_thresholds  bands, normalisation, exceed flags, outputs
 *  11. pthr_remember    the previous-sample state for the next step
 */

/* The quantities of one step that later phases use. */
typedef struct {
  bool ok1;           /* TPS1 in range */
  bool ok2;           /* TPS2 in range */
  uint8_t ok;         /* bit 0: ok1, bit 1: ok2 */
  int32_t th1;        /* angle from TPS1, rad */
  int32_t th2;        /* angle from TPS2, rad */
  int32_t th_mean;    /* position measurement (limp-home without one) */
  int32_t corr_raw;   /* TPS1 + TPS2 - tps_sum, V */
  bool clip;          /* |i| at or above i_max */
  int32_t u_app;      /* voltage applied over the interval, V */
  int32_t i_avg;      /* interval-mean current, A */
  int32_t di;         /* current change over the interval, A */
  int32_t corr;       /* CORR, low-passed, V */
  int64_t inc_q32;    /* angle increment of theta_arm, rad, Q32 */
  int32_t th_arm_q16; /* theta_arm, rad */
  int32_t th_arm_avg; /* mean of theta_arm over the interval, rad */
  uint8_t src;        /* observer feedback source in use */
  int32_t th_hat_q16; /* observer angle, rad */
} pthr_step_t;

/* Sensor ranges, angles through the characteristics, the TPS sum, the
 * current clip and the applied voltage; the position measurement is the
 * mean of the sensors in range. Reads only the configuration. */
static void pthr_condition(const canfdi_parity_thr_t *p, const canfdi_parity_thr_in_t *in, pthr_step_t *s)
{
  const canfdi_parity_thr_cfg_t *c = p->cfg;
  const int32_t supply = (in->supply_V_q16 > 0) ? in->supply_V_q16 : 0;
  s->ok1 = pthr_in(in->tps1_V_q16, c->tps_min_V_q16, c->tps_max_V_q16);
  s->ok2 = pthr_in(in->tps2_V_q16, c->tps_min_V_q16, c->tps_max_V_q16);
  s->ok = (uint8_t)((s->ok1 ? 1U : 0U) | (s->ok2 ? 2U : 0U));
  s->th1 = canfdi_tps_V_to_rad_q16(&p->tps[0], in->tps1_V_q16);
  s->th2 = canfdi_tps_V_to_rad_q16(&p->tps[1], in->tps2_V_q16);
  s->corr_raw = canfdi_sub_s32_sat(canfdi_add_s32_sat(in->tps1_V_q16, in->tps2_V_q16), p->tps_sum_V_q16);
  s->clip = (in->i_A_q16 >= c->i_max_A_q16) || (in->i_A_q16 <= -c->i_max_A_q16);
  s->u_app = in->enabled ? canfdi_clamp_s32(in->u_V_q16, -supply, supply) : 0;
  s->th_mean = c->limp_home_rad_q16;
  if (s->ok1 && s->ok2) {
    s->th_mean = canfdi_sat_s64_to_s32(canfdi_asr64_rnd((int64_t)s->th1 + s->th2, 1U));
  } else if (s->ok1) {
    s->th_mean = s->th1;
  } else if (s->ok2) {
    s->th_mean = s->th2;
  } else {
    /* no position measurement: the limp-home angle as a placeholder */
  }
}

/* The first sample after init/reset: previous samples, theta_arm, the
 * observer, the low-passes and the SVFs start from it. */
static void pthr_prime(canfdi_parity_thr_t *p, const canfdi_parity_thr_in_t *in, const pthr_step_t *s)
{
  if (!p->primed) {
    p->i_prev_q16 = in->i_A_q16;
    p->th1_prev_q16 = s->th1;
    p->th2_prev_q16 = s->th2;
    p->ok_prev = s->ok;
    p->th_arm_q32 = (int64_t)s->th_mean * 65536;
    p->th_arm_prev_q32 = p->th_arm_q32;
    p->th_hat_q32 = (int64_t)s->th_mean * 65536;
    p->w_hat_q32 = 0;
    p->corr_q32 = (s->ok1 && s->ok2) ? ((int64_t)s->corr_raw * 65536) : 0;
    p->pos_q32[0] = 0;
    p->pos_q32[1] = 0;
    p->en_prev = in->enabled;
    canfdi_svf_reset(&p->svf_u, s->u_app);
    canfdi_svf_reset(&p->svf_i, in->i_A_q16);
    canfdi_svf_reset(&p->svf_th, s->th_mean);
    p->primed = true;
  }
}

/* ZOH alignment as in canfdi_parity_dcm.h: u is the voltage held over the
 * interval, i enters as its interval mean. L/R of this motor equals the
 * step, so the trapezoid (beta = 1/2) would be 8 % off in transients: the
 * exact first-order weight beta is used instead. */
static void pthr_current(const canfdi_parity_thr_t *p, const canfdi_parity_thr_in_t *in, pthr_step_t *s)
{
  s->di = canfdi_sub_s32_sat(in->i_A_q16, p->i_prev_q16);
  s->i_avg = canfdi_sat_s64_to_s32((int64_t)p->i_prev_q16 + canfdi_asr64_rnd(canfdi_smull32(s->di, p->beta_q31), 31U));
}

/* Correlation residual, low-passed; held while a sensor is out of range. */
static void pthr_corr(canfdi_parity_thr_t *p, pthr_step_t *s)
{
  s->corr = pthr_q32_to_q16(p->corr_q32);
  if (s->ok1 && s->ok2) {
    s->corr = pthr_lp(&p->corr_q32, s->corr_raw, p->res_alpha_q31);
  }
}

/*
 * theta_arm: the angle whose derivative enters the armature residual,
 * integrated from per-step increments. With both sensors in range the
 * increment is the mean of the two sensor increments, or, when they differ
 * by more than jump_rad (a sensor jumped: fault onset, in-range drift
 * step), the median of the two and the previous increment, so the jump is
 * outvoted (switching between two noisy sensors every step would inject
 * white speed noise, so it is done only on jumps); it never leaves
 * [min(d1,d2), max(d1,d2)]. While the two agree, theta_arm leaks towards
 * their mean (1/2^8 per step), which bounds the random walk of the median
 * choices. Q32 state: the mean increment (d1 + d2) / 2 and the leak are
 * exact or rounded at 2^-32; rounding them to Q16.16 every step would add a
 * speed bias of up to 1/4 LSB per ms (ties round up), i.e. 4 mrad/s in
 * dtheta/dt, 1.5 mV in ARM.
 */
static void pthr_theta_arm(canfdi_parity_thr_t *p, pthr_step_t *s)
{
  const bool v1 = s->ok1 && ((p->ok_prev & 1U) != 0U);
  const bool v2 = s->ok2 && ((p->ok_prev & 2U) != 0U);
  const int32_t d1 = canfdi_sub_s32_sat(s->th1, p->th1_prev_q16);
  const int32_t d2 = canfdi_sub_s32_sat(s->th2, p->th2_prev_q16);
  if (v1 && v2) {
    if (pthr_abs(canfdi_sub_s32_sat(d1, d2)) > p->cfg->jump_rad_q16) {
      s->inc_q32 = pthr_median3_64((int64_t)d1 * 65536, (int64_t)d2 * 65536, p->inc_prev_q32);
    } else {
      s->inc_q32 = ((int64_t)d1 + (int64_t)d2) * 32768; /* exact */
    }
  } else if (v1) {
    s->inc_q32 = (int64_t)d1 * 65536;
  } else if (v2) {
    s->inc_q32 = (int64_t)d2 * 65536;
  } else {
    s->inc_q32 = 0;
  }
  p->th_arm_prev_q32 = p->th_arm_q32;
  p->th_arm_q32 = canfdi_add_s64_sat(p->th_arm_q32, s->inc_q32);
  if (s->ok1 && s->ok2 && !canfdi_adapt_exceeds(&p->thr[CANFDI_PARITY_THR_CORR], s->corr)) {
    p->th_arm_q32 = canfdi_add_s64_sat(
        p->th_arm_q32,
        canfdi_asr64_rnd(canfdi_sub_s64_sat((int64_t)s->th_mean * 65536, p->th_arm_q32), PTHR_LEAK_SHIFT));
  }
  p->inc_prev_q32 = s->inc_q32;
  s->th_arm_q16 = pthr_q32_to_q16(p->th_arm_q32);
  s->th_arm_avg = pthr_q32_to_q16(canfdi_asr64_rnd(canfdi_add_s64_sat(p->th_arm_q32, p->th_arm_prev_q32), 1U));
}

/* Observer: predict, choose the correcting measurement, correct, keep the
 * angle between the stops. */
static void pthr_observe(canfdi_parity_thr_t *p, const canfdi_parity_thr_in_t *in, pthr_step_t *s)
{
  const canfdi_parity_thr_cfg_t *c = p->cfg;
  const int32_t rate = canfdi_svf_dy_q16(&p->svf_th); /* filtered angular speed, last step */
  const bool emf_ok = in->enabled && !s->clip && (pthr_abs(p->i_prev_q16) < c->i_max_A_q16);
  int64_t th_p;
  int64_t w_p;
  const uint8_t src_prev = p->src;
  pthr_predict(p, s->i_avg, s->di, s->u_app, emf_ok, &th_p, &w_p);
  s->src = pthr_source(p, s->ok1, s->ok2, s->corr, rate);
  p->src = s->src;
  if ((src_prev == CANFDI_PARITY_THR_SRC_MEAN) && (s->src == CANFDI_PARITY_THR_SRC_NONE) && s->ok1 &&
      s->ok2) {
    /* Coast entry: the observer's prediction, limited to what a fault of
     * one sensor leaves possible. theta_arm lies between the true angle and
     * the sensors' mean (an abrupt offset is outvoted there, an offset jump
     * within jump_rad of the other sensor's noisy increment moves it by up
     * to half the jump, a drift by half the drift), so the true angle is
     * within half the sensors' disagreement of theta_arm. Inside that
     * interval the observer is kept: it lags the mean and so still holds
     * most of the angle from before the disagreement. Outside it, the
     * observer carries its own model error (right after a fast stroke it
     * can be several bands, decaying only with the position feedback that
     * coasting gives up), and the nearest end of the interval is taken. */
    const int64_t half_q32 = (int64_t)pthr_abs(canfdi_sub_s32_sat(s->th1, s->th2)) * 32768;
    th_p = pthr_clamp64(th_p, canfdi_sub_s64_sat(p->th_arm_q32, half_q32),
                        canfdi_add_s64_sat(p->th_arm_q32, half_q32));
  } else if ((s->src == CANFDI_PARITY_THR_SRC_NONE) && (s->ok1 || s->ok2) && !emf_ok) {
    if ((p->off_n >= PTHR_LH_SETTLE_STEPS) && (c->pretension_Nm_q24 > c->friction_Nm_q24)) {
      /* De-energised and at rest: the pretension holds the valve at the
       * limp-home angle (the header, coasting). */
      th_p = (int64_t)c->limp_home_rad_q16 * 65536;
      w_p = 0;
      p->unref = false;
    } else {
      /* Coasting without the back-EMF speed (current clipped in a fast
       * stroke, or bridge off): the mechanical model alone is poor there,
       * whereas a sensor offset, even a drifting one, barely changes
       * within a few steps: follow the jump-robust sensor increment. */
      th_p = canfdi_add_s64_sat(p->th_hat_q32, s->inc_q32);
    }
  } else {
    /* the model's prediction */
  }
  if (s->src != CANFDI_PARITY_THR_SRC_NONE) {
    const int32_t y = (s->src == CANFDI_PARITY_THR_SRC_MEAN)   ? s->th_mean
                      : (s->src == CANFDI_PARITY_THR_SRC_TPS1) ? s->th1
                                                               : s->th2;
    const int32_t e = canfdi_sub_s32_sat(y, pthr_q32_to_q16(th_p));
    th_p = canfdi_add_s64_sat(th_p, canfdi_mul_s64_q31((int64_t)e * 65536, p->l1_q31));
    w_p = canfdi_add_s64_sat(w_p, canfdi_smull32(p->l2_q16, e));
  }
  if (th_p < 0) {
    th_p = 0;
  } else if (th_p > ((int64_t)c->max_rad_q16 * 65536)) {
    th_p = (int64_t)c->max_rad_q16 * 65536;
  } else {
    /* between the stops */
  }
  p->th_hat_q32 = th_p;
  p->w_hat_q32 = w_p;
  s->th_hat_q16 = pthr_q32_to_q16(th_p);
}

/* Model-versus-sensor residuals, low-passed like the correlation; held
 * while the sensor is out of range. */
static void pthr_pos(canfdi_parity_thr_t *p, const pthr_step_t *s, int32_t r[CANFDI_PARITY_THR_N_RES])
{
  r[CANFDI_PARITY_THR_POS1] = pthr_q32_to_q16(p->pos_q32[0]);
  r[CANFDI_PARITY_THR_POS2] = pthr_q32_to_q16(p->pos_q32[1]);
  if (s->ok1) {
    r[CANFDI_PARITY_THR_POS1] =
        pthr_lp(&p->pos_q32[0], canfdi_sub_s32_sat(s->th1, s->th_hat_q16), p->res_alpha_q31);
  }
  if (s->ok2) {
    r[CANFDI_PARITY_THR_POS2] =
        pthr_lp(&p->pos_q32[1], canfdi_sub_s32_sat(s->th2, s->th_hat_q16), p->res_alpha_q31);
  }
}

/* Armature residual r = u - R i - L di/dt - K dtheta/dt on SVF outputs.
 * The bridge's terminal voltage is unknown while it is off: the filters
 * restart on the enable edge and the residual waits settle_steps (arm_ok
 * counts the steps it could be formed). */
static int32_t pthr_arm(canfdi_parity_thr_t *p, const canfdi_parity_thr_in_t *in, const pthr_step_t *s)
{
  const canfdi_parity_thr_cfg_t *c = p->cfg;
  int64_t acc;
  if (in->enabled && !p->en_prev) {
    canfdi_svf_reset(&p->svf_u, s->u_app);
    canfdi_svf_reset(&p->svf_i, s->i_avg);
    canfdi_svf_reset(&p->svf_th, s->th_arm_avg);
  }
  canfdi_svf_step(&p->svf_u, s->u_app);
  canfdi_svf_step(&p->svf_i, s->i_avg);
  canfdi_svf_step(&p->svf_th, s->th_arm_avg);
  acc = (int64_t)canfdi_svf_y_q16(&p->svf_u) * ((int64_t)1 << 24);
  acc = canfdi_sub_s64_sat(acc, canfdi_smull32(c->r_ohm_q24, canfdi_svf_y_q16(&p->svf_i)));
  acc = canfdi_sub_s64_sat(acc, canfdi_smull32(c->l_H_q24, canfdi_svf_dy_q16(&p->svf_i)));
  acc = canfdi_sub_s64_sat(acc, canfdi_smull32(c->k_Nm_A_q24, canfdi_svf_dy_q16(&p->svf_th)));
  if (s->clip) {
    canfdi_count_inc(&p->diag.current_clips);
  }
  if (in->enabled && !s->clip && (s->ok1 || s->ok2)) {
    p->arm_ok = (p->arm_ok < UINT16_MAX) ? (uint16_t)(p->arm_ok + 1U) : p->arm_ok;
  } else {
    p->arm_ok = 0U;
  }
  return canfdi_sat_s64_to_s32(canfdi_asr64_rnd(acc, 24U));
}

/* Validity: nothing for settle_steps after init/reset; CORR needs both
 * sensors in range, POSk sensor k, ARM arm_ok for settle_steps. */
static uint8_t pthr_validity(canfdi_parity_thr_t *p, const pthr_step_t *s)
{
  uint8_t valid = 0U;
  if (p->settle > 0U) {
    p->settle = (uint16_t)(p->settle - 1U);
  }
  if (p->settle == 0U) {
    valid = (uint8_t)((s->ok1 && s->ok2) ? (1U << CANFDI_PARITY_THR_CORR) : 0U);
    valid |= (uint8_t)((p->arm_ok >= p->cfg->settle_steps) ? (1U << CANFDI_PARITY_THR_ARM) : 0U);
    valid |= (uint8_t)(s->ok1 ? (1U << CANFDI_PARITY_THR_POS1) : 0U);
    valid |= (uint8_t)(s->ok2 ? (1U << CANFDI_PARITY_THR_POS2) : 0U);
  }
  p->out.no_ref = p->unref && s->ok1 && s->ok2;
  return valid;
}

/* Thresholds: the armature band widens with the rate of the voltage, the
 * position and correlation bands with the angular speed; normalisation,
 * flags and the outputs of the step. */
static void pthr_thresholds(canfdi_parity_thr_t *p, const pthr_step_t *s, const int32_t r[CANFDI_PARITY_THR_N_RES],
                            uint8_t valid)
{
  uint8_t exceed = 0U;
  unsigned j;
  for (j = 0U; j < CANFDI_PARITY_THR_N_RES; j++) {
    const int32_t th = canfdi_adapt_step(&p->thr[j], (j == CANFDI_PARITY_THR_ARM) ? s->u_app : s->th_arm_q16);
    p->out.thr_q16[j] = th;
    p->out.r_q16[j] = r[j];
    p->out.rn_q16[j] = canfdi_div_s32_qn(r[j], th, 16U);
    if (((valid & (1U << j)) != 0U) && canfdi_adapt_exceeds(&p->thr[j], r[j])) {
      exceed |= (uint8_t)(1U << j);
    }
  }
  p->out.valid = valid;
  p->out.exceed = exceed;
  p->out.src = s->src;
  p->out.theta_hat_rad_q16 = s->th_hat_q16;
  p->out.omega_hat_rad_s_q16 = pthr_q32_to_q16(p->w_hat_q32);
  p->out.theta1_rad_q16 = s->th1;
  p->out.theta2_rad_q16 = s->th2;
}

/* The previous-sample state for the next step. */
static void pthr_remember(canfdi_parity_thr_t *p, const canfdi_parity_thr_in_t *in, const pthr_step_t *s)
{
  p->i_prev_q16 = in->i_A_q16;
  p->th1_prev_q16 = s->th1;
  p->th2_prev_q16 = s->th2;
  p->ok_prev = s->ok;
  p->en_prev = in->enabled;
  if (in->enabled || (pthr_abs(canfdi_svf_dy_q16(&p->svf_th)) > p->cfg->rest_w_rad_s_q16)) {
    p->off_n = 0U;
  } else if (p->off_n < UINT16_MAX) {
    p->off_n = (uint16_t)(p->off_n + 1U);
  } else {
    /* saturated */
  }
}

const canfdi_parity_thr_out_t *canfdi_parity_thr_step(canfdi_parity_thr_t *p,
                                                      const canfdi_parity_thr_in_t *in)
{
  const canfdi_parity_thr_out_t *out = NULL;
  if ((p != NULL) && (p->cfg != NULL) && (in != NULL)) {
    pthr_step_t s;
    int32_t r[CANFDI_PARITY_THR_N_RES];
    uint8_t valid;
    pthr_condition(p, in, &s);
    pthr_prime(p, in, &s);
    pthr_current(p, in, &s);
    pthr_corr(p, &s);
    pthr_theta_arm(p, &s);
    pthr_observe(p, in, &s);
    pthr_pos(p, &s, r);
    r[CANFDI_PARITY_THR_CORR] = s.corr;
    r[CANFDI_PARITY_THR_ARM] = pthr_arm(p, in, &s);
    valid = pthr_validity(p, &s);
    pthr_thresholds(p, &s, r, valid);
    pthr_remember(p, in, &s);
    canfdi_count_inc(&p->diag.steps);
    out = &p->out;
  }
  return out;
}

int32_t canfdi_parity_thr_force_source(canfdi_parity_thr_t *p, uint8_t src)
{
  int32_t out = -CANFDI_EINVAL;
  if ((p != NULL) && (p->cfg != NULL) && (src <= CANFDI_PARITY_THR_SRC_MEAN)) {
    p->src = src;
    p->in_band_n = 0U;
    p->cand_n = 0U;
    if ((src == CANFDI_PARITY_THR_SRC_TPS1) || (src == CANFDI_PARITY_THR_SRC_TPS2)) {
      p->unref = false; /* the observer follows the sensor imposed */
    }
    out = CANFDI_OK;
  }
  return out;
}

const canfdi_parity_thr_out_t *canfdi_parity_thr_out(const canfdi_parity_thr_t *p)
{
  return ((p != NULL) && (p->cfg != NULL)) ? &p->out : NULL;
}

const canfdi_parity_thr_diag_t *canfdi_parity_thr_diag(const canfdi_parity_thr_t *p)
{
  return (p != NULL) ? &p->diag : NULL;
}

void canfdi_parity_thr_default_cfg(canfdi_parity_thr_cfg_t *cfg)
{
  unsigned k;
  /* corr 0.01 V, armature 0.05 V, positions 0.012 rad (0.7 deg) */
  static const int32_t base_q16[CANFDI_PARITY_THR_N_RES] = {
      CANFDI_Q16_MILLI(10), CANFDI_Q16_MILLI(50), CANFDI_Q16_MILLI(12), CANFDI_Q16_MILLI(12)};
  /* band growth per unit/s of excitation (2^-20 resolution): the armature
   * band grows with |du/dt| [V per V/s], the position bands with the
   * angular speed [rad per rad/s]: model-uncertainty propagation, see
   * "Position bands" in the header. POS: gain = eps (tau + T) with
   * eps = 5 % (relative speed error of the valve model), tau = 2 / lambda
   * = 66.7 ms (the observer's error decay): 0.05 * 0.067667 s * 2^20 = 3548. */
  static const int32_t gain[CANFDI_PARITY_THR_N_RES] = {0, 100, 3548, 3548};
  static const uint32_t tau_us[CANFDI_PARITY_THR_N_RES] = {20000U, 20000U, 66667U, 66667U};
  if (cfg != NULL) {
    canfdi_tps_cal_default(&cfg->tps1, &cfg->tps2);
    cfg->tps_min_V_q16 = CANFDI_Q16_MILLI(250);
    cfg->tps_max_V_q16 = CANFDI_Q16_MILLI(4750);
    cfg->i_max_A_q16 = CANFDI_Q16_MILLI(9800);
    cfg->r_ohm_q24 = CANFDI_Q24(15, 10);
    cfg->l_H_q24 = CANFDI_Q24(15, 10000);
    cfg->k_Nm_A_q24 = CANFDI_Q24(383, 1000);
    cfg->j_kgm2_q24 = CANFDI_Q24(21, 10000);
    cfg->b_Nms_q24 = CANFDI_Q24(88, 10000);
    cfg->spring_Nm_rad_q24 = CANFDI_Q24(87, 1000);
    cfg->pretension_Nm_q24 = CANFDI_Q24(396, 1000);
    cfg->friction_Nm_q24 = CANFDI_Q24(284, 1000);
    cfg->limp_home_rad_q16 = CANFDI_Q16_DEG(65, 10);
    cfg->lh_width_rad_q16 = CANFDI_Q16_DEG(5, 10);
    cfg->max_rad_q16 = CANFDI_Q16_DEG(90, 1);
    cfg->omega_c_rad_s = 100;
    cfg->obs_lambda_rad_s = 30;
    cfg->obs_emf_gain_q31 = CANFDI_Q31_RATIO(3, 10);
    cfg->stick_w_rad_s_q16 = CANFDI_Q16_MILLI(1);
    cfg->rest_w_rad_s_q16 = CANFDI_Q16_MILLI(200);
    cfg->jump_rad_q16 = CANFDI_Q16_MILLI(10);
    cfg->res_tau_us = 10000U;
    cfg->settle_steps = 60U;
    cfg->select_steps = 20U;
    cfg->release_steps = 200U;
    cfg->select_ratio = 4U;
    for (k = 0U; k < CANFDI_PARITY_THR_N_RES; k++) {
      cfg->band[k].base = base_q16[k];
      cfg->band[k].max = 16 * base_q16[k];
      cfg->band[k].gain = gain[k];
      cfg->band[k].gain_frac_bits = 20U;
      cfg->band[k].tau_us = tau_us[k];
    }
  }
}
