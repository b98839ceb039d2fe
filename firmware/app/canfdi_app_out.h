/*
 * canfdi_app_out.h — the ECU's output frames of one step, composed from the
 * stages' results and handed to the transmit scheduler (comm/canfdi_tx.h):
 * the two actuator frames every step, and whichever slow frame is due
 * (residuals, status, diagnosis, self-diagnostics, a stored trouble code,
 * parameter estimates), plus the on-change trouble-code frames.
 *
 * Only the parts of a frame that are due are read from the sources, so a
 * step without a slow frame costs the two actuator frames only.
 *
 * Trouble codes on the bus (EcuDtc):
 *   on change   every step, each DTC whose status byte differs from the
 *               last one sent is queued (canfdi_tx_dtc_event), in table
 *               order, with its occurrence counter and the stored count;
 *               the queue (CANFDI_CFG_TX_DTC_QUEUE, 8) sends one a step,
 *               so when more change at once (a tester's clear changes
 *               every code) the rest wait, unsent, and are queued in the
 *               next steps with the status they have then: no change is
 *               lost, one that is undone before its turn is not sent;
 *   cyclic      every 100 ms one stored code (testFailedSinceLastClear),
 *               round robin: the n-th cyclic frame since init shows stored
 *               code number n modulo the number stored. n is a state of
 *               this module (rr_frames), counted per cyclic frame; it
 *               wraps after 2^32 frames (13.6 years) by intent, which only
 *               restarts the rotation at another code.
 * Port timing (canfdi_app_out_port_timing): the largest step and cycle time
 * since the last EcuStatus, sent in the next one and then started anew; 0
 * when the port never reports (SIL, lockstep).
 *
 * Scaling and overflow: values pass through as Q16.16 SI; canfdi_tx
 * saturates them to the DBC's ranges. Q8.24 estimates are converted with
 * canfdi_qconv_s32 (saturating). Counters saturate.
 * Cost per step: when the DTC memory changed (its `changes` counter moved)
 * one pass over the 32 statuses finds the changed codes and counts the
 * stored and the failed ones, which EcuStatus and every EcuDtc carry (a
 * step without a change reads no status for them); plus the frame due: a
 * pass over the DTCs and one record read for the cyclic EcuDtc, two
 * isolated-fault reads for EcuDiagnosis; then canfdi_tx_step.
 * Memory: sizeof(canfdi_app_out_t) = 64 bytes on a 32-bit target with the
 * product's 32 DTCs. No heap.
 */
#ifndef CANFDI_APP_OUT_H
#define CANFDI_APP_OUT_H

#include "catalogue/canfdi_catalogue.h"
#include "comm/canfdi_tx.h"
#include "core/canfdi_common.h"
#include "diag/canfdi_diagnosis.h"
#include "diag/canfdi_dtc.h"
#include "ft/canfdi_actmgr.h"
#include "model/canfdi_est_dcm.h"
#include "model/canfdi_est_thr.h"
#include "model/canfdi_parity_dcm.h"
#include "model/canfdi_parity_thr.h"

/* Where the frames' values come from in one step. */
typedef struct {
  const canfdi_actmgr_out_t *mgr;       /* this step's commands and states */
  const canfdi_parity_dcm_t *parity_dcm;
  const canfdi_parity_thr_t *parity_thr;
  const canfdi_est_dcm_t *est_dcm;
  const canfdi_est_thr_t *est_thr;
  const canfdi_diagnosis_t *diagnosis;
  const canfdi_dtc_t *dtc;
  uint32_t faults;                      /* the manager's fault bits: the communication fault shown */
  uint32_t deadline_misses;             /* reported by the port */
  canfdi_tx_self_diag_t self_diag;      /* the supervisor's counters */
} canfdi_app_out_src_t;

/* Monotone counters, saturating at UINT32_MAX. */
typedef struct {
  uint32_t frames_sent;
  uint32_t dtc_events;        /* on-change EcuDtc frames queued */
  uint32_t dtc_queue_full;    /* steps whose changes waited for room in the queue */
} canfdi_app_out_diag_t;

typedef struct {
  uint8_t dtc_status_sent[CANFDI_CFG_DTC_MAX_DTCS]; /* last status queued per DTC */
  uint32_t dtc_changes_seen;   /* dtc->changes at the last look for changes:
                                * a status changes only with it */
  uint8_t n_stored;            /* codes with TFSLC, as of dtc_changes_seen */
  uint8_t n_failed;            /* codes with TF, as of dtc_changes_seen */
  bool dtc_behind;             /* changes waiting for room in the queue */
  uint8_t dtc_next;            /* the look for changes starts at this DTC
                                * index (one after the last queued): a
                                * code that keeps changing cannot hold back
                                * the others while the queue is full */
  uint32_t rr_frames;          /* cyclic EcuDtc frames composed (wraps by intent) */
  uint32_t step_time_max_us;   /* port timing since the last EcuStatus */
  uint32_t cycle_time_max_us;
  canfdi_app_out_diag_t diag;
} canfdi_app_out_t;

/* Starts with the statuses of dtc as already sent, rotation 0, no timing.
 * The application calls it before an NVM image is loaded, so the codes
 * of a loaded memory are announced by the first steps. Cannot fail by
 * contract. */
void canfdi_app_out_init(canfdi_app_out_t *o, const canfdi_dtc_t *dtc);

/* Queues the on-change EcuDtc frames, composes the frames due and runs
 * canfdi_tx_step: out[0..n-1] (CANFDI_TX_MAX_FRAMES_PER_STEP) are this
 * step's frames. Returns n >= 0 or the canfdi_tx_step error. */
int32_t canfdi_app_out_step(canfdi_app_out_t *o, canfdi_tx_t *tx, const canfdi_app_out_src_t *src,
                            canfdi_tx_frame_t *out);

/* The port's timing of the step it just ran (see canfdi_app.h). O(1). */
void canfdi_app_out_port_timing(canfdi_app_out_t *o, uint32_t step_us, uint32_t cycle_us);

#endif /* CANFDI_APP_OUT_H */
