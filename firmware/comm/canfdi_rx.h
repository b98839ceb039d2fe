/*
 * canfdi_rx.h — input supervision of the ECU: every received CAN frame goes
 * through here, and once per 1 ms step the module hands the application a
 * validated input set and a monitor report for the trouble-code memory.
 *
 * What it supervises (Isermann, Fault-Diagnosis Systems, ch. 19.3, and
 * AUTOSAR E2E/COM practice):
 *
 *   frame        id     cycle  checks
 *   DcmSensor    0x010  1 ms   length, E2E CRC, E2E counter, raw range, timeout
 *   ThrSensor    0x011  1 ms   length, E2E CRC, E2E counter, raw range, timeout
 *   SetpointDcm  0x100  10 ms  length, E2E CRC, E2E counter, raw range, timeout
 *   SetpointThr  0x101  10 ms  length, E2E CRC, E2E counter, raw range, timeout
 * Every supervised frame is E2E protected (comm/canfdi_e2e.h, data ID = the
 * CAN identifier): a corrupted or forged setpoint (a throttle setpoint
 * opens the valve) is rejected exactly like a corrupted sensor frame.
 * Every other identifier is counted (diag.unknown_id) and ignored; its data
 * is never read. Cycle times come from the DBC (CANFDI_MSG_*_CYCLE_TIME_MS);
 * all packing and unpacking goes through the generated codec
 * (comm/gen/canfdi_msg.h), plausibility through comm/gen/canfdi_raw_limits.h,
 * and raw -> Q16.16 SI through the integer constants of
 * comm/gen/canfdi_sig_conv.h (no float anywhere).
 *
 * Per received frame, canfdi_rx_frame() judges in this order and stops at
 * the first failure:
 *   1. length: DLC must be 8 (the DBC length)           -> monitor LENGTH
 *   2. CRC (canfdi_e2e_check)                            -> monitor CRC
 *   3. counter: REPEATED or WRONG_SEQUENCE (jump beyond  -> monitor COUNTER
 *      max_delta) reject the frame
 *   4. raw range of each signal against canfdi_raw_limits.h -> IMPLAUSIBLE
 *      (setpoints: RANGE). Judged per signal: an implausible signal is
 *      rejected, the plausible signals of the same frame are accepted.
 * A monitor that ran on a frame reports pre-passed, a monitor that saw its
 * symptom pre-failed; monitors after the failing one do not run (no
 * verdict). A frame whose length or CRC is wrong tells nothing about its
 * counter, so the sequence check restarts with the next frame that passes
 * (E2E INITIAL) instead of flagging the jump those frames leave; the same
 * after a timeout. A lost communication therefore shows as TIMEOUT only, a
 * CRC burst as CRC only (fault isolation, catalogue faults 22..31).
 * A second sender on a supervised identifier (its own counter sequence
 * interleaved with the genuine one) shows as counter errors: after each
 * WRONG_SEQUENCE the check resynchronises to the frame just seen, so the
 * next frame of the other sequence is out of sequence again.
 *
 * Timeout (canfdi_rx_step): a frame times out when no frame with its id —
 * whatever its content — arrived for timeout_cycles cycle times:
 *   now_us - last_reception_us >= timeout_cycles * cycle_us.
 * With frames time-stamped no later than the step that consumes them (the
 * normal case: a frame is received before the step), that is exactly the
 * step at which the timeout_cycles-th consecutive frame is missing: with the
 * default 4 for the 1 ms frames, frames up to t, nothing after -> steps
 * t+1..t+3 ms pre-passed, t+4 ms pre-failed; the setpoints' default is 5
 * cycles (50 ms). Before the first reception the
 * supervision runs from init with the window first_timeout_us when that is
 * longer (startup timeout; AUTOSAR COM's "first timeout": the other nodes
 * of a bus boot at their own pace, so an ECU that starts before its sensor
 * node must not latch a communication fault for it), else the same window. A timed-out
 * frame is latched until its next reception, so a uint32_t time stamp
 * wrapping (71 min) cannot clear it. The timeout monitor reports every step
 * once the frame was received at least once or has timed out (no verdict
 * during the startup window).
 *
 * Validated inputs (rx->in[], published by canfdi_rx_step; Q16.16 SI):
 *   CANFDI_RX_IN_DCM_UA V, _DCM_IA A, _DCM_OMEGA rad/s, _DCM_USUPPLY V,
 *   _THR_TPS1 V, _THR_TPS2 V, _THR_IMOT A, _THR_USUPPLY V,
 *   _SP_DCM_SPEED rad/s, _SP_DCM_LOAD N m (the vehicle's known load
 *   torque, SetpointDcm.SpDcmLoad), _SP_THR_ANGLE rad (the DBC sends
 *   degrees). The two SetpointDcm signals are range-checked one by one:
 *   an implausible load is rejected (the input goes into error) while a
 *   plausible speed of the same frame is taken, and vice versa. What to use
 *   in place of a lost or rejected load is the application's choice
 *   (canfdi_app: the calibrated nominal load via canfdi_rx_set_estimate).
 * Quality of each input, decided per step:
 *   VALID        the last accepted value, no error since (or recovered),
 *                frame not timed out. `fresh` says a new sample arrived since
 *                the previous step, `samples` how many (2 or more when a
 *                frame came early; the value is the last one's) (a 1 ms
 *                input is VALID but not fresh for
 *                the steps in which its frame is late but not timed out).
 *   SUBSTITUTED  the input is in error (a rejected frame or signal, a
 *                timeout, or still recovering) and a stand-in is available:
 *                the model estimate the application supplied for this step
 *                with canfdi_rx_set_estimate(), else the last valid value if
 *                it is younger than the timeout window.
 *   INVALID      in error and no stand-in: the last valid value is older than
 *                the timeout window (or none since init) and no estimate was
 *                supplied. The value is then the last valid one (or
 *                cfg.default_q16 before the first) — never data of a
 *                rejected frame: the application must not use it for
 *                control, but it is a defined number.
 * Recovery: after an error an input returns to VALID once recover_frames
 * consecutive samples of it were accepted (default 3 for the 1 ms frames,
 * 1 for the setpoints).
 * Setpoints in error (canfdi_app decides what follows; docs/design.md,
 * "Setpoint supervision"): a rejected setpoint frame (length, CRC, counter,
 * range) or a missing one leaves the last accepted setpoint SUBSTITUTED,
 * i.e. held, while it is younger than the timeout window (5 cycles = 50 ms
 * after its acceptance); after that the input is INVALID and the
 * application applies its safe reaction. The next accepted frame makes it
 * VALID again (recover_frames 1). At start-up nothing is in error: an input is
 * INVALID (default value) until its first accepted sample, then VALID —
 * unless the startup timeout expired first, which is an error like any
 * other timeout (recover_frames apply).
 * Estimates are one-shot: canfdi_rx_step consumes them, so a stale estimate
 * is never used.
 *
 * Monitor report (rx->report, published by canfdi_rx_step): for each
 * monitor m (canfdi_rx_mon_t) bit m of `prefailed` (symptom seen in at least
 * one frame or by the timeout check since the previous step) or of
 * `prepassed` (ran and saw nothing), never both; neither = no verdict. These
 * are raw, undebounced per-step results: feed them to one canfdi_debounce_t
 * per DTC (canfdi_rx_monitor_result() returns the canfdi_deb_report_t), do
 * not debounce here again. Monitors 0..9 are the catalogue's communication
 * faults 22..31 in catalogue order (canfdi_rx_monitor_fault_id(),
 * canfdi_rx_monitor_dtc(): U1A00/U1A01 timeout, U1A10/11 counter, U1A20/21
 * CRC, U1A30/31 length, U1A40/41 implausible; DCM first). Monitors 10..19
 * supervise the setpoints, which have no catalogue fault (the simulator
 * injects none) but two trouble codes of their own, per source node (the
 * vehicle controller) as J2012 has them: the two timeouts report to U1A50
 * (lost communication), the length, CRC, counter and range monitors of both
 * frames to U1A51 (invalid data). Monitors sharing a code are combined per
 * step by the DTC routing (diag/canfdi_dtcroute.h: a failure dominates).
 *
 * Use, once per 1 ms step:
 *   for each received frame: canfdi_rx_frame(&rx, id, data, dlc, t_rx_us);
 *   optionally canfdi_rx_set_estimate(&rx, CANFDI_RX_IN_..., model_q16);
 *   canfdi_rx_step(&rx, now_us);
 *   read the inputs with canfdi_rx_valid/usable/fresh/value, feed rx.report
 *   to the DTC memory.
 *
 * Scaling and overflow: raw -> Q16.16 with canfdi_rx_raw_to_q16() (int64_t
 * accumulator, half-up rounding, saturation to int32_t; every input within
 * one Q16.16 LSB of exact, see canfdi_sig_conv.h). Times are
 * uint32_t microseconds, differences taken modulo 2^32 and read as signed,
 * so a frame stamped up to 35 min after the step counts as age 0; windows
 * are at most 255 cycles (2.55 s for 10 ms frames). Counters saturate.
 *
 * Cost: executed instructions per call, measured on QEMU mps2-an386 with
 * -icount (SysTick), arm-none-eabi-gcc 12 -Os, min / mean / max over
 * 2000 calls with random plausible values and injected errors; the M0+
 * build runs its ARMv6-M code on the same emulated core, so these are
 * instruction counts, not cycles (max is the largest seen, not a proof):
 *                                        Cortex-M4          Cortex-M0+
 *   canfdi_rx_frame, sensor accepted     641 / 659 / 782    971 / 994 / 1133
 *     (E2E CRC over 9 bytes, generated unpack, 4 range checks, 4 64-bit
 *     conversions)
 *   canfdi_rx_frame, sensor implausible  710                1005
 *   canfdi_rx_frame, CRC error           266                320
 *   canfdi_rx_frame, length error        131                161
 *   canfdi_rx_frame, setpoint            171                262
 *     (before the setpoints were E2E protected; now a setpoint frame pays
 *     the E2E check of a sensor frame plus 1..2 conversions: not
 *     re-measured)
 *   canfdi_rx_frame, unknown id          43                 57
 *   canfdi_rx_step                       638 / 672 / 765    866 / 891 / 1013
 *   canfdi_rx_raw_to_q16                 55                 102
 * A 1 ms cycle with both sensor frames (and a setpoint every 10 ms) costs
 * about 2000 (M4) / 2900 (M0+) instructions. No division anywhere; 64-bit
 * multiplies call __aeabi_lmul on M0+.
 * Memory: sizeof(canfdi_rx_t) = 804 bytes on Cortex-M (204 of them
 * the diagnostics, 176 the four E2E receivers with their counters); code
 * 2.9 kB (-Os, M0+ and M4); stack: canfdi_rx_frame 48 + 88 bytes plus the
 * E2E check and the generated unpack (-fstack-usage). No heap, no
 * recursion.
 */
#ifndef CANFDI_RX_H
#define CANFDI_RX_H

#include "comm/canfdi_e2e.h"
#include "core/canfdi_common.h"
#include "core/canfdi_debounce.h"

/* Supervised frames. */
typedef enum {
  CANFDI_RX_F_DCM_SENSOR = 0, /* 0x010, 1 ms, E2E */
  CANFDI_RX_F_THR_SENSOR = 1, /* 0x011, 1 ms, E2E */
  CANFDI_RX_F_SP_DCM = 2,     /* 0x100, 10 ms, E2E */
  CANFDI_RX_F_SP_THR = 3,     /* 0x101, 10 ms, E2E */
  CANFDI_RX_F_COUNT = 4
} canfdi_rx_frame_id_t;

#define CANFDI_RX_F_E2E_COUNT 4U /* frames 0..3: every supervised frame is E2E protected */

/* The validated input set; values Q16.16 in the unit given. */
typedef enum {
  CANFDI_RX_IN_DCM_UA = 0,      /* armature voltage U_A, V */
  CANFDI_RX_IN_DCM_IA = 1,      /* armature current I_A, A */
  CANFDI_RX_IN_DCM_OMEGA = 2,   /* rotor speed, rad/s */
  CANFDI_RX_IN_DCM_USUPPLY = 3, /* bridge supply, V */
  CANFDI_RX_IN_THR_TPS1 = 4,    /* throttle position sensor 1, V */
  CANFDI_RX_IN_THR_TPS2 = 5,    /* throttle position sensor 2, V */
  CANFDI_RX_IN_THR_IMOT = 6,    /* throttle motor current, A */
  CANFDI_RX_IN_THR_USUPPLY = 7, /* throttle supply, V */
  CANFDI_RX_IN_SP_DCM_SPEED = 8, /* speed setpoint, rad/s */
  CANFDI_RX_IN_SP_DCM_LOAD = 9,  /* known load torque (feed-forward), N m */
  CANFDI_RX_IN_SP_THR_ANGLE = 10, /* throttle angle setpoint, rad */
  CANFDI_RX_IN_COUNT = 11
} canfdi_rx_input_id_t;

typedef enum {
  CANFDI_RX_VALID = 0,
  CANFDI_RX_SUBSTITUTED = 1,
  CANFDI_RX_INVALID = 2
} canfdi_rx_quality_t;

typedef struct {
  int32_t value_q16; /* never data of a rejected frame (see the header) */
  uint8_t quality;   /* canfdi_rx_quality_t */
  bool fresh;        /* VALID and a new sample arrived since the last step */
  uint8_t samples;   /* VALID: samples accepted since the last step (saturating;
                      * more than 1: a frame came early, the one before it is
                      * lost to this input); else 0 */
} canfdi_rx_input_t;

/* Monitors; 0..9 in the order of catalogue faults 22..31. */
typedef enum {
  CANFDI_RX_MON_DCM_TIMEOUT = 0,     /* U1A00 */
  CANFDI_RX_MON_THR_TIMEOUT = 1,     /* U1A01 */
  CANFDI_RX_MON_DCM_COUNTER = 2,     /* U1A10 */
  CANFDI_RX_MON_THR_COUNTER = 3,     /* U1A11 */
  CANFDI_RX_MON_DCM_CRC = 4,         /* U1A20 */
  CANFDI_RX_MON_THR_CRC = 5,         /* U1A21 */
  CANFDI_RX_MON_DCM_LENGTH = 6,      /* U1A30 */
  CANFDI_RX_MON_THR_LENGTH = 7,      /* U1A31 */
  CANFDI_RX_MON_DCM_IMPLAUSIBLE = 8, /* U1A40 */
  CANFDI_RX_MON_THR_IMPLAUSIBLE = 9, /* U1A41 */
  CANFDI_RX_MON_SP_DCM_TIMEOUT = 10, /* U1A50 (no catalogue fault) */
  CANFDI_RX_MON_SP_THR_TIMEOUT = 11, /* U1A50 */
  CANFDI_RX_MON_SP_DCM_LENGTH = 12,  /* U1A51 */
  CANFDI_RX_MON_SP_THR_LENGTH = 13,  /* U1A51 */
  CANFDI_RX_MON_SP_DCM_RANGE = 14,   /* U1A51 */
  CANFDI_RX_MON_SP_THR_RANGE = 15,   /* U1A51 */
  CANFDI_RX_MON_SP_DCM_COUNTER = 16, /* U1A51 */
  CANFDI_RX_MON_SP_THR_COUNTER = 17, /* U1A51 */
  CANFDI_RX_MON_SP_DCM_CRC = 18,     /* U1A51 */
  CANFDI_RX_MON_SP_THR_CRC = 19,     /* U1A51 */
  CANFDI_RX_MON_COUNT = 20
} canfdi_rx_mon_t;

typedef struct {
  uint32_t prefailed; /* bit m: monitor m saw its symptom this step */
  uint32_t prepassed; /* bit m: monitor m ran and saw nothing; & prefailed == 0 */
} canfdi_rx_report_t;

/* What canfdi_rx_frame() made of one frame (>= 0). */
typedef enum {
  CANFDI_RX_ACCEPTED = 0,    /* every signal taken */
  CANFDI_RX_UNKNOWN_ID = 1,  /* not a supervised frame; ignored */
  CANFDI_RX_BAD_LENGTH = 2,  /* rejected: DLC != 8 */
  CANFDI_RX_BAD_CRC = 3,     /* rejected: E2E CRC */
  CANFDI_RX_BAD_COUNTER = 4, /* rejected: counter repeated or jumped */
  CANFDI_RX_IMPLAUSIBLE = 5  /* some signal out of its raw range and rejected;
                                the plausible ones were taken */
} canfdi_rx_result_t;

typedef struct {
  uint8_t timeout_cycles; /* 1..255 missed cycles until timeout */
  uint8_t recover_frames; /* 1..255 accepted samples after an error until VALID */
  uint8_t max_delta;      /* 1..15 largest counter step still usable */
} canfdi_rx_frame_cfg_t;

typedef struct {
  canfdi_rx_frame_cfg_t frame[CANFDI_RX_F_COUNT];
  int32_t default_q16[CANFDI_RX_IN_COUNT]; /* INVALID value before the first sample */
  uint32_t first_timeout_us; /* timeout window before a frame's first reception
                                if longer than its normal window (0: none) */
} canfdi_rx_cfg_t;

/* Monotone counters, saturating at UINT32_MAX. */
typedef struct {
  uint32_t frames;                         /* canfdi_rx_frame calls with valid arguments */
  uint32_t unknown_id;                     /* frames with an unsupervised id */
  uint32_t bad_args;                       /* calls rejected with -CANFDI_EINVAL */
  uint32_t steps;                          /* canfdi_rx_step calls */
  uint32_t accepted[CANFDI_RX_F_COUNT];    /* frames with every signal taken */
  uint32_t length_err[CANFDI_RX_F_COUNT];  /* frames with DLC != 8 */
  uint32_t crc_err[CANFDI_RX_F_COUNT];     /* frames with a wrong CRC */
  uint32_t counter_err[CANFDI_RX_F_COUNT]; /* frames repeated or out of sequence */
  uint32_t implausible[CANFDI_RX_F_COUNT]; /* frames with >= 1 signal out of range */
  uint32_t timeouts[CANFDI_RX_F_COUNT];    /* transitions into timeout */
  uint32_t substituted[CANFDI_RX_IN_COUNT]; /* steps an input was SUBSTITUTED */
  uint32_t invalid[CANFDI_RX_IN_COUNT];     /* steps an input was INVALID */
  uint32_t estimates_used;                  /* SUBSTITUTED steps that used an estimate */
} canfdi_rx_diag_t;

/* Internal state of one frame and one input; read-only for the caller. */
typedef struct {
  uint32_t last_rx_us; /* last reception of the id (any content), or init time */
  bool received;       /* at least one reception since init */
  bool timed_out;      /* latched by step, cleared by the next reception */
  bool resync;         /* E2E sequence check restarts with the next good frame */
} canfdi_rx_frame_state_t;

typedef struct {
  int32_t last_q16;    /* last accepted value */
  uint32_t last_ok_us; /* when it was accepted */
  uint8_t good_run;    /* accepted samples since the last error (saturating) */
  bool has_value;      /* a sample was accepted since init */
  bool in_error;       /* set by an error, cleared after recover_frames samples */
  bool stale;          /* last sample older than the timeout window (latched) */
  bool fresh;          /* accepted since the last step */
  uint8_t samples;     /* accepted since the last step (saturating) */
} canfdi_rx_signal_state_t;

/* Instance, caller-owned (static). Read the inputs through
 * canfdi_rx_valid/usable/fresh/value below, report and diag directly;
 * change the rest only through the functions. */
typedef struct {
  canfdi_rx_cfg_t cfg;
  canfdi_e2e_rx_t e2e[CANFDI_RX_F_E2E_COUNT];
  canfdi_rx_frame_state_t frame[CANFDI_RX_F_COUNT];
  canfdi_rx_signal_state_t sig[CANFDI_RX_IN_COUNT];
  int32_t estimate_q16[CANFDI_RX_IN_COUNT];
  uint32_t estimate_mask; /* bit i: estimate_q16[i] supplied for the next step */
  canfdi_rx_report_t acc; /* results gathered since the last step */
  canfdi_rx_report_t report;                /* published by the last step */
  canfdi_rx_input_t in[CANFDI_RX_IN_COUNT]; /* published by the last step */
  canfdi_rx_diag_t diag;
  bool initialised;
} canfdi_rx_t;

/* Defaults (see the header): sensors timeout 4 cycles, recovery 3 frames;
 * setpoints timeout 5 cycles (50 ms: how long a setpoint in error is held),
 * recovery 1; max_delta 2 for all (one lost frame tolerated); default
 * values 0. Cannot fail by contract (no-op on NULL). */
void canfdi_rx_default_cfg(canfdi_rx_cfg_t *cfg);

/*
 * Copies cfg, resets every state and counter; supervision (startup timeout)
 * runs from now_us; every input INVALID with its default value until the
 * first step. Returns CANFDI_OK or -CANFDI_EINVAL (NULL, or a field out of
 * its domain; rx is then unusable). Cost: O(size of the instance).
 */
int canfdi_rx_init(canfdi_rx_t *rx, const canfdi_rx_cfg_t *cfg, uint32_t now_us);

/*
 * Judges one received frame (see the header): id the CAN identifier
 * (anything other than the four supervised 11-bit ids is unknown, including
 * ids with flag bits set), data its payload, dlc its byte count (0..8 for
 * classic CAN; any value other than 8 is a length error, the data is then
 * not read), now_us its reception time. data may be NULL only if dlc == 0.
 * Returns a canfdi_rx_result_t (>= 0), or -CANFDI_EINVAL (rx NULL or not
 * initialised, or data NULL with dlc > 0; counted in diag.bad_args when rx
 * is usable). Cost: see the header.
 */
int canfdi_rx_frame(canfdi_rx_t *rx, uint32_t id, const uint8_t *data, uint8_t dlc,
                    uint32_t now_us);

/*
 * Supplies a model estimate of one input for the next canfdi_rx_step only
 * (a later call for the same input overwrites it). It is used when the
 * input is not VALID, in preference to the held value. Returns CANFDI_OK or
 * -CANFDI_EINVAL (rx unusable or input out of range). Cost: O(1).
 */
int canfdi_rx_set_estimate(canfdi_rx_t *rx, unsigned input, int32_t value_q16);

/*
 * The 1 ms step at time now_us: timeout supervision of each frame, quality
 * and value of each input (rx->in[]), the monitor report of the frames
 * received since the previous step plus the timeout verdicts (rx->report);
 * consumes the estimates. Returns CANFDI_OK or -CANFDI_EINVAL (rx unusable).
 * Cost: see the header.
 */
int canfdi_rx_step(canfdi_rx_t *rx, uint32_t now_us);

/*
 * The verdicts of the last canfdi_rx_step on input i (CANFDI_RX_IN_*), the
 * way the rest of the firmware reads them:
 *   canfdi_rx_valid    VALID (a measured, accepted, recent value)
 *   canfdi_rx_usable   VALID or SUBSTITUTED (a value fit for control)
 *   canfdi_rx_fresh    VALID and a new sample arrived since the last step
 *   canfdi_rx_samples  VALID: how many (2 or more: a frame came early)
 *   canfdi_rx_value    the value (defined for every quality, see above)
 * i must be < CANFDI_RX_IN_COUNT (asserted); before the first step every
 * input is INVALID with its default value. Cost: O(1), inline.
 */
static inline bool canfdi_rx_valid(const canfdi_rx_t *rx, unsigned i)
{
  CANFDI_ASSERT((rx != NULL) && (i < (unsigned)CANFDI_RX_IN_COUNT));
  return rx->in[i].quality == (uint8_t)CANFDI_RX_VALID;
}

static inline bool canfdi_rx_usable(const canfdi_rx_t *rx, unsigned i)
{
  CANFDI_ASSERT((rx != NULL) && (i < (unsigned)CANFDI_RX_IN_COUNT));
  return rx->in[i].quality != (uint8_t)CANFDI_RX_INVALID;
}

static inline bool canfdi_rx_fresh(const canfdi_rx_t *rx, unsigned i)
{
  CANFDI_ASSERT((rx != NULL) && (i < (unsigned)CANFDI_RX_IN_COUNT));
  return rx->in[i].fresh;
}

static inline uint8_t canfdi_rx_samples(const canfdi_rx_t *rx, unsigned i)
{
  CANFDI_ASSERT((rx != NULL) && (i < (unsigned)CANFDI_RX_IN_COUNT));
  return rx->in[i].samples;
}

static inline int32_t canfdi_rx_value(const canfdi_rx_t *rx, unsigned i)
{
  CANFDI_ASSERT((rx != NULL) && (i < (unsigned)CANFDI_RX_IN_COUNT));
  return rx->in[i].value_q16;
}

/*
 * Result of monitor `mon` in the last step, ready for canfdi_debounce_step:
 * CANFDI_DEB_REPORT_PREFAILED or CANFDI_DEB_REPORT_PREPASSED (>= 0), or
 * -CANFDI_ENODATA (no verdict this step), -CANFDI_EINVAL (rx NULL or mon out
 * of range). Cost: O(1).
 */
int canfdi_rx_monitor_result(const canfdi_rx_t *rx, unsigned mon);

/* Catalogue fault id of a monitor (CANFDI_FAULT_COM_*), 0 (none) for the
 * setpoint monitors and for mon out of range. Cost: O(1). */
uint8_t canfdi_rx_monitor_fault_id(unsigned mon);

/* ISO 14229-1 3-byte DTC of a monitor (CANFDI_DTC_U1A*): the sensor
 * monitors' from their catalogue fault, U1A50 for the setpoint timeouts,
 * U1A51 for the other setpoint monitors; 0 for mon out of range.
 * Cost: O(1), a table lookup in canfdi_catalogue_fault[]. */
uint32_t canfdi_rx_monitor_dtc(unsigned mon);

/*
 * raw -> Q16.16 with the integer constants of canfdi_sig_conv.h:
 * round_half_up((raw * scale_q32 + offset_q32) / 2^16), saturated to
 * int32_t. Scaling and overflow: int64_t accumulator; scale_q32 is clamped
 * to [-(2^32 - 1), 2^32] (|scale| <= 1, which covers every signal of
 * canfdi.dbc), so the product cannot overflow for any int32_t raw, and the
 * offset is added with saturation: total by contract, no undefined
 * behaviour for any argument. Accuracy with generated constants: within
 * (|raw| + 1) / 2^17 + 1/2 Q16.16 LSB of exact, i.e. < 1 LSB for raw
 * values up to 16 bits. Cost: one 64 x 64 multiply (__aeabi_lmul on M0+)
 * and a rounding shift: 55 (M4) / 102 (M0+) instructions per call, measured.
 */
int32_t canfdi_rx_raw_to_q16(int32_t raw, int64_t scale_q32, int64_t offset_q32);

#endif /* CANFDI_RX_H */
