/*
 * canfdi_nvm_file.c — host NVM port on a regular file; the manual is the
 * header. Needs _POSIX_C_SOURCE >= 200809L from the command line (the
 * unit-test build pre-includes assert.h, which fixes the feature macros
 * before this file could define them).
 */
#include "port/linux/canfdi_nvm_file.h"

#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <unistd.h>

#define PATH_BYTES 4096U
#define ERASE_CHUNK 256U
#define BANK_BYTES_MAX 0x10000000U

static int32_t io_fail(canfdi_nvm_file_t *f)
{
  f->last_errno = errno;
  if (f->io_errors < UINT32_MAX) {
    f->io_errors++;
  }
  return -CANFDI_EIO;
}

/* Full pwrite at an absolute file offset, retrying short writes/EINTR. */
static int32_t pwrite_all(canfdi_nvm_file_t *f, int fd, const uint8_t *buf, size_t len, off_t at)
{
  int32_t rc = CANFDI_OK;
  size_t done = 0U;
  while ((rc == CANFDI_OK) && (done < len)) {
    const ssize_t w = pwrite(fd, buf + done, len - done, at + (off_t)done);
    if (w > 0) {
      done += (size_t)w;
    } else if ((w < 0) && (errno == EINTR)) {
      /* retry */
    } else {
      rc = io_fail(f);
    }
  }
  return rc;
}

static int32_t sync_fd(canfdi_nvm_file_t *f, int fd)
{
  int32_t rc = CANFDI_OK;
  if (fdatasync(fd) != 0) {
    rc = io_fail(f);
  }
  return rc;
}

static bool range_ok(const canfdi_nvm_file_t *f, uint8_t bank, uint32_t offset, uint32_t len)
{
  return (f->fd >= 0) && (bank < CANFDI_NVM_BANKS) && (offset <= f->bank_bytes) &&
         (len <= (f->bank_bytes - offset));
}

static off_t file_offset(const canfdi_nvm_file_t *f, uint8_t bank, uint32_t offset)
{
  return ((off_t)bank * (off_t)f->bank_bytes) + (off_t)offset;
}

static int32_t file_read(void *ctx, uint8_t bank, uint32_t offset, uint8_t *buf, uint32_t len)
{
  canfdi_nvm_file_t *f = (canfdi_nvm_file_t *)ctx;
  int32_t rc = -CANFDI_EINVAL;
  if ((f != NULL) && ((buf != NULL) || (len == 0U)) && range_ok(f, bank, offset, len)) {
    const off_t at = file_offset(f, bank, offset);
    size_t done = 0U;
    rc = CANFDI_OK;
    while ((rc == CANFDI_OK) && (done < len)) {
      const ssize_t r = pread(f->fd, buf + done, (size_t)len - done, at + (off_t)done);
      if (r > 0) {
        done += (size_t)r;
      } else if ((r < 0) && (errno == EINTR)) {
        /* retry */
      } else {
        /* r == 0: end of file inside a bank, i.e. the file shrank */
        if (r == 0) {
          errno = 0;
        }
        rc = io_fail(f);
      }
    }
  }
  return rc;
}

static int32_t file_write(void *ctx, uint8_t bank, uint32_t offset, const uint8_t *buf, uint32_t len)
{
  canfdi_nvm_file_t *f = (canfdi_nvm_file_t *)ctx;
  int32_t rc = -CANFDI_EINVAL;
  if ((f != NULL) && ((buf != NULL) || (len == 0U)) && range_ok(f, bank, offset, len)) {
    rc = pwrite_all(f, f->fd, buf, len, file_offset(f, bank, offset));
    if (rc == CANFDI_OK) {
      rc = sync_fd(f, f->fd);
    }
  }
  return rc;
}

static int32_t erase_range(canfdi_nvm_file_t *f, int fd, off_t at, uint32_t len)
{
  uint8_t ff[ERASE_CHUNK];
  int32_t rc = CANFDI_OK;
  uint32_t done = 0U;
  memset(ff, 0xFF, sizeof ff);
  while ((rc == CANFDI_OK) && (done < len)) {
    const uint32_t k = ((len - done) < ERASE_CHUNK) ? (len - done) : ERASE_CHUNK;
    rc = pwrite_all(f, fd, ff, k, at + (off_t)done);
    done += k;
  }
  return rc;
}

static int32_t file_erase(void *ctx, uint8_t bank)
{
  canfdi_nvm_file_t *f = (canfdi_nvm_file_t *)ctx;
  int32_t rc = -CANFDI_EINVAL;
  if ((f != NULL) && range_ok(f, bank, 0U, 0U)) {
    rc = erase_range(f, f->fd, file_offset(f, bank, 0U), f->bank_bytes);
    if (rc == CANFDI_OK) {
      rc = sync_fd(f, f->fd);
    }
  }
  return rc;
}

/* fsync the directory holding path, so a rename into it is durable. */
static int32_t sync_dir_of(canfdi_nvm_file_t *f, const char *path)
{
  char dir[PATH_BYTES];
  const char *slash = strrchr(path, '/');
  int32_t rc = CANFDI_OK;
  if (slash == NULL) {
    dir[0] = '.';
    dir[1] = '\0';
  } else if (slash == path) {
    dir[0] = '/';
    dir[1] = '\0';
  } else {
    const size_t n = (size_t)(slash - path);
    memcpy(dir, path, n);
    dir[n] = '\0';
  }
  const int dfd = open(dir, O_RDONLY);
  if (dfd < 0) {
    rc = io_fail(f);
  } else {
    if (fsync(dfd) != 0) {
      rc = io_fail(f);
    }
    (void)close(dfd);
  }
  return rc;
}

/* Create path as a complete erased image via "<path>.tmp" and rename. */
static int32_t create_erased(canfdi_nvm_file_t *f, const char *path)
{
  char tmp[PATH_BYTES];
  const size_t n = strlen(path);
  int32_t rc = CANFDI_OK;
  memcpy(tmp, path, n);
  memcpy(tmp + n, ".tmp", 5U);
  const int fd = open(tmp, O_RDWR | O_CREAT | O_TRUNC, 0644);
  if (fd < 0) {
    rc = io_fail(f);
  } else {
    rc = erase_range(f, fd, 0, 2U * f->bank_bytes);
    if (rc == CANFDI_OK) {
      rc = sync_fd(f, fd);
    }
    if (close(fd) != 0) {
      rc = io_fail(f);
    }
    if ((rc == CANFDI_OK) && (rename(tmp, path) != 0)) {
      rc = io_fail(f);
    }
    if (rc == CANFDI_OK) {
      rc = sync_dir_of(f, path);
    } else {
      (void)unlink(tmp);
    }
  }
  return rc;
}

int32_t canfdi_nvm_file_open(canfdi_nvm_file_t *f, const char *path, uint32_t bank_bytes,
                             uint32_t flags)
{
  int32_t rc = -CANFDI_EINVAL;
  if (f != NULL) {
    f->fd = -1;
    f->last_errno = 0;
    f->io_errors = 0U;
    f->bank_bytes = bank_bytes;
    f->port.ctx = f;
    f->port.read = file_read;
    f->port.write = file_write;
    f->port.erase = file_erase;
    f->port.bank_bytes = bank_bytes;
    f->port.write_unit = 1U;
    if ((path != NULL) && (path[0] != '\0') && (strlen(path) < (PATH_BYTES - 5U)) &&
        (bank_bytes >= 1U) && (bank_bytes <= BANK_BYTES_MAX) &&
        ((flags & ~CANFDI_NVM_FILE_CREATE) == 0U)) {
      const bool create = (flags & CANFDI_NVM_FILE_CREATE) != 0U;
      int fd = open(path, O_RDWR);
      rc = CANFDI_OK;
      if ((fd < 0) && (errno == ENOENT)) {
        if (create) {
          rc = create_erased(f, path);
          if (rc == CANFDI_OK) {
            fd = open(path, O_RDWR);
            if (fd < 0) {
              rc = io_fail(f);
            }
          }
        } else {
          f->last_errno = errno;
          rc = -CANFDI_ENODATA;
        }
      } else if (fd < 0) {
        rc = io_fail(f);
      } else {
        /* opened */
      }
      if (rc == CANFDI_OK) {
        struct stat st;
        if (fstat(fd, &st) != 0) {
          rc = io_fail(f);
        } else if (!S_ISREG(st.st_mode) || (st.st_size != (off_t)2 * (off_t)bank_bytes)) {
          rc = -CANFDI_ERANGE;
        } else {
          f->fd = fd;
        }
        if (rc != CANFDI_OK) {
          (void)close(fd);
        }
      }
    }
  }
  return rc;
}

void canfdi_nvm_file_close(canfdi_nvm_file_t *f)
{
  if ((f != NULL) && (f->fd >= 0)) {
    (void)close(f->fd);
    f->fd = -1;
  }
}
