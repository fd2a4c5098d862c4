/* surface_remesh.c — the "remesh" mesher for a closed surface at a size
 * (bs__mesh_remeshed_surface, see mesh_internal.h; surface_mesh.c chooses
 * between it and Mesh_3):
 * CGAL's isotropic remeshing of the surface at edge length h (the shim,
 * bs_shim_remesh_surface; sharp edges kept on a CAD-like surface), then
 * Gmsh's HXT volume mesher on those triangles (one thread), with Gmsh's
 * optimisers towards the gate (bs__gmsh_surface_volume). The volume mesher
 * sees a surface of well-shaped triangles of size h, so its tets are sized
 * h throughout (Gmsh interpolates the size from the boundary). Tets under
 * the gate that no optimiser moves because their four vertices lie on the
 * boundary and two of their faces are boundary triangles (caps across a
 * nearly flat surface edge) are removed, which flips that surface edge
 * (peel_caps); then the gate.
 */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "bs_shim.h"
#include "mesh_internal.h"

#define BS_REMESH_ITERATIONS 3
/* Gmsh 4.8.4's HXT on two threads left voids in the volume (extra boundary
 * triangles; 2 of 4 runs of the elephant at diagonal / 60) and was slower on
 * a shared two-core machine (1M tets: 8.6 s against 6.6 s): one thread. */
#define BS_REMESH_THREADS 1
#define BS_GMSH_HXT 10
/* Gmsh 4.8.4's HXT gives a different mesh from run to run and from call to
 * call (it depends on the heap's addresses): the pig at diagonal / 30 missed
 * the gate in 1 run of 40 and the remesh camel at diagonal / 50 missed 13
 * degrees in 1 of 24, and a call again in the same process draws anew. */
#define BS_HXT_ATTEMPTS 3

/* m's tets but those with drop[t] into a new mesh with the default groups
 * (bs__mesh_default_groups). */
static int without_tets(const char *path, const bs_mesh *m, const char *drop, bs_mesh **out, bs_error *err) {
  int32_t *tets = malloc(4 * (size_t)m->n_tets * sizeof *tets), n = 0;
  if (!tets) return bs_error_set(err, BS_ENOMEM, "%s: out of memory for the tets", path);
  for (int32_t t = 0; t < m->n_tets; t++)
    if (!drop[t]) memcpy(tets + 4 * (size_t)n++, m->tets + 4 * (size_t)t, 4 * sizeof *tets);
  int rc = bs__mesh_default_groups(path, m->n_vertices, m->x, n, tets, out, err);
  free(tets);
  return rc;
}

/* Marks in drop the caps under the gate: tets with two boundary faces (so
 * four boundary vertices), their two other vertices c, d not joined by a
 * boundary edge, no vertex shared with another marked cap. Removing one
 * flips the surface edge between its two boundary faces to c-d. */
static int32_t mark_caps(const bs_mesh *m, double gate, const uint64_t *bedges, char *drop, int32_t *fa,
                         int32_t *fb, char *used) {
  int32_t n = 0;
  for (int32_t f = 0; f < m->n_faces; f++) {
    int32_t t = m->face_tet[f];
    if (fa[t] < 0) fa[t] = f;
    else fb[t] = f;
  }
  for (int32_t t = 0; t < m->n_tets; t++) {
    const int32_t *v = m->tets + 4 * (size_t)t;
    if (fb[t] < 0 || used[v[0]] || used[v[1]] || used[v[2]] || used[v[3]]) continue;
    const double *p[4] = {m->x + 3 * (size_t)v[0], m->x + 3 * (size_t)v[1], m->x + 3 * (size_t)v[2],
                          m->x + 3 * (size_t)v[3]};
    bs__tet_measures q;
    bs__tet_quality(p, &q);
    if (q.dihedral_min >= gate) continue;
    int32_t other[2], k = 0; /* the vertex of each boundary face not in the other */
    for (int i = 0; i < 3; i++) {
      const int32_t a = m->faces[3 * (size_t)fa[t] + i], b = m->faces[3 * (size_t)fb[t] + i];
      const int32_t *g = m->faces + 3 * (size_t)fb[t], *h = m->faces + 3 * (size_t)fa[t];
      if (a != g[0] && a != g[1] && a != g[2] && k < 2) other[k++] = a;
      if (b != h[0] && b != h[1] && b != h[2] && k < 2) other[k++] = b;
    }
    uint64_t key = bs__edge_key(other[0], other[1]);
    if (k != 2 || bsearch(&key, bedges, (size_t)m->n_edges, sizeof key, bs__cmp_u64)) continue;
    drop[t] = 1, n++;
    for (int i = 0; i < 4; i++) used[v[i]] = 1;
  }
  return n;
}

/* Removes the caps under the gate (mark_caps) from *m, in up to three
 * passes: tets whose four vertices lie on the boundary and that no optimiser
 * moves. The volume changes by the caps' own (flat) volume. */
static int peel_caps(const char *path, double gate, bs_mesh **m, bs_error *err) {
  int rc = BS_OK;
  for (int pass = 0; !rc && pass < 3; pass++) {
    const bs_mesh *c = *m;
    uint64_t *be = malloc(((size_t)c->n_edges + 1) * sizeof *be);
    char *drop = calloc((size_t)c->n_tets + 1, 1), *used = calloc((size_t)c->n_vertices + 1, 1);
    int32_t *fa = malloc(((size_t)c->n_tets + 1) * sizeof *fa), *fb = malloc(((size_t)c->n_tets + 1) * sizeof *fb);
    int32_t n = 0;
    if (!be || !drop || !used || !fa || !fb) rc = bs_error_set(err, BS_ENOMEM, "%s: out of memory", path);
    if (!rc) {
      for (int32_t e = 0; e < c->n_edges; e++) be[e] = bs__edge_key(c->edges[2 * e], c->edges[2 * e + 1]);
      qsort(be, (size_t)c->n_edges, sizeof *be, bs__cmp_u64);
      for (int32_t t = 0; t < c->n_tets; t++) fa[t] = fb[t] = -1;
      n = mark_caps(c, gate, be, drop, fa, fb, used);
    }
    bs_mesh *next = NULL;
    if (!rc && n > 0) rc = without_tets(path, c, drop, &next, err);
    if (next) bs_mesh_destroy(m), *m = next;
    free(be), free(drop), free(used), free(fa), free(fb);
    if (n == 0) break;
  }
  return rc;
}

/* One HXT mesh inside the soup, checked (bs__mesh_hxt_inside). */
static int hxt_inside_once(const char *path, const double *pts, int64_t np, const int32_t *tris, int64_t nt,
                           const bs_mesh_read_opts *opts, bs_mesh **out, bs_error *err) {
  int rc = bs__gmsh_surface_volume(path, pts, np, tris, nt, opts, BS_GMSH_HXT, BS_REMESH_THREADS, out, err);
  const double gate = bs__mesh_gate(opts);
  if (!rc && gate > 0) rc = peel_caps(path, gate, out, err);
  if (!rc) rc = bs__boundary_like_soup(*out, path, pts, np, tris, nt, 0.0, err);
  if (!rc) rc = bs_mesh_dihedral_gate(*out, gate, path, err);
  if (rc) bs_mesh_destroy(out);
  return rc;
}

int bs__mesh_hxt_inside(const char *path, const double *pts, int64_t np, const int32_t *tris, int64_t nt,
                        const bs_mesh_read_opts *opts, bs_mesh **out, bs_error *err) {
  int rc = BS_OK;
  for (int a = 0; a < BS_HXT_ATTEMPTS; a++) {
    if (a) bs_error_clear(err);
    rc = hxt_inside_once(path, pts, np, tris, nt, opts, out, err);
    if (rc != BS_EINPUT && rc != BS_EGMSH) break;
  }
  return rc;
}

int bs__mesh_remeshed_surface(const char *path, const double *pts, int64_t np, const int32_t *tris, int64_t nt,
                              const bs_mesh_read_opts *opts, bs_mesh **out, bs_error *err) {
  *out = NULL;
  const double fa = opts ? opts->feature_angle : 0.0;
  bs_shim_remesh_opts o = {.size = opts ? opts->size : 0.0,
                           .feature_angle = fa < 0 ? 0.0 : (fa > 0 ? fa : BS_MESH_FEATURE_ANGLE),
                           .iterations = BS_REMESH_ITERATIONS};
  bs_shim_remesh_out r;
  int rc = bs_shim_remesh_surface(path, pts, np, tris, nt, &o, &r, err);
  if (!rc) rc = bs__mesh_hxt_inside(path, r.points, r.n_points, r.tris, r.n_tris, opts, out, err);
  bs_shim_free(r.points);
  bs_shim_free(r.tris);
  return rc;
}
