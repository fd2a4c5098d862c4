/* surface_repair.c — a surface file read and made clean for volume meshing
 * (bs_surface_prepare): bs_shim_read_surface, then bs_shim_repair_surface;
 * a surface the repair refuses (a hole it cannot triangulate,
 * self-intersections it cannot remove, a non-manifold result, a soup of
 * overlapping facets; an open one only when it is a soup of facets and
 * the wrap is solid, see wrap_instead) is replaced by its alpha wrap at the requested size
 * (bs__surface_wrap; without a size, bs_surface_auto_size's first), held
 * to the wrap's volume check. The file's name
 * is in front of every message; when the wrap is refused too, the repair's
 * message is kept and the wrap's reason appended. */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

#include "bs_mesh.h"
#include "bs_shim.h"
#include "mesh_internal.h"

/* The share of the soup's edges (points at equal positions merged) that
 * lie in one triangle only; 0 when out of memory. */
static double border_share(const double *x, int64_t nx, const int32_t *t, int64_t nt) {
  int32_t *rep = malloc(((size_t)nx + 1) * sizeof *rep);
  uint64_t *keys = malloc((3 * (size_t)nt + 1) * sizeof *keys);
  bs_error e;
  double share = 0;
  if (rep && keys && bs__coincident(nx, x, rep, &e) >= 0) {
    for (int64_t f = 0; f < nt; f++)
      for (int k = 0; k < 3; k++) keys[3 * f + k] = bs__edge_key(rep[t[3 * f + k]], rep[t[3 * f + (k + 1) % 3]]);
    qsort(keys, 3 * (size_t)nt, sizeof *keys, bs__cmp_u64);
    size_t edges = 0, border = 0;
    for (size_t i = 0, j; i < 3 * (size_t)nt; i = j) {
      for (j = i + 1; j < 3 * (size_t)nt && keys[j] == keys[i]; j++) {}
      edges++;
      border += j - i == 1;
    }
    share = edges ? (double)border / (double)edges : 0.0;
  }
  free(rep);
  free(keys);
  return share;
}

/* The repair refused the soup: its alpha wrap instead, unless the budget is
 * spent. A soup refused as open is wrapped only when it is a soup of
 * facets rather than a surface with holes (at least BS_WRAP_OPEN_SHARE of
 * its edges on a border: border_share), and its wrap is kept only when it is
 * solid (bs__surface_wrap's solid check: its openings were gaps narrower
 * than the element size, as between the facets of a polygon soup); a real
 * hole lets the wrap in and the open surface stays refused (holes are
 * closed only on request). */
#define BS_WRAP_OPEN_SHARE 0.05
static int wrap_instead(const char *path, const double *x, int64_t nx, const int32_t *t, int64_t ntri,
                        const bs_mesh_read_opts *opts, double **pts, int64_t *np, int32_t **tris, int64_t *nt,
                        bs_surface_report *rep, bs_error *err) {
  if (bs__budget_exceeded(err) || (rep->open_refused && border_share(x, nx, t, ntri) < BS_WRAP_OPEN_SHARE))
    return err ? err->code : BS_EINPUT;
  const double h = opts && opts->size > 0 ? opts->size : bs_surface_auto_size(x, nx, t, ntri, 0, opts);
  bs_error e2;
  bs_error_clear(&e2);
  const int rc = bs__surface_wrap(path, x, nx, t, ntri, h, 1, rep->open_refused, pts, np, tris, nt, rep, &e2);
  if (!rc) {
    bs_error_clear(err);
    return BS_OK;
  }
  if (rc != BS_EINPUT || bs__budget_exceeded(&e2)) {
    if (err) *err = e2;
    return rc;
  }
  if (err) {
    char first[BS_ERROR_MSG];
    snprintf(first, sizeof first, "%s", err->msg);
    bs_error_set(err, BS_EINPUT, "%s; its alpha wrap was refused too: %.400s", first, e2.msg);
  }
  return BS_EINPUT;
}

int bs_surface_prepare(const char *path, double **pts, int64_t *np, int32_t **tris, int64_t *nt,
                       const bs_mesh_read_opts *opts, bs_surface_report *rep, bs_error *err) {
  if (!path || !pts || !np || !tris || !nt) return bs_error_set(err, BS_EINPUT, "bs_surface_prepare: NULL argument");
  *pts = NULL;
  *tris = NULL;
  *np = *nt = 0;
  double *x = NULL;
  int32_t *t = NULL;
  int64_t nx = 0, ntri = 0;
  int rc = bs_shim_read_surface(path, &x, &nx, &t, &ntri, err);
  if (rc) return rc;
  bs_surface_report local;
  if (!rep) rep = &local;
  bs_surface_repair_opts o = {.close_holes = opts ? opts->close_holes : 0, .max_hole = opts ? opts->max_hole : 0};
  rc = bs_shim_repair_surface(x, nx, t, ntri, &o, pts, np, tris, nt, rep, err);
  if (rc) bs_error_prefix(err, "%s", path);
  if (rc == BS_EINPUT) rc = wrap_instead(path, x, nx, t, ntri, opts, pts, np, tris, nt, rep, err);
  bs_shim_free(x);
  bs_shim_free(t);
  return rc;
}
