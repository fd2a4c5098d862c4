/* test_dense.h — a dense symmetric eigensolver (cyclic Jacobi) for tests:
 * the independent reference against which PSD projections are checked. */
#ifndef BS_TEST_DENSE_H
#define BS_TEST_DENSE_H

#include <math.h>
#include <string.h>

/* Eigenvalues (and eigenvectors, columns of Q, when Q != NULL) of a symmetric
 * n x n matrix, n <= 12, by cyclic Jacobi: the test's independent reference. */
static void sym_eig_dense(int n, const double *A_in, double *lam, double *Qout) {
  double A[144], Q[144];
  memcpy(A, A_in, sizeof(double) * n * n);
  for (int i = 0; i < n * n; i++) Q[i] = (i % (n + 1) == 0);
  for (int sweep = 0; sweep < 100; sweep++) {
    double off = 0, diag = 0;
    for (int p = 0; p < n; p++) {
      diag += A[p * n + p] * A[p * n + p];
      for (int q = p + 1; q < n; q++) off += A[p * n + q] * A[p * n + q];
    }
    if (off <= 1e-36 * diag || off == 0) break;
    for (int p = 0; p < n; p++)
      for (int q = p + 1; q < n; q++) {
        double apq = A[p * n + q];
        if (apq == 0) continue;
        double th = (A[q * n + q] - A[p * n + p]) / (2 * apq);
        double t = (th >= 0 ? 1.0 : -1.0) / (fabs(th) + sqrt(th * th + 1));
        double c = 1 / sqrt(t * t + 1), s = t * c;
        for (int k = 0; k < n; k++) {
          double akp = A[k * n + p], akq = A[k * n + q];
          A[k * n + p] = c * akp - s * akq;
          A[k * n + q] = s * akp + c * akq;
        }
        for (int k = 0; k < n; k++) {
          double apk = A[p * n + k], aqk = A[q * n + k];
          A[p * n + k] = c * apk - s * aqk;
          A[q * n + k] = s * apk + c * aqk;
        }
        for (int k = 0; k < n; k++) {
          double qkp = Q[k * n + p], qkq = Q[k * n + q];
          Q[k * n + p] = c * qkp - s * qkq;
          Q[k * n + q] = s * qkp + c * qkq;
        }
      }
  }
  for (int i = 0; i < n; i++) lam[i] = A[i * n + i];
  if (Qout) memcpy(Qout, Q, sizeof(double) * n * n);
}

#endif
