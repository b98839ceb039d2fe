/*
 * canfdi_sim_uds.h — the scenario's diagnostic tester for the SIL rig: an
 * ISO 15765-2 client that sends the `uds` lines of a scenario
 * (canfdi_sim_scenario.h) to the ECU and judges the responses against
 * their patterns, so the SIL rig tests the ECU's diagnostic server without
 * a bus.
 *
 * Timing: a request leaves at the first step at or after its time, or
 * when the previous request has its response (one request at a time, as a
 * tester does). Segmentation: single frame up to 7 bytes, else a first
 * frame, then consecutive frames after the ECU's flow control (its block
 * size and STmin honoured, one frame per 1 ms step). A segmented response
 * gets the flow control continue-to-send with BS 0, STmin 0. Every frame
 * is 8 bytes, padded with 0xCC. Verdicts: `expect <pattern>` passes when
 * the complete response matches (".." any byte, a final "*" any rest);
 * `expect none` passes when nothing comes within CANFDI_SIM_UDS_NONE_MS;
 * a response that does not come within CANFDI_SIM_UDS_TIMEOUT_MS (P2*)
 * fails, as does an ECU flow control other than continue-to-send.
 *
 * The frames' bytes are the ISO-TP bytes; the caller packs and unpacks
 * them with the DBC codec (UdsPhysReq/UdsFuncReq, UdsPhysResp).
 * Cost O(1) per step; memory: sizeof(canfdi_sim_uds_tester_t) ~ 6 kB (a
 * verdict message per request). No heap.
 */
#ifndef CANFDI_SIM_UDS_H
#define CANFDI_SIM_UDS_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "canfdi_sim_scenario.h"

#define CANFDI_SIM_UDS_TIMEOUT_MS 5000
#define CANFDI_SIM_UDS_NONE_MS 200
#define CANFDI_SIM_UDS_RESP_MAX 512U

typedef struct {
  bool done;
  bool ok;
  char msg[160];
} canfdi_sim_uds_verdict_t;

typedef struct {
  const canfdi_sim_uds_t *list;
  size_t n;
  size_t next;        /* next request to send */
  size_t cur;         /* the request in flight */
  int state;          /* internal */
  int64_t deadline_us;
  uint32_t pos;       /* request bytes sent */
  uint8_t sn;         /* next sequence number sent / expected */
  uint8_t gap;        /* steps until the next CF may leave */
  uint8_t stmin;      /* the ECU's STmin in steps */
  uint8_t block;      /* CFs left in the ECU's block (0: unlimited) */
  bool block_limited;
  uint8_t resp[CANFDI_SIM_UDS_RESP_MAX];
  uint32_t resp_len;
  uint32_t resp_got;
  canfdi_sim_uds_verdict_t verdict[CANFDI_SIM_SCN_MAX_UDS];
} canfdi_sim_uds_tester_t;

void canfdi_sim_uds_tester_init(canfdi_sim_uds_tester_t *t, const canfdi_sim_uds_t *list, size_t n);

/* Step at t_us, before the ECU's: at most one frame for the ECU. Returns
 * true with pdu (its 8 ISO-TP bytes) and *functional set when one leaves. */
bool canfdi_sim_uds_tester_tx(canfdi_sim_uds_tester_t *t, int64_t t_us, bool *functional, uint8_t pdu[8]);

/* One UdsPhysResp frame of the ECU (its 8 ISO-TP bytes, unpacked by the
 * codec), received at t_us. */
void canfdi_sim_uds_tester_rx(canfdi_sim_uds_tester_t *t, int64_t t_us, const uint8_t pdu[8]);

/* The end of the run: a request still open fails. */
void canfdi_sim_uds_tester_finish(canfdi_sim_uds_tester_t *t);

#endif /* CANFDI_SIM_UDS_H */
