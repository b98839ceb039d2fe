/*
 * canfdi_e2e.h — end-to-end protection of the 1 ms control frames: a CRC-8
 * SAE J1850 and a 4-bit rolling counter, in the manner of AUTOSAR E2E
 * profile 1 (simplified, see "Differences from AUTOSAR P01" below).
 *
 * Used by the firmware (checks sensor frames, protects actuator frames) and
 * by host_sim (protects sensor frames, checks actuator frames), so both ends
 * share one implementation. The Python twin is tools/canfdi/e2e.py.
 *
 * Frame layout (fixed by dbc/canfdi.dbc, classic CAN, DLC 8):
 *   byte 0       CRC-8 SAE J1850
 *   byte 1 0..3  rolling counter 0..15, wraps 15 -> 0
 *   byte 1 4..7  and bytes 2..7: payload (cantools-generated codec)
 * The CRC covers the 16-bit data ID (low byte first, then high byte) and
 * then bytes 1..7, i.e. everything but the CRC byte itself. The data ID of
 * a frame is its 11-bit CAN identifier, so a frame that arrives under the
 * wrong identifier (or a codec mix-up) fails the CRC.
 *
 * CRC-8 SAE J1850: polynomial 0x1D, initial value 0xFF, final XOR 0xFF, no
 * reflection. Check value over ASCII "123456789" is 0x4B. The polynomial is
 * primitive, so over the 9 protected bytes plus the CRC the Hamming
 * distance is 3 (checked by exhaustive search in tests/dbc): every 1- and
 * 2-bit error and every burst of up to 8 bits is detected, and a random
 * corruption slips through with probability 1/256, which is why the counter
 * and the timeout exist.
 *
 * Use:
 *   sender:   canfdi_e2e_tx_init(&tx, id);  each cycle: pack the payload with
 *             the generated codec (any counter/CRC value), then
 *             canfdi_e2e_protect(&tx, frame, 8);
 *   receiver: canfdi_e2e_rx_init(&rx, id, max_delta);  each cycle:
 *             status = canfdi_e2e_check(&rx, frame_or_NULL, dlc);
 *
 * Check state machine (one canfdi_e2e_rx_t per received frame):
 *   frame == NULL                     -> NO_NEW_DATA   (state kept)
 *   dlc != 8                          -> WRONG_LENGTH  (state kept)
 *   CRC mismatch                      -> WRONG_CRC     (state kept)
 *   first good frame after init       -> INITIAL       (counter learnt)
 *   delta = (rx - last) mod 16:
 *     delta == 0                      -> REPEATED      (state kept)
 *     delta == 1                      -> OK
 *     2 <= delta <= max_delta         -> OK_SOME_LOST  (lost = delta - 1)
 *     delta > max_delta               -> WRONG_SEQUENCE (lost = delta - 1),
 *                                        counter resynchronised to rx
 *   Only INITIAL, OK and OK_SOME_LOST frames carry usable data
 *   (canfdi_e2e_status_is_usable()).
 *
 * Differences from AUTOSAR P01 (deliberate, to keep this one job):
 *   - The counter uses all 16 values (P01 reserves 15 as invalid).
 *   - No SyncCounter / MaxNoNewOrRepeatedData: after WRONG_SEQUENCE the very
 *     next consecutive frame is OK again. How many bad statuses make a fault
 *     is the debouncer's decision, not this module's.
 *   - Timeouts are not judged here: NO_NEW_DATA is reported and counted, the
 *     deadline supervision lives with the caller.
 *   - With a 4-bit counter, 16k lost frames alias to REPEATED and 16k+d to
 *     a delta of d; the lost count is therefore modulo 16 and long losses
 *     must be caught by the timeout.
 *
 * Cost (worst case): one CRC over 9 bytes per protect or check. With the
 * table (default) the loop is 6 Thumb-2 instructions per byte (about 10
 * cycles on Cortex-M4 from the disassembly, so roughly 100 cycles per frame;
 * not measured on target); with CANFDI_CFG_E2E_CRC_TABLE 0 it is 8
 * shift/XOR steps per byte, several times slower. Otherwise O(1).
 * Memory: tx 4 bytes, rx 44 bytes (36 of them diagnostic counters). ROM
 * (arm-none-eabi-gcc -Os, Cortex-M4): 592 bytes with the table, 346
 * without. No heap, no recursion, no floating point.
 */
#ifndef CANFDI_E2E_H
#define CANFDI_E2E_H

#include "core/canfdi_common.h"

/* 1: 256-byte const CRC table in ROM, fastest. 0: bitwise, no table (246
 * bytes less ROM), several times slower per byte. Both give identical
 * results (the unit test runs against an independent bitwise reference). */
#ifndef CANFDI_CFG_E2E_CRC_TABLE
#define CANFDI_CFG_E2E_CRC_TABLE 1
#endif

#define CANFDI_E2E_FRAME_LEN 8U     /* DLC of every protected frame */
#define CANFDI_E2E_CRC_BYTE 0U      /* byte index of the CRC */
#define CANFDI_E2E_COUNTER_BYTE 1U  /* byte index of the counter (low nibble) */
#define CANFDI_E2E_COUNTER_MASK 0x0FU
#define CANFDI_E2E_COUNTER_MOD 16U
#define CANFDI_E2E_CRC_INIT 0xFFU
#define CANFDI_E2E_CRC_XOROUT 0xFFU

/* Results of canfdi_e2e_check (non-negative; errors are negative). */
typedef enum {
  CANFDI_E2E_OK = 0,             /* counter advanced by exactly 1 */
  CANFDI_E2E_OK_SOME_LOST = 1,   /* advanced by 2..max_delta; data usable */
  CANFDI_E2E_INITIAL = 2,        /* first valid frame since init; data usable */
  CANFDI_E2E_REPEATED = 3,       /* same counter as the last accepted frame */
  CANFDI_E2E_WRONG_SEQUENCE = 4, /* advanced by more than max_delta */
  CANFDI_E2E_WRONG_CRC = 5,      /* CRC does not match data ID + bytes 1..7 */
  CANFDI_E2E_WRONG_LENGTH = 6,   /* DLC is not CANFDI_E2E_FRAME_LEN */
  CANFDI_E2E_NO_NEW_DATA = 7,    /* called without a frame this cycle */
  CANFDI_E2E_STATUS_COUNT = 8
} canfdi_e2e_status_t;

/* Sender state: one per transmitted protected frame. */
typedef struct {
  uint16_t data_id; /* the CAN identifier */
  uint8_t counter;  /* value the next protect writes, 0..15 */
} canfdi_e2e_tx_t;

/* Monotone diagnostic counters of one receiver; saturate at UINT32_MAX. */
typedef struct {
  uint32_t status[CANFDI_E2E_STATUS_COUNT]; /* calls per status */
  uint32_t lost_frames;                     /* sum of lost counts (mod-16 each) */
} canfdi_e2e_diag_t;

/* Receiver state: one per received protected frame. */
typedef struct {
  uint16_t data_id;      /* the CAN identifier */
  uint8_t max_delta;     /* largest counter step still usable, 1..15 */
  uint8_t last_counter;  /* counter of the last accepted frame */
  bool synced;           /* false until the first valid frame */
  uint8_t lost;          /* frames lost before the last frame (0..15) */
  canfdi_e2e_diag_t diag;
} canfdi_e2e_rx_t;

/*
 * CRC-8 SAE J1850 continuation: feeds `len` bytes into a running register
 * `crc` (start with CANFDI_E2E_CRC_INIT) and returns the new register; the
 * final CRC is register ^ CANFDI_E2E_CRC_XOROUT. Cannot fail by contract
 * (data may be NULL only if len == 0). Cost O(len).
 * Scaling and overflow: pure 8-bit polynomial arithmetic, no overflow.
 */
uint8_t canfdi_e2e_crc8_update(uint8_t crc, const uint8_t *data, size_t len);

/* Complete CRC-8 SAE J1850 of a buffer (init 0xFF, xor-out 0xFF). */
uint8_t canfdi_e2e_crc8(const uint8_t *data, size_t len);

/*
 * The E2E CRC of a frame: over data_id (low byte, high byte) and bytes
 * 1..len-1 of `frame`. Byte 0 is not read. len must be >= 1.
 */
uint8_t canfdi_e2e_frame_crc(uint16_t data_id, const uint8_t *frame, size_t len);

/* Sender: counter starts at 0. Cannot fail by contract (tx non-NULL). */
void canfdi_e2e_tx_init(canfdi_e2e_tx_t *tx, uint16_t data_id);

/*
 * Writes the counter into the low nibble of byte 1 (the high nibble is
 * payload and kept), then the CRC into byte 0, then advances the counter
 * (15 wraps to 0). Returns CANFDI_OK, or -CANFDI_EINVAL if a pointer is
 * NULL or len != CANFDI_E2E_FRAME_LEN (frame untouched, counter kept).
 */
int canfdi_e2e_protect(canfdi_e2e_tx_t *tx, uint8_t *frame, size_t len);

/*
 * Receiver: max_delta is the largest counter step still accepted as usable
 * (1 = any lost frame is WRONG_SEQUENCE). Returns CANFDI_OK, or
 * -CANFDI_EINVAL if rx is NULL or max_delta is not in 1..15.
 */
int canfdi_e2e_rx_init(canfdi_e2e_rx_t *rx, uint16_t data_id, uint8_t max_delta);

/*
 * Judges one received frame (or frame == NULL: nothing arrived this cycle)
 * per the state machine above, updates rx->lost and the diagnostics.
 * Returns a canfdi_e2e_status_t (>= 0), or -CANFDI_EINVAL if rx is NULL.
 */
int canfdi_e2e_check(canfdi_e2e_rx_t *rx, const uint8_t *frame, size_t len);

/* True for INITIAL, OK and OK_SOME_LOST: the payload may be used. */
bool canfdi_e2e_status_is_usable(int status);

#endif /* CANFDI_E2E_H */
