/* canfdi_sim_rig.c — the plant/vehicle side of one step; see canfdi_sim_rig.h. */
#include "canfdi_sim_rig.h"

#include <math.h>
#include <string.h>

#include "comm/canfdi_e2e.h"
#include "core/canfdi_common.h"
#include "gen/canfdi_faults.h"
#include "gen/canfdi_sim_msg.h"

int canfdi_sim_rig_init(canfdi_sim_rig_t *r, canfdi_sim_scn_t *scn, canfdi_sim_t *sim,
                        uint8_t sim_mode)
{
  int rc = CANFDI_OK;
  if ((r == NULL) || (scn == NULL) || (sim == NULL)) {
    rc = -CANFDI_EINVAL;
  } else {
    memset(r, 0, sizeof *r);
    r->scn = scn;
    r->sim = sim;
    r->in.dcm.bridge = (uint8_t)CANFDI_SIM_BRIDGE_A;
    r->dcm_supply_V = sim->dcm.p.supply_V;
    r->thr_supply_V = sim->thr.p.supply_V;
    canfdi_sim_frames_init(&r->frames, sim_mode);
    canfdi_e2e_tx_init(&r->sp_e2e[0], (uint16_t)CANFDI_SIM_MSG_SETPOINT_DCM_FRAME_ID);
    canfdi_e2e_tx_init(&r->sp_e2e[1], (uint16_t)CANFDI_SIM_MSG_SETPOINT_THR_FRAME_ID);
  }
  return rc;
}

static void put(canfdi_sim_frame_t *out, size_t *n, uint32_t id, const uint8_t *d)
{
  out[*n].id = id;
  out[*n].dlc = 8U;
  memcpy(out[*n].data, d, 8U);
  (*n)++;
}

size_t canfdi_sim_rig_begin(canfdi_sim_rig_t *r, canfdi_sim_frame_t *out)
{
  const int64_t t_us = canfdi_sim_time_us(r->sim);
  size_t n = 0U;
  CANFDI_ASSERT((r != NULL) && (out != NULL));
  /* The profiles are evaluated every step even while overridden: the
   * scenario's own state must not depend on the overrides. */
  canfdi_sim_scn_eval(r->scn, t_us, &r->sp.speed_rad_s, &r->sp.angle_deg, &r->sp.load_Nm);
  canfdi_sim_scn_supply(r->scn, t_us, &r->dcm_supply_V, &r->thr_supply_V);
  if (r->ovr_dcm) {
    r->sp.speed_rad_s = canfdi_sim_msg_setpoint_dcm_sp_dcm_speed_decode(r->ovr_speed_raw);
    r->sp.load_Nm = canfdi_sim_msg_setpoint_dcm_sp_dcm_load_decode(r->ovr_load_raw);
  }
  if (r->ovr_thr) {
    r->sp.angle_deg = canfdi_sim_msg_setpoint_thr_sp_thr_angle_decode(r->ovr_angle_raw);
  }
  if ((r->sim->step % CANFDI_SIM_RIG_SETPOINT_PERIOD_STEPS) == 0U) {
    uint8_t d[8];
    struct canfdi_sim_msg_setpoint_dcm_t spd;
    struct canfdi_sim_msg_setpoint_thr_t spt;
    memset(d, 0, sizeof d);
    /* The vehicle knows the load it applies (the scenario's load profile;
     * a `load fan` share is not sent: it stays unknown to the ECU). */
    spd.sp_dcm_speed = r->ovr_dcm ? r->ovr_speed_raw
                                  : canfdi_sim_msg_setpoint_dcm_sp_dcm_speed_encode(r->sp.speed_rad_s);
    spd.sp_dcm_load = r->ovr_dcm ? r->ovr_load_raw
                                 : canfdi_sim_msg_setpoint_dcm_sp_dcm_load_encode(r->sp.load_Nm);
    spd.setpoint_dcm_crc = 0U;
    spd.setpoint_dcm_counter = 0U;
    (void)canfdi_sim_msg_setpoint_dcm_pack(d, &spd, sizeof d);
    (void)canfdi_e2e_protect(&r->sp_e2e[0], d, sizeof d);
    put(out, &n, CANFDI_SIM_MSG_SETPOINT_DCM_FRAME_ID, d);
    memset(d, 0, sizeof d);
    spt.sp_thr_angle = r->ovr_thr ? r->ovr_angle_raw
                                  : canfdi_sim_msg_setpoint_thr_sp_thr_angle_encode(r->sp.angle_deg);
    spt.setpoint_thr_crc = 0U;
    spt.setpoint_thr_counter = 0U;
    (void)canfdi_sim_msg_setpoint_thr_pack(d, &spt, sizeof d);
    (void)canfdi_e2e_protect(&r->sp_e2e[1], d, sizeof d);
    put(out, &n, CANFDI_SIM_MSG_SETPOINT_THR_FRAME_ID, d);
  }
  n += canfdi_sim_frames_build(&r->frames, r->sim, &r->in, &out[n]);
  r->got_act_dcm = false;
  r->got_act_thr = false;
  r->diag.frames_tx += (uint32_t)n;
  return n;
}

static int rx_inject(canfdi_sim_rig_t *r, const canfdi_sim_frame_t *f, canfdi_sim_rig_event_t *ev)
{
  struct canfdi_sim_msg_sim_fault_inject_t m;
  canfdi_sim_fault_spec_t spec;
  int rc = -CANFDI_EINVAL;
  if ((canfdi_sim_msg_sim_fault_inject_unpack(&m, f->data, f->dlc) == 0) && (m.inj_fault_id != 0U) &&
      (m.inj_fault_id < canfdi_fault_table_len)) {
    const double t_s = ((double)canfdi_sim_time_us(r->sim) * 1e-6) +
                       canfdi_sim_msg_sim_fault_inject_inj_start_delay_decode(m.inj_start_delay);
    const double rp_s = canfdi_sim_msg_sim_fault_inject_inj_ramp_or_period_decode(m.inj_ramp_or_period);
    /* binary faults ignore the magnitude (DBC); the catalogue checks it */
    const double mag = (strcmp(canfdi_fault_table[m.inj_fault_id].unit, "-") == 0)
                           ? 1.0
                           : canfdi_sim_msg_sim_fault_inject_inj_magnitude_decode(m.inj_magnitude);
    rc = canfdi_sim_fault_spec_make(&spec, m.inj_fault_id, m.inj_mode, t_s, mag,
                                    (m.inj_mode == CANFDI_SIM_MODE_INCIPIENT) ? rp_s : 0.0,
                                    (m.inj_mode == CANFDI_SIM_MODE_INTERMITTENT) ? rp_s : 0.0,
                                    (double)m.inj_duty * 0.01);
    if (rc == CANFDI_OK) {
      rc = canfdi_sim_add_fault(r->sim, &spec);
    }
  }
  if (rc == CANFDI_OK) {
    r->diag.injects++;
    if (ev != NULL) {
      ev->spec = spec;
    }
    rc = CANFDI_SIM_RIG_RX_INJECT;
  }
  return rc;
}

/* An actuator frame a power stage would take: 8 bytes, the E2E CRC over
 * its data ID (the CAN ID) and bytes 1..7 right. */
static bool act_e2e_ok(const canfdi_sim_frame_t *f)
{
  return (f->dlc == CANFDI_E2E_FRAME_LEN) &&
         (canfdi_e2e_frame_crc((uint16_t)f->id, f->data, CANFDI_E2E_FRAME_LEN) == f->data[CANFDI_E2E_CRC_BYTE]);
}

int canfdi_sim_rig_rx(canfdi_sim_rig_t *r, const canfdi_sim_frame_t *f, canfdi_sim_rig_event_t *ev)
{
  int rc = -CANFDI_EINVAL;
  CANFDI_ASSERT((r != NULL) && (f != NULL));
  r->diag.frames_rx++;
  if (ev != NULL) {
    memset(ev, 0, sizeof *ev);
  }
  switch (f->id) {
  case CANFDI_SIM_MSG_DCM_ACTUATOR_FRAME_ID: {
    struct canfdi_sim_msg_dcm_actuator_t a;
    if (!act_e2e_ok(f)) {
      r->diag.act_rejected++;
    } else if (canfdi_sim_msg_dcm_actuator_unpack(&a, f->data, f->dlc) == 0) {
      r->in.dcm.u_cmd_V = canfdi_sim_msg_dcm_actuator_dcm_ua_cmd_decode(a.dcm_ua_cmd);
      r->in.dcm.bridge = a.dcm_bridge_sel;
      r->in.dcm.enable = (a.dcm_enable != 0U);
      r->got_act_dcm = true;
      r->diag.actuators++;
      rc = CANFDI_SIM_RIG_RX_ACT_DCM;
    }
    break;
  }
  case CANFDI_SIM_MSG_THR_ACTUATOR_FRAME_ID: {
    struct canfdi_sim_msg_thr_actuator_t a;
    if (!act_e2e_ok(f)) {
      r->diag.act_rejected++;
    } else if (canfdi_sim_msg_thr_actuator_unpack(&a, f->data, f->dlc) == 0) {
      r->in.thr.u_cmd_V = canfdi_sim_msg_thr_actuator_thr_u_cmd_decode(a.thr_u_cmd);
      r->in.thr.enable = (a.thr_enable != 0U);
      r->got_act_thr = true;
      r->diag.actuators++;
      rc = CANFDI_SIM_RIG_RX_ACT_THR;
    }
    break;
  }
  case CANFDI_SIM_MSG_SETPOINT_DCM_FRAME_ID: {
    struct canfdi_sim_msg_setpoint_dcm_t m;
    if ((f->dlc == 8U) && (canfdi_sim_msg_setpoint_dcm_unpack(&m, f->data, f->dlc) == 0)) {
      const bool changed = !r->ovr_dcm || (m.sp_dcm_speed != r->ovr_speed_raw) ||
                           (m.sp_dcm_load != r->ovr_load_raw);
      r->ovr_dcm = true;
      r->ovr_speed_raw = m.sp_dcm_speed;
      r->ovr_load_raw = m.sp_dcm_load;
      /* the load acts from this step on */
      r->sp.speed_rad_s = canfdi_sim_msg_setpoint_dcm_sp_dcm_speed_decode(m.sp_dcm_speed);
      r->sp.load_Nm = canfdi_sim_msg_setpoint_dcm_sp_dcm_load_decode(m.sp_dcm_load);
      r->diag.overrides++;
      if (ev != NULL) {
        ev->changed = changed;
      }
      rc = CANFDI_SIM_RIG_RX_SP_DCM;
    }
    break;
  }
  case CANFDI_SIM_MSG_SETPOINT_THR_FRAME_ID: {
    struct canfdi_sim_msg_setpoint_thr_t m;
    if ((f->dlc == 8U) && (canfdi_sim_msg_setpoint_thr_unpack(&m, f->data, f->dlc) == 0)) {
      const bool changed = !r->ovr_thr || (m.sp_thr_angle != r->ovr_angle_raw);
      r->ovr_thr = true;
      r->ovr_angle_raw = m.sp_thr_angle;
      r->sp.angle_deg = canfdi_sim_msg_setpoint_thr_sp_thr_angle_decode(m.sp_thr_angle);
      r->diag.overrides++;
      if (ev != NULL) {
        ev->changed = changed;
      }
      rc = CANFDI_SIM_RIG_RX_SP_THR;
    }
    break;
  }
  case CANFDI_SIM_MSG_SIM_FAULT_INJECT_FRAME_ID:
    rc = (f->dlc == 8U) ? rx_inject(r, f, ev) : -CANFDI_EINVAL;
    break;
  case CANFDI_SIM_MSG_SIM_FAULT_CLEAR_FRAME_ID: {
    struct canfdi_sim_msg_sim_fault_clear_t m;
    if ((f->dlc == 8U) && (canfdi_sim_msg_sim_fault_clear_unpack(&m, f->data, f->dlc) == 0)) {
      const size_t n = canfdi_sim_clear_faults(r->sim, m.clr_fault_id);
      r->diag.clears++;
      if (ev != NULL) {
        ev->fault_id = m.clr_fault_id;
        ev->n_cleared = n;
      }
      rc = CANFDI_SIM_RIG_RX_CLEAR;
    }
    break;
  }
  default:
    r->diag.ignored++;
    rc = CANFDI_SIM_RIG_RX_IGNORED;
    break;
  }
  if (rc < 0) {
    r->diag.rejected++;
  }
  return rc;
}

void canfdi_sim_rig_sim_step(canfdi_sim_rig_t *r, canfdi_sim_frame_t *out)
{
  struct canfdi_sim_msg_sim_step_t m;
  CANFDI_ASSERT((r != NULL) && (out != NULL));
  memset(out, 0, sizeof *out);
  m.sim_step_index = (uint32_t)r->sim->step; /* wraps after 49.7 days of simulated time */
  out->id = CANFDI_SIM_MSG_SIM_STEP_FRAME_ID;
  out->dlc = 8U;
  (void)canfdi_sim_msg_sim_step_pack(out->data, &m, sizeof out->data);
  r->diag.frames_tx++;
}

void canfdi_sim_rig_end(canfdi_sim_rig_t *r)
{
  CANFDI_ASSERT(r != NULL);
  r->in.dcm.load_Nm = r->sp.load_Nm;
  canfdi_sim_set_supply(r->sim, r->dcm_supply_V, r->thr_supply_V);
  canfdi_sim_step(r->sim, &r->in);
}
