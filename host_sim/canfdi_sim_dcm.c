/* canfdi_sim_dcm.c — see canfdi_sim_dcm.h. */
#include "canfdi_sim_dcm.h"

#include <math.h>
#include <stddef.h>

#include "canfdi_sim_bridge.h"
#include "canfdi_sim_ode.h"
#include "core/canfdi_common.h"

#define DCM_SUPPLY_MAX_V 80.0

/* Everything the derivative needs for one sub-step: the effective
 * parameters, the frozen inputs and the frozen friction mode. */
typedef struct {
  const canfdi_sim_dcm_t *m;
  canfdi_sim_bridge_mode_t br;
  double psi;
  double mf0;
  double mf1;
  double load_Nm;
  double ra_factor;
  double fric_dir;   /* +1 / -1: direction friction opposes; unused if stuck */
  bool stuck;
} dcm_ctx_t;

void canfdi_sim_dcm_default_params(canfdi_sim_dcm_params_t *p)
{
  p->ra_cold_ohm = 1.35;
  p->la_H = 6.82e-3;
  p->psi_Vs = 0.33;
  p->j_kgm2 = 1.92e-3;
  p->mf1_Nms = 0.36e-3;
  p->mf0_Nm = 0.11;
  p->alpha_per_K = 0.0039;
  p->ambient_C = 20.0;
  p->rth_K_W = 1.3;
  p->cth_J_K = 2000.0;
  p->thermal = true;
  p->load_k_fan_Nms = 0.0;
  p->supply_V = 48.0;
  p->stiction_band_rad_s = 1e-4;
}

void canfdi_sim_dcm_fx_none(canfdi_sim_dcm_fx_t *fx)
{
  fx->ra_factor = 1.0;
  fx->psi_factor = 1.0;
  fx->friction_factor = 1.0;
  fx->bridge_dead[0] = false;
  fx->bridge_dead[1] = false;
}

static bool all_finite(const canfdi_sim_dcm_params_t *p)
{
  return isfinite(p->ra_cold_ohm) && isfinite(p->la_H) && isfinite(p->psi_Vs) &&
         isfinite(p->j_kgm2) && isfinite(p->mf1_Nms) && isfinite(p->mf0_Nm) &&
         isfinite(p->alpha_per_K) && isfinite(p->ambient_C) && isfinite(p->rth_K_W) &&
         isfinite(p->cth_J_K) && isfinite(p->load_k_fan_Nms) && isfinite(p->supply_V) &&
         isfinite(p->stiction_band_rad_s);
}

int canfdi_sim_dcm_init(canfdi_sim_dcm_t *m, const canfdi_sim_dcm_params_t *p)
{
  int rc = CANFDI_OK;
  if ((m == NULL) || (p == NULL) || !all_finite(p) || !(p->ra_cold_ohm > 0.0) ||
      !(p->la_H > 0.0) || !(p->psi_Vs > 0.0) || !(p->j_kgm2 > 0.0) || (p->mf1_Nms < 0.0) ||
      (p->mf0_Nm < 0.0) || (p->alpha_per_K < 0.0) || !(p->rth_K_W > 0.0) ||
      !(p->cth_J_K > 0.0) || (p->load_k_fan_Nms < 0.0) || (p->supply_V < 0.0) ||
      (p->supply_V > DCM_SUPPLY_MAX_V) || !(p->stiction_band_rad_s > 0.0) ||
      !((1.0 + (p->alpha_per_K * (p->ambient_C - 20.0))) > 0.0)) {
    rc = -CANFDI_EINVAL;
  } else {
    m->p = *p;
    m->r20_ohm = p->ra_cold_ohm / (1.0 + (p->alpha_per_K * (p->ambient_C - 20.0)));
    m->i_A = 0.0;
    m->w_rad_s = 0.0;
    m->temp_C = p->ambient_C;
    m->stuck = true;
    m->ua_V = 0.0;
    m->ra_ohm = p->ra_cold_ohm;
    m->psi_eff_Vs = p->psi_Vs;
    m->mf0_eff_Nm = p->mf0_Nm;
    m->mf1_eff_Nms = p->mf1_Nms;
    m->load_total_Nm = 0.0;
    m->diag.stick_events = 0U;
    m->diag.cmd_clamps = 0U;
  }
  return rc;
}

int canfdi_sim_dcm_set_state(canfdi_sim_dcm_t *m, double i_A, double w_rad_s, double temp_C)
{
  int rc = CANFDI_OK;
  if (!isfinite(i_A) || !isfinite(w_rad_s) || !isfinite(temp_C) || (temp_C < -273.15)) {
    rc = -CANFDI_EINVAL;
  } else {
    m->i_A = i_A;
    m->w_rad_s = w_rad_s;
    m->temp_C = temp_C;
    m->stuck = false;
    m->ra_ohm = canfdi_sim_dcm_winding_ohm(m, temp_C);
  }
  return rc;
}

double canfdi_sim_dcm_winding_ohm(const canfdi_sim_dcm_t *m, double temp_C)
{
  double r = m->r20_ohm * (1.0 + (m->p.alpha_per_K * (temp_C - 20.0)));
  /* Below about -236 C the linear law would go negative; copper does not. */
  if (r < (0.01 * m->r20_ohm)) {
    r = 0.01 * m->r20_ohm;
  }
  return r;
}

/* x = {I_A, w, T}. */
static void dcm_deriv(const void *vctx, const double *x, double *dxdt)
{
  const dcm_ctx_t *c = (const dcm_ctx_t *)vctx;
  const canfdi_sim_dcm_t *m = c->m;
  const double rw = canfdi_sim_dcm_winding_ohm(m, x[2]);
  const double ra = rw * c->ra_factor;
  if (c->br.open) {
    dxdt[0] = 0.0;
  } else {
    dxdt[0] = (c->br.u_V - (ra * x[0]) - (c->psi * x[1])) / m->p.la_H;
  }
  if (c->stuck) {
    dxdt[1] = 0.0;
  } else {
    const double load = c->load_Nm + (m->p.load_k_fan_Nms * x[1]);
    dxdt[1] = ((c->psi * x[0]) - (c->mf1 * x[1]) - (c->mf0 * c->fric_dir) - load) / m->p.j_kgm2;
  }
  if (m->p.thermal) {
    dxdt[2] = ((x[0] * x[0] * rw) - ((x[2] - m->p.ambient_C) / m->p.rth_K_W)) / m->p.cth_J_K;
  } else {
    dxdt[2] = 0.0;
  }
}

void canfdi_sim_dcm_step(canfdi_sim_dcm_t *m, const canfdi_sim_dcm_in_t *in,
                         const canfdi_sim_dcm_fx_t *fx)
{
  dcm_ctx_t c;
  double x[3];
  unsigned k;
  bool dead_sel = false;
  bool on = false;

  CANFDI_ASSERT((m != NULL) && (in != NULL) && (fx != NULL));
  if ((in->bridge == CANFDI_SIM_BRIDGE_A) || (in->bridge == CANFDI_SIM_BRIDGE_B)) {
    on = in->enable;
    dead_sel = fx->bridge_dead[in->bridge - 1U];
  }
  if (on && ((in->u_cmd_V > m->p.supply_V) || (in->u_cmd_V < -m->p.supply_V))) {
    m->diag.cmd_clamps++;
  }
  c.m = m;
  c.psi = m->p.psi_Vs * fx->psi_factor;
  c.mf0 = m->p.mf0_Nm * fx->friction_factor;
  c.mf1 = m->p.mf1_Nms * fx->friction_factor;
  c.load_Nm = in->load_Nm;
  c.ra_factor = fx->ra_factor;
  x[0] = m->i_A;
  x[1] = m->w_rad_s;
  x[2] = m->temp_C;

  for (k = 0U; k < CANFDI_SIM_SUBSTEPS; k++) {
    const double drive = (c.psi * x[0]) - (c.mf1 * x[1]) - c.load_Nm -
                         (m->p.load_k_fan_Nms * x[1]);
    const bool was_stuck = m->stuck;
    c.br = canfdi_sim_bridge_mode(in->u_cmd_V, m->p.supply_V, on, dead_sel, x[0],
                                  c.psi * x[1]);
    if (c.br.open) {
      x[0] = 0.0;
    }
    if (fabs(x[1]) < m->p.stiction_band_rad_s) {
      if (fabs(drive) <= c.mf0) {
        c.stuck = true;
        c.fric_dir = 0.0;
        x[1] = 0.0;
      } else {
        c.stuck = false;
        c.fric_dir = (drive > 0.0) ? 1.0 : -1.0;
      }
    } else {
      c.stuck = false;
      c.fric_dir = (x[1] > 0.0) ? 1.0 : -1.0;
    }
    if (c.stuck && !was_stuck) {
      m->diag.stick_events++;
    }
    m->stuck = c.stuck;
    canfdi_sim_ode_rk4(dcm_deriv, &c, x, 3U, CANFDI_SIM_SUBSTEP_S);
    /* Friction can stop the rotor but never reverse it. */
    if (!c.stuck && ((x[1] * c.fric_dir) < 0.0)) {
      x[1] = 0.0;
    }
    /* Free-wheeling diodes block reverse current. */
    if ((x[0] * c.br.i_sign) < 0.0) {
      x[0] = 0.0;
    }
  }
  m->i_A = x[0];
  m->w_rad_s = x[1];
  m->temp_C = x[2];
  c.br = canfdi_sim_bridge_mode(in->u_cmd_V, m->p.supply_V, on, dead_sel, x[0],
                                c.psi * x[1]);
  m->ua_V = canfdi_sim_bridge_terminal_V(&c.br, c.psi * x[1]);
  m->ra_ohm = canfdi_sim_dcm_winding_ohm(m, x[2]) * fx->ra_factor;
  m->psi_eff_Vs = c.psi;
  m->mf0_eff_Nm = c.mf0;
  m->mf1_eff_Nms = c.mf1;
  m->load_total_Nm = c.load_Nm + (m->p.load_k_fan_Nms * x[1]);
}
