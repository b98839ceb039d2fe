/*
 * canfdi_app_cal.h — the product calibration: every module's configuration
 * in one struct, and its defaults for the plants of docs/design.md.
 *
 * Each physical fact is set once here and handed to every module that
 * needs it (the throttle position sensors' characteristic to the vote and
 * the throttle parity equations, the nominal load to the parity equations
 * and the estimator); the modules keep their own copies of what they were
 * given. A calibration that a module refuses makes canfdi_app_init fail.
 *
 * Memory: sizeof(canfdi_app_cal_t) is about 1 kB; canfdi_app_t holds one
 * copy (the modules point into it). Cost: canfdi_app_default_cal is init
 * time only.
 */
#ifndef CANFDI_APP_CAL_H
#define CANFDI_APP_CAL_H

#include "app/canfdi_app_sym.h"
#include "comm/canfdi_rx.h"
#include "app/canfdi_app_test.h"
#include "core/canfdi_common.h"
#include "ctrl/canfdi_ctrl_dcm.h"
#include "ctrl/canfdi_ctrl_thr.h"
#include "ctrl/canfdi_excite.h"
#include "detect/canfdi_actmon.h"
#include "detect/canfdi_limit.h"
#include "diag/canfdi_diagnosis.h"
#include "diag/canfdi_dtcroute.h"
#include "ft/canfdi_actmgr.h"
#include "ft/canfdi_vote.h"
#include "model/canfdi_est_dcm.h"
#include "model/canfdi_est_thr.h"
#include "model/canfdi_parity_dcm.h"
#include "model/canfdi_parity_thr.h"
#include "model/canfdi_tps.h"
#include "uds/canfdi_uds.h"

typedef struct {
  canfdi_tps_cal_t tps1;           /* throttle-position sensor characteristics: */
  canfdi_tps_cal_t tps2;           /* the one source for the vote and the parity
                                    * equations (canfdi_app_init copies them into
                                    * vote and parity_thr) */
  canfdi_rx_cfg_t rx;
  canfdi_ctrl_dcm_cal_t ctrl_dcm;
  canfdi_ctrl_thr_cal_t ctrl_thr;
  canfdi_excite_cfg_t excite_dcm; /* added to the speed reference, rad/s */
  canfdi_excite_cfg_t excite_thr; /* added to the angle reference, rad */
  bool excite_dcm_on;              /* the test signal may run at all ... */
  bool excite_thr_on;
  canfdi_app_test_cfg_t test;      /* ... and runs when these conditions say */
  canfdi_parity_dcm_cfg_t parity_dcm;
  canfdi_parity_thr_cfg_t parity_thr;
  canfdi_est_dcm_cfg_t est_dcm;
  canfdi_est_thr_cfg_t est_thr;
  canfdi_limit_cfg_t tps_range;    /* TPS voltage window, Q16.16 V */
  canfdi_vote_cfg_t vote;
  canfdi_actmon_cfg_t actmon;
  canfdi_app_sym_cfg_t sym;
  canfdi_actmgr_cfg_t actmgr;
  canfdi_diagnosis_cfg_t diagnosis;
  canfdi_dtcroute_cfg_t dtcroute;
  uint8_t diag_period_steps;       /* the rate schedule (canfdi_app.h): the
                                    * model rules' matching runs every
                                    * diag_period_steps 1 ms steps, 1..10
                                    * (1: every step, the unscheduled
                                    * diagnosis); isolate_steps stays given
                                    * in 1 ms steps (converted at init) */
  canfdi_uds_cfg_t uds;            /* the diagnostic server (limp-home angle from ctrl_thr) */
  uint16_t rearm_steps;            /* a plant's model rules held this many 1 ms
                                    * steps after its inputs came back from an
                                    * interruption (canfdi_app.h, feedback) ... */
  uint16_t late_hold_steps;        /* ... and this many after a late sample */
  int32_t load_nom_Nm_q16;         /* load the models assume while the vehicle's
                                    * load feed-forward (SetpointDcm.SpDcmLoad) is
                                    * lost, rejected or not yet received */
} canfdi_app_cal_t;

/* Every module's defaults (their *_default_cfg / *_cal_default) plus the
 * product's choices documented in canfdi_app_cal.c. Cannot fail for
 * non-NULL (no-op on NULL). */
void canfdi_app_default_cal(canfdi_app_cal_t *cal);

#endif /* CANFDI_APP_CAL_H */
