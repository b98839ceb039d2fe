/*
 * canfdi_sim_rng.h — deterministic pseudo-random numbers for host_sim.
 *
 * Why its own generator: rand() differs between C libraries and its state is
 * global, so two runs of the same scenario on two machines (or two sensors in
 * one run) would not see the same noise. Each consumer (every sensor, the
 * communication-fault dice) owns one instance, seeded from the scenario seed
 * and a fixed stream number, so changing the noise of one sensor never shifts
 * the noise of another.
 *
 * Generator: xoshiro256** (Blackman & Vigna, 2018), 256-bit state, period
 * 2^256 - 1, state expanded from (seed, stream) with SplitMix64. Gaussian
 * samples: Box-Muller on two uniforms in (0, 1), both outputs used.
 * Results depend only on IEEE-754 double arithmetic and the C library's
 * log/sqrt/cos/sin; on one machine and build they are bit-reproducible.
 *
 * Cost: _next ~10 integer operations; _gauss one log, one sqrt, one sin/cos
 * per two samples. Memory: 48 bytes per instance. No heap, no globals.
 */
#ifndef CANFDI_SIM_RNG_H
#define CANFDI_SIM_RNG_H

#include <stdbool.h>
#include <stdint.h>

typedef struct {
  uint64_t s[4];      /* xoshiro256** state, never all zero */
  double spare;       /* second Box-Muller output, valid if has_spare */
  bool has_spare;
} canfdi_sim_rng_t;

/* Seeds the generator. Distinct (seed, stream) pairs give independent
 * sequences. Cannot fail by contract. */
void canfdi_sim_rng_init(canfdi_sim_rng_t *rng, uint64_t seed, uint32_t stream);

/* Next raw 64-bit output. */
uint64_t canfdi_sim_rng_next(canfdi_sim_rng_t *rng);

/* Uniform double in the open interval (0, 1), 53 random bits. */
double canfdi_sim_rng_uniform(canfdi_sim_rng_t *rng);

/* Standard normal sample (mean 0, variance 1). */
double canfdi_sim_rng_gauss(canfdi_sim_rng_t *rng);

#endif /* CANFDI_SIM_RNG_H */
