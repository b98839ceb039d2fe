/*
 * unit_q16.h — conversions between double (test side) and the firmware's
 * Q16.16 signals, and window statistics, shared by the plant-driven unit
 * tests.
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

/* Running mean and standard deviation of a window of test samples. */
typedef struct {
  double s;
  double s2;
  long n;
} stat_t;

static inline void st_add(stat_t *st, double v)
{
  st->s += v;
  st->s2 += v * v;
  st->n++;
}

static inline double st_mean(const stat_t *st)
{
  return st->s / (double)st->n;
}

static inline double st_sd(const stat_t *st)
{
  const double m = st_mean(st);
  return sqrt(fmax(0.0, st->s2 / (double)st->n - m * m));
}

#endif /* CANFDI_UNIT_Q16_H */
