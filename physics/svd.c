/* svd.c — signed 3x3 SVD (one-sided Jacobi) and symmetric 3x3 eigen-
 * decomposition (two-sided Jacobi). See bs_svd.h for the contracts. */
#include "bs_svd.h"

#include <float.h>
#include <math.h>

enum { SVD_MAX_SWEEPS = 24, EIG_MAX_SWEEPS = 40 };

/* Off-diagonal Gram entries below this multiple of eps |b_p||b_q| count as
 * zero. A dot product of 3-vectors is only computed to ~3 eps, so a bound of
 * one eps could keep rotating on round-off; 8 eps leaves U orthogonal to ~1e-15.
 * Typical F take 3 or 4 sweeps (the last one only checks). */
#define SVD_TOL (8.0 * DBL_EPSILON)

static const int pair_p[3] = {0, 0, 1}, pair_q[3] = {1, 2, 2};

static void set_identity(double A[9]) {
  for (int i = 0; i < 9; i++) A[i] = (i % 4 == 0) ? 1.0 : 0.0;
}

static double det3(const double A[9]) {
  return A[0] * (A[4] * A[8] - A[5] * A[7]) - A[1] * (A[3] * A[8] - A[5] * A[6]) +
         A[2] * (A[3] * A[7] - A[4] * A[6]);
}

/* Swap columns i and j of a 3x3 matrix. */
static void swap_col(double A[9], int i, int j) {
  for (int r = 0; r < 3; r++) {
    double t = A[3 * r + i];
    A[3 * r + i] = A[3 * r + j];
    A[3 * r + j] = t;
  }
}

void bs_svd3(const double F[9], double U[9], double sigma[3], double V[9]) {
  /* Scale by an exact power of two so that the largest entry is in [0.5, 1). */
  double fm = 0.0, bad = 0.0;
  for (int i = 0; i < 9; i++) {
    const double a = fabs(F[i]);
    if (a > fm) fm = a;
    bad += F[i] - F[i]; /* 0, or NaN when some entry is Inf or NaN */
  }
  if (bad != 0.0 || bad != bad) {
    for (int i = 0; i < 9; i++) U[i] = V[i] = NAN;
    sigma[0] = sigma[1] = sigma[2] = NAN;
    return;
  }
  if (fm == 0.0) {
    set_identity(U);
    set_identity(V);
    sigma[0] = sigma[1] = sigma[2] = 0.0;
    return;
  }
  int ex;
  frexp(fm, &ex);
  double B[9];
  if (ex > -1000 && ex < 1000) {
    const double sc = ldexp(1.0, -ex);
    for (int i = 0; i < 9; i++) B[i] = F[i] * sc;
  } else
    for (int i = 0; i < 9; i++) B[i] = ldexp(F[i], -ex);
  set_identity(V);

  /* One-sided Jacobi: rotate column pairs (p, q) of B = F V until orthogonal. */
  for (int sweep = 0; sweep < SVD_MAX_SWEEPS; sweep++) {
    int rotated = 0;
    for (int k = 0; k < 3; k++) {
      const int p = pair_p[k], q = pair_q[k];
      double a = 0, b = 0, g = 0;
      for (int r = 0; r < 3; r++) {
        a += B[3 * r + p] * B[3 * r + p];
        b += B[3 * r + q] * B[3 * r + q];
        g += B[3 * r + p] * B[3 * r + q];
      }
      if (g * g <= SVD_TOL * SVD_TOL * a * b) continue;
      /* The rotation [c s; -s c] diagonalizes the Gram block [a g; g b]:
       * t = s / c is the smaller root of t^2 + 2 zeta t - 1 = 0, zeta =
       * (b - a) / 2g, i.e. t = 2g sgn(b - a) / D with r = sqrt((b - a)^2 + 4g^2),
       * D = |b - a| + r; and 1 + t^2 = 2 r D / D^2. (Entries are <= 1 after
       * the scaling: nothing overflows; D underflows only for columns below
       * 1e-150, which are then left alone.) */
      const double dab = b - a, r = sqrt(dab * dab + 4.0 * g * g);
      const double D = fabs(dab) + r;
      if (!(D > 0)) continue;
      const double iq = 1.0 / sqrt(2.0 * r * D);
      const double c = D * iq, s = (dab >= 0 ? 2.0 * g : -2.0 * g) * iq;
      for (int r = 0; r < 3; r++) {
        double bp = B[3 * r + p], bq = B[3 * r + q];
        B[3 * r + p] = c * bp - s * bq;
        B[3 * r + q] = s * bp + c * bq;
        double vp = V[3 * r + p], vq = V[3 * r + q];
        V[3 * r + p] = c * vp - s * vq;
        V[3 * r + q] = s * vp + c * vq;
      }
      rotated = 1;
    }
    if (!rotated) break;
  }

  /* Sort the columns by length, descending. */
  double n[3];
  for (int j = 0; j < 3; j++) n[j] = B[j] * B[j] + B[3 + j] * B[3 + j] + B[6 + j] * B[6 + j];
  for (int i = 0; i < 2; i++)
    for (int j = 2; j > i; j--)
      if (n[j] > n[j - 1]) {
        double t = n[j];
        n[j] = n[j - 1];
        n[j - 1] = t;
        swap_col(B, j, j - 1);
        swap_col(V, j, j - 1);
      }
  /* V a rotation: a reflection moves into the last column (and into sigma2). */
  if (det3(V) < 0.0)
    for (int r = 0; r < 3; r++) {
      V[3 * r + 2] = -V[3 * r + 2];
      B[3 * r + 2] = -B[3 * r + 2];
    }

  double u0[3], u1[3], u2[3];
  const double s0 = sqrt(n[0]); /* >= 0.5: the column holding fm */
  for (int r = 0; r < 3; r++) u0[r] = B[3 * r] / s0;
  /* u1: b1 made orthogonal to u0 (it already is to ~eps); when b1 is
   * negligible, any unit vector orthogonal to u0. */
  double d = u0[0] * B[1] + u0[1] * B[4] + u0[2] * B[7], nw2 = 0;
  for (int r = 0; r < 3; r++) {
    u1[r] = B[3 * r + 1] - d * u0[r];
    nw2 += u1[r] * u1[r];
  }
  if (!(nw2 > 1e-300)) {
    int k = 0;
    if (fabs(u0[1]) < fabs(u0[k])) k = 1;
    if (fabs(u0[2]) < fabs(u0[k])) k = 2;
    nw2 = 0;
    for (int r = 0; r < 3; r++) {
      u1[r] = (r == k ? 1.0 : 0.0) - u0[k] * u0[r];
      nw2 += u1[r] * u1[r];
    }
  }
  const double inw = 1.0 / sqrt(nw2);
  for (int r = 0; r < 3; r++) u1[r] *= inw;
  u2[0] = u0[1] * u1[2] - u0[2] * u1[1];
  u2[1] = u0[2] * u1[0] - u0[0] * u1[2];
  u2[2] = u0[0] * u1[1] - u0[1] * u1[0];

  double s1 = sqrt(n[1]);
  double s2 = u2[0] * B[2] + u2[1] * B[5] + u2[2] * B[8];
  if (fabs(s2) > s1) s2 = copysign(s1, s2);
  for (int r = 0; r < 3; r++) {
    U[3 * r] = u0[r];
    U[3 * r + 1] = u1[r];
    U[3 * r + 2] = u2[r];
  }
  if (ex > -1000 && ex < 1000) {
    const double sc = ldexp(1.0, ex);
    sigma[0] = s0 * sc;
    sigma[1] = s1 * sc;
    sigma[2] = s2 * sc;
  } else {
    sigma[0] = ldexp(s0, ex);
    sigma[1] = ldexp(s1, ex);
    sigma[2] = ldexp(s2, ex);
  }
}

void bs_sym3_eig(const double A[9], double lambda[3], double Q[9]) {
  double a[9];
  for (int i = 0; i < 3; i++)
    for (int j = i; j < 3; j++) a[3 * i + j] = a[3 * j + i] = A[3 * i + j];
  set_identity(Q);
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
  for (int i = 0; i < 2; i++)
    for (int j = 2; j > i; j--)
      if (lambda[j] > lambda[j - 1]) {
        double t = lambda[j];
        lambda[j] = lambda[j - 1];
        lambda[j - 1] = t;
        swap_col(Q, j, j - 1);
      }
  if (det3(Q) < 0.0)
    for (int i = 0; i < 3; i++) Q[3 * i + 2] = -Q[3 * i + 2];
}
