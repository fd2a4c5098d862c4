/* bs_element.h — the P1 (linear) tetrahedron kernel: rest shape, deformation
 * gradient, and one tet's elastic energy, gradient and Hessian.
 *
 * Conventions
 *  - A tet's coordinates are 12 doubles: vertex a at x[3a .. 3a+2] (metres).
 *  - Dm = [X1 - X0, X2 - X0, X3 - X0] (columns) at rest, Ds the same at x;
 *    F = Ds Dm^-1 is constant over the tet. 3x3 matrices are row-major.
 *  - The energy of a tet is E = V Psi(F) (J), V its rest volume (m^3). Its
 *    gradient g = dE/dx (N, 12 doubles, the negated nodal forces) and Hessian
 *    H = d2E/dx2 = V G^T (dP/dF) G (N/m, 12x12 row-major, H[12*i + j],
 *    symmetric bit for bit), G = dF/dx the 9x12 map, never formed: F_mj
 *    depends only on coordinate m of each vertex, with weight w[a][j] = row
 *    a-1 of Dm^-1 for a = 1..3 and w[0][j] = -(sum of those rows).
 *  - Nothing allocates, prints or fails; every configuration is accepted
 *    (inverted, flat, collapsed), as the models are (bs_material.h).
 */
#ifndef BS_ELEMENT_H
#define BS_ELEMENT_H

#include "bs_material.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Rest shape of the tet with vertices X (12 doubles): Dm^-1 and the SIGNED
 * volume det(Dm) / 6 (positive for a positively oriented tet). A degenerate
 * tet (det Dm = 0 or not finite) gets Dm_inv = 0; callers reject volume <= 0. */
void bs_tet_rest(const double X[12], double Dm_inv[9], double *volume);

/* F = Ds Dm^-1 at the configuration x (12 doubles). */
void bs_tet_F(const double x[12], const double Dm_inv[9], double F[9]);

/* vol * Psi(F). */
double bs_tet_energy(const bs_material *m, const double x[12], const double Dm_inv[9], double vol);

/* vol * Psi(F) returned; g = its gradient with respect to x (12 doubles). */
double bs_tet_energy_grad(const bs_material *m, const double x[12], const double Dm_inv[9], double vol,
                          double g[12]);

/* H = vol G^T dP/dF G (12x12 row-major); project_psd = 1 uses the PSD
 * projection of dP/dF, which makes H positive semidefinite. */
void bs_tet_hessian(const bs_material *m, const double x[12], const double Dm_inv[9], double vol, bs_psd_mode project_psd,
                    double H[144]);

/* The same on n tets at once, bit for bit the single-tet results: x is 12
 * doubles per tet, Dm_inv 9, vol 1, e 1 (vol Psi), g 12, H 144, all packed
 * (tet i at x + 12 i, ...). The SVDs run batched (bs_material_*_batch). */
void bs_tet_energy_batch(const bs_material *m, int n, const double *x, const double *Dm_inv, const double *vol,
                         double *e);
void bs_tet_energy_grad_batch(const bs_material *m, int n, const double *x, const double *Dm_inv,
                              const double *vol, double *e, double *g);
void bs_tet_hessian_batch(const bs_material *m, int n, const double *x, const double *Dm_inv, const double *vol,
                          bs_psd_mode project_psd, double *H);

#ifdef __cplusplus
}
#endif
#endif
