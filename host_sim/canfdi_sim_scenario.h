/*
 * canfdi_sim_scenario.h — the scenario description shared by SIL (C) and
 * HIL (Python tools): parser, validation, and setting up a canfdi_sim_t.
 *
 * Format: one directive per line, whitespace-separated tokens, '#' starts
 * a comment. The full reference with examples is host_sim/SCENARIO.md;
 * examples live in host_sim/scenarios/. Summary:
 *   duration <s>                              (required)
 *   seed <unsigned integer>
 *   noise <sensor> <sigma>                    sensors: see canfdi_sim.h
 *   init <dcm_speed|dcm_current|dcm_winding|thr_angle> <value>
 *   param <name> <value>                      plant parameters (SCENARIO.md)
 *   speed|angle|load const <v>
 *   speed|angle|load step <t0> <delta>
 *   speed|angle|load ramp <t0> <t1> <delta>
 *   speed|angle|load prbs <t0> <t1> <amplitude> <bit_s> <seed>
 *   speed|angle|load sine <t0> <t1> <amplitude> <freq_hz>
 *   load fan <k_Nms>                          speed-proportional load
 *   fault <t_start> <name> <mode> <magnitude> [<ramp_s> | <period_s> <duty>]
 *   expect <t> dtc <code> [pending|confirmed] | no_dtc |
 *          degradation <dcm|thr> <normal|degraded|fail_safe>
 * `expect` lines are parsed, validated and kept for the scenario runner of
 * a later issue; nothing evaluates them yet.
 * Errors: every malformed, unknown, duplicate or out-of-range item is
 * rejected with "<file>:<line>: <message>" in err->msg; parsing stops at the
 * first error. Lines longer than CANFDI_SIM_SCN_LINE_MAX are errors.
 *
 * Cost: parsing is O(file size). Memory: sizeof(canfdi_sim_scn_t) ~ 9 kB
 * (three profiles, CANFDI_SIM_MAX_FAULTS faults, CANFDI_SIM_SCN_MAX_EXPECT
 * expectations), caller-owned; the file is read line by line into a stack
 * buffer. No heap.
 */
#ifndef CANFDI_SIM_SCENARIO_H
#define CANFDI_SIM_SCENARIO_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "canfdi_sim.h"
#include "canfdi_sim_profile.h"

#define CANFDI_SIM_SCN_LINE_MAX 256U
#define CANFDI_SIM_SCN_MAX_EXPECT 32U
#define CANFDI_SIM_SCN_MAX_DURATION_S 1e5

#define CANFDI_SIM_INIT_DCM_SPEED 0U
#define CANFDI_SIM_INIT_DCM_CURRENT 1U
#define CANFDI_SIM_INIT_DCM_WINDING 2U
#define CANFDI_SIM_INIT_THR_ANGLE 3U
#define CANFDI_SIM_N_INIT 4U

typedef struct {
  char msg[384];    /* "<file>:<line>: <message>" */
  unsigned line;    /* 0 if not tied to a line (e.g. cannot open) */
} canfdi_sim_scn_err_t;

typedef struct {
  double t_s;
  char kind[16];    /* dtc | no_dtc | degradation */
  char arg1[16];    /* code or subsystem */
  char arg2[16];    /* status or state ("" if absent) */
  unsigned line;
} canfdi_sim_expect_t;

typedef struct {
  double duration_s;
  canfdi_sim_cfg_t cfg;            /* plant parameters, noise, seed */
  bool has_init[CANFDI_SIM_N_INIT];
  double init[CANFDI_SIM_N_INIT];
  canfdi_sim_profile_t speed;      /* rad/s, clamped to -400..400 */
  canfdi_sim_profile_t angle;      /* deg, clamped to 0..90 */
  canfdi_sim_profile_t load;       /* N m, clamped to -10..10 */
  canfdi_sim_fault_spec_t faults[CANFDI_SIM_MAX_FAULTS];
  size_t n_faults;
  canfdi_sim_expect_t expects[CANFDI_SIM_SCN_MAX_EXPECT];
  size_t n_expects;
} canfdi_sim_scn_t;

/* Parses a NUL-terminated text; `name` is used in messages. Returns
 * CANFDI_OK or -CANFDI_EINVAL with err filled. */
int canfdi_sim_scn_parse(canfdi_sim_scn_t *scn, const char *text, const char *name,
                         canfdi_sim_scn_err_t *err);

/* Reads and parses a file. -CANFDI_EINVAL also when it cannot be read. */
int canfdi_sim_scn_load(canfdi_sim_scn_t *scn, const char *path, canfdi_sim_scn_err_t *err);

/* Initialises sim from the scenario: parameters, noise, seed, initial
 * state, faults; samples at t = 0. Returns the canfdi_sim_init result. */
int canfdi_sim_scn_setup(const canfdi_sim_scn_t *scn, canfdi_sim_t *sim);

/* Setpoints and load at t_us. */
void canfdi_sim_scn_eval(canfdi_sim_scn_t *scn, int64_t t_us, double *speed_rad_s,
                         double *angle_deg, double *load_Nm);

#endif /* CANFDI_SIM_SCENARIO_H */
