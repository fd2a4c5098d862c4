/* bs_amg.h — one V-cycle of hypre's BoomerAMG as a preconditioner, built from
 * a 3x3 block CSR matrix (bs_bsr) on the free dofs of a mask.
 *
 * Settings (tuned for 3-D elasticity; measurements in bench/README.md):
 * systems AMG with 3 functions per node (dofs interleaved, dof 3i+a is
 * function a) and nodal coarsening (the block row-sum norm,
 * HYPRE_BoomerAMGSetNodal 4, nodal diagonal 1), HMIS coarsening, one level of
 * aggressive coarsening, extended+i interpolation with at most 4 entries per
 * row (P_max 4), strength threshold 0.5, hypre's default smoothers (hybrid
 * Gauss-Seidel forward down, backward up: a symmetric cycle) and a direct
 * solve on the coarsest level. One V-cycle from a zero guess per apply: z = B
 * r with B symmetric positive definite when the matrix it was built from is.
 *
 * The matrix P given to bs_amg_setup must be symmetric positive definite on
 * the free dofs (e.g. a rest-state stiffness plus M/dt^2, or a PSD-projected
 * Hessian plus M/dt^2): built from an indefinite matrix the cycle may fail or
 * give an ascent direction. Constrained dofs (mask 0) are removed: the AMG
 * sees only the free dofs, in vertex order.
 *
 * MPI: hypre is MPI-based. The first bs_amg_create initializes MPI when the
 * program has not (a singleton: one process, no mpirun; finalized at exit) and
 * calls HYPRE_Init; everything runs on MPI_COMM_SELF, one process.
 * hypre here is built without OpenMP: setup and cycles are single-threaded.
 *
 * Ownership: bs_amg_create allocates; bs_amg_destroy (accepts NULL, nulls)
 * frees it and its hypre objects. bs_amg_setup copies what it needs from P and
 * the mask (they may change or be freed after). Not thread-safe.
 *
 * Status: 0 ok; BS_EINPUT (NULL argument, a pattern size different from the
 * setup's in apply), BS_ENUMERIC (a non-finite free entry of P, named; a
 * matrix with no free dof is fine: apply gives 0), BS_ENOMEM, BS_EINTERNAL
 * (MPI or hypre reported an error: its code is named).
 */
#ifndef BS_AMG_H
#define BS_AMG_H

#include <stdint.h>

#include "bs_base.h"
#include "bs_bsr.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct bs_amg bs_amg;

typedef struct bs_amg_info {
  int setups;           /* bs_amg_setup calls that succeeded                    */
  int64_t free_dofs;    /* rows of the last hierarchy's finest level            */
  double setup_seconds; /* wall time of the last setup (matrix copy included)   */
} bs_amg_info;

int bs_amg_create(bs_amg **out, bs_error *err);
void bs_amg_destroy(bs_amg **amg);

/* Builds the hierarchy from P restricted to the free dofs of mask (NULL: all
 * free), replacing any earlier one. Only P's pattern blocks are read (its
 * extra list, if any, is ignored). */
int bs_amg_setup(bs_amg *amg, const bs_bsr *P, const uint8_t *mask, bs_error *err);

/* 1 once a setup has succeeded. */
int bs_amg_ready(const bs_amg *amg);
/* 1 if mask (NULL: all free) selects the same free vertices, out of n, as the
 * last setup's. */
int bs_amg_same_mask(const bs_amg *amg, int32_t n, const uint8_t *mask);

/* z = B r: one V-cycle from zero on the free dofs of the last setup; z is 0 on
 * the constrained dofs. r and z have 3n entries (n of the setup's matrix) and
 * must not overlap. Returns r . z through *rz when rz is not NULL. */
int bs_amg_apply(bs_amg *amg, const double *r, double *z, double *rz, bs_error *err);

void bs_amg_get_info(const bs_amg *amg, bs_amg_info *info);

#ifdef __cplusplus
}
#endif
#endif
