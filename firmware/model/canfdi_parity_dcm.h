/*
 * canfdi_parity_dcm.h — structured parity residuals of the DC motor drive
 * (Isermann, Fault-Diagnosis Systems, 2006, ch. 10: parity equations with
 * structured residuals), in fixed point, one 1 ms step at a time.
 *
 * The model. Armature and mechanics of the DC motor (docs/design.md):
 *   (A)  L_A dI/dt = U_A - R_A I_A - Psi w
 *   (B)  J dw/dt   = Psi I_A - M_F1 w - M_F0 sgn(w) - M_L
 * Four residuals, each computed without one of the four signals U_A, I_A,
 * w and M_L, so that a fault of that signal leaves it untouched:
 *   r1 = U - R I - L dI - Psi w                             (A)    [V]   no M_L
 *   r2 = Psi I - J dw - M_F1 w - z                          (B)    [N m] no U_A
 *   r3 = cI I + cdI dI + cd2I d2I - (J/Psi) dU - (M_F1/Psi) U - z  [N m] no w
 *        (w eliminated: Psi w = U - R I - L dI from (A), put into (B) / Psi)
 *   r4 = U - cI w - cdI dw - cd2I d2w - (R/Psi) z - (L/Psi) dz     [V]   no I_A
 *        (I eliminated: Psi I = J dw + M_F1 w + z from (B), put into (A))
 * with z = M_L + M_F0 sgn(w) (the torques that are not a measured signal),
 * cI = Psi + M_F1 R / Psi, cdI = (J R + M_F1 L) / Psi, cd2I = L J / Psi
 * (r3 and r4 share them). r1 and r4 are in volts, r2 and r3 in newton
 * metres (A-equivalent: divide by Psi).
 *
 * Derivatives. Every signal goes through its own third-order state-variable
 * filter (model/canfdi_svf.h) with the same corner wc, so that every filtered
 * signal obeys the same linear equations (Isermann: same filter on every
 * signal of one equation); third order because r3 and r4 need d2I and d2w.
 * z is filtered too (a known input is a signal of the equation as well).
 *
 * Sampling alignment (why the residuals stay small in transients). The
 * measured U_A is the voltage the bridge held over the 1 ms interval that
 * ends with the sample (zero-order hold), while I_A and w are point samples.
 * The interval form of (A) is exact: U_k = R mean(I) + L (I_k - I_k-1)/T
 * + Psi mean(w). The module therefore feeds the SVFs with (I_k + I_k-1)/2
 * and (w_k + w_k-1)/2 (trapezoidal interval means) and U_k as it is. With
 * the host_sim plant and its reference speed controller (setpoint steps of
 * +-20 rad/s) the peak fault-free r1 is 0.04 V with the interval means and
 * 0.43 V with point samples, r3 0.02 N m against 0.28 N m
 * (double-precision exploration at wc 100 rad/s).
 * The caller passes the measured U_A; for a drive without a voltage sensor,
 * pass the command that was applied over the interval.
 *
 * The load M_L. The firmware has no torque sensor, so M_L is an input:
 * `load_Nm_q16` is the load the application knows (a measured torque, the
 * nominal load of the operating point, or 0 for an unloaded drive). The
 * deviation of the true load from it is the fourth "signal" of the
 * structure: it moves r2, r3, r4 and not r1 — the pattern (0 1 1 1), the
 * same as friction up, which is a load-like torque. Optionally
 * (cfg.load_tau_s > 0) the load is treated as a slowly varying unknown: each
 * of r2, r3, r4 subtracts its own mean tracked with time constant load_tau
 * (only while valid), which keeps each residual's decoupling exactly (no
 * residual borrows another's signals) but makes r2..r4 blind to deviations
 * slower than load_tau; r1 is unaffected. Default: off (input only).
 * Late load (cfg.load_hold_steps). A known load that reaches the ECU over
 * a bus arrives up to one frame cycle (plus the step alignment) after the
 * plant's torque changed: for that lag d the true and the known load
 * differ by the whole step dM, a pulse of width d that the SVF spreads
 * into r2..r4 (r1 has no M_L) for as long as its impulse response lasts.
 * The difference of the filtered true and known load after the known one
 * changed is dM (S(t - t_true) - S(t - t_known)) <= dM (1 - S(t - t_known)),
 * S the step response of the order-3 binomial SVF, whose tail is
 * e^-x (1 + x + x^2/2), x = wc t: below 1e-3 from x = 11.23 on. So from
 * the step in which the known load changes, r2..r4 are not valid for
 * load_hold_steps (the caller's figure for its link: the lag is already
 * over when the change is seen, what remains is the filter's tail,
 * ceil(11.23 / (wc T)) = 113 steps at wc 100 rad/s, T 1 ms); their load
 * means (load_tau) are not updated meanwhile. The first sample after
 * init/reset only records the load. Cost: one compare per step.
 *
 * Fault-symptom structure (theory; steady state, one fault at a time, small
 * deviations; "+"/"-" is the sign of the residual change for the fault in
 * its named direction, 0 = decoupled by construction, ~0 = coupled only
 * through the tiny M_F1 term, below noise for this motor):
 *
 *   fault (direction)        r1 [V]        r2 [N m]        r3 [N m]       r4 [V]
 *   U_A sensor offset +dU    +dU           0               ~0 (-M_F1/Psi dU) +dU
 *   I_A sensor offset +dI    -R dI         +Psi dI         +cI dI         0
 *   w sensor offset +dw      -Psi dw       ~0 (-M_F1 dw)   0              -cI dw
 *   w sensor gain +g         -Psi g w      ~0              0              -cI g w
 *   M_L above input +dM      0             +dM             +dM            +(R/Psi) dM
 *   R_A up +dR               +dR I         0               ~0             +dR I
 *   Psi down (-d Psi)        -d Psi w      +d Psi I        +d Psi I       +d(R I - Psi w) (<0)
 *   friction up (x(1+f))     0             +f(M_F0+M_F1 w) +f(M_F0+M_F1 w) +(R/Psi) f(..)
 *   bridge dead (U_A = 0)    measured U_A is 0: the equations hold, no symptom
 *
 * Reading it: the ideal structure of the four residuals (each blind to one
 * signal) holds exactly; quantitatively, for this motor U_A offsets, w
 * offsets and R_A faults share the strong pattern (+,0,0,+)/(-,0,0,-) in
 * steady state because the mechanics see U_A and w only through the viscous
 * term M_F1 (0.36e-3 N m s). They differ in how the symptom scales (dR I
 * follows the current, dU does not, Psi dw follows nothing) and in the
 * transient (r3 sees d(dU)/dt at the onset); parameter estimation separates
 * them. I_A offsets (+ + + 0), load/friction (0 + + +) and flux (- + + -)
 * have distinct patterns. Measured deviations: see the table below.
 *
 * Adaptive armature resistance (separation of time scales). R_A rises by
 * ~11 % as the winding warms (1.35 -> 1.5 Ohm over 1-2 h, thermal time
 * constant ~43 min); a fixed R_A would drift r1 and r4 by dR I = 0.6 V at
 * 4 A, far outside the band. With ra_track set, R_A is re-estimated from r1
 * itself: over blocks of N = ra_block_steps samples the least-squares
 * residual resistance dR = sum(r1 I) / sum(I^2) is computed, and R_A moves
 * by the fraction N T / ra_tau of it (a first-order tracker with time
 * constant ra_tau, default 60 s: ~40 x faster than the thermal time
 * constant, so the lag error is ~rate * ra_tau = 3.5 mOhm, 14 mV at 4 A,
 * with the initial warm-up rate of ~0.06 mOhm/s) and by at most
 * ra_rate_max * N T (default 0.5 mOhm/s, ~9 x the fastest thermal rise).
 * A block is used only if sum(I^2) >= N ra_i_min^2 (R_A is unobservable at
 * low current) and the block mean of r1 / threshold stayed within
 * +-ra_gate (default 1: inside the band on average; single noise peaks do
 * not stop the tracker): a fault moves r1 abruptly beyond the gate and
 * freezes the tracker, so an abrupt +10 % R_A (0.6 V at 4 A) stays visible
 * in r1 and r4 for as long as it lasts, while the warm-up (a few mV per minute) is
 * absorbed. R_A is bounded to the plausible thermal range [ra_min, ra_max];
 * ra_at_limit reports an estimate pinned at a bound (an incipient R_A fault
 * slower than the tracker is absorbed like warm-up until it leaves that
 * range: the parameter estimator, canfdi_est_dcm, sees it as R_A out of
 * range). After init
 * and reset the first ra_learn_blocks accepted blocks learn R_A fast
 * (a quarter of the error per block, no gate, no rate bound, still inside
 * the range) because no history separates warm-up from fault at start; r1
 * and r4 are flagged not valid meanwhile. canfdi_parity_dcm_set_ra() sets
 * R_A from non-volatile memory (a warm restart). r3 and r4 use the same
 * estimate (their R_A terms are those of r1 seen through (B)).
 *
 * Validity. out.valid bit j says residual j+1 may be evaluated: not for
 * settle_steps after init/reset (SVF start-up); r1/r4 not while R_A is
 * being learnt; r2..r4 only while |w_f| >= w_band and again settle_steps
 * after entering that region (near standstill the Coulomb friction is not
 * +-M_F0 but whatever holds the rotor, and the SVF remembers it for ~5/wc).
 * Inside +-w_band sgn(w) is replaced by w / w_band. sgn uses the measured w,
 * the one place where r3 touches w: only its sign, only near standstill.
 * out.exceed bit j = valid and |r| > threshold.
 *
 * Thresholds (Isermann ch. 7.3 / 10: adaptive thresholds from the
 * propagation of model uncertainty). Each residual's band is
 *   threshold_j = min(band[j].max, adapt_j + sum_p |dr_j/dp| dp)
 * adapt_j: one canfdi_adapt_t per residual (detect/canfdi_adapt.h), base +
 * gain * filtered |dU_f/dt| (gain 0 by default: base = the noise band).
 * The sum is the first-order bound of the residual a parameter error dp
 * produces, evaluated every step on the same filtered signals as the
 * residual itself (so it is exact to first order at every instant and
 * needs no extra filter). The partial derivatives of the four equations:
 *   r1  dr/dR = -I                      dr/dL = -dI
 *   r2  dr/dJ = -dw
 *   r3  dr/dR = (M_F1 I + J dI) / Psi   dr/dL = (M_F1 dI + J d2I) / Psi
 *       dr/dJ = (R dI + L d2I - dU) / Psi
 *   r4  dr/dR = -(M_F1 w + J dw + z) / Psi
 *       dr/dL = -(M_F1 dw + J d2w + dz) / Psi
 *       dr/dJ = -(R dw + L d2w) / Psi
 * (r3's R and J terms dominate in current swings: (J dR / Psi) dI is
 * 0.1 N m, 5 base bands, for dR = 8 mOhm and dI = 2000 A/s.) The stated uncertainties (cfg.unc_*, defaults):
 *   dR = 10 mOhm: the accuracy of the tracked R_A. The tracker is a
 *     first-order follower with time constant ra_tau (60 s), so it lags a
 *     winding heating at rate rho by rho ra_tau. Cold, the heating rate is
 *     rho = alpha R_20 I_rms^2 R / C_th (copper alpha 0.0039/K, R_20 1.35,
 *     C_th 2000 J/K of the plant): 0.057 mOhm/s at the nominal 4 A, a lag
 *     of 3.4 mOhm. Bursts of excitation raise I_rms; the bound allows
 *     I_rms = 6.9 A (1.7 x nominal, 3 x the heat): rho = 0.17 mOhm/s,
 *     dR = rho ra_tau = 10 mOhm (0.7 % of R_A). (A faster tracker would
 *     shrink dR but absorb incipient R_A faults sooner. Measured tracker
 *     error after learning in the 10 h bench: 8.6 mOhm.)
 *   dL = 2 %, dJ = 2 %: the identification class of the parameters in use
 *     (the acceptance of canfdi_est_dcm, docs/requirements.md: within 2 %,
 *     standard deviation below 2 %); datasheet tolerances (+-10..20 %) would widen the
 *     transient bands by that factor: configure them so when L and J are
 *     not identified on the drive.
 *   Psi is not in the sum on purpose: its error acts in steady state
 *     (dPsi w), where a band wide enough to hold it (0.66 V at 2 % and
 *     100 rad/s) would hide an R_A +10 % fault (0.6 V at 4 A); the
 *     configured Psi must therefore be calibrated to better than
 *     base / w_max (0.08 V / 110 rad/s: 0.2 %), which the estimator reaches
 *     (sigma 0.03 % in bench_longrun). M_F1 and M_F0 errors are absorbed by
 *     the base (M_F1 w <= 0.04 N m is the friction fault's own signature).
 * Steady state (all derivatives 0) only the dR terms remain: r1 base +
 * dR |I| (+0.04 V at 4 A: 0.12 V), r4 base + dR |z| / Psi (+0.04 V), r3
 * base + dR M_F1 |I| / Psi (+0.04 mN m), r2 base. A 2 %-of-full-scale
 * sensor offset (U_A 1.2 V, I_A 0.6 A -> r1 0.9 V, w 8 rad/s -> r1 2.6 V)
 * stays 7 x or more outside. In transients the bands widen with |dI|,
 * |d2I|, |dw|, |dU|: faults of the size of the base (friction +20 %,
 * 0.03 N m in r2/r3) are then inside the band during strong excitation and
 * seen only in the quieter phases (bench_symptoms, PRBS excitation:
 * friction +20 % is outside r2's band 26 % of the time; its deviation in
 * sigma, the symptom, does not depend on the band). out.thr_q16 is the total band;
 * out.rn_q16 = r / threshold (1.0 = threshold).
 *
 * Scaling and overflow. Inputs Q16.16 in V, A, rad/s, N m. Parameters Q8.24
 * (0..128, resolution 6e-8). SVF inputs are Q16.16 scaled down by a shift:
 * I_A by 2^CANFDI_PARITY_DCM_I_PRESCALE (outputs Q.11: range of d2I
 * +-1.0e6 A/s^2, resolution 0.5 mA) and w by 2^CANFDI_PARITY_DCM_W_PRESCALE
 * (Q.9: d2w +-4.2e6 rad/s^3, resolution 2 mrad/s), because the second
 * derivative of a current step through a 100 rad/s filter reaches
 * ~2e5 A/s^2 and d2w = Psi dI / J ~1e6 rad/s^3: far outside Q16.16.
 * Coefficients are stored as m * 2^-f with |m| in [2^29, 2^31) (30
 * significant bits whatever the size: cd2I = 4e-5 keeps 1e-9 relative
 * precision; computed at init and after an R_A update by an integer long
 * division). Each term m * x is an exact 64-bit product aligned by a
 * round-half-up shift to a Q23.40 int64 accumulator; sums saturate; the
 * residual is rounded half up to Q16.16 and saturates (counted in
 * diag.res_saturations). The R_A sums are Q32 in int64 (|r1| clamped to
 * 64 V, |I| < 2^15 A, N <= 1000: < 2^53). The load means are Q32.
 * Rounding error against an exact (double) evaluation of the same
 * equations on the same Q16.16 inputs — the analysis behind the tolerance
 * of the reference comparison (tests/ref/ref_parity.cpp). Per term, two
 * roundings matter: (a) the SVF input of I and w is rounded to its
 * prescaled LSB (+-2^-12 A, +-2^-10 rad/s; z +-2^-16 N m), an error that
 * passes the filter with the L1 norm of its impulse response: 1 for y,
 * 0.54 wc = 54/s for dy, 0.62 wc^2 = 6200/s^2 for d2y (binomial, wc = 100);
 * (b) each SVF output is rounded to the same LSB (+-half of it; U +-2^-17).
 * Coefficients keep 30 bits (2^-30 relative), the Q40 accumulator rounds at
 * 2^-41, the result at 2^-17: together < 1 LSB. Summed with Isermann's
 * parameters, the worst case (all errors aligned) is r1 98, r2 19, r3 24,
 * r4 98 LSB of Q16.16 (r1: R (2^-12 + 2^-12) + L (2^-12 + 54 2^-12)
 * + Psi (2^-10 + 2^-10) + ...; r4 alike with w; r2/r3 carry w and I
 * through small coefficients only). Tolerance: r1, r4 100 LSB (1.5 mV),
 * r2, r3 24 LSB (0.4 mN m), 1/8 of the fault-free noise sigma or less;
 * measured maxima over 410 000 samples: 44.5, 6.2, 6.7, 24.0 LSB. The R_A
 * estimates: a block's least-squares dR differs by at most
 * max|dr1| / I_min (1.5 mOhm at 1 A) if every rounding error had one sign;
 * they are zero-mean, average over a block and over ra_tau / (N T) = 600
 * blocks, so the comparison uses 0.1 mOhm (0.4 mV at 4 A); measured
 * 6.7e-6 Ohm. The SVFs themselves (Q31 gains, Q31.32 states) add < 1e-8
 * relative. The uncertainty bands: each sensitivity dr/dp is formed like a
 * residual (same terms, Q40 accumulator), its absolute value rounded half
 * up to Q16.16 and saturated, then multiplied by dp (Q8.24, rounded half
 * up, saturated); the error is that of the residual terms scaled by
 * dp / p (<= 5 LSB) plus four roundings: tolerance 8 LSB, measured 1.5.
 *
 * Cost per canfdi_parity_dcm_step: 4 SVF steps of order 3, 4
 * canfdi_adapt_step, 22 coefficient terms for the residuals and 20 for the
 * uncertainty bands (a 32x32->64 multiply, a run-time 64-bit shift and a
 * saturating add each) plus 11 rounded 32x32 multiplies by the dp, 4
 * canfdi_div_s32_qn (32/32 path while |r| < 1 unit, else 64/64), and every
 * ra_block_steps-th step the R_A update (4 ratios, each one 64/32
 * division, canfdi_div_u62_q30_rnd). `make bench-pil-profile` measures it in the application,
 * per module and function (build/bench/pil_profile.json; the SVF steps,
 * the thresholds and the 64-bit helpers are counted under canfdi_svf,
 * canfdi_adapt, canfdi_fixp, canfdi_intrin and libgcc there): in the
 * dcm_ia_offset scenario this module's own code took 1 900 instructions
 * per step on average on Cortex-M4 (the coefficient terms inline there)
 * and 4 300 on Cortex-M0 (one copy of them, a call each).
 * Most of it is the coefficient terms' 64-bit arithmetic, which ARMv6-M
 * lacks. Code (`make footprint`, the application image): 8.6 kB (M4),
 * 7.0 kB (M0) plus canfdi_svf, adapt and fixp. Memory: sizeof(canfdi_parity_dcm_t) = 792
 * bytes on a 32-bit target (4 SVFs 320, 4 thresholds 160, coefficients,
 * state), caller-owned; the configuration (168 bytes) is caller-owned and
 * must outlive the instance. No heap, no globals, no floating point;
 * reentrant per instance.
 *
 * Measured with host_sim (tests/unit/test_parity_dcm.c: Isermann's motor,
 * thermal model frozen at the cold 1.35 Ohm, reference speed controller at
 * 100 + 10 sin(pi t) rad/s, load 1.2 N m, ~4 A; sensor noise sigma U 0.05 V,
 * I 0.02 A, w 0.2 rad/s on top of the 12-bit ADCs; default cfg):
 *   fault-free sigma   r1 12.2 mV   r2 3.3 mN m   r3 2.8 mN m   r4 18.4 mV
 *   (max |r| / band 0.34 / 0.60 / 0.54 / 0.46 over 17 s, 0.33 / 0.58 / 0.51
 *   / 0.44 with +-20 rad/s setpoint steps every second)
 *   post-fault mean deviation in units of that sigma:
 *                          r1      r2      r3      r4
 *   U_A offset +1.2 V    +103      0      -0.4    +66
 *   I_A offset +0.6 A     -66    +60     +66       0
 *   w offset +8 rad/s    -225     -0.8     0     -148
 *   w gain +2 %           -51      0       0      -34
 *   R_A +10 %             +47      0      -0.3    +31
 *   Psi -10 %            -280    +48     +58     -152
 *   friction +20 %          0     +9     +10      +7 (0.12 V: inside r4's
 *                                                     steady band 0.16 V)
 *   friction +50 %          0    +21     +26     +16
 *   load 0.2 N m above     0.3   +60     +71     +45 (in units of the
 *                                                     fault-free sigma)
 * Adaptive R_A (warm-up with the thermal capacitance / 10 and the tracker
 * time scales / 10, see the test): R_A 1.35 -> 1.52 Ohm with a tracking
 * error <= 3.7 mOhm, every residual inside its band (max 0.74); the same
 * warm-up with R_A fixed drives r1 to 6.1 and r4 to 4.8 bands (the dR
 * term widens the band by 10 mOhm |I|, not by the 167 mOhm error); an abrupt
 * +10 % R_A afterwards keeps r1 and r4 out of band for the 40 s observed
 * (the tracker froze at the warm value).
 */
#ifndef CANFDI_PARITY_DCM_H
#define CANFDI_PARITY_DCM_H

#include "core/canfdi_common.h"
#include "core/canfdi_fixp.h"
#include "detect/canfdi_adapt.h"
#include "model/canfdi_svf.h"

#define CANFDI_PARITY_DCM_N_RES 4U
/* Residual indices (bit j of valid/exceed is residual j). */
#define CANFDI_PARITY_DCM_R1 0U /* armature, no M_L, V */
#define CANFDI_PARITY_DCM_R2 1U /* mechanics, no U_A, N m */
#define CANFDI_PARITY_DCM_R3 2U /* no w, N m */
#define CANFDI_PARITY_DCM_R4 3U /* no I_A, V */
/* SVF input scaling of I_A and w (see Scaling and overflow). */
#define CANFDI_PARITY_DCM_I_PRESCALE 5U
#define CANFDI_PARITY_DCM_W_PRESCALE 7U
/* Largest ra_tau_s / load_tau_s: one day. */
#define CANFDI_PARITY_DCM_TAU_MAX_S 86400U

/* Coefficient m * 2^-f (|m| in [2^29, 2^31) unless exact/zero). Internal. */
typedef struct {
  int32_t m;
  uint8_t f;
} canfdi_parity_dcm_coef_t;

/* Indices into canfdi_parity_dcm_t.k (internal). */
enum {
  CANFDI_PDCM_K_R = 0, /* R_A estimate */
  CANFDI_PDCM_K_L,     /* L_A */
  CANFDI_PDCM_K_PSI,   /* Psi */
  CANFDI_PDCM_K_J,     /* J */
  CANFDI_PDCM_K_F1,    /* M_F1 */
  CANFDI_PDCM_K_CI,    /* Psi + M_F1 R / Psi */
  CANFDI_PDCM_K_CDI,   /* (J R + M_F1 L) / Psi */
  CANFDI_PDCM_K_CD2I,  /* L J / Psi */
  CANFDI_PDCM_K_JP,    /* J / Psi */
  CANFDI_PDCM_K_FP,    /* M_F1 / Psi */
  CANFDI_PDCM_K_RP,    /* R / Psi */
  CANFDI_PDCM_K_LP,    /* L / Psi */
  CANFDI_PDCM_K_INVB,  /* 1 / w_band */
  CANFDI_PDCM_K_IP,    /* 1 / Psi */
  CANFDI_PDCM_K_ONE,   /* 1 */
  CANFDI_PDCM_N_K
};

/*
 * Configuration, caller-owned; the instance keeps a pointer to it (and its
 * thresholds point into band[]), so it must outlive the instance.
 * Domain (canfdi_parity_dcm_cfg_check, else -CANFDI_EINVAL):
 *   R_A 0.001..100 Ohm, L_A 1e-6..1 H, Psi 0.01..10 V s, J 1e-6..10 kg m^2,
 *   M_F1 0..1 N m s, M_F0 0..10 N m; wc 20..1000 rad/s; w_band > 0 and
 *   <= 100 rad/s; each band[] valid for canfdi_adapt with base > 0;
 *   with ra_track: block 10..1000 steps, ra_tau_s >= block duration and
 *   <= CANFDI_PARITY_DCM_TAU_MAX_S, ra_i_min 0..30 A (> 0), ra_gate
 *   0..32 (> 0), ra_rate_max 0..1 Ohm/s, ra_min <= R_A <= ra_max;
 *   load_tau_s 0 (off) or 10 steps .. CANFDI_PARITY_DCM_TAU_MAX_S.
 */
typedef struct {
  int32_t ra_ohm_q24;       /* R_A, initial value of the estimate */
  int32_t la_H_q24;         /* L_A */
  int32_t psi_Vs_q24;       /* Psi (= torque constant, N m/A) */
  int32_t j_kgm2_q24;       /* J */
  int32_t mf1_Nms_q24;      /* viscous friction */
  int32_t mf0_Nm_q24;       /* Coulomb friction */
  int32_t omega_c_rad_s;    /* SVF corner (order 3) */
  int32_t w_band_rad_s_q16; /* sgn regularisation and r2..r4 validity */
  uint16_t settle_steps;    /* steps before a residual is valid (SVF start) */
  canfdi_adapt_cfg_t band[CANFDI_PARITY_DCM_N_RES]; /* thresholds, residual units Q16.16 */
  uint8_t ra_track;         /* 1: adaptive R_A (see above), 0: fixed */
  uint16_t ra_block_steps;  /* N, samples per least-squares block */
  uint16_t ra_learn_blocks; /* fast-learning blocks after init/reset */
  uint32_t ra_tau_s;        /* tracking time constant */
  int32_t ra_i_min_A_q16;   /* RMS current a block needs */
  int32_t ra_gate_q16;      /* |block mean of r1 / threshold| above which it is discarded */
  int32_t ra_rate_max_ohm_s_q24; /* bound on |dR_A/dt| of the tracker */
  int32_t ra_min_ohm_q24;   /* plausible range of R_A */
  int32_t ra_max_ohm_q24;
  uint32_t load_tau_s;      /* 0: M_L is the input; else r2..r4 follow their mean */
  uint16_t load_hold_steps; /* 0: off; else r2..r4 are not valid for this many
                             * steps after a change of the known load (see
                             * "Late load") */
  /* Stated parameter uncertainties of the model in use (absolute, >= 0,
   * at most the parameter itself); they widen each band by
   * sum |dr/dp| dp on the current filtered signals (see Thresholds). */
  int32_t unc_ra_ohm_q24;   /* dR: accuracy of the R_A in use (tracker lag) */
  int32_t unc_la_H_q24;     /* dL */
  int32_t unc_j_kgm2_q24;   /* dJ */
} canfdi_parity_dcm_cfg_t;

/* One sample, Q16.16 SI. u: measured U_A (the voltage held over the
 * interval that ends now); i: I_A; w: speed; load: the known M_L. */
typedef struct {
  int32_t u_V_q16;
  int32_t i_A_q16;
  int32_t w_rad_s_q16;
  int32_t load_Nm_q16;
} canfdi_parity_dcm_in_t;

/* Outputs of the last step (also readable with canfdi_parity_dcm_out). */
typedef struct {
  int32_t r_q16[CANFDI_PARITY_DCM_N_RES];   /* r1 V, r2 N m, r3 N m, r4 V */
  int32_t rn_q16[CANFDI_PARITY_DCM_N_RES];  /* r / threshold, 1.0 = threshold */
  int32_t thr_q16[CANFDI_PARITY_DCM_N_RES]; /* thresholds, residual units */
  uint8_t valid;           /* bit j: residual j may be evaluated */
  uint8_t exceed;          /* bit j: valid and |r| > threshold */
  int32_t ra_hat_ohm_q24;  /* the R_A in use */
  bool ra_at_limit;        /* the last R_A update hit ra_min/ra_max */
} canfdi_parity_dcm_out_t;

/* Diagnostics counters: monotone, saturating at UINT32_MAX
 * (core/canfdi_count.h); init clears them, nothing else does. No decision
 * of the firmware depends on them. */
typedef struct {
  uint32_t steps;
  uint32_t resets;             /* canfdi_parity_dcm_reset calls (init not counted) */
  uint32_t res_saturations;    /* residuals clipped to the Q16.16 range */
  uint32_t ra_updates;         /* accepted R_A blocks */
  uint32_t ra_blocks_rejected; /* low current, gate, or not valid */
  uint32_t ra_limit_hits;      /* R_A step hit the rate bound or the range */
  uint32_t load_holds;         /* known-load changes that started a hold */
} canfdi_parity_dcm_diag_t;

/* Instance, caller-owned; read it through the functions below. */
typedef struct {
  const canfdi_parity_dcm_cfg_t *cfg;
  canfdi_svf_t svf_u;
  canfdi_svf_t svf_i; /* I / 2^I_PRESCALE */
  canfdi_svf_t svf_w; /* w / 2^W_PRESCALE */
  canfdi_svf_t svf_z;
  canfdi_adapt_t thr[CANFDI_PARITY_DCM_N_RES];
  canfdi_parity_dcm_coef_t k[CANFDI_PDCM_N_K];
  int32_t ra_hat_ohm_q24;
  canfdi_q31_t ra_gain_q31;   /* N T / ra_tau */
  int32_t ra_step_max_q24;    /* ra_rate_max N T */
  canfdi_q31_t load_alpha_q31; /* T / load_tau */
  int64_t blk_ri;             /* sum r1 I, Q32 */
  int64_t blk_ii;             /* sum I^2, Q32 */
  int64_t blk_rn;             /* sum r1 / threshold, Q16 */
  int64_t bias_q32[3];        /* load means of r2..r4 */
  int32_t i_prev_q16;
  int32_t w_prev_q16;
  uint16_t blk_n;             /* samples in the R_A block, 0 .. ra_block_steps - 1 */
  uint16_t settle;            /* steps left before the residuals are valid,
                               * settle_steps .. 0 */
  uint16_t w_ok;              /* consecutive steps with |w_f| >= w_band,
                               * saturating at UINT16_MAX */
  uint16_t ra_learn_left;     /* fast-learning blocks left, ra_learn_blocks .. 0 */
  uint16_t load_hold;         /* steps left of the late-load hold */
  int32_t load_prev_q16;      /* known load of the last step */
  bool blk_invalid;
  bool primed;
  canfdi_parity_dcm_out_t out;
  canfdi_parity_dcm_diag_t diag;
} canfdi_parity_dcm_t;

/* Isermann's motor (R_A 1.52 warm, L_A 6.82 mH, Psi 0.33, J 1.92e-3,
 * M_F1 0.36e-3, M_F0 0.11), wc 100 rad/s, w_band 2 rad/s, settle 60 steps,
 * base bands r1 0.08 V, r2 0.02 N m, r3 0.02 N m, r4 0.12 V (6.5, 6, 7,
 * 6.5 sigma of the noise model above), adaptive R_A (block 100, tau 60 s,
 * learn 20 blocks, I_min 1 A, gate 1.0, rate 0.5 mOhm/s, range
 * 1.0..2.0 Ohm), load input only, uncertainty bands dR 10 mOhm, dL 2 %,
 * dJ 2 % (see Thresholds). A starting point: derive the base bands from a
 * fault-free run of the real drive at rest-to-steady operating points and
 * state dR, dL, dJ from how R_A, L_A, J were obtained. Cannot fail (NULL is
 * ignored). */
void canfdi_parity_dcm_default_cfg(canfdi_parity_dcm_cfg_t *cfg);

/* CANFDI_OK or -CANFDI_EINVAL (see the domain above). O(1). */
int32_t canfdi_parity_dcm_cfg_check(const canfdi_parity_dcm_cfg_t *cfg);

/* Validates cfg, binds p to it, precomputes the coefficients, R_A = cfg
 * value, resets. CANFDI_OK or -CANFDI_EINVAL (NULL or invalid cfg; then p
 * is left unbound and step/reset/set_ra refuse it). Cost: ~13 long divisions + 8 SVF/adapt
 * inits, < 30 000 instructions on M0+; not for the 1 ms path. */
int32_t canfdi_parity_dcm_init(canfdi_parity_dcm_t *p, const canfdi_parity_dcm_cfg_t *cfg);

/* Restart: the next step re-primes the filters on its sample, settle and
 * R_A learning start again, load means and the R_A block are cleared,
 * thresholds reset; the R_A estimate and the counters are kept. Use after
 * a gap in the data (lost frames) or a drive restart. No-op on NULL. */
void canfdi_parity_dcm_reset(canfdi_parity_dcm_t *p);

/* The same restart without starting R_A's fast learning again once it has
 * finished: after a short interruption mid-drive the estimate kept is the
 * history that separates warm-up from a fault, and re-learning without the
 * gate would absorb a fault present across it into R_A (an I_A offset's
 * -R_A dI in r1, leaving the pattern of friction). No-op on NULL. */
void canfdi_parity_dcm_restart(canfdi_parity_dcm_t *p);

/* Sets the R_A estimate (e.g. from non-volatile memory), clamped to
 * [ra_min, ra_max] when tracking. CANFDI_OK or -CANFDI_EINVAL (NULL,
 * uninitialised, R outside 0.001..100 Ohm). Cost: 3 long divisions. */
int32_t canfdi_parity_dcm_set_ra(canfdi_parity_dcm_t *p, int32_t ra_ohm_q24);

/* One 1 ms step. Returns the outputs (pointer into p), or NULL for a NULL
 * or uninitialised p or NULL in. Every input value is accepted: extreme
 * values saturate (counted), never undefined behaviour. Cost: see above. */
const canfdi_parity_dcm_out_t *canfdi_parity_dcm_step(canfdi_parity_dcm_t *p,
                                                      const canfdi_parity_dcm_in_t *in);

/* The outputs of the last step (NULL for NULL/uninitialised). O(1). */
const canfdi_parity_dcm_out_t *canfdi_parity_dcm_out(const canfdi_parity_dcm_t *p);

/* The counters (NULL for NULL). O(1). */
const canfdi_parity_dcm_diag_t *canfdi_parity_dcm_diag(const canfdi_parity_dcm_t *p);

/* T / load_tau in Q31, the weight with which r2..r4 follow their means (0
 * when load_tau_s is 0 or for NULL/uninitialised): a caller that compares
 * r1 with r2..r4 applies the same high-pass to r1. O(1). */
canfdi_q31_t canfdi_parity_dcm_load_alpha_q31(const canfdi_parity_dcm_t *p);

#endif /* CANFDI_PARITY_DCM_H */
