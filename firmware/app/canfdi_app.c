/*
 * canfdi_app.c — the supervisor application, a sequencer of stages (see
 * canfdi_app.h for the order and the contract of each).
 */
#include "app/canfdi_app.h"

#include "app/canfdi_app_sym.h"
#include "app/canfdi_app_uds.h"
#include "comm/gen/canfdi_msg.h"
#include "core/canfdi_count.h"
#include "core/canfdi_fixp.h"
#include "core/canfdi_qconst.h"

/* Shorthands for the input supervision's verdicts of this step. */
#define IN_VALID(app, i) canfdi_rx_valid(&(app)->rx, (unsigned)(i))
#define IN_USABLE(app, i) canfdi_rx_usable(&(app)->rx, (unsigned)(i))
#define IN_FRESH(app, i) canfdi_rx_fresh(&(app)->rx, (unsigned)(i))
#define IN_SAMPLES(app, i) canfdi_rx_samples(&(app)->rx, (unsigned)(i))
#define IN_VAL(app, i) canfdi_rx_value(&(app)->rx, (unsigned)(i))

int32_t canfdi_app_rx_frame(canfdi_app_t *app, uint32_t id, const uint8_t *data, uint8_t dlc,
                            uint32_t now_us)
{
  int32_t rc = -CANFDI_EINVAL;
  if ((app != NULL) && app->initialised) {
    if ((id == CANFDI_MSG_UDS_PHYS_REQ_FRAME_ID) || (id == CANFDI_MSG_UDS_FUNC_REQ_FRAME_ID)) {
      /* the diagnostic server's connection, not a supervised input */
      rc = canfdi_uds_rx_can(&app->uds, id == CANFDI_MSG_UDS_FUNC_REQ_FRAME_ID, data, dlc);
    } else {
      rc = (int32_t)canfdi_rx_frame(&app->rx, id, data, dlc, now_us);
    }
  }
  return rc;
}

void canfdi_app_deadline_miss(canfdi_app_t *app)
{
  if (app != NULL) {
    canfdi_count_inc(&app->diag.deadline_misses);
  }
}

void canfdi_app_port_timing(canfdi_app_t *app, uint32_t step_us, uint32_t cycle_us)
{
  if (app != NULL) {
    canfdi_app_out_port_timing(&app->out, step_us, cycle_us);
  }
}

bool canfdi_app_reset_requested(const canfdi_app_t *app) { return (app != NULL) && app->reset_requested; }

const canfdi_dtc_t *canfdi_app_dtc(const canfdi_app_t *app) { return (app != NULL) ? &app->dtc : NULL; }

uint64_t canfdi_app_uptime_ms(const canfdi_app_t *app)
{
  return (app != NULL) ? canfdi_uptime_ms(&app->uptime) : 0U;
}

const canfdi_app_diag_t *canfdi_app_diag(const canfdi_app_t *app)
{
  return (app != NULL) ? &app->diag : NULL;
}

/* What canfdi_app_set_applied said for this step (canfdi_app.h); without
 * a call every command is this application's own, and known. */
static bool thr_cmd_known(const canfdi_app_t *app) { return !app->applied_set || app->applied.thr_known; }

static bool thr_ref_known(const canfdi_app_t *app) { return !app->applied_set || app->applied.thr_ref_known; }

int32_t canfdi_app_set_applied(canfdi_app_t *app, const canfdi_app_applied_t *applied)
{
  int32_t rc = -CANFDI_EINVAL;
  if ((app != NULL) && app->initialised && (applied != NULL)) {
    app->applied = *applied;
    app->applied_set = true;
    if (applied->dcm_known) {
      app->fb.mgr.dcm = applied->dcm;
    } else {
      app->fb.mgr.dcm = (canfdi_actmgr_dcm_cmd_t){0}; /* not driving: nothing judged on it */
    }
    if (applied->thr_known) {
      app->fb.mgr.thr = applied->thr;
    } else {
      app->fb.mgr.thr = (canfdi_actmgr_thr_cmd_t){0};
    }
    rc = canfdi_actmgr_set_applied(&app->actmgr, applied->dcm_known ? &applied->dcm : NULL);
  }
  return rc;
}

/* The load torque the models assume: the vehicle's feed-forward while it
 * is usable, else the calibrated nominal load (also what stage 1 offers the
 * input supervision as the stand-in of every step). */
static int32_t load_known_q16(const canfdi_app_t *app)
{
  return IN_USABLE(app, CANFDI_RX_IN_SP_DCM_LOAD) ? IN_VAL(app, CANFDI_RX_IN_SP_DCM_LOAD)
                                                  : app->cal.load_nom_Nm_q16;
}

/* Stage 2: TPS range checks (on received voltages only: an INVALID input
 * is the communication monitors' case) and the 2-out-of-3 vote. */
static void stage_vote(canfdi_app_t *app)
{
  static const unsigned tps[2] = {CANFDI_RX_IN_THR_TPS1, CANFDI_RX_IN_THR_TPS2};
  const canfdi_parity_thr_out_t *po = canfdi_parity_thr_out(&app->parity_thr);
  const uint8_t pos_bits = (uint8_t)((1U << CANFDI_PARITY_THR_POS1) | (1U << CANFDI_PARITY_THR_POS2));
  canfdi_vote_in_t vin;
  bool ok[2];
  uint32_t k;
  for (k = 0U; k < 2U; k++) {
    if (IN_USABLE(app, tps[k])) {
      (void)canfdi_limit_step(&app->tps_range[k], IN_VAL(app, tps[k]));
    }
    ok[k] = IN_VALID(app, tps[k]) && (canfdi_limit_symptom(&app->tps_range[k]) == CANFDI_LIMIT_IN_BAND);
  }
  vin.tps1_V_q16 = IN_VAL(app, CANFDI_RX_IN_THR_TPS1);
  vin.tps2_V_q16 = IN_VAL(app, CANFDI_RX_IN_THR_TPS2);
  vin.tps1_valid = ok[0];
  vin.tps2_valid = ok[1];
  vin.model_rad_q16 = (po != NULL) ? po->theta_hat_rad_q16 : 0;
  vin.model_valid = (po != NULL) && ((po->valid & pos_bits) != 0U) && !app->fb.thr_arm_symptom &&
                    thr_cmd_known(app);
  vin.model_no_blame = (po != NULL) && po->no_ref;
  (void)canfdi_vote_step(&app->vote, &vin, &app->vote_out);
}

/* A suspicion on the throttle's mechanics (canfdi_app_test.h, Need): the
 * fast test's friction deviation at or above half its threshold, or its
 * spring deviation at or below half its negative one (the directions of
 * the catalogue faults), or both position residuals past a quarter of
 * their bands with one sign for 50 consecutive steps (counted here, every
 * step). Last step's diagnosis values. */
static bool thr_suspect(canfdi_app_t *app)
{
  const uint8_t thr = CANFDI_COMPONENT_THROTTLE;
  const int32_t half = CANFDI_Q16_ONE / 2;
  const int32_t quarter = CANFDI_Q16_ONE / 4;
  const int32_t p1 = canfdi_diagnosis_value_q16(&app->diagnosis, thr, CANFDI_SYM_THR_POS1);
  const int32_t p2 = canfdi_diagnosis_value_q16(&app->diagnosis, thr, CANFDI_SYM_THR_POS2);
  const bool lag = ((p1 >= quarter) && (p2 >= quarter)) || ((p1 <= -quarter) && (p2 <= -quarter));
  if (!lag) {
    app->fb.thr_pos_lag = 0U;
  } else if (app->fb.thr_pos_lag < UINT16_MAX) {
    app->fb.thr_pos_lag++;
  } else {
    /* saturated */
  }
  return (canfdi_diagnosis_value_q16(&app->diagnosis, thr, CANFDI_DIAG_CH_THR_FRICTION) >= half) ||
         (canfdi_diagnosis_value_q16(&app->diagnosis, thr, CANFDI_DIAG_CH_THR_SPRING) <= -half) ||
         (app->fb.thr_pos_lag >= 50U);
}

/* Stage 3: both controllers, in the mode the manager set last step. TRACK
 * runs the controller (the manager's tracked value is the controller's own
 * output at a bridge switch, or 0 while the drive is held off). */
/* Stage 3a: whether the test signals run this step (canfdi_app_test.h),
 * on the last step's states and diagnosis. */
static void stage_test(canfdi_app_t *app)
{
  const canfdi_actmgr_out_t *m = &app->fb.mgr;
  const canfdi_diagnosis_result_t *rd = canfdi_diagnosis_result(&app->diagnosis, CANFDI_COMPONENT_DC_MOTOR);
  const canfdi_diagnosis_result_t *rt = canfdi_diagnosis_result(&app->diagnosis, CANFDI_COMPONENT_THROTTLE);
  canfdi_app_test_in_t d;
  canfdi_app_test_in_t t;
  bool dcm_on;
  bool thr_on;
  const bool suspect = thr_suspect(app);
  d.ref_usable = IN_USABLE(app, CANFDI_RX_IN_SP_DCM_SPEED);
  d.ref_q16 = IN_VAL(app, CANFDI_RX_IN_SP_DCM_SPEED);
  d.closed_loop = (m->dcm_ctrl_mode != CANFDI_CTRL_OFF) && (m->dcm_state == CANFDI_DEG_NORMAL);
  d.excited = app->dcm.est_on && canfdi_est_dcm_excited(&app->est_dcm);
  d.need = (rd != NULL) && rd->detected && rd->not_isolated;
  d.unlearnt = app->dcm.est_on && !canfdi_est_dcm_arm_converged(&app->est_dcm);
  t.ref_usable = IN_USABLE(app, CANFDI_RX_IN_SP_THR_ANGLE);
  t.ref_q16 = IN_VAL(app, CANFDI_RX_IN_SP_THR_ANGLE);
  t.closed_loop = (m->thr_ctrl_mode != CANFDI_CTRL_OFF) && (m->thr_state == CANFDI_DEG_NORMAL);
  t.excited = app->thr.est_on && canfdi_est_thr_excited(&app->est_thr);
  t.need = (rt != NULL) && ((rt->detected && rt->not_isolated) || suspect) &&
           !canfdi_diagnosis_corr_not_isolated(&app->diagnosis);
  t.unlearnt = app->thr.est_on && !canfdi_est_thr_el_converged(&app->est_thr);
  /* a component's first symptom: its estimator becomes alert (covariance
   * boost), so that the parameter evidence the isolation may need arrives
   * within the diagnosis' freshness count */
  app->dcm.est_restart = false;
  if ((rd != NULL) && rd->detected && !app->fb.dcm_detected) {
    canfdi_est_dcm_boost(&app->est_dcm);
    app->dcm.est_restart = true;
  }
  if ((rt != NULL) && rt->detected && !app->fb.thr_detected) {
    canfdi_est_thr_boost(&app->est_thr);
  }
  app->fb.dcm_detected = (rd != NULL) && rd->detected;
  app->fb.thr_detected = (rt != NULL) && rt->detected;
  canfdi_app_test_step(&app->test, &app->cal.test, &d, &t, &dcm_on, &thr_on);
  canfdi_excite_enable(&app->excite_dcm, dcm_on && app->cal.excite_dcm_on);
  canfdi_excite_enable(&app->excite_thr, thr_on && app->cal.excite_thr_on);
}

static void stage_control(canfdi_app_t *app, int32_t *u_dcm, int32_t *u_thr)
{
  canfdi_ctrl_dcm_in_t din;
  canfdi_ctrl_thr_in_t tin;
  const canfdi_actmgr_out_t *m = &app->fb.mgr;
  int32_t ex_dcm;
  int32_t ex_thr;
  stage_test(app);
  ex_dcm = canfdi_excite_step_q16(&app->excite_dcm);
  ex_thr = canfdi_excite_step_q16(&app->excite_thr);
  const uint8_t dmode = (m->dcm_ctrl_mode == CANFDI_CTRL_OFF) ? (uint8_t)CANFDI_CTRL_OFF : (uint8_t)CANFDI_CTRL_RUN;
  const uint8_t tmode = (m->thr_ctrl_mode == CANFDI_CTRL_OFF) ? (uint8_t)CANFDI_CTRL_OFF : (uint8_t)CANFDI_CTRL_RUN;
  din.speed_ref_rad_s_q16 = app->uds_act.speed_override ? app->uds_act.speed_ref_rad_s_q16
                            : (IN_USABLE(app, CANFDI_RX_IN_SP_DCM_SPEED) ? IN_VAL(app, CANFDI_RX_IN_SP_DCM_SPEED) : 0);
  din.excite_rad_s_q16 = ex_dcm;
  din.speed_rad_s_q16 = IN_VAL(app, CANFDI_RX_IN_DCM_OMEGA);
  din.ia_A_q16 = IN_VAL(app, CANFDI_RX_IN_DCM_IA);
  din.supply_V_q16 = IN_VAL(app, CANFDI_RX_IN_DCM_USUPPLY);
  din.u_track_V_q16 = m->dcm.u_cmd_V_q16;
  din.ia_valid = IN_VALID(app, CANFDI_RX_IN_DCM_IA);
  /* no usable speed or supply: the loop cannot run; the manager decides
   * the degradation from the communication monitors */
  din.mode = (IN_USABLE(app, CANFDI_RX_IN_DCM_OMEGA) && IN_USABLE(app, CANFDI_RX_IN_DCM_USUPPLY))
                 ? dmode
                 : (uint8_t)CANFDI_CTRL_OFF;
  *u_dcm = canfdi_ctrl_dcm_step(&app->ctrl_dcm, &din, NULL);
  tin.angle_ref_rad_q16 = app->uds_act.angle_override ? app->uds_act.angle_ref_rad_q16
                          : (IN_USABLE(app, CANFDI_RX_IN_SP_THR_ANGLE) ? IN_VAL(app, CANFDI_RX_IN_SP_THR_ANGLE)
                                                                       : app->cal.ctrl_thr.limp_home_rad_q16);
  tin.excite_rad_q16 = ex_thr;
  tin.angle_rad_q16 = app->vote_out.angle_rad_q16;
  tin.supply_V_q16 = IN_VAL(app, CANFDI_RX_IN_THR_USUPPLY);
  tin.u_track_V_q16 = m->thr.u_cmd_V_q16;
  tin.mode = app->vote_out.valid ? tmode : (uint8_t)CANFDI_CTRL_OFF;
  *u_thr = canfdi_ctrl_thr_step(&app->ctrl_thr, &tin, NULL);
}

/* One plant's gate for this step: the parity equations run on VALID inputs
 * (restarting after an interruption, then re-arming), the estimator learns
 * only when fed (restarting with a covariance reset, the estimate kept,
 * once it has run). A VALID sample that is not fresh (its frame late, not
 * timed out) interrupts nothing but holds the model rules for
 * cal->late_hold_steps (canfdi_app.h, feedback). */
static void gate(canfdi_app_gate_t *g, const canfdi_app_cal_t *cal, bool in_ok, bool fresh, bool est_on,
                 bool running, bool est_has_run, bool *reset_parity, bool *reset_est)
{
  *reset_parity = in_ok && !g->in_ok && running;
  *reset_est = est_on && !g->est_on && est_has_run;
  if (*reset_parity && g->started) {
    /* back after an interruption (not the first start): held while the
     * restarted equations leave their transient */
    g->rearm = cal->rearm_steps;
  } else if (in_ok && !fresh) {
    /* the models step on the last sample again: held while the filters
     * carry that distortion */
    g->rearm = (g->rearm > cal->late_hold_steps) ? g->rearm : cal->late_hold_steps;
  } else if (in_ok && (g->rearm > 0U)) {
    g->rearm--;
  } else {
    /* holding, or interrupted (the rules' inputs are invalid anyway) */
  }
  g->in_ok = in_ok;
  g->fresh = in_ok && fresh;
  g->started = g->started || in_ok;
  g->est_on = est_on;
}

/* Stage 4a: which models run and learn this step (canfdi_app.h, feedback). */
static void stage_gates(canfdi_app_t *app)
{
  const bool dcm_ok = IN_VALID(app, CANFDI_RX_IN_DCM_UA) && IN_VALID(app, CANFDI_RX_IN_DCM_IA) &&
                      IN_VALID(app, CANFDI_RX_IN_DCM_OMEGA);
  /* one frame carries the three (and the throttle's four): one freshness;
   * exactly one new sample (two: a frame came early, the models would see
   * two steps' change in one) */
  const bool dcm_fresh = IN_FRESH(app, CANFDI_RX_IN_DCM_OMEGA) && (IN_SAMPLES(app, CANFDI_RX_IN_DCM_OMEGA) == 1U);
  /* the throttle's models need the voltage applied (canfdi_app_set_applied) */
  const bool thr_ok = IN_VALID(app, CANFDI_RX_IN_THR_TPS1) && IN_VALID(app, CANFDI_RX_IN_THR_TPS2) &&
                      IN_VALID(app, CANFDI_RX_IN_THR_IMOT) && IN_VALID(app, CANFDI_RX_IN_THR_USUPPLY) &&
                      thr_cmd_known(app);
  const bool thr_fresh = IN_FRESH(app, CANFDI_RX_IN_THR_TPS1) && (IN_SAMPLES(app, CANFDI_RX_IN_THR_TPS1) == 1U);
  const bool thr_est = thr_ok && app->fb.mgr.thr.enable && app->vote_out.valid && !app->fb.thr_no_current;
  bool rp;
  bool re;
  gate(&app->dcm, &app->cal, dcm_ok, dcm_fresh, dcm_ok && !app->fb.dcm_sensor_bad, app->running,
       canfdi_est_dcm_has_run(&app->est_dcm), &rp, &re);
  if (rp) {
    canfdi_parity_dcm_restart(&app->parity_dcm);
  }
  if (re) {
    canfdi_est_dcm_reset(&app->est_dcm, true);
    app->dcm.est_restart = true;
  }
  gate(&app->thr, &app->cal, thr_ok, thr_fresh, thr_est, app->running, canfdi_est_thr_has_run(&app->est_thr), &rp,
       &re);
  if (rp) {
    canfdi_parity_thr_reset(&app->parity_thr);
  }
  if (re) {
    canfdi_est_thr_reset(&app->est_thr, true);
  }
}

/* An estimator's step of its schedule advanced with the slot, without a
 * division (canfdi_app_power.c sets it at power-up, canfdi_app.h). */
static uint8_t est_next(uint8_t k, uint32_t decim)
{
  uint8_t n = k;
  if (k != CANFDI_APP_EST_UNLOCKED) {
    n = (((uint32_t)k + 1U) >= decim) ? 0U : (uint8_t)(k + 1U);
  }
  return n;
}

/* Stage 4b: residuals, estimates and the actuator monitors on this step's
 * samples and the commands applied over the interval that ends with them. */
static void stage_detect(canfdi_app_t *app)
{
  const canfdi_actmgr_out_t *m = &app->fb.mgr;
  canfdi_parity_dcm_in_t pd;
  canfdi_parity_thr_in_t pt;
  canfdi_actmon_in_t ai;
  stage_gates(app);
  pd.u_V_q16 = IN_VAL(app, CANFDI_RX_IN_DCM_UA);
  pd.i_A_q16 = IN_VAL(app, CANFDI_RX_IN_DCM_IA);
  pd.w_rad_s_q16 = IN_VAL(app, CANFDI_RX_IN_DCM_OMEGA);
  pd.load_Nm_q16 = load_known_q16(app);
  canfdi_est_dcm_set_load_offset(&app->est_dcm, canfdi_sub_s32_sat(pd.load_Nm_q16, app->cal.load_nom_Nm_q16));
  if (app->dcm.in_ok) {
    (void)canfdi_parity_dcm_step(&app->parity_dcm, &pd);
  }
  if (app->dcm.est_on) {
    if (app->est_k[0] != CANFDI_APP_EST_UNLOCKED) {
      canfdi_est_dcm_align(&app->est_dcm, app->est_k[0]);
    }
    canfdi_est_dcm_step(&app->est_dcm, pd.u_V_q16, pd.i_A_q16, pd.w_rad_s_q16);
  }
  pt.tps1_V_q16 = IN_VAL(app, CANFDI_RX_IN_THR_TPS1);
  pt.tps2_V_q16 = IN_VAL(app, CANFDI_RX_IN_THR_TPS2);
  pt.i_A_q16 = IN_VAL(app, CANFDI_RX_IN_THR_IMOT);
  pt.u_V_q16 = m->thr.u_cmd_V_q16;
  pt.supply_V_q16 = IN_VAL(app, CANFDI_RX_IN_THR_USUPPLY);
  pt.enabled = m->thr.enable;
  if (app->thr.in_ok) {
    (void)canfdi_parity_thr_step(&app->parity_thr, &pt);
  }
  if (app->thr.est_on) {
    if (app->est_k[1] != CANFDI_APP_EST_UNLOCKED) {
      canfdi_est_thr_align(&app->est_thr, app->est_k[1]);
    }
    canfdi_est_thr_step(&app->est_thr, pt.u_V_q16, pt.i_A_q16, app->vote_out.angle_rad_q16);
  }
  ai.thr_angle_rad_q16 = app->vote_out.angle_rad_q16;
  ai.thr_ref_rad_q16 = app->ctrl_thr.out.angle_ref_rad_q16;
  ai.thr_angle_valid = app->vote_out.valid && thr_ref_known(app);
  ai.thr_i_A_q16 = IN_VAL(app, CANFDI_RX_IN_THR_IMOT);
  ai.thr_i_valid = IN_VALID(app, CANFDI_RX_IN_THR_IMOT);
  ai.thr_enabled = m->thr.enable;
  ai.thr_u_cmd_V_q16 = m->thr.u_cmd_V_q16;
  ai.dcm_ua_V_q16 = IN_VAL(app, CANFDI_RX_IN_DCM_UA);
  ai.dcm_ua_valid = IN_VALID(app, CANFDI_RX_IN_DCM_UA);
  ai.dcm_supply_V_q16 = IN_VAL(app, CANFDI_RX_IN_DCM_USUPPLY);
  ai.dcm_supply_valid = IN_VALID(app, CANFDI_RX_IN_DCM_USUPPLY);
  ai.dcm_enabled = m->dcm.enable;
  ai.dcm_u_cmd_V_q16 = m->dcm.u_cmd_V_q16;
  ai.dcm_bridge_settled = !m->bridge_switched && (m->detected == 0U);
  (void)canfdi_actmon_step(&app->actmon, &ai, &app->actmon_out);
}

/* Stage 5: the symptom vector every step (its filters run at 1 ms). */
static void stage_diagnose(canfdi_app_t *app)
{
  canfdi_app_sym_in_t si;
  si.parity_dcm = &app->parity_dcm;
  si.parity_thr = &app->parity_thr;
  si.dcm_in_ok = app->dcm.in_ok;
  si.dcm_fresh = app->dcm.fresh;
  si.thr_in_ok = app->thr.in_ok;
  si.est_dcm = &app->est_dcm;
  si.est_thr = &app->est_thr;
  si.dcm_est_on = app->dcm.est_on;
  si.dcm_est_restart = app->dcm.est_restart;
  app->dcm.learnt = app->dcm.learnt ||
                    (canfdi_est_dcm_arm_converged(&app->est_dcm) && canfdi_est_dcm_mech_converged(&app->est_dcm));
  if (app->dcm.learn_check == CANFDI_APP_LEARN_PENDING) {
    /* the learning check (canfdi_app.h), on the symptoms of the last run */
    const int8_t s2 = canfdi_diagnosis_symptom(&app->diagnosis, CANFDI_COMPONENT_DC_MOTOR, (uint8_t)CANFDI_SYM_DCM_R2);
    const int8_t s3 = canfdi_diagnosis_symptom(&app->diagnosis, CANFDI_COMPONENT_DC_MOTOR, (uint8_t)CANFDI_SYM_DCM_R3);
    const bool seen = (s2 != CANFDI_DIAG_SYM_UNKNOWN) || (s3 != CANFDI_DIAG_SYM_UNKNOWN);
    if (!seen) {
      app->dcm.learn_seen = 0U;
    } else if (app->dcm.learn_seen < UINT8_MAX) {
      app->dcm.learn_seen = (uint8_t)(app->dcm.learn_seen + 1U);
    } else {
      /* saturated */
    }
    const uint16_t need = (app->cal.diagnosis.sym_on_steps < (uint16_t)UINT8_MAX) ? app->cal.diagnosis.sym_on_steps
                                                                                   : (uint16_t)UINT8_MAX;
    if (app->dcm.learnt && (app->dcm.learn_seen >= need) &&
        ((canfdi_parity_dcm_out(&app->parity_dcm)->valid & (1U << CANFDI_PARITY_DCM_R1)) != 0U)) {
      app->dcm.learn_check = ((s2 == CANFDI_DIAG_SYM_POS) || (s2 == CANFDI_DIAG_SYM_NEG) ||
                              (s3 == CANFDI_DIAG_SYM_POS) || (s3 == CANFDI_DIAG_SYM_NEG))
                                 ? CANFDI_APP_LEARN_FAULT
                                 : CANFDI_APP_LEARN_CLEAN;
    }
  }
  si.dcm_learnt = app->dcm.learnt && (app->dcm.learn_check == CANFDI_APP_LEARN_CLEAN);
  si.dcm_rearm = app->dcm.rearm > 0U;
  si.thr_rearm = app->thr.rearm > 0U;
  si.thr_est_on = app->thr.est_on;
  si.load_known_Nm_q16 = load_known_q16(app);
  si.load_nom_Nm_q16 = app->cal.load_nom_Nm_q16;
  si.dcm_w_rad_s_q16 = IN_VAL(app, CANFDI_RX_IN_DCM_OMEGA);
  si.dcm_i_A_q16 = IN_VAL(app, CANFDI_RX_IN_DCM_IA);
  si.thr_u_V_q16 = app->fb.mgr.thr.u_cmd_V_q16;
  si.thr_i_A_q16 = IN_VAL(app, CANFDI_RX_IN_THR_IMOT);
  si.tps_range[0] = (uint8_t)canfdi_limit_symptom(&app->tps_range[0]);
  si.tps_range[1] = (uint8_t)canfdi_limit_symptom(&app->tps_range[1]);
  si.tps_invalid[0] = !IN_USABLE(app, CANFDI_RX_IN_THR_TPS1);
  si.tps_invalid[1] = !IN_USABLE(app, CANFDI_RX_IN_THR_TPS2);
  si.vote_isolated_mask = app->vote_out.isolated_mask;
  si.mgr_detected = app->fb.mgr.detected;
  si.actmon = &app->actmon_out;
  canfdi_app_sym_build(&app->sym_state, &si, &app->sym);
}

/* Stage 7, every step: the trouble codes from the diagnosis' verdicts of
 * its last run, the manager's findings and the communication monitors of
 * this step (events of one step: a frame rejected, a timeout). */
static void stage_dtc(canfdi_app_t *app)
{
  canfdi_dtcroute_in_t ri;
  canfdi_dtc_ff_t ff;
  ff.time_ms = canfdi_uptime_ms(&app->uptime);
  ff.omega_q16 = IN_VAL(app, CANFDI_RX_IN_DCM_OMEGA);
  ff.ia_q16 = IN_VAL(app, CANFDI_RX_IN_DCM_IA);
  ff.ua_q16 = IN_VAL(app, CANFDI_RX_IN_DCM_UA);
  ff.thr_angle_q16 = app->vote_out.angle_rad_q16;
  ff.supply_q16 = IN_VAL(app, CANFDI_RX_IN_DCM_USUPPLY);
  ff.deg_dcm = app->fb.mgr.dcm_state;
  ff.deg_thr = app->fb.mgr.thr_state;
  ri.failed = canfdi_diagnosis_failed_mask(&app->diagnosis);
  ri.passed = canfdi_diagnosis_passed_mask(&app->diagnosis);
  ri.mgr_detected = app->fb.mgr.detected;
  ri.corr_not_isolated = canfdi_diagnosis_corr_not_isolated(&app->diagnosis);
  ri.corr_tested = canfdi_diagnosis_symptom(&app->diagnosis, CANFDI_COMPONENT_THROTTLE,
                                            (uint8_t)CANFDI_SYM_THR_CORR) != CANFDI_DIAG_SYM_UNKNOWN;
  ri.com = &app->rx.report;
  ri.ff = &ff;
  (void)canfdi_dtcroute_step(&app->dtcroute, &app->dtc, &ri);
}

/* Stage 8: the actuator manager; its output is this step's command and
 * the next step's feedback. */
static void stage_manage(canfdi_app_t *app, int32_t u_dcm, int32_t u_thr)
{
  canfdi_actmgr_in_t mi;
  mi.dcm_u_ctrl_V_q16 = u_dcm;
  mi.dcm_ua_V_q16 = IN_VAL(app, CANFDI_RX_IN_DCM_UA);
  mi.dcm_supply_V_q16 = IN_VAL(app, CANFDI_RX_IN_DCM_USUPPLY);
  mi.dcm_ua_valid = IN_VALID(app, CANFDI_RX_IN_DCM_UA) && canfdi_rx_fresh(&app->rx, CANFDI_RX_IN_DCM_UA);
  mi.dcm_supply_valid = IN_VALID(app, CANFDI_RX_IN_DCM_USUPPLY);
  mi.thr_u_ctrl_V_q16 = u_thr;
  mi.faults = canfdi_dtcroute_manager_faults(&app->dtcroute, &app->dtc, canfdi_diagnosis_failed_mask(&app->diagnosis),
                                             canfdi_diagnosis_passed_mask(&app->diagnosis));
  mi.fail_silent = false;
  mi.dcm_hold_off = !app->dcm.started;
  mi.thr_hold_off = !app->thr.started || app->uds_act.thr_release; /* the spring check releases */
  mi.now_ms = canfdi_uptime_ms(&app->uptime);
  (void)canfdi_actmgr_step(&app->actmgr, &mi, &app->vote_out, &app->fb.mgr);
  app->fb.faults = mi.faults;
}

/* The verdicts the next step obeys (canfdi_app_fb_t). */
static void update_feedback(canfdi_app_t *app)
{
  const int8_t arm = canfdi_diagnosis_symptom(&app->diagnosis, CANFDI_COMPONENT_THROTTLE,
                                              (uint8_t)CANFDI_SYM_THR_ARM);
  const int8_t uac = canfdi_diagnosis_symptom(&app->diagnosis, CANFDI_COMPONENT_DC_MOTOR,
                                              (uint8_t)CANFDI_DIAG_CH_DCM_UAC);
  app->fb.thr_arm_symptom = (arm == CANFDI_DIAG_SYM_POS) || (arm == CANFDI_DIAG_SYM_NEG);
  const uint8_t iso = canfdi_diagnosis_isolated(&app->diagnosis, CANFDI_COMPONENT_DC_MOTOR, NULL);
  const uint32_t sensor_faults = CANFDI_FAULT_BIT(CANFDI_FAULT_DCM_UA_SENSOR_OFFSET) |
                                 CANFDI_FAULT_BIT(CANFDI_FAULT_DCM_IA_SENSOR_OFFSET) |
                                 CANFDI_FAULT_BIT(CANFDI_FAULT_DCM_SPEED_SENSOR_GAIN) |
                                 CANFDI_FAULT_BIT(CANFDI_FAULT_DCM_SPEED_SENSOR_OFFSET);
  /* the estimator learns only from sensors not known bad: a U_A that
   * disagrees with its command, a speed step the torque cannot give, a
   * sensor fault isolated now or acted on by the manager (its estimates
   * would be learnt from the faulty signal and outlive the fault) */
  app->fb.dcm_sensor_bad = (uac == CANFDI_DIAG_SYM_POS) || (uac == CANFDI_DIAG_SYM_NEG) ||
                           ((app->sym.flags & CANFDI_SYM_F_DCM_W_JUMP) != 0U) ||
                           ((iso != 0U) && ((CANFDI_FAULT_BIT(iso) & sensor_faults) != 0U)) ||
                           ((app->fb.faults & sensor_faults) != 0U);
  app->fb.thr_no_current = app->actmon_out.thr_no_current;
}

/* The self-diagnostics from the modules' counters (all saturating). */
static void update_diag(canfdi_app_t *app)
{
  const canfdi_rx_diag_t *r = &app->rx.diag;
  uint32_t rej = 0U;
  uint32_t i;
  for (i = 0U; i < CANFDI_RX_F_COUNT; i++) {
    rej = canfdi_count_sum(rej, canfdi_count_sum(canfdi_count_sum(r->length_err[i], r->crc_err[i]),
                                                 canfdi_count_sum(r->counter_err[i], r->implausible[i])));
  }
  app->diag.frames_rejected = rej;
  app->diag.frames_unknown = r->unknown_id;
  app->diag.saturations = canfdi_count_sum(canfdi_count_sum(canfdi_ctrl_dcm_diag(&app->ctrl_dcm)->u_limited,
                                                            canfdi_ctrl_thr_diag(&app->ctrl_thr)->u_limited),
                                           app->tx.diag.saturations);
  app->diag.estimator_resets =
      canfdi_count_sum(canfdi_count_sum(canfdi_est_dcm_diag(&app->est_dcm)->resets,
                                        canfdi_est_thr_diag(&app->est_thr)->resets),
                       canfdi_count_sum(canfdi_parity_dcm_diag(&app->parity_dcm)->resets,
                                        canfdi_parity_thr_diag(&app->parity_thr)->resets));
  app->diag.dtc_reports_rejected = canfdi_dtcroute_diag(&app->dtcroute).reports_rejected;
}

/* Stage 9: the frames of this step. */
static int32_t stage_outputs(canfdi_app_t *app, canfdi_tx_frame_t *out)
{
  canfdi_app_out_src_t src;
  int32_t n;
  update_diag(app);
  src.mgr = &app->fb.mgr;
  src.parity_dcm = &app->parity_dcm;
  src.parity_thr = &app->parity_thr;
  src.est_dcm = &app->est_dcm;
  src.est_thr = &app->est_thr;
  src.diagnosis = &app->diagnosis;
  src.dtc = &app->dtc;
  src.faults = app->fb.faults;
  src.deadline_misses = app->diag.deadline_misses;
  src.self_diag.frames_rejected = app->diag.frames_rejected;
  src.self_diag.frames_unknown = app->diag.frames_unknown;
  src.self_diag.saturations = app->diag.saturations;
  src.self_diag.estimator_resets = app->diag.estimator_resets;
  src.self_diag.dtc_reports_rejected = app->diag.dtc_reports_rejected;
  n = canfdi_app_out_step(&app->out, &app->tx, &src, out);
  app->diag.frames_sent = app->out.diag.frames_sent;
  return n;
}

int32_t canfdi_app_step(canfdi_app_t *app, uint32_t now_us, canfdi_tx_frame_t *out)
{
  int32_t rc = -CANFDI_EINVAL;
  if ((app != NULL) && app->initialised && (out != NULL)) {
    int32_t u_dcm = 0;
    int32_t u_thr = 0;
    (void)canfdi_uptime_advance(&app->uptime, now_us);
    /* 1. input supervision; the nominal load stands in for a missing load */
    (void)canfdi_rx_set_estimate(&app->rx, CANFDI_RX_IN_SP_DCM_LOAD, app->cal.load_nom_Nm_q16);
    (void)canfdi_rx_step(&app->rx, now_us);
    canfdi_app_uds_apply(app);         /* the tester's estimator resets */
    stage_vote(app);                   /* 2. */
    stage_control(app, &u_dcm, &u_thr); /* 3. */
    stage_detect(app);                 /* 4. */
    stage_diagnose(app);               /* 5. */
    /* 6. each component's model rules matched in its slot of the rate
     * schedule (canfdi_app.h); the hard rules in every step, a
     * component's model verdicts held between its full steps */
    {
      uint32_t matched = 0U;
      if (app->slot == CANFDI_APP_SLOT_DIAG) {
        matched |= (uint32_t)1U << CANFDI_DIAG_COMP_DCM;
      }
      if (app->slot == app->slot_diag_thr) {
        matched |= (uint32_t)1U << CANFDI_DIAG_COMP_THR;
      }
      canfdi_diagnosis_step_comp(&app->diagnosis, &app->sym, NULL, matched);
    }
    stage_dtc(app);                    /* 7. */
    stage_manage(app, u_dcm, u_thr);   /* 8. */
    update_feedback(app);
    rc = stage_outputs(app, out);      /* 9. */
    rc = canfdi_app_uds_stage(app, out, rc); /* 10. the diagnostic server */
    canfdi_count_inc(&app->diag.steps);
    app->slot = (uint8_t)(app->slot + 1U);
    if (app->slot >= app->cal.diag_period_steps) {
      app->slot = 0U;
    }
    app->est_k[0] = est_next(app->est_k[0], app->est_dcm.cfg.decim);
    app->est_k[1] = est_next(app->est_k[1], app->est_thr.cfg.decim);
    app->applied_set = false; /* set_applied acts on one step */
    app->running = true;
  }
  return rc;
}
