/*
 * canfdi_uds_dtc.h — ClearDiagnosticInformation (0x14) and
 * ReadDTCInformation (0x19) of the diagnostic server, encoded from the DTC
 * memory (diag/canfdi_dtc.h) itself: its status bytes, event-memory
 * entries, freeze frames and counters.
 *
 * Constants of every 0x19 response:
 *   DTCStatusAvailabilityMask  0xFF (all eight ISO 14229-1 status bits)
 *   DTCFormatIdentifier        0x04, SAE_J2012-DA_DTCFormat_04: a 2-byte
 *                              SAE J2012 code plus a failure-type byte
 *                              (P0122 = 0x01 0x22 0x00; dbc/dtcs.csv)
 * Sub-functions (request after the sub-function byte -> response after
 * 0x59 and the sub-function):
 *   0x01 reportNumberOfDTCByStatusMask  mask -> availability, format id,
 *        count (2 bytes) of DTCs with status & mask != 0
 *   0x02 reportDTCByStatusMask  mask -> availability, then DTC (3) +
 *        status for each such DTC, in table order
 *   0x03 reportDTCSnapshotIdentification  - -> DTC (3) + record number 1
 *        for each DTC with a stored freeze frame
 *   0x04 reportDTCSnapshotRecordByDTCNumber  DTC (3), record (0x01 or
 *        0xFF all) -> DTC, status, and if a freeze frame is stored: record
 *        1, the number of identifiers (CANFDI_UDS_SNAPSHOT_DIDS, 8), then
 *        each DID (2) and its value in the DID's format (uptime in ms,
 *        speed, currents, voltages, angle Q16.16, degradation states)
 *   0x06 reportDTCExtDataRecordByDTCNumber  DTC (3), record (0x01
 *        occurrence counter, 0x02 aging counter, 0xFF all) -> DTC, status,
 *        and if the DTC has an event-memory entry: each record number
 *        followed by its one byte (CANFDI_UDS_EXT_DATA_BYTES)
 *   0x0A reportSupportedDTC  - -> availability, DTC + status of every DTC
 *   0x14 reportDTCFaultDetectionCounter  - -> DTC (3) + FDC (signed byte)
 *        of every DTC that is prefailed, FDC 1..126 (not yet qualified)
 * NRCs, in this order: 0x13 wrong length; 0x31 unknown DTC or record.
 *
 * ClearDiagnosticInformation: groupOfDTC (3) [+ memorySelection 0x00]:
 * 0xFFFFFF all, a DTC of the table, or a component group
 * (CANFDI_UDS_GROUP_DC_MOTOR 0xFFFF01, _THROTTLE 0xFFFF02, _COMM 0xFFFF03);
 * else NRC 0x31 (also a memorySelection other than 0); length other than
 * 4 or 5: 0x13. The memory counts the change (canfdi_dtc_t.changes), so
 * the port stores it to NVM like any other change.
 *
 * Cost: O(number of DTCs) per request (30 table reads), plus the response
 * bytes (at most 3 + 4 per DTC). No state of its own.
 */
#ifndef CANFDI_UDS_DTC_H
#define CANFDI_UDS_DTC_H

#include "catalogue/canfdi_uds_ids.h"
#include "core/canfdi_common.h"
#include "diag/canfdi_dtc.h"
#include "uds/canfdi_uds_msg.h"

#define CANFDI_UDS_DTC_FORMAT_ID 0x04U

/* The 0x19 sub-functions this server supports. */
bool canfdi_uds_dtc_subfn_supported(uint8_t subfn);

/* 0x14 on dtc: the NRC (0 positive, response 0x54 appended). */
uint8_t canfdi_uds_dtc_clear(canfdi_dtc_t *dtc, canfdi_uds_msg_t *m);

/* 0x19 (sub-function checked supported): the NRC (0 positive). */
uint8_t canfdi_uds_dtc_read(const canfdi_dtc_t *dtc, canfdi_uds_msg_t *m);

#endif /* CANFDI_UDS_DTC_H */
