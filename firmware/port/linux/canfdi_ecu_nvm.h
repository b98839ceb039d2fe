/*
 * canfdi_ecu_nvm.h — canfdi-ecu's NVM (--nvm FILE): the DTC memory in a
 * two-bank file (canfdi_nvm_file + diag/canfdi_nvm), stored without
 * stalling the 1 ms loop.
 *
 * Start: the stored image is read and the application powered up with it
 * (canfdi_app_power_up: the image replaces the fresh memory and a new
 * operation cycle starts). Running: at most every CANFDI_ECU_NVM_PERIOD_S
 * seconds, when the memory changed (canfdi_app_nvm_changes), the loop
 * serialises the image (~2k instructions) and hands it to a background
 * thread, because a store costs one erase and four writes of the bank
 * file, each followed by fdatasync: milliseconds on a disk, which must not
 * stall the loop. A periodic image is taken mid-cycle: after a crash the
 * next start loads it and starts a new cycle without ending the
 * interrupted one (no healing step for it, as after a power cut on a real
 * ECU). Clean exit: canfdi_app_power_down ends the cycle and the image is
 * stored synchronously.
 * Memory: the instance holds two image buffers of CANFDI_APP_IMAGE_MAX_BYTES
 * and the file port; static in the port.
 */
#ifndef CANFDI_ECU_NVM_H
#define CANFDI_ECU_NVM_H

#include <pthread.h>
#include <stdbool.h>
#include <stdint.h>

#include "app/canfdi_app.h"
#include "diag/canfdi_nvm.h"
#include "port/linux/canfdi_ecu_stats.h"
#include "port/linux/canfdi_nvm_file.h"

#define CANFDI_ECU_NVM_PERIOD_S 10
#define CANFDI_ECU_NVM_BANK_BYTES 1024U

typedef struct {
  const char *path;
  bool quiet;
  pthread_t thread;
  pthread_mutex_t mu;
  pthread_cond_t cv;
  bool running;
  bool pending; /* under mu: an image waits for the thread */
  bool quit;    /* under mu */
  uint8_t img[CANFDI_APP_IMAGE_MAX_BYTES]; /* under mu */
  uint32_t len;                            /* under mu */
  canfdi_nvm_file_t file;
  canfdi_nvm_t nvm;
  canfdi_nvm_port_t port;
  int64_t last_ns;        /* last periodic hand-over */
  uint32_t changes_seen;  /* canfdi_app_nvm_changes at the last hand-over */
  canfdi_ecu_nvm_stats_t stats; /* under mu */
} canfdi_ecu_nvm_t;

/* Opens path (created if missing), powers the app up with the stored image
 * (or none) and starts the background store. Returns 0, or 1 with a
 * message on stderr (file unusable, calibration refused). */
int canfdi_ecu_nvm_start(canfdi_ecu_nvm_t *n, const char *path, bool quiet, canfdi_app_t *app,
                         const canfdi_app_cal_t *cal, int64_t now_ns);

/* Outside the step: hands a new image to the thread when due. */
void canfdi_ecu_nvm_maybe_store(canfdi_ecu_nvm_t *n, const canfdi_app_t *app, int64_t now_ns);

/* ECUReset: powers the app down, hands the image to the background store
 * (the next power-up's image) and powers the app up from it at now_us.
 * Returns 0, or 1 with a message on stderr. Without a started NVM the
 * image goes from power-down to power-up in RAM. */
int canfdi_ecu_nvm_restart(canfdi_ecu_nvm_t *n, canfdi_app_t *app, const canfdi_app_cal_t *cal, uint32_t now_us,
                           int64_t now_ns);

/* Stops the thread; with store, powers the app down and stores its image.
 * Returns 0, or 1 with a message on stderr. No-op (0) when not started. */
int canfdi_ecu_nvm_finish(canfdi_ecu_nvm_t *n, canfdi_app_t *app, bool store);

/* The store counters (thread-safe copy). */
canfdi_ecu_nvm_stats_t canfdi_ecu_nvm_stats(canfdi_ecu_nvm_t *n);

#endif /* CANFDI_ECU_NVM_H */
