/*
 * canfdi_socketcan.h — the ECU's CAN driver on Linux: one raw SocketCAN
 * socket (PF_CAN, SOCK_RAW, CAN_RAW) bound to one interface.
 *
 * What the kernel does for us. Receive filters (CAN_RAW_FILTER) pass only
 * the standard (11-bit) data frames whose identifiers the ECU consumes, so
 * a flood of foreign traffic costs the ECU process nothing: it is dropped
 * in the kernel. Each filter is {can_id = id, can_mask = CAN_SFF_MASK |
 * CAN_EFF_FLAG | CAN_RTR_FLAG}: an extended frame or a remote request with
 * the same low bits does not pass. Error frames are off
 * (CAN_RAW_ERR_FILTER = 0); frames we send are not received back
 * (CAN_RAW_RECV_OWN_MSGS off, the default) but are looped back to the
 * other sockets on the host (CAN_RAW_LOOPBACK on, the default), which is
 * what a plant process and candump on the same vcan need. SO_RXQ_OVFL
 * reports frames the kernel dropped because our receive queue was full
 * (diag.rx_kernel_drops). Classic CAN only (no CAN_RAW_FD_FRAMES).
 *
 * What is passed up. Every frame the filters let through, with its
 * identifier as the kernel gives it (flags included) and its length as
 * sent (0..8): judging a wrong length is the input supervision's job, not
 * the driver's.
 *
 * Sending. write() of one struct can_frame. A full device queue
 * (ENOBUFS; vcan and real controllers return it when the qdisc is full)
 * is retried after short sleeps up to tx_budget_us in total, then the frame
 * is dropped and counted (diag.tx_drops): the 1 ms loop never blocks for
 * long. Other errors (ENETDOWN: the interface is down; ENXIO/ENODEV: it
 * disappeared) are counted and returned at once; the caller decides when
 * they become fatal (canfdi-ecu: errors other than ENETDOWN with no
 * successful I/O for 5 s; a down interface keeps the socket bound and
 * works again when it is up).
 *
 * Cost: one system call per received or sent frame (recvmsg / write), plus
 * the retries above. Memory: the instance (~80 bytes); no heap.
 * Not thread-safe. Linux only (this is firmware/port/linux).
 * Build: needs _DEFAULT_SOURCE (mk/ecu.mk sets it).
 */
#ifndef CANFDI_SOCKETCAN_H
#define CANFDI_SOCKETCAN_H

#include <stdbool.h>
#include <stdint.h>

#define CANFDI_SOCKETCAN_MAX_FILTERS 16U

/* Default retry budget of a send that meets ENOBUFS, microseconds. */
#define CANFDI_SOCKETCAN_TX_BUDGET_US 200U

/* Monotone counters. */
typedef struct {
  uint32_t rx_frames;       /* frames received and passed up */
  uint32_t rx_bad;          /* reads that were not one classic CAN frame */
  uint32_t rx_errors;       /* recvmsg failures other than "nothing there" */
  uint32_t rx_kernel_drops; /* frames the kernel dropped (full rx queue), SO_RXQ_OVFL */
  uint32_t tx_frames;       /* frames sent */
  uint32_t tx_retries;      /* ENOBUFS retries */
  uint32_t tx_drops;        /* frames given up after tx_budget_us of ENOBUFS */
  uint32_t tx_errors;       /* write failures other than ENOBUFS */
} canfdi_socketcan_diag_t;

typedef struct {
  int fd;                  /* -1 when closed */
  int last_errno;          /* errno of the last failing call, 0 if none */
  uint32_t tx_budget_us;   /* see above; settable after open */
  uint32_t kernel_drops_seen; /* last SO_RXQ_OVFL value (the kernel's counter) */
  canfdi_socketcan_diag_t diag;
} canfdi_socketcan_t;

/* One received frame. */
typedef struct {
  uint32_t id;     /* can_id as received, flags included */
  uint8_t dlc;     /* 0..8 */
  uint8_t data[8]; /* bytes beyond dlc are 0 */
} canfdi_socketcan_frame_t;

/*
 * Open a raw CAN socket on interface `ifname`, set the receive filters to
 * ids[0..n_ids) (11-bit ids; n_ids <= CANFDI_SOCKETCAN_MAX_FILTERS; 0 ids
 * receives nothing), error frames off, and bind. Returns 0, or -errno of
 * the failing call (EAFNOSUPPORT: the kernel has no SocketCAN; ENODEV: no
 * such interface; EINVAL: bad arguments). On failure s->fd is -1.
 */
int canfdi_socketcan_open(canfdi_socketcan_t *s, const char *ifname, const uint32_t *ids,
                          uint32_t n_ids);

void canfdi_socketcan_close(canfdi_socketcan_t *s);

/*
 * Non-blocking read of one frame into *f. Returns 1 (a frame), 0 (none
 * waiting), or -errno (counted in rx_errors; e.g. -ENETDOWN once when the
 * interface went down).
 */
int canfdi_socketcan_recv(canfdi_socketcan_t *s, canfdi_socketcan_frame_t *f);

/*
 * Send one classic frame (dlc 0..8; id with CAN_EFF_FLAG for an extended
 * one). Returns 0, -ENOBUFS (dropped after the retry budget), or another
 * -errno. Cost: one write; on ENOBUFS up to tx_budget_us of sleeps.
 */
int canfdi_socketcan_send(canfdi_socketcan_t *s, uint32_t id, const uint8_t *data, uint8_t dlc);

#endif /* CANFDI_SOCKETCAN_H */
