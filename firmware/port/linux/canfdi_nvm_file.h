/*
 * canfdi_nvm_file.h — the host (Linux) NVM port of canfdi_nvm: both banks
 * in one regular file.
 *
 * File layout: bank 0 at offset 0, bank 1 at offset bank_bytes, file size
 * exactly 2 * bank_bytes; an erased byte is 0xFF, as in flash.
 *
 * Durability and ordering, which canfdi_nvm's power-fail argument needs
 * ("each port call is complete and durable before it returns, calls take
 * effect in order"): every write and erase is pwrite() followed by
 * fdatasync() before returning, so a kill -9 or a power cut at any moment
 * leaves the file with a prefix of the calls applied (the last one possibly
 * torn, which canfdi_nvm tolerates). Creating a file (CANFDI_NVM_FILE_CREATE
 * on a missing file) writes a complete erased image to "<path>.tmp",
 * fdatasyncs it, rename()s it into place and fsyncs the directory, so an
 * interrupted creation never leaves a half-sized file under `path`.
 *
 * Errors: a missing file without CREATE gives -CANFDI_ENODATA; a file whose
 * size is not 2 * bank_bytes (truncated, or another geometry) gives
 * -CANFDI_ERANGE and is left untouched (deleting it is the caller's
 * decision: it may still hold data); system call failures give -CANFDI_EIO
 * (errno kept in last_errno). Damaged contents are not an open error: the
 * loader of canfdi_nvm classifies the banks.
 *
 * Not for firmware targets (POSIX I/O); not thread-safe; one process per
 * file (no locking). write_unit is 1. Cost: one pread/pwrite per call plus
 * one fdatasync per write/erase (milliseconds on a disk, which is why
 * canfdi_nvm_store belongs outside the 1 ms step). Memory: the instance
 * (about 48 bytes), 256 bytes of stack for erase.
 * Build: needs _POSIX_C_SOURCE >= 200809L (mk/nvm.mk sets it).
 */
#ifndef CANFDI_NVM_FILE_H
#define CANFDI_NVM_FILE_H

#include "diag/canfdi_nvm.h"

#define CANFDI_NVM_FILE_CREATE 1U /* open flag: create an erased file if missing */

typedef struct {
  int fd;              /* -1 when closed */
  int last_errno;      /* errno of the last failing system call, 0 if none */
  uint32_t bank_bytes;
  uint32_t io_errors;  /* monotone: failing system calls */
  canfdi_nvm_port_t port; /* pass &port to canfdi_nvm_init */
} canfdi_nvm_file_t;

/*
 * Open (and with CANFDI_NVM_FILE_CREATE create) the bank file `path` for
 * banks of bank_bytes each (1..2^28) and fill f->port. Returns CANFDI_OK;
 * -CANFDI_EINVAL (NULL, bank_bytes out of range, unknown flags, path too
 * long for "<path>.tmp" in PATH_MAX-ish 4096 bytes); -CANFDI_ENODATA; -CANFDI_ERANGE;
 * -CANFDI_EIO (see above). On failure f->fd is -1.
 */
int32_t canfdi_nvm_file_open(canfdi_nvm_file_t *f, const char *path, uint32_t bank_bytes,
                             uint32_t flags);

/* Close the file (no-op if closed or NULL). */
void canfdi_nvm_file_close(canfdi_nvm_file_t *f);

#endif /* CANFDI_NVM_FILE_H */
