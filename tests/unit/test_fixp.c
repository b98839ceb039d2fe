/*
 * test_fixp.c — unit tests of the fixed-point core (firmware/core/canfdi_fixp).
 *
 * Every result is compared with an exact reference computed in a wider type
 * (int64_t, or __int128 on the host) by a different method than the firmware
 * uses: floor division by the '/' operator with a remainder correction
 * instead of shifts, "round half up" as floor(x + 1/2), "ties away from zero"
 * as floor((2|n| + |d|) / 2|d|), saturation as a clamp, square roots by the
 * defining inequality r^2 <= x < (r+1)^2. The tolerance is zero LSB
 * everywhere: every routine's contract is an exactly defined integer.
 *
 * Inputs: exhaustive where the domain is small (every Q15 value), strided
 * sweeps over Q15 x Q15 pairs, the edge values of each width (MIN, MAX, 0,
 * +-1 LSB, powers of two and their neighbours, rounding ties of both signs)
 * crossed with each other, and pseudo-random values from a fixed-seed
 * splitmix64 generator (so any failure reproduces) spread over all
 * magnitudes, not just large ones.
 *
 * Inner loops report a mismatch with ck_abort_msg only on failure:
 * ck_assert_* records a mark point per call, which would dominate the run
 * time of millions of comparisons. Set FIXP_VERBOSE=1 to print how many
 * comparisons each test made.
 */
#include <check.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>

#include "core/canfdi_fixp.h"
#include "core/canfdi_intrin.h"
#include "unit_main.h"

__extension__ typedef __int128 i128;

/* ------------------------------------------------------------------------ */
/* Harness                                                                  */
/* ------------------------------------------------------------------------ */

static unsigned long g_checks;

#define EXPECT(cond, ...)          \
  do {                             \
    g_checks++;                    \
    if (!(cond)) {                 \
      ck_abort_msg(__VA_ARGS__);   \
    }                              \
  } while (0)

static void report_checks(const char *name)
{
  if (getenv("FIXP_VERBOSE") != NULL) {
    fprintf(stderr, "  %-28s %10lu comparisons\n", name, g_checks);
  }
  g_checks = 0U;
}
#define DONE() report_checks(__func__)

/* splitmix64: tiny, good enough to spread test inputs, reproducible. */
static uint64_t g_rng;
static void rng_seed(uint64_t s) { g_rng = s; }
static uint64_t rnd64(void)
{
  uint64_t z = (g_rng += 0x9E3779B97F4A7C15U);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9U;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBU;
  return z ^ (z >> 31);
}

/* Random int32 whose magnitude is spread over all bit lengths. */
static int32_t rnd_s32(void)
{
  const uint64_t r = rnd64();
  const uint32_t bits = (uint32_t)(r >> 32);
  const unsigned drop = (unsigned)((r >> 8) % 40U); /* >= 32: full width */
  const uint32_t mag = (drop < 32U) ? (bits >> drop) : bits;
  const int64_t v = (int64_t)(int32_t)(mag & 0x7FFFFFFFU);
  int64_t s = ((r & 1U) != 0U) ? -v : v;
  if ((r & 0x6U) == 0x6U && drop >= 32U) {
    s = (int64_t)canfdi_wrap_u32_to_s32(bits); /* raw pattern, incl. MIN */
  }
  return (int32_t)s;
}

static int64_t rnd_s64(void)
{
  const uint64_t r = rnd64();
  const uint64_t sel = rnd64();
  const unsigned drop = (unsigned)(sel % 72U); /* >= 64: full width */
  int64_t v = (drop < 64U) ? (int64_t)((r & 0x7FFFFFFFFFFFFFFFU) >> drop)
                           : canfdi_wrap_u64_to_s64(r);
  if (((sel >> 8) & 1U) != 0U && v != INT64_MIN) {
    v = -v;
  }
  return v;
}

/* ------------------------------------------------------------------------ */
/* Exact references                                                         */
/* ------------------------------------------------------------------------ */

/* floor(x / 2^n) by division; exact for |x| < 2^126 (n capped there). */
static i128 ref_floor_pow2(i128 x, unsigned n)
{
  const unsigned s = (n > 126U) ? 126U : n;
  const i128 d = (i128)1 << s;
  i128 q = x / d; /* truncates toward zero */
  if ((x % d != 0) && (x < 0)) {
    q -= 1;
  }
  return q;
}

/* floor(x / 2^n + 1/2): round half up; n = 0 is the identity. */
static i128 ref_round_pow2(i128 x, unsigned n)
{
  i128 y = x;
  if (n > 0U) {
    const unsigned s = (n > 125U) ? 125U : n;
    y = ref_floor_pow2(x + ((i128)1 << (s - 1U)), s);
  }
  return y;
}

static i128 ref_clamp(i128 x, i128 lo, i128 hi) { return (x < lo) ? lo : ((x > hi) ? hi : x); }
static int16_t ref_sat16(i128 x) { return (int16_t)ref_clamp(x, INT16_MIN, INT16_MAX); }
static int32_t ref_sat32(i128 x) { return (int32_t)ref_clamp(x, INT32_MIN, INT32_MAX); }
static int64_t ref_sat64(i128 x) { return (int64_t)ref_clamp(x, INT64_MIN, INT64_MAX); }

/* sat(x * 2^n); for n > 64 every nonzero |x| >= 1 overflows 64 bits. */
static i128 ref_shl(i128 x, unsigned n, i128 lo, i128 hi)
{
  i128 y;
  if (x == 0) {
    y = 0;
  } else if (n > 64U) {
    y = (x > 0) ? hi : lo;
  } else {
    y = ref_clamp(x * ((i128)1 << n), lo, hi);
  }
  return y;
}

/* num/den rounded to nearest, ties away from zero; den != 0. */
static i128 ref_div_away(i128 num, i128 den)
{
  const int neg = (num < 0) != (den < 0);
  const i128 a = (num < 0) ? -num : num;
  const i128 b = (den < 0) ? -den : den;
  const i128 q = (2 * a + b) / (2 * b);
  return neg ? -q : q;
}

/* floor(a / b) for b > 0. */
static i128 ref_floor_div(i128 a, i128 b)
{
  i128 q = a / b;
  if ((a % b != 0) && (a < 0)) {
    q -= 1;
  }
  return q;
}

/* The documented division-by-zero rule. */
static i128 ref_div0(i128 num, i128 lo, i128 hi) { return (num > 0) ? hi : ((num < 0) ? lo : 0); }

/* ------------------------------------------------------------------------ */
/* Edge values                                                              */
/* ------------------------------------------------------------------------ */

static const int32_t EDGE32[] = {
  INT32_MIN, INT32_MIN + 1, INT32_MIN + 2, -1073741825, -1073741824, -1073741823,
  -65537, -65536, -65535, -49152, -32769, -32768, -32767, -16384, -5, -3, -2, -1,
  0, 1, 2, 3, 5, 16384, 32767, 32768, 32769, 49152, 65535, 65536, 65537,
  1073741823, 1073741824, 1073741825, INT32_MAX - 2, INT32_MAX - 1, INT32_MAX,
};
#define N_EDGE32 (sizeof EDGE32 / sizeof EDGE32[0])

static const int64_t EDGE64[] = {
  INT64_MIN, INT64_MIN + 1, INT64_MIN + 2, INT64_MIN + 0xFFFFFFFFLL, INT64_MIN + 0x100000000LL,
  -4611686018427387905LL, -4611686018427387904LL, -4294967297LL, -4294967296LL, -4294967295LL,
  -2147483649LL, -2147483648LL, -2147483647LL, -65536, -3, -2, -1, 0, 1, 2, 3, 65536,
  2147483647LL, 2147483648LL, 2147483649LL, 4294967295LL, 4294967296LL, 4294967297LL,
  4611686018427387903LL, 4611686018427387904LL, INT64_MAX - 0x100000000LL, INT64_MAX - 2,
  INT64_MAX - 1, INT64_MAX,
};
#define N_EDGE64 (sizeof EDGE64 / sizeof EDGE64[0])

static const canfdi_q15_t EDGE16[] = {
  INT16_MIN, INT16_MIN + 1, INT16_MIN + 2, -16385, -16384, -16383, -256, -255, -3, -2, -1,
  0, 1, 2, 3, 255, 256, 16383, 16384, 16385, INT16_MAX - 2, INT16_MAX - 1, INT16_MAX,
};
#define N_EDGE16 (sizeof EDGE16 / sizeof EDGE16[0])

/* Q15 partner set for sweeps over all 65536 first operands: the edges plus
 * every 257th value (257 is odd and coprime with 2^k, so the low bits of the
 * partners take every pattern). */
static canfdi_q15_t g_partners[N_EDGE16 + 256U];
static size_t g_npartners;
static void build_partners(void)
{
  size_t k = 0U;
  int32_t v;
  for (k = 0U; k < N_EDGE16; k++) {
    g_partners[k] = EDGE16[k];
  }
  for (v = INT16_MIN; v <= INT16_MAX; v += 257) {
    g_partners[k++] = (canfdi_q15_t)v;
  }
  g_npartners = k;
}

/* Shift counts exercised by the loop tests: 0..71, then far out of range.
 * One loop iteration covers a group of 8 counts: each iteration is a forked
 * process, and a fork under ASan costs milliseconds. */
#define N_SHIFT_ITERS 75
#define SHIFT_GROUP 8
#define N_SHIFT_GROUPS ((N_SHIFT_ITERS + SHIFT_GROUP - 1) / SHIFT_GROUP)
#define FOR_SHIFT_GROUP(it) \
  for (int it = _i * SHIFT_GROUP; it < (_i + 1) * SHIFT_GROUP && it < N_SHIFT_ITERS; it++)
static unsigned shift_for_iter(int i)
{
  static const unsigned far[] = {100U, 1000U, UINT_MAX};
  return (i < 72) ? (unsigned)i : far[i - 72];
}

/* ------------------------------------------------------------------------ */
/* TCase shifts                                                             */
/* ------------------------------------------------------------------------ */

static void check_asr32(unsigned n, int it)
{
  size_t k;
  int i;
  rng_seed(0x1000U + (uint64_t)it);
  for (k = 0U; k < N_EDGE32 + 20000U; k++) {
    const int32_t x = (k < N_EDGE32) ? EDGE32[k] : rnd_s32();
    const int32_t got = canfdi_asr32(x, n);
    const int32_t got_r = canfdi_asr32_rnd(x, n);
    EXPECT(got == (int32_t)ref_floor_pow2(x, n), "asr32(%ld, %u) = %ld", (long)x, n, (long)got);
    EXPECT(got_r == (int32_t)ref_round_pow2(x, n), "asr32_rnd(%ld, %u) = %ld", (long)x, n,
           (long)got_r);
  }
  /* Every x with low bits around the rounding point (both signs). */
  if (n >= 1U && n <= 31U) {
    for (i = -2; i <= 2; i++) {
      const int64_t half = (int64_t)1 << (n - 1U);
      const int64_t base[] = {half, -half, 3 * half, -3 * half};
      size_t b;
      for (b = 0U; b < 4U; b++) {
        const int64_t x64 = base[b] + i;
        if (x64 >= INT32_MIN && x64 <= INT32_MAX) {
          const int32_t x = (int32_t)x64;
          EXPECT(canfdi_asr32_rnd(x, n) == (int32_t)ref_round_pow2(x, n), "tie asr32_rnd(%ld, %u)",
                 (long)x, n);
        }
      }
    }
  }
}

START_TEST(test_asr32)
{
  FOR_SHIFT_GROUP(it) {
    check_asr32(shift_for_iter(it), it);
  }
  DONE();
}
END_TEST

static void check_asr64(unsigned n, int it)
{
  size_t k;
  rng_seed(0x2000U + (uint64_t)it);
  for (k = 0U; k < N_EDGE64 + 20000U; k++) {
    const int64_t x = (k < N_EDGE64) ? EDGE64[k] : rnd_s64();
    const int64_t got = canfdi_asr64(x, n);
    const int64_t got_r = canfdi_asr64_rnd(x, n);
    EXPECT(got == (int64_t)ref_floor_pow2(x, n), "asr64(%lld, %u) = %lld", (long long)x, n,
           (long long)got);
    EXPECT(got_r == (int64_t)ref_round_pow2(x, n), "asr64_rnd(%lld, %u) = %lld", (long long)x, n,
           (long long)got_r);
  }
}

START_TEST(test_asr64)
{
  FOR_SHIFT_GROUP(it) {
    check_asr64(shift_for_iter(it), it);
  }
  DONE();
}
END_TEST

/* Hand-derived ties: half up means -2.5 -> -2 and +2.5 -> +3. */
START_TEST(test_round_ties)
{
  ck_assert_int_eq(canfdi_asr32_rnd(5, 1U), 3);
  ck_assert_int_eq(canfdi_asr32_rnd(-5, 1U), -2);
  ck_assert_int_eq(canfdi_asr32_rnd(-3, 1U), -1);
  ck_assert_int_eq(canfdi_asr32_rnd(-1, 1U), 0);
  ck_assert_int_eq(canfdi_asr32_rnd(INT32_MAX, 1U), 1073741824);
  ck_assert_int_eq(canfdi_asr32_rnd(INT32_MIN, 31U), -1);
  ck_assert_int_eq(canfdi_asr32_rnd(-1073741824, 31U), 0); /* -0.5 -> 0 */
  ck_assert_int_eq(canfdi_asr32_rnd(1073741824, 31U), 1);  /* +0.5 -> 1 */
  ck_assert_int_eq(canfdi_asr32_rnd(INT32_MIN, 32U), 0);
  ck_assert_int_eq(canfdi_asr32(INT32_MIN, 31U), -1);
  ck_assert_int_eq(canfdi_asr32(-1, 0U), -1);
  ck_assert_int_eq(canfdi_asr32(-1, 31U), -1);
  ck_assert(canfdi_asr64_rnd(INT64_MAX, 1U) == ((int64_t)1 << 62));
  ck_assert(canfdi_asr64_rnd(INT64_MIN, 63U) == -1);
  ck_assert(canfdi_asr64_rnd(INT64_MIN, 64U) == 0);
  ck_assert(canfdi_asr64(INT64_MIN, 63U) == -1);
  ck_assert(canfdi_asr64(INT64_MIN + 1, 63U) == -1);
}
END_TEST

static void check_shl(unsigned n, int it)
{
  size_t k;
  rng_seed(0x3000U + (uint64_t)it);
  for (k = 0U; k < N_EDGE64 + 20000U; k++) {
    const int32_t x32 = (k < N_EDGE32) ? EDGE32[k] : rnd_s32();
    const int64_t x64 = (k < N_EDGE64) ? EDGE64[k] : rnd_s64();
    const int32_t g32 = canfdi_shl32_sat(x32, n);
    const int64_t g64 = canfdi_shl64_sat(x64, n);
    EXPECT(g32 == (int32_t)ref_shl(x32, n, INT32_MIN, INT32_MAX), "shl32_sat(%ld, %u) = %ld",
           (long)x32, n, (long)g32);
    EXPECT(g64 == (int64_t)ref_shl(x64, n, INT64_MIN, INT64_MAX), "shl64_sat(%lld, %u) = %lld",
           (long long)x64, n, (long long)g64);
  }
}

START_TEST(test_shl)
{
  FOR_SHIFT_GROUP(it) {
    check_shl(shift_for_iter(it), it);
  }
  DONE();
}
END_TEST

/* ------------------------------------------------------------------------ */
/* TCase saturation/conversion                                              */
/* ------------------------------------------------------------------------ */

START_TEST(test_sat_width)
{
  int64_t x;
  unsigned k;
  /* Every value within 2^17 of each 16-bit boundary, plus random. */
  for (x = INT16_MIN - 131072; x <= INT16_MAX + 131072; x++) {
    EXPECT(canfdi_sat_s32_to_s16((int32_t)x) == ref_sat16(x), "sat16(%lld)", (long long)x);
  }
  for (x = -131072; x <= 131072; x++) {
    const int64_t xs[] = {(int64_t)INT32_MIN + x, (int64_t)INT32_MAX + x};
    EXPECT(canfdi_sat_s64_to_s32(xs[0]) == ref_sat32(xs[0]), "sat32(%lld)", (long long)xs[0]);
    EXPECT(canfdi_sat_s64_to_s32(xs[1]) == ref_sat32(xs[1]), "sat32(%lld)", (long long)xs[1]);
  }
  rng_seed(0x4000U);
  for (k = 0U; k < 100000U; k++) {
    const int32_t a = rnd_s32();
    const int64_t b = rnd_s64();
    EXPECT(canfdi_sat_s32_to_s16(a) == ref_sat16(a), "sat16(%ld)", (long)a);
    EXPECT(canfdi_sat_s64_to_s32(b) == ref_sat32(b), "sat32(%lld)", (long long)b);
    EXPECT(canfdi_s64_fits_s32(b) == ((b >= INT32_MIN) && (b <= INT32_MAX)), "fits32(%lld)", (long long)b);
  }
  for (k = 0U; k < N_EDGE64; k++) {
    EXPECT(canfdi_sat_s64_to_s32(EDGE64[k]) == ref_sat32(EDGE64[k]), "sat32 edge %u", k);
    EXPECT(canfdi_s64_fits_s32(EDGE64[k]) == ((EDGE64[k] >= INT32_MIN) && (EDGE64[k] <= INT32_MAX)), "fits32 edge %u",
           k);
  }
  DONE();
}
END_TEST

START_TEST(test_wrap_clamp)
{
  unsigned k;
  const uint32_t u32[] = {0U, 1U, 0x7FFFFFFEU, 0x7FFFFFFFU, 0x80000000U, 0x80000001U, 0xFFFFFFFFU};
  const uint64_t u64[] = {0U, 1U, 0x7FFFFFFFFFFFFFFFU, 0x8000000000000000U, 0xFFFFFFFFFFFFFFFFU};
  for (k = 0U; k < sizeof u32 / sizeof u32[0]; k++) {
    const i128 want = (u32[k] > 0x7FFFFFFFU) ? (i128)u32[k] - ((i128)1 << 32) : (i128)u32[k];
    EXPECT(canfdi_wrap_u32_to_s32(u32[k]) == want, "wrap32(%lu)", (unsigned long)u32[k]);
  }
  for (k = 0U; k < sizeof u64 / sizeof u64[0]; k++) {
    const i128 want = (u64[k] > 0x7FFFFFFFFFFFFFFFU) ? (i128)u64[k] - ((i128)1 << 64) : (i128)u64[k];
    EXPECT(canfdi_wrap_u64_to_s64(u64[k]) == want, "wrap64(%llu)", (unsigned long long)u64[k]);
  }
  rng_seed(0x4100U);
  for (k = 0U; k < 100000U; k++) {
    const uint64_t r = rnd64();
    const uint32_t u = (uint32_t)r;
    const int32_t a = rnd_s32();
    const int32_t b = rnd_s32();
    const int32_t x = rnd_s32();
    const int32_t lo = (a < b) ? a : b;
    const int32_t hi = (a < b) ? b : a;
    EXPECT((uint32_t)canfdi_wrap_u32_to_s32(u) == u, "wrap32 round trip %lu", (unsigned long)u);
    EXPECT((uint64_t)canfdi_wrap_u64_to_s64(r) == r, "wrap64 round trip");
    EXPECT(canfdi_clamp_s32(x, lo, hi) == (int32_t)ref_clamp(x, lo, hi), "clamp(%ld, %ld, %ld)",
           (long)x, (long)lo, (long)hi);
  }
  DONE();
}
END_TEST

START_TEST(test_q15_q31_conv)
{
  int32_t v;
  unsigned k;
  /* Exhaustive Q15 -> Q31 (exact) and back (must be the identity). */
  for (v = INT16_MIN; v <= INT16_MAX; v++) {
    const canfdi_q15_t x = (canfdi_q15_t)v;
    const canfdi_q31_t w = canfdi_q15_to_q31(x);
    EXPECT(w == (int32_t)v * 65536, "q15_to_q31(%ld) = %ld", (long)v, (long)w);
    EXPECT(canfdi_q31_to_q15(w) == x, "round trip %ld", (long)v);
  }
  /* Q31 -> Q15 around every Q15 step: each rounding point and tie, both signs. */
  for (v = INT16_MIN; v <= INT16_MAX; v++) {
    const int32_t offs[] = {-32769, -32768, -32767, -1, 0, 1, 32767, 32768, 32769};
    for (k = 0U; k < sizeof offs / sizeof offs[0]; k++) {
      const int64_t x64 = (int64_t)v * 65536 + offs[k];
      if (x64 >= INT32_MIN && x64 <= INT32_MAX) {
        const int32_t x = (int32_t)x64;
        EXPECT(canfdi_q31_to_q15(x) == ref_sat16(ref_round_pow2(x, 16U)), "q31_to_q15(%ld)", (long)x);
      }
    }
  }
  EXPECT(canfdi_q31_to_q15(INT32_MAX) == INT16_MAX, "q31_to_q15(MAX) saturates");
  rng_seed(0x4200U);
  for (k = 0U; k < 100000U; k++) {
    const int32_t x = rnd_s32();
    EXPECT(canfdi_q31_to_q15(x) == ref_sat16(ref_round_pow2(x, 16U)), "q31_to_q15(%ld)", (long)x);
  }
  DONE();
}
END_TEST

/* Loop index = a group of 8 from_frac values (0..31); all to_frac 0..31. */
START_TEST(test_qconv)
{
  unsigned from;
  unsigned to;
  size_t k;
  rng_seed(0x4300U + (uint64_t)_i);
  for (from = 8U * (unsigned)_i; from < 8U * (unsigned)(_i + 1); from++) {
    for (to = 0U; to <= 31U; to++) {
      for (k = 0U; k < N_EDGE32 + 2000U; k++) {
        const int32_t x = (k < N_EDGE32) ? EDGE32[k] : rnd_s32();
        const i128 want = (to >= from) ? ref_shl(x, to - from, INT32_MIN, INT32_MAX)
                                       : ref_round_pow2(x, from - to);
        const int32_t got = canfdi_qconv_s32(x, from, to);
        EXPECT(got == (int32_t)want, "qconv(%ld, %u, %u) = %ld", (long)x, from, to, (long)got);
      }
    }
  }
  DONE();
}
END_TEST

/* The constant macros must be usable in constant expressions. */
CANFDI_STATIC_ASSERT(CANFDI_Q15_RATIO(1, 2) == 16384, q15_half);
CANFDI_STATIC_ASSERT(CANFDI_Q15_RATIO(-1, 1) == INT16_MIN, q15_minus_one);
CANFDI_STATIC_ASSERT(CANFDI_Q31_RATIO(-1, 4) == -536870912, q31_minus_quarter);
CANFDI_STATIC_ASSERT(CANFDI_Q15_RATIO(-1, 65536) == 0, q15_tie_up_negative);
CANFDI_STATIC_ASSERT(CANFDI_Q15_RATIO(1, 65536) == 1, q15_tie_up_positive);
CANFDI_STATIC_ASSERT(CANFDI_Q31_RATIO(1, 1) == INT32_MAX, q31_one_saturates);

static void check_ratio(int64_t num, int64_t den)
{
  /* round half up of num * 2^k / den = floor((2 * num * 2^k + den) / (2 * den)) */
  const i128 q15 = ref_sat16(ref_floor_div((i128)2 * num * 32768 + den, (i128)2 * den));
  const i128 q31 = ref_sat32(ref_floor_div((i128)2 * num * 2147483648LL + den, (i128)2 * den));
  EXPECT(CANFDI_Q15_RATIO(num, den) == q15, "Q15_RATIO(%lld, %lld)", (long long)num, (long long)den);
  EXPECT(CANFDI_Q31_RATIO(num, den) == q31, "Q31_RATIO(%lld, %lld)", (long long)num, (long long)den);
}

START_TEST(test_ratio_macros)
{
  int64_t den;
  int64_t num;
  unsigned j;
  unsigned m;
  /* Small denominators densely, numerators past +-den (saturation). */
  for (den = 1; den <= 3000; den += (den < 300) ? 1 : 37) {
    const int64_t step = (den < 64) ? 1 : den / 61;
    for (num = -2 * den - 1; num <= 2 * den + 1; num += step) {
      check_ratio(num, den);
    }
    check_ratio(den - 1, den);
    check_ratio(den, den);
    check_ratio(-den - 1, den);
  }
  /* Powers of two up to the documented 2^30: the only denominators that
   * produce exact ties (+-(2m+1)/2 LSB), plus the ends of the range. */
  for (j = 0U; j <= 30U; j++) {
    const int64_t d = (int64_t)1 << j;
    check_ratio(-d, d);
    check_ratio(d - 1, d);
    check_ratio(-1, d);
    check_ratio(1, d);
    check_ratio((int64_t)1 << 30, d);
    check_ratio(-((int64_t)1 << 30), d);
    for (m = 0U; m < 8U; m++) {
      const unsigned ks[] = {15U, 31U};
      unsigned t;
      for (t = 0U; t < 2U; t++) {
        if (j > ks[t]) {
          const int64_t tie = (int64_t)(2U * m + 1U) << (j - ks[t] - 1U); /* (2m+1)/2 LSB */
          if (tie < d) {
            check_ratio(tie, d);
            check_ratio(-tie, d);
          }
        }
      }
    }
  }
  DONE();
}
END_TEST

/* ------------------------------------------------------------------------ */
/* TCase add/sub/neg/abs                                                    */
/* ------------------------------------------------------------------------ */

START_TEST(test_q15_neg_abs_exhaustive)
{
  int32_t v;
  for (v = INT16_MIN; v <= INT16_MAX; v++) {
    const canfdi_q15_t x = (canfdi_q15_t)v;
    EXPECT(canfdi_q15_neg(x) == ref_sat16(-(i128)v), "q15_neg(%ld)", (long)v);
    EXPECT(canfdi_q15_abs(x) == ref_sat16(v < 0 ? -(i128)v : v), "q15_abs(%ld)", (long)v);
  }
  DONE();
}
END_TEST

/* Loop index selects a block of 16384 first operands; partners: g_partners. */
START_TEST(test_q15_add_sub_sweep)
{
  int32_t v;
  size_t k;
  build_partners();
  for (v = INT16_MIN + _i * 16384; v < INT16_MIN + (_i + 1) * 16384; v++) {
    const canfdi_q15_t a = (canfdi_q15_t)v;
    for (k = 0U; k < g_npartners; k++) {
      const canfdi_q15_t b = g_partners[k];
      EXPECT(canfdi_q15_add(a, b) == ref_sat16((i128)a + b), "q15_add(%d, %d)", a, b);
      EXPECT(canfdi_q15_sub(a, b) == ref_sat16((i128)a - b), "q15_sub(%d, %d)", a, b);
    }
  }
  DONE();
}
END_TEST

START_TEST(test_q31_add_sub_neg_abs)
{
  size_t i;
  size_t j;
  unsigned k;
  for (i = 0U; i < N_EDGE32; i++) {
    const int32_t a = EDGE32[i];
    EXPECT(canfdi_q31_neg(a) == ref_sat32(-(i128)a), "q31_neg(%ld)", (long)a);
    EXPECT(canfdi_q31_abs(a) == ref_sat32(a < 0 ? -(i128)a : a), "q31_abs(%ld)", (long)a);
    for (j = 0U; j < N_EDGE32; j++) {
      const int32_t b = EDGE32[j];
      EXPECT(canfdi_q31_add(a, b) == ref_sat32((i128)a + b), "q31_add(%ld, %ld)", (long)a, (long)b);
      EXPECT(canfdi_q31_sub(a, b) == ref_sat32((i128)a - b), "q31_sub(%ld, %ld)", (long)a, (long)b);
    }
  }
  rng_seed(0x5000U);
  for (k = 0U; k < 200000U; k++) {
    const int32_t a = rnd_s32();
    const int32_t b = rnd_s32();
    EXPECT(canfdi_add_s32_sat(a, b) == ref_sat32((i128)a + b), "add_s32(%ld, %ld)", (long)a, (long)b);
    EXPECT(canfdi_sub_s32_sat(a, b) == ref_sat32((i128)a - b), "sub_s32(%ld, %ld)", (long)a, (long)b);
    EXPECT(canfdi_q31_neg(a) == ref_sat32(-(i128)a), "q31_neg(%ld)", (long)a);
    EXPECT(canfdi_q31_abs(a) == ref_sat32(a < 0 ? -(i128)a : a), "q31_abs(%ld)", (long)a);
  }
  DONE();
}
END_TEST

START_TEST(test_s64_add_sub)
{
  size_t i;
  size_t j;
  unsigned k;
  for (i = 0U; i < N_EDGE64; i++) {
    for (j = 0U; j < N_EDGE64; j++) {
      const int64_t a = EDGE64[i];
      const int64_t b = EDGE64[j];
      EXPECT(canfdi_add_s64_sat(a, b) == ref_sat64((i128)a + b), "add_s64(%lld, %lld)", (long long)a,
             (long long)b);
      EXPECT(canfdi_sub_s64_sat(a, b) == ref_sat64((i128)a - b), "sub_s64(%lld, %lld)", (long long)a,
             (long long)b);
    }
  }
  rng_seed(0x5100U);
  for (k = 0U; k < 200000U; k++) {
    const int64_t a = rnd_s64();
    const int64_t b = rnd_s64();
    EXPECT(canfdi_add_s64_sat(a, b) == ref_sat64((i128)a + b), "add_s64(%lld, %lld)", (long long)a,
           (long long)b);
    EXPECT(canfdi_sub_s64_sat(a, b) == ref_sat64((i128)a - b), "sub_s64(%lld, %lld)", (long long)a,
           (long long)b);
  }
  DONE();
}
END_TEST

/* ------------------------------------------------------------------------ */
/* TCase multiply                                                           */
/* ------------------------------------------------------------------------ */

/* Loop index selects a block of 16384 first operands; partners: g_partners.
 * Reference: exact int64 product, floor / round-half-up by division. */
START_TEST(test_q15_mul_sweep)
{
  int32_t v;
  size_t k;
  build_partners();
  for (v = INT16_MIN + _i * 16384; v < INT16_MIN + (_i + 1) * 16384; v++) {
    const canfdi_q15_t a = (canfdi_q15_t)v;
    for (k = 0U; k < g_npartners; k++) {
      const canfdi_q15_t b = g_partners[k];
      const int64_t p = (int64_t)a * b;
      EXPECT(canfdi_q15_mul(a, b) == ref_sat16(ref_floor_pow2(p, 15U)), "q15_mul(%d, %d)", a, b);
      EXPECT(canfdi_q15_mul_rnd(a, b) == ref_sat16(ref_round_pow2(p, 15U)), "q15_mul_rnd(%d, %d)",
             a, b);
    }
  }
  DONE();
}
END_TEST

START_TEST(test_q15_mul_facts)
{
  /* Hand-derived: -1 x -1 saturates; ties of both signs round up. */
  ck_assert_int_eq(canfdi_q15_mul(INT16_MIN, INT16_MIN), INT16_MAX);
  ck_assert_int_eq(canfdi_q15_mul_rnd(INT16_MIN, INT16_MIN), INT16_MAX);
  ck_assert_int_eq(canfdi_q15_mul(INT16_MIN, INT16_MAX), -INT16_MAX);
  ck_assert_int_eq(canfdi_q15_mul(1, 1), 0);         /* 2^-30 floors to 0 */
  ck_assert_int_eq(canfdi_q15_mul(-1, 1), -1);       /* -2^-30 floors to -1 LSB */
  ck_assert_int_eq(canfdi_q15_mul_rnd(-1, 1), 0);
  ck_assert_int_eq(canfdi_q15_mul_rnd(1, 16384), 1);   /* +0.5 LSB -> 1 */
  ck_assert_int_eq(canfdi_q15_mul_rnd(-1, 16384), 0);  /* -0.5 LSB -> 0 */
  ck_assert_int_eq(canfdi_q15_mul_rnd(3, 16384), 2);   /* +1.5 LSB -> 2 */
  ck_assert_int_eq(canfdi_q15_mul_rnd(-3, 16384), -1); /* -1.5 LSB -> -1 */
}
END_TEST

START_TEST(test_q31_mul)
{
  size_t i;
  size_t j;
  unsigned k;
  for (i = 0U; i < N_EDGE32; i++) {
    for (j = 0U; j < N_EDGE32; j++) {
      const int32_t a = EDGE32[i];
      const int32_t b = EDGE32[j];
      const i128 p = (i128)a * b;
      EXPECT(canfdi_q31_mul(a, b) == ref_sat32(ref_floor_pow2(p, 31U)), "q31_mul(%ld, %ld)",
             (long)a, (long)b);
      EXPECT(canfdi_q31_mul_rnd(a, b) == ref_sat32(ref_round_pow2(p, 31U)), "q31_mul_rnd(%ld, %ld)",
             (long)a, (long)b);
    }
  }
  rng_seed(0x6000U);
  for (k = 0U; k < 300000U; k++) {
    const int32_t a = rnd_s32();
    const int32_t b = rnd_s32();
    const i128 p = (i128)a * b;
    EXPECT(canfdi_q31_mul(a, b) == ref_sat32(ref_floor_pow2(p, 31U)), "q31_mul(%ld, %ld)", (long)a,
           (long)b);
    EXPECT(canfdi_q31_mul_rnd(a, b) == ref_sat32(ref_round_pow2(p, 31U)), "q31_mul_rnd(%ld, %ld)",
           (long)a, (long)b);
  }
  ck_assert_int_eq(canfdi_q31_mul(INT32_MIN, INT32_MIN), INT32_MAX);
  ck_assert_int_eq(canfdi_q31_mul_rnd(1, 1073741824), 1);  /* +0.5 LSB */
  ck_assert_int_eq(canfdi_q31_mul_rnd(-1, 1073741824), 0); /* -0.5 LSB */
  DONE();
}
END_TEST

static void check_mul_s32_qn(unsigned n, int it)
{
  size_t i;
  size_t j;
  unsigned k;
  rng_seed(0x6100U + (uint64_t)it);
  for (i = 0U; i < N_EDGE32; i++) {
    for (j = 0U; j < N_EDGE32; j++) {
      const int32_t a = EDGE32[i];
      const int32_t b = EDGE32[j];
      const int32_t got = canfdi_mul_s32_qn(a, b, n);
      EXPECT(got == ref_sat32(ref_round_pow2((i128)a * b, n)), "mul_s32_qn(%ld, %ld, %u) = %ld",
             (long)a, (long)b, n, (long)got);
    }
  }
  for (k = 0U; k < 10000U; k++) {
    const int32_t a = rnd_s32();
    const int32_t b = rnd_s32();
    const int32_t got = canfdi_mul_s32_qn(a, b, n);
    EXPECT(got == ref_sat32(ref_round_pow2((i128)a * b, n)), "mul_s32_qn(%ld, %ld, %u) = %ld",
           (long)a, (long)b, n, (long)got);
  }
}

START_TEST(test_mul_s32_qn)
{
  FOR_SHIFT_GROUP(it) {
    check_mul_s32_qn(shift_for_iter(it), it);
  }
  DONE();
}
END_TEST

START_TEST(test_mul_s64_q31)
{
  size_t i;
  size_t j;
  unsigned k;
  for (i = 0U; i < N_EDGE64; i++) {
    for (j = 0U; j < N_EDGE32; j++) {
      const int64_t a = EDGE64[i];
      const int32_t b = EDGE32[j];
      const int64_t got = canfdi_mul_s64_q31(a, b);
      EXPECT(got == ref_sat64(ref_round_pow2((i128)a * b, 31U)), "mul_s64_q31(%lld, %ld) = %lld",
             (long long)a, (long)b, (long long)got);
    }
  }
  /* The case where 2*(ah*b) alone overflows but the result may not:
   * ah = -2^31, b = -1.0, every low word class. */
  rng_seed(0x6200U);
  for (k = 0U; k < 20000U; k++) {
    const int64_t a = INT64_MIN + (int64_t)(rnd64() & 0xFFFFFFFFU);
    const int64_t got = canfdi_mul_s64_q31(a, INT32_MIN);
    EXPECT(got == ref_sat64(ref_round_pow2((i128)a * INT32_MIN, 31U)), "mul_s64_q31(%lld, MIN)",
           (long long)a);
  }
  for (k = 0U; k < 300000U; k++) {
    const int64_t a = rnd_s64();
    const int32_t b = rnd_s32();
    const int64_t got = canfdi_mul_s64_q31(a, b);
    EXPECT(got == ref_sat64(ref_round_pow2((i128)a * b, 31U)), "mul_s64_q31(%lld, %ld) = %lld",
           (long long)a, (long)b, (long long)got);
  }
  DONE();
}
END_TEST

/* ------------------------------------------------------------------------ */
/* TCase divide                                                             */
/* ------------------------------------------------------------------------ */

/* Loop index selects a block of 16384 numerators; denominators: g_partners
 * (includes 0, +-1, MIN, MAX). */
START_TEST(test_q15_div_sweep)
{
  int32_t v;
  size_t k;
  build_partners();
  for (v = INT16_MIN + _i * 16384; v < INT16_MIN + (_i + 1) * 16384; v++) {
    const canfdi_q15_t num = (canfdi_q15_t)v;
    for (k = 0U; k < g_npartners; k++) {
      const canfdi_q15_t den = g_partners[k];
      const i128 want = (den == 0) ? ref_div0(num, INT16_MIN, INT16_MAX)
                                   : ref_div_away((i128)num * 32768, den);
      const canfdi_q15_t got = canfdi_q15_div(num, den);
      EXPECT(got == ref_sat16(want), "q15_div(%d, %d) = %d", num, den, got);
    }
  }
  DONE();
}
END_TEST

START_TEST(test_div_facts)
{
  /* Hand-derived from the contract. */
  ck_assert_int_eq(canfdi_q15_div(0, 0), 0);
  ck_assert_int_eq(canfdi_q15_div(1, 0), INT16_MAX);
  ck_assert_int_eq(canfdi_q15_div(-1, 0), INT16_MIN);
  ck_assert_int_eq(canfdi_q15_div(INT16_MIN, -1), INT16_MAX);
  ck_assert_int_eq(canfdi_q15_div(-100, 100), INT16_MIN); /* exactly -1.0 */
  ck_assert_int_eq(canfdi_q15_div(100, 100), INT16_MAX);  /* +1.0 saturates */
  ck_assert_int_eq(canfdi_q15_div(1, 3), 10923);          /* 10922.67 */
  ck_assert_int_eq(canfdi_q15_div(-1, 3), -10923);
  ck_assert_int_eq(canfdi_q15_div(1, 65536 / 2 - 1), 1);  /* 1.00003 */
  ck_assert_int_eq(canfdi_q15_div(1, -32768), -1);        /* -1 LSB exactly */
  ck_assert_int_eq(canfdi_q31_div(0, 0), 0);
  ck_assert_int_eq(canfdi_q31_div(5, 0), INT32_MAX);
  ck_assert_int_eq(canfdi_q31_div(INT32_MIN, 0), INT32_MIN);
  ck_assert_int_eq(canfdi_q31_div(INT32_MIN, -1), INT32_MAX);
  ck_assert_int_eq(canfdi_q31_div(INT32_MIN, INT32_MIN), INT32_MAX);
  ck_assert_int_eq(canfdi_q31_div(INT32_MIN, INT32_MAX), INT32_MIN);
  ck_assert_int_eq(canfdi_div_s32_qn(INT32_MIN, -1, 0U), INT32_MAX);
  ck_assert_int_eq(canfdi_div_s32_qn(7, 2, 0U), 4);   /* 3.5 -> 4 */
  ck_assert_int_eq(canfdi_div_s32_qn(-7, 2, 0U), -4); /* -3.5 -> -4 (away from zero) */
  ck_assert_int_eq(canfdi_div_s32_qn(5, 3, 0U), 2);
  ck_assert_int_eq(canfdi_div_s32_qn(-1, INT32_MIN, 31U), 1);
  ck_assert_int_eq(canfdi_div_s32_qn(1, INT32_MIN, 32U), -2);
  ck_assert_int_eq(canfdi_div_s32_qn(1, 1, UINT_MAX), INT32_MAX);
  ck_assert_int_eq(canfdi_div_s32_qn(-1, 1, UINT_MAX), INT32_MIN);
  ck_assert_int_eq(canfdi_div_s32_qn(0, 1, UINT_MAX), 0);
}
END_TEST

START_TEST(test_q31_div)
{
  size_t i;
  size_t j;
  unsigned k;
  for (i = 0U; i < N_EDGE32; i++) {
    for (j = 0U; j < N_EDGE32; j++) {
      const int32_t num = EDGE32[i];
      const int32_t den = EDGE32[j];
      const i128 want = (den == 0) ? ref_div0(num, INT32_MIN, INT32_MAX)
                                   : ref_div_away((i128)num * ((i128)1 << 31), den);
      const int32_t got = canfdi_q31_div(num, den);
      EXPECT(got == ref_sat32(want), "q31_div(%ld, %ld) = %ld", (long)num, (long)den, (long)got);
    }
  }
  rng_seed(0x7000U);
  for (k = 0U; k < 200000U; k++) {
    const int32_t den = rnd_s32();
    int32_t num = rnd_s32();
    if ((k & 1U) != 0U && den != INT32_MIN) {
      /* Make |num| < |den| half the time: the non-saturating region. */
      num = (int32_t)((i128)num * den / ((i128)INT32_MAX + 1));
    }
    {
      const i128 want = (den == 0) ? ref_div0(num, INT32_MIN, INT32_MAX)
                                   : ref_div_away((i128)num * ((i128)1 << 31), den);
      const int32_t got = canfdi_q31_div(num, den);
      EXPECT(got == ref_sat32(want), "q31_div(%ld, %ld) = %ld", (long)num, (long)den, (long)got);
    }
  }
  DONE();
}
END_TEST

/* Loop index = n (0..71, then 100, 1000, UINT_MAX). */
static void check_div_s32_qn(unsigned n, int it)
{
  const unsigned nref = (n > 94U) ? 94U : n; /* 2 * |num| * 2^94 < 2^127; beyond 63 all saturate */
  size_t i;
  size_t j;
  unsigned k;
  rng_seed(0x7100U + (uint64_t)it);
  for (i = 0U; i < N_EDGE32; i++) {
    for (j = 0U; j < N_EDGE32; j++) {
      const int32_t num = EDGE32[i];
      const int32_t den = EDGE32[j];
      const i128 want = (den == 0) ? ref_div0(num, INT32_MIN, INT32_MAX)
                                   : ref_div_away((i128)num * ((i128)1 << nref), den);
      const int32_t got = canfdi_div_s32_qn(num, den, n);
      EXPECT(got == ref_sat32(want), "div_s32_qn(%ld, %ld, %u) = %ld", (long)num, (long)den, n,
             (long)got);
    }
  }
  for (k = 0U; k < 10000U; k++) {
    const int32_t num = rnd_s32();
    const int32_t den = rnd_s32();
    const i128 want = (den == 0) ? ref_div0(num, INT32_MIN, INT32_MAX)
                                 : ref_div_away((i128)num * ((i128)1 << nref), den);
    const int32_t got = canfdi_div_s32_qn(num, den, n);
    EXPECT(got == ref_sat32(want), "div_s32_qn(%ld, %ld, %u) = %ld", (long)num, (long)den, n,
           (long)got);
  }
  /* divisors below 2^24 with dividends of every size (the 8-bit digit
   * path, quotients up to the saturation and just over it) */
  for (k = 0U; k < 20000U; k++) {
    const int32_t num = rnd_s32();
    const int32_t den = rnd_s32() / 256;
    const i128 want = (den == 0) ? ref_div0(num, INT32_MIN, INT32_MAX)
                                 : ref_div_away((i128)num * ((i128)1 << nref), den);
    const int32_t got = canfdi_div_s32_qn(num, den, n);
    EXPECT(got == ref_sat32(want), "div_s32_qn(%ld, %ld, %u) = %ld", (long)num, (long)den, n,
           (long)got);
  }
}

START_TEST(test_div_s32_qn)
{
  FOR_SHIFT_GROUP(it) {
    check_div_s32_qn(shift_for_iter(it), it);
  }
  DONE();
}
END_TEST

/* canfdi_div_s64_sat_s32 against the host's __int128 division (C's
 * truncation): every pair of 64-bit edges, quotients near 2^31 on both
 * sides of the saturation, divisors on both sides of 2^32 (the 64/32 and
 * the top-word paths) and random operands of every bit length. */
static void check_div_s64(int64_t num, int64_t den)
{
  const i128 want = (den == 0) ? ref_div0(num, INT32_MIN, INT32_MAX) : ((i128)num / (i128)den);
  const int32_t got = canfdi_div_s64_sat_s32(num, den);
  EXPECT(got == ref_sat32(want), "div_s64_sat_s32(%lld, %lld) = %ld", (long long)num, (long long)den, (long)got);
}

/* round(a 2^30 / b), ties up, by the bit-serial restoring division that
 * canfdi_div_u62_q30_rnd replaces: the reference. */
static uint32_t ref_div_u62_q30_rnd(uint64_t a, uint64_t b)
{
  uint64_t r = a;
  uint64_t q = 0U;
  unsigned i;
  if (r >= b) {
    q = 1U;
    r -= b;
  }
  for (i = 0U; i < 30U; i++) {
    r <<= 1;
    q <<= 1;
    if (r >= b) {
      r -= b;
      q |= 1U;
    }
  }
  r <<= 1;
  if (r >= b) {
    q += 1U;
  }
  return (uint32_t)q;
}

/* The ratio mantissa: the same bits as the reference at the domain's
 * edges (a = b, either at its ends, neighbours, quotients next to a tie and
 * to the estimate's corrections) and over random normalised pairs with
 * every spread of low bits. */
START_TEST(test_div_u62_q30_rnd)
{
  const uint64_t lo = (uint64_t)1 << 61;
  const uint64_t hi = ((uint64_t)1 << 62) - 1U;
  const uint64_t edge[] = {lo, lo + 1U, lo + 2U, hi, hi - 1U, hi - 2U, (uint64_t)3 << 60, ((uint64_t)3 << 60) - 1U,
                           ((uint64_t)3 << 60) + 1U, lo | 0xFFFFFFFFU, lo | ((uint64_t)0xFFFFFFFFU << 29),
                           hi & ~(uint64_t)0xFFFFFFFFU, lo + ((uint64_t)1 << 32), 0x2AAAAAAAAAAAAAAAU,
                           0x3555555555555555U};
  const size_t ne = sizeof edge / sizeof edge[0];
  size_t i;
  size_t j;
  uint32_t k;
  for (i = 0U; i < ne; i++) {
    for (j = 0U; j < ne; j++) {
      const uint32_t got = canfdi_div_u62_q30_rnd(edge[i], edge[j]);
      ck_assert_msg(got == ref_div_u62_q30_rnd(edge[i], edge[j]), "a %016llx b %016llx: %08x, reference %08x",
                    (unsigned long long)edge[i], (unsigned long long)edge[j], got,
                    ref_div_u62_q30_rnd(edge[i], edge[j]));
    }
  }
  rng_seed(0x62306271U);
  for (k = 0U; k < 400000U; k++) {
    const uint64_t r1 = rnd64();
    const uint64_t r2 = rnd64();
    /* low bits cleared now and then: divisors whose low word is 0, or a
     * small multiple of the top word */
    const unsigned z1 = (unsigned)((r1 >> 3) % 70U);
    const unsigned z2 = (unsigned)((r2 >> 3) % 70U);
    uint64_t a = lo | (r1 & (lo - 1U));
    uint64_t b = lo | (r2 & (lo - 1U));
    if (z1 < 61U) {
      a &= ~((((uint64_t)1) << z1) - 1U);
    }
    if (z2 < 61U) {
      b &= ~((((uint64_t)1) << z2) - 1U);
    }
    if ((k & 7U) == 0U) {
      b = a + (uint64_t)((int64_t)(r2 & 0x7FU) - 64); /* ratios near 1, either side */
      b = (b < lo) ? lo : ((b > hi) ? hi : b);
    }
    ck_assert_msg(canfdi_div_u62_q30_rnd(a, b) == ref_div_u62_q30_rnd(a, b), "a %016llx b %016llx",
                  (unsigned long long)a, (unsigned long long)b);
  }
  DONE();
}
END_TEST

START_TEST(test_div_s64_sat_s32)
{
  size_t i;
  size_t j;
  unsigned k;
  rng_seed(0x64D1U);
  for (i = 0U; i < N_EDGE64; i++) {
    for (j = 0U; j < N_EDGE64; j++) {
      check_div_s64(EDGE64[i], EDGE64[j]);
    }
  }
  for (k = 0U; k < 200000U; k++) {
    const int64_t den = rnd_s64();
    /* a quotient within a few units of a random 32-bit value, or of the
     * saturation limits, and the remainder anywhere in [0, |den|) */
    const int64_t qt = ((k & 3U) == 0U) ? (((k & 4U) != 0U) ? INT32_MAX : INT32_MIN) : (int64_t)rnd_s32();
    const i128 num = ((i128)qt + (i128)((int64_t)(rnd64() % 5U) - 2)) * den + (i128)(rnd64() % ((uint64_t)((den < 0) ? -(den + 1) : den) + 1U));
    if ((num >= (i128)INT64_MIN) && (num <= (i128)INT64_MAX)) {
      check_div_s64((int64_t)num, den);
    }
    check_div_s64(rnd_s64(), rnd_s64());
  }
  DONE();
}
END_TEST

/* ------------------------------------------------------------------------ */
/* TCase sqrt                                                               */
/* ------------------------------------------------------------------------ */

static int is_floor_sqrt_u64(uint64_t x, uint64_t r)
{
  __extension__ typedef unsigned __int128 u128;
  return ((u128)r * r <= x) && ((u128)(r + 1U) * (r + 1U) > x);
}

START_TEST(test_isqrt_u32)
{
  uint32_t x;
  uint32_t s;
  unsigned k;
  for (x = 0U; x < 65536U; x++) {
    const uint16_t r = canfdi_isqrt_u32(x);
    EXPECT(is_floor_sqrt_u64(x, r), "isqrt_u32(%lu) = %u", (unsigned long)x, r);
  }
  /* Every perfect square and its predecessor: each place the root steps. */
  for (s = 1U; s <= 65535U; s++) {
    const uint32_t sq = s * s;
    EXPECT(canfdi_isqrt_u32(sq) == s, "isqrt_u32(%lu^2)", (unsigned long)s);
    EXPECT(canfdi_isqrt_u32(sq - 1U) == s - 1U, "isqrt_u32(%lu^2 - 1)", (unsigned long)s);
  }
  EXPECT(canfdi_isqrt_u32(0xFFFFFFFFU) == 65535U, "isqrt_u32(max)");
  rng_seed(0x8000U);
  for (k = 0U; k < 200000U; k++) {
    const uint32_t v = (uint32_t)rnd64() >> (k % 32U);
    const uint16_t r = canfdi_isqrt_u32(v);
    EXPECT(is_floor_sqrt_u64(v, r), "isqrt_u32(%lu) = %u", (unsigned long)v, r);
  }
  DONE();
}
END_TEST

START_TEST(test_isqrt_u64)
{
  unsigned k;
  const uint64_t roots[] = {0U, 1U, 2U, 3U, 65535U, 65536U, 0x7FFFFFFFU, 0x80000000U,
                            0xFFFFFFFEU, 0xFFFFFFFFU};
  for (k = 0U; k < sizeof roots / sizeof roots[0]; k++) {
    const uint64_t s = roots[k];
    EXPECT(canfdi_isqrt_u64(s * s) == s, "isqrt_u64(%llu^2)", (unsigned long long)s);
    if (s > 0U) {
      EXPECT(canfdi_isqrt_u64(s * s - 1U) == s - 1U, "isqrt_u64(%llu^2 - 1)", (unsigned long long)s);
    }
    EXPECT(canfdi_isqrt_u64(s * s + 2U * s) == s, "isqrt_u64(%llu^2 + 2s)", (unsigned long long)s);
  }
  EXPECT(canfdi_isqrt_u64(UINT64_MAX) == 0xFFFFFFFFU, "isqrt_u64(max)");
  rng_seed(0x8100U);
  for (k = 0U; k < 200000U; k++) {
    const uint64_t v = rnd64() >> (k % 64U);
    const uint64_t s = rnd64() >> (32U + (k % 32U)); /* random root < 2^32 */
    const uint32_t r = canfdi_isqrt_u64(v);
    EXPECT(is_floor_sqrt_u64(v, r), "isqrt_u64(%llu) = %lu", (unsigned long long)v,
           (unsigned long)r);
    EXPECT(canfdi_isqrt_u64(s * s) == s, "isqrt_u64(%llu^2)", (unsigned long long)s);
    if (s > 0U) {
      EXPECT(canfdi_isqrt_u64(s * s - 1U) == s - 1U, "isqrt_u64(%llu^2 - 1)", (unsigned long long)s);
    }
  }
  DONE();
}
END_TEST

START_TEST(test_q15_sqrt_exhaustive)
{
  int32_t v;
  for (v = INT16_MIN; v <= INT16_MAX; v++) {
    const canfdi_q15_t y = canfdi_q15_sqrt((canfdi_q15_t)v);
    if (v <= 0) {
      EXPECT(y == 0, "q15_sqrt(%ld) = %d", (long)v, y);
    } else {
      EXPECT(y >= 0 && is_floor_sqrt_u64((uint64_t)v << 15, (uint64_t)y), "q15_sqrt(%ld) = %d",
             (long)v, y);
    }
  }
  ck_assert_int_eq(canfdi_q15_sqrt(16384), 23170); /* sqrt(0.5) = 0.70710678 -> 23170.47 */
  ck_assert_int_eq(canfdi_q15_sqrt(8192), 16384);  /* sqrt(0.25) = 0.5 exactly */
  DONE();
}
END_TEST

START_TEST(test_q31_sqrt)
{
  size_t i;
  unsigned k;
  for (i = 0U; i < N_EDGE32; i++) {
    const int32_t x = EDGE32[i];
    const canfdi_q31_t y = canfdi_q31_sqrt(x);
    EXPECT((x <= 0) ? (y == 0) : (y >= 0 && is_floor_sqrt_u64((uint64_t)x << 31, (uint64_t)y)),
           "q31_sqrt(%ld) = %ld", (long)x, (long)y);
  }
  rng_seed(0x8200U);
  for (k = 0U; k < 200000U; k++) {
    const int32_t x = rnd_s32();
    const canfdi_q31_t y = canfdi_q31_sqrt(x);
    EXPECT((x <= 0) ? (y == 0) : (y >= 0 && is_floor_sqrt_u64((uint64_t)x << 31, (uint64_t)y)),
           "q31_sqrt(%ld) = %ld", (long)x, (long)y);
  }
  ck_assert_int_eq(canfdi_q31_sqrt(536870912), 1073741824); /* sqrt(0.25) = 0.5 */
  ck_assert_int_eq(canfdi_q31_sqrt(INT32_MAX), INT32_MAX); /* sqrt(1 - 2^-31) = 1 - 2^-32 - ..., floors to MAX */
  DONE();
}
END_TEST

/* ------------------------------------------------------------------------ */

/* canfdi_intrin.h: the plain-C forms (the host build) against their
 * definitions, on every bit position and on products at the rounding
 * boundary. The ARM forms are checked equal to these bit for bit by the PIL
 * rig (tests/pil). */
START_TEST(test_intrin)
{
  unsigned b;
  ck_assert_uint_eq(canfdi_clz32(0U), 32U);
  ck_assert_uint_eq(canfdi_clz64(0U), 64U);
  for (b = 0U; b < 32U; b++) {
    const uint32_t x = (uint32_t)1 << b;
    ck_assert_uint_eq(canfdi_clz32(x), 31U - b);
    ck_assert_uint_eq(canfdi_clz32(x | (x - 1U)), 31U - b);
    ck_assert_uint_eq(canfdi_clz32(x | 1U), 31U - b);
    /* the lowest set bit, whatever lies above it */
    ck_assert_uint_eq(canfdi_ctz32(x), b);
    ck_assert_uint_eq(canfdi_ctz32(x | ~(x | (x - 1U))), b);
    ck_assert_uint_eq(canfdi_ctz32(x | 0x80000000U), b);
  }
  for (b = 0U; b < 64U; b++) {
    const uint64_t x = (uint64_t)1 << b;
    ck_assert_uint_eq(canfdi_clz64(x | (x - 1U)), 63U - b);
  }
  /* acc + floor((a b + 2^31) / 2^32) */
  ck_assert_int_eq(canfdi_mla_hi_rnd(0, 1 << 16, 1 << 15), 1);      /* +0.5: half up */
  ck_assert_int_eq(canfdi_mla_hi_rnd(0, -(1 << 16), 1 << 15), 0);   /* -0.5: half up */
  ck_assert_int_eq(canfdi_mla_hi_rnd(0, 1 << 16, (1 << 15) - 1), 0);
  ck_assert_int_eq(canfdi_mla_hi_rnd(5, INT32_MIN, INT32_MIN), 5 + (1 << 30));
  ck_assert_int_eq(canfdi_mla_hi_rnd(-7, INT32_MAX, INT32_MIN), -7 - (1 << 30) + 1);
  ck_assert_int_eq(canfdi_mla_hi_rnd(0, -3, 1 << 30), -1); /* -0.75 -> -1 */
  /* the 32x32->64 products on edge values (every sign combination) */
  {
    static const uint32_t ue[] = {0U, 1U, 0xFFFFU, 0x10000U, 0x7FFFFFFFU, 0x80000000U, 0xFFFFFFFFU, 0x12345678U};
    unsigned i;
    unsigned j;
    for (i = 0U; i < sizeof ue / sizeof ue[0]; i++) {
      for (j = 0U; j < sizeof ue / sizeof ue[0]; j++) {
        const uint64_t p = (uint64_t)ue[i] * (uint64_t)ue[j];
        const int64_t sp = (int64_t)canfdi_wrap_u32_to_s32(ue[i]) * (int64_t)canfdi_wrap_u32_to_s32(ue[j]);
        ck_assert_uint_eq(canfdi_umull32(ue[i], ue[j]), p);
        ck_assert_uint_eq(canfdi_umull32_h16(ue[i], ue[j]), p);
        ck_assert_uint_eq(canfdi_umulhi32_h16(ue[i], ue[j]), (uint32_t)(p >> 32));
        ck_assert(canfdi_smull32_h16(canfdi_wrap_u32_to_s32(ue[i]), canfdi_wrap_u32_to_s32(ue[j])) == sp);
        ck_assert_uint_eq(canfdi_umulhi32(ue[i], ue[j]), (uint32_t)(p >> 32));
        ck_assert(canfdi_smull32(canfdi_wrap_u32_to_s32(ue[i]), canfdi_wrap_u32_to_s32(ue[j])) == sp);
        ck_assert(canfdi_usmull32_h16(ue[i], canfdi_wrap_u32_to_s32(ue[j])) ==
                  (int64_t)ue[i] * (int64_t)canfdi_wrap_u32_to_s32(ue[j]));
        ck_assert(canfdi_usmull32(ue[i], canfdi_wrap_u32_to_s32(ue[j])) ==
                  (int64_t)ue[i] * (int64_t)canfdi_wrap_u32_to_s32(ue[j]));
      }
    }
  }
}
END_TEST

/* The 16-bit-halves products (ARMv6-M's) against the host's 64-bit
 * products on a pseudo-random sweep. */
START_TEST(test_mul_halves)
{
  uint32_t s = 0x2545F491U;
  unsigned k;
  for (k = 0U; k < 20000U; k++) {
    uint32_t a;
    uint32_t b;
    s ^= s << 13;
    s ^= s >> 17;
    s ^= s << 5;
    a = s;
    s ^= s << 13;
    s ^= s >> 17;
    s ^= s << 5;
    b = s;
    ck_assert_uint_eq(canfdi_umull32_h16(a, b), (uint64_t)a * (uint64_t)b);
    ck_assert_uint_eq(canfdi_umulhi32_h16(a, b), (uint32_t)(((uint64_t)a * (uint64_t)b) >> 32));
    ck_assert(canfdi_smull32_h16(canfdi_wrap_u32_to_s32(a), canfdi_wrap_u32_to_s32(b)) ==
              (int64_t)canfdi_wrap_u32_to_s32(a) * (int64_t)canfdi_wrap_u32_to_s32(b));
    ck_assert(canfdi_usmull32_h16(a, canfdi_wrap_u32_to_s32(b)) == (int64_t)a * (int64_t)canfdi_wrap_u32_to_s32(b));
  }
}
END_TEST

/* round(a g / 2^31) for |a| < 2^56 from 16-bit halves against the host's
 * 128-bit product, and c w (|c| <= 2^47, w < 2^15) from 32-bit multiplies
 * against the 64-bit one: edge values, then a sweep over the operand
 * sizes. */
__extension__ typedef __int128 test_i128; /* GCC and clang on 64-bit hosts */
static int64_t ref_mul_s56_q31_rnd(int64_t a, int32_t g)
{
  const test_i128 p = ((test_i128)a * g) + ((test_i128)1 << 30);
  return (int64_t)(p >> 31); /* GCC and clang: an arithmetic shift */
}

START_TEST(test_mul_s56_q31_halves)
{
  static const int64_t ae[] = {0, 1, -1, 2, -2, 0x7FFFFFFF, -0x80000000LL, 0xFFFFFFFFLL, 0x100000000LL, -0x100000000LL,
                               ((int64_t)1 << 56) - 1, -(((int64_t)1 << 56) - 1), ((int64_t)1 << 40) + 12345,
                               -((int64_t)1 << 47), -((int64_t)1 << 56)};
  static const int32_t ge[] = {0, 1, -1, 2, INT32_MAX, INT32_MIN, INT32_MIN + 1, 0x40000000, -0x40000000, 0x12345678,
                               -0x12345678, 0xFFFF, 0x10000};
  uint32_t s = 0x9E3779B9U;
  unsigned i;
  unsigned j;
  unsigned k;
  for (i = 0U; i < sizeof ae / sizeof ae[0]; i++) {
    for (j = 0U; j < sizeof ge / sizeof ge[0]; j++) {
      ck_assert(canfdi_mul_s56_q31_rnd_h16(ae[i], ge[j]) == ref_mul_s56_q31_rnd(ae[i], ge[j]));
    }
  }
  /* c w for |c| <= 2^47, w in 0..32767 */
  {
    static const int64_t ce[] = {0, 1, -1, 0xFFFF, 0x10000, -0x10000, 0xFFFFFFFFLL, -0xFFFFFFFFLL, 0x100000000LL,
                                 -0x100000000LL, (int64_t)1 << 47, -((int64_t)1 << 47), ((int64_t)1 << 47) - 1,
                                 -((int64_t)1 << 47) + 1};
    static const int32_t we[] = {0, 1, 2, 0x7FFF, 0x4000, 12345};
    for (i = 0U; i < sizeof ce / sizeof ce[0]; i++) {
      for (j = 0U; j < sizeof we / sizeof we[0]; j++) {
        ck_assert(canfdi_mul_s48_u15_h16(ce[i], we[j]) == ce[i] * (int64_t)we[j]);
      }
    }
  }
  for (k = 0U; k < 200000U; k++) {
    uint64_t a;
    int64_t av;
    int32_t g;
    s ^= s << 13;
    s ^= s >> 17;
    s ^= s << 5;
    a = (uint64_t)s << 32;
    s ^= s << 13;
    s ^= s >> 17;
    s ^= s << 5;
    a |= s;
    /* a size of 1..56 bits, either sign (the signs of a and g vary
     * independently of the size) */
    av = (int64_t)(a >> (8U + (k % 56U)));
    av = (((k / 56U) & 1U) != 0U) ? -av : av;
    s ^= s << 13;
    s ^= s >> 17;
    s ^= s << 5;
    g = canfdi_wrap_u32_to_s32(s >> ((k / 57U) % 32U));
    g = ((((k / 112U) & 1U) != 0U) && (g != INT32_MIN)) ? -g : g;
    ck_assert(canfdi_mul_s56_q31_rnd_h16(av, g) == ref_mul_s56_q31_rnd(av, g));
    {
      /* the same operands cut to |c| <= 2^47, w < 2^15 */
      const int64_t c = av / 512;
      const int32_t w = (int32_t)(((uint32_t)g >> 17) & 0x7FFFU);
      ck_assert(canfdi_mul_s48_u15_h16(c, w) == c * (int64_t)w);
    }
  }
}
END_TEST

/* canfdi_recip_q63: 2^63 / v from below, within 2^-30.4 (here: v q <= 2^63
 * and 2^63 - v q < 4 v, i.e. q within 4 units of the floor), below 2^32,
 * on every interval boundary of its seed table and on a sweep. */
START_TEST(test_recip_q63)
{
  const uint64_t one = (uint64_t)1 << 63;
  uint32_t worst = 0U;
  uint32_t k;
  for (k = 0U; k < 256U; k++) {
    const uint32_t base = 0x80000000U + (k << 23);
    const uint32_t vs[5] = {base, base + 1U, base + 0x7FFFFFU, base + 0x400000U, base + 0x40007FU};
    unsigned i;
    for (i = 0U; i < 5U; i++) {
      const uint32_t v = vs[i];
      const uint32_t q = canfdi_recip_q63(v);
      const uint64_t vq = (uint64_t)v * (uint64_t)q;
      ck_assert(vq <= one);
      ck_assert((one - vq) < (uint64_t)4U * v);
    }
  }
  for (k = 0U; k < 100000U; k++) {
    const uint32_t v = 0x80000000U + (k * 21473U) + (k >> 3);
    const uint32_t q = canfdi_recip_q63(v);
    const uint64_t vq = (uint64_t)v * (uint64_t)q;
    const uint32_t units = (uint32_t)((one - vq) / v);
    if (vq > one) {
      ck_abort_msg("v %u: q %u above 2^63 / v", v, q);
    }
    worst = (units > worst) ? units : worst;
  }
  ck_assert_uint_lt(worst, 4U);
  ck_assert_uint_eq(canfdi_recip_q63(0xFFFFFFFFU) >> 30, 1U); /* 2^31 - 1 or 2^31 */
  ck_assert_uint_eq(canfdi_recip_q63(0x80000000U) >> 31, 1U); /* just below 2^32 */
}
END_TEST

static Suite *make_suite(void)
{
  Suite *s = suite_create("fixp");
  TCase *tc;

  tc = tcase_create("shifts");
  tcase_add_loop_test(tc, test_asr32, 0, N_SHIFT_GROUPS);
  tcase_add_loop_test(tc, test_asr64, 0, N_SHIFT_GROUPS);
  tcase_add_test(tc, test_round_ties);
  tcase_add_test(tc, test_intrin);
  tcase_add_test(tc, test_recip_q63);
  tcase_add_test(tc, test_mul_halves);
  tcase_add_test(tc, test_mul_s56_q31_halves);
  tcase_add_loop_test(tc, test_shl, 0, N_SHIFT_GROUPS);
  suite_add_tcase(s, tc);

  tc = tcase_create("saturation_conversion");
  tcase_add_test(tc, test_sat_width);
  tcase_add_test(tc, test_wrap_clamp);
  tcase_add_test(tc, test_q15_q31_conv);
  tcase_add_loop_test(tc, test_qconv, 0, 4);
  tcase_add_test(tc, test_ratio_macros);
  suite_add_tcase(s, tc);

  tc = tcase_create("add_sub_neg_abs");
  tcase_add_test(tc, test_q15_neg_abs_exhaustive);
  tcase_add_loop_test(tc, test_q15_add_sub_sweep, 0, 4);
  tcase_add_test(tc, test_q31_add_sub_neg_abs);
  tcase_add_test(tc, test_s64_add_sub);
  suite_add_tcase(s, tc);

  tc = tcase_create("multiply");
  tcase_add_loop_test(tc, test_q15_mul_sweep, 0, 4);
  tcase_add_test(tc, test_q15_mul_facts);
  tcase_add_test(tc, test_q31_mul);
  tcase_add_loop_test(tc, test_mul_s32_qn, 0, N_SHIFT_GROUPS);
  tcase_add_test(tc, test_mul_s64_q31);
  suite_add_tcase(s, tc);

  tc = tcase_create("divide");
  tcase_add_loop_test(tc, test_q15_div_sweep, 0, 4);
  tcase_add_test(tc, test_div_facts);
  tcase_add_test(tc, test_q31_div);
  tcase_add_loop_test(tc, test_div_s32_qn, 0, N_SHIFT_GROUPS);
  tcase_add_test(tc, test_div_s64_sat_s32);
  tcase_add_test(tc, test_div_u62_q30_rnd);
  suite_add_tcase(s, tc);

  tc = tcase_create("sqrt");
  tcase_add_test(tc, test_isqrt_u32);
  tcase_add_test(tc, test_isqrt_u64);
  tcase_add_test(tc, test_q15_sqrt_exhaustive);
  tcase_add_test(tc, test_q31_sqrt);
  suite_add_tcase(s, tc);

  return s;
}

CANFDI_UNIT_MAIN(make_suite)
