/* step.c — a time step as a minimization (paper sections 2, 3.1; backward
 * Euler, BDF2, Newmark: bs_step.h), statics. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bs_step.h"
#include "bs_step_backend.h"

/* A list of terms handed to the backend (into bs_integrator.lists). */
typedef struct term_list {
  int n;
  bs_term **t;
} term_list;

/* Which terms a sum of energies takes: all, the cheap ones (every term but
 * the expensive ones, i.e. self-collision) or the expensive ones, which are
 * >= 0 (section 3.3). */
typedef enum { TERMS_ALL, TERMS_CHEAP, TERMS_EXPENSIVE } terms_which;

struct bs_integrator {
  bs_step_backend B;      /* the vectors' home (bs_step_backend.h)   */
  int32_t nv;             /* B.n_vertices                            */
  int n_terms;
  bs_term **terms;
  bs_term **lists;        /* storage of the term lists below          */
  term_list act[2][3];    /* [static_mode][terms_which]: the active    */
  term_list dyn[2];       /* [static_mode]: active and dynamic_only    */
  term_list external[2];  /* [static_mode]: active external loads      */
  term_list potential;    /* every term but inertia (f(xⁿ))           */
  uint8_t *mask;          /* owned copy (n_vertices)                 */
  bs_script_fn script;
  void *script_ctx;
  bs_integrator_opts opts;
  bs_step_hooks hooks;
  bs_step_data *step;     /* what the terms read (borrowed)          */
  int static_mode;        /* 1 while solving statics                 */
  bs_minimizer *min;
  double *x_n, *x_hat, *g1, *g2, *grad;
  double *gh;             /* 3n: grad E' for the post-solve hooks     */
  int has_expensive;
  int has_convexified;    /* a term offers hessian_convexified         */
  int has_hessian_g;      /* a term offers hessian_g and opts.penalty_secant */
  int has_max_step;       /* a term offers max_step (barrier contact: CCD) */
  int has_sweep;          /* a term offers sweep (barrier obstacles)        */
  const double *x_base;   /* where the guesses are clipped from: x_n, or sw_x after a sweep */
  double *sw_x, *sw_z, *sw_z2, *sw_zf; /* the sweep's point, predictors (rigid, not), followers' part (3n) */
  uint8_t *sw_mask;       /* the sweep's carried, then following, vertices (n) */
  int32_t *sw_body;       /* per vertex: its body (a component of the pattern's graph) */
  int32_t n_bodies;
  double *sw_bt;          /* per body (n_bodies): its translation in the predictor (3) */
  int32_t *sw_bn;         /* per body: its carried vertices, or -1 (not rigid: a vertex not free) */
  bs_bsr *sw_H;           /* the predictor's Hessian                        */
  bs_linsolve *sw_lin;    /* and its solver (PCG)                           */
  bs_previous_step prev;  /* the last step's displacement (prev.d: 3n, owned) */
  bs_step_history hist;   /* the integrator's history (hist.h: n_hist, owned) */
  size_t n_hist;          /* bs_integrator_history_doubles                    */
  double c;               /* the step's c (bs_step.h): 1, 4/9 or 1/4          */
  int cb_rc;              /* the first backend error inside a callback */
  bs_error cb_err;
};

static const char *method_names[] = {"optimization", "newton", "newton_k"};

int bs_method_parse(const char *name, bs_method *out, bs_error *err) {
  for (int i = 0; i < 3; i++)
    if (strcmp(name, method_names[i]) == 0) {
      *out = (bs_method)i;
      return 0;
    }
  return bs_error_set(err, BS_EINPUT, "unknown method '%s' (optimization, newton, newton_k)", name);
}

const char *bs_method_name(bs_method m) { return (unsigned)m < 3 ? method_names[m] : "?"; }

static const char *integrator_names[] = {"backward_euler", "bdf2", "newmark"};

int bs_time_integrator_parse(const char *name, bs_time_integrator *out, bs_error *err) {
  for (int i = 0; i < 3; i++)
    if (strcmp(name, integrator_names[i]) == 0) {
      *out = (bs_time_integrator)i;
      return 0;
    }
  return bs_error_set(err, BS_EINPUT, "unknown time integrator '%s' (backward_euler, bdf2, newmark)", name);
}

const char *bs_time_integrator_name(bs_time_integrator k) { return (unsigned)k < 3 ? integrator_names[k] : "?"; }

static const char *guess_names[] = {"x_hat", "explicit", "x_n", "previous"};

const char *bs_guess_name(bs_guess g) { return (unsigned)g < 4 ? guess_names[g] : "?"; }

void bs_integrator_opts_default(bs_integrator_opts *o) {
  memset(o, 0, sizeof *o);
  o->method = BS_METHOD_OPTIMIZATION;
  o->newton_k = 1;
  bs_minimize_opts_default(&o->min);
  /* Accept a Newton step whose decrease of E is below E's rounding level when
     the gradient says it is a good step (the paper, section 3.3, notes that E
     is noisy; without this, tolerances below the noise floor stall). */
  o->min.accept_noise = 1;
  o->amg_at_rest = 1;
}

void bs_integrator_destroy(bs_integrator **pI) {
  if (!pI || !*pI) return;
  bs_integrator *I = *pI;
  free(I->terms);
  free(I->lists);
  free(I->mask);
  bs_minimizer_destroy(&I->min);
  free(I->x_n);
  free(I->x_hat);
  free(I->g1);
  free(I->g2);
  free(I->grad);
  free(I->gh);
  free(I->prev.d);
  free(I->hist.h);
  free(I->sw_x);
  free(I->sw_z);
  free(I->sw_z2);
  free(I->sw_zf);
  free(I->sw_mask);
  free(I->sw_body);
  free(I->sw_bt);
  free(I->sw_bn);
  bs_bsr_destroy(&I->sw_H);
  bs_linsolve_destroy(&I->sw_lin);
  if (I->B.destroy) I->B.destroy(I->B.ctx);
  free(I);
  *pI = NULL;
}

static int term_active(int static_mode, const bs_term *t) { return !(static_mode && t->dynamic_only); }

/* The term lists of the integrator, in term order, in I->lists. */
static void make_lists(bs_integrator *I) {
  bs_term **p = I->lists;
  const int n = I->n_terms;
  for (int m = 0; m < 2; m++) {
    for (int w = 0; w < 3; w++) {
      term_list *l = &I->act[m][w];
      l->t = p, l->n = 0;
      for (int i = 0; i < n; i++) {
        const bs_term *t = I->terms[i];
        if (term_active(m, t) && (w == TERMS_ALL || !t->expensive == (w == TERMS_CHEAP))) l->t[l->n++] = I->terms[i];
      }
      p += n;
    }
    I->dyn[m].t = p, I->dyn[m].n = 0;
    for (int i = 0; i < n; i++)
      if (term_active(m, I->terms[i]) && I->terms[i]->dynamic_only) I->dyn[m].t[I->dyn[m].n++] = I->terms[i];
    p += n;
    I->external[m].t = p, I->external[m].n = 0;
    for (int i = 0; i < n; i++)
      if (term_active(m, I->terms[i]) && I->terms[i]->external) I->external[m].t[I->external[m].n++] = I->terms[i];
    p += n;
  }
  I->potential.t = p, I->potential.n = 0;
  for (int i = 0; i < n; i++)
    if (I->terms[i]->kind != BS_TERM_INERTIA) I->potential.t[I->potential.n++] = I->terms[i];
}

/* What the integrator is asked to run (bs_step_refuse). */
static void features(const bs_integrator *I, bs_step_features *f) {
  memset(f, 0, sizeof *f);
  f->self_collision = I->has_expensive || I->has_convexified;
  f->postprocess_obstacle = f->friction_obstacle = -1;
  f->post_solve = I->hooks.post_solve != NULL;
  f->method = I->opts.method;
  f->linear = I->opts.min.linear;
  f->globalization = I->opts.min.globalization;
  f->amg_at_rest = I->opts.amg_at_rest;
  f->trace = I->opts.trace != NULL;
  f->integrator = I->opts.integrator;
}

static int alloc_all(bs_integrator *I, int n_terms, bs_error *err) {
  const size_t n3 = 3 * (size_t)I->nv, b = sizeof(double) * (n3 ? n3 : 1);
  I->terms = malloc(sizeof *I->terms * (n_terms ? n_terms : 1));
  I->lists = malloc(sizeof *I->lists * (size_t)(11 * n_terms + 1));
  I->mask = malloc(I->nv ? (size_t)I->nv : 1);
  I->x_n = calloc(1, b), I->x_hat = calloc(1, b), I->g1 = malloc(b), I->g2 = malloc(b);
  I->grad = malloc(b), I->gh = malloc(b);
  I->prev.d = calloc(n3 ? n3 : 1, sizeof(double));
  I->n_hist = I->opts.integrator == BS_INTEGRATOR_BDF2 ? 2 * n3 : I->opts.integrator == BS_INTEGRATOR_NEWMARK ? n3 : 0;
  I->hist.h = calloc(I->n_hist ? I->n_hist : 1, sizeof(double));
  if (!I->terms || !I->lists || !I->mask || !I->x_n || !I->x_hat || !I->g1 || !I->g2 || !I->grad || !I->gh ||
      !I->prev.d || !I->hist.h)
    return bs_error_set(err, BS_ENOMEM, "out of memory creating the integrator (%d vertices)", (int)I->nv);
  return 0;
}

/* The minimizer on the backend's pattern; with the backend's vector
 * operations, their solve replaces the linear solver (bs_vecops.h). */
static int make_minimizer(bs_integrator *I, bs_error *err) {
  /* Room for the Hessian blocks the terms may add outside the pattern. */
  I->opts.min.hessian_extra = 0;
  for (int i = 0; i < I->n_terms; i++) I->opts.min.hessian_extra += I->terms[i]->hessian_extra;
  bs_minimize_opts mo = I->opts.min;
  if (I->B.vecops) mo.linear = BS_LIN_CG;
  int rc = bs_minimizer_create(I->B.pattern, &mo, &I->min, err);
  if (!rc && I->B.vecops) rc = bs_minimizer_set_vecops(I->min, I->B.vecops, err);
  return rc;
}

int bs_integrator_create_on(const bs_step_backend *B, bs_step_data *step, int n_terms, bs_term *const *terms,
                            const uint8_t *mask, bs_script_fn script, void *script_ctx, const bs_integrator_opts *opts,
                            bs_integrator **out, bs_error *err) {
  *out = NULL;
  bs_integrator *I = calloc(1, sizeof *I);
  if (!I) {
    if (B->destroy) B->destroy(B->ctx);
    return bs_error_set(err, BS_ENOMEM, "out of memory creating the integrator");
  }
  I->B = *B;
  I->nv = B->n_vertices;
  I->n_terms = n_terms;
  I->step = step;
  if (opts) I->opts = *opts;
  else bs_integrator_opts_default(&I->opts);
  I->c = 1.0;
  int rc = (unsigned)I->opts.integrator > BS_INTEGRATOR_NEWMARK
               ? bs_error_set(err, BS_EINPUT, "integrator: unknown time integrator %d (bs_time_integrator)",
                              I->opts.integrator)
               : alloc_all(I, n_terms, err);
  if (rc) {
    bs_integrator_destroy(&I);
    return rc;
  }
  for (int i = 0; i < n_terms; i++) {
    I->terms[i] = terms[i];
    if (terms[i]->expensive) I->has_expensive = 1;
    if (terms[i]->ops->hessian_convexified) I->has_convexified = 1;
    if (terms[i]->ops->hessian_g) I->has_hessian_g = 1;
    if (terms[i]->ops->max_step) I->has_max_step = 1;
    if (terms[i]->ops->sweep) I->has_sweep = I->has_max_step = 1;
  }
  make_lists(I);
  if (mask) memcpy(I->mask, mask, (size_t)I->nv);
  else memset(I->mask, 1, (size_t)I->nv);
  I->script = script;
  I->script_ctx = script_ctx;
  I->has_hessian_g = I->has_hessian_g && I->opts.penalty_secant;
  bs_step_features f;
  features(I, &f);
  rc = bs_step_refuse(&f, B->caps, "integrator", B->name, err);
  B->publish(B->ctx, step, I->x_n, I->x_hat);
  step->load = 1.0;
  step->dt = 0;
  step->c = 1.0;
  if (!rc) rc = make_minimizer(I, err);
  if (rc) {
    bs_integrator_destroy(&I);
    return rc;
  }
  *out = I;
  return 0;
}

int bs_integrator_create(const bs_fem *fem, bs_step_data *step, int n_terms, bs_term *const *terms, const uint8_t *mask,
                         bs_script_fn script, void *script_ctx, const bs_integrator_opts *opts,
                         bs_integrator **out, bs_error *err) {
  *out = NULL;
  bs_step_backend B;
  int rc = bs_step_backend_serial(fem, &B, err);
  return rc ? rc : bs_integrator_create_on(&B, step, n_terms, terms, mask, script, script_ctx, opts, out, err);
}

int bs_integrator_set_hooks_checked(bs_integrator *I, const bs_step_hooks *hooks, bs_error *err) {
  bs_step_features f;
  features(I, &f);
  f.post_solve = hooks && hooks->post_solve;
  int rc = bs_step_refuse(&f, I->B.caps, "integrator", I->B.name, err);
  if (!rc) bs_integrator_set_hooks(I, hooks);
  return rc;
}

void bs_integrator_set_hooks(bs_integrator *I, const bs_step_hooks *hooks) {
  if (hooks) I->hooks = *hooks;
  else memset(&I->hooks, 0, sizeof I->hooks);
}

/* ---- the objective handed to the minimizer ----------------------------- */

/* A backend's error inside a callback kept as the first (run_solver returns it). */
static int note(bs_integrator *I, int rc) {
  if (rc < 0 && !I->cb_rc) I->cb_rc = rc;
  return rc;
}

/* The minimizer's status for a backend's: a term's, or 1 for an error. */
static int min_status(int rc) { return rc > 0 ? rc : rc < 0; }

/* The active terms' energies at x summed into *E, in term order. A term's
 * BS_TERM_NOT_EVALUABLE (bs_terms.h) is returned as it is (E is then NaN). */
static int terms_energy(bs_integrator *I, const double *x, terms_which which, double *E) {
  const term_list *l = &I->act[I->static_mode][which];
  return note(I, I->B.energy(I->B.ctx, l->n, l->t, x, E, NULL, &I->cb_err));
}

/* The minimizer reads a nonzero status as "x is not evaluable". */
static int obj_value(const double *x, double *E, void *ctx) {
  int rc = terms_energy(ctx, x, TERMS_ALL, E);
  return rc ? min_status(rc) : !isfinite(*E);
}

/* terms_energy for the initial guesses: +Inf where a term is not evaluable
 * (a candidate that is never chosen). */
static double guess_part(bs_integrator *I, const double *x, terms_which which) {
  double E;
  return terms_energy(I, x, which, &E) ? INFINITY : E;
}

static int obj_lower_bound(const double *x, double *E, void *ctx) {
  int rc = terms_energy(ctx, x, TERMS_CHEAP, E);
  return rc ? min_status(rc) : !isfinite(*E);
}

/* E at an initial-guess candidate whose cheap terms sum to cheap, when it may
 * beat best; else cheap itself (a lower bound of E that already reaches best:
 * the expensive terms, >= 0, are skipped, as in section 3.3). */
static double guess_energy(bs_integrator *I, const double *x, double cheap, double best) {
  if (!isfinite(cheap) || cheap >= best) return cheap;
  return cheap + guess_part(I, x, TERMS_EXPENSIVE);
}

/* grad E' at x, over the active terms, into g; the energy is summed into *E
 * in term order. Nonzero (a term's status) when a term is not evaluable;
 * *bad (may be NULL) is then its name when the backend knows it. */
static int terms_gradient(bs_integrator *I, const double *x, double *E, double *g, const char **bad) {
  const term_list *l = &I->act[I->static_mode][TERMS_ALL];
  return note(I, I->B.gradient(I->B.ctx, l->n, l->t, x, E, g, bad, &I->cb_err));
}

static int obj_gradient(const double *x, double *E, double *g, void *ctx) {
  int rc = terms_gradient(ctx, x, E, g, NULL);
  if (rc) {
    *E = NAN;
    return min_status(rc);
  }
  return isfinite(*E) ? 0 : 1;
}

/* The active terms' Hessians at x into H, projected by the hook when there
 * is one (g_raw: the unprojected gradient, NULL: computed); convex: a term's
 * convexified Hessian where it offers one; g_raw is also the terms'
 * hessian_g models' gradient when I->has_hessian_g. */
static int hessian_projected(bs_integrator *I, const double *x, const double *g_raw, int convex, bs_bsr *H) {
  const term_list *l = &I->act[I->static_mode][TERMS_ALL];
  const bs_step_hooks *h = I->hooks.project_hessian ? &I->hooks : NULL;
  int rc = I->B.hessian(I->B.ctx, l->n, l->t, x, I->has_hessian_g ? g_raw : NULL, convex, 0, h, g_raw, I->mask, H,
                        &I->cb_err);
  return min_status(note(I, rc));
}

static int obj_hessian(const double *x, bs_bsr *H, void *ctx) { return hessian_projected(ctx, x, NULL, 0, H); }

/* The Hessian when the minimizer hands over grad E'(x): no second gradient. */
static int obj_hessian_g(const double *x, const double *g_raw, bs_bsr *H, void *ctx) {
  return hessian_projected(ctx, x, g_raw, 0, H);
}

/* The minimizer's convexified model (bs_minimize.h). */
static int obj_hessian_convexified(const double *x, const double *g_raw, bs_bsr *H, void *ctx) {
  return hessian_projected(ctx, x, g_raw, 1, H);
}

/* The AMG preconditioner matrix (bs_step.h, amg_at_rest): the dynamic terms'
 * Hessians plus the PSD-projected elastic Hessian at rest or at x. */
static int obj_precond(const double *x, bs_bsr *P, void *ctx) {
  bs_integrator *I = ctx;
  const term_list *l = &I->dyn[I->static_mode];
  return I->B.precond(I->B.ctx, l->n, l->t, x, I->opts.amg_at_rest, P);
}

/* The line search's bound (bs_minimize.h, "Step bound"): the smallest of the
 * active terms' max_step along d (CCD), 1 when none bounds it. */
static int obj_max_step(const double *x, const double *d, double *alpha, void *ctx) {
  bs_integrator *I = ctx;
  double a = INFINITY;
  for (int i = 0; i < I->n_terms; i++) {
    const bs_term *t = I->terms[i];
    double ai;
    if (!t->ops->max_step || !term_active(I->static_mode, t)) continue;
    int rc = t->ops->max_step(t, x, d, &ai);
    if (rc) return rc;
    a = fmin(a, ai);
  }
  *alpha = a;
  return 0;
}

/* Step 3 with barrier contact: candidate g clipped by the CCD from xⁿ (or
 * from where the sweep of moving obstacles left the step: I->x_base),
 * g <- xⁿ + alpha (g - xⁿ) on the free vertices (scripted ones keep their
 * positions), so that the guess offered is contact-free; alpha 0 (xⁿ) when
 * the CCD cannot run. I->gh is the scratch (free before the solve). */
static void clip_guess(bs_integrator *I, double *g) {
  if (!I->has_max_step) return;
  const size_t n3 = 3 * (size_t)I->nv;
  const double *b = I->x_base;
  for (size_t i = 0; i < n3; i++) I->gh[i] = g[i] - b[i];
  double a = 0;
  if (obj_max_step(b, I->gh, &a, I) || !(a >= 0)) a = 0;
  if (a >= 1) return;
  for (size_t i = 0; i < n3; i++)
    if (I->mask[i / 3]) g[i] = b[i] + a * I->gh[i];
}

static void hook_project_gradient(const double *x, double *g, void *ctx) {
  bs_integrator *I = ctx;
  note(I, I->B.project_gradient(I->B.ctx, &I->hooks, x, g, &I->cb_err));
}

static void hook_project(double *x, void *ctx) {
  bs_integrator *I = ctx;
  note(I, I->B.project(I->B.ctx, &I->hooks, x, &I->cb_err));
}

static void hook_register(const double *x, const double *g, void *ctx) {
  bs_integrator *I = ctx;
  I->B.register_active(I->B.ctx, &I->hooks, x, g);
}

static void obj_trace(const bs_min_iter *it, void *ctx) {
  bs_integrator *I = ctx;
  char kept[32] = "", bound[32] = "";
  if (it->lin_downhill_iterate > 0) snprintf(kept, sizeof kept, " (iterate %d)", it->lin_downhill_iterate);
  if (it->alpha_bound < 1) snprintf(bound, sizeof bound, " bound %.4g", it->alpha_bound);
  fprintf(I->opts.trace,
          "  iteration %d: |grad E| %.6e  E %.12e -> %.12e  krylov %d%s%s%s  alpha %.4g (%d trials)%s%s\n",
          it->iteration, it->grad_norm, it->phi0, it->phi, it->lin_iterations, it->lin_indefinite ? " (indefinite)" : "",
          kept, it->convexified ? " (convexified)" : "", it->alpha, it->ls_evaluations, bound,
          it->direction != BS_DIR_NEWTON ? (it->direction == BS_DIR_NEG_DX ? " fallback -dx" : " fallback -g") : "");
  fflush(I->opts.trace);
}

/* The 2-norm over the free dofs of the active external loads' forces (the
 * scale of opts.load_rtol), computed in I->g1 (free once the guess is in x);
 * 0 when there is none or it is not evaluable. */
static double load_norm(bs_integrator *I, const double *x) {
  const term_list *l = &I->external[I->static_mode];
  double e, s = 0;
  if (l->n == 0 || note(I, I->B.gradient(I->B.ctx, l->n, l->t, x, &e, I->g1, NULL, &I->cb_err))) return 0;
  if (note(I, I->B.free_sq(I->B.ctx, I->g1, I->mask, &s, &I->cb_err))) return 0;
  return isfinite(s) ? sqrt(s) : 0;
}
int bs_step_objective_quadratic(int n_terms, bs_term *const *terms, int statics, int projected) {
  if (projected) return 0;
  for (int i = 0; i < n_terms; i++)
    if (!(statics && terms[i]->dynamic_only) && !terms[i]->quadratic) return 0;
  return 1;
}

bs_forcing bs_step_forcing(bs_forcing forcing_ew, int64_t inverted) {
  return forcing_ew == BS_FORCING_ADAPTIVE && inverted > 0 ? BS_FORCING_PAPER : forcing_ew;
}

void bs_step_stats_add(bs_step_stats *st, const bs_step_stats *sub) {
  st->min.iterations += sub->min.iterations;
  st->min.cg_iterations += sub->min.cg_iterations;
  st->min.ls_evaluations += sub->min.ls_evaluations;
  st->min.indefinite_exits += sub->min.indefinite_exits;
  st->min.downhill_iterates += sub->min.downhill_iterates;
  st->min.convexified += sub->min.convexified;
  st->min.fallback_neg_dx += sub->min.fallback_neg_dx;
  st->min.fallback_neg_grad += sub->min.fallback_neg_grad;
  st->min.clamps += sub->min.clamps;
  st->min.cholmod_fallbacks += sub->min.cholmod_fallbacks;
  st->min.ls_failures += sub->min.ls_failures;
  st->min.noise_steps += sub->min.noise_steps;
  st->min.ccd_limited += sub->min.ccd_limited;
  st->min.tol_used = sub->min.tol_used;
  st->min.reason = sub->min.reason;
  st->min.reason_text = sub->min.reason_text;
  st->min.grad_norm = sub->min.grad_norm;
  st->min.E = sub->min.E;
  st->failed |= sub->failed;
}

static void make_objective(bs_integrator *I, const double *x, bs_objective *o) {
  memset(o, 0, sizeof *o);
  o->load_norm = I->opts.min.load_rtol > 0 ? load_norm(I, x) : 0; /* read by load_rtol only */
  o->quadratic = bs_step_objective_quadratic(I->n_terms, I->terms, I->static_mode, I->hooks.project != NULL);
  o->n = I->nv;
  o->mask = I->mask;
  o->value = obj_value;
  o->gradient = obj_gradient;
  o->hessian = obj_hessian;
  o->project = I->hooks.project ? hook_project : NULL;
  o->register_active = I->hooks.register_active ? hook_register : NULL;
  o->project_gradient = I->hooks.project_gradient ? hook_project_gradient : NULL;
  o->hessian_g = I->hooks.project_hessian || I->has_hessian_g ? obj_hessian_g : NULL;
  o->hessian_convexified = I->has_convexified ? obj_hessian_convexified : NULL;
  o->value_lower_bound = I->has_expensive ? obj_lower_bound : NULL;
  o->precond_matrix = I->B.precond ? obj_precond : NULL;
  o->trace = I->opts.trace ? obj_trace : NULL;
  o->max_step = I->has_max_step ? obj_max_step : NULL;
  o->ctx = I;
}

void bs_integrator_get_carry(const bs_integrator *I, bs_min_carry *c) { bs_minimizer_get_carry(I->min, c); }
void bs_integrator_set_carry(bs_integrator *I, const bs_min_carry *c) { bs_minimizer_set_carry(I->min, c); }

void bs_integrator_get_previous(const bs_integrator *I, bs_previous_step *p) {
  const size_t n3 = 3 * (size_t)I->nv;
  p->have = I->prev.have, p->dt = I->prev.dt, p->mark = I->prev.mark;
  if (p->d) memcpy(p->d, I->prev.d, sizeof(double) * n3);
}

void bs_integrator_set_previous(bs_integrator *I, const bs_previous_step *p) {
  const size_t n3 = 3 * (size_t)I->nv;
  I->prev.have = p->have && p->d && p->dt > 0, I->prev.dt = p->dt, I->prev.mark = p->mark;
  if (I->prev.have) memcpy(I->prev.d, p->d, sizeof(double) * n3);
}
size_t bs_integrator_history_doubles(const bs_integrator *I) { return I->n_hist; }

void bs_integrator_get_history(const bs_integrator *I, bs_step_history *hs) {
  hs->have = I->hist.have, hs->dt = I->hist.dt, hs->mark = I->hist.mark;
  if (hs->h && I->n_hist) memcpy(hs->h, I->hist.h, sizeof(double) * I->n_hist);
}

void bs_integrator_set_history(bs_integrator *I, const bs_step_history *hs) {
  I->hist.have = I->n_hist && hs->have && hs->h && hs->dt > 0, I->hist.dt = hs->dt, I->hist.mark = hs->mark;
  if (I->hist.have) memcpy(I->hist.h, hs->h, sizeof(double) * I->n_hist);
}

void bs_integrator_set_stop(bs_integrator *I, volatile sig_atomic_t *stop) { bs_minimizer_set_stop(I->min, stop); }

double bs_integrator_energy(bs_integrator *I, const double *x) {
  double E;
  obj_value(x, &E, I);
  return E;
}

int32_t bs_integrator_vertices(const bs_integrator *I) { return I->nv; }

int bs_integrator_count_inverted(bs_integrator *I, const double *x, int64_t *n, bs_error *err) {
  return I->B.count_inverted(I->B.ctx, x, n, err);
}

int bs_integrator_any(bs_integrator *I, int flag, int *any, bs_error *err) {
  int64_t f = flag != 0;
  int rc = I->B.sum_i64(I->B.ctx, &f, 1, err);
  *any = f > 0;
  return rc;
}

/* ∇Φ(xⁿ) = −f(xⁿ) into I->grad: every term but inertia. BS_ENUMERIC, naming
 * the term, when one is not evaluable at xⁿ. */
static int potential_gradient(bs_integrator *I, bs_error *err) {
  double e;
  const char *bad = NULL;
  int rc = I->B.gradient(I->B.ctx, I->potential.n, I->potential.t, I->x_n, &e, I->grad, &bad, err);
  if (rc <= 0) return rc;
  if (!bad) return bs_error_set(err, BS_ENUMERIC, "a term is not evaluable at the positions of the step's start");
  return bs_error_set(err, BS_ENUMERIC, "the %s term is not evaluable at the positions of the step's start", bad);
}

/* NaN / Inf in a vector (on some process): BS_ENUMERIC (on every process). */
static int check_finite(bs_integrator *I, const double *a, const char *what, bs_error *err) {
  const size_t n = 3 * (size_t)I->nv;
  size_t bad = n;
  for (size_t i = 0; i < n && bad == n; i++)
    if (!isfinite(a[i])) bad = i;
  int any, rc = bs_integrator_any(I, bad < n, &any, err);
  if (rc || !any) return rc;
  if (bad == n) return bs_error_set(err, BS_ENUMERIC, "a %s is not finite on another process", what);
  return bs_error_set(err, BS_ENUMERIC, "%s of vertex %zu (component %zu) is not finite (%g)", what, bad / 3, bad % 3,
                      a[bad]);
}

/* The solve's options: the initial guess's kind, the adaptive forcing
 * (cg_forcing adaptive: the paper's loose solves while the step starts
 * tangled, where they untangle best; README, Scenes), the backend's linear
 * solver. */
static int solve_opts(bs_integrator *I, int naive, bs_minimize_opts *mo, bs_error *err) {
  I->opts.min.naive_guess = naive;
  *mo = I->opts.min;
  int rc = 0;
  if (mo->forcing_ew == BS_FORCING_ADAPTIVE) {
    int64_t inv = 0;
    rc = I->B.count_inverted(I->B.ctx, I->x_n, &inv, err);
    mo->forcing_ew = bs_step_forcing(BS_FORCING_ADAPTIVE, inv);
  }
  const term_list *l = &I->act[I->static_mode][TERMS_ALL];
  const double pdt = I->static_mode ? 0.0 : I->step->dt * sqrt(I->c); /* sqrt(1) dt = dt */
  if (!rc) rc = I->B.prepare_solve(I->B.ctx, I->min, mo, pdt, l->n, l->t, I->mask, I->opts.amg_at_rest, err);
  if (I->B.vecops) mo->linear = BS_LIN_CG; /* their solve replaces the linear solver */
  return rc ? rc : bs_minimizer_set_opts(I->min, mo, err);
}

static int run_solver(bs_integrator *I, double *x, int naive, bs_step_stats *st, bs_error *err) {
  bs_objective obj;
  I->cb_rc = 0;
  make_objective(I, x, &obj);
  bs_minimize_opts mo;
  int rc = solve_opts(I, naive, &mo, err);
  if (rc) return rc;
  if (I->opts.method == BS_METHOD_OPTIMIZATION) rc = bs_minimize(I->min, &obj, x, &st->min, err);
  else rc = bs_newton(I->min, &obj, I->opts.method == BS_METHOD_NEWTON_K ? I->opts.newton_k : 0, x, &st->min, err);
  if (!rc && I->cb_rc) {
    if (err) *err = I->cb_err;
    rc = I->cb_rc;
  }
  if (!rc && I->B.solve_error) rc = I->B.solve_error(I->B.ctx, err);
  if (rc) return rc;
  /* "k Newton steps and stop" ends by design without convergence: not a failure. */
  st->failed = !bs_min_reason_converged(st->min.reason) && st->min.reason != BS_MIN_STEPS_DONE;
  return 0;
}

/* The mark of the state (x, v) a step left: the previous-step guess is
 * offered only from that state. */
static uint64_t state_mark(const double *x, const double *v, size_t n3) {
  return bs_fnv1a(bs_fnv1a(BS_FNV_SEED, x, sizeof(double) * n3), v, sizeof(double) * n3);
}

/* x <- P(x) outside the minimizer (the guesses, the start of statics). */
static int project_now(bs_integrator *I, double *x, bs_error *err) {
  return I->hooks.project ? I->B.project(I->B.ctx, &I->hooks, x, err) : 0;
}

/* A later candidate in I->g1 (xⁿ, the previous-step guess) made admissible
 * (masked vertices at xⁿ, then scripted ones at their positions at t1, then
 * projected: constraint collisions) and taken into x as `kind` when its E is
 * below Eb, the chosen guess's. Returns the chosen guess's E after. */
static double offer_candidate(bs_integrator *I, double t1, double Eb, bs_guess kind, double *x, int *naive,
                              bs_step_stats *st) {
  const size_t nv = (size_t)I->nv;
  double *g = I->g1;
  for (size_t vtx = 0; vtx < nv; vtx++)
    if (!I->mask[vtx])
      for (int k = 0; k < 3; k++) g[3 * vtx + k] = I->x_n[3 * vtx + k];
  if (I->script) I->script(t1, g, I->script_ctx);
  if (note(I, project_now(I, g, &I->cb_err))) return Eb;
  clip_guess(I, g);
  const double Ec = guess_energy(I, g, guess_part(I, g, TERMS_CHEAP), isfinite(Eb) ? Eb : INFINITY);
  if (!isfinite(Ec) || (isfinite(Eb) && Ec >= Eb)) return Eb;
  memcpy(x, g, sizeof(double) * 3 * nv);
  st->guess = kind;
  *naive = 1;
  return Ec;
}

/* The previous-step candidate (bs_step.h, step 3): xⁿ + (Δt / Δt_prev) d,
 * d the last step's displacement before its post-solve hooks (friction)
 * changed vⁿ, scripted vertices at tⁿ⁺¹, projected; taken into x when its E
 * is below Eb, the chosen guess's. Offered only when (x, v) is the state
 * that step left (its mark). */
static void previous_step_guess(bs_integrator *I, double t, double dt, double *x, const double *v, double Eb,
                                int *naive, bs_step_stats *st) {
  const size_t n3 = 3 * (size_t)I->nv;
  if (!I->prev.have || I->prev.mark != state_mark(I->x_n, v, n3)) return;
  const double s = dt / I->prev.dt;
  for (size_t i = 0; i < n3; i++) I->g1[i] = I->x_n[i] + s * I->prev.d[i];
  offer_candidate(I, t + dt, Eb, BS_GUESS_PREVIOUS, x, naive, st);
}

/* Step 3's paper guesses in I->g1 (x̂) and I->g2 (explicit), and xⁿ with
 * opts.guess_xn: the one with the smallest E into x (st->guess, *naive).
 * Returns its E (+Inf when none is evaluable). */
static double paper_guesses(bs_integrator *I, double t, double dt, double *x, int *naive, bs_step_stats *st) {
  const size_t n3 = 3 * (size_t)I->nv;
  clip_guess(I, I->g1);
  clip_guess(I, I->g2);
  /* the candidate with the smaller cheap part first: the other's expensive
     terms are then often skipped (and the detection left for the solve is the
     chosen guess's) */
  const double c1 = guess_part(I, I->g1, TERMS_CHEAP), c2 = guess_part(I, I->g2, TERMS_CHEAP);
  double E1, E2;
  if (c2 < c1) {
    E2 = guess_energy(I, I->g2, c2, INFINITY);
    E1 = guess_energy(I, I->g1, c1, E2);
  } else {
    E1 = guess_energy(I, I->g1, c1, INFINITY);
    E2 = guess_energy(I, I->g2, c2, E1);
  }
  *naive = 1;
  if (isfinite(E2) && (!isfinite(E1) || E2 < E1)) {
    memcpy(x, I->g2, sizeof(double) * n3);
    st->guess = BS_GUESS_EXPLICIT;
    *naive = 0;
  } else {
    memcpy(x, I->g1, sizeof(double) * n3);
  }
  /* A third candidate with opts.guess_xn (bs_step.h): xⁿ itself, scripted
     vertices at tⁿ⁺¹, projected; chosen only when its E is the smallest. */
  const double Eb = st->guess == BS_GUESS_EXPLICIT ? E2 : E1;
  if (!I->opts.guess_xn) return Eb;
  memcpy(I->g1, I->x_n, sizeof(double) * n3);
  return offer_candidate(I, t + dt, Eb, BS_GUESS_XN, x, naive, st);
}

/* Whether the step from (xⁿ = I->x_n, v) of size dt has its integrator's
 * history (bs_step.h): the one the last step left at this state (BDF2: at
 * this dt too). */
static int history_usable(const bs_integrator *I, double dt, const double *v) {
  if (I->opts.integrator == BS_INTEGRATOR_BACKWARD_EULER || !I->hist.have) return 0;
  if (I->opts.integrator == BS_INTEGRATOR_BDF2 && I->hist.dt != dt) return 0;
  return I->hist.mark == state_mark(I->x_n, v, 3 * (size_t)I->nv);
}

/* The step's c and x̃ (bs_step.h) into I->c, I->x_hat from xⁿ = I->x_n, v
 * and, with use, the history (Newmark without one: aⁿ = 0 here, set by
 * newmark_start). BDF2 without history: backward Euler's. */
static void predict(bs_integrator *I, double dt, const double *v, int use) {
  const size_t n3 = 3 * (size_t)I->nv;
  const double *x = I->x_n, *h = I->hist.h;
  if (I->opts.integrator == BS_INTEGRATOR_NEWMARK) {
    I->c = 0.25; /* beta */
    if (!use) memset(I->hist.h, 0, sizeof(double) * n3);
    for (size_t i = 0; i < n3; i++) I->x_hat[i] = x[i] + dt * v[i] + dt * dt * 0.25 * h[i]; /* (1/2 - beta) */
  } else if (I->opts.integrator == BS_INTEGRATOR_BDF2 && use) {
    I->c = 4.0 / 9.0;
    const double w = 2.0 * dt / 9.0;
    for (size_t i = 0; i < n3; i++) I->x_hat[i] = (4.0 * x[i] - h[i]) / 3.0 + w * (4.0 * v[i] - h[n3 + i]);
  } else {
    I->c = 1.0;
    for (size_t i = 0; i < n3; i++) I->x_hat[i] = x[i] + dt * v[i];
  }
  I->step->c = I->c;
}

/* Newmark without history: M aⁿ = f(xⁿ) = −I->grad (lumped M; 0 on scripted
 * and fixed vertices and those without mass) into the history, x̃ again. */
static void newmark_start(bs_integrator *I, double dt, const double *v) {
  const size_t nv = (size_t)I->nv;
  double *a = I->hist.h;
  for (size_t vtx = 0; vtx < nv; vtx++) {
    const double m = I->B.mass[vtx], s = I->mask[vtx] && m > 0 ? -1.0 / m : 0.0;
    for (int k = 0; k < 3; k++) a[3 * vtx + k] = s * I->grad[3 * vtx + k];
  }
  predict(I, dt, v, 1);
  I->B.publish(I->B.ctx, I->step, I->x_n, I->x_hat);
}

/* Step 5's vⁿ⁺¹ from the solve's x (bs_step.h), and the history it leaves
 * (its mark is set after the post-solve hooks). use: the step had its
 * history (history_usable). */
static void update_velocity(bs_integrator *I, double dt, const double *x, double *v, int use) {
  const size_t n3 = 3 * (size_t)I->nv;
  const double *xn = I->x_n;
  double *h = I->hist.h;
  if (I->opts.integrator == BS_INTEGRATOR_NEWMARK) {
    const double ib = 1.0 / (0.25 * dt * dt); /* 1/(beta dt^2), gamma = 1/2 */
    for (size_t i = 0; i < n3; i++) {
      const double a1 = (x[i] - I->x_hat[i]) * ib;
      v[i] += dt * (0.5 * h[i] + 0.5 * a1);
      h[i] = a1;
    }
  } else if (I->opts.integrator == BS_INTEGRATOR_BDF2) {
    for (size_t i = 0; i < n3; i++) {
      const double v1 = use ? (3.0 * x[i] - 4.0 * xn[i] + h[i]) / (2.0 * dt) : (x[i] - xn[i]) / dt;
      h[i] = xn[i], h[n3 + i] = v[i];
      v[i] = v1;
    }
  } else {
    for (size_t i = 0; i < n3; i++) v[i] = (x[i] - xn[i]) / dt;
  }
}

/* Step 1: the step data, x̃ and c (predict), the terms' begin_step; *use:
 * whether the step has its integrator's history. */
static int begin_step(bs_integrator *I, double t, double dt, const double *x, const double *v, int *use,
                      bs_error *err) {
  const size_t n3 = 3 * (size_t)I->nv;
  I->static_mode = 0;
  I->step->dt = dt;
  I->step->time = t + dt;
  I->step->load = 1.0;
  memcpy(I->x_n, x, sizeof(double) * n3);
  *use = history_usable(I, dt, v);
  predict(I, dt, v, *use);
  I->B.publish(I->B.ctx, I->step, I->x_n, I->x_hat);
  int rc = 0;
  for (int i = 0; i < I->n_terms && !rc; i++)
    if (I->terms[i]->ops->begin_step) rc = I->terms[i]->ops->begin_step(I->terms[i], err);
  return rc;
}

/* Steps 2 and 3: the paper's guesses in I->g1 (x̂) and I->g2 (x̂ + Δt² M⁻¹
 * f(xⁿ), f = -I->grad), scripted vertices at tⁿ⁺¹ in both, projected. */
static int make_guesses(bs_integrator *I, double t1, double dt, bs_error *err) {
  const size_t nv = (size_t)I->nv, n3 = 3 * nv;
  memcpy(I->g1, I->x_hat, sizeof(double) * n3);
  for (size_t vtx = 0; vtx < nv; vtx++) {
    double c = I->B.mass[vtx] > 0 ? I->c * dt * dt / I->B.mass[vtx] : 0; /* c = 1: dt * dt / m exactly */
    for (int k = 0; k < 3; k++) I->g2[3 * vtx + k] = I->x_hat[3 * vtx + k] - c * I->grad[3 * vtx + k];
  }
  if (I->script) {
    I->script(t1, I->g1, I->script_ctx);
    I->script(t1, I->g2, I->script_ctx);
  }
  /* Scripted vertices keep their scripted positions in both guesses. */
  for (size_t vtx = 0; vtx < nv; vtx++)
    if (!I->mask[vtx])
      for (int k = 0; k < 3; k++) {
        if (!I->script) I->g1[3 * vtx + k] = I->g2[3 * vtx + k] = I->x_n[3 * vtx + k];
        else I->g2[3 * vtx + k] = I->g1[3 * vtx + k];
      }
  int rc = project_now(I, I->g1, err);
  return rc ? rc : project_now(I, I->g2, err);
}

/* Step 5's post-solve hooks (friction) with g = grad E'(xⁿ⁺¹), and the
 * previous-step guess they leave for the next step. */
static int post_solve(bs_integrator *I, double dt, double *x, double *v, const bs_step_stats *st, bs_error *err) {
  const size_t n3 = 3 * (size_t)I->nv;
  double E;
  const char *bad = "?";
  int rc = terms_gradient(I, x, &E, I->gh, &bad);
  if (rc < 0) return rc;
  if (rc) return bs_error_set(err, BS_ENUMERIC, "the %s term is not evaluable at the solution (post-solve hooks)", bad);
  memcpy(I->g1, v, sizeof(double) * n3); /* the solve's own velocity, before friction */
  if ((rc = I->hooks.post_solve(I->x_n, x, I->gh, v, dt, I->hooks.ctx, err))) return rc;
  /* a stopped step is undone: keep the one before; hooks that left v as it
     was (no friction acted) make the candidate x̂ itself: none */
  if (st->min.reason != BS_MIN_STOPPED) {
    I->prev.have = memcmp(v, I->g1, sizeof(double) * n3) != 0;
    for (size_t i = 0; i < n3 && I->prev.have; i++) I->prev.d[i] = dt * I->g1[i];
    I->prev.dt = dt;
    I->prev.mark = I->prev.have ? state_mark(x, v, n3) : 0;
  }
  return 0;
}

/* ---- moving obstacles within a step (bs_step.h, "Moving obstacles") ---- */

#define BS_SWEEP_STAGES 256   /* stages before a sweep is given up (fig14: up to 56)     */
#define BS_SWEEP_STAGE_ITER 8 /* Newton iterations of a stage's solve (it only makes room) */

/* The certified fraction *s of the path (x + a d, time t0 + a (t1 - t0)),
 * a in [0, 1]: the smallest over the active terms of sweep, and of max_step
 * along d for the terms without sweep (d NULL: x fixed, 1 for them). */
static int path_fraction(bs_integrator *I, const double *x, const double *d, double t0, double t1, double *s) {
  double a = 1;
  for (int i = 0; i < I->n_terms && a > 0; i++) {
    const bs_term *t = I->terms[i];
    double ai = 1;
    int rc = 0;
    if (t->ops->sweep) rc = t->ops->sweep(t, x, d, t0, t1, &ai);
    else if (d && t->ops->max_step) rc = t->ops->max_step(t, x, d, &ai);
    if (rc) return rc;
    a = fmin(a, ai);
  }
  *s = a;
  return 0;
}

static int32_t body_root(int32_t *up, int32_t v) {
  while (up[v] != v) v = up[v] = up[up[v]];
  return v;
}

/* I->sw_body: each vertex's body, the connected components of the
 * pattern's graph (vertices that share a tet), numbered in vertex order. */
static void label_bodies(bs_integrator *I) {
  const bs_bsr *P = I->B.pattern;
  int32_t *up = I->sw_body;
  for (int32_t v = 0; v < I->nv; v++) up[v] = v;
  for (int32_t v = 0; v < I->nv; v++)
    for (int32_t s = P->row_ptr[v]; s < P->row_ptr[v + 1]; s++) {
      const int32_t a = body_root(up, v), b = body_root(up, P->col[s]);
      if (a != b) up[a > b ? a : b] = a < b ? a : b;
    }
  int32_t n = 0;
  for (int32_t v = 0; v < I->nv; v++) up[v] = up[v] == v ? n++ : up[up[v]];
  I->n_bodies = n;
}

static int sweep_alloc(bs_integrator *I, bs_error *err) {
  if (I->sw_lin) return 0;
  const size_t n3 = 3 * (size_t)I->nv + 1;
  const bs_bsr *P = I->B.pattern;
  I->sw_x = malloc(sizeof(double) * n3), I->sw_z = malloc(sizeof(double) * n3), I->sw_z2 = malloc(sizeof(double) * n3);
  I->sw_zf = malloc(sizeof(double) * n3), I->sw_mask = malloc((size_t)I->nv + 1);
  I->sw_body = malloc(sizeof(int32_t) * ((size_t)I->nv + 1));
  if (I->sw_body && !I->B.vecops) label_bodies(I);
  I->sw_bt = malloc(sizeof(double) * (3 * (size_t)I->n_bodies + 1));
  I->sw_bn = malloc(sizeof(int32_t) * ((size_t)I->n_bodies + 1));
  if (!I->sw_x || !I->sw_z || !I->sw_z2 || !I->sw_zf || !I->sw_mask || !I->sw_body || !I->sw_bt || !I->sw_bn)
    return bs_error_set(err, BS_ENOMEM, "out of memory for the sweep of moving obstacles");
  int rc = bs_bsr_create(P->n, P->row_ptr, P->col, &I->sw_H, err);
  if (!rc && I->opts.min.hessian_extra > 0) rc = bs_bsr_reserve_extra(I->sw_H, I->opts.min.hessian_extra, err);
  return rc ? rc : bs_linsolve_create(I->sw_H, BS_LIN_PCG, &I->sw_lin, err);
}

/* The sweep's marks of carried vertices (I->sw_mask while the predictor is
 * made): by a term along with others, or by a moving domain itself. */
enum { SWEEP_ALONG = 1, SWEEP_BY_DOMAIN = 2 };

/* The bodies with a carried vertex (c) move rigidly in z, each by the mean
 * displacement of its carried vertices, unless one of its vertices is not
 * free (I->mask): then only its vertices a moving domain carries
 * (SWEEP_BY_DOMAIN) stay carried. Returns the vertices carried then. */
static int32_t carry_bodies(bs_integrator *I, double *z, uint8_t *c) {
  const int32_t nb = I->n_bodies, *body = I->sw_body;
  double *t = I->sw_bt;
  int32_t *n = I->sw_bn, marked = 0;
  memset(n, 0, sizeof(int32_t) * (size_t)nb);
  memset(t, 0, sizeof(double) * 3 * (size_t)nb);
  for (int32_t v = 0; v < I->nv; v++) {
    if (!I->mask[v]) n[body[v]] = -1;
    if (!c[v] || n[body[v]] < 0) continue;
    n[body[v]]++;
    for (int k = 0; k < 3; k++) t[3 * body[v] + k] += z[3 * (size_t)v + k];
  }
  for (int32_t v = 0; v < I->nv; v++) {
    const int32_t b = body[v];
    if (n[b] > 0) {
      c[v] = SWEEP_ALONG;
      for (int k = 0; k < 3; k++) z[3 * (size_t)v + k] = t[3 * b + k] / n[b];
    } else if (c[v] == SWEEP_ALONG) { /* carried along in a body that is not rigid: left to the response */
      c[v] = 0;
      for (int k = 0; k < 3; k++) z[3 * (size_t)v + k] = 0;
    }
    marked += c[v] != 0;
  }
  return marked;
}

/* Calls the carry of the terms with (moving: 1) or without sweep. */
static int terms_carry(bs_integrator *I, int moving, const double *x, double t0, double t1, double *z, uint8_t *c,
                       bs_error *err) {
  for (int i = 0; i < I->n_terms; i++) {
    const bs_term *t = I->terms[i];
    if (t->ops->carry && moving == (t->ops->sweep != NULL) && t->ops->carry(t, x, t0, t1, z, c))
      return bs_error_set(err, BS_ENUMERIC, "the %s term cannot say what it carries in the sweep", t->name);
  }
  return 0;
}

/* What the sweep carries from (x, t0) to t1 (bs_term_ops.carry): the
 * vertices of the moving domains; their bodies (carry_bodies); and, until
 * no vertex is added, what the other terms carry along with those (barrier
 * contact: the vertices of its active pairs) and their bodies. */
static int sweep_carry(bs_integrator *I, const double *x, double t0, double t1, int rigid, double *z, uint8_t *c,
                       int *grew, bs_error *err) {
  *grew = 0;
  int rc = terms_carry(I, 1, x, t0, t1, z, c, err);
  if (rc || !rigid || I->B.vecops) return rc;
  int32_t first = 0;
  for (int32_t v = 0; v < I->nv; v++) {
    c[v] = c[v] ? SWEEP_BY_DOMAIN : 0;
    first += c[v] != 0;
  }
  int32_t marked = carry_bodies(I, z, c), before = -1;
  for (int pass = 0; pass < I->n_bodies && marked > before && !rc; pass++) {
    before = marked;
    if (!(rc = terms_carry(I, 0, x, t0, t1, z, c, err))) marked = carry_bodies(I, z, c);
  }
  *grew = marked > first;
  return rc;
}

/* The sweep's predictor from (x, t0) to t1 into z: the vertices the terms
 * carry (sweep_carry; with rigid, their bodies too) move with them, and
 * every other free vertex by the linear response of the step's objective
 * to that motion, H_ff z_f = -H_fc z_c (H the convexified Hessian at x,
 * assembled once per stage: *H_done; PCG to 1e-3 over the free vertices
 * not carried). z = 0 when nothing is carried. *grew: rigid added vertices
 * (else the predictor is the one without rigid). */
static int sweep_predictor(bs_integrator *I, const double *x, double t0, double t1, int rigid, double *z, int *grew,
                           int *H_done, bs_error *err) {
  const size_t nv = (size_t)I->nv, n3 = 3 * nv;
  uint8_t *c = I->sw_mask;
  memset(c, 0, nv);
  memset(z, 0, sizeof(double) * n3);
  int rc = sweep_carry(I, x, t0, t1, rigid, z, c, grew, err);
  if (rc) return rc;
  int any = 0;
  for (size_t v = 0; v < nv; v++) {
    c[v] = c[v] && I->mask[v];
    for (int k = 0; k < 3 && !c[v]; k++) z[3 * v + k] = 0;
    any |= c[v];
  }
  if (!any || I->B.vecops) return 0;
  if (!*H_done) {
    rc = hessian_projected(I, x, NULL, 1, I->sw_H);
    if (rc) return rc < 0 ? rc : bs_error_set(err, BS_ENUMERIC, "the Hessian is not evaluable in the sweep");
    bs_bsr_index_extra(I->sw_H);
    *H_done = 1;
  }
  double *b = I->gh, *zf = I->sw_zf;
  bs_bsr_mul(I->sw_H, NULL, z, b);
  for (size_t v = 0; v < nv; v++) {
    c[v] = I->mask[v] && !c[v]; /* now: the vertices that follow */
    for (int k = 0; k < 3; k++) b[3 * v + k] = c[v] ? -b[3 * v + k] : 0.0;
  }
  if ((rc = bs_linsolve_solve(I->sw_lin, I->sw_H, c, b, 1e-3, 0, zf, NULL, err))) return rc;
  for (size_t i = 0; i < n3; i++)
    if (c[i / 3]) z[i] = zf[i];
  return 0;
}

/* A predictor (rigid or not) from (x, tau) into z, *moving (z != 0) and
 * the fraction *s of the path to t1 that the terms certify. */
static int sweep_try(bs_integrator *I, const double *x, double tau, double t1, int rigid, double *z, int *grew,
                     int *H_done, int *moving, double *s, bs_error *err) {
  int rc = sweep_predictor(I, x, tau, t1, rigid, z, grew, H_done, err);
  if (rc) return rc;
  *moving = 0;
  for (size_t i = 0; i < 3 * (size_t)I->nv; i++) *moving |= z[i] != 0;
  if ((rc = path_fraction(I, x, *moving ? z : NULL, tau, t1, s)))
    return rc < 0 ? rc : bs_error_set(err, BS_ENUMERIC, "a contact term is not evaluable on the sweep's path");
  return 0;
}

/* The stage's predictor into *z (I->sw_z or I->sw_z2): the rigid one
 * (bodies carried whole), and when it is limited and differs, the one
 * without, whichever the terms certify further (a body carried whole may
 * be blocked, a pile against a wall, where its parts can give). */
static int sweep_choose(bs_integrator *I, const double *x, double tau, double t1, double **z, int *moving, double *s,
                        bs_error *err) {
  int grew = 0, H_done = 0, moving2 = 0, grew2 = 0;
  double s2 = 0;
  *z = I->sw_z;
  int rc = sweep_try(I, x, tau, t1, 1, *z, &grew, &H_done, moving, s, err);
  if (rc || !grew || *s >= 1) return rc;
  if ((rc = sweep_try(I, x, tau, t1, 0, I->sw_z2, &grew2, &H_done, &moving2, &s2, err))) return rc;
  if (s2 > *s) *z = I->sw_z2, *moving = moving2, *s = s2;
  return 0;
}

/* One stage from (x, *tau): along the predictor to the time it certifies,
 * then (when something is pushed and the step's end is not reached) the
 * step's objective minimized there, for at most BS_SWEEP_STAGE_ITER
 * iterations: the stage's answer only has to make room for the next one
 * (the step's own solve converges as usual). */
static int sweep_stage(bs_integrator *I, double *x, double *tau, double t0, double t1, bs_step_stats *acc,
                       bs_error *err) {
  const size_t n3 = 3 * (size_t)I->nv;
  double *z = NULL, s = 0;
  int moving = 0;
  I->step->time = *tau;
  int rc = sweep_choose(I, x, *tau, t1, &z, &moving, &s, err);
  if (rc) return rc;
  const double span = t1 - *tau;
  if (!(s > 0))
    return bs_error_set(err, BS_ENUMERIC,
                        "moving obstacles: the sweep of the step from t = %g s to %g s stands still at t = %g s: a "
                        "vertex touches a moving barrier obstacle closer than the CCD can certify",
                        t0, t1, *tau);
  if (moving)
    for (size_t i = 0; i < n3; i++) x[i] += fmin(s, 1.0) * z[i];
  *tau = s >= 1 ? t1 : *tau + s * span;
  acc->sweep_stages++;
  if (*tau >= t1 || !moving) return 0;
  I->step->time = *tau;
  bs_step_stats sub;
  memset(&sub, 0, sizeof sub);
  const int keep = I->opts.min.max_iter;
  I->opts.min.max_iter = keep < BS_SWEEP_STAGE_ITER ? keep : BS_SWEEP_STAGE_ITER;
  rc = run_solver(I, x, 1, &sub, err);
  I->opts.min.max_iter = keep;
  if (rc) return rc;
  sub.failed = 0; /* a stage's solve need not converge: its answer only has to be in the domain */
  bs_step_stats_add(acc, &sub);
  return 0;
}

/* 1 when a term's domain moves over xⁿ between t0 and t1 (a moving barrier
 * obstacle passes over a vertex): the step is then swept; 0 when not; a
 * negative code on errors. */
static int sweep_needed(bs_integrator *I, double t0, double t1, bs_error *err) {
  if (!I->has_sweep) return 0;
  double s = 1;
  int rc = path_fraction(I, I->x_n, NULL, t0, t1, &s);
  if (rc) return rc < 0 ? rc : bs_error_set(err, BS_ENUMERIC, "a contact term is not evaluable at the step's start");
  return s < 1;
}

/* Step 1b (needed: sweep_needed's answer): the step swept from t0 = tⁿ to
 * t1 = tⁿ⁺¹ in stages that each stay in the terms' domains, the guesses
 * then clipped from where the sweep ends (I->x_base; xⁿ without a sweep).
 * The stages' solves are counted in acc. */
static int sweep_obstacles(bs_integrator *I, int needed, double t0, double t1, bs_step_stats *acc, bs_error *err) {
  I->x_base = I->x_n;
  if (!needed) return 0;
  int rc = sweep_alloc(I, err);
  if (rc) return rc;
  double *x = I->sw_x, tau = t0;
  memcpy(x, I->x_n, sizeof(double) * 3 * (size_t)I->nv);
  for (int k = 0; k < BS_SWEEP_STAGES && tau < t1 && !rc; k++) rc = sweep_stage(I, x, &tau, t0, t1, acc, err);
  I->step->time = t1;
  if (rc) return rc;
  if (tau < t1)
    return bs_error_set(err, BS_ENUMERIC,
                        "moving obstacles: the sweep of the step from t = %g s reached only t = %g s of %g s in %d "
                        "stages",
                        t0, tau, t1, BS_SWEEP_STAGES);
  I->x_base = x;
  return 0;
}

/* st = the main solve's statistics with the sweep's stages and their
 * solves' counts (acc) added; the reason, guess and failure are the main
 * solve's. */
static void merge_sweep(bs_step_stats *st, const bs_step_stats *acc) {
  if (!acc->sweep_stages) return;
  const bs_step_stats main = *st;
  *st = *acc;
  bs_step_stats_add(st, &main);
  st->guess = main.guess;
  st->failed = main.failed;
}

int bs_integrator_step(bs_integrator *I, double t, double dt, double *x, double *v, bs_step_stats *st,
                       bs_error *err) {
  double t0 = bs_seconds();
  memset(st, 0, sizeof *st);
  const size_t n3 = 3 * (size_t)I->nv;
  if (!(dt > 0) || !isfinite(dt)) return bs_error_set(err, BS_EINPUT, "time step must be positive and finite, got %g", dt);
  int rc;
  if ((rc = check_finite(I, x, "position", err)) || (rc = check_finite(I, v, "velocity", err))) return rc;
  int use = 0;
  if ((rc = begin_step(I, t, dt, x, v, &use, err))) return rc;
  /* f(xⁿ) = −∇Φ(xⁿ): every term but inertia (moving obstacles where xⁿ
     is, at tⁿ, when they pass over it by tⁿ⁺¹: then swept). */
  bs_step_stats sw;
  memset(&sw, 0, sizeof sw);
  const int needed = sweep_needed(I, t, t + dt, err);
  if (needed < 0) return needed;
  if (needed) I->step->time = t;
  if ((rc = potential_gradient(I, err))) return rc;
  if ((rc = sweep_obstacles(I, needed, t, t + dt, &sw, err))) return rc;
  if (I->opts.integrator == BS_INTEGRATOR_NEWMARK && !use) newmark_start(I, dt, v);
  if ((rc = make_guesses(I, t + dt, dt, err))) return rc;
  int naive = 1;
  I->cb_rc = 0;
  const double Eb = paper_guesses(I, t, dt, x, &naive, st);
  if (I->hooks.post_solve) previous_step_guess(I, t, dt, x, v, Eb, &naive, st);
  if (I->cb_rc) {
    if (err) *err = I->cb_err;
    return I->cb_rc;
  }
  if ((rc = run_solver(I, x, naive, st, err))) return rc;
  merge_sweep(st, &sw);
  update_velocity(I, dt, x, v, use);
  if (I->hooks.post_solve && (rc = post_solve(I, dt, x, v, st, err))) return rc;
  if (I->n_hist) I->hist.have = 1, I->hist.dt = dt, I->hist.mark = state_mark(x, v, n3);
  st->seconds = bs_seconds() - t0;
  return 0;
}

int bs_integrator_static(bs_integrator *I, double t, int load_steps, double *x, bs_step_stats *st, bs_error *err) {
  double t0 = bs_seconds();
  memset(st, 0, sizeof *st);
  size_t n3 = 3 * (size_t)I->nv;
  int rc;
  if ((rc = check_finite(I, x, "position", err))) return rc;
  if (load_steps < 1) return bs_error_set(err, BS_EINPUT, "load_steps must be >= 1, got %d", load_steps);
  I->static_mode = 1;
  I->prev.have = 0;
  I->hist.have = 0;
  I->step->dt = 0;
  I->step->time = t;
  memcpy(I->x_n, x, sizeof(double) * n3);
  memcpy(I->x_hat, x, sizeof(double) * n3);
  I->B.publish(I->B.ctx, I->step, I->x_n, I->x_hat);
  if (I->script) I->script(t, x, I->script_ctx);
  rc = project_now(I, x, err);
  bs_step_stats sub;
  for (int l = 1; l <= load_steps && !rc; l++) {
    I->step->load = (double)l / load_steps;
    memset(&sub, 0, sizeof sub);
    if ((rc = run_solver(I, x, 1, &sub, err))) break;
    bs_step_stats_add(st, &sub);
    if (sub.min.reason == BS_MIN_STOPPED) break; /* the later load steps are not taken */
  }
  I->static_mode = 0;
  I->step->load = 1.0;
  st->seconds = bs_seconds() - t0;
  return rc;
}
