/*
 * fuzz_export.h — fuzz_app_rx's inputs written out as the frames and steps
 * they drive, for the step-cost check on the Cortex-M cores (`make
 * pil-cost`, tests/pil/pil_cost.py). Included by fuzz_app_rx.c when it is
 * built with FUZZ_EXPORT_LOG (tests/fuzz/fuzz_export_main.c, no libFuzzer):
 * the harness's two calls into the application are wrapped so that each
 * received frame and each step also become a candump -L line, then the real
 * function runs and the harness checks its invariants as when fuzzing.
 *
 * The log (read by tests/pil/pil_step.c built with PIL_COST):
 *   (T) fz III#DD..   a frame received at T us (any 11-bit id, 0..8 bytes)
 *   (T) fz FFFFFFFF#  canfdi_app_step at T us
 *   (0) fz FFFFFFFE#  a new input: the application as after canfdi_app_init
 * Harness side only; never part of the firmware.
 */
#ifndef FUZZ_EXPORT_H
#define FUZZ_EXPORT_H

#include <stdio.h>

#include "app/canfdi_app.h"

#define FZ_EXPORT_STEP_ID 0xFFFFFFFFUL
#define FZ_EXPORT_RESET_ID 0xFFFFFFFEUL

/* Where the lines go (set by the export tool's main). */
extern FILE *fz_export_out;

static inline void fz_export_line(uint32_t t_us, unsigned long id, const uint8_t *data, uint8_t dlc)
{
  uint8_t i;
  fprintf(fz_export_out, "(%lu.%06lu) fz %03lX#", (unsigned long)(t_us / 1000000UL),
          (unsigned long)(t_us % 1000000UL), id);
  for (i = 0U; i < dlc; i++) {
    fprintf(fz_export_out, "%02X", data[i]);
  }
  fputc('\n', fz_export_out);
}

static inline int32_t fz_export_rx_frame(canfdi_app_t *a, uint32_t id, const uint8_t *data, uint8_t dlc,
                                         uint32_t now_us)
{
  fz_export_line(now_us, (unsigned long)id, data, (dlc <= 8U) ? dlc : 8U);
  return canfdi_app_rx_frame(a, id, data, dlc, now_us);
}

static inline int32_t fz_export_step(canfdi_app_t *a, uint32_t now_us, canfdi_tx_frame_t *out)
{
  fz_export_line(now_us, FZ_EXPORT_STEP_ID, NULL, 0U);
  return canfdi_app_step(a, now_us, out);
}

#define canfdi_app_rx_frame fz_export_rx_frame
#define canfdi_app_step fz_export_step

#endif /* FUZZ_EXPORT_H */
