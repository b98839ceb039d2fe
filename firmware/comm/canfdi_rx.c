/*
 * canfdi_rx.c — input supervision; see canfdi_rx.h (the manual).
 */
#include "comm/canfdi_rx.h"

#include "catalogue/canfdi_catalogue.h"
#include "comm/gen/canfdi_msg.h"
#include "comm/gen/canfdi_raw_limits.h"
#include "comm/gen/canfdi_sig_conv.h"
#include "core/canfdi_count.h"
#include "core/canfdi_fixp.h"

/* Monitors 0..9 follow the catalogue's comm faults; a reordered catalogue
 * must fail the build, not silently mislabel a DTC. */
CANFDI_STATIC_ASSERT(CANFDI_FAULT_COM_DCM_TIMEOUT + 9U == CANFDI_FAULT_COM_THR_IMPLAUSIBLE,
                     rx_comm_faults_contiguous);
CANFDI_STATIC_ASSERT(CANFDI_FAULT_COM_THR_COUNTER == CANFDI_FAULT_COM_DCM_TIMEOUT + 3U,
                     rx_comm_faults_order);
CANFDI_STATIC_ASSERT(CANFDI_FAULT_COM_DCM_IMPLAUSIBLE == CANFDI_FAULT_COM_DCM_TIMEOUT + 8U,
                     rx_comm_faults_order2);
CANFDI_STATIC_ASSERT(CANFDI_RX_MON_COUNT <= 32, rx_monitors_fit_mask);
CANFDI_STATIC_ASSERT(CANFDI_RX_F_E2E_COUNT == (unsigned)CANFDI_RX_F_COUNT, rx_every_frame_is_e2e);
CANFDI_STATIC_ASSERT(CANFDI_RX_IN_COUNT <= 32, rx_inputs_fit_mask);
/* Every supervised frame is 8 bytes in the DBC (the length check). */
CANFDI_STATIC_ASSERT((CANFDI_MSG_DCM_SENSOR_LENGTH == 8U) && (CANFDI_MSG_THR_SENSOR_LENGTH == 8U) &&
                         (CANFDI_MSG_SETPOINT_DCM_LENGTH == 8U) &&
                         (CANFDI_MSG_SETPOINT_THR_LENGTH == 8U),
                     rx_frames_are_8_bytes);

/* Per-frame constants: the monitors each check reports to and the inputs
 * the frame carries (contiguous: first .. first + n - 1). */
typedef struct {
  uint32_t cycle_us;
  uint8_t mon_timeout;
  uint8_t mon_length;
  uint8_t mon_crc;
  uint8_t mon_counter;
  uint8_t mon_range;
  uint8_t first_input;
  uint8_t n_inputs;
} frame_info_t;

static const frame_info_t frame_info[CANFDI_RX_F_COUNT] = {
    {CANFDI_MSG_DCM_SENSOR_CYCLE_TIME_MS * 1000U, CANFDI_RX_MON_DCM_TIMEOUT,
     CANFDI_RX_MON_DCM_LENGTH, CANFDI_RX_MON_DCM_CRC, CANFDI_RX_MON_DCM_COUNTER,
     CANFDI_RX_MON_DCM_IMPLAUSIBLE, CANFDI_RX_IN_DCM_UA, 4U},
    {CANFDI_MSG_THR_SENSOR_CYCLE_TIME_MS * 1000U, CANFDI_RX_MON_THR_TIMEOUT,
     CANFDI_RX_MON_THR_LENGTH, CANFDI_RX_MON_THR_CRC, CANFDI_RX_MON_THR_COUNTER,
     CANFDI_RX_MON_THR_IMPLAUSIBLE, CANFDI_RX_IN_THR_TPS1, 4U},
    {CANFDI_MSG_SETPOINT_DCM_CYCLE_TIME_MS * 1000U, CANFDI_RX_MON_SP_DCM_TIMEOUT,
     CANFDI_RX_MON_SP_DCM_LENGTH, CANFDI_RX_MON_SP_DCM_CRC, CANFDI_RX_MON_SP_DCM_COUNTER,
     CANFDI_RX_MON_SP_DCM_RANGE, CANFDI_RX_IN_SP_DCM_SPEED, 2U},
    {CANFDI_MSG_SETPOINT_THR_CYCLE_TIME_MS * 1000U, CANFDI_RX_MON_SP_THR_TIMEOUT,
     CANFDI_RX_MON_SP_THR_LENGTH, CANFDI_RX_MON_SP_THR_CRC, CANFDI_RX_MON_SP_THR_COUNTER,
     CANFDI_RX_MON_SP_THR_RANGE, CANFDI_RX_IN_SP_THR_ANGLE, 1U},
};

/* Per-input constants: frame, plausible raw range, raw -> Q16.16 SI. */
typedef struct {
  int64_t scale_q32;
  int64_t offset_q32;
  int32_t raw_min;
  int32_t raw_max;
  uint8_t frame;
} input_info_t;

static const input_info_t input_info[CANFDI_RX_IN_COUNT] = {
    {CANFDI_SIG_DCM_SENSOR_DCM_UA_SCALE_Q32, CANFDI_SIG_DCM_SENSOR_DCM_UA_OFFSET_Q32,
     (int32_t)CANFDI_RAW_DCM_SENSOR_DCM_UA_MIN, (int32_t)CANFDI_RAW_DCM_SENSOR_DCM_UA_MAX,
     CANFDI_RX_F_DCM_SENSOR},
    {CANFDI_SIG_DCM_SENSOR_DCM_IA_SCALE_Q32, CANFDI_SIG_DCM_SENSOR_DCM_IA_OFFSET_Q32,
     (int32_t)CANFDI_RAW_DCM_SENSOR_DCM_IA_MIN, (int32_t)CANFDI_RAW_DCM_SENSOR_DCM_IA_MAX,
     CANFDI_RX_F_DCM_SENSOR},
    {CANFDI_SIG_DCM_SENSOR_DCM_OMEGA_SCALE_Q32, CANFDI_SIG_DCM_SENSOR_DCM_OMEGA_OFFSET_Q32,
     (int32_t)CANFDI_RAW_DCM_SENSOR_DCM_OMEGA_MIN, (int32_t)CANFDI_RAW_DCM_SENSOR_DCM_OMEGA_MAX,
     CANFDI_RX_F_DCM_SENSOR},
    {CANFDI_SIG_DCM_SENSOR_DCM_USUPPLY_SCALE_Q32, CANFDI_SIG_DCM_SENSOR_DCM_USUPPLY_OFFSET_Q32,
     (int32_t)CANFDI_RAW_DCM_SENSOR_DCM_USUPPLY_MIN, (int32_t)CANFDI_RAW_DCM_SENSOR_DCM_USUPPLY_MAX,
     CANFDI_RX_F_DCM_SENSOR},
    {CANFDI_SIG_THR_SENSOR_THR_TPS1_SCALE_Q32, CANFDI_SIG_THR_SENSOR_THR_TPS1_OFFSET_Q32,
     (int32_t)CANFDI_RAW_THR_SENSOR_THR_TPS1_MIN, (int32_t)CANFDI_RAW_THR_SENSOR_THR_TPS1_MAX,
     CANFDI_RX_F_THR_SENSOR},
    {CANFDI_SIG_THR_SENSOR_THR_TPS2_SCALE_Q32, CANFDI_SIG_THR_SENSOR_THR_TPS2_OFFSET_Q32,
     (int32_t)CANFDI_RAW_THR_SENSOR_THR_TPS2_MIN, (int32_t)CANFDI_RAW_THR_SENSOR_THR_TPS2_MAX,
     CANFDI_RX_F_THR_SENSOR},
    {CANFDI_SIG_THR_SENSOR_THR_IMOT_SCALE_Q32, CANFDI_SIG_THR_SENSOR_THR_IMOT_OFFSET_Q32,
     (int32_t)CANFDI_RAW_THR_SENSOR_THR_IMOT_MIN, (int32_t)CANFDI_RAW_THR_SENSOR_THR_IMOT_MAX,
     CANFDI_RX_F_THR_SENSOR},
    {CANFDI_SIG_THR_SENSOR_THR_USUPPLY_SCALE_Q32, CANFDI_SIG_THR_SENSOR_THR_USUPPLY_OFFSET_Q32,
     (int32_t)CANFDI_RAW_THR_SENSOR_THR_USUPPLY_MIN, (int32_t)CANFDI_RAW_THR_SENSOR_THR_USUPPLY_MAX,
     CANFDI_RX_F_THR_SENSOR},
    {CANFDI_SIG_SETPOINT_DCM_SP_DCM_SPEED_SCALE_Q32, CANFDI_SIG_SETPOINT_DCM_SP_DCM_SPEED_OFFSET_Q32,
     CANFDI_RAW_SETPOINT_DCM_SP_DCM_SPEED_MIN, CANFDI_RAW_SETPOINT_DCM_SP_DCM_SPEED_MAX,
     CANFDI_RX_F_SP_DCM},
    {CANFDI_SIG_SETPOINT_DCM_SP_DCM_LOAD_SCALE_Q32, CANFDI_SIG_SETPOINT_DCM_SP_DCM_LOAD_OFFSET_Q32,
     CANFDI_RAW_SETPOINT_DCM_SP_DCM_LOAD_MIN, CANFDI_RAW_SETPOINT_DCM_SP_DCM_LOAD_MAX,
     CANFDI_RX_F_SP_DCM},
    /* The DBC sends degrees; the firmware works in radians. */
    {CANFDI_SIG_SETPOINT_THR_SP_THR_ANGLE_RAD_SCALE_Q32,
     CANFDI_SIG_SETPOINT_THR_SP_THR_ANGLE_RAD_OFFSET_Q32,
     (int32_t)CANFDI_RAW_SETPOINT_THR_SP_THR_ANGLE_MIN,
     (int32_t)CANFDI_RAW_SETPOINT_THR_SP_THR_ANGLE_MAX, CANFDI_RX_F_SP_THR},
};

/* A failure in the same step dominates any pass of the same monitor. */
static void report(canfdi_rx_t *rx, unsigned mon, bool failed)
{
  const uint32_t bit = UINT32_C(1) << mon;
  if (failed) {
    rx->acc.prefailed |= bit;
    rx->acc.prepassed &= ~bit;
  } else if ((rx->acc.prefailed & bit) == 0U) {
    rx->acc.prepassed |= bit;
  }
}

/* Age of a time stamp at now; a stamp later than now (jitter) is age 0. */
static uint32_t age_us(uint32_t now_us, uint32_t then_us)
{
  const uint32_t d = now_us - then_us; /* modulo 2^32 by intent */
  return (d > (uint32_t)INT32_MAX) ? 0U : d;
}

static uint32_t window_us(const canfdi_rx_t *rx, unsigned f)
{
  const uint32_t w = (uint32_t)rx->cfg.frame[f].timeout_cycles * frame_info[f].cycle_us;
  return (!rx->frame[f].received && (rx->cfg.first_timeout_us > w)) ? rx->cfg.first_timeout_us : w;
}

static void signal_error(canfdi_rx_signal_state_t *s)
{
  s->in_error = true;
  s->good_run = 0U;
}

static void frame_error(canfdi_rx_t *rx, unsigned f)
{
  const unsigned first = frame_info[f].first_input;
  for (unsigned i = first; i < (first + frame_info[f].n_inputs); i++) {
    signal_error(&rx->sig[i]);
  }
}

static void signal_accept(canfdi_rx_t *rx, unsigned i, int32_t value_q16, uint32_t now_us)
{
  canfdi_rx_signal_state_t *s = &rx->sig[i];
  s->last_q16 = value_q16;
  s->last_ok_us = now_us;
  s->has_value = true;
  s->stale = false;
  s->fresh = true;
  s->samples = (s->samples < UINT8_MAX) ? (uint8_t)(s->samples + 1U) : s->samples;
  if (s->in_error) {
    if (s->good_run < UINT8_MAX) {
      s->good_run++;
    }
    if (s->good_run >= rx->cfg.frame[input_info[i].frame].recover_frames) {
      s->in_error = false;
    }
  }
}

/* Range check and conversion of one raw signal; true if plausible. */
static bool take_signal(canfdi_rx_t *rx, unsigned i, int32_t raw, uint32_t now_us)
{
  const input_info_t *ii = &input_info[i];
  const bool ok = (raw >= ii->raw_min) && (raw <= ii->raw_max);
  if (ok) {
    signal_accept(rx, i, canfdi_rx_raw_to_q16(raw, ii->scale_q32, ii->offset_q32), now_us);
  } else {
    signal_error(&rx->sig[i]);
  }
  return ok;
}

static void reception(canfdi_rx_t *rx, unsigned f, uint32_t now_us)
{
  canfdi_rx_frame_state_t *fs = &rx->frame[f];
  fs->last_rx_us = now_us;
  fs->received = true;
  fs->timed_out = false;
}

/* Restart the E2E sequence check, keeping its monotone counters. */
static void e2e_resync(canfdi_rx_t *rx, unsigned f)
{
  canfdi_e2e_rx_t *e = &rx->e2e[f];
  const canfdi_e2e_diag_t keep = e->diag;
  const int st = canfdi_e2e_rx_init(e, e->data_id, e->max_delta);
  CANFDI_ASSERT(st == CANFDI_OK);
  (void)st;
  e->diag = keep;
}

/* Steps 1..3 of the header: length, CRC, counter. Returns ACCEPTED when the
 * payload may be used. */
static int judge_e2e(canfdi_rx_t *rx, unsigned f, const uint8_t *data, uint8_t dlc)
{
  const frame_info_t *fi = &frame_info[f];
  canfdi_rx_frame_state_t *fs = &rx->frame[f];
  int out = CANFDI_RX_ACCEPTED;
  if (dlc != CANFDI_E2E_FRAME_LEN) {
    report(rx, fi->mon_length, true);
    canfdi_count_inc(&rx->diag.length_err[f]);
    fs->resync = true;
    out = CANFDI_RX_BAD_LENGTH;
  } else {
    int st;
    report(rx, fi->mon_length, false);
    if (fs->resync) {
      e2e_resync(rx, f);
      fs->resync = false;
    }
    st = canfdi_e2e_check(&rx->e2e[f], data, dlc);
    if (st == (int)CANFDI_E2E_WRONG_CRC) {
      report(rx, fi->mon_crc, true);
      canfdi_count_inc(&rx->diag.crc_err[f]);
      fs->resync = true;
      out = CANFDI_RX_BAD_CRC;
    } else {
      report(rx, fi->mon_crc, false);
      if (canfdi_e2e_status_is_usable(st)) {
        report(rx, fi->mon_counter, false);
      } else {
        /* REPEATED or WRONG_SEQUENCE (length and data were checked above) */
        report(rx, fi->mon_counter, true);
        canfdi_count_inc(&rx->diag.counter_err[f]);
        out = CANFDI_RX_BAD_COUNTER;
      }
    }
  }
  if (out != CANFDI_RX_ACCEPTED) {
    frame_error(rx, f);
  }
  return out;
}

static int dcm_sensor(canfdi_rx_t *rx, const uint8_t *data, uint8_t dlc, uint32_t now_us)
{
  const unsigned f = CANFDI_RX_F_DCM_SENSOR;
  int out = judge_e2e(rx, f, data, dlc);
  if (out == CANFDI_RX_ACCEPTED) {
    struct canfdi_msg_dcm_sensor_t m;
    bool ok;
    const int st = canfdi_msg_dcm_sensor_unpack(&m, data, dlc);
    CANFDI_ASSERT(st == 0); /* dlc == 8 was checked */
    (void)st;
    ok = take_signal(rx, CANFDI_RX_IN_DCM_UA, (int32_t)m.dcm_ua, now_us);
    ok = take_signal(rx, CANFDI_RX_IN_DCM_IA, (int32_t)m.dcm_ia, now_us) && ok;
    ok = take_signal(rx, CANFDI_RX_IN_DCM_OMEGA, (int32_t)m.dcm_omega, now_us) && ok;
    ok = take_signal(rx, CANFDI_RX_IN_DCM_USUPPLY, (int32_t)m.dcm_usupply, now_us) && ok;
    report(rx, frame_info[f].mon_range, !ok);
    out = ok ? CANFDI_RX_ACCEPTED : CANFDI_RX_IMPLAUSIBLE;
  }
  return out;
}

static int thr_sensor(canfdi_rx_t *rx, const uint8_t *data, uint8_t dlc, uint32_t now_us)
{
  const unsigned f = CANFDI_RX_F_THR_SENSOR;
  int out = judge_e2e(rx, f, data, dlc);
  if (out == CANFDI_RX_ACCEPTED) {
    struct canfdi_msg_thr_sensor_t m;
    bool ok;
    const int st = canfdi_msg_thr_sensor_unpack(&m, data, dlc);
    CANFDI_ASSERT(st == 0);
    (void)st;
    ok = take_signal(rx, CANFDI_RX_IN_THR_TPS1, (int32_t)m.thr_tps1, now_us);
    ok = take_signal(rx, CANFDI_RX_IN_THR_TPS2, (int32_t)m.thr_tps2, now_us) && ok;
    ok = take_signal(rx, CANFDI_RX_IN_THR_IMOT, (int32_t)m.thr_imot, now_us) && ok;
    ok = take_signal(rx, CANFDI_RX_IN_THR_USUPPLY, (int32_t)m.thr_usupply, now_us) && ok;
    report(rx, frame_info[f].mon_range, !ok);
    out = ok ? CANFDI_RX_ACCEPTED : CANFDI_RX_IMPLAUSIBLE;
  }
  return out;
}

static int setpoint(canfdi_rx_t *rx, unsigned f, const uint8_t *data, uint8_t dlc,
                    uint32_t now_us)
{
  const frame_info_t *fi = &frame_info[f];
  int out = judge_e2e(rx, f, data, dlc);
  if (out == CANFDI_RX_ACCEPTED) {
    int st;
    bool ok;
    if (f == (unsigned)CANFDI_RX_F_SP_DCM) {
      struct canfdi_msg_setpoint_dcm_t m;
      st = canfdi_msg_setpoint_dcm_unpack(&m, data, dlc);
      ok = take_signal(rx, CANFDI_RX_IN_SP_DCM_SPEED, (int32_t)m.sp_dcm_speed, now_us);
      ok = take_signal(rx, CANFDI_RX_IN_SP_DCM_LOAD, (int32_t)m.sp_dcm_load, now_us) && ok;
    } else {
      struct canfdi_msg_setpoint_thr_t m;
      st = canfdi_msg_setpoint_thr_unpack(&m, data, dlc);
      ok = take_signal(rx, fi->first_input, (int32_t)m.sp_thr_angle, now_us);
    }
    CANFDI_ASSERT(st == 0);
    (void)st;
    report(rx, fi->mon_range, !ok);
    out = ok ? CANFDI_RX_ACCEPTED : CANFDI_RX_IMPLAUSIBLE;
  }
  return out;
}

static bool usable(const canfdi_rx_t *rx)
{
  return (rx != NULL) && rx->initialised;
}

void canfdi_rx_default_cfg(canfdi_rx_cfg_t *cfg)
{
  if (cfg != NULL) {
    for (unsigned f = 0U; f < (unsigned)CANFDI_RX_F_COUNT; f++) {
      const bool sensor = (f <= (unsigned)CANFDI_RX_F_THR_SENSOR);
      cfg->frame[f].timeout_cycles = sensor ? 4U : 5U;
      cfg->frame[f].recover_frames = sensor ? 3U : 1U;
      cfg->frame[f].max_delta = 2U;
    }
    for (unsigned i = 0U; i < (unsigned)CANFDI_RX_IN_COUNT; i++) {
      cfg->default_q16[i] = 0;
    }
    cfg->first_timeout_us = 0U;
  }
}

int canfdi_rx_init(canfdi_rx_t *rx, const canfdi_rx_cfg_t *cfg, uint32_t now_us)
{
  int out = -CANFDI_EINVAL;
  if ((rx != NULL) && (cfg != NULL)) {
    bool ok = true;
    rx->initialised = false;
    for (unsigned f = 0U; f < (unsigned)CANFDI_RX_F_COUNT; f++) {
      const canfdi_rx_frame_cfg_t *fc = &cfg->frame[f];
      ok = ok && (fc->timeout_cycles >= 1U) && (fc->recover_frames >= 1U) &&
           (fc->max_delta >= 1U) && (fc->max_delta < CANFDI_E2E_COUNTER_MOD);
    }
    if (ok) {
      static const uint16_t e2e_id[CANFDI_RX_F_E2E_COUNT] = {
          CANFDI_MSG_DCM_SENSOR_FRAME_ID, CANFDI_MSG_THR_SENSOR_FRAME_ID,
          CANFDI_MSG_SETPOINT_DCM_FRAME_ID, CANFDI_MSG_SETPOINT_THR_FRAME_ID};
      rx->cfg = *cfg;
      for (unsigned f = 0U; f < CANFDI_RX_F_E2E_COUNT; f++) {
        const int st = canfdi_e2e_rx_init(&rx->e2e[f], e2e_id[f], cfg->frame[f].max_delta);
        CANFDI_ASSERT(st == CANFDI_OK); /* max_delta checked above */
        (void)st;
      }
      for (unsigned f = 0U; f < (unsigned)CANFDI_RX_F_COUNT; f++) {
        rx->frame[f].last_rx_us = now_us;
        rx->frame[f].received = false;
        rx->frame[f].timed_out = false;
        rx->frame[f].resync = false;
      }
      for (unsigned i = 0U; i < (unsigned)CANFDI_RX_IN_COUNT; i++) {
        canfdi_rx_signal_state_t *s = &rx->sig[i];
        s->last_q16 = cfg->default_q16[i];
        s->last_ok_us = now_us;
        s->good_run = 0U;
        s->has_value = false;
        s->in_error = false;
        s->stale = false;
        s->fresh = false;
        s->samples = 0U;
        rx->estimate_q16[i] = 0;
        rx->in[i].value_q16 = cfg->default_q16[i];
        rx->in[i].quality = (uint8_t)CANFDI_RX_INVALID;
        rx->in[i].fresh = false;
        rx->in[i].samples = 0U;
      }
      rx->estimate_mask = 0U;
      rx->acc.prefailed = 0U;
      rx->acc.prepassed = 0U;
      rx->report = rx->acc;
      {
        static const canfdi_rx_diag_t zero;
        rx->diag = zero;
      }
      rx->initialised = true;
      out = CANFDI_OK;
    }
  }
  return out;
}

/* Index of a supervised frame, CANFDI_RX_F_COUNT for any other id. */
static unsigned frame_of(uint32_t id)
{
  unsigned f = CANFDI_RX_F_COUNT;
  switch (id) {
  case CANFDI_MSG_DCM_SENSOR_FRAME_ID:
    f = CANFDI_RX_F_DCM_SENSOR;
    break;
  case CANFDI_MSG_THR_SENSOR_FRAME_ID:
    f = CANFDI_RX_F_THR_SENSOR;
    break;
  case CANFDI_MSG_SETPOINT_DCM_FRAME_ID:
    f = CANFDI_RX_F_SP_DCM;
    break;
  case CANFDI_MSG_SETPOINT_THR_FRAME_ID:
    f = CANFDI_RX_F_SP_THR;
    break;
  default:
    break;
  }
  return f;
}

int canfdi_rx_frame(canfdi_rx_t *rx, uint32_t id, const uint8_t *data, uint8_t dlc,
                    uint32_t now_us)
{
  int out = -CANFDI_EINVAL;
  if (usable(rx)) {
    if ((data == NULL) && (dlc > 0U)) {
      canfdi_count_inc(&rx->diag.bad_args);
    } else {
      const unsigned f = frame_of(id);
      canfdi_count_inc(&rx->diag.frames);
      if (f >= (unsigned)CANFDI_RX_F_COUNT) {
        canfdi_count_inc(&rx->diag.unknown_id);
        out = CANFDI_RX_UNKNOWN_ID;
      } else {
        reception(rx, f, now_us);
        if (f == (unsigned)CANFDI_RX_F_DCM_SENSOR) {
          out = dcm_sensor(rx, data, dlc, now_us);
        } else if (f == (unsigned)CANFDI_RX_F_THR_SENSOR) {
          out = thr_sensor(rx, data, dlc, now_us);
        } else {
          out = setpoint(rx, f, data, dlc, now_us);
        }
        if (out == CANFDI_RX_ACCEPTED) {
          canfdi_count_inc(&rx->diag.accepted[f]);
        } else if (out == CANFDI_RX_IMPLAUSIBLE) {
          canfdi_count_inc(&rx->diag.implausible[f]);
        } else {
          /* rejected: counted where judged */
        }
      }
    }
  }
  return out;
}

int canfdi_rx_set_estimate(canfdi_rx_t *rx, unsigned input, int32_t value_q16)
{
  int out = -CANFDI_EINVAL;
  if (usable(rx) && (input < (unsigned)CANFDI_RX_IN_COUNT)) {
    rx->estimate_q16[input] = value_q16;
    rx->estimate_mask |= UINT32_C(1) << input;
    out = CANFDI_OK;
  }
  return out;
}

/* Quality and value of input i at now (see the header). */
static void decide(canfdi_rx_t *rx, unsigned i, uint32_t now_us)
{
  canfdi_rx_signal_state_t *s = &rx->sig[i];
  canfdi_rx_input_t *in = &rx->in[i];
  const unsigned f = input_info[i].frame;
  if (s->has_value && !s->stale && (age_us(now_us, s->last_ok_us) >= window_us(rx, f))) {
    s->stale = true;
  }
  in->fresh = false;
  in->samples = 0U;
  if (s->has_value && !s->in_error && !s->stale && !rx->frame[f].timed_out) {
    in->quality = (uint8_t)CANFDI_RX_VALID;
    in->value_q16 = s->last_q16;
    in->fresh = s->fresh;
    in->samples = s->samples;
  } else if ((rx->estimate_mask & (UINT32_C(1) << i)) != 0U) {
    in->quality = (uint8_t)CANFDI_RX_SUBSTITUTED;
    in->value_q16 = rx->estimate_q16[i];
    canfdi_count_inc(&rx->diag.estimates_used);
  } else if (s->has_value && !s->stale) {
    in->quality = (uint8_t)CANFDI_RX_SUBSTITUTED;
    in->value_q16 = s->last_q16;
  } else {
    in->quality = (uint8_t)CANFDI_RX_INVALID;
    in->value_q16 = s->last_q16; /* the default until the first sample */
  }
  if (in->quality == (uint8_t)CANFDI_RX_SUBSTITUTED) {
    canfdi_count_inc(&rx->diag.substituted[i]);
  } else if (in->quality == (uint8_t)CANFDI_RX_INVALID) {
    canfdi_count_inc(&rx->diag.invalid[i]);
  } else {
    /* VALID */
  }
  s->fresh = false;
  s->samples = 0U;
}

int canfdi_rx_step(canfdi_rx_t *rx, uint32_t now_us)
{
  int out = -CANFDI_EINVAL;
  if (usable(rx)) {
    for (unsigned f = 0U; f < (unsigned)CANFDI_RX_F_COUNT; f++) {
      canfdi_rx_frame_state_t *fs = &rx->frame[f];
      if (!fs->timed_out && (age_us(now_us, fs->last_rx_us) >= window_us(rx, f))) {
        fs->timed_out = true;
        canfdi_count_inc(&rx->diag.timeouts[f]);
        frame_error(rx, f);
        fs->resync = true; /* every supervised frame is E2E protected */
      }
      if (fs->timed_out || fs->received) {
        report(rx, frame_info[f].mon_timeout, fs->timed_out);
      }
    }
    for (unsigned i = 0U; i < (unsigned)CANFDI_RX_IN_COUNT; i++) {
      decide(rx, i, now_us);
    }
    rx->estimate_mask = 0U;
    rx->report = rx->acc;
    rx->acc.prefailed = 0U;
    rx->acc.prepassed = 0U;
    canfdi_count_inc(&rx->diag.steps);
    out = CANFDI_OK;
  }
  return out;
}

int canfdi_rx_monitor_result(const canfdi_rx_t *rx, unsigned mon)
{
  int out = -CANFDI_EINVAL;
  if ((rx != NULL) && (mon < (unsigned)CANFDI_RX_MON_COUNT)) {
    const uint32_t bit = UINT32_C(1) << mon;
    if ((rx->report.prefailed & bit) != 0U) {
      out = (int)CANFDI_DEB_REPORT_PREFAILED;
    } else if ((rx->report.prepassed & bit) != 0U) {
      out = (int)CANFDI_DEB_REPORT_PREPASSED;
    } else {
      out = -CANFDI_ENODATA;
    }
  }
  return out;
}

uint8_t canfdi_rx_monitor_fault_id(unsigned mon)
{
  uint8_t out = (uint8_t)CANFDI_FAULT_NONE;
  if (mon <= (unsigned)CANFDI_RX_MON_THR_IMPLAUSIBLE) {
    out = (uint8_t)(CANFDI_FAULT_COM_DCM_TIMEOUT + mon);
  }
  return out;
}

uint32_t canfdi_rx_monitor_dtc(unsigned mon)
{
  uint32_t out;
  if ((mon == (unsigned)CANFDI_RX_MON_SP_DCM_TIMEOUT) || (mon == (unsigned)CANFDI_RX_MON_SP_THR_TIMEOUT)) {
    out = CANFDI_DTC_U1A50; /* lost communication with the vehicle controller */
  } else if ((mon > (unsigned)CANFDI_RX_MON_THR_IMPLAUSIBLE) && (mon < (unsigned)CANFDI_RX_MON_COUNT)) {
    out = CANFDI_DTC_U1A51; /* invalid data from it */
  } else {
    out = canfdi_catalogue_fault[canfdi_rx_monitor_fault_id(mon)].dtc[0];
  }
  return out;
}

int32_t canfdi_rx_raw_to_q16(int32_t raw, int64_t scale_q32, int64_t offset_q32)
{
  const int64_t s_max = INT64_C(1) << 32;
  const int64_t s_min = -(s_max - 1);
  const int64_t s = (scale_q32 > s_max) ? s_max : ((scale_q32 < s_min) ? s_min : scale_q32);
  const int64_t acc = canfdi_add_s64_sat((int64_t)raw * s, offset_q32);
  return canfdi_sat_s64_to_s32(canfdi_asr64_rnd(acc, 16U));
}
