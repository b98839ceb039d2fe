/*
 * canfdi_sim_refctl.h — the simulator's STAND-IN reference controller.
 *
 * This is not the product. It closes the loops of canfdi-sim offline
 * (without --can), of the plant tests and of the model benches; in SIL and
 * HIL the firmware ECU closes them over CAN. It does not react to faults:
 *   - DC motor speed: PI on the measured speed with back-EMF feed-forward
 *     (u = Psi_nom * w_ref + Kp e + Ki int e), clamped to +-supply, integrator
 *     frozen while the output saturates (conditional integration), always on
 *     bridge A (the fault-tolerant bridge manager is the firmware's job).
 *   - Throttle position: PID on the angle measured by TPS1 and TPS2 (their
 *     mean; one alone if the other is out of 0.25..4.75 V; limp-home command
 *     0 V with the bridge disabled if both are), with spring feed-forward from
 *     the nominal spring and a derivative of the measured angle through a
 *     first-order filter, clamped to +-supply.
 * Gains are fixed for the default plants (see canfdi_sim_refctl_default).
 *
 * Cost: ~40 flops per call. Memory: ~220 bytes. No heap.
 */
#ifndef CANFDI_SIM_REFCTL_H
#define CANFDI_SIM_REFCTL_H

#include <stdbool.h>

#include "canfdi_sim.h"

typedef struct {
  double speed_kp;        /* V per rad/s */
  double speed_ki;        /* V per rad */
  double psi_nom_Vs;      /* feed-forward back-EMF constant */
  double dcm_supply_V;
  double angle_kp;        /* V per deg */
  double angle_ki;        /* V per deg s */
  double angle_kd;        /* V per deg/s */
  double angle_d_tau_s;   /* derivative filter time constant */
  double thr_supply_V;
  canfdi_sim_thr_params_t thr_nom; /* for the spring feed-forward */
} canfdi_sim_refctl_cfg_t;

typedef struct {
  canfdi_sim_refctl_cfg_t cfg;
  double speed_int_V;
  double angle_int_V;
  double angle_prev_deg;
  double angle_rate_deg_s;  /* filtered derivative */
  bool have_prev;
} canfdi_sim_refctl_t;

/* Gains for the default plants and the given supplies. */
void canfdi_sim_refctl_default(canfdi_sim_refctl_cfg_t *cfg, const canfdi_sim_cfg_t *sim_cfg);

void canfdi_sim_refctl_init(canfdi_sim_refctl_t *c, const canfdi_sim_refctl_cfg_t *cfg);

/* One 1 ms control step: setpoints and the last measurement in, actuator
 * commands out (load_Nm in *out is left untouched). */
void canfdi_sim_refctl_step(canfdi_sim_refctl_t *c, double speed_ref_rad_s, double angle_ref_deg,
                            const canfdi_sim_meas_t *meas, canfdi_sim_in_t *out);

/* Angle in degrees estimated from the two TPS voltages as the controller
 * does; -1 if neither is plausible. */
double canfdi_sim_refctl_angle_deg(double tps1_V, double tps2_V);

#endif /* CANFDI_SIM_REFCTL_H */
