/* dstep.c — backward Euler steps and statics on a distributed mesh, through
 * the one minimizer of solver/ with distributed vector operations
 * (bs_dstep.h). Follows physics/step.c step by step. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bs_dstep.h"
#include "bs_dist.h"
#include "bs_vecops.h"
#include "dist_internal.h"
#include "dstep_internal.h"


/* ---- objective and vector operations ------------------------------------ */

void bs__dstep_note(bs_dintegrator *D, int rc) {
  if (rc < 0 && !D->cb_rc) D->cb_rc = rc;
}

static int obj_value(const double *x, double *E, void *ctx) {
  bs_dintegrator *D = ctx;
  int rc = bs_dfem_value(D->df, x, E, &D->cb_err);
  bs__dstep_note(D, rc);
  return rc ? 1 : !isfinite(*E);
}

static int obj_gradient(const double *x, double *E, double *g, void *ctx) {
  bs_dintegrator *D = ctx;
  int rc = bs_dfem_gradient(D->df, x, E, g, &D->cb_err);
  bs__dstep_note(D, rc);
  if (rc) *E = NAN;
  return rc ? 1 : 0;
}

static int obj_hessian(const double *x, bs_bsr *H, void *ctx) {
  bs_dintegrator *D = ctx;
  int rc = bs_dfem_hessian(D->df, x, D->mask, &D->cb_err);
  bs__dstep_note(D, rc);
  return rc ? 1 : 0;
}

static double vo_dot(int64_t N, const double *a, const double *b, void *ctx) {
  bs_dintegrator *D = ctx;
  double s = NAN;
  bs__dstep_note(D, bs_dfem_dot(D->df, a, b, &s, &D->cb_err));
  return s;
}

static int vo_any(int flag, void *ctx) {
  int64_t f = flag != 0;
  bs_dist_sum_i64(&f, 1, NULL);
  return f > 0;
}

static void vo_sum(double *v, int n, void *ctx) { bs_dist_sum(v, n, NULL); }

static int vo_solve(const uint8_t *mask, const double *r, double rel, int max_it, double kappa, double *d,
                    bs_lin_stats *ls, bs_error *err, void *ctx) {
  bs_dintegrator *D = ctx;
  return bs_dlin_solve(D->lin, mask, r, rel, max_it, kappa, d, ls, err);
}

void bs__dstep_objective(bs_dintegrator *D, bs_objective *o) {
  memset(o, 0, sizeof *o);
  o->n = D->df->mesh->n_vertices;
  o->mask = D->mask;
  o->value = obj_value;
  o->gradient = obj_gradient;
  o->hessian = obj_hessian;
  bs__dstep_hook_objective(D, o);
  o->ctx = D;
}

/* ---- create / destroy ---------------------------------------------------- */

static int check_opts(const bs_integrator_opts *o, bs_dpc *pc, bs_error *err) {
  if (o->method != BS_METHOD_OPTIMIZATION)
    return bs_error_set(err, BS_EINPUT, "solver.method: %s is not available with solver.backend petsc (optimization is)",
                        bs_method_name(o->method));
  if (o->guess_xn)
    return bs_error_set(err, BS_EINPUT, "integrator option guess_xn is not available with solver.backend petsc");
  switch (o->min.linear) {
  case BS_LIN_CG: *pc = BS_DPC_NONE; return BS_OK;
  case BS_LIN_PCG: *pc = BS_DPC_BJACOBI; return BS_OK;
  case BS_LIN_AMG: *pc = BS_DPC_GAMG; return BS_OK;
  default:
    return bs_error_set(err, BS_EINPUT, "solver.linear: %s is not available with solver.backend petsc (cg, pcg, amg are)",
                        bs_lin_kind_name(o->min.linear));
  }
}

/* The lumped mass of every local vertex, summed over the ranks. */
static int assembled_mass(bs_dintegrator *D, bs_error *err) {
  const bs_dfem *df = D->df;
  double *c = bs_calloc((size_t)df->n3, sizeof *c, "mass", err);
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
  D->mask = bs_calloc(nv + 1, 1, "mask", err);
  double **m[] = {&D->x_hat_m, &D->x_n_m, &D->hxm, &D->hgm};
  for (size_t k = 0; k < sizeof m / sizeof *m; k++) *m[k] = bs_calloc(nm, sizeof(double), "local-mesh vectors", err);
  double **v[] = {&D->x_n, &D->g1, &D->g2, &D->grad, &D->mass};
  for (size_t k = 0; k < sizeof v / sizeof *v; k++) *v[k] = bs_calloc(n3, sizeof(double), "integrator vectors", err);
  D->potential = bs_calloc((size_t)D->n_terms + 1, sizeof *D->potential, "terms", err);
  D->external = bs_calloc((size_t)D->n_terms + 1, sizeof *D->external, "terms", err);
  if (!D->mask || !D->x_hat_m || !D->x_n_m || !D->hxm || !D->hgm || !D->x_n || !D->g1 || !D->g2 || !D->grad ||
      !D->mass || !D->potential || !D->external)
    return BS_ENOMEM;
  return BS_OK;
}

/* The minimizer on a diagonal pattern of the local vertices (its Hessian
 * storage is not used: the dfem assembles its own matrix). */
static int make_minimizer(bs_dintegrator *D, bs_dpc pc, bs_error *err) {
  int32_t n = D->df->mesh->n_vertices;
  int32_t *ptr = bs_calloc((size_t)n + 1, sizeof *ptr, "pattern", err);
  if (!ptr) return BS_ENOMEM;
  int rc = bs_bsr_create(n, ptr, ptr, &D->diag, err);
  free(ptr);
  bs_minimize_opts mo = D->opts.min;
  mo.linear = BS_LIN_CG;
  if (!rc) rc = bs_minimizer_create(D->diag, &mo, &D->min, err);
  bs_vecops ops = {vo_dot, vo_any, vo_sum, vo_solve, D};
  if (!rc) rc = bs_minimizer_set_vecops(D->min, &ops, err);
  if (!rc) rc = bs_dlin_create(D->df, pc, &D->lin, err);
  return rc;
}

int bs_dintegrator_create(bs_dfem *df, bs_step_data *step, const uint8_t *mask, bs_script_fn script, void *script_ctx,
                          const bs_integrator_opts *opts, bs_dintegrator **out, bs_error *err) {
  *out = NULL;
  bs_dpc pc = BS_DPC_NONE;
  bs_integrator_opts o;
  if (opts) o = *opts;
  else bs_integrator_opts_default(&o);
  int rc = check_opts(&o, &pc, err);
  if (rc) return rc;
  bs_dintegrator *D = bs_calloc(1, sizeof *D, "distributed integrator", err);
  if (!D) return BS_ENOMEM;
  D->df = df, D->step = step, D->opts = o, D->script = script, D->script_ctx = script_ctx;
  D->n_terms = df->n_terms, D->terms = df->terms, D->pc = pc, D->amg_dt = -1;
  rc = alloc_all(D, err);
  if (!rc) {
    if (mask) memcpy(D->mask, mask, (size_t)df->mesh->n_vertices);
    else memset(D->mask, 1, (size_t)df->mesh->n_vertices);
    for (int i = 0; i < D->n_terms; i++) {
      if (D->terms[i]->kind != BS_TERM_INERTIA) D->potential[D->n_potential++] = D->terms[i];
      if (D->terms[i]->external) D->external[D->n_external++] = D->terms[i];
    }
    step->x_hat = D->x_hat_m, step->x_n = D->x_n_m, step->load = 1.0, step->dt = 0;
    rc = assembled_mass(D, err);
  }
  if (!rc) rc = make_minimizer(D, pc, err);
  if (rc) bs_dintegrator_destroy(&D);
  *out = D;
  return rc;
}

void bs_dintegrator_destroy(bs_dintegrator **pD) {
  if (!pD || !*pD) return;
  bs_dintegrator *D = *pD;
  bs_minimizer_destroy(&D->min);
  bs_bsr_destroy(&D->diag);
  bs_dlin_destroy(&D->lin);
  free(D->mask), free(D->x_hat_m), free(D->x_n_m), free(D->x_n), free(D->g1), free(D->g2), free(D->grad);
  free(D->mass), free(D->potential), free(D->external), free(D->hxm), free(D->hgm);
  free(D);
  *pD = NULL;
}

const bs_dlin *bs_dintegrator_linsolve(const bs_dintegrator *D) { return D->lin; }

void bs_dintegrator_get_carry(const bs_dintegrator *D, bs_min_carry *c) { bs_minimizer_get_carry(D->min, c); }
void bs_dintegrator_set_carry(bs_dintegrator *D, const bs_min_carry *c) { bs_minimizer_set_carry(D->min, c); }
void bs_dintegrator_set_stop(bs_dintegrator *D, volatile sig_atomic_t *stop) { bs_minimizer_set_stop(D->min, stop); }
