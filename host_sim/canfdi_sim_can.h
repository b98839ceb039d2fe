/*
 * canfdi_sim_can.h — SocketCAN I/O of canfdi-sim (Linux only; host code,
 * not part of the plant library that SIL and the unit tests link).
 *
 * One raw CAN socket bound to a named interface (vcan0, can0, ...) with
 * kernel filters, so that only the frames the plant consumes ever reach the
 * process: DcmActuator 0x020, ThrActuator 0x021 (from the ECU), SetpointDcm
 * 0x100, SetpointThr 0x101 (external overrides; the sim's own setpoints are
 * not looped back to it: CAN_RAW_RECV_OWN_MSGS stays off), SimFaultInject
 * 0x600 and SimFaultClear 0x601 (from the tester). Classic CAN, standard
 * 11-bit identifiers, no error frames.
 *
 * Errors come back as -CANFDI_EIO with the errno in c->last_errno and a
 * one-line message naming the interface in c->err, e.g.
 *   "cannot open vcan0: No such device (no vcan? run under tools/vcan-run)".
 * A signal during a wait is not an error: canfdi_sim_can_recv returns 0 as
 * on a timeout, and the caller looks at its own stop flag.
 *
 * Cost: one syscall per frame sent, one or two (ppoll + read) per frame
 * received. Memory: sizeof(canfdi_sim_can_t) ~ 200 bytes; the socket is
 * the only resource (closed by canfdi_sim_can_close). No heap.
 */
#ifndef CANFDI_SIM_CAN_H
#define CANFDI_SIM_CAN_H

#include <stdint.h>

#include "canfdi_sim_frames.h"

/* Consecutive milliseconds a send may wait for room in the socket's queue
 * (ENOBUFS) before the frame is counted as lost. */
#define CANFDI_SIM_CAN_TX_RETRY_MS 20

typedef struct {
  uint32_t tx;            /* frames sent */
  uint32_t rx;            /* frames received */
  uint32_t tx_lost;       /* frames given up after CANFDI_SIM_CAN_TX_RETRY_MS of ENOBUFS */
  uint32_t rx_bad;        /* reads that were not one classic CAN frame (ignored) */
} canfdi_sim_can_diag_t;

typedef struct {
  int fd;                 /* -1 when closed */
  char ifname[32];
  int last_errno;
  char err[160];          /* message of the last error, "" if none */
  canfdi_sim_can_diag_t diag;
} canfdi_sim_can_t;

/* Opens a raw CAN socket on ifname with the plant's receive filters.
 * Returns CANFDI_OK, -CANFDI_EINVAL for a name that is empty or too long,
 * -CANFDI_EIO when the kernel refuses (c->err says why). */
int canfdi_sim_can_open(canfdi_sim_can_t *c, const char *ifname);

/* Sends one frame (dlc 0..8, standard id). Returns CANFDI_OK, or
 * -CANFDI_EIO (the frame is lost; c->err). ENOBUFS is retried for up to
 * CANFDI_SIM_CAN_TX_RETRY_MS. */
int canfdi_sim_can_send(canfdi_sim_can_t *c, const canfdi_sim_frame_t *f);

/* Waits up to timeout_us (0: only what is already queued) for one frame.
 * Returns 1 with *f filled, 0 on timeout or a signal, -CANFDI_EIO on a
 * socket error. */
int canfdi_sim_can_recv(canfdi_sim_can_t *c, canfdi_sim_frame_t *f, int64_t timeout_us);

/* Closes the socket (idempotent). */
void canfdi_sim_can_close(canfdi_sim_can_t *c);

#endif /* CANFDI_SIM_CAN_H */
