/*
 * test_e2e.c — CRC-8 SAE J1850 and the E2E protect/check state machine.
 *
 * Reference values: the check value and the seven buffer vectors are the
 * published CRC-8 SAE J1850 examples (AUTOSAR CRC library specification);
 * the frame vectors were computed with Python crccheck.crc.Crc8SaeJ1850 over
 * [id low, id high, bytes 1..7]. tests/dbc/test_e2e_py.py checks the same
 * frame vectors against crccheck and tools/canfdi/e2e.py, and compares this
 * C implementation with crccheck on random frames.
 */
#include <check.h>
#include <string.h>

#include "comm/canfdi_e2e.h"
#include "unit_main.h"

/* Independent bitwise reference, written from the polynomial definition
 * (not from the module), to validate the 256-entry table. */
static uint8_t ref_crc8(const uint8_t *d, size_t n)
{
  unsigned reg = 0xFFU;
  for (size_t i = 0U; i < n; i++) {
    for (int b = 7; b >= 0; b--) {
      const unsigned in = ((unsigned)d[i] >> (unsigned)b) & 1U;
      const unsigned top = (reg >> 7) & 1U;
      reg = (reg << 1) & 0xFFU;
      if ((top ^ in) != 0U) {
        reg ^= 0x1DU;
      }
    }
  }
  return (uint8_t)(reg ^ 0xFFU);
}

static uint32_t lcg_state;
static uint8_t lcg_byte(void)
{
  lcg_state = lcg_state * 1664525U + 1013904223U;
  return (uint8_t)(lcg_state >> 24);
}

/* ---------------------------------------------------------------- crc ---- */

START_TEST(test_check_value)
{
  const uint8_t s[] = "123456789";
  ck_assert_uint_eq(canfdi_e2e_crc8(s, 9U), 0x4BU);
}
END_TEST

static const struct {
  const char *hex;
  uint8_t crc;
} buffer_vectors[] = {
  {"00000000", 0x59U}, {"F20183", 0x37U}, {"0FAA0055", 0x79U}, {"00FF5511", 0xB8U},
  {"332255AABBCCDDEEFF", 0xCBU}, {"926B55", 0x8CU}, {"FFFFFFFF", 0x74U},
};

static size_t from_hex(const char *hex, uint8_t *out, size_t cap)
{
  size_t n = strlen(hex) / 2U;
  ck_assert_uint_le(n, cap);
  for (size_t i = 0U; i < n; i++) {
    unsigned v = 0U;
    for (size_t k = 0U; k < 2U; k++) {
      const char c = hex[2U * i + k];
      const unsigned nib = (c <= '9') ? (unsigned)(c - '0') : (unsigned)(c - 'A' + 10);
      v = (v << 4) | nib;
    }
    out[i] = (uint8_t)v;
  }
  return n;
}

START_TEST(test_buffer_vectors)
{
  uint8_t buf[16];
  const size_t n = from_hex(buffer_vectors[_i].hex, buf, sizeof buf);
  ck_assert_uint_eq(canfdi_e2e_crc8(buf, n), buffer_vectors[_i].crc);
}
END_TEST

START_TEST(test_table_matches_bitwise_reference)
{
  /* Random lengths 0..16 cover every table entry many times over. */
  lcg_state = 12345U;
  for (unsigned trial = 0U; trial < 20000U; trial++) {
    uint8_t buf[16];
    const size_t n = (size_t)(lcg_byte() % 17U);
    for (size_t i = 0U; i < n; i++) {
      buf[i] = lcg_byte();
    }
    ck_assert_uint_eq(canfdi_e2e_crc8(buf, n), ref_crc8(buf, n));
  }
}
END_TEST

START_TEST(test_update_is_incremental)
{
  const uint8_t s[] = "123456789";
  for (size_t split = 0U; split <= 9U; split++) {
    uint8_t reg = canfdi_e2e_crc8_update(CANFDI_E2E_CRC_INIT, s, split);
    reg = canfdi_e2e_crc8_update(reg, &s[split], 9U - split);
    ck_assert_uint_eq((uint8_t)(reg ^ CANFDI_E2E_CRC_XOROUT), 0x4BU);
  }
}
END_TEST

static const struct {
  uint16_t id;
  const char *payload_hex; /* bytes 1..7 */
  uint8_t crc;
} frame_vectors[] = {
  {0x010U, "7942BDF22106F0", 0x01U}, {0x011U, "847762F0F3CB4D", 0x13U},
  {0x020U, "764DC707205115", 0x47U}, {0x021U, "9A0F89F2C6DACA", 0x50U},
  {0x7E8U, "00000000000000", 0x47U}, {0x123U, "0102030405060F", 0x16U},
  {0x321U, "0102030405060F", 0x62U},
};

START_TEST(test_frame_vectors)
{
  uint8_t frame[8] = {0xA5U}; /* byte 0 must not be read */
  (void)from_hex(frame_vectors[_i].payload_hex, &frame[1], 7U);
  ck_assert_uint_eq(canfdi_e2e_frame_crc(frame_vectors[_i].id, frame, 8U), frame_vectors[_i].crc);
  frame[0] = 0x5AU;
  ck_assert_uint_eq(canfdi_e2e_frame_crc(frame_vectors[_i].id, frame, 8U), frame_vectors[_i].crc);
}
END_TEST

/* ------------------------------------------------------------ protect ---- */

START_TEST(test_protect_layout_and_wrap)
{
  canfdi_e2e_tx_t tx;
  canfdi_e2e_tx_init(&tx, 0x011U);
  for (unsigned k = 0U; k < 40U; k++) {
    uint8_t frame[8] = {0x00U, 0xB7U, 1U, 2U, 3U, 4U, 5U, (uint8_t)k};
    ck_assert_int_eq(canfdi_e2e_protect(&tx, frame, 8U), CANFDI_OK);
    ck_assert_uint_eq(frame[1] & 0x0FU, k % 16U);     /* counter wraps 15 -> 0 */
    ck_assert_uint_eq(frame[1] & 0xF0U, 0xB0U);       /* payload nibble kept */
    ck_assert_uint_eq(frame[7], (uint8_t)k);          /* payload kept */
    ck_assert_uint_eq(frame[0], ref_crc8((const uint8_t[]){0x11U, 0x00U, frame[1], 1U, 2U, 3U, 4U, 5U, (uint8_t)k}, 9U));
  }
}
END_TEST

START_TEST(test_protect_rejects_bad_args)
{
  canfdi_e2e_tx_t tx;
  canfdi_e2e_tx_init(&tx, 0x020U);
  uint8_t frame[8] = {1U, 2U, 3U, 4U, 5U, 6U, 7U, 8U};
  const uint8_t copy[8] = {1U, 2U, 3U, 4U, 5U, 6U, 7U, 8U};
  ck_assert_int_eq(canfdi_e2e_protect(&tx, frame, 7U), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_e2e_protect(&tx, NULL, 8U), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_e2e_protect(NULL, frame, 8U), -CANFDI_EINVAL);
  ck_assert_mem_eq(frame, copy, 8U);
  ck_assert_uint_eq(tx.counter, 0U);
}
END_TEST

/* -------------------------------------------------------------- check ---- */

START_TEST(test_rx_init_domain)
{
  canfdi_e2e_rx_t rx;
  ck_assert_int_eq(canfdi_e2e_rx_init(&rx, 0x10U, 0U), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_e2e_rx_init(&rx, 0x10U, 16U), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_e2e_rx_init(NULL, 0x10U, 1U), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_e2e_rx_init(&rx, 0x10U, 15U), CANFDI_OK);
  ck_assert_int_eq(canfdi_e2e_check(NULL, NULL, 0U), -CANFDI_EINVAL);
}
END_TEST

/* Builds a correctly protected frame with the given counter. */
static void make_frame(uint16_t id, uint8_t counter, uint8_t fill, uint8_t frame[8])
{
  canfdi_e2e_tx_t tx;
  canfdi_e2e_tx_init(&tx, id);
  tx.counter = counter;
  for (size_t i = 1U; i < 8U; i++) {
    frame[i] = (uint8_t)(fill + i);
  }
  ck_assert_int_eq(canfdi_e2e_protect(&tx, frame, 8U), CANFDI_OK);
}

/* One step of a scripted receive sequence. */
typedef enum { EV_FRAME, EV_BAD_CRC, EV_SHORT, EV_NONE, EV_OTHER_ID } ev_kind_t;
typedef struct {
  ev_kind_t kind;
  uint8_t counter;
  int status;
  uint8_t lost;
} step_t;

#define STEPS_MAX 12
static const struct {
  uint8_t max_delta;
  step_t steps[STEPS_MAX];
  size_t n;
} scripts[] = {
  /* in-order stream across the wrap */
  {1U, {{EV_FRAME, 14U, CANFDI_E2E_INITIAL, 0U}, {EV_FRAME, 15U, CANFDI_E2E_OK, 0U},
        {EV_FRAME, 0U, CANFDI_E2E_OK, 0U}, {EV_FRAME, 1U, CANFDI_E2E_OK, 0U}}, 4U},
  /* repeated frames are rejected and do not move the state */
  {1U, {{EV_FRAME, 3U, CANFDI_E2E_INITIAL, 0U}, {EV_FRAME, 3U, CANFDI_E2E_REPEATED, 0U},
        {EV_FRAME, 3U, CANFDI_E2E_REPEATED, 0U}, {EV_FRAME, 4U, CANFDI_E2E_OK, 0U}}, 4U},
  /* a loss within max_delta is usable and counted, across the wrap */
  {3U, {{EV_FRAME, 13U, CANFDI_E2E_INITIAL, 0U}, {EV_FRAME, 15U, CANFDI_E2E_OK_SOME_LOST, 1U},
        {EV_FRAME, 2U, CANFDI_E2E_OK_SOME_LOST, 2U}, {EV_FRAME, 3U, CANFDI_E2E_OK, 0U},
        {EV_FRAME, 7U, CANFDI_E2E_WRONG_SEQUENCE, 3U}, {EV_FRAME, 8U, CANFDI_E2E_OK, 0U}}, 6U},
  /* a jump beyond max_delta resynchronises on the received counter */
  {1U, {{EV_FRAME, 0U, CANFDI_E2E_INITIAL, 0U}, {EV_FRAME, 2U, CANFDI_E2E_WRONG_SEQUENCE, 1U},
        {EV_FRAME, 3U, CANFDI_E2E_OK, 0U}, {EV_FRAME, 2U, CANFDI_E2E_WRONG_SEQUENCE, 14U},
        {EV_FRAME, 3U, CANFDI_E2E_OK, 0U}}, 5U},
  /* CRC, length, wrong data ID and missing frames keep the state */
  {1U, {{EV_BAD_CRC, 5U, CANFDI_E2E_WRONG_CRC, 0U}, {EV_FRAME, 5U, CANFDI_E2E_INITIAL, 0U},
        {EV_BAD_CRC, 6U, CANFDI_E2E_WRONG_CRC, 0U}, {EV_SHORT, 6U, CANFDI_E2E_WRONG_LENGTH, 0U},
        {EV_OTHER_ID, 6U, CANFDI_E2E_WRONG_CRC, 0U}, {EV_NONE, 0U, CANFDI_E2E_NO_NEW_DATA, 0U},
        {EV_FRAME, 6U, CANFDI_E2E_OK, 0U}}, 7U},
};

START_TEST(test_scripted_sequences)
{
  canfdi_e2e_rx_t rx;
  const uint16_t id = 0x010U;
  uint32_t expected_count[CANFDI_E2E_STATUS_COUNT] = {0U};
  ck_assert_int_eq(canfdi_e2e_rx_init(&rx, id, scripts[_i].max_delta), CANFDI_OK);
  for (size_t s = 0U; s < scripts[_i].n; s++) {
    const step_t *st = &scripts[_i].steps[s];
    uint8_t frame[8];
    int got;
    make_frame((st->kind == EV_OTHER_ID) ? (uint16_t)(id + 1U) : id, st->counter, (uint8_t)s, frame);
    if (st->kind == EV_BAD_CRC) {
      frame[0] = (uint8_t)(frame[0] ^ 0x01U);
    }
    if (st->kind == EV_NONE) {
      got = canfdi_e2e_check(&rx, NULL, 0U);
    } else {
      got = canfdi_e2e_check(&rx, frame, (st->kind == EV_SHORT) ? 7U : 8U);
    }
    ck_assert_msg(got == st->status, "script %d step %zu: status %d, want %d", _i, s, got, st->status);
    expected_count[st->status]++;
    if (canfdi_e2e_status_is_usable(got) || got == CANFDI_E2E_WRONG_SEQUENCE) {
      ck_assert_uint_eq(rx.lost, st->lost);
    }
  }
  for (size_t k = 0U; k < (size_t)CANFDI_E2E_STATUS_COUNT; k++) {
    ck_assert_uint_eq(rx.diag.status[k], expected_count[k]);
  }
}
END_TEST

/* Every counter step d = 1..15 against every max_delta = 1..15. */
START_TEST(test_all_deltas)
{
  const uint8_t max_delta = (uint8_t)(_i + 1);
  for (uint8_t d = 1U; d < 16U; d++) {
    canfdi_e2e_rx_t rx;
    uint8_t frame[8];
    ck_assert_int_eq(canfdi_e2e_rx_init(&rx, 0x021U, max_delta), CANFDI_OK);
    make_frame(0x021U, 9U, 0U, frame);
    ck_assert_int_eq(canfdi_e2e_check(&rx, frame, 8U), CANFDI_E2E_INITIAL);
    make_frame(0x021U, (uint8_t)((9U + d) & 15U), 1U, frame);
    const int want = (d == 1U) ? CANFDI_E2E_OK
                     : (d <= max_delta) ? CANFDI_E2E_OK_SOME_LOST
                                        : CANFDI_E2E_WRONG_SEQUENCE;
    ck_assert_int_eq(canfdi_e2e_check(&rx, frame, 8U), want);
    ck_assert_uint_eq(rx.lost, d - 1U);
    ck_assert_uint_eq(rx.diag.lost_frames, d - 1U);
  }
}
END_TEST

START_TEST(test_every_single_bit_flip_detected)
{
  for (unsigned bit = 0U; bit < 64U; bit++) {
    canfdi_e2e_rx_t rx;
    uint8_t frame[8];
    ck_assert_int_eq(canfdi_e2e_rx_init(&rx, 0x011U, 1U), CANFDI_OK);
    make_frame(0x011U, 4U, 0x30U, frame);
    ck_assert_int_eq(canfdi_e2e_check(&rx, frame, 8U), CANFDI_E2E_INITIAL);
    make_frame(0x011U, 5U, 0x31U, frame);
    frame[bit / 8U] = (uint8_t)(frame[bit / 8U] ^ (1U << (bit % 8U)));
    ck_assert_int_eq(canfdi_e2e_check(&rx, frame, 8U), CANFDI_E2E_WRONG_CRC);
    ck_assert_uint_eq(rx.last_counter, 4U);
  }
}
END_TEST

START_TEST(test_protect_then_check_stream)
{
  canfdi_e2e_tx_t tx;
  canfdi_e2e_rx_t rx;
  canfdi_e2e_tx_init(&tx, 0x020U);
  ck_assert_int_eq(canfdi_e2e_rx_init(&rx, 0x020U, 1U), CANFDI_OK);
  for (unsigned k = 0U; k < 100U; k++) {
    uint8_t frame[8] = {0U, (uint8_t)(k << 4), (uint8_t)k, 0U, 0U, 0U, 0U, 0xFFU};
    ck_assert_int_eq(canfdi_e2e_protect(&tx, frame, 8U), CANFDI_OK);
    ck_assert_int_eq(canfdi_e2e_check(&rx, frame, 8U), (k == 0U) ? CANFDI_E2E_INITIAL : CANFDI_E2E_OK);
  }
  ck_assert_uint_eq(rx.diag.status[CANFDI_E2E_OK], 99U);
  ck_assert_uint_eq(rx.diag.lost_frames, 0U);
}
END_TEST

START_TEST(test_diag_counters_saturate)
{
  canfdi_e2e_rx_t rx;
  ck_assert_int_eq(canfdi_e2e_rx_init(&rx, 0x010U, 1U), CANFDI_OK);
  rx.diag.status[CANFDI_E2E_NO_NEW_DATA] = UINT32_MAX - 1U;
  for (unsigned k = 0U; k < 3U; k++) {
    ck_assert_int_eq(canfdi_e2e_check(&rx, NULL, 0U), CANFDI_E2E_NO_NEW_DATA);
  }
  ck_assert_uint_eq(rx.diag.status[CANFDI_E2E_NO_NEW_DATA], UINT32_MAX);
  rx.diag.lost_frames = UINT32_MAX - 2U;
  uint8_t frame[8];
  make_frame(0x010U, 0U, 0U, frame);
  (void)canfdi_e2e_check(&rx, frame, 8U);
  make_frame(0x010U, 10U, 0U, frame);
  ck_assert_int_eq(canfdi_e2e_check(&rx, frame, 8U), CANFDI_E2E_WRONG_SEQUENCE);
  ck_assert_uint_eq(rx.diag.lost_frames, UINT32_MAX);
}
END_TEST

START_TEST(test_usable_statuses)
{
  for (int s = -CANFDI_EINVAL; s < (int)CANFDI_E2E_STATUS_COUNT; s++) {
    const bool want = (s == CANFDI_E2E_OK) || (s == CANFDI_E2E_OK_SOME_LOST) || (s == CANFDI_E2E_INITIAL);
    ck_assert(canfdi_e2e_status_is_usable(s) == want);
  }
}
END_TEST

static Suite *make_suite(void)
{
  Suite *s = suite_create("e2e");
  TCase *tc = tcase_create("crc");
  tcase_add_test(tc, test_check_value);
  tcase_add_loop_test(tc, test_buffer_vectors, 0, (int)(sizeof buffer_vectors / sizeof buffer_vectors[0]));
  tcase_add_test(tc, test_table_matches_bitwise_reference);
  tcase_add_test(tc, test_update_is_incremental);
  tcase_add_loop_test(tc, test_frame_vectors, 0, (int)(sizeof frame_vectors / sizeof frame_vectors[0]));
  suite_add_tcase(s, tc);

  tc = tcase_create("protect");
  tcase_add_test(tc, test_protect_layout_and_wrap);
  tcase_add_test(tc, test_protect_rejects_bad_args);
  suite_add_tcase(s, tc);

  tc = tcase_create("check");
  tcase_add_test(tc, test_rx_init_domain);
  tcase_add_loop_test(tc, test_scripted_sequences, 0, (int)(sizeof scripts / sizeof scripts[0]));
  tcase_add_loop_test(tc, test_all_deltas, 0, 15);
  tcase_add_test(tc, test_every_single_bit_flip_detected);
  tcase_add_test(tc, test_protect_then_check_stream);
  tcase_add_test(tc, test_diag_counters_saturate);
  tcase_add_test(tc, test_usable_statuses);
  suite_add_tcase(s, tc);
  return s;
}

CANFDI_UNIT_MAIN(make_suite)
