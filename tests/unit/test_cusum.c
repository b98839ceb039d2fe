/*
 * test_cusum.c — unit tests of canfdi_cusum (two-sided tabular CUSUM).
 *
 * Acceptance point (docs/requirements.md): driven by N(delta, 1) samples from
 * a seeded generator, the fixed-point CUSUM with k = 0.5 reproduces the
 * published average run lengths of the two-sided tabular CUSUM (Montgomery,
 * Table 9.3: in control 168 for h = 4 and 465 for h = 5; for a 1 sigma shift
 * 8.38 and 10.4) within 10 %.
 *
 * Monte Carlo design. Samples are N(delta, 1) from xoshiro256** + the
 * Marsaglia polar method, quantised to sigma = 2^12 LSB (quantisation
 * noise 2^-12 / sqrt(12) sigma: negligible). The detector runs in AUTO
 * restart mode with head start 0, so each alarm restarts both sums at zero
 * and consecutive run lengths are independent, each counted from a fresh
 * start. In control the run length is roughly geometric (SD ~ ARL), so the
 * standard error of the mean of N runs is ~ ARL / sqrt(N); a 2.5 % SE needs
 * N >= 1600. The test uses N = 3200 runs per case (SE ~ 1.8 %, so the 10 %
 * acceptance band is > 5 SE wide) and asserts the measured SE <= 2.5 % as
 * well, so a wrong run-length distribution cannot hide behind too few runs.
 */
#include <check.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "detect/canfdi_cusum.h"
#include "unit_main.h"

/* ck_assert reports each passing check to the parent process (a system
 * call); inside long loops use this, which only reports failure. */
#define CHECK(cond)                                         \
  do {                                                      \
    if (!(cond)) {                                          \
      ck_abort_msg("%s:%d: %s", __FILE__, __LINE__, #cond); \
    }                                                       \
  } while (0)

/* ---- deterministic generator: xoshiro256** seeded by splitmix64 -------- */

/* Every seed below is offset by this; rebuild with -DCUSUM_TEST_SEED=n to
 * check that no assertion depends on one lucky stream. */
#ifndef CUSUM_TEST_SEED
#define CUSUM_TEST_SEED 0U
#endif

static uint64_t xs[4];
static int have_spare;
static double spare;

static uint64_t splitmix64(uint64_t *st)
{
  uint64_t z = (*st += 0x9E3779B97F4A7C15ULL);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  return z ^ (z >> 31);
}

static uint64_t rotl(uint64_t x, unsigned k)
{
  return (x << k) | (x >> (64U - k));
}

static uint64_t xoshiro_next(void)
{
  const uint64_t result = rotl(xs[1] * 5U, 7U) * 9U;
  const uint64_t t = xs[1] << 17;
  xs[2] ^= xs[0];
  xs[3] ^= xs[1];
  xs[1] ^= xs[2];
  xs[0] ^= xs[3];
  xs[2] ^= t;
  xs[3] = rotl(xs[3], 45U);
  return result;
}

static void rng_seed(uint64_t seed)
{
  uint64_t st = seed + ((uint64_t)(CUSUM_TEST_SEED) << 32);
  for (int i = 0; i < 4; i++) {
    xs[i] = splitmix64(&st);
  }
  have_spare = 0;
}

/* Uniform in (-1, 1) from the top 53 bits. */
static double uniform_pm1(void)
{
  return ldexp((double)(xoshiro_next() >> 11), -52) - 1.0;
}

/* Standard normal, Marsaglia polar method (two per accepted pair). */
static double gauss(void)
{
  double out;
  if (have_spare != 0) {
    have_spare = 0;
    out = spare;
  } else {
    double u, v, q;
    do {
      u = uniform_pm1();
      v = uniform_pm1();
      q = u * u + v * v;
    } while ((q >= 1.0) || (q <= 0.0));
    const double f = sqrt(-2.0 * log(q) / q);
    spare = v * f;
    have_spare = 1;
    out = u * f;
  }
  return out;
}

/* ---- configuration helpers ---------------------------------------------- */

#define SIGMA_LSB 4096 /* sigma = 2^12 LSB */
#define Q16 65536.0

static uint32_t q16(double v)
{
  return (uint32_t)lround(v * Q16);
}

static canfdi_cusum_cfg_t cfg_std(double k, double h)
{
  canfdi_cusum_cfg_t c;
  c.mu0 = 0;
  c.sigma_q10 = (uint32_t)SIGMA_LSB * 1024U;
  c.k_q16 = q16(k);
  c.h_q16 = q16(h);
  c.head_start_q16 = 0U;
  c.restart = CANFDI_CUSUM_RESTART_AUTO;
  return c;
}

/* One N(delta, 1) sample in LSB, around mu0 = 0. */
static int32_t sample(double delta)
{
  return (int32_t)lround((delta + gauss()) * (double)SIGMA_LSB);
}

/* ---- ARL acceptance ----------------------------------------------------- */

typedef struct {
  double h, delta, arl_published;
} arl_case_t;

/* Montgomery, Introduction to Statistical Quality Control, Table 9.3
 * (two-sided tabular CUSUM, k = 1/2, zero start). */
static const arl_case_t arl_cases[] = {
    {4.0, 0.0, 168.0},
    {5.0, 0.0, 465.0},
    {4.0, 1.0, 8.38},
    {5.0, 1.0, 10.4},
};

#define ARL_RUNS 3200
#define ARL_SE_MAX 0.025
#define ARL_TOL 0.10

START_TEST(test_arl_matches_published)
{
  const arl_case_t *c = &arl_cases[_i];
  const canfdi_cusum_cfg_t cfg = cfg_std(0.5, c->h);
  canfdi_cusum_t s;
  ck_assert_int_eq(canfdi_cusum_init(&s, &cfg), CANFDI_OK);
  rng_seed(0xC05E5EEDU + (uint64_t)(unsigned)_i);

  double sum = 0.0, sum2 = 0.0;
  uint32_t n_hi = 0U, n_lo = 0U;
  for (int run = 0; run < ARL_RUNS; run++) {
    uint32_t len = 0U, side = CANFDI_CUSUM_NONE;
    do {
      side = canfdi_cusum_step(&s, sample(c->delta));
      len++;
      CHECK(len < 1000000U); /* a detector that never alarms */
    } while (side == CANFDI_CUSUM_NONE);
    /* AUTO restart: the next run starts from zero sums. */
    CHECK(canfdi_cusum_sum_hi_q16(&s) == 0 && canfdi_cusum_sum_lo_q16(&s) == 0);
    n_hi += (side == CANFDI_CUSUM_HI) ? 1U : 0U;
    n_lo += (side == CANFDI_CUSUM_LO) ? 1U : 0U;
    sum += (double)len;
    sum2 += (double)len * (double)len;
  }
  const double n = (double)ARL_RUNS;
  const double arl = sum / n;
  const double sd = sqrt((sum2 - n * arl * arl) / (n - 1.0));
  const double se = sd / sqrt(n);
  printf("cusum ARL h=%.0f k=0.5 delta=%.0f: %.2f +- %.2f (SE %.1f%%, SD %.1f), published %.2f "
         "(%+.1f%%), alarms hi/lo %u/%u\n",
         c->h, c->delta, arl, se, 100.0 * se / arl, sd, c->arl_published,
         100.0 * (arl - c->arl_published) / c->arl_published, (unsigned)n_hi, (unsigned)n_lo);
  fflush(stdout);
  ck_assert_msg(se <= ARL_SE_MAX * arl, "SE %.3g exceeds %.1f%% of ARL", se, 100.0 * ARL_SE_MAX);
  ck_assert_msg(fabs(arl - c->arl_published) <= ARL_TOL * c->arl_published,
                "ARL %.3g vs published %.3g", arl, c->arl_published);

  const canfdi_cusum_diag_t d = canfdi_cusum_diag(&s);
  ck_assert_uint_eq(d.alarms_hi, n_hi);
  ck_assert_uint_eq(d.alarms_lo, n_lo);
  ck_assert_uint_eq(d.restarts, (uint32_t)ARL_RUNS);
  if (!(c->delta > 0.0)) {
    /* In control the two sides are mirror images: the split of alarms is
     * Binomial(N, 1/2); 4 SD = 2 sqrt(N) bounds it except with p < 1e-4. */
    ck_assert_msg(fabs((double)n_hi - (double)n_lo) <= 4.0 * 0.5 * sqrt(n), "hi %u lo %u",
                  (unsigned)n_hi, (unsigned)n_lo);
  } else {
    /* A +1 sigma shift: a lower-side alarm needs an in-control-like run of
     * the lower sum against a drift of -1.5 sigma per sample — essentially
     * never within ~10 samples. */
    ck_assert_uint_le(n_lo, (uint32_t)ARL_RUNS / 100U);
  }
}
END_TEST

/* ---- change-time estimate ------------------------------------------------ */

/* Noise-free step of +-delta at sample t0 (index counted from 1): the sum
 * is zero up to t0 - 1 and grows by (delta - k) per sample from t0, so the
 * estimate must be exact, the alarm comes on the first n with
 * n (delta - k) > h, and the shift estimate K + S/N equals the step. */
static const double step_deltas[] = {2.0, -2.0, 1.0, -1.0, 3.25, -0.75};

START_TEST(test_change_time_noise_free)
{
  const double delta = step_deltas[_i];
  const uint32_t t0 = 50U;
  const canfdi_cusum_cfg_t cfg = cfg_std(0.5, 5.0);
  canfdi_cusum_t s;
  ck_assert_int_eq(canfdi_cusum_init(&s, &cfg), CANFDI_OK);
  const int32_t x_step = (int32_t)lround(delta * SIGMA_LSB);
  const uint32_t expect_n = (uint32_t)floor(5.0 / (fabs(delta) - 0.5)) + 1U;
  uint32_t side = CANFDI_CUSUM_NONE;
  for (uint32_t t = 1U; side == CANFDI_CUSUM_NONE; t++) {
    side = canfdi_cusum_step(&s, (t < t0) ? 0 : x_step);
    CHECK(t < t0 + 100U);
  }
  const canfdi_cusum_alarm_t a = canfdi_cusum_last_alarm(&s);
  ck_assert_uint_eq(side, (delta > 0.0) ? CANFDI_CUSUM_HI : CANFDI_CUSUM_LO);
  ck_assert_uint_eq(a.side, side);
  ck_assert_uint_eq(a.n_nonzero, expect_n);
  ck_assert_uint_eq(a.alarm_step, t0 + expect_n - 1U);
  ck_assert_uint_eq(a.change_step + 1U, t0);
  ck_assert_uint_eq(canfdi_cusum_step_index(&s), a.alarm_step);
  ck_assert(a.sum_q16 > canfdi_cusum_threshold_q16(&s));
  /* K + S/N = delta exactly (S/N = delta - K, a whole number of LSB here) */
  ck_assert(a.shift_q16 == (int64_t)x_step * 65536);
}
END_TEST

/*
 * With noise, delta = +-2, k = 0.5, h = 5, shift at t0 = 100 (LATCH mode,
 * fresh detector per trial). The estimate t0_hat = change_step + 1 is late
 * only when the sum drops back to zero after t0 (P(z < k) = 0.067 per
 * sample under the shift, and the sum is soon large), and early when the
 * sum was already in an in-control excursion at t0 - 1 — Montgomery's
 * estimator then points at the start of that excursion, which can lie many
 * samples back; that tail is a property of the estimator, not of the
 * fixed-point code. Trials that alarm before t0 are false alarms, not change
 * detections, and are excluded (~18 %).
 * Reference distribution (40 000 trials per sign, other seeds, both signs
 * alike): err = 0 in 49 %, -1 in 16 %, |err| <= 2 in 79 %, |err| <= 5 in
 * 89 %, err > +2 in 0.2 %. Asserted with >= 4.5 binomial SD of margin at the
 * ~820 valid trials used here: |err| <= 2 in >= 70 %, |err| <= 5 in >= 80 %,
 * err > +2 in <= 1 %, median in {-1, 0}; every alarm on the shifted side.
 */
START_TEST(test_change_time_noisy)
{
  const double delta = (_i == 0) ? 2.0 : -2.0;
  const uint32_t t0 = 100U;
  const int trials = 1000;
  const canfdi_cusum_cfg_t cfg = {0, (uint32_t)SIGMA_LSB * 1024U, 32768U, 5U * 65536U, 0U,
                                  CANFDI_CUSUM_RESTART_LATCH};
  int hist[41] = {0}; /* error -20 .. +20 */
  int valid = 0, within2 = 0, within5 = 0, late = 0, wrong_side = 0, false_alarms = 0;
  long delay_sum = 0;
  rng_seed(0xD1CEU + (uint64_t)(unsigned)_i);
  for (int tr = 0; tr < trials; tr++) {
    canfdi_cusum_t s;
    ck_assert_int_eq(canfdi_cusum_init(&s, &cfg), CANFDI_OK);
    uint32_t t = 0U;
    while (!canfdi_cusum_latched(&s)) {
      t++;
      (void)canfdi_cusum_step(&s, sample((t < t0) ? 0.0 : delta));
      CHECK(t < 100000U);
    }
    const canfdi_cusum_alarm_t a = canfdi_cusum_last_alarm(&s);
    if (a.alarm_step < t0) {
      false_alarms++;
      continue;
    }
    valid++;
    if (a.side != ((delta > 0.0) ? CANFDI_CUSUM_HI : CANFDI_CUSUM_LO)) {
      wrong_side++;
    }
    const int err = (int)(a.change_step + 1U) - (int)t0;
    hist[(err < -20) ? 0 : ((err > 20) ? 40 : err + 20)]++;
    within2 += (abs(err) <= 2) ? 1 : 0;
    within5 += (abs(err) <= 5) ? 1 : 0;
    late += (err > 2) ? 1 : 0;
    delay_sum += (long)(a.alarm_step - t0);
  }
  int cum = 0, median = 99;
  for (int e = 0; e <= 40; e++) {
    cum += hist[e];
    if ((2 * cum >= valid) && (median == 99)) {
      median = e - 20;
    }
  }
  printf("cusum change time delta=%+.0f: %d valid trials (%d false alarms before t0), "
         "|err|<=2: %.1f%%, |err|<=5: %.1f%%, err>2: %.1f%%, median err %d, mean delay %.2f, "
         "wrong side %d\n",
         delta, valid, false_alarms, 100.0 * within2 / valid, 100.0 * within5 / valid,
         100.0 * late / valid, median,
         (double)delay_sum / valid, wrong_side);
  fflush(stdout);
  ck_assert_int_ge(valid, trials / 2);
  ck_assert_int_eq(wrong_side, 0);
  ck_assert_int_ge(median, -1);
  ck_assert_int_le(median, 0);
  ck_assert_int_ge(100 * within2, 70 * valid);
  ck_assert_int_ge(100 * within5, 80 * valid);
  ck_assert_int_le(100 * late, valid);
}
END_TEST

/* ---- range: huge inputs, extreme configurations ------------------------- */

/* Full-range jumps: |x - mu0| up to 2^32 - 1 alarm at once on the right
 * side, with N = 1 and the exact shift; nothing overflows (UBSan). */
START_TEST(test_huge_inputs)
{
  static const struct {
    int32_t mu0, x;
    uint32_t side;
  } t[] = {
      {INT32_MIN, INT32_MAX, CANFDI_CUSUM_HI},
      {INT32_MAX, INT32_MIN, CANFDI_CUSUM_LO},
      {0, INT32_MAX, CANFDI_CUSUM_HI},
      {0, INT32_MIN, CANFDI_CUSUM_LO},
  };
  for (size_t i = 0; i < sizeof t / sizeof t[0]; i++) {
    canfdi_cusum_cfg_t cfg = {t[i].mu0, 1024U, 32768U, 5U * 65536U, 0U,
                              CANFDI_CUSUM_RESTART_LATCH};
    canfdi_cusum_t s;
    ck_assert_int_eq(canfdi_cusum_init(&s, &cfg), CANFDI_OK);
    ck_assert_uint_eq(canfdi_cusum_step(&s, t[i].x), t[i].side);
    const canfdi_cusum_alarm_t a = canfdi_cusum_last_alarm(&s);
    ck_assert_uint_eq(a.n_nonzero, 1U);
    ck_assert_uint_eq(a.change_step, 0U);
    ck_assert(a.shift_q16 == ((int64_t)t[i].x - (int64_t)t[i].mu0) * 65536);
    /* Latched: further extremes change nothing. */
    for (int k = 0; k < 10; k++) {
      ck_assert_uint_eq(canfdi_cusum_step(&s, (k & 1) ? INT32_MAX : INT32_MIN), 0U);
    }
    ck_assert_uint_eq(canfdi_cusum_diag(&s).latched_samples, 10U);
  }
}
END_TEST

/* Random int32 inputs against random valid configurations, including the
 * extreme sigma and k/h limits: invariants 0 <= S <= H after every
 * non-alarming step; UBSan aborts on any overflow. */
START_TEST(test_random_full_range_invariants)
{
  rng_seed(0xFEEDU);
  for (int cfgn = 0; cfgn < 200; cfgn++) {
    canfdi_cusum_cfg_t cfg;
    cfg.mu0 = (int32_t)((int64_t)(xoshiro_next() >> 32) + INT32_MIN);
    cfg.sigma_q10 = (cfgn % 4 == 0) ? UINT32_MAX : (uint32_t)(xoshiro_next() >> 32) | 1U;
    cfg.k_q16 = (cfgn % 5 == 0) ? CANFDI_CUSUM_KH_MAX_Q16
                                : (uint32_t)(xoshiro_next() % (CANFDI_CUSUM_KH_MAX_Q16 + 1U));
    cfg.h_q16 = (cfgn % 3 == 0) ? CANFDI_CUSUM_KH_MAX_Q16
                                : 1U + (uint32_t)(xoshiro_next() % CANFDI_CUSUM_KH_MAX_Q16);
    cfg.head_start_q16 = (uint32_t)(xoshiro_next() % cfg.h_q16);
    cfg.restart = CANFDI_CUSUM_RESTART_AUTO;
    canfdi_cusum_t s;
    ck_assert_int_eq(canfdi_cusum_init(&s, &cfg), CANFDI_OK);
    const int64_t h = canfdi_cusum_threshold_q16(&s);
    for (int k = 0; k < 2000; k++) {
      /* Mix uniform int32 with the two extremes. */
      const uint64_t r = xoshiro_next();
      const int32_t x = ((r & 7U) == 0U)   ? INT32_MAX
                        : ((r & 7U) == 1U) ? INT32_MIN
                                           : (int32_t)((int64_t)(r >> 32) + INT32_MIN);
      const uint32_t side = canfdi_cusum_step(&s, x);
      CHECK(side <= CANFDI_CUSUM_LO);
      CHECK(canfdi_cusum_sum_hi_q16(&s) >= 0 && canfdi_cusum_sum_hi_q16(&s) <= h);
      CHECK(canfdi_cusum_sum_lo_q16(&s) >= 0 && canfdi_cusum_sum_lo_q16(&s) <= h);
      if (side != CANFDI_CUSUM_NONE) {
        const canfdi_cusum_alarm_t a = canfdi_cusum_last_alarm(&s);
        CHECK(a.sum_q16 > h);
        CHECK(a.alarm_step - a.change_step == a.n_nonzero);
        CHECK((side == CANFDI_CUSUM_HI) ? (a.shift_q16 > 0) : (a.shift_q16 < 0));
      }
    }
  }
}
END_TEST

/* ---- restart options ---------------------------------------------------- */

/* LATCH freezes sums and alarm record until canfdi_cusum_restart; the index
 * keeps running; restart re-arms from the head start. */
START_TEST(test_latch_and_restart)
{
  canfdi_cusum_cfg_t cfg = cfg_std(0.5, 4.0);
  cfg.restart = CANFDI_CUSUM_RESTART_LATCH;
  canfdi_cusum_t s;
  ck_assert_int_eq(canfdi_cusum_init(&s, &cfg), CANFDI_OK);
  const int32_t up = 2 * SIGMA_LSB; /* +2 sigma: 1.5 sigma per sample */
  uint32_t t = 0U, side = 0U;
  while (side == 0U) {
    side = canfdi_cusum_step(&s, up);
    t++;
  }
  ck_assert_uint_eq(side, CANFDI_CUSUM_HI);
  ck_assert(canfdi_cusum_latched(&s));
  const int64_t frozen = canfdi_cusum_sum_hi_q16(&s);
  const canfdi_cusum_alarm_t a0 = canfdi_cusum_last_alarm(&s);
  for (int k = 0; k < 20; k++) {
    ck_assert_uint_eq(canfdi_cusum_step(&s, -up), 0U);
  }
  ck_assert(canfdi_cusum_sum_hi_q16(&s) == frozen);
  ck_assert_uint_eq(canfdi_cusum_last_alarm(&s).alarm_step, a0.alarm_step);
  ck_assert_uint_eq(canfdi_cusum_step_index(&s), t + 20U);
  ck_assert_uint_eq(canfdi_cusum_diag(&s).latched_samples, 20U);

  canfdi_cusum_restart(&s);
  ck_assert(!canfdi_cusum_latched(&s));
  ck_assert(canfdi_cusum_sum_hi_q16(&s) == 0 && canfdi_cusum_sum_lo_q16(&s) == 0);
  ck_assert_uint_eq(canfdi_cusum_diag(&s).restarts, 1U);
  /* Now a downward step alarms on the low side, timed on the running index
   * (the same number of samples as the upward one: symmetric). */
  side = 0U;
  uint32_t t2 = 0U;
  while (side == 0U) {
    side = canfdi_cusum_step(&s, -up);
    t2++;
  }
  ck_assert_uint_eq(side, CANFDI_CUSUM_LO);
  ck_assert_uint_eq(t2, t);
  const canfdi_cusum_alarm_t a1 = canfdi_cusum_last_alarm(&s);
  ck_assert_uint_eq(a1.alarm_step, t + 20U + t2);
  ck_assert_uint_eq(a1.change_step, t + 20U);
}
END_TEST

/* AUTO restart with and without the FIR head start h/2: noise-free shift
 * of delta = 1 from sample 1; the n-th alarm comes when the sum, restarted
 * at s0, first exceeds h: every floor((h - s0)/(delta - k)) + 1 samples. */
START_TEST(test_auto_restart_head_start)
{
  const double h = 5.0, k = 0.5, delta = 1.0;
  const double s0 = (_i == 0) ? 0.0 : h / 2.0;
  canfdi_cusum_cfg_t cfg = cfg_std(k, h);
  cfg.head_start_q16 = q16(s0);
  canfdi_cusum_t s;
  ck_assert_int_eq(canfdi_cusum_init(&s, &cfg), CANFDI_OK);
  ck_assert(canfdi_cusum_sum_hi_q16(&s) == (int64_t)lround(s0 * SIGMA_LSB * Q16));
  ck_assert(canfdi_cusum_sum_lo_q16(&s) == canfdi_cusum_sum_hi_q16(&s));
  const uint32_t period = (uint32_t)floor((h - s0) / (delta - k)) + 1U;
  uint32_t alarms = 0U;
  for (uint32_t t = 1U; t <= 10U * period; t++) {
    const uint32_t side = canfdi_cusum_step(&s, (int32_t)lround(delta * SIGMA_LSB));
    const bool due = (t % period) == 0U;
    ck_assert_uint_eq(side, due ? CANFDI_CUSUM_HI : CANFDI_CUSUM_NONE);
    if (due) {
      alarms++;
      ck_assert(!canfdi_cusum_latched(&s));
      ck_assert(canfdi_cusum_sum_hi_q16(&s) == (int64_t)lround(s0 * SIGMA_LSB * Q16));
    }
  }
  ck_assert_uint_eq(canfdi_cusum_diag(&s).alarms_hi, alarms);
  ck_assert_uint_eq(canfdi_cusum_diag(&s).restarts, alarms);
  ck_assert_uint_eq(alarms, 10U);
}
END_TEST

/* ---- init validation ---------------------------------------------------- */

START_TEST(test_init_rejects_bad_config)
{
  const canfdi_cusum_cfg_t good = cfg_std(0.5, 5.0);
  canfdi_cusum_cfg_t c[8];
  for (int i = 0; i < 8; i++) {
    c[i] = good;
  }
  c[0].sigma_q10 = 0U;
  c[1].h_q16 = 0U;
  c[2].k_q16 = CANFDI_CUSUM_KH_MAX_Q16 + 1U;
  c[3].h_q16 = CANFDI_CUSUM_KH_MAX_Q16 + 1U;
  c[4].head_start_q16 = good.h_q16;
  c[5].restart = (canfdi_cusum_restart_t)7;
  c[6].head_start_q16 = good.h_q16 + 1U;
  c[7].restart = (canfdi_cusum_restart_t)-1;
  canfdi_cusum_t s;
  for (int i = 0; i < 8; i++) {
    ck_assert_msg(canfdi_cusum_init(&s, &c[i]) == -CANFDI_EINVAL, "config %d accepted", i);
  }
  ck_assert_int_eq(canfdi_cusum_init(NULL, &good), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_cusum_init(&s, NULL), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_cusum_init(&s, &good), CANFDI_OK);
  ck_assert_uint_eq(canfdi_cusum_step_index(&s), 0U);
  ck_assert_uint_eq(canfdi_cusum_last_alarm(&s).side, CANFDI_CUSUM_NONE);
  /* K and H are k and h times sigma in LSB, Q16 */
  ck_assert(canfdi_cusum_threshold_q16(&s) == (int64_t)5 * SIGMA_LSB * 65536);
}
END_TEST

/* Diagnostics counters saturate at UINT32_MAX; the sample index is state
 * and wraps modulo 2^32 by design. */
START_TEST(test_counters_saturate_index_wraps)
{
  canfdi_cusum_cfg_t cfg = cfg_std(0.5, 4.0);
  cfg.restart = CANFDI_CUSUM_RESTART_LATCH;
  canfdi_cusum_t s;
  ck_assert_int_eq(canfdi_cusum_init(&s, &cfg), CANFDI_OK);
  ck_assert_uint_eq(canfdi_cusum_last_alarm(&s).side, CANFDI_CUSUM_NONE);
  s.diag.alarms_hi = UINT32_MAX;
  s.diag.latched_samples = UINT32_MAX - 1U;
  s.diag.restarts = UINT32_MAX - 1U;
  s.step = UINT32_MAX - 2U;
  uint32_t side = 0U;
  while (side == 0U) {
    side = canfdi_cusum_step(&s, 2 * SIGMA_LSB);
  }
  ck_assert_uint_eq(side, CANFDI_CUSUM_HI);
  ck_assert_uint_eq(canfdi_cusum_last_alarm(&s).side, CANFDI_CUSUM_HI);
  ck_assert_uint_eq(canfdi_cusum_diag(&s).alarms_hi, UINT32_MAX);
  for (int k = 0; k < 3; k++) {
    ck_assert_uint_eq(canfdi_cusum_step(&s, 0), 0U);
  }
  ck_assert_uint_eq(canfdi_cusum_diag(&s).latched_samples, UINT32_MAX);
  canfdi_cusum_restart(&s);
  canfdi_cusum_restart(&s);
  ck_assert_uint_eq(canfdi_cusum_diag(&s).restarts, UINT32_MAX);
  /* the index went past 2^32 - 1 and wrapped (a few samples to the alarm,
   * three latched ones) */
  ck_assert_uint_lt(canfdi_cusum_step_index(&s), 100U);
}
END_TEST

static Suite *make_suite(void)
{
  Suite *su = suite_create("cusum");
  TCase *tc = tcase_create("config");
  tcase_add_test(tc, test_init_rejects_bad_config);
  suite_add_tcase(su, tc);

  tc = tcase_create("arl");
  tcase_set_timeout(tc, 60);
  tcase_add_loop_test(tc, test_arl_matches_published, 0,
                      (int)(sizeof arl_cases / sizeof arl_cases[0]));
  suite_add_tcase(su, tc);

  tc = tcase_create("change_time");
  tcase_set_timeout(tc, 30);
  tcase_add_loop_test(tc, test_change_time_noise_free, 0,
                      (int)(sizeof step_deltas / sizeof step_deltas[0]));
  tcase_add_loop_test(tc, test_change_time_noisy, 0, 2);
  suite_add_tcase(su, tc);

  tc = tcase_create("range");
  tcase_set_timeout(tc, 30);
  tcase_add_test(tc, test_huge_inputs);
  tcase_add_test(tc, test_random_full_range_invariants);
  suite_add_tcase(su, tc);

  tc = tcase_create("restart");
  tcase_add_test(tc, test_latch_and_restart);
  tcase_add_loop_test(tc, test_auto_restart_head_start, 0, 2);
  suite_add_tcase(su, tc);

  tc = tcase_create("counters");
  tcase_add_test(tc, test_counters_saturate_index_wraps);
  suite_add_tcase(su, tc);
  return su;
}

CANFDI_UNIT_MAIN(make_suite)
