/* dstep.c — the integrator of physics/bs_step.h on a distributed mesh: the
 * petsc backend (bs_step_backend.h) made and handed to
 * bs_integrator_create_on (bs_dstep.h). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bs_dstep.h"
#include "bs_dist.h"
#include "bs_vecops.h"
#include "dist_internal.h"
#include "dstep_internal.h"

/* ---- the minimizer's vector operations ----------------------------------- */

static double vo_dot(int64_t N, const double *a, const double *b, void *ctx) {
  (void)N;
  bs_dintegrator *D = ctx;
  double s = NAN;
  int rc = bs_dfem_dot(D->df, a, b, &s, &D->cb_err);
  if (rc && !D->cb_rc) D->cb_rc = rc;
  return s;
}

static int vo_any(int flag, void *ctx) {
  (void)ctx;
  int64_t f = flag != 0;
  bs_dist_sum_i64(&f, 1, NULL);
  return f > 0;
}

static void vo_sum(double *v, int n, void *ctx) {
  (void)ctx;
  bs_dist_sum(v, n, NULL);
}

static int vo_solve(const uint8_t *mask, const double *r, double rel, int max_it, double kappa, double *d,
                    bs_lin_stats *ls, bs_error *err, void *ctx) {
  bs_dintegrator *D = ctx;
  return bs_dlin_solve(D->lin, mask, r, rel, max_it, kappa, d, ls, err);
}

/* ---- create / destroy ---------------------------------------------------- */

/* The lumped mass of every local vertex, summed over the ranks. */
static int assembled_mass(bs_dintegrator *D, bs_error *err) {
  const bs_dfem *df = D->df;
  double *c = bs_calloc((size_t)df->n3 + 3, sizeof *c, "mass", err);
  if (!c) return BS_ENOMEM;
  for (int32_t i = 0; i < df->mesh->local->n_vertices; i++) c[3 * (size_t)df->mesh->local_vertex[i]] = df->fem->mass[i];
  int rc = bs_dfem_assemble(df, c, c, err);
  for (int32_t v = 0; !rc && v < df->mesh->n_vertices; v++) D->mass[v] = c[3 * (size_t)v];
  free(c);
  return rc;
}

static int alloc_all(bs_dintegrator *D, bs_error *err) {
  const bs_dfem *df = D->df;
  size_t n3 = (size_t)df->n3 + 3, nm = 3 * (size_t)df->mesh->local->n_vertices + 3, nv = (size_t)df->mesh->n_vertices;
  double **m[] = {&D->x_hat_m, &D->x_n_m, &D->hxm, &D->hgm};
  for (size_t k = 0; k < sizeof m / sizeof *m; k++) *m[k] = bs_calloc(nm, sizeof(double), "local-mesh vectors", err);
  D->gtmp = bs_calloc(n3, sizeof(double), "integrator vectors", err);
  D->mass = bs_calloc(nv + 1, sizeof(double), "integrator vectors", err);
  if (!D->x_hat_m || !D->x_n_m || !D->hxm || !D->hgm || !D->gtmp || !D->mass) return BS_ENOMEM;
  return BS_OK;
}

/* The minimizer's pattern: diagonal over the local vertices (its Hessian
 * storage is not used: the dfem assembles its own matrix), and the solver. */
static int make_solver(bs_dintegrator *D, bs_error *err) {
  int32_t n = D->df->mesh->n_vertices;
  int32_t *ptr = bs_calloc((size_t)n + 1, sizeof *ptr, "pattern", err);
  if (!ptr) return BS_ENOMEM;
  int rc = bs_bsr_create(n, ptr, ptr, &D->diag, err);
  free(ptr);
  D->vecops = (bs_vecops){vo_dot, vo_any, vo_sum, vo_solve, D};
  if (!rc) rc = bs_dlin_create(D->df, D->pc, &D->lin, err);
  return rc;
}

/* The first error of a vector operation during the last solve. */
static int solve_error(void *ctx, bs_error *err) {
  bs_dintegrator *D = ctx;
  int rc = D->cb_rc;
  if (rc && err) *err = D->cb_err;
  D->cb_rc = 0;
  return rc;
}

static bs_dpc preconditioner(bs_lin_kind k) {
  return k == BS_LIN_PCG ? BS_DPC_BJACOBI : k == BS_LIN_AMG ? BS_DPC_GAMG : BS_DPC_NONE;
}

int bs_dintegrator_create(bs_dfem *df, bs_step_data *step, const uint8_t *mask, bs_script_fn script, void *script_ctx,
                          const bs_integrator_opts *opts, bs_dintegrator **out, bs_error *err) {
  *out = NULL;
  bs_integrator_opts o;
  if (opts) o = *opts;
  else bs_integrator_opts_default(&o);
  bs_dintegrator *D = bs_calloc(1, sizeof *D, "distributed integrator", err);
  if (!D) return BS_ENOMEM;
  D->df = df, D->n_all = df->n_terms, D->all = df->terms, D->statics_all = df->statics;
  D->pc = preconditioner(o.min.linear), D->amg_dt = -1;
  int rc = alloc_all(D, err);
  if (!rc) rc = assembled_mass(D, err);
  if (!rc) rc = make_solver(D, err);
  if (!rc) {
    bs_step_backend B = {.n_vertices = df->mesh->n_vertices, .mass = D->mass, .pattern = D->diag,
                         .vecops = &D->vecops, .caps = BS_DSTEP_CAPS, .name = "petsc", .ctx = D};
    bs__dstep_backend_ops(&B);
    B.solve_error = solve_error;
    rc = bs_integrator_create_on(&B, step, D->n_all, D->all, mask, script, script_ctx, &o, &D->integ, err);
  }
  if (rc) bs_dintegrator_destroy(&D);
  *out = D;
  return rc;
}

void bs_dintegrator_destroy(bs_dintegrator **pD) {
  if (!pD || !*pD) return;
  bs_dintegrator *D = *pD;
  bs_integrator_destroy(&D->integ);
  bs_bsr_destroy(&D->diag);
  bs_dlin_destroy(&D->lin);
  free(D->x_hat_m), free(D->x_n_m), free(D->hxm), free(D->hgm), free(D->gtmp), free(D->mass);
  free(D);
  *pD = NULL;
}

/* ---- the integrator's calls ---------------------------------------------- */

int bs_dintegrator_set_hooks(bs_dintegrator *D, const bs_step_hooks *hooks, bs_error *err) {
  return bs_integrator_set_hooks_checked(D->integ, hooks, err);
}

int bs_dintegrator_static(bs_dintegrator *D, double t, int load_steps, double *x, bs_step_stats *st, bs_error *err) {
  return bs_integrator_static(D->integ, t, load_steps, x, st, err);
}

int bs_dintegrator_step(bs_dintegrator *D, double t, double dt, double *x, double *v, bs_step_stats *st,
                        bs_error *err) {
  return bs_integrator_step(D->integ, t, dt, x, v, st, err);
}

bs_integrator *bs_dintegrator_integrator(bs_dintegrator *D) { return D->integ; }
const bs_dlin *bs_dintegrator_linsolve(const bs_dintegrator *D) { return D->lin; }

void bs_dintegrator_get_carry(const bs_dintegrator *D, bs_min_carry *c) { bs_integrator_get_carry(D->integ, c); }
void bs_dintegrator_set_carry(bs_dintegrator *D, const bs_min_carry *c) { bs_integrator_set_carry(D->integ, c); }
void bs_dintegrator_set_stop(bs_dintegrator *D, volatile sig_atomic_t *stop) { bs_integrator_set_stop(D->integ, stop); }
