/* tet10_mesh.c — a linear bs_mesh made quadratic in place (bs_tet10_mesh,
 * bs_tet10.h): its edge midpoints appended as vertices, bs_mesh.tets10, and
 * the groups grown by the midside nodes of their elements' edges. */
#include <stdlib.h>
#include <string.h>

#include "bs_tet10.h"

/* Marks the midside nodes of group g's element edges in mark (n_vertices). */
static void mark_group_edges(const bs_mesh *m, const bs_group *g, unsigned char *mark) {
  if (g->dim == 3) {
    for (int32_t e = 0; e < g->n_elems; e++)
      for (int k = 0; k < 6; k++) mark[m->tets10[10 * (size_t)g->elems[e] + 4 + k]] = 1;
    return;
  }
  const int per = g->dim + 1;
  for (int32_t e = 0; e < g->n_elems && per > 1; e++) {
    const int32_t *v = g->elems + (size_t)e * per;
    for (int i = 0; i < per; i++)
      for (int j = i + 1; j < per; j++) {
        const int32_t n = bs_mesh_edge_node(m, v[i], v[j]);
        if (n >= 0) mark[n] = 1;
      }
  }
}

/* Appends the midside nodes of each group's element edges to its vertices
 * (they are numbered after every corner, so the list stays sorted). */
static int grow_groups(bs_mesh *m, bs_error *err) {
  const int32_t nn = m->n_vertices, nc = m->n_corners;
  unsigned char *mark = bs_calloc((size_t)nn, 1, "tet10 group marker", err);
  if (!mark) return BS_ENOMEM;
  for (int i = 0; i < m->n_groups; i++) {
    bs_group *g = &m->groups[i];
    memset(mark + nc, 0, (size_t)(nn - nc));
    mark_group_edges(m, g, mark);
    int32_t add = 0;
    for (int32_t v = nc; v < nn; v++) add += mark[v];
    if (!add) continue;
    int32_t *list = realloc(g->vertices, sizeof(int32_t) * (size_t)(g->n_vertices + add));
    if (!list) {
      free(mark);
      return bs_error_set(err, BS_ENOMEM, "out of memory growing group \"%s\" by its midside nodes", g->name);
    }
    g->vertices = list;
    for (int32_t v = nc; v < nn; v++)
      if (mark[v]) list[g->n_vertices++] = v;
  }
  free(mark);
  return BS_OK;
}

int bs_tet10_mesh(bs_mesh *m, bs_error *err) {
  if (!m) return bs_error_set(err, BS_EINPUT, "bs_tet10_mesh: mesh is NULL");
  if (m->tets10) return bs_error_set(err, BS_EINPUT, "bs_tet10_mesh: the mesh is quadratic already");
  if (!m->v2t_ptr || !m->v2t) return bs_error_set(err, BS_EINPUT, "bs_tet10_mesh: the mesh is not finalized");
  int32_t nn = 0, *t10 = NULL;
  double *nodes = NULL;
  int st = bs_tet10_from_tet4(m->n_vertices, m->x, m->n_tets, m->tets, &nn, &nodes, &t10, err);
  if (st) return st;
  int32_t *ptr = realloc(m->v2t_ptr, sizeof(int32_t) * ((size_t)nn + 1));
  if (!ptr) {
    free(nodes);
    free(t10);
    return bs_error_set(err, BS_ENOMEM, "out of memory making the mesh quadratic (%d nodes)", nn);
  }
  for (int32_t v = m->n_vertices + 1; v <= nn; v++) ptr[v] = ptr[m->n_vertices]; /* midside nodes: no tet */
  m->v2t_ptr = ptr;
  free(m->x);
  m->x = nodes;
  m->tets10 = t10;
  m->n_corners = m->n_vertices;
  m->n_vertices = nn;
  /* a .msh of 10-node tets: the file's midside nodes (bs_mesh.midside_x) */
  for (int32_t i = 0; i < m->n_midside; i++) {
    const int32_t n = bs_mesh_edge_node(m, m->midside_edge[2 * i], m->midside_edge[2 * i + 1]);
    if (n >= 0) memcpy(m->x + 3 * (size_t)n, m->midside_x + 3 * (size_t)i, 3 * sizeof(double));
  }
  free(m->midside_edge);
  free(m->midside_x);
  m->midside_edge = NULL, m->midside_x = NULL, m->n_midside = 0;
  return grow_groups(m, err);
}
