/* canfdi_sim_fault.c — see canfdi_sim_fault.h. */
#include "canfdi_sim_fault.h"

#include <math.h>
#include <string.h>

#include "core/canfdi_common.h"
#include "gen/canfdi_faults.h"

/* Every id must fit the 64-bit active mask. */
CANFDI_STATIC_ASSERT(CANFDI_FAULT_COUNT <= 64U, fault_ids_fit_mask);

static const char *const mode_names[3] = {"abrupt", "incipient", "intermittent"};

int canfdi_sim_fault_find(const char *name)
{
  int out = -CANFDI_EINVAL;
  size_t i;
  if (name != NULL) {
    for (i = 0U; i < canfdi_fault_table_len; i++) {
      if (strcmp(canfdi_fault_table[i].name, name) == 0) {
        out = (int)canfdi_fault_table[i].id;
        break;
      }
    }
  }
  return out;
}

int canfdi_sim_fault_mode_find(const char *name)
{
  int out = -CANFDI_EINVAL;
  unsigned i;
  if (name != NULL) {
    for (i = 0U; i < 3U; i++) {
      if (strcmp(mode_names[i], name) == 0) {
        out = (int)i;
      }
    }
  }
  return out;
}

const char *canfdi_sim_fault_mode_name(uint8_t mode)
{
  return (mode < 3U) ? mode_names[mode] : "?";
}

/* True if the '|'-separated list `modes` contains `mode`. */
static bool mode_allowed(const char *modes, const char *mode)
{
  const size_t len = strlen(mode);
  const char *p = modes;
  bool found = false;
  while ((p != NULL) && (*p != '\0') && !found) {
    const char *bar = strchr(p, '|');
    const size_t tok = (bar != NULL) ? (size_t)(bar - p) : strlen(p);
    if ((tok == len) && (strncmp(p, mode, len) == 0)) {
      found = true;
    }
    p = (bar != NULL) ? (bar + 1) : NULL;
  }
  return found;
}

int canfdi_sim_fault_magnitude_range(uint8_t id, double *lo, double *hi, bool *lo_open)
{
  int rc = CANFDI_OK;
  *lo_open = false;
  switch (id) {
  case CANFDI_FAULT_DCM_RA_UP:
  case CANFDI_FAULT_DCM_FRICTION_UP:
  case CANFDI_FAULT_THR_FRICTION_UP:
  case CANFDI_FAULT_THR_MOTOR_R_UP:
    *lo = 0.0; /* up to ten times the healthy value */
    *hi = 10.0;
    break;
  case CANFDI_FAULT_DCM_FLUX_DOWN:
    *lo = 0.0; /* a motor without any flux is not a drift any more */
    *hi = 0.9;
    break;
  case CANFDI_FAULT_THR_SPRING_WEAK:
    *lo = 0.0; /* 1 = spring broken */
    *hi = 1.0;
    break;
  case CANFDI_FAULT_DCM_SPEED_SENSOR_GAIN:
    *lo = -1.0; /* gain must stay positive */
    *lo_open = true;
    *hi = 10.0;
    break;
  case CANFDI_FAULT_DCM_IA_SENSOR_OFFSET:
    *lo = -60.0; /* at most the sensor span */
    *hi = 60.0;
    break;
  case CANFDI_FAULT_DCM_SPEED_SENSOR_OFFSET:
    *lo = -800.0;
    *hi = 800.0;
    break;
  case CANFDI_FAULT_DCM_UA_SENSOR_OFFSET:
    *lo = -120.0;
    *hi = 120.0;
    break;
  case CANFDI_FAULT_THR_TPS1_DRIFT:
  case CANFDI_FAULT_THR_TPS2_DRIFT:
    *lo = -5.0;
    *hi = 5.0;
    break;
  default:
    if (id < canfdi_fault_table_len) {
      *lo = -1e300; /* binary: the magnitude is ignored, only finite */
      *hi = 1e300;
    } else {
      rc = -CANFDI_EINVAL;
    }
    break;
  }
  return rc;
}

static bool time_ok(double t_s)
{
  return isfinite(t_s) && (t_s >= 0.0) && (t_s <= CANFDI_SIM_FAULT_MAX_S);
}

static int64_t to_us(double t_s)
{
  return (int64_t)llround(t_s * 1e6);
}

int canfdi_sim_fault_spec_make(canfdi_sim_fault_spec_t *spec, uint8_t id, uint8_t mode,
                               double t_start_s, double magnitude, double ramp_s,
                               double period_s, double duty)
{
  int rc = CANFDI_OK;
  double lo = 0.0;
  double hi = 0.0;
  bool lo_open = false;

  if ((spec == NULL) || (id >= canfdi_fault_table_len) || (mode > CANFDI_SIM_MODE_INTERMITTENT) ||
      !mode_allowed(canfdi_fault_table[id].modes, mode_names[mode]) || !time_ok(t_start_s) ||
      !isfinite(magnitude)) {
    rc = -CANFDI_EINVAL;
  } else if ((mode == CANFDI_SIM_MODE_INCIPIENT) && (!time_ok(ramp_s) || (to_us(ramp_s) < 1))) {
    rc = -CANFDI_EINVAL;
  } else if ((mode == CANFDI_SIM_MODE_INTERMITTENT) &&
             (!time_ok(period_s) || (to_us(period_s) < 2) || !isfinite(duty) ||
              !(duty > 0.0) || (duty > 1.0))) {
    rc = -CANFDI_EINVAL;
  } else {
    (void)canfdi_sim_fault_magnitude_range(id, &lo, &hi, &lo_open);
    if ((magnitude < lo) || (lo_open && !(magnitude > lo)) || (magnitude > hi)) {
      rc = -CANFDI_ERANGE;
    }
  }
  if (rc == CANFDI_OK) {
    spec->id = id;
    spec->mode = mode;
    spec->magnitude = magnitude;
    spec->t_start_us = to_us(t_start_s);
    spec->ramp_us = 0;
    spec->period_us = 0;
    spec->on_us = 0;
    if (mode == CANFDI_SIM_MODE_INCIPIENT) {
      spec->ramp_us = to_us(ramp_s);
    } else if (mode == CANFDI_SIM_MODE_INTERMITTENT) {
      spec->period_us = to_us(period_s);
      spec->on_us = (int64_t)llround(duty * (double)spec->period_us);
      if (spec->on_us < 1) {
        spec->on_us = 1; /* a duty that rounds to nothing still switches on */
      }
    } else {
      /* abrupt: nothing else */
    }
  }
  return rc;
}

double canfdi_sim_fault_shape(const canfdi_sim_fault_spec_t *spec, int64_t t_us)
{
  double s = 0.0;
  if (t_us >= spec->t_start_us) {
    const int64_t dt = t_us - spec->t_start_us;
    switch (spec->mode) {
    case CANFDI_SIM_MODE_INCIPIENT:
      s = (dt >= spec->ramp_us) ? 1.0 : ((double)dt / (double)spec->ramp_us);
      break;
    case CANFDI_SIM_MODE_INTERMITTENT:
      s = ((dt % spec->period_us) < spec->on_us) ? 1.0 : 0.0;
      break;
    default:
      s = 1.0;
      break;
    }
  }
  return s;
}

void canfdi_sim_fx_none(canfdi_sim_fx_t *fx)
{
  unsigned i;
  canfdi_sim_dcm_fx_none(&fx->dcm);
  canfdi_sim_thr_fx_none(&fx->thr);
  fx->ia_offset_A = 0.0;
  fx->speed_gain = 0.0;
  fx->speed_offset_rad_s = 0.0;
  fx->ua_offset_V = 0.0;
  for (i = 0U; i < 2U; i++) {
    fx->tps_offset_V[i] = 0.0;
    fx->tps_open[i] = false;
    fx->tps_short[i] = false;
  }
  for (i = 0U; i < CANFDI_SIM_N_FRAMES; i++) {
    fx->frame[i].drop = false;
    fx->frame[i].bad_crc = false;
    fx->frame[i].bad_counter = false;
    fx->frame[i].bad_dlc = false;
    fx->frame[i].implausible = false;
  }
  fx->active_mask = 0U;
}

/* Applies one fault with effective magnitude m (= s * magnitude); binary
 * effects are applied when on (s = 1). */
static void apply_one(uint8_t id, double m, bool on, canfdi_sim_fx_t *fx)
{
  switch (id) {
  case CANFDI_FAULT_DCM_RA_UP:
    fx->dcm.ra_factor *= 1.0 + m;
    break;
  case CANFDI_FAULT_DCM_FLUX_DOWN:
    fx->dcm.psi_factor *= 1.0 - m;
    break;
  case CANFDI_FAULT_DCM_FRICTION_UP:
    fx->dcm.friction_factor *= 1.0 + m;
    break;
  case CANFDI_FAULT_DCM_IA_SENSOR_OFFSET:
    fx->ia_offset_A += m;
    break;
  case CANFDI_FAULT_DCM_SPEED_SENSOR_GAIN:
    /* gains compose multiplicatively: (1 + g1)(1 + g2) - 1 */
    fx->speed_gain = ((1.0 + fx->speed_gain) * (1.0 + m)) - 1.0;
    break;
  case CANFDI_FAULT_DCM_SPEED_SENSOR_OFFSET:
    fx->speed_offset_rad_s += m;
    break;
  case CANFDI_FAULT_DCM_UA_SENSOR_OFFSET:
    fx->ua_offset_V += m;
    break;
  case CANFDI_FAULT_DCM_BRIDGE_A_DEAD:
    fx->dcm.bridge_dead[0] = fx->dcm.bridge_dead[0] || on;
    break;
  case CANFDI_FAULT_DCM_BRIDGES_DEAD:
    fx->dcm.bridge_dead[0] = fx->dcm.bridge_dead[0] || on;
    fx->dcm.bridge_dead[1] = fx->dcm.bridge_dead[1] || on;
    break;
  case CANFDI_FAULT_THR_TPS1_OPEN:
    fx->tps_open[0] = fx->tps_open[0] || on;
    break;
  case CANFDI_FAULT_THR_TPS1_SHORT:
    fx->tps_short[0] = fx->tps_short[0] || on;
    break;
  case CANFDI_FAULT_THR_TPS2_OPEN:
    fx->tps_open[1] = fx->tps_open[1] || on;
    break;
  case CANFDI_FAULT_THR_TPS2_SHORT:
    fx->tps_short[1] = fx->tps_short[1] || on;
    break;
  case CANFDI_FAULT_THR_TPS1_DRIFT:
    fx->tps_offset_V[0] += m;
    break;
  case CANFDI_FAULT_THR_TPS2_DRIFT:
    fx->tps_offset_V[1] += m;
    break;
  case CANFDI_FAULT_THR_SPRING_WEAK:
    fx->thr.spring_factor *= 1.0 - m;
    break;
  case CANFDI_FAULT_THR_FRICTION_UP:
    fx->thr.friction_factor *= 1.0 + m;
    break;
  case CANFDI_FAULT_THR_MOTOR_R_UP:
    fx->thr.r_factor *= 1.0 + m;
    break;
  case CANFDI_FAULT_THR_MOTOR_OPEN:
    fx->thr.motor_open = fx->thr.motor_open || on;
    break;
  case CANFDI_FAULT_THR_JAMMED:
    fx->thr.jammed = fx->thr.jammed || on;
    break;
  case CANFDI_FAULT_THR_TPS_BOTH_LOST:
    fx->tps_open[0] = fx->tps_open[0] || on;
    fx->tps_open[1] = fx->tps_open[1] || on;
    break;
  case CANFDI_FAULT_COM_DCM_TIMEOUT:
    fx->frame[CANFDI_SIM_FRAME_DCM].drop = fx->frame[CANFDI_SIM_FRAME_DCM].drop || on;
    break;
  case CANFDI_FAULT_COM_THR_TIMEOUT:
    fx->frame[CANFDI_SIM_FRAME_THR].drop = fx->frame[CANFDI_SIM_FRAME_THR].drop || on;
    break;
  case CANFDI_FAULT_COM_DCM_COUNTER:
    fx->frame[CANFDI_SIM_FRAME_DCM].bad_counter = fx->frame[CANFDI_SIM_FRAME_DCM].bad_counter || on;
    break;
  case CANFDI_FAULT_COM_THR_COUNTER:
    fx->frame[CANFDI_SIM_FRAME_THR].bad_counter = fx->frame[CANFDI_SIM_FRAME_THR].bad_counter || on;
    break;
  case CANFDI_FAULT_COM_DCM_CRC:
    fx->frame[CANFDI_SIM_FRAME_DCM].bad_crc = fx->frame[CANFDI_SIM_FRAME_DCM].bad_crc || on;
    break;
  case CANFDI_FAULT_COM_THR_CRC:
    fx->frame[CANFDI_SIM_FRAME_THR].bad_crc = fx->frame[CANFDI_SIM_FRAME_THR].bad_crc || on;
    break;
  case CANFDI_FAULT_COM_DCM_LENGTH:
    fx->frame[CANFDI_SIM_FRAME_DCM].bad_dlc = fx->frame[CANFDI_SIM_FRAME_DCM].bad_dlc || on;
    break;
  case CANFDI_FAULT_COM_THR_LENGTH:
    fx->frame[CANFDI_SIM_FRAME_THR].bad_dlc = fx->frame[CANFDI_SIM_FRAME_THR].bad_dlc || on;
    break;
  case CANFDI_FAULT_COM_DCM_IMPLAUSIBLE:
    fx->frame[CANFDI_SIM_FRAME_DCM].implausible = fx->frame[CANFDI_SIM_FRAME_DCM].implausible || on;
    break;
  case CANFDI_FAULT_COM_THR_IMPLAUSIBLE:
    fx->frame[CANFDI_SIM_FRAME_THR].implausible = fx->frame[CANFDI_SIM_FRAME_THR].implausible || on;
    break;
  default:
    /* CANFDI_FAULT_NONE and anything the catalogue adds later without
     * physics here: no effect. test_sim_fault fails for the latter. */
    break;
  }
}

void canfdi_sim_fault_effects(const canfdi_sim_fault_spec_t *specs, size_t n, int64_t t_us,
                              canfdi_sim_fx_t *fx)
{
  size_t i;
  canfdi_sim_fx_none(fx);
  for (i = 0U; i < n; i++) {
    const double s = canfdi_sim_fault_shape(&specs[i], t_us);
    if (s > 0.0) {
      apply_one(specs[i].id, s * specs[i].magnitude, s >= 1.0, fx);
      if ((specs[i].id != CANFDI_FAULT_NONE) && (specs[i].id < 64U)) {
        fx->active_mask |= (uint64_t)1U << specs[i].id;
      }
    }
  }
}
