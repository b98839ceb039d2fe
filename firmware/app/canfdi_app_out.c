/*
 * canfdi_app_out.c — the ECU's output frames of one step; the manual is
 * the header.
 */
#include "app/canfdi_app_out.h"

#include "core/canfdi_count.h"
#include "core/canfdi_fixp.h"
#include "core/canfdi_intrin.h"

/* queue_changes collects the changed DTCs as bits of one word */
CANFDI_STATIC_ASSERT(CANFDI_CFG_DTC_MAX_DTCS <= 32U, changed_dtcs_fit_one_word);

#define TX_DUE(due, f) (((due) & (1U << (f))) != 0U)

void canfdi_app_out_init(canfdi_app_out_t *o, const canfdi_dtc_t *dtc)
{
  uint32_t i;
  CANFDI_ASSERT((o != NULL) && (dtc != NULL));
  for (i = 0U; i < CANFDI_CFG_DTC_MAX_DTCS; i++) {
    const int32_t st = (i < (uint32_t)dtc->n_dtcs) ? canfdi_dtc_status(dtc, (uint8_t)i) : 0;
    o->dtc_status_sent[i] = (st >= 0) ? (uint8_t)st : 0U;
  }
  o->dtc_changes_seen = dtc->changes;
  o->dtc_behind = false;
  o->dtc_next = 0U;
  o->n_stored = (uint8_t)canfdi_dtc_count_by_mask(dtc, (uint8_t)CANFDI_DTC_ST_TFSLC);
  o->n_failed = (uint8_t)canfdi_dtc_count_by_mask(dtc, (uint8_t)CANFDI_DTC_ST_TF);
  o->rr_frames = 0U;
  o->step_time_max_us = 0U;
  o->cycle_time_max_us = 0U;
  o->diag = (canfdi_app_out_diag_t){0};
}

void canfdi_app_out_port_timing(canfdi_app_out_t *o, uint32_t step_us, uint32_t cycle_us)
{
  CANFDI_ASSERT(o != NULL);
  o->step_time_max_us = (step_us > o->step_time_max_us) ? step_us : o->step_time_max_us;
  o->cycle_time_max_us = (cycle_us > o->cycle_time_max_us) ? cycle_us : o->cycle_time_max_us;
}

/* On change: one EcuDtc per DTC whose status differs from the last sent,
 * and the number of stored (TFSLC) and failed (TF) codes the frames carry,
 * all from one pass over the statuses. A status changes only with
 * dtc->changes (canfdi_dtc.h): while that has not moved, and no change
 * waits for room in the queue, there is nothing to look for and the
 * counts stand. */
static void queue_changes(canfdi_app_out_t *o, canfdi_tx_t *tx, const canfdi_dtc_t *dtc)
{
  if ((dtc->changes != o->dtc_changes_seen) || o->dtc_behind) {
    uint32_t changed = 0U;
    uint32_t stored = 0U;
    uint32_t failed = 0U;
    uint32_t part[2];
    uint32_t p;
    uint32_t j;
    for (j = 0U; j < (uint32_t)dtc->n_dtcs; j++) {
      const uint8_t s = canfdi_dtc_status_at(dtc, (uint8_t)j); /* j < n_dtcs */
      stored += ((s & CANFDI_DTC_ST_TFSLC) != 0U) ? 1U : 0U;
      failed += ((s & CANFDI_DTC_ST_TF) != 0U) ? 1U : 0U;
      changed |= (s != o->dtc_status_sent[j]) ? (UINT32_C(1) << j) : 0U;
    }
    o->dtc_changes_seen = dtc->changes;
    o->n_stored = (uint8_t)stored; /* <= n_dtcs */
    o->n_failed = (uint8_t)failed;
    o->dtc_behind = false;
    /* round robin: the changes from dtc_next on, then those below it
     * (dtc_next < n_dtcs <= 32) */
    part[0] = changed & ~((UINT32_C(1) << o->dtc_next) - 1U);
    part[1] = changed & ~part[0];
    for (p = 0U; (p < 2U) && !o->dtc_behind; p++) {
      uint32_t m = part[p];
      while (m != 0U) {
        canfdi_tx_dtc_t ev;
        j = (uint32_t)canfdi_ctz32(m);
        m &= m - 1U;
        ev.dtc = dtc->table[j].dtc;
        ev.status = canfdi_dtc_status_at(dtc, (uint8_t)j);
        ev.occurrence = canfdi_dtc_occurrence(dtc, (uint8_t)j);
        ev.index = (uint8_t)j;
        ev.count = o->n_stored;
        if (canfdi_tx_dtc_event(tx, &ev) == CANFDI_OK) {
          canfdi_count_inc(&o->diag.dtc_events);
          o->dtc_status_sent[j] = ev.status;
          o->dtc_next = 0U;
          if ((j + 1U) < (uint32_t)dtc->n_dtcs) {
            o->dtc_next = (uint8_t)(j + 1U); /* < 32 */
          }
        } else {
          /* the queue is full (it sends one a step): this change and the
           * rest stay unsent and are looked for again next step, from
           * this one on */
          canfdi_count_inc(&o->diag.dtc_queue_full);
          o->dtc_behind = true;
          o->dtc_next = (uint8_t)j;
          m = 0U;
        }
      }
    }
  }
}

/* Cyclic: stored code number rr_frames modulo the number stored. */
static void cyclic_dtc(canfdi_app_out_t *o, const canfdi_dtc_t *dtc, canfdi_tx_dtc_t *rec)
{
  const uint8_t count = o->n_stored;
  const uint32_t want = (count > 0U) ? (o->rr_frames % count) : 0U;
  uint32_t n = 0U;
  uint32_t j;
  *rec = (canfdi_tx_dtc_t){0};
  rec->count = count;
  for (j = 0U; j < (uint32_t)dtc->n_dtcs; j++) {
    const uint8_t st = canfdi_dtc_status_at(dtc, (uint8_t)j); /* j < n_dtcs */
    if ((st & CANFDI_DTC_ST_TFSLC) != 0U) {
      if (n == want) {
        rec->dtc = dtc->table[j].dtc;
        rec->status = st;
        rec->occurrence = canfdi_dtc_occurrence(dtc, (uint8_t)j);
        rec->index = (uint8_t)n;
      }
      n++;
    }
  }
  o->rr_frames++; /* wraps by intent (see the header) */
}

/* The lowest communication fault id among the manager's faults, or 0. */
static uint8_t com_fault(uint32_t faults)
{
  uint8_t id = CANFDI_FAULT_NONE;
  uint32_t f;
  for (f = CANFDI_FAULT_COM_DCM_TIMEOUT; (f < CANFDI_FAULT_COUNT) && (id == 0U); f++) {
    if ((faults & CANFDI_FAULT_BIT(f)) != 0U) {
      id = (uint8_t)f;
    }
  }
  return id;
}

static void fill_actuators(const canfdi_app_out_src_t *src, canfdi_tx_data_t *d)
{
  d->dcm_act.ua_cmd_q16 = src->mgr->dcm.u_cmd_V_q16;
  d->dcm_act.bridge = src->mgr->dcm.bridge;
  d->dcm_act.enable = src->mgr->dcm.enable;
  d->thr_act.u_cmd_q16 = src->mgr->thr.u_cmd_V_q16;
  d->thr_act.enable = src->mgr->thr.enable;
}

static void fill_residuals(uint32_t due, const canfdi_app_out_src_t *src, canfdi_tx_data_t *d)
{
  const canfdi_parity_dcm_out_t *pd = canfdi_parity_dcm_out(src->parity_dcm);
  const canfdi_parity_thr_out_t *pt = canfdi_parity_thr_out(src->parity_thr);
  uint32_t i;
  if (TX_DUE(due, CANFDI_TX_F_RES_DCM)) {
    for (i = 0U; i < 4U; i++) {
      d->res_dcm.r_q16[i] = (pd != NULL) ? pd->rn_q16[i] : 0;
    }
  }
  if (TX_DUE(due, CANFDI_TX_F_RES_THR)) {
    d->res_thr.corr_q16 = (pt != NULL) ? pt->rn_q16[CANFDI_PARITY_THR_CORR] : 0;
    d->res_thr.tps1_q16 = (pt != NULL) ? pt->rn_q16[CANFDI_PARITY_THR_POS1] : 0;
    d->res_thr.tps2_q16 = (pt != NULL) ? pt->rn_q16[CANFDI_PARITY_THR_POS2] : 0;
    d->res_thr.current_q16 = (pt != NULL) ? pt->rn_q16[CANFDI_PARITY_THR_ARM] : 0;
  }
}

static void fill_status(canfdi_app_out_t *o, const canfdi_app_out_src_t *src, canfdi_tx_data_t *d)
{
  d->status.deg_state_dcm = src->mgr->dcm_state;
  d->status.deg_state_thr = src->mgr->thr_state;
  d->status.active_bridge = src->mgr->dcm.bridge;
  d->status.thr_limp_home = src->mgr->thr_limp_home;
  d->status.active_dtc_count = o->n_failed;
  d->status.deadline_misses = src->deadline_misses;
  /* the port's timing since the last EcuStatus; a new maximum starts */
  d->status.step_time_max_us = o->step_time_max_us;
  d->status.cycle_time_max_us = o->cycle_time_max_us;
  o->step_time_max_us = 0U;
  o->cycle_time_max_us = 0U;
}

static void fill_diagnosis(const canfdi_app_out_src_t *src, canfdi_tx_data_t *d)
{
  d->diagnosis.dcm_fault_id = canfdi_diagnosis_isolated(src->diagnosis, CANFDI_COMPONENT_DC_MOTOR,
                                                        &d->diagnosis.dcm_confidence_pct);
  d->diagnosis.thr_fault_id = canfdi_diagnosis_isolated(src->diagnosis, CANFDI_COMPONENT_THROTTLE,
                                                        &d->diagnosis.thr_confidence_pct);
  d->diagnosis.com_fault_id = com_fault(src->faults);
  d->diagnosis.com_confidence_pct = (d->diagnosis.com_fault_id != 0U) ? 100U : 0U;
}

static void fill_parameters(uint32_t due, const canfdi_app_out_src_t *src, canfdi_tx_data_t *d)
{
  const canfdi_est_dcm_t *ed = src->est_dcm;
  const canfdi_est_thr_t *et = src->est_thr;
  if (TX_DUE(due, CANFDI_TX_F_PRM_DCM)) {
    d->prm_dcm.ra_q16 = canfdi_est_dcm_ra_q16(ed);
    d->prm_dcm.psi_q16 = canfdi_est_dcm_psi_q16(ed);
    d->prm_dcm.j_q16 = canfdi_qconv_s32(canfdi_est_dcm_j_q24(ed), 24U, 16U);
    d->prm_dcm.mf1_q16 = canfdi_qconv_s32(canfdi_est_dcm_mf1_q24(ed), 24U, 16U);
    d->prm_dcm.mf0_q16 = canfdi_est_dcm_mc_q16(ed);
    d->prm_dcm.valid = canfdi_est_dcm_arm_converged(ed);
  }
  if (TX_DUE(due, CANFDI_TX_F_PRM_THR)) {
    d->prm_thr.r_q16 = canfdi_est_thr_r_q16(et);
    d->prm_thr.spring_k_q16 = canfdi_qconv_s32(canfdi_est_thr_spring_q24(et), 24U, 16U);
    d->prm_thr.spring_pre_q16 = canfdi_est_thr_pretension_q16(et);
    d->prm_thr.fric_c_q16 = canfdi_est_thr_friction_q16(et);
    d->prm_thr.fric_v_q16 = canfdi_qconv_s32(canfdi_est_thr_b_q24(et), 24U, 16U);
    d->prm_thr.valid = canfdi_est_thr_el_converged(et);
  }
}

int32_t canfdi_app_out_step(canfdi_app_out_t *o, canfdi_tx_t *tx, const canfdi_app_out_src_t *src,
                            canfdi_tx_frame_t *out)
{
  canfdi_tx_data_t d;
  uint32_t due;
  int32_t n;
  CANFDI_ASSERT((o != NULL) && (tx != NULL) && (src != NULL));
  queue_changes(o, tx, src->dtc);
  due = canfdi_tx_due(tx);
  /* d is not cleared: canfdi_tx_step reads only the frames due, and each
   * fill_* below sets every field of the frame it fills (clearing the
   * whole struct every step cost about 140 instructions on a Cortex-M4,
   * 350 on an M0) */
  fill_actuators(src, &d);
  fill_residuals(due, src, &d);
  if (TX_DUE(due, CANFDI_TX_F_STATUS)) {
    fill_status(o, src, &d);
  }
  if (TX_DUE(due, CANFDI_TX_F_DIAGNOSIS)) {
    fill_diagnosis(src, &d);
  }
  if (TX_DUE(due, CANFDI_TX_F_SELF_DIAG)) {
    d.self_diag = src->self_diag;
  }
  if (TX_DUE(due, CANFDI_TX_F_DTC)) {
    cyclic_dtc(o, src->dtc, &d.dtc);
  }
  fill_parameters(due, src, &d);
  n = (int32_t)canfdi_tx_step(tx, &d, out);
  if (n > 0) {
    canfdi_count_add(&o->diag.frames_sent, (uint32_t)n);
  }
  return n;
}
