/* fuzz_util.c — temporary files and the status check of the fuzz harnesses. */
#define _DEFAULT_SOURCE
#include "fuzz_util.h"

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
