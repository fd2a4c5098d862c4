/* test_ipc_obstacle.c — the barrier against obstacles (bs_ipc_obstacle.h):
 * gradient and Hessian of the barrier (plane, sphere, box, torus, grid) and
 * of the lagged friction against finite differences; the CCD against level
 * sets (never past the surface, exact head-on fraction for a plane, grids'
 * Lipschitz bound), also against moving shapes, and the carry of vertices
 * with a moving obstacle; the analytic shapes are distances (|grad phi| = 1 and
 * phi equal to a brute-force distance); bad input named. */
#include <criterion/criterion.h>
#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

#include "bs_fem.h"
#include "bs_ipc_obstacle.h"
#include "bs_mesh.h"
#include "bs_terms.h"
#include "test_term_eval.h"

typedef struct fix {
  bs_mesh *mesh;
  bs_fem *fem;
  bs_term *t;
  bs_levelset *ls;
  bs_step_data step;
  double *x, *xn, *xhat;
  int n3;
} fix;

/* A 1x1x1 box of 2^3 cells [0,1]^2 x [z0, z0 + 1], jittered, and a term
 * with dhat against ls. */
static void fix_make(fix *f, double z0, double dhat, bs_levelset *ls, double mu) {
  memset(f, 0, sizeof *f);
  bs_error err = {0};
  const double lo[3] = {0, 0, z0}, hi[3] = {1, 1, z0 + 1};
  cr_assert_eq(bs_mesh_create_box(lo, hi, 2, 2, 2, &f->mesh, &err), 0, "%s", err.msg);
  bs_material mat;
  cr_assert_eq(bs_material_init(BS_MODEL_NEO_HOOKEAN, 1e5, 0.3, 1000, &mat, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_fem_create(f->mesh, 1, &mat, NULL, &f->fem, &err), 0, "%s", err.msg);
  f->n3 = 3 * f->mesh->n_vertices;
  f->x = malloc(sizeof(double) * (size_t)f->n3);
  f->xn = malloc(sizeof(double) * (size_t)f->n3);
  f->xhat = malloc(sizeof(double) * (size_t)f->n3);
  for (int i = 0; i < f->n3; i++) f->x[i] = f->mesh->x[i] + 1e-3 * sin(3.1 * i + 0.7);
  memcpy(f->xn, f->x, sizeof(double) * (size_t)f->n3);
  memcpy(f->xhat, f->x, sizeof(double) * (size_t)f->n3);
  f->step = (bs_step_data){.dt = 0.01, .x_hat = f->xhat, .x_n = f->xn, .time = 0.01, .load = 1};
  f->ls = ls;
  cr_assert_eq(bs_term_ipc_obstacle_create(f->fem, &f->step, NULL, dhat, 1.0, &f->t, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_term_ipc_obstacle_add(f->t, ls, mu, 0, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_term_ipc_obstacle_set_project(f->t, 0, &err), 0);
}

static void fix_free(fix *f) {
  bs_term_destroy(&f->t);
  bs_levelset_destroy(&f->ls);
  bs_fem_destroy(&f->fem);
  bs_mesh_destroy(&f->mesh);
  free(f->x);
  free(f->xn);
  free(f->xhat);
}

/* Central differences of E against g and of g against H at f->x; asserts
 * some contact is active (the check is not vacuous). */
static void check_fd(fix *f, double h, double tol) {
  bs_ipc_obstacle_stats st;
  bs_error err = {0};
  cr_assert_eq(bs_term_ipc_obstacle_detect(f->t, f->x, &st, &err), 0, "%s", err.msg);
  cr_assert_gt(st.pairs, 0, "no active pair");
  const int n = f->n3;
  double *g = calloc((size_t)n, sizeof(double)), *gp = calloc((size_t)n, sizeof(double)),
         *gm = calloc((size_t)n, sizeof(double)), *y = malloc(sizeof(double) * (size_t)n);
  term_gradient(f->t, f->x, g);
  bs_bsr *H = NULL;
  cr_assert_eq(bs_fem_matrix(f->fem, &H, &err), 0, "%s", err.msg);
  term_hessian(f->t, f->x, H);
  double gmax = 0, hmax = 0, eg = 0, eh = 0;
  for (int i = 0; i < n; i++) gmax = fmax(gmax, fabs(g[i]));
  for (int i = 0; i < n; i++) {
    memcpy(y, f->x, sizeof(double) * (size_t)n);
    y[i] = f->x[i] + h;
    memset(gp, 0, sizeof(double) * (size_t)n);
    const double Ep = term_gradient(f->t, y, gp);
    y[i] = f->x[i] - h;
    memset(gm, 0, sizeof(double) * (size_t)n);
    const double Em = term_gradient(f->t, y, gm);
    eg = fmax(eg, fabs((Ep - Em) / (2 * h) - g[i]));
    const int vi = i / 3, ci = i % 3;
    for (int j = 0; j < n; j++) {
      const int vj = j / 3, cj = j % 3;
      double Hij = 0;
      if (vi == vj) Hij = H->val[9 * (size_t)H->diag[vi] + 3 * cj + ci];
      const double fd = (gp[j] - gm[j]) / (2 * h);
      hmax = fmax(hmax, fabs(fd));
      eh = fmax(eh, fabs(fd - Hij));
    }
  }
  cr_assert_lt(eg, tol * gmax, "gradient error %g of %g", eg, gmax);
  cr_assert_lt(eh, tol * hmax, "Hessian error %g of %g", eh, hmax);
  free(g), free(gp), free(gm), free(y);
  bs_bsr_destroy(&H);
}

Test(ipc_obstacle, barrier_gradient_and_hessian_match_differences) {
  bs_error err = {0};
  /* plane z = 0 under a box whose bottom sits 0.02 above it, dhat 0.05 */
  bs_levelset *ls = NULL;
  const double nz[3] = {0.02, -0.01, 1}, c0[3] = {0.5, 0.5, -0.3}, c1[3] = {0.5, 0.5, -0.28}, ax[3] = {0.2, 0.1, 1};
  cr_assert_eq(bs_levelset_create_halfspace(nz, 0, &ls, &err), 0);
  fix f;
  fix_make(&f, 0.03, 0.05, ls, 0);
  check_fd(&f, 1e-7, 1e-5);
  fix_free(&f);
  /* a sphere touching the bottom face from below */
  cr_assert_eq(bs_levelset_create_sphere(c0, 0.31, &ls, &err), 0);
  fix_make(&f, 0.03, 0.05, ls, 0);
  check_fd(&f, 1e-7, 1e-5);
  fix_free(&f);
  /* a box below (its top face and edges) */
  const double half[3] = {0.4, 0.4, 0.3};
  cr_assert_eq(bs_levelset_create_box(c0, half, &ls, &err), 0);
  fix_make(&f, 0.03, 0.05, ls, 0);
  check_fd(&f, 1e-7, 1e-5);
  fix_free(&f);
  /* a torus below, tilted */
  cr_assert_eq(bs_levelset_create_torus(c1, ax, 0.4, 0.25, &ls, &err), 0);
  fix_make(&f, 0.03, 0.08, ls, 0);
  check_fd(&f, 1e-7, 1e-5);
  fix_free(&f);
}

Test(ipc_obstacle, friction_gradient_and_hessian_match_differences) {
  bs_error err = {0};
  bs_levelset *ls = NULL;
  const double nz[3] = {0, 0, 1};
  cr_assert_eq(bs_levelset_create_halfspace(nz, 0, &ls, &err), 0);
  fix f;
  fix_make(&f, 0.02, 0.05, ls, 0.5);
  /* lag at xⁿ, then move: sliding (|u| > eps) for some vertices, sticking
   * (|u| < eps = eps_v dt = 1e-5) for others */
  cr_assert_eq(f.t->ops->begin_step(f.t, &err), 0, "%s", err.msg);
  bs_ipc_obstacle_stats st;
  cr_assert_eq(bs_term_ipc_obstacle_stats(f.t, &st, &err), 0);
  cr_assert_gt(st.friction_pairs, 0);
  for (int i = 0; i < f.n3; i++) f.x[i] += (i % 3 == 2 ? 0 : 2e-5 * sin(1.7 * i));
  check_fd(&f, 1e-9, 2e-4);
  fix_free(&f);
}

Test(ipc_obstacle, analytic_shapes_are_distances) {
  bs_error err = {0};
  bs_levelset *ls[3] = {NULL, NULL, NULL};
  const double c[3] = {0.1, -0.2, 0.3}, half[3] = {0.5, 0.3, 0.2}, ax[3] = {0, 0, 1};
  cr_assert_eq(bs_levelset_create_box(c, half, &ls[0], &err), 0);
  cr_assert_eq(bs_levelset_create_cylinder(c, ax, 0.4, 0.3, &ls[1], &err), 0);
  cr_assert_eq(bs_levelset_create_torus(c, ax, 0.6, 0.2, &ls[2], &err), 0);
  /* phi(x) vs the distance to the nearest of many surface samples (outside) */
  for (int s = 0; s < 3; s++) {
    unsigned seed = 7;
    for (int q = 0; q < 200; q++) {
      double x[3], g[3];
      for (int k = 0; k < 3; k++) x[k] = c[k] + 1.6 * ((rand_r(&seed) / (double)RAND_MAX) - 0.5);
      const double phi = bs_levelset_eval(ls[s], 0, x, g, NULL);
      if (!(phi > 1e-3)) continue;
      cr_assert_float_eq(sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]), 1.0, 1e-12);
      /* P(x) lies on the surface, at distance phi: the distance is <= phi;
       * and the sphere of radius phi around x has no inside point (sampled) */
      double p[3];
      bs_levelset_project(ls[s], 0, x, p);
      cr_assert_float_eq(bs_levelset_eval(ls[s], 0, p, NULL, NULL), 0.0, 1e-12);
      cr_assert_float_eq(sqrt((p[0] - x[0]) * (p[0] - x[0]) + (p[1] - x[1]) * (p[1] - x[1]) +
                              (p[2] - x[2]) * (p[2] - x[2])), phi, 1e-12);
      for (int r = 0; r < 200; r++) {
        double u[3], y[3];
        for (int k = 0; k < 3; k++) u[k] = rand_r(&seed) / (double)RAND_MAX - 0.5;
        const double l = sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
        for (int k = 0; k < 3; k++) y[k] = x[k] + 0.999 * phi * u[k] / l;
        cr_assert_gt(bs_levelset_eval(ls[s], 0, y, NULL, NULL), 0, "shape %d", s);
      }
    }
    bs_levelset_destroy(&ls[s]);
  }
}

Test(ipc_obstacle, ccd_never_passes_the_surface) {
  bs_error err = {0};
  bs_levelset *ls = NULL;
  const double nz[3] = {0, 0, 1};
  cr_assert_eq(bs_levelset_create_halfspace(nz, 0, &ls, &err), 0);
  bs_levelset_frame fr;
  bs_levelset_frame_at(ls, 0, &fr);
  /* head-on from z = 1 by -2: contact at 0.5; ACCD's answer 0.9 of it */
  const double x0[3] = {0.3, 0.2, 1}, d[3] = {0.4, 0, -2}, dside[3] = {5, 3, 0};
  const double a = bs_ccd_levelset(ls, &fr, 1, x0, d, 0.1, 2000);
  cr_assert_float_eq(a, 0.45, 1e-10);
  cr_assert_eq(bs_ccd_levelset(ls, &fr, 1, x0, dside, 0.1, 2000), 1.0); /* sliding: exact rate 0 */
  bs_levelset_destroy(&ls);
  /* a sphere, a box and a torus: random motions; the fraction's end and 100
   * points before it are outside */
  const double c[3] = {0, 0, 0}, half[3] = {0.5, 0.3, 0.2}, ax[3] = {0.3, 0.1, 1};
  for (int s = 0; s < 3; s++) {
    if (s == 0) cr_assert_eq(bs_levelset_create_sphere(c, 0.5, &ls, &err), 0);
    if (s == 1) cr_assert_eq(bs_levelset_create_box(c, half, &ls, &err), 0);
    if (s == 2) cr_assert_eq(bs_levelset_create_torus(c, ax, 0.6, 0.2, &ls, &err), 0);
    bs_levelset_frame_at(ls, 0, &fr);
    unsigned seed = 11;
    int limited = 0;
    for (int q = 0; q < 300; q++) {
      double p[3], dv[3];
      for (int k = 0; k < 3; k++) p[k] = 2.4 * (rand_r(&seed) / (double)RAND_MAX - 0.5);
      for (int k = 0; k < 3; k++) dv[k] = 3 * (rand_r(&seed) / (double)RAND_MAX - 0.5);
      if (!(bs_levelset_eval(ls, 0, p, NULL, NULL) > 1e-6)) continue;
      const double t = bs_ccd_levelset(ls, &fr, 1, p, dv, 0.1, 2000);
      limited += t < 1;
      for (int r = 0; r <= 100; r++) {
        const double tt = t * r / 100.0, y[3] = {p[0] + tt * dv[0], p[1] + tt * dv[1], p[2] + tt * dv[2]};
        cr_assert_gt(bs_levelset_eval(ls, 0, y, NULL, NULL), 0, "shape %d, motion %d at %g of %g", s, q, tt, t);
      }
    }
    cr_assert_gt(limited, 10, "shape %d: the CCD limited only %d motions", s, limited);
    bs_levelset_destroy(&ls);
  }
}

/* The CCD against moving shapes (a sphere translating, a box translating and
 * turning, a torus on keyframes that turn it): for random paths, 1000 points
 * of [0, fraction] of (x0 + a d, t0 + a dt) are outside the shape at their
 * own time, and a point carried with a translating shape is never limited. */
static void moving_shape(int s, bs_levelset **ls) {
  bs_error err = {0};
  const double c[3] = {0.1, 0, 0}, half[3] = {0.5, 0.3, 0.2}, ax[3] = {0.3, 0.1, 1};
  const double v[3] = {3, -1, 2}, w0[3] = {0, 0, 0}, w[3] = {1, 4, -2};
  if (s == 0) cr_assert_eq(bs_levelset_create_sphere(c, 0.5, ls, &err), 0);
  if (s == 1) cr_assert_eq(bs_levelset_create_box(c, half, ls, &err), 0);
  if (s == 2) cr_assert_eq(bs_levelset_create_torus(c, ax, 0.6, 0.2, ls, &err), 0);
  if (s < 2) cr_assert_eq(bs_levelset_set_velocity(*ls, v, s ? w : w0, &err), 0, "%s", err.msg);
  const double kt[3] = {0, 0.3, 0.5}, kd[9] = {0, 0, 0, 1, 0.5, 0, 1.2, 0.2, -0.4}, kr[9] = {0, 0, 0, 0, 1, 0, 1, 1, 0};
  if (s == 2) cr_assert_eq(bs_levelset_set_keyframes(*ls, 3, kt, kd, kr, &err), 0, "%s", err.msg);
}

Test(ipc_obstacle, moving_ccd_never_passes_the_surface) {
  for (int s = 0; s < 3; s++) {
    bs_levelset *ls = NULL;
    moving_shape(s, &ls);
    unsigned seed = 5 + s;
    int limited = 0, tried = 0;
    for (int q = 0; q < 1500; q++) {
      double p[3], dv[3];
      const double t0 = 0.4 * rand_r(&seed) / (double)RAND_MAX, dt = 0.6 * rand_r(&seed) / (double)RAND_MAX;
      bs_levelset_frame fr;
      bs_levelset_frame_at(ls, t0, &fr);
      for (int k = 0; k < 3; k++) p[k] = fr.c[k] + 2.4 * (rand_r(&seed) / (double)RAND_MAX - 0.5);
      for (int k = 0; k < 3; k++) dv[k] = 2 * (rand_r(&seed) / (double)RAND_MAX - 0.5);
      if (!(bs_levelset_eval(ls, t0, p, NULL, NULL) > 1e-6)) continue;
      tried++;
      const double f = bs_ccd_levelset_moving(ls, 1, p, dv, t0, t0 + dt, 0.1, 2000);
      cr_assert(f >= 0 && f <= 1);
      limited += f < 1;
      for (int r = 0; r <= 1000; r++) {
        const double a = f * r / 1000.0, y[3] = {p[0] + a * dv[0], p[1] + a * dv[1], p[2] + a * dv[2]};
        cr_assert_gt(bs_levelset_eval(ls, t0 + a * dt, y, NULL, NULL), 0, "shape %d, path %d at %g of %g", s, q, a, f);
      }
    }
    cr_assert_gt(limited, 50, "shape %d: the CCD limited only %d of %d paths", s, limited, tried);
    bs_levelset_destroy(&ls);
  }
  /* carried with the translating sphere, 1e-4 from it: never limited */
  bs_levelset *ls = NULL;
  moving_shape(0, &ls);
  /* the centre at 0.1 s plus 0.5001 along z; the sphere's motion over 0.2 s */
  const double p[3] = {0.1 + 0.3, -0.1, 0.2 + 0.5001}, d[3] = {3 * 0.2, -1 * 0.2, 2 * 0.2};
  cr_assert_eq(bs_ccd_levelset_moving(ls, 1, p, d, 0.1, 0.3, 0.1, 2000), 1.0);
  /* and held still, the sphere coming at it: stopped before contact */
  const double z[3] = {0, 0, 0}, q[3] = {0.1 + 0.6 + 0.5, -0.2, 0.4};
  const double f = bs_ccd_levelset_moving(ls, 1, q, z, 0, 1, 0.1, 2000);
  cr_assert(f > 0 && f < 1, "%g", f);
  cr_assert_gt(bs_levelset_eval(ls, f, q, NULL, NULL), 0);
  bs_levelset_destroy(&ls);
}

/* carry moves a vertex within dhat of a moving obstacle with the obstacle's
 * material point: its phi at t1 equals its phi at t0; the others stay. */
Test(ipc_obstacle, carry_keeps_the_distance_to_a_moving_obstacle) {
  bs_error err = {0};
  bs_levelset *ls = NULL;
  const double c[3] = {0.5, 0.5, -0.25}, half[3] = {0.6, 0.6, 0.25}, v[3] = {0.3, 0.1, 2}, w[3] = {0.5, -1, 2};
  cr_assert_eq(bs_levelset_create_box(c, half, &ls, &err), 0);
  cr_assert_eq(bs_levelset_set_velocity(ls, v, w, &err), 0);
  fix f;
  fix_make(&f, 0.02, 0.05, ls, 0); /* the box's bottom 0.02 above the obstacle's top: z0 jittered by 1e-3 */
  const bs_term_ops *ops = f.t->ops;
  cr_assert_not_null(ops->carry);
  double *z = calloc((size_t)f.n3, sizeof(double));
  uint8_t *carried = calloc((size_t)f.n3 / 3, 1);
  const double t0 = 0.0, t1 = 0.004;
  f.step.time = t0;
  cr_assert_eq(ops->carry(f.t, f.x, t0, t1, z, carried), BS_TERM_OK);
  int n = 0;
  for (int v3 = 0; v3 < f.n3 / 3; v3++) {
    const double *p = f.x + 3 * v3, q[3] = {p[0] + z[3 * v3], p[1] + z[3 * v3 + 1], p[2] + z[3 * v3 + 2]};
    const double phi0 = bs_levelset_eval(ls, t0, p, NULL, NULL);
    if (!carried[v3]) {
      cr_assert_geq(phi0, 0.05, "vertex %d within dhat, not carried", v3);
      cr_assert_eq(z[3 * v3] == 0 && z[3 * v3 + 1] == 0 && z[3 * v3 + 2] == 0, 1, "vertex %d moved", v3);
      continue;
    }
    n++;
    cr_assert(phi0 > 0 && phi0 < 0.05, "vertex %d carried at phi %g", v3, phi0);
    cr_assert_float_eq(bs_levelset_eval(ls, t1, q, NULL, NULL), phi0, 1e-12, "vertex %d", v3);
  }
  cr_assert_eq(n, 9, "the box's 9 bottom vertices are carried, got %d", n);
  double a = 0;
  cr_assert_eq(ops->sweep(f.t, f.x, z, t0, t1, &a), BS_TERM_OK);
  cr_assert_gt(a, 0.9, "the carried path is certified only to %g", a);
  cr_assert_eq(ops->sweep(f.t, f.x, NULL, t0, 0.05, &a), BS_TERM_OK);
  cr_assert(a < 1, "held still, the obstacle passes over the box by t = 0.05: %g", a);
  free(z);
  free(carried);
  fix_free(&f);
}

Test(ipc_obstacle, grid_lipschitz_bound_and_ccd) {
  bs_error err = {0};
  bs_levelset *sp = NULL, *g = NULL;
  const double c[3] = {0, 0, 0}, lo[3] = {-1, -1, -1}, hi[3] = {1, 1, 1};
  cr_assert_eq(bs_levelset_create_sphere(c, 0.5, &sp, &err), 0);
  cr_assert_eq(bs_levelset_grid_sample(sp, 0, lo, hi, 0.1, &g, &err), 0, "%s", err.msg);
  double slope = 0;
  const double L = bs_ipc_obstacle_lipschitz(g, &slope);
  cr_assert(slope > 0.9 && slope <= 1.0 + 1e-12, "slope %g", slope);
  cr_assert_gt(L, 1.0);
  /* the bound holds: |grad phi| <= L at random points (inside and outside the box) */
  unsigned seed = 5;
  for (int q = 0; q < 2000; q++) {
    double x[3], gr[3];
    for (int k = 0; k < 3; k++) x[k] = 3 * (rand_r(&seed) / (double)RAND_MAX - 0.5);
    bs_levelset_eval(g, 0, x, gr, NULL);
    cr_assert_leq(sqrt(gr[0] * gr[0] + gr[1] * gr[1] + gr[2] * gr[2]), L);
  }
  bs_levelset_frame fr;
  bs_levelset_frame_at(g, 0, &fr);
  const double x0[3] = {0.9, 0.1, 0}, d[3] = {-1.8, 0, 0};
  const double t = bs_ccd_levelset(g, &fr, L, x0, d, 0.1, 2000);
  cr_assert(t > 0.05 && t < 0.25, "t = %g (contact near 0.22)", t);
  for (int r = 0; r <= 200; r++) {
    const double tt = t * r / 200.0, y[3] = {x0[0] + tt * d[0], x0[1], x0[2]};
    cr_assert_gt(bs_levelset_eval(g, 0, y, NULL, NULL), 0);
  }
  bs_levelset_destroy(&sp);
  bs_levelset_destroy(&g);
}

Test(ipc_obstacle, term_max_step_and_not_evaluable_inside) {
  bs_error err = {0};
  bs_levelset *ls = NULL;
  const double nz[3] = {0, 0, 1};
  cr_assert_eq(bs_levelset_create_halfspace(nz, 0, &ls, &err), 0);
  fix f;
  fix_make(&f, 0.1, 0.05, ls, 0);
  double *d = calloc((size_t)f.n3, sizeof(double)), a = -1;
  for (int i = 2; i < f.n3; i += 3) d[i] = -1; /* everything down by 1 m */
  cr_assert_eq(bs_term_ipc_obstacle_max_step(f.t, f.x, d, &a, &err), 0);
  /* the lowest vertex is about 0.1 above: 0.9 of its distance */
  double zmin = INFINITY;
  for (int i = 2; i < f.n3; i += 3) zmin = fmin(zmin, f.x[i]);
  cr_assert_float_eq(a, 0.9 * zmin, 1e-9);
  for (int i = 0; i < f.n3; i++) f.x[i] += 0.2 * d[i];
  double E;
  cr_assert_eq(f.t->ops->value(f.t, f.x, &E), BS_TERM_NOT_EVALUABLE);
  bs_ipc_obstacle_stats st;
  cr_assert_eq(bs_term_ipc_obstacle_detect(f.t, f.x, &st, &err), 0);
  cr_assert_gt(st.inside, 0);
  cr_assert_lt(st.min_distance, 0);
  free(d);
  fix_free(&f);
}

Test(ipc_obstacle, bad_input_is_named) {
  bs_error err = {0};
  bs_levelset *ls = NULL;
  const double nz[3] = {0, 0, 1};
  cr_assert_eq(bs_levelset_create_halfspace(nz, 0, &ls, &err), 0);
  fix f;
  fix_make(&f, 0.1, 0.05, ls, 0);
  cr_assert_eq(bs_term_ipc_obstacle_add(f.t, ls, -1, 3, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "obstacle 3") && strstr(err.msg, "friction"), "%s", err.msg);
  cr_assert_eq(bs_term_ipc_obstacle_set_friction(f.t, 0, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "eps_v"), "%s", err.msg);
  cr_assert_eq(bs_term_ipc_obstacle_set_kappa(f.t, -1, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "kappa"), "%s", err.msg);
  bs_term *t2 = NULL;
  cr_assert_eq(bs_term_ipc_obstacle_create(f.fem, NULL, NULL, 0, 1, &t2, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "dhat"), "%s", err.msg);
  /* a grid that is not a distance: 10 x a sphere's distance */
  const int32_t n[3] = {5, 5, 5};
  double vals[125];
  for (int k = 0; k < 5; k++)
    for (int j = 0; j < 5; j++)
      for (int i = 0; i < 5; i++)
        vals[i + 5 * (j + 5 * k)] = 10 * (sqrt((i - 2.0) * (i - 2.0) + (j - 2.0) * (j - 2.0) + (k - 2.0) * (k - 2.0)) * 0.25 - 0.3);
  const double org[3] = {-0.5, -0.5, -0.5};
  bs_levelset *g = NULL;
  cr_assert_eq(bs_levelset_grid_from_values(org, 0.25, n, vals, &g, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_term_ipc_obstacle_add(f.t, g, 0, 1, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "obstacle 1 (grid)") && strstr(err.msg, "distance"), "%s", err.msg);
  bs_levelset_destroy(&g);
  fix_free(&f);
}

Test(ipc_obstacle, same_bits_on_1_and_2_threads) {
  bs_error err = {0};
  bs_levelset *ls = NULL;
  const double c[3] = {0.5, 0.5, -0.5};
  cr_assert_eq(bs_levelset_create_sphere(c, 0.51, &ls, &err), 0);
  bs_mesh *m = NULL;
  const double lo[3] = {0, 0, 0.02}, hi[3] = {1, 1, 1.02};
  cr_assert_eq(bs_mesh_create_box(lo, hi, 20, 20, 20, &m, &err), 0, "%s", err.msg);
  bs_material mat;
  cr_assert_eq(bs_material_init(BS_MODEL_NEO_HOOKEAN, 1e5, 0.3, 1000, &mat, &err), 0);
  bs_fem *fem = NULL;
  cr_assert_eq(bs_fem_create(m, 1, &mat, NULL, &fem, &err), 0, "%s", err.msg);
  bs_term *t = NULL;
  cr_assert_eq(bs_term_ipc_obstacle_create(fem, NULL, NULL, 0.05, 3.0, &t, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_term_ipc_obstacle_add(t, ls, 0, 0, &err), 0, "%s", err.msg);
  const size_t n3 = 3 * (size_t)m->n_vertices;
  double *g[2], E[2], a[2], *d = malloc(sizeof(double) * n3);
  for (size_t i = 0; i < n3; i++) d[i] = i % 3 == 2 ? -0.3 : 0.01 * sin((double)i);
  for (int k = 0; k < 2; k++) {
    omp_set_num_threads(k + 1);
    g[k] = calloc(n3, sizeof(double));
    E[k] = term_gradient(t, m->x, g[k]);
    cr_assert_eq(bs_term_ipc_obstacle_max_step(t, m->x, d, &a[k], &err), 0);
  }
  cr_assert_eq(memcmp(&E[0], &E[1], sizeof E[0]), 0);
  cr_assert_eq(memcmp(g[0], g[1], sizeof(double) * n3), 0);
  cr_assert_eq(a[0], a[1]);
  cr_assert(a[0] > 0 && a[0] < 1, "alpha %g", a[0]);
  free(g[0]), free(g[1]), free(d);
  bs_term_destroy(&t);
  bs_levelset_destroy(&ls);
  bs_fem_destroy(&fem);
  bs_mesh_destroy(&m);
}
