/*
 * canfdi_app_sym.h — the symptom vector of one step (diag/canfdi_symptoms.h)
 * assembled from the detection stage's outputs: the parity residuals, the
 * estimators' parameter deviations, the TPS range checks, the vote, the
 * actuator monitors and what the actuator manager detected itself.
 *
 * Parameter deviations are (estimate - nominal) / nominal against the
 * estimators' own nominal values (their configuration), except the DC
 * motor's lumped M_c = M_F0 + M_L: its reference moves with the known load
 * (mc_nom holds the nominal load, so the reference is mc_nom + (known -
 * nominal) load) and the deviation stays normalised to mc_nom (the
 * thresholds are fractions of the nominal operating point's M_c, and the
 * reference may come near 0 at light load). The throttle's spring and
 * friction channels are the estimator's fast structured test (nominal
 * mechanical residual correlated with the spring torque and the friction
 * sign over ~0.3 s of motion in both directions, canfdi_est_thr.h).
 * The friction channel is direction-normalised: with s = sign(w),
 *   dev = (s (M_c - M_L,known) - M_F0,nom) / mc_nom,   M_F0,nom = mc_nom - load_nom,
 * i.e. the estimated Coulomb friction against its nominal value (the
 * lumped M_c = M_F0 sgn(w) + M_L flips its friction share with the
 * direction), normalised to the lumped nominal so that the thresholds keep
 * their meaning at the nominal operating point.
 * A channel is valid only while its module ran on valid inputs this step
 * (residuals) or while its estimator is fed and has converged
 * (parameters); the mechanical estimates (J, M_c and the J/Psi channel)
 * also not for cfg.mech_settle_steps after the speed's sign changed or
 * became unknown: the lumped M_c re-converges over the estimator's memory
 * after a reversal, and near standstill Coulomb friction is whatever holds
 * the rotor.
 *
 * Speed-step plausibility (CANFDI_SYM_F_DCM_W_JUMP). Between two valid
 * fresh samples of consecutive steps (a late frame's step repeats the last
 * sample, and the next one carries two steps' change) the shaft's speed
 * can only change by what the drive's torque
 * gives: dw = (Psi I_A - M_F0 sgn(w) - M_L) T / J with the nominal Psi,
 * J and Coulomb friction (the estimator's configuration) and the known
 * load. A measured step that differs from it by more than
 * cfg.w_jump_rad_s (noise of two speed samples, about 0.3 rad/s rms,
 * plus the model's error at the largest currents) is a step of the
 * sensor, not of the shaft: an abrupt speed-sensor offset or gain. The flag
 * is held for w_jump_hold_steps and then as long as the armature residual
 * r1 stays out of its band (a sensor step leaves r1 out of band; a single
 * noisy sample does not).
 *
 * Speed-gain magnitude (CANFDI_SYM_F_DCM_GAIN_CONTRA). A speed-sensor
 * gain g moves J/Psi by about -g (J -9.3 %, Psi -4.8 % at +5 %) and puts
 * r1 = -Psi g w into the armature equation: the J/Psi deviation x implies
 * |r1| = Psi |x| |w| (Psi nominal). The flag is set while that prediction
 * is at least 2 r1 thresholds and the measured |r1| is below a quarter of
 * it (both from converged, fed estimates and a valid r1): a J/Psi that
 * moved with no gain behind it, as the mechanical estimate's swing in a
 * test burst after a covariance boost (+2.1 % with r1 just at its
 * threshold during an R_A creep at 100 rad/s, where a gain of that size
 * gives 9 thresholds). The diagnosis then rules the gain rule out.
 *
 * Flux-loss prediction (canfdi_symptoms_t dcm_fx_q16, the physics there).
 * The smallest flux loss that explains the residuals beyond their
 * thresholds is dPsi = max_j |r_j| / s_j over those residuals, with the
 * sensitivities s1 = |w|, s2 = s3 = |I_A|, s4 = |R_A I_A - Psi w| / Psi
 * (R_A the parity equations' tracked value, Psi nominal); each residual's
 * prediction is dPsi s_k / threshold_k. r1 enters the prediction of
 * r2..r4 high-passed like them: minus its own mean over the load tracking
 * time (canfdi_parity_dcm_load_alpha_q31, tracked while r1 is valid), so a
 * drift slower than that time constant, which r2..r4 cannot show, does
 * not make their zeros count against a flux loss. r2..r4 enter the
 * prediction of r1 as they are (already high-passed: an underestimate of
 * dPsi, so a smaller prediction, on the cautious side). r4's prediction
 * adds the whole loss (|r1| / |w|, at least dPsi) times the change of its
 * signed sensitivity over the load tracking time ((e4 - mean e4) / Psi,
 * e4 = R_A I_A - Psi w): where the speed moves towards Psi w = R_A I_A,
 * r4 loses what its tracked mean had absorbed. A residual beyond
 * its threshold with the sign opposite to a flux loss's, or one whose
 * sensitivity is 0, leaves the prediction not valid (no flux loss
 * explains it). Scaling: dPsi in Q28 V s (saturating at 8 V s), products
 * and quotients by canfdi_mul_s32_qn / canfdi_div_s32_qn (saturating).
 *
 * Operating-point references (canfdi_symptoms_t dcm_ref, thr_ref: the signs
 * a rule's entries may follow, canfdi_diagnosis.h): the sign of the speed
 * and the armature current, of the throttle's voltage command and motor
 * current, each with a hysteresis: the sign counts from |x| >= on, is 0
 * below on / 2, and in between keeps the sign it had (0 stays 0).
 *
 * Scaling and overflow: Q16.16; deviations by canfdi_div_s32_qn
 * (saturating), differences by saturating subtraction. Cost: 2 saturating
 * divisions, 2 multiplications and ~60 compares per step, the six
 * parameter deviations' divisions only when an estimate moved, plus for the
 * flux-loss prediction up to 9 divisions and 8 multiplications while a
 * residual is beyond its threshold. Memory: 64 bytes of state and
 * configuration; no heap.
 */
#ifndef CANFDI_APP_SYM_H
#define CANFDI_APP_SYM_H

#include "core/canfdi_common.h"
#include "detect/canfdi_actmon.h"
#include "diag/canfdi_symptoms.h"
#include "model/canfdi_est_dcm.h"
#include "model/canfdi_est_thr.h"
#include "model/canfdi_parity_dcm.h"
#include "model/canfdi_parity_thr.h"

/* RAX is judged (valid) once |r1| is this many times its threshold: 3
 * bands of r1 (0.24 V + 30 mOhm |I|) are an R_A change of 6 % at 4 A, past
 * the spread of a fresh armature estimate; below that the estimate can
 * neither claim nor exclude R_A. */
#define CANFDI_APP_SYM_RAX_MIN_RN 3

/* The diagnosis' zero level (off, canfdi_diagnosis.h) as a share of a
 * residual's threshold (Q16.16, 0.8): below it a residual counts as a
 * zero; at or above it a residual is not a zero, so the flux-loss
 * prediction must account for it, and RAX has something to explain (a
 * residual in [off, on) keeps its symptom: the hysteresis). */
#define CANFDI_APP_SYM_ZERO_RN 52429

typedef struct {
  int32_t dcm_w_on_rad_s_q16;   /* > 0: |w| at which the speed's sign counts */
  int32_t dcm_i_on_A_q16;       /* > 0: |I_A| at which the current's sign counts */
  int32_t thr_u_on_V_q16;       /* > 0: |u| of the throttle command */
  int32_t thr_i_on_A_q16;       /* > 0: |i| of the throttle motor */
  uint16_t mech_settle_steps;   /* mechanical estimates invalid after a speed sign change */
  int32_t w_jump_rad_s_q16;     /* > 0: implausible speed step per sample */
  uint16_t w_jump_hold_steps;   /* the jump flag held at least this long */
  uint16_t rax_quiet_steps;     /* r1 below the zero level this long before
                                 * RAX reads "nothing to explain" (the
                                 * diagnosis' sym_off_steps: until then r1's
                                 * symptom may still be held) */
} canfdi_app_sym_cfg_t;

/* A quotient with its operands: the parameter deviations' divisions are
 * redone only when an operand changed (the estimates move on their
 * estimator's updates, a few steps in ten; the quotient is a function of
 * the two operands alone, so the kept one is the same bits). den == 0
 * never matches (no deviation divides by 0). */
typedef struct {
  int32_t num;
  int32_t den;
  int32_t q;
} canfdi_app_sym_quot_t;

/* The deviations kept that way: DC motor R_A, Psi, J, friction; throttle
 * R, k. */
#define CANFDI_APP_SYM_N_PDEV 6U

typedef struct {
  canfdi_app_sym_cfg_t cfg;
  int8_t dcm_ref[2];            /* the references of the last step */
  int8_t thr_ref[2];
  uint16_t mech_hold;           /* steps the mechanical estimates stay invalid */
  int32_t w_prev_q16;           /* last valid speed sample */
  bool w_prev_ok;               /* w_prev_q16 is the previous step's valid sample */
  uint16_t jump_hold;           /* steps the jump flag is held at least */
  bool jump;                    /* the jump flag */
  int64_t r1_mean_q32;          /* r1's mean over the parity's load_tau (V, Q32) */
  int64_t e4_mean_q32;          /* R_A I_A - Psi w, its mean over load_tau (V, Q32) */
  int64_t r1_est_q32;           /* r1 weighted as the armature estimate weights its
                                 * data (V, Q32; RAX) */
  int32_t r1_est_w_q16;         /* the sum of those weights, Q16.16 (<= 1 / forget) */
  uint16_t r1_quiet;            /* steps r1 has been below the zero level
                                 * (saturating at cfg.rax_quiet_steps) */
  canfdi_app_sym_quot_t pdev[CANFDI_APP_SYM_N_PDEV]; /* the parameter
                                 * deviations' last quotients */
} canfdi_app_sym_t;

typedef struct {
  const canfdi_parity_dcm_t *parity_dcm;
  const canfdi_parity_thr_t *parity_thr;
  bool dcm_in_ok;                  /* the DC-motor parity equations ran on valid inputs */
  bool dcm_fresh;                  /* ... and a new sample of them arrived */
  bool thr_in_ok;                  /* the throttle parity equations ran on valid inputs */
  const canfdi_est_dcm_t *est_dcm;
  const canfdi_est_thr_t *est_thr;
  bool dcm_est_on;                 /* the DC-motor estimator was fed this step */
  bool thr_est_on;                 /* the throttle estimator was fed this step */
  bool dcm_est_restart;            /* the DC-motor estimator's covariance was
                                    * boosted or reset this step */
  bool dcm_learnt;                 /* canfdi_app_gate_t.learnt of the DC motor,
                                    * and its learning check not failed */
  bool dcm_rearm;                  /* canfdi_app_gate_t.rearm > 0, DC motor ... */
  bool thr_rearm;                  /* ... and throttle */
  int32_t load_known_Nm_q16;       /* the load the models assume this step */
  int32_t load_nom_Nm_q16;         /* the calibrated nominal load (in mc_nom) */
  int32_t dcm_w_rad_s_q16;         /* measured speed */
  int32_t dcm_i_A_q16;             /* measured armature current */
  int32_t thr_u_V_q16;             /* throttle command over the last interval */
  int32_t thr_i_A_q16;             /* measured throttle motor current */
  uint8_t tps_range[2];            /* canfdi_limit symptom of TPS1, TPS2 */
  bool tps_invalid[2];             /* TPS1, TPS2 input INVALID this step */
  uint8_t vote_isolated_mask;      /* canfdi_vote_out_t.isolated_mask */
  uint32_t mgr_detected;           /* faults the manager detected itself (last step) */
  const canfdi_actmon_out_t *actmon;
} canfdi_app_sym_in_t;

/* Defaults: speed sign from 10 rad/s (r1 of a 10 % flux loss is 0.33 V
 * there, 3 bands), current from 0.8 A (r1 of a 20 % R_A rise is 0.24 V, 2
 * bands), throttle voltage from 1 V, current from 0.1 A; mechanical settle
 * 1000 steps (twice the mechanical estimator's memory). Cannot fail for
 * non-NULL. */
void canfdi_app_sym_default_cfg(canfdi_app_sym_cfg_t *cfg);

/* Validates cfg (all > 0) and starts with unknown references. Returns
 * CANFDI_OK or -CANFDI_EINVAL. */
int32_t canfdi_app_sym_init(canfdi_app_sym_t *m, const canfdi_app_sym_cfg_t *cfg);

/* Writes every field of *s. Cannot fail by contract (non-NULL arguments,
 * asserted). */
void canfdi_app_sym_build(canfdi_app_sym_t *m, const canfdi_app_sym_in_t *in, canfdi_symptoms_t *s);

#endif /* CANFDI_APP_SYM_H */
