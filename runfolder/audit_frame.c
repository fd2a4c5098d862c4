/* audit_frame.c — auditing one VTU file (bs_audit.h): the rest mesh from
 * x - displacement, inverted tets and surface self-intersections with exact
 * predicates, vertices inside the simulation's obstacles. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bs_audit.h"
#include "bs_shim.h"
#include "bs_tet10.h"
#include "bs_vtu_read.h"

/* The rest mesh of the previous frame, reused while the connectivity and the
 * rest positions stay the same (the usual case along a run). */
typedef struct mesh_cache {
  bs_mesh *mesh;
  int32_t n_points, n_cells;
  double *rest;   /* 3 n_points, as read */
  int32_t *tets;  /* 4 n_cells, as read  */
  int32_t *newid; /* n_points: compacted vertex id, -1 when no tet uses it */
} mesh_cache;

struct bs_auditor {
  bs_sim *sim; /* borrowed; NULL: no obstacle check */
  mesh_cache cache;
  double *xc; /* the current positions of the rest mesh's vertices */
  size_t xc_cap;
};

static void cache_free(mesh_cache *c) {
  bs_mesh_destroy(&c->mesh);
  free(c->rest);
  free(c->tets);
  free(c->newid);
  memset(c, 0, sizeof *c);
}

int bs_auditor_create(bs_sim *sim, bs_auditor **out, bs_error *err) {
  *out = calloc(1, sizeof **out);
  if (!*out) return bs_error_set(err, BS_ENOMEM, "out of memory");
  (*out)->sim = sim;
  return BS_OK;
}

void bs_auditor_destroy(bs_auditor **a) {
  if (!a || !*a) return;
  cache_free(&(*a)->cache);
  free((*a)->xc);
  free(*a);
  *a = NULL;
}

/* The compaction of bs_mesh_create (it keeps the vertices some tet uses, in
 * input order), which maps the current positions too; returns the count. */
static int32_t compact_ids(const bs_vtu *v, int32_t *newid) {
  const size_t np = (size_t)v->n_points, nc = (size_t)v->n_cells;
  for (size_t i = 0; i < np; i++) newid[i] = -1;
  for (size_t i = 0; i < 4 * nc; i++) newid[v->tets[i]] = 0;
  int32_t k = 0;
  for (size_t i = 0; i < np; i++)
    if (newid[i] == 0) newid[i] = k++;
  return k;
}

/* The rest mesh of v with rest positions rest (taken: kept or freed). */
static int cache_mesh(const bs_vtu *v, double *rest, const char *path, mesh_cache *c, bs_error *err) {
  const size_t np = (size_t)v->n_points, nc = (size_t)v->n_cells;
  if (c->mesh && c->n_points == v->n_points && c->n_cells == v->n_cells &&
      !memcmp(c->tets, v->tets, 4 * nc * sizeof(int32_t)) && !memcmp(c->rest, rest, 3 * np * sizeof(double))) {
    free(rest);
    return BS_OK;
  }
  cache_free(c);
  c->rest = rest;
  c->n_points = v->n_points;
  c->n_cells = v->n_cells;
  c->tets = malloc(4 * nc * sizeof(int32_t));
  c->newid = malloc(np * sizeof(int32_t) + 1);
  if (!c->tets || !c->newid) return bs_error_set(err, BS_ENOMEM, "'%s': out of memory", path);
  memcpy(c->tets, v->tets, 4 * nc * sizeof(int32_t));
  int32_t k = compact_ids(v, c->newid);
  int rc = bs_mesh_create(v->n_points, rest, v->n_cells, v->tets, 0, NULL, &c->mesh, err);
  if (rc) {
    bs_error_prefix(err, "'%s': rest shape (x - displacement)", path);
    cache_free(c);
    return rc;
  }
  if (c->mesh->n_vertices != k) {
    cache_free(c);
    return bs_error_set(err, BS_EINTERNAL, "'%s': rest mesh has %d vertices, expected %d", path, c->mesh->n_vertices,
                        k);
  }
  return BS_OK;
}

/* The largest edge of the box of the n points x. */
static double box_size(const double *x, int32_t n) {
  double lo[3] = {1e300, 1e300, 1e300}, hi[3] = {-1e300, -1e300, -1e300};
  for (int32_t i = 0; i < n; i++)
    for (int k = 0; k < 3; k++) {
      double r = x[3 * (size_t)i + k];
      if (r < lo[k]) lo[k] = r;
      if (r > hi[k]) hi[k] = r;
    }
  double size = 0;
  for (int k = 0; k < 3; k++) size = hi[k] - lo[k] > size ? hi[k] - lo[k] : size;
  return size;
}

/* Vertices inside the scene's obstacles at time t for the file's positions. */
static int audit_obstacles(const bs_vtu *v, const double *rest, const char *path, double t, bs_sim *s,
                           bs_audit_counts *c, bs_error *err) {
  const bs_mesh *m = s->mesh;
  if (v->n_points != m->n_vertices)
    return bs_error_set(err, BS_EINPUT, "'%s' has %d points but the scene's mesh has %d vertices: not a state of this scene",
                        path, v->n_points, m->n_vertices);
  const double size = box_size(m->x, m->n_vertices);
  for (int32_t i = 0; i < m->n_vertices; i++)
    for (int k = 0; k < 3; k++)
      if (fabs(rest[3 * (size_t)i + k] - m->x[3 * (size_t)i + k]) > 1e-9 * size)
        return bs_error_set(err, BS_EINPUT,
                            "'%s': point %d rests at (%g, %g, %g) but the scene's vertex %d rests at (%g, %g, %g): "
                            "not a state of this scene",
                            path, i, rest[3 * (size_t)i], rest[3 * (size_t)i + 1], rest[3 * (size_t)i + 2], i,
                            m->x[3 * (size_t)i], m->x[3 * (size_t)i + 1], m->x[3 * (size_t)i + 2]);
  memcpy(s->x, v->x, 3 * (size_t)m->n_vertices * sizeof(double));
  s->time = t;
  bs_sim_penetration(s, &c->penetrating, &c->max_depth);
  return BS_OK;
}

/* Reads path, checks it against the sim, and makes (or reuses) the rest
 * mesh; *out is the file, for the current positions. */
static int read_state(bs_auditor *a, const char *path, double t, bs_vtu **out, bs_audit_counts *c, bs_error *err) {
  bs_vtu *v = NULL;
  int rc = bs_vtu_read(path, &v, err);
  if (rc) return rc;
  if (v->n_cells == 0) {
    bs_vtu_destroy(&v);
    return bs_error_set(err, BS_EINPUT, "'%s' has no cells: nothing to audit", path);
  }
  double *rest = malloc(3 * (size_t)v->n_points * sizeof(double) + 1);
  if (!rest) {
    bs_vtu_destroy(&v);
    return bs_error_set(err, BS_ENOMEM, "'%s': out of memory", path);
  }
  if ((rc = bs_vtu_rest(v, path, rest, err)) || (a->sim && (rc = audit_obstacles(v, rest, path, t, a->sim, c, err)))) {
    free(rest);
    bs_vtu_destroy(&v);
    return rc;
  }
  if ((rc = cache_mesh(v, rest, path, &a->cache, err))) { /* takes rest */
    bs_vtu_destroy(&v);
    return rc;
  }
  *out = v;
  return BS_OK;
}

/* The current positions of the rest mesh's vertices, into a->xc. */
static int current_positions(bs_auditor *a, const bs_vtu *v, const char *path, bs_error *err) {
  size_t need = 3 * (size_t)a->cache.mesh->n_vertices;
  if (need > a->xc_cap) {
    double *nb = realloc(a->xc, need * sizeof(double));
    if (!nb) return bs_error_set(err, BS_ENOMEM, "'%s': out of memory", path);
    a->xc = nb;
    a->xc_cap = need;
  }
  const int32_t *newid = a->cache.newid;
  for (int32_t i = 0; i < v->n_points; i++)
    if (newid[i] >= 0) memcpy(a->xc + 3 * (size_t)newid[i], v->x + 3 * (size_t)i, 3 * sizeof(double));
  return BS_OK;
}

/* Inverted tets (exact orientation of each, positively oriented at rest)
 * and intersecting surface pairs at the current positions xc. */
static int count_defects(const bs_mesh *m, const double *xc, const char *path, bs_audit_counts *c, bs_error *err) {
  c->n_tets = m->n_tets;
  c->inverted = 0;
  for (int32_t t = 0; t < m->n_tets; t++) {
    const int32_t *tv = m->tets + 4 * (size_t)t;
    int o = bs_shim_orient3d(xc + 3 * (size_t)tv[0], xc + 3 * (size_t)tv[1], xc + 3 * (size_t)tv[2],
                             xc + 3 * (size_t)tv[3]);
    if (o < -1) return bs_error_set(err, BS_EINTERNAL, "'%s': orientation test failed on tet %d", path, t);
    c->inverted += o <= 0;
  }
  int32_t *pairs = NULL;
  int64_t np = 0;
  int rc = bs_shim_self_intersections(xc, m->n_vertices, m->faces, m->n_faces, &pairs, &np, err);
  bs_shim_free(pairs);
  if (rc) {
    bs_error_prefix(err, "'%s': self-intersection test", path);
    return rc;
  }
  c->self_pairs = np;
  return BS_OK;
}

/* Element t's 10 nodes of positions x (VTK order), reoriented as a positive
 * tet at rest when sign < 0 (nodes 1 and 2 swapped, with their edges). */
static void gather10(const int32_t *n10, const double *x, int sign, double out[30]) {
  static const int swap12[10] = {0, 2, 1, 3, 6, 5, 4, 7, 9, 8};
  for (int a = 0; a < 10; a++)
    memcpy(out + 3 * a, x + 3 * (size_t)n10[sign < 0 ? swap12[a] : a], 3 * sizeof(double));
}

/* Quadratic cells whose corners are not inverted but whose curved map
 * folds: det J <= 0 at one of its 10 nodes or 14 quadrature points
 * (bs_tet10_rest_init on the current positions; floating point, not exact). */
static int count_folded_tet10(const bs_vtu *v, const double *rest, const char *path, bs_audit_counts *c,
                              bs_error *err) {
  for (int32_t t = 0; t < v->n_cells; t++) {
    const int32_t *n = v->tets10 + 10 * (size_t)t;
    const int o0 = bs_shim_orient3d(rest + 3 * (size_t)n[0], rest + 3 * (size_t)n[1], rest + 3 * (size_t)n[2],
                                    rest + 3 * (size_t)n[3]);
    const int o = bs_shim_orient3d(v->x + 3 * (size_t)n[0], v->x + 3 * (size_t)n[1], v->x + 3 * (size_t)n[2],
                                   v->x + 3 * (size_t)n[3]);
    if (o0 < -1 || o < -1) return bs_error_set(err, BS_EINTERNAL, "'%s': orientation test failed on tet %d", path, t);
    if (o0 == 0 || o != o0) continue; /* counted by count_defects (or refused at rest) */
    double x[30];
    bs_tet10_rest r;
    bs_error ignore;
    gather10(n, v->x, o0, x);
    if (bs_tet10_rest_init(x, BS_TET10_RULE_14PT_DEG5, &r, &ignore) == BS_ENUMERIC) c->inverted++;
  }
  return BS_OK;
}

int bs_auditor_frame(bs_auditor *a, const char *path, double t, bs_audit_counts *c, bs_error *err) {
  memset(c, 0, sizeof *c);
  bs_vtu *v = NULL;
  int rc = read_state(a, path, t, &v, c, err);
  if (!rc) rc = current_positions(a, v, path, err);
  if (!rc) rc = count_defects(a->cache.mesh, a->xc, path, c, err);
  if (!rc && v->tets10) rc = count_folded_tet10(v, a->cache.rest, path, c, err);
  bs_vtu_destroy(&v);
  return rc;
}
