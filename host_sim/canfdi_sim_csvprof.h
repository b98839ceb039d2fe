/*
 * canfdi_sim_csvprof.h — a time profile of the vehicle's quantities read
 * from a CSV file (scenario directive `profile <file.csv>`,
 * host_sim/SCENARIO.md), linearly interpolated at every 1 ms step.
 *
 * File format (one header line, then one row per time point):
 *   # comment lines and blank lines are allowed anywhere
 *   t_s,speed_rad_s,angle_deg,load_Nm,dcm_supply_V,thr_supply_V
 *   0,0,5,0,46.5,12.2
 *   0.1,0.4,5,0.3,46.5,12.2
 * The first column is the time `t_s` in seconds; any non-empty subset of
 * the quantities follows, in any order, each at most once:
 *   speed_rad_s    motor speed setpoint           -400 .. 400 rad/s
 *   angle_deg      throttle angle setpoint           0 .. 90 deg
 *   load_Nm        external load torque on the motor -10 .. 10 N m
 *   dcm_supply_V   DC motor bridge supply            0 .. 80 V
 *   thr_supply_V   throttle bridge supply            0 .. 16 V
 * (the ranges of the scenario's profiles and `param`s, i.e. what the plant
 * and its sensors can represent). Fields are separated by commas, with
 * optional spaces or tabs around them; lines end in LF or CRLF and are at
 * most CANFDI_SIM_CSV_LINE_MAX characters of printable ASCII (the line end
 * not counted). Times are
 * rounded to whole microseconds; the first row is at 0 and every row is
 * later than the one before (a step is two rows 1 ms apart). Between rows
 * every quantity is interpolated linearly; after the last row it holds.
 *
 * Errors name the file and line, "<file>:<line>: <message>", and the first
 * one stops the check. _open reads and checks the whole file once; _eval
 * reads it again in blocks of CANFDI_SIM_CSV_BUF_ROWS rows as time moves
 * on (a backwards jump in time restarts from the top), each block with the
 * same checks. A file that no longer reads as it did when it was checked
 * (changed or removed during the run) sets a sticky error (`err`, with file
 * and line) and the values hold from then on: the caller checks `err`.
 *
 * Cost: _open is O(file size); _eval is O(1) amortised when time moves
 * forward (one fopen/fseek/fclose per block). Memory:
 * sizeof(canfdi_sim_csvprof_t) ~ 4.5 kB, caller-owned; the file is not
 * kept open between calls. No heap.
 */
#ifndef CANFDI_SIM_CSVPROF_H
#define CANFDI_SIM_CSVPROF_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#define CANFDI_SIM_CSV_SPEED 0U      /* speed_rad_s */
#define CANFDI_SIM_CSV_ANGLE 1U      /* angle_deg */
#define CANFDI_SIM_CSV_LOAD 2U       /* load_Nm */
#define CANFDI_SIM_CSV_DCM_SUPPLY 3U /* dcm_supply_V */
#define CANFDI_SIM_CSV_THR_SUPPLY 4U /* thr_supply_V */
#define CANFDI_SIM_CSV_N 5U

#define CANFDI_SIM_CSV_PATH_MAX 512U
#define CANFDI_SIM_CSV_LINE_MAX 256U
#define CANFDI_SIM_CSV_BUF_ROWS 64U
#define CANFDI_SIM_CSV_MAX_TIME_S 1e5

typedef struct {
  char path[CANFDI_SIM_CSV_PATH_MAX];
  bool has[CANFDI_SIM_CSV_N];      /* the quantities the file gives */
  uint8_t field[CANFDI_SIM_CSV_N]; /* their field index in a row (time is 0) */
  uint8_t n_fields;                /* fields per row, time included */
  uint32_t n_rows;                 /* data rows */
  int64_t t_last_us;               /* time of the last row */
  double first[CANFDI_SIM_CSV_N];  /* values of the first row (t = 0) */
  double min[CANFDI_SIM_CSV_N];    /* smallest and largest value of each */
  double max[CANFDI_SIM_CSV_N];    /* quantity in the file */
  long data_off;                   /* file offset just after the header */
  unsigned data_line;              /* line number of the header */
  /* read cursor of _eval */
  long next_off;                   /* where the next block starts */
  unsigned next_line;              /* line number before that point */
  uint32_t rows_read;              /* data rows read by the cursor so far */
  size_t buf_n;                    /* rows in the block */
  size_t seg;                      /* buf_t[seg] <= t < buf_t[seg + 1] */
  int64_t buf_t[CANFDI_SIM_CSV_BUF_ROWS];
  double buf_v[CANFDI_SIM_CSV_BUF_ROWS][CANFDI_SIM_CSV_N];
  char err[384];                   /* sticky error of _eval, "" while fine */
} canfdi_sim_csvprof_t;

/* Name of quantity q ("speed_rad_s", ...) and its range; NULL/0 if q is
 * out of range. */
const char *canfdi_sim_csvprof_name(unsigned q);
void canfdi_sim_csvprof_range(unsigned q, double *lo, double *hi);

/* Reads and checks the whole file at `path` (used as given, also in
 * messages; at most CANFDI_SIM_CSV_PATH_MAX - 1 characters). Returns
 * CANFDI_OK, or -CANFDI_EINVAL with "<path>:<line>: <message>" (or
 * "<path>: <message>" when no line is at fault) in msg. */
int canfdi_sim_csvprof_open(canfdi_sim_csvprof_t *p, const char *path, char *msg, size_t cap);

/* The quantities at t_us (interpolated; holding before 0 and after the
 * last row): out[q] for every q with p->has[q], the others are left as
 * they are. Cannot fail by contract; a read problem sets p->err. */
void canfdi_sim_csvprof_eval(canfdi_sim_csvprof_t *p, int64_t t_us, double *out);

#endif /* CANFDI_SIM_CSVPROF_H */
