/*
 * test_sim_fault.c — fault injection (host_sim/canfdi_sim_fault.h) applied
 * through the combined plant (canfdi_sim.h): every catalogue entry changes
 * exactly the quantity it names by the requested amount and nothing else;
 * shapes follow their definitions; specs are validated.
 */
#include <check.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "canfdi_sim.h"
#include "canfdi_sim_fault.h"
#include "core/canfdi_common.h"
#include "gen/canfdi_faults.h"
#include "unit_main.h"

/* ---- the observable view of the plant -------------------------------------
 * Everything a fault may act on, observed right after it was applied:
 * effective parameters, bridge output voltages, whether the throttle motor
 * conducts and whether the valve can move, the error of every sensor
 * (analog value before noise/ADC minus the true quantity) and the frame
 * flags. Sensor errors and parameters do not depend on the (diverging)
 * plant state, so they compare exactly between a healthy and a faulty run. */
enum {
  V_RA,
  V_PSI,
  V_MF0,
  V_MF1,
  V_UA_A, /* U_A with bridge A selected and 30 V commanded */
  V_UA_B, /* same on bridge B */
  V_KS,
  V_PRE,
  V_FC,
  V_B,
  V_RTHR,
  V_THR_OPEN, /* 1 if no throttle current flows while driven */
  V_THR_JAM,  /* 1 if the valve did not move while driven */
  V_ERR0,     /* + sensor index: analog - truth */
  V_FLAG0 = V_ERR0 + CANFDI_SIM_N_SENSORS, /* + 5 * frame + flag */
  V_N = V_FLAG0 + (5 * CANFDI_SIM_N_FRAMES)
};

static const char *const view_names[V_N] = {
    "R_A", "Psi", "M_F0", "M_F1", "U_A(bridge A)", "U_A(bridge B)", "k_spring", "pretension",
    "T_coulomb", "B_viscous", "R_thr", "thr_open", "thr_jammed", "err dcm_ua", "err dcm_ia",
    "err dcm_speed", "err dcm_supply", "err thr_tps1", "err thr_tps2", "err thr_i",
    "err thr_supply", "dcm drop", "dcm crc", "dcm counter", "dcm dlc", "dcm implausible",
    "thr drop", "thr crc", "thr counter", "thr dlc", "thr implausible"};

typedef struct {
  double v[V_N];
  double truth[CANFDI_SIM_N_SENSORS];
  double value[CANFDI_SIM_N_SENSORS];
  double lsb[CANFDI_SIM_N_SENSORS];
} view_t;

static double flag(bool b)
{
  return b ? 1.0 : 0.0;
}

/* Runs 10 steps with the fault (if any) active from t = 0 and observes. */
static void observe(const canfdi_sim_fault_spec_t *spec, uint8_t bridge, view_t *out)
{
  static canfdi_sim_t sim;
  canfdi_sim_cfg_t cfg;
  canfdi_sim_in_t in;
  double theta0;
  unsigned k;
  unsigned f;

  canfdi_sim_default_cfg(&cfg);
  cfg.dcm.thermal = false; /* keep R_A independent of the current history */
  ck_assert_int_eq(canfdi_sim_init(&sim, &cfg), CANFDI_OK);
  ck_assert_int_eq(canfdi_sim_dcm_set_state(&sim.dcm, 2.0, 80.0, 20.0), CANFDI_OK);
  ck_assert_int_eq(canfdi_sim_thr_set_state(&sim.thr, 40.0, 0.0), CANFDI_OK);
  if (spec != NULL) {
    ck_assert_int_eq(canfdi_sim_add_fault(&sim, spec), CANFDI_OK);
  }
  in.dcm.u_cmd_V = 30.0;
  in.dcm.bridge = bridge;
  in.dcm.enable = true;
  in.dcm.load_Nm = 0.5;
  in.thr.u_cmd_V = 8.0;
  in.thr.enable = true;
  theta0 = sim.thr.theta_rad;
  for (k = 0U; k < 10U; k++) {
    canfdi_sim_step(&sim, &in);
  }
  out->v[V_RA] = sim.dcm.ra_ohm;
  out->v[V_PSI] = sim.dcm.psi_eff_Vs;
  out->v[V_MF0] = sim.dcm.mf0_eff_Nm;
  out->v[V_MF1] = sim.dcm.mf1_eff_Nms;
  out->v[V_UA_A] = sim.dcm.ua_V; /* the caller files it under A or B */
  out->v[V_UA_B] = 0.0;
  out->v[V_KS] = sim.thr.spring_eff_Nm_rad;
  out->v[V_PRE] = sim.thr.pretension_eff_Nm;
  out->v[V_FC] = sim.thr.friction_eff_Nm;
  out->v[V_B] = sim.thr.b_eff_Nms;
  out->v[V_RTHR] = sim.thr.r_eff_ohm;
  out->v[V_THR_OPEN] = flag(fabs(sim.thr.i_A) < 1e-300);
  out->v[V_THR_JAM] = flag(fabs(sim.thr.theta_rad - theta0) < 1e-300);
  for (k = 0U; k < CANFDI_SIM_N_SENSORS; k++) {
    out->v[V_ERR0 + k] = sim.meas.analog[k] - sim.meas.truth[k];
    out->truth[k] = sim.meas.truth[k];
    out->value[k] = sim.meas.value[k];
    out->lsb[k] = sim.sensor[k].lsb;
  }
  for (f = 0U; f < CANFDI_SIM_N_FRAMES; f++) {
    const canfdi_sim_frame_fx_t *fr = &sim.fx.frame[f];
    out->v[V_FLAG0 + (5U * f) + 0U] = flag(fr->drop);
    out->v[V_FLAG0 + (5U * f) + 1U] = flag(fr->bad_crc);
    out->v[V_FLAG0 + (5U * f) + 2U] = flag(fr->bad_counter);
    out->v[V_FLAG0 + (5U * f) + 3U] = flag(fr->bad_dlc);
    out->v[V_FLAG0 + (5U * f) + 4U] = flag(fr->implausible);
  }
}

static void view_of(const canfdi_sim_fault_spec_t *spec, view_t *out)
{
  view_t b;
  observe(spec, CANFDI_SIM_BRIDGE_B, &b);
  observe(spec, CANFDI_SIM_BRIDGE_A, out);
  out->v[V_UA_B] = b.v[V_UA_A];
}

/* The test's own reading of the catalogue: what each named fault must do to
 * the view, given the healthy view h and magnitude m. Returns false if the
 * test does not know the fault (a new catalogue entry needs a test). */
static bool expect(const char *name, double m, const view_t *h, double *e)
{
  const double tps_short = 5.0;
  bool known = true;
  memcpy(e, h->v, sizeof h->v);
  if (strcmp(name, "none") == 0) {
    /* nothing */
  } else if (strcmp(name, "dcm_ra_up") == 0) {
    e[V_RA] = h->v[V_RA] * (1.0 + m);
  } else if (strcmp(name, "dcm_flux_down") == 0) {
    e[V_PSI] = h->v[V_PSI] * (1.0 - m);
  } else if (strcmp(name, "dcm_friction_up") == 0) {
    e[V_MF0] = h->v[V_MF0] * (1.0 + m);
    e[V_MF1] = h->v[V_MF1] * (1.0 + m);
  } else if (strcmp(name, "dcm_ia_sensor_offset") == 0) {
    e[V_ERR0 + CANFDI_SIM_S_DCM_IA] = m;
  } else if (strcmp(name, "dcm_speed_sensor_gain") == 0) {
    e[V_ERR0 + CANFDI_SIM_S_DCM_SPEED] = m * h->truth[CANFDI_SIM_S_DCM_SPEED];
  } else if (strcmp(name, "dcm_speed_sensor_offset") == 0) {
    e[V_ERR0 + CANFDI_SIM_S_DCM_SPEED] = m;
  } else if (strcmp(name, "dcm_ua_sensor_offset") == 0) {
    e[V_ERR0 + CANFDI_SIM_S_DCM_UA] = m;
  } else if (strcmp(name, "dcm_bridge_a_dead") == 0) {
    e[V_UA_A] = 0.0;
  } else if (strcmp(name, "dcm_bridges_dead") == 0) {
    e[V_UA_A] = 0.0;
    e[V_UA_B] = 0.0;
  } else if (strcmp(name, "thr_tps1_open") == 0) {
    e[V_ERR0 + CANFDI_SIM_S_THR_TPS1] = -h->truth[CANFDI_SIM_S_THR_TPS1];
  } else if (strcmp(name, "thr_tps1_short") == 0) {
    e[V_ERR0 + CANFDI_SIM_S_THR_TPS1] = tps_short - h->truth[CANFDI_SIM_S_THR_TPS1];
  } else if (strcmp(name, "thr_tps2_open") == 0) {
    e[V_ERR0 + CANFDI_SIM_S_THR_TPS2] = -h->truth[CANFDI_SIM_S_THR_TPS2];
  } else if (strcmp(name, "thr_tps2_short") == 0) {
    e[V_ERR0 + CANFDI_SIM_S_THR_TPS2] = tps_short - h->truth[CANFDI_SIM_S_THR_TPS2];
  } else if (strcmp(name, "thr_tps1_drift") == 0) {
    e[V_ERR0 + CANFDI_SIM_S_THR_TPS1] = m;
  } else if (strcmp(name, "thr_tps2_drift") == 0) {
    e[V_ERR0 + CANFDI_SIM_S_THR_TPS2] = m;
  } else if (strcmp(name, "thr_spring_weak") == 0) {
    e[V_KS] = h->v[V_KS] * (1.0 - m);
    e[V_PRE] = h->v[V_PRE] * (1.0 - m);
  } else if (strcmp(name, "thr_friction_up") == 0) {
    e[V_FC] = h->v[V_FC] * (1.0 + m);
    e[V_B] = h->v[V_B] * (1.0 + m);
  } else if (strcmp(name, "thr_motor_r_up") == 0) {
    e[V_RTHR] = h->v[V_RTHR] * (1.0 + m);
  } else if (strcmp(name, "thr_motor_open") == 0) {
    e[V_THR_OPEN] = 1.0;
  } else if (strcmp(name, "thr_jammed") == 0) {
    e[V_THR_JAM] = 1.0;
  } else if (strcmp(name, "thr_tps_both_lost") == 0) {
    e[V_ERR0 + CANFDI_SIM_S_THR_TPS1] = -h->truth[CANFDI_SIM_S_THR_TPS1];
    e[V_ERR0 + CANFDI_SIM_S_THR_TPS2] = -h->truth[CANFDI_SIM_S_THR_TPS2];
  } else if (strncmp(name, "com_", 4U) == 0) {
    static const char *const kinds[5] = {"timeout", "crc", "counter", "length", "implausible"};
    const unsigned fr = (strncmp(name, "com_dcm_", 8U) == 0) ? CANFDI_SIM_FRAME_DCM : CANFDI_SIM_FRAME_THR;
    unsigned k;
    known = false;
    for (k = 0U; k < 5U; k++) {
      if (strcmp(name + 8, kinds[k]) == 0) {
        e[V_FLAG0 + (5U * fr) + k] = 1.0;
        known = true;
      }
    }
  } else {
    known = false;
  }
  return known;
}

START_TEST(every_fault_changes_exactly_its_quantity)
{
  const canfdi_fault_info_t *info = &canfdi_fault_table[_i];
  view_t healthy;
  unsigned rep;

  ck_assert_uint_eq(info->id, (unsigned)_i);
  view_of(NULL, &healthy);
  /* Binary faults are checked once; the others at the catalogue default and
   * at half of it, so a hard-coded amount cannot pass. */
  for (rep = 0U; rep < ((strcmp(info->unit, "-") == 0) ? 1U : 2U); rep++) {
    const double m = (rep == 0U) ? info->default_magnitude : (0.5 * info->default_magnitude);
    canfdi_sim_fault_spec_t spec;
    view_t faulty;
    double e[V_N];
    unsigned j;
    unsigned changed = 0U;

    ck_assert_int_eq(canfdi_sim_fault_spec_make(&spec, info->id, CANFDI_SIM_MODE_ABRUPT, 0.0, m, 0.0,
                                                0.0, 0.0),
                     CANFDI_OK);
    view_of(&spec, &faulty);
    ck_assert_msg(expect(info->name, m, &healthy, e), "no expectation for fault %s", info->name);
    for (j = 0U; j < (unsigned)V_N; j++) {
      /* Exact arithmetic up to rounding of one multiply/add: 1e-12. */
      const double tol = 1e-12 * (1.0 + fabs(e[j]));
      ck_assert_msg(fabs(faulty.v[j] - e[j]) <= tol, "%s (m = %g): %s is %.12g, expected %.12g",
                    info->name, m, view_names[j], faulty.v[j], e[j]);
      if (fabs(e[j] - healthy.v[j]) > tol) {
        changed++;
      }
    }
    if (info->id != CANFDI_FAULT_NONE) {
      ck_assert_msg(changed > 0U, "%s changes nothing", info->name);
    }
    /* Offsets also arrive in the quantised reading: two roundings of the
     * same true value differ by at most one LSB from the offset. */
    if ((strcmp(info->kind, "sensor") == 0) && (strcmp(info->unit, "-") != 0) &&
        (strcmp(info->unit, "rel") != 0)) {
      for (j = 0U; j < CANFDI_SIM_N_SENSORS; j++) {
        const double d = faulty.value[j] - healthy.value[j];
        const double want = e[V_ERR0 + j] - healthy.v[V_ERR0 + j];
        ck_assert_msg(fabs(d - want) <= faulty.lsb[j] + 1e-12, "%s: reading %u moved %g, want %g",
                      info->name, j, d, want);
      }
    }
  }
}
END_TEST

/* ---- shapes --------------------------------------------------------------- */

START_TEST(shapes_follow_definitions)
{
  canfdi_sim_fault_spec_t s;
  const uint8_t id = (uint8_t)CANFDI_FAULT_DCM_RA_UP;
  ck_assert_int_eq(canfdi_sim_fault_spec_make(&s, id, CANFDI_SIM_MODE_ABRUPT, 1.0, 0.2, 0, 0, 0), 0);
  ck_assert_msg(canfdi_sim_fault_shape(&s, 999999) < 1e-300, "abrupt before t0");
  ck_assert_msg(fabs(canfdi_sim_fault_shape(&s, 1000000) - 1.0) < 1e-15, "abrupt at t0");
  ck_assert_msg(fabs(canfdi_sim_fault_shape(&s, 50000000) - 1.0) < 1e-15, "abrupt later");

  /* incipient: linear from t0 = 1 s, full magnitude after ramp_s = 2 s */
  ck_assert_int_eq(canfdi_sim_fault_spec_make(&s, id, CANFDI_SIM_MODE_INCIPIENT, 1.0, 0.2, 2.0, 0, 0), 0);
  ck_assert_msg(canfdi_sim_fault_shape(&s, 500000) < 1e-300, "incipient before t0");
  ck_assert_msg(canfdi_sim_fault_shape(&s, 1000000) < 1e-300, "incipient at t0");
  ck_assert_msg(fabs(canfdi_sim_fault_shape(&s, 2000000) - 0.5) < 1e-15, "incipient half way");
  ck_assert_msg(fabs(canfdi_sim_fault_shape(&s, 2500000) - 0.75) < 1e-15, "incipient 3/4");
  ck_assert_msg(fabs(canfdi_sim_fault_shape(&s, 3000000) - 1.0) < 1e-15, "incipient end");
  ck_assert_msg(fabs(canfdi_sim_fault_shape(&s, 9000000) - 1.0) < 1e-15, "incipient holds");

  /* intermittent: period 0.2 s, duty 0.25 from t0 = 1 s: on [1, 1.05), off
   * [1.05, 1.2), on [1.2, 1.25) ... */
  ck_assert_int_eq(
      canfdi_sim_fault_spec_make(&s, id, CANFDI_SIM_MODE_INTERMITTENT, 1.0, 0.2, 0, 0.2, 0.25), 0);
  ck_assert_msg(canfdi_sim_fault_shape(&s, 900000) < 0.5, "intermittent before t0");
  ck_assert_msg(canfdi_sim_fault_shape(&s, 1000000) > 0.5, "on at t0");
  ck_assert_msg(canfdi_sim_fault_shape(&s, 1049999) > 0.5, "on before duty end");
  ck_assert_msg(canfdi_sim_fault_shape(&s, 1050000) < 0.5, "off at duty end");
  ck_assert_msg(canfdi_sim_fault_shape(&s, 1199999) < 0.5, "off before period end");
  ck_assert_msg(canfdi_sim_fault_shape(&s, 1200000) > 0.5, "on at next period");
  ck_assert_msg(canfdi_sim_fault_shape(&s, 1250000) < 0.5, "off again");
  ck_assert_msg(canfdi_sim_fault_shape(&s, 101000000) > 0.5, "on after 500 periods");
}
END_TEST

START_TEST(shapes_reach_the_plant)
{
  static canfdi_sim_t sim;
  canfdi_sim_cfg_t cfg;
  canfdi_sim_fault_spec_t s;
  canfdi_sim_in_t in;
  unsigned k;

  memset(&in, 0, sizeof in);
  canfdi_sim_default_cfg(&cfg);
  ck_assert_int_eq(canfdi_sim_init(&sim, &cfg), CANFDI_OK);
  /* I_A offset drifting to 2 A over 1 s from 0.5 s */
  ck_assert_int_eq(canfdi_sim_fault_spec_make(&s, CANFDI_FAULT_DCM_IA_SENSOR_OFFSET,
                                              CANFDI_SIM_MODE_INCIPIENT, 0.5, 2.0, 1.0, 0, 0),
                   0);
  ck_assert_int_eq(canfdi_sim_add_fault(&sim, &s), CANFDI_OK);
  /* throttle frame CRC broken 30 ms of every 100 ms from 0.2 s */
  ck_assert_int_eq(canfdi_sim_fault_spec_make(&s, CANFDI_FAULT_COM_THR_CRC,
                                              CANFDI_SIM_MODE_INTERMITTENT, 0.2, 1.0, 0, 0.1, 0.3),
                   0);
  ck_assert_int_eq(canfdi_sim_add_fault(&sim, &s), CANFDI_OK);
  for (k = 1U; k <= 2000U; k++) {
    double want;
    bool crc_on;
    canfdi_sim_step(&sim, &in);
    want = (k <= 500U) ? 0.0 : ((k >= 1500U) ? 2.0 : (2.0 * (double)(k - 500U) / 1000.0));
    ck_assert_msg(fabs((sim.meas.analog[CANFDI_SIM_S_DCM_IA] - sim.meas.truth[CANFDI_SIM_S_DCM_IA]) -
                       want) < 1e-12,
                  "I_A offset at %u ms", k);
    crc_on = (k >= 200U) && (((k - 200U) % 100U) < 30U);
    ck_assert_msg(sim.fx.frame[CANFDI_SIM_FRAME_THR].bad_crc == crc_on, "crc flag at %u ms", k);
    ck_assert_msg(!sim.fx.frame[CANFDI_SIM_FRAME_DCM].bad_crc, "wrong frame at %u ms", k);
  }
}
END_TEST

START_TEST(simultaneous_faults_combine)
{
  canfdi_sim_fault_spec_t s[3];
  canfdi_sim_fx_t fx;
  ck_assert_int_eq(canfdi_sim_fault_spec_make(&s[0], CANFDI_FAULT_DCM_RA_UP, 0U, 0.0, 0.1, 0, 0, 0), 0);
  ck_assert_int_eq(canfdi_sim_fault_spec_make(&s[1], CANFDI_FAULT_DCM_RA_UP, 0U, 0.0, 0.1, 0, 0, 0), 0);
  ck_assert_int_eq(canfdi_sim_fault_spec_make(&s[2], CANFDI_FAULT_THR_TPS1_DRIFT, 0U, 0.0, 0.25, 0, 0, 0), 0);
  canfdi_sim_fault_effects(s, 3U, 0, &fx);
  ck_assert_msg(fabs(fx.dcm.ra_factor - 1.21) < 1e-12, "ra factor %g", fx.dcm.ra_factor);
  ck_assert_msg(fabs(fx.tps_offset_V[0] - 0.25) < 1e-12, "tps1 offset %g", fx.tps_offset_V[0]);
  ck_assert_uint_eq(fx.active_mask, ((uint64_t)1U << CANFDI_FAULT_DCM_RA_UP) |
                                        ((uint64_t)1U << CANFDI_FAULT_THR_TPS1_DRIFT));
}
END_TEST

/* ---- validation ------------------------------------------------------------- */

START_TEST(specs_are_validated)
{
  canfdi_sim_fault_spec_t s;
  ck_assert_int_eq(canfdi_sim_fault_find("dcm_ra_up"), (int)CANFDI_FAULT_DCM_RA_UP);
  ck_assert_int_eq(canfdi_sim_fault_find("com_thr_implausible"), (int)CANFDI_FAULT_COM_THR_IMPLAUSIBLE);
  ck_assert_int_lt(canfdi_sim_fault_find("dcm_ra_upp"), 0);
  ck_assert_int_eq(canfdi_sim_fault_mode_find("incipient"), (int)CANFDI_SIM_MODE_INCIPIENT);
  ck_assert_int_lt(canfdi_sim_fault_mode_find("sudden"), 0);
  /* the catalogue allows only abrupt|intermittent for binary faults */
  ck_assert_int_eq(canfdi_sim_fault_spec_make(&s, CANFDI_FAULT_DCM_BRIDGE_A_DEAD,
                                              CANFDI_SIM_MODE_INCIPIENT, 0.0, 1.0, 1.0, 0, 0),
                   -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_sim_fault_spec_make(&s, CANFDI_FAULT_DCM_FLUX_DOWN, 0U, 0.0, 1.5, 0, 0, 0),
                   -CANFDI_ERANGE);
  ck_assert_int_eq(canfdi_sim_fault_spec_make(&s, CANFDI_FAULT_DCM_RA_UP, 0U, 0.0, -0.1, 0, 0, 0),
                   -CANFDI_ERANGE);
  ck_assert_int_eq(canfdi_sim_fault_spec_make(&s, CANFDI_FAULT_DCM_SPEED_SENSOR_GAIN, 0U, 0.0, -1.0,
                                              0, 0, 0),
                   -CANFDI_ERANGE);
  ck_assert_int_eq(canfdi_sim_fault_spec_make(&s, CANFDI_FAULT_DCM_RA_UP, 0U, -1.0, 0.1, 0, 0, 0),
                   -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_sim_fault_spec_make(&s, CANFDI_FAULT_DCM_RA_UP, 0U, 0.0, NAN, 0, 0, 0),
                   -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_sim_fault_spec_make(&s, CANFDI_FAULT_DCM_RA_UP, CANFDI_SIM_MODE_INTERMITTENT,
                                              0.0, 0.1, 0, 0.1, 0.0),
                   -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_sim_fault_spec_make(&s, CANFDI_FAULT_DCM_RA_UP, CANFDI_SIM_MODE_INCIPIENT,
                                              0.0, 0.1, 0.0, 0, 0),
                   -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_sim_fault_spec_make(&s, (uint8_t)canfdi_fault_table_len, 0U, 0.0, 1.0, 0,
                                              0, 0),
                   -CANFDI_EINVAL);
}
END_TEST

static Suite *make_suite(void)
{
  Suite *s = suite_create("sim_fault");
  TCase *tc = tcase_create("catalogue");
  tcase_add_loop_test(tc, every_fault_changes_exactly_its_quantity, 0, (int)canfdi_fault_table_len);
  suite_add_tcase(s, tc);
  tc = tcase_create("shapes");
  tcase_add_test(tc, shapes_follow_definitions);
  tcase_add_test(tc, shapes_reach_the_plant);
  tcase_add_test(tc, simultaneous_faults_combine);
  suite_add_tcase(s, tc);
  tc = tcase_create("validation");
  tcase_add_test(tc, specs_are_validated);
  suite_add_tcase(s, tc);
  return s;
}

CANFDI_UNIT_MAIN(make_suite)
