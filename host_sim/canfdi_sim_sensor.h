/*
 * canfdi_sim_sensor.h — one measurement channel: calibration, fault
 * distortion, Gaussian noise and a 12-bit ADC.
 *
 * Signal chain, in this order (x is the true physical value):
 *   analog = gain * (1 + fault_gain) * x + offset + fault_offset
 *   noisy  = analog + sigma * N(0, 1)             (seeded, per channel)
 *   code   = round((noisy - min) / lsb), clamped to 0 .. 4095
 *   value  = min + code * lsb,   lsb = (max - min) / 4096
 * A bipolar span symmetric about zero (e.g. -30 .. +30 A) therefore
 * represents 0 exactly (code 2048); the top code reads max - lsb. Values
 * outside the span clip to the end codes and count in diag.clips.
 * Open and short circuits are not gains or offsets: the caller replaces x
 * by the rail value first (see canfdi_sim.c), then noise and ADC apply.
 *
 * All arithmetic is double precision; no scaling concerns beyond the clamp.
 * Cost: one Gaussian sample (see canfdi_sim_rng.h) and a few flops per
 * sample. Memory: sizeof(canfdi_sim_sensor_t) ~ 110 bytes. No heap.
 */
#ifndef CANFDI_SIM_SENSOR_H
#define CANFDI_SIM_SENSOR_H

#include <stdint.h>

#include "canfdi_sim_rng.h"

#define CANFDI_SIM_ADC_BITS 12U
#define CANFDI_SIM_ADC_CODES 4096U

typedef struct {
  double min;     /* lower end of the ADC span, physical unit */
  double max;     /* upper end of the ADC span, physical unit (> min) */
  double gain;    /* calibration gain, 1 when healthy */
  double offset;  /* calibration offset, physical unit, 0 when healthy */
  double sigma;   /* noise standard deviation, physical unit, >= 0 */
} canfdi_sim_sensor_cfg_t;

typedef struct {
  uint32_t clips; /* samples clamped to code 0 or 4095 (monotone) */
} canfdi_sim_sensor_diag_t;

typedef struct {
  canfdi_sim_sensor_cfg_t cfg;
  canfdi_sim_rng_t rng;
  double lsb;             /* (max - min) / 4096 */
  double last_analog;     /* analog value before noise of the last sample */
  uint16_t last_code;     /* ADC code of the last sample */
  canfdi_sim_sensor_diag_t diag;
} canfdi_sim_sensor_t;

/* Returns -CANFDI_EINVAL if max <= min, sigma < 0 or a value is not finite;
 * CANFDI_OK otherwise. The noise stream is (seed, stream). */
int canfdi_sim_sensor_init(canfdi_sim_sensor_t *s, const canfdi_sim_sensor_cfg_t *cfg,
                           uint64_t seed, uint32_t stream);

/* One sample of true value x with an additional fault gain (relative, 0 =
 * none) and fault offset (physical unit). Returns the quantised physical
 * value; the code is kept in s->last_code. Cannot fail by contract. */
double canfdi_sim_sensor_sample(canfdi_sim_sensor_t *s, double x, double fault_gain,
                                double fault_offset);

/* Physical value of an ADC code (code clamped to 0..4095). */
double canfdi_sim_sensor_value_of_code(const canfdi_sim_sensor_t *s, uint16_t code);

#endif /* CANFDI_SIM_SENSOR_H */
