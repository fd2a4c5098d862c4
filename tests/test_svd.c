/* The signed 3x3 SVD and the symmetric 3x3 eigen-decomposition: reconstruction
 * and orthogonality to 1e-12 relative, rotations (det +1), ordering and the
 * inversion sign convention, over random, rank-deficient, repeated, inverted,
 * nearly flat and extreme-scale matrices. */
#include <criterion/criterion.h>
#include <float.h>
#include <math.h>
#include <stdint.h>
#include <string.h>

#include "bs_svd.h"

/* ---- deterministic random numbers and small matrix helpers ---- */

#define BS_TEST_SEED 0x9E3779B97F4A7C15ull
#include "test_random.h"
static double det3(const double A[9]) {
  return A[0] * (A[4] * A[8] - A[5] * A[7]) - A[1] * (A[3] * A[8] - A[5] * A[6]) +
         A[2] * (A[3] * A[7] - A[4] * A[6]);
}
/* F = Q diag(s) R^T */
static void compose(const double Q[9], const double s[3], const double R[9], double F[9]) {
  for (int i = 0; i < 3; i++)
    for (int j = 0; j < 3; j++) {
      double v = 0;
      for (int k = 0; k < 3; k++) v += Q[3 * i + k] * s[k] * R[3 * j + k];
      F[3 * i + j] = v;
    }
}
static double maxabs(const double A[9]) {
  double m = 0;
  for (int i = 0; i < 9; i++) m = fmax(m, fabs(A[i]));
  return m;
}
/* Frobenius norm, scaled so that it neither over- nor underflows. */
static double fro(const double A[9]) {
  double m = maxabs(A), v = 0;
  if (m == 0) return 0;
  for (int i = 0; i < 9; i++) v += (A[i] / m) * (A[i] / m);
  return m * sqrt(v);
}
/* max |A^T A - I| */
static double orth_err(const double A[9]) {
  double e = 0;
  for (int i = 0; i < 3; i++)
    for (int j = 0; j < 3; j++) {
      double v = -(i == j);
      for (int k = 0; k < 3; k++) v += A[3 * k + i] * A[3 * k + j];
      e = fmax(e, fabs(v));
    }
  return e;
}

/* Worst figures over a test, reported in the log. */
static double worst_rec, worst_orth;

/* Every property of bs_svd3 at F; returns sigma. */
static void check_svd(const double F[9], double sigma[3], const char *what) {
  double U[9], V[9], s[3], R[9];
  bs_svd3(F, U, s, V);
  for (int i = 0; i < 9; i++) cr_assert(isfinite(U[i]) && isfinite(V[i]), "%s: non-finite U or V", what);
  cr_assert(isfinite(s[0]) && isfinite(s[1]) && isfinite(s[2]), "%s: non-finite sigma", what);
  compose(U, s, V, R);
  double nF = fro(F), d[9];
  for (int i = 0; i < 9; i++) d[i] = R[i] - F[i];
  double rec = nF > 0 ? fro(d) / nF : fro(d);
  double ou = orth_err(U), ov = orth_err(V);
  worst_rec = fmax(worst_rec, rec);
  worst_orth = fmax(worst_orth, fmax(ou, ov));
  cr_assert(rec <= 1e-12, "%s: reconstruction error %g (relative)", what, rec);
  cr_assert(ou <= 1e-12 && ov <= 1e-12, "%s: orthogonality error U %g V %g", what, ou, ov);
  cr_assert(fabs(det3(U) - 1) <= 1e-12 && fabs(det3(V) - 1) <= 1e-12, "%s: det U = %.17g, det V = %.17g", what,
            det3(U), det3(V));
  cr_assert(s[0] >= s[1] && s[1] >= fabs(s[2]), "%s: order violated: %.17g %.17g %.17g", what, s[0], s[1], s[2]);
  cr_assert(s[1] >= 0, "%s: sigma1 = %g < 0", what, s[1]);
  double Fs[9], mF = maxabs(F);
  for (int i = 0; i < 9; i++) Fs[i] = mF > 0 ? F[i] / mF : 0;
  double dF = det3(Fs); /* sign of det F without overflow */
  if (fabs(dF) > 1e-9)
    cr_assert((dF > 0) == (s[2] > 0), "%s: sign of sigma2 (%g) differs from det F (%g)", what, s[2], dF);
  if (sigma) memcpy(sigma, s, sizeof s);
}

/* F = Q diag(s) R^T for random rotations; the computed sigma must be s. */
static void check_known(const double s_in[3], const char *what) {
  for (int t = 0; t < 200; t++) {
    double Q[9], R[9], F[9], s[3];
    rand_rot(Q);
    rand_rot(R);
    compose(Q, s_in, R, F);
    check_svd(F, s, what);
    double sc = fabs(s_in[0]);
    for (int k = 0; k < 3; k++)
      cr_assert(fabs(s[k] - s_in[k]) <= 1e-14 * sc, "%s: sigma%d = %.17g, expected %.17g", what, k, s[k], s_in[k]);
  }
}

Test(svd, random) {
  worst_rec = worst_orth = 0;
  for (int t = 0; t < 20000; t++) {
    double F[9];
    for (int i = 0; i < 9; i++) F[i] = nrand();
    check_svd(F, NULL, "random");
  }
  cr_log_info("random: worst reconstruction %.2e, orthogonality %.2e", worst_rec, worst_orth);
}

Test(svd, inverted) {
  int n_inv = 0;
  for (int t = 0; t < 5000; t++) {
    double F[9], s[3];
    for (int i = 0; i < 9; i++) F[i] = nrand();
    if (det3(F) > 0)
      for (int j = 0; j < 3; j++) F[j] = -F[j]; /* reflect a row */
    check_svd(F, s, "inverted");
    cr_assert(s[2] < 0, "inverted F must give sigma2 < 0, got %g", s[2]);
    n_inv++;
  }
  cr_assert_eq(n_inv, 5000);
  check_known((double[]){2.0, 1.0, -0.5}, "inverted known");
  check_known((double[]){1.0, 1.0, -1.0}, "inverted repeated (1,1,-1)");
  check_known((double[]){2.0, 1.0, -1.0}, "inverted repeated (2,1,-1)");
  /* pure reflections */
  double M[9] = {-1, 0, 0, 0, -1, 0, 0, 0, -1}, s[3];
  check_svd(M, s, "-I");
  cr_assert(s[0] == 1 && s[1] == 1 && s[2] == -1, "-I: sigma %g %g %g", s[0], s[1], s[2]);
}

Test(svd, rank_deficient) {
  for (int t = 0; t < 2000; t++) {
    double a[3], b[3], c[3], d[3], F[9], s[3];
    for (int i = 0; i < 3; i++) a[i] = nrand(), b[i] = nrand(), c[i] = nrand(), d[i] = nrand();
    for (int i = 0; i < 3; i++)
      for (int j = 0; j < 3; j++) F[3 * i + j] = a[i] * b[j];
    check_svd(F, s, "rank 1");
    cr_assert(s[1] <= 1e-14 * s[0] && fabs(s[2]) <= 1e-14 * s[0], "rank 1: sigma %g %g %g", s[0], s[1], s[2]);
    for (int i = 0; i < 3; i++)
      for (int j = 0; j < 3; j++) F[3 * i + j] = a[i] * b[j] + c[i] * d[j];
    check_svd(F, s, "rank 2");
    cr_assert(fabs(s[2]) <= 1e-14 * s[0], "rank 2: sigma %g %g %g", s[0], s[1], s[2]);
  }
  /* rank 0 */
  double Z[9] = {0}, U[9], V[9], s[3];
  bs_svd3(Z, U, s, V);
  cr_assert(s[0] == 0 && s[1] == 0 && s[2] == 0, "zero matrix: sigma %g %g %g", s[0], s[1], s[2]);
  check_svd(Z, NULL, "zero");
  /* single nonzero entries, a permutation, a rank-1 diagonal */
  for (int k = 0; k < 9; k++) {
    double E[9] = {0};
    E[k] = -3.5;
    check_svd(E, s, "single entry");
    cr_assert(s[0] == 3.5 && s[1] == 0 && s[2] == 0, "single entry %d: sigma %g %g %g", k, s[0], s[1], s[2]);
  }
  double P[9] = {0, 1, 0, 0, 0, 1, 1, 0, 0}; /* cyclic permutation, det +1 */
  check_svd(P, s, "permutation");
  cr_assert(fabs(s[0] - 1) < 1e-15 && fabs(s[1] - 1) < 1e-15 && fabs(s[2] - 1) < 1e-15);
  double P2[9] = {0, 1, 0, 1, 0, 0, 0, 0, 1}; /* transposition, det -1 */
  check_svd(P2, s, "transposition");
  cr_assert(fabs(s[2] + 1) < 1e-15, "transposition: sigma2 = %g", s[2]);
}

Test(svd, repeated) {
  check_known((double[]){2, 2, 1}, "diag(2,2,1)");
  check_known((double[]){1, 1, 1}, "rotation");
  check_known((double[]){2, 1, 1}, "diag(2,1,1)");
  check_known((double[]){3, 3, 3}, "3 I");
  check_known((double[]){1, 1, 0}, "diag(1,1,0)");
  check_known((double[]){1, 0, 0}, "diag(1,0,0)");
  check_known((double[]){1, 1 - 1e-12, 1 - 2e-12}, "nearly repeated");
  double I[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1}, U[9], V[9], s[3];
  bs_svd3(I, U, s, V);
  for (int i = 0; i < 9; i++) cr_assert(U[i] == I[i] && V[i] == I[i], "identity: U, V must be I exactly");
  cr_assert(s[0] == 1 && s[1] == 1 && s[2] == 1, "identity: sigma must be 1 exactly");
}

Test(svd, near_identity) {
  for (int t = 0; t < 2000; t++) {
    double F[9], s[3];
    for (int i = 0; i < 9; i++) F[i] = (i % 4 == 0) + 1e-9 * nrand();
    check_svd(F, s, "near identity");
    for (int k = 0; k < 3; k++) cr_assert(fabs(s[k] - 1) < 1e-8, "near identity: sigma%d = %g", k, s[k]);
  }
}

Test(svd, nearly_flat) {
  check_known((double[]){1.5, 0.7, 1e-8}, "flat +1e-8");
  check_known((double[]){1.5, 0.7, -1e-8}, "flat -1e-8");
  check_known((double[]){1.0, 1e-8, 1e-9}, "needle");
  check_known((double[]){1.0, 1.0, 1e-8}, "flat repeated");
  check_known((double[]){1.0, 1e-8, -1e-8}, "needle repeated inverted");
  /* relative accuracy of the smallest singular value (one-sided Jacobi) */
  for (int t = 0; t < 200; t++) {
    double Q[9], R[9], F[9], s[3], s_in[3] = {2.0, 0.5, 1e-10};
    rand_rot(Q);
    rand_rot(R);
    compose(Q, s_in, R, F);
    check_svd(F, s, "tiny sigma");
    cr_assert(fabs(s[2] - 1e-10) <= 1e-5 * 1e-10, "tiny sigma: %.17g", s[2]);
  }
}

Test(svd, extreme_scales) {
  const double scales[] = {1e-300, 1e-200, 1e-20, 1e20, 1e200, 1e300};
  for (int k = 0; k < 6; k++)
    for (int t = 0; t < 500; t++) {
      double F[9], s[3], dF;
      for (int i = 0; i < 9; i++) F[i] = nrand();
      dF = det3(F);
      for (int i = 0; i < 9; i++) F[i] *= scales[k];
      check_svd(F, s, "scaled");
      cr_assert((s[2] > 0) == (dF > 0), "scaled %g: sign of sigma2", scales[k]);
    }
}

Test(svd, non_finite) {
  const double bad[3] = {NAN, INFINITY, -INFINITY};
  for (int k = 0; k < 3; k++)
    for (int pos = 0; pos < 9; pos++) {
      double F[9] = {1, 2, 0.5, 0, 3, 0, 0.25, 0, 1}, U[9], V[9], s[3];
      F[pos] = bad[k];
      bs_svd3(F, U, s, V);
      cr_assert(isnan(s[0]) && isnan(s[1]) && isnan(s[2]) && isnan(U[0]) && isnan(V[8]),
                "a non-finite entry at %d must give NaN outputs", pos);
    }
}

/* A = Q diag(lambda) Q^T, Q a rotation, lambda sorted. */
static void check_eig(const double A[9], const char *what) {
  double lam[3], Q[9], R[9], d[9];
  bs_sym3_eig(A, lam, Q);
  compose(Q, lam, Q, R);
  for (int i = 0; i < 9; i++) d[i] = R[i] - A[i];
  double nA = fro(A);
  cr_assert(fro(d) <= 1e-13 * (nA > 0 ? nA : 1), "%s: eig reconstruction %g", what, fro(d) / nA);
  cr_assert(orth_err(Q) <= 1e-13 && fabs(det3(Q) - 1) <= 1e-13, "%s: Q not a rotation", what);
  cr_assert(lam[0] >= lam[1] && lam[1] >= lam[2], "%s: eigenvalues not sorted", what);
  /* bs_sym3_from_eig puts it back, exactly symmetric. */
  double B[9];
  bs_sym3_from_eig(lam, Q, B);
  for (int i = 0; i < 9; i++) d[i] = B[i] - A[i];
  cr_assert(fro(d) <= 1e-13 * (nA > 0 ? nA : 1), "%s: from_eig reconstruction %g", what, fro(d) / nA);
  cr_assert(B[1] == B[3] && B[2] == B[6] && B[5] == B[7], "%s: from_eig not symmetric", what);
}

Test(svd, sym3_eig) {
  for (int t = 0; t < 5000; t++) {
    double A[9];
    for (int i = 0; i < 3; i++)
      for (int j = i; j < 3; j++) A[3 * i + j] = A[3 * j + i] = nrand();
    check_eig(A, "random symmetric");
  }
  const double spectra[][3] = {{2, 2, 1}, {1, 1, 1}, {3, -1, -1}, {0, 0, 0}, {1, 0, -1}, {1e-12, 0, -1e-12}};
  for (int k = 0; k < 6; k++)
    for (int t = 0; t < 200; t++) {
      double Q[9], A[9], lam[3], Qo[9];
      rand_rot(Q);
      compose(Q, spectra[k], Q, A);
      for (int i = 0; i < 3; i++) /* exactly symmetric */
        for (int j = i + 1; j < 3; j++) A[3 * j + i] = A[3 * i + j];
      check_eig(A, "known spectrum");
      bs_sym3_eig(A, lam, Qo);
      for (int i = 0; i < 3; i++)
        cr_assert(fabs(lam[i] - spectra[k][i]) <= 1e-14 * (1 + fabs(spectra[k][0])), "eigenvalue %d: %.17g vs %g",
                  i, lam[i], spectra[k][i]);
    }
}

/* bs_svd3_batch is bs_svd3 bit for bit, on a mix of every kind of matrix in
 * one batch (so that lanes needing different sweep counts, the special lanes
 * that fall back to bs_svd3, and batch sizes that are not a multiple of the
 * lane count are all exercised). */
Test(svd, batch_bitwise) {
  enum { N = 4003 };
  static double F[9 * N], U[9 * N], s[3 * N], V[9 * N];
  for (int m = 0; m < N; m++) {
    double *A = F + 9 * m, Q[9], R[9], sv[3];
    switch (m % 9) {
    case 0: for (int i = 0; i < 9; i++) A[i] = nrand(); break;
    case 1: for (int i = 0; i < 9; i++) A[i] = (i % 4 == 0) + 0.1 * nrand(); break;
    case 2: /* rank deficient */
      for (int i = 0; i < 3; i++) A[3 * i] = nrand(), A[3 * i + 1] = 2 * A[3 * i], A[3 * i + 2] = -A[3 * i];
      break;
    case 3: /* repeated singular values, inverted */
      rand_rot(Q), rand_rot(R), sv[0] = sv[1] = 2, sv[2] = -2, compose(Q, sv, R, A);
      break;
    case 4: /* nearly flat */
      rand_rot(Q), rand_rot(R), sv[0] = 1, sv[1] = 0.5, sv[2] = 1e-12 * nrand(), compose(Q, sv, R, A);
      break;
    case 5: for (int i = 0; i < 9; i++) A[i] = ldexp(nrand(), (m % 3 ? 1 : -1) * 1010); break; /* special */
    case 6: for (int i = 0; i < 9; i++) A[i] = ldexp(nrand(), (m % 2 ? 1 : -1) * 990); break;  /* scaled */
    case 7: for (int i = 0; i < 9; i++) A[i] = (m % 4 == 0) ? 0.0 : (i == 4 ? NAN : nrand()); break;
    default: for (int i = 0; i < 9; i++) A[i] = (i % 4 == 0) + 1e-9 * nrand(); break;
    }
  }
  for (int n = 0; n <= 9; n++) { /* short batches, then the whole array */
    bs_svd3_batch(n, F, U, s, V);
    for (int m = 0; m < n; m++) {
      double u[9], v[9], ss[3];
      bs_svd3(F + 9 * m, u, ss, v);
      cr_assert(memcmp(u, U + 9 * m, sizeof u) == 0 && memcmp(v, V + 9 * m, sizeof v) == 0 &&
                    memcmp(ss, s + 3 * m, sizeof ss) == 0,
                "batch of %d: matrix %d differs from bs_svd3", n, m);
    }
  }
  bs_svd3_batch(N, F, U, s, V);
  for (int m = 0; m < N; m++) {
    double u[9], v[9], ss[3];
    bs_svd3(F + 9 * m, u, ss, v);
    cr_assert(memcmp(u, U + 9 * m, sizeof u) == 0 && memcmp(v, V + 9 * m, sizeof v) == 0 &&
                  memcmp(ss, s + 3 * m, sizeof ss) == 0,
              "matrix %d (kind %d) differs from bs_svd3", m, m % 9);
  }
}

/* ---- bs_polar3 ---- */

/* R is the polar rotation of F: orthogonal, det +1, R^T F symmetric positive
 * definite (which fixes it), and U V^T of bs_svd3. */
static void check_polar(const double F[9], double cond, const char *what) {
  double R[9], U[9], s[3], V[9], S[9], lam[3], Q[9];
  cr_assert(bs_polar3(F, R) == 1, "%s: bs_polar3 declined (cond %g)", what, cond);
  cr_assert(orth_err(R) <= 1e-14, "%s: R^T R - I = %g", what, orth_err(R));
  cr_assert(fabs(det3(R) - 1) <= 1e-14, "%s: det R = %.17g", what, det3(R));
  const double nF = fro(F);
  for (int i = 0; i < 3; i++)
    for (int j = 0; j < 3; j++) {
      double v = 0;
      for (int k = 0; k < 3; k++) v += R[3 * k + i] * F[3 * k + j];
      S[3 * i + j] = v;
    }
  for (int i = 0; i < 3; i++)
    for (int j = i + 1; j < 3; j++)
      cr_assert(fabs(S[3 * i + j] - S[3 * j + i]) <= 1e-14 * cond * nF, "%s: R^T F not symmetric (%g)", what,
                fabs(S[3 * i + j] - S[3 * j + i]) / nF);
  bs_sym3_eig(S, lam, Q);
  cr_assert(lam[2] > 0, "%s: R^T F has eigenvalue %g", what, lam[2]);
  bs_svd3(F, U, s, V);
  for (int i = 0; i < 3; i++)
    for (int j = 0; j < 3; j++) {
      const double uv = U[3 * i] * V[3 * j] + U[3 * i + 1] * V[3 * j + 1] + U[3 * i + 2] * V[3 * j + 2];
      cr_assert(fabs(uv - R[3 * i + j]) <= 1e-15 * cond * 10, "%s: R differs from U V^T by %g (cond %g)", what,
                fabs(uv - R[3 * i + j]), cond);
    }
}

Test(svd, polar_rotation) {
  int accepted = 0;
  for (int t = 0; t < 20000; t++) {
    double Q[9], P[9], sv[3], F[9];
    rand_rot(Q);
    rand_rot(P);
    /* singular values log-uniform over up to 9 decades, at scales 1e-7..1e7;
     * accepted exactly when det F > 1e-9 ||F||^3 (margins of 1% skipped) */
    const double scale = pow(10.0, 14 * urand() - 7), spread = pow(10.0, 9 * urand());
    for (int k = 0; k < 3; k++) sv[k] = pow(spread, urand() - 1); /* in [1/spread, 1] */
    compose(Q, sv, P, F);
    for (int i = 0; i < 9; i++) F[i] *= scale;
    const double n2 = sv[0] * sv[0] + sv[1] * sv[1] + sv[2] * sv[2], r = sv[0] * sv[1] * sv[2] / (n2 * sqrt(n2));
    const double cond = fmax(sv[0], fmax(sv[1], sv[2])) / fmin(sv[0], fmin(sv[1], sv[2]));
    if (r > 1.01e-9) {
      double R[9];
      cr_assert(bs_polar3(F, R) == 1, "declined sigma = %.17g %.17g %.17g (scale %g, det F / ||F||^3 = %g)", sv[0],
                sv[1], sv[2], scale, r);
      check_polar(F, cond, "random");
      accepted++;
    } else if (r < 0.99e-9) {
      double R[9];
      cr_assert(bs_polar3(F, R) == 0, "accepted det F / ||F||^3 = %g", r);
    }
  }
  cr_assert(accepted > 5000 && accepted < 19500, "%d of 20000 in range: the sample misses one side", accepted);
  for (int t = 0; t < 2000; t++) { /* near rest and near a rotation */
    double Q[9], F[9], A[9];
    rand_rot(Q);
    const double eps = pow(10.0, -1 - 11 * urand()); /* 1e-12 .. 0.1 */
    for (int i = 0; i < 9; i++) A[i] = (i % 4 == 0) + eps * nrand();
    for (int i = 0; i < 3; i++)
      for (int j = 0; j < 3; j++) F[3 * i + j] = Q[3 * i] * A[j] + Q[3 * i + 1] * A[3 + j] + Q[3 * i + 2] * A[6 + j];
    check_polar(F, 1.0 + 10 * eps, "near a rotation");
  }
  const double I[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  double R[9];
  cr_assert(bs_polar3(I, R) == 1 && memcmp(R, I, sizeof R) == 0, "the polar rotation of I is not I exactly");
}

/* Outside its range bs_polar3 returns 0 and leaves R alone. */
Test(svd, polar_declines) {
  double Q[9], P[9], F[9], R[9];
  rand_rot(Q);
  rand_rot(P);
  const double inv[3] = {2, 1, -0.5}, flat[3] = {1, 1, 1e-9}, far[3] = {1e16, 2e16, 3e16}, tiny[3] = {1e-16, 2e-16, 1e-16};
  const double *cases[4] = {inv, flat, far, tiny};
  const char *names[4] = {"inverted", "nearly flat", "||F|| beyond 1e15", "||F|| below 1e-15"};
  for (int c = 0; c < 4; c++) {
    compose(Q, cases[c], P, F);
    for (int i = 0; i < 9; i++) R[i] = 7.0;
    cr_assert(bs_polar3(F, R) == 0, "%s: bs_polar3 accepted", names[c]);
    for (int i = 0; i < 9; i++) cr_assert(R[i] == 7.0, "%s: R was written", names[c]);
  }
  double Z[9] = {0}, N[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1}, Inf[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  N[4] = NAN;
  Inf[8] = INFINITY;
  cr_assert(bs_polar3(Z, R) == 0, "F = 0 accepted");
  cr_assert(bs_polar3(N, R) == 0, "F with NaN accepted");
  cr_assert(bs_polar3(Inf, R) == 0, "F with Inf accepted");
}

/* bs_polar3_batch is bs_polar3 bit for bit, lanes of every kind mixed. */
Test(svd, polar_batch_bitwise) {
  enum { N = 2003 };
  static double F[9 * N], R[9 * N];
  static int ok[N];
  for (int m = 0; m < N; m++) {
    double *A = F + 9 * m, Q[9], P[9], sv[3];
    switch (m % 6) {
    case 0: for (int i = 0; i < 9; i++) A[i] = (i % 4 == 0) + 0.01 * nrand(); break;
    case 1: for (int i = 0; i < 9; i++) A[i] = (i % 4 == 0) + 0.3 * nrand(); break; /* some inverted */
    case 2:
      rand_rot(Q), rand_rot(P), sv[0] = 3, sv[1] = 1, sv[2] = 1e-3, compose(Q, sv, P, A);
      break;
    case 3: for (int i = 0; i < 9; i++) A[i] = (i % 4 == 0) + 1e-12 * nrand(); break;
    case 4: for (int i = 0; i < 9; i++) A[i] = (i == 4 && m % 4 == 0) ? NAN : nrand(); break;
    default: rand_rot(A); break;
    }
  }
  int accepted = 0;
  for (int n = 0; n <= N; n = n < 9 ? n + 1 : N) {
    for (int i = 0; i < 9 * n; i++) R[i] = -1.0;
    bs_polar3_batch(n, F, R, ok);
    for (int m = 0; m < n; m++) {
      double r[9];
      const int o = bs_polar3(F + 9 * m, r);
      cr_assert(o == ok[m], "batch of %d: matrix %d: ok %d, bs_polar3 %d", n, m, ok[m], o);
      if (o) cr_assert(memcmp(r, R + 9 * m, sizeof r) == 0, "batch of %d: matrix %d differs", n, m);
      accepted += (n == N) & o;
    }
    if (n == N) break;
  }
  cr_assert(accepted > N / 2 && accepted < N, "%d of %d accepted: the mix does not exercise both paths", accepted, N);
}
