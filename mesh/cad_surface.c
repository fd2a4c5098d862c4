/* cad_surface.c — a geometry's Gmsh mesh that misses the quality gate and
 * that CGAL's tetrahedral remeshing cannot lift (its tets do not form a
 * triangulation the remesher takes: a part with a through hole, say) meshed
 * again from its own boundary by the surface path (bs__mesh_closed_surface:
 * Mesh_3 with the sharp edges kept, sliver exudation, the alpha wrap behind
 * it), with its groups carried over (mesh_internal.h, bs__mesh_cad_by_surface).
 *
 * Groups: the one 3-D group (all tets) keeps its name and tag; each new
 * boundary triangle takes the 2-D group of the Gmsh boundary triangle
 * closest to its centroid (an AABB tree over the old boundary), so the CAD
 * faces' groups follow the surface. The path is not taken (BS_EINPUT, the
 * caller keeps its own message) when the groups cannot be carried that way:
 * several 3-D groups or one that is not every tet, 0-D or 1-D groups, or a
 * boundary triangle in two 2-D groups. The new mesh must enclose the Gmsh
 * mesh's volume to BS_FROM_BOUNDARY_VOLUME_TOL (else BS_EINPUT, said). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bs_shim.h"
#include "mesh_internal.h"

/* Whether m's groups can be carried over (see the top). */
static int carriable(const bs_mesh *m) {
  int n3 = 0;
  int64_t in2 = 0, tagged = 0;
  for (int g = 0; g < m->n_groups; g++) {
    const bs_group *gr = &m->groups[g];
    if (gr->dim < 2) return 0;
    if (gr->dim == 3 && (++n3 > 1 || gr->n_elems != m->n_tets)) return 0;
    if (gr->dim == 2) in2 += gr->n_elems;
  }
  for (int32_t f = 0; f < m->n_faces; f++) tagged += m->boundary[f] != 0;
  return in2 == tagged;
}

/* The groups of the new mesh b (groups from old mesh a): tag2[f] is the 2-D
 * tag of b's face f. *out has a->n_groups entries, elems filled. */
static int carry_groups(const char *path, const bs_mesh *a, const bs_mesh *b, const int *tag2, bs_group **out,
                        bs_error *err) {
  int rc = bs__groups_copy(a->groups, a->n_groups, out, err);
  for (int g = 0; !rc && g < a->n_groups; g++) {
    bs_group *gr = &(*out)[g];
    free(gr->elems);
    free(gr->vertices), gr->vertices = NULL, gr->n_vertices = 0;
    const int32_t n = gr->dim == 3 ? b->n_tets : 0;
    int32_t k = 0;
    if (gr->dim == 2)
      for (int32_t f = 0; f < b->n_faces; f++) k += tag2[f] == gr->tag;
    gr->elems = malloc(((size_t)(gr->dim == 3 ? n : 3 * k) + 1) * sizeof *gr->elems);
    if (!gr->elems) rc = bs_error_set(err, BS_ENOMEM, "%s: out of memory for the groups", path);
    gr->n_elems = gr->dim == 3 ? n : k;
    for (int32_t t = 0; !rc && gr->dim == 3 && t < n; t++) gr->elems[t] = t;
    for (int32_t f = 0, j = 0; !rc && gr->dim == 2 && f < b->n_faces; f++)
      if (tag2[f] == gr->tag) memcpy(gr->elems + 3 * (size_t)j++, b->faces + 3 * (size_t)f, 3 * sizeof(int32_t));
  }
  if (rc && *out) bs__groups_free(*out, a->n_groups), *out = NULL;
  return rc;
}

/* tag2[f] for each face of b: the 2-D tag of a's boundary triangle closest
 * to the face's centroid. */
static int closest_tags(const char *path, const bs_mesh *a, const bs_mesh *b, int *tag2, bs_error *err) {
  bs_shim_tree *t = NULL;
  int rc = bs_shim_tree_create(a->x, a->n_vertices, a->faces, a->n_faces, &t, err);
  for (int32_t f = 0; !rc && f < b->n_faces; f++) {
    double c[3] = {0, 0, 0};
    for (int k = 0; k < 3; k++)
      for (int i = 0; i < 3; i++) c[i] += b->x[3 * (size_t)b->faces[3 * (size_t)f + k] + i] / 3.0;
    int32_t tri = -1;
    rc = bs_shim_tree_closest(t, c, NULL, &tri, NULL, NULL);
    if (!rc && (tri < 0 || tri >= a->n_faces)) rc = BS_EINTERNAL;
    if (rc) bs_error_set(err, rc, "%s: the closest old boundary triangle of face %d was not found", path, f);
    else tag2[f] = a->boundary[tri];
  }
  bs_shim_tree_destroy(&t);
  return rc;
}

/* a's boundary as a soup of its own vertices only (the surface path takes
 * no isolated point), meshed by the surface path at h into *b. */
static int boundary_meshed(const char *path, const bs_mesh *a, double h, const bs_mesh_read_opts *opts, bs_mesh **b,
                           bs_error *err) {
  bs_mesh_read_opts o = {0};
  if (opts) o = *opts;
  o.size = h;
  o.report = NULL;
  int32_t *id = malloc(((size_t)a->n_vertices + 1) * sizeof *id), *tris = malloc((3 * (size_t)a->n_faces + 1) * sizeof *tris);
  double *pts = malloc((3 * (size_t)a->n_vertices + 1) * sizeof *pts);
  int rc = id && tris && pts ? BS_OK : bs_error_set(err, BS_ENOMEM, "%s: out of memory for the boundary", path);
  int32_t n = 0;
  for (int32_t v = 0; !rc && v < a->n_vertices; v++) id[v] = -1;
  for (int64_t k = 0; !rc && k < 3 * (int64_t)a->n_faces; k++) {
    const int32_t v = a->faces[k];
    if (id[v] < 0) memcpy(pts + 3 * (size_t)n, a->x + 3 * (size_t)v, 3 * sizeof(double)), id[v] = n++;
    tris[k] = id[v];
  }
  if (!rc) rc = bs__mesh_closed_surface(path, pts, n, tris, a->n_faces, &o, b, err);
  free(id), free(tris), free(pts);
  return rc;
}

/* err (the gate's message) with what the surface path said appended. */
static int keep_first(bs_error *err, const bs_error *second) {
  const size_t n = strlen(err->msg);
  if (n + 64 < sizeof err->msg)
    snprintf(err->msg + n, sizeof err->msg - n, "; meshed again from its boundary by CGAL: %.*s",
             (int)(sizeof err->msg - n - 48), second->msg);
  err->code = BS_EINPUT;
  return BS_EINPUT;
}

/* The mean thickness 2 V / A of a (volume over boundary area). */
static double mean_thickness(const bs_mesh *a) {
  double area = 0;
  for (int32_t f = 0; f < a->n_faces; f++) {
    const double *p = a->x + 3 * (size_t)a->faces[3 * (size_t)f], *q = a->x + 3 * (size_t)a->faces[3 * (size_t)f + 1],
                 *r = a->x + 3 * (size_t)a->faces[3 * (size_t)f + 2];
    const double u[3] = {q[0] - p[0], q[1] - p[1], q[2] - p[2]}, v[3] = {r[0] - p[0], r[1] - p[1], r[2] - p[2]};
    const double c[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
    area += 0.5 * sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
  }
  return area > 0 ? 2 * bs_mesh_volume(a) / area : 0.0;
}

int bs__mesh_cad_by_surface(const char *path, bs_mesh **m, double h, const bs_mesh_read_opts *opts, bs_error *err) {
  const bs_mesh *a = *m;
  if (!carriable(a)) return BS_EINPUT;
  if (!(h > 0)) h = bs__mean_tet_edge(a->x, a->n_tets, a->tets);
  /* a part much thinner than h (a plate): Mesh_3's protection of its edges takes minutes, for nothing */
  if (mean_thickness(a) < BS_FROM_BOUNDARY_MIN_THICKNESS * h) return BS_EINPUT;
  bs_mesh *b = NULL, *c = NULL;
  bs_error e2;
  bs_error_clear(&e2);
  int rc = boundary_meshed(path, a, h, opts, &b, &e2);
  if (rc && (rc != BS_EINPUT || bs__budget_exceeded(&e2))) {
    *err = e2;
    return rc;
  }
  if (rc) return keep_first(err, &e2);
  int *tag2 = malloc(((size_t)b->n_faces + 1) * sizeof *tag2);
  bs_group *groups = NULL;
  if (!tag2) rc = bs_error_set(err, BS_ENOMEM, "%s: out of memory for the groups", path);
  if (!rc) rc = closest_tags(path, a, b, tag2, err);
  if (!rc) rc = carry_groups(path, a, b, tag2, &groups, err);
  if (!rc) rc = bs_mesh_create(b->n_vertices, b->x, b->n_tets, b->tets, a->n_groups, groups, &c, err);
  if (groups) bs__groups_free(groups, a->n_groups);
  free(tag2);
  bs_mesh_destroy(&b);
  if (rc) return rc;
  const double v0 = bs_mesh_volume(a), dv = v0 > 0 ? (bs_mesh_volume(c) - v0) / v0 : 0.0;
  if (fabs(dv) > BS_FROM_BOUNDARY_VOLUME_TOL) {
    bs_mesh_destroy(&c);
    bs_error_set(&e2, BS_EINPUT, "it passes the gate but its volume differs from Gmsh's mesh by %+.2f%% (beyond %g%%)",
                 100 * dv, 100 * BS_FROM_BOUNDARY_VOLUME_TOL);
    return keep_first(err, &e2);
  }
  bs_surface_report *rep = bs__read_report();
  if (rep) {
    bs_mesh_quality q;
    bs_mesh_quality_compute(a, NULL, &q);
    rep->from_boundary = 1;
    rep->from_boundary_dihedral_in = q.dihedral_min;
    rep->from_boundary_volume_change = dv;
  }
  bs_mesh_destroy(m);
  *m = c;
  return BS_OK;
}
