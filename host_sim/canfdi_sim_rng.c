/* canfdi_sim_rng.c — see canfdi_sim_rng.h. */
#include "canfdi_sim_rng.h"

#include <math.h>

static uint64_t rotl64(uint64_t x, unsigned k)
{
  return (x << k) | (x >> (64U - k));
}

/* SplitMix64 step: spreads a counter over all 64 bits so that close seeds
 * (1, 2, 3...) still give unrelated xoshiro states. */
static uint64_t splitmix64(uint64_t *x)
{
  uint64_t z;
  *x += 0x9E3779B97F4A7C15ULL;
  z = *x;
  z = (z ^ (z >> 30U)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27U)) * 0x94D049BB133111EBULL;
  return z ^ (z >> 31U);
}

void canfdi_sim_rng_init(canfdi_sim_rng_t *rng, uint64_t seed, uint32_t stream)
{
  /* Unsigned multiplication wraps by definition: the stream number moves the
   * SplitMix64 starting point by an odd constant times the stream. */
  uint64_t x = seed ^ ((uint64_t)stream * 0xD1B54A32D192ED03ULL);
  unsigned i;
  for (i = 0U; i < 4U; i++) {
    rng->s[i] = splitmix64(&x);
  }
  if ((rng->s[0] | rng->s[1] | rng->s[2] | rng->s[3]) == 0U) {
    rng->s[0] = 1U; /* the one forbidden state; practically unreachable */
  }
  rng->spare = 0.0;
  rng->has_spare = false;
}

uint64_t canfdi_sim_rng_next(canfdi_sim_rng_t *rng)
{
  uint64_t *s = rng->s;
  const uint64_t result = rotl64(s[1] * 5U, 7U) * 9U;
  const uint64_t t = s[1] << 17U;
  s[2] ^= s[0];
  s[3] ^= s[1];
  s[1] ^= s[2];
  s[0] ^= s[3];
  s[2] ^= t;
  s[3] = rotl64(s[3], 45U);
  return result;
}

double canfdi_sim_rng_uniform(canfdi_sim_rng_t *rng)
{
  /* Top 53 bits plus one half LSB: never exactly 0 (log(0) in Box-Muller)
   * and never exactly 1. */
  const uint64_t top = canfdi_sim_rng_next(rng) >> 11U;
  return ((double)top + 0.5) * (1.0 / 9007199254740992.0);
}

double canfdi_sim_rng_gauss(canfdi_sim_rng_t *rng)
{
  double out;
  if (rng->has_spare) {
    rng->has_spare = false;
    out = rng->spare;
  } else {
    const double two_pi = 6.283185307179586;
    const double u1 = canfdi_sim_rng_uniform(rng);
    const double u2 = canfdi_sim_rng_uniform(rng);
    const double r = sqrt(-2.0 * log(u1));
    rng->spare = r * sin(two_pi * u2);
    rng->has_spare = true;
    out = r * cos(two_pi * u2);
  }
  return out;
}
