/* canfdi_sim_trace.c — see canfdi_sim_trace.h. */
#include "canfdi_sim_trace.h"

#include <string.h>

#include "core/canfdi_common.h"
#include "gen/canfdi_faults.h"

int canfdi_sim_trace_header(FILE *out)
{
  const int n = fprintf(out,
                        "t_s,sp_speed_rad_s,sp_angle_deg,load_Nm,"
                        "dcm_u_cmd_V,dcm_bridge,dcm_enable,thr_u_cmd_V,thr_enable,"
                        "dcm_ua_V,dcm_ia_A,dcm_speed_rad_s,dcm_winding_C,dcm_ra_ohm,"
                        "thr_angle_deg,thr_speed_rad_s,thr_i_A,thr_u_V,"
                        "m_dcm_ua_V,m_dcm_ia_A,m_dcm_speed_rad_s,m_dcm_supply_V,"
                        "m_thr_tps1_V,m_thr_tps2_V,m_thr_i_A,m_thr_supply_V,faults\n");
  return (n < 0) ? -CANFDI_EINVAL : CANFDI_OK;
}

int canfdi_sim_trace_row(FILE *out, const canfdi_sim_t *sim, const canfdi_sim_trace_sp_t *sp,
                         const canfdi_sim_in_t *in)
{
  const double *m = sim->meas.value;
  int rc = CANFDI_OK;
  size_t i;
  bool first = true;
  int n = fprintf(out,
                  "%.3f,%.9g,%.9g,%.9g,%.9g,%u,%u,%.9g,%u,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,"
                  "%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,",
                  canfdi_sim_time_s(sim), sp->speed_rad_s, sp->angle_deg, sp->load_Nm,
                  in->dcm.u_cmd_V, (unsigned)in->dcm.bridge, in->dcm.enable ? 1U : 0U,
                  in->thr.u_cmd_V, in->thr.enable ? 1U : 0U, sim->dcm.ua_V, sim->dcm.i_A,
                  sim->dcm.w_rad_s, sim->dcm.temp_C, sim->dcm.ra_ohm,
                  canfdi_sim_thr_angle_deg(&sim->thr), sim->thr.w_rad_s, sim->thr.i_A,
                  sim->thr.u_V, m[CANFDI_SIM_S_DCM_UA], m[CANFDI_SIM_S_DCM_IA],
                  m[CANFDI_SIM_S_DCM_SPEED], m[CANFDI_SIM_S_DCM_SUPPLY], m[CANFDI_SIM_S_THR_TPS1],
                  m[CANFDI_SIM_S_THR_TPS2], m[CANFDI_SIM_S_THR_I], m[CANFDI_SIM_S_THR_SUPPLY]);
  if (n < 0) {
    rc = -CANFDI_EINVAL;
  }
  for (i = 0U; (rc == CANFDI_OK) && (i < canfdi_fault_table_len) && (i < 64U); i++) {
    if ((sim->fx.active_mask & ((uint64_t)1U << i)) != 0U) {
      if (fputs(first ? "" : "|", out) < 0 || fputs(canfdi_fault_table[i].name, out) < 0) {
        rc = -CANFDI_EINVAL;
      }
      first = false;
    }
  }
  if ((rc == CANFDI_OK) && (fputc('\n', out) == EOF)) {
    rc = -CANFDI_EINVAL;
  }
  return rc;
}

int canfdi_sim_trace_candump(FILE *out, const char *channel, int64_t epoch_us, int64_t t_us,
                             const canfdi_sim_frame_t *fr)
{
  const int64_t ts = epoch_us + t_us;
  char hex[2U * 8U + 1U];
  unsigned i;
  const unsigned dlc = (fr->dlc <= 8U) ? fr->dlc : 8U;
  static const char digits[] = "0123456789ABCDEF";
  for (i = 0U; i < dlc; i++) {
    hex[2U * i] = digits[(fr->data[i] >> 4U) & 0x0FU];
    hex[(2U * i) + 1U] = digits[fr->data[i] & 0x0FU];
  }
  hex[2U * dlc] = '\0';
  return (fprintf(out, "(%010lld.%06lld) %s %03X#%s\n", (long long)(ts / 1000000),
                  (long long)(ts % 1000000), channel, (unsigned)fr->id, hex) < 0)
             ? -CANFDI_EINVAL
             : CANFDI_OK;
}
