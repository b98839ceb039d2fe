/* canfdi_sim.c — see canfdi_sim.h. */
#include "canfdi_sim.h"

#include <math.h>
#include <string.h>

#include "core/canfdi_common.h"

static const char *const sensor_names[CANFDI_SIM_N_SENSORS] = {
    "dcm_ua", "dcm_ia", "dcm_speed", "dcm_supply", "thr_tps1", "thr_tps2", "thr_i", "thr_supply",
};

/* ADC spans from the agreed physical ranges. */
static const double span_min[CANFDI_SIM_N_SENSORS] = {-60.0, -30.0, -400.0, 0.0,
                                                      0.0,   0.0,   -10.0,  0.0};
static const double span_max[CANFDI_SIM_N_SENSORS] = {60.0, 30.0, 400.0, 80.0,
                                                      5.0,  5.0,  10.0,  16.0};

const char *canfdi_sim_sensor_name(unsigned idx)
{
  return (idx < CANFDI_SIM_N_SENSORS) ? sensor_names[idx] : NULL;
}

int canfdi_sim_sensor_find(const char *name)
{
  int out = -CANFDI_EINVAL;
  unsigned i;
  for (i = 0U; (name != NULL) && (i < CANFDI_SIM_N_SENSORS); i++) {
    if (strcmp(name, sensor_names[i]) == 0) {
      out = (int)i;
    }
  }
  return out;
}

void canfdi_sim_default_cfg(canfdi_sim_cfg_t *cfg)
{
  unsigned i;
  canfdi_sim_dcm_default_params(&cfg->dcm);
  canfdi_sim_thr_default_params(&cfg->thr);
  for (i = 0U; i < CANFDI_SIM_N_SENSORS; i++) {
    cfg->sigma[i] = 0.0;
  }
  cfg->seed = 1U;
}

int64_t canfdi_sim_time_us(const canfdi_sim_t *sim)
{
  return (int64_t)sim->step * (int64_t)CANFDI_CFG_STEP_US;
}

double canfdi_sim_time_s(const canfdi_sim_t *sim)
{
  return (double)canfdi_sim_time_us(sim) * 1e-6;
}

/* Samples every sensor with the effects in sim->fx. */
static void sample(canfdi_sim_t *sim)
{
  const canfdi_sim_fx_t *fx = &sim->fx;
  const double theta_deg = canfdi_sim_thr_angle_deg(&sim->thr);
  double truth[CANFDI_SIM_N_SENSORS];
  double x[CANFDI_SIM_N_SENSORS];
  double gain[CANFDI_SIM_N_SENSORS];
  double off[CANFDI_SIM_N_SENSORS];
  unsigned i;

  truth[CANFDI_SIM_S_DCM_UA] = sim->dcm.ua_V;
  truth[CANFDI_SIM_S_DCM_IA] = sim->dcm.i_A;
  truth[CANFDI_SIM_S_DCM_SPEED] = sim->dcm.w_rad_s;
  truth[CANFDI_SIM_S_DCM_SUPPLY] = sim->dcm.p.supply_V;
  truth[CANFDI_SIM_S_THR_TPS1] = canfdi_sim_thr_tps1_V(theta_deg);
  truth[CANFDI_SIM_S_THR_TPS2] = canfdi_sim_thr_tps2_V(theta_deg);
  truth[CANFDI_SIM_S_THR_I] = sim->thr.i_A;
  truth[CANFDI_SIM_S_THR_SUPPLY] = sim->thr.p.supply_V;
  for (i = 0U; i < CANFDI_SIM_N_SENSORS; i++) {
    x[i] = truth[i];
    gain[i] = 0.0;
    off[i] = 0.0;
  }
  off[CANFDI_SIM_S_DCM_UA] = fx->ua_offset_V;
  off[CANFDI_SIM_S_DCM_IA] = fx->ia_offset_A;
  gain[CANFDI_SIM_S_DCM_SPEED] = fx->speed_gain;
  off[CANFDI_SIM_S_DCM_SPEED] = fx->speed_offset_rad_s;
  for (i = 0U; i < 2U; i++) {
    const unsigned s = CANFDI_SIM_S_THR_TPS1 + i;
    off[s] = fx->tps_offset_V[i];
    /* A broken wire replaces the signal: drift no longer matters. A short
     * to the sensor supply wins over an open (it is the stronger path). */
    if (fx->tps_short[i]) {
      x[s] = CANFDI_SIM_TPS_SHORT_V;
      off[s] = 0.0;
    } else if (fx->tps_open[i]) {
      x[s] = CANFDI_SIM_TPS_OPEN_V;
      off[s] = 0.0;
    } else {
      /* healthy wiring */
    }
  }
  for (i = 0U; i < CANFDI_SIM_N_SENSORS; i++) {
    sim->meas.truth[i] = truth[i];
    sim->meas.value[i] = canfdi_sim_sensor_sample(&sim->sensor[i], x[i], gain[i], off[i]);
    sim->meas.code[i] = sim->sensor[i].last_code;
    sim->meas.analog[i] = sim->sensor[i].last_analog;
  }
}

int canfdi_sim_init(canfdi_sim_t *sim, const canfdi_sim_cfg_t *cfg)
{
  int rc = CANFDI_OK;
  unsigned i;
  if ((sim == NULL) || (cfg == NULL)) {
    rc = -CANFDI_EINVAL;
  } else {
    sim->cfg = *cfg;
    rc = canfdi_sim_dcm_init(&sim->dcm, &cfg->dcm);
    if (rc == CANFDI_OK) {
      rc = canfdi_sim_thr_init(&sim->thr, &cfg->thr);
    }
    for (i = 0U; (rc == CANFDI_OK) && (i < CANFDI_SIM_N_SENSORS); i++) {
      canfdi_sim_sensor_cfg_t sc;
      sc.min = span_min[i];
      sc.max = span_max[i];
      sc.gain = 1.0;
      sc.offset = 0.0;
      sc.sigma = cfg->sigma[i];
      rc = canfdi_sim_sensor_init(&sim->sensor[i], &sc, cfg->seed, i);
    }
  }
  if (rc == CANFDI_OK) {
    sim->n_faults = 0U;
    sim->step = 0U;
    canfdi_sim_fx_none(&sim->fx);
    sample(sim);
  }
  return rc;
}

void canfdi_sim_resample(canfdi_sim_t *sim)
{
  canfdi_sim_fault_effects(sim->faults, sim->n_faults, canfdi_sim_time_us(sim), &sim->fx);
  sample(sim);
}

int canfdi_sim_add_fault(canfdi_sim_t *sim, const canfdi_sim_fault_spec_t *spec)
{
  int rc = CANFDI_OK;
  if ((sim == NULL) || (spec == NULL)) {
    rc = -CANFDI_EINVAL;
  } else if (sim->n_faults >= CANFDI_SIM_MAX_FAULTS) {
    rc = -CANFDI_ERANGE;
  } else {
    sim->faults[sim->n_faults] = *spec;
    sim->n_faults++;
  }
  return rc;
}

size_t canfdi_sim_clear_faults(canfdi_sim_t *sim, uint8_t id)
{
  size_t kept = 0U;
  size_t i;
  CANFDI_ASSERT(sim != NULL);
  for (i = 0U; i < sim->n_faults; i++) {
    if ((id != 0U) && (sim->faults[i].id != id)) {
      sim->faults[kept] = sim->faults[i];
      kept++;
    }
  }
  i = sim->n_faults - kept;
  sim->n_faults = kept;
  return i;
}

void canfdi_sim_set_supply(canfdi_sim_t *sim, double dcm_supply_V, double thr_supply_V)
{
  CANFDI_ASSERT((sim != NULL) && (dcm_supply_V >= 0.0) && (dcm_supply_V <= span_max[CANFDI_SIM_S_DCM_SUPPLY]) &&
                (thr_supply_V >= 0.0) && (thr_supply_V <= span_max[CANFDI_SIM_S_THR_SUPPLY]));
  sim->cfg.dcm.supply_V = dcm_supply_V;
  sim->cfg.thr.supply_V = thr_supply_V;
  sim->dcm.p.supply_V = dcm_supply_V;
  sim->thr.p.supply_V = thr_supply_V;
}

void canfdi_sim_step(canfdi_sim_t *sim, const canfdi_sim_in_t *in)
{
  canfdi_sim_fx_t fx_now;
  CANFDI_ASSERT((sim != NULL) && (in != NULL));
  canfdi_sim_fault_effects(sim->faults, sim->n_faults, canfdi_sim_time_us(sim), &fx_now);
  canfdi_sim_dcm_step(&sim->dcm, &in->dcm, &fx_now.dcm);
  canfdi_sim_thr_step(&sim->thr, &in->thr, &fx_now.thr);
  sim->step++;
  canfdi_sim_fault_effects(sim->faults, sim->n_faults, canfdi_sim_time_us(sim), &sim->fx);
  sample(sim);
}
