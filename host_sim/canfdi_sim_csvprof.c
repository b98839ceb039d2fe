/* canfdi_sim_csvprof.c — see canfdi_sim_csvprof.h and SCENARIO.md. */
#include "canfdi_sim_csvprof.h"

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/canfdi_common.h"

/* Fields a line may have before it is certainly wrong (time + every
 * quantity, and some room to count a few too many). */
#define MAX_FIELDS (CANFDI_SIM_CSV_N + 4U)
/* A line buffer: at most CANFDI_SIM_CSV_LINE_MAX characters, CR, LF, NUL. */
#define LINE_BUF (CANFDI_SIM_CSV_LINE_MAX + 3U)

static const char *const q_names[CANFDI_SIM_CSV_N] = {"speed_rad_s", "angle_deg", "load_Nm",
                                                      "dcm_supply_V", "thr_supply_V"};
static const double q_lo[CANFDI_SIM_CSV_N] = {-400.0, 0.0, -10.0, 0.0, 0.0};
static const double q_hi[CANFDI_SIM_CSV_N] = {400.0, 90.0, 10.0, 80.0, 16.0};

const char *canfdi_sim_csvprof_name(unsigned q)
{
  return (q < CANFDI_SIM_CSV_N) ? q_names[q] : NULL;
}

void canfdi_sim_csvprof_range(unsigned q, double *lo, double *hi)
{
  *lo = (q < CANFDI_SIM_CSV_N) ? q_lo[q] : 0.0;
  *hi = (q < CANFDI_SIM_CSV_N) ? q_hi[q] : 0.0;
}

/* One pass over the file: where messages go and which line was read last. */
typedef struct {
  FILE *f;
  const char *path;
  unsigned line;
  char *msg;
  size_t cap;
} reader_t;

static int fail(reader_t *r, bool with_line, const char *fmt, ...)
{
  char tmp[256];
  va_list ap;
  va_start(ap, fmt);
  (void)vsnprintf(tmp, sizeof tmp, fmt, ap);
  va_end(ap);
  if (with_line) {
    (void)snprintf(r->msg, r->cap, "%s:%u: %s", r->path, r->line, tmp);
  } else {
    (void)snprintf(r->msg, r->cap, "%s: %s", r->path, tmp);
  }
  return -CANFDI_EINVAL;
}

static bool is_space(char c)
{
  return (c == ' ') || (c == '\t') || (c == '\r') || (c == '\n');
}

/* The next line that is neither blank nor a comment, into buf (LINE_BUF
 * bytes: the longest line, CRLF and the NUL). 1: a line; 0: end of file; <0: error
 * (message written). */
static int next_line(reader_t *r, char *buf)
{
  int rc = 0;
  bool done = false;
  while (!done) {
    size_t len;
    size_t i;
    const char *p;
    if (fgets(buf, (int)LINE_BUF, r->f) == NULL) {
      if (ferror(r->f)) {
        rc = fail(r, false, "read error after line %u", r->line);
      }
      done = true;
      continue;
    }
    r->line++;
    len = strlen(buf);
    if ((len > 0U) && (buf[len - 1U] == '\n')) {
      len--;
    } else if (!feof(r->f)) {
      rc = fail(r, true, "line longer than %u characters", CANFDI_SIM_CSV_LINE_MAX);
      done = true;
      continue;
    } else {
      /* last line without a newline */
    }
    if ((len > 0U) && (buf[len - 1U] == '\r')) {
      len--;
    }
    if (len > CANFDI_SIM_CSV_LINE_MAX) {
      rc = fail(r, true, "line longer than %u characters", CANFDI_SIM_CSV_LINE_MAX);
      done = true;
      continue;
    }
    buf[len] = '\0';
    for (i = 0U; (rc == 0) && (i < len); i++) {
      const unsigned char c = (unsigned char)buf[i];
      if (((c < 0x20U) && (c != (unsigned char)'\t')) || (c > 0x7EU)) {
        rc = fail(r, true, "non-printable or non-ASCII character (byte 0x%02X)", (unsigned)c);
      }
    }
    if (rc != 0) {
      done = true;
      continue;
    }
    p = buf;
    while ((*p == ' ') || (*p == '\t')) {
      p++;
    }
    if ((*p != '\0') && (*p != '#')) {
      rc = 1;
      done = true;
    }
  }
  return rc;
}

/* Splits a line at commas, trimming blanks around each field. Returns the
 * number of fields (counted on beyond MAX_FIELDS; only the first
 * MAX_FIELDS are stored). */
static size_t split(char *line, char **field)
{
  size_t n = 0U;
  char *p = line;
  for (;;) {
    char *end;
    char *comma = strchr(p, ',');
    if (comma != NULL) {
      *comma = '\0';
    }
    while ((*p == ' ') || (*p == '\t')) {
      p++;
    }
    end = p + strlen(p);
    while ((end > p) && is_space(end[-1])) {
      end--;
    }
    *end = '\0';
    if (n < MAX_FIELDS) {
      field[n] = p;
    }
    n++;
    if (comma == NULL) {
      break;
    }
    p = comma + 1;
  }
  return n;
}

static int parse_header(canfdi_sim_csvprof_t *p, reader_t *r, char *line)
{
  char *field[MAX_FIELDS];
  const size_t n = split(line, field);
  size_t i;
  int rc = CANFDI_OK;
  if (strcmp(field[0], "t_s") != 0) {
    rc = fail(r, true, "header: the first column must be t_s (time in seconds), not '%s'", field[0]);
  } else if (n < 2U) {
    rc = fail(r, true, "header: no quantity after t_s (speed_rad_s, angle_deg, load_Nm, "
                       "dcm_supply_V, thr_supply_V)");
  }
  for (i = 1U; (rc == CANFDI_OK) && (i < n); i++) {
    unsigned q;
    unsigned k = CANFDI_SIM_CSV_N;
    if (i >= MAX_FIELDS) {
      rc = fail(r, true, "header: %zu columns, at most %u (t_s and each quantity once)", n,
                CANFDI_SIM_CSV_N + 1U);
      break;
    }
    for (q = 0U; q < CANFDI_SIM_CSV_N; q++) {
      if (strcmp(field[i], q_names[q]) == 0) {
        k = q;
      }
    }
    if (k == CANFDI_SIM_CSV_N) {
      rc = fail(r, true, "header: unknown column '%s' (speed_rad_s, angle_deg, load_Nm, "
                         "dcm_supply_V, thr_supply_V)", field[i]);
    } else if (p->has[k]) {
      rc = fail(r, true, "header: duplicate column '%s'", field[i]);
    } else {
      p->has[k] = true;
      p->field[k] = (uint8_t)i;
    }
  }
  if (rc == CANFDI_OK) {
    p->n_fields = (uint8_t)n;
  }
  return rc;
}

static bool num(const char *tok, double *out)
{
  char *end = NULL;
  double v;
  errno = 0;
  v = strtod(tok, &end);
  if ((end == tok) || (*end != '\0') || (errno != 0) || !isfinite(v)) {
    return false;
  }
  *out = v;
  return true;
}

/* One data row: field count, numbers, ranges; time after prev_t_us (or at
 * 0 for the first row, prev_t_us < 0). */
static int parse_row(const canfdi_sim_csvprof_t *p, reader_t *r, char *line, int64_t prev_t_us,
                     int64_t *t_us, double *v)
{
  char *field[MAX_FIELDS];
  const size_t n = split(line, field);
  double t = 0.0;
  unsigned q;
  int rc = CANFDI_OK;
  if (n != (size_t)p->n_fields) {
    rc = fail(r, true, "%zu fields, the header has %u", n, (unsigned)p->n_fields);
  } else if (!num(field[0], &t)) {
    rc = fail(r, true, "t_s '%s' is not a number", field[0]);
  } else if ((t < 0.0) || (t > CANFDI_SIM_CSV_MAX_TIME_S)) {
    rc = fail(r, true, "t_s %g out of range [0, %g]", t, CANFDI_SIM_CSV_MAX_TIME_S);
  } else {
    *t_us = (int64_t)llround(t * 1e6);
    if ((prev_t_us < 0) && (*t_us != 0)) {
      rc = fail(r, true, "the first row must be at t_s 0, not %g", t);
    } else if ((prev_t_us >= 0) && (*t_us <= prev_t_us)) {
      rc = fail(r, true, "t_s %g is not after the previous row's %g (times must increase)", t,
                (double)prev_t_us * 1e-6);
    } else {
      /* in order */
    }
  }
  for (q = 0U; (rc == CANFDI_OK) && (q < CANFDI_SIM_CSV_N); q++) {
    if (p->has[q]) {
      const char *tok = field[p->field[q]];
      if (!num(tok, &v[q])) {
        rc = fail(r, true, "%s '%s' is not a number", q_names[q], tok);
      } else if ((v[q] < q_lo[q]) || (v[q] > q_hi[q])) {
        rc = fail(r, true, "%s %g out of range [%g, %g]", q_names[q], v[q], q_lo[q], q_hi[q]);
      } else {
        /* fine */
      }
    }
  }
  return rc;
}

int canfdi_sim_csvprof_open(canfdi_sim_csvprof_t *p, const char *path, char *msg, size_t cap)
{
  reader_t r;
  char buf[LINE_BUF];
  int rc = CANFDI_OK;
  int got;
  unsigned q;

  memset(p, 0, sizeof *p);
  r.f = NULL;
  r.path = path;
  r.line = 0U;
  r.msg = msg;
  r.cap = cap;
  if (strlen(path) >= sizeof p->path) {
    return fail(&r, false, "path longer than %u characters", CANFDI_SIM_CSV_PATH_MAX - 1U);
  }
  (void)memcpy(p->path, path, strlen(path) + 1U);
  r.path = p->path;
  r.f = fopen(path, "rb");
  if (r.f == NULL) {
    return fail(&r, false, "cannot open: %s", strerror(errno));
  }
  got = next_line(&r, buf);
  if (got == 0) {
    rc = fail(&r, false, "no header line (t_s and at least one of speed_rad_s, angle_deg, "
                         "load_Nm, dcm_supply_V, thr_supply_V)");
  } else if (got < 0) {
    rc = got;
  } else {
    rc = parse_header(p, &r, buf);
  }
  if (rc == CANFDI_OK) {
    p->data_off = ftell(r.f);
    p->data_line = r.line;
    if (p->data_off < 0L) {
      rc = fail(&r, false, "cannot tell the file position: %s", strerror(errno));
    }
  }
  while (rc == CANFDI_OK) {
    int64_t t_us = 0;
    double v[CANFDI_SIM_CSV_N] = {0.0, 0.0, 0.0, 0.0, 0.0};
    got = next_line(&r, buf);
    if (got <= 0) {
      rc = got;
      break;
    }
    rc = parse_row(p, &r, buf, (p->n_rows == 0U) ? -1 : p->t_last_us, &t_us, v);
    if (rc == CANFDI_OK) {
      for (q = 0U; q < CANFDI_SIM_CSV_N; q++) {
        if (p->n_rows == 0U) {
          p->first[q] = v[q];
          p->min[q] = v[q];
          p->max[q] = v[q];
        } else {
          p->min[q] = (v[q] < p->min[q]) ? v[q] : p->min[q];
          p->max[q] = (v[q] > p->max[q]) ? v[q] : p->max[q];
        }
      }
      p->t_last_us = t_us;
      p->n_rows++;
    }
  }
  if ((rc == CANFDI_OK) && (p->n_rows == 0U)) {
    rc = fail(&r, false, "no data rows after the header");
  }
  (void)fclose(r.f);
  p->buf_n = 0U;
  p->seg = 0U;
  p->err[0] = '\0';
  return rc;
}

/* Reads the next block of rows after the cursor. The row the current
 * segment starts at is kept as the block's first row, so that the segment
 * that crosses into the new block interpolates. */
static void refill(canfdi_sim_csvprof_t *p)
{
  reader_t r;
  char buf[LINE_BUF];
  size_t n = 0U;
  int rc = CANFDI_OK;

  if (p->buf_n > 0U) {
    size_t q;
    p->buf_t[0] = p->buf_t[p->seg];
    for (q = 0U; q < CANFDI_SIM_CSV_N; q++) {
      p->buf_v[0][q] = p->buf_v[p->seg][q];
    }
    n = 1U;
  }
  r.path = p->path;
  r.line = p->next_line;
  r.msg = p->err;
  r.cap = sizeof p->err;
  r.f = fopen(p->path, "rb");
  if (r.f == NULL) {
    (void)fail(&r, false, "cannot open again during the run: %s", strerror(errno));
    return;
  }
  if (fseek(r.f, p->next_off, SEEK_SET) != 0) {
    rc = fail(&r, false, "cannot seek during the run: %s", strerror(errno));
  }
  while ((rc == CANFDI_OK) && (n < CANFDI_SIM_CSV_BUF_ROWS) && (p->rows_read < p->n_rows)) {
    const int got = next_line(&r, buf);
    if (got < 0) {
      rc = got;
    } else if (got == 0) {
      rc = fail(&r, false, "ends after %u of its %u rows: changed since it was checked",
                (unsigned)p->rows_read, (unsigned)p->n_rows);
    } else {
      rc = parse_row(p, &r, buf, (n == 0U) ? -1 : p->buf_t[n - 1U], &p->buf_t[n], p->buf_v[n]);
      if (rc == CANFDI_OK) {
        n++;
        p->rows_read++;
      }
    }
  }
  if (rc == CANFDI_OK) {
    p->next_off = ftell(r.f);
    p->next_line = r.line;
    if (p->next_off < 0L) {
      (void)fail(&r, false, "cannot tell the file position: %s", strerror(errno));
    }
  }
  (void)fclose(r.f);
  p->buf_n = n;
  p->seg = 0U;
}

static void restart(canfdi_sim_csvprof_t *p)
{
  p->next_off = p->data_off;
  p->next_line = p->data_line;
  p->rows_read = 0U;
  p->buf_n = 0U;
  p->seg = 0U;
  refill(p);
}

void canfdi_sim_csvprof_eval(canfdi_sim_csvprof_t *p, int64_t t_us, double *out)
{
  unsigned q;
  CANFDI_ASSERT((p != NULL) && (out != NULL));
  if (p->err[0] == '\0') {
    if (p->buf_n == 0U) {
      restart(p);
    } else if (t_us < p->buf_t[p->seg]) {
      /* back in time: within the block, or from the top of the file */
      if ((t_us < p->buf_t[0]) && (p->rows_read > (uint32_t)p->buf_n)) {
        restart(p);
      } else {
        p->seg = 0U;
      }
    } else {
      /* forward */
    }
    while (p->err[0] == '\0') {
      while (((p->seg + 1U) < p->buf_n) && (t_us >= p->buf_t[p->seg + 1U])) {
        p->seg++;
      }
      if (((p->seg + 1U) < p->buf_n) || (p->rows_read >= p->n_rows)) {
        break;
      }
      refill(p);
    }
  }
  for (q = 0U; q < CANFDI_SIM_CSV_N; q++) {
    if (!p->has[q]) {
      continue;
    }
    if (p->buf_n == 0U) {
      out[q] = p->first[q]; /* nothing could be read: the checked start */
    } else if (((p->seg + 1U) < p->buf_n) && (t_us > p->buf_t[p->seg])) {
      const int64_t t0 = p->buf_t[p->seg];
      const int64_t t1 = p->buf_t[p->seg + 1U];
      const double a = (double)(t_us - t0) / (double)(t1 - t0);
      out[q] = p->buf_v[p->seg][q] + (a * (p->buf_v[p->seg + 1U][q] - p->buf_v[p->seg][q]));
    } else {
      out[q] = p->buf_v[p->seg][q];
    }
  }
}
