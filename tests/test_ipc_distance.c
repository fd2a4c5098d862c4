/* IPC kernels (bs_ipc.h): every distance type and the classified
 * point-triangle / edge-edge distances against a brute-force minimisation
 * (a dense parameter grid refined by zooming: the squared distance is convex
 * in the barycentric / edge parameters) and against an independent closed
 * form (Ericson, Real-Time Collision Detection, 5.1.5 and 5.1.9); gradients
 * and Hessians against central differences (the best of several steps, at
 * steps that keep the classified type) at random and near-degenerate
 * configurations; the barrier b, b', b'' near 0 and near dhat; the pair
 * energies (with the mollifier) against differences; the projected Hessian
 * is PSD, equal to the unprojected one when that is PSD; the kappa helpers;
 * status codes. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "bs_ipc.h"
#include "bs_svd.h"
#define BS_TEST_SEED 0x1A2B3C4D5E6F7081ull
#include "test_dense.h"
#include "test_random.h"

#include "ipc_ref.h"

static void rand_pts(int n, double *x) {
  for (int i = 0; i < 3 * n; i++) x[i] = 2 * urand() - 1;
}

/* ---- the functions under test, as f(x, g, H, type) over n coordinates ---- */
typedef double (*dfun)(const double *x, double *g, double *H, int *type);
static double f_pp(const double *x, double *g, double *H, int *ty) { return *ty = 0, bs_ipc_pp_d2(x, x + 3, g, H); }
static double f_pe(const double *x, double *g, double *H, int *ty) {
  return *ty = 0, bs_ipc_pe_d2(x, x + 3, x + 6, g, H);
}
static double f_plane(const double *x, double *g, double *H, int *ty) {
  return *ty = 0, bs_ipc_pt_plane_d2(x, x + 3, x + 6, x + 9, g, H);
}
static double f_line(const double *x, double *g, double *H, int *ty) {
  return *ty = 0, bs_ipc_ee_line_d2(x, x + 3, x + 6, x + 9, g, H);
}
static double f_pt(const double *x, double *g, double *H, int *ty) {
  bs_ipc_pt_type t;
  const double d = bs_ipc_pt_d2_full(x, x + 3, x + 6, x + 9, &t, g, H);
  return *ty = (int)t, d;
}
static double f_ee(const double *x, double *g, double *H, int *ty) {
  bs_ipc_ee_type t;
  const double d = bs_ipc_ee_d2_full(x, x + 3, x + 6, x + 9, &t, g, H);
  return *ty = (int)t, d;
}
static double moll_eps = 1;
static double f_moll(const double *x, double *g, double *H, int *ty) {
  return *ty = 0, bs_ipc_mollifier(x, x + 3, x + 6, x + 9, moll_eps, g, H);
}

/* The worst relative differences seen (printed at the end of a test). */
static double worst_g, worst_H;

/* Central differences of f at x over steps h L (h = 1e-3 ... 1e-7) that keep
 * x's type at every x +- h L e_i; the best step's max errors, relative to
 * max|g| + max|H| L (gradient) and max|H| (Hessian), must be below tol. */
static void fd_check(dfun f, int n, const double *x, double L, double tol, const char *what) {
  double g[12], H[144], xp[12], xm[12], gp[12], gm[12];
  int ty, typ, tym;
  f(x, g, H, &ty);
  double sg = 0, sH = 0, bg = INFINITY, bH = INFINITY;
  for (int i = 0; i < n; i++) sg = fmax(sg, fabs(g[i]));
  for (int i = 0; i < n * n; i++) sH = fmax(sH, fabs(H[i]));
  for (int i = 0; i < n; i++)
    for (int j = 0; j < n; j++) cr_assert(H[i * n + j] == H[j * n + i], "%s: Hessian not symmetric", what);
  for (double h = 1e-3 * L; h > 1e-8 * L; h /= 10) {
    double eg = 0, eH = 0;
    int stable = 1;
    for (int i = 0; i < n && stable; i++) {
      memcpy(xp, x, n * sizeof(double));
      memcpy(xm, x, n * sizeof(double));
      xp[i] += h, xm[i] -= h;
      const double fp = f(xp, gp, NULL, &typ), fm = f(xm, gm, NULL, &tym);
      stable = typ == ty && tym == ty;
      eg = fmax(eg, fabs((fp - fm) / (2 * h) - g[i]));
      for (int j = 0; j < n; j++) eH = fmax(eH, fabs((gp[j] - gm[j]) / (2 * h) - H[j * n + i]));
    }
    if (stable) bg = fmin(bg, eg), bH = fmin(bH, eH);
  }
  cr_assert(isfinite(bg), "%s: no step keeps the type %d", what, ty);
  const double rg = bg / (sg + sH * L + 1e-300), rH = bH / (sH + 1e-300);
  worst_g = fmax(worst_g, rg), worst_H = fmax(worst_H, rH);
  cr_assert(rg < tol && rH < tol, "%s (type %d): FD errors gradient %g Hessian %g", what, ty, rg, rH);
}

/* ---- references ---- */
/* Squared distance from p to a + u ab + v ac over the triangle, by a grid in
 * (u, v) refined 8 times around the best sample (convex: it converges). */
static double brute_pt(const double *x) {
  const double *p = x, *t0 = x + 3;
  double ab[3], ac[3], best = INFINITY, cu = 0.5, cv = 0.5, w = 0.5;
  for (int c = 0; c < 3; c++) ab[c] = x[6 + c] - t0[c], ac[c] = x[9 + c] - t0[c];
  for (int level = 0; level < 40; level++) {
    const int N = level == 0 ? 200 : 20;
    double bu = cu, bv = cv;
    for (int i = 0; i <= N; i++)
      for (int j = 0; j <= N; j++) {
        double u = cu - w + 2 * w * i / N, v = cv - w + 2 * w * j / N;
        u = fmax(u, 0), v = fmax(v, 0);
        if (u + v > 1) u /= u + v, v = 1 - u;
        double r[3];
        for (int c = 0; c < 3; c++) r[c] = p[c] - t0[c] - u * ab[c] - v * ac[c];
        if (dot3(r, r) < best) best = dot3(r, r), bu = u, bv = v;
      }
    cu = bu, cv = bv, w = level == 0 ? 2.0 / 200 : w / 2;
  }
  return best;
}

static double brute_ee(const double *x) {
  double a[3], b[3], best = INFINITY, cs = 0.5, ct = 0.5, w = 0.5;
  for (int c = 0; c < 3; c++) a[c] = x[3 + c] - x[c], b[c] = x[9 + c] - x[6 + c];
  for (int level = 0; level < 40; level++) {
    const int N = level == 0 ? 200 : 20;
    double bs = cs, bt = ct;
    for (int i = 0; i <= N; i++)
      for (int j = 0; j <= N; j++) {
        const double s = fmin(fmax(cs - w + 2 * w * i / N, 0), 1), t = fmin(fmax(ct - w + 2 * w * j / N, 0), 1);
        double r[3];
        for (int c = 0; c < 3; c++) r[c] = x[c] + s * a[c] - x[6 + c] - t * b[c];
        if (dot3(r, r) < best) best = dot3(r, r), bs = s, bt = t;
      }
    cs = bs, ct = bt, w = level == 0 ? 2.0 / 200 : w / 2;
  }
  return best;
}

/* ---- distance values ---- */
Test(ipc_distance, values_against_brute_force_and_ericson) {
  double x[12];
  for (int it = 0; it < 300; it++) {
    rand_pts(4, x);
    const double dpt = bs_ipc_pt_d2_full(x, x + 3, x + 6, x + 9, NULL, NULL, NULL), bpt = brute_pt(x);
    cr_assert(dpt <= bpt + 1e-14 && bpt - dpt < 1e-11, "pt %d: %.17g vs brute %.17g", it, dpt, bpt);
    const double dee = bs_ipc_ee_d2_full(x, x + 3, x + 6, x + 9, NULL, NULL, NULL), bee = brute_ee(x);
    cr_assert(dee <= bee + 1e-14 && bee - dee < 1e-11, "ee %d: %.17g vs brute %.17g", it, dee, bee);
  }
  for (int it = 0; it < 100000; it++) {
    rand_pts(4, x);
    const double dpt = bs_ipc_pt_d2_full(x, x + 3, x + 6, x + 9, NULL, NULL, NULL);
    const double ept = ericson_pt(x, x + 3, x + 6, x + 9);
    cr_assert(fabs(dpt - ept) < 1e-12 * (1 + ept), "pt %d: %.17g vs Ericson %.17g", it, dpt, ept);
    const double dee = bs_ipc_ee_d2_full(x, x + 3, x + 6, x + 9, NULL, NULL, NULL);
    const double eee = ericson_ee(x, x + 3, x + 6, x + 9);
    cr_assert(dee <= eee + 1e-12 * (1 + eee) && eee - dee < 1e-9, "ee %d: %.17g vs Ericson %.17g", it, dee, eee);
  }
}

/* Every type reached by the classification, each one's value checked. */
Test(ipc_distance, every_type_is_reached) {
  int seen_pt[7] = {0}, seen_ee[9] = {0};
  double x[12];
  for (int it = 0; it < 20000; it++) {
    rand_pts(4, x);
    for (int c = 0; c < 3; c++) x[c] *= 3; /* the point far more often outside */
    bs_ipc_pt_type tp;
    bs_ipc_ee_type te;
    bs_ipc_pt_d2_full(x, x + 3, x + 6, x + 9, &tp, NULL, NULL);
    bs_ipc_ee_d2_full(x, x + 3, x + 6, x + 9, &te, NULL, NULL);
    seen_pt[tp]++, seen_ee[te]++;
  }
  for (int k = 0; k < 7; k++) cr_assert(seen_pt[k] > 0, "point-triangle type %d never seen", k);
  for (int k = 0; k < 9; k++) cr_assert(seen_ee[k] > 0, "edge-edge type %d never seen", k);
}

/* Near-degenerate values: parallel edges (classified on the endpoints),
 * nearly parallel ones, crossing edges (0), a point on an edge (0), a
 * degenerate triangle. */
Test(ipc_distance, degenerate_values) {
  double x[12] = {0, 0, 0, 1, 0, 0, 0.3, 0.2, 0, 1.5, 0.2, 0}; /* parallel, offset 0.2, overlapping */
  bs_ipc_ee_type te;
  double d = bs_ipc_ee_d2_full(x, x + 3, x + 6, x + 9, &te, NULL, NULL);
  cr_assert(te != BS_IPC_EA_EB && fabs(d - 0.04) < 1e-15, "parallel: type %d d2 %g", (int)te, d);
  x[10] = 0.2 + 1e-6; /* nearly parallel, closest points inside */
  d = bs_ipc_ee_d2_full(x, x + 3, x + 6, x + 9, &te, NULL, NULL);
  cr_assert(fabs(d - brute_ee(x)) < 1e-12, "nearly parallel: %.17g vs %.17g", d, brute_ee(x));
  const double xc[12] = {-1, 0, 0, 1, 0, 0, 0.2, -1, 0, 0.2, 1, 0}; /* crossing */
  d = bs_ipc_ee_d2_full(xc, xc + 3, xc + 6, xc + 9, &te, NULL, NULL);
  cr_assert(te == BS_IPC_EA_EB && d == 0, "crossing: type %d d2 %g", (int)te, d);
  const double pe[9] = {0.25, 0, 0, 0, 0, 0, 1, 0, 0};
  cr_assert(bs_ipc_pe_d2(pe, pe + 3, pe + 6, NULL, NULL) == 0);
  const double tri[12] = {0.3, 1, 0.5, 0, 0, 0, 1, 0, 0, 2, 0, 0}; /* collinear triangle */
  bs_ipc_pt_type tp;
  d = bs_ipc_pt_d2_full(tri, tri + 3, tri + 6, tri + 9, &tp, NULL, NULL);
  cr_assert(tp != BS_IPC_P_T && fabs(d - 1.25) < 1e-15, "degenerate triangle: type %d d2 %g", (int)tp, d);
}

/* ---- derivatives ---- */
Test(ipc_distance, derivatives_random) {
  double x[12];
  worst_g = worst_H = 0;
  for (int it = 0; it < 200; it++) {
    rand_pts(4, x);
    fd_check(f_pp, 6, x, 1, 1e-7, "PP");
    fd_check(f_pe, 9, x, 1, 1e-7, "PE");
    fd_check(f_plane, 12, x, 1, 1e-6, "PT plane");
    fd_check(f_line, 12, x, 1, 1e-6, "EE lines");
    fd_check(f_pt, 12, x, 1, 1e-6, "PT full");
    fd_check(f_ee, 12, x, 1, 1e-6, "EE full");
    moll_eps = 1e3 * bs_ipc_mollifier_eps(x, x + 3, x + 6, x + 9); /* active: c < eps */
    fd_check(f_moll, 12, x, 1, 1e-6, "mollifier");
  }
  fprintf(stderr, "ipc_distance random: worst FD relative error gradient %.3g Hessian %.3g\n", worst_g, worst_H);
}

/* Rotates the n points of x by a random rotation and shifts them (the
 * near-degenerate cases are built axis-aligned). */
static void place(double *x, int n) {
  double Q[9], s[3] = {nrand(), nrand(), nrand()};
  rand_rot(Q);
  for (int k = 0; k < n; k++) {
    double y[3];
    for (int r = 0; r < 3; r++) y[r] = Q[3 * r] * x[3 * k] + Q[3 * r + 1] * x[3 * k + 1] + Q[3 * r + 2] * x[3 * k + 2];
    for (int r = 0; r < 3; r++) x[3 * k + r] = y[r] + s[r];
  }
}

Test(ipc_distance, derivatives_near_degenerate) {
  worst_g = worst_H = 0;
  for (int it = 0; it < 20; it++) {
    const double angles[4] = {1e-2, 1e-3, 1e-4, 0};
    for (int k = 0; k < 4; k++) { /* (nearly) parallel edges, overlapping */
      const double th = angles[k];
      const double sh = th > 0 ? 0.3 : 1.3; /* exactly parallel: apart along the axis (overlapping
                                              ones are at a kink: any tilt makes the type EA_EB) */
      double x[12] = {0, 0, 0, 1, 0, 0, sh, 0.1, 0.05, sh + cos(th), 0.1 + sin(th), 0.05};
      place(x, 4);
      fd_check(f_ee, 12, x, th > 0 ? fmin(1, 30 * th) : 1, 1e-5, "EE nearly parallel");
    }
    double xc[12] = {-1, 0, 0, 1, 0, 0, 0.2, -1, 0, 0.2 + 0.3 * urand(), 1, 0}; /* crossing: d = 0 */
    place(xc, 4);
    fd_check(f_ee, 12, xc, 1, 1e-6, "EE crossing");
    fd_check(f_line, 12, xc, 1, 1e-6, "EE lines crossing");
    double xp[9] = {0.3, 0, 0, 0, 0, 0, 1, 0, 0}; /* a point on an edge */
    place(xp, 3);
    fd_check(f_pe, 9, xp, 1, 1e-6, "PE on the edge");
    /* p just outside edge E0 in the plane, 1e-6 from it: P_E0 */
    double xe[12] = {0.4, -1e-6, 0, 0, 0, 0, 1, 0, 0, 0.2, 1, 0};
    place(xe, 4);
    fd_check(f_pt, 12, xe, 1e-7, 1e-5, "PT beside an edge");
    /* p in t0's region 1e-3 from the P_E0 region's boundary, and in E0's
     * region 1e-3 from the P_T one, above the plane */
    double xv[12] = {-1e-3, -0.2, 0.3, 0, 0, 0, 1, 0, 0, 0.2, 1, 0};
    place(xv, 4);
    fd_check(f_pt, 12, xv, 1e-3, 1e-5, "PT vertex region near an edge region");
    double xf[12] = {0.5, -1e-3, 0.3, 0, 0, 0, 1, 0, 0, 0.2, 1, 0};
    place(xf, 4);
    fd_check(f_pt, 12, xf, 1e-3, 1e-5, "PT edge region near the face region");
    double xo[12] = {0.3, 0.3, 1e-4, 0, 0, 0, 1, 0, 0, 0.2, 1, 0}; /* nearly on the face */
    place(xo, 4);
    fd_check(f_pt, 12, xo, 1e-4, 1e-5, "PT over the face");
  }
  fprintf(stderr, "ipc_distance near-degenerate: worst FD relative error gradient %.3g Hessian %.3g\n", worst_g,
          worst_H);
}

/* ---- barrier ---- */
Test(ipc_barrier, values_and_derivatives) {
  const double dh = 2.5e-5;
  double b[3], bp[3], bm[3];
  cr_assert_eq(bs_ipc_barrier(dh, dh, b), BS_OK);
  cr_assert(b[0] == 0 && b[1] == 0 && b[2] == 0);
  cr_assert_eq(bs_ipc_barrier(2 * dh, dh, b), BS_OK);
  cr_assert(b[0] == 0 && b[1] == 0 && b[2] == 0);
  const double rel[] = {1e-8, 1e-5, 1e-2, 0.3, 0.9, 1 - 1e-3, 1 - 1e-5};
  for (size_t i = 0; i < sizeof rel / sizeof *rel; i++) {
    const double d = rel[i] * dh, h = 1e-4 * fmin(d, dh - d);
    cr_assert_eq(bs_ipc_barrier(d, dh, b), BS_OK);
    cr_assert(b[0] > 0 && b[1] < 0 && b[2] > 0, "signs at %g", rel[i]);
    const double ref = (double)(-(long double)(d - dh) * (d - dh) * logl((long double)d / dh)); /* 64-bit mantissa */
    cr_assert(fabs(b[0] - ref) <= 1e-12 * fabs(ref) + 1e-300, "b at %g: %g vs %g", rel[i], b[0], ref);
    bs_ipc_barrier(d + h, dh, bp);
    bs_ipc_barrier(d - h, dh, bm);
    const double e1 = fabs((bp[0] - bm[0]) / (2 * h) - b[1]) / fabs(b[1]);
    const double e2 = fabs((bp[1] - bm[1]) / (2 * h) - b[2]) / fabs(b[2]);
    cr_assert(e1 < 1e-6 && e2 < 1e-6, "at d = %g dhat: b' error %g, b'' error %g", rel[i], e1, e2);
  }
  cr_assert_eq(bs_ipc_barrier(0, dh, b), BS_IPC_ECONTACT);
  cr_assert(b[0] == 0 && b[1] == 0 && b[2] == 0);
  cr_assert_eq(bs_ipc_barrier(-1e-9, dh, b), BS_IPC_ECONTACT);
  cr_assert_eq(bs_ipc_barrier(NAN, dh, b), BS_EINPUT);
  cr_assert_eq(bs_ipc_barrier(1e-6, 0, b), BS_EINPUT);
  cr_assert_eq(BS_IPC_ECONTACT, BS_ENUMERIC);
}

/* E(x) of a pair with its gradient and unprojected Hessian as dfun. */
static double e_dhat = 0.3, e_kappa = 7, e_epsx = 1;
static double f_ept(const double *x, double *g, double *H, int *ty) {
  double E;
  *ty = (int)bs_ipc_pt_classify(x, x + 3, x + 6, x + 9);
  cr_assert_eq(bs_ipc_pt_energy(x, x + 3, x + 6, x + 9, e_dhat, e_kappa, 0, &E, g, H, NULL), BS_OK);
  return E;
}
static double f_eee(const double *x, double *g, double *H, int *ty) {
  double E;
  *ty = (int)bs_ipc_ee_classify(x, x + 3, x + 6, x + 9);
  cr_assert_eq(bs_ipc_ee_energy(x, x + 3, x + 6, x + 9, e_epsx, e_dhat, e_kappa, 0, &E, g, H, NULL), BS_OK);
  return E;
}

/* The projected Hessian: PSD to 1e-12 of its largest eigenvalue, equal to
 * the unprojected one when that is PSD, and projecting it again changes no
 * bit (it is PSD). */
static void check_projection(const double *Hu, const double *Hp, const char *what) {
  double lam[12], lamu[12], mx = 0, mn = INFINITY, mnu = INFINITY, Hpp[144];
  sym_eig_dense(12, Hp, lam, NULL);
  sym_eig_dense(12, Hu, lamu, NULL);
  for (int i = 0; i < 12; i++) mx = fmax(mx, fabs(lamu[i])), mn = fmin(mn, lam[i]), mnu = fmin(mnu, lamu[i]);
  cr_assert(mn >= -1e-12 * mx, "%s: projected smallest eigenvalue %g (largest %g)", what, mn, mx);
  if (mnu >= -1e-12 * mx) cr_assert(memcmp(Hu, Hp, sizeof(double) * 144) == 0, "%s: PSD Hessian changed", what);
  memcpy(Hpp, Hp, sizeof Hpp);
  bs_sym_psd_project(12, Hpp);
  cr_assert(memcmp(Hpp, Hp, sizeof Hpp) == 0, "%s: projection not idempotent", what);
}

/* Random pairs within dhat: FD of the unprojected derivatives, projection. */
Test(ipc_barrier, energy_derivatives_and_projection) {
  worst_g = worst_H = 0;
  int n_pt = 0, n_ee = 0, n_moll = 0;
  for (int it = 0; it < 4000 && (n_pt < 150 || n_ee < 150); it++) {
    double x[12], rest[12], g[12], Hu[144], Hp[144], E;
    rand_pts(4, x);
    for (int i = 0; i < 12; i++) rest[i] = x[i] + 0.2 * (urand() - 0.5);
    const double dpt = bs_ipc_pt_d2_full(x, x + 3, x + 6, x + 9, NULL, NULL, NULL);
    if (dpt < e_dhat * e_dhat && dpt > 1e-4 && n_pt < 150) {
      fd_check(f_ept, 12, x, 1e-2, 1e-5, "PT energy");
      bs_ipc_pt_energy(x, x + 3, x + 6, x + 9, e_dhat, e_kappa, 0, &E, g, Hu, NULL);
      bs_ipc_pt_energy(x, x + 3, x + 6, x + 9, e_dhat, e_kappa, 1, &E, g, Hp, NULL);
      check_projection(Hu, Hp, "PT");
      n_pt++;
    }
    /* make the edges nearly parallel half of the time (mollifier active) */
    if (it % 2)
      for (int c = 0; c < 3; c++) x[9 + c] = x[6 + c] + (x[3 + c] - x[c]) * 0.7 + 0.02 * (urand() - 0.5);
    const double dee = bs_ipc_ee_d2_full(x, x + 3, x + 6, x + 9, NULL, NULL, NULL);
    if (dee < e_dhat * e_dhat && dee > 1e-4 && n_ee < 150) {
      e_epsx = bs_ipc_mollifier_eps(rest, rest + 3, rest + 6, rest + 9);
      n_moll += bs_ipc_mollifier(x, x + 3, x + 6, x + 9, e_epsx, NULL, NULL) < 1;
      fd_check(f_eee, 12, x, 1e-2, 1e-5, "EE energy");
      bs_ipc_ee_energy(x, x + 3, x + 6, x + 9, e_epsx, e_dhat, e_kappa, 0, &E, g, Hu, NULL);
      bs_ipc_ee_energy(x, x + 3, x + 6, x + 9, e_epsx, e_dhat, e_kappa, 1, &E, g, Hp, NULL);
      check_projection(Hu, Hp, "EE");
      n_ee++;
    }
  }
  cr_assert(n_pt == 150 && n_ee == 150 && n_moll >= 20, "pairs: %d PT, %d EE, %d mollified", n_pt, n_ee, n_moll);
  fprintf(stderr, "ipc energy: %d PT, %d EE (%d mollified) pairs: worst FD relative error gradient %.3g Hessian %.3g\n",
          n_pt, n_ee, n_moll, worst_g, worst_H);
}

/* Outside dhat everything is 0; touching pairs and bad arguments are named
 * statuses with zeroed outputs; kappa = 0 gives a zero (PSD, unchanged)
 * Hessian. */
Test(ipc_barrier, energy_statuses) {
  double E = 1, g[12], H[144];
  bs_error err;
  const double far[12] = {0, 0, 5, 0, 0, 0, 1, 0, 0, 0, 1, 0};
  cr_assert_eq(bs_ipc_pt_energy(far, far + 3, far + 6, far + 9, 1, 10, 1, &E, g, H, &err), BS_OK);
  cr_assert(E == 0 && g[0] == 0 && H[0] == 0);
  const double on[12] = {0.2, 0.2, 0, 0, 0, 0, 1, 0, 0, 0, 1, 0};
  cr_assert_eq(bs_ipc_pt_energy(on, on + 3, on + 6, on + 9, 1, 10, 1, &E, g, H, &err), BS_IPC_ECONTACT);
  cr_assert(E == 0 && isfinite(g[0]) && g[0] == 0 && strstr(err.msg, "<= 0"));
  const double cross[12] = {-1, 0, 0, 1, 0, 0, 0, -1, 0, 0, 1, 0};
  cr_assert_eq(bs_ipc_ee_energy(cross, cross + 3, cross + 6, cross + 9, 1, 1, 10, 1, &E, g, H, &err),
               BS_IPC_ECONTACT);
  cr_assert_eq(bs_ipc_ee_energy(cross, cross + 3, cross + 6, cross + 9, 0, 1, 10, 1, &E, g, H, &err), BS_EINPUT);
  cr_assert_eq(bs_ipc_pt_energy(far, far + 3, far + 6, far + 9, 0, 10, 1, &E, g, H, &err), BS_EINPUT);
  cr_assert_eq(bs_ipc_pt_energy(far, far + 3, far + 6, far + 9, 1, -1, 1, &E, g, H, &err), BS_EINPUT);
  double bad[12];
  memcpy(bad, far, sizeof bad);
  bad[4] = NAN;
  cr_assert_eq(bs_ipc_pt_energy(bad, bad + 3, bad + 6, bad + 9, 1, 10, 1, &E, g, H, &err), BS_EINPUT);
  const double near[12] = {0.2, 0.2, 0.1, 0, 0, 0, 1, 0, 0, 0, 1, 0};
  cr_assert_eq(bs_ipc_pt_energy(near, near + 3, near + 6, near + 9, 1, 0, 1, &E, g, H, &err), BS_OK);
  for (int i = 0; i < 144; i++) cr_assert(H[i] == 0);
  cr_assert_eq(bs_ipc_pt_energy(near, near + 3, near + 6, near + 9, 1, 10, 1, &E, NULL, NULL, &err), BS_OK);
  cr_assert(E > 0);
}

/* ---- kappa ---- */
Test(ipc_barrier, kappa_helpers) {
  double kmin, kmax, b[3];
  bs_error err;
  const double mass = 0.01, dhat = 1e-3, diag = 2;
  cr_assert_eq(bs_ipc_kappa_bounds(mass, dhat, diag, 1e11, &kmin, &kmax, &err), BS_OK, "%s", err.msg);
  const double d0 = (1e-8 * diag) * (1e-8 * diag);
  bs_ipc_barrier(d0, dhat * dhat, b);
  cr_assert(fabs(kmin - 1e11 * mass / (4 * d0 * b[2])) <= 1e-14 * kmin && kmax == 100 * kmin);
  /* d0 beyond dhat: d0 = dhat^2 / 2 */
  cr_assert_eq(bs_ipc_kappa_bounds(mass, 1e-9, diag, 1e11, &kmin, &kmax, &err), BS_OK);
  bs_ipc_barrier(0.5e-18, 1e-18, b);
  cr_assert(fabs(kmin - 1e11 * mass / (4 * 0.5e-18 * b[2])) <= 1e-14 * kmin);
  cr_assert_eq(bs_ipc_kappa_bounds(0, dhat, diag, 1e11, &kmin, &kmax, &err), BS_EINPUT);
  cr_assert_eq(bs_ipc_kappa_bounds(mass, dhat, INFINITY, 1e11, &kmin, &kmax, &err), BS_EINPUT);
  /* initial: argmin |ge + k gb| = 3 here, clamped */
  const double gb[3] = {1, 2, 0}, ge[3] = {-3, -6, 5}, zero[3] = {0, 0, 0};
  cr_assert(fabs(bs_ipc_kappa_initial(3, ge, gb, 1, 100) - 3) < 1e-15);
  cr_assert_eq(bs_ipc_kappa_initial(3, ge, gb, 10, 100), 10);
  cr_assert_eq(bs_ipc_kappa_initial(3, ge, gb, 0.1, 2), 2);
  cr_assert_eq(bs_ipc_kappa_initial(3, ge, zero, 0.5, 2), 1);
  cr_assert_eq(bs_ipc_kappa_initial(3, ge, zero, 1.5, 2), 1.5);
  /* update: doubles only below eps twice and decreasing, capped */
  const double eps = bs_ipc_kappa_d2_eps(diag);
  cr_assert(fabs(eps - 4e-18) < 1e-30);
  cr_assert_eq(bs_ipc_kappa_update(5, 100, 0.5 * eps, 0.25 * eps, eps), 10);
  cr_assert_eq(bs_ipc_kappa_update(5, 8, 0.5 * eps, 0.25 * eps, eps), 8);
  cr_assert_eq(bs_ipc_kappa_update(5, 100, 0.25 * eps, 0.5 * eps, eps), 5);
  cr_assert_eq(bs_ipc_kappa_update(5, 100, 2 * eps, 0.5 * eps, eps), 5);
  cr_assert_eq(bs_ipc_kappa_update(5, 100, 0.5 * eps, 0.5 * eps, eps), 5);
}
