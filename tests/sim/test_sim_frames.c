/*
 * test_sim_frames.c — the plant's frames (host_sim/canfdi_sim_frames.h)
 * read back by the ECU side: the firmware codec (firmware/comm/gen/
 * canfdi_msg.h) and the E2E receiver (firmware/comm/canfdi_e2e.h). Healthy
 * frames must be accepted with the values sent; every communication fault
 * must produce exactly the E2E/codec symptom it names.
 */
#include <check.h>
#include <math.h>
#include <string.h>

#include "canfdi_sim.h"
#include "canfdi_sim_frames.h"
#include "comm/canfdi_e2e.h"
#include "comm/gen/canfdi_msg.h"
#include "core/canfdi_common.h"
#include "gen/canfdi_faults.h"
#include "unit_main.h"

typedef struct {
  canfdi_sim_frame_t dcm[60];
  bool dcm_sent[60];
  canfdi_sim_frame_t thr[60];
  bool thr_sent[60];
  unsigned status_frames;
} capture_t;

/* 60 steps with an optional fault on [20 ms, 40 ms). */
static void capture(int fault_id, capture_t *cap)
{
  static canfdi_sim_t sim;
  canfdi_sim_cfg_t cfg;
  canfdi_sim_frames_t fr;
  canfdi_sim_in_t in;
  unsigned k;
  memset(cap, 0, sizeof *cap);
  canfdi_sim_default_cfg(&cfg);
  ck_assert_int_eq(canfdi_sim_init(&sim, &cfg), CANFDI_OK);
  if (fault_id >= 0) {
    canfdi_sim_fault_spec_t s;
    /* intermittent with period 40 ms, duty 0.5 from 20 ms: on 20..39 ms,
     * off 40..59 ms (the next on-phase starts after the capture) */
    ck_assert_int_eq(canfdi_sim_fault_spec_make(&s, (uint8_t)fault_id, CANFDI_SIM_MODE_INTERMITTENT,
                                                0.020, 1.0, 0.0, 0.040, 0.5),
                     CANFDI_OK);
    ck_assert_int_eq(canfdi_sim_add_fault(&sim, &s), CANFDI_OK);
  }
  canfdi_sim_frames_init(&fr, (uint8_t)CANFDI_SIM_MODE_OFFLINE);
  in.dcm.u_cmd_V = 24.0;
  in.dcm.bridge = CANFDI_SIM_BRIDGE_A;
  in.dcm.enable = true;
  in.dcm.load_Nm = 0.5;
  in.thr.u_cmd_V = 4.0;
  in.thr.enable = true;
  for (k = 0U; k < 60U; k++) {
    canfdi_sim_frame_t out[CANFDI_SIM_FRAMES_MAX_PER_STEP];
    const size_t n = canfdi_sim_frames_build(&fr, &sim, &in, out);
    size_t i;
    for (i = 0U; i < n; i++) {
      if (out[i].id == CANFDI_MSG_DCM_SENSOR_FRAME_ID) {
        cap->dcm[k] = out[i];
        cap->dcm_sent[k] = true;
      } else if (out[i].id == CANFDI_MSG_THR_SENSOR_FRAME_ID) {
        cap->thr[k] = out[i];
        cap->thr_sent[k] = true;
      } else {
        cap->status_frames++;
      }
    }
    canfdi_sim_step(&sim, &in);
  }
}

START_TEST(healthy_frames_are_accepted_with_their_values)
{
  static canfdi_sim_t sim;
  canfdi_sim_cfg_t cfg;
  canfdi_sim_frames_t fr;
  canfdi_sim_in_t in;
  canfdi_e2e_rx_t rx_dcm;
  canfdi_e2e_rx_t rx_thr;
  unsigned k;
  canfdi_sim_default_cfg(&cfg);
  cfg.sigma[CANFDI_SIM_S_DCM_IA] = 0.05;
  ck_assert_int_eq(canfdi_sim_init(&sim, &cfg), CANFDI_OK);
  canfdi_sim_frames_init(&fr, (uint8_t)CANFDI_SIM_MODE_OFFLINE);
  ck_assert_int_eq(canfdi_e2e_rx_init(&rx_dcm, CANFDI_MSG_DCM_SENSOR_FRAME_ID, 1U), CANFDI_OK);
  ck_assert_int_eq(canfdi_e2e_rx_init(&rx_thr, CANFDI_MSG_THR_SENSOR_FRAME_ID, 1U), CANFDI_OK);
  in.dcm.u_cmd_V = 30.0;
  in.dcm.bridge = CANFDI_SIM_BRIDGE_A;
  in.dcm.enable = true;
  in.dcm.load_Nm = 0.8;
  in.thr.u_cmd_V = 5.0;
  in.thr.enable = true;
  for (k = 0U; k < 300U; k++) {
    canfdi_sim_frame_t out[CANFDI_SIM_FRAMES_MAX_PER_STEP];
    const size_t n = canfdi_sim_frames_build(&fr, &sim, &in, out);
    size_t i;
    ck_assert_uint_eq(n, ((k % 100U) == 0U) ? 3U : 2U);
    for (i = 0U; i < n; i++) {
      if (out[i].id == CANFDI_MSG_DCM_SENSOR_FRAME_ID) {
        struct canfdi_msg_dcm_sensor_t m;
        const int st = canfdi_e2e_check(&rx_dcm, out[i].data, out[i].dlc);
        ck_assert_int_eq(st, (k == 0U) ? CANFDI_E2E_INITIAL : CANFDI_E2E_OK);
        ck_assert_int_eq(canfdi_msg_dcm_sensor_unpack(&m, out[i].data, out[i].dlc), 0);
        ck_assert(canfdi_msg_dcm_sensor_dcm_ia_is_in_range(m.dcm_ia));
        /* raw -> physical with the DBC scaling 0.0075 A, offset -30.72 A:
         * within one DBC LSB below the quantised reading */
        {
          const double ia = ((double)m.dcm_ia * 0.0075) - 30.72;
          const double d = sim.meas.value[CANFDI_SIM_S_DCM_IA] - ia;
          ck_assert_msg((d > -1e-9) && (d < 0.0075 + 1e-9), "I_A %g sent as %g", sim.meas.value[1], ia);
        }
      } else if (out[i].id == CANFDI_MSG_THR_SENSOR_FRAME_ID) {
        struct canfdi_msg_thr_sensor_t m;
        const int st = canfdi_e2e_check(&rx_thr, out[i].data, out[i].dlc);
        ck_assert_int_eq(st, (k == 0U) ? CANFDI_E2E_INITIAL : CANFDI_E2E_OK);
        ck_assert_int_eq(canfdi_msg_thr_sensor_unpack(&m, out[i].data, out[i].dlc), 0);
        ck_assert(canfdi_msg_thr_sensor_thr_tps1_is_in_range(m.thr_tps1));
        ck_assert(canfdi_msg_thr_sensor_thr_tps2_is_in_range(m.thr_tps2));
      } else {
        ck_assert_uint_eq(out[i].id, 0x610U); /* SimPlantStatus, not an ECU frame */
      }
    }
    canfdi_sim_step(&sim, &in);
  }
  ck_assert_uint_eq(fr.diag.sent, 2U * 300U + 3U);
  ck_assert_uint_eq(fr.diag.corrupted, 0U);
}
END_TEST

/* Index of comm fault _i (0..9) in catalogue order: dcm/thr x timeout,
 * counter, crc, length, implausible. */
static const char *const comm_faults[10] = {
    "com_dcm_timeout", "com_thr_timeout", "com_dcm_counter", "com_thr_counter", "com_dcm_crc",
    "com_thr_crc",     "com_dcm_length",  "com_thr_length",  "com_dcm_implausible",
    "com_thr_implausible"};

START_TEST(comm_fault_produces_its_symptom)
{
  const char *name = comm_faults[_i];
  const int id = canfdi_sim_fault_find(name);
  const bool on_dcm = (strncmp(name, "com_dcm", 7U) == 0);
  capture_t *cap = NULL;
  static capture_t c;
  canfdi_e2e_rx_t rx[2];
  unsigned k;
  unsigned f;

  ck_assert_int_ge(id, 0);
  capture(id, &c);
  cap = &c;
  for (f = 0U; f < 2U; f++) {
    ck_assert_int_eq(canfdi_e2e_rx_init(&rx[f], (f == 0U) ? CANFDI_MSG_DCM_SENSOR_FRAME_ID
                                                           : CANFDI_MSG_THR_SENSOR_FRAME_ID,
                                         1U),
                     CANFDI_OK);
  }
  for (k = 0U; k < 60U; k++) {
    const bool active = (k >= 20U) && (k < 40U);
    for (f = 0U; f < 2U; f++) {
      const bool hit = active && (on_dcm == (f == 0U));
      const bool sent = (f == 0U) ? cap->dcm_sent[k] : cap->thr_sent[k];
      const canfdi_sim_frame_t *fr = (f == 0U) ? &cap->dcm[k] : &cap->thr[k];
      int st;
      if (hit && (strstr(name, "timeout") != NULL)) {
        ck_assert_msg(!sent, "%s: frame sent at %u ms", name, k);
        continue;
      }
      ck_assert_msg(sent, "%s: frame %u missing at %u ms", name, f, k);
      st = canfdi_e2e_check(&rx[f], fr->data, fr->dlc);
      if (!hit) {
        /* Healthy frames: usable, except the first one after a counter, CRC
         * or length fault: those frames were sent, so the sender's sequence
         * advanced by 21 while the receiver accepted none (or a repeat), and
         * the first good frame jumps. A dropped frame is never sent and its
         * counter does not advance; implausible frames are valid E2E-wise. */
        if ((k == 40U) && (on_dcm == (f == 0U)) &&
            ((strstr(name, "counter") != NULL) || (strstr(name, "crc") != NULL) ||
             (strstr(name, "length") != NULL))) {
          ck_assert_int_eq(st, CANFDI_E2E_WRONG_SEQUENCE);
        } else {
          ck_assert_msg(canfdi_e2e_status_is_usable(st), "%s: frame %u at %u ms: status %d", name,
                        f, k, st);
        }
      } else if (strstr(name, "counter") != NULL) {
        ck_assert_int_eq(st, CANFDI_E2E_REPEATED);
      } else if (strstr(name, "crc") != NULL) {
        ck_assert_int_eq(st, CANFDI_E2E_WRONG_CRC);
      } else if (strstr(name, "length") != NULL) {
        ck_assert_int_eq(fr->dlc, 7U);
        ck_assert_int_eq(st, CANFDI_E2E_WRONG_LENGTH);
      } else { /* implausible: E2E valid, every measurement raw all ones */
        ck_assert_msg(canfdi_e2e_status_is_usable(st), "implausible frame rejected by E2E: %d", st);
        if (f == 0U) {
          struct canfdi_msg_dcm_sensor_t m;
          ck_assert_int_eq(canfdi_msg_dcm_sensor_unpack(&m, fr->data, fr->dlc), 0);
          ck_assert_uint_eq(m.dcm_ua, 8191U);
          ck_assert_uint_eq(m.dcm_ia, 8191U);
          ck_assert_uint_eq(m.dcm_omega, 8191U);
          ck_assert_uint_eq(m.dcm_usupply, 8191U);
          ck_assert(!canfdi_msg_dcm_sensor_dcm_omega_is_in_range(m.dcm_omega));
        } else {
          struct canfdi_msg_thr_sensor_t m;
          ck_assert_int_eq(canfdi_msg_thr_sensor_unpack(&m, fr->data, fr->dlc), 0);
          ck_assert_uint_eq(m.thr_tps1, 8191U);
          ck_assert_uint_eq(m.thr_tps2, 8191U);
          ck_assert(!canfdi_msg_thr_sensor_thr_tps1_is_in_range(m.thr_tps1));
        }
      }
    }
  }
  ck_assert_uint_eq(cap->status_frames, 1U);
}
END_TEST

static Suite *make_suite(void)
{
  Suite *s = suite_create("sim_frames");
  TCase *tc = tcase_create("healthy");
  tcase_add_test(tc, healthy_frames_are_accepted_with_their_values);
  suite_add_tcase(s, tc);
  tc = tcase_create("comm_faults");
  tcase_add_loop_test(tc, comm_fault_produces_its_symptom, 0, 10);
  suite_add_tcase(s, tc);
  return s;
}

CANFDI_UNIT_MAIN(make_suite)
