/*
 * canfdi_uds_did.h — the data identifiers of the diagnostic server
 * (ReadDataByIdentifier 0x22, the freeze frame's records, the actuator
 * test's status): their values, read from the application's stages through
 * a read-only view, never from formatted bus frames.
 *
 * The identifiers, their formats and units are dbc/uds_dids.csv, generated
 * into catalogue/canfdi_uds_ids.h (CANFDI_UDS_DID_TABLE) and the tester's
 * tools/canfdi/uds_config.py. Formats (big-endian): ASCII16 (16 bytes,
 * space padded), S32Q16 (Q16.16 in the SI unit of the table: the firmware's
 * own value, exact), S32Q24 (Q8.24, the estimators' small parameters), U8,
 * U32 (counters saturate at their width).
 *
 * Groups: identification (F195 software version, F182 calibration id, F18C
 * serial number: the configuration's strings), live values (D1xx: the
 * input supervision's values of this step, the voted angle, the references
 * in use), estimates (D2xx), residuals over their thresholds (D3xx),
 * degradation (D4xx), self-diagnostic counters (D5xx), DF00 the uptime.
 *
 * Cost: canfdi_uds_did_put is a switch over the identifier and at most 16
 * byte writes; canfdi_uds_did_find O(number of DIDs) (51).
 */
#ifndef CANFDI_UDS_DID_H
#define CANFDI_UDS_DID_H

#include "catalogue/canfdi_uds_ids.h"
#include "comm/canfdi_isotp.h"
#include "comm/canfdi_rx.h"
#include "core/canfdi_common.h"
#include "ft/canfdi_actmgr.h"
#include "ft/canfdi_vote.h"
#include "model/canfdi_est_dcm.h"
#include "model/canfdi_est_thr.h"
#include "model/canfdi_parity_dcm.h"
#include "model/canfdi_parity_thr.h"
#include "uds/canfdi_uds_msg.h"

#define CANFDI_UDS_ID_BYTES 16U

/* The self-diagnostic counters (D500..D507), in DID order. */
typedef enum {
  CANFDI_UDS_CNT_STEPS = 0,
  CANFDI_UDS_CNT_DEADLINE_MISSES,
  CANFDI_UDS_CNT_FRAMES_REJECTED,
  CANFDI_UDS_CNT_FRAMES_UNKNOWN,
  CANFDI_UDS_CNT_FRAMES_SENT,
  CANFDI_UDS_CNT_SATURATIONS,
  CANFDI_UDS_CNT_ESTIMATOR_RESETS,
  CANFDI_UDS_CNT_DTC_REPORTS_REJECTED,
  CANFDI_UDS_CNT_COUNT
} canfdi_uds_cnt_t;

/* What the server may read of the application (pointers into the app's
 * state; filled by the application every step). */
typedef struct {
  const canfdi_rx_t *rx;
  const canfdi_vote_out_t *vote;
  const canfdi_actmgr_out_t *mgr;
  const canfdi_est_dcm_t *est_dcm;
  const canfdi_est_thr_t *est_thr;
  const canfdi_parity_dcm_t *parity_dcm;
  const canfdi_parity_thr_t *parity_thr;
  int32_t speed_ref_rad_s_q16; /* the references the controllers got */
  int32_t angle_ref_rad_q16;
  int32_t load_Nm_q16;         /* the load the models assume */
  uint64_t uptime_ms;
  uint32_t counters[CANFDI_UDS_CNT_COUNT];
} canfdi_uds_src_t;

/* The identification strings (16 bytes each, padded with spaces). */
typedef struct {
  uint8_t sw_version[CANFDI_UDS_ID_BYTES];
  uint8_t calibration_id[CANFDI_UDS_ID_BYTES];
  uint8_t serial_number[CANFDI_UDS_ID_BYTES];
} canfdi_uds_ident_t;

/* The server's own values a DID shows (ISO-TP errors, failed keys). */
typedef struct {
  uint32_t isotp_errors;
  uint8_t security_attempts;
} canfdi_uds_own_t;

/* Index of did in the table, or -CANFDI_EINVAL. */
int32_t canfdi_uds_did_find(uint16_t did);

/* Data bytes of did (0 for an unknown one). */
uint32_t canfdi_uds_did_size(uint16_t did);

/*
 * Append did (2 bytes) and its value to m. Returns CANFDI_UDS_NRC_OK, or
 * CANFDI_UDS_NRC_ROOR for an unknown did (nothing appended). A response
 * without room sets m->overflow.
 */
uint8_t canfdi_uds_did_put(const canfdi_uds_src_t *src, const canfdi_uds_ident_t *id,
                           const canfdi_uds_own_t *own, uint16_t did, canfdi_uds_msg_t *m);

#endif /* CANFDI_UDS_DID_H */
