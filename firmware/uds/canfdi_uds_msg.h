/*
 * canfdi_uds_msg.h — what the diagnostic server's modules share: the
 * ISO 14229-1 service identifiers and negative response codes (NRC) it
 * uses, and the request/response pair a service handler works on.
 *
 * A handler reads req[0..req_len) (req[0] is the service id) and appends
 * its positive response to resp with the canfdi_uds_put_* helpers, which
 * never write past resp_cap: a response that does not fit sets
 * `overflow`, and the server answers NRC 0x14 (responseTooLong) instead.
 * Multi-byte values are big-endian, the UDS byte order. Cost O(1) per put.
 */
#ifndef CANFDI_UDS_MSG_H
#define CANFDI_UDS_MSG_H

#include "core/canfdi_common.h"

/* Services. */
#define CANFDI_UDS_SID_DSC 0x10U  /* DiagnosticSessionControl */
#define CANFDI_UDS_SID_ER 0x11U   /* ECUReset */
#define CANFDI_UDS_SID_CDTCI 0x14U /* ClearDiagnosticInformation */
#define CANFDI_UDS_SID_RDTCI 0x19U /* ReadDTCInformation */
#define CANFDI_UDS_SID_RDBI 0x22U /* ReadDataByIdentifier */
#define CANFDI_UDS_SID_SA 0x27U   /* SecurityAccess */
#define CANFDI_UDS_SID_CC 0x28U   /* CommunicationControl */
#define CANFDI_UDS_SID_IOCBI 0x2FU /* InputOutputControlByIdentifier */
#define CANFDI_UDS_SID_RC 0x31U   /* RoutineControl */
#define CANFDI_UDS_SID_TP 0x3EU   /* TesterPresent */
#define CANFDI_UDS_NEG 0x7FU      /* negative response service id */
#define CANFDI_UDS_POS_OFFSET 0x40U

/* Negative response codes (0: positive). */
#define CANFDI_UDS_NRC_OK 0x00U
#define CANFDI_UDS_NRC_SNS 0x11U    /* serviceNotSupported */
#define CANFDI_UDS_NRC_SFNS 0x12U   /* subFunctionNotSupported */
#define CANFDI_UDS_NRC_IMLOIF 0x13U /* incorrectMessageLengthOrInvalidFormat */
#define CANFDI_UDS_NRC_RTL 0x14U    /* responseTooLong */
#define CANFDI_UDS_NRC_CNC 0x22U    /* conditionsNotCorrect */
#define CANFDI_UDS_NRC_RSE 0x24U    /* requestSequenceError */
#define CANFDI_UDS_NRC_ROOR 0x31U   /* requestOutOfRange */
#define CANFDI_UDS_NRC_SAD 0x33U    /* securityAccessDenied */
#define CANFDI_UDS_NRC_IK 0x35U     /* invalidKey */
#define CANFDI_UDS_NRC_ENOA 0x36U   /* exceededNumberOfAttempts */
#define CANFDI_UDS_NRC_RTDNE 0x37U  /* requiredTimeDelayNotExpired */
#define CANFDI_UDS_NRC_SFNSIAS 0x7EU /* subFunctionNotSupportedInActiveSession */
#define CANFDI_UDS_NRC_SNSIAS 0x7FU  /* serviceNotSupportedInActiveSession */

/* Sessions. */
#define CANFDI_UDS_SESSION_DEFAULT 0x01U
#define CANFDI_UDS_SESSION_EXTENDED 0x03U

typedef struct {
  const uint8_t *req; /* req[0] is the service id */
  uint32_t req_len;
  uint8_t *resp;      /* resp[0] is the positive response id */
  uint32_t resp_cap;
  uint32_t resp_len;
  bool overflow;      /* a put did not fit: NRC 0x14 */
} canfdi_uds_msg_t;

static inline void canfdi_uds_put_u8(canfdi_uds_msg_t *m, uint8_t v)
{
  if (m->resp_len < m->resp_cap) {
    m->resp[m->resp_len] = v;
    m->resp_len++;
  } else {
    m->overflow = true;
  }
}

static inline void canfdi_uds_put_u16(canfdi_uds_msg_t *m, uint16_t v)
{
  canfdi_uds_put_u8(m, (uint8_t)(v >> 8));
  canfdi_uds_put_u8(m, (uint8_t)(v & 0xFFU));
}

static inline void canfdi_uds_put_u24(canfdi_uds_msg_t *m, uint32_t v)
{
  canfdi_uds_put_u8(m, (uint8_t)((v >> 16) & 0xFFU));
  canfdi_uds_put_u16(m, (uint16_t)(v & 0xFFFFU));
}

static inline void canfdi_uds_put_u32(canfdi_uds_msg_t *m, uint32_t v)
{
  canfdi_uds_put_u16(m, (uint16_t)(v >> 16));
  canfdi_uds_put_u16(m, (uint16_t)(v & 0xFFFFU));
}

/* A signed value as its 32-bit two's complement pattern. */
static inline void canfdi_uds_put_s32(canfdi_uds_msg_t *m, int32_t v)
{
  canfdi_uds_put_u32(m, (v >= 0) ? (uint32_t)v : (uint32_t)(~(uint32_t)(-(v + 1))));
}

/* Big-endian reads of the request; the caller has checked the length. */
static inline uint16_t canfdi_uds_get_u16(const uint8_t *p)
{
  return (uint16_t)(((uint32_t)p[0] << 8) | (uint32_t)p[1]);
}

static inline uint32_t canfdi_uds_get_u24(const uint8_t *p)
{
  return ((uint32_t)p[0] << 16) | ((uint32_t)p[1] << 8) | (uint32_t)p[2];
}

static inline uint32_t canfdi_uds_get_u32(const uint8_t *p)
{
  return ((uint32_t)p[0] << 24) | canfdi_uds_get_u24(p + 1);
}

/* A 32-bit two's complement pattern as a signed value. */
static inline int32_t canfdi_uds_get_s32(const uint8_t *p)
{
  const uint32_t b = canfdi_uds_get_u32(p);
  return (b <= (uint32_t)INT32_MAX) ? (int32_t)b : (-(int32_t)(~b)) - 1;
}

#endif /* CANFDI_UDS_MSG_H */
