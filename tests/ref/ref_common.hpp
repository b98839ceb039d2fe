// ref_common.hpp — shared pieces of the double-precision (MIL) reference
// programs in tests/ref/: a pass/fail tally, traces from the host_sim plant
// library, and the Eigen/double twins of the fixed-point model-layer modules
// (state-variable filter, RLS, DC-motor and throttle estimators).
//
// The twins implement the SAME algorithms as firmware/model/ — same
// discretisation, same normalisation, same gates and decimation — in double
// precision, so that any difference between the two is the cost of the
// fixed-point arithmetic. The RLS twin uses the plain covariance form
// (mathematically identical to the UD form; double has the margin).
#ifndef CANFDI_REF_COMMON_HPP
#define CANFDI_REF_COMMON_HPP

#include <Eigen/Dense>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdarg>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <vector>

extern "C" {
#include "canfdi_sim.h"
#include "canfdi_sim_fault.h"
#include "canfdi_sim_profile.h"
#include "canfdi_sim_refctl.h"
#include "model/canfdi_est_dcm.h"
#include "model/canfdi_est_thr.h"
#include "model/canfdi_rls.h"
#include "model/canfdi_svf.h"
}

namespace ref {

constexpr double kT = static_cast<double>(CANFDI_CFG_STEP_US) * 1e-6;
constexpr double kQ16 = 65536.0;

inline double q16d(int32_t x) { return static_cast<double>(x) / kQ16; }
inline int32_t q16i(double x) { return static_cast<int32_t>(std::lround(x * kQ16)); }
inline double q31d(int32_t x) { return static_cast<double>(x) / 2147483648.0; }

// ---- tally ----------------------------------------------------------------

struct Tally {
  int passed = 0;
  int failed = 0;
  void check(bool ok, const char *fmt, ...) __attribute__((format(printf, 3, 4))) {
    va_list ap;
    va_start(ap, fmt);
    std::printf("%s ", ok ? "PASS" : "FAIL");
    std::vprintf(fmt, ap);
    std::printf("\n");
    va_end(ap);
    (ok ? passed : failed) += 1;
  }
  int finish() const {
    std::printf("%d passed, %d failed\n", passed, failed);
    return (failed == 0) ? 0 : 1;
  }
};

// ---- traces from the plant library ----------------------------------------

struct DcmSample {
  int32_t ua_q16, ia_q16, w_q16;
};
struct ThrSample {
  int32_t u_q16, i_q16, angle_q16;
};

// Isermann's motor (R_A 1.52 held, thermal off), load 1.2 N m, reference
// speed controller, setpoint 100 rad/s + PRBS +-30 rad/s (20 ms bits) on
// [prbs_t0, prbs_t1), sensor noise as in host_sim/scenarios/nominal.scn.
// Optional abrupt dcm_ra_up of ra_step (relative) at fault_t.
inline std::vector<DcmSample> dcm_trace(uint64_t seed, double seconds, double prbs_t0, double prbs_t1,
                                        double fault_t = -1.0, double ra_step = 0.0) {
  static canfdi_sim_t sim;
  canfdi_sim_cfg_t cfg;
  canfdi_sim_default_cfg(&cfg);
  cfg.dcm.ra_cold_ohm = 1.52;
  cfg.dcm.thermal = false;
  cfg.sigma[CANFDI_SIM_S_DCM_UA] = 0.05;
  cfg.sigma[CANFDI_SIM_S_DCM_IA] = 0.02;
  cfg.sigma[CANFDI_SIM_S_DCM_SPEED] = 0.2;
  cfg.seed = seed;
  std::vector<DcmSample> out;
  if (canfdi_sim_init(&sim, &cfg) != CANFDI_OK) {
    return out;
  }
  if (fault_t >= 0.0) {
    canfdi_sim_fault_spec_t fs;
    const int id = canfdi_sim_fault_find("dcm_ra_up");
    if ((id < 0) ||
        (canfdi_sim_fault_spec_make(&fs, static_cast<uint8_t>(id), CANFDI_SIM_MODE_ABRUPT, fault_t, ra_step, 0, 0, 0) !=
         CANFDI_OK) ||
        (canfdi_sim_add_fault(&sim, &fs) != CANFDI_OK)) {
      return out;
    }
  }
  canfdi_sim_refctl_cfg_t rc;
  canfdi_sim_refctl_default(&rc, &cfg);
  canfdi_sim_refctl_t ctl;
  canfdi_sim_refctl_init(&ctl, &rc);
  static canfdi_sim_profile_t sp;
  canfdi_sim_profile_init(&sp, -400.0, 400.0);
  canfdi_sim_profile_add(&sp, CANFDI_SIM_PROF_CONST, 0, 0, 100.0, 0, 0);
  if (prbs_t1 > prbs_t0) {
    canfdi_sim_profile_add(&sp, CANFDI_SIM_PROF_PRBS, prbs_t0, prbs_t1, 30.0, 0.02, 11U + static_cast<uint32_t>(seed));
  }
  const long n = std::lround(seconds / kT);
  out.reserve(static_cast<size_t>(n));
  for (long k = 0; k < n; k++) {
    canfdi_sim_in_t in;
    std::memset(&in, 0, sizeof in);
    canfdi_sim_refctl_step(&ctl, canfdi_sim_profile_eval(&sp, static_cast<int64_t>(k) * CANFDI_CFG_STEP_US), 30.0,
                           &sim.meas, &in);
    in.dcm.load_Nm = 1.2;
    canfdi_sim_step(&sim, &in);
    out.push_back({q16i(sim.meas.value[CANFDI_SIM_S_DCM_UA]), q16i(sim.meas.value[CANFDI_SIM_S_DCM_IA]),
                   q16i(sim.meas.value[CANFDI_SIM_S_DCM_SPEED])});
  }
  return out;
}

// Throttle with the parameters of docs/design.md under the reference position
// controller: 45 deg + 0.5 Hz sine of +-30 deg + PRBS +-2 deg (50 ms bits);
// noise TPS 0.003 V, current 0.01 A, supply 0.01 V. Voltage = command
// clamped to the measured supply; angle = mean of the two TPS.
inline std::vector<ThrSample> thr_trace(uint64_t seed, double seconds) {
  static canfdi_sim_t sim;
  canfdi_sim_cfg_t cfg;
  canfdi_sim_default_cfg(&cfg);
  cfg.sigma[CANFDI_SIM_S_THR_TPS1] = 0.003;
  cfg.sigma[CANFDI_SIM_S_THR_TPS2] = 0.003;
  cfg.sigma[CANFDI_SIM_S_THR_I] = 0.01;
  cfg.sigma[CANFDI_SIM_S_THR_SUPPLY] = 0.01;
  cfg.seed = seed;
  std::vector<ThrSample> out;
  if (canfdi_sim_init(&sim, &cfg) != CANFDI_OK) {
    return out;
  }
  canfdi_sim_refctl_cfg_t rc;
  canfdi_sim_refctl_default(&rc, &cfg);
  canfdi_sim_refctl_t ctl;
  canfdi_sim_refctl_init(&ctl, &rc);
  static canfdi_sim_profile_t ap;
  canfdi_sim_profile_init(&ap, 0.0, 90.0);
  canfdi_sim_profile_add(&ap, CANFDI_SIM_PROF_CONST, 0, 0, 45.0, 0, 0);
  canfdi_sim_profile_add(&ap, CANFDI_SIM_PROF_SINE, 0.5, 1e4, 30.0, 0.5, 0);
  canfdi_sim_profile_add(&ap, CANFDI_SIM_PROF_PRBS, 0.5, 1e4, 2.0, 0.05, 29U + static_cast<uint32_t>(seed));
  const long n = std::lround(seconds / kT);
  out.reserve(static_cast<size_t>(n));
  for (long k = 0; k < n; k++) {
    canfdi_sim_in_t in;
    std::memset(&in, 0, sizeof in);
    canfdi_sim_refctl_step(&ctl, 0.0, canfdi_sim_profile_eval(&ap, static_cast<int64_t>(k) * CANFDI_CFG_STEP_US),
                           &sim.meas, &in);
    in.dcm.enable = false;
    canfdi_sim_step(&sim, &in);
    const double sup = sim.meas.value[CANFDI_SIM_S_THR_SUPPLY];
    const double u = std::max(-sup, std::min(sup, in.thr.u_cmd_V));
    const double ang = canfdi_sim_refctl_angle_deg(sim.meas.value[CANFDI_SIM_S_THR_TPS1],
                                                   sim.meas.value[CANFDI_SIM_S_THR_TPS2]) *
                       M_PI / 180.0;
    out.push_back({q16i(u), q16i(sim.meas.value[CANFDI_SIM_S_THR_I]), q16i(ang)});
  }
  return out;
}

// ---- SVF twin ---------------------------------------------------------------

// Trapezoidal rule on the normalised binomial integrator chain, exactly as
// canfdi_svf.h documents: dv = G w, G = h (I - h M)^-1, w = 2 M v + b (u_k + u_k+1).
class Svf {
 public:
  Svf(int order, double wc) : n_(order), wc_(wc) {
    const double h = wc * kT / 2.0;
    M_ = Eigen::MatrixXd::Zero(n_, n_);
    for (int i = 0; i + 1 < n_; i++) M_(i, i + 1) = 1.0;
    if (n_ == 2) {
      M_(1, 0) = -1.0;
      M_(1, 1) = -2.0;
    } else {
      M_(2, 0) = -1.0;
      M_(2, 1) = -3.0;
      M_(2, 2) = -3.0;
    }
    G_ = h * (Eigen::MatrixXd::Identity(n_, n_) - h * M_).inverse();
    v_ = Eigen::VectorXd::Zero(n_);
    reset(0.0);
  }
  void reset(double x0) {
    v_.setZero();
    v_(0) = x0;
    u_prev_ = x0;
    y_ = x0;
    dy_ = 0.0;
    d2y_ = 0.0;
  }
  void step(double x) {
    Eigen::VectorXd w = 2.0 * (M_ * v_);
    w(n_ - 1) += u_prev_ + x;
    v_ += G_ * w;
    u_prev_ = x;
    y_ = v_(0);
    dy_ = wc_ * v_(1);
    d2y_ = (n_ == 3) ? wc_ * wc_ * v_(2) : wc_ * wc_ * (x - v_(0) - 2.0 * v_(1));
  }
  double y() const { return y_; }
  double dy() const { return dy_; }
  double d2y() const { return d2y_; }

 private:
  int n_;
  double wc_;
  Eigen::MatrixXd M_, G_;
  Eigen::VectorXd v_;
  double u_prev_ = 0, y_ = 0, dy_ = 0, d2y_ = 0;
};

// ---- RLS twin -----------------------------------------------------------------

// Covariance-form RLS with the firmware's normalisation, excitation gate
// (per-regressor running mean and mean-square deviation, minimum over the
// mask), forgetting applied only on updates, and trace bound (P scaled).
class Rls {
 public:
  explicit Rls(const canfdi_rls_cfg_t &c) : c_(c), n_(c.n_params) {
    lam_ = 1.0 - q31d(c.forget_q31);
    reset(false);
  }
  void reset(bool keep_theta) {
    P_ = Eigen::MatrixXd::Identity(n_, n_) * q16d(c_.p0_q16);
    if (!keep_theta) {
      th_ = Eigen::VectorXd::Zero(n_);
      for (int i = 0; i < n_; i++) th_(i) = std::ldexp(q16d(c_.theta0_q16[i]), c_.phi_shift[i] - c_.y_shift);
    }
    mean_ = Eigen::VectorXd::Zero(n_);
    ex_ = Eigen::VectorXd::Zero(n_);
    primed_ = false;
  }
  // theta_i in physical units
  double theta(int i) const { return std::ldexp(th_(i), c_.y_shift - c_.phi_shift[i]); }
  void set_theta(int i, double v) { th_(i) = std::ldexp(v, c_.phi_shift[i] - c_.y_shift); }
  double trace() const { return P_.trace(); }
  const Eigen::MatrixXd &P() const { return P_; }
  double excitation() const {
    double m = 0.0;
    bool first = true;
    for (int i = 0; i < n_; i++) {
      if (gated(i) && (first || ex_(i) < m)) {
        m = ex_(i);
        first = false;
      }
    }
    return m;
  }
  bool update(const double *phi, double y) {
    const double a = std::ldexp(1.0, -c_.excite_shift);
    if (!primed_) {
      for (int i = 0; i < n_; i++) mean_(i) = phi[i];
      ex_.setZero();
      primed_ = true;
    }
    for (int i = 0; i < n_; i++) {
      const double dev = phi[i] - mean_(i);
      const double dn = std::ldexp(dev, -c_.phi_shift[i]);
      ex_(i) += (dn * dn - ex_(i)) * a;
      mean_(i) += dev * a;
    }
    const bool go = (c_.excite_min_q16 == 0) || (excitation() >= q16d(c_.excite_min_q16));
    Eigen::VectorXd f(n_);
    for (int i = 0; i < n_; i++) f(i) = std::ldexp(phi[i], -c_.phi_shift[i]);
    const double yn = std::ldexp(y, -c_.y_shift);
    const double e = yn - th_.dot(f);
    if (go) {
      const Eigen::VectorXd pf = P_ * f;
      const double den = lam_ + f.dot(pf);
      th_ += pf * (e / den);
      P_ = (P_ - pf * pf.transpose() / den) / lam_;
      P_ = 0.5 * (P_ + P_.transpose());
      const double tm = q16d(c_.trace_max_q16);
      if (P_.trace() > tm) P_ *= tm / P_.trace();
      updates++;
    } else {
      skipped++;
    }
    return go;
  }
  long updates = 0;
  long skipped = 0;

 private:
  bool gated(int i) const { return (c_.excite_mask == 0U) || (((c_.excite_mask >> i) & 1U) != 0U); }
  canfdi_rls_cfg_t c_;
  int n_;
  double lam_;
  Eigen::MatrixXd P_;
  Eigen::VectorXd th_, mean_, ex_;
  bool primed_ = false;
};

// RLS configuration exactly as the estimators build it.
inline canfdi_rls_cfg_t est_rls_cfg(int n, canfdi_q31_t forget, int32_t p0, int32_t trmax, int32_t exmin, uint8_t exshift,
                                    uint16_t mask, int8_t ys, std::initializer_list<int> shifts) {
  canfdi_rls_cfg_t c;
  std::memset(&c, 0, sizeof c);
  c.n_params = static_cast<uint8_t>(n);
  c.forget_q31 = forget;
  c.p0_q16 = p0;
  c.trace_max_q16 = trmax;
  c.excite_min_q16 = exmin;
  c.excite_shift = exshift;
  c.excite_mask = mask;
  c.y_shift = ys;
  int i = 0;
  for (int s : shifts) c.phi_shift[i++] = static_cast<int8_t>(s);
  return c;
}

// ---- DC motor estimator twin ---------------------------------------------------

class EstDcm {
 public:
  explicit EstDcm(const canfdi_est_dcm_cfg_t &c)
      : c_(c),
        su_(c.svf.order, c.svf.omega_c_rad_s),
        si_(c.svf.order, c.svf.omega_c_rad_s),
        sw_(c.svf.order, c.svf.omega_c_rad_s),
        arm_(est_rls_cfg(3, c.forget_q31, c.p0_q16, c.trace_max_q16, c.excite_min_q16, c.excite_shift, 0x5U,
                         CANFDI_EST_DCM_SHIFT_U, {CANFDI_EST_DCM_SHIFT_I, CANFDI_EST_DCM_SHIFT_DI, CANFDI_EST_DCM_SHIFT_W})),
        mech_(est_rls_cfg(3, c.forget_q31, c.p0_q16, c.trace_max_q16, c.excite_min_q16, c.excite_shift, 0x3U,
                          CANFDI_EST_DCM_SHIFT_I, {CANFDI_EST_DCM_SHIFT_DW, CANFDI_EST_DCM_SHIFT_W, 0})) {
    reset(false);
  }
  void reset(bool keep) {
    arm_.reset(keep);
    mech_.reset(keep);
    if (!keep) {
      const double psi = q16d(c_.psi_nom_q16);
      arm_.set_theta(0, q16d(c_.ra_nom_q16));
      arm_.set_theta(1, c_.la_nom_q24 / 16777216.0);
      arm_.set_theta(2, psi);
      mech_.set_theta(0, c_.j_nom_q24 / 16777216.0 / psi);
      mech_.set_theta(1, c_.mf1_nom_q24 / 16777216.0 / psi);
      mech_.set_theta(2, q16d(c_.mc_nom_q16) / psi);
    }
    phase_ = 0;
    started_ = false;
    arm_n_ = 0;
    mech_n_ = 0;
  }
  void step(const DcmSample &s) {
    const double u = q16d(s.ua_q16), i = q16d(s.ia_q16), w = q16d(s.w_q16);
    if (!started_) {
      su_.reset(u);
      si_.reset(i);
      sw_.reset(w);
      started_ = true;
      return;
    }
    su_.step(u);
    si_.step(i);
    sw_.step(w);
    phase_ = (phase_ + 1 >= c_.decim) ? 0 : phase_ + 1;
    if (phase_ == 0) {
      const double phi[3] = {si_.y(), si_.dy(), sw_.y()};
      if (arm_.update(phi, su_.y() + 0.5 * kT * su_.dy())) arm_n_++;
    }
    if (phase_ == ((c_.decim > 1) ? 1 : 0)) {
      const double phi[3] = {sw_.dy(), sw_.y(), 1.0};
      if (mech_.update(phi, si_.y())) mech_n_++;
    }
  }
  bool arm_converged() const { return arm_n_ >= static_cast<long>(c_.conv_updates); }
  double ra() const { return arm_.theta(0); }
  double la() const { return arm_.theta(1); }
  double psi() const { return arm_.theta(2); }
  double psi_mech() const { return arm_converged() ? psi() : q16d(c_.psi_nom_q16); }
  double j() const { return psi_mech() * mech_.theta(0); }
  double mf1() const { return psi_mech() * mech_.theta(1); }
  double mc() const { return psi_mech() * mech_.theta(2); }
  const Rls &arm() const { return arm_; }
  const Rls &mech() const { return mech_; }

 private:
  canfdi_est_dcm_cfg_t c_;
  Svf su_, si_, sw_;
  Rls arm_, mech_;
  int phase_ = 0;
  bool started_ = false;
  long arm_n_ = 0, mech_n_ = 0;
};

// ---- throttle estimator twin -----------------------------------------------------

class EstThr {
 public:
  explicit EstThr(const canfdi_est_thr_cfg_t &c)
      : c_(c),
        su_(c.svf.order, c.svf.omega_c_rad_s),
        si_(c.svf.order, c.svf.omega_c_rad_s),
        sa_(c.svf.order, c.svf.omega_c_rad_s),
        ss_(c.svf.order, c.svf.omega_c_rad_s),
        el_(est_rls_cfg(4, c.forget_q31, c.p0_q16, c.trace_max_q16, c.excite_min_q16, c.excite_shift, 0x5U,
                        CANFDI_EST_THR_SHIFT_U,
                        {CANFDI_EST_THR_SHIFT_I, CANFDI_EST_THR_SHIFT_DI, CANFDI_EST_THR_SHIFT_DA, 0})),
        mech_(est_rls_cfg(5, c.mech_forget_q31, c.p0_q16, c.trace_max_q16, c.excite_min_q16, c.excite_shift, 0x6U,
                          CANFDI_EST_THR_SHIFT_I,
                          {CANFDI_EST_THR_SHIFT_D2A, CANFDI_EST_THR_SHIFT_DA, CANFDI_EST_THR_SHIFT_A, 0, 0})) {
    reset(false);
  }
  void reset(bool keep) {
    el_.reset(keep);
    mech_.reset(keep);
    if (!keep) {
      const double k = q16d(c_.k_nom_q16);
      const double ks = c_.spring_nom_q24 / 16777216.0;
      el_.set_theta(0, q16d(c_.r_nom_q16));
      el_.set_theta(1, c_.l_nom_q24 / 16777216.0);
      el_.set_theta(2, k);
      el_.set_theta(3, q16d(c_.u0_nom_q16));
      mech_.set_theta(0, c_.j_nom_q24 / 16777216.0 / k);
      mech_.set_theta(1, c_.b_nom_q24 / 16777216.0 / k);
      mech_.set_theta(2, ks / k);
      mech_.set_theta(3, (q16d(c_.pretension_nom_q16) - ks * q16d(c_.limp_home_q16)) / k);
      mech_.set_theta(4, q16d(c_.friction_nom_q16) / k);
    }
    phase_ = 0;
    started_ = false;
    since_clip_ = 0;
    moving_ = 0;
    last_dir_ = 0;
    el_n_ = 0;
    mech_n_ = 0;
  }
  void step(const ThrSample &smp) {
    const double u = q16d(smp.u_q16), i = q16d(smp.i_q16), a = q16d(smp.angle_q16);
    if (!started_) {
      su_.reset(u);
      si_.reset(i);
      sa_.reset(a);
      ss_.reset(0.0);
      started_ = true;
      return;
    }
    const double v = sa_.dy(), band = q16d(c_.sign_band_q16);
    const int dir = (v > band) ? 1 : ((v < -band) ? -1 : 0);
    if ((dir == 0) || (dir != last_dir_)) {
      moving_ = 0;
    } else {
      moving_++;
    }
    last_dir_ = dir;
    if ((c_.i_limit_q16 > 0) && (std::fabs(i) >= q16d(c_.i_limit_q16))) {
      since_clip_ = 0;
    } else {
      since_clip_++;
    }
    su_.step(u);
    si_.step(i);
    sa_.step(a);
    ss_.step(static_cast<double>(dir));
    phase_ = (phase_ + 1 >= c_.decim) ? 0 : phase_ + 1;
    const long hold = c_.holdoff_steps;
    if ((phase_ == 0) && (since_clip_ >= hold)) {
      const double phi[4] = {si_.y(), si_.dy(), sa_.dy(), 1.0};
      if (el_.update(phi, su_.y() + 0.5 * kT * su_.dy())) el_n_++;
    }
    if ((phase_ == ((c_.decim > 1) ? 1 : 0)) && (since_clip_ >= hold) &&
        (sa_.y() > q16d(c_.limp_home_q16) + q16d(c_.limp_band_q16)) && (moving_ >= hold)) {
      const double phi[5] = {sa_.d2y(), sa_.dy(), sa_.y(), 1.0, ss_.y()};
      if (mech_.update(phi, si_.y())) mech_n_++;
    }
  }
  bool el_converged() const { return el_n_ >= static_cast<long>(c_.conv_updates); }
  double r() const { return el_.theta(0); }
  double l() const { return el_.theta(1); }
  double k() const { return el_.theta(2); }
  double u0() const { return el_.theta(3); }
  double km() const { return el_converged() ? k() : q16d(c_.k_nom_q16); }
  double j() const { return km() * mech_.theta(0); }
  double b() const { return km() * mech_.theta(1); }
  double spring() const { return km() * mech_.theta(2); }
  double pretension() const { return km() * mech_.theta(3) + spring() * q16d(c_.limp_home_q16); }
  double friction() const { return km() * mech_.theta(4); }

 private:
  canfdi_est_thr_cfg_t c_;
  Svf su_, si_, sa_, ss_;
  Rls el_, mech_;
  int phase_ = 0;
  bool started_ = false;
  long since_clip_ = 0, moving_ = 0;
  int last_dir_ = 0;
  long el_n_ = 0, mech_n_ = 0;
};

}  // namespace ref

#endif  // CANFDI_REF_COMMON_HPP
