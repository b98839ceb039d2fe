/*
 * canfdi_app_uds.c — the application's side of the diagnostic server; the
 * manual is the header.
 */
#include "app/canfdi_app_uds.h"

#include "comm/gen/canfdi_msg.h"

static void fill_src(const canfdi_app_t *app, canfdi_uds_src_t *s)
{
  const canfdi_app_diag_t *d = &app->diag;
  s->rx = &app->rx;
  s->vote = &app->vote_out;
  s->mgr = &app->fb.mgr;
  s->est_dcm = &app->est_dcm;
  s->est_thr = &app->est_thr;
  s->parity_dcm = &app->parity_dcm;
  s->parity_thr = &app->parity_thr;
  s->speed_ref_rad_s_q16 = app->ctrl_dcm.out.speed_ref_rad_s_q16;
  s->angle_ref_rad_q16 = app->ctrl_thr.out.angle_ref_rad_q16;
  s->load_Nm_q16 = canfdi_rx_usable(&app->rx, CANFDI_RX_IN_SP_DCM_LOAD)
                       ? canfdi_rx_value(&app->rx, CANFDI_RX_IN_SP_DCM_LOAD)
                       : app->cal.load_nom_Nm_q16;
  s->uptime_ms = canfdi_uptime_ms(&app->uptime);
  s->counters[CANFDI_UDS_CNT_STEPS] = d->steps;
  s->counters[CANFDI_UDS_CNT_DEADLINE_MISSES] = d->deadline_misses;
  s->counters[CANFDI_UDS_CNT_FRAMES_REJECTED] = d->frames_rejected;
  s->counters[CANFDI_UDS_CNT_FRAMES_UNKNOWN] = d->frames_unknown;
  s->counters[CANFDI_UDS_CNT_FRAMES_SENT] = d->frames_sent;
  s->counters[CANFDI_UDS_CNT_SATURATIONS] = d->saturations;
  s->counters[CANFDI_UDS_CNT_ESTIMATOR_RESETS] = d->estimator_resets;
  s->counters[CANFDI_UDS_CNT_DTC_REPORTS_REJECTED] = d->dtc_reports_rejected;
}

/* While the monitoring frames are off: keep the actuator frames only. */
static int32_t keep_actuators(canfdi_tx_frame_t *out, int32_t n)
{
  int32_t k = 0;
  for (int32_t i = 0; i < n; i++) {
    if ((out[i].id == CANFDI_MSG_DCM_ACTUATOR_FRAME_ID) || (out[i].id == CANFDI_MSG_THR_ACTUATOR_FRAME_ID)) {
      out[k] = out[i];
      k++;
    }
  }
  return k;
}

int32_t canfdi_app_uds_stage(canfdi_app_t *app, canfdi_tx_frame_t *out, int32_t n)
{
  int32_t m = n;
  canfdi_uds_src_t src;
  uint8_t frame[CANFDI_CFG_ISOTP_FRAME_BYTES];
  fill_src(app, &src);
  if ((m > 0) && app->uds_act.tx_silent) {
    m = keep_actuators(out, m);
  }
  if ((canfdi_uds_step(&app->uds, &app->dtc, &src, &app->uds_act, frame) == 1) && (m >= 0) &&
      (m < (int32_t)CANFDI_APP_MAX_TX) && (canfdi_tx_encode_uds_resp(&app->tx, frame, &out[m]) == CANFDI_OK)) {
    m++;
  }
  app->reset_requested = app->reset_requested || app->uds_act.ecu_reset;
  return m;
}

void canfdi_app_uds_apply(canfdi_app_t *app)
{
  if ((app->uds_act.est_reset & 1U) != 0U) {
    canfdi_est_dcm_reset(&app->est_dcm, false);
  }
  if ((app->uds_act.est_reset & 2U) != 0U) {
    canfdi_est_thr_reset(&app->est_thr, false);
  }
  app->uds_act.est_reset = 0U;
}
