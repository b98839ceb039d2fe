/*
 * canfdi_est_dcm.h — parameter estimator of the DC motor drive: armature
 * resistance R_A, inductance L_A and flux linkage Psi from the armature
 * equation, inertia J, viscous friction M_F1 and the constant load from the
 * mechanical equation, by two UD-RLS estimators (canfdi_rls.h) on signals
 * and derivatives from state-variable filters (canfdi_svf.h).
 *
 * Equations (Isermann, Fault-Diagnosis Systems; the motor of
 * docs/design.md):
 *   armature:    U_A = R_A I_A + L_A dI_A/dt + Psi w
 *                y = U_A,  phi = [I_A, dI_A/dt, w],  theta_a = [R_A, L_A, Psi]
 *   mechanical:  Psi I_A = J dw/dt + M_F1 w + M_F0 sign(w) + M_L
 *                divided by Psi (so that the measured current is the output):
 *                y = I_A,  phi = [dw/dt, w, 1],
 *                theta_m = [J / Psi, M_F1 / Psi, M_c / Psi]
 *                with M_c = M_F0 sign(w) + M_L lumped into one constant
 *                (the load is unknown; sign(w) is constant while the motor
 *                runs one way). J, M_F1 and M_c are recovered with Psi from
 *                the armature estimate (the nominal Psi until that one has
 *                converged). A speed-proportional load share (fan) is not
 *                separable from M_F1 and is reported inside M_F1.
 * Known load: canfdi_est_dcm_set_load_offset() gives dM_L, the known
 * change of the load from the operating point that cfg.mc_nom_q16 includes
 * (e.g. a load torque the vehicle reports minus the nominal load). It is
 * filtered by its own SVF and moved to the output side of the mechanical
 * equation, y = I_A - dM_L / Psi, so a known load step does not disturb
 * the RLS; theta_m[2] then estimates M_c - dM_L, and canfdi_est_dcm_mc_q16
 * adds dM_L back: the read-out stays the lumped M_c, comparable with
 * mc_nom + dM_L. Default 0 (the load is unknown, as above); kept across
 * resets.
 * Filtering: one SVF per measured signal (U_A, I_A, w), all with the same
 * configuration, shared by both equations — every signal of an equation sees
 * the same filter, so the filtered signals obey the same equations.
 * Sample alignment: the measured U_A of step k+1 is the bridge voltage held
 * during (t_k, t_k+1] (zero-order hold), whereas I_A and w are sampled
 * states. The trapezoidal SVF treats its input as the average of two
 * samples, so the consistent armature output is
 *   y = U_f + (T/2) dU_f/dt
 * (from (z + 1)/2 * [L s I + R I + Psi w] = z U in Tustin form); without
 * this term the estimate of L_A is biased by the half-sample delay.
 *
 * Decimation: the filters run every step; the two RLS updates run every
 * `decim` steps (offset by one step from each other so that no single step
 * carries both), which sets the estimator memory 1 / (forget * rate) and
 * divides the average cost.
 *
 * Flags: `excited` is the armature RLS's last excitation-gate decision;
 * `converged` is true once the armature RLS has applied conv_updates
 * updates since the last init/reset (the mechanical flag likewise). The
 * estimates are held (not forgotten) while the gate keeps them closed.
 *
 * Scaling and overflow: inputs Q16.16 SI (U_A V, I_A A, w rad/s); within
 * the ranges of the model layer (U_A +-60 V, I_A +-30 A, w +-400 rad/s,
 * dI/dt +-10000 A/s, dw/dt +-6000 rad/s^2) every filtered signal fits
 * Q16.16; the RLS normalising shifts are fixed below so that normalised
 * signals are O(1). Outputs: R_A and Psi Q16.16, L_A and J and M_F1 Q24
 * (their values are 1e-3 .. 1e-2; Q24 resolves 6e-8, i.e. < 1e-4
 * relative), M_c Q16.16 N m. Read-outs saturate.
 *
 * Cost per step: 4 SVF steps (order 2; the fourth filters the known load
 * offset) every step, plus one RLS update of 3 parameters on two of every
 * `decim` steps (never both in one step): canfdi_svf.h and canfdi_rls.h
 * state their cost per call; `make bench-pil-profile` measures the whole
 * step in the application, per module and function
 * (build/bench/pil_profile.json). Memory: sizeof(canfdi_est_dcm_t) = 1136
 * bytes on a 32-bit target (four SVFs and two RLS instances sized
 * CANFDI_CFG_RLS_MAX_PARAMS).
 */
#ifndef CANFDI_EST_DCM_H
#define CANFDI_EST_DCM_H

#include "model/canfdi_rls.h"
#include "model/canfdi_svf.h"

/* Normalising shifts (powers of two dividing the physical signal). */
#define CANFDI_EST_DCM_SHIFT_U 6    /* U_A / 64 V */
#define CANFDI_EST_DCM_SHIFT_I 3    /* I_A / 8 A */
#define CANFDI_EST_DCM_SHIFT_DI 10  /* dI/dt / 1024 A/s */
#define CANFDI_EST_DCM_SHIFT_W 7    /* w / 128 rad/s */
#define CANFDI_EST_DCM_SHIFT_DW 10  /* dw/dt / 1024 rad/s^2 */

typedef struct {
  canfdi_svf_cfg_t svf;     /* shared by all signals */
  uint8_t decim;            /* RLS update every decim steps, 1..100 */
  canfdi_q31_t forget_q31;  /* 1 - lambda, both RLS */
  int32_t p0_q16;           /* initial P diagonal (normalised units) */
  int32_t trace_max_q16;    /* trace bound (normalised units) */
  int32_t excite_min_q16;   /* armature excitation gate: mean-square
                             * normalised deviation of each of I_A and w */
  int32_t excite_min_mech_q16; /* mechanical gate, on dw/dt and w: higher,
                             * because dw/dt carries the differentiated speed
                             * noise, whose errors-in-variables bias pulls J
                             * toward 0 when noise alone passes the gate */
  uint8_t excite_shift;     /* excitation filter time constant, 2^k updates */
  uint32_t conv_updates;    /* updates until `converged` */
  /* nominal parameters: initial theta and the Psi used before convergence */
  int32_t ra_nom_q16;   /* Ohm */
  int32_t la_nom_q24;   /* H */
  int32_t psi_nom_q16;  /* V s */
  int32_t j_nom_q24;    /* kg m^2 */
  int32_t mf1_nom_q24;  /* N m s */
  int32_t mc_nom_q16;   /* N m, lumped Coulomb friction + load */
  uint16_t load_hold_steps; /* 0: off; else no mechanical update for this many
                             * steps after the known load offset changed
                             * (late load, see canfdi_est_dcm_set_load_offset) */
} canfdi_est_dcm_cfg_t;

/* Diagnostics counters: monotone, saturating at UINT32_MAX
 * (core/canfdi_count.h); init clears them, nothing else does. No decision
 * of the firmware depends on them (canfdi_est_dcm_has_run says whether the
 * estimator has stepped). */
typedef struct {
  uint32_t steps;           /* canfdi_est_dcm_step calls */
  uint32_t arm_updates;   /* armature RLS updates applied */
  uint32_t mech_updates;  /* mechanical RLS updates applied */
  uint32_t resets;          /* canfdi_est_dcm_reset calls (init counts as none) */
  uint32_t load_hold_skips; /* mechanical updates skipped: late-load hold */
} canfdi_est_dcm_diag_t;

typedef struct {
  canfdi_est_dcm_cfg_t cfg;
  canfdi_svf_t svf_u;
  canfdi_svf_t svf_i;
  canfdi_svf_t svf_w;
  canfdi_svf_t svf_l;     /* known load offset dM_L */
  canfdi_rls_t arm;
  canfdi_rls_t mech;
  uint8_t phase;          /* step counter modulo decim, 0 .. decim - 1 */
  uint8_t updated;        /* CANFDI_EST_DCM_UPD_* of the last step */
  bool has_run;           /* stepped at least once since init (reset keeps it) */
  bool started;           /* filters reset on the first sample */
  uint32_t arm_since_reset;  /* armature updates since init/reset (state of
                              * `converged`), saturating at UINT32_MAX */
  uint32_t mech_since_reset; /* mechanical updates, likewise */
  int32_t dload_q16;      /* known load offset, Q16.16 N m */
  uint16_t load_hold;     /* steps left of the late-load hold */
  canfdi_est_dcm_diag_t diag;
} canfdi_est_dcm_t;

/*
 * Defaults for Isermann's motor at 1 ms: SVF order 2 at 200 rad/s, decim 5
 * (200 Hz updates), lambda 0.99 (memory 0.5 s), p0 100, trace bound 1000,
 * armature excitation threshold 2e-4 on the less excited of I_A and w (a
 * speed swing of ~1.8 rad/s rms; sensor noise alone gives ~1e-5, so the
 * gate opens within ~10 updates of a test signal of a few rad/s instead of
 * ~70 with 1e-3), mechanical threshold 1e-3 on dw/dt and w (the speed
 * noise differentiated by the SVF reaches ~1.5e-4), time constant 2^6
 * updates, converged after
 * 400 updates (2 s), nominal parameters of docs/design.md with
 * M_c = 0.11 + 1.2 N m, no late-load hold (load_hold_steps 0).
 */
void canfdi_est_dcm_default_cfg(canfdi_est_dcm_cfg_t *cfg);

/* Validates (SVF and RLS domains, decim 1..100, positive nominal Psi) and
 * resets. CANFDI_OK or -CANFDI_EINVAL (then *e may be partly written and
 * must not be stepped). */
int32_t canfdi_est_dcm_init(canfdi_est_dcm_t *e, const canfdi_est_dcm_cfg_t *cfg);

/* Back to the nominal parameters and P0; the filters restart on the next
 * sample. keep_theta: covariance reset only. Cannot fail. */
void canfdi_est_dcm_reset(canfdi_est_dcm_t *e, bool keep_theta);

/* Covariance boost of both RLS (canfdi_rls_boost): filters, estimates,
 * convergence state and excitation measures kept. For a change the caller
 * detected (the diagnosis' first symptom). Cannot fail. Cost: O(n^2). */
void canfdi_est_dcm_boost(canfdi_est_dcm_t *e);

/* Which RLS applied an update in the last step: bit 0 armature, bit 1
 * mechanical (CANFDI_EST_DCM_UPD_*). O(1). */
#define CANFDI_EST_DCM_UPD_ARM 0x01U
#define CANFDI_EST_DCM_UPD_MECH 0x02U
uint8_t canfdi_est_dcm_updated(const canfdi_est_dcm_t *e);

/* The next step is step k of the caller's schedule: the armature update
 * falls on the steps with k mod decim = 0, the mechanical update on those
 * with k mod decim = 1 (the same steps when decim is 1). Called before
 * every step, it locks the updates to the schedule; never called, they
 * count from the estimator's (re)start. Cannot fail. Cost: O(1);
 * a 32-bit division only for k >= decim. */
void canfdi_est_dcm_align(canfdi_est_dcm_t *e, uint32_t k);

/* The known load offset dM_L (Q16.16 N m, see the header) used from the
 * next step on until changed. Cannot fail. Cost: O(1).
 * Late load: a known load that arrives over a bus lags the true one by up
 * to a frame cycle, and for that lag the mechanical equation carries the
 * whole step as an unexplained torque. The filtered signals keep the
 * mismatch after the new value arrives, for the tail of the SVF's step
 * response, e^-x (1 + x) at x = wc t for order 2, below 1e-3 from
 * x = 9.23 on. A change of the value therefore closes the mechanical
 * update for cfg.load_hold_steps steps (ceil(9.23 / (wc T)) = 47 at
 * 200 rad/s; diag.load_hold_skips); the <= lag / (decim T) updates made
 * before the change was known remain (2 at 10 ms and decim 5). */
void canfdi_est_dcm_set_load_offset(canfdi_est_dcm_t *e, int32_t dload_q16);

/* One 1 ms step with the measurements (Q16.16: V, A, rad/s). Cannot fail. */
void canfdi_est_dcm_step(canfdi_est_dcm_t *e, int32_t ua_q16, int32_t ia_q16, int32_t w_q16);

/* Physical estimates. */
int32_t canfdi_est_dcm_ra_q16(const canfdi_est_dcm_t *e);
int32_t canfdi_est_dcm_la_q24(const canfdi_est_dcm_t *e);
int32_t canfdi_est_dcm_psi_q16(const canfdi_est_dcm_t *e);
int32_t canfdi_est_dcm_j_q24(const canfdi_est_dcm_t *e);
int32_t canfdi_est_dcm_mf1_q24(const canfdi_est_dcm_t *e);
int32_t canfdi_est_dcm_mc_q16(const canfdi_est_dcm_t *e);

/* Whether canfdi_est_dcm_step ran at least once since init (a reset does
 * not clear it): the state a caller needs to tell a restart from the first
 * start. O(1). */
bool canfdi_est_dcm_has_run(const canfdi_est_dcm_t *e);

/* Flags (see above): armature gate open at the last update; armature /
 * mechanical estimate converged. */
bool canfdi_est_dcm_excited(const canfdi_est_dcm_t *e);
bool canfdi_est_dcm_arm_converged(const canfdi_est_dcm_t *e);
bool canfdi_est_dcm_mech_converged(const canfdi_est_dcm_t *e);

/* The two estimators, read-only (covariance, diagnostics, invariants). */
const canfdi_rls_t *canfdi_est_dcm_arm_rls(const canfdi_est_dcm_t *e);
const canfdi_rls_t *canfdi_est_dcm_mech_rls(const canfdi_est_dcm_t *e);

const canfdi_est_dcm_diag_t *canfdi_est_dcm_diag(const canfdi_est_dcm_t *e);

#endif /* CANFDI_EST_DCM_H */
