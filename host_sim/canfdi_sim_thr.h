/*
 * canfdi_sim_thr.h — electronic throttle valve: DC motor and two-stage gear
 * (all referred to the valve shaft), return spring with a limp-home
 * position, Coulomb and viscous friction, end stops, one H-bridge.
 *
 * Model (substitute parameters of a Bosch DV-E5 class valve; sources of
 * every default in docs/design.md):
 *   L di/dt = U - R i - K w
 *   J dw/dt = K i - B w - T_spring(theta) - T_c sign(w)
 *   T_spring = k_s (theta - theta_LH) + P tanh((theta - theta_LH) / delta)
 * The pretension term P sign(theta - theta_LH) of the ideal spring pair is
 * regularised with tanh over delta = 0.1 deg: the real return and limp-home
 * springs meet over a small angle, and a continuous torque keeps RK4
 * accurate (local stiffness P/delta ~ 230 N m/rad, ~330 rad/s, well inside
 * the 100 us sub-step). Because P > T_c the unpowered valve returns to
 * theta_LH and rests where |T_spring| <= T_c, i.e. within
 * delta * atanh(T_c / P) ~ 0.09 deg of it.
 * Stiction: as for the DC motor (canfdi_sim_dcm.h): mode frozen per 100 us
 * sub-step, stuck while |K i - B w - T_spring| <= T_c inside the band.
 * End stops at 0 and theta_max (90 deg) are inelastic: a sub-step that
 * would leave [0, theta_max] ends on the stop with w = 0, and while the net
 * torque presses into the stop the valve stays there. The angle therefore
 * never leaves [0, theta_max].
 * Faults: spring weak (k_s and P), friction up (T_c and B), motor R up,
 * motor circuit open (i forced to 0), jammed (mechanical state frozen at
 * the angle it had; the motor then sees a locked rotor).
 * Potentiometers (true voltages; noise and ADC in canfdi_sim_sensor.h):
 *   TPS1 = 0.5 + 4.0 theta / 90 deg,  TPS2 = 4.5 - 4.0 theta / 90 deg.
 *
 * Cost: 10 sub-steps x 4 derivative evaluations (one tanh each), ~700 flops
 * per 1 ms step. Memory: sizeof(canfdi_sim_thr_t) ~ 200 bytes. No heap.
 */
#ifndef CANFDI_SIM_THR_H
#define CANFDI_SIM_THR_H

#include <stdbool.h>
#include <stdint.h>

typedef struct {
  double j_kgm2;            /* shaft-referred inertia, 0.0021 */
  double b_Nms;             /* viscous friction, 0.0088 */
  double k_Nm_A;            /* motor constant (= back-EMF, V s/rad), 0.383 */
  double r_ohm;             /* motor circuit resistance, 1.5 */
  double l_H;               /* motor inductance, 1.5e-3 */
  double spring_Nm_rad;     /* return spring constant, 0.087 */
  double pretension_Nm;     /* spring pretension at limp-home, 0.396 */
  double friction_Nm;       /* Coulomb friction, 0.284 */
  double limp_home_deg;     /* limp-home angle, 6.5 */
  double lh_width_deg;      /* pretension regularisation delta, 0.1 */
  double max_deg;           /* upper end stop, 90 (lower is 0) */
  double supply_V;          /* bridge supply, 13.5 (0..16) */
  double stiction_band_rad_s; /* 1e-4 */
} canfdi_sim_thr_params_t;

typedef struct {
  double spring_factor;    /* k_s and P multiplier, 1 = healthy */
  double friction_factor;  /* T_c and B multiplier */
  double r_factor;         /* motor R multiplier */
  bool motor_open;         /* no current can flow */
  bool jammed;             /* valve frozen where it is */
} canfdi_sim_thr_fx_t;

typedef struct {
  double u_cmd_V;  /* motor voltage command */
  bool enable;     /* false: bridge off (high impedance, canfdi_sim_bridge.h) */
} canfdi_sim_thr_in_t;

typedef struct {
  uint32_t stop_hits;      /* sub-steps that ended on an end stop with motion (monotone) */
  uint32_t cmd_clamps;     /* steps with |u_cmd| > supply (monotone) */
} canfdi_sim_thr_diag_t;

typedef struct {
  canfdi_sim_thr_params_t p;
  /* state */
  double i_A;
  double w_rad_s;
  double theta_rad;
  bool stuck;
  /* outputs of the last step */
  double u_V;              /* winding terminal voltage at step end */
  double spring_eff_Nm_rad;
  double pretension_eff_Nm;
  double friction_eff_Nm;
  double b_eff_Nms;
  double r_eff_ohm;
  canfdi_sim_thr_diag_t diag;
} canfdi_sim_thr_t;

void canfdi_sim_thr_default_params(canfdi_sim_thr_params_t *p);
void canfdi_sim_thr_fx_none(canfdi_sim_thr_fx_t *fx);

/* -CANFDI_EINVAL for a parameter out of its domain (non-positive J, K, R,
 * L, widths; negative B, spring, friction; limp-home outside (0, max);
 * max not in (0, 180]; supply outside 0..16 V; non-finite). Starts at rest
 * at the limp-home angle. */
int canfdi_sim_thr_init(canfdi_sim_thr_t *v, const canfdi_sim_thr_params_t *p);

/* Sets angle [deg] (must lie in [0, max]) and speed; current 0. */
int canfdi_sim_thr_set_state(canfdi_sim_thr_t *v, double theta_deg, double w_rad_s);

/* Angle in degrees. */
double canfdi_sim_thr_angle_deg(const canfdi_sim_thr_t *v);

/* Ideal potentiometer voltages of an angle in degrees. */
double canfdi_sim_thr_tps1_V(double theta_deg);
double canfdi_sim_thr_tps2_V(double theta_deg);

/* Spring torque at an angle with a spring factor (exposed for tests). */
double canfdi_sim_thr_spring_Nm(const canfdi_sim_thr_t *v, double theta_rad, double spring_factor);

/* Advances the valve by 1 ms. Cannot fail by contract. */
void canfdi_sim_thr_step(canfdi_sim_thr_t *v, const canfdi_sim_thr_in_t *in,
                         const canfdi_sim_thr_fx_t *fx);

#endif /* CANFDI_SIM_THR_H */
