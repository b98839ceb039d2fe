/*
 * test_actmgr.c — unit tests of firmware/ft/canfdi_actmgr: bridge A -> B
 * switchover, the built-in plausibility check (detects a dead bridge in
 * exactly bridge_fail_steps samples, never fires on a healthy bridge under
 * random command transients, noise, a measurement lag inside the window or
 * an unconfirmed 2 V U_A sensor offset), drive off when both bridges fail,
 * the throttle decision table (fail-operational on one TPS, limp-home on
 * two, on a jam, a motor-circuit fault, a lost frame, a persistently
 * invalid vote), hold until clear, the clear rule, a property test of
 * monotone degradation under random inputs, and closed-loop runs with the
 * host_sim plants (bridge A killed at speed; both bridges killed; a
 * fault-free speed profile; both TPS lost -> limp-home angle).
 *
 * The healthy-bridge model of the open-loop tests is the averaged-PWM
 * bridge of the design (canfdi_sim_bridge.h): the terminal voltage is the
 * command clamped to the supply, seen by the U_A sensor one step later
 * (lockstep: command, plant step, sample), with Gaussian noise sigma 50 mV
 * and quantised to the DBC's 15 mV. A dead bridge delivers 0 V.
 */
#include <check.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>

#include "canfdi_sim.h"
#include "canfdi_sim_refctl.h"
#include "ft/canfdi_actmgr.h"
#include "unit_main.h"

#define Q16(x) ((int32_t)lround((x) * 65536.0))
#define BIT(id) CANFDI_FAULT_BIT(id)

static double v_of_q16(int32_t q) { return (double)q / 65536.0; }

/* xorshift64* and Box-Muller: a fixed PRNG so failures reproduce. */
static uint64_t rng_state;
static void rng_seed(uint64_t s) { rng_state = (s != 0U) ? s : 0x9E3779B97F4A7C15ULL; }
static uint32_t rng_u32(void)
{
  rng_state ^= rng_state >> 12;
  rng_state ^= rng_state << 25;
  rng_state ^= rng_state >> 27;
  return (uint32_t)((rng_state * 0x2545F4914F6CDD1DULL) >> 32);
}
static double rng_unit(void) { return ((double)rng_u32() + 0.5) / 4294967296.0; }
static double rng_gauss(void)
{
  return sqrt(-2.0 * log(rng_unit())) * cos(6.283185307179586 * rng_unit());
}

static canfdi_actmgr_cfg_t cfg_with(uint16_t fail_steps, uint8_t lag_min, uint8_t lag_max)
{
  canfdi_actmgr_cfg_t c;
  canfdi_actmgr_default_cfg(&c);
  c.dcm_bridge_fail_steps = fail_steps;
  c.dcm_lag_min_steps = lag_min;
  c.dcm_lag_max_steps = lag_max;
  return c;
}

/* A decided, healthy three-way vote. */
static canfdi_vote_out_t vote_ok(void)
{
  canfdi_vote_out_t v = {0};
  v.angle_rad_q16 = Q16(0.3);
  v.status = (uint8_t)CANFDI_VOTE_THREE;
  v.n_available = 3U;
  v.used_mask = CANFDI_VOTE_BIT_TPS1 | CANFDI_VOTE_BIT_TPS2;
  v.valid = true;
  return v;
}

static canfdi_actmgr_in_t in_nominal(void)
{
  canfdi_actmgr_in_t in = {0};
  in.dcm_u_ctrl_V_q16 = Q16(20.0);
  in.dcm_ua_V_q16 = Q16(20.0);
  in.dcm_supply_V_q16 = Q16(48.0);
  in.dcm_ua_valid = true;
  in.dcm_supply_valid = true;
  in.thr_u_ctrl_V_q16 = Q16(2.0);
  return in;
}

/* --------------------------------------------------- bridge + sensor model */

#define TB_HIST 8U
typedef struct {
  double cmd[TB_HIST]; /* terminal voltages delivered, newest at [k % TB_HIST] */
  uint32_t k;
  uint32_t lag;        /* sensor sees the voltage of `lag` steps ago */
  double supply_V;
  double sigma_V;
  double offset_V;     /* U_A sensor offset */
} tb_t;

static void tb_init(tb_t *b, uint32_t lag)
{
  uint32_t i;
  for (i = 0U; i < TB_HIST; i++) {
    b->cmd[i] = 0.0;
  }
  b->k = 0U;
  b->lag = lag;
  b->supply_V = 48.0;
  b->sigma_V = 0.05;
  b->offset_V = 0.0;
}

/* The U_A sample of this step (before the manager runs). */
static int32_t tb_measure(const tb_t *b)
{
  /* cmd[k % TB_HIST] is the newest delivered voltage (lag 1) */
  const double u = b->cmd[(b->k + TB_HIST + 1U - b->lag) % TB_HIST];
  const double noisy = u + b->offset_V + b->sigma_V * rng_gauss();
  return Q16(0.015 * round(noisy / 0.015));
}

/* Apply the manager's output for the coming step; dead bridges deliver 0 V,
 * a disabled bridge is taken as 0 V as well (not checked by the manager). */
static void tb_apply(tb_t *b, const canfdi_actmgr_out_t *o, bool a_dead, bool b_dead)
{
  double u = 0.0;
  if (o->dcm.enable) {
    const bool dead = (o->dcm.bridge == CANFDI_ACTMGR_BRIDGE_A) ? a_dead : b_dead;
    u = dead ? 0.0 : fmax(-b->supply_V, fmin(b->supply_V, v_of_q16(o->dcm.u_cmd_V_q16)));
  }
  b->k++;
  b->cmd[b->k % TB_HIST] = u;
}

/* ------------------------------------------------------------------ config */

START_TEST(test_cfg_domain)
{
  canfdi_actmgr_cfg_t c = cfg_with(3U, 1U, 1U);
  canfdi_actmgr_t m;
  bool ok = false;
  switch (_i) {
  case 0: ok = true; break;
  case 1: c.dcm_u_max_V_q16 = 0; break;
  case 2: c.dcm_check_min_V_q16 = 0; break;
  case 3: c.dcm_deliver_ratio_q16 = 0; break;
  case 4: c.dcm_deliver_ratio_q16 = 65536; break;
  case 5: c.dcm_lag_min_steps = 0U; break;
  case 6: c.dcm_lag_min_steps = 2U; c.dcm_lag_max_steps = 1U; break;
  case 7: c.dcm_lag_max_steps = CANFDI_ACTMGR_UA_HIST + 1U; break;
  case 8: c.dcm_bridge_fail_steps = 0U; break;
  case 9: c.dcm_bridge_fail_steps = 32768U; break;
  case 10: c.thr_u_max_V_q16 = -1; break;
  case 11: c.thr_vote_loss_steps = 0U; break;
  case 12: c.dcm_lag_min_steps = 1U; c.dcm_lag_max_steps = CANFDI_ACTMGR_UA_HIST; ok = true; break;
  default: break;
  }
  ck_assert_int_eq(canfdi_actmgr_init(&m, &c), ok ? CANFDI_OK : -CANFDI_EINVAL);
  if (!ok) {
    canfdi_actmgr_in_t in = in_nominal();
    canfdi_vote_out_t v = vote_ok();
    canfdi_actmgr_out_t o;
    ck_assert_int_eq(canfdi_actmgr_step(&m, &in, &v, &o), -CANFDI_EINVAL);
    ck_assert(!o.dcm.enable && !o.thr.enable); /* the safe side */
  }
}
END_TEST

START_TEST(test_null_args)
{
  canfdi_actmgr_cfg_t c = cfg_with(3U, 1U, 1U);
  canfdi_actmgr_t m;
  canfdi_actmgr_in_t in = in_nominal();
  canfdi_vote_out_t v = vote_ok();
  canfdi_actmgr_out_t o;
  ck_assert_int_eq(canfdi_actmgr_init(NULL, &c), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_actmgr_init(&m, NULL), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_actmgr_init(&m, &c), CANFDI_OK);
  ck_assert_int_eq(canfdi_actmgr_step(&m, NULL, &v, &o), -CANFDI_EINVAL);
  ck_assert(!o.dcm.enable && !o.thr.enable && o.thr_limp_home);
  ck_assert_uint_eq(o.dcm.bridge, CANFDI_ACTMGR_BRIDGE_NONE);
  ck_assert_uint_eq(o.dcm_state, CANFDI_DEG_FAIL_SAFE);
  ck_assert_uint_eq(o.dcm_ctrl_mode, CANFDI_CTRL_OFF);
  ck_assert_int_eq(canfdi_actmgr_step(&m, &in, NULL, &o), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_actmgr_step(&m, &in, &v, NULL), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_actmgr_step(NULL, &in, &v, &o), -CANFDI_EINVAL);
  ck_assert_uint_eq(canfdi_actmgr_diag(&m).rejected, 3U);
  ck_assert_int_eq(canfdi_actmgr_clear(&m, 0U, CANFDI_DEGRADE_CLEAR_TESTER, 0U, 0U), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_actmgr_clear(&m, 4U, CANFDI_DEGRADE_CLEAR_TESTER, 0U, 0U), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_actmgr_clear(&m, 1U, 0x12U, 0U, 0U), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_actmgr_clear(NULL, 1U, CANFDI_DEGRADE_CLEAR_TESTER, 0U, 0U),
                   -CANFDI_EINVAL);
  ck_assert(canfdi_actmgr_degrade_dcm(NULL) == NULL);
  ck_assert(canfdi_actmgr_degrade_thr(NULL) == NULL);
  ck_assert_uint_eq(canfdi_actmgr_diag(NULL).steps, 0U);
  canfdi_actmgr_default_cfg(NULL);
  /* nominal step: bridge A, both enabled, NORMAL */
  ck_assert_int_eq(canfdi_actmgr_step(&m, &in, &v, &o), CANFDI_OK);
  ck_assert(o.dcm.enable && o.thr.enable && !o.thr_limp_home);
  ck_assert_uint_eq(o.dcm.bridge, CANFDI_ACTMGR_BRIDGE_A);
  ck_assert_int_eq(o.dcm.u_cmd_V_q16, in.dcm_u_ctrl_V_q16);
  ck_assert_int_eq(o.thr.u_cmd_V_q16, in.thr_u_ctrl_V_q16);
  ck_assert(!o.dcm_track && !o.thr_track);
  ck_assert_uint_eq(o.dcm_ctrl_mode, CANFDI_CTRL_RUN);
  ck_assert_uint_eq(o.thr_ctrl_mode, CANFDI_CTRL_RUN);
  ck_assert_uint_eq(o.dcm_state, CANFDI_DEG_NORMAL);
  ck_assert_uint_eq(o.thr_state, CANFDI_DEG_NORMAL);
}
END_TEST

/* ------------------------------------------------- healthy bridge transients */

typedef struct {
  uint8_t lag_min, lag_max; /* manager window */
  uint32_t lag;             /* true sensor lag */
  double offset_V;          /* unconfirmed U_A sensor offset */
} healthy_case_t;

static const healthy_case_t healthy_cases[] = {
    {1U, 1U, 1U, 0.0}, {1U, 2U, 1U, 0.0}, {1U, 2U, 2U, 0.0},
    {2U, 3U, 3U, 0.0}, {1U, 1U, 1U, 2.0}, {1U, 1U, 1U, -2.0},
};
#define N_HEALTHY ((int)(sizeof healthy_cases / sizeof healthy_cases[0]))

START_TEST(test_healthy_bridge_never_fails)
{
  /* 60 000 steps of random commands: levels in +-60 V (beyond the 48 V
   * supply too) held 1..20 steps, every 8th level a step-by-step
   * alternation between +-u (the hardest transient), noise and
   * quantisation. Not a single implausible step is allowed. */
  const healthy_case_t *k = &healthy_cases[_i];
  canfdi_actmgr_cfg_t c = cfg_with(1U, k->lag_min, k->lag_max); /* most sensitive */
  canfdi_actmgr_t m;
  canfdi_actmgr_in_t in = in_nominal();
  canfdi_vote_out_t v = vote_ok();
  canfdi_actmgr_out_t o;
  tb_t b;
  uint32_t step = 0U;
  uint32_t evaluated_levels = 0U;

  rng_seed(0xC0FFEEU + (uint64_t)_i);
  tb_init(&b, k->lag);
  b.offset_V = k->offset_V;
  ck_assert_int_eq(canfdi_actmgr_init(&m, &c), CANFDI_OK);
  while (step < 60000U) {
    const double level = 120.0 * rng_unit() - 60.0;
    const uint32_t hold = 1U + (rng_u32() % 20U);
    const bool alternate = (rng_u32() % 8U) == 0U;
    uint32_t h;
    if (fabs(level) >= 6.0) {
      evaluated_levels++;
    }
    for (h = 0U; h < hold; h++, step++) {
      in.dcm_u_ctrl_V_q16 = Q16((alternate && ((h % 2U) != 0U)) ? -level : level);
      in.dcm_ua_V_q16 = tb_measure(&b);
      in.now_ms = step;
      ck_assert_int_eq(canfdi_actmgr_step(&m, &in, &v, &o), CANFDI_OK);
      ck_assert_uint_eq(o.dcm.bridge, CANFDI_ACTMGR_BRIDGE_A);
      tb_apply(&b, &o, false, false);
    }
  }
  ck_assert_uint_eq(canfdi_actmgr_diag(&m).ua_implausible, 0U);
  ck_assert_uint_eq(o.detected, 0U);
  ck_assert_uint_eq(o.dcm_state, CANFDI_DEG_NORMAL);
  ck_assert_uint_gt(evaluated_levels, 3000U);
}
END_TEST

/* ---------------------------------------------------- dead bridge detection */

static const uint16_t fail_steps_cases[] = {1U, 3U, 5U};

START_TEST(test_dead_bridge_a_switch)
{
  /* _i: fail steps (3) x command sign (2). A dies after 50 healthy steps at
   * +-20 V; the switch to B must be in the step of the fail_steps-th 0 V
   * sample, and only then. */
  const uint16_t n = fail_steps_cases[_i / 2];
  const double u = ((_i % 2) == 0) ? 20.0 : -20.0;
  canfdi_actmgr_cfg_t c = cfg_with(n, 1U, 1U);
  canfdi_actmgr_t m;
  canfdi_actmgr_in_t in = in_nominal();
  canfdi_vote_out_t v = vote_ok();
  canfdi_actmgr_out_t o;
  canfdi_degrade_transition_t t;
  tb_t b;
  uint32_t step;
  uint32_t zero_samples = 0U;
  uint32_t switched_at = 0U;

  rng_seed(77U + (uint64_t)_i);
  tb_init(&b, 1U);
  ck_assert_int_eq(canfdi_actmgr_init(&m, &c), CANFDI_OK);
  in.dcm_u_ctrl_V_q16 = Q16(u);
  for (step = 0U; step < 400U; step++) {
    const bool a_dead = step >= 50U;
    in.dcm_ua_V_q16 = tb_measure(&b);
    in.now_ms = step;
    if ((step > 50U) && (fabs(v_of_q16(in.dcm_ua_V_q16)) < 1.0)) {
      zero_samples++;
    }
    ck_assert_int_eq(canfdi_actmgr_step(&m, &in, &v, &o), CANFDI_OK);
    if (o.bridge_switched) {
      ck_assert_uint_eq(switched_at, 0U); /* once */
      switched_at = step;
      ck_assert_uint_eq(zero_samples, n);
      ck_assert(o.dcm_track);
      ck_assert_uint_eq(o.dcm_ctrl_mode, CANFDI_CTRL_TRACK);
      ck_assert_int_eq(o.dcm_track_V_q16, in.dcm_u_ctrl_V_q16); /* command continues */
    }
    if ((switched_at == 0U) && !o.bridge_switched) {
      ck_assert_uint_eq(o.dcm.bridge, CANFDI_ACTMGR_BRIDGE_A);
      ck_assert_uint_eq(o.dcm_state, CANFDI_DEG_NORMAL);
    } else {
      /* from the decision step on: B, enabled, degraded (fail-operational) */
      ck_assert_uint_eq(o.dcm.bridge, CANFDI_ACTMGR_BRIDGE_B);
      ck_assert(o.dcm.enable);
      ck_assert_int_eq(o.dcm.u_cmd_V_q16, in.dcm_u_ctrl_V_q16);
      ck_assert_uint_eq(o.dcm_state, CANFDI_DEG_DEGRADED);
      ck_assert_uint_eq(o.dcm_reason, CANFDI_FAULT_DCM_BRIDGE_A_DEAD);
      ck_assert_uint_eq(o.detected, BIT(CANFDI_FAULT_DCM_BRIDGE_A_DEAD));
    }
    tb_apply(&b, &o, a_dead, false);
  }
  /* the first 0 V sample is at step 51 (lag 1), the n-th at 50 + n */
  ck_assert_uint_eq(switched_at, 50U + n);
  ck_assert_uint_eq(canfdi_actmgr_diag(&m).bridge_switches, 1U);
  ck_assert_int_eq(canfdi_degrade_log_get(canfdi_actmgr_degrade_dcm(&m), 0U, &t), CANFDI_OK);
  ck_assert_uint_eq(t.t_ms, 50U + n);
  ck_assert_uint_eq(t.to, CANFDI_DEG_DEGRADED);
}
END_TEST

START_TEST(test_diagnosis_switch_same_step)
{
  /* diagnosis confirms bridge_a_dead: B in that very step, even with a
   * command too small for the built-in check; latched after the bit goes */
  canfdi_actmgr_cfg_t c = cfg_with(3U, 1U, 1U);
  canfdi_actmgr_t m;
  canfdi_actmgr_in_t in = in_nominal();
  canfdi_vote_out_t v = vote_ok();
  canfdi_actmgr_out_t o;
  ck_assert_int_eq(canfdi_actmgr_init(&m, &c), CANFDI_OK);
  in.dcm_u_ctrl_V_q16 = Q16(1.0);
  in.dcm_ua_V_q16 = Q16(1.0);
  ck_assert_int_eq(canfdi_actmgr_step(&m, &in, &v, &o), CANFDI_OK);
  ck_assert_uint_eq(o.dcm.bridge, CANFDI_ACTMGR_BRIDGE_A);
  in.faults = BIT(CANFDI_FAULT_DCM_BRIDGE_A_DEAD);
  ck_assert_int_eq(canfdi_actmgr_step(&m, &in, &v, &o), CANFDI_OK);
  ck_assert(o.bridge_switched);
  ck_assert_uint_eq(o.dcm.bridge, CANFDI_ACTMGR_BRIDGE_B);
  ck_assert_uint_eq(o.detected, 0U); /* not its own finding */
  in.faults = 0U;
  ck_assert_int_eq(canfdi_actmgr_step(&m, &in, &v, &o), CANFDI_OK);
  ck_assert(!o.bridge_switched);
  ck_assert_uint_eq(o.dcm.bridge, CANFDI_ACTMGR_BRIDGE_B);
  ck_assert_uint_eq(o.dcm_state, CANFDI_DEG_DEGRADED);
  /* diagnosis: both dead -> off at once */
  in.faults = BIT(CANFDI_FAULT_DCM_BRIDGES_DEAD);
  ck_assert_int_eq(canfdi_actmgr_step(&m, &in, &v, &o), CANFDI_OK);
  ck_assert(!o.dcm.enable);
  ck_assert_uint_eq(o.dcm.bridge, CANFDI_ACTMGR_BRIDGE_NONE);
  ck_assert_int_eq(o.dcm.u_cmd_V_q16, 0);
  ck_assert_uint_eq(o.dcm_state, CANFDI_DEG_FAIL_SAFE);
  ck_assert_uint_eq(o.dcm_reason, CANFDI_FAULT_DCM_BRIDGES_DEAD);
  ck_assert(o.dcm_track);
  ck_assert_int_eq(o.dcm_track_V_q16, 0);
  ck_assert_uint_eq(o.dcm_ctrl_mode, CANFDI_CTRL_OFF);
  ck_assert_uint_eq(canfdi_actmgr_diag(&m).drive_offs, 1U);
}
END_TEST

START_TEST(test_both_bridges_die)
{
  /* A dies at step 50, B at step 200 (_i: fail steps). After the switch
   * the window refills with B's commands; B is failed on its n-th 0 V
   * sample and the drive goes off in that step, for good. */
  const uint16_t n = fail_steps_cases[_i];
  canfdi_actmgr_cfg_t c = cfg_with(n, 1U, 1U);
  canfdi_actmgr_t m;
  canfdi_actmgr_in_t in = in_nominal();
  canfdi_vote_out_t v = vote_ok();
  canfdi_actmgr_out_t o;
  tb_t b;
  uint32_t step;
  uint32_t off_at = 0U;

  rng_seed(5U);
  tb_init(&b, 1U);
  ck_assert_int_eq(canfdi_actmgr_init(&m, &c), CANFDI_OK);
  in.dcm_u_ctrl_V_q16 = Q16(-30.0);
  for (step = 0U; step < 400U; step++) {
    in.dcm_ua_V_q16 = tb_measure(&b);
    in.now_ms = step;
    ck_assert_int_eq(canfdi_actmgr_step(&m, &in, &v, &o), CANFDI_OK);
    if (!o.dcm.enable && (off_at == 0U)) {
      off_at = step;
    }
    if (off_at != 0U) {
      ck_assert(!o.dcm.enable);
      ck_assert_uint_eq(o.dcm.bridge, CANFDI_ACTMGR_BRIDGE_NONE);
      ck_assert_int_eq(o.dcm.u_cmd_V_q16, 0);
      ck_assert_uint_eq(o.dcm_state, CANFDI_DEG_FAIL_SAFE);
      ck_assert_uint_eq(o.dcm_reason, CANFDI_FAULT_DCM_BRIDGES_DEAD);
      ck_assert_uint_eq(o.detected, BIT(CANFDI_FAULT_DCM_BRIDGE_A_DEAD) |
                                        BIT(CANFDI_FAULT_DCM_BRIDGES_DEAD));
    }
    tb_apply(&b, &o, step >= 50U, step >= 200U);
  }
  ck_assert_uint_eq(off_at, 200U + n);
  ck_assert_uint_eq(canfdi_actmgr_diag(&m).drive_offs, 1U);
  ck_assert_uint_eq(canfdi_actmgr_diag(&m).bridge_switches, 1U);
}
END_TEST

typedef struct {
  const char *name;
  double u_small_V; /* command while dead */
  bool ua_valid;
  uint32_t faults;
  uint32_t switch_step; /* after lifting: 1 more step when the window still
                           holds the small command */
} blind_case_t;

static const blind_case_t blind_cases[] = {
    {"command below check_min", 5.9, true, 0U, 4U},
    {"U_A invalid", 20.0, false, 0U, 3U},
    {"U_A sensor fault confirmed", 20.0, true, BIT(CANFDI_FAULT_DCM_UA_SENSOR_OFFSET), 3U},
};

START_TEST(test_check_blind_conditions)
{
  /* Where the check must not judge: no detection however long the bridge
   * is dead; detection in n samples once the condition is lifted. */
  const blind_case_t *k = &blind_cases[_i];
  canfdi_actmgr_cfg_t c = cfg_with(3U, 1U, 1U);
  canfdi_actmgr_t m;
  canfdi_actmgr_in_t in = in_nominal();
  canfdi_vote_out_t v = vote_ok();
  canfdi_actmgr_out_t o;
  tb_t b;
  uint32_t step;
  rng_seed(9U);
  tb_init(&b, 1U);
  ck_assert_int_eq(canfdi_actmgr_init(&m, &c), CANFDI_OK);
  for (step = 0U; step < 1000U; step++) {
    in.dcm_u_ctrl_V_q16 = Q16(k->u_small_V);
    in.dcm_ua_V_q16 = tb_measure(&b);
    in.dcm_ua_valid = k->ua_valid;
    in.faults = k->faults;
    ck_assert_int_eq(canfdi_actmgr_step(&m, &in, &v, &o), CANFDI_OK);
    ck_assert_msg(o.dcm.bridge == CANFDI_ACTMGR_BRIDGE_A, "%s", k->name);
    tb_apply(&b, &o, true, false);
  }
  ck_assert_uint_eq(canfdi_actmgr_diag(&m).ua_implausible, 0U);
  in.dcm_u_ctrl_V_q16 = Q16(20.0);
  in.dcm_ua_valid = true;
  in.faults = 0U;
  for (step = 1U; step <= k->switch_step; step++) {
    in.dcm_ua_V_q16 = tb_measure(&b);
    ck_assert_int_eq(canfdi_actmgr_step(&m, &in, &v, &o), CANFDI_OK);
    ck_assert_msg((o.dcm.bridge == CANFDI_ACTMGR_BRIDGE_B) == (step == k->switch_step),
                  "%s step %u", k->name, (unsigned)step);
    tb_apply(&b, &o, true, false);
  }
}
END_TEST

static const double weak_fraction[] = {0.0, 0.3, 0.49, 0.51, 0.8, 1.0, -0.5};

/* canfdi_actmgr_set_applied: the newest history entry becomes what the
 * bridge got; the check of the next step judges it (an applied -30 V that
 * the measured +20 V does not show is implausible), and an unknown command
 * (NULL) is never judged. Before the first step there is nothing to
 * replace. */
START_TEST(test_set_applied_history)
{
  canfdi_actmgr_t m;
  canfdi_actmgr_cfg_t c = cfg_with(3U, 1U, 1U);
  canfdi_actmgr_in_t in = in_nominal();
  canfdi_actmgr_out_t out;
  const canfdi_vote_out_t v = vote_ok();
  canfdi_actmgr_dcm_cmd_t cmd = {true, (uint8_t)CANFDI_ACTMGR_BRIDGE_A, Q16(-30.0)};
  uint32_t k;
  ck_assert_int_eq(canfdi_actmgr_set_applied(NULL, &cmd), -CANFDI_EINVAL);
  ck_assert_int_eq(canfdi_actmgr_init(&m, &c), CANFDI_OK);
  ck_assert_int_eq(canfdi_actmgr_set_applied(&m, &cmd), CANFDI_OK);
  ck_assert_uint_eq(m.hist_count, 0U);
  /* healthy: +20 V commanded and measured */
  for (k = 0U; k < 10U; k++) {
    ck_assert_int_eq(canfdi_actmgr_step(&m, &in, &v, &out), CANFDI_OK);
  }
  ck_assert_uint_eq(canfdi_actmgr_diag(&m).ua_implausible, 0U);
  /* unknown: not judged, however long */
  for (k = 0U; k < 10U; k++) {
    ck_assert_int_eq(canfdi_actmgr_set_applied(&m, NULL), CANFDI_OK);
    ck_assert_int_eq(canfdi_actmgr_step(&m, &in, &v, &out), CANFDI_OK);
  }
  ck_assert_uint_eq(canfdi_actmgr_diag(&m).ua_implausible, 0U);
  /* applied -30 V, measured +20 V: bridge A failed after 3 samples */
  for (k = 0U; k < 3U; k++) {
    ck_assert(!m.bridge_failed[0]);
    ck_assert_int_eq(canfdi_actmgr_set_applied(&m, &cmd), CANFDI_OK);
    ck_assert_int_eq(canfdi_actmgr_step(&m, &in, &v, &out), CANFDI_OK);
  }
  ck_assert(m.bridge_failed[0]);
  ck_assert_uint_eq(canfdi_actmgr_diag(&m).ua_implausible, 3U);
  ck_assert_uint_eq(out.dcm.bridge, CANFDI_ACTMGR_BRIDGE_B);
}
END_TEST

START_TEST(test_weak_bridge_threshold)
{
  /* _i: delivered fraction (7) x sign (2). A bridge that delivers less
   * than deliver_ratio (0.5) of the expected 20 V (reversed polarity too)
   * fails in exactly n = 3 samples; one that delivers more never does. The
   * fractions keep >= 0.2 V from the 10 V threshold, 13 quantisation
   * steps of 15 mV. */
  const double f = weak_fraction[_i / 2];
  const double u = ((_i % 2) == 0) ? 20.0 : -20.0;
  const bool weak = f < 0.5;
  canfdi_actmgr_cfg_t c = cfg_with(3U, 1U, 1U);
  canfdi_actmgr_t m;
  canfdi_actmgr_in_t in = in_nominal();
  canfdi_vote_out_t v = vote_ok();
  canfdi_actmgr_out_t o;
  uint32_t step;
  ck_assert_int_eq(canfdi_actmgr_init(&m, &c), CANFDI_OK);
  in.dcm_u_ctrl_V_q16 = Q16(u);
  in.dcm_ua_V_q16 = Q16(u); /* before the first command: not evaluated */
  for (step = 0U; step < 200U; step++) {
    ck_assert_int_eq(canfdi_actmgr_step(&m, &in, &v, &o), CANFDI_OK);
    ck_assert(o.bridge_switched == (weak && (step == 3U)));
    ck_assert_uint_eq(o.dcm.bridge, (weak && (step >= 3U)) ? CANFDI_ACTMGR_BRIDGE_B
                                                           : CANFDI_ACTMGR_BRIDGE_A);
    /* the bridge in use from now on delivers f x command on A, all on B */
    in.dcm_ua_V_q16 =
        Q16(0.015 * round(((o.dcm.bridge == CANFDI_ACTMGR_BRIDGE_A) ? f : 1.0) * u / 0.015));
  }
  ck_assert_uint_eq(canfdi_actmgr_diag(&m).ua_implausible, weak ? 3U : 0U);
}
END_TEST

START_TEST(test_supply_clamp_expected)
{
  /* a command above the supply is expected as the supply (48 V measured),
   * and the command itself is limited to dcm_u_max (60 V default) */
  canfdi_actmgr_cfg_t c = cfg_with(1U, 1U, 1U);
  canfdi_actmgr_t m;
  canfdi_actmgr_in_t in = in_nominal();
  canfdi_vote_out_t v = vote_ok();
  canfdi_actmgr_out_t o;
  uint32_t step;
  ck_assert_int_eq(canfdi_actmgr_init(&m, &c), CANFDI_OK);
  in.dcm_u_ctrl_V_q16 = Q16(200.0);
  in.dcm_supply_V_q16 = Q16(20.0); /* sagging supply: still plausible */
  in.dcm_ua_V_q16 = Q16(19.9);
  for (step = 0U; step < 10U; step++) {
    ck_assert_int_eq(canfdi_actmgr_step(&m, &in, &v, &o), CANFDI_OK);
    ck_assert_uint_eq(o.dcm.bridge, CANFDI_ACTMGR_BRIDGE_A);
    ck_assert_int_eq(o.dcm.u_cmd_V_q16, c.dcm_u_max_V_q16);
    ck_assert(o.dcm_track);
    ck_assert_int_eq(o.dcm_track_V_q16, c.dcm_u_max_V_q16);
  }
  ck_assert_uint_eq(canfdi_actmgr_diag(&m).dcm_clamps, 10U);
  /* without a valid supply the full command is expected: 19.9 V < 30 V */
  in.dcm_supply_valid = false;
  ck_assert_int_eq(canfdi_actmgr_step(&m, &in, &v, &o), CANFDI_OK);
  ck_assert_uint_eq(o.dcm.bridge, CANFDI_ACTMGR_BRIDGE_B);
}
END_TEST

/* ---------------------------------------------------- DC-motor catalogue */

typedef struct {
  uint32_t faults;
  uint8_t state;
  uint8_t reason;
} dcm_cat_case_t;

static const dcm_cat_case_t dcm_cat_cases[] = {
    {0U, CANFDI_DEG_NORMAL, CANFDI_FAULT_NONE},
    {BIT(CANFDI_FAULT_DCM_RA_UP), CANFDI_DEG_NORMAL, CANFDI_FAULT_NONE},
    {BIT(CANFDI_FAULT_DCM_IA_SENSOR_OFFSET), CANFDI_DEG_DEGRADED, CANFDI_FAULT_DCM_IA_SENSOR_OFFSET},
    {BIT(CANFDI_FAULT_DCM_SPEED_SENSOR_GAIN) | BIT(CANFDI_FAULT_DCM_FLUX_DOWN), CANFDI_DEG_DEGRADED,
     CANFDI_FAULT_DCM_SPEED_SENSOR_GAIN},
    {BIT(CANFDI_FAULT_COM_DCM_TIMEOUT), CANFDI_DEG_FAIL_SAFE, CANFDI_FAULT_COM_DCM_TIMEOUT},
    {BIT(CANFDI_FAULT_COM_DCM_CRC) | BIT(CANFDI_FAULT_DCM_IA_SENSOR_OFFSET), CANFDI_DEG_FAIL_SAFE,
     CANFDI_FAULT_COM_DCM_CRC},
    /* throttle faults do not touch the DC motor */
    {BIT(CANFDI_FAULT_THR_JAMMED) | BIT(CANFDI_FAULT_COM_THR_TIMEOUT), CANFDI_DEG_NORMAL,
     CANFDI_FAULT_NONE},
};

START_TEST(test_dcm_catalogue)
{
  const dcm_cat_case_t *k = &dcm_cat_cases[_i];
  canfdi_actmgr_cfg_t c = cfg_with(3U, 1U, 1U);
  canfdi_actmgr_t m;
  canfdi_actmgr_in_t in = in_nominal();
  canfdi_vote_out_t v = vote_ok();
  canfdi_actmgr_out_t o;
  ck_assert_int_eq(canfdi_actmgr_init(&m, &c), CANFDI_OK);
  in.faults = k->faults;
  ck_assert_int_eq(canfdi_actmgr_step(&m, &in, &v, &o), CANFDI_OK);
  ck_assert_uint_eq(o.dcm_state, k->state);
  ck_assert_uint_eq(o.dcm_reason, k->reason);
  ck_assert(o.dcm.enable == (k->state < CANFDI_DEG_FAIL_SAFE));
  ck_assert_uint_eq(o.dcm.bridge, (k->state < CANFDI_DEG_FAIL_SAFE) ? CANFDI_ACTMGR_BRIDGE_A
                                                                    : CANFDI_ACTMGR_BRIDGE_NONE);
}
END_TEST

/* ----------------------------------------------------- throttle decisions */

typedef struct {
  const char *name;
  uint8_t status;     /* vote status */
  uint8_t excluded;   /* vote excluded_mask */
  uint8_t isolated;   /* vote isolated_mask */
  uint32_t faults;
  uint8_t state;
  uint8_t reason;
} thr_case_t;

#define VT1 CANFDI_VOTE_BIT_TPS1
#define VT2 CANFDI_VOTE_BIT_TPS2
#define VM CANFDI_VOTE_BIT_MODEL

static const thr_case_t thr_cases[] = {
    {"healthy", CANFDI_VOTE_THREE, 0U, 0U, 0U, CANFDI_DEG_NORMAL, CANFDI_FAULT_NONE},
    {"model invalid (not isolated)", CANFDI_VOTE_TWO, VM, 0U, 0U, CANFDI_DEG_NORMAL,
     CANFDI_FAULT_NONE},
    {"TPS1 input invalid", CANFDI_VOTE_TWO, VT1, 0U, 0U, CANFDI_DEG_DEGRADED,
     CANFDI_ACTMGR_REASON_TPS1_INVALID},
    {"TPS2 input invalid", CANFDI_VOTE_TWO, VT2, 0U, 0U, CANFDI_DEG_DEGRADED,
     CANFDI_ACTMGR_REASON_TPS2_INVALID},
    {"TPS1 open confirmed", CANFDI_VOTE_TWO, VT1, 0U, BIT(CANFDI_FAULT_THR_TPS1_OPEN),
     CANFDI_DEG_DEGRADED, CANFDI_FAULT_THR_TPS1_OPEN},
    {"TPS2 short confirmed", CANFDI_VOTE_TWO, VT2, 0U, BIT(CANFDI_FAULT_THR_TPS2_SHORT),
     CANFDI_DEG_DEGRADED, CANFDI_FAULT_THR_TPS2_SHORT},
    {"TPS1 isolated by vote", CANFDI_VOTE_TWO, VT1, VT1, 0U, CANFDI_DEG_DEGRADED,
     CANFDI_FAULT_THR_TPS1_DRIFT},
    {"TPS2 isolated by vote", CANFDI_VOTE_TWO, VT2, VT2, 0U, CANFDI_DEG_DEGRADED,
     CANFDI_FAULT_THR_TPS2_DRIFT},
    {"model isolated", CANFDI_VOTE_TWO, VM, VM, 0U, CANFDI_DEG_DEGRADED,
     CANFDI_ACTMGR_REASON_MODEL_ISOLATED},
    {"both TPS invalid", CANFDI_VOTE_SINGLE, VT1 | VT2, 0U, 0U, CANFDI_DEG_FAIL_SAFE,
     CANFDI_FAULT_THR_TPS_BOTH_LOST},
    {"TPS1 isolated, TPS2 invalid", CANFDI_VOTE_SINGLE, VT1 | VT2, VT1, 0U, CANFDI_DEG_FAIL_SAFE,
     CANFDI_FAULT_THR_TPS_BOTH_LOST},
    {"both TPS open confirmed", CANFDI_VOTE_SINGLE, VT1 | VT2, 0U,
     BIT(CANFDI_FAULT_THR_TPS1_OPEN) | BIT(CANFDI_FAULT_THR_TPS2_OPEN), CANFDI_DEG_FAIL_SAFE,
     CANFDI_FAULT_THR_TPS_BOTH_LOST},
    {"both lost named", CANFDI_VOTE_SINGLE, VT1 | VT2, 0U, BIT(CANFDI_FAULT_THR_TPS_BOTH_LOST),
     CANFDI_DEG_FAIL_SAFE, CANFDI_FAULT_THR_TPS_BOTH_LOST},
    {"jammed", CANFDI_VOTE_THREE, 0U, 0U, BIT(CANFDI_FAULT_THR_JAMMED), CANFDI_DEG_FAIL_SAFE,
     CANFDI_FAULT_THR_JAMMED},
    {"motor circuit open", CANFDI_VOTE_THREE, 0U, 0U, BIT(CANFDI_FAULT_THR_MOTOR_OPEN),
     CANFDI_DEG_FAIL_SAFE, CANFDI_FAULT_THR_MOTOR_OPEN},
    {"sensor frame lost", CANFDI_VOTE_THREE, 0U, 0U, BIT(CANFDI_FAULT_COM_THR_TIMEOUT),
     CANFDI_DEG_FAIL_SAFE, CANFDI_FAULT_COM_THR_TIMEOUT},
    {"sensor frame CRC", CANFDI_VOTE_THREE, 0U, 0U, BIT(CANFDI_FAULT_COM_THR_CRC),
     CANFDI_DEG_FAIL_SAFE, CANFDI_FAULT_COM_THR_CRC},
    {"friction up (parametric)", CANFDI_VOTE_THREE, 0U, 0U, BIT(CANFDI_FAULT_THR_FRICTION_UP),
     CANFDI_DEG_NORMAL, CANFDI_FAULT_NONE},
    {"motor R up (parametric)", CANFDI_VOTE_THREE, 0U, 0U, BIT(CANFDI_FAULT_THR_MOTOR_R_UP),
     CANFDI_DEG_NORMAL, CANFDI_FAULT_NONE},
    {"DC-motor fault only", CANFDI_VOTE_THREE, 0U, 0U, BIT(CANFDI_FAULT_COM_DCM_TIMEOUT),
     CANFDI_DEG_NORMAL, CANFDI_FAULT_NONE},
    {"jam + TPS1 invalid", CANFDI_VOTE_TWO, VT1, 0U, BIT(CANFDI_FAULT_THR_JAMMED),
     CANFDI_DEG_FAIL_SAFE, CANFDI_FAULT_THR_JAMMED},
};
#define N_THR ((int)(sizeof thr_cases / sizeof thr_cases[0]))

START_TEST(test_thr_table)
{
  const thr_case_t *k = &thr_cases[_i];
  canfdi_actmgr_cfg_t c = cfg_with(3U, 1U, 1U);
  canfdi_actmgr_t m;
  canfdi_actmgr_in_t in = in_nominal();
  canfdi_vote_out_t v = vote_ok();
  canfdi_actmgr_out_t o;
  const bool limp = k->state >= CANFDI_DEG_FAIL_SAFE;
  ck_assert_int_eq(canfdi_actmgr_init(&m, &c), CANFDI_OK);
  v.status = k->status;
  v.valid = (k->status == CANFDI_VOTE_THREE) || (k->status == CANFDI_VOTE_TWO);
  v.excluded_mask = k->excluded;
  v.isolated_mask = k->isolated;
  in.faults = k->faults;
  /* one step: every decision here is immediate (no vote-loss debounce) */
  ck_assert_int_eq(canfdi_actmgr_step(&m, &in, &v, &o), CANFDI_OK);
  ck_assert_msg(o.thr_state == k->state, "%s: state %u", k->name, o.thr_state);
  ck_assert_msg(o.thr_reason == k->reason, "%s: reason 0x%x", k->name, o.thr_reason);
  ck_assert(o.thr_limp_home == limp);
  ck_assert(o.thr.enable == !limp);
  ck_assert_int_eq(o.thr.u_cmd_V_q16, limp ? 0 : in.thr_u_ctrl_V_q16);
  ck_assert(o.thr_track == limp);
  ck_assert_uint_eq(o.thr_ctrl_mode, limp ? CANFDI_CTRL_OFF : CANFDI_CTRL_RUN);
  /* the DC motor is unaffected by throttle-only conditions */
  if ((k->faults & CANFDI_ACTMGR_DCM_FAULTS) == 0U) {
    ck_assert_uint_eq(o.dcm_state, CANFDI_DEG_NORMAL);
    ck_assert(o.dcm.enable);
  }
}
END_TEST

static const uint8_t vote_loss_status[] = {CANFDI_VOTE_DISAGREE, CANFDI_VOTE_SINGLE,
                                           CANFDI_VOTE_INVALID};

START_TEST(test_vote_loss_debounce)
{
  /* _i: status (3) x loss steps {1, 20, 100} (3). A not-valid vote (with
   * at most one TPS excluded) is tolerated for n - 1 consecutive steps,
   * limp-home on the n-th; a valid vote in between restarts the count. */
  static const uint16_t ns[] = {1U, 20U, 100U};
  const uint8_t st = vote_loss_status[_i / 3];
  const uint16_t n = ns[_i % 3];
  canfdi_actmgr_cfg_t c = cfg_with(3U, 1U, 1U);
  canfdi_actmgr_t m;
  canfdi_actmgr_in_t in = in_nominal();
  canfdi_vote_out_t good = vote_ok();
  canfdi_vote_out_t bad = vote_ok();
  canfdi_actmgr_out_t o;
  uint32_t rep;
  uint32_t step;
  c.thr_vote_loss_steps = n;
  ck_assert_int_eq(canfdi_actmgr_init(&m, &c), CANFDI_OK);
  bad.status = st;
  bad.valid = false;
  bad.excluded_mask = (st == CANFDI_VOTE_DISAGREE) ? 0U : VM;
  for (rep = 0U; rep < 5U; rep++) {
    for (step = 1U; step < n; step++) {
      ck_assert_int_eq(canfdi_actmgr_step(&m, &in, &bad, &o), CANFDI_OK);
      ck_assert(o.thr.enable);
    }
    ck_assert_int_eq(canfdi_actmgr_step(&m, &in, &good, &o), CANFDI_OK);
    ck_assert(o.thr.enable);
  }
  for (step = 1U; step <= n; step++) {
    ck_assert_int_eq(canfdi_actmgr_step(&m, &in, &bad, &o), CANFDI_OK);
    ck_assert(o.thr.enable == (step < n));
  }
  ck_assert_uint_eq(o.thr_state, CANFDI_DEG_FAIL_SAFE);
  ck_assert_uint_eq(o.thr_reason, (st == CANFDI_VOTE_DISAGREE) ? CANFDI_ACTMGR_REASON_TPS_DISAGREE
                                                                : CANFDI_ACTMGR_REASON_VOTE_LOST);
  ck_assert_uint_eq(canfdi_actmgr_diag(&m).limp_homes, 1U);
}
END_TEST

START_TEST(test_limp_home_hold_and_clear)
{
  /* jam -> limp-home; the jam bit goes away -> still limp-home; clear
   * refused while the jam is confirmed, accepted after; enabled again. */
  canfdi_actmgr_cfg_t c = cfg_with(3U, 1U, 1U);
  canfdi_actmgr_t m;
  canfdi_actmgr_in_t in = in_nominal();
  canfdi_vote_out_t v = vote_ok();
  canfdi_actmgr_out_t o;
  uint32_t step;
  const uint32_t jam = BIT(CANFDI_FAULT_THR_JAMMED);
  ck_assert_int_eq(canfdi_actmgr_init(&m, &c), CANFDI_OK);
  in.faults = jam;
  in.now_ms = 1234U;
  ck_assert_int_eq(canfdi_actmgr_step(&m, &in, &v, &o), CANFDI_OK);
  ck_assert(o.thr_limp_home);
  in.faults = 0U;
  for (step = 0U; step < 5000U; step++) {
    in.now_ms = 1235U + step;
    ck_assert_int_eq(canfdi_actmgr_step(&m, &in, &v, &o), CANFDI_OK);
    ck_assert(o.thr_limp_home && !o.thr.enable);
    ck_assert_int_eq(o.thr.u_cmd_V_q16, 0);
    ck_assert_uint_eq(o.thr_reason, CANFDI_FAULT_THR_JAMMED);
  }
  ck_assert_uint_eq(canfdi_degrade_since_ms(canfdi_actmgr_degrade_thr(&m)), 1234U);
  /* a request for NORMAL is not a request: nothing was ignored here */
  ck_assert_uint_eq(canfdi_degrade_diag(canfdi_actmgr_degrade_thr(&m)).ignored_relax, 0U);
  ck_assert_int_eq(canfdi_actmgr_clear(&m, CANFDI_ACTMGR_SUB_THR, CANFDI_DEGRADE_CLEAR_TESTER, jam,
                                       7000U),
                   0);
  ck_assert_uint_eq(canfdi_actmgr_diag(&m).clears_refused, 1U);
  ck_assert_int_eq(canfdi_actmgr_step(&m, &in, &v, &o), CANFDI_OK);
  ck_assert(o.thr_limp_home);
  /* clearing both while the DC motor is fine and the jam gone */
  ck_assert_int_eq(canfdi_actmgr_clear(&m, CANFDI_ACTMGR_SUB_THR | CANFDI_ACTMGR_SUB_DCM,
                                       CANFDI_DEGRADE_CLEAR_NEW_CYCLE, 0U, 7001U),
                   (int32_t)(CANFDI_ACTMGR_SUB_THR | CANFDI_ACTMGR_SUB_DCM));
  ck_assert_int_eq(canfdi_actmgr_step(&m, &in, &v, &o), CANFDI_OK);
  ck_assert(!o.thr_limp_home && o.thr.enable);
  ck_assert_uint_eq(o.thr_state, CANFDI_DEG_NORMAL);
  ck_assert_uint_eq(o.thr_reason, CANFDI_DEGRADE_CLEAR_NEW_CYCLE);
  ck_assert_uint_eq(canfdi_actmgr_diag(&m).clears, 2U);
}
END_TEST

START_TEST(test_dcm_clear_restores_bridge_a)
{
  /* after an accepted clear the manager goes back to A (and would find it
   * dead again within n samples if it still is) */
  canfdi_actmgr_cfg_t c = cfg_with(3U, 1U, 1U);
  canfdi_actmgr_t m;
  canfdi_actmgr_in_t in = in_nominal();
  canfdi_vote_out_t v = vote_ok();
  canfdi_actmgr_out_t o;
  ck_assert_int_eq(canfdi_actmgr_init(&m, &c), CANFDI_OK);
  in.faults = BIT(CANFDI_FAULT_DCM_BRIDGE_A_DEAD);
  ck_assert_int_eq(canfdi_actmgr_step(&m, &in, &v, &o), CANFDI_OK);
  ck_assert_uint_eq(o.dcm.bridge, CANFDI_ACTMGR_BRIDGE_B);
  ck_assert_int_eq(canfdi_actmgr_clear(&m, CANFDI_ACTMGR_SUB_DCM, CANFDI_DEGRADE_CLEAR_TESTER,
                                       in.faults, 1U),
                   0);
  in.faults = 0U;
  ck_assert_int_eq(canfdi_actmgr_clear(&m, CANFDI_ACTMGR_SUB_DCM, CANFDI_DEGRADE_CLEAR_TESTER,
                                       in.faults, 2U),
                   (int32_t)CANFDI_ACTMGR_SUB_DCM);
  ck_assert_int_eq(canfdi_actmgr_step(&m, &in, &v, &o), CANFDI_OK);
  ck_assert_uint_eq(o.dcm.bridge, CANFDI_ACTMGR_BRIDGE_A);
  ck_assert_uint_eq(o.dcm_state, CANFDI_DEG_NORMAL);
  ck_assert(!o.bridge_switched);
}
END_TEST

START_TEST(test_fail_silent)
{
  canfdi_actmgr_cfg_t c = cfg_with(3U, 1U, 1U);
  canfdi_actmgr_t m;
  canfdi_actmgr_in_t in = in_nominal();
  canfdi_vote_out_t v = vote_ok();
  canfdi_actmgr_out_t o;
  ck_assert_int_eq(canfdi_actmgr_init(&m, &c), CANFDI_OK);
  in.fail_silent = true;
  ck_assert_int_eq(canfdi_actmgr_step(&m, &in, &v, &o), CANFDI_OK);
  ck_assert_uint_eq(o.dcm_state, CANFDI_DEG_FAIL_SILENT);
  ck_assert_uint_eq(o.thr_state, CANFDI_DEG_FAIL_SILENT);
  ck_assert_uint_eq(o.dcm_reason, CANFDI_ACTMGR_REASON_FAIL_SILENT);
  ck_assert(!o.dcm.enable && !o.thr.enable && o.thr_limp_home);
}
END_TEST

START_TEST(test_thr_clamp_track)
{
  canfdi_actmgr_cfg_t c = cfg_with(3U, 1U, 1U);
  canfdi_actmgr_t m;
  canfdi_actmgr_in_t in = in_nominal();
  canfdi_vote_out_t v = vote_ok();
  canfdi_actmgr_out_t o;
  ck_assert_int_eq(canfdi_actmgr_init(&m, &c), CANFDI_OK);
  in.thr_u_ctrl_V_q16 = -c.thr_u_max_V_q16 - 1;
  ck_assert_int_eq(canfdi_actmgr_step(&m, &in, &v, &o), CANFDI_OK);
  ck_assert_int_eq(o.thr.u_cmd_V_q16, -c.thr_u_max_V_q16);
  ck_assert(o.thr_track);
  ck_assert_int_eq(o.thr_track_V_q16, -c.thr_u_max_V_q16);
  ck_assert_uint_eq(o.thr_ctrl_mode, CANFDI_CTRL_TRACK);
  ck_assert_uint_eq(canfdi_actmgr_diag(&m).thr_clamps, 1U);
}
END_TEST

/* ------------------------------------------------ property: monotone */

START_TEST(test_property_monotone)
{
  /* Random fault bitsets (sparse), vote outcomes and U_A samples for 5000
   * steps per seed; a random clear now and then. Without an accepted clear
   * neither state ever decreases; FAIL_SAFE or worse always means the
   * actuator is off; B once chosen is kept until a clear. */
  canfdi_actmgr_cfg_t c = cfg_with(2U, 1U, 1U);
  canfdi_actmgr_t m;
  canfdi_actmgr_in_t in = in_nominal();
  canfdi_vote_out_t v = vote_ok();
  canfdi_actmgr_out_t o;
  uint8_t prev_dcm = 0U;
  uint8_t prev_thr = 0U;
  bool on_b = false;
  uint32_t step;
  uint32_t clears = 0U;
  rng_seed(0xABCDEF01ULL * ((uint64_t)_i + 1U));
  c.thr_vote_loss_steps = 3U;
  ck_assert_int_eq(canfdi_actmgr_init(&m, &c), CANFDI_OK);
  for (step = 0U; step < 5000U; step++) {
    const uint32_t r = rng_u32();
    in.faults = ((r & 63U) == 0U) ? BIT(rng_u32() % CANFDI_FAULT_COUNT) : 0U;
    in.dcm_u_ctrl_V_q16 = Q16(100.0 * rng_unit() - 50.0);
    in.dcm_ua_V_q16 = ((r & 0x300U) == 0U) ? 0 : in.dcm_u_ctrl_V_q16;
    v.status = (uint8_t)((r >> 12) % 5U);
    v.valid = (v.status == CANFDI_VOTE_THREE) || (v.status == CANFDI_VOTE_TWO);
    v.excluded_mask = (uint8_t)(((r >> 16) & 0x3FU) == 0U ? ((r >> 22) & 7U) : 0U);
    v.isolated_mask = (uint8_t)(v.excluded_mask & ((r >> 25) & 7U));
    in.now_ms = step;
    ck_assert_int_eq(canfdi_actmgr_step(&m, &in, &v, &o), CANFDI_OK);
    ck_assert_uint_ge(o.dcm_state, prev_dcm);
    ck_assert_uint_ge(o.thr_state, prev_thr);
    if (o.dcm_state >= CANFDI_DEG_FAIL_SAFE) {
      ck_assert(!o.dcm.enable && (o.dcm.u_cmd_V_q16 == 0));
    }
    if (o.thr_state >= CANFDI_DEG_FAIL_SAFE) {
      ck_assert(!o.thr.enable && (o.thr.u_cmd_V_q16 == 0) && o.thr_limp_home);
    }
    if (on_b && o.dcm.enable) {
      ck_assert_uint_eq(o.dcm.bridge, CANFDI_ACTMGR_BRIDGE_B);
    }
    on_b = on_b || (o.dcm.bridge == CANFDI_ACTMGR_BRIDGE_B);
    prev_dcm = o.dcm_state;
    prev_thr = o.thr_state;
    if (((r >> 28) == 0U) && ((rng_u32() & 15U) == 0U)) {
      const int32_t done = canfdi_actmgr_clear(&m, CANFDI_ACTMGR_SUB_DCM | CANFDI_ACTMGR_SUB_THR,
                                               CANFDI_DEGRADE_CLEAR_TESTER, in.faults, step);
      ck_assert_int_ge(done, 0);
      if ((done & (int32_t)CANFDI_ACTMGR_SUB_DCM) != 0) {
        prev_dcm = 0U;
        on_b = false;
        clears++;
      }
      if ((done & (int32_t)CANFDI_ACTMGR_SUB_THR) != 0) {
        prev_thr = 0U;
        clears++;
      }
    }
  }
  ck_assert_uint_gt(clears, 0U);
  ck_assert_uint_gt(canfdi_degrade_diag(canfdi_actmgr_degrade_thr(&m)).escalations, 2U);
}
END_TEST

/* --------------------------------------------------------- closed loop */

/*
 * The firmware manager in the loop with the double-precision plants and
 * the simulator's stand-in controllers (canfdi_sim_refctl.h). Per 1 ms:
 * sample -> controller -> vote/manager -> plant step. The controller's
 * integrator follows "must track" by back-calculation. Sensor noise:
 * U_A 50 mV, I_A 20 mA, speed 0.05 rad/s, TPS 2 mV (sigma).
 */
typedef struct {
  canfdi_sim_t sim;
  canfdi_sim_refctl_t ctl;
  canfdi_actmgr_t mgr;
  canfdi_vote_t vote;
  canfdi_actmgr_out_t out;
  canfdi_vote_out_t vout;
  uint32_t k;
} rig_t;

static void rig_init(rig_t *r)
{
  canfdi_sim_cfg_t sc;
  canfdi_sim_refctl_cfg_t rc;
  canfdi_actmgr_cfg_t mc;
  canfdi_vote_cfg_t vc;
  canfdi_sim_default_cfg(&sc);
  sc.sigma[CANFDI_SIM_S_DCM_UA] = 0.05;
  sc.sigma[CANFDI_SIM_S_DCM_IA] = 0.02;
  sc.sigma[CANFDI_SIM_S_DCM_SPEED] = 0.05;
  sc.sigma[CANFDI_SIM_S_THR_TPS1] = 0.002;
  sc.sigma[CANFDI_SIM_S_THR_TPS2] = 0.002;
  sc.seed = 4242U;
  ck_assert_int_eq(canfdi_sim_init(&r->sim, &sc), CANFDI_OK);
  canfdi_sim_refctl_default(&rc, &sc);
  canfdi_sim_refctl_init(&r->ctl, &rc);
  canfdi_actmgr_default_cfg(&mc);
  ck_assert_int_eq(canfdi_actmgr_init(&r->mgr, &mc), CANFDI_OK);
  canfdi_tps_cal_default(&vc.tps1, &vc.tps2);
  vc.tol_tps_rad_q16 = Q16(0.02);
  vc.tol_model_rad_q16 = Q16(0.05);
  vc.isolate_steps_tps = 20U;
  vc.isolate_steps_model = 50U;
  ck_assert_int_eq(canfdi_vote_init(&r->vote, &vc), CANFDI_OK);
  r->k = 0U;
}

static bool tps_in_range(double v) { return (v >= 0.25) && (v <= 4.75); }

static void rig_step(rig_t *r, double speed_ref, double angle_ref_deg, double load_Nm)
{
  const canfdi_sim_meas_t *me = &r->sim.meas;
  canfdi_sim_in_t pin;
  canfdi_actmgr_in_t in = {0};
  canfdi_vote_in_t vin;
  canfdi_sim_refctl_step(&r->ctl, speed_ref, angle_ref_deg, me, &pin);

  vin.tps1_V_q16 = Q16(me->value[CANFDI_SIM_S_THR_TPS1]);
  vin.tps2_V_q16 = Q16(me->value[CANFDI_SIM_S_THR_TPS2]);
  vin.model_rad_q16 = 0;
  vin.tps1_valid = tps_in_range(me->value[CANFDI_SIM_S_THR_TPS1]);
  vin.tps2_valid = tps_in_range(me->value[CANFDI_SIM_S_THR_TPS2]);
  vin.model_valid = false; /* no observer in this rig: the vote runs on the TPS pair */
  vin.model_no_blame = false;
  ck_assert_int_eq(canfdi_vote_step(&r->vote, &vin, &r->vout), CANFDI_OK);

  in.dcm_u_ctrl_V_q16 = Q16(pin.dcm.u_cmd_V);
  in.dcm_ua_V_q16 = Q16(me->value[CANFDI_SIM_S_DCM_UA]);
  in.dcm_supply_V_q16 = Q16(me->value[CANFDI_SIM_S_DCM_SUPPLY]);
  in.dcm_ua_valid = true;
  in.dcm_supply_valid = true;
  in.thr_u_ctrl_V_q16 = Q16(pin.thr.enable ? pin.thr.u_cmd_V : 0.0);
  in.now_ms = r->k;
  ck_assert_int_eq(canfdi_actmgr_step(&r->mgr, &in, &r->vout, &r->out), CANFDI_OK);

  if (r->out.dcm_track) {
    /* back-calculation: the integrator that makes the PI output the
     * applied command (the P and feed-forward parts as the controller
     * formed them this step) */
    r->ctl.speed_int_V += v_of_q16(r->out.dcm_track_V_q16) - pin.dcm.u_cmd_V;
  }
  pin.dcm.u_cmd_V = v_of_q16(r->out.dcm.u_cmd_V_q16);
  pin.dcm.bridge = r->out.dcm.bridge;
  pin.dcm.enable = r->out.dcm.enable;
  pin.dcm.load_Nm = load_Nm;
  pin.thr.u_cmd_V = v_of_q16(r->out.thr.u_cmd_V_q16);
  pin.thr.enable = r->out.thr.enable;
  canfdi_sim_step(&r->sim, &pin);
  r->k++;
}

static void add_fault(rig_t *r, uint8_t id, double t_s)
{
  canfdi_sim_fault_spec_t fs;
  ck_assert_int_eq(canfdi_sim_fault_spec_make(&fs, id, CANFDI_SIM_MODE_ABRUPT, t_s, 1.0, 0, 0, 0),
                   CANFDI_OK);
  ck_assert_int_eq(canfdi_sim_add_fault(&r->sim, &fs), CANFDI_OK);
}

static rig_t rig; /* ~3 kB: keep it off the test's stack */

START_TEST(test_closed_loop_bridge_a_killed)
{
  /* 100 rad/s against a 1 N m load (I_A ~ 3.8 A, U_A ~ 39 V); bridge A dies
   * at t = 1.000 s. Expected: switch to B in the 3rd step after the first
   * 0 V sample (<= 4 ms after the death), speed recovers; the dip is
   * measured on the true speed and printed. */
  const double ref = 100.0;
  double w_before = 0.0;
  double w_min = 1e9;
  double w_max_after = 0.0;
  uint32_t switch_k = 0U;
  uint32_t recovered_k = 0U;
  rig_init(&rig);
  add_fault(&rig, CANFDI_FAULT_DCM_BRIDGE_A_DEAD, 1.0);
  while (rig.k < 2000U) {
    const uint32_t k = rig.k;
    rig_step(&rig, ref, 30.0, 1.0);
    if ((k >= 900U) && (k < 1000U)) {
      w_before += rig.sim.dcm.w_rad_s / 100.0;
    }
    if (rig.out.bridge_switched) {
      switch_k = k;
    }
    if (k >= 1000U) {
      w_min = fmin(w_min, rig.sim.dcm.w_rad_s);
      w_max_after = fmax(w_max_after, rig.sim.dcm.w_rad_s);
      if ((recovered_k == 0U) && (switch_k != 0U) && (fabs(rig.sim.dcm.w_rad_s - ref) < 1.0) &&
          (k > switch_k + 5U)) {
        recovered_k = k;
      }
    }
  }
  printf("closed loop, bridge A killed at 1.000 s at %.1f rad/s, 1 N m: B drives from step %u "
         "(%u ms of 0 V), speed dip %.2f rad/s (%.1f %%), back within 1 rad/s after %u ms, "
         "overshoot %.2f rad/s\n",
         w_before, (unsigned)switch_k, (unsigned)(switch_k - 1000U), w_before - w_min,
         100.0 * (w_before - w_min) / w_before, (unsigned)(recovered_k - 1000U),
         w_max_after - ref);
  ck_assert(fabs(w_before - ref) < 1.0);          /* it was in control before */
  ck_assert_uint_ge(switch_k, 1001U);             /* not before the first 0 V sample */
  ck_assert_uint_le(switch_k, 1003U);             /* n = 3 samples: steps 1001..1003 */
  ck_assert_uint_eq(rig.out.dcm.bridge, CANFDI_ACTMGR_BRIDGE_B);
  ck_assert_uint_eq(rig.out.dcm_state, CANFDI_DEG_DEGRADED);
  ck_assert_uint_ne(recovered_k, 0U);
  ck_assert_uint_lt(recovered_k - 1000U, 300U);   /* recovers well inside 0.3 s */
  ck_assert(w_before - w_min > 1.0);              /* the dip is real ... */
  ck_assert(w_before - w_min < 40.0);             /* ... but no stall */
  ck_assert(fabs(rig.sim.dcm.w_rad_s - ref) < 1.0);
}
END_TEST

START_TEST(test_closed_loop_both_bridges_killed)
{
  /* both die at 1.000 s: switch to B after 3 samples, B found dead 3
   * samples later, drive off for good; the motor coasts down */
  uint32_t off_k = 0U;
  rig_init(&rig);
  add_fault(&rig, CANFDI_FAULT_DCM_BRIDGES_DEAD, 1.0);
  while (rig.k < 1500U) {
    const uint32_t k = rig.k;
    rig_step(&rig, 100.0, 30.0, 1.0);
    if ((off_k == 0U) && !rig.out.dcm.enable) {
      off_k = k;
    }
    if (off_k != 0U) {
      ck_assert(!rig.out.dcm.enable);
      ck_assert_uint_eq(rig.out.dcm_state, CANFDI_DEG_FAIL_SAFE);
    }
  }
  printf("closed loop, both bridges killed at 1.000 s: drive off from step %u (%u ms after the "
         "fault)\n",
         (unsigned)off_k, (unsigned)(off_k - 1000U));
  ck_assert_uint_ge(off_k, 1004U);
  ck_assert_uint_le(off_k, 1006U);
  ck_assert_uint_eq(rig.out.dcm_reason, CANFDI_FAULT_DCM_BRIDGES_DEAD);
  ck_assert(rig.sim.dcm.w_rad_s < 50.0); /* coasting down against the load */
}
END_TEST

START_TEST(test_closed_loop_fault_free_profile)
{
  /* 6 s of speed setpoint steps including reversals (+-100 rad/s, the
   * command at the supply limit) and load steps: the check never fires */
  static const double refs[] = {0.0, 100.0, -100.0, 50.0, 120.0, -20.0, 0.0, 80.0,
                                -120.0, 100.0, 10.0, 0.0};
  rig_init(&rig);
  while (rig.k < 6000U) {
    const double ref = refs[rig.k / 500U];
    const double load = (((rig.k / 700U) % 2U) == 0U) ? 1.0 : 0.2;
    rig_step(&rig, ref, 30.0, (ref >= 0.0) ? load : -load);
    ck_assert_uint_eq(rig.out.dcm.bridge, CANFDI_ACTMGR_BRIDGE_A);
  }
  ck_assert_uint_eq(canfdi_actmgr_diag(&rig.mgr).ua_implausible, 0U);
  ck_assert_uint_eq(rig.out.dcm_state, CANFDI_DEG_NORMAL);
  ck_assert_uint_eq(rig.out.thr_state, CANFDI_DEG_NORMAL);
  ck_assert_uint_eq(rig.out.detected, 0U);
}
END_TEST

START_TEST(test_closed_loop_tps_both_lost)
{
  /* throttle held at 30 deg; both TPS open at 1.000 s: limp-home
   * (de-energised) in the first step that sees it; the valve springs back
   * to its limp-home angle; the time to within 1 deg of it is printed */
  uint32_t limp_k = 0U;
  uint32_t home_k = 0U;
  rig_init(&rig);
  add_fault(&rig, CANFDI_FAULT_THR_TPS_BOTH_LOST, 1.0);
  while (rig.k < 1500U) {
    const uint32_t k = rig.k;
    rig_step(&rig, 0.0, 30.0, 0.0);
    if (k == 999U) {
      ck_assert(fabs(rig.sim.thr.theta_rad - 30.0 * 0.017453292519943295) < 0.02);
    }
    if ((limp_k == 0U) && rig.out.thr_limp_home) {
      limp_k = k;
    }
    if ((home_k == 0U) && (limp_k != 0U) &&
        (fabs(rig.sim.thr.theta_rad - rig.sim.cfg.thr.limp_home_deg * 0.017453292519943295) <
         0.017453292519943295)) {
      home_k = k;
    }
    if (limp_k != 0U) {
      ck_assert(!rig.out.thr.enable);
    }
  }
  printf("closed loop, both TPS lost at 1.000 s: limp-home commanded in step %u, valve within 1 deg "
         "of limp-home %u ms after the fault\n",
         (unsigned)limp_k, (unsigned)(home_k + 1U - 1000U));
  /* the sample taken at t = 1.000 s already shows the open circuits (the
   * plant applies sensor faults at the sampling instant): the first step
   * that sees them commands limp-home */
  ck_assert_uint_eq(limp_k, 1000U);
  ck_assert_uint_eq(rig.out.thr_state, CANFDI_DEG_FAIL_SAFE);
  ck_assert_uint_eq(rig.out.thr_reason, CANFDI_FAULT_THR_TPS_BOTH_LOST);
  ck_assert_uint_ne(home_k, 0U);
  ck_assert_uint_lt(home_k - 1000U, 200U); /* limp-home budget, docs/requirements.md */
}
END_TEST

static Suite *make_suite(void)
{
  Suite *s = suite_create("actmgr");
  TCase *tc;

  tc = tcase_create("config");
  tcase_add_loop_test(tc, test_cfg_domain, 0, 13);
  tcase_add_test(tc, test_null_args);
  suite_add_tcase(s, tc);

  tc = tcase_create("bridge_check");
  tcase_set_timeout(tc, 120);
  tcase_add_loop_test(tc, test_healthy_bridge_never_fails, 0, N_HEALTHY);
  tcase_add_loop_test(tc, test_dead_bridge_a_switch, 0, 6);
  tcase_add_test(tc, test_diagnosis_switch_same_step);
  tcase_add_loop_test(tc, test_both_bridges_die, 0, 3);
  tcase_add_loop_test(tc, test_check_blind_conditions, 0, 3);
  tcase_add_loop_test(tc, test_weak_bridge_threshold, 0,
                      (int)(2U * sizeof weak_fraction / sizeof weak_fraction[0]));
  tcase_add_test(tc, test_supply_clamp_expected);
  tcase_add_test(tc, test_set_applied_history);
  tcase_add_loop_test(tc, test_dcm_catalogue, 0,
                      (int)(sizeof dcm_cat_cases / sizeof dcm_cat_cases[0]));
  tcase_add_test(tc, test_dcm_clear_restores_bridge_a);
  suite_add_tcase(s, tc);

  tc = tcase_create("throttle");
  tcase_add_loop_test(tc, test_thr_table, 0, N_THR);
  tcase_add_loop_test(tc, test_vote_loss_debounce, 0, 9);
  tcase_add_test(tc, test_limp_home_hold_and_clear);
  tcase_add_test(tc, test_fail_silent);
  tcase_add_test(tc, test_thr_clamp_track);
  suite_add_tcase(s, tc);

  tc = tcase_create("property");
  tcase_add_loop_test(tc, test_property_monotone, 0, 20);
  suite_add_tcase(s, tc);

  tc = tcase_create("closed_loop");
  tcase_set_timeout(tc, 120);
  tcase_add_test(tc, test_closed_loop_bridge_a_killed);
  tcase_add_test(tc, test_closed_loop_both_bridges_killed);
  tcase_add_test(tc, test_closed_loop_fault_free_profile);
  tcase_add_test(tc, test_closed_loop_tps_both_lost);
  suite_add_tcase(s, tc);
  return s;
}

CANFDI_UNIT_MAIN(make_suite)
