/* surface_mesh.c — a closed surface (a soup read by the shim) meshed into a
 * volume by CGAL's Mesh_3 at a target size, optimised, held to the gate
 * (bs__mesh_closed_surface, see mesh_internal.h).
 *
 * The size is checked against the surface first: larger than its bounding
 * box's diagonal gives no interior at all, and the tets it would make
 * (6 V / h^3 for the enclosed volume V) must fit this machine
 * (bs__check_mesh_size). The mesh gets the groups of Gmsh's discrete
 * surfaces: (3, 1, "body") and (2, 1, "surface_1"), its whole boundary.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bs_shim.h"
#include "mesh_internal.h"

/* Mesh_3's options for a target size h (see bs_shim_mesh3_opts): ODT
 * smoothing, then perturbation and exudation in rounds towards the gate, at
 * least the default gate (a relaxed gate still gets a good mesh) and at most
 * BS_MESH3_MAX_TARGET: CGAL's perturber reaches 10 to 15 degrees; asked
 * for more it works on nearly every tet for minutes and rarely gets there.
 * A scan (not CAD-like) meshed coarser than BS_MESH3_SCAN_FINE of its
 * bounding-box diagonal gets facet distance max(h / 25, diagonal / 900),
 * facet angle 30, radius-edge 2 and the thickness size field (2 elements
 * across thin parts, floor h / 8): at h / 10 and radius-edge 3 its curved and
 * thin parts lose about 3% of its volume at diagonal / 35 (the chords' sag,
 * which scales with the facet distance over the diagonal), and finer facet
 * distances alone leave slivers. Finer than that, h / 10 is already within
 * about 1% and a scan is meshed as a CAD part is. */
#define BS_MESH3_MAX_TARGET 15.0
#define BS_MESH3_SCAN_FINE (1.0 / 90.0)
static bs_shim_mesh3_opts mesh3_opts(double h, const double *pts, int64_t np, const bs_mesh_read_opts *opts) {
  double fa = opts ? opts->feature_angle : 0.0;
  double gate = bs__mesh_gate(opts);
  double lo[3], hi[3];
  bs_bbox(np, pts, lo, hi);
  const double diag = bs_bbox_diagonal(lo, hi);
  bs_shim_mesh3_opts o = {.size = h,
                          .facet_distance = h / 10.0,
                          .feature_angle = fa < 0 ? 0.0 : (fa > 0 ? fa : BS_MESH_FEATURE_ANGLE),
                          .smoother = BS_SHIM_SMOOTH_ODT,
                          .smooth_iterations = 10,
                          .perturb = 1,
                          .exude = 1,
                          .target_dihedral = fmin(fmax(gate, BS_MESH_MIN_DIHEDRAL), BS_MESH3_MAX_TARGET),
                          .max_rounds = 3};
  if (h > BS_MESH3_SCAN_FINE * diag) {
    o.scan_facet_distance = fmax(h / 25.0, BS_MESH3_SCAN_FINE * diag / 10.0);
    o.scan_facet_angle = 30;
    o.scan_radius_edge = 2;
    o.thickness_elements = 2;
    o.size_gradation = 0.5;
    o.min_size = h / 8.0;
  }
  return o;
}

/* Volume enclosed by the soup's triangles (divergence theorem; its sign
 * follows their orientation). */
double bs__soup_volume(const double *p, const int32_t *t, int64_t nt) {
  double v = 0;
  for (int64_t f = 0; f < nt; f++) {
    const double *a = p + 3 * t[3 * f], *b = p + 3 * t[3 * f + 1], *c = p + 3 * t[3 * f + 2];
    v += a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) + a[2] * (b[0] * c[1] - b[1] * c[0]);
  }
  return v / 6.0;
}

static int check_size(const char *path, const double *pts, int64_t np, const int32_t *tris, int64_t nt, double h,
                      const bs_mesh_read_opts *opts, bs_error *err) {
  double lo[3], hi[3];
  bs_bbox(np, pts, lo, hi);
  const double diag = bs_bbox_diagonal(lo, hi);
  if (!(h > 0) || !isfinite(h)) return bs_error_set(err, BS_EINPUT, "%s: mesh size %g must be > 0", path, h);
  if (h > diag)
    return bs_error_set(err, BS_EINPUT,
                        "%s: mesh size %g m is larger than the surface's bounding-box diagonal %g m (no tet would "
                        "fit; about %.3g m, 1/30 of it, is a usual size)",
                        path, h, diag, diag / 30.0);
  for (int64_t f = 0; f < nt; f++)
    for (int k = 0; k < 3; k++)
      if (tris[3 * f + k] < 0 || tris[3 * f + k] >= np)
        return bs_error_set(err, BS_EINPUT, "%s: triangle %lld refers to point %d of %lld", path, (long long)f,
                            tris[3 * f + k], (long long)np);
  return bs__check_mesh_size(fabs(bs__soup_volume(pts, tris, nt)), h, opts, path, err);
}

/* The mesh of the shim's arrays with the default groups. */
static int build_mesh(const char *path, const bs_shim_mesh3_out *r, bs_mesh **out, bs_error *err) {
  bs_mesh *m0 = NULL;
  if (r->n_vertices > BS_MESH_MAX_TETS || r->n_tets > BS_MESH_MAX_TETS)
    return bs_error_set(err, BS_EINPUT, "%s: %lld tets exceed the 32-bit index range", path, (long long)r->n_tets);
  int rc = bs_mesh_create((int32_t)r->n_vertices, r->x, (int32_t)r->n_tets, r->tets, 0, NULL, &m0, err);
  if (rc) {
    bs_error_prefix(err, "%s", path);
    return rc;
  }
  int32_t *body = malloc((size_t)m0->n_tets * sizeof *body), *surf = malloc(3 * (size_t)m0->n_faces * sizeof *surf);
  if (!body || !surf) {
    rc = bs_error_set(err, BS_ENOMEM, "%s: out of memory for the mesh's groups", path);
  } else {
    for (int32_t t = 0; t < m0->n_tets; t++) body[t] = t;
    memcpy(surf, m0->faces, 3 * (size_t)m0->n_faces * sizeof *surf);
    bs_group g[2] = {{.dim = 2, .tag = 1, .name = "surface_1", .n_elems = m0->n_faces, .elems = surf},
                     {.dim = 3, .tag = 1, .name = "body", .n_elems = m0->n_tets, .elems = body}};
    rc = bs_mesh_create(m0->n_vertices, m0->x, m0->n_tets, m0->tets, 2, g, out, err);
    if (rc) bs_error_prefix(err, "%s", path);
  }
  free(body);
  free(surf);
  bs_mesh_destroy(&m0);
  return rc;
}

int bs__mesh_closed_surface(const char *path, const double *pts, int64_t np, const int32_t *tris, int64_t nt,
                            const bs_mesh_read_opts *opts, bs_mesh **out, bs_error *err) {
  *out = NULL;
  const double h = opts ? opts->size : 0.0;
  if (np <= 0 || nt <= 0)
    return bs_error_set(err, BS_EINPUT, "%s: the surface is empty (%lld points, %lld triangles)", path, (long long)np,
                        (long long)nt);
  int rc = check_size(path, pts, np, tris, nt, h, opts, err);
  if (rc) return rc;
  int done = 0; /* the remesh path (surface_remesh.c) when opts ask for it or the size is large */
  rc = bs__mesh_surface_auto(path, pts, np, tris, nt, opts, &done, out, err);
  if (done || rc) return rc;
  bs_shim_mesh3_opts o = mesh3_opts(h, pts, np, opts);
  bs_shim_mesh3_out r;
  rc = bs_shim_mesh_surface(path, pts, np, tris, nt, &o, &r, err);
  if (!rc) rc = build_mesh(path, &r, out, err);
  bs_shim_free(r.x);
  bs_shim_free(r.tets);
  const int gated = !rc; /* the mesh exists: a failure from here on is the gate's */
  if (!rc) rc = bs_mesh_dihedral_gate(*out, bs__mesh_gate(opts), path, err);
  if (rc) bs_mesh_destroy(out);
  if (rc == BS_EINPUT && gated && (!opts || opts->surface_mesher == BS_SURFACE_AUTO)) {
    /* auto: Mesh_3 under the gate, the remesh path may meet it (the camel at
       diagonal / 40 to / 50); if it does not either, Mesh_3's message stands */
    bs_error e2;
    bs_error_clear(&e2);
    if (!bs__mesh_remeshed_surface(path, pts, np, tris, nt, opts, out, &e2)) {
      bs_error_clear(err);
      return BS_OK;
    }
  }
  return rc;
}
