/* Uniform red refinement: counts, volume, orientation, vertex numbering,
 * groups, quality, determinism, and the error paths. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bs_mesh.h"

static const double ref_tet_x[12] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};

/* A single tet with one group of every dimension. */
static bs_mesh *single_tet(void) {
  static const int32_t tet[4] = {0, 1, 2, 3};
  static int32_t body[1] = {0};
  static int32_t tri[3] = {1, 2, 3};
  static int32_t seg[2] = {0, 1};
  static int32_t pt[1] = {3};
  bs_group g[4] = {
      {.dim = 3, .tag = 7, .name = "body", .n_elems = 1, .elems = body},
      {.dim = 2, .tag = 3, .name = "slant", .n_elems = 1, .elems = tri},
      {.dim = 1, .tag = 2, .name = "axis", .n_elems = 1, .elems = seg},
      {.dim = 0, .tag = 5, .name = "apex", .n_elems = 1, .elems = pt},
  };
  bs_mesh *m = NULL;
  bs_error err = {0};
  int rc = bs_mesh_create(4, ref_tet_x, 1, tet, 4, g, &m, &err);
  cr_assert_eq(rc, BS_OK, "create single tet: %s", err.msg);
  return m;
}

static bs_mesh *box(int nx, int ny, int nz) {
  const double lo[3] = {-1.0, 0.0, 0.5}, hi[3] = {1.0, 1.5, 2.5};
  bs_mesh *m = NULL;
  bs_error err = {0};
  int rc = bs_mesh_create_box(lo, hi, nx, ny, nz, &m, &err);
  cr_assert_eq(rc, BS_OK, "create box: %s", err.msg);
  return m;
}

static bs_mesh *refined(const bs_mesh *m) {
  bs_mesh *f = NULL;
  bs_error err = {0};
  int rc = bs_mesh_refine(m, &f, &err);
  cr_assert_eq(rc, BS_OK, "refine: %s", err.msg);
  cr_assert_not_null(f);
  return f;
}

/* Number of distinct edges of the mesh (the vertex graph's edges). */
static int64_t count_edges(const bs_mesh *m) {
  int32_t *ptr = NULL, *adj = NULL;
  bs_error err = {0};
  cr_assert_eq(bs_mesh_vertex_graph(m, &ptr, &adj, &err), BS_OK, "%s", err.msg);
  int64_t n = ptr[m->n_vertices] / 2;
  free(ptr);
  free(adj);
  return n;
}

static double dist2(const double *x, int32_t a, int32_t b) {
  double s = 0;
  for (int k = 0; k < 3; k++) s += (x[3 * a + k] - x[3 * b + k]) * (x[3 * a + k] - x[3 * b + k]);
  return s;
}

/* Everything a refinement must satisfy, for coarse c and fine f. */
static void check_refinement(const bs_mesh *c, const bs_mesh *f) {
  bs_error err = {0};
  cr_assert_eq(bs_mesh_check(f, &err), BS_OK, "check of refined mesh: %s", err.msg);
  cr_assert_eq(f->n_tets, 8 * c->n_tets);
  int64_t ne = count_edges(c);
  cr_assert_eq((int64_t)f->n_vertices, c->n_vertices + ne, "fine vertices %d, coarse %d + edges %lld", f->n_vertices,
               c->n_vertices, (long long)ne);

  /* coarse vertices keep index and position, bit for bit */
  cr_assert(memcmp(f->x, c->x, 3 * sizeof(double) * (size_t)c->n_vertices) == 0, "coarse vertices moved");

  /* volume preserved, every child positive; boundary volume agrees */
  double vc = bs_mesh_volume(c), vf = bs_mesh_volume(f);
  cr_assert(fabs(vf - vc) <= 1e-12 * vc, "volume %.17g -> %.17g", vc, vf);
  cr_assert(fabs(bs_mesh_boundary_volume(f) - vf) <= 1e-12 * vf, "boundary volume %.17g vs %.17g",
            bs_mesh_boundary_volume(f), vf);
  for (int32_t t = 0; t < f->n_tets; t++) {
    double v = bs_mesh_tet_volume(f, f->x, t);
    cr_assert(v > 0, "child %d has volume %g", t, v);
  }
  /* the 8 children of each parent fill it exactly */
  for (int32_t t = 0; t < c->n_tets; t++) {
    double s = 0;
    for (int k = 0; k < 8; k++) s += bs_mesh_tet_volume(f, f->x, 8 * t + k);
    double p = bs_mesh_tet_volume(c, c->x, t);
    cr_assert(fabs(s - p) <= 1e-12 * p, "children of tet %d: volume %.17g vs parent %.17g", t, s, p);
  }

  /* every new vertex is the midpoint of a coarse edge: new vertex n + e is
   * the midpoint of the e-th edge in lexicographic (min, max) order */
  {
    int32_t *ptr = NULL, *adj = NULL;
    cr_assert_eq(bs_mesh_vertex_graph(c, &ptr, &adj, &err), BS_OK, "%s", err.msg);
    int32_t v = c->n_vertices;
    for (int32_t a = 0; a < c->n_vertices; a++)
      for (int32_t p = ptr[a]; p < ptr[a + 1]; p++) {
        int32_t b = adj[p];
        if (b <= a) continue;
        for (int k = 0; k < 3; k++)
          cr_assert_eq(f->x[3 * v + k], 0.5 * (c->x[3 * a + k] + c->x[3 * b + k]),
                       "vertex %d is not the midpoint of edge %d-%d", v, a, b);
        v++;
      }
    cr_assert_eq(v, f->n_vertices);
    free(ptr);
    free(adj);
  }

  /* children inherit material */
  for (int32_t t = 0; t < c->n_tets; t++)
    for (int k = 0; k < 8; k++)
      cr_assert_eq(f->material[8 * t + k], c->material[t], "child %d of tet %d: material %d, parent %d", k, t,
                   f->material[8 * t + k], c->material[t]);

  /* groups: same (dim, tag, name), element counts scaled */
  cr_assert_eq(f->n_groups, c->n_groups);
  static const int factor[4] = {1, 2, 4, 8};
  for (int g = 0; g < c->n_groups; g++) {
    const bs_group *gc = &c->groups[g];
    const bs_group *gf = bs_mesh_group_by_tag(f, gc->dim, gc->tag);
    cr_assert_not_null(gf, "group (%d, %d) lost", gc->dim, gc->tag);
    cr_assert_str_eq(gf->name, gc->name);
    cr_assert_eq(gf->n_elems, factor[gc->dim] * gc->n_elems, "group %s: %d elements from %d", gc->name, gf->n_elems,
                 gc->n_elems);
    if (gc->dim == 3) {
      /* exactly the children of the parent's tets */
      char *in = calloc((size_t)f->n_tets, 1);
      for (int32_t j = 0; j < gf->n_elems; j++) {
        cr_assert(gf->elems[j] >= 0 && gf->elems[j] < f->n_tets);
        in[gf->elems[j]] = 1;
      }
      for (int32_t i = 0; i < gc->n_elems; i++)
        for (int k = 0; k < 8; k++)
          cr_assert(in[8 * gc->elems[i] + k], "group %s: child %d of tet %d missing", gc->name, k, gc->elems[i]);
      free(in);
    }
  }
}

/* The diagonal chosen for each octahedron is a shortest one. */
static void check_shortest_diagonal(const bs_mesh *c, const bs_mesh *f) {
  for (int32_t t = 0; t < c->n_tets; t++) {
    const int32_t *p = c->tets + 4 * t;
    /* midpoint vertex of parent edge (i, j): the vertex of the corner child
     * at i that is equidistant (1/2) between p[i] and p[j]: find it by
     * position */
    int32_t m[4][4];
    for (int i = 0; i < 4; i++)
      for (int j = 0; j < 4; j++) {
        m[i][j] = -1;
        if (i == j) continue;
        double mx[3];
        for (int k = 0; k < 3; k++) mx[k] = 0.5 * (c->x[3 * p[i] + k] + c->x[3 * p[j] + k]);
        for (int ch = 0; ch < 8 && m[i][j] < 0; ch++)
          for (int q = 0; q < 4; q++) {
            int32_t v = f->tets[4 * (8 * t + ch) + q];
            if (f->x[3 * v] == mx[0] && f->x[3 * v + 1] == mx[1] && f->x[3 * v + 2] == mx[2]) m[i][j] = v;
          }
        cr_assert(m[i][j] >= 0, "tet %d: no child vertex at the midpoint of edge %d-%d", t, i, j);
        cr_assert(m[i][j] >= c->n_vertices, "tet %d: midpoint of %d-%d is a coarse vertex", t, i, j);
      }
    const int32_t diag[3][2] = {{m[0][1], m[2][3]}, {m[0][2], m[1][3]}, {m[0][3], m[1][2]}};
    double len[3];
    for (int d = 0; d < 3; d++) len[d] = dist2(f->x, diag[d][0], diag[d][1]);
    /* which diagonal do the four interior children all contain? */
    int chosen = -1;
    for (int d = 0; d < 3; d++) {
      int all = 1;
      for (int ch = 4; ch < 8; ch++) {
        int has0 = 0, has1 = 0;
        for (int q = 0; q < 4; q++) {
          has0 |= f->tets[4 * (8 * t + ch) + q] == diag[d][0];
          has1 |= f->tets[4 * (8 * t + ch) + q] == diag[d][1];
        }
        all &= has0 && has1;
      }
      if (all) chosen = d;
    }
    cr_assert(chosen >= 0, "tet %d: interior children share no octahedron diagonal", t);
    for (int d = 0; d < 3; d++)
      cr_assert(len[chosen] <= len[d], "tet %d: diagonal %d (length^2 %g) chosen over shorter %d (%g)", t, chosen,
                len[chosen], d, len[d]);
  }
}

Test(refine, single_tet) {
  bs_mesh *c = single_tet();
  bs_mesh *f = refined(c);
  check_refinement(c, f);
  check_shortest_diagonal(c, f);
  cr_assert_eq(f->n_vertices, 10);
  cr_assert_eq(f->n_faces, 16, "a refined tet has 4 x 4 boundary triangles, got %d", f->n_faces);
  /* all 8 children of the reference tet have volume 1/48 */
  for (int32_t t = 0; t < 8; t++) {
    double v = bs_mesh_tet_volume(f, f->x, t);
    cr_assert(fabs(v - 1.0 / 48.0) < 1e-15, "child %d volume %.17g", t, v);
  }
  /* midpoints numbered in lexicographic edge order: 01 02 03 12 13 23 */
  static const int ends[6][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};
  for (int e = 0; e < 6; e++)
    for (int k = 0; k < 3; k++)
      cr_assert_eq(f->x[3 * (4 + e) + k], 0.5 * (ref_tet_x[3 * ends[e][0] + k] + ref_tet_x[3 * ends[e][1] + k]),
                   "vertex %d is not the midpoint of %d-%d", 4 + e, ends[e][0], ends[e][1]);
  /* vertex sets of the lower-dimensional groups */
  const bs_group *tri = bs_mesh_group(f, "slant");
  cr_assert_not_null(tri);
  cr_assert_eq(tri->n_vertices, 6); /* 1 2 3 and the midpoints of 12 13 23 = 7 8 9 */
  static const int32_t tri_v[6] = {1, 2, 3, 7, 8, 9};
  cr_assert(memcmp(tri->vertices, tri_v, sizeof tri_v) == 0);
  /* the four triangles are boundary faces carrying the group's tag */
  int tagged = 0;
  for (int32_t i = 0; i < f->n_faces; i++) tagged += f->boundary[i] == 3;
  cr_assert_eq(tagged, 4, "faces tagged 3: %d", tagged);
  const bs_group *seg = bs_mesh_group(f, "axis");
  cr_assert_not_null(seg);
  static const int32_t seg_v[3] = {0, 1, 4};
  cr_assert_eq(seg->n_vertices, 3);
  cr_assert(memcmp(seg->vertices, seg_v, sizeof seg_v) == 0);
  static const int32_t seg_e[4] = {0, 4, 4, 1};
  cr_assert(memcmp(seg->elems, seg_e, sizeof seg_e) == 0);
  const bs_group *pt = bs_mesh_group(f, "apex");
  cr_assert_not_null(pt);
  cr_assert_eq(pt->n_elems, 1);
  cr_assert_eq(pt->elems[0], 3);
  cr_assert_eq(f->material[5], 7);
  bs_mesh_destroy(&f);
  bs_mesh_destroy(&c);
  cr_assert_null(c);
}

/* The six face groups of a box: 4x the triangles, and vertex sets exactly
 * the vertices on the face plane. */
static void check_box_faces(const bs_mesh *c, const bs_mesh *f) {
  static const char *names[6] = {"xmin", "xmax", "ymin", "ymax", "zmin", "zmax"};
  double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
  for (int32_t v = 0; v < c->n_vertices; v++)
    for (int k = 0; k < 3; k++) {
      lo[k] = fmin(lo[k], c->x[3 * v + k]);
      hi[k] = fmax(hi[k], c->x[3 * v + k]);
    }
  for (int s = 0; s < 6; s++) {
    const bs_group *gc = bs_mesh_group(c, names[s]);
    const bs_group *gf = bs_mesh_group(f, names[s]);
    cr_assert_not_null(gc, "coarse box lacks group %s", names[s]);
    cr_assert_not_null(gf, "refined box lacks group %s", names[s]);
    cr_assert_eq(gf->dim, 2);
    cr_assert_eq(gf->n_elems, 4 * gc->n_elems, "%s: %d triangles from %d", names[s], gf->n_elems, gc->n_elems);
    int k = s / 2;
    double plane = s % 2 ? hi[k] : lo[k];
    int32_t n_on = 0;
    for (int32_t v = 0; v < f->n_vertices; v++) {
      if (f->x[3 * v + k] != plane) continue;
      cr_assert(n_on < gf->n_vertices && gf->vertices[n_on] == v, "%s: vertex %d on the plane is not in the set",
                names[s], v);
      n_on++;
    }
    cr_assert_eq(n_on, gf->n_vertices, "%s: %d vertices on the plane, set has %d", names[s], n_on, gf->n_vertices);
    /* its triangles are boundary faces tagged with the group */
    int32_t tagged = 0;
    for (int32_t i = 0; i < f->n_faces; i++) tagged += f->boundary[i] == gf->tag;
    cr_assert_eq(tagged, gf->n_elems, "%s: %d faces tagged %d, %d triangles", names[s], tagged, gf->tag, gf->n_elems);
  }
  const bs_group *body = bs_mesh_group(f, "body");
  cr_assert_not_null(body);
  cr_assert_eq(body->n_elems, f->n_tets);
}

Test(refine, box_three_levels) {
  bs_mesh *m0 = box(2, 3, 4);
  bs_mesh *m1 = refined(m0);
  bs_mesh *m2 = refined(m1);
  bs_mesh *m3 = refined(m2);
  check_refinement(m0, m1);
  check_refinement(m1, m2);
  check_refinement(m2, m3);
  check_shortest_diagonal(m0, m1);
  check_shortest_diagonal(m1, m2);
  check_box_faces(m0, m1);
  check_box_faces(m1, m2);
  check_box_faces(m2, m3);
  cr_assert_eq(m3->n_tets, 6 * 24 * 512);
  /* coarse vertex i is vertex i at every level */
  cr_assert(memcmp(m3->x, m0->x, 3 * sizeof(double) * (size_t)m0->n_vertices) == 0);

  /* quality stays bounded: the radius ratio of the refined meshes does not
   * fall below a fixed fraction of the coarse one */
  bs_mesh_quality q0, q1, q2, q3;
  bs_mesh_quality_compute(m0, NULL, &q0);
  bs_mesh_quality_compute(m1, NULL, &q1);
  bs_mesh_quality_compute(m2, NULL, &q2);
  bs_mesh_quality_compute(m3, NULL, &q3);
  cr_log_info("radius ratio min: %.6f %.6f %.6f %.6f", q0.radius_ratio_min, q1.radius_ratio_min, q2.radius_ratio_min,
              q3.radius_ratio_min);
  /* measured: 0.578 coarse (Kuhn tets), 0.487 after one level, then the
   * same at every level (the children fall into a fixed set of shapes) */
  cr_assert(q0.radius_ratio_min > 0.5);
  cr_assert(q1.radius_ratio_min >= 0.8 * q0.radius_ratio_min, "level 1: %g vs %g", q1.radius_ratio_min,
            q0.radius_ratio_min);
  cr_assert(q2.radius_ratio_min >= (1 - 1e-9) * q1.radius_ratio_min, "level 2: %g vs level 1 %g",
            q2.radius_ratio_min, q1.radius_ratio_min);
  cr_assert(q3.radius_ratio_min >= (1 - 1e-9) * q1.radius_ratio_min, "level 3: %g vs level 1 %g",
            q3.radius_ratio_min, q1.radius_ratio_min);
  cr_assert_eq(q3.n_inverted, 0);
  cr_assert_eq(q3.n_sliver, 0);
  bs_mesh_destroy(&m3);
  bs_mesh_destroy(&m2);
  bs_mesh_destroy(&m1);
  bs_mesh_destroy(&m0);
}

/* A single badly shaped tet refined repeatedly: quality bounded relative to
 * the coarse tet (the shortest-diagonal rule keeps a bounded number of
 * similarity classes). */
Test(refine, quality_of_a_skewed_tet) {
  static const double x[12] = {0, 0, 0, 3, 0, 0, 0.4, 0.7, 0, 2.2, 0.3, 0.5};
  static const int32_t tet[4] = {0, 1, 2, 3};
  bs_mesh *m = NULL;
  bs_error err = {0};
  cr_assert_eq(bs_mesh_create(4, x, 1, tet, 0, NULL, &m, &err), BS_OK, "%s", err.msg);
  bs_mesh_quality q0;
  bs_mesh_quality_compute(m, NULL, &q0);
  double worst = 1.0;
  for (int level = 1; level <= 4; level++) {
    bs_mesh *f = refined(m);
    check_refinement(m, f);
    check_shortest_diagonal(m, f);
    bs_mesh_quality q;
    bs_mesh_quality_compute(f, NULL, &q);
    worst = fmin(worst, q.radius_ratio_min / q0.radius_ratio_min);
    bs_mesh_destroy(&m);
    m = f;
  }
  cr_log_info("skewed tet: coarse radius ratio %.4f, worst refined / coarse %.4f", q0.radius_ratio_min, worst);
  /* measured: 0.73 over four levels */
  cr_assert(worst >= 0.6, "radius ratio fell to %.4f of the coarse one", worst);
  bs_mesh_destroy(&m);
}

static void assert_same_mesh(const bs_mesh *a, const bs_mesh *b) {
  cr_assert_eq(a->n_vertices, b->n_vertices);
  cr_assert_eq(a->n_tets, b->n_tets);
  cr_assert_eq(a->n_faces, b->n_faces);
  cr_assert(memcmp(a->x, b->x, 3 * sizeof(double) * (size_t)a->n_vertices) == 0);
  cr_assert(memcmp(a->tets, b->tets, 4 * sizeof(int32_t) * (size_t)a->n_tets) == 0);
  cr_assert(memcmp(a->material, b->material, sizeof(int32_t) * (size_t)a->n_tets) == 0);
  cr_assert(memcmp(a->faces, b->faces, 3 * sizeof(int32_t) * (size_t)a->n_faces) == 0);
  cr_assert_eq(a->n_groups, b->n_groups);
  for (int g = 0; g < a->n_groups; g++) {
    const bs_group *x = &a->groups[g], *y = &b->groups[g];
    int tuple = x->dim == 3 ? 1 : x->dim + 1;
    cr_assert_eq(x->n_elems, y->n_elems);
    cr_assert_eq(x->n_vertices, y->n_vertices);
    cr_assert(memcmp(x->elems, y->elems, sizeof(int32_t) * (size_t)x->n_elems * tuple) == 0);
    cr_assert(memcmp(x->vertices, y->vertices, sizeof(int32_t) * (size_t)x->n_vertices) == 0);
  }
}

Test(refine, repeatable) {
  bs_mesh *m0 = box(2, 3, 4);
  bs_mesh *a1 = refined(m0), *b1 = refined(m0);
  assert_same_mesh(a1, b1);
  bs_mesh *a2 = refined(a1), *b2 = refined(b1);
  assert_same_mesh(a2, b2);
  bs_mesh_destroy(&a1);
  bs_mesh_destroy(&b1);
  bs_mesh_destroy(&a2);
  bs_mesh_destroy(&b2);
  bs_mesh_destroy(&m0);
}

Test(refine, errors) {
  bs_error err = {0};
  bs_mesh *f = (bs_mesh *)&err; /* must be reset to NULL on failure */
  cr_assert_eq(bs_mesh_refine(NULL, &f, &err), BS_EINPUT);
  cr_assert_null(f);
  cr_assert(strstr(err.msg, "refine") != NULL, "message: %s", err.msg);

  /* a 2-D group triangle whose edge 0-4 is not a mesh edge */
  static const double x[15] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 1, 1};
  static const int32_t tets[8] = {0, 1, 2, 3, 1, 2, 3, 4};
  static int32_t tri[3] = {0, 4, 1};
  bs_group g = {.dim = 2, .tag = 9, .name = "skewer", .n_elems = 1, .elems = tri};
  bs_mesh *m = NULL;
  /* a 2-D group triangle need not be a face (interior interfaces are
   * allowed), but refinement needs its edges */
  cr_assert_eq(bs_mesh_create(5, x, 2, tets, 1, &g, &m, &err), BS_OK, "%s", err.msg);
  bs_error_clear(&err);
  cr_assert_eq(bs_mesh_refine(m, &f, &err), BS_EINPUT);
  cr_assert_null(f);
  cr_assert(strstr(err.msg, "skewer") && strstr(err.msg, "0-4"), "message: %s", err.msg);
  bs_mesh_destroy(&m);
}
