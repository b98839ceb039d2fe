/*
 * canfdi_app_cal.c — the product calibration (see canfdi_app_cal.h): each
 * choice below states the physical fact or the figure it rests on.
 */
#include "app/canfdi_app_cal.h"

#include "core/canfdi_qconst.h"

static void cal_excitation(canfdi_app_cal_t *cal)
{
  /* Speed excitation for the parameter estimators: a +-5 rad/s PRBS with
   * 50 ms bits (above the ~20 ms speed time constant, so the current
   * swings), about the estimator's excitation gate (~4 rad/s rms). */
  cal->excite_dcm.prbs_amp_q16 = 5 * CANFDI_Q16_ONE;
  cal->excite_dcm.prbs_bit_us = 50000U;
  cal->excite_dcm.prbs_seed = 0x1234U;
  cal->excite_dcm.sine_amp_q16 = 0;
  cal->excite_dcm.sine_period_us = 0U;
  cal->excite_dcm_on = true;
  /* Throttle: a +-3 deg sine of 0.5 s period on the angle reference.
   * The mechanical estimator only learns while the valve moves one way
   * faster than its friction-sign band (0.3 rad/s) for its hold-off
   * (40 ms), and the electrical one needs current and angle-rate swings
   * (canfdi_est_thr.h). Peak rate 0.052 rad x 4 pi/s = 0.66 rad/s (2.2 x
   * the band); 2 Hz is a tenth of the position loop's ~19 Hz, so the
   * valve follows without lag; one-way phases of 250 ms minus the
   * hold-off give ~200 mechanical updates per second. A PRBS (edges every
   * 50 ms) reverses too often for the motion gate and clips the current
   * at its edges. */
  cal->excite_thr.prbs_amp_q16 = 0;
  cal->excite_thr.prbs_bit_us = 50000U;
  cal->excite_thr.prbs_seed = 0x0321U;
  cal->excite_thr.sine_amp_q16 = CANFDI_Q16_MILLI(52);
  cal->excite_thr.sine_period_us = 500000U;
  cal->excite_thr_on = true;
  canfdi_app_test_default_cfg(&cal->test);
}

static void cal_models(canfdi_app_cal_t *cal)
{
  canfdi_parity_dcm_default_cfg(&cal->parity_dcm);
  /* The load comes from the vehicle (SpDcmLoad); an unknown share of it
   * may remain: r2..r4 follow their own mean over 1 s, so that a constant
   * or slowly changing unknown share is not a fault (canfdi_parity_dcm.h,
   * load_tau_s). */
  cal->parity_dcm.load_tau_s = 1U;
  /* The known load (SetpointDcm, 10 ms cycle) lags a load step by up to
   * 10 + 1 ms; when the new value arrives the lag is over and what
   * remains is the filters' memory of the mismatch: r2..r4 are held for
   * the tail of the parity SVF (order 3, 100 rad/s: 113 steps to 1e-3),
   * the mechanical estimator for the tail of its SVF (order 2, 200 rad/s:
   * 47 steps). Derivations in canfdi_parity_dcm.h / canfdi_est_dcm.h. */
  cal->parity_dcm.load_hold_steps = 113U;
  canfdi_parity_thr_default_cfg(&cal->parity_thr);
  canfdi_est_dcm_default_cfg(&cal->est_dcm);
  cal->est_dcm.load_hold_steps = 47U;
  canfdi_est_thr_default_cfg(&cal->est_thr);
  /* The drive's nominal operating load, 1.2 N m (docs/design.md), the
   * same operating point as est_dcm's nominal M_c = 0.11 + 1.2 N m. */
  cal->load_nom_Nm_q16 = CANFDI_Q16_MILLI(1200);
  /* Model rules held 0.5 s after a plant's inputs come back. A sensor
   * node restarted in the HIL bench (tests/hil/test_busfault.py) shows the
   * motor at rest where it ran at 60 rad/s; the drive accelerates it with
   * the bridge saturated and the restarted DC-motor residuals stay out of
   * band for about 0.16 s (the parity's 60 settle steps included); a
   * fault-free start from rest into a 60 rad/s step, for 0.2 s. 0.5 s is
   * the DC-motor estimator's memory. A late sample, stepped on again,
   * disturbs the parity equations' filters for the tail of their SVF
   * (113 steps to 1e-3, above) and the residuals' persistence (20 steps)
   * after it: 150 ms. */
  cal->rearm_steps = 500U;
  cal->late_hold_steps = 150U;
}

static void cal_position_sensors(canfdi_app_cal_t *cal)
{
  /* TPS window 0.25..4.75 V (the sensors' 0.5..4.5 V plus margin), a
   * little hysteresis; the raw symptom is used (the diagnosis debounces). */
  cal->tps_range.max_set = CANFDI_Q16_MILLI(4750);
  cal->tps_range.max_clear = CANFDI_Q16_MILLI(4700);
  cal->tps_range.min_set = CANFDI_Q16_MILLI(250);
  cal->tps_range.min_clear = CANFDI_Q16_MILLI(300);
  cal->tps_range.max_enabled = true;
  cal->tps_range.min_enabled = true;
  cal->tps_range.deb.failed_threshold = 20;
  cal->tps_range.deb.passed_threshold = -20;
  cal->tps_range.deb.prefailed_step = 1U;
  cal->tps_range.deb.prepassed_step = 1U;
  cal->tps_range.deb.jump_up_value = 0;
  cal->tps_range.deb.jump_down_value = 0;
  cal->tps_range.deb.jump_up = true;
  cal->tps_range.deb.jump_down = true;
  /* The potentiometers' design lines: TPS1 0.5 V + 4 V per 90 deg, TPS2
   * 4.5 V - 4 V per 90 deg (model/canfdi_tps.h). */
  canfdi_tps_cal_default(&cal->tps1, &cal->tps2);
  cal->vote.tps1 = cal->tps1;
  cal->vote.tps2 = cal->tps2;
  cal->vote.tol_tps_rad_q16 = CANFDI_Q16_MILLI(20);
  cal->vote.tol_model_rad_q16 = CANFDI_Q16_MILLI(50);
  cal->vote.isolate_steps_tps = 20U;
  cal->vote.isolate_steps_model = 50U;
}

void canfdi_app_default_cal(canfdi_app_cal_t *cal)
{
  if (cal != NULL) {
    canfdi_rx_default_cfg(&cal->rx);
    /* First reception: the sensor node and the vehicle may boot up to 2 s
     * after this ECU (a HIL bench starts its processes one after the
     * other; a vehicle powers its nodes in sequence: AUTOSAR COM's first
     * timeout). Until then the inputs are INVALID and the drives are held
     * off; after the first frame the normal 4/5-cycle windows apply. */
    cal->rx.first_timeout_us = 2000000U;
    canfdi_ctrl_dcm_cal_default(&cal->ctrl_dcm);
    canfdi_ctrl_thr_cal_default(&cal->ctrl_thr);
    canfdi_uds_default_cfg(&cal->uds);
    cal->uds.limp_home_rad_q16 = cal->ctrl_thr.limp_home_rad_q16;
    cal_excitation(cal);
    cal_models(cal);
    cal_position_sensors(cal);
    canfdi_actmon_default_cfg(&cal->actmon);
    canfdi_app_sym_default_cfg(&cal->sym);
    canfdi_actmgr_default_cfg(&cal->actmgr);
    canfdi_diagnosis_default_cfg(&cal->diagnosis);
    /* RAX's "nothing to explain" waits for r1's symptom to clear */
    cal->sym.rax_quiet_steps = cal->diagnosis.sym_off_steps;
    canfdi_dtcroute_default_cfg(&cal->dtcroute);
    /* the model rules' matching every 10 ms (canfdi_app.h, the rate
     * schedule) */
    cal->diag_period_steps = 10U;
  }
}
