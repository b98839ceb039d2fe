/*
 * canfdi_board.h — what a board provides to the Cortex-M port
 * (canfdi_cortexm_main.c): the only hardware-facing functions the
 * application's loop calls. docs/porting.md explains each with the
 * timing it must meet; canfdi_board_none.c is the empty board the
 * footprint image links (tests/pil/footprint.py).
 *
 * Contract: no function blocks except canfdi_board_wait_tick; none is
 * called from an interrupt by the port; a board may receive CAN frames in
 * an interrupt into its own queue and hand them out from
 * canfdi_board_can_rx. Cost and memory are the board's.
 */
#ifndef CANFDI_BOARD_H
#define CANFDI_BOARD_H

#include "comm/canfdi_tx.h"
#include "core/canfdi_common.h"

/* Clocks, CAN controller (500 kbit/s, the ids of dbc/canfdi.dbc), the 1 ms
 * tick, NVM. Called once before anything else. */
void canfdi_board_init(void);

/* Waits for the next 1 ms tick and returns the microsecond clock then
 * (uint32_t, wraps every 71.6 min). Sets *missed when one or more ticks
 * passed since the last call (the step overran). */
uint32_t canfdi_board_wait_tick(bool *missed);

/* The microsecond clock now (for the step's execution time). */
uint32_t canfdi_board_now_us(void);

/* One received frame, if any: true and *id, data[0..7], *dlc filled; the
 * receive time in *t_us (the same clock). */
bool canfdi_board_can_rx(uint32_t *id, uint8_t data[8], uint8_t *dlc, uint32_t *t_us);

/* Queues one frame for transmission; false when the controller's queue is
 * full (the port counts it as a deadline problem: the step's frames must
 * leave within the step). */
bool canfdi_board_can_tx(const canfdi_tx_frame_t *f);

/* NVM: the DTC memory's image, at most CANFDI_DTC_IMAGE_MAX_BYTES. read
 * returns the stored length (0: none); write stores len bytes and returns
 * CANFDI_OK or a negative error (it may take several ms: the port calls it
 * only after a power-down request or between steps when the image changed). */
int32_t canfdi_board_nvm_read(uint8_t *buf, uint32_t cap);
int32_t canfdi_board_nvm_write(const uint8_t *buf, uint32_t len);

/* True once the ignition is off (power-down requested): the port stores the
 * image and calls canfdi_board_power_off. */
bool canfdi_board_power_down_requested(void);
void canfdi_board_power_off(void);

#endif /* CANFDI_BOARD_H */
