/*
 * canfdi_actmgr.c — fault-tolerant actuator manager; the rules are in the
 * header.
 */
#include "ft/canfdi_actmgr.h"

#include "core/canfdi_count.h"
#include "core/canfdi_fixp.h"
#include "core/canfdi_qconst.h"

CANFDI_STATIC_ASSERT(CANFDI_FAULT_COUNT <= 32U, fault_ids_fit_a_uint32_bitset);
CANFDI_STATIC_ASSERT((CANFDI_ACTMGR_DCM_FAULTS & CANFDI_ACTMGR_THR_FAULTS) == 0U,
                     subsystem_fault_sets_disjoint);
CANFDI_STATIC_ASSERT(CANFDI_ACTMGR_UA_HIST >= 1U && CANFDI_ACTMGR_UA_HIST <= 255U,
                     actmgr_hist_fits_uint8);
CANFDI_STATIC_ASSERT(CANFDI_ACTMGR_REASON_FAIL_SILENT < CANFDI_DEGRADE_CLEAR_TESTER,
                     actmgr_reasons_below_clear_causes);



/* Keep the safest (state, reason); the first reason wins among equals. */
static void consider(uint8_t *state, uint8_t *reason, uint8_t s, uint8_t r)
{
  if (s > *state) {
    *state = s;
    *reason = r;
  }
}

/* Safest catalogue degradation among the faults in `set`, and its id
 * (lowest id among equals). NORMAL / NONE for none. */
static void catalogue_target(uint32_t set, uint8_t *state, uint8_t *reason)
{
  uint32_t id;
  *state = CANFDI_DEG_NORMAL;
  *reason = CANFDI_FAULT_NONE;
  /* stops after the highest set bit: no cost without faults */
  for (id = 1U; (id < CANFDI_FAULT_COUNT) && ((set >> id) != 0U); id++) {
    if ((set & CANFDI_FAULT_BIT(id)) != 0U) {
      consider(state, reason, canfdi_catalogue_fault[id].degradation, (uint8_t)id);
    }
  }
}

static uint8_t ctrl_mode(bool enable, bool track)
{
  uint8_t mode = CANFDI_CTRL_RUN;
  if (!enable) {
    mode = CANFDI_CTRL_OFF;
  } else if (track) {
    mode = CANFDI_CTRL_TRACK;
  } else {
    /* closed loop */
  }
  return mode;
}

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

static bool cfg_ok(const canfdi_actmgr_cfg_t *c)
{
  return (c->dcm_u_max_V_q16 > 0) && (c->dcm_check_min_V_q16 > 0) &&
         (c->dcm_deliver_ratio_q16 > 0) && (c->dcm_deliver_ratio_q16 < CANFDI_Q16_ONE) &&
         (c->dcm_lag_min_steps >= 1U) && (c->dcm_lag_min_steps <= c->dcm_lag_max_steps) &&
         (c->dcm_lag_max_steps <= CANFDI_ACTMGR_UA_HIST) && (c->dcm_bridge_fail_steps >= 1U) &&
         (c->dcm_bridge_fail_steps <= 32767U) && (c->thr_u_max_V_q16 > 0) &&
         (c->thr_vote_loss_steps >= 1U) && (c->thr_vote_loss_steps <= 32767U);
}

void canfdi_actmgr_default_cfg(canfdi_actmgr_cfg_t *cfg)
{
  if (cfg != NULL) {
    cfg->dcm_u_max_V_q16 = 60 * CANFDI_Q16_ONE;
    cfg->dcm_check_min_V_q16 = 6 * CANFDI_Q16_ONE;
    cfg->dcm_deliver_ratio_q16 = CANFDI_Q16_ONE / 2;
    cfg->dcm_lag_min_steps = 1U;
    cfg->dcm_lag_max_steps = 1U;
    cfg->dcm_bridge_fail_steps = 3U;
    cfg->thr_u_max_V_q16 = 16 * CANFDI_Q16_ONE;
    cfg->thr_vote_loss_steps = 20U;
  }
}

static void reset_dcm(canfdi_actmgr_t *m)
{
  uint32_t i;
  canfdi_debounce_reset(&m->bridge_deb[0]);
  canfdi_debounce_reset(&m->bridge_deb[1]);
  m->bridge_failed[0] = false;
  m->bridge_failed[1] = false;
  m->active_bridge = CANFDI_ACTMGR_BRIDGE_A;
  m->hist_head = 0U;
  m->hist_count = 0U;
  for (i = 0U; i < CANFDI_ACTMGR_UA_HIST; i++) {
    m->hist[i].u_V_q16 = 0;
    m->hist[i].bridge = CANFDI_ACTMGR_BRIDGE_NONE;
    m->hist[i].enable = false;
  }
  m->detected &= ~CANFDI_ACTMGR_DCM_FAULTS;
}

static void reset_thr(canfdi_actmgr_t *m)
{
  canfdi_debounce_reset(&m->vote_deb);
  m->thr_off = false;
  m->detected &= ~CANFDI_ACTMGR_THR_FAULTS;
}

int32_t canfdi_actmgr_init(canfdi_actmgr_t *m, const canfdi_actmgr_cfg_t *cfg)
{
  int32_t rc = -CANFDI_EINVAL;
  if (m != NULL) {
    m->initialised = false;
    if ((cfg != NULL) && cfg_ok(cfg)) {
      m->cfg = *cfg;
      consecutive_cfg(&m->bridge_deb_cfg, cfg->dcm_bridge_fail_steps);
      consecutive_cfg(&m->vote_deb_cfg, cfg->thr_vote_loss_steps);
      rc = CANFDI_OK;
      if ((canfdi_debounce_init(&m->bridge_deb[0], &m->bridge_deb_cfg) != CANFDI_OK) ||
          (canfdi_debounce_init(&m->bridge_deb[1], &m->bridge_deb_cfg) != CANFDI_OK) ||
          (canfdi_debounce_init(&m->vote_deb, &m->vote_deb_cfg) != CANFDI_OK) ||
          (canfdi_degrade_init(&m->dcm_deg) != CANFDI_OK) ||
          (canfdi_degrade_init(&m->thr_deg) != CANFDI_OK)) {
        rc = -CANFDI_EINVAL; /* unreachable with a checked cfg */
      }
      m->detected = 0U;
      reset_dcm(m);
      reset_thr(m);
      m->diag.steps = 0U;
      m->diag.bridge_switches = 0U;
      m->diag.drive_offs = 0U;
      m->diag.limp_homes = 0U;
      m->diag.ua_implausible = 0U;
      m->diag.dcm_clamps = 0U;
      m->diag.thr_clamps = 0U;
      m->diag.clears = 0U;
      m->diag.clears_refused = 0U;
      m->diag.rejected = 0U;
      m->initialised = (rc == CANFDI_OK);
    }
  }
  return rc;
}

/* History entry `lag` steps back (lag 1 = the command of the last step). */
static const canfdi_actmgr_hist_t *hist_at(const canfdi_actmgr_t *m, uint32_t lag)
{
  const uint32_t idx =
      ((uint32_t)m->hist_head + CANFDI_ACTMGR_UA_HIST - lag) % CANFDI_ACTMGR_UA_HIST;
  return &m->hist[idx];
}

/* The plausibility check of the bridge that drove over the lag window;
 * marks it failed when its debouncer qualifies. */
static void check_bridge(canfdi_actmgr_t *m, const canfdi_actmgr_in_t *in)
{
  const canfdi_actmgr_cfg_t *c = &m->cfg;
  bool evaluate = in->dcm_ua_valid &&
                  ((in->faults & CANFDI_FAULT_BIT(CANFDI_FAULT_DCM_UA_SENSOR_OFFSET)) == 0U) &&
                  (m->hist_count >= c->dcm_lag_max_steps);
  bool explained = false;
  uint8_t bridge = CANFDI_ACTMGR_BRIDGE_NONE;
  uint32_t lag;

  for (lag = c->dcm_lag_min_steps; evaluate && (lag <= c->dcm_lag_max_steps); lag++) {
    const canfdi_actmgr_hist_t *h = hist_at(m, lag);
    int32_t u_exp = h->u_V_q16;
    if (in->dcm_supply_valid && (in->dcm_supply_V_q16 >= 0)) {
      u_exp = canfdi_clamp_s32(u_exp, -in->dcm_supply_V_q16, in->dcm_supply_V_q16);
    }
    if (lag == c->dcm_lag_min_steps) {
      bridge = h->bridge;
    }
    if (!h->enable || (h->bridge != bridge) || (bridge == CANFDI_ACTMGR_BRIDGE_NONE) ||
        (canfdi_q31_abs(u_exp) < c->dcm_check_min_V_q16)) {
      evaluate = false;
    } else {
      const int32_t mag = canfdi_q31_abs(u_exp);
      const int32_t delivered = (u_exp >= 0) ? in->dcm_ua_V_q16 : canfdi_q31_neg(in->dcm_ua_V_q16);
      if (delivered >= canfdi_mul_s32_qn(c->dcm_deliver_ratio_q16, mag, 16U)) {
        explained = true;
      }
    }
  }

  if (evaluate) {
    const uint32_t b = (uint32_t)bridge - 1U; /* bridge is A or B here */
    const int32_t st = canfdi_debounce_report(
        &m->bridge_deb[b], explained ? CANFDI_DEB_REPORT_PREPASSED : CANFDI_DEB_REPORT_PREFAILED);
    CANFDI_ASSERT(st >= 0);
    if (!explained) {
      canfdi_count_inc(&m->diag.ua_implausible);
      if (st == (int32_t)CANFDI_DEB_FAILED) {
        m->bridge_failed[b] = true;
        m->detected |= CANFDI_FAULT_BIT((b == 0U) ? CANFDI_FAULT_DCM_BRIDGE_A_DEAD
                                                         : CANFDI_FAULT_DCM_BRIDGES_DEAD);
      }
    }
  }
}

static void step_dcm(canfdi_actmgr_t *m, const canfdi_actmgr_in_t *in, canfdi_actmgr_out_t *out)
{
  const canfdi_actmgr_cfg_t *c = &m->cfg;
  const uint32_t f = in->faults;
  uint8_t target;
  uint8_t reason;
  uint8_t state;
  uint8_t bridge;
  canfdi_actmgr_hist_t *h;

  check_bridge(m, in);
  if ((f & CANFDI_FAULT_BIT(CANFDI_FAULT_DCM_BRIDGE_A_DEAD)) != 0U) {
    m->bridge_failed[0] = true;
  }
  if ((f & CANFDI_FAULT_BIT(CANFDI_FAULT_DCM_BRIDGES_DEAD)) != 0U) {
    m->bridge_failed[0] = true;
    m->bridge_failed[1] = true;
  }

  catalogue_target(f & CANFDI_ACTMGR_DCM_FAULTS, &target, &reason);
  if (m->bridge_failed[0] && m->bridge_failed[1]) {
    consider(&target, &reason, CANFDI_DEG_FAIL_SAFE, CANFDI_FAULT_DCM_BRIDGES_DEAD);
  } else if (m->bridge_failed[0]) {
    /* Lost redundancy: B alone is fail-operational. (B alone cannot fail:
     * it is only checked while it drives, i.e. after A failed.) */
    consider(&target, &reason, CANFDI_DEG_DEGRADED, CANFDI_FAULT_DCM_BRIDGE_A_DEAD);
  } else {
    /* both healthy */
  }
  if (in->fail_silent) {
    consider(&target, &reason, CANFDI_DEG_FAIL_SILENT, CANFDI_ACTMGR_REASON_FAIL_SILENT);
  }
  if (target > CANFDI_DEG_NORMAL) { /* NORMAL is no request: only a clear leads there */
    (void)canfdi_degrade_request(&m->dcm_deg, target, reason, in->now_ms);
  }
  state = canfdi_degrade_state(&m->dcm_deg);

  if ((state >= CANFDI_DEG_FAIL_SAFE) || (m->bridge_failed[0] && m->bridge_failed[1])) {
    bridge = CANFDI_ACTMGR_BRIDGE_NONE;
  } else if (m->bridge_failed[0]) {
    bridge = CANFDI_ACTMGR_BRIDGE_B;
  } else {
    bridge = CANFDI_ACTMGR_BRIDGE_A;
  }

  out->bridge_switched = (m->active_bridge == CANFDI_ACTMGR_BRIDGE_A) &&
                         (bridge == CANFDI_ACTMGR_BRIDGE_B);
  if (out->bridge_switched) {
    canfdi_count_inc(&m->diag.bridge_switches);
  }
  if ((bridge == CANFDI_ACTMGR_BRIDGE_NONE) && (m->active_bridge != CANFDI_ACTMGR_BRIDGE_NONE)) {
    canfdi_count_inc(&m->diag.drive_offs);
  }
  m->active_bridge = bridge;

  out->dcm.bridge = bridge;
  out->dcm.enable = (bridge != CANFDI_ACTMGR_BRIDGE_NONE);
  if (out->dcm.enable) {
    out->dcm.u_cmd_V_q16 =
        canfdi_clamp_s32(in->dcm_u_ctrl_V_q16, -c->dcm_u_max_V_q16, c->dcm_u_max_V_q16);
    if (out->dcm.u_cmd_V_q16 != in->dcm_u_ctrl_V_q16) {
      canfdi_count_inc(&m->diag.dcm_clamps);
    }
  } else {
    out->dcm.u_cmd_V_q16 = 0;
  }
  out->dcm_track = (out->dcm.u_cmd_V_q16 != in->dcm_u_ctrl_V_q16) || out->bridge_switched ||
                   !out->dcm.enable;
  out->dcm_track_V_q16 = out->dcm.u_cmd_V_q16;
  out->dcm_ctrl_mode = ctrl_mode(out->dcm.enable, out->dcm_track);
  if (in->dcm_hold_off && out->dcm.enable) {
    out->dcm.enable = false;
    out->dcm.u_cmd_V_q16 = 0;
    out->dcm_track = true;
    out->dcm_track_V_q16 = 0;
    out->dcm_ctrl_mode = CANFDI_CTRL_TRACK;
  }
  out->dcm_state = state;
  out->dcm_reason = canfdi_degrade_reason(&m->dcm_deg);

  h = &m->hist[m->hist_head];
  h->u_V_q16 = out->dcm.u_cmd_V_q16;
  h->bridge = bridge;
  h->enable = out->dcm.enable;
  m->hist_head = (uint8_t)((m->hist_head + 1U) % CANFDI_ACTMGR_UA_HIST);
  if (m->hist_count < CANFDI_ACTMGR_UA_HIST) {
    m->hist_count = (uint8_t)(m->hist_count + 1U);
  }
}

/* Reason for a lost TPS k (0 or 1), in the priority of the header. */
static uint8_t tps_reason(uint32_t faults, const canfdi_vote_out_t *vote, uint32_t k)
{
  static const uint8_t named[2][3] = {
      {CANFDI_FAULT_THR_TPS1_OPEN, CANFDI_FAULT_THR_TPS1_SHORT, CANFDI_FAULT_THR_TPS1_DRIFT},
      {CANFDI_FAULT_THR_TPS2_OPEN, CANFDI_FAULT_THR_TPS2_SHORT, CANFDI_FAULT_THR_TPS2_DRIFT}};
  uint8_t r = (k == 0U) ? CANFDI_ACTMGR_REASON_TPS1_INVALID : CANFDI_ACTMGR_REASON_TPS2_INVALID;
  uint32_t i;
  bool found = false;
  for (i = 0U; (i < 3U) && !found; i++) {
    if ((faults & CANFDI_FAULT_BIT(named[k][i])) != 0U) {
      r = named[k][i];
      found = true;
    }
  }
  if (!found && ((vote->isolated_mask & (1U << k)) != 0U)) {
    r = named[k][2];
  }
  return r;
}

static void step_thr(canfdi_actmgr_t *m, const canfdi_actmgr_in_t *in,
                     const canfdi_vote_out_t *vote, canfdi_actmgr_out_t *out)
{
  const canfdi_actmgr_cfg_t *c = &m->cfg;
  const uint32_t f = in->faults;
  const uint8_t tps_mask = CANFDI_VOTE_BIT_TPS1 | CANFDI_VOTE_BIT_TPS2;
  const uint8_t lost = (uint8_t)(vote->excluded_mask & tps_mask);
  uint8_t target;
  uint8_t reason;
  uint8_t state;
  int32_t vst;
  bool off;

  vst = canfdi_debounce_report(&m->vote_deb, vote->valid ? CANFDI_DEB_REPORT_PREPASSED
                                                          : CANFDI_DEB_REPORT_PREFAILED);
  CANFDI_ASSERT(vst >= 0);

  catalogue_target(f & CANFDI_ACTMGR_THR_FAULTS, &target, &reason);
  if (lost == tps_mask) {
    consider(&target, &reason, CANFDI_DEG_FAIL_SAFE, CANFDI_FAULT_THR_TPS_BOTH_LOST);
  }
  if (!vote->valid && (vst == (int32_t)CANFDI_DEB_FAILED)) {
    consider(&target, &reason, CANFDI_DEG_FAIL_SAFE,
             (vote->status == (uint8_t)CANFDI_VOTE_DISAGREE) ? CANFDI_ACTMGR_REASON_TPS_DISAGREE
                                                             : CANFDI_ACTMGR_REASON_VOTE_LOST);
  }
  if (lost == CANFDI_VOTE_BIT_TPS1) {
    consider(&target, &reason, CANFDI_DEG_DEGRADED, tps_reason(f, vote, 0U));
  } else if (lost == CANFDI_VOTE_BIT_TPS2) {
    consider(&target, &reason, CANFDI_DEG_DEGRADED, tps_reason(f, vote, 1U));
  } else {
    /* none or both (handled above) */
  }
  if ((vote->isolated_mask & CANFDI_VOTE_BIT_MODEL) != 0U) {
    consider(&target, &reason, CANFDI_DEG_DEGRADED, CANFDI_ACTMGR_REASON_MODEL_ISOLATED);
  }
  if ((vote->newly_isolated & tps_mask) != 0U) {
    m->detected |= CANFDI_FAULT_BIT(((vote->newly_isolated & CANFDI_VOTE_BIT_TPS1) != 0U)
                                               ? CANFDI_FAULT_THR_TPS1_DRIFT
                                               : CANFDI_FAULT_THR_TPS2_DRIFT);
  }
  if (in->fail_silent) {
    consider(&target, &reason, CANFDI_DEG_FAIL_SILENT, CANFDI_ACTMGR_REASON_FAIL_SILENT);
  }
  if (target > CANFDI_DEG_NORMAL) {
    (void)canfdi_degrade_request(&m->thr_deg, target, reason, in->now_ms);
  }
  state = canfdi_degrade_state(&m->thr_deg);

  off = (state >= CANFDI_DEG_FAIL_SAFE);
  if (off && !m->thr_off) {
    canfdi_count_inc(&m->diag.limp_homes);
  }
  m->thr_off = off;
  out->thr.enable = !off;
  if (off) {
    out->thr.u_cmd_V_q16 = 0;
  } else {
    out->thr.u_cmd_V_q16 =
        canfdi_clamp_s32(in->thr_u_ctrl_V_q16, -c->thr_u_max_V_q16, c->thr_u_max_V_q16);
    if (out->thr.u_cmd_V_q16 != in->thr_u_ctrl_V_q16) {
      canfdi_count_inc(&m->diag.thr_clamps);
    }
  }
  out->thr_limp_home = off;
  out->thr_track = off || (out->thr.u_cmd_V_q16 != in->thr_u_ctrl_V_q16);
  out->thr_track_V_q16 = out->thr.u_cmd_V_q16;
  out->thr_ctrl_mode = ctrl_mode(out->thr.enable, out->thr_track);
  if (in->thr_hold_off && out->thr.enable) {
    out->thr.enable = false;
    out->thr.u_cmd_V_q16 = 0;
    out->thr_track = true;
    out->thr_track_V_q16 = 0;
    out->thr_ctrl_mode = CANFDI_CTRL_TRACK;
  }
  out->thr_state = state;
  out->thr_reason = canfdi_degrade_reason(&m->thr_deg);
}

static void out_safe(canfdi_actmgr_out_t *out)
{
  out->dcm.enable = false;
  out->dcm.bridge = CANFDI_ACTMGR_BRIDGE_NONE;
  out->dcm.u_cmd_V_q16 = 0;
  out->thr.enable = false;
  out->thr.u_cmd_V_q16 = 0;
  out->dcm_state = CANFDI_DEG_FAIL_SAFE;
  out->thr_state = CANFDI_DEG_FAIL_SAFE;
  out->dcm_reason = CANFDI_FAULT_NONE;
  out->thr_reason = CANFDI_FAULT_NONE;
  out->dcm_track = true;
  out->thr_track = true;
  out->dcm_track_V_q16 = 0;
  out->thr_track_V_q16 = 0;
  out->dcm_ctrl_mode = CANFDI_CTRL_OFF;
  out->thr_ctrl_mode = CANFDI_CTRL_OFF;
  out->thr_limp_home = true;
  out->bridge_switched = false;
  out->detected = 0U;
}

int32_t canfdi_actmgr_step(canfdi_actmgr_t *m, const canfdi_actmgr_in_t *in,
                           const canfdi_vote_out_t *vote, canfdi_actmgr_out_t *out)
{
  int32_t rc = -CANFDI_EINVAL;
  if ((m == NULL) || (in == NULL) || (vote == NULL) || (out == NULL) || !m->initialised) {
    if (out != NULL) {
      out_safe(out);
    }
    if ((m != NULL) && m->initialised) {
      canfdi_count_inc(&m->diag.rejected);
    }
  } else {
    step_dcm(m, in, out);
    step_thr(m, in, vote, out);
    out->detected = m->detected;
    canfdi_count_inc(&m->diag.steps);
    rc = CANFDI_OK;
  }
  return rc;
}

int32_t canfdi_actmgr_clear(canfdi_actmgr_t *m, uint32_t subsystems, uint8_t cause,
                            uint32_t faults, uint64_t now_ms)
{
  int32_t rc = -CANFDI_EINVAL;
  if ((m != NULL) && m->initialised && (subsystems != 0U) &&
      ((subsystems & ~(CANFDI_ACTMGR_SUB_DCM | CANFDI_ACTMGR_SUB_THR)) == 0U) &&
      ((cause == CANFDI_DEGRADE_CLEAR_TESTER) || (cause == CANFDI_DEGRADE_CLEAR_NEW_CYCLE))) {
    uint32_t done = 0U;
    uint8_t st;
    uint8_t why;
    if ((subsystems & CANFDI_ACTMGR_SUB_DCM) != 0U) {
      catalogue_target(faults & CANFDI_ACTMGR_DCM_FAULTS, &st, &why);
      if (canfdi_degrade_clear(&m->dcm_deg, cause, st > CANFDI_DEG_NORMAL, now_ms) == CANFDI_OK) {
        reset_dcm(m);
        done |= CANFDI_ACTMGR_SUB_DCM;
        canfdi_count_inc(&m->diag.clears);
      } else {
        canfdi_count_inc(&m->diag.clears_refused);
      }
    }
    if ((subsystems & CANFDI_ACTMGR_SUB_THR) != 0U) {
      catalogue_target(faults & CANFDI_ACTMGR_THR_FAULTS, &st, &why);
      if (canfdi_degrade_clear(&m->thr_deg, cause, st > CANFDI_DEG_NORMAL, now_ms) == CANFDI_OK) {
        reset_thr(m);
        done |= CANFDI_ACTMGR_SUB_THR;
        canfdi_count_inc(&m->diag.clears);
      } else {
        canfdi_count_inc(&m->diag.clears_refused);
      }
    }
    rc = (int32_t)done;
  } else if ((m != NULL) && m->initialised) {
    canfdi_count_inc(&m->diag.rejected);
  } else {
    /* nothing to count in */
  }
  return rc;
}

int32_t canfdi_actmgr_set_applied(canfdi_actmgr_t *m, const canfdi_actmgr_dcm_cmd_t *dcm)
{
  int32_t rc = -CANFDI_EINVAL;
  if ((m != NULL) && m->initialised) {
    if (m->hist_count > 0U) {
      canfdi_actmgr_hist_t *h =
          &m->hist[((uint32_t)m->hist_head + CANFDI_ACTMGR_UA_HIST - 1U) % CANFDI_ACTMGR_UA_HIST];
      if (dcm != NULL) {
        h->u_V_q16 = dcm->u_cmd_V_q16;
        h->bridge = dcm->bridge;
        h->enable = dcm->enable;
      } else {
        h->u_V_q16 = 0;
        h->bridge = CANFDI_ACTMGR_BRIDGE_NONE;
        h->enable = false;
      }
    }
    rc = CANFDI_OK;
  }
  return rc;
}

const canfdi_degrade_t *canfdi_actmgr_degrade_dcm(const canfdi_actmgr_t *m)
{
  return (m != NULL) ? &m->dcm_deg : NULL;
}

const canfdi_degrade_t *canfdi_actmgr_degrade_thr(const canfdi_actmgr_t *m)
{
  return (m != NULL) ? &m->thr_deg : NULL;
}

canfdi_actmgr_diag_t canfdi_actmgr_diag(const canfdi_actmgr_t *m)
{
  canfdi_actmgr_diag_t z = {0U, 0U, 0U, 0U, 0U, 0U, 0U, 0U, 0U, 0U};
  return (m != NULL) ? m->diag : z;
}
