/* bs_sym3.h — the eigen-decomposition of a symmetric 3x3 matrix, shared by
 * the constitutive models (physics/material.c: the definiteness fix of the
 * dP/dF blocks) and the block-Jacobi preconditioner (solver/linsolve.c: a
 * diagonal block that is not positive definite).
 *
 * Matrices are row-major double[9]: A[3*r + c]; no units of its own. Nothing
 * allocates, prints or fails: a non-finite A gives non-finite outputs after a
 * bounded number of sweeps.
 *
 * Example:
 *   double lam[3], Q[9];
 *   bs_sym3_eig(A, lam, Q);   // A = Q diag(lam) Q^T, lam[0] >= lam[1] >= lam[2]
 *   lam[2] = fmax(lam[2], 0.0);
 *   bs_sym3_from_eig(lam, Q, A);   // A with its negative eigenvalue clamped
 */
#ifndef BS_SYM3_H
#define BS_SYM3_H

#ifdef __cplusplus
extern "C" {
#endif

/* A = Q diag(lambda) Q^T for symmetric A (only the upper triangle is read),
 * Q a rotation, lambda sorted descending. Cyclic Jacobi to machine precision:
 * eigenvalues carry an absolute error of a few ulps of max |lambda|. */
void bs_sym3_eig(const double A[9], double lambda[3], double Q[9]);

/* A = Q diag(d) Q^T (exactly symmetric; the upper triangle is computed and
 * mirrored): the matrix with bs_sym3_eig's vectors Q and new eigenvalues d,
 * e.g. clamped (a PSD projection) or inverted (a pseudo-inverse). */
void bs_sym3_from_eig(const double d[3], const double Q[9], double A[9]);

#ifdef __cplusplus
}
#endif

#endif /* BS_SYM3_H */
