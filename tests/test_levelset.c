/* Level sets: for every analytic shape, its complement, its moving versions
 * and the grid, grad vs central differences of phi and Hessian vs central
 * differences of grad at random points away from the non-smooth sets, with
 * O(h^2) convergence; |grad| = 1 for SDFs; the sign convention at known
 * points; the projection lands on phi = 0 and is idempotent; moving shapes
 * equal the static shape at the transformed point; obstacle velocities; grid
 * interpolation (exact on trilinear functions), extrapolation, accuracy of a
 * sampled sphere, save/load round trip and load errors; parameter errors. */
#define _POSIX_C_SOURCE 200809L
#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "bs_levelset.h"
#include "bs_vec3.h"

/* ---- helpers ------------------------------------------------------------ */

static uint64_t rng = 0x9E3779B97F4A7C15ull;
static double urand(void) {
  uint64_t z = (rng += 0x9E3779B97F4A7C15ull);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  z ^= z >> 31;
  return (double)(z >> 11) * 0x1.0p-53;
}
static double urange(double a, double b) { return a + (b - a) * urand(); }

/* Rotation matrix of the axis-angle vector r (Rodrigues). */
static void rot_aa(const double r[3], double R[9]) {
  double th = sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
  memset(R, 0, 9 * sizeof(double));
  R[0] = R[4] = R[8] = 1;
  if (th == 0) return;
  double a[3] = {r[0] / th, r[1] / th, r[2] / th}, c = cos(th), s = sin(th);
  double K[9] = {0, -a[2], a[1], a[2], 0, -a[0], -a[1], a[0], 0};
  for (int i = 0; i < 3; i++)
    for (int j = 0; j < 3; j++) {
      double K2 = 0;
      for (int k = 0; k < 3; k++) K2 += K[3 * i + k] * K[3 * k + j];
      R[3 * i + j] += s * K[3 * i + j] + (1 - c) * K2;
    }
}
static void mv(const double A[9], const double x[3], double y[3]) {
  for (int i = 0; i < 3; i++) y[i] = A[3 * i] * x[0] + A[3 * i + 1] * x[1] + A[3 * i + 2] * x[2];
}
static void mtv(const double A[9], const double x[3], double y[3]) {
  for (int i = 0; i < 3; i++) y[i] = A[i] * x[0] + A[3 + i] * x[1] + A[6 + i] * x[2];
}
/* R H R^T */
static void conj3(const double R[9], const double H[9], double out[9]) {
  for (int i = 0; i < 3; i++)
    for (int j = 0; j < 3; j++) {
      double v = 0;
      for (int a = 0; a < 3; a++)
        for (int b = 0; b < 3; b++) v += R[3 * i + a] * H[3 * a + b] * R[3 * j + b];
      out[3 * i + j] = v;
    }
}
static double maxdiff(int n, const double *a, const double *b) {
  double m = 0;
  for (int i = 0; i < n; i++) m = fmax(m, fabs(a[i] - b[i]));
  return m;
}
/* Angle of the rotation A^T B. */
static double rot_angle(const double A[9], const double B[9]) {
  double tr = 0;
  for (int i = 0; i < 3; i++)
    for (int k = 0; k < 3; k++) tr += A[3 * k + i] * B[3 * k + i];
  return acos(fmax(-1.0, fmin(1.0, 0.5 * (tr - 1))));
}

/* ---- the shapes under test (oblique placements) ------------------------ */

enum { N_ANALYTIC = 5 };

static bs_levelset *make_shape(int kind) {
  bs_levelset *ls = NULL;
  bs_error err;
  int st = -1;
  double c[3] = {0.1, -0.2, 0.3};
  switch (kind) {
    case 0: {
      double n[3] = {0.3, 1, -0.2};
      st = bs_levelset_create_halfspace(n, 0.4, &ls, &err);
      break;
    }
    case 1: st = bs_levelset_create_sphere(c, 0.7, &ls, &err); break;
    case 2: {
      double half[3] = {0.5, 0.3, 0.4};
      st = bs_levelset_create_box(c, half, &ls, &err);
      break;
    }
    case 3: {
      double a[3] = {1, 2, 0.5};
      st = bs_levelset_create_cylinder(c, a, 0.4, 0.6, &ls, &err);
      break;
    }
    case 4: {
      double a[3] = {0.2, -1, 0.3};
      st = bs_levelset_create_torus(c, a, 0.8, 0.25, &ls, &err);
      break;
    }
  }
  cr_assert_eq(st, 0, "shape %d: %s", kind, err.msg);
  return ls;
}

static void set_test_velocity(bs_levelset *ls) {
  bs_error err;
  double v[3] = {0.3, -0.5, 0.2}, w[3] = {0.7, 0.4, -1.1};
  cr_assert_eq(bs_levelset_set_velocity(ls, v, w, &err), 0, "%s", err.msg);
}
static void set_test_keyframes(bs_levelset *ls) {
  bs_error err;
  double t[3] = {0, 1, 2.5};
  double d[9] = {0, 0, 0, 0.5, -0.2, 0.1, 0.3, 0.4, -0.6};
  double r[9] = {0, 0, 0, 0.4, -0.9, 0.3, 1.2, 0.5, -0.7};
  cr_assert_eq(bs_levelset_set_keyframes(ls, 3, t, d, r, &err), 0, "%s", err.msg);
}

/* A lower bound on the distance from x to where phi is not C^2 (in the
 * shape's local frame; for grids, cell faces and the grid box). */
static double smooth_margin(const bs_levelset *ls, double t, const double x[3]) {
  double y[3];
  bs_levelset_local_point(ls, t, x, y);
  const double *p = ls->param;
  double rho = hypot(y[0], y[1]);
  switch (ls->kind) {
    case BS_LS_HALFSPACE: return 1e9;
    case BS_LS_SPHERE: return sqrt(y[0] * y[0] + y[1] * y[1] + y[2] * y[2]);
    case BS_LS_BOX: {
      double q[3], m = 1e9;
      for (int k = 0; k < 3; k++) {
        q[k] = fabs(y[k]) - p[k];
        m = fmin(m, fmin(fabs(q[k]), fabs(y[k])));
      }
      for (int i = 0; i < 3; i++)
        for (int j = i + 1; j < 3; j++) m = fmin(m, fabs(q[i] - q[j]) / 2);
      return m;
    }
    case BS_LS_CYLINDER: {
      double d1 = rho - p[0], d2 = fabs(y[2]) - p[1];
      return fmin(fmin(rho, fabs(y[2])), fmin(fmin(fabs(d1), fabs(d2)), fabs(d1 - d2) / 2));
    }
    case BS_LS_TORUS: return fmin(rho, hypot(rho - p[0], y[2]));
    case BS_LS_GRID: {
      double m = 1e9;
      for (int k = 0; k < 3; k++) {
        double u = (ls->c0[k] + y[k] - ls->origin[k]) / ls->h, umax = ls->n[k] - 1;
        if (u <= 0 || u >= umax) m = fmin(m, ls->h * fmin(fabs(u), fabs(u - umax)));
        else m = fmin(m, ls->h * fmin(u - floor(u), ceil(u) - u));
      }
      return m;
    }
  }
  return 0;
}

/* Central-difference errors at x for step h: max over entries of
 * |FD(phi) - grad| and |FD(grad) - Hess|. */
static void fd_errors(const bs_levelset *ls, double t, const double x[3], double h, double *eg, double *eH) {
  double g[3], H[9];
  bs_levelset_eval(ls, t, x, g, H);
  *eg = *eH = 0;
  for (int k = 0; k < 3; k++) {
    double xp[3] = {x[0], x[1], x[2]}, xm[3] = {x[0], x[1], x[2]}, gp[3], gm[3];
    xp[k] += h, xm[k] -= h;
    double fp = bs_levelset_eval(ls, t, xp, gp, NULL), fm = bs_levelset_eval(ls, t, xm, gm, NULL);
    *eg = fmax(*eg, fabs((fp - fm) / (2 * h) - g[k]));
    for (int i = 0; i < 3; i++) *eH = fmax(*eH, fabs((gp[i] - gm[i]) / (2 * h) - H[3 * i + k]));
  }
}

enum { N_H = 3, N_PTS = 150 };
static const double fd_h[N_H] = {4e-3, 2e-3, 1e-3};

/* Derivatives of ls at time t at N_PTS random points of the cube of half
 * side L around the shape's current centre with margin > min_margin:
 * errors summed over the points fall as h^2 (ratio 4 per halving) or sit at
 * round-off; |grad| = 1 when sdf; Hessian symmetric. */
static void check_derivatives(const char *name, const bs_levelset *ls, double t, double L, double min_margin,
                              int sdf) {
  bs_levelset_frame f;
  bs_levelset_frame_at(ls, t, &f);
  double Eg[N_H] = {0}, EH[N_H] = {0};
  int found = 0;
  for (int tries = 0; found < N_PTS && tries < 100 * N_PTS; tries++) {
    double x[3];
    for (int k = 0; k < 3; k++) x[k] = f.c[k] + urange(-L, L);
    if (smooth_margin(ls, t, x) < min_margin) continue;
    found++;
    double g[3], H[9];
    bs_levelset_eval(ls, t, x, g, H);
    if (sdf) {
      double ng = sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
      cr_assert(fabs(ng - 1) < 1e-12, "%s: |grad| = %.17g at (%g, %g, %g)", name, ng, x[0], x[1], x[2]);
    }
    for (int i = 0; i < 3; i++)
      for (int j = 0; j < i; j++)
        cr_assert(fabs(H[3 * i + j] - H[3 * j + i]) <= 1e-12 * (1 + fabs(H[3 * i + j])), "%s: Hessian asymmetric",
                  name);
    for (int s = 0; s < N_H; s++) {
      double eg, eH;
      fd_errors(ls, t, x, fd_h[s], &eg, &eH);
      Eg[s] += eg;
      EH[s] += eH;
    }
  }
  cr_assert_eq(found, N_PTS, "%s: only %d smooth points found", name, found);
  const double floor_ = 1e-8 * N_PTS; /* round-off level of a central difference at h = 1e-3 */
  for (int s = 0; s + 1 < N_H; s++) {
    if (Eg[s + 1] > floor_) {
      double r = Eg[s] / Eg[s + 1];
      cr_assert(r > 3.5 && r < 4.5, "%s: gradient FD error ratio %g (h %g -> %g: %g -> %g), expected 4", name, r,
                fd_h[s], fd_h[s + 1], Eg[s], Eg[s + 1]);
    }
    if (EH[s + 1] > floor_) {
      double r = EH[s] / EH[s + 1];
      cr_assert(r > 3.5 && r < 4.5, "%s: Hessian FD error ratio %g (h %g -> %g: %g -> %g), expected 4", name, r,
                fd_h[s], fd_h[s + 1], EH[s], EH[s + 1]);
    }
  }
  /* and the errors are small in absolute terms (mean over points) */
  cr_assert(Eg[N_H - 1] / N_PTS < 1e-5, "%s: mean gradient FD error %g", name, Eg[N_H - 1] / N_PTS);
  cr_assert(EH[N_H - 1] / N_PTS < 1e-4, "%s: mean Hessian FD error %g", name, EH[N_H - 1] / N_PTS);
}

/* ---- derivatives --------------------------------------------------------- */

Test(levelset, analytic_derivatives) {
  for (int kind = 0; kind < N_ANALYTIC; kind++)
    for (int variant = 0; variant < 6; variant++) {
      bs_levelset *ls = make_shape(kind);
      int comp = variant & 1, motion = variant / 2; /* 0 static, 1 velocity, 2 keyframes */
      bs_levelset_set_complement(ls, comp);
      if (motion == 1) set_test_velocity(ls);
      if (motion == 2) set_test_keyframes(ls);
      double t = motion == 2 ? 1.7 : 0.8;
      char name[96];
      snprintf(name, sizeof name, "%s%s (%s)", comp ? "complement of " : "", bs_levelset_kind_name(ls->kind),
               motion == 0 ? "static" : motion == 1 ? "velocity" : "keyframes");
      check_derivatives(name, ls, t, 1.2, 0.05, 1);
      bs_levelset_destroy(&ls);
      cr_assert_null(ls);
    }
}

/* The torus of make_shape(4) sampled over the box [TORUS_LO, TORUS_HI] at
 * spacing h. */
static const double TORUS_LO[3] = {-1.1, -1.3, -0.8}, TORUS_HI[3] = {1.3, 0.9, 1.4};
static bs_levelset *sampled_torus(double h) {
  bs_levelset *torus = make_shape(4), *grid = NULL;
  bs_error err;
  cr_assert_eq(bs_levelset_grid_sample(torus, 0, TORUS_LO, TORUS_HI, h, &grid, &err), 0, "%s", err.msg);
  bs_levelset_destroy(&torus);
  return grid;
}

Test(levelset, grid_derivatives) {
  bs_levelset *grid = sampled_torus(0.08);
  bs_error err;
  for (int variant = 0; variant < 6; variant++) {
    bs_grid_interp mode = variant < 3 ? BS_GRID_CUBIC : BS_GRID_LINEAR;
    cr_assert_eq(bs_levelset_grid_set_interp(grid, mode, &err), 0, "%s", err.msg);
    bs_levelset_set_complement(grid, variant % 3 == 1);
    if (variant % 3 == 2) set_test_velocity(grid);
    if (variant % 3 == 0) { /* back at rest */
      const double zero[3] = {0, 0, 0};
      cr_assert_eq(bs_levelset_set_velocity(grid, zero, zero, &err), 0, "%s", err.msg);
    }
    /* points inside cells (trilinear: FD exact to round-off, linear along
     * each axis; cubic: O(h^2)) and outside the grid box (the extrapolation:
     * O(h^2)) */
    char name[64];
    snprintf(name, sizeof name, "%s %s grid", variant % 3 == 0 ? "static" : variant % 3 == 1 ? "complement of" : "moving",
             bs_grid_interp_name(mode));
    check_derivatives(name, grid, 0.6, 1.9, 0.015, 0);
  }
  bs_levelset_destroy(&grid);
}

/* ---- sign convention, |grad| ----------------------------------------------- */

Test(levelset, sign_convention) {
  const double c[3] = {0.1, -0.2, 0.3};
  bs_levelset *ls[N_ANALYTIC];
  for (int k = 0; k < N_ANALYTIC; k++) ls[k] = make_shape(k);
  /* half-space (0.3, 1, -0.2).x = 0.4: */
  double n[3] = {0.3, 1, -0.2}, nn = sqrt(0.09 + 1 + 0.04), on[3], above[3], below[3];
  for (int k = 0; k < 3; k++) {
    on[k] = 0.4 * n[k] / (nn * nn);
    above[k] = on[k] + 2 * n[k] / nn;
    below[k] = on[k] - 0.5 * n[k] / nn;
  }
  cr_assert(fabs(bs_levelset_eval(ls[0], 0, on, NULL, NULL)) < 1e-15);
  cr_assert(fabs(bs_levelset_eval(ls[0], 0, above, NULL, NULL) - 2) < 1e-14);
  cr_assert(fabs(bs_levelset_eval(ls[0], 0, below, NULL, NULL) + 0.5) < 1e-14);
  /* centres: sphere -r, box -min half, cylinder -min(r, hh) */
  cr_assert(fabs(bs_levelset_eval(ls[1], 0, c, NULL, NULL) + 0.7) < 1e-15);
  cr_assert(fabs(bs_levelset_eval(ls[2], 0, c, NULL, NULL) + 0.3) < 1e-15);
  cr_assert(fabs(bs_levelset_eval(ls[3], 0, c, NULL, NULL) + 0.4) < 1e-15);
  /* torus: its centre is in the hole (phi = R - r > 0); a point of the core
   * circle is at depth r */
  cr_assert(fabs(bs_levelset_eval(ls[4], 0, c, NULL, NULL) - 0.55) < 1e-15);
  double y[3] = {0.8, 0, 0}, x[3], f0;
  bs_levelset_frame fr;
  bs_levelset_frame_at(ls[4], 0, &fr);
  mv(fr.M, y, x);
  for (int k = 0; k < 3; k++) x[k] += c[k];
  cr_assert(fabs(bs_levelset_eval(ls[4], 0, x, NULL, NULL) + 0.25) < 1e-14);
  /* a far point is outside everything but the half-space's below side */
  double far[3] = {5, 5, 5};
  for (int k = 1; k < N_ANALYTIC; k++) {
    cr_assert(bs_levelset_eval(ls[k], 0, far, NULL, NULL) > 0, "%s", bs_levelset_kind_name(ls[k]->kind));
    f0 = bs_levelset_eval(ls[k], 0, c, NULL, NULL);
    bs_levelset_set_complement(ls[k], 1);
    cr_assert(bs_levelset_eval(ls[k], 0, far, NULL, NULL) < 0, "complement of %s", bs_levelset_kind_name(ls[k]->kind));
    cr_assert_eq(bs_levelset_eval(ls[k], 0, c, NULL, NULL), -f0);
    cr_assert(bs_levelset_is_complement(ls[k]));
    cr_assert(bs_levelset_is_analytic(ls[k]));
  }
  /* box: an outside corner region point is at the Euclidean distance to the corner */
  double corner[3] = {c[0] + 0.5 + 0.3, c[1] + 0.3 + 0.4, c[2] - 0.4 - 1.2};
  bs_levelset_set_complement(ls[2], 0);
  cr_assert(fabs(bs_levelset_eval(ls[2], 0, corner, NULL, NULL) - 1.3) < 1e-14);
  /* cylinder rim: distance to the rim circle */
  for (int k = 0; k < N_ANALYTIC; k++) bs_levelset_destroy(&ls[k]);
}

/* ---- projection ------------------------------------------------------------ */

Test(levelset, projection_lands_on_surface_and_is_idempotent) {
  for (int kind = 0; kind < N_ANALYTIC; kind++)
    for (int variant = 0; variant < 4; variant++) {
      bs_levelset *ls = make_shape(kind);
      bs_levelset_set_complement(ls, variant & 1);
      if (variant >= 2) set_test_keyframes(ls);
      double t = variant >= 2 ? 0.6 : 0;
      bs_levelset_frame f;
      bs_levelset_frame_at(ls, t, &f);
      int found = 0;
      for (int tries = 0; found < 200 && tries < 100000; tries++) {
        double x[3], xp[3], xpp[3];
        for (int k = 0; k < 3; k++) x[k] = f.c[k] + urange(-1.5, 1.5);
        double phi = bs_levelset_eval(ls, t, x, NULL, NULL);
        if (!(phi < 0) || smooth_margin(ls, t, x) < 0.02) continue;
        found++;
        double phi0 = bs_levelset_project(ls, t, x, xp);
        cr_assert_eq(phi0, phi);
        double phip = bs_levelset_eval(ls, t, xp, NULL, NULL);
        cr_assert(fabs(phip) < 1e-12, "%s%s: phi(P(x)) = %g (phi(x) = %g)", variant & 1 ? "complement of " : "",
                  bs_levelset_kind_name(ls->kind), phip, phi);
        bs_levelset_project(ls, t, xp, xpp);
        cr_assert(maxdiff(3, xp, xpp) < 1e-12, "%s: P(P(x)) - P(x) = %g", bs_levelset_kind_name(ls->kind),
                  maxdiff(3, xp, xpp));
        /* P(x) is the nearest surface point: |x - P(x)| = |phi(x)| */
        double d = sqrt((x[0] - xp[0]) * (x[0] - xp[0]) + (x[1] - xp[1]) * (x[1] - xp[1]) +
                        (x[2] - xp[2]) * (x[2] - xp[2]));
        cr_assert(fabs(d + phi) < 1e-12);
        /* in place (xp aliases x) */
        double xi[3] = {x[0], x[1], x[2]};
        bs_levelset_project(ls, t, xi, xi);
        cr_assert(maxdiff(3, xi, xp) == 0);
      }
      cr_assert_eq(found, 200, "%s: only %d inside points", bs_levelset_kind_name(ls->kind), found);
      bs_levelset_destroy(&ls);
    }
}

/* ---- moving shapes ----------------------------------------------------------- */

/* Checks phi, grad and Hessian of the moving shape at (t, x) against the
 * static shape at the point c0 + R^T (x - c0 - d), rotated back. */
static void check_transformed(const bs_levelset *moving, const bs_levelset *still, double t, const double d[3],
                              const double R[9], const char *what) {
  for (int i = 0; i < 20; i++) {
    double x[3], dx[3], xs[3], gm[3], Hm[9], gs[3], Hs[9], Rg[3], RH[9];
    for (int k = 0; k < 3; k++) x[k] = still->c0[k] + d[k] + urange(-1.2, 1.2);
    for (int k = 0; k < 3; k++) dx[k] = x[k] - still->c0[k] - d[k];
    mtv(R, dx, xs);
    for (int k = 0; k < 3; k++) xs[k] += still->c0[k];
    double pm = bs_levelset_eval(moving, t, x, gm, Hm), ps = bs_levelset_eval(still, 0, xs, gs, Hs);
    mv(R, gs, Rg);
    conj3(R, Hs, RH);
    cr_assert(fabs(pm - ps) < 1e-12, "%s t=%g: phi %.17g vs static %.17g", what, t, pm, ps);
    cr_assert(maxdiff(3, gm, Rg) < 1e-11, "%s t=%g: grad differs by %g", what, t, maxdiff(3, gm, Rg));
    cr_assert(maxdiff(9, Hm, RH) < 1e-9 * (1 + maxdiff(9, Hs, (double[9]){0})), "%s t=%g: Hessian differs by %g",
              what, t, maxdiff(9, Hm, RH));
  }
}

Test(levelset, moving_equals_static_transformed) {
  const double v[3] = {0.3, -0.5, 0.2}, w[3] = {0.7, 0.4, -1.1};
  for (int kind = 0; kind < N_ANALYTIC; kind++) {
    bs_levelset *still = make_shape(kind), *moving = make_shape(kind);
    set_test_velocity(moving);
    cr_assert_eq(bs_levelset_motion(moving), BS_LS_VELOCITY);
    const double ts[4] = {0, 0.3, 1.7, -0.4};
    for (int i = 0; i < 4; i++) {
      double t = ts[i], r[3] = {w[0] * t, w[1] * t, w[2] * t}, R[9], d[3] = {v[0] * t, v[1] * t, v[2] * t};
      rot_aa(r, R);
      check_transformed(moving, still, t, d, R, "velocity");
    }
    /* keyframes about one axis: slerp is linear in the angle */
    bs_error err;
    double a[3] = {0.48, -0.6, 0.64}; /* unit */
    double kt[3] = {0, 1, 2.5}, th[3] = {0.2, 1.5, 0.3}, kd[9] = {0, 0, 0, 0.5, -0.2, 0.1, 0.3, 0.4, -0.6}, kr[9];
    for (int k = 0; k < 3; k++)
      for (int j = 0; j < 3; j++) kr[3 * k + j] = th[k] * a[j];
    cr_assert_eq(bs_levelset_set_keyframes(moving, 3, kt, kd, kr, &err), 0, "%s", err.msg);
    cr_assert_eq(bs_levelset_motion(moving), BS_LS_KEYFRAMES);
    const double tq[6] = {-1, 0, 0.4, 1, 1.9, 4};
    for (int i = 0; i < 6; i++) {
      double t = tq[i], s, ang, d[3], r[3], R[9];
      int seg = t < 1 ? 0 : 1;
      s = (t - kt[seg]) / (kt[seg + 1] - kt[seg]);
      s = fmax(0, fmin(1, s));
      if (t >= 2.5) seg = 1, s = 1;
      ang = th[seg] + s * (th[seg + 1] - th[seg]);
      for (int j = 0; j < 3; j++) {
        d[j] = kd[3 * seg + j] + s * (kd[3 * (seg + 1) + j] - kd[3 * seg + j]);
        r[j] = ang * a[j];
      }
      rot_aa(r, R);
      check_transformed(moving, still, t, d, R, "keyframes");
    }
    bs_levelset_destroy(&still);
    bs_levelset_destroy(&moving);
  }
}

Test(levelset, keyframe_slerp_general_axes) {
  bs_levelset *ls = make_shape(2);
  set_test_keyframes(ls);
  const double r[9] = {0, 0, 0, 0.4, -0.9, 0.3, 1.2, 0.5, -0.7}, kt[3] = {0, 1, 2.5};
  bs_levelset_frame f;
  for (int k = 0; k < 3; k++) { /* at the key times: exactly the key rotations */
    double R[9];
    rot_aa(r + 3 * k, R);
    bs_levelset_frame_at(ls, kt[k], &f);
    cr_assert(maxdiff(9, f.M, R) < 1e-14, "key %d", k);
  }
  /* between keys: along the geodesic at a uniform rate */
  for (int seg = 0; seg < 2; seg++) {
    double Ra[9], Rb[9];
    rot_aa(r + 3 * seg, Ra);
    rot_aa(r + 3 * seg + 3, Rb);
    double total = rot_angle(Ra, Rb);
    for (int i = 1; i < 5; i++) {
      double s = i / 5.0;
      bs_levelset_frame_at(ls, kt[seg] + s * (kt[seg + 1] - kt[seg]), &f);
      cr_assert(fabs(rot_angle(Ra, f.M) - s * total) < 1e-12);
      cr_assert(fabs(rot_angle(f.M, Rb) - (1 - s) * total) < 1e-12);
    }
  }
  bs_levelset_destroy(&ls);
}

/* v(x) against central differences of the material point's path. */
Test(levelset, obstacle_velocity) {
  for (int motion = 0; motion < 3; motion++) {
    bs_levelset *ls = make_shape(3);
    if (motion == 1) set_test_velocity(ls);
    if (motion == 2) set_test_keyframes(ls);
    const double ts[3] = {0.37, 1.2, 2.2};
    for (int i = 0; i < 3; i++) {
      double t = ts[i], x[3], y[3], v[3], h = 1e-5;
      for (int k = 0; k < 3; k++) x[k] = urange(-1, 1);
      bs_levelset_local_point(ls, t, x, y);
      bs_levelset_velocity(ls, t, x, v);
      bs_levelset_frame fp, fm;
      bs_levelset_frame_at(ls, t + h, &fp);
      bs_levelset_frame_at(ls, t - h, &fm);
      double xp[3], xm[3];
      mv(fp.M, y, xp);
      mv(fm.M, y, xm);
      for (int k = 0; k < 3; k++) {
        double fd = (xp[k] + fp.c[k] - xm[k] - fm.c[k]) / (2 * h);
        cr_assert(fabs(fd - v[k]) < 1e-8, "motion %d t=%g: v[%d] = %g, FD %g", motion, t, k, v[k], fd);
      }
      if (motion == 0) cr_assert(v[0] == 0 && v[1] == 0 && v[2] == 0);
    }
    bs_levelset_destroy(&ls);
  }
  /* held before the first and after the last key: no velocity */
  bs_levelset *ls = make_shape(1);
  set_test_keyframes(ls);
  double x[3] = {0.3, 0.2, 0.1}, v[3];
  bs_levelset_velocity(ls, 7.0, x, v);
  cr_assert(v[0] == 0 && v[1] == 0 && v[2] == 0);
  bs_levelset_velocity(ls, -1.0, x, v);
  cr_assert(v[0] == 0 && v[1] == 0 && v[2] == 0);
  bs_levelset_destroy(&ls);
}

/* ---- grids ------------------------------------------------------------------- */

/* A trilinear function (linear in each variable): reproduced exactly. */
static double trilinear(const double x[3], double g[3], double H[9]) {
  double X = x[0], Y = x[1], Z = x[2];
  if (g) {
    g[0] = 2 + 3 * Y + Z + 4 * Y * Z;
    g[1] = -1 + 3 * X - 2 * Z + 4 * X * Z;
    g[2] = 0.5 - 2 * Y + X + 4 * X * Y;
  }
  if (H) {
    H[0] = H[4] = H[8] = 0;
    H[1] = H[3] = 3 + 4 * Z;
    H[2] = H[6] = 1 + 4 * Y;
    H[5] = H[7] = -2 + 4 * X;
  }
  return 1 + 2 * X - Y + 0.5 * Z + 3 * X * Y - 2 * Y * Z + X * Z + 4 * X * Y * Z;
}

static bs_levelset *grid_of(double (*fn)(const double *, double *, double *), const double origin[3], double h,
                            const int32_t n[3]) {
  size_t total = (size_t)n[0] * n[1] * n[2];
  double *vals = malloc(total * sizeof(double));
  for (int32_t k = 0; k < n[2]; k++)
    for (int32_t j = 0; j < n[1]; j++)
      for (int32_t i = 0; i < n[0]; i++) {
        double x[3] = {origin[0] + h * i, origin[1] + h * j, origin[2] + h * k};
        vals[i + (size_t)n[0] * (j + (size_t)n[1] * k)] = fn(x, NULL, NULL);
      }
  bs_levelset *ls = NULL;
  bs_error err;
  cr_assert_eq(bs_levelset_grid_from_values(origin, h, n, vals, &ls, &err), 0, "%s", err.msg);
  free(vals);
  return ls;
}

static void check_trilinear_reproduced(const bs_levelset *ls, const double origin[3], double h, const int32_t n[3],
                                       const char *name);

/* Both modes: the cubic B-spline's natural end condition (ghost coefficients
 * linearly extrapolated) reproduces linear functions along each axis, hence
 * trilinear ones, exactly, up to the boundary; n = 2 and 3 exercise a stencil
 * folded at both ends. */
Test(levelset, grid_reproduces_trilinear_functions) {
  const double origin[3] = {-0.4, 0.1, -0.3}, h = 0.125;
  const int32_t sizes[2][3] = {{7, 5, 6}, {2, 3, 4}};
  for (int v = 0; v < 4; v++) {
    const int32_t *n = sizes[v / 2];
    bs_grid_interp mode = (v & 1) ? BS_GRID_LINEAR : BS_GRID_CUBIC;
    bs_levelset *ls = grid_of(trilinear, origin, h, n);
    cr_assert_eq(bs_levelset_grid_get_interp(ls), BS_GRID_CUBIC, "cubic is the default");
    bs_error err;
    cr_assert_eq(bs_levelset_grid_set_interp(ls, mode, &err), 0, "%s", err.msg);
    cr_assert_eq(bs_levelset_grid_get_interp(ls), mode);
    check_trilinear_reproduced(ls, origin, h, n, bs_grid_interp_name(mode));
    bs_levelset_destroy(&ls);
  }
}

static void check_trilinear_reproduced(const bs_levelset *ls, const double origin[3], double h, const int32_t n[3],
                                       const char *name) {
  cr_assert_eq(bs_levelset_kind(ls), BS_LS_GRID);
  cr_assert(!bs_levelset_is_analytic(ls));
  for (int i = 0; i < 2000; i++) {
    double x[3], g[3], H[9], ge[3], He[9];
    for (int k = 0; k < 3; k++) x[k] = origin[k] + urange(0, h * (n[k] - 1));
    if (i < 8) /* the corners of the grid box */
      for (int k = 0; k < 3; k++) x[k] = origin[k] + ((i >> k) & 1) * h * (n[k] - 1);
    double phi = bs_levelset_eval(ls, 0, x, g, H), fe = trilinear(x, ge, He);
    cr_assert(fabs(phi - fe) < 1e-13, "%s: value %.17g vs %.17g", name, phi, fe);
    if (i >= 8) { /* derivatives are those of the same function inside the cells */
      cr_assert(maxdiff(3, g, ge) < 1e-12, "%s: grad differs by %g", name, maxdiff(3, g, ge));
      cr_assert(maxdiff(9, H, He) < 1e-11, "%s: Hessian differs by %g", name, maxdiff(9, H, He));
      cr_assert(fabs(H[0]) < 1e-11 && fabs(H[4]) < 1e-11 && fabs(H[8]) < 1e-11, "%s", name);
    }
  }
}

/* Random node values, trilinear mode: inside a cell the returned derivatives
 * match central differences of the returned phi to round-off (the
 * interpolant is linear along each axis, so central differences are exact
 * there). */
Test(levelset, grid_derivatives_inside_cells) {
  const double origin[3] = {0.2, -0.1, 0.05}, h = 0.1;
  const int32_t n[3] = {6, 5, 7};
  double vals[6 * 5 * 7];
  for (int i = 0; i < 6 * 5 * 7; i++) vals[i] = urange(-1, 1);
  bs_levelset *ls = NULL;
  bs_error err;
  cr_assert_eq(bs_levelset_grid_from_values(origin, h, n, vals, &ls, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_levelset_grid_set_interp(ls, BS_GRID_LINEAR, &err), 0, "%s", err.msg);
  int found = 0;
  double m = 0, mH = 0;
  for (int i = 0; found < 500 && i < 100000; i++) {
    double x[3];
    for (int k = 0; k < 3; k++) x[k] = origin[k] + urange(0, h * (n[k] - 1));
    if (smooth_margin(ls, 0, x) < 0.01) continue;
    found++;
    double eg, eH;
    fd_errors(ls, 0, x, 1e-3, &eg, &eH);
    m = fmax(m, eg);
    mH = fmax(mH, eH);
    double H[9];
    bs_levelset_eval(ls, 0, x, NULL, H);
    cr_assert(H[0] == 0 && H[4] == 0 && H[8] == 0);
  }
  cr_assert_eq(found, 500);
  cr_assert(m < 1e-11 && mH < 1e-9, "FD errors inside cells: grad %g, Hessian %g", m, mH);
  /* and a node value is returned exactly at its node */
  double x[3] = {origin[0] + 2 * h, origin[1] + 3 * h, origin[2] + 4 * h};
  cr_assert(fabs(bs_levelset_eval(ls, 0, x, NULL, NULL) - vals[2 + 6 * (3 + 5 * 4)]) < 1e-15);
  bs_levelset_destroy(&ls);
}

static double linear_fn(const double x[3], double *g, double *H) { return 0.3 + 0.6 * x[0] - 0.48 * x[1] + 0.64 * x[2]; }

Test(levelset, grid_extrapolation) {
  const double origin[3] = {0, 0, 0}, h = 0.25;
  const int32_t n[3] = {5, 5, 5};
  bs_levelset *ls = grid_of(linear_fn, origin, h, n);
  for (int i = 0; i < 500; i++) {
    double x[3], q[3], dist2 = 0;
    for (int k = 0; k < 3; k++) {
      x[k] = urange(-1, 2);
      q[k] = fmin(fmax(x[k], 0), 1);
      dist2 += (x[k] - q[k]) * (x[k] - q[k]);
    }
    double phi = bs_levelset_eval(ls, 0, x, NULL, NULL);
    cr_assert(fabs(phi - (linear_fn(q, NULL, NULL) + sqrt(dist2))) < 1e-13, "extrapolation at (%g, %g, %g)", x[0],
              x[1], x[2]);
  }
  /* continuity across the grid boundary */
  double a[3] = {1 - 1e-12, 0.3, 0.6}, b[3] = {1 + 1e-12, 0.3, 0.6};
  cr_assert(fabs(bs_levelset_eval(ls, 0, a, NULL, NULL) - bs_levelset_eval(ls, 0, b, NULL, NULL)) < 1e-11);
  bs_levelset_destroy(&ls);
}

static void check_sampled_sphere(bs_grid_interp mode);

/* The trilinear and the cubic interpolants of a sphere's SDF are within C h^2
 * of the exact one (away from the centre), and the error falls as h^2 (or
 * faster). */
Test(levelset, grid_sampled_sphere_accuracy) {
  for (int mode = BS_GRID_CUBIC; mode <= BS_GRID_LINEAR; mode++)
    check_sampled_sphere((bs_grid_interp)mode);
}

static void check_sampled_sphere(bs_grid_interp mode) {
  const double c[3] = {0.05, -0.02, 0.03}, r = 0.5;
  bs_levelset *sphere = NULL;
  bs_error err;
  cr_assert_eq(bs_levelset_create_sphere(c, r, &sphere, &err), 0, "%s", err.msg);
  double lo[3] = {-0.8, -0.8, -0.8}, hi[3] = {0.8, 0.8, 0.8}, errs[3], gerrs[3];
  const double hs[3] = {0.1, 0.05, 0.025};
  const char *name = bs_grid_interp_name(mode);
  for (int s = 0; s < 3; s++) {
    bs_levelset *grid = NULL;
    cr_assert_eq(bs_levelset_grid_sample(sphere, 0, lo, hi, hs[s], &grid, &err), 0, "%s", err.msg);
    cr_assert_eq(bs_levelset_grid_set_interp(grid, mode, &err), 0, "%s", err.msg);
    int32_t n[3];
    double o[3], h;
    cr_assert_not_null(bs_levelset_grid_values(grid, n, o, &h));
    cr_assert(h == hs[s] && o[0] == lo[0]);
    cr_assert(o[0] + h * (n[0] - 1) >= hi[0] - 1e-12 && o[0] + h * (n[0] - 2) < hi[0]);
    double m = 0, mg = 0;
    for (int i = 0; i < 3000; i++) {
      double x[3], d2 = 0;
      for (int k = 0; k < 3; k++) {
        x[k] = urange(-0.75, 0.75);
        d2 += (x[k] - c[k]) * (x[k] - c[k]);
      }
      if (sqrt(d2) < 0.2) continue;
      double g[3], ge[3];
      m = fmax(m, fabs(bs_levelset_eval(grid, 0, x, g, NULL) - bs_levelset_eval(sphere, 0, x, ge, NULL)));
      mg = fmax(mg, maxdiff(3, g, ge));
    }
    errs[s] = m;
    gerrs[s] = mg;
    /* |Hess phi| <= 1/|x - c| = 5: trilinear error <= h^2/8 * 3 * 5 */
    cr_assert(m <= 2 * hs[s] * hs[s], "%s: h = %g: max error %g > 2 h^2", name, hs[s], m);
    bs_levelset_destroy(&grid);
  }
  cr_assert(errs[0] / errs[1] > 2.5 && errs[1] / errs[2] > 2.5, "%s: errors %g %g %g do not fall as h^2", name,
            errs[0], errs[1], errs[2]);
  for (int s = 0; s < 3; s++) {
    double h = hs[s];
    if (mode == BS_GRID_CUBIC) { /* interior O(h^4) for phi, O(h^3) for grad */
      cr_assert(errs[s] <= 0.25 * h * h, "cubic: h = %g: max error %g > h^2 / 4", h, errs[s]);
      cr_assert(gerrs[s] <= 2 * h * h, "cubic: h = %g: max gradient error %g > 2 h^2", h, gerrs[s]);
    } else {
      cr_assert(gerrs[s] <= 3 * h, "linear: h = %g: max gradient error %g > 3 h", h, gerrs[s]);
    }
  }
  if (mode == BS_GRID_CUBIC)
    cr_assert(errs[0] / errs[1] > 8 && errs[1] / errs[2] > 8 && gerrs[0] / gerrs[1] > 4 && gerrs[1] / gerrs[2] > 4,
              "cubic: errors %g %g %g, gradient errors %g %g %g fall too slowly", errs[0], errs[1], errs[2], gerrs[0],
              gerrs[1], gerrs[2]);
  bs_levelset_destroy(&sphere);
}

static void temp_path(char *buf, size_t cap, const char *tag) {
  snprintf(buf, cap, "/tmp/bs_test_levelset_%ld_%s.bsls", (long)getpid(), tag);
}

Test(levelset, grid_save_load_round_trip) {
  bs_levelset *torus = make_shape(4), *grid = NULL, *back = NULL;
  bs_error err;
  double lo[3] = {-1, -1.2, -0.7}, hi[3] = {1.2, 0.8, 1.3};
  cr_assert_eq(bs_levelset_grid_sample(torus, 0, lo, hi, 0.1, &grid, &err), 0, "%s", err.msg);
  char path[256];
  temp_path(path, sizeof path, "rt");
  cr_assert_eq(bs_levelset_grid_save(grid, path, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_levelset_grid_load(path, &back, &err), 0, "%s", err.msg);
  int32_t n1[3], n2[3];
  double o1[3], o2[3], h1, h2;
  const double *v1 = bs_levelset_grid_values(grid, n1, o1, &h1), *v2 = bs_levelset_grid_values(back, n2, o2, &h2);
  cr_assert(memcmp(n1, n2, sizeof n1) == 0 && memcmp(o1, o2, sizeof o1) == 0 && h1 == h2);
  cr_assert(memcmp(v1, v2, sizeof(double) * (size_t)n1[0] * n1[1] * n1[2]) == 0);
  for (int i = 0; i < 100; i++) {
    double x[3] = {urange(-1.5, 1.5), urange(-1.5, 1.5), urange(-1.5, 1.5)};
    cr_assert_eq(bs_levelset_eval(grid, 0, x, NULL, NULL), bs_levelset_eval(back, 0, x, NULL, NULL));
  }
  /* file size: 56-byte header + 8 per value */
  FILE *fp = fopen(path, "rb");
  fseek(fp, 0, SEEK_END);
  cr_assert_eq(ftell(fp), 56 + 8 * (long)n1[0] * n1[1] * n1[2]);
  fclose(fp);
  remove(path);
  /* an analytic level set cannot be saved */
  cr_assert_eq(bs_levelset_grid_save(torus, path, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "torus") && strstr(err.msg, path), "%s", err.msg);
  cr_assert_null(bs_levelset_grid_values(torus, NULL, NULL, NULL));
  bs_levelset_destroy(&grid);
  bs_levelset_destroy(&back);
  bs_levelset_destroy(&torus);
}

/* ---- cubic B-spline grids ------------------------------------------------------ */

/* A grid of random values on the origin 0 with h a power of two (so that node
 * coordinates and x / h are exact). */
static bs_levelset *random_grid(const int32_t n[3], double h, double *vals) {
  const double origin[3] = {0, 0, 0};
  size_t total = (size_t)n[0] * n[1] * n[2];
  for (size_t i = 0; i < total; i++) vals[i] = urange(-1, 1);
  bs_levelset *ls = NULL;
  bs_error err;
  cr_assert_eq(bs_levelset_grid_from_values(origin, h, n, vals, &ls, &err), 0, "%s", err.msg);
  return ls;
}

/* The prefiltered spline interpolates every node, boundary nodes and
 * corners included, for axes of 2, 3 and more nodes. */
Test(levelset, grid_cubic_interpolates_nodes) {
  const int32_t sizes[3][3] = {{6, 5, 7}, {2, 3, 9}, {12, 2, 4}};
  const double h = 0.125;
  for (int s = 0; s < 3; s++) {
    const int32_t *n = sizes[s];
    double *vals = malloc(sizeof(double) * (size_t)n[0] * n[1] * n[2]);
    bs_levelset *ls = random_grid(n, h, vals);
    cr_assert_eq(bs_levelset_grid_get_interp(ls), BS_GRID_CUBIC);
    double m = 0, moff = 0;
    for (int32_t k = 0; k < n[2]; k++)
      for (int32_t j = 0; j < n[1]; j++)
        for (int32_t i = 0; i < n[0]; i++) {
          double x[3] = {h * i, h * j, h * k}, v = vals[i + n[0] * (j + n[1] * k)];
          m = fmax(m, fabs(bs_levelset_eval(ls, 0, x, NULL, NULL) - v));
          /* mid-cell the B-spline is not the trilinear average of random data */
          if (i + 1 < n[0] && j + 1 < n[1] && k + 1 < n[2]) {
            double y[3] = {x[0] + h / 2, x[1] + h / 2, x[2] + h / 2};
            double c = bs_levelset_eval(ls, 0, y, NULL, NULL);
            bs_error err;
            cr_assert_eq(bs_levelset_grid_set_interp(ls, BS_GRID_LINEAR, &err), 0);
            moff = fmax(moff, fabs(c - bs_levelset_eval(ls, 0, y, NULL, NULL)));
            cr_assert_eq(bs_levelset_grid_set_interp(ls, BS_GRID_CUBIC, &err), 0);
          }
        }
    cr_assert(m < 1e-14, "grid %d x %d x %d: spline misses a node by %g", n[0], n[1], n[2], m);
    cr_assert(moff > 1e-3, "grid %d x %d x %d: cubic equals trilinear mid-cell (%g)", n[0], n[1], n[2], moff);
    /* the samples themselves are returned unchanged */
    cr_assert(memcmp(bs_levelset_grid_values(ls, NULL, NULL, NULL), vals, sizeof(double) * n[0] * n[1] * n[2]) == 0);
    free(vals);
    bs_levelset_destroy(&ls);
  }
}

/* The value alone (no gradient asked: the penalty's first pass) is the value
 * of the full evaluation bit for bit, in boundary cells (ghost nodes folded),
 * inside and outside the grid (clamped plus the distance). */
Test(levelset, grid_cubic_value_alone_is_the_full_value) {
  const int32_t n[3] = {5, 2, 7};
  const double h = 0.25;
  double vals[5 * 2 * 7];
  bs_levelset *ls = random_grid(n, h, vals);
  int differ = 0;
  for (int p = 0; p < 2000; p++) {
    double x[3], g[3], H[9];
    for (int k = 0; k < 3; k++) x[k] = urange(-0.5, h * (n[k] - 1) + 0.5);
    const double v = bs_levelset_eval(ls, 0, x, NULL, NULL), vg = bs_levelset_eval(ls, 0, x, g, NULL),
                 vh = bs_levelset_eval(ls, 0, x, g, H);
    differ += memcmp(&v, &vg, sizeof v) != 0 || memcmp(&v, &vh, sizeof v) != 0;
  }
  cr_assert_eq(differ, 0, "%d of 2000 points: the value alone differs from the full evaluation's", differ);
  bs_levelset_destroy(&ls);
}

/* grad vs central differences of phi and Hessian vs central differences of
 * grad for the cubic mode, at random points of the whole box (cells next to
 * the boundary included) and at points ON cell faces: errors summed over the
 * points fall as h^2 (ratio 4 per halving), except the Hessian's ON a face.
 * There the third derivative jumps (the spline is C2, not C3), so the
 * central difference of grad errs by e/4 times that jump: O(e), ratio 2,
 * which is the expected behaviour of a continuous Hessian with a kink (a
 * jump in the Hessian itself would give an O(1) error that does not fall). */
Test(levelset, grid_cubic_derivatives_across_faces) {
  const int32_t n[3] = {7, 6, 8};
  const double h = 0.125, margin = 0.02, steps[3] = {h / 8, h / 16, h / 32};
  double vals[7 * 6 * 8];
  bs_levelset *ls = random_grid(n, h, vals);
  for (int on_face = 0; on_face < 2; on_face++) {
    double Eg[3] = {0}, EH[3] = {0};
    for (int p = 0; p < 300; p++) {
      double x[3];
      for (int k = 0; k < 3; k++) x[k] = urange(margin, h * (n[k] - 1) - margin);
      if (on_face) { /* one or two coordinates on an interior node plane */
        int k = p % 3;
        x[k] = h * (1 + (int)(urand() * (n[k] - 2)));
        if (p % 2) x[(k + 1) % 3] = h * (1 + (int)(urand() * (n[(k + 1) % 3] - 2)));
      }
      double g[3], H[9];
      bs_levelset_eval(ls, 0, x, g, H);
      for (int i = 0; i < 3; i++)
        for (int j = 0; j < i; j++) cr_assert(H[3 * i + j] == H[3 * j + i], "Hessian asymmetric");
      for (int s = 0; s < 3; s++) {
        double eg, eH;
        fd_errors(ls, 0, x, steps[s], &eg, &eH);
        Eg[s] += eg;
        EH[s] += eH;
      }
    }
    for (int s = 0; s < 2; s++) {
      double rg = Eg[s] / Eg[s + 1], rH = EH[s] / EH[s + 1];
      cr_assert(rg > 3.5 && rg < 4.5, "%s: gradient FD error ratio %g (%g -> %g), expected 4",
                on_face ? "on faces" : "random", rg, Eg[s], Eg[s + 1]);
      double lo = on_face ? 1.7 : 3.5, hi = on_face ? 2.3 : 4.5;
      cr_assert(rH > lo && rH < hi, "%s: Hessian FD error ratio %g (%g -> %g), expected %g",
                on_face ? "on faces" : "random", rH, EH[s], EH[s + 1], on_face ? 2.0 : 4.0);
    }
    /* and small in absolute terms: for node data of unit size the third and
     * fourth derivatives scale as 1/h^3 and 1/h^4, so e^2 / h^3 and e^2 / h^4 */
    double e2 = steps[2] * steps[2], eH = on_face ? steps[2] * h : e2;
    cr_assert(Eg[2] / 300 < 20 * e2 / (h * h * h) && EH[2] / 300 < 20 * eH / (h * h * h * h),
              "mean FD errors %g, %g", Eg[2] / 300, EH[2] / 300);
  }
  bs_levelset_destroy(&ls);
}

/* Left and right limits on a cell face: the cubic B-spline's value, gradient
 * and Hessian agree (C2) to round-off, on every interior face (those next to
 * the boundary, where the stencil is folded, included); the trilinear
 * gradient does not. */
Test(levelset, grid_cubic_gradient_continuous_across_faces) {
  const int32_t n[3] = {6, 5, 7};
  const double h = 0.125, d = 1e-14; /* x = i h -+ d lies in cells i - 1 and i */
  double vals[6 * 5 * 7];
  bs_levelset *ls = random_grid(n, h, vals);
  bs_error err;
  double worst_g = 0, worst_H = 0, worst_lin = 1e9;
  for (int k = 0; k < 3; k++)
    for (int32_t i = 1; i + 1 < n[k]; i++)
      for (int p = 0; p < 10; p++) {
        double a[3], b[3];
        for (int q = 0; q < 3; q++) a[q] = b[q] = urange(0.01, h * (n[q] - 1) - 0.01);
        a[k] = h * i - d, b[k] = h * i + d;
        double ga[3], gb[3], Ha[9], Hb[9];
        cr_assert_eq(bs_levelset_grid_set_interp(ls, BS_GRID_CUBIC, &err), 0);
        double fa = bs_levelset_eval(ls, 0, a, ga, Ha), fb = bs_levelset_eval(ls, 0, b, gb, Hb);
        double ng = sqrt(ga[0] * ga[0] + ga[1] * ga[1] + ga[2] * ga[2]), nH = 0;
        for (int q = 0; q < 9; q++) nH = fmax(nH, fabs(Ha[q]));
        cr_assert(fabs(fa - fb) <= 4 * d * ng + 1e-15, "value jumps by %g across face %d of axis %d", fabs(fa - fb), i,
                  k);
        worst_g = fmax(worst_g, maxdiff(3, ga, gb) / ng);
        worst_H = fmax(worst_H, maxdiff(9, Ha, Hb) / nH);
        cr_assert_eq(bs_levelset_grid_set_interp(ls, BS_GRID_LINEAR, &err), 0);
        bs_levelset_eval(ls, 0, a, ga, NULL);
        bs_levelset_eval(ls, 0, b, gb, NULL);
        ng = sqrt(ga[0] * ga[0] + ga[1] * ga[1] + ga[2] * ga[2]);
        worst_lin = fmin(worst_lin, fabs(ga[k] - gb[k]) / ng);
      }
  cr_assert(worst_g < 1e-10, "cubic gradient jumps across a face by %g (relative)", worst_g);
  cr_assert(worst_H < 1e-8, "cubic Hessian jumps across a face by %g (relative)", worst_H);
  /* random data: the trilinear normal derivative jumps on every face */
  cr_assert(worst_lin > 1e-6, "trilinear gradient continuous across a face? smallest jump %g", worst_lin);
  bs_levelset_destroy(&ls);
}

/* The interpolation mode is not stored: a loaded grid is cubic and evaluates
 * (value, gradient, Hessian) exactly as the saved one, in both modes. */
Test(levelset, grid_cubic_save_load_round_trip) {
  bs_levelset *torus = make_shape(4), *grid = NULL, *back = NULL;
  bs_error err;
  double lo[3] = {-1, -1.2, -0.7}, hi[3] = {1.2, 0.8, 1.3};
  cr_assert_eq(bs_levelset_grid_sample(torus, 0, lo, hi, 0.1, &grid, &err), 0, "%s", err.msg);
  char path[256];
  temp_path(path, sizeof path, "cubic");
  cr_assert_eq(bs_levelset_grid_set_interp(grid, BS_GRID_LINEAR, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_levelset_grid_save(grid, path, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_levelset_grid_load(path, &back, &err), 0, "%s", err.msg);
  remove(path);
  cr_assert_eq(bs_levelset_grid_get_interp(back), BS_GRID_CUBIC, "a loaded grid is cubic");
  for (int mode = BS_GRID_CUBIC; mode <= BS_GRID_LINEAR; mode++) {
    cr_assert_eq(bs_levelset_grid_set_interp(grid, (bs_grid_interp)mode, &err), 0);
    cr_assert_eq(bs_levelset_grid_set_interp(back, (bs_grid_interp)mode, &err), 0);
    for (int i = 0; i < 200; i++) {
      double x[3] = {urange(-1.5, 1.5), urange(-1.5, 1.5), urange(-1.5, 1.5)}, g1[3], g2[3], H1[9], H2[9];
      double f1 = bs_levelset_eval(grid, 0, x, g1, H1), f2 = bs_levelset_eval(back, 0, x, g2, H2);
      cr_assert(f1 == f2 && memcmp(g1, g2, sizeof g1) == 0 && memcmp(H1, H2, sizeof H1) == 0,
                "%s: loaded grid differs at (%g, %g, %g)", bs_grid_interp_name((bs_grid_interp)mode), x[0], x[1],
                x[2]);
    }
  }
  bs_levelset_destroy(&grid);
  bs_levelset_destroy(&back);
  bs_levelset_destroy(&torus);
}

Test(levelset, grid_set_interp_errors_name_the_culprit) {
  bs_error err;
  const double c[3] = {0, 0, 0};
  bs_levelset *sphere = NULL, *grid = NULL;
  cr_assert_eq(bs_levelset_create_sphere(c, 1, &sphere, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_levelset_grid_set_interp(sphere, BS_GRID_CUBIC, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "sphere"), "%s", err.msg);
  cr_assert_eq(bs_levelset_grid_set_interp(NULL, BS_GRID_CUBIC, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "NULL"), "%s", err.msg);
  const double lo[3] = {-1.5, -1.5, -1.5}, hi[3] = {1.5, 1.5, 1.5};
  cr_assert_eq(bs_levelset_grid_sample(sphere, 0, lo, hi, 0.5, &grid, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_levelset_grid_set_interp(grid, (bs_grid_interp)7, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "mode = 7"), "%s", err.msg);
  cr_assert_eq(bs_levelset_grid_get_interp(grid), BS_GRID_CUBIC, "a rejected mode leaves the grid unchanged");
  cr_assert_str_eq(bs_grid_interp_name(BS_GRID_LINEAR), "linear");
  cr_assert_str_eq(bs_grid_interp_name(BS_GRID_CUBIC), "cubic");
  bs_levelset_destroy(&grid);
  bs_levelset_destroy(&sphere);
}

static void write_bytes(const char *path, const void *data, size_t n) {
  FILE *fp = fopen(path, "wb");
  cr_assert_not_null(fp);
  cr_assert_eq(fwrite(data, 1, n, fp), n);
  fclose(fp);
}

Test(levelset, grid_load_errors_name_the_file) {
  bs_error err;
  bs_levelset *ls = NULL;
  char path[256], good[256];
  temp_path(path, sizeof path, "missing");
  remove(path);
  cr_assert_eq(bs_levelset_grid_load(path, &ls, &err), BS_EIO);
  cr_assert(strstr(err.msg, path), "%s", err.msg);
  cr_assert_null(ls);

  /* a good file, then damaged copies of it */
  const double origin[3] = {0, 0, 0};
  const int32_t n[3] = {3, 3, 2};
  bs_levelset *g = grid_of(linear_fn, origin, 0.5, n);
  temp_path(good, sizeof good, "good");
  cr_assert_eq(bs_levelset_grid_save(g, good, &err), 0, "%s", err.msg);
  bs_levelset_destroy(&g);
  unsigned char buf[56 + 8 * 18 + 8];
  FILE *fp = fopen(good, "rb");
  size_t len = fread(buf, 1, sizeof buf, fp);
  fclose(fp);
  cr_assert_eq(len, 56 + 8 * 18);
  remove(good);

  temp_path(path, sizeof path, "damaged");
  write_bytes(path, buf, len - 5); /* truncated values */
  cr_assert_eq(bs_levelset_grid_load(path, &ls, &err), BS_EIO);
  cr_assert(strstr(err.msg, path) && strstr(err.msg, "truncated"), "%s", err.msg);
  write_bytes(path, buf, 30); /* truncated header */
  cr_assert_eq(bs_levelset_grid_load(path, &ls, &err), BS_EIO);
  cr_assert(strstr(err.msg, path) && strstr(err.msg, "truncated"), "%s", err.msg);
  unsigned char bad[sizeof buf];
  memcpy(bad, buf, len);
  bad[3] = 'X'; /* bad magic */
  write_bytes(path, bad, len);
  cr_assert_eq(bs_levelset_grid_load(path, &ls, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, path) && strstr(err.msg, "magic"), "%s", err.msg);
  write_bytes(path, "hello", 5); /* not even a header, wrong magic */
  cr_assert_eq(bs_levelset_grid_load(path, &ls, &err), BS_EIO);
  cr_assert(strstr(err.msg, path), "%s", err.msg);
  memcpy(bad, buf, len);
  bad[8] = 1; /* nx = 1 */
  write_bytes(path, bad, len);
  cr_assert_eq(bs_levelset_grid_load(path, &ls, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, path) && strstr(err.msg, "n[0]"), "%s", err.msg);
  memcpy(bad, buf, len);
  memset(bad + 56 + 8 * 4, 0xff, 8); /* a NaN value */
  write_bytes(path, bad, len);
  cr_assert_eq(bs_levelset_grid_load(path, &ls, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, path) && strstr(err.msg, "(1, 1, 0)"), "%s", err.msg);
  memcpy(bad, buf, len);
  memset(bad + len, 0, 8); /* trailing bytes */
  write_bytes(path, bad, len + 8);
  cr_assert_eq(bs_levelset_grid_load(path, &ls, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, path) && strstr(err.msg, "trailing"), "%s", err.msg);
  write_bytes(path, buf, len); /* and the undamaged bytes load */
  cr_assert_eq(bs_levelset_grid_load(path, &ls, &err), 0, "%s", err.msg);
  bs_levelset_destroy(&ls);
  remove(path);
  /* an unwritable path */
  g = grid_of(linear_fn, origin, 0.5, n);
  cr_assert_eq(bs_levelset_grid_save(g, "/nonexistent/dir/x.bsls", &err), BS_EIO);
  cr_assert(strstr(err.msg, "/nonexistent/dir/x.bsls"), "%s", err.msg);
  bs_levelset_destroy(&g);
}

/* ---- parameter errors ------------------------------------------------------- */

Test(levelset, parameter_errors_name_the_parameter) {
  bs_error err;
  bs_levelset *ls = NULL;
  const double c[3] = {0, 0, 0}, z[3] = {0, 0, 0}, a[3] = {0, 0, 1}, nanv[3] = {0, NAN, 0};
  cr_assert_eq(bs_levelset_create_sphere(c, -1, &ls, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "radius"), "%s", err.msg);
  cr_assert_eq(bs_levelset_create_sphere(c, 0, &ls, &err), BS_EINPUT);
  cr_assert_eq(bs_levelset_create_sphere(nanv, 1, &ls, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "centre[1]"), "%s", err.msg);
  cr_assert_eq(bs_levelset_create_sphere(c, NAN, &ls, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "radius"), "%s", err.msg);
  cr_assert_eq(bs_levelset_create_halfspace(z, 0, &ls, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "normal"), "%s", err.msg);
  cr_assert_eq(bs_levelset_create_halfspace(a, INFINITY, &ls, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "offset"), "%s", err.msg);
  double half[3] = {1, 0, 1};
  cr_assert_eq(bs_levelset_create_box(c, half, &ls, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "half_extents[1]"), "%s", err.msg);
  cr_assert_eq(bs_levelset_create_cylinder(c, z, 1, 1, &ls, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "axis"), "%s", err.msg);
  cr_assert_eq(bs_levelset_create_cylinder(c, a, 1, -2, &ls, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "half_height"), "%s", err.msg);
  cr_assert_eq(bs_levelset_create_torus(c, a, 1, 1.5, &ls, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "minor"), "%s", err.msg);
  cr_assert_eq(bs_levelset_create_torus(c, a, -1, 0.5, &ls, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "major"), "%s", err.msg);
  cr_assert_null(ls);
  /* grids */
  const double o[3] = {0, 0, 0}, vals[8] = {1, 2, 3, 4, 5, NAN, 7, 8};
  const int32_t n2[3] = {2, 2, 2}, n1[3] = {2, 1, 2};
  cr_assert_eq(bs_levelset_grid_from_values(o, 0.1, n1, vals, &ls, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "n[1]"), "%s", err.msg);
  cr_assert_eq(bs_levelset_grid_from_values(o, -0.1, n2, vals, &ls, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "h = "), "%s", err.msg);
  cr_assert_eq(bs_levelset_grid_from_values(o, 0.1, n2, vals, &ls, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "(1, 0, 1)"), "%s", err.msg);
  cr_assert_null(ls);
  bs_levelset *s = make_shape(1);
  double lo[3] = {0, 0, 0}, hi[3] = {1, -1, 1};
  cr_assert_eq(bs_levelset_grid_sample(s, 0, lo, hi, 0.1, &ls, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "hi[1]"), "%s", err.msg);
  /* motions */
  double v[3] = {0, 0, NAN}, t2[2] = {1, 1}, d6[6] = {0}, r6[6] = {0};
  cr_assert_eq(bs_levelset_set_velocity(s, z, v, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "angular_velocity[2]"), "%s", err.msg);
  cr_assert_eq(bs_levelset_set_keyframes(s, 2, t2, d6, r6, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "keyframes[1].time"), "%s", err.msg);
  cr_assert_eq(bs_levelset_set_keyframes(s, 0, t2, d6, r6, &err), BS_EINPUT);
  t2[1] = 2;
  r6[4] = INFINITY;
  cr_assert_eq(bs_levelset_set_keyframes(s, 2, t2, d6, r6, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "keyframes[1].rotation"), "%s", err.msg);
  cr_assert_eq(bs_levelset_motion(s), BS_LS_STATIC); /* failed setters leave the motion alone */
  bs_levelset_destroy(&s);
  bs_levelset_destroy(&s); /* NULL is fine */
  bs_levelset_destroy(NULL);
}

/* No NaN or Inf on the non-smooth sets: centres, axes, core circles, edges. */
Test(levelset, finite_on_degenerate_points) {
  for (int kind = 1; kind < N_ANALYTIC; kind++) {
    bs_levelset *ls = make_shape(kind);
    double pts[4][3] = {{0, 0, 0}, {0, 0, 0.3}, {0.8, 0, 0}, {0.5, 0.3, 0.4}}; /* local */
    bs_levelset_frame f;
    bs_levelset_frame_at(ls, 0, &f);
    for (int i = 0; i < 4; i++) {
      double x[3], g[3], H[9];
      mv(f.M, pts[i], x);
      for (int k = 0; k < 3; k++) x[k] += f.c[k];
      double phi = bs_levelset_eval(ls, 0, x, g, H);
      cr_assert(isfinite(phi));
      for (int k = 0; k < 3; k++) cr_assert(isfinite(g[k]));
      for (int k = 0; k < 9; k++) cr_assert(isfinite(H[k]), "%s point %d", bs_levelset_kind_name(ls->kind), i);
      cr_assert(fabs(sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]) - 1) < 1e-12);
    }
    bs_levelset_destroy(&ls);
  }
}

/* A normal or an axis of components near 1e154 and beyond (their squares
 * overflow) or near 1e-200 (they underflow) is the same direction as (0, 1,
 * 0): the plane y >= 0.5 and the cylinder about y, not a zero vector. */
Test(levelset, huge_and_tiny_directions_normalize) {
  const double dirs[][3] = {{0, 1e155, 0}, {0, 1e300, 0}, {0, 1e-200, 0}, {0, 4e-320, 0}, {1e-310, 1e300, 0}};
  const double x[3] = {0.3, 2.0, -0.4}, c[3] = {0, 0, 0};
  bs_error err;
  for (size_t i = 0; i < sizeof dirs / sizeof dirs[0]; i++) {
    bs_levelset *ls = NULL;
    const double len = bs_norm3_scaled(dirs[i]);
    cr_assert_eq(bs_levelset_create_halfspace(dirs[i], 0.5 * len, &ls, &err), 0, "%zu: %s", i, err.msg);
    double g[3];
    double phi = bs_levelset_eval(ls, 0, x, g, NULL);
    cr_expect(fabs(phi - 1.5) < 1e-14 && fabs(g[1] - 1) < 1e-14, "direction %zu: phi %.17g grad (%g, %g, %g)", i, phi,
              g[0], g[1], g[2]);
    bs_levelset_destroy(&ls);
    cr_assert_eq(bs_levelset_create_cylinder(c, dirs[i], 1, 10, &ls, &err), 0, "%zu: %s", i, err.msg);
    phi = bs_levelset_eval(ls, 0, x, g, NULL);
    cr_expect(fabs(phi - (hypot(0.3, 0.4) - 1)) < 1e-14, "cylinder %zu: phi %.17g", i, phi);
    bs_levelset_destroy(&ls);
  }
  const double inf3[3] = {0, INFINITY, 0};
  bs_levelset *ls = NULL;
  cr_expect_eq(bs_levelset_create_halfspace(inf3, 0, &ls, &err), BS_EINPUT);
  cr_expect(fabs(bs_norm3_scaled((const double[3]){3e200, 4e200, 0}) / 5e200 - 1) < 1e-15);
  cr_expect_eq(bs_norm3_scaled((const double[3]){0, 0, 0}), 0);
}

/* bs_levelset_surely_outside_frame: wherever it says 1 the evaluated phi is
 * >= 0, for a sampled torus, its complement, moving, and the linear mode
 * (never 1); it does say 1 at nine in ten points 0.3 outside inside the grid
 * (so the test can fail), and 0 for an analytic shape. */
Test(levelset, grid_surely_outside_never_contradicts_phi) {
  bs_levelset *torus = make_shape(4), *grid = sampled_torus(0.05);
  bs_error err;
  const double *lo = TORUS_LO, *hi = TORUS_HI;
  for (int variant = 0; variant < 4; variant++) {
    cr_assert_eq(bs_levelset_grid_set_interp(grid, variant == 3 ? BS_GRID_LINEAR : BS_GRID_CUBIC, &err), 0);
    bs_levelset_set_complement(grid, variant == 1);
    if (variant == 2) set_test_velocity(grid);
    const double t = variant == 2 ? 0.3 : 0;
    bs_levelset_frame f;
    bs_levelset_frame_at(grid, t, &f);
    int said = 0, far = 0, far_said = 0;
    for (int p = 0; p < 20000; p++) {
      double x[3], y[3];
      for (int k = 0; k < 3; k++) x[k] = urange(lo[k] - 0.3, hi[k] + 0.3);
      const double phi = bs_levelset_eval_frame(grid, &f, x, NULL, NULL);
      const int s = bs_levelset_surely_outside_frame(grid, &f, x);
      cr_assert(!s || phi >= 0, "variant %d: surely outside where phi = %g", variant, phi);
      said += s;
      bs_levelset_local_point(grid, t, x, y);
      int interior = 1; /* two cells and a block from the grid's faces (in its own frame) */
      for (int k = 0; k < 3; k++) interior &= grid->c0[k] + y[k] - lo[k] > 0.25 && hi[k] - grid->c0[k] - y[k] > 0.25;
      if (interior && phi > 0.3) far++, far_said += s;
    }
    if (variant == 3) {
      cr_assert_eq(said, 0, "the linear mode has no coefficient ranges");
    } else if (variant != 1) { /* the complement's outside, the tube, is at most 0.25 deep */
      cr_assert_gt(far, 200);
      cr_assert_geq(far_said, far * 9 / 10, "variant %d: %d of %d points 0.3 outside, inside the grid, certain",
                    variant, far_said, far);
    }
  }
  bs_levelset_frame f0;
  bs_levelset_frame_at(torus, 0, &f0);
  const double x[3] = {5, 5, 5};
  cr_assert_eq(bs_levelset_surely_outside_frame(torus, &f0, x), 0, "an analytic shape is always evaluated");
  bs_levelset_destroy(&grid);
  bs_levelset_destroy(&torus);
}
