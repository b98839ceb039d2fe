/*
 * canfdi_sim_ode.h — the integrator shared by the plant models.
 *
 * Method: classical fourth-order Runge-Kutta (RK4) with a fixed step h. The
 * plants call it CANFDI_SIM_SUBSTEPS times per 1 ms plant step, so
 * h = 100 us. Why that is enough: the fastest eigenvalues of the plants are
 * the electrical poles, lambda ~ -R/L: about -950 1/s for the throttle
 * (L/R = 1 ms, coupled with the back-EMF) and -175 1/s for the DC motor
 * (L_A/R_A ~ 4.5..5 ms). With h = 100 us, |lambda*h| <= 0.095, RK4 is stable
 * up to 2.78 and its local relative error is ~ (lambda*h)^5 / 120 ~ 6e-8, so
 * trajectories agree with the exact solution to ~1e-7 relative over many
 * time constants (tests/sim/test_sim_dcm.c measures it against the
 * analytic solution of the linear motor model). The plants' non-smooth
 * terms (Coulomb friction, stiction, end stops) are not integrated through:
 * their mode is frozen for one sub-step and events are resolved between
 * sub-steps (see canfdi_sim_dcm.h, canfdi_sim_thr.h), so RK4 only ever sees
 * a smooth right-hand side.
 *
 * Cost: 4 calls of the derivative function and ~6*n flops per step.
 * Memory: 5*n doubles on the stack (n <= CANFDI_SIM_ODE_MAX_N).
 */
#ifndef CANFDI_SIM_ODE_H
#define CANFDI_SIM_ODE_H

#include <stddef.h>

/* Sub-steps per 1 ms plant step and the resulting RK4 step. */
#define CANFDI_SIM_SUBSTEPS 10U
#define CANFDI_SIM_STEP_S 1e-3
#define CANFDI_SIM_SUBSTEP_S (CANFDI_SIM_STEP_S / (double)CANFDI_SIM_SUBSTEPS)

#define CANFDI_SIM_ODE_MAX_N 4U

/* dx/dt = f(ctx, x). Must be smooth over one step. */
typedef void (*canfdi_sim_ode_fn)(const void *ctx, const double *x, double *dxdt);

/* Advances x (n states, n <= CANFDI_SIM_ODE_MAX_N) by one RK4 step of h
 * seconds, in place. Cannot fail by contract (n is asserted). */
void canfdi_sim_ode_rk4(canfdi_sim_ode_fn f, const void *ctx, double *x, size_t n, double h);

#endif /* CANFDI_SIM_ODE_H */
