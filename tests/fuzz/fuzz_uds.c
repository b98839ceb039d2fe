/*
 * fuzz_uds.c — the diagnostic server as a tester meets it: raw CAN frames
 * on UdsPhysReq (0x7E0) and UdsFuncReq (0x7DF) through
 * canfdi_app_rx_frame, the ISO-TP layer (comm/canfdi_isotp.c) and the UDS
 * dispatch (uds/) backed by the application's real DTC memory and
 * SecurityAccess state; the responses from the application's UDS stage
 * (canfdi_app_uds_stage, the function canfdi_app_step calls), stepped 1 ms
 * at a time. The plant models are not stepped (that is fuzz_app_rx's
 * business), so a step costs microseconds.
 *
 * The input is a sequence of operations (tests/fuzz/README.md):
 *   raw physical / functional frame, a whole request segmented by the
 *   harness (SF, or FF + CFs after the server's FC), time advances (short,
 *   or long enough for S3 and the security delay), the correct key for the
 *   last seed handed out (or a key one bit off), monitor reports into the
 *   DTC memory, an operation cycle's end and start.
 *
 * Invariants, checked after every operation:
 *   - every frame the server sends is 8 bytes with a valid ISO-TP PCI;
 *   - every reassembled response is a positive response (request SID +
 *     0x40 of a SID some request carried, of at least the service's
 *     minimum length) or 7F SID NRC (3 bytes, NRC != 0);
 *   - no unlock without the right key: the security level only rises when
 *     a key sent was key_default(the seed of the last positive seed
 *     response for that level);
 *   - the attempt counter never goes down while locked;
 *   - the DTC memory's invariants (canfdi_dtc_invariants_hold) and,
 *     spelled out, confirmed or pending => testFailedSinceLastClear.
 */
#include <string.h>

#include "app/canfdi_app.h"
#include "app/canfdi_app_uds.h"
#include "fuzz_input.h"

#define PHYS 0x7E0U
#define FUNC 0x7DFU
#define RESP 0x7E8U
#define MAX_OPS 512U
#define MAX_STEPS 12000U /* > the security delay (10 s) + S3 (5 s) */
#define KEYS MAX_OPS /* every key attempt of an input: the server queues 4 requests, a log of the last few missed a right key queued before wrong ones */

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static canfdi_app_t app;
static canfdi_app_t pristine;
static canfdi_app_cal_t cal;

/* the harness as tester */
static struct {
  uint32_t now_us;
  uint32_t steps;
  bool sid_seen[256];
  /* the response being reassembled */
  uint8_t resp[4096];
  uint32_t resp_len;
  uint32_t resp_got;
  uint8_t resp_sn;
  bool resp_active;
  bool fc_seen;  /* the server sent an FC (for our segmented request) */
  /* security */
  uint32_t seed[CANFDI_UDS_SEC_MAX_LEVELS + 1U];
  bool seed_known[CANFDI_UDS_SEC_MAX_LEVELS + 1U];
  struct {
    uint8_t level;
    uint32_t key;
  } keys[KEYS]; /* key attempts sent, newest last */
  uint32_t n_keys;
} t;

static uint32_t get_u32(const uint8_t *p)
{
  return ((uint32_t)p[0] << 24) | ((uint32_t)p[1] << 16) | ((uint32_t)p[2] << 8) | (uint32_t)p[3];
}

/* Note what a request frame the harness sends may carry. */
static void note_request(const uint8_t *d, uint8_t dlc)
{
  if (dlc < 2U) {
    return;
  }
  const uint8_t pci = (uint8_t)(d[0] >> 4);
  if ((pci == 0U) && ((d[0] & 0x0FU) != 0U)) {
    t.sid_seen[d[1]] = true;
    if ((d[1] == 0x27U) && ((d[0] & 0x0FU) == 6U) && (dlc >= 7U) && ((d[2] & 0x7FU) % 2U == 0U)) {
      if (t.n_keys == KEYS) {
        memmove(&t.keys[0], &t.keys[1], (KEYS - 1U) * sizeof t.keys[0]);
        t.n_keys--;
      }
      t.keys[t.n_keys].level = (uint8_t)((d[2] & 0x7FU) / 2U);
      t.keys[t.n_keys].key = get_u32(&d[3]);
      t.n_keys++;
    }
  } else if ((pci == 1U) && (dlc >= 3U)) {
    t.sid_seen[d[2]] = true;
  }
}

static bool trace; /* FUZZ_TRACE=1: print every frame sent and reply (seeds, crashes) */

static void send(uint32_t id, const uint8_t *d, uint8_t dlc)
{
  if (trace) {
    fprintf(stderr, "t=%u ms %03X", t.steps, (unsigned)id);
    for (uint8_t k = 0U; k < dlc; k++) {
      fprintf(stderr, " %02X", d[k]);
    }
    fprintf(stderr, "\n");
  }
  if (id == PHYS) {
    note_request(d, dlc);
  } else if ((dlc >= 2U) && ((d[0] >> 4) == 0U)) {
    t.sid_seen[d[1]] = true; /* functional: single frames only */
  }
  (void)canfdi_app_rx_frame(&app, id, d, dlc, t.now_us);
}

static size_t min_len(uint8_t rsid)
{
  switch (rsid) {
  case 0x50U: return 6U; /* session, P2, P2* */
  case 0x51U: return 2U;
  case 0x54U: return 1U;
  case 0x59U: return 2U;
  case 0x62U: return 3U; /* DID and at least one byte */
  case 0x67U: return 2U;
  case 0x68U: return 2U;
  case 0x6FU: return 3U;
  case 0x71U: return 4U;
  case 0x7EU: return 2U;
  default: return 0U; /* not a service of this server */
  }
}

static void check_response(const uint8_t *r, uint32_t len)
{
  if (trace) {
    fprintf(stderr, "t=%u ms resp", t.steps);
    for (uint32_t k = 0U; k < len && k < 16U; k++) {
      fprintf(stderr, " %02X", r[k]);
    }
    fprintf(stderr, "%s (level %u)\n", len > 16U ? " ..." : "", canfdi_uds_sec_level(&app.uds.sec));
  }
  FZ_CHECK(len >= 1U, "%s", "empty response");
  if (r[0] == 0x7FU) {
    FZ_CHECK(len == 3U, "negative response of %u bytes", len);
    FZ_CHECK(t.sid_seen[r[1]], "7F for SID %02X never requested", r[1]);
    FZ_CHECK(r[2] != 0U, "NRC 00 for SID %02X", r[1]);
    return;
  }
  FZ_CHECK(r[0] >= 0x40U && t.sid_seen[r[0] - 0x40U], "positive %02X for a SID never requested", r[0]);
  FZ_CHECK(min_len(r[0]) != 0U, "positive response %02X of a service not served", r[0]);
  FZ_CHECK(len >= min_len(r[0]), "positive %02X of %u bytes", r[0], len);
  if ((r[0] == 0x67U) && ((r[1] & 1U) != 0U) && (len == 6U)) {
    const uint8_t level = (uint8_t)((r[1] + 1U) / 2U);
    if (level <= CANFDI_UDS_SEC_MAX_LEVELS) {
      t.seed[level] = get_u32(&r[2]);
      t.seed_known[level] = true;
    }
  }
}

/* A frame the server sent: the tester's ISO-TP receiver (sends the FC). */
static void receive(const canfdi_tx_frame_t *f)
{
  FZ_CHECK(f->id == RESP && f->dlc == 8U, "frame %03X dlc %u", (unsigned)f->id, f->dlc);
  const uint8_t *d = f->data;
  switch (d[0] >> 4) {
  case 0U: {
    const uint32_t n = d[0] & 0x0FU;
    FZ_CHECK(n >= 1U && n <= 7U, "SF length %u", n);
    t.resp_active = false;
    check_response(&d[1], n);
    break;
  }
  case 1U: {
    const uint32_t n = ((uint32_t)(d[0] & 0x0FU) << 8) | d[1];
    FZ_CHECK(n >= 8U && n <= CANFDI_CFG_ISOTP_TX_BYTES, "FF length %u", n);
    memcpy(t.resp, &d[2], 6U);
    t.resp_len = n;
    t.resp_got = 6U;
    t.resp_sn = 1U;
    t.resp_active = true;
    {
      static const uint8_t fc[8] = {0x30U, 0U, 0U, 0xCCU, 0xCCU, 0xCCU, 0xCCU, 0xCCU};
      send(PHYS, fc, 8U);
    }
    break;
  }
  case 2U: {
    FZ_CHECK(t.resp_active, "%s", "CF without an FF");
    FZ_CHECK((d[0] & 0x0FU) == t.resp_sn, "CF SN %u, want %u", d[0] & 0x0FU, t.resp_sn);
    t.resp_sn = (uint8_t)((t.resp_sn + 1U) & 0x0FU);
    uint32_t k = t.resp_len - t.resp_got;
    k = (k > 7U) ? 7U : k;
    memcpy(&t.resp[t.resp_got], &d[1], k);
    t.resp_got += k;
    if (t.resp_got == t.resp_len) {
      t.resp_active = false;
      check_response(t.resp, t.resp_len);
    }
    break;
  }
  case 3U:
    FZ_CHECK((d[0] & 0x0FU) <= 2U, "FC flow status %u", d[0] & 0x0FU);
    t.fc_seen = true;
    break;
  default:
    FZ_CHECK(0, "PCI %02X", d[0]);
  }
}

static void check_dtc(void)
{
  const canfdi_dtc_t *m = &app.dtc;
  FZ_CHECK(canfdi_dtc_invariants_hold(m), "%s", "DTC memory invariants");
  for (uint8_t i = 0U; i < (uint8_t)CANFDI_DTC_COUNT; i++) {
    const int32_t s = canfdi_dtc_status(m, i);
    FZ_CHECK(s >= 0, "status of %u", i);
    if ((s & 0x0C) != 0) {
      FZ_CHECK((s & 0x20) != 0, "DTC %u: status %02X confirmed/pending without TFSLC", i, (unsigned)s);
    }
  }
}

static void step(void)
{
  canfdi_tx_frame_t out[CANFDI_APP_MAX_TX];
  const uint8_t lvl0 = canfdi_uds_sec_level(&app.uds.sec);
  const uint8_t att0 = canfdi_uds_sec_attempts(&app.uds);
  t.now_us += 1000U;
  t.steps++;
  const int32_t m = canfdi_app_uds_stage(&app, out, 0);
  canfdi_app_uds_apply(&app);
  app.reset_requested = false; /* the port would restart; the harness goes on */
  FZ_CHECK(m == 0 || m == 1, "UDS stage returned %d", (int)m);
  const uint8_t lvl1 = canfdi_uds_sec_level(&app.uds.sec);
  const uint8_t att1 = canfdi_uds_sec_attempts(&app.uds);
  if ((lvl1 != 0U) && (lvl1 != lvl0)) {
    bool justified = false;
    for (uint32_t k = 0U; k < t.n_keys; k++) {
      justified = justified || ((t.keys[k].level == lvl1) && t.seed_known[lvl1] &&
                                (t.keys[k].key == canfdi_uds_sec_key_default(t.seed[lvl1], lvl1)));
    }
    FZ_CHECK(justified, "unlocked level %u without the right key", lvl1);
  }
  if (lvl1 == 0U) {
    FZ_CHECK(att1 >= att0, "attempt counter went down while locked: %u -> %u", att0, att1);
  }
  if (m == 1) {
    receive(&out[0]);
    check_dtc(); /* only a request changes the DTC memory in a step here */
  }
}

static void steps(uint32_t n)
{
  for (uint32_t k = 0U; (k < n) && (t.steps < MAX_STEPS); k++) {
    step();
  }
}

/* A whole request, segmented as a tester does. */
static void request(fz_in_t *in)
{
  uint8_t msg[CANFDI_CFG_ISOTP_RX_BYTES + 8U];
  uint8_t f[8];
  const uint32_t len = 1U + (fz_u8(in) % (uint32_t)sizeof msg);
  for (uint32_t k = 0U; k < len; k++) {
    msg[k] = fz_u8(in);
  }
  memset(f, 0xCC, sizeof f);
  if (len <= 7U) {
    f[0] = (uint8_t)len;
    memcpy(&f[1], msg, len);
    send(PHYS, f, 8U);
    return;
  }
  f[0] = (uint8_t)(0x10U | (len >> 8));
  f[1] = (uint8_t)len;
  memcpy(&f[2], msg, 6U);
  t.fc_seen = false;
  send(PHYS, f, 8U);
  for (uint32_t k = 0U; (k < 4U) && !t.fc_seen; k++) {
    steps(1U);
  }
  uint32_t pos = 6U;
  uint8_t sn = 1U;
  while (pos < len) {
    uint32_t k = len - pos;
    k = (k > 7U) ? 7U : k;
    memset(f, 0xCC, sizeof f);
    f[0] = (uint8_t)(0x20U | sn);
    memcpy(&f[1], &msg[pos], k);
    send(PHYS, f, 8U);
    pos += k;
    sn = (uint8_t)((sn + 1U) & 0x0FU);
    steps(1U);
  }
}

static void raw(fz_in_t *in, uint32_t id)
{
  uint8_t f[8];
  const uint8_t dlc = (uint8_t)(fz_u8(in) % 9U);
  for (uint32_t k = 0U; k < 8U; k++) {
    f[k] = (k < dlc) ? fz_u8(in) : 0xCCU;
  }
  send(id, f, dlc);
}

static void key(fz_in_t *in)
{
  const uint8_t b = fz_u8(in);
  const uint8_t level = (uint8_t)(1U + (b & 1U));
  uint32_t k = canfdi_uds_sec_key_default(t.seed[level], level);
  if ((b & 2U) != 0U) {
    k ^= 1UL << ((b >> 2) & 31U); /* one bit off */
  }
  const uint8_t f[8] = {0x06U, 0x27U, (uint8_t)(2U * level), (uint8_t)(k >> 24), (uint8_t)(k >> 16),
                        (uint8_t)(k >> 8), (uint8_t)k, 0xCCU};
  send(PHYS, f, 8U);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
  static bool ready = false;
  fz_in_t in = {data, size, 0U};
  if (!ready) {
    canfdi_app_default_cal(&cal);
    if (canfdi_app_init(&app, &cal, 0U) != CANFDI_OK) {
      abort();
    }
    memcpy(&pristine, &app, sizeof app);
    trace = getenv("FUZZ_TRACE") != NULL;
    ready = true;
  }
  memcpy(&app, &pristine, sizeof app);
  memset(&t, 0, sizeof t);
  for (uint32_t op = 0U; fz_left(&in) && (op < MAX_OPS) && (t.steps < MAX_STEPS); op++) {
    const uint8_t o = fz_u8(&in);
    switch (o % 10U) {
    case 0U:
    case 1U: raw(&in, PHYS); break;
    case 2U: raw(&in, FUNC); break;
    case 3U:
    case 4U: request(&in); break;
    case 5U: {
      const uint8_t b = fz_u8(&in);
      steps((b >= 0xF0U) ? 1000U * (uint32_t)(b - 0xEFU) : (uint32_t)b % 64U + 1U);
      break;
    }
    case 6U: key(&in); break;
    case 7U: {
      const uint8_t i = (uint8_t)(fz_u8(&in) % (uint8_t)CANFDI_DTC_COUNT);
      (void)canfdi_dtc_report(&app.dtc, i, (canfdi_deb_report_t)(fz_u8(&in) % 4U), NULL);
      break;
    }
    case 8U:
      (void)canfdi_dtc_cycle_end(&app.dtc);
      (void)canfdi_dtc_cycle_start(&app.dtc);
      break;
    default: steps(1U); break;
    }
    check_dtc();
  }
  steps(8U); /* let the last response leave */
  return 0;
}
