/*
 * fuzz_isotp.c — the ISO-TP layer alone (comm/canfdi_isotp.c) between a
 * hostile tester and an echo server: raw frames of any PCI and length on
 * the physical and functional connection (including the tester's flow
 * control: wait frames, overflow, any block size and STmin), 1 ms steps,
 * and a server that takes each complete request and answers with a
 * response of an input-chosen length (SF or segmented).
 * Operations (first byte % 4): 0 physical frame, 1 functional frame (DLC
 * byte, bytes); 2 steps (1..64, or 1..2 s); 3 the server answers the
 * request waiting (length byte pair).
 * Invariants: a request handed to the server is 1..CANFDI_CFG_ISOTP_RX_BYTES
 * long, a functional one a single frame; every frame sent has a valid PCI:
 * an SF of the length sent, an FF announcing the length sent, CFs in
 * sequence carrying exactly the response's bytes, an FC CTS never for a
 * reception that ended (idle: only an overflow FC); the diagnostic counters
 * never go down; a transmission never sends more than it was given.
 */
#include <string.h>

#include "comm/canfdi_isotp.h"
#include "fuzz_input.h"

#define MAX_OPS 512U
#define MAX_STEPS 6000U

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static canfdi_isotp_t tp;

static struct {
  uint32_t steps;
  uint8_t resp[CANFDI_CFG_ISOTP_TX_BYTES];
  uint32_t resp_len; /* the response being sent, 0: none */
  uint32_t resp_pos; /* its bytes seen in frames */
  uint8_t sn;
} t;

static void check_diag_monotone(const canfdi_isotp_diag_t *before)
{
  const uint32_t *a = (const uint32_t *)before;
  const uint32_t *b = (const uint32_t *)&tp.diag;
  for (size_t k = 0U; k < sizeof(canfdi_isotp_diag_t) / sizeof(uint32_t); k++) {
    FZ_CHECK(b[k] >= a[k], "diag counter %zu went down %u -> %u", k, a[k], b[k]);
  }
}

static void frame_out(const uint8_t *f)
{
  const uint8_t pci = (uint8_t)(f[0] >> 4);
  switch (pci) {
  case 0U: {
    const uint32_t n = f[0] & 0x0FU;
    FZ_CHECK(t.resp_len != 0U && n == t.resp_len && n <= CANFDI_ISOTP_SF_MAX, "SF of %u, sending %u", n,
             t.resp_len);
    FZ_CHECK(memcmp(&f[1], t.resp, n) == 0, "%s", "SF bytes differ from the response");
    t.resp_len = 0U;
    break;
  }
  case 1U: {
    const uint32_t n = ((uint32_t)(f[0] & 0x0FU) << 8) | f[1];
    FZ_CHECK(t.resp_len != 0U && n == t.resp_len && t.resp_pos == 0U, "FF of %u, sending %u at %u", n,
             t.resp_len, t.resp_pos);
    FZ_CHECK(memcmp(&f[2], t.resp, 6U) == 0, "%s", "FF bytes differ");
    t.resp_pos = 6U;
    t.sn = 1U;
    break;
  }
  case 2U: {
    FZ_CHECK(t.resp_len != 0U && t.resp_pos >= 6U && t.resp_pos < t.resp_len, "CF at %u of %u", t.resp_pos,
             t.resp_len);
    FZ_CHECK((f[0] & 0x0FU) == t.sn, "CF SN %u, want %u", f[0] & 0x0FU, t.sn);
    t.sn = (uint8_t)((t.sn + 1U) & 0x0FU);
    uint32_t k = t.resp_len - t.resp_pos;
    k = (k > 7U) ? 7U : k;
    FZ_CHECK(memcmp(&f[1], &t.resp[t.resp_pos], k) == 0, "CF bytes differ at %u", t.resp_pos);
    t.resp_pos += k;
    if (t.resp_pos == t.resp_len) {
      t.resp_len = 0U;
    }
    break;
  }
  case 3U:
    FZ_CHECK((f[0] & 0x0FU) <= 2U, "FC flow status %u", f[0] & 0x0FU);
    /* a CTS only for a reception in progress, or one the tester completed
     * with CFs sent before our FC left (its violation, accepted) */
    FZ_CHECK(tp.rx_state != CANFDI_ISOTP_RX_IDLE || (f[0] & 0x0FU) == 2U, "FC %02X while not receiving", f[0]);
    break;
  default:
    FZ_CHECK(0, "PCI %02X", f[0]);
  }
}

static void step(void)
{
  uint8_t f[CANFDI_CFG_ISOTP_FRAME_BYTES];
  canfdi_isotp_diag_t d = tp.diag;
  const bool was_busy = canfdi_isotp_tx_busy(&tp);
  t.steps++;
  const int32_t r = canfdi_isotp_step(&tp, f);
  FZ_CHECK(r == 0 || r == 1, "step %d", (int)r);
  check_diag_monotone(&d);
  if (r == 1) {
    frame_out(f);
  }
  if (was_busy && !canfdi_isotp_tx_busy(&tp)) {
    t.resp_len = 0U; /* ended: sent, or aborted by the tester's FC/timeout */
  }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
  fz_in_t in = {data, size, 0U};
  canfdi_isotp_cfg_t cfg;
  canfdi_isotp_default_cfg(&cfg);
  cfg.bs = fz_u8(&in) % 4U;
  if (canfdi_isotp_init(&tp, &cfg) != CANFDI_OK) {
    abort();
  }
  memset(&t, 0, sizeof t);
  for (uint32_t op = 0U; fz_left(&in) && (op < MAX_OPS) && (t.steps < MAX_STEPS); op++) {
    const uint8_t o = fz_u8(&in);
    switch (o % 4U) {
    case 0U:
    case 1U: {
      uint8_t f[8];
      canfdi_isotp_diag_t d = tp.diag;
      const uint8_t dlc = (uint8_t)(fz_u8(&in) % 9U);
      for (uint32_t k = 0U; k < 8U; k++) {
        f[k] = (k < dlc) ? fz_u8(&in) : 0xCCU;
      }
      FZ_CHECK(canfdi_isotp_rx_can(&tp, (o % 4U) == 1U, f, dlc) == CANFDI_OK, "%s", "rx_can refused");
      check_diag_monotone(&d);
      break;
    }
    case 2U: {
      const uint8_t b = fz_u8(&in);
      const uint32_t n = (b >= 0xF0U) ? 1000U * (uint32_t)(b - 0xEEU) : (uint32_t)(b % 64U) + 1U;
      for (uint32_t k = 0U; (k < n) && (t.steps < MAX_STEPS); k++) {
        step();
      }
      break;
    }
    default: {
      const uint8_t *msg = NULL;
      bool functional = false;
      const uint32_t len = canfdi_isotp_rx_peek(&tp, &msg, &functional);
      const uint32_t want = 1U + (fz_u16(&in) % CANFDI_CFG_ISOTP_TX_BYTES);
      if (len == 0U) {
        break;
      }
      FZ_CHECK(msg != NULL && len <= CANFDI_CFG_ISOTP_RX_BYTES, "request of %u", len);
      FZ_CHECK(!functional || len <= CANFDI_ISOTP_SF_MAX, "functional request of %u", len);
      if (!canfdi_isotp_tx_busy(&tp)) {
        uint8_t *buf = canfdi_isotp_tx_buf(&tp);
        for (uint32_t k = 0U; k < want; k++) {
          buf[k] = (uint8_t)(msg[k % len] + k);
        }
        memcpy(t.resp, buf, want);
        canfdi_isotp_rx_release(&tp);
        FZ_CHECK(canfdi_isotp_send(&tp, want) == CANFDI_OK, "send %u", want);
        t.resp_len = want;
        t.resp_pos = 0U;
      }
      break;
    }
    }
  }
  return 0;
}
