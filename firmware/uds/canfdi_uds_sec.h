/*
 * canfdi_uds_sec.h — SecurityAccess (UDS 0x27): the seed/key state machine
 * of the diagnostic server, with an attempt counter that survives a
 * power-up.
 *
 * Levels. Level n (1..cfg.levels, at most 2) is unlocked by requestSeed
 * 2n-1 and sendKey 2n: level 1 is 0x01/0x02, level 2 0x03/0x04.
 *
 * State machine (one instance; every rule is checked in this order):
 *   requestSeed (length 2, else NRC 0x13):
 *     the delay runs                      -> NRC 0x37 requiredTimeDelayNotExpired
 *     the level is already unlocked       -> seed 00 00 00 00 (ISO 14229-1)
 *     else                                -> a new 4-byte seed (never 0) for
 *                                            this level; any earlier seed is void
 *   sendKey (length 6, else NRC 0x13):
 *     the delay runs                      -> NRC 0x37
 *     no seed, the seed used up, or a seed of another level
 *                                         -> NRC 0x24 requestSequenceError
 *                                            (the seed is used up)
 *     key == key_fn(seed, level)          -> unlocked at this level; attempts 0
 *     else attempts + 1 (saturating at 255):
 *       attempts <  cfg.attempt_limit     -> NRC 0x35 invalidKey
 *       attempts >= cfg.attempt_limit     -> NRC 0x36 exceededNumberOfAttempts,
 *                                            the delay (cfg.delay_ms) starts
 *   Any key, right or wrong, uses the seed up. The counter is not reset
 *   when the delay ends: after the limit, every wrong key costs a new
 *   delay at once (one guess per delay), and only a valid key resets it.
 *   The counter is kept in NVM (the application's image): at a power-up
 *   with attempts >= cfg.attempt_limit the delay starts again, so a restart
 *   does not buy a guess. canfdi_uds_sec_lock (every session change, S3
 *   timeout, power-up) locks and voids the seed.
 *
 * Key algorithm (canfdi_uds_sec_key_default; replace it with cfg.key_fn,
 * the tester's copy is tools/canfdi/uds_key.py): with s the level's
 * secret (CANFDI_CFG_UDS_SECRET_L1, _L2) and all arithmetic mod 2^32,
 *   k = seed XOR s;  k = rotate_left(k, 11);  k = k * 0x9E3779B1;
 *   key = k XOR (k >> 15).
 * It is an obfuscation, not cryptography: anyone with the firmware has the
 * secret. A production ECU uses a per-device secret and an HMAC or an
 * asymmetric scheme through key_fn.
 * Seeds: xorshift32 over a state stirred with the port's entropy at
 * power-up and with the step count at every request (in SIL reproducible).
 *
 * Cost: O(1) per call; the key function a few instructions. Memory:
 * sizeof(canfdi_uds_sec_t) = 32 bytes on a 32-bit target.
 */
#ifndef CANFDI_UDS_SEC_H
#define CANFDI_UDS_SEC_H

#include "core/canfdi_common.h"

#ifndef CANFDI_CFG_UDS_SECRET_L1
#define CANFDI_CFG_UDS_SECRET_L1 0x5A17C0DEU
#endif
#ifndef CANFDI_CFG_UDS_SECRET_L2
#define CANFDI_CFG_UDS_SECRET_L2 0x1EE7F00DU
#endif
#define CANFDI_UDS_SEC_MAX_LEVELS 2U
#define CANFDI_UDS_SEC_SEED_BYTES 4U

typedef uint32_t (*canfdi_uds_key_fn_t)(uint32_t seed, uint8_t level);

typedef struct {
  canfdi_uds_key_fn_t key_fn; /* NULL: canfdi_uds_sec_key_default */
  uint32_t delay_ms;          /* delay after the limit, 1..3 600 000 */
  uint8_t attempt_limit;      /* failed keys that start the delay, 1..255 */
  uint8_t levels;             /* 1..CANFDI_UDS_SEC_MAX_LEVELS */
} canfdi_uds_sec_cfg_t;

typedef struct {
  canfdi_uds_sec_cfg_t cfg;
  uint32_t prng;        /* xorshift32 state, never 0 */
  uint32_t seed;        /* the seed handed out */
  uint32_t delay_left_ms;
  uint32_t changes;     /* persistent state changed (wraps): store to NVM */
  uint8_t seed_level;   /* the level of the seed, 0: no seed */
  uint8_t unlocked;     /* the level unlocked, 0: locked */
  uint8_t attempts;     /* failed keys since the last valid one (NVM) */
} canfdi_uds_sec_t;

/* The default: 3 attempts, 10 s delay, 1 level, the default key. */
void canfdi_uds_sec_default_cfg(canfdi_uds_sec_cfg_t *cfg);

/* Locked, with the attempt counter read from NVM (0 for none) and the
 * port's entropy; the delay starts when attempts >= the limit. Returns
 * CANFDI_OK or -CANFDI_EINVAL (NULL, cfg outside its domain). */
int32_t canfdi_uds_sec_init(canfdi_uds_sec_t *s, const canfdi_uds_sec_cfg_t *cfg, uint8_t attempts,
                            uint32_t entropy);

/* Lock and void the seed (session change). */
void canfdi_uds_sec_lock(canfdi_uds_sec_t *s);

/* One 1 ms step: the delay runs down. */
void canfdi_uds_sec_tick(canfdi_uds_sec_t *s);

/* The level unlocked now (0 locked). */
uint8_t canfdi_uds_sec_level(const canfdi_uds_sec_t *s);

/*
 * One 0x27 request req[0..len) (req[0] = 0x27, req[1] = the sub-function
 * without the suppress bit, already checked to be 1..2*levels). Writes the
 * seed into seed_out (4 bytes) for a requestSeed. Returns the NRC (0:
 * positive). stir mixes into the seed generator (the step count).
 */
uint8_t canfdi_uds_sec_request(canfdi_uds_sec_t *s, const uint8_t *req, uint32_t len, uint32_t stir,
                               uint8_t seed_out[CANFDI_UDS_SEC_SEED_BYTES]);

/* The default key of seed for level (see the header). */
uint32_t canfdi_uds_sec_key_default(uint32_t seed, uint8_t level);

#endif /* CANFDI_UDS_SEC_H */
