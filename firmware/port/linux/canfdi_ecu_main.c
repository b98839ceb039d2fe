/*
 * canfdi_ecu_main.c — canfdi-ecu: the supervisor application
 * (firmware/app/canfdi_app.h) as a Linux process on a SocketCAN interface.
 *
 * This file and canfdi_socketcan.c are all the ECU knows about Linux: the
 * application is the same object code as in SIL and on the Cortex-M
 * targets; only the loop around it changes.
 *
 * Realtime (default). A step every 1 ms of CLOCK_MONOTONIC. Between steps
 * the loop waits in ppoll() on the socket until GUARD_US before the next
 * step and hands every frame to canfdi_app_rx_frame() with its arrival time
 * (monotonic µs since start, wrapping after 71 min like the app's time
 * base); then clock_nanosleep(TIMER_ABSTIME) to the step time, one more
 * non-blocking drain, and the step. Wake-up lateness (step start - step
 * time) goes into a histogram; a step that starts more than 1 ms late is a
 * deadline miss (canfdi_app_deadline_miss) and the periods missed are
 * skipped, not replayed. The step's execution time (canfdi_app_step + the
 * writes of its frames) and the cycle time (start to start) go to
 * canfdi_app_port_timing, so EcuStatus carries their maxima per 100 ms.
 * Timer slack is set to 1 ns (PR_SET_TIMERSLACK); nothing else (no
 * SCHED_FIFO, no mlockall): run it under `chrt -f 80` for better figures.
 *
 * Lockstep (--lockstep, the HIL contract): the plant paces the ECU. A
 * SimStep(k) frame (0x611) runs canfdi_app_step(now_us = k * 1000) and sends
 * its frames; every other frame goes to canfdi_app_rx_frame with now_us =
 * (last_k + 1) * 1000. k <= last_k: ignored, counted (stale_steps);
 * k > last_k + 1: counted (lockstep_gaps), then stepped. No timing reaches
 * the app, so the ECU's frames are bit-identical to SIL.
 *
 * Clock line (--clock IFACE, lockstep only): SimStep frames are also read
 * from a second socket on IFACE (filtered to 0x611). A rig that takes the
 * bus interface down, or a controller bus-off, keeps the ECU stepping
 * through that line, as a real ECU's own clock would (tests/hil/
 * test_busfault.py). Before each tick from the clock line every frame
 * waiting on the bus socket is handled, so a frame sent before the tick
 * is seen in the step it belongs to; a tick that arrived on both paths
 * runs once (the second is stale, counted).
 *
 * ECUReset (UDS 0x11 answered, canfdi_app_reset_requested after a step's
 * frames left): the application is powered down and up again with its
 * image (canfdi_ecu_nvm_restart), as a hard reset of the ECU would; the
 * process, its socket and its clock go on. Counted (ecu_resets).
 *
 * NVM (--nvm FILE): canfdi_ecu_nvm.h (loaded at start into a new
 * operation cycle, stored in the background while running and at a clean
 * exit). Statistics (--stats): canfdi_ecu_stats.h. Command line:
 * canfdi_ecu_cli.h. This file is the loop.
 *
 * Robustness: unknown identifiers and wrong lengths go to the app, whose
 * input supervision judges them (the kernel filter passes only the ids the
 * ECU consumes); a SimStep of the wrong length is counted and ignored;
 * socket errors are counted and reported; only errors with no successful
 * socket I/O for 5 s end the process (exit 1). ENETDOWN is not such an
 * error: the interface is down (`ip link set down`, a driver closing it
 * after bus-off), the socket stays bound and works again when it comes
 * up, so the loop goes on stepping and the input supervision names the
 * frames that stopped (U1A00/U1A01), as a controller off the bus would;
 * the first error of an outage and the return of good I/O are reported.
 *
 * Identifiers in the kernel filter: DcmSensor 0x010, ThrSensor 0x011,
 * SetpointDcm 0x100, SetpointThr 0x101, SimStep 0x611, and the UDS requests
 * 0x7DF/0x7E0, which reach the app's diagnostic server. A SimStep in realtime mode is ignored, counted
 * (simstep_ignored) and reported once: a lockstep plant needs --lockstep.
 *
 * Measured (build/bin/canfdi-ecu-rel, realtime, no plant, inside User-Mode
 * Linux via tools/vcan-run on the 2-core development machine shared with
 * other jobs, host load 1.4-2.3): step (canfdi_app_step + 2-4 writes)
 * p50 74-88 us, wake-up lateness p50 ~60 us; the tails are the sandbox's,
 * not the loop's: p99.9 4-8 ms and 3-7 % deadline misses over 10-30 s
 * (every system call of a UML process is a round trip through the host
 * scheduler). NVM store in the sandbox (hostfs, fdatasync): 1-2 ms.
 *
 * Sanitizers: build/bin/canfdi-ecu is the UBSan build (mk/ecu.mk says why
 * not ASan: ASan cannot run inside UML).
 *
 * Memory: the app instance (~9 kB) and two 10 001-bin histograms (80 kB)
 * are static; no heap except what libc and pthread do internally.
 */
#include <errno.h>
#include <inttypes.h>
#include <poll.h>
#include <signal.h>
#include <stdio.h>
#include <string.h>
#include <sys/prctl.h>
#include <time.h>

#include "app/canfdi_app.h"
#include "comm/gen/canfdi_msg.h"
#include "port/linux/canfdi_ecu_cli.h"
#include "port/linux/canfdi_ecu_nvm.h"
#include "port/linux/canfdi_ecu_stats.h"
#include "port/linux/canfdi_socketcan.h"

#define PROG CANFDI_ECU_PROG
#define STEP_NS INT64_C(1000000)
#define GUARD_NS INT64_C(100000)          /* ppoll until 100 us before the step */
#define DRAIN_MAX 64U                     /* frames per drain before the clock is checked */
#define SOCKET_FATAL_NS INT64_C(5000000000) /* errors without any good I/O for 5 s */
#define SOCKET_FATAL_ERRORS 100U
#define LOCKSTEP_TX_BUDGET_US 50000U      /* the sim waits for every actuator frame */

/* Identifiers the ECU consumes (the kernel filter). */
static const uint32_t rx_ids[] = {
    CANFDI_MSG_DCM_SENSOR_FRAME_ID,   CANFDI_MSG_THR_SENSOR_FRAME_ID,
    CANFDI_MSG_SETPOINT_DCM_FRAME_ID, CANFDI_MSG_SETPOINT_THR_FRAME_ID,
    CANFDI_MSG_SIM_STEP_FRAME_ID,     CANFDI_MSG_UDS_FUNC_REQ_FRAME_ID,
    CANFDI_MSG_UDS_PHYS_REQ_FRAME_ID,
};

typedef struct {
  canfdi_ecu_opts_t opt;
  canfdi_ecu_counts_t n;
  int64_t last_k; /* lockstep: the last step run, -1 before the first */
  /* socket health */
  int64_t last_ok_ns;
  uint32_t errors_since_ok;
  int last_errno;
  int64_t t0_ns;
} ecu_t;

static canfdi_app_t app;
static ecu_t ecu;
static canfdi_socketcan_t sock;
static canfdi_socketcan_t clock_sock; /* --clock: SimStep only; fd -1 without */
static canfdi_ecu_hist_t step_hist;
static canfdi_ecu_hist_t lat_hist;
static canfdi_ecu_nvm_t nvm;
static canfdi_app_cal_t cal;
static volatile sig_atomic_t stop_signal;

static void on_signal(int sig) { stop_signal = sig; }

static int64_t mono_ns(void)
{
  struct timespec ts;
  (void)clock_gettime(CLOCK_MONOTONIC, &ts);
  return ((int64_t)ts.tv_sec * INT64_C(1000000000)) + (int64_t)ts.tv_nsec;
}

static struct timespec ns_to_ts(int64_t ns)
{
  struct timespec ts;
  ts.tv_sec = (time_t)(ns / INT64_C(1000000000));
  ts.tv_nsec = (long)(ns % INT64_C(1000000000));
  return ts;
}

/* Monotonic us since start: the app's port clock (wraps like uint32_t;
 * the app keeps its uptime from the differences). */
static uint32_t app_us(int64_t t_ns) { return (uint32_t)((uint64_t)((t_ns - ecu.t0_ns) / 1000)); }

static uint32_t ns_to_us_u32(int64_t ns)
{
  const int64_t us = ns / 1000;
  return (us < 0) ? 0U : ((us > (int64_t)UINT32_MAX) ? UINT32_MAX : (uint32_t)us);
}

/* ------------------------------------------------------------ socket health */

static void sock_ok(int64_t now)
{
  if ((ecu.last_errno != 0) && !ecu.opt.quiet) {
    fprintf(stderr, PROG ": %s works again (%" PRIu64 " socket errors so far)\n", ecu.opt.iface,
            ecu.n.socket_errors);
  }
  ecu.last_ok_ns = now;
  ecu.errors_since_ok = 0U;
  ecu.last_errno = 0;
}

static void sock_error(int err)
{
  ecu.n.socket_errors++;
  if (err != ENETDOWN) { /* a down interface is a bus condition, never fatal */
    ecu.errors_since_ok = (ecu.errors_since_ok < UINT32_MAX) ? (ecu.errors_since_ok + 1U) : UINT32_MAX;
  }
  if ((ecu.last_errno != err) && !ecu.opt.quiet) {
    fprintf(stderr, PROG ": socket error on %s: %s (counted; going on)\n", ecu.opt.iface, strerror(err));
  }
  ecu.last_errno = err;
}

static bool sock_dead(int64_t now)
{
  return (ecu.errors_since_ok >= SOCKET_FATAL_ERRORS) && ((now - ecu.last_ok_ns) >= SOCKET_FATAL_NS);
}

/* ------------------------------------------------------------ frames */

static void send_frames(const canfdi_tx_frame_t *out, int32_t n)
{
  for (int32_t i = 0; i < n; i++) {
    const int rc = canfdi_socketcan_send(&sock, out[i].id, out[i].data, out[i].dlc);
    if (rc == 0) {
      sock_ok(mono_ns());
    } else if (rc != -ENOBUFS) {
      sock_error(-rc);
    } else {
      /* dropped after the retry budget: counted by the driver */
    }
  }
}

/* After a step's frames: an answered ECUReset restarts the application. */
static void maybe_reset(uint32_t now_us)
{
  if (canfdi_app_reset_requested(&app)) {
    ecu.n.ecu_resets++;
    if ((canfdi_ecu_nvm_restart(&nvm, &app, &cal, now_us, mono_ns()) == 0) && !ecu.opt.quiet) {
      fprintf(stderr, PROG ": ECU reset (UDS 0x11): application powered down and up\n");
    }
  }
}

static void lockstep_step(uint32_t k)
{
  canfdi_tx_frame_t out[CANFDI_APP_MAX_TX];
  const int64_t t = mono_ns();
  int32_t n;
  if ((ecu.last_k >= 0) && ((int64_t)k <= ecu.last_k)) {
    ecu.n.stale_steps++;
    return;
  }
  if ((int64_t)k > (ecu.last_k + 1)) {
    ecu.n.lockstep_gaps++;
  }
  n = canfdi_app_step(&app, (uint32_t)((uint64_t)k * 1000U), out);
  send_frames(out, n);
  maybe_reset((uint32_t)((uint64_t)k * 1000U));
  canfdi_ecu_hist_add(&step_hist, ns_to_us_u32(mono_ns() - t));
  ecu.n.steps++;
  ecu.last_k = (int64_t)k;
}

static void simstep_frame(const canfdi_socketcan_frame_t *f)
{
  struct canfdi_msg_sim_step_t m;
  if (f->dlc != CANFDI_MSG_SIM_STEP_LENGTH) {
    ecu.n.simstep_bad_length++;
  } else if (!ecu.opt.lockstep) {
    if ((ecu.n.simstep_ignored == 0U) && !ecu.opt.quiet) {
      fprintf(stderr, PROG ": SimStep frames on %s but this ECU runs in realtime mode "
                      "(ignored; start canfdi-ecu --lockstep for a lockstep plant)\n",
              ecu.opt.iface);
    }
    ecu.n.simstep_ignored++;
  } else if (canfdi_msg_sim_step_unpack(&m, f->data, f->dlc) == 0) {
    lockstep_step(m.sim_step_index);
  } else {
    ecu.n.simstep_bad_length++;
  }
}

/* One received frame: SimStep or the app. */
static void handle_frame(const canfdi_socketcan_frame_t *f, int64_t now)
{
  if (f->id == CANFDI_MSG_SIM_STEP_FRAME_ID) {
    simstep_frame(f);
  } else {
    const uint32_t now_us = ecu.opt.lockstep ? (uint32_t)((uint64_t)(ecu.last_k + 1) * 1000U) : app_us(now);
    (void)canfdi_app_rx_frame(&app, f->id, f->data, f->dlc, now_us);
    ecu.n.frames_to_app++;
  }
}

/* Read up to max frames (non-blocking). Returns the number read. */
static uint32_t drain(uint32_t max)
{
  uint32_t got = 0U;
  while (got < max) {
    canfdi_socketcan_frame_t f;
    const int rc = canfdi_socketcan_recv(&sock, &f);
    if (rc == 1) {
      const int64_t now = mono_ns();
      sock_ok(now);
      handle_frame(&f, now);
      got++;
    } else {
      if (rc < 0) {
        sock_error(-rc);
      }
      break;
    }
  }
  return got;
}

/* ------------------------------------------------------------ loops */

static bool duration_over(int64_t now)
{
  return (ecu.opt.duration_ns > 0) && ((now - ecu.t0_ns) >= ecu.opt.duration_ns);
}

/* Between steps: frames until GUARD_NS before the step, then the sleep to
 * the step time and one more drain. */
static void wait_for_step(struct pollfd *pfd, int64_t t_sched)
{
  int64_t now = mono_ns();
  while ((stop_signal == 0) && (now < (t_sched - GUARD_NS))) {
    const struct timespec ts = ns_to_ts(t_sched - GUARD_NS - now);
    if (ppoll(pfd, 1U, &ts, NULL) > 0) {
      (void)drain(DRAIN_MAX);
    }
    now = mono_ns();
  }
  if (stop_signal == 0) {
    const struct timespec ts = ns_to_ts(t_sched);
    int r;
    do {
      r = clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, NULL);
    } while ((r == EINTR) && (stop_signal == 0));
    (void)drain(DRAIN_MAX); /* what came in during the guard time */
  }
}

/* After a step: timing, NVM, the end conditions. Returns -1 to go on, else
 * the exit status. */
static int after_step(int64_t t_start, int64_t *prev_start)
{
  const int64_t t_end = mono_ns();
  const uint32_t step_us = ns_to_us_u32(t_end - t_start);
  const uint32_t cycle_us = (*prev_start != 0) ? ns_to_us_u32(t_start - *prev_start) : 0U;
  int rc = -1;
  canfdi_app_port_timing(&app, step_us, cycle_us);
  canfdi_ecu_hist_add(&step_hist, step_us);
  *prev_start = t_start;
  ecu.n.steps++;
  canfdi_ecu_nvm_maybe_store(&nvm, &app, t_end);
  if (duration_over(t_end)) {
    rc = 0;
  } else if (sock_dead(t_end)) {
    fprintf(stderr, PROG ": %s failing for 5 s with no good I/O (last error: %s)\n", ecu.opt.iface,
            strerror(ecu.last_errno));
    rc = 1;
  } else {
    /* go on */
  }
  return rc;
}

static int run_realtime(void)
{
  struct pollfd pfd;
  int64_t t_sched = ecu.t0_ns + STEP_NS;
  int64_t prev_start = 0;
  int rc = -1;
  pfd.fd = sock.fd;
  pfd.events = POLLIN;
  (void)prctl(PR_SET_TIMERSLACK, 1UL, 0UL, 0UL, 0UL);
  while ((stop_signal == 0) && (rc < 0)) {
    canfdi_tx_frame_t out[CANFDI_APP_MAX_TX];
    int64_t t_start;
    int64_t late;
    wait_for_step(&pfd, t_sched);
    if (stop_signal != 0) {
      break;
    }
    t_start = mono_ns();
    late = t_start - t_sched;
    canfdi_ecu_hist_add(&lat_hist, ns_to_us_u32(late));
    if (late > STEP_NS) {
      const int64_t missed = late / STEP_NS;
      canfdi_app_deadline_miss(&app);
      ecu.n.deadline_misses++;
      ecu.n.skipped_periods += (uint64_t)missed;
      t_sched += missed * STEP_NS;
    }
    send_frames(out, canfdi_app_step(&app, app_us(t_start), out));
    maybe_reset(app_us(t_start));
    t_sched += STEP_NS;
    rc = after_step(t_start, &prev_start);
  }
  return (rc < 0) ? 0 : rc;
}

/* --clock: the ticks waiting on the clock line, each after the bus's
 * frames that arrived before it. */
static void drain_clock(void)
{
  canfdi_socketcan_frame_t f;
  int rc;
  do {
    (void)drain(UINT32_MAX);
    rc = canfdi_socketcan_recv(&clock_sock, &f);
    if (rc == 1) {
      sock_ok(mono_ns());
      if (f.id == CANFDI_MSG_SIM_STEP_FRAME_ID) {
        simstep_frame(&f);
      }
    } else if (rc < 0) {
      sock_error(-rc);
    } else {
      /* nothing more */
    }
  } while ((rc == 1) && (stop_signal == 0));
}

static int run_lockstep(void)
{
  struct pollfd pfd[2];
  const nfds_t nfd = (clock_sock.fd >= 0) ? 2U : 1U;
  int rc = -1;
  pfd[0].fd = sock.fd;
  pfd[0].events = POLLIN;
  pfd[1].fd = clock_sock.fd;
  pfd[1].events = POLLIN;
  sock.tx_budget_us = LOCKSTEP_TX_BUDGET_US;
  while ((stop_signal == 0) && (rc < 0)) {
    const int r = poll(pfd, nfd, 100);
    int64_t now;
    if (r > 0) {
      (void)drain(UINT32_MAX);
      if (nfd == 2U) {
        drain_clock();
      }
    }
    now = mono_ns();
    canfdi_ecu_nvm_maybe_store(&nvm, &app, now);
    if (duration_over(now)) {
      rc = 0;
    } else if (sock_dead(now)) {
      fprintf(stderr, PROG ": %s failing for 5 s with no good I/O (last error: %s)\n", ecu.opt.iface,
              strerror(ecu.last_errno));
      rc = 1;
    } else {
      /* go on */
    }
  }
  return (rc < 0) ? 0 : rc;
}

/* ------------------------------------------------------------ main */

static void install_signals(void)
{
  struct sigaction sa;
  memset(&sa, 0, sizeof sa);
  sa.sa_handler = on_signal;
  (void)sigemptyset(&sa.sa_mask);
  sa.sa_flags = 0; /* no SA_RESTART: ppoll/poll return at once */
  (void)sigaction(SIGINT, &sa, NULL);
  (void)sigaction(SIGTERM, &sa, NULL);
}

/* The application with its DTC memory (from NVM when asked). Returns 0 or 1. */
static int power_up(void)
{
  int rc = 0;
  canfdi_app_default_cal(&cal);
  if (ecu.opt.nvm_path != NULL) {
    rc = canfdi_ecu_nvm_start(&nvm, ecu.opt.nvm_path, ecu.opt.quiet, &app, &cal, mono_ns());
  } else if (canfdi_app_init(&app, &cal, 0U) != CANFDI_OK) {
    fprintf(stderr, PROG ": the application refused its calibration\n");
    rc = 1;
  } else {
    /* running without NVM */
  }
  return rc;
}

static void summary(void)
{
  const canfdi_app_diag_t *d = canfdi_app_diag(&app);
  fprintf(stderr,
          PROG ": %" PRIu64 " steps, %" PRIu64 " deadline misses, frames rx %" PRIu32 " tx %" PRIu32
               " (dropped %" PRIu32 "), rejected %" PRIu32 ", unknown %" PRIu32
               ", step p99.9 %" PRIu32 " us, latency p99.9 %" PRIu32 " us\n",
          ecu.n.steps, ecu.n.deadline_misses, sock.diag.rx_frames, sock.diag.tx_frames,
          sock.diag.tx_drops, d->frames_rejected, d->frames_unknown,
          canfdi_ecu_hist_pct(&step_hist, 9990U), canfdi_ecu_hist_pct(&lat_hist, 9990U));
}

int main(int argc, char **argv)
{
  int rc;
  int rc_nvm;
  int64_t t_end;
  rc = canfdi_ecu_parse_args(argc, argv, &ecu.opt);
  if (rc != CANFDI_ECU_ARGS_RUN) {
    return (rc == CANFDI_ECU_ARGS_HELP) ? 0 : 2;
  }
  ecu.last_k = -1;
  install_signals();
  if (power_up() != 0) {
    return 1;
  }
  rc = canfdi_socketcan_open(&sock, ecu.opt.iface, rx_ids, (uint32_t)(sizeof rx_ids / sizeof rx_ids[0]));
  if (rc != 0) {
    if (rc == -EAFNOSUPPORT) {
      fprintf(stderr, PROG ": this kernel has no SocketCAN (PF_CAN); run it under tools/vcan-run\n");
    } else {
      fprintf(stderr, PROG ": cannot open CAN interface %s: %s\n", ecu.opt.iface, strerror(-rc));
    }
    (void)canfdi_ecu_nvm_finish(&nvm, &app, false);
    return 1;
  }
  clock_sock.fd = -1;
  if (ecu.opt.clock_iface != NULL) {
    static const uint32_t clock_ids[] = {CANFDI_MSG_SIM_STEP_FRAME_ID};
    rc = canfdi_socketcan_open(&clock_sock, ecu.opt.clock_iface, clock_ids, 1U);
    if (rc != 0) {
      fprintf(stderr, PROG ": cannot open the clock line %s: %s\n", ecu.opt.clock_iface, strerror(-rc));
      canfdi_socketcan_close(&sock);
      (void)canfdi_ecu_nvm_finish(&nvm, &app, false);
      return 1;
    }
  }
  /* time starts now: step 1 is 1 ms after the ready line */
  ecu.t0_ns = mono_ns();
  ecu.last_ok_ns = ecu.t0_ns;
  fprintf(stderr, PROG ": ready on %s (%s)\n", ecu.opt.iface, ecu.opt.lockstep ? "lockstep" : "realtime");
  (void)fflush(stderr);

  rc = ecu.opt.lockstep ? run_lockstep() : run_realtime();
  t_end = mono_ns();

  rc_nvm = canfdi_ecu_nvm_finish(&nvm, &app, true);
  if (ecu.opt.stats_path != NULL) {
    canfdi_ecu_report_t r;
    r.opts = &ecu.opt;
    r.run_ns = t_end - ecu.t0_ns;
    r.counts = &ecu.n;
    r.sock = &sock.diag;
    r.app = canfdi_app_diag(&app);
    r.nvm = canfdi_ecu_nvm_stats(&nvm);
    r.step = &step_hist;
    r.latency = &lat_hist;
    rc = (canfdi_ecu_write_stats(ecu.opt.stats_path, &r) != 0) ? 1 : rc;
  }
  if (!ecu.opt.quiet) {
    summary();
  }
  canfdi_socketcan_close(&clock_sock);
  canfdi_socketcan_close(&sock);
  return (rc != 0) ? rc : rc_nvm;
}
