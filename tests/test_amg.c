/* test_amg.c — BoomerAMG-preconditioned CG (linear "amg") on box elasticity:
 * iterations far below block-Jacobi PCG, the same solution as CHOLMOD, a
 * symmetric positive definite V-cycle, masks, error paths, the minimizer's
 * reuse/rebuild policy, and a cube_stretch run with solver.linear=amg. */
#define _POSIX_C_SOURCE 200809L
#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bs_amg.h"
#include "bs_fem.h"
#include "bs_linsolve.h"
#include "bs_material.h"
#include "bs_mesh.h"
#include "bs_minimize.h"
#include "sim_util.h"

/* A box of c^3 cells (unit cube, fixed_corotated E = 1e5, nu = 0.3, rho = 1000):
 * A = rest stiffness + M/dt^2 (dt = 1/24), mask fixing the x = 0 face. */
typedef struct elast {
  bs_mesh *mesh;
  bs_fem *fem;
  bs_bsr *A;
  uint8_t *mask;
  double *b;
  size_t N;
} elast;

static void elast_make(int c, elast *e) {
  memset(e, 0, sizeof *e);
  bs_error err = {0};
  const double lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
  cr_assert_eq(bs_mesh_create_box(lo, hi, c, c, c, &e->mesh, &err), 0, "%s", err.msg);
  bs_material mat;
  cr_assert_eq(bs_material_init(BS_MODEL_FIXED_COROTATED, 1e5, 0.3, 1000, &mat, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_fem_create(e->mesh, 1, &mat, NULL, &e->fem, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_fem_matrix(e->fem, &e->A, &err), 0, "%s", err.msg);
  bs_fem_elastic_hessian(e->fem, e->mesh->x, 1, 1.0, e->A);
  const double dt = 1.0 / 24;
  for (int32_t i = 0; i < e->A->n; ++i) {
    double *D = e->A->val + 9 * (int64_t)e->A->diag[i];
    for (int a = 0; a < 3; ++a) D[4 * a] += e->fem->mass[i] / (dt * dt);
  }
  const size_t n = (size_t)(uint32_t)e->A->n;
  e->N = 3 * n;
  e->mask = malloc(n);
  for (size_t i = 0; i < n; ++i) e->mask[i] = e->mesh->x[3 * i] > 1e-9;
  e->b = malloc(sizeof *e->b * e->N);
  unsigned s = 12345u;
  for (size_t k = 0; k < e->N; ++k) {
    s = s * 1103515245u + 12345u;
    e->b[k] = ((s >> 8) & 0xffff) / 65536.0 - 0.5 + (k % 3 == 1 ? -1.0 : 0.0);
  }
}

static void elast_free(elast *e) {
  bs_bsr_destroy(&e->A);
  bs_fem_destroy(&e->fem);
  bs_mesh_destroy(&e->mesh);
  free(e->mask);
  free(e->b);
}

static double rel_diff(const double *x, const double *y, size_t N) {
  double d = 0, n = 0;
  for (size_t k = 0; k < N; ++k) {
    d += (x[k] - y[k]) * (x[k] - y[k]);
    n += y[k] * y[k];
  }
  return sqrt(d / n);
}

static double true_residual(const elast *e, const double *x) {
  double *q = malloc(sizeof *q * e->N);
  bs_bsr_mul(e->A, e->mask, x, q);
  double r = 0, bb = 0;
  for (size_t k = 0; k < e->N; ++k) {
    if (!e->mask[k / 3]) continue;
    r += (e->b[k] - q[k]) * (e->b[k] - q[k]);
    bb += e->b[k] * e->b[k];
  }
  free(q);
  return sqrt(r / bb);
}

static void solve(const elast *e, bs_lin_kind kind, double tol, double *x, bs_lin_stats *st) {
  bs_error err = {0};
  bs_linsolve *ls = NULL;
  cr_assert_eq(bs_linsolve_create(e->A, kind, &ls, &err), 0, "%s", err.msg);
  if (kind == BS_LIN_AMG) cr_assert_eq(bs_linsolve_amg_setup(ls, e->A, e->mask, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_linsolve_solve(ls, e->A, e->mask, e->b, tol, 100000, x, st, &err), 0, "%s", err.msg);
  bs_linsolve_destroy(&ls);
}

/* 16^3 cells: 4913 vertices, 14739 dofs (14028 free). */
Test(amg, far_fewer_iterations_than_block_jacobi_same_solution, .timeout = 300) {
  elast e;
  elast_make(16, &e);
  double *xa = malloc(sizeof *xa * e.N), *xp = malloc(sizeof *xp * e.N), *xc = malloc(sizeof *xc * e.N);
  bs_lin_stats sa, sp, sc;
  solve(&e, BS_LIN_AMG, 1e-8, xa, &sa);
  solve(&e, BS_LIN_PCG, 1e-8, xp, &sp);
  solve(&e, BS_LIN_CHOLMOD, 0, xc, &sc);
  cr_log_info("1e-8: amg %d iterations, pcg %d\n", sa.iterations, sp.iterations);
  cr_assert(sa.converged && sp.converged && sc.converged);
  cr_assert_eq(sa.indefinite, 0);
  cr_assert_eq(sa.precond_failed, 0);
  cr_assert_leq(true_residual(&e, xa), 1e-7, "amg true residual %g", true_residual(&e, xa));
  cr_assert_leq(5 * sa.iterations, sp.iterations, "amg %d iterations vs block Jacobi %d: expected 5x fewer",
                sa.iterations, sp.iterations);
  cr_assert_leq(rel_diff(xa, xc, e.N), 1e-6, "amg vs cholmod: %g", rel_diff(xa, xc, e.N));
  cr_assert_leq(rel_diff(xp, xc, e.N), 1e-6, "pcg vs cholmod: %g", rel_diff(xp, xc, e.N));
  for (size_t k = 0; k < e.N; ++k)
    if (!e.mask[k / 3]) cr_assert_eq(xa[k], 0.0, "constrained dof %zu not zero", k);
  /* Looser tolerance: still converged, and much cheaper than block Jacobi. */
  solve(&e, BS_LIN_AMG, 1e-4, xa, &sa);
  solve(&e, BS_LIN_PCG, 1e-4, xp, &sp);
  cr_log_info("1e-4: amg %d iterations, pcg %d\n", sa.iterations, sp.iterations);
  cr_assert(sa.converged);
  cr_assert_leq(4 * sa.iterations, sp.iterations, "amg %d vs pcg %d at 1e-4", sa.iterations, sp.iterations);
  free(xa);
  free(xp);
  free(xc);
  elast_free(&e);
}

/* The V-cycle is a symmetric positive definite operator on the free dofs. */
Test(amg, vcycle_is_symmetric_positive_definite) {
  elast e;
  elast_make(6, &e);
  bs_error err = {0};
  bs_amg *amg = NULL;
  cr_assert_eq(bs_amg_create(&amg, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_amg_ready(amg), 0);
  cr_assert_eq(bs_amg_setup(amg, e.A, e.mask, &err), 0, "%s", err.msg);
  cr_assert(bs_amg_ready(amg));
  cr_assert(bs_amg_same_mask(amg, e.A->n, e.mask));
  cr_assert_eq(bs_amg_same_mask(amg, e.A->n, NULL), 0);
  bs_amg_info info;
  bs_amg_get_info(amg, &info);
  cr_assert_eq(info.setups, 1);
  int64_t nfree = 0;
  for (int32_t i = 0; i < e.A->n; ++i) nfree += 3 * e.mask[i];
  cr_assert_eq(info.free_dofs, nfree);
  double *u = malloc(sizeof *u * e.N), *v = malloc(sizeof *v * e.N), *Bu = malloc(sizeof *Bu * e.N),
         *Bv = malloc(sizeof *Bv * e.N);
  unsigned s = 7u;
  for (size_t k = 0; k < e.N; ++k) {
    s = s * 1103515245u + 12345u;
    u[k] = e.mask[k / 3] ? ((s >> 8) & 0xffff) / 65536.0 - 0.5 : 0.0;
    s = s * 1103515245u + 12345u;
    v[k] = e.mask[k / 3] ? ((s >> 8) & 0xffff) / 65536.0 - 0.5 : 0.0;
  }
  double uBu = 0, vBv = 0;
  cr_assert_eq(bs_amg_apply(amg, u, Bu, &uBu, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_amg_apply(amg, v, Bv, &vBv, &err), 0, "%s", err.msg);
  double vBu = 0, uBv = 0, nrm = 0;
  for (size_t k = 0; k < e.N; ++k) {
    vBu += v[k] * Bu[k];
    uBv += u[k] * Bv[k];
    nrm += fabs(u[k] * Bv[k]);
    if (!e.mask[k / 3]) cr_assert_eq(Bu[k], 0.0);
  }
  cr_assert_gt(uBu, 0.0);
  cr_assert_gt(vBv, 0.0);
  cr_assert_leq(fabs(vBu - uBv), 1e-10 * nrm, "v.Bu = %.15g, u.Bv = %.15g", vBu, uBv);
  free(u);
  free(v);
  free(Bu);
  free(Bv);
  bs_amg_destroy(&amg);
  cr_assert_null(amg);
  bs_amg_destroy(NULL);
  elast_free(&e);
}

/* Without an explicit setup, the solve sets up from A; a new mask re-does it;
 * all-fixed and all-free masks work. */
Test(amg, setup_follows_the_mask) {
  elast e;
  elast_make(5, &e);
  bs_error err = {0};
  bs_linsolve *ls = NULL;
  cr_assert_eq(bs_linsolve_create(e.A, BS_LIN_AMG, &ls, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_linsolve_amg_ready(ls, e.mask), 0);
  double *x = malloc(sizeof *x * e.N);
  bs_lin_stats st;
  cr_assert_eq(bs_linsolve_solve(ls, e.A, e.mask, e.b, 1e-8, 0, x, &st, &err), 0, "%s", err.msg);
  cr_assert(st.converged);
  cr_assert(bs_linsolve_amg_ready(ls, e.mask));
  cr_assert_leq(true_residual(&e, x), 1e-7);
  bs_amg_info info;
  bs_linsolve_amg_info(ls, &info);
  cr_assert_eq(info.setups, 1);
  /* Same mask: reused. */
  cr_assert_eq(bs_linsolve_solve(ls, e.A, e.mask, e.b, 1e-8, 0, x, &st, &err), 0, "%s", err.msg);
  bs_linsolve_amg_info(ls, &info);
  cr_assert_eq(info.setups, 1);
  /* All fixed: x = 0, converged. */
  uint8_t *none = calloc((size_t)e.A->n, 1);
  cr_assert_eq(bs_linsolve_solve(ls, e.A, none, e.b, 1e-8, 0, x, &st, &err), 0, "%s", err.msg);
  cr_assert(st.converged);
  for (size_t k = 0; k < e.N; ++k) cr_assert_eq(x[k], 0.0);
  bs_linsolve_amg_info(ls, &info);
  cr_assert_eq(info.setups, 2);
  free(none);
  /* Back to the mask: a third setup. */
  cr_assert_eq(bs_linsolve_solve(ls, e.A, e.mask, e.b, 1e-8, 0, x, &st, &err), 0, "%s", err.msg);
  cr_assert(st.converged);
  bs_linsolve_amg_info(ls, &info);
  cr_assert_eq(info.setups, 3);
  free(x);
  bs_linsolve_destroy(&ls);
  elast_free(&e);
}

Test(amg, error_paths) {
  elast e;
  elast_make(3, &e);
  bs_error err = {0};
  bs_linsolve *pcg = NULL, *ls = NULL;
  cr_assert_eq(bs_linsolve_create(e.A, BS_LIN_PCG, &pcg, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_linsolve_amg_setup(pcg, e.A, e.mask, &err), BS_EINPUT);
  cr_assert_not_null(strstr(err.msg, "pcg"), "%s", err.msg);
  cr_assert_eq(bs_linsolve_amg_ready(pcg, e.mask), 0);
  bs_linsolve_destroy(&pcg);
  bs_lin_kind k;
  cr_assert_eq(bs_lin_kind_parse("amg", &k, &err), 0);
  cr_assert_eq(k, BS_LIN_AMG);
  cr_assert_str_eq(bs_lin_kind_name(BS_LIN_AMG), "amg");
  cr_assert_eq(bs_lin_kind_parse("AMG", &k, &err), BS_EINPUT);
  cr_assert_not_null(strstr(err.msg, "amg"), "%s", err.msg);
  cr_assert_eq(bs_linsolve_create(e.A, BS_LIN_AMG, &ls, &err), 0, "%s", err.msg);
  /* A non-finite entry on a free block is named. */
  int32_t v = -1;
  for (int32_t i = 0; i < e.A->n && v < 0; ++i)
    if (e.mask[i]) v = i;
  e.A->val[9 * (int64_t)e.A->diag[v] + 4] = NAN;
  cr_assert_eq(bs_linsolve_amg_setup(ls, e.A, e.mask, &err), BS_ENUMERIC);
  char want[64];
  snprintf(want, sizeof want, "block (%d,%d)", (int)v, (int)v);
  cr_assert_not_null(strstr(err.msg, want), "%s", err.msg);
  cr_assert_eq(bs_linsolve_amg_ready(ls, e.mask), 0);
  bs_amg *amg = NULL;
  cr_assert_eq(bs_amg_create(&amg, &err), 0);
  double z[3];
  cr_assert_eq(bs_amg_apply(amg, z, z + 1, NULL, &err), BS_EINPUT, "apply before setup");
  bs_amg_destroy(&amg);
  bs_linsolve_destroy(&ls);
  elast_free(&e);
}

/* ---- the minimizer's reuse policy on a quadratic E = 1/2 x'Ax - b'x ------ */

typedef struct quad {
  const elast *e;
  double *Ax;
  int precond_calls;
} quad;

static int q_value(const double *x, double *E, void *ctx) {
  quad *q = ctx;
  bs_bsr_mul(q->e->A, NULL, x, q->Ax);
  double s = 0;
  for (size_t k = 0; k < q->e->N; ++k) s += 0.5 * x[k] * q->Ax[k] - q->e->b[k] * x[k];
  *E = s;
  return 0;
}
static int q_gradient(const double *x, double *E, double *g, void *ctx) {
  quad *q = ctx;
  q_value(x, E, ctx);
  for (size_t k = 0; k < q->e->N; ++k) g[k] = q->Ax[k] - q->e->b[k];
  return 0;
}
static int q_hessian(const double *x, bs_bsr *H, void *ctx) {
  (void)x;
  quad *q = ctx;
  memcpy(H->val, q->e->A->val, sizeof(double) * 9 * (size_t)H->nnzb);
  return 0;
}
static int q_precond(const double *x, bs_bsr *P, void *ctx) {
  (void)x;
  quad *q = ctx;
  q->precond_calls++;
  memcpy(P->val, q->e->A->val, sizeof(double) * 9 * (size_t)P->nnzb);
  return 0;
}

Test(amg, minimizer_reuses_the_setup) {
  elast e;
  elast_make(5, &e);
  quad q = {&e, malloc(sizeof(double) * e.N), 0};
  bs_objective obj = {0};
  obj.n = e.A->n;
  obj.mask = e.mask;
  obj.value = q_value;
  obj.gradient = q_gradient;
  obj.hessian = q_hessian;
  obj.precond_matrix = q_precond;
  obj.ctx = &q;
  bs_minimize_opts o;
  bs_minimize_opts_default(&o);
  o.linear = BS_LIN_AMG;
  o.tol = 1e-8;
  bs_error err = {0};
  bs_minimizer *m = NULL;
  cr_assert_eq(bs_minimizer_create(e.A, &o, &m, &err), 0, "%s", err.msg);
  double *x = calloc(e.N, sizeof *x);
  bs_minimize_stats st;
  cr_assert_eq(bs_minimize(m, &obj, x, &st, &err), 0, "%s", err.msg);
  cr_assert_eq(st.reason, BS_MIN_CONVERGED, "%s", st.reason_text);
  cr_assert_eq(st.amg_setups, 1);
  cr_assert_eq(q.precond_calls, 1);
  cr_assert_gt(st.iterations, 1, "several Newton iterations share one setup");
  /* A second call reuses the hierarchy. */
  memset(x, 0, sizeof *x * e.N);
  cr_assert_eq(bs_minimize(m, &obj, x, &st, &err), 0, "%s", err.msg);
  cr_assert_eq(st.amg_setups, 0);
  /* Reset: rebuilt once. */
  bs_minimizer_amg_reset(m);
  memset(x, 0, sizeof *x * e.N);
  cr_assert_eq(bs_minimize(m, &obj, x, &st, &err), 0, "%s", err.msg);
  cr_assert_eq(st.amg_setups, 1);
  cr_assert_eq(q.precond_calls, 2);
  /* Every call. */
  o.amg_rebuild_every = 1;
  cr_assert_eq(bs_minimizer_set_opts(m, &o, &err), 0, "%s", err.msg);
  for (int r = 0; r < 2; ++r) {
    memset(x, 0, sizeof *x * e.N);
    cr_assert_eq(bs_minimize(m, &obj, x, &st, &err), 0, "%s", err.msg);
    cr_assert_eq(st.amg_setups, 1);
  }
  /* Bad options are named. */
  o.amg_rebuild_factor = 0.5;
  cr_assert_eq(bs_minimizer_set_opts(m, &o, &err), BS_EINPUT);
  cr_assert_not_null(strstr(err.msg, "amg_rebuild_factor"), "%s", err.msg);
  o.amg_rebuild_factor = 3;
  o.amg_rebuild_every = -1;
  cr_assert_eq(bs_minimizer_set_opts(m, &o, &err), BS_EINPUT);
  cr_assert_not_null(strstr(err.msg, "amg_rebuild_every"), "%s", err.msg);
  free(x);
  free(q.Ax);
  bs_minimizer_destroy(&m);
  elast_free(&e);
}

/* ---- a scene (through the library) --------------------------------------- */

Test(amg, cube_stretch_with_amg_converges, .timeout = 600) {
  const char *scene = BS_SOURCE_DIR "/data/scenes/cube_stretch.json";
  sim_rec rec;
  bs_run_totals T;
  bs_scene *sc = NULL;
  bs_sim *s = sim_run_scene(scene, "time.frames=4 bodies.0.box.cells=[8,8,8] solver.linear=amg", NULL, &rec, &T, 1,
                            &sc);
  cr_assert_eq(sc->solver.min.linear, BS_LIN_AMG, "the scene's linear solver is not amg");
  cr_assert_eq(T.failed, 0, "failed steps: %s", T.first_fail_reason);
  cr_assert_eq(T.steps, 4);
  cr_assert_gt((double)T.iterations / (double)T.steps, 0.0);
  bs_sim_destroy(&s);
  bs_scene_destroy(&sc);
  /* "current": the PSD-projected Hessian at the iterate (the default, "rest", is
   * the rest-state stiffness). */
  sim_run_scene(scene,
                "time.frames=3 bodies.0.box.cells=[6,6,6] solver.linear=amg solver.amg_matrix=current "
                "solver.amg_rebuild_every=2",
                NULL, &rec, &T, 0, NULL);
  cr_assert_eq(T.failed, 0, "failed steps: %s", T.first_fail_reason);
  /* Bad values are named. */
  const char *bad[] = {"solver.linear=amg", "solver.amg_matrix=later"};
  bs_error err;
  cr_assert_neq(sim_load_error(scene, bad, 2, &err), 0);
  cr_assert_not_null(strstr(err.msg, "amg_matrix"), "%s", err.msg);
}
