/*
 * canfdi_app_test.h — the product's enabling conditions for the intrusive
 * test signals: one scheduler per plant (diag/canfdi_testsched.h) decides
 * when the excitation (ctrl/canfdi_excite.h) is on; this module says when
 * a plant may carry it and feeds the schedulers each step.
 *
 * Enabling conditions (all of them, per plant):
 *   DC motor: the drive runs in closed loop (controller RUN) in NORMAL
 *             degradation, with a usable speed reference whose magnitude
 *             lies in [dcm_w_min, dcm_w_max]: never at standstill (the
 *             driver expects the motor to stand still) and never where the
 *             test signal would push the speed past the calibrated range.
 *   Throttle: the valve runs in closed loop in NORMAL degradation with a
 *             usable angle reference in [thr_min, thr_max]: away from the
 *             limp-home band (the spring's kink) and from the stops.
 * Need: the plant's diagnosis shows a symptom it has not isolated yet (the
 * last step's result: the diagnosis runs after the controllers). For the
 * throttle also a suspicion: the fast mechanical test's friction deviation
 * at or above half its threshold, or its spring deviation at or below
 * half its (negative) threshold, without a symptom yet. That test
 * qualifies data only while the valve moves one way at 0.3 rad/s or more
 * for 40 ms; a driver's slow sweep gives it a few updates after a fault's
 * onset and then none for a second, and its deviation may stop short of
 * the threshold. The burst's 2 Hz motion qualifies it, so a suspicion is
 * confirmed or cleared within the parametric budget. Fault-free, in the
 * SIL spread of canfdi_diagnosis.c, the friction deviation stays negative
 * and the spring deviation above -4.8 % (half its threshold is -5 %).
 * Where the valve sticks at the onset it may never hold that motion, and
 * the test gets no update at all; the valve then lags (or leads) the
 * model: both position residuals past a quarter of their bands with one
 * sign for 50 consecutive steps are a suspicion too (fault-free, the
 * 11.5-minute drive never held that for 50 ms). The driveability bench
 * measures what the suspicions cost (docs/driving.md).
 * The throttle has no need (symptom or suspicion) while the two sensors
 * disagree (CORR, P2135's condition):
 * only a sensor drift moves CORR (dbc/diag_rules.csv), and the position
 * residuals that tell TPS1 from TPS2 compare the sensors with the model,
 * whose error a test burst raises; parameter evidence decides nothing
 * there.
 * Excited: the plant's estimator was fed this step and its excitation gate
 * applied the last update.
 *
 * Cost: two scheduler steps and a few compares per step, O(1).
 */
#ifndef CANFDI_APP_TEST_H
#define CANFDI_APP_TEST_H

#include "core/canfdi_common.h"
#include "diag/canfdi_testsched.h"

typedef struct {
  canfdi_testsched_cfg_t dcm;
  canfdi_testsched_cfg_t thr;
  int32_t dcm_w_min_rad_s_q16; /* |speed reference| window, Q16.16 rad/s */
  int32_t dcm_w_max_rad_s_q16;
  int32_t thr_min_rad_q16;     /* angle reference window, Q16.16 rad */
  int32_t thr_max_rad_q16;
} canfdi_app_test_cfg_t;

typedef struct {
  bool ref_usable;   /* the driver's reference was received and is usable */
  int32_t ref_q16;   /* speed (rad/s) or angle (rad) reference */
  bool closed_loop;  /* controller RUN in NORMAL degradation */
  bool excited;      /* estimator fed and its last update applied */
  bool need;         /* detected, not isolated (last step) */
  bool unlearnt;     /* the estimator is fed but has not converged */
} canfdi_app_test_in_t;

typedef struct {
  canfdi_testsched_t dcm;
  canfdi_testsched_t thr;
} canfdi_app_test_t;

/* Defaults: the schedulers' defaults; DC motor 20..350 rad/s; throttle
 * 10..80 deg (above the limp-home angle of 6.5 deg and its band, below the
 * upper stop at 90 deg with room for the test signal). */
void canfdi_app_test_default_cfg(canfdi_app_test_cfg_t *cfg);

/* CANFDI_OK or -CANFDI_EINVAL (NULL, an empty window, a scheduler cfg
 * refused). */
int32_t canfdi_app_test_init(canfdi_app_test_t *t, const canfdi_app_test_cfg_t *cfg);

/* One step of both schedulers; *dcm_on / *thr_on: the test signal is on. */
void canfdi_app_test_step(canfdi_app_test_t *t, const canfdi_app_test_cfg_t *cfg, const canfdi_app_test_in_t *dcm,
                          const canfdi_app_test_in_t *thr, bool *dcm_on, bool *thr_on);

#endif /* CANFDI_APP_TEST_H */
