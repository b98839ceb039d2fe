/*
 * canfdi_replay_core.c — `canfdi-replay-core`: the supervisor application
 * (firmware/app/canfdi_app.h, the same object code as on the ECU) stepped on
 * the time base of a recorded CAN log, fed the recorded input frames, with
 * what it finds written as a stream of JSON lines (one event per line) for
 * the Python front end `canfdi-replay` (tools/canfdi/replay.py), which turns
 * it into the timeline, the JSON report and the HTML report. The event
 * stream is documented in tools/replay/README.md.
 *
 * Input: candump text (`candump -L`) from files, gzip-compressed files
 * (zlib reads both) or stdin ("-"), which is how every other log format
 * arrives: python-can converts it to candump text in a pipe. Several files
 * are consecutive recordings of one vehicle: between two files the
 * supervisor is powered down and up again with its trouble-code memory
 * (the NVM image), as an ECU is between two drives. --nvm-in and --nvm-out
 * carry that image across separate runs (one run per drive, e.g. the fleet
 * replay canfdi-fleet): the first log starts with a power-up from the image
 * read, and after the last log the supervisor is powered down and the image
 * written, so a chain of runs holds the same memory as one run over all the
 * logs.
 *
 * Time base (per file, decided from the first frames, --clock):
 *   simstep     the log has SimStep frames (a lockstep HIL recording): as
 *               canfdi-ecu --lockstep, SimStep(k) runs the step at k ms and
 *               every input frame before it goes to that step; a log time
 *               is the step's k ms, as canfdi-watch reads such logs.
 *   timestamps  a step every 1 ms of log time, on a grid that follows the
 *               sensor frames: a step takes the frames stamped up to half
 *               a step after its time (GRID_MARGIN_US), and its time is
 *               where its DcmSensor and ThrSensor frames are expected, so
 *               each of them falls into a step of its own even when the
 *               logger's time stamps jitter (by up to half a step less
 *               GRID_MOVE_US and half the distance between the two
 *               plants' phases). The grid starts at the sensor frames'
 *               mean phase in the frames read ahead, or at the first
 *               frame's time stamp when that is less than GRID_MOVE_US off
 *               it (so the first step's time may lie up to half a step
 *               before the first frame's). After each sensor frame whose
 *               time stamp is its own (not one earlier than the last
 *               frame's, nor an outlier's) the grid moves, by the whole
 *               error at once, when the best step time for the sensor
 *               frames' filtered phases (the middle of the two when both
 *               plants' frames come) is GRID_MOVE_US or more off its own,
 *               as it is once the logger's clock drifts against the sensor
 *               nodes': the steps keep the sensor nodes' 1 ms, and the
 *               supervisor's clock advances 1 ms a step whatever the
 *               logger's clock says. A plant whose frames stopped for
 *               PHASE_STALE_STEPS steps, or come slower than every step
 *               (--rx-rate), does not steer it; after a gap or a jump of
 *               the time stamps the next sensor frames set it anew; a log
 *               without sensor frames keeps the first frame's time stamp.
 *               In a SIL log every frame of step k carries the time stamp
 *               k ms, the sensor frames first and the ECU's frames (that
 *               step's output) after them; the grid does not move there,
 *               so the steps are the recorded ECU's.
 * Log times are seconds from the first frame, or the time stamps
 * themselves when the first one is below 1e6 s (already relative, e.g. a
 * canfdi-sil log or a cut of it), as canfdi-watch does.
 *
 * What goes in: the frames the ECU's kernel filter passes (DcmSensor,
 * ThrSensor, SetpointDcm, SetpointThr, the UDS requests) of the channel
 * judged, as classic data frames with their own length; the input
 * supervision judges them exactly as on the ECU. Remote, CAN FD and error
 * frames and other channels are counted, never fed.
 *
 * The recorded ECU's commands. The models need the voltage the actuators
 * held over the interval that ends with a sample; in a recording that is
 * the ECU's last DcmActuator / ThrActuator frame before the sensor frame
 * of the sample. Before each step the core compares it with the command
 * this supervisor applied itself in its last step (the frame it sent): the
 * same to the frame's resolution, the supervisor's own value stands (so a
 * replay from power-up is the recorded run, frame for frame); different,
 * the recorded one is given to the application (canfdi_app_set_applied).
 * A command frame with a wrong CRC, or none for CMD_FRESH_STEPS steps,
 * makes the command unknown: the monitors that need it are not judged.
 * The throttle's tracking monitor compares the valve with this
 * supervisor's position reference: from a power-up log that is the one the
 * recorded ECU drove it to, as long as their throttle commands agree. Once
 * the recorded command differs (the replay took other inputs than the
 * recorded ECU, e.g. setpoints the replay rejects), the valve followed
 * another reference: the monitor is not judged until the commands have
 * agreed again for THR_AGREE_STEPS steps.
 * The recorded ECU's EcuDtc frames (what it reported, beside what the
 * replay finds) are taken only when they pass the E2E check the ECU's own
 * receivers make (CRC, counter with max_delta 2): a forged or corrupted one
 * is counted (eof rec_e2e_bad), never reported as the ECU's code. The
 * setpoints are fed like every input: the replayed supervision judges
 * their E2E protection as on the ECU (U1A50/U1A51).
 *
 * Start: a log that begins at the recorded ECU's power-up (its first frames
 * equal this supervisor's, counters and all: --start auto checks the first
 * PU_MIN_FRAMES of them) is judged from the first step. Any other log
 * starts mid-drive: the models are not judged for the settling time
 * (--settle-ms) and the throttle's tracking monitor not at all, because
 * the phase of the recorded ECU's excitation on the position reference is
 * not in the recording.
 *
 * Exit status: 0 the log was read (whatever it held), 2 usage error or a
 * file that cannot be opened.
 */
#include <errno.h>
#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <zlib.h>

#include "app/canfdi_app.h"
#include "canfdi_rp_msg.h"
#include "comm/canfdi_e2e.h"
#include "comm/gen/canfdi_sig_conv.h"
#include "replay_candump.h"
#include "replay_fw_id.h"

#define PROG "canfdi-replay-core"
/* Models not judged after a mid-drive start or a gap: see --settle-ms and
 * docs/design.md (technicians) for how it was measured. */
#define REPLAY_DEFAULT_SETTLE_MS 5000
#define REPLAY_DEFAULT_GAP_MS 10
#define EXIT_USAGE 2

#define STEP_US 1000
#define GRID_MARGIN_US 500           /* a step takes the frames up to this long after its time */
#define GRID_MOVE_US 100             /* the grid moves when the sensor frames are this far off its step times */
#define PHASE_FILTER 16              /* the sensor frames' phase: a first-order filter, gain 1/16 */
#define PHASE_STALE_STEPS 10U        /* a plant whose frames stopped this long no longer steers the grid */
#define CMD_FRESH_STEPS 10U          /* a command older than this is not known */
#define THR_AGREE_STEPS 1000U        /* recorded = own throttle command this long: the reference is ours again */
#define PU_MIN_FRAMES 20U            /* ECU frames compared before the start is called power-up */
#define PU_MAX_STEPS 100U            /* ... within these steps, else mid-drive */
#define LOOKAHEAD_FRAMES 512U        /* frames read before the clock is chosen */
#define LOOKAHEAD_US 100000          /* ... or this much log time */
#define JUMP_CONFIRM 8U              /* frames that confirm a jump of the time stamps */
#define GAP_STEP_MAX_US 60000000LL   /* a longer gap is not stepped through */
#define LINE_MAX_LEN 1024U
#define MAX_BAD_EVENTS 100U
#define MAX_GAP_EVENTS 1000U
#define MAX_MISC_EVENTS 20U
#define QCAP 64U
#define N_CHANS 16U
#define N_UNKNOWN_IDS 64U
#define PROGRESS_BYTES (8U << 20)

/* ------------------------------------------------------------ options */

enum { START_AUTO, START_POWER_UP, START_MID_DRIVE };
enum { CLOCK_AUTO, CLOCK_TIMESTAMPS, CLOCK_SIMSTEP };

typedef struct {
  int start;
  int clock;
  const char *channel;     /* NULL: the first channel carrying a frame of the DBC */
  int64_t settle_us;
  int64_t gap_us;
  int64_t every_us;        /* samples for the plots; 0: none */
  bool no_models[2];       /* [0] DC motor, [1] throttle: inputs the models cannot use */
  const char *no_models_why;
  bool progress;
  uint32_t rx_rate_ms[CANFDI_RX_F_COUNT]; /* 0: the DBC's cycle time */
  const char *nvm_in;      /* DTC memory image to power up with; NULL: cleared memory */
  const char *nvm_out;     /* where the image goes at the end; NULL: nowhere */
} opts_t;

/* ------------------------------------------------------------ events */

static FILE *ev;

static void ev_time(int64_t us)
{
  const int64_t a = (us < 0) ? -us : us;
  fprintf(ev, "%s%" PRId64 ".%06" PRId64, (us < 0) ? "-" : "", a / 1000000, a % 1000000);
}

static void ev_str(const char *s, size_t n)
{
  size_t i;
  fputc('"', ev);
  for (i = 0U; i < n; i++) {
    const unsigned char c = (unsigned char)s[i];
    if ((c == '"') || (c == '\\')) {
      fputc('\\', ev);
      fputc((int)c, ev);
    } else if ((c < 0x20U) || (c >= 0x7FU)) {
      fprintf(ev, "\\u%04x", (unsigned)c);
    } else {
      fputc((int)c, ev);
    }
  }
  fputc('"', ev);
}

static void ev_q16(int32_t v) { fprintf(ev, "%.5g", (double)v / 65536.0); }

/* A UDS identification string (16 bytes padded with spaces), without the padding. */
static void ev_ident(const uint8_t *p)
{
  size_t n = CANFDI_UDS_ID_BYTES;
  while ((n > 0U) && (p[n - 1U] == (uint8_t)' ')) {
    n--;
  }
  ev_str((const char *)p, n);
}

/* ------------------------------------------------------------ state */

typedef struct {
  bool seen;        /* a frame with a good CRC was recorded */
  uint64_t step;    /* the step it was recorded in */
  uint8_t bridge;   /* DcmActuator: DcmBridgeSel */
  bool enable;
  int32_t raw_u;    /* DcmUaCmd / ThrUCmd, raw */
} cmd_t;

typedef struct {
  uint8_t len;
  uint8_t data[8];
  int64_t t_us;
} qent_t;

typedef struct {
  qent_t e[QCAP];
  unsigned head;
  unsigned n;
} queue_t;

/* The ECU's frames, compared recorded against replayed. */
static const uint32_t ecu_ids[] = {
    CANFDI_RP_MSG_DCM_ACTUATOR_FRAME_ID,     CANFDI_RP_MSG_THR_ACTUATOR_FRAME_ID,
    CANFDI_RP_MSG_ECU_RESIDUAL_DCM_FRAME_ID, CANFDI_RP_MSG_ECU_RESIDUAL_THR_FRAME_ID,
    CANFDI_RP_MSG_ECU_STATUS_FRAME_ID,       CANFDI_RP_MSG_ECU_DIAGNOSIS_FRAME_ID,
    CANFDI_RP_MSG_ECU_SELF_DIAG_FRAME_ID,    CANFDI_RP_MSG_ECU_DTC_FRAME_ID,
    CANFDI_RP_MSG_ECU_PARAM_DCM_FRAME_ID,    CANFDI_RP_MSG_ECU_PARAM_THR_FRAME_ID,
    CANFDI_RP_MSG_UDS_PHYS_RESP_FRAME_ID};
#define N_ECU_IDS (sizeof ecu_ids / sizeof ecu_ids[0])

/* What the ECU's kernel filter passes to the application
 * (firmware/port/linux/canfdi_socketcan.h). */
static bool ecu_input(uint32_t id)
{
  return (id == CANFDI_RP_MSG_DCM_SENSOR_FRAME_ID) || (id == CANFDI_RP_MSG_THR_SENSOR_FRAME_ID) ||
         (id == CANFDI_RP_MSG_SETPOINT_DCM_FRAME_ID) || (id == CANFDI_RP_MSG_SETPOINT_THR_FRAME_ID) ||
         (id == CANFDI_RP_MSG_UDS_FUNC_REQ_FRAME_ID) || (id == CANFDI_RP_MSG_UDS_PHYS_REQ_FRAME_ID);
}

static int ecu_index(uint32_t id)
{
  unsigned i;
  for (i = 0U; i < N_ECU_IDS; i++) {
    if (ecu_ids[i] == id) {
      return (int)i;
    }
  }
  return -1;
}

static bool in_dbc(uint32_t id)
{
  return ecu_input(id) || (ecu_index(id) >= 0) || (id == CANFDI_RP_MSG_SIM_STEP_FRAME_ID) ||
         (id == CANFDI_RP_MSG_SIM_FAULT_INJECT_FRAME_ID) || (id == CANFDI_RP_MSG_SIM_FAULT_CLEAR_FRAME_ID) ||
         (id == CANFDI_RP_MSG_SIM_PLANT_STATUS_FRAME_ID);
}

/* Monitors as the report names them: what each needs from the recording. */
enum { MON_COM_DCM, MON_COM_THR, MON_COM_SP, MON_TPS_RANGE, MON_DCM_MODELS, MON_DCM_CMD, MON_THR_MODELS,
       MON_THR_TRACK, N_MON };
static const char *const mon_name[N_MON] = {"com_dcm",    "com_thr",    "com_sp",      "tps_range",
                                            "dcm_models", "dcm_cmd",    "thr_models", "thr_tracking"};

enum {
  WHY_NONE,
  WHY_GAP,
  WHY_SETTLE_START,
  WHY_SETTLE_GAP,
  WHY_DCM_FRAME,
  WHY_DCM_INPUTS,
  WHY_DCM_CMD,
  WHY_THR_FRAME,
  WHY_THR_INPUTS,
  WHY_THR_CMD,
  WHY_THR_REF,
  WHY_THR_APART,
  WHY_DCM_UNLEARNT,
  WHY_DCM_TAINTED,
  WHY_DCM_UNCHECKED,
  WHY_DCM_REARM,
  WHY_THR_REARM,
  WHY_MODELS_DCM,
  WHY_MODELS_THR,
  N_WHY
};
static const char *const why_text[N_WHY] = {
    "",
    "a gap in the log (no frame at all)",
    "settling after the start of the log (it starts after the recorded ECU's power-up)",
    "settling after a gap in the log",
    "DcmSensor not received",
    "DC-motor inputs not valid (frames rejected or values out of range)",
    "no valid DcmActuator command in the recording",
    "ThrSensor not received",
    "throttle inputs not valid (frames rejected or values out of range)",
    "no valid ThrActuator command in the recording",
    "the recorded ECU's position reference is not in the recording (its excitation phase is "
    "known only from its power-up)",
    "the recorded ECU drove the throttle otherwise than the replay (another position reference)",
    "the DC motor's estimates (R_A, Psi, J, friction) have not converged since the start: too little "
    "excitation in the recording so far",
    "the DC motor's residuals without R_A (r2, r3) showed a fault when its estimates and the parity "
    "equations' R_A had been learnt: the fault may be learnt into them (to the end of the power cycle)",
    "the DC motor's estimates have converged, but what they and R_A learnt is not checked yet against r2 "
    "and r3 (R_A still being learnt, or r2 and r3 not evaluated long enough: near standstill, a load hold)",
    "re-arming: the DC-motor inputs came back from an interruption (rejected frames or values, a "
    "timeout) or a DcmSensor frame was late, less than the calibration's hold time ago",
    "re-arming: the throttle inputs came back from an interruption (rejected frames or values, a "
    "timeout) or a ThrSensor frame was late, less than the calibration's hold time ago",
    NULL, /* --no-models text */
    NULL};

typedef struct {
  int64_t t_us;
  uint8_t w_pu[N_MON]; /* as if the log starts at power-up */
  uint8_t w_md[N_MON]; /* ... mid-drive */
} mon_buf_t;

typedef struct {
  uint64_t rej[CANFDI_RX_F_COUNT][5]; /* length, crc, counter, implausible, timeouts */
} rxcount_t;

typedef struct {
  /* the supervisor */
  canfdi_app_t app;
  canfdi_app_cal_t cal;
  uint8_t image[CANFDI_APP_IMAGE_MAX_BYTES];
  int32_t image_len;
  /* file */
  int file_index;
  const char *file_name;
  uint64_t line_no;
  uint64_t frames;
  uint64_t bad_lines;
  bool truncated;
  /* channel */
  char chan[RP_CHAN_MAX];
  bool chan_fixed;
  char other_chan[N_CHANS][RP_CHAN_MAX];
  uint64_t other_chan_n[N_CHANS];
  uint64_t other_chan_line[N_CHANS];
  unsigned n_other;
  /* clock */
  int clock;
  bool clock_decided;
  rp_frame_t look[LOOKAHEAD_FRAMES];
  uint64_t look_line[LOOKAHEAD_FRAMES];
  unsigned n_look;
  bool have_t0;
  int64_t t0_abs_us;       /* first frame's time stamp */
  int64_t origin_us;       /* log time = abs - origin */
  int64_t shift_us;        /* added to time stamps after a jump back */
  int64_t last_ts_us;      /* last time stamp seen (shifted) */
  int64_t next_step_abs;   /* timestamps: the next step's time (its frames: up to GRID_MARGIN_US later) */
  int32_t phase_us[2];     /* timestamps: DcmSensor, ThrSensor frames' filtered phase to the step times */
  bool phase_seen[2];      /* ... known: the plant's frames came within PHASE_STALE_STEPS */
  uint64_t phase_step[2];  /* ... the step count at the plant's last frame */
  int32_t grid_seed_us;    /* timestamps: the first step's time after the first frame's */
  uint64_t grid_moves;     /* timestamps: times the grid followed the sensor frames */
  int64_t step_log_us;     /* log time of the current batch's step */
  int64_t first_step_log_us;
  int64_t last_k;          /* simstep: last step run, -1 none */
  int64_t ecu_step_log_us; /* simstep: the step of the latest recorded actuator frame */
  int64_t k0;              /* simstep: the first step of the log, -1 none */
  uint32_t now_us;         /* the supervisor's clock */
  uint64_t steps;
  bool batch_nonempty;
  rp_frame_t pend[JUMP_CONFIRM];  /* timestamps: frames after a jump, not yet confirmed */
  uint64_t pend_line[JUMP_CONFIRM];
  unsigned n_pend;
  uint64_t outliers;
  /* recorded commands */
  cmd_t dcm_latest, thr_latest;
  cmd_t dcm_batch0, thr_batch0;  /* at the start of this batch */
  cmd_t dcm_sample, thr_sample;  /* before the batch's newest sensor frame */
  bool dcm_sample_set, thr_sample_set;
  cmd_t dcm_own, thr_own;        /* the supervisor's own last command frames */
  uint64_t cmd_bad_crc;
  uint32_t thr_apart_steps;      /* > 0: the recorded throttle command differed from own lately */
  /* the recorded ECU's EcuDtc frames, judged as its receivers judge theirs */
  canfdi_e2e_rx_t rec_dtc_e2e;
  uint64_t rec_e2e_bad;
  /* start */
  int start_mode;               /* START_POWER_UP / START_MID_DRIVE once decided */
  bool start_decided;
  int64_t settle_until_log_us;
  uint8_t settle_why;
  /* comparison */
  queue_t rq[N_ECU_IDS], sq[N_ECU_IDS];
  uint64_t matched, mismatched, rec_only, replay_only, rec_ecu_frames;
  bool mismatch_reported;
  /* monitors */
  uint8_t mon_why[N_MON];
  bool mon_init;
  mon_buf_t mon_buf[PU_MAX_STEPS];
  unsigned n_mon_buf;
  /* gaps */
  int64_t gap_until_log_us;     /* com monitors not judged up to here */
  uint64_t gaps;
  /* trouble codes seen */
  uint8_t dtc_st_rep[CANFDI_DTC_COUNT];
  uint8_t dtc_occ_rep[CANFDI_DTC_COUNT];
  bool dtc_seen_rep[CANFDI_DTC_COUNT];
  uint32_t dtc_code_ecu[64];
  uint8_t dtc_st_ecu[64];
  uint8_t dtc_occ_ecu[64];
  unsigned n_dtc_ecu;
  /* degradation and isolation */
  uint8_t deg[2], deg_reason[2], bridge;
  bool limp;
  bool deg_init;
  uint8_t iso[2];
  /* samples */
  int64_t next_sample_log_us;
  int32_t smax[8];
  uint8_t sval[2];
  /* data quality */
  uint64_t back_n, err_frames, fd_frames, remote_frames, ext_frames, unknown_frames;
  uint64_t fd_line, remote_line, ext_line;
  uint32_t unknown_id[N_UNKNOWN_IDS];
  uint64_t unknown_n[N_UNKNOWN_IDS];
  unsigned n_unknown;
  int64_t bus_sec;              /* log second being counted, -1 none */
  uint64_t bus_frames, bus_bits, bus_err;
  rxcount_t rxc;
  bool frame_ok[CANFDI_RX_F_COUNT];
  bool frame_init;
  uint64_t simstep_bad;
  uint64_t progress_next;
} rp_t;

static rp_t rp;
static opts_t opt;

/* ------------------------------------------------------------ helpers */

static int64_t log_us_of_abs(int64_t abs_us) { return abs_us - rp.origin_us; }

static const char *deg_name(unsigned s)
{
  static const char *const n[] = {"normal", "degraded", "fail_safe", "fail_silent"};
  return (s < 4U) ? n[s] : "?";
}

static void dtc_code_text(uint32_t dtc, char out[8])
{
  static const char letters[] = "PCBU";
  const unsigned hi = (unsigned)((dtc >> 16) & 0xFFU);
  const unsigned lo = (unsigned)((dtc >> 8) & 0xFFU);
  (void)snprintf(out, 8, "%c%u%X%02X", letters[(hi >> 6) & 3U], (hi >> 4) & 3U, hi & 0xFU, lo);
}

static void q_push(queue_t *q, const uint8_t *data, uint8_t len, int64_t t_us)
{
  qent_t *e = &q->e[(q->head + q->n) % QCAP];
  e->len = len;
  memcpy(e->data, data, (len <= 8U) ? len : 8U);
  e->t_us = t_us;
  q->n++;
}

static qent_t *q_front(queue_t *q) { return &q->e[q->head]; }

static void q_pop(queue_t *q)
{
  q->head = (q->head + 1U) % QCAP;
  q->n--;
}

/* ------------------------------------------------------------ comparison */

static void compare_one(uint32_t id, const qent_t *rec, const qent_t *rep)
{
  if ((rec->len == rep->len) && (memcmp(rec->data, rep->data, rec->len) == 0)) {
    rp.matched++;
    return;
  }
  rp.mismatched++;
  if (!rp.mismatch_reported) {
    unsigned i;
    rp.mismatch_reported = true;
    fprintf(ev, "{\"ev\":\"mismatch\",\"file\":%d,\"t\":", rp.file_index);
    ev_time(rec->t_us);
    fprintf(ev, ",\"id\":%u,\"recorded\":\"", (unsigned)id);
    for (i = 0U; i < rec->len; i++) {
      fprintf(ev, "%02X", rec->data[i]);
    }
    fprintf(ev, "\",\"replay\":\"");
    for (i = 0U; i < rep->len; i++) {
      fprintf(ev, "%02X", rep->data[i]);
    }
    fprintf(ev, "\"}\n");
  }
}

/* One ECU frame, recorded (rec) or replayed; pairs them per id in order. */
static void ecu_frame(int idx, bool recorded, const uint8_t *data, uint8_t len, int64_t t_us)
{
  queue_t *mine = recorded ? &rp.rq[idx] : &rp.sq[idx];
  queue_t *other = recorded ? &rp.sq[idx] : &rp.rq[idx];
  if (other->n > 0U) {
    qent_t me;
    me.len = len;
    memcpy(me.data, data, len);
    me.t_us = t_us;
    if (recorded) {
      compare_one(ecu_ids[idx], &me, q_front(other));
    } else {
      compare_one(ecu_ids[idx], q_front(other), &me);
    }
    q_pop(other);
    return;
  }
  if (mine->n >= QCAP) {
    q_pop(mine);
    if (recorded) {
      rp.rec_only++;
    } else {
      rp.replay_only++;
    }
  }
  q_push(mine, data, len, t_us);
}

/* ------------------------------------------------------------ commands */

static void decode_dcm_cmd(const uint8_t *d, uint8_t len, cmd_t *c)
{
  struct canfdi_rp_msg_dcm_actuator_t m;
  if ((len == 8U) && (canfdi_rp_msg_dcm_actuator_unpack(&m, d, len) == 0)) {
    c->bridge = m.dcm_bridge_sel;
    c->enable = (m.dcm_enable != 0U);
    c->raw_u = (int32_t)m.dcm_ua_cmd;
    c->seen = true;
  }
}

static void decode_thr_cmd(const uint8_t *d, uint8_t len, cmd_t *c)
{
  struct canfdi_rp_msg_thr_actuator_t m;
  if ((len == 8U) && (canfdi_rp_msg_thr_actuator_unpack(&m, d, len) == 0)) {
    c->bridge = 0U;
    c->enable = (m.thr_enable != 0U);
    c->raw_u = (int32_t)m.thr_u_cmd;
    c->seen = true;
  }
}

static bool cmd_same(const cmd_t *a, const cmd_t *b)
{
  return a->seen && b->seen && (a->bridge == b->bridge) && (a->enable == b->enable) && (a->raw_u == b->raw_u);
}

static bool cmd_known(const cmd_t *c) { return c->seen && ((rp.steps - c->step) <= CMD_FRESH_STEPS); }

/* The recorded command of the interval that ends with this step's sample
 * versus the supervisor's own; sets what the next step uses. */
static void apply_commands(bool *dcm_known_out, bool *thr_known_out)
{
  const cmd_t *d = rp.dcm_sample_set ? &rp.dcm_sample : &rp.dcm_batch0;
  const cmd_t *t = rp.thr_sample_set ? &rp.thr_sample : &rp.thr_batch0;
  const bool power_up = (rp.start_decided && (rp.start_mode == START_POWER_UP)) ||
                        (!rp.start_decided && (opt.start != START_MID_DRIVE));
  canfdi_app_applied_t a;
  bool call = false;
  a.dcm_known = true;
  a.thr_known = true;
  a.dcm = rp.app.fb.mgr.dcm;
  a.thr = rp.app.fb.mgr.thr;
  if (cmd_known(t) && !cmd_same(t, &rp.thr_own)) {
    rp.thr_apart_steps = THR_AGREE_STEPS; /* the valve follows the recorded ECU's reference */
  } else if (rp.thr_apart_steps > 0U) {
    rp.thr_apart_steps--;
  } else {
    /* agreeing */
  }
  a.thr_ref_known = power_up && (rp.thr_apart_steps == 0U);
  if (!a.thr_ref_known) {
    call = true;
  }
  /* before the recorded ECU's first command of a power-up log it has
   * applied nothing: the supervisor's own (held off) command stands */
  if (cmd_known(d)) {
    if (!cmd_same(d, &rp.dcm_own)) {
      a.dcm.enable = d->enable;
      a.dcm.bridge = d->bridge;
      a.dcm.u_cmd_V_q16 = d->enable ? canfdi_rx_raw_to_q16(d->raw_u, CANFDI_SIG_DCM_ACTUATOR_DCM_UA_CMD_SCALE_Q32,
                                                            CANFDI_SIG_DCM_ACTUATOR_DCM_UA_CMD_OFFSET_Q32)
                                    : 0;
      call = true;
    }
  } else if (!(power_up && !d->seen)) {
    a.dcm_known = false;
    call = true;
  } else {
    /* power-up, nothing recorded yet: own */
  }
  if (cmd_known(t)) {
    if (!cmd_same(t, &rp.thr_own)) {
      a.thr.enable = t->enable;
      a.thr.u_cmd_V_q16 = t->enable ? canfdi_rx_raw_to_q16(t->raw_u, CANFDI_SIG_THR_ACTUATOR_THR_UCMD_SCALE_Q32,
                                                            CANFDI_SIG_THR_ACTUATOR_THR_UCMD_OFFSET_Q32)
                                    : 0;
      call = true;
    }
  } else if (!(power_up && !t->seen)) {
    a.thr_known = false;
    call = true;
  } else {
    /* as above */
  }
  if (call) {
    (void)canfdi_app_set_applied(&rp.app, &a);
  }
  *dcm_known_out = a.dcm_known;
  *thr_known_out = a.thr_known;
}

/* ------------------------------------------------------------ trouble codes */

static void emit_evidence(void)
{
  const canfdi_symptoms_t *y = &rp.app.sym;
  unsigned c;
  unsigned i;
  fprintf(ev, "{\"ev\":\"why\",\"rn\":[");
  for (i = 0U; i < CANFDI_SYM_N_RES; i++) {
    fprintf(ev, "%s", (i > 0U) ? "," : "");
    ev_q16(y->dcm_rn_q16[i]);
  }
  for (i = 0U; i < CANFDI_SYM_N_RES; i++) {
    fprintf(ev, ",");
    ev_q16(y->thr_rn_q16[i]);
  }
  fprintf(ev, "],\"pd\":[");
  for (i = 0U; i < CANFDI_SYM_N_PAR; i++) {
    fprintf(ev, "%s", (i > 0U) ? "," : "");
    ev_q16(y->dcm_pdev_q16[i]);
  }
  for (i = 0U; i < CANFDI_SYM_N_PAR; i++) {
    fprintf(ev, ",");
    ev_q16(y->thr_pdev_q16[i]);
  }
  fprintf(ev, "],\"valid\":[%u,%u,%u,%u],\"flags\":%lu,\"uac\":", (unsigned)y->dcm_rn_valid,
          (unsigned)y->thr_rn_valid, (unsigned)y->dcm_pdev_valid, (unsigned)y->thr_pdev_valid,
          (unsigned long)y->flags);
  ev_q16(y->dcm_ua_cmd_rn_q16);
  fprintf(ev, ",\"x\":[");
  for (c = 0U; c < CANFDI_DIAG_N_COMP; c++) {
    fprintf(ev, "%s[", (c > 0U) ? "," : "");
    for (i = 0U; i < CANFDI_DIAG_N_CH; i++) {
      fprintf(ev, "%s", (i > 0U) ? "," : "");
      ev_q16(rp.app.diagnosis.x_q16[c][i]);
    }
    fprintf(ev, "]");
  }
  fprintf(ev, "],\"sym\":[");
  for (c = 0U; c < CANFDI_DIAG_N_COMP; c++) {
    fprintf(ev, "%s[", (c > 0U) ? "," : "");
    for (i = 0U; i < CANFDI_DIAG_N_CH; i++) {
      fprintf(ev, "%s%d", (i > 0U) ? "," : "", (int)canfdi_diagnosis_symptom(&rp.app.diagnosis, (uint8_t)(CANFDI_COMPONENT_DC_MOTOR + c), (uint8_t)i));
    }
    fprintf(ev, "]");
  }
  fprintf(ev, "],\"flag_sym\":[");
  for (i = 0U; i < CANFDI_DIAG_N_FLAGS; i++) {
    fprintf(ev, "%s%d", (i > 0U) ? "," : "", (int)rp.app.diagnosis.flag[i].state);
  }
  fprintf(ev, "],\"res\":[");
  for (c = 0U; c < CANFDI_DIAG_N_COMP; c++) {
    const canfdi_diagnosis_result_t *r = canfdi_diagnosis_result(&rp.app.diagnosis, (uint8_t)(CANFDI_COMPONENT_DC_MOTOR + c));
    fprintf(ev,
            "%s{\"isolated\":%u,\"conf\":%u,\"best\":%u,\"best_pct\":%u,\"second\":%u,\"second_pct\":%u,"
            "\"detected\":%s,\"not_isolated\":%s}",
            (c > 0U) ? "," : "", r->isolated, r->confidence_pct, r->best, r->best_pct, r->second, r->second_pct,
            r->detected ? "true" : "false", r->not_isolated ? "true" : "false");
  }
  fprintf(ev, "],\"faults\":%lu,\"failed\":%lu,\"mgr_detected\":%lu}\n", (unsigned long)rp.app.fb.faults,
          (unsigned long)canfdi_diagnosis_failed_mask(&rp.app.diagnosis), (unsigned long)rp.app.fb.mgr.detected);
}

static void emit_dtc(const char *src, uint32_t dtc, uint8_t st, uint8_t occ, int64_t t_us)
{
  char code[8];
  dtc_code_text(dtc, code);
  fprintf(ev, "{\"ev\":\"dtc\",\"src\":\"%s\",\"file\":%d,\"t\":", src, rp.file_index);
  ev_time(t_us);
  fprintf(ev, ",\"code\":\"%s\",\"dtc\":%lu,\"status\":%u,\"occ\":%u}\n", code, (unsigned long)dtc,
          (unsigned)st, (unsigned)occ);
}

static void dtc_frame(bool recorded, const uint8_t *d, uint8_t len, int64_t t_us)
{
  struct canfdi_rp_msg_ecu_dtc_t m;
  uint8_t st;
  if (recorded && !canfdi_e2e_status_is_usable(canfdi_e2e_check(&rp.rec_dtc_e2e, d, len))) {
    rp.rec_e2e_bad++; /* forged or corrupted: not the recorded ECU's word */
    return;
  }
  if ((len != 8U) || (canfdi_rp_msg_ecu_dtc_unpack(&m, d, len) != 0) || (m.dtc_code == 0U)) {
    return;
  }
  st = (uint8_t)(m.dtc_sts_test_failed | (m.dtc_sts_test_failed_this_op_cycle << 1) | (m.dtc_sts_pending << 2) |
                 (m.dtc_sts_confirmed << 3) | (m.dtc_sts_not_completed_since_clear << 4) |
                 (m.dtc_sts_failed_since_clear << 5) | (m.dtc_sts_not_completed_this_op_cycle << 6) |
                 (m.dtc_sts_warning_indicator << 7));
  if (recorded) {
    unsigned i;
    for (i = 0U; i < rp.n_dtc_ecu; i++) {
      if (rp.dtc_code_ecu[i] == m.dtc_code) {
        break;
      }
    }
    if (i == rp.n_dtc_ecu) {
      if (i >= 64U) {
        return;
      }
      rp.dtc_code_ecu[i] = m.dtc_code;
      rp.dtc_st_ecu[i] = 0U;
      rp.dtc_occ_ecu[i] = 0U;
      rp.n_dtc_ecu++;
      emit_dtc("ecu", m.dtc_code, st, m.dtc_occurrence, t_us);
    } else if ((rp.dtc_st_ecu[i] != st) || (rp.dtc_occ_ecu[i] != m.dtc_occurrence)) {
      emit_dtc("ecu", m.dtc_code, st, m.dtc_occurrence, t_us);
    } else {
      /* unchanged */
    }
    rp.dtc_st_ecu[i] = st;
    rp.dtc_occ_ecu[i] = m.dtc_occurrence;
  } else {
    const int32_t idx = canfdi_dtc_find(&rp.app.dtc, m.dtc_code);
    if ((idx < 0) || (idx >= (int32_t)CANFDI_DTC_COUNT)) {
      return;
    }
    if (!rp.dtc_seen_rep[idx] || (rp.dtc_st_rep[idx] != st) || (rp.dtc_occ_rep[idx] != m.dtc_occurrence)) {
      const bool tf_rise = ((st & 1U) != 0U) && (!rp.dtc_seen_rep[idx] || ((rp.dtc_st_rep[idx] & 1U) == 0U));
      emit_dtc("replay", m.dtc_code, st, m.dtc_occurrence, t_us);
      if (tf_rise) {
        emit_evidence();
      }
    }
    rp.dtc_seen_rep[idx] = true;
    rp.dtc_st_rep[idx] = st;
    rp.dtc_occ_rep[idx] = m.dtc_occurrence;
  }
}

/* ------------------------------------------------------------ monitors */

/* Why each monitor is not judged this step (WHY_NONE: judged), for a start
 * at power-up (power_up) or mid-drive. */
static void monitor_whys(bool dcm_cmd_known, bool thr_cmd_known, bool power_up, uint8_t w[N_MON])
{
  const canfdi_app_t *a = &rp.app;
  const bool gap = rp.step_log_us < rp.gap_until_log_us;
  const int64_t settle_until =
      power_up ? rp.settle_until_log_us
               : ((rp.settle_until_log_us > (rp.first_step_log_us + opt.settle_us)) ? rp.settle_until_log_us
                                                                                   : (rp.first_step_log_us + opt.settle_us));
  const bool settle = rp.step_log_us < settle_until;
  const uint8_t settle_why = (power_up || (rp.settle_why == WHY_SETTLE_GAP)) ? rp.settle_why : (uint8_t)WHY_SETTLE_START;
  const bool dcm_rx = a->rx.frame[CANFDI_RX_F_DCM_SENSOR].received && !a->rx.frame[CANFDI_RX_F_DCM_SENSOR].timed_out;
  const bool thr_rx = a->rx.frame[CANFDI_RX_F_THR_SENSOR].received && !a->rx.frame[CANFDI_RX_F_THR_SENSOR].timed_out;
  const bool dcm_in = canfdi_rx_valid(&a->rx, CANFDI_RX_IN_DCM_UA) && canfdi_rx_valid(&a->rx, CANFDI_RX_IN_DCM_IA) &&
                      canfdi_rx_valid(&a->rx, CANFDI_RX_IN_DCM_OMEGA);
  const bool thr_in = canfdi_rx_valid(&a->rx, CANFDI_RX_IN_THR_TPS1) && canfdi_rx_valid(&a->rx, CANFDI_RX_IN_THR_TPS2) &&
                      canfdi_rx_valid(&a->rx, CANFDI_RX_IN_THR_IMOT) && canfdi_rx_valid(&a->rx, CANFDI_RX_IN_THR_USUPPLY);
  const bool tps_in = canfdi_rx_usable(&a->rx, CANFDI_RX_IN_THR_TPS1) && canfdi_rx_usable(&a->rx, CANFDI_RX_IN_THR_TPS2);
  w[MON_COM_DCM] = gap ? WHY_GAP : WHY_NONE;
  w[MON_COM_THR] = gap ? WHY_GAP : WHY_NONE;
  w[MON_COM_SP] = gap ? WHY_GAP : WHY_NONE;
  w[MON_TPS_RANGE] = gap ? WHY_GAP : (!thr_rx ? WHY_THR_FRAME : (!tps_in ? WHY_THR_INPUTS : WHY_NONE));
  w[MON_DCM_MODELS] = gap      ? WHY_GAP
                      : settle ? settle_why
                      : opt.no_models[0] ? WHY_MODELS_DCM
                      : !dcm_rx ? WHY_DCM_FRAME
                      : !dcm_in ? WHY_DCM_INPUTS
                      : !a->dcm.learnt ? WHY_DCM_UNLEARNT
                      : (a->dcm.learn_check == CANFDI_APP_LEARN_FAULT) ? WHY_DCM_TAINTED
                      : (a->dcm.learn_check == CANFDI_APP_LEARN_PENDING) ? WHY_DCM_UNCHECKED
                      : (a->dcm.rearm > 0U) ? WHY_DCM_REARM
                                : WHY_NONE;
  w[MON_DCM_CMD] = (w[MON_DCM_MODELS] != WHY_NONE) ? w[MON_DCM_MODELS] : (!dcm_cmd_known ? WHY_DCM_CMD : WHY_NONE);
  w[MON_THR_MODELS] = gap      ? WHY_GAP
                      : settle ? settle_why
                      : opt.no_models[1] ? WHY_MODELS_THR
                      : !thr_rx ? WHY_THR_FRAME
                      : !thr_in ? WHY_THR_INPUTS
                      : !thr_cmd_known ? WHY_THR_CMD
                      : (a->thr.rearm > 0U) ? WHY_THR_REARM
                                       : WHY_NONE;
  w[MON_THR_TRACK] = (w[MON_THR_MODELS] != WHY_NONE) ? w[MON_THR_MODELS]
                     : !power_up                    ? WHY_THR_REF
                     : (rp.thr_apart_steps > 0U)    ? WHY_THR_APART
                                                    : WHY_NONE;
}

static void emit_monitors(int64_t t_us, const uint8_t w[N_MON])
{
  unsigned m;
  for (m = 0U; m < N_MON; m++) {
    if (!rp.mon_init || (w[m] != rp.mon_why[m])) {
      fprintf(ev, "{\"ev\":\"mon\",\"file\":%d,\"t\":", rp.file_index);
      ev_time(t_us);
      fprintf(ev, ",\"mon\":\"%s\",\"tested\":%s", mon_name[m], (w[m] == WHY_NONE) ? "true" : "false");
      if (w[m] != WHY_NONE) {
        const char *txt = (w[m] >= WHY_MODELS_DCM) ? opt.no_models_why : why_text[w[m]];
        fprintf(ev, ",\"why\":");
        ev_str(txt, strlen(txt));
      }
      fprintf(ev, "}\n");
      rp.mon_why[m] = w[m];
    }
  }
  rp.mon_init = true;
}

/* The monitors of this step; while the start is not decided both variants
 * are kept and emitted once it is. */
static void flush_monitors(void)
{
  unsigned i;
  const bool pu = (rp.start_mode == START_POWER_UP);
  for (i = 0U; i < rp.n_mon_buf; i++) {
    emit_monitors(rp.mon_buf[i].t_us, pu ? rp.mon_buf[i].w_pu : rp.mon_buf[i].w_md);
  }
  rp.n_mon_buf = 0U;
}

static void eval_monitors(bool dcm_cmd_known, bool thr_cmd_known)
{
  if (rp.start_decided && (rp.n_mon_buf > 0U)) {
    flush_monitors();
  }
  if (rp.start_decided) {
    uint8_t w[N_MON];
    monitor_whys(dcm_cmd_known, thr_cmd_known, rp.start_mode == START_POWER_UP, w);
    emit_monitors(rp.step_log_us, w);
  } else if (rp.n_mon_buf < PU_MAX_STEPS) {
    mon_buf_t *b = &rp.mon_buf[rp.n_mon_buf++];
    b->t_us = rp.step_log_us;
    monitor_whys(dcm_cmd_known, thr_cmd_known, true, b->w_pu);
    monitor_whys(dcm_cmd_known, thr_cmd_known, false, b->w_md);
  } else {
    /* decided at PU_MAX_STEPS at the latest */
  }
}

/* ------------------------------------------------------------ per step */

static void emit_state_changes(void)
{
  const canfdi_actmgr_out_t *m = &rp.app.fb.mgr;
  unsigned c;
  if (!rp.deg_init || (m->dcm_state != rp.deg[0]) || (m->thr_state != rp.deg[1]) || (m->dcm.bridge != rp.bridge) ||
      (m->thr_limp_home != rp.limp) || (m->dcm_reason != rp.deg_reason[0]) || (m->thr_reason != rp.deg_reason[1])) {
    fprintf(ev, "{\"ev\":\"deg\",\"file\":%d,\"t\":", rp.file_index);
    ev_time(rp.step_log_us);
    fprintf(ev, ",\"dcm\":\"%s\",\"thr\":\"%s\",\"dcm_reason\":%u,\"thr_reason\":%u,\"bridge\":%u,\"limp\":%s}\n",
            deg_name(m->dcm_state), deg_name(m->thr_state), m->dcm_reason, m->thr_reason, m->dcm.bridge,
            m->thr_limp_home ? "true" : "false");
    rp.deg[0] = m->dcm_state;
    rp.deg[1] = m->thr_state;
    rp.deg_reason[0] = m->dcm_reason;
    rp.deg_reason[1] = m->thr_reason;
    rp.bridge = m->dcm.bridge;
    rp.limp = m->thr_limp_home;
  }
  for (c = 0U; c < CANFDI_DIAG_N_COMP; c++) {
    uint8_t conf = 0U;
    const uint8_t f = canfdi_diagnosis_isolated(&rp.app.diagnosis, (uint8_t)(CANFDI_COMPONENT_DC_MOTOR + c), &conf);
    if (!rp.deg_init || (f != rp.iso[c])) {
      fprintf(ev, "{\"ev\":\"iso\",\"file\":%d,\"t\":", rp.file_index);
      ev_time(rp.step_log_us);
      fprintf(ev, ",\"comp\":%u,\"fault\":%u,\"conf\":%u}\n", c, f, conf);
      rp.iso[c] = f;
    }
  }
  rp.deg_init = true;
}

static void sample(void)
{
  const canfdi_symptoms_t *y = &rp.app.sym;
  unsigned i;
  for (i = 0U; i < 4U; i++) {
    const int32_t d = y->dcm_rn_q16[i];
    const int32_t t = y->thr_rn_q16[i];
    if ((((unsigned)y->dcm_rn_valid >> i) & 1U) != 0U) {
      if (((((unsigned)rp.sval[0] >> i) & 1U) == 0U) || (llabs((long long)d) > llabs((long long)rp.smax[i]))) {
        rp.smax[i] = d;
      }
      rp.sval[0] = (uint8_t)(rp.sval[0] | (1U << i));
    }
    if ((((unsigned)y->thr_rn_valid >> i) & 1U) != 0U) {
      if (((((unsigned)rp.sval[1] >> i) & 1U) == 0U) || (llabs((long long)t) > llabs((long long)rp.smax[4U + i]))) {
        rp.smax[4U + i] = t;
      }
      rp.sval[1] = (uint8_t)(rp.sval[1] | (1U << i));
    }
  }
  if ((opt.every_us > 0) && (rp.step_log_us >= rp.next_sample_log_us)) {
    const canfdi_est_dcm_t *ed = &rp.app.est_dcm;
    const canfdi_est_thr_t *et = &rp.app.est_thr;
    fprintf(ev, "{\"ev\":\"s\",\"file\":%d,\"t\":", rp.file_index);
    ev_time(rp.step_log_us);
    fprintf(ev, ",\"r\":[");
    for (i = 0U; i < 8U; i++) {
      fprintf(ev, "%s", (i > 0U) ? "," : "");
      ev_q16(rp.smax[i]);
    }
    fprintf(ev, "],\"rv\":[%u,%u],\"p\":[", rp.sval[0], rp.sval[1]);
    for (i = 0U; i < 4U; i++) {
      fprintf(ev, "%s", (i > 0U) ? "," : "");
      ev_q16(y->dcm_pdev_q16[i]);
    }
    for (i = 0U; i < 4U; i++) {
      fprintf(ev, ",");
      ev_q16(y->thr_pdev_q16[i]);
    }
    fprintf(ev, "],\"pv\":[%u,%u],\"e\":[%.5g,%.5g,%.5g,%.5g,%.5g,%.5g,%.5g,%.5g],\"uac\":", (unsigned)y->dcm_pdev_valid,
            (unsigned)y->thr_pdev_valid, (double)canfdi_est_dcm_ra_q16(ed) / 65536.0,
            (double)canfdi_est_dcm_psi_q16(ed) / 65536.0, (double)canfdi_est_dcm_j_q24(ed) / 16777216.0,
            (double)canfdi_est_dcm_mc_q16(ed) / 65536.0, (double)canfdi_est_thr_r_q16(et) / 65536.0,
            (double)canfdi_est_thr_k_q16(et) / 65536.0, (double)canfdi_est_thr_pretension_q16(et) / 65536.0,
            (double)canfdi_est_thr_friction_q16(et) / 65536.0);
    ev_q16(y->dcm_ua_cmd_rn_q16);
    fprintf(ev, ",\"uacv\":%s,\"trk\":", ((y->flags & CANFDI_SYM_F_DCM_UA_CMD_VALID) != 0U) ? "true" : "false");
    ev_q16(rp.app.actmon_out.thr_track_err_rad_q16);
    fprintf(ev, ",\"deg\":[%u,%u]}\n", rp.app.fb.mgr.dcm_state, rp.app.fb.mgr.thr_state);
    rp.sval[0] = 0U;
    rp.sval[1] = 0U;
    memset(rp.smax, 0, sizeof rp.smax);
    rp.next_sample_log_us = rp.step_log_us + opt.every_us;
  }
}

static const char *const rx_frame_name[CANFDI_RX_F_COUNT] = {"DcmSensor", "ThrSensor", "SetpointDcm", "SetpointThr"};

static void rx_quality(bool flush)
{
  const canfdi_rx_diag_t *d = &rp.app.rx.diag;
  unsigned f;
  for (f = 0U; f < CANFDI_RX_F_COUNT; f++) {
    const canfdi_rx_frame_state_t *fs = &rp.app.rx.frame[f];
    const bool ok = fs->received && !fs->timed_out;
    const uint64_t now[5] = {d->length_err[f], d->crc_err[f], d->counter_err[f], d->implausible[f], d->timeouts[f]};
    if (!rp.frame_init || (ok != rp.frame_ok[f])) {
      fprintf(ev, "{\"ev\":\"frame\",\"file\":%d,\"t\":", rp.file_index);
      ev_time(rp.step_log_us);
      fprintf(ev, ",\"name\":\"%s\",\"ok\":%s,\"received\":%s}\n", rx_frame_name[f], ok ? "true" : "false",
              fs->received ? "true" : "false");
      rp.frame_ok[f] = ok;
    }
    if (flush) {
      unsigned k;
      bool any = false;
      for (k = 0U; k < 5U; k++) {
        any = any || (now[k] != rp.rxc.rej[f][k]);
      }
      if (any) {
        fprintf(ev, "{\"ev\":\"rxq\",\"file\":%d,\"t\":", rp.file_index);
        ev_time(rp.step_log_us);
        fprintf(ev,
                ",\"frame\":\"%s\",\"length\":%" PRIu64 ",\"crc\":%" PRIu64 ",\"counter\":%" PRIu64
                ",\"implausible\":%" PRIu64 ",\"timeouts\":%" PRIu64 "}\n",
                rx_frame_name[f], now[0] - rp.rxc.rej[f][0], now[1] - rp.rxc.rej[f][1], now[2] - rp.rxc.rej[f][2],
                now[3] - rp.rxc.rej[f][3], now[4] - rp.rxc.rej[f][4]);
        for (k = 0U; k < 5U; k++) {
          rp.rxc.rej[f][k] = now[k];
        }
      }
    }
  }
  rp.frame_init = true;
}

/* Power-up or mid-drive (see the header); at_end: the log ended first. */
static void decide_start(bool at_end)
{
  if (rp.start_decided) {
    return;
  }
  if (opt.start != START_AUTO) {
    rp.start_mode = opt.start;
  } else if ((rp.mismatched > 0U) || (rp.rec_only > 0U)) {
    rp.start_mode = START_MID_DRIVE;
  } else if (rp.matched >= PU_MIN_FRAMES) {
    rp.start_mode = START_POWER_UP;
  } else if (at_end) {
    rp.start_mode = (rp.matched > 0U) ? START_POWER_UP : START_MID_DRIVE;
  } else if (rp.steps >= PU_MAX_STEPS) {
    rp.start_mode = START_MID_DRIVE;
  } else {
    return;
  }
  rp.start_decided = true;
  if (rp.start_mode == START_MID_DRIVE) {
    rp.settle_until_log_us = rp.first_step_log_us + opt.settle_us;
    rp.settle_why = WHY_SETTLE_START;
  }
  fprintf(ev, "{\"ev\":\"start\",\"file\":%d,\"mode\":\"%s\",\"decided_by\":\"%s\",\"matched\":%" PRIu64
              ",\"mismatched\":%" PRIu64 ",\"settle_until\":",
          rp.file_index, (rp.start_mode == START_POWER_UP) ? "power-up" : "mid-drive",
          (opt.start != START_AUTO) ? "option" : "frames", rp.matched, rp.mismatched);
  ev_time((rp.start_mode == START_MID_DRIVE) ? rp.settle_until_log_us : 0);
  fprintf(ev, "}\n");
}

/* ------------------------------------------------------------ one step */

static void bus_flush(void)
{
  if (rp.bus_sec >= 0) {
    fprintf(ev, "{\"ev\":\"bus\",\"file\":%d,\"t\":%" PRId64 ",\"frames\":%" PRIu64 ",\"bits\":%" PRIu64
                ",\"err\":%" PRIu64 "}\n",
            rp.file_index, rp.bus_sec, rp.bus_frames, rp.bus_bits, rp.bus_err);
  }
  rp.bus_frames = 0U;
  rp.bus_bits = 0U;
  rp.bus_err = 0U;
}

/* The step at rp.step_log_us with the supervisor's clock now_us. */
static void run_step(uint32_t now_us)
{
  canfdi_tx_frame_t out[CANFDI_APP_MAX_TX];
  bool dk = true;
  bool tk = true;
  int32_t n;
  int32_t j;
  const int64_t sec_before = (rp.steps == 0U) ? -1 : (rp.step_log_us - STEP_US) / 1000000;
  if (rp.steps == 0U) {
    rp.first_step_log_us = rp.step_log_us;
    rp.next_sample_log_us = rp.step_log_us;
  }
  apply_commands(&dk, &tk);
  n = canfdi_app_step(&rp.app, now_us, out);
  for (j = 0; j < n; j++) {
    const canfdi_tx_frame_t *f = &out[j];
    const int idx = ecu_index(f->id);
    if (f->id == CANFDI_RP_MSG_DCM_ACTUATOR_FRAME_ID) {
      decode_dcm_cmd(f->data, f->dlc, &rp.dcm_own);
    } else if (f->id == CANFDI_RP_MSG_THR_ACTUATOR_FRAME_ID) {
      decode_thr_cmd(f->data, f->dlc, &rp.thr_own);
    } else if (f->id == CANFDI_RP_MSG_ECU_DTC_FRAME_ID) {
      dtc_frame(false, f->data, f->dlc, rp.step_log_us);
    } else {
      /* compared below only */
    }
    if (idx >= 0) {
      ecu_frame(idx, false, f->data, f->dlc, rp.step_log_us);
    }
  }
  if (canfdi_app_reset_requested(&rp.app)) {
    /* an ECUReset the replayed server answered (the recording holds the
     * tester's request): the port's hard reset, a power cycle through the
     * memory's image, as canfdi-ecu and the SIL rig perform it */
    int32_t rc;
    rp.image_len = canfdi_app_power_down(&rp.app, rp.image, (uint32_t)sizeof rp.image);
    rc = canfdi_app_power_up(&rp.app, &rp.cal, now_us, rp.image, (rp.image_len > 0) ? (uint32_t)rp.image_len : 0U);
    /* the recorded ECU restarted too: its E2E counters start again */
    (void)canfdi_e2e_rx_init(&rp.rec_dtc_e2e, (uint16_t)CANFDI_RP_MSG_ECU_DTC_FRAME_ID, 2U);
    fprintf(ev, "{\"ev\":\"power_cycle\",\"file\":%d,\"image_bytes\":%d,\"rc\":%d,\"ecu_reset\":true,\"t\":",
            rp.file_index, (int)rp.image_len, (int)rc);
    ev_time(rp.step_log_us);
    fprintf(ev, "}\n");
  }
  emit_state_changes();
  rp.steps++;
  decide_start(false);
  eval_monitors(dk, tk);
  sample();
  rx_quality((rp.step_log_us / 1000000) != sec_before);
  rp.dcm_batch0 = rp.dcm_latest;
  rp.thr_batch0 = rp.thr_latest;
  rp.dcm_sample_set = false;
  rp.thr_sample_set = false;
  rp.batch_nonempty = false;
}

/* ------------------------------------------------------------ frames */

static void count_line_event(const char *what, uint64_t line, int64_t t_us, uint64_t n)
{
  if (n <= MAX_MISC_EVENTS) {
    fprintf(ev, "{\"ev\":\"%s\",\"file\":%d,\"line\":%" PRIu64 ",\"t\":", what, rp.file_index, line);
    ev_time(t_us);
    fprintf(ev, "}\n");
  }
}

static void note_unknown(uint32_t id, bool ext)
{
  unsigned i;
  const uint32_t key = id | (ext ? 0x80000000UL : 0U);
  rp.unknown_frames++;
  for (i = 0U; i < rp.n_unknown; i++) {
    if (rp.unknown_id[i] == key) {
      rp.unknown_n[i]++;
      return;
    }
  }
  if (rp.n_unknown < N_UNKNOWN_IDS) {
    rp.unknown_id[rp.n_unknown] = key;
    rp.unknown_n[rp.n_unknown] = 1U;
    rp.n_unknown++;
  }
}

/* Bits of a frame on the bus without stuffing: classic 47 + 8 per byte
 * (11-bit id), 67 + 8 per byte (29-bit). */
static uint64_t frame_bits(const rp_frame_t *f)
{
  return (f->ext ? 67U : 47U) + (8U * (uint64_t)f->len);
}

/* Whether the frame is on the channel judged (fixing it on the first frame
 * of the DBC when no --channel was given). */
static bool on_channel(const rp_frame_t *f, uint64_t line)
{
  unsigned i;
  if (!rp.chan_fixed && !f->ext && (f->kind == RP_KIND_DATA) && in_dbc(f->id)) {
    rp_chan_set(rp.chan, f->chan);
    rp.chan_fixed = true;
    fprintf(ev, "{\"ev\":\"channel\",\"file\":%d,\"name\":", rp.file_index);
    ev_str(rp.chan, strlen(rp.chan));
    fprintf(ev, ",\"line\":%" PRIu64 ",\"chosen\":\"%s\"}\n", line, (opt.channel != NULL) ? "option" : "first frame of the DBC");
  }
  if (!rp.chan_fixed || rp_chan_eq(f->chan, rp.chan)) {
    return true;
  }
  for (i = 0U; i < rp.n_other; i++) {
    if (rp_chan_eq(rp.other_chan[i], f->chan)) {
      rp.other_chan_n[i]++;
      return false;
    }
  }
  if (rp.n_other < N_CHANS) {
    rp_chan_set(rp.other_chan[rp.n_other], f->chan);
    rp.other_chan_n[rp.n_other] = 1U;
    rp.other_chan_line[rp.n_other] = line;
    rp.n_other++;
  }
  return false;
}

/* ------------------------------------------------------------ the timestamps grid */

/* x on the circle of one step, in (-STEP_US/2, STEP_US/2]. */
static int32_t wrap_step(int64_t x)
{
  int64_t w = x % STEP_US;
  if (w > (STEP_US / 2)) {
    w -= STEP_US;
  } else if (w <= -(STEP_US / 2)) {
    w += STEP_US;
  } else {
    /* in range */
  }
  return (int32_t)w;
}

/* The plant whose sensor frame f is, for the grid: 0 DcmSensor, 1
 * ThrSensor; -1 any other frame, one of another channel than chan, and one
 * of a plant mapped to a slower rate than the step (--rx-rate: it comes
 * one step in several, so where it falls says nothing of the step times). */
static int grid_plant(const rp_frame_t *f, const char *chan)
{
  int i = -1;
  if ((f->kind == RP_KIND_DATA) && !f->ext && rp_chan_eq(f->chan, chan)) {
    if (f->id == CANFDI_RP_MSG_DCM_SENSOR_FRAME_ID) {
      i = CANFDI_RX_F_DCM_SENSOR;
    } else if (f->id == CANFDI_RP_MSG_THR_SENSOR_FRAME_ID) {
      i = CANFDI_RX_F_THR_SENSOR;
    } else {
      /* not a sensor frame */
    }
  }
  if ((i >= 0) && (opt.rx_rate_ms[i] > (uint32_t)(STEP_US / 1000))) {
    i = -1;
  }
  return i;
}

/* A sensor frame of plant i, e microseconds after the time of the step it
 * went into: the plant's filtered phase to the step times (its first frame
 * sets it). */
static void track_phase(unsigned i, int64_t e)
{
  unsigned k;
  for (k = 0U; k < 2U; k++) {
    if (rp.phase_seen[k] && ((rp.steps - rp.phase_step[k]) > PHASE_STALE_STEPS)) {
      /* its frames stopped (a timeout): the other plant's alone steer the
       * grid, and its next frame sets its phase anew */
      rp.phase_seen[k] = false;
    }
  }
  rp.phase_step[i] = rp.steps;
  if (!rp.phase_seen[i]) {
    rp.phase_us[i] = wrap_step(e);
    rp.phase_seen[i] = true;
  } else {
    rp.phase_us[i] = wrap_step((int64_t)rp.phase_us[i] + (wrap_step(e - rp.phase_us[i]) / PHASE_FILTER));
  }
}

/* How far the sensor frame nearest to a step boundary would be from it
 * with the grid moved by c (STEP_US / 2: no sensor frame). */
static int32_t grid_room(int32_t c)
{
  int32_t room = STEP_US / 2;
  unsigned i;
  for (i = 0U; i < 2U; i++) {
    if (rp.phase_seen[i]) {
      const int32_t e = wrap_step((int64_t)rp.phase_us[i] - c);
      const int32_t r = (STEP_US / 2) - ((e < 0) ? -e : e);
      room = (r < room) ? r : room;
    }
  }
  return room;
}

/* The move that puts the sensor frames farthest from the step boundaries:
 * onto their phase when one plant's frames come; when both come, onto the
 * middle of the shorter arc between their phases (the boundary then lies
 * in the middle of the longer one), the smaller move of two equal ones. */
static int32_t grid_best(void)
{
  int32_t c = 0;
  if (rp.phase_seen[0] && rp.phase_seen[1]) {
    const int32_t c1 = wrap_step((int64_t)rp.phase_us[0] + (wrap_step((int64_t)rp.phase_us[1] - rp.phase_us[0]) / 2));
    const int32_t c2 = wrap_step((int64_t)c1 + (STEP_US / 2));
    const int32_t r1 = grid_room(c1);
    const int32_t r2 = grid_room(c2);
    const int32_t a1 = (c1 < 0) ? -c1 : c1;
    const int32_t a2 = (c2 < 0) ? -c2 : c2;
    c = ((r1 > r2) || ((r1 == r2) && (a1 <= a2))) ? c1 : c2;
  } else if (rp.phase_seen[0] || rp.phase_seen[1]) {
    c = rp.phase_us[rp.phase_seen[0] ? 0 : 1];
  } else {
    /* no sensor frame yet */
  }
  return c;
}

/* The grid moved by c: the phases relative to it. */
static void grid_shift(int32_t c)
{
  unsigned i;
  for (i = 0U; i < 2U; i++) {
    rp.phase_us[i] = wrap_step((int64_t)rp.phase_us[i] - c);
  }
}

/* The timestamps grid follows the sensor frames (the file header comment):
 * once their best step time is GRID_MOVE_US or more off the grid's, the
 * next step moves there. */
static void grid_follow(void)
{
  const int32_t c = grid_best();
  if (((c >= GRID_MOVE_US) || (c <= -GRID_MOVE_US)) && (grid_room(c) > grid_room(0))) {
    rp.next_step_abs += c;
    grid_shift(c);
    rp.grid_moves++;
  }
}

/* A gap or a jump of the time stamps: the sensor frames after it set the
 * grid anew (the logger may have restarted, the stamps moved by any amount). */
static void grid_forget(void)
{
  rp.phase_seen[0] = false;
  rp.phase_seen[1] = false;
}

/* The grid's start (timestamps clock): the sensor frames' mean phases to
 * the first frame's time stamp in the frames read ahead, so that the first
 * step takes its plant's first samples as the later ones take theirs. */
static void grid_seed(void)
{
  unsigned i;
  unsigned k;
  const int64_t t0 = rp.look[0].ts_us;
  const char *chan = rp.chan_fixed ? rp.chan : NULL;
  for (i = 0U; (chan == NULL) && (i < rp.n_look); i++) {
    /* the channel on_channel() will judge */
    const rp_frame_t *f = &rp.look[i];
    if ((f->kind == RP_KIND_DATA) && !f->ext && in_dbc(f->id)) {
      chan = f->chan;
    }
  }
  for (k = 0U; k < 2U; k++) {
    int64_t sum = 0;
    int64_t n = 0;
    int32_t ref = 0;
    for (i = 0U; (chan != NULL) && (i < rp.n_look); i++) {
      const rp_frame_t *f = &rp.look[i];
      if ((grid_plant(f, chan) == (int)k) && (f->ts_us >= t0) && ((f->ts_us - t0) <= LOOKAHEAD_US)) {
        /* around the first one's phase: the mean of a circular quantity */
        if (n == 0) {
          ref = wrap_step(f->ts_us - t0);
        }
        sum += wrap_step(f->ts_us - t0 - ref);
        n++;
      }
    }
    rp.phase_seen[k] = (n > 0);
    rp.phase_step[k] = 0U;
    rp.phase_us[k] = (n > 0) ? wrap_step(ref + (sum / n)) : 0;
  }
  rp.grid_seed_us = grid_best();
  if ((rp.grid_seed_us < GRID_MOVE_US) && (rp.grid_seed_us > -GRID_MOVE_US)) {
    rp.grid_seed_us = 0; /* close enough: the first frame's time stamp */
  }
  grid_shift(rp.grid_seed_us);
}

/* One frame of the channel judged, in the current batch. frame_log_us: its
 * log time (ECU frames are reported at it); now_us: the supervisor's clock
 * at its reception. */
static void handle_frame(const rp_frame_t *f, uint64_t line, int64_t frame_log_us, uint32_t now_us)
{
  const int64_t sec = frame_log_us / 1000000;
  if (sec != rp.bus_sec) {
    bus_flush();
    rp.bus_sec = sec;
  }
  rp.bus_frames++;
  rp.bus_bits += frame_bits(f);
  if (f->kind == RP_KIND_ERROR) {
    rp.bus_err++;
    rp.err_frames++;
    if (rp.err_frames <= MAX_MISC_EVENTS) {
      fprintf(ev, "{\"ev\":\"errframe\",\"file\":%d,\"line\":%" PRIu64 ",\"t\":", rp.file_index, line);
      ev_time(frame_log_us);
      fprintf(ev, ",\"class\":%lu}\n", (unsigned long)f->id);
    }
    return;
  }
  if (!on_channel(f, line)) {
    return;
  }
  if (f->kind == RP_KIND_FD) {
    rp.fd_frames++;
    rp.fd_line = (rp.fd_line == 0U) ? line : rp.fd_line;
    count_line_event("fd", line, frame_log_us, rp.fd_frames);
    return;
  }
  if (f->kind == RP_KIND_REMOTE) {
    rp.remote_frames++;
    rp.remote_line = (rp.remote_line == 0U) ? line : rp.remote_line;
    return;
  }
  if (f->ext) {
    rp.ext_frames++;
    rp.ext_line = (rp.ext_line == 0U) ? line : rp.ext_line;
    note_unknown(f->id, true);
    return;
  }
  if (ecu_input(f->id)) {
    if (f->id == CANFDI_RP_MSG_DCM_SENSOR_FRAME_ID) {
      rp.dcm_sample = rp.dcm_latest;
      rp.dcm_sample_set = true;
    } else if (f->id == CANFDI_RP_MSG_THR_SENSOR_FRAME_ID) {
      rp.thr_sample = rp.thr_latest;
      rp.thr_sample_set = true;
    } else {
      /* setpoints, UDS requests */
    }
    (void)canfdi_app_rx_frame(&rp.app, f->id, f->data, f->len, now_us);
    rp.batch_nonempty = true;
  } else if (ecu_index(f->id) >= 0) {
    const int idx = ecu_index(f->id);
    rp.rec_ecu_frames++;
    if (f->id == CANFDI_RP_MSG_DCM_ACTUATOR_FRAME_ID) {
      struct canfdi_rp_msg_dcm_actuator_t m;
      if ((f->len == 8U) && (canfdi_rp_msg_dcm_actuator_unpack(&m, f->data, f->len) == 0) &&
          (m.dcm_actuator_crc == canfdi_e2e_frame_crc((uint16_t)f->id, f->data, f->len))) {
        decode_dcm_cmd(f->data, f->len, &rp.dcm_latest);
        rp.dcm_latest.step = rp.steps;
      } else {
        rp.cmd_bad_crc++;
      }
    } else if (f->id == CANFDI_RP_MSG_THR_ACTUATOR_FRAME_ID) {
      struct canfdi_rp_msg_thr_actuator_t m;
      if ((f->len == 8U) && (canfdi_rp_msg_thr_actuator_unpack(&m, f->data, f->len) == 0) &&
          (m.thr_actuator_crc == canfdi_e2e_frame_crc((uint16_t)f->id, f->data, f->len))) {
        decode_thr_cmd(f->data, f->len, &rp.thr_latest);
        rp.thr_latest.step = rp.steps;
      } else {
        rp.cmd_bad_crc++;
      }
    } else if (f->id == CANFDI_RP_MSG_ECU_DTC_FRAME_ID) {
      dtc_frame(true, f->data, f->len, frame_log_us);
    } else {
      /* compared only */
    }
    ecu_frame(idx, true, f->data, (f->len <= 8U) ? f->len : 8U, frame_log_us);
  } else if (!in_dbc(f->id)) {
    note_unknown(f->id, false);
  } else {
    /* SimFaultInject/Clear, SimPlantStatus, a SimStep in timestamps mode:
     * the supervisor does not receive them */
  }
}

/* ------------------------------------------------------------ clocks */

static void mark_gap(int64_t from_log_us, int64_t to_log_us)
{
  rp.gaps++;
  if (rp.gaps <= MAX_GAP_EVENTS) {
    fprintf(ev, "{\"ev\":\"gap\",\"file\":%d,\"t0\":", rp.file_index);
    ev_time(from_log_us);
    fprintf(ev, ",\"t1\":");
    ev_time(to_log_us);
    fprintf(ev, "}\n");
  }
  /* the communication monitors: until the frames are back and judged again
   * (the frame debounce class needs up to six good frames: 20 ms) */
  if (to_log_us + 20000 > rp.gap_until_log_us) {
    rp.gap_until_log_us = to_log_us + 20000;
  }
  if (to_log_us + opt.settle_us > rp.settle_until_log_us) {
    rp.settle_until_log_us = to_log_us + opt.settle_us;
    rp.settle_why = WHY_SETTLE_GAP;
  }
  /* the monitors of the steps inside the gap */
  if (from_log_us < rp.gap_until_log_us) {
    /* gap_until covers every later step; the steps of the gap come next */
  }
}

static int64_t shadow_next_us; /* timestamps: the supervisor's clock of the next step */

/* A frame at time stamp ts (shifted) on the accepted time base; stamp_ok:
 * ts is its own time stamp (not an outlier's, taken at the current time). */
static void ts_accept(const rp_frame_t *f, int64_t ts, uint64_t line, bool stamp_ok)
{
  int plant;
  if (ts < rp.last_ts_us) {
    const int64_t back = rp.last_ts_us - ts;
    rp.back_n++;
    if (back > opt.gap_us) {
      rp.shift_us += back;
      grid_forget();
      fprintf(ev, "{\"ev\":\"rebase\",\"file\":%d,\"line\":%" PRIu64 ",\"t\":", rp.file_index, line);
      ev_time(log_us_of_abs(rp.last_ts_us));
      fprintf(ev, ",\"back_us\":%" PRId64 "}\n", back);
    } else if (rp.back_n <= MAX_MISC_EVENTS) {
      fprintf(ev, "{\"ev\":\"back\",\"file\":%d,\"line\":%" PRIu64 ",\"t\":", rp.file_index, line);
      ev_time(log_us_of_abs(rp.last_ts_us));
      fprintf(ev, ",\"back_us\":%" PRId64 "}\n", back);
    } else {
      /* counted */
    }
    ts = rp.last_ts_us;
    stamp_ok = false; /* taken at the last one's: where the frame fell is not known */
  }
  if ((ts - rp.last_ts_us) > opt.gap_us) {
    mark_gap(log_us_of_abs(rp.last_ts_us), log_us_of_abs(ts));
    grid_forget();
    if ((ts - rp.next_step_abs) > GAP_STEP_MAX_US) {
      /* step through the first GAP_STEP_MAX_US of it, then skip to the end
       * (the supervisor's clock sees only the steps it ran) */
      const int64_t stop = rp.next_step_abs + GAP_STEP_MAX_US;
      while (rp.next_step_abs < stop) {
        rp.step_log_us = log_us_of_abs(rp.next_step_abs);
        run_step((uint32_t)shadow_next_us);
        rp.next_step_abs += STEP_US;
        shadow_next_us += STEP_US;
      }
      rp.next_step_abs += ((ts - rp.next_step_abs) / STEP_US) * STEP_US;
    }
  }
  while (ts > (rp.next_step_abs + GRID_MARGIN_US)) {
    rp.step_log_us = log_us_of_abs(rp.next_step_abs);
    run_step((uint32_t)shadow_next_us);
    rp.next_step_abs += STEP_US;
    shadow_next_us += STEP_US;
  }
  rp.last_ts_us = ts;
  rp.step_log_us = log_us_of_abs(rp.next_step_abs);
  /* on the supervisor's clock a frame comes no later than its step */
  handle_frame(f, line, log_us_of_abs(ts),
               (uint32_t)(shadow_next_us - ((ts < rp.next_step_abs) ? (rp.next_step_abs - ts) : 0)));
  plant = rp.chan_fixed ? grid_plant(f, rp.chan) : -1;
  if (stamp_ok && (plant >= 0)) {
    track_phase((unsigned)plant, ts - rp.next_step_abs);
    grid_follow();
  }
}

static int64_t abs64(int64_t x) { return (x < 0) ? -x : x; }

/* The pending frames were outliers: each is reported and taken at the
 * current time (its content is kept, its time stamp is not believed). */
static void ts_flush_outliers(void)
{
  unsigned i;
  for (i = 0U; i < rp.n_pend; i++) {
    rp.outliers++;
    if (rp.outliers <= MAX_MISC_EVENTS) {
      fprintf(ev, "{\"ev\":\"outlier\",\"file\":%d,\"line\":%" PRIu64 ",\"t\":", rp.file_index, rp.pend_line[i]);
      ev_time(log_us_of_abs(rp.last_ts_us));
      fprintf(ev, ",\"stamp_s\":");
      ev_time(rp.pend[i].ts_us);
      fprintf(ev, "}\n");
    }
    ts_accept(&rp.pend[i], rp.last_ts_us, rp.pend_line[i], false);
  }
  rp.n_pend = 0U;
}

/*
 * A time stamp more than a gap away from the last (either way) starts a
 * new time base only when JUMP_CONFIRM frames in a row agree with it (a
 * pause of the logger, two logs concatenated); a frame that does not
 * follow it back to the old time base makes the pending ones outliers.
 */
static void ts_frame(rp_frame_t *f, uint64_t line)
{
  const int64_t ts = f->ts_us + rp.shift_us;
  if (!rp.have_t0) {
    rp.have_t0 = true;
    rp.t0_abs_us = ts;
    rp.origin_us = (ts < INT64_C(1000000000000)) ? 0 : ts;
    rp.next_step_abs = ts + rp.grid_seed_us;
    rp.last_ts_us = ts;
    shadow_next_us = 0;
  }
  if (rp.n_pend > 0U) {
    const int64_t base = rp.pend[rp.n_pend - 1U].ts_us + rp.shift_us;
    if (abs64(ts - base) <= opt.gap_us) {
      rp.pend[rp.n_pend] = *f;
      rp.pend_line[rp.n_pend] = line;
      rp.n_pend++;
      if (rp.n_pend >= JUMP_CONFIRM) {
        unsigned i;
        for (i = 0U; i < rp.n_pend; i++) {
          ts_accept(&rp.pend[i], rp.pend[i].ts_us + rp.shift_us, rp.pend_line[i], true);
        }
        rp.n_pend = 0U;
      }
      return;
    }
    ts_flush_outliers();
  }
  if (abs64(ts - rp.last_ts_us) > opt.gap_us) {
    rp.pend[0] = *f;
    rp.pend_line[0] = line;
    rp.n_pend = 1U;
    return;
  }
  ts_accept(f, ts, line, true);
}

static void ts_end(void)
{
  ts_flush_outliers();
  if (rp.batch_nonempty || (rp.have_t0 && (rp.last_ts_us >= rp.next_step_abs))) {
    rp.step_log_us = log_us_of_abs(rp.next_step_abs);
    run_step((uint32_t)shadow_next_us);
    rp.next_step_abs += STEP_US;
    shadow_next_us += STEP_US;
  }
}

static void simstep_frame(rp_frame_t *f, uint64_t line)
{
  if (!rp.have_t0) {
    rp.have_t0 = true;
    rp.origin_us = 0;
    rp.t0_abs_us = 0;
  }
  if ((f->kind == RP_KIND_DATA) && !f->ext && (f->id == CANFDI_RP_MSG_SIM_STEP_FRAME_ID) && on_channel(f, line)) {
    struct canfdi_rp_msg_sim_step_t m;
    int64_t k;
    const int64_t sec = rp.step_log_us / 1000000;
    if (sec != rp.bus_sec) {
      bus_flush();
      rp.bus_sec = sec;
    }
    rp.bus_frames++;
    rp.bus_bits += frame_bits(f);
    if ((f->len != 8U) || (canfdi_rp_msg_sim_step_unpack(&m, f->data, f->len) != 0)) {
      rp.simstep_bad++;
      return;
    }
    k = (int64_t)m.sim_step_index;
    if (rp.k0 < 0) {
      /* the supervisor's clock starts with the log's first step, as it
       * does on time stamps (from power-up: SimStep(0), the same clock) */
      rp.k0 = k;
    }
    if ((rp.last_k >= 0) && (k <= rp.last_k)) {
      rp.simstep_bad++;
      return;
    }
    if ((rp.last_k >= 0) && (k > (rp.last_k + 1))) {
      int64_t i;
      const int64_t stop = ((k - rp.last_k - 1) * STEP_US > GAP_STEP_MAX_US) ? (rp.last_k + 1 + (GAP_STEP_MAX_US / STEP_US)) : k;
      mark_gap((rp.last_k + 1) * STEP_US, k * STEP_US);
      for (i = rp.last_k + 1; i < stop; i++) {
        rp.step_log_us = i * STEP_US;
        run_step((uint32_t)((i - rp.k0) * STEP_US));
      }
    }
    rp.step_log_us = k * STEP_US;
    run_step((uint32_t)((k - rp.k0) * STEP_US));
    rp.last_k = k;
    return;
  }
  rp.step_log_us = ((rp.last_k >= 0) ? rp.last_k : 0) * STEP_US;
  /* The ECU's frames of step k: its actuator frames follow SimStep(k) (the
   * plant waits for them before SimStep(k+1)); its further frames of that
   * step may reach the bus after the plant's next frames, so they take the
   * step of the latest actuator frame, as canfdi-watch reads such logs. */
  if (!f->ext && (f->kind == RP_KIND_DATA) &&
      ((f->id == CANFDI_RP_MSG_DCM_ACTUATOR_FRAME_ID) || (f->id == CANFDI_RP_MSG_THR_ACTUATOR_FRAME_ID))) {
    rp.ecu_step_log_us = rp.step_log_us;
  }
  handle_frame(f, line, (ecu_index(f->id) >= 0) ? rp.ecu_step_log_us : rp.step_log_us,
               (uint32_t)((rp.last_k < 0) ? 0 : ((rp.last_k + 1 - rp.k0) * STEP_US)));
}

static void route(rp_frame_t *f, uint64_t line)
{
  if (rp.clock == CLOCK_SIMSTEP) {
    simstep_frame(f, line);
  } else {
    ts_frame(f, line);
  }
}

static void decide_clock(void)
{
  unsigned i;
  if (opt.clock != CLOCK_AUTO) {
    rp.clock = opt.clock;
  } else {
    rp.clock = CLOCK_TIMESTAMPS;
    for (i = 0U; i < rp.n_look; i++) {
      if ((rp.look[i].kind == RP_KIND_DATA) && !rp.look[i].ext && (rp.look[i].id == CANFDI_RP_MSG_SIM_STEP_FRAME_ID)) {
        rp.clock = CLOCK_SIMSTEP;
      }
    }
  }
  rp.clock_decided = true;
  fprintf(ev, "{\"ev\":\"clock\",\"file\":%d,\"clock\":\"%s\"}\n", rp.file_index,
          (rp.clock == CLOCK_SIMSTEP) ? "simstep" : "timestamps");
  if ((rp.clock == CLOCK_TIMESTAMPS) && (rp.n_look > 0U)) {
    grid_seed();
  }
  for (i = 0U; i < rp.n_look; i++) {
    route(&rp.look[i], rp.look_line[i]);
  }
  rp.n_look = 0U;
}

static void on_frame(rp_frame_t *f, uint64_t line)
{
  if (rp.clock_decided) {
    route(f, line);
    return;
  }
  rp.look[rp.n_look] = *f;
  rp.look_line[rp.n_look] = line;
  rp.n_look++;
  if ((rp.n_look >= LOOKAHEAD_FRAMES) || ((f->ts_us - rp.look[0].ts_us) >= LOOKAHEAD_US) ||
      ((f->kind == RP_KIND_DATA) && !f->ext && (f->id == CANFDI_RP_MSG_SIM_STEP_FRAME_ID))) {
    decide_clock();
  }
}

/* ------------------------------------------------------------ files */

static void bad_line(const char *line, size_t n, const char *why)
{
  rp.bad_lines++;
  if (rp.bad_lines <= MAX_BAD_EVENTS) {
    fprintf(ev, "{\"ev\":\"bad\",\"file\":%d,\"line\":%" PRIu64 ",\"why\":", rp.file_index, rp.line_no);
    ev_str(why, strlen(why));
    fprintf(ev, ",\"text\":");
    ev_str(line, (n > 80U) ? 80U : n);
    fprintf(ev, "}\n");
  }
}

static void on_line(const char *line, size_t n)
{
  rp_frame_t f;
  const char *why = "";
  int r;
  rp.line_no++;
  if (n > LINE_MAX_LEN) {
    bad_line(line, n, "line longer than 1024 characters");
    return;
  }
  if (memchr(line, '\0', n) != NULL) {
    bad_line(line, n, "NUL byte in the line (binary data?)");
    return;
  }
  r = rp_candump_parse(line, n, &f, &why);
  if (r == RP_LINE_FRAME) {
    rp.frames++;
    on_frame(&f, rp.line_no);
  } else if (r == RP_LINE_BAD) {
    bad_line(line, n, why);
  } else {
    /* blank or comment */
  }
}

static void reset_file_state(int index, const char *name)
{
  unsigned i;
  rp.file_index = index;
  rp.file_name = name;
  rp.line_no = 0U;
  rp.frames = 0U;
  rp.bad_lines = 0U;
  rp.truncated = false;
  rp.chan_fixed = (opt.channel != NULL);
  if (opt.channel != NULL) {
    rp_chan_set(rp.chan, opt.channel);
  }
  rp.n_other = 0U;
  rp.clock_decided = false;
  rp.n_look = 0U;
  rp.have_t0 = false;
  rp.grid_moves = 0U;
  rp.grid_seed_us = 0;
  rp.phase_seen[0] = false;
  rp.phase_seen[1] = false;
  rp.shift_us = 0;
  rp.last_k = -1;
  rp.k0 = -1;
  rp.ecu_step_log_us = 0;
  rp.steps = 0U;
  rp.batch_nonempty = false;
  rp.n_pend = 0U;
  rp.outliers = 0U;
  memset(&rp.dcm_latest, 0, sizeof rp.dcm_latest);
  memset(&rp.thr_latest, 0, sizeof rp.thr_latest);
  rp.dcm_batch0 = rp.dcm_latest;
  rp.thr_batch0 = rp.thr_latest;
  rp.dcm_own = rp.dcm_latest;
  rp.thr_own = rp.thr_latest;
  rp.dcm_sample_set = false;
  rp.thr_sample_set = false;
  rp.cmd_bad_crc = 0U;
  rp.thr_apart_steps = 0U;
  (void)canfdi_e2e_rx_init(&rp.rec_dtc_e2e, (uint16_t)CANFDI_RP_MSG_ECU_DTC_FRAME_ID, 2U);
  rp.rec_e2e_bad = 0U;
  rp.start_decided = false;
  rp.settle_until_log_us = INT64_MIN;
  rp.gap_until_log_us = INT64_MIN;
  rp.settle_why = WHY_NONE;
  for (i = 0U; i < N_ECU_IDS; i++) {
    rp.rq[i].n = 0U;
    rp.rq[i].head = 0U;
    rp.sq[i].n = 0U;
    rp.sq[i].head = 0U;
  }
  rp.matched = 0U;
  rp.mismatched = 0U;
  rp.rec_only = 0U;
  rp.replay_only = 0U;
  rp.rec_ecu_frames = 0U;
  rp.mismatch_reported = false;
  rp.mon_init = false;
  rp.n_mon_buf = 0U;
  rp.gaps = 0U;
  memset(rp.dtc_seen_rep, 0, sizeof rp.dtc_seen_rep);
  rp.n_dtc_ecu = 0U;
  rp.deg_init = false;
  memset(rp.smax, 0, sizeof rp.smax);
  rp.sval[0] = 0U;
  rp.sval[1] = 0U;
  rp.back_n = 0U;
  rp.err_frames = 0U;
  rp.fd_frames = 0U;
  rp.remote_frames = 0U;
  rp.ext_frames = 0U;
  rp.unknown_frames = 0U;
  rp.fd_line = 0U;
  rp.remote_line = 0U;
  rp.ext_line = 0U;
  rp.n_unknown = 0U;
  rp.bus_sec = -1;
  rp.bus_frames = 0U;
  rp.bus_bits = 0U;
  rp.bus_err = 0U;
  memset(&rp.rxc, 0, sizeof rp.rxc);
  rp.frame_init = false;
  rp.simstep_bad = 0U;
}

static void end_file(void)
{
  unsigned i;
  unsigned q;
  if (!rp.clock_decided) {
    decide_clock();
  }
  if (rp.clock == CLOCK_TIMESTAMPS) {
    ts_end();
  }
  if (rp.steps > 0U) {
    decide_start(true); /* a log too short to tell: what was compared decides */
    flush_monitors();
  }
  bus_flush();
  rx_quality(true);
  for (q = 0U; q < N_ECU_IDS; q++) {
    rp.rec_only += rp.rq[q].n;
    rp.replay_only += rp.sq[q].n;
  }
  fprintf(ev, "{\"ev\":\"agree\",\"file\":%d,\"recorded_ecu_frames\":%" PRIu64 ",\"matched\":%" PRIu64
              ",\"mismatched\":%" PRIu64 ",\"recorded_only\":%" PRIu64 ",\"replay_only\":%" PRIu64 "}\n",
          rp.file_index, rp.rec_ecu_frames, rp.matched, rp.mismatched, rp.rec_only, rp.replay_only);
  fprintf(ev, "{\"ev\":\"eof\",\"file\":%d,\"lines\":%" PRIu64 ",\"frames\":%" PRIu64 ",\"bad_lines\":%" PRIu64
              ",\"truncated\":%s,\"steps\":%" PRIu64 ",\"first_t\":",
          rp.file_index, rp.line_no, rp.frames, rp.bad_lines, rp.truncated ? "true" : "false", rp.steps);
  ev_time(rp.first_step_log_us);
  fprintf(ev, ",\"last_t\":");
  ev_time(rp.step_log_us);
  fprintf(ev, ",\"gaps\":%" PRIu64 ",\"back\":%" PRIu64 ",\"error_frames\":%" PRIu64 ",\"fd_frames\":%" PRIu64
              ",\"fd_line\":%" PRIu64 ",\"remote_frames\":%" PRIu64 ",\"remote_line\":%" PRIu64
              ",\"ext_frames\":%" PRIu64 ",\"ext_line\":%" PRIu64 ",\"cmd_bad_crc\":%" PRIu64
              ",\"rec_e2e_bad\":%" PRIu64 ",\"simstep_bad\":%" PRIu64 ",\"outliers\":%" PRIu64
              ",\"grid_moves\":%" PRIu64 ",\"channel\":",
          rp.gaps, rp.back_n, rp.err_frames, rp.fd_frames, rp.fd_line, rp.remote_frames, rp.remote_line,
          rp.ext_frames, rp.ext_line, rp.cmd_bad_crc, rp.rec_e2e_bad, rp.simstep_bad, rp.outliers,
          rp.grid_moves);
  ev_str(rp.chan_fixed ? rp.chan : "", rp.chan_fixed ? strlen(rp.chan) : 0U);
  fprintf(ev, ",\"other_channels\":{");
  for (i = 0U; i < rp.n_other; i++) {
    fprintf(ev, "%s", (i > 0U) ? "," : "");
    ev_str(rp.other_chan[i], strlen(rp.other_chan[i]));
    fprintf(ev, ":[%" PRIu64 ",%" PRIu64 "]", rp.other_chan_n[i], rp.other_chan_line[i]);
  }
  fprintf(ev, "},\"unknown_ids\":{");
  for (i = 0U; i < rp.n_unknown; i++) {
    const bool ext = (rp.unknown_id[i] & 0x80000000UL) != 0U;
    fprintf(ev, "%s\"%s%lX\":%" PRIu64, (i > 0U) ? "," : "", ext ? "x" : "", (unsigned long)(rp.unknown_id[i] & 0x1FFFFFFFUL),
            rp.unknown_n[i]);
  }
  fprintf(ev, "},\"rx\":{");
  for (i = 0U; i < CANFDI_RX_F_COUNT; i++) {
    const canfdi_rx_diag_t *d = &rp.app.rx.diag;
    fprintf(ev, "%s\"%s\":{\"accepted\":%lu,\"length\":%lu,\"crc\":%lu,\"counter\":%lu,\"implausible\":%lu,\"timeouts\":%lu}",
            (i > 0U) ? "," : "", rx_frame_name[i], (unsigned long)d->accepted[i], (unsigned long)d->length_err[i],
            (unsigned long)d->crc_err[i], (unsigned long)d->counter_err[i], (unsigned long)d->implausible[i],
            (unsigned long)d->timeouts[i]);
  }
  fprintf(ev, "}}\n");
}

/* The supervisor's trouble-code memory at the end. */
static void emit_memory(void)
{
  unsigned i;
  for (i = 0U; i < CANFDI_DTC_COUNT; i++) {
    canfdi_dtc_record_t r;
    const uint32_t dtc = rp.app.dtc.table[i].dtc;
    char code[8];
    if (canfdi_dtc_read_record(&rp.app.dtc, dtc, &r) != CANFDI_OK) {
      continue;
    }
    dtc_code_text(dtc, code);
    fprintf(ev, "{\"ev\":\"mem\",\"code\":\"%s\",\"dtc\":%lu,\"status\":%u,\"occ\":%u,\"ff\":", code,
            (unsigned long)dtc, (unsigned)r.status, (unsigned)r.occurrence);
    if (r.ff_valid) {
      fprintf(ev, "{\"time_s\":%.3f,\"speed_rad_s\":", (double)r.ff.time_ms * 1e-3);
      ev_q16(r.ff.omega_q16);
      fprintf(ev, ",\"ia_A\":");
      ev_q16(r.ff.ia_q16);
      fprintf(ev, ",\"ua_V\":");
      ev_q16(r.ff.ua_q16);
      fprintf(ev, ",\"thr_angle_deg\":%.4g,\"supply_V\":", (double)r.ff.thr_angle_q16 / 65536.0 * (180.0 / 3.14159265358979323846));
      ev_q16(r.ff.supply_q16);
      fprintf(ev, ",\"deg_dcm\":\"%s\",\"deg_thr\":\"%s\"}}\n", deg_name(r.ff.deg_dcm), deg_name(r.ff.deg_thr));
    } else {
      fprintf(ev, "null}\n");
    }
  }
}

static int replay_file(const char *path)
{
  static char buf[1U << 20];
  static char carry[LINE_MAX_LEN + 2U];
  size_t ncarry = 0U;
  bool overlong = false;
  gzFile g;
  int n;
  if (strcmp(path, "-") == 0) {
    g = gzdopen(0, "rb");
  } else {
    g = gzopen(path, "rb");
  }
  if (g == NULL) {
    fprintf(stderr, PROG ": cannot open %s: %s\n", path, strerror(errno));
    return -1;
  }
  (void)gzbuffer(g, 1U << 20);
  fprintf(ev, "{\"ev\":\"file\",\"file\":%d,\"name\":", rp.file_index);
  ev_str(path, strlen(path));
  fprintf(ev, "}\n");
  rp.progress_next = PROGRESS_BYTES;
  while ((n = gzread(g, buf, (unsigned)sizeof buf)) > 0) {
    size_t i = 0U;
    const size_t len = (size_t)n;
    while (i < len) {
      const char *nl = memchr(&buf[i], '\n', len - i);
      const size_t end = (nl != NULL) ? (size_t)(nl - buf) : len;
      const size_t seg = end - i;
      if (ncarry > 0U || (nl == NULL) || overlong) {
        /* a line split over two reads */
        if (!overlong && ((ncarry + seg) <= LINE_MAX_LEN)) {
          memcpy(&carry[ncarry], &buf[i], seg);
          ncarry += seg;
        } else if (!overlong) {
          memcpy(&carry[ncarry], &buf[i], LINE_MAX_LEN - ncarry); /* kept for the message */
          ncarry = LINE_MAX_LEN;
          overlong = true;
        } else {
          /* skipping the rest of an overlong line */
        }
        if (nl != NULL) {
          if (overlong) {
            on_line(carry, LINE_MAX_LEN + 1U);
          } else {
            on_line(carry, ncarry);
          }
          ncarry = 0U;
          overlong = false;
        }
      } else {
        on_line(&buf[i], (seg > LINE_MAX_LEN) ? (LINE_MAX_LEN + 1U) : seg);
      }
      i = end + 1U;
    }
    if (opt.progress) {
      const z_off_t off = gzoffset(g);
      if ((off >= 0) && ((uint64_t)off >= rp.progress_next)) {
        fprintf(ev, "{\"ev\":\"p\",\"file\":%d,\"bytes\":%lld}\n", rp.file_index, (long long)off);
        fflush(ev);
        rp.progress_next = (uint64_t)off + PROGRESS_BYTES;
      }
    }
  }
  {
    /* a read error, or (zlib: Z_BUF_ERROR) a compressed stream that ends
     * before its end: what was read is judged, the rest is reported lost */
    int err = Z_OK;
    const char *msg = gzerror(g, &err);
    if ((n < 0) || ((err != Z_OK) && (err != Z_STREAM_END))) {
      rp.truncated = true;
      fprintf(ev, "{\"ev\":\"readerr\",\"file\":%d,\"line\":%" PRIu64 ",\"why\":", rp.file_index, rp.line_no);
      ev_str(msg, strlen(msg));
      fprintf(ev, "}\n");
    }
  }
  if (ncarry > 0U) {
    /* a last line without a newline: kept if it parses (a truncated one
     * does not) */
    on_line(carry, ncarry);
  }
  (void)gzclose(g);
  return 0;
}

/* ------------------------------------------------------------ main */

static void usage(FILE *out)
{
  fprintf(out,
          "Usage: " PROG " [options] LOG [LOG...]\n"
          "\n"
          "The canfdi supervisor (the firmware application) stepped on the time base of\n"
          "recorded candump logs (plain, .gz, or '-' for stdin); writes JSON lines, one\n"
          "event per line (tools/replay/README.md). Several logs are consecutive drives:\n"
          "the trouble-code memory is carried across a power cycle. Normally run by\n"
          "canfdi-replay (tools/canfdi/replay.py), which reads every log format.\n"
          "\n"
          "Options:\n"
          "  -o, --output FILE        events to FILE (default stdout)\n"
          "  -c, --channel NAME       the channel to judge (default: the first channel\n"
          "                           carrying a frame of dbc/canfdi.dbc)\n"
          "      --start MODE         auto | power-up | mid-drive (default auto: power-up\n"
          "                           when the first recorded ECU frames equal the replay's)\n"
          "      --clock MODE         auto | timestamps | simstep (default auto: simstep\n"
          "                           when the log has SimStep frames)\n"
          "      --settle-ms N        models not judged for N ms after a mid-drive start\n"
          "                           or a gap (default %d)\n"
          "      --gap-ms N           no frame for more than N ms is a gap in the log\n"
          "                           (default %d)\n"
          "      --every-ms N         a sample of residuals and estimates every N ms for\n"
          "                           plots (default 0: none)\n"
          "      --no-models WHICH    dcm, thr or dcm,thr: the models of that plant are not\n"
          "                           judged (inputs they cannot use), with --no-models-why\n"
          "      --no-models-why TEXT the reason reported\n"
          "      --rx-rate F=MS       input frame F (DcmSensor, ThrSensor, SetpointDcm,\n"
          "                           SetpointThr) comes every MS ms (mapped inputs): its\n"
          "                           timeout is the calibration's count of missed cycles\n"
          "                           at that period (at most 255 of the DBC's cycles)\n"
          "      --nvm-in FILE        power up with the DTC memory image in FILE (what\n"
          "                           --nvm-out wrote after the previous drive)\n"
          "      --nvm-out FILE       after the last log: power down (the operation cycle\n"
          "                           ends) and write the DTC memory image to FILE\n"
          "      --progress           progress events (bytes read) every 8 MB\n"
          "      --fw-id              print the firmware id and exit\n"
          "  -h, --help               this text\n"
          "\n"
          "Exit status: 0 the logs were read (whatever they held), 2 usage error or a\n"
          "log that cannot be opened.\n",
          REPLAY_DEFAULT_SETTLE_MS, REPLAY_DEFAULT_GAP_MS);
}

static bool parse_ms(const char *v, int64_t *out, int64_t max_ms)
{
  char *end = NULL;
  long long x;
  errno = 0;
  x = strtoll(v, &end, 10);
  if ((errno != 0) || (end == v) || (*end != '\0') || (x < 0) || (x > max_ms)) {
    return false;
  }
  *out = (int64_t)x * 1000;
  return true;
}

static int parse_args(int argc, char **argv, int *first_file)
{
  int i;
  opt.start = START_AUTO;
  opt.clock = CLOCK_AUTO;
  opt.settle_us = (int64_t)REPLAY_DEFAULT_SETTLE_MS * 1000;
  opt.gap_us = (int64_t)REPLAY_DEFAULT_GAP_MS * 1000;
  opt.no_models_why = "the inputs cannot be used by the models";
  for (i = 1; i < argc; i++) {
    const char *a = argv[i];
    const char *v = ((i + 1) < argc) ? argv[i + 1] : NULL;
    if ((a[0] != '-') || (strcmp(a, "-") == 0)) {
      break;
    }
    if (strcmp(a, "--") == 0) {
      i++;
      break;
    }
    if ((strcmp(a, "-h") == 0) || (strcmp(a, "--help") == 0)) {
      usage(stdout);
      exit(0);
    } else if (strcmp(a, "--fw-id") == 0) {
      printf("%s\n", REPLAY_FW_ID);
      exit(0);
    } else if (strcmp(a, "--progress") == 0) {
      opt.progress = true;
      continue;
    }
    if (v == NULL) {
      fprintf(stderr, PROG ": unknown option or missing value '%s'\nTry '" PROG " --help'.\n", a);
      return -1;
    }
    i++;
    if ((strcmp(a, "-o") == 0) || (strcmp(a, "--output") == 0)) {
      ev = fopen(v, "w");
      if (ev == NULL) {
        fprintf(stderr, PROG ": cannot write %s: %s\n", v, strerror(errno));
        return -1;
      }
    } else if ((strcmp(a, "-c") == 0) || (strcmp(a, "--channel") == 0)) {
      if ((strlen(v) == 0U) || (strlen(v) >= RP_CHAN_MAX)) {
        fprintf(stderr, PROG ": --channel: 1..15 characters\n");
        return -1;
      }
      opt.channel = v;
    } else if (strcmp(a, "--start") == 0) {
      opt.start = (strcmp(v, "auto") == 0) ? START_AUTO
                  : (strcmp(v, "power-up") == 0) ? START_POWER_UP
                  : (strcmp(v, "mid-drive") == 0) ? START_MID_DRIVE
                                                  : -1;
      if (opt.start < 0) {
        fprintf(stderr, PROG ": --start: auto, power-up or mid-drive\n");
        return -1;
      }
    } else if (strcmp(a, "--clock") == 0) {
      opt.clock = (strcmp(v, "auto") == 0) ? CLOCK_AUTO
                  : (strcmp(v, "timestamps") == 0) ? CLOCK_TIMESTAMPS
                  : (strcmp(v, "simstep") == 0) ? CLOCK_SIMSTEP
                                                : -1;
      if (opt.clock < 0) {
        fprintf(stderr, PROG ": --clock: auto, timestamps or simstep\n");
        return -1;
      }
    } else if (strcmp(a, "--settle-ms") == 0) {
      if (!parse_ms(v, &opt.settle_us, 3600000)) {
        fprintf(stderr, PROG ": --settle-ms: 0..3600000\n");
        return -1;
      }
    } else if (strcmp(a, "--gap-ms") == 0) {
      if (!parse_ms(v, &opt.gap_us, 3600000) || (opt.gap_us < 2000)) {
        fprintf(stderr, PROG ": --gap-ms: 2..3600000\n");
        return -1;
      }
    } else if (strcmp(a, "--every-ms") == 0) {
      if (!parse_ms(v, &opt.every_us, 3600000)) {
        fprintf(stderr, PROG ": --every-ms: 0..3600000\n");
        return -1;
      }
    } else if (strcmp(a, "--no-models") == 0) {
      opt.no_models[0] = (strstr(v, "dcm") != NULL);
      opt.no_models[1] = (strstr(v, "thr") != NULL);
      if (!opt.no_models[0] && !opt.no_models[1]) {
        fprintf(stderr, PROG ": --no-models: dcm, thr or dcm,thr\n");
        return -1;
      }
    } else if (strcmp(a, "--no-models-why") == 0) {
      opt.no_models_why = v;
    } else if (strcmp(a, "--nvm-in") == 0) {
      opt.nvm_in = v;
    } else if (strcmp(a, "--nvm-out") == 0) {
      opt.nvm_out = v;
    } else if (strcmp(a, "--rx-rate") == 0) {
      const char *eq = strchr(v, '=');
      unsigned f;
      char *end = NULL;
      const long ms = (eq != NULL) ? strtol(eq + 1, &end, 10) : 0;
      bool found = false;
      for (f = 0U; (eq != NULL) && (f < CANFDI_RX_F_COUNT); f++) {
        if ((strlen(rx_frame_name[f]) == (size_t)(eq - v)) && (strncmp(v, rx_frame_name[f], (size_t)(eq - v)) == 0)) {
          found = (ms >= 1) && (ms <= 60000) && (end != NULL) && (*end == '\0');
          opt.rx_rate_ms[f] = (uint32_t)ms;
        }
      }
      if (!found) {
        fprintf(stderr, PROG ": --rx-rate: FRAME=MS, FRAME one of DcmSensor, ThrSensor, "
                        "SetpointDcm, SetpointThr, MS 1..60000\n");
        return -1;
      }
    } else {
      fprintf(stderr, PROG ": unknown option '%s'\nTry '" PROG " --help'.\n", a);
      return -1;
    }
  }
  *first_file = i;
  if (i >= argc) {
    fprintf(stderr, PROG ": no log given\nTry '" PROG " --help'.\n");
    return -1;
  }
  return 0;
}

int main(int argc, char **argv)
{
  static char evbuf[1U << 20];
  int first = 0;
  int i;
  unsigned f;
  ev = NULL;
  if (parse_args(argc, argv, &first) != 0) {
    return EXIT_USAGE;
  }
  if (ev == NULL) {
    ev = stdout;
  }
  (void)setvbuf(ev, evbuf, _IOFBF, sizeof evbuf);
  canfdi_app_default_cal(&rp.cal);
  for (f = 0U; f < CANFDI_RX_F_COUNT; f++) {
    static const uint32_t dbc_ms[CANFDI_RX_F_COUNT] = {
        CANFDI_RP_MSG_DCM_SENSOR_CYCLE_TIME_MS, CANFDI_RP_MSG_THR_SENSOR_CYCLE_TIME_MS,
        CANFDI_RP_MSG_SETPOINT_DCM_CYCLE_TIME_MS, CANFDI_RP_MSG_SETPOINT_THR_CYCLE_TIME_MS};
    if (opt.rx_rate_ms[f] > dbc_ms[f]) {
      /* the same number of missed frames at the mapped period */
      const uint32_t c = ((uint32_t)rp.cal.rx.frame[f].timeout_cycles * opt.rx_rate_ms[f] + dbc_ms[f] - 1U) / dbc_ms[f];
      rp.cal.rx.frame[f].timeout_cycles = (uint8_t)((c > 255U) ? 255U : c);
    }
  }
  fprintf(ev, "{\"ev\":\"hdr\",\"core\":\"" PROG "\",\"fw\":\"%s\",\"sw_version\":", REPLAY_FW_ID);
  ev_ident(rp.cal.uds.ident.sw_version);
  fprintf(ev, ",\"calibration_id\":");
  ev_ident(rp.cal.uds.ident.calibration_id);
  fprintf(ev, ",\"step_us\":%d,\"settle_s\":%.3f,\"gap_s\":%.3f,\"every_s\":%.3f,\"thr_pos\":{", STEP_US,
          (double)opt.settle_us * 1e-6, (double)opt.gap_us * 1e-6, (double)opt.every_us * 1e-6);
  {
    /* the parameter thresholds of the diagnosis, for the plots */
    const canfdi_diagnosis_cfg_t *d = &rp.cal.diagnosis;
    unsigned k;
    fprintf(ev, "\"dcm_pos\":[");
    for (k = 0U; k < CANFDI_SYM_N_PAR; k++) {
      fprintf(ev, "%s", (k > 0U) ? "," : "");
      ev_q16(d->dcm_par_pos_q16[k]);
    }
    fprintf(ev, "],\"dcm_neg\":[");
    for (k = 0U; k < CANFDI_SYM_N_PAR; k++) {
      fprintf(ev, "%s", (k > 0U) ? "," : "");
      ev_q16(d->dcm_par_neg_q16[k]);
    }
    fprintf(ev, "],\"thr_pos\":[");
    for (k = 0U; k < CANFDI_SYM_N_PAR; k++) {
      fprintf(ev, "%s", (k > 0U) ? "," : "");
      ev_q16(d->thr_par_pos_q16[k]);
    }
    fprintf(ev, "],\"thr_neg\":[");
    for (k = 0U; k < CANFDI_SYM_N_PAR; k++) {
      fprintf(ev, "%s", (k > 0U) ? "," : "");
      ev_q16(d->thr_par_neg_q16[k]);
    }
    fprintf(ev, "]},\"rx_timeout_cycles\":[%u,%u,%u,%u]}\n", rp.cal.rx.frame[0].timeout_cycles,
            rp.cal.rx.frame[1].timeout_cycles, rp.cal.rx.frame[2].timeout_cycles, rp.cal.rx.frame[3].timeout_cycles);
  }
  for (i = first; i < argc; i++) {
    int32_t rc;
    if ((i == first) && (opt.nvm_in != NULL)) {
      /* the previous drive's memory, stored by a run with --nvm-out */
      FILE *nf = fopen(opt.nvm_in, "rb");
      size_t n;
      if (nf == NULL) {
        fprintf(stderr, PROG ": cannot read %s: %s\n", opt.nvm_in, strerror(errno));
        return EXIT_USAGE;
      }
      n = fread(rp.image, 1U, sizeof rp.image, nf);
      (void)fclose(nf);
      rp.image_len = (int32_t)n;
      rc = canfdi_app_power_up(&rp.app, &rp.cal, 0U, rp.image, (uint32_t)n);
      fprintf(ev, "{\"ev\":\"nvm_in\",\"file\":0,\"image_bytes\":%d,\"rc\":%d}\n", (int)n, (int)rc);
      if (rc == CANFDI_APP_IMAGE_REJECTED) {
        fprintf(stderr, PROG ": %s: the DTC memory image was rejected\n", opt.nvm_in);
        return EXIT_USAGE;
      }
    } else if (i == first) {
      rc = canfdi_app_init(&rp.app, &rp.cal, 0U);
    } else {
      /* the next drive: power-down with the memory's image, power-up with it */
      rp.image_len = canfdi_app_power_down(&rp.app, rp.image, (uint32_t)sizeof rp.image);
      rc = canfdi_app_power_up(&rp.app, &rp.cal, 0U, rp.image, (rp.image_len > 0) ? (uint32_t)rp.image_len : 0U);
      fprintf(ev, "{\"ev\":\"power_cycle\",\"file\":%d,\"image_bytes\":%d,\"rc\":%d}\n", i - first,
              (int)rp.image_len, (int)rc);
    }
    if ((rc != CANFDI_OK) && (rc != CANFDI_APP_IMAGE_REJECTED)) {
      fprintf(stderr, PROG ": the firmware refused its calibration (%d)\n", (int)rc);
      return EXIT_USAGE;
    }
    reset_file_state(i - first, argv[i]);
    if (replay_file(argv[i]) != 0) {
      fflush(ev);
      return EXIT_USAGE;
    }
    end_file();
  }
  emit_memory();
  {
    const canfdi_app_diag_t *d = canfdi_app_diag(&rp.app);
    fprintf(ev, "{\"ev\":\"end\",\"steps\":%lu,\"frames_rejected\":%lu,\"frames_unknown\":%lu}\n",
            (unsigned long)d->steps, (unsigned long)d->frames_rejected, (unsigned long)d->frames_unknown);
  }
  if (opt.nvm_out != NULL) {
    /* ignition off after the last drive: the image the next run starts from */
    FILE *nf;
    rp.image_len = canfdi_app_power_down(&rp.app, rp.image, (uint32_t)sizeof rp.image);
    nf = (rp.image_len > 0) ? fopen(opt.nvm_out, "wb") : NULL;
    if ((nf == NULL) || (fwrite(rp.image, 1U, (size_t)rp.image_len, nf) != (size_t)rp.image_len) ||
        (fclose(nf) != 0)) {
      fprintf(stderr, PROG ": cannot write the DTC memory image to %s\n", opt.nvm_out);
      fflush(ev);
      return EXIT_USAGE;
    }
  }
  if (fflush(ev) != 0) {
    fprintf(stderr, PROG ": writing the events failed: %s\n", strerror(errno));
    return EXIT_USAGE;
  }
  return 0;
}
