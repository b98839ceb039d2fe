/*
 * canfdi_fixp.c — the heavier fixed-point routines: division and square
 * roots. See canfdi_fixp.h for the contract of each function.
 *
 * Divisions work on magnitudes in unsigned arithmetic and apply the sign at
 * the end: that sidesteps INT_MIN / -1 and the implementation's rounding
 * direction of signed '/', and makes "ties away from zero" a plain
 * round-half-up on the magnitude.
 */
#include "core/canfdi_fixp.h"

/* |x| as an unsigned value; exact for INT32_MIN (2^31). */
static uint32_t mag_u32(int32_t x)
{
  return (x < 0) ? (0U - (uint32_t)x) : (uint32_t)x;
}

/*
 * round(num / den) for den != 0, ties up (away from zero for magnitudes).
 * 'r >= den - r' is '2r >= den' without the overflow of 2r.
 */
static uint32_t udiv_rnd_u32(uint32_t num, uint32_t den)
{
  const uint32_t q = num / den;
  const uint32_t r = num % den;
  return (r >= (den - r)) ? (q + 1U) : q;
}

static uint64_t udiv_rnd_u64(uint64_t num, uint32_t den)
{
  uint64_t q;
  if ((num >> 32) == 0U) {
    /* Small operands take the 32-bit division (UDIV on M4, the cheaper
     * helper on M0+) instead of the 64-bit helper. */
    q = udiv_rnd_u32((uint32_t)num, den);
  } else {
    const uint64_t q0 = num / den;
    const uint64_t r = num % den; /* one __aeabi_uldivmod gives both */
    q = (r >= ((uint64_t)den - r)) ? (q0 + 1U) : q0;
  }
  return q;
}

/* Saturated signed result from a rounded magnitude q and a sign. */
static int32_t apply_sign_sat_s32(uint64_t q, bool negative)
{
  int32_t y;
  if (negative) {
    y = (q >= ((uint64_t)1U << 31)) ? INT32_MIN : -(int32_t)q;
  } else {
    y = (q > (uint64_t)INT32_MAX) ? INT32_MAX : (int32_t)q;
  }
  return y;
}

/* The documented result of a division by zero: saturate to num's sign. */
static int32_t div_by_zero_s32(int32_t num)
{
  int32_t y = 0;
  if (num > 0) {
    y = INT32_MAX;
  } else if (num < 0) {
    y = INT32_MIN;
  } else {
    /* 0 / 0 stays 0 */
  }
  return y;
}

canfdi_q15_t canfdi_q15_div(canfdi_q15_t num, canfdi_q15_t den)
{
  int32_t y;
  if (den == 0) {
    y = div_by_zero_s32(num);
  } else {
    /* |num| * 2^15 <= 2^30: the whole job fits 32-bit unsigned words. */
    const uint32_t q = udiv_rnd_u32(mag_u32(num) << 15, mag_u32(den));
    y = apply_sign_sat_s32(q, (num < 0) != (den < 0));
  }
  return canfdi_sat_s32_to_s16(y);
}

int32_t canfdi_div_s32_qn(int32_t num, int32_t den, unsigned n)
{
  int32_t y;
  const bool negative = (num < 0) != (den < 0);
  if (den == 0) {
    y = div_by_zero_s32(num);
  } else if (num == 0) {
    y = 0;
  } else if ((n > 32U) && ((n >= 63U) || ((mag_u32(num) >> (63U - n)) != 0U))) {
    /* |num| * 2^n >= 2^63 and |den| <= 2^31, so |quotient| >= 2^32: it
     * saturates, and the shift below would lose bits. */
    y = negative ? INT32_MIN : INT32_MAX;
  } else {
    /* n <= 32 or |num| < 2^(63-n): the shifted magnitude is below 2^64. */
    const uint64_t q = udiv_rnd_u64((uint64_t)mag_u32(num) << n, mag_u32(den));
    y = apply_sign_sat_s32(q, negative);
  }
  return y;
}

canfdi_q31_t canfdi_q31_div(canfdi_q31_t num, canfdi_q31_t den)
{
  return canfdi_div_s32_qn(num, den, 31U);
}

/*
 * Digit-by-digit binary square root. Invariant at the top of each step k
 * (bit = 4^k): res = 2^(k+1) * r, where r is the root of the bits of x above
 * position 2k+2, and x holds the remainder (original - r^2 * 4^(k+1)).
 * Testing remainder >= (2r+1) * 4^k decides the next root bit; the loop runs
 * a fixed number of times so the cost does not depend on the argument.
 */
uint16_t canfdi_isqrt_u32(uint32_t x)
{
  uint32_t rem = x;
  uint32_t res = 0U;
  uint32_t bit = (uint32_t)1U << 30;
  unsigned i;
  for (i = 0U; i < 16U; i++) {
    if (rem >= (res + bit)) {
      rem -= res + bit;
      res = (res >> 1) + bit;
    } else {
      res >>= 1;
    }
    bit >>= 2;
  }
  CANFDI_ASSERT(res <= 0xFFFFU);
  return (uint16_t)res;
}

uint32_t canfdi_isqrt_u64(uint64_t x)
{
  uint64_t rem = x;
  uint64_t res = 0U;
  uint64_t bit = (uint64_t)1U << 62;
  unsigned i;
  for (i = 0U; i < 32U; i++) {
    if (rem >= (res + bit)) {
      rem -= res + bit;
      res = (res >> 1) + bit;
    } else {
      res >>= 1;
    }
    bit >>= 2;
  }
  CANFDI_ASSERT(res <= 0xFFFFFFFFU);
  return (uint32_t)res;
}

canfdi_q15_t canfdi_q15_sqrt(canfdi_q15_t x)
{
  canfdi_q15_t y = 0;
  if (x > 0) {
    /* x * 2^15 < 2^30, so the root is < 2^15 and fits Q15. */
    y = (canfdi_q15_t)canfdi_isqrt_u32((uint32_t)x << 15);
  }
  return y;
}

canfdi_q31_t canfdi_q31_sqrt(canfdi_q31_t x)
{
  canfdi_q31_t y = 0;
  if (x > 0) {
    /* x * 2^31 < 2^62, so the root is < 2^31 and fits Q31. */
    y = (canfdi_q31_t)canfdi_isqrt_u64((uint64_t)x << 31);
  }
  return y;
}
