/*
 * canfdi_cusum.h — two-sided tabular CUSUM change detector (Page 1954; the
 * tabular form of Montgomery, Introduction to Statistical Quality Control,
 * ch. 9), as used for change detection of residuals and features in
 * Isermann, Fault-Diagnosis Systems, ch. 7.
 *
 * The detector watches a signal x (LSB) whose in-control mean mu0 and
 * standard deviation sigma are known (e.g. from canfdi_meanvar over a
 * fault-free learning phase). With the reference value K = k*sigma and the
 * decision interval H = h*sigma (k, h in units of sigma, the way ARL tables
 * are published):
 *
 *   S_hi(n) = max(0, S_hi(n-1) + (x(n) - mu0) - K)     upward shift
 *   S_lo(n) = max(0, S_lo(n-1) - (x(n) - mu0) - K)     downward shift
 *
 * and an alarm is raised on the first sample where S_hi > H or S_lo > H.
 * N_hi / N_lo count the consecutive samples on which the sum has been
 * non-zero. At an alarm on sample n_a, Montgomery's change-point estimate is
 * n_a - N: the last sample at which the alarming sum was zero; the first
 * sample affected by the change is estimated as n_a - N + 1. The new mean is
 * estimated as mu0 +- (K + S/N). (With a head start, N counts from the
 * restart, so the estimate is never earlier than the restart, and S/N
 * includes head_start/N.) The estimate is late only if the sum returned to
 * zero after the change, and early when the sum was in an in-control
 * excursion when the change came; see test_cusum.c for its distribution.
 *
 * Verified (tests/unit/test_cusum.c, Monte Carlo with N(delta, 1) samples
 * at sigma = 4096 LSB, 3200 runs per case, zero start): k = 0.5 gives ARLs
 * within 3 % of the published two-sided values (Montgomery Table 9.3:
 * 168 / 465 in control for h = 4 / 5; 8.38 / 10.4 for a 1 sigma shift).
 *
 * Why mu0 and sigma go in at init instead of a pre-normalised input
 * z = (x - mu0)/sigma: normalising costs a division per sample (no divider
 * on Cortex-M0+) and a rounding; here k and h are scaled to signal units
 * once at init, and each step is two 64-bit add/compare chains. A caller
 * that already has z just passes mu0 = 0 and sigma = its Q scale (e.g.
 * z in Q12: sigma_q10 = 2^22).
 *
 * Sample index: every canfdi_cusum_step call advances an index (1 for the
 * first sample after init). It wraps modulo 2^32 by design (49.7 days at
 * 1 kHz); alarm_step and change_step are on that index, so compare them
 * with unsigned modular differences.
 *
 * Restart after an alarm (cfg.restart):
 *   CANFDI_CUSUM_RESTART_AUTO  both sums restart at the head start on the
 *       sample after the alarm, so the next run length counts from there
 *       (the convention behind published ARLs). A persisting fault then
 *       re-alarms after about one out-of-control run length.
 *   CANFDI_CUSUM_RESTART_LATCH the detector freezes (sums, counters and the
 *       alarm record stay as at the alarm; samples only advance the index)
 *       until canfdi_cusum_restart(); for callers that hand the alarm to
 *       fault-symptom reasoning and re-arm on its decision.
 * Head start (cfg.head_start_q16): the value both sums take at init and at
 * every restart. 0 is the standard CUSUM (the published ARLs assume it);
 * h/2 is the fast initial response (FIR) of Lucas and Crosier (1982), which
 * shortens the out-of-control ARL when a fault is still present at restart.
 *
 * Scaling and overflow (exact: nothing in a step can overflow, so nothing
 * needs saturating except the run counters):
 *   - x, mu0: any int32_t. e = x - mu0 is formed in int64_t: |e| < 2^32.
 *   - sigma_q10: LSB with 10 fraction bits, 1 .. UINT32_MAX (sigma up to
 *     ~4.2e6 LSB). k_q16, h_q16, head_start_q16: sigma units with 16
 *     fraction bits, each <= CANFDI_CUSUM_KH_MAX_Q16 (256 sigma).
 *   - sums S, K, H: int64_t, LSB with 16 fraction bits. K and H are
 *     round(k_q16 * sigma_q10 / 2^10), the product <= 2^56 in uint64_t, so
 *     K, H <= 2^46. An update adds e*2^16 - K, |.| < 2^49, to a sum that is
 *     <= H before the step (larger sums raise the alarm and restart or
 *     freeze): |S| < 2^50 always. Rounding happens only in K and H (half
 *     up, 2^-17 LSB); the sums themselves are exact integer arithmetic.
 *   - N_hi, N_lo saturate at UINT32_MAX (a sum sitting exactly on a
 *     non-zero value forever).
 *   - On the input grid: the published ARLs are for continuous data; keep
 *     the quantisation step well below sigma (the tests use sigma = 4096
 *     LSB) or the run lengths differ from the tables.
 *
 * Cost per canfdi_cusum_step: no multiply, no division, no loop; two
 * chains of 64-bit subtract/add/compare. Measured (gcc -Os, instructions
 * executed per call, QEMU -icount): 100 instructions for Cortex-M0+ code
 * (about 130 cycles), 60 on Cortex-M4. The step that raises an alarm also
 * divides once (64/32, __aeabi_uldivmod) for the shift estimate: measured
 * 640 instructions in all on M0+ and 180 on M4 for typical operands, up
 * to 910 (M0+) with full-scale ones (the library division's time depends
 * on the quotient): budget 1000 instructions on M0+ for that one step.
 * canfdi_cusum_init: three 32x32->64 multiplies.
 * RAM: sizeof(canfdi_cusum_t) = 112 bytes per instance (caller-owned).
 */
#ifndef CANFDI_CUSUM_H
#define CANFDI_CUSUM_H

#include "core/canfdi_common.h"
#include "core/canfdi_fixp.h"

/* Largest k, h and head start accepted by init: 256 sigma in Q16. */
#define CANFDI_CUSUM_KH_MAX_Q16 ((uint32_t)1U << 24)

/* Alarm side flags (return value of canfdi_cusum_step). */
#define CANFDI_CUSUM_NONE 0U
#define CANFDI_CUSUM_HI 1U /* upward shift of the mean */
#define CANFDI_CUSUM_LO 2U /* downward shift of the mean */

typedef enum {
  CANFDI_CUSUM_RESTART_AUTO = 0,
  CANFDI_CUSUM_RESTART_LATCH = 1
} canfdi_cusum_restart_t;

typedef struct {
  int32_t mu0;                    /* in-control mean, LSB */
  uint32_t sigma_q10;             /* in-control std deviation, LSB, Q10, > 0 */
  uint32_t k_q16;                 /* reference value k, sigma units, Q16 */
  uint32_t h_q16;                 /* decision interval h, sigma units, Q16, > 0 */
  uint32_t head_start_q16;        /* sums after init/restart, sigma, Q16, < h */
  canfdi_cusum_restart_t restart; /* what happens after an alarm */
} canfdi_cusum_cfg_t;

/* What the last alarm said. side is CANFDI_CUSUM_NONE (and the record
 * zero) until the first alarm. */
typedef struct {
  uint32_t side;         /* CANFDI_CUSUM_HI or CANFDI_CUSUM_LO */
  uint32_t alarm_step;   /* index of the sample that raised it */
  uint32_t n_nonzero;    /* N: consecutive non-zero steps of that sum */
  uint32_t change_step;  /* alarm_step - N (mod 2^32): last zero of the sum */
  int64_t shift_q16;     /* estimated mean shift, LSB, Q16: +-(K + S/N) */
  int64_t sum_q16;       /* the alarming sum S, LSB, Q16 (> H) */
} canfdi_cusum_alarm_t;

/* Diagnostics counters: monotone, saturating at UINT32_MAX
 * (core/canfdi_count.h); init clears them, nothing else does. No decision
 * of the firmware depends on them. */
typedef struct {
  uint32_t alarms_hi;    /* alarms on the upper sum */
  uint32_t alarms_lo;    /* alarms on the lower sum */
  uint32_t restarts;     /* automatic and canfdi_cusum_restart restarts */
  uint32_t latched_samples; /* samples ignored while latched */
} canfdi_cusum_diag_t;

/* Instance state; fields are private, use the accessors. */
typedef struct {
  int64_t k_lsb_q16;     /* K = k * sigma, LSB, Q16 */
  int64_t h_lsb_q16;     /* H = h * sigma, LSB, Q16 */
  int64_t s0_lsb_q16;    /* head start, LSB, Q16 */
  int64_t s_hi_q16;      /* upper sum, LSB, Q16, 0 <= S_hi */
  int64_t s_lo_q16;      /* lower sum, LSB, Q16, 0 <= S_lo */
  canfdi_cusum_alarm_t alarm;
  int32_t mu0;
  uint32_t n_hi;         /* N_hi: consecutive non-zero steps of S_hi,
                          * saturating at UINT32_MAX */
  uint32_t n_lo;         /* N_lo, likewise */
  uint32_t step;         /* index of the last sample (wraps by design) */
  canfdi_cusum_diag_t diag;
  uint8_t restart;       /* canfdi_cusum_restart_t */
  bool latched;
} canfdi_cusum_t;

/*
 * Prepare an instance from cfg (copied; cfg may be discarded afterwards).
 * Returns CANFDI_OK, or -CANFDI_EINVAL (instance untouched) if s or cfg is
 * NULL, sigma_q10 == 0, h_q16 == 0, k_q16, h_q16 or head_start_q16 exceeds
 * CANFDI_CUSUM_KH_MAX_Q16, head_start_q16 >= h_q16, or restart is not one of
 * the enumerators. Sums start at the head start, the index at 0, counters
 * cleared. Cost: constant (three 32x32->64 multiplies).
 */
int canfdi_cusum_init(canfdi_cusum_t *s, const canfdi_cusum_cfg_t *cfg);

/*
 * Feed one sample x (LSB, any int32_t). Returns the side mask of an alarm
 * raised by this sample (CANFDI_CUSUM_HI or CANFDI_CUSUM_LO; with k >= 0 the
 * two sums cannot cross H on the same sample), or CANFDI_CUSUM_NONE. The
 * alarm record (canfdi_cusum_last_alarm) is written when it returns non-zero.
 * While latched it returns CANFDI_CUSUM_NONE and only advances the index.
 * Cannot fail by contract (s != NULL, initialised). Cost: see header.
 */
uint32_t canfdi_cusum_step(canfdi_cusum_t *s, int32_t x);

/*
 * Re-arm: both sums to the head start, N counters to 0, latch released.
 * Counts diag.restarts. The index keeps running. Cannot fail by contract.
 * Cost: constant.
 */
void canfdi_cusum_restart(canfdi_cusum_t *s);

/* True while a LATCH-mode detector holds an alarm. */
bool canfdi_cusum_latched(const canfdi_cusum_t *s);

/* Current sums (LSB, Q16, >= 0) and the decision interval H (LSB, Q16),
 * e.g. for plotting residuals against thresholds. */
int64_t canfdi_cusum_sum_hi_q16(const canfdi_cusum_t *s);
int64_t canfdi_cusum_sum_lo_q16(const canfdi_cusum_t *s);
int64_t canfdi_cusum_threshold_q16(const canfdi_cusum_t *s);

/* Index of the last sample fed (0 before the first). */
uint32_t canfdi_cusum_step_index(const canfdi_cusum_t *s);

/* The record of the most recent alarm (all zero before the first). */
canfdi_cusum_alarm_t canfdi_cusum_last_alarm(const canfdi_cusum_t *s);

/* The diagnostics counters. */
canfdi_cusum_diag_t canfdi_cusum_diag(const canfdi_cusum_t *s);

#endif /* CANFDI_CUSUM_H */
