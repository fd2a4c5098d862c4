/* reorder.c — vertex renumbering (deal.II's DoFRenumbering) and its measures.
 *
 * A permutation is always given as perm[new] = old. Renumbering relabels the
 * vertices, then sorts the tets by their smallest new vertex (stable counting
 * sort, so tets that touch the same low vertex stay together and the order
 * is reproducible), remaps every group (3-D group tet lists and vertex sets
 * sorted ascending, lower-dimensional elements relabelled and sorted stably
 * by their smallest vertex), and re-derives faces, edges and adjacency with
 * bs_mesh_finalize. Tet vertex order is kept, so orientations are unchanged.
 *
 * Orders:
 *  - BS_ORDER_METIS: METIS_NodeND (multilevel nested dissection) on the
 *    vertex graph, a fill-reducing order for the 3x3-block Cholesky factor.
 *    METIS returns perm (new -> old, "row i of A' is row perm[i] of A") and
 *    iperm (old -> new); we use perm.
 *  - BS_ORDER_RCM: reverse Cuthill-McKee, a bandwidth/profile-reducing order
 *    (good for locality of CG and matrix-vector products): per connected
 *    component, breadth-first search from a pseudo-peripheral vertex (George
 *    and Liu's iteration), visiting unnumbered neighbours by increasing
 *    degree (ties by index); the whole sequence is then reversed. */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include <metis.h>

#include "bs_mesh.h"

/* ---- measures -------------------------------------------------------- */

void bs_mesh_bandwidth(const bs_mesh *m, int64_t *bandwidth, int64_t *profile) {
  int64_t bw = 0, prof = 0;
  if (m && m->v2t_ptr && m->v2t && m->tets) {
    /* The vertex graph joins the vertices of each tet, so row i's
     * neighbours are the vertices of the tets around i (no allocation). */
    for (int32_t i = 0; i < m->n_vertices; i++) {
      int32_t lo = i, hi = i;
      for (int32_t p = m->v2t_ptr[i]; p < m->v2t_ptr[i + 1]; p++) {
        const int32_t *v = m->tets + 4 * (size_t)m->v2t[p];
        for (int k = 0; k < 4; k++) {
          if (v[k] < lo) lo = v[k];
          if (v[k] > hi) hi = v[k];
        }
      }
      if (hi - i > bw) bw = hi - i;
      if (i - lo > bw) bw = i - lo;
      prof += i - lo;
    }
  }
  if (bandwidth) *bandwidth = bw;
  if (profile) *profile = prof;
}

/* ---- explicit permutation ------------------------------------------- */

typedef struct key_index {
  int32_t key, index;
} key_index;

static int cmp_key_index(const void *a, const void *b) {
  const key_index *x = a, *y = b;
  if (x->key != y->key) return x->key < y->key ? -1 : 1;
  return (x->index > y->index) - (x->index < y->index);
}

/* New element and vertex arrays of one group under vertex map iperm
 * (old -> new) and tet map tip (old -> new). */
static int permute_group(const bs_group *g, const int32_t *iperm, int32_t nv, const int32_t *tip, int32_t nt,
                         int32_t **elems_out, int32_t **verts_out, bs_error *err) {
  const char *name = g->name ? g->name : "";
  int tuple = g->dim == 3 ? 1 : g->dim + 1;
  int rc = BS_OK;
  size_t ne = (size_t)g->n_elems * (size_t)tuple;
  int32_t *el = bs_calloc(ne + 1, sizeof(int32_t), "reorder: group elements", err);
  int32_t *vs = bs_calloc((size_t)g->n_vertices + 1, sizeof(int32_t), "reorder: group vertices", err);
  key_index *ki = NULL;
  if (g->dim != 3) ki = bs_calloc((size_t)g->n_elems + 1, sizeof(key_index), "reorder: group sort keys", err);
  if (!el || !vs || (g->dim != 3 && !ki)) {
    rc = BS_ENOMEM;
    goto fail;
  }
  if (g->dim == 3) {
    for (int32_t i = 0; i < g->n_elems; i++) {
      int32_t t = g->elems[i];
      if (t < 0 || t >= nt) {
        rc = bs_error_set(err, BS_EINPUT, "reorder: group '%s' (%d, %d) element %d is tet %d (mesh has %d)", name,
                          g->dim, g->tag, i, t, nt);
        goto fail;
      }
      el[i] = tip[t];
    }
    qsort(el, (size_t)g->n_elems, sizeof(int32_t), bs_cmp_i32);
  } else {
    for (int32_t i = 0; i < g->n_elems; i++) {
      int32_t key = INT32_MAX;
      for (int k = 0; k < tuple; k++) {
        int32_t v = g->elems[(size_t)i * tuple + k];
        if (v < 0 || v >= nv) {
          rc = bs_error_set(err, BS_EINPUT, "reorder: group '%s' (%d, %d) element %d uses vertex %d (mesh has %d)",
                            name, g->dim, g->tag, i, v, nv);
          goto fail;
        }
        if (iperm[v] < key) key = iperm[v];
      }
      ki[i].key = key;
      ki[i].index = i;
    }
    qsort(ki, (size_t)g->n_elems, sizeof(key_index), cmp_key_index);
    for (int32_t i = 0; i < g->n_elems; i++)
      for (int k = 0; k < tuple; k++) el[(size_t)i * tuple + k] = iperm[g->elems[(size_t)ki[i].index * tuple + k]];
  }
  for (int32_t i = 0; i < g->n_vertices; i++) {
    int32_t v = g->vertices[i];
    if (v < 0 || v >= nv) {
      rc = bs_error_set(err, BS_EINPUT, "reorder: group '%s' (%d, %d) lists vertex %d (mesh has %d)", name, g->dim,
                        g->tag, v, nv);
      goto fail;
    }
    vs[i] = iperm[v];
  }
  qsort(vs, (size_t)g->n_vertices, sizeof(int32_t), bs_cmp_i32);
  free(ki);
  *elems_out = el;
  *verts_out = vs;
  return BS_OK;
fail:
  free(ki);
  free(el);
  free(vs);
  return rc;
}

/* iperm from perm, which must be a bijection of 0..nv-1 (iperm holds nv). */
static int invert_perm(const int32_t *perm, int32_t nv, int32_t *iperm, bs_error *err) {
  for (int32_t i = 0; i < nv; i++) iperm[i] = -1;
  for (int32_t i = 0; i < nv; i++) {
    int32_t o = perm[i];
    if (o < 0 || o >= nv) return bs_error_set(err, BS_EINPUT, "permute: perm[%d] = %d is out of range [0, %d)", i, o, nv);
    if (iperm[o] >= 0)
      return bs_error_set(err, BS_EINPUT, "permute: vertex %d appears twice in perm (at %d and %d)", o, iperm[o], i);
    iperm[o] = i;
  }
  return BS_OK;
}

/* The tets relabelled and counting-sorted (stably) by their smallest new
 * vertex into tets and mat; tip[t] the new index of tet t (count: nv + 1
 * zeroed ints of work). */
static int permute_tets(const bs_mesh *m, const int32_t *iperm, int32_t *count, int32_t *tip, int32_t *tets,
                        int32_t *mat, bs_error *err) {
  const int32_t nv = m->n_vertices, nt = m->n_tets;
  for (int32_t t = 0; t < nt; t++) {
    int32_t lo = INT32_MAX;
    for (int k = 0; k < 4; k++) {
      int32_t v = m->tets[4 * (size_t)t + k];
      if (v < 0 || v >= nv) return bs_error_set(err, BS_EINPUT, "permute: tet %d uses vertex %d (mesh has %d)", t, v, nv);
      if (iperm[v] < lo) lo = iperm[v];
    }
    tip[t] = lo;
    count[lo]++;
  }
  for (int32_t i = 0, s = 0; i < nv; i++) {
    int32_t c = count[i];
    count[i] = s;
    s += c;
  }
  for (int32_t t = 0; t < nt; t++) {
    int32_t nt_new = count[tip[t]]++;
    tip[t] = nt_new;
    for (int k = 0; k < 4; k++) tets[4 * (size_t)nt_new + k] = iperm[m->tets[4 * (size_t)t + k]];
    mat[nt_new] = m->material ? m->material[t] : 0;
  }
  return BS_OK;
}

/* The new arrays put in m (taken over: the pointers are nulled), then the
 * derived data made again. */
static int permute_commit(bs_mesh *m, double **x, int32_t **tets, int32_t **mat, int32_t **gel, int32_t **gvs,
                          bs_error *err) {
  free(m->x);
  m->x = *x;
  *x = NULL;
  free(m->tets);
  m->tets = *tets;
  *tets = NULL;
  free(m->material);
  m->material = *mat;
  *mat = NULL;
  for (int g = 0; g < m->n_groups; g++) {
    free(m->groups[g].elems);
    free(m->groups[g].vertices);
    m->groups[g].elems = gel[g];
    m->groups[g].vertices = gvs[g];
    gel[g] = gvs[g] = NULL;
  }
  int rc = bs_mesh_finalize(m, err);
  if (rc) bs_error_prefix(err, "permute");
  return rc;
}

int bs_mesh_permute(bs_mesh *m, const int32_t *perm, bs_error *err) {
  if (!m || !perm) return bs_error_set(err, BS_EINPUT, "permute: %s is NULL", m ? "perm" : "mesh");
  if (m->tets10) return bs_error_set(err, BS_EINPUT, "permute: the mesh is quadratic (tet10): renumber its linear mesh");
  const int32_t nv = m->n_vertices, nt = m->n_tets;
  int rc = BS_OK;
  int32_t *iperm = bs_calloc((size_t)nv + 1, sizeof(int32_t), "permute: inverse permutation", err);
  int32_t *count = bs_calloc((size_t)nv + 1, sizeof(int32_t), "permute: tet buckets", err);
  int32_t *tip = bs_calloc((size_t)nt + 1, sizeof(int32_t), "permute: tet map", err);
  double *x = bs_calloc(3 * (size_t)nv + 1, sizeof(double), "permute: vertices", err);
  int32_t *tets = bs_calloc(4 * (size_t)nt + 1, sizeof(int32_t), "permute: tets", err);
  int32_t *mat = bs_calloc((size_t)nt + 1, sizeof(int32_t), "permute: materials", err);
  int32_t **gel = bs_calloc((size_t)m->n_groups + 1, sizeof(int32_t *), "permute: groups", err);
  int32_t **gvs = bs_calloc((size_t)m->n_groups + 1, sizeof(int32_t *), "permute: groups", err);
  if (!iperm || !count || !tip || !x || !tets || !mat || !gel || !gvs) rc = BS_ENOMEM;
  if (!rc) rc = invert_perm(perm, nv, iperm, err);
  for (int32_t i = 0; i < nv && !rc; i++) memcpy(x + 3 * (size_t)i, m->x + 3 * (size_t)perm[i], 3 * sizeof(double));
  if (!rc) rc = permute_tets(m, iperm, count, tip, tets, mat, err);
  for (int g = 0; g < m->n_groups && !rc; g++) rc = permute_group(&m->groups[g], iperm, nv, tip, nt, &gel[g], &gvs[g], err);
  if (!rc) rc = permute_commit(m, &x, &tets, &mat, gel, gvs, err); /* the mesh changes only here */
  for (int32_t i = 0; !rc && i < 2 * m->n_midside; i++) m->midside_edge[i] = iperm[m->midside_edge[i]];
  for (int g = 0; g < m->n_groups; g++) {
    if (gel) free(gel[g]);
    if (gvs) free(gvs[g]);
  }
  free(gel);
  free(gvs);
  free(iperm);
  free(count);
  free(tip);
  free(x);
  free(tets);
  free(mat);
  return rc;
}

/* ---- orderings ------------------------------------------------------- */

static int order_metis(const bs_mesh *m, const int32_t *ptr, const int32_t *adj, int32_t *perm, bs_error *err) {
  const int32_t n = m->n_vertices;
  int rc = BS_OK;
  idx_t nvtxs = n;
  idx_t *xadj = bs_calloc((size_t)n + 1, sizeof(idx_t), "reorder: METIS xadj", err);
  idx_t *adjncy = bs_calloc((size_t)ptr[n] + 1, sizeof(idx_t), "reorder: METIS adjncy", err);
  idx_t *mp = bs_calloc((size_t)n + 1, sizeof(idx_t), "reorder: METIS perm", err);
  idx_t *mip = bs_calloc((size_t)n + 1, sizeof(idx_t), "reorder: METIS iperm", err);
  if (!xadj || !adjncy || !mp || !mip) {
    rc = BS_ENOMEM;
    goto done;
  }
  for (int32_t i = 0; i <= n; i++) xadj[i] = ptr[i];
  for (int32_t i = 0; i < ptr[n]; i++) adjncy[i] = adj[i];
  idx_t options[METIS_NOPTIONS];
  METIS_SetDefaultOptions(options);
  options[METIS_OPTION_NUMBERING] = 0;
  options[METIS_OPTION_SEED] = 1; /* reproducible orderings */
  int st = METIS_NodeND(&nvtxs, xadj, adjncy, NULL, options, mp, mip);
  if (st != METIS_OK) {
    rc = bs_error_set(err, st == METIS_ERROR_MEMORY ? BS_ENOMEM : BS_EINTERNAL,
                      "reorder: METIS_NodeND failed (status %d) on a graph of %d vertices and %d edges", st, n,
                      ptr[n] / 2);
    goto done;
  }
  for (int32_t i = 0; i < n; i++) perm[i] = (int32_t)mp[i]; /* new -> old */
done:
  free(xadj);
  free(adjncy);
  free(mp);
  free(mip);
  return rc;
}

/* Breadth-first level structure from root, over unnumbered vertices
 * (done[v] == 0). Visited vertices get mark[v] = stamp and are stored in
 * queue[0 .. *size); returns the number of levels, and *last the start of
 * the last level in queue. */
static int32_t bfs_levels(int32_t root, const int32_t *ptr, const int32_t *adj, const char *done, int32_t *mark,
                          int32_t stamp, int32_t *queue, int32_t *size, int32_t *last) {
  int32_t head = 0, tail = 0, levels = 0;
  queue[tail++] = root;
  mark[root] = stamp;
  *last = 0;
  while (head < tail) {
    int32_t end = tail;
    *last = head;
    levels++;
    for (; head < end; head++) {
      int32_t v = queue[head];
      for (int32_t p = ptr[v]; p < ptr[v + 1]; p++) {
        int32_t w = adj[p];
        if (!done[w] && mark[w] != stamp) {
          mark[w] = stamp;
          queue[tail++] = w;
        }
      }
    }
  }
  *size = tail;
  return levels;
}

static int order_rcm(const bs_mesh *m, const int32_t *ptr, const int32_t *adj, int32_t *perm, bs_error *err) {
  const int32_t n = m->n_vertices;
  int32_t maxdeg = 0;
  for (int32_t v = 0; v < n; v++)
    if (ptr[v + 1] - ptr[v] > maxdeg) maxdeg = ptr[v + 1] - ptr[v];
  char *done = bs_calloc((size_t)n + 1, 1, "reorder: RCM flags", err);
  int32_t *mark = bs_calloc((size_t)n + 1, sizeof(int32_t), "reorder: RCM marks", err);
  int32_t *queue = bs_calloc((size_t)n + 1, sizeof(int32_t), "reorder: RCM queue", err);
  int32_t *order = bs_calloc((size_t)n + 1, sizeof(int32_t), "reorder: RCM order", err);
  int32_t *nb = bs_calloc((size_t)maxdeg + 1, sizeof(int32_t), "reorder: RCM neighbours", err);
  if (!done || !mark || !queue || !order || !nb) {
    free(done);
    free(mark);
    free(queue);
    free(order);
    free(nb);
    return BS_ENOMEM;
  }
#define DEG(v) (ptr[(v) + 1] - ptr[(v)])
  int32_t numbered = 0, stamp = 0;
  for (int32_t s = 0; s < n; s++) {
    if (done[s]) continue;
    /* the component of s; start from its vertex of least degree */
    int32_t size, last;
    bfs_levels(s, ptr, adj, done, mark, ++stamp, queue, &size, &last);
    int32_t root = s;
    for (int32_t i = 0; i < size; i++)
      if (DEG(queue[i]) < DEG(root) || (DEG(queue[i]) == DEG(root) && queue[i] < root)) root = queue[i];
    /* George-Liu: move to a least-degree vertex of the last level while the
     * eccentricity grows */
    int32_t ecc = bfs_levels(root, ptr, adj, done, mark, ++stamp, queue, &size, &last);
    for (;;) {
      int32_t cand = queue[last];
      for (int32_t i = last; i < size; i++)
        if (DEG(queue[i]) < DEG(cand) || (DEG(queue[i]) == DEG(cand) && queue[i] < cand)) cand = queue[i];
      int32_t e2 = bfs_levels(cand, ptr, adj, done, mark, ++stamp, queue, &size, &last);
      if (e2 <= ecc) break;
      ecc = e2;
      root = cand;
    }
    /* Cuthill-McKee from root: neighbours by increasing degree */
    int32_t head = numbered;
    order[numbered++] = root;
    done[root] = 1;
    while (head < numbered) {
      int32_t v = order[head++];
      int32_t k = 0;
      for (int32_t p = ptr[v]; p < ptr[v + 1]; p++)
        if (!done[adj[p]]) {
          done[adj[p]] = 1;
          nb[k++] = adj[p];
        }
      for (int32_t i = 1; i < k; i++) { /* insertion sort by (degree, index) */
        int32_t w = nb[i], j = i - 1;
        while (j >= 0 && (DEG(nb[j]) > DEG(w) || (DEG(nb[j]) == DEG(w) && nb[j] > w))) {
          nb[j + 1] = nb[j];
          j--;
        }
        nb[j + 1] = w;
      }
      for (int32_t i = 0; i < k; i++) order[numbered++] = nb[i];
    }
  }
#undef DEG
  for (int32_t i = 0; i < n; i++) perm[i] = order[n - 1 - i];
  free(done);
  free(mark);
  free(queue);
  free(order);
  free(nb);
  return BS_OK;
}

int bs_mesh_reorder(bs_mesh *m, bs_order order, int32_t *perm, bs_error *err) {
  if (!m) return bs_error_set(err, BS_EINPUT, "reorder: mesh is NULL");
  if (m->tets10) return bs_error_set(err, BS_EINPUT, "reorder: the mesh is quadratic (tet10): reorder its linear mesh");
  if (order != BS_ORDER_NONE && order != BS_ORDER_METIS && order != BS_ORDER_RCM)
    return bs_error_set(err, BS_EINPUT, "reorder: unknown order %d (expected none, metis or rcm)", (int)order);
  const int32_t n = m->n_vertices;
  int32_t *p = bs_calloc((size_t)n + 1, sizeof(int32_t), "reorder: permutation", err);
  if (!p) return BS_ENOMEM;
  int rc = BS_OK;
  if (order == BS_ORDER_NONE || n == 0) {
    for (int32_t i = 0; i < n; i++) p[i] = i;
  } else {
    int32_t *ptr = NULL, *adj = NULL;
    rc = bs_mesh_vertex_graph(m, &ptr, &adj, err);
    if (!rc) rc = order == BS_ORDER_METIS ? order_metis(m, ptr, adj, p, err) : order_rcm(m, ptr, adj, p, err);
    free(ptr);
    free(adj);
    if (!rc) rc = bs_mesh_permute(m, p, err);
  }
  if (!rc && perm) memcpy(perm, p, (size_t)n * sizeof(int32_t));
  free(p);
  return rc;
}
