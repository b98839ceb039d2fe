// ref_rls.cpp — the fixed-point UD RLS (firmware/model/canfdi_rls) against
// its double-precision covariance-form twin (ref_common.hpp, Eigen), fed the
// same Q16.16 samples, for n = 1..CANFDI_CFG_RLS_MAX_PARAMS, with
//   - excitation that stops and resumes (the gate must take the same
//     decisions: identical update/skip counts), and
//   - a stretch without the gate where forgetting drives the trace into its
//     bound (the clipping must agree too).
// The gated runs again with badly scaled regressors (normalised sizes
// 2^-6 .. 2^6: P's diagonal spans 2^24) for n = 4 and 6, P read out with
// ~29 bits below sqrt(P_ii P_jj): theta within 2e-5 there (the gain
// block's spread of 2^12 costs its small elements bits), P within 1e-4.
// Each run holds a sudden +20 % change of theta_0 at update 7000.
// Tolerances: theta within 1e-5 of max(1, |theta|) (physical units; the
// read-out resolution is 2^-20), P within 1e-4 of sqrt(P_ii P_jj) (read-out
// 2^-20 against P ~ 1e-2 .. 1e3), at every 100th update. The fixed-point
// arithmetic carries ~2^-30 relative per operation, so the margin is wide.
// Exception: without the gate, the constant-regressor stretch (and 1000
// updates after it) winds P up to its trace bound; P's condition number is
// then ~1e5 (1e3 against ~1e-2) and both implementations amplify their
// rounding differences by it (1e5 x 2^-30 ~ 1e-4): there theta must agree
// within 1e-3 (P keeps 1e-4). Both figures are printed.
#include "ref_common.hpp"

namespace {

uint64_t g_s = 1;
double urand() {
  g_s ^= g_s << 13;
  g_s ^= g_s >> 7;
  g_s ^= g_s << 17;
  return static_cast<double>(g_s >> 11) * (1.0 / 9007199254740992.0);
}
double nrand() {
  const double u1 = urand() + 1e-300, u2 = urand();
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * M_PI * u2);
}

struct Result {
  double th = 0, p = 0, th_wound = 0;
  long upd_f = 0, upd_d = 0, skip_f = 0, skip_d = 0, clip_f = 0;
};

// bad: the regressors' normalised sizes 2^-6, 2^-2, 2^2, 2^6 (cycling over
// i) although the shifts say O(1): P's diagonal then spans 2^24.
Result run(int n, bool gate, uint64_t seed, bool bad = false) {
  g_s = seed * 0x9E3779B97F4A7C15ULL + 7U;
  canfdi_rls_cfg_t c;
  std::memset(&c, 0, sizeof c);
  c.n_params = static_cast<uint8_t>(n);
  c.y_shift = bad ? 0 : 3;
  for (int i = 0; i < n; i++) c.phi_shift[i] = static_cast<int8_t>(bad ? 0 : ((i % 4) * 2 - 2));
  c.forget_q31 = CANFDI_Q31_RATIO(1, 100);
  c.p0_q16 = 100 * 65536;
  c.trace_max_q16 = (bad ? 30000 : 1000) * 65536;
  c.excite_min_q16 = gate ? ref::q16i(1e-3) : 0;
  c.excite_shift = 6U;
  c.excite_mask = 0U;
  if (bad) {
    // the 2^-6 regressors' mean square (~3e-5) stays below any useful
    // threshold: the gate watches the others
    for (int i = 0; i < n; i++) {
      if ((i % 4) != 0) c.excite_mask = static_cast<uint16_t>(c.excite_mask | (1U << i));
    }
  }
  for (int i = 0; i < n; i++) c.theta0_q16[i] = ref::q16i(0.1 * i);
  canfdi_rls_t r;
  Result res;
  if (canfdi_rls_init(&r, &c) != CANFDI_OK) {
    res.th = 1e9;
    return res;
  }
  ref::Rls d(c);
  std::vector<double> th(static_cast<size_t>(n));
  for (int i = 0; i < n; i++) th[static_cast<size_t>(i)] = (i % 2 ? -1.0 : 1.0) * (0.3 + 0.4 * i);
  static const int kBad[4] = {-6, -2, 2, 6};
  std::vector<int> sc(static_cast<size_t>(n));
  for (int i = 0; i < n; i++) sc[static_cast<size_t>(i)] = c.phi_shift[i] + (bad ? kBad[i % 4] : 0);
  std::vector<double> hold(static_cast<size_t>(n));
  for (int i = 0; i < n; i++) hold[static_cast<size_t>(i)] = std::ldexp(0.5 + 0.1 * i, sc[static_cast<size_t>(i)]);
  for (int k = 0; k < 12000; k++) {
    // excited, then 4000 updates of a constant regressor (+ tiny noise),
    // then excited again with a changed parameter
    const bool still = (k >= 3000) && (k < 7000);
    if (k == 7000) th[0] *= 1.2;
    int32_t phi[CANFDI_CFG_RLS_MAX_PARAMS];
    double phid[CANFDI_CFG_RLS_MAX_PARAMS];
    double y = 0.0;
    for (int i = 0; i < n; i++) {
      const int e = sc[static_cast<size_t>(i)];
      const double x = still ? hold[static_cast<size_t>(i)] + std::ldexp(1e-4 * nrand(), e)
                             : std::ldexp(2.0 * urand() - 1.0, e);
      phi[i] = ref::q16i(x);
      phid[i] = ref::q16d(phi[i]);
      y += th[static_cast<size_t>(i)] * phid[i];
    }
    const int32_t yq = ref::q16i(y + 0.02 * nrand());
    canfdi_rls_update(&r, phi, yq);
    d.update(phid, ref::q16d(yq));
    if ((k % 100) == 99) {
      for (int i = 0; i < n; i++) {
        const double tf = static_cast<double>(canfdi_rls_theta_qn(&r, static_cast<unsigned>(i), 20U)) / 1048576.0;
        const double e = std::fabs(tf - d.theta(i)) / std::max(1.0, std::fabs(d.theta(i)));
        if ((k >= 3000) && (k < 8000)) {
          res.th_wound = std::max(res.th_wound, e);
        } else {
          res.th = std::max(res.th, e);
        }
        for (int j = 0; j < n; j++) {
          const double sc = std::sqrt(d.P()(i, i) * d.P()(j, j));
          // badly scaled: a read-out format with ~29 bits below sqrt(P_ii P_jj)
          // (P spans 2^24; Q20 would resolve its small entries to 5e-4)
          const int fr = bad ? static_cast<int>(std::fmin(31.0, std::fmax(0.0, 29.0 - std::ceil(std::log2(sc))))) : 20;
          const double pf = std::ldexp(static_cast<double>(canfdi_rls_cov_qn(&r, static_cast<unsigned>(i),
                                                                             static_cast<unsigned>(j),
                                                                             static_cast<unsigned>(fr))),
                                       -fr);
          res.p = std::max(res.p, std::fabs(pf - d.P()(i, j)) / (bad ? sc : std::max(1e-3, sc)));
        }
      }
    }
  }
  res.upd_f = canfdi_rls_diag(&r)->updates;
  res.skip_f = canfdi_rls_diag(&r)->skipped;
  res.clip_f = canfdi_rls_diag(&r)->trace_clips;
  res.upd_d = d.updates;
  res.skip_d = d.skipped;
  return res;
}

}  // namespace

int main() {
  ref::Tally t;
  for (int gate = 1; gate >= 0; gate--) {
    for (int n = 1; n <= static_cast<int>(CANFDI_CFG_RLS_MAX_PARAMS); n++) {
      const Result r = run(n, gate != 0, static_cast<uint64_t>(n));
      const bool same = (r.upd_f == r.upd_d) && (r.skip_f == r.skip_d);
      t.check((r.th <= 1e-5) && (r.th_wound <= 1e-3) && (r.p <= 1e-4) && same,
              "rls n=%d %s: max |theta_fix - theta_double| %.2e (rel; %.2e in 3000..8000), max |P_fix - "
              "P_double| %.2e (rel), updates %ld/%ld skipped %ld/%ld (fix/double), trace clips %ld",
              n, gate ? "gated  " : "no gate", r.th, r.th_wound, r.p, r.upd_f, r.upd_d, r.skip_f, r.skip_d, r.clip_f);
    }
  }
  // badly scaled regressors (n = 4 and 6), gated: without the gate the
  // constant stretch winds P up to a condition number near 2^60, where the
  // double-precision covariance form itself loses every digit of the small
  // entries (the previous fixed-point code and this one differ from it by
  // 0.9 there alike), so that case is left to tests/unit/test_rls.c
  for (int gate = 1; gate >= 1; gate--) {
    for (int n = 4; n <= static_cast<int>(CANFDI_CFG_RLS_MAX_PARAMS); n += 2) {
      const Result r = run(n, gate != 0, static_cast<uint64_t>(n) + 40U, true);
      const bool same = (r.upd_f == r.upd_d) && (r.skip_f == r.skip_d);
      t.check((r.th <= 2e-5) && (r.th_wound <= 2e-5) && (r.p <= 1e-4) && same,
              "rls n=%d %s, regressors 2^-6..2^6 normalised: max |theta_fix - theta_double| %.2e (rel; %.2e in "
              "3000..8000), max |P_fix - P_double| %.2e (rel), updates %ld/%ld skipped %ld/%ld, trace clips %ld",
              n, gate ? "gated  " : "no gate", r.th, r.th_wound, r.p, r.upd_f, r.upd_d, r.skip_f, r.skip_d, r.clip_f);
    }
  }
  return t.finish();
}
