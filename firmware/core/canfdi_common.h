/*
 * canfdi_common.h — what every canfdi module shares: fixed-width types,
 * error codes, the invariant assertion and the configuration.
 *
 * Error convention (as in libcanard): a function that can fail returns a
 * negated CANFDI_E* code (so < 0), and >= 0 on success. A function that
 * cannot fail "by contract" says so and returns void or a value.
 */
#ifndef CANFDI_COMMON_H
#define CANFDI_COMMON_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "canfdi_config.h"

#define CANFDI_OK 0
#define CANFDI_EINVAL 2 /* an argument is out of its documented domain */
#define CANFDI_ERANGE 3 /* a value does not fit its representation */
#define CANFDI_ENODATA 4 /* no valid data (yet) */
#define CANFDI_EIO 5     /* a port (flash, file, bus) reported an I/O error */

/*
 * Invariant check. Internal invariants only; never used to validate inputs
 * (inputs get an error code). Defaults to nothing on targets; the host tests
 * define it to assert(). Override by defining CANFDI_ASSERT before inclusion
 * or in CANFDI_CONFIG_HEADER.
 */
#ifndef CANFDI_ASSERT
#define CANFDI_ASSERT(x) ((void)0)
#endif

/*
 * A small helper of the 1 ms path that is always expanded in place: at -Os
 * GCC keeps many static inline functions out of line, and a call then
 * costs more than the helper's own few instructions. Only for functions of
 * a handful of instructions (the flash each copy costs is stated where it
 * is used). Plain inline for compilers without the attribute.
 */
#if defined(__GNUC__)
#define CANFDI_ALWAYS_INLINE inline __attribute__((always_inline))
#else
#define CANFDI_ALWAYS_INLINE inline
#endif

/* A decimated task that advances its phase (0 .. decim - 1) at the start
 * of each step and runs its work at phase 0: the phase to set before step
 * k of a caller's schedule so that the work falls on the steps with
 * k mod decim = 0 (one less than k mod decim, modulo decim). decim >= 1.
 * The estimators lock their RLS updates to the rate schedule with it. */
static inline uint8_t canfdi_phase_before(uint32_t k, uint32_t decim)
{
  uint32_t p = (k < decim) ? k : (k % decim); /* no division for k < decim */
  if (p == 0U) {
    p = decim;
  }
  return (uint8_t)(p - 1U);
}

/* Compile-time assertion usable in C99, at file scope only (at block scope
 * the typedef trips -Wunused-local-typedefs). */
#define CANFDI_STATIC_ASSERT(cond, msg) typedef char canfdi_static_assert_##msg[(cond) ? 1 : -1]

#endif /* CANFDI_COMMON_H */
