/*
 * canfdi_est_thr.h — parameter estimator of the electronic throttle valve:
 * motor resistance R, inductance L, back-EMF constant K (= Psi nu, motor
 * flux times gear ratio, shaft-referred) and a voltage offset from the
 * electrical equation; inertia J, viscous friction B, return-spring
 * constant k_s, pretension P and Coulomb friction T_c from the mechanical
 * equation. Two UD-RLS estimators (canfdi_rls.h) on SVF signals
 * (canfdi_svf.h).
 *
 * Equations (the valve of docs/design.md, shaft-referred; theta the valve
 * angle):
 *   electrical:  U = R i + L di/dt + K dtheta/dt + U_0
 *                y = U,  phi = [i, di/dt, dtheta/dt, 1],
 *                theta_e = [R, L, K, U_0]
 *                (L is estimated too: L/R = 1 ms is not negligible against
 *                the SVF corner, and leaving it out biases R through the
 *                correlated di/dt.)
 *   mechanical:  K i = J theta'' + B theta' + k_s (theta - theta_LH)
 *                      + P sign(theta - theta_LH) + T_c sign(theta')
 *                divided by K, with the measured current as output and
 *                theta > theta_LH (sign +1; see the gate below):
 *                y = i,  phi = [theta'', theta', theta, 1, s],
 *                theta_m = [J/K, B/K, k_s/K, (P - k_s theta_LH)/K, T_c/K]
 *                and converted back with K from the electrical estimate
 *                (the nominal K until that has converged):
 *                k_s = K th2, P = K th3 + k_s theta_LH, B = K th1, ...
 * Friction sign. s is the sign of the velocity, +1 / -1 when the filtered
 * |theta'| exceeds a dead band (cfg), else 0, passed through its own SVF
 * of the same configuration so that it is filtered like the other signals.
 * This is an approximation: while the valve sticks the friction torque lies
 * anywhere in [-T_c, T_c], not at T_c s; the estimates of T_c and P carry
 * that error (see the tests for the measured accuracy).
 * Validity gates (besides the RLS excitation gate), each counted:
 *  - the mechanical update is skipped while the filtered angle is within
 *    limp_band of theta_LH (the pretension sign is ambiguous there;
 *    diag.mech_lh_skips) and unless the valve has moved in one direction
 *    beyond the sign dead band for holdoff_steps steps (diag.
 *    mech_still_skips): only then is the filtered sign signal settled at
 *    +-1 and the friction torque known to be T_c s. Near reversals and
 *    while sticking the equation is not valid, so those data are left out.
 *  - both updates are skipped for holdoff_steps after a current sample at
 *    or beyond i_limit (a clipped ADC reading: the valve draws more than
 *    the sensor's span during full-voltage moves; diag.clip_skips).
 * Excitation that identifies the mechanical parameters therefore needs
 * sustained motion: e.g. a slow sine of the angle setpoint over a wide
 * range (the spring torque changes by only k_s * 1.2 rad ~ 0.1 N m over
 * the stroke, against T_c ~ 0.28 N m).
 * Fast mechanical test. The 5-parameter RLS needs ~10 s of memory to tell
 * k_s, P and T_c apart (the spring torque changes by ~0.1 N m over the
 * stroke only), so on its own it isolates a weak spring or a doubled
 * friction only 1.6-2.8 s after the fault. With the nominal parameters
 * known, only the
 * two fault directions are estimated, on the same gated samples as the
 * mechanical RLS (moving one way, away from limp-home, no clipping):
 *   r = K i - J theta'' - B theta' - c - T_c s,
 *   c = k_s (theta - theta_LH) + P            (nominal spring torque)
 *   r ~ a c + b s:  a = relative spring deviation (k_s and P scale
 *   together when the spring weakens), b = T_c deviation (N m).
 * Least squares on exponentially weighted means (weight 2^-fast_shift per
 * update; shift 6 at ~200 updates/s is a ~0.3 s memory, about half the
 * 2 Hz excitation's 0.5 s period): m_xy += (x y - m_xy) 2^-shift, then
 *   det = m_cc m_ss - m_cs^2,  a = (m_ss m_cr - m_cs m_sr) / det,
 *   b = (m_cc m_sr - m_cs m_cr) / det.
 * c is ~0.4 N m and nearly constant, s is +-1: the two are separable once
 * the window holds motion in both directions, which det / (m_cc m_ss)
 * = 1 - corr(c, s)^2 measures (fast_sep_min). Valid after fast_min_updates
 * updates, while separable and within fast_stale_steps of the last update
 * (a valve that stopped moving keeps no stale verdict).
 * Direction pairing. In one direction of motion a weaker spring and a
 * higher friction are alike: closing, the spring aids the motion and
 * friction opposes it, so either lowers r (a c < 0, or -b < 0); opening,
 * a weaker spring lowers r and a higher friction raises it. Only the
 * difference between the directions separates them, and only if both
 * directions' data describe the same plant. The means keep the last window
 * of the other direction while the valve moves one way (a driver's 0.5 Hz
 * sine gives one-way windows ~1 s apart): a change that arrives during a
 * closing window, or a ramp between windows, is then split between a and
 * b by the old opening data (a weakening spring reads as a friction rise,
 * a friction step as a spring loss). The solution is therefore "paired"
 * only when its last update was opening, or closing within
 * fast_pair_steps of an opening update (canfdi_est_thr_fast_paired);
 * opening data are not ambiguous for the catalogue faults (a weaker spring
 * and a higher friction move r opposite ways), closing data are. 300 steps
 * bound the error a ramp leaves: the fastest catalogue ramp, 30 % of the
 * spring over 2 s, moves a by 0.15 x 0.3 = 4.5 %, i.e. b by 4.5 % x c / 2
 * ~ 3 % of T_c, against the +8 % friction threshold; and the 2 Hz test
 * burst (canfdi_app_cal.c) reverses every 0.25 s, so that with it on the
 * closing windows are paired.
 * Why this is fast: the fault enters r at once and fully (a step of a c
 * or b s), and the two-regressor solution follows the EW mean with its
 * ~0.3 s memory, instead of waiting for a 5-parameter RLS to re-separate
 * k_s, P and T_c from the slow spring-torque variation.
 * Spread and thresholds: a and b err by the relative error of K (K i) and
 * of the nominal spring and friction (datasheet class, ~5 % each), plus
 * the J theta'' and B theta' terms (uncorrelated with s and c over a
 * period), plus noise (0.01 A current noise x K = 4 mN m, averaged over
 * ~100 updates); the TPS noise through the SVF's theta'' (J theta'') and
 * the closed loop's reaction to it dominate. Measured (tests/unit/
 * test_est_thr.c, reference controller, 25 deg +- 3 deg at 2 Hz): fault-free
 * spring -0.001 (sd 0.005), friction -0.014 (sd 0.010); spring -30 % / -10 %
 * read -0.299 / -0.099, friction x2 / +20 % +1.009 / +0.190, 70 % of the
 * fault reached 0.26-0.29 s after the step. In the application (SIL, its
 * controller and the vehicle's +-8 deg sine on top) the spread is larger;
 * the thresholds and their argument are in canfdi_diagnosis.c.
 * Scaling and overflow: torques Q16.16 N m from Q24 x Q16.16 and Q16.16 x
 * Q16.16 products with rounded shifts, summed in int64 and saturated to
 * int32 and clamped to +-16 N m (4 x the largest torque of the valve,
 * K x 10 A); the means are Q32 in int64; the solution reduces them to Q24
 * (every product Q48 < 2^61 with |c|, |r| <= 16, |s| <= 1), det to Q32; a, b Q16.16 saturated; b / T_c by canfdi_div_s32_qn.
 * Sample alignment: as for the DC motor (canfdi_est_dcm.h), the measured
 * motor voltage is held over the step, so y = U_f + (T/2) dU_f/dt.
 * All four SVFs have the same configuration (order 3, so that theta'' is a
 * filter state).
 *
 * Inputs Q16.16 SI: motor voltage V, current A, angle rad (0 .. 1.6).
 * Outputs: R, K, U_0, P, T_c Q16.16; L, J, B, k_s Q24. Read-outs saturate.
 *
 * Cost per step: 4 SVF steps of order 3 every step, plus one RLS update
 * (4 parameters, or 5 for the mechanical part) on each of two steps out of
 * `decim`; the fast test adds ~40 multiplies and 3 divisions (64-bit
 * dividends, core/canfdi_fixp.h: no libgcc 64-bit division) per
 * mechanical update: canfdi_svf.h and canfdi_rls.h state their cost per
 * call; `make bench-pil-profile` measures the whole step in the
 * application, per module and function (build/bench/pil_profile.json).
 * A larger decim lowers the average (the memory 1/(forget rate) scales
 * with it). Memory: sizeof(canfdi_est_thr_t) = 1248 bytes on
 * a 32-bit target.
 */
#ifndef CANFDI_EST_THR_H
#define CANFDI_EST_THR_H

#include "model/canfdi_rls.h"
#include "model/canfdi_svf.h"

#if CANFDI_CFG_RLS_MAX_PARAMS < 5
#error "canfdi_est_thr needs CANFDI_CFG_RLS_MAX_PARAMS >= 5"
#endif

/* Normalising shifts (powers of two dividing the physical signal). */
#define CANFDI_EST_THR_SHIFT_U 4    /* U / 16 V */
#define CANFDI_EST_THR_SHIFT_I 1    /* i / 2 A */
#define CANFDI_EST_THR_SHIFT_DI 8   /* di/dt / 256 A/s */
#define CANFDI_EST_THR_SHIFT_DA 3   /* theta' / 8 rad/s */
#define CANFDI_EST_THR_SHIFT_D2A 10 /* theta'' / 1024 rad/s^2 */
#define CANFDI_EST_THR_SHIFT_A 0    /* theta / 1 rad */

typedef struct {
  canfdi_svf_cfg_t svf;     /* order must be 3 */
  uint8_t decim;            /* RLS update every decim steps, 1..100 */
  canfdi_q31_t forget_q31;  /* 1 - lambda, electrical RLS */
  canfdi_q31_t mech_forget_q31; /* 1 - lambda, mechanical RLS (longer memory:
                             * the spring shows only over whole sweeps) */
  int32_t p0_q16;
  int32_t trace_max_q16;
  int32_t excite_min_q16;
  uint8_t excite_shift;
  uint32_t conv_updates;
  int32_t sign_band_q16;    /* |theta'| dead band of the friction sign, rad/s */
  int32_t limp_band_q16;    /* mechanical gate around theta_LH, rad */
  int32_t i_limit_q16;      /* |i| at or above this is a clipped sample, A
                             * (the current sensor's span); 0 disables */
  uint16_t holdoff_steps;   /* steps a gate stays closed after its cause
                             * (about the SVF's memory), 1..1000 */
  /* nominal parameters (initial theta; K before convergence) */
  int32_t r_nom_q16;        /* Ohm */
  int32_t l_nom_q24;        /* H */
  int32_t k_nom_q16;        /* V s/rad = N m/A */
  int32_t u0_nom_q16;       /* V */
  int32_t j_nom_q24;        /* kg m^2 */
  int32_t b_nom_q24;        /* N m s/rad */
  int32_t spring_nom_q24;   /* N m/rad */
  int32_t pretension_nom_q16; /* N m */
  int32_t friction_nom_q16; /* N m */
  int32_t limp_home_q16;    /* theta_LH, rad */
  /* fast structured test (see "Fast mechanical test" above) */
  uint8_t fast_shift;       /* EW weight 2^-shift per mechanical update, 1..12 */
  uint16_t fast_min_updates; /* updates before the deviations are valid */
  int32_t fast_sep_min_q16; /* det / (m_cc m_ss) at or above: separable */
  uint16_t fast_stale_steps; /* valid only within this many steps of an update */
  uint16_t fast_pair_steps; /* a solution last updated while closing is valid
                             * only within this many steps of an opening
                             * update (see "Direction pairing") */
} canfdi_est_thr_cfg_t;

/* Diagnostics counters: monotone, saturating at UINT32_MAX
 * (core/canfdi_count.h); init clears them, nothing else does. No decision
 * of the firmware depends on them (canfdi_est_thr_has_run says whether the
 * estimator has stepped). */
typedef struct {
  uint32_t steps;           /* canfdi_est_thr_step calls */
  uint32_t el_updates;
  uint32_t mech_updates;
  uint32_t mech_lh_skips;  /* mechanical updates skipped near limp-home */
  uint32_t mech_still_skips; /* mechanical updates skipped: not moving steadily */
  uint32_t clip_skips;     /* updates skipped after a clipped current sample */
  uint32_t resets;          /* canfdi_est_thr_reset calls (init counts as none) */
  uint32_t fast_updates;   /* updates of the fast structured test */
} canfdi_est_thr_diag_t;

typedef struct {
  canfdi_est_thr_cfg_t cfg;
  canfdi_svf_t svf_u;
  canfdi_svf_t svf_i;
  canfdi_svf_t svf_a;
  canfdi_svf_t svf_s;
  canfdi_rls_t el;
  canfdi_rls_t mech;
  uint8_t phase;           /* step counter modulo decim, 0 .. decim - 1 */
  uint8_t updated;        /* CANFDI_EST_THR_UPD_* of the last step */
  bool has_run;           /* stepped at least once since init (reset keeps it) */
  bool started;
  uint16_t since_clip;     /* steps since the last clipped current sample,
                            * saturating at UINT16_MAX */
  uint16_t moving;         /* steps moving in one direction beyond the band,
                            * saturating at UINT16_MAX */
  int8_t last_dir;
  uint32_t el_since_reset;   /* electrical updates since init/reset (state of
                              * `converged`), saturating at UINT32_MAX */
  uint32_t mech_since_reset; /* mechanical updates, likewise */
  /* fast structured test: EW means, Q32 (c, s, r of the header) */
  int64_t f_cc_q32;
  int64_t f_cs_q32;
  int64_t f_ss_q32;
  int64_t f_cr_q32;
  int64_t f_sr_q32;
  int32_t f_spring_dev_q16; /* last solution */
  int32_t f_fric_dev_q16;
  uint16_t f_n;             /* updates since reset, saturating at UINT16_MAX */
  uint16_t f_age;           /* steps since the last update, saturating at
                             * UINT16_MAX (UINT16_MAX after reset: none yet) */
  uint16_t f_open_age;      /* steps since the last opening update,
                             * saturating at UINT16_MAX (likewise after reset) */
  bool f_sep;               /* last solution separable */
  bool f_paired;            /* last update opening, or closing within
                             * fast_pair_steps of an opening update */
  canfdi_est_thr_diag_t diag;
} canfdi_est_thr_t;

/*
 * Defaults for the valve of docs/design.md at 1 ms: SVF order 3 at
 * 300 rad/s, decim 2 (500 Hz updates), lambda 0.995 electrical (memory
 * 0.4 s) and 0.9995 mechanical (2000 updates; with the motion gate
 * ~ 5-8 s), p0 100, trace bound 1000, excitation threshold 1e-3 on the less
 * excited of i and theta' (electrical: ~0.06 A and ~0.25 rad/s rms) and of
 * theta' and theta (mechanical: ~0.25 rad/s and ~1.8 deg rms), time
 * constant 2^6, converged after 1000 updates (2 s), sign dead band
 * 0.3 rad/s (~3 sigma of the filtered velocity noise for 0.003 V TPS
 * noise), limp band 2 deg, current limit 9.9 A (the simulator's sensor span
 * is +-10 A), hold-off 40 steps (the order-3 impulse response at 300 rad/s
 * decays below 1e-3 in ~37 ms), nominal parameters of docs/design.md with
 * U_0 = 0 and theta_LH = 6.5 deg; fast test shift 6, valid after 100
 * updates while det / (m_cc m_ss) >= 1/4 and within 500 steps of the last
 * update, paired within 300 steps of an opening update.
 */
void canfdi_est_thr_default_cfg(canfdi_est_thr_cfg_t *cfg);

/* Validates (SVF order 3, RLS domains, decim 1..100, K > 0, bands >= 0)
 * and resets. CANFDI_OK or -CANFDI_EINVAL (*e may be partly written). */
int32_t canfdi_est_thr_init(canfdi_est_thr_t *e, const canfdi_est_thr_cfg_t *cfg);

/* As canfdi_est_dcm_reset. Cannot fail. */
void canfdi_est_thr_reset(canfdi_est_thr_t *e, bool keep_theta);

/* Covariance boost of both RLS (canfdi_rls_boost); filters, estimates,
 * convergence state and the fast test kept. For a change the caller
 * detected (the diagnosis' first symptom). Cannot fail. Cost: O(n^2). */
void canfdi_est_thr_boost(canfdi_est_thr_t *e);

/* Which RLS applied an update in the last step: bit 0 electrical, bit 1
 * mechanical and fast test (CANFDI_EST_THR_UPD_*). O(1). */
#define CANFDI_EST_THR_UPD_EL 0x01U
#define CANFDI_EST_THR_UPD_MECH 0x02U
uint8_t canfdi_est_thr_updated(const canfdi_est_thr_t *e);

/* The next step is step k of the caller's schedule: the electrical update
 * falls on the steps with k mod decim = 0, the mechanical update and the
 * fast test on those with k mod decim = 1 (the same steps when decim is 1).
 * Called before every step, it locks the updates to the schedule; never
 * called, they count from the estimator's (re)start. Cannot fail. Cost: O(1);
 * a 32-bit division only for k >= decim. */
void canfdi_est_thr_align(canfdi_est_thr_t *e, uint32_t k);

/* One 1 ms step: motor voltage (V), current (A), angle (rad), Q16.16. */
void canfdi_est_thr_step(canfdi_est_thr_t *e, int32_t u_q16, int32_t i_q16, int32_t angle_q16);

int32_t canfdi_est_thr_r_q16(const canfdi_est_thr_t *e);
int32_t canfdi_est_thr_l_q24(const canfdi_est_thr_t *e);
int32_t canfdi_est_thr_k_q16(const canfdi_est_thr_t *e);
int32_t canfdi_est_thr_u0_q16(const canfdi_est_thr_t *e);
int32_t canfdi_est_thr_j_q24(const canfdi_est_thr_t *e);
int32_t canfdi_est_thr_b_q24(const canfdi_est_thr_t *e);
int32_t canfdi_est_thr_spring_q24(const canfdi_est_thr_t *e);
int32_t canfdi_est_thr_pretension_q16(const canfdi_est_thr_t *e);
int32_t canfdi_est_thr_friction_q16(const canfdi_est_thr_t *e);

/* Fast structured test: relative deviation of the spring torque
 * (k_s, P together; -0.3 = 30 % weaker) and of the Coulomb friction
 * (+1.0 = doubled), Q16.16; meaningful while canfdi_est_thr_fast_valid. */
int32_t canfdi_est_thr_fast_spring_dev_q16(const canfdi_est_thr_t *e);
int32_t canfdi_est_thr_fast_friction_dev_q16(const canfdi_est_thr_t *e);
bool canfdi_est_thr_fast_valid(const canfdi_est_thr_t *e);

/* Valid, and the last update was opening or closing within
 * fast_pair_steps of an opening update ("Direction pairing" above): only
 * then does the solution separate a weaker spring from a higher friction.
 * O(1). */
bool canfdi_est_thr_fast_paired(const canfdi_est_thr_t *e);

/* As canfdi_est_dcm_has_run. O(1). */
bool canfdi_est_thr_has_run(const canfdi_est_thr_t *e);

bool canfdi_est_thr_excited(const canfdi_est_thr_t *e);
bool canfdi_est_thr_el_converged(const canfdi_est_thr_t *e);
bool canfdi_est_thr_mech_converged(const canfdi_est_thr_t *e);

const canfdi_rls_t *canfdi_est_thr_el_rls(const canfdi_est_thr_t *e);
const canfdi_rls_t *canfdi_est_thr_mech_rls(const canfdi_est_thr_t *e);
const canfdi_est_thr_diag_t *canfdi_est_thr_diag(const canfdi_est_thr_t *e);

#endif /* CANFDI_EST_THR_H */
