/* surface_remesh.c — the "remesh" mesher for a closed surface at a size
 * (bs__mesh_remeshed_surface, see mesh_internal.h): CGAL's isotropic
 * remeshing of the surface at edge length h (the shim,
 * bs_shim_remesh_surface; sharp edges protected on a CAD-like surface),
 * then Gmsh's HXT volume mesher on those triangles, on two threads, with
 * Gmsh's optimisers towards the gate (bs__gmsh_surface_volume). The volume
 * mesher sees a surface of well-shaped triangles of size h, so its tets
 * are sized h throughout (Gmsh interpolates the size from the boundary).
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "bs_shim.h"
#include "mesh_internal.h"

#define BS_REMESH_ITERATIONS 3
#define BS_REMESH_THREADS 2
#define BS_GMSH_HXT 10

int bs__mesh_remeshed_surface(const char *path, const double *pts, int64_t np, const int32_t *tris, int64_t nt,
                              const bs_mesh_read_opts *opts, bs_mesh **out, bs_error *err) {
  *out = NULL;
  const double fa = opts ? opts->feature_angle : 0.0;
  bs_shim_remesh_opts o = {.size = opts ? opts->size : 0.0,
                           .feature_angle = fa < 0 ? 0.0 : (fa > 0 ? fa : BS_MESH_FEATURE_ANGLE),
                           .iterations = BS_REMESH_ITERATIONS};
  const char *e = getenv("BS_REMESH_ITERS"); /* TEMPORARY: measurements */
  if (e) o.iterations = atoi(e);
  e = getenv("BS_REMESH_ALGO3D");
  int algo = e ? atoi(e) : BS_GMSH_HXT;
  bs_shim_remesh_out r;
  double t0 = bs_seconds();
  int rc = bs_shim_remesh_surface(path, pts, np, tris, nt, &o, &r, err);
  if (getenv("BS_REMESH_DEBUG")) fprintf(stderr, "DEBUG remesh %.2f s, %lld tris\n", bs_seconds() - t0, (long long)r.n_tris);
  if (!rc) rc = bs__gmsh_surface_volume(path, r.points, r.n_points, r.tris, r.n_tris, opts, algo,
                                        BS_REMESH_THREADS, out, err);
  if (getenv("BS_REMESH_DEBUG")) fprintf(stderr, "DEBUG total %.2f s\n", bs_seconds() - t0);
  bs_shim_free(r.points);
  bs_shim_free(r.tris);
  return rc;
}
