/* linesearch.c — strong Wolfe line search (Nocedal & Wright, Numerical
 * Optimization, 2nd ed., Algorithm 3.5 with the zoom of Algorithm 3.6) along
 * the projected curve a -> P(x + a d) (paper, sections 3.1 and 3.2).
 *
 *   phi(a)  = E(P(x + a d))            (+Inf where E is not evaluable/finite)
 *   phi'(a) = grad E(P(x + a d)) . d   (masked, project_gradient applied)
 *   sufficient decrease: phi(a) <= phi(0) + c1 a phi'(0)
 *   curvature (strong):  |phi'(a)| <= c2 |phi'(0)|
 */
#include <float.h>
#include <math.h>
#include <string.h>

#include "minimize_impl.h"

#define ALPHA_MAX 1e10 /* largest step length the extrapolation may try */

/* Minimizer of the cubic matching f and f' at a and b (N&W eq. 3.59); NaN if
 * the cubic has no local minimizer or the data are degenerate. */
static double cubic_min(double a, double fa, double da, double b, double fb, double db) {
  if (a == b) return NAN;
  double d1 = da + db - 3.0 * (fa - fb) / (a - b);
  double disc = d1 * d1 - da * db;
  if (!(disc >= 0)) return NAN;
  double d2 = copysign(sqrt(disc), b - a);
  double den = db - da + 2.0 * d2;
  if (den == 0) return NAN;
  double c = b - (b - a) * (db + d2 - d1) / den;
  return isfinite(c) ? c : NAN;
}

/* Line-search state: what m->y / m->gy currently hold. */
typedef struct {
  bs_minimizer *m;
  const bs_objective *obj;
  const double *x;
  bs_minimize_stats *st;
  double phi0;
  double a_top;   /* largest trial step: min(ALPHA_MAX, the step bound) */
  int bounded;    /* 1: a_top is the step bound (obj->max_step)      */
  int limited;    /* 1: the bound shortened a trial step             */
  double cur_a;   /* alpha whose point m->y holds (NaN: none)       */
  int cur_grad;   /* 1: m->gy_raw / m->gy belong to that point      */
} ls_state;

/* Sets m->y = P(x + a d) with the fixed dofs of x. */
static void make_point(ls_state *s, double a) {
  bs_minimizer *m = s->m;
  const double *x = s->x, *d = m->d;
  const int64_t N = m->n3;
#pragma omp parallel for schedule(static) if (N > 16384)
  for (int64_t i = 0; i < N; ++i) m->y[i] = x[i] + a * d[i];
  bs__project(s->obj, m->y, x, s->st);
  s->cur_a = a;
  s->cur_grad = 0;
}

/* Gradient at the point in m->y: returns phi (+Inf if not evaluable) and the
 * slope in *dphi. */
static double grad_here(ls_state *s, double *dphi) {
  bs_minimizer *m = s->m;
  double E = NAN;
  int64_t bad;
  if (bs__gradient(m, s->obj, m->y, &E, m->gy_raw, &bad, s->st)) {
    *dphi = NAN;
    return INFINITY;
  }
  bs__constrained_gradient(m, s->obj, m->y, m->gy_raw, m->gy, s->st, 0);
  double sl = bs__mdot(m, m->gy, m->d);
  if (!isfinite(sl)) {
    *dphi = NAN;
    return INFINITY;
  }
  *dphi = sl;
  s->cur_grad = 1;
  return E;
}

/* One trial point. The lower bound (if any) is consulted first: when it exceeds
 * phi(0) the point cannot satisfy sufficient decrease and the bound is returned
 * as phi without calling value() or gradient(). Otherwise want_grad selects
 * gradient() (phi and phi') or value() (phi only). *has_grad tells whether
 * *dphi is valid. */
static double trial(ls_state *s, double a, int want_grad, int *has_grad, double *dphi) {
  bs_minimizer *m = s->m;
  const bs_objective *obj = s->obj;
  make_point(s, a);
  *has_grad = 0;
  *dphi = NAN;
  if (obj->value_lower_bound) {
    double lb, t = bs_seconds();
    int rc = obj->value_lower_bound(m->y, &lb, obj->ctx);
    s->st->t_eval += bs_seconds() - t;
    if (rc != 0 || isnan(lb)) return INFINITY;
    if (lb > s->phi0) return lb;
  }
  if (want_grad) {
    double phi = grad_here(s, dphi);
    *has_grad = s->cur_grad;
    return phi;
  }
  double E, t = bs_seconds();
  int rc = obj->value(m->y, &E, obj->ctx);
  s->st->t_eval += bs_seconds() - t;
  if (rc != 0 || !isfinite(E)) return INFINITY;
  return E;
}

/* Rounding-level search (opts.accept_noise; paper 3.3): when the decrease the
 * direction predicts, |phi'(0)|, is below the rounding level of E, values of
 * phi cannot rank trial points, but slopes still can. Hager and Zhang's
 * approximate Wolfe conditions (SIAM J. Optim. 16, 2005, with delta = 0.1 and
 * sigma = c2) ask only
 *     phi(a) <= phi(0) + noise  and  c2 phi'(0) <= phi'(a) <= (2 delta - 1) phi'(0),
 * a point where the slope has fallen by the factor c2 without overshooting
 * far. The bracket on the slope's sign is narrowed by the secant of phi'
 * (kept 10% inside the bracket, else bisection); a = 1 first, doubling while
 * the slope stays steep and no upper end is known (never beyond s->a_top:
 * min(1, a_top) first, the doubling stops there). Gradients are evaluated at
 * every trial point (no lower-bound shortcut: these searches are rare and
 * short). Returns 1 with res filled when a point is found within the budget. */
static int noise_search(ls_state *s, double dphi0, int budget, int *evals, bs__ls_result *res) {
  const double c2 = s->m->opts.c2, noise = bs__noise_level(s->phi0);
  const double up = -0.8 * dphi0, down = c2 * dphi0; /* accept phi' in [down, up] */
  double lo = 0, dlo = dphi0, hi = NAN, dhi = NAN, a = fmin(1.0, s->a_top);
  for (int k = 0; k < budget; ++k) {
    double dphi;
    make_point(s, a);
    const double phi = grad_here(s, &dphi);
    ++*evals;
    if (!(phi <= s->phi0 + noise) || !isfinite(dphi) || dphi > up) {
      hi = a, dhi = isfinite(dphi) && phi <= s->phi0 + noise ? dphi : NAN;
    } else if (dphi < down) {
      lo = a, dlo = dphi;
    } else {
      res->status = BS_LSEARCH_NOISE;
      res->alpha = a;
      res->phi = phi;
      res->dphi = dphi;
      return 1;
    }
    if (isnan(hi)) {
      const double a_was = a;
      a = 2 * a;
      if (a > s->a_top) {
        if (!s->bounded || a_was >= s->a_top) return 0;
        a = s->a_top;
        s->limited = 1;
      }
      continue;
    }
    const double w = hi - lo;
    if (!(w > 4.0 * DBL_EPSILON * hi)) return 0;
    double c = isfinite(dhi) && dhi != dlo ? lo - dlo * w / (dhi - dlo) : NAN;
    a = isfinite(c) ? fmin(fmax(c, lo + 0.1 * w), hi - 0.1 * w) : lo + 0.5 * w;
  }
  return 0;
}

void bs__line_search(bs_minimizer *m, const bs_objective *obj, const double *x, double phi0, double dphi0,
                     double amax, bs_minimize_stats *st, bs__ls_result *res) {
  const bs_minimize_opts *o = &m->opts;
  const double c1 = o->c1, c2 = o->c2;
  if (!(amax >= 0)) amax = 0;
  ls_state s = {m, obj, x, st, phi0, fmin(ALPHA_MAX, amax), amax < ALPHA_MAX, amax < 1.0, NAN, 0};
  int evals = 0;
  double best_a = 0, best_phi = phi0; /* lowest trial value below phi(0) */
  double acc_a = 0, acc_phi = 0, acc_dphi = 0;
  double lo = 0, phi_lo = phi0, dphi_lo = dphi0;
  double hi = 0, phi_hi = 0, dphi_hi = 0;
  int hi_d = 0;
  memset(res, 0, sizeof *res);
  res->status = BS_LSEARCH_NO_DECREASE;
  res->bound = amax;
  res->limited = s.limited;
  if (!(s.a_top > 0)) return; /* the bound allows no step */

#define NOTE_BEST(a_, phi_)                                                                                           \
  do {                                                                                                                \
    if ((phi_) < best_phi) {                                                                                          \
      best_phi = (phi_);                                                                                              \
      best_a = (a_);                                                                                                  \
    }                                                                                                                 \
  } while (0)

  /* Algorithm 3.5: bracketing, a_1 = 1 first (the bound if below 1),
   * growing while the slope stays negative and too steep, up to the bound. */
  double a_prev = 0, phi_prev = phi0, dphi_prev = dphi0, a = fmin(1.0, s.a_top);
  for (int i = 0;; ++i) {
    if (evals >= o->max_ls) goto capped;
    int hg;
    double dphi, phi = trial(&s, a, 1, &hg, &dphi);
    ++evals;
    if (hg) NOTE_BEST(a, phi);
    if (i == 0 && o->accept_noise && !(phi <= phi0 + c1 * a * dphi0) && -dphi0 <= bs__noise_level(phi0)) {
      /* E cannot resolve the decrease this step predicts (paper 3.3): search
       * on the slope (approximate Wolfe conditions) instead. */
      if (noise_search(&s, dphi0, o->max_ls - evals, &evals, res)) {
        res->evals = evals;
        res->limited = s.limited;
        return;
      }
      /* None found: the trial points stay what they were (phi(1) is the
       * one the bracket below starts from). */
      if (evals >= o->max_ls) goto capped;
    }
    if (!(phi <= phi0 + c1 * a * dphi0) || (i > 0 && phi >= phi_prev)) {
      lo = a_prev, phi_lo = phi_prev, dphi_lo = dphi_prev;
      hi = a, phi_hi = phi, dphi_hi = dphi, hi_d = hg;
      break;
    }
    /* Sufficient decrease holds with a finite phi: the gradient was evaluated. */
    if (fabs(dphi) <= -c2 * dphi0) {
      acc_a = a, acc_phi = phi, acc_dphi = dphi;
      goto accept;
    }
    if (dphi >= 0) {
      lo = a, phi_lo = phi, dphi_lo = dphi;
      hi = a_prev, phi_hi = phi_prev, dphi_hi = dphi_prev, hi_d = 1;
      break;
    }
    if (a >= s.a_top) {
      if (!s.bounded) goto capped;
      acc_a = a, acc_phi = phi, acc_dphi = dphi; /* the bound, E still falling steeply */
      res->status = BS_LSEARCH_BOUND;
      goto taken;
    }
    /* Extrapolate: cubic minimizer kept in [a + (a - a_prev)/2, a + 10 (a - a_prev)]. */
    double w = a - a_prev, c = cubic_min(a_prev, phi_prev, dphi_prev, a, phi, dphi), a_next;
    if (isfinite(c) && c > a) a_next = fmin(fmax(c, a + 0.5 * w), a + 10.0 * w);
    else a_next = a + 4.0 * w;
    a_prev = a, phi_prev = phi, dphi_prev = dphi;
    if (s.bounded && a_next > s.a_top) s.limited = 1;
    a = fmin(a_next, s.a_top);
  }

  /* Algorithm 3.6: zoom in the bracket (lo, hi); lo satisfies sufficient
   * decrease with the lowest value so far, and dphi_lo (hi - lo) < 0. */
  for (;;) {
    if (evals >= o->max_ls) goto capped;
    double al = fmin(lo, hi), ah = fmax(lo, hi), w = ah - al;
    if (!(w > 4.0 * DBL_EPSILON * ah)) goto capped; /* the bracket collapsed */
    double aj = NAN;
    if (hi_d && isfinite(phi_hi)) {
      aj = cubic_min(lo, phi_lo, dphi_lo, hi, phi_hi, dphi_hi);
    } else if (isfinite(phi_hi)) { /* quadratic through phi(lo), phi'(lo), phi(hi) */
      double h = hi - lo, den = 2.0 * (phi_hi - phi_lo - dphi_lo * h);
      if (den > 0) aj = lo - dphi_lo * h * h / den;
    }
    if (isfinite(aj)) aj = fmin(fmax(aj, al + 0.1 * w), ah - 0.1 * w); /* safeguard */
    else aj = 0.5 * (lo + hi);                                          /* bisection */
    int hg;
    double dphi, phi = trial(&s, aj, 0, &hg, &dphi);
    ++evals;
    if (!(phi <= phi0 + c1 * aj * dphi0) || phi >= phi_lo) {
      NOTE_BEST(aj, phi); /* may still lie below phi(0): a fallback if the cap is hit */
      hi = aj, phi_hi = phi, hi_d = 0;
      continue;
    }
    phi = grad_here(&s, &dphi);
    if (!(phi <= phi0 + c1 * aj * dphi0) || phi >= phi_lo) { /* gradient() disagreed with value() */
      hi = aj, phi_hi = phi, dphi_hi = dphi, hi_d = s.cur_grad;
      continue;
    }
    NOTE_BEST(aj, phi);
    if (fabs(dphi) <= -c2 * dphi0) {
      acc_a = aj, acc_phi = phi, acc_dphi = dphi;
      goto accept;
    }
    if (dphi * (hi - lo) >= 0) hi = lo, phi_hi = phi_lo, dphi_hi = dphi_lo, hi_d = 1;
    lo = aj, phi_lo = phi, dphi_lo = dphi;
  }

capped:
  /* No Wolfe point within the cap: the lowest decreasing point, if any. */
  res->evals = evals;
  res->limited = s.limited;
  if (!(best_phi < phi0)) return;
  if (!(s.cur_a == best_a && s.cur_grad)) {
    double dphi;
    make_point(&s, best_a);
    double phi = grad_here(&s, &dphi);
    if (!(phi < phi0)) return; /* not reproducible: treat as no decrease */
    best_phi = phi;
    res->dphi = dphi;
  } else {
    res->dphi = bs__mdot(m, m->gy, m->d);
  }
  res->status = BS_LSEARCH_CAPPED;
  res->alpha = best_a;
  res->phi = best_phi;
  return;

accept:
  res->status = BS_LSEARCH_WOLFE;
taken:
  res->evals = evals;
  res->limited = s.limited;
  res->alpha = acc_a;
  res->phi = acc_phi;
  res->dphi = acc_dphi;
#undef NOTE_BEST
}
