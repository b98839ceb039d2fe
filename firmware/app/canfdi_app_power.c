/*
 * canfdi_app_power.c — the application's power and operation-cycle
 * sequence (see canfdi_app.h): cold start with or without a stored DTC
 * image, power-down with the image to store, a new operation cycle, a
 * tester's clear, and the NVM image: a 4-byte header (CANFDI_APP_IMAGE_TAG,
 * CANFDI_APP_IMAGE_VERSION, the SecurityAccess attempt counter, 0) before
 * the DTC memory's image. An image that starts with a DTC image version
 * (1 or 2: stored by a firmware without the header) is the DTC memory
 * alone and loads with no failed attempts. The Linux port (port/linux/canfdi_ecu_nvm.c) and the SIL
 * rig (tests/sil/canfdi_sil.c) both go through these functions, so a
 * power cycle is the same sequence everywhere.
 */
#include "app/canfdi_app.h"

/* A count of 1 ms steps as a count of calls every period steps (rounded
 * up, at least 1): the isolation's consecutive wins, calibrated in 1 ms
 * steps, at the rate of the full diagnosis steps (the symptoms' and flags'
 * persistence runs in every step). */
static uint16_t per_period(uint16_t steps, uint8_t period)
{
  const uint32_t n = ((uint32_t)steps + (uint32_t)period - 1U) / (uint32_t)period;
  return (uint16_t)((n < 1U) ? 1U : n);
}

/* An estimator's step of its schedule in slot 0 (canfdi_app.h, the
 * estimators' slots): k mod decim = 0 exactly on the slots with
 * slot mod decim = offset; unlocked when decim does not divide the period
 * (the intervals between its updates would vary). decim 1..100. */
static uint8_t est_k0(uint32_t period, uint32_t decim, uint32_t offset)
{
  uint8_t k = (uint8_t)CANFDI_APP_EST_UNLOCKED;
  if ((period % decim) == 0U) {
    k = (uint8_t)((decim - (offset % decim)) % decim);
  }
  return k;
}

/* The throttle's matching slot (canfdi_app.h, CANFDI_APP_SLOT_DIAG_THR_*):
 * from period * 2 / 5 on, the first slot that is not the DC motor's
 * matching slot and holds no update of a locked estimator (the DC
 * motor's two, the throttle's other than its electrical one); the DC
 * motor's slot when there is none (periods 1 and 2). */
static uint8_t thr_match_slot(uint32_t period, uint32_t dcm_decim, uint32_t thr_decim)
{
  const uint32_t s0 = (period * CANFDI_APP_SLOT_DIAG_THR_NUM) / CANFDI_APP_SLOT_DIAG_THR_DEN;
  const bool dcm_locked = ((period % dcm_decim) == 0U);
  const bool thr_locked = ((period % thr_decim) == 0U);
  uint8_t slot = (uint8_t)CANFDI_APP_SLOT_DIAG;
  uint32_t i;
  for (i = 0U; (i < period) && (slot == (uint8_t)CANFDI_APP_SLOT_DIAG); i++) {
    const uint32_t s = (s0 + i) % period;
    const uint32_t kd = s % dcm_decim;
    const bool dcm_busy = dcm_locked && ((kd == (CANFDI_APP_SLOT_EST_DCM % dcm_decim)) ||
                                         (kd == ((CANFDI_APP_SLOT_EST_DCM + 1U) % dcm_decim)));
    const bool thr_busy = thr_locked && ((s % thr_decim) != (CANFDI_APP_SLOT_EST_THR % thr_decim));
    if ((s != CANFDI_APP_SLOT_DIAG) && !dcm_busy && !thr_busy) {
      slot = (uint8_t)s;
    }
  }
  return slot;
}

static int32_t init_modules(canfdi_app_t *app, uint32_t now_us)
{
  canfdi_app_cal_t *c = &app->cal;
  canfdi_diagnosis_cfg_t dc = c->diagnosis;
  const uint8_t period = c->diag_period_steps;
  int32_t rc = CANFDI_OK;
  if ((period < 1U) || (period > CANFDI_APP_FRAME_SLOTS)) {
    rc = -CANFDI_EINVAL;
  } else {
    dc.isolate_steps = per_period(dc.isolate_steps, period);
  }
  app->slot = 0U;
  if ((rc == CANFDI_OK) && ((canfdi_rx_init(&app->rx, &c->rx, now_us) != CANFDI_OK) || (canfdi_tx_init(&app->tx) != CANFDI_OK) ||
      (canfdi_ctrl_dcm_init(&app->ctrl_dcm, &c->ctrl_dcm) != CANFDI_OK) ||
      (canfdi_ctrl_thr_init(&app->ctrl_thr, &c->ctrl_thr) != CANFDI_OK) ||
      (canfdi_excite_init(&app->excite_dcm, &c->excite_dcm) != CANFDI_OK) ||
      (canfdi_excite_init(&app->excite_thr, &c->excite_thr) != CANFDI_OK) ||
      (canfdi_app_test_init(&app->test, &c->test) != CANFDI_OK) ||
      (canfdi_parity_dcm_init(&app->parity_dcm, &c->parity_dcm) != CANFDI_OK) ||
      (canfdi_parity_thr_init(&app->parity_thr, &c->parity_thr) != CANFDI_OK) ||
      (canfdi_est_dcm_init(&app->est_dcm, &c->est_dcm) != CANFDI_OK) ||
      (canfdi_est_thr_init(&app->est_thr, &c->est_thr) != CANFDI_OK) ||
      (canfdi_limit_init(&app->tps_range[0], &c->tps_range) != CANFDI_OK) ||
      (canfdi_limit_init(&app->tps_range[1], &c->tps_range) != CANFDI_OK) ||
      (canfdi_vote_init(&app->vote, &c->vote) != CANFDI_OK) ||
      (canfdi_actmon_init(&app->actmon, &c->actmon) != CANFDI_OK) ||
      (canfdi_app_sym_init(&app->sym_state, &c->sym) != CANFDI_OK) ||
      (canfdi_actmgr_init(&app->actmgr, &c->actmgr) != CANFDI_OK) ||
      (canfdi_diagnosis_init(&app->diagnosis, &dc) != CANFDI_OK) ||
      (canfdi_dtc_init(&app->dtc, canfdi_dtc_defaults, (uint8_t)CANFDI_DTC_COUNT) != CANFDI_OK) ||
      (canfdi_dtcroute_init(&app->dtcroute, &c->dtcroute, &app->dtc) != CANFDI_OK) ||
      (canfdi_uds_init(&app->uds, &c->uds, 0U, now_us) != CANFDI_OK) ||
      (canfdi_dtc_cycle_start(&app->dtc) != CANFDI_OK))) {
    rc = -CANFDI_EINVAL;
  }
  if (rc == CANFDI_OK) {
    app->est_k[0] = est_k0(period, app->est_dcm.cfg.decim, CANFDI_APP_SLOT_EST_DCM);
    app->est_k[1] = est_k0(period, app->est_thr.cfg.decim, CANFDI_APP_SLOT_EST_THR);
    app->slot_diag_thr = thr_match_slot(period, app->est_dcm.cfg.decim, app->est_thr.cfg.decim);
  }
  return rc;
}

int32_t canfdi_app_init(canfdi_app_t *app, const canfdi_app_cal_t *cal, uint32_t now_us)
{
  int32_t rc = -CANFDI_EINVAL;
  if ((app != NULL) && (cal != NULL)) {
    app->initialised = false;
    app->cal = *cal;
    /* one characteristic per sensor, whatever the module fields hold */
    app->cal.vote.tps1 = cal->tps1;
    app->cal.vote.tps2 = cal->tps2;
    app->cal.parity_thr.tps1 = cal->tps1;
    app->cal.parity_thr.tps2 = cal->tps2;
    rc = init_modules(app, now_us);
    if (rc == CANFDI_OK) {
      canfdi_excite_enable(&app->excite_dcm, false);
      canfdi_excite_enable(&app->excite_thr, false);
      canfdi_app_out_init(&app->out, &app->dtc);
      canfdi_uptime_init(&app->uptime, now_us);
      app->vote_out = (canfdi_vote_out_t){0};
      app->actmon_out = (canfdi_actmon_out_t){0};
      app->sym = (canfdi_symptoms_t){0};
      app->dcm = (canfdi_app_gate_t){0};
      app->thr = (canfdi_app_gate_t){0};
      app->fb = (canfdi_app_fb_t){0};
      app->applied = (canfdi_app_applied_t){0};
      app->applied_set = false;
      app->diag = (canfdi_app_diag_t){0};
      app->uds_act = (canfdi_uds_act_t){0};
      app->running = false;
      app->reset_requested = false;
      app->initialised = true;
    }
  }
  return rc;
}

int32_t canfdi_app_power_up(canfdi_app_t *app, const canfdi_app_cal_t *cal, uint32_t now_us,
                            const uint8_t *image, uint32_t len)
{
  int32_t rc = canfdi_app_init(app, cal, now_us);
  if ((rc == CANFDI_OK) && (image != NULL) && (len > 0U)) {
    const bool framed = image[0] == (uint8_t)CANFDI_APP_IMAGE_TAG;
    const bool header_ok = (len > CANFDI_APP_IMAGE_HEADER_BYTES) && (image[1] == (uint8_t)CANFDI_APP_IMAGE_VERSION) &&
                           (image[3] == 0U);
    /* the fresh memory's cycle had no report: ending it changes nothing */
    (void)canfdi_dtc_cycle_end(&app->dtc);
    if (framed && !header_ok) {
      rc = CANFDI_APP_IMAGE_REJECTED;
    } else if (canfdi_dtc_deserialize(&app->dtc, framed ? &image[CANFDI_APP_IMAGE_HEADER_BYTES] : image,
                                      framed ? (len - CANFDI_APP_IMAGE_HEADER_BYTES) : len) != CANFDI_OK) {
      rc = CANFDI_APP_IMAGE_REJECTED;
    } else {
      /* the memory loaded */
    }
    if (framed && header_ok) {
      /* the attempt counter survives even a rejected DTC image */
      (void)canfdi_uds_init(&app->uds, &app->cal.uds, image[2], now_us);
    }
    (void)canfdi_dtc_cycle_start(&app->dtc);
  }
  return rc;
}

/* The header, then the DTC memory's image. */
static int32_t write_image(const canfdi_app_t *app, uint8_t *image, uint32_t cap)
{
  int32_t rc = -CANFDI_ERANGE;
  if (cap > CANFDI_APP_IMAGE_HEADER_BYTES) {
    rc = canfdi_dtc_serialize(&app->dtc, &image[CANFDI_APP_IMAGE_HEADER_BYTES], cap - CANFDI_APP_IMAGE_HEADER_BYTES);
    if (rc >= 0) {
      image[0] = (uint8_t)CANFDI_APP_IMAGE_TAG;
      image[1] = (uint8_t)CANFDI_APP_IMAGE_VERSION;
      image[2] = canfdi_uds_sec_attempts(&app->uds);
      image[3] = 0U;
      rc += (int32_t)CANFDI_APP_IMAGE_HEADER_BYTES;
    }
  }
  return rc;
}

int32_t canfdi_app_power_down(canfdi_app_t *app, uint8_t *image, uint32_t cap)
{
  int32_t rc = -CANFDI_EINVAL;
  if ((app != NULL) && app->initialised && (image != NULL)) {
    (void)canfdi_dtc_cycle_end(&app->dtc);
    rc = write_image(app, image, cap);
  }
  return rc;
}

int32_t canfdi_app_nvm_image(const canfdi_app_t *app, uint8_t *image, uint32_t cap)
{
  return ((app != NULL) && app->initialised && (image != NULL)) ? write_image(app, image, cap) : -CANFDI_EINVAL;
}

uint32_t canfdi_app_nvm_changes(const canfdi_app_t *app)
{
  return (app != NULL) ? (app->dtc.changes + canfdi_uds_nvm_changes(&app->uds)) : 0U;
}

int32_t canfdi_app_new_cycle(canfdi_app_t *app)
{
  int32_t rc = -CANFDI_EINVAL;
  if ((app != NULL) && app->initialised && (canfdi_dtc_cycle_end(&app->dtc) == CANFDI_OK)) {
    rc = canfdi_dtc_cycle_start(&app->dtc);
  }
  return rc;
}

int32_t canfdi_app_clear_dtc(canfdi_app_t *app, uint32_t group)
{
  return ((app != NULL) && app->initialised) ? canfdi_dtc_clear(&app->dtc, group) : -CANFDI_EINVAL;
}
