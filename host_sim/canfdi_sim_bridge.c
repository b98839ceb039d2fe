/* canfdi_sim_bridge.c — see canfdi_sim_bridge.h. */
#include "canfdi_sim_bridge.h"

canfdi_sim_bridge_mode_t canfdi_sim_bridge_mode(double u_cmd_V, double supply_V, bool enable,
                                                bool dead, double i_A, double emf_V)
{
  canfdi_sim_bridge_mode_t m;
  m.u_V = 0.0;
  m.open = false;
  m.i_sign = 0.0;
  if (enable && dead) {
    /* shorted terminals */
  } else if (enable) {
    m.u_V = u_cmd_V;
    if (m.u_V > supply_V) {
      m.u_V = supply_V;
    } else if (m.u_V < -supply_V) {
      m.u_V = -supply_V;
    } else {
      /* within the supply */
    }
  } else if (i_A > 0.0) {
    m.u_V = -supply_V;
    m.i_sign = 1.0;
  } else if (i_A < 0.0) {
    m.u_V = supply_V;
    m.i_sign = -1.0;
  } else if (emf_V > supply_V) {
    m.u_V = supply_V; /* generator: current starts flowing negative */
    m.i_sign = -1.0;
  } else if (emf_V < -supply_V) {
    m.u_V = -supply_V;
    m.i_sign = 1.0;
  } else {
    m.open = true;
  }
  return m;
}

double canfdi_sim_bridge_terminal_V(const canfdi_sim_bridge_mode_t *m, double emf_V)
{
  return m->open ? emf_V : m->u_V;
}
