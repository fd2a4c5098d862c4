/* tet_lift.c — a tet mesh that misses the quality gate, or holds tets of zero
 * volume, lifted by CGAL's tetrahedral isotropic remeshing
 * (bs_shim_tet_remesh): the quality back end of the Mesh_3 path (scans) and
 * of the Gmsh path (CAD), see mesh_internal.h.
 *
 * The rule: first with every boundary triangle kept (BS_SHIM_TET_PROTECT_
 * BOUNDARY: the surface, its groups, volume and distance to the input stay
 * exactly as they were); then, when allowed (a mesh whose only groups are
 * the default "body" and "surface_1") and still under the gate, with the
 * boundary remeshed and its sharp edges (faces turning by more than
 * BS_MESH_FEATURE_ANGLE) constrained, held to the volume check |V - V0| <=
 * BS_LIFT_VOLUME_TOL V0. The target edge length is the mesh size h when
 * known, else the mean edge length of the tets. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bs_shim.h"
#include "mesh_internal.h"

double bs__mean_tet_edge(const double *x, int32_t nt, const int32_t *tets) {
  double sum = 0;
  int64_t n = 0;
  for (int32_t t = 0; t < nt; t++)
    for (int a = 0; a < 4; a++)
      for (int b = a + 1; b < 4; b++) {
        const double *p = x + 3 * (size_t)tets[4 * (size_t)t + a], *q = x + 3 * (size_t)tets[4 * (size_t)t + b];
        sum += sqrt((p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) + (p[2] - q[2]) * (p[2] - q[2]));
        n++;
      }
  return n ? sum / (double)n : 0.0;
}

static void free_out(bs_shim_tet_remesh_out *r) {
  bs_shim_free(r->x);
  bs_shim_free(r->tets);
  bs_shim_free(r->subdomain);
  memset(r, 0, sizeof *r);
}

/* One remeshing with protection `protect`, then the volume check. */
static int lift_once(const char *path, int32_t nv, const double *x, int32_t nt, const int32_t *tets,
                     const int32_t *sub, double h, double gate, int protect, bs_shim_tet_remesh_out *r,
                     bs_error *err) {
  bs_shim_tet_remesh_opts o = {.size = h,
                               .protect = protect,
                               .feature_angle = BS_MESH_FEATURE_ANGLE,
                               .target_dihedral = gate,
                               .iterations = BS_LIFT_ROUNDS,
                               .deadline = bs__budget_deadline()};
  int rc = bs_shim_tet_remesh(path, x, nv, tets, nt, sub, &o, r, err);
  if (rc) return rc;
  const double v0 = r->volume_in, v = r->volume;
  if (v0 > 0 && fabs(v - v0) > BS_LIFT_VOLUME_TOL * v0) {
    rc = bs_error_set(err, BS_EINPUT,
                      "%s: the tetrahedral remeshing changed the volume from %.6g to %.6g (%+.2f%%, beyond %g%%)", path,
                      v0, v, 100 * (v - v0) / v0, 100 * BS_LIFT_VOLUME_TOL);
    free_out(r);
  }
  return rc;
}

/* The lift r into the read's report (bs__read_report), when rc is BS_OK. */
static int record(const bs_shim_tet_remesh_out *r, int rc) {
  bs_surface_report *rep = bs__read_report();
  if (rc || !rep) return rc;
  rep->lifted++;
  rep->lift_dihedral_in = r->dihedral_in;
  rep->lift_dihedral = r->dihedral;
  rep->lift_seconds += r->seconds;
  return rc;
}

int bs__tets_lift(const char *path, int32_t nv, const double *x, int32_t nt, const int32_t *tets, const int32_t *sub,
                  double h, double gate, int allow_boundary, bs_shim_tet_remesh_out *out, bs_error *err) {
  memset(out, 0, sizeof *out);
  int rc = bs__budget_check(path, "the tetrahedral remeshing", err);
  if (rc) return rc;
  if (!(h > 0)) h = bs__mean_tet_edge(x, nt, tets);
  const double target = gate > 0 ? gate : BS_MESH_MIN_DIHEDRAL;
  rc = lift_once(path, nv, x, nt, tets, sub, h, target, BS_SHIM_TET_PROTECT_BOUNDARY, out, err);
  if (rc || out->dihedral >= target || !allow_boundary) return record(out, rc);
  bs_shim_tet_remesh_out second;
  bs_error e2;
  bs_error_clear(&e2);
  if (lift_once(path, nv, x, nt, tets, sub, h, target, BS_SHIM_TET_PROTECT_FEATURES, &second, &e2)) {
    if (bs__budget_exceeded(&e2)) {
      free_out(out);
      *err = e2;
      return e2.code;
    }
    return record(out, BS_OK); /* the first, boundary kept, stands */
  }
  second.seconds += out->seconds;
  if (second.dihedral > out->dihedral) {
    free_out(out);
    *out = second;
  } else {
    out->seconds = second.seconds;
    free_out(&second);
  }
  return record(out, BS_OK);
}

/* The groups of m for the lifted mesh r: 3-D groups from the subdomains
 * (material + 1), lower ones remapped by position (their vertices are on
 * the boundary, which the first lift keeps bitwise). BS_EINPUT when a
 * vertex of a group is not found. */
static int remap_groups(const char *path, const bs_mesh *m, const bs_shim_tet_remesh_out *r, bs_group **out,
                        bs_error *err) {
  int rc = bs__groups_copy(m->groups, m->n_groups, out, err);
  if (rc) return rc;
  int32_t *rep = malloc(((size_t)m->n_vertices + (size_t)r->n_vertices + 1) * sizeof *rep);
  double *both = malloc(3 * ((size_t)m->n_vertices + (size_t)r->n_vertices + 1) * sizeof *both);
  if (!rep || !both) rc = bs_error_set(err, BS_ENOMEM, "%s: out of memory for the groups", path);
  if (!rc) {
    /* new vertices first, so that rep of an old vertex is the new one at its place */
    memcpy(both, r->x, 3 * (size_t)r->n_vertices * sizeof *both);
    memcpy(both + 3 * (size_t)r->n_vertices, m->x, 3 * (size_t)m->n_vertices * sizeof *both);
    if (bs__coincident((int64_t)r->n_vertices + m->n_vertices, both, rep, err) < 0) rc = BS_ENOMEM;
  }
  for (int g = 0; !rc && g < m->n_groups; g++) {
    bs_group *gr = &(*out)[g];
    if (gr->dim == 3) {
      int32_t n = 0;
      for (int64_t t = 0; t < r->n_tets; t++)
        if (r->subdomain[t] - 1 == gr->tag) n++;
      free(gr->elems);
      gr->elems = malloc(((size_t)n + 1) * sizeof *gr->elems);
      if (!gr->elems) rc = bs_error_set(err, BS_ENOMEM, "%s: out of memory for the groups", path);
      gr->n_elems = 0;
      for (int64_t t = 0; !rc && t < r->n_tets; t++)
        if (r->subdomain[t] - 1 == gr->tag) gr->elems[gr->n_elems++] = (int32_t)t;
    } else {
      for (int64_t k = 0; !rc && k < (int64_t)gr->n_elems * (gr->dim + 1); k++) {
        const int32_t v = rep[r->n_vertices + gr->elems[k]];
        if (v >= r->n_vertices)
          rc = bs_error_set(err, BS_EINPUT, "%s: group \"%s\" lost vertex %d in the tetrahedral remeshing", path,
                            gr->name, gr->elems[k]);
        else gr->elems[k] = v;
      }
    }
    free(gr->vertices), gr->vertices = NULL, gr->n_vertices = 0;
  }
  free(rep);
  free(both);
  if (rc) bs__groups_free(*out, m->n_groups), *out = NULL;
  return rc;
}

/* Whether m's groups are the default ones of a surface's mesh. */
static int default_groups(const bs_mesh *m) {
  for (int g = 0; g < m->n_groups; g++)
    if (strcmp(m->groups[g].name, "body") && strcmp(m->groups[g].name, "surface_1")) return 0;
  return 1;
}

int bs__mesh_lift(const char *path, bs_mesh **m, double h, double gate, bs_error *err) {
  bs_mesh *a = *m;
  int32_t *sub = malloc(((size_t)a->n_tets + 1) * sizeof *sub);
  if (!sub) return bs_error_set(err, BS_ENOMEM, "%s: out of memory for the remeshing", path);
  for (int32_t t = 0; t < a->n_tets; t++) sub[t] = a->material[t] + 1;
  bs_shim_tet_remesh_out r;
  const int defaults = default_groups(a);
  int rc = bs__tets_lift(path, a->n_vertices, a->x, a->n_tets, a->tets, sub, h, gate, defaults, &r, err);
  free(sub);
  if (rc) return rc;
  bs_mesh *b = NULL;
  if (r.n_vertices > INT32_MAX || r.n_tets > INT32_MAX)
    rc = bs_error_set(err, BS_EINPUT, "%s: %lld tets exceed the 32-bit index range", path, (long long)r.n_tets);
  else if (defaults)
    rc = bs__mesh_default_groups(path, (int32_t)r.n_vertices, r.x, (int32_t)r.n_tets, r.tets, &b, err);
  else {
    bs_group *groups = NULL;
    rc = remap_groups(path, a, &r, &groups, err);
    if (!rc) rc = bs_mesh_create((int32_t)r.n_vertices, r.x, (int32_t)r.n_tets, r.tets, a->n_groups, groups, &b, err);
    bs__groups_free(groups, a->n_groups);
  }
  free_out(&r);
  if (rc) return rc;
  b->n_coincident = a->n_coincident;
  b->coincident_merged = a->coincident_merged;
  bs_mesh_destroy(m);
  *m = b;
  return BS_OK;
}

int bs__lift_note(const bs_mesh *m, bs_error *err) {
  if (!err) return BS_EINPUT;
  bs_mesh_quality q;
  bs_mesh_quality_compute(m, NULL, &q);
  const size_t n = strlen(err->msg);
  if (n + 96 < sizeof err->msg)
    snprintf(err->msg + n, sizeof err->msg - n, "; CGAL's tetrahedral remeshing of it reached %.3g degrees",
             q.dihedral_min);
  err->code = BS_EINPUT;
  return BS_EINPUT;
}
