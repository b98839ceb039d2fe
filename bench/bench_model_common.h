/*
 * bench_model_common.h — the closed-loop rig shared by the model-layer
 * benches (bench_symptoms.c, bench_longrun.c): both host_sim plants under
 * the stand-in reference controller, the four fixed-point model modules fed
 * with the sensor values, and the signal-based symptoms, all sampled into
 * one flat table of "channels" per 1 ms step.
 *
 * One step (bm_rig_step):
 *   1. the reference controller computes both actuator commands from the
 *      setpoints and the last measurement (canfdi_sim_refctl.h);
 *   2. the plant advances 1 ms (canfdi_sim_step) and samples its sensors
 *      (12-bit ADC values with noise, as the simulator provides them);
 *   3. the measured values are converted to Q16.16 SI units (rounded,
 *      saturated) and fed to canfdi_parity_dcm, canfdi_est_dcm,
 *      canfdi_parity_thr and canfdi_est_thr, exactly as the unit tests do:
 *        parity_dcm  measured U_A, I_A, w and the load the application
 *                    knows (the load setpoint; the true load equals it);
 *        est_dcm     measured U_A, I_A, w;
 *        parity_thr  TPS1, TPS2, current, the command in force over the
 *                    interval, the measured supply, the bridge enable;
 *        est_thr     the command clamped to the measured supply, the
 *                    current, and the angle the controller computes from
 *                    the potentiometers (mean of the plausible ones) in
 *                    rad — held at its last value while neither TPS is
 *                    plausible (the estimator has no position then);
 *   4. every channel's value and validity is recorded (bm_rig_t.val/valid).
 *
 * Noise model (sigma on top of the ADC quantisation; the same as
 * bench/bench_sim.c and the estimator tests): U_A 0.05 V, I_A 0.02 A,
 * w 0.2 rad/s, DC supply 0.05 V, TPS 3 mV each, throttle current 0.01 A,
 * throttle supply 0.01 V.
 *
 * Host-only bench code: double precision is fine here; the firmware
 * modules themselves are the -O2 host build of the fixed-point sources.
 */
#ifndef BENCH_MODEL_COMMON_H
#define BENCH_MODEL_COMMON_H

#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>

#include "canfdi_sim.h"
#include "canfdi_sim_refctl.h"
#include "model/canfdi_est_dcm.h"
#include "model/canfdi_est_thr.h"
#include "model/canfdi_parity_dcm.h"
#include "model/canfdi_parity_thr.h"

/* Channels: residuals, estimated parameters, signal-based symptoms. */
enum {
  BM_CH_R1 = 0, /* parity_dcm r1 [V] */
  BM_CH_R2,     /* r2 [N m] */
  BM_CH_R3,     /* r3 [N m] */
  BM_CH_R4,     /* r4 [V] */
  BM_CH_CORR,   /* parity_thr TPS correlation [V] */
  BM_CH_ARM,    /* throttle armature equation [V] */
  BM_CH_POS1,   /* TPS1 angle - observer [rad] */
  BM_CH_POS2,   /* TPS2 angle - observer [rad] */
  BM_CH_D_RA,   /* est_dcm R_A [Ohm] */
  BM_CH_D_LA,   /* L_A [H] */
  BM_CH_D_PSI,  /* Psi [V s] */
  BM_CH_D_J,    /* J [kg m^2] */
  BM_CH_D_MF1,  /* M_F1 [N m s] */
  BM_CH_D_MC,   /* M_c = M_F0 sgn(w) + M_L [N m] */
  BM_CH_T_R,    /* est_thr R [Ohm] */
  BM_CH_T_L,    /* L [H] */
  BM_CH_T_K,    /* K [N m/A] */
  BM_CH_T_U0,   /* U_0 [V] */
  BM_CH_T_J,    /* J [kg m^2] */
  BM_CH_T_B,    /* B [N m s/rad] */
  BM_CH_T_KS,   /* spring constant [N m/rad] */
  BM_CH_T_P,    /* pretension [N m] */
  BM_CH_T_TC,   /* Coulomb friction [N m] */
  BM_CH_T_FP,   /* fast test: spring torque scale as pretension P_nom (1 + a) [N m] */
  BM_CH_T_FTC,  /* fast test: Coulomb friction T_c,nom (1 + dev) [N m] */
  BM_CH_UA_CMD, /* measured U_A - command clamped to the measured supply [V] */
  BM_CH_D_TRK,  /* speed setpoint - measured speed [rad/s] */
  BM_CH_T_TRK,  /* angle setpoint - measured angle [deg] */
  BM_N_CH
};

/* Number of residual channels (the first ones), and where each plant's
 * residuals start. */
#define BM_N_RES 8U
#define BM_FIRST_PARAM BM_CH_D_RA
#define BM_FIRST_SIGNAL BM_CH_UA_CMD

/* Range checks (limit checking of a raw sensor value against its plausible
 * range): state -1 below, 0 inside, +1 above. */
enum {
  BM_RNG_TPS1 = 0, /* 0.25 .. 4.75 V */
  BM_RNG_TPS2,     /* 0.25 .. 4.75 V */
  BM_RNG_IA,       /* |I_A| < 29.5 A (the ADC span is +-30 A) */
  BM_RNG_W,        /* |w| < 395 rad/s (span +-400) */
  BM_RNG_THR_I,    /* |i| < 9.9 A (span +-10 A) */
  BM_N_RNG
};

#define BM_KIND_RESIDUAL 0U
#define BM_KIND_PARAMETER 1U
#define BM_KIND_SIGNAL 2U
#define BM_KIND_RANGE 3U

#define BM_PLANT_DCM 0U
#define BM_PLANT_THR 1U

typedef struct {
  const char *name;   /* JSON key, e.g. "r1", "est_dcm.R_A" */
  const char *label;  /* short table heading */
  const char *unit;
  uint8_t kind;       /* BM_KIND_* */
  uint8_t plant;      /* BM_PLANT_* */
  double nominal;     /* the plant's true value (parameters), else 0 */
} bm_chan_info_t;

extern const bm_chan_info_t bm_chan[BM_N_CH];
extern const bm_chan_info_t bm_rng[BM_N_RNG];

typedef struct {
  bool dcm_thermal;     /* winding warm-up on (start cold at ambient) */
  double dcm_ra_cold_ohm; /* R_A at ambient (host_sim default 1.35) */
  uint64_t seed;        /* noise seed */
} bm_rig_opts_t;

typedef struct {
  canfdi_sim_cfg_t sim_cfg;
  canfdi_sim_t sim;
  canfdi_sim_refctl_t ctl;
  canfdi_parity_dcm_cfg_t pdcm_cfg; /* must outlive pdcm */
  canfdi_parity_dcm_t pdcm;
  canfdi_parity_thr_cfg_t pthr_cfg; /* must outlive pthr */
  canfdi_parity_thr_t pthr;
  canfdi_est_dcm_t edcm;
  canfdi_est_thr_t ethr;
  double angle_rad_hold; /* last plausible angle for est_thr */
  long k;                /* completed steps */
  /* last step */
  double val[BM_N_CH];
  uint32_t valid;        /* bit c: channel c valid */
  double rn[BM_N_RES];   /* residual / threshold */
  uint32_t exceed;       /* bit c (c < BM_N_RES): valid and beyond threshold */
  int8_t rng[BM_N_RNG];  /* range-check state */
  const canfdi_parity_dcm_out_t *pdcm_out;
  const canfdi_parity_thr_out_t *pthr_out;
} bm_rig_t;

CANFDI_STATIC_ASSERT(BM_N_CH <= 32, valid_mask_fits);

/* Q16.16 from a double, rounded, saturated. */
int32_t bm_q16(double x);

void bm_rig_default_opts(bm_rig_opts_t *o);

/* Plants at rest (throttle at limp-home, motor at ambient temperature),
 * default module configurations, no fault. Returns 0 or a negative code
 * (a configuration the modules or the plant reject). */
int bm_rig_init(bm_rig_t *r, const bm_rig_opts_t *o);

/* Puts the DC motor at a running operating point (speed w, the current
 * that carries the load at the nominal Psi, winding at ambient) and
 * re-samples, so that no run starts with a clipped start-up current. Call
 * after bm_rig_init, before the first step. 0 or negative. */
int bm_rig_start_dcm(bm_rig_t *r, double w_rad_s, double load_Nm);

/* Adds an abrupt fault at t_s (catalogue id, magnitude). 0 or negative. */
int bm_rig_add_fault(bm_rig_t *r, uint8_t id, double t_s, double magnitude);

/* One 1 ms step with the speed setpoint [rad/s], angle setpoint [deg] and
 * load [N m] in force over it (see the header comment). */
void bm_rig_step(bm_rig_t *r, double speed_ref_rad_s, double angle_ref_deg, double load_Nm);

/* Wall-clock seconds (CLOCK_MONOTONIC). */
double bm_wall_s(void);

/* Writes s as a JSON string (quotes and escapes). */
void bm_json_str(FILE *f, const char *s);

#endif /* BENCH_MODEL_COMMON_H */
