/* The P1 tet kernel: rest shape and F, energy gradient against central
 * differences of the energy and Hessian against central differences of the
 * gradient with O(h^2) convergence over h = 1e-2 .. 1e-4, at random, inverted,
 * flat and nearly flat configurations, for every model; the sparse
 * contraction against a dense G^T dPdF G; translation and rotation
 * invariance; symmetry; the PSD projection (12x12 dense Jacobi); finiteness at
 * collapsed tets. */
#include <criterion/criterion.h>
#include <float.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "bs_element.h"
#include "bs_svd.h"

/* ---- deterministic random numbers, helpers ---- */

#define BS_TEST_SEED 0x6A09E667F3BCC909ull
#include "test_random.h"
static double maxabs(int n, const double *a) {
  double m = 0;
  for (int i = 0; i < n; i++) m = fmax(m, fabs(a[i]));
  return m;
}
static double tet_det(const double X[12]) {
  double D[9];
  for (int m = 0; m < 3; m++)
    for (int k = 0; k < 3; k++) D[3 * m + k] = X[3 * (k + 1) + m] - X[m];
  return D[0] * (D[4] * D[8] - D[5] * D[7]) - D[1] * (D[3] * D[8] - D[5] * D[6]) + D[2] * (D[3] * D[7] - D[4] * D[6]);
}

#include "test_dense.h"

static const bs_model models[5] = {BS_MODEL_FIXED_COROTATED, BS_MODEL_COROTATED, BS_MODEL_NEO_HOOKEAN,
                                   BS_MODEL_STABLE_NEO_HOOKEAN, BS_MODEL_LINEAR};

static bs_material make(bs_model model, double E, double nu) {
  bs_material m;
  bs_error err = {0};
  cr_assert_eq(bs_material_init(model, E, nu, 1000, &m, &err), BS_OK, "%s", err.msg);
  return m;
}

/* A well-shaped random rest tet with edges ~1.4: a perturbed regular tet
 * (det Dm = 2 unperturbed), rotated, translated, positively oriented. */
static void rest_tet(double X[12]) {
  static const double reg[12] = {1, 1, 1, 1, -1, -1, -1, 1, -1, -1, -1, 1};
  double Q[9], t[3] = {nrand(), nrand(), nrand()};
  for (;;) {
    rand_rot(Q);
    for (int a = 0; a < 4; a++) {
      double p[3];
      for (int k = 0; k < 3; k++) p[k] = 0.5 * reg[3 * a + k] + 0.12 * nrand();
      for (int k = 0; k < 3; k++) X[3 * a + k] = Q[3 * k] * p[0] + Q[3 * k + 1] * p[1] + Q[3 * k + 2] * p[2] + t[k];
    }
    if (tet_det(X) < 0)
      for (int k = 0; k < 3; k++) {
        double tmp = X[3 + k];
        X[3 + k] = X[6 + k];
        X[6 + k] = tmp;
      }
    if (tet_det(X) > 1.0) return;
  }
}

/* Deformed configurations of the rest tet X. */
static void deform(const char *kind, const double X[12], double x[12]) {
  double c[3] = {0, 0, 0}, n[3];
  for (int a = 0; a < 4; a++)
    for (int k = 0; k < 3; k++) c[k] += 0.25 * X[3 * a + k];
  if (strcmp(kind, "random") == 0) {
    for (int i = 0; i < 12; i++) x[i] = X[i] + 0.25 * nrand();
  } else if (strcmp(kind, "inverted") == 0) {
    /* vertex 0 mirrored through the plane of the others, then noise */
    memcpy(x, X, sizeof(double) * 12);
    double u[3], v[3], d = 0, nn = 0;
    for (int k = 0; k < 3; k++) u[k] = X[6 + k] - X[3 + k], v[k] = X[9 + k] - X[3 + k];
    n[0] = u[1] * v[2] - u[2] * v[1], n[1] = u[2] * v[0] - u[0] * v[2], n[2] = u[0] * v[1] - u[1] * v[0];
    for (int k = 0; k < 3; k++) nn += n[k] * n[k];
    for (int k = 0; k < 3; k++) n[k] /= sqrt(nn);
    for (int k = 0; k < 3; k++) d += (X[k] - X[3 + k]) * n[k];
    for (int k = 0; k < 3; k++) x[k] = X[k] - 2 * d * n[k];
    for (int i = 0; i < 12; i++) x[i] += 0.1 * nrand();
  } else { /* flat, nearly flat: projected onto a random plane through the centroid */
    double nn = 0;
    for (int k = 0; k < 3; k++) {
      n[k] = nrand();
      nn += n[k] * n[k];
    }
    for (int k = 0; k < 3; k++) n[k] /= sqrt(nn);
    for (int a = 0; a < 4; a++) {
      double d = 0;
      for (int k = 0; k < 3; k++) d += (X[3 * a + k] - c[k]) * n[k];
      double off = strcmp(kind, "nearly flat") == 0 ? 1e-8 * nrand() : 0.0, w[3], wn = 0;
      for (int k = 0; k < 3; k++) { /* in-plane noise */
        w[k] = 0.15 * nrand();
        wn += w[k] * n[k];
      }
      for (int k = 0; k < 3; k++) x[3 * a + k] = X[3 * a + k] - (d - off) * n[k] + w[k] - wn * n[k];
    }
  }
}

/* ---- finite differences ---- */

enum { NH = 8, ND = 15 };
static double hval(int k) { return 1e-2 * pow(10.0, -2.0 * k / (NH - 1)); } /* 1e-2 .. 1e-4 */
static double dirs[ND][12];
/* the 12 coordinate directions and 3 random unit ones */
static void new_directions(void) {
  for (int d = 0; d < ND; d++) {
    double n = 0;
    for (int b = 0; b < 12; b++) {
      dirs[d][b] = d < 12 ? (b == d) : nrand();
      n += dirs[d][b] * dirs[d][b];
    }
    for (int b = 0; b < 12; b++) dirs[d][b] /= sqrt(n);
  }
}

typedef struct {
  const bs_material *m;
  const double *Dm_inv;
  double vol;
} tet;

static double err_grad(const tet *t, const double x[12], const double g[12], double h) {
  double e = 0;
  for (int d = 0; d < ND; d++) {
    double xp[12], xm[12], gd = 0;
    for (int i = 0; i < 12; i++) {
      xp[i] = x[i] + h * dirs[d][i];
      xm[i] = x[i] - h * dirs[d][i];
      gd += g[i] * dirs[d][i];
    }
    double fd = (bs_tet_energy(t->m, xp, t->Dm_inv, t->vol) - bs_tet_energy(t->m, xm, t->Dm_inv, t->vol)) / (2 * h);
    e = fmax(e, fabs(fd - gd));
  }
  return e;
}

static double err_hess(const tet *t, const double x[12], const double H[144], double h) {
  double e = 0;
  for (int d = 0; d < ND; d++) {
    double xp[12], xm[12], gp[12], gm[12];
    for (int i = 0; i < 12; i++) {
      xp[i] = x[i] + h * dirs[d][i];
      xm[i] = x[i] - h * dirs[d][i];
    }
    bs_tet_energy_grad(t->m, xp, t->Dm_inv, t->vol, gp);
    bs_tet_energy_grad(t->m, xm, t->Dm_inv, t->vol, gm);
    for (int i = 0; i < 12; i++) {
      double Hd = 0;
      for (int j = 0; j < 12; j++) Hd += H[12 * i + j] * dirs[d][j];
      e = fmax(e, fabs((gp[i] - gm[i]) / (2 * h) - Hd));
    }
  }
  return e;
}

/* Errors must fall as h^2 (least-squares slope in [1.8, 2.2] over the h above
 * round-off), or be round-off at every h (quadratic energies). */
static void check_order(const double e[NH], double dscale, double fscale, const char *what) {
  if (e[0] <= 1e-9 * dscale) {
    for (int k = 0; k < NH; k++)
      cr_assert(e[k] <= 1e-9 * dscale, "%s: FD error %g at h = %g (exact at h = 1e-2)", what, e[k], hval(k));
    return;
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
}

/* Is the configuration a fair point for FD of the Hessian? Not within 0.2 of
 * the corotated ridge s1 = -s2, not within 0.1 of the neo-Hookean J0 (where
 * Psi is only C^2), no stretch above 3. */
static int fair(const bs_material *m, const double F[9]) {
  double U[9], V[9], s[3];
  bs_svd3(F, U, s, V);
  if (s[0] > 3) return 0;
  if ((m->model == BS_MODEL_FIXED_COROTATED || m->model == BS_MODEL_COROTATED) && s[1] + s[2] < 0.2) return 0;
  if (m->model == BS_MODEL_NEO_HOOKEAN && fabs(s[0] * s[1] * s[2] - m->J0) < 0.1) return 0;
  return 1;
}

static void check_model(bs_model model) {
  const char *kinds[4] = {"random", "inverted", "flat", "nearly flat"};
  const double nus[2] = {0.3, 0.45};
  int n_inverted = 0;
  for (int pn = 0; pn < 2; pn++) {
    bs_material m = make(model, 1e5, nus[pn]);
    for (int kd = 0; kd < 4; kd++)
      for (int rep = 0; rep < 6;) {
        double X[12], x[12], Dm_inv[9], vol, F[9], g[12], H[144], e[NH];
        rest_tet(X);
        bs_tet_rest(X, Dm_inv, &vol);
        deform(kinds[kd], X, x);
        bs_tet_F(x, Dm_inv, F);
        if (!fair(&m, F)) continue;
        rep++;
        if (tet_det(x) < 0) n_inverted++;
        tet t = {&m, Dm_inv, vol};
        new_directions();
        double E = bs_tet_energy_grad(&m, x, Dm_inv, vol, g);
        bs_tet_hessian(&m, x, Dm_inv, vol, 0, H);
        cr_assert(E == bs_tet_energy(&m, x, Dm_inv, vol), "energy_grad and energy disagree");
        const double xs = maxabs(12, x) + 1, gs = fmax(maxabs(12, g), m.mu * vol),
                     Hs = fmax(maxabs(144, H), m.mu * vol);
        char buf[160];
        for (int k = 0; k < NH; k++) e[k] = err_grad(&t, x, g, hval(k));
        snprintf(buf, sizeof buf, "%s nu=%g %s: gradient vs FD of energy", bs_model_name(model), nus[pn], kinds[kd]);
        check_order(e, gs, fmax(fabs(E), gs * xs), buf);
        for (int k = 0; k < NH; k++) e[k] = err_hess(&t, x, H, hval(k));
        snprintf(buf, sizeof buf, "%s nu=%g %s: Hessian vs FD of gradient", bs_model_name(model), nus[pn], kinds[kd]);
        check_order(e, Hs, fmax(gs, Hs * xs), buf);
      }
  }
  cr_assert(n_inverted >= 12, "%s: expected inverted tets among the configurations (%d)", bs_model_name(model),
            n_inverted);
}

Test(element_fd, fixed_corotated) { check_model(BS_MODEL_FIXED_COROTATED); }
Test(element_fd, corotated) { check_model(BS_MODEL_COROTATED); }
Test(element_fd, neo_hookean) { check_model(BS_MODEL_NEO_HOOKEAN); }
Test(element_fd, stable_neo_hookean) { check_model(BS_MODEL_STABLE_NEO_HOOKEAN); }
Test(element_fd, linear) { check_model(BS_MODEL_LINEAR); }

/* ---- kinematics ---- */

Test(element, rest_shape) {
  const double ref[12] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
  double Dm_inv[9], vol, F[9];
  bs_tet_rest(ref, Dm_inv, &vol);
  cr_assert(fabs(vol - 1.0 / 6.0) < 1e-16, "unit tet volume %g", vol);
  for (int i = 0; i < 9; i++) cr_assert(Dm_inv[i] == (i % 4 == 0), "unit tet: Dm_inv must be I");
  for (int t = 0; t < 200; t++) {
    double X[12], x[12], A[9], b[3];
    rest_tet(X);
    bs_tet_rest(X, Dm_inv, &vol);
    cr_assert(fabs(vol - tet_det(X) / 6) <= 1e-14 * fabs(vol), "volume %g vs %g", vol, tet_det(X) / 6);
    /* Dm Dm_inv = I */
    for (int m = 0; m < 3; m++)
      for (int j = 0; j < 3; j++) {
        double v = 0;
        for (int k = 0; k < 3; k++) v += (X[3 * (k + 1) + m] - X[m]) * Dm_inv[3 * k + j];
        cr_assert(fabs(v - (m == j)) < 1e-13, "Dm Dm_inv != I");
      }
    bs_tet_F(X, Dm_inv, F);
    for (int i = 0; i < 9; i++) cr_assert(fabs(F[i] - (i % 4 == 0)) < 1e-13, "F at rest must be I");
    /* an affine map x = A X + b gives F = A */
    for (int i = 0; i < 9; i++) A[i] = nrand();
    for (int k = 0; k < 3; k++) b[k] = nrand();
    for (int a = 0; a < 4; a++)
      for (int k = 0; k < 3; k++)
        x[3 * a + k] = A[3 * k] * X[3 * a] + A[3 * k + 1] * X[3 * a + 1] + A[3 * k + 2] * X[3 * a + 2] + b[k];
    bs_tet_F(x, Dm_inv, F);
    for (int i = 0; i < 9; i++) cr_assert(fabs(F[i] - A[i]) < 1e-12 * (1 + maxabs(9, A)), "affine map: F != A");
    /* a reflected tet has negative volume */
    double Xr[12];
    memcpy(Xr, X, sizeof Xr);
    for (int k = 0; k < 3; k++) {
      double tmp = Xr[3 + k];
      Xr[3 + k] = Xr[6 + k];
      Xr[6 + k] = tmp;
    }
    bs_tet_rest(Xr, Dm_inv, &vol);
    cr_assert(vol < 0, "a negatively oriented tet must give a negative volume");
  }
  const double flat[12] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0};
  bs_tet_rest(flat, Dm_inv, &vol);
  cr_assert(vol == 0, "flat tet volume %g", vol);
  for (int i = 0; i < 9; i++) cr_assert(Dm_inv[i] == 0, "flat tet: Dm_inv must be zeroed");
}

/* ---- invariances, symmetry, dense reference, projection ---- */

Test(element, invariants) {
  const char *kinds[4] = {"random", "inverted", "flat", "nearly flat"};
  for (int i = 0; i < 5; i++) {
    bs_material m = make(models[i], 1e5, 0.3);
    for (int t = 0; t < 40; t++) {
      double X[12], x[12], Dm_inv[9], vol, F[9], K[81], g[12], H[144], Hp[144], G[9][12], lam[12];
      rest_tet(X);
      bs_tet_rest(X, Dm_inv, &vol);
      deform(kinds[t % 4], X, x);
      bs_tet_F(x, Dm_inv, F);
      bs_tet_energy_grad(&m, x, Dm_inv, vol, g);
      bs_tet_hessian(&m, x, Dm_inv, vol, 0, H);
      bs_tet_hessian(&m, x, Dm_inv, vol, 1, Hp);
      const double gs = fmax(maxabs(12, g), m.mu * vol), Hs = fmax(maxabs(144, H), m.mu * vol);
      /* translation: forces sum to zero; Hessian block rows sum to zero */
      for (int k = 0; k < 3; k++) {
        double s = g[k] + g[3 + k] + g[6 + k] + g[9 + k];
        cr_assert(fabs(s) <= 1e-12 * gs, "%s: net force %g", bs_model_name(m.model), s);
      }
      for (int r = 0; r < 12; r++)
        for (int k = 0; k < 3; k++) {
          double s = H[12 * r + k] + H[12 * r + 3 + k] + H[12 * r + 6 + k] + H[12 * r + 9 + k];
          cr_assert(fabs(s) <= 1e-11 * Hs, "%s: Hessian row %d does not annihilate translations (%g)",
                    bs_model_name(m.model), r, s);
        }
      /* rotation invariance: zero net torque (not for linear elasticity) */
      if (models[i] != BS_MODEL_LINEAR) {
        double tq[3] = {0, 0, 0};
        for (int a = 0; a < 4; a++) {
          const double *p = x + 3 * a, *f = g + 3 * a;
          tq[0] += p[1] * f[2] - p[2] * f[1];
          tq[1] += p[2] * f[0] - p[0] * f[2];
          tq[2] += p[0] * f[1] - p[1] * f[0];
        }
        cr_assert(maxabs(3, tq) <= 1e-11 * gs * (1 + maxabs(12, x)), "%s: net torque %g", bs_model_name(m.model),
                  maxabs(3, tq));
      }
      /* symmetric bit for bit */
      for (int a = 0; a < 12; a++)
        for (int b = 0; b < 12; b++)
          cr_assert(H[12 * a + b] == H[12 * b + a] && Hp[12 * a + b] == Hp[12 * b + a], "Hessian not symmetric");
      /* the sparse contraction equals vol G^T K G with G formed densely */
      bs_material_dPdF(&m, F, 0, K);
      memset(G, 0, sizeof G);
      for (int c = 0; c < 3; c++)
        for (int j = 0; j < 3; j++)
          for (int k = 1; k < 4; k++) {
            G[3 * c + j][3 * k + c] = Dm_inv[3 * (k - 1) + j];
            G[3 * c + j][c] -= Dm_inv[3 * (k - 1) + j];
          }
      double dmax = 0;
      for (int a = 0; a < 12; a++)
        for (int b = 0; b < 12; b++) {
          double v = 0;
          for (int p = 0; p < 9; p++)
            for (int q = 0; q < 9; q++) v += G[p][a] * K[9 * p + q] * G[q][b];
          dmax = fmax(dmax, fabs(vol * v - H[12 * a + b]));
        }
      cr_assert(dmax <= 1e-12 * Hs, "%s: Hessian differs from the dense G^T K G by %g", bs_model_name(m.model), dmax);
      /* the projected Hessian is PSD */
      sym_eig_dense(12, Hp, lam, NULL);
      double lmin = lam[0], lmax = fabs(lam[0]);
      for (int k = 1; k < 12; k++) lmin = fmin(lmin, lam[k]), lmax = fmax(lmax, fabs(lam[k]));
      cr_assert(lmin >= -1e-10 * lmax, "%s %s: projected Hessian eigenvalue %g (max %g)", bs_model_name(m.model),
                kinds[t % 4], lmin, lmax);
    }
  }
}

Test(element, rest_and_rigid_motion) {
  for (int i = 0; i < 5; i++) {
    bs_material m = make(models[i], 1e5, 0.3);
    double X[12], x[12], Dm_inv[9], vol, g[12], Q[9];
    rest_tet(X);
    bs_tet_rest(X, Dm_inv, &vol);
    double E = bs_tet_energy_grad(&m, X, Dm_inv, vol, g);
    cr_assert(fabs(E) <= 1e-20 * m.mu && maxabs(12, g) <= 1e-10 * m.mu * vol, "%s: rest energy %g, force %g",
              bs_model_name(m.model), E, maxabs(12, g));
    if (models[i] == BS_MODEL_LINEAR) continue;
    rand_rot(Q);
    for (int a = 0; a < 4; a++)
      for (int k = 0; k < 3; k++)
        x[3 * a + k] = Q[3 * k] * X[3 * a] + Q[3 * k + 1] * X[3 * a + 1] + Q[3 * k + 2] * X[3 * a + 2] + 3.0;
    E = bs_tet_energy_grad(&m, x, Dm_inv, vol, g);
    cr_assert(fabs(E) <= 1e-12 * m.mu * vol && maxabs(12, g) <= 1e-11 * m.mu * vol,
              "%s: rigid motion energy %g, force %g", bs_model_name(m.model), E, maxabs(12, g));
  }
}

/* Collapsed tets (collinear, coincident): every output finite. */
Test(element, collapsed_finite) {
  double X[12], Dm_inv[9], vol;
  rest_tet(X);
  bs_tet_rest(X, Dm_inv, &vol);
  const double line[12] = {0, 0, 0, 1, 1, 1, 2, 2, 2, -1, -1, -1};
  const double point[12] = {0.3, 0.1, 0.2, 0.3, 0.1, 0.2, 0.3, 0.1, 0.2, 0.3, 0.1, 0.2};
  const double *cfg[2] = {line, point};
  for (int i = 0; i < 5; i++) {
    bs_material m = make(models[i], 1e5, 0.3);
    for (int c = 0; c < 2; c++) {
      double g[12], H[144];
      double E = bs_tet_energy_grad(&m, cfg[c], Dm_inv, vol, g);
      cr_assert(isfinite(E) && isfinite(bs_tet_energy(&m, cfg[c], Dm_inv, vol)), "%s: energy not finite",
                bs_model_name(m.model));
      for (int k = 0; k < 12; k++) cr_assert(isfinite(g[k]), "%s: gradient not finite", bs_model_name(m.model));
      for (int p = 0; p < 2; p++) {
        bs_tet_hessian(&m, cfg[c], Dm_inv, vol, p, H);
        for (int k = 0; k < 144; k++) cr_assert(isfinite(H[k]), "%s: Hessian not finite", bs_model_name(m.model));
      }
      if (models[i] != BS_MODEL_LINEAR) /* a collapsed tet stores energy */
        cr_assert(E > 0, "%s: collapsed tet energy %g", bs_model_name(m.model), E);
    }
  }
}

/* The batched kernels are the single-tet kernels bit for bit, for every
 * model, on a batch mixing ordinary, inverted, flat and collapsed tets, at
 * batch sizes around the internal batch width. */
Test(element, batch_bitwise) {
  enum { N = 2 * BS_MATERIAL_BATCH + 3 };
  for (int mi = 0; mi < 5; mi++) {
    bs_material m = make(models[mi], 1e5, 0.3);
    double x[12 * N], Dm[9 * N], vol[N];
    for (int t = 0; t < N; t++) {
      double X[12];
      rest_tet(X);
      bs_tet_rest(X, Dm + 9 * t, &vol[t]);
      for (int i = 0; i < 12; i++) x[12 * t + i] = X[i] + 0.3 * nrand();
      if (t % 5 == 1) /* inverted: swap two vertices */
        for (int k = 0; k < 3; k++) {
          double tmp = x[12 * t + k];
          x[12 * t + k] = x[12 * t + 3 + k];
          x[12 * t + 3 + k] = tmp;
        }
      if (t % 5 == 2) /* flat */
        for (int k = 0; k < 3; k++) x[12 * t + 9 + k] = (x[12 * t + k] + x[12 * t + 3 + k]) / 2;
      if (t % 7 == 3) /* collapsed */
        for (int i = 3; i < 12; i++) x[12 * t + i] = x[12 * t + i % 3];
    }
    for (int n = 1; n <= N; n += (n < BS_MATERIAL_BATCH + 2 ? 1 : 3)) {
      double e[N], ee[N], g[12 * N], H[144 * N];
      bs_tet_energy_batch(&m, n, x, Dm, vol, ee);
      bs_tet_energy_grad_batch(&m, n, x, Dm, vol, e, g);
      for (int t = 0; t < n; t++) {
        double gs[12];
        double es = bs_tet_energy_grad(&m, x + 12 * t, Dm + 9 * t, vol[t], gs);
        cr_assert(memcmp(&es, &e[t], sizeof es) == 0 && memcmp(gs, g + 12 * t, sizeof gs) == 0,
                  "%s: batch of %d, tet %d: energy/gradient differ", bs_model_name(m.model), n, t);
        double e1 = bs_tet_energy(&m, x + 12 * t, Dm + 9 * t, vol[t]);
        cr_assert(memcmp(&e1, &ee[t], sizeof e1) == 0, "%s: batch of %d, tet %d: energy differs",
                  bs_model_name(m.model), n, t);
      }
      for (int psd = 0; psd < 2; psd++) {
        bs_tet_hessian_batch(&m, n, x, Dm, vol, psd, H);
        for (int t = 0; t < n; t++) {
          double Hs[144];
          bs_tet_hessian(&m, x + 12 * t, Dm + 9 * t, vol[t], psd, Hs);
          cr_assert(memcmp(Hs, H + 144 * t, sizeof Hs) == 0, "%s: batch of %d, tet %d, psd %d: Hessian differs",
                    bs_model_name(m.model), n, t, psd);
        }
      }
    }
  }
}

/* The corotated models' fused 4-lane kernels (element.c) against the
 * single-tet kernels, bit for bit, over many tets near rest and strongly
 * deformed, with inverted ones mixed in (their lanes go the SVD way). */
Test(element, corotated_fused_bitwise) {
  enum { N = 4096 };
  static double x[12 * N], Dm[9 * N], vol[N], e[N], ee[N], g[12 * N];
  for (int mi = 0; mi < 2; mi++) {
    bs_material m = make(models[mi], 1e5, 0.3);
    int inverted = 0;
    for (int t = 0; t < N; t++) {
      double X[12];
      rest_tet(X);
      bs_tet_rest(X, Dm + 9 * t, &vol[t]);
      const double amp = t % 3 == 0 ? 1e-6 : t % 3 == 1 ? 0.05 : 0.4;
      for (int i = 0; i < 12; i++) x[12 * t + i] = X[i] + amp * nrand();
      inverted += tet_det(x + 12 * t) < 0;
    }
    cr_assert(inverted > 10, "only %d inverted tets: the SVD lanes are not exercised", inverted);
    bs_tet_energy_batch(&m, N, x, Dm, vol, ee);
    bs_tet_energy_grad_batch(&m, N, x, Dm, vol, e, g);
    for (int t = 0; t < N; t++) {
      double gs[12];
      const double es = bs_tet_energy_grad(&m, x + 12 * t, Dm + 9 * t, vol[t], gs);
      const double e1 = bs_tet_energy(&m, x + 12 * t, Dm + 9 * t, vol[t]);
      cr_assert(memcmp(&es, &e[t], sizeof es) == 0 && memcmp(gs, g + 12 * t, sizeof gs) == 0 &&
                    memcmp(&e1, &ee[t], sizeof e1) == 0,
                "%s: tet %d: the batch differs from the single-tet kernels", bs_model_name(m.model), t);
    }
  }
}
