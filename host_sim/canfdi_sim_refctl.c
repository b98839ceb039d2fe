/* canfdi_sim_refctl.c — see canfdi_sim_refctl.h. */
#include "canfdi_sim_refctl.h"

#include <math.h>

#include "canfdi_sim_ode.h"

#define TPS_PLAUSIBLE_LO_V 0.25
#define TPS_PLAUSIBLE_HI_V 4.75
#define ANGLE_INT_BAND_DEG 3.0

void canfdi_sim_refctl_default(canfdi_sim_refctl_cfg_t *cfg, const canfdi_sim_cfg_t *sim_cfg)
{
  cfg->speed_kp = 0.8;
  cfg->speed_ki = 20.0;
  cfg->psi_nom_Vs = sim_cfg->dcm.psi_Vs;
  cfg->dcm_supply_V = sim_cfg->dcm.supply_V;
  cfg->angle_kp = 6.0;
  cfg->angle_ki = 50.0;
  cfg->angle_kd = 0.05;
  cfg->angle_d_tau_s = 2e-3;
  cfg->thr_supply_V = sim_cfg->thr.supply_V;
  cfg->thr_nom = sim_cfg->thr;
}

void canfdi_sim_refctl_init(canfdi_sim_refctl_t *c, const canfdi_sim_refctl_cfg_t *cfg)
{
  c->cfg = *cfg;
  c->speed_int_V = 0.0;
  c->angle_int_V = 0.0;
  c->angle_prev_deg = 0.0;
  c->angle_rate_deg_s = 0.0;
  c->have_prev = false;
}

static double clampd(double x, double lim, bool *sat)
{
  double y = x;
  *sat = false;
  if (y > lim) {
    y = lim;
    *sat = true;
  } else if (y < -lim) {
    y = -lim;
    *sat = true;
  } else {
    /* inside */
  }
  return y;
}

double canfdi_sim_refctl_angle_deg(double tps1_V, double tps2_V)
{
  const bool ok1 = (tps1_V > TPS_PLAUSIBLE_LO_V) && (tps1_V < TPS_PLAUSIBLE_HI_V);
  const bool ok2 = (tps2_V > TPS_PLAUSIBLE_LO_V) && (tps2_V < TPS_PLAUSIBLE_HI_V);
  const double a1 = (tps1_V - 0.5) * (90.0 / 4.0);
  const double a2 = (4.5 - tps2_V) * (90.0 / 4.0);
  double a = -1.0;
  if (ok1 && ok2) {
    a = 0.5 * (a1 + a2);
  } else if (ok1) {
    a = a1;
  } else if (ok2) {
    a = a2;
  } else {
    /* no position feedback */
  }
  return a;
}

void canfdi_sim_refctl_step(canfdi_sim_refctl_t *c, double speed_ref_rad_s, double angle_ref_deg,
                            const canfdi_sim_meas_t *meas, canfdi_sim_in_t *out)
{
  const double dt = CANFDI_SIM_STEP_S;
  const canfdi_sim_refctl_cfg_t *g = &c->cfg;
  const double e_w = speed_ref_rad_s - meas->value[CANFDI_SIM_S_DCM_SPEED];
  const double angle = canfdi_sim_refctl_angle_deg(meas->value[CANFDI_SIM_S_THR_TPS1],
                                                   meas->value[CANFDI_SIM_S_THR_TPS2]);
  bool sat = false;
  double u;

  /* Speed loop. */
  u = (g->psi_nom_Vs * speed_ref_rad_s) + (g->speed_kp * e_w) + c->speed_int_V;
  u = clampd(u, g->dcm_supply_V, &sat);
  if (!sat || ((e_w > 0.0) != (c->speed_int_V > 0.0))) {
    c->speed_int_V += g->speed_ki * e_w * dt;
  }
  out->dcm.u_cmd_V = u;
  out->dcm.bridge = CANFDI_SIM_BRIDGE_A;
  out->dcm.enable = true;

  /* Position loop. */
  if (angle < 0.0) {
    out->thr.u_cmd_V = 0.0;
    out->thr.enable = false; /* no feedback: let the spring take it home */
    c->have_prev = false;
    c->angle_int_V = 0.0;
  } else {
    const canfdi_sim_thr_params_t *n = &g->thr_nom;
    const double d_deg = angle_ref_deg - n->limp_home_deg;
    const double rad = 0.017453292519943295;
    const double t_spring = (n->spring_Nm_rad * d_deg * rad) +
                            ((d_deg > 0.0) ? n->pretension_Nm : -n->pretension_Nm);
    const double u_ff = (n->r_ohm / n->k_Nm_A) * t_spring;
    const double e = angle_ref_deg - angle;
    const double a = dt / (g->angle_d_tau_s + dt);
    if (c->have_prev) {
      c->angle_rate_deg_s += a * (((angle - c->angle_prev_deg) / dt) - c->angle_rate_deg_s);
    }
    c->angle_prev_deg = angle;
    c->have_prev = true;
    u = u_ff + (g->angle_kp * e) + c->angle_int_V - (g->angle_kd * c->angle_rate_deg_s);
    u = clampd(u, g->thr_supply_V, &sat);
    /* Integrate only near the target: during a stroke the integrator would
     * wind up and cause overshoot; near it, it removes the friction error. */
    if ((fabs(e) < ANGLE_INT_BAND_DEG) &&
        (!sat || ((e > 0.0) != (c->angle_int_V > 0.0)))) {
      c->angle_int_V += g->angle_ki * e * dt;
    }
    out->thr.u_cmd_V = u;
    out->thr.enable = true;
  }
}
