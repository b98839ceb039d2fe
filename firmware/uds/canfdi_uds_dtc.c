/*
 * canfdi_uds_dtc.c — 0x14 and 0x19 from the DTC memory; the manual is the
 * header.
 */
#include "uds/canfdi_uds_dtc.h"

#define SF_NUM_BY_MASK 0x01U
#define SF_BY_MASK 0x02U
#define SF_SNAPSHOT_ID 0x03U
#define SF_SNAPSHOT 0x04U
#define SF_EXT_DATA 0x06U
#define SF_SUPPORTED 0x0AU
#define SF_FDC 0x14U
#define RECORD_ALL 0xFFU

bool canfdi_uds_dtc_subfn_supported(uint8_t subfn)
{
  return (subfn == SF_NUM_BY_MASK) || (subfn == SF_BY_MASK) || (subfn == SF_SNAPSHOT_ID) ||
         (subfn == SF_SNAPSHOT) || (subfn == SF_EXT_DATA) || (subfn == SF_SUPPORTED) || (subfn == SF_FDC);
}

uint8_t canfdi_uds_dtc_clear(canfdi_dtc_t *dtc, canfdi_uds_msg_t *m)
{
  uint8_t nrc = CANFDI_UDS_NRC_IMLOIF;
  if ((m->req_len == 4U) || (m->req_len == 5U)) {
    const uint32_t group = canfdi_uds_get_u24(&m->req[1]);
    int32_t rc = -CANFDI_EINVAL;
    nrc = CANFDI_UDS_NRC_ROOR;
    if ((m->req_len == 5U) && (m->req[4] != 0U)) {
      rc = -CANFDI_EINVAL; /* only the primary memory exists */
    } else if (group == CANFDI_UDS_GROUP_DC_MOTOR) {
      rc = canfdi_dtc_clear_group(dtc, (uint8_t)CANFDI_COMPONENT_DC_MOTOR);
    } else if (group == CANFDI_UDS_GROUP_THROTTLE) {
      rc = canfdi_dtc_clear_group(dtc, (uint8_t)CANFDI_COMPONENT_THROTTLE);
    } else if (group == CANFDI_UDS_GROUP_COMM) {
      rc = canfdi_dtc_clear_group(dtc, (uint8_t)CANFDI_COMPONENT_COMM);
    } else {
      rc = canfdi_dtc_clear(dtc, group); /* all, or one DTC */
    }
    if (rc >= 0) {
      canfdi_uds_put_u8(m, (uint8_t)(CANFDI_UDS_SID_CDTCI + CANFDI_UDS_POS_OFFSET));
      nrc = CANFDI_UDS_NRC_OK;
    }
  }
  return nrc;
}

static void put_dtc_status(canfdi_uds_msg_t *m, uint32_t dtc, uint8_t status)
{
  canfdi_uds_put_u24(m, dtc);
  canfdi_uds_put_u8(m, status);
}

/* 0x01, 0x02, 0x0A: by status mask (0x0A: every DTC). */
static void by_mask(const canfdi_dtc_t *dtc, uint8_t subfn, uint8_t mask, canfdi_uds_msg_t *m)
{
  canfdi_uds_put_u8(m, (uint8_t)CANFDI_DTC_STATUS_AVAILABILITY_MASK);
  if (subfn == SF_NUM_BY_MASK) {
    canfdi_uds_put_u8(m, (uint8_t)CANFDI_UDS_DTC_FORMAT_ID);
    canfdi_uds_put_u16(m, canfdi_dtc_count_by_mask(dtc, mask));
  } else {
    for (uint8_t i = 0U; i < dtc->n_dtcs; i++) {
      const uint8_t s = dtc->dtc[i].status;
      if ((subfn == SF_SUPPORTED) || ((s & mask) != 0U)) {
        put_dtc_status(m, dtc->table[i].dtc, s);
      }
    }
  }
}

/* 0x03 and 0x14: lists over the table. */
static void lists(const canfdi_dtc_t *dtc, uint8_t subfn, canfdi_uds_msg_t *m)
{
  for (uint8_t i = 0U; i < dtc->n_dtcs; i++) {
    const uint8_t e = dtc->dtc[i].entry;
    if (subfn == SF_SNAPSHOT_ID) {
      if ((e != CANFDI_DTC_NONE) && dtc->entry[e].ff_valid) {
        canfdi_uds_put_u24(m, dtc->table[i].dtc);
        canfdi_uds_put_u8(m, (uint8_t)CANFDI_UDS_SNAPSHOT_RECORD);
      }
    } else {
      const int8_t fdc = canfdi_dtc_fdc(dtc, i);
      if ((fdc > 0) && (fdc < 127)) {
        canfdi_uds_put_u24(m, dtc->table[i].dtc);
        canfdi_uds_put_u8(m, (uint8_t)fdc);
      }
    }
  }
}

static uint32_t sat_u32(uint64_t v) { return (v > (uint64_t)UINT32_MAX) ? UINT32_MAX : (uint32_t)v; }

/* One freeze-frame DID's value, in its format (catalogue/canfdi_uds_ids.h). */
static void put_ff_did(canfdi_uds_msg_t *m, const canfdi_dtc_ff_t *ff, uint16_t did)
{
  canfdi_uds_put_u16(m, did);
  switch (did) {
    case CANFDI_UDS_DID_UPTIME: canfdi_uds_put_u32(m, sat_u32(ff->time_ms)); break;
    case CANFDI_UDS_DID_DCM_SPEED: canfdi_uds_put_s32(m, ff->omega_q16); break;
    case CANFDI_UDS_DID_DCM_CURRENT: canfdi_uds_put_s32(m, ff->ia_q16); break;
    case CANFDI_UDS_DID_DCM_VOLTAGE: canfdi_uds_put_s32(m, ff->ua_q16); break;
    case CANFDI_UDS_DID_THR_ANGLE: canfdi_uds_put_s32(m, ff->thr_angle_q16); break;
    case CANFDI_UDS_DID_DCM_SUPPLY: canfdi_uds_put_s32(m, ff->supply_q16); break;
    case CANFDI_UDS_DID_DEG_DCM: canfdi_uds_put_u8(m, ff->deg_dcm); break;
    default: canfdi_uds_put_u8(m, ff->deg_thr); break; /* CANFDI_UDS_DID_DEG_THR */
  }
}

#define FF_DID(did) (did),

static void snapshot(const canfdi_dtc_t *dtc, uint8_t i, canfdi_uds_msg_t *m)
{
  static const uint16_t dids[CANFDI_UDS_SNAPSHOT_DIDS] = {CANFDI_UDS_SNAPSHOT_TABLE(FF_DID)};
  const uint8_t e = dtc->dtc[i].entry;
  if ((e != CANFDI_DTC_NONE) && dtc->entry[e].ff_valid) {
    canfdi_uds_put_u8(m, (uint8_t)CANFDI_UDS_SNAPSHOT_RECORD);
    canfdi_uds_put_u8(m, (uint8_t)CANFDI_UDS_SNAPSHOT_DIDS);
    for (uint32_t k = 0U; k < CANFDI_UDS_SNAPSHOT_DIDS; k++) {
      put_ff_did(m, &dtc->entry[e].ff, dids[k]);
    }
  }
}

static void ext_data(const canfdi_dtc_t *dtc, uint8_t i, uint8_t rec, canfdi_uds_msg_t *m)
{
  const uint8_t e = dtc->dtc[i].entry;
  if (e != CANFDI_DTC_NONE) {
    if ((rec == CANFDI_UDS_EXT_OCCURRENCE) || (rec == RECORD_ALL)) {
      canfdi_uds_put_u8(m, (uint8_t)CANFDI_UDS_EXT_OCCURRENCE);
      canfdi_uds_put_u8(m, dtc->entry[e].occurrence);
    }
    if ((rec == CANFDI_UDS_EXT_AGING) || (rec == RECORD_ALL)) {
      canfdi_uds_put_u8(m, (uint8_t)CANFDI_UDS_EXT_AGING);
      canfdi_uds_put_u8(m, dtc->dtc[i].healthy_cycles);
    }
  }
}

/* 0x04 and 0x06: one DTC's records. */
static uint8_t by_dtc(const canfdi_dtc_t *dtc, uint8_t subfn, canfdi_uds_msg_t *m)
{
  const int32_t i = canfdi_dtc_find(dtc, canfdi_uds_get_u24(&m->req[2]));
  const uint8_t rec = m->req[5];
  const bool rec_ok = (subfn == SF_SNAPSHOT)
                          ? ((rec == CANFDI_UDS_SNAPSHOT_RECORD) || (rec == RECORD_ALL))
                          : ((rec == CANFDI_UDS_EXT_OCCURRENCE) || (rec == CANFDI_UDS_EXT_AGING) || (rec == RECORD_ALL));
  uint8_t nrc = CANFDI_UDS_NRC_ROOR;
  if ((i >= 0) && rec_ok) {
    put_dtc_status(m, dtc->table[i].dtc, dtc->dtc[i].status);
    if (subfn == SF_SNAPSHOT) {
      snapshot(dtc, (uint8_t)i, m);
    } else {
      ext_data(dtc, (uint8_t)i, rec, m);
    }
    nrc = CANFDI_UDS_NRC_OK;
  }
  return nrc;
}

/* The request length of each sub-function. */
static uint32_t want_len(uint8_t subfn)
{
  uint32_t n = 2U; /* 0x03, 0x0A, 0x14 */
  if ((subfn == SF_NUM_BY_MASK) || (subfn == SF_BY_MASK)) {
    n = 3U;
  } else if ((subfn == SF_SNAPSHOT) || (subfn == SF_EXT_DATA)) {
    n = 6U;
  } else {
    /* no parameters */
  }
  return n;
}

uint8_t canfdi_uds_dtc_read(const canfdi_dtc_t *dtc, canfdi_uds_msg_t *m)
{
  const uint8_t subfn = (uint8_t)(m->req[1] & 0x7FU);
  uint8_t nrc = CANFDI_UDS_NRC_IMLOIF;
  if (m->req_len == want_len(subfn)) {
    nrc = CANFDI_UDS_NRC_OK;
    canfdi_uds_put_u8(m, (uint8_t)(CANFDI_UDS_SID_RDTCI + CANFDI_UDS_POS_OFFSET));
    canfdi_uds_put_u8(m, subfn);
    if ((subfn == SF_NUM_BY_MASK) || (subfn == SF_BY_MASK)) {
      by_mask(dtc, subfn, (uint8_t)(m->req[2] & CANFDI_DTC_STATUS_AVAILABILITY_MASK), m);
    } else if (subfn == SF_SUPPORTED) {
      by_mask(dtc, subfn, 0U, m);
    } else if ((subfn == SF_SNAPSHOT_ID) || (subfn == SF_FDC)) {
      lists(dtc, subfn, m);
    } else {
      nrc = by_dtc(dtc, subfn, m);
    }
  }
  return nrc;
}
