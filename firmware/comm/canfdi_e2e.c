/*
 * canfdi_e2e.c — CRC-8 SAE J1850 and the rolling-counter check; see the
 * header for the frame layout and the state machine.
 */
#include "comm/canfdi_e2e.h"

#include "core/canfdi_count.h"

#define CRC8_POLY 0x1DU

#if CANFDI_CFG_E2E_CRC_TABLE
/* T[i] = i shifted through 8 steps of the MSB-first LFSR with 0x1D, i.e.
 * the CRC register after feeding byte i into a zero register. */
static const uint8_t crc8_table[256] = {
  0x00U, 0x1DU, 0x3AU, 0x27U, 0x74U, 0x69U, 0x4EU, 0x53U, 0xE8U, 0xF5U, 0xD2U, 0xCFU, 0x9CU, 0x81U, 0xA6U, 0xBBU,
  0xCDU, 0xD0U, 0xF7U, 0xEAU, 0xB9U, 0xA4U, 0x83U, 0x9EU, 0x25U, 0x38U, 0x1FU, 0x02U, 0x51U, 0x4CU, 0x6BU, 0x76U,
  0x87U, 0x9AU, 0xBDU, 0xA0U, 0xF3U, 0xEEU, 0xC9U, 0xD4U, 0x6FU, 0x72U, 0x55U, 0x48U, 0x1BU, 0x06U, 0x21U, 0x3CU,
  0x4AU, 0x57U, 0x70U, 0x6DU, 0x3EU, 0x23U, 0x04U, 0x19U, 0xA2U, 0xBFU, 0x98U, 0x85U, 0xD6U, 0xCBU, 0xECU, 0xF1U,
  0x13U, 0x0EU, 0x29U, 0x34U, 0x67U, 0x7AU, 0x5DU, 0x40U, 0xFBU, 0xE6U, 0xC1U, 0xDCU, 0x8FU, 0x92U, 0xB5U, 0xA8U,
  0xDEU, 0xC3U, 0xE4U, 0xF9U, 0xAAU, 0xB7U, 0x90U, 0x8DU, 0x36U, 0x2BU, 0x0CU, 0x11U, 0x42U, 0x5FU, 0x78U, 0x65U,
  0x94U, 0x89U, 0xAEU, 0xB3U, 0xE0U, 0xFDU, 0xDAU, 0xC7U, 0x7CU, 0x61U, 0x46U, 0x5BU, 0x08U, 0x15U, 0x32U, 0x2FU,
  0x59U, 0x44U, 0x63U, 0x7EU, 0x2DU, 0x30U, 0x17U, 0x0AU, 0xB1U, 0xACU, 0x8BU, 0x96U, 0xC5U, 0xD8U, 0xFFU, 0xE2U,
  0x26U, 0x3BU, 0x1CU, 0x01U, 0x52U, 0x4FU, 0x68U, 0x75U, 0xCEU, 0xD3U, 0xF4U, 0xE9U, 0xBAU, 0xA7U, 0x80U, 0x9DU,
  0xEBU, 0xF6U, 0xD1U, 0xCCU, 0x9FU, 0x82U, 0xA5U, 0xB8U, 0x03U, 0x1EU, 0x39U, 0x24U, 0x77U, 0x6AU, 0x4DU, 0x50U,
  0xA1U, 0xBCU, 0x9BU, 0x86U, 0xD5U, 0xC8U, 0xEFU, 0xF2U, 0x49U, 0x54U, 0x73U, 0x6EU, 0x3DU, 0x20U, 0x07U, 0x1AU,
  0x6CU, 0x71U, 0x56U, 0x4BU, 0x18U, 0x05U, 0x22U, 0x3FU, 0x84U, 0x99U, 0xBEU, 0xA3U, 0xF0U, 0xEDU, 0xCAU, 0xD7U,
  0x35U, 0x28U, 0x0FU, 0x12U, 0x41U, 0x5CU, 0x7BU, 0x66U, 0xDDU, 0xC0U, 0xE7U, 0xFAU, 0xA9U, 0xB4U, 0x93U, 0x8EU,
  0xF8U, 0xE5U, 0xC2U, 0xDFU, 0x8CU, 0x91U, 0xB6U, 0xABU, 0x10U, 0x0DU, 0x2AU, 0x37U, 0x64U, 0x79U, 0x5EU, 0x43U,
  0xB2U, 0xAFU, 0x88U, 0x95U, 0xC6U, 0xDBU, 0xFCU, 0xE1U, 0x5AU, 0x47U, 0x60U, 0x7DU, 0x2EU, 0x33U, 0x14U, 0x09U,
  0x7FU, 0x62U, 0x45U, 0x58U, 0x0BU, 0x16U, 0x31U, 0x2CU, 0x97U, 0x8AU, 0xADU, 0xB0U, 0xE3U, 0xFEU, 0xD9U, 0xC4U,
};
#endif

uint8_t canfdi_e2e_crc8_update(uint8_t crc, const uint8_t *data, size_t len)
{
  uint8_t reg = crc;
  for (size_t i = 0U; i < len; i++) {
#if CANFDI_CFG_E2E_CRC_TABLE
    reg = crc8_table[(uint8_t)(reg ^ data[i])];
#else
    reg = (uint8_t)(reg ^ data[i]);
    for (unsigned bit = 0U; bit < 8U; bit++) {
      /* MSB-first: shift out the top bit, fold the polynomial back in if it
       * was set. The cast keeps the register 8 bits wide. */
      const bool top = (reg & 0x80U) != 0U;
      reg = (uint8_t)(reg << 1);
      if (top) {
        reg = (uint8_t)(reg ^ CRC8_POLY);
      }
    }
#endif
  }
  return reg;
}

uint8_t canfdi_e2e_crc8(const uint8_t *data, size_t len)
{
  return (uint8_t)(canfdi_e2e_crc8_update(CANFDI_E2E_CRC_INIT, data, len) ^ CANFDI_E2E_CRC_XOROUT);
}

uint8_t canfdi_e2e_frame_crc(uint16_t data_id, const uint8_t *frame, size_t len)
{
  CANFDI_ASSERT(frame != NULL && len >= 1U);
  const uint8_t id_bytes[2] = {(uint8_t)(data_id & 0xFFU), (uint8_t)(data_id >> 8)};
  uint8_t reg = canfdi_e2e_crc8_update(CANFDI_E2E_CRC_INIT, id_bytes, sizeof id_bytes);
  reg = canfdi_e2e_crc8_update(reg, &frame[CANFDI_E2E_CRC_BYTE + 1U], len - 1U);
  return (uint8_t)(reg ^ CANFDI_E2E_CRC_XOROUT);
}

void canfdi_e2e_tx_init(canfdi_e2e_tx_t *tx, uint16_t data_id)
{
  CANFDI_ASSERT(tx != NULL);
  tx->data_id = data_id;
  tx->counter = 0U;
}

int canfdi_e2e_protect(canfdi_e2e_tx_t *tx, uint8_t *frame, size_t len)
{
  int out = -CANFDI_EINVAL;
  if ((tx != NULL) && (frame != NULL) && (len == CANFDI_E2E_FRAME_LEN)) {
    CANFDI_ASSERT(tx->counter < CANFDI_E2E_COUNTER_MOD);
    frame[CANFDI_E2E_COUNTER_BYTE] =
        (uint8_t)((frame[CANFDI_E2E_COUNTER_BYTE] & (uint8_t)~CANFDI_E2E_COUNTER_MASK) | tx->counter);
    frame[CANFDI_E2E_CRC_BYTE] = canfdi_e2e_frame_crc(tx->data_id, frame, len);
    /* Wrapping 15 -> 0 is the documented intent of a rolling counter. */
    tx->counter = (uint8_t)((tx->counter + 1U) & CANFDI_E2E_COUNTER_MASK);
    out = CANFDI_OK;
  }
  return out;
}

int canfdi_e2e_rx_init(canfdi_e2e_rx_t *rx, uint16_t data_id, uint8_t max_delta)
{
  int out = -CANFDI_EINVAL;
  if ((rx != NULL) && (max_delta >= 1U) && (max_delta < CANFDI_E2E_COUNTER_MOD)) {
    rx->data_id = data_id;
    rx->max_delta = max_delta;
    rx->last_counter = 0U;
    rx->synced = false;
    rx->lost = 0U;
    for (unsigned i = 0U; i < (unsigned)CANFDI_E2E_STATUS_COUNT; i++) {
      rx->diag.status[i] = 0U;
    }
    rx->diag.lost_frames = 0U;
    out = CANFDI_OK;
  }
  return out;
}

static canfdi_e2e_status_t judge(canfdi_e2e_rx_t *rx, const uint8_t *frame, size_t len)
{
  canfdi_e2e_status_t st;
  if (frame == NULL) {
    st = CANFDI_E2E_NO_NEW_DATA;
  } else if (len != CANFDI_E2E_FRAME_LEN) {
    st = CANFDI_E2E_WRONG_LENGTH;
  } else if (frame[CANFDI_E2E_CRC_BYTE] != canfdi_e2e_frame_crc(rx->data_id, frame, len)) {
    st = CANFDI_E2E_WRONG_CRC;
  } else {
    const uint8_t counter = (uint8_t)(frame[CANFDI_E2E_COUNTER_BYTE] & CANFDI_E2E_COUNTER_MASK);
    /* Modulo-16 difference; unsigned wrap is the intent. */
    const uint8_t delta =
        (uint8_t)((counter + CANFDI_E2E_COUNTER_MOD - rx->last_counter) & CANFDI_E2E_COUNTER_MASK);
    if (!rx->synced) {
      st = CANFDI_E2E_INITIAL;
      rx->lost = 0U;
    } else if (delta == 0U) {
      st = CANFDI_E2E_REPEATED;
    } else if (delta == 1U) {
      st = CANFDI_E2E_OK;
      rx->lost = 0U;
    } else {
      st = (delta <= rx->max_delta) ? CANFDI_E2E_OK_SOME_LOST : CANFDI_E2E_WRONG_SEQUENCE;
      rx->lost = (uint8_t)(delta - 1U);
      canfdi_count_add(&rx->diag.lost_frames, rx->lost);
    }
    /* Also right for REPEATED, where counter == last_counter already. */
    rx->last_counter = counter;
    rx->synced = true;
  }
  return st;
}

int canfdi_e2e_check(canfdi_e2e_rx_t *rx, const uint8_t *frame, size_t len)
{
  int out = -CANFDI_EINVAL;
  if (rx != NULL) {
    const canfdi_e2e_status_t st = judge(rx, frame, len);
    canfdi_count_inc(&rx->diag.status[st]);
    out = (int)st;
  }
  return out;
}

bool canfdi_e2e_status_is_usable(int status)
{
  return (status == (int)CANFDI_E2E_OK) || (status == (int)CANFDI_E2E_OK_SOME_LOST) ||
         (status == (int)CANFDI_E2E_INITIAL);
}
