/*
 * bench_foundation.c — harness for the foundation bench (make bench).
 *
 * Calls the step function of each detector N_SAMPLES times on a seeded,
 * noisy 1 kHz signal that contains what the detectors exist for (a mean
 * step, a slow drift, spikes beyond the limits, a variance increase), so
 * that alarm paths are exercised, and calls a few fixed-point operations on
 * random operands. The CUSUM gets a residual (in control but for a short
 * shift every 10 s) rather than the raw signal, on which its in-control mean
 * would be wrong most of the time; the adaptive threshold gets a command
 * with steps and ramps. bench/foundation_report.py
 * runs this under callgrind and divides the inclusive cost of the calls by
 * their number. The input is generated before the timed loops so that only
 * the calls are counted; the loops themselves are in the caller and are not
 * part of the figures.
 *
 * Integer-only signal generation (xorshift32; Irwin-Hall sum of four
 * uniforms for a bell-shaped noise), so the figures are identical on every
 * host. Prints a checksum of the results so nothing is optimised away.
 */
#include <stdio.h>
#include <stdlib.h>

#include "core/canfdi_fixp.h"
#include "detect/canfdi_adapt.h"
#include "detect/canfdi_cusum.h"
#include "detect/canfdi_limit.h"
#include "detect/canfdi_meanvar.h"
#include "detect/canfdi_trend.h"
#include "core/canfdi_debounce.h"

#define N_SAMPLES 100000U
#define N_OPS 20000U
#define BASE_MA 2000
#define SIGMA_MA 20

static int32_t sig_mA[N_SAMPLES];
static int32_t cmd_mA[N_SAMPLES];
static int32_t res_mA[N_SAMPLES]; /* a residual: in control but for short shifts */
static int32_t op_a[N_OPS];
static int32_t op_b[N_OPS];
static int64_t op_c[N_OPS];
static uint32_t rng_state = 0x2545F491U;
static volatile int64_t sink;
/* Alarm counts, printed to show the alarm paths were exercised. */
static uint32_t n_limit_failed, n_trend_failed, n_cusum_alarms;

static uint32_t rng_u32(void)
{
  uint32_t x = rng_state;
  x ^= x << 13;
  x ^= x >> 17;
  x ^= x << 5;
  rng_state = x;
  return x;
}

/* Bell-shaped noise with standard deviation ~sigma: the sum of four
 * uniforms on [-0.5, 0.5) has variance 4/12, so scale by sigma * sqrt(3). */
static int32_t noise(int32_t sigma)
{
  int32_t acc = 0;
  for (unsigned i = 0U; i < 4U; i++)
  {
    acc += (int32_t)(rng_u32() >> 16) - 32768;
  }
  /* acc has std 65536/sqrt(12) * 2 = 37837; sigma * acc / 37837 */
  return (int32_t)(((int64_t)acc * sigma) / 37837);
}

static void make_signal(void)
{
  for (uint32_t k = 0U; k < N_SAMPLES; k++)
  {
    int32_t x = BASE_MA;
    int32_t sigma = SIGMA_MA;
    if (k >= N_SAMPLES / 4U)
    {
      x += 5 * SIGMA_MA; /* mean step */
    }
    if (k >= N_SAMPLES / 2U)
    {
      x += (int32_t)((k - N_SAMPLES / 2U) / 50U); /* 20 mA/s drift */
    }
    if (k >= (3U * N_SAMPLES) / 4U)
    {
      sigma = 3 * SIGMA_MA; /* variance increase */
    }
    if ((k % 10000U) >= 9950U)
    {
      x += 1000; /* 50 ms spike beyond the limits */
    }
    sig_mA[k] = x + noise(sigma);
    /* Change detection watches residuals, which are in control most of the
     * time: a 2 sigma shift for 200 ms every 10 s. */
    res_mA[k] = noise(SIGMA_MA) + (((k % 10000U) >= 9800U) ? 2 * SIGMA_MA : 0);
    /* A command for the adaptive threshold: steps every 0.5 s, a ramp
     * every other second, constant otherwise. */
    cmd_mA[k] = BASE_MA + (((k / 500U) % 2U) != 0U ? 800 : 0) +
                ((((k / 1000U) % 2U) != 0U) ? (int32_t)(k % 1000U) : 0);
  }
  for (uint32_t i = 0U; i < N_OPS; i++)
  {
    op_a[i] = (int32_t)rng_u32();
    op_b[i] = (int32_t)rng_u32();
    if (op_b[i] == 0)
    {
      op_b[i] = 1;
    }
    op_c[i] = (int64_t)(((uint64_t)rng_u32() << 32) | rng_u32());
  }
}

static const canfdi_debounce_cfg_t deb_cfg = {
    .failed_threshold = 20,
    .passed_threshold = -20,
    .prefailed_step = 1U,
    .prepassed_step = 1U,
    .jump_up_value = 0,
    .jump_down_value = 0,
    .jump_up = true,
    .jump_down = true,
};

static void bench_limit(void)
{
  static const canfdi_limit_cfg_t cfg = {
      .max_set = BASE_MA + 500,
      .max_clear = BASE_MA + 450,
      .min_set = BASE_MA - 500,
      .min_clear = BASE_MA - 450,
      .max_enabled = true,
      .min_enabled = true,
      .deb = {20, -20, 1U, 1U, 0, 0, true, true},
  };
  static canfdi_limit_t l;
  int64_t acc = 0;
  if (canfdi_limit_init(&l, &cfg) != CANFDI_OK)
  {
    abort();
  }
  for (uint32_t k = 0U; k < N_SAMPLES; k++)
  {
    acc += canfdi_limit_step(&l, sig_mA[k]);
  }
  sink += acc;
  n_limit_failed = l.deb.diag.failed_qualifications;
}

static void bench_trend(void)
{
  static const canfdi_trend_cfg_t cfg = {
      .tau_us = 50000U,
      .order = 2U,
      .rate_frac_bits = 0U,
      .rate_limit =
          {
              .max_set = 2000,
              .max_clear = 1500,
              .min_set = -2000,
              .min_clear = -1500,
              .max_enabled = true,
              .min_enabled = true,
              .deb = {20, -20, 1U, 1U, 0, 0, true, true},
          },
  };
  static canfdi_trend_t t;
  int64_t acc = 0;
  if (canfdi_trend_init(&t, &cfg) != CANFDI_OK)
  {
    abort();
  }
  for (uint32_t k = 0U; k < N_SAMPLES; k++)
  {
    acc += canfdi_trend_step(&t, sig_mA[k]);
  }
  sink += acc;
  n_trend_failed = t.limit.deb.diag.failed_qualifications;
}

static void bench_adapt(void)
{
  static const canfdi_adapt_cfg_t cfg = {
      .base = 100,
      .max = 5000,
      .gain = 2032, /* 0.031 s in Q16 */
      .tau_us = 30000U,
      .gain_frac_bits = 16U,
  };
  static canfdi_adapt_t a;
  int64_t acc = 0;
  if (canfdi_adapt_init(&a, &cfg) != CANFDI_OK)
  {
    abort();
  }
  for (uint32_t k = 0U; k < N_SAMPLES; k++)
  {
    acc += canfdi_adapt_step(&a, cmd_mA[k]);
  }
  sink += acc;
}

static void bench_debounce(void)
{
  static canfdi_debounce_t d;
  int64_t acc = 0;
  if (canfdi_debounce_init(&d, &deb_cfg) != CANFDI_OK)
  {
    abort();
  }
  for (uint32_t k = 0U; k < N_SAMPLES; k++)
  {
    const int32_t e = sig_mA[k] - BASE_MA;
    const bool sym = (e > 3 * SIGMA_MA) || (e < -3 * SIGMA_MA);
    acc += canfdi_debounce_step(&d, sym ? CANFDI_DEB_REPORT_PREFAILED : CANFDI_DEB_REPORT_PREPASSED);
  }
  sink += acc;
}

static void bench_meanvar(void)
{
  static canfdi_meanvar_t mv;
  if (canfdi_meanvar_init(&mv, CANFDI_Q31_RATIO(1, 1000)) != CANFDI_OK)
  {
    abort();
  }
  for (uint32_t k = 0U; k < N_SAMPLES; k++)
  {
    canfdi_meanvar_step(&mv, sig_mA[k]);
  }
  sink += (int64_t)canfdi_meanvar_var(&mv) + canfdi_meanvar_mean(&mv);
}

static void bench_cusum(void)
{
  static canfdi_cusum_t cu;
  const canfdi_cusum_cfg_t cfg = {
      .mu0 = 0,
      .sigma_q10 = (uint32_t)SIGMA_MA << 10,
      .k_q16 = 1U << 15, /* k = 0.5 sigma */
      .h_q16 = 5U << 16, /* h = 5 sigma */
      .head_start_q16 = 0U,
      .restart = CANFDI_CUSUM_RESTART_AUTO,
  };
  int64_t acc = 0;
  if (canfdi_cusum_init(&cu, &cfg) != CANFDI_OK)
  {
    abort();
  }
  for (uint32_t k = 0U; k < N_SAMPLES; k++)
  {
    acc += canfdi_cusum_step(&cu, res_mA[k]);
  }
  sink += acc;
  n_cusum_alarms = canfdi_cusum_diag(&cu).alarms_hi + canfdi_cusum_diag(&cu).alarms_lo;
}

/* Inline operations, measured through a call each (see the report). */
__attribute__((noinline, noclone)) static int32_t bench_q31_mul_rnd(int32_t a, int32_t b)
{
  return canfdi_q31_mul_rnd(a, b);
}

__attribute__((noinline, noclone)) static int64_t bench_mul_s64_q31(int64_t a, int32_t b)
{
  return canfdi_mul_s64_q31(a, b);
}

static void bench_fixp(void)
{
  int64_t acc = 0;
  for (uint32_t i = 0U; i < N_OPS; i++)
  {
    const int32_t a = op_a[i];
    const int32_t b = op_b[i];
    acc += bench_q31_mul_rnd(a, b);
    acc ^= bench_mul_s64_q31(op_c[i], b);
    acc += canfdi_q15_div((canfdi_q15_t)(a / 65536), (canfdi_q15_t)(b / 65536));
    acc += canfdi_q31_div(a, b);
    acc += canfdi_div_s32_qn(a / 256, b, 16U);
    acc += canfdi_isqrt_u32((uint32_t)a);
    acc += canfdi_isqrt_u64((uint64_t)op_c[i]);
    acc += canfdi_q31_sqrt(a);
  }
  sink += acc;
}

int main(void)
{
  make_signal();
  bench_limit();
  bench_trend();
  bench_adapt();
  bench_debounce();
  bench_meanvar();
  bench_cusum();
  bench_fixp();
  printf("bench_foundation: %u samples (alarms: limit %u, trend %u, cusum %u), %u fixp operand sets, "
         "checksum %lld\n",
         N_SAMPLES, (unsigned)n_limit_failed, (unsigned)n_trend_failed, (unsigned)n_cusum_alarms, N_OPS,
         (long long)sink);
  return 0;
}
