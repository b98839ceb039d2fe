/*
 * canfdi_ecu_stats.c — canfdi-ecu's run statistics; see canfdi_ecu_stats.h.
 */
#include "port/linux/canfdi_ecu_stats.h"

#include <errno.h>
#include <inttypes.h>
#include <stdio.h>
#include <string.h>

void canfdi_ecu_hist_add(canfdi_ecu_hist_t *h, uint32_t v)
{
  h->bin[(v < CANFDI_ECU_HIST_BINS) ? v : CANFDI_ECU_HIST_BINS]++;
  h->n++;
  h->max = (v > h->max) ? v : h->max;
}

uint32_t canfdi_ecu_hist_pct(const canfdi_ecu_hist_t *h, uint32_t p)
{
  uint64_t rank = (h->n * p + 9999U) / 10000U;
  uint64_t cum = 0U;
  uint32_t out = h->max;
  uint32_t v;
  bool found = false;
  if (h->n == 0U) {
    out = 0U;
    found = true;
  }
  rank = (rank == 0U) ? 1U : rank;
  for (v = 0U; (v < CANFDI_ECU_HIST_BINS) && !found; v++) {
    cum += h->bin[v];
    if (cum >= rank) {
      out = v;
      found = true;
    }
  }
  return out;
}

static void json_hist(FILE *f, const char *name, const canfdi_ecu_hist_t *h, const char *tail)
{
  fprintf(f, "  \"%s\": {\"p50\": %" PRIu32 ", \"p99\": %" PRIu32 ", \"p999\": %" PRIu32
             ", \"max\": %" PRIu32 ", \"n\": %" PRIu64 "}%s\n",
          name, canfdi_ecu_hist_pct(h, 5000U), canfdi_ecu_hist_pct(h, 9900U),
          canfdi_ecu_hist_pct(h, 9990U), h->max, h->n, tail);
}

int canfdi_ecu_write_stats(const char *path, const canfdi_ecu_report_t *r)
{
  const canfdi_ecu_counts_t *c = r->counts;
  FILE *f = fopen(path, "w");
  if (f == NULL) {
    fprintf(stderr, CANFDI_ECU_PROG ": cannot write %s: %s\n", path, strerror(errno));
    return 1;
  }
  fprintf(f, "{\n");
  fprintf(f, "  \"mode\": \"%s\",\n", r->opts->lockstep ? "lockstep" : "realtime");
  fprintf(f, "  \"iface\": \"%s\",\n", r->opts->iface);
  fprintf(f, "  \"run_s\": %" PRId64 ".%03" PRId64 ",\n", r->run_ns / 1000000000,
          (r->run_ns / 1000000) % 1000);
  fprintf(f, "  \"steps\": %" PRIu64 ",\n", c->steps);
  fprintf(f, "  \"deadline_misses\": %" PRIu64 ",\n", c->deadline_misses);
  fprintf(f, "  \"skipped_periods\": %" PRIu64 ",\n", c->skipped_periods);
  fprintf(f, "  \"lockstep_gaps\": %" PRIu64 ",\n", c->lockstep_gaps);
  fprintf(f, "  \"stale_steps\": %" PRIu64 ",\n", c->stale_steps);
  fprintf(f, "  \"simstep_bad_length\": %" PRIu64 ",\n", c->simstep_bad_length);
  fprintf(f, "  \"simstep_ignored\": %" PRIu64 ",\n", c->simstep_ignored);
  fprintf(f, "  \"ecu_resets\": %" PRIu64 ",\n", c->ecu_resets);
  fprintf(f, "  \"frames_rx\": %" PRIu32 ",\n", r->sock->rx_frames);
  fprintf(f, "  \"frames_tx\": %" PRIu32 ",\n", r->sock->tx_frames);
  fprintf(f, "  \"frames_to_app\": %" PRIu64 ",\n", c->frames_to_app);
  fprintf(f, "  \"frames_rejected\": %" PRIu32 ",\n", r->app->frames_rejected);
  fprintf(f, "  \"frames_unknown\": %" PRIu32 ",\n", r->app->frames_unknown);
  fprintf(f, "  \"tx_drops\": %" PRIu32 ",\n", r->sock->tx_drops);
  fprintf(f, "  \"tx_retries\": %" PRIu32 ",\n", r->sock->tx_retries);
  fprintf(f, "  \"rx_kernel_drops\": %" PRIu32 ",\n", r->sock->rx_kernel_drops);
  fprintf(f, "  \"socket_errors\": %" PRIu64 ",\n", c->socket_errors);
  fprintf(f, "  \"nvm\": {\"stores\": %" PRIu32 ", \"failures\": %" PRIu32
             ", \"store_us_max\": %" PRIu32 "},\n",
          r->nvm.stores, r->nvm.failures, r->nvm.store_us_max);
  json_hist(f, "step_us", r->step, ",");
  /* wake-up lateness: realtime only (zeros in lockstep) */
  json_hist(f, "latency_us", r->latency, "");
  fprintf(f, "}\n");
  if (fclose(f) != 0) {
    fprintf(stderr, CANFDI_ECU_PROG ": cannot write %s: %s\n", path, strerror(errno));
    return 1;
  }
  return 0;
}
