/*
 * canfdi_cortexm_main.c — the application's loop on a Cortex-M: power-up
 * with the NVM image, then every 1 ms tick: hand every received frame to
 * the application, run one step, queue its frames, report the step's
 * timing; on a power-down request store the DTC memory and switch off.
 * The board functions are canfdi_board.h's (docs/porting.md).
 *
 * Memory: the application's state (canfdi_app_t) and the NVM image buffer
 * (CANFDI_DTC_IMAGE_MAX_BYTES) are static; the calibration lives on the
 * stack of power_up() only (the application keeps its own copy). Stack:
 * the worst case, measured by tests/pil/footprint.py.
 */
#include "app/canfdi_app.h"
#include "port/cortexm/canfdi_board.h"

static canfdi_app_t app;
static uint8_t image[CANFDI_DTC_IMAGE_MAX_BYTES];

int main(void);

/* Stores the image when the DTC memory changed since the last store. */
static void store_if_changed(uint32_t *stored)
{
  const uint32_t c = canfdi_app_nvm_changes(&app);
  if (c != *stored) {
    const int32_t len = canfdi_app_nvm_image(&app, image, (uint32_t)sizeof image);
    if ((len > 0) && (canfdi_board_nvm_write(image, (uint32_t)len) == CANFDI_OK)) {
      *stored = c;
    }
  }
}

static void one_step(uint32_t now_us)
{
  canfdi_tx_frame_t out[CANFDI_APP_MAX_TX];
  uint32_t id;
  uint8_t data[8];
  uint8_t dlc;
  uint32_t t_us;
  int32_t n;
  int32_t i;
  const uint32_t t0 = canfdi_board_now_us();
  while (canfdi_board_can_rx(&id, data, &dlc, &t_us)) {
    (void)canfdi_app_rx_frame(&app, id, data, dlc, t_us);
  }
  n = canfdi_app_step(&app, now_us, out);
  for (i = 0; i < n; i++) {
    if (!canfdi_board_can_tx(&out[i])) {
      canfdi_app_deadline_miss(&app);
    }
  }
  canfdi_app_port_timing(&app, canfdi_board_now_us() - t0, 0U);
}

/* Cold start with the stored DTC memory (the calibration is copied by the
 * application, so it needs no static home here). */
static void power_up(void)
{
  canfdi_app_cal_t cal;
  int32_t len;
  canfdi_app_default_cal(&cal);
  len = canfdi_board_nvm_read(image, (uint32_t)sizeof image);
  (void)canfdi_app_power_up(&app, &cal, canfdi_board_now_us(), image, (len > 0) ? (uint32_t)len : 0U);
}

int main(void)
{
  uint32_t stored;
  int32_t len;
  bool running = true;
  canfdi_board_init();
  power_up();
  stored = canfdi_app_nvm_changes(&app);
  while (running) {
    bool missed = false;
    const uint32_t now = canfdi_board_wait_tick(&missed);
    if (missed) {
      canfdi_app_deadline_miss(&app);
    }
    one_step(now);
    if (canfdi_board_power_down_requested()) {
      len = canfdi_app_power_down(&app, image, (uint32_t)sizeof image);
      if (len > 0) {
        (void)canfdi_board_nvm_write(image, (uint32_t)len);
      }
      canfdi_board_power_off();
      running = false;
    } else {
      store_if_changed(&stored);
    }
  }
  return 0;
}
