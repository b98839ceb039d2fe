/*
 * guard_main.c — entry point of the target build guard images
 * ($(BUILD)/target/<core>/canfdi.elf, see mk/target.mk).
 *
 * It calls EVERY public function of every firmware module, the static inline
 * ones of the headers included, on inputs read from volatiles and sinks every
 * result into volatiles, so that --gc-sections keeps the code and the
 * optimiser cannot fold it: whatever a function needs (a libgcc helper, a
 * soft-float routine, malloc) is then in the image, where
 * tests/target/fw_guard.sh looks for it. The guard also checks that this
 * file is complete: a new public function missing here fails the build.
 *
 * Not meant to compute anything meaningful: the inputs are all zero when it
 * runs (the Cortex-M4 image boots and returns from main on QEMU
 * mps2-an386); the PIL rig will have its own entry point. Adding a module: include its header, add one
 * guard_<module>() that calls each of its functions, call it from main().
 * Generated firmware code (firmware/<any>/gen/: the cantools DBC codec) is
 * covered by guard_generated(), which tests/target/gen_guard_calls.pl writes
 * from the generated headers at build time; it leaves out the codec's
 * *_is_in_phys_range(double), which firmware must never call.
 */
#include "comm/canfdi_e2e.h"
#include "comm/canfdi_rx.h"
#include "comm/canfdi_tx.h"
#include "core/canfdi_count.h"
#include "core/canfdi_fixp.h"
#include "core/canfdi_intrin.h"
#include "core/canfdi_qconst.h"
#include "detect/canfdi_adapt.h"
#include "detect/canfdi_cusum.h"
#include "detect/canfdi_limit.h"
#include "detect/canfdi_meanvar.h"
#include "detect/canfdi_trend.h"
#include "core/canfdi_debounce.h"
#include "diag/canfdi_dtc.h"
#include "diag/canfdi_nvm.h"
#include "model/canfdi_svf.h"
#include "model/canfdi_rls.h"
#include "model/canfdi_est_dcm.h"
#include "model/canfdi_est_thr.h"
#include "model/canfdi_parity_dcm.h"
#include "model/canfdi_parity_thr.h"
#include "model/canfdi_tps.h"
#include "ft/canfdi_actmgr.h"
#include "ft/canfdi_degrade.h"
#include "ft/canfdi_vote.h"

#include "ctrl/canfdi_ctrl_dcm.h"
#include "ctrl/canfdi_ctrl_thr.h"
#include "ctrl/canfdi_excite.h"
#include "ctrl/canfdi_pi.h"

#include "app/canfdi_app.h"
#include "app/canfdi_app_uds.h"
#include "comm/canfdi_isotp.h"
#include "uds/canfdi_uds.h"

/* Inputs the compiler cannot know. */
static volatile int16_t in_s16[2];
static volatile int32_t in_s32[3];
static volatile int64_t in_s64[2];
static volatile uint32_t in_u32;
static volatile uint64_t in_u64;
static volatile uint8_t in_frame[8];
static volatile unsigned in_n;

/* Results the compiler must produce. */
static volatile int32_t sink_s32;
static volatile int64_t sink_s64;
static volatile uint64_t sink_u64;

static void sink32(int32_t v) { sink_s32 = v; }
static void sink64(int64_t v) { sink_s64 = v; }
static void sinku64(uint64_t v) { sink_u64 = v; }

/* What the generated calls use (see tests/target/gen_guard_calls.pl). */
static uint8_t guard_buf[64];
#define guard_in_u64 in_u64
#define guard_sink_u64 sinku64
#include "guard_generated.h"

static void guard_fixp(void)
{
  const int16_t a15 = in_s16[0];
  const int16_t b15 = in_s16[1];
  const int32_t a = in_s32[0];
  const int32_t b = in_s32[1];
  const int32_t c = in_s32[2];
  const int64_t a64 = in_s64[0];
  const int64_t b64 = in_s64[1];
  const unsigned n = in_n;

  sink32(canfdi_wrap_u32_to_s32(in_u32));
  sink64(canfdi_wrap_u64_to_s64(in_u64));
  sink32((int32_t)canfdi_clz32(in_u32));
  sink32((int32_t)canfdi_ctz32(in_u32 | 1U));
  sink32((int32_t)canfdi_phase_before(in_u32, in_n + 1U));
  sink32((int32_t)canfdi_clz64(in_u64));
  sink32(canfdi_mla_hi_rnd(a, b, c));
  sinku64(canfdi_umull32(in_u32, (uint32_t)b));
  sink32((int32_t)canfdi_umulhi32(in_u32, (uint32_t)b));
  sink64(canfdi_smull32(a, b));
  sink64(canfdi_usmull32(in_u32, b));
  sink32((int32_t)canfdi_recip_q63(in_u32 | 0x80000000U));
  sinku64(canfdi_umull32_h16(in_u32, (uint32_t)b));
  sink32((int32_t)canfdi_umulhi32_h16(in_u32, (uint32_t)b));
  sink64(canfdi_smull32_h16(a, b));
  sink64(canfdi_usmull32_h16(in_u32, b));
  sink64(canfdi_mul_s56_q31_rnd_h16(in_s64[0] / 256, b));
  sink64(canfdi_mul_s48_u15_h16(in_s64[1] / 65536, b & 0x7FFF));
  sink32(canfdi_s64_fits_s32(in_s64[0]) ? 1 : 0);
  sink32(canfdi_clamp_s32(a, b, c));
  sink32(canfdi_asr32(a, n));
  sink64(canfdi_asr64(a64, n));
  sink32(canfdi_asr32_rnd(a, n));
  sink64(canfdi_asr64_rnd(a64, n));
  sink32(canfdi_shl32_sat(a, n));
  sink64(canfdi_shl64_sat(a64, n));
  sink32(canfdi_sat_s32_to_s16(a));
  sink32(canfdi_sat_s64_to_s32(a64));
  sink32(canfdi_add_s32_sat(a, b));
  sink32(canfdi_sub_s32_sat(a, b));
  sink64(canfdi_add_s64_sat(a64, b64));
  sink64(canfdi_sub_s64_sat(a64, b64));
  sink32(canfdi_q15_add(a15, b15));
  sink32(canfdi_q15_sub(a15, b15));
  sink32(canfdi_q15_neg(a15));
  sink32(canfdi_q15_abs(a15));
  sink32(canfdi_q15_mul(a15, b15));
  sink32(canfdi_q15_mul_rnd(a15, b15));
  sink32(canfdi_q31_add(a, b));
  sink32(canfdi_q31_sub(a, b));
  sink32(canfdi_q31_neg(a));
  sink32(canfdi_q31_abs(a));
  sink32(canfdi_q31_mul(a, b));
  sink32(canfdi_q31_mul_rnd(a, b));
  sink32(canfdi_mul_s32_qn(a, b, n));
  sink64(canfdi_mul_s64_q31(a64, b));
  sink32(canfdi_q15_to_q31(a15));
  sink32(canfdi_q31_to_q15(a));
  sink32(canfdi_qconv_s32(a, n, in_n));
  sink32(canfdi_q15_div(a15, b15));
  sink32(canfdi_q31_div(a, b));
  sink32(canfdi_div_s32_qn(a, b, n));
  sink32(canfdi_div_s64_sat_s32(a64, b64));
  sinku64(canfdi_isqrt_u32(in_u32));
  sinku64(canfdi_isqrt_u64(in_u64));
  sink32(canfdi_q15_sqrt(a15));
  sink32(canfdi_q31_sqrt(a));
}

static void guard_count(void)
{
  static uint32_t c32;
  static uint16_t c16;
  static uint8_t c8;
  canfdi_count_inc(&c32);
  canfdi_count_add(&c32, in_u32);
  sinku64(canfdi_count_sum(c32, in_u32));
  canfdi_count_inc16(&c16);
  canfdi_count_inc8(&c8);
  sinku64((uint64_t)c16 + (uint64_t)c8);
}

static void guard_debounce(void)
{
  static const canfdi_debounce_cfg_t cfg = {
      .failed_threshold = 100,
      .passed_threshold = -100,
      .prefailed_step = 10U,
      .prepassed_step = 1U,
      .jump_up_value = 0,
      .jump_down_value = 0,
      .jump_up = true,
      .jump_down = false,
  };
  static canfdi_debounce_t deb;

  sink32(canfdi_debounce_cfg_check(&cfg));
  sink32(canfdi_debounce_init(&deb, &cfg));
  sink32(canfdi_debounce_step(&deb, (canfdi_deb_report_t)in_u32));
  sink32(canfdi_debounce_report(&deb, (canfdi_deb_report_t)in_u32));
  sink32(canfdi_debounce_pass_is_noop(&deb, (canfdi_deb_report_t)in_u32) ? 1 : 0);
  canfdi_debounce_start_cycle(&deb);
  sink32((int32_t)canfdi_debounce_status(&deb));
  sink32(canfdi_debounce_counter(&deb));
  sink32(canfdi_debounce_fdc(&deb));
  canfdi_debounce_reset(&deb);
}

static void guard_meanvar(void)
{
  static canfdi_meanvar_t mv;
  canfdi_meanvar_diag_t d;

  sink32(canfdi_meanvar_init(&mv, in_s32[0]));
  canfdi_meanvar_step(&mv, in_s32[1]);
  sinku64(canfdi_meanvar_count(&mv));
  sink32(canfdi_meanvar_mean(&mv));
  sink64(canfdi_meanvar_mean_q32(&mv));
  sinku64(canfdi_meanvar_var_q20(&mv));
  sinku64(canfdi_meanvar_var(&mv));
  sinku64(canfdi_meanvar_std_q10(&mv));
  d = canfdi_meanvar_diag(&mv);
  sinku64(d.input_saturations + d.resets);
  canfdi_meanvar_reset(&mv);
}

static void guard_cusum(void)
{
  static canfdi_cusum_t cu;
  canfdi_cusum_cfg_t cfg;
  canfdi_cusum_alarm_t al;
  canfdi_cusum_diag_t d;

  cfg.mu0 = in_s32[0];
  cfg.sigma_q10 = in_u32;
  cfg.k_q16 = in_u32;
  cfg.h_q16 = in_u32;
  cfg.head_start_q16 = in_u32;
  cfg.restart = (canfdi_cusum_restart_t)in_n;
  sink32(canfdi_cusum_init(&cu, &cfg));
  sinku64(canfdi_cusum_step(&cu, in_s32[1]));
  sinku64(canfdi_cusum_latched(&cu) ? 1U : 0U);
  sink64(canfdi_cusum_sum_hi_q16(&cu));
  sink64(canfdi_cusum_sum_lo_q16(&cu));
  sink64(canfdi_cusum_threshold_q16(&cu));
  sinku64(canfdi_cusum_step_index(&cu));
  al = canfdi_cusum_last_alarm(&cu);
  sink64(al.shift_q16 + al.sum_q16 + (int64_t)al.change_step);
  d = canfdi_cusum_diag(&cu);
  sinku64((uint64_t)d.alarms_hi + d.alarms_lo + d.restarts + d.latched_samples);
  canfdi_cusum_restart(&cu);
}

/* Limits and debouncing from volatiles: the checks cannot be folded. */
static void fill_limit_cfg(canfdi_limit_cfg_t *cfg)
{
  cfg->max_set = in_s32[0];
  cfg->max_clear = in_s32[1];
  cfg->min_set = in_s32[2];
  cfg->min_clear = in_s32[0];
  cfg->max_enabled = (in_n & 1U) != 0U;
  cfg->min_enabled = (in_n & 2U) != 0U;
  cfg->deb.failed_threshold = in_s16[0];
  cfg->deb.passed_threshold = in_s16[1];
  cfg->deb.prefailed_step = (uint16_t)in_u32;
  cfg->deb.prepassed_step = (uint16_t)in_u32;
  cfg->deb.jump_up_value = in_s16[0];
  cfg->deb.jump_down_value = in_s16[1];
  cfg->deb.jump_up = (in_n & 4U) != 0U;
  cfg->deb.jump_down = (in_n & 8U) != 0U;
}

static void guard_limit(void)
{
  static canfdi_limit_cfg_t cfg;
  static canfdi_limit_t lim;

  fill_limit_cfg(&cfg);
  sink32(canfdi_limit_cfg_check(&cfg));
  sink32(canfdi_limit_init(&lim, &cfg));
  sink32(canfdi_limit_step(&lim, in_s32[1]));
  sink32((int32_t)canfdi_limit_symptom(&lim));
  sink32((int32_t)canfdi_limit_status(&lim));
  sink32((int32_t)canfdi_limit_failed_side(&lim));
  canfdi_limit_reset(&lim);
}

static void guard_trend(void)
{
  static canfdi_trend_cfg_t cfg;
  static canfdi_trend_t tr;

  cfg.tau_us = in_u32;
  cfg.order = (uint8_t)in_n;
  cfg.rate_frac_bits = (uint8_t)in_n;
  fill_limit_cfg(&cfg.rate_limit);
  sink32(canfdi_trend_cfg_check(&cfg));
  sink32(canfdi_trend_init(&tr, &cfg));
  sink32(canfdi_trend_step(&tr, in_s32[2]));
  sink32(canfdi_trend_rate(&tr));
  sink32(canfdi_trend_filtered(&tr));
  sink32((int32_t)canfdi_trend_status(&tr));
  canfdi_trend_reset(&tr);
}

static void guard_adapt(void)
{
  static canfdi_adapt_cfg_t cfg;
  static canfdi_adapt_t ad;

  cfg.base = in_s32[0];
  cfg.max = in_s32[1];
  cfg.gain = in_s32[2];
  cfg.tau_us = in_u32;
  cfg.gain_frac_bits = (uint8_t)in_n;
  sink32(canfdi_adapt_cfg_check(&cfg));
  sink32(canfdi_adapt_init(&ad, &cfg));
  sink32(canfdi_adapt_step(&ad, in_s32[1]));
  sink32(canfdi_adapt_exceeds(&ad, in_s32[2]) ? 1 : 0);
  sink32(canfdi_adapt_threshold(&ad));
  sink32(canfdi_adapt_excitation(&ad));
  canfdi_adapt_reset(&ad);
}

static void guard_e2e(void)
{
  static canfdi_e2e_tx_t tx;
  static canfdi_e2e_rx_t rx;
  uint8_t frame[8];
  int st;

  for (unsigned i = 0U; i < 8U; i++)
  {
    frame[i] = in_frame[i];
  }
  sinku64(canfdi_e2e_crc8_update((uint8_t)in_u32, frame, 8U));
  sinku64(canfdi_e2e_crc8(frame, 8U));
  sinku64(canfdi_e2e_frame_crc((uint16_t)in_u32, frame, 8U));
  canfdi_e2e_tx_init(&tx, (uint16_t)in_u32);
  sink32(canfdi_e2e_protect(&tx, frame, 8U));
  sink32(canfdi_e2e_rx_init(&rx, (uint16_t)in_u32, (uint8_t)in_n));
  st = canfdi_e2e_check(&rx, frame, 8U);
  sink32(st);
  sink32(canfdi_e2e_status_is_usable(st) ? 1 : 0);
}

static void guard_svf(void)
{
  static canfdi_svf_t svf;
  canfdi_svf_cfg_t cfg;
  const canfdi_svf_diag_t *d;

  cfg.order = (uint8_t)in_n;
  cfg.outputs = (uint8_t)in_s32[1];
  cfg.omega_c_rad_s = in_s32[0];
  sink32(canfdi_svf_init(&svf, &cfg));
  canfdi_svf_reset(&svf, in_s32[1]);
  canfdi_svf_step(&svf, in_s32[2]);
  sink32(canfdi_svf_y_q16(&svf));
  sink32(canfdi_svf_dy_q16(&svf));
  sink32(canfdi_svf_d2y_q16(&svf));
  d = canfdi_svf_diag(&svf);
  sinku64((uint64_t)d->steps + d->resets + d->out_saturations);
}

static void guard_rls(void)
{
  static canfdi_rls_t rls;
  canfdi_rls_cfg_t cfg = {0};
  int32_t phi[CANFDI_CFG_RLS_MAX_PARAMS];
  const canfdi_rls_diag_t *d;
  canfdi_rls_xf_t x;

  cfg.n_params = (uint8_t)in_n;
  cfg.forget_q31 = in_s32[0];
  cfg.p0_q16 = in_s32[1];
  cfg.trace_max_q16 = in_s32[2];
  for (unsigned i = 0U; i < CANFDI_CFG_RLS_MAX_PARAMS; i++)
  {
    phi[i] = in_s32[i % 3U];
  }
  sink32(canfdi_rls_init(&rls, &cfg));
  canfdi_rls_reset(&rls, in_n != 0U);
  sink32(canfdi_rls_update(&rls, phi, in_s32[0]) ? 1 : 0);
  canfdi_rls_set_theta_qn(&rls, in_n, in_s32[1], 16U);
  sink32(canfdi_rls_theta_qn(&rls, in_n, 16U));
  sink32(canfdi_rls_err_q16(&rls));
  sink32(canfdi_rls_cov_qn(&rls, in_n, in_n, 16U));
  sink32(canfdi_rls_trace_q16(&rls));
  x = canfdi_rls_d(&rls, in_n);
  sink32(x.m + x.e);
  sink32(canfdi_rls_excitation_q16(&rls));
  sink32(canfdi_rls_excited(&rls) ? 1 : 0);
  sink32(canfdi_rls_invariants_hold(&rls) ? 1 : 0);
  d = canfdi_rls_diag(&rls);
  sinku64((uint64_t)d->updates + d->skipped + d->trace_clips + d->resets + d->saturations);
}

static void guard_est_dcm(void)
{
  static canfdi_est_dcm_t est;
  static canfdi_est_dcm_cfg_t cfg;
  const canfdi_est_dcm_diag_t *d;

  canfdi_est_dcm_default_cfg(&cfg);
  sink32(canfdi_est_dcm_init(&est, &cfg));
  canfdi_est_dcm_reset(&est, in_n != 0U);
  canfdi_est_dcm_set_load_offset(&est, in_s32[2]);
  canfdi_est_dcm_align(&est, in_u32);
  canfdi_est_dcm_step(&est, in_s32[0], in_s32[1], in_s32[2]);
  sink32(canfdi_est_dcm_ra_q16(&est));
  sink32(canfdi_est_dcm_la_q24(&est));
  sink32(canfdi_est_dcm_psi_q16(&est));
  sink32(canfdi_est_dcm_j_q24(&est));
  sink32(canfdi_est_dcm_mf1_q24(&est));
  sink32(canfdi_est_dcm_mc_q16(&est));
  sink32(canfdi_est_dcm_has_run(&est) ? 1 : 0);
  sink32(canfdi_est_dcm_excited(&est) ? 1 : 0);
  sink32(canfdi_est_dcm_arm_converged(&est) ? 1 : 0);
  sink32(canfdi_est_dcm_mech_converged(&est) ? 1 : 0);
  sink32(canfdi_rls_trace_q16(canfdi_est_dcm_arm_rls(&est)));
  sink32(canfdi_rls_trace_q16(canfdi_est_dcm_mech_rls(&est)));
  d = canfdi_est_dcm_diag(&est);
  sinku64((uint64_t)d->steps + d->arm_updates + d->mech_updates + d->resets);
}

static void guard_est_thr(void)
{
  static canfdi_est_thr_t est;
  static canfdi_est_thr_cfg_t cfg;
  const canfdi_est_thr_diag_t *d;

  canfdi_est_thr_default_cfg(&cfg);
  sink32(canfdi_est_thr_init(&est, &cfg));
  canfdi_est_thr_reset(&est, in_n != 0U);
  canfdi_est_thr_align(&est, in_u32);
  canfdi_est_thr_step(&est, in_s32[0], in_s32[1], in_s32[2]);
  sink32(canfdi_est_thr_r_q16(&est));
  sink32(canfdi_est_thr_l_q24(&est));
  sink32(canfdi_est_thr_k_q16(&est));
  sink32(canfdi_est_thr_u0_q16(&est));
  sink32(canfdi_est_thr_j_q24(&est));
  sink32(canfdi_est_thr_b_q24(&est));
  sink32(canfdi_est_thr_spring_q24(&est));
  sink32(canfdi_est_thr_pretension_q16(&est));
  sink32(canfdi_est_thr_friction_q16(&est));
  sink32(canfdi_est_thr_fast_spring_dev_q16(&est));
  sink32(canfdi_est_thr_fast_friction_dev_q16(&est));
  sink32(canfdi_est_thr_fast_valid(&est) ? 1 : 0);
  sink32(canfdi_est_thr_has_run(&est) ? 1 : 0);
  sink32(canfdi_est_thr_excited(&est) ? 1 : 0);
  sink32(canfdi_est_thr_el_converged(&est) ? 1 : 0);
  sink32(canfdi_est_thr_mech_converged(&est) ? 1 : 0);
  sink32(canfdi_rls_trace_q16(canfdi_est_thr_el_rls(&est)));
  sink32(canfdi_rls_trace_q16(canfdi_est_thr_mech_rls(&est)));
  d = canfdi_est_thr_diag(&est);
  sinku64((uint64_t)d->steps + d->el_updates + d->mech_updates + d->mech_lh_skips +
          d->mech_still_skips + d->clip_skips + d->resets);
}

/* Fault tolerance (firmware/ft): voting, degradation, actuator manager. */
static void guard_ft(void)
{
  static canfdi_vote_t vote;
  static canfdi_actmgr_t mgr;
  static canfdi_degrade_t deg;
  canfdi_vote_cfg_t vc;
  canfdi_vote_in_t vin;
  canfdi_vote_out_t vout;
  canfdi_actmgr_cfg_t mc;
  canfdi_actmgr_in_t mi;
  canfdi_actmgr_out_t mout;
  canfdi_degrade_transition_t tr;

  vc.tps1.zero_V_q16 = in_s32[0];
  vc.tps1.slope_V_rad_q16 = in_s32[1];
  vc.tps2.zero_V_q16 = in_s32[2];
  vc.tps2.slope_V_rad_q16 = -in_s32[1];
  vc.tol_tps_rad_q16 = in_s32[0];
  vc.tol_model_rad_q16 = in_s32[2];
  vc.isolate_steps_tps = (uint16_t)in_u32;
  vc.isolate_steps_model = (uint16_t)in_n;
  vin.tps1_V_q16 = in_s32[0];
  vin.tps2_V_q16 = in_s32[1];
  vin.model_rad_q16 = in_s32[2];
  vin.tps1_valid = (in_u32 & 1U) != 0U;
  vin.tps2_valid = (in_u32 & 2U) != 0U;
  vin.model_valid = (in_u32 & 4U) != 0U;
  vin.model_no_blame = (in_u32 & 64U) != 0U;
  sink32(canfdi_vote_init(&vote, &vc));
  sink32(canfdi_vote_step(&vote, &vin, &vout));
  canfdi_vote_clear(&vote);
  sink32((int32_t)canfdi_vote_diag(&vote).steps);

  canfdi_actmgr_default_cfg(&mc);
  mc.dcm_lag_max_steps = (uint8_t)in_n;
  sink32(canfdi_actmgr_init(&mgr, &mc));
  mi.dcm_u_ctrl_V_q16 = in_s32[0];
  mi.dcm_ua_V_q16 = in_s32[1];
  mi.dcm_supply_V_q16 = in_s32[2];
  mi.dcm_ua_valid = vin.tps1_valid;
  mi.dcm_supply_valid = vin.tps2_valid;
  mi.thr_u_ctrl_V_q16 = in_s32[1];
  mi.faults = in_u32;
  mi.fail_silent = vin.model_valid;
  mi.now_ms = in_u32;
  sink32(canfdi_actmgr_step(&mgr, &mi, &vout, &mout));
  sink32(mout.dcm.u_cmd_V_q16 + mout.thr.u_cmd_V_q16 + (int32_t)mout.dcm.bridge +
         (int32_t)mout.dcm_ctrl_mode);
  sink32(canfdi_actmgr_clear(&mgr, in_u32, (uint8_t)in_n, in_u32, in_u32));
  sink32(canfdi_actmgr_set_applied(&mgr, (in_n != 0U) ? &mout.dcm : NULL));
  sink32((int32_t)canfdi_degrade_state(canfdi_actmgr_degrade_dcm(&mgr)));
  sink32((int32_t)canfdi_degrade_state(canfdi_actmgr_degrade_thr(&mgr)));
  sink32((int32_t)canfdi_actmgr_diag(&mgr).steps);

  sink32(canfdi_degrade_init(&deg));
  sink32(canfdi_degrade_request(&deg, (uint8_t)in_u32, (uint8_t)in_n, in_u32));
  sink32(canfdi_degrade_clear(&deg, (uint8_t)in_n, vin.tps1_valid, in_u32));
  sink32((int32_t)canfdi_degrade_state(&deg));
  sink32((int32_t)canfdi_degrade_reason(&deg));
  sink32((int32_t)canfdi_degrade_since_ms(&deg));
  sink32(canfdi_degrade_log_get(&deg, in_u32, &tr));
  sink32((int32_t)tr.t_ms);
  sink32((int32_t)canfdi_degrade_diag(&deg).transitions);
}

/* Control (firmware/ctrl): PI(D), DC motor speed, throttle position,
 * excitation. */
static void guard_ctrl(void)
{
  static canfdi_pi_t pi;
  static canfdi_ctrl_dcm_t dcm;
  static canfdi_ctrl_thr_t thr;
  static canfdi_excite_t exc;
  canfdi_pi_cfg_t pc;
  canfdi_ctrl_dcm_cal_t dc;
  canfdi_ctrl_dcm_in_t di;
  canfdi_ctrl_dcm_out_t dout;
  canfdi_ctrl_thr_cal_t tc;
  canfdi_ctrl_thr_in_t ti;
  canfdi_ctrl_thr_out_t tout;
  canfdi_excite_cfg_t ec;
  const canfdi_pi_diag_t *pd;

  pc.kp_q16 = in_s32[0];
  pc.ki_q16 = in_s32[1];
  pc.kd_q16 = in_s32[2];
  pc.kd_tau_us = in_u32;
  pc.i_band_q16 = in_s32[0];
  pc.out_min_q16 = in_s32[1];
  pc.out_max_q16 = in_s32[2];
  pc.anti_windup = (uint8_t)in_n;
  sink32(canfdi_pi_init(&pi, &pc));
  sink32(canfdi_pi_set_limits_q16(&pi, in_s32[0], in_s32[1]));
  sink32(canfdi_pi_step_q16(&pi, in_s32[0], in_s32[1], in_s32[2], in_u32));
  canfdi_pi_track_q16(&pi, in_s32[2]);
  canfdi_pi_reset_q16(&pi, in_s32[0], in_s32[1]);
  sink32(canfdi_pi_out_q16(&pi));
  sink32(canfdi_pi_integral_q16(&pi));
  sink32(canfdi_pi_saturation(&pi));
  pd = canfdi_pi_diag(&pi);
  sinku64((uint64_t)pd->steps + pd->sat_hi + pd->sat_lo + pd->int_holds + pd->tracks +
          pd->resets);

  canfdi_ctrl_dcm_cal_default(&dc);
  dc.speed_kp_A_s_rad_q16 = in_s32[0];
  dc.accel_max_rad_s2_q16 = in_s32[1];
  sink32(canfdi_ctrl_dcm_init(&dcm, &dc));
  di.speed_ref_rad_s_q16 = in_s32[0];
  di.excite_rad_s_q16 = in_s32[1];
  di.speed_rad_s_q16 = in_s32[2];
  di.ia_A_q16 = in_s32[0];
  di.supply_V_q16 = in_s32[1];
  di.u_track_V_q16 = in_s32[2];
  di.ia_valid = (in_u32 & 1U) != 0U;
  di.mode = (uint8_t)in_n;
  sink32(canfdi_ctrl_dcm_step(&dcm, &di, &dout));
  sink32(dout.ia_ref_A_q16 + dout.speed_ref_rad_s_q16 + dout.u_limit_V_q16 + dout.u_sat);
  sinku64(canfdi_ctrl_dcm_diag(&dcm)->steps);
  sinku64(canfdi_ctrl_dcm_pi_diag(&dcm, (in_u32 & 2U) != 0U)->steps);

  canfdi_ctrl_thr_cal_default(&tc);
  tc.kp_V_rad_q16 = in_s32[0];
  tc.rate_max_rad_s_q16 = in_s32[1];
  sink32(canfdi_ctrl_thr_init(&thr, &tc));
  ti.angle_ref_rad_q16 = in_s32[0];
  ti.excite_rad_q16 = in_s32[1];
  ti.angle_rad_q16 = in_s32[2];
  ti.supply_V_q16 = in_s32[0];
  ti.u_track_V_q16 = in_s32[1];
  ti.mode = (uint8_t)in_n;
  sink32(canfdi_ctrl_thr_step(&thr, &ti, &tout));
  sink32(tout.u_ff_V_q16 + tout.angle_ref_rad_q16 + tout.u_limit_V_q16 + tout.u_sat);
  sink32(canfdi_ctrl_thr_ff_q16(&thr, in_s32[0], in_s32[1]));
  sinku64(canfdi_ctrl_thr_diag(&thr)->steps);
  sinku64(canfdi_ctrl_thr_pi_diag(&thr)->steps);

  ec.prbs_amp_q16 = in_s32[0];
  ec.prbs_bit_us = in_u32;
  ec.prbs_seed = (uint16_t)in_n;
  ec.sine_amp_q16 = in_s32[1];
  ec.sine_period_us = in_u32;
  sink32(canfdi_excite_init(&exc, &ec));
  canfdi_excite_enable(&exc, (in_u32 & 4U) != 0U);
  sink32(canfdi_excite_step_q16(&exc));
  sink32(canfdi_excite_active(&exc) ? 1 : 0);
  sink32(canfdi_excite_sin_q15(in_u32));
  sinku64(canfdi_excite_diag(&exc)->steps);
}

static void guard_parity_dcm(void)
{
  static canfdi_parity_dcm_cfg_t cfg;
  static canfdi_parity_dcm_t p;
  canfdi_parity_dcm_in_t in;
  const canfdi_parity_dcm_out_t *o;

  canfdi_parity_dcm_default_cfg(&cfg);
  sink32(canfdi_parity_dcm_cfg_check(&cfg));
  sink32(canfdi_parity_dcm_init(&p, &cfg));
  sink32(canfdi_parity_dcm_set_ra(&p, in_s32[0]));
  in.u_V_q16 = in_s32[0];
  in.i_A_q16 = in_s32[1];
  in.w_rad_s_q16 = in_s32[2];
  in.load_Nm_q16 = in_s32[1];
  o = canfdi_parity_dcm_step(&p, &in);
  sink32((o != NULL) ? o->r_q16[0] : 0);
  o = canfdi_parity_dcm_out(&p);
  sink32((o != NULL) ? o->rn_q16[3] : 0);
  sink32((int32_t)canfdi_parity_dcm_diag(&p)->steps);
  canfdi_parity_dcm_reset(&p);
}

static void guard_tps(void)
{
  static canfdi_tps_cal_t cal[2];
  static canfdi_tps_t t;

  canfdi_tps_cal_default(&cal[0], &cal[1]);
  cal[in_n & 1U].zero_V_q16 = in_s32[0];
  sink32(canfdi_tps_cal_check(&cal[0]));
  sink32(canfdi_tps_init(&t, &cal[in_n & 1U]));
  sink32(canfdi_tps_V_to_rad_q16(&t, in_s32[1]));
  sink32(canfdi_tps_rad_to_V_q16(&cal[0], in_s32[2]));
}

static void guard_parity_thr(void)
{
  static canfdi_parity_thr_cfg_t cfg;
  static canfdi_parity_thr_t p;
  canfdi_parity_thr_in_t in;
  const canfdi_parity_thr_out_t *o;

  canfdi_parity_thr_default_cfg(&cfg);
  sink32(canfdi_parity_thr_cfg_check(&cfg));
  sink32(canfdi_parity_thr_init(&p, &cfg));
  sink32(canfdi_parity_thr_force_source(&p, (uint8_t)in_n));
  in.tps1_V_q16 = in_s32[0];
  in.tps2_V_q16 = in_s32[1];
  in.i_A_q16 = in_s32[2];
  in.u_V_q16 = in_s32[0];
  in.supply_V_q16 = in_s32[1];
  in.enabled = (in_n != 0U);
  o = canfdi_parity_thr_step(&p, &in);
  sink32((o != NULL) ? o->r_q16[1] : 0);
  o = canfdi_parity_thr_out(&p);
  sink32((o != NULL) ? o->theta_hat_rad_q16 : 0);
  sink32((int32_t)canfdi_parity_thr_diag(&p)->steps);
  canfdi_parity_thr_reset(&p);
}

/* DTC memory and its NVM storage (diag/canfdi_dtc, diag/canfdi_nvm): a RAM
 * stand-in for two 128-byte flash banks with flash semantics. */
static uint8_t guard_nvm_flash[2][128];

static int32_t guard_nvm_read(void *ctx, uint8_t bank, uint32_t off, uint8_t *buf, uint32_t len)
{
  (void)ctx;
  for (uint32_t i = 0U; i < len; i++) {
    buf[i] = guard_nvm_flash[bank & 1U][(off + i) & 127U];
  }
  return 0;
}

static int32_t guard_nvm_write(void *ctx, uint8_t bank, uint32_t off, const uint8_t *buf, uint32_t len)
{
  (void)ctx;
  for (uint32_t i = 0U; i < len; i++) {
    guard_nvm_flash[bank & 1U][(off + i) & 127U] &= buf[i];
  }
  return 0;
}

static int32_t guard_nvm_erase(void *ctx, uint8_t bank)
{
  (void)ctx;
  for (uint32_t i = 0U; i < 128U; i++) {
    guard_nvm_flash[bank & 1U][i] = 0xFFU;
  }
  return 0;
}

static void guard_dtc(void)
{
  static canfdi_dtc_t dtc;
  static uint8_t img[CANFDI_DTC_IMAGE_MAX_BYTES];
  canfdi_dtc_ff_t ff;
  canfdi_dtc_record_t rec;
  uint16_t cursor = 0U;
  uint32_t code = 0U;
  uint8_t status = 0U;
  const uint8_t idx = (uint8_t)in_n;

  ff.time_ms = in_u32;
  ff.omega_q16 = in_s32[0];
  ff.ia_q16 = in_s32[1];
  ff.ua_q16 = in_s32[2];
  ff.thr_angle_q16 = in_s32[0];
  ff.supply_q16 = in_s32[1];
  ff.deg_dcm = (uint8_t)in_n;
  ff.deg_thr = (uint8_t)in_u32;
  sink32(canfdi_dtc_init(&dtc, canfdi_dtc_defaults, (uint8_t)CANFDI_DTC_COUNT));
  sink32(canfdi_dtc_cycle_start(&dtc));
  sink32(canfdi_dtc_report(&dtc, idx, (canfdi_deb_report_t)in_u32, &ff));
  sink32(canfdi_dtc_find(&dtc, in_u32));
  sink32(canfdi_dtc_status(&dtc, idx));
  sink32(canfdi_dtc_pass_is_noop(&dtc, idx, (canfdi_deb_report_t)in_u32) ? 1 : 0);
  sink32((int32_t)canfdi_dtc_status_at(&dtc, (uint8_t)(idx % CANFDI_DTC_COUNT)));
  sink32(canfdi_dtc_fdc(&dtc, idx));
  sink32((int32_t)canfdi_dtc_occurrence(&dtc, idx));
  sink32((int32_t)canfdi_dtc_count_by_mask(&dtc, (uint8_t)in_u32));
  sink32(canfdi_dtc_next_by_mask(&dtc, (uint8_t)in_u32, &cursor, &code, &status));
  sinku64((uint64_t)code + status + cursor);
  sink32(canfdi_dtc_read_record(&dtc, in_u32, &rec));
  sinku64((uint64_t)rec.occurrence + (uint64_t)rec.ff.time_ms);
  sink32(canfdi_dtc_cycle_end(&dtc));
  sink32(canfdi_dtc_serialize(&dtc, img, (uint32_t)sizeof img));
  sink32(canfdi_dtc_deserialize(&dtc, img, in_u32));
  sink32(canfdi_dtc_clear(&dtc, in_u32));
  sink32(canfdi_dtc_clear_group(&dtc, (uint8_t)in_n));
  sink32(canfdi_dtc_invariants_hold(&dtc) ? 1 : 0);
}

static void guard_nvm(void)
{
  static const canfdi_nvm_port_t port = {NULL, guard_nvm_read, guard_nvm_write, guard_nvm_erase, 128U, 8U};
  static canfdi_nvm_t nvm;
  uint8_t buf[16];

  for (unsigned i = 0U; i < 16U; i++) {
    buf[i] = in_frame[i & 7U];
  }
  sinku64(canfdi_nvm_crc32_update(in_u32, buf, 16U));
  sinku64(canfdi_nvm_crc32(buf, (uint32_t)in_n & 15U));
  sink32(canfdi_nvm_init(&nvm, &port));
  sink32(canfdi_nvm_store(&nvm, buf, (uint32_t)in_n & 15U));
  sink32(canfdi_nvm_load(&nvm, buf, 16U));
}

/* comm/canfdi_rx + comm/canfdi_tx: input supervision and the
 * transmit side. */
static void guard_rx(void)
{
  static canfdi_rx_t rx;
  canfdi_rx_cfg_t cfg;
  uint8_t frame[8];

  for (unsigned i = 0U; i < 8U; i++) {
    frame[i] = in_frame[i];
  }
  canfdi_rx_default_cfg(&cfg);
  cfg.frame[0].timeout_cycles = (uint8_t)in_n;
  sink32(canfdi_rx_init(&rx, &cfg, in_u32));
  sink32(canfdi_rx_frame(&rx, in_u32, frame, (uint8_t)in_n, in_u32));
  sink32(canfdi_rx_set_estimate(&rx, in_n, in_s32[0]));
  sink32(canfdi_rx_step(&rx, in_u32));
  sink32(canfdi_rx_monitor_result(&rx, in_n));
  sinku64(canfdi_rx_monitor_fault_id(in_n));
  sinku64(canfdi_rx_monitor_dtc(in_n));
  sink32(canfdi_rx_raw_to_q16(in_s32[1], in_s64[0], in_s64[1]));
  sink32(canfdi_rx_value(&rx, in_n % CANFDI_RX_IN_COUNT) + (canfdi_rx_valid(&rx, 0U) ? 1 : 0) +
         (canfdi_rx_usable(&rx, 1U) ? 2 : 0) + (canfdi_rx_fresh(&rx, 2U) ? 4 : 0) + (int)canfdi_rx_samples(&rx, 2U));
  sinku64((uint64_t)rx.report.prefailed + rx.diag.frames);
}

static void guard_tx(void)
{
  static canfdi_tx_t tx;
  static canfdi_tx_data_t data;
  static canfdi_tx_frame_t out[CANFDI_TX_MAX_FRAMES_PER_STEP];
  canfdi_tx_frame_t fr;

  data.dcm_act.ua_cmd_q16 = in_s32[0];
  data.dcm_act.bridge = (uint8_t)in_n;
  data.thr_act.u_cmd_q16 = in_s32[1];
  data.res_dcm.r_q16[0] = in_s32[2];
  data.prm_dcm.j_q16 = in_s32[0];
  data.status.deadline_misses = in_u32;
  data.dtc.dtc = in_u32;
  data.self_diag.frames_rejected = in_u32;
  sink32(canfdi_tx_init(&tx));
  sinku64(canfdi_tx_due(&tx));
  sink32(canfdi_tx_dtc_event(&tx, &data.dtc));
  sink32(canfdi_tx_step(&tx, &data, out));
  sink32(canfdi_tx_encode_dcm_act(&tx, &data.dcm_act, &fr));
  sink32(canfdi_tx_encode_thr_act(&tx, &data.thr_act, &fr));
  sink32(canfdi_tx_encode_res_dcm(&tx, &data.res_dcm, &fr));
  sink32(canfdi_tx_encode_res_thr(&tx, &data.res_thr, &fr));
  sink32(canfdi_tx_encode_status(&tx, &data.status, &fr));
  sink32(canfdi_tx_encode_diagnosis(&tx, &data.diagnosis, &fr));
  sink32(canfdi_tx_encode_self_diag(&tx, &data.self_diag, &fr));
  sink32(canfdi_tx_encode_dtc(&tx, &data.dtc, (in_n & 1U) != 0U, &fr));
  sink32(canfdi_tx_encode_prm_dcm(&tx, &data.prm_dcm, &fr));
  sink32(canfdi_tx_encode_prm_thr(&tx, &data.prm_thr, &fr));
  sink32(canfdi_tx_encode_uds_resp(&tx, guard_buf, &fr));
  sinku64((uint64_t)fr.data[0] + out[0].data[7] + tx.diag.saturations);
}

/* comm/canfdi_isotp and uds/: the transport and the diagnostic server. */
static uint32_t guard_key(uint32_t seed, uint8_t level) { return seed ^ level; }

static void guard_uds(void)
{
  static canfdi_isotp_t tp;
  static canfdi_uds_t uds;
  static canfdi_dtc_t dtc;
  static canfdi_uds_sec_t sec;
  static uint8_t resp[64];
  canfdi_isotp_cfg_t tcfg;
  canfdi_uds_cfg_t ucfg;
  canfdi_uds_sec_cfg_t scfg;
  canfdi_uds_src_t src = {0};
  canfdi_uds_act_t act;
  canfdi_uds_own_t own = {0U, 0U};
  canfdi_uds_msg_t m;
  uint8_t frame[CANFDI_CFG_ISOTP_FRAME_BYTES];
  uint8_t seed[CANFDI_UDS_SEC_SEED_BYTES];
  const uint8_t *msg = NULL;
  bool fn = false;

  for (unsigned i = 0U; i < 8U; i++) {
    frame[i] = in_frame[i];
  }
  canfdi_isotp_default_cfg(&tcfg);
  sink32(canfdi_isotp_init(&tp, &tcfg));
  sink32(canfdi_isotp_rx_can(&tp, (in_n & 1U) != 0U, frame, (uint8_t)in_n));
  sinku64(canfdi_isotp_rx_peek(&tp, &msg, &fn) + (fn ? 1U : 0U));
  canfdi_isotp_rx_release(&tp);
  sink32(canfdi_isotp_tx_busy(&tp) ? 1 : 0);
  sinku64((uint64_t)(uintptr_t)canfdi_isotp_tx_buf(&tp));
  sink32(canfdi_isotp_send(&tp, in_u32));
  sink32(canfdi_isotp_step(&tp, frame));
  canfdi_isotp_reset(&tp);
  canfdi_uds_sec_default_cfg(&scfg);
  scfg.key_fn = guard_key;
  sink32(canfdi_uds_sec_init(&sec, &scfg, (uint8_t)in_n, in_u32));
  canfdi_uds_sec_tick(&sec);
  sink32(canfdi_uds_sec_request(&sec, frame, in_n, in_u32, seed));
  sink32(canfdi_uds_sec_level(&sec));
  canfdi_uds_sec_lock(&sec);
  sinku64(canfdi_uds_sec_key_default(in_u32, (uint8_t)in_n) + seed[0]);
  canfdi_uds_default_cfg(&ucfg);
  sink32(canfdi_uds_init(&uds, &ucfg, (uint8_t)in_n, in_u32));
  sink32(canfdi_uds_rx_can(&uds, false, frame, (uint8_t)in_n));
  sink32(canfdi_dtc_init(&dtc, canfdi_dtc_defaults, (uint8_t)CANFDI_DTC_COUNT));
  sink32(canfdi_uds_step(&uds, &dtc, &src, &act, frame));
  sinku64((uint64_t)canfdi_uds_sec_attempts(&uds) + canfdi_uds_nvm_changes(&uds) + canfdi_uds_session(&uds) +
          act.est_reset);
  m.req = frame;
  m.req_len = in_n;
  m.resp = resp;
  m.resp_cap = (uint32_t)sizeof resp;
  m.resp_len = 0U;
  m.overflow = false;
  canfdi_uds_put_u8(&m, frame[0]);
  canfdi_uds_put_u16(&m, canfdi_uds_get_u16(frame));
  canfdi_uds_put_u24(&m, canfdi_uds_get_u24(frame));
  canfdi_uds_put_u32(&m, canfdi_uds_get_u32(frame));
  canfdi_uds_put_s32(&m, canfdi_uds_get_s32(frame));
  sink32(canfdi_uds_did_find((uint16_t)in_u32));
  sinku64(canfdi_uds_did_size((uint16_t)in_u32));
  sink32(canfdi_uds_did_put(&src, &ucfg.ident, &own, (uint16_t)in_u32, &m));
  sink32(canfdi_uds_dtc_subfn_supported((uint8_t)in_n) ? 1 : 0);
  sink32(canfdi_uds_dtc_clear(&dtc, &m));
  sink32(canfdi_uds_dtc_read(&dtc, &m));
  sinku64((uint64_t)m.resp_len + resp[0]);
}

/* The application (firmware/app): its whole state is one static instance,
 * so the image's .bss shows the RAM the product needs. */
static void guard_app(void)
{
  static canfdi_app_t app;
  static canfdi_app_cal_t cal;
  canfdi_tx_frame_t out[CANFDI_APP_MAX_TX];
  uint8_t frame[8];
  const canfdi_app_diag_t *d;

  for (unsigned i = 0U; i < 8U; i++) {
    frame[i] = in_frame[i];
  }
  canfdi_app_default_cal(&cal);
  sink32(canfdi_app_init(&app, &cal, in_u32));
  sink32(canfdi_app_rx_frame(&app, in_u32, frame, (uint8_t)in_n, in_u32));
  sink32(canfdi_app_step(&app, in_u32, out));
  {
    canfdi_app_applied_t ap = {0};
    ap.dcm_known = (in_n & 1U) != 0U;
    ap.thr_known = (in_n & 2U) != 0U;
    ap.thr_ref_known = (in_n & 4U) != 0U;
    sink32(canfdi_app_set_applied(&app, &ap));
  }
  canfdi_app_deadline_miss(&app);
  canfdi_app_port_timing(&app, in_u32, in_u32 + 1U);
  sinku64((uint64_t)canfdi_app_dtc(&app)->changes);
  d = canfdi_app_diag(&app);
  sinku64((uint64_t)d->steps + d->deadline_misses + out[0].data[0]);
  sink32(canfdi_app_new_cycle(&app));
  sink32(canfdi_app_clear_dtc(&app, in_u32));
  sink32(canfdi_app_nvm_image(&app, guard_buf, in_u32));
  sinku64(canfdi_app_nvm_changes(&app) + canfdi_app_uptime_ms(&app));
  sink32(canfdi_app_power_down(&app, guard_buf, in_u32));
  sink32(canfdi_app_power_up(&app, &cal, in_u32, guard_buf, in_n));
  sinku64(canfdi_actmon_diag(&app.actmon).steps + (canfdi_app_reset_requested(&app) ? 1U : 0U));
  canfdi_app_uds_apply(&app);
  sink32(canfdi_app_uds_stage(&app, out, (int32_t)in_n));
}

/* Fault-symptom reasoning (firmware/diag/canfdi_diagnosis). */
#include "diag/canfdi_diagnosis.h"

static void guard_diagnosis(void)
{
  static canfdi_diagnosis_t dg;
  canfdi_diagnosis_cfg_t cfg;
  canfdi_symptoms_t sym;
  int8_t rep[CANFDI_FAULT_COUNT];
  uint8_t conf = 0U;
  const canfdi_diagnosis_result_t *res;

  canfdi_diagnosis_default_cfg(&cfg);
  sink32(canfdi_diagnosis_cfg_check(&cfg));
  sink32(canfdi_diagnosis_init(&dg, &cfg));
  for (unsigned i = 0U; i < CANFDI_SYM_N_RES; i++) {
    sym.dcm_rn_q16[i] = in_s32[i % 3U];
    sym.thr_rn_q16[i] = in_s32[(i + 1U) % 3U];
    sym.dcm_pdev_q16[i] = in_s32[(i + 2U) % 3U];
    sym.thr_pdev_q16[i] = in_s32[i % 3U];
  }
  sym.dcm_rn_valid = (uint8_t)in_n;
  sym.thr_rn_valid = (uint8_t)in_n;
  sym.dcm_pdev_valid = (uint8_t)in_n;
  sym.thr_pdev_valid = (uint8_t)in_n;
  sym.flags = in_u32;
  sym.dcm_ua_cmd_rn_q16 = in_s32[1];
  canfdi_diagnosis_step(&dg, &sym, rep);
  canfdi_diagnosis_step_hard(&dg, &sym, rep);
  sinku64((uint64_t)canfdi_diagnosis_isolated(&dg, CANFDI_COMPONENT_DC_MOTOR, &conf) + conf);
  res = canfdi_diagnosis_result(&dg, CANFDI_COMPONENT_THROTTLE);
  sinku64((uint64_t)((res != NULL) ? res->best : 0U));
  sinku64((uint64_t)canfdi_diagnosis_corr_not_isolated(&dg) + canfdi_diagnosis_failed_mask(&dg));
  sink32(canfdi_diagnosis_symptom(&dg, CANFDI_COMPONENT_DC_MOTOR, (uint8_t)in_n));
  sinku64((uint64_t)canfdi_diagnosis_diag(&dg).steps + (uint64_t)(uint8_t)rep[in_n % CANFDI_FAULT_COUNT]);
  canfdi_diagnosis_reset(&dg);
}

int main(void)
{
  guard_fixp();
  guard_count();
  guard_debounce();
  guard_meanvar();
  guard_cusum();
  guard_limit();
  guard_trend();
  guard_adapt();
  guard_e2e();
  guard_svf();
  guard_rls();
  guard_est_dcm();
  guard_est_thr();
  guard_parity_dcm();
  guard_tps();
  guard_parity_thr();
  guard_ft();
  guard_ctrl();
  guard_dtc();
  guard_nvm();
  guard_rx();
  guard_tx();
  guard_uds();
  guard_generated();
  guard_app();
  guard_diagnosis();
  return 0;
}
