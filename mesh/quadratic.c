/* quadratic.c — queries of a quadratic mesh (bs_mesh.tets10). */
#include "bs_mesh.h"

/* The vertex pairs of the midside nodes 4..9 of a tet10, VTK order (as
 * bs_tet10_edges, physics/bs_tet10.h). */
static const int edge_ends[6][2] = {{0, 1}, {1, 2}, {0, 2}, {0, 3}, {1, 3}, {2, 3}};

int32_t bs_mesh_edge_node(const bs_mesh *m, int32_t a, int32_t b) {
  if (!m || !m->tets10 || a < 0 || b < 0 || a >= m->n_corners || b >= m->n_corners || a == b) return -1;
  for (int32_t p = m->v2t_ptr[a]; p < m->v2t_ptr[a + 1]; p++) {
    const int32_t *t = m->tets10 + 10 * (size_t)m->v2t[p];
    int ia = -1, ib = -1;
    for (int c = 0; c < 4; c++) {
      if (t[c] == a) ia = c;
      if (t[c] == b) ib = c;
    }
    if (ia < 0 || ib < 0) continue;
    for (int k = 0; k < 6; k++)
      if ((edge_ends[k][0] == ia && edge_ends[k][1] == ib) || (edge_ends[k][0] == ib && edge_ends[k][1] == ia))
        return t[4 + k];
  }
  return -1;
}
