/*
 * canfdi_uds.c — the diagnostic server; the manual is the header.
 */
#include "uds/canfdi_uds.h"

#include "core/canfdi_count.h"
#include "core/canfdi_qconst.h"

#define S_DEF 0x01U /* default session */
#define S_EXT 0x02U /* extended session */
#define SPRMIB 0x80U
#define NO_RESPONSE 0xFFU /* internal: answer nothing */


typedef struct {
  canfdi_dtc_t *dtc;
  const canfdi_uds_src_t *src;
  bool functional;
} ctx_t;

typedef uint8_t (*svc_fn_t)(canfdi_uds_t *u, const ctx_t *c, canfdi_uds_msg_t *m);

/* ------------------------------------------------- the permission table */

typedef struct {
  uint8_t sid;
  uint8_t sessions;   /* S_DEF | S_EXT */
  uint8_t level;      /* security level needed, 0 none */
  bool subfn;         /* has a sub-function (and the suppress bit) */
  bool functional;    /* served on functional addressing */
  svc_fn_t fn;
} svc_row_t;

typedef struct {
  uint8_t sid;
  uint8_t subfn;
  uint8_t sessions;
  uint8_t level;
} subfn_row_t;

static uint8_t svc_dsc(canfdi_uds_t *u, const ctx_t *c, canfdi_uds_msg_t *m);
static uint8_t svc_er(canfdi_uds_t *u, const ctx_t *c, canfdi_uds_msg_t *m);
static uint8_t svc_cdtci(canfdi_uds_t *u, const ctx_t *c, canfdi_uds_msg_t *m);
static uint8_t svc_rdtci(canfdi_uds_t *u, const ctx_t *c, canfdi_uds_msg_t *m);
static uint8_t svc_rdbi(canfdi_uds_t *u, const ctx_t *c, canfdi_uds_msg_t *m);
static uint8_t svc_sa(canfdi_uds_t *u, const ctx_t *c, canfdi_uds_msg_t *m);
static uint8_t svc_cc(canfdi_uds_t *u, const ctx_t *c, canfdi_uds_msg_t *m);
static uint8_t svc_iocbi(canfdi_uds_t *u, const ctx_t *c, canfdi_uds_msg_t *m);
static uint8_t svc_rc(canfdi_uds_t *u, const ctx_t *c, canfdi_uds_msg_t *m);
static uint8_t svc_tp(canfdi_uds_t *u, const ctx_t *c, canfdi_uds_msg_t *m);

/* Service x session x security level, and the sub-functions likewise. */
static const svc_row_t services[] = {
    {CANFDI_UDS_SID_DSC, S_DEF | S_EXT, 0U, true, true, svc_dsc},
    {CANFDI_UDS_SID_ER, S_DEF | S_EXT, 0U, true, true, svc_er},
    {CANFDI_UDS_SID_CDTCI, S_DEF | S_EXT, 0U, false, true, svc_cdtci},
    {CANFDI_UDS_SID_RDTCI, S_DEF | S_EXT, 0U, true, true, svc_rdtci},
    {CANFDI_UDS_SID_RDBI, S_DEF | S_EXT, 0U, false, true, svc_rdbi},
    {CANFDI_UDS_SID_SA, S_EXT, 0U, true, false, svc_sa},
    {CANFDI_UDS_SID_CC, S_EXT, 0U, true, true, svc_cc},
    {CANFDI_UDS_SID_IOCBI, S_EXT, 1U, false, false, svc_iocbi},
    {CANFDI_UDS_SID_RC, S_EXT, 1U, true, false, svc_rc},
    {CANFDI_UDS_SID_TP, S_DEF | S_EXT, 0U, true, true, svc_tp},
};

static const subfn_row_t subfns[] = {
    {CANFDI_UDS_SID_DSC, CANFDI_UDS_SESSION_DEFAULT, S_DEF | S_EXT, 0U},
    {CANFDI_UDS_SID_DSC, CANFDI_UDS_SESSION_EXTENDED, S_DEF | S_EXT, 0U},
    {CANFDI_UDS_SID_ER, 0x01U, S_EXT, 0U}, /* hardReset: extended only (0x7E in default) */
    {CANFDI_UDS_SID_RDTCI, 0x01U, S_DEF | S_EXT, 0U},
    {CANFDI_UDS_SID_RDTCI, 0x02U, S_DEF | S_EXT, 0U},
    {CANFDI_UDS_SID_RDTCI, 0x03U, S_DEF | S_EXT, 0U},
    {CANFDI_UDS_SID_RDTCI, 0x04U, S_DEF | S_EXT, 0U},
    {CANFDI_UDS_SID_RDTCI, 0x06U, S_DEF | S_EXT, 0U},
    {CANFDI_UDS_SID_RDTCI, 0x0AU, S_DEF | S_EXT, 0U},
    {CANFDI_UDS_SID_RDTCI, 0x14U, S_DEF | S_EXT, 0U},
    {CANFDI_UDS_SID_SA, 0x01U, S_EXT, 0U},
    {CANFDI_UDS_SID_SA, 0x02U, S_EXT, 0U},
    {CANFDI_UDS_SID_SA, 0x03U, S_EXT, 0U},
    {CANFDI_UDS_SID_SA, 0x04U, S_EXT, 0U},
    {CANFDI_UDS_SID_CC, 0x00U, S_EXT, 0U},
    {CANFDI_UDS_SID_CC, 0x01U, S_EXT, 0U},
    {CANFDI_UDS_SID_RC, 0x01U, S_EXT, 1U},
    {CANFDI_UDS_SID_RC, 0x02U, S_EXT, 1U},
    {CANFDI_UDS_SID_RC, 0x03U, S_EXT, 1U},
    {CANFDI_UDS_SID_TP, 0x00U, S_DEF | S_EXT, 0U},
};

#define N_SERVICES (sizeof services / sizeof services[0])
#define N_SUBFNS (sizeof subfns / sizeof subfns[0])

/* ------------------------------------------------------------ helpers */

static uint8_t session_bit(const canfdi_uds_t *u)
{
  return (u->session == (uint8_t)CANFDI_UDS_SESSION_EXTENDED) ? S_EXT : S_DEF;
}

static bool level_ok(const canfdi_uds_t *u, uint8_t level)
{
  return (level == 0U) || (canfdi_uds_sec_level(&u->sec) >= level);
}

static int32_t abs_q(int32_t v) { return (v < 0) ? ((v == INT32_MIN) ? INT32_MAX : -v) : v; }

static void pos_head(canfdi_uds_msg_t *m) { canfdi_uds_put_u8(m, (uint8_t)(m->req[0] + CANFDI_UDS_POS_OFFSET)); }

/* The DC motor at rest (ECU reset, start of a test). */
static bool at_rest(const canfdi_uds_t *u, const ctx_t *c)
{
  const canfdi_rx_t *rx = c->src->rx;
  return canfdi_rx_valid(rx, CANFDI_RX_IN_DCM_OMEGA) &&
         (abs_q(canfdi_rx_value(rx, CANFDI_RX_IN_DCM_OMEGA)) <= u->cfg.rest_rad_s_q16) &&
         (abs_q(canfdi_rx_value(rx, CANFDI_RX_IN_SP_DCM_SPEED)) <= u->cfg.rest_rad_s_q16);
}

/* A fault: a DTC testFailed or a subsystem degraded. */
static bool any_fault(const ctx_t *c)
{
  return (canfdi_dtc_count_by_mask(c->dtc, (uint8_t)CANFDI_DTC_ST_TF) != 0U) ||
         (c->src->mgr->dcm_state != (uint8_t)CANFDI_DEG_NORMAL) ||
         (c->src->mgr->thr_state != (uint8_t)CANFDI_DEG_NORMAL);
}

static bool safe_state(const canfdi_uds_t *u, const ctx_t *c) { return at_rest(u, c) && !any_fault(c); }

static void spring_end(canfdi_uds_t *u, uint8_t status)
{
  u->spring_status = status;
  u->spring_phase = 0U;
}

/* What a session change ends (also the S3 fall-back and init). */
static void enter_session(canfdi_uds_t *u, uint8_t session)
{
  u->session = session;
  u->s3_left_ms = u->cfg.s3_ms;
  canfdi_uds_sec_lock(&u->sec);
  u->speed_on = false;
  u->angle_on = false;
  u->tx_silent = false;
  if (u->spring_phase != 0U) {
    spring_end(u, (uint8_t)CANFDI_UDS_RT_ABORTED);
  }
}

/* ------------------------------------------------------------ services */

static uint8_t svc_dsc(canfdi_uds_t *u, const ctx_t *c, canfdi_uds_msg_t *m)
{
  uint8_t nrc = CANFDI_UDS_NRC_IMLOIF;
  (void)c;
  if (m->req_len == 2U) {
    enter_session(u, (uint8_t)(m->req[1] & 0x7FU));
    pos_head(m);
    canfdi_uds_put_u8(m, (uint8_t)(m->req[1] & 0x7FU));
    canfdi_uds_put_u16(m, u->cfg.p2_ms);
    canfdi_uds_put_u16(m, (uint16_t)(u->cfg.p2star_ms / 10U));
    nrc = CANFDI_UDS_NRC_OK;
  }
  return nrc;
}

static uint8_t svc_er(canfdi_uds_t *u, const ctx_t *c, canfdi_uds_msg_t *m)
{
  uint8_t nrc = CANFDI_UDS_NRC_IMLOIF;
  if (m->req_len == 2U) {
    nrc = CANFDI_UDS_NRC_CNC;
    if (at_rest(u, c)) {
      pos_head(m);
      canfdi_uds_put_u8(m, (uint8_t)(m->req[1] & 0x7FU));
      u->reset_pending = true;
      nrc = CANFDI_UDS_NRC_OK;
    }
  }
  return nrc;
}

static uint8_t svc_cdtci(canfdi_uds_t *u, const ctx_t *c, canfdi_uds_msg_t *m)
{
  (void)u;
  return canfdi_uds_dtc_clear(c->dtc, m);
}

static uint8_t svc_rdtci(canfdi_uds_t *u, const ctx_t *c, canfdi_uds_msg_t *m)
{
  (void)u;
  return canfdi_uds_dtc_read(c->dtc, m);
}

static canfdi_uds_own_t own_values(const canfdi_uds_t *u)
{
  const canfdi_isotp_diag_t *d = &u->tp.diag;
  canfdi_uds_own_t o;
  o.isotp_errors = canfdi_count_sum(
      canfdi_count_sum(canfdi_count_sum(d->bad_length, d->wrong_sn), canfdi_count_sum(d->timeout_cr, d->timeout_bs)),
      canfdi_count_sum(canfdi_count_sum(d->wft_exceeded, d->tx_aborted), d->rx_overflow));
  o.security_attempts = u->sec.attempts;
  return o;
}

static uint8_t svc_rdbi(canfdi_uds_t *u, const ctx_t *c, canfdi_uds_msg_t *m)
{
  uint8_t nrc = CANFDI_UDS_NRC_IMLOIF;
  const uint32_t n = (m->req_len - 1U) / 2U;
  if ((m->req_len >= 3U) && (((m->req_len - 1U) % 2U) == 0U) && (n <= u->cfg.max_dids)) {
    const canfdi_uds_own_t own = own_values(u);
    uint32_t known = 0U;
    nrc = CANFDI_UDS_NRC_ROOR;
    pos_head(m);
    for (uint32_t k = 0U; k < n; k++) {
      const uint16_t did = canfdi_uds_get_u16(&m->req[1U + (2U * k)]);
      if (canfdi_uds_did_put(c->src, &u->cfg.ident, &own, did, m) == CANFDI_UDS_NRC_OK) {
        known++;
      }
    }
    if (known > 0U) {
      nrc = CANFDI_UDS_NRC_OK;
    }
  }
  return nrc;
}

static uint8_t svc_sa(canfdi_uds_t *u, const ctx_t *c, canfdi_uds_msg_t *m)
{
  uint8_t seed[CANFDI_UDS_SEC_SEED_BYTES];
  const uint8_t nrc = canfdi_uds_sec_request(&u->sec, m->req, m->req_len, u->steps, seed);
  (void)c;
  if (nrc == CANFDI_UDS_NRC_OK) {
    pos_head(m);
    canfdi_uds_put_u8(m, (uint8_t)(m->req[1] & 0x7FU));
    if ((m->req[1] & 1U) != 0U) {
      for (uint32_t k = 0U; k < CANFDI_UDS_SEC_SEED_BYTES; k++) {
        canfdi_uds_put_u8(m, seed[k]);
      }
    }
  }
  return nrc;
}

static uint8_t svc_cc(canfdi_uds_t *u, const ctx_t *c, canfdi_uds_msg_t *m)
{
  uint8_t nrc = CANFDI_UDS_NRC_IMLOIF;
  (void)c;
  if (m->req_len == 3U) {
    const uint8_t type = m->req[2];
    nrc = CANFDI_UDS_NRC_ROOR;
    if ((type == 0x01U) || (type == 0x03U)) {
      u->tx_silent = (m->req[1] & 0x7FU) == 0x01U;
      pos_head(m);
      canfdi_uds_put_u8(m, (uint8_t)(m->req[1] & 0x7FU));
      nrc = CANFDI_UDS_NRC_OK;
    }
  }
  return nrc;
}

/* 0x2F: control parameter 0x00 or 0x03 on D104 / D115. */
static uint8_t svc_iocbi(canfdi_uds_t *u, const ctx_t *c, canfdi_uds_msg_t *m)
{
  uint8_t nrc = CANFDI_UDS_NRC_IMLOIF;
  if (m->req_len >= 4U) {
    const uint16_t did = canfdi_uds_get_u16(&m->req[1]);
    const uint8_t param = m->req[3];
    const bool speed = did == CANFDI_UDS_DID_DCM_SPEED_REF;
    nrc = CANFDI_UDS_NRC_ROOR;
    if ((speed || (did == CANFDI_UDS_DID_THR_ANGLE_REF)) && ((param == 0x00U) || (param == 0x03U))) {
      nrc = CANFDI_UDS_NRC_IMLOIF;
      if (m->req_len == ((param == 0x00U) ? 4U : 8U)) {
        if (param == 0x00U) {
          u->speed_on = speed ? false : u->speed_on;
          u->angle_on = speed ? u->angle_on : false;
          nrc = CANFDI_UDS_NRC_OK;
        } else if (!safe_state(u, c) && !(u->speed_on || u->angle_on)) {
          nrc = CANFDI_UDS_NRC_CNC;
        } else {
          const int32_t v = canfdi_uds_get_s32(&m->req[4]);
          const bool in = speed ? (abs_q(v) <= u->cfg.ioc_speed_max_rad_s_q16)
                                : ((v >= u->cfg.ioc_angle_min_rad_q16) && (v <= u->cfg.ioc_angle_max_rad_q16));
          nrc = CANFDI_UDS_NRC_ROOR;
          if (in && (u->spring_phase == 0U)) {
            u->speed_on = speed ? true : u->speed_on;
            u->speed_rad_s_q16 = speed ? v : u->speed_rad_s_q16;
            u->angle_on = speed ? u->angle_on : true;
            u->angle_rad_q16 = speed ? u->angle_rad_q16 : v;
            nrc = CANFDI_UDS_NRC_OK;
          } else if (in) {
            nrc = CANFDI_UDS_NRC_CNC; /* the spring check drives the throttle */
          } else {
            /* out of range */
          }
        }
        if (nrc == CANFDI_UDS_NRC_OK) {
          pos_head(m);
          canfdi_uds_put_u16(m, did);
          canfdi_uds_put_u8(m, param);
          canfdi_uds_put_s32(m, speed ? (u->speed_on ? u->speed_rad_s_q16 : c->src->speed_ref_rad_s_q16)
                                      : (u->angle_on ? u->angle_rad_q16 : c->src->angle_ref_rad_q16));
        }
      }
    }
  }
  return nrc;
}

/* 0x31 on the estimator reset (0x0201). */
static uint8_t rc_estimator(canfdi_uds_t *u, const ctx_t *c, uint8_t sf, canfdi_uds_msg_t *m)
{
  uint8_t nrc = CANFDI_UDS_NRC_OK;
  if (sf == 0x01U) {
    if (m->req_len != 5U) {
      nrc = CANFDI_UDS_NRC_IMLOIF;
    } else if ((m->req[4] == 0U) || (m->req[4] > 3U)) {
      nrc = CANFDI_UDS_NRC_ROOR;
    } else if (!at_rest(u, c)) {
      nrc = CANFDI_UDS_NRC_CNC;
    } else {
      u->est_reset = m->req[4];
      u->est_status = (uint8_t)CANFDI_UDS_RT_PASSED;
    }
  } else if (sf == 0x02U) {
    nrc = CANFDI_UDS_NRC_SFNS; /* instantaneous: nothing to stop */
  } else if (m->req_len != 4U) {
    nrc = CANFDI_UDS_NRC_IMLOIF;
  } else if (u->est_status == (uint8_t)CANFDI_UDS_RT_NONE) {
    nrc = CANFDI_UDS_NRC_RSE;
  } else {
    /* results */
  }
  return nrc;
}

/* 0x31 on the spring check (0x0202). */
static uint8_t rc_spring(canfdi_uds_t *u, const ctx_t *c, uint8_t sf, canfdi_uds_msg_t *m)
{
  uint8_t nrc = CANFDI_UDS_NRC_OK;
  if (m->req_len != 4U) {
    nrc = CANFDI_UDS_NRC_IMLOIF;
  } else if (sf == 0x01U) {
    if ((u->spring_phase != 0U) || u->angle_on || u->speed_on || !safe_state(u, c)) {
      nrc = CANFDI_UDS_NRC_CNC;
    } else {
      u->spring_phase = 1U;
      u->spring_ms = 0U;
      u->spring_return_ms = 0U;
      u->spring_angle_rad_q16 = c->src->vote->angle_rad_q16;
      u->spring_status = (uint8_t)CANFDI_UDS_RT_RUNNING;
    }
  } else if (sf == 0x02U) {
    if (u->spring_phase == 0U) {
      nrc = CANFDI_UDS_NRC_RSE;
    } else {
      spring_end(u, (uint8_t)CANFDI_UDS_RT_ABORTED);
    }
  } else if (u->spring_status == (uint8_t)CANFDI_UDS_RT_NONE) {
    nrc = CANFDI_UDS_NRC_RSE;
  } else {
    /* results */
  }
  return nrc;
}

static uint8_t svc_rc(canfdi_uds_t *u, const ctx_t *c, canfdi_uds_msg_t *m)
{
  uint8_t nrc = CANFDI_UDS_NRC_IMLOIF;
  if (m->req_len >= 4U) {
    const uint8_t sf = (uint8_t)(m->req[1] & 0x7FU);
    const uint16_t rid = canfdi_uds_get_u16(&m->req[2]);
    nrc = CANFDI_UDS_NRC_ROOR;
    if (rid == CANFDI_UDS_RID_ESTIMATOR_RESET) {
      nrc = rc_estimator(u, c, sf, m);
    } else if (rid == CANFDI_UDS_RID_SPRING_CHECK) {
      nrc = rc_spring(u, c, sf, m);
    } else {
      /* unknown routine */
    }
    if (nrc == CANFDI_UDS_NRC_OK) {
      const bool est = rid == CANFDI_UDS_RID_ESTIMATOR_RESET;
      pos_head(m);
      canfdi_uds_put_u8(m, sf);
      canfdi_uds_put_u16(m, rid);
      canfdi_uds_put_u8(m, est ? u->est_status : u->spring_status);
      if (!est && (sf == 0x03U)) {
        canfdi_uds_put_u16(m, u->spring_return_ms);
        canfdi_uds_put_s32(m, u->spring_angle_rad_q16);
      }
    }
  }
  return nrc;
}

static uint8_t svc_tp(canfdi_uds_t *u, const ctx_t *c, canfdi_uds_msg_t *m)
{
  uint8_t nrc = CANFDI_UDS_NRC_IMLOIF;
  (void)u;
  (void)c;
  if (m->req_len == 2U) {
    pos_head(m);
    canfdi_uds_put_u8(m, 0x00U);
    nrc = CANFDI_UDS_NRC_OK;
  }
  return nrc;
}

/* ------------------------------------------------------------ dispatch */

static const svc_row_t *find_service(uint8_t sid)
{
  const svc_row_t *r = NULL;
  for (uint32_t i = 0U; (i < N_SERVICES) && (r == NULL); i++) {
    if (services[i].sid == sid) {
      r = &services[i];
    }
  }
  return r;
}

static const subfn_row_t *find_subfn(uint8_t sid, uint8_t sf)
{
  const subfn_row_t *r = NULL;
  for (uint32_t i = 0U; (i < N_SUBFNS) && (r == NULL); i++) {
    if ((subfns[i].sid == sid) && (subfns[i].subfn == sf)) {
      r = &subfns[i];
    }
  }
  return r;
}

/* The general checks in ISO order, then the service. Returns the NRC. */
static uint8_t dispatch(canfdi_uds_t *u, const ctx_t *c, canfdi_uds_msg_t *m)
{
  const svc_row_t *s = find_service(m->req[0]);
  uint8_t nrc = CANFDI_UDS_NRC_OK;
  if (s == NULL) {
    nrc = CANFDI_UDS_NRC_SNS;
  } else if (c->functional && !s->functional) {
    nrc = NO_RESPONSE; /* a physical-only service */
  } else if ((s->sessions & session_bit(u)) == 0U) {
    nrc = CANFDI_UDS_NRC_SNSIAS;
  } else if (!level_ok(u, s->level)) {
    nrc = CANFDI_UDS_NRC_SAD;
  } else if (s->subfn) {
    const subfn_row_t *f = (m->req_len >= 2U) ? find_subfn(s->sid, (uint8_t)(m->req[1] & 0x7FU)) : NULL;
    if (m->req_len < 2U) {
      nrc = CANFDI_UDS_NRC_IMLOIF;
    } else if ((f == NULL) || ((s->sid == CANFDI_UDS_SID_RDTCI) &&
                               !canfdi_uds_dtc_subfn_supported((uint8_t)(m->req[1] & 0x7FU)))) {
      nrc = CANFDI_UDS_NRC_SFNS;
    } else if ((f->sessions & session_bit(u)) == 0U) {
      nrc = CANFDI_UDS_NRC_SFNSIAS;
    } else if (!level_ok(u, f->level)) {
      nrc = CANFDI_UDS_NRC_SAD;
    } else {
      nrc = s->fn(u, c, m);
    }
  } else {
    nrc = s->fn(u, c, m);
  }
  if ((nrc == CANFDI_UDS_NRC_OK) && m->overflow) {
    nrc = CANFDI_UDS_NRC_RTL;
  }
  return nrc;
}

static bool silent_on_functional(uint8_t nrc)
{
  return (nrc == CANFDI_UDS_NRC_SNS) || (nrc == CANFDI_UDS_NRC_SFNS) || (nrc == CANFDI_UDS_NRC_ROOR) ||
         (nrc == CANFDI_UDS_NRC_SFNSIAS) || (nrc == CANFDI_UDS_NRC_SNSIAS) || (nrc == NO_RESPONSE);
}

/* One request: the response (or none) handed to ISO-TP. */
static void serve(canfdi_uds_t *u, const ctx_t *c, const uint8_t *req, uint32_t len)
{
  const svc_row_t *s = find_service(req[0]);
  const bool sprmib = (s != NULL) && s->subfn && (len >= 2U) && ((req[1] & SPRMIB) != 0U);
  canfdi_uds_msg_t m;
  uint8_t nrc;
  m.req = req;
  m.req_len = len;
  m.resp = canfdi_isotp_tx_buf(&u->tp);
  m.resp_cap = CANFDI_CFG_ISOTP_TX_BYTES;
  m.resp_len = 0U;
  m.overflow = false;
  canfdi_count_inc(&u->diag.requests);
  u->s3_left_ms = u->cfg.s3_ms;
  nrc = dispatch(u, c, &m);
  if (nrc == CANFDI_UDS_NRC_OK) {
    canfdi_count_inc(&u->diag.positive);
    if (sprmib) {
      canfdi_count_inc(&u->diag.suppressed);
    } else {
      (void)canfdi_isotp_send(&u->tp, m.resp_len);
    }
  } else if (c->functional && silent_on_functional(nrc)) {
    canfdi_count_inc(&u->diag.func_silent);
  } else if (nrc != NO_RESPONSE) {
    canfdi_count_inc(&u->diag.negative);
    m.resp[0] = (uint8_t)CANFDI_UDS_NEG;
    m.resp[1] = req[0];
    m.resp[2] = nrc;
    (void)canfdi_isotp_send(&u->tp, 3U);
  } else {
    canfdi_count_inc(&u->diag.func_silent);
  }
}

/* ------------------------------------------------------------ timers */

static void spring_step(canfdi_uds_t *u, const ctx_t *c)
{
  const int32_t angle = c->src->vote->angle_rad_q16;
  u->spring_ms = (u->spring_ms < UINT16_MAX) ? (uint16_t)(u->spring_ms + 1U) : UINT16_MAX;
  u->spring_angle_rad_q16 = angle;
  if (u->spring_phase == 1U) {
    if (u->spring_ms >= u->cfg.spring_open_ms) {
      u->spring_phase = 2U;
      u->spring_ms = 0U;
    }
  } else if (abs_q(angle - u->cfg.limp_home_rad_q16) <= u->cfg.spring_band_rad_q16) {
    u->spring_return_ms = u->spring_ms;
    spring_end(u, (u->spring_ms <= u->cfg.spring_pass_ms) ? (uint8_t)CANFDI_UDS_RT_PASSED
                                                          : (uint8_t)CANFDI_UDS_RT_FAILED);
  } else if (u->spring_ms >= u->cfg.spring_timeout_ms) {
    u->spring_return_ms = u->spring_ms;
    spring_end(u, (uint8_t)CANFDI_UDS_RT_FAILED);
  } else {
    /* returning */
  }
}

static void timers(canfdi_uds_t *u, const ctx_t *c)
{
  canfdi_uds_sec_tick(&u->sec);
  if (u->session != (uint8_t)CANFDI_UDS_SESSION_DEFAULT) {
    if (u->s3_left_ms > 0U) {
      u->s3_left_ms--;
    }
    if (u->s3_left_ms == 0U) {
      canfdi_count_inc(&u->diag.s3_timeouts);
      enter_session(u, (uint8_t)CANFDI_UDS_SESSION_DEFAULT);
    }
  }
  if ((u->speed_on || u->angle_on || (u->spring_phase != 0U)) && any_fault(c)) {
    canfdi_count_inc(&u->diag.ioc_fault_ends);
    u->speed_on = false;
    u->angle_on = false;
    if (u->spring_phase != 0U) {
      spring_end(u, (uint8_t)CANFDI_UDS_RT_ABORTED);
    }
  }
  if (u->spring_phase != 0U) {
    spring_step(u, c);
  }
}

static void fill_act(canfdi_uds_t *u, canfdi_uds_act_t *act)
{
  act->speed_override = u->speed_on;
  act->speed_ref_rad_s_q16 = u->speed_rad_s_q16;
  act->angle_override = u->angle_on || (u->spring_phase == 1U);
  act->angle_ref_rad_q16 = (u->spring_phase == 1U) ? u->cfg.spring_open_rad_q16 : u->angle_rad_q16;
  act->thr_release = u->spring_phase == 2U;
  act->est_reset = u->est_reset;
  u->est_reset = 0U;
  act->tx_silent = u->tx_silent;
  act->ecu_reset = false;
}

/* ------------------------------------------------------------ API */

void canfdi_uds_default_cfg(canfdi_uds_cfg_t *cfg)
{
  static const canfdi_uds_ident_t ident = {
      {'c', 'a', 'n', 'f', 'd', 'i', ' ', '1', '4', '.', '0', ' ', ' ', ' ', ' ', ' '},
      {'C', 'A', 'L', '-', 'D', 'E', 'F', 'A', 'U', 'L', 'T', '-', '0', '0', '0', '1'},
      {'C', 'F', 'D', 'I', '-', '0', '0', '0', '0', '0', '0', '0', '0', '0', '0', '1'}};
  if (cfg != NULL) {
    canfdi_isotp_default_cfg(&cfg->tp);
    canfdi_uds_sec_default_cfg(&cfg->sec);
    cfg->ident = ident;
    cfg->p2_ms = 50U;
    cfg->p2star_ms = 5000U;
    cfg->s3_ms = 5000U;
    cfg->max_dids = 16U;
    cfg->rest_rad_s_q16 = 10 * CANFDI_Q16_ONE;
    cfg->ioc_speed_max_rad_s_q16 = 200 * CANFDI_Q16_ONE;
    cfg->ioc_angle_min_rad_q16 = 0;
    cfg->ioc_angle_max_rad_q16 = CANFDI_Q16_DEG(80, 1);
    cfg->limp_home_rad_q16 = CANFDI_Q16_DEG(13, 2);
    cfg->spring_open_rad_q16 = CANFDI_Q16_DEG(25, 1);
    cfg->spring_band_rad_q16 = CANFDI_Q16_DEG(2, 1);
    cfg->spring_open_ms = 400U;
    cfg->spring_pass_ms = 200U;
    cfg->spring_timeout_ms = 1000U;
  }
}

int32_t canfdi_uds_init(canfdi_uds_t *u, const canfdi_uds_cfg_t *cfg, uint8_t sec_attempts, uint32_t entropy)
{
  int32_t rc = -CANFDI_EINVAL;
  if ((u != NULL) && (cfg != NULL) && (cfg->s3_ms >= 1U) && (cfg->max_dids >= 1U) && (cfg->max_dids <= 63U) &&
      (cfg->spring_open_ms >= 1U) && (cfg->spring_timeout_ms >= 1U) &&
      (cfg->ioc_angle_min_rad_q16 <= cfg->ioc_angle_max_rad_q16) &&
      (canfdi_isotp_init(&u->tp, &cfg->tp) == CANFDI_OK) &&
      (canfdi_uds_sec_init(&u->sec, &cfg->sec, sec_attempts, entropy) == CANFDI_OK)) {
    u->cfg = *cfg;
    u->steps = 0U;
    u->reset_pending = false;
    u->speed_rad_s_q16 = 0;
    u->angle_rad_q16 = 0;
    u->est_reset = 0U;
    u->est_status = (uint8_t)CANFDI_UDS_RT_NONE;
    u->spring_status = (uint8_t)CANFDI_UDS_RT_NONE;
    u->spring_phase = 0U;
    u->spring_ms = 0U;
    u->spring_return_ms = 0U;
    u->spring_angle_rad_q16 = 0;
    u->diag = (canfdi_uds_diag_t){0};
    enter_session(u, (uint8_t)CANFDI_UDS_SESSION_DEFAULT);
    u->initialised = true;
    rc = CANFDI_OK;
  }
  return rc;
}

int32_t canfdi_uds_rx_can(canfdi_uds_t *u, bool functional, const uint8_t *data, uint8_t dlc)
{
  return (u != NULL) ? canfdi_isotp_rx_can(&u->tp, functional, data, dlc) : -CANFDI_EINVAL;
}

int32_t canfdi_uds_step(canfdi_uds_t *u, canfdi_dtc_t *dtc, const canfdi_uds_src_t *src, canfdi_uds_act_t *act,
                        uint8_t frame[CANFDI_CFG_ISOTP_FRAME_BYTES])
{
  int32_t rc = -CANFDI_EINVAL;
  if ((u != NULL) && u->initialised && (dtc != NULL) && (src != NULL) && (act != NULL) && (frame != NULL)) {
    ctx_t c;
    c.dtc = dtc;
    c.src = src;
    c.functional = false;
    u->steps++;
    timers(u, &c);
    if (!canfdi_isotp_tx_busy(&u->tp)) {
      const uint8_t *req = NULL;
      const uint32_t len = canfdi_isotp_rx_peek(&u->tp, &req, &c.functional);
      if (len > 0U) {
        serve(u, &c, req, len);
        canfdi_isotp_rx_release(&u->tp);
      }
    }
    rc = canfdi_isotp_step(&u->tp, frame);
    fill_act(u, act);
    if (u->reset_pending && !canfdi_isotp_tx_busy(&u->tp)) {
      u->reset_pending = false;
      act->ecu_reset = true;
    }
  }
  return rc;
}

uint8_t canfdi_uds_sec_attempts(const canfdi_uds_t *u) { return (u != NULL) ? u->sec.attempts : 0U; }

uint32_t canfdi_uds_nvm_changes(const canfdi_uds_t *u) { return (u != NULL) ? u->sec.changes : 0U; }

uint8_t canfdi_uds_session(const canfdi_uds_t *u) { return (u != NULL) ? u->session : 0U; }
