/*
 * canfdi_dtc.h — the event/trouble-code memory of canfdi, in the style of an
 * AUTOSAR Diagnostic Event Manager (Dem) with ISO 14229-1 (UDS) status bits.
 *
 * What it does. Monitors (the diagnosis, the input supervision) report one
 * raw result per test run for a DTC. Each DTC has its own counter debouncer
 * (canfdi_debounce, one instance per DTC) that turns the stream into
 * qualified "test failed" / "test passed" results; those drive the eight UDS
 * status bits, an occurrence counter, operation-cycle bookkeeping, aging and
 * self-healing, and a bounded set of event-memory entries that hold a freeze
 * frame. The state serialises to a compact, versioned byte image that
 * canfdi_nvm stores power-fail-safely.
 *
 * Two levels of storage (as in Dem):
 *   - per DTC, always present (every DTC of the table): the status byte, the
 *     failed-cycle counter, the healthy-cycle counter, the debouncer;
 *   - per event-memory entry, CANFDI_CFG_DTC_MAX_ENTRIES of them: the DTC it
 *     belongs to, the occurrence counter and the freeze frame. An entry is
 *     created at the first qualified failure ("storage trigger: test
 *     failed"); confirmedDTC is only ever set on a DTC that has an entry.
 *
 * Typical use by the application:
 *   boot:     canfdi_dtc_init(&dtc, canfdi_dtc_defaults, CANFDI_DTC_COUNT);
 *             n = canfdi_nvm_load(&nvm, buf, sizeof buf);
 *             if (n >= 0) canfdi_dtc_deserialize(&dtc, buf, (uint32_t)n);
 *             (on failure the defaults stay; report nvm.bank_state[])
 *             canfdi_dtc_cycle_start(&dtc);
 *   1 ms:     canfdi_dtc_report(&dtc, index, result, &snapshot) per monitor
 *   shutdown: canfdi_dtc_cycle_end(&dtc); n = canfdi_dtc_serialize(...);
 *             canfdi_nvm_store(&nvm, buf, n) — also from a background task
 *             whenever dtc.changes moved, so that a power cut loses little.
 *
 * ---------------------------------------------------------------- DTC table
 * A table of canfdi_dtc_def_t in ROM, one row per DTC; the instance keeps a
 * pointer. canfdi_dtc_defaults[] is the product table: the CANFDI_DTC_COUNT
 * trouble codes of dbc/dtcs.csv in that file's order (index i is
 * canfdi_catalogue_dtc[i]; the unit test checks both against the CSV). Its
 * attributes follow the CSV severity column:
 *   severity             priority  warning indicator (bit 7)
 *   check_immediately        1        yes
 *   check_at_next_halt       2        yes
 *   maintenance_only         3        no
 *     check_immediately:  P2100 P2119 P1A31 U1A00 U1A01 U1A10 U1A11 U1A20
 *                         U1A21 U1A30 U1A31 U1A40 U1A41
 *     check_at_next_halt: P0121 P0122 P0123 P0221 P0222 P0223 P2135 P1A20
 *                         P1A21 P1A22 P1A30
 *     maintenance_only:   P0638 P2101 P1A10 P1A11 P1A12 P1B10
 * For every DTC: confirmation threshold N = 1 failed operation cycle, warning
 * indicator healing after M = 3 healthy cycles (the OBD convention for the
 * MIL), aging after K = 40 healthy cycles (the OBD convention for erasing a
 * confirmed code). Group (for clear-by-group) = the catalogue component:
 * P1Axx DC motor, P0xxx/P21xx/P1B10 throttle, U1Axx communication.
 * Debounce class: canfdi_dtc_deb_frame for the per-frame checks (U1A10..
 * U1A41: rolling counter, CRC, length, implausible value), whose monitor
 * reports every received frame; canfdi_dtc_deb_direct for all others, whose
 * monitors already qualify their result (limit/trend detectors embed
 * canfdi_debounce, timeouts are time-qualified by the receiver, the
 * fault-symptom reasoning reports decisions). A FAILED/PASSED report always
 * qualifies at once whatever the class; PREFAILED/PREPASSED are counted.
 *
 * ---------------------------------------------------- status bits (UDS)
 * Bit  name (ISO 14229-1)                     abbreviation here
 *  0   testFailed                             CANFDI_DTC_ST_TF
 *  1   testFailedThisOperationCycle           CANFDI_DTC_ST_TFTOC
 *  2   pendingDTC                             CANFDI_DTC_ST_PDTC
 *  3   confirmedDTC                           CANFDI_DTC_ST_CDTC
 *  4   testNotCompletedSinceLastClear         CANFDI_DTC_ST_TNCSLC
 *  5   testFailedSinceLastClear               CANFDI_DTC_ST_TFSLC
 *  6   testNotCompletedThisOperationCycle     CANFDI_DTC_ST_TNCTOC
 *  7   warningIndicatorRequested              CANFDI_DTC_ST_WIR
 * All eight are supported: availability mask 0xFF.
 *
 * Transitions (s = status byte; "healthy cycle" = an operation cycle that
 * ended with the test completed and never failed in it, i.e. TNCTOC = 0 and
 * TFTOC = 0 at cycle end):
 *   init, ClearDiagnosticInformation:
 *       s = 0x50 (TNCSLC, TNCTOC); failed-cycle and healthy-cycle counters 0;
 *       the entry (freeze frame, occurrence counter) is freed; debouncer reset.
 *   qualified test failed:
 *       TF = 1, TFTOC = 1, PDTC = 1, TFSLC = 1, TNCSLC = 0, TNCTOC = 0;
 *       if TFTOC was 0: failed-cycle counter += 1 (saturating at 255);
 *       healthy-cycle counter = 0;
 *       if TF was 0 or TFTOC was 0 and the DTC has no entry: an entry is
 *         allocated (displacing one if full, see below) and the freeze frame
 *         stored, occurrence = 1; else if TF was 0: occurrence += 1;
 *       if the DTC has an entry and failed-cycle counter >= N: CDTC = 1;
 *       if CDTC and the table requests the warning indicator: WIR = 1.
 *   qualified test passed:
 *       TF = 0, TNCSLC = 0, TNCTOC = 0 (TFTOC, PDTC, CDTC, WIR unchanged).
 *   end of operation cycle (canfdi_dtc_cycle_end):
 *       healthy cycle: PDTC = 0 and failed-cycle counter = 0 (confirmation
 *         starts over, the OBD "two-trip" meaning of N = 2); if the DTC has
 *         an entry: healthy-cycle counter += 1 (saturating); if it reaches
 *         M: WIR = 0; if K != 0 and it reaches K: aging — CDTC = 0, WIR = 0,
 *         the entry is freed, the counter back to 0 (TFSLC stays: aging is
 *         not a clear; ISO resets TFSLC on a clear only). DTCs without an
 *         entry have nothing to heal (WIR implies CDTC implies an entry).
 *       cycle in which the test failed, or did not complete: nothing
 *         (PDTC stays; an untested cycle neither heals nor resets healing).
 *   start of operation cycle (canfdi_dtc_cycle_start):
 *       TFTOC = 0, TNCTOC = 1 (TF kept: it reports the last result); the
 *       debouncer starts its cycle (counter 0, qualified status kept).
 * Occurrence counter: the number of testFailed 0 -> 1 transitions while the
 * entry exists (1 at the first failure, +1 at each failed -> passed ->
 * failed), saturating at 255. A failure that persists across operation
 * cycles without a qualified pass is one occurrence.
 * Freeze frame: the snapshot passed with the report that created the entry;
 * never overwritten until the entry is freed (clear, aging, displacement).
 *
 * Displacement when all entries are in use and a DTC without an entry fails
 * (the AUTOSAR "full" strategy): candidates are entries of strictly lower
 * priority (larger number) and entries of equal priority that are passive
 * (TF = 0); of those, the lowest priority goes first, then passive before
 * active, then the oldest (smallest storage order). The displaced DTC loses
 * CDTC and WIR (ISO: confirmedDTC is reset when its record is overwritten);
 * its other bits and counters stay. No candidate: the failure is not stored
 * (its bits are still set, CDTC is not), diag.not_stored counts it and the
 * storage is retried at the next failure transition or the first failure of
 * the next cycle. diag.overflows counts every time an entry was needed while
 * all were in use.
 *
 * Reports are accepted only between cycle_start and cycle_end (Dem ignores
 * reports of events whose operation cycle is not started). After init or a
 * load from NVM no cycle is active; the application starts one.
 *
 * ----------------------------------------------------- NVM byte image (v2)
 * canfdi_dtc_serialize writes (all multi-byte fields big-endian, the UDS
 * byte order; DTCs as 3 bytes):
 *   0   u8  format version (CANFDI_DTC_IMAGE_VERSION, 2)
 *   1   u8  r, number of status records
 *   2   u8  e, number of entries
 *   3   u8  0 (reserved)
 *   4   r x 6 bytes: DTC(3), status, failed-cycle counter, healthy-cycle ctr
 *       (only DTCs whose state differs from the cleared state)
 *   ..  e x 39 bytes: DTC(3), occurrence, storage order(4), flags (bit 0:
 *       freeze frame valid), freeze frame: time_ms(8), omega, ia, ua,
 *       thr_angle, supply (4 each), deg_dcm, deg_thr (1 each)
 * canfdi_dtc_deserialize also reads version 1 images, whose entries are 35
 * bytes with a 4-byte time_ms (an image stored by an earlier firmware is
 * kept across the update).
 * Records are matched to the table by DTC number, so a table that gains or
 * loses DTCs still loads (unknown DTCs are dropped and counted). The
 * debouncer state is not stored (a new cycle restarts it anyway).
 *
 * ---------------------------------------------------------------- cost
 * canfdi_dtc_report: one debounce step plus a dozen bit operations;
 *   O(CANFDI_CFG_DTC_MAX_ENTRIES) only when an entry is allocated (at most
 *   once per failure transition or cycle), plus a 32-byte copy.
 * cycle_start/cycle_end, count_by_mask, clear: O(number of DTCs).
 * find, clear(one DTC), read_record: O(number of DTCs) (linear search).
 * serialize O(DTCs + entries); deserialize O(DTCs * records) (a linear
 *   find per record), for boot time only.
 * No recursion, no heap, no floating point, no division.
 * Measured executed instructions (arm-none-eabi-gcc 12 -Os, QEMU
 * mps2-an386 -icount, product table, 8 entries, 20000 random reports over
 * all DTCs and kinds with cycles and clears in between; min/mean/max seen,
 * the M0+ build's ARMv6-M code run on the same emulated core):
 *                               Cortex-M4          Cortex-M0+
 *   report                      75 / 139 / 541     111 / 202 / 891
 *   cycle_start (+ implicit end)   1178 max 1213    1543 max 1718
 *   count_by_mask                  352              272
 *   serialize (8 entries)          1965             2420
 *   deserialize (same image)       14183            16328
 * (serialize and deserialize were measured with 4-byte freeze-frame time
 * stamps; the 8-byte stamp adds four byte moves per entry.)
 * Stack (-fstack-usage, M0+): report 64 bytes + debounce 16, deserialize
 * 56 + 24, others <= 32.
 *
 * ---------------------------------------------------------------- memory
 * RAM: sizeof(canfdi_dtc_t) = 32 + 20 * CANFDI_CFG_DTC_MAX_DTCS
 *   + 48 * CANFDI_CFG_DTC_MAX_ENTRIES bytes on a 32-bit target (16 of the
 *   32 are the diagnostics); with the defaults (32 DTCs, 8 entries): 1056
 *   bytes. Per DTC 20 bytes (16 of them the debouncer), per entry 48 bytes
 *   (32 of them the freeze frame).
 * ROM: the table, 16 bytes per DTC (512 for the product table), two
 *   debounce classes (28 bytes); code + tables 4038 bytes on M0+, 3764 on
 *   M4 (-Os), plus canfdi_debounce (472 / 438).
 * NVM image: at most CANFDI_DTC_IMAGE_MAX_BYTES
 *   (4 + 6 per DTC + 39 per entry: 508 bytes with the defaults).
 */
#ifndef CANFDI_DTC_H
#define CANFDI_DTC_H

#include "catalogue/canfdi_catalogue.h"
#include "core/canfdi_common.h"
#include "core/canfdi_debounce.h"

/* Largest table an instance can hold (1..254; indices are uint8_t, 0xFF
 * means "none"). RAM: 20 bytes per DTC. */
#ifndef CANFDI_CFG_DTC_MAX_DTCS
#define CANFDI_CFG_DTC_MAX_DTCS CANFDI_DTC_COUNT
#endif

/* Event-memory entries (freeze frame + occurrence), 1..254.
 * RAM: 48 bytes per entry; NVM image: 39 bytes per entry. */
#ifndef CANFDI_CFG_DTC_MAX_ENTRIES
#define CANFDI_CFG_DTC_MAX_ENTRIES 8U
#endif

/* UDS status bits (ISO 14229-1 DTCStatusMask). */
#define CANFDI_DTC_ST_TF 0x01U     /* testFailed */
#define CANFDI_DTC_ST_TFTOC 0x02U  /* testFailedThisOperationCycle */
#define CANFDI_DTC_ST_PDTC 0x04U   /* pendingDTC */
#define CANFDI_DTC_ST_CDTC 0x08U   /* confirmedDTC */
#define CANFDI_DTC_ST_TNCSLC 0x10U /* testNotCompletedSinceLastClear */
#define CANFDI_DTC_ST_TFSLC 0x20U  /* testFailedSinceLastClear */
#define CANFDI_DTC_ST_TNCTOC 0x40U /* testNotCompletedThisOperationCycle */
#define CANFDI_DTC_ST_WIR 0x80U    /* warningIndicatorRequested */
/* Status after init and after ClearDiagnosticInformation. */
#define CANFDI_DTC_STATUS_CLEARED (CANFDI_DTC_ST_TNCSLC | CANFDI_DTC_ST_TNCTOC)
/* DTCStatusAvailabilityMask for ReadDTCInformation: every bit supported. */
#define CANFDI_DTC_STATUS_AVAILABILITY_MASK 0xFFU
/* groupOfDTC of ClearDiagnosticInformation meaning "all groups". */
#define CANFDI_DTC_GROUP_ALL 0xFFFFFFU

#define CANFDI_DTC_NONE 0xFFU /* "no entry" / "free entry" index */

/* Byte image (see above). */
#define CANFDI_DTC_IMAGE_VERSION 2U
#define CANFDI_DTC_IMAGE_HEADER_BYTES 4U
#define CANFDI_DTC_IMAGE_RECORD_BYTES 6U
#define CANFDI_DTC_IMAGE_ENTRY_BYTES 39U
#define CANFDI_DTC_IMAGE_ENTRY_BYTES_V1 35U
#define CANFDI_DTC_IMAGE_MAX_BYTES                                                      \
  (CANFDI_DTC_IMAGE_HEADER_BYTES + (CANFDI_DTC_IMAGE_RECORD_BYTES * CANFDI_CFG_DTC_MAX_DTCS) + \
   (CANFDI_DTC_IMAGE_ENTRY_BYTES * CANFDI_CFG_DTC_MAX_ENTRIES))

/*
 * Freeze frame: the key signals at the first failure, as the application
 * has them (Q16.16 SI units, see the signal convention of the firmware).
 */
typedef struct {
  uint64_t time_ms;      /* operating time stamp: the uptime in ms (core/canfdi_uptime.h) */
  int32_t omega_q16;     /* DC motor speed, rad/s */
  int32_t ia_q16;        /* DC motor armature current, A */
  int32_t ua_q16;        /* DC motor armature voltage, V */
  int32_t thr_angle_q16; /* throttle angle, rad */
  int32_t supply_q16;    /* supply voltage, V */
  uint8_t deg_dcm;       /* degradation state DC motor (CANFDI_DEG_*) */
  uint8_t deg_thr;       /* degradation state throttle (CANFDI_DEG_*) */
} canfdi_dtc_ff_t;

/* One row of the DTC table (ROM). Valid domain (checked by init): dtc in
 * 1..0xFFFFFE and unique in the table, deb valid (canfdi_debounce_cfg_check),
 * priority >= 1, confirm_cycles >= 1, heal_cycles >= 1,
 * aging_cycles == 0 or >= heal_cycles. */
typedef struct {
  uint32_t dtc;                     /* 3-byte UDS DTC, e.g. CANFDI_DTC_P0122 */
  const canfdi_debounce_cfg_t *deb; /* debounce class of the raw reports */
  uint8_t priority;                 /* 1 = highest; displacement order */
  uint8_t group;                    /* clear-by-group id (CANFDI_COMPONENT_*) */
  uint8_t confirm_cycles;           /* N: failed cycles until confirmedDTC */
  uint8_t heal_cycles;              /* M: healthy cycles until WIR = 0 */
  uint8_t aging_cycles;             /* K: healthy cycles until aged out; 0 never */
  bool warning_indicator;           /* this DTC requests the warning lamp */
} canfdi_dtc_def_t;

/* Per-DTC state (RAM). */
typedef struct {
  canfdi_debounce_t deb;
  uint8_t status;         /* UDS status byte */
  uint8_t failed_cycles;  /* failed operation cycles since PDTC was last 0 */
  uint8_t healthy_cycles; /* healthy cycles since the last failure */
  uint8_t entry;          /* index into canfdi_dtc_t.entry or CANFDI_DTC_NONE */
} canfdi_dtc_state_t;

/* Event-memory entry (RAM). */
typedef struct {
  uint32_t order;      /* storage order (larger = newer); displacement ages */
  canfdi_dtc_ff_t ff;  /* freeze frame at the first failure */
  uint8_t dtc_index;   /* table index of the owner or CANFDI_DTC_NONE */
  uint8_t occurrence;  /* testFailed 0->1 transitions, saturating */
  bool ff_valid;       /* false if the creating report carried no snapshot */
} canfdi_dtc_entry_t;

/* Monotone counters, saturating at UINT16_MAX, never cleared after init. */
typedef struct {
  uint16_t overflows;        /* an entry was needed while all were in use */
  uint16_t displacements;    /* entries displaced by a higher-ranked failure */
  uint16_t not_stored;       /* failures that could not get an entry */
  uint16_t aged;             /* entries freed by aging */
  uint16_t clears;           /* clear calls that cleared at least one DTC */
  uint16_t rejected_reports; /* bad index/report or no active cycle */
  uint16_t image_rejected;   /* deserialize calls that failed */
  uint16_t image_dropped;    /* records/entries dropped at load */
} canfdi_dtc_diag_t;

/* The DTC memory, caller-owned (normally static). Read fields freely; write
 * only through the functions below. `changes` is incremented (wrapping) on
 * every change of the persistent state, every status byte included: save
 * to NVM when it differs from the value at the last save, and look for
 * status changes only when it moved (tests/unit/test_dtc.c checks this on
 * random histories). */
typedef struct {
  const canfdi_dtc_def_t *table;
  uint8_t n_dtcs;
  bool cycle_active;
  uint32_t next_order;
  uint32_t changes;
  canfdi_dtc_state_t dtc[CANFDI_CFG_DTC_MAX_DTCS];
  canfdi_dtc_entry_t entry[CANFDI_CFG_DTC_MAX_ENTRIES];
  canfdi_dtc_diag_t diag;
} canfdi_dtc_t;

/* What ReadDTCInformation needs about one DTC (canfdi_dtc_read_record). */
typedef struct {
  uint32_t dtc;
  uint8_t status;
  uint8_t occurrence; /* 0 if no entry */
  bool ff_valid;
  canfdi_dtc_ff_t ff; /* zero if !ff_valid */
} canfdi_dtc_record_t;

/* The product table (see above) and its two debounce classes. */
extern const canfdi_dtc_def_t canfdi_dtc_defaults[CANFDI_DTC_COUNT];
/* direct: failed +1 / passed -1, step 1, jump up/down to 0: every report
 * qualifies at once, in either direction. */
extern const canfdi_debounce_cfg_t canfdi_dtc_deb_direct;
/* frame: failed +6 / passed -6, PREFAILED +2, PREPASSED -1, no jumps: three
 * bad frames in a row qualify FAILED, six good ones from 0 qualify PASSED,
 * and a bad-frame ratio above 1/3 qualifies FAILED eventually. */
extern const canfdi_debounce_cfg_t canfdi_dtc_deb_frame;

/*
 * Bind m to a table of n rows (1..CANFDI_CFG_DTC_MAX_DTCS) and clear it: all
 * DTCs in the cleared state (0x50), no entries, no cycle active, diagnostics
 * zero. The table must outlive m. Returns CANFDI_OK, or -CANFDI_EINVAL for
 * NULL, n out of range or a row outside the domain above (m is then
 * unbound: every other call fails or does nothing). Cost O(n^2) compares
 * (uniqueness), init time only.
 */
int32_t canfdi_dtc_init(canfdi_dtc_t *m, const canfdi_dtc_def_t *table, uint8_t n);

/*
 * Start an operation cycle (ending the active one first, as Dem's restart).
 * Returns CANFDI_OK or -CANFDI_EINVAL (NULL/unbound). Cost O(DTCs).
 */
int32_t canfdi_dtc_cycle_start(canfdi_dtc_t *m);

/*
 * End the active operation cycle: pending reset, healing and aging (above).
 * Returns CANFDI_OK, or -CANFDI_EINVAL if m is NULL/unbound or no cycle is
 * active (then nothing changes). Cost O(DTCs).
 */
int32_t canfdi_dtc_cycle_end(canfdi_dtc_t *m);

/*
 * Report one raw monitor result for the DTC at table index `index`. ff is
 * the current snapshot (may be NULL: an entry created now has ff_valid
 * false); it is only read when an entry is created. Returns the DTC's status
 * byte after the report (0..255), or -CANFDI_EINVAL (NULL/unbound m, index
 * out of range, unknown report, no cycle active; counted in
 * diag.rejected_reports, nothing else changes). Cost: see above.
 */
int32_t canfdi_dtc_report(canfdi_dtc_t *m, uint8_t index, canfdi_deb_report_t report,
                          const canfdi_dtc_ff_t *ff);

/*
 * True when `report` for the DTC at `index` would change nothing: it is a
 * PASSED or PREPASSED, a cycle is active, the index is in range, and the
 * DTC has passed and is settled there (its debouncer's counter on the
 * passed threshold, no testFailed, test completed this cycle and since the
 * last clear). canfdi_dtc_report returns the status at once in that case;
 * this is the same test, inline, for a caller that gives many reports a
 * step (the DTC routing) and can skip the call. False for NULL or unbound
 * m. O(1).
 */
static inline bool canfdi_dtc_pass_is_noop(const canfdi_dtc_t *m, uint8_t index, canfdi_deb_report_t report)
{
  bool r = false;
  if (((report == CANFDI_DEB_REPORT_PASSED) || (report == CANFDI_DEB_REPORT_PREPASSED)) && (m != NULL) &&
      (m->table != NULL) && m->cycle_active && (index < m->n_dtcs)) {
    const canfdi_dtc_state_t *st = &m->dtc[index];
    r = canfdi_debounce_pass_is_noop(&st->deb, report) &&
        ((st->status & (CANFDI_DTC_ST_TF | CANFDI_DTC_ST_TNCSLC | CANFDI_DTC_ST_TNCTOC)) == 0U);
  }
  return r;
}

/*
 * ClearDiagnosticInformation (UDS 0x14): group_of_dtc CANFDI_DTC_GROUP_ALL
 * clears every DTC, a DTC number of the table clears that DTC. Returns
 * CANFDI_OK, or -CANFDI_EINVAL for NULL/unbound m or an unknown group
 * (UDS NRC requestOutOfRange). Cost O(DTCs).
 */
int32_t canfdi_dtc_clear(canfdi_dtc_t *m, uint32_t group_of_dtc);

/*
 * Clear every DTC whose table group is `group` (manufacturer groups: the
 * CANFDI_COMPONENT_* ids in the product table). Returns the number of DTCs
 * cleared (0 if none belongs to the group), or -CANFDI_EINVAL (NULL/unbound).
 */
int32_t canfdi_dtc_clear_group(canfdi_dtc_t *m, uint8_t group);

/* Table index of a DTC number, or -CANFDI_EINVAL (unknown, NULL). O(DTCs). */
int32_t canfdi_dtc_find(const canfdi_dtc_t *m, uint32_t dtc);

/* Status byte of the DTC at `index` (0..255), or -CANFDI_EINVAL. O(1). */
int32_t canfdi_dtc_status(const canfdi_dtc_t *m, uint8_t index);

/* The same byte inline and unchecked, for the scans of the table in the
 * 1 ms step: m bound and index < m->n_dtcs are the caller's (asserted). */
static inline uint8_t canfdi_dtc_status_at(const canfdi_dtc_t *m, uint8_t index)
{
  CANFDI_ASSERT((m != NULL) && (m->table != NULL) && (index < m->n_dtcs));
  return m->dtc[index].status;
}

/* Occurrence counter of the DTC at `index` (its event-memory entry's; 0
 * without an entry, for a bad index or NULL): canfdi_dtc_read_record's
 * `occurrence` without the search by DTC number. O(1). */
uint8_t canfdi_dtc_occurrence(const canfdi_dtc_t *m, uint8_t index);

/* Fault detection counter (-128..127) of the DTC's debouncer
 * (ReadDTCInformation 0x14); 0 for a bad index or NULL. O(1). */
int8_t canfdi_dtc_fdc(const canfdi_dtc_t *m, uint8_t index);

/*
 * ReadDTCInformation 0x01 (reportNumberOfDTCByStatusMask): the number of
 * DTCs with (status & mask & CANFDI_DTC_STATUS_AVAILABILITY_MASK) != 0.
 * 0 for NULL/unbound. Cost O(DTCs).
 */
uint16_t canfdi_dtc_count_by_mask(const canfdi_dtc_t *m, uint8_t mask);

/*
 * ReadDTCInformation 0x02 (reportDTCByStatusMask) as an iterator: set
 * *cursor = 0, then call until it returns 0. Each call that returns 1
 * writes the next matching DTC (table order) and its status and advances
 * *cursor. Returns 1, 0 (no more), or -CANFDI_EINVAL (NULL argument,
 * unbound m). Cost O(DTCs) over a whole iteration.
 */
int32_t canfdi_dtc_next_by_mask(const canfdi_dtc_t *m, uint8_t mask, uint16_t *cursor,
                                uint32_t *dtc, uint8_t *status);

/*
 * ReadDTCInformation 0x04 (reportDTCSnapshotRecordByDTCNumber) and 0x06
 * (occurrence): fills *out for DTC `dtc`. Returns CANFDI_OK if the DTC has
 * an entry, -CANFDI_ENODATA if it has none (out still gets dtc and status,
 * occurrence 0, no freeze frame), -CANFDI_EINVAL for an unknown DTC or
 * NULL. Cost O(DTCs).
 */
int32_t canfdi_dtc_read_record(const canfdi_dtc_t *m, uint32_t dtc, canfdi_dtc_record_t *out);

/*
 * Write the byte image (format above) into buf[0..cap). Returns its length
 * (<= CANFDI_DTC_IMAGE_MAX_BYTES), -CANFDI_ERANGE if cap is too small
 * (nothing useful written), -CANFDI_EINVAL for NULL/unbound. O(DTCs+entries).
 */
int32_t canfdi_dtc_serialize(const canfdi_dtc_t *m, uint8_t *buf, uint32_t cap);

/*
 * Replace the state of m (bound, no cycle active) by the image buf[0..len).
 * All or nothing: on any error m is left in the cleared state (defaults)
 * and the error is returned: -CANFDI_EINVAL (NULL/unbound, cycle active,
 * wrong version or length, duplicate DTC, an occurrence of 0, unknown flag
 * bits, or a state that breaks the status-bit invariants). DTCs not in the
 * table are dropped, entries beyond CANFDI_CFG_DTC_MAX_ENTRIES are dropped
 * (their DTCs lose CDTC/WIR); both counted in diag.image_dropped, and the
 * call still succeeds. Returns CANFDI_OK. O(DTCs*records + entries).
 */
int32_t canfdi_dtc_deserialize(canfdi_dtc_t *m, const uint8_t *buf, uint32_t len);

/*
 * Self-check of the invariants between status bits, counters and entries:
 * TF => TFSLC & !TNCSLC; TFTOC => TFSLC & !TNCTOC; PDTC => TFSLC;
 * CDTC => entry; WIR => CDTC & warning_indicator; TFSLC => !TNCSLC;
 * entry => TFSLC & occurrence >= 1; entry<->DTC links consistent.
 * Returns false for NULL/unbound. Cost O(DTCs + entries). For tests and a
 * start-up check.
 */
bool canfdi_dtc_invariants_hold(const canfdi_dtc_t *m);

#endif /* CANFDI_DTC_H */
