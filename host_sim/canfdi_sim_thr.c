/* canfdi_sim_thr.c — see canfdi_sim_thr.h. */
#include "canfdi_sim_thr.h"

#include <math.h>
#include <stddef.h>

#include "canfdi_sim_bridge.h"
#include "canfdi_sim_ode.h"
#include "core/canfdi_common.h"

#define THR_SUPPLY_MAX_V 16.0
#define DEG_PER_RAD 57.29577951308232
#define RAD_PER_DEG 0.017453292519943295

typedef struct {
  const canfdi_sim_thr_t *v;
  canfdi_sim_bridge_mode_t br;
  double r;
  double fric;
  double b;
  double spring_factor;
  double fric_dir;
  bool stuck;
  bool open;
} thr_ctx_t;

void canfdi_sim_thr_default_params(canfdi_sim_thr_params_t *p)
{
  p->j_kgm2 = 0.0021;
  p->b_Nms = 0.0088;
  p->k_Nm_A = 0.383;
  p->r_ohm = 1.5;
  p->l_H = 1.5e-3;
  p->spring_Nm_rad = 0.087;
  p->pretension_Nm = 0.396;
  p->friction_Nm = 0.284;
  p->limp_home_deg = 6.5;
  p->lh_width_deg = 0.1;
  p->max_deg = 90.0;
  p->supply_V = 13.5;
  p->stiction_band_rad_s = 1e-4;
}

void canfdi_sim_thr_fx_none(canfdi_sim_thr_fx_t *fx)
{
  fx->spring_factor = 1.0;
  fx->friction_factor = 1.0;
  fx->r_factor = 1.0;
  fx->motor_open = false;
  fx->jammed = false;
}

static bool all_finite(const canfdi_sim_thr_params_t *p)
{
  return isfinite(p->j_kgm2) && isfinite(p->b_Nms) && isfinite(p->k_Nm_A) &&
         isfinite(p->r_ohm) && isfinite(p->l_H) && isfinite(p->spring_Nm_rad) &&
         isfinite(p->pretension_Nm) && isfinite(p->friction_Nm) &&
         isfinite(p->limp_home_deg) && isfinite(p->lh_width_deg) && isfinite(p->max_deg) &&
         isfinite(p->supply_V) && isfinite(p->stiction_band_rad_s);
}

int canfdi_sim_thr_init(canfdi_sim_thr_t *v, const canfdi_sim_thr_params_t *p)
{
  int rc = CANFDI_OK;
  if ((v == NULL) || (p == NULL) || !all_finite(p) || !(p->j_kgm2 > 0.0) ||
      (p->b_Nms < 0.0) || !(p->k_Nm_A > 0.0) || !(p->r_ohm > 0.0) || !(p->l_H > 0.0) ||
      (p->spring_Nm_rad < 0.0) || (p->pretension_Nm < 0.0) || (p->friction_Nm < 0.0) ||
      !(p->lh_width_deg > 0.0) || !(p->max_deg > 0.0) || (p->max_deg > 180.0) ||
      !(p->limp_home_deg > 0.0) || !(p->limp_home_deg < p->max_deg) || (p->supply_V < 0.0) ||
      (p->supply_V > THR_SUPPLY_MAX_V) || !(p->stiction_band_rad_s > 0.0)) {
    rc = -CANFDI_EINVAL;
  } else {
    v->p = *p;
    v->i_A = 0.0;
    v->w_rad_s = 0.0;
    v->theta_rad = p->limp_home_deg * RAD_PER_DEG;
    v->stuck = true;
    v->u_V = 0.0;
    v->spring_eff_Nm_rad = p->spring_Nm_rad;
    v->pretension_eff_Nm = p->pretension_Nm;
    v->friction_eff_Nm = p->friction_Nm;
    v->b_eff_Nms = p->b_Nms;
    v->r_eff_ohm = p->r_ohm;
    v->diag.stop_hits = 0U;
    v->diag.cmd_clamps = 0U;
  }
  return rc;
}

int canfdi_sim_thr_set_state(canfdi_sim_thr_t *v, double theta_deg, double w_rad_s)
{
  int rc = CANFDI_OK;
  if (!isfinite(theta_deg) || !isfinite(w_rad_s) || (theta_deg < 0.0) ||
      (theta_deg > v->p.max_deg)) {
    rc = -CANFDI_EINVAL;
  } else {
    v->theta_rad = theta_deg * RAD_PER_DEG;
    v->w_rad_s = w_rad_s;
    v->i_A = 0.0;
    v->stuck = false;
  }
  return rc;
}

double canfdi_sim_thr_angle_deg(const canfdi_sim_thr_t *v)
{
  return v->theta_rad * DEG_PER_RAD;
}

double canfdi_sim_thr_tps1_V(double theta_deg)
{
  return 0.5 + ((4.0 * theta_deg) / 90.0);
}

double canfdi_sim_thr_tps2_V(double theta_deg)
{
  return 4.5 - ((4.0 * theta_deg) / 90.0);
}

double canfdi_sim_thr_spring_Nm(const canfdi_sim_thr_t *v, double theta_rad, double spring_factor)
{
  const double d = theta_rad - (v->p.limp_home_deg * RAD_PER_DEG);
  const double width = v->p.lh_width_deg * RAD_PER_DEG;
  return spring_factor * ((v->p.spring_Nm_rad * d) + (v->p.pretension_Nm * tanh(d / width)));
}

/* x = {i, w, theta}. */
static void thr_deriv(const void *vctx, const double *x, double *dxdt)
{
  const thr_ctx_t *c = (const thr_ctx_t *)vctx;
  const canfdi_sim_thr_t *v = c->v;
  if (c->open || c->br.open) {
    dxdt[0] = 0.0;
  } else {
    dxdt[0] = (c->br.u_V - (c->r * x[0]) - (v->p.k_Nm_A * x[1])) / v->p.l_H;
  }
  if (c->stuck) {
    dxdt[1] = 0.0;
    dxdt[2] = 0.0;
  } else {
    dxdt[1] = ((v->p.k_Nm_A * x[0]) - (c->b * x[1]) -
               canfdi_sim_thr_spring_Nm(v, x[2], c->spring_factor) - (c->fric * c->fric_dir)) /
              v->p.j_kgm2;
    dxdt[2] = x[1];
  }
}

void canfdi_sim_thr_step(canfdi_sim_thr_t *v, const canfdi_sim_thr_in_t *in,
                         const canfdi_sim_thr_fx_t *fx)
{
  const double max_rad = v->p.max_deg * RAD_PER_DEG;
  thr_ctx_t c;
  double x[3];
  unsigned k;

  CANFDI_ASSERT((v != NULL) && (in != NULL) && (fx != NULL));
  if (in->enable && ((in->u_cmd_V > v->p.supply_V) || (in->u_cmd_V < -v->p.supply_V))) {
    v->diag.cmd_clamps++;
  }
  c.v = v;
  c.r = v->p.r_ohm * fx->r_factor;
  c.fric = v->p.friction_Nm * fx->friction_factor;
  c.b = v->p.b_Nms * fx->friction_factor;
  c.spring_factor = fx->spring_factor;
  c.open = fx->motor_open;
  c.fric_dir = 0.0;
  x[0] = fx->motor_open ? 0.0 : v->i_A;
  x[1] = v->w_rad_s;
  x[2] = v->theta_rad;

  for (k = 0U; k < CANFDI_SIM_SUBSTEPS; k++) {
    const double drive = (v->p.k_Nm_A * x[0]) - (c.b * x[1]) -
                         canfdi_sim_thr_spring_Nm(v, x[2], c.spring_factor);
    const bool slow = fabs(x[1]) < v->p.stiction_band_rad_s;
    c.br = canfdi_sim_bridge_mode(in->u_cmd_V, v->p.supply_V, in->enable, false, x[0],
                                  v->p.k_Nm_A * x[1]);
    if (c.br.open || c.open) {
      x[0] = 0.0;
    }
    if (fx->jammed) {
      c.stuck = true;
    } else if ((x[2] <= 0.0) && (x[1] <= 0.0) && (drive <= c.fric)) {
      c.stuck = true; /* resting on (or pressed into) the closed stop */
    } else if ((x[2] >= max_rad) && (x[1] >= 0.0) && (drive >= -c.fric)) {
      c.stuck = true; /* resting on (or pressed into) the open stop */
    } else if (slow) {
      c.stuck = fabs(drive) <= c.fric;
      c.fric_dir = (drive > 0.0) ? 1.0 : -1.0;
    } else {
      c.stuck = false;
      c.fric_dir = (x[1] > 0.0) ? 1.0 : -1.0;
    }
    if (c.stuck) {
      x[1] = 0.0;
      c.fric_dir = 0.0;
    }
    v->stuck = c.stuck;
    canfdi_sim_ode_rk4(thr_deriv, &c, x, 3U, CANFDI_SIM_SUBSTEP_S);
    if (!c.stuck && ((x[1] * c.fric_dir) < 0.0)) {
      x[1] = 0.0; /* friction stops the valve, never reverses it */
    }
    if ((x[0] * c.br.i_sign) < 0.0) {
      x[0] = 0.0; /* free-wheeling diodes block reverse current */
    }
    if (x[2] < 0.0) {
      x[2] = 0.0;
      x[1] = 0.0;
      v->diag.stop_hits++;
    } else if (x[2] > max_rad) {
      x[2] = max_rad;
      x[1] = 0.0;
      v->diag.stop_hits++;
    } else {
      /* between the stops */
    }
  }
  v->i_A = x[0];
  v->w_rad_s = x[1];
  v->theta_rad = x[2];
  c.br = canfdi_sim_bridge_mode(in->u_cmd_V, v->p.supply_V, in->enable, false, x[0],
                                v->p.k_Nm_A * x[1]);
  /* With the motor circuit open no voltage reaches the winding. */
  v->u_V = fx->motor_open ? 0.0 : canfdi_sim_bridge_terminal_V(&c.br, v->p.k_Nm_A * x[1]);
  v->spring_eff_Nm_rad = v->p.spring_Nm_rad * fx->spring_factor;
  v->pretension_eff_Nm = v->p.pretension_Nm * fx->spring_factor;
  v->friction_eff_Nm = c.fric;
  v->b_eff_Nms = c.b;
  v->r_eff_ohm = c.r;
}
