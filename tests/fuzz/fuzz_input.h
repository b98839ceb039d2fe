/*
 * fuzz_input.h — reading a libFuzzer input as a stream of small decisions
 * (harness side only; never part of the firmware). When the input is used
 * up every read returns 0, so a short input still drives a valid sequence.
 */
#ifndef FUZZ_INPUT_H
#define FUZZ_INPUT_H

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

typedef struct {
  const uint8_t *p;
  size_t n;
  size_t i;
} fz_in_t;

static inline int fz_left(const fz_in_t *in) { return in->i < in->n; }

static inline uint8_t fz_u8(fz_in_t *in)
{
  if (in->i >= in->n) {
    return 0U;
  }
  return in->p[in->i++];
}

static inline uint16_t fz_u16(fz_in_t *in)
{
  uint16_t hi = fz_u8(in);
  return (uint16_t)((uint16_t)(hi << 8) | fz_u8(in));
}

static inline uint32_t fz_u32(fz_in_t *in)
{
  uint32_t v = 0U;
  for (int k = 0; k < 4; k++) {
    v = (v << 8) | fz_u8(in);
  }
  return v;
}

/* An invariant of the issue-15 list broke: report it and abort, so that
 * libFuzzer keeps the input as a crash. */
#define FZ_CHECK(cond, ...)                                                  \
  do {                                                                       \
    if (!(cond)) {                                                           \
      fprintf(stderr, "fuzz invariant failed: %s (%s:%d): ", #cond, __FILE__, \
              __LINE__);                                                     \
      fprintf(stderr, __VA_ARGS__);                                          \
      fprintf(stderr, "\n");                                                 \
      abort();                                                               \
    }                                                                        \
  } while (0)

#endif /* FUZZ_INPUT_H */
