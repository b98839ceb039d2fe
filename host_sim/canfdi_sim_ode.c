/* canfdi_sim_ode.c — see canfdi_sim_ode.h. */
#include "canfdi_sim_ode.h"

#include "core/canfdi_common.h"

void canfdi_sim_ode_rk4(canfdi_sim_ode_fn f, const void *ctx, double *x, size_t n, double h)
{
  double k1[CANFDI_SIM_ODE_MAX_N];
  double k2[CANFDI_SIM_ODE_MAX_N];
  double k3[CANFDI_SIM_ODE_MAX_N];
  double k4[CANFDI_SIM_ODE_MAX_N];
  double tmp[CANFDI_SIM_ODE_MAX_N];
  size_t i;

  CANFDI_ASSERT((n > 0U) && (n <= CANFDI_SIM_ODE_MAX_N));
  f(ctx, x, k1);
  for (i = 0U; i < n; i++) {
    tmp[i] = x[i] + (0.5 * h * k1[i]);
  }
  f(ctx, tmp, k2);
  for (i = 0U; i < n; i++) {
    tmp[i] = x[i] + (0.5 * h * k2[i]);
  }
  f(ctx, tmp, k3);
  for (i = 0U; i < n; i++) {
    tmp[i] = x[i] + (h * k3[i]);
  }
  f(ctx, tmp, k4);
  for (i = 0U; i < n; i++) {
    x[i] += (h / 6.0) * (k1[i] + (2.0 * k2[i]) + (2.0 * k3[i]) + k4[i]);
  }
}
