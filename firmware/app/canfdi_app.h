/*
 * canfdi_app.h — the supervisor application: one 1 ms step over statically
 * allocated state that closes both control loops, supervises its inputs and
 * both plants, names the fault, remembers it and keeps the plants safe.
 *
 * Ports. Frames in: canfdi_app_rx_frame() for every received CAN frame
 * (any id; the input supervision judges it). Frames out: canfdi_app_step()
 * writes the frames to send in this step into the caller's buffer
 * (CANFDI_APP_MAX_TX frames). Nothing else crosses the boundary: the same
 * core runs in SIL (tests/sil), on SocketCAN and on a microcontroller.
 *
 * Order inside one step (canfdi_app_step):
 *   1. input supervision  canfdi_rx_step: validated inputs, U-code monitors
 *   2. range checks       canfdi_limit on TPS1/TPS2 (raw symptom excludes
 *                         the sensor from the vote at once)
 *   3. voting             canfdi_vote over TPS1, TPS2 and the throttle
 *                         observer's angle of the previous step
 *   4. control            ctrl_dcm (speed), ctrl_thr (position) + excitation,
 *                         in the mode the actuator manager set last step
 *   5. detection          parity_dcm, parity_thr (residuals), est_dcm,
 *                         est_thr (parameters; their RLS updates are
 *                         decimated inside the modules). An estimator is
 *                         not fed while an input of its equations is known
 *                         bad (U_A: UAC symptom or a latched U_A offset) or
 *                         its plant is not driven (throttle de-energised,
 *                         no valid position, no current); it restarts with
 *                         a covariance reset and its parameter symptoms
 *                         stay invalid until it has re-converged
 *   6. symptoms           canfdi_symptoms_t
 *   7. diagnosis          canfdi_diagnosis_step: report per fault id
 *   8. DTC memory         diagnosis, manager and rx monitors -> canfdi_dtc,
 *                         freeze frame of the key signals
 *   9. fault tolerance    canfdi_actmgr (bridges, limp-home, degradation)
 *  10. outputs            canfdi_tx: actuators every step, residuals 10 ms,
 *                         status / diagnosis / self-diagnostics / DTC /
 *                         parameters 100 ms, DTC
 *                         status changes on change
 * The models use the command applied in the previous step (the voltage the
 * bridge held over the interval that ends with this sample).
 *
 * Load: the firmware has no torque sensor; the vehicle sends the load it
 * knows it applies with the speed setpoint (SpDcmLoad, rx input
 * CANFDI_RX_IN_SP_DCM_LOAD). It is the parity equations' load_Nm_q16, the
 * estimator's known load offset (canfdi_est_dcm_set_load_offset, relative
 * to cal.load_nom_Nm_q16 which est_dcm's mc_nom includes), and the lumped
 * M_c deviation compares against mc_nom + (known - nominal) load,
 * normalised to mc_nom. Lost or rejected: cal.load_nom_Nm_q16 (given to
 * canfdi_rx as the stand-in every step). An unknown share of the load (the
 * vehicle's figure is wrong or incomplete) still looks like friction: r2..r4
 * follow their mean over load_tau_s, the lumped M_c does not.
 *
 * Faults given to the manager: the catalogue ids whose trouble code has
 * testFailed set (qualified by the DTC memory's debouncing), plus the ids
 * the diagnosis reports FAILED this step, plus what the manager detected
 * itself. The manager's degradation ratchet keeps them latched.
 *
 * Scaling and overflow: all signals Q16.16 SI (see the modules); the app
 * adds only conversions by the modules' own helpers and saturating
 * arithmetic (canfdi_fixp.h). Normalised parameter deviations
 * (est - nom) / nom are formed with canfdi_div_s32_qn (saturating).
 *
 * Cost per canfdi_app_step, executed instructions measured on QEMU
 * mps2-an386 with -icount (SysTick), arm-none-eabi-gcc 12 -Os, over the
 * 24 000 steps of the SIL demo (tests/sil/scenarios/demo.scn: fault-free
 * phase, TPS drift, R_A fault, bridge switchover, limp-home), `make sil-pil`
 * (the M0+ code runs on the same emulated core: instruction counts, not
 * cycles):
 *                      min      mean     max
 *   Cortex-M4          30 500   51 700   75 600
 *   Cortex-M0+ code    53 900   97 200  140 900
 * The model layer dominates (parity_dcm, parity_thr, est_dcm, est_thr: SVFs
 * every step, RLS updates decimated inside the modules; the throttle's
 * always-on excitation keeps its mechanical estimator and fast test busy);
 * the max was seen at 5.7 s (M4) and 6.3 s (M0+) of the demo.
 * A 1 ms step therefore needs a Cortex-M4 of roughly 100 MHz or more with
 * margin; on a Cortex-M0+ at 48 MHz it does not fit (raise the estimators'
 * decim, or run them in a slower task). Host (x86-64, gcc -O2, callgrind):
 * 35.6..37.5 k instructions per step on average (`make sil-bench`). The same
 * run shows the ECU's frames bit-identical between the host build and both
 * target builds.
 * Memory: sizeof(canfdi_app_t) = 9496 bytes on Cortex-M0+/M4 (~940 of them
 * the calibration copy), all of the application's RAM (static; `make
 * firmware` shows it in .bss); code ~5.4 kB for this module (M0+, -Os) on
 * top of the modules it calls. Stack: canfdi_app_step 296 bytes (M0+,
 * -fstack-usage, helpers inlined) plus the deepest module it calls. No heap.
 */
#ifndef CANFDI_APP_H
#define CANFDI_APP_H

#include "comm/canfdi_rx.h"
#include "comm/canfdi_tx.h"
#include "core/canfdi_common.h"
#include "ctrl/canfdi_ctrl_dcm.h"
#include "ctrl/canfdi_ctrl_thr.h"
#include "ctrl/canfdi_excite.h"
#include "detect/canfdi_limit.h"
#include "diag/canfdi_diagnosis.h"
#include "diag/canfdi_dtc.h"
#include "diag/canfdi_symptoms.h"
#include "ft/canfdi_actmgr.h"
#include "ft/canfdi_vote.h"
#include "model/canfdi_est_dcm.h"
#include "model/canfdi_est_thr.h"
#include "model/canfdi_parity_dcm.h"
#include "model/canfdi_parity_thr.h"

#define CANFDI_APP_MAX_TX CANFDI_TX_MAX_FRAMES_PER_STEP

/* The one calibration of the product: every module's configuration. */
typedef struct {
  canfdi_rx_cfg_t rx;
  canfdi_ctrl_dcm_cal_t ctrl_dcm;
  canfdi_ctrl_thr_cal_t ctrl_thr;
  canfdi_excite_cfg_t excite_dcm; /* added to the speed reference, rad/s */
  canfdi_excite_cfg_t excite_thr; /* added to the angle reference, rad */
  bool excite_dcm_on;
  bool excite_thr_on;
  canfdi_parity_dcm_cfg_t parity_dcm;
  canfdi_parity_thr_cfg_t parity_thr;
  canfdi_est_dcm_cfg_t est_dcm;
  canfdi_est_thr_cfg_t est_thr;
  canfdi_limit_cfg_t tps_range;    /* TPS voltage window, Q16.16 V */
  canfdi_vote_cfg_t vote;
  canfdi_actmgr_cfg_t actmgr;
  canfdi_diagnosis_cfg_t diagnosis;
  int32_t load_nom_Nm_q16;         /* load the models assume while the vehicle's
                                    * load feed-forward (SetpointDcm.SpDcmLoad) is
                                    * lost, rejected or not yet received */
  int32_t track_err_alpha_q16;     /* low-pass of |angle - setpoint| per step */
  uint16_t p2135_steps;            /* TPS disagreement not isolated this long -> P2135 */
  int32_t uac_alpha_q16;           /* low-pass of U_A - command per step */
  int32_t uac_thr_V_q16;           /* threshold of the filtered U_A - command */
} canfdi_app_cal_t;

/* Monotone self-diagnostics, saturating at UINT32_MAX. */
typedef struct {
  uint32_t steps;
  uint32_t deadline_misses;   /* reported by the port */
  uint32_t saturations;       /* controller outputs limited + tx values limited */
  uint32_t estimator_resets;  /* est_dcm + est_thr + parity resets */
  uint32_t frames_rejected;   /* length, CRC, counter, implausible (rx) */
  uint32_t frames_unknown;    /* identifiers the rx does not supervise */
  uint32_t frames_sent;
  uint32_t dtc_reports_rejected;
} canfdi_app_diag_t;

typedef struct {
  canfdi_app_cal_t cal;  /* copy; the modules point into it */
  canfdi_rx_t rx;
  canfdi_tx_t tx;
  canfdi_ctrl_dcm_t ctrl_dcm;
  canfdi_ctrl_thr_t ctrl_thr;
  canfdi_excite_t excite_dcm;
  canfdi_excite_t excite_thr;
  canfdi_parity_dcm_t parity_dcm;
  canfdi_parity_thr_t parity_thr;
  canfdi_est_dcm_t est_dcm;
  canfdi_est_thr_t est_thr;
  canfdi_limit_t tps_range[2];
  canfdi_vote_t vote;
  canfdi_actmgr_t actmgr;
  canfdi_diagnosis_t diagnosis;
  canfdi_dtc_t dtc;
  canfdi_symptoms_t sym;
  canfdi_vote_out_t vote_out;
  canfdi_actmgr_out_t mgr_out;   /* of the last step */
  int8_t report[CANFDI_FAULT_COUNT];
  uint8_t dtc_index[CANFDI_FAULT_COUNT][CANFDI_CATALOGUE_MAX_DTCS]; /* 0xFF none */
  uint8_t dtc_status_prev[CANFDI_DTC_COUNT];
  uint32_t faults;               /* fault bits given to the manager last step */
  int32_t thr_track_err_q16;
  int32_t uac_f_q16;             /* filtered U_A - applied command, V */
  uint16_t p2135_n;              /* steps the disagreement stayed unisolated */
  bool dcm_in_ok;                /* U_A, I_A, omega VALID this step */
  bool thr_in_ok;                /* TPS1/2, current, supply usable this step */
  bool dcm_started;              /* dcm_in_ok was true once (start-up inhibit) */
  bool thr_started;              /* thr_in_ok was true once */
  bool dcm_est_on;               /* est_dcm fed this step (see step_detect) */
  bool thr_est_on;               /* est_thr fed this step (see step_detect) */
  uint32_t now_us;
  uint32_t step_time_max_us;  /* port timing since the last EcuStatus (0 in SIL) */
  uint32_t cycle_time_max_us;
  canfdi_app_diag_t diag;
  bool initialised;
} canfdi_app_t;

/* Defaults of every module (their *_default_cfg / *_cal_default) plus the
 * application's choices documented in canfdi_app.c. Cannot fail for
 * non-NULL. */
void canfdi_app_default_cal(canfdi_app_cal_t *cal);

/*
 * Copies cal, initialises every module, starts an operation cycle of the
 * DTC memory (after an optional NVM load by the caller: see
 * canfdi_app_dtc()). Returns CANFDI_OK or -CANFDI_EINVAL (a module refused
 * its configuration; app unusable). Cost: init time only (divisions).
 */
int32_t canfdi_app_init(canfdi_app_t *app, const canfdi_app_cal_t *cal, uint32_t now_us);

/* One received frame (forwarded to the input supervision). Returns the
 * canfdi_rx_frame result. Cost: see canfdi_rx.h. */
int32_t canfdi_app_rx_frame(canfdi_app_t *app, uint32_t id, const uint8_t *data, uint8_t dlc,
                            uint32_t now_us);

/* One 1 ms step at now_us; writes the frames to send into out[0..n-1]
 * (out holds CANFDI_APP_MAX_TX). Returns n >= 0 or -CANFDI_EINVAL. */
int32_t canfdi_app_step(canfdi_app_t *app, uint32_t now_us, canfdi_tx_frame_t *out);

/* The port reports a missed 1 ms deadline. */
void canfdi_app_deadline_miss(canfdi_app_t *app);

/*
 * The port reports the timing of the step it just ran: step_us, the
 * execution time of canfdi_app_step (and the sending of its frames, as the
 * port measures it), and cycle_us, the time between the starts of this step
 * and the previous one. The app keeps the maximum of each and sends it in
 * the next EcuStatus (StsStepTimeMax, StsCycleTimeMax, saturating at 4095
 * us), then starts a new maximum. A port that never calls this (SIL,
 * lockstep) sends 0 for both, so its frames do not depend on the host's
 * speed. No-op on NULL. Cost O(1).
 */
void canfdi_app_port_timing(canfdi_app_t *app, uint32_t step_us, uint32_t cycle_us);

/* The trouble-code memory (read access, NVM load/store by the port). */
canfdi_dtc_t *canfdi_app_dtc(canfdi_app_t *app);

const canfdi_app_diag_t *canfdi_app_diag(const canfdi_app_t *app);

#endif /* CANFDI_APP_H */
