/*
 * bench_sim.c — simulation rate of host_sim: simulated seconds per wall
 * second for both plants together (DC motor + throttle, 8 noisy sensors,
 * fault evaluation, the stand-in controller closing both loops), and for
 * the two plant integrators alone. Built -O2 without sanitizers by
 * host_sim/host_sim.mk. Prints one line and writes JSON to argv[1].
 * A benchmark: it reports, it never fails a test run.
 */
#define _POSIX_C_SOURCE 199309L

#include <stdio.h>
#include <string.h>
#include <time.h>

#include "canfdi_sim.h"
#include "canfdi_sim_ode.h"
#include "canfdi_sim_refctl.h"

#define SIM_SECONDS 200U

static double wall_s(void)
{
  struct timespec ts;
  (void)clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + ((double)ts.tv_nsec * 1e-9);
}

static canfdi_sim_t sim;

int main(int argc, char **argv)
{
  const unsigned steps = SIM_SECONDS * 1000U;
  canfdi_sim_cfg_t cfg;
  canfdi_sim_refctl_cfg_t ccfg;
  canfdi_sim_refctl_t ctl;
  canfdi_sim_in_t in;
  canfdi_sim_dcm_fx_t dfx;
  canfdi_sim_thr_fx_t tfx;
  double t0;
  double full_s;
  double plants_s;
  double checksum = 0.0;
  unsigned k;
  unsigned i;
  FILE *f;
  const double sig[CANFDI_SIM_N_SENSORS] = {0.05, 0.02, 0.2, 0.05, 0.003, 0.003, 0.01, 0.01};

  canfdi_sim_default_cfg(&cfg);
  memcpy(cfg.sigma, sig, sizeof sig);
  if (canfdi_sim_init(&sim, &cfg) != 0) {
    return 1;
  }
  canfdi_sim_refctl_default(&ccfg, &cfg);
  canfdi_sim_refctl_init(&ctl, &ccfg);
  in.dcm.load_Nm = 1.2;
  t0 = wall_s();
  for (k = 0U; k < steps; k++) {
    /* setpoints that keep both plants moving: speed and angle square waves */
    const double sp = ((k / 500U) % 2U == 0U) ? 100.0 : 60.0;
    const double an = ((k / 300U) % 2U == 0U) ? 20.0 : 70.0;
    canfdi_sim_refctl_step(&ctl, sp, an, &sim.meas, &in);
    canfdi_sim_step(&sim, &in);
  }
  full_s = wall_s() - t0;
  for (i = 0U; i < CANFDI_SIM_N_SENSORS; i++) {
    checksum += sim.meas.value[i];
  }

  canfdi_sim_dcm_fx_none(&dfx);
  canfdi_sim_thr_fx_none(&tfx);
  in.dcm.u_cmd_V = 38.4;
  in.thr.u_cmd_V = 4.0;
  t0 = wall_s();
  for (k = 0U; k < steps; k++) {
    in.thr.u_cmd_V = ((k / 300U) % 2U == 0U) ? 4.0 : -2.0;
    canfdi_sim_dcm_step(&sim.dcm, &in.dcm, &dfx);
    canfdi_sim_thr_step(&sim.thr, &in.thr, &tfx);
  }
  plants_s = wall_s() - t0;
  checksum += sim.dcm.w_rad_s + sim.thr.theta_rad;

  printf("bench sim: %.0f simulated s per wall s for both plants with sensors, faults and "
         "controller (%.2f us per 1 ms step); plant integrators alone %.0f s/s "
         "(%.2f us per step; RK4, %u sub-steps) [checksum %.3f]\n",
         (double)SIM_SECONDS / full_s, full_s * 1e6 / (double)steps,
         (double)SIM_SECONDS / plants_s, plants_s * 1e6 / (double)steps, CANFDI_SIM_SUBSTEPS,
         checksum);
  if (argc > 1) {
    f = fopen(argv[1], "w");
    if (f == NULL) {
      perror(argv[1]);
      return 1;
    }
    fprintf(f,
            "{\n  \"benchmark\": \"sim\",\n  \"build\": \"-O2, no sanitizers\",\n"
            "  \"simulated_s\": %u,\n  \"step_s\": 0.001,\n  \"substeps\": %u,\n"
            "  \"wall_s\": %.6f,\n  \"sim_s_per_wall_s\": %.1f,\n  \"us_per_step\": %.4f,\n"
            "  \"plants_only_wall_s\": %.6f,\n  \"plants_only_sim_s_per_wall_s\": %.1f,\n"
            "  \"plants_only_us_per_step\": %.4f\n}\n",
            SIM_SECONDS, CANFDI_SIM_SUBSTEPS, full_s, (double)SIM_SECONDS / full_s,
            full_s * 1e6 / (double)steps, plants_s, (double)SIM_SECONDS / plants_s,
            plants_s * 1e6 / (double)steps);
    if (fclose(f) != 0) {
      return 1;
    }
  }
  return 0;
}
