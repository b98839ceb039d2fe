/*
 * canfdi_sim_uds.c — the scenario's diagnostic tester; the manual is the
 * header.
 */
#include "canfdi_sim_uds.h"

#include <stdio.h>
#include <string.h>

enum { ST_IDLE, ST_SEND_FF, ST_WAIT_FC, ST_SEND_CF, ST_WAIT_RESP, ST_SEND_FC, ST_RECV_CF };

#define PAD 0xCCU

void canfdi_sim_uds_tester_init(canfdi_sim_uds_tester_t *t, const canfdi_sim_uds_t *list, size_t n)
{
  memset(t, 0, sizeof *t);
  t->list = list;
  t->n = (n <= CANFDI_SIM_SCN_MAX_UDS) ? n : CANFDI_SIM_SCN_MAX_UDS;
  t->state = ST_IDLE;
}

/* "3E 00" of up to max bytes, "..." when longer. */
static void hex_text(const uint8_t *b, uint32_t n, char *out, size_t cap)
{
  size_t w = 0U;
  out[0] = '\0';
  for (uint32_t i = 0U; (i < n) && ((w + 8U) < cap); i++) {
    w += (size_t)snprintf(&out[w], cap - w, (i == 0U) ? "%02X" : " %02X", b[i]);
    if ((i == 15U) && (n > 16U)) {
      (void)snprintf(&out[w], cap - w, " ...");
      break;
    }
  }
}

static void finish(canfdi_sim_uds_tester_t *t, bool ok, const char *what)
{
  const canfdi_sim_uds_t *u = &t->list[t->cur];
  canfdi_sim_uds_verdict_t *v = &t->verdict[t->cur];
  char req[64];
  hex_text(u->req, u->req_len, req, sizeof req);
  v->done = true;
  v->ok = ok;
  (void)snprintf(v->msg, sizeof v->msg, "uds %s %s at %.3f s: %s", u->functional ? "func" : "phys", req,
                 (double)u->t_us * 1e-6, what);
  t->state = ST_IDLE;
}

static bool matches(const canfdi_sim_uds_t *u, const uint8_t *r, uint32_t n)
{
  bool ok = u->any_tail ? (n >= u->pat_len) : (n == u->pat_len);
  for (uint32_t i = 0U; ok && (i < u->pat_len); i++) {
    ok = (u->pat_any[i] != 0U) || (u->pat[i] == r[i]);
  }
  return ok;
}

static void judge(canfdi_sim_uds_tester_t *t)
{
  const canfdi_sim_uds_t *u = &t->list[t->cur];
  char got[64];
  char what[140];
  hex_text(t->resp, t->resp_len, got, sizeof got);
  if (!u->judged) {
    (void)snprintf(what, sizeof what, "%s (not judged)", got);
    finish(t, true, what);
  } else if (u->none) {
    (void)snprintf(what, sizeof what, "%s (expected no response)", got);
    finish(t, false, what);
  } else {
    (void)snprintf(what, sizeof what, "%s", got);
    finish(t, matches(u, t->resp, t->resp_len), what);
  }
}

static void start(canfdi_sim_uds_tester_t *t, int64_t t_us, bool *functional, uint8_t f[8])
{
  const canfdi_sim_uds_t *u = &t->list[t->next];
  t->cur = t->next;
  t->next++;
  *functional = u->functional;
  t->resp_len = 0U;
  t->resp_got = 0U;
  if (u->req_len <= 7U) {
    f[0] = u->req_len;
    memcpy(&f[1], u->req, u->req_len);
    t->state = ST_WAIT_RESP;
    t->deadline_us = t_us + (1000 * (u->none ? CANFDI_SIM_UDS_NONE_MS : CANFDI_SIM_UDS_TIMEOUT_MS));
  } else {
    f[0] = (uint8_t)(0x10U | ((u->req_len >> 8) & 0x0FU));
    f[1] = u->req_len;
    memcpy(&f[2], u->req, 6U);
    t->pos = 6U;
    t->sn = 1U;
    t->state = ST_WAIT_FC;
    t->deadline_us = t_us + 1000000;
  }
}

bool canfdi_sim_uds_tester_tx(canfdi_sim_uds_tester_t *t, int64_t t_us, bool *functional, uint8_t pdu[8])
{
  bool out = false;
  memset(pdu, PAD, 8U);
  *functional = false;
  if ((t->state == ST_IDLE) && (t->next < t->n) && (t->list[t->next].t_us <= t_us)) {
    start(t, t_us, functional, pdu);
    out = true;
  } else if (t->state == ST_SEND_CF) {
    t->gap = (t->gap > 0U) ? (uint8_t)(t->gap - 1U) : 0U;
    if (t->gap == 0U) {
      const canfdi_sim_uds_t *u = &t->list[t->cur];
      const uint32_t n = ((u->req_len - t->pos) < 7U) ? (u->req_len - t->pos) : 7U;
      pdu[0] = (uint8_t)(0x20U | t->sn);
      memcpy(&pdu[1], &u->req[t->pos], n);
      t->pos += n;
      t->sn = (uint8_t)((t->sn + 1U) & 0x0FU);
      t->gap = (t->stmin > 1U) ? t->stmin : 1U;
      if (t->pos >= u->req_len) {
        t->state = ST_WAIT_RESP;
        t->deadline_us = t_us + (1000 * (u->none ? CANFDI_SIM_UDS_NONE_MS : CANFDI_SIM_UDS_TIMEOUT_MS));
      } else if (t->block_limited && (--t->block == 0U)) {
        t->state = ST_WAIT_FC;
        t->deadline_us = t_us + 1000000;
      } else {
        /* more in this block */
      }
      out = true;
    }
  } else if (t->state == ST_SEND_FC) {
    pdu[0] = 0x30U;
    pdu[1] = 0U;
    pdu[2] = 0U;
    t->state = ST_RECV_CF;
    t->deadline_us = t_us + 1000000;
    out = true;
  } else if ((t->state != ST_IDLE) && (t_us > t->deadline_us)) {
    if ((t->state == ST_WAIT_RESP) && t->list[t->cur].none) {
      finish(t, true, "no response, as expected");
    } else {
      finish(t, false, (t->state == ST_WAIT_RESP) ? "no response within P2* (5 s)" : "ISO-TP timeout");
    }
  } else {
    /* waiting */
  }
  return out;
}

void canfdi_sim_uds_tester_rx(canfdi_sim_uds_tester_t *t, int64_t t_us, const uint8_t pdu[8])
{
  const unsigned type = pdu[0] >> 4;
  if ((t->state == ST_WAIT_FC) && (type == 3U)) {
    if ((pdu[0] & 0x0FU) == 0U) {
      t->block = pdu[1];
      t->block_limited = pdu[1] != 0U;
      t->stmin = (pdu[2] <= 0x7FU) ? pdu[2] : 1U;
      t->gap = 1U;
      t->state = ST_SEND_CF;
    } else if ((pdu[0] & 0x0FU) != 1U) {
      finish(t, false, "the ECU's flow control: overflow or invalid");
    } else {
      t->deadline_us = t_us + 1000000; /* wait */
    }
  } else if ((t->state == ST_WAIT_RESP) && (type == 0U) && ((pdu[0] & 0x0FU) >= 1U) &&
             ((pdu[0] & 0x0FU) <= 7U)) {
    t->resp_len = pdu[0] & 0x0FU;
    memcpy(t->resp, &pdu[1], t->resp_len);
    judge(t);
  } else if ((t->state == ST_WAIT_RESP) && (type == 1U)) {
    t->resp_len = ((uint32_t)(pdu[0] & 0x0FU) << 8) | pdu[1];
    if ((t->resp_len > CANFDI_SIM_UDS_RESP_MAX) || (t->resp_len < 8U)) {
      finish(t, false, "first frame of a bad length");
    } else {
      memcpy(t->resp, &pdu[2], 6U);
      t->resp_got = 6U;
      t->sn = 1U;
      t->state = ST_SEND_FC;
    }
  } else if ((t->state == ST_RECV_CF) && (type == 2U)) {
    if ((pdu[0] & 0x0FU) != t->sn) {
      finish(t, false, "consecutive frame out of sequence");
    } else {
      const uint32_t n = ((t->resp_len - t->resp_got) < 7U) ? (t->resp_len - t->resp_got) : 7U;
      memcpy(&t->resp[t->resp_got], &pdu[1], n);
      t->resp_got += n;
      t->sn = (uint8_t)((t->sn + 1U) & 0x0FU);
      t->deadline_us = t_us + 1000000;
      if (t->resp_got >= t->resp_len) {
        judge(t);
      }
    }
  } else {
    /* not for this tester's state: ignored */
  }
}

void canfdi_sim_uds_tester_finish(canfdi_sim_uds_tester_t *t)
{
  if (t->state != ST_IDLE) {
    if ((t->state == ST_WAIT_RESP) && t->list[t->cur].none) {
      finish(t, true, "no response, as expected (end of the run)");
    } else {
      finish(t, false, "no complete response by the end of the run");
    }
  }
  while (t->next < t->n) {
    t->cur = t->next;
    t->next++;
    finish(t, false, "not sent (the run ended first)");
  }
}
