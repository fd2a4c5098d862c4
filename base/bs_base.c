#define _POSIX_C_SOURCE 200809L
#define _DEFAULT_SOURCE /* madvise, MADV_HUGEPAGE */
#include "bs_base.h"

#include <stdint.h>
#include <sys/mman.h>

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <errno.h>
#include <math.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

void bs_error_clear(bs_error *err) {
  if (!err) return;
  err->code = 0;
  err->msg[0] = '\0';
}

int bs_error_set(bs_error *err, int code, const char *fmt, ...) {
  if (!err) return code;
  err->code = code;
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(err->msg, sizeof err->msg, fmt, ap);
  va_end(ap);
  return code;
}

void bs_error_prefix(bs_error *err, const char *fmt, ...) {
  if (!err) return;
  char pre[BS_ERROR_MSG], old[BS_ERROR_MSG];
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(pre, sizeof pre, fmt, ap);
  va_end(ap);
  memcpy(old, err->msg, sizeof old);
  size_t np = strlen(pre);
  if (np > sizeof err->msg - 3) np = sizeof err->msg - 3;
  memcpy(err->msg, pre, np);
  err->msg[np] = ':';
  err->msg[np + 1] = ' ';
  size_t room = sizeof err->msg - np - 2;
  size_t no = strnlen(old, room - 1);
  memcpy(err->msg + np + 2, old, no);
  err->msg[np + 2 + no] = '\0';
}

const char *bs_status_name(int code) {
  switch (code) {
  case BS_OK: return "ok";
  case BS_EIO: return "io";
  case BS_EINPUT: return "input";
  case BS_ENOMEM: return "memory";
  case BS_ENUMERIC: return "numeric";
  case BS_EGMSH: return "gmsh";
  case BS_EINTERNAL: return "internal";
  default: return code > 0 ? "warning" : "error";
  }
}

double bs_seconds(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

#ifndef BS_VERSION_STRING
#error "BS_VERSION_STRING is set by base/CMakeLists.txt"
#endif
const char *bs_version(void) { return BS_VERSION_STRING; }

size_t bs_peak_rss(void) {
  struct rusage self, children;
  if (getrusage(RUSAGE_SELF, &self) != 0) return 0;
  long kib = self.ru_maxrss; /* Linux reports KiB */
  if (getrusage(RUSAGE_CHILDREN, &children) == 0 && children.ru_maxrss > kib) kib = children.ru_maxrss;
  return (size_t)kib * 1024u;
}

double bs_machine_memory(void) {
  const long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGESIZE);
  return pages > 0 && page > 0 ? (double)pages * (double)page : 0.0;
}

void *bs_calloc(size_t n, size_t size, const char *what, bs_error *err) {
  void *p = calloc(n ? n : 1, size ? size : 1);
  if (!p) bs_error_set(err, BS_ENOMEM, "out of memory allocating %zu x %zu bytes for %s", n, size, what);
  return p;
}

void *bs_calloc_large(size_t n, size_t size, const char *what, bs_error *err) {
  const size_t huge = (size_t)2 << 20;
  if (n == 0 || size == 0 || n > SIZE_MAX / size || n * size < 4 * huge) return bs_calloc(n, size, what, err);
  const size_t bytes = n * size;
  void *p = NULL;
  if (posix_memalign(&p, huge, bytes) != 0 || !p) {
    bs_error_set(err, BS_ENOMEM, "out of memory allocating %zu x %zu bytes for %s", n, size, what);
    return NULL;
  }
#ifdef MADV_HUGEPAGE
  (void)madvise(p, bytes, MADV_HUGEPAGE); /* advice only: pages stay 4 KiB if refused */
#endif
  memset(p, 0, bytes);
  return p;
}

int bs_cmp_i32(const void *a, const void *b) {
  const int32_t x = *(const int32_t *)a, y = *(const int32_t *)b;
  return (x > y) - (x < y);
}

int bs_mkdir_p(const char *dir, bs_error *err) {
  char buf[4096];
  if (!dir || !*dir) return bs_error_set(err, BS_EINPUT, "cannot create a folder with an empty name");
  if (snprintf(buf, sizeof buf, "%s", dir) >= (int)sizeof buf)
    return bs_error_set(err, BS_EINPUT, "folder name too long (%zu characters)", strlen(dir));
  for (char *p = buf + 1; *p; p++)
    if (*p == '/') {
      *p = 0;
      if (mkdir(buf, 0755) && errno != EEXIST) return bs_error_set(err, BS_EIO, "cannot create folder '%s'", buf);
      *p = '/';
    }
  if (mkdir(buf, 0755) && errno != EEXIST) return bs_error_set(err, BS_EIO, "cannot create folder '%s'", buf);
  return 0;
}

int bs_parse_double(const char *s, double *out) {
  if (!s || !*s) return -1;
  char *end;
  errno = 0;
  double v = strtod(s, &end);
  if (*end || errno || !isfinite(v)) return -1;
  *out = v;
  return 0;
}

int bs_parse_int(const char *s, long lo, long hi, int *out) {
  if (!s || !*s) return -1;
  char *end;
  errno = 0;
  long v = strtol(s, &end, 10);
  if (*end || errno || v < lo || v > hi) return -1;
  *out = (int)v;
  return 0;
}

uint64_t bs_fnv1a(uint64_t h, const void *p, size_t n) {
  const unsigned char *b = p;
  for (size_t i = 0; i < n; i++) h = (h ^ b[i]) * 1099511628211ULL;
  return h;
}
