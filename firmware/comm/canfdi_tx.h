/*
 * canfdi_tx.h — the ECU's transmit side: encodes every frame the ECU sends
 * from plain structs of Q16.16 SI values and integers, and schedules them
 * on the 1 ms step.
 *
 *   frame           id     period  phase  content
 *   DcmActuator     0x020  1 ms    0      U_A command, bridge, enable; E2E
 *   ThrActuator     0x021  1 ms    0      motor voltage command, enable; E2E
 *   EcuResidualDcm  0x200  10 ms   2      r1..r4, normalised (1.0 = threshold)
 *   EcuResidualThr  0x201  10 ms   7      corr, tps1, tps2, current residuals
 *   EcuStatus       0x300  100 ms  3      degradation, bridge, limp-home, counts; E2E
 *   EcuDiagnosis    0x301  100 ms  23     isolated fault ids and confidences; E2E
 *   EcuSelfDiag     0x302  100 ms  13     the supervisor's monotone counters
 *   EcuDtc          0x310  100 ms  43     one stored DTC per frame, round robin; E2E
 *                   + on change: queued by canfdi_tx_dtc_event, one per step
 *   EcuParamDcm     0x320  100 ms  63     RLS estimates of the DC motor
 *   EcuParamThr     0x321  100 ms  83     estimates of the throttle
 * Periods come from the DBC (CANFDI_MSG_*_CYCLE_TIME_MS, in steps of
 * CANFDI_CFG_STEP_US); the phases (in steps, fixed) spread the slow frames
 * so that no step sends more than CANFDI_TX_MAX_FRAMES_PER_STEP frames:
 * the two actuator frames, at most one 10 ms or 100 ms frame (the 100 ms
 * phases are distinct and all 3 mod 10, the 10 ms ones 2 and 7 mod 10, so
 * none coincide) and at most one on-change DTC frame. The first
 * step after init sends the actuators only; each slow frame first goes out
 * at the step equal to its phase. Scheduling uses per-frame countdowns, so
 * it never drifts or wraps.
 *
 * Encoding: all bits go through the generated codec (comm/gen/canfdi_msg.h,
 * *_pack); the frames marked E2E (the DBC's CanfdiE2E) are then protected
 * (canfdi_e2e_protect: counter +1 per frame of that identifier, CRC-8 over
 * data id and bytes 1..7): the actuators, and the frames a tester or the
 * vehicle acts on, EcuStatus, EcuDiagnosis and EcuDtc (the cyclic and the
 * on-change EcuDtc share one counter, in the order encoded). EcuStatus's
 * counter is its alive counter. The engineering frames (residuals,
 * self-diagnostics, parameters) are not protected (dbc/README.md). Values are
 * converted with the integer constants of comm/gen/canfdi_sig_conv.h and
 * saturated to the DBC's [min|max] (raw limits of canfdi_raw_limits.h);
 * integers (counts, times, confidences, DTC, the EcuSelfDiag counters)
 * saturate at their field's maximum (EcuStatus: 63 active DTCs, step and
 * cycle time in 2 us units rounded up, 4094 us; EcuDtc: index 31, count
 * 63); an enumeration out of its table saturates to its top value,
 * except the actuator bridge: an unknown bridge selection is sent as
 * bridge none with the drive disabled (the safe state). Every limited
 * value is counted in diag.saturations (or diag.invalid_enums).
 *
 * Scaling and overflow (Q16.16 -> raw, per signal): inputs below MIN_Q16
 * or above MAX_Q16 saturate to the raw limit directly; inside, raw =
 * round_half_up((v_q16 * INV_SCALE_Q32 - OFFSET_RAW_Q32) / 2^32) in int64_t
 * (the generator proves the product below 2^62), then clamped to the raw
 * limits (a rounding at the range edge, not counted). The result is the
 * exactly rounded raw value up to (|v_q16| + 1) / 2^33 raw LSB near a tie
 * (< 0.001 raw for every signal sent here). Residuals: raw = round(v/64),
 * i.e. exact Q16.16 -> Q5.10. Note the Q16.16 resolution (1.5e-5) is
 * coarser than the DBC step of PrmDcmJ, PrmDcmMf1 (2e-6) and PrmThrFricV
 * (1e-5): those are sent as exactly as Q16.16 allows.
 *
 * Use, once per 1 ms step:
 *   due = canfdi_tx_due(&tx);       which frames this step will send
 *   fill the parts of `data` that `due` asks for;
 *   n = canfdi_tx_step(&tx, &data, frames);  frames[0..n-1] to the bus
 *   and whenever the DTC memory reports a status change:
 *   canfdi_tx_dtc_event(&tx, &record);
 * Each encoder can also be called on its own (then it does not touch the
 * schedule).
 *
 * Cost: executed instructions per canfdi_tx_step, measured on QEMU
 * mps2-an386 with -icount (SysTick), arm-none-eabi-gcc 12 -Os, min / mean /
 * max over 2000 steps with a DTC event every 7th step (M0+ code run on the
 * same emulated core: instruction counts, not cycles):
 *                                          Cortex-M4          Cortex-M0+
 *   actuators only (9 steps in 10)         621                953
 *   with a 10/100 ms frame and/or event    701 / 856 / 1078   1116 / 1426 / 1856
 * Per actuator frame about 300 (M4) / 450 (M0+): one 64-bit conversion
 * (__aeabi_lmul on M0+), the generated pack and the E2E CRC over 9 bytes.
 * Memory: sizeof(canfdi_tx_t) = 168 bytes on Cortex-M with the
 * default 8-entry DTC event queue (8 bytes per entry); the caller's frame
 * buffer 4 x 16 bytes; code 2.7 kB (-Os); stack <= 48 bytes per encoder
 * plus the generated pack and the E2E protect (-fstack-usage). The E2E
 * protection of EcuStatus, EcuDiagnosis and EcuDtc adds one CRC over 9
 * bytes to those frames (about 100 instructions on M4, not re-measured).
 * No heap, no recursion, no floating point.
 */
#ifndef CANFDI_TX_H
#define CANFDI_TX_H

#include "comm/canfdi_e2e.h"
#include "comm/canfdi_isotp.h"
#include "core/canfdi_common.h"

/* Depth of the on-change DTC queue; RAM: 8 bytes per entry. */
#ifndef CANFDI_CFG_TX_DTC_QUEUE
#define CANFDI_CFG_TX_DTC_QUEUE 8U
#endif

/* Transmitted frames; bit positions of canfdi_tx_due(). */
typedef enum {
  CANFDI_TX_F_DCM_ACT = 0,    /* 0x020 DcmActuator */
  CANFDI_TX_F_THR_ACT = 1,    /* 0x021 ThrActuator */
  CANFDI_TX_F_RES_DCM = 2,    /* 0x200 EcuResidualDcm */
  CANFDI_TX_F_RES_THR = 3,    /* 0x201 EcuResidualThr */
  CANFDI_TX_F_STATUS = 4,     /* 0x300 EcuStatus */
  CANFDI_TX_F_DIAGNOSIS = 5,  /* 0x301 EcuDiagnosis */
  CANFDI_TX_F_SELF_DIAG = 6,  /* 0x302 EcuSelfDiag */
  CANFDI_TX_F_DTC = 7,        /* 0x310 EcuDtc, cyclic (round robin) */
  CANFDI_TX_F_PRM_DCM = 8,    /* 0x320 EcuParamDcm */
  CANFDI_TX_F_PRM_THR = 9,    /* 0x321 EcuParamThr */
  CANFDI_TX_F_COUNT = 10,
  CANFDI_TX_F_DTC_EVENT = 10  /* due bit only: an on-change EcuDtc is queued */
} canfdi_tx_frame_id_t;

#define CANFDI_TX_MAX_FRAMES_PER_STEP 4U

typedef struct {
  uint32_t id;  /* 11-bit CAN identifier */
  uint8_t dlc;  /* 8 */
  uint8_t data[8];
} canfdi_tx_frame_t;

/* DcmActuator. */
typedef struct {
  int32_t ua_cmd_q16; /* armature voltage command, V; sent within -60..60 V */
  uint8_t bridge;     /* 0 none, 1 bridge A, 2 bridge B */
  bool enable;
} canfdi_tx_dcm_act_t;

/* ThrActuator. */
typedef struct {
  int32_t u_cmd_q16; /* motor voltage command, V; sent within -16..16 V */
  bool enable;
} canfdi_tx_thr_act_t;

/* EcuResidualDcm: parity residuals divided by their thresholds, Q16.16
 * (1.0 = threshold); sent as Q5.10, saturated to [-32, 32). */
typedef struct {
  int32_t r_q16[4]; /* r1..r4 */
} canfdi_tx_res_dcm_t;

/* EcuResidualThr, normalised like canfdi_tx_res_dcm_t. */
typedef struct {
  int32_t corr_q16;
  int32_t tps1_q16;
  int32_t tps2_q16;
  int32_t current_q16;
} canfdi_tx_res_thr_t;

/* EcuStatus (its E2E counter, the alive counter, is kept in canfdi_tx_t). */
typedef struct {
  uint8_t deg_state_dcm;      /* CANFDI_DEG_*: 0 normal .. 3 fail_silent */
  uint8_t deg_state_thr;
  uint8_t active_bridge;      /* 0 none, 1 A, 2 B */
  bool thr_limp_home;
  uint32_t active_dtc_count;  /* saturates at 63 */
  uint32_t deadline_misses;   /* saturates at 65535 */
  uint32_t step_time_max_us;  /* sent in 2 us units rounded up; saturates at 4094 */
  uint32_t cycle_time_max_us; /* the same */
} canfdi_tx_status_t;

/* EcuDiagnosis. */
typedef struct {
  uint8_t dcm_fault_id; /* CANFDI_FAULT_* */
  uint8_t thr_fault_id;
  uint8_t com_fault_id;
  uint8_t dcm_confidence_pct; /* saturates at 100 */
  uint8_t thr_confidence_pct;
  uint8_t com_confidence_pct;
} canfdi_tx_diagnosis_t;

/* EcuSelfDiag: monotone counters of the supervisor (canfdi_app_diag_t);
 * each saturates at its field's maximum (65535 for the first three, 255
 * for the last two), where it then stays. */
typedef struct {
  uint32_t frames_rejected;      /* rx: length, CRC, counter, implausible */
  uint32_t frames_unknown;       /* rx: identifiers not supervised */
  uint32_t saturations;          /* controller outputs + tx values limited */
  uint32_t estimator_resets;     /* estimators + parity equations */
  uint32_t dtc_reports_rejected; /* reports the DTC memory refused */
} canfdi_tx_self_diag_t;

/* EcuDtc: one stored trouble code. */
typedef struct {
  uint32_t dtc;       /* ISO 14229-1 3-byte DTC (CANFDI_DTC_*); saturates at 0xFFFFFF */
  uint8_t status;     /* UDS status byte: bit 0 testFailed .. bit 7 warningIndicator */
  uint8_t occurrence; /* times testFailed went 0 -> 1 */
  uint8_t index;      /* 0-based index among the stored DTCs; saturates at 31 */
  uint8_t count;      /* number of stored DTCs; saturates at 63 */
} canfdi_tx_dtc_t;

/* EcuParamDcm, physical units, Q16.16. */
typedef struct {
  int32_t ra_q16;  /* Ohm, 0..8 */
  int32_t psi_q16; /* V s, 0..0.8 */
  int32_t j_q16;   /* kg m^2, 0..0.016 (Q16.16 resolution 1.5e-5) */
  int32_t mf1_q16; /* N m s, 0..0.004 */
  int32_t mf0_q16; /* N m, 0..0.4 */
  bool valid;      /* estimator converged */
} canfdi_tx_param_dcm_t;

/* EcuParamThr, physical units (shaft-referred), Q16.16. */
typedef struct {
  int32_t r_q16;          /* Ohm, 0..8 */
  int32_t spring_k_q16;   /* N m / rad, 0..0.4 */
  int32_t spring_pre_q16; /* N m, 0..0.8 */
  int32_t fric_c_q16;     /* N m, 0..0.8 */
  int32_t fric_v_q16;     /* N m s / rad, 0..0.04 */
  bool valid;
} canfdi_tx_param_thr_t;

/* Everything canfdi_tx_step may send; only the parts due are read. */
typedef struct {
  canfdi_tx_dcm_act_t dcm_act;
  canfdi_tx_thr_act_t thr_act;
  canfdi_tx_res_dcm_t res_dcm;
  canfdi_tx_res_thr_t res_thr;
  canfdi_tx_status_t status;
  canfdi_tx_diagnosis_t diagnosis;
  canfdi_tx_self_diag_t self_diag;
  canfdi_tx_dtc_t dtc; /* the cyclic round-robin record */
  canfdi_tx_param_dcm_t prm_dcm;
  canfdi_tx_param_thr_t prm_thr;
} canfdi_tx_data_t;

/* Monotone counters, saturating at UINT32_MAX. */
typedef struct {
  uint32_t frames[CANFDI_TX_F_COUNT]; /* frames encoded, per frame (EcuDtc: both kinds) */
  uint32_t steps;                     /* canfdi_tx_step calls */
  uint32_t dtc_events;                /* on-change EcuDtc frames sent */
  uint32_t dtc_events_dropped;        /* canfdi_tx_dtc_event with a full queue */
  uint32_t saturations;               /* values limited to their DBC range */
  uint32_t invalid_enums;             /* unknown bridge selections sent as none */
  uint32_t bad_args;                  /* calls rejected with -CANFDI_EINVAL */
  uint32_t uds_frames;                /* UdsPhysResp frames encoded */
} canfdi_tx_diag_t;

/* The E2E protected frames' sender states in canfdi_tx_t.e2e[]. */
typedef enum {
  CANFDI_TX_E2E_DCM_ACT = 0,   /* 0x020 DcmActuator */
  CANFDI_TX_E2E_THR_ACT = 1,   /* 0x021 ThrActuator */
  CANFDI_TX_E2E_STATUS = 2,    /* 0x300 EcuStatus (its alive counter) */
  CANFDI_TX_E2E_DIAGNOSIS = 3, /* 0x301 EcuDiagnosis */
  CANFDI_TX_E2E_DTC = 4,       /* 0x310 EcuDtc, cyclic and on change */
  CANFDI_TX_E2E_COUNT = 5
} canfdi_tx_e2e_id_t;

/* Instance, caller-owned (static). Read diag directly. */
typedef struct {
  canfdi_e2e_tx_t e2e[CANFDI_TX_E2E_COUNT]; /* see canfdi_tx_e2e_id_t */
  uint8_t countdown[CANFDI_TX_F_COUNT];   /* steps until the frame is due */
  uint8_t q_head;                         /* next event to send */
  uint8_t q_len;                          /* queued events */
  canfdi_tx_dtc_t queue[CANFDI_CFG_TX_DTC_QUEUE];
  canfdi_tx_diag_t diag;
  bool initialised;
} canfdi_tx_t;

/* Schedule at its start (see the table), E2E counters 0, queue empty,
 * counters 0. Returns CANFDI_OK or -CANFDI_EINVAL (tx NULL). O(1). */
int canfdi_tx_init(canfdi_tx_t *tx);

/* Bit set of the frames (CANFDI_TX_F_*) the next canfdi_tx_step will send,
 * including CANFDI_TX_F_DTC_EVENT when an event is queued; 0 for an unusable
 * tx. Does not change anything. Cost: O(CANFDI_TX_F_COUNT). */
uint32_t canfdi_tx_due(const canfdi_tx_t *tx);

/*
 * One 1 ms step: encodes the frames due (canfdi_tx_due) from `data` into
 * out[0..n-1], in identifier order with the on-change DTC frame after the
 * cyclic frames, and advances the schedule. out must hold
 * CANFDI_TX_MAX_FRAMES_PER_STEP frames. Returns n >= 0, or -CANFDI_EINVAL
 * (a NULL argument or tx not initialised; nothing changes).
 * Cost: see the header.
 */
int canfdi_tx_step(canfdi_tx_t *tx, const canfdi_tx_data_t *data, canfdi_tx_frame_t *out);

/*
 * Queues an on-change EcuDtc frame (DtcTxReason = change), sent by the next
 * steps, one per step, in order. Returns CANFDI_OK, -CANFDI_ERANGE when the
 * queue is full (the record is dropped and counted), -CANFDI_EINVAL for a
 * NULL argument or an uninitialised tx. Cost: O(1).
 */
int canfdi_tx_dtc_event(canfdi_tx_t *tx, const canfdi_tx_dtc_t *rec);

/*
 * Encoders: one frame each into *out (id, dlc 8, data), CANFDI_OK or
 * -CANFDI_EINVAL (NULL argument or tx not initialised; *out untouched).
 * The encoders of E2E protected frames (actuators, status, diagnosis, DTC)
 * advance their frame's E2E counter; none touches the schedule. `change` selects DtcTxReason
 * (false cyclic, true change).
 */
int canfdi_tx_encode_dcm_act(canfdi_tx_t *tx, const canfdi_tx_dcm_act_t *v, canfdi_tx_frame_t *out);
int canfdi_tx_encode_thr_act(canfdi_tx_t *tx, const canfdi_tx_thr_act_t *v, canfdi_tx_frame_t *out);
int canfdi_tx_encode_res_dcm(canfdi_tx_t *tx, const canfdi_tx_res_dcm_t *v, canfdi_tx_frame_t *out);
int canfdi_tx_encode_res_thr(canfdi_tx_t *tx, const canfdi_tx_res_thr_t *v, canfdi_tx_frame_t *out);
int canfdi_tx_encode_status(canfdi_tx_t *tx, const canfdi_tx_status_t *v, canfdi_tx_frame_t *out);
int canfdi_tx_encode_diagnosis(canfdi_tx_t *tx, const canfdi_tx_diagnosis_t *v,
                               canfdi_tx_frame_t *out);
int canfdi_tx_encode_self_diag(canfdi_tx_t *tx, const canfdi_tx_self_diag_t *v,
                               canfdi_tx_frame_t *out);
int canfdi_tx_encode_dtc(canfdi_tx_t *tx, const canfdi_tx_dtc_t *v, bool change,
                         canfdi_tx_frame_t *out);
int canfdi_tx_encode_prm_dcm(canfdi_tx_t *tx, const canfdi_tx_param_dcm_t *v,
                             canfdi_tx_frame_t *out);
int canfdi_tx_encode_prm_thr(canfdi_tx_t *tx, const canfdi_tx_param_thr_t *v,
                             canfdi_tx_frame_t *out);

/*
 * UdsPhysResp (0x7E8): one ISO-TP frame of the diagnostic server
 * (comm/canfdi_isotp.h), its CANFDI_CFG_ISOTP_FRAME_BYTES bytes in bus
 * order, packed by the generated codec. Not part of the schedule: the
 * application adds it to a step's frames when the server has one (at most
 * one per step). CANFDI_OK or -CANFDI_EINVAL (NULL argument, tx not
 * initialised).
 */
int canfdi_tx_encode_uds_resp(canfdi_tx_t *tx, const uint8_t *isotp, canfdi_tx_frame_t *out);

#endif /* CANFDI_TX_H */
