/*
 * test_est_dcm.c — acceptance tests of canfdi_est_dcm (docs/requirements.md,
 * accuracy of the building blocks) on traces of the host_sim plant library.
 *
 * Rig: Isermann's motor (R_A 1.52 Ohm held constant — thermal model off —
 * L_A 6.82 mH, Psi 0.33 V s, J 1.92e-3 kg m^2, M_F1 0.36e-3, M_F0 0.11),
 * nominal load 1.2 N m (~4 A), the simulator's reference speed controller,
 * speed setpoint 100 rad/s plus a PRBS of +-30 rad/s with 20 ms bits
 * (about the mechanical time constant), sensor noise of a few ADC LSB
 * (U_A 0.05 V, I_A 0.02 A, w 0.2 rad/s) and 12-bit quantisation. Each test
 * runs for three noise seeds (loop tests), so no figure rests on one
 * stream. Figures are printed; the tolerances are the acceptance figures:
 *   - converged window 5..20 s: R_A and Psi within 2 %, J within 5 %, the
 *     standard deviation of each within 2 % (of the mean);
 *   - abrupt +10 % R_A at 20 s: the estimate reaches +5 % within 2 s;
 *   - 10 s excited, 60 s at a constant operating point (no PRBS), then a
 *     setpoint step and PRBS again: both estimators keep D > 0 and the
 *     trace bound at every step (canfdi_rls_invariants_hold), the estimates
 *     stay within 5 % of the truth during the constant stretch (they are
 *     held, not wound up) and re-converge after it;
 *   - a full reset re-converges within 2 s of excitation;
 *   - a +0.5 N m load step given as the known load offset
 *     (canfdi_est_dcm_set_load_offset) leaves the lumped M_c within 3 % of
 *     the nominal M_c (the diagnosis's friction threshold) of the new truth
 *     and J within 5 % at every step after it, while the same step unknown
 *     moves M_c by more than that (the test discriminates).
 */
#include <check.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "canfdi_sim.h"
#include "canfdi_sim_fault.h"
#include "canfdi_sim_profile.h"
#include "canfdi_sim_refctl.h"
#include "model/canfdi_est_dcm.h"
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

#define RA_TRUE 1.52
#define LA_TRUE 6.82e-3
#define PSI_TRUE 0.33
#define J_TRUE 1.92e-3
#define LOAD_NM 1.2

typedef struct {
  canfdi_sim_cfg_t cfg;
  canfdi_sim_t sim;
  canfdi_sim_refctl_t ctl;
  canfdi_sim_profile_t speed;
  canfdi_est_dcm_t est;
  long k;
} rig_t;

static rig_t rig; /* large: static */

/* Load step of the plant: at load_step_k, by load_step_Nm; the offset is
 * told to the estimator when load_known. */
static long load_step_k = -1;
static double load_step_Nm = 0.0;
static bool load_known = false;

static double load_at(long k)
{
  return LOAD_NM + (((load_step_k >= 0) && (k >= load_step_k)) ? load_step_Nm : 0.0);
}

static double ra(void)
{
  return (double)canfdi_est_dcm_ra_q16(&rig.est) / 65536.0;
}
static double psi(void)
{
  return (double)canfdi_est_dcm_psi_q16(&rig.est) / 65536.0;
}
static double jj(void)
{
  return (double)canfdi_est_dcm_j_q24(&rig.est) / 16777216.0;
}
static double la(void)
{
  return (double)canfdi_est_dcm_la_q24(&rig.est) / 16777216.0;
}

/* PRBS windows: [t0, t1) pairs, up to two. */
static void rig_init(uint64_t seed, double p0, double p1, double p2, double p3, double step_t, double step_v)
{
  canfdi_sim_refctl_cfg_t rc;
  canfdi_est_dcm_cfg_t ec;
  canfdi_sim_default_cfg(&rig.cfg);
  rig.cfg.dcm.ra_cold_ohm = RA_TRUE;
  rig.cfg.dcm.thermal = false;
  rig.cfg.sigma[CANFDI_SIM_S_DCM_UA] = 0.05;
  rig.cfg.sigma[CANFDI_SIM_S_DCM_IA] = 0.02;
  rig.cfg.sigma[CANFDI_SIM_S_DCM_SPEED] = 0.2;
  rig.cfg.seed = seed;
  ck_assert_int_eq(canfdi_sim_init(&rig.sim, &rig.cfg), CANFDI_OK);
  canfdi_sim_refctl_default(&rc, &rig.cfg);
  canfdi_sim_refctl_init(&rig.ctl, &rc);
  canfdi_sim_profile_init(&rig.speed, -400.0, 400.0);
  ck_assert_int_eq(canfdi_sim_profile_add(&rig.speed, CANFDI_SIM_PROF_CONST, 0, 0, 100.0, 0, 0), CANFDI_OK);
  if (p1 > p0) {
    ck_assert_int_eq(canfdi_sim_profile_add(&rig.speed, CANFDI_SIM_PROF_PRBS, p0, p1, 30.0, 0.02, 11U + (uint32_t)seed),
                     CANFDI_OK);
  }
  if (p3 > p2) {
    ck_assert_int_eq(canfdi_sim_profile_add(&rig.speed, CANFDI_SIM_PROF_PRBS, p2, p3, 30.0, 0.02, 23U + (uint32_t)seed),
                     CANFDI_OK);
  }
  if (step_t > 0.0) {
    ck_assert_int_eq(canfdi_sim_profile_add(&rig.speed, CANFDI_SIM_PROF_STEP, step_t, 0, step_v, 0, 0), CANFDI_OK);
  }
  canfdi_est_dcm_default_cfg(&ec);
  ck_assert_int_eq(canfdi_est_dcm_init(&rig.est, &ec), CANFDI_OK);
  rig.k = 0;
}

static void rig_step(void)
{
  canfdi_sim_in_t in;
  memset(&in, 0, sizeof in);
  canfdi_sim_refctl_step(&rig.ctl, canfdi_sim_profile_eval(&rig.speed, (int64_t)rig.k * 1000), 30.0, &rig.sim.meas,
                         &in);
  in.dcm.load_Nm = load_at(rig.k);
  canfdi_sim_step(&rig.sim, &in);
  if (load_known) {
    /* the load of the interval that ends with this sample */
    canfdi_est_dcm_set_load_offset(&rig.est, q16(load_at(rig.k) - LOAD_NM));
  }
  canfdi_est_dcm_step(&rig.est, q16(rig.sim.meas.value[CANFDI_SIM_S_DCM_UA]),
                      q16(rig.sim.meas.value[CANFDI_SIM_S_DCM_IA]), q16(rig.sim.meas.value[CANFDI_SIM_S_DCM_SPEED]));
  rig.k++;
}


/* ---- accuracy and R_A step --------------------------------------------- */

START_TEST(test_accuracy_and_step)
{
  const uint64_t seed = 1U + (uint64_t)_i;
  stat_t sr = {0, 0, 0};
  stat_t sp = {0, 0, 0};
  stat_t sj = {0, 0, 0};
  stat_t sl = {0, 0, 0};
  double t_reach = -1.0;
  canfdi_sim_fault_spec_t fs;
  const int id = canfdi_sim_fault_find("dcm_ra_up");
  ck_assert_int_ge(id, 0);
  rig_init(seed, 1.0, 1e4, 0, 0, 0, 0);
  ck_assert_int_eq(canfdi_sim_fault_spec_make(&fs, (uint8_t)id, CANFDI_SIM_MODE_ABRUPT, 20.0, 0.1, 0, 0, 0), CANFDI_OK);
  ck_assert_int_eq(canfdi_sim_add_fault(&rig.sim, &fs), CANFDI_OK);
  while (rig.k < 23000) {
    const double t = (double)(rig.k + 1) * 1e-3;
    rig_step();
    CHECK(canfdi_rls_invariants_hold(canfdi_est_dcm_arm_rls(&rig.est)));
    CHECK(canfdi_rls_invariants_hold(canfdi_est_dcm_mech_rls(&rig.est)));
    if ((t >= 5.0) && (t < 20.0)) {
      CHECK(canfdi_est_dcm_arm_converged(&rig.est));
      st_add(&sr, ra());
      st_add(&sp, psi());
      st_add(&sj, jj());
      st_add(&sl, la());
    }
    if ((t >= 20.0) && (t_reach < 0.0) && (ra() >= RA_TRUE * 1.05)) {
      t_reach = t - 20.0;
    }
  }
  {
    const double er = st_mean(&sr) / RA_TRUE - 1.0;
    const double ep = st_mean(&sp) / PSI_TRUE - 1.0;
    const double ej = st_mean(&sj) / J_TRUE - 1.0;
    const double dr = st_sd(&sr) / st_mean(&sr);
    const double dp = st_sd(&sp) / st_mean(&sp);
    const double dj = st_sd(&sj) / st_mean(&sj);
    SHOW("est_dcm seed %u (5..20 s): R_A %.4f (%+.2f %%, sd %.2f %%)  Psi %.4f (%+.2f %%, sd %.2f %%)  "
           "J %.4e (%+.2f %%, sd %.2f %%)  L_A %.3e (%+.2f %%)  R_A +10 %% step: +5 %% after %.3f s, "
           "final %.4f\n",
           (unsigned)seed, st_mean(&sr), 100 * er, 100 * dr, st_mean(&sp), 100 * ep, 100 * dp, st_mean(&sj), 100 * ej,
           100 * dj, st_mean(&sl), 100 * (st_mean(&sl) / LA_TRUE - 1.0), t_reach, ra());
    CHECK(fabs(er) <= 0.02);
    CHECK(fabs(ep) <= 0.02);
    CHECK(fabs(ej) <= 0.05);
    CHECK(dr < 0.02);
    CHECK(dp < 0.02);
    CHECK(dj < 0.02);
    CHECK((t_reach >= 0.0) && (t_reach <= 2.0));
    /* and it settles at the new value (within the 2 % accuracy band) */
    CHECK(fabs(ra() / (RA_TRUE * 1.1) - 1.0) <= 0.02);
  }
}
END_TEST

/* ---- known load step --------------------------------------------------- */

static double mc(void)
{
  return (double)canfdi_est_dcm_mc_q16(&rig.est) / 65536.0;
}

/* Largest |M_c - (M_F0 + M_L)| and |J / J_true - 1| after a +0.5 N m load
 * step at 10 s (until 15 s), with the step known or not. */
static void run_load_step(uint64_t seed, bool known, double *mc_err, double *j_err)
{
  const double mc_nom = 0.11 + LOAD_NM;
  rig_init(seed, 1.0, 1e4, 0, 0, 0, 0);
  load_step_k = 10000;
  load_step_Nm = 0.5;
  load_known = known;
  *mc_err = 0.0;
  *j_err = 0.0;
  while (rig.k < 15000) {
    rig_step();
    if (rig.k == 9999) {
      CHECK(fabs(mc() - mc_nom) <= 0.03 * mc_nom); /* settled before the step */
    }
    if (rig.k > 10000) { /* rig.k - 1: the step just taken */
      const double e = fabs(mc() - (0.11 + load_at(rig.k - 1)));
      const double ej = fabs(jj() / J_TRUE - 1.0);
      *mc_err = (e > *mc_err) ? e : *mc_err;
      *j_err = (ej > *j_err) ? ej : *j_err;
    }
  }
  load_step_k = -1;
  load_known = false;
}

START_TEST(test_known_load_step)
{
  const uint64_t seed = 1U + (uint64_t)_i;
  const double tol = 0.03 * (0.11 + LOAD_NM); /* diagnosis threshold, N m */
  double mk;
  double jk;
  double mu;
  double ju;
  run_load_step(seed, true, &mk, &jk);
  run_load_step(seed, false, &mu, &ju);
  SHOW("est_dcm seed %u, +0.5 N m load step: known max |dM_c| %.4f N m, max |dJ| %.2f %%; "
       "unknown %.4f N m, %.2f %%\n",
       (unsigned)seed, mk, 100 * jk, mu, 100 * ju);
  CHECK(mk < tol);
  CHECK(jk < 0.05);
  CHECK(mu > tol);
}
END_TEST

/* ---- no excitation ------------------------------------------------------ */

START_TEST(test_no_excitation_60s)
{
  const uint64_t seed = 1U + (uint64_t)_i;
  double worst_hold = 0.0;
  double tr_max_arm = 0.0;
  double tr_max_mech = 0.0;
  uint32_t skipped0 = 0U;
  uint32_t skipped1 = 0U;
  /* 0..10 s PRBS, 10..70 s constant 100 rad/s, 70 s step +20 rad/s, PRBS
   * again 72..80 s */
  rig_init(seed, 1.0, 10.0, 72.0, 1e4, 70.0, 20.0);
  while (rig.k < 80000) {
    const double t = (double)(rig.k + 1) * 1e-3;
    const canfdi_rls_t *a = canfdi_est_dcm_arm_rls(&rig.est);
    const canfdi_rls_t *m = canfdi_est_dcm_mech_rls(&rig.est);
    rig_step();
    /* D > 0 and bounded trace, every step, both estimators */
    CHECK(canfdi_rls_invariants_hold(a));
    CHECK(canfdi_rls_invariants_hold(m));
    if ((t >= 10.0) && (t < 70.0)) {
      /* trace during the constant stretch (at the start it is n p0) */
      tr_max_arm = fmax(tr_max_arm, (double)canfdi_rls_trace_q16(a) / 65536.0);
      tr_max_mech = fmax(tr_max_mech, (double)canfdi_rls_trace_q16(m) / 65536.0);
    }
    if (rig.k == 11000) {
      skipped0 = canfdi_rls_diag(a)->skipped;
    }
    if (rig.k == 70000) {
      skipped1 = canfdi_rls_diag(a)->skipped;
    }
    if ((t >= 10.0) && (t < 70.0)) {
      worst_hold = fmax(worst_hold, fabs(ra() / RA_TRUE - 1.0));
      worst_hold = fmax(worst_hold, fabs(psi() / PSI_TRUE - 1.0));
      worst_hold = fmax(worst_hold, fabs(jj() / J_TRUE - 1.0));
    }
  }
  SHOW("est_dcm seed %u no-excitation: worst |rel. error| of R_A/Psi/J over 10..70 s %.2f %%, gate skipped "
         "%u of %u armature updates in 11..70 s, max trace over 10..70 s arm %.3g mech %.3g (bound %.3g); after step+PRBS: "
         "R_A %.4f Psi %.4f J %.4e\n",
         (unsigned)seed, 100 * worst_hold, skipped1 - skipped0, (70000U - 11000U) / 5U, tr_max_arm, tr_max_mech,
         (double)rig.est.cfg.trace_max_q16 / 65536.0, ra(), psi(), jj());
  CHECK(worst_hold <= 0.05);
  /* the gate holds the estimate through (nearly all of) the stretch */
  CHECK((skipped1 - skipped0) >= 9 * ((70000U - 11000U) / 5U) / 10);
  CHECK(fabs(ra() / RA_TRUE - 1.0) <= 0.02);
  CHECK(fabs(psi() / PSI_TRUE - 1.0) <= 0.02);
  CHECK(fabs(jj() / J_TRUE - 1.0) <= 0.05);
}
END_TEST

/* ---- reset ---------------------------------------------------------------- */

START_TEST(test_reset_recovery)
{
  /* Nominal R_A deliberately wrong (2.0 Ohm, +32 %): converge, then a full
   * reset goes back to the nominal values and P0, and the estimator must
   * recover from there within 2 s of excitation. */
  const uint64_t seed = 1U + (uint64_t)_i;
  canfdi_est_dcm_cfg_t ec;
  double t_back = -1.0;
  rig_init(seed, 1.0, 1e4, 0, 0, 0, 0);
  canfdi_est_dcm_default_cfg(&ec);
  ec.ra_nom_q16 = q16(2.0);
  ck_assert_int_eq(canfdi_est_dcm_init(&rig.est, &ec), CANFDI_OK);
  while (rig.k < 12000) {
    const double t = (double)(rig.k + 1) * 1e-3;
    if (rig.k == 6000) {
      CHECK(fabs(ra() / RA_TRUE - 1.0) <= 0.02);
      canfdi_est_dcm_reset(&rig.est, false);
      ck_assert_uint_eq(canfdi_est_dcm_diag(&rig.est)->resets, 1U);
      ck_assert_int_eq(canfdi_est_dcm_ra_q16(&rig.est), q16(2.0));
      CHECK(!canfdi_est_dcm_arm_converged(&rig.est));
    }
    rig_step();
    CHECK(canfdi_rls_invariants_hold(canfdi_est_dcm_arm_rls(&rig.est)));
    if ((rig.k > 6000) && (t_back < 0.0) && (fabs(ra() / RA_TRUE - 1.0) <= 0.02) &&
        (fabs(psi() / PSI_TRUE - 1.0) <= 0.02)) {
      t_back = t - 6.0;
    }
  }
  SHOW("est_dcm seed %u reset: R_A 2.0 (nominal) -> within 2 %% after %.3f s\n", (unsigned)seed, t_back);
  CHECK((t_back >= 0.0) && (t_back <= 2.0));
  CHECK(fabs(ra() / RA_TRUE - 1.0) <= 0.02);
  CHECK(canfdi_est_dcm_arm_converged(&rig.est));
}
END_TEST

/* ---- configuration -------------------------------------------------------- */

START_TEST(test_cfg)
{
  canfdi_est_dcm_cfg_t c;
  canfdi_est_dcm_default_cfg(&c);
  ck_assert_int_eq(canfdi_est_dcm_init(&rig.est, &c), CANFDI_OK);
  ck_assert_int_eq(canfdi_est_dcm_init(NULL, &c), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_est_dcm_init(&rig.est, NULL), -CANFDI_EINVAL);
  c.decim = 0U;
  ck_assert_int_eq(canfdi_est_dcm_init(&rig.est, &c), -CANFDI_EINVAL);
  canfdi_est_dcm_default_cfg(&c);
  c.psi_nom_q16 = 0;
  ck_assert_int_eq(canfdi_est_dcm_init(&rig.est, &c), -CANFDI_EINVAL);
  canfdi_est_dcm_default_cfg(&c);
  c.svf.order = 4U;
  ck_assert_int_eq(canfdi_est_dcm_init(&rig.est, &c), -CANFDI_EINVAL);
  canfdi_est_dcm_default_cfg(&c);
  c.forget_q31 = -1;
  ck_assert_int_eq(canfdi_est_dcm_init(&rig.est, &c), -CANFDI_EINVAL);
  /* nominal values read back at their resolution */
  canfdi_est_dcm_default_cfg(&c);
  ck_assert_int_eq(canfdi_est_dcm_init(&rig.est, &c), CANFDI_OK);
  ck_assert_int_eq(canfdi_est_dcm_ra_q16(&rig.est), c.ra_nom_q16);
  ck_assert_int_eq(canfdi_est_dcm_la_q24(&rig.est), c.la_nom_q24);
  ck_assert_int_eq(canfdi_est_dcm_psi_q16(&rig.est), c.psi_nom_q16);
  CHECK(abs(canfdi_est_dcm_j_q24(&rig.est) - c.j_nom_q24) <= 2);
  CHECK(abs(canfdi_est_dcm_mf1_q24(&rig.est) - c.mf1_nom_q24) <= 2);
  CHECK(abs(canfdi_est_dcm_mc_q16(&rig.est) - c.mc_nom_q16) <= 2);
  CHECK(!canfdi_est_dcm_excited(&rig.est));
  CHECK(!canfdi_est_dcm_mech_converged(&rig.est));
}
END_TEST

/* Late load (canfdi_est_dcm_set_load_offset): a change of the known load
 * offset skips the mechanical updates of the next load_hold_steps steps
 * (one per decim steps), none before the change, none after the hold, none
 * with the hold off. */
START_TEST(test_late_load_hold)
{
  canfdi_est_dcm_cfg_t c;
  unsigned k;
  uint32_t n;
  canfdi_est_dcm_default_cfg(&c);
  c.load_hold_steps = 47U;
  ck_assert_int_eq(canfdi_est_dcm_init(&rig.est, &c), CANFDI_OK);
  for (k = 0U; k < 100U; k++) {
    canfdi_est_dcm_set_load_offset(&rig.est, 0);
    canfdi_est_dcm_step(&rig.est, q16(38.0), q16(4.0), q16(100.0));
  }
  ck_assert_uint_eq(canfdi_est_dcm_diag(&rig.est)->load_hold_skips, 0U);
  for (k = 0U; k < 47U; k++) {
    canfdi_est_dcm_set_load_offset(&rig.est, q16(0.4));
    canfdi_est_dcm_step(&rig.est, q16(38.0), q16(4.0), q16(100.0));
  }
  n = canfdi_est_dcm_diag(&rig.est)->load_hold_skips;
  CHECK((n >= 47U / c.decim) && (n <= (47U + c.decim - 1U) / c.decim));
  for (k = 0U; k < 100U; k++) {
    canfdi_est_dcm_set_load_offset(&rig.est, q16(0.4));
    canfdi_est_dcm_step(&rig.est, q16(38.0), q16(4.0), q16(100.0));
  }
  ck_assert_uint_eq(canfdi_est_dcm_diag(&rig.est)->load_hold_skips, n);
  c.load_hold_steps = 0U;
  ck_assert_int_eq(canfdi_est_dcm_init(&rig.est, &c), CANFDI_OK);
  for (k = 0U; k < 100U; k++) {
    canfdi_est_dcm_set_load_offset(&rig.est, (k < 50U) ? 0 : q16(0.4));
    canfdi_est_dcm_step(&rig.est, q16(38.0), q16(4.0), q16(100.0));
  }
  ck_assert_uint_eq(canfdi_est_dcm_diag(&rig.est)->load_hold_skips, 0U);
}
END_TEST

/* has_run is state (stepped since init, kept by reset), not a counter; the
 * diagnostics counters saturate at UINT32_MAX. */
START_TEST(test_has_run_and_counters_saturate)
{
  canfdi_est_dcm_cfg_t c;
  canfdi_est_dcm_default_cfg(&c);
  ck_assert_int_eq(canfdi_est_dcm_init(&rig.est, &c), CANFDI_OK);
  ck_assert(!canfdi_est_dcm_has_run(&rig.est));
  canfdi_est_dcm_reset(&rig.est, true);
  ck_assert(!canfdi_est_dcm_has_run(&rig.est));
  rig.est.diag.steps = UINT32_MAX - 1U;
  rig.est.diag.resets = UINT32_MAX;
  canfdi_est_dcm_step(&rig.est, q16(38.0), q16(4.0), q16(100.0));
  ck_assert(canfdi_est_dcm_has_run(&rig.est));
  canfdi_est_dcm_step(&rig.est, q16(38.0), q16(4.0), q16(100.0));
  ck_assert_uint_eq(canfdi_est_dcm_diag(&rig.est)->steps, UINT32_MAX);
  canfdi_est_dcm_reset(&rig.est, true);
  ck_assert(canfdi_est_dcm_has_run(&rig.est));
  ck_assert_uint_eq(canfdi_est_dcm_diag(&rig.est)->resets, UINT32_MAX);
  ck_assert_int_eq(canfdi_est_dcm_init(&rig.est, &c), CANFDI_OK);
  ck_assert(!canfdi_est_dcm_has_run(&rig.est));
  ck_assert_uint_eq(canfdi_est_dcm_diag(&rig.est)->steps, 0U);
}
END_TEST

static Suite *make_suite(void)
{
  Suite *s = suite_create("est_dcm");
  TCase *tc;

  tc = tcase_create("config");
  tcase_add_test(tc, test_cfg);
  tcase_add_test(tc, test_late_load_hold);
  tcase_add_test(tc, test_has_run_and_counters_saturate);
  suite_add_tcase(s, tc);

  tc = tcase_create("acceptance");
  tcase_set_timeout(tc, 300);
  tcase_add_loop_test(tc, test_accuracy_and_step, 0, 3);
  tcase_add_loop_test(tc, test_no_excitation_60s, 0, 3);
  tcase_add_loop_test(tc, test_reset_recovery, 0, 3);
  tcase_add_loop_test(tc, test_known_load_step, 0, 3);
  suite_add_tcase(s, tc);
  return s;
}

CANFDI_UNIT_MAIN(make_suite)
