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

/* The search's bracket and outcomes (Algorithms 3.5 and 3.6). */
typedef struct {
  ls_state s;
  double phi0, dphi0, c1, c2;
  int evals, max_ls;
  double best_a, best_phi;          /* lowest trial value below phi(0)   */
  double acc_a, acc_phi, acc_dphi;  /* the accepted point                */
  double lo, phi_lo, dphi_lo;
  double hi, phi_hi, dphi_hi;
  int hi_d;                         /* 1: dphi_hi is known               */
} ls_search;

typedef enum { LS_BRACKETED, LS_ACCEPT, LS_BOUND, LS_CAPPED, LS_NOISE_DONE } ls_outcome;

static void note_best(ls_search *q, double a, double phi) {
  if (phi < q->best_phi) {
    q->best_phi = phi;
    q->best_a = a;
  }
}

static ls_outcome accept_at(ls_search *q, double a, double phi, double dphi, ls_outcome how) {
  q->acc_a = a, q->acc_phi = phi, q->acc_dphi = dphi;
  return how;
}

/* Algorithm 3.5: bracketing, a_1 = 1 first (the bound if below 1), growing
 * while the slope stays negative and too steep, up to the bound. */
static ls_outcome bracket(ls_search *q, const bs_minimize_opts *o, bs__ls_result *res) {
  ls_state *s = &q->s;
  double a_prev = 0, phi_prev = q->phi0, dphi_prev = q->dphi0, a = fmin(1.0, s->a_top);
  for (int i = 0;; ++i) {
    if (q->evals >= q->max_ls) return LS_CAPPED;
    int hg;
    double dphi, phi = trial(s, a, 1, &hg, &dphi);
    ++q->evals;
    if (hg) note_best(q, a, phi);
    if (i == 0 && o->accept_noise && !(phi <= q->phi0 + q->c1 * a * q->dphi0) &&
        -q->dphi0 <= bs__noise_level(q->phi0)) {
      /* E cannot resolve the decrease this step predicts (paper 3.3): search
       * on the slope (approximate Wolfe conditions) instead. None found: the
       * trial points stay what they were (phi(1) starts the bracket below). */
      if (noise_search(s, q->dphi0, q->max_ls - q->evals, &q->evals, res)) return LS_NOISE_DONE;
      if (q->evals >= q->max_ls) return LS_CAPPED;
    }
    if (!(phi <= q->phi0 + q->c1 * a * q->dphi0) || (i > 0 && phi >= phi_prev)) {
      q->lo = a_prev, q->phi_lo = phi_prev, q->dphi_lo = dphi_prev;
      q->hi = a, q->phi_hi = phi, q->dphi_hi = dphi, q->hi_d = hg;
      return LS_BRACKETED;
    }
    /* Sufficient decrease holds with a finite phi: the gradient was evaluated. */
    if (fabs(dphi) <= -q->c2 * q->dphi0) return accept_at(q, a, phi, dphi, LS_ACCEPT);
    if (dphi >= 0) {
      q->lo = a, q->phi_lo = phi, q->dphi_lo = dphi;
      q->hi = a_prev, q->phi_hi = phi_prev, q->dphi_hi = dphi_prev, q->hi_d = 1;
      return LS_BRACKETED;
    }
    if (a >= s->a_top) /* at the bound with E still falling steeply: the bound */
      return s->bounded ? accept_at(q, a, phi, dphi, LS_BOUND) : LS_CAPPED;
    /* Extrapolate: cubic minimizer kept in [a + (a - a_prev)/2, a + 10 (a - a_prev)]. */
    double w = a - a_prev, c = cubic_min(a_prev, phi_prev, dphi_prev, a, phi, dphi), a_next;
    if (isfinite(c) && c > a) a_next = fmin(fmax(c, a + 0.5 * w), a + 10.0 * w);
    else a_next = a + 4.0 * w;
    a_prev = a, phi_prev = phi, dphi_prev = dphi;
    if (s->bounded && a_next > s->a_top) s->limited = 1;
    a = fmin(a_next, s->a_top);
  }
}

/* The next trial of the zoom: the safeguarded cubic (or quadratic)
 * interpolant's minimizer in the bracket, else its midpoint. */
static double zoom_trial(const ls_search *q, double al, double ah, double w) {
  double aj = NAN;
  if (q->hi_d && isfinite(q->phi_hi)) {
    aj = cubic_min(q->lo, q->phi_lo, q->dphi_lo, q->hi, q->phi_hi, q->dphi_hi);
  } else if (isfinite(q->phi_hi)) { /* quadratic through phi(lo), phi'(lo), phi(hi) */
    double h = q->hi - q->lo, den = 2.0 * (q->phi_hi - q->phi_lo - q->dphi_lo * h);
    if (den > 0) aj = q->lo - q->dphi_lo * h * h / den;
  }
  if (isfinite(aj)) return fmin(fmax(aj, al + 0.1 * w), ah - 0.1 * w); /* safeguard */
  return 0.5 * (q->lo + q->hi);                                         /* bisection */
}

/* Algorithm 3.6: zoom in the bracket (lo, hi); lo satisfies sufficient
 * decrease with the lowest value so far, and dphi_lo (hi - lo) < 0. */
static ls_outcome zoom(ls_search *q) {
  for (;;) {
    if (q->evals >= q->max_ls) return LS_CAPPED;
    double al = fmin(q->lo, q->hi), ah = fmax(q->lo, q->hi), w = ah - al;
    if (!(w > 4.0 * DBL_EPSILON * ah)) return LS_CAPPED; /* the bracket collapsed */
    double aj = zoom_trial(q, al, ah, w);
    int hg;
    double dphi, phi = trial(&q->s, aj, 0, &hg, &dphi);
    ++q->evals;
    if (!(phi <= q->phi0 + q->c1 * aj * q->dphi0) || phi >= q->phi_lo) {
      note_best(q, aj, phi); /* may still lie below phi(0): a fallback if the cap is hit */
      q->hi = aj, q->phi_hi = phi, q->hi_d = 0;
      continue;
    }
    phi = grad_here(&q->s, &dphi);
    if (!(phi <= q->phi0 + q->c1 * aj * q->dphi0) || phi >= q->phi_lo) { /* gradient() disagreed with value() */
      q->hi = aj, q->phi_hi = phi, q->dphi_hi = dphi, q->hi_d = q->s.cur_grad;
      continue;
    }
    note_best(q, aj, phi);
    if (fabs(dphi) <= -q->c2 * q->dphi0) return accept_at(q, aj, phi, dphi, LS_ACCEPT);
    if (dphi * (q->hi - q->lo) >= 0) q->hi = q->lo, q->phi_hi = q->phi_lo, q->dphi_hi = q->dphi_lo, q->hi_d = 1;
    q->lo = aj, q->phi_lo = phi, q->dphi_lo = dphi;
  }
}

/* No Wolfe point within the cap: the lowest decreasing point, if any. */
static void capped(ls_search *q, bs__ls_result *res) {
  bs_minimizer *m = q->s.m;
  if (!(q->best_phi < q->phi0)) return;
  if (!(q->s.cur_a == q->best_a && q->s.cur_grad)) {
    double dphi;
    make_point(&q->s, q->best_a);
    double phi = grad_here(&q->s, &dphi);
    if (!(phi < q->phi0)) return; /* not reproducible: treat as no decrease */
    q->best_phi = phi;
    res->dphi = dphi;
  } else {
    res->dphi = bs__mdot(m, m->gy, m->d);
  }
  res->status = BS_LSEARCH_CAPPED;
  res->alpha = q->best_a;
  res->phi = q->best_phi;
}

void bs__line_search(bs_minimizer *m, const bs_objective *obj, const double *x, double phi0, double dphi0,
                     double amax, bs_minimize_stats *st, bs__ls_result *res) {
  const bs_minimize_opts *o = &m->opts;
  if (!(amax >= 0)) amax = 0;
  ls_search q = {.s = {m, obj, x, st, phi0, fmin(ALPHA_MAX, amax), amax < ALPHA_MAX, amax < 1.0, NAN, 0},
                 .phi0 = phi0, .dphi0 = dphi0, .c1 = o->c1, .c2 = o->c2, .max_ls = o->max_ls,
                 .best_phi = phi0, .phi_lo = phi0, .dphi_lo = dphi0};
  memset(res, 0, sizeof *res);
  res->status = BS_LSEARCH_NO_DECREASE;
  res->bound = amax;
  res->limited = q.s.limited;
  if (!(q.s.a_top > 0)) return; /* the bound allows no step */
  ls_outcome out = bracket(&q, o, res);
  if (out == LS_BRACKETED) out = zoom(&q);
  res->evals = q.evals;
  res->limited = q.s.limited;
  if (out == LS_NOISE_DONE) return;
  if (out == LS_CAPPED) {
    capped(&q, res);
    return;
  }
  res->status = out == LS_BOUND ? BS_LSEARCH_BOUND : BS_LSEARCH_WOLFE;
  res->alpha = q.acc_a;
  res->phi = q.acc_phi;
  res->dphi = q.acc_dphi;
}
