/*
 * canfdi_nvm.h — power-fail-safe storage of one byte image (the DTC memory)
 * in two banks of non-volatile memory behind a small port.
 *
 * The port. Three callbacks and two sizes (canfdi_nvm_port_t): read, write
 * (program) and erase of one bank; bank_bytes; write_unit, the program
 * granularity (1, 2, 4, 8 or 16: every write starts at a multiple of it and
 * has a length that is a multiple of it, as ECC flash of Cortex-M parts
 * requires, e.g. 8 bytes on STM32G0/L4). The module assumes flash
 * semantics: erase sets every byte of the bank to 0xFF, and each byte is
 * programmed at most once between erases (it never relies on overwriting).
 * A Cortex-M port maps a bank to one or more flash pages; the host port
 * (firmware/port/linux/canfdi_nvm_file.h) to a file.
 *
 * Bank layout (little-endian, offsets in bytes; u = write_unit,
 * up(x) = x rounded up to a multiple of u):
 *   0    magic    u32  CANFDI_NVM_MAGIC ("CNVM")
 *   4    version  u16  CANFDI_NVM_VERSION (container format)
 *   6    reserved u16  0
 *   8    seq      u32  sequence number of this image
 *   12   len      u32  payload length
 *   16   payload  len bytes, then 0xFF up to P = up(16 + len)
 *   P    crc      u32  CRC-32 over bytes [0, 16 + len), then 0xFF to up(P+4)
 *   C    commit   u32  CANFDI_NVM_COMMIT, C = up(P + 4), then 0xFF padding
 * Footprint of an image: up(C + 4) bytes; it must fit bank_bytes.
 *
 * Update (canfdi_nvm_store), each step a separate port call, in order:
 *   1. erase the bank that does not hold the current image (the older or
 *      the invalid one);
 *   2. write header (seq = current seq + 1) and payload;
 *   3. write the CRC;
 *   4. write the commit word — the single step that makes the new image
 *      exist;
 *   5. read the bank back and validate it (as the loader would).
 * Why a kill at any moment leaves a valid image: the current image is in
 * the other bank and is never touched. Before step 4 completes, the target
 * bank has no complete commit word, so the loader ignores it: an erased
 * word is 0xFFFFFFFF, and since programming only clears bits, a word whose
 * programming was cut short still has a 1 where the commit value has a 0.
 * Once it matches, steps 2-3 are complete, because the port performs
 * calls in order (the file port fdatasyncs each one). The loader therefore
 * returns the complete old image or the complete new one, never a mix.
 * The CRC is not what makes the update atomic; it catches corruption
 * afterwards (bit flips, a worn or disturbed cell) and an interrupted erase
 * of the target bank (which may leave an older image partly destroyed).
 *
 * Load (canfdi_nvm_load): each bank is classified
 *   EMPTY       header all 0xFF (erased, never written);
 *   INCOMPLETE  plausible header but the commit word is still erased (an
 *               update interrupted before its last step);
 *   CORRUPT     anything else that fails: magic, version, length, commit
 *               word, CRC;
 *   VALID       all checks pass;
 * and the VALID bank with the newer sequence number is selected. Sequence
 * comparison is serial-number arithmetic (RFC 1982): a is newer than b if
 * (a - b) mod 2^32 is in 1..2^31-1, so the wrap from 0xFFFFFFFF to 0 is
 * harmless. No VALID bank: -CANFDI_ENODATA, the states tell why (both EMPTY
 * = a new device; otherwise an error worth reporting), and the caller keeps
 * its defaults.
 *
 * CRC-32: the IEEE 802.3 / zlib CRC (reflected polynomial 0xEDB88320, init
 * 0xFFFFFFFF, final XOR 0xFFFFFFFF; check value of "123456789" is
 * 0xCBF43926). Hamming distance 4 up to 91607 data bits (Koopman), so every
 * 1-, 2- and 3-bit error of an image is detected. Implemented with a
 * 16-entry nibble table (64 bytes ROM), two table look-ups per byte.
 *
 * Cost. store: one erase, 4 write calls (+1 or 2 for padding tails), then a
 * read-back of up(C+4) bytes in CANFDI_CFG_NVM_CHUNK_BYTES pieces; CPU time
 * O(len) (two CRC passes). load: up to two bank validations (O(len) each)
 * plus one payload read. Blocking: run it at the end of an operation cycle
 * or from a background task, never in the 1 ms step (a flash page erase
 * alone takes tens of ms). Measured (QEMU -icount as in canfdi_dtc.h, RAM
 * port, 464-byte image, write unit 8, instructions including the port's
 * byte loops): store 16606 (M4) / 23495 (M0+), load 12656 / 18537; the
 * CRC costs about 11 (M4) / 16 (M0+) instructions per byte.
 * Stack (-fstack-usage, M0+): store 112 + validate 144 + 32 bytes plus the
 * port callback's own (the chunk buffer, CANFDI_CFG_NVM_CHUNK_BYTES, is
 * inside the 144). RAM: sizeof(canfdi_nvm_t) = 28 bytes (32-bit target).
 * ROM: 1562 bytes (M0+) / 1520 (M4) -Os, including the 64-byte CRC table.
 */
#ifndef CANFDI_NVM_H
#define CANFDI_NVM_H

#include "core/canfdi_common.h"

/* Read-back and CRC scratch buffer on the stack, bytes (>= 16). */
#ifndef CANFDI_CFG_NVM_CHUNK_BYTES
#define CANFDI_CFG_NVM_CHUNK_BYTES 32U
#endif

#define CANFDI_NVM_BANKS 2U
#define CANFDI_NVM_MAGIC 0x4D564E43U  /* "CNVM" in memory order */
#define CANFDI_NVM_VERSION 1U
#define CANFDI_NVM_COMMIT 0x3CA5C35AU /* any value but 0xFFFFFFFF works */
#define CANFDI_NVM_HEADER_BYTES 16U
#define CANFDI_NVM_MAX_WRITE_UNIT 16U

/* Bank footprint of a payload of len bytes with write unit u. */
#define CANFDI_NVM_ALIGN_UP(x, u) ((((x) + (u) - 1U) / (u)) * (u))
#define CANFDI_NVM_FOOTPRINT(len, u)                                                     \
  (CANFDI_NVM_ALIGN_UP(CANFDI_NVM_ALIGN_UP(CANFDI_NVM_ALIGN_UP(CANFDI_NVM_HEADER_BYTES + \
                                                                   (len), (u)) + 4U, (u)) + 4U, (u)))

/*
 * The port. Each callback returns >= 0 on success or a negative CANFDI
 * error (normally -CANFDI_EIO); bank is 0 or 1; offset + len <= bank_bytes;
 * write offsets and lengths are multiples of write_unit. ctx is passed
 * through. The callbacks are called in program order and must complete
 * (be durable) before returning.
 */
typedef struct {
  void *ctx;
  int32_t (*read)(void *ctx, uint8_t bank, uint32_t offset, uint8_t *buf, uint32_t len);
  int32_t (*write)(void *ctx, uint8_t bank, uint32_t offset, const uint8_t *buf, uint32_t len);
  int32_t (*erase)(void *ctx, uint8_t bank);
  uint32_t bank_bytes; /* size of one bank, >= CANFDI_NVM_FOOTPRINT(0, u) */
  uint8_t write_unit;  /* 1, 2, 4, 8 or 16 */
} canfdi_nvm_port_t;

typedef enum {
  CANFDI_NVM_BANK_UNKNOWN = 0,    /* not scanned yet */
  CANFDI_NVM_BANK_EMPTY = 1,      /* erased */
  CANFDI_NVM_BANK_INCOMPLETE = 2, /* update interrupted before the commit */
  CANFDI_NVM_BANK_CORRUPT = 3,    /* fails a check */
  CANFDI_NVM_BANK_VALID = 4
} canfdi_nvm_bank_state_t;

/* Monotone counters, saturating at UINT16_MAX. */
typedef struct {
  uint16_t loads;         /* load calls that returned an image */
  uint16_t load_failures; /* load calls without an image (incl. new device) */
  uint16_t stores;        /* successful stores */
  uint16_t store_failures;/* stores that failed (port error, verify) */
  uint16_t corrupt_banks; /* banks classified CORRUPT by a scan */
  uint16_t incomplete_banks; /* banks classified INCOMPLETE by a scan */
} canfdi_nvm_diag_t;

/* Instance, caller-owned. Fields are readable; bank_state[] and current
 * describe the last scan. */
typedef struct {
  const canfdi_nvm_port_t *port;
  uint32_t seq;          /* sequence number of the current image */
  uint32_t len;          /* payload length of the current image */
  int8_t current;        /* bank of the current image, -1 = none */
  bool scanned;
  uint8_t bank_state[CANFDI_NVM_BANKS]; /* canfdi_nvm_bank_state_t */
  canfdi_nvm_diag_t diag;
} canfdi_nvm_t;

/*
 * CRC-32 (see above) continuation: start with crc = 0xFFFFFFFF, feed data,
 * final value = result ^ 0xFFFFFFFF. Cannot fail by contract (data may be
 * NULL only if len == 0). Cost O(len), two nibble-table steps per byte.
 * Scaling and overflow: polynomial arithmetic over GF(2), no overflow.
 */
uint32_t canfdi_nvm_crc32_update(uint32_t crc, const uint8_t *data, uint32_t len);

/* Complete CRC-32 of a buffer. */
uint32_t canfdi_nvm_crc32(const uint8_t *data, uint32_t len);

/*
 * Bind n to a port (no I/O). Returns CANFDI_OK, or -CANFDI_EINVAL if n or
 * port is NULL, a callback is missing, write_unit is not a power of two up
 * to 16, or bank_bytes cannot hold an empty image (then n is unbound).
 */
int32_t canfdi_nvm_init(canfdi_nvm_t *n, const canfdi_nvm_port_t *port);

/*
 * Scan both banks and copy the payload of the newest valid image into
 * buf[0..cap). Returns the payload length (>= 0); -CANFDI_ENODATA if no
 * bank is valid (see n->bank_state[]); -CANFDI_ERANGE if the image is
 * longer than cap (nothing copied; n->len says how long); -CANFDI_EINVAL
 * for bad arguments; a port error. Cost: see above.
 */
int32_t canfdi_nvm_load(canfdi_nvm_t *n, uint8_t *buf, uint32_t cap);

/*
 * Store data[0..len) as the new current image (scans first if load was
 * never called). Returns CANFDI_OK; -CANFDI_ERANGE if the footprint
 * exceeds bank_bytes (nothing written); -CANFDI_EINVAL for bad arguments;
 * -CANFDI_EIO if the read-back does not validate; a port error. On any
 * failure the instance keeps the previous image as current and the next
 * store rewrites the same target bank; the device holds the previous image
 * or, if the failure came after the commit word (a failing read-back), the
 * new one — never neither. Cost: see above.
 */
int32_t canfdi_nvm_store(canfdi_nvm_t *n, const uint8_t *data, uint32_t len);

#endif /* CANFDI_NVM_H */
