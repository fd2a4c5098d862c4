/* stress.c — stress and strain measures of a deformation gradient (see
 * bs_stress.h). The constitutive models are bs_material's; nothing here
 * restates them. */
#include <math.h>

#include "bs_stress.h"
#include "bs_svd.h"

double bs_det3(const double F[9]) {
  return F[0] * (F[4] * F[8] - F[5] * F[7]) - F[1] * (F[3] * F[8] - F[5] * F[6]) + F[2] * (F[3] * F[7] - F[4] * F[6]);
}

void bs_cauchy_from_P(const double F[9], const double P[9], double sigma[9]) {
  const double J = bs_det3(F);
  if (!(J != 0) || !isfinite(J)) {
    for (int i = 0; i < 9; i++) sigma[i] = NAN;
    return;
  }
  double A[9]; /* P F^T */
  for (int i = 0; i < 3; i++)
    for (int j = 0; j < 3; j++) A[3 * i + j] = P[3 * i] * F[3 * j] + P[3 * i + 1] * F[3 * j + 1] + P[3 * i + 2] * F[3 * j + 2];
  for (int i = 0; i < 3; i++)
    for (int j = 0; j < 3; j++) sigma[3 * i + j] = 0.5 * (A[3 * i + j] + A[3 * j + i]) / J;
}

double bs_von_mises(const double s[9]) {
  const double d01 = s[0] - s[4], d12 = s[4] - s[8], d20 = s[8] - s[0];
  return sqrt(0.5 * (d01 * d01 + d12 * d12 + d20 * d20) + 3.0 * (s[1] * s[1] + s[2] * s[2] + s[5] * s[5]));
}

void bs_green_strain(const double F[9], double E[9]) {
  const double G[9] = {F[0] - 1.0, F[1], F[2], F[3], F[4] - 1.0, F[5], F[6], F[7], F[8] - 1.0};
  for (int i = 0; i < 3; i++)
    for (int j = 0; j < 3; j++) {
      const double gtg = G[i] * G[j] + G[3 + i] * G[3 + j] + G[6 + i] * G[6 + j]; /* (G^T G)_ij */
      E[3 * i + j] = 0.5 * (G[3 * i + j] + G[3 * j + i] + gtg);
    }
}

void bs_principal_stretches(const double F[9], double stretch[3]) {
  double U[9], V[9];
  bs_svd3(F, U, stretch, V);
}

void bs_stress_eval(const bs_material *m, const double F[9], bs_stress_fields *out) {
  out->psi = bs_material_psi_P(m, F, out->P);
  out->J = bs_det3(F);
  bs_cauchy_from_P(F, out->P, out->cauchy);
  out->von_mises = bs_von_mises(out->cauchy);
  bs_green_strain(F, out->green);
  bs_principal_stretches(F, out->stretch);
}
