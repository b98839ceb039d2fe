/*
 * canfdi_sim_frames.h — the plant's CAN frames: DcmSensor and ThrSensor
 * every 1 ms, SimPlantStatus every 100 ms, packed with the codec generated
 * from dbc/canfdi.dbc (host_sim/gen/canfdi_sim_msg.h), protected with
 * firmware/comm/canfdi_e2e.h, and damaged as the communication faults
 * demand. No bit packing here: only the generated codec touches bits.
 *
 * Signals carry the quantised sensor values (canfdi_sim_meas_t.value),
 * encoded by the generated encoders, which truncate to the DBC raw value at
 * or below (error < 1 DBC LSB; the DBC resolution is about half an ADC LSB;
 * the PLANT codec has no decoders for these frames, so no rounding step).
 *
 * Communication faults (canfdi_sim_fx_t.frame[], per sensor frame):
 *   drop         the frame is not sent; its counter does not advance
 *   bad_counter  the counter repeats the last value sent, while the
 *                sender's sequence keeps advancing, so the first good frame
 *                after the fault jumps (E2E: REPEATED, then WRONG_SEQUENCE
 *                or OK_SOME_LOST)
 *   bad_crc      the CRC byte is inverted (always wrong)
 *   bad_dlc      the frame goes out with DLC 7 (last byte cut)
 *   implausible  every measurement signal is raw all-ones (outside its DBC
 *                min/max), counter and CRC valid
 * Several flags may combine; drop wins.
 *
 * SimPlantStatus (no E2E, a test-bench frame): first fault of the scenario
 * that is acting now, else the first injected one (0 = none); its mode and
 * whether it acts; throttle de-energised (bridge disabled or motor open);
 * active DC-motor bridge (0 when disabled); sim mode; time; true angle;
 * winding temperature.
 *
 * Cost: two or three cantools packs and CRCs per step. Memory: ~24 bytes.
 */
#ifndef CANFDI_SIM_FRAMES_H
#define CANFDI_SIM_FRAMES_H

#include <stddef.h>
#include <stdint.h>

#include "canfdi_sim.h"
#include "comm/canfdi_e2e.h"

#define CANFDI_SIM_FRAMES_MAX_PER_STEP 3U
#define CANFDI_SIM_STATUS_PERIOD_STEPS 100U

/* PstSimMode values. */
#define CANFDI_SIM_MODE_LOCKSTEP 0U
#define CANFDI_SIM_MODE_REALTIME 1U
#define CANFDI_SIM_MODE_OFFLINE 2U

typedef struct {
  uint32_t id;
  uint8_t dlc;
  uint8_t data[8];
} canfdi_sim_frame_t;

typedef struct {
  uint32_t sent;         /* frames returned (monotone) */
  uint32_t dropped;      /* sensor frames suppressed by drop */
  uint32_t corrupted;    /* sensor frames with any other damage */
} canfdi_sim_frames_diag_t;

typedef struct {
  canfdi_e2e_tx_t tx[CANFDI_SIM_N_FRAMES];
  uint8_t last_counter[CANFDI_SIM_N_FRAMES];
  uint8_t sim_mode;
  canfdi_sim_frames_diag_t diag;
} canfdi_sim_frames_t;

/* Cannot fail by contract. sim_mode: CANFDI_SIM_MODE_*. */
void canfdi_sim_frames_init(canfdi_sim_frames_t *f, uint8_t sim_mode);

/* Frames due at the simulation's current time, built from sim->meas and
 * sim->fx; act is the actuator input now applied to the plant. out must
 * hold CANFDI_SIM_FRAMES_MAX_PER_STEP frames (all are cleared); returns how
 * many were written, in the order DcmSensor, ThrSensor, SimPlantStatus.
 * Cannot fail by contract. */
size_t canfdi_sim_frames_build(canfdi_sim_frames_t *f, const canfdi_sim_t *sim,
                               const canfdi_sim_in_t *act, canfdi_sim_frame_t *out);

#endif /* CANFDI_SIM_FRAMES_H */
