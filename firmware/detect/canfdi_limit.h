/*
 * canfdi_limit.h — limit checking of an absolute value with hysteresis and
 * Dem-style debouncing (Isermann, Fault-Diagnosis Systems, ch. 7.1).
 *
 * The signal x is an int32_t in any engineering unit the caller chooses
 * (mA, mrad/s, units/s of a rate from canfdi_trend); the limits are in the
 * same unit. Every int32_t value is valid input: the module only compares,
 * so nothing overflows and nothing saturates.
 *
 * Raw symptom, with hysteresis on each side (either side may be disabled):
 *   upper: becomes ABOVE when x > max_set; leaves ABOVE only when
 *          x < max_clear (max_clear <= max_set); in between it holds.
 *   lower: becomes BELOW when x < min_set; leaves BELOW only when
 *          x > min_clear (min_clear >= min_set).
 * With both sides enabled the configuration must satisfy
 *   min_set <= min_clear < max_clear <= max_set,
 * which makes ABOVE and BELOW mutually exclusive. max_clear == max_set
 * (no hysteresis) is allowed: then x == max_set holds the previous symptom.
 *
 * Each step the raw symptom is reported to an embedded canfdi_debounce:
 * ABOVE or BELOW -> PREFAILED, IN_BAND -> PREPASSED. The qualified result is
 * the debouncer's status (UNDECIDED / PASSED / FAILED, latched as in Dem), so
 * with a 1 ms step a failed_threshold of 100 and step 1 means "violated for
 * 100 consecutive steps". `failed_side` is the raw symptom of the latest
 * step whose PREFAILED report left the debounce counter at the failed
 * threshold, i.e. the side that qualified (or keeps) the result FAILED, for
 * the trouble-code mapping (P0123 above vs P0122 below). When the two sides
 * need separate codes with separate debouncing, use one instance per side.
 *
 * Scaling and overflow: no arithmetic on x, comparisons only; the
 * diagnostics counters saturate at UINT32_MAX. See canfdi_debounce.h for
 * the debouncer.
 *
 * Cost, worst case per canfdi_limit_step(): 4 signed compares for the
 * symptoms, 2 counter updates and one canfdi_debounce_step (about 12
 * compares); no multiply or divide. Measured (arm-none-eabi-gcc 12 -Os,
 * QEMU -icount, 2000 calls incl. full-scale inputs), debouncing included:
 * at most 109 instructions on Cortex-M0 (mean 95), 86 on Cortex-M4 (mean
 * 74). Stack: 32 bytes worst chain (16 here + 16 in canfdi_debounce_step;
 * -fstack-usage, M0+). Code: 400 bytes (M0+) plus the debouncer.
 * RAM per instance: sizeof(canfdi_limit_t) = 36 bytes on a 32-bit target
 * (config pointer 4, debouncer 16, symptom state 4, counters 12); the
 * configuration (32 bytes) is caller-owned, normally const.
 */
#ifndef CANFDI_LIMIT_H
#define CANFDI_LIMIT_H

#include "core/canfdi_common.h"
#include "core/canfdi_debounce.h"

/* Raw (hysteresis-latched, not debounced) symptom. */
typedef enum {
  CANFDI_LIMIT_IN_BAND = 0,
  CANFDI_LIMIT_ABOVE_MAX = 1,
  CANFDI_LIMIT_BELOW_MIN = 2
} canfdi_limit_symptom_t;

/*
 * Configuration, caller-owned; the instance keeps a pointer to it (and its
 * debouncer to `deb`), so it must outlive the instance and stay unchanged.
 */
typedef struct {
  int32_t max_set;   /* ABOVE when x > max_set */
  int32_t max_clear; /* leave ABOVE when x < max_clear; max_clear <= max_set */
  int32_t min_set;   /* BELOW when x < min_set */
  int32_t min_clear; /* leave BELOW when x > min_clear; min_clear >= min_set */
  bool max_enabled;
  bool min_enabled;
  canfdi_debounce_cfg_t deb; /* debouncing of the raw symptom */
} canfdi_limit_cfg_t;

/* Diagnostics counters: monotone, saturating at UINT32_MAX
 * (core/canfdi_count.h); init clears them, nothing else does. No decision
 * of the firmware depends on them. */
typedef struct {
  uint32_t above_events; /* raw symptom entered ABOVE_MAX */
  uint32_t below_events; /* raw symptom entered BELOW_MIN */
  uint32_t steps_violated; /* steps with a raw symptom other than IN_BAND */
} canfdi_limit_diag_t;

/* Instance, caller-owned; fields are read-only for the caller. */
typedef struct {
  const canfdi_limit_cfg_t *cfg;
  canfdi_debounce_t deb;
  uint8_t symptom;     /* canfdi_limit_symptom_t, raw, this step */
  uint8_t failed_side; /* canfdi_limit_symptom_t that qualified FAILED, see above */
  canfdi_limit_diag_t diag;
} canfdi_limit_t;

/* Check cfg (limits as above, debouncer as canfdi_debounce_cfg_check, at
 * least one side enabled). Returns CANFDI_OK or -CANFDI_EINVAL. O(1). */
int32_t canfdi_limit_cfg_check(const canfdi_limit_cfg_t *cfg);

/* Bind l to cfg: symptom IN_BAND, failed_side IN_BAND, debouncer fresh,
 * counters 0. Returns CANFDI_OK or -CANFDI_EINVAL (NULL, invalid cfg; then
 * l stays unbound and step() rejects it). O(1). */
int32_t canfdi_limit_init(canfdi_limit_t *l, const canfdi_limit_cfg_t *cfg);

/* Check one sample x (any int32_t). Returns the qualified status (a
 * canfdi_deb_status_t, >= 0) or -CANFDI_EINVAL for NULL/unbound l.
 * Cost: see above. */
int32_t canfdi_limit_step(canfdi_limit_t *l, int32_t x);

/* Forget the symptom state and restart debouncing (canfdi_debounce_reset);
 * counters kept. No-op on NULL/unbound. O(1). */
void canfdi_limit_reset(canfdi_limit_t *l);

/* Raw symptom of the last step; IN_BAND for NULL. O(1). */
canfdi_limit_symptom_t canfdi_limit_symptom(const canfdi_limit_t *l);

/* Qualified status; UNDECIDED for NULL. O(1). */
canfdi_deb_status_t canfdi_limit_status(const canfdi_limit_t *l);

/* Side that qualified FAILED (see above; IN_BAND if none since init or
 * reset); IN_BAND for NULL. O(1). */
canfdi_limit_symptom_t canfdi_limit_failed_side(const canfdi_limit_t *l);

#endif /* CANFDI_LIMIT_H */
