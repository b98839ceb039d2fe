/*
 * canfdi_intrin.h — the processor instructions the fixed-point code leans
 * on, each with a plain-C fallback that gives the same result bit for bit,
 * in the manner of CMSIS's core intrinsics:
 *
 *   canfdi_clz32, canfdi_clz64   count leading zeros (normalisation)
 *   canfdi_ctz32                 count trailing zeros (bit masks)
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
 * SMULL + ADDS/ADC + ADD on ARMv7-M (4), the 16-bit halves of
 * canfdi_smull32 (core/canfdi_fixp.h) and an add on ARMv6-M. RAM: none.
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

/*
 * Trailing zeros of x != 0: 0..31, the index of its lowest set bit (for
 * walking a bit mask from its lowest bit). Where CLZ exists: 31 minus the
 * leading zeros of that bit. Elsewhere the bit 2^i times the de Bruijn
 * constant 0x077CB531 (modulo 2^32) has a different top five bits for each
 * i, and a 32-entry table maps them back to i: one multiply and one load
 * (ARMv6-M has a single-cycle MULS, no CLZ). The table is built from the
 * constant: entry (0x077CB531 << i) >> 27 holds i.
 * Scaling and overflow: none (a bit index); the product wraps by design.
 */
static inline unsigned canfdi_ctz32(uint32_t x)
{
  const uint32_t low = x & ~(x - 1U); /* x != 0: no wrap */
  unsigned n;
  CANFDI_ASSERT(x != 0U);
#if defined(__ARM_FEATURE_CLZ)
  n = 31U - (unsigned)__builtin_clz(low);
#else
  static const uint8_t debruijn_index[32] = {0U,  1U,  28U, 2U,  29U, 14U, 24U, 3U,  30U, 22U, 20U,
                                             15U, 25U, 17U, 4U,  8U,  31U, 27U, 13U, 23U, 21U, 19U,
                                             16U, 7U,  26U, 12U, 18U, 6U,  11U, 5U,  10U, 9U};
  n = debruijn_index[(low * 0x077CB531U) >> 27];
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
 * q ~ 2^63 / v for 2^31 <= v < 2^32 (so 2^31 - 1 <= q < 2^32): the
 * reciprocal of the Q31 number v in [1, 2) as a Q32 number in (1/2, 1],
 * from below. Scaling and overflow: a seed interpolated linearly between
 * two entries of canfdi_recip_seed (canfdi_fixp.h; within 2^-16 below
 * 2^63 / v), then one Newton-Raphson step q (2 - v q / 2^63) with
 * t = 2^63 - v q >= 0 (below 2^47) in 64 bits. Error: 0 to 2^-30.4
 * relative (q never exceeds 2^63 / v). No division: the same bits on
 * every core. Cost: two table loads and three 32x32->64 multiplies.
 */
static inline uint32_t canfdi_recip_q63(uint32_t v)
{
  const uint32_t i = (v >> 23) & 0xFFU;
  const uint32_t a = canfdi_recip_seed[i];
  const uint32_t q0 = a - canfdi_umulhi32(a - canfdi_recip_seed[i + 1U], ((v >> 7) & 0xFFFFU) << 16);
  const uint64_t t = ((uint64_t)1 << 63) - canfdi_umull32(v, q0);
  return q0 + canfdi_umulhi32(q0, (uint32_t)(t >> 31));
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
#if defined(__ARM_ARCH_6M__)
  const int64_t p = canfdi_smull32(a, b) + 2147483648LL;
  return acc + (int32_t)canfdi_asr64(p, 32U);
#else
  const int64_t p = (((int64_t)acc * 4294967296LL) + 2147483648LL) + ((int64_t)a * (int64_t)b);
  return (int32_t)canfdi_asr64(p, 32U);
#endif
}

#endif /* CANFDI_INTRIN_H */
