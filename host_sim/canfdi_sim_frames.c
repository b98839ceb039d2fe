/* canfdi_sim_frames.c — see canfdi_sim_frames.h. */
#include "canfdi_sim_frames.h"

#include <math.h>
#include <string.h>

#include "core/canfdi_common.h"
#include "gen/canfdi_sim_msg.h"

/* The E2E layout the codec must agree with. */
CANFDI_STATIC_ASSERT(CANFDI_SIM_MSG_DCM_SENSOR_LENGTH == CANFDI_E2E_FRAME_LEN, dcm_len);
CANFDI_STATIC_ASSERT(CANFDI_SIM_MSG_THR_SENSOR_LENGTH == CANFDI_E2E_FRAME_LEN, thr_len);
/* The plant's enumerations are the DBC's value tables. */
CANFDI_STATIC_ASSERT(CANFDI_SIM_MSG_SIM_PLANT_STATUS_PST_FAULT_MODE_ABRUPT_CHOICE == CANFDI_SIM_MODE_ABRUPT &&
                         CANFDI_SIM_MSG_SIM_PLANT_STATUS_PST_FAULT_MODE_INCIPIENT_CHOICE ==
                             CANFDI_SIM_MODE_INCIPIENT &&
                         CANFDI_SIM_MSG_SIM_PLANT_STATUS_PST_FAULT_MODE_INTERMITTENT_CHOICE ==
                             CANFDI_SIM_MODE_INTERMITTENT,
                     fault_modes_match_dbc);
CANFDI_STATIC_ASSERT(CANFDI_SIM_MSG_SIM_PLANT_STATUS_PST_ACTIVE_BRIDGE_NONE_CHOICE == CANFDI_SIM_BRIDGE_NONE &&
                         CANFDI_SIM_MSG_SIM_PLANT_STATUS_PST_ACTIVE_BRIDGE_BRIDGE_A_CHOICE ==
                             CANFDI_SIM_BRIDGE_A &&
                         CANFDI_SIM_MSG_SIM_PLANT_STATUS_PST_ACTIVE_BRIDGE_BRIDGE_B_CHOICE ==
                             CANFDI_SIM_BRIDGE_B,
                     bridges_match_dbc);
CANFDI_STATIC_ASSERT(CANFDI_SIM_MSG_SIM_PLANT_STATUS_PST_SIM_MODE_LOCKSTEP_CHOICE == CANFDI_SIM_MODE_LOCKSTEP &&
                         CANFDI_SIM_MSG_SIM_PLANT_STATUS_PST_SIM_MODE_REALTIME_CHOICE ==
                             CANFDI_SIM_MODE_REALTIME &&
                         CANFDI_SIM_MSG_SIM_PLANT_STATUS_PST_SIM_MODE_OFFLINE_CHOICE ==
                             CANFDI_SIM_MODE_OFFLINE,
                     sim_modes_match_dbc);

/* The generated encoders truncate (v - offset) / scale towards zero. A value
 * that lies exactly on a DBC grid point may be computed a hair below it and
 * lose one raw step; the nudge of ~1e-9 relative puts it back on the point.
 * Values between grid points are still truncated (error < 1 DBC LSB). */
static double nudge(double v)
{
  return v + (1e-9 * (1.0 + fabs(v)));
}

void canfdi_sim_frames_init(canfdi_sim_frames_t *f, uint8_t sim_mode)
{
  unsigned i;
  canfdi_e2e_tx_init(&f->tx[CANFDI_SIM_FRAME_DCM], (uint16_t)CANFDI_SIM_MSG_DCM_SENSOR_FRAME_ID);
  canfdi_e2e_tx_init(&f->tx[CANFDI_SIM_FRAME_THR], (uint16_t)CANFDI_SIM_MSG_THR_SENSOR_FRAME_ID);
  for (i = 0U; i < CANFDI_SIM_N_FRAMES; i++) {
    f->last_counter[i] = 0U;
  }
  f->sim_mode = sim_mode;
  f->diag.sent = 0U;
  f->diag.dropped = 0U;
  f->diag.corrupted = 0U;
}

/* Protects a packed sensor frame and applies the frame faults. Returns
 * false if the frame must not be sent. */
static bool finish_sensor(canfdi_sim_frames_t *f, unsigned k, const canfdi_sim_frame_fx_t *fx,
                          canfdi_sim_frame_t *fr)
{
  canfdi_e2e_tx_t *tx = &f->tx[k];
  bool send = true;
  if (fx->drop) {
    f->diag.dropped++;
    send = false;
  } else {
    const uint8_t next = tx->counter;
    if (fx->bad_counter) {
      tx->counter = f->last_counter[k];
    }
    (void)canfdi_e2e_protect(tx, fr->data, CANFDI_E2E_FRAME_LEN);
    f->last_counter[k] = (uint8_t)(fr->data[CANFDI_E2E_COUNTER_BYTE] & CANFDI_E2E_COUNTER_MASK);
    if (fx->bad_counter) {
      tx->counter = (uint8_t)((next + 1U) % CANFDI_E2E_COUNTER_MOD);
    }
    if (fx->bad_crc) {
      fr->data[CANFDI_E2E_CRC_BYTE] ^= 0xFFU;
    }
    if (fx->bad_dlc) {
      fr->dlc = (uint8_t)(CANFDI_E2E_FRAME_LEN - 1U);
    }
    if (fx->bad_counter || fx->bad_crc || fx->bad_dlc || fx->implausible) {
      f->diag.corrupted++;
    }
  }
  return send;
}

static bool build_dcm(canfdi_sim_frames_t *f, const canfdi_sim_t *sim, canfdi_sim_frame_t *fr)
{
  const canfdi_sim_frame_fx_t *fx = &sim->fx.frame[CANFDI_SIM_FRAME_DCM];
  const double *v = sim->meas.value;
  struct canfdi_sim_msg_dcm_sensor_t m;
  (void)canfdi_sim_msg_dcm_sensor_init(&m);
  if (fx->implausible) {
    /* The codec masks each raw value to its signal width: all ones. */
    m.dcm_ua = UINT16_MAX;
    m.dcm_ia = UINT16_MAX;
    m.dcm_omega = UINT16_MAX;
    m.dcm_usupply = UINT16_MAX;
  } else {
    m.dcm_ua = canfdi_sim_msg_dcm_sensor_dcm_ua_encode(nudge(v[CANFDI_SIM_S_DCM_UA]));
    m.dcm_ia = canfdi_sim_msg_dcm_sensor_dcm_ia_encode(nudge(v[CANFDI_SIM_S_DCM_IA]));
    m.dcm_omega = canfdi_sim_msg_dcm_sensor_dcm_omega_encode(nudge(v[CANFDI_SIM_S_DCM_SPEED]));
    m.dcm_usupply = canfdi_sim_msg_dcm_sensor_dcm_usupply_encode(nudge(v[CANFDI_SIM_S_DCM_SUPPLY]));
  }
  fr->id = CANFDI_SIM_MSG_DCM_SENSOR_FRAME_ID;
  fr->dlc = (uint8_t)canfdi_sim_msg_dcm_sensor_pack(fr->data, &m, sizeof fr->data);
  return finish_sensor(f, CANFDI_SIM_FRAME_DCM, fx, fr);
}

static bool build_thr(canfdi_sim_frames_t *f, const canfdi_sim_t *sim, canfdi_sim_frame_t *fr)
{
  const canfdi_sim_frame_fx_t *fx = &sim->fx.frame[CANFDI_SIM_FRAME_THR];
  const double *v = sim->meas.value;
  struct canfdi_sim_msg_thr_sensor_t m;
  (void)canfdi_sim_msg_thr_sensor_init(&m);
  if (fx->implausible) {
    m.thr_tps1 = UINT16_MAX;
    m.thr_tps2 = UINT16_MAX;
    m.thr_imot = UINT16_MAX;
    m.thr_usupply = UINT16_MAX;
  } else {
    m.thr_tps1 = canfdi_sim_msg_thr_sensor_thr_tps1_encode(nudge(v[CANFDI_SIM_S_THR_TPS1]));
    m.thr_tps2 = canfdi_sim_msg_thr_sensor_thr_tps2_encode(nudge(v[CANFDI_SIM_S_THR_TPS2]));
    m.thr_imot = canfdi_sim_msg_thr_sensor_thr_imot_encode(nudge(v[CANFDI_SIM_S_THR_I]));
    m.thr_usupply = canfdi_sim_msg_thr_sensor_thr_usupply_encode(nudge(v[CANFDI_SIM_S_THR_SUPPLY]));
  }
  fr->id = CANFDI_SIM_MSG_THR_SENSOR_FRAME_ID;
  fr->dlc = (uint8_t)canfdi_sim_msg_thr_sensor_pack(fr->data, &m, sizeof fr->data);
  return finish_sensor(f, CANFDI_SIM_FRAME_THR, fx, fr);
}

static void build_status(const canfdi_sim_frames_t *f, const canfdi_sim_t *sim,
                         const canfdi_sim_in_t *act, canfdi_sim_frame_t *fr)
{
  struct canfdi_sim_msg_sim_plant_status_t m;
  const int64_t t_us = canfdi_sim_time_us(sim);
  const canfdi_sim_fault_spec_t *shown = NULL;
  size_t i;
  double temp = sim->dcm.temp_C;

  for (i = 0U; (i < sim->n_faults) && (shown == NULL); i++) {
    if (canfdi_sim_fault_shape(&sim->faults[i], t_us) > 0.0) {
      shown = &sim->faults[i];
    }
  }
  if ((shown == NULL) && (sim->n_faults > 0U)) {
    shown = &sim->faults[0];
  }
  (void)canfdi_sim_msg_sim_plant_status_init(&m);
  if (shown != NULL) {
    m.pst_active_fault_id = shown->id;
    m.pst_fault_mode = shown->mode;
    m.pst_fault_active = (canfdi_sim_fault_shape(shown, t_us) > 0.0) ? 1U : 0U;
  }
  m.pst_thr_limp_home = (!act->thr.enable || sim->fx.thr.motor_open) ? 1U : 0U;
  m.pst_active_bridge = act->dcm.enable ? act->dcm.bridge : (uint8_t)CANFDI_SIM_BRIDGE_NONE;
  if (m.pst_active_bridge > CANFDI_SIM_BRIDGE_B) {
    m.pst_active_bridge = (uint8_t)CANFDI_SIM_BRIDGE_NONE;
  }
  m.pst_sim_mode = f->sim_mode;
  /* The signal wraps after 16777.215 s (24 bits of ms), as the DBC says. */
  m.pst_sim_time = (uint32_t)(((uint64_t)t_us / 1000U) & 0xFFFFFFU);
  m.pst_thr_angle =
      canfdi_sim_msg_sim_plant_status_pst_thr_angle_encode(nudge(canfdi_sim_thr_angle_deg(&sim->thr)));
  if (temp < -40.0) {
    temp = -40.0;
  } else if (temp > 215.0) {
    temp = 215.0;
  } else {
    /* in the signal's range */
  }
  m.pst_dcm_winding_temp = canfdi_sim_msg_sim_plant_status_pst_dcm_winding_temp_encode(nudge(temp));
  fr->id = CANFDI_SIM_MSG_SIM_PLANT_STATUS_FRAME_ID;
  fr->dlc = (uint8_t)canfdi_sim_msg_sim_plant_status_pack(fr->data, &m, sizeof fr->data);
}

size_t canfdi_sim_frames_build(canfdi_sim_frames_t *f, const canfdi_sim_t *sim,
                               const canfdi_sim_in_t *act, canfdi_sim_frame_t *out)
{
  size_t n = 0U;
  memset(out, 0, CANFDI_SIM_FRAMES_MAX_PER_STEP * sizeof *out);
  if (build_dcm(f, sim, &out[n])) {
    n++;
  }
  if (build_thr(f, sim, &out[n])) {
    n++;
  }
  if ((sim->step % CANFDI_SIM_STATUS_PERIOD_STEPS) == 0U) {
    build_status(f, sim, act, &out[n]);
    n++;
  }
  f->diag.sent += (uint32_t)n;
  return n;
}
