/*
 * pil_step.c — processor in the loop: the application cross-compiled for a
 * Cortex-M core and run on QEMU (-icount shift=6, semihosting), fed the
 * frames of a SIL bus log, measuring the executed instructions of every
 * canfdi_app_step with SysTick and comparing the ECU's frames bit for bit
 * with the ones the host build sent in the SIL run (the same core must give
 * the same output on every rig).
 *
 * Run by tests/pil/run_pil.sh (`make pil-test`, tests/pil/pil.mk) in a
 * directory that holds the log as pil.log (candump -L of `canfdi-sil -l`).
 * BENCH_TICKS_NUM / BENCH_TICKS_DEN: SysTick counts per executed
 * instruction of the machine (8/5 on mps2 at 25 MHz, 128/125 on microbit at
 * 16 MHz, one instruction every 64 ns with shift=6). Prints one line
 *   pil: steps N min A mean B max C max_step K compared M differ D first F
 * (instructions; F the first step whose frames differ, -1 for none), and
 * when the log holds a tester's UDS requests (0x7E0/0x7DF) a second line
 *   pil: uds_steps U max X max_step S
 * over the steps with a request received or a response (0x7E8) sent; exits
 * 1 when a frame differs, 2 when the run cannot start.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "app/canfdi_app.h"

#define SYST_CSR (*(volatile uint32_t *)0xE000E010U)
#define SYST_RVR (*(volatile uint32_t *)0xE000E014U)
#define SYST_CVR (*(volatile uint32_t *)0xE000E018U)

extern void initialise_monitor_handles(void);

#ifndef BENCH_TICKS_NUM
#define BENCH_TICKS_NUM 8U
#define BENCH_TICKS_DEN 5U
#endif

static canfdi_app_t app;
static uint32_t first_diff = UINT32_MAX;

typedef struct {
  uint32_t id;
  uint8_t dlc;
  uint8_t data[8];
} logged_t;

/* ECU frames of the current step as logged by the host. */
static logged_t logged[8];
static unsigned n_logged;

static uint32_t ticks_min = UINT32_MAX;
static uint32_t ticks_max;
static uint64_t ticks_sum;
static uint32_t steps;
static uint32_t max_step;
static uint32_t mismatches;
static uint32_t compared;
/* steps with a UDS frame received before them or sent by them */
static bool uds_rx_this_step;
static uint32_t uds_steps;
static uint32_t uds_ticks_max;
static uint32_t uds_max_step;

static int hexval(char c)
{
  int v = -1;
  if ((c >= '0') && (c <= '9')) {
    v = c - '0';
  } else if ((c >= 'A') && (c <= 'F')) {
    v = c - 'A' + 10;
  } else if ((c >= 'a') && (c <= 'f')) {
    v = c - 'a' + 10;
  } else {
    /* not hex */
  }
  return v;
}

/* "(SSSSSSSSSS.UUUUUU) ch ID#DATA" -> time, frame; 0 on success. */
static int parse_line(const char *s, uint32_t *t_us, logged_t *f)
{
  unsigned long sec = 0UL;
  unsigned long usec = 0UL;
  const char *p;
  int rc = -1;
  if (s[0] == '(') {
    p = s + 1;
    while ((*p >= '0') && (*p <= '9')) {
      sec = (sec * 10UL) + (unsigned long)(*p - '0');
      p++;
    }
    if (*p == '.') {
      p++;
      while ((*p >= '0') && (*p <= '9')) {
        usec = (usec * 10UL) + (unsigned long)(*p - '0');
        p++;
      }
      p = strchr(p, ' ');
      p = (p != NULL) ? strchr(p + 1, ' ') : NULL;
      if (p != NULL) {
        uint32_t id = 0U;
        int h;
        p++;
        while ((h = hexval(*p)) >= 0) {
          id = (id << 4) | (uint32_t)h;
          p++;
        }
        if (*p == '#') {
          uint8_t n = 0U;
          p++;
          while ((n < 8U) && (hexval(p[0]) >= 0) && (hexval(p[1]) >= 0)) {
            f->data[n] = (uint8_t)((hexval(p[0]) << 4) | hexval(p[1]));
            n++;
            p += 2;
          }
          f->id = id;
          f->dlc = n;
          *t_us = (uint32_t)((sec * 1000000UL) + usec);
          rc = 0;
        }
      }
    }
  }
  return rc;
}

static bool is_ecu_rx(uint32_t id)
{
  return (id == 0x010U) || (id == 0x011U) || (id == 0x100U) || (id == 0x101U) || (id == 0x7E0U) ||
         (id == 0x7DFU);
}

static void do_step(uint32_t t_us)
{
  canfdi_tx_frame_t out[CANFDI_APP_MAX_TX];
  uint32_t c0;
  uint32_t c1;
  uint32_t d;
  int32_t n;
  int32_t i;
  c0 = SYST_CVR;
  n = canfdi_app_step(&app, t_us, out);
  c1 = SYST_CVR;
  d = (c0 - c1) & 0x00FFFFFFU;
  ticks_sum += d;
  if (d < ticks_min) {
    ticks_min = d;
  }
  if (d > ticks_max) {
    ticks_max = d;
    max_step = steps;
  }
  {
    bool uds = uds_rx_this_step;
    for (i = 0; i < n; i++) {
      uds = uds || (out[i].id == 0x7E8U);
    }
    if (uds) {
      uds_steps++;
      if (d > uds_ticks_max) {
        uds_ticks_max = d;
        uds_max_step = steps;
      }
    }
    uds_rx_this_step = false;
  }
  steps++;
  compared++;
  if ((n < 0) || ((unsigned)n != n_logged)) {
    mismatches++;
  } else {
    for (i = 0; i < n; i++) {
      if ((out[i].id != logged[i].id) || (out[i].dlc != logged[i].dlc) ||
          (memcmp(out[i].data, logged[i].data, logged[i].dlc) != 0)) {
        mismatches++;
        break;
      }
    }
  }
  if ((mismatches != 0U) && (first_diff == UINT32_MAX)) {
    first_diff = steps - 1U;
  }
  n_logged = 0U;
}

/* The application copies its calibration, so the harness holds it only
 * here, on the stack during initialisation: the 16 KiB of the Cortex-M0
 * machine hold the application, newlib's semihosting buffers and the
 * stack, and no second copy. */
static __attribute__((noinline)) int32_t app_init(void)
{
  canfdi_app_cal_t cal;
  canfdi_app_default_cal(&cal);
  return canfdi_app_init(&app, &cal, 0U);
}

int main(void)
{
  static char line[128];
  FILE *f;
  uint32_t cur_t = 0U;
  bool have = false;
  initialise_monitor_handles();
  SYST_RVR = 0x00FFFFFFU;
  SYST_CVR = 0U;
  SYST_CSR = 0x5U; /* core clock, enabled, no interrupt */
  if (app_init() != CANFDI_OK) {
    printf("pil: init failed\n");
    exit(2);
  }
  f = fopen("pil.log", "r");
  if (f == NULL) {
    printf("pil: cannot open pil.log in the working directory\n");
    exit(2);
  }
  while (fgets(line, (int)sizeof line, f) != NULL) {
    logged_t fr;
    uint32_t t_us;
    if (parse_line(line, &t_us, &fr) != 0) {
      continue;
    }
    if (have && (t_us != cur_t)) {
      do_step(cur_t);
    }
    cur_t = t_us;
    have = true;
    if (is_ecu_rx(fr.id)) {
      (void)canfdi_app_rx_frame(&app, fr.id, fr.data, fr.dlc, t_us);
      uds_rx_this_step = uds_rx_this_step || (fr.id >= 0x7DFU);
    } else if ((fr.id >= 0x020U) && (fr.id != 0x610U) && (n_logged < 8U)) {
      logged[n_logged++] = fr;
    } else {
      /* SimPlantStatus: not for the ECU */
    }
  }
  if (have) {
    do_step(cur_t);
  }
  (void)fclose(f);
  printf("pil: steps %lu min %lu mean %lu max %lu max_step %lu compared %lu differ %lu first %ld\n",
         (unsigned long)steps, (unsigned long)(((uint64_t)ticks_min * BENCH_TICKS_DEN) / BENCH_TICKS_NUM),
         (unsigned long)((ticks_sum * BENCH_TICKS_DEN) / ((uint64_t)BENCH_TICKS_NUM * (steps ? steps : 1U))),
         (unsigned long)(((uint64_t)ticks_max * BENCH_TICKS_DEN) / BENCH_TICKS_NUM), (unsigned long)max_step,
         (unsigned long)compared, (unsigned long)mismatches,
         (first_diff == UINT32_MAX) ? -1L : (long)first_diff);
  if (uds_steps > 0U) {
    printf("pil: uds_steps %lu max %lu max_step %lu\n", (unsigned long)uds_steps,
           (unsigned long)(((uint64_t)uds_ticks_max * BENCH_TICKS_DEN) / BENCH_TICKS_NUM),
           (unsigned long)uds_max_step);
  }
  /* exit() ends the emulation through semihosting (returning from main
   * would idle in Reset_Handler) */
  exit((mismatches == 0U) ? 0 : 1);
}
