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
#include "core/canfdi_fixp.h"
#include "detect/canfdi_adapt.h"
#include "detect/canfdi_cusum.h"
#include "detect/canfdi_limit.h"
#include "detect/canfdi_meanvar.h"
#include "detect/canfdi_trend.h"
#include "diag/canfdi_debounce.h"
#include "model/canfdi_svf.h"
#include "model/canfdi_rls.h"
#include "model/canfdi_est_dcm.h"
#include "model/canfdi_est_thr.h"

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
  sinku64(canfdi_isqrt_u32(in_u32));
  sinku64(canfdi_isqrt_u64(in_u64));
  sink32(canfdi_q15_sqrt(a15));
  sink32(canfdi_q31_sqrt(a));
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
  canfdi_est_dcm_step(&est, in_s32[0], in_s32[1], in_s32[2]);
  sink32(canfdi_est_dcm_ra_q16(&est));
  sink32(canfdi_est_dcm_la_q24(&est));
  sink32(canfdi_est_dcm_psi_q16(&est));
  sink32(canfdi_est_dcm_j_q24(&est));
  sink32(canfdi_est_dcm_mf1_q24(&est));
  sink32(canfdi_est_dcm_mc_q16(&est));
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
  sink32(canfdi_est_thr_excited(&est) ? 1 : 0);
  sink32(canfdi_est_thr_el_converged(&est) ? 1 : 0);
  sink32(canfdi_est_thr_mech_converged(&est) ? 1 : 0);
  sink32(canfdi_rls_trace_q16(canfdi_est_thr_el_rls(&est)));
  sink32(canfdi_rls_trace_q16(canfdi_est_thr_mech_rls(&est)));
  d = canfdi_est_thr_diag(&est);
  sinku64((uint64_t)d->steps + d->el_updates + d->mech_updates + d->mech_lh_skips +
          d->mech_still_skips + d->clip_skips + d->resets);
}

int main(void)
{
  guard_fixp();
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
  guard_generated();
  return 0;
}
