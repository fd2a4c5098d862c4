/* mesh.c — creation, derived topology, checker and queries of bs_mesh.
 *
 * Faces are found by bucketing the 4 n_tets tet faces by their smallest
 * vertex (a counting sort, O(n)), then sorting each (small) bucket by the
 * other two vertices: a face key is its sorted vertex triple (a < b < c).
 * A key seen once is a boundary face, twice an interior face; more is an
 * error. Everything here is O(n) or O(n log k) with k a bucket size.
 */
#include "mesh_internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Face f is opposite local vertex f. With V = det[x1-x0, x2-x0, x3-x0]/6 > 0
 * (e.g. x0 = 0, x1 = e1, x2 = e2, x3 = e3) these orders give (b-a) x (c-a)
 * pointing away from the opposite vertex: (1,2,3) -> (1,1,1), (0,3,2) -> -e1,
 * (0,1,3) -> -e2, (0,2,1) -> -e3. */
const int bs_tet_face[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};

/* ---- small helpers ------------------------------------------------------ */

char *bs__strdup(const char *s) {
  if (!s) s = "";
  size_t n = strlen(s) + 1;
  char *d = malloc(n);
  if (d) memcpy(d, s, n);
  return d;
}

static void *dup_array(const void *src, size_t n, size_t size, const char *what, bs_error *err) {
  void *d = bs_calloc(n, size, what, err);
  if (d && src && n) memcpy(d, src, n * size);
  return d;
}

static void sort3(int32_t v[3]) {
  int32_t t;
  if (v[0] > v[1]) { t = v[0]; v[0] = v[1]; v[1] = t; }
  if (v[1] > v[2]) { t = v[1]; v[1] = v[2]; v[2] = t; }
  if (v[0] > v[1]) { t = v[0]; v[0] = v[1]; v[1] = t; }
}

/* Signed volume det[x1-x0, x2-x0, x3-x0] / 6 of the tet with vertices t[4]. */
static double tet_volume(const double *x, const int32_t *t) {
  const double *p0 = x + 3 * t[0], *p1 = x + 3 * t[1], *p2 = x + 3 * t[2], *p3 = x + 3 * t[3];
  double a[3], b[3], c[3];
  for (int k = 0; k < 3; ++k) {
    a[k] = p1[k] - p0[k];
    b[k] = p2[k] - p0[k];
    c[k] = p3[k] - p0[k];
  }
  return (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) +
          a[2] * (b[0] * c[1] - b[1] * c[0])) / 6.0;
}

static double longest_edge2(const double *x, const int32_t *t) {
  double m = 0.0;
  for (int i = 0; i < 4; ++i)
    for (int j = i + 1; j < 4; ++j) {
      double d2 = 0.0;
      for (int k = 0; k < 3; ++k) {
        double d = x[3 * t[i] + k] - x[3 * t[j] + k];
        d2 += d * d;
      }
      if (d2 > m) m = d2;
    }
  return m;
}

/* ---- groups ------------------------------------------------------------- */

void bs__groups_free(bs_group *g, int n) {
  if (!g) return;
  for (int i = 0; i < n; ++i) {
    free(g[i].name);
    free(g[i].elems);
    free(g[i].vertices);
  }
  free(g);
}

int bs__groups_copy(const bs_group *src, int n, bs_group **out, bs_error *err) {
  *out = NULL;
  if (n <= 0) return BS_OK;
  bs_group *g = bs_calloc((size_t)n, sizeof *g, "mesh groups", err);
  if (!g) return BS_ENOMEM;
  for (int i = 0; i < n; ++i) {
    const bs_group *s = &src[i];
    g[i].dim = s->dim;
    g[i].tag = s->tag;
    g[i].name = bs__strdup(s->name);
    g[i].n_elems = s->n_elems;
    g[i].n_vertices = s->n_vertices;
    size_t ne = (size_t)(s->n_elems > 0 ? s->n_elems : 0) * (size_t)bs__group_elem_size(s->dim);
    if (!g[i].name) goto nomem;
    if (s->elems && ne) {
      g[i].elems = dup_array(s->elems, ne, sizeof(int32_t), "group elements", err);
      if (!g[i].elems) goto nomem;
    }
    if (s->vertices && s->n_vertices > 0) {
      g[i].vertices = dup_array(s->vertices, (size_t)s->n_vertices, sizeof(int32_t), "group vertices", err);
      if (!g[i].vertices) goto nomem;
    } else {
      g[i].n_vertices = 0;
    }
  }
  *out = g;
  return BS_OK;
nomem:
  bs__groups_free(g, n);
  return bs_error_set(err, BS_ENOMEM, "out of memory copying mesh groups");
}

int bs__group_update_vertices(const bs_mesh *m, bs_group *g, bs_error *err) {
  int32_t nv = m->n_vertices;
  size_t per = g->dim < 3 ? (size_t)g->dim + 1 : 4;
  size_t k = (size_t)(g->n_elems > 0 ? g->n_elems : 0) * per;
  free(g->vertices);
  g->vertices = NULL;
  g->n_vertices = 0;
  if (k == 0) return BS_OK;
  int32_t *list = NULL;
  int32_t n = 0;
  if (k >= (size_t)nv / 16) {
    /* Dense: a marker over all vertices, collected in increasing order. */
    unsigned char *mark = bs_calloc((size_t)nv, 1, "group vertex marker", err);
    if (!mark) return BS_ENOMEM;
    for (int32_t e = 0; e < g->n_elems; ++e) {
      if (g->dim < 3)
        for (size_t j = 0; j < per; ++j) mark[g->elems[(size_t)e * per + j]] = 1;
      else
        for (int j = 0; j < 4; ++j) mark[m->tets[4 * (size_t)g->elems[e] + j]] = 1;
    }
    for (int32_t v = 0; v < nv; ++v) n += mark[v];
    list = bs_calloc((size_t)n, sizeof *list, "group vertices", err);
    if (!list) {
      free(mark);
      return BS_ENOMEM;
    }
    n = 0;
    for (int32_t v = 0; v < nv; ++v)
      if (mark[v]) list[n++] = v;
    free(mark);
  } else {
    /* Sparse: sort the element vertices and keep the unique ones. */
    list = bs_calloc(k, sizeof *list, "group vertices", err);
    if (!list) return BS_ENOMEM;
    for (int32_t e = 0; e < g->n_elems; ++e) {
      if (g->dim < 3)
        for (size_t j = 0; j < per; ++j) list[(size_t)e * per + j] = g->elems[(size_t)e * per + j];
      else
        for (int j = 0; j < 4; ++j) list[(size_t)e * 4 + j] = m->tets[4 * (size_t)g->elems[e] + j];
    }
    qsort(list, k, sizeof *list, bs_cmp_i32);
    for (size_t i = 0; i < k; ++i)
      if (n == 0 || list[i] != list[n - 1]) list[n++] = list[i];
    int32_t *shrunk = realloc(list, (size_t)n * sizeof *list);
    if (shrunk) list = shrunk;
  }
  g->vertices = list;
  g->n_vertices = n;
  return BS_OK;
}

static int cmp_group(const void *a, const void *b) {
  const bs_group *x = a, *y = b;
  if (x->dim != y->dim) return x->dim < y->dim ? -1 : 1;
  return (x->tag > y->tag) - (x->tag < y->tag);
}

/* ---- the face table ----------------------------------------------------- */

/* One tet face: key (a, b, c) sorted with a given by the bucket, and
 * id = 4 t + f (local face f of tet t). */
typedef struct {
  int32_t b, c, id;
} face_rec;

static int cmp_face(const face_rec *x, const face_rec *y) {
  if (x->b != y->b) return x->b < y->b ? -1 : 1;
  if (x->c != y->c) return x->c < y->c ? -1 : 1;
  return (x->id > y->id) - (x->id < y->id);
}

static int cmp_face_q(const void *a, const void *b) { return cmp_face(a, b); }

static void face_key(const int32_t *tets, int32_t id, int32_t v[3]) {
  const int32_t *t = tets + 4 * (size_t)(id >> 2);
  const int *f = bs_tet_face[id & 3];
  v[0] = t[f[0]];
  v[1] = t[f[1]];
  v[2] = t[f[2]];
  sort3(v);
}

/* Buckets all tet faces by smallest vertex: on return rec[ptr[a] .. ptr[a+1])
 * holds the faces whose smallest vertex is a, sorted by (b, c, id). */
static int face_table(const int32_t *tets, int32_t nt, int32_t nv, int32_t **ptr_out, face_rec **rec_out,
                      bs_error *err) {
  *ptr_out = NULL;
  *rec_out = NULL;
  int32_t *ptr = bs_calloc((size_t)nv + 1, sizeof *ptr, "face buckets", err);
  if (!ptr) return BS_ENOMEM;
  face_rec *rec = bs_calloc((size_t)nt * 4, sizeof *rec, "face table", err);
  if (!rec) {
    free(ptr);
    return BS_ENOMEM;
  }
  int32_t v[3];
  for (int32_t id = 0; id < 4 * nt; ++id) {
    face_key(tets, id, v);
    ptr[v[0] + 1]++;
  }
  for (int32_t a = 0; a < nv; ++a) ptr[a + 1] += ptr[a];
  for (int32_t id = 0; id < 4 * nt; ++id) {
    face_key(tets, id, v);
    face_rec *r = &rec[ptr[v[0]]++];
    r->b = v[1];
    r->c = v[2];
    r->id = id;
  }
  for (int32_t a = nv; a > 0; --a) ptr[a] = ptr[a - 1];
  ptr[0] = 0;
  for (int32_t a = 0; a < nv; ++a) {
    face_rec *r = rec + ptr[a];
    int32_t n = ptr[a + 1] - ptr[a];
    if (n > 32) {
      qsort(r, (size_t)n, sizeof *r, cmp_face_q);
      continue;
    }
    for (int32_t i = 1; i < n; ++i) { /* insertion sort: buckets are small */
      face_rec key = r[i];
      int32_t j = i - 1;
      while (j >= 0 && cmp_face(&r[j], &key) > 0) {
        r[j + 1] = r[j];
        --j;
      }
      r[j + 1] = key;
    }
  }
  *ptr_out = ptr;
  *rec_out = rec;
  return BS_OK;
}

/* Length of the run of equal keys starting at rec[i] (bounded by end). */
static int32_t run_length(const face_rec *rec, int32_t i, int32_t end) {
  int32_t j = i + 1;
  while (j < end && rec[j].b == rec[i].b && rec[j].c == rec[i].c) ++j;
  return j - i;
}

/* Oriented vertices of local face (id & 3) of tet (id >> 2). */
static void face_oriented(const int32_t *tets, int32_t id, int32_t v[3]) {
  const int32_t *t = tets + 4 * (size_t)(id >> 2);
  const int *f = bs_tet_face[id & 3];
  v[0] = t[f[0]];
  v[1] = t[f[1]];
  v[2] = t[f[2]];
}

/* +1 if (u) is a cyclic rotation of (v), -1 if of its reverse, 0 if the sets differ. */
static int same_cycle(const int32_t u[3], const int32_t v[3]) {
  for (int s = 0; s < 3; ++s) {
    if (u[0] == v[s] && u[1] == v[(s + 1) % 3] && u[2] == v[(s + 2) % 3]) return 1;
    if (u[0] == v[s] && u[1] == v[(s + 2) % 3] && u[2] == v[(s + 1) % 3]) return -1;
  }
  return 0;
}

static int face_shared_error(const int32_t *tets, const face_rec *r, int32_t a, int32_t n, bs_error *err) {
  return bs_error_set(err, BS_EINPUT,
                      "face (%d %d %d) is shared by %d tets (tets %d, %d, %d%s); at most two may share a face", a,
                      r[0].b, r[0].c, n, r[0].id >> 2, r[1].id >> 2, r[2].id >> 2, n > 3 ? ", ..." : "");
}

/* ---- finalize ----------------------------------------------------------- */

static void free_derived(bs_mesh *m) {
  free(m->material);
  free(m->faces);
  free(m->face_tet);
  free(m->boundary);
  free(m->edges);
  free(m->v2t_ptr);
  free(m->v2t);
  m->material = m->faces = m->face_tet = m->boundary = m->edges = m->v2t_ptr = m->v2t = NULL;
  m->n_faces = m->n_edges = 0;
}

static const char *gname(const bs_group *g) { return g->name ? g->name : ""; }

/* Element ranges of every group (vertices for dim < 3, tets for dim 3). */
static int check_group_ranges(const bs_group *groups, int n_groups, int32_t nv, int32_t nt, bs_error *err) {
  for (int i = 0; i < n_groups; ++i) {
    const bs_group *g = &groups[i];
    if (g->dim < 0 || g->dim > 3)
      return bs_error_set(err, BS_EINPUT, "group \"%s\" (dim %d, tag %d): dimension must be 0, 1, 2 or 3", gname(g),
                          g->dim, g->tag);
    if (g->n_elems < 0 || (g->n_elems > 0 && !g->elems))
      return bs_error_set(err, BS_EINPUT, "group \"%s\" (dim %d, tag %d): %d elements but no element array",
                          gname(g), g->dim, g->tag, g->n_elems);
    int per = bs__group_elem_size(g->dim);
    int32_t lim = g->dim < 3 ? nv : nt;
    for (int32_t e = 0; e < g->n_elems; ++e)
      for (int j = 0; j < per; ++j) {
        int32_t v = g->elems[(size_t)e * per + j];
        if (v < 0 || v >= lim)
          return bs_error_set(err, BS_EINPUT, "group \"%s\" (dim %d, tag %d): element %d references %s %d, out of range [0, %d)",
                              gname(g), g->dim, g->tag, e, g->dim < 3 ? "vertex" : "tet", v, lim);
      }
  }
  return BS_OK;
}

static int check_tet_ranges(const int32_t *tets, int32_t nt, int32_t nv, bs_error *err) {
  for (int32_t t = 0; t < nt; ++t)
    for (int j = 0; j < 4; ++j) {
      int32_t v = tets[4 * (size_t)t + j];
      if (v < 0 || v >= nv)
        return bs_error_set(err, BS_EINPUT, "tet %d has vertex index %d out of range [0, %d)", t, v, nv);
    }
  return BS_OK;
}

int bs__tet_flat(const double *x, const int32_t *tv) {
  const double l2 = longest_edge2(x, tv);
  return !(fabs(tet_volume(x, tv)) > 1e-14 * l2 * sqrt(l2));
}

/* Reorients each tet to positive volume; zero volume (bs__tet_flat) is an
 * error naming the tet. */
static int orient_tets(bs_mesh *m, bs_error *err) {
  for (int32_t t = 0; t < m->n_tets; ++t) {
    int32_t *tv = m->tets + 4 * (size_t)t;
    double vol = tet_volume(m->x, tv);
    if (bs__tet_flat(m->x, tv))
      return bs_error_set(err, BS_EINPUT, "tet %d has zero volume (vertices %d %d %d %d)", t, tv[0], tv[1], tv[2],
                          tv[3]);
    if (vol < 0) {
      int32_t s = tv[2];
      tv[2] = tv[3];
      tv[3] = s;
    }
  }
  return BS_OK;
}

/* Boundary faces (outward) and face_tet from the face table; keys of the
 * boundary faces (in emission order = sorted key order) go to bkey/bptr so
 * that group triangles can be matched. */
static int derive_faces(bs_mesh *m, int32_t **bptr_out, int32_t **bkey_out, bs_error *err) {
  int32_t *ptr = NULL, *bptr = NULL, *bkey = NULL;
  face_rec *rec = NULL;
  int rc = face_table(m->tets, m->n_tets, m->n_vertices, &ptr, &rec, err);
  if (rc) return rc;
  int32_t nb = 0;
  for (int32_t a = 0; a < m->n_vertices; ++a) {
    for (int32_t i = ptr[a]; i < ptr[a + 1];) {
      int32_t n = run_length(rec, i, ptr[a + 1]);
      if (n > 2) {
        rc = face_shared_error(m->tets, rec + i, a, n, err);
        goto done;
      }
      nb += (n == 1);
      i += n;
    }
  }
  m->n_faces = nb;
  m->faces = bs_calloc((size_t)nb * 3, sizeof(int32_t), "boundary faces", err);
  m->face_tet = bs_calloc((size_t)nb, sizeof(int32_t), "boundary face tets", err);
  m->boundary = bs_calloc((size_t)nb, sizeof(int32_t), "boundary ids", err);
  bptr = bs_calloc((size_t)m->n_vertices + 1, sizeof *bptr, "boundary face buckets", err);
  bkey = bs_calloc((size_t)nb * 2, sizeof *bkey, "boundary face keys", err);
  if (!m->faces || !m->face_tet || !m->boundary || !bptr || !bkey) {
    rc = BS_ENOMEM;
    goto done;
  }
  nb = 0;
  for (int32_t a = 0; a < m->n_vertices; ++a) {
    for (int32_t i = ptr[a]; i < ptr[a + 1];) {
      int32_t n = run_length(rec, i, ptr[a + 1]);
      if (n == 1) {
        face_oriented(m->tets, rec[i].id, m->faces + 3 * (size_t)nb);
        m->face_tet[nb] = rec[i].id >> 2;
        bkey[2 * (size_t)nb] = rec[i].b;
        bkey[2 * (size_t)nb + 1] = rec[i].c;
        ++nb;
      }
      i += n;
    }
    bptr[a + 1] = nb;
  }
done:
  free(ptr);
  free(rec);
  if (rc) {
    free(bptr);
    free(bkey);
    return rc;
  }
  *bptr_out = bptr;
  *bkey_out = bkey;
  return BS_OK;
}

/* Boundary face index with sorted key v, or -1. */
static int32_t find_boundary_face(const int32_t *bptr, const int32_t *bkey, const int32_t v[3]) {
  int32_t lo = bptr[v[0]], hi = bptr[v[0] + 1];
  while (lo < hi) {
    int32_t mid = lo + (hi - lo) / 2;
    int32_t b = bkey[2 * (size_t)mid], c = bkey[2 * (size_t)mid + 1];
    if (b == v[1] && c == v[2]) return mid;
    if (b < v[1] || (b == v[1] && c < v[2]))
      lo = mid + 1;
    else
      hi = mid;
  }
  return -1;
}

/* Unique boundary edges (a < b), sorted, from the boundary faces. */
static int derive_edges(bs_mesh *m, bs_error *err) {
  int32_t nv = m->n_vertices, nf = m->n_faces;
  int32_t *ptr = bs_calloc((size_t)nv + 1, sizeof *ptr, "edge buckets", err);
  int32_t *other = bs_calloc((size_t)nf * 3, sizeof *other, "edge table", err);
  if (!ptr || !other) {
    free(ptr);
    free(other);
    return BS_ENOMEM;
  }
  for (int32_t f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k) {
      int32_t a = m->faces[3 * (size_t)f + k], b = m->faces[3 * (size_t)f + (k + 1) % 3];
      ptr[(a < b ? a : b) + 1]++;
    }
  for (int32_t a = 0; a < nv; ++a) ptr[a + 1] += ptr[a];
  for (int32_t f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k) {
      int32_t a = m->faces[3 * (size_t)f + k], b = m->faces[3 * (size_t)f + (k + 1) % 3];
      if (a < b)
        other[ptr[a]++] = b;
      else
        other[ptr[b]++] = a;
    }
  for (int32_t a = nv; a > 0; --a) ptr[a] = ptr[a - 1];
  ptr[0] = 0;
  int32_t ne = 0;
  for (int32_t a = 0; a < nv; ++a) {
    int32_t *r = other + ptr[a], n = ptr[a + 1] - ptr[a];
    qsort(r, (size_t)n, sizeof *r, bs_cmp_i32);
    for (int32_t i = 0; i < n; ++i) ne += (i == 0 || r[i] != r[i - 1]);
  }
  m->edges = bs_calloc((size_t)ne * 2, sizeof(int32_t), "boundary edges", err);
  if (!m->edges) {
    free(ptr);
    free(other);
    return BS_ENOMEM;
  }
  m->n_edges = ne;
  ne = 0;
  for (int32_t a = 0; a < nv; ++a) {
    int32_t *r = other + ptr[a], n = ptr[a + 1] - ptr[a];
    for (int32_t i = 0; i < n; ++i)
      if (i == 0 || r[i] != r[i - 1]) {
        m->edges[2 * (size_t)ne] = a;
        m->edges[2 * (size_t)ne + 1] = r[i];
        ++ne;
      }
  }
  free(ptr);
  free(other);
  return BS_OK;
}

static int derive_v2t(bs_mesh *m, bs_error *err) {
  int32_t nv = m->n_vertices, nt = m->n_tets;
  m->v2t_ptr = bs_calloc((size_t)nv + 1, sizeof(int32_t), "vertex-to-tet pointers", err);
  m->v2t = bs_calloc((size_t)nt * 4, sizeof(int32_t), "vertex-to-tet adjacency", err);
  if (!m->v2t_ptr || !m->v2t) return BS_ENOMEM;
  int32_t *p = m->v2t_ptr;
  for (size_t i = 0; i < 4 * (size_t)nt; ++i) p[m->tets[i] + 1]++;
  for (int32_t v = 0; v < nv; ++v) p[v + 1] += p[v];
  for (int32_t t = 0; t < nt; ++t) /* rows come out sorted by tet */
    for (int j = 0; j < 4; ++j) m->v2t[p[m->tets[4 * (size_t)t + j]]++] = t;
  for (int32_t v = nv; v > 0; --v) p[v] = p[v - 1];
  p[0] = 0;
  return BS_OK;
}

int bs_mesh_finalize(bs_mesh *m, bs_error *err) {
  if (!m) return bs_error_set(err, BS_EINPUT, "bs_mesh_finalize: mesh is NULL");
  if (m->tets10) return bs_error_set(err, BS_EINPUT, "bs_mesh_finalize: the mesh is quadratic (tet10): finalize its linear mesh");
  if (m->n_vertices < 0 || m->n_tets < 1 || !m->x || !m->tets)
    return bs_error_set(err, BS_EINPUT, "mesh has %d vertices and %d tets: need at least one tet", m->n_vertices,
                        m->n_tets);
  if (m->n_tets > INT32_MAX / 4)
    return bs_error_set(err, BS_EINPUT, "mesh has %d tets: at most %d are supported", m->n_tets, INT32_MAX / 4);
  for (int32_t v = 0; v < m->n_vertices; ++v) {
    const double *p = m->x + 3 * (size_t)v;
    if (!isfinite(p[0]) || !isfinite(p[1]) || !isfinite(p[2]))
      return bs_error_set(err, BS_ENUMERIC, "vertex %d has a non-finite coordinate (%g, %g, %g)", v, p[0], p[1], p[2]);
  }
  int rc = check_tet_ranges(m->tets, m->n_tets, m->n_vertices, err);
  if (!rc) rc = check_group_ranges(m->groups, m->n_groups, m->n_vertices, m->n_tets, err);
  if (rc) return rc;
  free_derived(m);
  rc = orient_tets(m, err);
  if (rc) return rc;

  int32_t *bptr = NULL, *bkey = NULL;
  rc = derive_faces(m, &bptr, &bkey, err);
  if (rc) {
    free_derived(m);
    return rc;
  }
  m->material = bs_calloc((size_t)m->n_tets, sizeof(int32_t), "material ids", err);
  if (!m->material) {
    rc = BS_ENOMEM;
    goto fail;
  }
  /* Groups are visited in reverse (dim, tag) order so that, when an element
   * lies in several groups, the smallest tag wins. */
  for (int i = m->n_groups - 1; i >= 0; --i) {
    const bs_group *g = &m->groups[i];
    if (g->dim == 3) {
      for (int32_t e = 0; e < g->n_elems; ++e) m->material[g->elems[e]] = g->tag;
    } else if (g->dim == 2) {
      for (int32_t e = 0; e < g->n_elems; ++e) {
        int32_t v[3] = {g->elems[3 * (size_t)e], g->elems[3 * (size_t)e + 1], g->elems[3 * (size_t)e + 2]};
        sort3(v);
        int32_t f = find_boundary_face(bptr, bkey, v);
        if (f >= 0) m->boundary[f] = g->tag; /* otherwise an interior interface */
      }
    }
  }
  rc = derive_edges(m, err);
  if (!rc) rc = derive_v2t(m, err);
  for (int i = 0; !rc && i < m->n_groups; ++i) rc = bs__group_update_vertices(m, &m->groups[i], err);
  if (rc) goto fail;
  free(bptr);
  free(bkey);
  return BS_OK;
fail:
  free(bptr);
  free(bkey);
  free_derived(m);
  return rc;
}

/* ---- create, copy, destroy ---------------------------------------------- */

void bs_mesh_destroy(bs_mesh **mp) {
  if (!mp || !*mp) return;
  bs_mesh *m = *mp;
  free_derived(m);
  free(m->x);
  free(m->tets);
  free(m->tets10);
  free(m->midside_edge);
  free(m->midside_x);
  bs__groups_free(m->groups, m->n_groups);
  free(m);
  *mp = NULL;
}

int bs_mesh_create(int32_t n_vertices, const double *x, int32_t n_tets, const int32_t *tets, int n_groups,
                   const bs_group *groups, bs_mesh **out, bs_error *err) {
  if (!out) return bs_error_set(err, BS_EINPUT, "bs_mesh_create: out is NULL");
  *out = NULL;
  if (n_vertices < 0 || n_tets < 1 || (n_vertices > 0 && !x) || !tets)
    return bs_error_set(err, BS_EINPUT, "mesh has %d vertices and %d tets: need at least one tet", n_vertices, n_tets);
  if (n_groups < 0 || (n_groups > 0 && !groups))
    return bs_error_set(err, BS_EINPUT, "mesh has %d groups but no group array", n_groups);
  for (int32_t v = 0; v < n_vertices; ++v) {
    const double *p = x + 3 * (size_t)v;
    if (!isfinite(p[0]) || !isfinite(p[1]) || !isfinite(p[2]))
      return bs_error_set(err, BS_ENUMERIC, "vertex %d has a non-finite coordinate (%g, %g, %g)", v, p[0], p[1], p[2]);
  }
  int rc = check_tet_ranges(tets, n_tets, n_vertices, err);
  if (!rc) {
    for (int i = 0; i < n_groups; ++i)
      if (groups[i].tag <= 0)
        return bs_error_set(err, BS_EINPUT, "group \"%s\" (dim %d, tag %d): tag must be positive", gname(&groups[i]),
                            groups[i].dim, groups[i].tag);
    rc = check_group_ranges(groups, n_groups, n_vertices, n_tets, err);
  }
  if (rc) return rc;

  /* Renumber the vertices some tet uses, in input order. */
  int32_t *newid = bs_calloc((size_t)n_vertices, sizeof *newid, "vertex renumbering", err);
  bs_mesh *m = bs_calloc(1, sizeof *m, "mesh", err);
  if (!newid || !m) {
    free(newid);
    free(m);
    return BS_ENOMEM;
  }
  for (size_t i = 0; i < 4 * (size_t)n_tets; ++i) newid[tets[i]] = 1;
  int32_t nv = 0;
  for (int32_t v = 0; v < n_vertices; ++v) newid[v] = newid[v] ? nv++ : -1;
  m->n_vertices = nv;
  m->n_dropped = n_vertices - nv;
  m->n_tets = n_tets;
  m->x = bs_calloc((size_t)nv * 3, sizeof *m->x, "mesh vertices", err);
  m->tets = bs_calloc((size_t)n_tets * 4, sizeof *m->tets, "mesh tets", err);
  if (!m->x || !m->tets) {
    rc = BS_ENOMEM;
    goto fail;
  }
  for (int32_t v = 0; v < n_vertices; ++v)
    if (newid[v] >= 0) memcpy(m->x + 3 * (size_t)newid[v], x + 3 * (size_t)v, 3 * sizeof(double));
  for (size_t i = 0; i < 4 * (size_t)n_tets; ++i) m->tets[i] = newid[tets[i]];

  /* Groups: copy, renumber, sort by (dim, tag). */
  rc = bs__groups_copy(groups, n_groups, &m->groups, err);
  if (rc) goto fail;
  m->n_groups = n_groups;
  for (int i = 0; i < n_groups; ++i) {
    bs_group *g = &m->groups[i];
    free(g->vertices);
    g->vertices = NULL;
    g->n_vertices = 0;
    if (g->dim == 3) continue;
    int per = g->dim + 1;
    int32_t kept = 0;
    for (int32_t e = 0; e < g->n_elems; ++e) {
      int32_t *el = g->elems + (size_t)e * per;
      int dropped = -1;
      for (int j = 0; j < per; ++j)
        if (newid[el[j]] < 0) dropped = j;
      if (dropped >= 0 && g->dim > 0) {
        rc = bs_error_set(err, BS_EINPUT, "group \"%s\" (dim %d, tag %d): element %d uses vertex %d, which no tet uses",
                          gname(g), g->dim, g->tag, e, el[dropped]);
        goto fail;
      }
      if (dropped >= 0) continue; /* a 0-D point off the mesh: dropped */
      for (int j = 0; j < per; ++j) g->elems[(size_t)kept * per + j] = newid[el[j]];
      ++kept;
    }
    g->n_elems = kept;
  }
  if (n_groups > 1) qsort(m->groups, (size_t)n_groups, sizeof *m->groups, cmp_group);
  for (int i = 1; i < n_groups; ++i)
    if (m->groups[i].dim == m->groups[i - 1].dim && m->groups[i].tag == m->groups[i - 1].tag) {
      rc = bs_error_set(err, BS_EINPUT, "groups \"%s\" and \"%s\" share (dim %d, tag %d)", gname(&m->groups[i - 1]),
                        gname(&m->groups[i]), m->groups[i].dim, m->groups[i].tag);
      goto fail;
    }
  free(newid);
  newid = NULL;
  rc = bs_mesh_finalize(m, err);
  if (rc) goto fail;
  *out = m;
  return BS_OK;
fail:
  free(newid);
  bs_mesh_destroy(&m);
  return rc;
}

int bs_mesh_copy(const bs_mesh *m, bs_mesh **out, bs_error *err) {
  if (!out) return bs_error_set(err, BS_EINPUT, "bs_mesh_copy: out is NULL");
  *out = NULL;
  if (!m) return bs_error_set(err, BS_EINPUT, "bs_mesh_copy: mesh is NULL");
  bs_mesh *c = bs_calloc(1, sizeof *c, "mesh", err);
  if (!c) return BS_ENOMEM;
  *c = *m;
  c->x = NULL;
  c->tets = c->material = c->faces = c->face_tet = c->boundary = c->edges = c->v2t_ptr = c->v2t = NULL;
  c->groups = NULL;
  c->n_groups = 0;
  c->tets10 = NULL;
  c->midside_edge = NULL;
  c->midside_x = NULL;
  size_t nv = (size_t)m->n_vertices, nt = (size_t)m->n_tets, nf = (size_t)m->n_faces;
  int bad = 0;
#define COPY(field, n, what)                                                                                           \
  if (m->field) {                                                                                                      \
    c->field = dup_array(m->field, (n), sizeof *m->field, what, err);                                                  \
    bad |= !c->field;                                                                                                  \
  }
  COPY(x, 3 * nv, "mesh vertices")
  COPY(tets, 4 * nt, "mesh tets")
  COPY(tets10, 10 * nt, "quadratic tets")
  COPY(midside_edge, 2 * (size_t)m->n_midside, "midside edges")
  COPY(midside_x, 3 * (size_t)m->n_midside, "midside nodes")
  COPY(material, nt, "material ids")
  COPY(faces, 3 * nf, "boundary faces")
  COPY(face_tet, nf, "boundary face tets")
  COPY(boundary, nf, "boundary ids")
  COPY(edges, 2 * (size_t)m->n_edges, "boundary edges")
  COPY(v2t_ptr, nv + 1, "vertex-to-tet pointers")
  if (m->v2t && m->v2t_ptr) {
    c->v2t = dup_array(m->v2t, (size_t)m->v2t_ptr[nv], sizeof *m->v2t, "vertex-to-tet adjacency", err);
    bad |= !c->v2t;
  }
#undef COPY
  if (!bad && bs__groups_copy(m->groups, m->n_groups, &c->groups, err) == BS_OK) c->n_groups = m->n_groups;
  else bad = 1;
  if (bad) {
    bs_mesh_destroy(&c);
    return BS_ENOMEM;
  }
  *out = c;
  return BS_OK;
}

/* ---- queries ------------------------------------------------------------ */

const bs_group *bs_mesh_group(const bs_mesh *m, const char *name) {
  if (!m || !name) return NULL;
  for (int i = 0; i < m->n_groups; ++i)
    if (strcmp(gname(&m->groups[i]), name) == 0) return &m->groups[i];
  return NULL;
}

const bs_group *bs_mesh_group_by_tag(const bs_mesh *m, int dim, int tag) {
  if (!m) return NULL;
  for (int i = 0; i < m->n_groups; ++i)
    if (m->groups[i].dim == dim && m->groups[i].tag == tag) return &m->groups[i];
  return NULL;
}

double bs_mesh_tet_volume(const bs_mesh *m, const double *x, int32_t t) {
  return tet_volume(x ? x : m->x, m->tets + 4 * (size_t)t);
}

/* Neumaier's compensated sum: a million equal terms summed naively lose
 * about n eps relative; compensated, the error stays near eps. */
typedef struct {
  double s, c;
} ksum;

static void ksum_add(ksum *k, double v) {
  double t = k->s + v;
  k->c += fabs(k->s) >= fabs(v) ? (k->s - t) + v : (v - t) + k->s;
  k->s = t;
}

double bs_mesh_volume(const bs_mesh *m) {
  ksum k = {0.0, 0.0};
  for (int32_t t = 0; t < m->n_tets; ++t) ksum_add(&k, tet_volume(m->x, m->tets + 4 * (size_t)t));
  return k.s + k.c;
}

/* Divergence theorem with F = x/3: V = sum over outward faces of a.(b x c)/6. */
double bs_mesh_boundary_volume(const bs_mesh *m) {
  ksum k = {0.0, 0.0};
  for (int32_t f = 0; f < m->n_faces; ++f) {
    const double *a = m->x + 3 * (size_t)m->faces[3 * (size_t)f], *b = m->x + 3 * (size_t)m->faces[3 * (size_t)f + 1],
                 *c = m->x + 3 * (size_t)m->faces[3 * (size_t)f + 2];
    ksum_add(&k, a[0] * (b[1] * c[2] - b[2] * c[1]) + a[1] * (b[2] * c[0] - b[0] * c[2]) +
                     a[2] * (b[0] * c[1] - b[1] * c[0]));
  }
  return (k.s + k.c) / 6.0;
}

/* ---- vertex graph ------------------------------------------------------- */

int bs_mesh_vertex_graph(const bs_mesh *m, int32_t **ptr_out, int32_t **adj_out, bs_error *err) {
  if (!ptr_out || !adj_out) return bs_error_set(err, BS_EINPUT, "bs_mesh_vertex_graph: NULL output");
  *ptr_out = NULL;
  *adj_out = NULL;
  if (!m || !m->v2t_ptr || !m->v2t)
    return bs_error_set(err, BS_EINPUT, "bs_mesh_vertex_graph: mesh has no vertex-to-tet adjacency (not finalized)");
  int32_t nv = m->n_vertices;
  int32_t *mark = bs_calloc((size_t)nv, sizeof *mark, "vertex graph marker", err);
  int32_t *ptr = bs_calloc((size_t)nv + 1, sizeof *ptr, "vertex graph pointers", err);
  if (!mark || !ptr) {
    free(mark);
    free(ptr);
    return BS_ENOMEM;
  }
  for (int32_t v = 0; v < nv; ++v) mark[v] = -1;
  /* Pass 1: row lengths (distinct neighbours through the tets at v). */
  for (int32_t v = 0; v < nv; ++v) {
    int32_t n = 0;
    mark[v] = v;
    for (int32_t k = m->v2t_ptr[v]; k < m->v2t_ptr[v + 1]; ++k) {
      const int32_t *t = m->tets + 4 * (size_t)m->v2t[k];
      for (int j = 0; j < 4; ++j)
        if (mark[t[j]] != v) {
          mark[t[j]] = v;
          ++n;
        }
    }
    ptr[v + 1] = ptr[v] + n;
  }
  int32_t *adj = bs_calloc((size_t)ptr[nv], sizeof *adj, "vertex graph adjacency", err);
  if (!adj) {
    free(mark);
    free(ptr);
    return BS_ENOMEM;
  }
  for (int32_t v = 0; v < nv; ++v) mark[v] = -1;
  /* Pass 2: fill and sort each row. */
  for (int32_t v = 0; v < nv; ++v) {
    int32_t n = ptr[v];
    mark[v] = v;
    for (int32_t k = m->v2t_ptr[v]; k < m->v2t_ptr[v + 1]; ++k) {
      const int32_t *t = m->tets + 4 * (size_t)m->v2t[k];
      for (int j = 0; j < 4; ++j)
        if (mark[t[j]] != v) {
          mark[t[j]] = v;
          adj[n++] = t[j];
        }
    }
    int32_t *r = adj + ptr[v];
    int32_t len = ptr[v + 1] - ptr[v];
    for (int32_t i = 1; i < len; ++i) { /* insertion sort: rows are short */
      int32_t key = r[i], j = i - 1;
      while (j >= 0 && r[j] > key) {
        r[j + 1] = r[j];
        --j;
      }
      r[j + 1] = key;
    }
  }
  free(mark);
  *ptr_out = ptr;
  *adj_out = adj;
  return BS_OK;
}

/* ---- checker ------------------------------------------------------------ */

/* The faces of the tets (face_table's ptr, rec): an interior face is shared
 * by two tets with opposite orientations (they lie on either side of it), a
 * boundary face belongs to one tet. *nb receives the boundary faces. */
static int check_shared_faces(const bs_mesh *m, const int32_t *ptr, const face_rec *rec, int32_t *nb,
                              bs_error *err) {
  *nb = 0;
  for (int32_t a = 0; a < m->n_vertices; ++a) {
    for (int32_t i = ptr[a]; i < ptr[a + 1];) {
      int32_t n = run_length(rec, i, ptr[a + 1]);
      if (n > 2) return face_shared_error(m->tets, rec + i, a, n, err);
      if (n == 2) {
        int32_t u[3], w[3];
        face_oriented(m->tets, rec[i].id, u);
        face_oriented(m->tets, rec[i + 1].id, w);
        if (same_cycle(u, w) != -1)
          return bs_error_set(err, BS_EINPUT,
                              "face (%d %d %d) is shared by tets %d and %d lying on the same side of it "
                              "(overlapping tets)",
                              a, rec[i].b, rec[i].c, rec[i].id >> 2, rec[i + 1].id >> 2);
      }
      *nb += (n == 1);
      i += n;
    }
  }
  return BS_OK;
}

/* Boundary face f: a face of its tet, outward, not interior (face_table's
 * ptr, rec), listed once (seen: 4 marks per tet). */
static int check_boundary_face(const bs_mesh *m, int32_t f, const int32_t *ptr, const face_rec *rec, int32_t *seen,
                               bs_error *err) {
  const int32_t *fv = m->faces + 3 * (size_t)f;
  int32_t t = m->face_tet[f];
  if (t < 0 || t >= m->n_tets)
    return bs_error_set(err, BS_EINPUT, "boundary face %d (%d %d %d) names tet %d, out of range [0, %d)", f, fv[0],
                        fv[1], fv[2], t, m->n_tets);
  int lf = -1, sign = 0;
  for (int k = 0; k < 4 && !sign; ++k) {
    int32_t u[3];
    face_oriented(m->tets, 4 * t + k, u);
    sign = same_cycle(fv, u);
    lf = k;
  }
  if (sign == 0)
    return bs_error_set(err, BS_EINPUT, "boundary face %d (%d %d %d) is not a face of its tet %d", f, fv[0], fv[1],
                        fv[2], t);
  if (sign < 0)
    return bs_error_set(err, BS_EINPUT, "boundary face %d (%d %d %d) points into its tet %d (not outward)", f, fv[0],
                        fv[1], fv[2], t);
  int32_t v[3] = {fv[0], fv[1], fv[2]};
  sort3(v);
  int32_t hits = 0;
  for (int32_t i = ptr[v[0]]; i < ptr[v[0] + 1]; ++i) hits += (rec[i].b == v[1] && rec[i].c == v[2]);
  if (hits != 1)
    return bs_error_set(err, BS_EINPUT, "boundary face %d (%d %d %d) is an interior face (shared by %d tets)", f, fv[0],
                        fv[1], fv[2], hits);
  if (seen[4 * t + lf]++)
    return bs_error_set(err, BS_EINPUT, "boundary face %d (%d %d %d) is listed twice", f, fv[0], fv[1], fv[2]);
  return BS_OK;
}

static int check_faces(const bs_mesh *m, bs_error *err) {
  int32_t *ptr = NULL, *seen = NULL, nb = 0;
  face_rec *rec = NULL;
  int rc = face_table(m->tets, m->n_tets, m->n_vertices, &ptr, &rec, err);
  if (rc) return rc;
  rc = check_shared_faces(m, ptr, rec, &nb, err);
  if (!rc && nb != m->n_faces)
    rc = bs_error_set(err, BS_EINPUT, "mesh lists %d boundary faces but its tets have %d", m->n_faces, nb);
  if (!rc && nb > 0 && (!m->faces || !m->face_tet || !m->boundary))
    rc = bs_error_set(err, BS_EINPUT, "mesh has %d boundary faces but no face arrays", nb);
  if (!rc && !(seen = bs_calloc((size_t)4 * m->n_tets, sizeof *seen, "boundary face marks", err))) rc = BS_ENOMEM;
  for (int32_t f = 0; f < m->n_faces && !rc; ++f) rc = check_boundary_face(m, f, ptr, rec, seen, err);
  free(seen);
  free(ptr);
  free(rec);
  return rc;
}

/* Every boundary edge in an even number >= 2 of boundary faces, traversed as
 * often a->b as b->a (closed, consistently oriented); m->edges is that set. */
static int check_edges(const bs_mesh *m, bs_error *err) {
  int32_t nv = m->n_vertices, nf = m->n_faces;
  int32_t *ptr = bs_calloc((size_t)nv + 1, sizeof *ptr, "edge buckets", err);
  int32_t *other = bs_calloc((size_t)nf * 3 + 1, sizeof *other, "edge table", err);
  int rc = BS_OK;
  if (!ptr || !other) {
    rc = BS_ENOMEM;
    goto done;
  }
  for (size_t i = 0; i < 3 * (size_t)nf; ++i)
    if (m->faces[i] < 0 || m->faces[i] >= nv) {
      rc = bs_error_set(err, BS_EINPUT, "boundary face %d has vertex %d, out of range [0, %d)", (int)(i / 3),
                        m->faces[i], nv);
      goto done;
    }
  for (int32_t f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k) {
      int32_t a = m->faces[3 * (size_t)f + k], b = m->faces[3 * (size_t)f + (k + 1) % 3];
      ptr[(a < b ? a : b) + 1]++;
    }
  for (int32_t a = 0; a < nv; ++a) ptr[a + 1] += ptr[a];
  /* Store the larger vertex, encoded as 2 b + (1 if traversed small->large). */
  for (int32_t f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k) {
      int32_t a = m->faces[3 * (size_t)f + k], b = m->faces[3 * (size_t)f + (k + 1) % 3];
      if (a < b)
        other[ptr[a]++] = 2 * b + 1;
      else
        other[ptr[b]++] = 2 * a;
    }
  for (int32_t a = nv; a > 0; --a) ptr[a] = ptr[a - 1];
  ptr[0] = 0;
  int32_t ne = 0;
  for (int32_t a = 0; a < nv; ++a) {
    int32_t *r = other + ptr[a], n = ptr[a + 1] - ptr[a];
    qsort(r, (size_t)n, sizeof *r, bs_cmp_i32);
    for (int32_t i = 0; i < n;) {
      int32_t b = r[i] / 2, fwd = 0, bwd = 0, j = i;
      for (; j < n && r[j] / 2 == b; ++j) (r[j] & 1) ? ++fwd : ++bwd;
      if (fwd != bwd) {
        rc = bs_error_set(err, BS_EINPUT,
                          "boundary edge (%d %d) is traversed %d times as %d->%d and %d times as %d->%d: the boundary is "
                          "%s",
                          a, b, fwd, a, b, bwd, b, a, fwd + bwd == 1 ? "not closed" : "inconsistently oriented");
        goto done;
      }
      if (ne >= m->n_edges || !m->edges || m->edges[2 * (size_t)ne] != a || m->edges[2 * (size_t)ne + 1] != b) {
        rc = bs_error_set(err, BS_EINPUT, "boundary edge %d should be (%d %d) but the mesh lists %s", ne, a, b,
                          ne >= m->n_edges ? "fewer edges" : "another edge");
        goto done;
      }
      ++ne;
      i = j;
    }
  }
  if (ne != m->n_edges)
    rc = bs_error_set(err, BS_EINPUT, "mesh lists %d boundary edges but its boundary faces have %d", m->n_edges, ne);
done:
  free(ptr);
  free(other);
  return rc;
}

static int check_groups(const bs_mesh *m, bs_error *err) {
  int rc = check_group_ranges(m->groups, m->n_groups, m->n_vertices, m->n_tets, err);
  if (rc) return rc;
  for (int i = 0; i < m->n_groups; ++i) {
    const bs_group *g = &m->groups[i];
    if (!g->name) return bs_error_set(err, BS_EINPUT, "group (dim %d, tag %d) has a NULL name", g->dim, g->tag);
    if (g->n_vertices < 0 || (g->n_vertices > 0 && !g->vertices))
      return bs_error_set(err, BS_EINPUT, "group \"%s\" (dim %d, tag %d): %d vertices but no vertex array", g->name,
                          g->dim, g->tag, g->n_vertices);
    for (int32_t k = 0; k < g->n_vertices; ++k) {
      int32_t v = g->vertices[k];
      if (v < 0 || v >= m->n_vertices || (k > 0 && v <= g->vertices[k - 1]))
        return bs_error_set(err, BS_EINPUT,
                            "group \"%s\" (dim %d, tag %d): vertex set entry %d (vertex %d) is out of range or unsorted",
                            g->name, g->dim, g->tag, k, v);
    }
    /* Every element vertex is in the vertex set. */
    int per = g->dim < 3 ? g->dim + 1 : 4;
    for (int32_t e = 0; e < g->n_elems; ++e)
      for (int j = 0; j < per; ++j) {
        int32_t v = g->dim < 3 ? g->elems[(size_t)e * per + j] : m->tets[4 * (size_t)g->elems[e] + j];
        if (!bsearch(&v, g->vertices, (size_t)g->n_vertices, sizeof v, bs_cmp_i32))
          return bs_error_set(err, BS_EINPUT, "group \"%s\" (dim %d, tag %d): element %d uses vertex %d, missing from its vertex set",
                              g->name, g->dim, g->tag, e, v);
      }
  }
  return BS_OK;
}

static int check_ids(const bs_mesh *m, bs_error *err) {
  if (!m->material) return bs_error_set(err, BS_EINPUT, "mesh has no material ids (not finalized)");
  for (int32_t t = 0; t < m->n_tets; ++t)
    if (m->material[t] != 0 && !bs_mesh_group_by_tag(m, 3, m->material[t]))
      return bs_error_set(err, BS_EINPUT, "tet %d has material id %d but there is no 3-D group with that tag", t,
                          m->material[t]);
  for (int32_t f = 0; f < m->n_faces; ++f)
    if (m->boundary[f] != 0 && !bs_mesh_group_by_tag(m, 2, m->boundary[f]))
      return bs_error_set(err, BS_EINPUT, "boundary face %d has boundary id %d but there is no 2-D group with that tag", f,
                          m->boundary[f]);
  return BS_OK;
}

static int check_v2t(const bs_mesh *m, bs_error *err) {
  const int32_t *p = m->v2t_ptr;
  if (!p || !m->v2t) return bs_error_set(err, BS_EINPUT, "mesh has no vertex-to-tet adjacency (not finalized)");
  if (p[0] != 0 || p[m->n_vertices] != 4 * m->n_tets)
    return bs_error_set(err, BS_EINPUT, "vertex-to-tet adjacency holds %d entries, expected %d", p[m->n_vertices] - p[0],
                        4 * m->n_tets);
  for (int32_t v = 0; v < m->n_vertices; ++v) {
    if (p[v + 1] < p[v]) return bs_error_set(err, BS_EINPUT, "vertex-to-tet pointers decrease at vertex %d", v);
    if (p[v + 1] == p[v]) return bs_error_set(err, BS_EINPUT, "vertex %d belongs to no tet", v);
    for (int32_t k = p[v]; k < p[v + 1]; ++k) {
      int32_t t = m->v2t[k];
      if (t < 0 || t >= m->n_tets || (k > p[v] && t <= m->v2t[k - 1]))
        return bs_error_set(err, BS_EINPUT, "vertex %d: adjacency entry %d (tet %d) is out of range or unsorted", v, k, t);
      const int32_t *tv = m->tets + 4 * (size_t)t;
      if (tv[0] != v && tv[1] != v && tv[2] != v && tv[3] != v)
        return bs_error_set(err, BS_EINPUT, "vertex %d lists tet %d, which does not contain it", v, t);
    }
  }
  return BS_OK;
}

int bs_mesh_check(const bs_mesh *m, bs_error *err) {
  if (!m) return bs_error_set(err, BS_EINPUT, "bs_mesh_check: mesh is NULL");
  if (m->n_vertices < 0 || m->n_tets < 1 || !m->x || !m->tets)
    return bs_error_set(err, BS_EINPUT, "mesh has %d vertices and %d tets: need at least one tet", m->n_vertices,
                        m->n_tets);
  if (m->n_tets > INT32_MAX / 4)
    return bs_error_set(err, BS_EINPUT, "mesh has %d tets: at most %d are supported", m->n_tets, INT32_MAX / 4);
  for (int32_t v = 0; v < m->n_vertices; ++v) {
    const double *p = m->x + 3 * (size_t)v;
    if (!isfinite(p[0]) || !isfinite(p[1]) || !isfinite(p[2]))
      return bs_error_set(err, BS_ENUMERIC, "vertex %d has a non-finite coordinate (%g, %g, %g)", v, p[0], p[1], p[2]);
  }
  int rc = check_tet_ranges(m->tets, m->n_tets, m->n_vertices, err);
  if (rc) return rc;
  for (int32_t t = 0; t < m->n_tets; ++t) {
    const int32_t *tv = m->tets + 4 * (size_t)t;
    double vol = tet_volume(m->x, tv);
    if (!(vol > 0))
      return bs_error_set(err, BS_EINPUT, "tet %d (vertices %d %d %d %d) has non-positive volume %g", t, tv[0], tv[1],
                          tv[2], tv[3], vol);
  }
  if ((rc = check_faces(m, err))) return rc;
  if ((rc = check_edges(m, err))) return rc;
  if ((rc = check_groups(m, err))) return rc;
  if ((rc = check_ids(m, err))) return rc;
  return check_v2t(m, err);
}
