/*
 * test_uds.c — conformance tests of the diagnostic server (uds/canfdi_uds.h)
 * and its ISO-TP transport (comm/canfdi_isotp.h), through the application's
 * frame ports only: a tester written here (ISO 15765-2 segmentation and flow
 * control) sends UdsPhysReq / UdsFuncReq frames to canfdi_app_rx_frame and
 * reads UdsPhysResp frames from canfdi_app_step, while the host_sim plants
 * close the loops as in SIL (canfdi_sim_rig.h). Every service and
 * sub-function with its positive and negative paths, the NRC order,
 * SecurityAccess's attempt counter across a restart, the ISO-TP error paths,
 * and the 1 ms step's frame budget while a request is in flight.
 */
#include <check.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "app/canfdi_app.h"
#include "core/canfdi_qconst.h"
#include "canfdi_sim.h"
#include "canfdi_sim_rig.h"
#include "canfdi_sim_scenario.h"
#include "unit_main.h"

#define PHYS 0x7E0U
#define FUNC 0x7DFU
#define RESP 0x7E8U
#define NONE (-1)
#define QMAX 256U

static canfdi_app_t app;
static canfdi_app_cal_t cal;
static canfdi_sim_scn_t scn;
static canfdi_sim_t sim;
static canfdi_sim_rig_t rig;
static uint8_t rq[QMAX][8]; /* UdsPhysResp frames not yet read */
static uint32_t rq_head;
static uint32_t rq_len;
static uint32_t frames_seen[0x800];
static uint32_t max_frames_per_step;
static uint8_t image[CANFDI_APP_IMAGE_MAX_BYTES];

/* ------------------------------------------------ the loop: plant + ECU */

static void loop_setup(const char *text)
{
  canfdi_sim_scn_err_t err;
  ck_assert_msg(canfdi_sim_scn_parse(&scn, text, "test", &err) == 0, "%s", err.msg);
  ck_assert_int_eq(canfdi_sim_scn_setup(&scn, &sim), 0);
  ck_assert_int_eq(canfdi_sim_rig_init(&rig, &scn, &sim, (uint8_t)CANFDI_SIM_MODE_LOCKSTEP), 0);
  ck_assert_int_eq(canfdi_app_power_up(&app, &cal, 0U, NULL, 0U), CANFDI_OK);
  rq_head = 0U;
  rq_len = 0U;
  memset(frames_seen, 0, sizeof frames_seen);
  max_frames_per_step = 0U;
}

static uint32_t now_us(void) { return (uint32_t)canfdi_sim_time_us(&sim); }

static void loop_step(void)
{
  canfdi_sim_frame_t pf[CANFDI_SIM_RIG_MAX_TX];
  canfdi_tx_frame_t out[CANFDI_APP_MAX_TX];
  const size_t npf = canfdi_sim_rig_begin(&rig, pf);
  int32_t n;
  for (size_t j = 0U; j < npf; j++) {
    if (pf[j].id < 0x600U) {
      (void)canfdi_app_rx_frame(&app, pf[j].id, pf[j].data, pf[j].dlc, now_us());
    }
  }
  n = canfdi_app_step(&app, now_us(), out);
  ck_assert_int_ge(n, 2);
  ck_assert_int_le(n, (int32_t)CANFDI_APP_MAX_TX);
  max_frames_per_step = ((uint32_t)n > max_frames_per_step) ? (uint32_t)n : max_frames_per_step;
  ck_assert_uint_eq(out[0].id, 0x020U); /* the actuators first, every step */
  ck_assert_uint_eq(out[1].id, 0x021U);
  for (int32_t i = 0; i < n; i++) {
    canfdi_sim_frame_t rf;
    frames_seen[out[i].id & 0x7FFU]++;
    if (out[i].id == RESP) {
      ck_assert_uint_eq(out[i].dlc, 8U);
      ck_assert_uint_lt(rq_len, QMAX);
      memcpy(rq[(rq_head + rq_len) % QMAX], out[i].data, 8U);
      rq_len++;
    } else {
      rf.id = out[i].id;
      rf.dlc = out[i].dlc;
      memcpy(rf.data, out[i].data, 8U);
      (void)canfdi_sim_rig_rx(&rig, &rf, NULL);
    }
  }
  canfdi_sim_rig_end(&rig);
}

static void run_ms(uint32_t ms)
{
  for (uint32_t k = 0U; k < ms; k++) {
    loop_step();
  }
}

static bool pop(uint8_t f[8])
{
  bool got = rq_len > 0U;
  if (got) {
    memcpy(f, rq[rq_head], 8U);
    rq_head = (rq_head + 1U) % QMAX;
    rq_len--;
  }
  return got;
}

static void send_raw(uint32_t id, const uint8_t *d, uint8_t dlc)
{
  ck_assert_int_eq(canfdi_app_rx_frame(&app, id, d, dlc, now_us()), CANFDI_OK);
}

/* Wait up to ms steps for a response frame. */
static bool wait_frame(uint8_t f[8], uint32_t ms)
{
  bool got = pop(f);
  for (uint32_t k = 0U; (k < ms) && !got; k++) {
    loop_step();
    got = pop(f);
  }
  return got;
}

/* ------------------------------------------------ the tester (ISO-TP client) */

/* Sends req (segmented), returns the response length or NONE within ms. */
static int32_t uds_to(uint32_t id, const uint8_t *req, uint32_t len, uint8_t *resp, uint32_t ms)
{
  uint8_t f[8];
  int32_t out = NONE;
  memset(f, 0xCC, sizeof f);
  if (len <= 7U) {
    f[0] = (uint8_t)len;
    memcpy(&f[1], req, len);
    send_raw(id, f, 8U);
  } else {
    uint32_t pos = 6U;
    uint8_t sn = 1U;
    f[0] = (uint8_t)(0x10U | (len >> 8));
    f[1] = (uint8_t)len;
    memcpy(&f[2], req, 6U);
    send_raw(id, f, 8U);
    ck_assert(wait_frame(f, 10U));
    ck_assert_uint_eq(f[0], 0x30U); /* FC continue to send */
    while (pos < len) {
      const uint32_t n = ((len - pos) < 7U) ? (len - pos) : 7U;
      memset(f, 0xCC, sizeof f);
      f[0] = (uint8_t)(0x20U | sn);
      memcpy(&f[1], &req[pos], n);
      send_raw(id, f, 8U);
      pos += n;
      sn = (uint8_t)((sn + 1U) & 0x0FU);
      loop_step();
    }
  }
  if (wait_frame(f, ms)) {
    if ((f[0] >> 4) == 0U) {
      out = f[0] & 0x0F;
      memcpy(resp, &f[1], (size_t)out);
    } else {
      const uint32_t total = ((uint32_t)(f[0] & 0x0FU) << 8) | f[1];
      uint32_t got = 6U;
      uint8_t sn = 1U;
      uint8_t fc[8] = {0x30U, 0U, 0U, 0xCCU, 0xCCU, 0xCCU, 0xCCU, 0xCCU};
      ck_assert_uint_eq(f[0] >> 4, 1U);
      memcpy(resp, &f[2], 6U);
      send_raw(PHYS, fc, 8U);
      while (got < total) {
        const uint32_t n = ((total - got) < 7U) ? (total - got) : 7U;
        ck_assert(wait_frame(f, 5U));
        ck_assert_uint_eq(f[0], 0x20U | sn);
        memcpy(&resp[got], &f[1], n);
        got += n;
        sn = (uint8_t)((sn + 1U) & 0x0FU);
      }
      out = (int32_t)total;
    }
  }
  return out;
}

static int32_t uds(const uint8_t *req, uint32_t len, uint8_t *resp)
{
  const int32_t n = uds_to(PHYS, req, len, resp, 20U);
  if ((n == 3) && (resp[0] == 0x7FU)) {
    printf("  (SID 0x%02X answered NRC 0x%02X at %.3f s)\n", req[0], resp[2], (double)now_us() * 1e-6);
  }
  return n;
}

/* Steps with a functional TesterPresent (suppressed) every 2 s, so a
 * non-default session outlives S3. */
static void run_ms_tp(uint32_t ms)
{
  for (uint32_t k = 0U; k < ms; k++) {
    if ((k % 2000U) == 1999U) {
      send_raw(FUNC, (const uint8_t[]){0x02, 0x3E, 0x80, 0xCC, 0xCC, 0xCC, 0xCC, 0xCC}, 8U);
    }
    loop_step();
  }
}

#define REQ(...) ((const uint8_t[]){__VA_ARGS__}), (uint32_t)sizeof((const uint8_t[]){__VA_ARGS__})

static void expect_nrc_id(uint32_t id, const uint8_t *req, uint32_t len, uint8_t nrc)
{
  uint8_t r[512];
  const int32_t n = uds_to(id, req, len, r, 20U);
  ck_assert_msg(n == 3, "SID 0x%02X: no negative response (got %d bytes)", req[0], (int)n);
  ck_assert_uint_eq(r[0], 0x7FU);
  ck_assert_uint_eq(r[1], req[0]);
  ck_assert_msg(r[2] == nrc, "SID 0x%02X: NRC 0x%02X, expected 0x%02X", req[0], r[2], nrc);
}

static void expect_nrc(const uint8_t *req, uint32_t len, uint8_t nrc) { expect_nrc_id(PHYS, req, len, nrc); }

static void expect_silence(uint32_t id, const uint8_t *req, uint32_t len)
{
  uint8_t r[512];
  ck_assert_int_eq(uds_to(id, req, len, r, 30U), NONE);
}

static void extended(void)
{
  uint8_t r[64];
  ck_assert_int_eq(uds(REQ(0x10, 0x03), r), 6);
  ck_assert_uint_eq(r[0], 0x50U);
}

static void unlock(uint8_t level)
{
  uint8_t r[64];
  uint8_t key[6];
  uint32_t seed;
  uint32_t k;
  const uint8_t sub = (uint8_t)((2U * level) - 1U);
  ck_assert_int_eq(uds(REQ(0x27, sub), r), 6);
  ck_assert_uint_eq(r[0], 0x67U);
  seed = ((uint32_t)r[2] << 24) | ((uint32_t)r[3] << 16) | ((uint32_t)r[4] << 8) | r[5];
  ck_assert_uint_ne(seed, 0U);
  k = canfdi_uds_sec_key_default(seed, level);
  key[0] = 0x27U;
  key[1] = (uint8_t)(sub + 1U);
  key[2] = (uint8_t)(k >> 24);
  key[3] = (uint8_t)(k >> 16);
  key[4] = (uint8_t)(k >> 8);
  key[5] = (uint8_t)k;
  ck_assert_int_eq(uds(key, 6U, r), 2);
  ck_assert_uint_eq(r[0], 0x67U);
}

static int32_t s32_at(const uint8_t *p)
{
  const uint32_t b = ((uint32_t)p[0] << 24) | ((uint32_t)p[1] << 16) | ((uint32_t)p[2] << 8) | p[3];
  return (b <= (uint32_t)INT32_MAX) ? (int32_t)b : (-(int32_t)(~b)) - 1;
}

static const char *AT_REST = "duration 600\nspeed const 0\nangle const 10\n";

/* ------------------------------------------------ sessions and general */

START_TEST(test_session_control)
{
  uint8_t r[64];
  canfdi_app_default_cal(&cal);
  loop_setup(AT_REST);
  run_ms(50U);
  ck_assert_int_eq(uds(REQ(0x10, 0x01), r), 6);
  ck_assert_mem_eq(r, ((const uint8_t[]){0x50, 0x01, 0x00, 50, 0x01, 0xF4}), 6);
  extended();
  ck_assert_uint_eq(canfdi_uds_session(&app.uds), CANFDI_UDS_SESSION_EXTENDED);
  /* TesterPresent keeps it past S3; silence ends it */
  for (uint32_t k = 0U; k < 4U; k++) {
    run_ms(2000U);
    ck_assert_int_eq(uds(REQ(0x3E, 0x00), r), 2);
    ck_assert_mem_eq(r, ((const uint8_t[]){0x7E, 0x00}), 2);
  }
  /* suppressed positive response, also functionally */
  expect_silence(PHYS, REQ(0x3E, 0x80));
  expect_silence(FUNC, REQ(0x3E, 0x80));
  ck_assert_uint_eq(canfdi_uds_session(&app.uds), CANFDI_UDS_SESSION_EXTENDED);
  run_ms(cal.uds.s3_ms + 10U);
  ck_assert_uint_eq(canfdi_uds_session(&app.uds), CANFDI_UDS_SESSION_DEFAULT);
  ck_assert_uint_eq(app.uds.diag.s3_timeouts, 1U);
  expect_nrc(REQ(0x27, 0x01), 0x7F); /* back in default */
  /* general NRCs */
  expect_nrc(REQ(0x10), 0x13);
  expect_nrc(REQ(0x10, 0x03, 0x00), 0x13);
  expect_nrc(REQ(0x10, 0x02), 0x12);
  expect_nrc(REQ(0x3E, 0x01), 0x12);
  expect_nrc(REQ(0x85, 0x02), 0x11);
  expect_nrc(REQ(0xBA), 0x11);
  expect_nrc(REQ(0x3E, 0x00, 0x00), 0x13);
  /* a negative response is sent even with the suppress bit */
  expect_nrc(REQ(0x10, 0x82), 0x12);
  /* functional: no NRC 0x11/0x12/0x31/0x7E/0x7F, positive responses yes */
  expect_silence(FUNC, REQ(0xBA));
  expect_silence(FUNC, REQ(0x10, 0x02));
  expect_silence(FUNC, REQ(0x22, 0x12, 0x34));
  expect_silence(FUNC, REQ(0x27, 0x01));
  ck_assert_int_eq(uds_to(FUNC, REQ(0x3E, 0x00), r, 20U), 2);
  expect_nrc_id(FUNC, REQ(0x3E), 0x13);
}
END_TEST

/* ------------------------------------------------ SecurityAccess */

START_TEST(test_security_access)
{
  uint8_t r[64];
  canfdi_app_default_cal(&cal);
  loop_setup(AT_REST);
  run_ms(50U);
  expect_nrc(REQ(0x27, 0x01), 0x7F);
  extended();
  expect_nrc(REQ(0x27, 0x02, 1, 2, 3, 4), 0x24);  /* key without a seed */
  expect_nrc(REQ(0x27), 0x13);
  expect_nrc(REQ(0x27, 0x05), 0x12);               /* level 3: not served */
  expect_nrc(REQ(0x27, 0x03), 0x12);               /* level 2 not configured */
  expect_nrc(REQ(0x27, 0x01, 0x00), 0x13);
  ck_assert_int_eq(uds(REQ(0x27, 0x01), r), 6);
  expect_nrc(REQ(0x27, 0x02, 1, 2, 3), 0x13);
  expect_nrc(REQ(0x27, 0x02, 0, 0, 0, 0), 0x35);  /* attempt 1 */
  expect_nrc(REQ(0x27, 0x02, 0, 0, 0, 0), 0x24);  /* the seed is used up */
  ck_assert_int_eq(uds(REQ(0x27, 0x01), r), 6);
  expect_nrc(REQ(0x27, 0x02, 0, 0, 0, 0), 0x35);  /* attempt 2 */
  ck_assert_int_eq(uds(REQ(0x27, 0x01), r), 6);
  expect_nrc(REQ(0x27, 0x02, 0, 0, 0, 0), 0x36);  /* attempt 3 reaches the limit */
  expect_nrc(REQ(0x27, 0x01), 0x37);
  expect_nrc(REQ(0x27, 0x02, 0, 0, 0, 0), 0x37);
  ck_assert_uint_eq(canfdi_uds_sec_attempts(&app.uds), 3U);
  /* the counter is kept across a restart: the delay runs again at once */
  {
    const int32_t len = canfdi_app_power_down(&app, image, sizeof image);
    ck_assert_int_gt(len, 4);
    ck_assert_uint_eq(image[0], CANFDI_APP_IMAGE_TAG);
    ck_assert_uint_eq(image[2], 3U);
    ck_assert_int_eq(canfdi_app_power_up(&app, &cal, now_us(), image, (uint32_t)len), CANFDI_OK);
  }
  run_ms(20U);
  extended();
  expect_nrc(REQ(0x27, 0x01), 0x37);
  run_ms_tp(cal.uds.sec.delay_ms);
  /* after the delay: one guess, and a wrong one costs a new delay at once */
  ck_assert_int_eq(uds(REQ(0x27, 0x01), r), 6);
  expect_nrc(REQ(0x27, 0x02, 0, 0, 0, 0), 0x36);
  expect_nrc(REQ(0x27, 0x01), 0x37);
  run_ms_tp(cal.uds.sec.delay_ms);
  unlock(1U);
  ck_assert_uint_eq(canfdi_uds_sec_attempts(&app.uds), 0U);
  /* unlocked: requestSeed answers seed 0 */
  ck_assert_int_eq(uds(REQ(0x27, 0x01), r), 6);
  ck_assert_mem_eq(&r[2], ((const uint8_t[]){0, 0, 0, 0}), 4);
  /* every session change locks */
  extended();
  expect_nrc(REQ(0x2F, 0xD1, 0x15, 0x00), 0x33);
  expect_nrc(REQ(0x31, 0x01, 0x02, 0x01, 0x01), 0x33);
}
END_TEST

/* The default key: the same known answers as the tester's copy
 * (tests/tools/test_uds_tool.py), and a replaced key function. */
static uint32_t other_key(uint32_t seed, uint8_t level) { return ~seed + level; }

START_TEST(test_key_function)
{
  uint8_t r[64];
  uint8_t key[6] = {0x27, 0x02, 0, 0, 0, 0};
  uint32_t seed;
  uint32_t k;
  ck_assert_uint_eq(canfdi_uds_sec_key_default(0x12345678U, 1U), 0x67FFB80FU);
  ck_assert_uint_eq(canfdi_uds_sec_key_default(0xA4E25C5FU, 1U), 0x354BA250U);
  ck_assert_uint_eq(canfdi_uds_sec_key_default(0x00000001U, 2U), 0xDCA97096U);
  canfdi_app_default_cal(&cal);
  cal.uds.sec.key_fn = other_key;
  loop_setup(AT_REST);
  run_ms(20U);
  extended();
  ck_assert_int_eq(uds(REQ(0x27, 0x01), r), 6);
  seed = ((uint32_t)r[2] << 24) | ((uint32_t)r[3] << 16) | ((uint32_t)r[4] << 8) | r[5];
  k = other_key(seed, 1U);
  key[2] = (uint8_t)(k >> 24);
  key[3] = (uint8_t)(k >> 16);
  key[4] = (uint8_t)(k >> 8);
  key[5] = (uint8_t)k;
  ck_assert_int_eq(uds(key, 6U, r), 2);
  ck_assert_uint_eq(canfdi_uds_sec_level(&app.uds.sec), 1U);
}
END_TEST

/* Two levels: a key for another level than the seed's is a sequence error. */
START_TEST(test_security_levels)
{
  uint8_t r[64];
  canfdi_app_default_cal(&cal);
  cal.uds.sec.levels = 2U;
  loop_setup(AT_REST);
  run_ms(20U);
  extended();
  ck_assert_int_eq(uds(REQ(0x27, 0x01), r), 6);
  expect_nrc(REQ(0x27, 0x04, 0, 0, 0, 0), 0x24);
  expect_nrc(REQ(0x27, 0x02, 0, 0, 0, 0), 0x24); /* used up by that key */
  ck_assert_uint_eq(canfdi_uds_sec_attempts(&app.uds), 0U);
  unlock(2U);
  ck_assert_uint_eq(canfdi_uds_sec_level(&app.uds.sec), 2U);
}
END_TEST

/* ------------------------------------------------ trouble codes */

static const char *TPS1_OPEN = "duration 600\nspeed const 0\nangle const 10\nfault 0.3 thr_tps1_open abrupt 1\n";

START_TEST(test_read_dtc_information)
{
  uint8_t r[512];
  int32_t n;
  canfdi_dtc_record_t rec;
  const canfdi_dtc_t *dtc;
  canfdi_app_default_cal(&cal);
  loop_setup(TPS1_OPEN);
  run_ms(800U);
  dtc = canfdi_app_dtc(&app);
  ck_assert_int_eq(canfdi_dtc_read_record(dtc, CANFDI_DTC_P0122, &rec), CANFDI_OK);
  /* 0x01: number by mask, availability 0xFF, format 0x04 */
  n = uds(REQ(0x19, 0x01, 0x09), r);
  ck_assert_int_eq(n, 6);
  ck_assert_mem_eq(r, ((const uint8_t[]){0x59, 0x01, 0xFF, 0x04}), 4);
  ck_assert_uint_eq(((uint32_t)r[4] << 8) | r[5], canfdi_dtc_count_by_mask(dtc, 0x09U));
  ck_assert_uint_ge(((uint32_t)r[4] << 8) | r[5], 1U);
  /* 0x02: every DTC with a matching status, as in the memory */
  n = uds(REQ(0x19, 0x02, 0x08), r);
  ck_assert_int_eq(n, 3 + (4 * (int32_t)canfdi_dtc_count_by_mask(dtc, 0x08U)));
  {
    bool found = false;
    for (int32_t i = 3; i < n; i += 4) {
      const uint32_t code = ((uint32_t)r[i] << 16) | ((uint32_t)r[i + 1] << 8) | r[i + 2];
      ck_assert_int_eq(r[i + 3], canfdi_dtc_status(dtc, (uint8_t)canfdi_dtc_find(dtc, code)));
      found = found || (code == CANFDI_DTC_P0122);
    }
    ck_assert(found);
  }
  ck_assert_int_eq(uds(REQ(0x19, 0x02, 0x00), r), 3); /* mask 0: none */
  /* 0x0A: all 30 */
  ck_assert_int_eq(uds(REQ(0x19, 0x0A), r), 3 + (4 * (int32_t)CANFDI_DTC_COUNT));
  /* 0x03: snapshot identification */
  n = uds(REQ(0x19, 0x03), r);
  ck_assert_int_ge(n, 6);
  /* 0x04: the freeze frame, field by field */
  n = uds(REQ(0x19, 0x04, 0x01, 0x22, 0x00, 0xFF), r);
  ck_assert_int_eq(n, 6 + 2 + (int32_t)CANFDI_UDS_SNAPSHOT_BYTES);
  ck_assert_mem_eq(r, ((const uint8_t[]){0x59, 0x04, 0x01, 0x22, 0x00}), 5);
  ck_assert_uint_eq(r[5], rec.status);
  ck_assert_uint_eq(r[6], 0x01U);
  ck_assert_uint_eq(r[7], CANFDI_UDS_SNAPSHOT_DIDS);
  ck_assert_mem_eq(&r[8], ((const uint8_t[]){0xDF, 0x00}), 2);
  ck_assert_uint_eq(((uint32_t)r[10] << 24) | ((uint32_t)r[11] << 16) | ((uint32_t)r[12] << 8) | r[13],
                    (uint32_t)rec.ff.time_ms);
  ck_assert_mem_eq(&r[14], ((const uint8_t[]){0xD1, 0x00}), 2);
  ck_assert_int_eq(s32_at(&r[16]), rec.ff.omega_q16);
  ck_assert_mem_eq(&r[32], ((const uint8_t[]){0xD1, 0x10}), 2);
  ck_assert_int_eq(s32_at(&r[34]), rec.ff.thr_angle_q16);
  /* a DTC without an entry: DTC and status only */
  ck_assert_int_eq(uds(REQ(0x19, 0x04, 0x1A, 0x10, 0x00, 0x01), r), 6);
  /* 0x06: occurrence and aging counters */
  n = uds(REQ(0x19, 0x06, 0x01, 0x22, 0x00, 0xFF), r);
  ck_assert_int_eq(n, 10);
  ck_assert_mem_eq(&r[6], ((const uint8_t[]){0x01, rec.occurrence, 0x02, 0x00}), 4);
  ck_assert_int_eq(uds(REQ(0x19, 0x06, 0x01, 0x22, 0x00, 0x02), r), 8);
  /* 0x14: fault detection counters of prefailed DTCs (none here) */
  ck_assert_int_eq(uds(REQ(0x19, 0x14), r), 2);
  /* negative paths */
  expect_nrc(REQ(0x19), 0x13);
  expect_nrc(REQ(0x19, 0x05), 0x12);
  expect_nrc(REQ(0x19, 0x01), 0x13);
  expect_nrc(REQ(0x19, 0x04, 0x01, 0x22, 0x00), 0x13);
  expect_nrc(REQ(0x19, 0x04, 0x01, 0x22, 0x01, 0x01), 0x31); /* unknown DTC */
  expect_nrc(REQ(0x19, 0x04, 0x01, 0x22, 0x00, 0x02), 0x31); /* unknown record */
  expect_nrc(REQ(0x19, 0x06, 0x01, 0x22, 0x00, 0x03), 0x31);
  /* a long response goes out segmented: 0x0A is 3 + 4 per DTC bytes */
  ck_assert_uint_le(max_frames_per_step, CANFDI_APP_MAX_TX);
}
END_TEST

START_TEST(test_clear_dtc)
{
  uint8_t r[64];
  const canfdi_dtc_t *dtc;
  uint32_t ch;
  canfdi_app_default_cal(&cal);
  loop_setup(TPS1_OPEN);
  run_ms(800U);
  dtc = canfdi_app_dtc(&app);
  ck_assert_uint_ge(canfdi_dtc_count_by_mask(dtc, CANFDI_DTC_ST_TFSLC), 1U);
  expect_nrc(REQ(0x14, 0xFF, 0xFF), 0x13);
  expect_nrc(REQ(0x14, 0xFF, 0xFF, 0xFF, 0x00, 0x00), 0x13);
  expect_nrc(REQ(0x14, 0x12, 0x34, 0x56), 0x31);
  expect_nrc(REQ(0x14, 0xFF, 0xFF, 0xFF, 0x01), 0x31);
  /* one code */
  ch = canfdi_app_nvm_changes(&app);
  ck_assert_int_eq(uds(REQ(0x14, 0x01, 0x22, 0x00), r), 1);
  ck_assert_uint_eq(r[0], 0x54U);
  ck_assert_uint_ne(canfdi_app_nvm_changes(&app), ch); /* the port stores it */
  /* a group (the throttle), then all, with the memory selection 0 */
  ck_assert_int_eq(uds(REQ(0x14, 0xFF, 0xFF, 0x02), r), 1);
  ck_assert_int_eq(uds(REQ(0x14, 0xFF, 0xFF, 0xFF, 0x00), r), 1);
  ck_assert_uint_eq(canfdi_dtc_count_by_mask(dtc, (uint8_t)CANFDI_DTC_ST_TFSLC), 0U);
}
END_TEST

/* ------------------------------------------------ ReadDataByIdentifier */

START_TEST(test_read_data)
{
  uint8_t r[512];
  int32_t n;
  canfdi_app_default_cal(&cal);
  loop_setup("duration 600\nspeed const 80\nangle const 20\nload const 0.5\n");
  run_ms(1500U);
  n = uds(REQ(0x22, 0xF1, 0x95), r);
  ck_assert_int_eq(n, 3 + 16);
  ck_assert_mem_eq(&r[3], cal.uds.ident.sw_version, 16);
  n = uds(REQ(0x22, 0xD1, 0x00, 0xD1, 0x10, 0xD5, 0x00, 0xD4, 0x00), r);
  ck_assert_int_eq(n, 1 + 6 + 6 + 6 + 3);
  ck_assert_mem_eq(&r[1], ((const uint8_t[]){0xD1, 0x00}), 2);
  /* the value of the step that answered (the speed moves a little) */
  ck_assert_int_lt(abs(s32_at(&r[3]) - canfdi_rx_value(&app.rx, CANFDI_RX_IN_DCM_OMEGA)), 2 * 65536);
  ck_assert_int_lt(abs(s32_at(&r[3]) - (80 * 65536)), 10 * 65536);
  ck_assert_int_lt(abs(s32_at(&r[9]) - CANFDI_Q16_DEG(20, 1)), CANFDI_Q16_DEG(1, 1));
  ck_assert_uint_ge((uint32_t)s32_at(&r[15]), 1500U);
  ck_assert_uint_eq(r[21], 0U); /* degradation normal */
  /* unknown DIDs are left out while one is known */
  ck_assert_int_eq(uds(REQ(0x22, 0x12, 0x34, 0xD5, 0x09), r), 1 + 3);
  expect_nrc(REQ(0x22, 0x12, 0x34), 0x31);
  expect_nrc(REQ(0x22), 0x13);
  expect_nrc(REQ(0x22, 0xD1), 0x13);
  /* a multi-frame request (9 DIDs) and response */
  n = uds(REQ(0x22, 0xD2, 0x00, 0xD2, 0x01, 0xD2, 0x02, 0xD2, 0x03, 0xD2, 0x04, 0xD3, 0x00, 0xD3, 0x01,
              0xD4, 0x01, 0xF1, 0x8C),
          r);
  ck_assert_int_eq(n, 1 + (7 * 6) + 3 + 18);
  /* more DIDs than cfg.max_dids: 0x13 */
  {
    uint8_t big[1 + (2 * 17)];
    big[0] = 0x22U;
    for (uint32_t k = 0U; k < 17U; k++) {
      big[1U + (2U * k)] = 0xD5U;
      big[2U + (2U * k)] = 0x00U;
    }
    expect_nrc(big, sizeof big, 0x13);
  }
}
END_TEST

/* ------------------------------------------------ actuator test */

START_TEST(test_io_control)
{
  uint8_t r[64];
  const int32_t a30 = CANFDI_Q16_DEG(30, 1);
  canfdi_app_default_cal(&cal);
  loop_setup("duration 600\nspeed const 0\nangle const 10\nfault 9 thr_tps2_open abrupt 1\n");
  run_ms(1000U);
  expect_nrc(REQ(0x2F, 0xD1, 0x15, 0x03, 0, 0, 0, 0), 0x7F);
  extended();
  expect_nrc(REQ(0x2F, 0xD1, 0x15, 0x03, 0, 0, 0, 0), 0x33);
  unlock(1U);
  expect_nrc(REQ(0x2F, 0xD1, 0x15), 0x13);
  expect_nrc(REQ(0x2F, 0xD1, 0x00, 0x03, 0, 0, 0, 0), 0x31);  /* not controllable */
  expect_nrc(REQ(0x2F, 0xD1, 0x15, 0x02), 0x31);              /* freezeCurrentState */
  expect_nrc(REQ(0x2F, 0xD1, 0x15, 0x03, 0, 0), 0x13);
  expect_nrc(REQ(0x2F, 0xD1, 0x15, 0x03, 0x00, 0x10, 0x00, 0x00), 0x31); /* 16 rad */
  expect_nrc(REQ(0x2F, 0xD1, 0x04, 0x03, 0x01, 0x00, 0x00, 0x00), 0x31); /* 256 rad/s */
  ck_assert_int_eq(uds(REQ(0x2F, 0xD1, 0x15, 0x03, (uint8_t)(a30 >> 24), (uint8_t)(a30 >> 16),
                           (uint8_t)(a30 >> 8), (uint8_t)a30),
                       r),
                   8);
  ck_assert_mem_eq(r, ((const uint8_t[]){0x6F, 0xD1, 0x15, 0x03}), 4);
  ck_assert_int_eq(s32_at(&r[4]), a30);
  run_ms(1000U);
  ck_assert_int_lt(abs(app.vote_out.angle_rad_q16 - a30), CANFDI_Q16_DEG(4, 1));
  /* the speed too, together */
  ck_assert_int_eq(uds(REQ(0x2F, 0xD1, 0x04, 0x03, 0x00, 0x32, 0x00, 0x00), r), 8);
  run_ms(800U);
  ck_assert_int_lt(abs(canfdi_rx_value(&app.rx, CANFDI_RX_IN_DCM_OMEGA) - (50 * 65536)), 10 * 65536);
  /* returnControlToECU: back to the vehicle's setpoint */
  ck_assert_int_eq(uds(REQ(0x2F, 0xD1, 0x04, 0x00), r), 8);
  ck_assert_int_eq(uds(REQ(0x2F, 0xD1, 0x15, 0x00), r), 8);
  run_ms(1000U);
  ck_assert_int_lt(abs(app.vote_out.angle_rad_q16 - CANFDI_Q16_DEG(10, 1)), CANFDI_Q16_DEG(4, 1));
  /* a new test on the throttle */
  ck_assert_int_eq(uds(REQ(0x2F, 0xD1, 0x15, 0x03, (uint8_t)(a30 >> 24), (uint8_t)(a30 >> 16),
                           (uint8_t)(a30 >> 8), (uint8_t)a30),
                       r),
                   8);
  /* a new fault ends the test (TPS2 open at 9 s) */
  ck_assert_uint_lt(now_us(), 8000000U);
  run_ms_tp(8500U - (now_us() / 1000U));
  ck_assert(app.uds_act.angle_override);
  run_ms_tp(1000U);
  ck_assert(!app.uds_act.angle_override);
  ck_assert_uint_ge(app.uds.diag.ioc_fault_ends, 1U);
  /* and with a fault present none starts */
  expect_nrc(REQ(0x2F, 0xD1, 0x15, 0x03, (uint8_t)(a30 >> 24), (uint8_t)(a30 >> 16), (uint8_t)(a30 >> 8),
                 (uint8_t)a30),
             0x22);
}
END_TEST

START_TEST(test_io_control_session_end)
{
  uint8_t r[64];
  canfdi_app_default_cal(&cal);
  loop_setup(AT_REST);
  run_ms(500U);
  extended();
  unlock(1U);
  ck_assert_int_eq(uds(REQ(0x2F, 0xD1, 0x04, 0x03, 0x00, 0x14, 0x00, 0x00), r), 8);
  run_ms(100U);
  ck_assert(app.uds_act.speed_override);
  ck_assert_int_eq(uds(REQ(0x10, 0x01), r), 6);
  run_ms(2U);
  ck_assert(!app.uds_act.speed_override);
  run_ms(3000U); /* the motor coasts down */
  /* the motor moving: not at rest */
  extended();
  unlock(1U);
  ck_assert_int_eq(uds(REQ(0x2F, 0xD1, 0x04, 0x03, 0x00, 0x14, 0x00, 0x00), r), 8);
  run_ms(300U);
  ck_assert_int_eq(uds(REQ(0x2F, 0xD1, 0x04, 0x00), r), 8);
  expect_nrc(REQ(0x2F, 0xD1, 0x15, 0x03, 0, 0, 0, 0), 0x22);
  expect_nrc(REQ(0x11, 0x01), 0x22);
  run_ms(cal.uds.s3_ms + 10U); /* S3 ends the session */
  ck_assert_uint_eq(canfdi_uds_session(&app.uds), CANFDI_UDS_SESSION_DEFAULT);
}
END_TEST

/* ------------------------------------------------ routines */

START_TEST(test_routines)
{
  uint8_t r[64];
  canfdi_app_default_cal(&cal);
  loop_setup(AT_REST);
  run_ms(1000U);
  extended();
  expect_nrc(REQ(0x31, 0x01, 0x02, 0x01, 0x01), 0x33);
  unlock(1U);
  expect_nrc(REQ(0x31, 0x01, 0x02), 0x13);
  expect_nrc(REQ(0x31, 0x04, 0x02, 0x01), 0x12);
  expect_nrc(REQ(0x31, 0x01, 0x12, 0x34), 0x31);
  expect_nrc(REQ(0x31, 0x03, 0x02, 0x01), 0x24); /* results before a start */
  expect_nrc(REQ(0x31, 0x02, 0x02, 0x02), 0x24); /* stop of a routine not running */
  expect_nrc(REQ(0x31, 0x01, 0x02, 0x01), 0x13);
  expect_nrc(REQ(0x31, 0x01, 0x02, 0x01, 0x04), 0x31);
  expect_nrc(REQ(0x31, 0x02, 0x02, 0x01), 0x12);
  {
    const uint32_t resets = canfdi_est_dcm_diag(&app.est_dcm)->resets;
    ck_assert_int_eq(uds(REQ(0x31, 0x01, 0x02, 0x01, 0x03), r), 5);
    ck_assert_mem_eq(r, ((const uint8_t[]){0x71, 0x01, 0x02, 0x01, 0x01}), 5);
    run_ms(2U);
    ck_assert_uint_eq(canfdi_est_dcm_diag(&app.est_dcm)->resets, resets + 1U);
    ck_assert_int_eq(uds(REQ(0x31, 0x03, 0x02, 0x01), r), 5);
  }
  /* the spring check on a healthy throttle: passes */
  ck_assert_int_eq(uds(REQ(0x31, 0x01, 0x02, 0x02), r), 5);
  ck_assert_uint_eq(r[4], 0U); /* running */
  expect_nrc(REQ(0x31, 0x01, 0x02, 0x02), 0x22);
  run_ms(cal.uds.spring_open_ms + cal.uds.spring_timeout_ms);
  ck_assert_int_eq(uds(REQ(0x31, 0x03, 0x02, 0x02), r), 11);
  ck_assert_msg(r[4] == 1U, "spring check status %u, return %u ms", r[4], ((unsigned)r[5] << 8) | r[6]);
  ck_assert_uint_gt(((uint32_t)r[5] << 8) | r[6], 0U);
  ck_assert_uint_le(((uint32_t)r[5] << 8) | r[6], cal.uds.spring_pass_ms);
  /* stopped while running: aborted */
  ck_assert_int_eq(uds(REQ(0x31, 0x01, 0x02, 0x02), r), 5);
  run_ms(50U);
  ck_assert(app.uds_act.angle_override);
  ck_assert_int_eq(uds(REQ(0x31, 0x02, 0x02, 0x02), r), 5);
  ck_assert_uint_eq(r[4], 3U);
  run_ms(2U);
  ck_assert(!app.uds_act.angle_override);
}
END_TEST

/* A weak spring and pretension: the valve does not return in time. */
START_TEST(test_spring_weak)
{
  uint8_t r[64];
  canfdi_app_default_cal(&cal);
  loop_setup("duration 600\nspeed const 0\nangle const 10\nparam thr_spring_Nm_rad 0.02\n"
             "param thr_pretension_Nm 0.1\n");
  run_ms(1000U);
  extended();
  unlock(1U);
  ck_assert_int_eq(uds(REQ(0x31, 0x01, 0x02, 0x02), r), 5);
  run_ms(cal.uds.spring_open_ms + cal.uds.spring_timeout_ms + 10U);
  ck_assert_int_eq(uds(REQ(0x31, 0x03, 0x02, 0x02), r), 11);
  /* never passed: failed (not back in time), or aborted when the ECU's own
   * monitors flag the weak return (any new fault ends a test) */
  ck_assert_msg((r[4] == 2U) || (r[4] == 3U), "spring check status %u", r[4]);
}
END_TEST

/* ------------------------------------------------ ECUReset, CommunicationControl */

START_TEST(test_ecu_reset_and_comm_control)
{
  uint8_t r[64];
  uint32_t status0;
  canfdi_app_default_cal(&cal);
  loop_setup(AT_REST);
  run_ms(500U);
  expect_nrc(REQ(0x11, 0x01), 0x7E);
  expect_nrc(REQ(0x28, 0x01, 0x01), 0x7F);
  extended();
  expect_nrc(REQ(0x11, 0x03), 0x12);
  expect_nrc(REQ(0x11, 0x01, 0x00), 0x13);
  /* CommunicationControl: monitoring frames off, actuators on */
  expect_nrc(REQ(0x28, 0x03, 0x01), 0x12);
  expect_nrc(REQ(0x28, 0x01, 0x02), 0x31);
  expect_nrc(REQ(0x28, 0x01), 0x13);
  ck_assert_int_eq(uds(REQ(0x28, 0x01, 0x01), r), 2);
  status0 = frames_seen[0x300];
  run_ms(1000U);
  ck_assert_uint_eq(frames_seen[0x300], status0);
  ck_assert_uint_eq(frames_seen[0x200], frames_seen[0x200]);
  ck_assert_int_eq(uds(REQ(0x28, 0x00, 0x01), r), 2);
  run_ms(1000U);
  ck_assert_uint_ge(frames_seen[0x300], status0 + 9U);
  /* hard reset: the response leaves, then the request to the port */
  ck_assert_int_eq(uds(REQ(0x11, 0x01), r), 2);
  ck_assert_mem_eq(r, ((const uint8_t[]){0x51, 0x01}), 2);
  ck_assert(canfdi_app_reset_requested(&app));
  {
    const int32_t len = canfdi_app_power_down(&app, image, sizeof image);
    ck_assert_int_gt(len, 0);
    ck_assert_int_eq(canfdi_app_power_up(&app, &cal, now_us(), image, (uint32_t)len), CANFDI_OK);
  }
  ck_assert(!canfdi_app_reset_requested(&app));
  ck_assert_uint_eq(canfdi_uds_session(&app.uds), CANFDI_UDS_SESSION_DEFAULT);
  /* suppressed positive response: reset at once */
  run_ms(100U);
  extended();
  expect_silence(PHYS, REQ(0x11, 0x81));
  ck_assert(canfdi_app_reset_requested(&app));
}
END_TEST

/* ------------------------------------------------ NVM image compatibility */

START_TEST(test_image_versions)
{
  static uint8_t dtc_img[CANFDI_DTC_IMAGE_MAX_BYTES];
  int32_t len;
  canfdi_app_default_cal(&cal);
  loop_setup(TPS1_OPEN);
  run_ms(800U);
  /* a bare DTC image (an earlier firmware's) still loads, no attempts */
  len = canfdi_dtc_serialize(canfdi_app_dtc(&app), dtc_img, sizeof dtc_img);
  ck_assert_int_gt(len, 4);
  ck_assert_int_eq(canfdi_app_power_up(&app, &cal, 0U, dtc_img, (uint32_t)len), CANFDI_OK);
  ck_assert_int_ge(canfdi_dtc_find(canfdi_app_dtc(&app), CANFDI_DTC_P0122), 0);
  ck_assert_int_eq(canfdi_dtc_status(canfdi_app_dtc(&app), (uint8_t)canfdi_dtc_find(canfdi_app_dtc(&app),
                                                                                   CANFDI_DTC_P0122)) & 0x20,
                   0x20);
  ck_assert_uint_eq(canfdi_uds_sec_attempts(&app.uds), 0U);
  /* a damaged header is rejected, the memory starts cleared */
  len = canfdi_app_nvm_image(&app, image, sizeof image);
  ck_assert_int_gt(len, 4);
  image[1] = 9U;
  ck_assert_int_eq(canfdi_app_power_up(&app, &cal, 0U, image, (uint32_t)len), CANFDI_APP_IMAGE_REJECTED);
  ck_assert_int_eq(canfdi_app_nvm_image(&app, image, 4U), -CANFDI_ERANGE);
}
END_TEST

/* ------------------------------------------------ ISO-TP error paths */

START_TEST(test_isotp_errors)
{
  uint8_t f[8];
  uint8_t r[512];
  const canfdi_isotp_diag_t *d = &app.uds.tp.diag;
  canfdi_app_default_cal(&cal);
  loop_setup(AT_REST);
  run_ms(20U);
  /* wrong sequence number: reception ends, no response */
  send_raw(PHYS, (const uint8_t[]){0x10, 0x09, 0x22, 0xD1, 0x00, 0xD1, 0x01, 0xD1}, 8U);
  ck_assert(wait_frame(f, 5U));
  ck_assert_uint_eq(f[0], 0x30U);
  send_raw(PHYS, (const uint8_t[]){0x22, 0x02, 0xD1, 0x03, 0xCC, 0xCC, 0xCC, 0xCC}, 8U);
  ck_assert(!wait_frame(f, 30U));
  ck_assert_uint_eq(d->wrong_sn, 1U);
  /* N_Cr: FF, then nothing */
  send_raw(PHYS, (const uint8_t[]){0x10, 0x09, 0x22, 0xD1, 0x00, 0xD1, 0x01, 0xD1}, 8U);
  ck_assert(wait_frame(f, 5U));
  run_ms(cal.uds.tp.n_cr_ms + 5U);
  ck_assert_uint_eq(d->timeout_cr, 1U);
  send_raw(PHYS, (const uint8_t[]){0x21, 0x02, 0xD1, 0x03, 0xCC, 0xCC, 0xCC, 0xCC}, 8U);
  ck_assert(!wait_frame(f, 20U));
  ck_assert_uint_ge(d->unexpected, 1U);
  /* FF longer than the buffer: FC overflow */
  send_raw(PHYS, (const uint8_t[]){0x11, 0x00, 0x22, 0xD1, 0x00, 0xD1, 0x01, 0xD1}, 8U);
  ck_assert(wait_frame(f, 5U));
  ck_assert_uint_eq(f[0], 0x32U);
  ck_assert_uint_eq(d->rx_overflow, 1U);
  /* lengths out of range, short frames, functional multi-frame */
  send_raw(PHYS, (const uint8_t[]){0x00, 0x3E, 0, 0xCC, 0xCC, 0xCC, 0xCC, 0xCC}, 8U);
  send_raw(PHYS, (const uint8_t[]){0x08, 0x3E, 0, 0xCC, 0xCC, 0xCC, 0xCC, 0xCC}, 8U);
  send_raw(PHYS, (const uint8_t[]){0x10, 0x05, 0x22, 0xD1, 0x00, 0xD1, 0x01, 0xD1}, 8U);
  send_raw(PHYS, (const uint8_t[]){0x02, 0x3E, 0x00}, 3U);
  send_raw(FUNC, (const uint8_t[]){0x10, 0x09, 0x22, 0xD1, 0x00, 0xD1, 0x01, 0xD1}, 8U);
  send_raw(PHYS, (const uint8_t[]){0x45, 0x3E, 0, 0xCC, 0xCC, 0xCC, 0xCC, 0xCC}, 8U);
  send_raw(PHYS, (const uint8_t[]){0x30, 0x00, 0x00, 0xCC, 0xCC, 0xCC, 0xCC, 0xCC}, 8U);
  ck_assert(!wait_frame(f, 20U));
  ck_assert_uint_eq(d->bad_length, 3U);
  ck_assert_uint_eq(d->short_frames, 1U);
  ck_assert_uint_eq(d->func_ignored, 1U);
  ck_assert_uint_ge(d->unexpected, 3U);
  /* N_Bs: a long response whose FC never comes */
  send_raw(PHYS, (const uint8_t[]){0x02, 0x19, 0x0A, 0xCC, 0xCC, 0xCC, 0xCC, 0xCC}, 8U);
  ck_assert(wait_frame(f, 5U));
  ck_assert_uint_eq(f[0] >> 4, 1U);
  run_ms(cal.uds.tp.n_bs_ms + 5U);
  ck_assert_uint_eq(d->timeout_bs, 1U);
  ck_assert_int_eq(uds(REQ(0x3E, 0x00), r), 2); /* the server serves again */
  /* FC wait frames: up to the limit accepted, one more ends the transfer */
  send_raw(PHYS, (const uint8_t[]){0x02, 0x19, 0x0A, 0xCC, 0xCC, 0xCC, 0xCC, 0xCC}, 8U);
  ck_assert(wait_frame(f, 5U));
  for (uint32_t k = 0U; k <= cal.uds.tp.wft_max; k++) {
    send_raw(PHYS, (const uint8_t[]){0x31, 0x00, 0x00, 0xCC, 0xCC, 0xCC, 0xCC, 0xCC}, 8U);
    run_ms(5U);
  }
  ck_assert_uint_eq(d->wft_exceeded, 1U);
  /* FC overflow from the tester ends it too */
  send_raw(PHYS, (const uint8_t[]){0x02, 0x19, 0x0A, 0xCC, 0xCC, 0xCC, 0xCC, 0xCC}, 8U);
  ck_assert(wait_frame(f, 5U));
  send_raw(PHYS, (const uint8_t[]){0x32, 0x00, 0x00, 0xCC, 0xCC, 0xCC, 0xCC, 0xCC}, 8U);
  ck_assert(!wait_frame(f, 20U));
  ck_assert_uint_eq(d->tx_aborted, 1U);
  /* the tester's block size and STmin: BS 2, STmin 5 ms */
  send_raw(PHYS, (const uint8_t[]){0x02, 0x19, 0x0A, 0xCC, 0xCC, 0xCC, 0xCC, 0xCC}, 8U);
  ck_assert(wait_frame(f, 5U));
  send_raw(PHYS, (const uint8_t[]){0x30, 0x02, 0x05, 0xCC, 0xCC, 0xCC, 0xCC, 0xCC}, 8U);
  {
    uint32_t t0;
    ck_assert(wait_frame(f, 5U));
    ck_assert_uint_eq(f[0], 0x21U);
    t0 = now_us();
    ck_assert(wait_frame(f, 10U));
    ck_assert_uint_eq(f[0], 0x22U);
    ck_assert_uint_ge(now_us() - t0, 5000U);
    ck_assert(!wait_frame(f, 50U)); /* block done: waits for the next FC */
    send_raw(PHYS, (const uint8_t[]){0x30, 0x00, 0x00, 0xCC, 0xCC, 0xCC, 0xCC, 0xCC}, 8U);
    ck_assert(wait_frame(f, 5U));
    ck_assert_uint_eq(f[0], 0x23U);
  }
  run_ms(100U);
  /* a request while the previous response is still being sent is dropped */
  ck_assert_uint_le(max_frames_per_step, CANFDI_APP_MAX_TX);
}
END_TEST

/* Requests back to back within one step, and during a segmented response:
 * queued and answered one per step, in order; a full queue drops. */
START_TEST(test_back_to_back)
{
  uint8_t f[8];
  const canfdi_isotp_diag_t *d = &app.uds.tp.diag;
  canfdi_app_default_cal(&cal);
  loop_setup(AT_REST);
  run_ms(20U);
  send_raw(FUNC, (const uint8_t[]){0x02, 0x3E, 0x80, 0xCC, 0xCC, 0xCC, 0xCC, 0xCC}, 8U);
  send_raw(PHYS, (const uint8_t[]){0x03, 0x22, 0xD5, 0x09, 0xCC, 0xCC, 0xCC, 0xCC}, 8U);
  ck_assert(wait_frame(f, 5U));
  ck_assert_mem_eq(f, ((const uint8_t[]){0x04, 0x62, 0xD5, 0x09, 0x00}), 5);
  /* a long response in flight: the next request waits for it */
  send_raw(PHYS, (const uint8_t[]){0x02, 0x19, 0x0A, 0xCC, 0xCC, 0xCC, 0xCC, 0xCC}, 8U);
  ck_assert(wait_frame(f, 5U));
  ck_assert_uint_eq(f[0] >> 4, 1U);
  send_raw(PHYS, (const uint8_t[]){0x02, 0x3E, 0x00, 0xCC, 0xCC, 0xCC, 0xCC, 0xCC}, 8U);
  send_raw(PHYS, (const uint8_t[]){0x30, 0x00, 0x00, 0xCC, 0xCC, 0xCC, 0xCC, 0xCC}, 8U);
  /* 0x59 0x0A, the availability mask and 4 bytes per DTC: the first frame
   * carries 6 of them, each consecutive frame 7 */
  for (uint32_t k = 0U; k < ((3U + 4U * CANFDI_DTC_COUNT) - 6U + 6U) / 7U; k++) {
    ck_assert(wait_frame(f, 5U));
    ck_assert_uint_eq(f[0], 0x20U | ((k + 1U) & 0x0FU));
  }
  ck_assert(wait_frame(f, 5U));
  ck_assert_mem_eq(f, ((const uint8_t[]){0x02, 0x7E, 0x00}), 3);
  /* more single frames in one step than the queue holds */
  for (uint32_t k = 0U; k <= CANFDI_CFG_ISOTP_SF_QUEUE; k++) {
    send_raw(PHYS, (const uint8_t[]){0x02, 0x3E, 0x00, 0xCC, 0xCC, 0xCC, 0xCC, 0xCC}, 8U);
  }
  ck_assert_uint_eq(d->busy_dropped, 1U);
  for (uint32_t k = 0U; k < CANFDI_CFG_ISOTP_SF_QUEUE; k++) {
    ck_assert(wait_frame(f, 5U));
    ck_assert_uint_eq(f[1], 0x7EU);
  }
  ck_assert(!wait_frame(f, 20U));
}
END_TEST

/* The transport's own argument checks and a CAN FD-length escape. */
START_TEST(test_isotp_api)
{
  canfdi_isotp_t t;
  canfdi_isotp_cfg_t c;
  uint8_t f[CANFDI_CFG_ISOTP_FRAME_BYTES];
  const uint8_t *msg = NULL;
  bool fn = true;
  canfdi_isotp_default_cfg(&c);
  c.stmin = 0x80U;
  ck_assert_int_eq(canfdi_isotp_init(&t, &c), -CANFDI_EINVAL);
  canfdi_isotp_default_cfg(&c);
  c.n_cr_ms = 0U;
  ck_assert_int_eq(canfdi_isotp_init(&t, &c), -CANFDI_EINVAL);
  canfdi_isotp_default_cfg(&c);
  ck_assert_int_eq(canfdi_isotp_init(NULL, &c), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_isotp_init(&t, &c), CANFDI_OK);
  ck_assert_int_eq(canfdi_isotp_rx_can(&t, false, NULL, 8U), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_isotp_send(&t, 0U), -CANFDI_ERANGE);
  ck_assert_int_eq(canfdi_isotp_send(&t, CANFDI_CFG_ISOTP_TX_BYTES + 1U), -CANFDI_ERANGE);
  ck_assert_int_eq(canfdi_isotp_step(&t, f), 0);
  ck_assert_uint_eq(canfdi_isotp_rx_peek(&t, &msg, &fn), 0U);
  canfdi_isotp_rx_release(&t);
  /* a 7-byte single frame, padded */
  canfdi_isotp_tx_buf(&t)[0] = 0x62U;
  for (uint32_t k = 1U; k < 7U; k++) {
    canfdi_isotp_tx_buf(&t)[k] = (uint8_t)k;
  }
  ck_assert_int_eq(canfdi_isotp_send(&t, 7U), CANFDI_OK);
  ck_assert_ptr_null(canfdi_isotp_tx_buf(&t));
  ck_assert_int_eq(canfdi_isotp_send(&t, 7U), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_isotp_step(&t, f), 1);
  ck_assert_uint_eq(f[0], 0x07U);
  ck_assert(!canfdi_isotp_tx_busy(&t));
  /* 8 bytes: FF + one CF */
  ck_assert_int_eq(canfdi_isotp_send(&t, 8U), CANFDI_OK);
  ck_assert_int_eq(canfdi_isotp_step(&t, f), 1);
  ck_assert_uint_eq(f[0], 0x10U);
  ck_assert_uint_eq(f[1], 0x08U);
  canfdi_isotp_reset(&t);
  ck_assert(!canfdi_isotp_tx_busy(&t));
}
END_TEST

static Suite *make_suite(void)
{
  Suite *s = suite_create("uds");
  TCase *tc = tcase_create("conformance");
  tcase_set_timeout(tc, 600);
  tcase_add_test(tc, test_isotp_api);
  tcase_add_test(tc, test_session_control);
  tcase_add_test(tc, test_security_access);
  tcase_add_test(tc, test_security_levels);
  tcase_add_test(tc, test_key_function);
  tcase_add_test(tc, test_read_dtc_information);
  tcase_add_test(tc, test_clear_dtc);
  tcase_add_test(tc, test_read_data);
  tcase_add_test(tc, test_io_control);
  tcase_add_test(tc, test_io_control_session_end);
  tcase_add_test(tc, test_routines);
  tcase_add_test(tc, test_spring_weak);
  tcase_add_test(tc, test_ecu_reset_and_comm_control);
  tcase_add_test(tc, test_image_versions);
  tcase_add_test(tc, test_isotp_errors);
  tcase_add_test(tc, test_back_to_back);
  suite_add_tcase(s, tc);
  return s;
}

CANFDI_UNIT_MAIN(make_suite)
