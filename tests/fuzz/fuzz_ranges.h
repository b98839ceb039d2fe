/* fuzz_ranges.h — a frame's signals against the DBC (generated
 * fuzz_ranges.c, tests/fuzz/gen_ranges.py). True when every signal decodes
 * within its range; else false with *bad naming the first that does not. */
#ifndef FUZZ_RANGES_H
#define FUZZ_RANGES_H

#include <stdbool.h>
#include <stdint.h>

bool fuzz_frame_in_range(uint32_t id, const uint8_t *d, uint8_t dlc, const char **bad);

/* The codec round trip of message k (0..fuzz_codec_count-1 of the tester
 * codec): NULL when d does not unpack or when pack(unpack(d)) unpacks to the
 * same signals and the firmware's own unpack (messages it receives) agrees;
 * else what differs. */
extern const unsigned fuzz_codec_count;
const char *fuzz_codec_check(unsigned k, const uint8_t *d, uint8_t dlc);

#endif /* FUZZ_RANGES_H */
