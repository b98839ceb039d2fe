/*
 * bench_symptoms.c — the measured fault-symptom table: a
 * reproduction of the kind of table Isermann publishes (Fault-Diagnosis
 * Systems, 2006: residual and parameter deviations per fault, in units of
 * their fault-free noise, with the sign).
 *
 * Method.
 *  - Rig (bench_model_common.h): both host_sim plants in closed loop with
 *    the stand-in reference controller, sensor noise and 12-bit ADCs, the
 *    four fixed-point model modules fed with the measured values (Q16.16).
 *  - Excitation, as in the estimator tests: DC motor at 100 rad/s plus a
 *    PRBS of +-30 rad/s with 20 ms bits at the nominal load of 1.2 N m
 *    (~4 A, R_A held at Isermann's warm 1.52 Ohm); throttle at 45 deg plus
 *    a 0.5 Hz sine of +-30 deg and a PRBS of +-2 deg with 50 ms bits. The
 *    PRBS sequence changes with the seed index.
 *  - Timeline: settle 0..25 s (estimators converge, parity learns R_A);
 *    fault abrupt at 25 s; window "before" 15..25 s; onset skipped for 7 s
 *    (the throttle's mechanical estimator has a memory of ~5-8 s); window
 *    "after" 32..42 s.
 *  - For each channel (residual, estimated parameter, signal-based extra):
 *    deviation = (mean after - mean before) / sigma, where sigma is the
 *    fault-free noise of that channel, from fault-free runs with their own
 *    noise seeds, over windows of the same length and spacing: the larger
 *    of the pooled within-window standard deviation and the rms difference
 *    of consecutive window means (see score_fault_free: a slowly wandering
 *    parameter estimate needs the second). Samples count only while the
 *    channel is valid (residual validity bits, estimator converged). Fault
 *    runs use other noise seeds; the table shows the mean deviation over
 *    them.
 *  - Symptom "+"/"-" when |mean deviation| >= 3 sigma, "0" otherwise; "x"
 *    when the channel is not valid after the fault (e.g. a residual whose
 *    sensor went out of range). Range checks (raw value outside its
 *    plausible window) are reported as the change of the fraction of
 *    samples outside, "+" above / "-" below when it grows by >= 0.1.
 *  - The fault-free runs are also scored against each other (after vs
 *    before with no fault): their largest |deviation| per channel is
 *    printed as the false-symptom margin of the method.
 * Parametric faults run at their catalogue magnitude and at 10 % and 20 %
 * (the catalogue allows only the fault's own direction: a "rel" magnitude
 * is >= 0). Everything else runs at its catalogue magnitude.
 *
 * A benchmark: it reports figures and the acceptance verdict; it exits
 * non-zero only when it cannot run (bad option, rig or file error).
 *
 * Usage: bench_symptoms [-n fault_seeds] [-f fault_free_seeds] [-o out.json]
 */
#define _POSIX_C_SOURCE 199309L

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "bench_model_common.h"
#include "canfdi_sim_profile.h"
#include "gen/canfdi_faults.h"

/* Windows j = 0, 1, ...: (W0_S + j W_PITCH_S, W0_S + j W_PITCH_S + W_LEN_S];
 * a fault run uses j = 0 (before) and j = 1 (after), a fault-free run
 * N_WIN_FF of them (consecutive pairs give the null distribution). */
#define T_FAULT_S 25.0
#define W0_S 15.0
#define W_PITCH_S 17.0
#define W_LEN_S 10.0
#define N_WIN_FF 5
#define N_WIN_MAX N_WIN_FF
#define PRE_T0_S W0_S
#define POST_T0_S (W0_S + W_PITCH_S)
#define T_END_S (POST_T0_S + W_LEN_S)
#define WIN_STEPS 10000L
#define MIN_VALID_FRAC 0.2   /* of a window, for a channel to be evaluated */
#define SYMPTOM_SIGMA 3.0
#define RANGE_FRAC 0.1
#define MAX_SEEDS 8
#define MAX_CASES 64
#define SPEED_NOM 100.0
#define LOAD_NOM 1.2
#define ANGLE_NOM 45.0

/* ---- accumulation ---------------------------------------------------------- */

typedef struct {
  double s[N_WIN_MAX];
  double s2[N_WIN_MAX];
  long n[N_WIN_MAX];
  long out[N_WIN_MAX]; /* residuals: steps beyond the threshold */
} acc_t;

typedef struct {
  long hi[N_WIN_MAX];
  long lo[N_WIN_MAX];
  long n[N_WIN_MAX];
} racc_t;

typedef struct {
  acc_t ch[BM_N_CH];
  racc_t rg[BM_N_RNG];
} run_acc_t;

static double acc_mean(const acc_t *a, int w)
{
  return (a->n[w] > 0) ? a->s[w] / (double)a->n[w] : 0.0;
}

static double acc_var(const acc_t *a, int w)
{
  const double m = acc_mean(a, w);
  return (a->n[w] > 1) ? fmax(0.0, (a->s2[w] / (double)a->n[w]) - (m * m)) : 0.0;
}

static bool acc_ok(const acc_t *a, int w)
{
  return (double)a->n[w] >= MIN_VALID_FRAC * (double)WIN_STEPS;
}

/* signed fraction of samples out of range: above minus below */
static double racc_frac(const racc_t *a, int w)
{
  return (a->n[w] > 0) ? (double)(a->hi[w] - a->lo[w]) / (double)a->n[w] : 0.0;
}

/* ---- one run ----------------------------------------------------------------- */

static bm_rig_t rig;

/* fault_id < 0: fault-free. Returns 0 or a negative code. */
static int run_one(int fault_id, double mag, uint64_t noise_seed, unsigned prbs_idx, int n_win, run_acc_t *acc)
{
  bm_rig_opts_t o;
  canfdi_sim_profile_t sp;
  canfdi_sim_profile_t ap;
  const long n_end = lround((W0_S + ((double)(n_win - 1) * W_PITCH_S) + W_LEN_S) * 1000.0);
  long k;
  int rc;
  memset(acc, 0, sizeof(*acc));
  bm_rig_default_opts(&o);
  o.seed = noise_seed;
  rc = bm_rig_init(&rig, &o);
  if (rc == 0) {
    rc = bm_rig_start_dcm(&rig, SPEED_NOM, LOAD_NOM);
  }
  if ((rc == 0) && (fault_id >= 0)) {
    rc = bm_rig_add_fault(&rig, (uint8_t)fault_id, T_FAULT_S, mag);
  }
  canfdi_sim_profile_init(&sp, -400.0, 400.0);
  canfdi_sim_profile_init(&ap, 0.0, 90.0);
  if (rc == 0) {
    rc = canfdi_sim_profile_add(&sp, CANFDI_SIM_PROF_CONST, 0, 0, SPEED_NOM, 0, 0);
  }
  if (rc == 0) {
    rc = canfdi_sim_profile_add(&sp, CANFDI_SIM_PROF_PRBS, 1.0, 1e4, 30.0, 0.02, 11U + prbs_idx);
  }
  if (rc == 0) {
    rc = canfdi_sim_profile_add(&ap, CANFDI_SIM_PROF_CONST, 0, 0, ANGLE_NOM, 0, 0);
  }
  if (rc == 0) {
    rc = canfdi_sim_profile_add(&ap, CANFDI_SIM_PROF_SINE, 0.5, 1e4, 30.0, 0.5, 0);
  }
  if (rc == 0) {
    rc = canfdi_sim_profile_add(&ap, CANFDI_SIM_PROF_PRBS, 0.5, 1e4, 2.0, 0.05, 29U + prbs_idx);
  }
  for (k = 0L; (rc == 0) && (k < n_end); k++) {
    const int64_t t_us = k * 1000L;
    /* window of the sample taken at the end of this step, time (k + 1) ms:
     * [start, start + length), so the sample at the fault time (which
     * already carries a sensor fault) is not in the window before */
    const long tw = (k + 1L) - lround(W0_S * 1000.0);
    const long pitch = lround(W_PITCH_S * 1000.0);
    const int w = (tw >= 0L) ? (int)(tw / pitch) : -1;
    unsigned c;
    bm_rig_step(&rig, canfdi_sim_profile_eval(&sp, t_us), canfdi_sim_profile_eval(&ap, t_us), LOAD_NOM);
    if ((w < 0) || (w >= n_win) || ((tw - ((long)w * pitch)) >= lround(W_LEN_S * 1000.0))) {
      continue; /* settling, onset or between windows */
    }
    for (c = 0U; c < BM_N_CH; c++) {
      if ((rig.valid & (1U << c)) != 0U) {
        acc_t *a = &acc->ch[c];
        a->s[w] += rig.val[c];
        a->s2[w] += rig.val[c] * rig.val[c];
        a->n[w]++;
        if ((rig.exceed & (1U << c)) != 0U) {
          a->out[w]++;
        }
      }
    }
    for (c = 0U; c < BM_N_RNG; c++) {
      racc_t *a = &acc->rg[c];
      a->n[w]++;
      if (rig.rng[c] > 0) {
        a->hi[w]++;
      } else if (rig.rng[c] < 0) {
        a->lo[w]++;
      } else {
        /* inside */
      }
    }
  }
  return rc;
}

/* ---- the catalogue --------------------------------------------------------- */

typedef struct {
  uint8_t id;
  double mag;
  bool is_default;
  /* results */
  double dev[BM_N_CH][MAX_SEEDS];
  bool ok[BM_N_CH][MAX_SEEDS];   /* evaluated (valid in both windows) */
  double pre_mean[BM_N_CH];      /* mean over seeds */
  double post_mean[BM_N_CH];
  double out_frac[BM_N_CH];      /* residuals: post-window fraction beyond threshold */
  double rdev[BM_N_RNG][MAX_SEEDS];
  double mean_dev[BM_N_CH];
  int n_ok[BM_N_CH];
  char sym[BM_N_CH];             /* '+', '-', '0', 'x' */
  bool all_seeds[BM_N_CH];       /* every seed beyond 3 sigma with the symptom's sign */
  double mean_rdev[BM_N_RNG];
  char rsym[BM_N_RNG];
  bool observable;               /* a model-based symptom >= 3 sigma */
} case_t;

static case_t cases[MAX_CASES];
static size_t n_cases;

static bool is_parametric(uint8_t id)
{
  return strcmp(canfdi_fault_table[id].kind, "parametric") == 0;
}

static unsigned fault_plant(uint8_t id)
{
  const canfdi_fault_info_t *f = &canfdi_fault_table[id];
  unsigned p = BM_PLANT_DCM;
  if ((strcmp(f->component, "throttle") == 0) || (strncmp(f->name, "com_thr", 7) == 0)) {
    p = BM_PLANT_THR;
  }
  return p;
}

/*
 * Which faults the model-based methods (parity equations, parameter
 * estimation) are expected to see (docs/design.md, "Which methods see which
 * faults"), and why the others are not theirs. NULL: expected to be
 * observable.
 */
static const char *not_observable_why(uint8_t id)
{
  const char *why = NULL;
  switch (id) {
  case CANFDI_FAULT_DCM_BRIDGE_A_DEAD:
  case CANFDI_FAULT_DCM_BRIDGES_DEAD:
    why = "a dead bridge delivers 0 V and the U_A sensor measures those 0 V: the armature and "
          "mechanical equations hold with the measured signals (the motor brakes on its back-EMF "
          "towards standstill), so the parity residuals stay consistent; what the estimators do "
          "during that deceleration is not a diagnosis of the bridge. It shows as measured U_A ~ 0 "
          "against the command (the actuator manager's plausibility check, column "
          "command_vs_measured_ua) and as a speed tracking error";
    break;
  case CANFDI_FAULT_THR_TPS1_OPEN:
  case CANFDI_FAULT_THR_TPS1_SHORT:
  case CANFDI_FAULT_THR_TPS2_OPEN:
  case CANFDI_FAULT_THR_TPS2_SHORT:
    why = "the potentiometer reads a rail (0 V open, 5 V short) outside its plausible window: the "
          "range check names it (range_tps1/range_tps2); the parity module drops that sensor "
          "(CORR and its POS residual become invalid, 'x') and controller and estimator run on "
          "the other potentiometer, so the model-based channels that stay valid do not deviate";
    break;
  case CANFDI_FAULT_THR_JAMMED:
    why = "with the valve stuck the motor sees a locked rotor: u = R i + L di/dt holds with "
          "dtheta/dt = 0, so ARM stays consistent, and the estimators lose their excitation (no "
          "motion) and hold their values; the symptom that names it is the position not following "
          "the setpoint (thr_tracking_error). The position residuals may move in common mode (the "
          "observer, driven by the motor current, predicts motion the stuck valve does not make): "
          "see the note";
    break;
  case CANFDI_FAULT_THR_TPS_BOTH_LOST:
    why = "both potentiometers read 0 V, out of range: the range checks name it; no position "
          "signal is left for a model-based residual (CORR, POS1, POS2 invalid), the controller "
          "disables the bridge and the spring returns the valve to limp-home";
    break;
  default:
    if (strcmp(canfdi_fault_table[id].kind, "communication") == 0) {
      why = "a communication fault corrupts only the CAN frame (timeout, rolling counter, CRC, "
            "DLC or an out-of-range raw value); the plant and the sensor values are untouched. It "
            "is judged by input supervision (E2E counter/CRC, timeout, DLC and DBC range checks) "
            "before any value reaches a model; this bench feeds the models the sensor values "
            "directly, so no residual or parameter can move";
    }
    break;
  }
  return why;
}

/*
 * The parity residuals' fault-symptom structure as the module headers
 * predict it (canfdi_parity_dcm.h, canfdi_parity_thr.h: "Fault-symptom
 * structure (theory)"), in the fault's named direction, for the residuals
 * r1 r2 r3 r4 / CORR ARM POS1 POS2 of the fault's plant: '+', '-', '0'
 * (decoupled), '.' (weakly coupled or sign not stated: not compared).
 * NULL: no prediction in the headers.
 */
static const char *predicted_structure(uint8_t id)
{
  const char *p = NULL;
  switch (id) {
  case CANFDI_FAULT_DCM_RA_UP: p = "+0.+"; break;
  case CANFDI_FAULT_DCM_FLUX_DOWN: p = "-++-"; break;
  case CANFDI_FAULT_DCM_FRICTION_UP: p = "0+++"; break;
  case CANFDI_FAULT_DCM_IA_SENSOR_OFFSET: p = "-++0"; break;
  case CANFDI_FAULT_DCM_SPEED_SENSOR_GAIN: p = "-.0-"; break;
  case CANFDI_FAULT_DCM_SPEED_SENSOR_OFFSET: p = "-.0-"; break;
  case CANFDI_FAULT_DCM_UA_SENSOR_OFFSET: p = "+0.+"; break;
  case CANFDI_FAULT_THR_TPS1_DRIFT: p = "+0+0"; break;
  case CANFDI_FAULT_THR_TPS2_DRIFT: p = "+00-"; break;
  case CANFDI_FAULT_THR_SPRING_WEAK: p = "00.."; break;
  case CANFDI_FAULT_THR_FRICTION_UP: p = "00.."; break;
  case CANFDI_FAULT_THR_MOTOR_R_UP: p = "0+.."; break;
  case CANFDI_FAULT_THR_MOTOR_OPEN: p = "0+.."; break;
  case CANFDI_FAULT_THR_JAMMED: p = "00.."; break;
  default: break;
  }
  return p;
}

/* The measured parity symbols of the fault's plant into m[5]. Returns 0
 * if they agree with the prediction, 1 if they agree but for predicted
 * symptoms that stay below 3 sigma (weaker), 2 if they differ (opposite
 * sign, a symptom in a decoupled residual, or not valid). */
static int structure_cmp(uint8_t id, const char *sym, char m[5])
{
  const char *p = predicted_structure(id);
  const unsigned first = (fault_plant(id) == BM_PLANT_DCM) ? BM_CH_R1 : BM_CH_CORR;
  int out = 0;
  unsigned j;
  for (j = 0U; j < 4U; j++) {
    m[j] = sym[first + j];
    if ((p != NULL) && (p[j] != '.') && (p[j] != m[j])) {
      if ((m[j] == '0') && (p[j] != '0')) {
        out = (out > 1) ? out : 1;
      } else {
        out = 2;
      }
    }
  }
  m[4] = '\0';
  return out;
}

static void build_cases(void)
{
  uint8_t id;
  static const double extra[] = {0.1, 0.2};
  n_cases = 0U;
  for (id = 1U; id < canfdi_fault_table_len; id++) {
    const double dm = canfdi_fault_table[id].default_magnitude;
    cases[n_cases].id = id;
    cases[n_cases].mag = dm;
    cases[n_cases].is_default = true;
    n_cases++;
    if (is_parametric(id)) {
      size_t e;
      for (e = 0U; e < sizeof extra / sizeof extra[0]; e++) {
        if ((fabs(extra[e] - dm) > 1e-9) && (n_cases < MAX_CASES)) {
          cases[n_cases].id = id;
          cases[n_cases].mag = extra[e];
          cases[n_cases].is_default = false;
          n_cases++;
        }
      }
    }
  }
}

/* ---- fault-free noise ------------------------------------------------------ */

/*
 * sigma of a channel: the larger of
 *  - sigma_within: the within-window standard deviation, pooled over every
 *    window of the fault-free runs (the "noise" of the channel), and
 *  - sigma_diff: the root mean square of the difference of the means of
 *    two consecutive windows (same spacing as before/after) in the
 *    fault-free runs — the null distribution of the deviation itself.
 * For a residual sigma_within dominates by far (10 000 samples average
 * the noise); a parameter estimate wanders slowly (the RLS memory is
 * 0.4..8 s), so the window means of a fault-free run differ by about its
 * within-window deviation and sigma_within alone would call that wander
 * a symptom. Both figures are in the JSON.
 */
static double sigma[BM_N_CH];
static double sigma_within[BM_N_CH];
static double sigma_diff[BM_N_CH];
static double ff_valid_frac[BM_N_CH];
static double ff_max_dev[BM_N_CH];  /* false-symptom margin */
static double ff_max_rdev[BM_N_RNG];
static double ff_out_frac[BM_N_CH];
static double ff_rng_frac[BM_N_RNG]; /* fraction of samples out of range */
static bool ff_sigma_ok[BM_N_CH];
static int n_ff_pairs;

static run_acc_t ff_acc[MAX_SEEDS];
static run_acc_t f_acc;

static void score_fault_free(int n_ff)
{
  unsigned c;
  int s;
  int w;
  n_ff_pairs = 0;
  for (c = 0U; c < BM_N_CH; c++) {
    double vs = 0.0;
    double ds = 0.0;
    long n = 0L;
    long out = 0L;
    long nw = 0L;
    int np = 0;
    for (s = 0; s < n_ff; s++) {
      const acc_t *a = &ff_acc[s].ch[c];
      for (w = 0; w < N_WIN_FF; w++) {
        vs += acc_var(a, w) * (double)a->n[w];
        n += a->n[w];
        out += a->out[w];
        nw += WIN_STEPS;
        if ((w > 0) && acc_ok(a, w - 1) && acc_ok(a, w)) {
          const double d = acc_mean(a, w) - acc_mean(a, w - 1);
          ds += d * d;
          np++;
        }
      }
    }
    sigma_within[c] = (n > 1) ? sqrt(vs / (double)n) : 0.0;
    sigma_diff[c] = (np > 0) ? sqrt(ds / (double)np) : 0.0;
    sigma[c] = fmax(sigma_within[c], sigma_diff[c]);
    ff_sigma_ok[c] = (n > 1) && (sigma[c] > 0.0);
    ff_valid_frac[c] = (double)n / (double)nw;
    ff_out_frac[c] = (n > 0) ? (double)out / (double)n : 0.0;
    ff_max_dev[c] = 0.0;
    for (s = 0; s < n_ff; s++) {
      const acc_t *a = &ff_acc[s].ch[c];
      for (w = 1; w < N_WIN_FF; w++) {
        if (ff_sigma_ok[c] && acc_ok(a, w - 1) && acc_ok(a, w)) {
          ff_max_dev[c] = fmax(ff_max_dev[c], fabs(acc_mean(a, w) - acc_mean(a, w - 1)) / sigma[c]);
        }
      }
    }
    if (np > n_ff_pairs) {
      n_ff_pairs = np;
    }
  }
  for (c = 0U; c < BM_N_RNG; c++) {
    long out = 0L;
    long n = 0L;
    ff_max_rdev[c] = 0.0;
    for (s = 0; s < n_ff; s++) {
      const racc_t *a = &ff_acc[s].rg[c];
      for (w = 0; w < N_WIN_FF; w++) {
        out += a->hi[w] + a->lo[w];
        n += a->n[w];
        if (w > 0) {
          ff_max_rdev[c] = fmax(ff_max_rdev[c], fabs(racc_frac(a, w) - racc_frac(a, w - 1)));
        }
      }
    }
    ff_rng_frac[c] = (n > 0) ? (double)out / (double)n : 0.0;
  }
}

static void score_case_seed(case_t *cs, int s, const run_acc_t *a)
{
  unsigned c;
  for (c = 0U; c < BM_N_CH; c++) {
    const acc_t *x = &a->ch[c];
    cs->ok[c][s] = ff_sigma_ok[c] && acc_ok(x, 0) && acc_ok(x, 1);
    cs->dev[c][s] = cs->ok[c][s] ? (acc_mean(x, 1) - acc_mean(x, 0)) / sigma[c] : 0.0;
    cs->pre_mean[c] += acc_mean(x, 0);
    cs->post_mean[c] += acc_mean(x, 1);
    cs->out_frac[c] += (x->n[1] > 0) ? (double)x->out[1] / (double)x->n[1] : 0.0;
  }
  for (c = 0U; c < BM_N_RNG; c++) {
    cs->rdev[c][s] = racc_frac(&a->rg[c], 1) - racc_frac(&a->rg[c], 0);
  }
}

static void finish_case(case_t *cs, int n_seeds)
{
  unsigned c;
  int s;
  cs->observable = false;
  for (c = 0U; c < BM_N_CH; c++) {
    double sum = 0.0;
    int n = 0;
    cs->pre_mean[c] /= (double)n_seeds;
    cs->post_mean[c] /= (double)n_seeds;
    cs->out_frac[c] /= (double)n_seeds;
    for (s = 0; s < n_seeds; s++) {
      if (cs->ok[c][s]) {
        sum += cs->dev[c][s];
        n++;
      }
    }
    cs->n_ok[c] = n;
    cs->mean_dev[c] = (n > 0) ? sum / (double)n : 0.0;
    if (n < n_seeds) {
      cs->sym[c] = 'x';
    } else if (cs->mean_dev[c] >= SYMPTOM_SIGMA) {
      cs->sym[c] = '+';
    } else if (cs->mean_dev[c] <= -SYMPTOM_SIGMA) {
      cs->sym[c] = '-';
    } else {
      cs->sym[c] = '0';
    }
    cs->all_seeds[c] = (cs->sym[c] == '+') || (cs->sym[c] == '-');
    for (s = 0; (s < n_seeds) && cs->all_seeds[c]; s++) {
      const double d = (cs->sym[c] == '+') ? cs->dev[c][s] : -cs->dev[c][s];
      cs->all_seeds[c] = d >= SYMPTOM_SIGMA;
    }
    if (((cs->sym[c] == '+') || (cs->sym[c] == '-')) &&
        ((bm_chan[c].kind == BM_KIND_RESIDUAL) || (bm_chan[c].kind == BM_KIND_PARAMETER))) {
      cs->observable = true;
    }
  }
  for (c = 0U; c < BM_N_RNG; c++) {
    double sum = 0.0;
    for (s = 0; s < n_seeds; s++) {
      sum += cs->rdev[c][s];
    }
    cs->mean_rdev[c] = sum / (double)n_seeds;
    cs->rsym[c] = (cs->mean_rdev[c] >= RANGE_FRAC) ? '+' : ((cs->mean_rdev[c] <= -RANGE_FRAC) ? '-' : '0');
  }
}

/* ---- output ------------------------------------------------------------------ */

static const unsigned dcm_cols[] = {BM_CH_R1,  BM_CH_R2,   BM_CH_R3,  BM_CH_R4,     BM_CH_D_RA,
                                    BM_CH_D_LA, BM_CH_D_PSI, BM_CH_D_J, BM_CH_D_MF1, BM_CH_D_MC,
                                    BM_CH_UA_CMD, BM_CH_D_TRK};
static const unsigned dcm_rcols[] = {BM_RNG_IA, BM_RNG_W};
static const unsigned thr_cols[] = {BM_CH_CORR, BM_CH_ARM, BM_CH_POS1, BM_CH_POS2, BM_CH_T_R,
                                    BM_CH_T_L,  BM_CH_T_K, BM_CH_T_U0, BM_CH_T_J,  BM_CH_T_B,
                                    BM_CH_T_KS, BM_CH_T_P, BM_CH_T_TC, BM_CH_T_TRK};
static const unsigned thr_rcols[] = {BM_RNG_TPS1, BM_RNG_TPS2, BM_RNG_THR_I};

#define NELEM(a) (sizeof(a) / sizeof((a)[0]))

static void case_label(const case_t *cs, char *buf, size_t len)
{
  (void)snprintf(buf, len, "%s %g%s", canfdi_fault_table[cs->id].name, cs->mag, cs->is_default ? "" : " *");
}

static void print_cell(const case_t *cs, unsigned c)
{
  if (cs->sym[c] == 'x') {
    printf(" %5s", "x");
  } else if (cs->sym[c] == '0') {
    printf(" %5s", "0");
  } else if (fabs(cs->mean_dev[c]) >= 99999.5) {
    printf(" %5s", (cs->mean_dev[c] > 0.0) ? "+++++" : "-----");
  } else {
    printf(" %+5.0f", cs->mean_dev[c]);
  }
}

static void print_group(unsigned plant, const unsigned *cols, size_t nc, const unsigned *rcols, size_t nr)
{
  size_t i;
  size_t j;
  char lbl[64];
  printf("%-32s", (plant == BM_PLANT_DCM) ? "DC motor fault / magnitude" : "throttle fault / magnitude");
  for (j = 0U; j < nc; j++) {
    printf(" %5s", bm_chan[cols[j]].label);
  }
  printf(" |");
  for (j = 0U; j < nr; j++) {
    printf(" %4s", bm_rng[rcols[j]].label);
  }
  printf("\n");
  for (i = 0U; i < n_cases; i++) {
    const case_t *cs = &cases[i];
    if (fault_plant(cs->id) != plant) {
      continue;
    }
    case_label(cs, lbl, sizeof lbl);
    printf("%-32s", lbl);
    for (j = 0U; j < nc; j++) {
      print_cell(cs, cols[j]);
    }
    printf(" |");
    for (j = 0U; j < nr; j++) {
      printf(" %4c", cs->rsym[rcols[j]]);
    }
    printf("\n");
  }
  printf("%-32s", "fault-free max |dev|/sigma");
  for (j = 0U; j < nc; j++) {
    printf(" %5.1f", ff_max_dev[cols[j]]);
  }
  printf("\nsigma:");
  for (j = 0U; j < nc; j++) {
    const unsigned c = cols[j];
    printf(" %s %.3g %s%s", bm_chan[c].label, sigma[c], bm_chan[c].unit, (sigma_diff[c] > sigma_within[c]) ? " (w)" : "");
    printf("%s", (j + 1U < nc) ? "," : "");
  }
  printf("\nfault-free valid steps beyond the residual's threshold:");
  for (j = 0U; j < nc; j++) {
    if (bm_chan[cols[j]].kind == BM_KIND_RESIDUAL) {
      printf(" %s %.4f %%", bm_chan[cols[j]].label, 100.0 * ff_out_frac[cols[j]]);
    }
  }
  printf("\nrange checks, fault-free fraction of samples out of range:");
  for (j = 0U; j < nr; j++) {
    printf(" %s %.4f", bm_rng[rcols[j]].label, ff_rng_frac[rcols[j]]);
  }
  printf("\n\n");
}

/* One word for the stdout table: who sees a fault the models do not. */
static const char *seen_by(uint8_t id)
{
  const char *w = "";
  if (strcmp(canfdi_fault_table[id].kind, "communication") == 0) {
    w = "input supervision (E2E/timeout/DLC/range)";
  } else if ((id == CANFDI_FAULT_DCM_BRIDGE_A_DEAD) || (id == CANFDI_FAULT_DCM_BRIDGES_DEAD)) {
    w = "U_A vs command plausibility, tracking error";
  } else if (id == CANFDI_FAULT_THR_JAMMED) {
    w = "position tracking error";
  } else {
    w = "range checks";
  }
  return w;
}

static void json_num(FILE *f, double v)
{
  if (isfinite(v)) {
    fprintf(f, "%.6g", v);
  } else {
    fprintf(f, "null");
  }
}

static int write_json(const char *path, int n_seeds, int n_ff, double wall, const char *const *met, size_t n_met,
                      const char *const *missed, size_t n_missed)
{
  FILE *f = fopen(path, "w");
  size_t i;
  unsigned c;
  int s;
  if (f == NULL) {
    perror(path);
    return -1;
  }
  fprintf(f, "{\n  \"benchmark\": \"symptoms\",\n  \"build\": \"-O2, no sanitizers\",\n");
  fprintf(f, "  \"method\": {\n    \"rig\": \"host_sim plants + stand-in reference controller; sensor noise sigma "
             "U_A 0.05 V, I_A 0.02 A, w 0.2 rad/s, TPS 3 mV, throttle i 0.01 A, on 12-bit ADCs; measured values "
             "converted to Q16.16 and fed to canfdi_parity_dcm, canfdi_est_dcm, canfdi_parity_thr, canfdi_est_thr "
             "(default configurations)\",\n");
  fprintf(f, "    \"excitation\": \"DC motor 100 rad/s + PRBS +-30 rad/s (20 ms bits), load 1.2 N m, R_A 1.52 Ohm "
             "held; throttle 45 deg + sine +-30 deg 0.5 Hz + PRBS +-2 deg (50 ms bits)\",\n");
  fprintf(f, "    \"fault_time_s\": %.1f,\n    \"window_before_s\": [%.1f, %.1f],\n    \"window_after_s\": [%.1f, "
             "%.1f],\n",
          T_FAULT_S, PRE_T0_S, T_FAULT_S, POST_T0_S, T_END_S);
  fprintf(f, "    \"deviation\": \"(mean after - mean before) / sigma; sigma = max(sigma_within, sigma_diff) from the "
             "fault-free runs: sigma_within the within-window standard deviation pooled over all their windows, "
             "sigma_diff the rms difference of the means of consecutive windows (same spacing as before/after, "
             "%d pairs); the table value is the mean over the fault seeds\",\n", n_ff_pairs);
  fprintf(f, "    \"symptom_threshold_sigma\": %.1f,\n    \"range_symptom_fraction\": %.2f,\n", SYMPTOM_SIGMA,
          RANGE_FRAC);
  fprintf(f, "    \"min_valid_fraction\": %.2f,\n    \"fault_seeds\": %d,\n    \"fault_free_seeds\": %d,\n",
          MIN_VALID_FRAC, n_seeds, n_ff);
  fprintf(f, "    \"magnitudes\": \"catalogue default; parametric faults also 0.1 and 0.2 (rel, in the fault's "
             "direction)\"\n  },\n");
  fprintf(f, "  \"channels\": {\n");
  for (c = 0U; c < BM_N_CH; c++) {
    static const char *const kinds[] = {"residual", "parameter", "signal", "range"};
    fprintf(f, "    ");
    bm_json_str(f, bm_chan[c].name);
    fprintf(f, ": {\"kind\": \"%s\", \"plant\": \"%s\", \"unit\": ", kinds[bm_chan[c].kind],
            (bm_chan[c].plant == BM_PLANT_DCM) ? "dc_motor" : "throttle");
    bm_json_str(f, bm_chan[c].unit);
    fprintf(f, ", \"sigma\": ");
    json_num(f, sigma[c]);
    fprintf(f, ", \"sigma_within\": ");
    json_num(f, sigma_within[c]);
    fprintf(f, ", \"sigma_diff\": ");
    json_num(f, sigma_diff[c]);
    fprintf(f, ", \"fault_free_valid_fraction\": %.4f, \"fault_free_max_abs_dev_sigma\": %.3f", ff_valid_frac[c],
            ff_max_dev[c]);
    if (bm_chan[c].kind == BM_KIND_RESIDUAL) {
      fprintf(f, ", \"fault_free_out_of_band_fraction\": %.6f", ff_out_frac[c]);
    }
    if (bm_chan[c].kind == BM_KIND_PARAMETER) {
      fprintf(f, ", \"true_value\": %.6g", bm_chan[c].nominal);
    }
    fprintf(f, "},\n");
  }
  for (c = 0U; c < BM_N_RNG; c++) {
    fprintf(f, "    ");
    bm_json_str(f, bm_rng[c].name);
    fprintf(f,
            ": {\"kind\": \"range\", \"plant\": \"%s\", \"fault_free_out_of_range_fraction\": %.6f, "
            "\"fault_free_max_abs_change\": %.4f}%s\n",
            (bm_rng[c].plant == BM_PLANT_DCM) ? "dc_motor" : "throttle", ff_rng_frac[c], ff_max_rdev[c],
            (c + 1U < BM_N_RNG) ? "," : "");
  }
  fprintf(f, "  },\n  \"faults\": [\n");
  for (i = 0U; i < n_cases; i++) {
    const case_t *cs = &cases[i];
    const canfdi_fault_info_t *fi = &canfdi_fault_table[cs->id];
    const char *why = not_observable_why(cs->id);
    bool first = true;
    fprintf(f, "    {\"id\": %u, \"name\": ", cs->id);
    bm_json_str(f, fi->name);
    fprintf(f, ", \"component\": ");
    bm_json_str(f, fi->component);
    fprintf(f, ", \"kind\": ");
    bm_json_str(f, fi->kind);
    fprintf(f, ", \"magnitude\": %g, \"unit\": ", cs->mag);
    bm_json_str(f, fi->unit);
    fprintf(f, ", \"default_magnitude\": %s, \"dtc\": ", cs->is_default ? "true" : "false");
    bm_json_str(f, fi->dtc);
    fprintf(f, ",\n     \"expected_observable\": %s, \"observable\": %s", (why == NULL) ? "true" : "false",
            cs->observable ? "true" : "false");
    if (why != NULL) {
      fprintf(f, ", \"why\": ");
      bm_json_str(f, why);
      fprintf(f, ", \"judged_by\": ");
      bm_json_str(f, seen_by(cs->id));
      if (cs->observable) {
        bool first_n = true;
        fprintf(f, ", \"note\": \"not expected (docs/design.md), but these model-based channels moved by >= 3 "
                   "sigma in this rig:");
        for (c = 0U; c < BM_N_CH; c++) {
          if (((cs->sym[c] == '+') || (cs->sym[c] == '-')) &&
              ((bm_chan[c].kind == BM_KIND_RESIDUAL) || (bm_chan[c].kind == BM_KIND_PARAMETER))) {
            fprintf(f, "%s %s%c", first_n ? "" : ",", bm_chan[c].name, cs->sym[c]);
            first_n = false;
          }
        }
        fprintf(f, "\"");
      }
    } else if (!cs->observable) {
      fprintf(f, ", \"why\": ");
      bm_json_str(f, "expected to be observable by the model-based methods, but no residual or parameter reached "
                     "3 sigma in this rig");
    }
    if (why == NULL) {
      fprintf(f, ", \"acceptance\": \"%s\"", cs->observable ? "met" : "missed");
    } else {
      fprintf(f, ", \"acceptance\": \"not_applicable\"");
    }
    if (predicted_structure(cs->id) != NULL) {
      static const char *const verdict[] = {"agrees", "weaker", "differs"};
      char m[5];
      const int v = structure_cmp(cs->id, cs->sym, m);
      fprintf(f, ",\n     \"parity_structure\": {\"residuals\": \"%s\", \"predicted\": \"%s\", \"measured\": \"%s\", "
                 "\"verdict\": \"%s\"}",
              (fault_plant(cs->id) == BM_PLANT_DCM) ? "r1 r2 r3 r4" : "corr arm pos1 pos2", predicted_structure(cs->id),
              m, verdict[v]);
    }
    fprintf(f, ",\n     \"symptoms\": [");
    for (c = 0U; c < BM_N_CH; c++) {
      if ((cs->sym[c] == '+') || (cs->sym[c] == '-')) {
        fprintf(f, "%s\"%s%c\"", first ? "" : ", ", bm_chan[c].name, cs->sym[c]);
        first = false;
      }
    }
    for (c = 0U; c < BM_N_RNG; c++) {
      if (cs->rsym[c] != '0') {
        fprintf(f, "%s\"%s%c\"", first ? "" : ", ", bm_rng[c].name, cs->rsym[c]);
        first = false;
      }
    }
    fprintf(f, "],\n     \"not_valid_after_fault\": [");
    first = true;
    for (c = 0U; c < BM_N_CH; c++) {
      if (cs->sym[c] == 'x') {
        fprintf(f, "%s\"%s\"", first ? "" : ", ", bm_chan[c].name);
        first = false;
      }
    }
    fprintf(f, "],\n     \"columns\": {\n");
    for (c = 0U; c < BM_N_CH; c++) {
      fprintf(f, "       ");
      bm_json_str(f, bm_chan[c].name);
      fprintf(f, ": {\"symptom\": \"%c\", \"dev_sigma\": ", cs->sym[c]);
      if (cs->n_ok[c] > 0) {
        json_num(f, cs->mean_dev[c]);
      } else {
        fprintf(f, "null");
      }
      fprintf(f, ", \"per_seed\": [");
      for (s = 0; s < n_seeds; s++) {
        if (s > 0) {
          fprintf(f, ", ");
        }
        if (cs->ok[c][s]) {
          json_num(f, cs->dev[c][s]);
        } else {
          fprintf(f, "null");
        }
      }
      fprintf(f, "], \"all_seeds_beyond\": %s, \"mean_before\": ", cs->all_seeds[c] ? "true" : "false");
      json_num(f, cs->pre_mean[c]);
      fprintf(f, ", \"mean_after\": ");
      json_num(f, cs->post_mean[c]);
      if (bm_chan[c].kind == BM_KIND_RESIDUAL) {
        fprintf(f, ", \"out_of_band_fraction_after\": %.4f", cs->out_frac[c]);
      }
      fprintf(f, "},\n");
    }
    for (c = 0U; c < BM_N_RNG; c++) {
      fprintf(f, "       ");
      bm_json_str(f, bm_rng[c].name);
      fprintf(f, ": {\"symptom\": \"%c\", \"change_of_out_of_range_fraction\": %.4f}%s\n", cs->rsym[c],
              cs->mean_rdev[c], (c + 1U < BM_N_RNG) ? "," : "");
    }
    fprintf(f, "     }}%s\n", (i + 1U < n_cases) ? "," : "");
  }
  fprintf(f, "  ],\n  \"acceptance\": {\n    \"criterion\": \"every catalogue fault that docs/design.md expects "
             "model-based methods to see shows a deviation of at least 3 sigma in at least one residual or "
             "parameter (at its catalogue magnitude); faults that are not observable say so and why\",\n");
  fprintf(f, "    \"met\": [");
  for (i = 0U; i < n_met; i++) {
    fprintf(f, "%s", (i > 0U) ? ", " : "");
    bm_json_str(f, met[i]);
  }
  fprintf(f, "],\n    \"missed\": [");
  for (i = 0U; i < n_missed; i++) {
    fprintf(f, "%s", (i > 0U) ? ", " : "");
    bm_json_str(f, missed[i]);
  }
  fprintf(f, "],\n    \"passed\": %s\n  },\n  \"wall_s\": %.2f\n}\n", (n_missed == 0U) ? "true" : "false", wall);
  if (fclose(f) != 0) {
    perror(path);
    return -1;
  }
  return 0;
}

static void usage(const char *argv0)
{
  fprintf(stderr,
          "usage: %s [-n fault_seeds] [-f fault_free_seeds] [-o out.json]\n"
          "  -n  noise seeds per fault case (1..%d, default 3)\n"
          "  -f  fault-free runs for sigma (2..%d, default 6)\n"
          "  -o  JSON output (default: none)\n"
          "example: %s -n 3 -f 6 -o build/bench/symptoms.json\n",
          argv0, MAX_SEEDS, MAX_SEEDS, argv0);
}

int main(int argc, char **argv)
{
  int n_seeds = 3;
  int n_ff = 6;
  const char *out = NULL;
  int opt;
  int s;
  size_t i;
  double t0;
  double wall;
  const char *met[MAX_CASES];
  const char *missed[MAX_CASES];
  size_t n_met = 0U;
  size_t n_missed = 0U;
  int rc = 0;

  while ((opt = getopt(argc, argv, "n:f:o:h")) != -1) {
    switch (opt) {
    case 'n': n_seeds = atoi(optarg); break;
    case 'f': n_ff = atoi(optarg); break;
    case 'o': out = optarg; break;
    default: usage(argv[0]); return (opt == 'h') ? 0 : 2;
    }
  }
  if ((n_seeds < 1) || (n_seeds > MAX_SEEDS) || (n_ff < 2) || (n_ff > MAX_SEEDS) || (optind != argc)) {
    usage(argv[0]);
    return 2;
  }
  t0 = bm_wall_s();
  build_cases();
  for (s = 0; (rc == 0) && (s < n_ff); s++) {
    rc = run_one(-1, 0.0, 1000U + (uint64_t)s, (unsigned)s, N_WIN_FF, &ff_acc[s]);
  }
  if (rc != 0) {
    fprintf(stderr, "bench_symptoms: fault-free run failed (%d)\n", rc);
    return 1;
  }
  score_fault_free(n_ff);
  fprintf(stderr, "symptoms: %d fault-free runs done (%.1f s); %zu fault cases x %d seeds\n", n_ff,
          bm_wall_s() - t0, n_cases, n_seeds);
  for (i = 0U; i < n_cases; i++) {
    case_t *cs = &cases[i];
    for (s = 0; s < n_seeds; s++) {
      rc = run_one((int)cs->id, cs->mag, 2000U + (100U * (uint64_t)i) + (uint64_t)s, (unsigned)s, 2, &f_acc);
      if (rc != 0) {
        fprintf(stderr, "bench_symptoms: run of %s failed (%d)\n", canfdi_fault_table[cs->id].name, rc);
        return 1;
      }
      score_case_seed(cs, s, &f_acc);
    }
    finish_case(cs, n_seeds);
    fprintf(stderr, "\rsymptoms: %zu/%zu cases, %.0f s", i + 1U, n_cases, bm_wall_s() - t0);
  }
  fprintf(stderr, "\n");
  wall = bm_wall_s() - t0;

  printf("Measured fault-symptom table: mean deviation after the fault / fault-free sigma "
         "(%d seeds; sigma from %d fault-free runs).\n"
         "Symptom when |dev| >= %.0f sigma (shown with its value), else 0; x = channel not valid after the fault; "
         "range checks (after |): +/- = the fraction of samples above/below the plausible range grew by >= %.1f. "
         "* = extra magnitude of a parametric fault. sigma = max(within-window sd, rms change of consecutive "
         "fault-free window means); (w) marks channels where the second (slow wander) dominates.\n\n",
         n_seeds, n_ff, SYMPTOM_SIGMA, RANGE_FRAC);
  print_group(BM_PLANT_DCM, dcm_cols, NELEM(dcm_cols), dcm_rcols, NELEM(dcm_rcols));
  print_group(BM_PLANT_THR, thr_cols, NELEM(thr_cols), thr_rcols, NELEM(thr_rcols));

  /* Symptoms in the other plant's channels would mean a coupling the rig
   * does not have: report them. */
  {
    unsigned n_cross = 0U;
    for (i = 0U; i < n_cases; i++) {
      unsigned c;
      for (c = 0U; c < BM_N_CH; c++) {
        if ((bm_chan[c].plant != fault_plant(cases[i].id)) && ((cases[i].sym[c] == '+') || (cases[i].sym[c] == '-'))) {
          printf("cross-plant symptom: %s %g -> %s %+.1f sigma\n", canfdi_fault_table[cases[i].id].name,
                 cases[i].mag, bm_chan[c].name, cases[i].mean_dev[c]);
          n_cross++;
        }
      }
    }
    printf("cross-plant symptoms (a fault of one plant moving the other plant's channels): %u\n\n", n_cross);
  }

  {
    static const char *const verdict[] = {"agrees", "weaker (a predicted symptom below 3 sigma)", "DIFFERS"};
    unsigned n_v[3] = {0U, 0U, 0U};
    printf("Parity structure, predicted by the module headers (+ - 0, '.' = weak/unstated) vs measured "
           "(r1 r2 r3 r4 | CORR ARM POS1 POS2):\n");
    for (i = 0U; i < n_cases; i++) {
      char m[5];
      int v;
      if (predicted_structure(cases[i].id) == NULL) {
        continue;
      }
      v = structure_cmp(cases[i].id, cases[i].sym, m);
      n_v[v]++;
      printf("  %-24s %-5g predicted %s measured %s %s\n", canfdi_fault_table[cases[i].id].name, cases[i].mag,
             predicted_structure(cases[i].id), m, verdict[v]);
    }
    printf("  %u agree, %u weaker, %u differ\n\n", n_v[0], n_v[1], n_v[2]);
  }
  printf("Acceptance (catalogue magnitude): a fault docs/design.md expects model-based methods to see must show "
         ">= 3 sigma in a residual or parameter.\n");
  for (i = 0U; i < n_cases; i++) {
    const case_t *cs = &cases[i];
    const char *why = not_observable_why(cs->id);
    unsigned c;
    if (!cs->is_default) {
      continue;
    }
    printf("  %-24s %-7s", canfdi_fault_table[cs->id].name,
           (why != NULL) ? "n/a" : (cs->observable ? "MET" : "MISSED"));
    for (c = 0U; c < BM_N_CH; c++) {
      if ((cs->sym[c] == '+') || (cs->sym[c] == '-')) {
        printf(" %s%c%s", bm_chan[c].name, cs->sym[c], cs->all_seeds[c] ? "" : "(mean only)");
      }
    }
    for (c = 0U; c < BM_N_RNG; c++) {
      if (cs->rsym[c] != '0') {
        printf(" %s%c", bm_rng[c].name, cs->rsym[c]);
      }
    }
    if (why != NULL) {
      printf("  [model-based: not expected; judged by %s%s]", seen_by(cs->id),
             cs->observable ? "; NOTE: a model channel moved anyway" : "");
    }
    printf("\n");
    if (why == NULL) {
      if (cs->observable) {
        met[n_met++] = canfdi_fault_table[cs->id].name;
      } else {
        missed[n_missed++] = canfdi_fault_table[cs->id].name;
      }
    }
  }
  printf("  smaller parametric magnitudes (*):");
  for (i = 0U; i < n_cases; i++) {
    if (!cases[i].is_default) {
      printf(" %s@%g:%s", canfdi_fault_table[cases[i].id].name, cases[i].mag, cases[i].observable ? "seen" : "NOT seen");
    }
  }
  printf("\nsymptoms: %zu of %zu expected-observable faults meet the 3-sigma criterion%s; wall time %.1f s\n", n_met,
         n_met + n_missed, (n_missed == 0U) ? " (acceptance point met)" : " (acceptance point NOT met)", wall);
  if (out != NULL) {
    if (write_json(out, n_seeds, n_ff, wall, met, n_met, missed, n_missed) != 0) {
      rc = 1;
    } else {
      printf("symptoms: wrote %s\n", out);
    }
  }
  return rc;
}
