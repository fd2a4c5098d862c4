/* step_serial.c — the serial backend of the integrator (bs_step_backend.h):
 * the terms on the whole mesh of a bs_fem, the minimizer's own vectors and
 * linear solvers, nothing to sum over processes. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bs_step.h"
#include "bs_step_backend.h"

typedef struct serial {
  const bs_fem *fem;
  double *gh;    /* 3n: the gradient for a projected Hessian without one */
  double amg_dt; /* dt of the last AMG preconditioner matrix (-1: none)  */
} serial;

static void s_publish(void *ctx, bs_step_data *step, const double *x_n, const double *x_hat) {
  (void)ctx;
  step->x_n = x_n, step->x_hat = x_hat;
}

static int s_energy(void *ctx, int n, bs_term *const *terms, const double *x, double *E, const char **bad,
                    bs_error *err) {
  (void)ctx, (void)err;
  double s = 0;
  *E = NAN;
  for (int i = 0; i < n; i++) {
    double e;
    int rc = terms[i]->ops->value(terms[i], x, &e);
    if (rc) {
      if (bad) *bad = terms[i]->name;
      return rc;
    }
    s += e;
  }
  *E = s;
  return 0;
}

static int s_gradient(void *ctx, int n, bs_term *const *terms, const double *x, double *E, double *g,
                      const char **bad, bs_error *err) {
  (void)err;
  serial *S = ctx;
  memset(g, 0, sizeof(double) * 3 * (size_t)S->fem->n_vertices);
  double s = 0;
  for (int i = 0; i < n; i++) {
    double e;
    int rc = terms[i]->ops->gradient(terms[i], x, &e, g);
    if (rc) {
      if (bad) *bad = terms[i]->name;
      return rc;
    }
    s += e;
  }
  *E = s;
  return 0;
}

static int add_hessians(int n, bs_term *const *terms, const double *x, const double *g_model, int convex, bs_bsr *H) {
  for (int i = 0; i < n; i++) {
    const bs_term *t = terms[i];
    int rc = convex && t->ops->hessian_convexified ? t->ops->hessian_convexified(t, x, H)
             : g_model && t->ops->hessian_g       ? t->ops->hessian_g(t, x, g_model, H)
                                                  : t->ops->hessian(t, x, H);
    if (rc) return rc;
  }
  return 0;
}

static int s_hessian(void *ctx, int n, bs_term *const *terms, const double *x, const double *g_model, int convex,
                     int add, const bs_step_hooks *hooks, const double *g_raw, const uint8_t *mask, bs_bsr *H,
                     bs_error *err) {
  (void)mask;
  serial *S = ctx;
  if (!add) bs_bsr_zero(H);
  int rc = add_hessians(n, terms, x, g_model, convex, H);
  if (rc || !hooks || !hooks->project_hessian) return rc;
  if (!g_raw) {
    double E;
    if ((rc = s_gradient(S, n, terms, x, &E, S->gh, NULL, err))) return rc;
    g_raw = S->gh;
  }
  hooks->project_hessian(x, g_raw, H, hooks->ctx);
  return 0;
}

static int s_project(void *ctx, const bs_step_hooks *h, double *x, bs_error *err) {
  (void)ctx, (void)err;
  h->project(x, h->ctx);
  return 0;
}

static void s_register(void *ctx, const bs_step_hooks *h, const double *x, const double *g) {
  (void)ctx;
  h->register_active(x, g, h->ctx);
}

static int s_project_gradient(void *ctx, const bs_step_hooks *h, const double *x, double *g, bs_error *err) {
  (void)ctx, (void)err;
  h->project_gradient(x, g, h->ctx);
  return 0;
}

static int s_sum_i64(void *ctx, int64_t *v, int n, bs_error *err) {
  (void)ctx, (void)v, (void)n, (void)err;
  return 0;
}

static int s_free_sq(void *ctx, const double *g, const uint8_t *mask, double *out, bs_error *err) {
  (void)err;
  serial *S = ctx;
  const size_t n3 = 3 * (size_t)S->fem->n_vertices;
  double s = 0;
  for (size_t i = 0; i < n3; i++)
    if (!mask || mask[i / 3]) s += g[i] * g[i];
  *out = s;
  return 0;
}

static int s_count_inverted(void *ctx, const double *x, int64_t *n, bs_error *err) {
  (void)err;
  serial *S = ctx;
  *n = bs_fem_count_inverted(S->fem, x, NULL);
  return 0;
}

/* The AMG preconditioner: P changes with dt (M/dt^2) and between dynamic
 * and static solves; built at rest, it does not depend on x. */
static int s_prepare_solve(void *ctx, bs_minimizer *min, bs_minimize_opts *mo, double pdt, int n,
                           bs_term *const *terms, const uint8_t *mask, int amg_at_rest, bs_error *err) {
  (void)n, (void)terms, (void)mask, (void)err;
  serial *S = ctx;
  if (mo->linear != BS_LIN_AMG) return 0;
  if (pdt != S->amg_dt) bs_minimizer_amg_reset(min);
  S->amg_dt = pdt;
  if (amg_at_rest) mo->amg_rebuild_factor = 0;
  return 0;
}

static int s_precond(void *ctx, int n, bs_term *const *terms, const double *x, int at_rest, bs_bsr *P) {
  serial *S = ctx;
  int rc = add_hessians(n, terms, x, NULL, 0, P);
  if (rc) return rc;
  bs_fem_elastic_hessian(S->fem, at_rest ? S->fem->mesh->x : x, 1, 1.0, P);
  return 0;
}

static void s_destroy(void *ctx) {
  serial *S = ctx;
  if (!S) return;
  free(S->gh);
  free(S);
}

int bs_step_backend_serial(const bs_fem *fem, bs_step_backend *B, bs_error *err) {
  memset(B, 0, sizeof *B);
  serial *S = calloc(1, sizeof *S);
  const size_t n3 = 3 * (size_t)fem->n_vertices;
  if (S) S->gh = malloc(sizeof(double) * (n3 ? n3 : 1));
  if (!S || !S->gh) {
    s_destroy(S);
    return bs_error_set(err, BS_ENOMEM, "out of memory creating the integrator (%zu vertices)", n3 / 3);
  }
  S->fem = fem;
  S->amg_dt = -1;
  *B = (bs_step_backend){.n_vertices = fem->n_vertices, .mass = fem->mass, .pattern = fem->pattern,
                         .caps = BS_STEP_CAN_ALL, .name = "serial", .publish = s_publish, .energy = s_energy,
                         .gradient = s_gradient, .hessian = s_hessian, .project = s_project,
                         .register_active = s_register, .project_gradient = s_project_gradient,
                         .sum_i64 = s_sum_i64, .free_sq = s_free_sq, .count_inverted = s_count_inverted,
                         .prepare_solve = s_prepare_solve, .precond = s_precond, .destroy = s_destroy, .ctx = S};
  return 0;
}
