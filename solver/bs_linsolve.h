/* bs_linsolve.h — linear solvers on bs_bsr matrices: conjugate gradient (CG),
 * block-Jacobi preconditioned CG (PCG), CG preconditioned by one BoomerAMG
 * V-cycle (AMG, bs_amg.h), MINRES (Paige–Saunders) and CHOLMOD's supernodal
 * Cholesky.
 *
 * Units: x has the units of b divided by those of A; tolerances are relative.
 *
 * Masks: n bytes, 1 = free vertex, 0 = constrained (all three dofs); NULL means
 * all free. The solvers act on the free dofs only: A restricted to the free
 * rows and columns, b restricted to the free entries; constrained entries of x
 * are set to 0 on return (except when CHOLMOD reports not_pd: x is untouched).
 * All norms are masked 2-norms.
 *
 * CG/PCG and negative curvature (paper, section 3.1): the Newton system of a
 * nonconvex energy may be indefinite. CG starts from x = 0; if a search
 * direction p has p^T A p <= 0, it stops, returns the last iterate and sets
 * stats.indefinite = 1. On the very first iteration (no iterate yet) it returns
 * x = b, the right-hand side (for the Newton system H dx = -g this is the
 * steepest-descent direction). Every CG iterate x_k (k >= 1) satisfies
 * b^T x_k > 0, so the result is a descent direction of the quadratic
 * 1/2 x^T A x - b^T x at 0 (and of E when b = -grad E).
 * PCG preconditioner: block Jacobi with the inverse of each free 3x3 diagonal
 * block. A diagonal block that is not clearly symmetric positive definite
 * (Cholesky of its symmetric part meets a pivot <= 1e-6 times its largest
 * diagonal magnitude: a smaller pivot can be rounding) gets Q diag(1/|lambda|)
 * Q^T from the eigen-decomposition of its symmetric part (bs_sym3_eig),
 * eigenvalues at or below 1e-12 of the largest |lambda| left out: a definite
 * block gets its inverse, an indefinite block (contacts) keeps its scale, and
 * a vertex on a constraint obstacle, whose block has a zero row and column
 * along the normal (bs_obstacles.h: the Hessian on the tangent space; the
 * residual is zero there too), is preconditioned in its tangent plane only.
 * A zero or non-finite block gets the identity. So
 * M^-1 is positive semidefinite (definite wherever the block is nonsingular)
 * and PCG's early exit keeps the same meaning.
 *
 * AMG: the same PCG (same negative-curvature exit) with z = B r, B one V-cycle
 * of a BoomerAMG hierarchy built by bs_linsolve_amg_setup from a matrix P the
 * caller chooses, which must be SPD on the free dofs (not necessarily A: e.g.
 * a rest-state stiffness plus M/dt^2 while A is the true Hessian). The
 * hierarchy is kept and reused by every solve until the next setup. A solve
 * whose mask differs from the hierarchy's (or before any setup) first sets up
 * from A itself, which must then be SPD. If B turns out not positive definite
 * (r.Br <= 0: P was not SPD), the solve stops with stats.precond_failed = 1 and
 * returns its last iterate (b when there is none), which is still a descent
 * direction of the quadratic.
 *
 * MINRES: for symmetric (possibly indefinite, nonsingular) A; iterates until
 * ||b - A x|| <= rel_tol ||b|| (recomputed explicitly at exit) or max_iter.
 *
 * CHOLMOD: the scalar lower-triangular CSC pattern of the free dofs (3x3 blocks
 * expanded, constrained dofs removed) and the symbolic analysis (ordering,
 * supernodes) are built once per mask and reused; a call with a different mask
 * from the previous one redoes them (this allocates). The numeric
 * factorization runs per call (allocation only inside CHOLMOD). If CHOLMOD
 * reports "not positive definite", stats.not_pd = 1, status 0, x untouched:
 * the caller falls back to CG. rel_tol and max_iter are ignored.
 *
 * Ownership: bs_linsolve_create sizes all workspace for the pattern it is
 * given (the pattern's arrays are copied or referenced only during create; any
 * bs_bsr with the same pattern may be passed to solve). The caller owns the
 * workspace and frees it with bs_linsolve_destroy (accepts NULL, nulls).
 * A workspace is not thread-safe: one solve at a time (each solve is itself
 * parallel through OpenMP).
 *
 * Threads: results are bitwise the same with any number of OpenMP threads
 * (iterates, iteration counts, exits): every inner product and norm is summed
 * in the fixed order of bs_sum.h. CHOLMOD's solve sets OpenBLAS (when it is
 * the BLAS) to one thread for its duration and puts the count back after,
 * since OpenBLAS's kernels change their last bits with its thread count; a
 * process that calls OpenBLAS from another thread at the same time sees that
 * setting. hypre's BoomerAMG here is serial.
 *
 * Status: 0 when the solver ran (converged or not: see stats.converged,
 * stats.indefinite, stats.not_pd); BS_ENUMERIC when b or A holds a NaN/Inf in
 * a free entry (the message names the entry or block), or a breakdown produces
 * one; BS_EINPUT for a bad argument (unknown kind name, a matrix whose pattern
 * differs in size from the workspace's, rel_tol < 0); BS_ENOMEM; BS_EINTERNAL
 * if CHOLMOD fails for another reason (its status is named).
 */
#ifndef BS_LINSOLVE_H
#define BS_LINSOLVE_H

#include <stdint.h>

#include "bs_amg.h"
#include "bs_base.h"
#include "bs_bsr.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum { BS_LIN_CG = 0, BS_LIN_PCG, BS_LIN_CHOLMOD, BS_LIN_MINRES, BS_LIN_AMG } bs_lin_kind;
#define BS_LIN_KINDS (BS_LIN_AMG + 1) /* number of kinds */

/* "cg", "pcg", "cholmod", "minres", "amg" (exact, lower case); BS_EINPUT naming the
 * string otherwise. */
int bs_lin_kind_parse(const char *name, bs_lin_kind *out, bs_error *err);
/* The name parsed above, or "unknown". */
const char *bs_lin_kind_name(bs_lin_kind k);

/* The PCG preconditioner's block (above) for one 3x3 diagonal block D
 * (row-major) into Mi (row-major): the inverse of D's symmetric part, the
 * pseudo-inverse of its absolute value, or the identity; returns 0, 1 or 2
 * for those. Shared with the
 * petsc backend's point-block Jacobi (petsc/bs_dlinsolve.h). Nothing
 * allocates or fails. */
int bs_linsolve_block_inverse(const double D[9], double Mi[9]);

typedef struct bs_lin_stats {
  int iterations;      /* Krylov iterations (0 for a direct solve)                          */
  int indefinite;      /* 1: CG/PCG met p^T A p <= 0 and returned early (see above)          */
  int not_pd;          /* 1: CHOLMOD found A not positive definite (x untouched)            */
  int converged;       /* 1: reached rel_tol (a direct solve counts as converged)           */
  double rel_residual; /* ||b - A x|| / ||b|| at exit (masked norms; 0 when b = 0)          */
  double seconds;      /* wall time of the call                                              */
  int precond_failed;  /* 1: AMG's V-cycle was not positive definite (r.Br <= 0; see above)  */
  int single_overflow; /* 1: a value overflowed single precision; this solve ran in double   */
  int downhill_iterate; /* k > 0: the answer is CG's iterate k, the last that passed the       */
                        /* downhill test (bs_linsolve_set_downhill); 0: the usual answer       */
  int boundary;         /* 1: the answer lies on the trust-region boundary ||x|| = radius     */
                        /* (bs_linsolve_set_radius)                                           */
} bs_lin_stats;

typedef struct bs_linsolve bs_linsolve; /* workspace sized once for a pattern */

int bs_linsolve_create(const bs_bsr *pattern, bs_lin_kind kind, bs_linsolve **out,
                       bs_error *err);
void bs_linsolve_destroy(bs_linsolve **ls);

/* Solves A x = b on the free dofs (see the top of this header). b and x have
 * 3n entries and must not overlap; st may be NULL. b = 0 (on the free dofs)
 * gives x = 0, converged, 0 iterations. max_iter <= 0 means 3n (the dimension).
 * stats.rel_residual: CG/PCG report the recursively updated residual (equal to
 * ||b - A x|| in exact arithmetic; recomputed explicitly after an indefinite
 * exit on the first iteration); MINRES and CHOLMOD recompute ||b - A x||. */
int bs_linsolve_solve(bs_linsolve *ls, const bs_bsr *A, const uint8_t *mask, const double *b,
                      double rel_tol, int max_iter, double *x, bs_lin_stats *st, bs_error *err);

/* CG, PCG and AMG workspaces (BS_EINPUT for another kind when on): on = 1
 * makes the following solves read A's pattern values in single precision from
 * their 6th product on. The 5th product, in double, also rounds the values
 * into a copy of 36 bytes per block that the workspace allocates here
 * (BS_ENOMEM); the later products read the copy, with vectors, sums, the
 * preconditioner and the extra blocks in double. So a long solve solves with
 * A rounded to float (relative change <= 2^-24 per entry; its rel_residual is
 * the recursive one of that matrix), and a short one is unchanged. A value
 * beyond single precision's range makes the solve start again in double
 * (stats.single_overflow = 1). on = 0 frees the copy. */
int bs_linsolve_set_single(bs_linsolve *ls, int on, bs_error *err);

/* CG, PCG and AMG workspaces (BS_EINPUT for another kind when kappa > 0):
 * kappa in (0, 1) makes the following solves check each iterate x_k against
 * the downhill test of the minimizer (paper 3.1, step 5), b.x_k >= kappa ||b||
 * ||x_k|| (b = -grad E), and answer with the last iterate that passed when
 * the one they would return fails it (stats.downhill_iterate = its k; the
 * residual reported is that iterate's). Where the paper would replace a
 * failing answer by -grad E, this keeps the part of the Newton direction CG
 * had built: a long solve that ends on negative curvature, or in a nearly
 * singular direction, can return an iterate nearly orthogonal to grad E
 * after many iterates that were good directions. b.x_k comes from the PCG
 * identity b.p_k = r_k.z_k and ||x_k|| from the update pass, so the test
 * costs nothing; the workspace allocates one more vector of 3n here
 * (BS_ENOMEM) and copies into it only when an iterate that passed is followed
 * by one that fails. kappa = 0 (the default) turns it off and frees it. */
int bs_linsolve_set_downhill(bs_linsolve *ls, double kappa, bs_error *err);

/* CG, PCG and AMG workspaces (BS_EINPUT for another kind when radius > 0):
 * radius > 0 (in x's units) makes the following solves Steihaug's truncated
 * CG for the trust region ||x||_2 <= radius (Nocedal & Wright, Algorithm
 * 7.2): on negative curvature (p^T A p <= 0), or when an iterate leaves the
 * ball, the answer is the point where the current direction p crosses the
 * boundary (stats.boundary = 1, and stats.indefinite = 1 for the first
 * case); otherwise the usual answer. The downhill replacement
 * (bs_linsolve_set_downhill) is not applied to a boundary answer: every
 * point of Steihaug's path decreases the model. The norm is the Euclidean
 * one for PCG and AMG too (Steihaug's theory takes the preconditioner's
 * norm; with it ||x_k|| grows monotonically, here it need not). Nothing is
 * allocated; radius = 0 (the default) turns it off. */
int bs_linsolve_set_radius(bs_linsolve *ls, double radius, bs_error *err);

/* AMG workspaces only (BS_EINPUT otherwise): builds the BoomerAMG hierarchy
 * from P (SPD on the free dofs of mask; P's pattern size must match) and keeps
 * it for the following solves. Errors as bs_amg_setup. */
int bs_linsolve_amg_setup(bs_linsolve *ls, const bs_bsr *P, const uint8_t *mask, bs_error *err);
/* 1 if ls is an AMG workspace holding a hierarchy for this mask. */
int bs_linsolve_amg_ready(const bs_linsolve *ls, const uint8_t *mask);
/* The hierarchy's info (zeros for another kind or NULL). */
void bs_linsolve_amg_info(const bs_linsolve *ls, bs_amg_info *info);

#ifdef __cplusplus
}
#endif
#endif
