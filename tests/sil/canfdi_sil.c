/*
 * canfdi_sil.c — `canfdi-sil`: software-in-the-loop rig. The firmware
 * application (firmware/app/canfdi_app.h) and the host_sim plants run in
 * lockstep in one process and talk only through CAN frames packed and
 * unpacked by codecs generated from dbc/canfdi.dbc:
 *
 *   t_k: scenario setpoints -> SetpointDcm/SetpointThr frames (every 10 ms)
 *        plant sample       -> DcmSensor/ThrSensor (E2E, comm faults) and
 *                              SimPlantStatus frames (host_sim frame builder)
 *        frames the ECU's   -> canfdi_app_rx_frame; canfdi_app_step
 *        kernel filter passes  (setpoints and sensor frames, as on SocketCAN)
 *        ECU frames         -> actuator commands go to the plant; decoded
 *                              with the tester codec, EcuStatus/EcuDtc feed
 *                              the timeline and the expectations
 *        plant steps to t_k+1 with the commands held.
 * The plant/vehicle side of the step is host_sim's canfdi_sim_rig.h, the
 * same code canfdi-sim runs on SocketCAN (HIL), so SIL and HIL lockstep
 * differ only in the transport.
 *
 * Reads the scenario format of host_sim/SCENARIO.md and evaluates its
 * `expect` lines; prints a technician's timeline and one PASS/FAIL line per
 * expectation, plus an implicit check that no trouble code appears that no
 * `expect ... dtc` line names. The ECU-side lines `cycle`, `clear` and
 * `power_cycle` act on the firmware's DTC memory before its step at their
 * time; `dtc_status`/`occurrence` are judged on the last EcuDtc frame of the
 * code at or before t (never reported: the cleared state 0x50), `freeze` on
 * the ECU's memory (SIL only). Exit status 0 all passed, 1 a check failed,
 * 2 usage / scenario error.
 */
/* clock_gettime: the pre-included assert.h fixes the feature macros first,
 * so sil.mk passes -D_POSIX_C_SOURCE for this file as well. */
#ifndef _POSIX_C_SOURCE
#define _POSIX_C_SOURCE 200809L
#endif

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "app/canfdi_app.h"
#include "canfdi_sil_msg.h"
#include "diag/canfdi_nvm.h"
#include "canfdi_sim.h"
#include "canfdi_sim_frames.h"
#include "canfdi_sim_rig.h"
#include "canfdi_sim_scenario.h"
#include "canfdi_sim_uds.h"
#include "canfdi_sim_trace.h"
#include "core/canfdi_common.h"
#include "gen/canfdi_faults.h"

#define EXIT_CHECK 1
#define EXIT_USAGE 2
#define MAX_CODES 64U

typedef struct {
  uint32_t dtc;
  char code[8];
  char desc[160];
} dtc_desc_t;

typedef struct {
  uint32_t dtc;
  uint8_t status;       /* last status seen */
  uint8_t occurrence;   /* DtcOccurrence of the last frame */
  int64_t last_us;      /* time of the last EcuDtc frame of this code, -1 none */
  int64_t since_us;     /* first frame with the current status and occurrence */
  int64_t first_tf_us;  /* first testFailed, -1 never */
  int64_t first_pd_us;  /* first pendingDTC */
  int64_t first_cf_us;  /* first confirmedDTC */
} dtc_seen_t;

static dtc_desc_t descs[MAX_CODES];
static size_t n_descs;
static dtc_seen_t seen[MAX_CODES];
static size_t n_seen;

static const char *deg_name(unsigned s)
{
  static const char *const names[] = {"normal", "degraded", "fail_safe", "fail_silent"};
  return (s < 4U) ? names[s] : "?";
}

/* "P0122" from the 3-byte DTC (SAE J2012 letter coding). */
static void dtc_to_code(uint32_t dtc, char out[8])
{
  static const char letters[] = "PCBU";
  const unsigned hi = (unsigned)((dtc >> 16) & 0xFFU);
  const unsigned lo = (unsigned)((dtc >> 8) & 0xFFU);
  (void)snprintf(out, 8, "%c%u%X%02X", letters[(hi >> 6) & 3U], (hi >> 4) & 3U, hi & 0xFU, lo);
}

static int load_descs(const char *path)
{
  FILE *f = fopen(path, "r");
  char line[512];
  if (f == NULL) {
    return -CANFDI_EINVAL;
  }
  while ((fgets(line, (int)sizeof line, f) != NULL) && (n_descs < MAX_CODES)) {
    char *fields[5];
    char *p = line;
    size_t n = 0U;
    while ((n < 5U) && (p != NULL)) {
      fields[n++] = p;
      p = (n < 5U) ? strchr(p, ',') : NULL;
      if (p != NULL) {
        *p++ = '\0';
      }
    }
    if ((n == 5U) && (strncmp(fields[1], "0x", 2) == 0)) {
      dtc_desc_t *d = &descs[n_descs++];
      char *nl = strchr(fields[4], '\n');
      if (nl != NULL) {
        *nl = '\0';
      }
      d->dtc = (uint32_t)strtoul(fields[1], NULL, 16);
      (void)snprintf(d->code, sizeof d->code, "%s", fields[0]);
      (void)snprintf(d->desc, sizeof d->desc, "%s", fields[4]);
    }
  }
  (void)fclose(f);
  return CANFDI_OK;
}

static const char *dtc_desc(uint32_t dtc)
{
  size_t i;
  for (i = 0U; i < n_descs; i++) {
    if (descs[i].dtc == dtc) {
      return descs[i].desc;
    }
  }
  return "";
}

static dtc_seen_t *seen_get(uint32_t dtc)
{
  size_t i;
  for (i = 0U; i < n_seen; i++) {
    if (seen[i].dtc == dtc) {
      return &seen[i];
    }
  }
  if (n_seen < MAX_CODES) {
    dtc_seen_t *s = &seen[n_seen++];
    s->dtc = dtc;
    s->status = 0U;
    s->occurrence = 0U;
    s->last_us = -1;
    s->since_us = -1;
    s->first_tf_us = -1;
    s->first_pd_us = -1;
    s->first_cf_us = -1;
    return s;
  }
  return NULL;
}

static uint32_t code_to_dtc(const char *code)
{
  size_t i;
  for (i = 0U; i < n_descs; i++) {
    if (strcmp(descs[i].code, code) == 0) {
      return descs[i].dtc;
    }
  }
  return 0U;
}


/* ------------------------------------------------ ECU-side actions (SIL) */

/* The ECU's NVM in RAM: two banks behind the canfdi_nvm port, flash
 * semantics (erase to 0xFF; programming only clears bits), so a power_cycle
 * goes through the same store/load path as canfdi-ecu --nvm. */
#define SIL_NVM_BANK_BYTES 1024U
static uint8_t sil_nvm_mem[2][SIL_NVM_BANK_BYTES];

static int32_t sil_nvm_read(void *ctx, uint8_t bank, uint32_t off, uint8_t *buf, uint32_t len)
{
  (void)ctx;
  memcpy(buf, &sil_nvm_mem[bank][off], len);
  return CANFDI_OK;
}

static int32_t sil_nvm_write(void *ctx, uint8_t bank, uint32_t off, const uint8_t *buf, uint32_t len)
{
  uint32_t i;
  (void)ctx;
  for (i = 0U; i < len; i++) {
    sil_nvm_mem[bank][off + i] &= buf[i];
  }
  return CANFDI_OK;
}

static int32_t sil_nvm_erase(void *ctx, uint8_t bank)
{
  (void)ctx;
  memset(sil_nvm_mem[bank], 0xFF, SIL_NVM_BANK_BYTES);
  return CANFDI_OK;
}

static const canfdi_nvm_port_t sil_nvm_port = {NULL, sil_nvm_read, sil_nvm_write, sil_nvm_erase,
                                               SIL_NVM_BANK_BYTES, 8U};
static canfdi_nvm_t sil_nvm;

/* "TF=1,PDTC=0" for the bits in mask, values from v (bit order). */
static void bits_text(uint8_t mask, uint8_t v, char *out, size_t cap)
{
  unsigned b;
  size_t n = 0U;
  out[0] = '\0';
  for (b = 0U; b < 8U; b++) {
    if ((((unsigned)mask >> b) & 1U) != 0U) {
      const int w = snprintf(out + n, cap - n, "%s%s=%u", (n > 0U) ? "," : "",
                             canfdi_sim_status_bit_name(b), ((unsigned)v >> b) & 1U);
      n = ((w > 0) && ((size_t)w < (cap - n))) ? (n + (size_t)w) : (cap - 1U);
    }
  }
}

/* Freeze-frame signal in the scenario's unit (CANFDI_SIM_FF_*). */
static double ff_value(const canfdi_dtc_ff_t *ff, unsigned signal)
{
  static const double q16 = 1.0 / 65536.0;
  double v = 0.0;
  switch (signal) {
  case CANFDI_SIM_FF_TIME: v = (double)ff->time_ms * 1e-3; break;
  case CANFDI_SIM_FF_DCM_SPEED: v = (double)ff->omega_q16 * q16; break;
  case CANFDI_SIM_FF_DCM_IA: v = (double)ff->ia_q16 * q16; break;
  case CANFDI_SIM_FF_DCM_UA: v = (double)ff->ua_q16 * q16; break;
  case CANFDI_SIM_FF_THR_ANGLE: v = (double)ff->thr_angle_q16 * q16 * (180.0 / 3.14159265358979323846); break;
  case CANFDI_SIM_FF_DCM_SUPPLY: v = (double)ff->supply_q16 * q16; break;
  case CANFDI_SIM_FF_DEG_DCM: v = (double)ff->deg_dcm; break;
  default: v = (double)ff->deg_thr; break;
  }
  return v;
}

static void usage(FILE *out)
{
  fprintf(out,
          "Usage: canfdi-sil -s SCENARIO [options]\n"
          "\n"
          "Software in the loop: the canfdi firmware application against the host_sim\n"
          "plants in one process, in lockstep at 1 ms, through the DBC codecs (frames,\n"
          "not shared variables). Prints the trouble-code timeline and checks the\n"
          "scenario's `expect` lines (host_sim/SCENARIO.md).\n"
          "\n"
          "Options:\n"
          "  -s, --scenario FILE   scenario (host_sim/SCENARIO.md format)\n"
          "  -o, --output FILE     CSV trace of setpoints, responses, residuals, estimates\n"
          "  -D, --decimate N      write every N-th step to the trace (default 1)\n"
          "  -l, --log FILE        candump -L log of every frame on the bus\n"
          "  -c, --channel NAME    channel name in the log (default vcan0)\n"
          "  -t, --dtcs FILE       DTC descriptions (default dbc/dtcs.csv)\n"
          "      --seed N          override the scenario's noise seed\n"
          "      --test-signals M  the ECU's test signals (calibration, canfdi_app_cal.h):\n"
          "                        on     the product calibration: bursts where enabled (default)\n"
          "                        off    suppressed: excite_dcm_on = excite_thr_on = false; the\n"
          "                               schedulers still run, nothing is added to a reference\n"
          "                        always the former permanent dither: a burst wherever the loop\n"
          "                               runs closed in normal degradation (windows and schedulers\n"
          "                               widened), for comparison\n"
          "      --responses FILE  per step one 17-byte record, host byte order: the plant's\n"
          "                        speed (double, rad/s) and valve angle (double, rad) at the\n"
          "                        step, then a flag byte: bit 0 / 1 DC-motor / throttle burst\n"
          "                        on (scheduler ON), bit 2 / 3 DC-motor / throttle excitation\n"
          "                        applied (generator gated on), bit 4 / 5 DC-motor / throttle\n"
          "                        setpoint inside the product's enabling window\n"
          "                        (make bench-driveability)\n"
          "      --timing          wall-clock time of canfdi_app_step: mean and max\n"
          "      --symptoms[=MS]   print the symptom vector every MS ms (default 100) on stderr\n"
          "      --sizes           print the firmware's RAM use and exit\n"
          "      --nvm-in FILE     power up with the DTC memory image in FILE (the bytes\n"
          "                        --nvm-out wrote: the previous drive's memory)\n"
          "      --nvm-out FILE    at the end, power down and write the DTC memory image\n"
          "  -q, --quiet           only the verdict lines\n"
          "  -h, --help            this text\n"
          "\n"
          "Examples:\n"
          "  canfdi-sil -s tests/sil/scenarios/thr_tps1_open.scn\n"
          "  canfdi-sil -s tests/sil/scenarios/demo.scn -o trace.csv -D 5 -l bus.log\n"
          "\n"
          "Exit status: 0 every expectation met, 1 an expectation failed, 2 usage error.\n");
}

static void log_frame(FILE *log, const char *ch, int64_t t_us, uint32_t id, const uint8_t *data,
                      uint8_t dlc)
{
  canfdi_sim_frame_t fr;
  if (log != NULL) {
    fr.id = id;
    fr.dlc = dlc;
    memcpy(fr.data, data, 8U);
    (void)canfdi_sim_trace_candump(log, ch, 0, t_us, &fr);
  }
}

typedef struct {
  struct canfdi_sil_msg_ecu_status_t status;
  struct canfdi_sil_msg_ecu_residual_dcm_t res_dcm;
  struct canfdi_sil_msg_ecu_residual_thr_t res_thr;
  struct canfdi_sil_msg_ecu_param_dcm_t prm_dcm;
  struct canfdi_sil_msg_ecu_param_thr_t prm_thr;
  bool have_status;
} ecu_view_t;

static canfdi_app_t app;  /* the firmware's whole state, as on a target */
static canfdi_sim_scn_t scn;
static canfdi_sim_t sim;
static canfdi_sim_rig_t rig; /* the plant/vehicle side of a step (shared with HIL) */
static canfdi_sim_uds_tester_t tester; /* the scenario's `uds` lines */

/* The tester's frame of this step, if any, packed by the codec and handed
 * to the ECU (the ECU's socket passes 0x7E0 and 0x7DF). */
static void tester_send(FILE *log, const char *channel, int64_t t_us)
{
  bool functional = false;
  uint8_t b[8];
  if (canfdi_sim_uds_tester_tx(&tester, t_us, &functional, b)) {
    uint8_t data[8];
    uint64_t v = 0U;
    uint32_t id;
    for (unsigned i = 0U; i < 8U; i++) {
      v = (v << 8) | b[i];
    }
    if (functional) {
      struct canfdi_sil_msg_uds_func_req_t m = {v};
      (void)canfdi_sil_msg_uds_func_req_pack(data, &m, sizeof data);
      id = CANFDI_SIL_MSG_UDS_FUNC_REQ_FRAME_ID;
    } else {
      struct canfdi_sil_msg_uds_phys_req_t m = {v};
      (void)canfdi_sil_msg_uds_phys_req_pack(data, &m, sizeof data);
      id = CANFDI_SIL_MSG_UDS_PHYS_REQ_FRAME_ID;
    }
    (void)canfdi_app_rx_frame(&app, id, data, 8U, (uint32_t)t_us);
    log_frame(log, channel, t_us, id, data, 8U);
  }
}

/* An ECU frame for the tester: UdsPhysResp, unpacked by the codec. */
static void tester_receive(const canfdi_tx_frame_t *f, int64_t t_us)
{
  struct canfdi_sil_msg_uds_phys_resp_t m;
  if (canfdi_sil_msg_uds_phys_resp_unpack(&m, f->data, f->dlc) == 0) {
    uint8_t b[8];
    for (unsigned i = 0U; i < 8U; i++) {
      b[i] = (uint8_t)(m.uds_phys_resp_data >> (8U * (7U - i)));
    }
    canfdi_sim_uds_tester_rx(&tester, t_us, b);
  }
}

/* What the ECU's SocketCAN filter passes to the application (HIL contract):
 * the setpoints and the sensor frames, not SimPlantStatus. */
static bool ecu_filter_passes(uint32_t id)
{
  return (id == CANFDI_SIL_MSG_DCM_SENSOR_FRAME_ID) || (id == CANFDI_SIL_MSG_THR_SENSOR_FRAME_ID) ||
         (id == CANFDI_SIL_MSG_SETPOINT_DCM_FRAME_ID) || (id == CANFDI_SIL_MSG_SETPOINT_THR_FRAME_ID);
}

/* One ECU-side action of the scenario (cycle, clear, power_cycle) on the
 * firmware's own state, before its step at now_us. Returns 0, or -1 with
 * msg filled when the firmware refused it (a rig failure). */
static int apply_action(const canfdi_sim_action_t *a, const canfdi_app_cal_t *cal, uint32_t now_us,
                        bool quiet, char *msg, size_t cap)
{
  int rc = 0;
  msg[0] = '\0';
  if (a->kind == (uint8_t)CANFDI_SIM_ACT_CYCLE) {
    if (canfdi_app_new_cycle(&app) != CANFDI_OK) {
      (void)snprintf(msg, cap, "cycle at %.3f s: the DTC memory refused cycle_end/cycle_start",
                     (double)a->t_us * 1e-6);
      rc = -1;
    } else if (!quiet) {
      printf("  %8.3f  ecu: operation cycle ends, a new one starts (ignition off/on)\n",
             (double)now_us * 1e-6);
    }
  } else if (a->kind == (uint8_t)CANFDI_SIM_ACT_CLEAR) {
    const uint32_t group = (a->code[0] != '\0') ? code_to_dtc(a->code) : CANFDI_DTC_GROUP_ALL;
    if (canfdi_app_clear_dtc(&app, group) != CANFDI_OK) {
      (void)snprintf(msg, cap, "clear %s at %.3f s: refused by the DTC memory",
                     (a->code[0] != '\0') ? a->code : "all", (double)a->t_us * 1e-6);
      rc = -1;
    } else if (!quiet) {
      printf("  %8.3f  ecu: ClearDiagnosticInformation %s\n", (double)now_us * 1e-6,
             (a->code[0] != '\0') ? a->code : "(all groups)");
    }
  } else {
    /* power_cycle: the application's power-down (end the cycle, the image
     * to store), the store and load through the NVM port as canfdi-ecu
     * --nvm does it, and a cold start with the loaded image */
    static uint8_t img[CANFDI_APP_IMAGE_MAX_BYTES];
    int32_t n = canfdi_app_power_down(&app, img, (uint32_t)sizeof img);
    if ((n < 0) || (canfdi_nvm_store(&sil_nvm, img, (uint32_t)n) != CANFDI_OK)) {
      (void)snprintf(msg, cap, "power_cycle at %.3f s: storing the DTC memory failed",
                     (double)a->t_us * 1e-6);
      rc = -1;
    } else {
      int32_t up;
      memset(img, 0, sizeof img);
      n = canfdi_nvm_load(&sil_nvm, img, (uint32_t)sizeof img);
      up = (n >= 0) ? canfdi_app_power_up(&app, cal, now_us, img, (uint32_t)n) : -CANFDI_EIO;
      if (up != CANFDI_OK) {
        (void)snprintf(msg, cap, "power_cycle at %.3f s: %s (%d)", (double)a->t_us * 1e-6,
                       (up == CANFDI_APP_IMAGE_REJECTED) ? "the DTC image was rejected"
                                                         : "loading the DTC memory failed",
                       (int)n);
        rc = -1;
      } else if (!quiet) {
        printf("  %8.3f  ecu: power cycle (DTC memory stored to NVM, %d bytes, application "
               "restarted, memory loaded)\n", (double)now_us * 1e-6, (int)n);
      }
    }
  }
  return rc;
}

/* dtc_status, occurrence, freeze: judged once the run has passed t (every
 * frame at or before t seen). dtc_status/occurrence from the last EcuDtc
 * frame of the code; freeze from the ECU's DTC memory (SIL only). */
static bool is_state_expect(const canfdi_sim_expect_t *e)
{
  return (strcmp(e->kind, "dtc_status") == 0) || (strcmp(e->kind, "occurrence") == 0) ||
         (strcmp(e->kind, "freeze") == 0);
}

static int judge_state(const canfdi_sim_expect_t *e, char *msg, size_t cap)
{
  const uint32_t dtc = code_to_dtc(e->arg1);
  const dtc_seen_t *s = NULL;
  char src[48];
  size_t q;
  int ok = 0;
  for (q = 0U; q < n_seen; q++) {
    if ((seen[q].dtc == dtc) && (seen[q].last_us >= 0)) {
      s = &seen[q];
    }
  }
  if (s != NULL) {
    (void)snprintf(src, sizeof src, "reported since %.3f s", (double)s->since_us * 1e-6);
  } else {
    (void)snprintf(src, sizeof src, "never reported: cleared state assumed");
  }
  if (strcmp(e->kind, "dtc_status") == 0) {
    const uint8_t st = (s != NULL) ? s->status : (uint8_t)CANFDI_DTC_STATUS_CLEARED;
    char got[64];
    char want[64];
    bits_text(e->st_mask, st, got, sizeof got);
    bits_text(e->st_mask, e->st_value, want, sizeof want);
    ok = ((st & e->st_mask) == e->st_value) ? 1 : 0;
    /* formatted whole (at most ~540 bytes by gcc's count), then cut to cap:
     * -O2's -Wformat-truncation rejects a direct snprintf into cap */
    char whole[640];
    size_t n;
    (void)snprintf(whole, sizeof whole, "dtc_status %s at %.3f s: %s (expected %s) [0x%02X %s]", e->arg1, e->t_s,
                   got, want, (unsigned)st, src);
    n = strlen(whole);
    if ((cap > 0U) && (msg != NULL)) {
      n = (n < cap) ? n : (cap - 1U);
      (void)memcpy(msg, whole, n);
      msg[n] = '\0';
    }
  } else if (strcmp(e->kind, "occurrence") == 0) {
    const unsigned occ = (s != NULL) ? s->occurrence : 0U;
    ok = ((unsigned)llround(e->lo) == occ) ? 1 : 0;
    (void)snprintf(msg, cap, "occurrence %s at %.3f s: %u (expected %.0f) [%s]", e->arg1, e->t_s, occ,
                   e->lo, src);
  } else {
    canfdi_dtc_record_t rec;
    const int32_t rc = canfdi_dtc_read_record(canfdi_app_dtc(&app), dtc, &rec);
    if ((rc == CANFDI_OK) && rec.ff_valid) {
      const double v = ff_value(&rec.ff, e->ff_signal);
      ok = ((v >= e->lo) && (v <= e->hi)) ? 1 : 0;
      (void)snprintf(msg, cap, "freeze %s %s at %.3f s: %.6g (expected %g..%g; frame of %.3f s)", e->arg1,
                     e->arg2, e->t_s, v, e->lo, e->hi, (double)rec.ff.time_ms * 1e-3);
    } else {
      (void)snprintf(msg, cap, "freeze %s %s at %.3f s: no freeze frame (no event-memory entry)", e->arg1,
                     e->arg2, e->t_s);
    }
  }
  return ok;
}

/* The diagnosis' persistent symptom per channel (+ - 0, '?' not valid) and
 * the operating-point reference signs, one line on stderr (--symptoms). */
static void print_diag_symptoms(const canfdi_diagnosis_t *d)
{
  static const char mark[4] = {'-', '0', '+', '?'};
  char line[2][CANFDI_DIAG_N_CH + 1U];
  uint8_t c;
  uint8_t ch;
  for (c = 0U; c < 2U; c++) {
    for (ch = 0U; ch < CANFDI_DIAG_N_CH; ch++) {
      const int8_t v = canfdi_diagnosis_symptom(d, (c == 0U) ? CANFDI_COMPONENT_DC_MOTOR : CANFDI_COMPONENT_THROTTLE, ch);
      line[c][ch] = mark[(v >= -1) && (v <= 2) ? v + 1 : 3];
    }
    line[c][CANFDI_DIAG_N_CH] = '\0';
  }
  fprintf(stderr, "       sym dcm %.4s %.4s %.2s ref %+d%+d | thr %.4s %.4s ref %+d%+d\n", line[0], &line[0][4],
          &line[0][8], d->ref[CANFDI_DIAG_COMP_DCM][0], d->ref[CANFDI_DIAG_COMP_DCM][1], line[1], &line[1][4],
          d->ref[CANFDI_DIAG_COMP_THR][0], d->ref[CANFDI_DIAG_COMP_THR][1]);
}

/* --test-signals: the ECU's test signals through its calibration only (no
 * firmware logic is changed). "off" clears the switches the calibration
 * has for it (excite_dcm_on / excite_thr_on, "the test signal may run at
 * all"): the schedulers keep running on the same inputs, the generators
 * keep their time-only sequence, nothing is added to a reference. Until a
 * burst would start, an "off" run is bit-identical to an "on" run.
 * "always": the schedulers' enabling windows span every reference, a
 * LACK burst is due after one step and lasts for ever, no rest: the
 * previous permanent dither wherever the loop runs closed in normal
 * degradation. Returns 0, or -1 for an unknown mode. */
static int apply_test_signals(canfdi_app_cal_t *cal, const char *mode)
{
  int rc = 0;
  if (strcmp(mode, "on") == 0) {
    /* the product calibration as it is */
  } else if (strcmp(mode, "off") == 0) {
    cal->excite_dcm_on = false;
    cal->excite_thr_on = false;
  } else if (strcmp(mode, "always") == 0) {
    canfdi_testsched_cfg_t *c[2] = {&cal->test.dcm, &cal->test.thr};
    size_t j;
    for (j = 0U; j < 2U; j++) {
      c[j]->lack_steps = 1U;
      c[j]->burst_steps = UINT32_MAX;
      c[j]->need_max_steps = UINT32_MAX;
      c[j]->rest_steps = 0U;
      c[j]->keyon = true;
    }
    cal->test.dcm_w_min_rad_s_q16 = 0;
    cal->test.dcm_w_max_rad_s_q16 = INT32_MAX;
    cal->test.thr_min_rad_q16 = INT32_MIN;
    cal->test.thr_max_rad_q16 = INT32_MAX;
    cal->excite_dcm_on = true;
    cal->excite_thr_on = true;
  } else {
    rc = -1;
  }
  return rc;
}

/* --responses: one 17-byte record of this step (see usage()); the window
 * bits against the product calibration's enabling windows (cal), whatever
 * --test-signals made of the firmware's. */
static int write_response(FILE *f, const canfdi_app_cal_t *cal, const canfdi_sim_trace_sp_t *sp)
{
  uint8_t rec[17];
  const double w = sim.dcm.w_rad_s;
  const double th = sim.thr.theta_rad;
  const double sp_w = fabs(sp->speed_rad_s);
  const double sp_th = sp->angle_deg * (3.14159265358979323846 / 180.0);
  uint8_t fl = 0U;
  fl |= (app.test.dcm.phase == CANFDI_TESTSCHED_ON) ? 0x01U : 0U;
  fl |= (app.test.thr.phase == CANFDI_TESTSCHED_ON) ? 0x02U : 0U;
  fl |= canfdi_excite_active(&app.excite_dcm) ? 0x04U : 0U;
  fl |= canfdi_excite_active(&app.excite_thr) ? 0x08U : 0U;
  fl |= ((sp_w >= (double)cal->test.dcm_w_min_rad_s_q16 / 65536.0) &&
         (sp_w <= (double)cal->test.dcm_w_max_rad_s_q16 / 65536.0)) ? 0x10U : 0U;
  fl |= ((sp_th >= (double)cal->test.thr_min_rad_q16 / 65536.0) &&
         (sp_th <= (double)cal->test.thr_max_rad_q16 / 65536.0)) ? 0x20U : 0U;
  memcpy(&rec[0], &w, 8U);
  memcpy(&rec[8], &th, 8U);
  rec[16] = fl;
  return (fwrite(rec, sizeof rec, 1U, f) == 1U) ? 0 : -1;
}

int main(int argc, char **argv)
{
  const char *scn_path = NULL;
  const char *out_path = NULL;
  const char *log_path = NULL;
  const char *dtcs_path = "dbc/dtcs.csv";
  const char *channel = "vcan0";
  const char *test_signals = "on";
  const char *resp_path = NULL;
  FILE *resp = NULL;
  unsigned long decimate = 1UL;
  bool quiet = false;
  bool symptoms = false;
  unsigned long sym_every = 100UL;
  bool timing = false;
  double step_ns_sum = 0.0;
  double step_ns_max = 0.0;
  bool have_seed = false;
  unsigned long long seed = 0ULL;
  const char *nvm_in = NULL;
  const char *nvm_out = NULL;
  canfdi_sim_scn_err_t err;
  canfdi_app_cal_t cal;
  canfdi_app_cal_t product_cal;
  const canfdi_sim_in_t *in = &rig.in;
  const canfdi_sim_trace_sp_t *sp = &rig.sp;
  ecu_view_t ecu;
  FILE *out = NULL;
  FILE *log = NULL;
  uint64_t n_steps;
  uint64_t k;
  size_t i;
  int failures = 0;
  bool expect_done[CANFDI_SIM_SCN_MAX_EXPECT];
  int expect_ok[CANFDI_SIM_SCN_MAX_EXPECT];
  char expect_msg[CANFDI_SIM_SCN_MAX_EXPECT][200];
  size_t next_action = 0U;
  unsigned last_deg[2] = {0U, 0U};
  unsigned last_bridge = 1U;
  bool last_thr_en = true;
  int64_t t_fault_us = -1;

  for (i = 1U; i < (size_t)argc; i++) {
    const char *a = argv[i];
    const char *v = ((i + 1U) < (size_t)argc) ? argv[i + 1U] : NULL;
    if ((strcmp(a, "-h") == 0) || (strcmp(a, "--help") == 0)) {
      usage(stdout);
      return EXIT_SUCCESS;
    } else if ((strcmp(a, "-q") == 0) || (strcmp(a, "--quiet") == 0)) {
      quiet = true;
    } else if (strcmp(a, "--timing") == 0) {
      timing = true;
    } else if (strcmp(a, "--symptoms") == 0) {
      symptoms = true;
    } else if (strncmp(a, "--symptoms=", 11) == 0) {
      char *end = NULL;
      sym_every = strtoul(a + 11, &end, 10);
      if ((end == (a + 11)) || (*end != '\0') || (sym_every == 0UL) || (sym_every > 60000UL)) {
        fprintf(stderr, "canfdi-sil: --symptoms=MS wants 1..60000 ms, not '%s'\n", a + 11);
        return 2;
      }
      symptoms = true;
    } else if (strcmp(a, "--sizes") == 0) {
      printf("sizeof(canfdi_app_t) = %zu bytes (host; the target figure is in the .bss of "
             "make firmware)\n",
             sizeof(canfdi_app_t));
      printf("  of which the diagnostic server sizeof(canfdi_uds_t) = %zu, its ISO-TP "
             "sizeof(canfdi_isotp_t) = %zu\n",
             sizeof(canfdi_uds_t), sizeof(canfdi_isotp_t));
      return EXIT_SUCCESS;
    } else if (v == NULL) {
      fprintf(stderr, "canfdi-sil: unknown option or missing value '%s'\nTry 'canfdi-sil --help'.\n",
              a);
      return EXIT_USAGE;
    } else if ((strcmp(a, "-s") == 0) || (strcmp(a, "--scenario") == 0)) {
      scn_path = v;
      i++;
    } else if ((strcmp(a, "-o") == 0) || (strcmp(a, "--output") == 0)) {
      out_path = v;
      i++;
    } else if ((strcmp(a, "-l") == 0) || (strcmp(a, "--log") == 0)) {
      log_path = v;
      i++;
    } else if ((strcmp(a, "-c") == 0) || (strcmp(a, "--channel") == 0)) {
      channel = v;
      i++;
    } else if ((strcmp(a, "-t") == 0) || (strcmp(a, "--dtcs") == 0)) {
      dtcs_path = v;
      i++;
    } else if ((strcmp(a, "-D") == 0) || (strcmp(a, "--decimate") == 0)) {
      decimate = strtoul(v, NULL, 10);
      if ((decimate == 0UL) || (decimate > 1000000UL)) {
        fprintf(stderr, "canfdi-sil: --decimate must be 1..1000000\n");
        return EXIT_USAGE;
      }
      i++;
    } else if (strcmp(a, "--test-signals") == 0) {
      test_signals = v;
      i++;
    } else if (strcmp(a, "--responses") == 0) {
      resp_path = v;
      i++;
    } else if (strcmp(a, "--seed") == 0) {
      seed = strtoull(v, NULL, 10);
      have_seed = true;
      i++;
    } else if (strcmp(a, "--nvm-in") == 0) {
      nvm_in = v;
      i++;
    } else if (strcmp(a, "--nvm-out") == 0) {
      nvm_out = v;
      i++;
    } else {
      fprintf(stderr, "canfdi-sil: unknown option '%s'\nTry 'canfdi-sil --help'.\n", a);
      return EXIT_USAGE;
    }
  }
  if (scn_path == NULL) {
    fprintf(stderr, "canfdi-sil: no scenario given (-s FILE)\nTry 'canfdi-sil --help'.\n");
    return EXIT_USAGE;
  }
  if (load_descs(dtcs_path) != CANFDI_OK) {
    fprintf(stderr, "canfdi-sil: cannot read %s: %s\n", dtcs_path, strerror(errno));
    return EXIT_USAGE;
  }
  if (canfdi_sim_scn_load(&scn, scn_path, &err) != CANFDI_OK) {
    fprintf(stderr, "canfdi-sil: %s\n", err.msg);
    return EXIT_USAGE;
  }
  if (have_seed) {
    scn.cfg.seed = (uint64_t)seed;
  }
  if (canfdi_sim_scn_setup(&scn, &sim) != CANFDI_OK) {
    fprintf(stderr, "canfdi-sil: %s: cannot set up the plant\n", scn_path);
    return EXIT_USAGE;
  }
  canfdi_app_default_cal(&cal);
  product_cal = cal;
  if (apply_test_signals(&cal, test_signals) != 0) {
    fprintf(stderr, "canfdi-sil: --test-signals wants on, off or always, not '%s'\n", test_signals);
    return EXIT_USAGE;
  }
  if (nvm_in != NULL) {
    /* a cold start with the memory the previous drive stored (a vehicle's
     * next drive); the image is the bytes of canfdi_app_power_down */
    static uint8_t img_in[CANFDI_APP_IMAGE_MAX_BYTES];
    FILE *f = fopen(nvm_in, "rb");
    size_t n_in;
    int32_t up;
    if (f == NULL) {
      fprintf(stderr, "canfdi-sil: cannot read %s: %s\n", nvm_in, strerror(errno));
      return EXIT_USAGE;
    }
    n_in = fread(img_in, 1U, sizeof img_in, f);
    (void)fclose(f);
    up = canfdi_app_power_up(&app, &cal, 0U, img_in, (uint32_t)n_in);
    if (up == CANFDI_APP_IMAGE_REJECTED) {
      fprintf(stderr, "canfdi-sil: %s: the DTC memory image was rejected\n", nvm_in);
      return EXIT_USAGE;
    }
    if (up != CANFDI_OK) {
      fprintf(stderr, "canfdi-sil: the firmware refused its calibration\n");
      return EXIT_USAGE;
    }
  } else if (canfdi_app_init(&app, &cal, 0U) != CANFDI_OK) {
    fprintf(stderr, "canfdi-sil: the firmware refused its calibration\n");
    return EXIT_USAGE;
  }
  if (out_path != NULL) {
    out = fopen(out_path, "w");
    if (out == NULL) {
      fprintf(stderr, "canfdi-sil: cannot write %s: %s\n", out_path, strerror(errno));
      return EXIT_USAGE;
    }
    fprintf(out, "t_s,sp_speed,speed,sp_angle_deg,angle_deg,ua_cmd,thr_u_cmd,load,"
                 "rn_dcm1,rn_dcm2,rn_dcm3,rn_dcm4,rn_thr_corr,rn_thr_tps1,rn_thr_tps2,rn_thr_arm,"
                 "ra_est,psi_est,ra_true,thr_r_est,deg_dcm,deg_thr,bridge,thr_enable\n");
  }
  if (resp_path != NULL) {
    resp = fopen(resp_path, "wb");
    if (resp == NULL) {
      fprintf(stderr, "canfdi-sil: cannot write %s: %s\n", resp_path, strerror(errno));
      return EXIT_USAGE;
    }
  }
  if (log_path != NULL) {
    log = fopen(log_path, "w");
    if (log == NULL) {
      fprintf(stderr, "canfdi-sil: cannot write %s: %s\n", log_path, strerror(errno));
      return EXIT_USAGE;
    }
  }
  for (i = 0U; i < scn.n_faults; i++) {
    if ((t_fault_us < 0) || (scn.faults[i].t_start_us < t_fault_us)) {
      t_fault_us = scn.faults[i].t_start_us;
    }
  }
  for (i = 0U; i < CANFDI_SIM_SCN_MAX_EXPECT; i++) {
    expect_done[i] = false;
    expect_ok[i] = 0;
    expect_msg[i][0] = '\0';
  }
  memset(&ecu, 0, sizeof ecu);
  memset(sil_nvm_mem, 0xFF, sizeof sil_nvm_mem);
  if (canfdi_nvm_init(&sil_nvm, &sil_nvm_port) != CANFDI_OK) {
    fprintf(stderr, "canfdi-sil: NVM port refused\n");
    return EXIT_USAGE;
  }
  (void)canfdi_sim_rig_init(&rig, &scn, &sim, (uint8_t)CANFDI_SIM_MODE_LOCKSTEP);
  canfdi_sim_uds_tester_init(&tester, scn.uds, scn.n_uds);
  n_steps = (uint64_t)llround(scn.duration_s * 1000.0);
  if (!quiet) {
    printf("canfdi-sil: %s, %.3f s, seed %llu, %zu fault(s)\n", scn_path, scn.duration_s,
           (unsigned long long)scn.cfg.seed, scn.n_faults);
    for (i = 0U; i < scn.n_faults; i++) {
      printf("  injects %-22s %-12s from %8.3f s  (%s)\n", canfdi_fault_table[scn.faults[i].id].name,
             canfdi_sim_fault_mode_name(scn.faults[i].mode), (double)scn.faults[i].t_start_us * 1e-6,
             canfdi_fault_table[scn.faults[i].id].description);
    }
    printf("\n  time [s]  event\n");
  }
  for (k = 0U; k < n_steps; k++) {
    const int64_t t_us = canfdi_sim_time_us(&sim);
    const uint32_t now_us = (uint32_t)t_us;
    canfdi_sim_frame_t pf[CANFDI_SIM_RIG_MAX_TX];
    canfdi_tx_frame_t ef[CANFDI_APP_MAX_TX];
    size_t npf;
    int32_t nef;
    size_t j;
    /* expectations on the DTC state whose time has passed (all frames at or
     * before it seen), then the ECU-side actions due at t_k */
    for (i = 0U; i < scn.n_expects; i++) {
      const canfdi_sim_expect_t *e = &scn.expects[i];
      if (!expect_done[i] && is_state_expect(e) && ((int64_t)llround(e->t_s * 1e6) < t_us)) {
        expect_ok[i] = judge_state(e, expect_msg[i], sizeof expect_msg[i]);
        expect_done[i] = true;
      }
    }
    while ((next_action < scn.n_actions) && (scn.actions[next_action].t_us <= t_us)) {
      char amsg[160];
      if (apply_action(&scn.actions[next_action], &cal, now_us, quiet, amsg, sizeof amsg) != 0) {
        printf("FAIL  %s:%u: %s\n", scn_path, scn.actions[next_action].line, amsg);
        failures++;
      }
      next_action++;
    }
    /* the vehicle's setpoints (every 10 ms) and the plant's frames */
    npf = canfdi_sim_rig_begin(&rig, pf);
    if (canfdi_sim_scn_run_error(&scn) != NULL) {
      fprintf(stderr, "canfdi-sil: %s\n", canfdi_sim_scn_run_error(&scn));
      return EXIT_USAGE;
    }
    for (j = 0U; j < npf; j++) {
      if (ecu_filter_passes(pf[j].id)) {
        (void)canfdi_app_rx_frame(&app, pf[j].id, pf[j].data, pf[j].dlc, now_us);
      }
      log_frame(log, channel, t_us, pf[j].id, pf[j].data, pf[j].dlc);
    }
    tester_send(log, channel, t_us);
    /* the ECU's step */
    if (timing) {
      struct timespec t0;
      struct timespec t1;
      double ns;
      (void)clock_gettime(CLOCK_MONOTONIC, &t0);
      nef = canfdi_app_step(&app, now_us, ef);
      (void)clock_gettime(CLOCK_MONOTONIC, &t1);
      ns = ((double)(t1.tv_sec - t0.tv_sec) * 1e9) + (double)(t1.tv_nsec - t0.tv_nsec);
      step_ns_sum += ns;
      step_ns_max = (ns > step_ns_max) ? ns : step_ns_max;
    } else {
      nef = canfdi_app_step(&app, now_us, ef);
    }
    for (j = 0U; (nef > 0) && (j < (size_t)nef); j++) {
      const canfdi_tx_frame_t *f = &ef[j];
      canfdi_sim_frame_t rf;
      int rx;
      log_frame(log, channel, t_us, f->id, f->data, f->dlc);
      /* to the plant: what canfdi-sim's SocketCAN filter would pass */
      rf.id = f->id;
      rf.dlc = f->dlc;
      memcpy(rf.data, f->data, sizeof rf.data);
      rx = canfdi_sim_rig_rx(&rig, &rf, NULL);
      if (f->id == CANFDI_SIL_MSG_UDS_PHYS_RESP_FRAME_ID) {
        tester_receive(f, t_us);
      } else if (rx == CANFDI_SIM_RIG_RX_ACT_DCM) {
        if (!quiet && (in->dcm.bridge != last_bridge)) {
          printf("  %8.3f  dcm: power stage %s -> %s\n", (double)t_us * 1e-6,
                 (last_bridge == 1U) ? "A" : ((last_bridge == 2U) ? "B" : "none"),
                 (in->dcm.bridge == 1U) ? "A" : ((in->dcm.bridge == 2U) ? "B" : "none (drive off)"));
        }
        last_bridge = in->dcm.bridge;
      } else if (rx == CANFDI_SIM_RIG_RX_ACT_THR) {
        if (!quiet && (in->thr.enable != last_thr_en)) {
          printf("  %8.3f  thr: motor %s\n", (double)t_us * 1e-6,
                 in->thr.enable ? "energised" : "de-energised (spring -> limp-home)");
        }
        last_thr_en = in->thr.enable;
      } else if (f->id == CANFDI_SIL_MSG_ECU_STATUS_FRAME_ID) {
        if (canfdi_sil_msg_ecu_status_unpack(&ecu.status, f->data, f->dlc) == 0) {
          const unsigned ds[2] = {ecu.status.sts_deg_state_dcm, ecu.status.sts_deg_state_thr};
          unsigned s;
          ecu.have_status = true;
          for (s = 0U; s < 2U; s++) {
            if (!quiet && (ds[s] != last_deg[s])) {
              printf("  %8.3f  degradation %s: %s -> %s\n", (double)t_us * 1e-6,
                     (s == 0U) ? "dcm" : "thr", deg_name(last_deg[s]), deg_name(ds[s]));
            }
            last_deg[s] = ds[s];
          }
        }
      } else if (f->id == CANFDI_SIL_MSG_ECU_DTC_FRAME_ID) {
        struct canfdi_sil_msg_ecu_dtc_t d;
        if ((canfdi_sil_msg_ecu_dtc_unpack(&d, f->data, f->dlc) == 0) && (d.dtc_code != 0U)) {
          dtc_seen_t *s = seen_get(d.dtc_code);
          const uint8_t st = (uint8_t)(d.dtc_sts_test_failed | (d.dtc_sts_test_failed_this_op_cycle << 1) |
                                       (d.dtc_sts_pending << 2) | (d.dtc_sts_confirmed << 3) |
                                       (d.dtc_sts_not_completed_since_clear << 4) |
                                       (d.dtc_sts_failed_since_clear << 5) |
                                       (d.dtc_sts_not_completed_this_op_cycle << 6) |
                                       (d.dtc_sts_warning_indicator << 7));
          if (s != NULL) {
            char code[8];
            dtc_to_code(d.dtc_code, code);
            if ((d.dtc_sts_test_failed != 0U) && (s->first_tf_us < 0)) {
              s->first_tf_us = t_us;
            }
            if ((d.dtc_sts_pending != 0U) && (s->first_pd_us < 0)) {
              s->first_pd_us = t_us;
            }
            if ((d.dtc_sts_confirmed != 0U) && (s->first_cf_us < 0)) {
              s->first_cf_us = t_us;
            }
            if (!quiet && (((st ^ s->status) & 0x09U) != 0U)) {
              printf("  %8.3f  %-5s %-12s %s\n", (double)t_us * 1e-6, code,
                     (st & 0x08U) ? ((st & 0x01U) ? "confirmed" : "stored") :
                                    ((st & 0x01U) ? "testFailed" : "passed"),
                     dtc_desc(d.dtc_code));
            }
            if ((s->last_us < 0) || (st != s->status) || (d.dtc_occurrence != s->occurrence)) {
              s->since_us = t_us;
            }
            s->status = st;
            s->occurrence = (uint8_t)d.dtc_occurrence;
            s->last_us = t_us;
          }
        }
      } else if (f->id == CANFDI_SIL_MSG_ECU_RESIDUAL_DCM_FRAME_ID) {
        (void)canfdi_sil_msg_ecu_residual_dcm_unpack(&ecu.res_dcm, f->data, f->dlc);
      } else if (f->id == CANFDI_SIL_MSG_ECU_RESIDUAL_THR_FRAME_ID) {
        (void)canfdi_sil_msg_ecu_residual_thr_unpack(&ecu.res_thr, f->data, f->dlc);
      } else if (f->id == CANFDI_SIL_MSG_ECU_PARAM_DCM_FRAME_ID) {
        (void)canfdi_sil_msg_ecu_param_dcm_unpack(&ecu.prm_dcm, f->data, f->dlc);
      } else if (f->id == CANFDI_SIL_MSG_ECU_PARAM_THR_FRAME_ID) {
        (void)canfdi_sil_msg_ecu_param_thr_unpack(&ecu.prm_thr, f->data, f->dlc);
      } else {
        /* EcuDiagnosis: in the log only */
      }
    }
    if (canfdi_app_reset_requested(&app)) {
      /* ECUReset answered: the rig is the port, and a hard reset is a
       * power cycle through the NVM (as canfdi-ecu does it) */
      canfdi_sim_action_t reset;
      char amsg[160];
      memset(&reset, 0, sizeof reset);
      reset.t_us = t_us;
      reset.kind = (uint8_t)CANFDI_SIM_ACT_POWER_CYCLE;
      if (apply_action(&reset, &cal, now_us, quiet, amsg, sizeof amsg) != 0) {
        printf("FAIL  %s: ECU reset: %s\n", scn_path, amsg);
        failures++;
      }
    }
    if (symptoms && ((k % sym_every) == 0U)) {
      const canfdi_symptoms_t *y = &app.sym;
      fprintf(stderr, "%6.2f rn %5.2f %5.2f %5.2f %5.2f v%x | pd %6.3f %6.3f %6.3f %6.3f v%x | thr rn %5.2f %5.2f %5.2f %5.2f pd %6.3f %6.3f %6.3f %6.3f v%x f%x\n",
              (double)t_us * 1e-6, y->dcm_rn_q16[0] / 65536.0, y->dcm_rn_q16[1] / 65536.0,
              y->dcm_rn_q16[2] / 65536.0, y->dcm_rn_q16[3] / 65536.0, y->dcm_rn_valid,
              y->dcm_pdev_q16[0] / 65536.0, y->dcm_pdev_q16[1] / 65536.0, y->dcm_pdev_q16[2] / 65536.0,
              y->dcm_pdev_q16[3] / 65536.0, y->dcm_pdev_valid, y->thr_rn_q16[0] / 65536.0,
              y->thr_rn_q16[1] / 65536.0, y->thr_rn_q16[2] / 65536.0, y->thr_rn_q16[3] / 65536.0,
              y->thr_pdev_q16[0] / 65536.0, y->thr_pdev_q16[1] / 65536.0, y->thr_pdev_q16[2] / 65536.0,
              y->thr_pdev_q16[3] / 65536.0, y->thr_pdev_valid, (unsigned)y->flags);
      print_diag_symptoms(&app.diagnosis);
      fprintf(stderr, "       test dcm %u/%u lack %u  thr %u/%u lack %u\n", (unsigned)app.test.dcm.phase,
              (unsigned)app.test.dcm.reason, (unsigned)app.test.dcm.lack, (unsigned)app.test.thr.phase,
              (unsigned)app.test.thr.reason, (unsigned)app.test.thr.lack);
    }
    if ((out != NULL) && ((k % decimate) == 0U)) {
      fprintf(out,
              "%.3f,%.4g,%.5g,%.4g,%.5g,%.4g,%.4g,%.4g,%.4g,%.4g,%.4g,%.4g,%.4g,%.4g,%.4g,%.4g,"
              "%.5g,%.5g,%.5g,%.5g,%u,%u,%u,%u\n",
              (double)t_us * 1e-6, sp->speed_rad_s, sim.dcm.w_rad_s, sp->angle_deg,
              sim.thr.theta_rad * (180.0 / 3.14159265358979323846), in->dcm.u_cmd_V, in->thr.u_cmd_V,
              sp->load_Nm, canfdi_sil_msg_ecu_residual_dcm_res_dcm_r1_decode(ecu.res_dcm.res_dcm_r1),
              canfdi_sil_msg_ecu_residual_dcm_res_dcm_r2_decode(ecu.res_dcm.res_dcm_r2),
              canfdi_sil_msg_ecu_residual_dcm_res_dcm_r3_decode(ecu.res_dcm.res_dcm_r3),
              canfdi_sil_msg_ecu_residual_dcm_res_dcm_r4_decode(ecu.res_dcm.res_dcm_r4),
              canfdi_sil_msg_ecu_residual_thr_res_thr_corr_decode(ecu.res_thr.res_thr_corr),
              canfdi_sil_msg_ecu_residual_thr_res_thr_tps1_decode(ecu.res_thr.res_thr_tps1),
              canfdi_sil_msg_ecu_residual_thr_res_thr_tps2_decode(ecu.res_thr.res_thr_tps2),
              canfdi_sil_msg_ecu_residual_thr_res_thr_current_decode(ecu.res_thr.res_thr_current),
              canfdi_sil_msg_ecu_param_dcm_prm_dcm_ra_decode(ecu.prm_dcm.prm_dcm_ra),
              canfdi_sil_msg_ecu_param_dcm_prm_dcm_psi_decode(ecu.prm_dcm.prm_dcm_psi), sim.dcm.ra_ohm,
              canfdi_sil_msg_ecu_param_thr_prm_thr_r_decode(ecu.prm_thr.prm_thr_r), last_deg[0],
              last_deg[1], (unsigned)in->dcm.bridge, in->thr.enable ? 1U : 0U);
    }
    if ((resp != NULL) && (write_response(resp, &product_cal, sp) != 0)) {
      fprintf(stderr, "canfdi-sil: writing %s failed\n", resp_path);
      return EXIT_USAGE;
    }
    canfdi_sim_rig_end(&rig);
    /* degradation expectations are judged at their time */
    for (i = 0U; i < scn.n_expects; i++) {
      const canfdi_sim_expect_t *e = &scn.expects[i];
      const int64_t te_us = (int64_t)llround(e->t_s * 1e6);
      if (!expect_done[i] && (strcmp(e->kind, "degradation") == 0) &&
          (canfdi_sim_time_us(&sim) >= te_us)) {
        const unsigned s = (strcmp(e->arg1, "dcm") == 0) ? 0U : 1U;
        expect_done[i] = true;
        expect_ok[i] = (ecu.have_status && (strcmp(deg_name(last_deg[s]), e->arg2) == 0)) ? 1 : 0;
        (void)snprintf(expect_msg[i], sizeof expect_msg[i], "degradation %s at %.3f s: %s (expected %s)",
                       e->arg1, e->t_s, ecu.have_status ? deg_name(last_deg[s]) : "no EcuStatus yet",
                       e->arg2);
      }
    }
  }
  /* the DTC expectations and the implicit "nothing else" */
  if (!quiet) {
    printf("\n");
  }
  canfdi_sim_uds_tester_finish(&tester);
  for (i = 0U; i < scn.n_uds; i++) {
    printf("%s  %s:%u: %s\n", tester.verdict[i].ok ? "PASS" : "FAIL", scn_path, scn.uds[i].line,
           tester.verdict[i].msg);
    failures += tester.verdict[i].ok ? 0 : 1;
  }
  for (i = 0U; i < scn.n_expects; i++) {
    if (!expect_done[i] && is_state_expect(&scn.expects[i])) {
      expect_ok[i] = judge_state(&scn.expects[i], expect_msg[i], sizeof expect_msg[i]);
      expect_done[i] = true;
    }
  }
  for (i = 0U; i < scn.n_expects; i++) {
    const canfdi_sim_expect_t *e = &scn.expects[i];
    const int64_t te_us = (int64_t)llround(e->t_s * 1e6);
    if (strcmp(e->kind, "dtc") == 0) {
      const uint32_t dtc = code_to_dtc(e->arg1);
      const dtc_seen_t *s = NULL;
      int64_t t_seen = -1;
      size_t q;
      const char *what = (e->arg2[0] != '\0') ? e->arg2 : "testFailed or confirmed";
      for (q = 0U; q < n_seen; q++) {
        if (seen[q].dtc == dtc) {
          s = &seen[q];
        }
      }
      if (s != NULL) {
        if (strcmp(e->arg2, "confirmed") == 0) {
          t_seen = s->first_cf_us;
        } else if (strcmp(e->arg2, "pending") == 0) {
          t_seen = s->first_pd_us;
        } else {
          t_seen = (s->first_tf_us >= 0) ? s->first_tf_us : s->first_cf_us;
        }
      }
      expect_ok[i] = ((t_seen >= 0) && (t_seen <= te_us)) ? 1 : 0;
      if (t_seen < 0) {
        (void)snprintf(expect_msg[i], sizeof expect_msg[i], "dtc %s %s by %.3f s: never seen", e->arg1,
                       what, e->t_s);
      } else if ((t_fault_us >= 0) && (t_fault_us <= t_seen)) {
        /* delay after the latest injection at or before the detection */
        int64_t t_f = t_fault_us;
        for (q = 0U; q < scn.n_faults; q++) {
          if ((scn.faults[q].t_start_us <= t_seen) && (scn.faults[q].t_start_us > t_f)) {
            t_f = scn.faults[q].t_start_us;
          }
        }
        (void)snprintf(expect_msg[i], sizeof expect_msg[i],
                       "dtc %s %s by %.3f s: at %.3f s (%.0f ms after the fault at %.3f s)", e->arg1,
                       what, e->t_s, (double)t_seen * 1e-6, (double)(t_seen - t_f) * 1e-3,
                       (double)t_f * 1e-6);
      } else {
        (void)snprintf(expect_msg[i], sizeof expect_msg[i], "dtc %s %s by %.3f s: at %.3f s", e->arg1, what,
                       e->t_s, (double)t_seen * 1e-6);
      }
      expect_done[i] = true;
    } else if (strcmp(e->kind, "no_dtc") == 0) {
      size_t q;
      int64_t first = -1;
      uint32_t code = 0U;
      for (q = 0U; q < n_seen; q++) {
        const int64_t tq = (seen[q].first_tf_us >= 0) ? seen[q].first_tf_us : seen[q].first_cf_us;
        if ((tq >= 0) && (tq <= te_us) && ((first < 0) || (tq < first))) {
          first = tq;
          code = seen[q].dtc;
        }
      }
      expect_ok[i] = (first < 0) ? 1 : 0;
      if (first < 0) {
        (void)snprintf(expect_msg[i], sizeof expect_msg[i], "no trouble code up to %.3f s", e->t_s);
      } else {
        char c[8];
        dtc_to_code(code, c);
        (void)snprintf(expect_msg[i], sizeof expect_msg[i], "no trouble code up to %.3f s: %s at %.3f s",
                       e->t_s, c, (double)first * 1e-6);
      }
      expect_done[i] = true;
    } else if (!expect_done[i]) {
      expect_ok[i] = 0;
      (void)snprintf(expect_msg[i], sizeof expect_msg[i], "%s: not evaluated (beyond the run?)", e->kind);
    } else {
      /* degradation, dtc_status, occurrence, freeze: judged during the run */
    }
    printf("%s  %s:%u: %s\n", expect_ok[i] ? "PASS" : "FAIL", scn_path, e->line, expect_msg[i]);
    if (!expect_ok[i]) {
      failures++;
    }
  }
  for (i = 0U; i < n_seen; i++) {
    size_t q;
    bool named = false;
    char c[8];
    if ((seen[i].first_tf_us < 0) && (seen[i].first_cf_us < 0)) {
      continue;
    }
    dtc_to_code(seen[i].dtc, c);
    for (q = 0U; q < scn.n_expects; q++) {
      if ((strcmp(scn.expects[q].kind, "dtc") == 0) && (strcmp(scn.expects[q].arg1, c) == 0)) {
        named = true;
      }
    }
    if (!named) {
      printf("FAIL  %s: unexpected trouble code %s at %.3f s (%s)\n", scn_path, c,
             (double)((seen[i].first_tf_us >= 0) ? seen[i].first_tf_us : seen[i].first_cf_us) * 1e-6,
             dtc_desc(seen[i].dtc));
      failures++;
    }
  }
  if (!quiet) {
    const canfdi_app_diag_t *d = canfdi_app_diag(&app);
    printf("ecu self-diagnostics: %lu steps, %lu frames sent, %lu rejected, %lu saturations, "
           "%lu estimator resets, %lu deadline misses\n",
           (unsigned long)d->steps, (unsigned long)d->frames_sent, (unsigned long)d->frames_rejected,
           (unsigned long)d->saturations, (unsigned long)d->estimator_resets,
           (unsigned long)d->deadline_misses);
  }
  if (timing && (n_steps > 0U)) {
    printf("canfdi_app_step wall-clock: mean %.0f ns, max %.0f ns over %llu steps (host)\n",
           step_ns_sum / (double)n_steps, step_ns_max, (unsigned long long)n_steps);
  }
  printf("%s  %s (%d check(s) failed)\n", (failures == 0) ? "PASSED" : "FAILED", scn_path, failures);
  if ((out != NULL) && (fclose(out) != 0)) {
    failures++;
  }
  if ((log != NULL) && (fclose(log) != 0)) {
    failures++;
  }
  if ((resp != NULL) && (fclose(resp) != 0)) {
    failures++;
  }
  if (nvm_out != NULL) {
    /* ignition off: the operation cycle ends, the memory's image is stored */
    static uint8_t img_out[CANFDI_APP_IMAGE_MAX_BYTES];
    const int32_t n_out = canfdi_app_power_down(&app, img_out, (uint32_t)sizeof img_out);
    FILE *f = fopen(nvm_out, "wb");
    if ((n_out <= 0) || (f == NULL) || (fwrite(img_out, 1U, (size_t)n_out, f) != (size_t)n_out) ||
        (fclose(f) != 0)) {
      fprintf(stderr, "canfdi-sil: cannot write the DTC memory image to %s\n", nvm_out);
      return EXIT_USAGE;
    }
  }
  return (failures == 0) ? EXIT_SUCCESS : EXIT_CHECK;
}
