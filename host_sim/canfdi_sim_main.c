/*
 * canfdi_sim_main.c — `canfdi-sim`: runs a scenario against the plant
 * models without CAN and writes a CSV trace and a candump log of the frames
 * the plant would send. The loop is closed by the simulator's stand-in
 * controller (canfdi_sim_refctl.h) until the firmware ECU takes over.
 */
/* getopt_long and clock_gettime. The host build pre-includes assert.h,
 * which fixes the feature macros before this line, so host_sim.mk also
 * passes -D_GNU_SOURCE for this file. */
#ifndef _GNU_SOURCE
#define _GNU_SOURCE
#endif

#include <errno.h>
#include <getopt.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "canfdi_sim.h"
#include "canfdi_sim_frames.h"
#include "canfdi_sim_refctl.h"
#include "canfdi_sim_scenario.h"
#include "canfdi_sim_trace.h"
#include "core/canfdi_common.h"
#include "gen/canfdi_faults.h"

#define EXIT_USAGE 2

static void usage(FILE *out)
{
  fprintf(out,
          "Usage: canfdi-sim -s SCENARIO [options]\n"
          "\n"
          "Runs a host_sim scenario (DC motor drive + throttle valve, with injected\n"
          "faults) without CAN, closed by the simulator's stand-in reference controller\n"
          "(PI speed / PID position; the firmware ECU replaces it in a later issue).\n"
          "Writes a CSV trace and a candump-format log (as `candump -L`) of the frames\n"
          "the plant would send: DcmSensor and ThrSensor every 1 ms, SimPlantStatus\n"
          "every 100 ms (dbc/canfdi.dbc), E2E-protected, damaged by comm faults.\n"
          "\n"
          "Options:\n"
          "  -s, --scenario FILE   scenario to run (format: host_sim/SCENARIO.md)\n"
          "  -o, --output FILE     CSV trace ('-' for stdout); none if omitted\n"
          "  -l, --log FILE        candump log of the plant's frames; none if omitted\n"
          "  -c, --channel NAME    channel name written into the log (default vcan0)\n"
          "      --seed N          override the scenario's noise seed\n"
          "  -d, --duration S      override the scenario's duration [s]\n"
          "  -D, --decimate N      write every N-th step to the trace (default 1)\n"
          "      --epoch S         log timestamp of t = 0 [s since 1970] (default 0)\n"
          "      --check           only parse and validate the scenario, print a summary\n"
          "      --list-faults     print the fault catalogue and exit\n"
          "  -q, --quiet           no progress report on stderr\n"
          "  -h, --help            this text\n"
          "\n"
          "Examples:\n"
          "  canfdi-sim -s host_sim/scenarios/nominal.scn -o trace.csv -l frames.log\n"
          "  canfdi-sim -s host_sim/scenarios/dcm_ra_up.scn --seed 7 -d 5 -o - | head\n"
          "  canfdi-sim -s my.scn -l frames.log && \\\n"
          "    python -m cantools decode dbc/canfdi.dbc < frames.log | less\n"
          "  canfdi-sim --list-faults\n"
          "\n"
          "Exit status: 0 success, 1 I/O error, 2 bad usage or invalid scenario.\n");
}

static double wall_s(void)
{
  struct timespec ts;
  (void)clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + ((double)ts.tv_nsec * 1e-9);
}

static int parse_u64(const char *s, uint64_t *out)
{
  char *end = NULL;
  unsigned long long v;
  if ((s[0] < '0') || (s[0] > '9')) {
    return -CANFDI_EINVAL;
  }
  errno = 0;
  v = strtoull(s, &end, 10);
  if ((*end != '\0') || (errno != 0)) {
    return -CANFDI_EINVAL;
  }
  *out = (uint64_t)v;
  return CANFDI_OK;
}

static int parse_num(const char *s, double lo, double hi, double *out)
{
  char *end = NULL;
  double v;
  errno = 0;
  v = strtod(s, &end);
  if ((end == s) || (*end != '\0') || (errno != 0) || !isfinite(v) || (v < lo) || (v > hi)) {
    return -CANFDI_EINVAL;
  }
  *out = v;
  return CANFDI_OK;
}

static void list_faults(void)
{
  size_t i;
  printf("%-3s %-24s %-11s %-13s %-6s %-9s %-30s %s\n", "id", "name", "component", "kind", "unit",
         "default", "modes", "dtc");
  for (i = 0U; i < canfdi_fault_table_len; i++) {
    const canfdi_fault_info_t *f = &canfdi_fault_table[i];
    printf("%-3u %-24s %-11s %-13s %-6s %-9g %-30s %s\n", (unsigned)f->id, f->name, f->component,
           f->kind, f->unit, f->default_magnitude, f->modes, f->dtc);
  }
}

static void summary(const canfdi_sim_scn_t *scn, const char *path)
{
  size_t i;
  printf("%s: duration %g s, seed %llu, %zu speed / %zu angle / %zu load components, "
         "%zu fault(s), %zu expectation(s)\n",
         path, scn->duration_s, (unsigned long long)scn->cfg.seed, scn->speed.n, scn->angle.n,
         scn->load.n, scn->n_faults, scn->n_expects);
  for (i = 0U; i < scn->n_faults; i++) {
    const canfdi_sim_fault_spec_t *f = &scn->faults[i];
    printf("  fault %s %s from %.6f s, magnitude %g\n", canfdi_fault_table[f->id].name,
           canfdi_sim_fault_mode_name(f->mode), (double)f->t_start_us * 1e-6, f->magnitude);
  }
}

int main(int argc, char **argv)
{
  static const struct option longopts[] = {
      {"scenario", required_argument, NULL, 's'}, {"output", required_argument, NULL, 'o'},
      {"log", required_argument, NULL, 'l'},      {"channel", required_argument, NULL, 'c'},
      {"seed", required_argument, NULL, 'S'},     {"duration", required_argument, NULL, 'd'},
      {"decimate", required_argument, NULL, 'D'}, {"epoch", required_argument, NULL, 'E'},
      {"check", no_argument, NULL, 'C'},          {"list-faults", no_argument, NULL, 'L'},
      {"quiet", no_argument, NULL, 'q'},          {"help", no_argument, NULL, 'h'},
      {NULL, 0, NULL, 0}};
  const char *scn_path = NULL;
  const char *out_path = NULL;
  const char *log_path = NULL;
  const char *channel = "vcan0";
  bool have_seed = false;
  uint64_t seed = 0U;
  bool have_duration = false;
  double duration = 0.0;
  uint64_t decimate = 1U;
  double epoch_s = 0.0;
  bool check_only = false;
  bool quiet = false;
  int opt;
  static canfdi_sim_scn_t scn; /* ~9 kB: static rather than on the stack */
  static canfdi_sim_t sim;
  canfdi_sim_scn_err_t err;
  canfdi_sim_refctl_cfg_t ctl_cfg;
  canfdi_sim_refctl_t ctl;
  canfdi_sim_frames_t frames;
  canfdi_sim_in_t in;
  FILE *out = NULL;
  FILE *log = NULL;
  int status = EXIT_SUCCESS;
  uint64_t n_steps;
  uint64_t k;
  int64_t epoch_us;
  double t_wall0;
  double t_next_report;

  while ((opt = getopt_long(argc, argv, "s:o:l:c:d:D:qh", longopts, NULL)) != -1) {
    switch (opt) {
    case 's':
      scn_path = optarg;
      break;
    case 'o':
      out_path = optarg;
      break;
    case 'l':
      log_path = optarg;
      break;
    case 'c':
      channel = optarg;
      if ((channel[0] == '\0') || (strpbrk(channel, " \t\n()#") != NULL) || (strlen(channel) > 32U)) {
        fprintf(stderr, "canfdi-sim: invalid channel name '%s'\n", optarg);
        return EXIT_USAGE;
      }
      break;
    case 'S':
      if (parse_u64(optarg, &seed) != CANFDI_OK) {
        fprintf(stderr, "canfdi-sim: --seed '%s' is not an unsigned 64-bit integer\n", optarg);
        return EXIT_USAGE;
      }
      have_seed = true;
      break;
    case 'd':
      if (parse_num(optarg, 1e-3, CANFDI_SIM_SCN_MAX_DURATION_S, &duration) != CANFDI_OK) {
        fprintf(stderr, "canfdi-sim: --duration '%s' must be a number of seconds in [0.001, %g]\n",
                optarg, CANFDI_SIM_SCN_MAX_DURATION_S);
        return EXIT_USAGE;
      }
      have_duration = true;
      break;
    case 'D':
      if ((parse_u64(optarg, &decimate) != CANFDI_OK) || (decimate == 0U) || (decimate > 1000000U)) {
        fprintf(stderr, "canfdi-sim: --decimate '%s' must be an integer in 1..1000000\n", optarg);
        return EXIT_USAGE;
      }
      break;
    case 'E':
      if (parse_num(optarg, 0.0, 4e9, &epoch_s) != CANFDI_OK) {
        fprintf(stderr, "canfdi-sim: --epoch '%s' must be seconds in [0, 4e9]\n", optarg);
        return EXIT_USAGE;
      }
      break;
    case 'C':
      check_only = true;
      break;
    case 'L':
      list_faults();
      return EXIT_SUCCESS;
    case 'q':
      quiet = true;
      break;
    case 'h':
      usage(stdout);
      return EXIT_SUCCESS;
    default:
      fprintf(stderr, "Try 'canfdi-sim --help'.\n");
      return EXIT_USAGE;
    }
  }
  if (optind < argc) {
    fprintf(stderr, "canfdi-sim: unexpected argument '%s'\nTry 'canfdi-sim --help'.\n", argv[optind]);
    return EXIT_USAGE;
  }
  if (scn_path == NULL) {
    fprintf(stderr, "canfdi-sim: no scenario given (-s FILE)\nTry 'canfdi-sim --help'.\n");
    return EXIT_USAGE;
  }
  if (canfdi_sim_scn_load(&scn, scn_path, &err) != CANFDI_OK) {
    fprintf(stderr, "canfdi-sim: %s\n", err.msg);
    return EXIT_USAGE;
  }
  if (have_seed) {
    scn.cfg.seed = seed;
  }
  if (have_duration) {
    scn.duration_s = duration;
  }
  if (check_only) {
    summary(&scn, scn_path);
    return EXIT_SUCCESS;
  }
  if (canfdi_sim_scn_setup(&scn, &sim) != CANFDI_OK) {
    fprintf(stderr, "canfdi-sim: %s: cannot set up the plant from this scenario\n", scn_path);
    return EXIT_USAGE;
  }
  if (out_path != NULL) {
    out = (strcmp(out_path, "-") == 0) ? stdout : fopen(out_path, "w");
    if (out == NULL) {
      fprintf(stderr, "canfdi-sim: cannot write %s: %s\n", out_path, strerror(errno));
      return EXIT_FAILURE;
    }
  }
  if (log_path != NULL) {
    log = (strcmp(log_path, "-") == 0) ? stdout : fopen(log_path, "w");
    if (log == NULL) {
      fprintf(stderr, "canfdi-sim: cannot write %s: %s\n", log_path, strerror(errno));
      if ((out != NULL) && (out != stdout)) {
        (void)fclose(out);
      }
      return EXIT_FAILURE;
    }
  }

  canfdi_sim_refctl_default(&ctl_cfg, &scn.cfg);
  canfdi_sim_refctl_init(&ctl, &ctl_cfg);
  canfdi_sim_frames_init(&frames, (uint8_t)CANFDI_SIM_MODE_OFFLINE);
  epoch_us = (int64_t)llround(epoch_s * 1e6);
  n_steps = (uint64_t)llround(scn.duration_s * 1000.0);
  if ((out != NULL) && (canfdi_sim_trace_header(out) != CANFDI_OK)) {
    status = EXIT_FAILURE;
  }
  t_wall0 = wall_s();
  t_next_report = t_wall0 + 1.0;
  for (k = 0U; (k < n_steps) && (status == EXIT_SUCCESS); k++) {
    const int64_t t_us = canfdi_sim_time_us(&sim);
    canfdi_sim_trace_sp_t sp;
    canfdi_sim_scn_eval(&scn, t_us, &sp.speed_rad_s, &sp.angle_deg, &sp.load_Nm);
    canfdi_sim_refctl_step(&ctl, sp.speed_rad_s, sp.angle_deg, &sim.meas, &in);
    in.dcm.load_Nm = sp.load_Nm;
    if ((out != NULL) && ((k % decimate) == 0U) &&
        (canfdi_sim_trace_row(out, &sim, &sp, &in) != CANFDI_OK)) {
      status = EXIT_FAILURE;
    }
    if (log != NULL) {
      canfdi_sim_frame_t fr[CANFDI_SIM_FRAMES_MAX_PER_STEP];
      const size_t nf = canfdi_sim_frames_build(&frames, &sim, &in, fr);
      size_t i;
      for (i = 0U; i < nf; i++) {
        if (canfdi_sim_trace_candump(log, channel, epoch_us, t_us, &fr[i]) != CANFDI_OK) {
          status = EXIT_FAILURE;
        }
      }
    }
    canfdi_sim_step(&sim, &in);
    if (!quiet && ((k & 0x3FFU) == 0U)) {
      const double now = wall_s();
      if (now >= t_next_report) {
        fprintf(stderr, "canfdi-sim: %.1f / %.1f s simulated (%.0f %%), %.0fx real time\n",
                canfdi_sim_time_s(&sim), scn.duration_s,
                100.0 * (double)k / (double)n_steps, canfdi_sim_time_s(&sim) / (now - t_wall0));
        t_next_report = now + 1.0;
      }
    }
  }
  if ((out != NULL) && (out != stdout) && (fclose(out) != 0)) {
    status = EXIT_FAILURE;
  }
  if ((log != NULL) && (log != stdout) && (fclose(log) != 0)) {
    status = EXIT_FAILURE;
  }
  if ((out == stdout) || (log == stdout)) {
    if (fflush(stdout) != 0) {
      status = EXIT_FAILURE;
    }
  }
  if (status != EXIT_SUCCESS) {
    fprintf(stderr, "canfdi-sim: write error: %s\n", strerror(errno));
  }
  return status;
}
