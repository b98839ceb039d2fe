/*
 * canfdi_qconst.h — compile-time fixed-point constants from integers: the
 * one place where a decimal, a ratio or an angle in degrees becomes a
 * Q16.16 or Q8.24 number, and the one value of pi.
 *
 * Why: a constant written twice drifts apart (a sensor characteristic with
 * pi/2 as 25736 in one module and as 355/113 in another gives a false
 * residual, not a compile error). Modules write physical values the way a
 * datasheet gives them (CANFDI_Q16_MILLI(4750) for 4.750 V,
 * CANFDI_Q16_DEG(7, 1) for 7 degrees) and never a raw Q literal without its
 * derivation.
 *
 * Scaling and overflow: integer constant expressions in int64_t (see
 * CANFDI_QN_RATIO_ in canfdi_fixp.h), rounded half up and saturated to
 * int32_t. Domain: |num| <= 2^30 and 0 < den <= 2^30 for the ratio forms;
 * CANFDI_Q16_MILLI takes |m| <= 2^31 / 65.536 (values below 32768.0);
 * CANFDI_Q16_DEG takes |num| <= 20000 and 0 < den <= 10^6 (the int64_t
 * intermediates num * CANFDI_PI_NUM * 2^17 and den * 180 * CANFDI_PI_DEN
 * stay below 2^63). Cost: none at run time for constant arguments.
 */
#ifndef CANFDI_QCONST_H
#define CANFDI_QCONST_H

#include "core/canfdi_fixp.h"

/* 1.0 in Q16.16 and Q8.24. */
#define CANFDI_Q16_ONE ((int32_t)65536)
#define CANFDI_Q24_ONE ((int32_t)16777216)

/* pi as the ratio CANFDI_PI_NUM / CANFDI_PI_DEN (10 significant digits:
 * relative error 1e-10, below 0.02 LSB of any Q16.16 or Q8.24 angle up to
 * 2 pi). */
#define CANFDI_PI_NUM ((int64_t)3141592654)
#define CANFDI_PI_DEN ((int64_t)1000000000)

/* num/den in Q16.16 and Q8.24, saturating to int32_t. */
#define CANFDI_Q16(num, den) ((int32_t)CANFDI_QN_RATIO_SAT_((num), (den), 16, INT32_MIN, INT32_MAX))
#define CANFDI_Q24(num, den) ((int32_t)CANFDI_QN_RATIO_SAT_((num), (den), 24, INT32_MIN, INT32_MAX))

/* A decimal given in thousandths, in Q16.16: CANFDI_Q16_MILLI(1200) = 1.2. */
#define CANFDI_Q16_MILLI(m) CANFDI_Q16((m), 1000)

/* (num/den) degrees in radians, Q16.16: CANFDI_Q16_DEG(90, 1) = pi/2. */
#define CANFDI_Q16_DEG(num, den)                                                          \
  ((int32_t)CANFDI_QN_RATIO_SAT_((int64_t)(num) * CANFDI_PI_NUM,                          \
                                 (int64_t)(den) * 180 * CANFDI_PI_DEN, 16, INT32_MIN, INT32_MAX))

#endif /* CANFDI_QCONST_H */
