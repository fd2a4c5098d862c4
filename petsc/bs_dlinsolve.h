/* bs_dlinsolve.h — the Newton system H d = r on a distributed mesh: the CG
 * of bs_linsolve.h (from zero, ||r - H d|| <= rel ||r||, the exit on
 * negative curvature with the last iterate or r itself on the first
 * iteration, the last downhill iterate with kappa > 0), written on PETSc
 * vectors over bs_dfem's matrix, with a preconditioner:
 *   BS_DPC_NONE    plain CG (the serial "cg");
 *   BS_DPC_BJACOBI 3x3 point-block Jacobi of H, each owned diagonal block
 *                  inverted as the serial "pcg" does (bs_linsolve_block_inverse:
 *                  a block that is not SPD, e.g. left singular in the normal
 *                  of an active constraint, gets the pseudo-inverse of its
 *                  absolute value, where PETSc's PCPBJACOBI would divide by
 *                  a zero pivot);
 *   BS_DPC_GAMG    one PCGAMG cycle built from a symmetric positive definite
 *                  matrix P (bs_dlin_setup) with the rigid-body near-null
 *                  space of the rest positions (MatNullSpaceCreateRigidBody),
 *                  reused across solves until the next setup.
 * The loop is ours, not KSPCG (PETSc 3.18's KSPCG does not stop on negative
 * curvature at its first iteration), so the iterates are the serial CG's up
 * to rounding.
 *
 * Vectors are bs_dfem local vectors (consistent). Collective. Ownership: the
 * solver borrows the dfem (and its matrix); bs_dlin_destroy frees the rest.
 * Status: BS_OK, BS_ENUMERIC (a non-finite product or preconditioner, naming
 * the iteration), BS_EINTERNAL (PETSc).
 */
#ifndef BS_DLINSOLVE_H
#define BS_DLINSOLVE_H

#include "bs_dfem.h"
#include "bs_linsolve.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum { BS_DPC_NONE = 0, BS_DPC_BJACOBI, BS_DPC_GAMG } bs_dpc;

typedef struct bs_dlin bs_dlin;

int bs_dlin_create(bs_dfem *df, bs_dpc pc, bs_dlin **out, bs_error *err);
void bs_dlin_destroy(bs_dlin **s);

/* GAMG: builds the hierarchy from P (copied structure, SPD on the free dofs). */
int bs_dlin_setup(bs_dlin *s, Mat P, bs_error *err);
/* 1 when a GAMG hierarchy is ready (always 1 for the other kinds). */
int bs_dlin_ready(const bs_dlin *s);

/* d = H^-1 r by CG on df->H (r masked: zero on fixed vertices, whose rows
 * df->H holds as identity; mask, per local vertex, 1 free / 0 fixed, NULL:
 * all free; the preconditioned residual is masked too, so d is 0 there). */
int bs_dlin_solve(bs_dlin *s, const uint8_t *mask, const double *r, double rel, int max_it, double kappa, double *d, bs_lin_stats *st,
                  bs_error *err);

/* GAMG setup figures of the last bs_dlin_setup: levels, seconds. */
void bs_dlin_info(const bs_dlin *s, int *levels, double *setup_seconds);

#ifdef __cplusplus
}
#endif
#endif
