/* test_mesh_core.c — bs_mesh creation, derived topology, checker, box, quality. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bs_mesh.h"
#include "mesh_internal.h"

/* Unit right tet: vertices 0, e1, e2, e3 (positive order 0 1 2 3). */
static const double tet_x[] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
/* Two tets sharing face (1 2 3); vertex 4 = (1,1,1) beyond it. */
static const double two_x[] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 1, 1};
static const int32_t two_t[] = {0, 1, 2, 3, 1, 2, 3, 4};

static double rel(double a, double b) { return fabs(a - b) / fabs(b); }

/* Every boundary face's normal points away from the opposite vertex of its tet. */
static void assert_outward(const bs_mesh *m) {
  for (int32_t f = 0; f < m->n_faces; ++f) {
    const int32_t *fv = m->faces + 3 * f, *tv = m->tets + 4 * m->face_tet[f];
    int32_t opp = -1;
    for (int j = 0; j < 4; ++j)
      if (tv[j] != fv[0] && tv[j] != fv[1] && tv[j] != fv[2]) opp = tv[j];
    cr_assert(opp >= 0, "face %d is not a face of its tet", f);
    const double *a = m->x + 3 * fv[0], *b = m->x + 3 * fv[1], *c = m->x + 3 * fv[2], *o = m->x + 3 * opp;
    double u[3], v[3], w[3];
    for (int k = 0; k < 3; ++k) {
      u[k] = b[k] - a[k];
      v[k] = c[k] - a[k];
      w[k] = a[k] - o[k];
    }
    double n[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
    cr_assert_gt(n[0] * w[0] + n[1] * w[1] + n[2] * w[2], 0.0, "face %d points inward", f);
  }
}

Test(mesh_core, tet_face_table_is_outward) {
  /* Regular orientation check of bs_tet_face on the unit tet. */
  bs_mesh *m = NULL;
  bs_error err = {0};
  int32_t t[] = {0, 1, 2, 3};
  cr_assert_eq(bs_mesh_create(4, tet_x, 1, t, 0, NULL, &m, &err), BS_OK, "%s", err.msg);
  cr_assert_eq(m->n_faces, 4);
  cr_assert_eq(m->n_edges, 6);
  cr_assert_eq(m->n_dropped, 0);
  cr_assert_float_eq(bs_mesh_volume(m), 1.0 / 6.0, 1e-15);
  cr_assert_float_eq(bs_mesh_boundary_volume(m), 1.0 / 6.0, 1e-15);
  assert_outward(m);
  for (int f = 0; f < 4; ++f) cr_assert_eq(m->face_tet[f], 0);
  for (int e = 0; e < m->n_edges; ++e) cr_assert_lt(m->edges[2 * e], m->edges[2 * e + 1]);
  cr_assert_eq(bs_mesh_check(m, &err), BS_OK, "%s", err.msg);
  bs_mesh_destroy(&m);
  cr_assert_null(m);
  bs_mesh_destroy(&m); /* NULL is fine */
  bs_mesh_destroy(NULL);
}

Test(mesh_core, two_tets_share_a_face) {
  bs_mesh *m = NULL;
  bs_error err = {0};
  cr_assert_eq(bs_mesh_create(5, two_x, 2, two_t, 0, NULL, &m, &err), BS_OK, "%s", err.msg);
  cr_assert_eq(m->n_faces, 6);
  cr_assert_eq(m->n_edges, 9); /* closed surface: E = 3F/2 */
  assert_outward(m);
  for (int32_t f = 0; f < m->n_faces; ++f) { /* the shared face is not on the boundary */
    int32_t s[3] = {m->faces[3 * f], m->faces[3 * f + 1], m->faces[3 * f + 2]};
    int has1 = 0, has2 = 0, has3 = 0;
    for (int k = 0; k < 3; ++k) {
      has1 |= s[k] == 1;
      has2 |= s[k] == 2;
      has3 |= s[k] == 3;
    }
    cr_assert(!(has1 && has2 && has3), "interior face (1 2 3) listed as boundary face %d", f);
  }
  for (int32_t e = 1; e < m->n_edges; ++e) /* sorted, unique */
    cr_assert(m->edges[2 * e - 2] < m->edges[2 * e] ||
              (m->edges[2 * e - 2] == m->edges[2 * e] && m->edges[2 * e - 1] < m->edges[2 * e + 1]));
  cr_assert_float_eq(bs_mesh_volume(m), bs_mesh_boundary_volume(m), 1e-15);
  /* v2t: vertex 0 in tet 0 only, vertex 1 in both, vertex 4 in tet 1. */
  cr_assert_eq(m->v2t_ptr[1] - m->v2t_ptr[0], 1);
  cr_assert_eq(m->v2t_ptr[2] - m->v2t_ptr[1], 2);
  cr_assert_eq(m->v2t[m->v2t_ptr[4]], 1);
  int32_t *ptr = NULL, *adj = NULL;
  cr_assert_eq(bs_mesh_vertex_graph(m, &ptr, &adj, &err), BS_OK, "%s", err.msg);
  cr_assert_eq(ptr[1] - ptr[0], 3); /* 0: 1 2 3 */
  cr_assert_eq(ptr[2] - ptr[1], 4); /* 1: 0 2 3 4 */
  int32_t want1[] = {0, 2, 3, 4};
  for (int k = 0; k < 4; ++k) cr_assert_eq(adj[ptr[1] + k], want1[k]);
  cr_assert_eq(ptr[5], 2 * 9); /* 9 graph edges, each stored twice */
  free(ptr);
  free(adj);
  cr_assert_eq(bs_mesh_check(m, &err), BS_OK, "%s", err.msg);
  bs_mesh_destroy(&m);
}

Test(mesh_core, negative_tet_is_reoriented) {
  bs_mesh *m = NULL;
  bs_error err = {0};
  int32_t t[] = {0, 2, 1, 3, 4, 2, 3, 1}; /* both negatively oriented */
  cr_assert_eq(bs_mesh_create(5, two_x, 2, t, 0, NULL, &m, &err), BS_OK, "%s", err.msg);
  for (int32_t i = 0; i < 2; ++i) cr_assert_gt(bs_mesh_tet_volume(m, NULL, i), 0.0);
  cr_assert_float_eq(bs_mesh_tet_volume(m, m->x, 0), 1.0 / 6.0, 1e-15);
  /* Same vertex sets as given. */
  int sum0 = 0;
  for (int j = 0; j < 4; ++j) sum0 += m->tets[j];
  cr_assert_eq(sum0, 6);
  assert_outward(m);
  cr_assert_eq(bs_mesh_check(m, &err), BS_OK, "%s", err.msg);
  bs_mesh_destroy(&m);
}

Test(mesh_core, zero_volume_tet_is_named) {
  bs_mesh *m = NULL;
  bs_error err = {0};
  double x[] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0};
  int32_t t[] = {0, 1, 2, 3};
  cr_assert_eq(bs_mesh_create(4, x, 1, t, 0, NULL, &m, &err), BS_EINPUT);
  cr_assert_null(m);
  cr_assert(strstr(err.msg, "tet 0 has zero volume"), "%s", err.msg);
  cr_assert(strstr(err.msg, "vertices 0 1 2 3"), "%s", err.msg);
  /* A second, nearly flat tet (volume 1e-16 of its edge cubed) is named. */
  double y[] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 1, 1e-16};
  int32_t u[] = {0, 1, 2, 3, 1, 2, 4, 0};
  cr_assert_eq(bs_mesh_create(5, y, 2, u, 0, NULL, &m, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "tet 1 has zero volume"), "%s", err.msg);
  /* A repeated vertex is a zero-volume tet too. */
  int32_t r[] = {0, 1, 1, 3};
  cr_assert_eq(bs_mesh_create(4, tet_x, 1, r, 0, NULL, &m, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "tet 0"), "%s", err.msg);
}

Test(mesh_core, bad_inputs_are_named) {
  bs_mesh *m = NULL;
  bs_error err = {0};
  int32_t t[] = {0, 1, 2, 3, 1, 2, 3, 7};
  cr_assert_eq(bs_mesh_create(5, two_x, 2, t, 0, NULL, &m, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "tet 1") && strstr(err.msg, "index 7"), "%s", err.msg);
  int32_t neg[] = {0, 1, -2, 3};
  cr_assert_eq(bs_mesh_create(4, tet_x, 1, neg, 0, NULL, &m, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "tet 0") && strstr(err.msg, "-2"), "%s", err.msg);

  double x[15];
  memcpy(x, two_x, sizeof x);
  x[3 * 2 + 1] = NAN;
  cr_assert_eq(bs_mesh_create(5, x, 2, two_t, 0, NULL, &m, &err), BS_ENUMERIC);
  cr_assert(strstr(err.msg, "vertex 2"), "%s", err.msg);
  x[3 * 2 + 1] = INFINITY;
  cr_assert_eq(bs_mesh_create(5, x, 2, two_t, 0, NULL, &m, &err), BS_ENUMERIC);
  cr_assert(strstr(err.msg, "vertex 2"), "%s", err.msg);

  cr_assert_eq(bs_mesh_create(5, two_x, 0, two_t, 0, NULL, &m, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "no") || strstr(err.msg, "at least one tet"), "%s", err.msg);

  /* Group element out of range names the group. */
  int32_t tri[] = {0, 1, 9};
  bs_group g = {.dim = 2, .tag = 5, .name = "lid", .n_elems = 1, .elems = tri};
  cr_assert_eq(bs_mesh_create(5, two_x, 2, two_t, 1, &g, &m, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "\"lid\"") && strstr(err.msg, "dim 2, tag 5") && strstr(err.msg, "vertex 9"), "%s",
            err.msg);
  int32_t tet_el[] = {2};
  bs_group h = {.dim = 3, .tag = 4, .name = "steel", .n_elems = 1, .elems = tet_el};
  cr_assert_eq(bs_mesh_create(5, two_x, 2, two_t, 1, &h, &m, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "\"steel\"") && strstr(err.msg, "tet 2"), "%s", err.msg);
  /* Two groups with the same (dim, tag). */
  int32_t tet0[] = {0}, tet1[] = {1};
  bs_group dup[2] = {{.dim = 3, .tag = 4, .name = "a", .n_elems = 1, .elems = tet0},
                     {.dim = 3, .tag = 4, .name = "b", .n_elems = 1, .elems = tet1}};
  cr_assert_eq(bs_mesh_create(5, two_x, 2, two_t, 2, dup, &m, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "\"a\"") && strstr(err.msg, "\"b\""), "%s", err.msg);
  cr_assert_null(m);
}

Test(mesh_core, face_in_three_tets_is_an_error) {
  bs_mesh *m = NULL;
  bs_error err = {0};
  double x[] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 1, 1, -1, -1, -1};
  int32_t t[] = {0, 1, 2, 3, 1, 2, 3, 4, 1, 2, 3, 5};
  cr_assert_eq(bs_mesh_create(6, x, 3, t, 0, NULL, &m, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "face (1 2 3)") && strstr(err.msg, "3 tets"), "%s", err.msg);
}

Test(mesh_core, unused_vertices_are_dropped) {
  bs_mesh *m = NULL;
  bs_error err = {0};
  /* Vertices 1 and 3 are unused; tet uses 0 2 4 5 = the unit tet. */
  double x[] = {0, 0, 0, 9, 9, 9, 1, 0, 0, 8, 8, 8, 0, 1, 0, 0, 0, 1};
  int32_t t[] = {0, 2, 4, 5};
  int32_t pts[] = {3, 5, 1};      /* 0-D: points 3 and 1 are dropped, 5 kept */
  int32_t tri[] = {2, 4, 5};      /* 2-D: the face (1 2 3) after renumbering */
  int32_t lines[] = {0, 2, 2, 3}; /* 1-D: uses dropped vertex 3 -> error */
  bs_group g[3] = {{.dim = 0, .tag = 1, .name = "pins", .n_elems = 3, .elems = pts},
                   {.dim = 2, .tag = 2, .name = NULL, .n_elems = 1, .elems = tri},
                   {.dim = 1, .tag = 3, .name = "wire", .n_elems = 2, .elems = lines}};
  cr_assert_eq(bs_mesh_create(6, x, 1, t, 3, g, &m, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "\"wire\"") && strstr(err.msg, "vertex 3"), "%s", err.msg);

  cr_assert_eq(bs_mesh_create(6, x, 1, t, 2, g, &m, &err), BS_OK, "%s", err.msg);
  cr_assert_eq(m->n_vertices, 4);
  cr_assert_eq(m->n_dropped, 2);
  cr_assert_float_eq(bs_mesh_volume(m), 1.0 / 6.0, 1e-15);
  for (int k = 0; k < 12; ++k) cr_assert_float_eq(m->x[k], tet_x[k], 0.0);
  const bs_group *pins = bs_mesh_group(m, "pins");
  cr_assert_not_null(pins);
  cr_assert_eq(pins->n_elems, 1);
  cr_assert_eq(pins->elems[0], 3);
  cr_assert_eq(pins->n_vertices, 1);
  const bs_group *face = bs_mesh_group_by_tag(m, 2, 2);
  cr_assert_not_null(face);
  cr_assert_str_eq(face->name, "");
  cr_assert_eq(face->n_vertices, 3);
  cr_assert_eq(face->vertices[0], 1);
  cr_assert_eq(face->vertices[2], 3);
  int tagged = 0;
  for (int32_t f = 0; f < m->n_faces; ++f) tagged += m->boundary[f] == 2;
  cr_assert_eq(tagged, 1);
  cr_assert_eq(bs_mesh_check(m, &err), BS_OK, "%s", err.msg);
  bs_mesh_destroy(&m);
}

Test(mesh_core, groups_set_ids) {
  bs_mesh *m = NULL;
  bs_error err = {0};
  int32_t tet1[] = {1};
  int32_t inner[] = {3, 2, 1};  /* the interface (1 2 3): not a boundary face */
  int32_t outer[] = {4, 2, 1};  /* a boundary face of tet 1 */
  bs_group g[3] = {{.dim = 3, .tag = 7, .name = "rubber", .n_elems = 1, .elems = tet1},
                   {.dim = 2, .tag = 3, .name = "interface", .n_elems = 1, .elems = inner},
                   {.dim = 2, .tag = 4, .name = "side", .n_elems = 1, .elems = outer}};
  cr_assert_eq(bs_mesh_create(5, two_x, 2, two_t, 3, g, &m, &err), BS_OK, "%s", err.msg);
  cr_assert_eq(m->material[0], 0);
  cr_assert_eq(m->material[1], 7);
  int n3 = 0, n4 = 0;
  for (int32_t f = 0; f < m->n_faces; ++f) {
    n3 += m->boundary[f] == 3;
    if (m->boundary[f] == 4) {
      ++n4;
      cr_assert_eq(m->face_tet[f], 1);
    }
  }
  cr_assert_eq(n3, 0);
  cr_assert_eq(n4, 1);
  /* Groups are sorted by (dim, tag); lookups by name and by tag. */
  cr_assert_eq(m->groups[0].tag, 3);
  cr_assert_eq(m->groups[2].dim, 3);
  cr_assert_eq(bs_mesh_group(m, "rubber")->n_vertices, 4);
  cr_assert_null(bs_mesh_group(m, "nothing"));
  cr_assert_null(bs_mesh_group_by_tag(m, 3, 1));
  cr_assert_str_eq(bs_mesh_group_by_tag(m, 2, 4)->name, "side");
  cr_assert_eq(bs_mesh_check(m, &err), BS_OK, "%s", err.msg);
  bs_mesh_destroy(&m);
}

Test(mesh_core, box_counts_and_invariants) {
  bs_mesh *m = NULL;
  bs_error err = {0};
  const double lo[3] = {-1.0, 0.5, 2.0}, hi[3] = {0.5, 1.25, 4.0};
  const int nx = 3, ny = 4, nz = 5;
  cr_assert_eq(bs_mesh_create_box(lo, hi, nx, ny, nz, &m, &err), BS_OK, "%s", err.msg);
  cr_assert_eq(m->n_vertices, (nx + 1) * (ny + 1) * (nz + 1));
  cr_assert_eq(m->n_tets, 6 * nx * ny * nz);
  const int nf = 4 * (nx * ny + ny * nz + nz * nx);
  cr_assert_eq(m->n_faces, nf);
  cr_assert_eq(m->n_edges, 3 * nf / 2);
  cr_assert_eq(m->n_dropped, 0);
  cr_assert_eq(bs_mesh_check(m, &err), BS_OK, "%s", err.msg);
  assert_outward(m);
  const double vol = (hi[0] - lo[0]) * (hi[1] - lo[1]) * (hi[2] - lo[2]);
  cr_assert_lt(rel(bs_mesh_volume(m), vol), 1e-12);
  cr_assert_lt(rel(bs_mesh_boundary_volume(m), bs_mesh_volume(m)), 1e-12);
  cr_assert_eq(m->n_groups, 7);
  static const char *names[6] = {"xmin", "xmax", "ymin", "ymax", "zmin", "zmax"};
  const int n[3] = {nx, ny, nz};
  for (int d = 0; d < 3; ++d)
    for (int s = 0; s < 2; ++s) {
      const bs_group *g = bs_mesh_group(m, names[2 * d + s]);
      cr_assert_not_null(g, "%s", names[2 * d + s]);
      int u = (d + 1) % 3, w = (d + 2) % 3;
      cr_assert_eq(g->dim, 2);
      cr_assert_eq(g->tag, 2 * d + s + 1);
      cr_assert_eq(g->n_elems, 2 * n[u] * n[w]);
      cr_assert_eq(g->n_vertices, (n[u] + 1) * (n[w] + 1), "%s", g->name);
      double plane = s ? hi[d] : lo[d];
      for (int32_t k = 0; k < g->n_vertices; ++k) cr_assert_eq(m->x[3 * g->vertices[k] + d], plane);
      /* Each boundary face with this tag lies on the plane; there are n_elems of them. */
      int cnt = 0;
      for (int32_t f = 0; f < m->n_faces; ++f) {
        if (m->boundary[f] != g->tag) continue;
        ++cnt;
        for (int k = 0; k < 3; ++k) cr_assert_eq(m->x[3 * m->faces[3 * f + k] + d], plane);
      }
      cr_assert_eq(cnt, g->n_elems);
    }
  for (int32_t f = 0; f < m->n_faces; ++f) cr_assert_neq(m->boundary[f], 0, "face %d has no boundary id", f);
  const bs_group *body = bs_mesh_group_by_tag(m, 3, 1);
  cr_assert_not_null(body);
  cr_assert_str_eq(body->name, "body");
  cr_assert_eq(body->n_elems, m->n_tets);
  cr_assert_eq(body->n_vertices, m->n_vertices);
  for (int32_t t = 0; t < m->n_tets; ++t) cr_assert_eq(m->material[t], 1);

  /* Vertex graph: symmetric, sorted, no self loops; an interior vertex of the
   * Kuhn box has 14 neighbours. */
  int32_t *ptr = NULL, *adj = NULL;
  cr_assert_eq(bs_mesh_vertex_graph(m, &ptr, &adj, &err), BS_OK, "%s", err.msg);
  for (int32_t v = 0; v < m->n_vertices; ++v)
    for (int32_t k = ptr[v]; k < ptr[v + 1]; ++k) {
      int32_t w = adj[k];
      cr_assert_neq(w, v);
      if (k > ptr[v]) cr_assert_lt(adj[k - 1], w);
      int found = 0;
      for (int32_t q = ptr[w]; q < ptr[w + 1]; ++q) found |= adj[q] == v;
      cr_assert(found, "edge %d-%d not symmetric", v, w);
    }
  int32_t centre = 1 + (nx + 1) * (1 + (ny + 1) * 1);
  cr_assert_eq(ptr[centre + 1] - ptr[centre], 14);
  free(ptr);
  free(adj);

  /* Copy is deep and valid. */
  bs_mesh *c = NULL;
  cr_assert_eq(bs_mesh_copy(m, &c, &err), BS_OK, "%s", err.msg);
  cr_assert_neq(c->x, m->x);
  cr_assert_eq(memcmp(c->tets, m->tets, sizeof(int32_t) * 4 * m->n_tets), 0);
  cr_assert_eq(memcmp(c->faces, m->faces, sizeof(int32_t) * 3 * m->n_faces), 0);
  cr_assert_str_eq(c->groups[3].name, m->groups[3].name);
  cr_assert_neq(c->groups[3].name, m->groups[3].name);
  bs_mesh_destroy(&m);
  cr_assert_eq(bs_mesh_check(c, &err), BS_OK, "%s", err.msg);
  bs_mesh_destroy(&c);
}

Test(mesh_core, box_bad_arguments) {
  bs_mesh *m = NULL;
  bs_error err = {0};
  const double lo[3] = {0, 0, 0}, hi[3] = {1, 0, 1};
  cr_assert_eq(bs_mesh_create_box(lo, hi, 2, 2, 2, &m, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "y range"), "%s", err.msg);
  const double hi2[3] = {1, 1, 1};
  cr_assert_eq(bs_mesh_create_box(lo, hi2, 2, 0, 2, &m, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "ny = 0"), "%s", err.msg);
  cr_assert_eq(bs_mesh_create_box(lo, hi2, 2000, 2000, 2000, &m, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "too many"), "%s", err.msg);
  cr_assert_null(m);
}

Test(mesh_core, finalize_rederives_after_edit) {
  bs_mesh *m = NULL;
  bs_error err = {0};
  const double lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
  cr_assert_eq(bs_mesh_create_box(lo, hi, 2, 2, 2, &m, &err), BS_OK, "%s", err.msg);
  /* Flip every tet's orientation in place: finalize restores it. */
  for (int32_t t = 0; t < m->n_tets; ++t) {
    int32_t s = m->tets[4 * t];
    m->tets[4 * t] = m->tets[4 * t + 1];
    m->tets[4 * t + 1] = s;
  }
  cr_assert_neq(bs_mesh_check(m, &err), BS_OK);
  cr_assert(strstr(err.msg, "tet 0"), "%s", err.msg);
  cr_assert_eq(bs_mesh_finalize(m, &err), BS_OK, "%s", err.msg);
  cr_assert_eq(bs_mesh_check(m, &err), BS_OK, "%s", err.msg);
  cr_assert_eq(m->n_faces, 48);
  /* A non-finite coordinate is refused by name; fixing it and finalizing again recovers. */
  double keep = m->x[3 * 7 + 2];
  m->x[3 * 7 + 2] = NAN;
  cr_assert_eq(bs_mesh_finalize(m, &err), BS_ENUMERIC);
  cr_assert(strstr(err.msg, "vertex 7"), "%s", err.msg);
  m->x[3 * 7 + 2] = keep;
  cr_assert_eq(bs_mesh_finalize(m, &err), BS_OK, "%s", err.msg);
  cr_assert_eq(bs_mesh_check(m, &err), BS_OK, "%s", err.msg);
  bs_mesh_destroy(&m);
}

Test(mesh_core, check_detects_flipped_face) {
  bs_mesh *m = NULL;
  bs_error err = {0};
  const double lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
  cr_assert_eq(bs_mesh_create_box(lo, hi, 2, 2, 2, &m, &err), BS_OK, "%s", err.msg);
  int32_t s = m->faces[3 * 5 + 1];
  m->faces[3 * 5 + 1] = m->faces[3 * 5 + 2];
  m->faces[3 * 5 + 2] = s;
  cr_assert_eq(bs_mesh_check(m, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "boundary face 5") && strstr(err.msg, "not outward"), "%s", err.msg);
  bs_mesh_destroy(&m);
}

Test(mesh_core, check_detects_broken_boundary_and_adjacency) {
  bs_mesh *m = NULL;
  bs_error err = {0};
  cr_assert_eq(bs_mesh_create(5, two_x, 2, two_t, 0, NULL, &m, &err), BS_OK, "%s", err.msg);
  /* Drop a boundary face from the list. */
  m->n_faces--;
  cr_assert_eq(bs_mesh_check(m, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "5 boundary faces") && strstr(err.msg, "6"), "%s", err.msg);
  m->n_faces++;
  /* Corrupt the adjacency. */
  int32_t keep = m->v2t[0];
  m->v2t[0] = 1; /* vertex 0 is not in tet 1 */
  cr_assert_eq(bs_mesh_check(m, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "vertex 0") && strstr(err.msg, "tet 1"), "%s", err.msg);
  m->v2t[0] = keep;
  /* A group vertex set out of range. */
  int32_t tet1[] = {1};
  bs_group g = {.dim = 3, .tag = 2, .name = "part", .n_elems = 1, .elems = tet1};
  bs_mesh *h = NULL;
  cr_assert_eq(bs_mesh_create(5, two_x, 2, two_t, 1, &g, &h, &err), BS_OK, "%s", err.msg);
  h->groups[0].vertices[3] = 99;
  cr_assert_eq(bs_mesh_check(h, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "\"part\"") && strstr(err.msg, "99"), "%s", err.msg);
  cr_assert_eq(bs__group_update_vertices(h, &h->groups[0], &err), BS_OK);
  cr_assert_eq(bs_mesh_check(h, &err), BS_OK, "%s", err.msg);
  h->material[0] = 5;
  cr_assert_eq(bs_mesh_check(h, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "tet 0") && strstr(err.msg, "material id 5"), "%s", err.msg);
  bs_mesh_destroy(&h);
  cr_assert_eq(bs_mesh_check(m, &err), BS_OK, "%s", err.msg);
  bs_mesh_destroy(&m);
}

/* Appends a copy of tet `dup` to m (bypassing finalize). */
static void duplicate_tet(bs_mesh *m, int32_t dup) {
  int32_t *t = realloc(m->tets, sizeof(int32_t) * 4 * (m->n_tets + 1));
  cr_assert_not_null(t);
  memcpy(t + 4 * m->n_tets, t + 4 * dup, 4 * sizeof(int32_t));
  m->tets = t;
  m->n_tets++;
}

Test(mesh_core, check_detects_duplicate_tet) {
  bs_mesh *m = NULL;
  bs_error err = {0};
  cr_assert_eq(bs_mesh_create(5, two_x, 2, two_t, 0, NULL, &m, &err), BS_OK, "%s", err.msg);
  duplicate_tet(m, 1);
  cr_assert_eq(bs_mesh_check(m, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "face (1 2 3)") && strstr(err.msg, "3 tets") && strstr(err.msg, "2"), "%s", err.msg);
  bs_mesh_destroy(&m);
  /* A single tet given twice: every face in two tets on the same side. */
  int32_t t[] = {0, 1, 2, 3};
  cr_assert_eq(bs_mesh_create(4, tet_x, 1, t, 0, NULL, &m, &err), BS_OK, "%s", err.msg);
  duplicate_tet(m, 0);
  cr_assert_eq(bs_mesh_check(m, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "tets 0 and 1") && strstr(err.msg, "same side"), "%s", err.msg);
  bs_mesh_destroy(&m);
  /* And bs_mesh_create refuses it too. */
  int32_t tt[] = {0, 1, 2, 3, 0, 1, 2, 3, 1, 2, 3, 4};
  cr_assert_eq(bs_mesh_create(5, two_x, 3, tt, 0, NULL, &m, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "3 tets"), "%s", err.msg);
}

Test(mesh_core, check_detects_open_boundary) {
  bs_mesh *m = NULL;
  bs_error err = {0};
  const double lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
  cr_assert_eq(bs_mesh_create_box(lo, hi, 1, 1, 1, &m, &err), BS_OK, "%s", err.msg);
  /* Edge list out of step with the faces. */
  m->edges[1]++;
  cr_assert_eq(bs_mesh_check(m, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "boundary edge 0"), "%s", err.msg);
  m->edges[1]--;
  cr_assert_eq(bs_mesh_check(m, &err), BS_OK, "%s", err.msg);
  /* Point boundary face 0 at an interior face of its tet (each Kuhn tet of a
   * single cube has two): the list no longer covers the boundary. */
  int32_t t = m->face_tet[0];
  int32_t *fv = m->faces;
  for (int lf = 0; lf < 4; ++lf) {
    int32_t u[3] = {m->tets[4 * t + bs_tet_face[lf][0]], m->tets[4 * t + bs_tet_face[lf][1]],
                    m->tets[4 * t + bs_tet_face[lf][2]]};
    int same = 0;
    for (int k = 0; k < 3; ++k) same += (u[k] == fv[0] || u[k] == fv[1] || u[k] == fv[2]);
    int boundary = 0;
    for (int32_t g = 0; g < m->n_faces; ++g) {
      int s = 0;
      for (int k = 0; k < 3; ++k)
        for (int q = 0; q < 3; ++q) s += u[k] == m->faces[3 * g + q];
      boundary |= s == 3;
    }
    if (same < 3 && !boundary) {
      memcpy(fv, u, sizeof u);
      break;
    }
  }
  cr_assert_eq(bs_mesh_check(m, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "boundary face 0") && strstr(err.msg, "interior"), "%s", err.msg);
  bs_mesh_destroy(&m);
}

Test(mesh_core, quality_regular_tet) {
  bs_mesh *m = NULL;
  bs_error err = {0};
  double x[] = {1, 1, 1, 1, -1, -1, -1, 1, -1, -1, -1, 1};
  int32_t t[] = {0, 1, 2, 3};
  cr_assert_eq(bs_mesh_create(4, x, 1, t, 0, NULL, &m, &err), BS_OK, "%s", err.msg);
  bs_mesh_quality q;
  bs_mesh_quality_compute(m, NULL, &q);
  const double dih = acos(1.0 / 3.0) * 180.0 / acos(-1.0);
  cr_assert_float_eq(q.radius_ratio_min, 1.0, 1e-12);
  cr_assert_float_eq(q.radius_ratio_mean, 1.0, 1e-12);
  cr_assert_float_eq(q.dihedral_min, dih, 1e-10);
  cr_assert_float_eq(q.dihedral_max, dih, 1e-10);
  cr_assert_float_eq(fabs(q.vol_min), 8.0 / 3.0, 1e-12); /* edge 2 sqrt 2: a^3 / (6 sqrt 2) */
  cr_assert_eq(q.n_inverted, 0);
  cr_assert_eq(q.n_degenerate, 0);
  cr_assert_eq(q.n_sliver, 0);
  /* Reflect one vertex through the opposite face: inverted. */
  double y[12];
  memcpy(y, m->x, sizeof y);
  int32_t v0 = m->tets[0];
  /* The other three span the plane through their centroid -x0/3 with normal
   * x0; -x0 lies beyond it. */
  for (int k = 0; k < 3; ++k) y[3 * v0 + k] = -m->x[3 * v0 + k];
  bs_mesh_quality_compute(m, y, &q);
  cr_assert_eq(q.n_inverted, 1);
  cr_assert_lt(q.vol_max, 0.0);
  cr_assert_lt(q.radius_ratio_min, 0.0);
  /* Flatten it onto that plane: zero volume, dihedral angles 0 and 180. */
  for (int k = 0; k < 3; ++k) y[3 * v0 + k] = -m->x[3 * v0 + k] / 3.0;
  bs_mesh_quality_compute(m, y, &q);
  cr_assert_eq(q.n_sliver + q.n_degenerate, 2, "sliver %d degenerate %d", q.n_sliver, q.n_degenerate);
  cr_assert_float_eq(q.radius_ratio_min, 0.0, 1e-12);
  bs_mesh_destroy(&m);
}

Test(mesh_core, quality_box) {
  bs_mesh *m = NULL;
  bs_error err = {0};
  const double lo[3] = {0, 0, 0}, hi[3] = {2, 2, 2};
  cr_assert_eq(bs_mesh_create_box(lo, hi, 4, 4, 4, &m, &err), BS_OK, "%s", err.msg);
  bs_mesh_quality q;
  bs_mesh_quality_compute(m, NULL, &q);
  /* Kuhn tets of a cube of side h: volume h^3/6, dihedral angles 45, 60, 90
   * degrees, all congruent so min = mean radius ratio. */
  cr_assert_float_eq(q.vol_min, 0.125 / 6.0, 1e-15);
  cr_assert_float_eq(q.vol_max, 0.125 / 6.0, 1e-15);
  cr_assert_float_eq(q.dihedral_min, 45.0, 1e-10);
  cr_assert_float_eq(q.dihedral_max, 90.0, 1e-10);
  cr_assert_float_eq(q.radius_ratio_min, q.radius_ratio_mean, 1e-12);
  /* Kuhn tet (0, e1, e1+e2, e1+e2+e3): r_in = 1/(2 + sqrt 2) * ... computed
   * independently: 3 r_in / R with R = sqrt 3 / 2, r_in = 3V/S. */
  double S = 0.5 * (1 + sqrt(2.0)) * 2, V = 1.0 / 6.0; /* two right triangles 1x1, two 1 x sqrt2 */
  double expect = 3 * (3 * V / S) / (sqrt(3.0) / 2);
  cr_assert_float_eq(q.radius_ratio_min, expect, 1e-12);
  cr_assert_eq(q.n_inverted + q.n_degenerate + q.n_sliver, 0);
  bs_mesh_destroy(&m);
}

Test(mesh_core, box_64_cubed) {
  /* The largest box the benchmarks use: 64^3 cells, 1.57M tets. */
  bs_mesh *m = NULL;
  bs_error err = {0};
  const double lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
  cr_assert_eq(bs_mesh_create_box(lo, hi, 64, 64, 64, &m, &err), BS_OK, "%s", err.msg);
  cr_assert_eq(m->n_vertices, 65 * 65 * 65);
  cr_assert_eq(m->n_tets, 6 * 64 * 64 * 64);
  cr_assert_eq(m->n_faces, 12 * 64 * 64);
  cr_assert_eq(m->n_edges, 18 * 64 * 64);
  cr_assert_lt(rel(bs_mesh_volume(m), 1.0), 1e-12);
  cr_assert_lt(rel(bs_mesh_boundary_volume(m), 1.0), 1e-12);
  cr_assert_eq(bs_mesh_check(m, &err), BS_OK, "%s", err.msg);
  bs_mesh_destroy(&m);
}

/* bs__boundary_manifold: one tet is a closed 2-manifold with one
 * component; two tets joined by an edge or by a vertex only are refused
 * (bs_mesh_check accepts both), naming the edge's midpoint or the vertex;
 * two separate tets are two components, refused when one is expected. */
Test(mesh_core, boundary_manifold_refuses_pinches) {
  static const double x[] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, /* tet A: 0 1 2 3 */
                             1, 1, 1, 2, 1, 0, 1, 2, 0,           /* 4 5 6 */
                             5, 5, 5, 6, 5, 5, 5, 6, 5, 5, 5, 6}; /* 7 8 9 10: far away */
  static const int32_t one[] = {0, 1, 2, 3};
  static const int32_t by_edge[] = {0, 1, 2, 3, 1, 2, 4, 5}; /* shares edge 1-2 only */
  static const int32_t by_vertex[] = {0, 1, 2, 3, 3, 4, 5, 6}; /* shares vertex 3 only */
  static const int32_t apart[] = {0, 1, 2, 3, 7, 8, 9, 10};
  bs_mesh *m = NULL;
  bs_error err = {0};
  cr_assert_eq(bs_mesh_create(4, x, 1, one, 0, NULL, &m, &err), BS_OK, "%s", err.msg);
  cr_expect_eq(bs__boundary_manifold(m, "one.msh", 1, &err), BS_OK, "%s", err.msg);
  bs_mesh_destroy(&m);

  cr_assert_eq(bs_mesh_create(6, x, 2, by_edge, 0, NULL, &m, &err), BS_OK, "%s", err.msg);
  cr_expect_eq(bs_mesh_check(m, &err), BS_OK, "%s", err.msg);
  cr_expect_eq(bs__boundary_manifold(m, "edge.msh", 1, &err), BS_EINPUT);
  cr_expect(strstr(err.msg, "edge.msh") && strstr(err.msg, "1 edges in more than two") &&
                strstr(err.msg, "(0.5, 0.5, 0)"),
            "%s", err.msg);
  bs_mesh_destroy(&m);

  cr_assert_eq(bs_mesh_create(7, x, 2, by_vertex, 0, NULL, &m, &err), BS_OK, "%s", err.msg);
  cr_expect_eq(bs__boundary_manifold(m, "vertex.msh", 1, &err), BS_EINPUT);
  cr_expect(strstr(err.msg, "0 edges") && strstr(err.msg, "1 vertices where two parts") && strstr(err.msg, "(0, 0, 1)"),
            "%s", err.msg);
  bs_mesh_destroy(&m);

  cr_assert_eq(bs_mesh_create(11, x, 2, apart, 0, NULL, &m, &err), BS_OK, "%s", err.msg);
  cr_expect_eq(bs__boundary_manifold(m, "apart.msh", 2, &err), BS_OK, "%s", err.msg);
  cr_expect_eq(bs__boundary_manifold(m, "apart.msh", 1, &err), BS_EINPUT);
  cr_expect(strstr(err.msg, "2 boundary components where the surface has 1"), "%s", err.msg);
  /* a soup's components, those under a volume left out */
  int32_t parent[11];
  cr_expect_eq(bs__soup_components(m->x, m->n_vertices, m->faces, m->n_faces, 0.0, parent), 2);
  cr_expect_eq(bs__soup_components(m->x, m->n_vertices, m->faces, m->n_faces, 1.0 / 6.0 + 1e-9, parent), 0);
  bs_mesh_destroy(&m);
}
