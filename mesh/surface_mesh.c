/* surface_mesh.c — a closed surface (a soup read by the shim) meshed into a
 * volume at a target size, held to the gate (bs__mesh_closed_surface, see
 * mesh_internal.h): by CGAL's Mesh_3 (here), or by the remesh path
 * (surface_remesh.c), as opts->surface_mesher says.
 *
 * The choice: BS_SURFACE_CGAL always Mesh_3, BS_SURFACE_REMESH always the
 * remesh path, BS_SURFACE_AUTO the remesh path first when the size asks for
 * more than BS_REMESH_AUTO_TETS tets (6 V / h^3), Mesh_3 first below that,
 * and the other one when the first refuses (BS_EINPUT: the gate not met, a
 * surface that folds through itself once remeshed, CGAL's failure); when
 * both refuse, Mesh_3's message is the one returned. Below that count
 * Mesh_3 is fast enough and stays closer to the surface (its facet distance
 * h / 10); above it Mesh_3's perturber stalls under the gate for minutes
 * while the remesh path meets the gate without optimising.
 *
 * A Mesh_3 mesh must have a boundary that is a closed 2-manifold with as
 * many components as the surface has of at least one tet's volume (the
 * shim fills the small cavities and pinches Mesh_3 leaves; what remains is
 * refused by manifold.c's check); one under the gate is meshed again inside
 * its own boundary by Gmsh's HXT and optimisers (hxt_inside_mesh3), which
 * keeps Mesh_3's surface (its volume and distance to the input) where the
 * remesh path would cut thin parts. A scan's mesh that is refused or more
 * than 1% off the surface's volume is made again with finer facet
 * distances (mesh3_path), the passing one closest to the volume kept; a
 * mesh more than BS_MESH_VOLUME_LOST off counts as its mesher's refusal
 * (volume_kept). Separate solids (surface_parts.c) are meshed one at a
 * time (mesh_solids) and joined.
 *
 * The size is checked against the surface first: larger than its bounding
 * box's diagonal gives no interior at all, and the tets it would make
 * (6 V / h^3 for the enclosed volume V) must fit this machine
 * (bs__check_mesh_size). The mesh gets the groups of Gmsh's discrete
 * surfaces: (3, 1, "body") and (2, 1, "surface_1"), its whole boundary.
 */
#include <math.h>
#include <stdio.h>
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
#define BS_REMESH_AUTO_TETS 2e5
static bs_shim_mesh3_opts mesh3_opts(double h, double diag, const bs_mesh_read_opts *opts) {
  double fa = opts ? opts->feature_angle : 0.0;
  double gate = bs__mesh_gate(opts);
  bs_shim_mesh3_opts o = {.size = h,
                          .facet_distance = h / 10.0,
                          .feature_angle = fa < 0 ? 0.0 : (fa > 0 ? fa : BS_MESH_FEATURE_ANGLE),
                          .smoother = BS_SHIM_SMOOTH_ODT,
                          .smooth_iterations = 10,
                          .perturb = 1,
                          .exude = 1,
                          .target_dihedral = fmin(fmax(gate, BS_MESH_MIN_DIHEDRAL), BS_MESH3_MAX_TARGET),
                          .max_rounds = 3,
                          .deadline = bs__budget_deadline()};
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

/* The size h against the surface (its diagonal and |enclosed volume| into
 * *diag and *volume). */
static int check_size(const char *path, const double *pts, int64_t np, const int32_t *tris, int64_t nt, double h,
                      const bs_mesh_read_opts *opts, double *diag_out, double *volume, bs_error *err) {
  double lo[3], hi[3];
  bs_bbox(np, pts, lo, hi);
  const double diag = *diag_out = bs_bbox_diagonal(lo, hi);
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
  *volume = fabs(bs__soup_volume(pts, tris, nt));
  return bs__check_mesh_size(*volume, h, opts, path, err);
}

/* A tet face as its sorted vertices, and qsort's order of them. */
typedef struct tet_face {
  int32_t v[3];
} tet_face;

static int cmp_face(const void *a, const void *b) {
  const int32_t *p = ((const tet_face *)a)->v, *q = ((const tet_face *)b)->v;
  for (int k = 0; k < 3; k++)
    if (p[k] != q[k]) return p[k] < q[k] ? -1 : 1;
  return 0;
}

static tet_face face_of(const int32_t *tv, int f) {
  tet_face r = {{tv[bs_tet_face[f][0]], tv[bs_tet_face[f][1]], tv[bs_tet_face[f][2]]}};
  for (int i = 0; i < 2; i++)
    for (int j = 0; j < 2 - i; j++)
      if (r.v[j] > r.v[j + 1]) {
        const int32_t s = r.v[j];
        r.v[j] = r.v[j + 1], r.v[j + 1] = s;
      }
  return r;
}

/* One pass: the flat tets (bs__tet_flat) of tets[0 .. *nt) that have a face
 * in no other tet are removed (tets compacted, *nt updated); faces: 4 *nt
 * scratch. Returns the flat tets left (0: none). */
static int32_t peel_pass(const double *x, int32_t *tets, int32_t *nt, tet_face *faces) {
  for (int32_t t = 0; t < *nt; t++)
    for (int f = 0; f < 4; f++) faces[4 * (size_t)t + f] = face_of(tets + 4 * (size_t)t, f);
  qsort(faces, 4 * (size_t)*nt, sizeof *faces, cmp_face);
  int32_t n = 0, left = 0;
  for (int32_t t = 0; t < *nt; t++) {
    const int32_t *tv = tets + 4 * (size_t)t;
    int open = 0;
    if (bs__tet_flat(x, tv))
      for (int f = 0; f < 4 && !open; f++) {
        const tet_face key = face_of(tv, f);
        const tet_face *hit = bsearch(&key, faces, 4 * (size_t)*nt, sizeof *faces, cmp_face);
        const tet_face *end = faces + 4 * (size_t)*nt;
        open = (hit == faces || cmp_face(hit - 1, hit)) && (hit + 1 == end || cmp_face(hit, hit + 1));
      }
    if (open) continue;
    left += bs__tet_flat(x, tv);
    memmove(tets + 4 * (size_t)n++, tv, 4 * sizeof *tets);
  }
  const int32_t removed = *nt - n;
  *nt = n;
  return removed ? left : -left;
}

/* The tets but the flat ones that lie on the boundary (a face in no other
 * tet), removed in turn (a removal can bring another one to the boundary),
 * into *kept (malloc'ed, *nk of them): a flat tet has no volume, and its
 * other faces lie in the plane of the face it showed, so the body and its
 * surface stay as they were. BS_EINPUT naming the count when flat tets are
 * left inside (removing them would leave flat voids). */
static int peel_flat_tets(const char *path, const double *x, int32_t nt, const int32_t *tets, int32_t **kept,
                          int32_t *nk, bs_error *err) {
  *kept = malloc(4 * ((size_t)nt + 1) * sizeof **kept);
  tet_face *faces = malloc(4 * ((size_t)nt + 1) * sizeof *faces);
  if (!*kept || !faces) {
    free(*kept), free(faces), *kept = NULL;
    return bs_error_set(err, BS_ENOMEM, "%s: out of memory for the flat tets", path);
  }
  memcpy(*kept, tets, 4 * (size_t)nt * sizeof **kept);
  *nk = nt;
  int32_t left;
  while ((left = peel_pass(x, *kept, nk, faces)) > 0) {
  }
  free(faces);
  if (left == 0) return BS_OK;
  free(*kept), *kept = NULL;
  return bs_error_set(err, BS_EINPUT, "%s: %d tets of zero volume lie inside the mesh, where neither CGAL's "
                      "tetrahedral remeshing nor their removal can take them", path, -left);
}

/* The mesh of the raw tets, or, when one has zero volume, of their lift
 * (bs__tets_lift towards the default gate), or when the remesher cannot
 * take them (a boundary that pinches), of the tets but the flat ones on the
 * boundary (peel_flat_tets): a degenerate tet is remeshed or removed, never
 * the error (the mesh's other faults are found after: manifold.c, the
 * gate). */
static int create_or_lift(const char *path, int32_t nv, const double *x, int32_t nt, const int32_t *tets,
                          bs_mesh **out, bs_error *err) {
  int rc = bs_mesh_create(nv, x, nt, tets, 0, NULL, out, err);
  if (rc != BS_EINPUT || !strstr(err->msg, "zero volume")) return rc;
  bs_shim_tet_remesh_out r;
  bs_error e2;
  bs_error_clear(&e2);
  if (bs__tets_lift(path, nv, x, nt, tets, NULL, 0.0, BS_MESH_MIN_DIHEDRAL, 1, &r, &e2)) {
    if (e2.code != BS_EINPUT || bs__budget_exceeded(&e2)) return *err = e2, e2.code;
    int32_t *kept = NULL, nk = 0;
    bs_error_clear(err);
    if ((rc = peel_flat_tets(path, x, nt, tets, &kept, &nk, err))) return rc;
    rc = bs_mesh_create(nv, x, nk, kept, 0, NULL, out, err);
    free(kept);
    return rc;
  }
  if (r.n_vertices <= INT32_MAX && r.n_tets <= INT32_MAX)
    rc = bs_mesh_create((int32_t)r.n_vertices, r.x, (int32_t)r.n_tets, r.tets, 0, NULL, out, err);
  bs_shim_free(r.x), bs_shim_free(r.tets), bs_shim_free(r.subdomain);
  return rc;
}

int bs__mesh_default_groups(const char *path, int32_t nv, const double *x, int32_t nt, const int32_t *tets,
                            bs_mesh **out, bs_error *err) {
  bs_mesh *m0 = NULL;
  int rc = create_or_lift(path, nv, x, nt, tets, &m0, err);
  if (rc) {
    bs_error_prefix(err, "%s", path);
    return rc;
  }
  int32_t *body = malloc(((size_t)m0->n_tets + 1) * sizeof *body);
  int32_t *surf = malloc((3 * (size_t)m0->n_faces + 1) * sizeof *surf);
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

/* m's boundary triangles as a soup of their own points (the boundary
 * vertices only, renumbered), malloc'ed into *pts and *tris. */
static int boundary_soup(const char *path, const bs_mesh *m, double **pts, int64_t *np, int32_t **tris,
                         bs_error *err) {
  int32_t *id = malloc(((size_t)m->n_vertices + 1) * sizeof *id), n = 0;
  *pts = malloc((3 * (size_t)m->n_vertices + 1) * sizeof **pts);
  *tris = malloc((3 * (size_t)m->n_faces + 1) * sizeof **tris);
  if (!id || !*pts || !*tris) {
    free(id), free(*pts), free(*tris);
    *pts = NULL, *tris = NULL;
    return bs_error_set(err, BS_ENOMEM, "%s: out of memory for the mesh's boundary", path);
  }
  for (int32_t v = 0; v < m->n_vertices; v++) id[v] = -1;
  for (size_t k = 0; k < 3 * (size_t)m->n_faces; k++) {
    const int32_t v = m->faces[k];
    if (id[v] < 0) {
      memcpy(*pts + 3 * (size_t)n, m->x + 3 * (size_t)v, 3 * sizeof **pts);
      id[v] = n++;
    }
    (*tris)[k] = id[v];
  }
  *np = n;
  free(id);
  return BS_OK;
}

/* BS_EINPUT unless m's boundary is a closed 2-manifold with as many
 * components as the soup has of at least a regular tet's volume at size h
 * (h^3 / (6 sqrt 2): a smaller one, a bubble or a crumb, has no tet at
 * that size) (bs__boundary_like_soup). */
static int manifold_like(const char *path, const bs_mesh *m, const double *pts, int64_t np, const int32_t *tris,
                         int64_t nt, double h, bs_error *err) {
  return bs__boundary_like_soup(m, path, pts, np, tris, nt, h * h * h / (6.0 * sqrt(2.0)), err);
}

/* A Mesh_3 mesh under the gate meshed again inside its own boundary by
 * Gmsh's HXT and optimisers (bs__mesh_hxt_inside): Mesh_3's surface, close
 * to the input (its facet distance), is kept, and the slivers its perturber
 * and exuder leave where the surface is finely divided (thin and curved
 * parts) are not remade. On BS_EINPUT from there, *err keeps Mesh_3's
 * gate message. */
static int hxt_inside_mesh3(const char *path, bs_mesh **m, const bs_mesh_read_opts *opts, bs_error *err) {
  double *bp = NULL;
  int32_t *bt = NULL;
  int64_t nbp = 0;
  bs_mesh *again = NULL;
  bs_error e2;
  bs_error_clear(&e2);
  if (boundary_soup(path, *m, &bp, &nbp, &bt, &e2)) {
    *err = e2;
    return e2.code ? e2.code : BS_ENOMEM;
  }
  int rc = bs__mesh_hxt_inside(path, bp, nbp, bt, (*m)->n_faces, opts, &again, &e2);
  free(bp), free(bt);
  if (rc == BS_EINPUT || rc == BS_EGMSH) return BS_EINPUT; /* Mesh_3's message stays in *err */
  if (rc) {
    *err = e2;
    return rc;
  }
  bs_mesh_destroy(m);
  *m = again;
  bs_error_clear(err);
  return BS_OK;
}

/* A Mesh_3 mesh under the gate lifted by CGAL's tetrahedral remeshing
 * (bs__mesh_lift at h); BS_OK when the lift passes the gate, else
 * BS_EINPUT with *err keeping the gate's message (the budget's when spent),
 * *m the lift when it is better. */
static int lift_mesh3(const char *path, bs_mesh **m, double h, const bs_mesh_read_opts *opts, bs_error *err) {
  bs_error e2;
  bs_error_clear(&e2);
  const double gate = bs__mesh_gate(opts);
  int rc = bs__mesh_lift(path, m, h, gate, &e2);
  if (rc) {
    if (rc != BS_EINPUT || bs__budget_exceeded(&e2)) *err = e2;
    return rc;
  }
  if (bs_mesh_dihedral_gate(*m, gate, path, &e2)) return bs__lift_note(*m, err);
  bs_error_clear(err);
  return BS_OK;
}

/* One Mesh_3 mesh at o: the shim's mesh with the default groups, checked
 * manifold, held to the gate, meshed again inside its boundary when under
 * it (hxt_inside_mesh3). *scan: whether the shim meshed it as a scan (no
 * sharp-edge chains kept), so with o's scan criteria. */
static int mesh3_once(const char *path, const double *pts, int64_t np, const int32_t *tris, int64_t nt,
                      const bs_shim_mesh3_opts *o, const bs_mesh_read_opts *opts, int *scan, bs_mesh **out,
                      bs_error *err) {
  bs_shim_mesh3_out r;
  int rc = bs_shim_mesh_surface(path, pts, np, tris, nt, o, &r, err);
  *scan = !rc && r.n_features == 0;
  if (!rc && (r.n_vertices > BS_MESH_MAX_TETS || r.n_tets > BS_MESH_MAX_TETS))
    rc = bs_error_set(err, BS_EINPUT, "%s: %lld tets exceed the 32-bit index range", path, (long long)r.n_tets);
  if (!rc) rc = bs__mesh_default_groups(path, (int32_t)r.n_vertices, r.x, (int32_t)r.n_tets, r.tets, out, err);
  bs_shim_free(r.x);
  bs_shim_free(r.tets);
  if (!rc) rc = manifold_like(path, *out, pts, np, tris, nt, o->size, err);
  if (!rc && (rc = bs_mesh_dihedral_gate(*out, bs__mesh_gate(opts), path, err)) == BS_EINPUT) {
    rc = lift_mesh3(path, out, o->size, opts, err);
    if (rc == BS_EINPUT && !bs__budget_exceeded(err)) rc = hxt_inside_mesh3(path, out, opts, err);
  }
  if (rc) bs_mesh_destroy(out);
  return rc;
}

/* The Mesh_3 path (mesh3_once). A scan meshed with the scan criteria that
 * is refused, or whose volume is more than BS_MESH3_SCAN_VOLUME_TOL off the
 * surface's (volume), is meshed again with the finer facet distances h /
 * scan_finer[k] (no floor), until one passes within it: the chords' sag on
 * thin curved parts is what it loses (the elk at diagonal / 40: -1.06%,
 * then -0.51% at h / 40), and where Mesh_3's perturber ends just under the
 * gate a finer surface can end over it (the cow at diagonal / 30: 5.73
 * degrees, then 10.0 and -0.38%). The passing mesh closest to the volume is
 * kept; when none passes, the first's message stands. A CAD part's mesh
 * (its sharp edges kept, facet distance h / 10) that passes but is more
 * than 1% off is meshed again the same way with facet distance h /
 * scan_finer[k]: the chords' sag on its curved faces, which scales with the
 * facet distance (pinion.off at D/25: -1.12%, then -0.33% at h / 40). */
#define BS_MESH3_SCAN_VOLUME_TOL 0.01
static const double scan_finer[] = {40.0, 55.0};

/* Keeps *cand in *best when it passed (rc BS_OK) and is closer to volume
 * than *best_off; frees it otherwise. */
static void keep_closer(bs_mesh **cand, int rc, double volume, bs_mesh **best, double *best_off) {
  const double off = rc ? INFINITY : fabs(bs_mesh_volume(*cand) - volume) / volume;
  if (off < *best_off) {
    bs_mesh_destroy(best);
    *best = *cand, *best_off = off;
    *cand = NULL;
  }
  bs_mesh_destroy(cand);
}

static int mesh3_path(const char *path, const double *pts, int64_t np, const int32_t *tris, int64_t nt, double h,
                      double diag, double volume, const bs_mesh_read_opts *opts, bs_mesh **out, bs_error *err) {
  bs_shim_mesh3_opts o = mesh3_opts(h, diag, opts);
  int scan = 0;
  int rc = mesh3_once(path, pts, np, tris, nt, &o, opts, &scan, out, err);
  if ((rc && rc != BS_EINPUT) || !(volume > 0) || (scan ? !(o.scan_facet_distance > 0) : rc != BS_OK)) return rc;
  double off = rc ? INFINITY : fabs(bs_mesh_volume(*out) - volume) / volume;
  for (size_t k = 0; k < sizeof scan_finer / sizeof *scan_finer && off > BS_MESH3_SCAN_VOLUME_TOL; k++) {
    if (scan) o.scan_facet_distance = h / scan_finer[k];
    else o.facet_distance = h / scan_finer[k];
    bs_mesh *fine = NULL;
    bs_error e2;
    bs_error_clear(&e2);
    const int rc2 = mesh3_once(path, pts, np, tris, nt, &o, opts, &scan, &fine, &e2);
    if (rc2 && rc2 != BS_EINPUT) {
      bs_mesh_destroy(out);
      *err = e2;
      return rc2;
    }
    keep_closer(&fine, rc2, volume, out, &off);
  }
  if (*out) {
    bs_error_clear(err);
    return BS_OK;
  }
  return rc;
}

/* A mesh that passed a mesher's checks but encloses more than
 * BS_MESH_VOLUME_LOST off the surface's volume has lost or filled a part
 * (blade.off at diagonal/50, its holes faired: Mesh_3 then the lift kept
 * 807 tets, 41.8% short, where the thin blade got no cells): that mesher is
 * taken to have refused, so the next one (the remesh path, the alpha wrap)
 * is tried. Under it, the closest mesh is kept and its change reported. */
#define BS_MESH_VOLUME_LOST 0.05
static int volume_kept(const char *path, int rc, double volume, bs_mesh **out, bs_error *err) {
  if (rc || !(volume > 0)) return rc;
  const double v = bs_mesh_volume(*out), off = (v - volume) / volume;
  if (fabs(off) <= BS_MESH_VOLUME_LOST) return BS_OK;
  bs_mesh_destroy(out);
  return bs_error_set(err, BS_EINPUT,
                      "%s: the mesh encloses %.6g, %+.1f%% off the surface's %.6g (more than %.0f%%: a part thinner "
                      "than the size was lost or a gap filled)",
                      path, v, 100 * off, volume, 100 * BS_MESH_VOLUME_LOST);
}

/* The meshers of opts->surface_mesher on the soup, whose size h has been
 * checked (see the file comment for the auto order); each mesh held to
 * the surface's volume (volume_kept). */
static int mesh_with_meshers(const char *path, const double *pts, int64_t np, const int32_t *tris, int64_t nt,
                             double h, double diag, double volume, const bs_mesh_read_opts *opts, bs_mesh **out,
                             bs_error *err) {
  const int mesher = opts ? opts->surface_mesher : BS_SURFACE_AUTO;
  if (mesher == BS_SURFACE_REMESH)
    return volume_kept(path, bs__mesh_remeshed_surface(path, pts, np, tris, nt, opts, out, err), volume, out, err);
  if (mesher != BS_SURFACE_AUTO)
    return volume_kept(path, mesh3_path(path, pts, np, tris, nt, h, diag, volume, opts, out, err), volume, out, err);
  /* auto: the likelier path first, the other when it refuses */
  bs_error e2;
  bs_error_clear(&e2);
  int rc;
  if (6.0 * volume / (h * h * h) > BS_REMESH_AUTO_TETS) {
    rc = volume_kept(path, bs__mesh_remeshed_surface(path, pts, np, tris, nt, opts, out, &e2), volume, out, &e2);
    if (rc != BS_EINPUT || bs__budget_exceeded(&e2)) {
      if (rc) *err = e2;
      return rc;
    }
    return volume_kept(path, mesh3_path(path, pts, np, tris, nt, h, diag, volume, opts, out, err), volume, out, err);
  }
  rc = volume_kept(path, mesh3_path(path, pts, np, tris, nt, h, diag, volume, opts, out, err), volume, out, err);
  if (rc != BS_EINPUT || bs__budget_exceeded(err)) return rc;
  if ((rc = bs__budget_check(path, "the remesh path", &e2)) ||
      volume_kept(path, bs__mesh_remeshed_surface(path, pts, np, tris, nt, opts, out, &e2), volume, out, &e2)) {
    if (rc) *err = e2;
    return rc ? rc : BS_EINPUT;
  }
  bs_error_clear(err);
  return BS_OK;
}

/* Every mesher refused the clean surface (a boundary that is not a closed
 * 2-manifold where parts touch, the gate on thin walls, a surface that
 * folds once remeshed): its alpha wrap at h meshed instead
 * (bs__surface_wrap, how 2). On refusal the first message stays, and the
 * report's surface (points, triangles, volume) is the repaired one again:
 * the wrap's attempt is kept only in its wrap_* fields. */
static int mesh_wrap(const char *path, const double *pts, int64_t np, const int32_t *tris, int64_t nt, double h,
                     double diag, const bs_mesh_read_opts *opts, bs_mesh **out, bs_error *err) {
  double *wp = NULL, volume = 0;
  int32_t *wt = NULL;
  int64_t nwp = 0, nwt = 0;
  bs_error e2;
  bs_error_clear(&e2);
  bs_surface_report *rep = opts ? opts->report : NULL, before = {0};
  if (rep) before = *rep;
  int rc = bs__surface_wrap(path, pts, np, tris, nt, h, 2, 0, &wp, &nwp, &wt, &nwt, rep, &e2);
  if (!rc) {
    volume = fabs(bs__soup_volume(wp, wt, nwt));
    rc = mesh_with_meshers(path, wp, nwp, wt, nwt, h, diag, volume, opts, out, &e2);
  }
  bs_shim_free(wp);
  bs_shim_free(wt);
  if (!rc) {
    bs_error_clear(err);
    return BS_OK;
  }
  if (rc != BS_EINPUT || bs__budget_exceeded(&e2)) *err = e2;
  if (rep) {
    rep->wrapped = 0;
    rep->points_out = before.points_out, rep->tris_out = before.tris_out, rep->volume = before.volume;
  }
  return rc;
}

/* One solid (or a solid with cavities): the meshers, then the wrap. */
static int mesh_solid(const char *path, const double *pts, int64_t np, const int32_t *tris, int64_t nt,
                      const bs_mesh_read_opts *opts, bs_mesh **out, bs_error *err) {
  const double h = opts ? opts->size : 0.0;
  double diag = 0, volume = 0;
  int rc = check_size(path, pts, np, tris, nt, h, opts, &diag, &volume, err);
  if (rc) return rc;
  rc = mesh_with_meshers(path, pts, np, tris, nt, h, diag, volume, opts, out, err);
  if (rc != BS_EINPUT || bs__budget_exceeded(err)) return rc;
  return mesh_wrap(path, pts, np, tris, nt, h, diag, opts, out, err);
}

/* Separate solids (bs__soup_solids) meshed one at a time and joined; a
 * refusal names the solid. A solid smaller than twice the size across (its
 * bounding-box diagonal) is meshed at half its diagonal: finer where it is
 * needed, rather than a part with no interior at the size. */
static int mesh_solids(const char *path, const bs_soup_part *parts, int64_t n, const bs_mesh_read_opts *opts,
                       bs_mesh **out, bs_error *err) {
  bs_mesh **m = calloc((size_t)n, sizeof *m);
  if (!m) return bs_error_set(err, BS_ENOMEM, "%s: out of memory for the meshes of its solids", path);
  int rc = BS_OK;
  for (int64_t i = 0; i < n && !rc; i++) {
    bs_mesh_read_opts o = *opts;
    o.size = fmin(opts->size, 0.5 * parts[i].diag);
    rc = mesh_solid(path, parts[i].x, parts[i].np, parts[i].tris, parts[i].nt, &o, &m[i], err);
    const size_t len = strlen(err->msg);
    if (rc && len < sizeof err->msg)
      snprintf(err->msg + len, sizeof err->msg - len, " (solid %lld of the surface's %lld, meshed one at a time)",
               (long long)i + 1, (long long)n);
  }
  if (!rc) rc = bs__mesh_concat(path, m, n, out, err);
  for (int64_t i = 0; i < n; i++) bs_mesh_destroy(&m[i]);
  free(m);
  return rc;
}

int bs__mesh_closed_surface(const char *path, const double *pts, int64_t np, const int32_t *tris, int64_t nt,
                            const bs_mesh_read_opts *opts, bs_mesh **out, bs_error *err) {
  *out = NULL;
  if (np <= 0 || nt <= 0)
    return bs_error_set(err, BS_EINPUT, "%s: the surface is empty (%lld points, %lld triangles)", path, (long long)np,
                        (long long)nt);
  bs_soup_part *parts = NULL;
  int64_t n = 0;
  int rc = opts ? bs__soup_solids(path, pts, np, tris, nt, &parts, &n, err) : BS_OK;
  if (!rc) rc = n > 1 ? mesh_solids(path, parts, n, opts, out, err) : mesh_solid(path, pts, np, tris, nt, opts, out, err);
  bs__soup_parts_free(parts, n);
  return rc;
}

static const double auto_cells[BS_SURFACE_AUTO_ATTEMPTS] = {40.0, 60.0};

double bs_surface_auto_size(const double *pts, int64_t np, const int32_t *tris, int64_t nt, int attempt,
                            const bs_mesh_read_opts *opts) {
  if (np <= 0 || nt <= 0 || attempt < 0 || attempt >= BS_SURFACE_AUTO_ATTEMPTS) return 0.0;
  double lo[3], hi[3];
  bs_bbox(np, pts, lo, hi);
  const double h = bs_bbox_diagonal(lo, hi) / auto_cells[attempt];
  const double v = fabs(bs__soup_volume(pts, tris, nt)), cap = bs_mesh_max_tets(opts);
  return v > 0 ? fmax(h, cbrt(6.0 * v / cap)) : h;
}

int bs__mesh_surface_auto(const char *path, const double *pts, int64_t np, const int32_t *tris, int64_t nt,
                          const bs_mesh_read_opts *opts, bs_mesh **out, bs_error *err) {
  bs_mesh_read_opts o = {0};
  if (opts) o = *opts;
  int rc = BS_EINPUT;
  bs_error first;
  bs_error_clear(&first);
  for (int k = 0; k < BS_SURFACE_AUTO_ATTEMPTS; k++) {
    o.size = bs_surface_auto_size(pts, np, tris, nt, k, opts);
    rc = bs__mesh_closed_surface(path, pts, np, tris, nt, &o, out, err);
    if (!rc) {
      (*out)->auto_size = o.size;
      return BS_OK;
    }
    if (k == 0) first = *err;
    if (rc != BS_EINPUT || bs__budget_exceeded(err)) return rc;
  }
  *err = first;
  bs_error_prefix(err, "no size given, chosen %g (diagonal / %g)", bs_surface_auto_size(pts, np, tris, nt, 0, opts),
                  auto_cells[0]);
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
