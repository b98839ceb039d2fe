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
 * NVM (--nvm FILE): the DTC memory in a two-bank file (canfdi_nvm_file +
 * canfdi_nvm). Loaded at start (the image replaces the fresh memory and a
 * new operation cycle starts), stored at a clean exit after
 * canfdi_dtc_cycle_end, and in between at most every NVM_PERIOD_S seconds
 * when dtc.changes moved. The periodic store runs in a background thread
 * (the loop only serialises the image, ~2k instructions, and hands it
 * over), because a store costs one erase and four writes of the bank file,
 * each followed by fdatasync: milliseconds on a disk (the stats report the
 * largest, nvm.store_us_max), which must not stall the 1 ms loop. A
 * periodic image is taken mid-cycle: after a crash the next start loads it
 * and starts a new cycle without ending the interrupted one (no healing
 * step for it, as after a power cut on a real ECU).
 *
 * Robustness: unknown identifiers and wrong lengths go to the app, whose
 * input supervision judges them (the kernel filter passes only the ids the
 * ECU consumes); a SimStep of the wrong length is counted and ignored;
 * socket errors are counted and reported; only errors with no successful
 * socket I/O for 5 s end the process (exit 1).
 *
 * Identifiers in the kernel filter: DcmSensor 0x010, ThrSensor 0x011,
 * SetpointDcm 0x100, SetpointThr 0x101, SimStep 0x611, and the UDS requests
 * 0x7DF/0x7E0, which reach the app (no diagnostic server yet: counted as
 * unknown, SdgFramesUnknown). A SimStep in realtime mode is ignored, counted
 * (simstep_ignored) and reported once: a lockstep plant needs --lockstep.
 *
 * --stats JSON: steps, deadline_misses, skipped_periods, lockstep_gaps,
 * stale_steps, simstep_bad_length, simstep_ignored, frames_rx, frames_tx,
 * frames_to_app, frames_rejected and frames_unknown (the app's input
 * supervision), tx_drops, tx_retries, rx_kernel_drops, socket_errors,
 * nvm {stores, failures, store_us_max}, step_us and latency_us {p50, p99,
 * p999, max, n} (nearest-rank percentiles from 1 us histograms up to
 * 10 ms; beyond, the max). latency_us is realtime only (zeros in lockstep).
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
#include <getopt.h>
#include <inttypes.h>
#include <poll.h>
#include <pthread.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/prctl.h>
#include <time.h>
#include <unistd.h>

#include "app/canfdi_app.h"
#include "comm/gen/canfdi_msg.h"
#include "diag/canfdi_dtc.h"
#include "diag/canfdi_nvm.h"
#include "port/linux/canfdi_nvm_file.h"
#include "port/linux/canfdi_socketcan.h"

#define PROG "canfdi-ecu"
#define STEP_NS INT64_C(1000000)
#define GUARD_NS INT64_C(100000)          /* ppoll until 100 us before the step */
#define DRAIN_MAX 64U                     /* frames per drain before the clock is checked */
#define SOCKET_FATAL_NS INT64_C(5000000000) /* errors without any good I/O for 5 s */
#define SOCKET_FATAL_ERRORS 100U
#define NVM_PERIOD_S 10
#define NVM_BANK_BYTES 1024U
#define LOCKSTEP_TX_BUDGET_US 50000U      /* the sim waits for every actuator frame */
#define HIST_BINS 10000U                  /* 1 us bins; larger values in one overflow bin */

CANFDI_STATIC_ASSERT(CANFDI_NVM_FOOTPRINT(CANFDI_DTC_IMAGE_MAX_BYTES, 1U) <= NVM_BANK_BYTES,
                     ecu_nvm_bank_holds_the_dtc_image);

/* Identifiers the ECU consumes (the kernel filter). */
static const uint32_t rx_ids[] = {
    CANFDI_MSG_DCM_SENSOR_FRAME_ID,   CANFDI_MSG_THR_SENSOR_FRAME_ID,
    CANFDI_MSG_SETPOINT_DCM_FRAME_ID, CANFDI_MSG_SETPOINT_THR_FRAME_ID,
    CANFDI_MSG_SIM_STEP_FRAME_ID,     CANFDI_MSG_UDS_FUNC_REQ_FRAME_ID,
    CANFDI_MSG_UDS_PHYS_REQ_FRAME_ID,
};

/* ------------------------------------------------------------ histogram */

typedef struct {
  uint32_t bin[HIST_BINS + 1U];
  uint64_t n;
  uint32_t max;
} hist_t;

static void hist_add(hist_t *h, uint32_t v)
{
  h->bin[(v < HIST_BINS) ? v : HIST_BINS]++;
  h->n++;
  h->max = (v > h->max) ? v : h->max;
}

/* The smallest value v with at least ceil(n * p / 10000) samples <= v
 * (nearest-rank percentile; p in 1/10000). Values beyond the bins: max. */
static uint32_t hist_pct(const hist_t *h, uint32_t p)
{
  uint64_t rank = (h->n * p + 9999U) / 10000U;
  uint64_t cum = 0U;
  uint32_t v;
  if (h->n == 0U) {
    return 0U;
  }
  rank = (rank == 0U) ? 1U : rank;
  for (v = 0U; v < HIST_BINS; v++) {
    cum += h->bin[v];
    if (cum >= rank) {
      return v;
    }
  }
  return h->max;
}

/* ------------------------------------------------------------ state */

typedef struct {
  /* options */
  const char *iface;
  const char *nvm_path;
  const char *stats_path;
  int64_t duration_ns; /* 0: until signalled */
  bool lockstep;
  bool quiet;
  /* counters */
  uint64_t steps;
  uint64_t deadline_misses;
  uint64_t skipped_periods;
  uint64_t lockstep_gaps;
  uint64_t stale_steps;
  uint64_t simstep_bad_length;
  uint64_t simstep_ignored; /* SimStep frames in realtime mode */
  uint64_t socket_errors;
  uint64_t frames_to_app;
  int64_t last_k;
  /* socket health */
  int64_t last_ok_ns;
  uint32_t errors_since_ok;
  int last_errno;
  int64_t t0_ns;
} ecu_t;

typedef struct {
  pthread_t thread;
  pthread_mutex_t mu;
  pthread_cond_t cv;
  bool running;
  bool pending;
  bool quit;
  uint8_t img[CANFDI_DTC_IMAGE_MAX_BYTES];
  uint32_t len;
  canfdi_nvm_file_t file;
  canfdi_nvm_t nvm;
  canfdi_nvm_port_t port;
  /* under mu */
  uint32_t stores;
  uint32_t failures;
  uint32_t store_us_max;
  int32_t last_rc;
} nvm_bg_t;

static canfdi_app_t app;
static ecu_t ecu;
static canfdi_socketcan_t sock;
static hist_t step_hist;
static hist_t lat_hist;
static nvm_bg_t nvmbg;
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

/* Monotonic us since start, the app's time base (wraps like uint32_t). */
static uint32_t app_us(int64_t t_ns) { return (uint32_t)((uint64_t)((t_ns - ecu.t0_ns) / 1000)); }

static uint32_t ns_to_us_u32(int64_t ns)
{
  const int64_t us = ns / 1000;
  return (us < 0) ? 0U : ((us > (int64_t)UINT32_MAX) ? UINT32_MAX : (uint32_t)us);
}

static void info(const char *msg)
{
  if (!ecu.quiet) {
    fprintf(stderr, PROG ": %s\n", msg);
  }
}

/* ------------------------------------------------------------ socket health */

static void sock_ok(int64_t now)
{
  ecu.last_ok_ns = now;
  ecu.errors_since_ok = 0U;
}

static void sock_error(int err)
{
  ecu.socket_errors++;
  ecu.errors_since_ok = (ecu.errors_since_ok < UINT32_MAX) ? (ecu.errors_since_ok + 1U) : UINT32_MAX;
  if ((ecu.last_errno != err) && !ecu.quiet) {
    fprintf(stderr, PROG ": socket error on %s: %s (counted; going on)\n", ecu.iface,
            strerror(err));
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

static void lockstep_step(uint32_t k)
{
  canfdi_tx_frame_t out[CANFDI_APP_MAX_TX];
  const int64_t t = mono_ns();
  int32_t n;
  if ((ecu.last_k >= 0) && ((int64_t)k <= ecu.last_k)) {
    ecu.stale_steps++;
    return;
  }
  if ((int64_t)k > (ecu.last_k + 1)) {
    ecu.lockstep_gaps++;
  }
  n = canfdi_app_step(&app, (uint32_t)((uint64_t)k * 1000U), out);
  send_frames(out, n);
  hist_add(&step_hist, ns_to_us_u32(mono_ns() - t));
  ecu.steps++;
  ecu.last_k = (int64_t)k;
}

/* One received frame: SimStep or the app. */
static void handle_frame(const canfdi_socketcan_frame_t *f, int64_t now)
{
  if (f->id == CANFDI_MSG_SIM_STEP_FRAME_ID) {
    if (f->dlc != CANFDI_MSG_SIM_STEP_LENGTH) {
      ecu.simstep_bad_length++;
    } else if (ecu.lockstep) {
      struct canfdi_msg_sim_step_t m;
      if (canfdi_msg_sim_step_unpack(&m, f->data, f->dlc) == 0) {
        lockstep_step(m.sim_step_index);
      } else {
        ecu.simstep_bad_length++;
      }
    } else {
      if ((ecu.simstep_ignored == 0U) && !ecu.quiet) {
        fprintf(stderr, PROG ": SimStep frames on %s but this ECU runs in realtime mode "
                        "(ignored; start canfdi-ecu --lockstep for a lockstep plant)\n",
                ecu.iface);
      }
      ecu.simstep_ignored++;
    }
  } else {
    const uint32_t now_us =
        ecu.lockstep ? (uint32_t)((uint64_t)(ecu.last_k + 1) * 1000U) : app_us(now);
    (void)canfdi_app_rx_frame(&app, f->id, f->data, f->dlc, now_us);
    ecu.frames_to_app++;
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

/* ------------------------------------------------------------ NVM */

static void *nvm_thread(void *arg)
{
  static uint8_t local[CANFDI_DTC_IMAGE_MAX_BYTES];
  (void)arg;
  (void)pthread_mutex_lock(&nvmbg.mu);
  for (;;) {
    uint32_t len;
    int64_t t;
    int32_t rc;
    uint32_t us;
    while (!nvmbg.pending && !nvmbg.quit) {
      (void)pthread_cond_wait(&nvmbg.cv, &nvmbg.mu);
    }
    if (!nvmbg.pending) {
      break;
    }
    len = nvmbg.len;
    memcpy(local, nvmbg.img, len);
    nvmbg.pending = false;
    (void)pthread_mutex_unlock(&nvmbg.mu);
    t = mono_ns();
    rc = canfdi_nvm_store(&nvmbg.nvm, local, len);
    us = ns_to_us_u32(mono_ns() - t);
    (void)pthread_mutex_lock(&nvmbg.mu);
    nvmbg.last_rc = rc;
    if (rc == CANFDI_OK) {
      nvmbg.stores++;
    } else {
      nvmbg.failures++;
    }
    nvmbg.store_us_max = (us > nvmbg.store_us_max) ? us : nvmbg.store_us_max;
  }
  (void)pthread_mutex_unlock(&nvmbg.mu);
  return NULL;
}

/* Open the file, load the image into the app's DTC memory, start the
 * background store. Returns 0 or 1 (message printed). */
static int nvm_start(void)
{
  static uint8_t buf[CANFDI_DTC_IMAGE_MAX_BYTES];
  canfdi_dtc_t *dtc = canfdi_app_dtc(&app);
  int32_t rc = canfdi_nvm_file_open(&nvmbg.file, ecu.nvm_path, NVM_BANK_BYTES,
                                    CANFDI_NVM_FILE_CREATE);
  int32_t n;
  if (rc != CANFDI_OK) {
    fprintf(stderr, PROG ": cannot open NVM file %s: %s\n", ecu.nvm_path,
            (rc == -CANFDI_ERANGE) ? "wrong size (another geometry or truncated; not touched)"
                                   : strerror((nvmbg.file.last_errno != 0) ? nvmbg.file.last_errno : EIO));
    return 1;
  }
  nvmbg.port = nvmbg.file.port;
  if (canfdi_nvm_init(&nvmbg.nvm, &nvmbg.port) != CANFDI_OK) {
    fprintf(stderr, PROG ": NVM file %s: bad geometry\n", ecu.nvm_path);
    return 1;
  }
  n = canfdi_nvm_load(&nvmbg.nvm, buf, sizeof buf);
  if (n >= 0) {
    /* the fresh memory's cycle had no report: ending it changes nothing */
    (void)canfdi_dtc_cycle_end(dtc);
    rc = canfdi_dtc_deserialize(dtc, buf, (uint32_t)n);
    (void)canfdi_dtc_cycle_start(dtc);
    if (rc != CANFDI_OK) {
      fprintf(stderr, PROG ": NVM file %s: DTC image rejected (%d); starting cleared\n",
              ecu.nvm_path, (int)rc);
    } else if (!ecu.quiet) {
      fprintf(stderr, PROG ": NVM %s: loaded %d-byte DTC image (seq %" PRIu32 "), %u DTC(s) stored\n",
              ecu.nvm_path, (int)n, nvmbg.nvm.seq,
              (unsigned)canfdi_dtc_count_by_mask(dtc, (uint8_t)CANFDI_DTC_ST_TFSLC));
    }
  } else if ((nvmbg.nvm.bank_state[0] == (uint8_t)CANFDI_NVM_BANK_EMPTY) &&
             (nvmbg.nvm.bank_state[1] == (uint8_t)CANFDI_NVM_BANK_EMPTY)) {
    info("NVM empty (new device)");
  } else {
    fprintf(stderr, PROG ": NVM file %s: no valid image (bank states %u/%u); starting cleared\n",
            ecu.nvm_path, (unsigned)nvmbg.nvm.bank_state[0], (unsigned)nvmbg.nvm.bank_state[1]);
  }
  (void)pthread_mutex_init(&nvmbg.mu, NULL);
  (void)pthread_cond_init(&nvmbg.cv, NULL);
  if (pthread_create(&nvmbg.thread, NULL, nvm_thread, NULL) != 0) {
    fprintf(stderr, PROG ": cannot start the NVM thread\n");
    return 1;
  }
  nvmbg.running = true;
  return 0;
}

/* Outside the step: hand a new image to the thread when due. Cost: one
 * serialisation (~2k instructions) and a memcpy under the mutex. */
static void nvm_maybe_store(int64_t now)
{
  static int64_t last_ns;
  static uint32_t changes_stored;
  static bool first = true;
  const canfdi_dtc_t *dtc = canfdi_app_dtc(&app);
  if (!nvmbg.running) {
    return;
  }
  if (first) {
    first = false;
    last_ns = now;
    changes_stored = dtc->changes;
  }
  if (((now - last_ns) >= ((int64_t)NVM_PERIOD_S * INT64_C(1000000000))) &&
      (dtc->changes != changes_stored)) {
    (void)pthread_mutex_lock(&nvmbg.mu);
    {
      const int32_t n = canfdi_dtc_serialize(dtc, nvmbg.img, sizeof nvmbg.img);
      if (n >= 0) {
        nvmbg.len = (uint32_t)n;
        nvmbg.pending = true;
        (void)pthread_cond_signal(&nvmbg.cv);
      }
    }
    (void)pthread_mutex_unlock(&nvmbg.mu);
    changes_stored = dtc->changes;
    last_ns = now;
  }
}

/* Stop the thread; on a clean exit (store) end the cycle and store.
 * Returns 0 or 1. */
static int nvm_finish(bool store)
{
  static uint8_t buf[CANFDI_DTC_IMAGE_MAX_BYTES];
  canfdi_dtc_t *dtc = canfdi_app_dtc(&app);
  int32_t n;
  int32_t rc;
  int64_t t;
  if (!nvmbg.running) {
    return 0;
  }
  (void)pthread_mutex_lock(&nvmbg.mu);
  nvmbg.quit = true;
  (void)pthread_cond_signal(&nvmbg.cv);
  (void)pthread_mutex_unlock(&nvmbg.mu);
  (void)pthread_join(nvmbg.thread, NULL);
  nvmbg.running = false;
  if (!store) {
    canfdi_nvm_file_close(&nvmbg.file);
    return 0;
  }
  (void)canfdi_dtc_cycle_end(dtc);
  n = canfdi_dtc_serialize(dtc, buf, sizeof buf);
  t = mono_ns();
  rc = (n >= 0) ? canfdi_nvm_store(&nvmbg.nvm, buf, (uint32_t)n) : n;
  {
    const uint32_t us = ns_to_us_u32(mono_ns() - t);
    nvmbg.store_us_max = (us > nvmbg.store_us_max) ? us : nvmbg.store_us_max;
  }
  canfdi_nvm_file_close(&nvmbg.file);
  if (rc != CANFDI_OK) {
    nvmbg.failures++;
    fprintf(stderr, PROG ": storing the DTC memory in %s failed (%d)\n", ecu.nvm_path, (int)rc);
    return 1;
  }
  nvmbg.stores++;
  return 0;
}

/* ------------------------------------------------------------ loops */

static bool duration_over(int64_t now)
{
  return (ecu.duration_ns > 0) && ((now - ecu.t0_ns) >= ecu.duration_ns);
}

static int run_realtime(void)
{
  struct pollfd pfd;
  int64_t t_sched = ecu.t0_ns + STEP_NS;
  int64_t prev_start = 0;
  pfd.fd = sock.fd;
  pfd.events = POLLIN;
  (void)prctl(PR_SET_TIMERSLACK, 1UL, 0UL, 0UL, 0UL);
  while (stop_signal == 0) {
    canfdi_tx_frame_t out[CANFDI_APP_MAX_TX];
    int64_t now = mono_ns();
    int64_t t_start;
    int64_t late;
    int32_t n;
    /* frames until shortly before the step */
    while ((stop_signal == 0) && (now < (t_sched - GUARD_NS))) {
      const struct timespec ts = ns_to_ts(t_sched - GUARD_NS - now);
      const int r = ppoll(&pfd, 1U, &ts, NULL);
      if (r > 0) {
        (void)drain(DRAIN_MAX);
      }
      now = mono_ns();
    }
    if (stop_signal != 0) {
      break;
    }
    {
      const struct timespec ts = ns_to_ts(t_sched);
      int r;
      do {
        r = clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, NULL);
      } while ((r == EINTR) && (stop_signal == 0));
    }
    (void)drain(DRAIN_MAX); /* what came in during the guard time */
    t_start = mono_ns();
    late = t_start - t_sched;
    hist_add(&lat_hist, ns_to_us_u32(late));
    if (late > STEP_NS) {
      const int64_t missed = late / STEP_NS;
      canfdi_app_deadline_miss(&app);
      ecu.deadline_misses++;
      ecu.skipped_periods += (uint64_t)missed;
      t_sched += missed * STEP_NS;
    }
    n = canfdi_app_step(&app, app_us(t_start), out);
    send_frames(out, n);
    {
      const int64_t t_end = mono_ns();
      const uint32_t step_us = ns_to_us_u32(t_end - t_start);
      const uint32_t cycle_us = (prev_start != 0) ? ns_to_us_u32(t_start - prev_start) : 0U;
      canfdi_app_port_timing(&app, step_us, cycle_us);
      hist_add(&step_hist, step_us);
      prev_start = t_start;
      ecu.steps++;
      t_sched += STEP_NS;
      nvm_maybe_store(t_end);
      if (duration_over(t_end)) {
        break;
      }
      if (sock_dead(t_end)) {
        fprintf(stderr, PROG ": %s failing for 5 s with no good I/O (last error: %s)\n",
                ecu.iface, strerror(ecu.last_errno));
        return 1;
      }
    }
  }
  return 0;
}

static int run_lockstep(void)
{
  struct pollfd pfd;
  pfd.fd = sock.fd;
  pfd.events = POLLIN;
  sock.tx_budget_us = LOCKSTEP_TX_BUDGET_US;
  while (stop_signal == 0) {
    const int r = poll(&pfd, 1U, 100);
    int64_t now;
    if (r > 0) {
      (void)drain(UINT32_MAX);
    }
    now = mono_ns();
    nvm_maybe_store(now);
    if (duration_over(now)) {
      break;
    }
    if (sock_dead(now)) {
      fprintf(stderr, PROG ": %s failing for 5 s with no good I/O (last error: %s)\n", ecu.iface,
              strerror(ecu.last_errno));
      return 1;
    }
  }
  return 0;
}

/* ------------------------------------------------------------ stats */

static void json_hist(FILE *f, const char *name, const hist_t *h, const char *tail)
{
  fprintf(f, "  \"%s\": {\"p50\": %" PRIu32 ", \"p99\": %" PRIu32 ", \"p999\": %" PRIu32
             ", \"max\": %" PRIu32 ", \"n\": %" PRIu64 "}%s\n",
          name, hist_pct(h, 5000U), hist_pct(h, 9900U), hist_pct(h, 9990U), h->max, h->n, tail);
}

static int write_stats(int64_t run_ns)
{
  const canfdi_app_diag_t *d = canfdi_app_diag(&app);
  FILE *f = fopen(ecu.stats_path, "w");
  if (f == NULL) {
    fprintf(stderr, PROG ": cannot write %s: %s\n", ecu.stats_path, strerror(errno));
    return 1;
  }
  fprintf(f, "{\n");
  fprintf(f, "  \"mode\": \"%s\",\n", ecu.lockstep ? "lockstep" : "realtime");
  fprintf(f, "  \"iface\": \"%s\",\n", ecu.iface);
  fprintf(f, "  \"run_s\": %" PRId64 ".%03" PRId64 ",\n", run_ns / 1000000000, (run_ns / 1000000) % 1000);
  fprintf(f, "  \"steps\": %" PRIu64 ",\n", ecu.steps);
  fprintf(f, "  \"deadline_misses\": %" PRIu64 ",\n", ecu.deadline_misses);
  fprintf(f, "  \"skipped_periods\": %" PRIu64 ",\n", ecu.skipped_periods);
  fprintf(f, "  \"lockstep_gaps\": %" PRIu64 ",\n", ecu.lockstep_gaps);
  fprintf(f, "  \"stale_steps\": %" PRIu64 ",\n", ecu.stale_steps);
  fprintf(f, "  \"simstep_bad_length\": %" PRIu64 ",\n", ecu.simstep_bad_length);
  fprintf(f, "  \"simstep_ignored\": %" PRIu64 ",\n", ecu.simstep_ignored);
  fprintf(f, "  \"frames_rx\": %" PRIu32 ",\n", sock.diag.rx_frames);
  fprintf(f, "  \"frames_tx\": %" PRIu32 ",\n", sock.diag.tx_frames);
  fprintf(f, "  \"frames_to_app\": %" PRIu64 ",\n", ecu.frames_to_app);
  fprintf(f, "  \"frames_rejected\": %" PRIu32 ",\n", d->frames_rejected);
  fprintf(f, "  \"frames_unknown\": %" PRIu32 ",\n", d->frames_unknown);
  fprintf(f, "  \"tx_drops\": %" PRIu32 ",\n", sock.diag.tx_drops);
  fprintf(f, "  \"tx_retries\": %" PRIu32 ",\n", sock.diag.tx_retries);
  fprintf(f, "  \"rx_kernel_drops\": %" PRIu32 ",\n", sock.diag.rx_kernel_drops);
  fprintf(f, "  \"socket_errors\": %" PRIu64 ",\n", ecu.socket_errors);
  fprintf(f, "  \"nvm\": {\"stores\": %" PRIu32 ", \"failures\": %" PRIu32
             ", \"store_us_max\": %" PRIu32 "},\n",
          nvmbg.stores, nvmbg.failures, nvmbg.store_us_max);
  json_hist(f, "step_us", &step_hist, ",");
  /* wake-up lateness: realtime only (zeros in lockstep) */
  json_hist(f, "latency_us", &lat_hist, "");
  fprintf(f, "}\n");
  if (fclose(f) != 0) {
    fprintf(stderr, PROG ": cannot write %s: %s\n", ecu.stats_path, strerror(errno));
    return 1;
  }
  return 0;
}

/* ------------------------------------------------------------ CLI */

static void usage(FILE *f)
{
  fprintf(f,
          "usage: " PROG " [-c IFACE] [--lockstep] [--nvm FILE] [--duration S]\n"
          "                  [--stats FILE.json] [-q]\n"
          "\n"
          "The canfdi supervisor (firmware/app) as a Linux process on SocketCAN.\n"
          "\n"
          "options:\n"
          "  -c, --channel IFACE  CAN interface (default: $CAN_CHANNEL, else vcan0)\n"
          "  --lockstep           step on SimStep frames (0x611) of canfdi-sim --lockstep;\n"
          "                       the ECU's frames are then bit-identical to SIL\n"
          "  --realtime           a step every 1 ms of CLOCK_MONOTONIC (the default)\n"
          "  --nvm FILE           keep the DTC memory in FILE (created if missing): loaded\n"
          "                       at start, stored at exit and every 10 s when changed\n"
          "  --duration S         stop after S seconds (default: run until SIGINT/SIGTERM)\n"
          "  --stats FILE.json    write run statistics at exit (steps, deadline misses,\n"
          "                       frames, step time and wake-up latency percentiles)\n"
          "  -q, --quiet          only the ready line and errors on stderr\n"
          "  -h, --help           this text\n"
          "\n"
          "Prints '" PROG ": ready on IFACE (lockstep|realtime)' on stderr once the\n"
          "socket is bound. SIGINT/SIGTERM: finish the step, store NVM, write stats,\n"
          "exit 0. Exit 1: runtime failure (no interface, NVM file unusable, socket\n"
          "failing for 5 s); 2: bad usage.\n"
          "\n"
          "examples:\n"
          "  " PROG " -c vcan0                       realtime, until Ctrl-C\n"
          "  " PROG " --lockstep & canfdi-sim --can vcan0 --lockstep -s SCN\n"
          "  " PROG " --nvm /tmp/ecu.nvm --duration 60 --stats /tmp/ecu.json\n"
          "  tools/vcan-run " PROG " --duration 2 -q     where the kernel lacks vcan\n"
          "  chrt -f 80 build/bin/canfdi-ecu-rel --stats rt.json   timing figures\n");
}

/* Seconds, decimal without exponent (e.g. 2, 0.5, 60; at most 9 fraction
 * digits), parsed in integers: firmware/ holds no floating point, not even
 * in a port. Returns false when not a number in (0, 10^7]. */
static bool parse_seconds(const char *s, int64_t *ns)
{
  int64_t whole = 0;
  int64_t frac = 0;
  int64_t scale = 100000000;
  const char *p = s;
  bool digits = false;
  while ((*p >= '0') && (*p <= '9')) {
    whole = (whole * 10) + (int64_t)(*p - '0');
    digits = true;
    if (whole > 10000000) {
      return false;
    }
    p++;
  }
  if (*p == '.') {
    p++;
    while ((*p >= '0') && (*p <= '9')) {
      if (scale == 0) {
        return false;
      }
      frac += (int64_t)(*p - '0') * scale;
      scale /= 10;
      digits = true;
      p++;
    }
  }
  *ns = (whole * 1000000000) + frac;
  return digits && (*p == '\0') && (*ns > 0) && (*ns <= (int64_t)10000000 * 1000000000);
}

int main(int argc, char **argv)
{
  enum { OPT_LOCKSTEP = 256, OPT_REALTIME, OPT_NVM, OPT_DURATION, OPT_STATS };
  static const struct option opts[] = {
      {"channel", required_argument, NULL, 'c'},
      {"lockstep", no_argument, NULL, OPT_LOCKSTEP},
      {"realtime", no_argument, NULL, OPT_REALTIME},
      {"nvm", required_argument, NULL, OPT_NVM},
      {"duration", required_argument, NULL, OPT_DURATION},
      {"stats", required_argument, NULL, OPT_STATS},
      {"quiet", no_argument, NULL, 'q'},
      {"help", no_argument, NULL, 'h'},
      {NULL, 0, NULL, 0},
  };
  canfdi_app_cal_t cal;
  struct sigaction sa;
  int opt;
  int rc;
  int rc_nvm;
  int64_t t_end;
  const char *env = getenv("CAN_CHANNEL");

  ecu.iface = ((env != NULL) && (env[0] != '\0')) ? env : "vcan0";
  ecu.last_k = -1;
  while ((opt = getopt_long(argc, argv, "c:qh", opts, NULL)) != -1) {
    switch (opt) {
    case 'c':
      ecu.iface = optarg;
      break;
    case OPT_LOCKSTEP:
      ecu.lockstep = true;
      break;
    case OPT_REALTIME:
      ecu.lockstep = false;
      break;
    case OPT_NVM:
      ecu.nvm_path = optarg;
      break;
    case OPT_DURATION:
      if (!parse_seconds(optarg, &ecu.duration_ns)) {
        fprintf(stderr, PROG ": --duration wants seconds > 0, got '%s'\n", optarg);
        return 2;
      }
      break;
    case OPT_STATS:
      ecu.stats_path = optarg;
      break;
    case 'q':
      ecu.quiet = true;
      break;
    case 'h':
      usage(stdout);
      return 0;
    default:
      fprintf(stderr, PROG ": bad usage (see " PROG " --help)\n");
      return 2;
    }
  }
  if (optind < argc) {
    fprintf(stderr, PROG ": unexpected argument '%s' (see " PROG " --help)\n", argv[optind]);
    return 2;
  }
  if ((ecu.iface[0] == '\0') || (strlen(ecu.iface) >= 16U)) {
    fprintf(stderr, PROG ": bad interface name '%s'\n", ecu.iface);
    return 2;
  }

  memset(&sa, 0, sizeof sa);
  sa.sa_handler = on_signal;
  (void)sigemptyset(&sa.sa_mask);
  sa.sa_flags = 0; /* no SA_RESTART: ppoll/poll return at once */
  (void)sigaction(SIGINT, &sa, NULL);
  (void)sigaction(SIGTERM, &sa, NULL);

  canfdi_app_default_cal(&cal);
  ecu.t0_ns = mono_ns();
  if (canfdi_app_init(&app, &cal, 0U) != CANFDI_OK) {
    fprintf(stderr, PROG ": the application refused its calibration\n");
    return 1;
  }
  if ((ecu.nvm_path != NULL) && (nvm_start() != 0)) {
    return 1;
  }
  rc = canfdi_socketcan_open(&sock, ecu.iface, rx_ids, (uint32_t)(sizeof rx_ids / sizeof rx_ids[0]));
  if (rc != 0) {
    if (rc == -EAFNOSUPPORT) {
      fprintf(stderr, PROG ": this kernel has no SocketCAN (PF_CAN); run it under tools/vcan-run\n");
    } else {
      fprintf(stderr, PROG ": cannot open CAN interface %s: %s\n", ecu.iface, strerror(-rc));
    }
    (void)nvm_finish(false);
    return 1;
  }
  /* time starts now: step 1 is 1 ms after the ready line */
  ecu.t0_ns = mono_ns();
  ecu.last_ok_ns = ecu.t0_ns;
  fprintf(stderr, PROG ": ready on %s (%s)\n", ecu.iface, ecu.lockstep ? "lockstep" : "realtime");
  (void)fflush(stderr);

  rc = ecu.lockstep ? run_lockstep() : run_realtime();
  t_end = mono_ns();

  rc_nvm = nvm_finish(true);
  if (ecu.stats_path != NULL) {
    rc = (write_stats(t_end - ecu.t0_ns) != 0) ? 1 : rc;
  }
  if (!ecu.quiet) {
    const canfdi_app_diag_t *d = canfdi_app_diag(&app);
    fprintf(stderr,
            PROG ": %" PRIu64 " steps, %" PRIu64 " deadline misses, frames rx %" PRIu32
                 " tx %" PRIu32 " (dropped %" PRIu32 "), rejected %" PRIu32 ", unknown %" PRIu32
                 ", step p99.9 %" PRIu32 " us, latency p99.9 %" PRIu32 " us\n",
            ecu.steps, ecu.deadline_misses, sock.diag.rx_frames, sock.diag.tx_frames,
            sock.diag.tx_drops, d->frames_rejected, d->frames_unknown, hist_pct(&step_hist, 9990U),
            hist_pct(&lat_hist, 9990U));
  }
  canfdi_socketcan_close(&sock);
  return (rc != 0) ? rc : rc_nvm;
}
