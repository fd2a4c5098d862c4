/* fuzz_util.c — temporary files and the status check of the fuzz harnesses. */
#define _DEFAULT_SOURCE
#include "fuzz_util.h"

#include "bs_shim.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

void fuzz_write_temp(const uint8_t *data, size_t size, const char *suffix, char *path, size_t n) {
  snprintf(path, n, "/tmp/bs_fuzz_XXXXXX%s", suffix);
  int fd = mkstemps(path, (int)strlen(suffix));
  if (fd < 0) {
    perror("fuzz: mkstemps");
    abort();
  }
  size_t done = 0;
  while (done < size) {
    ssize_t w = write(fd, data + done, size - done);
    if (w <= 0) {
      perror("fuzz: write");
      abort();
    }
    done += (size_t)w;
  }
  close(fd);
}

void fuzz_check(const char *reader, int rc, const bs_error *err) {
  if (rc == 0) return;
  int proper = rc < 0 && rc > BS_EINTERNAL && err->msg[0] != '\0';
  if (proper) return;
  fprintf(stderr, "fuzz %s: status %d (%s) with message \"%s\"\n", reader, rc, bs_status_name(rc), err->msg);
  abort();
}

void fuzz_file(const uint8_t *data, size_t size, const char *suffix, const char *name, fuzz_reader read) {
  char path[64];
  fuzz_write_temp(data, size, suffix, path, sizeof path);
  bs_error err = {0};
  int rc = read(path, &err);
  remove(path);
  fuzz_check(name, rc, &err);
}

int fuzz_read_surface(const char *path, bs_error *err) {
  double *pts = NULL;
  int32_t *tris = NULL;
  int64_t np = 0, nt = 0;
  int rc = bs_shim_read_surface(path, &pts, &np, &tris, &nt, err);
  bs_shim_free(pts);
  bs_shim_free(tris);
  return rc;
}
