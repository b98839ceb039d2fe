/*
 * canfdi_uds_did.c — the data identifiers' values; the manual is the header.
 */
#include "uds/canfdi_uds_did.h"

#include "core/canfdi_fixp.h"

#define DID_ROW(did, name, fmt, bytes) {(did), (fmt), (bytes)},

typedef struct {
  uint16_t did;
  uint8_t fmt;
  uint8_t bytes;
} did_row_t;

static const did_row_t rows[CANFDI_UDS_DID_COUNT] = {CANFDI_UDS_DID_TABLE(DID_ROW)};

int32_t canfdi_uds_did_find(uint16_t did)
{
  int32_t out = -CANFDI_EINVAL;
  for (uint32_t i = 0U; (i < CANFDI_UDS_DID_COUNT) && (out < 0); i++) {
    if (rows[i].did == did) {
      out = (int32_t)i;
    }
  }
  return out;
}

uint32_t canfdi_uds_did_size(uint16_t did)
{
  const int32_t i = canfdi_uds_did_find(did);
  return (i >= 0) ? rows[i].bytes : 0U;
}

static int32_t rx_val(const canfdi_uds_src_t *s, unsigned i) { return canfdi_rx_value(s->rx, i); }

static uint32_t sat_u32(uint64_t v) { return (v > (uint64_t)UINT32_MAX) ? UINT32_MAX : (uint32_t)v; }

/* Live values, estimates and residuals: the Q value, false if not one. */
static bool value_q(const canfdi_uds_src_t *s, uint16_t did, int32_t *v)
{
  const canfdi_parity_dcm_out_t *pd = canfdi_parity_dcm_out(s->parity_dcm);
  const canfdi_parity_thr_out_t *pt = canfdi_parity_thr_out(s->parity_thr);
  bool ok = true;
  switch (did) {
    case CANFDI_UDS_DID_DCM_SPEED: *v = rx_val(s, CANFDI_RX_IN_DCM_OMEGA); break;
    case CANFDI_UDS_DID_DCM_CURRENT: *v = rx_val(s, CANFDI_RX_IN_DCM_IA); break;
    case CANFDI_UDS_DID_DCM_VOLTAGE: *v = rx_val(s, CANFDI_RX_IN_DCM_UA); break;
    case CANFDI_UDS_DID_DCM_SUPPLY: *v = rx_val(s, CANFDI_RX_IN_DCM_USUPPLY); break;
    case CANFDI_UDS_DID_DCM_SPEED_REF: *v = s->speed_ref_rad_s_q16; break;
    case CANFDI_UDS_DID_DCM_LOAD: *v = s->load_Nm_q16; break;
    case CANFDI_UDS_DID_THR_ANGLE: *v = s->vote->angle_rad_q16; break;
    case CANFDI_UDS_DID_THR_TPS1: *v = rx_val(s, CANFDI_RX_IN_THR_TPS1); break;
    case CANFDI_UDS_DID_THR_TPS2: *v = rx_val(s, CANFDI_RX_IN_THR_TPS2); break;
    case CANFDI_UDS_DID_THR_CURRENT: *v = rx_val(s, CANFDI_RX_IN_THR_IMOT); break;
    case CANFDI_UDS_DID_THR_SUPPLY: *v = rx_val(s, CANFDI_RX_IN_THR_USUPPLY); break;
    case CANFDI_UDS_DID_THR_ANGLE_REF: *v = s->angle_ref_rad_q16; break;
    case CANFDI_UDS_DID_EST_DCM_RA: *v = canfdi_est_dcm_ra_q16(s->est_dcm); break;
    case CANFDI_UDS_DID_EST_DCM_PSI: *v = canfdi_est_dcm_psi_q16(s->est_dcm); break;
    case CANFDI_UDS_DID_EST_DCM_J: *v = canfdi_est_dcm_j_q24(s->est_dcm); break;
    case CANFDI_UDS_DID_EST_DCM_MF1: *v = canfdi_est_dcm_mf1_q24(s->est_dcm); break;
    case CANFDI_UDS_DID_EST_DCM_MC: *v = canfdi_est_dcm_mc_q16(s->est_dcm); break;
    case CANFDI_UDS_DID_EST_THR_R: *v = canfdi_est_thr_r_q16(s->est_thr); break;
    case CANFDI_UDS_DID_EST_THR_SPRING: *v = canfdi_est_thr_spring_q24(s->est_thr); break;
    case CANFDI_UDS_DID_EST_THR_PRETENSION: *v = canfdi_est_thr_pretension_q16(s->est_thr); break;
    case CANFDI_UDS_DID_EST_THR_FRICTION: *v = canfdi_est_thr_friction_q16(s->est_thr); break;
    case CANFDI_UDS_DID_EST_THR_VISCOUS: *v = canfdi_est_thr_b_q24(s->est_thr); break;
    case CANFDI_UDS_DID_RES_DCM_R1: *v = (pd != NULL) ? pd->rn_q16[0] : 0; break;
    case CANFDI_UDS_DID_RES_DCM_R2: *v = (pd != NULL) ? pd->rn_q16[1] : 0; break;
    case CANFDI_UDS_DID_RES_DCM_R3: *v = (pd != NULL) ? pd->rn_q16[2] : 0; break;
    case CANFDI_UDS_DID_RES_DCM_R4: *v = (pd != NULL) ? pd->rn_q16[3] : 0; break;
    case CANFDI_UDS_DID_RES_THR_CORR: *v = (pt != NULL) ? pt->rn_q16[CANFDI_PARITY_THR_CORR] : 0; break;
    case CANFDI_UDS_DID_RES_THR_TPS1: *v = (pt != NULL) ? pt->rn_q16[CANFDI_PARITY_THR_POS1] : 0; break;
    case CANFDI_UDS_DID_RES_THR_TPS2: *v = (pt != NULL) ? pt->rn_q16[CANFDI_PARITY_THR_POS2] : 0; break;
    case CANFDI_UDS_DID_RES_THR_CURRENT: *v = (pt != NULL) ? pt->rn_q16[CANFDI_PARITY_THR_ARM] : 0; break;
    default: ok = false; break;
  }
  return ok;
}

/* Flags, states and counters: the unsigned value, false if not one. */
static bool value_u(const canfdi_uds_src_t *s, const canfdi_uds_own_t *own, uint16_t did, uint32_t *v)
{
  bool ok = true;
  switch (did) {
    case CANFDI_UDS_DID_UPTIME: *v = sat_u32(s->uptime_ms); break;
    case CANFDI_UDS_DID_EST_DCM_VALID: *v = canfdi_est_dcm_arm_converged(s->est_dcm) ? 1U : 0U; break;
    case CANFDI_UDS_DID_EST_THR_VALID: *v = canfdi_est_thr_el_converged(s->est_thr) ? 1U : 0U; break;
    case CANFDI_UDS_DID_DEG_DCM: *v = s->mgr->dcm_state; break;
    case CANFDI_UDS_DID_DEG_THR: *v = s->mgr->thr_state; break;
    case CANFDI_UDS_DID_ACTIVE_BRIDGE: *v = s->mgr->dcm.bridge; break;
    case CANFDI_UDS_DID_THR_LIMP_HOME: *v = s->mgr->thr_limp_home ? 1U : 0U; break;
    case CANFDI_UDS_DID_STEPS: *v = s->counters[CANFDI_UDS_CNT_STEPS]; break;
    case CANFDI_UDS_DID_DEADLINE_MISSES: *v = s->counters[CANFDI_UDS_CNT_DEADLINE_MISSES]; break;
    case CANFDI_UDS_DID_FRAMES_REJECTED: *v = s->counters[CANFDI_UDS_CNT_FRAMES_REJECTED]; break;
    case CANFDI_UDS_DID_FRAMES_UNKNOWN: *v = s->counters[CANFDI_UDS_CNT_FRAMES_UNKNOWN]; break;
    case CANFDI_UDS_DID_FRAMES_SENT: *v = s->counters[CANFDI_UDS_CNT_FRAMES_SENT]; break;
    case CANFDI_UDS_DID_SATURATIONS: *v = s->counters[CANFDI_UDS_CNT_SATURATIONS]; break;
    case CANFDI_UDS_DID_ESTIMATOR_RESETS: *v = s->counters[CANFDI_UDS_CNT_ESTIMATOR_RESETS]; break;
    case CANFDI_UDS_DID_DTC_REPORTS_REJECTED: *v = s->counters[CANFDI_UDS_CNT_DTC_REPORTS_REJECTED]; break;
    case CANFDI_UDS_DID_ISOTP_ERRORS: *v = own->isotp_errors; break;
    case CANFDI_UDS_DID_SECURITY_ATTEMPTS: *v = own->security_attempts; break;
    default: ok = false; break;
  }
  return ok;
}

static const uint8_t *ident(const canfdi_uds_ident_t *id, uint16_t did)
{
  const uint8_t *p = id->serial_number;
  if (did == CANFDI_UDS_DID_SW_VERSION) {
    p = id->sw_version;
  } else if (did == CANFDI_UDS_DID_CALIBRATION_ID) {
    p = id->calibration_id;
  } else {
    /* the serial number */
  }
  return p;
}

uint8_t canfdi_uds_did_put(const canfdi_uds_src_t *src, const canfdi_uds_ident_t *id,
                           const canfdi_uds_own_t *own, uint16_t did, canfdi_uds_msg_t *m)
{
  uint8_t nrc = CANFDI_UDS_NRC_ROOR;
  const int32_t i = canfdi_uds_did_find(did);
  if ((i >= 0) && (src != NULL) && (id != NULL) && (own != NULL) && (m != NULL)) {
    const did_row_t *r = &rows[i];
    int32_t q = 0;
    uint32_t u = 0U;
    nrc = CANFDI_UDS_NRC_OK;
    canfdi_uds_put_u16(m, did);
    if (r->fmt == (uint8_t)CANFDI_UDS_FMT_ASCII16) {
      const uint8_t *p = ident(id, did);
      for (uint32_t k = 0U; k < CANFDI_UDS_ID_BYTES; k++) {
        canfdi_uds_put_u8(m, p[k]);
      }
    } else if ((r->fmt == (uint8_t)CANFDI_UDS_FMT_S32Q16) || (r->fmt == (uint8_t)CANFDI_UDS_FMT_S32Q24)) {
      (void)value_q(src, did, &q);
      canfdi_uds_put_s32(m, q);
    } else {
      (void)value_u(src, own, did, &u);
      if (r->fmt == (uint8_t)CANFDI_UDS_FMT_U8) {
        canfdi_uds_put_u8(m, (u > 255U) ? 255U : (uint8_t)u);
      } else {
        canfdi_uds_put_u32(m, u);
      }
    }
  }
  return nrc;
}
