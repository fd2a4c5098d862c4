/* sym_psd.c — a small symmetric matrix projected onto the positive
 * semidefinite cone (bs_sym_psd_project, see bs_svd.h).
 *
 * Cyclic Jacobi (Golub & Van Loan, Matrix Computations, 4th ed., 8.5.3): A =
 * V diag(lambda) V^T by plane rotations, each zeroing one off-diagonal pair;
 * sweeps until the off-diagonal part is below 1e-15 of the whole in norm
 * (quadratic convergence: about 6 sweeps at m = 12). */
#include <math.h>

#include "bs_svd.h"

/* The rotation in the (p, q) plane that zeroes A[p][q], applied to A (both
 * sides) and accumulated into V's columns. */
static void jacobi_rotate(int m, double *A, double *V, int p, int q) {
  const double apq = A[p * m + q];
  if (apq == 0) return;
  const double theta = (A[q * m + q] - A[p * m + p]) / (2 * apq);
  const double t = (theta >= 0 ? 1.0 : -1.0) / (fabs(theta) + sqrt(theta * theta + 1));
  const double c = 1 / sqrt(t * t + 1), sn = t * c;
  for (int k = 0; k < m; k++) {
    const double akp = A[k * m + p], akq = A[k * m + q];
    A[k * m + p] = c * akp - sn * akq;
    A[k * m + q] = sn * akp + c * akq;
  }
  for (int k = 0; k < m; k++) {
    const double apk = A[p * m + k], aqk = A[q * m + k];
    A[p * m + k] = c * apk - sn * aqk;
    A[q * m + k] = sn * apk + c * aqk;
  }
  for (int k = 0; k < m; k++) {
    const double vkp = V[k * m + p], vkq = V[k * m + q];
    V[k * m + p] = c * vkp - sn * vkq;
    V[k * m + q] = sn * vkp + c * vkq;
  }
}

/* Eigen-decomposition of the symmetric m x m matrix A (overwritten: its
 * diagonal ends as the eigenvalues), eigenvectors in the columns of V. */
static void jacobi_eigen(int m, double *A, double *V) {
  for (int i = 0; i < m * m; i++) V[i] = 0;
  for (int i = 0; i < m; i++) V[i * m + i] = 1;
  for (int sweep = 0; sweep < 50; sweep++) {
    double off = 0, all = 0;
    for (int i = 0; i < m; i++)
      for (int j = 0; j < m; j++) {
        const double a2 = A[i * m + j] * A[i * m + j];
        all += a2;
        off += i != j ? a2 : 0;
      }
    if (!(off > 1e-30 * all)) return; /* also ends on a zero or non-finite A */
    for (int p = 0; p < m; p++)
      for (int q = p + 1; q < m; q++) jacobi_rotate(m, A, V, p, q);
  }
}

int bs_sym_psd_project(int m, double *H) {
  if (m < 1 || m > 12) return -1;
  double A[144], V[144];
  for (int i = 0; i < m; i++)
    for (int j = 0; j < m; j++) A[i * m + j] = 0.5 * (H[i * m + j] + H[j * m + i]);
  jacobi_eigen(m, A, V);
  double big = 0;
  for (int k = 0; k < m; k++) big = fmax(big, fabs(A[k * m + k]));
  int neg = 0; /* eigenvalues below the rounding level of the largest */
  for (int k = 0; k < m; k++) neg += A[k * m + k] < -1e-12 * big;
  if (neg == 0) return 0; /* H unchanged, bit for bit */
  for (int i = 0; i < m; i++)
    for (int j = i; j < m; j++) {
      double s = 0;
      for (int k = 0; k < m; k++)
        if (A[k * m + k] > 0) s += V[i * m + k] * A[k * m + k] * V[j * m + k];
      H[i * m + j] = H[j * m + i] = s;
    }
  return neg;
}
