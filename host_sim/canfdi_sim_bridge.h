/*
 * canfdi_sim_bridge.h — averaged-PWM H-bridge driving an R-L-EMF load.
 *
 * Three ways a bridge can drive the motor terminals:
 *   driven:  enabled and healthy: U = clamp(u_cmd, -supply, +supply)
 *            (the PWM duty cycle averaged over a period);
 *   dead:    enabled but failed (catalogue: "delivers 0 V"): both low sides
 *            conduct, U = 0, the motor is shorted and brakes on its EMF;
 *   off:     disabled (all switches open, high impedance). Current can only
 *            flow through the free-wheeling diodes into the supply: while
 *            i > 0 the terminals sit at -supply (i < 0: +supply) until the
 *            current reaches zero; with i = 0 the circuit is open (U equals
 *            the back-EMF) unless |EMF| exceeds the supply, when the diodes
 *            conduct and the motor feeds the supply (generator).
 * A de-energised throttle therefore springs back to limp-home without the
 * braking a shorted motor would add.
 *
 * The plants call canfdi_sim_bridge_mode once per 100 us sub-step and
 * freeze the result, then stop the current at 0 if it would change sign in
 * free-wheeling (diodes block reverse current).
 * Cost: a few comparisons. Memory: none. No heap.
 */
#ifndef CANFDI_SIM_BRIDGE_H
#define CANFDI_SIM_BRIDGE_H

#include <stdbool.h>

typedef struct {
  double u_V;        /* terminal voltage imposed (not used when open) */
  bool open;         /* no current path: di/dt = 0, i stays 0 */
  double i_sign;     /* free-wheeling: sign the current may not leave (0 = none) */
} canfdi_sim_bridge_mode_t;

/* Mode for one sub-step. i_A: present current; emf_V: present back-EMF. */
canfdi_sim_bridge_mode_t canfdi_sim_bridge_mode(double u_cmd_V, double supply_V, bool enable,
                                                bool dead, double i_A, double emf_V);

/* Terminal voltage seen by a voltage sensor at the end of a sub-step. */
double canfdi_sim_bridge_terminal_V(const canfdi_sim_bridge_mode_t *m, double emf_V);

#endif /* CANFDI_SIM_BRIDGE_H */
