/* newton.c — the baseline of the paper's section 2: Newton's method as a
 * root-finder of h(x) = grad E(x), x <- x - H^-1 h, with MINRES (which accepts
 * indefinite H) to the tight relative tolerance opts.newton_rel_tol, no line
 * search, no clamp, no definiteness correction. See bs_minimize.h. */
#include <math.h>
#include <string.h>

#include "minimize_impl.h"

/* MINRES's cap: cg_max_iter, or min(2 N + 100, 100 + 20 sqrt(N)) for N free
 * dofs (a solve needing more is not converging: the step takes its best
 * iterate). */
static int minres_cap(const bs_minimizer *m, const bs_objective *obj) {
  if (m->opts.cg_max_iter > 0) return m->opts.cg_max_iter;
  int64_t free_dofs = 0;
  for (int32_t v = 0; v < m->n; ++v) free_dofs += (!obj->mask || obj->mask[v]) ? 3 : 0;
  const double cap = fmin(2.0 * (double)free_dofs + 100, 100 + 20 * sqrt((double)free_dofs));
  return (int)fmin(cap, 1e9);
}

/* The divergence watch of one solve: the smallest ||g|| so far, and the one
 * BS_NEWTON_WINDOW iterations ago. */
typedef struct watch {
  double g_min, g_min_at[BS_NEWTON_WINDOW];
} watch;

/* 1 (and the reason set) when iteration it at ||g|| = gnorm ends the solve:
 * converged, the cap, or diverged (bs_minimize.h). */
static int stop_here(bs_minimizer *m, const bs_objective *obj, bs_minimize_stats *st, watch *w, int k_steps, int it,
                     double gnorm) {
  const bs_minimize_opts *o = &m->opts;
  if (it == 0) st->tol_used = m->tau = bs__tolerance(o, obj, gnorm);
  const double tol = m->tau;
  if (k_steps > 0) {
    if (it < k_steps) return 0;
    if (gnorm < tol)
      bs__set_reason(m, st, BS_MIN_CONVERGED, "|grad E| = %.3e < tol %.3e after %d Newton steps", gnorm, tol, it);
    else
      bs__set_reason(m, st, BS_MIN_STEPS_DONE, "%d Newton steps taken, |grad E| = %.3e (tol %.3e)", it, gnorm, tol);
    return 1;
  }
  if (gnorm < tol) {
    bs__set_reason(m, st, BS_MIN_CONVERGED, "|grad E| = %.3e < tol %.3e after %d Newton iterations", gnorm, tol, it);
    return 1;
  }
  if (it == 0 || gnorm < w->g_min) w->g_min = gnorm;
  const double before = w->g_min_at[it % BS_NEWTON_WINDOW];
  w->g_min_at[it % BS_NEWTON_WINDOW] = w->g_min;
  if (gnorm > BS_NEWTON_GROWTH * w->g_min) {
    bs__set_reason(m, st, BS_MIN_DIVERGED, "|grad E| = %.3e at iteration %d, %.0fx its smallest %.3e", gnorm,
                   it, gnorm / w->g_min, w->g_min);
    return 1;
  }
  if (it >= BS_NEWTON_WINDOW && !(w->g_min <= 0.5 * before)) {
    bs__set_reason(m, st, BS_MIN_DIVERGED, "the smallest |grad E| (%.3e) did not halve over %d iterations",
                   w->g_min, BS_NEWTON_WINDOW);
    return 1;
  }
  if (bs__stopped(m, st, it, gnorm)) return 1;
  if (it >= o->newton_max_iter || it >= o->max_iter) {
    bs__set_reason(m, st, BS_MIN_MAX_ITER, "|grad E| = %.3e >= tol %.3e after %d Newton iterations", gnorm, tol, it);
    return 1;
  }
  return 0;
}

/* E and the (constrained) gradient at x into m->g; 1 (reason set) when not finite. */
static int newton_gradient(bs_minimizer *m, const bs_objective *obj, const double *x, int it, double *gnorm,
                           bs_minimize_stats *st) {
  double E = NAN;
  int64_t bad;
  if (bs__gradient(m, obj, x, &E, m->g_raw, &bad, st) || !isfinite(E)) {
    st->E = E;
    st->grad_norm = NAN;
    if (bad >= 0 && !isfinite(m->g_raw[bad]))
      bs__set_reason(m, st, BS_MIN_NONFINITE, "gradient not finite at iteration %d: vertex %lld component %d (%g)", it,
                     (long long)(bad / 3), (int)(bad % 3), m->g_raw[bad]);
    else bs__set_reason(m, st, BS_MIN_NONFINITE, "objective not evaluable at iteration %d (E = %g)", it, E);
    return 1;
  }
  *gnorm = bs__constrained_gradient(m, obj, x, m->g_raw, m->g, st, 1);
  st->E = E;
  st->grad_norm = *gnorm;
  if (!isfinite(*gnorm)) {
    bs__set_reason(m, st, BS_MIN_NONFINITE, "|grad E| not finite at iteration %d", it);
    return 1;
  }
  return 0;
}

static void newton_trace(const bs_objective *obj, const bs_minimizer *m, int it, int lin_it, double gnorm,
                         double E, const double *x) {
  bs_min_iter rec; /* the full step: no line search, E(y) not evaluated */
  memset(&rec, 0, sizeof rec);
  rec.iteration = it;
  rec.lin_iterations = lin_it;
  rec.grad_norm = gnorm;
  rec.lin_rel_tol = m->opts.newton_rel_tol;
  rec.alpha = 1.0;
  rec.phi0 = E;
  rec.phi = rec.dphi0 = rec.dphi = NAN;
  rec.x = x;
  rec.d = m->d;
  rec.y = m->y;
  obj->trace(&rec, obj->ctx);
}

/* One Newton step from x (m->g holds the gradient): H d = -g by MINRES, then
 * y = P(x + d). 0 with m->y set; 1 with the reason set (not finite); < 0 the
 * status of an error (BS_E*), in err. */
static int newton_step(bs_minimizer *m, const bs_objective *obj, const double *x, int it, int max_it, double gnorm,
                       bs_minimize_stats *st, int *lin_it, bs_error *err) {
  const int64_t N = m->n3;
  double t = bs_seconds();
  int hrc = obj->hessian_g ? obj->hessian_g(x, m->g_raw, m->H, obj->ctx) : obj->hessian(x, m->H, obj->ctx);
  if (!hrc) bs_bsr_index_extra(m->H);
  st->t_assembly += bs_seconds() - t;
  if (hrc) {
    bs__set_reason(m, st, BS_MIN_NONFINITE, "Hessian not evaluable at iteration %d (callback returned %d)", it, hrc);
    return 1;
  }
  for (int64_t i = 0; i < N; ++i) m->r[i] = -m->g[i];
  bs_lin_stats ls;
  memset(&ls, 0, sizeof ls);
  bs_error e2;
  bs_error_clear(&e2);
  t = bs_seconds();
  int rc = bs_linsolve_solve(m->lin[BS_LIN_MINRES], m->H, obj->mask, m->r, m->opts.newton_rel_tol, max_it, m->d, &ls,
                             &e2);
  st->t_linear += bs_seconds() - t;
  if ((rc = bs__solve_outcome(m, st, rc, &e2, it, "Newton", "minres", err))) return rc;
  st->cg_iterations += ls.iterations;
  *lin_it = ls.iterations;
  if (obj->max_step) { /* the step bound (bs_minimize.h): min(1, alpha_max) of the step */
    const double a = bs__step_bound(m, obj, x, st);
    if (a < 1) {
      for (int64_t i = 0; i < N; ++i) m->d[i] *= a;
      st->ccd_limited++;
    }
  }
  for (int64_t i = 0; i < N; ++i) m->y[i] = x[i] + m->d[i];
  bs__project(obj, m->y, x, st);
  const int64_t bad = bs__first_nonfinite(m->n, obj->mask, m->y);
  if (bad >= 0) {
    bs__set_reason(m, st, BS_MIN_NONFINITE, "Newton iterate %d not finite at vertex %lld component %d (|grad E| was %.3e)",
                   it + 1, (long long)(bad / 3), (int)(bad % 3), gnorm);
    return 1;
  }
  return 0;
}

int bs_newton(bs_minimizer *m, const bs_objective *obj, int k_steps, double *x, bs_minimize_stats *st_out,
              bs_error *err) {
  double t_start = bs_seconds();
  bs_minimize_stats local, *st = st_out ? st_out : &local;
  memset(st, 0, sizeof *st);
  int rc = bs__obj_check(m, obj, x, err);
  if (rc) return rc;
  if (k_steps < 0) return bs_error_set(err, BS_EINPUT, "bs_newton: k_steps must be >= 0, got %d", k_steps);
  const int64_t N = m->n3;
  if (N == 0) { /* nothing to move */
    bs__set_reason(m, st, BS_MIN_CONVERGED, "no unknowns");
    st->t_total = bs_seconds() - t_start;
    return 0;
  }
  const int max_it = minres_cap(m, obj);
  if (obj->project) {
    memcpy(m->y, x, sizeof(double) * (size_t)N);
    bs__project(obj, x, m->y, st);
  }
  watch w = {0};
  for (int it = 0;; ++it) {
    double gnorm = NAN;
    int lin_it = 0;
    if (newton_gradient(m, obj, x, it, &gnorm, st) || stop_here(m, obj, st, &w, k_steps, it, gnorm)) break;
    rc = newton_step(m, obj, x, it, max_it, gnorm, st, &lin_it, err);
    if (rc < 0) return rc;
    if (rc > 0) break;
    if (obj->trace) newton_trace(obj, m, it, lin_it, gnorm, st->E, x);
    memcpy(x, m->y, sizeof(double) * (size_t)N);
    st->iterations++;
    st->alpha_last = st->alpha_min = st->alpha_max = 1.0;
  }
  st->t_total = bs_seconds() - t_start;
  return 0;
}
