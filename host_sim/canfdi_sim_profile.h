/*
 * canfdi_sim_profile.h — time profiles for setpoints and load: a sum of
 * components, each active over its own time window.
 *
 * The value of a profile at time t is the sum of its components, clamped
 * to [lo, hi] (the physical range of the quantity):
 *   const v                       v for all t
 *   step  t0 d                    d for t >= t0, else 0
 *   ramp  t0 t1 d                 0 before t0, linear to d at t1, d after
 *   prbs  t0 t1 a bit_s seed      +a or -a for t0 <= t < t1, else 0; a new
 *                                 bit every bit_s from a 15-bit maximum-length
 *                                 LFSR (x^15 + x^14 + 1, period 32767 bits)
 *                                 started from state (seed mod 32767) + 1
 *   sine  t0 t1 a f               a sin(2 pi f (t - t0)) for t0 <= t < t1
 * Staircases are sums of steps, a pulse is two steps. PRBS gives the broad
 * excitation that parameter estimation needs; its bit period should be
 * about the plant's dominant time constant.
 * Times are whole microseconds (converted once when a component is added),
 * so every profile is exactly reproducible.
 *
 * Cost: _eval is O(components); a PRBS component advances its LFSR once per
 * elapsed bit (O(1) amortised when time moves forward, O(bits) after a jump
 * back). Memory: 64 bytes per component, CANFDI_SIM_PROFILE_MAX components
 * per profile. No heap.
 */
#ifndef CANFDI_SIM_PROFILE_H
#define CANFDI_SIM_PROFILE_H

#include <stddef.h>
#include <stdint.h>

#define CANFDI_SIM_PROFILE_MAX 32U

#define CANFDI_SIM_PROF_CONST 0U
#define CANFDI_SIM_PROF_STEP 1U
#define CANFDI_SIM_PROF_RAMP 2U
#define CANFDI_SIM_PROF_PRBS 3U
#define CANFDI_SIM_PROF_SINE 4U

typedef struct {
  uint8_t kind;      /* CANFDI_SIM_PROF_* */
  int64_t t0_us;
  int64_t t1_us;     /* ramp end / window end (INT64_MAX if open) */
  int64_t bit_us;    /* prbs bit period */
  double value;      /* const value, step/ramp delta, prbs/sine amplitude */
  double freq_hz;    /* sine */
  uint16_t seed_state;  /* prbs LFSR state at bit 0 */
  /* prbs cache: LFSR state after `bit` shifts */
  uint16_t state;
  int64_t bit;
} canfdi_sim_profile_comp_t;

typedef struct {
  canfdi_sim_profile_comp_t comp[CANFDI_SIM_PROFILE_MAX];
  size_t n;
  double lo;   /* clamp range of the sum */
  double hi;
} canfdi_sim_profile_t;

/* Empty profile (value 0) with a clamp range lo < hi. */
void canfdi_sim_profile_init(canfdi_sim_profile_t *p, double lo, double hi);

/* Adds a component. Arguments: for const (value); step (t0, value); ramp
 * (t0, t1, value); prbs (t0, t1, value, bit_s, seed); sine (t0, t1, value,
 * freq_hz). Unused arguments are ignored. Returns -CANFDI_ERANGE when the
 * profile is full, -CANFDI_EINVAL for non-finite values, negative times,
 * t1 <= t0 (ramp/prbs/sine), bit_s below 1 ms, freq_hz <= 0. */
int canfdi_sim_profile_add(canfdi_sim_profile_t *p, uint8_t kind, double t0_s, double t1_s,
                           double value, double bit_or_freq, uint32_t seed);

/* Value at t_us (not const: PRBS components cache their LFSR). */
double canfdi_sim_profile_eval(canfdi_sim_profile_t *p, int64_t t_us);

/* The sum of the components at t_us plus `extra` (e.g. a value read from
 * a profile file), clamped to [lo, hi]. */
double canfdi_sim_profile_eval_plus(canfdi_sim_profile_t *p, int64_t t_us, double extra);

#endif /* CANFDI_SIM_PROFILE_H */
