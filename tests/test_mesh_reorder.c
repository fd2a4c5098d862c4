/* Vertex reordering: explicit permutations, METIS nested dissection and
 * reverse Cuthill-McKee; bandwidth/profile and Cholesky fill as measures. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bs_mesh.h"

static bs_mesh *box(int n) {
  const double lo[3] = {0, 0, 0}, hi[3] = {1.0, 2.0, 0.5};
  bs_mesh *m = NULL;
  bs_error err = {0};
  cr_assert_eq(bs_mesh_create_box(lo, hi, n, n, n, &m, &err), BS_OK, "box: %s", err.msg);
  return m;
}

static bs_mesh *copy(const bs_mesh *m) {
  bs_mesh *c = NULL;
  bs_error err = {0};
  cr_assert_eq(bs_mesh_copy(m, &c, &err), BS_OK, "copy: %s", err.msg);
  return c;
}

/* Deterministic Fisher-Yates shuffle (64-bit LCG, fixed seed). */
static void shuffle(int32_t *p, int32_t n, uint64_t seed) {
  for (int32_t i = 0; i < n; i++) p[i] = i;
  for (int32_t i = n - 1; i > 0; i--) {
    seed = seed * 6364136223846793005ULL + 1442695040888963407ULL;
    int32_t j = (int32_t)((seed >> 33) % (uint64_t)(i + 1));
    int32_t t = p[i];
    p[i] = p[j];
    p[j] = t;
  }
}

static bs_mesh *shuffled_box(int n) {
  bs_mesh *m = box(n);
  int32_t *p = malloc(sizeof(int32_t) * (size_t)m->n_vertices);
  shuffle(p, m->n_vertices, 12345);
  bs_error err = {0};
  cr_assert_eq(bs_mesh_permute(m, p, &err), BS_OK, "permute: %s", err.msg);
  free(p);
  return m;
}

/* Off-diagonal nonzeros of the Cholesky factor of the vertex graph's
 * pattern in the current numbering (elimination tree row counts). */
static int64_t cholesky_fill(const bs_mesh *m) {
  int32_t *ptr = NULL, *adj = NULL;
  bs_error err = {0};
  cr_assert_eq(bs_mesh_vertex_graph(m, &ptr, &adj, &err), BS_OK, "%s", err.msg);
  int32_t n = m->n_vertices;
  int32_t *parent = malloc(sizeof(int32_t) * (size_t)n), *flag = malloc(sizeof(int32_t) * (size_t)n);
  int64_t nnz = 0;
  for (int32_t i = 0; i < n; i++) {
    parent[i] = -1;
    flag[i] = i;
    for (int32_t p = ptr[i]; p < ptr[i + 1]; p++) {
      int32_t j = adj[p];
      if (j >= i) continue;
      for (; flag[j] != i; j = parent[j]) { /* walk up the elimination tree */
        if (parent[j] == -1) parent[j] = i;
        nnz++;
        flag[j] = i;
      }
    }
  }
  free(parent);
  free(flag);
  free(ptr);
  free(adj);
  return nnz;
}

static void assert_permutation(const int32_t *p, int32_t n) {
  char *seen = calloc((size_t)n, 1);
  for (int32_t i = 0; i < n; i++) {
    cr_assert(p[i] >= 0 && p[i] < n, "perm[%d] = %d out of range", i, p[i]);
    cr_assert(!seen[p[i]], "vertex %d appears twice", p[i]);
    seen[p[i]] = 1;
  }
  free(seen);
}

/* What every renumbering must keep: geometry, groups, boundary ids, the
 * checker; and what it must establish: tets sorted by smallest vertex. */
static void assert_renumbered(const bs_mesh *before, const bs_mesh *after, const int32_t *perm) {
  bs_error err = {0};
  cr_assert_eq(bs_mesh_check(after, &err), BS_OK, "check: %s", err.msg);
  cr_assert_eq(after->n_vertices, before->n_vertices);
  cr_assert_eq(after->n_tets, before->n_tets);
  cr_assert_eq(after->n_faces, before->n_faces);
  cr_assert_eq(after->n_edges, before->n_edges);
  assert_permutation(perm, after->n_vertices);
  for (int32_t i = 0; i < after->n_vertices; i++)
    cr_assert(memcmp(after->x + 3 * i, before->x + 3 * perm[i], 3 * sizeof(double)) == 0,
              "new vertex %d is not old vertex %d", i, perm[i]);
  double vb = bs_mesh_volume(before), va = bs_mesh_volume(after);
  cr_assert(fabs(va - vb) <= 1e-12 * vb, "volume %.17g -> %.17g", vb, va);
  for (int32_t t = 0; t < after->n_tets; t++)
    cr_assert(bs_mesh_tet_volume(after, after->x, t) > 0, "tet %d not positive", t);
  /* tets sorted by their smallest vertex */
  int32_t prev = -1;
  for (int32_t t = 0; t < after->n_tets; t++) {
    const int32_t *v = after->tets + 4 * t;
    int32_t lo = v[0];
    for (int k = 1; k < 4; k++) lo = v[k] < lo ? v[k] : lo;
    cr_assert(lo >= prev, "tet %d (smallest vertex %d) after one with %d", t, lo, prev);
    prev = lo;
  }
  cr_assert_eq(after->n_groups, before->n_groups);
  for (int g = 0; g < before->n_groups; g++) {
    const bs_group *gb = &before->groups[g];
    const bs_group *ga = bs_mesh_group_by_tag(after, gb->dim, gb->tag);
    cr_assert_not_null(ga);
    cr_assert_eq(ga->n_elems, gb->n_elems, "group %s", gb->name);
    cr_assert_eq(ga->n_vertices, gb->n_vertices, "group %s: %d vertices, had %d", gb->name, ga->n_vertices,
                 gb->n_vertices);
    for (int32_t i = 0; i < ga->n_vertices; i++) {
      cr_assert(i == 0 || ga->vertices[i] > ga->vertices[i - 1], "group %s vertices not sorted", ga->name);
      /* the same points: new vertex v is old perm[v] */
      int32_t old = perm[ga->vertices[i]];
      int found = 0;
      int32_t lo = 0, hi = gb->n_vertices;
      while (lo < hi) {
        int32_t mid = (lo + hi) / 2;
        if (gb->vertices[mid] < old) lo = mid + 1;
        else hi = mid;
      }
      found = lo < gb->n_vertices && gb->vertices[lo] == old;
      cr_assert(found, "group %s: vertex %d (old %d) was not in the group", ga->name, ga->vertices[i], old);
    }
    if (ga->dim == 3)
      for (int32_t i = 1; i < ga->n_elems; i++) cr_assert(ga->elems[i] > ga->elems[i - 1], "group %s tets unsorted", ga->name);
  }
  /* boundary ids: the same number of faces per id */
  for (int tag = 0; tag <= 6; tag++) {
    int32_t nb = 0, na = 0;
    for (int32_t i = 0; i < before->n_faces; i++) nb += before->boundary[i] == tag;
    for (int32_t i = 0; i < after->n_faces; i++) na += after->boundary[i] == tag;
    cr_assert_eq(na, nb, "boundary id %d: %d faces, had %d", tag, na, nb);
  }
}

Test(reorder, bandwidth_of_one_tet) {
  static const double x[12] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
  static const int32_t tet[4] = {0, 1, 2, 3};
  bs_mesh *m = NULL;
  bs_error err = {0};
  cr_assert_eq(bs_mesh_create(4, x, 1, tet, 0, NULL, &m, &err), BS_OK, "%s", err.msg);
  int64_t bw = -1, prof = -1;
  bs_mesh_bandwidth(m, &bw, &prof);
  cr_assert_eq(bw, 3);
  cr_assert_eq(prof, 0 + 1 + 2 + 3);
  bs_mesh_destroy(&m);
}

Test(reorder, permute_moves_everything) {
  bs_mesh *a = box(4);
  bs_mesh *b = copy(a);
  int32_t *p = malloc(sizeof(int32_t) * (size_t)a->n_vertices);
  shuffle(p, a->n_vertices, 99);
  bs_error err = {0};
  cr_assert_eq(bs_mesh_permute(b, p, &err), BS_OK, "%s", err.msg);
  assert_renumbered(a, b, p);
  /* each boundary face of the permuted mesh is an old one, renamed */
  for (int32_t i = 0; i < b->n_faces; i++) {
    const int32_t *fb = b->faces + 3 * i;
    int found = 0;
    for (int32_t j = 0; j < a->n_faces && !found; j++) {
      const int32_t *fa = a->faces + 3 * j;
      for (int r = 0; r < 3 && !found; r++) /* same cyclic order: same orientation */
        found = fa[0] == p[fb[r]] && fa[1] == p[fb[(r + 1) % 3]] && fa[2] == p[fb[(r + 2) % 3]] &&
                a->boundary[j] == b->boundary[i];
    }
    cr_assert(found, "face %d (%d %d %d) has no counterpart", i, fb[0], fb[1], fb[2]);
  }
  free(p);
  bs_mesh_destroy(&a);
  bs_mesh_destroy(&b);
}

Test(reorder, rcm_on_a_box) {
  bs_mesh *s = shuffled_box(10);
  bs_mesh *m = copy(s);
  int64_t bw0, prof0, bw1, prof1;
  bs_mesh_bandwidth(s, &bw0, &prof0);
  int32_t *perm = malloc(sizeof(int32_t) * (size_t)m->n_vertices);
  bs_error err = {0};
  cr_assert_eq(bs_mesh_reorder(m, BS_ORDER_RCM, perm, &err), BS_OK, "%s", err.msg);
  assert_renumbered(s, m, perm);
  bs_mesh_bandwidth(m, &bw1, &prof1);
  cr_log_info("RCM on a 10^3 box: bandwidth %lld -> %lld, profile %lld -> %lld", (long long)bw0, (long long)bw1,
              (long long)prof0, (long long)prof1);
  cr_assert(bw1 * 5 <= bw0, "bandwidth %lld -> %lld: less than a 5x reduction", (long long)bw0, (long long)bw1);
  cr_assert(prof1 * 5 <= prof0, "profile %lld -> %lld: less than a 5x reduction", (long long)prof0,
            (long long)prof1);
  /* a level-set order of an 11x11x11 grid cannot be narrower than about one
   * diagonal slab: the bandwidth is of the order of n^2, not n^3 */
  cr_assert(bw1 < 4 * 121, "RCM bandwidth %lld", (long long)bw1);
  /* deterministic */
  bs_mesh *m2 = copy(s);
  int32_t *perm2 = malloc(sizeof(int32_t) * (size_t)m->n_vertices);
  cr_assert_eq(bs_mesh_reorder(m2, BS_ORDER_RCM, perm2, &err), BS_OK, "%s", err.msg);
  cr_assert(memcmp(perm, perm2, sizeof(int32_t) * (size_t)m->n_vertices) == 0);
  free(perm);
  free(perm2);
  bs_mesh_destroy(&m);
  bs_mesh_destroy(&m2);
  bs_mesh_destroy(&s);
}

Test(reorder, metis_on_a_box) {
  bs_mesh *s = shuffled_box(10);
  bs_mesh *m = copy(s);
  int64_t bw0, prof0, bw1, prof1;
  bs_mesh_bandwidth(s, &bw0, &prof0);
  int32_t *perm = malloc(sizeof(int32_t) * (size_t)m->n_vertices);
  bs_error err = {0};
  cr_assert_eq(bs_mesh_reorder(m, BS_ORDER_METIS, perm, &err), BS_OK, "%s", err.msg);
  assert_renumbered(s, m, perm);
  bs_mesh_bandwidth(m, &bw1, &prof1);
  int64_t fill0 = cholesky_fill(s), fill1 = cholesky_fill(m);

  /* RCM for comparison */
  bs_mesh *r = copy(s);
  cr_assert_eq(bs_mesh_reorder(r, BS_ORDER_RCM, NULL, &err), BS_OK, "%s", err.msg);
  int64_t fill_rcm = cholesky_fill(r);

  /* METIS's inverse permutation, applied instead: what using iperm for perm
   * would give */
  int32_t *inv = malloc(sizeof(int32_t) * (size_t)m->n_vertices);
  for (int32_t i = 0; i < m->n_vertices; i++) inv[perm[i]] = i;
  bs_mesh *w = copy(s);
  cr_assert_eq(bs_mesh_permute(w, inv, &err), BS_OK, "%s", err.msg);
  int64_t fill_wrong = cholesky_fill(w);

  cr_log_info("METIS on a 10^3 box: bandwidth %lld -> %lld, profile %lld -> %lld, fill %lld -> %lld "
              "(RCM %lld, inverse perm %lld)",
              (long long)bw0, (long long)bw1, (long long)prof0, (long long)prof1, (long long)fill0, (long long)fill1,
              (long long)fill_rcm, (long long)fill_wrong);
  /* No bandwidth claim: nested dissection numbers the top separator last,
   * and it touches vertices numbered first, so the bandwidth stays ~n (a
   * shuffled box: 1320; METIS: ~1325). Profile and fill are what it cuts. */
  cr_assert(prof1 * 3 <= prof0, "profile %lld -> %lld", (long long)prof0, (long long)prof1);
  /* nested dissection is a fill-reducing order: far less fill than a random
   * numbering, less than RCM, and the direction matters */
  cr_assert(fill1 * 3 <= fill0, "fill %lld -> %lld", (long long)fill0, (long long)fill1);
  cr_assert(fill1 < fill_rcm, "METIS fill %lld, RCM %lld", (long long)fill1, (long long)fill_rcm);
  cr_assert(fill1 * 2 <= fill_wrong, "METIS fill %lld, with the inverse permutation %lld", (long long)fill1,
            (long long)fill_wrong);
  free(perm);
  free(inv);
  bs_mesh_destroy(&m);
  bs_mesh_destroy(&r);
  bs_mesh_destroy(&w);
  bs_mesh_destroy(&s);
}

Test(reorder, rcm_two_components) {
  /* two separate tets, interleaved numbering: RCM numbers each component
   * contiguously */
  static const double x[24] = {0, 0, 0, 5, 0, 0, 1, 0, 0, 6, 0, 0, 0, 1, 0, 5, 1, 0, 0, 0, 1, 5, 0, 1};
  static const int32_t tets[8] = {0, 2, 4, 6, 1, 3, 5, 7};
  bs_mesh *m = NULL;
  bs_error err = {0};
  cr_assert_eq(bs_mesh_create(8, x, 2, tets, 0, NULL, &m, &err), BS_OK, "%s", err.msg);
  bs_mesh *before = copy(m);
  int32_t perm[8];
  cr_assert_eq(bs_mesh_reorder(m, BS_ORDER_RCM, perm, &err), BS_OK, "%s", err.msg);
  assert_renumbered(before, m, perm);
  for (int i = 0; i < 4; i++) cr_assert_eq(perm[i] % 2, perm[0] % 2, "perm[%d] = %d mixes components", i, perm[i]);
  int64_t bw;
  bs_mesh_bandwidth(m, &bw, NULL);
  cr_assert_eq(bw, 3);
  bs_mesh_destroy(&m);
  bs_mesh_destroy(&before);
}

Test(reorder, none_is_identity) {
  bs_mesh *m = box(3);
  bs_mesh *c = copy(m);
  int32_t *perm = malloc(sizeof(int32_t) * (size_t)m->n_vertices);
  bs_error err = {0};
  cr_assert_eq(bs_mesh_reorder(m, BS_ORDER_NONE, perm, &err), BS_OK, "%s", err.msg);
  for (int32_t i = 0; i < m->n_vertices; i++) cr_assert_eq(perm[i], i);
  cr_assert(memcmp(m->tets, c->tets, sizeof(int32_t) * 4 * (size_t)m->n_tets) == 0);
  free(perm);
  bs_mesh_destroy(&m);
  bs_mesh_destroy(&c);
}

Test(reorder, refined_then_reordered) {
  bs_mesh *c = box(3);
  bs_mesh *f = NULL;
  bs_error err = {0};
  cr_assert_eq(bs_mesh_refine(c, &f, &err), BS_OK, "%s", err.msg);
  bs_mesh *before = copy(f);
  int32_t *perm = malloc(sizeof(int32_t) * (size_t)f->n_vertices);
  cr_assert_eq(bs_mesh_reorder(f, BS_ORDER_METIS, perm, &err), BS_OK, "%s", err.msg);
  assert_renumbered(before, f, perm);
  free(perm);
  bs_mesh_destroy(&before);
  bs_mesh_destroy(&f);
  bs_mesh_destroy(&c);
}

Test(reorder, errors) {
  bs_mesh *m = box(2);
  bs_mesh *c = copy(m);
  int32_t n = m->n_vertices;
  int32_t *p = malloc(sizeof(int32_t) * (size_t)n);
  bs_error err = {0};
  for (int32_t i = 0; i < n; i++) p[i] = i;
  p[5] = 7; /* 7 twice, 5 missing */
  cr_assert_eq(bs_mesh_permute(m, p, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "vertex 7") != NULL, "message: %s", err.msg);
  p[5] = n + 3;
  cr_assert_eq(bs_mesh_permute(m, p, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "perm[5]") != NULL, "message: %s", err.msg);
  /* a refused permutation leaves the mesh untouched */
  cr_assert(memcmp(m->x, c->x, sizeof(double) * 3 * (size_t)n) == 0);
  cr_assert(memcmp(m->tets, c->tets, sizeof(int32_t) * 4 * (size_t)m->n_tets) == 0);
  cr_assert_eq(bs_mesh_permute(m, NULL, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "perm") != NULL, "message: %s", err.msg);
  cr_assert_eq(bs_mesh_reorder(m, (bs_order)7, NULL, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "7") != NULL, "message: %s", err.msg);
  cr_assert_eq(bs_mesh_reorder(NULL, BS_ORDER_RCM, NULL, &err), BS_EINPUT);
  free(p);
  bs_mesh_destroy(&m);
  bs_mesh_destroy(&c);
}
