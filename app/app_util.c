#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "app.h"

int bs_app_usage_error(const char *cmd, const char *fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  fprintf(stderr, "bigstep %s: ", cmd);
  vfprintf(stderr, fmt, ap);
  fprintf(stderr, " (see 'bigstep %s --help')\n", cmd);
  va_end(ap);
  return BS_EXIT_USAGE;
}

int bs_app_parse_double(const char *s, double *out) {
  if (!s || !*s) return -1;
  char *end;
  errno = 0;
  double v = strtod(s, &end);
  if (*end || errno || !isfinite(v)) return -1;
  *out = v;
  return 0;
}

int bs_app_parse_int(const char *s, long lo, long hi, int *out) {
  if (!s || !*s) return -1;
  char *end;
  errno = 0;
  long v = strtol(s, &end, 10);
  if (*end || errno || v < lo || v > hi) return -1;
  *out = (int)v;
  return 0;
}

/* "box:8", "box:8x4x2", "box:8x4x2:1x0.5x0.25" */
static int parse_box(const char *spec, int n[3], double len[3], bs_error *err) {
  const char *p = spec + 4;
  n[0] = n[1] = n[2] = 0;
  len[0] = len[1] = len[2] = 1.0;
  char buf[256];
  snprintf(buf, sizeof buf, "%s", p);
  char *cells = buf, *lens = strchr(buf, ':');
  if (lens) *lens++ = '\0';
  int k = 0;
  for (char *tok = strtok(cells, "x"); tok; tok = strtok(NULL, "x")) {
    if (k >= 3 || bs_app_parse_int(tok, 1, 4096, &n[k]) != 0)
      return bs_error_set(err, BS_EINPUT, "bad box spec '%s': cells must be NX or NXxNYxNZ, each 1..4096", spec);
    k++;
  }
  if (k == 1) n[1] = n[2] = n[0];
  else if (k != 3) return bs_error_set(err, BS_EINPUT, "bad box spec '%s': cells must be NX or NXxNYxNZ", spec);
  if (lens) {
    k = 0;
    for (char *tok = strtok(lens, "x"); tok; tok = strtok(NULL, "x")) {
      if (k >= 3 || bs_app_parse_double(tok, &len[k]) != 0 || len[k] <= 0)
        return bs_error_set(err, BS_EINPUT, "bad box spec '%s': lengths must be positive numbers", spec);
      k++;
    }
    if (k == 1) len[1] = len[2] = len[0];
    else if (k != 3) return bs_error_set(err, BS_EINPUT, "bad box spec '%s': lengths must be L or LXxLYxLZ", spec);
  }
  return 0;
}

int bs_app_load_mesh(const char *spec, double size, int refine, bs_mesh **out, bs_error *err) {
  *out = NULL;
  if (strncmp(spec, "box:", 4) == 0) {
    int n[3];
    double len[3], lo[3] = {0, 0, 0};
    int st = parse_box(spec, n, len, err);
    if (st) return st;
    bs_mesh *m = NULL;
    st = bs_mesh_create_box(lo, len, n[0], n[1], n[2], &m, err);
    if (st) return st;
    for (int i = 0; i < refine; i++) {
      bs_mesh *f = NULL;
      st = bs_mesh_refine(m, &f, err);
      bs_mesh_destroy(&m);
      if (st) return st;
      m = f;
    }
    *out = m;
    return 0;
  }
  bs_mesh_read_opts o = {.size = size, .refine = refine};
  return bs_mesh_read(spec, &o, out, err);
}

int bs_app_write_mesh(const bs_mesh *m, const char *path, bs_error *err) {
  const char *dot = strrchr(path, '.');
  if (dot && strcmp(dot, ".msh") == 0) return bs_mesh_write_msh(m, NULL, path, err);
  if (dot && strcmp(dot, ".vtu") == 0) return bs_mesh_write_vtu(m, NULL, path, err);
  return bs_error_set(err, BS_EINPUT, "cannot write '%s': the output extension must be .msh or .vtu", path);
}
