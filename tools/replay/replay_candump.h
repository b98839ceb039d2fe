/*
 * replay_candump.h — one line of a candump log (`candump -L`, the format of
 * `canfdi-sil -l`, `canfdi-scenario` and python-can's CanutilsLogWriter):
 *
 *   (1700000000.123456) can0 123#DEADBEEF
 *   (0000000003.051000) vcan0 010##1112233        CAN FD: "##", a flags digit, data
 *   (0000000003.051000) vcan0 123#R                remote frame (optional length digit)
 *   (0000000003.051000) vcan0 20000080#0000...     error frame (CAN_ERR_FLAG in an 8-digit id)
 *   (0000000003.051000) vcan0 123#1122_C           classic frame with a raw DLC 9..F
 *
 * with an optional trailing direction flag (R/T). Time stamps are kept as
 * integer microseconds (the text's first six decimals; more are cut, fewer
 * padded), so that the log's 1 ms grid stays exact. A line is either a
 * frame, blank / a comment ('#' in the first column: ignored), or bad with
 * a reason; nothing is ever guessed from a bad line.
 *
 * Cost: one pass over the line, no allocation. Memory: the frame struct
 * (~90 bytes).
 */
#ifndef REPLAY_CANDUMP_H
#define REPLAY_CANDUMP_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#define RP_KIND_DATA 0U   /* classic data frame */
#define RP_KIND_FD 1U     /* CAN FD frame */
#define RP_KIND_REMOTE 2U /* remote frame */
#define RP_KIND_ERROR 3U  /* error frame */

#define RP_CHAN_MAX 16U   /* IFNAMSIZ, with the terminating NUL */
#define RP_CAN_ERR_FLAG 0x20000000UL
#define RP_CAN_EFF_MASK 0x1FFFFFFFUL

typedef struct {
  int64_t ts_us;           /* time stamp, microseconds */
  uint32_t id;             /* identifier without flags */
  bool ext;                /* 29-bit identifier (8 hex digits) */
  uint8_t kind;            /* RP_KIND_* */
  uint8_t len;             /* data bytes (classic 0..8, FD 0..64) */
  uint8_t data[64];
  char chan[RP_CHAN_MAX];  /* interface name, NUL-padded to RP_CHAN_MAX */
} rp_frame_t;

/* Whether two channel names are the same, both NUL-padded to RP_CHAN_MAX
 * (as the parser and rp_chan_set leave them): one fixed-size compare per
 * frame instead of a strcmp call. */
static inline bool rp_chan_eq(const char *a, const char *b) { return memcmp(a, b, RP_CHAN_MAX) == 0; }

/* dst (RP_CHAN_MAX bytes) = src cut to RP_CHAN_MAX - 1 characters, NUL-padded. */
static inline void rp_chan_set(char *dst, const char *src)
{
  size_t n = strlen(src);
  if (n >= RP_CHAN_MAX) {
    n = RP_CHAN_MAX - 1U;
  }
  memset(dst, 0, RP_CHAN_MAX);
  memcpy(dst, src, n);
}

#define RP_LINE_FRAME 1
#define RP_LINE_EMPTY 0
#define RP_LINE_BAD (-1)

/*
 * Parses line[0..n-1] (no newline). Returns RP_LINE_FRAME with *f filled,
 * RP_LINE_EMPTY for a blank or comment line, or RP_LINE_BAD with *why set to
 * a static reason.
 */
int rp_candump_parse(const char *line, size_t n, rp_frame_t *f, const char **why);

#endif /* REPLAY_CANDUMP_H */
