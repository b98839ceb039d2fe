/*
 * canfdi_dtc.c — event/trouble-code memory; the manual is the header.
 */
#include "diag/canfdi_dtc.h"

#include "core/canfdi_count.h"

CANFDI_STATIC_ASSERT((CANFDI_CFG_DTC_MAX_DTCS >= 1) && (CANFDI_CFG_DTC_MAX_DTCS <= 254),
                     dtc_max_dtcs_in_range);
CANFDI_STATIC_ASSERT((CANFDI_CFG_DTC_MAX_ENTRIES >= 1) && (CANFDI_CFG_DTC_MAX_ENTRIES <= 254),
                     dtc_max_entries_in_range);
CANFDI_STATIC_ASSERT(CANFDI_DTC_COUNT <= CANFDI_CFG_DTC_MAX_DTCS, dtc_product_table_fits);
/* The header of the image stores r and e in one byte each. */
CANFDI_STATIC_ASSERT(CANFDI_CFG_DTC_MAX_DTCS <= 255, dtc_records_fit_a_byte);

/* The jumps to 0 make a report against the current direction qualify at
 * once too (without them a PREPASSED after a failure would need two). */
const canfdi_debounce_cfg_t canfdi_dtc_deb_direct = {
    .failed_threshold = 1,
    .passed_threshold = -1,
    .prefailed_step = 1U,
    .prepassed_step = 1U,
    .jump_up_value = 0,
    .jump_down_value = 0,
    .jump_up = true,
    .jump_down = true,
};

const canfdi_debounce_cfg_t canfdi_dtc_deb_frame = {
    .failed_threshold = 6,
    .passed_threshold = -6,
    .prefailed_step = 2U,
    .prepassed_step = 1U,
    .jump_up_value = 0,
    .jump_down_value = 0,
    .jump_up = false,
    .jump_down = false,
};

/* Rows per severity class of dbc/dtcs.csv (see the header). */
#define ROW_IMMEDIATE(code, grp, deb) \
  {(code), (deb), 1U, (grp), 1U, 3U, 40U, true}
#define ROW_AT_HALT(code, grp, deb) \
  {(code), (deb), 2U, (grp), 1U, 3U, 40U, true}
#define ROW_MAINTENANCE(code, grp, deb) \
  {(code), (deb), 3U, (grp), 1U, 3U, 40U, false}

#define DIRECT (&canfdi_dtc_deb_direct)
#define FRAME (&canfdi_dtc_deb_frame)
#define THR CANFDI_COMPONENT_THROTTLE
#define DCM CANFDI_COMPONENT_DC_MOTOR
#define COM CANFDI_COMPONENT_COMM

/* In dbc/dtcs.csv order (= canfdi_catalogue_dtc[]). */
const canfdi_dtc_def_t canfdi_dtc_defaults[CANFDI_DTC_COUNT] = {
    ROW_AT_HALT(CANFDI_DTC_P0121, THR, DIRECT),
    ROW_AT_HALT(CANFDI_DTC_P0122, THR, DIRECT),
    ROW_AT_HALT(CANFDI_DTC_P0123, THR, DIRECT),
    ROW_AT_HALT(CANFDI_DTC_P0221, THR, DIRECT),
    ROW_AT_HALT(CANFDI_DTC_P0222, THR, DIRECT),
    ROW_AT_HALT(CANFDI_DTC_P0223, THR, DIRECT),
    ROW_MAINTENANCE(CANFDI_DTC_P0638, THR, DIRECT),
    ROW_IMMEDIATE(CANFDI_DTC_P2100, THR, DIRECT),
    ROW_MAINTENANCE(CANFDI_DTC_P2101, THR, DIRECT),
    ROW_IMMEDIATE(CANFDI_DTC_P2119, THR, DIRECT),
    ROW_AT_HALT(CANFDI_DTC_P2135, THR, DIRECT),
    ROW_MAINTENANCE(CANFDI_DTC_P1A10, DCM, DIRECT),
    ROW_MAINTENANCE(CANFDI_DTC_P1A11, DCM, DIRECT),
    ROW_MAINTENANCE(CANFDI_DTC_P1A12, DCM, DIRECT),
    ROW_AT_HALT(CANFDI_DTC_P1A20, DCM, DIRECT),
    ROW_AT_HALT(CANFDI_DTC_P1A21, DCM, DIRECT),
    ROW_AT_HALT(CANFDI_DTC_P1A22, DCM, DIRECT),
    ROW_AT_HALT(CANFDI_DTC_P1A30, DCM, DIRECT),
    ROW_IMMEDIATE(CANFDI_DTC_P1A31, DCM, DIRECT),
    ROW_MAINTENANCE(CANFDI_DTC_P1B10, THR, DIRECT),
    ROW_IMMEDIATE(CANFDI_DTC_U1A00, COM, DIRECT),
    ROW_IMMEDIATE(CANFDI_DTC_U1A01, COM, DIRECT),
    ROW_IMMEDIATE(CANFDI_DTC_U1A10, COM, FRAME),
    ROW_IMMEDIATE(CANFDI_DTC_U1A11, COM, FRAME),
    ROW_IMMEDIATE(CANFDI_DTC_U1A20, COM, FRAME),
    ROW_IMMEDIATE(CANFDI_DTC_U1A21, COM, FRAME),
    ROW_IMMEDIATE(CANFDI_DTC_U1A30, COM, FRAME),
    ROW_IMMEDIATE(CANFDI_DTC_U1A31, COM, FRAME),
    ROW_IMMEDIATE(CANFDI_DTC_U1A40, COM, FRAME),
    ROW_IMMEDIATE(CANFDI_DTC_U1A41, COM, FRAME),
    /* the setpoints (no catalogue fault): a timeout as U1A00, a rejected
     * frame debounced like the sensor frames' */
    ROW_IMMEDIATE(CANFDI_DTC_U1A50, COM, DIRECT),
    ROW_IMMEDIATE(CANFDI_DTC_U1A51, COM, FRAME),
};

#undef ROW_IMMEDIATE
#undef ROW_AT_HALT
#undef ROW_MAINTENANCE
#undef DIRECT
#undef FRAME
#undef THR
#undef DCM
#undef COM

/* ------------------------------------------------------------ helpers */

static CANFDI_ALWAYS_INLINE bool bound(const canfdi_dtc_t *m)
{
  return (m != NULL) && (m->table != NULL);
}

static bool def_ok(const canfdi_dtc_def_t *d)
{
  return (d->dtc >= 1U) && (d->dtc <= 0xFFFFFEU) &&
         (canfdi_debounce_cfg_check(d->deb) == CANFDI_OK) && (d->priority >= 1U) &&
         (d->confirm_cycles >= 1U) && (d->heal_cycles >= 1U) &&
         ((d->aging_cycles == 0U) || (d->aging_cycles >= d->heal_cycles));
}

static void free_entry(canfdi_dtc_t *m, uint8_t e)
{
  canfdi_dtc_entry_t *en = &m->entry[e];
  if (en->dtc_index != CANFDI_DTC_NONE) {
    m->dtc[en->dtc_index].entry = CANFDI_DTC_NONE;
  }
  en->dtc_index = CANFDI_DTC_NONE;
  en->occurrence = 0U;
  en->order = 0U;
  en->ff_valid = false;
  en->ff.time_ms = 0U;
  en->ff.omega_q16 = 0;
  en->ff.ia_q16 = 0;
  en->ff.ua_q16 = 0;
  en->ff.thr_angle_q16 = 0;
  en->ff.supply_q16 = 0;
  en->ff.deg_dcm = 0U;
  en->ff.deg_thr = 0U;
}

/* ClearDiagnosticInformation for one DTC (also the init state). */
static void clear_one(canfdi_dtc_t *m, uint8_t i)
{
  canfdi_dtc_state_t *st = &m->dtc[i];
  if (st->entry != CANFDI_DTC_NONE) {
    free_entry(m, st->entry);
  }
  st->status = (uint8_t)CANFDI_DTC_STATUS_CLEARED;
  st->failed_cycles = 0U;
  st->healthy_cycles = 0U;
  st->entry = CANFDI_DTC_NONE;
  canfdi_debounce_reset(&st->deb);
}

static void clear_state(canfdi_dtc_t *m)
{
  for (uint8_t e = 0U; e < (uint8_t)CANFDI_CFG_DTC_MAX_ENTRIES; e++) {
    m->entry[e].dtc_index = CANFDI_DTC_NONE;
    free_entry(m, e);
  }
  for (uint8_t i = 0U; i < m->n_dtcs; i++) {
    m->dtc[i].entry = CANFDI_DTC_NONE;
    clear_one(m, i);
  }
  m->next_order = 0U;
}

/* Is entry a a better displacement victim than entry b (both in use)? */
static bool worse_entry(const canfdi_dtc_t *m, uint8_t a, uint8_t b)
{
  const uint8_t ia = m->entry[a].dtc_index;
  const uint8_t ib = m->entry[b].dtc_index;
  const uint8_t pa = m->table[ia].priority;
  const uint8_t pb = m->table[ib].priority;
  const bool act_a = (m->dtc[ia].status & CANFDI_DTC_ST_TF) != 0U;
  const bool act_b = (m->dtc[ib].status & CANFDI_DTC_ST_TF) != 0U;
  bool out;
  if (pa != pb) {
    out = pa > pb;
  } else if (act_a != act_b) {
    out = !act_a;
  } else {
    out = m->entry[a].order < m->entry[b].order;
  }
  return out;
}

/* An entry for DTC i: a free one, else a displaced one, else NONE. */
static uint8_t alloc_entry(canfdi_dtc_t *m, uint8_t i)
{
  uint8_t got = CANFDI_DTC_NONE;
  for (uint8_t e = 0U; (e < (uint8_t)CANFDI_CFG_DTC_MAX_ENTRIES) && (got == CANFDI_DTC_NONE); e++) {
    if (m->entry[e].dtc_index == CANFDI_DTC_NONE) {
      got = e;
    }
  }
  if (got == CANFDI_DTC_NONE) {
    const uint8_t p = m->table[i].priority;
    uint8_t victim = CANFDI_DTC_NONE;
    canfdi_count_inc16(&m->diag.overflows);
    for (uint8_t e = 0U; e < (uint8_t)CANFDI_CFG_DTC_MAX_ENTRIES; e++) {
      const uint8_t owner = m->entry[e].dtc_index;
      const uint8_t po = m->table[owner].priority;
      const bool passive = (m->dtc[owner].status & CANFDI_DTC_ST_TF) == 0U;
      if ((po > p) || ((po == p) && passive)) {
        if ((victim == CANFDI_DTC_NONE) || worse_entry(m, e, victim)) {
          victim = e;
        }
      }
    }
    if (victim != CANFDI_DTC_NONE) {
      canfdi_dtc_state_t *vs = &m->dtc[m->entry[victim].dtc_index];
      vs->status = (uint8_t)(vs->status & ~(CANFDI_DTC_ST_CDTC | CANFDI_DTC_ST_WIR));
      free_entry(m, victim);
      canfdi_count_inc16(&m->diag.displacements);
      got = victim;
    } else {
      canfdi_count_inc16(&m->diag.not_stored);
    }
  }
  if (got != CANFDI_DTC_NONE) {
    canfdi_dtc_entry_t *en = &m->entry[got];
    en->dtc_index = i;
    en->occurrence = 1U;
    /* Saturates: 2^32 storages never happen; ties only affect the order. */
    en->order = m->next_order;
    if (m->next_order < UINT32_MAX) {
      m->next_order++;
    }
    m->dtc[i].entry = got;
  }
  return got;
}

static void on_failed(canfdi_dtc_t *m, uint8_t i, const canfdi_dtc_ff_t *ff)
{
  canfdi_dtc_state_t *st = &m->dtc[i];
  const canfdi_dtc_def_t *def = &m->table[i];
  const uint8_t s0 = st->status;
  const bool was_failed = (s0 & CANFDI_DTC_ST_TF) != 0U;
  const bool first_in_cycle = (s0 & CANFDI_DTC_ST_TFTOC) == 0U;
  uint8_t s = s0;

  s = (uint8_t)(s | CANFDI_DTC_ST_TF | CANFDI_DTC_ST_TFTOC | CANFDI_DTC_ST_PDTC |
                CANFDI_DTC_ST_TFSLC);
  s = (uint8_t)(s & ~(CANFDI_DTC_ST_TNCSLC | CANFDI_DTC_ST_TNCTOC));
  if (first_in_cycle) {
    canfdi_count_inc8(&st->failed_cycles);
  }
  if (st->healthy_cycles != 0U) {
    st->healthy_cycles = 0U;
    m->changes++;
  }
  if (st->entry == CANFDI_DTC_NONE) {
    /* Storage is attempted once per failure transition or cycle, so a
     * failure that persists costs nothing more in the 1 ms path. */
    if (!was_failed || first_in_cycle) {
      const uint8_t e = alloc_entry(m, i);
      if (e != CANFDI_DTC_NONE) {
        canfdi_dtc_entry_t *en = &m->entry[e];
        if (ff != NULL) {
          en->ff = *ff;
          en->ff_valid = true;
        }
        m->changes++;
      }
    }
  } else if (!was_failed) {
    canfdi_count_inc8(&m->entry[st->entry].occurrence);
    m->changes++;
  } else {
    /* still failed: the same occurrence */
  }
  if ((st->entry != CANFDI_DTC_NONE) && (st->failed_cycles >= def->confirm_cycles)) {
    s = (uint8_t)(s | CANFDI_DTC_ST_CDTC);
  }
  if (((s & CANFDI_DTC_ST_CDTC) != 0U) && def->warning_indicator) {
    s = (uint8_t)(s | CANFDI_DTC_ST_WIR);
  }
  /* A first failure in the cycle always sets TFTOC, so s != s0 covers
   * the failed-cycle counter as well. */
  if (s != s0) {
    st->status = s;
    m->changes++;
  }
}

static void on_passed(canfdi_dtc_t *m, uint8_t i)
{
  canfdi_dtc_state_t *st = &m->dtc[i];
  const uint8_t s =
      (uint8_t)(st->status & ~(CANFDI_DTC_ST_TF | CANFDI_DTC_ST_TNCSLC | CANFDI_DTC_ST_TNCTOC));
  if (s != st->status) {
    st->status = s;
    m->changes++;
  }
}

static void end_cycle(canfdi_dtc_t *m)
{
  for (uint8_t i = 0U; i < m->n_dtcs; i++) {
    canfdi_dtc_state_t *st = &m->dtc[i];
    const canfdi_dtc_def_t *def = &m->table[i];
    const uint8_t s0 = st->status;
    uint8_t s = s0;
    if ((s & (CANFDI_DTC_ST_TNCTOC | CANFDI_DTC_ST_TFTOC)) == 0U) {
      s = (uint8_t)(s & ~CANFDI_DTC_ST_PDTC);
      if (st->failed_cycles != 0U) {
        st->failed_cycles = 0U;
        m->changes++;
      }
      /* Healing and aging act on stored DTCs only (WIR implies CDTC
       * implies an entry); counting for the others would only churn the
       * NVM image. */
      if (st->entry != CANFDI_DTC_NONE) {
        canfdi_count_inc8(&st->healthy_cycles);
        m->changes++;
        if (st->healthy_cycles >= def->heal_cycles) {
          s = (uint8_t)(s & ~CANFDI_DTC_ST_WIR);
        }
        if ((def->aging_cycles != 0U) && (st->healthy_cycles >= def->aging_cycles)) {
          s = (uint8_t)(s & ~(CANFDI_DTC_ST_CDTC | CANFDI_DTC_ST_WIR));
          free_entry(m, st->entry);
          st->healthy_cycles = 0U;
          canfdi_count_inc16(&m->diag.aged);
        }
      }
      if (s != s0) {
        st->status = s;
        m->changes++;
      }
    }
  }
  m->cycle_active = false;
}

/* ------------------------------------------------------------ API */

int32_t canfdi_dtc_init(canfdi_dtc_t *m, const canfdi_dtc_def_t *table, uint8_t n)
{
  int32_t out = -CANFDI_EINVAL;
  if (m != NULL) {
    bool ok = (table != NULL) && (n >= 1U) && (n <= (uint8_t)CANFDI_CFG_DTC_MAX_DTCS);
    for (uint8_t i = 0U; ok && (i < n); i++) {
      ok = def_ok(&table[i]);
      for (uint8_t j = 0U; ok && (j < i); j++) {
        ok = table[j].dtc != table[i].dtc;
      }
    }
    m->table = NULL;
    m->n_dtcs = 0U;
    m->cycle_active = false;
    m->next_order = 0U;
    m->changes = 0U;
    m->diag.overflows = 0U;
    m->diag.displacements = 0U;
    m->diag.not_stored = 0U;
    m->diag.aged = 0U;
    m->diag.clears = 0U;
    m->diag.rejected_reports = 0U;
    m->diag.image_rejected = 0U;
    m->diag.image_dropped = 0U;
    if (ok) {
      for (uint8_t i = 0U; i < n; i++) {
        /* cannot fail: def_ok checked the class */
        (void)canfdi_debounce_init(&m->dtc[i].deb, table[i].deb);
      }
      m->table = table;
      m->n_dtcs = n;
      clear_state(m);
      out = CANFDI_OK;
    }
  }
  return out;
}

int32_t canfdi_dtc_cycle_start(canfdi_dtc_t *m)
{
  int32_t out = -CANFDI_EINVAL;
  if (bound(m)) {
    if (m->cycle_active) {
      end_cycle(m);
    }
    for (uint8_t i = 0U; i < m->n_dtcs; i++) {
      canfdi_dtc_state_t *st = &m->dtc[i];
      const uint8_t s = (uint8_t)((st->status & ~CANFDI_DTC_ST_TFTOC) | CANFDI_DTC_ST_TNCTOC);
      if (s != st->status) {
        st->status = s;
        m->changes++;
      }
      canfdi_debounce_start_cycle(&st->deb);
    }
    m->cycle_active = true;
    out = CANFDI_OK;
  }
  return out;
}

int32_t canfdi_dtc_cycle_end(canfdi_dtc_t *m)
{
  int32_t out = -CANFDI_EINVAL;
  if (bound(m) && m->cycle_active) {
    end_cycle(m);
    out = CANFDI_OK;
  }
  return out;
}

/*
 * First a pass (PASSED or PREPASSED) that changes nothing
 * (canfdi_dtc_pass_is_noop, canfdi_dtc.h): the debouncer sits on
 * its pass threshold with the pass qualified this cycle, and the status
 * already shows a passed test. The debouncer would keep its counter there
 * (a PREPASSED step only moves it down, and it is clamped at the threshold)
 * and its flags as they are, and on_passed would clear bits that are
 * clear: the report is answered without them. Most reports of every step
 * are this one (a healthy monitor passes again).
 */
int32_t canfdi_dtc_report(canfdi_dtc_t *m, uint8_t index, canfdi_deb_report_t report,
                          const canfdi_dtc_ff_t *ff)
{
  int32_t out = -CANFDI_EINVAL;
  if (bound(m)) {
    if (canfdi_dtc_pass_is_noop(m, index, report)) {
      out = (int32_t)m->dtc[index].status;
    } else if (m->cycle_active && (index < m->n_dtcs) &&
               (canfdi_debounce_step(&m->dtc[index].deb, report) >= 0)) {
      const canfdi_debounce_t *d = &m->dtc[index].deb;
      /* The debouncer qualifies exactly when its counter sits on a
       * threshold after the step (see canfdi_debounce.h). */
      if (d->counter >= d->cfg->failed_threshold) {
        on_failed(m, index, ff);
      } else if (d->counter <= d->cfg->passed_threshold) {
        on_passed(m, index);
      } else {
        /* not qualified by this report */
      }
      out = (int32_t)m->dtc[index].status;
    } else {
      canfdi_count_inc16(&m->diag.rejected_reports);
    }
  }
  return out;
}

int32_t canfdi_dtc_clear(canfdi_dtc_t *m, uint32_t group_of_dtc)
{
  int32_t out = -CANFDI_EINVAL;
  if (bound(m)) {
    if (group_of_dtc == CANFDI_DTC_GROUP_ALL) {
      clear_state(m);
      out = CANFDI_OK;
    } else {
      const int32_t i = canfdi_dtc_find(m, group_of_dtc);
      if (i >= 0) {
        clear_one(m, (uint8_t)i);
        out = CANFDI_OK;
      }
    }
    if (out == CANFDI_OK) {
      canfdi_count_inc16(&m->diag.clears);
      m->changes++;
    }
  }
  return out;
}

int32_t canfdi_dtc_clear_group(canfdi_dtc_t *m, uint8_t group)
{
  int32_t out = -CANFDI_EINVAL;
  if (bound(m)) {
    out = 0;
    for (uint8_t i = 0U; i < m->n_dtcs; i++) {
      if (m->table[i].group == group) {
        clear_one(m, i);
        out++;
      }
    }
    if (out > 0) {
      canfdi_count_inc16(&m->diag.clears);
      m->changes++;
    }
  }
  return out;
}

int32_t canfdi_dtc_find(const canfdi_dtc_t *m, uint32_t dtc)
{
  int32_t out = -CANFDI_EINVAL;
  if (bound(m)) {
    for (uint8_t i = 0U; (i < m->n_dtcs) && (out < 0); i++) {
      if (m->table[i].dtc == dtc) {
        out = (int32_t)i;
      }
    }
  }
  return out;
}

int32_t canfdi_dtc_status(const canfdi_dtc_t *m, uint8_t index)
{
  int32_t out = -CANFDI_EINVAL;
  if (bound(m) && (index < m->n_dtcs)) {
    out = (int32_t)m->dtc[index].status;
  }
  return out;
}

uint8_t canfdi_dtc_occurrence(const canfdi_dtc_t *m, uint8_t index)
{
  uint8_t out = 0U;
  if (bound(m) && (index < m->n_dtcs) && (m->dtc[index].entry != CANFDI_DTC_NONE)) {
    out = m->entry[m->dtc[index].entry].occurrence;
  }
  return out;
}

int8_t canfdi_dtc_fdc(const canfdi_dtc_t *m, uint8_t index)
{
  int8_t out = 0;
  if (bound(m) && (index < m->n_dtcs)) {
    out = canfdi_debounce_fdc(&m->dtc[index].deb);
  }
  return out;
}

uint16_t canfdi_dtc_count_by_mask(const canfdi_dtc_t *m, uint8_t mask)
{
  uint32_t n = 0U;
  if (bound(m)) {
    const uint8_t eff = (uint8_t)(mask & CANFDI_DTC_STATUS_AVAILABILITY_MASK);
    for (uint8_t i = 0U; i < m->n_dtcs; i++) {
      n += ((m->dtc[i].status & eff) != 0U) ? 1U : 0U; /* no branch */
    }
  }
  return (uint16_t)n; /* n <= n_dtcs */
}

int32_t canfdi_dtc_next_by_mask(const canfdi_dtc_t *m, uint8_t mask, uint16_t *cursor,
                                uint32_t *dtc, uint8_t *status)
{
  int32_t out = -CANFDI_EINVAL;
  if (bound(m) && (cursor != NULL) && (dtc != NULL) && (status != NULL)) {
    const uint8_t eff = (uint8_t)(mask & CANFDI_DTC_STATUS_AVAILABILITY_MASK);
    uint16_t c = *cursor;
    out = 0;
    while ((out == 0) && (c < m->n_dtcs)) {
      const uint8_t s = m->dtc[c].status;
      if ((s & eff) != 0U) {
        *dtc = m->table[c].dtc;
        *status = s;
        out = 1;
      }
      c++;
    }
    *cursor = c;
  }
  return out;
}

int32_t canfdi_dtc_read_record(const canfdi_dtc_t *m, uint32_t dtc, canfdi_dtc_record_t *out_rec)
{
  int32_t out = -CANFDI_EINVAL;
  const int32_t i = canfdi_dtc_find(m, dtc);
  if ((i >= 0) && (out_rec != NULL)) {
    const canfdi_dtc_state_t *st = &m->dtc[i];
    out_rec->dtc = dtc;
    out_rec->status = st->status;
    out_rec->occurrence = 0U;
    out_rec->ff_valid = false;
    out_rec->ff.time_ms = 0U;
    out_rec->ff.omega_q16 = 0;
    out_rec->ff.ia_q16 = 0;
    out_rec->ff.ua_q16 = 0;
    out_rec->ff.thr_angle_q16 = 0;
    out_rec->ff.supply_q16 = 0;
    out_rec->ff.deg_dcm = 0U;
    out_rec->ff.deg_thr = 0U;
    out = -CANFDI_ENODATA;
    if (st->entry != CANFDI_DTC_NONE) {
      const canfdi_dtc_entry_t *en = &m->entry[st->entry];
      out_rec->occurrence = en->occurrence;
      out_rec->ff_valid = en->ff_valid;
      if (en->ff_valid) {
        out_rec->ff = en->ff;
      }
      out = CANFDI_OK;
    }
  }
  return out;
}

/* ------------------------------------------------------------ image */

static uint8_t *put_u24(uint8_t *p, uint32_t v)
{
  p[0] = (uint8_t)((v >> 16) & 0xFFU);
  p[1] = (uint8_t)((v >> 8) & 0xFFU);
  p[2] = (uint8_t)(v & 0xFFU);
  return p + 3;
}

static uint8_t *put_u32(uint8_t *p, uint32_t v)
{
  p[0] = (uint8_t)(v >> 24);
  return put_u24(p + 1, v);
}

/* Two's complement bit pattern of a signed value, without
 * implementation-defined conversions. */
static uint32_t s32_bits(int32_t v)
{
  return (v >= 0) ? (uint32_t)v : (uint32_t)(~(uint32_t)(-(v + 1)));
}

static int32_t bits_s32(uint32_t b)
{
  return (b <= (uint32_t)INT32_MAX) ? (int32_t)b : (-(int32_t)(~b)) - 1;
}

static uint32_t get_u24(const uint8_t *p)
{
  return ((uint32_t)p[0] << 16) | ((uint32_t)p[1] << 8) | (uint32_t)p[2];
}

static uint32_t get_u32(const uint8_t *p)
{
  return ((uint32_t)p[0] << 24) | get_u24(p + 1);
}

static uint8_t *put_u64(uint8_t *p, uint64_t v)
{
  return put_u32(put_u32(p, (uint32_t)(v >> 32)), (uint32_t)(v & 0xFFFFFFFFU));
}

static uint64_t get_u64(const uint8_t *p)
{
  return ((uint64_t)get_u32(p) << 32) | (uint64_t)get_u32(p + 4);
}

static bool is_default_state(const canfdi_dtc_state_t *st)
{
  return (st->status == (uint8_t)CANFDI_DTC_STATUS_CLEARED) && (st->failed_cycles == 0U) &&
         (st->healthy_cycles == 0U) && (st->entry == CANFDI_DTC_NONE);
}

int32_t canfdi_dtc_serialize(const canfdi_dtc_t *m, uint8_t *buf, uint32_t cap)
{
  int32_t out = -CANFDI_EINVAL;
  if (bound(m) && (buf != NULL)) {
    uint32_t r = 0U;
    uint32_t e = 0U;
    for (uint8_t i = 0U; i < m->n_dtcs; i++) {
      if (!is_default_state(&m->dtc[i])) {
        r++;
      }
    }
    for (uint8_t k = 0U; k < (uint8_t)CANFDI_CFG_DTC_MAX_ENTRIES; k++) {
      if (m->entry[k].dtc_index != CANFDI_DTC_NONE) {
        e++;
      }
    }
    const uint32_t len = CANFDI_DTC_IMAGE_HEADER_BYTES + (r * CANFDI_DTC_IMAGE_RECORD_BYTES) +
                         (e * CANFDI_DTC_IMAGE_ENTRY_BYTES);
    if (len > cap) {
      out = -CANFDI_ERANGE;
    } else {
      uint8_t *p = buf;
      *p++ = (uint8_t)CANFDI_DTC_IMAGE_VERSION;
      *p++ = (uint8_t)r;
      *p++ = (uint8_t)e;
      *p++ = 0U;
      for (uint8_t i = 0U; i < m->n_dtcs; i++) {
        const canfdi_dtc_state_t *st = &m->dtc[i];
        if (!is_default_state(st)) {
          p = put_u24(p, m->table[i].dtc);
          *p++ = st->status;
          *p++ = st->failed_cycles;
          *p++ = st->healthy_cycles;
        }
      }
      for (uint8_t k = 0U; k < (uint8_t)CANFDI_CFG_DTC_MAX_ENTRIES; k++) {
        const canfdi_dtc_entry_t *en = &m->entry[k];
        if (en->dtc_index != CANFDI_DTC_NONE) {
          p = put_u24(p, m->table[en->dtc_index].dtc);
          *p++ = en->occurrence;
          p = put_u32(p, en->order);
          *p++ = en->ff_valid ? 1U : 0U;
          p = put_u64(p, en->ff.time_ms);
          p = put_u32(p, s32_bits(en->ff.omega_q16));
          p = put_u32(p, s32_bits(en->ff.ia_q16));
          p = put_u32(p, s32_bits(en->ff.ua_q16));
          p = put_u32(p, s32_bits(en->ff.thr_angle_q16));
          p = put_u32(p, s32_bits(en->ff.supply_q16));
          *p++ = en->ff.deg_dcm;
          *p++ = en->ff.deg_thr;
        }
      }
      CANFDI_ASSERT((uint32_t)(p - buf) == len);
      out = (int32_t)len;
    }
  }
  return out;
}

#define SEEN_WORDS ((CANFDI_CFG_DTC_MAX_DTCS + 31U) / 32U)

/* Test-and-set bit i of a bitmap; returns the old bit. */
static bool seen_set(uint32_t *seen, uint8_t i)
{
  const uint32_t bit = 1U << (i & 31U);
  const bool was = (seen[i >> 5] & bit) != 0U;
  seen[i >> 5] |= bit;
  return was;
}

/* Apply the image to m (already cleared); false on a structural error. */
static bool apply_image(canfdi_dtc_t *m, const uint8_t *buf, uint32_t len)
{
  bool ok = len >= CANFDI_DTC_IMAGE_HEADER_BYTES;
  uint32_t r = 0U;
  uint32_t e = 0U;
  uint32_t entry_bytes = CANFDI_DTC_IMAGE_ENTRY_BYTES;
  if (ok) {
    r = buf[1];
    e = buf[2];
    /* version 1 images (4-byte time stamps) are still read */
    entry_bytes = (buf[0] == 1U) ? CANFDI_DTC_IMAGE_ENTRY_BYTES_V1 : CANFDI_DTC_IMAGE_ENTRY_BYTES;
    ok = ((buf[0] == (uint8_t)CANFDI_DTC_IMAGE_VERSION) || (buf[0] == 1U)) && (buf[3] == 0U) &&
         (len == (CANFDI_DTC_IMAGE_HEADER_BYTES + (r * CANFDI_DTC_IMAGE_RECORD_BYTES) +
                  (e * entry_bytes)));
  }
  const uint8_t *p = ok ? (buf + CANFDI_DTC_IMAGE_HEADER_BYTES) : buf;
  uint32_t seen[SEEN_WORDS] = {0U};
  for (uint32_t k = 0U; ok && (k < r); k++) {
    const int32_t i = canfdi_dtc_find(m, get_u24(p));
    if (i < 0) {
      canfdi_count_inc16(&m->diag.image_dropped);
    } else if (seen_set(seen, (uint8_t)i)) {
      ok = false;
    } else {
      canfdi_dtc_state_t *st = &m->dtc[i];
      st->status = p[3];
      st->failed_cycles = p[4];
      st->healthy_cycles = p[5];
    }
    p += CANFDI_DTC_IMAGE_RECORD_BYTES;
  }
  for (uint32_t k = 0U; k < SEEN_WORDS; k++) {
    seen[k] = 0U;
  }
  for (uint32_t k = 0U; ok && (k < e); k++) {
    const int32_t i = canfdi_dtc_find(m, get_u24(p));
    const uint8_t flags = p[8];
    ok = (p[3] != 0U) && ((flags & ~1U) == 0U);
    if (!ok) {
      /* structural error */
    } else if (i < 0) {
      canfdi_count_inc16(&m->diag.image_dropped);
    } else if (seen_set(seen, (uint8_t)i)) {
      ok = false;
    } else {
      uint8_t slot = CANFDI_DTC_NONE;
      for (uint8_t s = 0U; (s < (uint8_t)CANFDI_CFG_DTC_MAX_ENTRIES) && (slot == CANFDI_DTC_NONE); s++) {
        if (m->entry[s].dtc_index == CANFDI_DTC_NONE) {
          slot = s;
        }
      }
      if (slot == CANFDI_DTC_NONE) {
        canfdi_count_inc16(&m->diag.image_dropped);
      } else {
        canfdi_dtc_entry_t *en = &m->entry[slot];
        en->dtc_index = (uint8_t)i;
        en->occurrence = p[3];
        en->order = get_u32(p + 4);
        en->ff_valid = flags == 1U;
        const uint8_t *q = p + ((entry_bytes == CANFDI_DTC_IMAGE_ENTRY_BYTES) ? 17 : 13);
        en->ff.time_ms = (entry_bytes == CANFDI_DTC_IMAGE_ENTRY_BYTES) ? get_u64(p + 9)
                                                                       : (uint64_t)get_u32(p + 9);
        en->ff.omega_q16 = bits_s32(get_u32(q));
        en->ff.ia_q16 = bits_s32(get_u32(q + 4));
        en->ff.ua_q16 = bits_s32(get_u32(q + 8));
        en->ff.thr_angle_q16 = bits_s32(get_u32(q + 12));
        en->ff.supply_q16 = bits_s32(get_u32(q + 16));
        en->ff.deg_dcm = q[20];
        en->ff.deg_thr = q[21];
        m->dtc[i].entry = slot;
        if (en->order >= m->next_order) {
          m->next_order = (en->order < UINT32_MAX) ? (en->order + 1U) : UINT32_MAX;
        }
      }
    }
    p += entry_bytes;
  }
  /* Entries dropped for lack of room (or a table whose warning flag
   * changed) leave bits that need an entry / the flag: withdraw them. */
  for (uint8_t i = 0U; ok && (i < m->n_dtcs); i++) {
    canfdi_dtc_state_t *st = &m->dtc[i];
    if (st->entry == CANFDI_DTC_NONE) {
      st->status = (uint8_t)(st->status & ~(CANFDI_DTC_ST_CDTC | CANFDI_DTC_ST_WIR));
    }
    if (!m->table[i].warning_indicator) {
      st->status = (uint8_t)(st->status & ~CANFDI_DTC_ST_WIR);
    }
  }
  return ok && canfdi_dtc_invariants_hold(m);
}

int32_t canfdi_dtc_deserialize(canfdi_dtc_t *m, const uint8_t *buf, uint32_t len)
{
  int32_t out = -CANFDI_EINVAL;
  if (bound(m)) {
    if (!m->cycle_active && (buf != NULL)) {
      clear_state(m);
      if (apply_image(m, buf, len)) {
        out = CANFDI_OK;
      } else {
        clear_state(m);
      }
      m->changes++;
    }
    if (out != CANFDI_OK) {
      canfdi_count_inc16(&m->diag.image_rejected);
    }
  }
  return out;
}

/* ------------------------------------------------------------ self-check */

static bool has(uint8_t s, uint8_t bits)
{
  return (s & bits) == bits;
}

static bool status_ok(uint8_t s, bool entry, bool warning)
{
  bool ok = true;
  if (has(s, CANFDI_DTC_ST_TF)) {
    ok = has(s, CANFDI_DTC_ST_TFSLC) && !has(s, CANFDI_DTC_ST_TNCSLC);
  }
  if (ok && has(s, CANFDI_DTC_ST_TFTOC)) {
    ok = has(s, CANFDI_DTC_ST_TFSLC) && !has(s, CANFDI_DTC_ST_TNCTOC);
  }
  if (ok && has(s, CANFDI_DTC_ST_PDTC)) {
    ok = has(s, CANFDI_DTC_ST_TFSLC);
  }
  if (ok && has(s, CANFDI_DTC_ST_CDTC)) {
    ok = entry;
  }
  if (ok && has(s, CANFDI_DTC_ST_WIR)) {
    ok = has(s, CANFDI_DTC_ST_CDTC) && warning;
  }
  if (ok && has(s, CANFDI_DTC_ST_TFSLC)) {
    ok = !has(s, CANFDI_DTC_ST_TNCSLC);
  }
  if (ok && entry) {
    ok = has(s, CANFDI_DTC_ST_TFSLC);
  }
  return ok;
}

bool canfdi_dtc_invariants_hold(const canfdi_dtc_t *m)
{
  bool ok = bound(m);
  for (uint8_t i = 0U; ok && (i < m->n_dtcs); i++) {
    const canfdi_dtc_state_t *st = &m->dtc[i];
    const bool entry = st->entry != CANFDI_DTC_NONE;
    ok = status_ok(st->status, entry, m->table[i].warning_indicator);
    if (ok && entry) {
      ok = (st->entry < (uint8_t)CANFDI_CFG_DTC_MAX_ENTRIES) && (m->entry[st->entry].dtc_index == i);
    }
  }
  for (uint8_t e = 0U; ok && (e < (uint8_t)CANFDI_CFG_DTC_MAX_ENTRIES); e++) {
    const canfdi_dtc_entry_t *en = &m->entry[e];
    if (en->dtc_index != CANFDI_DTC_NONE) {
      ok = (en->dtc_index < m->n_dtcs) && (m->dtc[en->dtc_index].entry == e) &&
           (en->occurrence >= 1U);
    }
  }
  return ok;
}
