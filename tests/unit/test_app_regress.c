/*
 * test_app_regress.c — regression tests of the application (firmware/app)
 * in closed loop with the host_sim plants, for behaviour that must hold
 * after weeks of operation or in unusual start-ups:
 *   - the cyclic EcuDtc frame keeps rotating over the stored trouble codes
 *     past 2^32 steps (49.7 days): no decision rests on a diagnostic
 *     counter, which saturates;
 *   - an estimator whose feeding resumes restarts with a covariance reset
 *     whatever its diagnostic step counter reads;
 *   - a drive held off at start-up (its inputs never valid) is held off by
 *     the actuator manager itself, so the manager's plausibility check
 *     compares the measured armature voltage with what was applied (no
 *     false dead-bridge code when the sensor node starts with a bad
 *     current signal);
 *   - the setpoints' supervision in closed loop: a corrupted (wrong CRC),
 *     forged (a second counter sequence) or missing setpoint frame is
 *     rejected and counted, the last accepted setpoint held for 50 ms, then
 *     the safe reaction (motor braked to standstill, valve to limp-home),
 *     U1A51 / U1A50; good frames restore the setpoints;
 *   - the commands another controller applied (canfdi_app_set_applied, a
 *     replay of a recording): the application's own commands given back
 *     change no frame; an unknown throttle command stops the throttle's
 *     models until it is known again; an applied DC-motor command the
 *     measured U_A does not show is judged by the bridge check, an unknown
 *     one is not judged; an unknown position reference keeps the tracking
 *     monitor silent.
 * Counters near their wrap are set directly in the application's state
 * (the fields are public for reading; tests write them to fast-forward
 * time). The time stamps past 71.6 minutes are tested by the SIL scenario
 * tests/sil/scenarios/dtc_freeze_uptime.scn.
 * Frames are packed and unpacked with the cantools codecs (host_sim's PLANT
 * codec and the tester codec of the SIL rig), never by hand.
 */
#include <check.h>
#include <stdlib.h>
#include <string.h>

#include "app/canfdi_app.h"
#include "canfdi_sil_msg.h"
#include "canfdi_sim_rig.h"
#include "comm/canfdi_e2e.h"
#include "core/canfdi_qconst.h"
#include "gen/canfdi_sim_msg.h"
#include "unit_main.h"

static canfdi_app_t app;
static canfdi_app_cal_t cal;
static canfdi_sim_scn_t scn;
static canfdi_sim_t sim;
static canfdi_sim_rig_t rig;
/* Called before every ECU step of loop_step when set (the replay's hook). */
static void (*before_step)(void);
/* Given every setpoint frame of the rig before the ECU gets it when set:
 * may change it; false drops it (the vehicle's link, tampered with). */
static bool (*sp_tamper)(canfdi_sim_frame_t *f);
/* The same for the plant's sensor frames (DcmSensor, ThrSensor). */
static bool (*sensor_tamper)(canfdi_sim_frame_t *f);

static void loop_start(const char *text)
{
  canfdi_sim_scn_err_t err;
  ck_assert_int_eq(canfdi_sim_scn_parse(&scn, text, "test", &err), CANFDI_OK);
  ck_assert_int_eq(canfdi_sim_scn_setup(&scn, &sim), CANFDI_OK);
  ck_assert_int_eq(canfdi_sim_rig_init(&rig, &scn, &sim, (uint8_t)CANFDI_SIM_MODE_LOCKSTEP),
                   CANFDI_OK);
  canfdi_app_default_cal(&cal);
  ck_assert_int_eq(canfdi_app_init(&app, &cal, 0U), CANFDI_OK);
  before_step = NULL;
  sp_tamper = NULL;
  sensor_tamper = NULL;
}

/* One lockstep step as the SIL rig runs it: the plant's and the vehicle's
 * frames the ECU consumes, the ECU's step, its frames to the plant. The
 * ECU's frames of the step are left in out; returns their number. */
static int32_t loop_step(canfdi_tx_frame_t *out)
{
  canfdi_sim_frame_t pf[CANFDI_SIM_RIG_MAX_TX];
  const uint32_t now_us = (uint32_t)canfdi_sim_time_us(&sim);
  const size_t npf = canfdi_sim_rig_begin(&rig, pf);
  size_t j;
  int32_t n;
  for (j = 0U; j < npf; j++) {
    const uint32_t id = pf[j].id;
    const bool sp = (id == CANFDI_SIL_MSG_SETPOINT_DCM_FRAME_ID) || (id == CANFDI_SIL_MSG_SETPOINT_THR_FRAME_ID);
    const bool sensor = (id == CANFDI_SIL_MSG_DCM_SENSOR_FRAME_ID) || (id == CANFDI_SIL_MSG_THR_SENSOR_FRAME_ID);
    if (sp && (sp_tamper != NULL) && !sp_tamper(&pf[j])) {
      continue;
    }
    if (sensor && (sensor_tamper != NULL) && !sensor_tamper(&pf[j])) {
      continue;
    }
    if ((id == CANFDI_SIL_MSG_DCM_SENSOR_FRAME_ID) || (id == CANFDI_SIL_MSG_THR_SENSOR_FRAME_ID) || sp) {
      (void)canfdi_app_rx_frame(&app, id, pf[j].data, pf[j].dlc, now_us);
    }
  }
  if (before_step != NULL) {
    before_step();
  }
  n = canfdi_app_step(&app, now_us, out);
  ck_assert_int_ge(n, 2);
  for (j = 0U; j < (size_t)n; j++) {
    canfdi_sim_frame_t rf;
    rf.id = out[j].id;
    rf.dlc = out[j].dlc;
    memcpy(rf.data, out[j].data, sizeof rf.data);
    (void)canfdi_sim_rig_rx(&rig, &rf, NULL);
  }
  canfdi_sim_rig_end(&rig);
  return n;
}

static void loop_run(uint32_t steps)
{
  canfdi_tx_frame_t out[CANFDI_APP_MAX_TX];
  uint32_t k;
  for (k = 0U; k < steps; k++) {
    (void)loop_step(out);
  }
}

/* Two faults; the I_A offset after the DC motor's learning (about 2.1 s
 * here): inside it, the learning check would leave it untested
 * (canfdi_app.h, CANFDI_APP_LEARN_FAULT). */
static const char *const two_faults_scn =
    "duration 100\n"
    "seed 5\n"
    "noise dcm_ua 0.05\nnoise dcm_ia 0.02\nnoise dcm_speed 0.2\n"
    "noise thr_tps1 0.003\nnoise thr_tps2 0.003\nnoise thr_i 0.01\n"
    "init dcm_winding 52.3\n"
    "load const 1.2\nspeed const 100\nangle const 20\n"
    "fault 1 thr_tps1_open abrupt 1\n"
    "fault 2.3 dcm_ia_sensor_offset abrupt 0.5\n";

/* The cyclic EcuDtc frames of `steps` steps: how many distinct codes. */
static unsigned cyclic_codes_seen(uint32_t steps)
{
  canfdi_tx_frame_t out[CANFDI_APP_MAX_TX];
  uint32_t seen[8];
  unsigned n_seen = 0U;
  uint32_t k;
  for (k = 0U; k < steps; k++) {
    const int32_t n = loop_step(out);
    int32_t i;
    for (i = 0; i < n; i++) {
      struct canfdi_sil_msg_ecu_dtc_t m;
      unsigned s;
      bool known = false;
      if ((out[i].id != CANFDI_SIL_MSG_ECU_DTC_FRAME_ID) ||
          (canfdi_sil_msg_ecu_dtc_unpack(&m, out[i].data, out[i].dlc) != 0) ||
          (m.dtc_tx_reason != 0U) || (m.dtc_code == 0U)) {
        continue;
      }
      for (s = 0U; s < n_seen; s++) {
        known = known || (seen[s] == m.dtc_code);
      }
      if (!known && (n_seen < 8U)) {
        seen[n_seen++] = m.dtc_code;
      }
    }
  }
  return n_seen;
}

/* Two stored codes (P0122, P1A20): the cyclic frame shows both
 * within 400 ms, also once the step counter is saturated and whatever the
 * rotation's own position reads. */
START_TEST(test_dtc_round_robin_past_2_32_steps)
{
  loop_start(two_faults_scn);
  loop_run(3000U);
  ck_assert_uint_ge(canfdi_dtc_count_by_mask(canfdi_app_dtc(&app), (uint8_t)CANFDI_DTC_ST_TFSLC), 2U);
  ck_assert_uint_ge(cyclic_codes_seen(400U), 2U);
  /* 49.7 days later: the step counter saturates within the next 500 steps */
  app.diag.steps = UINT32_MAX - 500U;
  loop_run(600U);
  ck_assert_uint_eq(canfdi_app_diag(&app)->steps, UINT32_MAX);
  ck_assert_uint_ge(cyclic_codes_seen(400U), 2U);
  /* 13.6 years of cyclic frames: the rotation's own position wraps */
  app.out.rr_frames = UINT32_MAX - 1U;
  ck_assert_uint_ge(cyclic_codes_seen(400U), 2U);
  ck_assert_uint_lt(app.out.rr_frames, 10U);
}
END_TEST

static const char *const fault_free_scn =
    "duration 100\n"
    "seed 9\n"
    "noise dcm_ua 0.05\nnoise dcm_ia 0.02\nnoise dcm_speed 0.2\n"
    "noise thr_tps1 0.003\nnoise thr_tps2 0.003\nnoise thr_i 0.01\n"
    "init dcm_winding 52.3\n"
    "load const 1.2\nspeed const 100\nangle const 20\n";

/* The DC-motor estimator is fed while its inputs are valid; when its
 * frames stop for a while and come back, it restarts with a covariance
 * reset (its estimate re-converges on the new data). That must not depend
 * on its diagnostic step counter: during the gap the counter is set to 0,
 * what a wrapping 32-bit counter reads after 2^32 fed steps. */
START_TEST(test_estimator_restart_independent_of_counters)
{
  canfdi_tx_frame_t out[CANFDI_APP_MAX_TX];
  uint32_t resets_before;
  uint32_t k;
  bool resumed = false;
  loop_start(fault_free_scn);
  loop_run(2000U);
  resets_before = canfdi_est_dcm_diag(&app.est_dcm)->resets;
  /* 20 steps without DcmSensor */
  for (k = 0U; k < 20U; k++) {
    canfdi_sim_frame_t pf[CANFDI_SIM_RIG_MAX_TX];
    const uint32_t now_us = (uint32_t)canfdi_sim_time_us(&sim);
    const size_t npf = canfdi_sim_rig_begin(&rig, pf);
    size_t j;
    int32_t n;
    for (j = 0U; j < npf; j++) {
      if ((pf[j].id == CANFDI_SIL_MSG_THR_SENSOR_FRAME_ID) ||
          (pf[j].id == CANFDI_SIL_MSG_SETPOINT_DCM_FRAME_ID) ||
          (pf[j].id == CANFDI_SIL_MSG_SETPOINT_THR_FRAME_ID)) {
        (void)canfdi_app_rx_frame(&app, pf[j].id, pf[j].data, pf[j].dlc, now_us);
      }
    }
    n = canfdi_app_step(&app, now_us, out);
    for (j = 0U; j < (size_t)n; j++) {
      canfdi_sim_frame_t rf;
      rf.id = out[j].id;
      rf.dlc = out[j].dlc;
      memcpy(rf.data, out[j].data, sizeof rf.data);
      (void)canfdi_sim_rig_rx(&rig, &rf, NULL);
    }
    canfdi_sim_rig_end(&rig);
  }
  ck_assert(!app.dcm.est_on);
  app.est_dcm.diag.steps = 0U;
  /* frames again: the DcmSensor E2E counter jumped, the input recovers
   * after its recovery frames; the step in which feeding resumes resets
   * the estimator */
  for (k = 0U; (k < 200U) && !resumed; k++) {
    const bool was_on = app.dcm.est_on;
    const uint32_t r0 = canfdi_est_dcm_diag(&app.est_dcm)->resets;
    (void)loop_step(out);
    if (!was_on && app.dcm.est_on) {
      resumed = true;
      ck_assert_uint_eq(canfdi_est_dcm_diag(&app.est_dcm)->resets, r0 + 1U);
    }
  }
  ck_assert(resumed);
  ck_assert_uint_gt(canfdi_est_dcm_diag(&app.est_dcm)->resets, resets_before);
}
END_TEST

/* Which sensor frame tamper_one() drops or corrupts, once. */
static uint32_t tamper_id;
static bool tamper_corrupts;

static bool tamper_one(canfdi_sim_frame_t *f)
{
  bool keep = true;
  if (f->id == tamper_id) {
    tamper_id = 0U;
    if (tamper_corrupts) {
      f->data[0] ^= 0x5AU; /* the E2E CRC byte: the frame is rejected */
    } else {
      keep = false;
    }
  }
  return keep;
}

/* One sensor frame of a plant lost or corrupted while the drive
 * accelerates; the other plant's models untouched, nothing failed 1 s
 * later (a CRC error's U1A2x healed).
 * Lost (its counter then jumps by 2: accepted by design): the input stays
 * VALID but not fresh in that step, nothing restarts, and the plant's model
 * rules (CANFDI_SYM_F_*_REARM) are held for exactly cal.late_hold_steps
 * steps from that step on. Corrupted: the input is in error until its
 * recovery frames have passed; the next VALID sample restarts the parity
 * equations and holds the rules for exactly cal.rearm_steps steps. */
static void check_hold(bool corrupt, uint32_t id, const canfdi_app_gate_t *g, const canfdi_app_gate_t *other,
                       uint32_t flag, uint32_t other_flag, uint32_t (*resets)(void))
{
  canfdi_tx_frame_t out[CANFDI_APP_MAX_TX];
  uint32_t r0;
  uint32_t k;
  uint32_t hold;
  loop_start("duration 100\nseed 4\nnoise dcm_ua 0.05\nnoise dcm_ia 0.02\nnoise dcm_speed 0.2\n"
             "noise thr_tps1 0.003\nnoise thr_tps2 0.003\nnoise thr_i 0.01\n"
             "load const 0.5\nspeed const 60\nspeed step 3 40\nangle const 20\nangle step 3 10\n");
  loop_run(3003U);
  ck_assert(g->in_ok && g->fresh && (g->rearm == 0U) && ((app.sym.flags & flag) == 0U));
  r0 = resets();
  sensor_tamper = tamper_one;
  tamper_id = id;
  tamper_corrupts = corrupt;
  (void)loop_step(out);
  ck_assert_uint_eq(tamper_id, 0U);
  ck_assert(other->in_ok && other->fresh);
  if (corrupt) {
    ck_assert(!g->in_ok);
    for (k = 0U; (k < 10U) && !g->in_ok; k++) {
      ck_assert_uint_eq(resets(), r0);
      (void)loop_step(out);
    }
    ck_assert(g->in_ok);
    ck_assert_uint_eq(resets(), r0 + 1U);
    hold = cal.rearm_steps;
  } else {
    ck_assert(g->in_ok && !g->fresh);
    hold = cal.late_hold_steps;
  }
  ck_assert_uint_gt(hold, 1U);
  for (k = 1U; k < hold; k++) {
    ck_assert_msg((app.sym.flags & flag) != 0U, "held %u steps only", k);
    ck_assert((app.sym.flags & other_flag) == 0U);
    (void)loop_step(out);
  }
  ck_assert((app.sym.flags & flag) != 0U);
  (void)loop_step(out);
  ck_assert_uint_eq(app.sym.flags & flag, 0U);
  k = corrupt ? (r0 + 1U) : r0; /* (a conditional inside ck_assert_* binds wrongly) */
  ck_assert_uint_eq(resets(), k);
  loop_run(1000U);
  ck_assert_uint_eq(canfdi_dtc_count_by_mask(canfdi_app_dtc(&app), (uint8_t)CANFDI_DTC_ST_TF), 0U);
}

static uint32_t dcm_parity_resets(void) { return canfdi_parity_dcm_diag(&app.parity_dcm)->resets; }
static uint32_t thr_parity_resets(void) { return canfdi_parity_thr_diag(&app.parity_thr)->resets; }

START_TEST(test_models_hold_after_a_late_or_rejected_frame)
{
  bool corrupt = false;
  do {
    check_hold(corrupt, CANFDI_SIL_MSG_DCM_SENSOR_FRAME_ID, &app.dcm, &app.thr, CANFDI_SYM_F_DCM_REARM,
               CANFDI_SYM_F_THR_REARM, dcm_parity_resets);
    check_hold(corrupt, CANFDI_SIL_MSG_THR_SENSOR_FRAME_ID, &app.thr, &app.dcm, CANFDI_SYM_F_THR_REARM,
               CANFDI_SYM_F_DCM_REARM, thr_parity_resets);
    corrupt = !corrupt;
  } while (corrupt);
}
END_TEST

/* The sensor node starts with an implausible armature current (out of the
 * DBC range: the signal is rejected, its frame's other signals taken). The
 * DC motor's inputs are then never all valid and its drive stays off; the
 * speed controller, seeing a valid speed and supply, already asks for a
 * large voltage. The manager must know the drive is held off: its
 * plausibility check must not read the 0 V at the terminals as a dead
 * bridge. */
START_TEST(test_startup_hold_off_is_what_the_manager_applied)
{
  canfdi_tx_frame_t out[CANFDI_APP_MAX_TX];
  canfdi_e2e_tx_t e2e;
  canfdi_e2e_tx_t e2e_sp;
  uint32_t k;
  canfdi_app_default_cal(&cal);
  ck_assert_int_eq(canfdi_app_init(&app, &cal, 0U), CANFDI_OK);
  canfdi_e2e_tx_init(&e2e, (uint16_t)CANFDI_SIM_MSG_DCM_SENSOR_FRAME_ID);
  canfdi_e2e_tx_init(&e2e_sp, (uint16_t)CANFDI_SIM_MSG_SETPOINT_DCM_FRAME_ID);
  for (k = 1U; k <= 30U; k++) {
    struct canfdi_sim_msg_dcm_sensor_t m;
    struct canfdi_sim_msg_setpoint_dcm_t sp;
    uint8_t d[8];
    memset(&m, 0, sizeof m);
    m.dcm_ua = canfdi_sim_msg_dcm_sensor_dcm_ua_encode(0.0);
    m.dcm_ia = 0xFFFFU; /* beyond the DBC range: implausible */
    m.dcm_omega = canfdi_sim_msg_dcm_sensor_dcm_omega_encode(0.0);
    m.dcm_usupply = canfdi_sim_msg_dcm_sensor_dcm_usupply_encode(48.0);
    ck_assert_int_eq(canfdi_sim_msg_dcm_sensor_pack(d, &m, 8U), 8);
    ck_assert_int_eq(canfdi_e2e_protect(&e2e, d, 8U), CANFDI_OK);
    (void)canfdi_app_rx_frame(&app, CANFDI_SIM_MSG_DCM_SENSOR_FRAME_ID, d, 8U, k * 1000U);
    if ((k % 10U) == 1U) {
      memset(&sp, 0, sizeof sp);
      sp.sp_dcm_speed = canfdi_sim_msg_setpoint_dcm_sp_dcm_speed_encode(100.0);
      sp.sp_dcm_load = canfdi_sim_msg_setpoint_dcm_sp_dcm_load_encode(1.2);
      ck_assert_int_eq(canfdi_sim_msg_setpoint_dcm_pack(d, &sp, 8U), 8);
      ck_assert_int_eq(canfdi_e2e_protect(&e2e_sp, d, 8U), CANFDI_OK);
      ck_assert_int_eq(canfdi_app_rx_frame(&app, CANFDI_SIM_MSG_SETPOINT_DCM_FRAME_ID, d, 8U, k * 1000U),
                       CANFDI_RX_ACCEPTED);
    }
    ck_assert_int_ge(canfdi_app_step(&app, k * 1000U, out), 2);
  }
  /* held off: never enabled, and no bridge judged dead */
  ck_assert(!app.fb.mgr.dcm.enable);
  ck_assert_uint_eq(app.fb.mgr.detected &
                        (CANFDI_FAULT_BIT(CANFDI_FAULT_DCM_BRIDGE_A_DEAD) |
                         CANFDI_FAULT_BIT(CANFDI_FAULT_DCM_BRIDGES_DEAD)),
                    0U);
  ck_assert_uint_eq(canfdi_actmgr_diag(&app.actmgr).ua_implausible, 0U);
}
END_TEST


/* ------------------------------------------------ setpoint supervision */

static unsigned tampered;           /* setpoint frames changed or dropped */
static canfdi_e2e_tx_t forger;      /* a second sender's own sequence */

/* SetpointThr forged wide open (80 deg), its CRC wrong: a corruption. */
static bool thr_sp_bad_crc(canfdi_sim_frame_t *f)
{
  if (f->id == CANFDI_SIL_MSG_SETPOINT_THR_FRAME_ID) {
    struct canfdi_sim_msg_setpoint_thr_t m;
    memset(&m, 0, sizeof m);
    m.sp_thr_angle = canfdi_sim_msg_setpoint_thr_sp_thr_angle_encode(80.0);
    ck_assert_int_eq(canfdi_sim_msg_setpoint_thr_pack(f->data, &m, 8U), 8);
    f->data[0] = (uint8_t)(canfdi_e2e_frame_crc((uint16_t)f->id, f->data, 8U) ^ 0x5AU);
    tampered++;
  }
  return true;
}

/* A second sender on SetpointDcm's identifier: every 10 ms, just before
 * the vehicle's frame, its own frame, 300 rad/s with a right CRC and a
 * counter sequence of its own (8 ahead of the vehicle's, both +1 per
 * 10 ms). */
static bool dcm_sp_second_sender(canfdi_sim_frame_t *f)
{
  if (f->id == CANFDI_SIL_MSG_SETPOINT_DCM_FRAME_ID) {
    struct canfdi_sim_msg_setpoint_dcm_t m;
    uint8_t d[8];
    memset(&m, 0, sizeof m);
    m.sp_dcm_speed = canfdi_sim_msg_setpoint_dcm_sp_dcm_speed_encode(300.0);
    m.sp_dcm_load = canfdi_sim_msg_setpoint_dcm_sp_dcm_load_encode(1.2);
    ck_assert_int_eq(canfdi_sim_msg_setpoint_dcm_pack(d, &m, 8U), 8);
    ck_assert_int_eq(canfdi_e2e_protect(&forger, d, 8U), CANFDI_OK);
    (void)canfdi_app_rx_frame(&app, f->id, d, 8U, (uint32_t)canfdi_sim_time_us(&sim));
    tampered += 2U; /* the forged frame and the vehicle's */
  }
  return true;
}

/* Both setpoint frames lost. */
static bool sp_lost(canfdi_sim_frame_t *f)
{
  (void)f;
  tampered++;
  return false;
}

#define DEG_Q16(d) CANFDI_Q16_DEG((d), 1)

static int32_t valve_rad_q16(void) { return app.vote_out.angle_rad_q16; }
static int32_t speed_q16(void) { return canfdi_rx_value(&app.rx, CANFDI_RX_IN_DCM_OMEGA); }
static bool dtc_failed(uint32_t code)
{
  const int32_t i = canfdi_dtc_find(canfdi_app_dtc(&app), code);
  ck_assert_int_ge(i, 0);
  return (canfdi_dtc_status(canfdi_app_dtc(&app), (uint8_t)i) & (int32_t)CANFDI_DTC_ST_TF) != 0;
}

/* Closed loop at 100 rad/s and 20 deg. A wide-open throttle setpoint with
 * a wrong CRC is rejected: the valve holds 20 deg for 50 ms, then goes to
 * its limp-home angle (6.5 deg), never towards 80 deg; U1A51, frames
 * counted in the self-diagnostics. A second sender on SetpointDcm (right
 * CRC, own counter sequence, 300 rad/s): counter errors, the motor braked
 * to standstill. Both frames lost: U1A50 after 50 ms. Good frames again:
 * both setpoints restored. No catalogue fault, no degradation. */
START_TEST(test_setpoint_supervision_safe_reaction)
{
  canfdi_tx_frame_t out[CANFDI_APP_MAX_TX];
  uint32_t rej0;
  uint32_t k;
  int32_t valve_max = 0;
  int32_t speed_max = 0;
  loop_start(fault_free_scn);
  loop_run(4000U); /* the first 2.5 s carry the estimators' test signals */
  ck_assert_int_lt(abs(valve_rad_q16() - DEG_Q16(20)), DEG_Q16(1));
  ck_assert_int_lt(abs(speed_q16() - 100 * 65536), 3 * 65536);
  ck_assert(!dtc_failed(CANFDI_DTC_U1A51) && !dtc_failed(CANFDI_DTC_U1A50));
  rej0 = canfdi_app_diag(&app)->frames_rejected;
  /* 1. SetpointThr corrupted (the rig's next one is due at a 10 ms tick) */
  tampered = 0U;
  sp_tamper = thr_sp_bad_crc;
  for (k = 0U; k < 1000U; k++) {
    (void)loop_step(out);
    valve_max = (valve_rad_q16() > valve_max) ? valve_rad_q16() : valve_max;
    /* the last good frame came at -10 ms: held while younger than 50 ms */
    ck_assert_uint_eq(app.rx.in[CANFDI_RX_IN_SP_THR_ANGLE].quality,
                      (k < 40U) ? CANFDI_RX_SUBSTITUTED : CANFDI_RX_INVALID);
    if (k < 40U) {
      ck_assert_int_lt(abs(canfdi_rx_value(&app.rx, CANFDI_RX_IN_SP_THR_ANGLE) - DEG_Q16(20)), DEG_Q16(1) / 100);
    }
  }
  ck_assert_int_lt(valve_max, DEG_Q16(21));                                   /* never opened */
  ck_assert_int_lt(abs(valve_rad_q16() - cal.ctrl_thr.limp_home_rad_q16), DEG_Q16(1)); /* limp-home */
  ck_assert(dtc_failed(CANFDI_DTC_U1A51));
  ck_assert(!dtc_failed(CANFDI_DTC_U1A50)); /* the frames came */
  ck_assert_uint_eq(canfdi_app_diag(&app)->frames_rejected - rej0, tampered);
  ck_assert_uint_eq(app.rx.diag.crc_err[CANFDI_RX_F_SP_THR], tampered);
  ck_assert_int_lt(abs(speed_q16() - 100 * 65536), 8 * 65536); /* the motor's setpoint is untouched */
  ck_assert_uint_eq(app.fb.mgr.dcm_state, CANFDI_DEG_NORMAL);
  ck_assert_uint_eq(app.fb.mgr.thr_state, CANFDI_DEG_NORMAL);
  /* 2. good frames: the valve follows its setpoint again (the test
   * signals may run again meanwhile: +-3 deg) */
  sp_tamper = NULL;
  loop_run(1000U);
  ck_assert_int_lt(abs(valve_rad_q16() - DEG_Q16(20)), DEG_Q16(4));
  ck_assert_uint_eq(app.rx.in[CANFDI_RX_IN_SP_THR_ANGLE].quality, CANFDI_RX_VALID);
  /* 3. a second sender on SetpointDcm */
  canfdi_e2e_tx_init(&forger, (uint16_t)CANFDI_SIL_MSG_SETPOINT_DCM_FRAME_ID);
  forger.counter = (uint8_t)((rig.sp_e2e[0].counter + 8U) & 15U);
  tampered = 0U;
  rej0 = app.rx.diag.counter_err[CANFDI_RX_F_SP_DCM];
  sp_tamper = dcm_sp_second_sender;
  for (k = 0U; k < 2000U; k++) {
    (void)loop_step(out);
    speed_max = (speed_q16() > speed_max) ? speed_q16() : speed_max;
  }
  ck_assert_int_lt(speed_max, 108 * 65536); /* never towards 300 rad/s */
  ck_assert_int_lt(abs(speed_q16()), 3 * 65536); /* braked to standstill */
  ck_assert_uint_eq(app.rx.in[CANFDI_RX_IN_SP_DCM_SPEED].quality, CANFDI_RX_INVALID);
  ck_assert_uint_eq(app.rx.diag.counter_err[CANFDI_RX_F_SP_DCM] - rej0, tampered);
  ck_assert(dtc_failed(CANFDI_DTC_U1A51));
  /* 4. both lost: U1A50 after the 50 ms window, not before */
  sp_tamper = NULL;
  loop_run(1000U);
  ck_assert_int_lt(abs(speed_q16() - 100 * 65536), 8 * 65536);
  sp_tamper = sp_lost;
  for (k = 0U; (k < 200U) && !dtc_failed(CANFDI_DTC_U1A50); k++) {
    (void)loop_step(out);
  }
  ck_assert_uint_ge(k, 40U);
  ck_assert_uint_le(k, 60U);
  ck_assert_uint_eq(app.rx.in[CANFDI_RX_IN_SP_DCM_SPEED].quality, CANFDI_RX_INVALID);
  ck_assert_uint_eq(app.rx.in[CANFDI_RX_IN_SP_THR_ANGLE].quality, CANFDI_RX_INVALID);
  sp_tamper = NULL;
  loop_run(20U);
  ck_assert(!dtc_failed(CANFDI_DTC_U1A50));
  ck_assert_uint_eq(app.rx.in[CANFDI_RX_IN_SP_DCM_SPEED].quality, CANFDI_RX_VALID);
  /* none of it is a plant fault */
  ck_assert_uint_eq(canfdi_dtc_count_by_mask(canfdi_app_dtc(&app), (uint8_t)CANFDI_DTC_ST_TFSLC), 2U);
}
END_TEST

/* ------------------------------------------------ canfdi_app_set_applied */

static canfdi_app_applied_t applied;

static void give_own_commands(void)
{
  applied.dcm_known = true;
  applied.dcm = app.fb.mgr.dcm;
  applied.thr_known = true;
  applied.thr = app.fb.mgr.thr;
  applied.thr_ref_known = true;
  ck_assert_int_eq(canfdi_app_set_applied(&app, &applied), CANFDI_OK);
}

static void give_applied(void) { ck_assert_int_eq(canfdi_app_set_applied(&app, &applied), CANFDI_OK); }

/* FNV-1a over every frame the ECU sends in `steps` steps. */
static uint64_t frames_hash(uint32_t steps)
{
  canfdi_tx_frame_t out[CANFDI_APP_MAX_TX];
  uint64_t h = 1469598103934665603ULL;
  uint32_t k;
  for (k = 0U; k < steps; k++) {
    const int32_t n = loop_step(out);
    int32_t i;
    for (i = 0; i < n; i++) {
      unsigned b;
      h = (h ^ out[i].id) * 1099511628211ULL;
      for (b = 0U; b < out[i].dlc; b++) {
        h = (h ^ out[i].data[b]) * 1099511628211ULL;
      }
    }
  }
  return h;
}

/* A replay of a run from power-up gives the application its own commands
 * back: nothing may change, frame for frame, faults and all. */
START_TEST(test_set_applied_own_commands_change_nothing)
{
  uint64_t plain;
  uint64_t replayed;
  ck_assert_int_eq(canfdi_app_set_applied(NULL, &applied), -CANFDI_EINVAL);
  loop_start(two_faults_scn);
  ck_assert_int_eq(canfdi_app_set_applied(&app, NULL), -CANFDI_EINVAL);
  plain = frames_hash(2700U);
  loop_start(two_faults_scn);
  before_step = give_own_commands;
  replayed = frames_hash(2700U);
  ck_assert_uint_eq(replayed, plain);
  ck_assert_uint_ge(canfdi_dtc_count_by_mask(canfdi_app_dtc(&app), (uint8_t)CANFDI_DTC_ST_TF), 2U);
}
END_TEST

/* Without the throttle's command its models cannot run: no residual, no
 * estimate fed, the model not offered to the vote; when the command is
 * known again the parity equations restart. */
START_TEST(test_set_applied_thr_unknown_stops_throttle_models)
{
  canfdi_tx_frame_t out[CANFDI_APP_MAX_TX];
  uint32_t resets;
  uint32_t k;
  loop_start(fault_free_scn);
  loop_run(1500U);
  ck_assert(app.thr.in_ok);
  ck_assert_uint_ne(app.sym.thr_rn_valid, 0U);
  resets = canfdi_parity_thr_diag(&app.parity_thr)->resets;
  before_step = give_applied;
  applied = (canfdi_app_applied_t){0};
  applied.dcm_known = true;
  applied.thr_ref_known = true;
  for (k = 0U; k < 50U; k++) {
    applied.dcm = app.fb.mgr.dcm;
    (void)loop_step(out);
    ck_assert(!app.thr.in_ok);
    ck_assert(!app.thr.est_on);
    ck_assert_uint_eq(app.sym.thr_rn_valid, 0U);
    ck_assert_uint_eq(app.vote_out.used_mask & CANFDI_VOTE_BIT_MODEL, 0U);
    ck_assert(!app.actmon_out.thr_no_current);
  }
  before_step = NULL;
  (void)loop_step(out);
  ck_assert(app.thr.in_ok);
  ck_assert_uint_eq(canfdi_parity_thr_diag(&app.parity_thr)->resets, resets + 1U);
}
END_TEST

/* The bridge check judges the command the bridge got: an applied -40 V
 * that the measured U_A (about +38 V at 100 rad/s) does not show fails
 * bridge A after
 * bridge_fail_steps samples; an unknown command is never judged. */
START_TEST(test_set_applied_dcm_command_judged_or_not)
{
  canfdi_tx_frame_t out[CANFDI_APP_MAX_TX];
  uint32_t k;
  loop_start(fault_free_scn);
  loop_run(1500U);
  ck_assert(app.fb.mgr.dcm.enable);
  before_step = give_applied;
  applied = (canfdi_app_applied_t){0};
  applied.dcm_known = false;
  applied.thr_known = true;
  applied.thr_ref_known = true;
  for (k = 0U; k < 100U; k++) {
    applied.thr = app.fb.mgr.thr;
    (void)loop_step(out);
    ck_assert(!app.actmon_out.dcm_uac_valid);
  }
  ck_assert(!app.actmgr.bridge_failed[0]);
  applied.dcm_known = true;
  applied.dcm.enable = true;
  applied.dcm.bridge = CANFDI_ACTMGR_BRIDGE_A;
  applied.dcm.u_cmd_V_q16 = -40 * 65536;
  for (k = 0U; (k < 10U) && !app.actmgr.bridge_failed[0]; k++) {
    applied.thr = app.fb.mgr.thr;
    (void)loop_step(out);
  }
  ck_assert(app.actmgr.bridge_failed[0]);
  ck_assert_uint_eq(k, cal.actmgr.dcm_bridge_fail_steps);
}
END_TEST

/* A jammed valve (tests/sil/scenarios/thr_jammed.scn, with a setpoint step
 * of 30 deg after the jam): with the reference known the tracking monitor
 * sees the valve lag behind its slowest healthy trajectory (the model rule
 * names the jam first, at about 69 ms, before the filtered lag reaches its
 * threshold); with the reference unknown the monitor is not judged: no lag,
 * never "not following" (the model rule may still name the jam). */
START_TEST(test_set_applied_ref_unknown_silences_tracking)
{
  static const char *const jam_scn =
      "duration 5\nseed 113\nnoise dcm_ua 0.05\nnoise dcm_ia 0.02\nnoise dcm_speed 0.2\n"
      "noise thr_tps1 0.003\nnoise thr_tps2 0.003\nnoise thr_i 0.01\ninit dcm_winding 52.3\n"
      "speed const 100\nload const 1.2\nangle const 25\nangle sine 1 5 8 0.5\nangle step 3.02 30\n"
      "fault 3 thr_jammed abrupt 1\n";
  canfdi_tx_frame_t out[CANFDI_APP_MAX_TX];
  uint32_t k;
  int32_t lag_max = 0;
  loop_start(jam_scn);
  for (k = 0U; k < 3600U; k++) {
    (void)loop_step(out);
    lag_max = (app.actmon_out.thr_track_err_rad_q16 > lag_max) ? app.actmon_out.thr_track_err_rad_q16 : lag_max;
  }
  ck_assert_int_gt(lag_max, cal.actmon.track_thr_rad_q16 / 4);
  loop_start(jam_scn);
  before_step = give_applied;
  for (k = 0U; k < 3600U; k++) {
    applied.dcm_known = true;
    applied.dcm = app.fb.mgr.dcm;
    applied.thr_known = true;
    applied.thr = app.fb.mgr.thr;
    applied.thr_ref_known = false;
    (void)loop_step(out);
    ck_assert_int_eq(app.actmon_out.thr_track_err_rad_q16, 0);
    ck_assert_uint_eq(app.sym.flags & CANFDI_SYM_F_THR_NOT_FOLLOWING, 0U);
  }
}
END_TEST

static Suite *make_suite(void)
{
  Suite *s = suite_create("app_regress");
  TCase *tc = tcase_create("long_operation");
  tcase_set_timeout(tc, 120);
  tcase_add_test(tc, test_dtc_round_robin_past_2_32_steps);
  tcase_add_test(tc, test_estimator_restart_independent_of_counters);
  tcase_add_test(tc, test_models_hold_after_a_late_or_rejected_frame);
  suite_add_tcase(s, tc);
  tc = tcase_create("startup");
  tcase_add_test(tc, test_startup_hold_off_is_what_the_manager_applied);
  suite_add_tcase(s, tc);
  tc = tcase_create("setpoints");
  tcase_set_timeout(tc, 120);
  tcase_add_test(tc, test_setpoint_supervision_safe_reaction);
  suite_add_tcase(s, tc);
  tc = tcase_create("replay");
  tcase_set_timeout(tc, 120);
  tcase_add_test(tc, test_set_applied_own_commands_change_nothing);
  tcase_add_test(tc, test_set_applied_thr_unknown_stops_throttle_models);
  tcase_add_test(tc, test_set_applied_dcm_command_judged_or_not);
  tcase_add_test(tc, test_set_applied_ref_unknown_silences_tracking);
  suite_add_tcase(s, tc);
  return s;
}

CANFDI_UNIT_MAIN(make_suite)
