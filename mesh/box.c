/* box.c — structured box meshes (Kuhn / Freudenthal split).
 *
 * Vertex (i, j, k) is i + (nx+1) (j + (ny+1) k). Each cell is split into the
 * 6 tets of the Kuhn triangulation: for a permutation p of the axes, the tet
 * (c, c + e_p0, c + e_p0 + e_p1, c + e_p0 + e_p1 + e_p2) with c the cell's low
 * corner. All six share the cell diagonal; every cell face is cut along its
 * diagonal from low to high corner, so neighbouring cells conform. The tet's
 * determinant is det[e_p0, e_p1, e_p2] = sign(p): odd permutations swap their
 * last two vertices to be positive.
 */
#include "mesh_internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* The six axis permutations; the last three are odd. */
static const int perms[6][3] = {{0, 1, 2}, {1, 2, 0}, {2, 0, 1}, {0, 2, 1}, {2, 1, 0}, {1, 0, 2}};

int bs_mesh_create_box(const double lo[3], const double hi[3], int nx, int ny, int nz, bs_mesh **out,
                       bs_error *err) {
  if (!out) return bs_error_set(err, BS_EINPUT, "bs_mesh_create_box: out is NULL");
  *out = NULL;
  if (!lo || !hi) return bs_error_set(err, BS_EINPUT, "bs_mesh_create_box: lo or hi is NULL");
  const int n[3] = {nx, ny, nz};
  static const char axis[3] = {'x', 'y', 'z'};
  for (int d = 0; d < 3; ++d) {
    if (n[d] < 1) return bs_error_set(err, BS_EINPUT, "box: n%c = %d cells, need at least 1", axis[d], n[d]);
    if (!isfinite(lo[d]) || !isfinite(hi[d]) || !(hi[d] > lo[d]))
      return bs_error_set(err, BS_EINPUT, "box: %c range [%g, %g] must be finite with lo < hi", axis[d], lo[d], hi[d]);
  }
  double nv_d = (double)(nx + 1) * (ny + 1) * (nz + 1), nt_d = 6.0 * nx * ny * nz;
  if (nv_d > INT32_MAX || nt_d > INT32_MAX / 4)
    return bs_error_set(err, BS_EINPUT, "box: %d x %d x %d cells is too many (%.0f tets; at most %d)", nx, ny, nz, nt_d,
                        INT32_MAX / 4);
  const int32_t sx = 1, sy = nx + 1, sz = (int32_t)(nx + 1) * (ny + 1);
  const int32_t stride[3] = {sx, sy, sz};
  const int32_t nv = (int32_t)nv_d, nt = (int32_t)nt_d;

  bs_mesh *m = bs_calloc(1, sizeof *m, "mesh", err);
  if (!m) return BS_ENOMEM;
  int rc = BS_OK;
  m->n_vertices = nv;
  m->n_tets = nt;
  m->x = bs_calloc((size_t)nv * 3, sizeof *m->x, "box vertices", err);
  m->tets = bs_calloc((size_t)nt * 4, sizeof *m->tets, "box tets", err);
  m->groups = bs_calloc(7, sizeof *m->groups, "box groups", err);
  if (!m->x || !m->tets || !m->groups) {
    rc = BS_ENOMEM;
    goto fail;
  }
  m->n_groups = 7;

  double h[3];
  for (int d = 0; d < 3; ++d) h[d] = (hi[d] - lo[d]) / n[d];
  for (int k = 0; k <= nz; ++k)
    for (int j = 0; j <= ny; ++j)
      for (int i = 0; i <= nx; ++i) {
        double *p = m->x + 3 * ((size_t)i + (size_t)sy * j + (size_t)sz * k);
        /* The last layer is placed at hi exactly. */
        p[0] = i == nx ? hi[0] : lo[0] + h[0] * i;
        p[1] = j == ny ? hi[1] : lo[1] + h[1] * j;
        p[2] = k == nz ? hi[2] : lo[2] + h[2] * k;
      }

  int32_t *t = m->tets;
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        int32_t c = i + sy * j + sz * k;
        for (int p = 0; p < 6; ++p) {
          int32_t v1 = c + stride[perms[p][0]], v2 = v1 + stride[perms[p][1]], v3 = c + sx + sy + sz;
          t[0] = c;
          if (p < 3) {
            t[1] = v1;
            t[2] = v2;
            t[3] = v3;
          } else {
            t[1] = v1;
            t[2] = v3;
            t[3] = v2;
          }
          t += 4;
        }
      }

  /* Boundary groups: face of axis d at its min (side 0) or max (side 1),
   * tag 2 d + side + 1. The face's in-plane axes (u, w) are cyclic after d,
   * so e_u x e_w = +e_d; each square (u, w) -> (u+1, w+1) gives the triangles
   * (00, 10, 11) and (00, 11, 01), normal +e_d, reversed on the min side so
   * that group triangles point outward like the boundary faces. */
  static const char *names[6] = {"xmin", "xmax", "ymin", "ymax", "zmin", "zmax"};
  for (int d = 0; d < 3; ++d)
    for (int side = 0; side < 2; ++side) {
      bs_group *g = &m->groups[2 * d + side];
      int u = (d + 1) % 3, w = (d + 2) % 3;
      g->dim = 2;
      g->tag = 2 * d + side + 1;
      g->name = bs__strdup(names[2 * d + side]);
      g->n_elems = 2 * n[u] * n[w];
      g->elems = bs_calloc((size_t)g->n_elems * 3, sizeof *g->elems, "box boundary group", err);
      if (!g->name || !g->elems) {
        rc = bs_error_set(err, BS_ENOMEM, "out of memory building box group \"%s\"", names[2 * d + side]);
        goto fail;
      }
      int32_t base = side ? stride[d] * n[d] : 0, *e = g->elems;
      for (int b = 0; b < n[w]; ++b)
        for (int a = 0; a < n[u]; ++a) {
          int32_t v00 = base + stride[u] * a + stride[w] * b, v10 = v00 + stride[u], v01 = v00 + stride[w],
                  v11 = v10 + stride[w];
          int32_t tri[2][3] = {{v00, v10, v11}, {v00, v11, v01}};
          for (int q = 0; q < 2; ++q) {
            e[0] = tri[q][0];
            e[1] = side ? tri[q][1] : tri[q][2];
            e[2] = side ? tri[q][2] : tri[q][1];
            e += 3;
          }
        }
    }
  bs_group *body = &m->groups[6];
  body->dim = 3;
  body->tag = 1;
  body->name = bs__strdup("body");
  body->n_elems = nt;
  body->elems = bs_calloc((size_t)nt, sizeof *body->elems, "box body group", err);
  if (!body->name || !body->elems) {
    rc = bs_error_set(err, BS_ENOMEM, "out of memory building box group \"body\"");
    goto fail;
  }
  for (int32_t e = 0; e < nt; ++e) body->elems[e] = e;

  rc = bs_mesh_finalize(m, err);
  if (rc) goto fail;
  *out = m;
  return BS_OK;
fail:
  bs_mesh_destroy(&m);
  return rc;
}
