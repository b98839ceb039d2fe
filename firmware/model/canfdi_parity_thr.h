/*
 * canfdi_parity_thr.h — residuals of the electronic throttle valve, in fixed
 * point, one 1 ms step at a time: the TPS correlation, the armature
 * equation and a model-versus-sensor position residual per potentiometer,
 * which is the third vote that tells the drifting TPS from the healthy one.
 *
 * Signals. TPS1 and TPS2 voltages (opposite slopes, sum constant), the
 * motor current i, the voltage the bridge applied over the last interval
 * (the previous command, limited here to +-supply; unknown while the bridge
 * is off, hence `enabled`), the measured bridge supply. Angles from the
 * potentiometers through their characteristics (model/canfdi_tps.h):
 * theta1 from cfg.tps1, theta2 from cfg.tps2, a complementary pair
 * (tps2.slope = -tps1.slope, so TPS1 + TPS2 = tps1.zero + tps2.zero =
 * tps_sum at every angle); a voltage outside [tps_min, tps_max] marks that
 * sensor out of range (open/short: the range check of another module names
 * it; here it only drops out).
 *
 * The residuals (index, unit):
 *   CORR  r = LP(TPS1 + TPS2 - tps_sum)                             [V]
 *         Sensitive to an offset of either TPS (+ for an upward drift of
 *         either), blind to everything in the motor and the mechanics.
 *   ARM   r = u - R i - L di/dt - K dtheta/dt                       [V]
 *         The armature equation on third-order SVF outputs (same filter on
 *         u, i and theta). Sampling alignment as in canfdi_parity_dcm.h: u
 *         is the voltage held over the interval, i enters as its interval
 *         mean. Because L/R of this motor (1 ms) equals the step, the
 *         trapezoid (i_k + i_k-1)/2 would be 8 % off in current
 *         transients; the exact mean of a first-order R-L response,
 *         i_k-1 + beta (i_k - i_k-1) with beta = 1/(1 - e^-x) - 1/x,
 *         x = R T / L (0.582 here; 1/2 for L >> R T), is used instead,
 *         computed at init (fixed-point exp). dtheta/dt comes from
 *         theta_arm, an angle integrated from per-step sensor increments:
 *         the mean of the two TPS increments, or, when they differ by more
 *         than jump_rad in one step (a sensor jumped), the median of the
 *         two and the previous increment, so the jump is outvoted; theta_arm
 *         leaks towards the TPS mean (1/2^8 per step) while the two agree,
 *         which bounds its drift. (Switching between the sensors every step
 *         would inject white speed noise: with a plain median of three the
 *         fault-free noise of ARM is 28 mV instead of 2 mV.) A constant
 *         TPS offset has no derivative, so ARM is decoupled from TPS drift,
 *         from the very first sample of a jump; it sees R (dR i), K, an
 *         open circuit and current-sensor errors.
 *   POS1  r = LP(theta1 - theta_hat),  POS2  r = LP(theta2 - theta_hat)  [rad]
 *         theta_hat from the valve observer below. LP is a first-order
 *         low-pass with time constant res_tau (noise), identical on the
 *         sensor and the model side, so it adds no model error.
 *
 * The valve observer (why it stays stable and drift-free). The valve model
 * (J, viscous B, return spring k_s (theta - theta_LH) plus the pretension
 * P sat((theta - theta_LH) / lh_width), Coulomb friction with stiction,
 * end stops at 0 and max) is driven by K times the interval-mean current
 * and integrated once per step (semi-implicit Euler; friction decides stick
 * or slide first, and cannot reverse the motion within a step). Alone it
 * would drift: with these parameters friction (0.284 N m) dwarfs the spring
 * (0.087 N m/rad), so the steady angle is undetermined within several
 * radians of friction band, and the motion it predicts from the current
 * alone misses small controller moves. Two measurements correct it:
 *   1. the back-EMF velocity w_el = (u - R i_mean - L di/T) / K, blended
 *      into the predicted speed with obs_emf_gain per step (0.3): a speed
 *      measurement from the armature, independent of the potentiometers
 *      (available while the bridge is driving and the current is not
 *      clipped). It makes the prediction follow the real motion; its bias
 *      (an R error times i) is a drift the position feedback removes.
 *   2. position feedback from the potentiometers, theta_hat += l1 e,
 *      w_hat += l2 e with e = y - theta_hat, l1 = 2 lambda T,
 *      l2 = lambda^2 T (a double pole at 1 - lambda T, lambda = 30 rad/s):
 *      this is what keeps the observer drift-free. Which y:
 *        MEAN  the mean of TPS1 and TPS2 while their correlation residual
 *              is inside its band (normal operation);
 *        NONE  coasting on the model and w_el alone, as soon as the
 *              correlation leaves its band: a disagreeing sensor must not
 *              drag the model towards itself (its half of the mean would).
 *              The coast starts from the observer, limited to within
 *              half the sensors' disagreement of theta_arm (below), the
 *              interval a fault of one sensor leaves for the true angle:
 *              theta_arm lies between the truth and the mean (an abrupt
 *              offset is outvoted there; one whose jump is within jump_rad
 *              of the other sensor's noisy increment, or a drift, moves it
 *              by up to half). Inside, the observer lags the mean and so
 *              keeps most of the angle from before the disagreement (a
 *              0.04 V TPS1 step whose jump was not outvoted was otherwise
 *              taken for TPS2); outside, its own error just after a fast
 *              stroke (up to several bands after a 70-deg tip-out) would
 *              stay common to POS1 and POS2 for the whole coast, and the
 *              larger of them be taken for the drifting sensor.
 *              While w_el is unavailable (current clipped in a fast stroke,
 *              bridge off) the coasting observer follows the jump-robust
 *              sensor increment instead of the mechanical model, which is
 *              poor there; an offset, even a drifting one, barely changes
 *              within those few steps. One absolute angle is known: with
 *              the bridge off the return spring's pretension, larger than
 *              the Coulomb friction, leaves the valve at rest only within
 *              a fraction of lh_width of the limp-home angle (the default
 *              valve: 0.396 against 0.284 N m, so within 0.09 deg; it
 *              returns from full travel in about 0.3 s). So once the
 *              bridge has been off and the valve at rest (rest_w) for
 *              PTHR_LH_SETTLE_STEPS (0.1 s), the coasting observer is set
 *              to theta_LH: a disagreement present from power-up (the
 *              manager de-energises the valve while it is not isolated)
 *              or one that outlasted the coast is then decided by the
 *              sensor that reads the limp-home angle. Not with a
 *              configured pretension at or below the friction. The
 *              reference assumes one fault: a TPS disagreement together
 *              with a weak spring, more friction or a jam (the valve then
 *              rests elsewhere) is outside it, as for the diagnosis.
 *              A disagreement present from the first sample after init or
 *              reset leaves the observer at the sensors' mean with nothing
 *              from before it: coasting from there, the model's own drift
 *              would pick a sensor. No sensor is trusted then, by the
 *              selection below or by the vote (no_ref), until the observer
 *              has an angle of its own: the correlation was within its
 *              base band once (the band widens with the valve's motion,
 *              and a small disagreement fits a widened one; one just above
 *              the base band that dips into it leaves POS1/POS2 far inside
 *              their band), the limp-home angle was taken, or the manager
 *              imposed a sensor (canfdi_parity_thr_force_source).
 *              Measured coasting drift with the test plant: ~5 mrad over
 *              20 s of 20-deg strokes every 0.5 s;
 *        TPS1 / TPS2  once, while coasting, one position residual is more
 *              than select_ratio (4) times the other and above its band,
 *              with the valve at rest (|dtheta/dt| <= rest_w), for
 *              select_steps (20) consecutive steps: the model agrees with
 *              that sensor, so it is trusted and the observer follows it
 *              (latched). Back to MEAN after release_steps (200) steps with
 *              the correlation inside its band. With one sensor out of
 *              range the other is used; with none, NONE.
 *      canfdi_parity_thr_force_source() lets the fault manager impose a
 *      source (e.g. after it confirmed a sensor fault).
 *   Stability: with the position feedback the estimation error of a
 *   sticking or freely sliding valve obeys e(k+1) = [[1 - l1, T], [-l2, 1]]
 *   e(k), a double pole at 1 - lambda T, inside the unit circle for
 *   lambda T < 1 (lambda <= 100 rad/s is enforced); the model adds damping
 *   (viscous friction, Coulomb friction that cannot reverse the motion, and
 *   the w_el blend, a contraction of the speed error by 1 - emf_gain per
 *   step). Coasting has no position feedback: its error integrates the
 *   speed error (w_el bias and noise), which is why the isolation below
 *   relies on coasting staying short or quasi-static.
 *   The position residual of the faulty sensor then carries its whole
 *   offset, persistently, and the healthy one stays near zero: the
 *   decoupling is that POSk depends on sensor k and on the observer, and
 *   the observer, once a sensor is distrusted, no longer depends on it.
 *   Abrupt offsets are isolated at once (the jump is in one sensor only
 *   and the model says the valve did not move). A drifting offset is
 *   tracked by the mean until the correlation gate closes, so theta_hat
 *   starts coasting d0/2 off (d0 = the correlation band in angle units,
 *   10 mV -> 2 mrad); the isolation then rests on the coasting observer
 *   staying closer to the truth than the drift grows. Measured (0.1 V
 *   drifts, both sensors and signs, 4 noise seeds each): constant and
 *   1 Hz sine setpoints, ramps of 3, 10 and 30 s: 45 of 48 isolated
 *   correctly, 3 undecided (NONE: both POS out, CORR out -> "correlation,
 *   not isolated", P2135), none wrong. Continual 20-deg strokes every
 *   0.5 s: 3 s ramps 11 of 12 correct (1 undecided), 10 s ramps 5 correct,
 *   6 undecided, 1 wrong, 30 s ramps 5 correct, 2 undecided, 5 WRONG (the
 *   faulty sensor trusted): with frequent large strokes and slow drifts the
 *   model's coasting error is as large as the drift; a diagnosis should
 *   confirm an isolation only from a quasi-static phase, or use the
 *   mechanical parameter estimator's angle as a further vote.
 *
 * Fault-symptom structure (theory; steady state; sign for the named
 * direction; "cm" = common mode, the same in POS1 and POS2):
 *
 *   fault                      CORR      ARM          POS1           POS2
 *   TPS1 offset +d [V]         +d        0            +d/slope       0 (once isolated)
 *   TPS2 offset +d [V]         +d        0            0 (isolated)   -d/slope
 *   TPS open / short           out of range: dropped (a range check names it)
 *   motor R up (+dR)           0         +dR i        cm -, weak (w_el bias -dR i/K)
 *   motor circuit open         0         +u - K w     cm, large (w_el = u/K)
 *   current sensor offset +dI  0         -R dI        cm, weak (via w_el)
 *   return spring weak         0         0            cm +, weak (model, in motion)
 *   friction up / sticking     0         0            cm ~0 mean, weak
 *   valve jammed               0         0            ~0: u = R i + L di/dt holds
 *                                                     with w = 0 (the equations
 *                                                     stay consistent; the
 *                                                     position control error
 *                                                     shows it, not parity)
 * Measured (tests/unit/test_parity_thr.c, sine 30 +- 10 deg at 1 Hz unless
 * noted; deviation of the post-fault mean in fault-free sigma):
 *   TPS1 +-0.1 V: CORR +-155 sigma, POS1 +-230 sigma, POS2 0, ARM -1;
 *   TPS2 +-0.1 V: CORR +-155 sigma, POS2 -+220 sigma, POS1 0, ARM -1;
 *   motor R +20 % (constant 20 deg, i ~1.1 A): ARM +0.32 V = +150 sigma,
 *   POS1/POS2 -0.008 rad (~-50 sigma, common mode, below the band most of
 *   the time), CORR 0; spring -20 %: POS +0.0013 rad (+8 sigma, inside the
 *   band), CORR/ARM 0; friction x2: no mean deviation; motor open: ARM
 *   +13.5 V, POS -0.5 rad common mode. Fault-free sigma: CORR 0.6 mV,
 *   ARM 1.9-2.1 mV (6 mV with 20-deg steps), POS 0.16 mrad (0.5 mrad).
 * Mechanical faults reach the position residuals only weakly, because the
 * back-EMF velocity makes the observer follow the real motion; they are
 * the job of the mechanical parameter estimator.
 *
 * Validity (out.valid bit per residual): nothing for settle_steps after
 * init/reset; CORR needs both sensors in range; POSk sensor k in range;
 * ARM the bridge driving, the current below i_max and a sensor in range for
 * settle_steps consecutive steps (the SVFs restart on the enable edge).
 *
 * Thresholds: canfdi_adapt_t per residual; excitation u: the applied
 * voltage for ARM, theta_arm (so |dtheta/dt|) for CORR, POS1, POS2.
 * Position bands (Isermann: adaptive threshold from model uncertainty).
 * theta_hat moves with the model's speed (the back-EMF velocity blended
 * into the mechanical prediction), so a relative error eps of that speed
 * (K, R, spring, friction and inertia of the valve model, each known to
 * datasheet class only) integrates to a position error eps |w| dt over a
 * stroke, which the position feedback removes with the observer's error
 * dynamics (double pole at lambda: decay time ~2 / lambda). The error is
 * therefore bounded by eps times the stroke travelled in the last
 * ~2 / lambda, which is what canfdi_adapt's low-pass of |dtheta/dt| with
 * tau = 2 / lambda measures (f tau): band = base + eps (tau + T) f, i.e.
 * gain = eps (tau + T) (canfdi_adapt.h, "Choosing the parameters").
 * Default eps = 5 % (the substitute valve parameters are a class, not this
 * valve), lambda 30 rad/s: tau 66.7 ms, gain 3.4 ms; a 40-deg stroke in
 * 60 ms (f ~ 10 rad/s) widens the band by 0.034 rad for ~0.1 s. At rest
 * (f = 0) the band is the base, 0.012 rad: a TPS offset of 2 % of full
 * scale (0.1 V = 0.039 rad) stays 3 x outside in steady state; during and
 * just after a large stroke it can be inside (accepted: the correlation
 * residual CORR still sees it at once). In the 10 h bench (bench_longrun)
 * the fault-free POS1/POS2 peak at 0.44 of this band, where closing
 * strokes of more than ~40 deg reach 1.75 times a fixed band.
 * out.rn_q16 = r / threshold (1.0 = threshold); exceed = valid and beyond.
 *
 * Scaling and overflow. Inputs Q16.16 (V, A). Angles Q16.16 rad, from the
 * TPS characteristics (canfdi_tps.h: 1 / |slope| in Q8.24, exact to 1 LSB);
 * mechanical and electrical parameters Q8.24. Torques and the
 * armature voltage balance are Q40 in int64 (Q24 x Q16.16 exact products,
 * saturating sums), reduced to Q24 before the division by J (T/J as Q24)
 * or K (1/K as Q24) -> Q48 -> Q32. Observer states theta_hat and w_hat are
 * Q32 in int64 (a speed of 1 mrad/s moves the angle 1e-6 rad per step,
 * below the Q16.16 LSB); w_hat bounded to +-2000 rad/s, theta_hat to
 * [0, max]. Low-pass states Q32 in int64. theta_arm is Q32 in int64: the
 * mean increment (d1 + d2)/2 is exact there and the leak rounds at 2^-32;
 * in Q16.16 the round-half-up of every increment would bias dtheta/dt by
 * up to 4 mrad/s (1.5 mV in ARM). Everything saturates; nothing
 * wraps. Rounding half up throughout (canfdi_fixp.h). Against an exact
 * evaluation on the same inputs (tests/ref/ref_parity.cpp), the
 * tolerances, worst case with all rounding errors aligned: CORR 2 LSB (the
 * TPS sum is exact; the low-pass has a Q32 state and rounds once, 0.5 LSB).
 * ARM 24 LSB: the SVF inputs i_mean and theta_arm_mean are rounded
 * (+-2^-17), which passes the filter with L1 norms 1 (y) and 54/s (dy at
 * wc 100), plus +-2^-17 on every output and the result: 1.5 (2 x 2^-17)
 * + L (2^-17 + 54 x 2^-17) + K (2^-17 + 2 x 54 x 2^-17) + ... = 23.5 LSB
 * (the angle of each sensor is rounded too, hence 2 x on theta).
 * POS 8 LSB: the angles (+-0.5), theta_hat Q32 -> Q16 (+-0.5), the
 * rounded innovation in the feedback (loop DC gain 1, +-0.5 to +-1) and the
 * low-pass output (+-0.5): ~3 LSB, doubled. A discrete decision taken one
 * step apart (stick/slide, feedback source) would move theta_hat by up to
 * one step of motion until the feedback removes it (~1/lambda); the
 * comparison counts such steps and steps with a different source (both 0
 * in every reference run). Measured maxima: CORR 0.5, ARM 6.3, POS 1.7 LSB.
 *
 * Cost per canfdi_parity_thr_step: 3 SVF steps of order 3, 4
 * canfdi_adapt_step, 4 canfdi_div_s32_qn, ~20 64-bit multiplies and ~60
 * saturating 64-bit adds/shifts. `make bench-pil-profile` measures it in
 * the application, per module and function (build/bench/pil_profile.json;
 * the SVF steps, the thresholds and the 64-bit helpers are counted under
 * canfdi_svf, canfdi_adapt, canfdi_fixp, canfdi_intrin and libgcc there).
 * Code (`make footprint`, the application image): 6.0 kB (M4), 7.4 kB
 * (M0) plus canfdi_tps, svf, adapt and fixp.
 * Memory: sizeof(canfdi_parity_thr_t) = 664 bytes on a 32-bit target,
 * caller-owned; the configuration (188 bytes) must outlive the instance.
 * No heap, no globals, no floating point; reentrant per instance.
 */
#ifndef CANFDI_PARITY_THR_H
#define CANFDI_PARITY_THR_H

#include "core/canfdi_common.h"
#include "core/canfdi_fixp.h"
#include "detect/canfdi_adapt.h"
#include "model/canfdi_svf.h"
#include "model/canfdi_tps.h"

#define CANFDI_PARITY_THR_N_RES 4U
#define CANFDI_PARITY_THR_CORR 0U /* TPS1 + TPS2 - sum, V */
#define CANFDI_PARITY_THR_ARM 1U  /* armature equation, V */
#define CANFDI_PARITY_THR_POS1 2U /* theta1 - theta_hat, rad */
#define CANFDI_PARITY_THR_POS2 3U /* theta2 - theta_hat, rad */

/* Observer feedback source. */
#define CANFDI_PARITY_THR_SRC_NONE 0U /* coasting on the model */
#define CANFDI_PARITY_THR_SRC_TPS1 1U
#define CANFDI_PARITY_THR_SRC_TPS2 2U
#define CANFDI_PARITY_THR_SRC_MEAN 3U

/*
 * Configuration, caller-owned, must outlive the instance (thresholds point
 * into band[]). Domain (else -CANFDI_EINVAL): tps1 and tps2 valid for
 * canfdi_tps_cal_check and complementary (tps2.slope = -tps1.slope);
 * 0 <= tps_min <= tps_max <= 10 V; i_max
 * > 0 and <= 100 A; R 0.01..100 Ohm, L 0..0.1 H, K 0.01..10 N m/A,
 * J 1e-4..1 kg m^2, B, spring, pretension, friction 0..10; max 0.1..4 rad,
 * 0 <= limp_home <= max, lh_width 1e-4..0.1 rad; wc 20..1000 rad/s;
 * lambda 1..100 rad/s; emf gain >= 0 (Q31); stick_w 0..1 rad/s; rest_w
 * 0..100 rad/s; res_tau <= 10 s; select_ratio >= 1; bands valid for
 * canfdi_adapt with base > 0.
 */
typedef struct {
  canfdi_tps_cal_t tps1;       /* TPS1 characteristic (model/canfdi_tps.h) */
  canfdi_tps_cal_t tps2;       /* TPS2: the complement, slope -tps1.slope */
  int32_t tps_min_V_q16;       /* in-range window (0.25 .. 4.75 V) */
  int32_t tps_max_V_q16;
  int32_t i_max_A_q16;         /* |i| at/above: current sensor clipped */
  int32_t r_ohm_q24;           /* motor circuit resistance */
  int32_t l_H_q24;             /* motor inductance */
  int32_t k_Nm_A_q24;          /* motor constant = back-EMF constant */
  int32_t j_kgm2_q24;          /* shaft-referred inertia */
  int32_t b_Nms_q24;           /* viscous friction */
  int32_t spring_Nm_rad_q24;   /* return spring */
  int32_t pretension_Nm_q24;   /* spring pretension at limp-home */
  int32_t friction_Nm_q24;     /* Coulomb friction */
  int32_t limp_home_rad_q16;
  int32_t lh_width_rad_q16;    /* pretension regularisation width */
  int32_t max_rad_q16;         /* upper end stop (lower is 0) */
  int32_t omega_c_rad_s;       /* SVF corner (order 3) */
  int32_t obs_lambda_rad_s;    /* position feedback bandwidth */
  canfdi_q31_t obs_emf_gain_q31; /* back-EMF speed blend per step */
  int32_t stick_w_rad_s_q16;   /* stiction speed band of the model */
  int32_t rest_w_rad_s_q16;    /* |dtheta/dt| below which the valve is at rest */
  int32_t jump_rad_q16;        /* |d1 - d2| per step above which a TPS jumped */
  uint32_t res_tau_us;         /* low-pass of CORR, POS1, POS2 */
  uint16_t settle_steps;
  uint16_t select_steps;       /* persistence before trusting one sensor */
  uint16_t release_steps;      /* correlation in band before back to MEAN */
  uint8_t select_ratio;        /* |POS_bad| > ratio * |POS_good| to trust */
  canfdi_adapt_cfg_t band[CANFDI_PARITY_THR_N_RES]; /* residual units, Q16.16 */
} canfdi_parity_thr_cfg_t;

/* One sample. u: the voltage command in force over the interval that ends
 * now (the previous step's command); enabled: the bridge drove the motor
 * over that interval. */
typedef struct {
  int32_t tps1_V_q16;
  int32_t tps2_V_q16;
  int32_t i_A_q16;
  int32_t u_V_q16;
  int32_t supply_V_q16;
  bool enabled;
} canfdi_parity_thr_in_t;

typedef struct {
  int32_t r_q16[CANFDI_PARITY_THR_N_RES];   /* CORR V, ARM V, POS1 rad, POS2 rad */
  int32_t rn_q16[CANFDI_PARITY_THR_N_RES];  /* r / threshold */
  int32_t thr_q16[CANFDI_PARITY_THR_N_RES];
  uint8_t valid;
  uint8_t exceed;
  uint8_t src;                 /* CANFDI_PARITY_THR_SRC_* in use */
  bool no_ref;                 /* both sensors in range, and the observer
                                * has no angle of its own (unref): POS1 and
                                * POS2 say nothing about which sensor is
                                * wrong (its own drift would pick one); the
                                * vote still takes the observer's angle as
                                * the third opinion */
  int32_t theta_hat_rad_q16;   /* observer angle */
  int32_t omega_hat_rad_s_q16; /* observer speed */
  int32_t theta1_rad_q16;      /* angles from TPS1, TPS2 */
  int32_t theta2_rad_q16;
} canfdi_parity_thr_out_t;

/* Diagnostics counters: monotone, saturating at UINT32_MAX
 * (core/canfdi_count.h); init clears them, nothing else does. No decision
 * of the firmware depends on them. */
typedef struct {
  uint32_t steps;
  uint32_t resets;        /* canfdi_parity_thr_reset calls (init not counted) */
  uint32_t coast_entries; /* MEAN -> NONE (correlation left its band) */
  uint32_t selections;    /* a single sensor trusted */
  uint32_t releases;      /* back to MEAN */
  uint32_t current_clips; /* steps with |i| >= i_max */
} canfdi_parity_thr_diag_t;

typedef struct {
  const canfdi_parity_thr_cfg_t *cfg;
  canfdi_svf_t svf_u;
  canfdi_svf_t svf_i;
  canfdi_svf_t svf_th;
  canfdi_adapt_t thr[CANFDI_PARITY_THR_N_RES];
  canfdi_tps_t tps[2];    /* TPS1, TPS2 characteristics, prepared */
  int32_t tps_sum_V_q16;  /* TPS1 + TPS2 = tps1.zero + tps2.zero */
  int32_t t_over_j_q24;   /* T / J */
  int32_t l_over_t_q24;   /* L / T */
  int32_t inv_k_q24;      /* 1 / K */
  int32_t inv_lhw_q16;    /* 1 / lh_width */
  canfdi_q31_t t_q31;     /* T in s */
  canfdi_q31_t l1_q31;    /* 2 lambda T */
  int32_t l2_q16;         /* lambda^2 T, 1/s */
  canfdi_q31_t res_alpha_q31;
  canfdi_q31_t beta_q31;  /* interval-mean weight of the current */
  int64_t th_hat_q32;
  int64_t w_hat_q32;
  int64_t corr_q32;
  int64_t pos_q32[2];
  int32_t i_prev_q16;
  int32_t th1_prev_q16;
  int32_t th2_prev_q16;
  int64_t th_arm_q32;      /* angle for dtheta/dt (see ARM), Q32 */
  int64_t th_arm_prev_q32;
  int64_t inc_prev_q32;
  uint16_t settle;        /* steps left before the residuals are valid,
                           * settle_steps .. 0 */
  uint16_t arm_ok;        /* consecutive steps ARM could be formed,
                           * saturating at UINT16_MAX */
  uint16_t cand_n;        /* consecutive steps `cand` was the candidate,
                           * saturating at UINT16_MAX */
  uint16_t in_band_n;     /* consecutive steps CORR was inside its band,
                           * saturating at UINT16_MAX */
  uint16_t off_n;         /* consecutive steps with the bridge off and
                           * the valve at rest (rest_w), saturating at
                           * UINT16_MAX */
  uint8_t ok_prev;
  uint8_t src;
  uint8_t cand;
  bool en_prev;
  bool primed;
  bool unref;             /* the observer holds no angle of its own yet:
                           * the sensors have disagreed since the start
                           * (coasting, below) */
  canfdi_parity_thr_out_t out;
  canfdi_parity_thr_diag_t diag;
} canfdi_parity_thr_t;

/* The substitute DV-E5 class valve of docs/design.md (R 1.5, L 1.5 mH,
 * K 0.383, J 0.0021, B 0.0088, spring 0.087, pretension 0.396, friction
 * 0.284, limp-home 6.5 deg, 90 deg travel; TPS as canfdi_tps_cal_default:
 * 0.5 + 4 theta/90 deg and 4.5 - 4 theta/90 deg), wc 100 rad/s, lambda
 * 30 rad/s, emf gain 0.3, jump 0.01 rad, select ratio 4 for 20 steps at
 * rest (< 0.2 rad/s), release after 200 steps, bands CORR 0.01 V (~16 sigma of the filtered
 * noise), ARM 0.05 V + 9.5e-5 s x filtered |du/dt| (stroke transients),
 * POS 0.012 rad (0.7 deg, ~30 % of a 2 % TPS offset). NULL ignored. */
void canfdi_parity_thr_default_cfg(canfdi_parity_thr_cfg_t *cfg);

/* CANFDI_OK or -CANFDI_EINVAL. O(1). */
int32_t canfdi_parity_thr_cfg_check(const canfdi_parity_thr_cfg_t *cfg);

/* Validates, binds, precomputes, resets. CANFDI_OK or -CANFDI_EINVAL (then
 * p is unbound: step/reset refuse it). Not for the 1 ms path (64-bit
 * divisions, SVF inits). */
int32_t canfdi_parity_thr_init(canfdi_parity_thr_t *p, const canfdi_parity_thr_cfg_t *cfg);

/* Restart on the next sample (filters, observer at the measured angle,
 * source MEAN, settle); counters kept. No-op on NULL/unbound. */
void canfdi_parity_thr_reset(canfdi_parity_thr_t *p);

/* One 1 ms step. Returns the outputs, or NULL for NULL/unbound p or NULL
 * in. Every input value is accepted (saturating arithmetic, no UB). */
const canfdi_parity_thr_out_t *canfdi_parity_thr_step(canfdi_parity_thr_t *p,
                                                      const canfdi_parity_thr_in_t *in);

/* Imposes the observer's feedback source (CANFDI_PARITY_THR_SRC_*); the
 * automatic rules continue from it (MEAN returns after the correlation was
 * in band for release_steps). CANFDI_OK or -CANFDI_EINVAL. */
int32_t canfdi_parity_thr_force_source(canfdi_parity_thr_t *p, uint8_t src);

const canfdi_parity_thr_out_t *canfdi_parity_thr_out(const canfdi_parity_thr_t *p);
const canfdi_parity_thr_diag_t *canfdi_parity_thr_diag(const canfdi_parity_thr_t *p);

#endif /* CANFDI_PARITY_THR_H */
