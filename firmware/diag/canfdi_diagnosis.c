/*
 * canfdi_diagnosis.c — fault-symptom reasoning; the manual is the header.
 */
#include "diag/canfdi_diagnosis.h"

#include "core/canfdi_count.h"
#include "core/canfdi_fixp.h"
#include "core/canfdi_qconst.h"

#define STEPS_MAX 10000U
#define PAR_THR_MIN 66       /* 0.001 in Q16.16 */
#define PAR_THR_MAX 655360   /* 10.0 */

/* The rule tables are generated from dbc/diag_rules.csv
 * (diag/gen/canfdi_diag_rules.c). */
CANFDI_STATIC_ASSERT(CANFDI_FAULT_COUNT <= 32U, fault_ids_fit_the_mask);
CANFDI_STATIC_ASSERT((CANFDI_FAULT_COUNT % 4U) == 0U, report_written_four_at_a_time);
CANFDI_STATIC_ASSERT(CANFDI_DIAG_N_FLAGS <= 16U, flags_fit_uint16);
CANFDI_STATIC_ASSERT((CANFDI_DIAG_REPORT_FAILED == 1) && (CANFDI_DIAG_REPORT_PASSED == -1) &&
                         (CANFDI_DIAG_REPORT_NONE == 0),
                     report_phase_computes_the_codes);
CANFDI_STATIC_ASSERT(CANFDI_DIAG_COMP_THR < CANFDI_DIAG_N_COMP, components_fit);
CANFDI_STATIC_ASSERT(CANFDI_DIAG_N_COMP <= 8U, components_fit_the_hard_any_bits);
CANFDI_STATIC_ASSERT(CANFDI_DIAG_N_RULES <= 32U, rules_fit_the_gate_mask);

/* Most steps a low flux-loss prediction adds to a residual's hold (the
 * parity's load tracking time, 1 s). */
#define FX_LOW_MAX 1000U

/* Test verdicts while combining a hard and a model rule of one fault (no
 * such test: the fault's bit is not in the mask's has). */
#define V_NONE 1U /* not tested */
#define V_PASS 2U
#define V_FAIL 3U

static uint8_t comp_of_catalogue(uint8_t component)
{
  uint8_t c = 0xFFU;
  if (component == CANFDI_COMPONENT_DC_MOTOR) {
    c = (uint8_t)CANFDI_DIAG_COMP_DCM;
  } else if (component == CANFDI_COMPONENT_THROTTLE) {
    c = (uint8_t)CANFDI_DIAG_COMP_THR;
  } else {
    /* no diagnosis for other components */
  }
  return c;
}

static CANFDI_ALWAYS_INLINE int32_t abs_sat(int32_t x)
{
  return (x >= 0) ? x : ((x == INT32_MIN) ? INT32_MAX : -x);
}

static bool steps_ok(uint16_t n)
{
  return (n >= 1U) && (n <= STEPS_MAX);
}

static bool par_ok(int32_t t)
{
  return (t >= PAR_THR_MIN) && (t <= PAR_THR_MAX);
}

void canfdi_diagnosis_default_cfg(canfdi_diagnosis_cfg_t *cfg)
{
  if (cfg != NULL) {
    cfg->on_q16 = CANFDI_Q16_ONE;
    cfg->off_q16 = 52429; /* 0.8 */
    cfg->weight_cap_q16 = 4 * CANFDI_Q16_ONE;
    cfg->sym_on_steps = 20U;
    cfg->sym_off_steps = 50U;
    cfg->flag_on_steps = 10U;
    cfg->flag_off_steps = 10U;
    cfg->isolate_steps = 20U;
    cfg->conf_min_pct = 50U;
    cfg->margin_pct = 10U;
    cfg->par_fresh_updates = 12U;
    cfg->par_memory_updates = 100U;
    /* 1 % = 655.36 in Q16.16 */
    cfg->dcm_par_pos_q16[CANFDI_SYM_DCM_P_RA] = 5243;   /* +8 % */
    cfg->dcm_par_neg_q16[CANFDI_SYM_DCM_P_RA] = 13107;  /* -20 % */
    cfg->dcm_par_pos_q16[CANFDI_SYM_DCM_P_PSI] = 1638;  /* 2.5 % */
    cfg->dcm_par_neg_q16[CANFDI_SYM_DCM_P_PSI] = 1638;
    cfg->dcm_par_pos_q16[CANFDI_SYM_DCM_P_J] = 3277;    /* 5 % */
    cfg->dcm_par_neg_q16[CANFDI_SYM_DCM_P_J] = 3277;
    cfg->dcm_par_pos_q16[CANFDI_SYM_DCM_P_FRICTION] = 1966; /* +3 % */
    cfg->dcm_par_neg_q16[CANFDI_SYM_DCM_P_FRICTION] = 6554; /* -10 % */
    cfg->thr_par_pos_q16[CANFDI_SYM_THR_P_R] = 5243;    /* +8 % */
    cfg->thr_par_neg_q16[CANFDI_SYM_THR_P_R] = 13107;   /* -20 % */
    cfg->thr_par_pos_q16[CANFDI_SYM_THR_P_K] = 6554;    /* 10 % */
    cfg->thr_par_neg_q16[CANFDI_SYM_THR_P_K] = 6554;
    /* Spring and friction: the fast structured test of canfdi_est_thr
     * (relative spring-torque and Coulomb-friction deviations). Fault-free
     * SIL spread (3 scenarios x 3 seeds, every 100 ms while valid): spring
     * mean -0.009..+0.004, sd 0.015-0.018, extremes -0.048/+0.057;
     * friction mean -0.064..-0.083 (the closed loop's response to TPS
     * noise; -0.021 without it), sd 0.018-0.035, extremes -0.17/-0.012.
     * -10 % spring is ~6 sd below its mean; +8 % friction 4-7 sd above
     * its mean; the + spring side (+20 %) and the - friction side (-30 %)
     * name no catalogue fault and stay wide (the spring estimate swings to
     * +0.25 for ~0.1 s after a friction step; friction -0.17 fault-free). */
    cfg->thr_par_pos_q16[CANFDI_SYM_THR_P_SPRING] = 13107; /* +20 % */
    cfg->thr_par_neg_q16[CANFDI_SYM_THR_P_SPRING] = 6554;  /* -10 % */
    cfg->thr_par_pos_q16[CANFDI_SYM_THR_P_FRICTION] = 5243;  /* +8 % */
    cfg->thr_par_neg_q16[CANFDI_SYM_THR_P_FRICTION] = 19661; /* -30 % */
    cfg->jpsi_q16 = 1311; /* 2 % */
  }
}

int32_t canfdi_diagnosis_cfg_check(const canfdi_diagnosis_cfg_t *cfg)
{
  int32_t rc = CANFDI_OK;
  uint32_t i;
  if (cfg == NULL) {
    rc = -CANFDI_EINVAL;
  } else if ((cfg->off_q16 <= 0) || (cfg->off_q16 > cfg->on_q16) || (cfg->on_q16 > 16 * CANFDI_Q16_ONE) ||
             (cfg->weight_cap_q16 < CANFDI_Q16_ONE) || (cfg->weight_cap_q16 > 16 * CANFDI_Q16_ONE) ||
             !steps_ok(cfg->sym_on_steps) || !steps_ok(cfg->sym_off_steps) ||
             !steps_ok(cfg->flag_on_steps) || !steps_ok(cfg->flag_off_steps) ||
             !steps_ok(cfg->isolate_steps) || (cfg->conf_min_pct > 100U) || (cfg->margin_pct > 100U) ||
             (cfg->par_fresh_updates > STEPS_MAX) || (cfg->par_memory_updates > STEPS_MAX) ||
             !par_ok(cfg->jpsi_q16)) {
    rc = -CANFDI_EINVAL;
  } else {
    for (i = 0U; i < CANFDI_SYM_N_PAR; i++) {
      if (!par_ok(cfg->dcm_par_pos_q16[i]) || !par_ok(cfg->dcm_par_neg_q16[i]) ||
          !par_ok(cfg->thr_par_pos_q16[i]) || !par_ok(cfg->thr_par_neg_q16[i])) {
        rc = -CANFDI_EINVAL;
      }
    }
  }
  return rc;
}

static void pers_clear(canfdi_diagnosis_pers_t *p, int8_t state)
{
  p->state = state;
  p->cand = state;
  p->n = 0U;
  p->quiet = UINT16_MAX; /* settled; clamped to sym_off_steps by channel() */
}

void canfdi_diagnosis_reset(canfdi_diagnosis_t *d)
{
  uint32_t c;
  uint32_t j;
  if ((d != NULL) && d->initialised) {
    for (c = 0U; c < CANFDI_DIAG_N_COMP; c++) {
      for (j = 0U; j < CANFDI_DIAG_N_CH; j++) {
        pers_clear(&d->ch[c][j], CANFDI_DIAG_SYM_UNKNOWN);
        d->x_q16[c][j] = 0;
      }
      d->res[c] = (canfdi_diagnosis_result_t){0};
      d->win_n[c] = 0U;
      d->win_id[c] = 0U;
      d->latched[c] = false;
      d->fresh[c][0] = 0U;
      d->fresh[c][1] = 0U;
    }
    d->mv_last = (canfdi_diagnosis_vmask_t){0U, 0U, 0U};
    d->hard.valid = false;
    for (j = 0U; j < CANFDI_DIAG_N_FLAGS; j++) {
      pers_clear(&d->flag[j], CANFDI_DIAG_SYM_ZERO);
    }
    for (j = 0U; j < CANFDI_SYM_N_RES; j++) {
      d->fx_blind[j] = 0U;
      d->fx_low[j] = 0U;
    }
    pers_clear(&d->fx_contra, CANFDI_DIAG_SYM_ZERO);
    pers_clear(&d->gain_contra, CANFDI_DIAG_SYM_ZERO);
    d->held[CANFDI_DIAG_COMP_DCM] = false;
    d->held[CANFDI_DIAG_COMP_THR] = false;
    d->corr_not_isolated = false;
    d->failed_mask = 0U;
    d->passed_mask = 0U;
  }
}

/* Pattern string -> masks (init only). */
static void compile_rule(const canfdi_diag_model_rule_t *r, canfdi_diagnosis_rule_t *m)
{
  uint32_t j = 0U;
  uint32_t k;
  *m = (canfdi_diagnosis_rule_t){0};
  for (k = 0U; (k < CANFDI_DIAG_PATTERN_LEN) && (r->pattern[k] != '\0') && (j < CANFDI_DIAG_N_CH); k++) {
    const char e = r->pattern[k];
    const uint16_t b = (uint16_t)(1U << j);
    if (e != ' ') {
      if ((e == 'P') || (e == 'N') || (e == 'Z')) {
        m->nec = (uint16_t)(m->nec | b);
      }
      if ((e == 'P') || (e == '+')) {
        m->pos = (uint16_t)(m->pos | b);
      } else if ((e == 'N') || (e == '-')) {
        m->neg = (uint16_t)(m->neg | b);
      } else if ((e == 'Z') || (e == '0')) {
        m->zero = (uint16_t)(m->zero | b);
      } else {
        /* '.': don't care */
      }
      j++;
    }
  }
  m->care = (uint16_t)(m->pos | m->neg | m->zero);
  j = 0U;
  for (k = 0U; (k < CANFDI_DIAG_PATTERN_LEN) && (r->refs[k] != '\0') && (j < CANFDI_DIAG_N_CH); k++) {
    const char e = r->refs[k];
    const uint16_t b = (uint16_t)(1U << j);
    if (e != ' ') {
      if (e == 'a') {
        m->ref_a = (uint16_t)(m->ref_a | b);
      } else if (e == 'b') {
        m->ref_b = (uint16_t)(m->ref_b | b);
      } else {
        /* '.': the entry's sign is absolute */
      }
      j++;
    }
  }
}

/* The index of fault's model rule, CANFDI_DIAG_N_RULES if it has none. */
static uint8_t rule_of(uint8_t fault)
{
  uint32_t i;
  uint8_t idx = (uint8_t)CANFDI_DIAG_N_RULES;
  for (i = 0U; i < CANFDI_DIAG_N_RULES; i++) {
    if (canfdi_diag_model_rules[i].fault == fault) {
      idx = (uint8_t)i;
    }
  }
  return idx;
}

/*
 * The model rules whose residual zeros must be evidence against a flux
 * loss (init only): every DC-motor rule other than the flux rule itself,
 * unless it requires a symptom on a channel the flux rule expects at zero
 * (R_A up: the R_A estimate; U_A offset: UAC): that symptom already tells
 * it from a flux loss, whatever the residuals' zeros say. *flux: the flux
 * rule's index (CANFDI_DIAG_N_RULES if there is none).
 */
static uint32_t flux_gated_rules(const canfdi_diagnosis_rule_t rule[], uint8_t *flux)
{
  const uint8_t f = rule_of(CANFDI_FAULT_DCM_FLUX_DOWN);
  const uint32_t fz = (f < CANFDI_DIAG_N_RULES) ? (uint32_t)rule[f].zero : 0U;
  uint32_t gated = 0U;
  uint32_t i;
  *flux = f;
  for (i = 0U; i < CANFDI_DIAG_N_RULES; i++) {
    const canfdi_diagnosis_rule_t *m = &rule[i];
    if ((canfdi_diag_model_rules[i].comp == CANFDI_DIAG_COMP_DCM) && (i != (uint32_t)*flux) &&
        (((uint32_t)m->nec & (uint32_t)(m->pos | m->neg) & fz) == 0U)) {
      gated |= ((uint32_t)1U << i);
    }
  }
  return gated;
}

/*
 * The estimates exclude a flux loss: both DC-motor estimators have had
 * their memory's worth of updates (par_memory_updates) since the symptoms
 * appeared, and a necessary parameter entry of the flux rule (Psi -, J/Psi
 * +) is observed at zero or with the other sign. Before that memory has
 * passed an estimate mixes the data from before the fault with a
 * transient: while a flux loss develops at constant speed the mechanical
 * estimate may swing either way.
 */
static bool flux_excluded(const canfdi_diagnosis_t *d)
{
  bool ex = false;
  if ((d->flux_rule < CANFDI_DIAG_N_RULES) &&
      (d->fresh[CANFDI_DIAG_COMP_DCM][0] >= d->cfg.par_memory_updates) &&
      (d->fresh[CANFDI_DIAG_COMP_DCM][1] >= d->cfg.par_memory_updates)) {
    const canfdi_diagnosis_rule_t *f = &d->rule[d->flux_rule];
    const uint32_t par = (uint32_t)f->nec & ~(uint32_t)(f->ref_a | f->ref_b);
    const uint32_t contra = ((uint32_t)f->pos & (uint32_t)(d->obs_zero | d->obs_neg)) |
                            ((uint32_t)f->neg & (uint32_t)(d->obs_zero | d->obs_pos)) |
                            ((uint32_t)f->zero & (uint32_t)(d->obs_pos | d->obs_neg));
    ex = (par & contra) != 0U;
  }
  return ex;
}

int32_t canfdi_diagnosis_init(canfdi_diagnosis_t *d, const canfdi_diagnosis_cfg_t *cfg)
{
  int32_t rc = -CANFDI_EINVAL;
  uint32_t i;
  if (d != NULL) {
    d->initialised = false;
    if (canfdi_diagnosis_cfg_check(cfg) == CANFDI_OK) {
      d->cfg = *cfg;
      for (i = 0U; i < CANFDI_SYM_N_PAR; i++) {
        /* 2^32 / threshold: x = dev * inv / 2^16 is dev / threshold in Q16.16 */
        d->inv_pos_q16[CANFDI_DIAG_COMP_DCM][i] = canfdi_div_s32_qn(CANFDI_Q16_ONE, cfg->dcm_par_pos_q16[i], 16U);
        d->inv_neg_q16[CANFDI_DIAG_COMP_DCM][i] = canfdi_div_s32_qn(CANFDI_Q16_ONE, cfg->dcm_par_neg_q16[i], 16U);
        d->inv_pos_q16[CANFDI_DIAG_COMP_THR][i] = canfdi_div_s32_qn(CANFDI_Q16_ONE, cfg->thr_par_pos_q16[i], 16U);
        d->inv_neg_q16[CANFDI_DIAG_COMP_THR][i] = canfdi_div_s32_qn(CANFDI_Q16_ONE, cfg->thr_par_neg_q16[i], 16U);
      }
      d->inv_jpsi_q16 = canfdi_div_s32_qn(CANFDI_Q16_ONE, cfg->jpsi_q16, 16U);
      for (i = 0U; i < CANFDI_DIAG_N_RULES; i++) {
        compile_rule(&canfdi_diag_model_rules[i], &d->rule[i]);
      }
      d->fx_gated = flux_gated_rules(d->rule, &d->flux_rule);
      d->gain_rule = rule_of(CANFDI_FAULT_DCM_SPEED_SENSOR_GAIN);
      d->hard_untested = 0U;
      for (i = 0U; i < CANFDI_DIAG_N_HARD_RULES; i++) {
        d->hard_untested |= canfdi_diag_hard_rules[i].untested;
      }
      d->diag = (canfdi_diagnosis_diag_t){0};
      d->initialised = true;
      canfdi_diagnosis_reset(d);
      rc = CANFDI_OK;
    }
  }
  return rc;
}

/* Ternary of this step with hysteresis around the present state. */
static int8_t ternary(const canfdi_diagnosis_t *d, int32_t x, int8_t state)
{
  const int32_t ax = abs_sat(x);
  const int8_t sg = (x > 0) ? CANFDI_DIAG_SYM_POS : CANFDI_DIAG_SYM_NEG;
  int8_t t = CANFDI_DIAG_SYM_ZERO;
  if (ax >= d->cfg.on_q16) {
    t = sg;
  } else if ((ax >= d->cfg.off_q16) && (state == sg)) {
    t = sg;
  } else {
    /* below off, or in the band without history: absent */
  }
  return t;
}

static void pers_step(canfdi_diagnosis_pers_t *p, bool valid, int8_t t, uint16_t on_steps,
                      uint16_t off_steps)
{
  if (!valid) {
    pers_clear(p, CANFDI_DIAG_SYM_UNKNOWN);
  } else {
    if (p->state == CANFDI_DIAG_SYM_UNKNOWN) {
      /* a channel that returns starts from "absent": a symptom must persist */
      pers_clear(p, CANFDI_DIAG_SYM_ZERO);
    }
    if (t == p->state) {
      p->cand = t;
      p->n = 0U;
    } else {
      if (t != p->cand) {
        p->cand = t;
        p->n = 0U;
      }
      if (p->n < UINT16_MAX) {
        p->n++;
      }
      if (p->n >= ((t == CANFDI_DIAG_SYM_ZERO) ? off_steps : on_steps)) {
        p->state = t;
        p->n = 0U;
      }
    }
  }
}

/* Steps since the channel's value was last at or above the zero level
 * (valid), up to sym_off_steps: settled there. */
static void channel_quiet(const canfdi_diagnosis_t *d, canfdi_diagnosis_pers_t *p, int32_t x, bool valid)
{
  if (valid && (abs_sat(x) >= d->cfg.off_q16)) {
    p->quiet = 0U;
  } else if (p->quiet < d->cfg.sym_off_steps) {
    p->quiet++;
  } else {
    p->quiet = d->cfg.sym_off_steps; /* settled (also from pers_clear) */
  }
}

/* A persistence at rest on "absent": a step that reads absent again leaves
 * it as it is (pers_step would only rewrite the same values). */
static CANFDI_ALWAYS_INLINE bool pers_at_rest(const canfdi_diagnosis_pers_t *p)
{
  return (p->state == CANFDI_DIAG_SYM_ZERO) && (p->cand == CANFDI_DIAG_SYM_ZERO) && (p->n == 0U);
}

/* A channel's step off its settled state (channel below). */
static void channel_move(canfdi_diagnosis_t *d, canfdi_diagnosis_pers_t *p, int32_t x, bool valid)
{
  pers_step(p, valid, ternary(d, x, p->state), d->cfg.sym_on_steps, d->cfg.sym_off_steps);
  channel_quiet(d, p, x, valid);
}

/* Inline: some twenty channels a step, nearly all settled. */
static CANFDI_ALWAYS_INLINE void channel(canfdi_diagnosis_t *d, uint32_t c, uint32_t j, int32_t x, bool valid)
{
  canfdi_diagnosis_pers_t *p = &d->ch[c][j];
  d->x_q16[c][j] = valid ? x : 0;
  if (valid && pers_at_rest(p) && (p->quiet == d->cfg.sym_off_steps) && (abs_sat(x) < d->cfg.off_q16)) {
    /* settled and below the zero level again: nothing changes (the
     * ternary reads absent, the persistence rests, quiet stays settled);
     * the common case of every step */
  } else {
    channel_move(d, p, x, valid);
  }
}

/* Relative deviation / its threshold on that side, Q16.16. */
static int32_t par_norm(const canfdi_diagnosis_t *d, uint32_t c, uint32_t i, int32_t dev)
{
  const int32_t inv = (dev >= 0) ? d->inv_pos_q16[c][i] : d->inv_neg_q16[c][i];
  return canfdi_mul_s32_qn(dev, inv, 16U);
}

/* Estimator updates since the component's symptoms appeared: counted while
 * it was detected in the last step, from 0 at the first detected step. */
static void count_fresh(canfdi_diagnosis_t *d, uint32_t c, uint8_t upd)
{
  uint32_t k;
  for (k = 0U; k < 2U; k++) {
    const bool u = ((((uint32_t)upd) >> k) & 1U) != 0U;
    if (!d->res[c].detected) {
      d->fresh[c][k] = 0U;
    } else if (u && ((d->fresh[c][k] < d->cfg.par_fresh_updates) || (d->fresh[c][k] < d->cfg.par_memory_updates))) {
      d->fresh[c][k]++;
    } else {
      /* no update, or enough */
    }
  }
}

/* Parameter channels whose 0 is stale in component c (estimator A or B
 * has not had par_fresh_updates updates since the symptoms appeared). */
static uint16_t stale_mask(const canfdi_diagnosis_t *d, uint32_t c)
{
  const bool a = d->fresh[c][0] < d->cfg.par_fresh_updates;
  const bool b = d->fresh[c][1] < d->cfg.par_fresh_updates;
  uint16_t m = 0U;
  if (c == CANFDI_DIAG_COMP_DCM) {
    m = (uint16_t)((a ? ((1U << CANFDI_DIAG_CH_DCM_RA) | (1U << CANFDI_DIAG_CH_DCM_PSI)) : 0U) |
                   (a ? (1U << CANFDI_DIAG_CH_DCM_RAX) : 0U) | (b ? (1U << CANFDI_DIAG_CH_DCM_MC) : 0U) |
                   ((a || b) ? (1U << CANFDI_DIAG_CH_DCM_JPSI) : 0U));
  } else {
    m = (uint16_t)((a ? ((1U << CANFDI_DIAG_CH_THR_R) | (1U << CANFDI_DIAG_CH_THR_K)) : 0U) |
                   (b ? ((1U << CANFDI_DIAG_CH_THR_SPRING) | (1U << CANFDI_DIAG_CH_THR_FRICTION)) : 0U));
  }
  return m;
}

static void update_channels(canfdi_diagnosis_t *d, const canfdi_symptoms_t *s)
{
  uint32_t i;
  bool v;
  int32_t x;
  for (i = 0U; i < 2U; i++) {
    d->ref[CANFDI_DIAG_COMP_DCM][i] = s->dcm_ref[i];
    d->ref[CANFDI_DIAG_COMP_THR][i] = s->thr_ref[i];
  }
  d->held[CANFDI_DIAG_COMP_DCM] = (s->flags & (CANFDI_SYM_F_DCM_UNLEARNT | CANFDI_SYM_F_DCM_REARM)) != 0U;
  d->held[CANFDI_DIAG_COMP_THR] = (s->flags & CANFDI_SYM_F_THR_REARM) != 0U;
  count_fresh(d, CANFDI_DIAG_COMP_DCM, s->dcm_upd);
  count_fresh(d, CANFDI_DIAG_COMP_THR, s->thr_upd);
  for (i = 0U; i < CANFDI_SYM_N_RES; i++) {
    channel(d, CANFDI_DIAG_COMP_DCM, i, s->dcm_rn_q16[i], (s->dcm_rn_valid & (1U << i)) != 0U);
    channel(d, CANFDI_DIAG_COMP_THR, i, s->thr_rn_q16[i], (s->thr_rn_valid & (1U << i)) != 0U);
  }
  for (i = 0U; i < CANFDI_SYM_N_PAR; i++) {
    if ((CANFDI_SYM_N_RES + i) != CANFDI_DIAG_CH_DCM_RAX) {
      /* J enters through J/Psi only; its slot carries RAX */
      channel(d, CANFDI_DIAG_COMP_DCM, CANFDI_SYM_N_RES + i,
              par_norm(d, CANFDI_DIAG_COMP_DCM, i, s->dcm_pdev_q16[i]), (s->dcm_pdev_valid & (1U << i)) != 0U);
    }
    channel(d, CANFDI_DIAG_COMP_THR, CANFDI_SYM_N_RES + i, par_norm(d, CANFDI_DIAG_COMP_THR, i, s->thr_pdev_q16[i]),
            (s->thr_pdev_valid & (1U << i)) != 0U);
  }
  channel(d, CANFDI_DIAG_COMP_DCM, CANFDI_DIAG_CH_DCM_RAX, s->dcm_rax_q16,
          (s->flags & CANFDI_SYM_F_DCM_RAX_VALID) != 0U);
  v = ((s->dcm_pdev_valid & (1U << CANFDI_SYM_DCM_P_J)) != 0U) &&
      ((s->dcm_pdev_valid & (1U << CANFDI_SYM_DCM_P_PSI)) != 0U);
  x = canfdi_mul_s32_qn(canfdi_sub_s32_sat(s->dcm_pdev_q16[CANFDI_SYM_DCM_P_J],
                                           s->dcm_pdev_q16[CANFDI_SYM_DCM_P_PSI]),
                        d->inv_jpsi_q16, 16U);
  channel(d, CANFDI_DIAG_COMP_DCM, CANFDI_DIAG_CH_DCM_JPSI, x, v);
  channel(d, CANFDI_DIAG_COMP_DCM, CANFDI_DIAG_CH_DCM_UAC, s->dcm_ua_cmd_rn_q16,
          (s->flags & CANFDI_SYM_F_DCM_UA_CMD_VALID) != 0U);
  for (i = 0U; i < CANFDI_SYM_N_RES; i++) {
    /* a flux loss of the size the residuals show would leave residual i
     * below the zero level: its zero is no evidence against one, and
     * stays none until the prediction held above it for sym_on_steps
     * (as long as a flux loss would need to make it a symptom) */
    if (((s->flags & CANFDI_SYM_F_DCM_FX_VALID) != 0U) && (s->dcm_fx_q16[i] < d->cfg.off_q16)) {
      /* the longer the prediction has been low (since it last held
       * above the zero level for the whole hold), the longer the
       * residual needs to follow it out of its own tracked mean */
      if (d->fx_low[i] < FX_LOW_MAX) {
        d->fx_low[i]++;
      }
      d->fx_blind[i] = (uint16_t)(d->cfg.sym_on_steps + d->fx_low[i]);
    } else if (d->fx_blind[i] > 1U) {
      d->fx_blind[i]--;
    } else {
      d->fx_blind[i] = 0U; /* seen */
      d->fx_low[i] = 0U;
    }
  }
  pers_step(&d->fx_contra, true,
            ((s->flags & CANFDI_SYM_F_DCM_FX_CONTRA) != 0U) ? CANFDI_DIAG_SYM_POS : CANFDI_DIAG_SYM_ZERO,
            d->cfg.sym_on_steps, d->cfg.sym_off_steps);
  pers_step(&d->gain_contra, true,
            ((s->flags & CANFDI_SYM_F_DCM_GAIN_CONTRA) != 0U) ? CANFDI_DIAG_SYM_POS : CANFDI_DIAG_SYM_ZERO,
            d->cfg.sym_on_steps, d->cfg.sym_off_steps);
  channel(d, CANFDI_DIAG_COMP_THR, 8U, 0, false);
  channel(d, CANFDI_DIAG_COMP_THR, 9U, 0, false);
}

/* The flags' persistence: every step (full or hard rules only). Returns
 * the persistent flags (bit i: flag i present). */
static uint32_t update_flags(canfdi_diagnosis_t *d, const canfdi_symptoms_t *s)
{
  uint32_t f = 0U;
  uint32_t i;
  for (i = 0U; i < CANFDI_DIAG_N_FLAGS; i++) {
    const bool on = (s->flags & ((uint32_t)1U << i)) != 0U;
    if (on || !pers_at_rest(&d->flag[i])) {
      pers_step(&d->flag[i], true, on ? CANFDI_DIAG_SYM_POS : CANFDI_DIAG_SYM_ZERO, d->cfg.flag_on_steps,
                d->cfg.flag_off_steps);
    }
    if (d->flag[i].state == CANFDI_DIAG_SYM_POS) {
      f |= ((uint32_t)1U << i);
    }
  }
  return f;
}

static bool hard_fires(const canfdi_diag_hard_rule_t *h, uint32_t f)
{
  return ((f & h->req) == h->req) && ((f & h->forbid) == 0U);
}

/* Observed symptoms of component c as bit masks, and the weight of each
 * channel: clamp(|x|, 1, cap) while it shows a symptom, else 1 (Q16.16). */
static void observe(canfdi_diagnosis_t *d, uint32_t c)
{
  uint32_t j;
  uint16_t pos = 0U;
  uint16_t neg = 0U;
  uint16_t zero = 0U;
  for (j = 0U; j < CANFDI_DIAG_N_CH; j++) {
    const int8_t st = d->ch[c][j].state;
    const uint16_t b = (uint16_t)(1U << j);
    uint32_t w = (uint32_t)CANFDI_Q16_ONE;
    if (st == CANFDI_DIAG_SYM_POS) {
      pos = (uint16_t)(pos | b);
    } else if (st == CANFDI_DIAG_SYM_NEG) {
      neg = (uint16_t)(neg | b);
    } else if ((st == CANFDI_DIAG_SYM_ZERO) && (d->ch[c][j].cand == CANFDI_DIAG_SYM_ZERO) &&
               (d->ch[c][j].quiet >= d->cfg.sym_off_steps)) {
      /* "absent" only while settled: a channel on its way to +/- (its
       * persistence running) confirms no zero, else a fault whose
       * residuals cross their bands a few ms apart would be taken, for
       * those ms, for the fault that leaves the late one at zero; nor
       * does one inside its hysteresis band (see the header) */
      zero = (uint16_t)(zero | b);
    } else {
      /* unknown: in none of the masks */
    }
    if ((st == CANFDI_DIAG_SYM_POS) || (st == CANFDI_DIAG_SYM_NEG)) {
      w = (uint32_t)canfdi_clamp_s32(abs_sat(d->x_q16[c][j]), CANFDI_Q16_ONE, d->cfg.weight_cap_q16);
    }
    d->w_q16[j] = w;
  }
  if ((pos | neg) != 0U) {
    /* symptoms present: a parameter's 0 is evidence only once its
     * estimator has learnt from data after they appeared (a held or slow
     * estimate reads 0 whatever the fault) */
    zero = (uint16_t)(zero & ~stale_mask(d, c));
  }
  d->obs_pos = pos;
  d->obs_neg = neg;
  d->obs_zero = zero;
  d->obs_zero_fx = zero;
  if (c == CANFDI_DIAG_COMP_DCM) {
    for (j = 0U; j < CANFDI_SYM_N_RES; j++) {
      if (d->fx_blind[j] > 0U) {
        d->obs_zero_fx = (uint16_t)(d->obs_zero_fx & ~(1U << j));
      }
    }
  }
}

/* The rule's entries that follow an operating-point sign: those to flip
 * (the reference is negative) and those that cannot be judged (it is 0). */
typedef struct {
  uint32_t flip;
  uint32_t unknown;
} rule_refs_t;

static rule_refs_t refs_of(const canfdi_diagnosis_rule_t *m, const int8_t ref[2])
{
  rule_refs_t r;
  const uint32_t sign_e = (uint32_t)(m->pos | m->neg);
  r.flip = (((ref[0] < 0) ? (uint32_t)m->ref_a : 0U) | ((ref[1] < 0) ? (uint32_t)m->ref_b : 0U)) & sign_e;
  r.unknown = (((ref[0] == 0) ? (uint32_t)m->ref_a : 0U) | ((ref[1] == 0) ? (uint32_t)m->ref_b : 0U)) & sign_e;
  return r;
}

/*
 * One rule with polarity pol (+1/-1) against the observed masks, the
 * entries that follow an operating-point sign flipped or unjudgeable
 * (rr). Returns true for a candidate (every necessary entry seen, judgeable
 * and matched, at least one entry evaluated) with its confidence in *pct.
 * Sums: <= 10 entries x 2 x 16.0 in Q16.16 < 2^22; x 100 < 2^29.
 */
static bool eval_rule(const canfdi_diagnosis_t *d, const canfdi_diagnosis_rule_t *m, int8_t pol,
                      const rule_refs_t *rr, uint32_t obs_zero, uint32_t *pct)
{
  const uint32_t op = ((uint32_t)d->obs_pos & ~rr->flip) | ((uint32_t)d->obs_neg & rr->flip);
  const uint32_t on = ((uint32_t)d->obs_neg & ~rr->flip) | ((uint32_t)d->obs_pos & rr->flip);
  const uint32_t want_p = (pol > 0) ? m->pos : m->neg;
  const uint32_t want_n = (pol > 0) ? m->neg : m->pos;
  const uint32_t care = (uint32_t)m->care & ~rr->unknown;
  const uint32_t hit = ((want_p & op) | (want_n & on) | ((uint32_t)m->zero & obs_zero)) & care;
  const uint32_t seen = care & ((uint32_t)(d->obs_pos | d->obs_neg) | obs_zero);
  bool cand = ((m->nec & rr->unknown) == 0U) && ((m->nec & ~hit) == 0U) && (seen != 0U);
  if (cand) {
    uint32_t tot = 0U;
    uint32_t match = 0U;
    uint32_t rest = seen; /* the seen channels not yet summed, from bit j on */
    uint32_t j = 0U;
    while (rest != 0U) {
      const uint32_t b = 1UL << j;
      if ((rest & 1U) != 0U) {
        const uint32_t w = d->w_q16[j] << (((m->nec & b) != 0U) ? 1U : 0U);
        tot += w;
        if ((hit & b) != 0U) {
          match += w;
        }
      }
      rest >>= 1;
      j++;
    }
    /* seen != 0 and every weight >= 1.0: tot > 0 (the test is for the
     * analyzer) */
    *pct = (tot != 0U) ? ((match * 100U) / tot) : 0U;
  }
  return cand;
}

/* The primary trouble code of a fault (catalogue). */
static uint32_t code_of(uint8_t fault)
{
  return (fault < CANFDI_FAULT_COUNT) ? canfdi_catalogue_fault[fault].dtc[0] : 0U;
}

/* Best candidate of component c and the best candidate that names another
 * trouble code (model rules), into res: two rules of one code (speed-sensor
 * gain and offset) do not compete, since the decision is which code. */
static void rank(canfdi_diagnosis_t *d, uint32_t c)
{
  canfdi_diagnosis_result_t *res = &d->res[c];
  uint8_t pct_of[CANFDI_DIAG_N_RULES];
  const bool fx_off = (c != CANFDI_DIAG_COMP_DCM) || flux_excluded(d);
  uint32_t i;
  res->best = 0U;
  res->best_pct = 0U;
  res->second = 0U;
  res->second_pct = 0U;
  for (i = 0U; i < CANFDI_DIAG_N_RULES; i++) {
    const canfdi_diag_model_rule_t *r = &canfdi_diag_model_rules[i];
    pct_of[i] = 0U;
    if (r->comp == c) {
      const rule_refs_t rr = refs_of(&d->rule[i], d->ref[c]);
      const bool gate = (((d->fx_gated >> i) & 1U) != 0U) && !fx_off;
      const uint32_t zero = gate ? d->obs_zero_fx : d->obs_zero;
      uint32_t pct = 0U;
      uint32_t p2 = 0U;
      /* a residual whose sign no flux loss gives rules the flux rule out,
       * whatever its pattern's supporting entries score; an r1 too small
       * for the gain J/Psi implies rules the speed-gain rule out */
      const bool ruled_out = ((i == (uint32_t)d->flux_rule) && (d->fx_contra.state == CANFDI_DIAG_SYM_POS)) ||
                             ((i == (uint32_t)d->gain_rule) && (d->gain_contra.state == CANFDI_DIAG_SYM_POS));
      bool cand = !ruled_out && eval_rule(d, &d->rule[i], CANFDI_DIAG_SYM_POS, &rr, zero, &pct);
      if (!ruled_out && (r->bipolar != 0U) && eval_rule(d, &d->rule[i], CANFDI_DIAG_SYM_NEG, &rr, zero, &p2)) {
        if (!cand || (p2 > pct)) {
          pct = p2;
        }
        cand = true;
      }
      if (cand) {
        /* a candidate counts at least 1 % so that 0 marks "none" below */
        pct_of[i] = (uint8_t)((pct > 0U) ? pct : 1U);
        if ((res->best == 0U) || (pct_of[i] > res->best_pct)) {
          res->best = r->fault;
          res->best_pct = pct_of[i];
        }
      }
    }
  }
  for (i = 0U; i < CANFDI_DIAG_N_RULES; i++) {
    const uint8_t f = canfdi_diag_model_rules[i].fault;
    if ((pct_of[i] != 0U) && (code_of(f) != code_of(res->best)) && (pct_of[i] > res->second_pct)) {
      res->second = f;
      res->second_pct = pct_of[i];
    }
  }
}

/* Necessary channels of rule i all seen and judgeable at this operating
 * point: its test can run. */
static bool rule_testable(const canfdi_diagnosis_t *d, uint32_t i)
{
  const rule_refs_t rr = refs_of(&d->rule[i], d->ref[canfdi_diag_model_rules[i].comp]);
  return ((d->rule[i].nec & ~(uint32_t)(d->obs_pos | d->obs_neg | d->obs_zero)) == 0U) &&
         ((d->rule[i].nec & rr.unknown) == 0U);
}

static void fill_none(int8_t report[])
{
  uint32_t i;
  for (i = 0U; i < CANFDI_FAULT_COUNT; i++) {
    report[i] = CANFDI_DIAG_REPORT_NONE;
  }
}

/* Per-fault verdicts of one step, hard and model rules apart. */
typedef struct {
  canfdi_diagnosis_vmask_t h; /* hard-rule verdicts */
  canfdi_diagnosis_vmask_t m; /* model-rule verdicts */
  bool hard_any[CANFDI_DIAG_N_COMP];
} verdicts_t;

/* Fault f's verdict becomes vd (V_NONE, V_PASS or V_FAIL; a later verdict
 * replaces an earlier one). */
static CANFDI_ALWAYS_INLINE void vset(canfdi_diagnosis_vmask_t *m, uint8_t f, uint8_t vd)
{
  const uint32_t b = (uint32_t)1U << f;
  CANFDI_ASSERT((f < CANFDI_FAULT_COUNT) && (vd >= V_NONE) && (vd <= V_FAIL));
  m->has |= b;
  m->pass = (vd == V_PASS) ? (m->pass | b) : (m->pass & ~b);
  m->fail = (vd == V_FAIL) ? (m->fail | b) : (m->fail & ~b);
}

static bool vfailed(const canfdi_diagnosis_vmask_t *m, uint8_t f)
{
  return ((m->fail >> f) & 1U) != 0U;
}

/* Phase 1: the hard rules on this step's persistent flags (evaluated when
 * their inputs changed, canfdi_diagnosis_hard_t). */
static void hard_phase(canfdi_diagnosis_t *d, const canfdi_symptoms_t *s, uint32_t flags, verdicts_t *v)
{
  const uint32_t ut = s->flags & d->hard_untested;
  uint32_t i;
  if (!d->hard.valid || (flags != d->hard.flags) || (ut != d->hard.untested)) {
    canfdi_diagnosis_vmask_t h = {0U, 0U, 0U};
    uint8_t any = 0U;
    for (i = 0U; i < CANFDI_DIAG_N_HARD_RULES; i++) {
      const canfdi_diag_hard_rule_t *r = &canfdi_diag_hard_rules[i];
      if ((s->flags & r->untested) != 0U) {
        vset(&h, r->fault, V_NONE);
      } else if (hard_fires(r, flags)) {
        vset(&h, r->fault, V_FAIL);
        any = (uint8_t)(any | (1U << r->comp));
      } else {
        vset(&h, r->fault, V_PASS);
      }
    }
    d->hard = (canfdi_diagnosis_hard_t){h, flags, ut, any, true};
  }
  v->h = d->hard.v;
  for (i = 0U; i < CANFDI_DIAG_N_COMP; i++) {
    v->hard_any[i] = (((uint32_t)d->hard.any >> i) & 1U) != 0U;
  }
}

/* The component's model rules all get verdict `mv`, except that the
 * isolated fault (if any) fails. */
static void model_verdicts(uint32_t c, uint8_t mv, uint8_t isolated, verdicts_t *v)
{
  uint32_t i;
  for (i = 0U; i < CANFDI_DIAG_N_RULES; i++) {
    if (canfdi_diag_model_rules[i].comp == c) {
      vset(&v->m, canfdi_diag_model_rules[i].fault,
           ((isolated != 0U) && (canfdi_diag_model_rules[i].fault == isolated)) ? V_FAIL : mv);
    }
  }
}

static void clear_result(canfdi_diagnosis_t *d, uint32_t c, uint8_t id, uint8_t pct)
{
  canfdi_diagnosis_result_t *res = &d->res[c];
  res->best = id;
  res->best_pct = pct;
  res->second = 0U;
  res->second_pct = 0U;
  res->isolated = id;
  res->confidence_pct = pct;
  res->not_isolated = false;
  d->win_n[c] = 0U;
  d->win_id[c] = 0U;
  d->latched[c] = false;
}

/* A hard rule fired in component c: the flagged fault breaks the models'
 * assumptions, so no model verdicts. */
static void component_hard(canfdi_diagnosis_t *d, uint32_t c, bool prev_hard, verdicts_t *v)
{
  uint8_t hard_id = 0U;
  uint32_t i;
  for (i = 0U; i < CANFDI_DIAG_N_HARD_RULES; i++) {
    if ((canfdi_diag_hard_rules[i].comp == c) && vfailed(&v->h, canfdi_diag_hard_rules[i].fault) && (hard_id == 0U)) {
      hard_id = canfdi_diag_hard_rules[i].fault;
    }
  }
  clear_result(d, c, hard_id, 100U);
  if (!prev_hard) {
    canfdi_count_inc(&d->diag.hard_fires);
  }
  model_verdicts(c, V_NONE, 0U, v);
}

/* Nothing detected in component c: every testable model rule passes,
 * unless the component's models are held (held: the DC motor's estimates
 * not yet converged, or either component re-arming after an input
 * interruption; component_match). */
static void component_quiet(canfdi_diagnosis_t *d, uint32_t c, verdicts_t *v)
{
  const bool held = d->held[c];
  uint32_t i;
  clear_result(d, c, 0U, 0U);
  for (i = 0U; i < CANFDI_DIAG_N_RULES; i++) {
    if (canfdi_diag_model_rules[i].comp == c) {
      vset(&v->m, canfdi_diag_model_rules[i].fault, (!held && rule_testable(d, i)) ? V_PASS : V_NONE);
    }
  }
}

/* Something detected: rank the candidates; the winner is isolated after
 * isolate_steps consecutive wins. */
static void component_match(canfdi_diagnosis_t *d, uint32_t c, uint8_t prev_isolated, verdicts_t *v)
{
  canfdi_diagnosis_result_t *res = &d->res[c];
  uint8_t winner = 0U;
  rank(d, c);
  /* The DC motor's rules read the residuals against the estimated R_A and
   * the parameter channels against the estimates: until both have
   * converged once (the header's "Learnt estimates"), and for either
   * component while it re-arms after an input interruption ("Re-arming"),
   * a residual pattern is detected but not isolated (held). */
  if ((res->best != 0U) && !d->held[c] &&
      (res->best_pct >= d->cfg.conf_min_pct) &&
      (((uint32_t)res->best_pct) >= ((uint32_t)res->second_pct + d->cfg.margin_pct))) {
    winner = res->best;
  }
  if ((winner != 0U) && (winner == d->win_id[c])) {
    if (d->win_n[c] < UINT16_MAX) {
      d->win_n[c]++;
    }
  } else {
    d->win_id[c] = winner;
    d->win_n[c] = (winner != 0U) ? 1U : 0U;
  }
  if (d->latched[c] && (prev_isolated != 0U)) {
    /* Latched: the fault isolated in this episode stays the one named while
     * the component shows symptoms (its other model tests are inhibited:
     * their assumptions include the failed part). */
    res->isolated = prev_isolated;
    res->confidence_pct = (res->best == prev_isolated) ? res->best_pct : res->confidence_pct;
  } else if ((winner != 0U) && (d->win_n[c] >= d->cfg.isolate_steps)) {
    res->isolated = winner;
    res->confidence_pct = res->best_pct;
    d->latched[c] = true;
    if (prev_isolated != winner) {
      canfdi_count_inc(&d->diag.isolations);
    }
  } else {
    res->isolated = 0U;
    res->confidence_pct = 0U;
  }
  res->not_isolated = (res->isolated == 0U);
  if (res->not_isolated) {
    canfdi_count_inc(&d->diag.unisolated_steps);
  }
  model_verdicts(c, V_NONE, res->isolated, v);
}

/* Phase 2 of component c. full: its model rules are matched in this step
 * (hard rule, quiet or matching; every model rule of c gets its verdict
 * here). Otherwise, between its full steps: a fired hard rule clears it as
 * in a full step (its model verdicts NONE until its next one), else it
 * keeps its last full step's result and model verdicts. */
static void component_phase(canfdi_diagnosis_t *d, uint32_t c, bool full, verdicts_t *v)
{
  canfdi_diagnosis_result_t *res = &d->res[c];
  const uint8_t prev_isolated = res->isolated;
  if (v->hard_any[c]) {
    const bool prev_hard = (prev_isolated != 0U) && (res->confidence_pct == 100U) && vfailed(&v->h, prev_isolated);
    res->detected = true;
    component_hard(d, c, prev_hard, v);
  } else if (full) {
    observe(d, c);
    res->detected = ((d->obs_pos | d->obs_neg) != 0U);
    if (!res->detected) {
      component_quiet(d, c, v);
    } else {
      component_match(d, c, prev_isolated, v);
    }
  } else {
    /* between full steps: held */
  }
}

/* P2135's input: a persistent TPS disagreement (CORR) that no hard rule
 * and no model rule of the throttle explains. */
static void corr_phase(canfdi_diagnosis_t *d, const verdicts_t *v)
{
  d->corr_not_isolated = !v->hard_any[CANFDI_DIAG_COMP_THR] && (d->res[CANFDI_DIAG_COMP_THR].isolated == 0U) &&
                         ((d->ch[CANFDI_DIAG_COMP_THR][CANFDI_SYM_THR_CORR].state == CANFDI_DIAG_SYM_POS) ||
                          (d->ch[CANFDI_DIAG_COMP_THR][CANFDI_SYM_THR_CORR].state == CANFDI_DIAG_SYM_NEG));
}

/* Phase 3: one report per fault; FAILED if either test failed, PASSED only
 * if every test it has ran and passed (a passed or absent test on each
 * side, and one test at least). */
static void report_phase(canfdi_diagnosis_t *d, const verdicts_t *v, int8_t report[])
{
  const uint32_t failed = v->h.fail | v->m.fail;
  const uint32_t passed = ((~failed & (~v->h.has | v->h.pass)) & (~v->m.has | v->m.pass)) & (v->h.has | v->m.has);
  uint32_t i;
  d->failed_mask = failed;
  d->passed_mask = passed;
  if (report != NULL) {
    /* FAILED 1, PASSED -1, NONE 0; the two masks are disjoint. Four
     * faults an iteration from masks shifted as they go: every step, and
     * a bit test per fault costs twice as much. */
    uint32_t f = failed;
    uint32_t p = passed;
    for (i = 0U; i < CANFDI_FAULT_COUNT; i += 4U) {
      report[i] = (int8_t)((int32_t)(f & 1U) - (int32_t)(p & 1U));
      report[i + 1U] = (int8_t)((int32_t)((f >> 1) & 1U) - (int32_t)((p >> 1) & 1U));
      report[i + 2U] = (int8_t)((int32_t)((f >> 2) & 1U) - (int32_t)((p >> 2) & 1U));
      report[i + 3U] = (int8_t)((int32_t)((f >> 3) & 1U) - (int32_t)((p >> 3) & 1U));
      f >>= 4;
      p >>= 4;
    }
  }
}

/* One step; bit c of `model`: component c's full step (its model rules'
 * matching), else its step of the hard rules with its last full step's
 * model verdicts. Each component's model verdicts are kept apart: every
 * model rule belongs to one component, and a full step gives each of its
 * rules a verdict, so the verdicts of the last step (mv_last) stand for
 * the components not matched in this one. */
static void diagnosis_step(canfdi_diagnosis_t *d, const canfdi_symptoms_t *s, int8_t report[], uint32_t model)
{
  if ((d == NULL) || !d->initialised || (s == NULL)) {
    if ((d != NULL) && d->initialised) {
      canfdi_count_inc(&d->diag.rejected);
      d->failed_mask = 0U;
      d->passed_mask = 0U;
    }
    if (report != NULL) {
      fill_none(report);
    }
  } else {
    verdicts_t v;
    uint32_t flags;
    uint32_t c;
    canfdi_count_inc(&d->diag.steps);
    flags = update_flags(d, s);
    update_channels(d, s);
    v.m = d->mv_last;
    hard_phase(d, s, flags, &v);
    for (c = 0U; c < CANFDI_DIAG_N_COMP; c++) {
      component_phase(d, c, ((model >> c) & 1U) != 0U, &v);
    }
    d->mv_last = v.m;
    corr_phase(d, &v);
    report_phase(d, &v, report);
  }
}

void canfdi_diagnosis_step(canfdi_diagnosis_t *d, const canfdi_symptoms_t *s, int8_t report[])
{
  diagnosis_step(d, s, report, CANFDI_DIAG_ALL_COMP);
}

void canfdi_diagnosis_step_hard(canfdi_diagnosis_t *d, const canfdi_symptoms_t *s, int8_t report[])
{
  diagnosis_step(d, s, report, 0U);
}

void canfdi_diagnosis_step_comp(canfdi_diagnosis_t *d, const canfdi_symptoms_t *s, int8_t report[],
                                uint32_t components)
{
  diagnosis_step(d, s, report, components & CANFDI_DIAG_ALL_COMP);
}

uint8_t canfdi_diagnosis_isolated(const canfdi_diagnosis_t *d, uint8_t component, uint8_t *confidence_pct)
{
  const canfdi_diagnosis_result_t *r = canfdi_diagnosis_result(d, component);
  const uint8_t id = (r != NULL) ? r->isolated : 0U;
  if (confidence_pct != NULL) {
    *confidence_pct = (r != NULL) ? r->confidence_pct : 0U;
  }
  return id;
}

const canfdi_diagnosis_result_t *canfdi_diagnosis_result(const canfdi_diagnosis_t *d, uint8_t component)
{
  const uint8_t c = comp_of_catalogue(component);
  const canfdi_diagnosis_result_t *r = NULL;
  if ((d != NULL) && d->initialised && (c < CANFDI_DIAG_N_COMP)) {
    r = &d->res[c];
  }
  return r;
}

bool canfdi_diagnosis_corr_not_isolated(const canfdi_diagnosis_t *d)
{
  return (d != NULL) && d->initialised && d->corr_not_isolated;
}

uint32_t canfdi_diagnosis_failed_mask(const canfdi_diagnosis_t *d)
{
  return ((d != NULL) && d->initialised) ? d->failed_mask : 0U;
}

uint32_t canfdi_diagnosis_passed_mask(const canfdi_diagnosis_t *d)
{
  return ((d != NULL) && d->initialised) ? d->passed_mask : 0U;
}

int8_t canfdi_diagnosis_symptom(const canfdi_diagnosis_t *d, uint8_t component, uint8_t channel_idx)
{
  const uint8_t c = comp_of_catalogue(component);
  int8_t s = CANFDI_DIAG_SYM_UNKNOWN;
  if ((d != NULL) && d->initialised && (c < CANFDI_DIAG_N_COMP) && (channel_idx < CANFDI_DIAG_N_CH)) {
    s = d->ch[c][channel_idx].state;
  }
  return s;
}

int32_t canfdi_diagnosis_value_q16(const canfdi_diagnosis_t *d, uint8_t component, uint8_t channel_idx)
{
  const uint8_t c = comp_of_catalogue(component);
  int32_t x = 0;
  if ((d != NULL) && d->initialised && (c < CANFDI_DIAG_N_COMP) && (channel_idx < CANFDI_DIAG_N_CH)) {
    x = d->x_q16[c][channel_idx];
  }
  return x;
}

canfdi_diagnosis_diag_t canfdi_diagnosis_diag(const canfdi_diagnosis_t *d)
{
  canfdi_diagnosis_diag_t g = {0};
  if (d != NULL) {
    g = d->diag;
  }
  return g;
}
