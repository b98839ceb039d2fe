/*
 * canfdi_isotp.c — ISO 15765-2 transport of the diagnostic server; the
 * manual is the header.
 */
#include "comm/canfdi_isotp.h"

#include "comm/gen/canfdi_msg.h"
#include "core/canfdi_count.h"

/* The DBC's UDS frames carry exactly one connection frame each. */
CANFDI_STATIC_ASSERT(CANFDI_CFG_ISOTP_FRAME_BYTES == CANFDI_MSG_UDS_PHYS_REQ_LENGTH, isotp_dl_is_dbc_dl);
CANFDI_STATIC_ASSERT(CANFDI_CFG_ISOTP_FRAME_BYTES == CANFDI_MSG_UDS_FUNC_REQ_LENGTH, isotp_dl_is_dbc_dl_func);
CANFDI_STATIC_ASSERT(CANFDI_CFG_ISOTP_FRAME_BYTES == CANFDI_MSG_UDS_PHYS_RESP_LENGTH, isotp_dl_is_dbc_dl_resp);
/* A request must hold more than a single frame; lengths fit 32 bits. */
CANFDI_STATIC_ASSERT(CANFDI_CFG_ISOTP_RX_BYTES > CANFDI_ISOTP_SF_MAX, isotp_rx_buffer_size);
CANFDI_STATIC_ASSERT(CANFDI_CFG_ISOTP_TX_BYTES > CANFDI_ISOTP_SF_MAX, isotp_tx_buffer_size);
CANFDI_STATIC_ASSERT((CANFDI_CFG_ISOTP_SF_QUEUE >= 1U) && (CANFDI_CFG_ISOTP_SF_QUEUE <= 255U), isotp_sf_queue_size);

#define DL CANFDI_CFG_ISOTP_FRAME_BYTES
#define PCI_SF 0U
#define PCI_FF 1U
#define PCI_CF 2U
#define PCI_FC 3U
#define FS_CTS 0U
#define FS_WAIT 1U
#define FS_OVFLW 2U
/* ISO 15765-2: a reserved STmin counts as the largest, 127 ms. */
#define STMIN_RESERVED_MS 127U

void canfdi_isotp_default_cfg(canfdi_isotp_cfg_t *cfg)
{
  if (cfg != NULL) {
    cfg->n_bs_ms = 1000U;
    cfg->n_cr_ms = 1000U;
    cfg->bs = 0U;
    cfg->stmin = 0U;
    cfg->wft_max = 10U;
  }
}

static bool stmin_valid(uint8_t s)
{
  return (s <= 0x7FU) || ((s >= 0xF1U) && (s <= 0xF9U));
}

/* The tester's STmin in whole 1 ms steps (sub-ms values: the next step). */
static uint8_t stmin_steps(uint8_t s)
{
  uint8_t ms = (uint8_t)STMIN_RESERVED_MS;
  if (s <= 0x7FU) {
    ms = s;
  } else if ((s >= 0xF1U) && (s <= 0xF9U)) {
    ms = 0U;
  } else {
    /* reserved: the largest */
  }
  return ms;
}

static void rx_idle(canfdi_isotp_t *t)
{
  t->rx_state = (uint8_t)CANFDI_ISOTP_RX_IDLE;
  t->rx_len = 0U;
  t->rx_got = 0U;
  t->rx_timer_ms = 0U;
  t->rx_sn = 0U;
  t->rx_block = 0U;
  /* a reception that ended (new SF/FF, wrong SN, bad length, timeout) gets
   * no flow control still pending for it: no stray CTS to the tester */
  t->fc_pending = 0U;
}

static void tx_idle(canfdi_isotp_t *t)
{
  t->tx_state = (uint8_t)CANFDI_ISOTP_TX_IDLE;
  t->tx_len = 0U;
  t->tx_pos = 0U;
  t->tx_timer_ms = 0U;
  t->tx_sn = 0U;
  t->tx_block = 0U;
  t->tx_gap = 0U;
  t->tx_stmin_ms = 0U;
  t->tx_wft = 0U;
}

void canfdi_isotp_reset(canfdi_isotp_t *t)
{
  if (t != NULL) {
    rx_idle(t);
    tx_idle(t);
    t->fc_pending = 0U;
    t->sfq_head = 0U;
    t->sfq_len = 0U;
    t->peeked = 0U;
  }
}

int32_t canfdi_isotp_init(canfdi_isotp_t *t, const canfdi_isotp_cfg_t *cfg)
{
  int32_t rc = -CANFDI_EINVAL;
  if ((t != NULL) && (cfg != NULL) && (cfg->n_bs_ms >= 1U) && (cfg->n_cr_ms >= 1U) &&
      (cfg->n_bs_ms <= 60000U) && (cfg->n_cr_ms <= 60000U) && stmin_valid(cfg->stmin)) {
    t->cfg = *cfg;
    t->diag = (canfdi_isotp_diag_t){0};
    canfdi_isotp_reset(t);
    t->initialised = true;
    rc = CANFDI_OK;
  }
  return rc;
}

static bool usable(const canfdi_isotp_t *t) { return (t != NULL) && t->initialised; }

/* The frame's bytes through the generated codec (byte 0 first). */
static bool unpack(bool functional, const uint8_t *data, uint8_t dlc, uint8_t out[DL])
{
  uint64_t v = 0U;
  bool ok;
  if (functional) {
    struct canfdi_msg_uds_func_req_t m;
    ok = canfdi_msg_uds_func_req_unpack(&m, data, dlc) == 0;
    v = m.uds_func_req_data;
  } else {
    struct canfdi_msg_uds_phys_req_t m;
    ok = canfdi_msg_uds_phys_req_unpack(&m, data, dlc) == 0;
    v = m.uds_phys_req_data;
  }
  for (uint32_t i = 0U; i < DL; i++) {
    out[i] = (uint8_t)((v >> (8U * (DL - 1U - i))) & 0xFFU);
  }
  return ok;
}

/* SF: its length and the offset of its data; false if out of range. */
static bool sf_length(const uint8_t f[DL], uint32_t *len, uint32_t *off)
{
  bool ok;
  *len = (uint32_t)(f[0] & 0x0FU);
  *off = 1U;
  if ((*len == 0U) && (DL > 8U)) {
    /* CAN FD escape: the length in byte 1 */
    *len = f[1];
    *off = 2U;
    ok = (*len >= 8U) && (*len <= (DL - 2U));
  } else {
    ok = (*len >= 1U) && (*len <= (DL - 1U)) && (*len <= 7U);
  }
  return ok;
}

/* FF: its length and the offset of its data; false if out of range. */
static bool ff_length(const uint8_t f[DL], uint32_t *len, uint32_t *off)
{
  bool ok;
  *len = ((uint32_t)(f[0] & 0x0FU) << 8) | (uint32_t)f[1];
  *off = 2U;
  if (*len == 0U) {
    /* escape: 32-bit length */
    *len = ((uint32_t)f[2] << 24) | ((uint32_t)f[3] << 16) | ((uint32_t)f[4] << 8) | (uint32_t)f[5];
    *off = 6U;
    ok = *len > 4095U;
  } else {
    ok = *len >= DL;
  }
  return ok;
}

static void copy_in(uint8_t *dst, const uint8_t *src, uint32_t n)
{
  for (uint32_t i = 0U; i < n; i++) {
    dst[i] = src[i];
  }
}

static void rx_first(canfdi_isotp_t *t, const uint8_t f[DL])
{
  uint32_t len;
  uint32_t off;
  if (!ff_length(f, &len, &off)) {
    canfdi_count_inc(&t->diag.bad_length);
    rx_idle(t);
  } else if (len > CANFDI_CFG_ISOTP_RX_BYTES) {
    canfdi_count_inc(&t->diag.rx_overflow);
    rx_idle(t);
    t->fc_pending = (uint8_t)((PCI_FC << 4) | FS_OVFLW);
  } else {
    copy_in(t->rx_buf, &f[off], DL - off);
    t->rx_len = len;
    t->rx_got = DL - off;
    t->rx_sn = 1U;
    t->rx_block = t->cfg.bs;
    t->rx_timer_ms = 0U;
    t->rx_state = (uint8_t)CANFDI_ISOTP_RX_RECEIVING;
    t->fc_pending = (uint8_t)((PCI_FC << 4) | FS_CTS);
  }
}

static void rx_consecutive(canfdi_isotp_t *t, const uint8_t f[DL])
{
  if (t->rx_state != (uint8_t)CANFDI_ISOTP_RX_RECEIVING) {
    canfdi_count_inc(&t->diag.unexpected);
  } else if ((f[0] & 0x0FU) != t->rx_sn) {
    canfdi_count_inc(&t->diag.wrong_sn);
    rx_idle(t);
  } else {
    const uint32_t left = t->rx_len - t->rx_got;
    const uint32_t n = (left < (DL - 1U)) ? left : (DL - 1U);
    copy_in(&t->rx_buf[t->rx_got], &f[1], n);
    t->rx_got += n;
    t->rx_sn = (uint8_t)((t->rx_sn + 1U) & 0x0FU);
    t->rx_timer_ms = 0U;
    if (t->rx_got >= t->rx_len) {
      t->rx_state = (uint8_t)CANFDI_ISOTP_RX_DONE;
      canfdi_count_inc(&t->diag.rx_messages);
    } else if (t->cfg.bs != 0U) {
      t->rx_block--;
      if (t->rx_block == 0U) {
        t->rx_block = t->cfg.bs;
        t->fc_pending = (uint8_t)((PCI_FC << 4) | FS_CTS);
      }
    } else {
      /* no further FC */
    }
  }
}

static void tx_flow_control(canfdi_isotp_t *t, const uint8_t f[DL])
{
  const uint8_t fs = (uint8_t)(f[0] & 0x0FU);
  if (t->tx_state != (uint8_t)CANFDI_ISOTP_TX_WAIT_FC) {
    canfdi_count_inc(&t->diag.unexpected);
  } else if (fs == FS_CTS) {
    t->tx_block = f[1];
    t->tx_stmin_ms = stmin_steps(f[2]);
    t->tx_gap = 1U;
    t->tx_wft = 0U;
    t->tx_state = (uint8_t)CANFDI_ISOTP_TX_CF;
  } else if (fs == FS_WAIT) {
    t->tx_wft++;
    t->tx_timer_ms = 0U;
    if (t->tx_wft > t->cfg.wft_max) {
      canfdi_count_inc(&t->diag.wft_exceeded);
      tx_idle(t);
    }
  } else {
    canfdi_count_inc(&t->diag.tx_aborted);
    tx_idle(t);
  }
}

/* A complete single frame into the queue (or dropped when it is full). */
static void rx_single(canfdi_isotp_t *t, const uint8_t f[DL], bool functional)
{
  uint32_t len;
  uint32_t off;
  if (!sf_length(f, &len, &off)) {
    canfdi_count_inc(&t->diag.bad_length);
  } else if (t->sfq_len >= CANFDI_CFG_ISOTP_SF_QUEUE) {
    canfdi_count_inc(&t->diag.busy_dropped);
  } else {
    const uint32_t k = (t->sfq_head + t->sfq_len) % CANFDI_CFG_ISOTP_SF_QUEUE;
    copy_in(t->sfq[k].data, &f[off], len);
    t->sfq[k].len = (uint8_t)len;
    t->sfq[k].functional = functional;
    t->sfq_len++;
    canfdi_count_inc(&t->diag.rx_messages);
  }
}

/* A new request (SF or FF) on the physical address. */
static void rx_physical_start(canfdi_isotp_t *t, const uint8_t f[DL], uint8_t type)
{
  if (t->rx_state == (uint8_t)CANFDI_ISOTP_RX_RECEIVING) {
    /* ISO 15765-2: a new SF/FF ends the reception in progress */
    canfdi_count_inc(&t->diag.rx_restarted);
    rx_idle(t);
  }
  if (type == PCI_SF) {
    rx_single(t, f, false);
  } else if ((t->tx_state != (uint8_t)CANFDI_ISOTP_TX_IDLE) || (t->rx_state == (uint8_t)CANFDI_ISOTP_RX_DONE)) {
    canfdi_count_inc(&t->diag.busy_dropped);
  } else {
    rx_first(t, f);
  }
}

static void rx_functional(canfdi_isotp_t *t, const uint8_t f[DL], uint8_t type)
{
  if (type != PCI_SF) {
    canfdi_count_inc(&t->diag.func_ignored);
  } else {
    rx_single(t, f, true);
  }
}

int32_t canfdi_isotp_rx_can(canfdi_isotp_t *t, bool functional, const uint8_t *data, uint8_t dlc)
{
  int32_t rc = -CANFDI_EINVAL;
  if (usable(t) && (data != NULL)) {
    uint8_t f[DL];
    rc = CANFDI_OK;
    if ((dlc < DL) || !unpack(functional, data, dlc, f)) {
      canfdi_count_inc(&t->diag.short_frames);
    } else {
      const uint8_t type = (uint8_t)(f[0] >> 4);
      canfdi_count_inc(&t->diag.rx_frames);
      if (functional) {
        rx_functional(t, f, type);
      } else if ((type == PCI_SF) || (type == PCI_FF)) {
        rx_physical_start(t, f, type);
      } else if (type == PCI_CF) {
        rx_consecutive(t, f);
      } else if (type == PCI_FC) {
        tx_flow_control(t, f);
      } else {
        canfdi_count_inc(&t->diag.unexpected);
      }
    }
  }
  return rc;
}

uint32_t canfdi_isotp_rx_peek(canfdi_isotp_t *t, const uint8_t **msg, bool *functional)
{
  uint32_t len = 0U;
  if (usable(t) && (msg != NULL) && (functional != NULL)) {
    t->peeked = 0U;
    if (t->rx_state == (uint8_t)CANFDI_ISOTP_RX_DONE) {
      *msg = t->rx_buf;
      *functional = false;
      len = t->rx_len;
      t->peeked = 1U;
    } else if (t->sfq_len != 0U) {
      *msg = t->sfq[t->sfq_head].data;
      *functional = t->sfq[t->sfq_head].functional;
      len = t->sfq[t->sfq_head].len;
      t->peeked = 2U;
    } else {
      /* nothing waits */
    }
  }
  return len;
}

void canfdi_isotp_rx_release(canfdi_isotp_t *t)
{
  if (usable(t)) {
    if ((t->peeked == 1U) && (t->rx_state == (uint8_t)CANFDI_ISOTP_RX_DONE)) {
      rx_idle(t);
    } else if ((t->peeked == 2U) && (t->sfq_len != 0U)) {
      t->sfq_head = (uint8_t)((t->sfq_head + 1U) % CANFDI_CFG_ISOTP_SF_QUEUE);
      t->sfq_len--;
    } else {
      /* nothing peeked */
    }
    t->peeked = 0U;
  }
}

bool canfdi_isotp_tx_busy(const canfdi_isotp_t *t)
{
  return usable(t) && (t->tx_state != (uint8_t)CANFDI_ISOTP_TX_IDLE);
}

uint8_t *canfdi_isotp_tx_buf(canfdi_isotp_t *t)
{
  return (usable(t) && !canfdi_isotp_tx_busy(t)) ? t->tx_buf : NULL;
}

int32_t canfdi_isotp_send(canfdi_isotp_t *t, uint32_t len)
{
  int32_t rc = -CANFDI_EINVAL;
  if (usable(t) && !canfdi_isotp_tx_busy(t)) {
    if ((len == 0U) || (len > CANFDI_CFG_ISOTP_TX_BYTES)) {
      rc = -CANFDI_ERANGE;
    } else {
      t->tx_len = len;
      t->tx_pos = 0U;
      t->tx_sn = 1U;
      t->tx_wft = 0U;
      t->tx_state = (uint8_t)((len <= CANFDI_ISOTP_SF_MAX) ? CANFDI_ISOTP_TX_SF : CANFDI_ISOTP_TX_FF);
      rc = CANFDI_OK;
    }
  }
  return rc;
}

static void timers(canfdi_isotp_t *t)
{
  if (t->rx_state == (uint8_t)CANFDI_ISOTP_RX_RECEIVING) {
    /* N_Cr runs from the FC sent (or the last CF) */
    if (t->fc_pending == 0U) {
      t->rx_timer_ms++;
    }
    if (t->rx_timer_ms >= t->cfg.n_cr_ms) {
      canfdi_count_inc(&t->diag.timeout_cr);
      rx_idle(t);
    }
  }
  if (t->tx_state == (uint8_t)CANFDI_ISOTP_TX_WAIT_FC) {
    t->tx_timer_ms++;
    if (t->tx_timer_ms >= t->cfg.n_bs_ms) {
      canfdi_count_inc(&t->diag.timeout_bs);
      tx_idle(t);
    }
  }
}

/* The next frame of the transmission into f (already padded); false if
 * none leaves in this step. */
static bool tx_frame(canfdi_isotp_t *t, uint8_t f[DL])
{
  bool out = false;
  if (t->tx_state == (uint8_t)CANFDI_ISOTP_TX_SF) {
    f[0] = (uint8_t)t->tx_len;
    copy_in(&f[1], t->tx_buf, t->tx_len);
    t->tx_pos = t->tx_len;
    out = true;
  } else if (t->tx_state == (uint8_t)CANFDI_ISOTP_TX_FF) {
    uint32_t off = 2U;
    if (t->tx_len <= 4095U) {
      f[0] = (uint8_t)((PCI_FF << 4) | ((t->tx_len >> 8) & 0x0FU));
      f[1] = (uint8_t)(t->tx_len & 0xFFU);
    } else {
      f[0] = (uint8_t)(PCI_FF << 4);
      f[1] = 0U;
      f[2] = (uint8_t)(t->tx_len >> 24);
      f[3] = (uint8_t)(t->tx_len >> 16);
      f[4] = (uint8_t)(t->tx_len >> 8);
      f[5] = (uint8_t)t->tx_len;
      off = 6U;
    }
    copy_in(&f[off], t->tx_buf, DL - off);
    t->tx_pos = DL - off;
    t->tx_timer_ms = 0U;
    t->tx_state = (uint8_t)CANFDI_ISOTP_TX_WAIT_FC;
    out = true;
  } else if (t->tx_state == (uint8_t)CANFDI_ISOTP_TX_CF) {
    t->tx_gap = (t->tx_gap > 0U) ? (uint8_t)(t->tx_gap - 1U) : 0U;
    if (t->tx_gap == 0U) {
      const uint32_t left = t->tx_len - t->tx_pos;
      const uint32_t n = (left < (DL - 1U)) ? left : (DL - 1U);
      f[0] = (uint8_t)((PCI_CF << 4) | t->tx_sn);
      copy_in(&f[1], &t->tx_buf[t->tx_pos], n);
      t->tx_pos += n;
      t->tx_sn = (uint8_t)((t->tx_sn + 1U) & 0x0FU);
      t->tx_gap = (t->tx_stmin_ms > 1U) ? t->tx_stmin_ms : 1U;
      if ((t->tx_pos < t->tx_len) && (t->tx_block != 0U)) {
        t->tx_block--;
        if (t->tx_block == 0U) {
          t->tx_timer_ms = 0U;
          t->tx_state = (uint8_t)CANFDI_ISOTP_TX_WAIT_FC;
        }
      }
      out = true;
    }
  } else {
    /* idle or waiting for FC */
  }
  if (out && (t->tx_pos >= t->tx_len)) {
    canfdi_count_inc(&t->diag.tx_messages);
    tx_idle(t);
  }
  return out;
}

int32_t canfdi_isotp_step(canfdi_isotp_t *t, uint8_t frame[CANFDI_CFG_ISOTP_FRAME_BYTES])
{
  int32_t rc = -CANFDI_EINVAL;
  if (usable(t) && (frame != NULL)) {
    for (uint32_t i = 0U; i < DL; i++) {
      frame[i] = (uint8_t)CANFDI_CFG_ISOTP_PAD_BYTE;
    }
    timers(t);
    rc = 0;
    if (t->fc_pending != 0U) {
      frame[0] = t->fc_pending;
      frame[1] = t->cfg.bs;
      frame[2] = t->cfg.stmin;
      t->fc_pending = 0U;
      t->rx_timer_ms = 0U;
      rc = 1;
    } else if (tx_frame(t, frame)) {
      rc = 1;
    } else {
      /* nothing to send */
    }
    if (rc == 1) {
      canfdi_count_inc(&t->diag.tx_frames);
    }
  }
  return rc;
}
