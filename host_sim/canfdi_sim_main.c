/*
 * canfdi_sim_main.c — `canfdi-sim`: the plant simulator's command line.
 *
 * Offline (default): runs a scenario against the plant models without CAN,
 * closed by the simulator's stand-in controller (canfdi_sim_refctl.h), and
 * writes a CSV trace and a candump log of the frames the plant would send.
 *
 * On SocketCAN (--can IFACE): the plant and vehicle side of a HIL bench
 * (canfdi_sim_rig.h, the same code as the SIL runner) against the firmware
 * ECU in another process (canfdi-ecu), paced either in lockstep (SimStep
 * after the plant's frames of step k; the plant advances when both actuator
 * frames of step k have arrived) or in real time (a step every 1 ms on
 * CLOCK_MONOTONIC). The protocol is the HIL contract's (host_sim/SCENARIO.md,
 * "canfdi-sim on SocketCAN").
 */
/* getopt_long, clock_nanosleep, sigaction. The host build pre-includes
 * assert.h, which fixes the feature macros before this line, so host_sim.mk
 * also passes -D_GNU_SOURCE for this file. */
#ifndef _GNU_SOURCE
#define _GNU_SOURCE
#endif

#include <errno.h>
#include <getopt.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "canfdi_sim.h"
#include "canfdi_sim_can.h"
#include "canfdi_sim_frames.h"
#include "canfdi_sim_refctl.h"
#include "canfdi_sim_rig.h"
#include "canfdi_sim_scenario.h"
#include "canfdi_sim_trace.h"
#include "core/canfdi_common.h"
#include "gen/canfdi_faults.h"
#include "gen/canfdi_sim_msg.h"

#define EXIT_USAGE 2

/* --can without -s: the built-in vehicle of host_sim/scenarios/nominal.scn
 * (same noise), setpoints constant after the first second, until a signal
 * or --duration. */
static const char builtin_scn[] =
    "duration 100000\n"
    "seed 1\n"
    "noise dcm_ua 0.05\nnoise dcm_ia 0.02\nnoise dcm_speed 0.2\nnoise dcm_supply 0.05\n"
    "noise thr_tps1 0.003\nnoise thr_tps2 0.003\nnoise thr_i 0.01\nnoise thr_supply 0.01\n"
    "speed ramp 0 1 100\n"
    "load step 0 1.2\n"
    "angle const 10\n";

static volatile sig_atomic_t g_stop; /* the signal that asked us to stop, 0 none */

static void on_signal(int sig) { g_stop = sig; }

static void usage(FILE *out)
{
  fprintf(out,
          "Usage: canfdi-sim -s SCENARIO [options]              (offline)\n"
          "       canfdi-sim --can IFACE [-s SCENARIO] [options] (HIL on SocketCAN)\n"
          "\n"
          "Simulates the plants (DC motor drive + throttle valve, with injected faults)\n"
          "of the canfdi supervisor.\n"
          "\n"
          "Offline (no --can): runs the scenario closed by the simulator's stand-in\n"
          "reference controller (PI speed / PID position) and writes a CSV trace and a\n"
          "candump-format log (as `candump -L`) of the frames the plant would send:\n"
          "DcmSensor and ThrSensor every 1 ms, SimPlantStatus every 100 ms\n"
          "(dbc/canfdi.dbc), E2E-protected, damaged by comm faults.\n"
          "\n"
          "On SocketCAN (--can IFACE): the plant and vehicle of a HIL bench against the\n"
          "firmware ECU (canfdi-ecu) on IFACE. Each 1 ms step sends SetpointDcm/Thr\n"
          "(every 10 ms, E2E-protected), DcmSensor, ThrSensor and SimPlantStatus, applies the ECU's\n"
          "DcmActuator/ThrActuator, and obeys SimFaultInject/SimFaultClear (fault from\n"
          "now + InjStartDelay) and external SetpointDcm/SetpointThr (they override the\n"
          "scenario's setpoints and load from then on; the sim keeps sending them).\n"
          "  --lockstep: after the frames of step k it sends SimStep(k) and waits for\n"
          "  both actuator frames before the plant advances: deterministic, the same\n"
          "  frames as canfdi-sil. Start `canfdi-ecu --lockstep` first.\n"
          "  --realtime: a step every 1 ms on CLOCK_MONOTONIC, the latest actuator\n"
          "  frames applied, no SimStep.\n"
          "Without -s it runs the built-in nominal vehicle (100 rad/s, 1.2 N m, 10 deg)\n"
          "until SIGINT/SIGTERM or --duration. Prints injections, setpoint overrides\n"
          "and a summary on stderr.\n"
          "\n"
          "Options:\n"
          "  -s, --scenario FILE   scenario to run (format: host_sim/SCENARIO.md)\n"
          "  -o, --output FILE     CSV trace ('-' for stdout); none if omitted\n"
          "  -l, --log FILE        candump -L log ('-' for stdout): offline the plant's\n"
          "                        frames; with --can every frame sent and received,\n"
          "                        stamped with the simulation time of the step\n"
          "  -c, --channel NAME    channel name written into the log (default vcan0, or\n"
          "                        IFACE with --can)\n"
          "      --seed N          override the scenario's noise seed\n"
          "  -d, --duration S      override the scenario's duration [s]\n"
          "  -D, --decimate N      write every N-th step to the trace (default 1)\n"
          "      --epoch S         log timestamp of t = 0 [s since 1970] (default 0)\n"
          "      --can IFACE       run on the SocketCAN interface IFACE (e.g. vcan0)\n"
          "      --lockstep        lockstep pacing with SimStep (default with --can)\n"
          "      --realtime        real-time pacing, 1 ms on CLOCK_MONOTONIC\n"
          "      --ecu-timeout S   lockstep: give up when the ECU has not answered a\n"
          "                        step within S seconds (default 5)\n"
          "      --stats FILE      with --can: JSON with steps, frames_tx, frames_rx,\n"
          "                        wait_us {mean, max} (lockstep wait for the ECU)\n"
          "      --check           only parse and validate the scenario, print a summary\n"
          "      --list-faults     print the fault catalogue and exit\n"
          "  -q, --quiet           no progress report or events on stderr\n"
          "  -h, --help            this text\n"
          "\n"
          "Examples:\n"
          "  canfdi-sim -s host_sim/scenarios/nominal.scn -o trace.csv -l frames.log\n"
          "  canfdi-sim -s host_sim/scenarios/dcm_ra_up.scn --seed 7 -d 5 -o - | head\n"
          "  canfdi-sim -s my.scn -l frames.log && \\\n"
          "    python -m cantools decode dbc/canfdi.dbc < frames.log | less\n"
          "  canfdi-sim --list-faults\n"
          "  canfdi-ecu --lockstep -c vcan0 &   # then:\n"
          "  canfdi-sim --can vcan0 -s tests/sil/scenarios/tps1_open.scn -l bus.log\n"
          "  canfdi-sim --can vcan0 --realtime --duration 60 --stats sim.json\n"
          "  tools/vcan-run build/bin/canfdi-sim --can vcan0 --realtime -d 1\n"
          "\n"
          "Exit status: 0 success (end of the scenario or SIGINT/SIGTERM), 1 I/O error,\n"
          "CAN error or no answer from the ECU, 2 bad usage or invalid scenario.\n");
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
  if (scn->n_actions > 0U) {
    printf("  %zu ECU action(s) (cycle/clear/power_cycle): performed by the SIL rig only, "
           "ignored here\n", scn->n_actions);
  }
  if (scn->has_profile) {
    const canfdi_sim_csvprof_t *p = &scn->profile;
    unsigned q;
    printf("  profile %s: %u rows, 0 .. %.3f s\n", p->path, (unsigned)p->n_rows,
           (double)p->t_last_us * 1e-6);
    for (q = 0U; q < CANFDI_SIM_CSV_N; q++) {
      if (p->has[q]) {
        printf("    %-13s %g .. %g\n", canfdi_sim_csvprof_name(q), p->min[q], p->max[q]);
      }
    }
  }
  if (scn->n_uds > 0U) {
    printf("  %zu uds request(s): sent by the SIL rig's tester only, ignored here\n", scn->n_uds);
  }
}

/* Options of the SocketCAN mode. */
typedef struct {
  const char *iface;
  bool realtime;
  double ecu_timeout_s;
  const char *stats_path;
  bool unlimited;       /* built-in vehicle without --duration: until a signal */
  bool quiet;
  const char *channel;  /* in the log */
  int64_t epoch_us;
  uint64_t decimate;
} can_opts_t;

/* What a SocketCAN run counts (for the summary and --stats). */
typedef struct {
  uint64_t steps;
  double wait_us_sum;
  double wait_us_max;
  uint64_t late_steps;     /* realtime: woke more than one period late */
  double late_us_max;
  double wall_s;
} can_stats_t;

static int64_t mono_us(void)
{
  struct timespec ts;
  (void)clock_gettime(CLOCK_MONOTONIC, &ts);
  return ((int64_t)ts.tv_sec * 1000000) + ((int64_t)ts.tv_nsec / 1000);
}

static const char *fault_name(uint8_t id)
{
  return (id < canfdi_fault_table_len) ? canfdi_fault_table[id].name : "?";
}

/* One line on stderr for the events a tester causes. */
static void print_event(const canfdi_sim_rig_t *r, int rc, const canfdi_sim_rig_event_t *ev,
                        const canfdi_sim_frame_t *f, double t_s)
{
  if (rc == CANFDI_SIM_RIG_RX_INJECT) {
    fprintf(stderr, "canfdi-sim: %.3f s: inject %s %s magnitude %g from %.3f s\n", t_s,
            fault_name(ev->spec.id), canfdi_sim_fault_mode_name(ev->spec.mode), ev->spec.magnitude,
            (double)ev->spec.t_start_us * 1e-6);
  } else if (rc == CANFDI_SIM_RIG_RX_CLEAR) {
    fprintf(stderr, "canfdi-sim: %.3f s: clear %s (%zu fault(s) removed)\n", t_s,
            (ev->fault_id == 0U) ? "all faults" : fault_name(ev->fault_id), ev->n_cleared);
  } else if ((rc == CANFDI_SIM_RIG_RX_SP_DCM) && ev->changed) {
    fprintf(stderr, "canfdi-sim: %.3f s: setpoint override: speed %g rad/s, load %g N m\n", t_s,
            r->sp.speed_rad_s, r->sp.load_Nm);
  } else if ((rc == CANFDI_SIM_RIG_RX_SP_THR) && ev->changed) {
    fprintf(stderr, "canfdi-sim: %.3f s: setpoint override: angle %g deg\n", t_s, r->sp.angle_deg);
  } else if ((rc < 0) && (f->id != CANFDI_SIM_MSG_DCM_ACTUATOR_FRAME_ID) &&
             (f->id != CANFDI_SIM_MSG_THR_ACTUATOR_FRAME_ID)) {
    fprintf(stderr, "canfdi-sim: %.3f s: ignored frame 0x%03X (%s)\n", t_s, (unsigned)f->id,
            (rc == -CANFDI_ERANGE) ? "fault table full"
                                   : "wrong length, unknown fault or mode, or magnitude out of range");
  } else {
    /* actuators, repeated overrides: silent */
  }
}

static int write_stats(const char *path, const can_opts_t *o, const canfdi_sim_rig_t *r,
                       const canfdi_sim_can_t *c, const can_stats_t *st)
{
  FILE *f = fopen(path, "w");
  const uint64_t waits = o->realtime ? 0U : st->steps;
  int rc = CANFDI_OK;
  if (f == NULL) {
    return -CANFDI_EIO;
  }
  fprintf(f,
          "{\n  \"interface\": \"%s\",\n  \"mode\": \"%s\",\n  \"steps\": %llu,\n"
          "  \"sim_time_s\": %.3f,\n  \"wall_s\": %.3f,\n  \"steps_per_s\": %.1f,\n"
          "  \"frames_tx\": %lu,\n  \"frames_rx\": %lu,\n  \"frames_tx_lost\": %lu,\n"
          "  \"wait_us\": {\"mean\": %.1f, \"max\": %.1f},\n"
          "  \"late_steps\": %llu,\n  \"late_us_max\": %.1f,\n"
          "  \"injects\": %lu,\n  \"clears\": %lu,\n  \"overrides\": %lu,\n  \"rejected\": %lu,\n"
          "  \"actuators_rejected\": %lu\n}\n",
          o->iface, o->realtime ? "realtime" : "lockstep", (unsigned long long)st->steps,
          (double)st->steps * 1e-3, st->wall_s,
          (st->wall_s > 0.0) ? ((double)st->steps / st->wall_s) : 0.0, (unsigned long)c->diag.tx,
          (unsigned long)c->diag.rx, (unsigned long)c->diag.tx_lost,
          (waits > 0U) ? (st->wait_us_sum / (double)waits) : 0.0, st->wait_us_max,
          (unsigned long long)st->late_steps, st->late_us_max, (unsigned long)r->diag.injects,
          (unsigned long)r->diag.clears, (unsigned long)r->diag.overrides,
          (unsigned long)r->diag.rejected, (unsigned long)r->diag.act_rejected);
  if (fclose(f) != 0) {
    rc = -CANFDI_EIO;
  }
  return rc;
}

/* Logs a frame and applies it to the rig. */
static int rx_apply(canfdi_sim_rig_t *r, const canfdi_sim_frame_t *f, FILE *log, const can_opts_t *o,
                    int64_t t_us)
{
  canfdi_sim_rig_event_t ev;
  const int rc = canfdi_sim_rig_rx(r, f, &ev);
  int st = CANFDI_OK;
  if (!o->quiet) {
    print_event(r, rc, &ev, f, (double)t_us * 1e-6);
  }
  if ((log != NULL) && (canfdi_sim_trace_candump(log, o->channel, o->epoch_us, t_us, f) != CANFDI_OK)) {
    st = -CANFDI_EIO;
  }
  return st;
}

/* The SocketCAN run. Returns an exit status. */
static int run_can(const can_opts_t *o, canfdi_sim_scn_t *scn, canfdi_sim_t *sim, FILE *out, FILE *log)
{
  static canfdi_sim_rig_t rig;
  static canfdi_sim_can_t can;
  can_stats_t st;
  struct sigaction sa;
  struct timespec next;
  const uint64_t n_steps =
      o->unlimited ? UINT64_MAX : (uint64_t)llround(scn->duration_s * 1000.0);
  const int64_t timeout_us = (int64_t)llround(o->ecu_timeout_s * 1e6);
  int status = EXIT_SUCCESS;
  bool io_error = false;
  int64_t t0_us;
  uint64_t k;

  memset(&st, 0, sizeof st);
  if (canfdi_sim_can_open(&can, o->iface) != CANFDI_OK) {
    fprintf(stderr, "canfdi-sim: %s\n", can.err);
    return EXIT_FAILURE;
  }
  (void)canfdi_sim_rig_init(&rig, scn, sim,
                            (uint8_t)(o->realtime ? CANFDI_SIM_MODE_REALTIME : CANFDI_SIM_MODE_LOCKSTEP));
  memset(&sa, 0, sizeof sa);
  sa.sa_handler = on_signal; /* no SA_RESTART: a wait returns at once */
  (void)sigemptyset(&sa.sa_mask);
  (void)sigaction(SIGINT, &sa, NULL);
  (void)sigaction(SIGTERM, &sa, NULL);
  if ((out != NULL) && (canfdi_sim_trace_header(out) != CANFDI_OK)) {
    io_error = true;
  }
  fprintf(stderr, "canfdi-sim: ready on %s (%s)\n", o->iface, o->realtime ? "realtime" : "lockstep");
  (void)fflush(stderr);

  t0_us = mono_us();
  (void)clock_gettime(CLOCK_MONOTONIC, &next);
  for (k = 0U; (k < n_steps) && (g_stop == 0) && (status == EXIT_SUCCESS) && !io_error; k++) {
    const int64_t t_us = canfdi_sim_time_us(sim);
    canfdi_sim_frame_t fr[CANFDI_SIM_RIG_MAX_TX + 1U];
    canfdi_sim_frame_t rx;
    size_t n;
    size_t i;
    if (o->realtime) {
      int64_t late_us;
      if (k > 0U) {
        next.tv_nsec += 1000000L;
        if (next.tv_nsec >= 1000000000L) {
          next.tv_nsec -= 1000000000L;
          next.tv_sec++;
        }
        while ((clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &next, NULL) == EINTR) &&
               (g_stop == 0)) {
        }
        if (g_stop != 0) {
          break;
        }
      }
      late_us = mono_us() - (((int64_t)next.tv_sec * 1000000) + ((int64_t)next.tv_nsec / 1000));
      if (late_us > 1000) {
        st.late_steps++;
      }
      st.late_us_max = ((double)late_us > st.late_us_max) ? (double)late_us : st.late_us_max;
    }
    /* 1-2: setpoints (every 10 ms) and the plant's frames of t_k */
    n = canfdi_sim_rig_begin(&rig, fr);
    if (canfdi_sim_scn_run_error(scn) != NULL) {
      fprintf(stderr, "canfdi-sim: %s\n", canfdi_sim_scn_run_error(scn));
      status = EXIT_FAILURE;
      break;
    }
    if (!o->realtime) {
      /* 3: SimStep(k) after them */
      canfdi_sim_rig_sim_step(&rig, &fr[n]);
      n++;
    }
    for (i = 0U; (i < n) && (status == EXIT_SUCCESS); i++) {
      if (canfdi_sim_can_send(&can, &fr[i]) != CANFDI_OK) {
        fprintf(stderr, "canfdi-sim: %s\n", can.err);
        status = EXIT_FAILURE;
      } else if ((log != NULL) &&
                 (canfdi_sim_trace_candump(log, o->channel, o->epoch_us, t_us, &fr[i]) != CANFDI_OK)) {
        io_error = true;
      } else {
        /* sent */
      }
    }
    if (status != EXIT_SUCCESS) {
      break;
    }
    if (!o->realtime) {
      /* 4: wait for both actuator frames of step k */
      const int64_t w0 = mono_us();
      const int64_t deadline = w0 + timeout_us;
      double w;
      while (!(rig.got_act_dcm && rig.got_act_thr) && (g_stop == 0) && (status == EXIT_SUCCESS)) {
        const int64_t left = deadline - mono_us();
        int rc;
        if (left <= 0) {
          fprintf(stderr,
                  "canfdi-sim: no actuator frames from the ECU for step %llu within %g s "
                  "(is canfdi-ecu --lockstep running on %s?)\n",
                  (unsigned long long)k, o->ecu_timeout_s, o->iface);
          status = EXIT_FAILURE;
          break;
        }
        rc = canfdi_sim_can_recv(&can, &rx, left);
        if (rc < 0) {
          fprintf(stderr, "canfdi-sim: %s\n", can.err);
          status = EXIT_FAILURE;
        } else if ((rc == 1) && (rx_apply(&rig, &rx, log, o, t_us) != CANFDI_OK)) {
          io_error = true;
        } else {
          /* next */
        }
      }
      if (!(rig.got_act_dcm && rig.got_act_thr)) {
        break; /* stopped or failed inside the step: the plant does not advance */
      }
      w = (double)(mono_us() - w0);
      st.wait_us_sum += w;
      st.wait_us_max = (w > st.wait_us_max) ? w : st.wait_us_max;
    } else {
      /* realtime: whatever has arrived; the latest actuator frames win */
      int rc;
      while ((rc = canfdi_sim_can_recv(&can, &rx, 0)) == 1) {
        if (rx_apply(&rig, &rx, log, o, t_us) != CANFDI_OK) {
          io_error = true;
        }
      }
      if (rc < 0) {
        fprintf(stderr, "canfdi-sim: %s\n", can.err);
        status = EXIT_FAILURE;
        break;
      }
    }
    if ((out != NULL) && ((k % o->decimate) == 0U) &&
        (canfdi_sim_trace_row(out, sim, &rig.sp, &rig.in) != CANFDI_OK)) {
      io_error = true;
    }
    /* 5: the plant steps with the step's load */
    canfdi_sim_rig_end(&rig);
    st.steps++;
  }
  st.wall_s = (double)(mono_us() - t0_us) * 1e-6;
  canfdi_sim_can_close(&can);
  if (!o->quiet) {
    const uint64_t waits = o->realtime ? 0U : st.steps;
    fprintf(stderr,
            "canfdi-sim: %s %s on %s: %llu steps (%.3f s simulated) in %.2f s (%.0f steps/s), "
            "%lu frames sent, %lu received",
            (g_stop != 0) ? "stopped by signal," : "done,", o->realtime ? "realtime" : "lockstep",
            o->iface, (unsigned long long)st.steps, (double)st.steps * 1e-3, st.wall_s,
            (st.wall_s > 0.0) ? ((double)st.steps / st.wall_s) : 0.0, (unsigned long)can.diag.tx,
            (unsigned long)can.diag.rx);
    if (o->realtime) {
      fprintf(stderr, ", %llu late step(s), max lateness %.0f us\n", (unsigned long long)st.late_steps,
              st.late_us_max);
    } else {
      fprintf(stderr, ", ECU wait mean %.0f us, max %.0f us\n",
              (waits > 0U) ? (st.wait_us_sum / (double)waits) : 0.0, st.wait_us_max);
    }
  }
  if ((o->stats_path != NULL) && (write_stats(o->stats_path, o, &rig, &can, &st) != CANFDI_OK)) {
    fprintf(stderr, "canfdi-sim: cannot write %s: %s\n", o->stats_path, strerror(errno));
    io_error = true;
  }
  if (io_error && (status == EXIT_SUCCESS)) {
    fprintf(stderr, "canfdi-sim: write error: %s\n", strerror(errno));
    status = EXIT_FAILURE;
  }
  return status;
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
      {"can", required_argument, NULL, 256},      {"lockstep", no_argument, NULL, 257},
      {"realtime", no_argument, NULL, 258},       {"ecu-timeout", required_argument, NULL, 259},
      {"stats", required_argument, NULL, 260},    {NULL, 0, NULL, 0}};
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
  bool channel_set = false;
  const char *can_iface = NULL;
  int pacing = 0; /* 0 default, 1 lockstep, 2 realtime */
  bool have_ecu_timeout = false;
  double ecu_timeout_s = 5.0;
  const char *stats_path = NULL;
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
      channel_set = true;
      break;
    case 256:
      can_iface = optarg;
      if ((can_iface[0] == '\0') || (strlen(can_iface) > 15U) || (strpbrk(can_iface, " \t\n()#/") != NULL)) {
        fprintf(stderr, "canfdi-sim: invalid interface name '%s'\n", optarg);
        return EXIT_USAGE;
      }
      break;
    case 257:
    case 258:
      if ((pacing != 0) && (pacing != (opt - 256))) {
        fprintf(stderr, "canfdi-sim: --lockstep and --realtime exclude each other\n");
        return EXIT_USAGE;
      }
      pacing = opt - 256;
      break;
    case 259:
      if (parse_num(optarg, 1e-3, 3600.0, &ecu_timeout_s) != CANFDI_OK) {
        fprintf(stderr, "canfdi-sim: --ecu-timeout '%s' must be seconds in [0.001, 3600]\n", optarg);
        return EXIT_USAGE;
      }
      have_ecu_timeout = true;
      break;
    case 260:
      stats_path = optarg;
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
  if ((can_iface == NULL) && ((pacing != 0) || have_ecu_timeout || (stats_path != NULL))) {
    fprintf(stderr, "canfdi-sim: --lockstep, --realtime, --ecu-timeout and --stats need --can IFACE\n"
                    "Try 'canfdi-sim --help'.\n");
    return EXIT_USAGE;
  }
  if ((can_iface != NULL) && (pacing == 2) && have_ecu_timeout) {
    fprintf(stderr, "canfdi-sim: --ecu-timeout applies to --lockstep only\n");
    return EXIT_USAGE;
  }
  if ((scn_path == NULL) && (can_iface == NULL)) {
    fprintf(stderr, "canfdi-sim: no scenario given (-s FILE)\nTry 'canfdi-sim --help'.\n");
    return EXIT_USAGE;
  }
  if (scn_path == NULL) {
    if (canfdi_sim_scn_parse(&scn, builtin_scn, "(built-in nominal vehicle)", &err) != CANFDI_OK) {
      fprintf(stderr, "canfdi-sim: %s\n", err.msg);
      return EXIT_USAGE;
    }
  } else if (canfdi_sim_scn_load(&scn, scn_path, &err) != CANFDI_OK) {
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
    summary(&scn, (scn_path != NULL) ? scn_path : "(built-in nominal vehicle)");
    return EXIT_SUCCESS;
  }
  if (canfdi_sim_scn_setup(&scn, &sim) != CANFDI_OK) {
    fprintf(stderr, "canfdi-sim: %s: cannot set up the plant from this scenario\n",
            (scn_path != NULL) ? scn_path : "(built-in)");
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

  if (can_iface != NULL) {
    can_opts_t o;
    o.iface = can_iface;
    o.realtime = (pacing == 2);
    o.ecu_timeout_s = ecu_timeout_s;
    o.stats_path = stats_path;
    o.unlimited = (scn_path == NULL) && !have_duration;
    o.quiet = quiet;
    o.channel = channel_set ? channel : can_iface;
    o.epoch_us = (int64_t)llround(epoch_s * 1e6);
    o.decimate = decimate;
    status = run_can(&o, &scn, &sim, out, log);
    if ((out != NULL) && (out != stdout) && (fclose(out) != 0)) {
      status = EXIT_FAILURE;
    }
    if ((log != NULL) && (log != stdout) && (fclose(log) != 0)) {
      status = EXIT_FAILURE;
    }
    if (((out == stdout) || (log == stdout)) && (fflush(stdout) != 0)) {
      status = EXIT_FAILURE;
    }
    return status;
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
    double dcm_supply_V;
    double thr_supply_V;
    canfdi_sim_scn_eval(&scn, t_us, &sp.speed_rad_s, &sp.angle_deg, &sp.load_Nm);
    canfdi_sim_scn_supply(&scn, t_us, &dcm_supply_V, &thr_supply_V);
    if (canfdi_sim_scn_run_error(&scn) != NULL) {
      fprintf(stderr, "canfdi-sim: %s\n", canfdi_sim_scn_run_error(&scn));
      status = EXIT_FAILURE;
      break;
    }
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
    canfdi_sim_set_supply(&sim, dcm_supply_V, thr_supply_V);
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
