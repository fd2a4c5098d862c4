/* bvh.c — the bounding-volume hierarchy of bs_bvh.h: median-split build,
 * refit, box query. */
#include "bs_bvh.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Nodes below which a refit runs on one thread (a parallel region costs more). */
enum { PAR_NODES = 8192 };

/* A simplex's centroid and index, moved together by the build (the splits
 * read the centroids in sequence, not through the order). */
struct bs_bvh_rec {
  double c[3];
  int32_t id;
  int32_t pad;
};
typedef struct bs_bvh_rec rec_t;

int bs_bvh_init(bs_bvh *b, const int32_t *elems, int arity, int32_t n, bs_error *err) {
  memset(b, 0, sizeof *b);
  if ((arity != 3 && arity != 4) || n < 0 || (n > 0 && !elems))
    return bs_error_set(err, BS_EINPUT, "bs_bvh_init: %d simplices of arity %d (expected 3 or 4, n >= 0)", (int)n,
                        arity);
  b->elems = elems;
  b->arity = arity;
  b->n = n;
  b->nodes = bs_calloc(2 * (size_t)n + 1, sizeof(bs_bvh_node), "a bounding-volume hierarchy", err);
  b->order = bs_calloc((size_t)n + 1, sizeof(int32_t), "a bounding-volume hierarchy", err);
  b->rec = bs_calloc((size_t)n + 1, sizeof(struct bs_bvh_rec), "a bounding-volume hierarchy", err);
  b->leaf_elems = bs_calloc((size_t)arity * (size_t)n + 1, sizeof(int32_t), "a bounding-volume hierarchy", err);
  b->leaf_box = bs_calloc(6 * (size_t)n + 1, sizeof(double), "a bounding-volume hierarchy", err);
  if (!b->nodes || !b->order || !b->rec || !b->leaf_elems || !b->leaf_box) {
    bs_bvh_free(b);
    return BS_ENOMEM;
  }
  return BS_OK;
}

void bs_bvh_free(bs_bvh *b) {
  if (!b) return;
  free(b->nodes);
  free(b->order);
  free(b->rec);
  free(b->leaf_elems);
  free(b->leaf_box);
  memset(b, 0, sizeof *b);
}

/* Centroid key with index tie-break, for a deterministic median split. */
static int key_less(const rec_t *a, const rec_t *b, int axis) {
  double ka = a->c[axis], kb = b->c[axis];
  return ka < kb || (ka == kb && a->id < b->id);
}

static void swap_rec(rec_t *v, int32_t i, int32_t j) {
  rec_t t = v[i];
  v[i] = v[j];
  v[j] = t;
}

/* Places the m-th smallest of v[0..n) at v[m] (quickselect, median-of-three). */
static void select_nth(rec_t *v, int32_t n, int32_t m, int axis) {
  int32_t lo = 0, hi = n - 1;
  while (hi > lo) {
    int32_t mid = lo + (hi - lo) / 2;
    if (key_less(&v[mid], &v[lo], axis)) swap_rec(v, mid, lo);
    if (key_less(&v[hi], &v[lo], axis)) swap_rec(v, hi, lo);
    if (key_less(&v[hi], &v[mid], axis)) swap_rec(v, hi, mid);
    const rec_t pivot = v[mid];
    int32_t i = lo, j = hi;
    while (i <= j) {
      while (key_less(&v[i], &pivot, axis)) i++;
      while (key_less(&pivot, &v[j], axis)) j--;
      if (i <= j) swap_rec(v, i++, j--);
    }
    if (m <= j) hi = j;
    else if (m >= i) lo = i;
    else return;
  }
}

/* Nodes of the subtree over c simplices: 1 for a leaf, else 1 plus its two
 * halves' (c / 2 and c - c / 2). The halves of c and c + 1 are both among
 * h = c / 2 and h + 1, so (N(c), N(c + 1)) follows from (N(h), N(h + 1)):
 * O(log c). */
static void subtree_nodes(int32_t c, int64_t *nc, int64_t *nc1) {
  if (c + 1 <= BS_BVH_LEAF) {
    *nc = *nc1 = 1;
    return;
  }
  const int32_t h = c / 2;
  int64_t nh, nh1;
  subtree_nodes(h, &nh, &nh1);
  *nc = c <= BS_BVH_LEAF ? 1 : c % 2 == 0 ? 1 + 2 * nh : 1 + nh + nh1;
  *nc1 = c % 2 == 0 ? 1 + nh + nh1 : 1 + 2 * nh1;
}

/* Subtrees of at least this many simplices are built as separate tasks. */
enum { TASK_MIN = 16384 };

/* The subtree over order[first .. first+count) at `node`, in pre-order: its
 * left child at node + 1, its right child after the left subtree's nodes.
 * The layout depends on the counts only, so tasks may build the subtrees in
 * any order and the tree is the same on every thread count. */
static void build_node(bs_bvh *b, int32_t node, int32_t first, int32_t count) {
  bs_bvh_node *nd = &b->nodes[node];
  nd->first = first;
  nd->count = count;
  nd->left = nd->right = -1;
  if (count <= BS_BVH_LEAF) return;
  double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
  const rec_t *rec = b->rec;
  for (int32_t i = first; i < first + count; i++)
    for (int k = 0; k < 3; k++) {
      double c = rec[i].c[k];
      if (c < lo[k]) lo[k] = c;
      if (c > hi[k]) hi[k] = c;
    }
  int axis = 0;
  for (int k = 1; k < 3; k++)
    if (hi[k] - lo[k] > hi[axis] - lo[axis]) axis = k;
  int32_t half = count / 2;
  select_nth(b->rec + first, count, half, axis);
  int64_t nl, unused;
  subtree_nodes(half, &nl, &unused);
  const int32_t l = node + 1, r = node + 1 + (int32_t)nl;
  nd->left = l;
  nd->right = r;
  if (count >= TASK_MIN) {
#pragma omp task default(none) firstprivate(b, l, first, half)
    build_node(b, l, first, half);
    build_node(b, r, first + half, count - half);
#pragma omp taskwait
  } else {
    build_node(b, l, first, half);
    build_node(b, r, first + half, count - half);
  }
}

void bs_bvh_build(bs_bvh *b, const double *x, int nthreads) {
  const int s = b->arity;
  const double w = 1.0 / s;
  if (nthreads < 1) nthreads = 1;
#pragma omp parallel for schedule(static) num_threads(nthreads) if (b->n >= PAR_NODES)
  for (int32_t t = 0; t < b->n; t++) {
    const int32_t *tv = b->elems + (size_t)s * t;
    for (int k = 0; k < 3; k++) {
      double c = 0;
      for (int a = 0; a < s; a++) c += x[3 * (size_t)tv[a] + k];
      b->rec[t].c[k] = w * c; /* 1/4 is exact: the tets' 0.25 (x0 + x1 + x2 + x3) */
    }
    b->rec[t].id = t;
  }
  int64_t nn, unused;
  subtree_nodes(b->n, &nn, &unused);
  b->n_nodes = (int32_t)nn;
#pragma omp parallel num_threads(nthreads) if (b->n >= TASK_MIN)
#pragma omp single
  build_node(b, 0, 0, b->n);
#pragma omp parallel for schedule(static) num_threads(nthreads) if (b->n >= PAR_NODES)
  for (int32_t j = 0; j < b->n; j++) {
    const int32_t t = b->rec[j].id;
    b->order[j] = t;
    for (int a = 0; a < s; a++) b->leaf_elems[(size_t)s * j + a] = b->elems[(size_t)s * t + a];
  }
}

/* The box at x of the simplex in leaf slot j, into leaf_box[6 j ..] (lo, hi),
 * and grown around it: lo, hi. */
static void simplex_box(const bs_bvh *b, const double *x, int32_t j, double lo[3], double hi[3]) {
  const int32_t *tv = b->leaf_elems + (size_t)b->arity * j;
  double slo[3] = {INFINITY, INFINITY, INFINITY}, shi[3] = {-INFINITY, -INFINITY, -INFINITY};
  for (int a = 0; a < b->arity; a++)
    for (int k = 0; k < 3; k++) {
      double c = x[3 * (size_t)tv[a] + k];
      slo[k] = c < slo[k] ? c : slo[k];
      shi[k] = c > shi[k] ? c : shi[k];
    }
  double *box = b->leaf_box + 6 * (size_t)j;
  for (int k = 0; k < 3; k++) {
    box[k] = slo[k], box[3 + k] = shi[k];
    lo[k] = slo[k] < lo[k] ? slo[k] : lo[k];
    hi[k] = shi[k] > hi[k] ? shi[k] : hi[k];
  }
}

/* The leaves and their simplices' boxes in parallel (min and max are exact
 * in any order), then the inner nodes from the last to the first (children
 * have larger indices than their parent). */
void bs_bvh_refit(bs_bvh *b, const double *x, int nthreads) {
  const int32_t nn = b->n_nodes;
  if (nthreads < 1) nthreads = 1;
#pragma omp parallel for schedule(static) num_threads(nthreads) if (nn >= PAR_NODES)
  for (int32_t i = 0; i < nn; i++) {
    bs_bvh_node *nd = &b->nodes[i];
    if (nd->left >= 0) continue;
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (int32_t j = nd->first; j < nd->first + nd->count; j++) simplex_box(b, x, j, lo, hi);
    memcpy(nd->lo, lo, sizeof lo);
    memcpy(nd->hi, hi, sizeof hi);
  }
  for (int32_t i = nn - 1; i >= 0; i--) {
    bs_bvh_node *nd = &b->nodes[i];
    if (nd->left < 0) continue;
    const bs_bvh_node *l = &b->nodes[nd->left], *r = &b->nodes[nd->right];
    for (int k = 0; k < 3; k++) {
      nd->lo[k] = l->lo[k] < r->lo[k] ? l->lo[k] : r->lo[k];
      nd->hi[k] = l->hi[k] > r->hi[k] ? l->hi[k] : r->hi[k];
    }
  }
}

double bs_bvh_cost(const bs_bvh *b) {
  double s = 0;
  for (int32_t i = 0; i < b->n_nodes; i++) {
    const bs_bvh_node *nd = &b->nodes[i];
    const double e0 = nd->hi[0] - nd->lo[0], e1 = nd->hi[1] - nd->lo[1], e2 = nd->hi[2] - nd->lo[2];
    s += e0 * e1 + e1 * e2 + e2 * e0;
  }
  return isfinite(s) ? s : INFINITY;
}

int bs_bvh_finite(const bs_bvh *b) {
  const bs_bvh_node *root = &b->nodes[0];
  for (int k = 0; k < 3; k++)
    if (!isfinite(root->lo[k]) || !isfinite(root->hi[k])) return 0;
  return 1;
}

static int boxes_meet(const double *alo, const double *ahi, const double *blo, const double *bhi) {
  return !(alo[0] > bhi[0] || ahi[0] < blo[0] || alo[1] > bhi[1] || ahi[1] < blo[1] || alo[2] > bhi[2] ||
           ahi[2] < blo[2]);
}

int64_t bs_bvh_within(const bs_bvh *b, const double lo[3], const double hi[3], int32_t *out, int64_t cap) {
  if (b->n == 0) return 0;
  int32_t stack[BS_BVH_STACK];
  int top = 0;
  int64_t cnt = 0;
  stack[top++] = 0;
  while (top > 0) {
    const bs_bvh_node *nd = &b->nodes[stack[--top]];
    if (!boxes_meet(nd->lo, nd->hi, lo, hi)) continue;
    if (nd->left >= 0) {
      stack[top++] = nd->right;
      stack[top++] = nd->left;
      continue;
    }
    for (int32_t j = nd->first; j < nd->first + nd->count; j++) {
      const double *box = b->leaf_box + 6 * (size_t)j;
      if (!boxes_meet(box, box + 3, lo, hi)) continue;
      if (cnt < cap) out[cnt] = b->order[j];
      cnt++;
    }
  }
  return cnt;
}
