/*
 * canfdi_uds.h — the ECU's diagnostic server (ISO 14229-1:2020, UDS on
 * CAN) over its ISO-TP connection (comm/canfdi_isotp.h): sessions,
 * security, the trouble-code memory read and cleared from diag/canfdi_dtc
 * itself, live data, routines and an actuator test. It decides; the
 * application applies what it decided (canfdi_uds_act_t) in its step.
 *
 * Services and sub-functions (D default session, E extended; L1 unlocked
 * by SecurityAccess; F also on functional addressing 0x7DF). This table is
 * the permission table of canfdi_uds.c, in one place there:
 *   0x10 DiagnosticSessionControl  01 default, 03 extended     D E     F
 *        response 50 xx + P2 (cfg.p2_ms, 2 bytes, ms) + P2* (cfg.p2star_ms
 *        / 10, 2 bytes): the 2013+ form
 *   0x11 ECUReset                  01 hardReset               E       F
 *        only with the DC motor at rest (else 0x22); the response leaves,
 *        then act.ecu_reset asks the port to power the application down
 *        and up (NVM stored and loaded)
 *   0x14 ClearDiagnosticInformation                           D E     F
 *   0x19 ReadDTCInformation  01 02 03 04 06 0A 14             D E     F
 *        (uds/canfdi_uds_dtc.h: formats, records)
 *   0x22 ReadDataByIdentifier  1..cfg.max_dids DIDs           D E     F
 *        (uds/canfdi_uds_did.h); unknown DIDs are left out while at least
 *        one is known, else 0x31
 *   0x27 SecurityAccess  01/02 level 1 (03/04 level 2)        E
 *        (uds/canfdi_uds_sec.h: state machine, attempts, delay, key)
 *   0x28 CommunicationControl  00 enableRxAndTx, 01 enableRxAndDisableTx,
 *        communicationType 0x01 or 0x03 (normal messages; no network
 *        management here): the ECU's monitoring frames (0x200..0x321) stop;
 *        the actuator frames never do (they close the control loops)
 *                                                             E       F
 *   0x2F InputOutputControlByIdentifier  D104 speed reference,
 *        D115 throttle angle reference; parameter 00 returnControlToECU,
 *        03 shortTermAdjustment + 4-byte value (Q16.16, rad/s or rad)
 *                                                             E L1
 *   0x31 RoutineControl  01 start, 02 stop, 03 requestResults E L1
 *        0x0201 estimator reset (option byte: bit 0 DC motor, bit 1
 *        throttle): full reset to the nominal parameters after a repair;
 *        0x0202 throttle spring check (below)
 *   0x3E TesterPresent  00                                    D E     F
 * Not served: 0x85 ControlDTCSetting (the actuator manager takes the
 * communication faults from the DTC memory's testFailed bits, so a
 * memory that stops updating would blind the fault reaction), and every
 * other service (0x11 serviceNotSupported).
 *
 * NRC priority (ISO 14229-1:2020, general server response behaviour), the
 * first that applies: 0x11 service not supported; 0x7F not in the active
 * session; 0x33 service locked; for services with a sub-function: 0x13
 * shorter than 2 bytes, 0x12 sub-function not supported, 0x7E sub-function
 * not in the active session, 0x33 sub-function locked; then the service's
 * own checks in its order: 0x13 length, 0x31 identifier or parameter out of
 * range, 0x24 sequence, 0x22 conditions, 0x35/0x36/0x37 (0x27).
 * Suppress-positive-response (bit 7 of the sub-function) suppresses
 * positive responses only. Functional requests: no response for NRC 0x11,
 * 0x12, 0x31, 0x7E, 0x7F (the request does not concern this ECU) and none
 * for the physical-only services (0x27, 0x2F, 0x31).
 *
 * Session timing: S3 = cfg.s3_ms (5000): a non-default session without a
 * request for S3 falls back to default. Every session change (0x10 to any
 * session, the S3 fall-back, power-up) locks security, ends the actuator
 * test and the spring check, and enables the monitoring frames again.
 *
 * Safe state (the actuator test and the spring check start only in it):
 * no DTC with testFailed, both degradation states normal, the DC motor's
 * speed valid and |speed| and |speed setpoint| at most cfg.rest_rad_s_q16.
 * The actuator test ends by returnControlToECU, any session change, and
 * any new fault (a DTC testFailed or a degradation): checked every step.
 * Value limits: |speed| <= cfg.ioc_speed_max_rad_s_q16, angle within
 * [cfg.ioc_angle_min_rad_q16, cfg.ioc_angle_max_rad_q16], else 0x31.
 *
 * Throttle spring check (0x0202): the throttle is driven to
 * cfg.spring_open_rad_q16 for cfg.spring_open_ms, then released
 * (de-energised through the actuator manager's hold-off); the check times
 * how long the spring takes to bring the voted angle within
 * cfg.spring_band_rad_q16 of the limp-home angle. Passed when within
 * cfg.spring_pass_ms; failed when slower or not within cfg.spring_timeout_ms.
 * Results (03): status (0 running, 1 passed, 2 failed, 3 aborted), the
 * return time in ms (2 bytes), the last angle (Q16.16 rad, 4 bytes).
 * requestResults or stop of a routine never started: 0x24.
 *
 * One step (canfdi_uds_step, every 1 ms): timers (security delay, S3, the
 * actuator test's fault watch, the spring check), at most one request
 * answered (when no response is still being sent), then the ISO-TP step
 * (at most one frame). Cost: the timers O(1) (the fault watch O(DTCs)
 * while a test runs); a request O(DTCs) for 0x14/0x19, O(DIDs x
 * cfg.max_dids) for 0x22; measured in app/canfdi_app.h.
 * Memory: sizeof(canfdi_uds_t) = 740 bytes on Cortex-M (arm-none-eabi-gcc
 * 12; the ISO-TP instance 532 of them: 128 + 256 bytes of buffers, four
 * queued single frames, counters); `canfdi-sil --sizes` prints the host's.
 * Cost measured with the application (`make pil-test`, QEMU -icount,
 * -Os, over tests/sil/scenarios/uds_workshop.scn): the steps with a request
 * or response in flight take at most 39 938 instructions (Cortex-M4,
 * mps2-an386) / 84 096 (Cortex-M0, microbit), within the step's worst case
 * of the same run (42 083 / 86 851) and of the other PIL scenarios. No heap.
 */
#ifndef CANFDI_UDS_H
#define CANFDI_UDS_H

#include "comm/canfdi_isotp.h"
#include "core/canfdi_common.h"
#include "diag/canfdi_dtc.h"
#include "uds/canfdi_uds_did.h"
#include "uds/canfdi_uds_dtc.h"
#include "uds/canfdi_uds_msg.h"
#include "uds/canfdi_uds_sec.h"

typedef struct {
  canfdi_isotp_cfg_t tp;
  canfdi_uds_sec_cfg_t sec;
  canfdi_uds_ident_t ident;
  uint16_t p2_ms;                  /* P2server_max announced, 50 */
  uint16_t p2star_ms;              /* P2*server_max announced, 5000 (sent / 10) */
  uint16_t s3_ms;                  /* S3server, 5000 */
  uint8_t max_dids;                /* DIDs in one 0x22 request, 1..63 */
  int32_t rest_rad_s_q16;          /* safe state: motor at rest below this */
  int32_t ioc_speed_max_rad_s_q16; /* actuator test: largest |speed| */
  int32_t ioc_angle_min_rad_q16;   /* actuator test: angle window */
  int32_t ioc_angle_max_rad_q16;
  int32_t limp_home_rad_q16;       /* the throttle's limp-home angle */
  int32_t spring_open_rad_q16;     /* spring check: opening angle */
  int32_t spring_band_rad_q16;     /* spring check: "back" within this */
  uint16_t spring_open_ms;
  uint16_t spring_pass_ms;
  uint16_t spring_timeout_ms;
} canfdi_uds_cfg_t;

/* What the application applies in its step (canfdi_uds_step fills it). */
typedef struct {
  bool speed_override;         /* the actuator test drives the speed reference */
  int32_t speed_ref_rad_s_q16;
  bool angle_override;         /* ... the throttle angle reference */
  int32_t angle_ref_rad_q16;
  bool thr_release;            /* the spring check: throttle de-energised */
  uint8_t est_reset;           /* bit 0 DC motor, bit 1 throttle: reset now */
  bool tx_silent;              /* 0x28: monitoring frames off */
  bool ecu_reset;              /* the response left: reset the application */
} canfdi_uds_act_t;

/* Monotone counters, saturating at UINT32_MAX. */
typedef struct {
  uint32_t requests;
  uint32_t positive;
  uint32_t negative;
  uint32_t suppressed;     /* positive responses suppressed (bit 7) */
  uint32_t func_silent;    /* functional requests left unanswered */
  uint32_t s3_timeouts;
  uint32_t ioc_fault_ends; /* actuator tests ended by a fault */
} canfdi_uds_diag_t;

typedef enum {
  CANFDI_UDS_RT_NONE = 0xFF,
  CANFDI_UDS_RT_RUNNING = 0,
  CANFDI_UDS_RT_PASSED = 1,
  CANFDI_UDS_RT_FAILED = 2,
  CANFDI_UDS_RT_ABORTED = 3
} canfdi_uds_rt_status_t;

typedef struct {
  canfdi_uds_cfg_t cfg;
  canfdi_isotp_t tp;
  canfdi_uds_sec_t sec;
  uint32_t steps;          /* steps since init; wraps by intent: it only stirs the seeds */
  uint16_t s3_left_ms;
  uint8_t session;
  bool tx_silent;
  bool reset_pending;
  bool speed_on;
  bool angle_on;
  int32_t speed_rad_s_q16;
  int32_t angle_rad_q16;
  uint8_t est_reset;       /* pending for the next act */
  uint8_t est_status;      /* canfdi_uds_rt_status_t of 0x0201 */
  uint8_t spring_status;   /* canfdi_uds_rt_status_t of 0x0202 */
  uint8_t spring_phase;    /* 0 idle, 1 open, 2 released */
  uint16_t spring_ms;
  uint16_t spring_return_ms;
  int32_t spring_angle_rad_q16;
  canfdi_uds_diag_t diag;
  bool initialised;
} canfdi_uds_t;

/* The defaults of the header (identification strings "canfdi", blank). */
void canfdi_uds_default_cfg(canfdi_uds_cfg_t *cfg);

/* Default session, locked, idle; the security attempt counter from NVM
 * (0 for none) and the port's entropy. Returns CANFDI_OK or -CANFDI_EINVAL
 * (NULL, a configuration outside its domain). O(1). */
int32_t canfdi_uds_init(canfdi_uds_t *u, const canfdi_uds_cfg_t *cfg, uint8_t sec_attempts,
                        uint32_t entropy);

/* A received UDS frame (physical 0x7E0 or functional 0x7DF), to ISO-TP.
 * Returns the canfdi_isotp_rx_can result. */
int32_t canfdi_uds_rx_can(canfdi_uds_t *u, bool functional, const uint8_t *data, uint8_t dlc);

/*
 * One 1 ms step (see the header). dtc is the memory the services read and
 * clear; src the application's values of this step. Fills *act and writes
 * at most one ISO-TP frame (CANFDI_CFG_ISOTP_FRAME_BYTES bytes) into frame:
 * returns 1 if so, 0 if none, -CANFDI_EINVAL for a NULL argument.
 */
int32_t canfdi_uds_step(canfdi_uds_t *u, canfdi_dtc_t *dtc, const canfdi_uds_src_t *src,
                        canfdi_uds_act_t *act, uint8_t frame[CANFDI_CFG_ISOTP_FRAME_BYTES]);

/* The failed-key counter to keep in NVM, and its change count (wraps). */
uint8_t canfdi_uds_sec_attempts(const canfdi_uds_t *u);
uint32_t canfdi_uds_nvm_changes(const canfdi_uds_t *u);

/* The active session (CANFDI_UDS_SESSION_*), 0 for NULL. */
uint8_t canfdi_uds_session(const canfdi_uds_t *u);

#endif /* CANFDI_UDS_H */
