/* surface_remesh.c — the "remesh" mesher for a closed surface at a size
 * (bs__mesh_remeshed_surface, bs__mesh_surface_auto; see mesh_internal.h):
 * CGAL's isotropic remeshing of the surface at edge length h (the shim,
 * bs_shim_remesh_surface; sharp edges kept on a CAD-like surface), then
 * Gmsh's HXT volume mesher on those triangles (one thread), with Gmsh's
 * optimisers towards the gate (bs__gmsh_surface_volume). The volume mesher
 * sees a surface of well-shaped triangles of size h, so its tets are sized
 * h throughout (Gmsh interpolates the size from the boundary).
 *
 * Which mesher (opts->surface_mesher): BS_SURFACE_CGAL always Mesh_3,
 * BS_SURFACE_REMESH always this path, BS_SURFACE_AUTO this path when the
 * size asks for more than BS_REMESH_AUTO_TETS tets (6 V / h^3), Mesh_3
 * below that or when this path is refused (the gate not met, or the surface
 * folds through itself once remeshed). Below that count Mesh_3 is fast
 * enough and stays closer to the surface (its facet distance h / 10); above
 * it Mesh_3's perturber stalls under the gate for minutes while this path
 * meets the gate without optimising.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bs_shim.h"
#include "mesh_internal.h"

#define BS_REMESH_ITERATIONS 3
/* Gmsh 4.8.4's HXT on two threads left voids in the volume (extra boundary
 * triangles; 2 of 4 runs of the elephant at diagonal / 60) and was slower on
 * a shared two-core machine (1M tets: 8.6 s against 6.6 s): one thread. */
#define BS_REMESH_THREADS 1
#define BS_REMESH_AUTO_TETS 2e5
#define BS_GMSH_HXT 10

int bs__mesh_remeshed_surface(const char *path, const double *pts, int64_t np, const int32_t *tris, int64_t nt,
                              const bs_mesh_read_opts *opts, bs_mesh **out, bs_error *err) {
  *out = NULL;
  const double fa = opts ? opts->feature_angle : 0.0;
  bs_shim_remesh_opts o = {.size = opts ? opts->size : 0.0,
                           .feature_angle = fa < 0 ? 0.0 : (fa > 0 ? fa : BS_MESH_FEATURE_ANGLE),
                           .iterations = BS_REMESH_ITERATIONS};
  bs_shim_remesh_out r;
  int rc = bs_shim_remesh_surface(path, pts, np, tris, nt, &o, &r, err);
  if (!rc)
    rc = bs__gmsh_surface_volume(path, r.points, r.n_points, r.tris, r.n_tris, opts, BS_GMSH_HXT, BS_REMESH_THREADS,
                                 out, err);
  bs_shim_free(r.points);
  bs_shim_free(r.tris);
  if (!rc) rc = bs_mesh_dihedral_gate(*out, bs__mesh_gate(opts), path, err);
  if (rc) bs_mesh_destroy(out);
  return rc;
}

/* |volume| enclosed by the soup's triangles (divergence theorem). */
static double enclosed_volume(const double *p, const int32_t *t, int64_t nt) {
  double v = 0;
  for (int64_t f = 0; f < nt; f++) {
    const double *a = p + 3 * t[3 * f], *b = p + 3 * t[3 * f + 1], *c = p + 3 * t[3 * f + 2];
    v += a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) + a[2] * (b[0] * c[1] - b[1] * c[0]);
  }
  return fabs(v / 6.0);
}

int bs__mesh_surface_auto(const char *path, const double *pts, int64_t np, const int32_t *tris, int64_t nt,
                          const bs_mesh_read_opts *opts, int *done, bs_mesh **out, bs_error *err) {
  *done = 0;
  *out = NULL;
  const int mesher = opts ? opts->surface_mesher : BS_SURFACE_AUTO;
  const double h = opts ? opts->size : 0.0;
  if (mesher == BS_SURFACE_CGAL || !(h > 0)) return BS_OK;
  if (mesher == BS_SURFACE_AUTO && 6.0 * enclosed_volume(pts, tris, nt) / (h * h * h) <= BS_REMESH_AUTO_TETS)
    return BS_OK;
  int rc = bs__mesh_remeshed_surface(path, pts, np, tris, nt, opts, out, err);
  if (rc == BS_EINPUT && mesher == BS_SURFACE_AUTO) {
    bs_error_clear(err); /* refused: Mesh_3 meshes it */
    return BS_OK;
  }
  *done = 1;
  return rc;
}

static const struct {
  const char *name;
  int value;
} mesher_names[] = {{"auto", BS_SURFACE_AUTO}, {"cgal", BS_SURFACE_CGAL}, {"remesh", BS_SURFACE_REMESH}};
#define N_MESHERS (sizeof mesher_names / sizeof mesher_names[0])

const char *bs_mesh_mesher_name(int mesher) {
  for (size_t i = 0; i < N_MESHERS; i++)
    if (mesher_names[i].value == mesher) return mesher_names[i].name;
  return "auto";
}

int bs_mesh_parse_mesher(const char *s, int *mesher) {
  for (size_t i = 0; s && i < N_MESHERS; i++)
    if (!strcmp(s, mesher_names[i].name)) {
      *mesher = mesher_names[i].value;
      return 0;
    }
  return -1;
}
