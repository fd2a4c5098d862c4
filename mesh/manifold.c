/* manifold.c — the boundary of a mesh made from a closed surface checked to
 * be a closed 2-manifold with the surface's number of components
 * (bs__boundary_manifold, see mesh_internal.h): no edge in more than two
 * boundary triangles, no vertex where two parts of the body touch (its
 * boundary triangles in more than one fan), no cavity or loose part. */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "mesh_internal.h"

static int32_t root(int32_t *p, int32_t a) {
  while (p[a] != a) a = p[a] = p[p[a]];
  return a;
}

int64_t bs__soup_components(const double *x, int64_t np, const int32_t *tris, int64_t nt, double min_volume,
                            int32_t *parent) {
  const int64_t k = bs__soup_label_components(tris, nt, np, parent); /* parent: the labels */
  double *vol = k >= 0 ? calloc((size_t)k + 1, sizeof *vol) : NULL;
  if (!vol) return -1;
  for (int64_t f = 0; f < nt; f++) vol[parent[tris[3 * f]]] += bs__soup_volume(x, tris + 3 * f, 1);
  int64_t n = 0;
  for (int64_t c = 0; c < k; c++) n += fabs(vol[c]) >= min_volume;
  free(vol);
  return n;
}

int64_t bs__soup_label_components(const int32_t *tris, int64_t nt, int64_t np, int32_t *label) {
  int32_t *parent = malloc(((size_t)np + 1) * sizeof *parent);
  if (!parent) return -1;
  for (int64_t v = 0; v < np; v++) parent[v] = (int32_t)v, label[v] = -1;
  for (int64_t f = 0; f < nt; f++)
    for (int k = 0; k < 3; k++) {
      int32_t a = root(parent, tris[3 * f + k]), b = root(parent, tris[3 * f + (k + 1) % 3]);
      if (a != b) parent[a] = b;
    }
  for (int64_t v = 0; v < np; v++) parent[v] = root(parent, (int32_t)v); /* every point to its root */
  int64_t n = 0;
  for (int64_t f = 0; f < 3 * nt; f++) {
    const int32_t r = parent[tris[f]];
    if (label[r] < 0) label[r] = (int32_t)n++;
  }
  for (int64_t f = 0; f < 3 * nt; f++) label[tris[f]] = label[parent[tris[f]]];
  free(parent);
  return n;
}

/* Edges of the boundary in other than two triangles: their count, the
 * first one's midpoint into at. */
static int32_t odd_edges(const bs_mesh *m, uint64_t *keys, double at[3]) {
  const size_t n = 3 * (size_t)m->n_faces;
  for (int32_t f = 0; f < m->n_faces; f++)
    for (int k = 0; k < 3; k++) keys[3 * (size_t)f + k] = bs__edge_key(m->faces[3 * f + k], m->faces[3 * f + (k + 1) % 3]);
  qsort(keys, n, sizeof *keys, bs__cmp_u64);
  int32_t bad = 0;
  for (size_t i = 0, j; i < n; i = j) {
    for (j = i; j < n && keys[j] == keys[i]; j++) {
    }
    if (j - i == 2) continue;
    if (!bad++)
      for (int c = 0; c < 3; c++)
        at[c] = 0.5 * (m->x[3 * (size_t)(keys[i] >> 32) + c] + m->x[3 * (size_t)(keys[i] & 0xffffffffu) + c]);
  }
  return bad;
}

/* Vertices whose boundary triangles make more than one fan (joined across
 * the edges through the vertex): their count, the first one into at.
 * ptr/list: the vertex -> boundary faces CSR; scratch: 2 * max degree
 * keys, parent: max degree. */
static int32_t pinched_vertices(const bs_mesh *m, const int32_t *ptr, const int32_t *list, uint64_t *scratch,
                                int32_t *parent, double at[3]) {
  int32_t bad = 0;
  for (int32_t v = 0; v < m->n_vertices; v++) {
    const int32_t d = ptr[v + 1] - ptr[v];
    if (d == 0) continue;
    size_t n = 0;
    for (int32_t i = 0; i < d; i++) {
      parent[i] = i;
      const int32_t *f = m->faces + 3 * (size_t)list[ptr[v] + i];
      for (int k = 0; k < 3; k++)
        if (f[k] != v) scratch[n++] = (uint64_t)(uint32_t)f[k] << 32 | (uint32_t)i;
    }
    qsort(scratch, n, sizeof *scratch, bs__cmp_u64);
    for (size_t i = 1; i < n; i++)
      if (scratch[i] >> 32 == scratch[i - 1] >> 32) {
        int32_t a = root(parent, (int32_t)(scratch[i] & 0xffffffffu)), b = root(parent, (int32_t)(scratch[i - 1] & 0xffffffffu));
        if (a != b) parent[a] = b;
      }
    int32_t fans = 0;
    for (int32_t i = 0; i < d; i++) fans += root(parent, i) == i;
    if (fans > 1 && !bad++) memcpy(at, m->x + 3 * (size_t)v, 3 * sizeof *at);
  }
  return bad;
}

int bs__boundary_manifold(const bs_mesh *m, const char *path, int64_t components, bs_error *err) {
  const int32_t nv = m->n_vertices, nf = m->n_faces;
  int32_t *ptr = calloc((size_t)nv + 2, sizeof *ptr), *list = malloc((3 * (size_t)nf + 1) * sizeof *list);
  uint64_t *keys = malloc((3 * (size_t)nf + 1) * sizeof *keys);
  int32_t *parent = malloc(((size_t)nv + 1) * sizeof *parent), maxd = 0;
  int rc = BS_OK;
  if (!ptr || !list || !keys || !parent) {
    rc = bs_error_set(err, BS_ENOMEM, "%s: out of memory to check the mesh's boundary", path);
    goto done;
  }
  for (size_t k = 0; k < 3 * (size_t)nf; k++) ptr[m->faces[k] + 2]++;
  for (int32_t v = 0; v < nv; v++) maxd = ptr[v + 2] > maxd ? ptr[v + 2] : maxd, ptr[v + 2] += ptr[v + 1];
  for (int32_t f = 0; f < nf; f++)
    for (int k = 0; k < 3; k++) list[ptr[m->faces[3 * f + k] + 1]++] = f;
  double e_at[3] = {0, 0, 0}, v_at[3] = {0, 0, 0};
  const int32_t n_edges = odd_edges(m, keys, e_at);
  int32_t *fan = malloc(((size_t)maxd + 1) * sizeof *fan);
  if (!fan) {
    rc = bs_error_set(err, BS_ENOMEM, "%s: out of memory to check the mesh's boundary", path);
    goto done;
  }
  /* keys are free again: 2 * maxd <= 3 * nf */
  const int32_t n_verts = pinched_vertices(m, ptr, list, keys, fan, v_at);
  free(fan);
  const int64_t n_comp = bs__soup_components(m->x, nv, m->faces, nf, 0.0, parent);
  if (n_edges || n_verts || (components > 0 && n_comp != components))
    rc = bs_error_set(err, BS_EINPUT,
                      "%s: the mesh's boundary is not a closed 2-manifold like the surface: %d edges in more than "
                      "two boundary triangles (the first at (%.6g, %.6g, %.6g)), %d vertices where two parts of the "
                      "body touch (the first at (%.6g, %.6g, %.6g)), %lld boundary components where the surface has "
                      "%lld (a cavity or a loose part)",
                      path, n_edges, e_at[0], e_at[1], e_at[2], n_verts, v_at[0], v_at[1], v_at[2], (long long)n_comp,
                      (long long)components);
done:
  free(ptr), free(list), free(keys), free(parent);
  return rc;
}

int bs__boundary_like_soup(const bs_mesh *m, const char *path, const double *pts, int64_t np, const int32_t *tris,
                           int64_t nt, double min_volume, bs_error *err) {
  int32_t *parent = malloc(((size_t)np + 1) * sizeof *parent);
  const int64_t n = parent ? bs__soup_components(pts, np, tris, nt, min_volume, parent) : -1;
  free(parent);
  if (n < 0) return bs_error_set(err, BS_ENOMEM, "%s: out of memory to count the surface's components", path);
  return bs__boundary_manifold(m, path, n, err);
}
