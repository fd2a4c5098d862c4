/* surface_repair.c — a surface file read and made clean for volume meshing
 * (bs_surface_prepare): bs_shim_read_surface, then bs_shim_repair_surface,
 * with the file's name in front of every message. */
#include <stdint.h>

#include "bs_mesh.h"
#include "bs_shim.h"

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
  bs_surface_repair_opts o = {.close_holes = opts ? opts->close_holes : 0, .max_hole = opts ? opts->max_hole : 0};
  rc = bs_shim_repair_surface(x, nx, t, ntri, &o, pts, np, tris, nt, rep, err);
  bs_shim_free(x);
  bs_shim_free(t);
  if (rc) bs_error_prefix(err, "%s", path);
  return rc;
}
