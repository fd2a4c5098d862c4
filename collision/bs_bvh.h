/* bs_bvh.h — a bounding-volume hierarchy over the simplices (triangles or
 * tets) of a moving vertex array, for the self-collision queries
 * (bs_selfcollide.h).
 *
 * The topology is built from the simplices' centroids at one configuration
 * (median splits along the longest axis of the centroids' box, ties broken by
 * index: the same tree on every run and thread count); the boxes are then
 * refit to any later configuration in O(n) without changing the topology, so
 * the boxes stay exact (each the smallest box around its simplices at that
 * configuration) and only the tree's quality degrades as the shape moves away
 * from the one it was built at. Rebuild when that shape is far: bs_bvh_cost
 * measures how far (the self-collision term compares it at each time step's
 * start with its value at the last rebuild).
 *
 * Ownership: bs_bvh_init allocates the nodes and the order; the simplex array
 * `elems` stays the caller's and must outlive the hierarchy. Positions x are
 * 3 doubles per vertex (m), read only during the call.
 *
 * Usage:
 *   bs_bvh b;
 *   if (bs_bvh_init(&b, mesh->faces, 3, mesh->n_faces, &err)) return err.code;
 *   bs_bvh_build(&b, x0, nthreads);
 *   ... bs_bvh_refit(&b, x, nthreads);
 *   int64_t n = bs_bvh_within(&b, lo, hi, out, cap);  // simplices whose box meets [lo, hi]
 *   bs_bvh_free(&b);
 */
#ifndef BS_BVH_H
#define BS_BVH_H

#include <stdint.h>

#include "bs_base.h"

/* Simplices per leaf; traversal stack bound (a median split of n simplices
 * has depth log2(n / BS_BVH_LEAF) + 1, far below it for any int32 n). */
enum { BS_BVH_LEAF = 4, BS_BVH_STACK = 128 };

typedef struct bs_bvh_node {
  double lo[3], hi[3];  /* the box at the last refit                        */
  int32_t left, right;  /* children (left = -1: a leaf)                      */
  int32_t first, count; /* a leaf: the simplices order[first .. first+count) */
} bs_bvh_node;

typedef struct bs_bvh {
  const int32_t *elems; /* arity vertex indices per simplex (the caller's)   */
  int arity;            /* 3: triangles, 4: tets                             */
  int32_t n;            /* simplices                                         */
  int32_t n_nodes;      /* nodes in use (at most 2 n)                        */
  bs_bvh_node *nodes;   /* node 0 is the root; pre-order (children after)   */
  int32_t *order;       /* n: the simplices in leaf order                    */
  int32_t *leaf_elems;  /* arity n: their vertices in leaf order (simplex
                           order[j]'s at leaf_elems + arity j), so leaves
                           read one run of memory                           */
  double *leaf_box;     /* 6 n: simplex order[j]'s box at the last refit at
                           leaf_box + 6 j (lo[3], hi[3]): queries read it
                           and never the positions                          */
  struct bs_bvh_rec *rec; /* n: centroids and indices, bs_bvh_build's scratch */
} bs_bvh;

/* Allocates the hierarchy of n simplices of the given arity (3 or 4); no
 * topology until bs_bvh_build. BS_EINPUT on a bad arity or n < 0, BS_ENOMEM. */
int bs_bvh_init(bs_bvh *b, const int32_t *elems, int arity, int32_t n, bs_error *err);
void bs_bvh_free(bs_bvh *b);

/* The topology from the centroids at x (O(n log n), large subtrees as OpenMP
 * tasks on up to nthreads threads; fewer than 1 counts as 1). The nodes are in
 * pre-order (a node's left child follows it, its right child follows the left
 * subtree), a layout fixed by n alone: the same tree, node for node, on every
 * thread count. The boxes are not set: call bs_bvh_refit before a query. */
void bs_bvh_build(bs_bvh *b, const double *x, int nthreads);

/* Every box to x: each simplex's own box (leaf_box) and the leaves on up to
 * nthreads threads (less than 1 counts as 1), then the inner nodes. An infinite coordinate makes the boxes around
 * it infinite (bs_bvh_finite then says 0); a NaN coordinate is skipped by the
 * min and max, so check positions for NaN before trusting a query. */
void bs_bvh_refit(bs_bvh *b, const double *x, int nthreads);

/* The tree's cost at the last refit: the summed half surface areas of all
 * node boxes (m^2), to which the expected number of nodes a small query box
 * visits is proportional (the surface-area heuristic). It does not change
 * when the simplices move rigidly together and grows as they move apart from
 * the neighbours they were grouped with at the build; +Inf for infinite
 * boxes. One serial pass over the nodes: the same value on every thread count. */
double bs_bvh_cost(const bs_bvh *b);

/* 1 when the root's box at the last refit is finite. */
int bs_bvh_finite(const bs_bvh *b);

/* The simplices whose own box at the last refit meets the closed box [lo,
 * hi], in leaf order, written to out (up to cap of them); returns how many
 * there are (more than cap: out holds the first cap). Reads the boxes cached
 * by bs_bvh_refit (leaf_box), not the positions. */
int64_t bs_bvh_within(const bs_bvh *b, const double lo[3], const double hi[3], int32_t *out, int64_t cap);

#endif
