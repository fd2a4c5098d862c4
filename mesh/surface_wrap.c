/* surface_wrap.c — the alpha wrap (bs_shim_alpha_wrap) as bigstep's fallback
 * for a surface the repair cannot make clean (bs_surface_prepare) and for a
 * clean surface whose meshes are all refused (bs__mesh_closed_surface), held
 * to the volume check (bs__surface_wrap, see mesh_internal.h). */
#include <math.h>
#include <stdint.h>

#include "bs_shim.h"
#include "mesh_internal.h"

/* The volume check of a wrap (see mesh_internal.h): of an input refused as
 * open, the solid check; of a closed one, the volume against its own. */
static int volume_check(const char *path, const bs_shim_wrap_out *w, int open, bs_error *err) {
  const double shell = 2.0 * w->offset * w->area_in;
  if (open && !(w->volume >= BS_WRAP_SOLID * shell))
    return bs_error_set(err, BS_EINPUT,
                        "%s: its alpha wrap (alpha %g) encloses %.4g, a shell around the surface (under %g x the "
                        "shell's %.4g): its holes are wider than 2 alpha",
                        path, w->alpha, w->volume, BS_WRAP_SOLID, shell);
  if (!w->input_closed || !(w->volume_in > 0)) return BS_OK;
  const double bound = 2.0 * w->offset * w->area_in + BS_WRAP_VOLUME_TOL * w->volume_in;
  const double change = w->volume - w->volume_in;
  if (fabs(change) <= bound) return BS_OK;
  return bs_error_set(err, BS_EINPUT,
                      "%s: the surface's alpha wrap (alpha %g, offset %g) encloses %.6g where the surface encloses "
                      "%.6g (%+.2f%%), beyond the volume check's %.2f%% (2 offset x area + %g of the volume): a "
                      "smaller --size wraps it tighter",
                      path, w->alpha, w->offset, w->volume, w->volume_in, 100.0 * change / w->volume_in,
                      100.0 * bound / w->volume_in, BS_WRAP_VOLUME_TOL);
}

int bs__surface_wrap(const char *path, const double *x, int64_t nx, const int32_t *t, int64_t nt, double h, int how,
                     int open, double **pts, int64_t *np, int32_t **tris, int64_t *ntri, bs_surface_report *rep,
                     bs_error *err) {
  *pts = NULL, *tris = NULL, *np = *ntri = 0;
  int rc = bs__budget_check(path, "the alpha wrap", err);
  if (rc) return rc;
  bs_shim_wrap_opts o = {.size = h, .deadline = bs__budget_deadline()};
  bs_shim_wrap_out w;
  rc = bs_shim_alpha_wrap(path, x, nx, t, nt, &o, &w, err);
  if (!rc && (rc = volume_check(path, &w, open, err))) {
    bs_shim_free(w.points);
    bs_shim_free(w.tris);
  }
  if (rep) {
    rep->wrap_alpha = w.alpha, rep->wrap_offset = w.offset, rep->wrap_seconds = w.seconds;
    rep->wrap_volume_change = w.volume_in > 0 ? (w.volume - w.volume_in) / w.volume_in : 0.0;
  }
  if (rc) return rc;
  *pts = w.points, *tris = w.tris, *np = w.n_points, *ntri = w.n_tris;
  if (rep) {
    rep->wrapped = how;
    rep->points_out = w.n_points, rep->tris_out = w.n_tris, rep->volume = w.volume;
  }
  return BS_OK;
}
