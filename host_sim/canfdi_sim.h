/*
 * canfdi_sim.h — the combined plant: DC motor drive + throttle valve +
 * their eight sensors + the injected faults, stepped at 1 ms.
 *
 * One step (canfdi_sim_step) takes the plant from t_k = k * 1 ms to t_k+1:
 *   1. fault effects are evaluated at t_k and held over the step (physics),
 *   2. both plants integrate over 1 ms with the actuator inputs held
 *      (RK4, 10 sub-steps, canfdi_sim_ode.h),
 *   3. fault effects are evaluated at t_k+1 and the sensors sample the new
 *      state (canfdi_sim_sensor.h); sim->fx then holds the effects at t_k+1,
 *      including the frame flags for the sensor frames sent at t_k+1.
 * canfdi_sim_init samples once at t = 0 so a controller has a first
 * measurement before the first step.
 *
 * Sensors (index, true quantity, ADC span):
 *   DCM_UA     U_A applied by the bridges      -60 .. +60 V
 *   DCM_IA     armature current I_A             -30 .. +30 A
 *   DCM_SPEED  omega                           -400 .. +400 rad/s
 *   DCM_SUPPLY bridge supply                      0 .. 80 V
 *   THR_TPS1   0.5 + 4 theta/90deg                0 .. 5 V
 *   THR_TPS2   4.5 - 4 theta/90deg                0 .. 5 V
 *   THR_I      throttle motor current           -10 .. +10 A
 *   THR_SUPPLY throttle bridge supply             0 .. 16 V
 * A TPS open circuit reads 0 V and a short 5 V (the sensor supply) before
 * noise and ADC; offset and gain faults act as in canfdi_sim_sensor.h.
 *
 * Determinism: all noise comes from per-sensor streams of one 64-bit seed;
 * the same configuration, faults and inputs give bit-identical outputs.
 * Cost: ~1500 flops + 8 Gaussian samples per step (see bench/bench_sim.c
 * for the measured rate). Memory: sizeof(canfdi_sim_t) ~ 2.7 kB with
 * CANFDI_SIM_MAX_FAULTS = 16, caller-owned. No heap, no globals.
 */
#ifndef CANFDI_SIM_H
#define CANFDI_SIM_H

#include <stddef.h>
#include <stdint.h>

#include "canfdi_sim_dcm.h"
#include "canfdi_sim_fault.h"
#include "canfdi_sim_sensor.h"
#include "canfdi_sim_thr.h"

#define CANFDI_SIM_MAX_FAULTS 16U

#define CANFDI_SIM_S_DCM_UA 0U
#define CANFDI_SIM_S_DCM_IA 1U
#define CANFDI_SIM_S_DCM_SPEED 2U
#define CANFDI_SIM_S_DCM_SUPPLY 3U
#define CANFDI_SIM_S_THR_TPS1 4U
#define CANFDI_SIM_S_THR_TPS2 5U
#define CANFDI_SIM_S_THR_I 6U
#define CANFDI_SIM_S_THR_SUPPLY 7U
#define CANFDI_SIM_N_SENSORS 8U

/* TPS rails: open reads this low rail, short the sensor supply. */
#define CANFDI_SIM_TPS_OPEN_V 0.0
#define CANFDI_SIM_TPS_SHORT_V 5.0

typedef struct {
  canfdi_sim_dcm_params_t dcm;
  canfdi_sim_thr_params_t thr;
  double sigma[CANFDI_SIM_N_SENSORS];   /* noise sigma per sensor, unit of the sensor */
  uint64_t seed;
} canfdi_sim_cfg_t;

typedef struct {
  canfdi_sim_dcm_in_t dcm;
  canfdi_sim_thr_in_t thr;
} canfdi_sim_in_t;

typedef struct {
  double value[CANFDI_SIM_N_SENSORS];   /* quantised physical values */
  uint16_t code[CANFDI_SIM_N_SENSORS];  /* ADC codes */
  double analog[CANFDI_SIM_N_SENSORS];  /* before noise and ADC (for tests) */
  double truth[CANFDI_SIM_N_SENSORS];   /* true quantity the sensor looks at */
} canfdi_sim_meas_t;

typedef struct {
  canfdi_sim_cfg_t cfg;
  canfdi_sim_dcm_t dcm;
  canfdi_sim_thr_t thr;
  canfdi_sim_sensor_t sensor[CANFDI_SIM_N_SENSORS];
  canfdi_sim_fault_spec_t faults[CANFDI_SIM_MAX_FAULTS];
  size_t n_faults;
  canfdi_sim_fx_t fx;      /* effects at the current time (last sample) */
  uint64_t step;           /* completed steps; time = step * 1 ms */
  canfdi_sim_meas_t meas;  /* last sample */
} canfdi_sim_t;

/* Name of a sensor index ("dcm_ua", ...), NULL if out of range; and back
 * (-CANFDI_EINVAL if unknown). */
const char *canfdi_sim_sensor_name(unsigned idx);
int canfdi_sim_sensor_find(const char *name);

/* Defaults of both plants, no noise, seed 1. */
void canfdi_sim_default_cfg(canfdi_sim_cfg_t *cfg);

/* Validates and initialises; no faults; plants at rest (the throttle at
 * limp-home, the motor at ambient temperature); samples at t = 0.
 * -CANFDI_EINVAL for invalid parameters or a negative/non-finite sigma. */
int canfdi_sim_init(canfdi_sim_t *sim, const canfdi_sim_cfg_t *cfg);

/* Re-samples the sensors at the current time without advancing (after the
 * state was changed, e.g. initial conditions). Draws noise. */
void canfdi_sim_resample(canfdi_sim_t *sim);

/* Adds a fault (a validated spec). -CANFDI_ERANGE when full. */
int canfdi_sim_add_fault(canfdi_sim_t *sim, const canfdi_sim_fault_spec_t *spec);

/* Removes every fault with catalogue id `id` (0: every fault), keeping the
 * order of the others; returns how many were removed. The effects in
 * sim->fx change at the next step or resample. Cannot fail by contract. */
size_t canfdi_sim_clear_faults(canfdi_sim_t *sim, uint8_t id);

/* Sets the two bridge supplies (V; DC motor 0..80, throttle 0..16) from
 * now on: the bridges clamp their output to them from the next step, and
 * the supply sensors read them from the next sample. For a supply that
 * varies over time (a scenario's profile) call it before every step with
 * the value at the step's start: it holds over the step like the actuator
 * commands. Out-of-range values are a contract violation (asserted). */
void canfdi_sim_set_supply(canfdi_sim_t *sim, double dcm_supply_V, double thr_supply_V);

/* One 1 ms step (see above). Cannot fail by contract. */
void canfdi_sim_step(canfdi_sim_t *sim, const canfdi_sim_in_t *in);

/* Current time in microseconds and seconds. */
int64_t canfdi_sim_time_us(const canfdi_sim_t *sim);
double canfdi_sim_time_s(const canfdi_sim_t *sim);

#endif /* CANFDI_SIM_H */
