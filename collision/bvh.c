/* bvh.c — the bounding-volume hierarchy of bs_bvh.h: median-split build,
 * refit, box query. */
#include "bs_bvh.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Nodes below which a refit runs on one thread (a parallel region costs more). */
enum { PAR_NODES = 8192 };

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
  b->cent = bs_calloc(3 * (size_t)n + 1, sizeof(double), "a bounding-volume hierarchy", err);
  if (!b->nodes || !b->order || !b->cent) {
    bs_bvh_free(b);
    return BS_ENOMEM;
  }
  return BS_OK;
}

void bs_bvh_free(bs_bvh *b) {
  if (!b) return;
  free(b->nodes);
  free(b->order);
  free(b->cent);
  memset(b, 0, sizeof *b);
}

/* Centroid key with index tie-break, for a deterministic median split. */
static int key_less(const double *cent, int axis, int32_t a, int32_t b) {
  double ka = cent[3 * a + axis], kb = cent[3 * b + axis];
  return ka < kb || (ka == kb && a < b);
}

static void swap32(int32_t *v, int32_t i, int32_t j) {
  int32_t t = v[i];
  v[i] = v[j];
  v[j] = t;
}

/* Places the m-th smallest of v[0..n) at v[m] (quickselect, median-of-three). */
static void select_nth(int32_t *v, int32_t n, int32_t m, const double *cent, int axis) {
  int32_t lo = 0, hi = n - 1;
  while (hi > lo) {
    int32_t mid = lo + (hi - lo) / 2;
    if (key_less(cent, axis, v[mid], v[lo])) swap32(v, mid, lo);
    if (key_less(cent, axis, v[hi], v[lo])) swap32(v, hi, lo);
    if (key_less(cent, axis, v[hi], v[mid])) swap32(v, hi, mid);
    int32_t pivot = v[mid];
    int32_t i = lo, j = hi;
    while (i <= j) {
      while (key_less(cent, axis, v[i], pivot)) i++;
      while (key_less(cent, axis, pivot, v[j])) j--;
      if (i <= j) swap32(v, i++, j--);
    }
    if (m <= j) hi = j;
    else if (m >= i) lo = i;
    else return;
  }
}

static void build_node(bs_bvh *b, int32_t node, int32_t first, int32_t count) {
  bs_bvh_node *nd = &b->nodes[node];
  nd->first = first;
  nd->count = count;
  nd->left = nd->right = -1;
  if (count <= BS_BVH_LEAF) return;
  double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
  for (int32_t i = first; i < first + count; i++)
    for (int k = 0; k < 3; k++) {
      double c = b->cent[3 * b->order[i] + k];
      if (c < lo[k]) lo[k] = c;
      if (c > hi[k]) hi[k] = c;
    }
  int axis = 0;
  for (int k = 1; k < 3; k++)
    if (hi[k] - lo[k] > hi[axis] - lo[axis]) axis = k;
  int32_t half = count / 2;
  select_nth(b->order + first, count, half, b->cent, axis);
  int32_t l = b->n_nodes++, r = b->n_nodes++;
  nd->left = l;
  nd->right = r;
  build_node(b, l, first, half);
  build_node(b, r, first + half, count - half);
}

void bs_bvh_build(bs_bvh *b, const double *x) {
  const int s = b->arity;
  const double w = 1.0 / s;
  for (int32_t t = 0; t < b->n; t++) {
    const int32_t *tv = b->elems + (size_t)s * t;
    for (int k = 0; k < 3; k++) {
      double c = 0;
      for (int a = 0; a < s; a++) c += x[3 * (size_t)tv[a] + k];
      b->cent[3 * (size_t)t + k] = w * c; /* 1/4 is exact: the tets' 0.25 (x0 + x1 + x2 + x3) */
    }
    b->order[t] = t;
  }
  b->n_nodes = 1;
  build_node(b, 0, 0, b->n);
}

/* The box of simplex t at x. */
static void simplex_box(const bs_bvh *b, const double *x, int32_t t, double lo[3], double hi[3]) {
  const int32_t *tv = b->elems + (size_t)b->arity * t;
  for (int a = 0; a < b->arity; a++)
    for (int k = 0; k < 3; k++) {
      double c = x[3 * (size_t)tv[a] + k];
      lo[k] = c < lo[k] ? c : lo[k];
      hi[k] = c > hi[k] ? c : hi[k];
    }
}

/* The leaves in parallel (min and max are exact in any order), then the
 * inner nodes from the last to the first (children have larger indices than
 * their parent). */
void bs_bvh_refit(bs_bvh *b, const double *x, int nthreads) {
  const int32_t nn = b->n_nodes;
  if (nthreads < 1) nthreads = 1;
#pragma omp parallel for schedule(static) num_threads(nthreads) if (nn >= PAR_NODES)
  for (int32_t i = 0; i < nn; i++) {
    bs_bvh_node *nd = &b->nodes[i];
    if (nd->left >= 0) continue;
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (int32_t j = nd->first; j < nd->first + nd->count; j++) simplex_box(b, x, b->order[j], lo, hi);
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

int64_t bs_bvh_within(const bs_bvh *b, const double *x, const double lo[3], const double hi[3], int32_t *out,
                      int64_t cap) {
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
      const int32_t t = b->order[j];
      double tlo[3] = {INFINITY, INFINITY, INFINITY}, thi[3] = {-INFINITY, -INFINITY, -INFINITY};
      simplex_box(b, x, t, tlo, thi);
      if (!boxes_meet(tlo, thi, lo, hi)) continue;
      if (cnt < cap) out[cnt] = t;
      cnt++;
    }
  }
  return cnt;
}
