/* bs_dist.h — the distributed backend's process set-up: PETSc and MPI.
 *
 * Conventions
 *  - Every function of petsc/ is collective over PETSC_COMM_WORLD unless it
 *    says otherwise, and returns BS_OK (0) or a negative BS_E* code with the
 *    bs_error filled; a PETSc error becomes BS_EINTERNAL (or the code named)
 *    with PETSc's message and the call that failed. PETSc's own error printing
 *    is replaced by a handler that returns quietly (nothing in a library
 *    prints).
 *  - bs_dist_init initializes MPI and PETSc once per process (PetscInitialize
 *    reads PETSc options from argv and PETSC_OPTIONS); bs_dist_finalize ends
 *    them. Both are safe to call more than once.
 *
 * Example
 *   bs_error err;
 *   if (bs_dist_init(&argc, &argv, &err)) { fprintf(stderr, "%s\n", err.msg); return 1; }
 *   int rank = bs_dist_rank(), size = bs_dist_size();
 *   ...
 *   bs_dist_finalize();
 */
#ifndef BS_DIST_H
#define BS_DIST_H

#include "bs_base.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Initializes MPI and PETSc (argc, argv may be NULL). */
int bs_dist_init(int *argc, char ***argv, bs_error *err);

/* Finalizes PETSc and MPI if bs_dist_init started them (no-op otherwise). */
void bs_dist_finalize(void);

/* This process's rank in, and the size of, PETSC_COMM_WORLD (0 and 1 before
 * bs_dist_init). Not collective. */
int bs_dist_rank(void);
int bs_dist_size(void);

/* Sums / maxima over the ranks, in place (n values). */
int bs_dist_sum(double *v, int n, bs_error *err);
int bs_dist_sum_i64(int64_t *v, int n, bs_error *err);
int bs_dist_max(double *v, int n, bs_error *err);

#ifdef __cplusplus
}
#endif
#endif
