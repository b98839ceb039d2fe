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
 * A channel is valid only while its module ran on valid inputs this step
 * (residuals) or while its estimator is fed and has converged (parameters).
 *
 * Scaling and overflow: Q16.16; deviations by canfdi_div_s32_qn
 * (saturating), differences by saturating subtraction. Cost: 8 saturating
 * divisions and ~30 compares per step. Stateless; no heap.
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

typedef struct {
  const canfdi_parity_dcm_t *parity_dcm;
  const canfdi_parity_thr_t *parity_thr;
  bool dcm_in_ok;                  /* the DC-motor parity equations ran on valid inputs */
  bool thr_in_ok;                  /* the throttle parity equations ran on valid inputs */
  const canfdi_est_dcm_t *est_dcm;
  const canfdi_est_thr_t *est_thr;
  bool dcm_est_on;                 /* the DC-motor estimator was fed this step */
  bool thr_est_on;                 /* the throttle estimator was fed this step */
  int32_t load_offset_Nm_q16;      /* known load - the calibrated nominal load */
  uint8_t tps_range[2];            /* canfdi_limit symptom of TPS1, TPS2 */
  bool tps_invalid[2];             /* TPS1, TPS2 input INVALID this step */
  uint8_t vote_isolated_mask;      /* canfdi_vote_out_t.isolated_mask */
  uint32_t mgr_detected;           /* faults the manager detected itself (last step) */
  const canfdi_actmon_out_t *actmon;
} canfdi_app_sym_in_t;

/* Writes every field of *s. Cannot fail by contract (non-NULL arguments,
 * asserted). */
void canfdi_app_sym_build(const canfdi_app_sym_in_t *in, canfdi_symptoms_t *s);

#endif /* CANFDI_APP_SYM_H */
