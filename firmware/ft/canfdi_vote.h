/*
 * canfdi_vote.h — throttle position by 2-out-of-3 voting over the two
 * potentiometers TPS1, TPS2 and the model-based position estimate
 * (analytical redundancy, Isermann ch. 18–19), with outlier isolation.
 *
 * Sources (index, bit in the masks below):
 *   0 TPS1   voltage rising with the angle:   theta1 = (V1 - zero1) * gain1
 *   1 TPS2   voltage falling with the angle:  theta2 = (V2 - zero2) * gain2
 *            (gain2 < 0; with the design values zero1 0.5 V, zero2 4.5 V,
 *            gain1 = -gain2 = (pi/2) / 4 V = 0.3927 rad/V)
 *   2 MODEL  the observer's angle estimate (model/canfdi_parity_thr.h),
 *            already in rad.
 * All angles Q16.16 rad. A source takes part in the vote ("available")
 * when its input flag says valid (the caller clears it for a sensor known
 * bad: out of range, a confirmed DTC, an estimator not converged) AND this
 * module has not isolated it (see isolation below).
 *
 * Agreement: two sensors agree when |theta1 - theta2| <= tol_tps; a sensor
 * and the model agree when |theta_k - theta_model| <= tol_model (the model
 * has dynamic error, so its tolerance is the larger one). "<=" on both.
 *
 * Decision table. a12 = TPS1~TPS2, a1m = TPS1~MODEL, a2m = TPS2~MODEL;
 * "-" = don't care. Output angle, status, outlier of this step:
 *
 *   available     a12 a1m a2m | angle              status    outlier
 *   ------------------------------------------------------------------
 *   T1 T2 M        1   -   -  | mean(th1, th2)     THREE     MODEL if
 *                             |                              !a1m && !a2m
 *   T1 T2 M        0   1   1  | median of three    THREE     none (*1)
 *   T1 T2 M        0   1   0  | th1                THREE     TPS2
 *   T1 T2 M        0   0   1  | th2                THREE     TPS1
 *   T1 T2 M        0   0   0  | held (*2)          DISAGREE  none
 *   T1 T2          1          | mean(th1, th2)     TWO       none
 *   T1 T2          0          | held               DISAGREE  none
 *   T1 M               1      | th1                TWO       none
 *   T1 M               0      | held               DISAGREE  none
 *   T2 M                   1  | th2                TWO       none
 *   T2 M                   0  | held               DISAGREE  none
 *   any one                   | that source        SINGLE    none
 *   none                      | held               INVALID   none
 *
 * Why a sensor+model pair yields the sensor and not the mean: the model
 * confirms the measurement, it does not measure; its dynamic error (up to
 * tol_model during fast strokes) would otherwise enter the position loop.
 * (*1) Both sensors are within tol_model of the model but more than tol_tps
 * apart: the disagreement is real but the model cannot say which sensor is
 * wrong, so nobody is blamed and the mid-value (the model, as a rule) is
 * used; this is the "correlation fault, not isolated" case (P2135) that
 * the parity module reports. (*2) "held" = the last angle output;
 * 0 rad before the first decided vote. valid (= status THREE or TWO) says
 * whether the angle may close the position loop; a SINGLE angle is given
 * for information and for the limp-home transition only.
 *
 * Isolation. Each source has a Dem-style debouncer (core/canfdi_debounce.h)
 * fed once per decided vote (THREE or TWO): PREFAILED for the outlier,
 * PREPASSED for the other available sources. In the ambiguous row (*1) and
 * in DISAGREE / SINGLE / INVALID nothing is reported (no evidence either
 * way; counters hold). The debouncers count CONSECUTIVE outlier steps
 * (jump-up and jump-down to 0, step 1, passed threshold -1): a source that
 * is the outlier in isolate_steps consecutive reported steps is isolated
 * in the step of the last one (out.newly_isolated), and excluded from the
 * next step on; any agreeing step in between restarts the count, so
 * transient disagreements shorter than isolate_steps never isolate.
 * Isolation latches until canfdi_vote_clear() (a tester clear or a new
 * operation cycle — the same authority that clears the degradation state):
 * a drifting sensor that happens to pass through agreement is not
 * re-admitted. Separate step counts for the sensors and the model, because
 * the model may lag in fast strokes.
 *
 * Scaling and overflow: voltages to angles by the sensors' characteristics
 * (cfg.tps1/tps2, model/canfdi_tps.h): sat(V - zero) in Q16.16 times the
 * gain 1 / slope, which init rounds half up from canfdi_tps's Q8.24 value
 * to Q16.16 (for the default line (pi/2)/4 rad/V = 25736); the 64-bit
 * product is rounded half up to Q16.16 and saturated (canfdi_mul_s32_qn).
 * The angle is within 1 LSB (1.5e-5 rad) of canfdi_tps_V_to_rad_q16's. Differences of angles and
 * sums for the means are formed in int64 (exact), the means rounded half
 * up (canfdi_asr64_rnd by 1), so nothing overflows or wraps; a saturated
 * conversion (an absurd calibration) only makes that source disagree.
 *
 * Cost per canfdi_vote_step(): 2 conversions (one 32x32->64 multiply each:
 * __aeabi_lmul on Cortex-M0+), 3 differences and compares in 64 bits, up to
 * 3 debouncer steps (<= 74 instructions each on M0+). Measured executed
 * instructions (arm-none-eabi-gcc 12 -Os, QEMU mps2-an386 -icount, 4000
 * random votes over all validity patterns with isolations and clears,
 * min/mean/max incl. call overhead): Cortex-M0+ code 348 / 576 / 714,
 * Cortex-M4 194 / 330 / 422. Code: 1588 bytes (M0+). Stack: 104 bytes
 * (-fstack-usage, M0+) plus the debouncer's 16.
 * Memory: sizeof(canfdi_vote_t) = 156 bytes on a 32-bit target (the
 * configuration copy, two debounce configurations, three debouncers, the
 * diagnostics and the state). The instance holds pointers into itself (the debouncers'
 * configs): do not copy an instance after init. No heap, no globals.
 */
#ifndef CANFDI_VOTE_H
#define CANFDI_VOTE_H

#include "core/canfdi_common.h"
#include "core/canfdi_debounce.h"
#include "model/canfdi_tps.h"

#define CANFDI_VOTE_SRC_TPS1 0U
#define CANFDI_VOTE_SRC_TPS2 1U
#define CANFDI_VOTE_SRC_MODEL 2U
#define CANFDI_VOTE_N_SRC 3U

/* Masks of sources (used_mask, excluded_mask, isolated_mask, outlier_mask). */
#define CANFDI_VOTE_BIT_TPS1 0x01U
#define CANFDI_VOTE_BIT_TPS2 0x02U
#define CANFDI_VOTE_BIT_MODEL 0x04U

typedef enum {
  CANFDI_VOTE_INVALID = 0,  /* no source available: angle held */
  CANFDI_VOTE_SINGLE = 1,   /* one source available: its angle, not valid */
  CANFDI_VOTE_TWO = 2,      /* two available and agreeing */
  CANFDI_VOTE_THREE = 3,    /* three available, decided (maybe with outlier) */
  CANFDI_VOTE_DISAGREE = 4  /* two or three available, no agreeing pair */
} canfdi_vote_status_t;

/* Calibration (copied at init). Domain checked by canfdi_vote_init. */
typedef struct {
  canfdi_tps_cal_t tps1;        /* TPS1 characteristic, rising (model/canfdi_tps.h) */
  canfdi_tps_cal_t tps2;        /* TPS2 characteristic, falling */
  int32_t tol_tps_rad_q16;      /* > 0, sensor-sensor agreement */
  int32_t tol_model_rad_q16;    /* > 0, sensor-model agreement */
  uint16_t isolate_steps_tps;   /* 1..32767 consecutive outlier steps */
  uint16_t isolate_steps_model; /* 1..32767 */
} canfdi_vote_cfg_t;

typedef struct {
  int32_t tps1_V_q16;     /* TPS1 voltage, Q16.16 V */
  int32_t tps2_V_q16;     /* TPS2 voltage, Q16.16 V */
  int32_t model_rad_q16;  /* model estimate, Q16.16 rad */
  bool tps1_valid;
  bool tps2_valid;
  bool model_valid;
  bool model_no_blame; /* the model takes part but singles out no sensor:
                        * with the sensors apart and the model near one of
                        * them, the median of three, nobody blamed (as row
                        * (*1)). Set while the observer has no angle of its
                        * own (model/canfdi_parity_thr.h, no_ref): near a
                        * sensor only by its own drift. */
} canfdi_vote_in_t;

typedef struct {
  int32_t angle_rad_q16;                  /* voted angle (see table) */
  int32_t theta_rad_q16[CANFDI_VOTE_N_SRC]; /* each source as an angle */
  uint8_t status;         /* canfdi_vote_status_t */
  uint8_t n_available;    /* sources that voted this step, 0..3 */
  uint8_t used_mask;      /* sources the angle is formed from */
  uint8_t excluded_mask;  /* sources not voting: input invalid or isolated */
  uint8_t isolated_mask;  /* isolated by this module (latched) */
  uint8_t outlier_mask;   /* outlier of this step (0 or one bit) */
  uint8_t newly_isolated; /* isolated in this step (0 or one bit) */
  bool valid;             /* status is THREE or TWO */
} canfdi_vote_out_t;

/* Monotone counters, saturating at UINT32_MAX; only init zeroes them. */
typedef struct {
  uint32_t steps;
  uint32_t disagree_steps;
  uint32_t single_steps;
  uint32_t invalid_steps;
  uint32_t outlier_steps;  /* steps with an outlier (before debounce) */
  uint32_t isolations;     /* sources isolated */
  uint32_t clears;
} canfdi_vote_diag_t;

typedef struct {
  canfdi_vote_cfg_t cfg;
  int32_t zero_V_q16[2];          /* TPS1/TPS2 voltage at 0 rad, from cfg */
  int32_t rad_per_V_q16[2];       /* 1 / slope, Q16.16, from cfg at init */
  canfdi_debounce_cfg_t deb_cfg_tps;
  canfdi_debounce_cfg_t deb_cfg_model;
  canfdi_debounce_t deb[CANFDI_VOTE_N_SRC];
  int32_t last_angle_rad_q16;
  uint8_t isolated_mask;
  bool initialised;
  canfdi_vote_diag_t diag;
} canfdi_vote_t;

/*
 * Validate cfg (TPS1 rising, TPS2 falling, each a valid canfdi_tps
 * characteristic; tolerances > 0, step counts 1..32767) and reset v: nothing isolated, held angle 0,
 * diagnostics 0. Returns CANFDI_OK or -CANFDI_EINVAL (then v is unusable
 * and step() rejects it). Cost: O(1).
 */
int32_t canfdi_vote_init(canfdi_vote_t *v, const canfdi_vote_cfg_t *cfg);

/*
 * One vote (decision table and isolation above). Writes *out completely.
 * Returns CANFDI_OK, or -CANFDI_EINVAL for NULL arguments or an unusable
 * instance (then *out, if non-NULL, reports INVALID with everything
 * excluded and angle 0). Cost: see the header comment.
 */
int32_t canfdi_vote_step(canfdi_vote_t *v, const canfdi_vote_in_t *in, canfdi_vote_out_t *out);

/* Re-admit every isolated source and restart the debouncers (held angle
 * kept). For a tester clear or a new operation cycle. No-op on NULL or an
 * unusable instance. Cost: O(1). */
void canfdi_vote_clear(canfdi_vote_t *v);


/* Diagnostics snapshot (zero for NULL). Cost: O(1). */
canfdi_vote_diag_t canfdi_vote_diag(const canfdi_vote_t *v);

#endif /* CANFDI_VOTE_H */
