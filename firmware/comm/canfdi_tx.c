/*
 * canfdi_tx.c — transmit side; see canfdi_tx.h (the manual).
 */
#include "comm/canfdi_tx.h"

#include "catalogue/canfdi_catalogue.h"
#include "comm/gen/canfdi_msg.h"
#include "comm/gen/canfdi_raw_limits.h"
#include "comm/gen/canfdi_sig_conv.h"
#include "core/canfdi_count.h"
#include "core/canfdi_fixp.h"

/* Period of a DBC cycle time in steps; must be a whole number of steps. */
#define PERIOD_STEPS(ms) (((ms) * 1000U) / CANFDI_CFG_STEP_US)

CANFDI_STATIC_ASSERT(((CANFDI_MSG_ECU_STATUS_CYCLE_TIME_MS * 1000U) % CANFDI_CFG_STEP_US) == 0U,
                     tx_slow_period_whole_steps);
CANFDI_STATIC_ASSERT(((CANFDI_MSG_ECU_RESIDUAL_DCM_CYCLE_TIME_MS * 1000U) % CANFDI_CFG_STEP_US) ==
                         0U,
                     tx_mid_period_whole_steps);
CANFDI_STATIC_ASSERT(((CANFDI_MSG_DCM_ACTUATOR_CYCLE_TIME_MS * 1000U) % CANFDI_CFG_STEP_US) == 0U &&
                         PERIOD_STEPS(CANFDI_MSG_DCM_ACTUATOR_CYCLE_TIME_MS) >= 1U,
                     tx_fast_period_whole_steps);
CANFDI_STATIC_ASSERT(PERIOD_STEPS(CANFDI_MSG_ECU_PARAM_THR_CYCLE_TIME_MS) <= 255U,
                     tx_period_fits_countdown);
CANFDI_STATIC_ASSERT(CANFDI_CFG_TX_DTC_QUEUE >= 1U && CANFDI_CFG_TX_DTC_QUEUE <= 255U,
                     tx_queue_size);
/* EcuDtc carries a DTC's index among the stored ones in 5 bits (the E2E
 * header took the room): a larger catalogue needs a new frame layout. */
CANFDI_STATIC_ASSERT(CANFDI_DTC_COUNT <= (CANFDI_RAW_ECU_DTC_DTC_INDEX_MAX + 1U), tx_dtc_index_fits_ecu_dtc);

typedef struct {
  uint8_t period; /* steps */
  uint8_t phase;  /* first due step after init (the actuators: 0) */
} slot_t;

/* Phases: the 10 ms frames at 2 and 7, the 100 ms frames at 3, 13, 23, 43,
 * 63, 83 (all = 3 mod 10): no two slow frames share a step, which bounds a step
 * to two actuators + one slow frame + one DTC event. */
static const slot_t slots[CANFDI_TX_F_COUNT] = {
    {(uint8_t)PERIOD_STEPS(CANFDI_MSG_DCM_ACTUATOR_CYCLE_TIME_MS), 0U},
    {(uint8_t)PERIOD_STEPS(CANFDI_MSG_THR_ACTUATOR_CYCLE_TIME_MS), 0U},
    {(uint8_t)PERIOD_STEPS(CANFDI_MSG_ECU_RESIDUAL_DCM_CYCLE_TIME_MS), 2U},
    {(uint8_t)PERIOD_STEPS(CANFDI_MSG_ECU_RESIDUAL_THR_CYCLE_TIME_MS), 7U},
    {(uint8_t)PERIOD_STEPS(CANFDI_MSG_ECU_STATUS_CYCLE_TIME_MS), 3U},
    {(uint8_t)PERIOD_STEPS(CANFDI_MSG_ECU_DIAGNOSIS_CYCLE_TIME_MS), 23U},
    {(uint8_t)PERIOD_STEPS(CANFDI_MSG_ECU_SELF_DIAG_CYCLE_TIME_MS), 13U},
    {(uint8_t)PERIOD_STEPS(CANFDI_MSG_ECU_DTC_CYCLE_TIME_MS), 43U},
    {(uint8_t)PERIOD_STEPS(CANFDI_MSG_ECU_PARAM_DCM_CYCLE_TIME_MS), 63U},
    {(uint8_t)PERIOD_STEPS(CANFDI_MSG_ECU_PARAM_THR_CYCLE_TIME_MS), 83U},
};

/* Q16.16 -> raw of one signal (see canfdi_sig_conv.h). */
typedef struct {
  int64_t inv_scale_q32;
  int64_t offset_raw_q32;
  int32_t min_q16;
  int32_t max_q16;
  int32_t raw_min;
  int32_t raw_max;
} conv_t;

#define CONV(sig, msg_sig_raw)                                                                 \
  {                                                                                            \
    CANFDI_SIG_##sig##_INV_SCALE_Q32, CANFDI_SIG_##sig##_OFFSET_RAW_Q32,                       \
        CANFDI_SIG_##sig##_MIN_Q16, CANFDI_SIG_##sig##_MAX_Q16,                                \
        (int32_t)CANFDI_RAW_##msg_sig_raw##_MIN, (int32_t)CANFDI_RAW_##msg_sig_raw##_MAX       \
  }

enum {
  C_DCM_UA_CMD,
  C_THR_UCMD,
  C_RES_DCM_R1,
  C_RES_DCM_R2,
  C_RES_DCM_R3,
  C_RES_DCM_R4,
  C_RES_THR_CORR,
  C_RES_THR_TPS1,
  C_RES_THR_TPS2,
  C_RES_THR_CURRENT,
  C_PRM_DCM_RA,
  C_PRM_DCM_PSI,
  C_PRM_DCM_J,
  C_PRM_DCM_MF1,
  C_PRM_DCM_MF0,
  C_PRM_THR_R,
  C_PRM_THR_SPRING_K,
  C_PRM_THR_SPRING_PRE,
  C_PRM_THR_FRIC_C,
  C_PRM_THR_FRIC_V,
  C_COUNT
};

static const conv_t conv[C_COUNT] = {
    CONV(DCM_ACTUATOR_DCM_UA_CMD, DCM_ACTUATOR_DCM_UA_CMD),
    CONV(THR_ACTUATOR_THR_UCMD, THR_ACTUATOR_THR_UCMD),
    CONV(ECU_RESIDUAL_DCM_RES_DCM_R1, ECU_RESIDUAL_DCM_RES_DCM_R1),
    CONV(ECU_RESIDUAL_DCM_RES_DCM_R2, ECU_RESIDUAL_DCM_RES_DCM_R2),
    CONV(ECU_RESIDUAL_DCM_RES_DCM_R3, ECU_RESIDUAL_DCM_RES_DCM_R3),
    CONV(ECU_RESIDUAL_DCM_RES_DCM_R4, ECU_RESIDUAL_DCM_RES_DCM_R4),
    CONV(ECU_RESIDUAL_THR_RES_THR_CORR, ECU_RESIDUAL_THR_RES_THR_CORR),
    CONV(ECU_RESIDUAL_THR_RES_THR_TPS1, ECU_RESIDUAL_THR_RES_THR_TPS1),
    CONV(ECU_RESIDUAL_THR_RES_THR_TPS2, ECU_RESIDUAL_THR_RES_THR_TPS2),
    CONV(ECU_RESIDUAL_THR_RES_THR_CURRENT, ECU_RESIDUAL_THR_RES_THR_CURRENT),
    CONV(ECU_PARAM_DCM_PRM_DCM_RA, ECU_PARAM_DCM_PRM_DCM_RA),
    CONV(ECU_PARAM_DCM_PRM_DCM_PSI, ECU_PARAM_DCM_PRM_DCM_PSI),
    CONV(ECU_PARAM_DCM_PRM_DCM_J, ECU_PARAM_DCM_PRM_DCM_J),
    CONV(ECU_PARAM_DCM_PRM_DCM_MF1, ECU_PARAM_DCM_PRM_DCM_MF1),
    CONV(ECU_PARAM_DCM_PRM_DCM_MF0, ECU_PARAM_DCM_PRM_DCM_MF0),
    CONV(ECU_PARAM_THR_PRM_THR_R, ECU_PARAM_THR_PRM_THR_R),
    CONV(ECU_PARAM_THR_PRM_THR_SPRING_K, ECU_PARAM_THR_PRM_THR_SPRING_K),
    CONV(ECU_PARAM_THR_PRM_THR_SPRING_PRE, ECU_PARAM_THR_PRM_THR_SPRING_PRE),
    CONV(ECU_PARAM_THR_PRM_THR_FRIC_C, ECU_PARAM_THR_PRM_THR_FRIC_C),
    CONV(ECU_PARAM_THR_PRM_THR_FRIC_V, ECU_PARAM_THR_PRM_THR_FRIC_V),
};

/*
 * Scaling and overflow: see the header. Inside [min_q16, max_q16] the
 * generator bounds |v * inv_scale| + |offset_raw| below 2^62, so the int64_t
 * expression cannot overflow (asserted); rounding half up by
 * canfdi_asr64_rnd, then clamped to the raw limits.
 */
static int32_t to_raw(canfdi_tx_t *tx, unsigned c, int32_t v_q16)
{
  const conv_t *k = &conv[c];
  int32_t raw;
  if (v_q16 < k->min_q16) {
    raw = k->raw_min;
    canfdi_count_inc(&tx->diag.saturations);
  } else if (v_q16 > k->max_q16) {
    raw = k->raw_max;
    canfdi_count_inc(&tx->diag.saturations);
  } else {
    const int64_t acc = ((int64_t)v_q16 * k->inv_scale_q32) - k->offset_raw_q32;
    const int64_t r = canfdi_asr64_rnd(acc, 32U);
    CANFDI_ASSERT(((int64_t)v_q16 * k->inv_scale_q32) < (INT64_C(1) << 62));
    raw = (r < (int64_t)k->raw_min) ? k->raw_min
                                    : ((r > (int64_t)k->raw_max) ? k->raw_max : (int32_t)r);
  }
  return raw;
}

/* Integer field limited to [0, max]. */
static uint32_t sat_u(canfdi_tx_t *tx, uint32_t v, uint32_t max)
{
  uint32_t out = v;
  if (v > max) {
    out = max;
    canfdi_count_inc(&tx->diag.saturations);
  }
  return out;
}

/* A time in us as the DBC's 2 us units, rounded up (a maximum is never
 * under-reported); overflow-free for any uint32_t. */
static uint32_t us_to_2us_up(uint32_t us)
{
  return (us / 2U) + (us & 1U);
}

static uint16_t raw_u16(int32_t raw)
{
  CANFDI_ASSERT((raw >= 0) && (raw <= (int32_t)UINT16_MAX)); /* within raw limits */
  return (uint16_t)raw;
}

static int16_t raw_s16(int32_t raw)
{
  return canfdi_sat_s32_to_s16(raw); /* within raw limits: never saturates */
}

static bool usable(const canfdi_tx_t *tx)
{
  return (tx != NULL) && tx->initialised;
}

/* Common prologue of the encoders. */
static bool args_ok(canfdi_tx_t *tx, const void *v, const canfdi_tx_frame_t *out)
{
  bool ok = usable(tx) && (v != NULL) && (out != NULL);
  if (!ok && usable(tx)) {
    canfdi_count_inc(&tx->diag.bad_args);
  }
  return ok;
}

static void frame_head(canfdi_tx_frame_t *out, uint32_t id, int packed)
{
  CANFDI_ASSERT(packed == 8); /* the buffer is 8 bytes: pack cannot fail */
  (void)packed;
  out->id = id;
  out->dlc = 8U;
}

int canfdi_tx_init(canfdi_tx_t *tx)
{
  int out = -CANFDI_EINVAL;
  if (tx != NULL) {
    static const canfdi_tx_diag_t zero;
    canfdi_e2e_tx_init(&tx->e2e[CANFDI_TX_E2E_DCM_ACT], (uint16_t)CANFDI_MSG_DCM_ACTUATOR_FRAME_ID);
    canfdi_e2e_tx_init(&tx->e2e[CANFDI_TX_E2E_THR_ACT], (uint16_t)CANFDI_MSG_THR_ACTUATOR_FRAME_ID);
    canfdi_e2e_tx_init(&tx->e2e[CANFDI_TX_E2E_STATUS], (uint16_t)CANFDI_MSG_ECU_STATUS_FRAME_ID);
    canfdi_e2e_tx_init(&tx->e2e[CANFDI_TX_E2E_DIAGNOSIS], (uint16_t)CANFDI_MSG_ECU_DIAGNOSIS_FRAME_ID);
    canfdi_e2e_tx_init(&tx->e2e[CANFDI_TX_E2E_DTC], (uint16_t)CANFDI_MSG_ECU_DTC_FRAME_ID);
    for (unsigned f = 0U; f < (unsigned)CANFDI_TX_F_COUNT; f++) {
      tx->countdown[f] = (uint8_t)(slots[f].phase % slots[f].period);
    }
    tx->q_head = 0U;
    tx->q_len = 0U;
    tx->diag = zero;
    tx->initialised = true;
    out = CANFDI_OK;
  }
  return out;
}

uint32_t canfdi_tx_due(const canfdi_tx_t *tx)
{
  uint32_t due = 0U;
  if (usable(tx)) {
    for (unsigned f = 0U; f < (unsigned)CANFDI_TX_F_COUNT; f++) {
      if (tx->countdown[f] == 0U) {
        due |= UINT32_C(1) << f;
      }
    }
    if (tx->q_len > 0U) {
      due |= UINT32_C(1) << CANFDI_TX_F_DTC_EVENT;
    }
  }
  return due;
}

int canfdi_tx_encode_dcm_act(canfdi_tx_t *tx, const canfdi_tx_dcm_act_t *v, canfdi_tx_frame_t *out)
{
  int ret = -CANFDI_EINVAL;
  if (args_ok(tx, v, out)) {
    struct canfdi_msg_dcm_actuator_t m;
    bool enable = v->enable;
    uint8_t bridge = v->bridge;
    if (bridge > (uint8_t)CANFDI_RAW_DCM_ACTUATOR_DCM_BRIDGE_SEL_MAX) {
      /* An unknown stage must not be driven: none, and disabled. */
      bridge = (uint8_t)CANFDI_MSG_DCM_ACTUATOR_DCM_BRIDGE_SEL_NONE_CHOICE;
      enable = false;
      canfdi_count_inc(&tx->diag.invalid_enums);
    }
    m.dcm_actuator_crc = 0U;
    m.dcm_actuator_counter = 0U;
    m.dcm_bridge_sel = bridge;
    m.dcm_enable = enable ? 1U : 0U;
    m.dcm_ua_cmd = raw_u16(to_raw(tx, C_DCM_UA_CMD, v->ua_cmd_q16));
    frame_head(out, CANFDI_MSG_DCM_ACTUATOR_FRAME_ID, canfdi_msg_dcm_actuator_pack(out->data, &m, 8U));
    ret = canfdi_e2e_protect(&tx->e2e[CANFDI_TX_E2E_DCM_ACT], out->data, 8U);
    CANFDI_ASSERT(ret == CANFDI_OK);
    canfdi_count_inc(&tx->diag.frames[CANFDI_TX_F_DCM_ACT]);
  }
  return ret;
}

int canfdi_tx_encode_thr_act(canfdi_tx_t *tx, const canfdi_tx_thr_act_t *v, canfdi_tx_frame_t *out)
{
  int ret = -CANFDI_EINVAL;
  if (args_ok(tx, v, out)) {
    struct canfdi_msg_thr_actuator_t m;
    m.thr_actuator_crc = 0U;
    m.thr_actuator_counter = 0U;
    m.thr_enable = v->enable ? 1U : 0U;
    m.thr_u_cmd = raw_u16(to_raw(tx, C_THR_UCMD, v->u_cmd_q16));
    frame_head(out, CANFDI_MSG_THR_ACTUATOR_FRAME_ID, canfdi_msg_thr_actuator_pack(out->data, &m, 8U));
    ret = canfdi_e2e_protect(&tx->e2e[CANFDI_TX_E2E_THR_ACT], out->data, 8U);
    CANFDI_ASSERT(ret == CANFDI_OK);
    canfdi_count_inc(&tx->diag.frames[CANFDI_TX_F_THR_ACT]);
  }
  return ret;
}

int canfdi_tx_encode_res_dcm(canfdi_tx_t *tx, const canfdi_tx_res_dcm_t *v, canfdi_tx_frame_t *out)
{
  int ret = -CANFDI_EINVAL;
  if (args_ok(tx, v, out)) {
    struct canfdi_msg_ecu_residual_dcm_t m;
    m.res_dcm_r1 = raw_s16(to_raw(tx, C_RES_DCM_R1, v->r_q16[0]));
    m.res_dcm_r2 = raw_s16(to_raw(tx, C_RES_DCM_R2, v->r_q16[1]));
    m.res_dcm_r3 = raw_s16(to_raw(tx, C_RES_DCM_R3, v->r_q16[2]));
    m.res_dcm_r4 = raw_s16(to_raw(tx, C_RES_DCM_R4, v->r_q16[3]));
    frame_head(out, CANFDI_MSG_ECU_RESIDUAL_DCM_FRAME_ID,
               canfdi_msg_ecu_residual_dcm_pack(out->data, &m, 8U));
    canfdi_count_inc(&tx->diag.frames[CANFDI_TX_F_RES_DCM]);
    ret = CANFDI_OK;
  }
  return ret;
}

int canfdi_tx_encode_res_thr(canfdi_tx_t *tx, const canfdi_tx_res_thr_t *v, canfdi_tx_frame_t *out)
{
  int ret = -CANFDI_EINVAL;
  if (args_ok(tx, v, out)) {
    struct canfdi_msg_ecu_residual_thr_t m;
    m.res_thr_corr = raw_s16(to_raw(tx, C_RES_THR_CORR, v->corr_q16));
    m.res_thr_tps1 = raw_s16(to_raw(tx, C_RES_THR_TPS1, v->tps1_q16));
    m.res_thr_tps2 = raw_s16(to_raw(tx, C_RES_THR_TPS2, v->tps2_q16));
    m.res_thr_current = raw_s16(to_raw(tx, C_RES_THR_CURRENT, v->current_q16));
    frame_head(out, CANFDI_MSG_ECU_RESIDUAL_THR_FRAME_ID,
               canfdi_msg_ecu_residual_thr_pack(out->data, &m, 8U));
    canfdi_count_inc(&tx->diag.frames[CANFDI_TX_F_RES_THR]);
    ret = CANFDI_OK;
  }
  return ret;
}

int canfdi_tx_encode_status(canfdi_tx_t *tx, const canfdi_tx_status_t *v, canfdi_tx_frame_t *out)
{
  int ret = -CANFDI_EINVAL;
  if (args_ok(tx, v, out)) {
    struct canfdi_msg_ecu_status_t m;
    m.sts_deg_state_dcm =
        (uint8_t)sat_u(tx, v->deg_state_dcm, CANFDI_RAW_ECU_STATUS_STS_DEG_STATE_DCM_MAX);
    m.sts_deg_state_thr =
        (uint8_t)sat_u(tx, v->deg_state_thr, CANFDI_RAW_ECU_STATUS_STS_DEG_STATE_THR_MAX);
    m.sts_active_bridge =
        (uint8_t)sat_u(tx, v->active_bridge, CANFDI_RAW_ECU_STATUS_STS_ACTIVE_BRIDGE_MAX);
    m.sts_thr_limp_home = v->thr_limp_home ? 1U : 0U;
    m.sts_active_dtc_count =
        (uint8_t)sat_u(tx, v->active_dtc_count, CANFDI_RAW_ECU_STATUS_STS_ACTIVE_DTC_COUNT_MAX);
    m.sts_deadline_misses =
        (uint16_t)sat_u(tx, v->deadline_misses, CANFDI_RAW_ECU_STATUS_STS_DEADLINE_MISSES_MAX);
    m.sts_step_time_max = (uint16_t)sat_u(tx, us_to_2us_up(v->step_time_max_us),
                                          CANFDI_RAW_ECU_STATUS_STS_STEP_TIME_MAX_MAX);
    m.sts_cycle_time_max = (uint16_t)sat_u(tx, us_to_2us_up(v->cycle_time_max_us),
                                           CANFDI_RAW_ECU_STATUS_STS_CYCLE_TIME_MAX_MAX);
    m.ecu_status_crc = 0U;
    m.ecu_status_counter = 0U; /* canfdi_e2e_protect writes it: the alive counter */
    frame_head(out, CANFDI_MSG_ECU_STATUS_FRAME_ID, canfdi_msg_ecu_status_pack(out->data, &m, 8U));
    ret = canfdi_e2e_protect(&tx->e2e[CANFDI_TX_E2E_STATUS], out->data, 8U);
    CANFDI_ASSERT(ret == CANFDI_OK);
    canfdi_count_inc(&tx->diag.frames[CANFDI_TX_F_STATUS]);
  }
  return ret;
}

int canfdi_tx_encode_diagnosis(canfdi_tx_t *tx, const canfdi_tx_diagnosis_t *v,
                               canfdi_tx_frame_t *out)
{
  int ret = -CANFDI_EINVAL;
  if (args_ok(tx, v, out)) {
    struct canfdi_msg_ecu_diagnosis_t m;
    m.diag_dcm_fault_id = v->dcm_fault_id;
    m.diag_thr_fault_id = v->thr_fault_id;
    m.diag_com_fault_id = v->com_fault_id;
    m.diag_dcm_confidence = (uint8_t)sat_u(tx, v->dcm_confidence_pct,
                                           CANFDI_RAW_ECU_DIAGNOSIS_DIAG_DCM_CONFIDENCE_MAX);
    m.diag_thr_confidence = (uint8_t)sat_u(tx, v->thr_confidence_pct,
                                           CANFDI_RAW_ECU_DIAGNOSIS_DIAG_THR_CONFIDENCE_MAX);
    m.diag_com_confidence = (uint8_t)sat_u(tx, v->com_confidence_pct,
                                           CANFDI_RAW_ECU_DIAGNOSIS_DIAG_COM_CONFIDENCE_MAX);
    m.ecu_diagnosis_crc = 0U;
    m.ecu_diagnosis_counter = 0U;
    frame_head(out, CANFDI_MSG_ECU_DIAGNOSIS_FRAME_ID,
               canfdi_msg_ecu_diagnosis_pack(out->data, &m, 8U));
    ret = canfdi_e2e_protect(&tx->e2e[CANFDI_TX_E2E_DIAGNOSIS], out->data, 8U);
    CANFDI_ASSERT(ret == CANFDI_OK);
    canfdi_count_inc(&tx->diag.frames[CANFDI_TX_F_DIAGNOSIS]);
  }
  return ret;
}

int canfdi_tx_encode_self_diag(canfdi_tx_t *tx, const canfdi_tx_self_diag_t *v,
                               canfdi_tx_frame_t *out)
{
  int ret = -CANFDI_EINVAL;
  if (args_ok(tx, v, out)) {
    struct canfdi_msg_ecu_self_diag_t m;
    m.sdg_frames_rejected = (uint16_t)sat_u(tx, v->frames_rejected,
                                            CANFDI_RAW_ECU_SELF_DIAG_SDG_FRAMES_REJECTED_MAX);
    m.sdg_frames_unknown = (uint16_t)sat_u(tx, v->frames_unknown,
                                           CANFDI_RAW_ECU_SELF_DIAG_SDG_FRAMES_UNKNOWN_MAX);
    m.sdg_saturations =
        (uint16_t)sat_u(tx, v->saturations, CANFDI_RAW_ECU_SELF_DIAG_SDG_SATURATIONS_MAX);
    m.sdg_estimator_resets = (uint8_t)sat_u(tx, v->estimator_resets,
                                            CANFDI_RAW_ECU_SELF_DIAG_SDG_ESTIMATOR_RESETS_MAX);
    m.sdg_dtc_reports_rejected = (uint8_t)sat_u(
        tx, v->dtc_reports_rejected, CANFDI_RAW_ECU_SELF_DIAG_SDG_DTC_REPORTS_REJECTED_MAX);
    frame_head(out, CANFDI_MSG_ECU_SELF_DIAG_FRAME_ID,
               canfdi_msg_ecu_self_diag_pack(out->data, &m, 8U));
    canfdi_count_inc(&tx->diag.frames[CANFDI_TX_F_SELF_DIAG]);
    ret = CANFDI_OK;
  }
  return ret;
}

int canfdi_tx_encode_dtc(canfdi_tx_t *tx, const canfdi_tx_dtc_t *v, bool change,
                         canfdi_tx_frame_t *out)
{
  int ret = -CANFDI_EINVAL;
  if (args_ok(tx, v, out)) {
    struct canfdi_msg_ecu_dtc_t m;
    const uint8_t st = v->status;
    m.dtc_code = sat_u(tx, v->dtc, CANFDI_RAW_ECU_DTC_DTC_CODE_MAX);
    /* The UDS status byte, bit by bit, in the order of ISO 14229-1. */
    m.dtc_sts_test_failed = (uint8_t)(st & 1U);
    m.dtc_sts_test_failed_this_op_cycle = (uint8_t)((st >> 1U) & 1U);
    m.dtc_sts_pending = (uint8_t)((st >> 2U) & 1U);
    m.dtc_sts_confirmed = (uint8_t)((st >> 3U) & 1U);
    m.dtc_sts_not_completed_since_clear = (uint8_t)((st >> 4U) & 1U);
    m.dtc_sts_failed_since_clear = (uint8_t)((st >> 5U) & 1U);
    m.dtc_sts_not_completed_this_op_cycle = (uint8_t)((st >> 6U) & 1U);
    m.dtc_sts_warning_indicator = (uint8_t)((st >> 7U) & 1U);
    m.dtc_occurrence = v->occurrence;
    m.dtc_index = (uint8_t)sat_u(tx, v->index, CANFDI_RAW_ECU_DTC_DTC_INDEX_MAX);
    m.dtc_count = (uint8_t)sat_u(tx, v->count, CANFDI_RAW_ECU_DTC_DTC_COUNT_MAX);
    m.dtc_tx_reason = change ? 1U : 0U;
    m.ecu_dtc_crc = 0U;
    m.ecu_dtc_counter = 0U;
    frame_head(out, CANFDI_MSG_ECU_DTC_FRAME_ID, canfdi_msg_ecu_dtc_pack(out->data, &m, 8U));
    ret = canfdi_e2e_protect(&tx->e2e[CANFDI_TX_E2E_DTC], out->data, 8U);
    CANFDI_ASSERT(ret == CANFDI_OK);
    canfdi_count_inc(&tx->diag.frames[CANFDI_TX_F_DTC]);
  }
  return ret;
}

int canfdi_tx_encode_prm_dcm(canfdi_tx_t *tx, const canfdi_tx_param_dcm_t *v,
                             canfdi_tx_frame_t *out)
{
  int ret = -CANFDI_EINVAL;
  if (args_ok(tx, v, out)) {
    struct canfdi_msg_ecu_param_dcm_t m;
    m.prm_dcm_ra = raw_u16(to_raw(tx, C_PRM_DCM_RA, v->ra_q16));
    m.prm_dcm_psi = raw_u16(to_raw(tx, C_PRM_DCM_PSI, v->psi_q16));
    m.prm_dcm_j = raw_u16(to_raw(tx, C_PRM_DCM_J, v->j_q16));
    m.prm_dcm_mf1 = raw_u16(to_raw(tx, C_PRM_DCM_MF1, v->mf1_q16));
    m.prm_dcm_mf0 = raw_u16(to_raw(tx, C_PRM_DCM_MF0, v->mf0_q16));
    m.prm_dcm_valid = v->valid ? 1U : 0U;
    frame_head(out, CANFDI_MSG_ECU_PARAM_DCM_FRAME_ID,
               canfdi_msg_ecu_param_dcm_pack(out->data, &m, 8U));
    canfdi_count_inc(&tx->diag.frames[CANFDI_TX_F_PRM_DCM]);
    ret = CANFDI_OK;
  }
  return ret;
}

int canfdi_tx_encode_prm_thr(canfdi_tx_t *tx, const canfdi_tx_param_thr_t *v,
                             canfdi_tx_frame_t *out)
{
  int ret = -CANFDI_EINVAL;
  if (args_ok(tx, v, out)) {
    struct canfdi_msg_ecu_param_thr_t m;
    m.prm_thr_r = raw_u16(to_raw(tx, C_PRM_THR_R, v->r_q16));
    m.prm_thr_spring_k = raw_u16(to_raw(tx, C_PRM_THR_SPRING_K, v->spring_k_q16));
    m.prm_thr_spring_pre = raw_u16(to_raw(tx, C_PRM_THR_SPRING_PRE, v->spring_pre_q16));
    m.prm_thr_fric_c = raw_u16(to_raw(tx, C_PRM_THR_FRIC_C, v->fric_c_q16));
    m.prm_thr_fric_v = raw_u16(to_raw(tx, C_PRM_THR_FRIC_V, v->fric_v_q16));
    m.prm_thr_valid = v->valid ? 1U : 0U;
    frame_head(out, CANFDI_MSG_ECU_PARAM_THR_FRAME_ID,
               canfdi_msg_ecu_param_thr_pack(out->data, &m, 8U));
    canfdi_count_inc(&tx->diag.frames[CANFDI_TX_F_PRM_THR]);
    ret = CANFDI_OK;
  }
  return ret;
}

int canfdi_tx_encode_uds_resp(canfdi_tx_t *tx, const uint8_t *isotp, canfdi_tx_frame_t *out)
{
  int ret = -CANFDI_EINVAL;
  if (args_ok(tx, isotp, out)) {
    struct canfdi_msg_uds_phys_resp_t m;
    uint64_t v = 0U;
    for (uint32_t i = 0U; i < CANFDI_CFG_ISOTP_FRAME_BYTES; i++) {
      v = (v << 8) | (uint64_t)isotp[i];
    }
    m.uds_phys_resp_data = v;
    frame_head(out, CANFDI_MSG_UDS_PHYS_RESP_FRAME_ID,
               canfdi_msg_uds_phys_resp_pack(out->data, &m, 8U));
    canfdi_count_inc(&tx->diag.uds_frames);
    ret = CANFDI_OK;
  }
  return ret;
}

int canfdi_tx_dtc_event(canfdi_tx_t *tx, const canfdi_tx_dtc_t *rec)
{
  int ret = -CANFDI_EINVAL;
  if (usable(tx) && (rec != NULL)) {
    if (tx->q_len >= CANFDI_CFG_TX_DTC_QUEUE) {
      canfdi_count_inc(&tx->diag.dtc_events_dropped);
      ret = -CANFDI_ERANGE;
    } else {
      const unsigned tail = ((unsigned)tx->q_head + tx->q_len) % CANFDI_CFG_TX_DTC_QUEUE;
      tx->queue[tail] = *rec;
      tx->q_len++;
      ret = CANFDI_OK;
    }
  } else if (usable(tx)) {
    canfdi_count_inc(&tx->diag.bad_args);
  } else {
    /* nothing to count in */
  }
  return ret;
}

int canfdi_tx_step(canfdi_tx_t *tx, const canfdi_tx_data_t *data, canfdi_tx_frame_t *out)
{
  int ret = -CANFDI_EINVAL;
  if (usable(tx) && (data != NULL) && (out != NULL)) {
    const uint32_t due = canfdi_tx_due(tx);
    unsigned n = 0U;
    unsigned failed = 0U;
    if ((due & (UINT32_C(1) << CANFDI_TX_F_DCM_ACT)) != 0U) {
      failed += (canfdi_tx_encode_dcm_act(tx, &data->dcm_act, &out[n++]) != CANFDI_OK) ? 1U : 0U;
    }
    if ((due & (UINT32_C(1) << CANFDI_TX_F_THR_ACT)) != 0U) {
      failed += (canfdi_tx_encode_thr_act(tx, &data->thr_act, &out[n++]) != CANFDI_OK) ? 1U : 0U;
    }
    if ((due & (UINT32_C(1) << CANFDI_TX_F_RES_DCM)) != 0U) {
      failed += (canfdi_tx_encode_res_dcm(tx, &data->res_dcm, &out[n++]) != CANFDI_OK) ? 1U : 0U;
    }
    if ((due & (UINT32_C(1) << CANFDI_TX_F_RES_THR)) != 0U) {
      failed += (canfdi_tx_encode_res_thr(tx, &data->res_thr, &out[n++]) != CANFDI_OK) ? 1U : 0U;
    }
    if ((due & (UINT32_C(1) << CANFDI_TX_F_STATUS)) != 0U) {
      failed += (canfdi_tx_encode_status(tx, &data->status, &out[n++]) != CANFDI_OK) ? 1U : 0U;
    }
    if ((due & (UINT32_C(1) << CANFDI_TX_F_DIAGNOSIS)) != 0U) {
      failed += (canfdi_tx_encode_diagnosis(tx, &data->diagnosis, &out[n++]) != CANFDI_OK) ? 1U : 0U;
    }
    if ((due & (UINT32_C(1) << CANFDI_TX_F_SELF_DIAG)) != 0U) {
      failed += (canfdi_tx_encode_self_diag(tx, &data->self_diag, &out[n++]) != CANFDI_OK) ? 1U : 0U;
    }
    if ((due & (UINT32_C(1) << CANFDI_TX_F_DTC)) != 0U) {
      failed += (canfdi_tx_encode_dtc(tx, &data->dtc, false, &out[n++]) != CANFDI_OK) ? 1U : 0U;
    }
    if ((due & (UINT32_C(1) << CANFDI_TX_F_PRM_DCM)) != 0U) {
      failed += (canfdi_tx_encode_prm_dcm(tx, &data->prm_dcm, &out[n++]) != CANFDI_OK) ? 1U : 0U;
    }
    if ((due & (UINT32_C(1) << CANFDI_TX_F_PRM_THR)) != 0U) {
      failed += (canfdi_tx_encode_prm_thr(tx, &data->prm_thr, &out[n++]) != CANFDI_OK) ? 1U : 0U;
    }
    if ((due & (UINT32_C(1) << CANFDI_TX_F_DTC_EVENT)) != 0U) {
      failed += (canfdi_tx_encode_dtc(tx, &tx->queue[tx->q_head], true, &out[n++]) != CANFDI_OK) ? 1U : 0U;
      tx->q_head = (uint8_t)((tx->q_head + 1U) % CANFDI_CFG_TX_DTC_QUEUE);
      tx->q_len--;
      canfdi_count_inc(&tx->diag.dtc_events);
    }
    CANFDI_ASSERT(failed == 0U); /* arguments checked above */
    CANFDI_ASSERT(n <= CANFDI_TX_MAX_FRAMES_PER_STEP); /* the phases guarantee it */
    (void)failed;
    for (unsigned f = 0U; f < (unsigned)CANFDI_TX_F_COUNT; f++) {
      tx->countdown[f] = (tx->countdown[f] == 0U) ? (uint8_t)(slots[f].period - 1U)
                                                  : (uint8_t)(tx->countdown[f] - 1U);
    }
    canfdi_count_inc(&tx->diag.steps);
    ret = (int)n;
  } else if (usable(tx)) {
    canfdi_count_inc(&tx->diag.bad_args);
  } else {
    /* nothing to count in */
  }
  return ret;
}
