/* bs_bsr.h — 3x3 block compressed sparse row matrices (BSR) for the Hessians
 * of bigstep: one block row and one block column per vertex, 3 dofs per vertex.
 *
 * Units: none of its own (the entries carry whatever the assembler puts in,
 * e.g. N/m for a stiffness). Vectors have 3n doubles, dof 3i+a is component a
 * of vertex i.
 *
 * Storage: full (both triangles), blocks sorted by column within each row, the
 * diagonal block always present. Each block is row-major:
 *     val[9*s + 3*a + b] = A(3i+a, 3j+b)  for slot s of block (i,j).
 * row_ptr is int32_t, so a pattern holds fewer than 2^31 blocks (checked by
 * bs_bsr_create); nnzb is int64_t for convenience in size arithmetic.
 *
 * Masks: a mask is n bytes, 1 = free vertex, 0 = constrained vertex (all three
 * dofs); NULL means all free.
 *
 * Extra blocks: a matrix may reserve room for blocks outside its pattern
 * (bs_bsr_reserve_extra), kept as a list of (i, j, block) with i != j, in
 * the order of insertion until bs_bsr_index_extra sorts it by rows;
 * duplicates are allowed and add up. They are for couplings that a
 * fixed pattern cannot foresee (self-collision: a vertex and the triangle it
 * penetrates, which need not share a tet). bs_bsr_add_block puts a block in
 * its slot when the pattern has it, else in the list; bs_bsr_zero empties the
 * list; bs_bsr_mul and bs_bsr_check include it. Code that reads val directly
 * (the block-Jacobi preconditioner: diagonal blocks only, which are always in
 * the pattern; the CHOLMOD copy: pattern blocks only, so with extras CHOLMOD
 * solves with a part of the matrix) sees the pattern's blocks only.
 *
 * Ownership: bs_bsr_create allocates the struct and its arrays; the caller owns
 * it and frees it with bs_bsr_destroy (accepts NULL, nulls the pointer). The
 * pattern (row_ptr, col, diag) never changes after creation; assemblers write
 * val (and the extra list) only.
 *
 * Status: 0 ok; BS_EINPUT for a malformed graph (index out of range, negative
 * count) or a failed check (bs_bsr_check: asymmetry, unsorted or missing
 * diagonal, the message names the block (i,j)); BS_ENUMERIC for a non-finite
 * value (named by block and entry); BS_ENOMEM when allocation fails.
 *
 * Threads: bs_bsr_mul and bs_bsr_zero use OpenMP over rows with a static
 * schedule; each output entry is computed by one thread in a fixed order, so the
 * product is bitwise independent of the thread count; the dots of the _dot
 * products are summed in the fixed order of bs_sum.h, so they are too.
 */
#ifndef BS_BSR_H
#define BS_BSR_H

#include <stdint.h>

#include "bs_base.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct bs_bsr {
  int32_t n;        /* block rows = block columns (vertices); vectors have 3n doubles     */
  int64_t nnzb;     /* stored blocks                                                       */
  int32_t *row_ptr; /* n + 1: blocks of row i are slots row_ptr[i] .. row_ptr[i+1]-1       */
  int32_t *col;     /* nnzb, sorted within each row, the diagonal always present          */
  int32_t *diag;    /* n: slot of block (i,i)                                              */
  double *val;      /* 9 * nnzb, each block row-major: val[9*s + 3*a + b] = A(3i+a, 3j+b)  */
  int64_t n_extra;   /* extra blocks stored (0 <= n_extra <= cap_extra)                    */
  int64_t cap_extra; /* room reserved by bs_bsr_reserve_extra (0: none)                    */
  int32_t *extra_ij; /* 2 * cap_extra: block e is (extra_ij[2e], extra_ij[2e+1]), i != j    */
  double *extra_val; /* 9 * cap_extra: block e row-major, as in val                        */
  int64_t n_indexed;   /* extras the row index below was built for (bs_bsr_index_extra)  */
  int32_t *extra_ptr;  /* n + 1 (with room reserved): row i's extras are extra_ptr[i] ..    */
                       /* extra_ptr[i+1]-1 of the list once indexed                         */
  int32_t *extra_perm; /* cap_extra: scratch of bs_bsr_index_extra                          */
} bs_bsr;

/* Pattern from a vertex adjacency graph in CSR (adj_ptr: n + 1 offsets, adj:
 * adj_ptr[n] neighbour indices; no self loops needed; duplicates allowed):
 * block (i,j) exists iff i == j or j in adj(i). Full (both triangles) storage:
 * pass a symmetric graph to get a symmetric pattern (the graph is not
 * symmetrized). Values start at zero. n = 0 is allowed (an empty matrix). */
int bs_bsr_create(int32_t n, const int32_t *adj_ptr, const int32_t *adj, bs_bsr **out,
                  bs_error *err);
void bs_bsr_destroy(bs_bsr **A);

/* Slot of block (i,j), -1 if absent or out of range (binary search; for setup,
 * not hot loops). */
int32_t bs_bsr_slot(const bs_bsr *A, int32_t i, int32_t j);

/* Sets every stored value to 0 (the pattern stays) and empties the extra list. */
void bs_bsr_zero(bs_bsr *A);

/* Reserves room for cap >= 0 extra blocks (replacing any earlier reservation
 * and its blocks). BS_EINPUT for a negative cap or one of 2^31 or more,
 * BS_ENOMEM. */
int bs_bsr_reserve_extra(bs_bsr *A, int64_t cap, bs_error *err);

/* Where bs_bsr_add_block put a block. */
typedef enum {
  BS_BSR_DROPPED = -1, /* nowhere: no slot and the extra list is full, or i, j out of range */
  BS_BSR_SLOT = 0,     /* added into the pattern's slot of (i, j)                          */
  BS_BSR_EXTRA = 1     /* appended to the extra list                                       */
} bs_bsr_placement;

/* "dropped", "slot", "extra"; "?" for a value outside the enum. */
const char *bs_bsr_placement_name(bs_bsr_placement p);

/* A_ij += B (row-major 3x3): into the slot of (i,j) when the pattern has it,
 * else appended to the extra list; returns which (or BS_BSR_DROPPED).
 * Sequential: one thread at a time per matrix. */
bs_bsr_placement bs_bsr_add_block(bs_bsr *A, int32_t i, int32_t j, const double B[9]);

/* Sorts the extra list by rows in place (a stable counting sort: list order
 * kept within a row; O(n + n_extra), no allocation) and indexes it, so that
 * the products add row i's extras in the thread of row i. Call it once the
 * list is complete (the minimizer does after each Hessian); adding a block
 * or bs_bsr_zero voids the index until the next call (the products then add
 * the extras serially); values may change in place. */
void bs_bsr_index_extra(bs_bsr *A);

/* y = A x. With mask (n bytes, 1 = free, 0 = constrained; NULL = all free):
 * y_i = sum over free j of A_ij x_j for free i, and y_i = 0 for constrained i.
 * x and y have 3n entries and must not overlap. OpenMP over rows; y_i gets
 * row i's extra blocks after its pattern blocks, in list order (the same
 * arithmetic whether or not the list is indexed: by row i's thread when it
 * is, else in one serial pass after the rows). */
void bs_bsr_mul(const bs_bsr *A, const uint8_t *mask, const double *x, double *y);

/* bs_bsr_mul, returning x . y over the free entries (constrained entries of x
 * are skipped, so a non-finite one does not leak in), the dot fused into the
 * product's row loop when there are no extra blocks (one pass over y, not two;
 * with extras it is a second pass, summed over the 3n entries). */
double bs_bsr_mul_dot(const bs_bsr *A, const uint8_t *mask, const double *x, double *y);

/* Single-precision values for Krylov solvers (bs_linsolve_set_single): val32
 * holds bs_bsr_val32_count(A) floats (9 per block, in bsr.c's own order, and
 * padding), owned by the caller. bs_bsr_mul_dot_round32 is bs_bsr_mul_dot (in
 * double) that also writes each stored value rounded to float into val32
 * during its pass; bs_bsr_mul_dot32 is bs_bsr_mul_dot with the pattern's
 * values read from val32 (the extra blocks stay double), accumulated in double
 * (AVX2 and FMA when the CPU has them). A value beyond FLT_MAX becomes +-inf in
 * val32, so the next bs_bsr_mul_dot32 returns a non-finite x . y: the caller
 * can tell and go back to double. */
int64_t bs_bsr_val32_count(const bs_bsr *A);
double bs_bsr_mul_dot_round32(const bs_bsr *A, const uint8_t *mask, const double *x, double *y, float *val32);
double bs_bsr_mul_dot32(const bs_bsr *A, const float *val32, const uint8_t *mask, const double *x, double *y);

/* Checker (an invariant test, not for hot loops): row_ptr monotone, columns in
 * range and strictly increasing within each row, diag[i] pointing at (i,i),
 * pattern symmetric ((i,j) stored iff (j,i) stored), values finite, and values
 * symmetric to relative tolerance: |A_ij - A_ji^T| <= tol * max|A| entrywise.
 * Extra blocks: indices in range with i != j, values finite, and the sum of
 * the extras at (i,j) equal to the transpose of the sum at (j,i) within the
 * same bound (quadratic in n_extra: extras are few).
 * Returns 0, BS_EINPUT (structure or symmetry) or BS_ENUMERIC (non-finite);
 * the message names the block (i,j) and, for values, the entry. */
int bs_bsr_check(const bs_bsr *A, double tol, bs_error *err);

#ifdef __cplusplus
}
#endif
#endif
