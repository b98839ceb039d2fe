/*
 * canfdi_sim_dcm.h — DC motor drive: armature, mechanics, winding warm-up
 * and the two redundant H-bridges (A and B), in double precision.
 *
 * Model (Isermann, Fault-Diagnosis Systems, 2006; default parameters of his
 * test motor):
 *   L_A dI/dt = U_A - R_A(T) I - Psi w
 *   J   dw/dt = Psi I - M_F1 w - M_F0 sign(w) - M_L,   M_L = load_Nm + k_fan w
 *   C_th dT/dt = I^2 R_w(T) - (T - T_amb) / R_th
 *   R_w(T) = R_20 (1 + alpha (T - 20 C)),  R_20 chosen so R_w(T_amb) = ra_cold_ohm
 *   R_A = R_w(T) * (fault factor)
 * The fault factor of dcm_ra_up models a resistance outside the winding
 * (brushes, contacts): it adds voltage drop but does not heat the winding,
 * so a fault never disturbs the thermal state directly.
 *
 * Warm-up: with the defaults (R_th 1.3 K/W, C_th 2000 J/K, tau_th ~ 43 min)
 * and a nominal load of ~4 A (load_Nm 1.2 at ~100 rad/s) the winding heats
 * by ~30 K and R_A rises from 1.35 Ohm (cold, 20 C) to ~1.5 Ohm within 1-2 h
 * — Isermann's 1.52 Ohm is the warm value. A scenario that wants a warm
 * motor from the start sets the initial winding temperature.
 *
 * Coulomb friction without chatter: each 100 us sub-step first decides the
 * mode. If |w| is inside the stiction band and the driving torque
 * |Psi I - M_L - M_F1 w| does not exceed M_F0, the rotor sticks: w is set to
 * 0 and held for the sub-step (the electrical and thermal states still
 * integrate). Otherwise the friction direction is frozen for the sub-step
 * (direction of motion, or of the driving torque when breaking away); if
 * friction would reverse the motion inside the sub-step, w stops at 0 and
 * the next sub-step decides again. Integration: RK4, see canfdi_sim_ode.h.
 *
 * Bridges (averaged PWM, canfdi_sim_bridge.h): the selected bridge drives
 * U_A = clamp(u_cmd, -supply, +supply) when enabled; a dead bridge delivers
 * 0 V (shorted armature, the motor brakes on its back-EMF); disabled means
 * high impedance (free-wheeling diodes, the motor coasts); so does
 * selecting no bridge (NONE or an out-of-range value). ua_V is the terminal
 * voltage a sensor sees.
 *
 * Cost: 10 sub-steps x 4 derivative evaluations, ~600 flops per 1 ms step.
 * Memory: sizeof(canfdi_sim_dcm_t) ~ 220 bytes, caller-owned. No heap.
 */
#ifndef CANFDI_SIM_DCM_H
#define CANFDI_SIM_DCM_H

#include <stdbool.h>
#include <stdint.h>

/* Bridge selection, numbered as DcmBridgeSel in dbc/canfdi.dbc. */
#define CANFDI_SIM_BRIDGE_NONE 0U
#define CANFDI_SIM_BRIDGE_A 1U
#define CANFDI_SIM_BRIDGE_B 2U

typedef struct {
  double ra_cold_ohm;          /* R_A at ambient_C (cold), default 1.35 */
  double la_H;                 /* armature inductance, 6.82e-3 */
  double psi_Vs;               /* flux linkage, 0.33 */
  double j_kgm2;               /* inertia, 1.92e-3 */
  double mf1_Nms;              /* viscous friction, 0.36e-3 */
  double mf0_Nm;               /* Coulomb friction, 0.11 */
  double alpha_per_K;          /* temperature coefficient of copper, 0.0039 */
  double ambient_C;            /* ambient temperature, 20 */
  double rth_K_W;              /* winding-to-ambient thermal resistance, 1.3 */
  double cth_J_K;              /* thermal capacitance, 2000 */
  bool thermal;                /* false freezes the winding temperature */
  double load_k_fan_Nms;       /* speed-proportional (fan-type) load, 0 */
  double supply_V;             /* bridge supply, 48 (0..80) */
  double stiction_band_rad_s;  /* |w| below this may stick, 1e-4 */
} canfdi_sim_dcm_params_t;

/* Effects of the active faults on this plant (canfdi_sim_fault.h builds it). */
typedef struct {
  double ra_factor;        /* R_A multiplier, 1 = healthy */
  double psi_factor;       /* Psi multiplier */
  double friction_factor;  /* M_F0 and M_F1 multiplier */
  bool bridge_dead[2];     /* [0] A, [1] B deliver 0 V */
} canfdi_sim_dcm_fx_t;

typedef struct {
  double u_cmd_V;   /* armature voltage command */
  uint8_t bridge;   /* CANFDI_SIM_BRIDGE_A, _B or _NONE */
  bool enable;      /* false: bridges off (high impedance) */
  double load_Nm;   /* external load torque (the profile part of M_L) */
} canfdi_sim_dcm_in_t;

typedef struct {
  uint32_t stick_events;   /* transitions into the stuck mode (monotone) */
  uint32_t cmd_clamps;     /* steps with |u_cmd| > supply (monotone) */
} canfdi_sim_dcm_diag_t;

typedef struct {
  canfdi_sim_dcm_params_t p;
  double r20_ohm;          /* winding resistance at 20 C, from ra_cold_ohm */
  /* state */
  double i_A;
  double w_rad_s;
  double temp_C;           /* winding temperature */
  bool stuck;
  /* outputs of the last step (true values) */
  double ua_V;             /* terminal voltage at step end */
  double ra_ohm;           /* effective R_A (thermal and fault) at step end */
  double psi_eff_Vs;       /* effective Psi */
  double mf0_eff_Nm;       /* effective Coulomb friction */
  double mf1_eff_Nms;      /* effective viscous friction */
  double load_total_Nm;    /* M_L at step end, fan term included */
  canfdi_sim_dcm_diag_t diag;
} canfdi_sim_dcm_t;

/* Isermann's defaults as documented above. */
void canfdi_sim_dcm_default_params(canfdi_sim_dcm_params_t *p);

/* Healthy effects (factors 1, no dead bridge). */
void canfdi_sim_dcm_fx_none(canfdi_sim_dcm_fx_t *fx);

/* -CANFDI_EINVAL if a parameter is out of its physical domain (non-positive
 * L, J, Psi, R, R_th, C_th; negative friction; supply outside 0..80 V;
 * non-finite values). Starts at rest at ambient temperature. */
int canfdi_sim_dcm_init(canfdi_sim_dcm_t *m, const canfdi_sim_dcm_params_t *p);

/* Sets the state (e.g. from a scenario's initial conditions). -EINVAL if
 * not finite or temp_C below -273.15. */
int canfdi_sim_dcm_set_state(canfdi_sim_dcm_t *m, double i_A, double w_rad_s, double temp_C);

/* Winding resistance at a temperature (no fault factor). */
double canfdi_sim_dcm_winding_ohm(const canfdi_sim_dcm_t *m, double temp_C);

/* Advances the motor by 1 ms with constant inputs and fault effects.
 * Cannot fail by contract (pointers asserted). */
void canfdi_sim_dcm_step(canfdi_sim_dcm_t *m, const canfdi_sim_dcm_in_t *in,
                         const canfdi_sim_dcm_fx_t *fx);

#endif /* CANFDI_SIM_DCM_H */
