/*
 * signal_demo.c — the foundation detectors on one synthetic signal
 * (`make demo`).
 *
 * The monitored quantity is a motor current I_A [mA] sampled at 1 kHz. It
 * follows its command u through a 30 ms first-order lag (the "plant"); the
 * firmware's model of that lag assumes 15 ms, so the residual
 * r = I_A - model(u) carries a model error during command steps, as real
 * residuals do. Into I_A, on top of white noise, the demo injects: an offset
 * step, command steps (no fault), a slow drift out and back, two spikes (one
 * too short to be a fault), and a variance increase. The supervisor side is
 * the firmware, in fixed point, on integer mA:
 *   limit    canfdi_limit on I_A (absolute limits, debounced 10 ms)
 *   adapt    |r| against canfdi_adapt's threshold, which grows with the
 *            command's rate of change, debounced 10 ms (canfdi_debounce)
 *   trend    canfdi_trend on r: rate of change, order 2, tau 200 ms
 *   var      canfdi_meanvar on the first difference of r (insensitive to
 *            mean shifts and drifts), clipped to +-6 sigma (an outlier is
 *            the limit check's business, not a variance), its sigma against
 *            a canfdi_limit
 *   cusum    canfdi_cusum on r, with mu0 and sigma learnt by
 *            canfdi_meanvar during the first second; samples are withheld
 *            while the command moves (canfdi_adapt_excitation), because the
 *            model error would add up in the sums
 * It prints the alarm timeline and, per injected change, the detection
 * delay of every detector. The signal is generated in double from a seeded
 * generator, so the run is reproducible: `signal_demo [seed]`.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "core/canfdi_fixp.h"
#include "detect/canfdi_adapt.h"
#include "detect/canfdi_cusum.h"
#include "detect/canfdi_limit.h"
#include "detect/canfdi_meanvar.h"
#include "detect/canfdi_trend.h"
#include "core/canfdi_debounce.h"

#define N_SAMPLES 8000U /* 8 s at 1 ms */
#define T_S 0.001
#define I0_MA 2000.0
#define SIGMA_MA 20.0
#define LEARN_N 1000U        /* learning phase of mu0 and sigma, samples */
#define TAU_PLANT_S 0.030    /* true lag of I_A behind u */
#define CUSUM_GATE_MA_S 50   /* withhold CUSUM samples above this excitation */
#define CUSUM_QUIET_N 200U   /* a CUSUM alarm burst ends after 200 ms quiet */

/* ------------------------------------------------------------------ */
/* Signal generation (host side, double precision)                    */
/* ------------------------------------------------------------------ */

static uint64_t rng_state;

static uint64_t splitmix64(void)
{
  uint64_t z = (rng_state += 0x9E3779B97F4A7C15U);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9U;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBU;
  return z ^ (z >> 31);
}

static double uniform01(void) /* in (0, 1) */
{
  return ((double)(splitmix64() >> 11) + 0.5) * (1.0 / 9007199254740992.0);
}

static double gauss(void) /* Box-Muller, one of the pair */
{
  const double two_pi = 6.283185307179586;
  return sqrt(-2.0 * log(uniform01())) * cos(two_pi * uniform01());
}

enum { CH_OFFSET, CH_SETPOINT, CH_DRIFT, CH_SPIKE_SHORT, CH_SPIKE, CH_VARIANCE, N_CHANGES };

typedef struct
{
  const char *name;
  double onset_s;
  const char *expect; /* the detector meant to catch it */
} change_t;

static const change_t changes[N_CHANGES] = {
    {"offset +40 mA (2 sd)", 1.5, "cusum"},
    {"command steps, no fault", 3.0, "(none)"},
    {"drift +-250 mA/s", 4.0, "trend"},
    {"spike +1200 mA, 5 ms", 6.0, "(none)"},
    {"spike +1200 mA, 15 ms", 6.3, "limit"},
    {"noise sigma x3", 7.0, "var"},
};

/* Command u [mA] at time t. */
static double command_mA(double t)
{
  return ((t >= 3.0) && (t < 3.5)) ? I0_MA + 800.0 : I0_MA;
}

/* Sensor fault added to I_A at time t (all but the noise). */
static double fault_mA(double t)
{
  double f = 0.0;
  if ((t >= 1.5) && (t < 2.5))
  {
    f += 40.0;
  }
  if ((t >= 4.0) && (t < 4.8))
  {
    f += 250.0 * (t - 4.0);
  }
  else if ((t >= 4.8) && (t < 5.6))
  {
    f += 200.0 - 250.0 * (t - 4.8);
  }
  if (((t >= 6.0) && (t < 6.005)) || ((t >= 6.3) && (t < 6.315)))
  {
    f += 1200.0;
  }
  return f;
}

static double noise_sigma_mA(double t)
{
  return (t >= 7.0) ? 3.0 * SIGMA_MA : SIGMA_MA;
}

static int32_t sample_u_mA[N_SAMPLES];
static int32_t sample_i_mA[N_SAMPLES];

static void generate(uint64_t seed)
{
  const double a = exp(-T_S / TAU_PLANT_S);
  double y = I0_MA; /* plant at rest */
  rng_state = seed;
  for (uint32_t k = 0U; k < N_SAMPLES; k++)
  {
    const double t = (double)k * T_S;
    const double u = command_mA(t);
    y = a * y + (1.0 - a) * u;
    sample_u_mA[k] = (int32_t)lround(u);
    sample_i_mA[k] = (int32_t)lround(y + fault_mA(t) + noise_sigma_mA(t) * gauss());
  }
}

/* ------------------------------------------------------------------ */
/* Event log                                                          */
/* ------------------------------------------------------------------ */

enum { D_LIMIT, D_ADAPT, D_TREND, D_VAR, D_CUSUM, N_DET };
static const char *const det_name[N_DET] = {"limit", "adapt", "trend", "var", "cusum"};
static long first_alarm[N_CHANGES][N_DET]; /* sample index, -1: none */
static unsigned false_alarms;              /* before the first change */

static double t_of(uint32_t k) { return (double)k * T_S; }

/* The change whose window (its onset up to the next onset) holds sample k. */
static int change_at(uint32_t k)
{
  int c = -1;
  for (int i = 0; i < N_CHANGES; i++)
  {
    if (t_of(k) >= changes[i].onset_s - 1e-9)
    {
      c = i;
    }
  }
  return c;
}

static void alarm_set(int det, uint32_t k)
{
  const int c = change_at(k);
  if (c < 0)
  {
    false_alarms++;
  }
  else if (first_alarm[c][det] < 0)
  {
    first_alarm[c][det] = (long)k;
  }
}

static void event(uint32_t k, int det, const char *what, const char *detail)
{
  printf("  %6.3f  %-5s  %-34s %s\n", t_of(k), det_name[det], what, detail);
}

/* ------------------------------------------------------------------ */
/* Supervisor (firmware modules, fixed point)                         */
/* ------------------------------------------------------------------ */

/* One debounce class for the absolute checks: 10 ms to fail, 10 ms to pass,
 * counting restarts from 0 on a change of symptom. */
#define DEB_10MS {10, -10, 1U, 1U, 0, 0, true, true}

static const canfdi_limit_cfg_t limit_cfg = {
    .max_set = 3000, .max_clear = 2950, .min_set = 1000, .min_clear = 1050,
    .max_enabled = true, .min_enabled = true, .deb = DEB_10MS,
};
/* Same debounced check on |r| with a fixed threshold: what adapt replaces. */
static const canfdi_limit_cfg_t fixed_r_cfg = {
    .max_set = 100, .max_clear = 100, .min_set = -100, .min_clear = -100,
    .max_enabled = true, .min_enabled = true, .deb = DEB_10MS,
};
static const canfdi_debounce_cfg_t adapt_deb_cfg = DEB_10MS;
/* Threshold 100 mA (5 sigma) at rest. The residual of a lag mismatch after a
 * command step du is at most du * exp(-t / 30 ms), so tau = 30 ms and
 * gain = tau + T = 0.031 s (Q16) keep the threshold above it (see
 * canfdi_adapt.h, "Choosing the parameters"). */
static const canfdi_adapt_cfg_t adapt_cfg = {
    .base = 100, .max = 5000, .gain = 2032 /* 0.031 s in Q16 */, .tau_us = 30000U,
    .gain_frac_bits = 16U,
};
/* Rate of r beyond +-100 mA/s for 200 ms; white noise alone gives a rate
 * sigma of ~5 mA/s at tau 200 ms, order 2 (canfdi_trend.h). */
static const canfdi_trend_cfg_t trend_cfg = {
    .tau_us = 200000U, .order = 2U, .rate_frac_bits = 0U,
    .rate_limit = {.max_set = 100, .max_clear = 60, .min_set = -100, .min_clear = -60,
                   .max_enabled = true, .min_enabled = true,
                   .deb = {200, -100, 1U, 1U, 0, 0, true, true}},
};

int main(int argc, char **argv)
{
  const uint64_t seed = (argc > 1) ? strtoull(argv[1], NULL, 0) : 20240601U;
  static canfdi_limit_t lim, fixed_r;
  static canfdi_adapt_t adapt;
  static canfdi_debounce_t adapt_deb;
  static canfdi_trend_t trend;
  static canfdi_meanvar_t learn, dvar;
  static canfdi_limit_t var_lim;
  static canfdi_limit_cfg_t var_cfg;
  static canfdi_cusum_t cusum;
  static uint32_t cusum_k[N_SAMPLES + 1U]; /* CUSUM index -> sample */
  int32_t st_lim = 0, st_adapt = 0, st_trend = 0, st_var = 0, st_fixed = 0;
  unsigned fixed_alarms = 0U, adapt_setpoint_alarms = 0U;
  bool cusum_on = false;
  bool burst[2] = {false, false};
  uint32_t last_alarm_k[2] = {0U, 0U};
  int64_t model_q16 = (int64_t)I0_MA * 65536; /* model output, mA, Q16 */
  int32_t r_prev = 0;
  int32_t dr_clip = INT32_MAX;
  int32_t r_max_setpoint = 0;
  double sigma_mA = 0.0;
  char buf[96];

  generate(seed);
  for (int c = 0; c < N_CHANGES; c++)
  {
    for (int d = 0; d < N_DET; d++)
    {
      first_alarm[c][d] = -1;
    }
  }
  if ((canfdi_limit_init(&lim, &limit_cfg) != CANFDI_OK) ||
      (canfdi_limit_init(&fixed_r, &fixed_r_cfg) != CANFDI_OK) ||
      (canfdi_adapt_init(&adapt, &adapt_cfg) != CANFDI_OK) ||
      (canfdi_debounce_init(&adapt_deb, &adapt_deb_cfg) != CANFDI_OK) ||
      (canfdi_trend_init(&trend, &trend_cfg) != CANFDI_OK) ||
      (canfdi_meanvar_init(&learn, CANFDI_Q31_RATIO(1, 200)) != CANFDI_OK) ||
      (canfdi_meanvar_init(&dvar, CANFDI_Q31_RATIO(1, 500)) != CANFDI_OK))
  {
    fprintf(stderr, "signal_demo: a detector rejected its configuration\n");
    return EXIT_FAILURE;
  }

  printf("canfdi signal demo: I_A = %.0f mA + noise (sigma %.0f mA), %u samples at 1 ms, seed %llu\n",
         I0_MA, SIGMA_MA, N_SAMPLES, (unsigned long long)seed);
  printf("residual r = I_A - model(command), model lag 15 ms vs true 30 ms; fixed point from here on\n");
  printf("   t [s]  det    event                              value vs threshold\n");

  for (uint32_t k = 0U; k < N_SAMPLES; k++)
  {
    const int32_t x = sample_i_mA[k];
    const int32_t u = sample_u_mA[k];
    int32_t r, thr, st;

    /* Model: first-order lag, alpha = T / (15 ms + T) = 1/16, Q16 state. */
    model_q16 += canfdi_mul_s64_q31(((int64_t)u * 65536) - model_q16, CANFDI_Q31_RATIO(1, 16));
    r = canfdi_sub_s32_sat(x, canfdi_sat_s64_to_s32(canfdi_asr64_rnd(model_q16, 16U)));

    /* limit: absolute limits on I_A. */
    st = canfdi_limit_step(&lim, x);
    if ((st == CANFDI_DEB_FAILED) && (st_lim != CANFDI_DEB_FAILED))
    {
      snprintf(buf, sizeof buf, "I_A %d mA, limits %d..%d", (int)x, (int)limit_cfg.min_set,
               (int)limit_cfg.max_set);
      event(k, D_LIMIT,
            (canfdi_limit_failed_side(&lim) == CANFDI_LIMIT_BELOW_MIN) ? "SET below min (debounced 10 ms)"
                                                                       : "SET above max (debounced 10 ms)",
            buf);
      alarm_set(D_LIMIT, k);
    }
    else if ((st == CANFDI_DEB_PASSED) && (st_lim == CANFDI_DEB_FAILED))
    {
      snprintf(buf, sizeof buf, "I_A %d mA", (int)x);
      event(k, D_LIMIT, "cleared", buf);
    }
    st_lim = st;

    /* adapt: |r| against the excitation-dependent threshold. */
    thr = canfdi_adapt_step(&adapt, u);
    st = canfdi_debounce_step(&adapt_deb, canfdi_adapt_exceeds(&adapt, r) ? CANFDI_DEB_REPORT_PREFAILED
                                                                          : CANFDI_DEB_REPORT_PREPASSED);
    if ((st == CANFDI_DEB_FAILED) && (st_adapt != CANFDI_DEB_FAILED))
    {
      snprintf(buf, sizeof buf, "|r| %d mA > %d mA", (int)canfdi_q31_abs(r), (int)thr);
      event(k, D_ADAPT, "SET (debounced 10 ms)", buf);
      alarm_set(D_ADAPT, k);
      if (change_at(k) == CH_SETPOINT)
      {
        adapt_setpoint_alarms++;
      }
    }
    else if ((st == CANFDI_DEB_PASSED) && (st_adapt == CANFDI_DEB_FAILED))
    {
      snprintf(buf, sizeof buf, "|r| %d mA, threshold %d mA", (int)canfdi_q31_abs(r), (int)thr);
      event(k, D_ADAPT, "cleared", buf);
    }
    st_adapt = st;

    /* The fixed-threshold check the adaptive one replaces (summary only). */
    st = canfdi_limit_step(&fixed_r, r);
    if ((st == CANFDI_DEB_FAILED) && (st_fixed != CANFDI_DEB_FAILED) && (change_at(k) == CH_SETPOINT))
    {
      fixed_alarms++;
    }
    st_fixed = st;
    if ((change_at(k) == CH_SETPOINT) && (canfdi_q31_abs(r) > r_max_setpoint))
    {
      r_max_setpoint = canfdi_q31_abs(r);
    }

    /* trend: rate of change of r. */
    st = canfdi_trend_step(&trend, r);
    if ((st == CANFDI_DEB_FAILED) && (st_trend != CANFDI_DEB_FAILED))
    {
      snprintf(buf, sizeof buf, "dr/dt %+d mA/s, limit +-%d", (int)canfdi_trend_rate(&trend),
               (int)trend_cfg.rate_limit.max_set);
      event(k, D_TREND,
            (canfdi_trend_rate(&trend) < 0) ? "SET falling (debounced 200 ms)" : "SET rising (debounced 200 ms)",
            buf);
      alarm_set(D_TREND, k);
    }
    else if ((st == CANFDI_DEB_PASSED) && (st_trend == CANFDI_DEB_FAILED))
    {
      snprintf(buf, sizeof buf, "dr/dt %+d mA/s", (int)canfdi_trend_rate(&trend));
      event(k, D_TREND, "cleared", buf);
    }
    st_trend = st;

    /* var: sigma of the first difference of r (sqrt(2) sigma at rest),
     * clipped once sigma is known. */
    if (k > 0U)
    {
      canfdi_meanvar_step(&dvar, canfdi_clamp_s32(canfdi_sub_s32_sat(r, r_prev), -dr_clip, dr_clip));
    }
    r_prev = r;
    if (k < LEARN_N)
    {
      canfdi_meanvar_step(&learn, r);
    }
    else if (k == LEARN_N)
    {
      /* End of learning: configure CUSUM and the sigma limit. */
      const uint32_t sigma_q10 = canfdi_meanvar_std_q10(&learn);
      const canfdi_cusum_cfg_t ccfg = {
          .mu0 = canfdi_meanvar_mean(&learn),
          .sigma_q10 = (sigma_q10 > 0U) ? sigma_q10 : 1U,
          .k_q16 = 1U << 16, /* k = 1 sigma: tuned for a 2 sigma shift */
          .h_q16 = 6U << 16, /* h = 6 sigma: in-control ARL ~ 4e5 samples */
          .head_start_q16 = 0U,
          .restart = CANFDI_CUSUM_RESTART_AUTO,
      };
      sigma_mA = (double)sigma_q10 / 1024.0;
      dr_clip = (int32_t)((sigma_q10 * 8689U) >> 20); /* 6 sqrt(2) sigma, in mA */
      /* sigma of the difference is sqrt(2) sigma: alarm at 2x that. */
      var_cfg.max_set = (int32_t)((sigma_q10 * 2896U) >> 10); /* 2 sqrt(2) in Q10 */
      var_cfg.max_clear = (int32_t)((sigma_q10 * 2172U) >> 10); /* 1.5 sqrt(2) */
      var_cfg.max_enabled = true;
      var_cfg.min_enabled = false;
      var_cfg.deb = (canfdi_debounce_cfg_t){20, -20, 1U, 1U, 0, 0, true, true};
      if ((canfdi_cusum_init(&cusum, &ccfg) != CANFDI_OK) ||
          (canfdi_limit_init(&var_lim, &var_cfg) != CANFDI_OK))
      {
        fprintf(stderr, "signal_demo: learnt sigma unusable\n");
        return EXIT_FAILURE;
      }
      cusum_on = true;
      snprintf(buf, sizeof buf, "mu0 %+.1f mA, sigma %.1f mA", (double)ccfg.mu0, sigma_mA);
      printf("  %6.3f  %-5s  %-34s %s\n", t_of(k), "learn", "meanvar: cusum armed", buf);
    }
    if (k >= LEARN_N)
    {
      st = canfdi_limit_step(&var_lim, (int32_t)canfdi_meanvar_std_q10(&dvar));
      if ((st == CANFDI_DEB_FAILED) && (st_var != CANFDI_DEB_FAILED))
      {
        snprintf(buf, sizeof buf, "sd(dr) %.1f mA > %.1f mA", (double)canfdi_meanvar_std_q10(&dvar) / 1024.0,
                 (double)var_cfg.max_set / 1024.0);
        event(k, D_VAR, "SET variance up (debounced 20 ms)", buf);
        alarm_set(D_VAR, k);
      }
      else if ((st == CANFDI_DEB_PASSED) && (st_var == CANFDI_DEB_FAILED))
      {
        snprintf(buf, sizeof buf, "sd(dr) %.1f mA", (double)canfdi_meanvar_std_q10(&dvar) / 1024.0);
        event(k, D_VAR, "cleared", buf);
      }
      st_var = st;
    }

    /* cusum: mean shifts of r, withheld while the command moves. */
    if (cusum_on && (canfdi_adapt_excitation(&adapt) <= CUSUM_GATE_MA_S))
    {
      const uint32_t side = canfdi_cusum_step(&cusum, r);
      cusum_k[canfdi_cusum_step_index(&cusum)] = k;
      if (side != CANFDI_CUSUM_NONE)
      {
        const int s = (side == CANFDI_CUSUM_HI) ? 0 : 1;
        if (!burst[s])
        {
          const canfdi_cusum_alarm_t al = canfdi_cusum_last_alarm(&cusum);
          const uint32_t first = al.change_step + 1U; /* first affected sample */
          const double sd_q16 = sigma_mA * 65536.0;
          snprintf(buf, sizeof buf, "S %.1f sd > h %.1f sd, shift %+.0f mA", (double)al.sum_q16 / sd_q16,
                   (double)canfdi_cusum_threshold_q16(&cusum) / sd_q16, (double)al.shift_q16 / 65536.0);
          {
            char what[48];
            snprintf(what, sizeof what, "SET %s, change est. %.3f s", (s == 0) ? "up" : "down",
                     t_of(cusum_k[first <= canfdi_cusum_step_index(&cusum) ? first : 0U]));
            event(k, D_CUSUM, what, buf);
          }
          alarm_set(D_CUSUM, k);
          burst[s] = true;
        }
        last_alarm_k[s] = k;
      }
    }
    for (int s = 0; s < 2; s++)
    {
      if (burst[s] && (k - last_alarm_k[s] >= CUSUM_QUIET_N))
      {
        event(k, D_CUSUM, (s == 0) ? "cleared up (200 ms without alarm)" : "cleared down (200 ms without alarm)",
              "");
        burst[s] = false;
      }
    }
  }

  printf("summary: first alarm after each injected change, delay in ms ('-': none before the next change)\n");
  printf("  %-24s %7s  %-6s", "injected change", "t [s]", "target");
  for (int d = 0; d < N_DET; d++)
  {
    printf(" %6s", det_name[d]);
  }
  printf("\n");
  for (int c = 0; c < N_CHANGES; c++)
  {
    const uint32_t onset = (uint32_t)lround(changes[c].onset_s / T_S);
    printf("  %-24s %7.3f  %-6s", changes[c].name, changes[c].onset_s, changes[c].expect);
    for (int d = 0; d < N_DET; d++)
    {
      if (first_alarm[c][d] < 0)
      {
        printf(" %6s", "-");
      }
      else
      {
        printf(" %6ld", first_alarm[c][d] - (long)onset);
      }
    }
    printf("\n");
  }
  printf("  command steps: a fixed |r| > 100 mA check (same debounce) alarms %u times (|r| up to %d mA),\n"
         "  the adaptive threshold %u times; alarms before the first change: %u\n",
         fixed_alarms, (int)r_max_setpoint, adapt_setpoint_alarms, false_alarms);
  return EXIT_SUCCESS;
}
