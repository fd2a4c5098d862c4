/* refine.c — uniform red (Bey) 1 -> 8 refinement of a tetrahedral mesh.
 *
 * Every edge (a, b) of the mesh gets a new vertex at its midpoint. The fine
 * vertices are the coarse ones (same indices) followed by one midpoint per
 * edge, edges taken in lexicographic order of (min, max) vertex — a
 * deterministic numbering, so coarse vertex i is fine vertex i and refining
 * the same mesh twice yields identical arrays.
 *
 * Tet t = (x0, x1, x2, x3) with midpoints xij gives children 8t .. 8t+7:
 *   8t+0..3  the corner tets (x0 x01 x02 x03), (x01 x1 x12 x13),
 *            (x02 x12 x2 x23), (x03 x13 x23 x3): homotheties of ratio 1/2
 *            about each corner, hence of the parent's orientation;
 *   8t+4..7  the interior octahedron {x01 x02 x03 x12 x13 x23}, split into
 *            four tets around its shortest diagonal (x01-x23, x02-x13 or
 *            x03-x12; ties go to the first). Splitting along the shortest
 *            diagonal keeps the shape regularity bounded over any number
 *            of levels (Bey 1995; Zhang 1995).
 * The orientation tables below give children of positive volume for a
 * positively oriented parent (any affine image of the reference tet).
 * Groups: 3-D groups map each parent to its 8 children; triangles of 2-D
 * groups split in 4 (same midpoints, orientation kept), segments of 1-D
 * groups in 2; 0-D groups are unchanged. */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "bs_mesh.h"
#include "mesh_internal.h"

/* Local numbering: 0..3 the parent's vertices, 4..9 the midpoints of the
 * edges 01, 02, 03, 12, 13, 23. */
static const int edge_ends[6][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};

static const int corner_child[4][4] = {{0, 4, 5, 6}, {4, 1, 7, 8}, {5, 7, 2, 9}, {6, 8, 9, 3}};

/* Octahedron split around diagonal d: children (p, q, r_i, r_{i+1}) with the
 * equatorial ring r ordered so that all four have positive volume. */
static const int oct_child[3][4][4] = {
    /* diagonal x01-x23, ring x02 x03 x13 x12 */
    {{4, 9, 5, 6}, {4, 9, 6, 8}, {4, 9, 8, 7}, {4, 9, 7, 5}},
    /* diagonal x02-x13, ring x01 x12 x23 x03 */
    {{5, 8, 4, 7}, {5, 8, 7, 9}, {5, 8, 9, 6}, {5, 8, 6, 4}},
    /* diagonal x03-x12, ring x01 x02 x23 x13 */
    {{6, 7, 4, 5}, {6, 7, 5, 9}, {6, 7, 9, 8}, {6, 7, 8, 4}},
};
static const int oct_diag[3][2] = {{4, 9}, {5, 8}, {6, 7}};

/* The mesh edges as an upper CSR: row a lists the b > a joined to a by a
 * tet edge, sorted; edge ids run row by row, so id order is lexicographic. */
typedef struct edge_table {
  int32_t n_vertices;
  int64_t n_edges;
  int64_t *ptr; /* n_vertices + 1 */
  int32_t *adj; /* n_edges        */
} edge_table;

static void edge_table_free(edge_table *e) {
  free(e->ptr);
  free(e->adj);
  e->ptr = NULL;
  e->adj = NULL;
}

static void sort_small(int32_t *a, int64_t n) {
  for (int64_t i = 1; i < n; i++) {
    int32_t v = a[i];
    int64_t j = i - 1;
    while (j >= 0 && a[j] > v) {
      a[j + 1] = a[j];
      j--;
    }
    a[j + 1] = v;
  }
}

/* Bucket the 6 edges of every tet by their smaller vertex, then sort and
 * deduplicate each (short) row in place. O(n_tets) time and memory. */
static int edge_table_build(const bs_mesh *m, edge_table *e, bs_error *err) {
  const int32_t nv = m->n_vertices;
  e->n_vertices = nv;
  e->n_edges = 0;
  e->ptr = bs_calloc((size_t)nv + 1, sizeof(int64_t), "refine: edge table rows", err);
  int64_t *fill = bs_calloc((size_t)nv + 1, sizeof(int64_t), "refine: edge table cursor", err);
  if (!e->ptr || !fill) {
    free(fill);
    edge_table_free(e);
    return BS_ENOMEM;
  }
  for (int32_t t = 0; t < m->n_tets; t++) {
    const int32_t *v = m->tets + 4 * (size_t)t;
    for (int k = 0; k < 6; k++) {
      int32_t a = v[edge_ends[k][0]], b = v[edge_ends[k][1]];
      e->ptr[(a < b ? a : b) + 1]++;
    }
  }
  for (int32_t a = 0; a < nv; a++) e->ptr[a + 1] += e->ptr[a];
  e->adj = bs_calloc((size_t)e->ptr[nv] + 1, sizeof(int32_t), "refine: edge table", err);
  if (!e->adj) {
    free(fill);
    edge_table_free(e);
    return BS_ENOMEM;
  }
  memcpy(fill, e->ptr, ((size_t)nv + 1) * sizeof(int64_t));
  for (int32_t t = 0; t < m->n_tets; t++) {
    const int32_t *v = m->tets + 4 * (size_t)t;
    for (int k = 0; k < 6; k++) {
      int32_t a = v[edge_ends[k][0]], b = v[edge_ends[k][1]];
      if (a > b) {
        int32_t s = a;
        a = b;
        b = s;
      }
      e->adj[fill[a]++] = b;
    }
  }
  free(fill);
  /* sort and deduplicate each row, compacting the CSR in place */
  int64_t out = 0;
  for (int32_t a = 0; a < nv; a++) {
    int64_t lo = e->ptr[a], hi = e->ptr[a + 1];
    sort_small(e->adj + lo, hi - lo);
    e->ptr[a] = out;
    for (int64_t i = lo; i < hi; i++)
      if (i == lo || e->adj[i] != e->adj[i - 1]) e->adj[out++] = e->adj[i];
  }
  e->ptr[nv] = out;
  e->n_edges = out;
  return BS_OK;
}

/* Id of edge (a, b) or -1 if it is not a mesh edge. */
static int64_t edge_find(const edge_table *e, int32_t a, int32_t b) {
  if (a > b) {
    int32_t s = a;
    a = b;
    b = s;
  }
  if (a < 0 || b >= e->n_vertices || a == b) return -1;
  int64_t lo = e->ptr[a], hi = e->ptr[a + 1];
  while (lo < hi) {
    int64_t mid = lo + (hi - lo) / 2;
    if (e->adj[mid] < b) lo = mid + 1;
    else hi = mid;
  }
  return (lo < e->ptr[a + 1] && e->adj[lo] == b) ? lo : -1;
}

static double dist2(const double *x, int32_t a, int32_t b) {
  double s = 0.0;
  for (int k = 0; k < 3; k++) {
    double d = x[3 * (size_t)a + k] - x[3 * (size_t)b + k];
    s += d * d;
  }
  return s;
}

/* Refines the elements of one group into fg (which then owns its name and
 * elements; its vertex set is left to bs_mesh_finalize). */
static int refine_group(const bs_group *g, const edge_table *e, int32_t nv, int32_t nt, bs_group *fg,
                        bs_error *err) {
  memset(fg, 0, sizeof *fg);
  fg->dim = g->dim;
  fg->tag = g->tag;
  fg->name = bs__strdup(g->name);
  const char *gname = g->name ? g->name : "";
  if (!fg->name) return bs_error_set(err, BS_ENOMEM, "refine: out of memory copying the name of group '%s'", gname);
  static const int64_t factor[4] = {1, 2, 4, 8};
  static const int tuple[4] = {1, 2, 3, 1};
  if (g->dim < 0 || g->dim > 3)
    return bs_error_set(err, BS_EINPUT, "refine: group '%s' has dimension %d (expected 0..3)", gname, g->dim);
  int64_t n = (int64_t)g->n_elems * factor[g->dim];
  if (n > INT32_MAX)
    return bs_error_set(err, BS_EINPUT, "refine: group '%s' (%d, %d) would have %lld elements (over 2^31)", gname,
                        g->dim, g->tag, (long long)n);
  fg->n_elems = (int32_t)n;
  fg->elems = bs_calloc((size_t)n * tuple[g->dim] + 1, sizeof(int32_t), "refine: group elements", err);
  if (!fg->elems) return BS_ENOMEM;
  int32_t *o = fg->elems;
  for (int32_t i = 0; i < g->n_elems; i++) {
    const int32_t *v = g->elems + (size_t)i * tuple[g->dim];
    if (g->dim == 3) {
      if (v[0] < 0 || v[0] >= nt)
        return bs_error_set(err, BS_EINPUT, "refine: group '%s' (%d, %d) element %d is tet %d (mesh has %d)", gname,
                            g->dim, g->tag, i, v[0], nt);
      for (int c = 0; c < 8; c++) *o++ = 8 * v[0] + c;
      continue;
    }
    if (g->dim == 0) {
      *o++ = v[0];
      continue;
    }
    int nc = g->dim + 1; /* 2 or 3 corners */
    int32_t mid[3];
    for (int k = 0; k < nc; k++)
      if (v[k] < 0 || v[k] >= nv)
        return bs_error_set(err, BS_EINPUT, "refine: group '%s' (%d, %d) element %d uses vertex %d (mesh has %d)",
                            gname, g->dim, g->tag, i, v[k], nv);
    for (int k = 0; k < (g->dim == 1 ? 1 : 3); k++) {
      int32_t a = v[k], b = v[(k + 1) % nc];
      int64_t id = edge_find(e, a, b);
      if (id < 0)
        return bs_error_set(err, BS_EINPUT, "refine: group '%s' (%d, %d) element %d: %d-%d is not an edge of the mesh",
                            gname, g->dim, g->tag, i, a, b);
      mid[k] = nv + (int32_t)id;
    }
    if (g->dim == 1) {
      *o++ = v[0], *o++ = mid[0];
      *o++ = mid[0], *o++ = v[1];
    } else { /* (a b c), mid = (ab, bc, ca): 3 corners + centre, same orientation */
      *o++ = v[0], *o++ = mid[0], *o++ = mid[2];
      *o++ = mid[0], *o++ = v[1], *o++ = mid[1];
      *o++ = mid[2], *o++ = mid[1], *o++ = v[2];
      *o++ = mid[0], *o++ = mid[1], *o++ = mid[2];
    }
  }
  return BS_OK;
}

/* The input's checks: a non-empty mesh whose tets use its vertices, and a
 * fine mesh that fits in int32 indices. */
static int refine_check(const bs_mesh *m, bs_error *err) {
  if (!m || !m->x || !m->tets || m->n_vertices <= 0 || m->n_tets <= 0)
    return bs_error_set(err, BS_EINPUT, "refine: empty or NULL mesh");
  const int32_t nv = m->n_vertices, nt = m->n_tets;
  if ((int64_t)nt * 8 > INT32_MAX)
    return bs_error_set(err, BS_EINPUT, "refine: %d tets would give %lld children (over 2^31)", nt,
                        (long long)nt * 8);
  for (int32_t t = 0; t < nt; t++)
    for (int k = 0; k < 4; k++)
      if (m->tets[4 * (size_t)t + k] < 0 || m->tets[4 * (size_t)t + k] >= nv)
        return bs_error_set(err, BS_EINPUT, "refine: tet %d uses vertex %d (mesh has %d)", t,
                            m->tets[4 * (size_t)t + k], nv);
  return BS_OK;
}

/* Fine vertices: the coarse ones, then the edge midpoints in edge-id order. */
static void refine_vertices(const bs_mesh *m, const edge_table *e, double *x) {
  const int32_t nv = m->n_vertices;
  memcpy(x, m->x, 3 * (size_t)nv * sizeof(double));
  for (int32_t a = 0; a < nv; a++)
    for (int64_t i = e->ptr[a]; i < e->ptr[a + 1]; i++) {
      int32_t b = e->adj[i];
      double *p = x + 3 * ((size_t)nv + (size_t)i);
      for (int k = 0; k < 3; k++) p[k] = 0.5 * (m->x[3 * (size_t)a + k] + m->x[3 * (size_t)b + k]);
    }
}

/* The 8 children of tet t: its 4 corners, then the octahedron split around
 * its shortest diagonal (x: the fine vertices). */
static int refine_tet(const bs_mesh *m, const edge_table *e, const double *x, int32_t t, int32_t *tets,
                      bs_error *err) {
  const int32_t nv = m->n_vertices;
  int32_t l[10];
  for (int k = 0; k < 4; k++) l[k] = m->tets[4 * (size_t)t + k];
  for (int k = 0; k < 6; k++) {
    int64_t id = edge_find(e, l[edge_ends[k][0]], l[edge_ends[k][1]]);
    if (id < 0) /* cannot happen: every tet edge is in the table */
      return bs_error_set(err, BS_EINTERNAL, "refine: edge %d-%d of tet %d missing from the edge table",
                          l[edge_ends[k][0]], l[edge_ends[k][1]], t);
    l[4 + k] = nv + (int32_t)id;
  }
  int32_t *c = tets + 32 * (size_t)t;
  for (int j = 0; j < 4; j++)
    for (int k = 0; k < 4; k++) *c++ = l[corner_child[j][k]];
  int best = 0;
  double dbest = dist2(x, l[oct_diag[0][0]], l[oct_diag[0][1]]);
  for (int d = 1; d < 3; d++) {
    double dd = dist2(x, l[oct_diag[d][0]], l[oct_diag[d][1]]);
    if (dd < dbest) {
      dbest = dd;
      best = d;
    }
  }
  for (int j = 0; j < 4; j++)
    for (int k = 0; k < 4; k++) *c++ = l[oct_child[best][j][k]];
  return BS_OK;
}

/* The fine mesh from its arrays (taken over: *x, *tets, *groups are nulled),
 * without a copy of the big arrays: the input is a valid mesh, so tags are
 * positive and unique and the groups already in (dim, tag) order;
 * bs_mesh_finalize derives the rest. Children inherit their parent's
 * material (also what the 3-D groups say). */
static int refine_assemble(const bs_mesh *m, int32_t fnv, double **x, int32_t **tets, bs_group **groups,
                           bs_mesh **out, bs_error *err) {
  bs_mesh *f = bs_calloc(1, sizeof *f, "refine: mesh", err);
  if (!f) return BS_ENOMEM;
  f->n_vertices = fnv;
  f->x = *x;
  f->n_tets = 8 * m->n_tets;
  f->tets = *tets;
  f->n_groups = m->n_groups;
  f->groups = *groups;
  *x = NULL;
  *tets = NULL;
  *groups = NULL;
  int rc = bs_mesh_finalize(f, err);
  if (rc) {
    bs_error_prefix(err, "refine");
    bs_mesh_destroy(&f);
    return rc;
  }
  if (m->material && f->material)
    for (int32_t t = 0; t < m->n_tets; t++)
      for (int c = 0; c < 8; c++) f->material[8 * (size_t)t + c] = m->material[t];
  *out = f;
  return BS_OK;
}

int bs_mesh_refine(const bs_mesh *m, bs_mesh **out, bs_error *err) {
  if (!out) return bs_error_set(err, BS_EINPUT, "refine: output pointer is NULL");
  *out = NULL;
  int rc = refine_check(m, err);
  if (rc) return rc;
  if (m->tets10) return bs_error_set(err, BS_EINPUT, "refine: the mesh is quadratic (tet10): refine its linear mesh");
  const int32_t nv = m->n_vertices, nt = m->n_tets;
  edge_table e = {0};
  if ((rc = edge_table_build(m, &e, err))) return rc;
  if ((int64_t)nv + e.n_edges > INT32_MAX) {
    rc = bs_error_set(err, BS_EINPUT, "refine: %d vertices + %lld edge midpoints exceed 2^31", nv,
                      (long long)e.n_edges);
    edge_table_free(&e);
    return rc;
  }
  const int32_t fnv = nv + (int32_t)e.n_edges;
  double *x = bs_calloc(3 * (size_t)fnv, sizeof(double), "refine: fine vertices", err);
  int32_t *tets = bs_calloc(4 * (size_t)(8 * nt), sizeof(int32_t), "refine: fine tets", err);
  bs_group *groups = NULL;
  if (m->n_groups > 0) groups = bs_calloc((size_t)m->n_groups, sizeof(bs_group), "refine: groups", err);
  if (!x || !tets || (m->n_groups > 0 && !groups)) rc = BS_ENOMEM;
  if (!rc) refine_vertices(m, &e, x);
  for (int32_t t = 0; t < nt && !rc; t++) rc = refine_tet(m, &e, x, t, tets, err);
  for (int g = 0; g < m->n_groups && !rc; g++) rc = refine_group(&m->groups[g], &e, nv, nt, &groups[g], err);
  if (!rc) rc = refine_assemble(m, fnv, &x, &tets, &groups, out, err);
  free(x);
  free(tets);
  bs__groups_free(groups, m->n_groups);
  edge_table_free(&e);
  return rc;
}
