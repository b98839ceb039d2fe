/*
 * fuzz_nvm.c — the NVM image loader (diag/canfdi_nvm.c) and the
 * application's image reader (canfdi_app_power_up) on hostile flash: a RAM
 * port of two banks with flash semantics (erase to 0xFF, programming only
 * clears bits).
 *
 * Modes (first input byte % 4; tests/fuzz/README.md):
 *   0 random banks: the input is the flash content of both banks;
 *   1 torn store: a real image A (the application's power-down image after
 *     input-chosen monitor reports) is stored, then image B; the power fails
 *     after an input-chosen number of programmed bytes (mid-byte: some bits
 *     cleared) or during the erase (the bank partly erased);
 *   2 bit flips: A then B stored completely, then 1..4 input-chosen bits of
 *     the banks flipped (a flash bit flip, a disturbed cell);
 *   3 raw payload: the input as the image the loader hands the application
 *     (what a CRC collision or an old firmware's image would bring).
 * Whatever the loader returns goes to canfdi_app_power_up.
 *
 * Invariants: canfdi_nvm_load returns a length within the buffer or a
 * documented error; after a torn store or bit flips it returns exactly A or
 * exactly B or no image, never a mix (the module's atomicity promise);
 * canfdi_app_power_up returns CANFDI_OK or CANFDI_APP_IMAGE_REJECTED; the
 * DTC memory then satisfies its invariants and the application steps.
 */
#include <string.h>

#include "app/canfdi_app.h"
#include "diag/canfdi_nvm.h"
#include "fuzz_input.h"

#define UNIT 8U
#define BANK_BYTES CANFDI_NVM_FOOTPRINT(CANFDI_APP_IMAGE_MAX_BYTES, 16U)

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static canfdi_app_t app;
static canfdi_app_t pristine;
static canfdi_app_cal_t cal;

static struct {
  uint8_t bank[CANFDI_NVM_BANKS][BANK_BYTES];
  int64_t budget; /* bytes that may still be programmed/erased; < 0: no limit */
  bool dead;      /* the power failed */
} fl;

static int32_t p_read(void *ctx, uint8_t bank, uint32_t offset, uint8_t *buf, uint32_t len)
{
  (void)ctx;
  FZ_CHECK(bank < CANFDI_NVM_BANKS && offset <= BANK_BYTES && len <= BANK_BYTES - offset,
           "read bank %u %u+%u", bank, offset, len);
  memcpy(buf, &fl.bank[bank][offset], len);
  return CANFDI_OK;
}

/* Programs bytes one by one until the budget runs out; the byte being
 * programmed then has only its upper bits cleared. */
static int32_t p_write(void *ctx, uint8_t bank, uint32_t offset, const uint8_t *buf, uint32_t len)
{
  (void)ctx;
  FZ_CHECK(bank < CANFDI_NVM_BANKS && offset <= BANK_BYTES && len <= BANK_BYTES - offset,
           "write bank %u %u+%u", bank, offset, len);
  FZ_CHECK(offset % UNIT == 0U && len % UNIT == 0U, "write %u+%u not in units of %u", offset, len, UNIT);
  if (fl.dead) {
    return -CANFDI_EIO;
  }
  for (uint32_t k = 0U; k < len; k++) {
    if (fl.budget == 0) {
      fl.bank[bank][offset + k] &= (uint8_t)(buf[k] | 0x0FU);
      fl.dead = true;
      return -CANFDI_EIO;
    }
    if (fl.budget > 0) {
      fl.budget--;
    }
    fl.bank[bank][offset + k] &= buf[k];
  }
  return CANFDI_OK;
}

static int32_t p_erase(void *ctx, uint8_t bank)
{
  (void)ctx;
  FZ_CHECK(bank < CANFDI_NVM_BANKS, "erase bank %u", bank);
  if (fl.dead) {
    return -CANFDI_EIO;
  }
  for (uint32_t k = 0U; k < BANK_BYTES; k++) {
    if (fl.budget == 0) {
      fl.dead = true;
      return -CANFDI_EIO;
    }
    if (fl.budget > 0) {
      fl.budget--;
    }
    fl.bank[bank][k] = 0xFFU;
  }
  return CANFDI_OK;
}

static const canfdi_nvm_port_t port = {NULL, p_read, p_write, p_erase, BANK_BYTES, UNIT};

static uint8_t img_a[CANFDI_APP_IMAGE_MAX_BYTES];
static uint8_t img_b[CANFDI_APP_IMAGE_MAX_BYTES];
static uint8_t buf[CANFDI_APP_IMAGE_MAX_BYTES + 64U];

/* A real power-down image after some monitor reports and cycles. */
static int32_t real_image(fz_in_t *in, uint8_t *img)
{
  memcpy(&app, &pristine, sizeof app);
  const uint32_t n = fz_u8(in) % 32U;
  for (uint32_t k = 0U; k < n; k++) {
    const uint8_t b = fz_u8(in);
    if (b >= 0xF0U) {
      (void)canfdi_dtc_cycle_end(&app.dtc);
      (void)canfdi_dtc_cycle_start(&app.dtc);
    } else {
      (void)canfdi_dtc_report(&app.dtc, (uint8_t)(b % (uint8_t)CANFDI_DTC_COUNT),
                              (canfdi_deb_report_t)(fz_u8(in) % 4U), NULL);
    }
  }
  const int32_t len = canfdi_app_power_down(&app, img, CANFDI_APP_IMAGE_MAX_BYTES);
  FZ_CHECK(len > 0 && len <= (int32_t)CANFDI_APP_IMAGE_MAX_BYTES, "power_down %d", (int)len);
  return len;
}

static void power_up(const uint8_t *img, uint32_t len)
{
  canfdi_tx_frame_t out[CANFDI_APP_MAX_TX];
  const int32_t rc = canfdi_app_power_up(&app, &cal, 0U, img, len);
  FZ_CHECK(rc == CANFDI_OK || rc == CANFDI_APP_IMAGE_REJECTED, "power_up %d", (int)rc);
  FZ_CHECK(canfdi_dtc_invariants_hold(&app.dtc), "%s", "DTC invariants after power-up");
  for (uint32_t k = 1U; k <= 3U; k++) {
    const int32_t n = canfdi_app_step(&app, 1000U * k, out);
    FZ_CHECK(n >= 2, "step after power-up %d", (int)n);
  }
  FZ_CHECK(canfdi_dtc_invariants_hold(&app.dtc), "%s", "DTC invariants after steps");
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
  static bool ready = false;
  fz_in_t in = {data, size, 0U};
  canfdi_nvm_t nvm;
  if (size == 0U) {
    return 0;
  }
  if (!ready) {
    canfdi_app_default_cal(&cal);
    if (canfdi_app_init(&app, &cal, 0U) != CANFDI_OK) {
      abort();
    }
    memcpy(&pristine, &app, sizeof app);
    ready = true;
  }
  const uint8_t mode = fz_u8(&in) % 4U;
  if (mode == 3U) {
    power_up(&data[1], (uint32_t)(size - 1U));
    return 0;
  }
  memset(fl.bank, 0xFF, sizeof fl.bank);
  fl.budget = -1;
  fl.dead = false;
  int32_t la = -1;
  int32_t lb = -1;
  if (mode == 0U) {
    const size_t n = (size - 1U < sizeof fl.bank) ? size - 1U : sizeof fl.bank;
    memcpy(fl.bank, &data[1], n);
  } else {
    FZ_CHECK(canfdi_nvm_init(&nvm, &port) == CANFDI_OK, "%s", "nvm init");
    la = real_image(&in, img_a);
    lb = real_image(&in, img_b);
    FZ_CHECK(canfdi_nvm_store(&nvm, img_a, (uint32_t)la) == CANFDI_OK, "%s", "store A");
    if (mode == 1U) {
      fl.budget = (int64_t)(fz_u16(&in) % (BANK_BYTES + 2U * CANFDI_APP_IMAGE_MAX_BYTES));
    }
    (void)canfdi_nvm_store(&nvm, img_b, (uint32_t)lb);
    if (mode == 2U) {
      const uint32_t flips = 1U + (fz_u8(&in) % 4U);
      for (uint32_t k = 0U; k < flips; k++) {
        const uint32_t bit = fz_u32(&in) % (uint32_t)(sizeof fl.bank * 8U);
        ((uint8_t *)fl.bank)[bit / 8U] ^= (uint8_t)(1U << (bit % 8U));
      }
    }
  }
  /* a fresh instance reads the flash, as after a restart */
  fl.dead = false;
  fl.budget = -1;
  FZ_CHECK(canfdi_nvm_init(&nvm, &port) == CANFDI_OK, "%s", "nvm init");
  const int32_t len = canfdi_nvm_load(&nvm, buf, sizeof buf);
  FZ_CHECK(len >= 0 || len == -CANFDI_ENODATA, "load %d", (int)len);
  FZ_CHECK(len <= (int32_t)sizeof buf, "load %d", (int)len);
  if (mode != 0U && len >= 0) {
    const bool is_a = (len == la) && (memcmp(buf, img_a, (size_t)len) == 0);
    const bool is_b = (len == lb) && (memcmp(buf, img_b, (size_t)len) == 0);
    FZ_CHECK(is_a || is_b, "mode %u: loaded %d bytes, neither image A (%d) nor B (%d)", mode, (int)len,
             (int)la, (int)lb);
  }
  if (mode == 1U && len < 0) {
    FZ_CHECK(0, "%s", "torn store lost both images");
  }
  power_up(buf, len > 0 ? (uint32_t)len : 0U);
  return 0;
}
