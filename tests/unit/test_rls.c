/*
 * test_rls.c — unit tests of canfdi_rls (UD-factorised RLS with forgetting).
 *
 * What is proven:
 *   - configuration domain (table);
 *   - noise-free data: theta converges to the truth to ~1e-6 relative for
 *     every n = 1..CANFDI_CFG_RLS_MAX_PARAMS (the xf arithmetic carries
 *     ~2^-30 relative per operation);
 *   - noisy data: theta AND the covariance P follow a double-precision
 *     covariance-form RLS fed the same Q16.16 samples (the mathematical
 *     twin of the UD form) to 1e-5 relative — the UD factorisation and the
 *     scaling by the normalising shifts are exact up to rounding;
 *   - the same physical data with other normalising shifts give the same
 *     physical theta (shifts only change the internal scaling);
 *   - 100 000 updates with a constant regressor: with the gate, no update
 *     and no change of P; without the gate, the trace bound holds every
 *     step, D stays > 0 (invariants checked every step), and afterwards the
 *     estimator re-converges to new parameters;
 *   - an abrupt parameter change is followed within the forgetting memory;
 *   - reset restores theta0 and P0 (or keeps theta), and recovers;
 *   - nearly collinear regressors keep the factorisation valid;
 *   - badly scaled regressors (normalised sizes from 2^-6 to 2^6, i.e. the
 *     caller's shifts off by up to 2^6 either way) still follow the double
 *     twin to the same tolerances;
 *   - 200 000 excited updates (the scale c0 crosses its exponent window
 *     ~20 times) keep the invariants and the twin's theta and P;
 *   - the regressor block's fixed format and its dynamic fallback (shifts
 *     outside -20..10, normalised regressors beyond 16, the format
 *     changing from update to update) follow the twin alike;
 *   - the excitation measure reads the mean-square deviation of a square
 *     wave in either format, and the clip at 128^2;
 *   - 10^6 updates of a constant, noise-free regressor: with the gate
 *     nothing changes, without it the (tracked) trace bound holds.
 */
#include <check.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "model/canfdi_rls.h"
#include "unit_main.h"
#include "unit_q16.h"

/* figures are printed before the checks; flush so an abort cannot lose them */
#define SHOW(...) (void)(printf(__VA_ARGS__), fflush(stdout))

#define CHECK(cond)                                         \
  do {                                                      \
    if (!(cond)) {                                          \
      ck_abort_msg("%s:%d: %s", __FILE__, __LINE__, #cond); \
    }                                                       \
  } while (0)

#define NMAX ((int)CANFDI_CFG_RLS_MAX_PARAMS)
#define Q16 65536.0

/* ---- deterministic generator ------------------------------------------- */
static uint64_t rng_s;
static void rng_seed(uint64_t s)
{
  rng_s = s * 0x9E3779B97F4A7C15ULL + 1U;
}
static double rng_u(void) /* [0, 1) */
{
  rng_s ^= rng_s << 13;
  rng_s ^= rng_s >> 7;
  rng_s ^= rng_s << 17;
  return (double)(rng_s >> 11) * (1.0 / 9007199254740992.0);
}
static double rng_n(void)
{
  const double u1 = rng_u() + 1e-300;
  const double u2 = rng_u();
  return sqrt(-2.0 * log(u1)) * cos(6.283185307179586 * u2);
}

static void base_cfg(canfdi_rls_cfg_t *c, int n)
{
  int i;
  memset(c, 0, sizeof *c);
  c->n_params = (uint8_t)n;
  c->y_shift = 2;
  for (i = 0; i < NMAX; i++) {
    c->phi_shift[i] = (int8_t)(i % 3 - 1); /* -1, 0, 1, ... */
  }
  c->forget_q31 = CANFDI_Q31_RATIO(1, 100);
  c->p0_q16 = 100 * 65536;
  c->trace_max_q16 = 2000 * 65536;
  c->excite_min_q16 = 0;
  c->excite_shift = 6U;
}

/* ---- configuration ------------------------------------------------------ */

typedef struct {
  int field;
  int32_t value;
  int32_t expect;
} cfg_case_t;

enum { F_NONE, F_N, F_SHIFT, F_YSHIFT, F_FORGET, F_P0, F_TRMAX, F_EXMIN, F_EXSHIFT };

static const cfg_case_t cfg_cases[] = {
    {F_NONE, 0, CANFDI_OK},
    {F_N, 0, -CANFDI_EINVAL},
    {F_N, 1, CANFDI_OK},
    {F_N, NMAX, CANFDI_OK},
    {F_N, NMAX + 1, -CANFDI_EINVAL},
    {F_SHIFT, 33, -CANFDI_EINVAL},
    {F_SHIFT, -33, -CANFDI_EINVAL},
    {F_SHIFT, 32, CANFDI_OK},
    {F_YSHIFT, -40, -CANFDI_EINVAL},
    {F_FORGET, -1, -CANFDI_EINVAL},
    {F_FORGET, 0, CANFDI_OK},
    {F_FORGET, (int32_t)1 << 30, CANFDI_OK},
    {F_FORGET, ((int32_t)1 << 30) + 1, -CANFDI_EINVAL},
    {F_P0, 0, -CANFDI_EINVAL},
    {F_P0, -5, -CANFDI_EINVAL},
    {F_TRMAX, 100 * 65536, -CANFDI_EINVAL}, /* < n p0 for n = 3 */
    {F_TRMAX, 300 * 65536, CANFDI_OK},
    {F_EXMIN, -1, -CANFDI_EINVAL},
    {F_EXMIN, (int32_t)1 << 30, CANFDI_OK},
    {F_EXMIN, ((int32_t)1 << 30) + 1, -CANFDI_EINVAL},
    {F_EXSHIFT, 0, -CANFDI_EINVAL},
    {F_EXSHIFT, 17, -CANFDI_EINVAL},
    {F_EXSHIFT, 16, CANFDI_OK},
};

START_TEST(test_cfg_domain)
{
  const cfg_case_t *c = &cfg_cases[_i];
  canfdi_rls_cfg_t cfg;
  canfdi_rls_t r;
  base_cfg(&cfg, 3);
  switch (c->field) {
  case F_N: cfg.n_params = (uint8_t)c->value; break;
  case F_SHIFT: cfg.phi_shift[0] = (int8_t)c->value; break;
  case F_YSHIFT: cfg.y_shift = (int8_t)c->value; break;
  case F_FORGET: cfg.forget_q31 = c->value; break;
  case F_P0: cfg.p0_q16 = c->value; break;
  case F_TRMAX: cfg.trace_max_q16 = c->value; break;
  case F_EXMIN: cfg.excite_min_q16 = c->value; break;
  case F_EXSHIFT: cfg.excite_shift = (uint8_t)c->value; break;
  default: break;
  }
  ck_assert_int_eq(canfdi_rls_init(&r, &cfg), c->expect);
  ck_assert_int_eq(canfdi_rls_init(NULL, &cfg), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_rls_init(&r, NULL), -CANFDI_EINVAL);
}
END_TEST

/* ---- data generator ----------------------------------------------------- */

/* Regressor i: a random signal of physical size 2^shift_i (so that it is
 * O(1) after normalisation), rounded to Q16.16. */
static void gen_phi(int n, const canfdi_rls_cfg_t *c, int32_t phi[])
{
  int i;
  for (i = 0; i < n; i++) {
    phi[i] = q16(ldexp(2.0 * rng_u() - 1.0, c->phi_shift[i]) + ((i == n - 1) ? 0.3 : 0.0));
  }
}

static double dot_phys(int n, const double th[], const int32_t phi[])
{
  double y = 0.0;
  int i;
  for (i = 0; i < n; i++) {
    y += th[i] * (double)phi[i] / Q16;
  }
  return y;
}

static void gen_theta(int n, double th[])
{
  int i;
  for (i = 0; i < n; i++) {
    th[i] = (rng_u() < 0.5 ? -1.0 : 1.0) * (0.2 + 3.0 * rng_u());
  }
}

static double theta_phys(const canfdi_rls_t *r, int i)
{
  return (double)canfdi_rls_theta_qn(r, (unsigned)i, 20U) / 1048576.0;
}

/* ---- convergence, noise-free -------------------------------------------- */

START_TEST(test_converge_exact)
{
  const int n = _i;
  canfdi_rls_cfg_t c;
  canfdi_rls_t r;
  double th[NMAX];
  int k;
  int i;
  rng_seed(100U + (uint64_t)n);
  base_cfg(&c, n);
  ck_assert_int_eq(canfdi_rls_init(&r, &c), CANFDI_OK);
  gen_theta(n, th);
  for (k = 0; k < 600; k++) {
    int32_t phi[NMAX];
    gen_phi(n, &c, phi);
    (void)canfdi_rls_update(&r, phi, q16(dot_phys(n, th, phi)));
    CHECK(canfdi_rls_invariants_hold(&r));
  }
  /* The only noise is the rounding of y to Q16.16 (0.29 LSB rms); with
   * lambda = 0.99 the estimate averages ~100 samples of O(1) regressors:
   * error ~ 1e-6 absolute. Allow 2e-5. */
  for (i = 0; i < n; i++) {
    const double est = theta_phys(&r, i);
    if (!(fabs(est - th[i]) <= 2e-5 * fmax(1.0, fabs(th[i])) * ldexp(1.0, c.y_shift - c.phi_shift[i]))) {
      ck_abort_msg("n %d param %d: est %.9g true %.9g", n, i, est, th[i]);
    }
  }
  ck_assert_uint_eq(canfdi_rls_diag(&r)->updates, 600U);
  ck_assert_uint_eq(canfdi_rls_diag(&r)->saturations, 0U);
}
END_TEST

/* ---- twin: covariance RLS in double ------------------------------------- */

typedef struct {
  int n;
  double lam;
  double th[NMAX];
  double p[NMAX][NMAX];
} dbl_rls_t;

/* Plain covariance RLS in normalised coordinates (double is enough for the
 * well-conditioned data of this test). */
static void dbl_update(dbl_rls_t *d, const double phi[], double y)
{
  double pphi[NMAX];
  double den = d->lam;
  double e = y;
  int i;
  int j;
  for (i = 0; i < d->n; i++) {
    pphi[i] = 0.0;
    for (j = 0; j < d->n; j++) {
      pphi[i] += d->p[i][j] * phi[j];
    }
    den += phi[i] * pphi[i];
    e -= d->th[i] * phi[i];
  }
  for (i = 0; i < d->n; i++) {
    d->th[i] += pphi[i] / den * e;
  }
  for (i = 0; i < d->n; i++) {
    for (j = 0; j < d->n; j++) {
      d->p[i][j] = (d->p[i][j] - pphi[i] * pphi[j] / den) / d->lam;
    }
  }
}

START_TEST(test_twin_double)
{
  const int n = _i;
  canfdi_rls_cfg_t c;
  canfdi_rls_t r;
  dbl_rls_t d;
  double th[NMAX];
  double worst_th = 0.0;
  double worst_p = 0.0;
  int k;
  int i;
  int j;
  rng_seed(200U + (uint64_t)n);
  base_cfg(&c, n);
  c.forget_q31 = CANFDI_Q31_RATIO(2, 100);
  ck_assert_int_eq(canfdi_rls_init(&r, &c), CANFDI_OK);
  memset(&d, 0, sizeof d);
  d.n = n;
  d.lam = 1.0 - (double)c.forget_q31 / 2147483648.0;
  for (i = 0; i < n; i++) {
    d.p[i][i] = (double)c.p0_q16 / Q16;
  }
  gen_theta(n, th);
  for (k = 0; k < 3000; k++) {
    int32_t phi[NMAX];
    double phin[NMAX];
    int32_t y;
    gen_phi(n, &c, phi);
    y = q16(dot_phys(n, th, phi) + 0.05 * rng_n() + ((k > 1500) ? 0.5 : 0.0));
    for (i = 0; i < n; i++) {
      phin[i] = ldexp((double)phi[i] / Q16, -c.phi_shift[i]);
    }
    (void)canfdi_rls_update(&r, phi, y);
    dbl_update(&d, phin, ldexp((double)y / Q16, -c.y_shift));
    if ((k % 50) == 49) {
      for (i = 0; i < n; i++) {
        /* physical theta; the double twin is normalised */
        const double tp = ldexp(d.th[i], c.y_shift - c.phi_shift[i]);
        const double err = fabs(theta_phys(&r, i) - tp) / fmax(1.0, fabs(tp));
        worst_th = fmax(worst_th, err);
        for (j = 0; j < n; j++) {
          const double pf = (double)canfdi_rls_cov_qn(&r, (unsigned)i, (unsigned)j, 24U) / 16777216.0;
          worst_p = fmax(worst_p, fabs(pf - d.p[i][j]) / fmax(1e-3, sqrt(d.p[i][i] * d.p[j][j])));
        }
      }
    }
  }
  SHOW("rls twin n=%d: max |theta - theta_double| %.3g (rel), max |P - P_double| %.3g (rel to sqrt(PiiPjj))\n",
         n, worst_th, worst_p);
  /* theta read-out has 2^-20 resolution (~1e-6), P read-out 2^-24 against
   * P ~ 1e-2: allow 1e-5 for theta and 1e-4 for P. */
  CHECK(worst_th <= 1e-5);
  CHECK(worst_p <= 1e-4);
}
END_TEST

/* ---- normalisation invariance ------------------------------------------- */

START_TEST(test_shift_invariance)
{
  canfdi_rls_cfg_t c1;
  canfdi_rls_cfg_t c2;
  canfdi_rls_t r1;
  canfdi_rls_t r2;
  double th[4] = {1.25, -0.5, 2.0, 0.125};
  int k;
  int i;
  rng_seed(7U);
  base_cfg(&c1, 4);
  base_cfg(&c2, 4);
  c1.forget_q31 = 0; /* no forgetting: the exact LS solution, P0 aside */
  c2.forget_q31 = 0;
  c1.p0_q16 = 1000 * 65536;
  c2.p0_q16 = 1000 * 65536;
  c1.trace_max_q16 = 4000 * 65536;
  c2.trace_max_q16 = 4000 * 65536;
  for (i = 0; i < 4; i++) {
    c1.phi_shift[i] = 0;
    c2.phi_shift[i] = (int8_t)(3 * i - 4);
    /* the prior theta0 = truth: P0 = p0 I means a different physical
     * prior weight for each scaling (by 4^shift), which would otherwise
     * bias the two differently by ~ theta 4^shift / (p0 N / 3) */
    c1.theta0_q16[i] = q16(th[i]);
    c2.theta0_q16[i] = q16(th[i]);
  }
  c2.y_shift = 5;
  ck_assert_int_eq(canfdi_rls_init(&r1, &c1), CANFDI_OK);
  ck_assert_int_eq(canfdi_rls_init(&r2, &c2), CANFDI_OK);
  for (k = 0; k < 2000; k++) {
    int32_t phi[4];
    gen_phi(4, &c1, phi);
    {
      const int32_t y = q16(dot_phys(4, th, phi) + 0.01 * rng_n());
      (void)canfdi_rls_update(&r1, phi, y);
      (void)canfdi_rls_update(&r2, phi, y);
    }
  }
  /* Without forgetting both compute the same least-squares solution (the
   * prior is at the truth): same theta to 1e-5 relative, and both near the
   * truth within the noise (0.01 / sqrt(2000 / 3) ~ 4e-4 per parameter,
   * allow 5 sigma). */
  for (i = 0; i < 4; i++) {
    const double a = theta_phys(&r1, i);
    const double b = theta_phys(&r2, i);
    CHECK(fabs(a - b) <= 1e-5 * fabs(th[i]) + 2e-6);
    CHECK(fabs(a - th[i]) <= 2e-3);
  }
}
END_TEST

/* ---- wind-up ------------------------------------------------------------ */

/* A constant regressor (plus sensor noise of 1e-4 normalised) for 100 000
 * updates. _i == 0: gate on; _i == 1: gate off (trace bound only). */
START_TEST(test_no_excitation)
{
  const bool gate = (_i == 0);
  canfdi_rls_cfg_t c;
  canfdi_rls_t r;
  double th[3] = {1.0, -2.0, 0.5};
  double th2[3] = {1.3, -2.0, 0.4};
  int32_t tr0;
  int32_t tr_at_1000 = 0;
  uint32_t upd_at_1000 = 0U;
  int32_t trmax_seen = 0;
  long k;
  int i;
  rng_seed(11U);
  base_cfg(&c, 3);
  c.excite_min_q16 = gate ? (int32_t)(1e-3 * Q16) : 0;
  ck_assert_int_eq(canfdi_rls_init(&r, &c), CANFDI_OK);
  /* converge with excitation first */
  for (k = 0; k < 1000; k++) {
    int32_t phi[3];
    gen_phi(3, &c, phi);
    (void)canfdi_rls_update(&r, phi, q16(dot_phys(3, th, phi) + 0.01 * rng_n()));
  }
  tr0 = canfdi_rls_trace_q16(&r);
  {
    const uint32_t upd0 = canfdi_rls_diag(&r)->updates;
    int32_t phi_c[3] = {q16(0.4), q16(0.7), q16(1.1)};
    for (k = 0; k < 100000; k++) {
      int32_t phi[3];
      for (i = 0; i < 3; i++) {
        phi[i] = phi_c[i] + q16(ldexp(1e-4 * rng_n(), c.phi_shift[i]));
      }
      (void)canfdi_rls_update(&r, phi, q16(dot_phys(3, th, phi) + 0.01 * rng_n()));
      CHECK(canfdi_rls_invariants_hold(&r));
      if (k == 999) {
        tr_at_1000 = canfdi_rls_trace_q16(&r);
        upd_at_1000 = canfdi_rls_diag(&r)->updates;
      }
      {
        const int32_t t = canfdi_rls_trace_q16(&r);
        trmax_seen = (t > trmax_seen) ? t : trmax_seen;
      }
    }
    SHOW("rls no-excitation (%s): trace before %.4g, max during %.4g (bound %.4g), skipped %u, clips %u\n",
           gate ? "gate" : "no gate", (double)tr0 / Q16, (double)trmax_seen / Q16, (double)c.trace_max_q16 / Q16,
           canfdi_rls_diag(&r)->skipped, canfdi_rls_diag(&r)->trace_clips);
    if (gate) {
      /* The change from random to constant regressors is itself excitation
       * until the running means (memory 2^6 updates) have settled: the
       * filtered deviation decays from ~0.3 to the 1e-3 threshold in
       * ~64 ln(300) ~ 370 updates, then the gate stays shut (noise alone
       * gives a mean square ~1e-8). */
      ck_assert_uint_le(canfdi_rls_diag(&r)->updates - upd0, 600U);
      ck_assert_uint_ge(canfdi_rls_diag(&r)->skipped, 99400U);
      ck_assert_uint_eq(canfdi_rls_diag(&r)->updates, upd_at_1000);
      ck_assert_int_eq(canfdi_rls_trace_q16(&r), tr_at_1000);
    } else {
      /* forgetting inflates P until the bound clips it */
      ck_assert_uint_gt(canfdi_rls_diag(&r)->trace_clips, 0U);
      CHECK((int64_t)trmax_seen <= (int64_t)c.trace_max_q16 + (c.trace_max_q16 >> 19));
    }
    /* the estimate did not diverge: predictions along phi_c still right */
    {
      double pred = 0.0;
      for (i = 0; i < 3; i++) {
        pred += theta_phys(&r, i) * (double)phi_c[i] / Q16;
      }
      CHECK(fabs(pred - dot_phys(3, th, phi_c)) < 0.05);
    }
  }
  /* excitation again, with changed parameters: re-converges */
  for (k = 0; k < 1500; k++) {
    int32_t phi[3];
    gen_phi(3, &c, phi);
    (void)canfdi_rls_update(&r, phi, q16(dot_phys(3, th2, phi) + 0.01 * rng_n()));
    CHECK(canfdi_rls_invariants_hold(&r));
  }
  for (i = 0; i < 3; i++) {
    /* noise 0.01 over a memory of 100 samples: sigma ~ 1e-3 x scale */
    CHECK(fabs(theta_phys(&r, i) - th2[i]) <= 0.01 * ldexp(1.0, c.y_shift - c.phi_shift[i]));
  }
}
END_TEST

/* ---- tracking ----------------------------------------------------------- */

START_TEST(test_tracking)
{
  canfdi_rls_cfg_t c;
  canfdi_rls_t r;
  double th[2] = {1.5, 0.33};
  int k;
  int reach = -1;
  rng_seed(5U);
  base_cfg(&c, 2);
  c.phi_shift[0] = 0;
  c.phi_shift[1] = 0;
  c.excite_min_q16 = (int32_t)(1e-3 * Q16);
  ck_assert_int_eq(canfdi_rls_init(&r, &c), CANFDI_OK);
  for (k = 0; k < 2000; k++) {
    int32_t phi[2];
    if (k == 1000) {
      th[0] *= 1.1;
    }
    gen_phi(2, &c, phi);
    (void)canfdi_rls_update(&r, phi, q16(dot_phys(2, th, phi) + 0.002 * rng_n()));
    if ((k > 1000) && (reach < 0) && (theta_phys(&r, 0) >= 1.5 * 1.05)) {
      reach = k - 1000;
    }
  }
  SHOW("rls tracking: +10 %% step reaches +5 %% after %d updates (lambda 0.99)\n", reach);
  /* With lambda = 0.99 and white regressors, the old data's weight halves
   * every ln 2 / 0.01 = 69 updates: +5 % (half the step) after ~70. */
  CHECK((reach > 0) && (reach <= 150));
  CHECK(fabs(theta_phys(&r, 0) - 1.65) <= 0.005);
}
END_TEST

/* ---- reset ---------------------------------------------------------------- */

START_TEST(test_reset)
{
  canfdi_rls_cfg_t c;
  canfdi_rls_t r;
  double th[3] = {0.9, -1.1, 2.2};
  int k;
  int i;
  rng_seed(3U);
  base_cfg(&c, 3);
  c.theta0_q16[0] = q16(0.5);
  c.theta0_q16[1] = q16(-0.25);
  c.theta0_q16[2] = q16(1.0);
  ck_assert_int_eq(canfdi_rls_init(&r, &c), CANFDI_OK);
  for (i = 0; i < 3; i++) {
    ck_assert_int_eq(canfdi_rls_theta_qn(&r, (unsigned)i, 16U), c.theta0_q16[i]);
  }
  for (k = 0; k < 800; k++) {
    int32_t phi[3];
    gen_phi(3, &c, phi);
    (void)canfdi_rls_update(&r, phi, q16(dot_phys(3, th, phi)));
  }
  CHECK(canfdi_rls_trace_q16(&r) < c.p0_q16);
  /* covariance reset keeps theta */
  {
    int32_t keep[3];
    for (i = 0; i < 3; i++) {
      keep[i] = canfdi_rls_theta_qn(&r, (unsigned)i, 16U);
    }
    canfdi_rls_reset(&r, true);
    for (i = 0; i < 3; i++) {
      ck_assert_int_eq(canfdi_rls_theta_qn(&r, (unsigned)i, 16U), keep[i]);
      ck_assert_int_eq(canfdi_rls_cov_qn(&r, (unsigned)i, (unsigned)i, 16U), c.p0_q16);
    }
    ck_assert_int_eq(canfdi_rls_cov_qn(&r, 0U, 2U, 16U), 0);
  }
  /* full reset, then recovery from theta0 */
  canfdi_rls_reset(&r, false);
  ck_assert_uint_eq(canfdi_rls_diag(&r)->resets, 2U);
  for (i = 0; i < 3; i++) {
    ck_assert_int_eq(canfdi_rls_theta_qn(&r, (unsigned)i, 16U), c.theta0_q16[i]);
  }
  ck_assert_int_eq(canfdi_rls_trace_q16(&r), 3 * c.p0_q16);
  for (k = 0; k < 300; k++) {
    int32_t phi[3];
    gen_phi(3, &c, phi);
    (void)canfdi_rls_update(&r, phi, q16(dot_phys(3, th, phi)));
  }
  for (i = 0; i < 3; i++) {
    CHECK(fabs(theta_phys(&r, i) - th[i]) <= 1e-4 * ldexp(1.0, c.y_shift - c.phi_shift[i]));
  }
}
END_TEST

/* ---- ill-conditioning ----------------------------------------------------- */

START_TEST(test_collinear)
{
  /* phi2 = phi1 + 1e-4 noise: the sum theta1 + theta2 is well determined,
   * the difference hardly. P must stay positive definite, the prediction
   * must stay right and the sum must converge. */
  canfdi_rls_cfg_t c;
  canfdi_rls_t r;
  int k;
  rng_seed(9U);
  base_cfg(&c, 2);
  c.phi_shift[0] = 0;
  c.phi_shift[1] = 0;
  c.y_shift = 0;
  ck_assert_int_eq(canfdi_rls_init(&r, &c), CANFDI_OK);
  for (k = 0; k < 20000; k++) {
    int32_t phi[2];
    const double x = 2.0 * rng_u() - 1.0;
    phi[0] = q16(x);
    phi[1] = q16(x + 1e-4 * rng_n());
    (void)canfdi_rls_update(&r, phi, q16(0.7 * x + 0.4 * (double)phi[1] / Q16));
    CHECK(canfdi_rls_invariants_hold(&r));
  }
  CHECK(fabs(theta_phys(&r, 0) + theta_phys(&r, 1) - 1.1) < 1e-3);
  CHECK(canfdi_rls_d(&r, 0U).m > 0);
  CHECK(canfdi_rls_d(&r, 1U).m > 0);
  SHOW("rls collinear: trace clips %u, D0 %.3g, D1 %.3g\n", canfdi_rls_diag(&r)->trace_clips,
         ldexp((double)canfdi_rls_d(&r, 0U).m, canfdi_rls_d(&r, 0U).e),
         ldexp((double)canfdi_rls_d(&r, 1U).m, canfdi_rls_d(&r, 1U).e));
}
END_TEST

/* ---- badly scaled regressors -------------------------------------------- */

/* The shifts say "O(1)" but the regressors are 2^-6, 2^-2, 2^2 and 2^6 in
 * normalised units: P's diagonal then spans 2^24, the theta block 2^12. */
START_TEST(test_bad_scaling)
{
  static const int sc[4] = {-6, -2, 2, 6};
  canfdi_rls_cfg_t c;
  canfdi_rls_t r;
  dbl_rls_t d;
  double th[4] = {0.7, -1.3, 2.1, 0.4};
  double worst_th = 0.0;
  double worst_p = 0.0;
  int k;
  int i;
  int j;
  rng_seed(77U);
  base_cfg(&c, 4);
  for (i = 0; i < 4; i++) {
    c.phi_shift[i] = 0;
  }
  c.y_shift = 0;
  c.forget_q31 = CANFDI_Q31_RATIO(2, 100);
  c.trace_max_q16 = 30000 * 65536;
  ck_assert_int_eq(canfdi_rls_init(&r, &c), CANFDI_OK);
  memset(&d, 0, sizeof d);
  d.n = 4;
  d.lam = 1.0 - (double)c.forget_q31 / 2147483648.0;
  for (i = 0; i < 4; i++) {
    d.p[i][i] = (double)c.p0_q16 / Q16;
  }
  for (k = 0; k < 3000; k++) {
    int32_t phi[4];
    double phin[4];
    double y = 0.0;
    int32_t yq;
    for (i = 0; i < 4; i++) {
      phi[i] = q16(ldexp(2.0 * rng_u() - 1.0, sc[i]));
      phin[i] = (double)phi[i] / Q16;
      y += th[i] * phin[i];
    }
    yq = q16(y + 0.01 * rng_n());
    (void)canfdi_rls_update(&r, phi, yq);
    dbl_update(&d, phin, (double)yq / Q16);
    CHECK(canfdi_rls_invariants_hold(&r));
    if ((k % 50) == 49) {
      for (i = 0; i < 4; i++) {
        const double err = fabs(theta_phys(&r, i) - d.th[i]) / fmax(1.0, fabs(d.th[i]));
        worst_th = fmax(worst_th, err);
        for (j = 0; j < 4; j++) {
          /* read-out format with ~29 bits below sqrt(P_ii P_jj) */
          const double sc2 = sqrt(d.p[i][i] * d.p[j][j]);
          const int fr = (int)fmin(31.0, fmax(0.0, 29.0 - ceil(log2(sc2))));
          const double pf = ldexp((double)canfdi_rls_cov_qn(&r, (unsigned)i, (unsigned)j, (unsigned)fr), -fr);
          worst_p = fmax(worst_p, fabs(pf - d.p[i][j]) / sc2);
        }
      }
    }
  }
  SHOW("rls bad scaling: max |theta - theta_double| %.3g (rel), max |P - P_double| %.3g (rel)\n", worst_th,
       worst_p);
  CHECK(worst_th <= 1e-5);
  CHECK(worst_p <= 1e-4);
}
END_TEST

/* ---- long excited run ----------------------------------------------------- */

START_TEST(test_long_run)
{
  canfdi_rls_cfg_t c;
  canfdi_rls_t r;
  dbl_rls_t d;
  double th[3] = {1.1, -0.6, 0.25};
  double worst_th = 0.0;
  long k;
  int i;
  rng_seed(31U);
  base_cfg(&c, 3); /* no gate: the twin updates every sample too */
  ck_assert_int_eq(canfdi_rls_init(&r, &c), CANFDI_OK);
  memset(&d, 0, sizeof d);
  d.n = 3;
  d.lam = 1.0 - (double)c.forget_q31 / 2147483648.0;
  for (i = 0; i < 3; i++) {
    d.p[i][i] = (double)c.p0_q16 / Q16;
  }
  for (k = 0; k < 200000; k++) {
    int32_t phi[3];
    double phin[3];
    int32_t y;
    gen_phi(3, &c, phi);
    y = q16(dot_phys(3, th, phi) + 0.02 * rng_n());
    for (i = 0; i < 3; i++) {
      phin[i] = ldexp((double)phi[i] / Q16, -c.phi_shift[i]);
    }
    (void)canfdi_rls_update(&r, phi, y);
    dbl_update(&d, phin, ldexp((double)y / Q16, -c.y_shift));
    if ((k % 1000) == 999) {
      CHECK(canfdi_rls_invariants_hold(&r));
      for (i = 0; i < 3; i++) {
        const double tp = ldexp(d.th[i], c.y_shift - c.phi_shift[i]);
        worst_th = fmax(worst_th, fabs(theta_phys(&r, i) - tp) / fmax(1.0, fabs(tp)));
      }
    }
  }
  SHOW("rls long run (200000 updates): max |theta - theta_double| %.3g (rel), updates %u\n", worst_th,
       canfdi_rls_diag(&r)->updates);
  ck_assert_uint_eq(canfdi_rls_diag(&r)->updates, 200000U);
  CHECK(worst_th <= 1e-5);
  {
    /* P after 200 000 updates against the twin */
    int j;
    for (i = 0; i < 3; i++) {
      for (j = 0; j < 3; j++) {
        const double pf = (double)canfdi_rls_cov_qn(&r, (unsigned)i, (unsigned)j, 24U) / 16777216.0;
        CHECK(fabs(pf - d.p[i][j]) <= 1e-4 * fmax(1e-3, sqrt(d.p[i][i] * d.p[j][j])));
      }
    }
  }
}
END_TEST

/* ---- the regressor block's two formats ---------------------------------- */

/* The block takes a fixed format (x = phi_q16 2^(10 - s)) when every shift
 * is in -20..10 and every |phi_norm| < 16, else a dynamic block exponent.
 * _i == 0: shifts 12 (outside the fixed range); _i == 1: shifts 0 with
 * normalised regressors up to +-40 on two of them; _i == 2: the regressors
 * alternate between +-40 and +-0.5 every 10 updates (the format changes
 * from update to update). The double twin must be followed to the twin
 * test's tolerances in each case. */
START_TEST(test_block_formats)
{
  const int mode = _i;
  canfdi_rls_cfg_t c;
  canfdi_rls_t r;
  dbl_rls_t d;
  const double th[3] = {0.8, -1.7, 0.45};
  double worst_th = 0.0;
  double worst_p = 0.0;
  int k;
  int i;
  int j;
  rng_seed(300U + (uint64_t)mode);
  base_cfg(&c, 3);
  for (i = 0; i < 3; i++) {
    c.phi_shift[i] = (int8_t)((mode == 0) ? 12 : 0);
  }
  c.y_shift = (int8_t)((mode == 0) ? 12 : 4);
  c.forget_q31 = CANFDI_Q31_RATIO(2, 100);
  c.trace_max_q16 = 20000 * 65536;
  ck_assert_int_eq(canfdi_rls_init(&r, &c), CANFDI_OK);
  memset(&d, 0, sizeof d);
  d.n = 3;
  d.lam = 1.0 - (double)c.forget_q31 / 2147483648.0;
  for (i = 0; i < 3; i++) {
    d.p[i][i] = (double)c.p0_q16 / Q16;
  }
  for (k = 0; k < 3000; k++) {
    int32_t phi[3];
    double phin[3];
    double y = 0.0;
    int32_t yq;
    for (i = 0; i < 3; i++) {
      double a = 1.0;
      if (mode == 1) {
        a = (i == 2) ? 1.0 : 40.0;
      } else if (mode == 2) {
        a = (((k / 10) % 2) == 0) ? 40.0 : 0.5;
      } else {
        a = 1.0;
      }
      phi[i] = q16(ldexp(a * (2.0 * rng_u() - 1.0), c.phi_shift[i]));
      phin[i] = ldexp((double)phi[i] / Q16, -c.phi_shift[i]);
      y += th[i] * ldexp(phin[i], c.y_shift);
    }
    yq = q16(y + ldexp(0.01 * rng_n(), c.y_shift));
    (void)canfdi_rls_update(&r, phi, yq);
    dbl_update(&d, phin, ldexp((double)yq / Q16, -c.y_shift));
    CHECK(canfdi_rls_invariants_hold(&r));
    if ((k % 50) == 49) {
      for (i = 0; i < 3; i++) {
        const double tp = ldexp(d.th[i], c.y_shift - c.phi_shift[i]);
        worst_th = fmax(worst_th, fabs(theta_phys(&r, i) - tp) / fmax(1.0, fabs(tp)));
        for (j = 0; j < 3; j++) {
          const double sc2 = sqrt(d.p[i][i] * d.p[j][j]);
          const int fr = (int)fmin(31.0, fmax(0.0, 29.0 - ceil(log2(sc2))));
          const double pf = ldexp((double)canfdi_rls_cov_qn(&r, (unsigned)i, (unsigned)j, (unsigned)fr), -fr);
          worst_p = fmax(worst_p, fabs(pf - d.p[i][j]) / fmax(1e-3, sc2));
        }
      }
    }
  }
  SHOW("rls block format %d: max |theta - theta_double| %.3g (rel), max |P - P_double| %.3g (rel)\n", mode,
       worst_th, worst_p);
  CHECK(worst_th <= 1e-5);
  CHECK(worst_p <= 1e-4);
}
END_TEST

/* ---- the excitation measure --------------------------------------------- */

/* A square wave +-A (normalised) against its running mean (time constant
 * 2^k updates, a = 2^-k): the mean settles to +-a A / (2 - a) just before
 * each sample, so the deviation is 2 A / (2 - a) and the measure must read
 * its square (Q16.16, after the filters have settled), for A = 0.25 and 4
 * (fixed block format) and A = 100 (dynamic format: beyond 16 normalised);
 * an amplitude of 1000 normalised reads as the clip, 128^2 = 2^14. */
START_TEST(test_excitation_measure)
{
  static const double amp[4] = {0.25, 4.0, 100.0, 1000.0};
  static const int sh[4] = {0, 0, 5, 0};
  const double a = amp[_i];
  const double dev = 2.0 * a / (2.0 - 1.0 / 16.0);
  const double want = (_i == 3) ? 16384.0 : dev * dev;
  canfdi_rls_cfg_t c;
  canfdi_rls_t r;
  int k;
  base_cfg(&c, 2);
  c.phi_shift[0] = (int8_t)sh[_i];
  c.phi_shift[1] = (int8_t)sh[_i];
  c.excite_mask = 0x1U;
  c.excite_shift = 4U;
  c.excite_min_q16 = 0;
  ck_assert_int_eq(canfdi_rls_init(&r, &c), CANFDI_OK);
  for (k = 0; k < 2000; k++) {
    const double v = ((k % 2) == 0) ? a : -a;
    int32_t phi[2];
    phi[0] = q16(ldexp(v, sh[_i]));
    phi[1] = q16(ldexp(0.5, sh[_i]));
    (void)canfdi_rls_update(&r, phi, q16(0.1 * v));
  }
  {
    const double got = (double)canfdi_rls_excitation_q16(&r) / Q16;
    SHOW("rls excitation of a square wave +-%g: %.6g (expected %.6g)\n", a, got, want);
    CHECK(fabs(got - want) <= 1e-4 * want + 2.0 / Q16);
  }
}
END_TEST

/* ---- a long run without excitation ---------------------------------------- */

/* 10^6 updates (17 minutes at 1 kHz) of one constant, noise-free regressor
 * vector after a converged start, without the gate and with slow
 * forgetting: the trace bound (tracked, not recomputed every update) must
 * hold at every check, D stay positive, the factorisation valid, and the
 * estimate still predict along the constant direction. With the gate, the
 * same run leaves theta and P bit for bit unchanged. */
START_TEST(test_long_no_excitation)
{
  const bool gate = (_i == 0);
  canfdi_rls_cfg_t c;
  canfdi_rls_t r;
  const double th[3] = {0.6, 1.4, -0.9};
  const int32_t phi_c[3] = {q16(0.25), q16(-0.6), q16(0.9)};
  int32_t th0[3];
  int32_t cov0;
  int32_t trmax_seen = 0;
  long k;
  int i;
  rng_seed(41U);
  base_cfg(&c, 3);
  c.forget_q31 = CANFDI_Q31_RATIO(1, 1000);
  c.trace_max_q16 = 500 * 65536;
  c.excite_min_q16 = gate ? (int32_t)(1e-3 * Q16) : 0;
  ck_assert_int_eq(canfdi_rls_init(&r, &c), CANFDI_OK);
  for (k = 0; k < 5000; k++) {
    int32_t phi[3];
    gen_phi(3, &c, phi);
    (void)canfdi_rls_update(&r, phi, q16(dot_phys(3, th, phi) + 0.01 * rng_n()));
  }
  for (k = 0; k < 1000; k++) {
    (void)canfdi_rls_update(&r, phi_c, q16(dot_phys(3, th, phi_c)));
  }
  for (i = 0; i < 3; i++) {
    th0[i] = canfdi_rls_theta_qn(&r, (unsigned)i, 20U);
  }
  cov0 = canfdi_rls_cov_qn(&r, 0U, 2U, 24U);
  for (k = 0; k < 1000000L; k++) {
    (void)canfdi_rls_update(&r, phi_c, q16(dot_phys(3, th, phi_c)));
    if ((k % 10000) == 9999) {
      const int32_t t = canfdi_rls_trace_q16(&r);
      CHECK(canfdi_rls_invariants_hold(&r));
      trmax_seen = (t > trmax_seen) ? t : trmax_seen;
    }
  }
  SHOW("rls 10^6 updates without excitation (%s): max trace %.6g (bound %.6g), clips %u, skipped %u\n",
       gate ? "gate" : "no gate", (double)trmax_seen / Q16, (double)c.trace_max_q16 / Q16,
       canfdi_rls_diag(&r)->trace_clips, canfdi_rls_diag(&r)->skipped);
  CHECK((int64_t)trmax_seen <= (int64_t)c.trace_max_q16 + (c.trace_max_q16 >> 19));
  if (gate) {
    ck_assert_uint_ge(canfdi_rls_diag(&r)->skipped, 1000000U);
    for (i = 0; i < 3; i++) {
      ck_assert_int_eq(canfdi_rls_theta_qn(&r, (unsigned)i, 20U), th0[i]);
    }
    ck_assert_int_eq(canfdi_rls_cov_qn(&r, 0U, 2U, 24U), cov0);
  } else {
    double pred = 0.0;
    ck_assert_uint_gt(canfdi_rls_diag(&r)->trace_clips, 0U);
    for (i = 0; i < 3; i++) {
      pred += theta_phys(&r, i) * (double)phi_c[i] / Q16;
    }
    CHECK(fabs(pred - dot_phys(3, th, phi_c)) < 1e-3);
  }
}
END_TEST

START_TEST(test_readout)
{
  canfdi_rls_cfg_t c;
  canfdi_rls_t r;
  base_cfg(&c, 2);
  ck_assert_int_eq(canfdi_rls_init(&r, &c), CANFDI_OK);
  /* set/get round trip at high resolution, and saturation of a read-out
   * whose value does not fit the requested format */
  canfdi_rls_set_theta_qn(&r, 1U, 114420, 24U); /* 6.82e-3 H in Q24 */
  ck_assert_int_eq(canfdi_rls_theta_qn(&r, 1U, 24U), 114420);
  canfdi_rls_set_theta_qn(&r, 0U, 1000 * 65536, 16U);
  ck_assert_int_eq(canfdi_rls_theta_qn(&r, 0U, 24U), INT32_MAX);
  canfdi_rls_set_theta_qn(&r, 0U, -1000 * 65536, 16U);
  ck_assert_int_eq(canfdi_rls_theta_qn(&r, 0U, 24U), INT32_MIN);
  ck_assert_int_eq(canfdi_rls_theta_qn(&r, 5U, 16U), 0);
}
END_TEST

static uint64_t rng_bits(void)
{
  (void)rng_u();
  return rng_s;
}

/* round(x 2^t), half up, saturated to int32_t, for |x| <= 2^31: the
 * read-out's contract, in 64-bit arithmetic. */
static int32_t ref_round_sat(int64_t x, int32_t t)
{
  int64_t v;
  if (t >= 0) {
    v = (t > 31) ? ((x > 0) ? INT64_MAX : ((x < 0) ? INT64_MIN : 0)) : x * ((int64_t)1 << t);
  } else if (t >= -40) {
    v = (int64_t)floor(((double)x / ldexp(1.0, -t)) + 0.5); /* exact: |x| < 2^31, a power of two */
  } else {
    v = 0;
  }
  return (v > INT32_MAX) ? INT32_MAX : ((v < INT32_MIN) ? INT32_MIN : (int32_t)v);
}

/* The theta read-out on every block value's size, exponent and requested
 * format: the rounded (half up) and saturated value of theta_i 2^e, with
 * e the block exponent and the shifts; also at the block's edges +-2^30.
 * Beyond them (never in a running estimator) the value is first rounded
 * to 30 bits, half up on the magnitude: an odd magnitude in (2^30, 2^31)
 * moves up by one unit. */
START_TEST(test_readout_rounding)
{
  canfdi_rls_cfg_t c;
  canfdi_rls_t r;
  unsigned k;
  base_cfg(&c, 2);
  c.y_shift = 3;
  c.phi_shift[1] = -5;
  ck_assert_int_eq(canfdi_rls_init(&r, &c), CANFDI_OK);
  rng_seed(77U);
  for (k = 0U; k < 200000U; k++) {
    const unsigned bits = k % 31U;
    int32_t x = (bits == 0U) ? 0 : (int32_t)(rng_bits() >> (64U - bits)); /* 0 .. 2^bits - 1 */
    const unsigned frac = (unsigned)(rng_bits() % 32U);
    const unsigned i = k & 1U;
    int32_t e;
    if ((k & 2U) != 0U) {
      x = -x;
    }
    if (k % 97U == 0U) {
      x = ((k & 4U) != 0U) ? (1 << 30) : -(1 << 30);
    }
    r.theta[i] = x;
    r.theta_e = (int32_t)(rng_bits() % 120U) - 80;
    e = (r.theta_e + (int32_t)c.y_shift) - (int32_t)c.phi_shift[i];
    ck_assert_int_eq(canfdi_rls_theta_qn(&r, i, frac), ref_round_sat(x, e + (int32_t)frac));
    if (k % 89U == 0U) {
      /* beyond the bound: |x| in (2^30, 2^31], either sign */
      const uint32_t mag = (k % 178U == 0U) ? 0x80000000U : (0x40000001U + (uint32_t)(rng_bits() % 0x3FFFFFFFU));
      const int64_t v = (int64_t)mag + (int64_t)(mag & 1U);
      const bool neg = (mag == 0x80000000U) || ((k & 2U) != 0U);
      r.theta[i] = neg ? (int32_t)(-(int64_t)mag) : (int32_t)mag;
      ck_assert_int_eq(canfdi_rls_theta_qn(&r, i, frac), ref_round_sat(neg ? -v : v, e + (int32_t)frac));
    }
  }
}
END_TEST

static Suite *make_suite(void)
{
  Suite *s = suite_create("rls");
  TCase *tc;

  tc = tcase_create("config");
  tcase_add_loop_test(tc, test_cfg_domain, 0, (int)(sizeof cfg_cases / sizeof cfg_cases[0]));
  tcase_add_test(tc, test_readout);
  tcase_add_test(tc, test_readout_rounding);
  suite_add_tcase(s, tc);

  tc = tcase_create("accuracy");
  tcase_add_loop_test(tc, test_converge_exact, 1, NMAX + 1);
  tcase_add_loop_test(tc, test_twin_double, 1, NMAX + 1);
  tcase_add_test(tc, test_shift_invariance);
  tcase_add_test(tc, test_collinear);
  tcase_add_test(tc, test_bad_scaling);
  tcase_add_loop_test(tc, test_block_formats, 0, 3);
  tcase_add_loop_test(tc, test_excitation_measure, 0, 4);
  suite_add_tcase(s, tc);

  tc = tcase_create("robustness");
  tcase_set_timeout(tc, 120);
  tcase_add_loop_test(tc, test_no_excitation, 0, 2);
  tcase_add_test(tc, test_tracking);
  tcase_add_test(tc, test_reset);
  tcase_add_test(tc, test_long_run);
  tcase_add_loop_test(tc, test_long_no_excitation, 0, 2);
  suite_add_tcase(s, tc);
  return s;
}

CANFDI_UNIT_MAIN(make_suite)
