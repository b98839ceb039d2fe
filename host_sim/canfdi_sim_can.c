/* canfdi_sim_can.c — SocketCAN I/O of canfdi-sim; see canfdi_sim_can.h.
 * ppoll and the socket API need _GNU_SOURCE; the pre-included assert.h
 * fixes the feature macros first, so host_sim.mk passes it for this file. */
#ifndef _GNU_SOURCE
#define _GNU_SOURCE
#endif

#include "canfdi_sim_can.h"

#include <errno.h>
#include <linux/can.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <poll.h>
#include <stdio.h>
#include <string.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

#include "core/canfdi_common.h"

static const canid_t rx_ids[] = {0x020U, 0x021U, 0x100U, 0x101U, 0x600U, 0x601U};

static int fail(canfdi_sim_can_t *c, const char *what)
{
  const int e = errno;
  const char *hint = "";
  c->last_errno = e;
  if ((e == ENODEV) || (e == ENXIO)) {
    hint = " (no vcan? run under tools/vcan-run)";
  } else if ((e == EAFNOSUPPORT) || (e == EPROTONOSUPPORT)) {
    hint = " (no SocketCAN in this kernel? run under tools/vcan-run)";
  } else if (e == ENETDOWN) {
    hint = " (interface down? ip link set up it)";
  } else {
    /* no hint */
  }
  (void)snprintf(c->err, sizeof c->err, "%s %s: %s%s", what, c->ifname, strerror(e), hint);
  return -CANFDI_EIO;
}

int canfdi_sim_can_open(canfdi_sim_can_t *c, const char *ifname)
{
  int rc = CANFDI_OK;
  struct sockaddr_can addr;
  struct can_filter flt[sizeof rx_ids / sizeof rx_ids[0]];
  const int off = 0;
  size_t i;
  memset(c, 0, sizeof *c);
  c->fd = -1;
  if ((ifname == NULL) || (ifname[0] == '\0') || (strlen(ifname) >= IFNAMSIZ)) {
    (void)snprintf(c->err, sizeof c->err, "invalid interface name '%s'",
                   (ifname != NULL) ? ifname : "");
    return -CANFDI_EINVAL;
  }
  (void)snprintf(c->ifname, sizeof c->ifname, "%s", ifname);
  memset(&addr, 0, sizeof addr);
  c->fd = socket(PF_CAN, SOCK_RAW | SOCK_CLOEXEC, CAN_RAW);
  if (c->fd < 0) {
    rc = fail(c, "cannot open");
  }
  if (rc == CANFDI_OK) {
    const unsigned idx = if_nametoindex(ifname);
    if (idx == 0U) {
      rc = fail(c, "cannot open");
    }
    addr.can_family = AF_CAN;
    addr.can_ifindex = (int)idx;
  }
  if (rc == CANFDI_OK) {
    for (i = 0U; i < (sizeof rx_ids / sizeof rx_ids[0]); i++) {
      flt[i].can_id = rx_ids[i];
      flt[i].can_mask = CAN_SFF_MASK | CAN_EFF_FLAG | CAN_RTR_FLAG;
    }
    if ((setsockopt(c->fd, SOL_CAN_RAW, CAN_RAW_FILTER, flt, (socklen_t)sizeof flt) != 0) ||
        (setsockopt(c->fd, SOL_CAN_RAW, CAN_RAW_RECV_OWN_MSGS, &off, (socklen_t)sizeof off) != 0)) {
      rc = fail(c, "cannot set the receive filters on");
    }
  }
  if ((rc == CANFDI_OK) && (bind(c->fd, (struct sockaddr *)&addr, (socklen_t)sizeof addr) != 0)) {
    rc = fail(c, "cannot bind to");
  }
  if ((rc != CANFDI_OK) && (c->fd >= 0)) {
    (void)close(c->fd);
    c->fd = -1;
  }
  return rc;
}

int canfdi_sim_can_send(canfdi_sim_can_t *c, const canfdi_sim_frame_t *f)
{
  struct can_frame fr;
  int rc = CANFDI_OK;
  int waited_ms = 0;
  memset(&fr, 0, sizeof fr);
  fr.can_id = f->id & CAN_SFF_MASK;
  fr.can_dlc = (f->dlc <= 8U) ? f->dlc : 8U;
  memcpy(fr.data, f->data, 8U);
  for (;;) {
    const ssize_t n = write(c->fd, &fr, sizeof fr);
    if (n == (ssize_t)sizeof fr) {
      c->diag.tx++;
      break;
    }
    if ((n < 0) && (errno == EINTR)) {
      continue;
    }
    if ((n < 0) && (errno == ENOBUFS) && (waited_ms < CANFDI_SIM_CAN_TX_RETRY_MS)) {
      /* the interface's queue is full: wait for room, briefly */
      struct pollfd p = {c->fd, POLLOUT, 0};
      (void)poll(&p, 1U, 1);
      waited_ms++;
      continue;
    }
    c->diag.tx_lost++;
    rc = fail(c, "cannot send on");
    break;
  }
  return rc;
}

int canfdi_sim_can_recv(canfdi_sim_can_t *c, canfdi_sim_frame_t *f, int64_t timeout_us)
{
  struct pollfd p = {c->fd, POLLIN, 0};
  struct timespec ts;
  int rc = 0;
  int pr;
  if (timeout_us < 0) {
    timeout_us = 0;
  }
  ts.tv_sec = (time_t)(timeout_us / 1000000);
  ts.tv_nsec = (long)((timeout_us % 1000000) * 1000);
  pr = ppoll(&p, 1U, &ts, NULL);
  if (pr < 0) {
    rc = (errno == EINTR) ? 0 : fail(c, "cannot receive on");
  } else if ((pr > 0) && ((p.revents & POLLIN) != 0)) {
    struct can_frame fr;
    const ssize_t n = read(c->fd, &fr, sizeof fr);
    if (n == (ssize_t)sizeof fr) {
      if (((fr.can_id & (CAN_EFF_FLAG | CAN_RTR_FLAG | CAN_ERR_FLAG)) == 0U) && (fr.can_dlc <= 8U)) {
        memset(f, 0, sizeof *f);
        f->id = fr.can_id & CAN_SFF_MASK;
        f->dlc = fr.can_dlc;
        memcpy(f->data, fr.data, fr.can_dlc);
        c->diag.rx++;
        rc = 1;
      } else {
        c->diag.rx_bad++;
      }
    } else if ((n < 0) && ((errno == EINTR) || (errno == EAGAIN))) {
      rc = 0;
    } else if (n < 0) {
      rc = fail(c, "cannot receive on");
    } else {
      c->diag.rx_bad++;
    }
  } else if (pr > 0) {
    errno = EIO;
    rc = fail(c, "error on");
  } else {
    /* timeout */
  }
  return rc;
}

void canfdi_sim_can_close(canfdi_sim_can_t *c)
{
  if ((c != NULL) && (c->fd >= 0)) {
    (void)close(c->fd);
    c->fd = -1;
  }
}
