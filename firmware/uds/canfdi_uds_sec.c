/*
 * canfdi_uds_sec.c — SecurityAccess state machine; the manual is the header.
 */
#include "uds/canfdi_uds_sec.h"

#include "uds/canfdi_uds_msg.h"

#define DELAY_MAX_MS 3600000U

void canfdi_uds_sec_default_cfg(canfdi_uds_sec_cfg_t *cfg)
{
  if (cfg != NULL) {
    cfg->key_fn = NULL;
    cfg->delay_ms = 10000U;
    cfg->attempt_limit = 3U;
    cfg->levels = 1U;
  }
}

uint32_t canfdi_uds_sec_key_default(uint32_t seed, uint8_t level)
{
  const uint32_t secret = (level == 2U) ? CANFDI_CFG_UDS_SECRET_L2 : CANFDI_CFG_UDS_SECRET_L1;
  uint32_t k = seed ^ secret;
  k = (k << 11) | (k >> 21);
  k = k * 0x9E3779B1U;
  return k ^ (k >> 15);
}

static uint32_t xorshift(uint32_t x0)
{
  uint32_t x = (x0 != 0U) ? x0 : 0x6D2B79F5U;
  x ^= x << 13;
  x ^= x >> 17;
  x ^= x << 5;
  return x;
}

int32_t canfdi_uds_sec_init(canfdi_uds_sec_t *s, const canfdi_uds_sec_cfg_t *cfg, uint8_t attempts,
                            uint32_t entropy)
{
  int32_t rc = -CANFDI_EINVAL;
  if ((s != NULL) && (cfg != NULL) && (cfg->attempt_limit >= 1U) && (cfg->levels >= 1U) &&
      (cfg->levels <= CANFDI_UDS_SEC_MAX_LEVELS) && (cfg->delay_ms >= 1U) && (cfg->delay_ms <= DELAY_MAX_MS)) {
    s->cfg = *cfg;
    s->prng = xorshift(entropy ^ 0xA5A5A5A5U);
    s->seed = 0U;
    s->seed_level = 0U;
    s->unlocked = 0U;
    s->attempts = attempts;
    s->changes = 0U;
    /* a power-up at the limit does not buy a guess */
    s->delay_left_ms = (attempts >= cfg->attempt_limit) ? cfg->delay_ms : 0U;
    rc = CANFDI_OK;
  }
  return rc;
}

void canfdi_uds_sec_lock(canfdi_uds_sec_t *s)
{
  if (s != NULL) {
    s->unlocked = 0U;
    s->seed_level = 0U;
    s->seed = 0U;
  }
}

void canfdi_uds_sec_tick(canfdi_uds_sec_t *s)
{
  if ((s != NULL) && (s->delay_left_ms > 0U)) {
    s->delay_left_ms--;
  }
}

uint8_t canfdi_uds_sec_level(const canfdi_uds_sec_t *s) { return (s != NULL) ? s->unlocked : 0U; }

static uint8_t request_seed(canfdi_uds_sec_t *s, uint8_t level, uint32_t len, uint32_t stir, uint8_t *seed_out)
{
  uint8_t nrc = CANFDI_UDS_NRC_OK;
  uint32_t seed = 0U;
  if (len != 2U) {
    nrc = CANFDI_UDS_NRC_IMLOIF;
  } else if (s->delay_left_ms > 0U) {
    nrc = CANFDI_UDS_NRC_RTDNE;
  } else if (s->unlocked == level) {
    s->seed_level = 0U; /* already unlocked: seed 0, nothing to answer */
  } else {
    s->prng = xorshift(s->prng ^ stir);
    seed = (s->prng != 0U) ? s->prng : 1U;
    s->seed = seed;
    s->seed_level = level;
  }
  for (uint32_t i = 0U; i < CANFDI_UDS_SEC_SEED_BYTES; i++) {
    seed_out[i] = (uint8_t)((seed >> (8U * (3U - i))) & 0xFFU);
  }
  return nrc;
}

static uint8_t send_key(canfdi_uds_sec_t *s, uint8_t level, const uint8_t *req, uint32_t len)
{
  uint8_t nrc = CANFDI_UDS_NRC_OK;
  if (len != (2U + CANFDI_UDS_SEC_SEED_BYTES)) {
    nrc = CANFDI_UDS_NRC_IMLOIF;
  } else if (s->delay_left_ms > 0U) {
    nrc = CANFDI_UDS_NRC_RTDNE;
  } else if ((s->seed_level == 0U) || (s->seed_level != level)) {
    s->seed_level = 0U;
    nrc = CANFDI_UDS_NRC_RSE;
  } else {
    const canfdi_uds_key_fn_t fn = (s->cfg.key_fn != NULL) ? s->cfg.key_fn : canfdi_uds_sec_key_default;
    const uint32_t want = fn(s->seed, level);
    s->seed_level = 0U;
    if (canfdi_uds_get_u32(&req[2]) == want) {
      s->unlocked = level;
      if (s->attempts != 0U) {
        s->attempts = 0U;
        s->changes++;
      }
    } else {
      if (s->attempts < UINT8_MAX) {
        s->attempts++;
      }
      s->changes++;
      if (s->attempts >= s->cfg.attempt_limit) {
        s->delay_left_ms = s->cfg.delay_ms;
        nrc = CANFDI_UDS_NRC_ENOA;
      } else {
        nrc = CANFDI_UDS_NRC_IK;
      }
    }
  }
  return nrc;
}

uint8_t canfdi_uds_sec_request(canfdi_uds_sec_t *s, const uint8_t *req, uint32_t len, uint32_t stir,
                               uint8_t seed_out[CANFDI_UDS_SEC_SEED_BYTES])
{
  uint8_t nrc = CANFDI_UDS_NRC_SFNS;
  if ((s != NULL) && (req != NULL) && (seed_out != NULL) && (len >= 2U)) {
    const uint8_t sf = (uint8_t)(req[1] & 0x7FU);
    const uint8_t level = (uint8_t)((sf + 1U) / 2U);
    if ((sf >= 1U) && (level <= s->cfg.levels)) {
      nrc = ((sf & 1U) != 0U) ? request_seed(s, level, len, stir, seed_out) : send_key(s, level, req, len);
    }
  }
  return nrc;
}
