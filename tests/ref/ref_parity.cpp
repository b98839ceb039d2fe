// ref_parity.cpp — double-precision twins of the parity-equation modules
// (firmware/model/canfdi_parity_dcm.h, canfdi_parity_thr.h) fed the same
// host_sim traces as the fixed-point code; the differences are the cost of
// the fixed-point arithmetic and are checked against the tolerances the
// headers derive from their rounding analysis:
//   DC motor |r_fix - r_ref| <= 100 LSB of Q16.16 for r1, r4 (1.5 mV) and
//                    24 LSB for r2, r3 (0.4 mN m); R_A within 0.1 mOhm;
//   throttle CORR <= 2 LSB, ARM <= 24 LSB, POS1/POS2 <= 8 LSB while the
//                    observer's discrete decisions coincide (stick/slide,
//                    feedback source); steps where they differ are counted
//                    and must stay below 0.1 % of the run.
// The twins implement the same equations, the same sampling alignment, the
// same validity rules, gates and trackers in double; they use the configured
// (Q8.24 / Q16.16) parameter values as exact numbers, so parameter
// quantisation is not part of the measured difference (it is a model
// choice, like the parameter values themselves).
#include "ref_common.hpp"

extern "C" {
#include "canfdi_sim.h"
#include "canfdi_sim_refctl.h"
#include "gen/canfdi_faults.h"
#include "model/canfdi_parity_dcm.h"
#include "model/canfdi_parity_thr.h"
}

namespace {

using ref::kT;
using ref::q16d;

double q24d(int32_t x) { return static_cast<double>(x) / 16777216.0; }

double clampd(double x, double lo, double hi) { return std::min(hi, std::max(lo, x)); }

// canfdi_adapt twin: threshold = min(max, base + gain f), f a first-order
// low-pass of |du|/T; the first sample only primes.
struct AdaptRef {
  double base = 0, max = 0, gain = 0, alpha = 0;
  double f = 0, u_prev = 0, thr = 0;
  bool primed = false;
  void init(const canfdi_adapt_cfg_t &c) {
    base = q16d(c.base);
    max = q16d(c.max);
    gain = static_cast<double>(c.gain) / std::ldexp(1.0, c.gain_frac_bits);
    alpha = kT / (static_cast<double>(c.tau_us) * 1e-6 + kT);
    reset();
  }
  void reset() {
    f = 0;
    primed = false;
    thr = base;
  }
  double step(double u) {
    if (primed) f += alpha * (std::fabs(u - u_prev) / kT - f);
    u_prev = u;
    primed = true;
    thr = std::min(max, base + gain * f);
    return thr;
  }
  bool exceeds(double r) const { return std::fabs(r) > thr; }
};

// ---- DC motor twin ------------------------------------------------------------

struct PdcmRef {
  const canfdi_parity_dcm_cfg_t *cfg;
  double L, Psi, J, F1, F0, wband;
  double ra;
  ref::Svf su, si, sw, sz;
  AdaptRef thr[4];
  bool primed = false;
  int settle = 0, w_ok = 0, learn_left = 0, blk_n = 0;
  double i_prev = 0, w_prev = 0;
  double blk_ri = 0, blk_ii = 0, blk_rn = 0;
  bool blk_invalid = false;
  double bias[3] = {0, 0, 0};
  double r[4] = {0, 0, 0, 0}, rn[4] = {0, 0, 0, 0}, thv[4] = {0, 0, 0, 0};
  double dR = 0, dL = 0, dJ = 0;
  unsigned valid = 0;

  explicit PdcmRef(const canfdi_parity_dcm_cfg_t *c)
      : cfg(c), su(3, c->omega_c_rad_s), si(3, c->omega_c_rad_s), sw(3, c->omega_c_rad_s),
        sz(3, c->omega_c_rad_s) {
    L = q24d(c->la_H_q24);
    Psi = q24d(c->psi_Vs_q24);
    J = q24d(c->j_kgm2_q24);
    F1 = q24d(c->mf1_Nms_q24);
    F0 = q24d(c->mf0_Nm_q24);
    wband = q16d(c->w_band_rad_s_q16);
    ra = q24d(c->ra_ohm_q24);
    dR = q24d(c->unc_ra_ohm_q24);
    dL = q24d(c->unc_la_H_q24);
    dJ = q24d(c->unc_j_kgm2_q24);
    for (int j = 0; j < 4; j++) thr[j].init(c->band[j]);
    settle = c->settle_steps;
    learn_left = c->ra_track ? c->ra_learn_blocks : 0;
  }

  void ra_block() {
    const double imin = q16d(cfg->ra_i_min_A_q16);
    const double N = cfg->ra_block_steps;
    const bool learning = learn_left > 0;
    const double gate = q16d(cfg->ra_gate_q16) * N;
    const bool bad = std::fabs(blk_rn) > gate;
    if (!((bad && !learning) || blk_invalid || blk_ii < imin * imin * N)) {
      const double dr = blk_ri / blk_ii;
      double step;
      if (learning) {
        step = dr / 4.0;
        learn_left--;
      } else {
        const double blk_s = N * kT;
        const double smax = q24d(cfg->ra_rate_max_ohm_s_q24) * blk_s;
        step = clampd(dr * blk_s / static_cast<double>(cfg->ra_tau_s), -smax, smax);
      }
      ra = clampd(ra + step, q24d(cfg->ra_min_ohm_q24), q24d(cfg->ra_max_ohm_q24));
    }
    blk_ri = blk_ii = blk_rn = 0;
    blk_n = 0;
    blk_invalid = false;
  }

  void step(double U, double I, double W, double ML) {
    if (!primed) {
      i_prev = I;
      w_prev = W;
    }
    const double xi = 0.5 * (I + i_prev), xw = 0.5 * (W + w_prev);
    i_prev = I;
    w_prev = W;
    const double z = ML + F0 * clampd(xw / wband, -1.0, 1.0);
    if (!primed) {
      su.reset(U);
      si.reset(xi);
      sw.reset(xw);
      sz.reset(z);
      primed = true;
    }
    su.step(U);
    si.step(xi);
    sw.step(xw);
    sz.step(z);
    const double cI = Psi + F1 * ra / Psi, cdI = (J * ra + F1 * L) / Psi, cd2I = L * J / Psi;
    r[0] = su.y() - ra * si.y() - L * si.dy() - Psi * sw.y();
    r[1] = Psi * si.y() - J * sw.dy() - F1 * sw.y() - sz.y();
    r[2] = cI * si.y() + cdI * si.dy() + cd2I * si.d2y() - (J / Psi) * su.dy() - (F1 / Psi) * su.y() -
           sz.y();
    r[3] = su.y() - cI * sw.y() - cdI * sw.dy() - cd2I * sw.d2y() - (ra / Psi) * sz.y() -
           (L / Psi) * sz.dy();
    if (settle > 0) settle--;
    w_ok = (std::fabs(sw.y()) >= wband) ? w_ok + 1 : 0;
    valid = 0;
    if (settle == 0) {
      const bool ra_ok = learn_left == 0;
      valid = ra_ok ? 1U : 0U;
      if (w_ok >= cfg->settle_steps) valid |= ra_ok ? 0x0EU : 0x06U;
    }
    if (cfg->load_tau_s != 0U) {
      const double a = kT / static_cast<double>(cfg->load_tau_s);
      for (int j = 1; j < 4; j++) {
        if (valid & (1U << j)) bias[j - 1] += a * (r[j] - bias[j - 1]);
        r[j] -= bias[j - 1];
      }
    }
    // Uncertainty bands: sum over p of |dr/dp| dp (canfdi_parity_dcm.h).
    double unc[4];
    unc[0] = dR * std::fabs(si.y()) + dL * std::fabs(si.dy());
    unc[1] = dJ * std::fabs(sw.dy());
    unc[2] = dR * std::fabs((F1 * si.y() + J * si.dy()) / Psi) + dL * std::fabs((F1 * si.dy() + J * si.d2y()) / Psi) +
             dJ * std::fabs((ra * si.dy() + L * si.d2y() - su.dy()) / Psi);
    unc[3] = dR * std::fabs((F1 * sw.y() + J * sw.dy() + sz.y()) / Psi) +
             dL * std::fabs((F1 * sw.dy() + J * sw.d2y() + sz.dy()) / Psi) +
             dJ * std::fabs((ra * sw.dy() + L * sw.d2y()) / Psi);
    for (int j = 0; j < 4; j++) {
      thv[j] = std::min(thr[j].step(su.y()) + unc[j], q16d(cfg->band[j].max));
      rn[j] = r[j] / thv[j];
    }
    if (cfg->ra_track) {
      if (settle == 0) {
        blk_rn += rn[0];
        blk_ri += clampd(r[0], -64.0, 64.0) * si.y();
        blk_ii += si.y() * si.y();
      } else {
        blk_invalid = true;
      }
      if (++blk_n >= cfg->ra_block_steps) ra_block();
    }
  }
};

// ---- throttle twin ----------------------------------------------------------

struct PthrRef {
  const canfdi_parity_thr_cfg_t *cfg;
  double z1, z2, slope, sum, vmin, vmax, imax, R, L, K, J, B, ks, P, Tc, lh, lhw, tmax;
  double ke, stickw, restw, jump, ralpha, l1, l2, beta;
  ref::Svf su, si, sth;
  AdaptRef thr[4];
  bool primed = false, en_prev = false;
  int settle = 0, arm_ok = 0, cand_n = 0, in_band_n = 0;
  unsigned ok_prev = 0, src = CANFDI_PARITY_THR_SRC_MEAN, cand = CANFDI_PARITY_THR_SRC_NONE;
  double i_prev = 0, th1_prev = 0, th2_prev = 0, th_arm = 0, th_arm_prev = 0, inc_prev = 0;
  double th_hat = 0, w_hat = 0, corr_lp = 0, pos_lp[2] = {0, 0};
  double r[4] = {0, 0, 0, 0}, rn[4] = {0, 0, 0, 0}, thv[4] = {0, 0, 0, 0};
  unsigned valid = 0;

  explicit PthrRef(const canfdi_parity_thr_cfg_t *c)
      : cfg(c), su(3, c->omega_c_rad_s), si(3, c->omega_c_rad_s), sth(3, c->omega_c_rad_s) {
    // complementary characteristics: tps2.slope = -tps1.slope
    z1 = q16d(c->tps1.zero_V_q16);
    z2 = q16d(c->tps2.zero_V_q16);
    slope = q16d(c->tps1.slope_V_rad_q16);
    sum = z1 + z2;
    vmin = q16d(c->tps_min_V_q16);
    vmax = q16d(c->tps_max_V_q16);
    imax = q16d(c->i_max_A_q16);
    R = q24d(c->r_ohm_q24);
    L = q24d(c->l_H_q24);
    K = q24d(c->k_Nm_A_q24);
    J = q24d(c->j_kgm2_q24);
    B = q24d(c->b_Nms_q24);
    ks = q24d(c->spring_Nm_rad_q24);
    P = q24d(c->pretension_Nm_q24);
    Tc = q24d(c->friction_Nm_q24);
    lh = q16d(c->limp_home_rad_q16);
    lhw = q16d(c->lh_width_rad_q16);
    tmax = q16d(c->max_rad_q16);
    ke = ref::q31d(c->obs_emf_gain_q31);
    stickw = q16d(c->stick_w_rad_s_q16);
    restw = q16d(c->rest_w_rad_s_q16);
    jump = q16d(c->jump_rad_q16);
    ralpha = kT / (static_cast<double>(c->res_tau_us) * 1e-6 + kT);
    l1 = 2.0 * c->obs_lambda_rad_s * kT;
    l2 = static_cast<double>(c->obs_lambda_rad_s) * c->obs_lambda_rad_s * kT;
    // exact interval mean of a first-order R-L current (see the C code)
    const double x = R * kT / L;
    beta = 1.0 / (1.0 - std::exp(-x)) - 1.0 / x;
    for (int j = 0; j < 4; j++) thr[j].init(c->band[j]);
    settle = c->settle_steps;
    th_hat = lh;
  }

  static double median3(double a, double b, double c) {
    const double lo = std::min(a, b), hi = std::max(a, b);
    return (c < lo) ? lo : ((c > hi) ? hi : c);
  }

  unsigned source(bool ok1, bool ok2, double corr, double rate) {
    unsigned s = src;
    if (!ok1 && !ok2) {
      s = CANFDI_PARITY_THR_SRC_NONE;
    } else if (ok1 != ok2) {
      s = ok1 ? CANFDI_PARITY_THR_SRC_TPS1 : CANFDI_PARITY_THR_SRC_TPS2;
    } else if (!thr[CANFDI_PARITY_THR_CORR].exceeds(corr)) {
      in_band_n++;
      if (s != CANFDI_PARITY_THR_SRC_MEAN && in_band_n >= cfg->release_steps) s = CANFDI_PARITY_THR_SRC_MEAN;
      cand_n = 0;
    } else {
      in_band_n = 0;
      if (s == CANFDI_PARITY_THR_SRC_MEAN) {
        s = CANFDI_PARITY_THR_SRC_NONE;
        cand_n = 0;
      }
      if (s == CANFDI_PARITY_THR_SRC_NONE) {
        const double a1 = std::fabs(r[2]), a2 = std::fabs(r[3]);
        const bool rest = std::fabs(rate) <= restw;
        unsigned c = CANFDI_PARITY_THR_SRC_NONE;
        if (rest && a1 > cfg->select_ratio * a2 && a1 > thv[2]) {
          c = CANFDI_PARITY_THR_SRC_TPS2;
        } else if (rest && a2 > cfg->select_ratio * a1 && a2 > thv[3]) {
          c = CANFDI_PARITY_THR_SRC_TPS1;
        }
        if (c != CANFDI_PARITY_THR_SRC_NONE && c == cand) {
          cand_n++;
        } else {
          cand_n = (c != CANFDI_PARITY_THR_SRC_NONE) ? 1 : 0;
        }
        cand = c;
        if (c != CANFDI_PARITY_THR_SRC_NONE && cand_n >= cfg->select_steps) s = c;
      }
    }
    return s;
  }

  void step(double v1, double v2, double I, double U, double supply, bool en) {
    const bool ok1 = v1 >= vmin && v1 <= vmax, ok2 = v2 >= vmin && v2 <= vmax;
    const unsigned ok = (ok1 ? 1U : 0U) | (ok2 ? 2U : 0U);
    const double th1 = (v1 - z1) / slope, th2 = (z2 - v2) / slope;
    const double corr_raw = v1 + v2 - sum;
    const bool clip = std::fabs(I) >= imax;
    const double sup = std::max(0.0, supply);
    const double u = en ? clampd(U, -sup, sup) : 0.0;
    double th_mean = lh;
    if (ok1 && ok2) {
      th_mean = 0.5 * (th1 + th2);
    } else if (ok1) {
      th_mean = th1;
    } else if (ok2) {
      th_mean = th2;
    }
    if (!primed) {
      i_prev = I;
      th1_prev = th1;
      th2_prev = th2;
      ok_prev = ok;
      th_arm = th_arm_prev = th_mean;
      th_hat = th_mean;
      w_hat = 0;
      corr_lp = (ok1 && ok2) ? corr_raw : 0.0;
      pos_lp[0] = pos_lp[1] = 0;
      en_prev = en;
      su.reset(u);
      si.reset(I);
      sth.reset(th_mean);
      primed = true;
    }
    const double di = I - i_prev, i_avg = i_prev + beta * di;
    if (ok1 && ok2) corr_lp += ralpha * (corr_raw - corr_lp);
    const double corr = corr_lp;
    // theta_arm
    double inc;
    {
      const bool a = ok1 && (ok_prev & 1U), b = ok2 && (ok_prev & 2U);
      const double d1 = th1 - th1_prev, d2 = th2 - th2_prev;
      if (a && b) {
        inc = (std::fabs(d1 - d2) > jump) ? median3(d1, d2, inc_prev) : 0.5 * (d1 + d2);
      } else if (a) {
        inc = d1;
      } else if (b) {
        inc = d2;
      } else {
        inc = 0;
      }
      th_arm_prev = th_arm;
      th_arm += inc;
      if (ok1 && ok2 && !thr[CANFDI_PARITY_THR_CORR].exceeds(corr)) th_arm += (th_mean - th_arm) / 256.0;
      inc_prev = inc;
    }
    const double th_arm_avg = 0.5 * (th_arm + th_arm_prev);
    // observer
    const double rate = sth.dy();
    const bool emf_ok = en && !clip && std::fabs(i_prev) < imax;
    double thp, wp;
    {
      const double w0 = w_hat, d = th_hat - lh;
      const double drive = K * i_avg - B * w0 - ks * d - P * clampd(d / lhw, -1.0, 1.0);
      double w;
      if (std::fabs(w0) < stickw && std::fabs(drive) <= Tc) {
        w = 0;
      } else {
        const bool up = (w0 >= stickw) || (w0 > -stickw && drive > 0);
        w = w0 + (kT / J) * (up ? drive - Tc : drive + Tc);
        if ((w0 > 0 && w < 0) || (w0 < 0 && w > 0)) w = 0;
      }
      if (emf_ok) {
        const double wel = (u - R * i_avg - (L / kT) * di) / K;
        w += ke * (wel - w);
      }
      w = clampd(w, -2000.0, 2000.0);
      double th = th_hat + kT * w;
      if (th <= 0) {
        th = 0;
        w = std::max(w, 0.0);
      } else if (th >= tmax) {
        th = tmax;
        w = std::min(w, 0.0);
      }
      thp = th;
      wp = w;
    }
    const unsigned src_prev = src;
    src = source(ok1, ok2, corr, rate);
    if (src_prev == CANFDI_PARITY_THR_SRC_MEAN && src == CANFDI_PARITY_THR_SRC_NONE && ok1 && ok2) {
      const double half = 0.5 * std::fabs(th1 - th2);
      thp = clampd(thp, th_arm - half, th_arm + half);
    } else if (src == CANFDI_PARITY_THR_SRC_NONE && (ok1 || ok2) && !emf_ok) {
      thp = th_hat + inc;
    }
    if (src != CANFDI_PARITY_THR_SRC_NONE) {
      const double y = (src == CANFDI_PARITY_THR_SRC_MEAN) ? th_mean : ((src == CANFDI_PARITY_THR_SRC_TPS1) ? th1 : th2);
      const double e = y - thp;
      thp += l1 * e;
      wp += l2 * e;
    }
    thp = clampd(thp, 0.0, tmax);
    th_hat = thp;
    w_hat = wp;
    if (ok1) pos_lp[0] += ralpha * ((th1 - th_hat) - pos_lp[0]);
    if (ok2) pos_lp[1] += ralpha * ((th2 - th_hat) - pos_lp[1]);
    // armature
    if (en && !en_prev) {
      su.reset(u);
      si.reset(i_avg);
      sth.reset(th_arm_avg);
    }
    su.step(u);
    si.step(i_avg);
    sth.step(th_arm_avg);
    r[0] = corr;
    r[1] = su.y() - R * si.y() - L * si.dy() - K * sth.dy();
    r[2] = pos_lp[0];
    r[3] = pos_lp[1];
    arm_ok = (en && !clip && (ok1 || ok2)) ? arm_ok + 1 : 0;
    if (settle > 0) settle--;
    valid = 0;
    if (settle == 0) {
      valid = (ok1 && ok2) ? 1U : 0U;
      valid |= (arm_ok >= cfg->settle_steps) ? 2U : 0U;
      valid |= ok1 ? 4U : 0U;
      valid |= ok2 ? 8U : 0U;
    }
    for (int j = 0; j < 4; j++) {
      thv[j] = thr[j].step((j == CANFDI_PARITY_THR_ARM) ? u : th_arm);
      rn[j] = r[j] / thv[j];
    }
    i_prev = I;
    th1_prev = th1;
    th2_prev = th2;
    ok_prev = ok;
    en_prev = en;
  }
};

// ---- comparison statistics ------------------------------------------------------

struct Cmp {
  double max_lsb[4] = {0, 0, 0, 0};
  long n[4] = {0, 0, 0, 0};
  long beyond[4] = {0, 0, 0, 0};
  long valid_mismatch = 0;
  void add(int j, double fix, double ref, double tol_lsb) {
    const double e = std::fabs(fix - ref) * 65536.0;
    max_lsb[j] = std::max(max_lsb[j], e);
    n[j]++;
    if (e > tol_lsb) beyond[j]++;
  }
};

// ---- DC motor runs ---------------------------------------------------------------

struct DcmRun {
  const char *name;
  uint64_t seed;
  bool thermal;
  double cth;
  int fault_id;
  double fault_mag;
  double seconds;
  bool prbs;
};

// Worst-case rounding bounds of canfdi_parity_dcm.h (98, 19, 24, 98 LSB).
constexpr double kDcmTol[4] = {100.0, 24.0, 24.0, 100.0};

void run_dcm(ref::Tally &t, const DcmRun &run, canfdi_parity_dcm_cfg_t &cfg) {
  static canfdi_sim_t sim;
  static canfdi_parity_dcm_t fx;
  canfdi_sim_cfg_t sc;
  canfdi_sim_default_cfg(&sc);
  sc.dcm.thermal = run.thermal;
  if (run.cth > 0) sc.dcm.cth_J_K = run.cth;
  sc.sigma[CANFDI_SIM_S_DCM_UA] = 0.05;
  sc.sigma[CANFDI_SIM_S_DCM_IA] = 0.02;
  sc.sigma[CANFDI_SIM_S_DCM_SPEED] = 0.2;
  sc.seed = run.seed;
  canfdi_sim_init(&sim, &sc);
  canfdi_sim_refctl_cfg_t rc;
  canfdi_sim_refctl_default(&rc, &sc);
  canfdi_sim_refctl_t ctl;
  canfdi_sim_refctl_init(&ctl, &rc);
  canfdi_sim_dcm_set_state(&sim.dcm, 1.2 / 0.33, 100.0, sc.dcm.ambient_C);
  canfdi_sim_resample(&sim);
  if (run.fault_id >= 0) {
    canfdi_sim_fault_spec_t spec;
    canfdi_sim_fault_spec_make(&spec, static_cast<uint8_t>(run.fault_id), CANFDI_SIM_MODE_ABRUPT, run.seconds / 2.0,
                               run.fault_mag, 0, 0, 0);
    canfdi_sim_add_fault(&sim, &spec);
  }
  if (canfdi_parity_dcm_init(&fx, &cfg) != CANFDI_OK) {
    t.check(false, "dcm %s: init", run.name);
    return;
  }
  PdcmRef rf(&cfg);
  Cmp cmp;
  double max_dra = 0;
  double max_thr_lsb[4] = {0, 0, 0, 0};
  const long n = std::lround(run.seconds / kT);
  uint32_t lfsr = 0xACE1U;
  double wref = 100.0;
  for (long k = 0; k < n; k++) {
    if (run.prbs && (k % 20) == 0) {  // +-30 rad/s PRBS, 20 ms bits
      lfsr = (lfsr >> 1) ^ ((0U - (lfsr & 1U)) & 0xB400U);
      wref = 100.0 + ((lfsr & 1U) ? 30.0 : -30.0);
    }
    canfdi_sim_in_t in;
    in.dcm.load_Nm = 1.2;
    canfdi_sim_refctl_step(&ctl, wref, 10.0, &sim.meas, &in);
    canfdi_sim_step(&sim, &in);
    canfdi_parity_dcm_in_t pin;
    pin.u_V_q16 = ref::q16i(sim.meas.value[CANFDI_SIM_S_DCM_UA]);
    pin.i_A_q16 = ref::q16i(sim.meas.value[CANFDI_SIM_S_DCM_IA]);
    pin.w_rad_s_q16 = ref::q16i(sim.meas.value[CANFDI_SIM_S_DCM_SPEED]);
    pin.load_Nm_q16 = ref::q16i(1.2);
    const canfdi_parity_dcm_out_t *o = canfdi_parity_dcm_step(&fx, &pin);
    rf.step(q16d(pin.u_V_q16), q16d(pin.i_A_q16), q16d(pin.w_rad_s_q16), q16d(pin.load_Nm_q16));
    if (o->valid != rf.valid) cmp.valid_mismatch++;
    for (int j = 0; j < 4; j++) {
      if ((o->valid & rf.valid) & (1U << j)) cmp.add(j, q16d(o->r_q16[j]), rf.r[j], kDcmTol[j]);
      const double e = std::fabs(q16d(o->thr_q16[j]) - rf.thv[j]) * 65536.0;
      max_thr_lsb[j] = std::max(max_thr_lsb[j], e);
    }
    max_dra = std::max(max_dra, std::fabs(q24d(o->ra_hat_ohm_q24) - rf.ra));
  }
  std::printf("dcm %-28s max |r_fix - r_ref| [LSB]: r1 %.1f  r2 %.1f  r3 %.1f  r4 %.1f; |dR_A| %.2e Ohm; "
              "R_A %.4f (true %.4f)\n",
              run.name, cmp.max_lsb[0], cmp.max_lsb[1], cmp.max_lsb[2], cmp.max_lsb[3], max_dra, rf.ra,
              sim.dcm.ra_ohm);
  for (int j = 0; j < 4; j++) {
    t.check(cmp.n[j] > n / 2 && cmp.beyond[j] == 0, "dcm %s: r%d within %.0f LSB (max %.1f LSB, %ld samples)",
            run.name, j + 1, kDcmTol[j], cmp.max_lsb[j], cmp.n[j]);
  }
  t.check(cmp.valid_mismatch == 0, "dcm %s: validity flags identical (%ld mismatches)", run.name,
          cmp.valid_mismatch);
  t.check(max_dra <= 1e-4, "dcm %s: R_A estimates within 0.1 mOhm (%.2e Ohm)", run.name, max_dra);
  // Thresholds: the uncertainty band is sum |dr/dp| dp over the same
  // filtered signals, so its rounding error is that of the residual terms
  // scaled by dp/p (<= 5 %: at most 5 LSB of the residual bounds), plus one
  // rounding of each sensitivity (<= 0.5 LSB x dp) and of each of the three
  // products (0.5 LSB), plus the R_A difference (<= 0.1 mOhm x |sensitivity|,
  // < 1 LSB at the currents here): 8 LSB.
  for (int j = 0; j < 4; j++) {
    t.check(max_thr_lsb[j] <= 8.0, "dcm %s: threshold %d within 8 LSB (max %.1f LSB)", run.name, j + 1,
            max_thr_lsb[j]);
  }
}

// ---- throttle runs ----------------------------------------------------------------

struct ThrRun {
  const char *name;
  uint64_t seed;
  int prof;  // 0 const 20 deg, 1 sine 30+-10 deg 1 Hz, 2 steps 20<->40 deg
  int fault_id;
  double fault_mag;
  double ramp_s;
  double seconds;
};

double thr_angle(int prof, double t) {
  if (prof == 1) return 30.0 + 10.0 * std::sin(2.0 * M_PI * t);
  if (prof == 2) return (static_cast<long>(std::floor(t / 0.5)) % 2L == 0L) ? 20.0 : 40.0;
  return 20.0;
}

void run_thr(ref::Tally &t, const ThrRun &run, const canfdi_parity_thr_cfg_t &cfg) {
  static canfdi_sim_t sim;
  static canfdi_parity_thr_t fx;
  canfdi_sim_cfg_t sc;
  canfdi_sim_default_cfg(&sc);
  sc.sigma[CANFDI_SIM_S_THR_TPS1] = 0.002;
  sc.sigma[CANFDI_SIM_S_THR_TPS2] = 0.002;
  sc.sigma[CANFDI_SIM_S_THR_I] = 0.005;
  sc.seed = run.seed;
  canfdi_sim_init(&sim, &sc);
  canfdi_sim_refctl_cfg_t rc;
  canfdi_sim_refctl_default(&rc, &sc);
  canfdi_sim_refctl_t ctl;
  canfdi_sim_refctl_init(&ctl, &rc);
  if (run.fault_id >= 0) {
    canfdi_sim_fault_spec_t spec;
    canfdi_sim_fault_spec_make(&spec, static_cast<uint8_t>(run.fault_id),
                               run.ramp_s > 0 ? CANFDI_SIM_MODE_INCIPIENT : CANFDI_SIM_MODE_ABRUPT,
                               run.seconds / 3.0, run.fault_mag, run.ramp_s, 0, 0);
    canfdi_sim_add_fault(&sim, &spec);
  }
  if (canfdi_parity_thr_init(&fx, &cfg) != CANFDI_OK) {
    t.check(false, "thr %s: init", run.name);
    return;
  }
  PthrRef rf(&cfg);
  Cmp cmp;
  static const double tol[4] = {2.0, 24.0, 8.0, 8.0};
  long decision_diff = 0;
  double max_th = 0;
  const long n = std::lround(run.seconds / kT);
  for (long k = 0; k < n; k++) {
    canfdi_sim_in_t in;
    in.dcm.load_Nm = 0;
    canfdi_sim_refctl_step(&ctl, 0.0, thr_angle(run.prof, k * kT), &sim.meas, &in);
    canfdi_sim_step(&sim, &in);
    canfdi_parity_thr_in_t pin;
    pin.tps1_V_q16 = ref::q16i(sim.meas.value[CANFDI_SIM_S_THR_TPS1]);
    pin.tps2_V_q16 = ref::q16i(sim.meas.value[CANFDI_SIM_S_THR_TPS2]);
    pin.i_A_q16 = ref::q16i(sim.meas.value[CANFDI_SIM_S_THR_I]);
    pin.u_V_q16 = ref::q16i(in.thr.u_cmd_V);
    pin.supply_V_q16 = ref::q16i(sim.meas.value[CANFDI_SIM_S_THR_SUPPLY]);
    pin.enabled = in.thr.enable;
    const canfdi_parity_thr_out_t *o = canfdi_parity_thr_step(&fx, &pin);
    rf.step(q16d(pin.tps1_V_q16), q16d(pin.tps2_V_q16), q16d(pin.i_A_q16), q16d(pin.u_V_q16),
            q16d(pin.supply_V_q16), pin.enabled);
    if (o->valid != rf.valid) cmp.valid_mismatch++;
    if (o->src != rf.src) decision_diff++;
    max_th = std::max(max_th, std::fabs(q16d(o->theta_hat_rad_q16) - rf.th_hat) * 65536.0);
    for (int j = 0; j < 4; j++) {
      if ((o->valid & rf.valid) & (1U << j)) cmp.add(j, q16d(o->r_q16[j]), rf.r[j], tol[j]);
    }
  }
  const long beyond_pos = cmp.beyond[2] + cmp.beyond[3];
  std::printf("thr %-28s max |r_fix - r_ref| [LSB]: corr %.1f  arm %.1f  pos1 %.1f  pos2 %.1f; theta_hat %.1f LSB; "
              "POS steps beyond 8 LSB %ld, source differs %ld of %ld steps\n",
              run.name, cmp.max_lsb[0], cmp.max_lsb[1], cmp.max_lsb[2], cmp.max_lsb[3], max_th, beyond_pos,
              decision_diff, n);
  t.check(cmp.n[0] > n / 2 && cmp.beyond[0] == 0, "thr %s: CORR within 2 LSB (max %.1f)", run.name, cmp.max_lsb[0]);
  t.check(cmp.n[1] > n / 2 && cmp.beyond[1] == 0, "thr %s: ARM within 24 LSB (max %.1f)", run.name, cmp.max_lsb[1]);
  t.check(cmp.n[2] > n / 2 && beyond_pos * 1000 <= 2 * n,
          "thr %s: POS within 8 LSB except where a decision differs (%ld of %ld steps beyond)", run.name, beyond_pos,
          2 * n);
  t.check(decision_diff * 1000 <= n, "thr %s: feedback source identical in >= 99.9 %% of steps (%ld differ)",
          run.name, decision_diff);
  t.check(cmp.valid_mismatch == 0, "thr %s: validity flags identical (%ld mismatches)", run.name,
          cmp.valid_mismatch);
}

}  // namespace

int main() {
  ref::Tally t;
  canfdi_parity_dcm_cfg_t dcfg;
  canfdi_parity_dcm_default_cfg(&dcfg);
  static const DcmRun dcm_runs[] = {
      {"fault-free, PRBS +-30 rad/s", 1, false, 0, -1, 0, 20.0, true},
      {"R_A +10 % at 10 s", 2, false, 0, CANFDI_FAULT_DCM_RA_UP, 0.1, 20.0, true},
      {"I_A offset 0.6 A at 10 s", 3, false, 0, CANFDI_FAULT_DCM_IA_SENSOR_OFFSET, 0.6, 20.0, false},
      {"Psi -10 % at 10 s", 4, false, 0, CANFDI_FAULT_DCM_FLUX_DOWN, 0.1, 20.0, true},
  };
  for (const DcmRun &r : dcm_runs) run_dcm(t, r, dcfg);
  {
    // warm-up with the thermal capacitance / 10 and the tracker scaled alike
    // (as in tests/unit/test_parity_dcm.c): exercises the R_A tracker
    canfdi_parity_dcm_cfg_t wcfg = dcfg;
    wcfg.ra_tau_s = 6U;
    wcfg.ra_rate_max_ohm_s_q24 = static_cast<int32_t>(std::lround(0.005 * 16777216.0));
    const DcmRun warm = {"warm-up x10, 5 min", 5, true, 200.0, -1, 0, 300.0, false};
    run_dcm(t, warm, wcfg);
    canfdi_parity_dcm_cfg_t lcfg = dcfg;
    lcfg.load_tau_s = 2U;
    const DcmRun load = {"load tracking tau 2 s", 6, false, 0, -1, 0, 20.0, true};
    run_dcm(t, load, lcfg);
  }
  canfdi_parity_thr_cfg_t tcfg;
  canfdi_parity_thr_default_cfg(&tcfg);
  static const ThrRun thr_runs[] = {
      {"fault-free, sine", 11, 1, -1, 0, 0, 10.0},
      {"fault-free, steps", 12, 2, -1, 0, 0, 10.0},
      {"TPS1 +0.1 V abrupt, const", 13, 0, CANFDI_FAULT_THR_TPS1_DRIFT, 0.1, 0, 9.0},
      {"TPS2 -0.1 V in 3 s, sine", 14, 1, CANFDI_FAULT_THR_TPS2_DRIFT, -0.1, 3.0, 12.0},
      {"motor R +20 %, sine", 15, 1, CANFDI_FAULT_THR_MOTOR_R_UP, 0.2, 0, 9.0},
      {"TPS1 -0.1 V in 3 s, steps", 16, 2, CANFDI_FAULT_THR_TPS1_DRIFT, -0.1, 3.0, 12.0},
  };
  for (const ThrRun &r : thr_runs) run_thr(t, r, tcfg);
  return t.finish();
}
