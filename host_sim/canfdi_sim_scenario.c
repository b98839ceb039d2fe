/* canfdi_sim_scenario.c — see canfdi_sim_scenario.h and SCENARIO.md. */
#include "canfdi_sim_scenario.h"

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/canfdi_common.h"
#include "gen/canfdi_faults.h"

#define MAX_TOKENS 100U /* a uds line of a long request and its pattern fits */

/* Physical ranges of the profiled quantities (clamp of the sum) and the
 * largest magnitude one component may have (the span of the range). */
#define SPEED_LIM_RAD_S 400.0
#define ANGLE_MAX_DEG 90.0
#define LOAD_LIM_NM 10.0

typedef struct {
  const char *name;
  size_t offset;   /* of a double inside canfdi_sim_cfg_t */
  double lo;
  double hi;
} param_desc_t;

static const param_desc_t params[] = {
    {"dcm_ra_cold_ohm", offsetof(canfdi_sim_cfg_t, dcm.ra_cold_ohm), 0.01, 100.0},
    {"dcm_la_H", offsetof(canfdi_sim_cfg_t, dcm.la_H), 1e-5, 1.0},
    {"dcm_psi_Vs", offsetof(canfdi_sim_cfg_t, dcm.psi_Vs), 0.01, 10.0},
    {"dcm_j_kgm2", offsetof(canfdi_sim_cfg_t, dcm.j_kgm2), 1e-6, 10.0},
    {"dcm_mf0_Nm", offsetof(canfdi_sim_cfg_t, dcm.mf0_Nm), 0.0, 10.0},
    {"dcm_mf1_Nms", offsetof(canfdi_sim_cfg_t, dcm.mf1_Nms), 0.0, 1.0},
    {"dcm_ambient_C", offsetof(canfdi_sim_cfg_t, dcm.ambient_C), -40.0, 80.0},
    {"dcm_rth_K_W", offsetof(canfdi_sim_cfg_t, dcm.rth_K_W), 0.01, 100.0},
    {"dcm_cth_J_K", offsetof(canfdi_sim_cfg_t, dcm.cth_J_K), 1.0, 1e6},
    {"dcm_supply_V", offsetof(canfdi_sim_cfg_t, dcm.supply_V), 0.0, 80.0},
    {"thr_j_kgm2", offsetof(canfdi_sim_cfg_t, thr.j_kgm2), 1e-5, 1.0},
    {"thr_b_Nms", offsetof(canfdi_sim_cfg_t, thr.b_Nms), 0.0, 1.0},
    {"thr_k_Nm_A", offsetof(canfdi_sim_cfg_t, thr.k_Nm_A), 0.01, 10.0},
    {"thr_r_ohm", offsetof(canfdi_sim_cfg_t, thr.r_ohm), 0.01, 100.0},
    {"thr_l_H", offsetof(canfdi_sim_cfg_t, thr.l_H), 1e-5, 1.0},
    {"thr_spring_Nm_rad", offsetof(canfdi_sim_cfg_t, thr.spring_Nm_rad), 0.0, 10.0},
    {"thr_pretension_Nm", offsetof(canfdi_sim_cfg_t, thr.pretension_Nm), 0.0, 10.0},
    {"thr_friction_Nm", offsetof(canfdi_sim_cfg_t, thr.friction_Nm), 0.0, 10.0},
    {"thr_limp_home_deg", offsetof(canfdi_sim_cfg_t, thr.limp_home_deg), 1.0, 30.0},
    {"thr_supply_V", offsetof(canfdi_sim_cfg_t, thr.supply_V), 0.0, 16.0},
};
#define N_PARAMS (sizeof params / sizeof params[0])

static const char *const init_names[CANFDI_SIM_N_INIT] = {"dcm_speed", "dcm_current",
                                                          "dcm_winding", "thr_angle"};
static const double init_lo[CANFDI_SIM_N_INIT] = {-400.0, -30.0, -40.0, 0.0};
static const double init_hi[CANFDI_SIM_N_INIT] = {400.0, 30.0, 200.0, 90.0};

/* Noise sigma may be at most this fraction of the sensor's ADC span. */
#define SIGMA_MAX_OF_SPAN 0.1
static const double sensor_span[CANFDI_SIM_N_SENSORS] = {120.0, 60.0, 800.0, 80.0,
                                                         5.0,   5.0,  20.0,  16.0};

/* Parser state for one text. */
typedef struct {
  canfdi_sim_scn_t *scn;
  const char *name;
  canfdi_sim_scn_err_t *err;
  unsigned line;
  bool has_duration;
  bool has_seed;
  bool has_fan;
  bool has_noise[CANFDI_SIM_N_SENSORS];
  bool has_param[N_PARAMS];
  bool has_thermal;
  unsigned fault_line[CANFDI_SIM_MAX_FAULTS];
} parser_t;

static int fail(parser_t *ps, const char *fmt, ...)
{
  char tmp[256];
  va_list ap;
  va_start(ap, fmt);
  (void)vsnprintf(tmp, sizeof tmp, fmt, ap);
  va_end(ap);
  (void)snprintf(ps->err->msg, sizeof ps->err->msg, "%s:%u: %s", ps->name, ps->line, tmp);
  ps->err->line = ps->line;
  return -CANFDI_EINVAL;
}

/* Parses a whole token as a finite double. */
static bool num(const char *tok, double *out)
{
  char *end = NULL;
  double v;
  bool ok;
  errno = 0;
  v = strtod(tok, &end);
  ok = (end != tok) && (*end == '\0') && (errno == 0) && isfinite(v);
  if (ok) {
    *out = v;
  }
  return ok;
}

static bool u64(const char *tok, uint64_t *out)
{
  char *end = NULL;
  unsigned long long v = 0U;
  bool ok = (tok[0] >= '0') && (tok[0] <= '9'); /* no sign, no space */
  if (ok) {
    errno = 0;
    v = strtoull(tok, &end, 10);
    ok = (end != tok) && (*end == '\0') && (errno == 0);
  }
  if (ok) {
    *out = (uint64_t)v;
  }
  return ok;
}

/* Reads argument i as a number in [lo, hi]. */
static int arg_num(parser_t *ps, char **tok, size_t i, const char *what, double lo, double hi,
                   double *out)
{
  int rc = CANFDI_OK;
  if (!num(tok[i], out)) {
    rc = fail(ps, "%s: '%s' is not a number", what, tok[i]);
  } else if ((*out < lo) || (*out > hi)) {
    rc = fail(ps, "%s %g out of range [%g, %g]", what, *out, lo, hi);
  } else {
    /* fine */
  }
  return rc;
}

static int want_args(parser_t *ps, size_t n, size_t lo, size_t hi, const char *usage)
{
  int rc = CANFDI_OK;
  if ((n < lo) || (n > hi)) {
    rc = fail(ps, "%s to '%s' (usage: %s)", (n < lo) ? "too few arguments" : "too many arguments",
              usage, usage);
  }
  return rc;
}

static int do_profile(parser_t *ps, canfdi_sim_profile_t *p, const char *what, double lim,
                      char **tok, size_t n)
{
  int rc = CANFDI_OK;
  const char *shape = (n > 1U) ? tok[1] : "";
  double a[5] = {0.0, 0.0, 0.0, 0.0, 0.0};
  uint64_t seed = 0U;
  uint8_t kind = 0U;
  const double tmax = CANFDI_SIM_SCN_MAX_DURATION_S;

  if (strcmp(shape, "const") == 0) {
    kind = CANFDI_SIM_PROF_CONST;
    rc = want_args(ps, n, 3U, 3U, "<quantity> const <value>");
    if (rc == CANFDI_OK) {
      rc = arg_num(ps, tok, 2U, "value", -lim, lim, &a[2]);
    }
  } else if (strcmp(shape, "step") == 0) {
    kind = CANFDI_SIM_PROF_STEP;
    rc = want_args(ps, n, 4U, 4U, "<quantity> step <t0> <delta>");
    if (rc == CANFDI_OK) {
      rc = arg_num(ps, tok, 2U, "t0", 0.0, tmax, &a[0]);
    }
    if (rc == CANFDI_OK) {
      rc = arg_num(ps, tok, 3U, "delta", -2.0 * lim, 2.0 * lim, &a[2]);
    }
  } else if (strcmp(shape, "ramp") == 0) {
    kind = CANFDI_SIM_PROF_RAMP;
    rc = want_args(ps, n, 5U, 5U, "<quantity> ramp <t0> <t1> <delta>");
    if (rc == CANFDI_OK) {
      rc = arg_num(ps, tok, 2U, "t0", 0.0, tmax, &a[0]);
    }
    if (rc == CANFDI_OK) {
      rc = arg_num(ps, tok, 3U, "t1", 0.0, tmax, &a[1]);
    }
    if (rc == CANFDI_OK) {
      rc = arg_num(ps, tok, 4U, "delta", -2.0 * lim, 2.0 * lim, &a[2]);
    }
  } else if (strcmp(shape, "prbs") == 0) {
    kind = CANFDI_SIM_PROF_PRBS;
    rc = want_args(ps, n, 7U, 7U, "<quantity> prbs <t0> <t1> <amplitude> <bit_s> <seed>");
    if (rc == CANFDI_OK) {
      rc = arg_num(ps, tok, 2U, "t0", 0.0, tmax, &a[0]);
    }
    if (rc == CANFDI_OK) {
      rc = arg_num(ps, tok, 3U, "t1", 0.0, tmax, &a[1]);
    }
    if (rc == CANFDI_OK) {
      rc = arg_num(ps, tok, 4U, "amplitude", 0.0, lim, &a[2]);
    }
    if (rc == CANFDI_OK) {
      rc = arg_num(ps, tok, 5U, "bit period", 1e-3, tmax, &a[3]);
    }
    if ((rc == CANFDI_OK) && (!u64(tok[6], &seed) || (seed > UINT32_MAX))) {
      rc = fail(ps, "prbs seed '%s' is not an integer in 0..4294967295", tok[6]);
    }
  } else if (strcmp(shape, "sine") == 0) {
    kind = CANFDI_SIM_PROF_SINE;
    rc = want_args(ps, n, 6U, 6U, "<quantity> sine <t0> <t1> <amplitude> <freq_hz>");
    if (rc == CANFDI_OK) {
      rc = arg_num(ps, tok, 2U, "t0", 0.0, tmax, &a[0]);
    }
    if (rc == CANFDI_OK) {
      rc = arg_num(ps, tok, 3U, "t1", 0.0, tmax, &a[1]);
    }
    if (rc == CANFDI_OK) {
      rc = arg_num(ps, tok, 4U, "amplitude", 0.0, lim, &a[2]);
    }
    if (rc == CANFDI_OK) {
      rc = arg_num(ps, tok, 5U, "frequency", 1e-6, 500.0, &a[3]);
    }
  } else {
    rc = fail(ps, "unknown %s profile shape '%s' (const, step, ramp, prbs, sine%s)", what, shape,
              (p == &ps->scn->load) ? ", fan" : "");
  }
  if ((rc == CANFDI_OK) && (kind != CANFDI_SIM_PROF_CONST) && (kind != CANFDI_SIM_PROF_STEP) &&
      !(a[1] > a[0])) {
    rc = fail(ps, "t1 (%g) must be after t0 (%g)", a[1], a[0]);
  }
  if (rc == CANFDI_OK) {
    const int r = canfdi_sim_profile_add(p, kind, a[0], a[1], a[2], a[3], (uint32_t)seed);
    if (r == -CANFDI_ERANGE) {
      rc = fail(ps, "too many %s components (at most %u)", what, CANFDI_SIM_PROFILE_MAX);
    } else if (r != CANFDI_OK) {
      rc = fail(ps, "invalid %s component", what);
    } else {
      /* added */
    }
  }
  return rc;
}

static int do_fault(parser_t *ps, char **tok, size_t n)
{
  canfdi_sim_scn_t *scn = ps->scn;
  int rc = want_args(ps, n, 5U, 7U,
                     "fault <t_start> <name> <mode> <magnitude|default> [<ramp_s> | <period_s> <duty>]");
  int id = -1;
  int mode = -1;
  double t0 = 0.0;
  double mag = 0.0;
  double ramp = 0.0;
  double period = 0.0;
  double duty = 0.0;
  canfdi_sim_fault_spec_t spec;

  if (rc == CANFDI_OK) {
    rc = arg_num(ps, tok, 1U, "fault start time", 0.0, CANFDI_SIM_SCN_MAX_DURATION_S, &t0);
  }
  if (rc == CANFDI_OK) {
    id = canfdi_sim_fault_find(tok[2]);
    if (id < 0) {
      rc = fail(ps, "unknown fault '%s' (see dbc/faults.csv or canfdi-sim --list-faults)", tok[2]);
    }
  }
  if (rc == CANFDI_OK) {
    mode = canfdi_sim_fault_mode_find(tok[3]);
    if (mode < 0) {
      rc = fail(ps, "unknown fault mode '%s' (abrupt, incipient, intermittent)", tok[3]);
    }
  }
  if (rc == CANFDI_OK) {
    if (strcmp(tok[4], "default") == 0) {
      mag = canfdi_fault_table[id].default_magnitude;
    } else if (!num(tok[4], &mag)) {
      rc = fail(ps, "fault magnitude '%s' is not a number", tok[4]);
    } else {
      /* explicit magnitude */
    }
  }
  if (rc == CANFDI_OK) {
    if (mode == (int)CANFDI_SIM_MODE_ABRUPT) {
      rc = want_args(ps, n, 5U, 5U, "fault <t_start> <name> abrupt <magnitude>");
    } else if (mode == (int)CANFDI_SIM_MODE_INCIPIENT) {
      rc = want_args(ps, n, 6U, 6U, "fault <t_start> <name> incipient <magnitude> <ramp_s>");
      if (rc == CANFDI_OK) {
        rc = arg_num(ps, tok, 5U, "ramp_s", 1e-6, CANFDI_SIM_SCN_MAX_DURATION_S, &ramp);
      }
    } else {
      rc = want_args(ps, n, 7U, 7U,
                     "fault <t_start> <name> intermittent <magnitude> <period_s> <duty>");
      if (rc == CANFDI_OK) {
        rc = arg_num(ps, tok, 5U, "period_s", 2e-6, CANFDI_SIM_SCN_MAX_DURATION_S, &period);
      }
      if ((rc == CANFDI_OK) && (!num(tok[6], &duty) || !(duty > 0.0) || (duty > 1.0))) {
        rc = fail(ps, "duty '%s' must be a number in (0, 1]", tok[6]);
      }
    }
  }
  if (rc == CANFDI_OK) {
    const int r = canfdi_sim_fault_spec_make(&spec, (uint8_t)id, (uint8_t)mode, t0, mag, ramp,
                                             period, duty);
    if (r == -CANFDI_ERANGE) {
      double lo = 0.0;
      double hi = 0.0;
      bool lo_open = false;
      (void)canfdi_sim_fault_magnitude_range((uint8_t)id, &lo, &hi, &lo_open);
      rc = fail(ps, "magnitude %g of %s out of range %c%g, %g] (unit %s)", mag, tok[2],
                lo_open ? '(' : '[', lo, hi, canfdi_fault_table[id].unit);
    } else if (r != CANFDI_OK) {
      rc = fail(ps, "mode %s not allowed for %s (allowed: %s)", tok[3], tok[2],
                canfdi_fault_table[id].modes);
    } else if (scn->n_faults >= CANFDI_SIM_MAX_FAULTS) {
      rc = fail(ps, "too many faults (at most %u)", CANFDI_SIM_MAX_FAULTS);
    } else {
      ps->fault_line[scn->n_faults] = ps->line;
      scn->faults[scn->n_faults] = spec;
      scn->n_faults++;
    }
  }
  return rc;
}

static bool dtc_known(const char *code)
{
  size_t i;
  bool found = false;
  for (i = 0U; i < canfdi_dtc_table_len; i++) {
    if (strcmp(canfdi_dtc_table[i].code, code) == 0) {
      found = true;
    }
  }
  return found;
}

static const char *const status_bit_names[8] = {CANFDI_SIM_SCN_STATUS_BITS};

static const char *const ff_names[CANFDI_SIM_N_FF] = {"time",     "dcm_speed", "dcm_ia",  "dcm_ua",
                                                      "thr_angle", "dcm_supply", "deg_dcm", "deg_thr"};

const char *canfdi_sim_ff_name(unsigned signal)
{
  return (signal < CANFDI_SIM_N_FF) ? ff_names[signal] : "?";
}

const char *canfdi_sim_status_bit_name(unsigned bit)
{
  return (bit < 8U) ? status_bit_names[bit] : "?";
}

/* "TF=1,PDTC=0,..." (any subset, each name once) or "0xNN" (all eight). */
static int parse_status_bits(parser_t *ps, const char *text, uint8_t *mask, uint8_t *value)
{
  int rc = CANFDI_OK;
  *mask = 0U;
  *value = 0U;
  if ((text[0] == '0') && ((text[1] == 'x') || (text[1] == 'X'))) {
    char *end = NULL;
    const unsigned long v = strtoul(text + 2, &end, 16);
    const size_t len = strlen(text);
    bool hex = (len >= 3U) && (len <= 4U);
    size_t i;
    for (i = 2U; i < len; i++) {
      hex = hex && (strchr("0123456789abcdefABCDEF", text[i]) != NULL);
    }
    if (!hex || (*end != '\0') || (v > 0xFFUL)) {
      rc = fail(ps, "status byte '%s' must be 0x00..0xFF", text);
    } else {
      *mask = 0xFFU;
      *value = (uint8_t)v;
    }
  } else {
    const char *p = text;
    while ((rc == CANFDI_OK) && (*p != '\0')) {
      const char *eq = strchr(p, '=');
      const char *comma = strchr(p, ',');
      const size_t len = (eq != NULL) ? (size_t)(eq - p) : 0U;
      unsigned b;
      unsigned k = 8U;
      for (b = 0U; b < 8U; b++) {
        if ((len > 0U) && (strlen(status_bit_names[b]) == len) &&
            (strncmp(status_bit_names[b], p, len) == 0)) {
          k = b;
        }
      }
      if ((eq == NULL) || ((comma != NULL) && (comma < eq)) || (k == 8U)) {
        rc = fail(ps, "status bits '%s': expected NAME=0|1[,NAME=0|1...] with NAME one of "
                      "TF, TFTOC, PDTC, CDTC, TNCSLC, TFSLC, TNCTOC, WIR (or a byte 0xNN)", text);
      } else if (((eq[1] != '0') && (eq[1] != '1')) || ((eq[2] != ',') && (eq[2] != '\0')) ||
                 ((eq[2] == ',') && (eq[3] == '\0'))) {
        rc = fail(ps, "status bits '%s': %s must be 0 or 1", text, status_bit_names[k]);
      } else if ((*mask & (1U << k)) != 0U) {
        rc = fail(ps, "status bits '%s': %s named twice", text, status_bit_names[k]);
      } else {
        *mask = (uint8_t)(*mask | (1U << k));
        if (eq[1] == '1') {
          *value = (uint8_t)(*value | (1U << k));
        }
        p = (eq[2] == ',') ? (eq + 3) : (eq + 2);
      }
    }
  }
  return rc;
}

static int do_expect(parser_t *ps, char **tok, size_t n)
{
  canfdi_sim_scn_t *scn = ps->scn;
  canfdi_sim_expect_t e;
  int rc = want_args(ps, n, 3U, 7U, "expect <t> dtc <code> [pending|confirmed] | expect <t> no_dtc"
                                    " | expect <t> degradation <dcm|thr> <state>"
                                    " | expect <t> dtc_status <code> <bits>"
                                    " | expect <t> occurrence <code> <n>"
                                    " | expect <t> freeze <code> <signal> <min> <max>");
  memset(&e, 0, sizeof e);
  if (rc == CANFDI_OK) {
    rc = arg_num(ps, tok, 1U, "expect time", 0.0, CANFDI_SIM_SCN_MAX_DURATION_S, &e.t_s);
  }
  if (rc == CANFDI_OK) {
    const char *k = tok[2];
    if (strcmp(k, "dtc") == 0) {
      rc = want_args(ps, n, 4U, 5U, "expect <t> dtc <code> [pending|confirmed]");
      if ((rc == CANFDI_OK) && !dtc_known(tok[3])) {
        rc = fail(ps, "unknown trouble code '%s' (see dbc/dtcs.csv)", tok[3]);
      }
      if ((rc == CANFDI_OK) && (n == 5U) && (strcmp(tok[4], "pending") != 0) &&
          (strcmp(tok[4], "confirmed") != 0)) {
        rc = fail(ps, "dtc status '%s' must be pending or confirmed", tok[4]);
      }
    } else if (strcmp(k, "no_dtc") == 0) {
      rc = want_args(ps, n, 3U, 3U, "expect <t> no_dtc");
    } else if (strcmp(k, "degradation") == 0) {
      rc = want_args(ps, n, 5U, 5U, "expect <t> degradation <dcm|thr> <normal|degraded|fail_safe>");
      if ((rc == CANFDI_OK) && (strcmp(tok[3], "dcm") != 0) && (strcmp(tok[3], "thr") != 0)) {
        rc = fail(ps, "subsystem '%s' must be dcm or thr", tok[3]);
      }
      if ((rc == CANFDI_OK) && (strcmp(tok[4], "normal") != 0) &&
          (strcmp(tok[4], "degraded") != 0) && (strcmp(tok[4], "fail_safe") != 0)) {
        rc = fail(ps, "degradation '%s' must be normal, degraded or fail_safe", tok[4]);
      }
    } else if (strcmp(k, "dtc_status") == 0) {
      rc = want_args(ps, n, 5U, 5U, "expect <t> dtc_status <code> <NAME=0|1,...>");
      if ((rc == CANFDI_OK) && !dtc_known(tok[3])) {
        rc = fail(ps, "unknown trouble code '%s' (see dbc/dtcs.csv)", tok[3]);
      }
      if ((rc == CANFDI_OK) && (strlen(tok[4]) >= sizeof e.arg2)) {
        rc = fail(ps, "status bits '%s' too long", tok[4]);
      }
      if (rc == CANFDI_OK) {
        rc = parse_status_bits(ps, tok[4], &e.st_mask, &e.st_value);
      }
    } else if (strcmp(k, "occurrence") == 0) {
      uint64_t v = 0U;
      rc = want_args(ps, n, 5U, 5U, "expect <t> occurrence <code> <n>");
      if ((rc == CANFDI_OK) && !dtc_known(tok[3])) {
        rc = fail(ps, "unknown trouble code '%s' (see dbc/dtcs.csv)", tok[3]);
      }
      if ((rc == CANFDI_OK) && (!u64(tok[4], &v) || (v > 255U))) {
        rc = fail(ps, "occurrence '%s' must be an integer 0..255", tok[4]);
      }
      e.lo = (double)v;
      e.hi = (double)v;
    } else if (strcmp(k, "freeze") == 0) {
      rc = want_args(ps, n, 7U, 7U, "expect <t> freeze <code> <signal> <min> <max>");
      if ((rc == CANFDI_OK) && !dtc_known(tok[3])) {
        rc = fail(ps, "unknown trouble code '%s' (see dbc/dtcs.csv)", tok[3]);
      }
      if (rc == CANFDI_OK) {
        unsigned i;
        e.ff_signal = (uint8_t)CANFDI_SIM_N_FF;
        for (i = 0U; i < CANFDI_SIM_N_FF; i++) {
          if (strcmp(tok[4], ff_names[i]) == 0) {
            e.ff_signal = (uint8_t)i;
          }
        }
        if (e.ff_signal == (uint8_t)CANFDI_SIM_N_FF) {
          rc = fail(ps, "unknown freeze-frame signal '%s' (time, dcm_speed, dcm_ia, dcm_ua, "
                        "thr_angle, dcm_supply, deg_dcm, deg_thr)", tok[4]);
        }
      }
      if (rc == CANFDI_OK) {
        rc = arg_num(ps, tok, 5U, "freeze min", -1e9, 1e9, &e.lo);
      }
      if (rc == CANFDI_OK) {
        rc = arg_num(ps, tok, 6U, "freeze max", -1e9, 1e9, &e.hi);
      }
      if ((rc == CANFDI_OK) && (e.hi < e.lo)) {
        rc = fail(ps, "freeze max (%g) below min (%g)", e.hi, e.lo);
      }
    } else {
      rc = fail(ps, "unknown expectation '%s' (dtc, no_dtc, degradation, dtc_status, occurrence, "
                    "freeze)", k);
    }
  }
  if ((rc == CANFDI_OK) && (scn->n_expects >= CANFDI_SIM_SCN_MAX_EXPECT)) {
    rc = fail(ps, "too many expect lines (at most %u)", CANFDI_SIM_SCN_MAX_EXPECT);
  }
  if (rc == CANFDI_OK) {
    /* Tokens were length-checked against the known sets above; codes and
     * names are short, so the copies cannot truncate. */
    (void)snprintf(e.kind, sizeof e.kind, "%s", tok[2]);
    (void)snprintf(e.arg1, sizeof e.arg1, "%s", (n > 3U) ? tok[3] : "");
    (void)snprintf(e.arg2, sizeof e.arg2, "%s", (n > 4U) ? tok[4] : "");
    e.line = ps->line;
    scn->expects[scn->n_expects] = e;
    scn->n_expects++;
  }
  return rc;
}

/* cycle <t> | clear <t> [<code>|all] | power_cycle <t> */
static int do_action(parser_t *ps, char **tok, size_t n, uint8_t kind)
{
  canfdi_sim_scn_t *scn = ps->scn;
  canfdi_sim_action_t a;
  double t = 0.0;
  int rc;
  memset(&a, 0, sizeof a);
  if (kind == (uint8_t)CANFDI_SIM_ACT_CLEAR) {
    rc = want_args(ps, n, 2U, 3U, "clear <t> [<code>|all]");
  } else {
    rc = want_args(ps, n, 2U, 2U, (kind == (uint8_t)CANFDI_SIM_ACT_CYCLE) ? "cycle <t>" : "power_cycle <t>");
  }
  if (rc == CANFDI_OK) {
    rc = arg_num(ps, tok, 1U, "action time", 0.0, CANFDI_SIM_SCN_MAX_DURATION_S, &t);
  }
  if ((rc == CANFDI_OK) && (n == 3U) && (strcmp(tok[2], "all") != 0)) {
    if (!dtc_known(tok[2])) {
      rc = fail(ps, "unknown trouble code '%s' (see dbc/dtcs.csv, or all)", tok[2]);
    } else {
      (void)snprintf(a.code, sizeof a.code, "%s", tok[2]);
    }
  }
  if (rc == CANFDI_OK) {
    a.t_us = (int64_t)llround(t * 1e6);
    a.kind = kind;
    a.line = ps->line;
    if ((scn->n_actions > 0U) && (a.t_us < scn->actions[scn->n_actions - 1U].t_us)) {
      rc = fail(ps, "%s at %g s is before the previous cycle/clear/power_cycle line (write them in "
                    "time order)", tok[0], t);
    } else if (scn->n_actions >= CANFDI_SIM_SCN_MAX_ACTIONS) {
      rc = fail(ps, "too many cycle/clear/power_cycle lines (at most %u)", CANFDI_SIM_SCN_MAX_ACTIONS);
    } else {
      scn->actions[scn->n_actions] = a;
      scn->n_actions++;
    }
  }
  return rc;
}

/* Appends src to the string in dst (capacity cap), cutting at the end. */
static void append(char *dst, size_t cap, const char *src)
{
  size_t len = strlen(dst);
  while ((*src != '\0') && ((len + 1U) < cap)) {
    dst[len] = *src;
    len++;
    src++;
  }
  dst[len] = '\0';
}

/* profile <file.csv>: the path is taken from the scenario file's folder
 * unless it is absolute; the file is checked whole here. */
static int do_csv_profile(parser_t *ps, char **tok, size_t n)
{
  canfdi_sim_scn_t *scn = ps->scn;
  char path[CANFDI_SIM_CSV_PATH_MAX];
  char msg[sizeof ps->err->msg];
  const char *slash = strrchr(ps->name, '/');
  size_t dir_len = 0U;
  int rc = want_args(ps, n, 2U, 2U, "profile <file.csv>");
  if ((rc == CANFDI_OK) && scn->has_profile) {
    rc = fail(ps, "duplicate profile (one file per scenario)");
  }
  if ((rc == CANFDI_OK) && (tok[1][0] != '/') && (slash != NULL)) {
    dir_len = (size_t)(slash - ps->name) + 1U;
  }
  if ((rc == CANFDI_OK) && ((dir_len + strlen(tok[1]) + 1U) > sizeof path)) {
    rc = fail(ps, "profile path longer than %u characters", CANFDI_SIM_CSV_PATH_MAX - 1U);
  }
  if (rc == CANFDI_OK) {
    (void)memcpy(path, ps->name, dir_len);
    (void)memcpy(&path[dir_len], tok[1], strlen(tok[1]) + 1U);
    if (canfdi_sim_csvprof_open(&scn->profile, path, msg, sizeof msg) != CANFDI_OK) {
      /* the profile file's own "<file>:<line>: ..." first, then this line
       * (joined piece by piece: the whole is cut at the buffer's end) */
      char where[32];
      (void)snprintf(where, sizeof where, ":%u)", ps->line);
      ps->err->msg[0] = '\0';
      append(ps->err->msg, sizeof ps->err->msg, msg);
      append(ps->err->msg, sizeof ps->err->msg, " (profile of ");
      append(ps->err->msg, sizeof ps->err->msg, ps->name);
      append(ps->err->msg, sizeof ps->err->msg, where);
      ps->err->line = ps->line;
      rc = -CANFDI_EINVAL;
    } else {
      scn->has_profile = true;
      scn->profile_line = ps->line;
    }
  }
  return rc;
}

/* One hex byte "00".."FF" (case-insensitive); false if not one. */
static bool hex_byte(const char *s, uint8_t *v)
{
  unsigned x = 0U;
  bool ok = (strlen(s) == 2U);
  for (size_t i = 0U; ok && (i < 2U); i++) {
    const char c = s[i];
    const unsigned d = ((c >= '0') && (c <= '9'))   ? (unsigned)(c - '0')
                       : ((c >= 'a') && (c <= 'f')) ? (unsigned)(c - 'a' + 10)
                       : ((c >= 'A') && (c <= 'F')) ? (unsigned)(c - 'A' + 10)
                                                    : 16U;
    ok = d < 16U;
    x = (x << 4) | (d & 0x0FU);
  }
  *v = (uint8_t)x;
  return ok;
}

/* The expected response after `expect`: hex bytes, '..', a final '*', or none. */
static int uds_pattern(parser_t *ps, char **tok, size_t n, size_t k, canfdi_sim_uds_t *u)
{
  int rc = CANFDI_OK;
  u->judged = true;
  if ((k < n) && (strcmp(tok[k], "none") == 0)) {
    u->none = true;
    rc = (k + 1U == n) ? CANFDI_OK : fail(ps, "nothing may follow 'expect none'");
  } else if (k >= n) {
    rc = fail(ps, "expect what? hex bytes, '..' (any byte), a final '*' (any rest), or none");
  } else {
    for (; (rc == CANFDI_OK) && (k < n); k++) {
      uint8_t b = 0U;
      if ((strcmp(tok[k], "*") == 0) && (k + 1U == n)) {
        u->any_tail = true;
      } else if (u->pat_len >= CANFDI_SIM_SCN_UDS_BYTES) {
        rc = fail(ps, "expected response longer than %u bytes", CANFDI_SIM_SCN_UDS_BYTES);
      } else if (strcmp(tok[k], "..") == 0) {
        u->pat_any[u->pat_len] = 1U;
        u->pat_len++;
      } else if (hex_byte(tok[k], &b)) {
        u->pat[u->pat_len] = b;
        u->pat_len++;
      } else {
        rc = fail(ps, "'%s' is not a hex byte, '..' or a final '*'", tok[k]);
      }
    }
  }
  return rc;
}

/* uds <t> <phys|func> <hex byte>... [expect <pattern> | expect none] */
static int do_uds(parser_t *ps, char **tok, size_t n)
{
  canfdi_sim_scn_t *scn = ps->scn;
  canfdi_sim_uds_t *u = &scn->uds[(scn->n_uds < CANFDI_SIM_SCN_MAX_UDS) ? scn->n_uds : 0U];
  double t = 0.0;
  size_t k = 3U;
  int rc = want_args(ps, n, 4U, 3U + (2U * CANFDI_SIM_SCN_UDS_BYTES) + 2U,
                     "uds <t> <phys|func> <hex byte>... [expect <hex byte|..>... [*] | expect none]");
  if ((rc == CANFDI_OK) && (scn->n_uds >= CANFDI_SIM_SCN_MAX_UDS)) {
    rc = fail(ps, "too many uds lines (at most %u)", CANFDI_SIM_SCN_MAX_UDS);
  }
  if (rc == CANFDI_OK) {
    memset(u, 0, sizeof *u);
    rc = arg_num(ps, tok, 1U, "request time", 0.0, CANFDI_SIM_SCN_MAX_DURATION_S, &t);
  }
  if ((rc == CANFDI_OK) && (strcmp(tok[2], "phys") != 0) && (strcmp(tok[2], "func") != 0)) {
    rc = fail(ps, "addressing '%s': phys (0x7E0) or func (0x7DF)", tok[2]);
  }
  for (; (rc == CANFDI_OK) && (k < n) && (strcmp(tok[k], "expect") != 0); k++) {
    if (u->req_len >= CANFDI_SIM_SCN_UDS_BYTES) {
      rc = fail(ps, "request longer than %u bytes", CANFDI_SIM_SCN_UDS_BYTES);
    } else if (!hex_byte(tok[k], &u->req[u->req_len])) {
      rc = fail(ps, "'%s' is not a hex byte (two digits, e.g. 19 or 0A)", tok[k]);
    } else {
      u->req_len++;
    }
  }
  if ((rc == CANFDI_OK) && (u->req_len == 0U)) {
    rc = fail(ps, "uds: no request bytes");
  }
  u->functional = (rc == CANFDI_OK) && (strcmp(tok[2], "func") == 0);
  if ((rc == CANFDI_OK) && u->functional && (u->req_len > 7U)) {
    rc = fail(ps, "a functional request is one single frame: at most 7 bytes");
  }
  if ((rc == CANFDI_OK) && (k < n)) {
    rc = uds_pattern(ps, tok, n, k + 1U, u);
  }
  if (rc == CANFDI_OK) {
    u->t_us = (int64_t)llround(t * 1e6);
    u->line = ps->line;
    if ((scn->n_uds > 0U) && (u->t_us < scn->uds[scn->n_uds - 1U].t_us)) {
      rc = fail(ps, "uds at %g s is before the previous uds line (write them in time order)", t);
    } else {
      scn->n_uds++;
    }
  }
  return rc;
}

static int do_line(parser_t *ps, char *line)
{
  canfdi_sim_scn_t *scn = ps->scn;
  char *tok[MAX_TOKENS + 1U];
  size_t n = 0U;
  char *p = line;
  char *hash = strchr(line, '#');
  int rc = CANFDI_OK;
  const char *d;

  if (hash != NULL) {
    *hash = '\0';
  }
  while (rc == CANFDI_OK) {
    while ((*p == ' ') || (*p == '\t') || (*p == '\r') || (*p == '\n')) {
      p++;
    }
    if (*p == '\0') {
      break;
    }
    if (n > MAX_TOKENS) {
      rc = fail(ps, "too many tokens (at most %u)", MAX_TOKENS);
      break;
    }
    tok[n] = p;
    n++;
    while ((rc == CANFDI_OK) && (*p != '\0') && (*p != ' ') && (*p != '\t') && (*p != '\r') &&
           (*p != '\n')) {
      if (((unsigned char)*p < 0x20U) || ((unsigned char)*p > 0x7EU)) {
        rc = fail(ps, "non-printable or non-ASCII character (byte 0x%02X)",
                  (unsigned)(unsigned char)*p);
      }
      p++;
    }
    if ((rc == CANFDI_OK) && (*p != '\0')) {
      *p = '\0';
      p++;
    }
  }
  /* An error above, or an empty/comment line: nothing to interpret. */
  d = ((rc == CANFDI_OK) && (n > 0U)) ? tok[0] : "";
  if (d[0] == '\0') {
    /* done */
  } else if (strcmp(d, "duration") == 0) {
    rc = want_args(ps, n, 2U, 2U, "duration <seconds>");
    if ((rc == CANFDI_OK) && ps->has_duration) {
      rc = fail(ps, "duplicate duration");
    }
    if (rc == CANFDI_OK) {
      rc = arg_num(ps, tok, 1U, "duration", 1e-3, CANFDI_SIM_SCN_MAX_DURATION_S, &scn->duration_s);
    }
    ps->has_duration = true;
  } else if (strcmp(d, "seed") == 0) {
    rc = want_args(ps, n, 2U, 2U, "seed <unsigned integer>");
    if ((rc == CANFDI_OK) && ps->has_seed) {
      rc = fail(ps, "duplicate seed");
    }
    if ((rc == CANFDI_OK) && !u64(tok[1], &scn->cfg.seed)) {
      rc = fail(ps, "seed '%s' is not an unsigned 64-bit integer", tok[1]);
    }
    ps->has_seed = true;
  } else if (strcmp(d, "noise") == 0) {
    rc = want_args(ps, n, 3U, 3U, "noise <sensor> <sigma>");
    if (rc == CANFDI_OK) {
      const int s = canfdi_sim_sensor_find(tok[1]);
      if (s < 0) {
        rc = fail(ps, "unknown sensor '%s' (dcm_ua, dcm_ia, dcm_speed, dcm_supply, thr_tps1, "
                      "thr_tps2, thr_i, thr_supply)", tok[1]);
      } else if (ps->has_noise[s]) {
        rc = fail(ps, "duplicate noise for %s", tok[1]);
      } else {
        ps->has_noise[s] = true;
        rc = arg_num(ps, tok, 2U, "sigma", 0.0, SIGMA_MAX_OF_SPAN * sensor_span[s],
                     &scn->cfg.sigma[s]);
      }
    }
  } else if (strcmp(d, "init") == 0) {
    rc = want_args(ps, n, 3U, 3U, "init <dcm_speed|dcm_current|dcm_winding|thr_angle> <value>");
    if (rc == CANFDI_OK) {
      unsigned i;
      unsigned k = CANFDI_SIM_N_INIT;
      for (i = 0U; i < CANFDI_SIM_N_INIT; i++) {
        if (strcmp(tok[1], init_names[i]) == 0) {
          k = i;
        }
      }
      if (k == CANFDI_SIM_N_INIT) {
        rc = fail(ps, "unknown initial condition '%s' (dcm_speed, dcm_current, dcm_winding, "
                      "thr_angle)", tok[1]);
      } else if (scn->has_init[k]) {
        rc = fail(ps, "duplicate init %s", tok[1]);
      } else {
        scn->has_init[k] = true;
        rc = arg_num(ps, tok, 2U, tok[1], init_lo[k], init_hi[k], &scn->init[k]);
      }
    }
  } else if (strcmp(d, "param") == 0) {
    rc = want_args(ps, n, 3U, 3U, "param <name> <value>");
    if ((rc == CANFDI_OK) && (strcmp(tok[1], "dcm_thermal") == 0)) {
      if (ps->has_thermal) {
        rc = fail(ps, "duplicate param dcm_thermal");
      } else if ((strcmp(tok[2], "0") != 0) && (strcmp(tok[2], "1") != 0)) {
        rc = fail(ps, "dcm_thermal must be 0 or 1");
      } else {
        ps->has_thermal = true;
        scn->cfg.dcm.thermal = (tok[2][0] == '1');
      }
    } else if (rc == CANFDI_OK) {
      size_t i;
      size_t k = N_PARAMS;
      for (i = 0U; i < N_PARAMS; i++) {
        if (strcmp(tok[1], params[i].name) == 0) {
          k = i;
        }
      }
      if (k == N_PARAMS) {
        rc = fail(ps, "unknown parameter '%s' (see host_sim/SCENARIO.md)", tok[1]);
      } else if (ps->has_param[k]) {
        rc = fail(ps, "duplicate param %s", tok[1]);
      } else {
        double *dst = (double *)(void *)((char *)&scn->cfg + params[k].offset);
        ps->has_param[k] = true;
        rc = arg_num(ps, tok, 2U, tok[1], params[k].lo, params[k].hi, dst);
      }
    } else {
      /* argument count error already reported */
    }
  } else if (strcmp(d, "speed") == 0) {
    rc = do_profile(ps, &scn->speed, "speed", 2.0 * SPEED_LIM_RAD_S, tok, n);
  } else if (strcmp(d, "angle") == 0) {
    rc = do_profile(ps, &scn->angle, "angle", ANGLE_MAX_DEG, tok, n);
  } else if ((strcmp(d, "load") == 0) && (n > 1U) && (strcmp(tok[1], "fan") == 0)) {
    rc = want_args(ps, n, 3U, 3U, "load fan <k_Nms>");
    if ((rc == CANFDI_OK) && ps->has_fan) {
      rc = fail(ps, "duplicate load fan");
    }
    if (rc == CANFDI_OK) {
      rc = arg_num(ps, tok, 2U, "fan coefficient", 0.0, 1.0, &scn->cfg.dcm.load_k_fan_Nms);
    }
    ps->has_fan = true;
  } else if (strcmp(d, "load") == 0) {
    rc = do_profile(ps, &scn->load, "load", 2.0 * LOAD_LIM_NM, tok, n);
  } else if (strcmp(d, "fault") == 0) {
    rc = do_fault(ps, tok, n);
  } else if (strcmp(d, "expect") == 0) {
    rc = do_expect(ps, tok, n);
  } else if (strcmp(d, "cycle") == 0) {
    rc = do_action(ps, tok, n, (uint8_t)CANFDI_SIM_ACT_CYCLE);
  } else if (strcmp(d, "clear") == 0) {
    rc = do_action(ps, tok, n, (uint8_t)CANFDI_SIM_ACT_CLEAR);
  } else if (strcmp(d, "power_cycle") == 0) {
    rc = do_action(ps, tok, n, (uint8_t)CANFDI_SIM_ACT_POWER_CYCLE);
  } else if (strcmp(d, "profile") == 0) {
    rc = do_csv_profile(ps, tok, n);
  } else if (strcmp(d, "uds") == 0) {
    rc = do_uds(ps, tok, n);
  } else {
    rc = fail(ps, "unknown directive '%s' (duration, seed, noise, init, param, speed, angle, "
                  "load, profile, fault, expect, cycle, clear, power_cycle, uds)", d);
  }
  return rc;
}

static void scn_defaults(canfdi_sim_scn_t *scn)
{
  unsigned i;
  memset(scn, 0, sizeof *scn);
  scn->duration_s = 0.0;
  canfdi_sim_default_cfg(&scn->cfg);
  for (i = 0U; i < CANFDI_SIM_N_INIT; i++) {
    scn->has_init[i] = false;
    scn->init[i] = 0.0;
  }
  canfdi_sim_profile_init(&scn->speed, -SPEED_LIM_RAD_S, SPEED_LIM_RAD_S);
  canfdi_sim_profile_init(&scn->angle, 0.0, ANGLE_MAX_DEG);
  canfdi_sim_profile_init(&scn->load, -LOAD_LIM_NM, LOAD_LIM_NM);
  scn->n_faults = 0U;
  scn->n_expects = 0U;
  scn->n_actions = 0U;
  scn->n_uds = 0U;
}

static void parser_init(parser_t *ps, canfdi_sim_scn_t *scn, const char *name,
                        canfdi_sim_scn_err_t *err)
{
  memset(ps, 0, sizeof *ps);
  ps->scn = scn;
  ps->name = (name != NULL) ? name : "<scenario>";
  ps->err = err;
  err->msg[0] = '\0';
  err->line = 0U;
  scn_defaults(scn);
}

/* The profile file against the rest of the scenario: it reaches the end,
 * and no supply is given twice. */
static int finish_profile(parser_t *ps)
{
  canfdi_sim_scn_t *scn = ps->scn;
  const canfdi_sim_csvprof_t *pr = &scn->profile;
  static const unsigned supply_q[2] = {CANFDI_SIM_CSV_DCM_SUPPLY, CANFDI_SIM_CSV_THR_SUPPLY};
  int rc = CANFDI_OK;
  size_t i;
  size_t k;
  ps->line = scn->profile_line;
  if (((double)pr->t_last_us * 1e-6) < scn->duration_s) {
    rc = fail(ps, "profile %s ends at %g s, before the end of the scenario (duration %g s)",
              pr->path, (double)pr->t_last_us * 1e-6, scn->duration_s);
  }
  for (i = 0U; (rc == CANFDI_OK) && (i < 2U); i++) {
    const char *name = canfdi_sim_csvprof_name(supply_q[i]);
    for (k = 0U; k < N_PARAMS; k++) {
      if (pr->has[supply_q[i]] && ps->has_param[k] && (strcmp(params[k].name, name) == 0)) {
        rc = fail(ps, "profile %s has a %s column and the scenario sets param %s: give the supply "
                      "once", pr->path, name, name);
      }
    }
  }
  return rc;
}

/* Checks that need the whole file. */
static int finish(parser_t *ps)
{
  canfdi_sim_scn_t *scn = ps->scn;
  int rc = CANFDI_OK;
  size_t i;
  canfdi_sim_t probe;

  if (!ps->has_duration) {
    ps->line = 0U;
    rc = fail(ps, "missing 'duration <seconds>'");
  }
  for (i = 0U; (rc == CANFDI_OK) && (i < scn->n_faults); i++) {
    if ((double)scn->faults[i].t_start_us * 1e-6 >= scn->duration_s) {
      ps->line = ps->fault_line[i];
      rc = fail(ps, "fault starts at or after the end of the scenario (duration %g s)",
                scn->duration_s);
    }
  }
  for (i = 0U; (rc == CANFDI_OK) && (i < scn->n_actions); i++) {
    if ((double)scn->actions[i].t_us * 1e-6 >= scn->duration_s) {
      ps->line = scn->actions[i].line;
      rc = fail(ps, "action at or after the end of the scenario (duration %g s)", scn->duration_s);
    }
  }
  for (i = 0U; (rc == CANFDI_OK) && (i < scn->n_uds); i++) {
    if ((double)scn->uds[i].t_us * 1e-6 >= scn->duration_s) {
      ps->line = scn->uds[i].line;
      rc = fail(ps, "uds request at or after the end of the scenario (duration %g s)", scn->duration_s);
    }
  }
  for (i = 0U; (rc == CANFDI_OK) && (i < scn->n_expects); i++) {
    if (scn->expects[i].t_s > scn->duration_s) {
      ps->line = scn->expects[i].line;
      rc = fail(ps, "expectation after the end of the scenario (duration %g s)", scn->duration_s);
    }
  }
  if ((rc == CANFDI_OK) && scn->has_profile) {
    rc = finish_profile(ps);
  }
  if ((rc == CANFDI_OK) && (canfdi_sim_init(&probe, &scn->cfg) != CANFDI_OK)) {
    ps->line = 0U;
    rc = fail(ps, "the plant parameters are inconsistent");
  }
  if ((rc == CANFDI_OK) && scn->has_init[CANFDI_SIM_INIT_THR_ANGLE] &&
      (scn->init[CANFDI_SIM_INIT_THR_ANGLE] > scn->cfg.thr.max_deg)) {
    ps->line = 0U;
    rc = fail(ps, "initial throttle angle beyond the end stop");
  }
  return rc;
}

int canfdi_sim_scn_parse(canfdi_sim_scn_t *scn, const char *text, const char *name,
                         canfdi_sim_scn_err_t *err)
{
  parser_t ps;
  int rc = CANFDI_OK;
  const char *p = text;
  char buf[CANFDI_SIM_SCN_LINE_MAX + 1U];

  parser_init(&ps, scn, name, err);
  while ((rc == CANFDI_OK) && (p != NULL) && (*p != '\0')) {
    const char *nl = strchr(p, '\n');
    const size_t len = (nl != NULL) ? (size_t)(nl - p) : strlen(p);
    ps.line++;
    if (len > CANFDI_SIM_SCN_LINE_MAX) {
      rc = fail(&ps, "line longer than %u characters", CANFDI_SIM_SCN_LINE_MAX);
    } else if (memchr(p, '\0', len) != NULL) {
      rc = fail(&ps, "NUL byte in line");
    } else {
      memcpy(buf, p, len);
      buf[len] = '\0';
      rc = do_line(&ps, buf);
    }
    p = (nl != NULL) ? (nl + 1) : NULL;
  }
  if (rc == CANFDI_OK) {
    rc = finish(&ps);
  }
  return rc;
}

int canfdi_sim_scn_load(canfdi_sim_scn_t *scn, const char *path, canfdi_sim_scn_err_t *err)
{
  parser_t ps;
  int rc = CANFDI_OK;
  char buf[CANFDI_SIM_SCN_LINE_MAX + 2U];
  FILE *f;

  parser_init(&ps, scn, path, err);
  f = fopen(path, "rb");
  if (f == NULL) {
    (void)snprintf(err->msg, sizeof err->msg, "%s: cannot open: %s", path, strerror(errno));
    rc = -CANFDI_EINVAL;
  }
  while ((rc == CANFDI_OK) && (fgets(buf, (int)sizeof buf, f) != NULL)) {
    const size_t len = strlen(buf);
    ps.line++;
    if ((len > 0U) && (buf[len - 1U] != '\n') && !feof(f)) {
      rc = fail(&ps, "line longer than %u characters", CANFDI_SIM_SCN_LINE_MAX);
    } else if ((len > 0U) && (buf[len - 1U] == '\n') && ((len - 1U) > CANFDI_SIM_SCN_LINE_MAX)) {
      rc = fail(&ps, "line longer than %u characters", CANFDI_SIM_SCN_LINE_MAX);
    } else {
      rc = do_line(&ps, buf);
    }
  }
  if ((rc == CANFDI_OK) && ferror(f)) {
    ps.line = 0U;
    rc = fail(&ps, "read error");
  }
  if (f != NULL) {
    (void)fclose(f);
  }
  if (rc == CANFDI_OK) {
    rc = finish(&ps);
  }
  return rc;
}

int canfdi_sim_scn_setup(const canfdi_sim_scn_t *scn, canfdi_sim_t *sim)
{
  canfdi_sim_cfg_t cfg = scn->cfg;
  int rc;
  size_t i;
  /* the plants start with the profile's supplies at t = 0 (its first row) */
  if (scn->has_profile && scn->profile.has[CANFDI_SIM_CSV_DCM_SUPPLY]) {
    cfg.dcm.supply_V = scn->profile.first[CANFDI_SIM_CSV_DCM_SUPPLY];
  }
  if (scn->has_profile && scn->profile.has[CANFDI_SIM_CSV_THR_SUPPLY]) {
    cfg.thr.supply_V = scn->profile.first[CANFDI_SIM_CSV_THR_SUPPLY];
  }
  rc = canfdi_sim_init(sim, &cfg);
  if (rc == CANFDI_OK) {
    const double w = scn->has_init[CANFDI_SIM_INIT_DCM_SPEED] ? scn->init[CANFDI_SIM_INIT_DCM_SPEED] : 0.0;
    const double ia = scn->has_init[CANFDI_SIM_INIT_DCM_CURRENT] ? scn->init[CANFDI_SIM_INIT_DCM_CURRENT] : 0.0;
    const double temp = scn->has_init[CANFDI_SIM_INIT_DCM_WINDING] ? scn->init[CANFDI_SIM_INIT_DCM_WINDING]
                                                                   : scn->cfg.dcm.ambient_C;
    rc = canfdi_sim_dcm_set_state(&sim->dcm, ia, w, temp);
    if ((rc == CANFDI_OK) && scn->has_init[CANFDI_SIM_INIT_THR_ANGLE]) {
      rc = canfdi_sim_thr_set_state(&sim->thr, scn->init[CANFDI_SIM_INIT_THR_ANGLE], 0.0);
    }
  }
  for (i = 0U; (rc == CANFDI_OK) && (i < scn->n_faults); i++) {
    rc = canfdi_sim_add_fault(sim, &scn->faults[i]);
  }
  if (rc == CANFDI_OK) {
    canfdi_sim_resample(sim);
  }
  return rc;
}

void canfdi_sim_scn_eval(canfdi_sim_scn_t *scn, int64_t t_us, double *speed_rad_s,
                         double *angle_deg, double *load_Nm)
{
  double v[CANFDI_SIM_CSV_N] = {0.0, 0.0, 0.0, 0.0, 0.0};
  if (scn->has_profile) {
    canfdi_sim_csvprof_eval(&scn->profile, t_us, v);
  }
  *speed_rad_s = canfdi_sim_profile_eval_plus(&scn->speed, t_us, v[CANFDI_SIM_CSV_SPEED]);
  *angle_deg = canfdi_sim_profile_eval_plus(&scn->angle, t_us, v[CANFDI_SIM_CSV_ANGLE]);
  *load_Nm = canfdi_sim_profile_eval_plus(&scn->load, t_us, v[CANFDI_SIM_CSV_LOAD]);
}

void canfdi_sim_scn_supply(canfdi_sim_scn_t *scn, int64_t t_us, double *dcm_supply_V,
                           double *thr_supply_V)
{
  double v[CANFDI_SIM_CSV_N] = {0.0, 0.0, 0.0, 0.0, 0.0};
  v[CANFDI_SIM_CSV_DCM_SUPPLY] = scn->cfg.dcm.supply_V;
  v[CANFDI_SIM_CSV_THR_SUPPLY] = scn->cfg.thr.supply_V;
  if (scn->has_profile) {
    canfdi_sim_csvprof_eval(&scn->profile, t_us, v);
  }
  *dcm_supply_V = v[CANFDI_SIM_CSV_DCM_SUPPLY];
  *thr_supply_V = v[CANFDI_SIM_CSV_THR_SUPPLY];
}

const char *canfdi_sim_scn_run_error(const canfdi_sim_scn_t *scn)
{
  return (scn->has_profile && (scn->profile.err[0] != '\0')) ? scn->profile.err : NULL;
}
