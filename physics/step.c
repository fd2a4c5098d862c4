/* step.c — backward Euler as a minimization (paper sections 2, 3.1), statics. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bs_step.h"

struct bs_integrator {
  const bs_fem *fem;
  int n_terms;
  bs_term **terms;
  uint8_t *mask;          /* owned copy (n_vertices)                 */
  bs_script_fn script;
  void *script_ctx;
  bs_integrator_opts opts;
  bs_step_hooks hooks;
  bs_step_data *step;     /* what the terms read (borrowed)          */
  int static_mode;        /* 1 while solving statics                 */
  bs_minimizer *min;
  double *x_n, *x_hat, *g1, *g2, *grad;
  double *gh;             /* 3n: grad E' for the Hessian projection   */
  int has_expensive;
  int has_convexified;    /* a term offers hessian_convexified         */
  int has_hessian_g;      /* a term offers hessian_g and opts.penalty_secant */
  double amg_dt;          /* dt of the last AMG preconditioner matrix (-1: none) */
  bs_previous_step prev;  /* the last step's displacement (prev.d: 3n, owned) */
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
  free(I->mask);
  bs_minimizer_destroy(&I->min);
  free(I->x_n);
  free(I->x_hat);
  free(I->g1);
  free(I->g2);
  free(I->grad);
  free(I->gh);
  free(I->prev.d);
  free(I);
  *pI = NULL;
}

int bs_integrator_create(const bs_fem *fem, bs_step_data *step, int n_terms, bs_term *const *terms, const uint8_t *mask,
                         bs_script_fn script, void *script_ctx, const bs_integrator_opts *opts,
                         bs_integrator **out, bs_error *err) {
  *out = NULL;
  bs_integrator *I = calloc(1, sizeof *I);
  if (!I) return bs_error_set(err, BS_ENOMEM, "out of memory creating the integrator");
  size_t nv = (size_t)fem->n_vertices, n3 = 3 * nv;
  I->fem = fem;
  I->step = step;
  I->n_terms = n_terms;
  I->terms = malloc(sizeof(bs_term *) * (size_t)(n_terms ? n_terms : 1));
  I->mask = malloc(nv ? nv : 1);
  I->x_n = malloc(sizeof(double) * (n3 ? n3 : 1));
  I->x_hat = malloc(sizeof(double) * (n3 ? n3 : 1));
  I->g1 = malloc(sizeof(double) * (n3 ? n3 : 1));
  I->g2 = malloc(sizeof(double) * (n3 ? n3 : 1));
  I->grad = malloc(sizeof(double) * (n3 ? n3 : 1));
  I->gh = malloc(sizeof(double) * (n3 ? n3 : 1));
  I->prev.d = calloc(n3 ? n3 : 1, sizeof(double));
  if (!I->terms || !I->mask || !I->x_n || !I->x_hat || !I->g1 || !I->g2 || !I->grad || !I->gh || !I->prev.d) {
    bs_integrator_destroy(&I);
    return bs_error_set(err, BS_ENOMEM, "out of memory creating the integrator (%zu vertices)", nv);
  }
  for (int i = 0; i < n_terms; i++) {
    I->terms[i] = terms[i];
    if (terms[i]->expensive) I->has_expensive = 1;
    if (terms[i]->ops->hessian_convexified) I->has_convexified = 1;
    if (terms[i]->ops->hessian_g) I->has_hessian_g = 1;
  }
  if (mask) memcpy(I->mask, mask, nv);
  else memset(I->mask, 1, nv);
  I->script = script;
  I->script_ctx = script_ctx;
  if (opts) I->opts = *opts;
  else bs_integrator_opts_default(&I->opts);
  I->has_hessian_g = I->has_hessian_g && I->opts.penalty_secant;
  I->amg_dt = -1;
  step->x_hat = I->x_hat;
  step->x_n = I->x_n;
  step->load = 1.0;
  step->dt = 0;
  /* Room for the Hessian blocks the terms may add outside the pattern. */
  I->opts.min.hessian_extra = 0;
  for (int i = 0; i < n_terms; i++) I->opts.min.hessian_extra += terms[i]->hessian_extra;
  int st = bs_minimizer_create(fem->pattern, &I->opts.min, &I->min, err);
  if (st) {
    bs_integrator_destroy(&I);
    return st;
  }
  *out = I;
  return 0;
}

void bs_integrator_set_hooks(bs_integrator *I, const bs_step_hooks *hooks) {
  if (hooks) I->hooks = *hooks;
  else memset(&I->hooks, 0, sizeof I->hooks);
}

static int term_active(const bs_integrator *I, const bs_term *t) { return !(I->static_mode && t->dynamic_only); }

/* ---- the objective handed to the minimizer ----------------------------- */
/* Which terms a sum of energies takes: all, the cheap ones (every term but
 * the expensive ones, i.e. self-collision) or the expensive ones, which are
 * >= 0 (section 3.3). */
typedef enum { TERMS_ALL, TERMS_CHEAP, TERMS_EXPENSIVE } terms_which;

/* The active terms' energies at x summed into *E, in term order. A term's
 * BS_TERM_NOT_EVALUABLE (bs_terms.h) is returned as it is (E is then NaN). */
static int terms_energy(bs_integrator *I, const double *x, terms_which which, double *E) {
  double s = 0;
  *E = NAN;
  for (int i = 0; i < I->n_terms; i++) {
    const bs_term *t = I->terms[i];
    if (!term_active(I, t) || (which != TERMS_ALL && !t->expensive != (which == TERMS_CHEAP))) continue;
    double e;
    int rc = t->ops->value(t, x, &e);
    if (rc) return rc;
    s += e;
  }
  *E = s;
  return 0;
}

/* The minimizer reads a nonzero status as "x is not evaluable". */
static int obj_value(const double *x, double *E, void *ctx) {
  int rc = terms_energy(ctx, x, TERMS_ALL, E);
  return rc ? rc : !isfinite(*E);
}

/* terms_energy for the initial guesses: +Inf where a term is not evaluable
 * (a candidate that is never chosen). */
static double guess_part(bs_integrator *I, const double *x, terms_which which) {
  double E;
  return terms_energy(I, x, which, &E) ? INFINITY : E;
}

static int obj_lower_bound(const double *x, double *E, void *ctx) {
  int rc = terms_energy(ctx, x, TERMS_CHEAP, E);
  return rc ? rc : !isfinite(*E);
}

/* E at an initial-guess candidate whose cheap terms sum to cheap, when it may
 * beat best; else cheap itself (a lower bound of E that already reaches best:
 * the expensive terms, >= 0, are skipped, as in section 3.3). */
static double guess_energy(bs_integrator *I, const double *x, double cheap, double best) {
  if (!isfinite(cheap) || cheap >= best) return cheap;
  return cheap + guess_part(I, x, TERMS_EXPENSIVE);
}

/* grad E' at x, over the active terms, into g (zeroed first); the energy is
 * summed into *E in term order. Nonzero (a term's status) when a term is not
 * evaluable; *bad (may be NULL) is then its name. */
static int terms_gradient(bs_integrator *I, const double *x, double *E, double *g, const char **bad) {
  memset(g, 0, sizeof(double) * 3 * (size_t)I->fem->n_vertices);
  double s = 0;
  for (int i = 0; i < I->n_terms; i++)
    if (term_active(I, I->terms[i])) {
      double e;
      int rc = I->terms[i]->ops->gradient(I->terms[i], x, &e, g);
      if (rc) {
        if (bad) *bad = I->terms[i]->name;
        return rc;
      }
      s += e;
    }
  *E = s;
  return 0;
}

static int obj_gradient(const double *x, double *E, double *g, void *ctx) {
  int rc = terms_gradient(ctx, x, E, g, NULL);
  if (rc) {
    *E = NAN;
    return rc;
  }
  return isfinite(*E) ? 0 : 1;
}

/* The active terms' Hessians added into H (a term's status when one is not
 * evaluable); dynamic_only: only the terms marked so; convex: a term's
 * convexified Hessian where it offers one; g (may be NULL): grad E'(x), for
 * the terms' hessian_g models when I->has_hessian_g. */
static int terms_hessian(bs_integrator *I, const double *x, const double *g, int dynamic_only, int convex,
                         bs_bsr *H) {
  for (int i = 0; i < I->n_terms; i++) {
    const bs_term *t = I->terms[i];
    if (!term_active(I, t) || (dynamic_only && !t->dynamic_only)) continue;
    int rc = convex && t->ops->hessian_convexified ? t->ops->hessian_convexified(t, x, H)
             : g && I->has_hessian_g && t->ops->hessian_g ? t->ops->hessian_g(t, x, g, H)
                                                           : t->ops->hessian(t, x, H);
    if (rc) return rc;
  }
  return 0;
}

static int obj_hessian(const double *x, bs_bsr *H, void *ctx) {
  bs_integrator *I = ctx;
  bs_bsr_zero(H);
  int rc = terms_hessian(I, x, NULL, 0, 0, H);
  if (rc) return rc;
  if (I->hooks.project_hessian) {
    double E;
    if ((rc = terms_gradient(I, x, &E, I->gh, NULL))) return rc;
    I->hooks.project_hessian(x, I->gh, H, I->hooks.ctx);
  }
  return 0;
}

/* The terms' Hessians (convex: their convexified ones where offered) at x,
 * projected by the hook when there is one (g_raw: the unprojected gradient). */
static int hessian_projected(bs_integrator *I, const double *x, const double *g_raw, int convex, bs_bsr *H) {
  bs_bsr_zero(H);
  int rc = terms_hessian(I, x, g_raw, 0, convex, H);
  if (rc) return rc;
  if (I->hooks.project_hessian) I->hooks.project_hessian(x, g_raw, H, I->hooks.ctx);
  return 0;
}

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
  int rc = terms_hessian(I, x, NULL, 1, 0, P);
  if (rc) return rc;
  bs_fem_elastic_hessian(I->fem, I->opts.amg_at_rest ? I->fem->mesh->x : x, 1, 1.0, P);
  return 0;
}

static void hook_project_gradient(const double *x, double *g, void *ctx) {
  bs_integrator *I = ctx;
  I->hooks.project_gradient(x, g, I->hooks.ctx);
}

static void hook_project(double *x, void *ctx) {
  bs_integrator *I = ctx;
  I->hooks.project(x, I->hooks.ctx);
}

static void hook_register(const double *x, const double *g, void *ctx) {
  bs_integrator *I = ctx;
  I->hooks.register_active(x, g, I->hooks.ctx);
}

static void obj_trace(const bs_min_iter *it, void *ctx) {
  bs_integrator *I = ctx;
  char kept[32] = "";
  if (it->lin_downhill_iterate > 0) snprintf(kept, sizeof kept, " (iterate %d)", it->lin_downhill_iterate);
  fprintf(I->opts.trace, "  iteration %d: |grad E| %.6e  E %.12e -> %.12e  krylov %d%s%s%s  alpha %.4g (%d trials)%s\n",
          it->iteration, it->grad_norm, it->phi0, it->phi, it->lin_iterations, it->lin_indefinite ? " (indefinite)" : "",
          kept, it->convexified ? " (convexified)" : "", it->alpha, it->ls_evaluations,
          it->direction != BS_DIR_NEWTON ? (it->direction == BS_DIR_NEG_DX ? " fallback -dx" : " fallback -g") : "");
  fflush(I->opts.trace);
}

/* The 2-norm over the free dofs of the active external loads' forces (the
 * scale of opts.load_rtol), computed in I->g1 (free once the guess is in x). */
static double load_norm(bs_integrator *I, const double *x) {
  const size_t n3 = 3 * (size_t)I->fem->n_vertices;
  int any = 0;
  memset(I->g1, 0, sizeof(double) * n3);
  for (int i = 0; i < I->n_terms; i++) {
    double e;
    const bs_term *t = I->terms[i];
    if (t->external && term_active(I, t) && t->ops->gradient(t, x, &e, I->g1) == BS_TERM_OK) any = 1;
  }
  if (!any) return 0;
  double s = 0;
  for (size_t i = 0; i < n3; i++)
    if (!I->mask || I->mask[i / 3]) s += I->g1[i] * I->g1[i];
  return isfinite(s) ? sqrt(s) : 0;
}

int bs_step_objective_quadratic(int n_terms, bs_term *const *terms, int statics, int projected) {
  if (projected) return 0;
  for (int i = 0; i < n_terms; i++)
    if (!(statics && terms[i]->dynamic_only) && !terms[i]->quadratic) return 0;
  return 1;
}

int bs_step_forcing(int forcing_ew, int64_t inverted) { return forcing_ew == 2 && inverted > 0 ? 0 : forcing_ew; }

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
  o->n = I->fem->n_vertices;
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
  o->precond_matrix = obj_precond;
  o->trace = I->opts.trace ? obj_trace : NULL;
  o->ctx = I;
}

void bs_integrator_get_carry(const bs_integrator *I, bs_min_carry *c) { bs_minimizer_get_carry(I->min, c); }
void bs_integrator_set_carry(bs_integrator *I, const bs_min_carry *c) { bs_minimizer_set_carry(I->min, c); }

void bs_integrator_get_previous(const bs_integrator *I, bs_previous_step *p) {
  const size_t n3 = 3 * (size_t)I->fem->n_vertices;
  p->have = I->prev.have, p->dt = I->prev.dt, p->mark = I->prev.mark;
  if (p->d) memcpy(p->d, I->prev.d, sizeof(double) * n3);
}

void bs_integrator_set_previous(bs_integrator *I, const bs_previous_step *p) {
  const size_t n3 = 3 * (size_t)I->fem->n_vertices;
  I->prev.have = p->have && p->d && p->dt > 0, I->prev.dt = p->dt, I->prev.mark = p->mark;
  if (I->prev.have) memcpy(I->prev.d, p->d, sizeof(double) * n3);
}
void bs_integrator_set_stop(bs_integrator *I, volatile sig_atomic_t *stop) { bs_minimizer_set_stop(I->min, stop); }

double bs_integrator_energy(bs_integrator *I, const double *x) {
  double E;
  obj_value(x, &E, I);
  return E;
}

/* ∇Φ(xⁿ) = −f(xⁿ) into I->grad: every term but inertia. BS_ENUMERIC, naming
 * the term, when one is not evaluable at xⁿ. */
static int potential_gradient(bs_integrator *I, bs_error *err) {
  memset(I->grad, 0, sizeof(double) * 3 * (size_t)I->fem->n_vertices);
  for (int i = 0; i < I->n_terms; i++) {
    double e;
    const bs_term *t = I->terms[i];
    if (t->kind != BS_TERM_INERTIA && t->ops->gradient(t, I->x_n, &e, I->grad))
      return bs_error_set(err, BS_ENUMERIC, "the %s term is not evaluable at the positions of the step's start",
                          t->name);
  }
  return 0;
}

static int check_finite(const double *a, size_t n, const char *what, bs_error *err) {
  for (size_t i = 0; i < n; i++)
    if (!isfinite(a[i]))
      return bs_error_set(err, BS_ENUMERIC, "%s of vertex %zu (component %zu) is not finite (%g)", what, i / 3, i % 3,
                          a[i]);
  return 0;
}

static int run_solver(bs_integrator *I, double *x, int naive, bs_step_stats *st, bs_error *err) {
  bs_objective obj;
  make_objective(I, x, &obj);
  int rc;
  I->opts.min.naive_guess = naive;
  bs_minimize_opts mo = I->opts.min;
  /* cg_forcing adaptive: the paper's loose solves while the step starts
   * tangled (inverted tets), where they untangle best (README, Scenes) */
  if (mo.forcing_ew == 2) mo.forcing_ew = bs_step_forcing(2, bs_fem_count_inverted(I->fem, I->x_n, NULL));
  if (mo.linear == BS_LIN_AMG) {
    /* P changes with dt (M/dt^2) and between dynamic and static solves. */
    const double pdt = I->static_mode ? 0.0 : I->step->dt;
    if (pdt != I->amg_dt) bs_minimizer_amg_reset(I->min);
    I->amg_dt = pdt;
    if (I->opts.amg_at_rest) mo.amg_rebuild_factor = 0; /* P does not depend on x */
  }
  if ((rc = bs_minimizer_set_opts(I->min, &mo, err))) return rc;
  if (I->opts.method == BS_METHOD_OPTIMIZATION) rc = bs_minimize(I->min, &obj, x, &st->min, err);
  else rc = bs_newton(I->min, &obj, I->opts.method == BS_METHOD_NEWTON_K ? I->opts.newton_k : 0, x, &st->min, err);
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

/* A later candidate in I->g1 (xⁿ, the previous-step guess) made admissible
 * (masked vertices at xⁿ, then scripted ones at their positions at t1, then
 * projected: constraint collisions) and taken into x as `kind` when its E is
 * below Eb, the chosen guess's. Returns the chosen guess's E after. */
static double offer_candidate(bs_integrator *I, double t1, double Eb, bs_guess kind, double *x, int *naive,
                              bs_step_stats *st) {
  const size_t nv = (size_t)I->fem->n_vertices;
  double *g = I->g1;
  for (size_t vtx = 0; vtx < nv; vtx++)
    if (!I->mask[vtx])
      for (int k = 0; k < 3; k++) g[3 * vtx + k] = I->x_n[3 * vtx + k];
  if (I->script) I->script(t1, g, I->script_ctx);
  if (I->hooks.project) I->hooks.project(g, I->hooks.ctx);
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
  const size_t n3 = 3 * (size_t)I->fem->n_vertices;
  if (!I->prev.have || I->prev.mark != state_mark(I->x_n, v, n3)) return;
  const double s = dt / I->prev.dt;
  for (size_t i = 0; i < n3; i++) I->g1[i] = I->x_n[i] + s * I->prev.d[i];
  offer_candidate(I, t + dt, Eb, BS_GUESS_PREVIOUS, x, naive, st);
}

/* Step 3's paper guesses in I->g1 (x̂) and I->g2 (explicit), and xⁿ with
 * opts.guess_xn: the one with the smallest E into x (st->guess, *naive).
 * Returns its E (+Inf when none is evaluable). */
static double paper_guesses(bs_integrator *I, double t, double dt, double *x, int *naive, bs_step_stats *st) {
  const size_t n3 = 3 * (size_t)I->fem->n_vertices;
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

int bs_integrator_step(bs_integrator *I, double t, double dt, double *x, double *v, bs_step_stats *st,
                       bs_error *err) {
  double t0 = bs_seconds();
  memset(st, 0, sizeof *st);
  const bs_fem *fem = I->fem;
  size_t nv = (size_t)fem->n_vertices, n3 = 3 * nv;
  if (!(dt > 0) || !isfinite(dt)) return bs_error_set(err, BS_EINPUT, "time step must be positive and finite, got %g", dt);
  int rc;
  if ((rc = check_finite(x, n3, "position", err)) || (rc = check_finite(v, n3, "velocity", err))) return rc;
  I->static_mode = 0;
  I->step->dt = dt;
  I->step->time = t + dt;
  I->step->load = 1.0;
  memcpy(I->x_n, x, sizeof(double) * n3);
  for (size_t i = 0; i < n3; i++) I->x_hat[i] = x[i] + dt * v[i];
  for (int i = 0; i < I->n_terms; i++)
    if (I->terms[i]->ops->begin_step && (rc = I->terms[i]->ops->begin_step(I->terms[i], err))) return rc;

  /* f(xⁿ) = −∇Φ(xⁿ): every term but inertia. */
  if ((rc = potential_gradient(I, err))) return rc;
  memcpy(I->g1, I->x_hat, sizeof(double) * n3);
  for (size_t vtx = 0; vtx < nv; vtx++) {
    double c = fem->mass[vtx] > 0 ? dt * dt / fem->mass[vtx] : 0;
    for (int k = 0; k < 3; k++) I->g2[3 * vtx + k] = I->x_hat[3 * vtx + k] - c * I->grad[3 * vtx + k];
  }
  if (I->script) {
    I->script(t + dt, I->g1, I->script_ctx);
    I->script(t + dt, I->g2, I->script_ctx);
  }
  /* Scripted vertices keep their scripted positions in both guesses. */
  for (size_t vtx = 0; vtx < nv; vtx++)
    if (!I->mask[vtx])
      for (int k = 0; k < 3; k++) {
        if (!I->script) I->g1[3 * vtx + k] = I->g2[3 * vtx + k] = I->x_n[3 * vtx + k];
        else I->g2[3 * vtx + k] = I->g1[3 * vtx + k];
      }
  if (I->hooks.project) {
    I->hooks.project(I->g1, I->hooks.ctx);
    I->hooks.project(I->g2, I->hooks.ctx);
  }
  int naive = 1;
  const double Eb = paper_guesses(I, t, dt, x, &naive, st);
  if (I->hooks.post_solve) previous_step_guess(I, t, dt, x, v, Eb, &naive, st);
  if ((rc = run_solver(I, x, naive, st, err))) return rc;
  for (size_t i = 0; i < n3; i++) v[i] = (x[i] - I->x_n[i]) / dt;
  if (I->hooks.post_solve) {
    double E;
    const char *bad = "?";
    if (terms_gradient(I, x, &E, I->gh, &bad))
      return bs_error_set(err, BS_ENUMERIC, "the %s term is not evaluable at the solution (post-solve hooks)", bad);
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
  }
  st->seconds = bs_seconds() - t0;
  return 0;
}

int bs_integrator_static(bs_integrator *I, double t, int load_steps, double *x, bs_step_stats *st, bs_error *err) {
  double t0 = bs_seconds();
  memset(st, 0, sizeof *st);
  size_t n3 = 3 * (size_t)I->fem->n_vertices;
  int rc;
  if ((rc = check_finite(x, n3, "position", err))) return rc;
  if (load_steps < 1) return bs_error_set(err, BS_EINPUT, "load_steps must be >= 1, got %d", load_steps);
  I->static_mode = 1;
  I->prev.have = 0;
  I->step->dt = 0;
  I->step->time = t;
  memcpy(I->x_n, x, sizeof(double) * n3);
  memcpy(I->x_hat, x, sizeof(double) * n3);
  if (I->script) I->script(t, x, I->script_ctx);
  if (I->hooks.project) I->hooks.project(x, I->hooks.ctx);
  bs_step_stats sub;
  for (int l = 1; l <= load_steps; l++) {
    I->step->load = (double)l / load_steps;
    if ((rc = run_solver(I, x, 1, &sub, err))) break;
    bs_step_stats_add(st, &sub);
    if (sub.min.reason == BS_MIN_STOPPED) break; /* the later load steps are not taken */
  }
  I->static_mode = 0;
  I->step->load = 1.0;
  st->seconds = bs_seconds() - t0;
  return rc;
}
