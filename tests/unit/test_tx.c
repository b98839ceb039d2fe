/*
 * test_tx.c — the transmit side (firmware/comm/canfdi_tx.h).
 *
 * Two independent decoders read the frames back: the generated PLANT codec
 * (host_sim/gen/canfdi_sim_msg.h, which unpacks the actuator frames the
 * plant receives) with the E2E receiver, and, for every frame, a small
 * decoder driven by the text of dbc/canfdi.dbc itself (start bit, length,
 * byte order, sign), so that the frames the TESTER receives — for which no
 * C unpack is generated — are checked against the database too. Expected
 * raw values are computed from the DBC's exact scale/offset fractions in
 * 128-bit integers.
 */
#include <check.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gen/canfdi_sim_msg.h"
#include "comm/canfdi_e2e.h"
#include "comm/canfdi_tx.h"
#include "catalogue/canfdi_catalogue.h"
#include "comm/gen/canfdi_msg.h"
#include "comm/gen/canfdi_raw_limits.h"
#include "comm/gen/canfdi_sig_conv.h"
#include "unit_main.h"

__extension__ typedef __int128 i128;

/* Hot loops: plain checks (a passing ck_assert costs a system call). */
#define CHECK(cond, ...)                                                                         \
  do {                                                                                           \
    if (!(cond)) {                                                                               \
      ck_abort_msg(__VA_ARGS__);                                                                 \
    }                                                                                            \
  } while (0)

/* ------------------------------------------------------------------ */
/* A decoder from the DBC text                                          */
/* ------------------------------------------------------------------ */

typedef struct {
  char name[48];
  unsigned start;
  unsigned len;
  bool intel;
  bool is_signed;
} dbc_sig_t;

typedef struct {
  unsigned id;
  unsigned cycle_ms;
  unsigned n;
  dbc_sig_t sig[16];
} dbc_msg_t;

static dbc_msg_t dbc[40];
static unsigned n_dbc;

static void load_dbc(void)
{
  FILE *f;
  char line[1024];
  dbc_msg_t *cur = NULL;
  if (n_dbc > 0U) {
    return;
  }
  f = fopen("dbc/canfdi.dbc", "r");
  ck_assert_msg(f != NULL, "run from the repository root: dbc/canfdi.dbc not found");
  while (fgets(line, sizeof line, f) != NULL) {
    unsigned id;
    unsigned ms;
    char name[48];
    unsigned start;
    unsigned len;
    char order;
    char sign;
    if (sscanf(line, "BO_ %u %47[^:]:", &id, name) == 2) {
      ck_assert_uint_lt(n_dbc, 40U);
      cur = &dbc[n_dbc++];
      memset(cur, 0, sizeof *cur);
      cur->id = id;
    } else if ((cur != NULL) &&
               (sscanf(line, " SG_ %47s : %u|%u@%c%c", name, &start, &len, &order, &sign) == 5)) {
      dbc_sig_t *s = &cur->sig[cur->n++];
      ck_assert_uint_le(cur->n, 16U);
      strcpy(s->name, name);
      s->start = start;
      s->len = len;
      s->intel = (order == '1');
      s->is_signed = (sign == '-');
    } else if (sscanf(line, "BA_ \"GenMsgCycleTime\" BO_ %u %u;", &id, &ms) == 2) {
      for (unsigned k = 0U; k < n_dbc; k++) {
        if (dbc[k].id == id) {
          dbc[k].cycle_ms = ms;
        }
      }
    } else {
      /* other lines */
    }
  }
  fclose(f);
}

static const dbc_msg_t *dbc_msg(unsigned id)
{
  load_dbc();
  for (unsigned k = 0U; k < n_dbc; k++) {
    if (dbc[k].id == id) {
      return &dbc[k];
    }
  }
  ck_abort_msg("id 0x%x not in the DBC", id);
  return NULL;
}

/* Raw value of a signal: Intel bits counted from the LSB of byte 0;
 * Motorola from the start (most significant) bit, walking 7..0 of a byte,
 * then on to bit 7 of the next byte. */
static int64_t dbc_raw(const canfdi_tx_frame_t *fr, const char *signal)
{
  const dbc_msg_t *m = dbc_msg(fr->id);
  for (unsigned k = 0U; k < m->n; k++) {
    const dbc_sig_t *s = &m->sig[k];
    if (strcmp(s->name, signal) == 0) {
      uint64_t v = 0U;
      if (s->intel) {
        for (unsigned i = 0U; i < s->len; i++) {
          const unsigned bit = s->start + i;
          v |= (uint64_t)((fr->data[bit / 8U] >> (bit % 8U)) & 1U) << i;
        }
      } else {
        unsigned pos = s->start;
        for (unsigned i = 0U; i < s->len; i++) {
          v = (v << 1) | (uint64_t)(((unsigned)fr->data[pos / 8U] >> (pos % 8U)) & 1U);
          pos = ((pos % 8U) == 0U) ? pos + 15U : pos - 1U;
        }
      }
      if (s->is_signed && (s->len < 64U) && ((v >> (s->len - 1U)) & 1U)) {
        return (int64_t)v - ((int64_t)1 << s->len);
      }
      return (int64_t)v;
    }
  }
  ck_abort_msg("signal %s not in frame 0x%x", signal, fr->id);
  return 0;
}

/* ------------------------------------------------------------------ */
/* Numeric signals and their expected raw values                        */
/* ------------------------------------------------------------------ */

typedef struct {
  const char *name;
  int64_t sn, sd, on, od;
  int32_t min_q16, max_q16;
} conv_row_t;

#define CONV_ROW(id, lo, hi, sn, sd, on, od)                                                    \
  {#id, sn, sd, on, od, CANFDI_SIG_##id##_MIN_Q16, CANFDI_SIG_##id##_MAX_Q16},
static const conv_row_t conv_rows[] = {CANFDI_SIG_CONV_TABLE(CONV_ROW)};

static const conv_row_t *conv_row(const char *name)
{
  for (size_t k = 0U; k < sizeof conv_rows / sizeof conv_rows[0]; k++) {
    if (strcmp(conv_rows[k].name, name) == 0) {
      return &conv_rows[k];
    }
  }
  ck_abort_msg("%s not in CANFDI_SIG_CONV_TABLE", name);
  return NULL;
}

static i128 floor_div(i128 a, i128 b) /* b > 0 */
{
  i128 q = a / b;
  if (((a % b) != 0) && (a < 0)) {
    q--;
  }
  return q;
}

/* Raw values the encoder may send for v_q16: the exactly rounded (half up)
 * value, or its neighbour when the exact value lies within the documented
 * bound (|v| + 1) / 2^33 raw of a rounding tie; then the DBC range. */
static int64_t nearest_raw; /* the exactly rounded value of the last call */

static void expected_raw(const conv_row_t *c, int32_t v, int32_t raw_min, int32_t raw_max,
                         int64_t *lo, int64_t *hi)
{
  if (v < c->min_q16) {
    *lo = *hi = nearest_raw = raw_min;
  } else if (v > c->max_q16) {
    *lo = *hi = nearest_raw = raw_max;
  } else {
    /* exact raw = num / den */
    const i128 num = ((i128)v * c->od - (i128)c->on * 65536) * c->sd;
    const i128 den = (i128)65536 * c->od * c->sn;
    const i128 r = floor_div(2 * num + den, 2 * den);
    const i128 rem = (2 * num + den) - 2 * den * r; /* in [0, 2 den) */
    const i128 bound = (i128)(((v < 0) ? -(int64_t)v : v) + 1); /* / 2^33 raw */
    int64_t a = (int64_t)r;
    int64_t b = (int64_t)r;
    if (rem * ((i128)1 << 33) <= 2 * den * bound) {
      a = (int64_t)r - 1;
    }
    if ((2 * den - rem) * ((i128)1 << 33) <= 2 * den * bound) {
      b = (int64_t)r + 1;
    }
    nearest_raw = ((int64_t)r < raw_min) ? raw_min : (((int64_t)r > raw_max) ? raw_max : (int64_t)r);
    a = (a < raw_min) ? raw_min : ((a > raw_max) ? raw_max : a);
    b = (b < raw_min) ? raw_min : ((b > raw_max) ? raw_max : b);
    *lo = a;
    *hi = b;
  }
}

/* Every Q16.16 signal the ECU sends: DBC name, conversion, raw limits. */
typedef struct {
  const char *dbc_name;
  const char *conv_name;
  int32_t raw_min;
  int32_t raw_max;
  unsigned field; /* index for set_field() */
} tx_sig_t;

static const tx_sig_t tx_sigs[] = {
    {"DcmUaCmd", "DCM_ACTUATOR_DCM_UA_CMD", CANFDI_RAW_DCM_ACTUATOR_DCM_UA_CMD_MIN,
     CANFDI_RAW_DCM_ACTUATOR_DCM_UA_CMD_MAX, 0U},
    {"ThrUCmd", "THR_ACTUATOR_THR_UCMD", CANFDI_RAW_THR_ACTUATOR_THR_UCMD_MIN,
     CANFDI_RAW_THR_ACTUATOR_THR_UCMD_MAX, 1U},
    {"ResDcmR1", "ECU_RESIDUAL_DCM_RES_DCM_R1", CANFDI_RAW_ECU_RESIDUAL_DCM_RES_DCM_R1_MIN,
     CANFDI_RAW_ECU_RESIDUAL_DCM_RES_DCM_R1_MAX, 2U},
    {"ResDcmR2", "ECU_RESIDUAL_DCM_RES_DCM_R2", CANFDI_RAW_ECU_RESIDUAL_DCM_RES_DCM_R2_MIN,
     CANFDI_RAW_ECU_RESIDUAL_DCM_RES_DCM_R2_MAX, 3U},
    {"ResDcmR3", "ECU_RESIDUAL_DCM_RES_DCM_R3", CANFDI_RAW_ECU_RESIDUAL_DCM_RES_DCM_R3_MIN,
     CANFDI_RAW_ECU_RESIDUAL_DCM_RES_DCM_R3_MAX, 4U},
    {"ResDcmR4", "ECU_RESIDUAL_DCM_RES_DCM_R4", CANFDI_RAW_ECU_RESIDUAL_DCM_RES_DCM_R4_MIN,
     CANFDI_RAW_ECU_RESIDUAL_DCM_RES_DCM_R4_MAX, 5U},
    {"ResThrCorr", "ECU_RESIDUAL_THR_RES_THR_CORR", CANFDI_RAW_ECU_RESIDUAL_THR_RES_THR_CORR_MIN,
     CANFDI_RAW_ECU_RESIDUAL_THR_RES_THR_CORR_MAX, 6U},
    {"ResThrTps1", "ECU_RESIDUAL_THR_RES_THR_TPS1", CANFDI_RAW_ECU_RESIDUAL_THR_RES_THR_TPS1_MIN,
     CANFDI_RAW_ECU_RESIDUAL_THR_RES_THR_TPS1_MAX, 7U},
    {"ResThrTps2", "ECU_RESIDUAL_THR_RES_THR_TPS2", CANFDI_RAW_ECU_RESIDUAL_THR_RES_THR_TPS2_MIN,
     CANFDI_RAW_ECU_RESIDUAL_THR_RES_THR_TPS2_MAX, 8U},
    {"ResThrCurrent", "ECU_RESIDUAL_THR_RES_THR_CURRENT",
     CANFDI_RAW_ECU_RESIDUAL_THR_RES_THR_CURRENT_MIN, CANFDI_RAW_ECU_RESIDUAL_THR_RES_THR_CURRENT_MAX,
     9U},
    {"PrmDcmRa", "ECU_PARAM_DCM_PRM_DCM_RA", CANFDI_RAW_ECU_PARAM_DCM_PRM_DCM_RA_MIN,
     CANFDI_RAW_ECU_PARAM_DCM_PRM_DCM_RA_MAX, 10U},
    {"PrmDcmPsi", "ECU_PARAM_DCM_PRM_DCM_PSI", CANFDI_RAW_ECU_PARAM_DCM_PRM_DCM_PSI_MIN,
     CANFDI_RAW_ECU_PARAM_DCM_PRM_DCM_PSI_MAX, 11U},
    {"PrmDcmJ", "ECU_PARAM_DCM_PRM_DCM_J", CANFDI_RAW_ECU_PARAM_DCM_PRM_DCM_J_MIN,
     CANFDI_RAW_ECU_PARAM_DCM_PRM_DCM_J_MAX, 12U},
    {"PrmDcmMf1", "ECU_PARAM_DCM_PRM_DCM_MF1", CANFDI_RAW_ECU_PARAM_DCM_PRM_DCM_MF1_MIN,
     CANFDI_RAW_ECU_PARAM_DCM_PRM_DCM_MF1_MAX, 13U},
    {"PrmDcmMf0", "ECU_PARAM_DCM_PRM_DCM_MF0", CANFDI_RAW_ECU_PARAM_DCM_PRM_DCM_MF0_MIN,
     CANFDI_RAW_ECU_PARAM_DCM_PRM_DCM_MF0_MAX, 14U},
    {"PrmThrR", "ECU_PARAM_THR_PRM_THR_R", CANFDI_RAW_ECU_PARAM_THR_PRM_THR_R_MIN,
     CANFDI_RAW_ECU_PARAM_THR_PRM_THR_R_MAX, 15U},
    {"PrmThrSpringK", "ECU_PARAM_THR_PRM_THR_SPRING_K", CANFDI_RAW_ECU_PARAM_THR_PRM_THR_SPRING_K_MIN,
     CANFDI_RAW_ECU_PARAM_THR_PRM_THR_SPRING_K_MAX, 16U},
    {"PrmThrSpringPre", "ECU_PARAM_THR_PRM_THR_SPRING_PRE",
     CANFDI_RAW_ECU_PARAM_THR_PRM_THR_SPRING_PRE_MIN, CANFDI_RAW_ECU_PARAM_THR_PRM_THR_SPRING_PRE_MAX,
     17U},
    {"PrmThrFricC", "ECU_PARAM_THR_PRM_THR_FRIC_C", CANFDI_RAW_ECU_PARAM_THR_PRM_THR_FRIC_C_MIN,
     CANFDI_RAW_ECU_PARAM_THR_PRM_THR_FRIC_C_MAX, 18U},
    {"PrmThrFricV", "ECU_PARAM_THR_PRM_THR_FRIC_V", CANFDI_RAW_ECU_PARAM_THR_PRM_THR_FRIC_V_MIN,
     CANFDI_RAW_ECU_PARAM_THR_PRM_THR_FRIC_V_MAX, 19U},
};
#define N_TX_SIGS (sizeof tx_sigs / sizeof tx_sigs[0])

static canfdi_tx_t tx;

/* Encodes a frame in which only field `field` carries v (others 0). */
static void encode_field(unsigned field, int32_t v, canfdi_tx_frame_t *fr)
{
  int st = -1;
  if (field == 0U) {
    canfdi_tx_dcm_act_t a = {v, 1U, true};
    st = canfdi_tx_encode_dcm_act(&tx, &a, fr);
  } else if (field == 1U) {
    canfdi_tx_thr_act_t a = {v, true};
    st = canfdi_tx_encode_thr_act(&tx, &a, fr);
  } else if (field <= 5U) {
    canfdi_tx_res_dcm_t r;
    memset(&r, 0, sizeof r);
    r.r_q16[field - 2U] = v;
    st = canfdi_tx_encode_res_dcm(&tx, &r, fr);
  } else if (field <= 9U) {
    canfdi_tx_res_thr_t r;
    int32_t *p[4] = {&r.corr_q16, &r.tps1_q16, &r.tps2_q16, &r.current_q16};
    memset(&r, 0, sizeof r);
    *p[field - 6U] = v;
    st = canfdi_tx_encode_res_thr(&tx, &r, fr);
  } else if (field <= 14U) {
    canfdi_tx_param_dcm_t r;
    int32_t *p[5] = {&r.ra_q16, &r.psi_q16, &r.j_q16, &r.mf1_q16, &r.mf0_q16};
    memset(&r, 0, sizeof r);
    *p[field - 10U] = v;
    st = canfdi_tx_encode_prm_dcm(&tx, &r, fr);
  } else {
    canfdi_tx_param_thr_t r;
    int32_t *p[5] = {&r.r_q16, &r.spring_k_q16, &r.spring_pre_q16, &r.fric_c_q16, &r.fric_v_q16};
    memset(&r, 0, sizeof r);
    *p[field - 15U] = v;
    st = canfdi_tx_encode_prm_thr(&tx, &r, fr);
  }
  CHECK(st == CANFDI_OK, "encode field %u", field);
}

static uint64_t rng_state = 0xD1B54A32D192ED03ULL;
static uint32_t rnd(void)
{
  rng_state ^= rng_state << 13;
  rng_state ^= rng_state >> 7;
  rng_state ^= rng_state << 17;
  return (uint32_t)(rng_state >> 32);
}

/*
 * Every Q16.16 signal the ECU sends: random inputs over and beyond the DBC
 * range and inputs within +-2 Q16.16 LSB of every rounding tie of random
 * raw values; the decoded raw value must be the exactly rounded one (or its
 * neighbour only within the documented distance of a tie), saturated to
 * the DBC range, and every input outside [MIN_Q16, MAX_Q16] counted.
 */
START_TEST(q16_to_raw_exact_and_saturated)
{
  const tx_sig_t *t = &tx_sigs[_i];
  const conv_row_t *c = conv_row(t->conv_name);
  const int64_t span = (int64_t)c->max_q16 - c->min_q16;
  unsigned ties_seen = 0U;
  unsigned not_nearest = 0U;
  unsigned sat_expected = 0U;
  ck_assert_int_eq(canfdi_tx_init(&tx), CANFDI_OK);
  for (unsigned k = 0U; k < 40000U; k++) {
    int32_t v;
    canfdi_tx_frame_t fr;
    int64_t lo;
    int64_t hi;
    int64_t got;
    if (k < 2U) {
      v = (k == 0U) ? INT32_MIN : INT32_MAX;
    } else if ((k % 2U) == 0U) {
      /* uniform over the range plus a quarter on each side */
      const int64_t x = (int64_t)c->min_q16 - span / 4 + (int64_t)(rnd() % (uint32_t)(span * 3 / 2 + 1));
      v = (x > INT32_MAX) ? INT32_MAX : ((x < INT32_MIN) ? INT32_MIN : (int32_t)x);
    } else {
      /* near the tie between raw r and r + 1: (r + 1/2) * scale + offset */
      const int64_t r = t->raw_min + (int64_t)(rnd() % (uint32_t)(t->raw_max - t->raw_min + 1));
      const double tie = (((double)r + 0.5) * (double)c->sn / (double)c->sd +
                          (double)c->on / (double)c->od) * 65536.0;
      v = (int32_t)(tie + 0.5) + (int32_t)(rnd() % 5U) - 2;
    }
    if ((v < c->min_q16) || (v > c->max_q16)) {
      sat_expected++;
    }
    encode_field(t->field, v, &fr);
    expected_raw(c, v, t->raw_min, t->raw_max, &lo, &hi);
    got = dbc_raw(&fr, t->dbc_name);
    CHECK((got >= lo) && (got <= hi), "%s: v_q16 %d sent as raw %lld, expected %lld..%lld",
          t->dbc_name, v, (long long)got, (long long)lo, (long long)hi);
    if (lo != hi) {
      ties_seen++;
    }
    if (got != nearest_raw) {
      not_nearest++;
    }
  }
  ck_assert_uint_eq(tx.diag.saturations, sat_expected);
  ck_assert_uint_gt(sat_expected, 1000U);
  printf("tx %-15s 40000 inputs: %u within the tie bound, %u not the nearest raw value\n",
         t->dbc_name, ties_seen, not_nearest);
}
END_TEST

/* ------------------------------------------------------------------ */
/* Actuator frames with the generated decoder and E2E                   */
/* ------------------------------------------------------------------ */

START_TEST(actuator_frames_decode_with_generated_unpack_and_e2e)
{
  canfdi_e2e_rx_t rx_dcm;
  canfdi_e2e_rx_t rx_thr;
  canfdi_tx_data_t d;
  ck_assert_int_eq(canfdi_tx_init(&tx), CANFDI_OK);
  ck_assert_int_eq(canfdi_e2e_rx_init(&rx_dcm, 0x20U, 1U), CANFDI_OK);
  ck_assert_int_eq(canfdi_e2e_rx_init(&rx_thr, 0x21U, 1U), CANFDI_OK);
  memset(&d, 0, sizeof d);
  for (unsigned k = 0U; k < 1000U; k++) {
    canfdi_tx_frame_t out[CANFDI_TX_MAX_FRAMES_PER_STEP];
    int n;
    unsigned seen = 0U;
    d.dcm_act.ua_cmd_q16 = (int32_t)(rnd() % (140U * 65536U)) - 70 * 65536; /* +-70 V */
    d.dcm_act.bridge = (uint8_t)(rnd() % 3U);
    d.dcm_act.enable = (rnd() & 1U) != 0U;
    d.thr_act.u_cmd_q16 = (int32_t)(rnd() % (40U * 65536U)) - 20 * 65536; /* +-20 V */
    d.thr_act.enable = (rnd() & 1U) != 0U;
    n = canfdi_tx_step(&tx, &d, out);
    ck_assert_int_ge(n, 2);
    for (int j = 0; j < n; j++) {
      const canfdi_tx_frame_t *f = &out[j];
      int64_t lo;
      int64_t hi;
      if (f->id == 0x20U) {
        struct canfdi_sim_msg_dcm_actuator_t m;
        const int st = canfdi_e2e_check(&rx_dcm, f->data, f->dlc);
        CHECK(st == ((k == 0U) ? CANFDI_E2E_INITIAL : CANFDI_E2E_OK), "DcmActuator E2E %d", st);
        CHECK(canfdi_sim_msg_dcm_actuator_unpack(&m, f->data, f->dlc) == 0, "unpack");
        CHECK(m.dcm_bridge_sel == d.dcm_act.bridge, "bridge");
        CHECK(m.dcm_enable == (d.dcm_act.enable ? 1U : 0U), "enable");
        CHECK((int64_t)m.dcm_ua_cmd == dbc_raw(f, "DcmUaCmd"), "decoders disagree");
        expected_raw(conv_row("DCM_ACTUATOR_DCM_UA_CMD"), d.dcm_act.ua_cmd_q16,
                     CANFDI_RAW_DCM_ACTUATOR_DCM_UA_CMD_MIN, CANFDI_RAW_DCM_ACTUATOR_DCM_UA_CMD_MAX,
                     &lo, &hi);
        CHECK((m.dcm_ua_cmd >= lo) && (m.dcm_ua_cmd <= hi), "UaCmd %u", m.dcm_ua_cmd);
        /* physically: within half a DBC LSB of the command, or at +-60 V */
        {
          const double cmd = (double)d.dcm_act.ua_cmd_q16 / 65536.0;
          const double sent = (double)m.dcm_ua_cmd * 0.01 - 81.92;
          const double want = (cmd > 60.0) ? 60.0 : ((cmd < -60.0) ? -60.0 : cmd);
          CHECK((sent - want < 0.005 + 1e-9) && (want - sent < 0.005 + 1e-9), "%g sent as %g", cmd,
                sent);
        }
        seen |= 1U;
      } else if (f->id == 0x21U) {
        struct canfdi_sim_msg_thr_actuator_t m;
        const int st = canfdi_e2e_check(&rx_thr, f->data, f->dlc);
        CHECK(st == ((k == 0U) ? CANFDI_E2E_INITIAL : CANFDI_E2E_OK), "ThrActuator E2E %d", st);
        CHECK(canfdi_sim_msg_thr_actuator_unpack(&m, f->data, f->dlc) == 0, "unpack");
        CHECK(m.thr_enable == (d.thr_act.enable ? 1U : 0U), "enable");
        CHECK((int64_t)m.thr_u_cmd == dbc_raw(f, "ThrUCmd"), "decoders disagree");
        expected_raw(conv_row("THR_ACTUATOR_THR_UCMD"), d.thr_act.u_cmd_q16,
                     CANFDI_RAW_THR_ACTUATOR_THR_UCMD_MIN, CANFDI_RAW_THR_ACTUATOR_THR_UCMD_MAX, &lo,
                     &hi);
        CHECK((m.thr_u_cmd >= lo) && (m.thr_u_cmd <= hi), "UCmd %u", m.thr_u_cmd);
        seen |= 2U;
      } else {
        /* slow frames: see the schedule test */
      }
    }
    CHECK(seen == 3U, "both actuator frames every step (step %u)", k);
  }
  ck_assert_uint_eq(rx_dcm.diag.status[CANFDI_E2E_OK], 999U);
  ck_assert_uint_eq(rx_thr.diag.status[CANFDI_E2E_OK], 999U);
  ck_assert_uint_eq(tx.diag.frames[CANFDI_TX_F_DCM_ACT], 1000U);
}
END_TEST

/* An unknown bridge is never driven: none, and disabled. */
START_TEST(unknown_bridge_is_sent_as_none_disabled)
{
  canfdi_tx_frame_t fr;
  canfdi_tx_dcm_act_t a = {10 * 65536, 3U, true};
  struct canfdi_sim_msg_dcm_actuator_t m;
  ck_assert_int_eq(canfdi_tx_init(&tx), CANFDI_OK);
  ck_assert_int_eq(canfdi_tx_encode_dcm_act(&tx, &a, &fr), CANFDI_OK);
  ck_assert_int_eq(canfdi_sim_msg_dcm_actuator_unpack(&m, fr.data, fr.dlc), 0);
  ck_assert_uint_eq(m.dcm_bridge_sel, 0U);
  ck_assert_uint_eq(m.dcm_enable, 0U);
  ck_assert_uint_eq(tx.diag.invalid_enums, 1U);
  a.bridge = 2U;
  ck_assert_int_eq(canfdi_tx_encode_dcm_act(&tx, &a, &fr), CANFDI_OK);
  ck_assert_int_eq(canfdi_sim_msg_dcm_actuator_unpack(&m, fr.data, fr.dlc), 0);
  ck_assert_uint_eq(m.dcm_bridge_sel, 2U);
  ck_assert_uint_eq(m.dcm_enable, 1U);
  ck_assert_uint_eq(tx.diag.invalid_enums, 1U);
}
END_TEST

/* ------------------------------------------------------------------ */
/* Schedule                                                            */
/* ------------------------------------------------------------------ */

/*
 * Over 10 s: every frame goes out exactly with its DBC cycle time, first at
 * its documented phase; canfdi_tx_due() announces exactly what step sends;
 * never more than CANFDI_TX_MAX_FRAMES_PER_STEP, even with a DTC event
 * queued every step.
 */
START_TEST(schedule_follows_the_dbc_cycle_times)
{
  static const uint32_t ids[CANFDI_TX_F_COUNT] = {0x20U,  0x21U,  0x200U, 0x201U, 0x300U,
                                                  0x301U, 0x302U, 0x310U, 0x320U, 0x321U};
  static const unsigned phase[CANFDI_TX_F_COUNT] = {0U,  0U,  2U,  7U,  3U,
                                                    23U, 13U, 43U, 63U, 83U};
  unsigned count[CANFDI_TX_F_COUNT] = {0};
  unsigned events = 0U;
  unsigned most = 0U;
  canfdi_tx_data_t d;
  memset(&d, 0, sizeof d);
  ck_assert_int_eq(canfdi_tx_init(&tx), CANFDI_OK);
  for (unsigned k = 0U; k < 10000U; k++) {
    canfdi_tx_frame_t out[CANFDI_TX_MAX_FRAMES_PER_STEP];
    canfdi_tx_dtc_t ev = {CANFDI_DTC_U1A00, 0x09U, 1U, 0U, 1U};
    uint32_t due;
    uint32_t sent = 0U;
    int n;
    if ((k % 3U) == 0U) {
      (void)canfdi_tx_dtc_event(&tx, &ev); /* may be full */
    }
    due = canfdi_tx_due(&tx);
    n = canfdi_tx_step(&tx, &d, out);
    CHECK((n >= 2) && ((unsigned)n <= CANFDI_TX_MAX_FRAMES_PER_STEP), "step %u: %d frames", k, n);
    most = ((unsigned)n > most) ? (unsigned)n : most;
    for (int j = 0; j < n; j++) {
      bool found = false;
      CHECK(out[j].dlc == 8U, "dlc");
      if (j > 0) {
        CHECK((out[j].id > out[j - 1].id) || (out[j].id == 0x310U), "order");
      }
      for (unsigned f = 0U; f < CANFDI_TX_F_COUNT; f++) {
        if (out[j].id == ids[f]) {
          const dbc_msg_t *m = dbc_msg(ids[f]);
          const unsigned period = m->cycle_ms; /* steps of 1 ms */
          found = true;
          if ((f == CANFDI_TX_F_DTC) && (dbc_raw(&out[j], "DtcTxReason") == 1)) {
            events++;
            sent |= UINT32_C(1) << CANFDI_TX_F_DTC_EVENT;
            continue;
          }
          CHECK(period > 0U, "0x%x has a cycle time", ids[f]);
          CHECK((k % period) == (phase[f] % period), "0x%x at step %u (period %u)", ids[f], k,
                period);
          count[f]++;
          sent |= UINT32_C(1) << f;
        }
      }
      CHECK(found, "unexpected id 0x%x", out[j].id);
    }
    CHECK(sent == due, "step %u: due %x, sent %x", k, due, sent);
  }
  for (unsigned f = 0U; f < CANFDI_TX_F_COUNT; f++) {
    ck_assert_uint_eq(count[f], 10000U / dbc_msg(ids[f])->cycle_ms);
  }
  ck_assert_uint_eq(events, tx.diag.dtc_events);
  ck_assert_uint_eq(events, 3334U);
  ck_assert_uint_eq(most, CANFDI_TX_MAX_FRAMES_PER_STEP);
  ck_assert_uint_eq(tx.diag.steps, 10000U);
}
END_TEST

/* E2E over the schedule: every frame of the protected identifiers (the
 * actuators, EcuStatus, EcuDiagnosis, EcuDtc — cyclic and on-change
 * sharing one counter) passes an E2E receiver with max_delta 1 (INITIAL,
 * then OK: no counter skipped or repeated, right CRC over its own data
 * ID). The engineering
 * frames are not protected: byte 0 is their payload. */
START_TEST(ecu_frames_are_e2e_protected)
{
  static const uint32_t prot[5] = {0x020U, 0x021U, 0x300U, 0x301U, 0x310U};
  canfdi_e2e_rx_t rx[5];
  unsigned seen[5] = {0};
  canfdi_tx_data_t d;
  memset(&d, 0, sizeof d);
  ck_assert_int_eq(canfdi_tx_init(&tx), CANFDI_OK);
  for (unsigned i = 0U; i < 5U; i++) {
    ck_assert_int_eq(canfdi_e2e_rx_init(&rx[i], (uint16_t)prot[i], 1U), CANFDI_OK);
  }
  d.status.active_dtc_count = 3U;
  d.diagnosis.dcm_fault_id = 1U;
  d.diagnosis.dcm_confidence_pct = 87U;
  d.dtc.dtc = CANFDI_DTC_P1A10;
  d.dtc.count = 1U;
  for (unsigned k = 0U; k < 3000U; k++) {
    canfdi_tx_frame_t out[CANFDI_TX_MAX_FRAMES_PER_STEP];
    const canfdi_tx_dtc_t ev = {CANFDI_DTC_U1A51, (uint8_t)(k & 0xFFU), 1U, 0U, 1U};
    int n;
    if ((k % 7U) == 0U) {
      (void)canfdi_tx_dtc_event(&tx, &ev);
    }
    d.status.deadline_misses = k;
    n = canfdi_tx_step(&tx, &d, out);
    for (int j = 0; j < n; j++) {
      bool is_prot = false;
      for (unsigned i = 0U; i < 5U; i++) {
        if (out[j].id == prot[i]) {
          const int st = canfdi_e2e_check(&rx[i], out[j].data, out[j].dlc);
          CHECK(st == ((seen[i] == 0U) ? CANFDI_E2E_INITIAL : CANFDI_E2E_OK), "0x%x frame %u: E2E %d",
                prot[i], seen[i], st);
          seen[i]++;
          is_prot = true;
        }
      }
      if (!is_prot) {
        CHECK((out[j].id == 0x200U) || (out[j].id == 0x201U) || (out[j].id == 0x302U) ||
                  (out[j].id == 0x320U) || (out[j].id == 0x321U),
              "unexpected id 0x%x", out[j].id);
      }
    }
  }
  ck_assert_uint_eq(seen[0], 3000U);
  ck_assert_uint_eq(seen[2], 30U);
  ck_assert_uint_eq(seen[3], 30U);
  ck_assert_uint_eq(seen[4], 30U + tx.diag.dtc_events); /* cyclic + on change, one counter */
  ck_assert_uint_gt(tx.diag.dtc_events, 400U);
  for (unsigned i = 0U; i < 5U; i++) {
    ck_assert_uint_eq(rx[i].diag.status[CANFDI_E2E_OK], seen[i] - 1U);
  }
}
END_TEST

/* On-change DTC frames: in order, one per step, reason "change"; a full
 * queue drops and counts. */
START_TEST(dtc_events_queue_in_order)
{
  canfdi_tx_data_t d;
  canfdi_tx_frame_t out[CANFDI_TX_MAX_FRAMES_PER_STEP];
  unsigned got = 0U;
  memset(&d, 0, sizeof d);
  ck_assert_int_eq(canfdi_tx_init(&tx), CANFDI_OK);
  ck_assert_uint_eq(canfdi_tx_due(&tx) & (UINT32_C(1) << CANFDI_TX_F_DTC_EVENT), 0U);
  for (unsigned q = 0U; q < CANFDI_CFG_TX_DTC_QUEUE + 2U; q++) {
    const canfdi_tx_dtc_t ev = {canfdi_catalogue_dtc[q], (uint8_t)q, 0U, (uint8_t)q, 9U};
    ck_assert_int_eq(canfdi_tx_dtc_event(&tx, &ev),
                     (q < CANFDI_CFG_TX_DTC_QUEUE) ? CANFDI_OK : -CANFDI_ERANGE);
  }
  ck_assert_uint_eq(tx.diag.dtc_events_dropped, 2U);
  ck_assert_uint_ne(canfdi_tx_due(&tx) & (UINT32_C(1) << CANFDI_TX_F_DTC_EVENT), 0U);
  for (unsigned k = 0U; k < 20U; k++) {
    const int n = canfdi_tx_step(&tx, &d, out);
    unsigned this_step = 0U;
    for (int j = 0; j < n; j++) {
      if ((out[j].id == 0x310U) && (dbc_raw(&out[j], "DtcTxReason") == 1)) {
        ck_assert_int_eq(dbc_raw(&out[j], "DtcCode"), (int64_t)canfdi_catalogue_dtc[got]);
        ck_assert_int_eq(dbc_raw(&out[j], "DtcIndex"), (int64_t)got);
        ck_assert_int_eq(j, n - 1); /* after the cyclic frames */
        got++;
        this_step++;
      }
    }
    ck_assert_uint_eq(this_step, (k < CANFDI_CFG_TX_DTC_QUEUE) ? 1U : 0U);
  }
  ck_assert_uint_eq(got, CANFDI_CFG_TX_DTC_QUEUE);
}
END_TEST

/* ------------------------------------------------------------------ */
/* Integer frames                                                      */
/* ------------------------------------------------------------------ */

/* EcuDtc as dbc/README.md states it: the E2E CRC in byte 0 and counter in
 * the low nibble of byte 1, the reason, index and count in bits 12..23,
 * the 3-byte DTC big-endian in bytes 3..5 (P0122 -> 01 22 00), byte 6
 * exactly the UDS status byte, byte 7 the occurrence counter. */
START_TEST(dtc_frame_layout_is_uds)
{
  canfdi_tx_frame_t fr;
  const canfdi_tx_dtc_t rec = {CANFDI_DTC_P0122, 0xA5U, 7U, 2U, 3U};
  canfdi_tx_dtc_t big = rec;
  ck_assert_int_eq(canfdi_tx_init(&tx), CANFDI_OK);
  ck_assert_int_eq(canfdi_tx_encode_dtc(&tx, &rec, true, &fr), CANFDI_OK);
  ck_assert_uint_eq(fr.id, 0x310U);
  ck_assert_uint_eq(fr.data[0], canfdi_e2e_frame_crc(0x310U, fr.data, 8U));
  ck_assert_uint_eq(fr.data[1] & 0x0FU, 0U); /* the first frame's counter */
  ck_assert_uint_eq(fr.data[3], 0x01U);
  ck_assert_uint_eq(fr.data[4], 0x22U);
  ck_assert_uint_eq(fr.data[5], 0x00U);
  ck_assert_uint_eq(fr.data[6], 0xA5U);
  ck_assert_uint_eq(fr.data[7], 7U);
  ck_assert_int_eq(dbc_raw(&fr, "DtcIndex"), 2);
  ck_assert_int_eq(dbc_raw(&fr, "DtcCount"), 3);
  ck_assert_int_eq(dbc_raw(&fr, "DtcTxReason"), 1);
  ck_assert_int_eq(dbc_raw(&fr, "DtcStsConfirmed"), 0);   /* bit 3 of 0xA5 */
  ck_assert_int_eq(dbc_raw(&fr, "DtcStsWarningIndicator"), 1);
  ck_assert_int_eq(dbc_raw(&fr, "DtcCode"), (int64_t)CANFDI_DTC_P0122);
  big.dtc = 0x12345678UL;
  big.index = 40U; /* index and count saturate at their narrower fields */
  big.count = 70U;
  ck_assert_int_eq(canfdi_tx_encode_dtc(&tx, &big, false, &fr), CANFDI_OK);
  ck_assert_int_eq(dbc_raw(&fr, "DtcCode"), 0xFFFFFF);
  ck_assert_int_eq(dbc_raw(&fr, "DtcTxReason"), 0);
  ck_assert_int_eq(dbc_raw(&fr, "DtcIndex"), 31);
  ck_assert_int_eq(dbc_raw(&fr, "DtcCount"), 63);
  ck_assert_int_eq(dbc_raw(&fr, "EcuDtcCounter"), 1);
  ck_assert_uint_eq(fr.data[0], canfdi_e2e_frame_crc(0x310U, fr.data, 8U));
  ck_assert_uint_eq(tx.diag.saturations, 3U);
}
END_TEST

START_TEST(status_and_diagnosis_saturate)
{
  canfdi_tx_frame_t fr;
  canfdi_tx_status_t st = {1U, 2U, 2U, true, 300U, 70000U, 5000U, 4095U};
  canfdi_tx_diagnosis_t dg = {4U, 21U, 30U, 99U, 100U, 250U};
  ck_assert_int_eq(canfdi_tx_init(&tx), CANFDI_OK);
  for (unsigned k = 0U; k < 20U; k++) {
    ck_assert_int_eq(canfdi_tx_encode_status(&tx, &st, &fr), CANFDI_OK);
    /* the E2E counter is the alive counter */
    ck_assert_int_eq(dbc_raw(&fr, "EcuStatusCounter"), (int64_t)(k % 16U));
    ck_assert_int_eq(dbc_raw(&fr, "EcuStatusCrc"), canfdi_e2e_frame_crc(0x300U, fr.data, 8U));
  }
  ck_assert_int_eq(dbc_raw(&fr, "StsDegStateDcm"), 1);
  ck_assert_int_eq(dbc_raw(&fr, "StsDegStateThr"), 2);
  ck_assert_int_eq(dbc_raw(&fr, "StsActiveBridge"), 2);
  ck_assert_int_eq(dbc_raw(&fr, "StsThrLimpHome"), 1);
  ck_assert_int_eq(dbc_raw(&fr, "StsActiveDtcCount"), 63);
  ck_assert_int_eq(dbc_raw(&fr, "StsDeadlineMisses"), 65535);
  ck_assert_int_eq(dbc_raw(&fr, "StsStepTimeMax"), 2047); /* 4094 us */
  ck_assert_int_eq(dbc_raw(&fr, "StsCycleTimeMax"), 2047); /* 4095 us: 2048 units, saturated */
  ck_assert_uint_eq(tx.diag.saturations, 4U * 20U);
  /* the times in 2 us units, rounded up (a maximum is never under-reported) */
  st.step_time_max_us = 1001U;
  st.cycle_time_max_us = 1000U;
  ck_assert_int_eq(canfdi_tx_encode_status(&tx, &st, &fr), CANFDI_OK);
  ck_assert_int_eq(dbc_raw(&fr, "StsStepTimeMax"), 501);
  ck_assert_int_eq(dbc_raw(&fr, "StsCycleTimeMax"), 500);
  st.step_time_max_us = UINT32_MAX; /* no wrap on the way to the units */
  st.cycle_time_max_us = 0U;
  ck_assert_int_eq(canfdi_tx_encode_status(&tx, &st, &fr), CANFDI_OK);
  ck_assert_int_eq(dbc_raw(&fr, "StsStepTimeMax"), 2047);
  ck_assert_int_eq(dbc_raw(&fr, "StsCycleTimeMax"), 0);
  st.step_time_max_us = 5000U;
  st.cycle_time_max_us = 4095U;
  st.deg_state_dcm = 9U; /* enumerations saturate to their top value */
  st.active_bridge = 7U;
  ck_assert_int_eq(canfdi_tx_encode_status(&tx, &st, &fr), CANFDI_OK);
  ck_assert_int_eq(dbc_raw(&fr, "StsDegStateDcm"), 3);
  ck_assert_int_eq(dbc_raw(&fr, "StsActiveBridge"), 2);
  ck_assert_int_eq(canfdi_tx_encode_diagnosis(&tx, &dg, &fr), CANFDI_OK);
  ck_assert_uint_eq(fr.id, 0x301U);
  ck_assert_int_eq(dbc_raw(&fr, "EcuDiagnosisCounter"), 0);
  ck_assert_int_eq(dbc_raw(&fr, "EcuDiagnosisCrc"), canfdi_e2e_frame_crc(0x301U, fr.data, 8U));
  ck_assert_int_eq(dbc_raw(&fr, "DiagDcmFaultId"), 4);
  ck_assert_int_eq(dbc_raw(&fr, "DiagThrFaultId"), 21);
  ck_assert_int_eq(dbc_raw(&fr, "DiagComFaultId"), 30);
  ck_assert_int_eq(dbc_raw(&fr, "DiagDcmConfidence"), 99);
  ck_assert_int_eq(dbc_raw(&fr, "DiagThrConfidence"), 100);
  ck_assert_int_eq(dbc_raw(&fr, "DiagComConfidence"), 100);
}
END_TEST

/* Parameter frames: the defaults of the literature come out within half a
 * DBC step (or the Q16.16 resolution, where that is coarser); valid flags. */
START_TEST(parameter_frames_carry_the_estimates)
{
  canfdi_tx_frame_t fr;
  const canfdi_tx_param_dcm_t p = {99615, 21627, 126, 24, 7209, true}; /* 1.52, .33, 1.92e-3, .36e-3, .11 */
  const canfdi_tx_param_thr_t q = {98304, 5702, 25952, 18612, 577, false};
  ck_assert_int_eq(canfdi_tx_init(&tx), CANFDI_OK);
  ck_assert_int_eq(canfdi_tx_encode_prm_dcm(&tx, &p, &fr), CANFDI_OK);
  ck_assert_uint_eq(fr.id, 0x320U);
  ck_assert_int_eq(dbc_raw(&fr, "PrmDcmRa"), 1520);   /* 99615 / 65536 = 1.52000 */
  ck_assert_int_eq(dbc_raw(&fr, "PrmDcmPsi"), 1650);  /* 0.330002 / 0.0002 */
  ck_assert_int_eq(dbc_raw(&fr, "PrmDcmJ"), 961);     /* 126 LSB = 1.9226e-3 */
  ck_assert_int_eq(dbc_raw(&fr, "PrmDcmMf1"), 183);   /* 24 LSB = 3.662e-4 */
  ck_assert_int_eq(dbc_raw(&fr, "PrmDcmMf0"), 1100);
  ck_assert_int_eq(dbc_raw(&fr, "PrmDcmValid"), 1);
  ck_assert_int_eq(canfdi_tx_encode_prm_thr(&tx, &q, &fr), CANFDI_OK);
  ck_assert_uint_eq(fr.id, 0x321U);
  ck_assert_int_eq(dbc_raw(&fr, "PrmThrR"), 1500);
  ck_assert_int_eq(dbc_raw(&fr, "PrmThrSpringK"), 870);
  ck_assert_int_eq(dbc_raw(&fr, "PrmThrSpringPre"), 1980);
  ck_assert_int_eq(dbc_raw(&fr, "PrmThrFricC"), 1420);
  ck_assert_int_eq(dbc_raw(&fr, "PrmThrFricV"), 880);
  ck_assert_int_eq(dbc_raw(&fr, "PrmThrValid"), 0);
  ck_assert_uint_eq(tx.diag.saturations, 0U);
}
END_TEST

START_TEST(bad_arguments_are_rejected)
{
  canfdi_tx_frame_t fr;
  canfdi_tx_frame_t out[CANFDI_TX_MAX_FRAMES_PER_STEP];
  canfdi_tx_data_t d;
  canfdi_tx_t fresh;
  memset(&d, 0, sizeof d);
  memset(&fresh, 0, sizeof fresh);
  ck_assert_int_eq(canfdi_tx_init(NULL), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_tx_step(&fresh, &d, out), -CANFDI_EINVAL);
  ck_assert_uint_eq(canfdi_tx_due(&fresh), 0U);
  ck_assert_uint_eq(canfdi_tx_due(NULL), 0U);
  ck_assert_int_eq(canfdi_tx_init(&tx), CANFDI_OK);
  ck_assert_int_eq(canfdi_tx_step(&tx, NULL, out), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_tx_step(&tx, &d, NULL), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_tx_encode_dcm_act(&tx, NULL, &fr), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_tx_encode_thr_act(&tx, &d.thr_act, NULL), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_tx_encode_res_dcm(NULL, &d.res_dcm, &fr), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_tx_encode_status(&fresh, &d.status, &fr), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_tx_dtc_event(&tx, NULL), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_tx_dtc_event(NULL, &d.dtc), -CANFDI_EINVAL);
  ck_assert_uint_eq(tx.diag.bad_args, 5U);
  ck_assert_uint_eq(tx.diag.steps, 0U);
  /* encoders on their own do not touch the schedule */
  ck_assert_int_eq(canfdi_tx_encode_res_thr(&tx, &d.res_thr, &fr), CANFDI_OK);
  ck_assert_uint_eq(canfdi_tx_due(&tx), 3U); /* the actuators at step 0 */
}
END_TEST

static Suite *make_suite(void)
{
  Suite *s = suite_create("tx");
  TCase *tc = tcase_create("conversion");
  tcase_add_loop_test(tc, q16_to_raw_exact_and_saturated, 0, (int)N_TX_SIGS);
  suite_add_tcase(s, tc);

  tc = tcase_create("frames");
  tcase_add_test(tc, actuator_frames_decode_with_generated_unpack_and_e2e);
  tcase_add_test(tc, unknown_bridge_is_sent_as_none_disabled);
  tcase_add_test(tc, dtc_frame_layout_is_uds);
  tcase_add_test(tc, status_and_diagnosis_saturate);
  tcase_add_test(tc, parameter_frames_carry_the_estimates);
  tcase_add_test(tc, bad_arguments_are_rejected);
  suite_add_tcase(s, tc);

  tc = tcase_create("schedule");
  tcase_add_test(tc, schedule_follows_the_dbc_cycle_times);
  tcase_add_test(tc, dtc_events_queue_in_order);
  tcase_add_test(tc, ecu_frames_are_e2e_protected);
  suite_add_tcase(s, tc);
  return s;
}

CANFDI_UNIT_MAIN(make_suite)
