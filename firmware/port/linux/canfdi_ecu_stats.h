/*
 * canfdi_ecu_stats.h — canfdi-ecu's run statistics: 1 us histograms of the
 * step time and the wake-up lateness, the port's counters, and the JSON
 * file of --stats.
 *
 * JSON keys: mode, iface, run_s, steps, deadline_misses, skipped_periods,
 * lockstep_gaps, stale_steps, simstep_bad_length, simstep_ignored, ecu_resets,
 * frames_rx, frames_tx, frames_to_app, frames_rejected and frames_unknown
 * (the app's input supervision), tx_drops, tx_retries, rx_kernel_drops,
 * socket_errors, nvm {stores, failures, store_us_max}, step_us and
 * latency_us {p50, p99, p999, max, n} (nearest-rank percentiles from 1 us
 * histograms up to 10 ms; beyond, the max). latency_us is realtime only
 * (zeros in lockstep).
 * Memory: a histogram is 40 kB (10 001 bins); the port keeps two, static.
 */
#ifndef CANFDI_ECU_STATS_H
#define CANFDI_ECU_STATS_H

#include <stdint.h>

#include "app/canfdi_app.h"
#include "port/linux/canfdi_ecu_cli.h"
#include "port/linux/canfdi_socketcan.h"

#define CANFDI_ECU_HIST_BINS 10000U /* 1 us bins; larger values in one overflow bin */

typedef struct {
  uint32_t bin[CANFDI_ECU_HIST_BINS + 1U];
  uint64_t n;
  uint32_t max;
} canfdi_ecu_hist_t;

/* The port's counters (uint64_t: they cannot wrap in any run). */
typedef struct {
  uint64_t steps;
  uint64_t deadline_misses;
  uint64_t skipped_periods;
  uint64_t lockstep_gaps;
  uint64_t stale_steps;
  uint64_t simstep_bad_length;
  uint64_t simstep_ignored; /* SimStep frames in realtime mode */
  uint64_t socket_errors;
  uint64_t frames_to_app;
  uint64_t ecu_resets;      /* UDS ECUReset: application powered down and up */
} canfdi_ecu_counts_t;

typedef struct {
  uint32_t stores;
  uint32_t failures;
  uint32_t store_us_max;
} canfdi_ecu_nvm_stats_t;

void canfdi_ecu_hist_add(canfdi_ecu_hist_t *h, uint32_t v);

/* The smallest value v with at least ceil(n * p / 10000) samples <= v
 * (nearest-rank percentile; p in 1/10000); values beyond the bins: max;
 * 0 when empty. */
uint32_t canfdi_ecu_hist_pct(const canfdi_ecu_hist_t *h, uint32_t p);

/* Everything the JSON file reports. */
typedef struct {
  const canfdi_ecu_opts_t *opts;
  int64_t run_ns;
  const canfdi_ecu_counts_t *counts;
  const canfdi_socketcan_diag_t *sock;
  const canfdi_app_diag_t *app;
  canfdi_ecu_nvm_stats_t nvm;
  const canfdi_ecu_hist_t *step;
  const canfdi_ecu_hist_t *latency;
} canfdi_ecu_report_t;

/* Writes the JSON file. Returns 0, or 1 with a message on stderr. */
int canfdi_ecu_write_stats(const char *path, const canfdi_ecu_report_t *r);

#endif /* CANFDI_ECU_STATS_H */
