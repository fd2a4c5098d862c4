/* Constitutive models: parameter checks, rest state, rotation invariance,
 * P against central differences of Psi and dP/dF against central differences
 * of P with O(h^2) convergence over h = 1e-2 .. 1e-4 (random, inverted, nearly
 * flat, repeated singular values, identity), rest stiffness = linear
 * elasticity, continuity across inversion and across the neo-Hookean J0, and
 * the PSD projection. */
#include <criterion/criterion.h>
#include <float.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "bs_material.h"
#include "bs_svd.h"

/* ---- deterministic random numbers, small matrices ---- */

#define BS_TEST_SEED 0x2545F4914F6CDD1Dull
#include "test_random.h"
static void compose(const double Q[9], const double s[3], const double R[9], double F[9]) {
  for (int i = 0; i < 3; i++)
    for (int j = 0; j < 3; j++) {
      double v = 0;
      for (int k = 0; k < 3; k++) v += Q[3 * i + k] * s[k] * R[3 * j + k];
      F[3 * i + j] = v;
    }
}
static void matmul(const double A[9], const double B[9], double C[9]) {
  for (int i = 0; i < 3; i++)
    for (int j = 0; j < 3; j++) C[3 * i + j] = A[3 * i] * B[j] + A[3 * i + 1] * B[3 + j] + A[3 * i + 2] * B[6 + j];
}
static double maxabs(int n, const double *a) {
  double m = 0;
  for (int i = 0; i < n; i++) m = fmax(m, fabs(a[i]));
  return m;
}
static double maxdiff(int n, const double *a, const double *b) {
  double m = 0;
  for (int i = 0; i < n; i++) m = fmax(m, fabs(a[i] - b[i]));
  return m;
}

#include "test_dense.h"

/* ---- materials and test points ---- */

static const bs_model models[5] = {BS_MODEL_FIXED_COROTATED, BS_MODEL_COROTATED, BS_MODEL_NEO_HOOKEAN,
                                   BS_MODEL_STABLE_NEO_HOOKEAN, BS_MODEL_LINEAR};

static bs_material make(bs_model model, double E, double nu) {
  bs_material m;
  bs_error err = {0};
  cr_assert_eq(bs_material_init(model, E, nu, 1000, &m, &err), BS_OK, "%s", err.msg);
  return m;
}

static int corotated_family(bs_model m) { return m == BS_MODEL_FIXED_COROTATED || m == BS_MODEL_COROTATED; }

/* Signed singular values of the test points; F = Q diag(s) R^T with random
 * rotations. ridge = 1 marks s1 = -s2, where the corotated energies have a
 * ridge (not differentiable): those points are skipped for them. */
typedef struct {
  const char *name;
  double s[3];
  int ridge;
} point;
static const point points[] = {
    {"random", {1.4, 0.9, 0.6}, 0},
    {"stretched", {2.5, 1.6, 1.1}, 0},
    {"compressed", {0.6, 0.45, 0.3}, 0},
    {"inverted", {1.3, 0.8, -0.5}, 0},
    {"inverted strongly", {1.2, 1.0, -0.9}, 0},
    {"nearly flat", {1.2, 0.7, 1e-8}, 0},
    {"nearly flat inverted", {1.2, 0.7, -1e-8}, 0},
    {"repeated top", {1.2, 1.2, 0.8}, 0},
    {"repeated bottom", {1.3, 0.7, 0.7}, 0},
    {"repeated all", {0.9, 0.9, 0.9}, 0},
    {"repeated inverted", {1.3, 1.3, -0.6}, 0},
    {"repeated on the inversion ridge", {1.2, 0.7, -0.7}, 1},
    {"identity", {1, 1, 1}, 0},
};
enum { N_POINTS = sizeof points / sizeof points[0] };

/* ---- finite differences ---- */

enum { NH = 8 };
static double hval(int k) { return 1e-2 * pow(10.0, -2.0 * k / (NH - 1)); } /* 1e-2 .. 1e-4 */

/* Directions of differentiation: the 9 coordinate directions and 3 random
 * unit ones (along a single entry, det F is linear, so some energies are
 * polynomials of degree 2 there and central differences are exact; along a
 * general direction they are not). Refreshed for every test point. */
enum { ND = 12 };
static double dirs[ND][9];
static void new_directions(void) {
  for (int d = 0; d < ND; d++) {
    double n = 0;
    for (int b = 0; b < 9; b++) {
      dirs[d][b] = d < 9 ? (b == d) : nrand();
      n += dirs[d][b] * dirs[d][b];
    }
    for (int b = 0; b < 9; b++) dirs[d][b] /= sqrt(n);
  }
}
static void step(const double F[9], const double D[9], double h, double out[9]) {
  for (int b = 0; b < 9; b++) out[b] = F[b] + h * D[b];
}

/* max_d |(Psi(F + h D) - Psi(F - h D)) / 2h - P : D| */
static double fd_err_P(const bs_material *m, const double F[9], const double P[9], double h) {
  double e = 0;
  for (int d = 0; d < ND; d++) {
    double Fp[9], Fm[9], PD = 0;
    step(F, dirs[d], h, Fp);
    step(F, dirs[d], -h, Fm);
    for (int b = 0; b < 9; b++) PD += P[b] * dirs[d][b];
    double fd = (bs_material_psi(m, Fp) - bs_material_psi(m, Fm)) / (2 * h);
    e = fmax(e, fabs(fd - PD));
  }
  return e;
}

/* max_{d,a} |(P_a(F + h D) - P_a(F - h D)) / 2h - (dPdF D)_a| */
static double fd_err_K(const bs_material *m, const double F[9], const double K[81], double h) {
  double e = 0;
  for (int d = 0; d < ND; d++) {
    double Fp[9], Fm[9], Pp[9], Pm[9];
    step(F, dirs[d], h, Fp);
    step(F, dirs[d], -h, Fm);
    bs_material_psi_P(m, Fp, Pp);
    bs_material_psi_P(m, Fm, Pm);
    for (int a = 0; a < 9; a++) {
      double KD = 0;
      for (int b = 0; b < 9; b++) KD += K[9 * a + b] * dirs[d][b];
      e = fmax(e, fabs((Pp[a] - Pm[a]) / (2 * h) - KD));
    }
  }
  return e;
}

/* The FD errors e[k] at h_k must fall as h^2: the least-squares slope of
 * log e against log h, over the h where e is above the round-off level
 * (1e3 eps fscale / h, fscale the size of the differenced function), is in
 * [1.8, 2.2]. When even the largest h gives an error below 1e-9 dscale (dscale
 * the size of the derivative), the differences are exact up to round-off
 * (a quadratic energy) and every e[k] must stay below that. Returns the slope
 * (2 for the exact case). */
static double check_order(const double e[NH], double dscale, double fscale, const char *what) {
  if (e[0] <= 1e-9 * dscale) {
    for (int k = 0; k < NH; k++)
      cr_assert(e[k] <= 1e-9 * dscale, "%s: FD error %g at h = %g (exact at h = 1e-2)", what, e[k], hval(k));
    return 2.0;
  }
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  int n = 0;
  for (int k = 0; k < NH; k++) {
    if (!(e[k] > 1e3 * DBL_EPSILON * fscale / hval(k))) continue;
    double x = log(hval(k)), y = log(e[k]);
    sx += x, sy += y, sxx += x * x, sxy += x * y;
    n++;
  }
  cr_assert(n >= 3, "%s: only %d step sizes above round-off (errors %g .. %g)", what, n, e[0], e[NH - 1]);
  double slope = (n * sxy - sx * sy) / (n * sxx - sx * sx);
  cr_assert(slope > 1.8 && slope < 2.2, "%s: FD error slope %.3f (errors %g at h=1e-2, %g at h=1e-4), expected 2",
            what, slope, e[0], e[NH - 1]);
  return slope;
}

/* Range of the fitted slopes and count of round-off-exact cases, logged. */
static double slope_lo = INFINITY, slope_hi = -INFINITY;
static int n_exact, n_fit;
static void record(double e0, double dscale, double slope) {
  if (e0 <= 1e-9 * dscale) {
    n_exact++;
    return;
  }
  n_fit++;
  slope_lo = fmin(slope_lo, slope);
  slope_hi = fmax(slope_hi, slope);
}

/* P against FD of Psi and dPdF against FD of P, at F, for material m. */
static void check_fd_at(const bs_material *m, const double F[9], int check_K, const char *what) {
  double P[9], K[81], e[NH];
  new_directions();
  double psi = bs_material_psi_P(m, F, P);
  bs_material_dPdF(m, F, 0, K);
  cr_assert(isfinite(psi), "%s: psi not finite", what);
  const double Fmax = maxabs(9, F);
  const double Pscale = fmax(maxabs(9, P), m->mu), Kscale = fmax(maxabs(81, K), m->mu);
  char buf[256];
  for (int k = 0; k < NH; k++) e[k] = fd_err_P(m, F, P, hval(k));
  snprintf(buf, sizeof buf, "%s %s: P vs FD of psi", bs_model_name(m->model), what);
  record(e[0], Pscale, check_order(e, Pscale, fmax(fabs(psi), Pscale * Fmax), buf));
  if (!check_K) return;
  for (int k = 0; k < NH; k++) e[k] = fd_err_K(m, F, K, hval(k));
  snprintf(buf, sizeof buf, "%s %s: dPdF vs FD of P", bs_model_name(m->model), what);
  record(e[0], Kscale, check_order(e, Kscale, fmax(Pscale, Kscale * Fmax), buf));
}

static void check_fd_model(bs_model model) {
  const double params[2][2] = {{1.0, 0.3}, {1e5, 0.45}};
  for (int pset = 0; pset < 2; pset++) {
    bs_material m = make(model, params[pset][0], params[pset][1]);
    for (int p = 0; p < N_POINTS; p++) {
      if (points[p].ridge && corotated_family(model)) continue;
      for (int rep = 0; rep < 3; rep++) {
        double Q[9], R[9], F[9];
        rand_rot(Q);
        rand_rot(R);
        compose(Q, points[p].s, R, F);
        if (p == N_POINTS - 1 && rep == 0) /* the identity itself, exactly */
          for (int i = 0; i < 9; i++) F[i] = (i % 4 == 0);
        check_fd_at(&m, F, 1, points[p].name);
      }
    }
    /* general random F (Gaussian entries), away from the corotated ridge and
     * from the neo-Hookean J0 (where Psi is only C^2: dPdF FD is O(h) there) */
    int done = 0;
    while (done < 20) {
      double F[9], U[9], V[9], s[3];
      for (int i = 0; i < 9; i++) F[i] = (i % 4 == 0) + 0.6 * nrand();
      bs_svd3(F, U, s, V);
      if (corotated_family(model) && s[1] + s[2] < 0.2) continue;
      if (model == BS_MODEL_NEO_HOOKEAN && fabs(s[0] * s[1] * s[2] - m.J0) < 0.1) continue;
      if (s[0] > 3) continue;
      check_fd_at(&m, F, 1, "gaussian");
      done++;
    }
  }
  cr_log_info("%s: %d FD checks with fitted slopes in [%.3f, %.3f], %d exact to round-off", bs_model_name(model),
              n_fit, slope_lo, slope_hi, n_exact);
}

Test(material_fd, fixed_corotated) { check_fd_model(BS_MODEL_FIXED_COROTATED); }
Test(material_fd, corotated) { check_fd_model(BS_MODEL_COROTATED); }
Test(material_fd, neo_hookean) { check_fd_model(BS_MODEL_NEO_HOOKEAN); }
Test(material_fd, stable_neo_hookean) { check_fd_model(BS_MODEL_STABLE_NEO_HOOKEAN); }
Test(material_fd, linear) { check_fd_model(BS_MODEL_LINEAR); }

/* ---- parameters and names ---- */

static void expect_init_error(bs_model model, double E, double nu, double rho, const char *name) {
  bs_material m;
  bs_error err = {0};
  int rc = bs_material_init(model, E, nu, rho, &m, &err);
  cr_assert_eq(rc, BS_EINPUT, "E=%g nu=%g rho=%g should fail with BS_EINPUT (got %d)", E, nu, rho, rc);
  cr_assert(strstr(err.msg, name) != NULL, "message must name \"%s\": %s", name, err.msg);
}

Test(material, init_errors) {
  expect_init_error(BS_MODEL_NEO_HOOKEAN, 1e5, 0.5, 1000, "poisson");
  expect_init_error(BS_MODEL_NEO_HOOKEAN, 1e5, 0.6, 1000, "poisson");
  expect_init_error(BS_MODEL_LINEAR, 1e5, -1.0, 1000, "poisson");
  expect_init_error(BS_MODEL_LINEAR, 1e5, NAN, 1000, "poisson");
  expect_init_error(BS_MODEL_FIXED_COROTATED, 0, 0.3, 1000, "youngs");
  expect_init_error(BS_MODEL_FIXED_COROTATED, -5, 0.3, 1000, "youngs");
  expect_init_error(BS_MODEL_FIXED_COROTATED, NAN, 0.3, 1000, "youngs");
  expect_init_error(BS_MODEL_FIXED_COROTATED, INFINITY, 0.3, 1000, "youngs");
  expect_init_error(BS_MODEL_FIXED_COROTATED, 1e5, 0.3, 0, "density");
  expect_init_error(BS_MODEL_FIXED_COROTATED, 1e5, 0.3, -1, "density");
  expect_init_error(BS_MODEL_FIXED_COROTATED, 1e5, 0.3, NAN, "density");
  /* model conditions for an energy bounded below */
  expect_init_error(BS_MODEL_FIXED_COROTATED, 1e5, -0.2, 1000, "poisson");
  expect_init_error(BS_MODEL_NEO_HOOKEAN, 1e5, -0.45, 1000, "poisson");
  expect_init_error((bs_model)17, 1e5, 0.3, 1000, "model");
  /* nearly incompressible and auxetic values that are valid */
  bs_material m = make(BS_MODEL_NEO_HOOKEAN, 1e5, 0.499);
  cr_assert(isfinite(m.lambda) && m.lambda > 400 * m.mu, "nu = 0.499: lambda = %g, mu = %g", m.lambda, m.mu);
  m = make(BS_MODEL_FIXED_COROTATED, 2.6, 0.3);
  cr_assert(fabs(m.mu - 1.0) < 1e-15 && fabs(m.lambda - 1.5) < 1e-15, "Lame: mu %g lambda %g", m.mu, m.lambda);
  cr_assert_eq(m.J0, BS_NEO_HOOKEAN_J0);
  m = make(BS_MODEL_STABLE_NEO_HOOKEAN, 1e5, -0.9);
  m = make(BS_MODEL_COROTATED, 1e5, -0.9);
  m = make(BS_MODEL_LINEAR, 1e5, -0.9);
  m = make(BS_MODEL_NEO_HOOKEAN, 1e5, -0.25);
  m = make(BS_MODEL_FIXED_COROTATED, 1e5, 0.0);
  cr_assert_eq(m.lambda, 0.0);
}

Test(material, names) {
  for (int i = 0; i < 5; i++) {
    bs_model out = (bs_model)-1;
    bs_error err = {0};
    cr_assert_eq(bs_model_parse(bs_model_name(models[i]), &out, &err), BS_OK, "%s", err.msg);
    cr_assert_eq(out, models[i]);
  }
  cr_assert_str_eq(bs_model_name(BS_MODEL_STABLE_NEO_HOOKEAN), "stable_neo_hookean");
  cr_assert_str_eq(bs_model_name((bs_model)42), "unknown");
  bs_model out;
  bs_error err = {0};
  cr_assert_eq(bs_model_parse("mooney_rivlin", &out, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "mooney_rivlin") && strstr(err.msg, "fixed_corotated"), "message: %s", err.msg);
  cr_assert_eq(bs_model_parse(NULL, &out, &err), BS_EINPUT);
  cr_assert_eq(bs_model_parse("Neo_Hookean", &out, &err), BS_EINPUT);
}

/* ---- rest state, invariance, linearization ---- */

Test(material, rest_state) {
  for (int i = 0; i < 5; i++) {
    bs_material m = make(models[i], 1e5, 0.3);
    double I[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1}, P[9];
    double psi = bs_material_psi_P(&m, I, P);
    cr_assert(psi == 0 && bs_material_psi(&m, I) == 0, "%s: psi(I) = %g", bs_model_name(m.model), psi);
    cr_assert(maxabs(9, P) == 0, "%s: P(I) = %g", bs_model_name(m.model), maxabs(9, P));
    if (models[i] == BS_MODEL_LINEAR) continue;
    for (int t = 0; t < 20; t++) { /* every rotation is a rest state */
      double Q[9];
      rand_rot(Q);
      psi = bs_material_psi_P(&m, Q, P);
      cr_assert(fabs(psi) <= 1e-13 * m.mu && maxabs(9, P) <= 1e-13 * m.mu, "%s: psi(Q) = %g, |P(Q)| = %g",
                bs_model_name(m.model), psi, maxabs(9, P));
    }
  }
}

Test(material, rest_stiffness_is_linear) {
  const double nus[3] = {0.0, 0.3, 0.45};
  for (int k = 0; k < 3; k++) {
    bs_material lin = make(BS_MODEL_LINEAR, 1e5, nus[k]);
    double I[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1}, KL[81], K[81];
    bs_material_dPdF(&lin, I, 0, KL);
    for (int i = 0; i < 4; i++) {
      bs_material m = make(models[i], 1e5, nus[k]);
      bs_material_dPdF(&m, I, 0, K);
      double d = maxdiff(81, K, KL);
      cr_assert(d <= 1e-12 * maxabs(81, KL), "%s nu=%g: dPdF(I) differs from linear by %g", bs_model_name(m.model),
                nus[k], d);
      bs_material_dPdF(&m, I, 1, K);
      d = maxdiff(81, K, KL);
      cr_assert(d <= 1e-12 * maxabs(81, KL), "%s nu=%g: projected dPdF(I) differs from linear by %g",
                bs_model_name(m.model), nus[k], d);
    }
  }
}

Test(material, rotation_invariance) {
  for (int i = 0; i < 4; i++) {
    bs_material m = make(models[i], 1e5, 0.3);
    for (int t = 0; t < 200; t++) {
      double F[9], Q[9], QF[9], FQ[9], P[9], PQF[9], PFQ[9], QP[9], PQ[9];
      for (int j = 0; j < 9; j++) F[j] = (j % 4 == 0) + 0.5 * nrand();
      rand_rot(Q);
      matmul(Q, F, QF);
      matmul(F, Q, FQ);
      double psi = bs_material_psi_P(&m, F, P);
      double psi_qf = bs_material_psi_P(&m, QF, PQF), psi_fq = bs_material_psi_P(&m, FQ, PFQ);
      double sc = fmax(fabs(psi), m.mu);
      cr_assert(fabs(psi_qf - psi) <= 1e-12 * sc && fabs(psi_fq - psi) <= 1e-12 * sc,
                "%s: psi(F) = %.17g, psi(QF) = %.17g, psi(FQ) = %.17g", bs_model_name(m.model), psi, psi_qf, psi_fq);
      matmul(Q, P, QP); /* P(QF) = Q P(F), P(FQ) = P(F) Q */
      matmul(P, Q, PQ);
      double pc = fmax(maxabs(9, P), m.mu);
      cr_assert(maxdiff(9, PQF, QP) <= 1e-11 * pc && maxdiff(9, PFQ, PQ) <= 1e-11 * pc, "%s: P not objective",
                bs_model_name(m.model));
    }
  }
}

/* ---- continuity ---- */

static double fnorm(int n, const double *a) {
  double v = 0;
  for (int i = 0; i < n; i++) v += a[i] * a[i];
  return sqrt(v);
}

/* Psi and P across the inversion surface (s2 = 0) and, for every model, Psi
 * across the ridge s1 = -s2 where the SVD changes which value is negative.
 * Continuity: the change is bounded by the derivative's size times |dF|
 * (mean value theorem, 2x slack), and shrinks with the distance. */
Test(material, continuity) {
  double Q[9], R[9];
  rand_rot(Q);
  rand_rot(R);
  for (int i = 0; i < 5; i++) {
    bs_material m = make(models[i], 1e5, 0.3);
    for (int surf = 0; surf < 2; surf++) {
      double prev = INFINITY;
      for (double dl = 1e-3; dl >= 1e-11; dl *= 1e-2) {
        double sp[3] = {1.1, 0.9, dl}, sm[3] = {1.1, 0.9, -dl};
        if (surf == 1) { /* s = (1.1, 0.8 + t, -0.8): crosses s1 = |s2| at t = 0 */
          sp[1] = 0.8 + dl, sp[2] = -0.8;
          sm[1] = 0.8 - dl, sm[2] = -0.8; /* sorts to (1.1, 0.8, -(0.8 - dl)) */
        }
        double Fp[9], Fm[9], Pp[9], Pm[9], Kp[81], Km[81], dF[9], dP[9];
        compose(Q, sp, R, Fp);
        compose(Q, sm, R, Fm);
        double jump = fabs(bs_material_psi_P(&m, Fp, Pp) - bs_material_psi_P(&m, Fm, Pm));
        bs_material_dPdF(&m, Fp, 0, Kp);
        bs_material_dPdF(&m, Fm, 0, Km);
        for (int a = 0; a < 9; a++) dF[a] = Fp[a] - Fm[a], dP[a] = Pp[a] - Pm[a];
        const double nF = fnorm(9, dF), round = 1e-12 * (m.mu + fabs(m.lambda));
        cr_assert(jump <= 2 * fmax(fnorm(9, Pp), fnorm(9, Pm)) * nF + round,
                  "%s: psi jumps by %g across %s at distance %g (|P| %g)", bs_model_name(m.model), jump,
                  surf ? "s1 = -s2" : "s2 = 0", dl, fnorm(9, Pp));
        if (surf == 0)
          cr_assert(fnorm(9, dP) <= 2 * fmax(fnorm(81, Kp), fnorm(81, Km)) * nF + round,
                    "%s: P jumps by %g across s2 = 0 at distance %g", bs_model_name(m.model), fnorm(9, dP), dl);
        cr_assert(jump <= prev, "%s: the jump must shrink with the distance", bs_model_name(m.model));
        prev = jump;
      }
    }
  }
}

/* The neo-Hookean extension: Psi C^2 across J = J0 (Psi, P, dPdF continuous),
 * convex and decreasing in J below J0, finite for J <= 0. */
Test(material, neo_hookean_extension) {
  const double nus[3] = {0.0, 0.3, 0.45};
  for (int k = 0; k < 3; k++) {
    bs_material m = make(BS_MODEL_NEO_HOOKEAN, 1e5, nus[k]);
    double Q[9], R[9];
    rand_rot(Q);
    rand_rot(R);
    for (double dl = 1e-4; dl >= 1e-10; dl *= 1e-2) {
      /* s = (1.2, 0.8, s2) with J = 0.96 s2 = J0 (1 +- dl) */
      double sp[3] = {1.2, 0.8, m.J0 * (1 + dl) / 0.96}, sm[3] = {1.2, 0.8, m.J0 * (1 - dl) / 0.96};
      double Fp[9], Fm[9], Pp[9], Pm[9], Kp[81], Km[81];
      compose(Q, sp, R, Fp);
      compose(Q, sm, R, Fm);
      double jump = fabs(bs_material_psi_P(&m, Fp, Pp) - bs_material_psi_P(&m, Fm, Pm));
      bs_material_dPdF(&m, Fp, 0, Kp);
      bs_material_dPdF(&m, Fm, 0, Km);
      double kjump = maxdiff(81, Kp, Km), pjump = maxdiff(9, Pp, Pm);
      double sc = maxabs(81, Kp);
      cr_assert(jump <= 10 * sc * dl + 1e-12 * sc, "nu=%g: psi jumps by %g at J0 (dl %g)", nus[k], jump, dl);
      cr_assert(pjump <= 10 * sc * dl + 1e-11 * sc, "nu=%g: P jumps by %g at J0 (dl %g)", nus[k], pjump, dl);
      cr_assert(kjump <= 100 * sc * dl + 1e-9 * sc, "nu=%g: dPdF jumps by %g at J0 (dl %g)", nus[k], kjump, dl);
    }
    /* ghat(J) = Psi(diag(1,1,J)) - mu/2 (J^2 - 1): convex, decreasing below J0 */
    double prev2 = NAN, prev1 = NAN;
    for (double J = -3.0; J <= m.J0 + 0.3; J += 0.01) {
      double F[9] = {1, 0, 0, 0, 1, 0, 0, 0, J}, P[9];
      double psi = bs_material_psi_P(&m, F, P);
      cr_assert(isfinite(psi) && isfinite(P[8]), "psi not finite at J = %g", J);
      double gh = psi - 0.5 * m.mu * (J * J - 1);
      double dg = P[8] - m.mu * J; /* ghat'(J) */
      if (J < m.J0) cr_assert(dg < 0, "nu=%g: ghat'(%g) = %g must be < 0 below J0", nus[k], J, dg);
      if (!isnan(prev2))
        cr_assert(gh - 2 * prev1 + prev2 >= -1e-9 * m.mu, "nu=%g: ghat not convex at J = %g", nus[k], J);
      prev2 = prev1;
      prev1 = gh;
    }
  }
}

/* ---- PSD projection ---- */

static void check_projection(const bs_material *m, const double F[9], const char *what) {
  double K[81], Kp[81], lam[9], lamp[9], Qe[81];
  bs_material_dPdF(m, F, 0, K);
  bs_material_dPdF(m, F, 1, Kp);
  for (int i = 0; i < 81; i++) cr_assert(isfinite(Kp[i]), "%s: projected dPdF not finite", what);
  for (int a = 0; a < 9; a++)
    for (int b = 0; b < 9; b++)
      cr_assert(Kp[9 * a + b] == Kp[9 * b + a] && K[9 * a + b] == K[9 * b + a], "%s: dPdF not symmetric", what);
  sym_eig_dense(9, Kp, lamp, NULL);
  double lmax = maxabs(9, lamp), lmin = lamp[0];
  for (int i = 1; i < 9; i++) lmin = fmin(lmin, lamp[i]);
  cr_assert(lmin >= -1e-10 * lmax, "%s %s: projected dPdF has eigenvalue %g (max %g)", bs_model_name(m->model), what,
            lmin, lmax);
  /* the projection is the exact one: Q max(Lambda, 0) Q^T of the dense matrix */
  sym_eig_dense(9, K, lam, Qe);
  double ref[81], d;
  for (int a = 0; a < 9; a++)
    for (int b = 0; b < 9; b++) {
      double v = 0;
      for (int k = 0; k < 9; k++) v += fmax(lam[k], 0) * Qe[9 * a + k] * Qe[9 * b + k];
      ref[9 * a + b] = v;
    }
  d = maxdiff(81, Kp, ref);
  cr_assert(d <= 1e-9 * fmax(maxabs(81, K), m->mu), "%s %s: projection differs from the dense one by %g",
            bs_model_name(m->model), what, d);
}

Test(material, psd_projection) {
  for (int i = 0; i < 5; i++) {
    bs_material m = make(models[i], 1e5, 0.3);
    for (int p = 0; p < N_POINTS; p++) {
      double Q[9], R[9], F[9];
      rand_rot(Q);
      rand_rot(R);
      compose(Q, points[p].s, R, F);
      check_projection(&m, F, points[p].name);
    }
    for (int t = 0; t < 200; t++) {
      double F[9];
      for (int j = 0; j < 9; j++) F[j] = (j % 4 == 0) + 0.8 * nrand();
      check_projection(&m, F, "gaussian");
    }
  }
}

/* A PSD dPdF comes back unchanged (bit for bit): F = I for every model, a
 * moderate stretch for fixed_corotated; an indefinite one is changed. */
Test(material, psd_input_unchanged) {
  double I[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1}, K[81], Kp[81], lam[9];
  for (int i = 0; i < 5; i++) {
    bs_material m = make(models[i], 1e5, 0.3);
    bs_material_dPdF(&m, I, 0, K);
    bs_material_dPdF(&m, I, 1, Kp);
    cr_assert(memcmp(K, Kp, sizeof K) == 0, "%s: projection changed the PSD dPdF(I)", bs_model_name(m.model));
  }
  bs_material m = make(BS_MODEL_FIXED_COROTATED, 1e5, 0.3);
  double Q[9], R[9], F[9], s[3] = {1.2, 1.1, 1.05};
  rand_rot(Q);
  rand_rot(R);
  compose(Q, s, R, F);
  bs_material_dPdF(&m, F, 0, K);
  sym_eig_dense(9, K, lam, NULL);
  for (int k = 0; k < 9; k++) cr_assert(lam[k] > 0, "precondition: dPdF of the stretch must be PSD (%g)", lam[k]);
  bs_material_dPdF(&m, F, 1, Kp);
  cr_assert(memcmp(K, Kp, sizeof K) == 0, "projection changed the PSD dPdF of a stretch");
  /* compressed and inverted: indefinite, so the projection must act */
  double si[3] = {1.0, 0.6, -0.4};
  compose(Q, si, R, F);
  bs_material_dPdF(&m, F, 0, K);
  sym_eig_dense(9, K, lam, NULL);
  double lmin = lam[0];
  for (int k = 1; k < 9; k++) lmin = fmin(lmin, lam[k]);
  cr_assert(lmin < 0, "precondition: inverted dPdF should be indefinite");
  bs_material_dPdF(&m, F, 1, Kp);
  cr_assert(maxdiff(81, K, Kp) > 1e-3 * m.mu, "projection left an indefinite dPdF unchanged");
}

/* BS_PSD_INVERTED: an indefinite dPdF of a compressed but not inverted F is
 * left exact (bit for bit the BS_PSD_NONE one), an inverted F's is the
 * BS_PSD_ALL projection (bit for bit), for every nonlinear model. */
Test(material, psd_inverted_only) {
  double Q[9], R[9], F[9], K[81], Kp[81], Ki[81], lam[9];
  rand_rot(Q);
  rand_rot(R);
  for (int i = 0; i < 5; i++) {
    bs_material m = make(models[i], 1e5, 0.3);
    if (m.model == BS_MODEL_LINEAR) continue;
    /* strongly compressed, det F > 0: indefinite for the corotated models */
    double sc[3] = {0.9, 0.15, 0.1};
    compose(Q, sc, R, F);
    bs_material_dPdF(&m, F, BS_PSD_NONE, K);
    bs_material_dPdF(&m, F, BS_PSD_INVERTED, Ki);
    cr_assert(memcmp(K, Ki, sizeof K) == 0, "%s: inverted-only projection changed a non-inverted dPdF",
              bs_model_name(m.model));
    if (m.model == BS_MODEL_FIXED_COROTATED) { /* the check above must be able to fail */
      sym_eig_dense(9, K, lam, NULL);
      double lmin = lam[0];
      for (int k = 1; k < 9; k++) lmin = fmin(lmin, lam[k]);
      cr_assert(lmin < 0, "precondition: the compressed fixed_corotated dPdF should be indefinite (%g)", lmin);
    }
    /* inverted: the full projection, which changes it */
    double si[3] = {1.0, 0.6, -0.4};
    compose(Q, si, R, F);
    bs_material_dPdF(&m, F, BS_PSD_NONE, K);
    bs_material_dPdF(&m, F, BS_PSD_ALL, Kp);
    bs_material_dPdF(&m, F, BS_PSD_INVERTED, Ki);
    cr_assert(memcmp(Kp, Ki, sizeof K) == 0, "%s: inverted-only projection differs from the full one on an "
              "inverted F", bs_model_name(m.model));
    sym_eig_dense(9, K, lam, NULL);
    double lmin = lam[0];
    for (int k = 1; k < 9; k++) lmin = fmin(lmin, lam[k]);
    if (lmin < 0)
      cr_assert(maxdiff(81, K, Ki) > 1e-6 * m.mu, "%s: an indefinite inverted dPdF was left unchanged",
                bs_model_name(m.model));
  }
}

/* Degenerate F: zero, rank 1, rank 2, huge; every output finite. */
Test(material, degenerate_finite) {
  double Fs[5][9] = {{0},
                     {1, 2, 3, 2, 4, 6, -1, -2, -3},
                     {1, 0, 0, 0, 1, 0, 0, 0, 0},
                     {1e3, 2, 0, 0, 5e2, 1, 0, 0, -7e2},
                     {0, 0, 0, 0, 0, 0, 0, 0, 1e-300}};
  for (int i = 0; i < 5; i++) {
    bs_material m = make(models[i], 1e5, 0.3);
    for (int f = 0; f < 5; f++) {
      double P[9], K[81];
      double psi = bs_material_psi_P(&m, Fs[f], P);
      cr_assert(isfinite(psi) && isfinite(bs_material_psi(&m, Fs[f])), "%s: psi not finite at F %d",
                bs_model_name(m.model), f);
      for (int a = 0; a < 9; a++) cr_assert(isfinite(P[a]), "%s: P not finite at F %d", bs_model_name(m.model), f);
      for (int proj = 0; proj < 2; proj++) {
        bs_material_dPdF(&m, Fs[f], proj, K);
        for (int a = 0; a < 81; a++)
          cr_assert(isfinite(K[a]), "%s: dPdF not finite at F %d", bs_model_name(m.model), f);
      }
    }
  }
}

/* The corotated models take Psi and P from the polar rotation (bs_polar3)
 * where it applies and from the SVD elsewhere: both must be the closed forms
 * in singular values (to rounding, relative to the strain: no cancellation
 * near rest), on both sides of the switch det F = 1e-9 ||F||^3, and the batch
 * must be the single-matrix calls bit for bit. */
Test(material, corotated_polar_path) {
  for (int mi = 0; mi < 2; mi++) {
    bs_material m = make(models[mi], 1e5, 0.3);
    enum { N = 3000 };
    static double Fs[9 * N], Pb[9 * N], psib[N];
    int polar = 0;
    for (int t = 0; t < N; t++) {
      double Q[9], R[9], s[3], *F = Fs + 9 * t;
      rand_rot(Q);
      rand_rot(R);
      const double eps = t % 3 == 2 ? 0.5 : pow(10.0, -10 * urand()); /* strain 1e-10 .. 1, or large */
      for (int k = 0; k < 3; k++) s[k] = 1.0 + eps * (2 * urand() - 1);
      if (t % 7 == 0) s[2] = 1e-4 * (urand() - 0.5); /* near the switch, and inverted */
      compose(Q, s, R, F);
      double U[9], sv[3], V[9], P[9], Pref[9], Rp[9];
      polar += bs_polar3(F, Rp);
      bs_svd3(F, U, sv, V);
      /* the closed forms of material.c's sv_eval */
      const double d[3] = {sv[0] - 1, sv[1] - 1, sv[2] - 1};
      const double Jm1 = d[0] + d[1] + d[2] + d[0] * d[1] + d[0] * d[2] + d[1] * d[2] + d[0] * d[1] * d[2];
      const double Sd = d[0] + d[1] + d[2], Jk[3] = {sv[1] * sv[2], sv[0] * sv[2], sv[0] * sv[1]};
      double g[3], psi_ref = m.mu * (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
      psi_ref += 0.5 * m.lambda * (mi == 0 ? Jm1 * Jm1 : Sd * Sd);
      for (int k = 0; k < 3; k++) g[k] = 2 * m.mu * d[k] + m.lambda * (mi == 0 ? Jm1 * Jk[k] : Sd);
      for (int r = 0; r < 3; r++)
        for (int c = 0; c < 3; c++)
          Pref[3 * r + c] = U[3 * r] * g[0] * V[3 * c] + U[3 * r + 1] * g[1] * V[3 * c + 1] +
                            U[3 * r + 2] * g[2] * V[3 * c + 2];
      const double psi = bs_material_psi_P(&m, F, P), ps = bs_material_psi(&m, F);
      const double e = fmax(fabs(d[0]), fmax(fabs(d[1]), fabs(d[2]))), k = m.mu + m.lambda;
      cr_assert(psi == ps, "%s: psi and psi_P disagree: %.17g %.17g", bs_model_name(m.model), psi, ps);
      cr_assert(fabs(psi - psi_ref) <= 1e-13 * k * e * (1 + e * e * e * e),
                "%s: psi %.17g, closed form %.17g at strain %g", bs_model_name(m.model), psi, psi_ref, e);
      cr_assert(maxdiff(9, P, Pref) <= 1e-13 * k * (1 + e * e * e), "%s: P differs from U g V^T by %g at strain %g",
                bs_model_name(m.model), maxdiff(9, P, Pref), e);
    }
    cr_assert(polar > N / 2 && polar < N, "%d of %d on the polar path: the sample misses a path", polar, N);
    bs_material_psi_P_batch(&m, N, Fs, psib, Pb);
    for (int t = 0; t < N; t++) {
      double P[9];
      const double psi = bs_material_psi_P(&m, Fs + 9 * t, P);
      cr_assert(memcmp(&psi, psib + t, sizeof psi) == 0 && memcmp(P, Pb + 9 * t, sizeof P) == 0,
                "%s: batch differs at %d", bs_model_name(m.model), t);
    }
    bs_material_psi_batch(&m, N, Fs, psib);
    for (int t = 0; t < N; t++)
      cr_assert(psib[t] == bs_material_psi(&m, Fs + 9 * t), "%s: psi batch differs at %d", bs_model_name(m.model), t);
  }
}
