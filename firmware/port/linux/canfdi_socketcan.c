/*
 * canfdi_socketcan.c — raw SocketCAN socket of the ECU; see
 * canfdi_socketcan.h (the manual).
 */
#include "port/linux/canfdi_socketcan.h"

#include "core/canfdi_count.h"

#include <errno.h>
#include <linux/can.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <string.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

#ifndef SO_RXQ_OVFL
#define SO_RXQ_OVFL 40
#endif

int canfdi_socketcan_open(canfdi_socketcan_t *s, const char *ifname, const uint32_t *ids,
                          uint32_t n_ids)
{
  struct can_filter flt[CANFDI_SOCKETCAN_MAX_FILTERS];
  struct sockaddr_can addr;
  const can_err_mask_t err_mask = 0U;
  const int one = 1;
  const int rcvbuf = 1 << 20; /* ~ several thousand frames of slack */
  unsigned ifindex;
  int fd;
  int rc = 0;

  if ((s == NULL) || (ifname == NULL) || (n_ids > CANFDI_SOCKETCAN_MAX_FILTERS) ||
      ((ids == NULL) && (n_ids > 0U)) || (strlen(ifname) >= (size_t)IFNAMSIZ)) {
    return -EINVAL;
  }
  memset(s, 0, sizeof *s);
  s->fd = -1;
  s->tx_budget_us = CANFDI_SOCKETCAN_TX_BUDGET_US;

  fd = socket(PF_CAN, SOCK_RAW, CAN_RAW);
  if (fd < 0) {
    rc = -errno;
  } else {
    ifindex = if_nametoindex(ifname);
    if (ifindex == 0U) {
      rc = -errno;
    }
    if (rc == 0) {
      for (uint32_t i = 0U; i < n_ids; i++) {
        flt[i].can_id = ids[i] & CAN_SFF_MASK;
        flt[i].can_mask = CAN_SFF_MASK | CAN_EFF_FLAG | CAN_RTR_FLAG;
      }
      /* n_ids == 0: an empty filter list receives nothing */
      if (setsockopt(fd, SOL_CAN_RAW, CAN_RAW_FILTER, (n_ids > 0U) ? flt : NULL,
                     (socklen_t)(n_ids * sizeof flt[0])) != 0) {
        rc = -errno;
      }
    }
    if ((rc == 0) &&
        (setsockopt(fd, SOL_CAN_RAW, CAN_RAW_ERR_FILTER, &err_mask, sizeof err_mask) != 0)) {
      rc = -errno;
    }
    if (rc == 0) {
      /* best effort: a larger receive queue and the kernel's drop counter */
      (void)setsockopt(fd, SOL_SOCKET, SO_RCVBUF, &rcvbuf, sizeof rcvbuf);
      (void)setsockopt(fd, SOL_SOCKET, SO_RXQ_OVFL, &one, sizeof one);
      memset(&addr, 0, sizeof addr);
      addr.can_family = AF_CAN;
      addr.can_ifindex = (int)ifindex;
      if (bind(fd, (struct sockaddr *)&addr, sizeof addr) != 0) {
        rc = -errno;
      }
    }
    if (rc != 0) {
      (void)close(fd);
    } else {
      s->fd = fd;
    }
  }
  if (rc != 0) {
    s->last_errno = -rc;
  }
  return rc;
}

void canfdi_socketcan_close(canfdi_socketcan_t *s)
{
  if ((s != NULL) && (s->fd >= 0)) {
    (void)close(s->fd);
    s->fd = -1;
  }
}

/* The SO_RXQ_OVFL counter of one received message, if present. */
static void take_overflow(canfdi_socketcan_t *s, struct msghdr *msg)
{
  struct cmsghdr *c;
  for (c = CMSG_FIRSTHDR(msg); c != NULL; c = CMSG_NXTHDR(msg, c)) {
    if ((c->cmsg_level == SOL_SOCKET) && (c->cmsg_type == SO_RXQ_OVFL) &&
        (c->cmsg_len >= (size_t)CMSG_LEN(sizeof(uint32_t)))) {
      uint32_t drops;
      memcpy(&drops, CMSG_DATA(c), sizeof drops);
      if (drops != s->kernel_drops_seen) {
        const uint32_t d = drops - s->kernel_drops_seen; /* the kernel's counter wraps */
        s->diag.rx_kernel_drops = (s->diag.rx_kernel_drops > (UINT32_MAX - d))
                                      ? UINT32_MAX
                                      : (s->diag.rx_kernel_drops + d);
        s->kernel_drops_seen = drops;
      }
    }
  }
}

int canfdi_socketcan_recv(canfdi_socketcan_t *s, canfdi_socketcan_frame_t *f)
{
  struct can_frame cf;
  struct iovec iov;
  struct msghdr msg;
  union {
    char buf[CMSG_SPACE(sizeof(uint32_t))];
    struct cmsghdr align;
  } ctl;
  ssize_t n;
  int rc;

  if ((s == NULL) || (s->fd < 0) || (f == NULL)) {
    return -EINVAL;
  }
  iov.iov_base = &cf;
  iov.iov_len = sizeof cf;
  memset(&msg, 0, sizeof msg);
  msg.msg_iov = &iov;
  msg.msg_iovlen = 1U;
  msg.msg_control = ctl.buf;
  msg.msg_controllen = sizeof ctl.buf;
  n = recvmsg(s->fd, &msg, MSG_DONTWAIT);
  if (n < 0) {
    if ((errno == EAGAIN) || (errno == EWOULDBLOCK) || (errno == EINTR)) {
      rc = 0;
    } else {
      s->last_errno = errno;
      canfdi_count_inc(&s->diag.rx_errors);
      rc = -errno;
    }
  } else if (((size_t)n != sizeof cf) || (cf.can_dlc > 8U)) {
    canfdi_count_inc(&s->diag.rx_bad); /* not a classic frame: cannot happen without FD frames */
    rc = 0;
  } else {
    take_overflow(s, &msg);
    f->id = cf.can_id;
    f->dlc = cf.can_dlc;
    memset(f->data, 0, sizeof f->data);
    memcpy(f->data, cf.data, cf.can_dlc);
    canfdi_count_inc(&s->diag.rx_frames);
    rc = 1;
  }
  return rc;
}

int canfdi_socketcan_send(canfdi_socketcan_t *s, uint32_t id, const uint8_t *data, uint8_t dlc)
{
  struct can_frame cf;
  uint32_t waited_us = 0U;
  uint32_t pause_us = 20U;
  int rc = 1;

  if ((s == NULL) || (s->fd < 0) || (dlc > 8U) || ((data == NULL) && (dlc > 0U))) {
    return -EINVAL;
  }
  memset(&cf, 0, sizeof cf);
  cf.can_id = id;
  cf.can_dlc = dlc;
  if (dlc > 0U) {
    memcpy(cf.data, data, dlc);
  }
  while (rc > 0) {
    const ssize_t n = write(s->fd, &cf, sizeof cf);
    if (n == (ssize_t)sizeof cf) {
      canfdi_count_inc(&s->diag.tx_frames);
      rc = 0;
    } else if ((n < 0) && (errno == EINTR)) {
      /* a signal: try again at once */
    } else if ((n < 0) && ((errno == ENOBUFS) || (errno == EAGAIN)) &&
               (waited_us < s->tx_budget_us)) {
      /* the device queue is full: give it a moment to drain */
      const struct timespec ts = {0, (long)pause_us * 1000L};
      (void)nanosleep(&ts, NULL);
      waited_us += pause_us;
      pause_us = (pause_us < 400U) ? (pause_us * 2U) : pause_us;
      canfdi_count_inc(&s->diag.tx_retries);
    } else if ((n < 0) && ((errno == ENOBUFS) || (errno == EAGAIN))) {
      s->last_errno = ENOBUFS;
      canfdi_count_inc(&s->diag.tx_drops);
      rc = -ENOBUFS;
    } else {
      s->last_errno = (n < 0) ? errno : EIO;
      canfdi_count_inc(&s->diag.tx_errors);
      rc = -s->last_errno;
    }
  }
  return rc;
}
