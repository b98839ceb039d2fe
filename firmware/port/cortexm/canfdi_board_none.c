/*
 * canfdi_board_none.c — a board with nothing attached: no frames arrive,
 * none leave, no NVM, a tick that never comes late. It links the real
 * application loop (canfdi_cortexm_main.c) into an image whose size and
 * stack are the application's (tests/pil/footprint.py); replace it with
 * the board's drivers (docs/porting.md).
 */
#include "port/cortexm/canfdi_board.h"

static uint32_t now_us;

void canfdi_board_init(void)
{
  now_us = 0U;
}

uint32_t canfdi_board_wait_tick(bool *missed)
{
  *missed = false;
  now_us += CANFDI_CFG_STEP_US;
  return now_us;
}

uint32_t canfdi_board_now_us(void)
{
  return now_us;
}

bool canfdi_board_can_rx(uint32_t *id, uint8_t data[8], uint8_t *dlc, uint32_t *t_us)
{
  (void)id;
  (void)data;
  (void)dlc;
  (void)t_us;
  return false;
}

bool canfdi_board_can_tx(const canfdi_tx_frame_t *f)
{
  (void)f;
  return true;
}

int32_t canfdi_board_nvm_read(uint8_t *buf, uint32_t cap)
{
  (void)buf;
  (void)cap;
  return 0;
}

int32_t canfdi_board_nvm_write(const uint8_t *buf, uint32_t len)
{
  (void)buf;
  (void)len;
  return CANFDI_OK;
}

bool canfdi_board_power_down_requested(void)
{
  return false;
}

void canfdi_board_power_off(void)
{
}
