/*
 * canfdi_tps.c — throttle-position potentiometer characteristic; the
 * manual is the header.
 */
#include "model/canfdi_tps.h"

#include "core/canfdi_fixp.h"
#include "core/canfdi_qconst.h"

void canfdi_tps_cal_default(canfdi_tps_cal_t *tps1, canfdi_tps_cal_t *tps2)
{
  /* 4 V over 90 deg: 8 / pi V/rad (166886 in Q16.16, the exactly rounded
   * value). */
  const int32_t slope = canfdi_div_s32_qn(CANFDI_Q16_MILLI(4000), CANFDI_Q16_DEG(90, 1), 16U);
  if (tps1 != NULL) {
    tps1->zero_V_q16 = CANFDI_Q16_MILLI(500);
    tps1->slope_V_rad_q16 = slope;
  }
  if (tps2 != NULL) {
    tps2->zero_V_q16 = CANFDI_Q16_MILLI(4500);
    tps2->slope_V_rad_q16 = -slope;
  }
}

int32_t canfdi_tps_cal_check(const canfdi_tps_cal_t *cal)
{
  int32_t out = -CANFDI_EINVAL;
  if ((cal != NULL) && (cal->zero_V_q16 >= 0) && (cal->zero_V_q16 <= CANFDI_Q16_MILLI(5000))) {
    /* |slope| without overflow: the domain excludes INT32_MIN. */
    const int64_t mag = (cal->slope_V_rad_q16 < 0) ? -(int64_t)cal->slope_V_rad_q16
                                                   : (int64_t)cal->slope_V_rad_q16;
    if ((mag >= (int64_t)CANFDI_Q16_MILLI(100)) && (mag <= (int64_t)CANFDI_Q16_MILLI(10000))) {
      out = CANFDI_OK;
    }
  }
  return out;
}

int32_t canfdi_tps_init(canfdi_tps_t *t, const canfdi_tps_cal_t *cal)
{
  int32_t out = -CANFDI_EINVAL;
  if ((t != NULL) && (canfdi_tps_cal_check(cal) == CANFDI_OK)) {
    const int32_t mag = (cal->slope_V_rad_q16 < 0) ? -cal->slope_V_rad_q16 : cal->slope_V_rad_q16;
    t->cal = *cal;
    /* 1 / |slope| in Q8.24: 0.1 .. 10 rad/V, < 2^28. */
    t->rad_per_V_q24 = canfdi_div_s32_qn(CANFDI_Q16_ONE, mag, 24U);
    out = CANFDI_OK;
  }
  return out;
}

int32_t canfdi_tps_V_to_rad_q16(const canfdi_tps_t *t, int32_t v_V_q16)
{
  /* The difference in the direction of the slope, times 1 / |slope|. */
  const int32_t dv = (t->cal.slope_V_rad_q16 < 0) ? canfdi_sub_s32_sat(t->cal.zero_V_q16, v_V_q16)
                                                  : canfdi_sub_s32_sat(v_V_q16, t->cal.zero_V_q16);
  return canfdi_mul_s32_qn(dv, t->rad_per_V_q24, 24U);
}

int32_t canfdi_tps_rad_to_V_q16(const canfdi_tps_cal_t *cal, int32_t theta_rad_q16)
{
  return canfdi_add_s32_sat(cal->zero_V_q16, canfdi_mul_s32_qn(cal->slope_V_rad_q16, theta_rad_q16, 16U));
}
