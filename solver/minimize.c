/* minimize.c — the stabilized Newton minimizer of the paper (section 3.1):
 * Newton-CG with early exit on indefiniteness, adaptive CG tolerance, downhill
 * check, length clamp, strong Wolfe line search (linesearch.c), and the
 * gradient-projection hooks of section 3.2. See bs_minimize.h. */
#include <float.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bs_sum.h"
#include "minimize_impl.h"

/* ---- small shared helpers ------------------------------------------------ */

#define BS_PAR_MIN 16384 /* below this many doubles, vector kernels run serially */

/* in the fixed order of bs_sum.h: the same bits with any thread count */
double bs__dot(int64_t N, const double *a, const double *b) { return bs_sum_dot(N, a, b, BS_PAR_MIN); }

void bs__mask_copy(int32_t n, const uint8_t *mask, const double *src, double *dst) {
#pragma omp parallel for schedule(static) if (3 * (int64_t)n > BS_PAR_MIN)
  for (int32_t v = 0; v < n; ++v) {
    const int f = !mask || mask[v];
    for (int k = 0; k < 3; ++k) dst[3 * (int64_t)v + k] = f ? src[3 * (int64_t)v + k] : 0.0;
  }
}

void bs__restore_fixed(int32_t n, const uint8_t *mask, const double *src, double *dst) {
  if (!mask) return;
  for (int32_t v = 0; v < n; ++v)
    if (!mask[v])
      for (int k = 0; k < 3; ++k) dst[3 * (int64_t)v + k] = src[3 * (int64_t)v + k];
}

int64_t bs__first_nonfinite(int32_t n, const uint8_t *mask, const double *v) {
  for (int32_t i = 0; i < n; ++i) {
    if (mask && !mask[i]) continue;
    for (int k = 0; k < 3; ++k)
      if (!isfinite(v[3 * (int64_t)i + k])) return 3 * (int64_t)i + k;
  }
  return -1;
}

void bs__set_reason(bs_minimizer *m, bs_minimize_stats *st, bs_min_reason r, const char *fmt, ...) {
  char body[BS_MIN_TEXT - 16];
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(body, sizeof body, fmt, ap);
  va_end(ap);
  snprintf(m->text, sizeof m->text, "%s: %s", bs_min_reason_name(r), body);
  st->reason = r;
  st->reason_text = m->text;
}

void bs__project(const bs_objective *obj, double *x, const double *fixed_src, bs_minimize_stats *st) {
  if (!obj->project) return;
  double t = bs_seconds();
  obj->project(x, obj->ctx);
  bs__restore_fixed(obj->n, obj->mask, fixed_src, x);
  st->t_eval += bs_seconds() - t;
}

int bs__gradient(bs_minimizer *m, const bs_objective *obj, const double *x, double *E, double *g_raw,
                 int64_t *bad, bs_minimize_stats *st) {
  double t = bs_seconds();
  *bad = -1;
  int rc = obj->gradient(x, E, g_raw, obj->ctx);
  st->t_eval += bs_seconds() - t;
  if (rc != 0 || !isfinite(*E)) return 1;
  *bad = bs__first_nonfinite(m->n, obj->mask, g_raw);
  return bs__many(m, *bad >= 0);
}

double bs__constrained_gradient(bs_minimizer *m, const bs_objective *obj, const double *x,
                                const double *g_raw, double *g, bs_minimize_stats *st, int do_register) {
  if ((do_register && obj->register_active) || obj->project_gradient) {
    double t = bs_seconds();
    if (do_register && obj->register_active) obj->register_active(x, g_raw, obj->ctx);
    bs__mask_copy(m->n, obj->mask, g_raw, g);
    if (obj->project_gradient) {
      obj->project_gradient(x, g, obj->ctx);
      bs__mask_copy(m->n, obj->mask, g, g); /* the hook must not revive fixed dofs */
    }
    st->t_eval += bs_seconds() - t;
  } else {
    bs__mask_copy(m->n, obj->mask, g_raw, g);
  }
  return sqrt(bs__mdot(m, g, g));
}

double bs__noise_level(double E) { return 64 * DBL_EPSILON * fabs(E); }

int bs__solve_outcome(bs_minimizer *m, bs_minimize_stats *st, int rc, const bs_error *e2, int it, const char *who,
                      const char *solver, bs_error *err) {
  if (rc == BS_ENUMERIC) {
    bs__set_reason(m, st, BS_MIN_NONFINITE, "Newton system not finite at iteration %d (%s)", it, e2->msg);
    return 1;
  }
  if (rc) {
    if (err) *err = *e2;
    bs_error_prefix(err, "%s iteration %d: %s solve", who, it, solver);
  }
  return rc;
}

const char *bs_min_reason_name(bs_min_reason r) {
  switch (r) {
  case BS_MIN_CONVERGED: return "converged";
  case BS_MIN_MAX_ITER: return "max_iter";
  case BS_MIN_STALLED: return "stalled";
  case BS_MIN_LINE_SEARCH: return "line_search";
  case BS_MIN_NONFINITE: return "nonfinite";
  case BS_MIN_STEPS_DONE: return "steps_done";
  case BS_MIN_DIVERGED: return "diverged";
  case BS_MIN_FLOOR: return "converged_floor";
  case BS_MIN_STOPPED: return "stopped";
  }
  return "unknown";
}

void bs_minimizer_set_stop(bs_minimizer *m, volatile sig_atomic_t *stop) {
  if (m) m->stop = stop;
}

/* Collective with vecops (bs__many): a flag raised on any rank stops every
 * rank's solve at the same iteration. */
int bs__stopped(bs_minimizer *m, bs_minimize_stats *st, int it, double gnorm) {
  if (!m->stop || !bs__many(m, *m->stop != 0)) return 0;
  bs__set_reason(m, st, BS_MIN_STOPPED, "stopped on request after %d iterations (|grad E| = %.3e, tol %.3e)", it,
                 gnorm, m->tau);
  return 1;
}

void bs_minimizer_get_carry(const bs_minimizer *m, bs_min_carry *c) {
  c->full = m->prev_full;
  c->eta = m->prev_eta;
}

void bs_minimizer_set_carry(bs_minimizer *m, const bs_min_carry *c) {
  const int ok = (c->full == 0 || c->full == 1) && c->eta >= 0 && c->eta <= 0.5;
  m->prev_full = ok ? c->full : 0;
  m->prev_eta = ok ? c->eta : 0;
}

int bs_min_reason_converged(bs_min_reason r) { return r == BS_MIN_CONVERGED || r == BS_MIN_FLOOR; }

double bs__tolerance(const bs_minimize_opts *o, const bs_objective *obj, double g0) {
  return fmax(o->tol, fmax(o->rtol * g0, o->load_rtol * obj->load_norm));
}

const char *bs_direction_name(bs_direction d) {
  switch (d) {
  case BS_DIR_NEWTON: return "newton";
  case BS_DIR_NEG_DX: return "neg_dx";
  case BS_DIR_NEG_GRAD: return "neg_grad";
  }
  return "unknown";
}

const char *bs_globalization_name(bs_globalization g) {
  switch (g) {
  case BS_GLOBAL_LINE_SEARCH: return "line_search";
  case BS_GLOBAL_TRUST_REGION: return "trust_region";
  }
  return "unknown";
}

int bs_globalization_parse(const char *name, bs_globalization *out, bs_error *err) {
  for (int g = BS_GLOBAL_LINE_SEARCH; g <= BS_GLOBAL_TRUST_REGION; ++g)
    if (name && !strcmp(name, bs_globalization_name((bs_globalization)g))) {
      *out = (bs_globalization)g;
      return 0;
    }
  return bs_error_set(err, BS_EINPUT, "unknown globalization \"%s\" (expected line_search or trust_region)",
                      name ? name : "(null)");
}

const char *bs_lsearch_status_name(bs_lsearch_status s) {
  switch (s) {
  case BS_LSEARCH_NO_DECREASE: return "no_decrease";
  case BS_LSEARCH_CAPPED: return "capped";
  case BS_LSEARCH_WOLFE: return "wolfe";
  case BS_LSEARCH_NOISE: return "noise";
  case BS_LSEARCH_BOUND: return "bound";
  }
  return "unknown";
}

/* ---- options, create, destroy --------------------------------------------- */

void bs_minimize_opts_default(bs_minimize_opts *o) {
  memset(o, 0, sizeof *o);
  o->tol = 1e-3;
  o->max_iter = 500;
  o->newton_max_iter = 50;
  o->sigma = 1.0;
  o->kappa = 1e-2;
  o->clamp = 1e3;
  o->c1 = 1e-4;
  o->c2 = 0.9;
  o->max_ls = 40;
  o->naive_guess = 0;
  o->linear = BS_LIN_CG;
  o->cg_max_iter = 0;
  o->cg_downhill = 1;
  o->newton_rel_tol = 1e-10;
  o->accept_noise = 0;
  o->amg_rebuild_factor = 3.0;
  o->amg_rebuild_every = 0;
  o->globalization = BS_GLOBAL_LINE_SEARCH;
  o->tr_radius = 0.1;
  o->convexify = 1;
}

int bs__opts_check(const bs_minimize_opts *o, bs_error *err) {
  if (!o) return bs_error_set(err, BS_EINPUT, "minimizer options: NULL");
  if (!(o->tol >= 0) || !isfinite(o->tol))
    return bs_error_set(err, BS_EINPUT, "minimizer option tol must be finite and >= 0, got %g", o->tol);
  if (!(o->rtol >= 0 && o->rtol < 1) || !(o->load_rtol >= 0 && o->load_rtol < 1))
    return bs_error_set(err, BS_EINPUT, "minimizer options rtol and load_rtol must be in [0, 1), got %g and %g",
                        o->rtol, o->load_rtol);
  if (o->max_iter < 0)
    return bs_error_set(err, BS_EINPUT, "minimizer option max_iter must be >= 0, got %d", o->max_iter);
  if (o->convexify < 0 || o->convexify > 1)
    return bs_error_set(err, BS_EINPUT, "minimizer option convexify must be 0 or 1, got %d", o->convexify);
  if ((int)o->forcing_ew < BS_FORCING_PAPER || (int)o->forcing_ew > BS_FORCING_ADAPTIVE)
    return bs_error_set(err, BS_EINPUT, "minimizer option forcing_ew must be a bs_forcing (0, 1 or 2), got %d",
                        (int)o->forcing_ew);
  if (o->newton_max_iter < 1)
    return bs_error_set(err, BS_EINPUT, "minimizer option newton_max_iter must be >= 1, got %d", o->newton_max_iter);
  if (!(o->sigma > 0) || !isfinite(o->sigma))
    return bs_error_set(err, BS_EINPUT, "minimizer option sigma must be finite and > 0, got %g", o->sigma);
  if (!(o->kappa >= 0 && o->kappa < 1))
    return bs_error_set(err, BS_EINPUT, "minimizer option kappa must be in [0, 1), got %g", o->kappa);
  if (!(o->clamp > 0))
    return bs_error_set(err, BS_EINPUT, "minimizer option clamp must be > 0, got %g", o->clamp);
  if (!(o->c1 > 0 && o->c1 < 1))
    return bs_error_set(err, BS_EINPUT, "minimizer option c1 must be in (0, 1), got %g", o->c1);
  if (!(o->c2 > o->c1 && o->c2 < 1))
    return bs_error_set(err, BS_EINPUT, "minimizer option c2 must be in (c1, 1) = (%g, 1), got %g", o->c1,
                        o->c2);
  if (o->max_ls < 1)
    return bs_error_set(err, BS_EINPUT, "minimizer option max_ls must be >= 1, got %d", o->max_ls);
  if ((unsigned)o->linear >= (unsigned)BS_LIN_KINDS)
    return bs_error_set(err, BS_EINPUT, "minimizer option linear: unknown solver kind %d", (int)o->linear);
  if (o->cg_max_iter < 0)
    return bs_error_set(err, BS_EINPUT, "minimizer option cg_max_iter must be >= 0, got %d", o->cg_max_iter);
  if (!(o->amg_rebuild_factor == 0 || (o->amg_rebuild_factor >= 1 && isfinite(o->amg_rebuild_factor))))
    return bs_error_set(err, BS_EINPUT, "minimizer option amg_rebuild_factor must be 0 or a finite value >= 1, got %g",
                        o->amg_rebuild_factor);
  if (o->amg_rebuild_every < 0)
    return bs_error_set(err, BS_EINPUT, "minimizer option amg_rebuild_every must be >= 0, got %d",
                        o->amg_rebuild_every);
  if (!(o->newton_rel_tol > 0) || !isfinite(o->newton_rel_tol))
    return bs_error_set(err, BS_EINPUT, "minimizer option newton_rel_tol must be finite and > 0, got %g",
                        o->newton_rel_tol);
  if ((unsigned)o->globalization > (unsigned)BS_GLOBAL_TRUST_REGION)
    return bs_error_set(err, BS_EINPUT, "minimizer option globalization: unknown value %d", (int)o->globalization);
  if (o->globalization == BS_GLOBAL_TRUST_REGION && o->linear != BS_LIN_CG && o->linear != BS_LIN_PCG &&
      o->linear != BS_LIN_AMG)
    return bs_error_set(err, BS_EINPUT,
                        "minimizer option globalization trust_region needs linear cg, pcg or amg (Steihaug's CG), "
                        "got %s",
                        bs_lin_kind_name(o->linear));
  if (!(o->tr_radius > 0) || !isfinite(o->tr_radius))
    return bs_error_set(err, BS_EINPUT, "minimizer option tr_radius must be finite and > 0, got %g", o->tr_radius);
  if (o->hessian_extra < 0)
    return bs_error_set(err, BS_EINPUT, "minimizer option hessian_extra must be >= 0, got %lld",
                        (long long)o->hessian_extra);
  return 0;
}

void bs_minimizer_destroy(bs_minimizer **pm) {
  if (!pm || !*pm) return;
  bs_minimizer *m = *pm;
  for (int k = 0; k < BS_LIN_KINDS; ++k) bs_linsolve_destroy(&m->lin[k]);
  bs_bsr_destroy(&m->H);
  free(m->g_raw);
  free(m->g);
  free(m->d);
  free(m->r);
  free(m->y);
  free(m->gy_raw);
  free(m->gy);
  free(m);
  *pm = NULL;
}

static int ensure_solver(bs_minimizer *m, bs_lin_kind k, bs_error *err) {
  if (m->lin[k]) return 0;
  int rc = bs_linsolve_create(m->H, k, &m->lin[k], err);
  if (rc) bs_error_prefix(err, "minimizer: creating the %s workspace", bs_lin_kind_name(k));
  return rc;
}

/* The Krylov workspaces' options, values' precision (opts.cg_single) and
 * downhill iterate (opts.cg_downhill): on for the one the options solve with,
 * and for CG when CHOLMOD falls back to it; off (freed) otherwise. Allocates
 * here, once, not in the Newton loop. */
static int set_krylov_opts(bs_minimizer *m, const bs_minimize_opts *o, bs_error *err) {
  static const bs_lin_kind krylov[] = {BS_LIN_CG, BS_LIN_PCG, BS_LIN_AMG};
  for (int i = 0; i < 3; ++i) {
    const bs_lin_kind k = krylov[i];
    if (!m->lin[k]) continue;
    const int used = k == o->linear || (k == BS_LIN_CG && o->linear == BS_LIN_CHOLMOD);
    int rc = bs_linsolve_set_single(m->lin[k], used && o->cg_single, err);
    if (!rc) rc = bs_linsolve_set_downhill(m->lin[k], used && o->cg_downhill ? o->kappa : 0.0, err);
    if (!rc) rc = bs_linsolve_set_radius(m->lin[k], 0.0, err); /* trust_region sets it per solve */
    if (rc) return rc;
  }
  return 0;
}

int bs_minimizer_create(const bs_bsr *pattern, const bs_minimize_opts *opts, bs_minimizer **out,
                        bs_error *err) {
  if (!out) return bs_error_set(err, BS_EINPUT, "bs_minimizer_create: out is NULL");
  *out = NULL;
  if (!pattern) return bs_error_set(err, BS_EINPUT, "bs_minimizer_create: pattern is NULL");
  if (pattern->n < 0)
    return bs_error_set(err, BS_EINPUT, "bs_minimizer_create: pattern n = %d is negative", (int)pattern->n);
  bs_minimize_opts o;
  if (opts) o = *opts;
  else bs_minimize_opts_default(&o);
  int rc = bs__opts_check(&o, err);
  if (rc) return rc;

  bs_minimizer *m = bs_calloc(1, sizeof *m, "the minimizer", err);
  if (!m) return BS_ENOMEM;
  m->n = pattern->n;
  m->n3 = 3 * (int64_t)pattern->n;
  m->opts = o;
  /* Hessian storage: the same pattern (a graph with self loops gives back the
   * same sorted rows, hence the same slots). */
  if ((rc = bs_bsr_create(pattern->n, pattern->row_ptr, pattern->col, &m->H, err))) {
    bs_error_prefix(err, "minimizer: copying the Hessian pattern");
    bs_minimizer_destroy(&m);
    return rc;
  }
  if (m->H->nnzb != pattern->nnzb) {
    bs_minimizer_destroy(&m);
    return bs_error_set(err, BS_EINPUT,
                        "bs_minimizer_create: pattern is malformed (nnzb %lld, but its rows hold %lld distinct blocks)",
                        (long long)pattern->nnzb, (long long)m->H->nnzb);
  }
  if (o.hessian_extra > 0 && (rc = bs_bsr_reserve_extra(m->H, o.hessian_extra, err))) {
    bs_error_prefix(err, "minimizer: Hessian blocks outside the pattern");
    bs_minimizer_destroy(&m);
    return rc;
  }
  size_t N = m->n3 > 0 ? (size_t)m->n3 : 1;
  double **vecs[] = {&m->g_raw, &m->g, &m->d, &m->r, &m->y, &m->gy_raw, &m->gy};
  for (size_t k = 0; k < sizeof vecs / sizeof vecs[0]; ++k) {
    *vecs[k] = bs_calloc(N, sizeof(double), "minimizer work vectors", err);
    if (!*vecs[k]) {
      bs_minimizer_destroy(&m);
      return BS_ENOMEM;
    }
  }
  if ((rc = ensure_solver(m, BS_LIN_CG, err)) || (rc = ensure_solver(m, BS_LIN_MINRES, err)) ||
      (rc = ensure_solver(m, o.linear, err)) || (rc = set_krylov_opts(m, &o, err))) {
    bs_minimizer_destroy(&m);
    return rc;
  }
  *out = m;
  return 0;
}

int bs_minimizer_set_opts(bs_minimizer *m, const bs_minimize_opts *opts, bs_error *err) {
  if (!m) return bs_error_set(err, BS_EINPUT, "bs_minimizer_set_opts: minimizer is NULL");
  int rc = bs__opts_check(opts, err);
  if (rc) return rc;
  if ((rc = ensure_solver(m, opts->linear, err)) || (rc = set_krylov_opts(m, opts, err))) return rc;
  m->opts = *opts;
  return 0;
}

const bs_minimize_opts *bs_minimizer_opts(const bs_minimizer *m) { return m ? &m->opts : NULL; }

void bs_minimizer_amg_reset(bs_minimizer *m) {
  if (m) m->amg_reset = 1;
}

int bs__obj_check(const bs_minimizer *m, const bs_objective *obj, const double *x, bs_error *err) {
  if (!m) return bs_error_set(err, BS_EINPUT, "minimizer is NULL");
  if (!obj) return bs_error_set(err, BS_EINPUT, "objective is NULL");
  if (!x && m->n > 0) return bs_error_set(err, BS_EINPUT, "x is NULL");
  if (obj->n != m->n)
    return bs_error_set(err, BS_EINPUT, "objective has n = %d vertices but the minimizer was sized for n = %d",
                        (int)obj->n, (int)m->n);
  if (!obj->value) return bs_error_set(err, BS_EINPUT, "objective callback 'value' is NULL");
  if (!obj->gradient) return bs_error_set(err, BS_EINPUT, "objective callback 'gradient' is NULL");
  if (!obj->hessian) return bs_error_set(err, BS_EINPUT, "objective callback 'hessian' is NULL");
  if (!(obj->load_norm >= 0) || !isfinite(obj->load_norm))
    return bs_error_set(err, BS_EINPUT, "objective load_norm must be finite and >= 0, got %g", obj->load_norm);
  int64_t bad = bs__first_nonfinite(m->n, obj->mask, x);
  if (bs__many(m, bad >= 0) && bad < 0) return bs_error_set(err, BS_ENUMERIC, "initial x is not finite on another process");
  if (bad >= 0)
    return bs_error_set(err, BS_ENUMERIC, "initial x is not finite at vertex %lld component %d (%g)",
                        (long long)(bad / 3), (int)(bad % 3), x[bad]);
  return 0;
}

/* ---- the minimizer --------------------------------------------------------- */

/* AMG: builds the hierarchy when due (see "AMG reuse" in bs_minimize.h).
 * With the objective's precond_matrix, P is assembled in H's storage, so this
 * runs before H is assembled (no second matrix); without it, after (P = H).
 * Returns 0, 1 when P is not evaluable or not finite (reason set), or a
 * negative error. */
static int amg_prepare(bs_minimizer *m, const bs_objective *obj, const double *x, int it, bs_minimize_stats *st,
                       bs_error *err) {
  bs_linsolve *ls = m->lin[BS_LIN_AMG];
  if (!m->amg_reset && bs_linsolve_amg_ready(ls, obj->mask)) return 0;
  const double t = bs_seconds();
  const bs_bsr *P = m->H;
  if (obj->precond_matrix) {
    bs_bsr_zero(m->H);
    int prc = obj->precond_matrix(x, m->H, obj->ctx);
    if (prc) {
      bs__set_reason(m, st, BS_MIN_NONFINITE,
                     "AMG preconditioner matrix not evaluable at iteration %d (callback returned %d)", it, prc);
      return 1;
    }
  }
  bs_error e2;
  bs_error_clear(&e2);
  int rc = bs_linsolve_amg_setup(ls, P, obj->mask, &e2);
  const double dt = bs_seconds() - t;
  st->t_amg_setup += dt;
  st->t_linear += dt;
  if (rc == BS_ENUMERIC) {
    bs__set_reason(m, st, BS_MIN_NONFINITE, "AMG preconditioner matrix not finite at iteration %d (%s)", it, e2.msg);
    return 1;
  }
  if (rc) {
    if (err) *err = e2;
    bs_error_prefix(err, "minimizer iteration %d: AMG setup", it);
    return rc;
  }
  st->amg_setups++;
  m->amg_reset = 0;
  m->amg_calls = 0;
  m->amg_base = 0.0;
  return 0;
}

/* AMG: after a solve, requests a rebuild when the preconditioner has aged. */
static void amg_judge(bs_minimizer *m, const bs_lin_stats *ls) {
  if (ls->precond_failed) {
    m->amg_reset = 1;
    return;
  }
  if (!ls->converged || ls->indefinite || ls->iterations < 1 || !(ls->rel_residual > 0)) return;
  const double decades = fmax(log10(1.0 / ls->rel_residual), 0.3);
  const double cost = ls->iterations / decades;
  if (m->amg_base == 0.0) m->amg_base = cost;
  else if (m->opts.amg_rebuild_factor > 0 && cost > m->opts.amg_rebuild_factor * m->amg_base) m->amg_reset = 1;
}

/* Step 4: H d = -g on the free dofs. Returns 0, 1 when the solve produced a
 * non-finite value (reason set), or a negative error. */
int bs__newton_direction(bs_minimizer *m, const bs_objective *obj, const double *x, double gnorm, int it,
                            bs_minimize_stats *st, bs_min_iter *rec, bs_error *err) {
  const bs_minimize_opts *o = &m->opts;
  const int max_it = m->cg_cap;
  const double sigma = o->sigma_auto ? o->sigma / sqrt(m->g0_norm) : o->sigma;
  double rel = fmin(0.5, sigma * sqrt(fmax(gnorm, m->tau)));
  if (obj->quadratic) rel = fmin(rel, fmax(m->tau / (4 * gnorm), 1e-13)); /* one step reaches tau */
  /* Eisenstat & Walker (1996), choice 2, gamma 0.9, alpha 2; forcing_ew 2 only
   * after a full Newton step (bs_minimize.h) */
  if (o->forcing_ew != BS_FORCING_PAPER && it > 0 && (o->forcing_ew == BS_FORCING_EW || m->last_full)) {
    const double q = gnorm / m->g_prev, safe = 0.9 * m->eta_prev * m->eta_prev;
    double e = 0.9 * q * q;
    if (safe > 0.1) e = fmax(e, safe);
    rel = fmin(rel, e);
  }
  /* forcing_ew 2: a solve that follows one made only of full Newton steps
   * starts from that solve's last forcing term */
  if (o->forcing_ew == BS_FORCING_ADAPTIVE && it == 0 && m->prev_full && m->prev_eta > 0) rel = fmin(rel, m->prev_eta);
  m->g_prev = gnorm;
  m->eta_prev = rel;
  rec->lin_rel_tol = rel;
  for (int64_t i = 0; i < m->n3; ++i) m->r[i] = -m->g[i];
  bs_lin_kind kind = o->linear;
  bs_lin_stats ls;
  memset(&ls, 0, sizeof ls);
  if (kind == BS_LIN_AMG && !obj->precond_matrix && !m->has_vops) {
    int arc = amg_prepare(m, obj, x, it, st, err);
    if (arc) return arc;
  }
  double t = bs_seconds();
  bs_error e2;
  bs_error_clear(&e2);
  int rc = m->has_vops ? m->vops.solve(obj->mask, m->r, rel, max_it, o->cg_downhill ? o->kappa : 0.0, m->d, &ls, &e2,
                                        m->vops.ctx)
                       : bs_linsolve_solve(m->lin[kind], m->H, obj->mask, m->r, rel, max_it, m->d, &ls, &e2);
  if (rc == 0 && kind == BS_LIN_AMG && !m->has_vops) amg_judge(m, &ls);
  if (rc == 0 && kind == BS_LIN_CHOLMOD && ls.not_pd && !m->has_vops) {
    st->cholmod_fallbacks++;
    rec->cholmod_fallback = 1;
    kind = BS_LIN_CG;
    rc = bs_linsolve_solve(m->lin[kind], m->H, obj->mask, m->r, rel, max_it, m->d, &ls, &e2);
  }
  st->t_linear += bs_seconds() - t;
  if ((rc = bs__solve_outcome(m, st, rc, &e2, it, "minimizer", bs_lin_kind_name(kind), err))) return rc;
  st->cg_iterations += ls.iterations;
  st->indefinite_exits += ls.indefinite;
  st->downhill_iterates += ls.downhill_iterate > 0;
  rec->lin_iterations = ls.iterations;
  rec->lin_indefinite = ls.indefinite;
  rec->lin_downhill_iterate = ls.downhill_iterate;
  rec->lin_boundary = ls.boundary;
  return 0;
}

/* The start of bs_minimize: with no unknowns, E and a reason (returns 1);
 * else the initial guess projected (fixed dofs kept: m->y holds the input)
 * and its energy and raw gradient (returns 1 with the reason when they are
 * not evaluable, 0 to iterate). */
static int start(bs_minimizer *m, const bs_objective *obj, double *x, double *E, bs_minimize_stats *st) {
  const int64_t N = m->n3;
  if (N == 0) { /* nothing to move: report E */
    double E0 = 0;
    double t = bs_seconds();
    int vrc = obj->value(x, &E0, obj->ctx);
    st->t_eval += bs_seconds() - t;
    st->E = E0;
    if (vrc || !isfinite(E0)) bs__set_reason(m, st, BS_MIN_NONFINITE, "objective not evaluable (E = %g)", E0);
    else bs__set_reason(m, st, BS_MIN_CONVERGED, "no unknowns");
    return 1;
  }
  if (obj->project) {
    memcpy(m->y, x, sizeof(double) * (size_t)N);
    bs__project(obj, x, m->y, st);
  }
  int64_t bad;
  if (!bs__gradient(m, obj, x, E, m->g_raw, &bad, st)) return 0;
  st->E = *E;
  st->grad_norm = NAN;
  if (bad >= 0)
    bs__set_reason(m, st, BS_MIN_NONFINITE, "gradient not finite at the initial point: vertex %lld component %d (%g)",
                   (long long)(bad / 3), (int)(bad % 3), m->g_raw[bad]);
  else bs__set_reason(m, st, BS_MIN_NONFINITE, "objective not evaluable at the initial point (E = %g)", *E);
  return 1;
}

/* Step 6: the length clamp of m->d, whose norm is dn. */
static void clamp_direction(bs_minimizer *m, double dn, bs_minimize_stats *st, bs_min_iter *rec) {
  if (!(dn > m->opts.clamp)) return;
  const double s = m->opts.clamp / dn;
  for (int64_t i = 0; i < m->n3; ++i) m->d[i] *= s;
  rec->clamped = 1;
  st->clamps++;
}

/* d := -g, counted as a -grad E fallback, then clamped (step 6). */
static void along_neg_grad(bs_minimizer *m, double gnorm, bs_minimize_stats *st, bs_min_iter *rec) {
  for (int64_t i = 0; i < m->n3; ++i) m->d[i] = -m->g[i];
  rec->direction = BS_DIR_NEG_GRAD;
  st->fallback_neg_grad++;
  clamp_direction(m, gnorm, st, rec);
}

/* Steps 5 and 6 on the Newton direction m->d: the downhill check (dx, else
 * -dx, else -grad E) and the length clamp. Returns phi'(0) = d.g. */
static double downhill_and_clamp(bs_minimizer *m, double gnorm, bs_minimize_stats *st, bs_min_iter *rec) {
  const bs_minimize_opts *o = &m->opts;
  const int64_t N = m->n3;
  /* Step 5: downhill check. */
  double dn = sqrt(bs__mdot(m, m->d, m->d)), dg = bs__mdot(m, m->d, m->g);
  if (isfinite(dn) && isfinite(dg) && dn > 0 && dg < -o->kappa * dn * gnorm) {
    rec->direction = BS_DIR_NEWTON;
  } else if (isfinite(dn) && isfinite(dg) && dn > 0 && -dg < -o->kappa * dn * gnorm) {
    for (int64_t i = 0; i < N; ++i) m->d[i] = -m->d[i];
    rec->direction = BS_DIR_NEG_DX;
    st->fallback_neg_dx++;
  } else {
    along_neg_grad(m, gnorm, st, rec);
    return bs__mdot(m, m->d, m->g);
  }
  clamp_direction(m, dn, st, rec); /* step 6 */
  return bs__mdot(m, m->d, m->g);
}

/* After a line search along a Newton direction (dx or -dx) that found no
 * decrease above the rounding floor: d := -g (clamped), counted in
 * fallback_neg_grad, and the new g.d returned; 0 when d already points along
 * -g (the search would repeat) or the decrease it predicted is at the floor. */
static double restart_along_gradient(bs_minimizer *m, double E, double gnorm, double dphi0, bs_minimize_stats *st,
                                     bs_min_iter *rec) {
  const double dn = sqrt(bs__mdot(m, m->d, m->d));
  if (rec->direction == BS_DIR_NEG_GRAD || -dphi0 <= bs__noise_level(E) || -dphi0 >= (1 - 1e-12) * dn * gnorm)
    return 0;
  along_neg_grad(m, gnorm, st, rec);
  return bs__mdot(m, m->d, m->g);
}

double bs__step_bound(bs_minimizer *m, const bs_objective *obj, const double *x, bs_minimize_stats *st) {
  if (!obj->max_step) return INFINITY;
  double a = 0;
  const double t = bs_seconds();
  const int rc = obj->max_step(x, m->d, &a, obj->ctx);
  st->t_eval += bs_seconds() - t;
  return rc == 0 && a >= 0 ? a : 0.0;
}

/* One line search along m->d under the step bound there (rec->alpha_bound). */
static void search_once(bs_minimizer *m, const bs_objective *obj, const double *x, double E, double dphi0,
                        bs_minimize_stats *st, bs_min_iter *rec, bs__ls_result *ls) {
  rec->alpha_bound = bs__step_bound(m, obj, x, st);
  bs__line_search(m, obj, x, E, dphi0, rec->alpha_bound, st, ls);
  st->ls_evaluations += ls->evals;
  st->ccd_limited += ls->limited;
}

/* Steps 7-9's line search along m->d from x (E, slope *dphi0), made again
 * along -g when it finds no decrease (restart_along_gradient: *dphi0 and
 * rec follow); ls receives the last search. */
static void search(bs_minimizer *m, const bs_objective *obj, const double *x, double E, double gnorm, double *dphi0,
                   bs_minimize_stats *st, bs_min_iter *rec, bs__ls_result *ls) {
  const double t = bs_seconds();
  search_once(m, obj, x, E, *dphi0, st, rec, ls);
  double dg;
  if (ls->status == BS_LSEARCH_NO_DECREASE && (dg = restart_along_gradient(m, E, gnorm, *dphi0, st, rec)) < 0) {
    *dphi0 = dg;
    search_once(m, obj, x, E, *dphi0, st, rec, ls);
  }
  st->t_line_search += bs_seconds() - t;
}

/* The reason of a line search with no decrease. Paper 3.3: below some
 * |grad E| the decrease a step can make, about |g.d|/2, is lost in the
 * rounding of E itself: a Newton direction there is at the rounding floor,
 * a converged state (bs_minimize.h, "Rounding floor"). */
static void no_decrease_reason(bs_minimizer *m, bs_minimize_stats *st, const bs__ls_result *ls, int it, double E,
                               double gnorm, double dphi0, bs_direction dir) {
  if (!(ls->bound > 0))
    bs__set_reason(m, st, BS_MIN_LINE_SEARCH,
                   "the step bound (max_step) allows no motion along the search direction at iteration %d "
                   "(|grad E| = %.3e, E = %.9e)",
                   it, gnorm, E);
  else if (-dphi0 <= bs__noise_level(E) && dir != BS_DIR_NEG_GRAD)
    bs__set_reason(m, st, BS_MIN_FLOOR,
                   "converged at the rounding floor of E after %d iterations: no decrease in %d trial points, the "
                   "predicted decrease |g.d| = %.3e is below the rounding level %.3e of E = %.9e (|grad E| = %.3e, "
                   "tol %.3e)",
                   it, ls->evals, -dphi0, bs__noise_level(E), E, gnorm, m->tau);
  else
    bs__set_reason(m, st, BS_MIN_LINE_SEARCH,
                   "no decrease of E along the search direction in %d trial points at iteration %d "
                   "(|grad E| = %.3e, E = %.9e, g.d = %.3e)",
                   ls->evals, it, gnorm, E, dphi0);
}

/* The floor watch (bs_minimize.h, "Rounding floor") for the iteration at
 * ||g|| = gnorm whose direction predicts the decrease -dphi0: 1 (reason
 * set) when the solve ends there at the floor. */
int bs__at_floor(bs_minimizer *m, const bs_objective *obj, bs_minimize_stats *st, int it, double E, double gnorm,
                    double dphi0, bs_direction dir) {
  if (!(-dphi0 <= bs__noise_level(E)) || dir == BS_DIR_NEG_GRAD) {
    m->floor_run = 0;
    return 0;
  }
  if (m->floor_run == 0 || gnorm <= 0.5 * m->floor_best) {
    m->floor_run = 1;
    m->floor_best = gnorm;
    return 0;
  }
  if (++m->floor_run <= (obj->quadratic ? 1 : BS_FLOOR_WINDOW)) return 0;
  bs__set_reason(m, st, BS_MIN_FLOOR,
                 "converged at the rounding floor of E after %d iterations: |grad E| = %.3e (tol %.3e) did not halve "
                 "over %d iterations whose predicted decrease is below the rounding level %.3e of E = %.9e",
                 it, gnorm, m->tau, m->floor_run - 1, bs__noise_level(E), E);
  return 1;
}

/* The AMG setup when due, from the objective's matrix (assembled in H's
 * storage), then step 2's Hessian at x: 0, > 0 to stop (the reason is set),
 * < 0 an error. */
static int assemble(bs_minimizer *m, const bs_objective *obj, const double *x, int it, bs_minimize_stats *st,
                    bs_error *err) {
  if (m->opts.linear == BS_LIN_AMG && obj->precond_matrix && !m->has_vops) {
    int rc = amg_prepare(m, obj, x, it, st, err);
    if (rc) return rc;
  }
  double t = bs_seconds();
  int hrc = m->convex       ? obj->hessian_convexified(x, m->g_raw, m->H, obj->ctx)
            : obj->hessian_g ? obj->hessian_g(x, m->g_raw, m->H, obj->ctx)
                             : obj->hessian(x, m->H, obj->ctx);
  if (!hrc) bs_bsr_index_extra(m->H); /* its extras then go row by row in the products */
  st->t_assembly += bs_seconds() - t;
  if (!hrc) return 0;
  bs__set_reason(m, st, BS_MIN_NONFINITE, "Hessian not evaluable at iteration %d (callback returned %d)", it, hrc);
  return 1;
}

/* The accepted iteration handed to obj->trace (before x moves to m->y). */
void bs__trace_step(const bs_minimizer *m, const bs_objective *obj, const double *x, double E, double dphi0,
                       const bs__ls_result *ls, bs_min_iter *rec) {
  rec->ls_status = ls->status;
  rec->ls_evaluations = ls->evals;
  rec->alpha = ls->alpha;
  rec->phi0 = E;
  rec->dphi0 = dphi0;
  rec->phi = ls->phi;
  rec->dphi = ls->dphi;
  rec->x = x;
  rec->d = m->d;
  rec->y = m->y;
  obj->trace(rec, obj->ctx);
}

/* Whether the accepted point m->y differs from x on a free dof. */
static int free_dofs_moved(const bs_minimizer *m, const bs_objective *obj, const double *x) {
  for (int32_t v = 0; v < m->n; ++v)
    if (!obj->mask || obj->mask[v])
      for (int k = 0; k < 3; ++k)
        if (m->y[3 * (int64_t)v + k] != x[3 * (int64_t)v + k]) return 1;
  return 0;
}

/* Accept: x <- P(x + alpha d), with its gradient; the step-length counts.
 * Returns E at the new x. */
static double accept_step(bs_minimizer *m, double *x, const bs__ls_result *ls, bs_minimize_stats *st) {
  memcpy(x, m->y, sizeof(double) * (size_t)m->n3);
  memcpy(m->g_raw, m->gy_raw, sizeof(double) * (size_t)m->n3);
  st->iterations++;
  st->alpha_last = ls->alpha;
  if (st->iterations == 1 || ls->alpha < st->alpha_min) st->alpha_min = ls->alpha;
  if (st->iterations == 1 || ls->alpha > st->alpha_max) st->alpha_max = ls->alpha;
  return ls->phi;
}

/* Step 3 at iteration it with ||g|| = gnorm (the solve's Krylov cap,
 * tolerance and watches set at it = 0): 1 with the reason set when the solve ends there
 * (converged, or the iteration cap). */
static int converged_or_capped(bs_minimizer *m, const bs_objective *obj, bs_minimize_stats *st, int it, double gnorm) {
  const bs_minimize_opts *o = &m->opts;
  if (it == 0) {
    /* The Krylov cap of the solve's systems: CG ends in at most (free dofs)
     * steps in exact arithmetic; allow for rounding. */
    int64_t free_dofs = 0;
    for (int32_t v = 0; v < m->n; ++v) free_dofs += (!obj->mask || obj->mask[v]) ? 3 : 0;
    m->free_vertices = free_dofs / 3;
    if (m->has_vops) free_dofs = (int64_t)bs__msum(m, (double)free_dofs); /* ghosts counted too: a cap only */
    const int64_t auto_it = 2 * free_dofs + 100;
    m->cg_cap = o->cg_max_iter > 0 ? o->cg_max_iter : (int)(auto_it > 1000000000 ? 1000000000 : auto_it);
    m->g0_norm = gnorm;
    st->tol_used = m->tau = bs__tolerance(o, obj, gnorm);
    m->floor_run = 0;
    m->all_full = 1;
    m->convex = 0;
  }
  if (gnorm == 0 || (gnorm < m->tau && !(it == 0 && o->naive_guess))) {
    bs__set_reason(m, st, BS_MIN_CONVERGED, "|grad E| = %.3e < tol %.3e after %d iterations", gnorm, m->tau, it);
    return 1;
  }
  if (it >= o->max_iter) {
    bs__set_reason(m, st, BS_MIN_MAX_ITER, "|grad E| = %.3e >= tol %.3e after %d iterations", gnorm, m->tau, it);
    return 1;
  }
  return bs__stopped(m, st, it, gnorm);
}

/* The model of the next iteration (bs_minimize.h, "Convexified model"), after
 * an iteration of the line-search loop (m->last_full set): the convexified
 * Hessian after negative curvature, the exact one again after a full Newton
 * step from a solve of 2 or more Krylov iterations. */
static void update_model(bs_minimizer *m, const bs_objective *obj, const bs_min_iter *rec) {
  if (!m->opts.convexify || !obj->hessian_convexified) return;
  if (rec->lin_indefinite) m->convex = 1;
  else if (m->convex && m->last_full && rec->lin_iterations > 1) m->convex = 0;
}

int bs_minimize(bs_minimizer *m, const bs_objective *obj, double *x, bs_minimize_stats *st_out, bs_error *err) {
  double t_start = bs_seconds();
  bs_minimize_stats local, *st = st_out ? st_out : &local;
  memset(st, 0, sizeof *st);
  int rc = bs__obj_check(m, obj, x, err);
  if (rc) return rc;
  const bs_minimize_opts *o = &m->opts;
  if (o->linear == BS_LIN_AMG && ++m->amg_calls >= o->amg_rebuild_every && o->amg_rebuild_every > 0)
    m->amg_reset = 1;
  double E = NAN;
  if (start(m, obj, x, &E, st)) { /* no unknowns, or not evaluable there: st says which */
    st->t_total = bs_seconds() - t_start;
    return 0;
  }

  int it = 0;
  for (;; ++it) {
    /* Steps 1-3. */
    double gnorm = bs__constrained_gradient(m, obj, x, m->g_raw, m->g, st, 1);
    st->E = E;
    st->grad_norm = gnorm;
    if (converged_or_capped(m, obj, st, it, gnorm)) break;
    bs_min_iter rec;
    memset(&rec, 0, sizeof rec);
    rec.iteration = it;
    rec.grad_norm = gnorm;
    rec.alpha_bound = INFINITY;

    rec.convexified = m->convex;
    st->convexified += m->convex;
    rc = assemble(m, obj, x, it, st, err);
    if (rc < 0) return rc;
    if (rc > 0) break;
    if (o->globalization == BS_GLOBAL_TRUST_REGION) { /* steps 4-9 in a trust region */
      rc = bs__tr_iteration(m, obj, x, &E, gnorm, it, st, &rec, err);
      if (rc < 0) return rc;
      if (rc > 0) break;
      m->all_full &= m->last_full;
      continue;
    }
    /* Step 4: Newton direction. */
    rc = bs__newton_direction(m, obj, x, gnorm, it, st, &rec, err);
    if (rc < 0) return rc;
    if (rc > 0) break;

    double dphi0 = downhill_and_clamp(m, gnorm, st, &rec);
    if (bs__at_floor(m, obj, st, it, E, gnorm, dphi0, rec.direction)) break;

    /* Steps 7-9: line search along the projected curve. */
    bs__ls_result ls;
    search(m, obj, x, E, gnorm, &dphi0, st, &rec, &ls);
    if (ls.status == BS_LSEARCH_NO_DECREASE) {
      no_decrease_reason(m, st, &ls, it, E, gnorm, dphi0, rec.direction);
      break;
    }
    if (ls.status == BS_LSEARCH_CAPPED) st->ls_failures++;
    m->last_full = rec.direction == BS_DIR_NEWTON && !rec.lin_indefinite && ls.status == BS_LSEARCH_WOLFE &&
                   ls.alpha == 1 && ls.evals == 1;
    m->all_full &= m->last_full;
    update_model(m, obj, &rec);
    if (ls.status == BS_LSEARCH_NOISE) st->noise_steps++;
    const int moved = bs__many(m, free_dofs_moved(m, obj, x));
    if (obj->trace) bs__trace_step(m, obj, x, E, dphi0, &ls, &rec);
    E = accept_step(m, x, &ls, st);
    if (!moved) {
      gnorm = bs__constrained_gradient(m, obj, x, m->g_raw, m->g, st, 0);
      st->E = E;
      st->grad_norm = gnorm;
      bs__set_reason(m, st, BS_MIN_STALLED,
                     "the step at iteration %d left x unchanged (alpha = %.3e, |grad E| = %.3e)", it, ls.alpha, gnorm);
      break;
    }
  }
  m->prev_full = bs_min_reason_converged(st->reason) && m->all_full && it > 0;
  m->prev_eta = m->eta_prev;
  st->t_total = bs_seconds() - t_start;
  return 0;
}
