// ref_svf.cpp — fixed-point state-variable filter (firmware/model/canfdi_svf)
// against its double-precision Eigen twin (ref_common.hpp), both fed the same
// Q16.16 samples of simulated, noisy plant signals (DC motor U_A, I_A, w;
// throttle angle), for both orders and corner frequencies 50..1000 rad/s.
//
// Tolerance, per sample and output k (0: y, 1: dy, 2: d2y), in Q16.16 LSB:
//   1 + 64 wc^k 2^-16 + wc^k |v| 2^-15 / h,    h = wc T / 2,
//   |v| = |y| + |dy| / wc + |d2y| / wc^2 (1-norm of the normalised states)
// - 1 LSB: the output is rounded to Q16.16 (0.5 LSB) and so, in effect, is
//   the comparison;
// - the normalised states carry 2^-32 resolution and the update rounds a
//   few times per step: the k-th output inherits wc^k 2^-32 per state LSB;
//   64 state LSBs of accumulated rounding is the budget;
// - G is stored in Q31, each entry (size ~h) within 2^-32 of the exact
//   value: a relative error ~2^-31 / h of the filter's coefficients. It
//   acts on increments of the size of the normalised state vector |v|, so
//   the k-th output may differ by wc^k |v| 2^-31 / h units
//   = wc^k |v| 2^-15 / h LSB. (If every rounding
//   error of G aligned over the filter's memory the bound would be ~20x
//   that; the budget is the typical size, and the ratio printed shows the
//   margin.) It matters for the second derivatives of large signals at
//   low wc (w ~ 130 rad/s, wc = 50: ~400 LSB of a d2y resolved to 2^-16).
// Samples whose fixed-point output saturates at the Q16.16 limits (second
// derivatives of the drive's voltage steps exceed 32767 units/s^2 — by
// design, counted by the filter) are excluded and counted.
// The figure printed is the largest error/tolerance ratio and the largest
// absolute error in LSB.
#include "ref_common.hpp"

int main() {
  ref::Tally t;
  const auto dcm = ref::dcm_trace(5U, 6.0, 0.5, 6.0);
  const auto thr = ref::thr_trace(5U, 6.0);
  struct Sig {
    const char *name;
    std::vector<int32_t> x;
  };
  std::vector<Sig> sigs = {{"dcm_ua", {}}, {"dcm_ia", {}}, {"dcm_w", {}}, {"thr_angle", {}}};
  for (const auto &s : dcm) {
    sigs[0].x.push_back(s.ua_q16);
    sigs[1].x.push_back(s.ia_q16);
    sigs[2].x.push_back(s.w_q16);
  }
  for (const auto &s : thr) sigs[3].x.push_back(s.angle_q16);
  t.check(!dcm.empty() && !thr.empty(), "plant traces generated (%zu + %zu samples)", dcm.size(), thr.size());

  const int orders[] = {2, 3};
  const int wcs[] = {50, 200, 300, 1000};
  for (int order : orders) {
    for (int wc : wcs) {
      for (const auto &sg : sigs) {
        canfdi_svf_t f;
        canfdi_svf_cfg_t cfg;
        cfg.order = static_cast<uint8_t>(order);
        cfg.omega_c_rad_s = wc;
        if (canfdi_svf_init(&f, &cfg) != CANFDI_OK) {
          t.check(false, "svf init order %d wc %d", order, wc);
          continue;
        }
        ref::Svf r(order, wc);
        canfdi_svf_reset(&f, sg.x[0]);
        r.reset(ref::q16d(sg.x[0]));
        double worst[3] = {0, 0, 0};
        double ratio[3] = {0, 0, 0};
        long sat = 0;
        const double h = wc * ref::kT / 2.0;
        for (size_t k = 1; k < sg.x.size(); k++) {
          canfdi_svf_step(&f, sg.x[k]);
          r.step(ref::q16d(sg.x[k]));
          const int32_t fx[3] = {canfdi_svf_y_q16(&f), canfdi_svf_dy_q16(&f), canfdi_svf_d2y_q16(&f)};
          const double rx[3] = {r.y() * ref::kQ16, r.dy() * ref::kQ16, r.d2y() * ref::kQ16};
          for (int i = 0; i < 3; i++) {
            if ((fx[i] == INT32_MAX) || (fx[i] == INT32_MIN)) {
              sat++;
              continue;
            }
            const double err = std::fabs(fx[i] - rx[i]);
            const double wk = std::pow(static_cast<double>(wc), i);
            const double vn = std::fabs(r.y()) + std::fabs(r.dy()) / wc + std::fabs(r.d2y()) / (1.0 * wc * wc);
            const double tol = 1.0 + 64.0 * wk * std::ldexp(1.0, -16) + wk * vn * std::ldexp(1.0, -15) / h;
            worst[i] = std::max(worst[i], err);
            ratio[i] = std::max(ratio[i], err / tol);
          }
        }
        const bool ok = (ratio[0] <= 1.0) && (ratio[1] <= 1.0) && (ratio[2] <= 1.0);
        t.check(ok,
                "svf order %d wc %4d %-9s max |fix - double| [LSB] (err/tol): y %.2f (%.2f)  dy %.2f (%.2f)  "
                "d2y %.2f (%.2f); saturated outputs excluded: %ld",
                order, wc, sg.name, worst[0], ratio[0], worst[1], ratio[1], worst[2], ratio[2], sat);
      }
    }
  }
  return t.finish();
}
