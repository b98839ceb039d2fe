/*
 * canfdi_sim_trace.h — the CSV trace and the candump log of a simulation
 * run, written to stdio streams.
 *
 * CSV: one header line, then one row per (decimated) 1 ms step with the
 * time, setpoints, load, actuator commands, true plant states, the eight
 * measured sensor values and the active faults (catalogue names joined by
 * '|', empty if none). Columns are listed in CANFDI_SIM_TRACE_COLUMNS order
 * by canfdi_sim_trace_header(). Numbers use %.9g (time %.3f), so a trace is
 * byte-identical for identical runs of one build.
 *
 * candump log: the format of `candump -L`:
 *   (SSSSSSSSSS.UUUUUU) <channel> <ID>#<DATA>
 * with the time as the epoch plus the simulation time, printed from whole
 * microseconds (exact), 3 hex digits for the 11-bit ID, 2 per data byte.
 *
 * Cost: one fprintf per row/frame. Memory: none beyond stdio buffers.
 */
#ifndef CANFDI_SIM_TRACE_H
#define CANFDI_SIM_TRACE_H

#include <stdint.h>
#include <stdio.h>

#include "canfdi_sim.h"
#include "canfdi_sim_frames.h"

/* Setpoints of one row. */
typedef struct {
  double speed_rad_s;
  double angle_deg;
  double load_Nm;
} canfdi_sim_trace_sp_t;

/* Returns 0 or -CANFDI_EINVAL on a write error. */
int canfdi_sim_trace_header(FILE *out);
int canfdi_sim_trace_row(FILE *out, const canfdi_sim_t *sim, const canfdi_sim_trace_sp_t *sp,
                         const canfdi_sim_in_t *in);

/* One candump line; epoch_us is added to the simulation time. */
int canfdi_sim_trace_candump(FILE *out, const char *channel, int64_t epoch_us, int64_t t_us,
                             const canfdi_sim_frame_t *fr);

#endif /* CANFDI_SIM_TRACE_H */
