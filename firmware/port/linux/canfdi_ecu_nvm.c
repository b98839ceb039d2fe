/*
 * canfdi_ecu_nvm.c — canfdi-ecu's NVM; see canfdi_ecu_nvm.h.
 */
#include "port/linux/canfdi_ecu_nvm.h"

#include <errno.h>
#include <inttypes.h>
#include <stdio.h>
#include <string.h>
#include <time.h>

CANFDI_STATIC_ASSERT(CANFDI_NVM_FOOTPRINT(CANFDI_APP_IMAGE_MAX_BYTES, 1U) <= CANFDI_ECU_NVM_BANK_BYTES,
                     ecu_nvm_bank_holds_the_dtc_image);

static int64_t mono_ns(void)
{
  struct timespec ts;
  (void)clock_gettime(CLOCK_MONOTONIC, &ts);
  return ((int64_t)ts.tv_sec * INT64_C(1000000000)) + (int64_t)ts.tv_nsec;
}

static uint32_t elapsed_us(int64_t t0_ns)
{
  const int64_t us = (mono_ns() - t0_ns) / 1000;
  return (us < 0) ? 0U : ((us > (int64_t)UINT32_MAX) ? UINT32_MAX : (uint32_t)us);
}

/* One store, its time and result counted (caller holds no lock). */
static int32_t store(canfdi_ecu_nvm_t *n, const uint8_t *img, uint32_t len)
{
  const int64_t t = mono_ns();
  const int32_t rc = canfdi_nvm_store(&n->nvm, img, len);
  const uint32_t us = elapsed_us(t);
  (void)pthread_mutex_lock(&n->mu);
  if (rc == CANFDI_OK) {
    n->stats.stores++;
  } else {
    n->stats.failures++;
  }
  n->stats.store_us_max = (us > n->stats.store_us_max) ? us : n->stats.store_us_max;
  (void)pthread_mutex_unlock(&n->mu);
  return rc;
}

static void *nvm_thread(void *arg)
{
  static uint8_t local[CANFDI_APP_IMAGE_MAX_BYTES];
  canfdi_ecu_nvm_t *n = (canfdi_ecu_nvm_t *)arg;
  bool quit = false;
  while (!quit) {
    uint32_t len = 0U;
    (void)pthread_mutex_lock(&n->mu);
    while (!n->pending && !n->quit) {
      (void)pthread_cond_wait(&n->cv, &n->mu);
    }
    quit = !n->pending;
    if (n->pending) {
      len = n->len;
      memcpy(local, n->img, len);
      n->pending = false;
    }
    (void)pthread_mutex_unlock(&n->mu);
    if (!quit) {
      (void)store(n, local, len);
    }
  }
  return NULL;
}

/* Reads the stored image; returns its length, or 0 (none; message said). */
static uint32_t load(canfdi_ecu_nvm_t *n, uint8_t *buf, uint32_t cap)
{
  const int32_t len = canfdi_nvm_load(&n->nvm, buf, cap);
  uint32_t out = 0U;
  if (len >= 0) {
    out = (uint32_t)len;
  } else if ((n->nvm.bank_state[0] == (uint8_t)CANFDI_NVM_BANK_EMPTY) &&
             (n->nvm.bank_state[1] == (uint8_t)CANFDI_NVM_BANK_EMPTY)) {
    if (!n->quiet) {
      fprintf(stderr, CANFDI_ECU_PROG ": NVM empty (new device)\n");
    }
  } else {
    fprintf(stderr, CANFDI_ECU_PROG ": NVM file %s: no valid image (bank states %u/%u); starting cleared\n",
            n->path, (unsigned)n->nvm.bank_state[0], (unsigned)n->nvm.bank_state[1]);
  }
  return out;
}

int canfdi_ecu_nvm_start(canfdi_ecu_nvm_t *n, const char *path, bool quiet, canfdi_app_t *app,
                         const canfdi_app_cal_t *cal, int64_t now_ns)
{
  static uint8_t buf[CANFDI_APP_IMAGE_MAX_BYTES];
  int32_t rc = canfdi_nvm_file_open(&n->file, path, CANFDI_ECU_NVM_BANK_BYTES, CANFDI_NVM_FILE_CREATE);
  uint32_t len;
  n->path = path;
  n->quiet = quiet;
  if (rc != CANFDI_OK) {
    fprintf(stderr, CANFDI_ECU_PROG ": cannot open NVM file %s: %s\n", path,
            (rc == -CANFDI_ERANGE) ? "wrong size (another geometry or truncated; not touched)"
                                   : strerror((n->file.last_errno != 0) ? n->file.last_errno : EIO));
    return 1;
  }
  n->port = n->file.port;
  if (canfdi_nvm_init(&n->nvm, &n->port) != CANFDI_OK) {
    fprintf(stderr, CANFDI_ECU_PROG ": NVM file %s: bad geometry\n", path);
    canfdi_nvm_file_close(&n->file);
    return 1;
  }
  len = load(n, buf, (uint32_t)sizeof buf);
  rc = canfdi_app_power_up(app, cal, 0U, buf, len);
  if (rc < 0) {
    fprintf(stderr, CANFDI_ECU_PROG ": the application refused its calibration\n");
    canfdi_nvm_file_close(&n->file);
    return 1;
  }
  if (rc == CANFDI_APP_IMAGE_REJECTED) {
    fprintf(stderr, CANFDI_ECU_PROG ": NVM file %s: DTC image rejected (not this firmware's format, "
                    "or corrupt); starting cleared\n", path);
  } else if ((len > 0U) && !quiet) {
    fprintf(stderr, CANFDI_ECU_PROG ": NVM %s: loaded %" PRIu32 "-byte DTC image (seq %" PRIu32 "), %u DTC(s) stored\n",
            path, len, n->nvm.seq,
            (unsigned)canfdi_dtc_count_by_mask(canfdi_app_dtc(app), (uint8_t)CANFDI_DTC_ST_TFSLC));
  } else {
    /* nothing stored */
  }
  (void)pthread_mutex_init(&n->mu, NULL);
  (void)pthread_cond_init(&n->cv, NULL);
  n->last_ns = now_ns;
  n->changes_seen = canfdi_app_nvm_changes(app);
  if (pthread_create(&n->thread, NULL, nvm_thread, n) != 0) {
    fprintf(stderr, CANFDI_ECU_PROG ": cannot start the NVM thread\n");
    canfdi_nvm_file_close(&n->file);
    return 1;
  }
  n->running = true;
  return 0;
}

void canfdi_ecu_nvm_maybe_store(canfdi_ecu_nvm_t *n, const canfdi_app_t *app, int64_t now_ns)
{
  const uint32_t changes = canfdi_app_nvm_changes(app);
  if (n->running && ((now_ns - n->last_ns) >= ((int64_t)CANFDI_ECU_NVM_PERIOD_S * INT64_C(1000000000))) &&
      (changes != n->changes_seen)) {
    (void)pthread_mutex_lock(&n->mu);
    {
      const int32_t len = canfdi_app_nvm_image(app, n->img, (uint32_t)sizeof n->img);
      if (len >= 0) {
        n->len = (uint32_t)len;
        n->pending = true;
        (void)pthread_cond_signal(&n->cv);
      }
    }
    (void)pthread_mutex_unlock(&n->mu);
    n->changes_seen = changes;
    n->last_ns = now_ns;
  }
}

int canfdi_ecu_nvm_restart(canfdi_ecu_nvm_t *n, canfdi_app_t *app, const canfdi_app_cal_t *cal, uint32_t now_us,
                           int64_t now_ns)
{
  static uint8_t buf[CANFDI_APP_IMAGE_MAX_BYTES];
  const int32_t len = canfdi_app_power_down(app, buf, (uint32_t)sizeof buf);
  int32_t rc = -CANFDI_EINVAL;
  if (len >= 0) {
    if (n->running) {
      (void)pthread_mutex_lock(&n->mu);
      memcpy(n->img, buf, (size_t)len);
      n->len = (uint32_t)len;
      n->pending = true;
      (void)pthread_cond_signal(&n->cv);
      (void)pthread_mutex_unlock(&n->mu);
    }
    rc = canfdi_app_power_up(app, cal, now_us, buf, (uint32_t)len);
  }
  n->changes_seen = canfdi_app_nvm_changes(app);
  n->last_ns = now_ns;
  if (rc != CANFDI_OK) {
    fprintf(stderr, CANFDI_ECU_PROG ": ECU reset: the application did not power up again (%d)\n", (int)rc);
  }
  return (rc == CANFDI_OK) ? 0 : 1;
}

int canfdi_ecu_nvm_finish(canfdi_ecu_nvm_t *n, canfdi_app_t *app, bool do_store)
{
  static uint8_t buf[CANFDI_APP_IMAGE_MAX_BYTES];
  int32_t len;
  int32_t rc = CANFDI_OK;
  if (!n->running) {
    return 0;
  }
  (void)pthread_mutex_lock(&n->mu);
  n->quit = true;
  (void)pthread_cond_signal(&n->cv);
  (void)pthread_mutex_unlock(&n->mu);
  (void)pthread_join(n->thread, NULL);
  n->running = false;
  if (do_store) {
    len = canfdi_app_power_down(app, buf, (uint32_t)sizeof buf);
    rc = (len >= 0) ? store(n, buf, (uint32_t)len) : len;
  }
  canfdi_nvm_file_close(&n->file);
  if (rc != CANFDI_OK) {
    fprintf(stderr, CANFDI_ECU_PROG ": storing the DTC memory in %s failed (%d)\n", n->path, (int)rc);
    return 1;
  }
  return 0;
}

canfdi_ecu_nvm_stats_t canfdi_ecu_nvm_stats(canfdi_ecu_nvm_t *n)
{
  canfdi_ecu_nvm_stats_t s;
  if (n->running) {
    (void)pthread_mutex_lock(&n->mu);
    s = n->stats;
    (void)pthread_mutex_unlock(&n->mu);
  } else {
    s = n->stats;
  }
  return s;
}
