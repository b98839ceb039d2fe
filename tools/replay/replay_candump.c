/* replay_candump.c — one candump line; see replay_candump.h. */
#include "replay_candump.h"

#include <string.h>

/* Value of a hex digit, or -1: one table read per character (the parser
 * runs on every line of logs of millions of lines). */
#define HX(c, v) [(unsigned char)(c)] = (int8_t)((v) + 1)
static const int8_t hex_plus1[256] = {
    HX('0', 0),  HX('1', 1),  HX('2', 2),  HX('3', 3),  HX('4', 4),  HX('5', 5),  HX('6', 6),  HX('7', 7),
    HX('8', 8),  HX('9', 9),  HX('A', 10), HX('B', 11), HX('C', 12), HX('D', 13), HX('E', 14), HX('F', 15),
    HX('a', 10), HX('b', 11), HX('c', 12), HX('d', 13), HX('e', 14), HX('f', 15)};
#undef HX

static int hexval(char c) { return (int)hex_plus1[(unsigned char)c] - 1; }

static bool is_space(char c) { return (c == ' ') || (c == '\t') || (c == '\r'); }

/* "(sss.uuuuuu)" at line[*i]; advances *i past ')'. */
static bool parse_ts(const char *s, size_t n, size_t *i, int64_t *ts_us, const char **why)
{
  size_t k = *i;
  int64_t sec = 0;
  int64_t frac = 0;
  unsigned nd = 0U;
  unsigned nf = 0U;
  if ((k >= n) || (s[k] != '(')) {
    *why = "no '(timestamp)' at the start";
    return false;
  }
  k++;
  while ((k < n) && (s[k] >= '0') && (s[k] <= '9')) {
    if (nd >= 12U) {
      *why = "time stamp out of range (more than 12 digits of seconds)";
      return false;
    }
    sec = (sec * 10) + (s[k] - '0');
    nd++;
    k++;
  }
  if (nd == 0U) {
    *why = "time stamp has no seconds";
    return false;
  }
  if ((k < n) && (s[k] == '.')) {
    k++;
    while ((k < n) && (s[k] >= '0') && (s[k] <= '9')) {
      if (nf < 6U) {
        frac = (frac * 10) + (s[k] - '0');
      }
      nf++;
      k++;
    }
    if (nf == 0U) {
      *why = "time stamp has a '.' but no decimals";
      return false;
    }
  }
  if ((k >= n) || (s[k] != ')')) {
    *why = "time stamp not closed by ')'";
    return false;
  }
  while (nf < 6U) {
    frac *= 10;
    nf++;
  }
  *ts_us = (sec * 1000000) + frac;
  *i = k + 1U;
  return true;
}

/* Hex bytes at s[*i..]: up to max bytes, stops at the first non-hex char. */
static bool parse_bytes(const char *s, size_t n, size_t *i, uint8_t *out, unsigned max, uint8_t *len,
                        const char **why)
{
  size_t k = *i;
  unsigned b = 0U;
  int hi;
  while ((k < n) && ((hi = hexval(s[k])) >= 0)) {
    const int lo = ((k + 1U) < n) ? hexval(s[k + 1U]) : -1;
    if (lo < 0) {
      *why = "odd number of data digits";
      return false;
    }
    if (b >= max) {
      *why = (max == 8U) ? "more than 8 data bytes in a classic frame" : "more than 64 data bytes";
      return false;
    }
    out[b++] = (uint8_t)((hi << 4) | lo);
    k += 2U;
  }
  *len = (uint8_t)b;
  *i = k;
  return true;
}

static const uint8_t fd_lengths[] = {0, 1, 2, 3, 4, 5, 6, 7, 8, 12, 16, 20, 24, 32, 48, 64};

int rp_candump_parse(const char *s, size_t n, rp_frame_t *f, const char **why)
{
  size_t i = 0U;
  size_t c0;
  size_t nid = 0U;
  uint32_t id = 0U;
  *why = "";
  while ((i < n) && is_space(s[i])) {
    i++;
  }
  if ((i >= n) || (s[i] == '#')) {
    return RP_LINE_EMPTY;
  }
  if (!parse_ts(s, n, &i, &f->ts_us, why)) {
    return RP_LINE_BAD;
  }
  if ((i >= n) || !is_space(s[i])) {
    *why = "no channel after the time stamp";
    return RP_LINE_BAD;
  }
  while ((i < n) && is_space(s[i])) {
    i++;
  }
  c0 = i;
  while ((i < n) && !is_space(s[i])) {
    i++;
  }
  if ((i == c0) || (i >= n)) {
    *why = "no 'ID#DATA' after the channel";
    return RP_LINE_BAD;
  }
  if ((i - c0) >= RP_CHAN_MAX) {
    *why = "channel name longer than 15 characters";
    return RP_LINE_BAD;
  }
  memset(f->chan, 0, RP_CHAN_MAX);
  memcpy(f->chan, &s[c0], i - c0);
  while ((i < n) && is_space(s[i])) {
    i++;
  }
  while ((i < n) && (hexval(s[i]) >= 0) && (nid < 8U)) { /* 8 digits fill 32 bits: no bit shifted out */
    id = (id << 4) | (uint32_t)hexval(s[i]);
    nid++;
    i++;
  }
  if (((nid != 3U) && (nid != 8U)) || (i >= n) || (s[i] != '#')) {
    *why = "identifier is not 3 or 8 hex digits followed by '#'";
    return RP_LINE_BAD;
  }
  i++;
  f->ext = (nid == 8U);
  f->kind = RP_KIND_DATA;
  f->len = 0U;
  if (f->ext && ((id & RP_CAN_ERR_FLAG) != 0U)) {
    f->kind = RP_KIND_ERROR;
  } else if (!f->ext && (id > 0x7FFU)) {
    *why = "11-bit identifier above 0x7FF";
    return RP_LINE_BAD;
  } else {
    /* a data, remote or FD frame */
  }
  f->id = id & RP_CAN_EFF_MASK;
  if ((i < n) && (s[i] == '#')) {
    int fl;
    i++;
    fl = (i < n) ? hexval(s[i]) : -1;
    if (fl < 0) {
      *why = "CAN FD frame without its flags digit after '##'";
      return RP_LINE_BAD;
    }
    i++;
    if (!parse_bytes(s, n, &i, f->data, 64U, &f->len, why)) {
      return RP_LINE_BAD;
    }
    {
      size_t k;
      bool ok = false;
      for (k = 0U; k < sizeof fd_lengths; k++) {
        ok = ok || (fd_lengths[k] == f->len);
      }
      if (!ok) {
        *why = "CAN FD data length is not a valid FD length";
        return RP_LINE_BAD;
      }
    }
    f->kind = (f->kind == RP_KIND_ERROR) ? RP_KIND_ERROR : RP_KIND_FD;
  } else if ((i < n) && ((s[i] == 'R') || (s[i] == 'r'))) {
    i++;
    if ((i < n) && (hexval(s[i]) >= 0)) {
      f->len = (uint8_t)hexval(s[i]);
      i++;
    }
    f->kind = (f->kind == RP_KIND_ERROR) ? RP_KIND_ERROR : RP_KIND_REMOTE;
  } else {
    if (!parse_bytes(s, n, &i, f->data, 8U, &f->len, why)) {
      return RP_LINE_BAD;
    }
    if ((i < n) && (s[i] == '_')) { /* raw DLC 9..F of a classic 8-byte frame */
      if (((i + 1U) >= n) || (hexval(s[i + 1U]) < 9) || (f->len != 8U)) {
        *why = "'_' must follow 8 data bytes and carry a DLC 9..F";
        return RP_LINE_BAD;
      }
      i += 2U;
    }
  }
  if ((i < n) && !is_space(s[i])) {
    *why = "unexpected characters in the frame";
    return RP_LINE_BAD;
  }
  while ((i < n) && is_space(s[i])) {
    i++;
  }
  if ((i < n) && ((s[i] == 'R') || (s[i] == 'T') || (s[i] == 'r') || (s[i] == 't'))) {
    i++;
    while ((i < n) && is_space(s[i])) {
      i++;
    }
  }
  if (i != n) {
    *why = "unexpected text after the frame";
    return RP_LINE_BAD;
  }
  return RP_LINE_FRAME;
}
