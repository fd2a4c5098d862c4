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
#include "test_term_eval.h"

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
  f->step.c = 1; /* backward Euler's inertia (bs_step_data.c) */
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
  term_gradient(t, x, g);
  for (size_t i = 0; i < n3; i++) {
    xp[i] = x[i] + h * d[i];
    xm[i] = x[i] - h * d[i];
  }
  double fd = (term_value(t, xp) - term_value(t, xm)) / (2 * h);
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
  term_hessian(t, x, H);
  double *Hd = malloc(sizeof(double) * n3), *gp = calloc(n3, sizeof(double)), *gm = calloc(n3, sizeof(double));
  double *xp = malloc(sizeof(double) * n3), *xm = malloc(sizeof(double) * n3);
  bs_bsr_mul(H, NULL, d, Hd);
  for (size_t i = 0; i < n3; i++) {
    xp[i] = x[i] + h * d[i];
    xm[i] = x[i] - h * d[i];
  }
  term_gradient(t, xp, gp);
  term_gradient(t, xm, gm);
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
    const int32_t k = f.fem->tet_pos[t]; /* the fem stores per-tet data by position */
    cr_assert_eq(f.fem->chunk_tets[k], t);
    bs_tet_hessian(&f.mats[f.tet_mat[t]], xt, f.fem->Dm_inv + 9 * k, f.fem->volume[k], 0, He);
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
  cr_expect(E1 == E2, "energy differs with 1 and 2 threads: %.17g vs %.17g", E1, E2);
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

/* The chunks partition the tets (ascending within a chunk, at most
 * BS_FEM_CHUNK each); every chunk is in exactly one colour, ascending within a
 * colour; no two chunks of a colour share a vertex. */
static void check_colouring(const bs_fem *fem) {
  const bs_mesh *m = fem->mesh;
  cr_assert(fem->n_chunks >= 1 && fem->n_chunks <= m->n_tets, "%d chunks", fem->n_chunks);
  cr_assert_eq(fem->chunk_ptr[0], 0);
  cr_assert_eq(fem->chunk_ptr[fem->n_chunks], m->n_tets);
  cr_assert_eq(fem->color_ptr[0], 0);
  cr_assert_eq(fem->color_ptr[fem->n_colors], fem->n_chunks);
  int32_t *tet_seen = calloc((size_t)m->n_tets, sizeof(int32_t));
  for (int32_t k = 0; k < fem->n_chunks; k++) {
    int32_t lo = fem->chunk_ptr[k], hi = fem->chunk_ptr[k + 1];
    cr_expect(lo < hi && hi - lo <= BS_FEM_CHUNK, "chunk %d holds %d tets", k, hi - lo);
    for (int32_t q = lo; q < hi; q++) {
      int32_t t = fem->chunk_tets[q];
      cr_assert(t >= 0 && t < m->n_tets, "tet %d out of range", t);
      if (q > lo) cr_expect_gt(t, fem->chunk_tets[q - 1], "chunk %d: tets not ascending", k);
      /* position q holds tet t's data */
      cr_expect_eq(fem->tet_pos[t], q, "tet %d: position %d, expected %d", t, fem->tet_pos[t], q);
      for (int a = 0; a < 4; a++) cr_expect_eq(fem->tets[4 * q + a], m->tets[4 * t + a], "position %d: vertex %d", q, a);
      tet_seen[t]++;
    }
  }
  for (int32_t t = 0; t < m->n_tets; t++) cr_expect_eq(tet_seen[t], 1, "tet %d in %d chunks", t, tet_seen[t]);
  int32_t *seen_color = calloc((size_t)m->n_vertices, sizeof(int32_t));
  int32_t *seen_chunk = calloc((size_t)m->n_vertices, sizeof(int32_t));
  int32_t *chunk_seen = calloc((size_t)fem->n_chunks, sizeof(int32_t));
  int32_t conflicts = 0;
  for (int c = 0; c < fem->n_colors; c++) {
    cr_expect(fem->color_ptr[c + 1] > fem->color_ptr[c], "colour %d is empty", c);
    for (int32_t q = fem->color_ptr[c]; q < fem->color_ptr[c + 1]; q++) {
      int32_t k = fem->color_chunks[q];
      cr_assert(k >= 0 && k < fem->n_chunks, "chunk %d out of range", k);
      if (q > fem->color_ptr[c]) cr_expect_gt(k, fem->color_chunks[q - 1], "colour %d: chunks not ascending", c);
      chunk_seen[k]++;
      for (int32_t p = fem->chunk_ptr[k]; p < fem->chunk_ptr[k + 1]; p++)
        for (int a = 0; a < 4; a++) {
          int32_t v = m->tets[4 * (size_t)fem->chunk_tets[p] + a];
          if (seen_color[v] == c + 1 && seen_chunk[v] != k) conflicts++;
          seen_color[v] = c + 1;
          seen_chunk[v] = k;
        }
    }
  }
  cr_expect_eq(conflicts, 0, "%d vertices shared by two chunks of one colour", conflicts);
  for (int32_t k = 0; k < fem->n_chunks; k++) cr_expect_eq(chunk_seen[k], 1, "chunk %d coloured %d times", k, chunk_seen[k]);
  free(tet_seen);
  free(seen_color);
  free(seen_chunk);
  free(chunk_seen);
}

/* Lumped masses sum to the total mass ρV; the colouring is valid. */
Test(terms, masses_and_colouring) {
  fixture f;
  setup(&f, 3, BS_MODEL_FIXED_COROTATED);
  double m = 0, expect = 0;
  for (int32_t v = 0; v < f.mesh->n_vertices; v++) m += f.fem->mass[v];
  for (int32_t t = 0; t < f.mesh->n_tets; t++)
    expect += f.mats[f.tet_mat[t]].density * f.fem->volume[f.fem->tet_pos[t]];
  cr_expect(fabs(m - expect) < 1e-12 * expect, "mass %g vs %g", m, expect);
  check_colouring(f.fem);
  teardown(&f);
  /* a box large enough for many chunks per colour (the parallel path) */
  setup(&f, 12, BS_MODEL_FIXED_COROTATED);
  check_colouring(f.fem);
  cr_expect(f.fem->n_colors >= 2 && f.fem->n_colors <= 24, "%d colours for a 12^3 box", f.fem->n_colors);
  cr_expect(f.fem->n_chunks <= 2 * (f.mesh->n_tets / BS_FEM_CHUNK + 1), "%d chunks for %d tets", f.fem->n_chunks,
            f.mesh->n_tets);
  teardown(&f);
}

/* An unordered mesh (tets shuffled, two materials): the chunk colouring is
 * valid and still leaves colours with several chunks (the parallel path);
 * energy, gradient, Hessian (plain and projected) and the damping matrix are
 * bitwise identical with 1 and 2 threads and match per-tet sums in mesh order; the
 * damping matrix leaves out the material whose coefficient is 0. */
Test(terms, chunks_unordered_mesh_threads) {
  bs_error err;
  bs_mesh *box = NULL, *mesh = NULL;
  double lo[3] = {0, 0, 0}, hi[3] = {1, 0.8, 0.6};
  cr_assert_eq(bs_mesh_create_box(lo, hi, 14, 14, 14, &box, &err), 0, "%s", err.msg);
  const int32_t nt = box->n_tets;
  int32_t *perm = malloc(sizeof(int32_t) * (size_t)nt), *tets = malloc(sizeof(int32_t) * 4 * (size_t)nt);
  for (int32_t t = 0; t < nt; t++) perm[t] = t;
  for (int32_t t = nt - 1; t > 0; t--) {
    int32_t j = (int32_t)(urand() * (t + 1)), q = perm[t];
    if (j > t) j = t;
    perm[t] = perm[j];
    perm[j] = q;
  }
  for (int32_t t = 0; t < nt; t++)
    for (int a = 0; a < 4; a++) tets[4 * t + a] = box->tets[4 * perm[t] + a];
  cr_assert_eq(bs_mesh_create(box->n_vertices, box->x, nt, tets, 0, NULL, &mesh, &err), 0, "%s", err.msg);
  bs_material mats[2];
  cr_assert_eq(bs_material_init(BS_MODEL_FIXED_COROTATED, 1e4, 0.3, 1000, &mats[0], &err), 0, "%s", err.msg);
  cr_assert_eq(bs_material_init(BS_MODEL_NEO_HOOKEAN, 3e4, 0.45, 500, &mats[1], &err), 0, "%s", err.msg);
  int32_t *tm = malloc(sizeof(int32_t) * (size_t)nt);
  for (int32_t t = 0; t < nt; t++) tm[t] = (t / 5) % 2;
  bs_fem *fem = NULL;
  cr_assert_eq(bs_fem_create(mesh, 2, mats, tm, &fem, &err), 0, "%s", err.msg);
  check_colouring(fem);
  int wide = 0;
  for (int c = 0; c < fem->n_colors; c++) wide += fem->color_ptr[c + 1] - fem->color_ptr[c] >= 4;
  cr_expect(wide >= fem->n_colors / 2, "only %d of %d colours hold 4 chunks or more", wide, fem->n_colors);
  cr_expect(fem->n_colors <= 32, "%d colours for %d tets", fem->n_colors, nt);

  size_t n3 = 3 * (size_t)mesh->n_vertices;
  double *x = malloc(sizeof(double) * n3), *xn = malloc(sizeof(double) * n3);
  for (size_t i = 0; i < n3; i++) {
    x[i] = mesh->x[i] + 0.03 * (urand() - 0.5);
    xn[i] = mesh->x[i] + 0.03 * (urand() - 0.5);
  }
  bs_step_data step = {.dt = 1.0 / 24, .x_hat = xn, .x_n = xn, .load = 1};
  double kd[2] = {0, 0.03};
  bs_bsr *H[2][3];
  double *g[2], E[2], V[2];
  int saved = omp_get_max_threads();
  for (int r = 0; r < 2; r++) {
    omp_set_num_threads(r + 1);
    for (int i = 0; i < 2; i++) {
      cr_assert_eq(bs_fem_matrix(fem, &H[r][i], &err), 0);
      bs_fem_elastic_hessian(fem, x, i, 1.0, H[r][i]);
    }
    bs_term *damp = NULL;
    cr_assert_eq(bs_term_damping_create(fem, &step, kd, &damp, &err), 0, "%s", err.msg);
    cr_assert_eq(damp->ops->begin_step(damp, &err), 0);
    cr_assert_eq(bs_fem_matrix(fem, &H[r][2], &err), 0);
    term_hessian(damp, x, H[r][2]); /* D / dt */
    bs_term_destroy(&damp);
    g[r] = calloc(n3, sizeof(double));
    E[r] = bs_fem_elastic_gradient(fem, x, g[r]);
    V[r] = bs_fem_elastic_energy(fem, x);
  }
  omp_set_num_threads(saved);
  size_t nval = 9 * (size_t)H[0][0]->nnzb;
  const char *what[3] = {"Hessian", "projected Hessian", "damping matrix"};
  for (int i = 0; i < 3; i++)
    cr_expect(memcmp(H[0][i]->val, H[1][i]->val, sizeof(double) * nval) == 0, "%s differs with 1 and 2 threads",
              what[i]);
  cr_expect(memcmp(g[0], g[1], sizeof(double) * n3) == 0, "gradient differs with 1 and 2 threads");
  cr_expect(E[0] == E[1], "energy (gradient) differs with 1 and 2 threads: %.17g vs %.17g", E[0], E[1]);
  cr_expect(V[0] == V[1], "energy differs with 1 and 2 threads: %.17g vs %.17g", V[0], V[1]);
  cr_expect(fabs(V[0] - E[0]) <= 1e-12 * fabs(V[0]), "energy %.17g vs %.17g from the gradient", V[0], E[0]);

  /* references: per-tet kernels summed in mesh order */
  bs_bsr *R[3];
  double *gr = calloc(n3, sizeof(double)), Er = 0;
  for (int i = 0; i < 3; i++) cr_assert_eq(bs_fem_matrix(fem, &R[i], &err), 0);
  for (int32_t t = 0; t < nt; t++) {
    double xt[12], He[144], ge[12];
    const bs_material *mt = &mats[tm[t]];
    const size_t p = (size_t)fem->tet_pos[t]; /* per-tet data is stored by position */
    bs_fem_gather(fem, x, t, xt);
    Er += bs_tet_energy_grad(mt, xt, fem->Dm_inv + 9 * p, fem->volume[p], ge);
    for (int a = 0; a < 4; a++)
      for (int k = 0; k < 3; k++) gr[3 * (size_t)mesh->tets[4 * t + a] + k] += ge[3 * a + k];
    for (int i = 0; i < 2; i++) {
      bs_tet_hessian(mt, xt, fem->Dm_inv + 9 * p, fem->volume[p], i, He);
      bs_fem_scatter_hessian(fem, t, He, 1.0, R[i]);
    }
    if (tm[t] == 1) {
      bs_fem_gather(fem, xn, t, xt);
      bs_tet_hessian(mt, xt, fem->Dm_inv + 9 * p, fem->volume[p], 1, He);
      bs_fem_scatter_hessian(fem, t, He, kd[1] / step.dt, R[2]);
    }
  }
  for (int i = 0; i < 3; i++) {
    double mx = 0, md = 0;
    for (size_t q = 0; q < nval; q++) {
      mx = fmax(mx, fabs(R[i]->val[q]));
      md = fmax(md, fabs(R[i]->val[q] - H[0][i]->val[q]));
    }
    cr_expect(mx > 0 && md <= 1e-12 * mx, "%s differs from the per-tet sum: %g (max %g)", what[i], md, mx);
  }
  double mg = 0, dg = 0;
  for (size_t q = 0; q < n3; q++) {
    mg = fmax(mg, fabs(gr[q]));
    dg = fmax(dg, fabs(gr[q] - g[0][q]));
  }
  cr_expect(mg > 0 && dg <= 1e-12 * mg, "gradient differs from the per-tet sum: %g (max %g)", dg, mg);
  cr_expect(fabs(Er - E[0]) <= 1e-12 * fabs(Er), "energy %.17g vs per-tet %.17g", E[0], Er);
  for (int i = 0; i < 3; i++) {
    bs_bsr_destroy(&R[i]);
    for (int r = 0; r < 2; r++) bs_bsr_destroy(&H[r][i]);
  }
  for (int r = 0; r < 2; r++) free(g[r]);
  free(gr);
  free(x);
  free(xn);
  free(tm);
  free(perm);
  free(tets);
  bs_fem_destroy(&fem);
  bs_mesh_destroy(&mesh);
  bs_mesh_destroy(&box);
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

/* The elastic Hessian of a term with project_psd `mode` at x (step data of
 * f, whose dt the caller sets). Caller destroys H. */
static bs_bsr *elastic_H(fixture *f, int mode, const double *x) {
  bs_error err;
  bs_term *t = NULL;
  bs_bsr *H = NULL;
  cr_assert_eq(bs_term_elastic_create_step(f->fem, &f->step, mode, &t, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_fem_matrix(f->fem, &H, &err), 0);
  bs_bsr_zero(H);
  cr_assert_eq(t->ops->hessian(t, x, H), BS_TERM_OK);
  bs_term_destroy(&t);
  return H;
}

static int same_values(const bs_bsr *A, const bs_bsr *B) {
  return memcmp(A->val, B->val, sizeof(double) * 9 * (size_t)A->nnzb) == 0;
}

/* project_psd auto: the exact Hessian while mu dt^2 / (rho h^2) is below
 * BS_PSD_AUTO_RATIO, the inverted tets projected once it reaches it, and in a
 * static solve (dt = 0); bit for bit the fixed modes'. The rule is per tet;
 * the box's tets have one volume, and the fixture's two materials (mu / rho
 * 3.85 and 20.7 m^2/s^2) cross the ratio at different dt, so one dt gives
 * each its own mode. */
Test(terms, psd_auto) {
  fixture f;
  setup(&f, 3, BS_MODEL_FIXED_COROTATED);
  size_t n3 = 3 * (size_t)f.mesh->n_vertices;
  double *x = malloc(sizeof(double) * n3);
  config(&f, "random", x);
  cr_assert(bs_fem_count_inverted(f.fem, x, NULL) > 0, "precondition: the random state has inverted tets");
  f.step.dt = 1e-4; /* both soft against their inertia */
  bs_bsr *Hn = elastic_H(&f, BS_PSD_NONE, x), *Hi = elastic_H(&f, BS_PSD_INVERTED, x);
  cr_assert(!same_values(Hn, Hi), "precondition: projecting the inverted tets changes the Hessian");
  bs_bsr *Ha = elastic_H(&f, BS_PSD_AUTO, x);
  cr_expect(same_values(Ha, Hn), "auto at dt = 1e-4 s is not the exact Hessian");
  bs_bsr_destroy(&Ha);
  f.step.dt = 10; /* both stiff */
  Ha = elastic_H(&f, BS_PSD_AUTO, x);
  cr_expect(same_values(Ha, Hi), "auto at dt = 10 s is not the inverted tets' projection");
  bs_bsr_destroy(&Ha);
  f.step.dt = 0; /* statics */
  Ha = elastic_H(&f, BS_PSD_AUTO, x);
  cr_expect(same_values(Ha, Hi), "auto in a static solve is not the inverted tets' projection");
  bs_bsr_destroy(&Ha);
  /* between: material 1 (stiffer per mass) projected, material 0 exact */
  const double h = cbrt(6.0 * sqrt(2.0) * (0.8 * 0.6 / 27 / 6));
  const double r0 = f.mats[0].mu / (f.mats[0].density * h * h), r1 = f.mats[1].mu / (f.mats[1].density * h * h);
  f.step.dt = sqrt(BS_PSD_AUTO_RATIO / sqrt(r0 * r1));
  cr_assert(r0 * f.step.dt * f.step.dt < BS_PSD_AUTO_RATIO && r1 * f.step.dt * f.step.dt > BS_PSD_AUTO_RATIO);
  Ha = elastic_H(&f, BS_PSD_AUTO, x);
  cr_expect(!same_values(Ha, Hn) && !same_values(Ha, Hi), "auto between the ratios is not a per-material mix");
  bs_bsr_destroy(&Ha);
  bs_error err;
  bs_term *t = NULL;
  cr_expect_neq(bs_term_elastic_create(f.fem, BS_PSD_AUTO, &t, &err), 0, "auto without the step was accepted");
  cr_expect(strstr(err.msg, "auto") != NULL, "%s", err.msg);
  cr_expect_neq(bs_term_elastic_create(f.fem, 7, &t, &err), 0, "project_psd 7 was accepted");
  bs_bsr_destroy(&Hn);
  bs_bsr_destroy(&Hi);
  free(x);
  teardown(&f);
}
