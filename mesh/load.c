/* load.c — a mesh from a path or a structured-box spec, then refined; the
 * bounding box of a point set. */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "mesh_internal.h"

int bs_mesh_create_box_refined(const double size[3], const int cells[3], int refine, bs_mesh **out,
                               bs_error *err) {
  *out = NULL;
  const double lo[3] = {0, 0, 0};
  bs_mesh *m = NULL;
  char what[96];
  snprintf(what, sizeof what, "box of %d x %d x %d cells", cells[0], cells[1], cells[2]);
  int st = bs__check_refined_count(6.0 * cells[0] * cells[1] * cells[2], refine, NULL, what, err);
  if (st) return st;
  st = bs_mesh_create_box(lo, size, cells[0], cells[1], cells[2], &m, err);
  for (int r = 0; !st && r < refine; r++) {
    bs_mesh *f = NULL;
    st = bs_mesh_refine(m, &f, err);
    bs_mesh_destroy(&m);
    m = f;
  }
  if (st) {
    bs_mesh_destroy(&m);
    return st;
  }
  *out = m;
  return 0;
}

int bs_mesh_box_spec_parse(const char *spec, int n[3], double len[3], bs_error *err) {
  n[0] = n[1] = n[2] = 0;
  len[0] = len[1] = len[2] = 1.0;
  if (strncmp(spec, "box:", 4) != 0) return bs_error_set(err, BS_EINPUT, "bad box spec '%s': must start with 'box:'", spec);
  char buf[256];
  snprintf(buf, sizeof buf, "%s", spec + 4);
  char *cells = buf, *lens = strchr(buf, ':'), *save = NULL;
  if (lens) *lens++ = '\0';
  int k = 0;
  for (char *tok = strtok_r(cells, "x", &save); tok; tok = strtok_r(NULL, "x", &save)) {
    if (k >= 3 || bs_parse_int(tok, 1, 4096, &n[k]))
      return bs_error_set(err, BS_EINPUT, "bad box spec '%s': cells must be NX or NXxNYxNZ, each 1..4096", spec);
    k++;
  }
  if (k == 1) n[1] = n[2] = n[0];
  else if (k != 3) return bs_error_set(err, BS_EINPUT, "bad box spec '%s': cells must be NX or NXxNYxNZ", spec);
  if (!lens) return 0;
  k = 0;
  for (char *tok = strtok_r(lens, "x", &save); tok; tok = strtok_r(NULL, "x", &save)) {
    if (k >= 3 || bs_parse_double(tok, &len[k]) || !(len[k] > 0))
      return bs_error_set(err, BS_EINPUT, "bad box spec '%s': lengths must be positive numbers", spec);
    k++;
  }
  if (k == 1) len[1] = len[2] = len[0];
  else if (k != 3) return bs_error_set(err, BS_EINPUT, "bad box spec '%s': lengths must be L or LXxLYxLZ", spec);
  return 0;
}

int bs_mesh_load(const char *spec, const bs_mesh_read_opts *opts, bs_mesh **out, bs_error *err) {
  *out = NULL;
  bs_mesh_read_opts o = {0};
  if (opts) o = *opts;
  if (strncmp(spec, "box:", 4) != 0) return bs_mesh_read(spec, &o, out, err);
  int n[3];
  double len[3];
  int st = bs_mesh_box_spec_parse(spec, n, len, err);
  return st ? st : bs_mesh_create_box_refined(len, n, o.refine, out, err);
}

void bs_bbox(int64_t n, const double *x, double lo[3], double hi[3]) {
  for (int k = 0; k < 3; k++) lo[k] = hi[k] = n > 0 ? x[k] : 0.0;
  for (int64_t v = 1; v < n; v++)
    for (int k = 0; k < 3; k++) {
      lo[k] = fmin(lo[k], x[3 * v + k]);
      hi[k] = fmax(hi[k], x[3 * v + k]);
    }
}

double bs_bbox_diagonal(const double lo[3], const double hi[3]) {
  return sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
              (hi[2] - lo[2]) * (hi[2] - lo[2]));
}
