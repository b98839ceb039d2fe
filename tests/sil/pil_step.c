/*
 * pil_step.c — the application on an emulated Cortex-M (QEMU -M mps2-an386,
 * -icount shift=6, semihosting), fed the frames of a SIL bus log, measuring
 * the executed instructions of every canfdi_app_step with SysTick and
 * comparing the ECU's frames bit for bit with the ones the host build sent
 * in the SIL run (the same core must give the same output on every rig).
 *
 * Usage (see mk/sil.mk, `make sil-pil`):
 *   qemu-system-arm -M mps2-an386 -nographic -icount shift=6 \
 *     -semihosting-config enable=on,target=native -kernel pil_step.elf
 * reads build/demo/canfdi-demo.log (candump -L of `make demo`) relative to
 * QEMU's working directory, or the log named by -DPIL_LOG. A log with a
 * tester's UDS requests (`make sil-pil-uds`: tests/sil/scenarios/
 * uds_workshop.scn) feeds them to the ECU too, and the steps in which a
 * request or response is in flight are reported on their own.
 *
 * With -icount shift=6 SysTick (CLKSOURCE = core clock) advances 1.6 counts
 * per executed instruction (docs/design.md, facts about the build machines),
 * so instructions = counts * 5 / 8.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "app/canfdi_app.h"

#ifndef PIL_LOG
#define PIL_LOG "build/demo/canfdi-demo.log"
#endif

#define SYST_CSR (*(volatile uint32_t *)0xE000E010U)
#define SYST_RVR (*(volatile uint32_t *)0xE000E014U)
#define SYST_CVR (*(volatile uint32_t *)0xE000E018U)

extern void initialise_monitor_handles(void);

static canfdi_app_t app;
static canfdi_app_cal_t cal;

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
          (memcmp(out[i].data, logged[i].data, 8U) != 0)) {
        mismatches++;
        break;
      }
    }
  }
  n_logged = 0U;
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
  canfdi_app_default_cal(&cal);
  if (canfdi_app_init(&app, &cal, 0U) != CANFDI_OK) {
    printf("pil: init failed\n");
    exit(2);
  }
  f = fopen(PIL_LOG, "r");
  if (f == NULL) {
    printf("pil: cannot open %s (run make demo first)\n", PIL_LOG);
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
  printf("pil: %lu steps; instructions per canfdi_app_step min %lu mean %lu max %lu (step %lu)\n",
         (unsigned long)steps, (unsigned long)((ticks_min * 5U) / 8U),
         (unsigned long)((ticks_sum * 5U) / (8U * (steps ? steps : 1U))),
         (unsigned long)((ticks_max * 5U) / 8U), (unsigned long)max_step);
  if (uds_steps > 0U) {
    printf("pil: %lu steps with a UDS request or response in flight: instructions max %lu (step %lu)\n",
           (unsigned long)uds_steps, (unsigned long)((uds_ticks_max * 5U) / 8U), (unsigned long)uds_max_step);
  }
  printf("pil: ECU frames compared with the host SIL run: %lu steps, %lu differ\n",
         (unsigned long)compared, (unsigned long)mismatches);
  /* exit() ends the emulation through semihosting (returning from main
   * would idle in Reset_Handler) */
  exit((mismatches == 0U) ? 0 : 1);
}
