/* dstep_run.c — the petsc backend's evaluations (bs_step_backend.h): the
 * terms of a list on the rank's owned cells through the dfem, summed and
 * assembled over the ranks; the constraint hooks on local-mesh copies of the
 * local vectors, made consistent; the reductions over the ranks. */
#include <math.h>
#include <string.h>

/* dstep_internal.h first: <complex.h>, which PETSc includes, defines I. */
#include "dstep_internal.h"
#include "bs_dist.h"
#include "dist_internal.h"

static void use(bs_dintegrator *D, int n, bs_term *const *terms) { bs_dfem_set_terms(D->df, n, terms, 0); }
static void restore(bs_dintegrator *D) { bs_dfem_set_terms(D->df, D->n_all, D->all, D->statics_all); }

static void d_publish(void *ctx, bs_step_data *step, const double *x_n, const double *x_hat) {
  bs_dintegrator *D = ctx;
  bs_dfem_mesh_vector(D->df, x_n, D->x_n_m);
  bs_dfem_mesh_vector(D->df, x_hat, D->x_hat_m);
  step->x_n = D->x_n_m, step->x_hat = D->x_hat_m;
}

static int d_energy(void *ctx, int n, bs_term *const *terms, const double *x, double *E, const char **bad,
                    bs_error *err) {
  (void)bad;
  bs_dintegrator *D = ctx;
  use(D, n, terms);
  int rc = bs_dfem_value(D->df, x, E, err);
  restore(D);
  if (rc) *E = NAN;
  return rc;
}

static int d_gradient(void *ctx, int n, bs_term *const *terms, const double *x, double *E, double *g,
                      const char **bad, bs_error *err) {
  (void)bad;
  bs_dintegrator *D = ctx;
  use(D, n, terms);
  int rc = bs_dfem_gradient(D->df, x, E, g, err);
  restore(D);
  return rc;
}

static void to_hook(bs_dintegrator *D, const double *x, const double *g) {
  bs_dfem_mesh_vector(D->df, x, D->hxm);
  if (g) bs_dfem_mesh_vector(D->df, g, D->hgm);
}

/* Inside bs_dfem_hessian_model: the rank's partial Hessian projected at the
 * point d_hessian was given (a block the hook adds per vertex is added on
 * one rank only: bs_dstep.h). */
static void project_partial(bs_bsr *Hm, void *ctx) {
  bs_dintegrator *D = ctx;
  to_hook(D, D->hess_x, D->hess_g);
  D->hess_hooks->project_hessian(D->hxm, D->hgm, Hm, D->hess_hooks->ctx);
}

/* The dfem's own matrix (H, convex and add unused: no convexified terms). */
static int d_hessian(void *ctx, int n, bs_term *const *terms, const double *x, const double *g_model, int convex,
                     int add, const bs_step_hooks *hooks, const double *g_raw, const uint8_t *mask, bs_bsr *H,
                     bs_error *err) {
  (void)convex, (void)add, (void)H;
  bs_dintegrator *D = ctx;
  int rc = 0;
  if (hooks && !g_raw) {
    double E;
    rc = d_gradient(D, n, terms, x, &E, D->gtmp, NULL, err);
    g_raw = D->gtmp;
  }
  if (rc) return rc;
  D->hess_hooks = hooks, D->hess_x = x, D->hess_g = g_raw;
  use(D, n, terms);
  rc = bs_dfem_hessian_model(D->df, x, g_model, mask, hooks ? project_partial : NULL, D, err);
  restore(D);
  return rc;
}

static int d_project(void *ctx, const bs_step_hooks *h, double *x, bs_error *err) {
  bs_dintegrator *D = ctx;
  to_hook(D, x, NULL);
  h->project(D->hxm, h->ctx);
  bs_dfem_from_mesh_vector(D->df, D->hxm, x);
  return bs_dfem_consistent(D->df, x, err);
}

static void d_register(void *ctx, const bs_step_hooks *h, const double *x, const double *g) {
  bs_dintegrator *D = ctx;
  to_hook(D, x, g);
  h->register_active(D->hxm, D->hgm, h->ctx);
}

static int d_project_gradient(void *ctx, const bs_step_hooks *h, const double *x, double *g, bs_error *err) {
  bs_dintegrator *D = ctx;
  to_hook(D, x, g);
  h->project_gradient(D->hxm, D->hgm, h->ctx);
  bs_dfem_from_mesh_vector(D->df, D->hgm, g);
  return bs_dfem_consistent(D->df, g, err);
}

static int d_sum_i64(void *ctx, int64_t *v, int n, bs_error *err) {
  (void)ctx;
  return bs_dist_sum_i64(v, n, err);
}

/* Over the owned free dofs, summed over the ranks. */
static int d_free_sq(void *ctx, const double *g, const uint8_t *mask, double *out, bs_error *err) {
  bs_dintegrator *D = ctx;
  const bs_dmesh *m = D->df->mesh;
  double s = 0;
  for (int32_t v = 0; v < m->n_vertices; v++)
    if (m->owned[v] && (!mask || mask[v]))
      for (int k = 0; k < 3; k++) s += g[3 * (size_t)v + k] * g[3 * (size_t)v + k];
  int rc = bs_dist_sum(&s, 1, err);
  *out = s;
  return rc;
}

static int d_count_inverted(void *ctx, const double *x, int64_t *n, bs_error *err) {
  bs_dintegrator *D = ctx;
  bs_dfem_mesh_vector(D->df, x, D->hxm);
  *n = bs_fem_count_inverted(D->df->fem, D->hxm, NULL);
  return bs_dist_sum_i64(n, 1, err);
}

/* GAMG: its matrix is the Hessian of the active terms at the rest positions
 * (SPD on the free dofs: the rest stiffness, plus M/dt^2 and the damping in a
 * dynamic solve), built again when dt changes. */
static int d_prepare_solve(void *ctx, bs_minimizer *min, bs_minimize_opts *mo, double pdt, int n,
                           bs_term *const *terms, const uint8_t *mask, int amg_at_rest, bs_error *err) {
  (void)min, (void)mo, (void)amg_at_rest;
  bs_dintegrator *D = ctx;
  if (D->pc != BS_DPC_GAMG || (pdt == D->amg_dt && bs_dlin_ready(D->lin))) return BS_OK;
  use(D, n, terms);
  int rc = bs_dfem_hessian(D->df, D->df->mesh->x, mask, err);
  restore(D);
  if (!rc) rc = bs_dlin_setup(D->lin, D->df->H, err);
  if (!rc) D->amg_dt = pdt;
  return rc;
}

void bs__dstep_backend_ops(bs_step_backend *B) {
  B->publish = d_publish, B->energy = d_energy, B->gradient = d_gradient, B->hessian = d_hessian;
  B->project = d_project, B->register_active = d_register, B->project_gradient = d_project_gradient;
  B->sum_i64 = d_sum_i64, B->free_sq = d_free_sq, B->count_inverted = d_count_inverted;
  B->prepare_solve = d_prepare_solve, B->precond = NULL, B->destroy = NULL;
}
