/* sym3.c — symmetric 3x3 eigen-decomposition (two-sided cyclic Jacobi).
 * See bs_sym3.h for the contract. */
#include "bs_sym3.h"

#include "bs_vec3.h"

#include <math.h>
#include <stddef.h>

enum { EIG_MAX_SWEEPS = 40 };

static const int pair_p[3] = {0, 0, 1}, pair_q[3] = {1, 2, 2};

void bs_sym3_eig(const double A[9], double lambda[3], double Q[9]) {
  double a[9];
  for (int i = 0; i < 3; i++)
    for (int j = i; j < 3; j++) a[3 * i + j] = a[3 * j + i] = A[3 * i + j];
  bs_mat3_identity(Q);
  for (int sweep = 0; sweep < EIG_MAX_SWEEPS; sweep++) {
    int rotated = 0;
    for (int k = 0; k < 3; k++) {
      const int p = pair_p[k], q = pair_q[k], r = 3 - p - q;
      const double apq = a[3 * p + q];
      if (apq == 0.0) continue;
      const double app = a[3 * p + p], aqq = a[3 * q + q];
      /* Negligible against both diagonal entries: drop it (Rutishauser). */
      if (fabs(app) + 1e3 * fabs(apq) == fabs(app) && fabs(aqq) + 1e3 * fabs(apq) == fabs(aqq)) {
        a[3 * p + q] = a[3 * q + p] = 0.0;
        continue;
      }
      const double theta = (aqq - app) / (2.0 * apq);
      const double at = fabs(theta);
      const double t = copysign(1.0, theta) / (at + (at < 1e100 ? sqrt(1.0 + theta * theta) : at));
      const double c = 1.0 / sqrt(1.0 + t * t), s = c * t;
      a[3 * p + p] = app - t * apq;
      a[3 * q + q] = aqq + t * apq;
      a[3 * p + q] = a[3 * q + p] = 0.0;
      const double arp = a[3 * r + p], arq = a[3 * r + q];
      a[3 * r + p] = a[3 * p + r] = c * arp - s * arq;
      a[3 * r + q] = a[3 * q + r] = s * arp + c * arq;
      for (int i = 0; i < 3; i++) {
        const double qp = Q[3 * i + p], qq = Q[3 * i + q];
        Q[3 * i + p] = c * qp - s * qq;
        Q[3 * i + q] = s * qp + c * qq;
      }
      rotated = 1;
    }
    if (!rotated) break;
  }
  for (int i = 0; i < 3; i++) lambda[i] = a[4 * i];
  bs_mat3_sort_cols_desc(lambda, Q, NULL);
  if (bs_mat3_det(Q) < 0.0)
    for (int i = 0; i < 3; i++) Q[3 * i + 2] = -Q[3 * i + 2];
}

void bs_sym3_from_eig(const double d[3], const double Q[9], double A[9]) {
  for (int i = 0; i < 3; i++)
    for (int j = i; j < 3; j++)
      A[3 * i + j] = A[3 * j + i] =
          d[0] * Q[3 * i] * Q[3 * j] + d[1] * Q[3 * i + 1] * Q[3 * j + 1] + d[2] * Q[3 * i + 2] * Q[3 * j + 2];
}
