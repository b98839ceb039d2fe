/*
 * canfdi_tps.h — the characteristic of one throttle-position potentiometer
 * (TPS): the straight line from the valve angle to the sensor's output
 * voltage, and its inverse: the calibration of that line as one struct, for
 * every module that converts TPS voltages (canfdi_parity_thr holds the pair
 * in its configuration; the plant and its datasheet figures:
 * docs/design.md).
 *
 *   V(theta) = zero + slope * theta          theta = (V - zero) / slope
 *
 * The electronic throttle carries two potentiometers on the same shaft with
 * opposite slopes (a complementary pair, TPS1 + TPS2 constant): the default
 * characteristic (canfdi_tps_cal_default) is 0.5 V at 0 rad rising by 4 V
 * per 90 deg for TPS1 and 4.5 V at 0 rad falling by 4 V per 90 deg for TPS2,
 * i.e. slopes of +-8/pi V/rad and a sum of 5 V.
 *
 * Conversion voltage -> angle. canfdi_tps_init prepares a characteristic
 * once: it keeps the calibration and 1 / |slope| in Q8.24 (one division at
 * init, none per sample). canfdi_tps_V_to_rad_q16 then forms the voltage
 * difference from the zero in the direction of the slope, (V - zero) for a
 * rising and (zero - V) for a falling characteristic, and multiplies it by
 * 1 / |slope|.
 * Scaling and overflow: inputs and outputs Q16.16 (V, rad). The difference
 * is a saturating int32_t subtraction; the product with 1 / |slope| (Q8.24,
 * 0.1 .. 10 rad/V by the domain below) is an exact 64-bit product rounded
 * half up to Q16.16 and saturated (canfdi_mul_s32_qn): every int32_t input
 * is accepted, nothing wraps. Within the sensor's supply range (0 .. 5 V)
 * no result saturates (|theta| <= 50 rad). Precision: 1 / |slope| in Q8.24
 * is exact to 2^-25 rad/V, a relative error below 3e-7 for |slope| <= 10
 * V/rad (below 8e-8 for the default 2.55 V/rad): over the 4 V span of the
 * default line below 1.2e-7 rad, far under the 1.5e-5 rad LSB: the angle
 * is within 1 LSB of the exact (V - zero) / slope.
 * Conversion angle -> voltage (canfdi_tps_rad_to_V_q16): zero + slope *
 * theta, the product rounded half up to Q16.16 and saturated, the sum
 * saturating.
 *
 * Cost: canfdi_tps_V_to_rad_q16 and canfdi_tps_rad_to_V_q16 one saturating
 * add/subtract, one 32x32->64 multiply (__aeabi_lmul on Cortex-M0+) and a
 * rounding shift each; canfdi_tps_init one canfdi_div_s32_qn (not for the
 * 1 ms path). Memory: sizeof(canfdi_tps_cal_t) = 8 bytes,
 * sizeof(canfdi_tps_t) = 12 bytes, caller-owned. No heap, no globals.
 */
#ifndef CANFDI_TPS_H
#define CANFDI_TPS_H

#include "core/canfdi_common.h"

/*
 * One potentiometer's characteristic, Q16.16. Domain (canfdi_tps_cal_check):
 * zero 0 .. 5 V, 0.1 V/rad <= |slope| <= 10 V/rad.
 */
typedef struct {
  int32_t zero_V_q16;      /* output voltage at theta = 0, V */
  int32_t slope_V_rad_q16; /* dV/dtheta, V/rad: > 0 rising, < 0 falling */
} canfdi_tps_cal_t;

/* A characteristic prepared for conversion (canfdi_tps_init); fields are
 * read-only for the caller. */
typedef struct {
  canfdi_tps_cal_t cal;
  int32_t rad_per_V_q24;   /* 1 / |slope|, rad/V, Q8.24 */
} canfdi_tps_t;

/* The default pair (see above): TPS1 0.5 V + 4 V per 90 deg, TPS2 4.5 V -
 * 4 V per 90 deg; the slopes are exact negatives of each other. A NULL
 * pointer is skipped. Cannot fail. Cost: one canfdi_div_s32_qn. */
void canfdi_tps_cal_default(canfdi_tps_cal_t *tps1, canfdi_tps_cal_t *tps2);

/* CANFDI_OK, or -CANFDI_EINVAL for NULL or a cal outside the domain. O(1). */
int32_t canfdi_tps_cal_check(const canfdi_tps_cal_t *cal);

/* Validates cal and prepares t (copies cal, computes 1 / |slope|).
 * CANFDI_OK, or -CANFDI_EINVAL for NULL or an invalid cal (t untouched).
 * Cost: one canfdi_div_s32_qn. */
int32_t canfdi_tps_init(canfdi_tps_t *t, const canfdi_tps_cal_t *cal);

/* The angle (rad, Q16.16) of the output voltage v (V, Q16.16, any int32_t;
 * saturating, see above). t from a successful canfdi_tps_init; cannot fail
 * by contract. O(1). */
int32_t canfdi_tps_V_to_rad_q16(const canfdi_tps_t *t, int32_t v_V_q16);

/* The output voltage (V, Q16.16) at the angle theta (rad, Q16.16, any
 * int32_t; saturating). cal within the domain; cannot fail by contract.
 * O(1). */
int32_t canfdi_tps_rad_to_V_q16(const canfdi_tps_cal_t *cal, int32_t theta_rad_q16);

#endif /* CANFDI_TPS_H */
