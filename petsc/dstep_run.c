/* dstep_run.c — statics and one backward Euler step on a distributed mesh
 * (bs_dstep.h), as bs_integrator_static / bs_integrator_step. */
#include <math.h>
#include <string.h>

#include "dstep_internal.h"
#include "bs_dist.h"
#include "dist_internal.h"

/* NaN / Inf in a local vector on some rank: BS_ENUMERIC on every rank. */
static int check_finite(const bs_dintegrator *D, const double *a, const char *what, bs_error *err) {
  int64_t bad = -1;
  for (int64_t i = 0; i < D->df->n3 && bad < 0; i++)
    if (!isfinite(a[i])) bad = i;
  int64_t any = bad >= 0;
  int rc = bs_dist_sum_i64(&any, 1, err);
  if (rc || !any) return rc;
  if (bad >= 0)
    return bs_error_set(err, BS_ENUMERIC, "%s of local vertex %lld (component %d) on rank %d is not finite (%g)", what,
                        (long long)(bad / 3), (int)(bad % 3), bs_dist_rank(), a[bad]);
  return bs_error_set(err, BS_ENUMERIC, "a %s is not finite on another rank", what);
}

/* GAMG: its matrix is the Hessian of the active terms at the rest positions
 * (SPD on the free dofs: the rest stiffness, plus M/dt^2 and the damping in a
 * dynamic solve), built again when dt changes. */
static int gamg_prepare(bs_dintegrator *D, bs_error *err) {
  const double pdt = D->df->statics ? 0.0 : D->step->dt;
  if (D->pc != BS_DPC_GAMG || (pdt == D->amg_dt && bs_dlin_ready(D->lin))) return BS_OK;
  int rc = bs_dfem_hessian(D->df, D->df->mesh->x, D->mask, err);
  if (!rc) rc = bs_dlin_setup(D->lin, D->df->H, err);
  if (!rc) D->amg_dt = pdt;
  return rc;
}

/* The 2-norm over the free dofs of the external loads' forces at x (the
 * scale of load_rtol, as physics/step.c's load_norm), computed in D->g1
 * (free once the guess is in x); 0 when there is none or it is not
 * evaluable. */
static int load_norm(bs_dintegrator *D, const double *x, double *out, bs_error *err) {
  *out = 0;
  bs_dfem *df = D->df;
  const int statics = df->statics;
  if (D->n_external == 0) return BS_OK;
  double E, s = 0;
  bs_dfem_set_terms(df, D->n_external, D->external, statics);
  int rc = bs_dfem_gradient(df, x, &E, D->g1, err);
  bs_dfem_set_terms(df, D->n_terms, D->terms, statics);
  if (rc) return rc > 0 ? BS_OK : rc;
  for (int32_t v = 0; v < df->mesh->n_vertices; v++)
    if (!D->mask[v]) memset(D->g1 + 3 * (size_t)v, 0, 3 * sizeof(double));
  if ((rc = bs_dfem_dot(df, D->g1, D->g1, &s, err))) return rc;
  *out = isfinite(s) ? sqrt(s) : 0;
  return BS_OK;
}

/* The solve's options as physics/step.c's run_solver sets them: the
 * initial guess's kind, and the adaptive forcing's rule (bs_step_forcing)
 * from the inverted tets at the step's start over the ranks. */
static int solve_opts(bs_dintegrator *D, int naive, bs_minimize_opts *mo, bs_error *err) {
  *mo = D->opts.min;
  mo->naive_guess = naive;
  mo->linear = BS_LIN_CG;
  if (mo->forcing_ew != 2) return BS_OK;
  int64_t inv = bs_fem_count_inverted(D->df->fem, D->x_n_m, NULL);
  int rc = bs_dist_sum_i64(&inv, 1, err);
  mo->forcing_ew = bs_step_forcing(2, inv);
  return rc;
}

static int run_solver(bs_dintegrator *D, double *x, int naive, bs_step_stats *st, bs_error *err) {
  int rc = gamg_prepare(D, err);
  if (rc) return rc;
  bs_minimize_opts mo;
  if ((rc = solve_opts(D, naive, &mo, err)) || (rc = bs_minimizer_set_opts(D->min, &mo, err))) return rc;
  bs_objective obj;
  bs__dstep_objective(D, &obj);
  obj.quadratic = bs_step_objective_quadratic(D->n_terms, D->terms, D->df->statics, D->hooks.project != NULL);
  if (mo.load_rtol > 0 && (rc = load_norm(D, x, &obj.load_norm, err))) return rc;
  D->cb_rc = 0;
  rc = bs_minimize(D->min, &obj, x, &st->min, err);
  if (!rc && D->cb_rc) {
    if (err) *err = D->cb_err;
    rc = D->cb_rc;
  }
  st->failed = !bs_min_reason_converged(st->min.reason);
  return rc;
}

/* x <- P(x) outside the minimizer (the guesses, the start of statics). */
static int project_now(bs_dintegrator *D, double *x, bs_error *err) {
  D->cb_rc = 0;
  bs__dstep_project(D, x);
  if (D->cb_rc && err) *err = D->cb_err;
  return D->cb_rc;
}

int bs_dintegrator_static(bs_dintegrator *D, double t, int load_steps, double *x, bs_step_stats *st, bs_error *err) {
  double t0 = bs_seconds();
  memset(st, 0, sizeof *st);
  int rc = check_finite(D, x, "position", err);
  if (rc) return rc;
  if (load_steps < 1) return bs_error_set(err, BS_EINPUT, "load_steps must be >= 1, got %d", load_steps);
  bs_dfem_set_terms(D->df, D->n_terms, D->terms, 1);
  D->step->dt = 0;
  D->step->time = t;
  memcpy(D->x_n, x, (size_t)D->df->n3 * sizeof(double));
  bs_dfem_mesh_vector(D->df, x, D->x_n_m);
  bs_dfem_mesh_vector(D->df, x, D->x_hat_m);
  if (D->script) D->script(t, x, D->script_ctx);
  rc = project_now(D, x, err);
  bs_step_stats sub;
  for (int l = 1; l <= load_steps && !rc; l++) {
    D->step->load = (double)l / load_steps;
    memset(&sub, 0, sizeof sub);
    if (!(rc = run_solver(D, x, 1, &sub, err))) bs_step_stats_add(st, &sub);
    if (sub.min.reason == BS_MIN_STOPPED) break; /* the later load steps are not taken */
  }
  bs_dfem_set_terms(D->df, D->n_terms, D->terms, 0);
  D->step->load = 1.0;
  st->seconds = bs_seconds() - t0;
  return rc;
}

/* ∇Φ(xⁿ) = −f(xⁿ) into D->grad: every term but inertia. */
static int potential_gradient(bs_dintegrator *D, bs_error *err) {
  double E;
  bs_dfem_set_terms(D->df, D->n_potential, D->potential, 0);
  int rc = bs_dfem_gradient(D->df, D->x_n, &E, D->grad, err);
  bs_dfem_set_terms(D->df, D->n_terms, D->terms, 0);
  if (rc > 0) return bs_error_set(err, BS_ENUMERIC, "a term is not evaluable at the positions of the step's start");
  return rc;
}

/* The two initial guesses (step 3 of bs_step.h) into g1 (x̂) and g2 (x̂ +
 * dt² M⁻¹ f), scripted vertices at their positions at t. */
static void guesses(bs_dintegrator *D, double t, double dt) {
  const int32_t nv = D->df->mesh->n_vertices;
  for (int32_t v = 0; v < nv; v++) {
    double c = D->mass[v] > 0 ? dt * dt / D->mass[v] : 0;
    for (int k = 0; k < 3; k++) D->g2[3 * v + k] = D->g1[3 * v + k] - c * D->grad[3 * v + k];
  }
  if (D->script) {
    D->script(t, D->g1, D->script_ctx);
    D->script(t, D->g2, D->script_ctx);
  }
  for (int32_t v = 0; v < nv; v++)
    if (!D->mask[v])
      for (int k = 0; k < 3; k++) {
        if (!D->script) D->g1[3 * v + k] = D->g2[3 * v + k] = D->x_n[3 * v + k];
        else D->g2[3 * v + k] = D->g1[3 * v + k];
      }
}

static double guess_energy(bs_dintegrator *D, const double *x, bs_error *err) {
  double E = NAN;
  int rc = bs_dfem_value(D->df, x, &E, err);
  return rc || !isfinite(E) ? INFINITY : E;
}

int bs_dintegrator_step(bs_dintegrator *D, double t, double dt, double *x, double *v, bs_step_stats *st,
                        bs_error *err) {
  double t0 = bs_seconds();
  memset(st, 0, sizeof *st);
  const size_t n3 = (size_t)D->df->n3;
  if (!(dt > 0) || !isfinite(dt)) return bs_error_set(err, BS_EINPUT, "time step must be positive and finite, got %g", dt);
  int rc = check_finite(D, x, "position", err);
  if (!rc) rc = check_finite(D, v, "velocity", err);
  if (rc) return rc;
  bs_dfem_set_terms(D->df, D->n_terms, D->terms, 0);
  D->step->dt = dt, D->step->time = t + dt, D->step->load = 1.0;
  memcpy(D->x_n, x, n3 * sizeof(double));
  for (size_t i = 0; i < n3; i++) D->g1[i] = x[i] + dt * v[i];
  bs_dfem_mesh_vector(D->df, D->x_n, D->x_n_m);
  bs_dfem_mesh_vector(D->df, D->g1, D->x_hat_m);
  for (int i = 0; i < D->n_terms; i++)
    if (D->terms[i]->ops->begin_step && (rc = D->terms[i]->ops->begin_step(D->terms[i], err))) return rc;
  if ((rc = potential_gradient(D, err))) return rc;
  guesses(D, t + dt, dt);
  if ((rc = project_now(D, D->g1, err)) || (rc = project_now(D, D->g2, err))) return rc;
  const double E1 = guess_energy(D, D->g1, err), E2 = guess_energy(D, D->g2, err);
  int naive = 1;
  if (isfinite(E2) && (!isfinite(E1) || E2 < E1)) {
    memcpy(x, D->g2, n3 * sizeof(double));
    st->guess = BS_GUESS_EXPLICIT;
    naive = 0;
  } else {
    memcpy(x, D->g1, n3 * sizeof(double));
  }
  if ((rc = run_solver(D, x, naive, st, err))) return rc;
  for (size_t i = 0; i < n3; i++) v[i] = (x[i] - D->x_n[i]) / dt;
  st->seconds = bs_seconds() - t0;
  return 0;
}
