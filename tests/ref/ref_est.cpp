// ref_est.cpp — the fixed-point DC-motor and throttle estimators
// (firmware/model/canfdi_est_dcm, canfdi_est_thr) against their double-
// precision Eigen twins (ref_common.hpp: same SVF discretisation, same
// normalisation, gates, decimation, forgetting and trace bound), fed the
// same simulated traces (host_sim at Isermann's motor parameters at nominal
// load with a PRBS speed setpoint, and the throttle under a sine + PRBS
// angle setpoint; sensor noise on), two seeds each.
//
// Acceptance (docs/requirements.md): converged parameter estimates within 1 %
// (relative) of the reference. Checked on the mean over the converged window
// (DC motor 5..20 s; throttle 15..40 s) and on the final value, for every
// physical parameter with a nonzero true value (the throttle's voltage offset
// U_0 ~ 0 is compared in absolute terms: within 0.01 V). The largest
// pointwise difference over the window is printed as well. The DC-motor trace
// includes an abrupt +10 % R_A at 20 s; the time to +5 % is printed for both.
#include "ref_common.hpp"

namespace {

struct Cmp {
  const char *name;
  double sf = 0, sd = 0, worst = 0, last_f = 0, last_d = 0;
  long n = 0;
  void add(double f, double d) {
    sf += f;
    sd += d;
    worst = std::max(worst, std::fabs(f - d) / std::max(1e-12, std::fabs(d)));
    last_f = f;
    last_d = d;
    n++;
  }
};

void report(ref::Tally &t, const char *what, unsigned seed, std::vector<Cmp> &cs, const std::vector<bool> &abs_cmp) {
  for (size_t i = 0; i < cs.size(); i++) {
    Cmp &c = cs[i];
    const double mf = c.sf / static_cast<double>(c.n), md = c.sd / static_cast<double>(c.n);
    if (abs_cmp[i]) {
      const double e = std::fabs(mf - md), el = std::fabs(c.last_f - c.last_d);
      t.check((e <= 0.01) && (el <= 0.01), "%s seed %u %-4s window mean fix %.5g double %.5g (|diff| %.2e V), final |diff| %.2e V",
              what, seed, c.name, mf, md, e, el);
    } else {
      const double e = std::fabs(mf / md - 1.0), el = std::fabs(c.last_f / c.last_d - 1.0);
      t.check((e <= 0.01) && (el <= 0.01),
              "%s seed %u %-4s window mean fix %.6g double %.6g (%.4f %%), final %.4f %%, max pointwise %.4f %%", what,
              seed, c.name, mf, md, 100 * e, 100 * el, 100 * c.worst);
    }
  }
}

void dcm(ref::Tally &t, unsigned seed) {
  const auto tr = ref::dcm_trace(seed, 23.0, 1.0, 1e4, 20.0, 0.1);
  canfdi_est_dcm_cfg_t cfg;
  canfdi_est_dcm_default_cfg(&cfg);
  static canfdi_est_dcm_t f;
  if (tr.empty() || (canfdi_est_dcm_init(&f, &cfg) != CANFDI_OK)) {
    t.check(false, "dcm setup");
    return;
  }
  ref::EstDcm d(cfg);
  std::vector<Cmp> cs = {{"R_A"}, {"L_A"}, {"Psi"}, {"J"}, {"M_F1"}, {"M_c"}};
  double reach_f = -1, reach_d = -1;
  for (size_t k = 0; k < tr.size(); k++) {
    canfdi_est_dcm_step(&f, tr[k].ua_q16, tr[k].ia_q16, tr[k].w_q16);
    d.step(tr[k]);
    const double tt = static_cast<double>(k + 1) * ref::kT;
    const double fv[6] = {ref::q16d(canfdi_est_dcm_ra_q16(&f)), canfdi_est_dcm_la_q24(&f) / 16777216.0,
                          ref::q16d(canfdi_est_dcm_psi_q16(&f)), canfdi_est_dcm_j_q24(&f) / 16777216.0,
                          canfdi_est_dcm_mf1_q24(&f) / 16777216.0, ref::q16d(canfdi_est_dcm_mc_q16(&f))};
    const double dv[6] = {d.ra(), d.la(), d.psi(), d.j(), d.mf1(), d.mc()};
    if ((tt >= 5.0) && (tt < 20.0)) {
      for (int i = 0; i < 6; i++) cs[static_cast<size_t>(i)].add(fv[i], dv[i]);
    }
    if (tt >= 20.0) {
      if ((reach_f < 0) && (fv[0] >= 1.52 * 1.05)) reach_f = tt - 20.0;
      if ((reach_d < 0) && (dv[0] >= 1.52 * 1.05)) reach_d = tt - 20.0;
    }
  }
  report(t, "est_dcm", seed, cs, std::vector<bool>(6, false));
  t.check((reach_f >= 0) && (std::fabs(reach_f - reach_d) <= 0.05),
          "est_dcm seed %u R_A +10 %% at 20 s: +5 %% after %.3f s (fixed) vs %.3f s (double)", seed, reach_f, reach_d);
}

void thr(ref::Tally &t, unsigned seed) {
  const auto tr = ref::thr_trace(seed, 40.0);
  canfdi_est_thr_cfg_t cfg;
  canfdi_est_thr_default_cfg(&cfg);
  static canfdi_est_thr_t f;
  if (tr.empty() || (canfdi_est_thr_init(&f, &cfg) != CANFDI_OK)) {
    t.check(false, "thr setup");
    return;
  }
  ref::EstThr d(cfg);
  std::vector<Cmp> cs = {{"R"}, {"L"}, {"K"}, {"U0"}, {"J"}, {"B"}, {"k_s"}, {"P"}, {"T_c"}};
  for (size_t k = 0; k < tr.size(); k++) {
    canfdi_est_thr_step(&f, tr[k].u_q16, tr[k].i_q16, tr[k].angle_q16);
    d.step(tr[k]);
    const double tt = static_cast<double>(k + 1) * ref::kT;
    if (tt >= 15.0) {
      const double fv[9] = {ref::q16d(canfdi_est_thr_r_q16(&f)),          canfdi_est_thr_l_q24(&f) / 16777216.0,
                            ref::q16d(canfdi_est_thr_k_q16(&f)),          ref::q16d(canfdi_est_thr_u0_q16(&f)),
                            canfdi_est_thr_j_q24(&f) / 16777216.0,        canfdi_est_thr_b_q24(&f) / 16777216.0,
                            canfdi_est_thr_spring_q24(&f) / 16777216.0,   ref::q16d(canfdi_est_thr_pretension_q16(&f)),
                            ref::q16d(canfdi_est_thr_friction_q16(&f))};
      const double dv[9] = {d.r(), d.l(), d.k(), d.u0(), d.j(), d.b(), d.spring(), d.pretension(), d.friction()};
      for (int i = 0; i < 9; i++) cs[static_cast<size_t>(i)].add(fv[i], dv[i]);
    }
  }
  std::vector<bool> abs_cmp(9, false);
  abs_cmp[3] = true;
  report(t, "est_thr", seed, cs, abs_cmp);
}

}  // namespace

int main() {
  ref::Tally t;
  for (unsigned seed = 1; seed <= 2; seed++) {
    dcm(t, seed);
    thr(t, seed);
  }
  return t.finish();
}
