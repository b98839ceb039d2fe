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
 *   profile <file.csv>                        time profile of speed, angle, load
 *                                             and the two supplies (canfdi_sim_csvprof.h)
 *   fault <t_start> <name> <mode> <magnitude> [<ramp_s> | <period_s> <duty>]
 *   cycle <t>                                 ECU: operation cycle ends, a new one starts
 *   clear <t> [<code>|all]                    ECU: ClearDiagnosticInformation
 *   power_cycle <t>                           ECU: DTC memory -> NVM, re-init, load
 *   uds <t> <phys|func> <hex byte>... [expect <hex byte|..>... [*] | expect none]
 *                                             a tester's UDS request and the
 *                                             response it expects (SIL rig)
 *   expect <t> dtc <code> [pending|confirmed] | no_dtc |
 *          degradation <dcm|thr> <normal|degraded|fail_safe> |
 *          dtc_status <code> <bits> | occurrence <code> <n> |
 *          freeze <code> <signal> <min> <max>
 * `expect` lines are parsed, validated and kept; the SIL rig (tests/sil)
 * and the HIL runner (tools/canfdi) evaluate them. The ECU actions (cycle,
 * clear, power_cycle) are kept in time order in `actions`; only the SIL
 * rig performs them.
 * Errors: every malformed, unknown, duplicate or out-of-range item is
 * rejected with "<file>:<line>: <message>" in err->msg; parsing stops at the
 * first error. Lines longer than CANFDI_SIM_SCN_LINE_MAX are errors.
 *
 * `profile <file.csv>` (at most once; a relative path is taken from the
 * scenario file's folder) adds the file's speed, angle and load columns to
 * those profiles (the sum is clamped as before) and makes its supply
 * columns the plants' supplies over time (canfdi_sim_scn_supply; a supply
 * column and `param <that supply>` exclude each other). The file is
 * checked whole when the scenario is parsed and must reach the end of the
 * scenario; it is read again in blocks while the scenario is evaluated
 * (canfdi_sim_csvprof.h), so a run checks canfdi_sim_scn_run_error.
 *
 * Cost: parsing is O(file size) (the scenario and its profile file).
 * Memory: sizeof(canfdi_sim_scn_t) ~ 22 kB (three profiles, the CSV
 * profile's block, CANFDI_SIM_MAX_FAULTS faults, CANFDI_SIM_SCN_MAX_EXPECT
 * expectations, CANFDI_SIM_SCN_MAX_ACTIONS actions), caller-owned; the
 * files are read line by line into stack buffers. No heap.
 */
#ifndef CANFDI_SIM_SCENARIO_H
#define CANFDI_SIM_SCENARIO_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "canfdi_sim.h"
#include "canfdi_sim_csvprof.h"
#include "canfdi_sim_profile.h"

#define CANFDI_SIM_SCN_LINE_MAX 256U
#define CANFDI_SIM_SCN_MAX_EXPECT 64U
#define CANFDI_SIM_SCN_MAX_ACTIONS 64U
#define CANFDI_SIM_SCN_MAX_UDS 64U
#define CANFDI_SIM_SCN_UDS_BYTES 64U
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

/* `expect dtc_status` bit names, in status-bit order (bit 0 first). */
#define CANFDI_SIM_SCN_STATUS_BITS "TF", "TFTOC", "PDTC", "CDTC", "TNCSLC", "TFSLC", "TNCTOC", "WIR"

/* `expect freeze` signals (canfdi_dtc_ff_t fields, in the units named). */
#define CANFDI_SIM_FF_TIME 0U       /* time_ms, s */
#define CANFDI_SIM_FF_DCM_SPEED 1U  /* omega, rad/s */
#define CANFDI_SIM_FF_DCM_IA 2U     /* ia, A */
#define CANFDI_SIM_FF_DCM_UA 3U     /* ua, V */
#define CANFDI_SIM_FF_THR_ANGLE 4U  /* thr_angle, deg (the ECU's voted angle) */
#define CANFDI_SIM_FF_DCM_SUPPLY 5U /* supply, V */
#define CANFDI_SIM_FF_DEG_DCM 6U    /* deg_dcm, 0 normal .. 3 fail_silent */
#define CANFDI_SIM_FF_DEG_THR 7U    /* deg_thr */
#define CANFDI_SIM_N_FF 8U

typedef struct {
  double t_s;
  char kind[16];    /* dtc | no_dtc | degradation | dtc_status | occurrence | freeze */
  char arg1[16];    /* code or subsystem */
  char arg2[64];    /* dtc: status; degradation: state; dtc_status: the bits as
                     * written; freeze: the signal name ("" if absent) */
  uint8_t st_mask;  /* dtc_status: the bits named */
  uint8_t st_value; /* dtc_status: their expected values (within st_mask) */
  uint8_t ff_signal;/* freeze: CANFDI_SIM_FF_* */
  double lo;        /* occurrence: n; freeze: min */
  double hi;        /* occurrence: n; freeze: max */
  unsigned line;
} canfdi_sim_expect_t;

#define CANFDI_SIM_ACT_CYCLE 0U       /* canfdi_dtc_cycle_end + canfdi_dtc_cycle_start */
#define CANFDI_SIM_ACT_CLEAR 1U       /* canfdi_dtc_clear(code or all) */
#define CANFDI_SIM_ACT_POWER_CYCLE 2U /* store to NVM, re-init the app, load */

/* An action on the ECU side (SIL rig only), before its step at t_us. */
typedef struct {
  int64_t t_us;
  uint8_t kind;     /* CANFDI_SIM_ACT_* */
  char code[8];     /* clear: trouble code, "" = all */
  unsigned line;
} canfdi_sim_action_t;

/* A tester's UDS request (SIL rig only): sent at t_us (after the previous
 * one's response), its response judged against the pattern. */
typedef struct {
  int64_t t_us;
  bool functional;  /* UdsFuncReq 0x7DF (single frame), else UdsPhysReq 0x7E0 */
  bool judged;      /* an `expect` part was given */
  bool none;        /* expect none: no response at all */
  bool any_tail;    /* the pattern ends with '*': any further bytes */
  uint8_t req_len;
  uint8_t pat_len;
  uint8_t req[CANFDI_SIM_SCN_UDS_BYTES];
  uint8_t pat[CANFDI_SIM_SCN_UDS_BYTES];
  uint8_t pat_any[CANFDI_SIM_SCN_UDS_BYTES]; /* 1: '..', any byte */
  unsigned line;
} canfdi_sim_uds_t;

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
  canfdi_sim_action_t actions[CANFDI_SIM_SCN_MAX_ACTIONS]; /* non-decreasing t_us */
  size_t n_actions;
  bool has_profile;                /* a `profile` line was given */
  unsigned profile_line;
  canfdi_sim_csvprof_t profile;    /* its file (path resolved against the scenario's folder) */
  canfdi_sim_uds_t uds[CANFDI_SIM_SCN_MAX_UDS]; /* non-decreasing t_us */
  size_t n_uds;
} canfdi_sim_scn_t;

/* Name of a CANFDI_SIM_FF_* signal; "?" if out of range. */
const char *canfdi_sim_ff_name(unsigned signal);
/* Name of a status bit 0..7 (TF .. WIR); "?" if out of range. */
const char *canfdi_sim_status_bit_name(unsigned bit);

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

/* The plants' supplies at t_us: the profile's supply columns where it has
 * them, else the constant parameters (cfg.dcm.supply_V, cfg.thr.supply_V).
 * Apply them with canfdi_sim_set_supply before the step from t_us. */
void canfdi_sim_scn_supply(canfdi_sim_scn_t *scn, int64_t t_us, double *dcm_supply_V,
                           double *thr_supply_V);

/* NULL while the run is fine; else the profile file's read error during
 * the run ("<file>:<line>: ..."; canfdi_sim_csvprof.h). The values hold
 * from that point: a runner stops and reports it. */
const char *canfdi_sim_scn_run_error(const canfdi_sim_scn_t *scn);

#endif /* CANFDI_SIM_SCENARIO_H */
