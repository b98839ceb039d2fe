/*
 * canfdi_sim_fault.h — fault injection: the shape of each fault over time
 * and what it does to the plants, sensors and frames.
 *
 * The catalogue itself (ids, names, allowed modes, units) is the generated
 * table host_sim/gen/canfdi_faults.h from dbc/faults.csv; this module only
 * adds the physics of each entry. Magnitude semantics (dbc/faults.csv):
 * "rel" faults change the named quantity by magnitude in the named
 * direction (dcm_ra_up 0.2: R_A x 1.2; dcm_flux_down 0.1: Psi x 0.9);
 * offsets add magnitude in the sensor's unit; dcm_speed_sensor_gain reads
 * (1 + magnitude) x omega; binary faults ignore the magnitude.
 *
 * Shape s(t) in [0, 1] of one fault started at t0 (all times are whole
 * microseconds, so boundaries are exact and reproducible):
 *   abrupt:       s = 1 for t >= t0
 *   incipient:    s = min(1, (t - t0) / ramp_s) for t >= t0 (linear drift
 *                 that reaches the magnitude after ramp_s)
 *   intermittent: s = 1 for t0 + n*period_s <= t < t0 + (n + duty)*period_s,
 *                 n = 0, 1, ..., else 0
 *   s = 0 before t0.
 * The effective magnitude is s * magnitude. Binary faults (abrupt or
 * intermittent only, per the table) are on while s = 1.
 * Several faults may be active at once: relative factors multiply
 * (two dcm_ra_up of 0.1 give x 1.21), offsets add, binary effects OR.
 *
 * Communication faults do not touch the plant: they set per-frame flags
 * that the frame front end (canfdi_sim_frames.h) applies to DcmSensor
 * (CANFDI_SIM_FRAME_DCM) or ThrSensor (CANFDI_SIM_FRAME_THR).
 *
 * Cost: _effects is O(number of faults), a few flops each. Memory: a spec is
 * 48 bytes, canfdi_sim_fx_t 136 bytes (x86-64). No heap.
 */
#ifndef CANFDI_SIM_FAULT_H
#define CANFDI_SIM_FAULT_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "canfdi_sim_dcm.h"
#include "canfdi_sim_thr.h"

#define CANFDI_SIM_MODE_ABRUPT 0U
#define CANFDI_SIM_MODE_INCIPIENT 1U
#define CANFDI_SIM_MODE_INTERMITTENT 2U

#define CANFDI_SIM_FRAME_DCM 0U
#define CANFDI_SIM_FRAME_THR 1U
#define CANFDI_SIM_N_FRAMES 2U

/* Longest accepted time of a fault parameter (start, ramp, period): 1e6 s. */
#define CANFDI_SIM_FAULT_MAX_S 1e6

typedef struct {
  uint8_t id;          /* canfdi_fault_table index */
  uint8_t mode;        /* CANFDI_SIM_MODE_* */
  double magnitude;    /* see magnitude semantics above */
  int64_t t_start_us;
  int64_t ramp_us;     /* incipient only, > 0 */
  int64_t period_us;   /* intermittent only, > 0 */
  int64_t on_us;       /* intermittent only, 0 < on_us <= period_us */
} canfdi_sim_fault_spec_t;

/* What the sensor frames must suffer this step. */
typedef struct {
  bool drop;         /* not sent at all (timeout) */
  bool bad_crc;      /* CRC byte wrong */
  bool bad_counter;  /* rolling counter repeats the previous value */
  bool bad_dlc;      /* sent one byte short */
  bool implausible;  /* measurement signals carry all-ones raw values */
} canfdi_sim_frame_fx_t;

/* Combined effect of all faults at one instant. */
typedef struct {
  canfdi_sim_dcm_fx_t dcm;
  canfdi_sim_thr_fx_t thr;
  double ia_offset_A;       /* I_A measurement offset */
  double speed_gain;        /* omega measurement relative gain error (0 healthy) */
  double speed_offset_rad_s;
  double ua_offset_V;
  double tps_offset_V[2];   /* TPS1, TPS2 in-range drift */
  bool tps_open[2];         /* reads ~0 V */
  bool tps_short[2];        /* reads ~5 V */
  canfdi_sim_frame_fx_t frame[CANFDI_SIM_N_FRAMES];
  uint64_t active_mask;     /* bit id set while s(t) > 0 */
} canfdi_sim_fx_t;

/* Index of a fault by catalogue name, or -CANFDI_EINVAL if unknown. */
int canfdi_sim_fault_find(const char *name);

/* Mode by name ("abrupt", "incipient", "intermittent"), or -CANFDI_EINVAL. */
int canfdi_sim_fault_mode_find(const char *name);
const char *canfdi_sim_fault_mode_name(uint8_t mode);

/* Builds and validates a spec. ramp_s is used by incipient, period_s and
 * duty by intermittent (pass 0 otherwise). Returns -CANFDI_EINVAL for an
 * unknown id, a mode the catalogue does not allow for that fault, or a
 * value out of range; -CANFDI_ERANGE for a magnitude out of the fault's
 * range (canfdi_sim_fault_magnitude_range()). Rounds times to 1 us. */
int canfdi_sim_fault_spec_make(canfdi_sim_fault_spec_t *spec, uint8_t id, uint8_t mode,
                               double t_start_s, double magnitude, double ramp_s,
                               double period_s, double duty);

/* Accepted magnitudes of a fault: [*lo, *hi] (open at lo if *lo_open).
 * -CANFDI_EINVAL for an unknown id. */
int canfdi_sim_fault_magnitude_range(uint8_t id, double *lo, double *hi, bool *lo_open);

/* Shape s(t) of a spec at t_us (see above). */
double canfdi_sim_fault_shape(const canfdi_sim_fault_spec_t *spec, int64_t t_us);

/* Healthy effects. */
void canfdi_sim_fx_none(canfdi_sim_fx_t *fx);

/* Effects of n specs at t_us. Cannot fail by contract. */
void canfdi_sim_fault_effects(const canfdi_sim_fault_spec_t *specs, size_t n, int64_t t_us,
                              canfdi_sim_fx_t *fx);

#endif /* CANFDI_SIM_FAULT_H */
