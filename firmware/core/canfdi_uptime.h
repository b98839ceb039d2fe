/*
 * canfdi_uptime.h — the firmware's one time base: milliseconds of operation
 * since power-up (init), right for 584 million years, kept from the port's
 * free-running 32-bit microsecond clock.
 *
 * Why: a port clock of 32 bits in microseconds (a timer, CLOCK_MONOTONIC cut
 * to uint32_t, the SIL's step counter times 1000) wraps every 2^32 us =
 * 71.6 minutes. Differences of two such readings stay right across the
 * wrap (modulo 2^32), so supervision windows may use them directly; a time
 * stamp may not (now_us / 1000 jumps back to 0 after 71.6 minutes).
 * canfdi_uptime_advance() accumulates the differences into a 64-bit
 * millisecond count instead, with the sub-millisecond remainder kept, so
 * the count neither drifts nor wraps.
 *
 * Contract: advance at least once per 2^32 us (every step does); a longer
 * gap is taken modulo 2^32 (the clock cannot tell it). The port clock may
 * start anywhere, e.g. near its wrap: only differences are used.
 *
 * Scaling and overflow: unsigned integers; the elapsed time modulo 2^32 is
 * defined for unsigned operands. ms grows by at most 4.3e6 per call and
 * cannot overflow in 2^64 ms. Cost: a subtraction, one compare and, per
 * whole millisecond (one per 1 ms step), a subtraction; a division only
 * when more than 4 ms elapsed since the last call. Memory: 16 bytes.
 */
#ifndef CANFDI_UPTIME_H
#define CANFDI_UPTIME_H

#include "core/canfdi_common.h"

typedef struct {
  uint64_t ms;      /* whole milliseconds since init */
  uint32_t last_us; /* port clock at the last init/advance */
  uint32_t frac_us; /* microseconds elapsed beyond ms, 0..999 */
} canfdi_uptime_t;

/* Uptime 0 at port time now_us. Cannot fail by contract (t non-NULL). */
void canfdi_uptime_init(canfdi_uptime_t *t, uint32_t now_us);

/* Advances to port time now_us and returns the uptime in ms. Cannot fail
 * by contract (t non-NULL). */
uint64_t canfdi_uptime_advance(canfdi_uptime_t *t, uint32_t now_us);

/* The uptime in ms at the last init/advance. */
uint64_t canfdi_uptime_ms(const canfdi_uptime_t *t);

#endif /* CANFDI_UPTIME_H */
