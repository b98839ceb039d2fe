/*
 * unit_q16.h — conversions between double (test side) and the firmware's
 * Q16.16 signals, shared by the plant-driven unit tests.
 * q16(): rounded to nearest, saturated to the int32 range (a plant value
 * beyond +-32768 is a test-rig error the firmware would see saturated too).
 */
#ifndef CANFDI_UNIT_Q16_H
#define CANFDI_UNIT_Q16_H

#include <math.h>
#include <stdint.h>

static inline int32_t q16(double x)
{
  double y = x * 65536.0;
  if (y > 2147483647.0) {
    y = 2147483647.0;
  } else if (y < -2147483648.0) {
    y = -2147483648.0;
  }
  return (int32_t)lround(y);
}

static inline double fq16(int32_t x)
{
  return (double)x / 65536.0;
}

#endif /* CANFDI_UNIT_Q16_H */
