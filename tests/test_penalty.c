/* Object penalty term (paper 5.2): gradient and Hessian against central
 * differences (O(h^2)) on a small mesh pushed into a sphere, a half-space, a
 * bowl (complement of a sphere), a moving box and a torus; the energy is
 * k sum (-phi)^3 >= 0 over penetrating vertices and exactly zero (with zero
 * gradient and Hessian) when none penetrates; forces = -gradient; stats;
 * vertex subsets; identical results with 1 and 2 threads; argument errors. */
#include <criterion/criterion.h>
#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

#include "bs_fem.h"
#include "bs_levelset.h"
#include "bs_penalty.h"
#include "bs_selfcollide.h"
#include "bs_step.h"
#include "bs_terms.h"
#include "test_term_eval.h"

static uint64_t rng = 0x2545F4914F6CDD1Dull;
static double urand(void) {
  uint64_t z = (rng += 0x9E3779B97F4A7C15ull);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  z ^= z >> 31;
  return (double)(z >> 11) * 0x1.0p-53;
}

typedef struct fixture {
  bs_mesh *mesh;
  bs_fem *fem;
  bs_material mat;
  bs_step_data step;
  size_t n3;
} fixture;

/* The unit cube [-0.5, 0.5]^3 as 3 x 3 x 3 cells (64 vertices). */
static void setup(fixture *f) {
  bs_error err;
  double lo[3] = {-0.5, -0.5, -0.5}, hi[3] = {0.5, 0.5, 0.5};
  cr_assert_eq(bs_mesh_create_box(lo, hi, 3, 3, 3, &f->mesh, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_material_init(BS_MODEL_FIXED_COROTATED, 1e4, 0.3, 1000, &f->mat, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_fem_create(f->mesh, 1, &f->mat, NULL, &f->fem, &err), 0, "%s", err.msg);
  memset(&f->step, 0, sizeof f->step);
  f->step.dt = 1.0 / 24;
  f->step.load = 1;
  f->n3 = 3 * (size_t)f->mesh->n_vertices;
}
static void teardown(fixture *f) {
  bs_fem_destroy(&f->fem);
  bs_mesh_destroy(&f->mesh);
}

/* A lower bound on the distance from x to where phi is not C^2: the medial
 * sets of the analytic shapes (in the local frame). */
static double smooth_margin(const bs_levelset *ls, double t, const double x[3]) {
  double y[3];
  bs_levelset_local_point(ls, t, x, y);
  const double *p = ls->param;
  double rho = hypot(y[0], y[1]);
  switch (ls->kind) {
    case BS_LS_SPHERE: return sqrt(y[0] * y[0] + y[1] * y[1] + y[2] * y[2]);
    case BS_LS_BOX: { /* outside: the planes q_k = 0; inside: ties of the
                         largest q and the plane y_m = 0 of its axis */
      double q[3], m = 1e9;
      int mx = 0;
      for (int k = 0; k < 3; k++) {
        q[k] = fabs(y[k]) - p[k];
        if (q[k] > q[mx]) mx = k;
      }
      if (q[mx] > 0) {
        for (int k = 0; k < 3; k++) m = fmin(m, fabs(q[k]));
        return m;
      }
      m = fabs(y[mx]);
      for (int k = 0; k < 3; k++)
        if (k != mx) m = fmin(m, (q[mx] - q[k]) / 2);
      return m;
    }
    case BS_LS_TORUS: return fmin(rho, hypot(rho - p[0], y[2]));
    default: return 1e9;
  }
}

/* Rest positions shifted by `shift` and perturbed by `noise`, redrawn until
 * no vertex is within `gap` of the surface (where the energy's third
 * derivative jumps, which would spoil the O(h^2) rate of a difference
 * quotient) or of a medial set, and at least `min_in` vertices penetrate. */
static void config(const fixture *f, const bs_levelset *ls, double t, const double shift[3], double noise,
                   double gap, int min_in, double *x) {
  for (int tries = 0; tries < 1000; tries++) {
    int in = 0, ok = 1;
    for (int32_t v = 0; v < f->mesh->n_vertices; v++) {
      for (int k = 0; k < 3; k++) x[3 * v + k] = f->mesh->x[3 * v + k] + shift[k] + noise * (urand() - 0.5);
      double phi = bs_levelset_eval(ls, t, x + 3 * v, NULL, NULL);
      if (fabs(phi) < gap || smooth_margin(ls, t, x + 3 * v) < gap) ok = 0;
      in += phi < 0;
    }
    if (ok && in >= min_in) return;
  }
  cr_assert_fail("no configuration found");
}

/* Energy computed directly: k sum over vertices of max(-phi, 0)^3. */
static double direct_energy(const fixture *f, const bs_levelset *ls, double k, double t, const double *x) {
  double E = 0;
  for (int32_t v = 0; v < f->mesh->n_vertices; v++) {
    double phi = bs_levelset_eval(ls, t, x + 3 * v, NULL, NULL);
    if (phi < 0) E += k * pow(-phi, 3);
  }
  return E;
}

enum { N_H = 3 };
static const double hs[N_H] = {2e-3, 1e-3, 5e-4};

/* Gradient: sum over random directions of |central difference of E - g.d|;
 * Hessian: |central difference of g - H d| (2-norms), for each h; asserts an
 * h^2 rate (or round-off level) and small errors. */
static void check_term_fd(const fixture *f, const bs_term *t, const double *x, const char *what) {
  size_t n3 = f->n3;
  double *g = calloc(n3, sizeof(double)), *gp = calloc(n3, sizeof(double)), *gm = calloc(n3, sizeof(double));
  double *d = malloc(n3 * sizeof(double)), *xp = malloc(n3 * sizeof(double)), *xm = malloc(n3 * sizeof(double));
  double *Hd = malloc(n3 * sizeof(double));
  bs_bsr *H = NULL;
  bs_error err;
  cr_assert_eq(bs_fem_matrix(f->fem, &H, &err), 0, "%s", err.msg);
  bs_bsr_zero(H);
  term_hessian(t, x, H);
  cr_assert_eq(bs_bsr_check(H, 1e-12, &err), 0, "%s: %s", what, err.msg);
  /* only diagonal blocks */
  for (int32_t i = 0; i < H->n; i++)
    for (int32_t s = H->row_ptr[i]; s < H->row_ptr[i + 1]; s++)
      if (H->col[s] != i)
        for (int e = 0; e < 9; e++) cr_assert(H->val[9 * (size_t)s + e] == 0, "%s: off-diagonal block", what);
  double E = term_gradient(t, x, g);
  cr_assert(E == term_value(t, x), "%s: gradient's energy differs from value", what);
  double eg[N_H] = {0}, eH[N_H] = {0}, gscale = 0, Hscale = 0;
  for (int dir = 0; dir < 4; dir++) {
    for (size_t i = 0; i < n3; i++) d[i] = 2 * urand() - 1;
    bs_bsr_mul(H, NULL, d, Hd);
    double gd = 0;
    for (size_t i = 0; i < n3; i++) gd += g[i] * d[i], Hscale += Hd[i] * Hd[i];
    gscale += fabs(gd);
    for (int s = 0; s < N_H; s++) {
      double h = hs[s];
      for (size_t i = 0; i < n3; i++) xp[i] = x[i] + h * d[i], xm[i] = x[i] - h * d[i];
      double fd = (term_value(t, xp) - term_value(t, xm)) / (2 * h);
      eg[s] += fabs(fd - gd);
      memset(gp, 0, n3 * sizeof(double));
      memset(gm, 0, n3 * sizeof(double));
      term_gradient(t, xp, gp);
      term_gradient(t, xm, gm);
      double e2 = 0;
      for (size_t i = 0; i < n3; i++) {
        double r = (gp[i] - gm[i]) / (2 * h) - Hd[i];
        e2 += r * r;
      }
      eH[s] += sqrt(e2);
    }
  }
  Hscale = sqrt(Hscale);
  cr_assert(gscale > 0 && Hscale > 0, "%s: nothing penetrates", what);
  for (int s = 0; s + 1 < N_H; s++) {
    if (eg[s + 1] > 1e-10 * gscale) {
      double r = eg[s] / eg[s + 1];
      cr_assert(r > 3.5 && r < 4.5, "%s: gradient FD error ratio %g (%g -> %g)", what, r, eg[s], eg[s + 1]);
    }
    if (eH[s + 1] > 1e-10 * Hscale) {
      double r = eH[s] / eH[s + 1];
      cr_assert(r > 3.5 && r < 4.5, "%s: Hessian FD error ratio %g (%g -> %g)", what, r, eH[s], eH[s + 1]);
    }
  }
  cr_assert(eg[N_H - 1] < 1e-5 * gscale, "%s: gradient relative FD error %g", what, eg[N_H - 1] / gscale);
  cr_assert(eH[N_H - 1] < 1e-4 * Hscale, "%s: Hessian relative FD error %g", what, eH[N_H - 1] / Hscale);
  bs_bsr_destroy(&H);
  free(g), free(gp), free(gm), free(d), free(xp), free(xm), free(Hd);
}

/* The term against one obstacle: FD derivatives, energy = direct sum > 0,
 * forces = -gradient, stats. Vertices keep `gap` from the surface and the
 * medial sets (the torus needs more: the third derivative of phi grows as
 * 1/distance^2 to the core circle, and so does the FD error constant). */
static void check_obstacle(fixture *f, bs_levelset *ls, double t, const double shift[3], double gap,
                           const char *what) {
  bs_error err;
  bs_term *term = NULL;
  const double k = 3e5;
  f->step.time = t;
  cr_assert_eq(bs_term_penalty_create(f->fem, &f->step, ls, k, &term, &err), 0, "%s", err.msg);
  cr_assert(bs_term_is_penalty(term));
  cr_assert_eq(bs_term_penalty_levelset(term), ls);
  cr_assert_eq(bs_term_penalty_stiffness(term), k);
  double *x = malloc(f->n3 * sizeof(double)), *g = calloc(f->n3, sizeof(double)),
         *fv = malloc(f->n3 * sizeof(double));
  config(f, ls, t, shift, 0.15, gap, 5, x);
  check_term_fd(f, term, x, what);
  double E = term_value(term, x), Ed = direct_energy(f, ls, k, t, x);
  cr_assert(E > 0, "%s: energy %g", what, E);
  cr_assert(fabs(E - Ed) <= 1e-13 * Ed, "%s: energy %.17g, direct sum %.17g", what, E, Ed);
  /* forces are -gradient, point out of the obstacle, and match the point force */
  term_gradient(term, x, g);
  cr_assert_eq(bs_term_penalty_forces(term, x, fv, &err), 0, "%s", err.msg);
  int32_t count = 0, cd = 0;
  double depth = -1, dd = 0;
  for (int32_t v = 0; v < f->mesh->n_vertices; v++) {
    double grad[3], pf[3];
    double phi = bs_levelset_eval(ls, t, x + 3 * v, grad, NULL);
    double phi2 = bs_penalty_point_force(ls, k, t, x + 3 * v, pf);
    cr_assert_eq(phi, phi2);
    for (int a = 0; a < 3; a++) {
      cr_assert(fabs(fv[3 * v + a] + g[3 * v + a]) <= 1e-12 * (1 + fabs(g[3 * v + a])));
      cr_assert(fabs(fv[3 * v + a] - pf[a]) <= 1e-12 * (1 + fabs(pf[a])));
    }
    double fn = fv[3 * v] * grad[0] + fv[3 * v + 1] * grad[1] + fv[3 * v + 2] * grad[2];
    if (phi < 0) {
      cd++;
      dd = fmax(dd, -phi);
      cr_assert(fn > 0, "%s: the force on vertex %d does not push out", what, (int)v);
    } else {
      cr_assert(fn == 0);
    }
  }
  cr_assert_eq(bs_term_penalty_stats(term, x, &count, &depth, &err), 0, "%s", err.msg);
  cr_assert_eq(count, cd);
  cr_assert_eq(depth, dd);
  bs_term_destroy(&term);
  cr_assert_null(term);
  free(x), free(g), free(fv);
}

Test(penalty, sphere) {
  fixture f;
  setup(&f);
  bs_levelset *ls = NULL;
  bs_error err;
  double c[3] = {0.9, 0.1, -0.05}, shift[3] = {0, 0, 0};
  cr_assert_eq(bs_levelset_create_sphere(c, 0.6, &ls, &err), 0, "%s", err.msg);
  check_obstacle(&f, ls, 0, shift, 0.01, "sphere");
  bs_levelset_destroy(&ls);
  teardown(&f);
}

Test(penalty, halfspace_and_complement) {
  fixture f;
  setup(&f);
  bs_levelset *ls = NULL;
  bs_error err;
  double n[3] = {0.1, 1, 0.2}, shift[3] = {0, 0.1, 0};
  cr_assert_eq(bs_levelset_create_halfspace(n, 0, &ls, &err), 0, "%s", err.msg);
  check_obstacle(&f, ls, 0, shift, 0.01, "half-space");
  bs_levelset_set_complement(ls, 1); /* the region above is now the obstacle */
  check_obstacle(&f, ls, 0, shift, 0.01, "complement of half-space");
  bs_levelset_destroy(&ls);
  teardown(&f);
}

Test(penalty, bowl_complement_of_sphere) {
  fixture f;
  setup(&f);
  bs_levelset *ls = NULL;
  bs_error err;
  double c[3] = {0.05, -0.03, 0.02}, shift[3] = {0, 0, 0};
  cr_assert_eq(bs_levelset_create_sphere(c, 0.7, &ls, &err), 0, "%s", err.msg);
  bs_levelset_set_complement(ls, 1); /* the mesh's corners poke out of the ball */
  check_obstacle(&f, ls, 0, shift, 0.01, "bowl");
  bs_levelset_destroy(&ls);
  teardown(&f);
}

Test(penalty, moving_box_and_torus) {
  fixture f;
  setup(&f);
  bs_levelset *box = NULL, *torus = NULL;
  bs_error err;
  double c[3] = {1.2, 0.3, 0}, half[3] = {0.4, 0.5, 0.3}, v[3] = {-0.5, 0, 0}, w[3] = {0, 0, 0.4},
         shift[3] = {0, 0, 0};
  cr_assert_eq(bs_levelset_create_box(c, half, &box, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_levelset_set_velocity(box, v, w, &err), 0, "%s", err.msg);
  check_obstacle(&f, box, 1.0, shift, 0.01, "moving box"); /* at t = 1 its centre is at x = 0.7 */
  double tc[3] = {0, 0, 0.3}, axis[3] = {0.1, 0.2, 1};
  cr_assert_eq(bs_levelset_create_torus(tc, axis, 0.6, 0.3, &torus, &err), 0, "%s", err.msg);
  check_obstacle(&f, torus, 0, shift, 0.02, "torus");
  bs_levelset_destroy(&box);
  bs_levelset_destroy(&torus);
  teardown(&f);
}

/* Far from the obstacle: zero energy, zero gradient, zero Hessian, no stats. */
Test(penalty, zero_when_nothing_penetrates) {
  fixture f;
  setup(&f);
  bs_levelset *ls = NULL;
  bs_term *t = NULL;
  bs_error err;
  double c[3] = {3, 0, 0};
  cr_assert_eq(bs_levelset_create_sphere(c, 1, &ls, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_term_penalty_create(f.fem, NULL, ls, 1e5, &t, &err), 0, "%s", err.msg);
  double *x = malloc(f.n3 * sizeof(double)), *g = calloc(f.n3, sizeof(double));
  for (size_t i = 0; i < f.n3; i++) x[i] = f.mesh->x[i] + 0.1 * (urand() - 0.5);
  for (size_t i = 0; i < f.n3; i++) g[i] = (double)i; /* the gradient adds into g */
  cr_assert_eq(term_value(t, x), 0.0);
  cr_assert_eq(term_gradient(t, x, g), 0.0);
  for (size_t i = 0; i < f.n3; i++) cr_assert_eq(g[i], (double)i);
  bs_bsr *H = NULL;
  cr_assert_eq(bs_fem_matrix(f.fem, &H, &err), 0, "%s", err.msg);
  term_hessian(t, x, H);
  for (int64_t s = 0; s < 9 * H->nnzb; s++) cr_assert_eq(H->val[s], 0.0);
  int32_t count = -1;
  double depth = -1;
  cr_assert_eq(bs_term_penalty_stats(t, x, &count, &depth, &err), 0, "%s", err.msg);
  cr_assert(count == 0 && depth == 0);
  /* touching exactly (phi = 0) is not penetrating */
  double xs[3] = {2, 0, 0}, pf[3];
  cr_assert_eq(bs_penalty_point_force(ls, 1e5, 0, xs, pf), 0.0);
  cr_assert(pf[0] == 0 && pf[1] == 0 && pf[2] == 0);
  bs_bsr_destroy(&H);
  bs_term_destroy(&t);
  bs_levelset_destroy(&ls);
  free(x), free(g);
  teardown(&f);
}

/* Energy C^2 at phi = 0: value, gradient and Hessian of one vertex tend to 0
 * as it approaches the surface from inside. */
Test(penalty, smooth_at_the_surface) {
  bs_levelset *ls = NULL;
  bs_error err;
  double n[3] = {0, 0, 1};
  cr_assert_eq(bs_levelset_create_halfspace(n, 0, &ls, &err), 0, "%s", err.msg);
  const double k = 1e6;
  for (double depth = 1e-2; depth > 1e-6; depth /= 10) {
    double x[3] = {0.3, 0.2, -depth}, f3[3];
    double phi = bs_penalty_point_force(ls, k, 0, x, f3);
    cr_assert(fabs(phi + depth) < 1e-18);
    cr_assert(fabs(f3[2] - 3 * k * depth * depth) <= 1e-12 * 3 * k * depth * depth);
  }
  bs_levelset_destroy(&ls);
}

Test(penalty, vertex_subset) {
  fixture f;
  setup(&f);
  bs_levelset *ls = NULL;
  bs_term *all = NULL, *sub = NULL;
  bs_error err;
  double c[3] = {0.9, 0, 0}, shift[3] = {0, 0, 0};
  cr_assert_eq(bs_levelset_create_sphere(c, 0.6, &ls, &err), 0, "%s", err.msg);
  const bs_group *gx = bs_mesh_group(f.mesh, "xmax");
  cr_assert_not_null(gx);
  cr_assert_eq(bs_term_penalty_create(f.fem, &f.step, ls, 1e5, &all, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_term_penalty_create_subset(f.fem, &f.step, ls, 1e5, gx->n_vertices, gx->vertices, &sub, &err), 0,
               "%s", err.msg);
  double *x = malloc(f.n3 * sizeof(double)), *g = calloc(f.n3, sizeof(double)), *fv = malloc(f.n3 * sizeof(double));
  config(&f, ls, 0, shift, 0.15, 0.01, 5, x);
  /* the subset's energy is the sum over its vertices only */
  double Es = 0;
  uint8_t *in = calloc((size_t)f.mesh->n_vertices, 1);
  for (int32_t i = 0; i < gx->n_vertices; i++) in[gx->vertices[i]] = 1;
  for (int32_t i = 0; i < gx->n_vertices; i++) {
    double phi = bs_levelset_eval(ls, 0, x + 3 * gx->vertices[i], NULL, NULL);
    if (phi < 0) Es += 1e5 * pow(-phi, 3);
  }
  cr_assert(Es > 0);
  cr_assert(fabs(term_value(sub, x) - Es) <= 1e-13 * Es);
  cr_assert(term_value(sub, x) <= term_value(all, x));
  term_gradient(sub, x, g);
  cr_assert_eq(bs_term_penalty_forces(sub, x, fv, &err), 0, "%s", err.msg);
  for (int32_t v = 0; v < f.mesh->n_vertices; v++)
    if (!in[v])
      for (int a = 0; a < 3; a++) cr_assert(g[3 * v + a] == 0 && fv[3 * v + a] == 0);
  check_term_fd(&f, sub, x, "subset");
  bs_term_destroy(&all);
  bs_term_destroy(&sub);
  bs_levelset_destroy(&ls);
  free(x), free(g), free(fv), free(in);
  teardown(&f);
}

/* Energy, gradient and Hessian bitwise identical with 1 and 2 threads, on a
 * mesh large enough to span several energy chunks. */
Test(penalty, thread_count_independent) {
  bs_error err;
  bs_mesh *mesh = NULL;
  bs_fem *fem = NULL;
  bs_material mat;
  double lo[3] = {-0.5, -0.5, -0.5}, hi[3] = {0.5, 0.5, 0.5};
  cr_assert_eq(bs_mesh_create_box(lo, hi, 14, 14, 14, &mesh, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_material_init(BS_MODEL_FIXED_COROTATED, 1e4, 0.3, 1000, &mat, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_fem_create(mesh, 1, &mat, NULL, &fem, &err), 0, "%s", err.msg);
  bs_levelset *ls = NULL;
  double c[3] = {0.05, 0.02, -0.01};
  cr_assert_eq(bs_levelset_create_sphere(c, 0.55, &ls, &err), 0, "%s", err.msg);
  bs_levelset_set_complement(ls, 1);
  bs_term *t = NULL;
  cr_assert_eq(bs_term_penalty_create(fem, NULL, ls, 1e5, &t, &err), 0, "%s", err.msg);
  size_t n3 = 3 * (size_t)mesh->n_vertices;
  cr_assert(mesh->n_vertices > 3000);
  double *x = malloc(n3 * sizeof(double)), *g1 = calloc(n3, sizeof(double)), *g2 = calloc(n3, sizeof(double));
  for (size_t i = 0; i < n3; i++) x[i] = mesh->x[i] + 0.02 * (urand() - 0.5);
  bs_bsr *H1 = NULL, *H2 = NULL;
  cr_assert_eq(bs_fem_matrix(fem, &H1, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_fem_matrix(fem, &H2, &err), 0, "%s", err.msg);
  int saved = omp_get_max_threads();
  omp_set_num_threads(1);
  double E1 = term_gradient(t, x, g1);
  term_hessian(t, x, H1);
  omp_set_num_threads(2);
  double E2 = term_gradient(t, x, g2);
  term_hessian(t, x, H2);
  omp_set_num_threads(saved);
  cr_assert(E1 > 0);
  cr_assert(E1 == E2, "energy %.17g (1 thread) vs %.17g (2 threads)", E1, E2);
  cr_assert(memcmp(g1, g2, n3 * sizeof(double)) == 0);
  cr_assert(memcmp(H1->val, H2->val, 9 * (size_t)H1->nnzb * sizeof(double)) == 0);
  bs_bsr_destroy(&H1);
  bs_bsr_destroy(&H2);
  bs_term_destroy(&t);
  bs_levelset_destroy(&ls);
  bs_fem_destroy(&fem);
  bs_mesh_destroy(&mesh);
  free(x), free(g1), free(g2);
}

Test(penalty, argument_errors) {
  fixture f;
  setup(&f);
  bs_levelset *ls = NULL;
  bs_term *t = NULL;
  bs_error err;
  double c[3] = {0, 0, 0};
  cr_assert_eq(bs_levelset_create_sphere(c, 1, &ls, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_term_penalty_create(f.fem, NULL, ls, 0, &t, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "k = 0"), "%s", err.msg);
  cr_assert_eq(bs_term_penalty_create(f.fem, NULL, ls, NAN, &t, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "stiffness"), "%s", err.msg);
  cr_assert_eq(bs_term_penalty_create(f.fem, NULL, NULL, 1, &t, &err), BS_EINPUT);
  int32_t bad[3] = {0, 5, 5};
  cr_assert_eq(bs_term_penalty_create_subset(f.fem, NULL, ls, 1, 3, bad, &t, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "vertices[2] = 5") && strstr(err.msg, "repeated"), "%s", err.msg);
  bad[1] = 9999;
  cr_assert_eq(bs_term_penalty_create_subset(f.fem, NULL, ls, 1, 2, bad, &t, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "vertices[1] = 9999"), "%s", err.msg);
  cr_assert_null(t);
  /* the penalty queries refuse another kind of term */
  bs_term *inertia = NULL;
  cr_assert_eq(bs_term_inertia_create(f.fem, &f.step, &inertia, &err), 0, "%s", err.msg);
  cr_assert(!bs_term_is_penalty(inertia));
  cr_assert_null(bs_term_penalty_levelset(inertia));
  double *x = calloc(f.n3, sizeof(double)), *fv = calloc(f.n3, sizeof(double));
  int32_t count;
  cr_assert_eq(bs_term_penalty_forces(inertia, x, fv, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "inertia"), "%s", err.msg);
  cr_assert_eq(bs_term_penalty_stats(inertia, x, &count, NULL, &err), BS_EINPUT);
  bs_term_destroy(&inertia);
  /* an empty subset is a valid (zero) term */
  cr_assert_eq(bs_term_penalty_create_subset(f.fem, NULL, ls, 1, 0, bad, &t, &err), 0, "%s", err.msg);
  for (size_t i = 0; i < f.n3; i++) x[i] = f.mesh->x[i];
  cr_assert_eq(term_value(t, x), 0.0);
  bs_term_destroy(&t);
  bs_term_destroy(&t);
  free(x), free(fv);
  bs_levelset_destroy(&ls);
  teardown(&f);
}

/* The secant model (hessian_g, bs_penalty.h) on a half-space (unit grad phi,
 * Hess phi = 0), on blocks of the penetrating vertices, with k depth per
 * vertex: at balance (g = 0) it is the Hessian, 6 k depth; when the other
 * terms exert nothing (g = the penalty's own gradient) half of it, 3 k depth;
 * with a push F into the obstacle 3 k (depth + sqrt(F / 3k)). */
Test(penalty, secant_model_against_the_hessian) {
  fixture f;
  setup(&f);
  bs_levelset *ls = NULL;
  bs_term *t = NULL;
  bs_error err;
  const double nrm[3] = {0, 1, 0}, k = 1e6, F = 30.0;
  cr_assert_eq(bs_levelset_create_halfspace(nrm, 0, &ls, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_term_penalty_create(f.fem, &f.step, ls, k, &t, &err), 0, "%s", err.msg);
  cr_assert_not_null(t->ops->hessian_g);
  cr_expect_eq(bs_term_self_set_secant(t, 1, &err), BS_EINPUT, "a penalty term taken for a self-collision term");
  cr_expect(strstr(err.msg, "is not a self-collision term") != NULL, "%s", err.msg);
  double *x = malloc(f.n3 * sizeof(double)), *g = calloc(f.n3, sizeof(double));
  for (size_t i = 0; i < f.n3; i++) x[i] = f.mesh->x[i] + (i % 3 == 1 ? 0.3 : 0.0); /* 16 vertices 0.2 m deep */
  bs_bsr *H = NULL, *Hg = NULL;
  cr_assert_eq(bs_fem_matrix(f.fem, &H, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_fem_matrix(f.fem, &Hg, &err), 0, "%s", err.msg);
  bs_bsr_zero(H);
  term_hessian(t, x, H);
  for (int pass = 0; pass < 3; pass++) {
    memset(g, 0, f.n3 * sizeof(double));
    if (pass > 0) term_gradient(t, x, g);                              /* the penalty's own gradient */
    if (pass == 2)
      for (size_t i = 1; i < f.n3; i += 3) g[i] += F;                  /* others push down: +F along -grad phi */
    bs_bsr_zero(Hg);
    cr_assert_eq(t->ops->hessian_g(t, x, g, Hg), BS_TERM_OK);
    int in = 0;
    for (int32_t v = 0; v < f.mesh->n_vertices; v++) {
      const double depth = -x[3 * v + 1], *b = H->val + 9 * (size_t)H->diag[v], *bg = Hg->val + 9 * (size_t)Hg->diag[v];
      const double want = pass == 0 ? 6 * k * depth : pass == 1 ? 3 * k * depth : 3 * k * (depth + sqrt(F / (3 * k)));
      if (depth <= 0) {
        for (int e = 0; e < 9; e++) cr_expect(bg[e] == 0 && b[e] == 0, "vertex %d outside: block entry %d", v, e);
        continue;
      }
      in++;
      cr_expect(fabs(b[4] - 6 * k * depth) <= 1e-12 * b[4], "vertex %d: Hessian %.17g, 6 k depth %.17g", v, b[4],
                6 * k * depth);
      cr_expect(fabs(bg[4] - want) <= 1e-12 * want, "pass %d vertex %d: model %.17g, expected %.17g", pass, v, bg[4],
                want);
      for (int e = 0; e < 9; e++)
        if (e != 4) cr_expect(bg[e] == 0, "pass %d vertex %d: entry %d = %g off the normal", pass, v, e, bg[e]);
    }
    cr_expect_eq(in, 16);
  }
  bs_bsr_destroy(&H);
  bs_bsr_destroy(&Hg);
  free(x);
  free(g);
  bs_term_destroy(&t);
  bs_levelset_destroy(&ls);
  teardown(&f);
}

/* One backward Euler step of a bar falling at 3 m/s onto a penalty floor
 * (k = 1e7, dt = 1/24 s: the explicit guess puts its bottom 10 cm deep, about
 * 25 times the depth where the penalty balances its momentum): with the
 * secant model (bs_integrator_opts.penalty_secant) the solve converges to
 * the same minimizer in fewer Newton iterations than with the Hessian, which
 * halves the deep vertices' depth per iteration. */
static int floor_step(int secant, double *x, bs_step_stats *st) {
  bs_error err;
  bs_mesh *mesh = NULL;
  double lo[3] = {0, 0, 0}, hi[3] = {1, 0.25, 0.25}, nrm[3] = {0, 1, 0}, grav[3] = {0, -9.8, 0};
  cr_assert_eq(bs_mesh_create_box(lo, hi, 4, 1, 1, &mesh, &err), 0, "%s", err.msg);
  bs_material mat;
  cr_assert_eq(bs_material_init(BS_MODEL_FIXED_COROTATED, 1e5, 0.3, 1000, &mat, &err), 0, "%s", err.msg);
  bs_fem *fem = NULL;
  cr_assert_eq(bs_fem_create(mesh, 1, &mat, NULL, &fem, &err), 0, "%s", err.msg);
  bs_levelset *ls = NULL;
  cr_assert_eq(bs_levelset_create_halfspace(nrm, 0, &ls, &err), 0, "%s", err.msg);
  bs_step_data step = {0};
  bs_term *terms[4] = {NULL};
  cr_assert_eq(bs_term_inertia_create(fem, &step, &terms[0], &err), 0, "%s", err.msg);
  cr_assert_eq(bs_term_gravity_create(fem, &step, grav, &terms[1], &err), 0, "%s", err.msg);
  cr_assert_eq(bs_term_elastic_create(fem, 0, &terms[2], &err), 0, "%s", err.msg);
  cr_assert_eq(bs_term_penalty_create(fem, &step, ls, 1e7, &terms[3], &err), 0, "%s", err.msg);
  bs_integrator_opts o;
  bs_integrator_opts_default(&o);
  o.penalty_secant = secant;
  bs_integrator *I = NULL;
  cr_assert_eq(bs_integrator_create(fem, &step, 4, terms, NULL, NULL, NULL, &o, &I, &err), 0, "%s", err.msg);
  const size_t n3 = 3 * (size_t)mesh->n_vertices;
  double *v = malloc(n3 * sizeof(double));
  for (size_t i = 0; i < n3; i++) {
    x[i] = mesh->x[i] + (i % 3 == 1 ? 0.02 : 0.0);
    v[i] = i % 3 == 1 ? -3.0 : 0.0;
  }
  cr_assert_eq(bs_integrator_step(I, 0, 1.0 / 24, x, v, st, &err), 0, "%s", err.msg);
  int n = mesh->n_vertices;
  free(v);
  bs_integrator_destroy(&I);
  for (int i = 0; i < 4; i++) bs_term_destroy(&terms[i]);
  bs_levelset_destroy(&ls);
  bs_fem_destroy(&fem);
  bs_mesh_destroy(&mesh);
  return n;
}

Test(penalty, secant_model_takes_fewer_newton_iterations) {
  double xe[3 * 20], xs[3 * 20];
  bs_step_stats se, ss;
  const int n = floor_step(0, xe, &se);
  cr_assert_eq(n, 20);
  floor_step(1, xs, &ss);
  cr_log_info("bar onto a penalty floor: %d Newton iterations with the Hessian, %d with the secant model",
              se.min.iterations, ss.min.iterations);
  cr_expect_eq(se.failed, 0, "Hessian: %s", se.min.reason_text);
  cr_expect_eq(ss.failed, 0, "secant: %s", ss.min.reason_text);
  cr_expect_lt(ss.min.iterations, se.min.iterations);
  double ymin = INFINITY, dmax = 0;
  for (int i = 0; i < 3 * n; i++) {
    dmax = fmax(dmax, fabs(xe[i] - xs[i]));
    if (i % 3 == 1) ymin = fmin(ymin, xs[i]);
  }
  cr_expect(ymin < 0 && ymin > -0.02, "the bottom rests %g m deep", -ymin);
  cr_expect(dmax <= 1e-6, "the two minimizers differ by %g m", dmax);
}
