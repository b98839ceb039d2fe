/*
 * fuzz_export_main.c — `fuzz-export-app-rx OUT.log INPUT...`: runs each
 * fuzz_app_rx input (files, or every file of a directory) through the
 * harness once, as libFuzzer would, and writes the frames and steps it
 * drives to OUT.log (format: fuzz_export.h), a reset line before each
 * input. The harness's invariants are checked on the way (a broken one
 * aborts, as in fuzzing). Prints how many inputs and steps it wrote.
 * Exit status: 0 written, 2 usage or a file that cannot be read.
 */
#include <dirent.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "fuzz_export.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

FILE *fz_export_out;
static unsigned long n_inputs;

static int run_file(const char *path)
{
  static uint8_t buf[1U << 20];
  FILE *f = fopen(path, "rb");
  size_t n;
  if (f == NULL) {
    fprintf(stderr, "fuzz-export-app-rx: %s: cannot open\n", path);
    return 2;
  }
  n = fread(buf, 1U, sizeof buf, f);
  (void)fclose(f);
  fz_export_line(0U, FZ_EXPORT_RESET_ID, NULL, 0U);
  (void)LLVMFuzzerTestOneInput(buf, n);
  n_inputs++;
  return 0;
}

static int cmp_str(const void *a, const void *b)
{
  return strcmp(*(const char *const *)a, *(const char *const *)b);
}

/* A directory's regular files in name order (the log is reproducible). */
static int run_dir(const char *dir)
{
  DIR *d = opendir(dir);
  struct dirent *e;
  char **names = NULL;
  size_t n = 0U;
  size_t cap = 0U;
  size_t i;
  int rc = 0;
  if (d == NULL) {
    fprintf(stderr, "fuzz-export-app-rx: %s: cannot open the directory\n", dir);
    return 2;
  }
  while ((e = readdir(d)) != NULL) {
    if (e->d_name[0] == '.') {
      continue;
    }
    if (n == cap) {
      cap = cap ? 2U * cap : 64U;
      names = realloc(names, cap * sizeof *names);
      if (names == NULL) {
        abort();
      }
    }
    names[n] = malloc(strlen(dir) + strlen(e->d_name) + 2U);
    if (names[n] == NULL) {
      abort();
    }
    sprintf(names[n], "%s/%s", dir, e->d_name);
    n++;
  }
  (void)closedir(d);
  qsort(names, n, sizeof *names, cmp_str);
  for (i = 0U; i < n; i++) {
    struct stat st;
    if ((rc == 0) && (stat(names[i], &st) == 0) && S_ISREG(st.st_mode)) {
      rc = run_file(names[i]);
    }
    free(names[i]);
  }
  free(names);
  return rc;
}

int main(int argc, char **argv)
{
  int i;
  int rc = 0;
  if ((argc < 3) || (strcmp(argv[1], "-h") == 0) || (strcmp(argv[1], "--help") == 0)) {
    fprintf(stderr, "usage: fuzz-export-app-rx OUT.log INPUT_FILE_OR_DIR...\n"
                    "  writes the frames and steps each fuzz_app_rx input drives (tests/fuzz/fuzz_export.h)\n");
    return 2;
  }
  fz_export_out = fopen(argv[1], "w");
  if (fz_export_out == NULL) {
    fprintf(stderr, "fuzz-export-app-rx: %s: cannot write\n", argv[1]);
    return 2;
  }
  for (i = 2; (i < argc) && (rc == 0); i++) {
    struct stat st;
    if (stat(argv[i], &st) != 0) {
      fprintf(stderr, "fuzz-export-app-rx: %s: no such file or directory\n", argv[i]);
      rc = 2;
    } else if (S_ISDIR(st.st_mode)) {
      rc = run_dir(argv[i]);
    } else {
      rc = run_file(argv[i]);
    }
  }
  if (fclose(fz_export_out) != 0) {
    fprintf(stderr, "fuzz-export-app-rx: %s: write error\n", argv[1]);
    rc = 2;
  }
  if (rc == 0) {
    printf("fuzz-export-app-rx: %lu inputs -> %s\n", n_inputs, argv[1]);
  }
  return rc;
}
