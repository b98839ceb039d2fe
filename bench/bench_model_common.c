/* bench_model_common.c — see bench_model_common.h. */
#define _POSIX_C_SOURCE 199309L

#include "bench_model_common.h"

#include <math.h>
#include <string.h>
#include <time.h>

#define PI_D 3.14159265358979323846
#define TPS_LO_V 0.25
#define TPS_HI_V 4.75
#define IA_MAX_A 29.5
#define W_MAX_RAD_S 395.0
#define THR_I_MAX_A 9.9

/* Sensor noise sigma, in the order of the CANFDI_SIM_S_* indices. */
static const double noise_sigma[CANFDI_SIM_N_SENSORS] = {0.05, 0.02, 0.2, 0.05, 0.003, 0.003, 0.01, 0.01};

const bm_chan_info_t bm_chan[BM_N_CH] = {
    {"r1", "r1", "V", BM_KIND_RESIDUAL, BM_PLANT_DCM, 0.0},
    {"r2", "r2", "N m", BM_KIND_RESIDUAL, BM_PLANT_DCM, 0.0},
    {"r3", "r3", "N m", BM_KIND_RESIDUAL, BM_PLANT_DCM, 0.0},
    {"r4", "r4", "V", BM_KIND_RESIDUAL, BM_PLANT_DCM, 0.0},
    {"corr", "CORR", "V", BM_KIND_RESIDUAL, BM_PLANT_THR, 0.0},
    {"arm", "ARM", "V", BM_KIND_RESIDUAL, BM_PLANT_THR, 0.0},
    {"pos1", "POS1", "rad", BM_KIND_RESIDUAL, BM_PLANT_THR, 0.0},
    {"pos2", "POS2", "rad", BM_KIND_RESIDUAL, BM_PLANT_THR, 0.0},
    {"est_dcm.R_A", "R_A", "Ohm", BM_KIND_PARAMETER, BM_PLANT_DCM, 1.52},
    {"est_dcm.L_A", "L_A", "H", BM_KIND_PARAMETER, BM_PLANT_DCM, 6.82e-3},
    {"est_dcm.Psi", "Psi", "V s", BM_KIND_PARAMETER, BM_PLANT_DCM, 0.33},
    {"est_dcm.J", "J", "kg m^2", BM_KIND_PARAMETER, BM_PLANT_DCM, 1.92e-3},
    {"est_dcm.M_F1", "MF1", "N m s", BM_KIND_PARAMETER, BM_PLANT_DCM, 0.36e-3},
    {"est_dcm.M_c", "Mc", "N m", BM_KIND_PARAMETER, BM_PLANT_DCM, 0.11 + 1.2},
    {"est_thr.R", "R", "Ohm", BM_KIND_PARAMETER, BM_PLANT_THR, 1.5},
    {"est_thr.L", "L", "H", BM_KIND_PARAMETER, BM_PLANT_THR, 1.5e-3},
    {"est_thr.K", "K", "N m/A", BM_KIND_PARAMETER, BM_PLANT_THR, 0.383},
    {"est_thr.U0", "U0", "V", BM_KIND_PARAMETER, BM_PLANT_THR, 0.0},
    {"est_thr.J", "J", "kg m^2", BM_KIND_PARAMETER, BM_PLANT_THR, 0.0021},
    {"est_thr.B", "B", "N m s/rad", BM_KIND_PARAMETER, BM_PLANT_THR, 0.0088},
    {"est_thr.k_s", "k_s", "N m/rad", BM_KIND_PARAMETER, BM_PLANT_THR, 0.087},
    {"est_thr.P", "P", "N m", BM_KIND_PARAMETER, BM_PLANT_THR, 0.396},
    {"est_thr.T_c", "T_c", "N m", BM_KIND_PARAMETER, BM_PLANT_THR, 0.284},
    {"est_thr.fast_P", "fP", "N m", BM_KIND_PARAMETER, BM_PLANT_THR, 0.396},
    {"est_thr.fast_T_c", "fTc", "N m", BM_KIND_PARAMETER, BM_PLANT_THR, 0.284},
    {"command_vs_measured_ua", "Ucmd", "V", BM_KIND_SIGNAL, BM_PLANT_DCM, 0.0},
    {"dcm_tracking_error", "wtrk", "rad/s", BM_KIND_SIGNAL, BM_PLANT_DCM, 0.0},
    {"thr_tracking_error", "atrk", "deg", BM_KIND_SIGNAL, BM_PLANT_THR, 0.0},
};

const bm_chan_info_t bm_rng[BM_N_RNG] = {
    {"range_tps1", "rTP1", "-", BM_KIND_RANGE, BM_PLANT_THR, 0.0},
    {"range_tps2", "rTP2", "-", BM_KIND_RANGE, BM_PLANT_THR, 0.0},
    {"range_ia", "rIA", "-", BM_KIND_RANGE, BM_PLANT_DCM, 0.0},
    {"range_w", "rW", "-", BM_KIND_RANGE, BM_PLANT_DCM, 0.0},
    {"range_thr_i", "rI", "-", BM_KIND_RANGE, BM_PLANT_THR, 0.0},
};

int32_t bm_q16(double x)
{
  double y = x * 65536.0;
  if (y > 2147483647.0) {
    y = 2147483647.0;
  } else if (y < -2147483648.0) {
    y = -2147483648.0;
  } else {
    /* in range */
  }
  return (int32_t)lround(y);
}

static double fq16(int32_t x)
{
  return (double)x / 65536.0;
}

static double fq24(int32_t x)
{
  return (double)x / 16777216.0;
}

static double clampd(double x, double lim)
{
  return (x > lim) ? lim : ((x < -lim) ? -lim : x);
}

static int8_t range_state(double x, double lo, double hi)
{
  return (int8_t)((x < lo) ? -1 : ((x > hi) ? 1 : 0));
}

double bm_wall_s(void)
{
  struct timespec ts;
  (void)clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + ((double)ts.tv_nsec * 1e-9);
}

void bm_json_str(FILE *f, const char *s)
{
  (void)fputc('"', f);
  for (; *s != '\0'; s++) {
    const unsigned char c = (unsigned char)*s;
    if ((c == '"') || (c == '\\')) {
      (void)fprintf(f, "\\%c", c);
    } else if (c < 0x20U) {
      (void)fprintf(f, "\\u%04x", c);
    } else {
      (void)fputc(c, f);
    }
  }
  (void)fputc('"', f);
}

void bm_rig_default_opts(bm_rig_opts_t *o)
{
  o->dcm_thermal = false;
  o->dcm_ra_cold_ohm = 1.52; /* Isermann's (warm) value, held */
  o->seed = 1U;
}

int bm_rig_init(bm_rig_t *r, const bm_rig_opts_t *o)
{
  canfdi_sim_refctl_cfg_t rc;
  canfdi_est_dcm_cfg_t edc;
  canfdi_est_thr_cfg_t etc;
  int rcode;
  memset(r, 0, sizeof(*r));
  canfdi_sim_default_cfg(&r->sim_cfg);
  r->sim_cfg.dcm.thermal = o->dcm_thermal;
  r->sim_cfg.dcm.ra_cold_ohm = o->dcm_ra_cold_ohm;
  memcpy(r->sim_cfg.sigma, noise_sigma, sizeof noise_sigma);
  r->sim_cfg.seed = o->seed;
  rcode = canfdi_sim_init(&r->sim, &r->sim_cfg);
  if (rcode == 0) {
    canfdi_sim_refctl_default(&rc, &r->sim_cfg);
    canfdi_sim_refctl_init(&r->ctl, &rc);
    canfdi_parity_dcm_default_cfg(&r->pdcm_cfg);
    rcode = (int)canfdi_parity_dcm_init(&r->pdcm, &r->pdcm_cfg);
  }
  if (rcode == 0) {
    canfdi_parity_thr_default_cfg(&r->pthr_cfg);
    rcode = (int)canfdi_parity_thr_init(&r->pthr, &r->pthr_cfg);
  }
  if (rcode == 0) {
    canfdi_est_dcm_default_cfg(&edc);
    rcode = (int)canfdi_est_dcm_init(&r->edcm, &edc);
  }
  if (rcode == 0) {
    canfdi_est_thr_default_cfg(&etc);
    rcode = (int)canfdi_est_thr_init(&r->ethr, &etc);
  }
  r->angle_rad_hold = r->sim_cfg.thr.limp_home_deg * PI_D / 180.0;
  r->k = 0;
  return rcode;
}

int bm_rig_start_dcm(bm_rig_t *r, double w_rad_s, double load_Nm)
{
  const int rc = canfdi_sim_dcm_set_state(&r->sim.dcm, load_Nm / r->sim_cfg.dcm.psi_Vs, w_rad_s,
                                          r->sim_cfg.dcm.ambient_C);
  if (rc == 0) {
    canfdi_sim_resample(&r->sim);
  }
  return rc;
}

int bm_rig_add_fault(bm_rig_t *r, uint8_t id, double t_s, double magnitude)
{
  canfdi_sim_fault_spec_t spec;
  int rc = canfdi_sim_fault_spec_make(&spec, id, CANFDI_SIM_MODE_ABRUPT, t_s, magnitude, 0.0, 0.0, 0.0);
  if (rc == 0) {
    rc = canfdi_sim_add_fault(&r->sim, &spec);
  }
  return rc;
}

static void set(bm_rig_t *r, unsigned c, double v, bool valid)
{
  r->val[c] = v;
  if (valid) {
    r->valid |= 1U << c;
  }
}

void bm_rig_step(bm_rig_t *r, double speed_ref_rad_s, double angle_ref_deg, double load_Nm)
{
  canfdi_sim_in_t in;
  canfdi_parity_dcm_in_t pd;
  canfdi_parity_thr_in_t pt;
  const double *m;
  double angle_deg;
  double u_thr;
  unsigned j;

  memset(&in, 0, sizeof in);
  canfdi_sim_refctl_step(&r->ctl, speed_ref_rad_s, angle_ref_deg, &r->sim.meas, &in);
  in.dcm.load_Nm = load_Nm;
  canfdi_sim_step(&r->sim, &in);
  r->k++;
  m = r->sim.meas.value;

  /* DC motor */
  pd.u_V_q16 = bm_q16(m[CANFDI_SIM_S_DCM_UA]);
  pd.i_A_q16 = bm_q16(m[CANFDI_SIM_S_DCM_IA]);
  pd.w_rad_s_q16 = bm_q16(m[CANFDI_SIM_S_DCM_SPEED]);
  pd.load_Nm_q16 = bm_q16(load_Nm);
  r->pdcm_out = canfdi_parity_dcm_step(&r->pdcm, &pd);
  canfdi_est_dcm_step(&r->edcm, pd.u_V_q16, pd.i_A_q16, pd.w_rad_s_q16);

  /* Throttle */
  pt.tps1_V_q16 = bm_q16(m[CANFDI_SIM_S_THR_TPS1]);
  pt.tps2_V_q16 = bm_q16(m[CANFDI_SIM_S_THR_TPS2]);
  pt.i_A_q16 = bm_q16(m[CANFDI_SIM_S_THR_I]);
  pt.u_V_q16 = bm_q16(in.thr.u_cmd_V);
  pt.supply_V_q16 = bm_q16(m[CANFDI_SIM_S_THR_SUPPLY]);
  pt.enabled = in.thr.enable;
  r->pthr_out = canfdi_parity_thr_step(&r->pthr, &pt);
  angle_deg = canfdi_sim_refctl_angle_deg(m[CANFDI_SIM_S_THR_TPS1], m[CANFDI_SIM_S_THR_TPS2]);
  if (angle_deg >= 0.0) {
    r->angle_rad_hold = angle_deg * PI_D / 180.0;
  }
  u_thr = in.thr.enable ? clampd(in.thr.u_cmd_V, m[CANFDI_SIM_S_THR_SUPPLY]) : 0.0;
  canfdi_est_thr_step(&r->ethr, bm_q16(u_thr), pt.i_A_q16, bm_q16(r->angle_rad_hold));

  /* Channels */
  r->valid = 0U;
  r->exceed = 0U;
  for (j = 0U; j < CANFDI_PARITY_DCM_N_RES; j++) {
    const bool v = (r->pdcm_out->valid & (1U << j)) != 0U;
    set(r, BM_CH_R1 + j, fq16(r->pdcm_out->r_q16[j]), v);
    r->rn[BM_CH_R1 + j] = fq16(r->pdcm_out->rn_q16[j]);
    if ((r->pdcm_out->exceed & (1U << j)) != 0U) {
      r->exceed |= 1U << (BM_CH_R1 + j);
    }
  }
  for (j = 0U; j < CANFDI_PARITY_THR_N_RES; j++) {
    const bool v = (r->pthr_out->valid & (1U << j)) != 0U;
    set(r, BM_CH_CORR + j, fq16(r->pthr_out->r_q16[j]), v);
    r->rn[BM_CH_CORR + j] = fq16(r->pthr_out->rn_q16[j]);
    if ((r->pthr_out->exceed & (1U << j)) != 0U) {
      r->exceed |= 1U << (BM_CH_CORR + j);
    }
  }
  {
    const bool ca = canfdi_est_dcm_arm_converged(&r->edcm);
    const bool cm = canfdi_est_dcm_mech_converged(&r->edcm);
    set(r, BM_CH_D_RA, fq16(canfdi_est_dcm_ra_q16(&r->edcm)), ca);
    set(r, BM_CH_D_LA, fq24(canfdi_est_dcm_la_q24(&r->edcm)), ca);
    set(r, BM_CH_D_PSI, fq16(canfdi_est_dcm_psi_q16(&r->edcm)), ca);
    set(r, BM_CH_D_J, fq24(canfdi_est_dcm_j_q24(&r->edcm)), cm);
    set(r, BM_CH_D_MF1, fq24(canfdi_est_dcm_mf1_q24(&r->edcm)), cm);
    set(r, BM_CH_D_MC, fq16(canfdi_est_dcm_mc_q16(&r->edcm)), cm);
  }
  {
    const bool ce = canfdi_est_thr_el_converged(&r->ethr);
    const bool cm = canfdi_est_thr_mech_converged(&r->ethr);
    set(r, BM_CH_T_R, fq16(canfdi_est_thr_r_q16(&r->ethr)), ce);
    set(r, BM_CH_T_L, fq24(canfdi_est_thr_l_q24(&r->ethr)), ce);
    set(r, BM_CH_T_K, fq16(canfdi_est_thr_k_q16(&r->ethr)), ce);
    set(r, BM_CH_T_U0, fq16(canfdi_est_thr_u0_q16(&r->ethr)), ce);
    set(r, BM_CH_T_J, fq24(canfdi_est_thr_j_q24(&r->ethr)), cm);
    set(r, BM_CH_T_B, fq24(canfdi_est_thr_b_q24(&r->ethr)), cm);
    set(r, BM_CH_T_KS, fq24(canfdi_est_thr_spring_q24(&r->ethr)), cm);
    set(r, BM_CH_T_P, fq16(canfdi_est_thr_pretension_q16(&r->ethr)), cm);
    set(r, BM_CH_T_TC, fq16(canfdi_est_thr_friction_q16(&r->ethr)), cm);
    /* the fast structured test's relative deviations on the nominal values */
    set(r, BM_CH_T_FP, 0.396 * (1.0 + fq16(canfdi_est_thr_fast_spring_dev_q16(&r->ethr))),
        canfdi_est_thr_fast_valid(&r->ethr));
    set(r, BM_CH_T_FTC, 0.284 * (1.0 + fq16(canfdi_est_thr_fast_friction_dev_q16(&r->ethr))),
        canfdi_est_thr_fast_valid(&r->ethr));
  }
  /* The measured U_A is the voltage held over the interval that ends now,
   * i.e. the command of this step as the bridge could deliver it. */
  set(r, BM_CH_UA_CMD, m[CANFDI_SIM_S_DCM_UA] - clampd(in.dcm.u_cmd_V, m[CANFDI_SIM_S_DCM_SUPPLY]), true);
  set(r, BM_CH_D_TRK, speed_ref_rad_s - m[CANFDI_SIM_S_DCM_SPEED], true);
  set(r, BM_CH_T_TRK, angle_ref_deg - angle_deg, angle_deg >= 0.0);

  r->rng[BM_RNG_TPS1] = range_state(m[CANFDI_SIM_S_THR_TPS1], TPS_LO_V, TPS_HI_V);
  r->rng[BM_RNG_TPS2] = range_state(m[CANFDI_SIM_S_THR_TPS2], TPS_LO_V, TPS_HI_V);
  r->rng[BM_RNG_IA] = range_state(m[CANFDI_SIM_S_DCM_IA], -IA_MAX_A, IA_MAX_A);
  r->rng[BM_RNG_W] = range_state(m[CANFDI_SIM_S_DCM_SPEED], -W_MAX_RAD_S, W_MAX_RAD_S);
  r->rng[BM_RNG_THR_I] = range_state(m[CANFDI_SIM_S_THR_I], -THR_I_MAX_A, THR_I_MAX_A);
}
