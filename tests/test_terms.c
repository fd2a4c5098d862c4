/* Energy terms and parallel assembly: every term's gradient and Hessian against
 * central finite differences (O(h²) over a range of h) at random, inverted and
 * degenerate configurations; the assembled Hessian equals the sum of element
 * Hessians; results identical with 1 and 2 threads. */
#include <criterion/criterion.h>
#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

#include "bs_element.h"
#include "bs_fem.h"
#include "bs_terms.h"

static uint64_t seed = 12345;
static double urand(void) {
  seed ^= seed << 13;
  seed ^= seed >> 7;
  seed ^= seed << 17;
  return (double)(seed >> 11) / 9007199254740992.0;
}

typedef struct fixture {
  bs_mesh *mesh;
  bs_fem *fem;
  bs_step_data step;
  double *x_hat, *x_n;
  bs_material mats[2];
  int32_t *tet_mat;
} fixture;

static void setup(fixture *f, int nx, bs_model model) {
  bs_error err;
  double lo[3] = {0, 0, 0}, hi[3] = {1, 0.8, 0.6};
  cr_assert_eq(bs_mesh_create_box(lo, hi, nx, nx, nx, &f->mesh, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_material_init(model, 1e4, 0.3, 1000, &f->mats[0], &err), 0, "%s", err.msg);
  cr_assert_eq(bs_material_init(BS_MODEL_FIXED_COROTATED, 3e4, 0.45, 500, &f->mats[1], &err), 0, "%s", err.msg);
  f->tet_mat = calloc((size_t)f->mesh->n_tets, sizeof(int32_t));
  for (int32_t t = 0; t < f->mesh->n_tets; t++) f->tet_mat[t] = t % 2;
  cr_assert_eq(bs_fem_create(f->mesh, 2, f->mats, f->tet_mat, &f->fem, &err), 0, "%s", err.msg);
  size_t n3 = 3 * (size_t)f->mesh->n_vertices;
  f->x_hat = malloc(sizeof(double) * n3);
  f->x_n = malloc(sizeof(double) * n3);
  for (size_t i = 0; i < n3; i++) {
    f->x_n[i] = f->mesh->x[i] + 0.05 * (urand() - 0.5);
    f->x_hat[i] = f->x_n[i] + 0.02 * (urand() - 0.5);
  }
  f->step.dt = 1.0 / 24;
  f->step.x_hat = f->x_hat;
  f->step.x_n = f->x_n;
  f->step.load = 1;
}

static void teardown(fixture *f) {
  bs_fem_destroy(&f->fem);
  bs_mesh_destroy(&f->mesh);
  free(f->x_hat);
  free(f->x_n);
  free(f->tet_mat);
}

/* A configuration: "random" perturbs the rest shape strongly (many inverted
 * tets), "flat" squashes z to 1e-8, "rest" is within 1e-4 of the rest shape
 * (at the rest shape itself the elastic gradient vanishes and a relative
 * gradient error means nothing). */
static void config(const fixture *f, const char *kind, double *x) {
  size_t n = (size_t)f->mesh->n_vertices;
  for (size_t v = 0; v < n; v++)
    for (int k = 0; k < 3; k++) {
      double X = f->mesh->x[3 * v + k];
      if (!strcmp(kind, "random")) x[3 * v + k] = X + 0.4 * (urand() - 0.5);
      else if (!strcmp(kind, "flat")) x[3 * v + k] = k == 2 ? 1e-8 * X + 1e-9 * urand() : X + 0.05 * urand();
      else x[3 * v + k] = X + 1e-4 * (urand() - 0.5); /* near rest */
    }
}

/* Max relative error of the term's gradient against central differences in a
 * random direction d, for step h: |(E(x+hd)-E(x-hd))/2h - g.d| / scale. */
static double grad_fd_error(const bs_term *t, const double *x, const double *d, double h, size_t n3) {
  double *g = calloc(n3, sizeof(double)), *xp = malloc(sizeof(double) * n3), *xm = malloc(sizeof(double) * n3);
  t->ops->gradient(t, x, g);
  for (size_t i = 0; i < n3; i++) {
    xp[i] = x[i] + h * d[i];
    xm[i] = x[i] - h * d[i];
  }
  double fd = (t->ops->value(t, xp) - t->ops->value(t, xm)) / (2 * h);
  double gd = 0, gn = 0;
  for (size_t i = 0; i < n3; i++) {
    gd += g[i] * d[i];
    gn += fabs(g[i] * d[i]);
  }
  free(g);
  free(xp);
  free(xm);
  return fabs(fd - gd) / (gn + 1e-300);
}

/* |(g(x+hd)-g(x-hd))/2h - H d| / |H d| */
static double hess_fd_error(const bs_term *t, const bs_fem *fem, const double *x, const double *d, double h,
                            size_t n3) {
  bs_bsr *H;
  bs_error err;
  cr_assert_eq(bs_fem_matrix(fem, &H, &err), 0);
  bs_bsr_zero(H);
  t->ops->hessian(t, x, H);
  double *Hd = malloc(sizeof(double) * n3), *gp = calloc(n3, sizeof(double)), *gm = calloc(n3, sizeof(double));
  double *xp = malloc(sizeof(double) * n3), *xm = malloc(sizeof(double) * n3);
  bs_bsr_mul(H, NULL, d, Hd);
  for (size_t i = 0; i < n3; i++) {
    xp[i] = x[i] + h * d[i];
    xm[i] = x[i] - h * d[i];
  }
  t->ops->gradient(t, xp, gp);
  t->ops->gradient(t, xm, gm);
  double num = 0, den = 0;
  for (size_t i = 0; i < n3; i++) {
    double fd = (gp[i] - gm[i]) / (2 * h);
    num += (fd - Hd[i]) * (fd - Hd[i]);
    den += Hd[i] * Hd[i] + fd * fd;
  }
  free(Hd);
  free(gp);
  free(gm);
  free(xp);
  free(xm);
  bs_bsr_destroy(&H);
  return sqrt(num / (den + 1e-300));
}

/* Checks FD convergence: the smallest error over h in [1e-3, 1e-6] is small,
 * and between h = 1e-2 and 1e-3 the error falls by ~100 (O(h²)) unless it is
 * already at round-off. */
static void check_term(const bs_term *t, const bs_fem *fem, const double *x, int check_hessian, const char *what) {
  size_t n3 = 3 * (size_t)fem->n_vertices;
  double *d = malloc(sizeof(double) * n3);
  for (size_t i = 0; i < n3; i++) d[i] = urand() - 0.5;
  double hs[4] = {1e-2, 1e-3, 1e-4, 1e-5};
  double eg[4], eh[4];
  for (int i = 0; i < 4; i++) {
    eg[i] = grad_fd_error(t, x, d, hs[i] * 0.01, n3);
    eh[i] = check_hessian ? hess_fd_error(t, fem, x, d, hs[i] * 0.01, n3) : 0;
  }
  double bg = fmin(fmin(eg[0], eg[1]), fmin(eg[2], eg[3]));
  double bh = fmin(fmin(eh[0], eh[1]), fmin(eh[2], eh[3]));
  cr_expect(bg < 1e-6, "%s %s: gradient FD error %g %g %g %g", t->name, what, eg[0], eg[1], eg[2], eg[3]);
  if (check_hessian)
    cr_expect(bh < 1e-5, "%s %s: Hessian FD error %g %g %g %g", t->name, what, eh[0], eh[1], eh[2], eh[3]);
  /* O(h²): where the largest-h error is above round-off, one decade of h gives ~two decades of error. */
  if (eg[0] > 1e-9) cr_expect(eg[1] < eg[0] / 30, "%s %s: gradient error not O(h^2): %g -> %g", t->name, what, eg[0], eg[1]);
  if (check_hessian && eh[0] > 1e-9)
    cr_expect(eh[1] < eh[0] / 30, "%s %s: Hessian error not O(h^2): %g -> %g", t->name, what, eh[0], eh[1]);
  free(d);
}

static void check_all_terms(bs_model model) {
  fixture f;
  setup(&f, 2, model);
  bs_error err;
  bs_term *terms[5];
  double g[3] = {0, -9.8, 0.5}, k[2] = {0.01, 0.03};
  cr_assert_eq(bs_term_inertia_create(f.fem, &f.step, &terms[0], &err), 0);
  cr_assert_eq(bs_term_gravity_create(f.fem, &f.step, g, &terms[1], &err), 0);
  cr_assert_eq(bs_term_elastic_create(f.fem, 0, &terms[2], &err), 0);
  cr_assert_eq(bs_term_damping_create(f.fem, &f.step, k, &terms[3], &err), 0);
  cr_assert_eq(bs_term_drag_create(f.fem, &f.step, 0.2, &terms[4], &err), 0);
  cr_assert_eq(terms[3]->ops->begin_step(terms[3], &err), 0);
  size_t n3 = 3 * (size_t)f.mesh->n_vertices;
  double *x = malloc(sizeof(double) * n3);
  const char *kinds[3] = {"random", "flat", "rest"};
  for (int c = 0; c < 3; c++) {
    config(&f, kinds[c], x);
    for (int i = 0; i < 5; i++) check_term(terms[i], f.fem, x, 1, kinds[c]);
  }
  int32_t inv = 0;
  config(&f, "random", x);
  inv = bs_fem_count_inverted(f.fem, x, NULL);
  cr_expect(inv > 0, "the random configuration should hold inverted tets (got %d)", inv);
  for (int i = 0; i < 5; i++) bs_term_destroy(&terms[i]);
  cr_assert_null(terms[0]);
  free(x);
  teardown(&f);
}

Test(terms, fd_fixed_corotated) { check_all_terms(BS_MODEL_FIXED_COROTATED); }
Test(terms, fd_neo_hookean) { check_all_terms(BS_MODEL_NEO_HOOKEAN); }
Test(terms, fd_stable_neo_hookean) { check_all_terms(BS_MODEL_STABLE_NEO_HOOKEAN); }
Test(terms, fd_corotated) { check_all_terms(BS_MODEL_COROTATED); }
Test(terms, fd_linear) { check_all_terms(BS_MODEL_LINEAR); }

/* The assembled Hessian equals the dense sum of element Hessians, is
 * symmetric, and is bitwise identical with 1 and 2 threads. */
Test(terms, assembly_dense_and_threads) {
  fixture f;
  setup(&f, 3, BS_MODEL_FIXED_COROTATED);
  bs_error err;
  int32_t nv = f.mesh->n_vertices;
  size_t n3 = 3 * (size_t)nv;
  double *x = malloc(sizeof(double) * n3);
  config(&f, "random", x);
  bs_bsr *H1, *H2;
  cr_assert_eq(bs_fem_matrix(f.fem, &H1, &err), 0);
  cr_assert_eq(bs_fem_matrix(f.fem, &H2, &err), 0);
  double *dense = calloc(n3 * n3, sizeof(double));
  for (int32_t t = 0; t < f.mesh->n_tets; t++) {
    double xt[12], He[144];
    bs_fem_gather(f.fem, x, t, xt);
    bs_tet_hessian(&f.mats[f.tet_mat[t]], xt, f.fem->Dm_inv + 9 * t, f.fem->volume[t], 0, He);
    const int32_t *tv = f.mesh->tets + 4 * t;
    for (int a = 0; a < 4; a++)
      for (int b = 0; b < 4; b++)
        for (int i = 0; i < 3; i++)
          for (int j = 0; j < 3; j++) dense[(3 * tv[a] + i) * n3 + 3 * tv[b] + j] += He[12 * (3 * a + i) + 3 * b + j];
  }
  int saved = omp_get_max_threads();
  omp_set_num_threads(1);
  bs_bsr_zero(H1);
  bs_fem_elastic_hessian(f.fem, x, 0, 1.0, H1);
  double *g1 = calloc(n3, sizeof(double)), *g2 = calloc(n3, sizeof(double));
  double E1 = bs_fem_elastic_gradient(f.fem, x, g1);
  omp_set_num_threads(2);
  bs_bsr_zero(H2);
  bs_fem_elastic_hessian(f.fem, x, 0, 1.0, H2);
  double E2 = bs_fem_elastic_gradient(f.fem, x, g2);
  omp_set_num_threads(saved);
  cr_expect(memcmp(H1->val, H2->val, sizeof(double) * 9 * (size_t)H1->nnzb) == 0, "Hessian differs with 1 and 2 threads");
  cr_expect(memcmp(g1, g2, sizeof(double) * n3) == 0, "gradient differs with 1 and 2 threads");
  cr_expect(fabs(E1 - E2) <= 1e-12 * fabs(E1), "energy differs beyond round-off: %.17g vs %.17g", E1, E2);
  double maxabs = 0, maxdiff = 0;
  for (int32_t i = 0; i < nv; i++)
    for (int32_t s = H1->row_ptr[i]; s < H1->row_ptr[i + 1]; s++) {
      int32_t j = H1->col[s];
      for (int a = 0; a < 3; a++)
        for (int b = 0; b < 3; b++) {
          double dv = dense[(3 * (size_t)i + a) * n3 + 3 * (size_t)j + b];
          double hv = H1->val[9 * (size_t)s + 3 * a + b];
          maxabs = fmax(maxabs, fabs(dv));
          maxdiff = fmax(maxdiff, fabs(dv - hv));
          dense[(3 * (size_t)i + a) * n3 + 3 * (size_t)j + b] = 0;
        }
    }
  for (size_t i = 0; i < n3 * n3; i++) cr_expect(dense[i] == 0, "dense entry %zu outside the pattern", i);
  cr_expect(maxdiff <= 1e-12 * maxabs, "assembled Hessian differs from the element sum: %g (max %g)", maxdiff, maxabs);
  cr_expect_eq(bs_bsr_check(H1, 1e-12, &err), 0, "%s", err.msg);
  bs_bsr_destroy(&H1);
  bs_bsr_destroy(&H2);
  free(dense);
  free(g1);
  free(g2);
  free(x);
  teardown(&f);
}

/* Lumped masses sum to the total mass ρV; the colouring is valid. */
Test(terms, masses_and_colouring) {
  fixture f;
  setup(&f, 3, BS_MODEL_FIXED_COROTATED);
  double m = 0, expect = 0;
  for (int32_t v = 0; v < f.mesh->n_vertices; v++) m += f.fem->mass[v];
  for (int32_t t = 0; t < f.mesh->n_tets; t++) expect += f.mats[f.tet_mat[t]].density * f.fem->volume[t];
  cr_expect(fabs(m - expect) < 1e-12 * expect, "mass %g vs %g", m, expect);
  int32_t *seen = calloc((size_t)f.mesh->n_vertices, sizeof(int32_t));
  int32_t count = 0;
  for (int c = 0; c < f.fem->n_colors; c++) {
    for (int32_t k = f.fem->color_ptr[c]; k < f.fem->color_ptr[c + 1]; k++) {
      int32_t t = f.fem->color_tets[k];
      count++;
      for (int a = 0; a < 4; a++) {
        int32_t v = f.mesh->tets[4 * t + a];
        cr_expect_neq(seen[v], c + 1, "colour %d holds two tets sharing vertex %d", c, v);
        seen[v] = c + 1;
      }
    }
  }
  cr_expect_eq(count, f.mesh->n_tets);
  free(seen);
  teardown(&f);
}

Test(terms, bad_input) {
  fixture f;
  setup(&f, 1, BS_MODEL_FIXED_COROTATED);
  bs_error err;
  bs_term *t = NULL;
  double g[3] = {0, NAN, 0}, k[2] = {-1, 0};
  cr_expect_neq(bs_term_gravity_create(f.fem, NULL, g, &t, &err), 0);
  cr_expect(strstr(err.msg, "gravity") != NULL, "%s", err.msg);
  cr_expect_neq(bs_term_damping_create(f.fem, &f.step, k, &t, &err), 0);
  cr_expect(strstr(err.msg, "damping") != NULL, "%s", err.msg);
  cr_expect_neq(bs_term_drag_create(f.fem, &f.step, -2, &t, &err), 0);
  cr_expect(strstr(err.msg, "drag") != NULL, "%s", err.msg);
  int32_t bad[6] = {0, 0, 0, 0, 0, 7};
  bs_fem *fem = NULL;
  cr_expect_neq(bs_fem_create(f.mesh, 2, f.mats, bad, &fem, &err), 0);
  cr_expect(strstr(err.msg, "tet 5") != NULL, "%s", err.msg);
  teardown(&f);
}
