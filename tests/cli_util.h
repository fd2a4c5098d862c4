/* cli_util.h — runs a shell command from a test and captures its output. */
#ifndef BS_TEST_CLI_UTIL_H
#define BS_TEST_CLI_UTIL_H

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>

/* Runs cmd with stderr merged into stdout; *out receives the output (malloc'ed,
 * the caller frees). Returns the exit status, or -1 if it did not exit. */
static inline int bs_test_run(const char *cmd, char **out) {
  size_t len = strlen(cmd) + 16;
  char *full = malloc(len);
  snprintf(full, len, "%s 2>&1", cmd);
  FILE *p = popen(full, "r");
  free(full);
  size_t cap = 1 << 16, n = 0;
  char *buf = malloc(cap);
  if (p) {
    size_t got;
    while ((got = fread(buf + n, 1, cap - n - 1, p)) > 0) {
      n += got;
      if (cap - n < 4096) {
        cap *= 2;
        buf = realloc(buf, cap);
      }
    }
  }
  buf[n] = '\0';
  *out = buf;
  if (!p) return -1;
  int st = pclose(p);
  return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}

/* The row under the "method ..." header of `bigstep run`'s summary
 * (method steps s/frame dofs solves/step failed ...): *solves and *failed.
 * Returns 0, or -1 when out holds no such row. */
static inline int bs_test_summary_row(const char *out, double *solves, long *failed) {
  const char *p = strstr(out, "\nmethod ");
  if (!p || !(p = strchr(p + 1, '\n'))) return -1;
  char m[32];
  int steps;
  double spf;
  long dofs;
  return sscanf(p + 1, "%31s %d %lf %ld %lf %ld", m, &steps, &spf, &dofs, solves, failed) == 6 ? 0 : -1;
}

#endif
