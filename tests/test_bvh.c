/* The bounding-volume hierarchy (collision/bs_bvh.h): box queries against a
 * brute-force scan over every simplex, for triangles and tets, at the
 * configuration the tree was built at and after the vertices moved far
 * (refit only); the cap; a non-finite position; bad arguments; a tree large
 * enough for the parallel build's tasks is the same, node for node, on 1 and
 * 2 threads, and well formed (pre-order, every simplex in one leaf); the
 * cost keeps under a translation and grows when the vertices are shuffled. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bs_bvh.h"
#include "bs_mesh.h"

static double rnd(unsigned *s) {
  *s = *s * 1103515245u + 12345u;
  return ((*s >> 8) & 0xffff) / 65536.0;
}

static int meets(const double *x, const int32_t *e, int arity, const double lo[3], const double hi[3]) {
  for (int k = 0; k < 3; k++) {
    double a = INFINITY, b = -INFINITY;
    for (int v = 0; v < arity; v++) {
      a = fmin(a, x[3 * (size_t)e[v] + k]);
      b = fmax(b, x[3 * (size_t)e[v] + k]);
    }
    if (a > hi[k] || b < lo[k]) return 0;
  }
  return 1;
}

static int cmp_i32(const void *a, const void *b) {
  int32_t x = *(const int32_t *)a, y = *(const int32_t *)b;
  return (x > y) - (x < y);
}

/* 200 random boxes: the query's set is the brute-force set. Returns the
 * total number of hits (so that a test can check it is not trivially 0). */
static int64_t check_queries(const bs_bvh *b, const double *x, const int32_t *elems, int arity, int32_t n,
                             unsigned seed) {
  int32_t *got = malloc(sizeof(int32_t) * (size_t)n), *want = malloc(sizeof(int32_t) * (size_t)n);
  int64_t total = 0;
  for (int q = 0; q < 200; q++) {
    double c[3], lo[3], hi[3], r = 0.3 * rnd(&seed);
    for (int k = 0; k < 3; k++) c[k] = -0.2 + 1.4 * rnd(&seed), lo[k] = c[k] - r, hi[k] = c[k] + r;
    int64_t ng = bs_bvh_within(b, lo, hi, got, n), nw = 0;
    for (int32_t t = 0; t < n; t++)
      if (meets(x, elems + (size_t)arity * t, arity, lo, hi)) want[nw++] = t;
    cr_assert_eq(ng, nw, "query %d: %lld simplices, brute force %lld", q, (long long)ng, (long long)nw);
    qsort(got, (size_t)ng, sizeof(int32_t), cmp_i32);
    for (int64_t i = 0; i < ng; i++) cr_assert_eq(got[i], want[i], "query %d: hit %lld differs", q, (long long)i);
    total += ng;
  }
  free(got);
  free(want);
  return total;
}

static void run_case(int arity) {
  bs_error err;
  bs_mesh *m = NULL;
  double lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
  cr_assert_eq(bs_mesh_create_box(lo, hi, 6, 5, 4, &m, &err), BS_OK);
  const int32_t *elems = arity == 3 ? m->faces : m->tets;
  const int32_t n = arity == 3 ? m->n_faces : m->n_tets;
  bs_bvh b;
  cr_assert_eq(bs_bvh_init(&b, elems, arity, n, &err), BS_OK);
  bs_bvh_build(&b, m->x, 2);
  bs_bvh_refit(&b, m->x, 2);
  cr_assert(bs_bvh_finite(&b));
  cr_assert_gt(check_queries(&b, m->x, elems, arity, n, 7u), 200, "the queries hit almost nothing");
  /* move every vertex far (a twist and noise), refit only */
  size_t n3 = 3 * (size_t)m->n_vertices;
  double *x = malloc(n3 * sizeof(double));
  unsigned s = 3u;
  for (int32_t v = 0; v < m->n_vertices; v++) {
    const double *p = m->x + 3 * (size_t)v, a = 1.5 * p[2];
    x[3 * v] = 0.5 + cos(a) * (p[0] - 0.5) - sin(a) * (p[1] - 0.5) + 0.2 * rnd(&s);
    x[3 * v + 1] = 0.5 + sin(a) * (p[0] - 0.5) + cos(a) * (p[1] - 0.5) + 0.2 * rnd(&s);
    x[3 * v + 2] = p[2] + 0.2 * rnd(&s);
  }
  bs_bvh_refit(&b, x, 1);
  cr_assert_gt(check_queries(&b, x, elems, arity, n, 11u), 200);
  /* the cap: the count of all, the first cap written */
  double all_lo[3] = {-9, -9, -9}, all_hi[3] = {9, 9, 9};
  int32_t few[5] = {-1, -1, -1, -1, -1};
  cr_assert_eq(bs_bvh_within(&b, all_lo, all_hi, few, 4), n);
  for (int i = 0; i < 4; i++) cr_assert(few[i] >= 0 && few[i] < n);
  cr_assert_eq(few[4], -1, "wrote past the cap");
  /* a non-finite position shows in the root's box */
  x[3 * (size_t)elems[0]] = INFINITY;
  bs_bvh_refit(&b, x, 0); /* 0 threads counts as 1 */
  cr_assert_not(bs_bvh_finite(&b));
  free(x);
  bs_bvh_free(&b);
  bs_mesh_destroy(&m);
}

Test(bvh, triangles_match_brute_force_after_moving) { run_case(3); }
Test(bvh, tets_match_brute_force_after_moving) { run_case(4); }

Test(bvh, bad_arguments) {
  bs_error err;
  bs_bvh b;
  int32_t e[5] = {0, 1, 2, 3, 4};
  cr_assert_eq(bs_bvh_init(&b, e, 5, 1, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "arity 5"), "%s", err.msg);
  cr_assert_eq(bs_bvh_init(&b, NULL, 3, 2, &err), BS_EINPUT);
  cr_assert_eq(bs_bvh_init(&b, e, 3, 0, &err), BS_OK);
  double x[3] = {0, 0, 0}, lo[3] = {-1, -1, -1}, hi[3] = {1, 1, 1};
  bs_bvh_build(&b, x, 1);
  cr_assert_eq(bs_bvh_within(&b, lo, hi, NULL, 0), 0);
  bs_bvh_free(&b);
}

/* Pre-order and coverage: node i's children are i + 1 and the node after the
 * left subtree, the leaves hold order[] exactly once in leaf order, and
 * n_nodes nodes are reached. Returns the nodes of the subtree at i. */
static int32_t check_subtree(const bs_bvh *b, int32_t i, int32_t *next_first) {
  const bs_bvh_node *nd = &b->nodes[i];
  if (nd->left < 0) {
    cr_assert_eq(nd->first, *next_first, "leaf %d starts at %d, expected %d", i, nd->first, *next_first);
    cr_assert(nd->count >= 1 && nd->count <= BS_BVH_LEAF, "leaf %d holds %d", i, nd->count);
    *next_first += nd->count;
    return 1;
  }
  cr_assert_eq(nd->left, i + 1, "node %d: left child %d", i, nd->left);
  const int32_t nl = check_subtree(b, nd->left, next_first);
  cr_assert_eq(nd->right, i + 1 + nl, "node %d: right child %d after a left subtree of %d", i, nd->right, nl);
  return 1 + nl + check_subtree(b, nd->right, next_first);
}

Test(bvh, parallel_build_is_the_serial_tree) {
  bs_error err;
  bs_mesh *m = NULL;
  double lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
  cr_assert_eq(bs_mesh_create_box(lo, hi, 18, 17, 16, &m, &err), BS_OK); /* 29,376 tets: tasks */
  bs_bvh b1, b2;
  cr_assert_eq(bs_bvh_init(&b1, m->tets, 4, m->n_tets, &err), BS_OK);
  cr_assert_eq(bs_bvh_init(&b2, m->tets, 4, m->n_tets, &err), BS_OK);
  bs_bvh_build(&b1, m->x, 1);
  bs_bvh_build(&b2, m->x, 2);
  cr_assert_eq(b1.n_nodes, b2.n_nodes);
  cr_assert_eq(memcmp(b1.order, b2.order, sizeof(int32_t) * (size_t)m->n_tets), 0, "leaf order differs");
  for (int32_t i = 0; i < b1.n_nodes; i++) {
    const bs_bvh_node *p = &b1.nodes[i], *q = &b2.nodes[i];
    cr_assert(p->left == q->left && p->right == q->right && p->first == q->first && p->count == q->count,
              "node %d differs between 1 and 2 threads", i);
  }
  int32_t next_first = 0;
  cr_assert_eq(check_subtree(&b2, 0, &next_first), b2.n_nodes);
  cr_assert_eq(next_first, m->n_tets);
  int32_t *seen = calloc((size_t)m->n_tets, sizeof(int32_t));
  for (int32_t j = 0; j < m->n_tets; j++) seen[b2.order[j]]++;
  for (int32_t t = 0; t < m->n_tets; t++) cr_assert_eq(seen[t], 1, "tet %d in %d leaves", t, seen[t]);
  free(seen);
  bs_bvh_refit(&b2, m->x, 2);
  cr_assert_gt(check_queries(&b2, m->x, m->tets, 4, m->n_tets, 5u), 200);
  bs_bvh_free(&b1);
  bs_bvh_free(&b2);
  bs_mesh_destroy(&m);
}

/* bs_bvh_cost: the same after a rigid translation (the tree is as good), far
 * larger after the vertices were shuffled (every leaf box then spans about
 * the block), +Inf at an infinite coordinate. */
Test(bvh, cost_keeps_under_translation_and_grows_when_shuffled) {
  bs_error err;
  bs_mesh *m = NULL;
  double lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
  cr_assert_eq(bs_mesh_create_box(lo, hi, 8, 7, 6, &m, &err), BS_OK);
  bs_bvh b;
  cr_assert_eq(bs_bvh_init(&b, m->tets, 4, m->n_tets, &err), BS_OK);
  bs_bvh_build(&b, m->x, 1);
  bs_bvh_refit(&b, m->x, 1);
  const double c0 = bs_bvh_cost(&b);
  cr_assert(c0 > 0 && isfinite(c0), "cost %g", c0);
  const size_t n3 = 3 * (size_t)m->n_vertices;
  double *x = malloc(n3 * sizeof(double));
  for (size_t i = 0; i < n3; i++) x[i] = m->x[i] + (i % 3 == 0 ? 5.0 : i % 3 == 1 ? -3.0 : 2.0);
  bs_bvh_refit(&b, x, 2);
  cr_expect(fabs(bs_bvh_cost(&b) - c0) <= 1e-9 * c0, "translated: cost %.17g against %.17g", bs_bvh_cost(&b), c0);
  unsigned s = 5u; /* shuffle the positions among the vertices (Fisher-Yates) */
  memcpy(x, m->x, n3 * sizeof(double));
  for (int32_t v = m->n_vertices - 1; v > 0; v--) {
    int32_t u = (int32_t)(rnd(&s) * (v + 1));
    for (int k = 0; k < 3; k++) {
      double t = x[3 * (size_t)v + k];
      x[3 * (size_t)v + k] = x[3 * (size_t)u + k];
      x[3 * (size_t)u + k] = t;
    }
  }
  bs_bvh_refit(&b, x, 2);
  const double c1 = bs_bvh_cost(&b);
  cr_expect(c1 > 10 * c0, "shuffled: cost %g, built %g", c1, c0);
  cr_assert_gt(check_queries(&b, x, m->tets, 4, m->n_tets, 9u), 200);
  x[3 * (size_t)m->tets[0]] = INFINITY;
  bs_bvh_refit(&b, x, 1);
  cr_expect(isinf(bs_bvh_cost(&b)), "an infinite coordinate: cost %g", bs_bvh_cost(&b));
  free(x);
  bs_bvh_free(&b);
  bs_mesh_destroy(&m);
}
