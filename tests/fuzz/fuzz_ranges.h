/* fuzz_ranges.h — a frame's signals against the DBC (generated
 * fuzz_ranges.c, tests/fuzz/gen_ranges.py). True when every signal decodes
 * within its range; else false with *bad naming the first that does not. */
#ifndef FUZZ_RANGES_H
#define FUZZ_RANGES_H

#include <stdbool.h>
#include <stdint.h>

bool fuzz_frame_in_range(uint32_t id, const uint8_t *d, uint8_t dlc, const char **bad);

#endif /* FUZZ_RANGES_H */
