/* newton.c — the baseline of the paper's section 2: Newton's method as a
 * root-finder of h(x) = grad E(x), x <- x - H^-1 h, with MINRES (which accepts
 * indefinite H) to the tight relative tolerance opts.newton_rel_tol, no line
 * search, no clamp, no definiteness correction. See bs_minimize.h. */
#include <math.h>
#include <string.h>

#include "minimize_impl.h"

int bs_newton(bs_minimizer *m, const bs_objective *obj, int k_steps, double *x, bs_minimize_stats *st_out,
              bs_error *err) {
  double t_start = bs_seconds();
  bs_minimize_stats local, *st = st_out ? st_out : &local;
  memset(st, 0, sizeof *st);
  int rc = bs__obj_check(m, obj, x, err);
  if (rc) return rc;
  if (k_steps < 0) return bs_error_set(err, BS_EINPUT, "bs_newton: k_steps must be >= 0, got %d", k_steps);
  const bs_minimize_opts *o = &m->opts;
  const int64_t N = m->n3;
  if (N == 0) { /* nothing to move */
    bs__set_reason(m, st, BS_MIN_CONVERGED, "no unknowns");
    st->t_total = bs_seconds() - t_start;
    return 0;
  }
  int64_t free_dofs = 0;
  for (int32_t v = 0; v < m->n; ++v) free_dofs += (!obj->mask || obj->mask[v]) ? 3 : 0;
  /* MINRES may need more than the dimension in floating point: allow 2x + 100. */
  int64_t auto_it = 2 * free_dofs + 100;
  int max_it = o->cg_max_iter > 0 ? o->cg_max_iter : (int)(auto_it > 1000000000 ? 1000000000 : auto_it);

  if (obj->project) {
    memcpy(m->y, x, sizeof(double) * (size_t)N);
    bs__project(obj, x, m->y, st);
  }
  for (int it = 0;; ++it) {
    double E = NAN;
    int64_t bad;
    if (bs__gradient(m, obj, x, &E, m->g_raw, &bad, st)) {
      st->E = E;
      st->grad_norm = NAN;
      if (bad >= 0)
        bs__set_reason(m, st, BS_MIN_NONFINITE, "gradient not finite at iteration %d: vertex %lld component %d (%g)",
                       it, (long long)(bad / 3), (int)(bad % 3), m->g_raw[bad]);
      else bs__set_reason(m, st, BS_MIN_NONFINITE, "objective not evaluable at iteration %d (E = %g)", it, E);
      break;
    }
    double gnorm = bs__constrained_gradient(m, obj, x, m->g_raw, m->g, st, 1);
    st->E = E;
    st->grad_norm = gnorm;
    if (k_steps > 0) {
      if (it == k_steps) {
        if (gnorm < o->tol)
          bs__set_reason(m, st, BS_MIN_CONVERGED, "|grad E| = %.3e < tol %.3e after %d Newton steps", gnorm, o->tol,
                         it);
        else
          bs__set_reason(m, st, BS_MIN_STEPS_DONE, "%d Newton steps taken, |grad E| = %.3e (tol %.3e)", it, gnorm,
                         o->tol);
        break;
      }
    } else {
      if (gnorm < o->tol) {
        bs__set_reason(m, st, BS_MIN_CONVERGED, "|grad E| = %.3e < tol %.3e after %d Newton iterations", gnorm,
                       o->tol, it);
        break;
      }
      if (it >= o->max_iter) {
        bs__set_reason(m, st, BS_MIN_MAX_ITER, "|grad E| = %.3e >= tol %.3e after %d Newton iterations", gnorm,
                       o->tol, it);
        break;
      }
    }
    double t = bs_seconds();
    int hrc = obj->hessian_g ? obj->hessian_g(x, m->g_raw, m->H, obj->ctx) : obj->hessian(x, m->H, obj->ctx);
    st->t_assembly += bs_seconds() - t;
    if (hrc) {
      bs__set_reason(m, st, BS_MIN_NONFINITE, "Hessian not evaluable at iteration %d (callback returned %d)", it, hrc);
      break;
    }
    for (int64_t i = 0; i < N; ++i) m->r[i] = -m->g[i];
    bs_lin_stats ls;
    memset(&ls, 0, sizeof ls);
    bs_error e2;
    bs_error_clear(&e2);
    t = bs_seconds();
    rc = bs_linsolve_solve(m->lin[BS_LIN_MINRES], m->H, obj->mask, m->r, o->newton_rel_tol, max_it, m->d, &ls, &e2);
    st->t_linear += bs_seconds() - t;
    if (rc == BS_ENUMERIC) {
      bs__set_reason(m, st, BS_MIN_NONFINITE, "Newton system not finite at iteration %d (%s)", it, e2.msg);
      break;
    }
    if (rc) {
      if (err) *err = e2;
      bs_error_prefix(err, "Newton iteration %d: minres solve", it);
      return rc;
    }
    st->cg_iterations += ls.iterations;
    /* x <- P(x + dx); a non-finite iterate ends the solve with x unchanged. */
    for (int64_t i = 0; i < N; ++i) m->y[i] = x[i] + m->d[i];
    bs__project(obj, m->y, x, st);
    bad = bs__first_nonfinite(m->n, obj->mask, m->y);
    if (bad >= 0) {
      bs__set_reason(m, st, BS_MIN_NONFINITE,
                     "Newton iterate %d not finite at vertex %lld component %d (|grad E| was %.3e)", it + 1,
                     (long long)(bad / 3), (int)(bad % 3), gnorm);
      break;
    }
    if (obj->trace) { /* the full step: no line search, E(y) not evaluated */
      bs_min_iter rec;
      memset(&rec, 0, sizeof rec);
      rec.iteration = it;
      rec.lin_iterations = ls.iterations;
      rec.grad_norm = gnorm;
      rec.lin_rel_tol = o->newton_rel_tol;
      rec.alpha = 1.0;
      rec.phi0 = E;
      rec.phi = rec.dphi0 = rec.dphi = NAN;
      rec.x = x;
      rec.d = m->d;
      rec.y = m->y;
      obj->trace(&rec, obj->ctx);
    }
    memcpy(x, m->y, sizeof(double) * (size_t)N);
    st->iterations++;
    st->alpha_last = st->alpha_min = st->alpha_max = 1.0;
  }
  st->t_total = bs_seconds() - t_start;
  return 0;
}
