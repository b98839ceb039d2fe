/*
 * canfdi_excite.h — deterministic test signal for the parameter estimators:
 * a pseudo-random binary sequence (PRBS) and/or a small sinusoid, added by
 * the application to a setpoint (or a command) while the estimators need
 * excitation, and switched off in steady state when they do not.
 *
 * Why. Recursive least squares only learns parameters along directions the
 * signals move in (persistent excitation). At a constant operating point
 * the regressors are constant and the estimates drift or freeze; a small
 * broadband signal keeps them identifiable without disturbing the process
 * much. Isermann (Fault-Diagnosis Systems, ch. 9) uses PRBS on the input.
 *
 * PRBS. A 15-bit maximum-length LFSR, x^15 + x^14 + 1 (the simulator's
 * profile PRBS uses the same polynomial), Fibonacci form: per bit the state
 * shifts left by one and the new bit 0 is bit 14 XOR bit 13; the output is
 * +amp when bit 0 is 1, -amp otherwise. Period 2^15 - 1 = 32767 bits (all
 * non-zero states); a seed of 0 (the lock-up state) is replaced by 1. A new
 * bit every prbs_bit_us (a whole number of steps; rounded to the nearest
 * step, at least one).
 * Spectrum: the PRBS of amplitude a and bit period Tb is a line spectrum
 * (spacing 1 / (32767 Tb), i.e. practically continuous) with the envelope of
 * a random telegraph signal, power density a^2 Tb sinc^2(pi f Tb): flat
 * within 1 dB up to f = 0.26 / Tb, -3 dB at f = 0.443 / Tb, zeros at
 * multiples of 1 / Tb. Its mean is a / 32767 (one more +1 than -1 bits),
 * i.e. zero for control purposes. Rule: put the -3 dB point above the plant
 * dynamics to identify, i.e. Tb at or below the dominant time constant:
 *   DC motor (tau_m = J R / Psi^2 = 27 ms, tau_e = L / R = 4.5 ms, closed
 *   speed loop ~100 rad/s): Tb = 20 ms on the speed setpoint gives a flat
 *   band to 13 Hz and -3 dB at 22 Hz, covering the mechanical corner
 *   (5.9 Hz) and the closed-loop bandwidth (16 Hz); the current dynamics
 *   are excited through the loop's response to each bit edge.
 *   Throttle (tau_m = J / (B + K^2/R) = 20 ms, closed position loop
 *   ~120 rad/s = 19 Hz): Tb = 20..50 ms on the angle setpoint.
 * The bit period should also be short against the estimator's memory
 * (forgetting 0.99 at 1 ms = 100 ms): Tb = 20 ms gives ~2.5 edges per
 * memory length on average.
 * Sinusoid: amplitude sine_amp, period sine_period_us (>= 2 steps), a
 * single line for estimators that need one frequency (or a frequency
 * response check). Generated from a 32-bit phase accumulator (increment
 * round(2^32 T / period), so the frequency is exact to 2^-32 / T) and a
 * 65-entry quarter-wave Q15 table with linear interpolation: error below
 * 1.3e-4 of the amplitude (tested against libm).
 *
 * Enable. A change of canfdi_excite_enable takes effect for the PRBS at its
 * next bit edge (the LFSR and its bit clock run from init on regardless of
 * the enable) and for the sinusoid at an upward zero crossing: when the
 * sine is off, an enable starts its period in that step, so a test burst
 * does not wait up to a period for a free-running phase; a disable lets
 * the running period complete. Switching thus never produces a partial
 * bit or a jump of the sine.
 *
 * Scaling and overflow. Amplitudes and the output are Q16.16 in the unit of
 * the signal the caller adds it to. The sine sample is Q15 (int32); the
 * product amp x sin is rounded half up to Q16.16 (canfdi_mul_s32_qn, exact
 * 64-bit product); the sum of both components saturates. The interpolation
 * works on the non-negative table differences (< 2^10 per entry) times a
 * 10-bit fraction, well inside 32 bits.
 *
 * Cost per canfdi_excite_step_q16: a counter compare, a shift/XOR LFSR
 * update once per bit, one table interpolation (one 32-bit multiply) and
 * one 32x32->64 multiply for the sine; no division. Measured executed
 * instructions (arm-none-eabi-gcc 12 -Os, QEMU mps2-an386 -icount, 4000
 * calls with PRBS and sine on, min / mean / max): Cortex-M4 78 / 86 / 109,
 * Cortex-M0+ code 155 / 167 / 194. Stack 32 bytes. Code 776 bytes (M0+)
 * including the 130-byte constant table. Memory: sizeof(canfdi_excite_t) =
 * 60 bytes on a 32-bit target, caller-owned. No heap, no globals besides
 * the constant table.
 */
#ifndef CANFDI_EXCITE_H
#define CANFDI_EXCITE_H

#include "core/canfdi_common.h"

typedef struct {
  int32_t prbs_amp_q16;     /* PRBS amplitude (+-), >= 0; 0 = no PRBS */
  uint32_t prbs_bit_us;     /* bit period, >= 1 step (rounded to steps) */
  uint16_t prbs_seed;       /* LFSR start state (15 bits used; 0 -> 1) */
  int32_t sine_amp_q16;     /* sine amplitude, >= 0; 0 = no sine */
  uint32_t sine_period_us;  /* >= 2 steps when sine_amp > 0 */
} canfdi_excite_cfg_t;

/* Diagnostics counters: monotone, saturating at UINT32_MAX
 * (core/canfdi_count.h); init clears them, nothing else does. No decision
 * of the firmware depends on them. */
typedef struct {
  uint32_t steps;        /* canfdi_excite_step_q16 calls */
  uint32_t prbs_bits;    /* PRBS bits clocked */
  uint32_t active_steps; /* steps with a component switched on */
} canfdi_excite_diag_t;

typedef struct {
  canfdi_excite_cfg_t cfg;
  uint32_t bit_steps;    /* steps per PRBS bit */
  uint32_t bit_count;    /* steps into the current bit, 0 .. bit_steps - 1 */
  uint32_t phase_inc;    /* sine phase per step, 2^32 = one period */
  uint32_t phase;        /* sine phase of the next sample (wraps modulo 2^32
                            by design: one period) */
  uint16_t lfsr;         /* LFSR state, 1..0x7FFF */
  bool want;             /* requested enable */
  bool prbs_on;          /* PRBS gate (switches at bit edges) */
  bool sine_on;          /* sine gate (switches at upward zero crossings) */
  int32_t out_q16;       /* last output */
  canfdi_excite_diag_t diag;
} canfdi_excite_t;

/*
 * Validates cfg and starts: disabled, LFSR at the seed, sine phase 0.
 * Returns CANFDI_OK or -CANFDI_EINVAL (e untouched) for NULL, a negative
 * amplitude, prbs_bit_us shorter than half a step with prbs_amp > 0, or a
 * sine period below 2 steps with sine_amp > 0. Cost: one 64-bit division.
 */
int32_t canfdi_excite_init(canfdi_excite_t *e, const canfdi_excite_cfg_t *cfg);

/* Requests on/off: the PRBS at its next bit edge, the sine at once when
 * it is off and at the end of its period when it runs (see Enable above).
 * Cannot fail by contract. Cost: a store. */
void canfdi_excite_enable(canfdi_excite_t *e, bool on);

/* The output of this step (Q16.16), advancing the generators by one step.
 * Cannot fail by contract. Cost: see above. */
int32_t canfdi_excite_step_q16(canfdi_excite_t *e);

/* Whether any component is currently switched on (a gated generator). */
bool canfdi_excite_active(const canfdi_excite_t *e);

/* sin(2 pi phase / 2^32) in Q15 (int32 in [-32767, 32767]) from the table
 * (exposed for tests). Cannot fail by contract. Cost: one table
 * interpolation. */
int32_t canfdi_excite_sin_q15(uint32_t phase);

/* The diagnostics counters (pointer into *e). */
const canfdi_excite_diag_t *canfdi_excite_diag(const canfdi_excite_t *e);

#endif /* CANFDI_EXCITE_H */
