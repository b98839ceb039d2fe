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
#include "core/canfdi_intrin.h"

/* floor(2^63 / (2^31 + i 2^23)) - 2^15, i = 0..256 (see canfdi_fixp.h). */
const uint32_t canfdi_recip_seed[257] = {
    0xFFFF8000U, 0xFF007F00U, 0xFE03780FU, 0xFD086550U, 0xFC0F40FCU, 0xFB180565U,
    0xFA22ACF2U, 0xF92F3221U, 0xF83D8F83U, 0xF74DBFC2U, 0xF65FBD98U, 0xF57383D5U,
    0xF4890D5FU, 0xF3A0552CU, 0xF2B95648U, 0xF1D40BCEU, 0xF0F070F0U, 0xF00E80F0U,
    0xEF2E371FU, 0xEE4F8EE5U, 0xED7283B5U, 0xEC971118U, 0xEBBD32A5U, 0xEAE4E403U,
    0xEA0E20EAU, 0xE938E51FU, 0xE8652C7BU, 0xE792F2E2U, 0xE6C23448U, 0xE5F2ECB0U,
    0xE525182AU, 0xE458B2D7U, 0xE38DB8E3U, 0xE2C42688U, 0xE1FBF80EU, 0xE13529C9U,
    0xE06FB81CU, 0xDFAB9F74U, 0xDEE8DC4CU, 0xDE276B2CU, 0xDD6748A6U, 0xDCA87158U,
    0xDBEAE1EEU, 0xDB2E971DU, 0xDA738DA7U, 0xD9B9C256U, 0xD9013203U, 0xD849D98EU,
    0xD793B5E5U, 0xD6DEC3FCU, 0xD62B00D6U, 0xD578697CU, 0xD4C6FB03U, 0xD416B289U,
    0xD3678D36U, 0xD2B9883BU, 0xD20CA0D2U, 0xD160D43EU, 0xD0B61FCBU, 0xD00C80D0U,
    0xCF63F4A8U, 0xCEBC78BBU, 0xCE160A77U, 0xCD70A752U, 0xCCCC4CCCU, 0xCC28F86CU,
    0xCB86A7C0U, 0xCAE5585FU, 0xCA4507E6U, 0xC9A5B3FCU, 0xC9075A4EU, 0xC869F890U,
    0xC7CD8C7CU, 0xC73213D7U, 0xC6978C69U, 0xC5FDF403U, 0xC565487BU, 0xC4CD87B0U,
    0xC436AF85U, 0xC3A0BDE6U, 0xC30BB0C3U, 0xC2778613U, 0xC1E43BD5U, 0xC151D00CU,
    0xC0C040C0U, 0xC02F8C03U, 0xBF9FAFE8U, 0xBF10AA8AU, 0xBE827A0BU, 0xBDF51C91U,
    0xBD689047U, 0xBCDCD35DU, 0xBC51E40BU, 0xBBC7C08CU, 0xBB3E6721U, 0xBAB5D610U,
    0xBA2E0BA2U, 0xB9A7062AU, 0xB920C3FAU, 0xB89B436CU, 0xB81682E0U, 0xB79280B7U,
    0xB70F3B5AU, 0xB68CB134U, 0xB60AE0B6U, 0xB589C855U, 0xB509668AU, 0xB489B9D4U,
    0xB40AC0B4U, 0xB38C79B0U, 0xB30EE352U, 0xB291FC29U, 0xB215C2C8U, 0xB19A35C4U,
    0xB11F53B8U, 0xB0A51B41U, 0xB02B8B02U, 0xAFB2A1A1U, 0xAF3A5DC6U, 0xAEC2BE1FU,
    0xAE4BC15CU, 0xADD56632U, 0xAD5FAB58U, 0xACEA8F89U, 0xAC761184U, 0xAC02300AU,
    0xAB8EE9E2U, 0xAB1C3DD3U, 0xAAAA2AAAU, 0xAA38AF35U, 0xA9C7CA47U, 0xA9577AB5U,
    0xA8E7BF57U, 0xA8789708U, 0xA80A00A8U, 0xA79BFB16U, 0xA72E8539U, 0xA6C19DF6U,
    0xA6554439U, 0xA5E976EDU, 0xA57E3502U, 0xA5137D6BU, 0xA4A94F1DU, 0xA43FA910U,
    0xA3D68A3DU, 0xA36DF1A2U, 0xA305DE3FU, 0xA29E4F16U, 0xA237432BU, 0xA1D0B985U,
    0xA16AB12EU, 0xA1052932U, 0xA0A020A0U, 0xA03B9688U, 0x9FD789FDU, 0x9F73FA15U,
    0x9F10E5E7U, 0x9EAE4C8DU, 0x9E4C2D23U, 0x9DEA86C9U, 0x9D89589DU, 0x9D28A1C3U,
    0x9CC86160U, 0x9C68969BU, 0x9C09409CU, 0x9BAA5E8EU, 0x9B4BEF9EU, 0x9AEDF2FCU,
    0x9A9067D9U, 0x9A334D67U, 0x99D6A2DAU, 0x997A676BU, 0x991E9A51U, 0x98C33AC7U,
    0x98684809U, 0x980DC156U, 0x97B3A5EDU, 0x9759F50FU, 0x9700AE02U, 0x96A7D009U,
    0x964F5A6CU, 0x95F74C72U, 0x959FA568U, 0x95486497U, 0x94F1894FU, 0x949B12DDU,
    0x94450094U, 0x93EF51C5U, 0x939A05C4U, 0x93451BE6U, 0x92F09384U, 0x929C6BF4U,
    0x9248A492U, 0x91F53CB8U, 0x91A233C4U, 0x914F8915U, 0x90FD3C09U, 0x90AB4C02U,
    0x9059B863U, 0x90088090U, 0x8FB7A3EEU, 0x8F6721E3U, 0x8F16F9D9U, 0x8EC72B39U,
    0x8E77B56DU, 0x8E2897E0U, 0x8DD9D202U, 0x8D8B633FU, 0x8D3D4B08U, 0x8CEF88CFU,
    0x8CA21C04U, 0x8C55041CU, 0x8C08408CU, 0x8BBBD0C8U, 0x8B6FB44AU, 0x8B23EA87U,
    0x8AD872FBU, 0x8A8D4D1FU, 0x8A427870U, 0x89F7F469U, 0x89ADC089U, 0x8963DC4FU,
    0x891A473AU, 0x88D100CDU, 0x88880888U, 0x883F5DF0U, 0x87F70087U, 0x87AEEFD5U,
    0x87672B5FU, 0x871FB2ACU, 0x86D88544U, 0x8691A2B1U, 0x864B0A7DU, 0x8604BC34U,
    0x85BEB761U, 0x8578FB91U, 0x85338853U, 0x84EE5D35U, 0x84A979C8U, 0x8464DD9BU,
    0x84208842U, 0x83DC794DU, 0x8398B052U, 0x83552CE3U, 0x8311EE97U, 0x82CEF503U,
    0x828C3FBEU, 0x8249CE60U, 0x8207A082U, 0x81C5B5BCU, 0x81840DA8U, 0x8142A7E3U,
    0x81018408U, 0x80C0A1B2U, 0x80800080U, 0x803FA010U, 0x7FFF8000U
};

/* ARMv6-M with GCC: canfdi_smull32_h16 and canfdi_mul_s56_q31_rnd_h16, the
 * products the step calls most (~100 and ~60 times), in Thumb-1 assembly:
 * signed 16-bit high halves, so that every partial product fits 32 bits
 * with its sign, and the 64-bit sums carried with ADCS, which C cannot
 * express (the C forms below take ~30 and ~85 instructions, these 22 and
 * 52). The same bits as the C forms, which are the portable reference
 * (tests/unit/test_fixp.c on the host); the PIL images check both against
 * the compiler's own 64-bit products on the target (tests/pil/pil_step.c)
 * before every replay. Naked (no compiler prologue): each pushes the
 * registers it uses above r3, 8 and 16 bytes, which tests/pil/footprint.py
 * adds to the stack's worst case (its ASM_FRAMES). GCC reads Thumb-1
 * inline assembly in divided syntax: each block switches to unified and
 * back. */
#if defined(__ARM_ARCH_6M__) && defined(__GNUC__)
#define CANFDI_FIXP_V6M_ASM 1
#else
#define CANFDI_FIXP_V6M_ASM 0
#endif

/* The 32x32->64 products from 16-bit halves (canfdi_fixp.h). */

/* Unsigned: "mid" <= 2^32 - 1. */
uint64_t canfdi_umull32_h16(uint32_t a, uint32_t b)
{
  const uint32_t al = a & 0xFFFFU;
  const uint32_t ah = a >> 16;
  const uint32_t bl = b & 0xFFFFU;
  const uint32_t bh = b >> 16;
  const uint32_t ll = al * bl;
  const uint32_t lh = al * bh;
  const uint32_t mid = (ll >> 16) + (lh & 0xFFFFU) + (ah * bl);
  const uint32_t hi = (ah * bh) + (lh >> 16) + (mid >> 16);
  return ((uint64_t)hi << 32) | ((mid << 16) | (ll & 0xFFFFU));
}

/* The unsigned product's high word only (the low word is not assembled). */
uint32_t canfdi_umulhi32_h16(uint32_t a, uint32_t b)
{
  const uint32_t al = a & 0xFFFFU;
  const uint32_t ah = a >> 16;
  const uint32_t bl = b & 0xFFFFU;
  const uint32_t bh = b >> 16;
  const uint32_t lh = al * bh;
  const uint32_t mid = ((al * bl) >> 16) + (lh & 0xFFFFU) + (ah * bl);
  return (ah * bh) + (lh >> 16) + (mid >> 16);
}

/* Signed: the unsigned product of the two bit patterns, whose high word
 * less b when a < 0 and less a when b < 0 (modulo 2^32) is the signed
 * product's high word (a = a_u - 2^32 [a < 0]); the low words agree. All in
 * 32-bit words: no 64-bit addition, which ARMv6-M builds from carries. The
 * unsigned words are canfdi_umull32_h16's, written out here rather than
 * called: this product runs ~185 times a step. */
#if CANFDI_FIXP_V6M_ASM
/* a = ah 2^16 + al, b = bh 2^16 + bl with ah, bh signed and al, bl
 * unsigned: a b = ah bh 2^32 + (ah bl + al bh) 2^16 + al bl, each middle
 * product added as its word shifted left (low) and arithmetically right
 * (high) with the carry. a in r0, b in r1; a b in r1:r0. */
__attribute__((naked)) int64_t canfdi_smull32_h16(int32_t a __attribute__((unused)), int32_t b __attribute__((unused)))
{
  __asm__ volatile(
      ".syntax unified\n\t"
      "push {r4, r5}\n\t"
      "asrs r2, r0, #16\n\t" /* ah, signed */
      "uxth r0, r0\n\t"      /* al */
      "asrs r3, r1, #16\n\t" /* bh, signed */
      "uxth r1, r1\n\t"      /* bl */
      "movs r4, r0\n\t"
      "muls r4, r1\n\t"      /* al bl: low word, unsigned */
      "muls r1, r2\n\t"      /* ah bl, signed */
      "muls r0, r3\n\t"      /* al bh, signed */
      "muls r3, r2\n\t"      /* ah bh: high word, signed */
      "lsls r5, r1, #16\n\t"
      "asrs r1, r1, #16\n\t"
      "adds r4, r4, r5\n\t"
      "adcs r3, r1\n\t"
      "lsls r5, r0, #16\n\t"
      "asrs r0, r0, #16\n\t"
      "adds r4, r4, r5\n\t"
      "adcs r3, r0\n\t"
      "movs r0, r4\n\t"
      "movs r1, r3\n\t"
      "pop {r4, r5}\n\t"
      "bx lr\n\t"
      ".syntax divided\n\t");
}
#else
int64_t canfdi_smull32_h16(int32_t a, int32_t b)
{
  const uint32_t ua = (uint32_t)a;
  const uint32_t ub = (uint32_t)b;
  const uint32_t al = ua & 0xFFFFU;
  const uint32_t ah = ua >> 16;
  const uint32_t bl = ub & 0xFFFFU;
  const uint32_t bh = ub >> 16;
  const uint32_t ll = al * bl;
  const uint32_t lh = al * bh;
  const uint32_t mid = (ll >> 16) + (lh & 0xFFFFU) + (ah * bl);
  const uint32_t corr = (ub & (0U - (ua >> 31))) + (ua & (0U - (ub >> 31)));
  const uint32_t hi = ((ah * bh) + (lh >> 16) + (mid >> 16)) - corr;
  return canfdi_wrap_u64_to_s64(((uint64_t)hi << 32) | ((mid << 16) | (ll & 0xFFFFU)));
}
#endif

/* Unsigned times signed: the unsigned product of a and b's bit pattern,
 * less a 2^32 when b < 0 (modulo 2^64); a b lies in [-2^63, 2^64 / 2). */
int64_t canfdi_usmull32_h16(uint32_t a, int32_t b)
{
  const uint64_t p = canfdi_umull32_h16(a, (uint32_t)b);
  return canfdi_wrap_u64_to_s64((b < 0) ? (p - ((uint64_t)a << 32)) : p);
}

/* a = ah 2^32 + al (ah signed, al unsigned): a g = ah g 2^32 + al g, so
 * round(a g / 2^31) = 2 ah g + round(al g / 2^31) exactly. Both products
 * are formed from 16-bit halves as in canfdi_smull32_h16 (al g as the
 * unsigned product less al 2^32 when g < 0); al g (|al g| < 2^63) is
 * shifted by 31 on its two words, and the sum is carried word by word.
 * |ah| <= 2^24, so |2 ah g| <= 2^56 and nothing wraps. */
#if CANFDI_FIXP_V6M_ASM
/* The same identity as the C form: 2 ah g + floor(al g / 2^31) + bit 30 of
 * al g, with ah g (signed halves) and al g (al's halves unsigned, g's high
 * half signed) each built as in canfdi_smull32_h16. a in r1:r0, g in r2;
 * the result in r1:r0. */
__attribute__((naked)) int64_t canfdi_mul_s56_q31_rnd_h16(int64_t a __attribute__((unused)), int32_t g __attribute__((unused)))
{
  __asm__ volatile(
      ".syntax unified\n\t"
      "push {r4, r5, r6, r7}\n\t"
      /* H = ah g (ah = r1, signed; g = r2) into r7:r6 */
      "asrs r3, r1, #16\n\t"
      "uxth r1, r1\n\t"
      "asrs r4, r2, #16\n\t"
      "uxth r5, r2\n\t"
      "movs r6, r1\n\t"
      "muls r6, r5\n\t"
      "movs r7, r3\n\t"
      "muls r7, r4\n\t"
      "muls r1, r4\n\t"
      "muls r3, r5\n\t"
      "lsls r2, r3, #16\n\t"
      "asrs r3, r3, #16\n\t"
      "adds r6, r6, r2\n\t"
      "adcs r7, r3\n\t"
      "lsls r2, r1, #16\n\t"
      "asrs r1, r1, #16\n\t"
      "adds r6, r6, r2\n\t"
      "adcs r7, r1\n\t"
      /* 2 H */
      "adds r6, r6, r6\n\t"
      "adcs r7, r7\n\t"
      /* X = al g (al = r0, unsigned) into r3:r2 */
      "lsrs r1, r0, #16\n\t"
      "uxth r0, r0\n\t"
      "movs r2, r0\n\t"
      "muls r2, r5\n\t"
      "movs r3, r1\n\t"
      "muls r3, r4\n\t"
      "muls r0, r4\n\t"
      "muls r1, r5\n\t"
      "lsls r4, r1, #16\n\t"
      "lsrs r1, r1, #16\n\t"
      "adds r2, r2, r4\n\t"
      "adcs r3, r1\n\t"
      "lsls r4, r0, #16\n\t"
      "asrs r0, r0, #16\n\t"
      "adds r2, r2, r4\n\t"
      "adcs r3, r0\n\t"
      /* 2 H + floor(X / 2^31) + bit 30 of X */
      "lsrs r0, r2, #31\n\t"
      "lsls r1, r3, #1\n\t"
      "orrs r0, r1\n\t"
      "asrs r1, r3, #31\n\t"
      "adds r0, r0, r6\n\t"
      "adcs r1, r7\n\t"
      "lsls r2, r2, #1\n\t"
      "lsrs r2, r2, #31\n\t"
      "movs r3, #0\n\t"
      "adds r0, r0, r2\n\t"
      "adcs r1, r3\n\t"
      "pop {r4, r5, r6, r7}\n\t"
      "bx lr\n\t"
      ".syntax divided\n\t");
}
#else
int64_t canfdi_mul_s56_q31_rnd_h16(int64_t a, int32_t g)
{
  const uint64_t ua = (uint64_t)a;
  const uint32_t al = (uint32_t)ua;
  const uint32_t ah = (uint32_t)(ua >> 32); /* the signed high word's bits */
  const uint32_t ug = (uint32_t)g;
  const uint32_t gl = ug & 0xFFFFU;
  const uint32_t gh = ug >> 16;
  const uint32_t gneg = 0U - (ug >> 31); /* all ones when g < 0 */
  uint32_t xh;
  uint32_t xl;
  uint32_t hh;
  uint32_t hl;
  uint32_t rl;
  uint32_t rh;
  uint32_t s;
  {
    /* al g: unsigned words, then less al 2^32 for a negative g */
    const uint32_t a0 = al & 0xFFFFU;
    const uint32_t a1 = al >> 16;
    const uint32_t ll = a0 * gl;
    const uint32_t lh = a0 * gh;
    const uint32_t mid = (ll >> 16) + (lh & 0xFFFFU) + (a1 * gl);
    xh = (((a1 * gh) + (lh >> 16)) + (mid >> 16)) - (al & gneg);
    xl = (mid << 16) | (ll & 0xFFFFU);
  }
  {
    /* ah g, signed: the unsigned words less the two corrections */
    const uint32_t a0 = ah & 0xFFFFU;
    const uint32_t a1 = ah >> 16;
    const uint32_t ll = a0 * gl;
    const uint32_t lh = a0 * gh;
    const uint32_t mid = (ll >> 16) + (lh & 0xFFFFU) + (a1 * gl);
    const uint32_t corr = (ug & (0U - (ah >> 31))) + (ah & gneg);
    hh = (((a1 * gh) + (lh >> 16)) + (mid >> 16)) - corr;
    hl = (mid << 16) | (ll & 0xFFFFU);
  }
  /* 2 ah g */
  rl = hl << 1;
  rh = (hh << 1) | (hl >> 31);
  /* + floor(al g / 2^31): its words are (sign of xh, xh 2 + xl's top bit) */
  s = rl + ((xh << 1) | (xl >> 31));
  rh += (0U - (xh >> 31)) + ((s < rl) ? 1U : 0U);
  rl = s;
  /* + the last bit shifted out (half up) */
  s = rl + ((xl >> 30) & 1U);
  rh += (s < rl) ? 1U : 0U;
  return canfdi_wrap_u64_to_s64(((uint64_t)rh << 32) | s);
}
#endif

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

/*
 * floor(num / den) for num < den 2^32 (so that the quotient fits 32 bits),
 * the remainder in *rem: long division by 16-bit digits of the divisor
 * normalised to its top bit (Knuth, TAOCP vol. 2, 4.3.1, algorithm D),
 * i.e. two 32-bit divisions (UDIV on ARMv7-M, __aeabi_uidiv on ARMv6-M)
 * instead of libgcc's 64-bit division, which costs several times as much.
 * Scaling and overflow: num 2^s < den 2^(32+s) < 2^64 loses no bit; each
 * digit estimate exceeds the true digit by at most 2 and is corrected
 * before use, so every partial remainder is below d < 2^32 (formed in 64
 * bits: no unsigned wrap) and the products q dl are formed only for
 * q < 2^16. Inline in each caller: canfdi_div_s32_qn runs about twenty
 * times a step, and a call costs a tenth of the division.
 */
static CANFDI_ALWAYS_INLINE uint32_t udiv_u64_u32(uint64_t num, uint32_t den, uint32_t *rem)
{
  const unsigned s = canfdi_clz32(den); /* den != 0 */
  const uint32_t d = den << s;
  const uint32_t dh = d >> 16;
  const uint32_t dl = d & 0xFFFFU;
  const uint64_t nn = num << s;
  const uint32_t n1 = (uint32_t)(nn >> 32); /* < d */
  const uint32_t n0h = (uint32_t)nn >> 16;
  const uint32_t n0l = (uint32_t)nn & 0xFFFFU;
  uint32_t q1 = n1 / dh;
  uint32_t r = n1 - (q1 * dh);
  uint32_t m;
  uint32_t q0;
  while ((q1 > 0xFFFFU) || ((q1 * dl) > ((r << 16) | n0h))) {
    q1--;
    r += dh;
    if (r > 0xFFFFU) {
      break;
    }
  }
  /* the partial remainder n1 2^16 + n0h - q1 d is in [0, d): formed in 64
   * bits, so that neither the shift nor the product wraps */
  m = (uint32_t)((((uint64_t)n1 << 16) | n0h) - ((uint64_t)q1 * d));
  q0 = m / dh;
  r = m - (q0 * dh);
  while ((q0 > 0xFFFFU) || ((q0 * dl) > ((r << 16) | n0l))) {
    q0--;
    r += dh;
    if (r > 0xFFFFU) {
      break;
    }
  }
  *rem = (uint32_t)(((((uint64_t)m << 16) | n0l) - ((uint64_t)q0 * d)) >> s);
  return (q1 << 16) | q0;
}

/*
 * round(num / den) for den != 0, ties up, when it is below 2^32; 2^32 for
 * any larger quotient (the one caller saturates from 2^31 on).
 */
static uint64_t udiv_rnd_u64(uint64_t num, uint32_t den)
{
  uint64_t q;
  if ((num >> 32) == 0U) {
    /* Small operands take the 32-bit division (UDIV on M4, the cheaper
     * helper on M0+) instead of the 64-bit helper. */
    q = udiv_rnd_u32((uint32_t)num, den);
  } else if ((uint32_t)(num >> 32) >= den) {
    q = (uint64_t)1U << 32; /* num / den >= 2^32 */
  } else {
    uint32_t r;
    const uint32_t q0 = udiv_u64_u32(num, den, &r);
    q = (r >= (den - r)) ? ((uint64_t)q0 + 1U) : (uint64_t)q0;
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
  } else if ((n < 31U) && ((mag_u32(num) >> (31U - n)) == 0U)) {
    /* |num| 2^n < 2^31, the common case: one 32-bit division, and the
     * rounded quotient (at most |num| 2^n) needs no saturation */
    const uint32_t q = udiv_rnd_u32(mag_u32(num) << n, mag_u32(den));
    y = negative ? -(int32_t)q : (int32_t)q;
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

uint32_t canfdi_div_u62_q30_rnd(uint64_t a, uint64_t b)
{
  /* u = a 2^33 (words w2:w1:0), v = b 2^2 (words v1:v0, v1 >= 2^31) */
  const uint32_t w2 = (uint32_t)(a >> 31); /* < 2^31 <= v1: one digit */
  const uint32_t w1 = (uint32_t)(a << 1); /* a < 2^62: the shift loses no bit */
  const uint64_t v = b << 2;
  const uint32_t v1 = (uint32_t)(v >> 32);
  const uint32_t v0 = (uint32_t)v;
  uint32_t rhat;
  uint32_t q2;
  bool more = true;
  unsigned k;
  CANFDI_ASSERT((a >> 61) == 1U);
  CANFDI_ASSERT((b >> 61) == 1U);
  q2 = udiv_u64_u32(((uint64_t)w2 << 32) | w1, v1, &rhat);
  /* u - q2 v = rhat 2^32 - q2 v0: negative while q2 v0 > rhat 2^32 (the
   * estimate is too large, by 2 at most) */
  for (k = 0U; (k < 2U) && more; k++) {
    if (canfdi_umull32(q2, v0) > ((uint64_t)rhat << 32)) {
      q2--;
      more = (rhat <= (0xFFFFFFFFU - v1)); /* rhat + v1 >= 2^32: q2 is right */
      rhat = more ? (rhat + v1) : rhat;
    } else {
      more = false;
    }
  }
  return (q2 >> 1) + (q2 & 1U);
}

/* |x| as an unsigned value; exact for INT64_MIN (2^63). */
static uint64_t mag_u64(int64_t x)
{
  return (x < 0) ? (0U - (uint64_t)x) : (uint64_t)x;
}

int32_t canfdi_div_s64_sat_s32(int64_t num, int64_t den)
{
  int32_t y;
  const bool negative = (num < 0) != (den < 0);
  const uint64_t m = mag_u64(num);
  const uint64_t d = mag_u64(den);
  if (den == 0) {
    y = (num > 0) ? INT32_MAX : ((num < 0) ? INT32_MIN : 0);
  } else if ((m >> 31) >= d) {
    /* |quotient| >= 2^31: INT32_MIN exactly or beyond either end */
    y = negative ? INT32_MIN : INT32_MAX;
  } else {
    /* floor(m / d) < 2^31 by one 64/32 division: d itself when below 2^32
     * (m < d 2^31); else d's top word normalised to bit 63 (Hacker's
     * Delight, 9-5, "divDu"): v1 = floor(d 2^n / 2^32), and
     * floor(floor(m / 2) / v1) 2^n / 2^31 is the quotient or one above it;
     * one less is the quotient or one below it, and a compare of the
     * remainder decides. Scaling and overflow: m / 2 < v1 2^32, so the
     * 64/32 division applies; (q - 1) d <= m fits 64 bits. */
    const bool big = (d >> 32) != 0U;
    const unsigned n = big ? canfdi_clz32((uint32_t)(d >> 32)) : 0U; /* 0..31 */
    const uint32_t v = big ? (uint32_t)((d << n) >> 32) : (uint32_t)d;
    uint32_t r;
    uint32_t q = udiv_u64_u32(big ? (m >> 1) : m, v, &r);
    if (big) {
      q >>= 31U - n; /* q1 2^n / 2^31, exact in 64 bits */
      if (q != 0U) {
        q--;
      }
      {
        const uint32_t qdh = q * (uint32_t)(d >> 32); /* < 2^32: q d <= m */
        if ((m - (canfdi_umull32(q, (uint32_t)d) + ((uint64_t)qdh << 32))) >= d) {
          q++;
        }
      }
    }
    y = negative ? -(int32_t)q : (int32_t)q; /* q < 2^31 */
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
