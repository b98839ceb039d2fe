/*
 * fuzz_candump.c — the candump line parser of the replay core
 * (tools/replay/replay_candump.c), fed one arbitrary line (no NUL needed:
 * the parser takes a length). Invariants: the result is one of the three
 * documented values; a frame has a length its kind allows, an identifier
 * within its format and a NUL-terminated interface name; a bad line has a
 * reason.
 */
#include <string.h>

#include "fuzz_input.h"
#include "replay_candump.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
  rp_frame_t f;
  const char *why = NULL;
  /* a private copy: reading past size is caught by ASan */
  char *line = malloc(size ? size : 1U);
  if (line == NULL) {
    return 0;
  }
  memcpy(line, data, size);
  memset(&f, 0xA5, sizeof f);
  const int r = rp_candump_parse(line, size, &f, &why);
  FZ_CHECK(r == RP_LINE_FRAME || r == RP_LINE_EMPTY || r == RP_LINE_BAD, "result %d", r);
  if (r == RP_LINE_FRAME) {
    FZ_CHECK(f.kind <= RP_KIND_ERROR, "kind %u", f.kind);
    /* classic data 0..8; a remote frame's len is its DLC field (0..F,
     * no data); FD 0..64; an error frame (CAN_ERR_FLAG) is taken in either
     * syntax, the replay core counts and skips it */
    FZ_CHECK(f.len <= ((f.kind == RP_KIND_DATA) ? 8U : (f.kind == RP_KIND_REMOTE) ? 15U : 64U),
             "len %u kind %u", f.len, f.kind);
    FZ_CHECK(f.id <= (f.ext ? RP_CAN_EFF_MASK : 0x7FFUL) || f.kind == RP_KIND_ERROR, "id %x", (unsigned)f.id);
    FZ_CHECK(memchr(f.chan, '\0', sizeof f.chan) != NULL, "%s", "chan not terminated");
  } else if (r == RP_LINE_BAD) {
    FZ_CHECK(why != NULL && why[0] != '\0', "%s", "bad line without a reason");
  }
  free(line);
  return 0;
}
