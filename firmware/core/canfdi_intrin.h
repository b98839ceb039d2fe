/*
 * canfdi_intrin.h — the processor instructions the fixed-point code leans
 * on, each with a plain-C fallback that gives the same result bit for bit,
 * in the manner of CMSIS's core intrinsics:
 *
 *   canfdi_clz32, canfdi_clz64   count leading zeros (normalisation)
 *   canfdi_mla_hi_rnd            acc + round(a b / 2^32), the high word of a
 *                                rounded 32x32->64 multiply-accumulate
 *
 * Where the instruction exists (__ARM_FEATURE_CLZ: ARMv7-M and up; SMULL /
 * SMLAL: every ARMv7-M core) the compiler emits it; ARMv6-M (Cortex-M0/M0+)
 * and the host run the C. The PIL rig (tests/pil) compares the application's
 * output of the host build (fallbacks) with the target builds bit for bit,
 * so the two forms are checked equal on real data, and tests/unit/test_fixp
 * checks them on edge values.
 *
 * Scaling and overflow: stated per function. No floating point, no
 * implementation-defined shifts of negative values.
 * Cost (executed instructions, arm-none-eabi-gcc 12 -Os, inline): clz32 one
 * CLZ on ARMv7-M, ~14 on ARMv6-M; clz64 two to four more; mla_hi_rnd
 * SMULL + ADDS/ADC + ADD on ARMv7-M (4), a libgcc __aeabi_lmul call on
 * ARMv6-M (~30). RAM: none.
 */
#ifndef CANFDI_INTRIN_H
#define CANFDI_INTRIN_H

#include "core/canfdi_common.h"
#include "core/canfdi_fixp.h"

/*
 * Leading zeros of x: 0..31, and 32 for x == 0 (the ARM CLZ instruction's
 * definition; __builtin_clz(0) is undefined, hence the test).
 * Scaling and overflow: none (a bit count).
 */
static inline unsigned canfdi_clz32(uint32_t x)
{
  unsigned n;
#if defined(__ARM_FEATURE_CLZ)
  n = (x == 0U) ? 32U : (unsigned)__builtin_clz(x);
#else
  uint32_t v = x;
  n = 0U;
  if (v == 0U) {
    n = 32U;
  } else {
    if ((v & 0xFFFF0000U) == 0U) {
      n += 16U;
      v <<= 16;
    }
    if ((v & 0xFF000000U) == 0U) {
      n += 8U;
      v <<= 8;
    }
    if ((v & 0xF0000000U) == 0U) {
      n += 4U;
      v <<= 4;
    }
    if ((v & 0xC0000000U) == 0U) {
      n += 2U;
      v <<= 2;
    }
    if ((v & 0x80000000U) == 0U) {
      n += 1U;
    }
  }
#endif
  return n;
}

/* Leading zeros of a 64-bit x: 0..64 (64 for x == 0). */
static inline unsigned canfdi_clz64(uint64_t x)
{
  const uint32_t hi = (uint32_t)(x >> 32);
  return (hi != 0U) ? canfdi_clz32(hi) : (32U + canfdi_clz32((uint32_t)x));
}

/*
 * a b, the full 64-bit product of two unsigned 32-bit numbers: one UMULL on
 * ARMv7-M; on ARMv6-M, which has none, four 16x16->32 MULS and the carries
 * (libgcc's __aeabi_lmul would multiply 64 by 64 bits).
 * Scaling and overflow: exact, cannot overflow.
 */
static inline uint64_t canfdi_umull32(uint32_t a, uint32_t b)
{
#if defined(__ARM_ARCH_6M__)
  const uint32_t al = a & 0xFFFFU;
  const uint32_t ah = a >> 16;
  const uint32_t bl = b & 0xFFFFU;
  const uint32_t bh = b >> 16;
  const uint32_t ll = al * bl;
  const uint32_t lh = al * bh;
  const uint32_t mid = (ll >> 16) + (lh & 0xFFFFU) + (ah * bl); /* <= 2^32 - 1 */
  const uint32_t hi = (ah * bh) + (lh >> 16) + (mid >> 16);
  return ((uint64_t)hi << 32) | ((mid << 16) | (ll & 0xFFFFU));
#else
  return (uint64_t)a * (uint64_t)b;
#endif
}

/*
 * acc + floor((a b + 2^31) / 2^32): adds the product a b, rounded half up to
 * its high word, to acc (the SMMLAR of ARMv7E-M; on ARMv7-M one SMLAL into
 * the pair (2^31, acc)).
 * Scaling and overflow: a Qa x Qb product lands in Q(a + b - 32); the caller
 * guarantees that the sum fits an int32_t (it does not saturate: the users
 * bound their operands, see model/canfdi_rls.c). Rounding: half up.
 */
static inline int32_t canfdi_mla_hi_rnd(int32_t acc, int32_t a, int32_t b)
{
  const int64_t p = (((int64_t)acc * 4294967296LL) + 2147483648LL) + ((int64_t)a * (int64_t)b);
  return (int32_t)canfdi_asr64(p, 32U);
}

#endif /* CANFDI_INTRIN_H */
