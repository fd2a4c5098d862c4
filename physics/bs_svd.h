/* bs_svd.h — small dense decompositions (constitutive models, contacts): the
 * signed ("inversion-aware") SVD of a 3x3 matrix, its polar decomposition,
 * and the positive semidefinite projection of a symmetric matrix of order up
 * to 12. The symmetric 3x3 eigen-decomposition, which the solver's
 * preconditioner shares, is base/'s bs_sym3_eig (bs_sym3.h, included here).
 *
 * Conventions
 *  - Matrices are row-major double[9]: A[3*r + c]. Units: whatever the input
 *    carries (F is dimensionless).
 *  - Nothing allocates, prints or fails: these are total functions (but
 *    bs_sym_psd_project's order out of range, reported -1). A
 *    non-finite F gives NaN outputs at once.
 *
 * Accuracy: bs_svd3 is a cyclic Jacobi method run to machine precision. It
 * reconstructs F to a few ulps of ||F|| and returns U, V orthogonal to a few
 * ulps, for every F: rank 0..3, repeated, zero or tiny singular values,
 * inverted, and any scale from 1e-300 to 1e300.
 */
#ifndef BS_SVD_H
#define BS_SVD_H

#include "bs_sym3.h"

#ifdef __cplusplus
extern "C" {
#endif

/* F = U diag(sigma) V^T with U, V rotations (orthogonal, det +1) and
 *   sigma[0] >= sigma[1] >= |sigma[2]|,  sign(sigma[2]) = sign(det F)
 * (the inversion convention of Irving, Teran and Fedkiw 2004: a reflection is
 * carried by the smallest singular value, never by U or V).
 *
 * Method (one-sided Jacobi, Hestenes 1958): the columns of B = F V are
 * orthogonalized by plane rotations of V, each computed from the Gram entries
 * |b_p|^2, |b_q|^2, b_p.b_q of the current columns; this is Jacobi on F^T F
 * without forming it, so small singular values keep their relative accuracy.
 * Sweeps stop when every pair satisfies |b_p.b_q| <= eps |b_p||b_q|. Columns
 * are then sorted by length, V made a rotation, U = [b0/|b0|, Gram-Schmidt
 * of b1 (or any unit vector orthogonal to u0 when b1 vanishes), u0 x u1], and
 * sigma2 = u2 . b2 carries the sign of det F. F is scaled by a power of two
 * first (exact), so no step under- or overflows. F = 0 gives U = V = I. */
void bs_svd3(const double F[9], double U[9], double sigma[3], double V[9]);

/* bs_svd3 on n matrices: F, U, V are 9 doubles per matrix, sigma 3, packed
 * (matrix i at F + 9 i). Results are bit for bit those of bs_svd3 on each
 * matrix. On a CPU with AVX2 the work is done 4 matrices at a time in the
 * lanes of AVX2 registers (branch-free selects; a sweep runs while any of the
 * 4 still rotates, about 3 times faster than bs_svd3; bench/README.md);
 * elsewhere it is bs_svd3 on each matrix. */
void bs_svd3_batch(int n, const double *F, double *U, double *sigma, double *V);

/* The rotation R of the polar decomposition F = R S (S symmetric positive
 * definite) when det F > 0: the rotation closest to F, which for det F > 0 is
 * U V^T of bs_svd3. Returns 1 with R written, or 0 (R untouched) when F is
 * not in the range this method is for, and the caller takes bs_svd3:
 * non-finite, ||F||^2 outside [1e-30, 1e30], det F <= 1e-9 ||F||^3 (inverted,
 * or flattened to below ~3e-9, or stretched beyond ~3e4 times in one
 * direction), or no convergence in 20 steps.
 *
 * Method: Newton's iteration X <- (g X + X^-T / g) / 2 from X = F (Higham
 * 1986; X^-T is cof(X) / det X), scaled by g = (||X^-1|| / ||X||)^(1/2)
 * (Frobenius norms) until a step is below 0.1, unscaled (g = 1) after that.
 * It stops at the first iterate with ||X_new - X|| <= 1e-8 ||R||: convergence
 * is quadratic, so that iterate is R to rounding. Near rest this takes 2 to 4
 * steps of one cofactor matrix and one division each, a fraction of bs_svd3. */
int bs_polar3(const double F[9], double R[9]);

/* bs_polar3 on n matrices (packed, 9 doubles each); ok[i] is its return
 * value for matrix i. Bit for bit bs_polar3's results; on a CPU with AVX2, 4
 * matrices at a time in the lanes of AVX2 registers. */
void bs_polar3_batch(int n, const double *F, double *R, int *ok);

/* Projects the m x m matrix H (row-major, 1 <= m <= 12; its symmetric part
 * is used) onto the positive semidefinite cone in place: V diag(max(lambda,
 * 0)) V^T from its eigen-decomposition (cyclic Jacobi, sym_psd.c), exactly
 * symmetric. Returns the number of negative eigenvalues (those below -1e-12
 * times the largest in magnitude: rounding of a zero eigenvalue does not
 * count); with none, H is left untouched (bit for bit). -1 for m out of
 * range. Used for the self-collision contacts' Hessians (6x6 to 12x12). */
int bs_sym_psd_project(int m, double *H);

#ifdef __cplusplus
}
#endif
#endif
