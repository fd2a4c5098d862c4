/* The P2 tet kernel (bs_tet10.h): shape functions (partition of unity,
 * interpolation, gradients against differences); each quadrature rule exact to
 * its degree and not beyond; patch tests on straight and curved elements;
 * gradient and Hessian of every model against central differences (O(h^2)
 * over h = 1e-2 .. 1e-4); the PSD projection; the linear model's stiffness
 * with the 4-point rule; consistent and HRZ mass; body load; stresses; the
 * refusal of folded elements; Gmsh <-> VTK order; the tet4 -> tet10 builder. */
#include <criterion/criterion.h>
#include <float.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bs_element.h"
#include "bs_svd.h"
#include "bs_tet10.h"

#define BS_TEST_SEED 0xBB67AE8584CAA73Bull
#include "test_random.h"

static double maxabs(int n, const double *a) {
  double m = 0;
  for (int i = 0; i < n; i++) m = fmax(m, fabs(a[i]));
  return m;
}

static const bs_model models[5] = {BS_MODEL_FIXED_COROTATED, BS_MODEL_COROTATED, BS_MODEL_NEO_HOOKEAN,
                                   BS_MODEL_STABLE_NEO_HOOKEAN, BS_MODEL_LINEAR};

static bs_material make(bs_model model, double E, double nu) {
  bs_material m;
  bs_error err = {0};
  cr_assert_eq(bs_material_init(model, E, nu, 1000, &m, &err), BS_OK, "%s", err.msg);
  return m;
}

/* Eigenvalues of a symmetric n x n matrix, n <= 30 (cyclic Jacobi). */
static void sym_eig(int n, const double *A_in, double *lam) {
  static double A[900];
  memcpy(A, A_in, sizeof(double) * n * n);
  for (int sweep = 0; sweep < 100; sweep++) {
    double off = 0, diag = 0;
    for (int p = 0; p < n; p++) {
      diag += A[p * n + p] * A[p * n + p];
      for (int q = p + 1; q < n; q++) off += A[p * n + q] * A[p * n + q];
    }
    if (off <= 1e-36 * diag || off == 0) break;
    for (int p = 0; p < n; p++)
      for (int q = p + 1; q < n; q++) {
        const double apq = A[p * n + q];
        if (apq == 0) continue;
        const double th = (A[q * n + q] - A[p * n + p]) / (2 * apq);
        const double t = (th >= 0 ? 1.0 : -1.0) / (fabs(th) + sqrt(th * th + 1));
        const double c = 1 / sqrt(t * t + 1), s = t * c;
        for (int k = 0; k < n; k++) {
          const double akp = A[k * n + p], akq = A[k * n + q];
          A[k * n + p] = c * akp - s * akq;
          A[k * n + q] = s * akp + c * akq;
        }
        for (int k = 0; k < n; k++) {
          const double apk = A[p * n + k], aqk = A[q * n + k];
          A[p * n + k] = c * apk - s * aqk;
          A[q * n + k] = s * apk + c * aqk;
        }
      }
  }
  for (int i = 0; i < n; i++) lam[i] = A[i * n + i];
}

static double lam_min(int n, const double *A, double *lmax) {
  double lam[30], lo = INFINITY, hi = 0;
  sym_eig(n, A, lam);
  for (int i = 0; i < n; i++) lo = fmin(lo, lam[i]), hi = fmax(hi, fabs(lam[i]));
  if (lmax) *lmax = hi;
  return lo;
}

/* ---- elements ---- */

static double det4(const double X[30]) {
  double D[9];
  for (int m = 0; m < 3; m++)
    for (int k = 0; k < 3; k++) D[3 * m + k] = X[3 * (k + 1) + m] - X[m];
  return D[0] * (D[4] * D[8] - D[5] * D[7]) - D[1] * (D[3] * D[8] - D[5] * D[6]) + D[2] * (D[3] * D[7] - D[4] * D[6]);
}

/* Midside nodes at the midpoints of the vertices' edges. */
static void straight_midsides(double X[30]) {
  for (int k = 0; k < 6; k++)
    for (int c = 0; c < 3; c++)
      X[3 * (4 + k) + c] = 0.5 * (X[3 * bs_tet10_edges[k][0] + c] + X[3 * bs_tet10_edges[k][1] + c]);
}

/* A random well-shaped rest tet10 (edges ~1.4, a perturbed regular tet,
 * rotated, translated, positively oriented); curved > 0 moves each midside
 * node off its midpoint by ~curved (a curved element). Accepted by
 * bs_tet10_rest_init with the rule given, whose cache is returned in r. */
static void rest_tet10(double curved, bs_tet10_rule_id rule, double X[30], bs_tet10_rest *r) {
  static const double reg[12] = {1, 1, 1, 1, -1, -1, -1, 1, -1, -1, -1, 1};
  double Q[9], t[3] = {nrand(), nrand(), nrand()};
  bs_error err = {0};
  for (;;) {
    rand_rot(Q);
    for (int a = 0; a < 4; a++) {
      double p[3];
      for (int k = 0; k < 3; k++) p[k] = 0.5 * reg[3 * a + k] + 0.12 * nrand();
      for (int k = 0; k < 3; k++) X[3 * a + k] = Q[3 * k] * p[0] + Q[3 * k + 1] * p[1] + Q[3 * k + 2] * p[2] + t[k];
    }
    if (det4(X) < 0)
      for (int k = 0; k < 3; k++) {
        const double tmp = X[3 + k];
        X[3 + k] = X[6 + k];
        X[6 + k] = tmp;
      }
    if (det4(X) < 1.0) continue;
    straight_midsides(X);
    for (int i = 12; i < 30; i++) X[i] += curved * nrand();
    if (bs_tet10_rest_init(X, rule, r, &err) == BS_OK) return;
  }
}

/* x = A X + b at every node. */
static void affine(const double A[9], const double b[3], const double X[30], double x[30]) {
  for (int a = 0; a < 10; a++)
    for (int k = 0; k < 3; k++)
      x[3 * a + k] = A[3 * k] * X[3 * a] + A[3 * k + 1] * X[3 * a + 1] + A[3 * k + 2] * X[3 * a + 2] + b[k];
}

/* ---- shape functions ---- */

Test(tet10_shape, partition_interpolation_gradients) {
  double N[10], dN[30];
  for (int b = 0; b < 10; b++) {
    bs_tet10_shape(bs_tet10_ref_nodes[b], N);
    for (int a = 0; a < 10; a++) cr_assert(N[a] == (a == b), "N_%d(node %d) = %g", a, b, N[a]);
  }
  for (int t = 0; t < 200; t++) {
    double xi[3] = {urand(), urand(), urand()}, s = 0, sg[3] = {0, 0, 0};
    bs_tet10_shape(xi, N);
    bs_tet10_shape_grad(xi, dN);
    for (int a = 0; a < 10; a++) {
      s += N[a];
      for (int k = 0; k < 3; k++) sg[k] += dN[3 * a + k];
    }
    cr_assert(fabs(s - 1) < 1e-14, "sum N = %.17g at (%g %g %g)", s, xi[0], xi[1], xi[2]);
    cr_assert(maxabs(3, sg) < 1e-13, "sum dN = %g", maxabs(3, sg));
    for (int k = 0; k < 3; k++) { /* the gradient against central differences (exact for quadratics) */
      double xp[3] = {xi[0], xi[1], xi[2]}, xm[3] = {xi[0], xi[1], xi[2]}, Np[10], Nm[10];
      xp[k] += 1e-3, xm[k] -= 1e-3;
      bs_tet10_shape(xp, Np);
      bs_tet10_shape(xm, Nm);
      for (int a = 0; a < 10; a++)
        cr_assert(fabs((Np[a] - Nm[a]) / 2e-3 - dN[3 * a + k]) < 1e-11, "dN_%d/dxi_%d", a, k);
    }
  }
}

Test(tet10_shape, gmsh_vtk_order) {
  int32_t c[20];
  for (int i = 0; i < 20; i++) c[i] = 100 + i;
  bs_tet10_swap_gmsh_vtk(2, c);
  for (int t = 0; t < 2; t++)
    for (int i = 0; i < 10; i++) {
      const int want = 100 + 10 * t + (i == 8 ? 9 : i == 9 ? 8 : i);
      cr_assert_eq(c[10 * t + i], want, "tet %d node %d", t, i);
    }
  bs_tet10_swap_gmsh_vtk(2, c);
  for (int i = 0; i < 20; i++) cr_assert_eq(c[i], 100 + i, "the swap is its own inverse");
  /* VTK: node 8 on edge (1,3), 9 on (2,3); the reference nodes agree */
  cr_assert(bs_tet10_edges[4][0] == 1 && bs_tet10_edges[4][1] == 3 && bs_tet10_edges[5][0] == 2 &&
            bs_tet10_edges[5][1] == 3);
  for (int k = 0; k < 6; k++)
    for (int c3 = 0; c3 < 3; c3++)
      cr_assert(bs_tet10_ref_nodes[4 + k][c3] == 0.5 * (bs_tet10_ref_nodes[bs_tet10_edges[k][0]][c3] +
                                                        bs_tet10_ref_nodes[bs_tet10_edges[k][1]][c3]));
}

/* ---- quadrature ---- */

static double fact(int n) { return n <= 1 ? 1.0 : n * fact(n - 1); }

/* Largest error of the rule over the monomials xi^i eta^j zeta^k of total degree deg. */
static double monomial_error(const bs_tet10_rule *R, int deg) {
  double e = 0;
  for (int i = 0; i <= deg; i++)
    for (int j = 0; i + j <= deg; j++) {
      const int k = deg - i - j;
      const double exact = fact(i) * fact(j) * fact(k) / fact(deg + 3);
      double s = 0;
      for (int q = 0; q < R->n_points; q++)
        s += R->w[q] * pow(R->xi[q][0], i) * pow(R->xi[q][1], j) * pow(R->xi[q][2], k);
      e = fmax(e, fabs(s - exact));
    }
  return e;
}

Test(tet10_quadrature, exact_to_degree_and_no_further) {
  const int expect_n[2] = {4, 14}, expect_deg[2] = {2, 5};
  for (int id = 0; id < 2; id++) {
    const bs_tet10_rule *R = bs_tet10_rule_get((bs_tet10_rule_id)id);
    cr_assert(R && R->n_points == expect_n[id] && R->degree == expect_deg[id]);
    for (int q = 0; q < R->n_points; q++) {
      cr_assert(R->w[q] > 0, "%s: weight %d = %g", R->name, q, R->w[q]);
      const double *x = R->xi[q];
      cr_assert(x[0] > 0 && x[1] > 0 && x[2] > 0 && x[0] + x[1] + x[2] < 1, "%s: point %d outside", R->name, q);
    }
    for (int d = 0; d <= R->degree; d++) {
      const double e = monomial_error(R, d);
      cr_log_info("%s: degree %d max monomial error %.3g\n", R->name, d, e);
      cr_assert(e <= 1e-14, "%s: degree-%d monomials integrated with error %g", R->name, d, e);
    }
    const double e = monomial_error(R, R->degree + 1);
    cr_log_info("%s: degree %d (one past) max monomial error %.3g\n", R->name, R->degree + 1, e);
    cr_assert(e > 1e-6, "%s: claims degree %d but integrates degree %d too (error %g)", R->name, R->degree,
              R->degree + 1, e);
  }
  cr_assert(bs_tet10_rule_get((bs_tet10_rule_id)2) == NULL && bs_tet10_rule_get((bs_tet10_rule_id)-1) == NULL);
}

/* ---- patch tests ---- */

Test(tet10_patch, affine_reproduced_straight_and_curved) {
  for (int t = 0; t < 40; t++) {
    const double curved = t % 2 ? 0.08 : 0.0;
    const bs_tet10_rule_id rule = t % 4 < 2 ? BS_TET10_RULE_14PT_DEG5 : BS_TET10_RULE_4PT_DEG2;
    double X[30], x[30], A[9], b[3], F[9];
    bs_tet10_rest r;
    rest_tet10(curved, rule, X, &r);
    for (int i = 0; i < 9; i++) A[i] = (i % 4 == 0) + 0.3 * nrand();
    for (int k = 0; k < 3; k++) b[k] = nrand();
    affine(A, b, X, x);
    for (int q = 0; q < r.n_points; q++) {
      bs_tet10_F(&r, q, x, F);
      for (int i = 0; i < 9; i++)
        cr_assert(fabs(F[i] - A[i]) < 1e-13, "curved %g point %d: F[%d] = %.17g, A = %.17g", curved, q, i, F[i],
                  A[i]);
      bs_tet10_F(&r, q, X, F);
      for (int i = 0; i < 9; i++) cr_assert(fabs(F[i] - (i % 4 == 0)) < 1e-13, "F at rest != I");
    }
    /* the energy of a uniform F is V Psi(A) */
    bs_material m = make(BS_MODEL_NEO_HOOKEAN, 1e5, 0.3);
    const double E = bs_tet10_energy(&m, &r, x), want = r.volume * bs_material_psi(&m, A);
    cr_assert(fabs(E - want) <= 1e-12 * fabs(want), "uniform F: energy %.17g, V Psi(A) %.17g", E, want);
    if (curved == 0.0) { /* a straight tet10 under an affine map is the tet4 of its vertices (bs_element.h) */
      double Dm_inv[9], vol;
      bs_tet_rest(X, Dm_inv, &vol);
      const double E4 = bs_tet_energy(&m, x, Dm_inv, vol);
      cr_assert(fabs(vol - r.volume) <= 1e-14 * vol && fabs(E4 - E) <= 1e-12 * fabs(E4),
                "straight tet10 vs tet4: volume %g vs %g, energy %.17g vs %.17g", r.volume, vol, E, E4);
    }
  }
}

Test(tet10_patch, translation_and_rotation) {
  for (int t = 0; t < 20; t++) {
    double X[30], x[30], g[30], Q[9], b[3] = {nrand(), nrand(), nrand()};
    bs_tet10_rest r;
    rest_tet10(t % 2 ? 0.08 : 0.0, BS_TET10_RULE_14PT_DEG5, X, &r);
    bs_material lin = make(BS_MODEL_LINEAR, 1e5, 0.3), nh = make(BS_MODEL_NEO_HOOKEAN, 1e5, 0.3);
    for (int i = 0; i < 30; i++) x[i] = X[i] + b[i % 3];
    const double E = bs_tet10_energy_grad(&lin, &r, x, g);
    cr_assert(fabs(E) < 1e-20 * lin.mu && maxabs(30, g) < 1e-10 * lin.mu * r.volume,
              "linear, translated: energy %g, force %g", E, maxabs(30, g));
    /* neo-Hookean: E(Q x + b) = E(x) at a random deformation */
    for (int i = 0; i < 30; i++) x[i] = X[i] + 0.15 * nrand();
    rand_rot(Q);
    double y[30];
    affine(Q, b, x, y);
    const double E0 = bs_tet10_energy(&nh, &r, x), E1 = bs_tet10_energy(&nh, &r, y);
    cr_assert(fabs(E1 - E0) <= 1e-12 * fabs(E0), "neo-Hookean rotated: %.17g vs %.17g", E1, E0);
    cr_assert(fabs(bs_tet10_energy(&nh, &r, X)) < 1e-20 * nh.mu, "rest energy");
  }
}

/* The linear model's stiffness (a constant dP/dF) integrates exactly with the
 * 4-point rule on a straight tet10: both rules give the same Hessian. */
Test(tet10_patch, linear_stiffness_four_points_exact) {
  bs_material m = make(BS_MODEL_LINEAR, 1e5, 0.3);
  for (int t = 0; t < 10; t++) {
    double X[30], H4[900], H14[900];
    bs_tet10_rest r4, r14;
    rest_tet10(0.0, BS_TET10_RULE_4PT_DEG2, X, &r4);
    bs_error err = {0};
    cr_assert_eq(bs_tet10_rest_init(X, BS_TET10_RULE_14PT_DEG5, &r14, &err), BS_OK, "%s", err.msg);
    bs_tet10_hessian(&m, &r4, X, BS_PSD_NONE, H4);
    bs_tet10_hessian(&m, &r14, X, BS_PSD_NONE, H14);
    double d = 0;
    for (int i = 0; i < 900; i++) d = fmax(d, fabs(H4[i] - H14[i]));
    cr_assert(d <= 1e-12 * maxabs(900, H14), "linear stiffness: 4pt and 14pt differ by %g (max %g)", d,
              maxabs(900, H14));
    cr_assert(fabs(r4.volume - r14.volume) <= 1e-14 * r14.volume && fabs(r14.volume - det4(X) / 6) <= 1e-14 * r14.volume,
              "straight tet10 volume");
  }
}

/* ---- gradient and Hessian against finite differences ---- */

enum { NH = 8, ND = 33 };
static double hval(int k) { return 1e-2 * pow(10.0, -2.0 * k / (NH - 1)); } /* 1e-2 .. 1e-4 */
static double dirs[ND][30];
/* the 30 coordinate directions and 3 random unit ones */
static void new_directions(void) {
  for (int d = 0; d < ND; d++) {
    double n = 0;
    for (int b = 0; b < 30; b++) {
      dirs[d][b] = d < 30 ? (b == d) : nrand();
      n += dirs[d][b] * dirs[d][b];
    }
    for (int b = 0; b < 30; b++) dirs[d][b] /= sqrt(n);
  }
}

static void step(const double x[30], int d, double h, double xp[30], double xm[30]) {
  for (int i = 0; i < 30; i++) {
    xp[i] = x[i] + h * dirs[d][i];
    xm[i] = x[i] - h * dirs[d][i];
  }
}

static double err_grad(const bs_material *m, const bs_tet10_rest *r, const double x[30], const double g[30],
                       double h) {
  double e = 0;
  for (int d = 0; d < ND; d++) {
    double xp[30], xm[30], gd = 0;
    step(x, d, h, xp, xm);
    for (int i = 0; i < 30; i++) gd += g[i] * dirs[d][i];
    const double fd = (bs_tet10_energy(m, r, xp) - bs_tet10_energy(m, r, xm)) / (2 * h);
    e = fmax(e, fabs(fd - gd));
  }
  return e;
}

static double err_hess(const bs_material *m, const bs_tet10_rest *r, const double x[30], const double H[900],
                       double h) {
  double e = 0;
  for (int d = 0; d < ND; d++) {
    double xp[30], xm[30], gp[30], gm[30];
    step(x, d, h, xp, xm);
    bs_tet10_energy_grad(m, r, xp, gp);
    bs_tet10_energy_grad(m, r, xm, gm);
    for (int i = 0; i < 30; i++) {
      double Hd = 0;
      for (int j = 0; j < 30; j++) Hd += H[30 * i + j] * dirs[d][j];
      e = fmax(e, fabs((gp[i] - gm[i]) / (2 * h) - Hd));
    }
  }
  return e;
}

/* Errors must fall as h^2 (least-squares slope in [1.8, 2.2] over the h above
 * round-off), or be round-off at every h (quadratic energies). Returns the
 * smallest error over h relative to dscale. */
static double check_order(const double e[NH], double dscale, double fscale, const char *what) {
  double best = INFINITY;
  for (int k = 0; k < NH; k++) best = fmin(best, e[k] / dscale);
  if (e[0] <= 1e-9 * dscale) {
    for (int k = 0; k < NH; k++)
      cr_assert(e[k] <= 1e-9 * dscale, "%s: FD error %g at h = %g (exact at h = 1e-2)", what, e[k], hval(k));
    return best;
  }
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  int n = 0;
  for (int k = 0; k < NH; k++) {
    if (!(e[k] > 1e3 * DBL_EPSILON * fscale / hval(k))) continue;
    const double x = log(hval(k)), y = log(e[k]);
    sx += x, sy += y, sxx += x * x, sxy += x * y;
    n++;
  }
  cr_assert(n >= 3, "%s: only %d step sizes above round-off (errors %g .. %g)", what, n, e[0], e[NH - 1]);
  const double slope = (n * sxy - sx * sy) / (n * sxx - sx * sx);
  cr_assert(slope > 1.8 && slope < 2.2, "%s: FD error slope %.3f (errors %g at h=1e-2, %g at h=1e-4), expected 2",
            what, slope, e[0], e[NH - 1]);
  return best;
}

/* Is every quadrature point a fair point for differences of the Hessian? Not
 * within 0.2 of the corotated ridge s1 = -s2, not within 0.1 of the
 * neo-Hookean J0 (Psi only C^2 there), no stretch above 3. */
static int fair(const bs_material *m, const bs_tet10_rest *r, const double x[30], int *inverted) {
  for (int q = 0; q < r->n_points; q++) {
    double F[9], U[9], V[9], s[3];
    bs_tet10_F(r, q, x, F);
    bs_svd3(F, U, s, V);
    if (s[0] > 3) return 0;
    if ((m->model == BS_MODEL_FIXED_COROTATED || m->model == BS_MODEL_COROTATED) && s[1] + s[2] < 0.2) return 0;
    if (m->model == BS_MODEL_NEO_HOOKEAN && fabs(s[0] * s[1] * s[2] - m->J0) < 0.1) return 0;
    if (s[2] < 0) *inverted = 1;
  }
  return 1;
}

static void check_model(bs_model model) {
  const double nus[2] = {0.3, 0.45}, amps[3] = {0.1, 0.25, 0.45};
  double worst_g = 0, worst_H = 0;
  int n_inverted = 0;
  for (int pn = 0; pn < 2; pn++) {
    const bs_material m = make(model, 1e5, nus[pn]);
    for (int rep = 0; rep < 12;) {
      double X[30], x[30], g[30], H[900], e[NH];
      bs_tet10_rest r;
      rest_tet10(rep % 2 ? 0.08 : 0.0, rep % 4 == 3 ? BS_TET10_RULE_4PT_DEG2 : BS_TET10_RULE_14PT_DEG5, X, &r);
      for (int i = 0; i < 30; i++) x[i] = X[i] + amps[rep % 3] * nrand();
      int inverted = 0;
      if (!fair(&m, &r, x, &inverted)) continue;
      rep++;
      n_inverted += inverted;
      new_directions();
      const double E = bs_tet10_energy_grad(&m, &r, x, g);
      bs_tet10_hessian(&m, &r, x, BS_PSD_NONE, H);
      cr_assert(E == bs_tet10_energy(&m, &r, x), "energy_grad and energy disagree");
      const double xs = maxabs(30, x) + 1, gs = fmax(maxabs(30, g), m.mu * r.volume),
                   Hs = fmax(maxabs(900, H), m.mu * r.volume);
      char buf[160];
      for (int k = 0; k < NH; k++) e[k] = err_grad(&m, &r, x, g, hval(k));
      snprintf(buf, sizeof buf, "%s nu=%g rep %d: gradient vs FD of energy", bs_model_name(model), nus[pn], rep);
      worst_g = fmax(worst_g, check_order(e, gs, fmax(fabs(E), gs * xs), buf));
      for (int k = 0; k < NH; k++) e[k] = err_hess(&m, &r, x, H, hval(k));
      snprintf(buf, sizeof buf, "%s nu=%g rep %d: Hessian vs FD of gradient", bs_model_name(model), nus[pn], rep);
      worst_H = fmax(worst_H, check_order(e, Hs, fmax(gs, Hs * xs), buf));
    }
  }
  cr_log_info("%s: max relative FD error (best h) gradient %.3g, Hessian %.3g; %d configurations with an "
              "inverted point\n", bs_model_name(model), worst_g, worst_H, n_inverted);
  if (model != BS_MODEL_LINEAR)
    cr_assert(n_inverted >= 1, "%s: expected inverted quadrature points among the configurations",
              bs_model_name(model));
}

Test(tet10_fd, fixed_corotated) { check_model(BS_MODEL_FIXED_COROTATED); }
Test(tet10_fd, corotated) { check_model(BS_MODEL_COROTATED); }
Test(tet10_fd, neo_hookean) { check_model(BS_MODEL_NEO_HOOKEAN); }
Test(tet10_fd, stable_neo_hookean) { check_model(BS_MODEL_STABLE_NEO_HOOKEAN); }
Test(tet10_fd, linear) { check_model(BS_MODEL_LINEAR); }

/* Symmetry bit for bit, translations in the kernel of H, and the projected
 * Hessian positive semidefinite, for every model. */
Test(tet10_fd, symmetry_translation_psd) {
  for (int i = 0; i < 5; i++) {
    const bs_material m = make(models[i], 1e5, 0.3);
    for (int t = 0; t < 6; t++) {
      double X[30], x[30], H[900], Hp[900], lmax;
      bs_tet10_rest r;
      rest_tet10(t % 2 ? 0.08 : 0.0, BS_TET10_RULE_14PT_DEG5, X, &r);
      for (int k = 0; k < 30; k++) x[k] = X[k] + 0.4 * nrand();
      bs_tet10_hessian(&m, &r, x, BS_PSD_NONE, H);
      bs_tet10_hessian(&m, &r, x, BS_PSD_ALL, Hp);
      const double Hs = fmax(maxabs(900, H), m.mu * r.volume);
      for (int a = 0; a < 30; a++)
        for (int b = 0; b < 30; b++)
          cr_assert(H[30 * a + b] == H[30 * b + a] && Hp[30 * a + b] == Hp[30 * b + a], "not symmetric");
      for (int row = 0; row < 30; row++)
        for (int c = 0; c < 3; c++) {
          double s = 0;
          for (int b = 0; b < 10; b++) s += H[30 * row + 3 * b + c];
          cr_assert(fabs(s) <= 1e-11 * Hs, "%s: H row %d does not annihilate translations (%g)",
                    bs_model_name(m.model), row, s);
        }
      const double lo = lam_min(30, Hp, &lmax);
      cr_assert(lo >= -1e-10 * lmax, "%s: projected Hessian eigenvalue %g (max %g)", bs_model_name(m.model), lo, lmax);
    }
  }
}

/* ---- mass and body load ---- */

Test(tet10_mass, consistent_and_hrz) {
  const double rho = 1200;
  for (int t = 0; t < 20; t++) {
    const int curved = t % 2;
    double X[30], M[100], ml[10], lmax;
    bs_tet10_rest r;
    bs_error err = {0};
    rest_tet10(curved ? 0.08 : 0.0, BS_TET10_RULE_14PT_DEG5, X, &r);
    cr_assert_eq(bs_tet10_mass(&r, rho, M, &err), BS_OK, "%s", err.msg);
    cr_assert_eq(bs_tet10_mass_hrz(&r, rho, ml, &err), BS_OK, "%s", err.msg);
    const double mass = rho * r.volume;
    double sum = 0, sum_l = 0;
    for (int a = 0; a < 10; a++) {
      double row = 0;
      for (int b = 0; b < 10; b++) {
        row += M[10 * a + b];
        cr_assert(M[10 * a + b] == M[10 * b + a], "M not symmetric");
      }
      sum += row;
      sum_l += ml[a];
      cr_assert(ml[a] > 0, "HRZ mass %d = %g", a, ml[a]);
      if (!curved && a < 4) /* vertex rows: rho int N_a = -rho V / 20 */
        cr_assert(fabs(row + mass / 20) <= 1e-13 * mass, "vertex %d row sum %g, want %g", a, row, -mass / 20);
      if (!curved && a >= 4)
        cr_assert(fabs(row - mass / 5) <= 1e-13 * mass, "edge node %d row sum %g, want %g", a, row, mass / 5);
      if (!curved) /* HRZ on a straight tet10: 1/36 per vertex, 4/27 per edge node */
        cr_assert(fabs(ml[a] - (a < 4 ? mass / 36 : 4 * mass / 27)) <= 1e-13 * mass, "HRZ %d = %g", a, ml[a]);
      if (curved && a < 4) cr_assert(row < 0, "curved: vertex %d row sum %g not negative", a, row);
    }
    cr_assert(fabs(sum - mass) <= 1e-13 * mass && fabs(sum_l - mass) <= 1e-13 * mass,
              "total %g, HRZ total %g, element mass %g", sum, sum_l, mass);
    const double lo = lam_min(10, M, &lmax);
    cr_assert(lo > 1e-3 * lmax, "consistent mass not positive definite: eigenvalues %g .. %g", lo, lmax);
    if (t == 0) cr_log_info("straight tet10 consistent mass: eigenvalues %g .. %g (rho V = %g)\n", lo, lmax, mass);
  }
}

Test(tet10_mass, refuses_low_degree_rule_and_bad_density) {
  double X[30], M[100], ml[10];
  bs_tet10_rest r;
  bs_error err = {0};
  rest_tet10(0.0, BS_TET10_RULE_4PT_DEG2, X, &r);
  cr_assert_eq(bs_tet10_mass(&r, 1000, M, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "4pt_deg2"), "%s", err.msg);
  cr_assert_eq(bs_tet10_mass_hrz(&r, 1000, ml, &err), BS_EINPUT);
  rest_tet10(0.0, BS_TET10_RULE_14PT_DEG5, X, &r);
  cr_assert_eq(bs_tet10_mass(&r, 0, M, &err), BS_EINPUT);
  cr_assert_eq(bs_tet10_mass(&r, NAN, M, &err), BS_EINPUT);
}

Test(tet10_mass, body_load) {
  const double rho = 800, g[3] = {0.5, -9.81, 1.25};
  for (int t = 0; t < 10; t++) {
    double X[30], f4[30], f14[30], tot[3] = {0, 0, 0};
    bs_tet10_rest r4, r14;
    bs_error err = {0};
    rest_tet10(t % 2 ? 0.08 : 0.0, BS_TET10_RULE_14PT_DEG5, X, &r14);
    bs_tet10_body_load(&r14, rho, g, f14);
    for (int a = 0; a < 10; a++)
      for (int k = 0; k < 3; k++) tot[k] += f14[3 * a + k];
    for (int k = 0; k < 3; k++)
      cr_assert(fabs(tot[k] - rho * r14.volume * g[k]) <= 1e-13 * rho * r14.volume * 10, "total load %d", k);
    if (t % 2) continue;
    cr_assert_eq(bs_tet10_rest_init(X, BS_TET10_RULE_4PT_DEG2, &r4, &err), BS_OK, "%s", err.msg);
    bs_tet10_body_load(&r4, rho, g, f4);
    const double W = rho * r14.volume * 10;
    for (int a = 0; a < 10; a++)
      for (int k = 0; k < 3; k++) {
        const double want = rho * g[k] * r14.volume * (a < 4 ? -1.0 / 20 : 1.0 / 5);
        cr_assert(fabs(f14[3 * a + k] - want) <= 1e-13 * W && fabs(f4[3 * a + k] - want) <= 1e-13 * W,
                  "node %d: load %g (14pt), %g (4pt), want %g", a, f14[3 * a + k], f4[3 * a + k], want);
      }
  }
}

/* ---- stresses ---- */

Test(tet10_stress, uniform_F_at_every_point) {
  const bs_material m = make(BS_MODEL_NEO_HOOKEAN, 1e6, 0.3);
  double X[30], x[30], A[9] = {1.1, 0.05, 0, 0, 0.95, 0.02, 0.01, 0, 1.02}, b[3] = {1, 2, 3};
  bs_tet10_rest r;
  rest_tet10(0.08, BS_TET10_RULE_14PT_DEG5, X, &r);
  affine(A, b, X, x);
  bs_stress_fields s[BS_TET10_MAX_POINTS], ref;
  bs_stress_eval(&m, A, &ref);
  bs_tet10_stress(&m, &r, x, s);
  for (int q = 0; q < r.n_points; q++) {
    cr_assert(fabs(s[q].von_mises - ref.von_mises) <= 1e-10 * ref.von_mises, "point %d: von Mises %g vs %g", q,
              s[q].von_mises, ref.von_mises);
    for (int i = 0; i < 9; i++)
      cr_assert(fabs(s[q].cauchy[i] - ref.cauchy[i]) <= 1e-10 * ref.von_mises, "point %d: Cauchy %d", q, i);
  }
  bs_tet10_stress(&m, &r, X, s);
  for (int q = 0; q < r.n_points; q++) cr_assert(s[q].von_mises < 1e-8 * m.mu, "rest: von Mises %g", s[q].von_mises);
}

/* ---- refused elements ---- */

Test(tet10_rest, folded_refused) {
  double X[30], Y[30];
  bs_tet10_rest r;
  bs_error err = {0};
  rest_tet10(0.0, BS_TET10_RULE_14PT_DEG5, X, &r);
  const double V = r.volume;
  /* node 4 (edge 0-1) pushed past vertex 1: the map folds along that edge */
  memcpy(Y, X, sizeof Y);
  for (int k = 0; k < 3; k++) Y[12 + k] = X[k] + 1.3 * (X[3 + k] - X[k]);
  cr_assert_eq(bs_tet10_rest_init(Y, BS_TET10_RULE_14PT_DEG5, &r, &err), BS_ENUMERIC);
  cr_assert(r.fault == BS_TET10_FOLDED_AT_NODE || r.fault == BS_TET10_FOLDED_AT_POINT, "fault %s",
            bs_tet10_fault_name(r.fault));
  cr_assert(r.fault_detJ <= 0 && r.fault_where >= 0, "fault at %d, det J %g", r.fault_where, r.fault_detJ);
  cr_assert(r.n_points == 0 && r.volume == 0, "a refused cache must evaluate to nothing");
  cr_assert(strstr(err.msg, "folded"), "%s", err.msg);
  /* node 4 at 1/5 of its edge: dX/dxi at vertex 0 along the edge is 4 m - 3 X0 - X1 < 0 */
  for (int k = 0; k < 3; k++) Y[12 + k] = X[k] + 0.2 * (X[3 + k] - X[k]);
  cr_assert_eq(bs_tet10_rest_init(Y, BS_TET10_RULE_14PT_DEG5, &r, &err), BS_ENUMERIC);
  cr_assert_eq(r.fault, BS_TET10_FOLDED_AT_NODE, "fault %s", bs_tet10_fault_name(r.fault));
  cr_assert_eq(r.fault_where, 0, "the fold shows at vertex 0 (got %d)", r.fault_where);
  /* node 9 (edge 2-3) pushed inward across the element, past the midpoint of the opposite edge 0-1 */
  memcpy(Y, X, sizeof Y);
  for (int k = 0; k < 3; k++) {
    const double m23 = 0.5 * (X[6 + k] + X[9 + k]), m01 = 0.5 * (X[k] + X[3 + k]);
    Y[3 * 9 + k] = m23 + 1.2 * (m01 - m23);
  }
  cr_assert_eq(bs_tet10_rest_init(Y, BS_TET10_RULE_14PT_DEG5, &r, &err), BS_ENUMERIC);
  cr_assert_neq(r.fault, BS_TET10_SOUND);
  /* not finite, unknown rule */
  memcpy(Y, X, sizeof Y);
  Y[17] = NAN;
  cr_assert_eq(bs_tet10_rest_init(Y, BS_TET10_RULE_14PT_DEG5, &r, &err), BS_ENUMERIC);
  cr_assert_eq(r.fault, BS_TET10_NOT_FINITE);
  cr_assert_eq(bs_tet10_rest_init(X, (bs_tet10_rule_id)7, &r, &err), BS_EINPUT);
  cr_assert_eq(r.fault, BS_TET10_BAD_RULE);
  /* an inverted straight element (two vertices swapped) */
  memcpy(Y, X, sizeof Y);
  for (int k = 0; k < 3; k++) Y[3 + k] = X[6 + k], Y[6 + k] = X[3 + k];
  straight_midsides(Y);
  cr_assert_eq(bs_tet10_rest_init(Y, BS_TET10_RULE_4PT_DEG2, &r, &err), BS_ENUMERIC);
  cr_assert_eq(r.fault, BS_TET10_FOLDED_AT_NODE);
  /* the original is still sound */
  cr_assert_eq(bs_tet10_rest_init(X, BS_TET10_RULE_14PT_DEG5, &r, &err), BS_OK, "%s", err.msg);
  cr_assert(r.fault == BS_TET10_SOUND && fabs(r.volume - V) <= 1e-15 * V);
  cr_assert_str_eq(bs_tet10_fault_name(BS_TET10_FOLDED_AT_POINT), "folded_at_point");
  cr_assert_str_eq(bs_tet10_fault_name((bs_tet10_fault)99), "unknown");
}

/* ---- tet4 -> tet10 ---- */

Test(tet10_mesh, two_tets_sharing_a_face) {
  const double V[15] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 1, 1};
  const int32_t T[8] = {0, 1, 2, 3, 1, 2, 3, 4};
  int32_t n = 0, *T10 = NULL;
  double *P = NULL;
  bs_error err = {0};
  cr_assert_eq(bs_tet10_from_tet4(5, V, 2, T, &n, &P, &T10, &err), BS_OK, "%s", err.msg);
  cr_assert_eq(n, 14, "5 vertices + 9 unique edges = 14 nodes, got %d", n);
  for (int i = 0; i < 15; i++) cr_assert(P[i] == V[i], "vertices kept");
  for (int t = 0; t < 2; t++) {
    for (int a = 0; a < 4; a++) cr_assert_eq(T10[10 * t + a], T[4 * t + a]);
    for (int k = 0; k < 6; k++) {
      const int32_t node = T10[10 * t + 4 + k], i = T[4 * t + bs_tet10_edges[k][0]], j = T[4 * t + bs_tet10_edges[k][1]];
      cr_assert(node >= 5 && node < 14, "edge node %d", node);
      for (int c = 0; c < 3; c++)
        cr_assert(P[3 * node + c] == 0.5 * (V[3 * i + c] + V[3 * j + c]), "node %d is not the midpoint", node);
    }
    double X[30];
    bs_tet10_rest r;
    for (int a = 0; a < 10; a++)
      for (int c = 0; c < 3; c++) X[3 * a + c] = P[3 * T10[10 * t + a] + c];
    cr_assert_eq(bs_tet10_rest_init(X, BS_TET10_RULE_14PT_DEG5, &r, &err), BS_OK, "tet %d: %s", t, err.msg);
    for (int q = 0; q < r.n_points; q++) cr_assert(r.detJ[q] > 0);
    cr_assert(fabs(r.volume - (t == 0 ? 1.0 / 6 : 2.0 / 6)) < 1e-15, "tet %d volume %g", t, r.volume);
  }
  /* the shared face (1,2,3): its edges (1,2), (2,3), (1,3) share their nodes */
  cr_assert_eq(T10[5], T10[10 + 4], "edge (1,2)");  /* tet 0 edge 1 = (1,2); tet 1 edge 0 = (1,2) */
  cr_assert_eq(T10[8], T10[10 + 6], "edge (1,3)");  /* tet 0 edge 4 = (1,3); tet 1 edge 2 = (1,3) */
  cr_assert_eq(T10[9], T10[10 + 5], "edge (2,3)");  /* tet 0 edge 5 = (2,3); tet 1 edge 1 = (2,3) */
  int seen[14] = {0};
  for (int i = 0; i < 20; i++) seen[T10[i]]++;
  for (int v = 0; v < 14; v++) cr_assert(seen[v] >= 1, "node %d unused", v);
  free(P);
  free(T10);
}

Test(tet10_mesh, bad_input) {
  const double V[12] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
  const int32_t out_of_range[4] = {0, 1, 2, 4}, repeated[4] = {0, 1, 1, 3};
  int32_t n = 7, *T10 = (int32_t *)1;
  double *P = (double *)1;
  bs_error err = {0};
  cr_assert_eq(bs_tet10_from_tet4(4, V, 1, out_of_range, &n, &P, &T10, &err), BS_EINPUT);
  cr_assert(n == 0 && P == NULL && T10 == NULL && strstr(err.msg, "outside"), "%s", err.msg);
  cr_assert_eq(bs_tet10_from_tet4(4, V, 1, repeated, &n, &P, &T10, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "repeats"), "%s", err.msg);
  cr_assert_eq(bs_tet10_from_tet4(4, V, -1, repeated, &n, &P, &T10, &err), BS_EINPUT);
  cr_assert_eq(bs_tet10_from_tet4(4, NULL, 1, repeated, &n, &P, &T10, &err), BS_EINPUT);
  /* no tets: the vertices alone */
  cr_assert_eq(bs_tet10_from_tet4(4, V, 0, NULL, &n, &P, &T10, &err), BS_OK, "%s", err.msg);
  cr_assert(n == 4 && P && P[3] == 1);
  free(P);
  free(T10);
}

/* det J at xi of the element with nodes X (independent of the library's). */
static double detJ_at(const double X[30], const double xi[3]) {
  double dN[30], J[9];
  bs_tet10_shape_grad(xi, dN);
  for (int m = 0; m < 3; m++)
    for (int k = 0; k < 3; k++) {
      double s = 0;
      for (int a = 0; a < 10; a++) s += X[3 * a + m] * dN[3 * a + k];
      J[3 * m + k] = s;
    }
  return J[0] * (J[4] * J[8] - J[5] * J[7]) - J[1] * (J[3] * J[8] - J[5] * J[6]) + J[2] * (J[3] * J[7] - J[4] * J[6]);
}

/* One midside node moved off a straight tet10 (the usual way an element is
 * curved to a boundary): J = J0 + d (grad N_m)^T is a rank-one update, so det J
 * is affine in xi and its minimum is at a vertex: the node screen of
 * bs_tet10_rest_init is then exact. Against det J sampled on 20000 points. */
Test(tet10_rest, node_screen_exact_for_one_moved_midside_node) {
  int n_refused = 0, n_accepted = 0;
  for (int t = 0; t < 200; t++) {
    double X[30], Y[30];
    bs_tet10_rest r;
    bs_error err = {0};
    rest_tet10(0.0, BS_TET10_RULE_14PT_DEG5, X, &r);
    memcpy(Y, X, sizeof Y);
    const int node = 4 + t % 6;
    for (int k = 0; k < 3; k++) Y[3 * node + k] += 0.6 * nrand();
    double lo = INFINITY;
    for (int s = 0; s < 20000; s++) {
      double xi[3] = {urand(), urand(), urand()};
      if (xi[0] + xi[1] + xi[2] > 1) continue;
      lo = fmin(lo, detJ_at(Y, xi));
    }
    for (int b = 0; b < 4; b++) lo = fmin(lo, detJ_at(Y, bs_tet10_ref_nodes[b]));
    if (fabs(lo) < 1e-3 * det4(X)) continue; /* too close to call */
    const int st = bs_tet10_rest_init(Y, BS_TET10_RULE_14PT_DEG5, &r, &err);
    cr_assert_eq(st == BS_OK, lo > 0, "sampled min det J %g, status %d (%s)", lo, st, bs_tet10_fault_name(r.fault));
    if (st == BS_OK) n_accepted++;
    else n_refused++;
  }
  cr_log_info("one moved midside node: %d accepted, %d refused, all agreeing with sampling\n", n_accepted, n_refused);
  cr_assert(n_refused >= 10 && n_accepted >= 10, "%d refused, %d accepted", n_refused, n_accepted);
}
