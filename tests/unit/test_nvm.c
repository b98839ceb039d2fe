/*
 * test_nvm.c — unit tests of firmware/diag/canfdi_nvm (two-bank power-fail
 * safe storage) and of its host port firmware/port/linux/canfdi_nvm_file.
 *
 * The power-loss tests use a RAM fake of the port that behaves like NOR
 * flash (erase -> 0xFF, programming only clears bits, a byte programmed
 * twice without an erase is counted as a violation) and "loses power" after
 * exactly k byte operations (bytes erased or programmed): the byte being
 * worked on at that moment is torn (half programmed / half erased) and
 * every later call fails. For EVERY k from 0 to the number of byte
 * operations of one complete update, a fresh device holding the old image
 * is updated, cut at k, "rebooted" (new instance, power back) and loaded:
 * the result must be byte for byte the old or the new payload, switching
 * from old to new exactly where the commit word is complete.
 */
#include <check.h>
#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "diag/canfdi_dtc.h"
#include "diag/canfdi_nvm.h"
#include "port/linux/canfdi_nvm_file.h"
#include "unit_main.h"

/* ------------------------------------------------------------ fake port */

#define FAKE_BANK 1024U

typedef struct {
  uint8_t mem[2][FAKE_BANK];
  canfdi_nvm_port_t port;
  long budget;          /* byte operations left before power loss; < 0: none */
  bool dead;            /* power lost: every call fails */
  unsigned long ops;    /* byte operations done (erase + program) */
  unsigned violations;  /* bytes programmed while not erased */
  unsigned misaligned;  /* writes violating write_unit */
  unsigned writes, erases, reads;
  int fail_reads_after; /* inject a read error after this many reads; < 0 off */
  uint8_t torn_mask;    /* bits of a torn program that stay 1 */
  unsigned zero_write_call; /* this write call (1-based) programs its first byte to 0 */
} fake_t;

static fake_t fk;
static fake_t fk_saved;

/* Consume one byte operation; false when power is lost on this one. */
static bool fake_tick(fake_t *f)
{
  bool ok = !f->dead;
  if (ok && (f->budget == 0)) {
    f->dead = true;
    ok = false;
  } else if (ok) {
    if (f->budget > 0) {
      f->budget--;
    }
    f->ops++;
  }
  return ok;
}

static int32_t fake_read(void *ctx, uint8_t bank, uint32_t off, uint8_t *buf, uint32_t len)
{
  fake_t *f = (fake_t *)ctx;
  ck_assert_uint_lt(bank, 2U);
  ck_assert_uint_le(off, FAKE_BANK);
  ck_assert_uint_le(len, FAKE_BANK - off); /* the module never reads out of a bank */
  f->reads++;
  if ((f->fail_reads_after >= 0) && (f->reads > (unsigned)f->fail_reads_after)) {
    return -CANFDI_EIO;
  }
  if (f->dead) {
    return -CANFDI_EIO;
  }
  memcpy(buf, &f->mem[bank][off], len);
  return CANFDI_OK;
}

static int32_t fake_write(void *ctx, uint8_t bank, uint32_t off, const uint8_t *buf, uint32_t len)
{
  fake_t *f = (fake_t *)ctx;
  ck_assert_uint_lt(bank, 2U);
  ck_assert_uint_le(off, FAKE_BANK);
  ck_assert_uint_le(len, FAKE_BANK - off);
  f->writes++;
  if (((off % f->port.write_unit) != 0U) || ((len % f->port.write_unit) != 0U) || (len == 0U)) {
    f->misaligned++;
    return -CANFDI_EINVAL;
  }
  for (uint32_t i = 0U; i < len; i++) {
    uint8_t *cell = &f->mem[bank][off + i];
    const bool was_dead = f->dead;
    if (!fake_tick(f)) {
      if (!was_dead) {
        /* torn: some of the bits to clear are cleared, the others stay 1 */
        *cell = (uint8_t)(*cell & (buf[i] | f->torn_mask));
      }
      return -CANFDI_EIO;
    }
    if (*cell != 0xFFU) {
      f->violations++;
    }
    const bool flaky = (i == 0U) && (f->writes == f->zero_write_call);
    *cell = (uint8_t)(*cell & (flaky ? 0U : buf[i]));
  }
  return CANFDI_OK;
}

static int32_t fake_erase(void *ctx, uint8_t bank)
{
  fake_t *f = (fake_t *)ctx;
  ck_assert_uint_lt(bank, 2U);
  f->erases++;
  for (uint32_t i = 0U; i < f->port.bank_bytes; i++) {
    const bool was_dead = f->dead;
    if (!fake_tick(f)) {
      if (!was_dead) {
        f->mem[bank][i] = (uint8_t)(f->mem[bank][i] ^ 0x5AU); /* torn: garbage */
      }
      return -CANFDI_EIO;
    }
    f->mem[bank][i] = 0xFFU;
  }
  return CANFDI_OK;
}

static void fake_reset(fake_t *f, uint8_t unit, uint32_t bank_bytes)
{
  memset(f, 0, sizeof *f);
  memset(f->mem, 0xFF, sizeof f->mem);
  f->port.ctx = f;
  f->port.read = fake_read;
  f->port.write = fake_write;
  f->port.erase = fake_erase;
  f->port.bank_bytes = bank_bytes;
  f->port.write_unit = unit;
  f->budget = -1;
  f->fail_reads_after = -1;
  f->torn_mask = 0xF0U;
}

/* Power back on after a cut (memory kept). */
static void fake_reboot(fake_t *f)
{
  f->dead = false;
  f->budget = -1;
}

/* ------------------------------------------------------------ payloads */

static uint8_t pay_a[600];
static uint8_t pay_b[600];
static uint8_t pay_c[600];
static uint8_t out[1024];

static void fill(uint8_t *p, size_t n, uint32_t seed)
{
  uint32_t s = seed;
  for (size_t i = 0U; i < n; i++) {
    s = s * 1103515245U + 12345U;
    p[i] = (uint8_t)(s >> 16);
  }
}

static void setup_payloads(void)
{
  fill(pay_a, sizeof pay_a, 1U);
  fill(pay_b, sizeof pay_b, 2U);
  fill(pay_c, sizeof pay_c, 3U);
}

/* ------------------------------------------------------------ CRC */

static uint32_t crc32_bitwise(const uint8_t *d, size_t n)
{
  uint32_t c = 0xFFFFFFFFU;
  for (size_t i = 0U; i < n; i++) {
    c ^= d[i];
    for (int b = 0; b < 8; b++) {
      c = (c & 1U) ? ((c >> 1) ^ 0xEDB88320U) : (c >> 1);
    }
  }
  return c ^ 0xFFFFFFFFU;
}

START_TEST(test_crc32_check_value)
{
  /* the published check value of CRC-32/ISO-HDLC (zlib, IEEE 802.3) */
  ck_assert_uint_eq(canfdi_nvm_crc32((const uint8_t *)"123456789", 9U), 0xCBF43926U);
  ck_assert_uint_eq(canfdi_nvm_crc32(NULL, 0U), 0x00000000U);
}
END_TEST

START_TEST(test_crc32_matches_bitwise_and_is_incremental)
{
  uint8_t buf[300];
  fill(buf, sizeof buf, 77U);
  for (uint32_t n = 0U; n <= sizeof buf; n++) {
    ck_assert_uint_eq(canfdi_nvm_crc32(buf, n), crc32_bitwise(buf, n));
  }
  for (uint32_t cut = 0U; cut <= sizeof buf; cut += 37U) {
    uint32_t c = canfdi_nvm_crc32_update(0xFFFFFFFFU, buf, cut);
    c = canfdi_nvm_crc32_update(c, buf + cut, (uint32_t)sizeof buf - cut) ^ 0xFFFFFFFFU;
    ck_assert_uint_eq(c, crc32_bitwise(buf, sizeof buf));
  }
}
END_TEST

/* ------------------------------------------------------------ basics */

static canfdi_nvm_t nvm;

START_TEST(test_init_rejects)
{
  fake_reset(&fk, 1U, FAKE_BANK);
  ck_assert_int_eq(canfdi_nvm_init(&nvm, &fk.port), CANFDI_OK);
  ck_assert_int_eq(canfdi_nvm_init(NULL, &fk.port), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_nvm_init(&nvm, NULL), -CANFDI_EINVAL);
  const uint8_t units[] = {0U, 3U, 6U, 12U, 32U};
  for (size_t i = 0U; i < sizeof units; i++) {
    fk.port.write_unit = units[i];
    ck_assert_int_eq(canfdi_nvm_init(&nvm, &fk.port), -CANFDI_EINVAL);
    ck_assert_int_eq(canfdi_nvm_store(&nvm, pay_a, 4U), -CANFDI_EINVAL); /* unbound */
  }
  fk.port.write_unit = 1U;
  fk.port.read = NULL;
  ck_assert_int_eq(canfdi_nvm_init(&nvm, &fk.port), -CANFDI_EINVAL);
  fake_reset(&fk, 8U, FAKE_BANK);
  /* smallest bank: header 16 + crc unit 8 + commit unit 8 */
  fk.port.bank_bytes = 31U;
  ck_assert_int_eq(canfdi_nvm_init(&nvm, &fk.port), -CANFDI_EINVAL);
  fk.port.bank_bytes = 32U;
  ck_assert_int_eq(canfdi_nvm_init(&nvm, &fk.port), CANFDI_OK);
  ck_assert_int_eq(canfdi_nvm_store(&nvm, pay_a, 0U), CANFDI_OK);
  ck_assert_int_eq(canfdi_nvm_store(&nvm, pay_a, 1U), -CANFDI_ERANGE);
  ck_assert_int_eq(canfdi_nvm_load(&nvm, out, sizeof out), 0);
}
END_TEST

START_TEST(test_store_load_alternates_banks)
{
  const uint8_t unit = (uint8_t)(1U << _i); /* 1, 2, 4, 8, 16 */
  fake_reset(&fk, unit, FAKE_BANK);
  ck_assert_int_eq(canfdi_nvm_init(&nvm, &fk.port), CANFDI_OK);
  /* a new device: no image, both banks empty */
  ck_assert_int_eq(canfdi_nvm_load(&nvm, out, sizeof out), -CANFDI_ENODATA);
  ck_assert_uint_eq(nvm.bank_state[0], CANFDI_NVM_BANK_EMPTY);
  ck_assert_uint_eq(nvm.bank_state[1], CANFDI_NVM_BANK_EMPTY);
  const uint32_t lens[] = {0U, 1U, 5U, 17U, 333U, 600U};
  int expect_bank = 0;
  for (size_t k = 0U; k < 3U * (sizeof lens / sizeof lens[0]); k++) {
    const uint32_t len = lens[k % (sizeof lens / sizeof lens[0])];
    const uint8_t *src = (k % 2U) ? pay_a : pay_b;
    ck_assert_int_eq(canfdi_nvm_store(&nvm, src, len), CANFDI_OK);
    ck_assert_int_eq(nvm.current, expect_bank);
    ck_assert_uint_eq(nvm.seq, (uint32_t)k + 1U);
    /* a fresh instance (a reboot) sees the same */
    canfdi_nvm_t n2;
    ck_assert_int_eq(canfdi_nvm_init(&n2, &fk.port), CANFDI_OK);
    memset(out, 0xA5, sizeof out);
    ck_assert_int_eq(canfdi_nvm_load(&n2, out, sizeof out), (int32_t)len);
    ck_assert_mem_eq(out, src, len);
    ck_assert_int_eq(n2.current, expect_bank);
    ck_assert_uint_eq(n2.seq, (uint32_t)k + 1U);
    if (k > 0U) {
      ck_assert_uint_eq(n2.bank_state[0], CANFDI_NVM_BANK_VALID);
      ck_assert_uint_eq(n2.bank_state[1], CANFDI_NVM_BANK_VALID);
    }
    /* the footprint is what the header says */
    ck_assert_uint_le(CANFDI_NVM_FOOTPRINT(len, unit), FAKE_BANK);
    for (uint32_t i = CANFDI_NVM_FOOTPRINT(len, unit); i < FAKE_BANK; i++) {
      ck_assert_uint_eq(fk.mem[expect_bank][i], 0xFFU);
    }
    expect_bank = 1 - expect_bank;
  }
  ck_assert_uint_eq(fk.violations, 0U);
  ck_assert_uint_eq(fk.misaligned, 0U);
  /* too big: nothing written */
  const unsigned w = fk.writes;
  const unsigned e = fk.erases;
  ck_assert_int_eq(canfdi_nvm_store(&nvm, pay_a, FAKE_BANK), -CANFDI_ERANGE);
  ck_assert_int_eq(canfdi_nvm_store(&nvm, pay_a, FAKE_BANK - 16U - 8U + 1U), -CANFDI_ERANGE);
  ck_assert_uint_eq(fk.writes, w);
  ck_assert_uint_eq(fk.erases, e);
  /* a buffer too small for the image */
  ck_assert_int_eq(canfdi_nvm_store(&nvm, pay_a, 100U), CANFDI_OK);
  ck_assert_int_eq(canfdi_nvm_load(&nvm, out, 99U), -CANFDI_ERANGE);
  ck_assert_uint_eq(nvm.len, 100U);
  ck_assert_int_eq(canfdi_nvm_load(&nvm, NULL, 10U), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_nvm_store(&nvm, NULL, 10U), -CANFDI_EINVAL);
}
END_TEST

/* ------------------------------------------------------------ power loss */

typedef struct {
  uint8_t unit;
  int history;   /* images stored before the update: 0, 1 or 2 */
  uint32_t old_len, new_len;
  uint8_t torn_mask;
} pl_case_t;

static const pl_case_t pl_cases[] = {
    {1U, 0, 0U, 211U, 0xF0U},  {1U, 1, 211U, 333U, 0x0FU}, {1U, 2, 600U, 17U, 0xAAU},
    {2U, 1, 10U, 11U, 0x55U},  {2U, 2, 211U, 0U, 0xF0U},   {4U, 0, 0U, 3U, 0x0FU},
    {4U, 1, 333U, 333U, 0xAAU}, {4U, 2, 5U, 600U, 0x55U},  {8U, 0, 0U, 333U, 0xF0U},
    {8U, 1, 17U, 211U, 0x0FU}, {8U, 2, 211U, 9U, 0xAAU},   {16U, 0, 0U, 1U, 0x55U},
    {16U, 1, 333U, 5U, 0xF0U}, {16U, 2, 600U, 600U, 0x0FU},
};
#define N_PL_CASES ((int)(sizeof pl_cases / sizeof pl_cases[0]))

/* Banks just big enough for the largest case (600 bytes, unit 16: 656),
 * so that fewer of the k are spent inside the erase. */
#define PL_BANK 700U

/* The device state before the update, built once per case. */
static void pl_prepare(const pl_case_t *c)
{
  fake_reset(&fk, c->unit, PL_BANK);
  fk.torn_mask = c->torn_mask;
  ck_assert_int_eq(canfdi_nvm_init(&nvm, &fk.port), CANFDI_OK);
  if (c->history >= 2) {
    ck_assert_int_eq(canfdi_nvm_store(&nvm, pay_c, 100U), CANFDI_OK);
  }
  if (c->history >= 1) {
    ck_assert_int_eq(canfdi_nvm_store(&nvm, pay_a, c->old_len), CANFDI_OK);
  }
  fk.ops = 0U;
  fk_saved = fk;
}

START_TEST(test_power_loss_at_every_byte)
{
  const pl_case_t *c = &pl_cases[_i];
  /* the number of byte operations of one complete update */
  pl_prepare(c);
  ck_assert_int_eq(canfdi_nvm_store(&nvm, pay_b, c->new_len), CANFDI_OK);
  const unsigned long total = fk.ops;
  /* one erase of the bank plus the footprint of the new image */
  ck_assert_uint_eq(total, PL_BANK + CANFDI_NVM_FOOTPRINT(c->new_len, c->unit));
  /* padding after the commit word (write units > 4) comes after the point
   * of no return */
  const unsigned long pad_after_commit = (c->unit > 4U) ? (unsigned long)c->unit - 4U : 0U;
  long first_new = -1;

  for (unsigned long k = 0U; k <= total; k++) {
    fk = fk_saved;
    fk.port.ctx = &fk;
    canfdi_nvm_t n1;
    ck_assert_int_eq(canfdi_nvm_init(&n1, &fk.port), CANFDI_OK);
    ck_assert_int_eq(canfdi_nvm_load(&n1, out, sizeof out), (c->history >= 1) ? (int32_t)c->old_len : -CANFDI_ENODATA);
    fk.budget = (long)k;
    const int32_t rc = canfdi_nvm_store(&n1, pay_b, c->new_len);
    ck_assert_int_eq(rc, (k == total) ? CANFDI_OK : -CANFDI_EIO);
    ck_assert_uint_eq(fk.violations, 0U);

    fake_reboot(&fk);
    canfdi_nvm_t n2;
    ck_assert_int_eq(canfdi_nvm_init(&n2, &fk.port), CANFDI_OK);
    memset(out, 0xA5, sizeof out);
    const int32_t got = canfdi_nvm_load(&n2, out, sizeof out);
    bool is_new = false;
    if ((got == (int32_t)c->new_len) && (memcmp(out, pay_b, c->new_len) == 0) &&
        ((c->history == 0) || (n2.seq == n1.seq + ((k == total) ? 0U : 1U)))) {
      is_new = true;
    }
    if (!is_new) {
      if (c->history == 0) {
        ck_assert_msg(got == -CANFDI_ENODATA, "k=%lu: got %d, neither nothing nor the new image", k, (int)got);
      } else {
        ck_assert_msg(got == (int32_t)c->old_len, "k=%lu: length %d, neither old nor new", k, (int)got);
        ck_assert_msg(memcmp(out, pay_a, c->old_len) == 0, "k=%lu: a mix of old and new", k);
      }
    }
    if (is_new && (first_new < 0)) {
      first_new = (long)k;
    }
    ck_assert_msg(!(first_new >= 0) || is_new, "k=%lu: old again after new at %ld", k, first_new);

    /* the device stays usable: the next update succeeds and does not
     * touch the image just loaded (it survives a corrupted newest bank) */
    const int8_t loaded_bank = n2.current;
    ck_assert_int_eq(canfdi_nvm_store(&n2, pay_c, 50U), CANFDI_OK);
    ck_assert_int_ne(n2.current, loaded_bank);
    ck_assert_uint_eq(fk.violations, 0U);
    if (loaded_bank >= 0) {
      fk.mem[n2.current][20] ^= 0x01U;
      canfdi_nvm_t n3;
      ck_assert_int_eq(canfdi_nvm_init(&n3, &fk.port), CANFDI_OK);
      ck_assert_int_eq(canfdi_nvm_load(&n3, out, sizeof out), got);
      ck_assert_mem_eq(out, is_new ? pay_b : pay_a, (size_t)got);
    }
  }
  /* new exactly from the moment the last byte of the commit word is in */
  ck_assert_int_eq(first_new, (long)(total - pad_after_commit));
}
END_TEST

/* ------------------------------------------------------------ corruption */

/* A bank written by hand from the layout in the header. */
static void put32(uint8_t *p, uint32_t v)
{
  p[0] = (uint8_t)v;
  p[1] = (uint8_t)(v >> 8);
  p[2] = (uint8_t)(v >> 16);
  p[3] = (uint8_t)(v >> 24);
}

typedef struct {
  uint32_t magic;
  uint16_t version, reserved;
  uint32_t seq, len;
  const uint8_t *payload;
  uint32_t payload_len; /* bytes actually written (may differ from len) */
  bool bad_crc;
  uint32_t commit;
} hand_bank_t;

static hand_bank_t good_bank(uint32_t seq, const uint8_t *p, uint32_t len)
{
  hand_bank_t b = {CANFDI_NVM_MAGIC, 1U, 0U, seq, len, p, len, false, 0x3CA5C35AU};
  return b;
}

static void write_hand_bank(fake_t *f, uint8_t bank, const hand_bank_t *b)
{
  uint8_t *m = f->mem[bank];
  const uint32_t u = f->port.write_unit;
  memset(m, 0xFF, FAKE_BANK);
  put32(m, b->magic);
  m[4] = (uint8_t)b->version;
  m[5] = (uint8_t)(b->version >> 8);
  m[6] = (uint8_t)b->reserved;
  m[7] = (uint8_t)(b->reserved >> 8);
  put32(m + 8, b->seq);
  put32(m + 12, b->len);
  memcpy(m + 16, b->payload, b->payload_len);
  const uint32_t crc_off = ((16U + b->len + u - 1U) / u) * u;
  const uint32_t commit_off = ((crc_off + 4U + u - 1U) / u) * u;
  if (commit_off + 4U <= FAKE_BANK) {
    uint32_t crc = crc32_bitwise(m, 16U + b->len);
    put32(m + crc_off, b->bad_crc ? (crc ^ 0x00010000U) : crc);
    put32(m + commit_off, b->commit);
  }
}

START_TEST(test_hand_written_bank_is_accepted)
{
  fake_reset(&fk, 8U, FAKE_BANK);
  hand_bank_t b = good_bank(7U, pay_a, 123U);
  write_hand_bank(&fk, 1U, &b);
  ck_assert_int_eq(canfdi_nvm_init(&nvm, &fk.port), CANFDI_OK);
  ck_assert_int_eq(canfdi_nvm_load(&nvm, out, sizeof out), 123);
  ck_assert_mem_eq(out, pay_a, 123U);
  ck_assert_int_eq(nvm.current, 1);
  ck_assert_uint_eq(nvm.seq, 7U);
  ck_assert_uint_eq(nvm.bank_state[0], CANFDI_NVM_BANK_EMPTY);
  /* and the next store writes seq 8 into bank 0 */
  ck_assert_int_eq(canfdi_nvm_store(&nvm, pay_b, 10U), CANFDI_OK);
  ck_assert_int_eq(nvm.current, 0);
  ck_assert_uint_eq(nvm.seq, 8U);
  ck_assert_uint_eq(fk.mem[0][8], 8U);
}
END_TEST

START_TEST(test_every_bit_flip_falls_back)
{
  /* two images; flip each bit of the newer one's footprint: the loader
   * must return the older image (CRC-32 detects every 1-bit error). */
  fake_reset(&fk, 1U, FAKE_BANK);
  ck_assert_int_eq(canfdi_nvm_init(&nvm, &fk.port), CANFDI_OK);
  ck_assert_int_eq(canfdi_nvm_store(&nvm, pay_a, 200U), CANFDI_OK);
  ck_assert_int_eq(canfdi_nvm_store(&nvm, pay_b, 150U), CANFDI_OK);
  const int newest = nvm.current;
  const uint32_t foot = CANFDI_NVM_FOOTPRINT(150U, 1U);
  for (uint32_t byte = 0U; byte < foot; byte++) {
    for (unsigned bit = 0U; bit < 8U; bit++) {
      fk.mem[newest][byte] ^= (uint8_t)(1U << bit);
      canfdi_nvm_t n2;
      ck_assert_int_eq(canfdi_nvm_init(&n2, &fk.port), CANFDI_OK);
      ck_assert_msg(canfdi_nvm_load(&n2, out, sizeof out) == 200, "flip %u.%u not detected", byte, bit);
      ck_assert_mem_eq(out, pay_a, 200U);
      /* a flip in the length field may point the commit word at erased
       * bytes: INCOMPLETE; anything else: CORRUPT */
      ck_assert((n2.bank_state[newest] == CANFDI_NVM_BANK_CORRUPT) ||
                (n2.bank_state[newest] == CANFDI_NVM_BANK_INCOMPLETE));
      fk.mem[newest][byte] ^= (uint8_t)(1U << bit);
    }
  }
  /* a single image with a flip: nothing valid, reported */
  fake_reset(&fk, 1U, FAKE_BANK);
  ck_assert_int_eq(canfdi_nvm_init(&nvm, &fk.port), CANFDI_OK);
  ck_assert_int_eq(canfdi_nvm_store(&nvm, pay_a, 200U), CANFDI_OK);
  fk.mem[0][100] ^= 0x10U;
  ck_assert_int_eq(canfdi_nvm_init(&nvm, &fk.port), CANFDI_OK);
  ck_assert_int_eq(canfdi_nvm_load(&nvm, out, sizeof out), -CANFDI_ENODATA);
  ck_assert_uint_eq(nvm.bank_state[0], CANFDI_NVM_BANK_CORRUPT);
  ck_assert_uint_eq(nvm.bank_state[1], CANFDI_NVM_BANK_EMPTY);
  ck_assert_uint_eq(nvm.diag.corrupt_banks, 1U);
  ck_assert_uint_eq(nvm.diag.load_failures, 1U);
}
END_TEST

typedef struct {
  const char *name;
  int kind;
  uint8_t expect_state;
} hdr_case_t;

static const hdr_case_t hdr_cases[] = {
    {"bad magic", 0, CANFDI_NVM_BANK_CORRUPT},
    {"newer container version", 1, CANFDI_NVM_BANK_CORRUPT},
    {"reserved field set", 2, CANFDI_NVM_BANK_CORRUPT},
    {"length beyond the bank", 3, CANFDI_NVM_BANK_CORRUPT},
    {"length 0xFFFFFFFF", 4, CANFDI_NVM_BANK_CORRUPT},
    {"footprint one byte too big", 5, CANFDI_NVM_BANK_CORRUPT},
    {"commit word erased", 6, CANFDI_NVM_BANK_INCOMPLETE},
    {"commit word wrong", 7, CANFDI_NVM_BANK_CORRUPT},
    {"CRC wrong", 8, CANFDI_NVM_BANK_CORRUPT},
    {"sequence number changed after the CRC", 9, CANFDI_NVM_BANK_CORRUPT},
};

START_TEST(test_bad_headers)
{
  const hdr_case_t *c = &hdr_cases[_i];
  fake_reset(&fk, 4U, FAKE_BANK);
  hand_bank_t old = good_bank(41U, pay_a, 64U);
  hand_bank_t bad = good_bank(42U, pay_b, 64U);
  switch (c->kind) {
  case 0: bad.magic ^= 0x100U; break;
  case 1: bad.version = 2U; break;
  case 2: bad.reserved = 1U; break;
  case 3: bad.len = FAKE_BANK + 1U; bad.payload_len = 64U; break;
  case 4: bad.len = 0xFFFFFFFFU; bad.payload_len = 64U; break;
  case 5: bad.len = FAKE_BANK - 16U - 8U + 1U; bad.payload_len = 64U; break;
  case 6: bad.commit = 0xFFFFFFFFU; break;
  case 7: bad.commit = 0x3CA5C35BU; break;
  case 8: bad.bad_crc = true; break;
  default: break;
  }
  write_hand_bank(&fk, 0U, &old);
  write_hand_bank(&fk, 1U, &bad);
  if (c->kind == 9) {
    fk.mem[1][8] ^= 0x02U;
  }
  ck_assert_int_eq(canfdi_nvm_init(&nvm, &fk.port), CANFDI_OK);
  ck_assert_int_eq(canfdi_nvm_load(&nvm, out, sizeof out), 64);
  ck_assert_mem_eq(out, pay_a, 64U);
  ck_assert_uint_eq(nvm.bank_state[1], c->expect_state);
  ck_assert_uint_eq(nvm.bank_state[0], CANFDI_NVM_BANK_VALID);
  /* both bad: no image, a defined error, both reported */
  write_hand_bank(&fk, 0U, &bad);
  if (c->kind == 9) {
    fk.mem[0][8] ^= 0x02U;
  }
  ck_assert_int_eq(canfdi_nvm_init(&nvm, &fk.port), CANFDI_OK);
  ck_assert_int_eq(canfdi_nvm_load(&nvm, out, sizeof out), -CANFDI_ENODATA);
  ck_assert_uint_eq(nvm.bank_state[0], c->expect_state);
  ck_assert_uint_eq(nvm.bank_state[1], c->expect_state);
  /* and a store recovers (writes bank 0 with seq 1) */
  ck_assert_int_eq(canfdi_nvm_store(&nvm, pay_c, 30U), CANFDI_OK);
  ck_assert_int_eq(canfdi_nvm_load(&nvm, out, sizeof out), 30);
  ck_assert_mem_eq(out, pay_c, 30U);
}
END_TEST

typedef struct {
  uint32_t seq0, seq1;
  int expect_bank;
} seq_case_t;

static const seq_case_t seq_cases[] = {
    {1U, 2U, 1},
    {2U, 1U, 0},
    {0xFFFFFFFFU, 0U, 1}, /* wrap: 0 is newer */
    {0U, 0xFFFFFFFFU, 0},
    {0x7FFFFFFFU, 0x80000000U, 1},
    {5U, 5U, 0}, /* equal: bank 0 by definition */
};

START_TEST(test_sequence_selection)
{
  const seq_case_t *c = &seq_cases[_i];
  fake_reset(&fk, 1U, FAKE_BANK);
  hand_bank_t b0 = good_bank(c->seq0, pay_a, 40U);
  hand_bank_t b1 = good_bank(c->seq1, pay_b, 41U);
  write_hand_bank(&fk, 0U, &b0);
  write_hand_bank(&fk, 1U, &b1);
  ck_assert_int_eq(canfdi_nvm_init(&nvm, &fk.port), CANFDI_OK);
  ck_assert_int_eq(canfdi_nvm_load(&nvm, out, sizeof out), c->expect_bank ? 41 : 40);
  ck_assert_int_eq(nvm.current, c->expect_bank);
  const uint32_t cur = c->expect_bank ? c->seq1 : c->seq0;
  ck_assert_int_eq(canfdi_nvm_store(&nvm, pay_c, 12U), CANFDI_OK);
  ck_assert_int_eq(nvm.current, 1 - c->expect_bank);
  ck_assert_uint_eq(nvm.seq, cur + 1U); /* wraps */
  canfdi_nvm_t n2;
  ck_assert_int_eq(canfdi_nvm_init(&n2, &fk.port), CANFDI_OK);
  ck_assert_int_eq(canfdi_nvm_load(&n2, out, sizeof out), 12);
}
END_TEST

START_TEST(test_port_errors_propagate)
{
  fake_reset(&fk, 1U, FAKE_BANK);
  ck_assert_int_eq(canfdi_nvm_init(&nvm, &fk.port), CANFDI_OK);
  ck_assert_int_eq(canfdi_nvm_store(&nvm, pay_a, 100U), CANFDI_OK);
  ck_assert_int_eq(canfdi_nvm_store(&nvm, pay_b, 100U), CANFDI_OK);
  /* a read error is an error, not "no image" */
  for (int after = 0; after < 8; after++) {
    fk.reads = 0U;
    fk.fail_reads_after = after;
    canfdi_nvm_t n2;
    ck_assert_int_eq(canfdi_nvm_init(&n2, &fk.port), CANFDI_OK);
    const int32_t rc = canfdi_nvm_load(&n2, out, sizeof out);
    ck_assert_msg((rc == -CANFDI_EIO) || (rc == 100), "after %d reads: %d", after, (int)rc);
    if (rc == 100) {
      ck_assert_mem_eq(out, pay_b, 100U);
    }
  }
  /* a failing verify read leaves the previous image current */
  fk.fail_reads_after = -1;
  canfdi_nvm_t n3;
  ck_assert_int_eq(canfdi_nvm_init(&n3, &fk.port), CANFDI_OK);
  ck_assert_int_eq(canfdi_nvm_load(&n3, out, sizeof out), 100);
  const int8_t cur = n3.current;
  fk.reads = 0U;
  fk.fail_reads_after = 0;
  ck_assert_int_eq(canfdi_nvm_store(&n3, pay_c, 10U), -CANFDI_EIO);
  ck_assert_int_eq(n3.current, cur);
  ck_assert_uint_eq(n3.diag.store_failures, 1U);
  /* a write that silently stores something else fails the verify */
  fk.fail_reads_after = -1;
  ck_assert_uint_ne(pay_c[0], 0U);
  fk.zero_write_call = fk.writes + 2U; /* header, then the payload */
  ck_assert_int_eq(canfdi_nvm_store(&n3, pay_c, 40U), -CANFDI_EIO);
  ck_assert_int_eq(n3.current, cur);
  ck_assert_uint_eq(n3.bank_state[1 - cur], CANFDI_NVM_BANK_CORRUPT);
  canfdi_nvm_t n4;
  ck_assert_int_eq(canfdi_nvm_init(&n4, &fk.port), CANFDI_OK);
  ck_assert_int_eq(canfdi_nvm_load(&n4, out, sizeof out), 100);
  ck_assert_mem_eq(out, pay_b, 100U);
}
END_TEST

/* ------------------------------------------------------- DTC end to end */

static canfdi_dtc_t dtc_mem;
static uint8_t img_old[CANFDI_DTC_IMAGE_MAX_BYTES];
static uint8_t img_new[CANFDI_DTC_IMAGE_MAX_BYTES];
static uint8_t img_got[CANFDI_DTC_IMAGE_MAX_BYTES];

START_TEST(test_dtc_image_survives_power_loss)
{
  /* the bank must hold the largest DTC image */
  const uint32_t bank = CANFDI_NVM_FOOTPRINT(CANFDI_DTC_IMAGE_MAX_BYTES, 8U);
  ck_assert_uint_le(bank, FAKE_BANK);
  const canfdi_dtc_ff_t ff = {1234U, 1, 2, 3, 4, 5, 1U, 0U};
  ck_assert_int_eq(canfdi_dtc_init(&dtc_mem, canfdi_dtc_defaults, (uint8_t)CANFDI_DTC_COUNT), CANFDI_OK);
  ck_assert_int_eq(canfdi_dtc_cycle_start(&dtc_mem), CANFDI_OK);
  for (uint8_t i = 0U; i < 5U; i++) {
    ck_assert_int_ge(canfdi_dtc_report(&dtc_mem, i, CANFDI_DEB_REPORT_FAILED, &ff), 0);
  }
  ck_assert_int_eq(canfdi_dtc_cycle_end(&dtc_mem), CANFDI_OK);
  const int32_t len_old = canfdi_dtc_serialize(&dtc_mem, img_old, sizeof img_old);
  ck_assert_int_gt(len_old, 0);
  ck_assert_int_eq(canfdi_dtc_cycle_start(&dtc_mem), CANFDI_OK);
  ck_assert_int_ge(canfdi_dtc_report(&dtc_mem, 0U, CANFDI_DEB_REPORT_PASSED, &ff), 0);
  ck_assert_int_eq(canfdi_dtc_clear(&dtc_mem, canfdi_dtc_defaults[1].dtc), CANFDI_OK);
  for (uint8_t i = 10U; i < 20U; i++) {
    ck_assert_int_ge(canfdi_dtc_report(&dtc_mem, i, CANFDI_DEB_REPORT_FAILED, &ff), 0);
  }
  ck_assert_int_eq(canfdi_dtc_cycle_end(&dtc_mem), CANFDI_OK);
  const int32_t len_new = canfdi_dtc_serialize(&dtc_mem, img_new, sizeof img_new);
  ck_assert_int_gt(len_new, 0);
  ck_assert(!((len_new == len_old) && (memcmp(img_old, img_new, (size_t)len_new) == 0)));

  fake_reset(&fk, 8U, bank);
  ck_assert_int_eq(canfdi_nvm_init(&nvm, &fk.port), CANFDI_OK);
  ck_assert_int_eq(canfdi_nvm_store(&nvm, img_old, (uint32_t)len_old), CANFDI_OK);
  fk.ops = 0U;
  fk_saved = fk;
  ck_assert_int_eq(canfdi_nvm_store(&nvm, img_new, (uint32_t)len_new), CANFDI_OK);
  const unsigned long total = fk.ops;
  unsigned n_old = 0U;
  unsigned n_new = 0U;
  for (unsigned long k = 0U; k <= total; k++) {
    fk = fk_saved;
    fk.port.ctx = &fk;
    canfdi_nvm_t n1;
    ck_assert_int_eq(canfdi_nvm_init(&n1, &fk.port), CANFDI_OK);
    fk.budget = (long)k;
    (void)canfdi_nvm_store(&n1, img_new, (uint32_t)len_new);
    fake_reboot(&fk);
    /* boot: load the image, hand it to the DTC memory */
    canfdi_nvm_t n2;
    ck_assert_int_eq(canfdi_nvm_init(&n2, &fk.port), CANFDI_OK);
    const int32_t got = canfdi_nvm_load(&n2, img_got, sizeof img_got);
    ck_assert_int_gt(got, 0);
    ck_assert_int_eq(canfdi_dtc_init(&dtc_mem, canfdi_dtc_defaults, (uint8_t)CANFDI_DTC_COUNT), CANFDI_OK);
    ck_assert_int_eq(canfdi_dtc_deserialize(&dtc_mem, img_got, (uint32_t)got), CANFDI_OK);
    const int32_t again = canfdi_dtc_serialize(&dtc_mem, img_got, sizeof img_got);
    if ((again == len_new) && (memcmp(img_got, img_new, (size_t)again) == 0)) {
      n_new++;
    } else {
      ck_assert_int_eq(again, len_old);
      ck_assert_mem_eq(img_got, img_old, (size_t)again);
      n_old++;
    }
  }
  ck_assert_uint_gt(n_old, 0U);
  ck_assert_uint_gt(n_new, 0U);
  ck_assert_uint_eq(n_old + n_new, total + 1U);
}
END_TEST

START_TEST(test_dtc_defaults_when_both_banks_bad)
{
  fake_reset(&fk, 1U, FAKE_BANK);
  ck_assert_int_eq(canfdi_nvm_init(&nvm, &fk.port), CANFDI_OK);
  ck_assert_int_eq(canfdi_nvm_store(&nvm, pay_a, 100U), CANFDI_OK);
  ck_assert_int_eq(canfdi_nvm_store(&nvm, pay_b, 100U), CANFDI_OK);
  fk.mem[0][50] ^= 0x80U;
  fk.mem[1][3] ^= 0x01U;
  /* the boot sequence of the application */
  ck_assert_int_eq(canfdi_dtc_init(&dtc_mem, canfdi_dtc_defaults, (uint8_t)CANFDI_DTC_COUNT), CANFDI_OK);
  ck_assert_int_eq(canfdi_nvm_init(&nvm, &fk.port), CANFDI_OK);
  const int32_t got = canfdi_nvm_load(&nvm, img_got, sizeof img_got);
  ck_assert_int_eq(got, -CANFDI_ENODATA);
  ck_assert_uint_eq(nvm.bank_state[0], CANFDI_NVM_BANK_CORRUPT);
  ck_assert_uint_eq(nvm.bank_state[1], CANFDI_NVM_BANK_CORRUPT);
  ck_assert_uint_eq(nvm.diag.corrupt_banks, 2U);
  for (uint8_t i = 0U; i < CANFDI_DTC_COUNT; i++) {
    ck_assert_int_eq(canfdi_dtc_status(&dtc_mem, i), 0x50);
  }
  /* a valid container holding a non-DTC payload is refused by the DTC
   * memory, which then keeps its defaults */
  ck_assert_int_eq(canfdi_nvm_store(&nvm, pay_a, 100U), CANFDI_OK);
  ck_assert_int_eq(canfdi_nvm_load(&nvm, img_got, sizeof img_got), 100);
  ck_assert_int_eq(canfdi_dtc_deserialize(&dtc_mem, img_got, 100U), -CANFDI_EINVAL);
  ck_assert_uint_eq(canfdi_dtc_count_by_mask(&dtc_mem, CANFDI_DTC_ST_TFSLC), 0U);
}
END_TEST

/* ------------------------------------------------------------ file port */

static char tmpdir[256];
static char path[300];

static void file_setup(void)
{
  setup_payloads();
  snprintf(tmpdir, sizeof tmpdir, "/tmp/canfdi_nvm_XXXXXX");
  ck_assert_ptr_nonnull(mkdtemp(tmpdir));
  snprintf(path, sizeof path, "%s/nvm.bin", tmpdir);
}

static void file_teardown(void)
{
  char tmp[320];
  snprintf(tmp, sizeof tmp, "%s.tmp", path);
  (void)unlink(path);
  (void)unlink(tmp);
  (void)rmdir(tmpdir);
}

static off_t file_size(const char *p)
{
  struct stat s;
  return (stat(p, &s) == 0) ? s.st_size : (off_t)-1;
}

#define FILE_BANK 512U

START_TEST(test_file_create_store_reopen)
{
  canfdi_nvm_file_t f;
  ck_assert_int_eq(canfdi_nvm_file_open(&f, path, FILE_BANK, 0U), -CANFDI_ENODATA);
  ck_assert_int_eq(f.fd, -1);
  ck_assert_int_eq(canfdi_nvm_file_open(&f, path, FILE_BANK, CANFDI_NVM_FILE_CREATE), CANFDI_OK);
  ck_assert_int_eq((long)file_size(path), 2L * FILE_BANK);
  char tmp[320];
  snprintf(tmp, sizeof tmp, "%s.tmp", path);
  ck_assert_int_eq((long)file_size(tmp), -1L); /* renamed away */
  ck_assert_int_eq(canfdi_nvm_init(&nvm, &f.port), CANFDI_OK);
  ck_assert_int_eq(canfdi_nvm_load(&nvm, out, sizeof out), -CANFDI_ENODATA);
  ck_assert_uint_eq(nvm.bank_state[0], CANFDI_NVM_BANK_EMPTY);
  ck_assert_uint_eq(nvm.bank_state[1], CANFDI_NVM_BANK_EMPTY);
  ck_assert_int_eq(canfdi_nvm_store(&nvm, pay_a, 300U), CANFDI_OK);
  canfdi_nvm_file_close(&f);
  canfdi_nvm_file_close(&f); /* twice is harmless */

  ck_assert_int_eq(canfdi_nvm_file_open(&f, path, FILE_BANK, 0U), CANFDI_OK);
  ck_assert_int_eq(canfdi_nvm_init(&nvm, &f.port), CANFDI_OK);
  ck_assert_int_eq(canfdi_nvm_load(&nvm, out, sizeof out), 300);
  ck_assert_mem_eq(out, pay_a, 300U);
  ck_assert_int_eq(canfdi_nvm_store(&nvm, pay_b, 444U), CANFDI_OK);
  canfdi_nvm_file_close(&f);

  /* CREATE on an existing file keeps it */
  ck_assert_int_eq(canfdi_nvm_file_open(&f, path, FILE_BANK, CANFDI_NVM_FILE_CREATE), CANFDI_OK);
  ck_assert_int_eq(canfdi_nvm_init(&nvm, &f.port), CANFDI_OK);
  ck_assert_int_eq(canfdi_nvm_load(&nvm, out, sizeof out), 444);
  ck_assert_mem_eq(out, pay_b, 444U);
  ck_assert_int_eq(nvm.bank_state[0], CANFDI_NVM_BANK_VALID);
  ck_assert_int_eq(nvm.bank_state[1], CANFDI_NVM_BANK_VALID);
  /* the port refuses out-of-bank access */
  uint8_t b[8];
  ck_assert_int_eq(f.port.read(f.port.ctx, 2U, 0U, b, 1U), -CANFDI_EINVAL);
  ck_assert_int_eq(f.port.read(f.port.ctx, 0U, FILE_BANK - 4U, b, 5U), -CANFDI_EINVAL);
  ck_assert_int_eq(f.port.write(f.port.ctx, 1U, FILE_BANK, b, 1U), -CANFDI_EINVAL);
  ck_assert_int_eq(f.port.erase(f.port.ctx, 2U), -CANFDI_EINVAL);
  canfdi_nvm_file_close(&f);
  ck_assert_int_eq(canfdi_nvm_file_open(&f, NULL, FILE_BANK, 0U), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_nvm_file_open(&f, path, 0U, 0U), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_nvm_file_open(&f, path, FILE_BANK, 2U), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_nvm_file_open(NULL, path, FILE_BANK, 0U), -CANFDI_EINVAL);
}
END_TEST

START_TEST(test_file_truncated_and_corrupt)
{
  canfdi_nvm_file_t f;
  ck_assert_int_eq(canfdi_nvm_file_open(&f, path, FILE_BANK, CANFDI_NVM_FILE_CREATE), CANFDI_OK);
  ck_assert_int_eq(canfdi_nvm_init(&nvm, &f.port), CANFDI_OK);
  ck_assert_int_eq(canfdi_nvm_store(&nvm, pay_a, 100U), CANFDI_OK);
  ck_assert_int_eq(canfdi_nvm_store(&nvm, pay_b, 120U), CANFDI_OK);
  const int newest = nvm.current;
  canfdi_nvm_file_close(&f);

  /* a flipped byte in the newest bank: the older image */
  int fd = open(path, O_RDWR);
  ck_assert_int_ge(fd, 0);
  uint8_t byte = 0U;
  const off_t at = (off_t)newest * (off_t)FILE_BANK + 40;
  ck_assert_int_eq((int)pread(fd, &byte, 1U, at), 1);
  byte ^= 0x04U;
  ck_assert_int_eq((int)pwrite(fd, &byte, 1U, at), 1);
  ck_assert_int_eq(canfdi_nvm_file_open(&f, path, FILE_BANK, 0U), CANFDI_OK);
  ck_assert_int_eq(canfdi_nvm_init(&nvm, &f.port), CANFDI_OK);
  ck_assert_int_eq(canfdi_nvm_load(&nvm, out, sizeof out), 100);
  ck_assert_mem_eq(out, pay_a, 100U);
  ck_assert_uint_eq(nvm.bank_state[newest], CANFDI_NVM_BANK_CORRUPT);
  canfdi_nvm_file_close(&f);
  /* both: no image, both reported */
  const off_t at2 = (off_t)(1 - newest) * (off_t)FILE_BANK + 2;
  ck_assert_int_eq((int)pread(fd, &byte, 1U, at2), 1);
  byte ^= 0x40U;
  ck_assert_int_eq((int)pwrite(fd, &byte, 1U, at2), 1);
  ck_assert_int_eq(canfdi_nvm_file_open(&f, path, FILE_BANK, 0U), CANFDI_OK);
  ck_assert_int_eq(canfdi_nvm_init(&nvm, &f.port), CANFDI_OK);
  ck_assert_int_eq(canfdi_nvm_load(&nvm, out, sizeof out), -CANFDI_ENODATA);
  ck_assert_uint_eq(nvm.bank_state[0], CANFDI_NVM_BANK_CORRUPT);
  ck_assert_uint_eq(nvm.bank_state[1], CANFDI_NVM_BANK_CORRUPT);
  canfdi_nvm_file_close(&f);

  /* truncated (or another geometry): a defined error, file untouched */
  const off_t sizes[] = {2 * FILE_BANK - 1, FILE_BANK, 1, 0, 2 * FILE_BANK + 1};
  for (size_t i = 0U; i < sizeof sizes / sizeof sizes[0]; i++) {
    ck_assert_int_eq(ftruncate(fd, sizes[i]), 0);
    ck_assert_int_eq(canfdi_nvm_file_open(&f, path, FILE_BANK, 0U), -CANFDI_ERANGE);
    ck_assert_int_eq(canfdi_nvm_file_open(&f, path, FILE_BANK, CANFDI_NVM_FILE_CREATE), -CANFDI_ERANGE);
    ck_assert_int_eq((long)file_size(path), (long)sizes[i]);
  }
  /* the right size with the wrong bank size is refused too */
  ck_assert_int_eq(ftruncate(fd, 2 * FILE_BANK), 0);
  ck_assert_int_eq(canfdi_nvm_file_open(&f, path, FILE_BANK / 2U, 0U), -CANFDI_ERANGE);
  close(fd);
  /* a file that shrinks while open: reads fail with an I/O error */
  ck_assert_int_eq(canfdi_nvm_file_open(&f, path, FILE_BANK, 0U), CANFDI_OK);
  ck_assert_int_eq(truncate(path, FILE_BANK), 0);
  ck_assert_int_eq(canfdi_nvm_init(&nvm, &f.port), CANFDI_OK);
  uint8_t b[4];
  ck_assert_int_eq(f.port.read(f.port.ctx, 1U, 0U, b, 4U), -CANFDI_EIO);
  ck_assert_uint_ge(f.io_errors, 1U);
  canfdi_nvm_file_close(&f);
}
END_TEST

/* A real kill -9 at random moments of a store loop: after each, the file
 * holds one complete image, never older than the previous survivor. */
START_TEST(test_file_kill9_during_updates)
{
  canfdi_nvm_file_t f;
  ck_assert_int_eq(canfdi_nvm_file_open(&f, path, FILE_BANK, CANFDI_NVM_FILE_CREATE), CANFDI_OK);
  canfdi_nvm_file_close(&f);
  uint32_t last = 0U;
  unsigned progressed = 0U;
  for (int round = 0; round < 20; round++) {
    const pid_t pid = fork();
    ck_assert_int_ge(pid, 0);
    if (pid == 0) {
      /* child: store images whose every byte encodes their number */
      canfdi_nvm_file_t cf;
      canfdi_nvm_t cn;
      uint8_t img[256];
      if ((canfdi_nvm_file_open(&cf, path, FILE_BANK, 0U) != CANFDI_OK) ||
          (canfdi_nvm_init(&cn, &cf.port) != CANFDI_OK)) {
        _exit(2);
      }
      int32_t got = canfdi_nvm_load(&cn, img, sizeof img);
      uint32_t i = (got >= 4) ? ((uint32_t)img[0] | ((uint32_t)img[1] << 8) | ((uint32_t)img[2] << 16) |
                                 ((uint32_t)img[3] << 24))
                              : 0U;
      for (;;) {
        i++;
        const uint32_t len = 4U + (i % 200U);
        img[0] = (uint8_t)i;
        img[1] = (uint8_t)(i >> 8);
        img[2] = (uint8_t)(i >> 16);
        img[3] = (uint8_t)(i >> 24);
        for (uint32_t k = 4U; k < len; k++) {
          img[k] = (uint8_t)(i * 31U + k);
        }
        if (canfdi_nvm_store(&cn, img, len) != CANFDI_OK) {
          _exit(3);
        }
      }
    }
    const struct timespec ts = {0, (long)(1 + (round * 7919) % 20) * 1000000L};
    nanosleep(&ts, NULL);
    ck_assert_int_eq(kill(pid, SIGKILL), 0);
    int status = 0;
    ck_assert_int_eq((int)waitpid(pid, &status, 0), (int)pid);
    ck_assert(WIFSIGNALED(status) && (WTERMSIG(status) == SIGKILL));

    ck_assert_int_eq(canfdi_nvm_file_open(&f, path, FILE_BANK, 0U), CANFDI_OK);
    ck_assert_int_eq(canfdi_nvm_init(&nvm, &f.port), CANFDI_OK);
    uint8_t img[256];
    const int32_t got = canfdi_nvm_load(&nvm, img, sizeof img);
    canfdi_nvm_file_close(&f);
    if (got == -CANFDI_ENODATA) {
      ck_assert_uint_eq(last, 0U); /* killed before the very first commit */
      continue;
    }
    ck_assert_int_ge(got, 4);
    const uint32_t i = (uint32_t)img[0] | ((uint32_t)img[1] << 8) | ((uint32_t)img[2] << 16) |
                       ((uint32_t)img[3] << 24);
    ck_assert_uint_eq((uint32_t)got, 4U + (i % 200U));
    for (uint32_t k = 4U; k < (uint32_t)got; k++) {
      ck_assert_uint_eq(img[k], (uint8_t)(i * 31U + k));
    }
    ck_assert_uint_ge(i, last);
    progressed += (i > last) ? 1U : 0U;
    last = i;
  }
  ck_assert_uint_gt(progressed, 0U);
}
END_TEST

static Suite *make_suite(void)
{
  Suite *s = suite_create("nvm");
  TCase *tc = tcase_create("crc");
  tcase_add_test(tc, test_crc32_check_value);
  tcase_add_test(tc, test_crc32_matches_bitwise_and_is_incremental);
  suite_add_tcase(s, tc);

  tc = tcase_create("store_load");
  tcase_add_unchecked_fixture(tc, setup_payloads, NULL);
  tcase_add_test(tc, test_init_rejects);
  tcase_add_loop_test(tc, test_store_load_alternates_banks, 0, 5);
  tcase_add_test(tc, test_hand_written_bank_is_accepted);
  tcase_add_loop_test(tc, test_sequence_selection, 0, (int)(sizeof seq_cases / sizeof seq_cases[0]));
  suite_add_tcase(s, tc);

  tc = tcase_create("power_loss");
  tcase_add_unchecked_fixture(tc, setup_payloads, NULL);
  tcase_add_loop_test(tc, test_power_loss_at_every_byte, 0, N_PL_CASES);
  tcase_set_timeout(tc, 300);
  suite_add_tcase(s, tc);

  tc = tcase_create("corruption");
  tcase_add_unchecked_fixture(tc, setup_payloads, NULL);
  tcase_add_test(tc, test_every_bit_flip_falls_back);
  tcase_add_loop_test(tc, test_bad_headers, 0, (int)(sizeof hdr_cases / sizeof hdr_cases[0]));
  tcase_add_test(tc, test_port_errors_propagate);
  tcase_set_timeout(tc, 120);
  suite_add_tcase(s, tc);

  tc = tcase_create("dtc_image");
  tcase_add_unchecked_fixture(tc, setup_payloads, NULL);
  tcase_add_test(tc, test_dtc_image_survives_power_loss);
  tcase_add_test(tc, test_dtc_defaults_when_both_banks_bad);
  tcase_set_timeout(tc, 120);
  suite_add_tcase(s, tc);

  tc = tcase_create("file_port");
  tcase_add_checked_fixture(tc, file_setup, file_teardown);
  tcase_add_test(tc, test_file_create_store_reopen);
  tcase_add_test(tc, test_file_truncated_and_corrupt);
  tcase_add_test(tc, test_file_kill9_during_updates);
  tcase_set_timeout(tc, 60);
  suite_add_tcase(s, tc);
  return s;
}

CANFDI_UNIT_MAIN(make_suite)
