/* bs_material.h — hyperelastic constitutive models: the energy density
 * Psi(F), the first Piola-Kirchhoff stress P = dPsi/dF and its exact
 * derivative dP/dF, with an optional projection onto the PSD cone.
 *
 * Units: SI. youngs, mu, lambda in Pa; density in kg/m^3; F dimensionless;
 * Psi in J/m^3 (= Pa); P in Pa; dP/dF in Pa.
 * Layout: 3x3 matrices are row-major double[9], M[3*r + c]. dPdF[9*a + b] is
 * dP_a / dF_b with a, b those flat row-major indices (a symmetric 9x9).
 * Ownership: bs_material is a plain value; nothing here allocates.
 * Status: bs_material_init and bs_model_parse return BS_OK or BS_EINPUT and
 * name the parameter at fault; the evaluation functions cannot fail.
 *
 * Every model is defined, finite and continuous for EVERY F (inverted,
 * degenerate, zero), is zero with zero stress at F = I, and (except linear)
 * depends on F only through the signed singular values sigma of F
 * (bs_svd3: sigma0 >= sigma1 >= |sigma2|, sign sigma2 = sign det F), which
 * makes it invariant under rotations on either side. With J = s0 s1 s2:
 *
 *  fixed_corotated     mu sum (s_i - 1)^2 + lambda/2 (J - 1)^2
 *                      (Stomakhin, Howes, Schroeder, Teran 2012; the paper's model)
 *  corotated           mu sum (s_i - 1)^2 + lambda/2 (sum s_i - 3)^2
 *                      = mu |F - R|^2 + lambda/2 tr(R^T F - I)^2, R = U V^T
 *  neo_hookean         mu/2 (tr F^T F - 3) + g(J),  g(J) = -mu ln J + lambda/2 ln^2 J
 *                      for J >= J0; for J < J0 g is replaced by its second-order
 *                      Taylor expansion at J0 (energy-based extrapolation):
 *                      g(J0) + g'(J0)(J - J0) + g''(J0)(J - J0)^2 / 2.
 *                      Psi is C^2 across J = J0 (the third derivative jumps) and
 *                      finite for J <= 0. The extension is convex in J iff
 *                      g''(J0) = (mu + lambda (1 - ln J0)) / J0^2 > 0, and its slope
 *                      stays negative for all J < J0 (it always pushes toward
 *                      larger J, through J = 0, out of inversion).
 *  stable_neo_hookean  Smith, de Goes, Kim 2018: with mu' = 4 mu / 3,
 *                      lambda' = lambda + 5 mu / 6 (their reparameterization, so
 *                      that the rest Hessian is linear elasticity's with mu, lambda),
 *                      alpha = 1 + 3 mu' / (4 lambda'), I_C = tr F^T F:
 *                      mu'/2 (I_C - 3) + lambda'/2 (J - alpha)^2 - mu'/2 ln(I_C + 1) - Psi0,
 *                      Psi0 the constant that makes Psi(I) = 0.
 *  linear              mu eps:eps + lambda/2 tr(eps)^2, eps = (F + F^T)/2 - I
 *                      (small-strain; not rotation invariant).
 *
 * Default J0 = BS_NEO_HOOKEAN_J0 = 0.2, because:
 *  - for J >= 0.2 the model is exactly neo-Hookean; a solid compressed to a fifth
 *    of its volume is outside what the model describes anyway, and such states
 *    are transient (impacts) or trial points of a line search;
 *  - the extension's curvature g''(J0) grows like 1/J0^2: relative to g''(1) =
 *    mu + lambda it is 49x at nu = 0.3 and 61x at nu = 0.45 for J0 = 0.2, but
 *    240x for J0 = 0.1 and ~4e4x for J0 = 0.01. A small J0 rebuilds the ln J
 *    barrier the extension removes (stiff, badly scaled Newton systems, tiny
 *    line-search steps near inversion); a large J0 would change the physics at
 *    ordinary compressions;
 *  - it keeps the extension convex for every nu >= 0 and down to nu ~ -0.31
 *    (mu + lambda (1 - ln 0.2) > 0 iff lambda / mu > -0.383).
 *
 * Stiffness (dPdF): isotropic models use the singular-value-space form
 * (Teran, Sifakis, Irving, Fedkiw 2005; Sifakis & Barbic 2012): in the basis
 * u_i v_j^T, dP/dF is block diagonal with the 3x3 Hessian of Psi(sigma) acting
 * on the diagonal entries and, for each pair i < j, a 2x2 block on
 * (F_ij, F_ji) with eigenvalues
 *   (dPsi/ds_i - dPsi/ds_j) / (s_i - s_j)  on (E_ij + E_ji)/sqrt 2,
 *   (dPsi/ds_i + dPsi/ds_j) / (s_i + s_j)  on (E_ij - E_ji)/sqrt 2,
 * both evaluated through closed-form quotients per model, exact at repeated
 * singular values (s_i = s_j) with no division by a small difference. The
 * second quotient of the corotated models contains 4 mu / (s_i + s_j), a true
 * singularity of |F - R|^2 where s_i = -s_j (R jumps there: the energy has a
 * ridge); its denominator is clamped at BS_SIGMA_SUM_MIN (Stomakhin et al.
 * 2012), which changes dPdF only within 1e-6 of that ridge.
 * project_psd (a bs_psd_mode) = BS_PSD_ALL clamps the eigenvalues of the 3x3
 * block and of the 2x2 blocks at zero — the exact projection of dP/dF onto the
 * PSD cone (the blocks are its eigen-decomposition; no 9x9 eigensolve). A
 * block with no negative eigenvalue is returned bit for bit (a positive
 * definite 3x3 block is recognized by its Cholesky pivots, without an
 * eigen-decomposition). BS_PSD_INVERTED projects only where det F <= 0 (the
 * inverted elements of a tangle) and leaves dP/dF exact elsewhere.
 */

#ifndef BS_MATERIAL_H
#define BS_MATERIAL_H

#include "bs_base.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The definiteness fix of dP/dF: the project_psd argument of the functions
 * below and of the element kernels (bs_element.h, bs_fem.h). */
typedef enum bs_psd_mode {
  BS_PSD_NONE = 0,    /* exact dP/dF                                    */
  BS_PSD_ALL = 1,     /* projected onto the PSD cone everywhere         */
  BS_PSD_INVERTED = 2, /* projected where det F <= 0, exact elsewhere   */
  BS_PSD_AUTO = 3      /* the elasticity term's choice per tet (INVERTED  */
                       /* or NONE, bs_terms.h); kernels read it as NONE   */
} bs_psd_mode;

/* BS_PSD_AUTO: a tet whose mu dt^2 / (rho h^2) reaches this (its stiffness
 * over its inertia in the step's Hessian) gets BS_PSD_INVERTED. */
#define BS_PSD_AUTO_RATIO 10.0

#define BS_NEO_HOOKEAN_J0 0.2
#define BS_SIGMA_SUM_MIN 1e-6

typedef enum {
  BS_MODEL_FIXED_COROTATED,
  BS_MODEL_COROTATED,
  BS_MODEL_NEO_HOOKEAN,
  BS_MODEL_STABLE_NEO_HOOKEAN,
  BS_MODEL_LINEAR
} bs_model;

typedef struct bs_material {
  bs_model model;
  double youngs, poisson, density; /* as given                        */
  double mu, lambda;               /* Lame parameters from youngs, poisson */
  double J0;                       /* neo-Hookean threshold (BS_NEO_HOOKEAN_J0) */
} bs_material;

/* Fills *out from Young's modulus E and Poisson ratio nu:
 *   mu = E / (2 (1 + nu)),  lambda = E nu / ((1 + nu)(1 - 2 nu)).
 * Errors (BS_EINPUT, the message names the parameter and its value): youngs
 * not finite or <= 0; poisson not finite or outside (-1, 0.5) (0.5 exactly is
 * incompressible: lambda infinite; 0.499 works); density not finite or <= 0;
 * an unknown model. Model conditions that keep Psi bounded below (which the
 * minimizer needs): fixed_corotated needs lambda >= 0 (poisson >= 0) — with
 * lambda < 0 the (J - 1)^2 term, of degree 6 in sigma, sends Psi to -infinity;
 * neo_hookean needs g''(J0) > 0 (poisson > about -0.31). */
int bs_material_init(bs_model model, double youngs, double poisson, double density, bs_material *out,
                     bs_error *err);

/* "fixed_corotated", "corotated", "neo_hookean", "stable_neo_hookean", "linear".
 * An unknown or NULL name is BS_EINPUT, naming it and listing the valid ones. */
int bs_model_parse(const char *name, bs_model *out, bs_error *err);
/* The name bs_model_parse accepts; "unknown" for a value outside the enum. */
const char *bs_model_name(bs_model model);

/* Energy density Psi(F). */
double bs_material_psi(const bs_material *m, const double F[9]);

/* Psi(F) returned, P = dPsi/dF written to P. */
double bs_material_psi_P(const bs_material *m, const double F[9], double P[9]);

/* dP/dF (symmetric 9x9, see Layout); project_psd = 1: its projection onto the
 * positive semidefinite cone. */
void bs_material_dPdF(const bs_material *m, const double F[9], bs_psd_mode project_psd, double dPdF[81]);

/* dP/dF in the modal form above, for the element kernels (which never form
 * the 9x9 matrix): the SVD F = U diag(s) V^T and the blocks, projected as
 * bs_material_dPdF does when project_psd = 1:
 *   dP/dF = sum_ij H_ij d_i d_j^T + sum_p (lp_p S_p S_p^T + lm_p T_p T_p^T) / 2,
 * d_i = vec(u_i v_i^T), S_p, T_p = vec(u_i v_j^T +- u_j v_i^T) for the pairs
 * p = (i, j) = (0, 1), (0, 2), (1, 2); u_i, v_i the columns of U and V.
 * BS_MODEL_LINEAR has no such form (its dP/dF is the constant of
 * bs_material_dPdF): for it every field of out is NaN. */
typedef struct bs_dPdF_modes {
  double U[9], V[9]; /* rotations, row-major                  */
  double H[9];       /* symmetric 3x3 block on the d_i          */
  double lp[3], lm[3];
} bs_dPdF_modes;
void bs_material_dPdF_modes(const bs_material *m, const double F[9], bs_psd_mode project_psd, bs_dPdF_modes *out);

/* The same on n matrices at once (F, P: 9 doubles per matrix, packed; psi: n;
 * modes: n), bit for bit the results of the single-matrix calls above, with
 * the SVDs done BS_MATERIAL_BATCH at a time by bs_svd3_batch (several times
 * faster per matrix than bs_svd3); Psi and P of the corotated models come
 * from the polar rotation (bs_polar3) where it applies. */
#define BS_MATERIAL_BATCH 8
void bs_material_psi_batch(const bs_material *m, int n, const double *F, double *psi);
void bs_material_psi_P_batch(const bs_material *m, int n, const double *F, double *psi, double *P);
void bs_material_dPdF_modes_batch(const bs_material *m, int n, const double *F, bs_psd_mode project_psd,
                                  bs_dPdF_modes *out);

#ifdef __cplusplus
}
#endif
#endif
