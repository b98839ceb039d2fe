/*
 * test_sim_scenario.c — scenario parser and profiles
 * (host_sim/canfdi_sim_scenario.h, canfdi_sim_profile.h).
 */
#include <check.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "canfdi_sim_profile.h"
#include "canfdi_sim_scenario.h"
#include "core/canfdi_common.h"
#include "gen/canfdi_faults.h"
#include "unit_main.h"

static canfdi_sim_scn_t scn; /* ~17 kB: static */

static const char full_text[] =
    "# every directive once\n"
    "duration 12.5   # seconds\n"
    "seed 18446744073709551615\n"
    "noise dcm_ia 0.02\n"
    "noise thr_tps1 0.003\n"
    "init dcm_speed 50\n"
    "init dcm_winding 52.3\n"
    "init thr_angle 20\n"
    "param dcm_supply_V 36\n"
    "param dcm_thermal 0\n"
    "param thr_limp_home_deg 7\n"
    "\n"
    "speed const 10\n"
    "speed step 1 90\n"
    "speed ramp 2 4 -50\n"
    "angle step 0 10\n"
    "angle prbs 1 9 5 0.05 77\n"
    "angle sine 9 12 3 2\n"
    "load step 0.5 1.2\n"
    "load fan 0.004\n"
    "fault 3 dcm_ra_up incipient 0.2 4\n"
    "fault 5 com_thr_crc intermittent 1 0.1 0.3\n"
    "fault 6 thr_jammed abrupt default\n"
    "expect 8 dtc P1A10 confirmed\n"
    "expect 9 degradation thr fail_safe\n"
    "\texpect 1 no_dtc\n";

START_TEST(full_scenario_parses)
{
  canfdi_sim_scn_err_t err;
  ck_assert_msg(canfdi_sim_scn_parse(&scn, full_text, "full.scn", &err) == CANFDI_OK, "%s", err.msg);
  ck_assert_msg(fabs(scn.duration_s - 12.5) < 1e-12, "duration");
  ck_assert_uint_eq(scn.cfg.seed, UINT64_MAX);
  ck_assert_msg(fabs(scn.cfg.sigma[CANFDI_SIM_S_DCM_IA] - 0.02) < 1e-15, "noise");
  ck_assert_msg(scn.cfg.sigma[CANFDI_SIM_S_DCM_SPEED] < 1e-300, "default noise is 0");
  ck_assert(scn.has_init[CANFDI_SIM_INIT_DCM_SPEED] && !scn.has_init[CANFDI_SIM_INIT_DCM_CURRENT]);
  ck_assert_msg(fabs(scn.cfg.dcm.supply_V - 36.0) < 1e-12, "param");
  ck_assert(!scn.cfg.dcm.thermal);
  ck_assert_msg(fabs(scn.cfg.dcm.load_k_fan_Nms - 0.004) < 1e-15, "fan");
  ck_assert_uint_eq(scn.speed.n, 3U);
  ck_assert_uint_eq(scn.angle.n, 3U);
  ck_assert_uint_eq(scn.load.n, 1U);
  ck_assert_uint_eq(scn.n_faults, 3U);
  ck_assert_uint_eq(scn.faults[0].id, CANFDI_FAULT_DCM_RA_UP);
  ck_assert_uint_eq(scn.faults[0].mode, CANFDI_SIM_MODE_INCIPIENT);
  ck_assert_int_eq(scn.faults[0].ramp_us, 4000000);
  ck_assert_int_eq(scn.faults[1].period_us, 100000);
  ck_assert_int_eq(scn.faults[1].on_us, 30000);
  ck_assert_msg(fabs(scn.faults[2].magnitude - canfdi_fault_table[CANFDI_FAULT_THR_JAMMED].default_magnitude) < 1e-12,
                "default magnitude");
  ck_assert_uint_eq(scn.n_expects, 3U);
  ck_assert_str_eq(scn.expects[0].kind, "dtc");
  ck_assert_str_eq(scn.expects[0].arg1, "P1A10");
  ck_assert_str_eq(scn.expects[0].arg2, "confirmed");
  ck_assert_uint_eq(scn.expects[1].line, 25U);
  ck_assert_str_eq(scn.expects[2].kind, "no_dtc");
}
END_TEST

START_TEST(profiles_sum_their_components)
{
  canfdi_sim_scn_err_t err;
  double sp;
  double an;
  double ld;
  ck_assert_msg(canfdi_sim_scn_parse(&scn, full_text, "full.scn", &err) == CANFDI_OK, "%s", err.msg);
  /* speed = 10 + step(1 s, 90) + ramp(2..4 s, -50) */
  canfdi_sim_scn_eval(&scn, 400000, &sp, &an, &ld);
  ck_assert_msg(fabs(sp - 10.0) < 1e-12, "speed at 0.4 s: %g", sp);
  ck_assert_msg(fabs(ld) < 1e-300, "load before its step: %g", ld);
  canfdi_sim_scn_eval(&scn, 1000000, &sp, &an, &ld);
  ck_assert_msg(fabs(sp - 100.0) < 1e-12, "speed at 1 s: %g", sp);
  canfdi_sim_scn_eval(&scn, 3000000, &sp, &an, &ld);
  ck_assert_msg(fabs(sp - 75.0) < 1e-12, "speed at 3 s: %g", sp);
  ck_assert_msg(fabs(ld - 1.2) < 1e-12, "load: %g", ld);
  canfdi_sim_scn_eval(&scn, 8000000, &sp, &an, &ld);
  ck_assert_msg(fabs(sp - 50.0) < 1e-12, "speed at 8 s: %g", sp);
  /* angle: 10 + prbs(+-5) in [1, 9) s; 10 + 3 sin(2 pi 2 (t - 9)) in [9, 12) */
  canfdi_sim_scn_eval(&scn, 4000000, &sp, &an, &ld);
  ck_assert_msg((fabs(an - 15.0) < 1e-12) || (fabs(an - 5.0) < 1e-12), "prbs level %g", an);
  canfdi_sim_scn_eval(&scn, 9125000, &sp, &an, &ld);
  ck_assert_msg(fabs(an - 13.0) < 1e-9, "sine peak %g", an);
  canfdi_sim_scn_eval(&scn, 12000000, &sp, &an, &ld);
  ck_assert_msg(fabs(an - 10.0) < 1e-12, "after the sine window %g", an);
}
END_TEST

START_TEST(profile_clamps_to_range)
{
  canfdi_sim_profile_t p;
  canfdi_sim_profile_init(&p, 0.0, 90.0);
  ck_assert_int_eq(canfdi_sim_profile_add(&p, CANFDI_SIM_PROF_STEP, 0.0, 0.0, 80.0, 0.0, 0U), 0);
  ck_assert_int_eq(canfdi_sim_profile_add(&p, CANFDI_SIM_PROF_STEP, 1.0, 0.0, 30.0, 0.0, 0U), 0);
  ck_assert_int_eq(canfdi_sim_profile_add(&p, CANFDI_SIM_PROF_STEP, 2.0, 0.0, -200.0, 0.0, 0U), 0);
  ck_assert_msg(fabs(canfdi_sim_profile_eval(&p, 500000) - 80.0) < 1e-12, "80");
  ck_assert_msg(fabs(canfdi_sim_profile_eval(&p, 1500000) - 90.0) < 1e-12, "clamped high");
  ck_assert_msg(fabs(canfdi_sim_profile_eval(&p, 2500000)) < 1e-300, "clamped low");
  ck_assert_int_eq(canfdi_sim_profile_add(&p, CANFDI_SIM_PROF_RAMP, 2.0, 1.0, 1.0, 0.0, 0U),
                   -CANFDI_EINVAL);
}
END_TEST

START_TEST(prbs_is_a_seeded_binary_sequence)
{
  canfdi_sim_profile_t a;
  canfdi_sim_profile_t b;
  canfdi_sim_profile_t c;
  int64_t t;
  unsigned flips = 0U;
  unsigned bits = 0U;
  unsigned ones = 0U;
  unsigned differ = 0U;
  double prev = 0.0;
  canfdi_sim_profile_init(&a, -100.0, 100.0);
  canfdi_sim_profile_init(&b, -100.0, 100.0);
  canfdi_sim_profile_init(&c, -100.0, 100.0);
  ck_assert_int_eq(canfdi_sim_profile_add(&a, CANFDI_SIM_PROF_PRBS, 1.0, 100.0, 2.0, 0.01, 5U), 0);
  ck_assert_int_eq(canfdi_sim_profile_add(&b, CANFDI_SIM_PROF_PRBS, 1.0, 100.0, 2.0, 0.01, 5U), 0);
  ck_assert_int_eq(canfdi_sim_profile_add(&c, CANFDI_SIM_PROF_PRBS, 1.0, 100.0, 2.0, 0.01, 6U), 0);
  ck_assert_msg(fabs(canfdi_sim_profile_eval(&a, 999000)) < 1e-300, "before t0");
  for (t = 1000000; t < 41000000; t += 1000) {
    const double v = canfdi_sim_profile_eval(&a, t);
    ck_assert_msg((fabs(v - 2.0) < 1e-12) || (fabs(v + 2.0) < 1e-12), "level %g", v);
    ck_assert_msg(fabs(v - canfdi_sim_profile_eval(&b, t)) < 1e-300, "same seed differs");
    differ += (fabs(v - canfdi_sim_profile_eval(&c, t)) > 0.0) ? 1U : 0U;
    if (((t - 1000000) % 10000) == 0) {
      bits++;
      ones += (v > 0.0) ? 1U : 0U;
    } else {
      ck_assert_msg(fabs(v - prev) < 1e-300, "changed inside a bit at %lld us", (long long)t);
    }
    if ((t > 1000000) && (fabs(v - prev) > 0.0)) {
      flips++;
    }
    prev = v;
  }
  /* 4000 bits of a maximum-length sequence: ones/zeros balanced within a few
   * percent, about half the bit boundaries flip. */
  ck_assert_msg(abs((int)ones - (int)(bits / 2U)) < (int)(bits / 20U), "ones %u of %u", ones, bits);
  ck_assert_msg((flips > bits / 3U) && (flips < (2U * bits) / 3U), "flips %u", flips);
  ck_assert_msg(differ > 0U, "seeds 5 and 6 give the same sequence");
  /* going back in time restarts the register: same value again */
  ck_assert_msg(fabs(canfdi_sim_profile_eval(&a, 1234000) - canfdi_sim_profile_eval(&b, 1234000)) < 1e-300,
                "rewind");
}
END_TEST

/* ---- errors ---------------------------------------------------------------- */

typedef struct {
  const char *text;
  unsigned line;
  const char *needle;
} bad_t;

/* ten one-character tokens: eleven of them exceed the tokens a line may hold */
#define TEN_TOKENS " 1 1 1 1 1 1 1 1 1 1"


static const bad_t bad[] = {
    {"duration 1\nbogus 3\n", 2U, "unknown directive 'bogus'"},
    {"duration 1\nduration 2\n", 2U, "duplicate duration"},
    {"duration -1\n", 1U, "out of range"},
    {"duration abc\n", 1U, "not a number"},
    {"duration 1 2\n", 1U, "too many arguments"},
    {"seed 1\n", 0U, "missing 'duration"},
    {"duration 1\nseed -4\n", 2U, "seed"},
    {"duration 1\nnoise dcm_foo 0.1\n", 2U, "unknown sensor"},
    {"duration 1\nnoise dcm_ia 1e9\n", 2U, "out of range"},
    {"duration 1\ninit thr_angle 95\n", 2U, "out of range"},
    {"duration 1\nparam dcm_supply_V 100\n", 2U, "out of range"},
    {"duration 1\nparam dcm_nope 1\n", 2U, "unknown parameter"},
    {"duration 1\nspeed wobble 1\n", 2U, "unknown speed profile shape"},
    {"duration 1\nspeed ramp 2 1 10\n", 2U, "t1"},
    {"duration 1\nangle prbs 0 1 5 0.01\n", 2U, "too few arguments"},
    {"duration 1\nangle sine 0 1 5 0\n", 2U, "out of range"},
    {"duration 1\n\nfault 0.5 dcm_ra_upp abrupt 0.2\n", 3U, "unknown fault 'dcm_ra_upp'"},
    {"duration 1\nfault 0.5 dcm_ra_up sudden 0.2\n", 2U, "unknown fault mode"},
    {"duration 1\nfault 0.5 dcm_bridge_a_dead incipient 1 0.3\n", 2U, "not allowed"},
    {"duration 1\nfault 0.5 dcm_flux_down abrupt 2\n", 2U, "out of range"},
    {"duration 1\nfault 0.5 dcm_ra_up incipient 0.2\n", 2U, "too few arguments"},
    {"duration 1\nfault 0.5 dcm_ra_up intermittent 0.2 0.1 1.5\n", 2U, "duty"},
    {"duration 1\nfault 0.5 dcm_ra_up abrupt 0.2 7\n", 2U, "too many arguments"},
    {"fault 5 dcm_ra_up abrupt 0.2\nduration 1\n", 1U, "after the end"},
    {"duration 1\nexpect 0.5 dtc P9999\n", 2U, "unknown trouble code"},
    {"duration 1\nexpect 0.5 degradation dcm broken\n", 2U, "degradation"},
    {"duration 1\nexpect 0.5 weather sunny\n", 2U, "unknown expectation"},
    {"duration 1\nexpect 3 no_dtc\n", 2U, "after the end"},
    {"duration 1\nload fan 0.1\nload fan 0.2\n", 3U, "duplicate load fan"},
    {"duration 1\nexpect 0.5 dtc_status P0122 TF=2\n", 2U, "TF must be 0 or 1"},
    {"duration 1\nexpect 0.5 dtc_status P0122 TF=1,\n", 2U, "must be 0 or 1"},
    {"duration 1\nexpect 0.5 dtc_status P0122 XX=1\n", 2U, "expected NAME=0|1"},
    {"duration 1\nexpect 0.5 dtc_status P0122 TF=1,TF=0\n", 2U, "TF named twice"},
    {"duration 1\nexpect 0.5 dtc_status P0122 0x1FF\n", 2U, "status byte"},
    {"duration 1\nexpect 0.5 dtc_status P0122 0x+1\n", 2U, "status byte"},
    {"duration 1\nexpect 0.5 dtc_status P0122\n", 2U, "too few arguments"},
    {"duration 1\nexpect 0.5 occurrence P0122 256\n", 2U, "0..255"},
    {"duration 1\nexpect 0.5 occurrence P9999 1\n", 2U, "unknown trouble code"},
    {"duration 1\nexpect 0.5 freeze P0122 rpm 1 2\n", 2U, "unknown freeze-frame signal"},
    {"duration 1\nexpect 0.5 freeze P0122 time 2 1\n", 2U, "below min"},
    {"duration 1\ncycle\n", 2U, "too few arguments"},
    {"duration 1\ncycle 0.5 0.6\n", 2U, "too many arguments"},
    {"duration 1\ncycle 1\n", 2U, "at or after the end"},
    {"duration 1\ncycle 0.5\nclear 0.4\n", 3U, "time order"},
    {"duration 1\nclear 0.5 P9999\n", 2U, "unknown trouble code"},
    {"duration 1\npower_cycle -1\n", 2U, "out of range"},
    {"duration 1\nspeed step 0 1\xc3\xa9\n", 2U, "non-ASCII"},
    {"duration 1\nspeed step 0 1 2 3 4 5 6 7 8 9 10 11 12 13\n", 2U, "too many arguments"},
    {"duration 1\nspeed step" TEN_TOKENS TEN_TOKENS TEN_TOKENS TEN_TOKENS TEN_TOKENS TEN_TOKENS TEN_TOKENS
     TEN_TOKENS TEN_TOKENS TEN_TOKENS "\n", 2U, "too many tokens"},
    {"duration 5\nuds 1 phys\n", 2U, "too few arguments"},
    {"duration 5\nuds 1 can 3E 00\n", 2U, "phys (0x7E0) or func"},
    {"duration 5\nuds 1 phys 3E 0\n", 2U, "not a hex byte"},
    {"duration 5\nuds 1 phys expect 7E\n", 2U, "no request bytes"},
    {"duration 5\nuds 1 phys 3E expect\n", 2U, "expect what"},
    {"duration 5\nuds 1 phys 3E expect none 00\n", 2U, "nothing may follow"},
    {"duration 5\nuds 1 phys 3E expect * 00\n", 2U, "not a hex byte"},
    {"duration 5\nuds 1 func 22 D1 00 D1 01 D1 02 D1\n", 2U, "single frame"},
    {"duration 5\nuds 2 phys 3E 00\nuds 1 phys 3E 00\n", 3U, "time order"},
    {"duration 5\nuds 5 phys 3E 00\n", 2U, "at or after the end"},
};

/* uds lines: the request, the addressing and the expected response. */
START_TEST(uds_lines)
{
  canfdi_sim_scn_err_t err;
  const canfdi_sim_uds_t *u;
  ck_assert_int_eq(canfdi_sim_scn_parse(&scn, "duration 5\nuds 1 phys 3E 00 expect 7E 00\n"
                                              "uds 2 func 3E 80 expect none\nuds 2.5 phys 19 02 ff expect 59 02 FF .. *\n"
                                              "uds 3 phys 22 F1 95\n",
                                        "good.scn", &err),
                   CANFDI_OK);
  ck_assert_uint_eq(scn.n_uds, 4U);
  u = &scn.uds[0];
  ck_assert(!u->functional && u->judged && !u->none && !u->any_tail);
  ck_assert_int_eq(u->t_us, 1000000);
  ck_assert_uint_eq(u->req_len, 2U);
  ck_assert_uint_eq(u->req[0], 0x3EU);
  ck_assert_uint_eq(u->pat_len, 2U);
  ck_assert_uint_eq(u->pat[0], 0x7EU);
  ck_assert(scn.uds[1].functional && scn.uds[1].none);
  u = &scn.uds[2];
  ck_assert_uint_eq(u->req[2], 0xFFU);
  ck_assert(u->any_tail);
  ck_assert_uint_eq(u->pat_len, 4U);
  ck_assert_uint_eq(u->pat_any[3], 1U);
  ck_assert(!scn.uds[3].judged);
  ck_assert_uint_eq(scn.uds[3].line, 5U);
}
END_TEST

START_TEST(bad_input_names_file_and_line)
{
  canfdi_sim_scn_err_t err;
  char prefix[64];
  const bad_t *b = &bad[_i];
  ck_assert_int_eq(canfdi_sim_scn_parse(&scn, b->text, "bad.scn", &err), -CANFDI_EINVAL);
  (void)snprintf(prefix, sizeof prefix, "bad.scn:%u: ", b->line);
  ck_assert_msg(strncmp(err.msg, prefix, strlen(prefix)) == 0, "case %d: '%s' lacks '%s'", _i, err.msg,
                prefix);
  ck_assert_msg(strstr(err.msg, b->needle) != NULL, "case %d: '%s' lacks '%s'", _i, err.msg, b->needle);
}
END_TEST

START_TEST(overlong_line_rejected_in_text_and_file)
{
  static char text[600];
  canfdi_sim_scn_err_t err;
  FILE *f;
  const char *path = "build/unit/test_sim_scenario_long.scn";
  memset(text, 0, sizeof text);
  strcpy(text, "duration 1\n# ");
  memset(text + strlen(text), 'x', 300U);
  strcat(text, "\n");
  ck_assert_int_eq(canfdi_sim_scn_parse(&scn, text, "long.scn", &err), -CANFDI_EINVAL);
  ck_assert_msg(strstr(err.msg, "long.scn:2: line longer") != NULL, "%s", err.msg);
  f = fopen(path, "w");
  ck_assert_ptr_nonnull(f);
  ck_assert_int_ge(fputs(text, f), 0);
  ck_assert_int_eq(fclose(f), 0);
  ck_assert_int_eq(canfdi_sim_scn_load(&scn, path, &err), -CANFDI_EINVAL);
  ck_assert_msg(strstr(err.msg, ":2: line longer") != NULL, "%s", err.msg);
  (void)remove(path);
  ck_assert_int_eq(canfdi_sim_scn_load(&scn, "build/unit/does/not/exist.scn", &err), -CANFDI_EINVAL);
  ck_assert_msg(strstr(err.msg, "cannot open") != NULL, "%s", err.msg);
}
END_TEST

/* ---- the shipped examples and setup --------------------------------------- */

static const char *const examples[] = {
    "host_sim/scenarios/nominal.scn",       "host_sim/scenarios/dcm_ra_up.scn",
    "host_sim/scenarios/thr_tps1_drift.scn", "host_sim/scenarios/prbs_identification.scn",
    "host_sim/scenarios/comm_faults.scn",   "host_sim/scenarios/warmup.scn",
};

START_TEST(shipped_examples_parse)
{
  canfdi_sim_scn_err_t err;
  ck_assert_msg(canfdi_sim_scn_load(&scn, examples[_i], &err) == CANFDI_OK, "%s", err.msg);
}
END_TEST

START_TEST(setup_applies_initial_conditions_and_faults)
{
  static canfdi_sim_t sim;
  canfdi_sim_scn_err_t err;
  ck_assert_msg(canfdi_sim_scn_parse(&scn, full_text, "full.scn", &err) == CANFDI_OK, "%s", err.msg);
  ck_assert_int_eq(canfdi_sim_scn_setup(&scn, &sim), CANFDI_OK);
  ck_assert_msg(fabs(sim.dcm.w_rad_s - 50.0) < 1e-12, "speed");
  ck_assert_msg(fabs(canfdi_sim_thr_angle_deg(&sim.thr) - 20.0) < 1e-12, "angle");
  /* 52.3 C makes the cold 1.35 Ohm about 1.52 Ohm */
  ck_assert_msg(fabs(sim.dcm.ra_ohm - (1.35 * (1.0 + (0.0039 * 32.3)))) < 1e-9, "R_A %g", sim.dcm.ra_ohm);
  ck_assert_uint_eq(sim.n_faults, 3U);
  ck_assert_msg(fabs(sim.meas.truth[CANFDI_SIM_S_DCM_SUPPLY] - 36.0) < 1e-12, "supply");
}
END_TEST

START_TEST(dtc_directives_parse)
{
  static const char text[] = "duration 5\n"
                             "cycle 1\n"
                             "clear 2\n"
                             "clear 2 P0122\n"
                             "clear 2.5 all\n"
                             "power_cycle 3.0004\n"
                             "expect 1 dtc_status P0122 TF=1,WIR=0,TNCTOC=1\n"
                             "expect 1 dtc_status U1A01 0xaf\n"
                             "expect 2 occurrence P0122 3\n"
                             "expect 3 freeze P0122 thr_angle -1 25.5\n";
  canfdi_sim_scn_err_t err;
  ck_assert_msg(canfdi_sim_scn_parse(&scn, text, "dtc.scn", &err) == CANFDI_OK, "%s", err.msg);
  ck_assert_uint_eq(scn.n_actions, 5U);
  ck_assert_uint_eq(scn.actions[0].kind, CANFDI_SIM_ACT_CYCLE);
  ck_assert_int_eq(scn.actions[0].t_us, 1000000);
  ck_assert_uint_eq(scn.actions[1].kind, CANFDI_SIM_ACT_CLEAR);
  ck_assert_str_eq(scn.actions[1].code, "");
  ck_assert_str_eq(scn.actions[2].code, "P0122");
  ck_assert_str_eq(scn.actions[3].code, "");
  ck_assert_uint_eq(scn.actions[4].kind, CANFDI_SIM_ACT_POWER_CYCLE);
  ck_assert_int_eq(scn.actions[4].t_us, 3000400);
  ck_assert_uint_eq(scn.actions[4].line, 6U);
  ck_assert_uint_eq(scn.n_expects, 4U);
  ck_assert_str_eq(scn.expects[0].kind, "dtc_status");
  ck_assert_uint_eq(scn.expects[0].st_mask, 0xC1U);
  ck_assert_uint_eq(scn.expects[0].st_value, 0x41U);
  ck_assert_str_eq(scn.expects[0].arg2, "TF=1,WIR=0,TNCTOC=1");
  ck_assert_uint_eq(scn.expects[1].st_mask, 0xFFU);
  ck_assert_uint_eq(scn.expects[1].st_value, 0xAFU);
  ck_assert_str_eq(scn.expects[2].kind, "occurrence");
  ck_assert_msg(fabs(scn.expects[2].lo - 3.0) < 1e-12, "%g", scn.expects[2].lo);
  ck_assert_uint_eq(scn.expects[3].ff_signal, CANFDI_SIM_FF_THR_ANGLE);
  ck_assert_msg(fabs(scn.expects[3].lo + 1.0) < 1e-12, "%g", scn.expects[3].lo);
  ck_assert_msg(fabs(scn.expects[3].hi - 25.5) < 1e-12, "%g", scn.expects[3].hi);
  ck_assert_str_eq(canfdi_sim_ff_name(CANFDI_SIM_FF_DEG_THR), "deg_thr");
  ck_assert_str_eq(canfdi_sim_status_bit_name(7U), "WIR");
  ck_assert_str_eq(canfdi_sim_status_bit_name(8U), "?");
}
END_TEST

static Suite *make_suite(void)
{
  Suite *s = suite_create("sim_scenario");
  TCase *tc = tcase_create("parse");
  tcase_add_test(tc, full_scenario_parses);
  tcase_add_test(tc, dtc_directives_parse);
  tcase_add_test(tc, uds_lines);
  tcase_add_test(tc, setup_applies_initial_conditions_and_faults);
  tcase_add_loop_test(tc, shipped_examples_parse, 0, (int)(sizeof examples / sizeof examples[0]));
  suite_add_tcase(s, tc);
  tc = tcase_create("profiles");
  tcase_add_test(tc, profiles_sum_their_components);
  tcase_add_test(tc, profile_clamps_to_range);
  tcase_add_test(tc, prbs_is_a_seeded_binary_sequence);
  suite_add_tcase(s, tc);
  tc = tcase_create("errors");
  tcase_add_loop_test(tc, bad_input_names_file_and_line, 0, (int)(sizeof bad / sizeof bad[0]));
  tcase_add_test(tc, overlong_line_rejected_in_text_and_file);
  suite_add_tcase(s, tc);
  return s;
}

CANFDI_UNIT_MAIN(make_suite)
