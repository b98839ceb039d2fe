/*
 * canfdi_fixp.h — fixed-point arithmetic core: Q15/Q31/Q63 types, saturating
 * add/sub/negate/abs/multiply, shifts that are defined for negative values,
 * format conversions, division and integer square roots.
 *
 * This header is the module's manual. Every routine is a pure function of its
 * arguments: no state, no memory besides the stack (at most a few words), no
 * error codes — each one is total "by contract" (every input has a documented
 * result, out-of-range results saturate). It never relies on undefined or
 * implementation-defined behaviour: no signed overflow, no shift of a
 * negative value, no shift by >= the width, no division by zero, no
 * INT_MIN / -1, no conversion of an out-of-range value to a signed type.
 * Right shifts of negative numbers are done arithmetically as
 * -1 - ((-1 - x) >> n), whose operand is never negative.
 *
 * Formats. A Qm.n value v stands for v / 2^n. Q15 = int16_t in [-1, 1),
 * Q31 = int32_t in [-1, 1), Q63 = int64_t in [-1, 1). The general routines
 * (canfdi_mul_s32_qn, canfdi_div_s32_qn, canfdi_qconv_s32) take the number
 * of fraction bits as an argument and serve every other Qm.n format.
 *
 * Rounding. Unless a name or note says floor/trunc, results are rounded
 * "half up": add 2^(n-1), then floor-shift by n, so ties go toward +inf
 * (the convention of the Cortex-M SMMULR instruction). Exceptions: the two
 * plain multiplies canfdi_q15_mul/canfdi_q31_mul floor; divisions round
 * half away from zero; square roots floor.
 *
 * Saturation. Results that do not fit saturate to the format's MIN/MAX.
 * Nothing here counts saturations (the functions are stateless); a caller
 * that needs a diagnostics counter compares the result with MIN/MAX.
 *
 * Cost. Stated per function for Cortex-M0+ (ARMv6-M: 32x32->32 MULS only,
 * no divide, no 64-bit multiply) and Cortex-M4 (SMULL/UMULL, UDIV/SDIV).
 * 32x32->64 products on M0+ are built from 16-bit halves (below), and only
 * products of 64-bit operands call libgcc's __aeabi_lmul; 64-bit shifts by a
 * run-time amount call __aeabi_llsl/__aeabi_llsr/__aeabi_lasr on M0+ (they
 * are inline code on M4); 32-bit divisions are UDIV on M4 and
 * __aeabi_uidivmod on M0+, and the 64-bit ones are long division by 16-bit
 * digits on them (canfdi_fixp.c: two 32-bit divisions, never libgcc's
 * 64-bit division). No routine uses floating point.
 * Everything in this header is static inline and branch-light, meant for the
 * 1 ms path; the divisions and square roots live in canfdi_fixp.c.
 *
 * Measured executed instructions per call (arm-none-eabi-gcc 12 -Os, QEMU
 * mps2-an386 with -icount, SysTick read-out; min/mean/max over 4000 random
 * and edge inputs, each including ~10 instructions of call overhead; the
 * M0+ build runs its ARMv6-M code on the same emulated core, so these are
 * instruction counts, not cycles; max is the largest seen, not a proof):
 *
 *                       Cortex-M4           Cortex-M0+
 *   q15_mul_rnd         17 / 17 / 18        22 / 23 / 23
 *   q31_mul_rnd         21 / 22 / 22        70 / 72 / 78
 *   mul_s32_qn (var n)  20 / 49 / 52        66 / 117 / 125
 *   mul_s64_q31         32 / 35 / 40        128 / 133 / 147
 *   add_s64_sat         20 / 26 / 28        28 / 33 / 39  (portable form)
 *   q15_div             22 / 35 / 36        25 / 158 / 238
 *   q31_div             22 / 119 / 146      25 / 670 / 974
 *   isqrt_u32           162 / 163 / 163     153 / 166 / 179
 *   isqrt_u64           478 / 521 / 568     1111 / 1171 / 1235
 *   q31_sqrt            16 / 266 / 598      20 / 592 / 1280
 *
 * The q31_div row was measured with libgcc's 64-bit division, which the
 * 64/32 long division has since replaced (cheaper on both cores; not
 * re-measured). The add_s64_sat row is the portable form's (CANFDI_FIXP_PORTABLE) with
 * its call; the default form through the overflow builtins is an
 * ADDS/ADCS pair and a branch on the overflow flag, inline.
 * Code size of canfdi_fixp.c (-Os): 444 bytes (M4), 492 bytes (M0+), plus
 * the libgcc helpers named above. RAM: none.
 */
#ifndef CANFDI_FIXP_H
#define CANFDI_FIXP_H

#include "core/canfdi_common.h"

/* The helpers the step calls most (saturation, |x|, the Q-format
 * products): always inline except on ARMv6-M. At -Os GCC keeps
 * out-of-line copies of them, and on ARMv7-M a call with its register
 * moves costs about as much as their few instructions (forced inline:
 * -400 a step on the M4 for 2.2 KB of code, `make pil-test`). On ARMv6-M
 * their 64-bit work is calls anyway, and flash is the tighter budget. */
#if defined(__ARM_ARCH_6M__)
#define CANFDI_V7M_INLINE inline
#else
#define CANFDI_V7M_INLINE CANFDI_ALWAYS_INLINE
#endif

typedef int16_t canfdi_q15_t; /* Q0.15, [-1, 1 - 2^-15] */
typedef int32_t canfdi_q31_t; /* Q0.31, [-1, 1 - 2^-31] */
typedef int64_t canfdi_q63_t; /* Q0.63, also the 64-bit accumulator type */

#define CANFDI_Q15_MAX INT16_MAX
#define CANFDI_Q15_MIN INT16_MIN
#define CANFDI_Q31_MAX INT32_MAX
#define CANFDI_Q31_MIN INT32_MIN

/*
 * Compile-time constants from a ratio of integers: CANFDI_Q15_RATIO(num, den)
 * is num/den in Q15, CANFDI_Q31_RATIO(num, den) is num/den in Q31, e.g.
 * CANFDI_Q31_RATIO(99, 100) for a forgetting factor of 0.99, so that
 * firmware needs no float literals and no magic numbers.
 * Scaling and overflow: integer constant expressions in int64_t; domain
 * 0 < den <= 2^30 and |num| <= 2^30, which keeps 2 * num * 2^31 + den inside
 * int64_t (outside it the expression overflows: use the macros for
 * constants, where the compiler diagnoses that). The result saturates to
 * [MIN, MAX], so 1/1 gives MAX and a ratio within half an LSB of +1 too.
 * Rounding: half up, as everywhere (CANFDI_Q15_RATIO(-1, 65536) is -0.5 LSB
 * and gives 0).
 * Cost: none at run time when the arguments are constants.
 */
#define CANFDI_QN_RATIO_(num, den, frac)                                         \
  (((num) >= 0)                                                                \
       ? ((2 * (int64_t)(num) * ((int64_t)1 << (frac)) + (int64_t)(den)) /     \
          (2 * (int64_t)(den)))                                                \
       : -((2 * -(int64_t)(num) * ((int64_t)1 << (frac)) + (int64_t)(den) - 1) / \
           (2 * (int64_t)(den))))
#define CANFDI_QN_RATIO_SAT_(num, den, frac, min, max)                           \
  ((CANFDI_QN_RATIO_((num), (den), (frac)) > (max))                              \
       ? (int64_t)(max)                                                          \
       : ((CANFDI_QN_RATIO_((num), (den), (frac)) < (min))                       \
              ? (int64_t)(min)                                                   \
              : CANFDI_QN_RATIO_((num), (den), (frac))))
#define CANFDI_Q15_RATIO(num, den)                                               \
  ((canfdi_q15_t)CANFDI_QN_RATIO_SAT_((num), (den), 15, INT16_MIN, INT16_MAX))
#define CANFDI_Q31_RATIO(num, den)                                               \
  ((canfdi_q31_t)CANFDI_QN_RATIO_SAT_((num), (den), 31, INT32_MIN, INT32_MAX))

/* ------------------------------------------------------------------------ */
/* Two's-complement reinterpretation and clamping                            */
/* ------------------------------------------------------------------------ */

/*
 * The int32_t with the same two's-complement bit pattern as u (u mod 2^32).
 * A plain (int32_t)u cast is implementation-defined for u > INT32_MAX; this
 * is the portable spelling, and compilers reduce it to nothing.
 * Scaling and overflow: wraps by definition (that is its job).
 * Cost: a compare and a select at most; usually zero instructions.
 */
static inline int32_t canfdi_wrap_u32_to_s32(uint32_t u)
{
  return (u <= (uint32_t)INT32_MAX) ? (int32_t)u : (-(int32_t)(~u) - 1);
}

/* As canfdi_wrap_u32_to_s32, for 64 bits. */
static inline int64_t canfdi_wrap_u64_to_s64(uint64_t u)
{
  return (u <= (uint64_t)INT64_MAX) ? (int64_t)u : (-(int64_t)(~u) - 1);
}

/*
 * x limited to [lo, hi]. Precondition lo <= hi (if violated, the result is
 * hi when x > hi and lo otherwise — still defined).
 * Scaling and overflow: format-agnostic, cannot overflow.
 * Cost: two compares.
 */
static inline int32_t canfdi_clamp_s32(int32_t x, int32_t lo, int32_t hi)
{
  int32_t y = x;
  if (y > hi) {
    y = hi;
  } else if (y < lo) {
    y = lo;
  }
  return y;
}

/* ------------------------------------------------------------------------ */
/* Shifts                                                                   */
/* ------------------------------------------------------------------------ */

/*
 * floor(x / 2^n), an arithmetic right shift defined for negative x.
 * Scaling and overflow: format-agnostic (a Qm.n input gives Qm.(n-k) per
 * k bits shifted); cannot overflow. Rounding: floor (toward -inf), like
 * ASR. Domain: n 0..31; n > 31 gives the exact floor too (0 or -1).
 * Cost: a compare and one 32-bit shift (the negative branch adds two subs).
 */
static inline int32_t canfdi_asr32(int32_t x, unsigned n)
{
  const unsigned s = (n > 31U) ? 31U : n;
  return (x >= 0) ? (x >> s) : (-1 - ((-1 - x) >> s));
}

/*
 * floor(x / 2^n) for 64 bits; n 0..63, n > 63 gives the exact floor (0/-1).
 * Scaling and overflow: as canfdi_asr32.
 * Cost: one 64-bit shift (inline for a constant n; a run-time n calls
 * __aeabi_llsr on M0+).
 */
static inline int64_t canfdi_asr64(int64_t x, unsigned n)
{
  const unsigned s = (n > 63U) ? 63U : n;
  return (x >= 0) ? (x >> s) : (-1 - ((-1 - x) >> s));
}

/*
 * Round-half-up right shift: floor((x + 2^(n-1)) / 2^n), computed as the
 * floor shift plus the last bit shifted out, so that it never overflows
 * (canfdi_asr32_rnd(INT32_MAX, 1) == 2^30).
 * Scaling and overflow: format-agnostic; the result magnitude shrinks, so it
 * cannot overflow. Rounding: half up (ties toward +inf: -2.5 -> -2,
 * 2.5 -> 3). Domain: n 0..31 (n == 0 returns x); any n > 31 returns 0, which
 * is the exact rounded value.
 * Cost: two shifts, an AND and an add.
 */
static inline int32_t canfdi_asr32_rnd(int32_t x, unsigned n)
{
  int32_t y = x;
  if (n > 0U) {
    const unsigned s = (n > 32U) ? 32U : n;
    y = canfdi_asr32(x, s) + (int32_t)(((uint32_t)x >> (s - 1U)) & 1U);
  }
  return y;
}

/*
 * Round-half-up right shift for 64 bits; n 0..63, n > 63 returns 0 (exact).
 * Scaling and overflow: as canfdi_asr32_rnd; no overflow at INT64_MAX.
 * Cost: two 64-bit shifts (inline for a constant n), an AND and an add.
 */
static inline int64_t canfdi_asr64_rnd(int64_t x, unsigned n)
{
  int64_t y = x;
  if (n > 0U) {
    const unsigned s = (n > 64U) ? 64U : n;
    y = canfdi_asr64(x, s) + (int64_t)(((uint64_t)x >> (s - 1U)) & 1U);
  }
  return y;
}

/*
 * 32x32->64 products. ARMv7-M has UMULL/SMULL, which the plain C products
 * below compile to. ARMv6-M (Cortex-M0/M0+) has only a 32x32->32 MULS, and
 * a 64-bit product in C calls libgcc's __aeabi_lmul, which multiplies 64 by
 * 64 bits (~45 instructions with its call); the *_h16 forms (canfdi_fixp.c,
 * one copy each: inline they would grow every caller) build the product
 * from four 16x16->32 multiplies instead (20 to 40 instructions with the
 * call), and are what canfdi_umull32, canfdi_umulhi32, canfdi_smull32 and
 * canfdi_usmull32 use there; with GCC the signed product and
 * canfdi_mul_s56_q31_rnd_h16 are Thumb-1 assembly there (canfdi_fixp.c).
 * Both forms are exact, so every core gives the same bits
 * (tests/unit/test_fixp checks the C halves against the host's products,
 * the PIL images every form against the target compiler's).
 * Scaling and overflow: exact, cannot overflow (stated with each
 * definition in canfdi_fixp.c).
 */

/* Unsigned: exact. */
uint64_t canfdi_umull32_h16(uint32_t a, uint32_t b);
/* The unsigned product's high word only. */
uint32_t canfdi_umulhi32_h16(uint32_t a, uint32_t b);
/* Signed. */
int64_t canfdi_smull32_h16(int32_t a, int32_t b);
/* Unsigned a times signed b. */
int64_t canfdi_usmull32_h16(uint32_t a, int32_t b);
/* round(a g / 2^31), half up, for -2^56 <= a < 2^56 and a Q31 g (|result|
 * <= 2^56): on ARMv6-M the filters' product (model/canfdi_svf.c) and
 * canfdi_mul_s64_q31 in that range, in one call, eight 16x16->32
 * multiplies and 32-bit words, where the general form takes a signed and
 * an unsigned 32x32->64 product (two calls) and a 64-bit shift and sum.
 * Exact: the same bits as the 64-bit form. */
int64_t canfdi_mul_s56_q31_rnd_h16(int64_t a, int32_t g);

/* a b for unsigned 32-bit operands: UMULL (ARMv6-M: the halves). */
static inline uint64_t canfdi_umull32(uint32_t a, uint32_t b)
{
#if defined(__ARM_ARCH_6M__)
  return canfdi_umull32_h16(a, b);
#else
  return (uint64_t)a * (uint64_t)b;
#endif
}

/* floor(a b / 2^32) for unsigned 32-bit operands: UMULL's high word. */
static inline uint32_t canfdi_umulhi32(uint32_t a, uint32_t b)
{
#if defined(__ARM_ARCH_6M__)
  return canfdi_umulhi32_h16(a, b);
#else
  return (uint32_t)(((uint64_t)a * (uint64_t)b) >> 32);
#endif
}

/* a b for signed 32-bit operands: SMULL (ARMv6-M: the halves). */
static inline int64_t canfdi_smull32(int32_t a, int32_t b)
{
#if defined(__ARM_ARCH_6M__)
  return canfdi_smull32_h16(a, b);
#else
  return (int64_t)a * (int64_t)b;
#endif
}

/* a b for an unsigned a and a signed b (ARMv6-M: the halves). */
static inline int64_t canfdi_usmull32(uint32_t a, int32_t b)
{
#if defined(__ARM_ARCH_6M__)
  return canfdi_usmull32_h16(a, b);
#else
  return (int64_t)a * (int64_t)b;
#endif
}

/*
 * c w for |c| <= 2^47 and w in 0..32767 (exact, |c w| < 2^62) from three
 * 32-bit multiplies, for ARMv6-M, where the 64-bit product calls libgcc's
 * 64x64 multiply: with c = ch 2^32 + cl (ch the signed high word,
 * |ch| <= 2^15) and cl = c1 2^16 + c0, the products ch w, c1 w and c0 w
 * are each below 2^31, and c w = ch w 2^32 + c1 w 2^16 + c0 w is summed in
 * 32-bit words. The same bits as c * w (tests/unit/test_fixp).
 */
static CANFDI_ALWAYS_INLINE int64_t canfdi_mul_s48_u15_h16(int64_t c, int32_t w)
{
  const uint64_t u = (uint64_t)c;
  const uint32_t cl = (uint32_t)u;
  const int32_t ch = canfdi_wrap_u32_to_s32((uint32_t)(u >> 32));
  const uint32_t uw = (uint32_t)w;
  const uint32_t p0 = (cl & 0xFFFFU) * uw;
  const uint32_t p1 = (cl >> 16) * uw;
  const uint32_t lo = p0 + (p1 << 16);
  const uint32_t hi = ((uint32_t)(ch * w) + (p1 >> 16)) + ((lo < p0) ? 1U : 0U);
  return canfdi_wrap_u64_to_s64(((uint64_t)hi << 32) | lo);
}

/*
 * sat(x * 2^n): saturating left shift.
 * Scaling and overflow: format-agnostic; saturates to INT32_MIN/INT32_MAX
 * when x * 2^n does not fit. Exact otherwise (no rounding involved).
 * Domain: any n (n >= 31 saturates every x except 0, and -1 at n == 31).
 * Cost: one shift to form each limit, two compares, one shift.
 */
static inline int32_t canfdi_shl32_sat(int32_t x, unsigned n)
{
  const unsigned s = (n > 31U) ? 31U : n; /* exact: n >= 31 saturates alike */
  int32_t y;
  if (x > (INT32_MAX >> s)) {
    y = INT32_MAX;
  } else if (x < canfdi_asr32(INT32_MIN, s)) {
    y = INT32_MIN;
  } else {
    y = canfdi_wrap_u32_to_s32((uint32_t)x << s);
  }
  return y;
}

/*
 * sat(x * 2^n) for 64 bits, any n.
 * Scaling and overflow: as canfdi_shl32_sat, saturating to INT64_MIN/MAX.
 * Cost: three 64-bit shifts and two 64-bit compares (shifts call libgcc on
 * M0+ for a run-time n).
 */
static inline int64_t canfdi_shl64_sat(int64_t x, unsigned n)
{
  const unsigned s = (n > 63U) ? 63U : n;
  int64_t y;
  if (x > (INT64_MAX >> s)) {
    y = INT64_MAX;
  } else if (x < canfdi_asr64(INT64_MIN, s)) {
    y = INT64_MIN;
  } else {
    y = canfdi_wrap_u64_to_s64((uint64_t)x << s);
  }
  return y;
}

/* ------------------------------------------------------------------------ */
/* Width saturation                                                         */
/* ------------------------------------------------------------------------ */

/*
 * x clipped to [INT16_MIN, INT16_MAX] (the __SSAT(x, 16) of CMSIS).
 * Scaling and overflow: keeps the scaling; saturates. Cost: two compares.
 */
static inline int16_t canfdi_sat_s32_to_s16(int32_t x)
{
  int16_t y;
  if (x > INT16_MAX) {
    y = INT16_MAX;
  } else if (x < INT16_MIN) {
    y = INT16_MIN;
  } else {
    y = (int16_t)x;
  }
  return y;
}

/*
 * Whether x lies in [INT32_MIN, INT32_MAX]: exactly when its high word is
 * the sign extension of its low word. One compare of the two words (CMP
 * with an ASR #31 operand on ARMv7-M), where two 64-bit compares take six
 * instructions; canfdi_sat_s64_to_s32 runs about a hundred times a step.
 * Scaling and overflow: none (a test; no arithmetic that wraps).
 */
static inline bool canfdi_s64_fits_s32(int64_t x)
{
  const uint64_t u = (uint64_t)x;
  return canfdi_wrap_u32_to_s32((uint32_t)(u >> 32)) == canfdi_asr32(canfdi_wrap_u32_to_s32((uint32_t)u), 31U);
}

/*
 * x clipped to [INT32_MIN, INT32_MAX] (clip_q63_to_q31 in CMSIS terms).
 * Scaling and overflow: keeps the scaling; saturates. In range by
 * canfdi_s64_fits_s32; out of range, the sign of x picks the bound.
 * Cost: one compare and a branch (in range).
 */
static CANFDI_V7M_INLINE int32_t canfdi_sat_s64_to_s32(int64_t x)
{
  const uint64_t u = (uint64_t)x;
  int32_t y;
  if (canfdi_s64_fits_s32(x)) {
    y = canfdi_wrap_u32_to_s32((uint32_t)u);
  } else {
    y = ((u >> 63) != 0U) ? INT32_MIN : INT32_MAX;
  }
  return y;
}

/* ------------------------------------------------------------------------ */
/* Saturating add / sub for plain integers                                  */
/* ------------------------------------------------------------------------ */

/*
 * The saturating adds and subtracts below use the compiler's overflow
 * builtins where it has them (GCC >= 5, Clang): an add with carry and a
 * branch on the overflow flag (ADDS/ADCS + BVS on Cortex-M), where the
 * portable form needs a wider sum or two range compares. Both forms give
 * the same result for every input; define CANFDI_FIXP_PORTABLE to build
 * the portable one (the C11 unit-test flavour does, so both are tested).
 */
#if !defined(CANFDI_FIXP_PORTABLE) && (defined(__clang__) || (defined(__GNUC__) && (__GNUC__ >= 5)))
#define CANFDI_FIXP_OVF_BUILTINS 1
#else
#define CANFDI_FIXP_OVF_BUILTINS 0
#endif

/*
 * sat(a + b) for int32_t (any common Qm.n format of a and b).
 * Scaling and overflow: output has the inputs' format; the sum is formed in
 * 64 bits (exact) and saturated to 32. Cost: one 64-bit add, two compares.
 */
static inline int32_t canfdi_add_s32_sat(int32_t a, int32_t b)
{
#if CANFDI_FIXP_OVF_BUILTINS
  int32_t y;
  if (__builtin_add_overflow(a, b, &y)) {
    y = (b > 0) ? INT32_MAX : INT32_MIN;
  }
  return y;
#else
  return canfdi_sat_s64_to_s32((int64_t)a + (int64_t)b);
#endif
}

/* sat(a - b) for int32_t; as canfdi_add_s32_sat. */
static inline int32_t canfdi_sub_s32_sat(int32_t a, int32_t b)
{
#if CANFDI_FIXP_OVF_BUILTINS
  int32_t y;
  if (__builtin_sub_overflow(a, b, &y)) {
    y = (b < 0) ? INT32_MAX : INT32_MIN;
  }
  return y;
#else
  return canfdi_sat_s64_to_s32((int64_t)a - (int64_t)b);
#endif
}

/*
 * sat(a + b) for int64_t (accumulators).
 * Scaling and overflow: output has the inputs' format; overflow is detected
 * before it happens (no wider type needed) and saturates to INT64_MIN/MAX.
 * Cost: two 64-bit compares, one 64-bit subtract, one 64-bit add.
 */
static inline int64_t canfdi_add_s64_sat(int64_t a, int64_t b)
{
  int64_t y;
#if CANFDI_FIXP_OVF_BUILTINS
  if (__builtin_add_overflow(a, b, &y)) {
    y = (b > 0) ? INT64_MAX : INT64_MIN;
  }
#else
  if ((b > 0) && (a > (INT64_MAX - b))) {
    y = INT64_MAX;
  } else if ((b < 0) && (a < (INT64_MIN - b))) {
    y = INT64_MIN;
  } else {
    y = a + b;
  }
#endif
  return y;
}

/* sat(a - b) for int64_t; as canfdi_add_s64_sat. */
static inline int64_t canfdi_sub_s64_sat(int64_t a, int64_t b)
{
  int64_t y;
#if CANFDI_FIXP_OVF_BUILTINS
  if (__builtin_sub_overflow(a, b, &y)) {
    y = (b < 0) ? INT64_MAX : INT64_MIN;
  }
#else
  if ((b < 0) && (a > (INT64_MAX + b))) {
    y = INT64_MAX;
  } else if ((b > 0) && (a < (INT64_MIN + b))) {
    y = INT64_MIN;
  } else {
    y = a - b;
  }
#endif
  return y;
}

/* ------------------------------------------------------------------------ */
/* Q15                                                                      */
/* ------------------------------------------------------------------------ */

/*
 * sat(a + b) in Q15.
 * Scaling and overflow: Q15 + Q15 -> Q15, 32-bit intermediate (exact),
 * saturates. Cost: one add, two compares.
 */
static inline canfdi_q15_t canfdi_q15_add(canfdi_q15_t a, canfdi_q15_t b)
{
  return canfdi_sat_s32_to_s16((int32_t)a + (int32_t)b);
}

/* sat(a - b) in Q15; as canfdi_q15_add. */
static inline canfdi_q15_t canfdi_q15_sub(canfdi_q15_t a, canfdi_q15_t b)
{
  return canfdi_sat_s32_to_s16((int32_t)a - (int32_t)b);
}

/*
 * sat(-a) in Q15: -(-1.0) saturates to CANFDI_Q15_MAX.
 * Scaling and overflow: Q15 -> Q15, 32-bit intermediate, saturates.
 * Cost: a negate and a compare.
 */
static inline canfdi_q15_t canfdi_q15_neg(canfdi_q15_t a)
{
  return canfdi_sat_s32_to_s16(-(int32_t)a);
}

/*
 * sat(|a|) in Q15: |-1.0| saturates to CANFDI_Q15_MAX.
 * Scaling and overflow: as canfdi_q15_neg. Cost: two compares, a negate.
 */
static inline canfdi_q15_t canfdi_q15_abs(canfdi_q15_t a)
{
  return (a < 0) ? canfdi_q15_neg(a) : a;
}

/*
 * sat(floor(a * b / 2^15)) in Q15.
 * Scaling and overflow: Q15 x Q15 -> Q30 product in 32 bits (exact), floor
 * shift by 15 -> Q15; only (-1) x (-1) saturates. Rounding: floor (bias of
 * -1/2 LSB on average; use canfdi_q15_mul_rnd inside loops that integrate).
 * Cost: one 16x16->32 multiply (MULS), one shift, two compares.
 */
static inline canfdi_q15_t canfdi_q15_mul(canfdi_q15_t a, canfdi_q15_t b)
{
  return canfdi_sat_s32_to_s16(canfdi_asr32((int32_t)a * (int32_t)b, 15U));
}

/*
 * sat(round(a * b / 2^15)) in Q15.
 * Scaling and overflow: as canfdi_q15_mul; rounding half up (unbiased but
 * for exact ties). Cost: one 16x16->32 multiply, two shifts, two compares.
 */
static inline canfdi_q15_t canfdi_q15_mul_rnd(canfdi_q15_t a, canfdi_q15_t b)
{
  return canfdi_sat_s32_to_s16(canfdi_asr32_rnd((int32_t)a * (int32_t)b, 15U));
}

/* ------------------------------------------------------------------------ */
/* Q31                                                                      */
/* ------------------------------------------------------------------------ */

/* sat(a + b) in Q31; the same function as canfdi_add_s32_sat. */
static inline canfdi_q31_t canfdi_q31_add(canfdi_q31_t a, canfdi_q31_t b)
{
  return canfdi_add_s32_sat(a, b);
}

/* sat(a - b) in Q31; the same function as canfdi_sub_s32_sat. */
static inline canfdi_q31_t canfdi_q31_sub(canfdi_q31_t a, canfdi_q31_t b)
{
  return canfdi_sub_s32_sat(a, b);
}

/*
 * sat(-a) in Q31: -(-1.0) saturates to CANFDI_Q31_MAX.
 * Scaling and overflow: Q31 -> Q31, saturates; no wider type needed.
 * Cost: a compare and a negate.
 */
static inline canfdi_q31_t canfdi_q31_neg(canfdi_q31_t a)
{
  return (a == INT32_MIN) ? INT32_MAX : -a;
}

/* sat(|a|) in Q31: |-1.0| saturates to CANFDI_Q31_MAX. Cost: two compares. */
static CANFDI_V7M_INLINE canfdi_q31_t canfdi_q31_abs(canfdi_q31_t a)
{
  return (a < 0) ? canfdi_q31_neg(a) : a;
}

/*
 * sat(floor(a * b / 2^31)) in Q31.
 * Scaling and overflow: Q31 x Q31 -> Q62 product in 64 bits (exact), floor
 * shift by 31 -> Q31; only (-1) x (-1) saturates. Rounding: floor.
 * Cost: one 32x32->64 multiply (SMULL on M4, 16-bit halves on M0+), one
 * constant 64-bit shift, two compares.
 */
static inline canfdi_q31_t canfdi_q31_mul(canfdi_q31_t a, canfdi_q31_t b)
{
  return canfdi_sat_s64_to_s32(canfdi_asr64(canfdi_smull32(a, b), 31U));
}

/*
 * sat(round(a * b / 2^31)) in Q31.
 * Scaling and overflow: as canfdi_q31_mul, rounding half up.
 * Cost: one 32x32->64 multiply, two constant 64-bit shifts, two compares.
 */
static inline canfdi_q31_t canfdi_q31_mul_rnd(canfdi_q31_t a, canfdi_q31_t b)
{
  return canfdi_sat_s64_to_s32(canfdi_asr64_rnd(canfdi_smull32(a, b), 31U));
}

/* ------------------------------------------------------------------------ */
/* General Qm.n multiply                                                    */
/* ------------------------------------------------------------------------ */

/*
 * sat(round(a * b / 2^n)): multiply of any two 32-bit fixed-point values
 * whose fraction bits add up to n more than the output's (e.g. Q16.16 x
 * Q16.16 -> Q16.16 with n = 16, Q15 in int32 x Q31 -> Q15 with n = 31).
 * Scaling and overflow: 64-bit product (exact, |a*b| <= 2^62), round-half-up
 * shift by n, saturated to 32 bits. Domain: n 0..62 as specified; any n is
 * exact (n == 63 rounds (-2^31)^2 up to 1; n >= 64 gives 0).
 * Cost: one 32x32->64 multiply, two 64-bit shifts by a run-time amount
 * (libgcc calls on M0+; pass a constant n to keep them inline), two compares.
 */
static CANFDI_V7M_INLINE int32_t canfdi_mul_s32_qn(int32_t a, int32_t b, unsigned n)
{
  return canfdi_sat_s64_to_s32(canfdi_asr64_rnd(canfdi_smull32(a, b), n));
}

/*
 * sat(round(a * b / 2^31)): a 64-bit accumulator (any Qm.n) times a Q31
 * factor, result in a's format, without a 128-bit type.
 * Scaling and overflow: a = ah * 2^32 + al with ah signed (floor shift) and
 * al in [0, 2^32). Then a*b / 2^31 = 2*(ah*b) + al*b / 2^31, where ah*b and
 * al*b are exact 64-bit products (|al*b| < 2^63); only the second term needs
 * rounding and adding an integer does not change a half-up rounding, so the
 * result is exactly round(a*b / 2^31). The final add saturates to
 * INT64_MIN/MAX (only when |a| is near 2^63 and |b| near 1).
 * Rounding: half up. Cost: two 32x32->64 multiplies (M4: SMULL + a signed x
 * unsigned 64-bit product; M0+: their 16-bit halves), constant shifts, two
 * 64-bit adds with saturation checks. On ARMv6-M an a within 2^56 (the
 * filter states of the firmware, with few exceptions) takes
 * canfdi_mul_s56_q31_rnd_h16 instead: one call for two, the same bits (no
 * saturation can act there).
 */
static CANFDI_V7M_INLINE int64_t canfdi_mul_s64_q31(int64_t a, canfdi_q31_t b)
{
  const int32_t ah = (int32_t)canfdi_asr64(a, 32U);             /* in int32 range */
  int64_t y;
#if defined(__ARM_ARCH_6M__)
  if ((ah >= -16777216) && (ah < 16777216)) {
    /* -2^56 <= a < 2^56 */
    y = canfdi_mul_s56_q31_rnd_h16(a, b);
  } else
#endif
  {
    const uint32_t al = (uint32_t)((uint64_t)a & 0xFFFFFFFFU);     /* in [0, 2^32) */
    const int64_t hi = canfdi_smull32(ah, b);                      /* |hi| <= 2^62 */
    const int64_t lo = canfdi_asr64_rnd(canfdi_usmull32(al, b), 31U); /* |lo| <= 2^32 */
    /* 2*hi may overflow on its own while 2*hi + lo does not: add hi + lo
     * first (exact), then saturate once. */
    y = canfdi_add_s64_sat(hi, hi + lo);
  }
  return y;
}

/* ------------------------------------------------------------------------ */
/* Conversions                                                              */
/* ------------------------------------------------------------------------ */

/*
 * Q15 -> Q31, exact (x * 2^16).
 * Scaling and overflow: cannot overflow ((-2^15) * 2^16 = INT32_MIN).
 * Cost: one shift.
 */
static inline canfdi_q31_t canfdi_q15_to_q31(canfdi_q15_t x)
{
  return (canfdi_q31_t)x * 65536;
}

/*
 * Q31 -> Q15, rounded half up and saturated (values within half an LSB of
 * +1.0 saturate to CANFDI_Q15_MAX).
 * Scaling and overflow: round-half-up shift by 16, then saturate to 16 bits.
 * Cost: two shifts, an add, two compares.
 */
static inline canfdi_q15_t canfdi_q31_to_q15(canfdi_q31_t x)
{
  return canfdi_sat_s32_to_s16(canfdi_asr32_rnd(x, 16U));
}

/*
 * Change the number of fraction bits of a 32-bit value: x in Qm.from_frac
 * -> Q(m + from_frac - to_frac).to_frac. Going to more fraction bits is an
 * exact saturating left shift; going to fewer rounds half up.
 * Scaling and overflow: saturates to INT32_MIN/MAX; 32-bit arithmetic only.
 * Domain: from_frac, to_frac 0..31 (any values are defined: the shift
 * routines accept any count). Cost: one compare plus one shift routine.
 */
static inline int32_t canfdi_qconv_s32(int32_t x, unsigned from_frac, unsigned to_frac)
{
  return (to_frac >= from_frac) ? canfdi_shl32_sat(x, to_frac - from_frac)
                                : canfdi_asr32_rnd(x, from_frac - to_frac);
}

/* ------------------------------------------------------------------------ */
/* Division and square root (canfdi_fixp.c)                                 */
/* ------------------------------------------------------------------------ */

/*
 * Division by zero: every division returns the saturated value with the sign
 * of the numerator (MAX for num > 0, MIN for num < 0) and 0 for 0/0. That is
 * the limit a fixed-point quotient approaches as den -> 0 from the positive
 * side; a caller for which den == 0 means "no data" must test it first.
 */

/*
 * sat(round(num / den)) in Q15 (num, den Q15; also any common Qm.15 pair).
 * Scaling and overflow: magnitudes |num| * 2^15 <= 2^30 and |den| <= 2^15
 * in uint32_t; a quotient outside [-1, 1 - 2^-15] saturates (num == -den
 * gives exactly CANFDI_Q15_MIN = -1.0, num == den gives CANFDI_Q15_MAX).
 * Rounding: to nearest, ties away from zero. Division by zero: see above.
 * Cost: one 32/32 unsigned division (UDIV on M4, __aeabi_uidivmod on M0+).
 */
canfdi_q15_t canfdi_q15_div(canfdi_q15_t num, canfdi_q15_t den);

/*
 * sat(round(num / den)) in Q31. Scaling and overflow: as canfdi_q15_div
 * with |num| * 2^31 <= 2^62 in uint64_t.
 * Cost: canfdi_div_s32_qn with n = 31: a 64/32 long division (two 32-bit
 * divisions) and a few 64-bit shifts and compares.
 */
canfdi_q31_t canfdi_q31_div(canfdi_q31_t num, canfdi_q31_t den);

/*
 * sat(round(num * 2^n / den)): division with n extra fraction bits, e.g.
 * Q16.16 / Q16.16 -> Q16.16 with n = 16, or integer ratio -> Q31 with n = 31.
 * Scaling and overflow: num magnitude shifted left by n in uint64_t (exact
 * for n <= 32); for n > 32 the routine first proves saturation when
 * |num| * 2^n >= 2^63, so any n is exact. Saturates to INT32_MIN/MAX.
 * Rounding: to nearest, ties away from zero. Division by zero: see above.
 * Domain: n 0..31 specified; any n is defined.
 * Cost: one division, 32/32 (cheap path, when |num| * 2^n < 2^32) or 64/32
 * (long division by 16-bit digits: two 32-bit divisions), plus a 64-bit
 * shift by a run-time amount.
 */
int32_t canfdi_div_s32_qn(int32_t num, int32_t den, unsigned n);

/*
 * sat(trunc(num / den)): the quotient of two 64-bit integers rounded toward
 * zero (as C's '/'), saturated to INT32_MIN/MAX. Division by zero: see
 * above. Scaling and overflow: magnitudes in uint64_t (INT64_MIN exact);
 * saturation is decided before dividing (|num| >= |den| 2^31), so the
 * quotient computed is below 2^31.
 * Cost: no 64-bit division: one 64/32 division (two 32-bit divisions) when
 * |den| < 2^32, else that and two 32x32 products (the divisor's top word
 * gives the quotient within one).
 */
int32_t canfdi_div_s64_sat_s32(int64_t num, int64_t den);

/*
 * round(a 2^30 / b), ties up, for a and b normalised to [2^61, 2^62): the
 * mantissa of a ratio of two 62-bit magnitudes, in (2^29, 2^31].
 * Scaling and overflow: q2 = floor(a 2^31 / b) < 2^32 is one quotient digit
 * of a 95-bit by 64-bit division with the divisor normalised (a 2^33 /
 * b 2^2): its estimate from the divisor's top word (one 64/32 division)
 * exceeds it by at most 2, and the remainder test with the divisor's low
 * word, exact for a two-word divisor, corrects it; the result is
 * (q2 + 1) / 2 rounded down, which is round(a 2^30 / b) with ties up.
 * Exact: the same bits as a bit-serial restoring division
 * (tests/unit/test_fixp.c compares the two). Outside the domain the
 * result is unspecified (an assertion in debug builds).
 * Cost: one 64/32 division (two 32-bit divisions), two 32x32->64
 * products, at most two corrections; the bit-serial loop it replaces took
 * about 31 iterations of 64-bit shift, compare and subtract.
 */
uint32_t canfdi_div_u62_q30_rnd(uint64_t a, uint64_t b);

/*
 * floor(sqrt(x)), exact for every uint32_t.
 * Scaling and overflow: integer in, integer out (a Q2k value gives a Qk
 * root); the result always fits (sqrt(2^32 - 1) < 2^16). Rounding: floor.
 * Cost: bit-by-bit (digit-by-digit binary), always 16 iterations of
 * compare/subtract/shift on 32-bit words; no multiply, no divide.
 */
uint16_t canfdi_isqrt_u32(uint32_t x);

/*
 * floor(sqrt(x)), exact for every uint64_t.
 * Scaling and overflow: as canfdi_isqrt_u32; result < 2^32.
 * Cost: bit-by-bit, always 32 iterations on 64-bit words.
 */
uint32_t canfdi_isqrt_u64(uint64_t x);

/*
 * sqrt(x) in Q15: floor(sqrt(x * 2^15)); x <= 0 gives 0 (a negative argument
 * is treated as an estimate of zero that noise pushed below it).
 * Scaling and overflow: Q15 -> Q30 in uint32_t (x * 2^15 < 2^30), root is
 * Q15; cannot overflow. Rounding: floor (error in [0, 1) LSB).
 * Cost: one canfdi_isqrt_u32 (16 iterations).
 */
canfdi_q15_t canfdi_q15_sqrt(canfdi_q15_t x);

/*
 * sqrt(x) in Q31: floor(sqrt(x * 2^31)); x <= 0 gives 0.
 * Scaling and overflow: Q31 -> Q62 in uint64_t, root is Q31; cannot
 * overflow. Rounding: floor. Cost: one canfdi_isqrt_u64 (32 iterations).
 */
canfdi_q31_t canfdi_q31_sqrt(canfdi_q31_t x);

/*
 * The seed table of canfdi_recip_q63 (core/canfdi_intrin.h):
 * floor(2^63 / (2^31 + i 2^23)) - 2^15 for i = 0..256 (the first clipped to
 * 2^32 - 1): 2^63 / v at the 256 interval starts of v in [2^31, 2^32), less
 * a margin that keeps the linear interpolation between them below 2^63 / v.
 * 1028 bytes of flash.
 */
extern const uint32_t canfdi_recip_seed[257];

#endif /* CANFDI_FIXP_H */
