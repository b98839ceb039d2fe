/*
 * canfdi_sim_rig.h — the plant and vehicle side of one 1 ms lockstep step,
 * shared by the SIL runner (tests/sil/canfdi_sil.c, the ECU in the same
 * process) and canfdi-sim on SocketCAN (host_sim/canfdi_sim_main.c, the ECU
 * in another process), so that SIL and HIL run the same code.
 *
 * One step k (t_k = k ms = canfdi_sim_time_us(sim)):
 *   canfdi_sim_rig_begin   evaluates the scenario at t_k; every
 *                          CANFDI_SIM_RIG_SETPOINT_PERIOD_STEPS steps the
 *                          vehicle's SetpointDcm (speed + known load) and
 *                          SetpointThr, E2E protected (counter +1 per frame,
 *                          CRC over the data ID 0x100 / 0x101 and bytes
 *                          1..7, comm/canfdi_e2e.h); then the plant's frames of the sample
 *                          at t_k (canfdi_sim_frames_build: DcmSensor,
 *                          ThrSensor — damaged by comm faults — and
 *                          SimPlantStatus when due). The caller puts them on
 *                          the bus in this order.
 *   canfdi_sim_rig_rx      applies one received frame (any number per step):
 *                          DcmActuator / ThrActuator set the actuator inputs
 *                          (held until the next ones, like a real bridge);
 *                          SimFaultInject adds a fault starting at
 *                          t_k + InjStartDelay; SimFaultClear removes one
 *                          fault id (0: every fault, the scenario's too);
 *                          an external SetpointDcm / SetpointThr overrides
 *                          the scenario's values from then on: the rig keeps
 *                          sending the override (the same raw signal values,
 *                          in its own E2E sequence) every 10 ms, and its
 *                          SpDcmLoad becomes the plant load. The override's
 *                          CRC and counter are not checked (a test bench's
 *                          command). Other ids are counted and ignored.
 *   canfdi_sim_rig_end     plant load = the step's load (scenario or
 *                          override), the plants' supplies = the scenario's
 *                          at t_k (canfdi_sim_scn_supply; not overridable),
 *                          canfdi_sim_step to t_k+1 with the actuator inputs
 *                          held.
 * In lockstep the ECU's actuator frames of step k arrive between _begin and
 * _end (lag 1: the command of step k acts over (t_k, t_k+1], the sample at
 * t_k+1 shows it). canfdi_sim_rig_sim_step() builds SimStep(k) (0x611) for
 * the HIL lockstep protocol: the plant sends it after the frames of
 * _begin, the ECU runs its step k when it receives it and answers with its
 * actuator frames, and the plant ends the step when both have arrived
 * (host_sim/SCENARIO.md, "canfdi-sim on SocketCAN"; dbc/canfdi.dbc). The
 * `load fan` share of the scenario is never sent (unknown to the ECU).
 *
 * Actuator frames are applied only with 8 bytes and the right E2E CRC
 * (data ID = CAN ID, comm/canfdi_e2e.h), as a power stage that checks its
 * command frames would: a corrupted frame or one forged without the CRC
 * leaves the previous command in force (counted in diag.act_rejected).
 * The counter is not judged (a restarted ECU starts a new sequence). Every
 * frame is packed and unpacked only by host_sim's generated PLANT codec
 * (host_sim/gen/canfdi_sim_msg.h).
 *
 * Determinism: with the same scenario and the same received frames at the
 * same steps, the frames sent are bit-identical.
 * Cost: _begin is one scenario evaluation plus up to five packs and four
 * CRCs; _rx one unpack; _end one canfdi_sim_step (canfdi_sim.h).
 * Memory: sizeof(canfdi_sim_rig_t) ~ 200 bytes; the scenario and the plant
 * are the caller's and must outlive the rig. No heap.
 */
#ifndef CANFDI_SIM_RIG_H
#define CANFDI_SIM_RIG_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "canfdi_sim.h"
#include "canfdi_sim_frames.h"
#include "canfdi_sim_scenario.h"
#include "canfdi_sim_trace.h"

/* Two setpoint frames and the plant's frames. */
#define CANFDI_SIM_RIG_MAX_TX (2U + CANFDI_SIM_FRAMES_MAX_PER_STEP)
#define CANFDI_SIM_RIG_SETPOINT_PERIOD_STEPS 10U

/* What canfdi_sim_rig_rx did with a frame. */
#define CANFDI_SIM_RIG_RX_IGNORED 0   /* an id the plant does not consume */
#define CANFDI_SIM_RIG_RX_ACT_DCM 1   /* DcmActuator applied */
#define CANFDI_SIM_RIG_RX_ACT_THR 2   /* ThrActuator applied */
#define CANFDI_SIM_RIG_RX_INJECT 3    /* a fault added (see ev->spec) */
#define CANFDI_SIM_RIG_RX_CLEAR 4     /* fault(s) removed (ev->fault_id, ev->n_cleared) */
#define CANFDI_SIM_RIG_RX_SP_DCM 5    /* speed/load override (ev->changed) */
#define CANFDI_SIM_RIG_RX_SP_THR 6    /* angle override (ev->changed) */

/* Monotone counters. */
typedef struct {
  uint32_t frames_tx;        /* frames returned by _begin and _sim_step */
  uint32_t frames_rx;        /* frames given to _rx */
  uint32_t actuators;        /* actuator frames applied */
  uint32_t act_rejected;     /* actuator frames not applied: DLC or E2E CRC wrong */
  uint32_t injects;          /* faults added by SimFaultInject */
  uint32_t clears;           /* SimFaultClear frames obeyed */
  uint32_t overrides;        /* external setpoint frames obeyed */
  uint32_t rejected;         /* wrong DLC, unknown fault, bad mode/magnitude, fault table full */
  uint32_t ignored;          /* ids the plant does not consume */
} canfdi_sim_rig_diag_t;

/* Detail of one _rx call, for progress messages. */
typedef struct {
  canfdi_sim_fault_spec_t spec;  /* RX_INJECT: the fault added */
  uint8_t fault_id;              /* RX_CLEAR: the id asked for (0 = all) */
  size_t n_cleared;              /* RX_CLEAR: faults removed */
  bool changed;                  /* RX_SP_*: the override differs from the last one */
} canfdi_sim_rig_event_t;

typedef struct {
  canfdi_sim_scn_t *scn;           /* borrowed: setpoint profiles */
  canfdi_sim_t *sim;               /* borrowed: the plant */
  canfdi_sim_frames_t frames;      /* E2E state of the sensor frames */
  canfdi_e2e_tx_t sp_e2e[2];       /* E2E state of SetpointDcm, SetpointThr */
  canfdi_sim_in_t in;              /* actuator inputs in force (and the load of this step) */
  canfdi_sim_trace_sp_t sp;        /* setpoints and load of this step (after overrides) */
  double dcm_supply_V;             /* the plants' supplies over this step (scenario) */
  double thr_supply_V;
  bool ovr_dcm;                    /* an external SetpointDcm was received */
  int16_t ovr_speed_raw;           /* its raw SpDcmSpeed, resent as is */
  int16_t ovr_load_raw;            /* its raw SpDcmLoad */
  bool ovr_thr;                    /* an external SetpointThr was received */
  uint16_t ovr_angle_raw;          /* its raw SpThrAngle */
  bool got_act_dcm;                /* DcmActuator received since the last _begin */
  bool got_act_thr;                /* ThrActuator received since the last _begin */
  canfdi_sim_rig_diag_t diag;
} canfdi_sim_rig_t;

/* Binds the rig to a scenario and a plant set up from it
 * (canfdi_sim_scn_setup); sim_mode (CANFDI_SIM_MODE_*) goes into
 * SimPlantStatus. Actuators start as the firmware's reset state: bridge A,
 * disabled, 0 V. Returns -CANFDI_EINVAL for NULL pointers, else CANFDI_OK. */
int canfdi_sim_rig_init(canfdi_sim_rig_t *r, canfdi_sim_scn_t *scn, canfdi_sim_t *sim,
                        uint8_t sim_mode);

/* Starts step k = sim->step (see above): writes the frames to send, in bus
 * order, to out (CANFDI_SIM_RIG_MAX_TX entries) and returns how many.
 * Clears got_act_*. Cannot fail by contract. */
size_t canfdi_sim_rig_begin(canfdi_sim_rig_t *r, canfdi_sim_frame_t *out);

/* Applies one received frame at the current simulation time; returns a
 * CANFDI_SIM_RIG_RX_* code and fills ev (may be NULL), or -CANFDI_EINVAL
 * for a frame of a consumed id that cannot be obeyed (wrong DLC, unknown
 * fault id or mode, magnitude out of range), -CANFDI_ERANGE when the fault
 * table is full. A rejected frame changes nothing. */
int canfdi_sim_rig_rx(canfdi_sim_rig_t *r, const canfdi_sim_frame_t *f, canfdi_sim_rig_event_t *ev);

/* The SimStep frame of the current step (lockstep only). Cannot fail by
 * contract. */
void canfdi_sim_rig_sim_step(canfdi_sim_rig_t *r, canfdi_sim_frame_t *out);

/* Ends the step: applies the step's load and advances the plant by 1 ms.
 * Cannot fail by contract. */
void canfdi_sim_rig_end(canfdi_sim_rig_t *r);

#endif /* CANFDI_SIM_RIG_H */
