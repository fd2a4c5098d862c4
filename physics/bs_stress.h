/* bs_stress.h — what an engineer reads off a deformed element: stress and
 * strain measures of one deformation gradient F under a material model.
 *
 * Conventions
 *  - 3x3 matrices are row-major double[9], M[3*r + c], as in bs_material.h.
 *  - Units: P, sigma, von Mises and psi in Pa (psi is J/m^3 of REST volume);
 *    the Green strain, the stretches and J are dimensionless.
 *  - Nothing allocates, prints or fails: every F is accepted. Quantities
 *    that divide by J (sigma, von Mises) are NaN when J = 0 or F is not
 *    finite; for J < 0 (an inverted element) they are the formulas' values,
 *    which have no physical meaning.
 *
 * Definitions (F = the element's deformation gradient, J = det F):
 *  - first Piola-Kirchhoff P = dPsi/dF, from bs_material_psi_P (the models
 *    are defined once, in material.c);
 *  - Cauchy sigma = sym(P F^T) / J, sym(A) = (A + A^T)/2. For the isotropic
 *    models P F^T is symmetric already (sym changes only rounding); for the
 *    small-strain model "linear" it is not, and its symmetric part is the
 *    stress reported;
 *  - von Mises sqrt(3/2 s:s), s = sigma - tr(sigma)/3 I, the deviator;
 *  - Green-Lagrange strain E = (F^T F - I)/2, evaluated as
 *    (G + G^T + G^T G)/2 with G = F - I (no cancellation near rest);
 *  - principal stretches: the singular values of F in bs_svd3's convention
 *    (descending; the last carries the sign of J, so an inverted element has
 *    a negative third stretch);
 *  - energy density psi = Psi(F) of bs_material_psi_P.
 *
 * Example:
 *     bs_material m; bs_material_init(BS_MODEL_NEO_HOOKEAN, 1e6, 0.3, 1000, &m, &err);
 *     double F[9] = {1.1, 0, 0, 0, 1, 0, 0, 0, 1};
 *     bs_stress_fields f;
 *     bs_stress_eval(&m, F, &f);     f.cauchy[0]: the axial Cauchy stress, Pa
 */
#ifndef BS_STRESS_H
#define BS_STRESS_H

#include "bs_material.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Every measure of one F. */
typedef struct bs_stress_fields {
  double P[9];        /* first Piola-Kirchhoff stress (Pa)             */
  double cauchy[9];   /* Cauchy stress sigma, symmetric (Pa)           */
  double von_mises;   /* of sigma (Pa)                                 */
  double green[9];    /* Green-Lagrange strain E, symmetric (1)        */
  double stretch[3];  /* principal stretches, descending, signed (1)   */
  double psi;         /* energy density (Pa = J/m^3, rest volume)      */
  double J;           /* det F (1)                                     */
} bs_stress_fields;

/* All of the above for the material m at F. */
void bs_stress_eval(const bs_material *m, const double F[9], bs_stress_fields *out);

/* det F. */
double bs_det3(const double F[9]);

/* sigma = sym(P F^T) / J with J = det F; NaN (all nine) when J = 0 or not finite. */
void bs_cauchy_from_P(const double F[9], const double P[9], double sigma[9]);

/* von Mises stress of a symmetric sigma (only its upper triangle is read). */
double bs_von_mises(const double sigma[9]);

/* E = (F^T F - I) / 2. */
void bs_green_strain(const double F[9], double E[9]);

/* Principal stretches of F (bs_svd3's singular values). */
void bs_principal_stretches(const double F[9], double stretch[3]);

#ifdef __cplusplus
}
#endif
#endif
