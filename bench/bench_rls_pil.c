/*
 * bench_rls_pil.c — executed instructions of one RLS update, n = 4, on an
 * emulated Cortex-M (QEMU with -icount, SysTick read-out, semihosting
 * output), for the firmware's canfdi_rls_update and for the textbook
 * covariance RLS a user would write instead, in float and in double, fed
 * the same data (`make bench-pil`, bench/bench.mk; bench/pil_report.py
 * puts the figures side by side in $(BUILD)/bench/pil.json).
 *
 * Build with one of -DBENCH_IMPL_FIX, -DBENCH_IMPL_FLOAT, -DBENCH_IMPL_DOUBLE
 * and -DBENCH_TICKS_NUM=a -DBENCH_TICKS_DEN=b, the machine's SysTick counts
 * per executed instruction (a/b: 8/5 on mps2 at 25 MHz, 128/125 on microbit
 * at 16 MHz, each with -icount shift=6: one instruction every 64 ns).
 *
 * Data: 2000 updates, four regressors uniform in [-1, 1) (Q16.16, from an
 * integer xorshift generator, so every build sees the same bits), y =
 * theta^T phi + noise of 0.01, theta = (1.5, -0.8, 0.3, 2.0); the
 * firmware's RLS with the estimators' settings (lambda 0.99, P0 100 I,
 * trace bound 1000, excitation gate 1e-3 over 2^6 updates on regressors 0
 * and 2 as in the throttle's electrical estimator: open on this data). The textbook RLS has no gate and no trace bound: it is the
 * cheaper algorithm, measured as a user would write it.
 * Prints "rls-pil: <impl> calls N min A mean B max C (instructions) theta ..."
 * and the measurement overhead already subtracted.
 */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

#if defined(BENCH_IMPL_FIX)
#include "model/canfdi_rls.h"
#define IMPL_NAME "fixed"
#elif defined(BENCH_IMPL_FLOAT)
typedef float real_t;
#define IMPL_NAME "float"
#elif defined(BENCH_IMPL_DOUBLE)
typedef double real_t;
#define IMPL_NAME "double"
#else
#error "define BENCH_IMPL_FIX, BENCH_IMPL_FLOAT or BENCH_IMPL_DOUBLE"
#endif

#define SYST_CSR (*(volatile uint32_t *)0xE000E010U)
#define SYST_RVR (*(volatile uint32_t *)0xE000E014U)
#define SYST_CVR (*(volatile uint32_t *)0xE000E018U)

#define N 4
#define CALLS 2000

extern void initialise_monitor_handles(void);

static uint32_t rng = 0x12345678U;
static uint32_t xorshift(void)
{
  rng ^= rng << 13;
  rng ^= rng >> 17;
  rng ^= rng << 5;
  return rng;
}
/* uniform in [-1, 1) as Q16.16 */
static int32_t urand_q16(void)
{
  return (int32_t)(xorshift() >> 15) - 65536;
}

/* The next sample, made outside the timed call (no tables: the M0 board
 * has 16 KiB of RAM). */
static int32_t phi_q16[N];
static int32_t y_q16;
static void make_sample(void)
{
  static const int32_t th[N] = {98304, -52429, 19661, 131072}; /* 1.5 -0.8 0.3 2.0 */
  int64_t y = 0;
  int i;
  for (i = 0; i < N; i++) {
    phi_q16[i] = urand_q16();
    y += (int64_t)th[i] * phi_q16[i];
  }
  /* noise: 0.01 * uniform[-1, 1) ~ 655 LSB */
  y_q16 = (int32_t)(y / 65536) + (urand_q16() / 100);
}

#if defined(BENCH_IMPL_FIX)
static canfdi_rls_t rls;
static void impl_init(void)
{
  canfdi_rls_cfg_t c = {0};
  int i;
  c.n_params = N;
  c.forget_q31 = CANFDI_Q31_RATIO(1, 100);
  c.p0_q16 = 100 * 65536;
  c.trace_max_q16 = 1000 * 65536;
  c.excite_min_q16 = 66; /* 1e-3 */
  c.excite_shift = 6U;
  c.excite_mask = 0x5U; /* as the throttle's electrical estimator: 2 of 4 */
  for (i = 0; i < N; i++) {
    c.phi_shift[i] = 0;
  }
  (void)canfdi_rls_init(&rls, &c);
}
static void impl_prepare(void)
{
}
static void impl_update(void)
{
  (void)canfdi_rls_update(&rls, phi_q16, y_q16);
}
static long impl_theta_milli(int i)
{
  return (long)canfdi_rls_theta_qn(&rls, (unsigned)i, 16U) * 1000L / 65536L;
}
#else
/* The textbook covariance RLS with exponential forgetting, as a user
 * writes it with care: one division per update (1 / den), the forgetting as
 * a multiply by 1 / lambda, P kept symmetric by construction of the
 * update only (no UD factors, no gate, no trace bound). */
static real_t P[N][N];
static real_t theta[N];
static const real_t lambda = (real_t)0.99;
static const real_t inv_lambda = (real_t)1 / (real_t)0.99;
static void impl_init(void)
{
  int i;
  int j;
  for (i = 0; i < N; i++) {
    theta[i] = (real_t)0;
    for (j = 0; j < N; j++) {
      P[i][j] = (i == j) ? (real_t)100 : (real_t)0;
    }
  }
}
static void rls_update(const real_t phi[N], real_t y)
{
  real_t pphi[N];
  real_t k[N];
  real_t den = lambda;
  real_t e = y;
  int i;
  int j;
  for (i = 0; i < N; i++) {
    real_t s = (real_t)0;
    for (j = 0; j < N; j++) {
      s += P[i][j] * phi[j];
    }
    pphi[i] = s;
    den += phi[i] * s;
    e -= theta[i] * phi[i];
  }
  {
    const real_t inv_den = (real_t)1 / den;
    for (i = 0; i < N; i++) {
      k[i] = pphi[i] * inv_den;
      theta[i] += k[i] * e;
    }
  }
  for (i = 0; i < N; i++) {
    for (j = 0; j < N; j++) {
      P[i][j] = (P[i][j] - k[i] * pphi[j]) * inv_lambda;
    }
  }
}
static real_t phi_r[N];
static real_t y_r;
static void impl_prepare(void)
{
  int i;
  for (i = 0; i < N; i++) {
    phi_r[i] = (real_t)phi_q16[i] / (real_t)65536;
  }
  y_r = (real_t)y_q16 / (real_t)65536;
}
static void impl_update(void)
{
  rls_update(phi_r, y_r);
}
static long impl_theta_milli(int i)
{
  return (long)(theta[i] * (real_t)1000);
}
#endif

#if defined(__ARM_FP)
/* The FPU is off after reset: grant CP10/CP11 full access (CPACR) before
 * the first floating-point instruction, which lives in run() only. */
#define SCB_CPACR (*(volatile uint32_t *)0xE000ED88U)
static void fpu_on(void)
{
  SCB_CPACR |= (0xFU << 20);
  __asm__ volatile("dsb\n\tisb" ::: "memory");
}
#else
static void fpu_on(void)
{
}
#endif

static void run(void) __attribute__((noinline));

int main(void)
{
  initialise_monitor_handles();
  fpu_on();
  run();
  exit(0);
}

static void run(void)
{
  uint32_t tmin = UINT32_MAX;
  uint32_t tmax = 0U;
  uint64_t tsum = 0U;
  uint32_t ovh;
  int k;
  impl_init();
  SYST_RVR = 0x00FFFFFFU;
  SYST_CVR = 0U;
  SYST_CSR = 0x5U; /* core clock, enabled, no interrupt */
  {
    const uint32_t c0 = SYST_CVR;
    const uint32_t c1 = SYST_CVR;
    ovh = (c0 - c1) & 0x00FFFFFFU;
  }
  for (k = 0; k < CALLS; k++) {
    uint32_t c0;
    uint32_t c1;
    uint32_t d;
    make_sample();
    impl_prepare();
    c0 = SYST_CVR;
    impl_update();
    c1 = SYST_CVR;
    d = ((c0 - c1) & 0x00FFFFFFU) - ovh;
    tsum += d;
    tmin = (d < tmin) ? d : tmin;
    tmax = (d > tmax) ? d : tmax;
  }
  printf("rls-pil: %s calls %d min %lu mean %lu max %lu theta %ld %ld %ld %ld (milli)\n", IMPL_NAME, CALLS,
         (unsigned long)((uint64_t)tmin * BENCH_TICKS_DEN / BENCH_TICKS_NUM),
         (unsigned long)(tsum * BENCH_TICKS_DEN / ((uint64_t)BENCH_TICKS_NUM * CALLS)),
         (unsigned long)((uint64_t)tmax * BENCH_TICKS_DEN / BENCH_TICKS_NUM), impl_theta_milli(0),
         impl_theta_milli(1), impl_theta_milli(2), impl_theta_milli(3));
}
