/*
 * canfdi_symptoms.h — the symptom vector: what the detection layer hands to
 * fault-symptom reasoning (canfdi_diagnosis) once per 1 ms step.
 *
 * The application fills it from the detection modules (parity residuals,
 * parameter estimators, range checks, voting, actuator plausibility) and
 * passes it to canfdi_diagnosis_step(). Keeping it a plain struct lets
 * diagnosis be tested on synthetic symptoms, without plants.
 *
 * Units: normalised residuals are residual / threshold in Q16.16 (65536 = on
 * the threshold, sign kept); parameter deviations are (estimate - nominal) /
 * nominal in Q16.16 (6554 ~ +10 %). A quantity whose valid bit is clear must
 * be ignored (not converged, excluded, or not computed in this mode).
 * Memory: 96 bytes on a 32-bit target. Cost: none (data only).
 */
#ifndef CANFDI_SYMPTOMS_H
#define CANFDI_SYMPTOMS_H

#include "core/canfdi_common.h"

/* DC-motor structured residuals (model/canfdi_parity_dcm.h). */
#define CANFDI_SYM_DCM_R1 0U /* armature equation, no M_L */
#define CANFDI_SYM_DCM_R2 1U /* mechanical equation, no U_A */
#define CANFDI_SYM_DCM_R3 2U /* without omega */
#define CANFDI_SYM_DCM_R4 3U /* without I_A */
/* Throttle residuals (model/canfdi_parity_thr.h). */
#define CANFDI_SYM_THR_CORR 0U /* TPS1 + TPS2 - const */
#define CANFDI_SYM_THR_ARM 1U  /* motor voltage equation */
#define CANFDI_SYM_THR_POS1 2U /* model angle - TPS1 angle */
#define CANFDI_SYM_THR_POS2 3U /* model angle - TPS2 angle */
#define CANFDI_SYM_N_RES 4U

/* Parameter deviations. */
#define CANFDI_SYM_DCM_P_RA 0U
#define CANFDI_SYM_DCM_P_PSI 1U
#define CANFDI_SYM_DCM_P_J 2U
#define CANFDI_SYM_DCM_P_FRICTION 3U /* lumped Coulomb friction + load */
#define CANFDI_SYM_THR_P_R 0U
#define CANFDI_SYM_THR_P_K 1U
#define CANFDI_SYM_THR_P_SPRING 2U  /* return-spring pretension (better determined than k_s) */
#define CANFDI_SYM_THR_P_FRICTION 3U
#define CANFDI_SYM_N_PAR 4U

/* Signal-based and manager symptoms, bits of canfdi_symptoms_t.flags.
 * Bits 0..CANFDI_DIAG_N_FLAGS-1 get the diagnosis' persistence (they name
 * faults through its hard rules); the others are read raw, per step. */
#define CANFDI_SYM_F_TPS1_LOW (1UL << 0)        /* TPS1 below its range */
#define CANFDI_SYM_F_TPS1_HIGH (1UL << 1)       /* TPS1 above its range */
#define CANFDI_SYM_F_TPS2_LOW (1UL << 2)
#define CANFDI_SYM_F_TPS2_HIGH (1UL << 3)
#define CANFDI_SYM_F_TPS1_OUTLIER (1UL << 4)    /* isolated by the 2oo3 vote */
#define CANFDI_SYM_F_TPS2_OUTLIER (1UL << 5)
#define CANFDI_SYM_F_BRIDGE_A_DEAD (1UL << 6)   /* actuator manager plausibility */
#define CANFDI_SYM_F_BRIDGE_B_DEAD (1UL << 7)
#define CANFDI_SYM_F_THR_NOT_FOLLOWING (1UL << 8) /* position does not follow the command */
#define CANFDI_SYM_F_THR_NO_CURRENT (1UL << 9)  /* voltage applied, no motor current */
#define CANFDI_SYM_F_DCM_W_JUMP (1UL << 10)   /* the measured speed stepped by more
                                               * than the drive's torque explains */
#define CANFDI_SYM_F_TPS1_INVALID (1UL << 11)   /* TPS1 input INVALID this step (never
                                                 * received or lost): its range test
                                                 * cannot run */
#define CANFDI_SYM_F_TPS2_INVALID (1UL << 12)
#define CANFDI_SYM_F_DCM_UA_CMD_VALID (1UL << 13) /* dcm_ua_cmd_rn_q16 valid */
#define CANFDI_SYM_F_DCM_RAX_VALID (1UL << 14)    /* dcm_rax_q16 valid */
#define CANFDI_SYM_F_DCM_FX_VALID (1UL << 15)     /* dcm_fx_q16 valid */
#define CANFDI_SYM_F_DCM_FX_CONTRA (1UL << 16)    /* r1 or r4 at or above the zero
                                                   * level with a sign no flux loss
                                                   * can give it (app/canfdi_app_sym.c) */
#define CANFDI_SYM_F_DCM_UNLEARNT (1UL << 17)     /* the armature and the mechanical
                                                   * estimates have not both converged
                                                   * since power-up, or a fault was
                                                   * learnt into them (canfdi_app.h):
                                                   * the DC motor's model rules are
                                                   * not tested (canfdi_diagnosis.h) */
#define CANFDI_SYM_F_DCM_REARM (1UL << 18)        /* the DC motor's inputs came back
                                                   * from an interruption (a timeout,
                                                   * a rejected frame or sample) or
                                                   * a sample of theirs was late less
                                                   * than the calibration's rearm_steps
                                                   * / late_hold_steps ago: its model
                                                   * rules are not tested
                                                   * (canfdi_app.h, feedback) */
#define CANFDI_SYM_F_THR_REARM (1UL << 19)        /* the same for the throttle */
#define CANFDI_SYM_F_DCM_GAIN_CONTRA (1UL << 20)  /* r1 is below a quarter of what the
                                                   * speed-sensor gain that J/Psi
                                                   * implies would give it
                                                   * (app/canfdi_app_sym.h) */

/* Estimator updates (dcm_upd / thr_upd): A = the equation of R_A and Psi
 * (DC motor: armature) or R and K (throttle: electrical); B = the equation
 * of J and M_c (DC motor: mechanical) or spring and friction (throttle:
 * mechanical and its fast test). */
#define CANFDI_SYM_UPD_A 0x01U
#define CANFDI_SYM_UPD_B 0x02U

typedef struct {
  int32_t dcm_rn_q16[CANFDI_SYM_N_RES];
  int32_t thr_rn_q16[CANFDI_SYM_N_RES];
  int32_t dcm_pdev_q16[CANFDI_SYM_N_PAR];
  int32_t thr_pdev_q16[CANFDI_SYM_N_PAR];
  uint8_t dcm_rn_valid;   /* bit i: dcm_rn_q16[i] valid */
  uint8_t thr_rn_valid;
  uint8_t dcm_pdev_valid; /* bit i: dcm_pdev_q16[i] valid (converged) */
  uint8_t thr_pdev_valid;
  uint32_t flags;         /* CANFDI_SYM_F_* */
  /* Operating-point signs a rule's entries may refer to (the sign a
   * residual takes for a fault follows the speed, the current, ...:
   * canfdi_diagnosis.h, refs): -1, +1, or 0 while the quantity is too small
   * to tell, when an entry that refers to it cannot be judged. */
  int8_t dcm_ref[2];      /* 'a': speed w, 'b': armature current I_A */
  int8_t thr_ref[2];      /* 'a': motor voltage command, 'b': motor current */
  /* Measured U_A minus the bridge command applied over the same interval,
   * filtered (the actuator monitor UAC, detect/canfdi_actmon.h), / its
   * threshold (Q16.16, 1.0 = threshold) or, while the armature residual r1
   * is beyond its band, / (|r1| / 2): 1.0 = the disagreement explains half
   * of r1. It is the one signal that tells a U_A sensor offset (it explains
   * all of r1) from a speed-sensor offset (none of it): in the armature
   * equation the two are the same term; scaled by r1, a zero means "not the
   * voltage sensor" as early as r1 sees either. Valid when
   * CANFDI_SYM_F_DCM_UA_CMD_VALID is set. */
  int32_t dcm_ua_cmd_rn_q16;
  /* The share of the armature residual r1 that the resistance estimate
   * explains, (R_A,est - R_A,model) I_A / r1_est, / 0.5 (Q16.16: 1.0 = half
   * of r1 explained), with r1_est the r1 the estimate was fit on: r1
   * weighted as the estimator weights its updates (its forgetting, from its
   * last covariance boost or reset on; app/canfdi_app_sym.c). An R_A change
   * moves the estimate by what r1 showed over that memory (share ~1, also
   * while R_A ramps and the estimate lags r1 itself by its memory); a
   * sensor offset or a flux change leaves R_A alone (share ~0): at one
   * operating point r1 alone cannot tell them apart. 0 once r1 has been
   * below the diagnosis' zero level for rax_quiet_steps (nothing to
   * explain, app/canfdi_app_sym.c). Valid (CANFDI_SYM_F_DCM_RAX_VALID) while the
   * armature estimator has converged and is fed. */
  int32_t dcm_rax_q16;
  /* Flux-loss prediction: per residual, the normalised value (1.0 = its
   * threshold) that the smallest flux loss which explains the residuals
   * now beyond their thresholds would give it. A flux loss dPsi moves
   * r1 = -dPsi w, r2 = r3 = +dPsi I_A, r4 = dPsi (R_A I_A - Psi w) / Psi
   * (canfdi_parity_dcm.h); r2..r4 follow their own mean over the load
   * tracking time (load_tau), so what they can show of a flux change is
   * the part of r1 that is newer than that mean. Where the prediction is
   * below a residual's zero level, that residual's zero does not tell a
   * developing flux loss from a fault that leaves the residual alone (at
   * 100 rad/s and 4 A a flux loss that puts r1 at 3 thresholds moves r2 by
   * 0.7 of its threshold: the pattern of a speed-sensor offset).
   * Valid (CANFDI_SYM_F_DCM_FX_VALID) while some residual is beyond its
   * threshold and every such residual has the sign a flux loss gives it
   * (else no flux loss explains them and every zero counts). */
  int32_t dcm_fx_q16[CANFDI_SYM_N_RES];
  /* Which estimator applied an update in this step (CANFDI_SYM_UPD_*): the
   * diagnosis counts them to know whether a parameter channel's zero
   * carries evidence from after a symptom appeared (canfdi_diagnosis.h,
   * freshness). */
  uint8_t dcm_upd;
  uint8_t thr_upd;
} canfdi_symptoms_t;

#endif /* CANFDI_SYMPTOMS_H */
