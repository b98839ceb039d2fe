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
 * over the steps with a request received or a response (0x7E8) sent, and
 *   pil: ram heap_top H stack_low L free F
 * (the end of newlib's heap and the lowest stack byte written, both
 * addresses, and the bytes never touched between them); exits 1 when a frame
 * differs, 2 when the run cannot start, 3 when the stack and the heap met
 * (the run's results are then not to be trusted).
 * Before the replay it checks the out-of-line 32x32->64 products of
 * core/canfdi_fixp.c (the *_h16 forms: Thumb-1 assembly on ARMv6-M, C
 * elsewhere) against the compiler's own 64-bit products on edge values and
 * pseudo-random operands, and prints
 *   pil: products N checked D differ
 * exiting 4 when one differs: the replay compares only the operands the
 * scenario happens to produce.
 *
 * Built with PIL_COST (`make pil-cost`, tests/pil/pil_cost.py) it reads
 * the log fuzz_app_rx's inputs were written to (tests/fuzz/fuzz_export.h):
 * every frame line is received at its time whatever its identifier, the
 * id FFFFFFFF is a step at its time and FFFFFFFE a new input (the
 * application initialised again); nothing is compared, and a further line
 *   pil: cost_inputs N max_input I
 * says how many inputs ran and in which one the costliest step was.
 *
 * The harness uses no stdio and no heap: the log is read with read() into
 * a static chunk and the results are formatted here and written with
 * write(); the run ends with _exit(). newlib's FILEs, 1 KiB buffers, printf
 * and malloc state would take about 3 KiB, which the 16 KiB of the
 * Cortex-M0 machine do not have next to the application.
 */
#include <string.h>
#include <fcntl.h>
#include <unistd.h>

#include "app/canfdi_app.h"

#define SYST_CSR (*(volatile uint32_t *)0xE000E010U)
#define SYST_RVR (*(volatile uint32_t *)0xE000E014U)
#define SYST_CVR (*(volatile uint32_t *)0xE000E018U)

extern void initialise_monitor_handles(void);
extern void *_sbrk(ptrdiff_t incr);

/* RAM between the heap and the stack is painted at start; after the run the
 * lowest written word above the heap is the stack's low-water mark.
 * RAM_GUARD bytes under main's frame are left alone (paint_ram's own
 * frame). */
#define RAM_PAINT 0xA5C3E10FU
#define RAM_GUARD 256U
static uint32_t *paint_lo;
static uint32_t *paint_hi;

static __attribute__((noinline)) void paint_ram(void)
{
  uint32_t here = 0U;
  uint32_t *p;
  paint_lo = (uint32_t *)(((uintptr_t)_sbrk(0) + 3U) & ~(uintptr_t)3U);
  paint_hi = (uint32_t *)(((uintptr_t)&here - RAM_GUARD) & ~(uintptr_t)3U);
  for (p = paint_lo; p < paint_hi; p++) {
    *p = RAM_PAINT;
  }
}

/* Output: text into a static buffer, written to stdout (semihosting). */
static char out_buf[64];
static size_t out_len;
static void out_flush(void)
{
  if (out_len > 0U) {
    (void)write(1, out_buf, out_len);
    out_len = 0U;
  }
}
static void out_s(const char *s)
{
  while (*s != '\0') {
    if (out_len == sizeof out_buf) {
      out_flush();
    }
    out_buf[out_len++] = *s++;
  }
}
static void out_u(uint32_t v)
{
  char d[11];
  size_t i = sizeof d - 1U;
  d[i] = '\0';
  do {
    d[--i] = (char)('0' + (v % 10U));
    v /= 10U;
  } while (v != 0U);
  out_s(&d[i]);
}
static void out_x(uint32_t v)
{
  static const char hex[] = "0123456789abcdef";
  char d[11];
  unsigned i;
  d[0] = '0';
  d[1] = 'x';
  for (i = 0U; i < 8U; i++) {
    d[2U + i] = hex[(v >> (28U - (4U * i))) & 0xFU];
  }
  d[10] = '\0';
  out_s(d);
}
static void out_kv(const char *key, uint32_t v)
{
  out_s(key);
  out_u(v);
}
static __attribute__((noreturn)) void finish(const char *msg, int rc)
{
  out_s(msg);
  out_flush();
  _exit(rc);
}

/* One line of the log (without its newline) into line; 0 at the end. */
static char chunk[128];
static size_t chunk_len;
static size_t chunk_pos;
static int read_line(int fd, char *line, size_t cap)
{
  size_t n = 0U;
  int got = 0;
  for (;;) {
    if (chunk_pos == chunk_len) {
      ssize_t r = read(fd, chunk, sizeof chunk);
      chunk_pos = 0U;
      chunk_len = (r > 0) ? (size_t)r : 0U;
      if (chunk_len == 0U) {
        break;
      }
    }
    got = 1;
    {
      char c = chunk[chunk_pos++];
      if (c == '\n') {
        break;
      }
      if (n + 1U < cap) {
        line[n++] = c;
      }
    }
  }
  line[n] = '\0';
  return got;
}

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
#ifdef PIL_COST
#define COST_STEP_ID 0xFFFFFFFFU
#define COST_RESET_ID 0xFFFFFFFEU
static uint32_t cost_inputs;
static uint32_t cost_max_input;
#endif

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
#ifdef PIL_COST
    cost_max_input = cost_inputs - 1U;
#endif
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
#ifdef PIL_COST
  if (n < 0) {
    mismatches++;
  }
#else
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
#endif
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

/* The *_h16 products against the compiler's 64-bit products (libgcc's
 * __aeabi_lmul on ARMv6-M, SMULL/UMULL elsewhere): every pair of the edge
 * values and PRODUCT_RANDOM pseudo-random pairs (xorshift32; for the
 * 56-bit form the first operand shifted down to a random width). Returns
 * the number of results that differ; *checked counts the comparisons. */
#define PRODUCT_RANDOM 4000U
static uint32_t prng = 0x2545F491U;
static uint32_t next_u32(void)
{
  prng ^= prng << 13;
  prng ^= prng >> 17;
  prng ^= prng << 5;
  return prng;
}

static uint32_t check_pair(uint32_t x, uint32_t y, int64_t a56)
{
  const int32_t sx = (int32_t)x;
  const int32_t sy = (int32_t)y;
  const uint64_t up = (uint64_t)x * (uint64_t)y;
  /* round(a g / 2^31) half up: a = ah 2^32 + al, exact in 64 bits because
   * |ah| <= 2^24 (the function's domain) */
  const int32_t ah = (int32_t)(a56 >> 32);
  const int64_t alg = (int64_t)(uint64_t)(uint32_t)a56 * (int64_t)sy;
  const int64_t r56 = (2 * ((int64_t)ah * (int64_t)sy)) + ((alg + (1LL << 30)) >> 31);
  uint32_t bad = 0U;
  bad += (canfdi_umull32_h16(x, y) != up) ? 1U : 0U;
  bad += (canfdi_umulhi32_h16(x, y) != (uint32_t)(up >> 32)) ? 1U : 0U;
  bad += (canfdi_smull32_h16(sx, sy) != ((int64_t)sx * (int64_t)sy)) ? 1U : 0U;
  bad += (canfdi_usmull32_h16(x, sy) != ((int64_t)x * (int64_t)sy)) ? 1U : 0U;
  bad += (canfdi_mul_s56_q31_rnd_h16(a56, sy) != r56) ? 1U : 0U;
  return bad;
}

static __attribute__((noinline)) uint32_t check_products(uint32_t *checked)
{
  static const uint32_t edge[] = {0U,          1U,          2U,          0x7FFFU,     0x8000U,
                                  0xFFFFU,     0x10000U,    0x12345678U, 0x7FFFFFFFU, 0x80000000U,
                                  0x80000001U, 0xFFFF0000U, 0xFFFF8000U, 0xFFFFFFFEU, 0xFFFFFFFFU};
  static const int64_t edge56[] = {0, 1, -1, (1LL << 56) - 1, -(1LL << 56), 0x00FFFF00FFFF0000LL,
                                   -0x0000FFFF00000001LL, 0x7FFFFFFFLL, -0x80000000LL};
  const uint32_t ne = (uint32_t)(sizeof edge / sizeof edge[0]);
  const uint32_t n56 = (uint32_t)(sizeof edge56 / sizeof edge56[0]);
  uint32_t bad = 0U;
  uint32_t i;
  uint32_t j;
  *checked = 0U;
  for (i = 0U; i < ne; i++) {
    for (j = 0U; j < ne; j++) {
      bad += check_pair(edge[i], edge[j], edge56[(i + j) % n56]);
      *checked += 5U;
    }
  }
  for (i = 0U; i < PRODUCT_RANDOM; i++) {
    const uint32_t x = next_u32();
    const uint32_t y = next_u32();
    const int64_t w = (int64_t)(((uint64_t)next_u32() << 32) | next_u32());
    const int64_t a56 = w >> (7U + (next_u32() % 57U)); /* |a| <= 2^56 */
    bad += check_pair(x, y, a56);
    *checked += 5U;
  }
  return bad;
}

int main(void)
{
  static char line[128];
  int fd;
  uint32_t cur_t = 0U;
  bool have = false;
  initialise_monitor_handles();
  paint_ram();
  SYST_RVR = 0x00FFFFFFU;
  SYST_CVR = 0U;
  SYST_CSR = 0x5U; /* core clock, enabled, no interrupt */
  {
    uint32_t checked;
    const uint32_t bad = check_products(&checked);
    out_kv("pil: products ", checked);
    out_kv(" checked ", bad);
    out_s(" differ\n");
    if (bad != 0U) {
      finish("pil: an out-of-line product differs from the compiler's\n", 4);
    }
  }
  if (app_init() != CANFDI_OK) {
    finish("pil: init failed\n", 2);
  }
  fd = open("pil.log", O_RDONLY);
  if (fd < 0) {
    finish("pil: cannot open pil.log in the working directory\n", 2);
  }
  while (read_line(fd, line, sizeof line) != 0) {
    logged_t fr;
    uint32_t t_us;
    if (parse_line(line, &t_us, &fr) != 0) {
      continue;
    }
#ifdef PIL_COST
    if (fr.id == COST_STEP_ID) {
      do_step(t_us);
    } else if (fr.id == COST_RESET_ID) {
      if (app_init() != CANFDI_OK) {
        finish("pil: init failed\n", 2);
      }
      cost_inputs++;
    } else if (cost_inputs > 0U) {
      (void)canfdi_app_rx_frame(&app, fr.id, fr.data, fr.dlc, t_us);
    } else {
      /* before the first input: not a cost log */
    }
    continue;
#endif
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
  (void)close(fd);
  out_kv("pil: steps ", steps);
  out_kv(" min ", (uint32_t)(((uint64_t)ticks_min * BENCH_TICKS_DEN) / BENCH_TICKS_NUM));
  out_kv(" mean ", (uint32_t)((ticks_sum * BENCH_TICKS_DEN) / ((uint64_t)BENCH_TICKS_NUM * (steps ? steps : 1U))));
  out_kv(" max ", (uint32_t)(((uint64_t)ticks_max * BENCH_TICKS_DEN) / BENCH_TICKS_NUM));
  out_kv(" max_step ", max_step);
  out_kv(" compared ", compared);
  out_kv(" differ ", mismatches);
  if (first_diff == UINT32_MAX) {
    out_s(" first -1\n");
  } else {
    out_kv(" first ", first_diff);
    out_s("\n");
  }
#ifdef PIL_COST
  out_kv("pil: cost_inputs ", cost_inputs);
  out_kv(" max_input ", cost_max_input);
  out_s("\n");
#endif
  if (uds_steps > 0U) {
    out_kv("pil: uds_steps ", uds_steps);
    out_kv(" max ", (uint32_t)(((uint64_t)uds_ticks_max * BENCH_TICKS_DEN) / BENCH_TICKS_NUM));
    out_kv(" max_step ", uds_max_step);
    out_s("\n");
  }
  {
    uintptr_t heap_top = (uintptr_t)_sbrk(0);
    uint32_t *p = paint_lo;
    bool met;
    while ((p < paint_hi) && (((uintptr_t)p < heap_top) || (*p == RAM_PAINT))) {
      p++;
    }
    /* a painted word must remain between the heap and the stack */
    met = ((uintptr_t)p <= heap_top) || (p == paint_lo) || (p[-1] != RAM_PAINT);
    out_s("pil: ram heap_top ");
    out_x((uint32_t)heap_top);
    out_s(" stack_low ");
    out_x((uint32_t)(uintptr_t)p);
    out_kv(" free ", met ? 0U : (uint32_t)((uintptr_t)p - heap_top));
    out_s("\n");
    if (met) {
      finish("pil: the stack and the heap met: no RAM left on this machine\n", 3);
    }
  }
  /* _exit() ends the emulation through semihosting (returning from main
   * would idle in Reset_Handler) */
  finish("", (mismatches == 0U) ? 0 : 1);
}
