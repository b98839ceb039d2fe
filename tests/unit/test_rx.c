/*
 * test_rx.c — input supervision (firmware/comm/canfdi_rx.h).
 *
 * Test frames are built the way the plant builds them: the PLANT codec
 * generated from the same DBC (host_sim/gen/canfdi_sim_msg.h) and
 * canfdi_e2e_protect, or by the simulator's frame builder itself
 * (host_sim/canfdi_sim_frames.h). Expected physical values come from the
 * DBC's exact scale and offset fractions (CANFDI_SIG_CONV_TABLE) in 128-bit
 * integer or double arithmetic, never from the module's own constants.
 */
#include <check.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "canfdi_sim_frames.h"
#include "gen/canfdi_sim_msg.h"
#include "comm/canfdi_e2e.h"
#include "comm/canfdi_rx.h"
#include "catalogue/canfdi_catalogue.h"
#include "comm/gen/canfdi_msg.h"
#include "comm/gen/canfdi_raw_limits.h"
#include "comm/gen/canfdi_sig_conv.h"
#include "unit_main.h"

#define STEP_US 1000U

/* In hot loops: libcheck's ck_assert records every passing assertion
 * through a pipe (a system call each), which would dominate the run time
 * of the exhaustive and flood tests. */
#define CHECK(cond, ...)                                                                         \
  do {                                                                                           \
    if (!(cond)) {                                                                               \
      ck_abort_msg(__VA_ARGS__);                                                                 \
    }                                                                                            \
  } while (0)

/* Exact rational reference arithmetic (GCC/Clang extension). */
__extension__ typedef __int128 i128;

/* ------------------------------------------------------------------ */
/* Exact reference conversions                                         */
/* ------------------------------------------------------------------ */

typedef struct {
  const char *name;
  int64_t type_lo, type_hi, sn, sd, on, od;
  int64_t scale_q32, offset_q32;
} sig_t;

#define SIG_ROW(id, lo, hi, sn, sd, on, od)                                                     \
  {#id, lo, hi, sn, sd, on, od, CANFDI_SIG_##id##_SCALE_Q32, CANFDI_SIG_##id##_OFFSET_Q32},
static const sig_t all_sigs[] = {CANFDI_SIG_CONV_TABLE(SIG_ROW)};
#define N_SIGS (sizeof all_sigs / sizeof all_sigs[0])

/* Physical value of raw for the signal's DBC fractions, in double. */
static double phys(int64_t raw, int64_t sn, int64_t sd, int64_t on, int64_t od)
{
  return ((double)raw * (double)sn / (double)sd) + ((double)on / (double)od);
}

/* Q16.16 LSB in double. */
#define LSB (1.0 / 65536.0)

/* The inputs' signals in the table, in CANFDI_RX_IN_* order. */
static const char *const input_sig[CANFDI_RX_IN_COUNT] = {
    "DCM_SENSOR_DCM_UA",   "DCM_SENSOR_DCM_IA",   "DCM_SENSOR_DCM_OMEGA", "DCM_SENSOR_DCM_USUPPLY",
    "THR_SENSOR_THR_TPS1", "THR_SENSOR_THR_TPS2", "THR_SENSOR_THR_IMOT",  "THR_SENSOR_THR_USUPPLY",
    "SETPOINT_DCM_SP_DCM_SPEED", "SETPOINT_DCM_SP_DCM_LOAD", "SETPOINT_THR_SP_THR_ANGLE"};

static const sig_t *find_sig(const char *name)
{
  for (size_t k = 0U; k < N_SIGS; k++) {
    if (strcmp(all_sigs[k].name, name) == 0) {
      return &all_sigs[k];
    }
  }
  ck_abort_msg("signal %s not in CANFDI_SIG_CONV_TABLE", name);
  return NULL;
}

/* Expected SI value of input i for raw: the angle setpoint in radians. */
static double input_phys(unsigned i, int64_t raw)
{
  const sig_t *s = find_sig(input_sig[i]);
  double v = phys(raw, s->sn, s->sd, s->on, s->od);
  if (i == CANFDI_RX_IN_SP_THR_ANGLE) {
    v *= 3.14159265358979323846 / 180.0;
  }
  return v;
}

/* ------------------------------------------------------------------ */
/* Conversion                                                          */
/* ------------------------------------------------------------------ */

/*
 * Every signal with a raw value of up to 31 bits, over its whole raw type
 * range: |got - exact| must stay within the documented bound
 * 1/2 + (|raw| + 1) / 2^17 Q16.16 LSB, checked in exact 128-bit rational
 * arithmetic; results outside int32_t saturate. Every signal of up to 16
 * bits (all that the ECU receives) must be within 1 LSB; the 24-bit ones
 * (DtcCode, exact at scale 1; PstSimTime) only within the bound.
 * canfdi_rx_raw_to_q16 takes |scale| <= 1 by contract (it clamps): the
 * signals with a coarser step, EcuStatus's times in 2 us units, are ones
 * the ECU only sends (canfdi_tx converts them in integers) and are left
 * out; the test checks that they are the ECU's own (ECU_*) frames.
 */
START_TEST(conv_every_signal_whole_raw_range)
{
  size_t checked = 0U;
  size_t not_nearest = 0U;
  double worst = 0.0;
  for (size_t k = 0U; k < N_SIGS; k++) {
    const sig_t *s = &all_sigs[k];
    if (s->type_hi > INT32_MAX) {
      continue;
    }
    if (s->sn > s->sd) {
      CHECK(strncmp(s->name, "ECU_", 4U) == 0, "%s: scale %lld/%lld > 1 in a frame the ECU receives",
            s->name, (long long)s->sn, (long long)s->sd);
      continue;
    }
    for (int64_t raw = s->type_lo; raw <= s->type_hi; raw++) {
      /* exact value * 2^16 = num / den */
      const i128 num = ((i128)raw * s->sn * s->od + (i128)s->on * s->sd) * 65536;
      const i128 den = (i128)s->sd * s->od;
      const int32_t got = canfdi_rx_raw_to_q16((int32_t)raw, s->scale_q32, s->offset_q32);
      const i128 araw = (raw < 0) ? -raw : raw;
      i128 err; /* (got - exact) * den */
      if (num > (i128)INT32_MAX * den) {
        CHECK(got == INT32_MAX, "%s raw %lld: no saturation", s->name, (long long)raw);
        continue;
      }
      if (num < (i128)INT32_MIN * den) {
        CHECK(got == INT32_MIN, "%s raw %lld: no saturation", s->name, (long long)raw);
        continue;
      }
      err = (i128)got * den - num;
      if (err < 0) {
        err = -err;
      }
      /* |err| / den <= 1/2 + (|raw| + 1) / 2^17 */
      CHECK(err * 131072 <= den * (65536 + araw + 1), "%s raw %lld: q16 %d off by %g LSB",
                    s->name, (long long)raw, got, (double)err / (double)den);
      if ((s->type_hi - s->type_lo <= 65535) && (err * 2 > den)) {
        not_nearest++;
      }
      if ((s->type_hi - s->type_lo <= 65535) && ((double)err / (double)den > worst)) {
        worst = (double)err / (double)den;
      }
      checked++;
    }
  }
  ck_assert_uint_gt(checked, 100000U);
  ck_assert(worst < 1.0); /* every signal of up to 16 bits within 1 LSB */
  printf("conv: %zu raw values of %zu signals, up to 16 bits: worst %.4f LSB, %zu not nearest\n", checked,
         (size_t)N_SIGS, worst, not_nearest);
}
END_TEST

/* The angle setpoint in radians (the _RAD_ constants) over its raw range,
 * against double: within 1 LSB (bound 0.5 + 65536/2^17 = 1.0 LSB). */
START_TEST(conv_angle_in_radians)
{
  double worst = 0.0;
  for (int32_t raw = 0; raw <= 65535; raw++) {
    const double exact = input_phys(CANFDI_RX_IN_SP_THR_ANGLE, raw) * 65536.0;
    const int32_t got = canfdi_rx_raw_to_q16(raw, CANFDI_SIG_SETPOINT_THR_SP_THR_ANGLE_RAD_SCALE_Q32,
                                             CANFDI_SIG_SETPOINT_THR_SP_THR_ANGLE_RAD_OFFSET_Q32);
    const double e = fabs((double)got - exact);
    ck_assert_msg(e < 1.0, "raw %d: %d vs %f", raw, got, exact);
    worst = (e > worst) ? e : worst;
  }
  /* 90 deg = pi/2 rad within one LSB */
  ck_assert_int_le(abs(canfdi_rx_raw_to_q16(45000, CANFDI_SIG_SETPOINT_THR_SP_THR_ANGLE_RAD_SCALE_Q32,
                                            0) -
                       102944),
                   1);
  printf("conv: angle rad worst %.4f LSB\n", worst);
}
END_TEST

/* Arguments far outside the generated constants: defined, saturated results
 * (UBSan would abort on an overflow). */
START_TEST(conv_saturates_without_ub)
{
  const int64_t big = INT64_C(1) << 40;
  ck_assert_int_eq(canfdi_rx_raw_to_q16(INT32_MAX, big, 0), INT32_MAX);
  ck_assert_int_eq(canfdi_rx_raw_to_q16(INT32_MIN, big, 0), INT32_MIN);
  ck_assert_int_eq(canfdi_rx_raw_to_q16(INT32_MIN, -big, 0), INT32_MAX);
  ck_assert_int_eq(canfdi_rx_raw_to_q16(INT32_MAX, INT64_MAX, INT64_MAX), INT32_MAX);
  ck_assert_int_eq(canfdi_rx_raw_to_q16(INT32_MIN, INT64_MAX, INT64_MIN), INT32_MIN);
  ck_assert_int_eq(canfdi_rx_raw_to_q16(0, 0, INT64_MIN), INT32_MIN);
  /* scale 1.0, raw 3 -> 3.0; half-up rounding of -0.5 LSB gives 0 */
  ck_assert_int_eq(canfdi_rx_raw_to_q16(3, INT64_C(1) << 32, 0), 3 * 65536);
  ck_assert_int_eq(canfdi_rx_raw_to_q16(0, 0, -(INT64_C(1) << 15)), 0);
  ck_assert_int_eq(canfdi_rx_raw_to_q16(0, 0, -(INT64_C(1) << 15) - 1), -1);
}
END_TEST

/* ------------------------------------------------------------------ */
/* Frame helpers                                                       */
/* ------------------------------------------------------------------ */

static canfdi_rx_t rx;
static canfdi_e2e_tx_t tx_dcm;
static canfdi_e2e_tx_t tx_thr;
static canfdi_e2e_tx_t tx_sp_dcm;
static canfdi_e2e_tx_t tx_sp_thr;
static uint32_t now;

/* Nominal raw values: 24 V, 3 A, 200 rad/s, 48 V; 1 V, 4 V, 1 A, 12 V. */
static const uint16_t nominal_raw[8] = {5696U, 4496U, 6096U, 4800U, 1000U, 4000U, 4496U, 6000U};

static void make_dcm(uint8_t *d, const uint16_t *raw)
{
  struct canfdi_sim_msg_dcm_sensor_t m;
  memset(&m, 0, sizeof m);
  m.dcm_ua = raw[0];
  m.dcm_ia = raw[1];
  m.dcm_omega = raw[2];
  m.dcm_usupply = raw[3];
  ck_assert_int_eq(canfdi_sim_msg_dcm_sensor_pack(d, &m, 8U), 8);
  ck_assert_int_eq(canfdi_e2e_protect(&tx_dcm, d, 8U), CANFDI_OK);
}

static void make_thr(uint8_t *d, const uint16_t *raw)
{
  struct canfdi_sim_msg_thr_sensor_t m;
  memset(&m, 0, sizeof m);
  m.thr_tps1 = raw[0];
  m.thr_tps2 = raw[1];
  m.thr_imot = raw[2];
  m.thr_usupply = raw[3];
  ck_assert_int_eq(canfdi_sim_msg_thr_sensor_pack(d, &m, 8U), 8);
  ck_assert_int_eq(canfdi_e2e_protect(&tx_thr, d, 8U), CANFDI_OK);
}

static void make_sp_dcm(uint8_t *d, int16_t raw)
{
  struct canfdi_sim_msg_setpoint_dcm_t m;
  memset(&m, 0, sizeof m);
  m.sp_dcm_speed = raw;
  m.sp_dcm_load = 1200; /* 1.2 N m, plausible */
  ck_assert_int_eq(canfdi_sim_msg_setpoint_dcm_pack(d, &m, 8U), 8);
  ck_assert_int_eq(canfdi_e2e_protect(&tx_sp_dcm, d, 8U), CANFDI_OK);
}

static void make_sp_thr(uint8_t *d, uint16_t raw)
{
  struct canfdi_sim_msg_setpoint_thr_t m;
  memset(&m, 0, sizeof m);
  m.sp_thr_angle = raw;
  ck_assert_int_eq(canfdi_sim_msg_setpoint_thr_pack(d, &m, 8U), 8);
  ck_assert_int_eq(canfdi_e2e_protect(&tx_sp_thr, d, 8U), CANFDI_OK);
}

static void setup_cfg(const canfdi_rx_cfg_t *cfg)
{
  canfdi_rx_cfg_t def;
  if (cfg == NULL) {
    canfdi_rx_default_cfg(&def);
    cfg = &def;
  }
  now = 1000000U;
  canfdi_e2e_tx_init(&tx_dcm, CANFDI_MSG_DCM_SENSOR_FRAME_ID);
  canfdi_e2e_tx_init(&tx_thr, CANFDI_MSG_THR_SENSOR_FRAME_ID);
  canfdi_e2e_tx_init(&tx_sp_dcm, CANFDI_MSG_SETPOINT_DCM_FRAME_ID);
  canfdi_e2e_tx_init(&tx_sp_thr, CANFDI_MSG_SETPOINT_THR_FRAME_ID);
  ck_assert_int_eq(canfdi_rx_init(&rx, cfg, now), CANFDI_OK);
}

/* One 1 ms cycle: the two sensor frames (each if asked) with raw values,
 * the setpoints every 10th cycle if asked, then the step. */
static void cycle(bool dcm, bool thr, bool sp, const uint16_t *raw)
{
  uint8_t d[8];
  now += STEP_US;
  if (dcm) {
    make_dcm(d, raw);
    ck_assert_int_eq(canfdi_rx_frame(&rx, CANFDI_MSG_DCM_SENSOR_FRAME_ID, d, 8U, now),
                     CANFDI_RX_ACCEPTED);
  }
  if (thr) {
    make_thr(d, raw + 4);
    ck_assert_int_eq(canfdi_rx_frame(&rx, CANFDI_MSG_THR_SENSOR_FRAME_ID, d, 8U, now),
                     CANFDI_RX_ACCEPTED);
  }
  if (sp && ((now / STEP_US) % 10U == 0U)) {
    make_sp_dcm(d, 5000); /* 100 rad/s */
    ck_assert_int_eq(canfdi_rx_frame(&rx, CANFDI_MSG_SETPOINT_DCM_FRAME_ID, d, 8U, now),
                     CANFDI_RX_ACCEPTED);
    make_sp_thr(d, 15000U); /* 30 deg */
    ck_assert_int_eq(canfdi_rx_frame(&rx, CANFDI_MSG_SETPOINT_THR_FRAME_ID, d, 8U, now),
                     CANFDI_RX_ACCEPTED);
  }
  ck_assert_int_eq(canfdi_rx_step(&rx, now), CANFDI_OK);
}

static bool failed(unsigned mon) { return (rx.report.prefailed & (UINT32_C(1) << mon)) != 0U; }
static bool passed(unsigned mon) { return (rx.report.prepassed & (UINT32_C(1) << mon)) != 0U; }

/* Sensor monitors 0..9 as a mask. */
#define SENSOR_MONS 0x3FFU

static void assert_value(unsigned i, int64_t raw)
{
  const double exp = input_phys(i, raw);
  ck_assert_msg(fabs((double)rx.in[i].value_q16 * LSB - exp) <= LSB, "input %u: %d vs %g", i,
                rx.in[i].value_q16, exp);
}

/* ------------------------------------------------------------------ */
/* Frame supervision                                                   */
/* ------------------------------------------------------------------ */

START_TEST(healthy_stream_is_valid_and_passes)
{
  setup_cfg(NULL);
  for (unsigned k = 0U; k < 200U; k++) {
    cycle(true, true, true, nominal_raw);
    ck_assert_uint_eq(rx.report.prefailed, 0U);
    ck_assert_uint_eq(rx.report.prepassed & SENSOR_MONS, SENSOR_MONS);
    for (unsigned i = 0U; i < 8U; i++) {
      ck_assert_uint_eq(rx.in[i].quality, CANFDI_RX_VALID);
      ck_assert(rx.in[i].fresh);
      assert_value(i, nominal_raw[i]);
    }
    if (k >= 10U) { /* the first setpoints arrive within 10 ms */
      ck_assert_uint_eq(rx.in[CANFDI_RX_IN_SP_DCM_SPEED].quality, CANFDI_RX_VALID);
      ck_assert_uint_eq(rx.in[CANFDI_RX_IN_SP_THR_ANGLE].quality, CANFDI_RX_VALID);
      assert_value(CANFDI_RX_IN_SP_DCM_SPEED, 5000);
      assert_value(CANFDI_RX_IN_SP_THR_ANGLE, 15000);
      ck_assert(passed(CANFDI_RX_MON_SP_DCM_TIMEOUT));
    }
  }
  ck_assert_uint_eq(rx.diag.accepted[CANFDI_RX_F_DCM_SENSOR], 200U);
  ck_assert_uint_eq(rx.diag.accepted[CANFDI_RX_F_SP_THR], 20U);
  ck_assert_uint_eq(rx.diag.timeouts[0] + rx.diag.crc_err[0] + rx.diag.counter_err[0], 0U);
  ck_assert_uint_eq(rx.diag.substituted[0] + rx.diag.invalid[0], 0U);
  ck_assert_int_eq(canfdi_rx_monitor_result(&rx, CANFDI_RX_MON_DCM_CRC), CANFDI_DEB_REPORT_PREPASSED);
}
END_TEST

/* canfdi_rx_samples: 1 for the frame of each cycle; 0 (and not fresh,
 * still VALID) in a cycle whose frame is late; 2 in a cycle that received
 * two (a frame early), the value the later one's; 0 while not VALID. */
START_TEST(samples_count_the_frames_of_a_step)
{
  uint8_t d[8];
  uint16_t raw[8];
  setup_cfg(NULL);
  memcpy(raw, nominal_raw, sizeof raw);
  for (unsigned k = 0U; k < 20U; k++) {
    cycle(true, true, false, nominal_raw);
    ck_assert_uint_eq(canfdi_rx_samples(&rx, CANFDI_RX_IN_DCM_OMEGA), 1U);
  }
  cycle(false, true, false, nominal_raw);
  ck_assert_uint_eq(rx.in[CANFDI_RX_IN_DCM_OMEGA].quality, CANFDI_RX_VALID);
  ck_assert(!canfdi_rx_fresh(&rx, CANFDI_RX_IN_DCM_OMEGA));
  ck_assert_uint_eq(canfdi_rx_samples(&rx, CANFDI_RX_IN_DCM_OMEGA), 0U);
  ck_assert_uint_eq(canfdi_rx_samples(&rx, CANFDI_RX_IN_THR_TPS1), 1U);
  make_dcm(d, nominal_raw);
  ck_assert_int_eq(canfdi_rx_frame(&rx, CANFDI_MSG_DCM_SENSOR_FRAME_ID, d, 8U, now + STEP_US), CANFDI_RX_ACCEPTED);
  raw[2] = (uint16_t)(raw[2] + 10U);
  cycle(true, true, false, raw);
  ck_assert(canfdi_rx_fresh(&rx, CANFDI_RX_IN_DCM_OMEGA));
  ck_assert_uint_eq(canfdi_rx_samples(&rx, CANFDI_RX_IN_DCM_OMEGA), 2U);
  assert_value(CANFDI_RX_IN_DCM_OMEGA, raw[2]);
  cycle(true, true, false, raw);
  ck_assert_uint_eq(canfdi_rx_samples(&rx, CANFDI_RX_IN_DCM_OMEGA), 1U);
  for (unsigned k = 0U; k < 10U; k++) {
    cycle(false, true, false, raw);
  }
  ck_assert_uint_ne(rx.in[CANFDI_RX_IN_DCM_OMEGA].quality, CANFDI_RX_VALID);
  cycle(true, true, false, raw);
  ck_assert_uint_eq(canfdi_rx_samples(&rx, CANFDI_RX_IN_DCM_OMEGA), 0U);
}
END_TEST

/* Before anything arrives: INVALID with the configured default, no
 * verdict, then the startup timeout after timeout_cycles. */
START_TEST(startup_invalid_then_timeout)
{
  canfdi_rx_cfg_t cfg;
  canfdi_rx_default_cfg(&cfg);
  cfg.default_q16[CANFDI_RX_IN_THR_TPS1] = 12345;
  setup_cfg(&cfg);
  for (unsigned k = 1U; k <= 6U; k++) {
    cycle(false, false, false, nominal_raw);
    ck_assert_uint_eq(rx.in[CANFDI_RX_IN_THR_TPS1].quality, CANFDI_RX_INVALID);
    ck_assert_int_eq(rx.in[CANFDI_RX_IN_THR_TPS1].value_q16, 12345);
    ck_assert_int_eq(rx.in[CANFDI_RX_IN_DCM_UA].value_q16, 0);
    if (k < 4U) {
      ck_assert_int_eq(canfdi_rx_monitor_result(&rx, CANFDI_RX_MON_THR_TIMEOUT), -CANFDI_ENODATA);
    } else {
      ck_assert(failed(CANFDI_RX_MON_THR_TIMEOUT));
      ck_assert(failed(CANFDI_RX_MON_DCM_TIMEOUT));
    }
  }
  /* first frame: valid at once (start-up is not an error) */
  cycle(true, true, false, nominal_raw);
  ck_assert_uint_eq(rx.in[CANFDI_RX_IN_THR_TPS1].quality, CANFDI_RX_SUBSTITUTED);
  /* ... except that a startup timeout is one: recover_frames apply */
  cycle(true, true, false, nominal_raw);
  cycle(true, true, false, nominal_raw);
  ck_assert_uint_eq(rx.in[CANFDI_RX_IN_THR_TPS1].quality, CANFDI_RX_VALID);
  ck_assert(passed(CANFDI_RX_MON_THR_TIMEOUT));

  /* no startup timeout: the first accepted frame is VALID at once */
  setup_cfg(&cfg);
  cycle(true, true, false, nominal_raw);
  ck_assert_uint_eq(rx.in[CANFDI_RX_IN_THR_TPS1].quality, CANFDI_RX_VALID);
  ck_assert(rx.in[CANFDI_RX_IN_THR_TPS1].fresh);
}
END_TEST

/* first_timeout_us: before the first reception the window is the longer
 * startup window (no verdict, no timeout during it); once a frame has
 * arrived the normal 4-cycle window applies. */
START_TEST(first_timeout_window)
{
  canfdi_rx_cfg_t cfg;
  canfdi_rx_default_cfg(&cfg);
  cfg.first_timeout_us = 20000U; /* 20 steps */
  setup_cfg(&cfg);
  for (unsigned k = 1U; k <= 25U; k++) {
    cycle(false, false, false, nominal_raw);
    if (k < 20U) {
      ck_assert_int_eq(canfdi_rx_monitor_result(&rx, CANFDI_RX_MON_DCM_TIMEOUT), -CANFDI_ENODATA);
      ck_assert_uint_eq(rx.diag.timeouts[CANFDI_RX_F_DCM_SENSOR], 0U);
    } else {
      ck_assert(failed(CANFDI_RX_MON_DCM_TIMEOUT));
    }
  }
  /* a sensor node that boots inside the window: no timeout at all, and
   * after its first frame a loss is seen after the normal 4 cycles */
  setup_cfg(&cfg);
  for (unsigned k = 1U; k <= 15U; k++) {
    cycle(false, false, false, nominal_raw);
  }
  cycle(true, true, false, nominal_raw);
  ck_assert(passed(CANFDI_RX_MON_DCM_TIMEOUT));
  ck_assert_uint_eq(rx.diag.timeouts[CANFDI_RX_F_DCM_SENSOR], 0U);
  for (unsigned k = 1U; k <= 4U; k++) {
    cycle(false, true, false, nominal_raw);
    if (k < 4U) {
      ck_assert(passed(CANFDI_RX_MON_DCM_TIMEOUT));
    } else {
      ck_assert(failed(CANFDI_RX_MON_DCM_TIMEOUT));
    }
  }
}
END_TEST

/* Timeout exactly at the timeout_cycles-th missing frame, for several
 * configurations; recovery after recover_frames good frames. */
START_TEST(timeout_exactly_after_n_missed_cycles)
{
  const uint8_t n = (uint8_t)(1 + _i); /* 1..6 */
  canfdi_rx_cfg_t cfg;
  canfdi_rx_default_cfg(&cfg);
  cfg.frame[CANFDI_RX_F_DCM_SENSOR].timeout_cycles = n;
  setup_cfg(&cfg);
  for (unsigned k = 0U; k < 10U; k++) {
    cycle(true, true, false, nominal_raw);
  }
  for (unsigned m = 1U; m <= 10U; m++) { /* m-th missing DCM frame */
    cycle(false, true, false, nominal_raw);
    if (m < n) {
      ck_assert_msg(passed(CANFDI_RX_MON_DCM_TIMEOUT), "N=%u m=%u", n, m);
      ck_assert_uint_eq(rx.in[CANFDI_RX_IN_DCM_IA].quality, CANFDI_RX_VALID);
      ck_assert(!rx.in[CANFDI_RX_IN_DCM_IA].fresh);
    } else {
      ck_assert_msg(failed(CANFDI_RX_MON_DCM_TIMEOUT), "N=%u m=%u", n, m);
      ck_assert_uint_eq(rx.in[CANFDI_RX_IN_DCM_IA].quality, CANFDI_RX_INVALID);
      assert_value(CANFDI_RX_IN_DCM_IA, nominal_raw[1]); /* last valid, flagged */
    }
    ck_assert(passed(CANFDI_RX_MON_THR_TIMEOUT));
    ck_assert_uint_eq(rx.report.prefailed & ~(UINT32_C(1) << CANFDI_RX_MON_DCM_TIMEOUT) & SENSOR_MONS, 0U);
  }
  ck_assert_uint_eq(rx.diag.timeouts[CANFDI_RX_F_DCM_SENSOR], 1U);
  /* back: the counter continued at the sender meanwhile? here it did not,
   * but the sequence check restarts anyway: no counter error */
  tx_dcm.counter = (uint8_t)((tx_dcm.counter + 7U) & 15U);
  for (unsigned k = 1U; k <= 4U; k++) {
    cycle(true, true, false, nominal_raw);
    ck_assert(passed(CANFDI_RX_MON_DCM_TIMEOUT));
    ck_assert(passed(CANFDI_RX_MON_DCM_COUNTER));
    ck_assert_uint_eq(rx.in[CANFDI_RX_IN_DCM_IA].quality,
                      (k < 3U) ? CANFDI_RX_SUBSTITUTED : CANFDI_RX_VALID);
  }
}
END_TEST

START_TEST(setpoint_timeout_and_range)
{
  uint8_t d[8];
  setup_cfg(NULL);
  for (unsigned k = 0U; k < 30U; k++) {
    cycle(true, true, true, nominal_raw);
  }
  ck_assert_uint_eq(rx.in[CANFDI_RX_IN_SP_DCM_SPEED].quality, CANFDI_RX_VALID);
  /* last setpoint at now (a multiple of 10 ms? find it) */
  while ((now / STEP_US) % 10U != 0U) {
    cycle(true, true, true, nominal_raw);
  }
  /* setpoints stop; 5 cycles of 10 ms = 50 ms until timeout */
  for (unsigned ms = 1U; ms <= 60U; ms++) {
    cycle(true, true, false, nominal_raw);
    if (ms < 50U) {
      ck_assert_msg(passed(CANFDI_RX_MON_SP_DCM_TIMEOUT), "ms %u", ms);
      ck_assert_uint_eq(rx.in[CANFDI_RX_IN_SP_DCM_SPEED].quality, CANFDI_RX_VALID);
    } else {
      ck_assert_msg(failed(CANFDI_RX_MON_SP_DCM_TIMEOUT), "ms %u", ms);
      ck_assert(failed(CANFDI_RX_MON_SP_THR_TIMEOUT));
      ck_assert_uint_eq(rx.in[CANFDI_RX_IN_SP_DCM_SPEED].quality, CANFDI_RX_INVALID);
      assert_value(CANFDI_RX_IN_SP_DCM_SPEED, 5000);
    }
  }
  /* out of range: -401 rad/s and 90.002 deg; wrong length */
  now += STEP_US;
  make_sp_dcm(d, -20050);
  ck_assert_int_eq(canfdi_rx_frame(&rx, CANFDI_MSG_SETPOINT_DCM_FRAME_ID, d, 8U, now),
                   CANFDI_RX_IMPLAUSIBLE);
  make_sp_thr(d, 45001U);
  ck_assert_int_eq(canfdi_rx_frame(&rx, CANFDI_MSG_SETPOINT_THR_FRAME_ID, d, 8U, now),
                   CANFDI_RX_IMPLAUSIBLE);
  ck_assert_int_eq(canfdi_rx_step(&rx, now), CANFDI_OK);
  ck_assert(failed(CANFDI_RX_MON_SP_DCM_RANGE));
  ck_assert(failed(CANFDI_RX_MON_SP_THR_RANGE));
  ck_assert(passed(CANFDI_RX_MON_SP_DCM_TIMEOUT)); /* it did arrive */
  ck_assert_uint_eq(rx.in[CANFDI_RX_IN_SP_DCM_SPEED].quality, CANFDI_RX_INVALID);
  assert_value(CANFDI_RX_IN_SP_DCM_SPEED, 5000); /* not -401 */
  /* edges of the range are plausible */
  now += STEP_US;
  make_sp_dcm(d, -20000);
  ck_assert_int_eq(canfdi_rx_frame(&rx, CANFDI_MSG_SETPOINT_DCM_FRAME_ID, d, 8U, now),
                   CANFDI_RX_ACCEPTED);
  make_sp_thr(d, 45000U);
  ck_assert_int_eq(canfdi_rx_frame(&rx, CANFDI_MSG_SETPOINT_THR_FRAME_ID, d, 7U, now),
                   CANFDI_RX_BAD_LENGTH);
  ck_assert_int_eq(canfdi_rx_step(&rx, now), CANFDI_OK);
  ck_assert(passed(CANFDI_RX_MON_SP_DCM_RANGE));
  ck_assert(failed(CANFDI_RX_MON_SP_THR_LENGTH));
  ck_assert_uint_eq(rx.in[CANFDI_RX_IN_SP_DCM_SPEED].quality, CANFDI_RX_VALID); /* recover 1 */
  assert_value(CANFDI_RX_IN_SP_DCM_SPEED, -20000);
  ck_assert_uint_eq(canfdi_rx_monitor_dtc(CANFDI_RX_MON_SP_DCM_RANGE), CANFDI_DTC_U1A51);
  ck_assert_uint_eq(canfdi_rx_monitor_dtc(CANFDI_RX_MON_SP_THR_TIMEOUT), CANFDI_DTC_U1A50);
}
END_TEST

/* Setpoints at their 10 ms cycle, each frame checked for (what is left
 * after 30 healthy cycles): */
static void sp_healthy(unsigned cycles)
{
  for (unsigned k = 0U; k < cycles; k++) {
    cycle(true, true, true, nominal_raw);
  }
  while ((now / STEP_US) % 10U != 0U) {
    cycle(true, true, true, nominal_raw);
  }
}

/* One SetpointThr frame (raw angle) at the next 10 ms tick, sensors every
 * ms; returns canfdi_rx_frame's result. The DC motor setpoint keeps coming
 * healthy. */
static int sp_thr_tick(const uint8_t *d)
{
  uint8_t dd[8];
  int res;
  for (unsigned k = 0U; k < 9U; k++) {
    cycle(true, true, false, nominal_raw);
  }
  now += STEP_US;
  make_dcm(dd, nominal_raw);
  (void)canfdi_rx_frame(&rx, CANFDI_MSG_DCM_SENSOR_FRAME_ID, dd, 8U, now);
  make_thr(dd, nominal_raw + 4);
  (void)canfdi_rx_frame(&rx, CANFDI_MSG_THR_SENSOR_FRAME_ID, dd, 8U, now);
  make_sp_dcm(dd, 5000);
  ck_assert_int_eq(canfdi_rx_frame(&rx, CANFDI_MSG_SETPOINT_DCM_FRAME_ID, dd, 8U, now), CANFDI_RX_ACCEPTED);
  res = canfdi_rx_frame(&rx, CANFDI_MSG_SETPOINT_THR_FRAME_ID, d, 8U, now);
  ck_assert_int_eq(canfdi_rx_step(&rx, now), CANFDI_OK);
  return res;
}

/* The setpoints' E2E protection: a wrong CRC (a bit flipped in the angle),
 * a repeated counter and a counter jump beyond max_delta 2 each reject the
 * frame (counted; U1A51's monitors pre-fail; the DC motor setpoint is
 * untouched); the angle held is the last accepted one, SUBSTITUTED while
 * younger than 50 ms, then INVALID (the application's safe reaction);
 * one lost frame (jump 2) is still usable; the next good frame is VALID
 * again (recover 1). */
START_TEST(setpoint_e2e_rejects_and_holds)
{
  uint8_t d[8];
  uint32_t crc0;
  uint32_t ctr0;
  setup_cfg(NULL);
  sp_healthy(30U);
  ck_assert_uint_eq(rx.in[CANFDI_RX_IN_SP_THR_ANGLE].quality, CANFDI_RX_VALID);
  assert_value(CANFDI_RX_IN_SP_THR_ANGLE, 15000);
  crc0 = rx.diag.crc_err[CANFDI_RX_F_SP_THR];
  ctr0 = rx.diag.counter_err[CANFDI_RX_F_SP_THR];
  /* 1. wrong CRC: 60 deg with a bit flipped after the CRC was computed */
  make_sp_thr(d, 30000U);
  d[3] ^= 0x01U;
  ck_assert_int_eq(sp_thr_tick(d), CANFDI_RX_BAD_CRC);
  ck_assert(failed(CANFDI_RX_MON_SP_THR_CRC));
  ck_assert(passed(CANFDI_RX_MON_SP_DCM_CRC));
  ck_assert(passed(CANFDI_RX_MON_SP_THR_TIMEOUT)); /* it did arrive */
  ck_assert_uint_eq(rx.in[CANFDI_RX_IN_SP_THR_ANGLE].quality, CANFDI_RX_SUBSTITUTED);
  assert_value(CANFDI_RX_IN_SP_THR_ANGLE, 15000); /* held, never 60 deg */
  ck_assert_uint_eq(rx.in[CANFDI_RX_IN_SP_DCM_SPEED].quality, CANFDI_RX_VALID);
  ck_assert_uint_eq(rx.diag.crc_err[CANFDI_RX_F_SP_THR], crc0 + 1U);
  /* the next good frame: the sequence restarts after a CRC error */
  make_sp_thr(d, 15500U);
  ck_assert_int_eq(sp_thr_tick(d), CANFDI_RX_ACCEPTED);
  ck_assert_uint_eq(rx.in[CANFDI_RX_IN_SP_THR_ANGLE].quality, CANFDI_RX_VALID);
  assert_value(CANFDI_RX_IN_SP_THR_ANGLE, 15500);
  /* 2. the same frame again: REPEATED */
  ck_assert_int_eq(sp_thr_tick(d), CANFDI_RX_BAD_COUNTER);
  ck_assert(failed(CANFDI_RX_MON_SP_THR_COUNTER));
  ck_assert(passed(CANFDI_RX_MON_SP_THR_CRC));
  ck_assert_uint_eq(rx.in[CANFDI_RX_IN_SP_THR_ANGLE].quality, CANFDI_RX_SUBSTITUTED);
  ck_assert_uint_eq(rx.diag.counter_err[CANFDI_RX_F_SP_THR], ctr0 + 1U);
  /* 3. one frame lost (counter +2): usable */
  tx_sp_thr.counter = (uint8_t)((tx_sp_thr.counter + 1U) & 15U);
  make_sp_thr(d, 16000U);
  ck_assert_int_eq(sp_thr_tick(d), CANFDI_RX_ACCEPTED);
  ck_assert_uint_eq(rx.in[CANFDI_RX_IN_SP_THR_ANGLE].quality, CANFDI_RX_VALID);
  assert_value(CANFDI_RX_IN_SP_THR_ANGLE, 16000);
  /* 4. a jump of 3 (two lost) and more: rejected, then INVALID after 50 ms
   * of nothing accepted, the held value until then */
  for (unsigned k = 0U; k < 7U; k++) {
    tx_sp_thr.counter = (uint8_t)((tx_sp_thr.counter + 2U + (k % 2U) * 5U) & 15U);
    make_sp_thr(d, 45000U); /* 90 deg: wide open */
    ck_assert_int_eq(sp_thr_tick(d), CANFDI_RX_BAD_COUNTER);
    ck_assert(failed(CANFDI_RX_MON_SP_THR_COUNTER));
    assert_value(CANFDI_RX_IN_SP_THR_ANGLE, 16000);
    /* accepted at tick 0, rejected at 10..40 ms: held; 50 ms on: INVALID */
    ck_assert_uint_eq(rx.in[CANFDI_RX_IN_SP_THR_ANGLE].quality,
                      (k < 4U) ? CANFDI_RX_SUBSTITUTED : CANFDI_RX_INVALID);
    ck_assert_uint_eq(rx.in[CANFDI_RX_IN_SP_DCM_SPEED].quality, CANFDI_RX_VALID);
  }
  ck_assert_uint_eq(rx.diag.timeouts[CANFDI_RX_F_SP_THR], 0U); /* frames came: no timeout */
  ck_assert_uint_eq(rx.diag.counter_err[CANFDI_RX_F_SP_THR], ctr0 + 8U);
  /* 5. in sequence again: VALID at once */
  make_sp_thr(d, 17000U);
  ck_assert_int_eq(sp_thr_tick(d), CANFDI_RX_ACCEPTED);
  ck_assert_uint_eq(rx.in[CANFDI_RX_IN_SP_THR_ANGLE].quality, CANFDI_RX_VALID);
  assert_value(CANFDI_RX_IN_SP_THR_ANGLE, 17000);
  ck_assert_uint_eq(rx.diag.crc_err[CANFDI_RX_F_SP_DCM] + rx.diag.counter_err[CANFDI_RX_F_SP_DCM], 0U);
}
END_TEST

/* A second sender on SetpointThr's identifier with a right CRC and a
 * counter sequence of its own, interleaved with the vehicle's: every frame
 * after the first is out of sequence (the check resynchronises to each),
 * so neither sequence is taken and the angle goes INVALID after 50 ms. A
 * forged frame carries 90 deg; it is never the value. */
START_TEST(setpoint_second_sender_shows_as_counter_errors)
{
  uint8_t d[8];
  canfdi_e2e_tx_t forger;
  uint32_t ctr0;
  unsigned accepted = 0U;
  setup_cfg(NULL);
  sp_healthy(30U);
  canfdi_e2e_tx_init(&forger, CANFDI_MSG_SETPOINT_THR_FRAME_ID);
  forger.counter = (uint8_t)((tx_sp_thr.counter + 8U) & 15U);
  ctr0 = rx.diag.counter_err[CANFDI_RX_F_SP_THR];
  for (unsigned k = 0U; k < 20U; k++) {
    int res;
    if ((k % 2U) == 0U) {
      make_sp_thr(d, 15000U);
    } else {
      struct canfdi_sim_msg_setpoint_thr_t m;
      memset(&m, 0, sizeof m);
      m.sp_thr_angle = 45000U;
      ck_assert_int_eq(canfdi_sim_msg_setpoint_thr_pack(d, &m, 8U), 8);
      ck_assert_int_eq(canfdi_e2e_protect(&forger, d, 8U), CANFDI_OK);
    }
    res = sp_thr_tick(d);
    accepted += (res == CANFDI_RX_ACCEPTED) ? 1U : 0U;
    ck_assert_int_ne(res, CANFDI_RX_BAD_CRC); /* both CRCs are right */
    ck_assert_int_ne(rx.in[CANFDI_RX_IN_SP_THR_ANGLE].value_q16,
                     canfdi_rx_raw_to_q16(45000, CANFDI_SIG_SETPOINT_THR_SP_THR_ANGLE_RAD_SCALE_Q32,
                                          CANFDI_SIG_SETPOINT_THR_SP_THR_ANGLE_RAD_OFFSET_Q32));
    if (k >= 5U) {
      ck_assert_uint_eq(rx.in[CANFDI_RX_IN_SP_THR_ANGLE].quality, CANFDI_RX_INVALID);
    }
  }
  ck_assert_uint_eq(accepted, 1U); /* the vehicle's first, still in its sequence */
  ck_assert_uint_eq(rx.diag.counter_err[CANFDI_RX_F_SP_THR], ctr0 + 19U);
}
END_TEST

/* One bad frame of each error type on each sensor frame: exactly its
 * U-code pre-fails, in that step only; the frame's inputs are substituted
 * with the last valid value; the other frame is untouched. */
START_TEST(error_type_reports_its_u_code)
{
  static const uint32_t want_dtc[2][4] = {
      {CANFDI_DTC_U1A20, CANFDI_DTC_U1A10, CANFDI_DTC_U1A30, CANFDI_DTC_U1A40},
      {CANFDI_DTC_U1A21, CANFDI_DTC_U1A11, CANFDI_DTC_U1A31, CANFDI_DTC_U1A41}};
  static const int want_result[4] = {CANFDI_RX_BAD_CRC, CANFDI_RX_BAD_COUNTER,
                                     CANFDI_RX_BAD_LENGTH, CANFDI_RX_IMPLAUSIBLE};
  const unsigned f = (unsigned)_i / 4U;   /* 0 DCM, 1 THR */
  const unsigned err = (unsigned)_i % 4U; /* crc, counter, length, implausible */
  const uint32_t id = (f == 0U) ? CANFDI_MSG_DCM_SENSOR_FRAME_ID : CANFDI_MSG_THR_SENSOR_FRAME_ID;
  const unsigned in0 = (f == 0U) ? CANFDI_RX_IN_DCM_UA : CANFDI_RX_IN_THR_TPS1;
  uint16_t bad_raw[8];
  uint8_t d[8];
  uint8_t dlc = 8U;
  unsigned mon_failed = 0U;
  int res;
  setup_cfg(NULL);
  for (unsigned k = 0U; k < 20U; k++) {
    cycle(true, true, false, nominal_raw);
  }
  memcpy(bad_raw, nominal_raw, sizeof bad_raw);
  for (unsigned i = 0U; i < 8U; i++) {
    bad_raw[i] = (uint16_t)(bad_raw[i] + 100U); /* a different, plausible value */
  }
  if (err == 3U) {
    bad_raw[4U * f + 0U] = 8191U; /* all ones: implausible */
  }
  now += STEP_US;
  if (f == 0U) {
    make_dcm(d, bad_raw);
  } else {
    make_thr(d, bad_raw + 4);
  }
  if (err == 0U) {
    d[3] ^= 0x10U; /* one bit: the CRC catches every 1-bit error */
  } else if (err == 1U) {
    /* repeat the previous counter: re-protect with the counter stepped back */
    canfdi_e2e_tx_t *t = (f == 0U) ? &tx_dcm : &tx_thr;
    t->counter = (uint8_t)((t->counter + 14U) & 15U);
    ck_assert_int_eq(canfdi_e2e_protect(t, d, 8U), CANFDI_OK);
  } else if (err == 2U) {
    dlc = 7U;
  } else {
    /* implausible */
  }
  res = canfdi_rx_frame(&rx, id, d, dlc, now);
  ck_assert_int_eq(res, want_result[err]);
  /* the other frame, healthy */
  if (f == 0U) {
    make_thr(d, nominal_raw + 4);
    ck_assert_int_eq(canfdi_rx_frame(&rx, CANFDI_MSG_THR_SENSOR_FRAME_ID, d, 8U, now),
                     CANFDI_RX_ACCEPTED);
  } else {
    make_dcm(d, nominal_raw);
    ck_assert_int_eq(canfdi_rx_frame(&rx, CANFDI_MSG_DCM_SENSOR_FRAME_ID, d, 8U, now),
                     CANFDI_RX_ACCEPTED);
  }
  ck_assert_int_eq(canfdi_rx_step(&rx, now), CANFDI_OK);
  for (unsigned m = 0U; m < 10U; m++) {
    if (failed(m)) {
      mon_failed++;
      ck_assert_uint_eq(canfdi_rx_monitor_dtc(m), want_dtc[f][err]);
      ck_assert_int_eq(canfdi_rx_monitor_result(&rx, m), CANFDI_DEB_REPORT_PREFAILED);
    }
  }
  ck_assert_uint_eq(mon_failed, 1U);
  /* the failing input: substituted with the last valid value */
  ck_assert_uint_eq(rx.in[in0].quality, CANFDI_RX_SUBSTITUTED);
  assert_value(in0, nominal_raw[in0]);
  /* the other inputs of the frame: substituted too, unless only that
   * signal was implausible, then taken with the new value */
  for (unsigned i = in0 + 1U; i < in0 + 4U; i++) {
    if (err == 3U) {
      ck_assert_uint_eq(rx.in[i].quality, CANFDI_RX_VALID);
      assert_value(i, bad_raw[i]);
    } else {
      ck_assert_uint_eq(rx.in[i].quality, CANFDI_RX_SUBSTITUTED);
      assert_value(i, nominal_raw[i]);
    }
  }
  /* the other frame untouched */
  ck_assert_uint_eq(rx.in[(f == 0U) ? CANFDI_RX_IN_THR_TPS1 : CANFDI_RX_IN_DCM_UA].quality,
                    CANFDI_RX_VALID);
  /* next cycle healthy: every monitor passes again, even the counter (the
   * sequence restarts after a frame whose counter could not be read) */
  cycle(true, true, false, nominal_raw);
  ck_assert_uint_eq(rx.report.prefailed, 0U);
  ck_assert_uint_eq(rx.report.prepassed & SENSOR_MONS, SENSOR_MONS);
  ck_assert_uint_eq(rx.in[in0].quality, CANFDI_RX_SUBSTITUTED); /* recovering: 1 of 3 */
  cycle(true, true, false, nominal_raw);
  cycle(true, true, false, nominal_raw);
  ck_assert_uint_eq(rx.in[in0].quality, CANFDI_RX_VALID);
}
END_TEST

/* Counter: a repeat and a jump beyond max_delta are errors; a single lost
 * frame (delta 2 = max_delta) is not. */
START_TEST(counter_repeat_jump_and_one_lost)
{
  uint8_t d[8];
  uint8_t prev[8];
  setup_cfg(NULL);
  for (unsigned k = 0U; k < 5U; k++) {
    cycle(true, true, false, nominal_raw);
  }
  now += STEP_US;
  make_dcm(prev, nominal_raw);
  ck_assert_int_eq(canfdi_rx_frame(&rx, 0x10U, prev, 8U, now), CANFDI_RX_ACCEPTED);
  ck_assert_int_eq(canfdi_rx_frame(&rx, 0x10U, prev, 8U, now), CANFDI_RX_BAD_COUNTER);
  ck_assert_int_eq(canfdi_rx_step(&rx, now), CANFDI_OK);
  ck_assert(failed(CANFDI_RX_MON_DCM_COUNTER)); /* failure dominates the pass */
  ck_assert(!passed(CANFDI_RX_MON_DCM_COUNTER));
  /* one lost frame: accepted */
  make_dcm(d, nominal_raw);
  now += STEP_US;
  make_dcm(d, nominal_raw);
  ck_assert_int_eq(canfdi_rx_frame(&rx, 0x10U, d, 8U, now), CANFDI_RX_ACCEPTED);
  ck_assert_int_eq(canfdi_rx_step(&rx, now), CANFDI_OK);
  ck_assert(passed(CANFDI_RX_MON_DCM_COUNTER));
  /* jump by 3: rejected */
  make_dcm(d, nominal_raw);
  make_dcm(d, nominal_raw);
  now += STEP_US;
  make_dcm(d, nominal_raw);
  ck_assert_int_eq(canfdi_rx_frame(&rx, 0x10U, d, 8U, now), CANFDI_RX_BAD_COUNTER);
  ck_assert_int_eq(canfdi_rx_step(&rx, now), CANFDI_OK);
  ck_assert(failed(CANFDI_RX_MON_DCM_COUNTER));
  ck_assert_uint_eq(rx.diag.counter_err[CANFDI_RX_F_DCM_SENSOR], 2U);
  /* after the jump the receiver follows the new sequence */
  cycle(true, true, false, nominal_raw);
  ck_assert(passed(CANFDI_RX_MON_DCM_COUNTER));
}
END_TEST

/* Frames rejected for CRC: the held value is the last valid one, flagged
 * SUBSTITUTED while younger than the timeout window, then INVALID; never
 * the value of the rejected frames. */
START_TEST(substitution_holds_last_valid_value)
{
  uint16_t other[8];
  uint8_t d[8];
  setup_cfg(NULL);
  for (unsigned k = 0U; k < 5U; k++) {
    cycle(true, true, false, nominal_raw);
  }
  for (unsigned i = 0U; i < 8U; i++) {
    other[i] = (uint16_t)(nominal_raw[i] - 321U);
  }
  for (unsigned m = 1U; m <= 8U; m++) {
    now += STEP_US;
    make_dcm(d, other);
    d[0] ^= 0xFFU;
    ck_assert_int_eq(canfdi_rx_frame(&rx, 0x10U, d, 8U, now), CANFDI_RX_BAD_CRC);
    ck_assert_int_eq(canfdi_rx_step(&rx, now), CANFDI_OK);
    for (unsigned i = 0U; i < 4U; i++) {
      ck_assert_uint_eq(rx.in[i].quality, (m < 4U) ? CANFDI_RX_SUBSTITUTED : CANFDI_RX_INVALID);
      ck_assert(!rx.in[i].fresh);
      assert_value(i, nominal_raw[i]);
    }
    ck_assert(failed(CANFDI_RX_MON_DCM_CRC));
    ck_assert(passed(CANFDI_RX_MON_DCM_TIMEOUT)); /* frames do arrive */
  }
  ck_assert_uint_eq(rx.diag.substituted[CANFDI_RX_IN_DCM_OMEGA], 3U);
  ck_assert_uint_eq(rx.diag.invalid[CANFDI_RX_IN_DCM_OMEGA], 5U);
  ck_assert_uint_eq(rx.diag.crc_err[CANFDI_RX_F_DCM_SENSOR], 8U);
}
END_TEST

/* A model estimate replaces the held value while the input is not VALID,
 * for the one step it was supplied for; it is ignored while VALID. */
START_TEST(estimate_is_used_once_when_not_valid)
{
  uint8_t d[8];
  setup_cfg(NULL);
  for (unsigned k = 0U; k < 5U; k++) {
    cycle(true, true, false, nominal_raw);
  }
  ck_assert_int_eq(canfdi_rx_set_estimate(&rx, CANFDI_RX_IN_DCM_OMEGA, 777), CANFDI_OK);
  cycle(true, true, false, nominal_raw);
  ck_assert_uint_eq(rx.in[CANFDI_RX_IN_DCM_OMEGA].quality, CANFDI_RX_VALID);
  assert_value(CANFDI_RX_IN_DCM_OMEGA, nominal_raw[2]);
  ck_assert_uint_eq(rx.diag.estimates_used, 0U);
  for (unsigned m = 1U; m <= 10U; m++) {
    now += STEP_US;
    make_dcm(d, nominal_raw);
    ck_assert_int_eq(canfdi_rx_frame(&rx, 0x10U, d, 5U, now), CANFDI_RX_BAD_LENGTH);
    if ((m % 2U) == 1U) {
      ck_assert_int_eq(canfdi_rx_set_estimate(&rx, CANFDI_RX_IN_DCM_OMEGA, (int32_t)(1000 * m)),
                       CANFDI_OK);
    }
    ck_assert_int_eq(canfdi_rx_step(&rx, now), CANFDI_OK);
    if ((m % 2U) == 1U) {
      ck_assert_uint_eq(rx.in[CANFDI_RX_IN_DCM_OMEGA].quality, CANFDI_RX_SUBSTITUTED);
      ck_assert_int_eq(rx.in[CANFDI_RX_IN_DCM_OMEGA].value_q16, (int32_t)(1000 * m));
    } else {
      ck_assert_uint_eq(rx.in[CANFDI_RX_IN_DCM_OMEGA].quality,
                        (m < 4U) ? CANFDI_RX_SUBSTITUTED : CANFDI_RX_INVALID);
      assert_value(CANFDI_RX_IN_DCM_OMEGA, nominal_raw[2]);
    }
    ck_assert(failed(CANFDI_RX_MON_DCM_LENGTH));
  }
  ck_assert_uint_eq(rx.diag.estimates_used, 5U);
  ck_assert_int_eq(canfdi_rx_set_estimate(&rx, CANFDI_RX_IN_COUNT, 0), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_rx_set_estimate(NULL, 0U, 0), -CANFDI_EINVAL);
}
END_TEST

/* Recovery needs exactly recover_frames consecutive accepted samples; an
 * error in between starts the count again. */
START_TEST(recovery_after_configured_good_frames)
{
  const uint8_t r = (uint8_t)(1 + _i); /* 1..4 */
  canfdi_rx_cfg_t cfg;
  uint8_t d[8];
  canfdi_rx_default_cfg(&cfg);
  cfg.frame[CANFDI_RX_F_THR_SENSOR].recover_frames = r;
  setup_cfg(&cfg);
  for (unsigned k = 0U; k < 5U; k++) {
    cycle(true, true, false, nominal_raw);
  }
  for (unsigned rep = 0U; rep < 2U; rep++) {
    now += STEP_US;
    make_thr(d, nominal_raw + 4);
    d[7] ^= 0x01U;
    ck_assert_int_eq(canfdi_rx_frame(&rx, 0x11U, d, 8U, now), CANFDI_RX_BAD_CRC);
    ck_assert_int_eq(canfdi_rx_step(&rx, now), CANFDI_OK);
    ck_assert_uint_eq(rx.in[CANFDI_RX_IN_THR_TPS2].quality, CANFDI_RX_SUBSTITUTED);
    for (unsigned g = 1U; g <= r; g++) {
      cycle(true, true, false, nominal_raw);
      ck_assert_uint_eq(rx.in[CANFDI_RX_IN_THR_TPS2].quality,
                        (g < r) ? CANFDI_RX_SUBSTITUTED : CANFDI_RX_VALID);
      ck_assert(rx.in[CANFDI_RX_IN_THR_TPS2].fresh == (g >= r));
      if ((rep == 0U) && (g + 1U == r)) {
        break; /* interrupted one short of recovery: next error restarts */
      }
    }
  }
}
END_TEST

START_TEST(unknown_ids_and_bad_arguments)
{
  uint8_t d[16];
  setup_cfg(NULL);
  memset(d, 0xA5, sizeof d);
  ck_assert_int_eq(canfdi_rx_frame(&rx, 0x7E0U, d, 8U, now), CANFDI_RX_UNKNOWN_ID);
  ck_assert_int_eq(canfdi_rx_frame(&rx, 0x610U, NULL, 0U, now), CANFDI_RX_UNKNOWN_ID);
  ck_assert_int_eq(canfdi_rx_frame(&rx, 0x80000010UL, d, 8U, now), CANFDI_RX_UNKNOWN_ID);
  ck_assert_int_eq(canfdi_rx_frame(&rx, 0x020U, d, 8U, now), CANFDI_RX_UNKNOWN_ID); /* own */
  ck_assert_int_eq(canfdi_rx_frame(&rx, 0x10U, NULL, 3U, now), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_rx_frame(&rx, 0x10U, NULL, 0U, now), CANFDI_RX_BAD_LENGTH);
  ck_assert_int_eq(canfdi_rx_frame(&rx, 0x10U, d, 12U, now), CANFDI_RX_BAD_LENGTH);
  ck_assert_int_eq(canfdi_rx_frame(NULL, 0x10U, d, 8U, now), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_rx_step(&rx, now), CANFDI_OK);
  ck_assert_uint_eq(rx.diag.unknown_id, 4U);
  ck_assert_uint_eq(rx.diag.bad_args, 1U);
  ck_assert_uint_eq(rx.diag.frames, 6U);
  ck_assert_uint_eq(rx.diag.length_err[CANFDI_RX_F_DCM_SENSOR], 2U);
  ck_assert(failed(CANFDI_RX_MON_DCM_LENGTH));
  ck_assert_uint_eq(rx.report.prefailed, UINT32_C(1) << CANFDI_RX_MON_DCM_LENGTH);
  ck_assert_int_eq(canfdi_rx_step(NULL, now), -CANFDI_EINVAL);
  {
    canfdi_rx_t fresh;
    memset(&fresh, 0, sizeof fresh);
    ck_assert_int_eq(canfdi_rx_step(&fresh, now), -CANFDI_EINVAL); /* never initialised */
    ck_assert_int_eq(canfdi_rx_frame(&fresh, 0x10U, d, 8U, now), -CANFDI_EINVAL);
  }
}
END_TEST

START_TEST(monitor_tables_follow_the_catalogue)
{
  static const uint32_t dtc[10] = {CANFDI_DTC_U1A00, CANFDI_DTC_U1A01, CANFDI_DTC_U1A10,
                                   CANFDI_DTC_U1A11, CANFDI_DTC_U1A20, CANFDI_DTC_U1A21,
                                   CANFDI_DTC_U1A30, CANFDI_DTC_U1A31, CANFDI_DTC_U1A40,
                                   CANFDI_DTC_U1A41};
  static const uint8_t fid[10] = {
      CANFDI_FAULT_COM_DCM_TIMEOUT,     CANFDI_FAULT_COM_THR_TIMEOUT, CANFDI_FAULT_COM_DCM_COUNTER,
      CANFDI_FAULT_COM_THR_COUNTER,     CANFDI_FAULT_COM_DCM_CRC,     CANFDI_FAULT_COM_THR_CRC,
      CANFDI_FAULT_COM_DCM_LENGTH,      CANFDI_FAULT_COM_THR_LENGTH,
      CANFDI_FAULT_COM_DCM_IMPLAUSIBLE, CANFDI_FAULT_COM_THR_IMPLAUSIBLE};
  for (unsigned m = 0U; m < 10U; m++) {
    ck_assert_uint_eq(canfdi_rx_monitor_dtc(m), dtc[m]);
    ck_assert_uint_eq(canfdi_rx_monitor_fault_id(m), fid[m]);
  }
  /* the setpoints': no catalogue fault, U1A50 (timeouts) and U1A51 */
  for (unsigned m = 10U; m < CANFDI_RX_MON_COUNT; m++) {
    const bool timeout = (m == CANFDI_RX_MON_SP_DCM_TIMEOUT) || (m == CANFDI_RX_MON_SP_THR_TIMEOUT);
    ck_assert_uint_eq(canfdi_rx_monitor_dtc(m), timeout ? CANFDI_DTC_U1A50 : CANFDI_DTC_U1A51);
    ck_assert_uint_eq(canfdi_rx_monitor_fault_id(m), 0U);
  }
  for (unsigned m = CANFDI_RX_MON_COUNT; m < 40U; m++) {
    ck_assert_uint_eq(canfdi_rx_monitor_dtc(m), 0U);
    ck_assert_uint_eq(canfdi_rx_monitor_fault_id(m), 0U);
  }
  setup_cfg(NULL);
  ck_assert_int_eq(canfdi_rx_monitor_result(&rx, CANFDI_RX_MON_COUNT), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_rx_monitor_result(NULL, 0U), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_rx_monitor_result(&rx, 0U), -CANFDI_ENODATA);
}
END_TEST

START_TEST(init_rejects_bad_configuration)
{
  canfdi_rx_cfg_t cfg;
  canfdi_rx_default_cfg(&cfg);
  ck_assert_int_eq(canfdi_rx_init(NULL, &cfg, 0U), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_rx_init(&rx, NULL, 0U), -CANFDI_EINVAL);
  cfg.frame[2].timeout_cycles = 0U;
  ck_assert_int_eq(canfdi_rx_init(&rx, &cfg, 0U), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_rx_step(&rx, 0U), -CANFDI_EINVAL);
  canfdi_rx_default_cfg(&cfg);
  cfg.frame[0].max_delta = 16U;
  ck_assert_int_eq(canfdi_rx_init(&rx, &cfg, 0U), -CANFDI_EINVAL);
  canfdi_rx_default_cfg(&cfg);
  cfg.frame[1].recover_frames = 0U;
  ck_assert_int_eq(canfdi_rx_init(&rx, &cfg, 0U), -CANFDI_EINVAL);
  canfdi_rx_default_cfg(&cfg);
  ck_assert_int_eq(canfdi_rx_init(&rx, &cfg, 0U), CANFDI_OK);
  canfdi_rx_default_cfg(NULL); /* no-op */
}
END_TEST

/* Time stamps across the 2^32 us wrap and a frame stamped after the step
 * (jitter) behave like any others. */
START_TEST(time_wrap_and_jitter)
{
  canfdi_rx_cfg_t cfg;
  canfdi_rx_default_cfg(&cfg);
  ck_assert_int_eq(canfdi_rx_init(&rx, &cfg, UINT32_MAX - 5500U), CANFDI_OK);
  canfdi_e2e_tx_init(&tx_dcm, 0x10U);
  canfdi_e2e_tx_init(&tx_thr, 0x11U);
  now = UINT32_MAX - 5500U;
  for (unsigned k = 0U; k < 12U; k++) {
    uint8_t d[8];
    now += STEP_US;
    make_dcm(d, nominal_raw);
    /* stamped 300 us after the step that consumes it */
    ck_assert_int_eq(canfdi_rx_frame(&rx, 0x10U, d, 8U, now + 300U), CANFDI_RX_ACCEPTED);
    make_thr(d, nominal_raw + 4);
    ck_assert_int_eq(canfdi_rx_frame(&rx, 0x11U, d, 8U, now), CANFDI_RX_ACCEPTED);
    ck_assert_int_eq(canfdi_rx_step(&rx, now), CANFDI_OK);
    ck_assert_uint_eq(rx.report.prefailed & SENSOR_MONS, 0U);
    ck_assert_uint_eq(rx.in[CANFDI_RX_IN_DCM_UA].quality, CANFDI_RX_VALID);
  }
  ck_assert_uint_lt(now, 10000U); /* wrapped */
  for (unsigned m = 1U; m <= 5U; m++) {
    cycle(false, true, false, nominal_raw);
    /* the last DCM frame was stamped 300 us late: 4 ms age is reached one
     * step later than with an on-time stamp */
    ck_assert(failed(CANFDI_RX_MON_DCM_TIMEOUT) == (m >= 5U));
  }
}
END_TEST

/* ------------------------------------------------------------------ */
/* Flood                                                               */
/* ------------------------------------------------------------------ */

static uint64_t rng_state = 0x9E3779B97F4A7C15ULL;
static uint32_t rnd(void)
{
  rng_state ^= rng_state << 13;
  rng_state ^= rng_state >> 7;
  rng_state ^= rng_state << 17;
  return (uint32_t)(rng_state >> 32);
}

/*
 * 10^5 frames: well-formed sensor and setpoint frames with random (also
 * implausible) values, corrupted ones, repeats, gaps, random ids and
 * lengths 0..15 with random bytes, random estimates. Oracle kept by the
 * test from its own decode: after every step, a VALID input equals (within
 * 1 LSB) the last sample the module accepted, which is plausible and
 * younger than the timeout window; SUBSTITUTED is that sample or this
 * step's estimate; INVALID is that sample or the default. The module's
 * verdict on length and CRC is checked against the test's own judgement.
 */
START_TEST(random_flood_never_yields_unflagged_invalid_values)
{
  canfdi_rx_cfg_t cfg;
  double ref[CANFDI_RX_IN_COUNT];
  bool ref_has[CANFDI_RX_IN_COUNT];
  uint32_t ref_t[CANFDI_RX_IN_COUNT];
  uint32_t frames = 0U;
  uint32_t unknown = 0U;
  uint32_t n_valid = 0U;
  uint32_t n_sub = 0U;
  uint32_t n_inv = 0U;
  static const uint32_t sup_id[4] = {0x10U, 0x11U, 0x100U, 0x101U};
  uint8_t last[4][8];
  memset(last, 0, sizeof last);
  canfdi_rx_default_cfg(&cfg);
  for (unsigned i = 0U; i < CANFDI_RX_IN_COUNT; i++) {
    cfg.default_q16[i] = (int32_t)(i * 1000U) - 3000;
    ref_has[i] = false;
    ref[i] = 0.0;
    ref_t[i] = 0U;
  }
  setup_cfg(&cfg);
  while (frames < 100000U) {
    const unsigned nf = (rnd() % 8U == 0U) ? 0U : (rnd() % 4U);
    int32_t est[CANFDI_RX_IN_COUNT];
    uint32_t est_mask = 0U;
    now += STEP_US;
    for (unsigned j = 0U; j < nf; j++) {
      uint8_t d[16];
      uint32_t id;
      uint8_t dlc = 8U;
      const unsigned kind = rnd() % 20U;
      uint16_t raw[4];
      int res;
      for (unsigned q = 0U; q < 4U; q++) {
        raw[q] = (uint16_t)((rnd() % 4U == 0U) ? (rnd() & 0x1FFFU) : (200U + rnd() % 4800U));
      }
      for (unsigned q = 0U; q < 16U; q++) {
        d[q] = (uint8_t)rnd();
      }
      if (kind < 6U) {
        id = 0x10U;
        make_dcm(d, raw);
        memcpy(last[0], d, 8U);
      } else if (kind < 12U) {
        id = 0x11U;
        make_thr(d, raw);
        memcpy(last[1], d, 8U);
      } else if (kind == 12U) {
        id = 0x100U;
        make_sp_dcm(d, (int16_t)(rnd() & 0xFFFFU));
        memcpy(last[2], d, 8U);
      } else if (kind == 13U) {
        id = 0x101U;
        make_sp_thr(d, (uint16_t)(rnd() % 50000U));
        memcpy(last[3], d, 8U);
      } else if (kind == 14U) { /* corrupted well-formed frame */
        const unsigned f = rnd() % 4U;
        id = sup_id[f];
        if (f == 0U) {
          make_dcm(d, raw);
        } else if (f == 1U) {
          make_thr(d, raw);
        } else if (f == 2U) {
          make_sp_dcm(d, (int16_t)(rnd() & 0xFFFFU));
        } else {
          make_sp_thr(d, (uint16_t)(rnd() % 50000U));
        }
        d[rnd() % 8U] ^= (uint8_t)(1U << (rnd() % 8U));
      } else if (kind == 15U) { /* repeat: counter error */
        const unsigned f = rnd() % 4U;
        id = sup_id[f];
        memcpy(d, last[f], 8U);
      } else { /* random id and length, random bytes */
        const uint32_t pick = rnd() % 8U;
        id = (pick < 4U) ? (uint32_t[]){0x10U, 0x11U, 0x100U, 0x101U}[pick] : (rnd() & 0x7FFU);
        dlc = (uint8_t)(rnd() % 16U);
      }
      res = canfdi_rx_frame(&rx, id, d, dlc, now);
      frames++;
      CHECK((res) >= (0), "res >= 0");
      {
        const bool supervised = (id == 0x10U) || (id == 0x11U) || (id == 0x100U) || (id == 0x101U);
        if (!supervised) {
          unknown++;
          CHECK((res) == (CANFDI_RX_UNKNOWN_ID), "res == CANFDI_RX_UNKNOWN_ID");
          continue;
        }
        if (dlc != 8U) {
          CHECK((res) == (CANFDI_RX_BAD_LENGTH), "res == CANFDI_RX_BAD_LENGTH");
          continue;
        }
        if (canfdi_e2e_frame_crc((uint16_t)id, d, 8U) != d[0]) { /* every supervised frame is E2E */
          CHECK((res) == (CANFDI_RX_BAD_CRC), "res == CANFDI_RX_BAD_CRC");
          continue;
        }
        CHECK((res) != (CANFDI_RX_BAD_CRC), "res != CANFDI_RX_BAD_CRC");
        CHECK((res) != (CANFDI_RX_BAD_LENGTH), "res != CANFDI_RX_BAD_LENGTH");
        if (res == CANFDI_RX_BAD_COUNTER) {
          continue;
        }
        /* accepted, at least in part: the test's own decode */
        if (id == 0x10U) {
          struct canfdi_msg_dcm_sensor_t m;
          CHECK(canfdi_msg_dcm_sensor_unpack(&m, d, 8U) == 0, "unpack");
          {
            const int32_t rr[4] = {m.dcm_ua, m.dcm_ia, m.dcm_omega, m.dcm_usupply};
            const int32_t lo[4] = {CANFDI_RAW_DCM_SENSOR_DCM_UA_MIN, CANFDI_RAW_DCM_SENSOR_DCM_IA_MIN,
                                   CANFDI_RAW_DCM_SENSOR_DCM_OMEGA_MIN,
                                   CANFDI_RAW_DCM_SENSOR_DCM_USUPPLY_MIN};
            const int32_t hi[4] = {CANFDI_RAW_DCM_SENSOR_DCM_UA_MAX, CANFDI_RAW_DCM_SENSOR_DCM_IA_MAX,
                                   CANFDI_RAW_DCM_SENSOR_DCM_OMEGA_MAX,
                                   CANFDI_RAW_DCM_SENSOR_DCM_USUPPLY_MAX};
            bool all = true;
            for (unsigned q = 0U; q < 4U; q++) {
              if ((rr[q] >= lo[q]) && (rr[q] <= hi[q])) {
                ref[q] = input_phys(q, rr[q]);
                ref_has[q] = true;
                ref_t[q] = now;
              } else {
                all = false;
              }
            }
            CHECK((res) == (all ? CANFDI_RX_ACCEPTED : CANFDI_RX_IMPLAUSIBLE), "res == all ? CANFDI_RX_ACCEPTED : CANFDI_RX_IMPLAUSIBLE");
          }
        } else if (id == 0x11U) {
          struct canfdi_msg_thr_sensor_t m;
          CHECK(canfdi_msg_thr_sensor_unpack(&m, d, 8U) == 0, "unpack");
          {
            const int32_t rr[4] = {m.thr_tps1, m.thr_tps2, m.thr_imot, m.thr_usupply};
            const int32_t lo[4] = {CANFDI_RAW_THR_SENSOR_THR_TPS1_MIN, CANFDI_RAW_THR_SENSOR_THR_TPS2_MIN,
                                   CANFDI_RAW_THR_SENSOR_THR_IMOT_MIN,
                                   CANFDI_RAW_THR_SENSOR_THR_USUPPLY_MIN};
            const int32_t hi[4] = {CANFDI_RAW_THR_SENSOR_THR_TPS1_MAX, CANFDI_RAW_THR_SENSOR_THR_TPS2_MAX,
                                   CANFDI_RAW_THR_SENSOR_THR_IMOT_MAX,
                                   CANFDI_RAW_THR_SENSOR_THR_USUPPLY_MAX};
            bool all = true;
            for (unsigned q = 0U; q < 4U; q++) {
              if ((rr[q] >= lo[q]) && (rr[q] <= hi[q])) {
                ref[4U + q] = input_phys(4U + q, rr[q]);
                ref_has[4U + q] = true;
                ref_t[4U + q] = now;
              } else {
                all = false;
              }
            }
            CHECK((res) == (all ? CANFDI_RX_ACCEPTED : CANFDI_RX_IMPLAUSIBLE), "res == all ? CANFDI_RX_ACCEPTED : CANFDI_RX_IMPLAUSIBLE");
          }
        } else {
          const unsigned i = (id == 0x100U) ? CANFDI_RX_IN_SP_DCM_SPEED : CANFDI_RX_IN_SP_THR_ANGLE;
          int32_t r;
          bool ok;
          if (id == 0x100U) {
            struct canfdi_msg_setpoint_dcm_t m;
            int32_t rl;
            bool ok_l;
            CHECK(canfdi_msg_setpoint_dcm_unpack(&m, d, 8U) == 0, "unpack");
            r = m.sp_dcm_speed;
            ok = (r >= CANFDI_RAW_SETPOINT_DCM_SP_DCM_SPEED_MIN) &&
                 (r <= CANFDI_RAW_SETPOINT_DCM_SP_DCM_SPEED_MAX);
            /* the load is judged on its own: taken if plausible whatever
             * the speed, and the frame is IMPLAUSIBLE if either is not */
            rl = m.sp_dcm_load;
            ok_l = (rl >= CANFDI_RAW_SETPOINT_DCM_SP_DCM_LOAD_MIN) &&
                   (rl <= CANFDI_RAW_SETPOINT_DCM_SP_DCM_LOAD_MAX);
            if (ok_l) {
              ref[CANFDI_RX_IN_SP_DCM_LOAD] = input_phys(CANFDI_RX_IN_SP_DCM_LOAD, rl);
              ref_has[CANFDI_RX_IN_SP_DCM_LOAD] = true;
              ref_t[CANFDI_RX_IN_SP_DCM_LOAD] = now;
            }
            if (ok) {
              ref[i] = input_phys(i, r);
              ref_has[i] = true;
              ref_t[i] = now;
            }
            ok = ok && ok_l;
          } else {
            struct canfdi_msg_setpoint_thr_t m;
            CHECK(canfdi_msg_setpoint_thr_unpack(&m, d, 8U) == 0, "unpack");
            r = m.sp_thr_angle;
            ok = (r <= (int32_t)CANFDI_RAW_SETPOINT_THR_SP_THR_ANGLE_MAX);
          }
          CHECK((res) == (ok ? CANFDI_RX_ACCEPTED : CANFDI_RX_IMPLAUSIBLE), "res == ok ? CANFDI_RX_ACCEPTED : CANFDI_RX_IMPLAUSIBLE");
          if (ok) {
            ref[i] = input_phys(i, r);
            ref_has[i] = true;
            ref_t[i] = now;
          }
        }
      }
    }
    for (unsigned i = 0U; i < CANFDI_RX_IN_COUNT; i++) {
      if (rnd() % 5U == 0U) {
        est[i] = (int32_t)rnd();
        est_mask |= UINT32_C(1) << i;
        CHECK(canfdi_rx_set_estimate(&rx, i, est[i]) == CANFDI_OK, "set_estimate");
      }
    }
    CHECK(canfdi_rx_step(&rx, now) == CANFDI_OK, "step");
    CHECK((rx.report.prefailed & rx.report.prepassed) == (0U), "rx.report.prefailed & rx.report.prepassed == 0U");
    for (unsigned i = 0U; i < CANFDI_RX_IN_COUNT; i++) {
      const canfdi_rx_input_t *in = &rx.in[i];
      const double v = (double)in->value_q16 * LSB;
      const uint32_t window = (i < 8U) ? 4000U : 50000U;
      if (in->quality == CANFDI_RX_VALID) {
        n_valid++;
        CHECK(ref_has[i], "ref_has[i]");
        CHECK(fabs(v - ref[i]) <= LSB, "input %u VALID %g, last accepted %g", i, v, ref[i]);
        CHECK((now - ref_t[i]) < (window), "now - ref_t[i] < window");
      } else if (in->quality == CANFDI_RX_SUBSTITUTED) {
        n_sub++;
        CHECK(!in->fresh, "!in->fresh");
        if ((est_mask & (UINT32_C(1) << i)) != 0U) {
          CHECK((in->value_q16) == (est[i]), "in->value_q16 == est[i]");
        } else {
          CHECK(ref_has[i], "ref_has[i]");
          CHECK(fabs(v - ref[i]) <= LSB, "fabs(v - ref[i]) <= LSB");
          CHECK((now - ref_t[i]) < (window), "now - ref_t[i] < window");
        }
      } else {
        n_inv++;
        CHECK((in->quality) == (CANFDI_RX_INVALID), "in->quality == CANFDI_RX_INVALID");
        CHECK(!in->fresh, "!in->fresh");
        if (ref_has[i]) {
          CHECK(fabs(v - ref[i]) <= LSB, "fabs(v - ref[i]) <= LSB");
        } else {
          CHECK((in->value_q16) == (cfg.default_q16[i]), "in->value_q16 == cfg.default_q16[i]");
        }
      }
    }
  }
  ck_assert_uint_eq(rx.diag.frames, frames);
  ck_assert_uint_eq(rx.diag.unknown_id, unknown);
  /* the flood must have exercised every quality and every error */
  ck_assert_uint_gt(n_valid, 1000U);
  ck_assert_uint_gt(n_sub, 1000U);
  ck_assert_uint_gt(n_inv, 1000U);
  for (unsigned f = 0U; f < 2U; f++) {
    ck_assert_uint_gt(rx.diag.crc_err[f], 100U);
    ck_assert_uint_gt(rx.diag.counter_err[f], 10U);
    ck_assert_uint_gt(rx.diag.length_err[f], 100U);
    ck_assert_uint_gt(rx.diag.implausible[f], 100U);
    ck_assert_uint_gt(rx.diag.timeouts[f], 10U);
  }
  printf("flood: %u frames, %u unknown; input-steps valid %u substituted %u invalid %u\n", frames,
         unknown, n_valid, n_sub, n_inv);
}
END_TEST

/* ------------------------------------------------------------------ */
/* With the simulator's frame builder                                  */
/* ------------------------------------------------------------------ */

static canfdi_sim_t sim;

static void sim_setup(int fault_id)
{
  canfdi_sim_cfg_t cfg;
  canfdi_sim_default_cfg(&cfg);
  for (unsigned s = 0U; s < CANFDI_SIM_N_SENSORS; s++) {
    cfg.sigma[s] = 0.0;
  }
  cfg.sigma[CANFDI_SIM_S_DCM_IA] = 0.05; /* some noise so values move */
  cfg.sigma[CANFDI_SIM_S_THR_TPS1] = 0.002;
  ck_assert_int_eq(canfdi_sim_init(&sim, &cfg), CANFDI_OK);
  if (fault_id >= 0) {
    canfdi_sim_fault_spec_t s;
    /* intermittent, period 40 ms, duty 0.5, from 20 ms: on 20..39 ms */
    ck_assert_int_eq(canfdi_sim_fault_spec_make(&s, (uint8_t)fault_id, CANFDI_SIM_MODE_INTERMITTENT,
                                                0.020, 1.0, 0.0, 0.040, 0.5),
                     CANFDI_OK);
    ck_assert_int_eq(canfdi_sim_add_fault(&sim, &s), CANFDI_OK);
  }
}

static void sim_input(canfdi_sim_in_t *in)
{
  in->dcm.u_cmd_V = 30.0;
  in->dcm.bridge = CANFDI_SIM_BRIDGE_A;
  in->dcm.enable = true;
  in->dcm.load_Nm = 0.8;
  in->thr.u_cmd_V = 3.0;
  in->thr.enable = true;
}

/* One step: the plant's frames at k ms into rx, rx step, plant step. */
static void sim_cycle(canfdi_sim_frames_t *fr, const canfdi_sim_in_t *in, unsigned k)
{
  canfdi_sim_frame_t out[CANFDI_SIM_FRAMES_MAX_PER_STEP];
  const size_t n = canfdi_sim_frames_build(fr, &sim, in, out);
  const uint32_t t = 5000U + k * STEP_US;
  for (size_t j = 0U; j < n; j++) {
    ck_assert_int_ge(canfdi_rx_frame(&rx, out[j].id, out[j].data, out[j].dlc, t), 0);
  }
  ck_assert_int_eq(canfdi_rx_step(&rx, t), CANFDI_OK);
}

/* The plant's own frames come back within one DBC LSB: the plant truncates
 * to the raw value at or below its reading (< 1 DBC LSB), the firmware adds
 * at most 1 Q16.16 LSB. */
START_TEST(sim_frames_round_trip_within_one_dbc_lsb)
{
  static const double dbc_lsb[8] = {0.015, 0.0075, 0.1, 0.01, 0.001, 0.001, 0.0025, 0.002};
  canfdi_sim_frames_t fr;
  canfdi_sim_in_t in;
  canfdi_rx_cfg_t cfg;
  double worst[8] = {0};
  canfdi_rx_default_cfg(&cfg);
  ck_assert_int_eq(canfdi_rx_init(&rx, &cfg, 5000U), CANFDI_OK);
  sim_setup(-1);
  sim_input(&in);
  canfdi_sim_frames_init(&fr, (uint8_t)CANFDI_SIM_MODE_OFFLINE);
  for (unsigned k = 0U; k < 500U; k++) {
    double sent[8];
    for (unsigned i = 0U; i < 8U; i++) {
      sent[i] = sim.meas.value[i]; /* sensor index order == input order */
    }
    sim_cycle(&fr, &in, k);
    ck_assert_uint_eq(rx.report.prefailed & SENSOR_MONS, 0U);
    for (unsigned i = 0U; i < 8U; i++) {
      const double got = (double)rx.in[i].value_q16 * LSB;
      const double d = sent[i] - got; /* in [0, lsb) up to 1 Q16 LSB */
      ck_assert_uint_eq(rx.in[i].quality, CANFDI_RX_VALID);
      ck_assert_msg((d > -LSB - 1e-12) && (d < dbc_lsb[i] + LSB + 1e-12),
                    "input %u: sent %.6f got %.6f at %u ms", i, sent[i], got, k);
      worst[i] = (fabs(d) > worst[i]) ? fabs(d) : worst[i];
    }
    canfdi_sim_step(&sim, &in);
  }
  ck_assert_uint_eq(rx.diag.unknown_id, 5U); /* SimPlantStatus every 100 ms */
  printf("sim round trip: worst |sent - got| / DBC LSB:");
  for (unsigned i = 0U; i < 8U; i++) {
    printf(" %.3f", worst[i] / dbc_lsb[i]);
  }
  printf("\n");
}
END_TEST

/* Each of the catalogue's 10 communication faults, injected by the plant on
 * [20, 40) ms, pre-fails exactly its own monitor, over the expected steps,
 * and no other sensor-frame monitor ever. */
START_TEST(sim_comm_fault_is_isolated)
{
  static const char *const names[10] = {
      "com_dcm_timeout", "com_thr_timeout", "com_dcm_counter",     "com_thr_counter",
      "com_dcm_crc",     "com_thr_crc",     "com_dcm_length",      "com_thr_length",
      "com_dcm_implausible", "com_thr_implausible"};
  const unsigned mon = (unsigned)_i; /* monitor index == catalogue order */
  const int fid = canfdi_sim_fault_find(names[mon]);
  const bool is_dcm = (mon % 2U) == 0U;
  const unsigned in0 = is_dcm ? CANFDI_RX_IN_DCM_UA : CANFDI_RX_IN_THR_TPS1;
  canfdi_sim_frames_t fr;
  canfdi_sim_in_t in;
  canfdi_rx_cfg_t cfg;
  unsigned first = 20U;
  unsigned last = 39U;
  ck_assert_int_eq(fid, (int)canfdi_rx_monitor_fault_id(mon));
  canfdi_rx_default_cfg(&cfg);
  if (mon < 2U) {
    /* last frame at 19 ms, timeout at the timeout_cycles-th missing one */
    first = 19U + cfg.frame[0].timeout_cycles;
  } else if (mon < 4U) {
    last = 40U; /* the first good frame jumps the counter */
  } else {
    /* crc, length, implausible: exactly the faulty frames */
  }
  ck_assert_int_eq(canfdi_rx_init(&rx, &cfg, 5000U), CANFDI_OK);
  sim_setup(fid);
  sim_input(&in);
  canfdi_sim_frames_init(&fr, (uint8_t)CANFDI_SIM_MODE_OFFLINE);
  /* 60 ms: the intermittent fault's next on-phase starts at 60 ms */
  for (unsigned k = 0U; k < 60U; k++) {
    sim_cycle(&fr, &in, k);
    ck_assert_msg(failed(mon) == ((k >= first) && (k <= last)), "%s at %u ms: prefailed %x",
                  names[mon], k, rx.report.prefailed);
    ck_assert_msg((rx.report.prefailed & SENSOR_MONS & ~(UINT32_C(1) << mon)) == 0U,
                  "%s at %u ms: other monitors %x", names[mon], k, rx.report.prefailed);
    if ((k >= first) && (k <= last)) {
      ck_assert_uint_ne(rx.in[in0].quality, CANFDI_RX_VALID);
    }
    if ((k < 20U) || (k >= last + 3U)) {
      ck_assert_msg(rx.in[in0].quality == CANFDI_RX_VALID, "%s at %u ms: quality %u", names[mon],
                    k, rx.in[in0].quality);
    }
    canfdi_sim_step(&sim, &in);
  }
}
END_TEST

static Suite *make_suite(void)
{
  Suite *s = suite_create("rx");
  TCase *tc = tcase_create("conversion");
  tcase_add_test(tc, conv_every_signal_whole_raw_range);
  tcase_add_test(tc, conv_angle_in_radians);
  tcase_add_test(tc, conv_saturates_without_ub);
  suite_add_tcase(s, tc);

  tc = tcase_create("supervision");
  tcase_add_test(tc, healthy_stream_is_valid_and_passes);
  tcase_add_test(tc, samples_count_the_frames_of_a_step);
  tcase_add_test(tc, startup_invalid_then_timeout);
  tcase_add_test(tc, first_timeout_window);
  tcase_add_loop_test(tc, timeout_exactly_after_n_missed_cycles, 0, 6);
  tcase_add_test(tc, setpoint_timeout_and_range);
  tcase_add_test(tc, setpoint_e2e_rejects_and_holds);
  tcase_add_test(tc, setpoint_second_sender_shows_as_counter_errors);
  tcase_add_loop_test(tc, error_type_reports_its_u_code, 0, 8);
  tcase_add_test(tc, counter_repeat_jump_and_one_lost);
  tcase_add_test(tc, substitution_holds_last_valid_value);
  tcase_add_test(tc, estimate_is_used_once_when_not_valid);
  tcase_add_loop_test(tc, recovery_after_configured_good_frames, 0, 4);
  tcase_add_test(tc, unknown_ids_and_bad_arguments);
  tcase_add_test(tc, monitor_tables_follow_the_catalogue);
  tcase_add_test(tc, init_rejects_bad_configuration);
  tcase_add_test(tc, time_wrap_and_jitter);
  suite_add_tcase(s, tc);

  tc = tcase_create("flood");
  tcase_add_test(tc, random_flood_never_yields_unflagged_invalid_values);
  suite_add_tcase(s, tc);

  tc = tcase_create("simulator");
  tcase_add_test(tc, sim_frames_round_trip_within_one_dbc_lsb);
  tcase_add_loop_test(tc, sim_comm_fault_is_isolated, 0, 10);
  suite_add_tcase(s, tc);
  return s;
}

CANFDI_UNIT_MAIN(make_suite)
