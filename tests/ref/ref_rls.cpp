// ref_rls.cpp — the fixed-point UD RLS (firmware/model/canfdi_rls) against
// its double-precision covariance-form twin (ref_common.hpp, Eigen), fed the
// same Q16.16 samples, for n = 1..CANFDI_CFG_RLS_MAX_PARAMS, with
//   - excitation that stops and resumes (the gate must take the same
//     decisions: identical update/skip counts), and
//   - a stretch without the gate where forgetting drives the trace into its
//     bound (the clipping must agree too).
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

Result run(int n, bool gate, uint64_t seed) {
  g_s = seed * 0x9E3779B97F4A7C15ULL + 7U;
  canfdi_rls_cfg_t c;
  std::memset(&c, 0, sizeof c);
  c.n_params = static_cast<uint8_t>(n);
  c.y_shift = 3;
  for (int i = 0; i < n; i++) c.phi_shift[i] = static_cast<int8_t>((i % 4) * 2 - 2);
  c.forget_q31 = CANFDI_Q31_RATIO(1, 100);
  c.p0_q16 = 100 * 65536;
  c.trace_max_q16 = 1000 * 65536;
  c.excite_min_q16 = gate ? ref::q16i(1e-3) : 0;
  c.excite_shift = 6U;
  c.excite_mask = 0U;
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
  std::vector<double> hold(static_cast<size_t>(n));
  for (int i = 0; i < n; i++) hold[static_cast<size_t>(i)] = std::ldexp(0.5 + 0.1 * i, c.phi_shift[i]);
  for (int k = 0; k < 12000; k++) {
    // excited, then 4000 updates of a constant regressor (+ tiny noise),
    // then excited again with a changed parameter
    const bool still = (k >= 3000) && (k < 7000);
    if (k == 7000) th[0] *= 1.2;
    int32_t phi[CANFDI_CFG_RLS_MAX_PARAMS];
    double phid[CANFDI_CFG_RLS_MAX_PARAMS];
    double y = 0.0;
    for (int i = 0; i < n; i++) {
      const double x = still ? hold[static_cast<size_t>(i)] + std::ldexp(1e-4 * nrand(), c.phi_shift[i])
                             : std::ldexp(2.0 * urand() - 1.0, c.phi_shift[i]);
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
          const double pf =
              static_cast<double>(canfdi_rls_cov_qn(&r, static_cast<unsigned>(i), static_cast<unsigned>(j), 20U)) /
              1048576.0;
          const double sc = std::sqrt(d.P()(i, i) * d.P()(j, j));
          res.p = std::max(res.p, std::fabs(pf - d.P()(i, j)) / std::max(1e-3, sc));
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
  return t.finish();
}
