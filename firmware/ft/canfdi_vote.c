/*
 * canfdi_vote.c — 2-out-of-3 throttle position voting; the decision table
 * and the isolation rule are in the header.
 */
#include "ft/canfdi_vote.h"

#include "core/canfdi_count.h"
#include "core/canfdi_fixp.h"

static bool agree(int32_t a, int32_t b, int32_t tol)
{
  const int64_t d = (int64_t)a - (int64_t)b; /* exact, |d| < 2^32 */
  const int64_t ad = (d < 0) ? -d : d;
  return ad <= (int64_t)tol;
}

static int32_t mean2(int32_t a, int32_t b)
{
  return canfdi_sat_s64_to_s32(canfdi_asr64_rnd((int64_t)a + (int64_t)b, 1U));
}

static int32_t median3(int32_t a, int32_t b, int32_t c)
{
  int32_t m;
  if (a > b) {
    m = (b > c) ? b : ((a > c) ? c : a);
  } else {
    m = (a > c) ? a : ((b > c) ? c : b);
  }
  return m;
}

/* Debounce class for "n consecutive outlier steps": jump to 0 on either
 * report, then +-1, passed at -1 (see the header). */
static void consecutive_cfg(canfdi_debounce_cfg_t *c, uint16_t n)
{
  c->failed_threshold = (int16_t)n;
  c->passed_threshold = -1;
  c->prefailed_step = 1U;
  c->prepassed_step = 1U;
  c->jump_up_value = 0;
  c->jump_down_value = 0;
  c->jump_up = true;
  c->jump_down = true;
}

static bool cfg_ok(const canfdi_vote_cfg_t *c)
{
  return (canfdi_tps_cal_check(&c->tps1) == CANFDI_OK) && (canfdi_tps_cal_check(&c->tps2) == CANFDI_OK) &&
         (c->tps1.slope_V_rad_q16 > 0) && (c->tps2.slope_V_rad_q16 < 0) &&
         (c->tol_tps_rad_q16 > 0) && (c->tol_model_rad_q16 > 0) &&
         (c->isolate_steps_tps >= 1U) && (c->isolate_steps_tps <= 32767U) &&
         (c->isolate_steps_model >= 1U) && (c->isolate_steps_model <= 32767U);
}

/* The sensor's zero and its gain 1 / slope in Q16.16, signed like the
 * slope, rounded half up from canfdi_tps's Q8.24 reciprocal (cal valid). */
static void set_gain(canfdi_vote_t *v, uint32_t k, const canfdi_tps_cal_t *cal)
{
  canfdi_tps_t t;
  int32_t g;
  (void)canfdi_tps_init(&t, cal);
  g = canfdi_asr32_rnd(t.rad_per_V_q24, 8U);
  v->zero_V_q16[k] = cal->zero_V_q16;
  v->rad_per_V_q16[k] = (cal->slope_V_rad_q16 < 0) ? -g : g;
}

static int32_t tps_to_rad(const canfdi_vote_t *v, uint32_t k, int32_t v_V_q16)
{
  return canfdi_mul_s32_qn(canfdi_sub_s32_sat(v_V_q16, v->zero_V_q16[k]), v->rad_per_V_q16[k], 16U);
}

int32_t canfdi_vote_init(canfdi_vote_t *v, const canfdi_vote_cfg_t *cfg)
{
  int32_t rc = -CANFDI_EINVAL;
  if (v != NULL) {
    v->initialised = false;
    if ((cfg != NULL) && cfg_ok(cfg)) {
      uint32_t s;
      v->cfg = *cfg;
      set_gain(v, 0U, &cfg->tps1);
      set_gain(v, 1U, &cfg->tps2);
      consecutive_cfg(&v->deb_cfg_tps, cfg->isolate_steps_tps);
      consecutive_cfg(&v->deb_cfg_model, cfg->isolate_steps_model);
      rc = CANFDI_OK;
      for (s = 0U; s < CANFDI_VOTE_N_SRC; s++) {
        const canfdi_debounce_cfg_t *dc =
            (s == CANFDI_VOTE_SRC_MODEL) ? &v->deb_cfg_model : &v->deb_cfg_tps;
        if (canfdi_debounce_init(&v->deb[s], dc) != CANFDI_OK) {
          rc = -CANFDI_EINVAL; /* unreachable with a checked cfg */
        }
      }
      v->last_angle_rad_q16 = 0;
      v->isolated_mask = 0U;
      v->diag.steps = 0U;
      v->diag.disagree_steps = 0U;
      v->diag.single_steps = 0U;
      v->diag.invalid_steps = 0U;
      v->diag.outlier_steps = 0U;
      v->diag.isolations = 0U;
      v->diag.clears = 0U;
      v->initialised = (rc == CANFDI_OK);
    }
  }
  return rc;
}

/* The angle and outlier of a decided three-way vote; false if no pair
 * agrees. *report is false in the ambiguous row (*1). */
static bool vote3(const canfdi_vote_cfg_t *c, const int32_t th[CANFDI_VOTE_N_SRC], bool no_blame,
                  int32_t *angle, uint8_t *used, uint8_t *outlier, bool *report)
{
  const bool a12 = agree(th[0], th[1], c->tol_tps_rad_q16);
  const bool a1m = agree(th[0], th[2], c->tol_model_rad_q16);
  const bool a2m = agree(th[1], th[2], c->tol_model_rad_q16);
  bool decided = true;
  *report = true;
  *outlier = 0U;
  if (a12) {
    *angle = mean2(th[0], th[1]);
    *used = CANFDI_VOTE_BIT_TPS1 | CANFDI_VOTE_BIT_TPS2;
    if (!a1m && !a2m) {
      *outlier = CANFDI_VOTE_BIT_MODEL;
    }
  } else if ((a1m && a2m) || (no_blame && (a1m || a2m))) {
    *angle = median3(th[0], th[1], th[2]);
    *used = CANFDI_VOTE_BIT_TPS1 | CANFDI_VOTE_BIT_TPS2 | CANFDI_VOTE_BIT_MODEL;
    *report = false;
  } else if (a1m) {
    *angle = th[0];
    *used = CANFDI_VOTE_BIT_TPS1 | CANFDI_VOTE_BIT_MODEL;
    *outlier = CANFDI_VOTE_BIT_TPS2;
  } else if (a2m) {
    *angle = th[1];
    *used = CANFDI_VOTE_BIT_TPS2 | CANFDI_VOTE_BIT_MODEL;
    *outlier = CANFDI_VOTE_BIT_TPS1;
  } else {
    decided = false;
    *report = false;
  }
  return decided;
}

/* Two available sources (mask has exactly two bits). */
static bool vote2(const canfdi_vote_cfg_t *c, const int32_t th[CANFDI_VOTE_N_SRC], uint8_t avail,
                  int32_t *angle)
{
  bool ok;
  if ((avail & CANFDI_VOTE_BIT_MODEL) == 0U) {
    ok = agree(th[0], th[1], c->tol_tps_rad_q16);
    *angle = mean2(th[0], th[1]);
  } else {
    const uint32_t s = ((avail & CANFDI_VOTE_BIT_TPS1) != 0U) ? 0U : 1U;
    ok = agree(th[s], th[2], c->tol_model_rad_q16);
    *angle = th[s];
  }
  return ok;
}

static void report_all(canfdi_vote_t *v, uint8_t avail, uint8_t outlier, canfdi_vote_out_t *out)
{
  uint32_t s;
  for (s = 0U; s < CANFDI_VOTE_N_SRC; s++) {
    const uint8_t bit = (uint8_t)(1U << s);
    if ((avail & bit) != 0U) {
      const bool bad = (outlier & bit) != 0U;
      const int32_t st = canfdi_debounce_report(
          &v->deb[s], bad ? CANFDI_DEB_REPORT_PREFAILED : CANFDI_DEB_REPORT_PREPASSED);
      CANFDI_ASSERT(st >= 0);
      if (bad && (st == (int32_t)CANFDI_DEB_FAILED)) {
        v->isolated_mask = (uint8_t)(v->isolated_mask | bit);
        out->newly_isolated = bit;
        canfdi_count_inc(&v->diag.isolations);
      }
    }
  }
}

static void out_invalid(canfdi_vote_out_t *out)
{
  uint32_t s;
  out->angle_rad_q16 = 0;
  for (s = 0U; s < CANFDI_VOTE_N_SRC; s++) {
    out->theta_rad_q16[s] = 0;
  }
  out->status = (uint8_t)CANFDI_VOTE_INVALID;
  out->n_available = 0U;
  out->used_mask = 0U;
  out->excluded_mask = CANFDI_VOTE_BIT_TPS1 | CANFDI_VOTE_BIT_TPS2 | CANFDI_VOTE_BIT_MODEL;
  out->isolated_mask = 0U;
  out->outlier_mask = 0U;
  out->newly_isolated = 0U;
  out->valid = false;
}

int32_t canfdi_vote_step(canfdi_vote_t *v, const canfdi_vote_in_t *in, canfdi_vote_out_t *out)
{
  int32_t rc = -CANFDI_EINVAL;
  if ((v == NULL) || (in == NULL) || (out == NULL) || !v->initialised) {
    if (out != NULL) {
      out_invalid(out);
    }
  } else {
    const canfdi_vote_cfg_t *c = &v->cfg;
    uint8_t valid_in = 0U;
    uint8_t avail;
    uint8_t n = 0U;
    uint32_t s;
    int32_t angle = v->last_angle_rad_q16;
    uint8_t used = 0U;
    uint8_t outlier = 0U;
    bool report = false;
    canfdi_vote_status_t st;

    out->theta_rad_q16[0] = tps_to_rad(v, 0U, in->tps1_V_q16);
    out->theta_rad_q16[1] = tps_to_rad(v, 1U, in->tps2_V_q16);
    out->theta_rad_q16[2] = in->model_rad_q16;
    valid_in = (uint8_t)((in->tps1_valid ? CANFDI_VOTE_BIT_TPS1 : 0U) |
                         (in->tps2_valid ? CANFDI_VOTE_BIT_TPS2 : 0U) |
                         (in->model_valid ? CANFDI_VOTE_BIT_MODEL : 0U));
    avail = (uint8_t)(valid_in & (uint8_t)~v->isolated_mask);
    for (s = 0U; s < CANFDI_VOTE_N_SRC; s++) {
      if ((avail & (1U << s)) != 0U) {
        n = (uint8_t)(n + 1U);
      }
    }
    out->newly_isolated = 0U;

    if (n == 3U) {
      if (vote3(c, out->theta_rad_q16, in->model_no_blame, &angle, &used, &outlier, &report)) {
        st = CANFDI_VOTE_THREE;
      } else {
        st = CANFDI_VOTE_DISAGREE;
        angle = v->last_angle_rad_q16;
      }
    } else if (n == 2U) {
      if (vote2(c, out->theta_rad_q16, avail, &angle)) {
        st = CANFDI_VOTE_TWO;
        used = avail;
        report = true;
      } else {
        st = CANFDI_VOTE_DISAGREE;
        angle = v->last_angle_rad_q16;
      }
    } else if (n == 1U) {
      st = CANFDI_VOTE_SINGLE;
      used = avail;
      for (s = 0U; s < CANFDI_VOTE_N_SRC; s++) {
        if ((avail & (1U << s)) != 0U) {
          angle = out->theta_rad_q16[s];
        }
      }
    } else {
      st = CANFDI_VOTE_INVALID;
    }

    if (report) {
      report_all(v, avail, outlier, out);
    }
    if (outlier != 0U) {
      canfdi_count_inc(&v->diag.outlier_steps);
    }
    canfdi_count_inc(&v->diag.steps);
    if (st == CANFDI_VOTE_DISAGREE) {
      canfdi_count_inc(&v->diag.disagree_steps);
    } else if (st == CANFDI_VOTE_SINGLE) {
      canfdi_count_inc(&v->diag.single_steps);
    } else if (st == CANFDI_VOTE_INVALID) {
      canfdi_count_inc(&v->diag.invalid_steps);
    } else {
      /* decided */
    }

    v->last_angle_rad_q16 = angle;
    out->angle_rad_q16 = angle;
    out->status = (uint8_t)st;
    out->n_available = n;
    out->used_mask = used;
    out->excluded_mask = (uint8_t)((CANFDI_VOTE_BIT_TPS1 | CANFDI_VOTE_BIT_TPS2 |
                                    CANFDI_VOTE_BIT_MODEL) & (uint8_t)~avail);
    out->isolated_mask = v->isolated_mask;
    out->outlier_mask = outlier;
    out->valid = (st == CANFDI_VOTE_THREE) || (st == CANFDI_VOTE_TWO);
    rc = CANFDI_OK;
  }
  return rc;
}

void canfdi_vote_clear(canfdi_vote_t *v)
{
  if ((v != NULL) && v->initialised) {
    uint32_t s;
    v->isolated_mask = 0U;
    for (s = 0U; s < CANFDI_VOTE_N_SRC; s++) {
      canfdi_debounce_reset(&v->deb[s]);
    }
    canfdi_count_inc(&v->diag.clears);
  }
}

canfdi_vote_diag_t canfdi_vote_diag(const canfdi_vote_t *v)
{
  canfdi_vote_diag_t z = {0U, 0U, 0U, 0U, 0U, 0U, 0U};
  return (v != NULL) ? v->diag : z;
}
