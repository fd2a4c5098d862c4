/* trust_region.c — steps 4-9 of bs_minimize in a trust region: Steihaug's
 * truncated CG and the radius update of Nocedal & Wright, Algorithm 4.1
 * (bs__tr_iteration, see bs_minimize.h "Trust region"). */
#include "minimize_impl.h"

#include <math.h>
#include <string.h>

/* rho above which a trial step is taken (Algorithm 4.1's eta). */
#define BS_TR_ETA 1e-4

/* The trial direction m->d from Steihaug's CG in the current radius; when
 * it is not a descent direction, -Delta g / ||g||. Returns 0, or what
 * bs__newton_direction returns; *dg = g.d, *dn = ||d||. */
static int tr_direction(bs_minimizer *m, const bs_objective *obj, const double *x, double gnorm, int it,
                        bs_minimize_stats *st, bs_min_iter *rec, double *dg, double *dn, bs_error *err) {
  int rc = bs_linsolve_set_radius(m->lin[m->opts.linear], m->tr_radius, err);
  if (rc) return rc;
  rc = bs__newton_direction(m, obj, x, gnorm, it, st, rec, err);
  if (rc) return rc;
  *dg = bs__mdot(m, m->d, m->g);
  *dn = sqrt(bs__mdot(m, m->d, m->d));
  rec->direction = BS_DIR_NEWTON;
  if (isfinite(*dg) && isfinite(*dn) && *dn > 0 && *dg < 0) return 0;
  const double s = m->tr_radius / gnorm;
  for (int64_t i = 0; i < m->n3; ++i) m->d[i] = -s * m->g[i];
  *dg = -gnorm * m->tr_radius;
  *dn = m->tr_radius;
  rec->direction = BS_DIR_NEG_GRAD;
  rec->lin_boundary = 1;
  st->fallback_neg_grad++;
  return 0;
}

/* The decrease of the quadratic model along m->d: -(g.d + d.H d / 2), H d
 * into m->gy (scratch until the trial point's gradient). */
static double model_decrease(bs_minimizer *m, const bs_objective *obj, double dg) {
  bs_bsr_mul(m->H, obj->mask, m->d, m->gy);
  return -(dg + 0.5 * bs__mdot(m, m->d, m->gy));
}

/* E at the trial point m->y = P(x + d) (fixed dofs kept), its raw gradient
 * in m->gy_raw; +Inf when not evaluable. */
static double trial_energy(bs_minimizer *m, const bs_objective *obj, const double *x, bs_minimize_stats *st) {
  for (int64_t i = 0; i < m->n3; ++i) m->y[i] = x[i] + m->d[i];
  bs__restore_fixed(obj->n, obj->mask, x, m->y);
  bs__project(obj, m->y, x, st);
  double Ey = INFINITY;
  int64_t bad;
  if (bs__gradient(m, obj, m->y, &Ey, m->gy_raw, &bad, st) || !isfinite(Ey)) Ey = INFINITY;
  st->ls_evaluations++;
  return Ey;
}

/* The step bound (bs_minimize.h "Step bound"): a trial step m->d longer
 * than obj->max_step allows is scaled to it (*dg, *dn follow). */
static void bound_trial(bs_minimizer *m, const bs_objective *obj, const double *x, bs_minimize_stats *st,
                        bs_min_iter *rec, double *dg, double *dn) {
  if (!obj->max_step) return;
  const double a = rec->alpha_bound = bs__step_bound(m, obj, x, st);
  if (!(a < 1)) return;
  rec->alpha_bound = 1.0; /* along the scaled step */
  for (int64_t i = 0; i < m->n3; ++i) m->d[i] *= a;
  *dg *= a;
  *dn *= a;
  st->ccd_limited++;
}

/* Algorithm 4.1's radius update for a trial step of length dn. */
static void update_radius(bs_minimizer *m, double rho, double dn, int on_boundary) {
  if (!(rho >= 0.25)) m->tr_radius = 0.25 * fmin(m->tr_radius, dn);
  else if (rho > 0.75 && on_boundary) m->tr_radius = fmin(2.0 * m->tr_radius, m->opts.clamp);
}

/* The step to y taken: trace, then x <- y. */
static void take(bs_minimizer *m, const bs_objective *obj, double *x, double *E, double Ey, double dg, int trials,
                 bs_minimize_stats *st, bs_min_iter *rec) {
  const bs__ls_result ls = {.status = BS_LSEARCH_WOLFE, .evals = trials, .alpha = 1.0, .phi = Ey, .dphi = NAN};
  if (obj->trace) bs__trace_step(m, obj, x, *E, dg, &ls, rec);
  memcpy(x, m->y, sizeof(double) * (size_t)m->n3);
  memcpy(m->g_raw, m->gy_raw, sizeof(double) * (size_t)m->n3);
  *E = Ey;
  st->iterations++;
  st->alpha_last = st->alpha_min = st->alpha_max = 1.0;
  st->tr_boundary += rec->lin_boundary;
  st->tr_radius = m->tr_radius;
  m->last_full = trials == 1 && rec->direction == BS_DIR_NEWTON && !rec->lin_indefinite && !rec->lin_boundary;
}

int bs__tr_iteration(bs_minimizer *m, const bs_objective *obj, double *x, double *E, double gnorm, int it,
                     bs_minimize_stats *st, bs_min_iter *rec, bs_error *err) {
  const bs_minimize_opts *o = &m->opts;
  if (m->has_vops)
    return bs_error_set(err, BS_EINPUT, "minimizer: globalization trust_region is not available with vecops "
                                        "(the distributed backend); use line_search");
  if (it == 0) /* Delta_0: tr_radius RMS per free vertex */
    m->tr_radius = fmin(o->tr_radius * sqrt((double)(m->free_vertices > 0 ? m->free_vertices : 1)), o->clamp);
  for (int trial = 1;; ++trial) {
    double dg, dn;
    int rc = tr_direction(m, obj, x, gnorm, it, st, rec, &dg, &dn, err);
    if (rc) return rc;
    if (trial == 1 && bs__at_floor(m, obj, st, it, *E, gnorm, dg, rec->direction)) return 1;
    bound_trial(m, obj, x, st, rec, &dg, &dn);
    const double pred = model_decrease(m, obj, dg), Ey = trial_energy(m, obj, x, st);
    const double actual = *E - Ey;
    const double rho = pred > 0 ? actual / pred : (actual > 0 ? 1.0 : -1.0);
    const int on_boundary = rec->lin_boundary;
    update_radius(m, rho, dn, on_boundary);
    if (rho > BS_TR_ETA && isfinite(Ey)) {
      take(m, obj, x, E, Ey, dg, trial, st, rec);
      return 0;
    }
    st->tr_rejections++;
    st->tr_radius = m->tr_radius;
    if (trial < o->max_ls) continue;
    if (-dg <= bs__noise_level(*E) && rec->direction != BS_DIR_NEG_GRAD)
      bs__set_reason(m, st, BS_MIN_FLOOR,
                     "converged at the rounding floor of E after %d iterations: no decrease in %d trust-region "
                     "steps, the predicted decrease |g.d| = %.3e is below the rounding level %.3e of E = %.9e "
                     "(|grad E| = %.3e, tol %.3e)",
                     it, trial, -dg, bs__noise_level(*E), *E, gnorm, m->tau);
    else
      bs__set_reason(m, st, BS_MIN_LINE_SEARCH,
                     "no decrease of E in %d trust-region steps at iteration %d (radius down to %.3e, "
                     "|grad E| = %.3e, E = %.9e)",
                     trial, it, m->tr_radius, gnorm, *E);
    return 1;
  }
}
