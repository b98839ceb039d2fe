/*
 * canfdi_nvm.c — two-bank power-fail-safe image storage; the manual is the
 * header.
 */
#include "diag/canfdi_nvm.h"

#include "core/canfdi_count.h"

CANFDI_STATIC_ASSERT(CANFDI_CFG_NVM_CHUNK_BYTES >= CANFDI_NVM_HEADER_BYTES, nvm_chunk_holds_header);
CANFDI_STATIC_ASSERT((CANFDI_NVM_HEADER_BYTES % CANFDI_NVM_MAX_WRITE_UNIT) == 0U, nvm_header_aligned);

/* Largest bank the offset arithmetic below handles without overflow. */
#define BANK_BYTES_MAX 0x10000000U

#define CRC32_INIT 0xFFFFFFFFU
#define CRC32_XOROUT 0xFFFFFFFFU

/* CRC-32 of each nibble value, reflected polynomial 0xEDB88320. */
static const uint32_t crc32_nibble[16] = {
    0x00000000U, 0x1DB71064U, 0x3B6E20C8U, 0x26D930ACU, 0x76DC4190U, 0x6B6B51F4U,
    0x4DB26158U, 0x5005713CU, 0xEDB88320U, 0xF00F9344U, 0xD6D6A3E8U, 0xCB61B38CU,
    0x9B64C2B0U, 0x86D3D2D4U, 0xA00AE278U, 0xBDBDF21CU,
};

uint32_t canfdi_nvm_crc32_update(uint32_t crc, const uint8_t *data, uint32_t len)
{
  uint32_t c = crc;
  for (uint32_t i = 0U; i < len; i++) {
    c ^= (uint32_t)data[i];
    c = (c >> 4) ^ crc32_nibble[c & 0x0FU];
    c = (c >> 4) ^ crc32_nibble[c & 0x0FU];
  }
  return c;
}

uint32_t canfdi_nvm_crc32(const uint8_t *data, uint32_t len)
{
  return canfdi_nvm_crc32_update(CRC32_INIT, data, len) ^ CRC32_XOROUT;
}

/* ------------------------------------------------------------ helpers */

/* Round up to a multiple of the write unit (a power of two). */
static uint32_t up(uint32_t x, uint32_t u)
{
  return (x + u - 1U) & ~(u - 1U);
}

typedef struct {
  uint32_t crc_off;
  uint32_t commit_off;
  uint32_t end;
} layout_t;

/* len <= BANK_BYTES_MAX, so nothing here overflows. */
static layout_t layout_of(uint32_t len, uint32_t u)
{
  layout_t l;
  l.crc_off = up(CANFDI_NVM_HEADER_BYTES + len, u);
  l.commit_off = up(l.crc_off + 4U, u);
  l.end = up(l.commit_off + 4U, u);
  return l;
}

static void put_le32(uint8_t *p, uint32_t v)
{
  p[0] = (uint8_t)(v & 0xFFU);
  p[1] = (uint8_t)((v >> 8) & 0xFFU);
  p[2] = (uint8_t)((v >> 16) & 0xFFU);
  p[3] = (uint8_t)(v >> 24);
}

static uint32_t get_le32(const uint8_t *p)
{
  return (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) | ((uint32_t)p[3] << 24);
}

/* a newer than b in serial-number arithmetic (RFC 1982). */
static bool seq_newer(uint32_t a, uint32_t b)
{
  const uint32_t d = a - b; /* unsigned: wraps by definition */
  return (d != 0U) && (d < 0x80000000U);
}

static bool bound(const canfdi_nvm_t *n)
{
  return (n != NULL) && (n->port != NULL);
}

/* Read a little-endian word from a bank. */
static int32_t read_le32(const canfdi_nvm_port_t *p, uint8_t bank, uint32_t off, uint32_t *v)
{
  uint8_t b[4];
  int32_t rc = p->read(p->ctx, bank, off, b, 4U);
  if (rc >= 0) {
    *v = get_le32(b);
    rc = CANFDI_OK;
  }
  return rc;
}

/* CRC register after feeding bank bytes [from, to) read in chunks. */
static int32_t crc_of_bank(const canfdi_nvm_port_t *p, uint8_t bank, uint32_t from, uint32_t to,
                           uint32_t *crc)
{
  uint8_t chunk[CANFDI_CFG_NVM_CHUNK_BYTES];
  int32_t rc = CANFDI_OK;
  uint32_t off = from;
  while ((rc >= 0) && (off < to)) {
    const uint32_t left = to - off;
    const uint32_t k = (left < (uint32_t)sizeof chunk) ? left : (uint32_t)sizeof chunk;
    rc = p->read(p->ctx, bank, off, chunk, k);
    if (rc >= 0) {
      *crc = canfdi_nvm_crc32_update(*crc, chunk, k);
      off += k;
    }
  }
  return (rc >= 0) ? CANFDI_OK : rc;
}

/*
 * Classify one bank; on VALID also report its seq and payload length.
 * Returns a canfdi_nvm_bank_state_t (> 0) or a port error (< 0).
 */
static int32_t validate_bank(const canfdi_nvm_port_t *p, uint8_t bank, uint32_t *seq, uint32_t *len)
{
  uint8_t hdr[CANFDI_NVM_HEADER_BYTES];
  int32_t out = p->read(p->ctx, bank, 0U, hdr, CANFDI_NVM_HEADER_BYTES);
  if (out >= 0) {
    bool erased = true;
    for (uint32_t i = 0U; i < CANFDI_NVM_HEADER_BYTES; i++) {
      erased = erased && (hdr[i] == 0xFFU);
    }
    const uint32_t magic = get_le32(&hdr[0]);
    const uint32_t ver_res = get_le32(&hdr[4]);
    const uint32_t s = get_le32(&hdr[8]);
    const uint32_t l = get_le32(&hdr[12]);
    if (erased) {
      out = (int32_t)CANFDI_NVM_BANK_EMPTY;
    } else if ((magic != CANFDI_NVM_MAGIC) || (ver_res != (uint32_t)CANFDI_NVM_VERSION) ||
               (l > p->bank_bytes) || (layout_of(l, p->write_unit).end > p->bank_bytes)) {
      out = (int32_t)CANFDI_NVM_BANK_CORRUPT;
    } else {
      const layout_t lay = layout_of(l, p->write_unit);
      uint32_t commit = 0U;
      uint32_t stored_crc = 0U;
      uint32_t crc = CRC32_INIT;
      out = read_le32(p, bank, lay.commit_off, &commit);
      if (out >= 0) {
        out = read_le32(p, bank, lay.crc_off, &stored_crc);
      }
      if (out >= 0) {
        crc = canfdi_nvm_crc32_update(crc, hdr, CANFDI_NVM_HEADER_BYTES);
        out = crc_of_bank(p, bank, CANFDI_NVM_HEADER_BYTES, CANFDI_NVM_HEADER_BYTES + l, &crc);
      }
      if (out >= 0) {
        if (commit == 0xFFFFFFFFU) {
          out = (int32_t)CANFDI_NVM_BANK_INCOMPLETE;
        } else if ((commit != CANFDI_NVM_COMMIT) || ((crc ^ CRC32_XOROUT) != stored_crc)) {
          out = (int32_t)CANFDI_NVM_BANK_CORRUPT;
        } else {
          *seq = s;
          *len = l;
          out = (int32_t)CANFDI_NVM_BANK_VALID;
        }
      }
    }
  }
  return out;
}

static int32_t scan(canfdi_nvm_t *n)
{
  int32_t rc = CANFDI_OK;
  uint32_t seq[CANFDI_NVM_BANKS] = {0U, 0U};
  uint32_t len[CANFDI_NVM_BANKS] = {0U, 0U};
  n->current = -1;
  n->scanned = false;
  for (uint8_t b = 0U; (b < CANFDI_NVM_BANKS) && (rc >= 0); b++) {
    n->bank_state[b] = (uint8_t)CANFDI_NVM_BANK_UNKNOWN;
    rc = validate_bank(n->port, b, &seq[b], &len[b]);
    if (rc >= 0) {
      n->bank_state[b] = (uint8_t)rc;
      if (rc == (int32_t)CANFDI_NVM_BANK_CORRUPT) {
        canfdi_count_inc16(&n->diag.corrupt_banks);
      } else if (rc == (int32_t)CANFDI_NVM_BANK_INCOMPLETE) {
        canfdi_count_inc16(&n->diag.incomplete_banks);
      } else {
        /* empty or valid */
      }
    }
  }
  if (rc >= 0) {
    const bool v0 = n->bank_state[0] == (uint8_t)CANFDI_NVM_BANK_VALID;
    const bool v1 = n->bank_state[1] == (uint8_t)CANFDI_NVM_BANK_VALID;
    /* Equal sequence numbers never come from store(); bank 0 then wins,
     * a defined if arbitrary choice. */
    if (v1 && (!v0 || seq_newer(seq[1], seq[0]))) {
      n->current = 1;
    } else if (v0) {
      n->current = 0;
    } else {
      n->current = -1;
    }
    if (n->current >= 0) {
      n->seq = seq[n->current];
      n->len = len[n->current];
    }
    n->scanned = true;
    rc = CANFDI_OK;
  }
  return rc;
}

/* ------------------------------------------------------------ API */

int32_t canfdi_nvm_init(canfdi_nvm_t *n, const canfdi_nvm_port_t *port)
{
  int32_t out = -CANFDI_EINVAL;
  if (n != NULL) {
    n->port = NULL;
    n->seq = 0U;
    n->len = 0U;
    n->current = -1;
    n->scanned = false;
    n->bank_state[0] = (uint8_t)CANFDI_NVM_BANK_UNKNOWN;
    n->bank_state[1] = (uint8_t)CANFDI_NVM_BANK_UNKNOWN;
    n->diag.loads = 0U;
    n->diag.load_failures = 0U;
    n->diag.stores = 0U;
    n->diag.store_failures = 0U;
    n->diag.corrupt_banks = 0U;
    n->diag.incomplete_banks = 0U;
    if ((port != NULL) && (port->read != NULL) && (port->write != NULL) && (port->erase != NULL)) {
      const uint32_t u = port->write_unit;
      const bool unit_ok = (u >= 1U) && (u <= CANFDI_NVM_MAX_WRITE_UNIT) && ((u & (u - 1U)) == 0U);
      if (unit_ok && (port->bank_bytes <= BANK_BYTES_MAX) &&
          (layout_of(0U, u).end <= port->bank_bytes)) {
        n->port = port;
        out = CANFDI_OK;
      }
    }
  }
  return out;
}

int32_t canfdi_nvm_load(canfdi_nvm_t *n, uint8_t *buf, uint32_t cap)
{
  int32_t out = -CANFDI_EINVAL;
  if (bound(n) && ((buf != NULL) || (cap == 0U))) {
    out = scan(n);
    if (out >= 0) {
      if (n->current < 0) {
        out = -CANFDI_ENODATA;
      } else if (n->len > cap) {
        out = -CANFDI_ERANGE;
      } else {
        const canfdi_nvm_port_t *p = n->port;
        const uint8_t bank = (uint8_t)n->current;
        uint8_t hdr[CANFDI_NVM_HEADER_BYTES];
        uint32_t stored_crc = 0U;
        out = p->read(p->ctx, bank, 0U, hdr, CANFDI_NVM_HEADER_BYTES);
        if ((out >= 0) && (n->len > 0U)) {
          out = p->read(p->ctx, bank, CANFDI_NVM_HEADER_BYTES, buf, n->len);
        }
        if (out >= 0) {
          out = read_le32(p, bank, layout_of(n->len, p->write_unit).crc_off, &stored_crc);
        }
        if (out >= 0) {
          /* The copy handed out is checked again, not only the bank. */
          uint32_t crc = canfdi_nvm_crc32_update(CRC32_INIT, hdr, CANFDI_NVM_HEADER_BYTES);
          crc = canfdi_nvm_crc32_update(crc, buf, n->len) ^ CRC32_XOROUT;
          out = ((crc == stored_crc) && (get_le32(&hdr[12]) == n->len)) ? (int32_t)n->len
                                                                         : -CANFDI_EIO;
        }
      }
    }
    if (out >= 0) {
      canfdi_count_inc16(&n->diag.loads);
    } else {
      canfdi_count_inc16(&n->diag.load_failures);
    }
  }
  return out;
}

/* Write src[0..len) at off, the last partial unit padded with 0xFF. */
static int32_t write_padded(const canfdi_nvm_port_t *p, uint8_t bank, uint32_t off,
                            const uint8_t *src, uint32_t len)
{
  const uint32_t u = p->write_unit;
  const uint32_t full = len & ~(u - 1U);
  int32_t rc = CANFDI_OK;
  if (full > 0U) {
    rc = p->write(p->ctx, bank, off, src, full);
  }
  if ((rc >= 0) && (full < len)) {
    uint8_t tail[CANFDI_NVM_MAX_WRITE_UNIT];
    for (uint32_t i = 0U; i < u; i++) {
      tail[i] = ((full + i) < len) ? src[full + i] : 0xFFU;
    }
    rc = p->write(p->ctx, bank, off + full, tail, u);
  }
  return (rc >= 0) ? CANFDI_OK : rc;
}

int32_t canfdi_nvm_store(canfdi_nvm_t *n, const uint8_t *data, uint32_t len)
{
  int32_t out = -CANFDI_EINVAL;
  if (bound(n) && ((data != NULL) || (len == 0U))) {
    const canfdi_nvm_port_t *p = n->port;
    if ((len > p->bank_bytes) || (layout_of(len, p->write_unit).end > p->bank_bytes)) {
      out = -CANFDI_ERANGE;
    } else {
      out = n->scanned ? CANFDI_OK : scan(n);
    }
    if (out >= 0) {
      const layout_t lay = layout_of(len, p->write_unit);
      const uint8_t target = (n->current == 0) ? 1U : 0U;
      const uint32_t seq = (n->current >= 0) ? (n->seq + 1U) : 1U;
      uint8_t hdr[CANFDI_NVM_HEADER_BYTES];
      uint8_t word[4];
      uint32_t crc = 0U;
      put_le32(&hdr[0], CANFDI_NVM_MAGIC);
      put_le32(&hdr[4], (uint32_t)CANFDI_NVM_VERSION);
      put_le32(&hdr[8], seq);
      put_le32(&hdr[12], len);
      crc = canfdi_nvm_crc32_update(CRC32_INIT, hdr, CANFDI_NVM_HEADER_BYTES);
      crc = canfdi_nvm_crc32_update(crc, data, len) ^ CRC32_XOROUT;
      n->bank_state[target] = (uint8_t)CANFDI_NVM_BANK_UNKNOWN;

      out = p->erase(p->ctx, target);
      if (out >= 0) {
        out = p->write(p->ctx, target, 0U, hdr, CANFDI_NVM_HEADER_BYTES);
      }
      if (out >= 0) {
        out = write_padded(p, target, CANFDI_NVM_HEADER_BYTES, data, len);
      }
      if (out >= 0) {
        put_le32(word, crc);
        out = write_padded(p, target, lay.crc_off, word, 4U);
      }
      if (out >= 0) {
        /* The commit: from here on the new image exists. */
        put_le32(word, CANFDI_NVM_COMMIT);
        out = write_padded(p, target, lay.commit_off, word, 4U);
      }
      if (out >= 0) {
        uint32_t vseq = 0U;
        uint32_t vlen = 0U;
        out = validate_bank(p, target, &vseq, &vlen);
        if (out >= 0) {
          n->bank_state[target] = (uint8_t)out;
          out = ((out == (int32_t)CANFDI_NVM_BANK_VALID) && (vseq == seq) && (vlen == len))
                    ? CANFDI_OK
                    : -CANFDI_EIO;
        }
      }
      if (out >= 0) {
        n->current = (int8_t)target;
        n->seq = seq;
        n->len = len;
        canfdi_count_inc16(&n->diag.stores);
      } else {
        canfdi_count_inc16(&n->diag.store_failures);
      }
    }
  }
  return out;
}
