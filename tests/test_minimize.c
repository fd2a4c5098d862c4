/* test_minimize.c — the stabilized Newton minimizer (paper 3.1–3.3) and the
 * Newton baseline (section 2) on small analytic objectives with a bs_bsr
 * Hessian: a quadratic, Rosenbrock (embedded and n-dimensional), a double well
 * started on negative curvature, an underestimated step (alpha > 1), the length
 * clamp, strong Wolfe checks recomputed independently, a log barrier (non-
 * evaluable points), the sphere constraint through the projection hooks, fixed
 * dofs, the lower-bound shortcut, non-finite objectives, CHOLMOD and PCG, the
 * convexified model after negative curvature, and
 * the Newton baseline converging quadratically or failing. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bs_minimize.h"

/* ---- patterns ----------------------------------------------------------- */

/* Chain graph: vertex i is adjacent to i-1 and i+1 (n = 1: a single block). */
static bs_bsr *pattern_chain(int32_t n) {
  int32_t *ptr = calloc((size_t)n + 1, sizeof *ptr), *adj = malloc(sizeof *adj * (2 * (size_t)n + 1));
  int m = 0;
  for (int32_t i = 0; i < n; ++i) {
    if (i > 0) adj[m++] = i - 1;
    if (i < n - 1) adj[m++] = i + 1;
    ptr[i + 1] = m;
  }
  bs_bsr *A = NULL;
  bs_error err = {0};
  cr_assert_eq(bs_bsr_create(n, ptr, adj, &A, &err), 0, "%s", err.msg);
  free(ptr);
  free(adj);
  return A;
}

/* H(i, j) += v for scalar dofs i, j (setup-speed slot lookup; tests only). */
static void hadd(bs_bsr *H, int64_t i, int64_t j, double v) {
  int32_t s = bs_bsr_slot(H, (int32_t)(i / 3), (int32_t)(j / 3));
  cr_assert(s >= 0, "test pattern misses block (%lld, %lld)", (long long)(i / 3), (long long)(j / 3));
  H->val[9 * (int64_t)s + 3 * (i % 3) + (j % 3)] += v;
}

/* ---- test objectives ------------------------------------------------------ */

typedef struct fx fx;
/* E (always), g (if non-NULL, 3n entries) and H (if non-NULL, added) at x.
 * Returns nonzero when x is not evaluable. */
typedef int (*fx_eval)(fx *f, const double *x, double *E, double *g, bs_bsr *H);

struct fx {
  int32_t n;
  fx_eval eval;
  double hess_scale;   /* the Hessian callback returns hess_scale * H            */
  const double *A, *b; /* quadratic: dense 3n x 3n A and b                      */
  double eps;          /* weak quadratic curvature (clamp test)                 */
  double k, t[3], R;   /* sphere: stiffness, target, radius                     */
  int active, activations, releases;
  int nan_mode;        /* 1: E = NaN; 2: gradient NaN at vertex 1 component 2    */
  int noise_on;        /* rounding-noise test: bias switched on                  */
  /* counters */
  int n_value, n_grad, n_hess;
  /* trace checks */
  double c1, c2;
  int n_rec, bad_wolfe, bad_point, bad_decrease, rec_indef_descent;
  int n_noise_rec; /* records with ls_status BS_LSEARCH_NOISE (cb_trace_noise) */
  bs_min_iter first;
  int has_first;
  /* Newton iterates (first dof) */
  double u[128];
  int n_u;
  /* lower-bound test */
  double E_cur;
  int lb_calls, lb_skips, lb_violations;
};

static void fx_init(fx *f, int32_t n, fx_eval ev) {
  memset(f, 0, sizeof *f);
  f->n = n;
  f->eval = ev;
  f->hess_scale = 1.0;
  f->c1 = 1e-4;
  f->c2 = 0.9;
}

static int cb_value(const double *x, double *E, void *ctx) {
  fx *f = ctx;
  f->n_value++;
  return f->eval(f, x, E, NULL, NULL);
}

static int cb_gradient(const double *x, double *E, double *g, void *ctx) {
  fx *f = ctx;
  f->n_grad++;
  if (f->n_u < 128) f->u[f->n_u++] = x[0];
  memset(g, 0, sizeof(double) * 3 * (size_t)f->n);
  return f->eval(f, x, E, g, NULL);
}

static int cb_hessian(const double *x, bs_bsr *H, void *ctx) {
  fx *f = ctx;
  f->n_hess++;
  bs_bsr_zero(H);
  double E;
  int rc = f->eval(f, x, &E, NULL, H);
  for (int64_t i = 0; i < 9 * H->nnzb; ++i) H->val[i] *= f->hess_scale;
  return rc;
}

static double dot(int64_t N, const double *a, const double *b) {
  double s = 0;
  for (int64_t i = 0; i < N; ++i) s += a[i] * b[i];
  return s;
}

/* Recomputes phi and phi' at both ends of every accepted step with the test's
 * own function (unconstrained objectives) and checks the strong Wolfe
 * conditions and y = x + alpha d. */
static void cb_trace_wolfe(const bs_min_iter *it, void *ctx) {
  fx *f = ctx;
  const int64_t N = 3 * (int64_t)f->n;
  double *g = malloc(sizeof(double) * (size_t)N);
  double E0, E1;
  memset(g, 0, sizeof(double) * (size_t)N);
  f->eval(f, it->x, &E0, g, NULL);
  double d0 = dot(N, g, it->d);
  memset(g, 0, sizeof(double) * (size_t)N);
  f->eval(f, it->y, &E1, g, NULL);
  double d1 = dot(N, g, it->d);
  free(g);
  const double tiny = 1e-12 * (fabs(E0) + 1e-300);
  if (!(E1 <= E0 + f->c1 * it->alpha * d0 + tiny) || !(fabs(d1) <= f->c2 * fabs(d0) * (1 + 1e-12))) f->bad_wolfe++;
  if (!(d0 < 0)) f->bad_wolfe++;
  if (fabs(E0 - it->phi0) > tiny || fabs(E1 - it->phi) > tiny) f->bad_wolfe++;
  if (it->ls_status == BS_LSEARCH_CAPPED) f->bad_wolfe++;
  if (!(E1 <= E0)) f->bad_decrease++;
  for (int64_t i = 0; i < N; ++i)
    if (fabs(it->y[i] - (it->x[i] + it->alpha * it->d[i])) > 1e-12 * (1 + fabs(it->y[i]))) f->bad_point++;
  if (it->lin_indefinite && it->direction == BS_DIR_NEWTON && d0 < 0) f->rec_indef_descent++;
  if (!f->has_first) {
    f->first = *it;
    f->first.x = f->first.d = f->first.y = NULL;
    f->has_first = 1;
  }
  f->n_rec++;
}

static bs_objective make_obj(fx *f, const uint8_t *mask) {
  bs_objective o;
  memset(&o, 0, sizeof o);
  o.n = f->n;
  o.mask = mask;
  o.value = cb_value;
  o.gradient = cb_gradient;
  o.hessian = cb_hessian;
  o.trace = cb_trace_wolfe;
  o.ctx = f;
  return o;
}

/* One bs_minimize call of a fresh minimizer with options o on f from x
 * (no mask); asserts that the call ran (status 0) and returns its stats.
 * stats.reason_text points into the minimizer, so it is copied to a buffer
 * that outlives it (valid until the next call). */
static void min_run_obj(const bs_bsr *P, const bs_minimize_opts *o, const bs_objective *obj, double *x,
                        bs_minimize_stats *st) {
  static char reason[512];
  bs_minimizer *m = NULL;
  bs_error err = {0};
  cr_assert_eq(bs_minimizer_create(P, o, &m, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_minimize(m, obj, x, st, &err), 0, "%s", err.msg);
  snprintf(reason, sizeof reason, "%s", st->reason_text ? st->reason_text : "");
  st->reason_text = reason;
  bs_minimizer_destroy(&m);
}

static void min_run(const bs_bsr *P, const bs_minimize_opts *o, fx *f, double *x, bs_minimize_stats *st) {
  bs_objective obj = make_obj(f, NULL);
  min_run_obj(P, o, &obj, x, st);
}

/* Quadratic: E = 1/2 x^T A x - b^T x. */
static int ev_quad(fx *f, const double *x, double *E, double *g, bs_bsr *H) {
  const int64_t N = 3 * (int64_t)f->n;
  double e = 0;
  for (int64_t i = 0; i < N; ++i) {
    double ax = 0;
    for (int64_t j = 0; j < N; ++j) ax += f->A[i * N + j] * x[j];
    e += 0.5 * x[i] * ax - f->b[i] * x[i];
    if (g) g[i] = ax - f->b[i];
    if (H)
      for (int64_t j = 0; j < N; ++j)
        if (f->A[i * N + j] != 0) hadd(H, i, j, f->A[i * N + j]);
  }
  *E = e;
  return 0;
}

/* A = L (x) S + I on a chain of n vertices: SPD, block tridiagonal. */
static double *quad_matrix(int32_t n) {
  const int64_t N = 3 * (int64_t)n;
  const double S[9] = {2, 0.5, 0, 0.5, 1.5, 0.3, 0, 0.3, 1};
  double *A = calloc((size_t)(N * N), sizeof *A);
  for (int32_t v = 0; v < n; ++v) {
    int deg = (v > 0) + (v < n - 1);
    for (int a = 0; a < 3; ++a)
      for (int c = 0; c < 3; ++c) {
        A[(3 * v + a) * N + 3 * v + c] += deg * S[3 * a + c] + (a == c);
        if (v > 0) A[(3 * v + a) * N + 3 * (v - 1) + c] -= S[3 * a + c];
        if (v < n - 1) A[(3 * v + a) * N + 3 * (v + 1) + c] -= S[3 * a + c];
      }
  }
  return A;
}

/* Rosenbrock in one block: (1-x)^2 + 100 (y - x^2)^2 + z^2 / 2. */
static int ev_rosen2(fx *f, const double *u, double *E, double *g, bs_bsr *H) {
  double x = u[0], y = u[1], z = u[2], w = y - x * x;
  *E = (1 - x) * (1 - x) + 100 * w * w + 0.5 * z * z;
  if (g) {
    g[0] = -2 * (1 - x) - 400 * x * w;
    g[1] = 200 * w;
    g[2] = z;
  }
  if (H) {
    hadd(H, 0, 0, 2 - 400 * w + 800 * x * x);
    hadd(H, 0, 1, -400 * x);
    hadd(H, 1, 0, -400 * x);
    hadd(H, 1, 1, 200);
    hadd(H, 2, 2, 1);
  }
  return 0;
}

/* n-dimensional Rosenbrock over all 3n dofs: sum 100 (u_{k+1} - u_k^2)^2 + (1 - u_k)^2. */
static int ev_rosenN(fx *f, const double *u, double *E, double *g, bs_bsr *H) {
  const int64_t N = 3 * (int64_t)f->n;
  double e = 0;
  for (int64_t k = 0; k + 1 < N; ++k) {
    double w = u[k + 1] - u[k] * u[k];
    e += 100 * w * w + (1 - u[k]) * (1 - u[k]);
    if (g) {
      g[k] += -400 * u[k] * w - 2 * (1 - u[k]);
      g[k + 1] += 200 * w;
    }
    if (H) {
      hadd(H, k, k, 2 - 400 * w + 800 * u[k] * u[k]);
      hadd(H, k, k + 1, -400 * u[k]);
      hadd(H, k + 1, k, -400 * u[k]);
      hadd(H, k + 1, k + 1, 200);
    }
  }
  *E = e;
  return 0;
}

/* Double well per dof: u^4 - u^2 (minima at +-1/sqrt 2, negative curvature at 0). */
static int ev_well(fx *f, const double *u, double *E, double *g, bs_bsr *H) {
  const int64_t N = 3 * (int64_t)f->n;
  double e = 0;
  for (int64_t k = 0; k < N; ++k) {
    e += u[k] * u[k] * u[k] * u[k] - u[k] * u[k];
    if (g) g[k] = 4 * u[k] * u[k] * u[k] - 2 * u[k];
    if (H) hadd(H, k, k, 12 * u[k] * u[k] - 2);
  }
  *E = e;
  return 0;
}

/* Weak quadratic per dof: eps u^2 / 2 - u (minimum at 1/eps, Newton step huge). */
static int ev_weak(fx *f, const double *u, double *E, double *g, bs_bsr *H) {
  const int64_t N = 3 * (int64_t)f->n;
  double e = 0;
  for (int64_t k = 0; k < N; ++k) {
    e += 0.5 * f->eps * u[k] * u[k] - u[k];
    if (g) g[k] = f->eps * u[k] - 1;
    if (H) hadd(H, k, k, f->eps);
  }
  *E = e;
  return 0;
}

/* Log barrier per dof: u - log u (minimum at 1; not evaluable for u <= 0). */
static int ev_barrier(fx *f, const double *u, double *E, double *g, bs_bsr *H) {
  const int64_t N = 3 * (int64_t)f->n;
  double e = 0;
  for (int64_t k = 0; k < N; ++k) {
    if (!(u[k] > 0)) return 1;
    e += u[k] - log(u[k]);
    if (g) g[k] = 1 - 1 / u[k];
    if (H) hadd(H, k, k, 1 / (u[k] * u[k]));
  }
  *E = e;
  return 0;
}

/* Arctan gradient per dof: E = u atan u - log(1 + u^2)/2, g = atan u, H = 1/(1+u^2). */
static int ev_atan(fx *f, const double *u, double *E, double *g, bs_bsr *H) {
  const int64_t N = 3 * (int64_t)f->n;
  double e = 0;
  for (int64_t k = 0; k < N; ++k) {
    e += u[k] * atan(u[k]) - 0.5 * log1p(u[k] * u[k]);
    if (g) g[k] = atan(u[k]);
    if (H) hadd(H, k, k, 1 / (1 + u[k] * u[k]));
  }
  *E = e;
  return 0;
}

/* Exponential per dof: exp(u) - 2u (root of the gradient at log 2). */
static int ev_exp(fx *f, const double *u, double *E, double *g, bs_bsr *H) {
  const int64_t N = 3 * (int64_t)f->n;
  double e = 0;
  for (int64_t k = 0; k < N; ++k) {
    e += exp(u[k]) - 2 * u[k];
    if (g) g[k] = exp(u[k]) - 2;
    if (H) hadd(H, k, k, exp(u[k]));
  }
  *E = e;
  return 0;
}

/* NaN objectives. */
static int ev_nan(fx *f, const double *u, double *E, double *g, bs_bsr *H) {
  ev_quad(f, u, E, g, H);
  if (f->nan_mode == 1) *E = NAN;
  if (f->nan_mode == 2 && g) g[3 * 1 + 2] = NAN;
  return 0;
}

/* ---- basic behaviour -------------------------------------------------------- */

Test(minimize, defaults_and_reason_names) {
  bs_minimize_opts o;
  bs_minimize_opts_default(&o);
  cr_assert_eq(o.max_iter, 500);
  cr_assert_float_eq(o.kappa, 1e-2, 0);
  cr_assert_float_eq(o.clamp, 1e3, 0);
  cr_assert_float_eq(o.c1, 1e-4, 0);
  cr_assert_float_eq(o.c2, 0.9, 0);
  cr_assert_float_eq(o.sigma, 1.0, 0);
  cr_assert_eq(o.linear, BS_LIN_CG);
  cr_assert_str_eq(bs_min_reason_name(BS_MIN_CONVERGED), "converged");
  cr_assert_str_eq(bs_min_reason_name(BS_MIN_LINE_SEARCH), "line_search");
  cr_assert_str_eq(bs_min_reason_name(BS_MIN_STEPS_DONE), "steps_done");
  cr_assert_str_eq(bs_direction_name(BS_DIR_NEWTON), "newton");
  cr_assert_str_eq(bs_direction_name(BS_DIR_NEG_DX), "neg_dx");
  cr_assert_str_eq(bs_direction_name(BS_DIR_NEG_GRAD), "neg_grad");
  cr_assert_str_eq(bs_direction_name((bs_direction)7), "unknown");
  cr_assert_str_eq(bs_lsearch_status_name(BS_LSEARCH_NO_DECREASE), "no_decrease");
  cr_assert_str_eq(bs_lsearch_status_name(BS_LSEARCH_CAPPED), "capped");
  cr_assert_str_eq(bs_lsearch_status_name(BS_LSEARCH_WOLFE), "wolfe");
  cr_assert_str_eq(bs_lsearch_status_name(BS_LSEARCH_NOISE), "noise");
  cr_assert_str_eq(bs_lsearch_status_name((bs_lsearch_status)7), "unknown");
}

Test(minimize, quadratic_one_iteration) {
  const int32_t n = 4;
  const int64_t N = 3 * n;
  bs_bsr *P = pattern_chain(n);
  double *A = quad_matrix(n), b[12], x[12] = {0};
  for (int64_t i = 0; i < N; ++i) b[i] = sin(1.0 + i);
  fx f;
  fx_init(&f, n, ev_quad);
  f.A = A;
  f.b = b;
  bs_minimize_opts o;
  bs_minimize_opts_default(&o);
  o.tol = 1e-9;
  o.sigma = 1e-12; /* CG to ~1e-12 relative: one exact Newton step */
  bs_minimizer *m = NULL;
  bs_error err = {0};
  cr_assert_eq(bs_minimizer_create(P, &o, &m, &err), 0, "%s", err.msg);
  bs_objective obj = make_obj(&f, NULL);
  bs_minimize_stats st;
  cr_assert_eq(bs_minimize(m, &obj, x, &st, &err), 0, "%s", err.msg);
  cr_assert_eq(st.reason, BS_MIN_CONVERGED, "%s", st.reason_text);
  cr_assert_eq(st.iterations, 1, "took %d iterations", st.iterations);
  cr_assert_float_eq(st.alpha_last, 1.0, 0, "alpha %g", st.alpha_last);
  cr_assert_eq(st.ls_evaluations, 1);
  cr_assert_eq(f.n_hess, 1);
  double r = 0;
  for (int64_t i = 0; i < N; ++i) {
    double ax = 0;
    for (int64_t j = 0; j < N; ++j) ax += A[i * N + j] * x[j];
    r = fmax(r, fabs(ax - b[i]));
  }
  cr_assert_lt(r, 1e-9, "residual %g", r);
  cr_assert_lt(st.grad_norm, 1e-9);
  cr_assert_eq(f.bad_wolfe, 0);
  cr_assert_eq(f.n_rec, 1);
  cr_assert_not_null(st.reason_text);
  cr_assert(strstr(st.reason_text, "converged") != NULL, "%s", st.reason_text);
  cr_assert(st.t_total >= st.t_linear && st.t_linear >= 0 && st.t_eval >= 0 && st.t_assembly >= 0);
  bs_minimizer_destroy(&m);
  bs_minimizer_destroy(&m); /* NULL-safe */
  cr_assert_null(m);
  bs_bsr_destroy(&P);
  free(A);
}

/* opts.cg_downhill on a quadratic with a nearly singular direction: A =
 * diag(1, 1e-6, 1), b = (1, 1e-3, 0), from 0. The exact Newton step (1, 1e3,
 * 0) fails step 5's test (b.d / |b||d| = 2e-3 < kappa), so the paper's rule
 * falls back to -g; with cg_downhill the direction is CG's first iterate
 * instead. Both then converge to A^-1 b. */
Test(minimize, cg_downhill_keeps_an_earlier_iterate) {
  bs_bsr *P = pattern_chain(1);
  double A[9] = {1, 0, 0, 0, 1e-6, 0, 0, 0, 1}, b[3] = {1, 1e-3, 0};
  for (int on = 0; on < 2; ++on) {
    fx f;
    fx_init(&f, 1, ev_quad);
    f.A = A;
    f.b = b;
    bs_minimize_opts o;
    bs_minimize_opts_default(&o);
    cr_assert_eq(o.cg_downhill, 1);
    o.cg_downhill = on;
    o.tol = 1e-10;
    o.sigma = 1e-12; /* exact solves */
    double x[3] = {0, 0, 0};
    bs_minimize_stats st;
    min_run(P, &o, &f, x, &st);
    cr_assert_eq(st.reason, BS_MIN_CONVERGED, "on = %d: %s", on, st.reason_text);
    cr_assert_float_eq(x[0], 1.0, 1e-9);
    cr_assert_float_eq(x[1], 1e3, 1e-3);
    cr_assert_eq(f.has_first, 1);
    if (on) {
      cr_assert_geq(st.downhill_iterates, 1);
      cr_assert_eq(st.fallback_neg_grad, 0);
      cr_assert_eq(f.first.lin_downhill_iterate, 1, "first direction: iterate %d", f.first.lin_downhill_iterate);
      cr_assert_eq(f.first.direction, BS_DIR_NEWTON);
    } else {
      cr_assert_eq(st.downhill_iterates, 0);
      cr_assert_geq(st.fallback_neg_grad, 1);
      cr_assert_eq(f.first.direction, BS_DIR_NEG_GRAD);
    }
  }
  bs_bsr_destroy(&P);
}

Test(minimize, rosenbrock_embedded) {
  bs_bsr *P = pattern_chain(1);
  fx f;
  fx_init(&f, 1, ev_rosen2);
  bs_minimize_opts o;
  bs_minimize_opts_default(&o);
  o.tol = 1e-8;
  bs_minimizer *m = NULL;
  bs_error err = {0};
  cr_assert_eq(bs_minimizer_create(P, &o, &m, &err), 0, "%s", err.msg);
  bs_objective obj = make_obj(&f, NULL);
  double x[3] = {-1.2, 1.0, 0.5};
  bs_minimize_stats st;
  cr_assert_eq(bs_minimize(m, &obj, x, &st, &err), 0, "%s", err.msg);
  cr_assert_eq(st.reason, BS_MIN_CONVERGED, "%s", st.reason_text);
  cr_assert_float_eq(x[0], 1.0, 1e-7, "x = %.12g", x[0]);
  cr_assert_float_eq(x[1], 1.0, 1e-7, "y = %.12g", x[1]);
  cr_assert_float_eq(x[2], 0.0, 1e-7);
  cr_assert_lt(st.iterations, 100, "%d iterations", st.iterations);
  cr_assert_eq(f.bad_wolfe, 0, "%d accepted steps violate strong Wolfe", f.bad_wolfe);
  cr_assert_eq(f.bad_point, 0);
  cr_assert_eq(f.n_rec, st.iterations);
  cr_assert_eq(st.ls_failures, 0);
  bs_minimizer_destroy(&m);
  bs_bsr_destroy(&P);
}

Test(minimize, rosenbrock_n_dimensional) {
  const int32_t n = 4; /* 12-dimensional Rosenbrock spread over 4 blocks */
  bs_bsr *P = pattern_chain(n);
  fx f;
  fx_init(&f, n, ev_rosenN);
  bs_minimize_opts o;
  bs_minimize_opts_default(&o);
  o.tol = 1e-8;
  bs_minimizer *m = NULL;
  bs_error err = {0};
  cr_assert_eq(bs_minimizer_create(P, &o, &m, &err), 0, "%s", err.msg);
  bs_objective obj = make_obj(&f, NULL);
  double x[12];
  for (int k = 0; k < 12; ++k) x[k] = k % 2 ? 1.0 : -1.2;
  double E0;
  ev_rosenN(&f, x, &E0, NULL, NULL);
  bs_minimize_stats st;
  cr_assert_eq(bs_minimize(m, &obj, x, &st, &err), 0, "%s", err.msg);
  cr_assert_eq(st.reason, BS_MIN_CONVERGED, "%s", st.reason_text);
  cr_assert_lt(st.grad_norm, 1e-8);
  cr_assert_lt(st.E, E0);
  /* A local minimizer: the Hessian there is positive definite on every dof's
   * 1-D restriction (diagonal entries positive). */
  bs_bsr *H = pattern_chain(n);
  double E;
  ev_rosenN(&f, x, &E, NULL, H);
  for (int k = 0; k < 12; ++k) {
    int32_t s = H->diag[k / 3];
    cr_assert_gt(H->val[9 * s + 4 * (k % 3)], 0);
  }
  cr_assert_eq(f.bad_wolfe, 0);
  cr_assert_eq(f.bad_point, 0);
  bs_bsr_destroy(&H);
  bs_minimizer_destroy(&m);
  bs_bsr_destroy(&P);
}

/* Rosenbrock in other units: E, grad E and H times 2^20 (exact in binary). */
static int ev_rosenN_scaled(fx *f, const double *u, double *E, double *g, bs_bsr *H) {
  const double s = 1048576.0;
  int rc = ev_rosenN(f, u, E, g, H);
  *E *= s;
  if (g)
    for (int64_t k = 0; k < 3 * (int64_t)f->n; ++k) g[k] *= s;
  if (H)
    for (int64_t k = 0; k < 9 * H->nnzb; ++k) H->val[k] *= s;
  return rc;
}

/* One solve of the 3n-D Rosenbrock from the usual start, E in units scaled
 * by 2^20 or not (tol scaled alike), with the given linear solver and values'
 * precision; asserts convergence. */
static void rosen_solve(int32_t n, int scaled, int sigma_auto, bs_lin_kind linear, int single, int ew, double *x,
                        bs_minimize_stats *st) {
  bs_bsr *P = pattern_chain(n);
  fx f;
  fx_init(&f, n, scaled ? ev_rosenN_scaled : ev_rosenN);
  bs_minimize_opts o;
  bs_minimize_opts_default(&o);
  o.tol = scaled ? 1e-8 * 1048576.0 : 1e-8;
  o.sigma_auto = sigma_auto;
  o.linear = linear;
  o.cg_single = single;
  o.forcing_ew = ew;
  bs_minimizer *m = NULL;
  bs_error err = {0};
  cr_assert_eq(bs_minimizer_create(P, &o, &m, &err), 0, "%s", err.msg);
  bs_objective obj = make_obj(&f, NULL);
  for (int k = 0; k < 3 * n; ++k) x[k] = k % 2 ? 1.0 : -1.2;
  cr_assert_eq(bs_minimize(m, &obj, x, st, &err), 0, "%s", err.msg);
  cr_assert_eq(st->reason, BS_MIN_CONVERGED, "%s", st->reason_text);
  bs_minimizer_destroy(&m);
  bs_bsr_destroy(&P);
}

/* The 12-D one in plain CG, double values. */
static void rosen_units(int scaled, int sigma_auto, double x[12], bs_minimize_stats *st) {
  rosen_solve(4, scaled, sigma_auto, BS_LIN_CG, 0, 0, x, st);
}

/* sigma_auto makes the CG tolerance unitless: the same problem in units of E
 * scaled by a power of two takes the very same iterates. With the paper's
 * sigma = 1 the tolerance min(1/2, sqrt(||g||)) depends on the units, and the
 * scaled problem takes more Newton iterations (loose solves for longer). */
Test(minimize, sigma_auto_is_unitless) {
  double x1[12], x2[12];
  bs_minimize_stats a, b;
  rosen_units(0, 1, x1, &a);
  rosen_units(1, 1, x2, &b);
  cr_expect_eq(a.iterations, b.iterations, "Newton iterations %d and %d", a.iterations, b.iterations);
  cr_expect_eq(a.cg_iterations, b.cg_iterations, "CG iterations %d and %d", a.cg_iterations, b.cg_iterations);
  for (int k = 0; k < 12; ++k) cr_expect_eq(x1[k], x2[k], "x[%d]: %.17g and %.17g", k, x1[k], x2[k]);
  rosen_units(0, 0, x1, &a);
  rosen_units(1, 0, x2, &b);
  cr_expect_gt(b.iterations, a.iterations, "sigma = 1: %d Newton iterations in scaled units, %d in the others",
               b.iterations, a.iterations);
}

/* opts.cg_single: the 60-D Rosenbrock, with CG and with PCG, converges to the
 * minimizer (all ones) as in double, in as many Newton iterations give or take
 * one; CG's solves did read the single values (the iterates differ). */
Test(minimize, cg_single_converges) {
  for (int pcg = 0; pcg < 2; ++pcg) {
    double xs[2][60];
    bs_minimize_stats st[2];
    for (int single = 0; single < 2; ++single) {
      rosen_solve(20, 0, 1, pcg ? BS_LIN_PCG : BS_LIN_CG, single, 0, xs[single], &st[single]);
      for (int k = 0; k < 60; ++k) cr_assert_float_eq(xs[single][k], 1.0, 1e-6);
    }
    cr_assert_leq(abs(st[1].iterations - st[0].iterations), 1, "pcg %d: %d Newton iterations in single, %d in double",
                  pcg, st[1].iterations, st[0].iterations);
    if (!pcg) /* (PCG's solves here take 4 iterations or fewer: double values only) */
      cr_assert_neq(memcmp(xs[0], xs[1], sizeof xs[0]), 0, "single values were never read");
  }
}

/* The 2-vertex double well from near its top (the Hessian negative
 * definite there) with globalization g, tolerance 1e-10: converges to
 * 1/sqrt(2) in every dof; f holds the trace records. */
static void well_from_the_top(bs_globalization g, fx *f, bs_minimize_stats *st) {
  const int32_t n = 2;
  bs_bsr *P = pattern_chain(n);
  fx_init(f, n, ev_well);
  bs_minimize_opts o;
  bs_minimize_opts_default(&o);
  o.tol = 1e-10;
  o.globalization = g;
  bs_minimizer *m = NULL;
  bs_error err = {0};
  cr_assert_eq(bs_minimizer_create(P, &o, &m, &err), 0, "%s", err.msg);
  bs_objective obj = make_obj(f, NULL);
  double x[6];
  for (int k = 0; k < 6; ++k) x[k] = 0.01 * (1 + 0.1 * k);
  cr_assert_eq(bs_minimize(m, &obj, x, st, &err), 0, "%s", err.msg);
  cr_assert_eq(st->reason, BS_MIN_CONVERGED, "%s", st->reason_text);
  for (int k = 0; k < 6; ++k) cr_assert_float_eq(x[k], 1 / sqrt(2.0), 1e-8, "x[%d] = %.12g", k, x[k]);
  bs_minimizer_destroy(&m);
  bs_bsr_destroy(&P);
}

Test(minimize, negative_curvature_start) {
  fx f;
  bs_minimize_stats st;
  well_from_the_top(BS_GLOBAL_LINE_SEARCH, &f, &st);
  cr_assert_gt(st.indefinite_exits, 0);
  /* CG's indefinite exit on the first iteration returned the right-hand side
   * -grad E: a descent direction, kept by the downhill check. */
  cr_assert(f.has_first);
  cr_assert_eq(f.first.lin_indefinite, 1);
  cr_assert_eq(f.first.direction, BS_DIR_NEWTON);
  cr_assert_lt(f.first.dphi0, 0);
  cr_assert_gt(f.rec_indef_descent, 0);
  cr_assert_eq(st.fallback_neg_dx, 0, "CG never needs -dx (paper 3.1)");
  cr_assert_gt(st.alpha_max, 1.0, "the rhs direction is short: alpha grows");
  cr_assert_eq(f.bad_wolfe, 0);
}

/* ---- the convexified model (opts.convexify) ------------------------------ */

/* What cb_convex_trace records of each iteration. */
typedef struct conv_rec {
  int convexified, indefinite, krylov, full;
} conv_rec;
static conv_rec conv_recs[64];
static int n_conv_recs, n_convex_calls;

static void cb_convex_trace(const bs_min_iter *it, void *ctx) {
  (void)ctx;
  if (n_conv_recs >= 64) return;
  conv_rec *r = &conv_recs[n_conv_recs++];
  r->convexified = it->convexified;
  r->indefinite = it->lin_indefinite;
  r->krylov = it->lin_iterations;
  r->full = it->direction == BS_DIR_NEWTON && !it->lin_indefinite && it->ls_status == BS_LSEARCH_WOLFE &&
            it->alpha == 1 && it->ls_evaluations == 1;
}

/* Weighted double well: sum_k (1 + k) (u_k^4 - u_k^2), the wells of ev_well
 * with distinct curvatures (so that CG takes several iterations there). */
static int ev_wwell(fx *f, const double *u, double *E, double *g, bs_bsr *H) {
  double e = 0;
  for (int64_t k = 0; k < 3 * (int64_t)f->n; ++k) {
    const double c = 1.0 + (double)k;
    e += c * (u[k] * u[k] * u[k] * u[k] - u[k] * u[k]);
    if (g) g[k] = c * (4 * u[k] * u[k] * u[k] - 2 * u[k]);
    if (H) hadd(H, k, k, c * (12 * u[k] * u[k] - 2));
  }
  *E = e;
  return 0;
}

/* Its convexified Hessian for the test: each diagonal entry raised to at
 * least 1 + k (the minimizer only needs a PSD model). */
static int cb_hessian_convex(const double *x, const double *g_raw, bs_bsr *H, void *ctx) {
  (void)g_raw;
  fx *f = ctx;
  n_convex_calls++;
  bs_bsr_zero(H);
  for (int64_t k = 0; k < 3 * (int64_t)f->n; ++k) hadd(H, k, k, (1.0 + (double)k) * fmax(12 * x[k] * x[k] - 2, 1.0));
  return 0;
}

/* The 2-vertex weighted double well from near its top with the convexified model
 * offered (convexify on or off, or not offered: offer 0): the records of
 * the iterations into conv_recs; x converged. */
static void well_convex(int convexify, int offer, double *x, bs_minimize_stats *st) {
  bs_bsr *P = pattern_chain(2);
  fx f;
  fx_init(&f, 2, ev_wwell);
  bs_minimize_opts o;
  bs_minimize_opts_default(&o);
  cr_assert_eq(o.convexify, 1, "on by default");
  o.tol = 1e-10;
  o.convexify = convexify;
  bs_objective obj = make_obj(&f, NULL);
  obj.trace = cb_convex_trace;
  if (offer) obj.hessian_convexified = cb_hessian_convex;
  n_conv_recs = n_convex_calls = 0;
  for (int k = 0; k < 6; ++k) x[k] = 0.01 * (1 + 0.3 * k) * (k % 2 ? -1 : 1);
  min_run_obj(P, &o, &obj, x, st);
  cr_assert_eq(st->reason, BS_MIN_CONVERGED, "%s", st->reason_text);
  for (int k = 0; k < 6; ++k) cr_assert_float_eq(fabs(x[k]), 1 / sqrt(2.0), 1e-8, "x[%d] = %.12g", k, x[k]);
  bs_bsr_destroy(&P);
}

/* From the top of the double well the first system meets negative curvature:
 * the next iterations solve with the convexified Hessian until one takes the
 * full Newton step of a solve of 2 or more CG iterations, then the Hessian
 * again (bs_minimize.h, "Convexified model"); the stats count them. Off, or
 * not offered, the model is never called and the iterates are the paper's,
 * bit for bit. */
Test(minimize, convexified_model_after_negative_curvature) {
  double x[6], x_off[6], x_none[6];
  bs_minimize_stats st, st_off, st_none;
  well_convex(1, 1, x, &st);
  cr_assert_eq(conv_recs[0].indefinite, 1, "the first system meets negative curvature");
  cr_assert_eq(conv_recs[0].convexified, 0, "the first system is the Hessian");
  int model = 0, used = 0, back = 0;
  for (int i = 0; i < n_conv_recs; ++i) {
    cr_expect_eq(conv_recs[i].convexified, model, "iteration %d: convexified %d, expected %d", i,
                 conv_recs[i].convexified, model);
    used += conv_recs[i].convexified;
    if (conv_recs[i].indefinite) model = 1;
    else if (model && conv_recs[i].full && conv_recs[i].krylov > 1) model = 0, back++;
  }
  cr_expect_gt(used, 0, "the convexified model was never used");
  cr_expect_gt(back, 0, "the Hessian never came back");
  for (int i = 0; i < n_conv_recs; ++i)
    cr_log_info("iteration %d: convexified %d indefinite %d krylov %d full %d", i, conv_recs[i].convexified,
                conv_recs[i].indefinite, conv_recs[i].krylov, conv_recs[i].full);
  cr_expect_eq(st.convexified, used);
  cr_expect_eq(n_convex_calls, used);
  well_convex(0, 1, x_off, &st_off);
  cr_expect_eq(n_convex_calls, 0);
  cr_expect_eq(st_off.convexified, 0);
  well_convex(1, 0, x_none, &st_none);
  cr_expect_eq(st_none.convexified, 0);
  cr_expect(memcmp(x_off, x_none, sizeof x_off) == 0, "convexify 0 and no model differ");
  cr_expect_eq(st_off.iterations, st_none.iterations);
}

/* convexify outside {0, 1} is refused, naming the option. */
Test(minimize, convexify_option_checked) {
  bs_bsr *P = pattern_chain(2);
  bs_minimize_opts o;
  bs_minimize_opts_default(&o);
  o.convexify = 2;
  bs_minimizer *m = NULL;
  bs_error err = {0};
  cr_assert_eq(bs_minimizer_create(P, &o, &m, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "convexify"), "%s", err.msg);
  bs_bsr_destroy(&P);
}

Test(minimize, alpha_above_one_when_the_step_undershoots) {
  /* The Hessian callback overestimates curvature 20x: every Newton step is
   * 1/20 of the right one, so |phi'(1)| = 0.95 |phi'(0)| fails the curvature
   * condition (c2 = 0.9) with a negative slope and the line search must grow
   * alpha. */
  const int32_t n = 3;
  const int64_t N = 3 * n;
  bs_bsr *P = pattern_chain(n);
  double *A = quad_matrix(n), b[9], x[9] = {0};
  for (int64_t i = 0; i < N; ++i) b[i] = cos(2.0 * i);
  fx f;
  fx_init(&f, n, ev_quad);
  f.A = A;
  f.b = b;
  f.hess_scale = 20;
  bs_minimize_opts o;
  bs_minimize_opts_default(&o);
  o.tol = 1e-6;
  bs_minimizer *m = NULL;
  bs_error err = {0};
  cr_assert_eq(bs_minimizer_create(P, &o, &m, &err), 0, "%s", err.msg);
  bs_objective obj = make_obj(&f, NULL);
  bs_minimize_stats st;
  cr_assert_eq(bs_minimize(m, &obj, x, &st, &err), 0, "%s", err.msg);
  cr_assert_eq(st.reason, BS_MIN_CONVERGED, "%s", st.reason_text);
  cr_assert_gt(st.alpha_max, 10.0, "alpha_max = %g", st.alpha_max);
  cr_assert_eq(f.bad_wolfe, 0);
  cr_assert_eq(f.bad_point, 0);
  cr_assert_eq(st.ls_failures, 0);
  bs_minimizer_destroy(&m);
  bs_bsr_destroy(&P);
  free(A);
}

Test(minimize, length_clamp) {
  bs_bsr *P = pattern_chain(1);
  fx f;
  fx_init(&f, 1, ev_weak);
  f.eps = 1e-6; /* Newton step 1e6 per dof from 0, clamped to 1e3 */
  bs_minimize_opts o;
  bs_minimize_opts_default(&o);
  o.tol = 1e-6;
  bs_minimizer *m = NULL;
  bs_error err = {0};
  cr_assert_eq(bs_minimizer_create(P, &o, &m, &err), 0, "%s", err.msg);
  bs_objective obj = make_obj(&f, NULL);
  double x[3] = {0, 0, 0};
  bs_minimize_stats st;
  cr_assert_eq(bs_minimize(m, &obj, x, &st, &err), 0, "%s", err.msg);
  cr_assert_eq(st.reason, BS_MIN_CONVERGED, "%s", st.reason_text);
  cr_assert_gt(st.clamps, 0);
  cr_assert_gt(st.alpha_max, 1.0, "alpha beyond 1 undoes the clamp");
  for (int k = 0; k < 3; ++k) cr_assert_float_eq(x[k], 1e6, 1.0, "x = %.9g", x[k]);
  cr_assert_eq(f.bad_wolfe, 0);
  /* A smaller clamp: more clamped steps, same answer. */
  bs_minimize_opts o2 = o;
  o2.clamp = 10;
  cr_assert_eq(bs_minimizer_set_opts(m, &o2, &err), 0, "%s", err.msg);
  double y[3] = {0, 0, 0};
  cr_assert_eq(bs_minimize(m, &obj, y, &st, &err), 0, "%s", err.msg);
  cr_assert_eq(st.reason, BS_MIN_CONVERGED, "%s", st.reason_text);
  cr_assert_gt(st.clamps, 0);
  cr_assert_gt(st.alpha_max, 100.0, "alpha_max = %g", st.alpha_max);
  for (int k = 0; k < 3; ++k) cr_assert_float_eq(y[k], 1e6, 1.0);
  bs_minimizer_destroy(&m);
  bs_bsr_destroy(&P);
}

static void cap_trace(const bs_min_iter *it, void *ctx) {
  fx *f = ctx;
  if (!(it->phi < it->phi0)) f->bad_decrease++;
  if (it->ls_status == BS_LSEARCH_CAPPED) f->bad_wolfe++; /* here: counts steps taken without a Wolfe point */
  f->n_rec++;
}

Test(minimize, line_search_cap_takes_the_best_decrease) {
  /* One trial point per line search: along a clamped direction alpha = 1
   * decreases E but fails the curvature condition (|phi'(1)| = 0.94 |phi'(0)|),
   * and, as the lowest decreasing point, is taken anyway. */
  bs_bsr *P = pattern_chain(1);
  fx f;
  fx_init(&f, 1, ev_weak);
  f.eps = 1e-4;
  bs_minimize_opts o;
  bs_minimize_opts_default(&o);
  o.tol = 1e-8;
  o.max_ls = 1;
  bs_minimizer *m = NULL;
  bs_error err = {0};
  cr_assert_eq(bs_minimizer_create(P, &o, &m, &err), 0, "%s", err.msg);
  bs_objective obj = make_obj(&f, NULL);
  obj.trace = cap_trace;
  double x[3] = {0, 0, 0};
  bs_minimize_stats st;
  cr_assert_eq(bs_minimize(m, &obj, x, &st, &err), 0, "%s", err.msg);
  cr_assert_eq(st.reason, BS_MIN_CONVERGED, "%s", st.reason_text);
  cr_assert_gt(st.ls_failures, 0);
  cr_assert_eq(f.bad_wolfe, st.ls_failures);
  cr_assert_eq(f.bad_decrease, 0, "a capped line search never increases E");
  cr_assert_float_eq(st.alpha_max, 1.0, 0, "alpha_max = %.17g", st.alpha_max);
  cr_assert_eq(st.ls_evaluations, st.iterations);
  for (int k = 0; k < 3; ++k) cr_assert_float_eq(x[k], 1e4, 1e-6);
  bs_minimizer_destroy(&m);
  bs_bsr_destroy(&P);
}

Test(minimize, non_evaluable_points_shrink_the_step) {
  bs_bsr *P = pattern_chain(2);
  fx f;
  fx_init(&f, 2, ev_barrier);
  bs_minimize_opts o;
  bs_minimize_opts_default(&o);
  o.tol = 1e-10;
  bs_minimizer *m = NULL;
  bs_error err = {0};
  cr_assert_eq(bs_minimizer_create(P, &o, &m, &err), 0, "%s", err.msg);
  bs_objective obj = make_obj(&f, NULL);
  double x[6] = {10, 10, 10, 10, 10, 10};
  bs_minimize_stats st;
  cr_assert_eq(bs_minimize(m, &obj, x, &st, &err), 0, "%s", err.msg);
  cr_assert_eq(st.reason, BS_MIN_CONVERGED, "%s", st.reason_text);
  for (int k = 0; k < 6; ++k) cr_assert_float_eq(x[k], 1.0, 1e-9);
  cr_assert_lt(st.alpha_min, 1.0, "the first Newton step (to u = -80) had to shrink");
  cr_assert_eq(f.bad_wolfe, 0);
  bs_minimizer_destroy(&m);
  bs_bsr_destroy(&P);
}

/* ---- fixed dofs ------------------------------------------------------------- */

static void project_shift_fixed(double *x, void *ctx) {
  (void)ctx;
  /* A hostile projection that moves vertex 1 (fixed) and nothing else. */
  for (int k = 0; k < 3; ++k) x[3 + k] += 1.0;
}

Test(minimize, fixed_dofs_never_move) {
  const int32_t n = 4;
  const int64_t N = 3 * n;
  bs_bsr *P = pattern_chain(n);
  double *A = quad_matrix(n), b[12], x[12];
  for (int64_t i = 0; i < N; ++i) {
    b[i] = sin(3.0 * i);
    x[i] = 0.1 * i;
  }
  uint8_t mask[4] = {1, 0, 1, 0};
  double x0[12];
  memcpy(x0, x, sizeof x);
  fx f;
  fx_init(&f, n, ev_quad);
  f.A = A;
  f.b = b;
  bs_minimize_opts o;
  bs_minimize_opts_default(&o);
  o.tol = 1e-10;
  bs_minimizer *m = NULL;
  bs_error err = {0};
  cr_assert_eq(bs_minimizer_create(P, &o, &m, &err), 0, "%s", err.msg);
  bs_objective obj = make_obj(&f, mask);
  obj.trace = NULL;
  obj.project = project_shift_fixed;
  bs_minimize_stats st;
  cr_assert_eq(bs_minimize(m, &obj, x, &st, &err), 0, "%s", err.msg);
  cr_assert_eq(st.reason, BS_MIN_CONVERGED, "%s", st.reason_text);
  for (int v = 0; v < n; ++v)
    if (!mask[v])
      for (int k = 0; k < 3; ++k) cr_assert_eq(x[3 * v + k], x0[3 * v + k], "fixed vertex %d moved", v);
  /* Free rows satisfy A_ff x_f + A_fc x_c = b_f. */
  for (int64_t i = 0; i < N; ++i) {
    if (!mask[i / 3]) continue;
    double ax = 0;
    for (int64_t j = 0; j < N; ++j) ax += A[i * N + j] * x[j];
    cr_assert_float_eq(ax, b[i], 1e-9, "free row %lld", (long long)i);
  }
  /* The baseline obeys the mask too. */
  memcpy(x, x0, sizeof x);
  cr_assert_eq(bs_newton(m, &obj, 0, x, &st, &err), 0, "%s", err.msg);
  cr_assert_eq(st.reason, BS_MIN_CONVERGED, "%s", st.reason_text);
  for (int v = 0; v < n; ++v)
    if (!mask[v])
      for (int k = 0; k < 3; ++k) cr_assert_eq(x[3 * v + k], x0[3 * v + k]);
  bs_minimizer_destroy(&m);
  bs_bsr_destroy(&P);
  free(A);
}

/* ---- constraints: stay outside a sphere (paper 3.2) ------------------------- */

/* E' = k/2 |x - t|^2; feasible set |x| >= R; phi = |x| - R, grad phi = x/|x|. */
static int ev_sphere(fx *f, const double *x, double *E, double *g, bs_bsr *H) {
  double e = 0, gp[3];
  for (int k = 0; k < 3; ++k) {
    double dk = x[k] - f->t[k];
    e += 0.5 * f->k * dk * dk;
    gp[k] = f->k * dk;
    if (g) g[k] = gp[k];
  }
  *E = e;
  if (H) {
    if (f->active) {
      /* Hessian of E'(P(x)) at |x| = R in the tangent plane: k (I - nn^T) minus
       * (g'.n)/R (I - nn^T) (curvature of P); k nn^T keeps it nonsingular (the
       * normal direction is projected out of every right-hand side). */
      double r = sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]), nv[3], gn = 0;
      for (int k = 0; k < 3; ++k) nv[k] = x[k] / r;
      for (int k = 0; k < 3; ++k) gn += gp[k] * nv[k];
      for (int a = 0; a < 3; ++a)
        for (int c = 0; c < 3; ++c) {
          double T = (a == c) - nv[a] * nv[c];
          hadd(H, a, c, (f->k - gn / f->R) * T + f->k * nv[a] * nv[c]);
        }
    } else {
      for (int a = 0; a < 3; ++a) hadd(H, a, a, f->k);
    }
  }
  return 0;
}

static void sphere_project(double *x, void *ctx) {
  fx *f = ctx;
  double r = sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]);
  if ((f->active || r < f->R) && r > 0)
    for (int k = 0; k < 3; ++k) x[k] *= f->R / r;
}

static void sphere_register(const double *x, const double *g, void *ctx) {
  fx *f = ctx;
  double r = sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]);
  cr_assert_geq(r, f->R * (1 - 1e-12), "register_active called at an infeasible point (|x| = %.17g)", r);
  int touching = fabs(r - f->R) <= 1e-12 * f->R;
  double gn = (g[0] * x[0] + g[1] * x[1] + g[2] * x[2]) / r;
  int was = f->active;
  f->active = touching && gn >= 0; /* paper: touching and grad E'.grad phi >= 0 */
  f->activations += !was && f->active;
  f->releases += was && !f->active;
}

static void sphere_project_gradient(const double *x, double *g, void *ctx) {
  fx *f = ctx;
  if (!f->active) return;
  double r = sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]);
  double gn = (g[0] * x[0] + g[1] * x[1] + g[2] * x[2]) / r;
  for (int k = 0; k < 3; ++k) g[k] -= gn * x[k] / r;
}

static void sphere_trace(const bs_min_iter *it, void *ctx) {
  fx *f = ctx;
  if (!(it->phi <= it->phi0)) f->bad_decrease++;
  double r = sqrt(it->y[0] * it->y[0] + it->y[1] * it->y[1] + it->y[2] * it->y[2]);
  if (r < f->R * (1 - 1e-12)) f->bad_point++; /* iterates stay feasible */
  f->n_rec++;
}

static void run_sphere(fx *f, double *x, bs_minimize_stats *st) {
  bs_bsr *P = pattern_chain(1);
  bs_minimize_opts o;
  bs_minimize_opts_default(&o);
  o.tol = 1e-9;
  bs_minimizer *m = NULL;
  bs_error err = {0};
  cr_assert_eq(bs_minimizer_create(P, &o, &m, &err), 0, "%s", err.msg);
  bs_objective obj = make_obj(f, NULL);
  obj.project = sphere_project;
  obj.register_active = sphere_register;
  obj.project_gradient = sphere_project_gradient;
  obj.trace = sphere_trace;
  cr_assert_eq(bs_minimize(m, &obj, x, st, &err), 0, "%s", err.msg);
  bs_minimizer_destroy(&m);
  bs_bsr_destroy(&P);
}

Test(minimize, sphere_constraint_active_at_solution) {
  fx f;
  fx_init(&f, 1, ev_sphere);
  f.k = 2.0;
  f.R = 1.0;
  f.t[0] = 0.3, f.t[1] = 0.2, f.t[2] = -0.1; /* inside: the solution is on the sphere */
  double x[3] = {0.5, 2.0, 0.3};
  bs_minimize_stats st;
  run_sphere(&f, x, &st);
  cr_assert_eq(st.reason, BS_MIN_CONVERGED, "%s", st.reason_text);
  double tn = sqrt(f.t[0] * f.t[0] + f.t[1] * f.t[1] + f.t[2] * f.t[2]);
  for (int k = 0; k < 3; ++k)
    cr_assert_float_eq(x[k], f.R * f.t[k] / tn, 1e-8, "x[%d] = %.12g, expected %.12g", k, x[k], f.R * f.t[k] / tn);
  cr_assert_float_eq(sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]), f.R, 1e-12);
  cr_assert_eq(f.active, 1, "the constraint is active at the solution");
  cr_assert_eq(f.bad_decrease, 0);
  cr_assert_eq(f.bad_point, 0);
  cr_assert_lt(st.iterations, 30, "%d iterations", st.iterations);
}

Test(minimize, sphere_constraint_released) {
  /* Start touching with the pull partly inward: active first, then the point
   * slides round the sphere until grad E' points inward and the constraint
   * separates; the solution is the (outside) target. */
  fx f;
  fx_init(&f, 1, ev_sphere);
  f.k = 1.0;
  f.R = 1.0;
  f.t[0] = 2.0, f.t[1] = 0.5, f.t[2] = 0.0;
  double x[3] = {0.0, 1.0, 0.0};
  bs_minimize_stats st;
  run_sphere(&f, x, &st);
  cr_assert_eq(st.reason, BS_MIN_CONVERGED, "%s", st.reason_text);
  for (int k = 0; k < 3; ++k) cr_assert_float_eq(x[k], f.t[k], 1e-8, "x[%d] = %.12g", k, x[k]);
  cr_assert_geq(f.activations, 1, "the constraint was active at the start");
  cr_assert_geq(f.releases, 1, "and was released");
  cr_assert_eq(f.active, 0);
  cr_assert_eq(f.bad_decrease, 0);
  cr_assert_eq(f.bad_point, 0);
}

Test(minimize, initial_guess_is_projected) {
  fx f;
  fx_init(&f, 1, ev_sphere);
  f.k = 1.0;
  f.R = 1.0;
  f.t[0] = 0.0, f.t[1] = 0.0, f.t[2] = 3.0; /* outside, straight above */
  double x[3] = {0.0, 0.0, 0.2};           /* infeasible start */
  bs_bsr *P = pattern_chain(1);
  bs_minimize_opts o;
  bs_minimize_opts_default(&o);
  o.tol = 1e-9;
  bs_minimizer *m = NULL;
  bs_error err = {0};
  cr_assert_eq(bs_minimizer_create(P, &o, &m, &err), 0, "%s", err.msg);
  bs_objective obj = make_obj(&f, NULL);
  obj.project = sphere_project;
  obj.register_active = sphere_register; /* asserts feasibility when called */
  obj.project_gradient = sphere_project_gradient;
  obj.trace = sphere_trace;
  bs_minimize_stats st;
  cr_assert_eq(bs_minimize(m, &obj, x, &st, &err), 0, "%s", err.msg);
  cr_assert_eq(st.reason, BS_MIN_CONVERGED, "%s", st.reason_text);
  cr_assert_float_eq(x[2], 3.0, 1e-8);
  cr_assert_eq(f.bad_point, 0);
  bs_minimizer_destroy(&m);
  bs_bsr_destroy(&P);
}

/* ---- the lower-bound shortcut (paper 3.3) ---------------------------------- */

/* E = sum (u-1)^2/2 + s(u), s = 0.1 sum u^4 >= 0 (the "expensive" term);
 * the lower bound is the quadratic part. */
static double lb_quad(const double *u) {
  double q = 0;
  for (int k = 0; k < 3; ++k) q += 0.5 * (u[k] - 1) * (u[k] - 1);
  return q;
}

static int ev_lb(fx *f, const double *u, double *E, double *g, bs_bsr *H) {
  double e = lb_quad(u);
  for (int k = 0; k < 3; ++k) {
    e += 0.1 * pow(u[k], 4);
    if (g) g[k] = (u[k] - 1) + 0.4 * pow(u[k], 3);
    if (H) hadd(H, k, k, 1 + 1.2 * u[k] * u[k]);
  }
  *E = e;
  return 0;
}

static int lb_value(const double *x, double *E, void *ctx) {
  fx *f = ctx;
  if (lb_quad(x) > f->E_cur * (1 + 1e-14)) f->lb_violations++;
  return cb_value(x, E, ctx);
}

static int lb_gradient(const double *x, double *E, double *g, void *ctx) {
  fx *f = ctx;
  if (lb_quad(x) > f->E_cur * (1 + 1e-14)) f->lb_violations++;
  return cb_gradient(x, E, g, ctx);
}

static int lb_bound(const double *x, double *E, void *ctx) {
  fx *f = ctx;
  f->lb_calls++;
  *E = lb_quad(x);
  if (*E > f->E_cur) f->lb_skips++;
  return 0;
}

static void lb_trace(const bs_min_iter *it, void *ctx) {
  fx *f = ctx;
  f->E_cur = it->phi; /* E(x_{i+1}): the reference of the next line search */
  f->n_rec++;
}

Test(minimize, lower_bound_skips_expensive_terms) {
  bs_bsr *P = pattern_chain(1);
  fx f;
  fx_init(&f, 1, ev_lb);
  f.hess_scale = 1e-3; /* 1000x too long Newton steps: the first trial overshoots far */
  bs_minimize_opts o;
  bs_minimize_opts_default(&o);
  o.tol = 1e-7;
  bs_minimizer *m = NULL;
  bs_error err = {0};
  cr_assert_eq(bs_minimizer_create(P, &o, &m, &err), 0, "%s", err.msg);
  bs_objective obj = make_obj(&f, NULL);
  obj.value = lb_value;
  obj.gradient = lb_gradient;
  obj.value_lower_bound = lb_bound;
  obj.trace = lb_trace;
  double x[3] = {3.0, -2.0, 2.5};
  ev_lb(&f, x, &f.E_cur, NULL, NULL);
  bs_minimize_stats st;
  cr_assert_eq(bs_minimize(m, &obj, x, &st, &err), 0, "%s", err.msg);
  cr_assert_eq(st.reason, BS_MIN_CONVERGED, "%s", st.reason_text);
  cr_assert_gt(f.lb_skips, 0, "the bound exceeded E(x_i) at some trial point");
  cr_assert_eq(f.lb_violations, 0, "value()/gradient() called where the bound already exceeded E(x_i)");
  cr_assert_eq(f.lb_calls, st.ls_evaluations);
  double g[3];
  double E;
  ev_lb(&f, x, &E, g, NULL);
  cr_assert_lt(sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]), 1e-7);
  bs_minimizer_destroy(&m);
  bs_bsr_destroy(&P);
}

/* ---- non-finite objectives and errors -------------------------------------- */

Test(minimize, nan_objective_is_reported) {
  const int32_t n = 2;
  bs_bsr *P = pattern_chain(n);
  double *A = quad_matrix(n), b[6] = {1, 2, 3, 4, 5, 6}, x[6] = {0};
  fx f;
  fx_init(&f, n, ev_nan);
  f.A = A;
  f.b = b;
  f.nan_mode = 1;
  bs_minimizer *m = NULL;
  bs_error err = {0};
  cr_assert_eq(bs_minimizer_create(P, NULL, &m, &err), 0, "%s", err.msg);
  bs_objective obj = make_obj(&f, NULL);
  bs_minimize_stats st;
  cr_assert_eq(bs_minimize(m, &obj, x, &st, &err), 0, "%s", err.msg);
  cr_assert_eq(st.reason, BS_MIN_NONFINITE);
  cr_assert(strstr(st.reason_text, "initial point") != NULL, "%s", st.reason_text);
  cr_assert_eq(st.iterations, 0);
  f.nan_mode = 2;
  cr_assert_eq(bs_minimize(m, &obj, x, &st, &err), 0, "%s", err.msg);
  cr_assert_eq(st.reason, BS_MIN_NONFINITE);
  cr_assert(strstr(st.reason_text, "vertex 1 component 2") != NULL, "%s", st.reason_text);
  /* The baseline reports it the same way. */
  cr_assert_eq(bs_newton(m, &obj, 0, x, &st, &err), 0, "%s", err.msg);
  cr_assert_eq(st.reason, BS_MIN_NONFINITE);
  cr_assert(strstr(st.reason_text, "vertex 1 component 2") != NULL, "%s", st.reason_text);
  bs_minimizer_destroy(&m);
  bs_bsr_destroy(&P);
  free(A);
}

static int hess_fails(const double *x, bs_bsr *H, void *ctx) {
  (void)x, (void)H, (void)ctx;
  return 7;
}

Test(minimize, errors_name_the_culprit) {
  bs_bsr *P = pattern_chain(2);
  bs_error err = {0};
  bs_minimizer *m = NULL;
  bs_minimize_opts o;
  bs_minimize_opts_default(&o);
  o.c2 = 1e-5; /* below c1 */
  cr_assert_eq(bs_minimizer_create(P, &o, &m, &err), BS_EINPUT);
  cr_assert_null(m);
  cr_assert(strstr(err.msg, "c2") != NULL, "%s", err.msg);
  bs_minimize_opts_default(&o);
  o.kappa = 1.5;
  cr_assert_eq(bs_minimizer_create(P, &o, &m, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "kappa") != NULL, "%s", err.msg);
  bs_minimize_opts_default(&o);
  o.max_ls = 0;
  cr_assert_eq(bs_minimizer_create(P, &o, &m, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "max_ls") != NULL, "%s", err.msg);
  cr_assert_eq(bs_minimizer_create(NULL, NULL, &m, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "pattern") != NULL, "%s", err.msg);

  cr_assert_eq(bs_minimizer_create(P, NULL, &m, &err), 0, "%s", err.msg);
  /* set_opts rejects bad options and keeps the old ones. */
  bs_minimize_opts_default(&o);
  o.clamp = -1;
  cr_assert_eq(bs_minimizer_set_opts(m, &o, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "clamp") != NULL, "%s", err.msg);
  cr_assert_float_eq(bs_minimizer_opts(m)->clamp, 1e3, 0);

  fx f;
  fx_init(&f, 3, ev_well); /* wrong size: 3 vertices for a 2-vertex minimizer */
  bs_objective obj = make_obj(&f, NULL);
  double x[9] = {0};
  bs_minimize_stats st;
  cr_assert_eq(bs_minimize(m, &obj, x, &st, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "n = 3") != NULL, "%s", err.msg);
  f.n = 2;
  obj = make_obj(&f, NULL);
  obj.hessian = NULL;
  cr_assert_eq(bs_minimize(m, &obj, x, &st, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "hessian") != NULL, "%s", err.msg);
  obj = make_obj(&f, NULL);
  x[4] = INFINITY;
  cr_assert_eq(bs_minimize(m, &obj, x, &st, &err), BS_ENUMERIC);
  cr_assert(strstr(err.msg, "vertex 1 component 1") != NULL, "%s", err.msg);
  cr_assert_eq(bs_newton(m, &obj, 0, x, &st, &err), BS_ENUMERIC);
  x[4] = 0.3;
  cr_assert_eq(bs_newton(m, &obj, -1, x, &st, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "k_steps") != NULL, "%s", err.msg);
  /* A Hessian callback that fails stops the solve with a reason. */
  for (int k = 0; k < 6; ++k) x[k] = 0.3;
  obj.hessian = hess_fails;
  cr_assert_eq(bs_minimize(m, &obj, x, &st, &err), 0, "%s", err.msg);
  cr_assert_eq(st.reason, BS_MIN_NONFINITE);
  cr_assert(strstr(st.reason_text, "Hessian") != NULL, "%s", st.reason_text);
  bs_minimizer_destroy(&m);
  bs_bsr_destroy(&P);
}

static int ev_const(fx *f, const double *u, double *E, double *g, bs_bsr *H) {
  (void)f, (void)u, (void)g, (void)H;
  *E = 42.0;
  return 0;
}

Test(minimize, empty_problem) {
  int32_t ptr[1] = {0};
  bs_bsr *P = NULL;
  bs_error err = {0};
  cr_assert_eq(bs_bsr_create(0, ptr, NULL, &P, &err), 0, "%s", err.msg);
  bs_minimizer *m = NULL;
  cr_assert_eq(bs_minimizer_create(P, NULL, &m, &err), 0, "%s", err.msg);
  fx f;
  fx_init(&f, 0, ev_const);
  bs_objective obj = make_obj(&f, NULL);
  double x[1] = {0};
  bs_minimize_stats st;
  cr_assert_eq(bs_minimize(m, &obj, x, &st, &err), 0, "%s", err.msg);
  cr_assert_eq(st.reason, BS_MIN_CONVERGED, "%s", st.reason_text);
  cr_assert_eq(st.iterations, 0);
  cr_assert_float_eq(st.E, 42.0, 0);
  cr_assert_eq(bs_newton(m, &obj, 3, x, &st, &err), 0, "%s", err.msg);
  cr_assert_eq(st.reason, BS_MIN_CONVERGED, "%s", st.reason_text);
  bs_minimizer_destroy(&m);
  bs_bsr_destroy(&P);
}

/* A stalled objective: E rises in every direction the solver can take
 * (a non-smooth kink). The line search must report it, not loop. */
static int ev_kink(fx *f, const double *u, double *E, double *g, bs_bsr *H) {
  /* E = |u0| with the gradient of a smooth function pointing the wrong way. */
  *E = fabs(u[0]) + fabs(u[1]) + fabs(u[2]);
  if (g) g[0] = g[1] = g[2] = 1.0;
  if (H)
    for (int k = 0; k < 3; ++k) hadd(H, k, k, 1.0);
  return 0;
}

/* A kink across which the Newton direction steps (E = 10 |u0| + 100 (u1 -
 * 1)^2 + u2^2 from the origin, with a Hessian that models the kink as a
 * shallow valley: d = (-1e5, 1, 0), clamped to length 1e3): E rises along
 * every point of that line search. The minimizer then searches along -g,
 * which decreases E, instead of ending the solve. */
static int ev_kink_valley(fx *f, const double *u, double *E, double *g, bs_bsr *H) {
  (void)f;
  *E = 10 * fabs(u[0]) + 100 * (u[1] - 1) * (u[1] - 1) + u[2] * u[2];
  if (g) g[0] = u[0] >= 0 ? 10 : -10, g[1] = 200 * (u[1] - 1), g[2] = 2 * u[2];
  if (H) hadd(H, 0, 0, 1e-4), hadd(H, 1, 1, 200), hadd(H, 2, 2, 2);
  return 0;
}

Test(minimize, a_failed_newton_line_search_restarts_along_the_gradient) {
  bs_bsr *P = pattern_chain(1);
  fx f;
  fx_init(&f, 1, ev_kink_valley);
  bs_minimize_opts o;
  bs_minimize_opts_default(&o);
  o.max_iter = 20;
  o.sigma = 1e-12; /* exact Newton directions (a loose CG stops near -g) */
  o.cg_downhill = 0;
  bs_objective obj = make_obj(&f, NULL);
  obj.trace = NULL;
  double x[3] = {0, 0, 0};
  bs_minimize_stats st;
  min_run_obj(P, &o, &obj, x, &st);
  cr_expect(st.iterations >= 1 && st.fallback_neg_grad >= 1, "%d iterations, %d -g fallbacks: %s", st.iterations,
            st.fallback_neg_grad, st.reason_text);
  cr_expect(st.E < 1e-2, "E = %g (100 at the start; without the restart the solve ends there)", st.E);
  bs_bsr_destroy(&P);
}

Test(minimize, line_search_failure_is_reported) {
  bs_bsr *P = pattern_chain(1);
  fx f;
  fx_init(&f, 1, ev_kink);
  bs_minimize_opts o;
  bs_minimize_opts_default(&o);
  o.max_ls = 15;
  bs_minimizer *m = NULL;
  bs_error err = {0};
  cr_assert_eq(bs_minimizer_create(P, &o, &m, &err), 0, "%s", err.msg);
  bs_objective obj = make_obj(&f, NULL);
  obj.trace = NULL;
  double x[3] = {0, 0, 0}, x0[3] = {0, 0, 0};
  bs_minimize_stats st;
  cr_assert_eq(bs_minimize(m, &obj, x, &st, &err), 0, "%s", err.msg);
  cr_assert_eq(st.reason, BS_MIN_LINE_SEARCH, "%s", st.reason_text);
  cr_assert_eq(st.ls_evaluations, 15);
  cr_assert_eq(memcmp(x, x0, sizeof x), 0, "x unchanged when E cannot decrease");
  cr_assert_eq(st.iterations, 0);
  bs_minimizer_destroy(&m);
  bs_bsr_destroy(&P);
}

Test(minimize, max_iter_and_naive_guess) {
  bs_bsr *P = pattern_chain(1);
  fx f;
  fx_init(&f, 1, ev_rosen2);
  bs_minimize_opts o;
  bs_minimize_opts_default(&o);
  o.tol = 1e-12;
  o.max_iter = 3;
  bs_minimizer *m = NULL;
  bs_error err = {0};
  cr_assert_eq(bs_minimizer_create(P, &o, &m, &err), 0, "%s", err.msg);
  bs_objective obj = make_obj(&f, NULL);
  double x[3] = {-1.2, 1.0, 0.0};
  bs_minimize_stats st;
  cr_assert_eq(bs_minimize(m, &obj, x, &st, &err), 0, "%s", err.msg);
  cr_assert_eq(st.reason, BS_MIN_MAX_ITER, "%s", st.reason_text);
  cr_assert_eq(st.iterations, 3);
  /* Already converged: no iteration, unless the guess is naive. */
  fx_init(&f, 1, ev_rosen2);
  obj = make_obj(&f, NULL);
  o.tol = 1e-3;
  o.max_iter = 500;
  cr_assert_eq(bs_minimizer_set_opts(m, &o, &err), 0, "%s", err.msg);
  double y[3] = {1.0 + 1e-6, 1.0 + 2e-6, 0.0};
  cr_assert_eq(bs_minimize(m, &obj, y, &st, &err), 0, "%s", err.msg);
  cr_assert_eq(st.reason, BS_MIN_CONVERGED);
  cr_assert_eq(st.iterations, 0);
  o.naive_guess = 1;
  cr_assert_eq(bs_minimizer_set_opts(m, &o, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_minimize(m, &obj, y, &st, &err), 0, "%s", err.msg);
  cr_assert_eq(st.reason, BS_MIN_CONVERGED);
  cr_assert_eq(st.iterations, 1);
  bs_minimizer_destroy(&m);
  bs_bsr_destroy(&P);
}

/* Rounding noise of E emulated deterministically: exp(u) - 2u per dof, and
 * from the first gradient evaluation with |g| < 1e-7 on, every evaluation of
 * E is 16 eps |E| higher (the last iterate's E was a "lucky low" rounding, as
 * happens with sums of many terms). The gradient is exact throughout. */
static int noisy_value(const double *x, double *E, void *ctx) {
  fx *f = ctx;
  ev_exp(f, x, E, NULL, NULL);
  if (f->noise_on) *E += 16 * 2.220446049250313e-16 * fabs(*E);
  return 0;
}

static int noisy_gradient(const double *x, double *E, double *g, void *ctx) {
  fx *f = ctx;
  noisy_value(x, E, ctx);
  ev_exp(f, x, &(double){0}, g, NULL);
  if (sqrt(dot(3, g, g)) < 1e-7) f->noise_on = 1; /* switch the bias on for later evaluations */
  return 0;
}

static void cb_trace_noise(const bs_min_iter *it, void *ctx) {
  ((fx *)ctx)->n_noise_rec += it->ls_status == BS_LSEARCH_NOISE;
}

Test(minimize, tolerance_below_the_rounding_of_E) {
  bs_bsr *P = pattern_chain(1);
  fx f;
  fx_init(&f, 1, ev_exp);
  f.hess_scale = 2; /* half Newton steps: |g| passes every scale on its way down */
  bs_minimize_opts o;
  bs_minimize_opts_default(&o);
  o.tol = 1e-12;
  bs_minimizer *m = NULL;
  bs_error err = {0};
  cr_assert_eq(bs_minimizer_create(P, &o, &m, &err), 0, "%s", err.msg);
  bs_objective obj = make_obj(&f, NULL);
  obj.value = noisy_value;
  obj.gradient = noisy_gradient;
  obj.trace = NULL;
  double x[3] = {1.0, 1.2, 0.9};
  bs_minimize_stats st;
  /* The paper's rule: stop, and say why. */
  cr_assert_eq(bs_minimize(m, &obj, x, &st, &err), 0, "%s", err.msg);
  cr_assert_eq(f.noise_on, 1, "the noise was switched on");
  cr_assert_eq(st.reason, BS_MIN_FLOOR, "%s", st.reason_text);
  cr_assert(bs_min_reason_converged(st.reason));
  cr_assert(strstr(st.reason_text, "rounding floor of E") != NULL, "%s", st.reason_text);
  cr_assert_gt(st.grad_norm, o.tol);
  /* accept_noise: the rounding-level step is taken and tol is reached. */
  o.accept_noise = 1;
  cr_assert_eq(bs_minimizer_set_opts(m, &o, &err), 0, "%s", err.msg);
  f.noise_on = 0;
  double y[3] = {1.0, 1.2, 0.9};
  obj.trace = cb_trace_noise;
  cr_assert_eq(bs_minimize(m, &obj, y, &st, &err), 0, "%s", err.msg);
  cr_assert_eq(st.reason, BS_MIN_CONVERGED, "%s", st.reason_text);
  cr_assert_gt(st.noise_steps, 0);
  cr_assert_eq(f.n_noise_rec, st.noise_steps, "the trace saw %d noise steps", f.n_noise_rec);
  for (int k = 0; k < 3; ++k) cr_assert_float_eq(y[k], log(2.0), 1e-12);
  bs_minimizer_destroy(&m);
  bs_bsr_destroy(&P);
}

/* ---- other linear solvers ---------------------------------------------------- */

static void run_well(bs_lin_kind kind, bs_minimize_stats *st, double *x) {
  bs_bsr *P = pattern_chain(2);
  fx f;
  fx_init(&f, 2, ev_well);
  bs_minimize_opts o;
  bs_minimize_opts_default(&o);
  o.tol = 1e-10;
  o.linear = kind;
  bs_minimizer *m = NULL;
  bs_error err = {0};
  cr_assert_eq(bs_minimizer_create(P, &o, &m, &err), 0, "%s", err.msg);
  bs_objective obj = make_obj(&f, NULL);
  for (int k = 0; k < 6; ++k) x[k] = (k % 2 ? -0.02 : 0.01) * (1 + 0.1 * k);
  cr_assert_eq(bs_minimize(m, &obj, x, st, &err), 0, "%s", err.msg);
  cr_assert_eq(f.bad_wolfe, 0);
  bs_minimizer_destroy(&m);
  bs_bsr_destroy(&P);
}

Test(minimize, cholmod_falls_back_to_cg_when_indefinite) {
  bs_minimize_stats st;
  double x[6];
  run_well(BS_LIN_CHOLMOD, &st, x);
  cr_assert_eq(st.reason, BS_MIN_CONVERGED, "%s", st.reason_text);
  cr_assert_gt(st.cholmod_fallbacks, 0);
  for (int k = 0; k < 6; ++k) cr_assert_float_eq(fabs(x[k]), 1 / sqrt(2.0), 1e-8);
}

Test(minimize, pcg_converges) {
  bs_minimize_stats st;
  double x[6];
  run_well(BS_LIN_PCG, &st, x);
  cr_assert_eq(st.reason, BS_MIN_CONVERGED, "%s", st.reason_text);
  cr_assert_gt(st.indefinite_exits, 0);
  for (int k = 0; k < 6; ++k) cr_assert_float_eq(fabs(x[k]), 1 / sqrt(2.0), 1e-8);
}

/* ---- the Newton baseline ------------------------------------------------------ */

Test(newton, converges_quadratically_on_a_mild_problem) {
  bs_bsr *P = pattern_chain(1);
  fx f;
  fx_init(&f, 1, ev_exp);
  bs_minimize_opts o;
  bs_minimize_opts_default(&o);
  o.tol = 1e-13;
  bs_minimizer *m = NULL;
  bs_error err = {0};
  cr_assert_eq(bs_minimizer_create(P, &o, &m, &err), 0, "%s", err.msg);
  bs_objective obj = make_obj(&f, NULL);
  double x[3] = {0, 0, 0};
  bs_minimize_stats st;
  cr_assert_eq(bs_newton(m, &obj, 0, x, &st, &err), 0, "%s", err.msg);
  cr_assert_eq(st.reason, BS_MIN_CONVERGED, "%s", st.reason_text);
  cr_assert_lt(st.iterations, 10);
  for (int k = 0; k < 3; ++k) cr_assert_float_eq(x[k], log(2.0), 1e-13);
  /* e_{k+1} ~ (f''/2f') e_k^2 = e_k^2 / 2 for the root of exp(u) - 2. */
  int pairs = 0;
  for (int i = 0; i + 1 < f.n_u; ++i) {
    double e0 = fabs(f.u[i] - log(2.0)), e1 = fabs(f.u[i + 1] - log(2.0));
    if (e0 < 0.2 && e1 > 1e-12) {
      double q = e1 / (e0 * e0);
      cr_assert(q > 0.2 && q < 1.0, "e_{k+1}/e_k^2 = %g at step %d (e = %g -> %g)", q, i, e0, e1);
      pairs++;
    }
  }
  cr_assert_geq(pairs, 2, "only %d steps in the quadratic regime", pairs);
  cr_assert_float_eq(st.alpha_last, 1.0, 0);
  /* k Newton steps and stop. */
  fx_init(&f, 1, ev_exp);
  double y[3] = {0, 0, 0};
  cr_assert_eq(bs_newton(m, &obj, 2, y, &st, &err), 0, "%s", err.msg);
  cr_assert_eq(st.iterations, 2);
  cr_assert_eq(st.reason, BS_MIN_STEPS_DONE, "%s", st.reason_text);
  cr_assert_gt(st.grad_norm, o.tol);
  double z[3] = {0, 0, 0};
  cr_assert_eq(bs_newton(m, &obj, 8, z, &st, &err), 0, "%s", err.msg);
  cr_assert_eq(st.iterations, 8);
  cr_assert_eq(st.reason, BS_MIN_CONVERGED, "%s", st.reason_text);
  bs_minimizer_destroy(&m);
  bs_bsr_destroy(&P);
}

Test(newton, fails_where_the_minimizer_succeeds) {
  /* grad E = atan(u): Newton from |u0| > 1.39 diverges; the minimizer converges. */
  bs_bsr *P = pattern_chain(1);
  fx f;
  fx_init(&f, 1, ev_atan);
  bs_minimize_opts o;
  bs_minimize_opts_default(&o);
  o.tol = 1e-10;
  o.max_iter = 100;
  bs_minimizer *m = NULL;
  bs_error err = {0};
  cr_assert_eq(bs_minimizer_create(P, &o, &m, &err), 0, "%s", err.msg);
  bs_objective obj = make_obj(&f, NULL);
  double x[3] = {3.0, -2.0, 5.0};
  bs_minimize_stats st;
  cr_assert_eq(bs_newton(m, &obj, 0, x, &st, &err), 0, "%s", err.msg);
  cr_assert(st.reason == BS_MIN_MAX_ITER || st.reason == BS_MIN_NONFINITE || st.reason == BS_MIN_DIVERGED, "%s",
            st.reason_text);
  cr_assert(!(st.grad_norm < o.tol), "Newton ended away from the root: %s", st.reason_text);
  for (int k = 0; k < 3; ++k) cr_assert(isfinite(x[k]), "x keeps the last finite iterate");

  fx_init(&f, 1, ev_atan);
  double y[3] = {3.0, -2.0, 5.0};
  cr_assert_eq(bs_minimize(m, &obj, y, &st, &err), 0, "%s", err.msg);
  cr_assert_eq(st.reason, BS_MIN_CONVERGED, "%s", st.reason_text);
  for (int k = 0; k < 3; ++k) cr_assert_float_eq(y[k], 0.0, 1e-10);
  cr_assert_eq(f.bad_wolfe, 0);

  /* Rosenbrock-type: the minimizer converges from (-1.2, 1); record what the
   * baseline does from the same start (it must not report convergence to a
   * non-stationary point). */
  fx_init(&f, 1, ev_rosen2);
  double r[3] = {-1.2, 1.0, 0.0};
  cr_assert_eq(bs_newton(m, &obj, 0, r, &st, &err), 0, "%s", err.msg);
  if (st.reason == BS_MIN_CONVERGED) cr_assert_lt(st.grad_norm, o.tol);
  bs_minimizer_destroy(&m);
  bs_bsr_destroy(&P);
}

/* E = |u|^p per dof: Newton's step is u <- u (p - 2) / (p - 1), which
 * diverges for p < 1.5 (p = 1.2: u grows 4-fold, |g| 1.32-fold per step)
 * and converges only linearly for large p (p = 20: u shrinks by 18/19). */
static int ev_pow(fx *f, const double *u, double *E, double *g, bs_bsr *H, double p) {
  const int64_t N = 3 * (int64_t)f->n;
  double e = 0;
  for (int64_t k = 0; k < N; ++k) {
    const double a = fabs(u[k]);
    e += pow(a, p);
    if (g) g[k] = (u[k] < 0 ? -1 : 1) * p * pow(a, p - 1);
    if (H) hadd(H, k, k, p * (p - 1) * pow(a, p - 2));
  }
  *E = e;
  return 0;
}
static int ev_pow12(fx *f, const double *u, double *E, double *g, bs_bsr *H) { return ev_pow(f, u, E, g, H, 1.2); }
static int ev_pow20(fx *f, const double *u, double *E, double *g, bs_bsr *H) { return ev_pow(f, u, E, g, H, 20); }
static int ev_pow15(fx *f, const double *u, double *E, double *g, bs_bsr *H) { return ev_pow(f, u, E, g, H, 1.5); }

/* bs_newton on a 1-vertex fixture (Hessian scaled by hess_scale) from x,
 * at tolerance tol with the iteration cap newton_max_iter; st->reason_text
 * points at a copy valid until the next call. */
static void newton_1(fx_eval ev, double hess_scale, double tol, int newton_max_iter, double x[3],
                     bs_minimize_stats *st) {
  bs_bsr *P = pattern_chain(1);
  fx f;
  fx_init(&f, 1, ev);
  f.hess_scale = hess_scale;
  bs_minimize_opts o;
  bs_minimize_opts_default(&o);
  o.tol = tol;
  o.newton_max_iter = newton_max_iter;
  bs_minimizer *m = NULL;
  bs_error err = {0};
  cr_assert_eq(bs_minimizer_create(P, &o, &m, &err), 0, "%s", err.msg);
  bs_objective obj = make_obj(&f, NULL);
  cr_assert_eq(bs_newton(m, &obj, 0, x, st, &err), 0, "%s", err.msg);
  static char why[512]; /* reason_text lives in the minimizer: keep a copy */
  snprintf(why, sizeof why, "%s", st->reason_text);
  st->reason_text = why;
  bs_minimizer_destroy(&m);
  bs_bsr_destroy(&P);
}

/* The baseline stops a diverging solve early with the reason (not at the
 * iteration cap), and lets a slow but converging one run to convergence. */
Test(newton, stops_when_it_diverges_not_when_it_is_slow) {
  double x[3] = {1, -1, 0.5};
  bs_minimize_stats st;
  newton_1(ev_pow12, 1, 1e-12, 200, x, &st);
  cr_expect_eq(st.reason, BS_MIN_DIVERGED, "%s", st.reason_text);
  cr_expect_leq(st.iterations, BS_NEWTON_WINDOW, "%d iterations: %s", st.iterations, st.reason_text);
  cr_expect(strstr(st.reason_text, "smallest") != NULL, "%s", st.reason_text);
  cr_expect_str_eq(bs_min_reason_name(st.reason), "diverged");

  double y[3] = {1, -1, 0.9};
  newton_1(ev_pow20, 1, 1e-12, 200, y, &st);
  cr_expect_eq(st.reason, BS_MIN_CONVERGED, "%s", st.reason_text);
  cr_expect_gt(st.iterations, BS_NEWTON_WINDOW, "the slow solve took %d iterations: not slow", st.iterations);
  /* u_k = (18/19)^k u_0: with two dofs at u_0 = 1, |g| = sqrt(2) 20 u^19 < 1e-12
   * first at k = 31. */
  cr_expect_eq(st.iterations, 31, "%d", st.iterations);
}

/* p = 1.5: Newton's step maps u to -u, |g| stays where it is: the window
 * rule ends the solve after BS_NEWTON_WINDOW iterations, not at the cap. */
Test(newton, a_solve_that_makes_no_progress_ends_after_the_window) {
  double x[3] = {1, -1, 0.5};
  bs_minimize_stats st;
  newton_1(ev_pow15, 1, 1e-12, 200, x, &st);
  cr_expect_eq(st.reason, BS_MIN_DIVERGED, "%s", st.reason_text);
  cr_expect_eq(st.iterations, BS_NEWTON_WINDOW, "%d iterations: %s", st.iterations, st.reason_text);
  cr_expect(strstr(st.reason_text, "did not halve over 20 iterations") != NULL, "%s", st.reason_text);
}

/* A sudden blow-up of |g| (by BS_NEWTON_GROWTH) ends the solve at once. */
static int ev_cliff(fx *f, const double *u, double *E, double *g, bs_bsr *H) {
  /* E = u^2/2 + 1e9 (u - 1)^4 for u > 1: Newton's first step from 0.5 on the
   * understated Hessian (scaled by 1e-3 below) jumps past the cliff at 1. */
  const int64_t N = 3 * (int64_t)f->n;
  double e = 0;
  for (int64_t k = 0; k < N; ++k) {
    const double d = u[k] > 1 ? u[k] - 1 : 0;
    e += 0.5 * u[k] * u[k] + 1e9 * d * d * d * d;
    if (g) g[k] = u[k] + 4e9 * d * d * d;
    if (H) hadd(H, k, k, 1 + 12e9 * d * d);
  }
  *E = e;
  return 0;
}

Test(newton, a_blow_up_of_the_gradient_ends_the_solve_at_once) {
  double x[3] = {0.5, 0.5, 0.5};
  bs_minimize_stats st;
  newton_1(ev_cliff, 1e-3, 1e-10, 50, x, &st); /* a Hessian 1000x too soft: the step overshoots */
  cr_expect_eq(st.reason, BS_MIN_DIVERGED, "%s", st.reason_text);
  cr_expect_leq(st.iterations, 2, "%d iterations: %s", st.iterations, st.reason_text);
  cr_expect(strstr(st.reason_text, "its smallest") != NULL, "%s", st.reason_text);
}

/* ---- the fixtures' derivatives (so that the tests above test the solver) ---- */

static void fd_check(fx *f, const double *x0, const char *name) {
  const int64_t N = 3 * (int64_t)f->n;
  double *g = calloc((size_t)N, sizeof *g), *gp = calloc((size_t)N, sizeof *gp), *gm = calloc((size_t)N, sizeof *gm);
  double *x = malloc(sizeof(double) * (size_t)N);
  bs_bsr *H = pattern_chain(f->n);
  double E;
  f->eval(f, x0, &E, g, H);
  double err_g[3], err_h[3], hs[3] = {1e-2, 1e-3, 1e-4};
  for (int s = 0; s < 3; ++s) {
    double h = hs[s], eg = 0, eh = 0;
    for (int64_t i = 0; i < N; ++i) {
      memcpy(x, x0, sizeof(double) * (size_t)N);
      x[i] += h;
      double Ep, Em;
      memset(gp, 0, sizeof(double) * (size_t)N);
      f->eval(f, x, &Ep, gp, NULL);
      x[i] -= 2 * h;
      memset(gm, 0, sizeof(double) * (size_t)N);
      f->eval(f, x, &Em, gm, NULL);
      eg = fmax(eg, fabs((Ep - Em) / (2 * h) - g[i]));
      for (int64_t j = 0; j < N; ++j) {
        int32_t sl = bs_bsr_slot(H, (int32_t)(j / 3), (int32_t)(i / 3));
        double hji = sl >= 0 ? H->val[9 * (int64_t)sl + 3 * (j % 3) + (i % 3)] : 0;
        eh = fmax(eh, fabs((gp[j] - gm[j]) / (2 * h) - hji));
      }
    }
    err_g[s] = eg;
    err_h[s] = eh;
  }
  for (int s = 0; s + 1 < 3; ++s) {
    cr_assert(err_g[s + 1] < 0.02 * err_g[s] || err_g[s + 1] < 1e-9, "%s gradient: FD error %g -> %g is not O(h^2)",
              name, err_g[s], err_g[s + 1]);
    cr_assert(err_h[s + 1] < 0.02 * err_h[s] || err_h[s + 1] < 1e-7, "%s Hessian: FD error %g -> %g is not O(h^2)",
              name, err_h[s], err_h[s + 1]);
  }
  cr_assert_lt(err_g[2], 1e-5, "%s gradient", name);
  cr_assert_lt(err_h[2], 1e-4, "%s Hessian", name);
  bs_bsr_destroy(&H);
  free(g), free(gp), free(gm), free(x);
}

Test(fixtures, derivatives_match_finite_differences) {
  fx f;
  double x[12];
  for (int k = 0; k < 12; ++k) x[k] = 0.3 + 0.37 * sin(1.7 * k);
  fx_init(&f, 4, ev_rosenN);
  fd_check(&f, x, "rosenbrock");
  fx_init(&f, 1, ev_rosen2);
  fd_check(&f, x, "rosenbrock2");
  fx_init(&f, 2, ev_well);
  fd_check(&f, x, "double well");
  fx_init(&f, 2, ev_atan);
  fd_check(&f, x, "atan");
  fx_init(&f, 2, ev_exp);
  fd_check(&f, x, "exp");
  double xp[6];
  for (int k = 0; k < 6; ++k) xp[k] = 0.5 + 0.3 * sin(1.3 * k); /* inside the barrier's domain */
  fx_init(&f, 2, ev_barrier);
  fd_check(&f, xp, "barrier");
  fx_init(&f, 1, ev_lb);
  fd_check(&f, x, "lower-bound objective");
  /* The sphere's projected Hessian: the tangential part must match the
   * derivative of the projected gradient along the sphere. */
  fx_init(&f, 1, ev_sphere);
  f.k = 2.0;
  f.R = 1.0;
  f.t[0] = 0.3, f.t[1] = 0.2, f.t[2] = -0.1;
  double p[3] = {0.6, 0.0, 0.8}, gp[3], gm[3], e;
  f.active = 1;
  bs_bsr *H = pattern_chain(1);
  ev_sphere(&f, p, &e, NULL, H);
  double tng[3] = {0.8, 0.0, -0.6}; /* unit tangent at p */
  double errs[2];
  for (int s = 0; s < 2; ++s) {
    double h = s ? 1e-4 : 1e-3, q[3];
    for (int k = 0; k < 3; ++k) q[k] = p[k] + h * tng[k];
    sphere_project(q, &f);
    ev_sphere(&f, q, &e, gp, NULL);
    sphere_project_gradient(q, gp, &f);
    for (int k = 0; k < 3; ++k) q[k] = p[k] - h * tng[k];
    sphere_project(q, &f);
    ev_sphere(&f, q, &e, gm, NULL);
    sphere_project_gradient(q, gm, &f);
    /* tangential component of d(grad E)/ds vs t^T H t */
    double fd = 0, ht = 0;
    for (int k = 0; k < 3; ++k) fd += tng[k] * (gp[k] - gm[k]) / (2 * h);
    for (int a = 0; a < 3; ++a)
      for (int c = 0; c < 3; ++c) ht += tng[a] * H->val[3 * a + c] * tng[c];
    errs[s] = fabs(fd - ht);
  }
  cr_assert(errs[1] < 1e-6 || errs[1] < 0.02 * errs[0], "sphere tangential Hessian: %g -> %g", errs[0], errs[1]);
  bs_bsr_destroy(&H);
}

/* A strictly convex chain: sum_k exp(u_k) - 2 u_k + 5 (u_k - u_k+1)^2, its
 * minimizer u = log 2 (the coupling vanishes there); Newton converges
 * quadratically near it, and CG needs several iterations per solve. */
static int ev_exp_chain(fx *f, const double *u, double *E, double *g, bs_bsr *H) {
  const int64_t N = 3 * (int64_t)f->n;
  const double w = 5.0;
  double e = 0;
  if (g) memset(g, 0, sizeof *g * (size_t)N);
  for (int64_t k = 0; k < N; ++k) {
    e += exp(u[k]) - 2 * u[k];
    if (g) g[k] += exp(u[k]) - 2;
    if (H) hadd(H, k, k, exp(u[k]));
    if (k + 1 < N) {
      const double d = u[k] - u[k + 1];
      e += w * d * d;
      if (g) {
        g[k] += 2 * w * d;
        g[k + 1] -= 2 * w * d;
      }
      if (H) {
        hadd(H, k, k, 2 * w);
        hadd(H, k + 1, k + 1, 2 * w);
        hadd(H, k, k + 1, -2 * w);
        hadd(H, k + 1, k, -2 * w);
      }
    }
  }
  *E = e;
  return 0;
}

/* opts.forcing_ew on that chain (60 dofs, sigma_auto, CG, from a start far
 * from the minimizer): both rules converge to log 2; Eisenstat-Walker's cap
 * tightens the solves once Newton converges fast, and takes fewer Newton
 * iterations than the paper's rule alone. */
Test(minimize, forcing_ew) {
  const int32_t n = 20;
  bs_bsr *P = pattern_chain(n);
  int its[2];
  for (int ew = 0; ew < 2; ++ew) {
    fx f;
    fx_init(&f, n, ev_exp_chain);
    bs_minimize_opts o;
    bs_minimize_opts_default(&o);
    cr_assert_eq(o.forcing_ew, 0);
    o.tol = 1e-7;
    o.sigma_auto = 1;
    o.forcing_ew = ew;
    double x[60];
    for (int k = 0; k < 60; ++k) x[k] = 3.0 + sin(k);
    bs_minimize_stats st;
    min_run(P, &o, &f, x, &st);
    cr_assert_eq(st.reason, BS_MIN_CONVERGED, "ew %d: %s", ew, st.reason_text);
    for (int k = 0; k < 60; ++k) cr_assert_float_eq(x[k], log(2.0), 1e-7, "ew %d: x[%d] = %.17g", ew, k, x[k]);
    its[ew] = st.iterations;
    cr_log_info("forcing_ew %d: %d Newton and %d CG iterations", ew, st.iterations, st.cg_iterations);
  }
  cr_assert_lt(its[1], its[0], "Eisenstat-Walker %d, paper %d Newton iterations", its[1], its[0]);
  bs_bsr_destroy(&P);
}

/* ---- forcing terms ------------------------------------------------------------ */

static double first_rel_tol;
static int n_traced;
static void cb_trace_first_tol(const bs_min_iter *it, void *ctx) {
  if (n_traced++ == 0) first_rel_tol = it->lin_rel_tol;
}

/* forcing_ew 2 (adaptive): a solve that follows one of full Newton steps
 * starts from that solve's last forcing term, not from 1/2, and takes no
 * more iterations to the same tolerance (the scenes' counts are in the
 * README: fig6 5.81 -> 1.98 solves/step); forcing_ew 0 starts every solve at the
 * paper's term. */
static void two_solves(int forcing, double *tol0, int *iters) {
  bs_bsr *P = pattern_chain(4);
  fx f;
  fx_init(&f, 4, ev_exp);
  bs_minimize_opts o;
  bs_minimize_opts_default(&o);
  o.tol = 1e-10;
  o.forcing_ew = forcing;
  o.linear = BS_LIN_CG;
  bs_minimizer *m = NULL;
  bs_error err = {0};
  cr_assert_eq(bs_minimizer_create(P, &o, &m, &err), 0, "%s", err.msg);
  bs_objective obj = make_obj(&f, NULL);
  obj.trace = cb_trace_first_tol;
  for (int s = 0; s < 2; s++) {
    double x[12];
    for (int k = 0; k < 12; k++) x[k] = 1.0 + 0.05 * k;
    bs_minimize_stats st;
    n_traced = 0;
    cr_assert_eq(bs_minimize(m, &obj, x, &st, &err), 0, "%s", err.msg);
    cr_assert_eq(st.reason, BS_MIN_CONVERGED, "%s", st.reason_text);
    tol0[s] = first_rel_tol;
    iters[s] = st.iterations;
  }
  bs_minimizer_destroy(&m);
  bs_bsr_destroy(&P);
}

Test(minimize, adaptive_forcing_starts_from_the_last_full_solve) {
  double paper[2], adaptive[2];
  int ip[2], ia[2];
  two_solves(0, paper, ip);
  two_solves(2, adaptive, ia);
  cr_assert_eq(paper[0], paper[1], "the paper's rule forgets the previous solve: %g %g", paper[0], paper[1]);
  cr_assert_eq(adaptive[0], paper[0], "the first solve of all starts at the paper's term");
  cr_assert_lt(adaptive[1], 0.1 * paper[1], "the second solve starts at %g (paper %g)", adaptive[1], paper[1]);
  cr_assert_leq(ia[1], ip[1], "adaptive: %d iterations, paper: %d", ia[1], ip[1]);
}

/* globalization trust_region (Steihaug's CG, bs_minimize.h "Trust region"):
 * the 12-D Rosenbrock from its usual start converges to the minimizer, with
 * steps on the boundary of a first radius (0.2) shorter than the way there,
 * and with plain CG and PCG alike. */
Test(minimize, trust_region_rosenbrock) {
  for (int pcg = 0; pcg < 2; ++pcg) {
    const int32_t n = 4;
    bs_bsr *P = pattern_chain(n);
    fx f;
    fx_init(&f, n, ev_rosenN);
    bs_minimize_opts o;
    bs_minimize_opts_default(&o);
    o.tol = 1e-8;
    o.linear = pcg ? BS_LIN_PCG : BS_LIN_CG;
    o.globalization = BS_GLOBAL_TRUST_REGION;
    bs_minimizer *m = NULL;
    bs_error err = {0};
    cr_assert_eq(bs_minimizer_create(P, &o, &m, &err), 0, "%s", err.msg);
    bs_objective obj = make_obj(&f, NULL);
    double x[12];
    for (int k = 0; k < 12; ++k) x[k] = k % 2 ? 1.0 : -1.2;
    bs_minimize_stats st;
    cr_assert_eq(bs_minimize(m, &obj, x, &st, &err), 0, "%s", err.msg);
    cr_assert_eq(st.reason, BS_MIN_CONVERGED, "pcg %d: %s", pcg, st.reason_text);
    for (int k = 0; k < 12; ++k) cr_assert_float_eq(x[k], 1.0, 1e-7, "pcg %d: x[%d] = %.12g", pcg, k, x[k]);
    cr_assert_gt(st.tr_boundary, 0, "pcg %d: no step reached the first radius", pcg);
    cr_assert_lt(st.iterations, 100, "pcg %d: %d iterations", pcg, st.iterations);
    cr_assert_eq(f.n_rec, st.iterations, "one trace record per step taken");
    cr_assert_eq(f.bad_point, 0);
    cr_assert_eq(f.bad_decrease, 0);
    bs_minimizer_destroy(&m);
    bs_bsr_destroy(&P);
  }
}

/* From the top of the double well, where the Hessian is negative definite,
 * CG's first curvature is negative: the trust-region step follows it to the
 * boundary (the line search gets CG's right-hand side, a short -grad E). */
Test(minimize, trust_region_negative_curvature) {
  fx f;
  bs_minimize_stats st;
  well_from_the_top(BS_GLOBAL_TRUST_REGION, &f, &st);
  cr_assert(f.has_first);
  cr_assert_eq(f.first.lin_indefinite, 1);
  cr_assert_eq(f.first.lin_boundary, 1);
  /* The first step is -Delta_0 g / ||g|| (CG's first direction is -g): g.d = -Delta_0 ||g||, Delta_0 = 0.1 sqrt(2). */
  double x0[6], g0[6] = {0}, E0;
  for (int k = 0; k < 6; ++k) x0[k] = 0.01 * (1 + 0.1 * k);
  ev_well(&f, x0, &E0, g0, NULL);
  const double want = -0.1 * sqrt(2.0) * sqrt(dot(6, g0, g0));
  cr_assert_float_eq(f.first.dphi0, want, 1e-12 * fabs(want), "g.d = %.15g, expected %.15g", f.first.dphi0, want);
  cr_assert_eq(f.bad_decrease, 0);
}

/* trust_region needs a Krylov solver and a positive radius: the errors name
 * the option. */
Test(minimize, trust_region_options) {
  bs_bsr *P = pattern_chain(2);
  bs_minimize_opts o;
  bs_minimize_opts_default(&o);
  o.globalization = BS_GLOBAL_TRUST_REGION;
  o.linear = BS_LIN_CHOLMOD;
  bs_minimizer *m = NULL;
  bs_error err = {0};
  cr_assert_eq(bs_minimizer_create(P, &o, &m, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "trust_region") && strstr(err.msg, "cholmod"), "%s", err.msg);
  o.linear = BS_LIN_CG;
  o.tr_radius = 0;
  cr_assert_eq(bs_minimizer_create(P, &o, &m, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "tr_radius"), "%s", err.msg);
  bs_globalization g;
  cr_assert_eq(bs_globalization_parse("trust_region", &g, &err), 0);
  cr_assert_eq(g, BS_GLOBAL_TRUST_REGION);
  cr_assert_str_eq(bs_globalization_name(BS_GLOBAL_LINE_SEARCH), "line_search");
  cr_assert_eq(bs_globalization_parse("dogleg", &g, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "dogleg"), "%s", err.msg);
  bs_bsr_destroy(&P);
}

/* ---- the step bound (obj->max_step) -------------------------------------------- */

/* A wall at u = 1 on dof 0 that the objective cannot see from the far side:
 * E = (u - 3)^2 / 2 - mu ln((1 - u)^2) + |v - 1/2|^2 / 2 over the other dofs
 * v, defined on both sides of the wall (a Newton step from u = 0 jumps over
 * it to the minimum near u = 3: "tunnelling"). */
static int ev_wall(fx *f, const double *u, double *E, double *g, bs_bsr *H) {
  const double mu = 0.01, w = 1 - u[0];
  if (w == 0) return 1;
  double e = 0.5 * (u[0] - 3) * (u[0] - 3) - mu * log(w * w);
  if (g) g[0] = (u[0] - 3) + 2 * mu / w;
  if (H) hadd(H, 0, 0, 1 + 2 * mu / (w * w));
  for (int k = 1; k < 3 * f->n; ++k) {
    e += 0.5 * (u[k] - 0.5) * (u[k] - 0.5);
    if (g) g[k] = u[k] - 0.5;
    if (H) hadd(H, k, k, 1);
  }
  *E = e;
  return 0;
}

/* The CCD of the wall: the fraction 0.9 of the way to u = 1 when d moves
 * towards it, no bound otherwise; counts its calls. */
typedef struct wall_ctx {
  fx f;
  int calls, beyond; /* hook calls; trace records past the bound or the wall */
  double fixed;      /* nonzero: return this bound instead                   */
} wall_ctx;

static int wall_step(const double *x, const double *d, double *amax, void *ctx) {
  wall_ctx *w = ctx;
  w->calls++;
  if (w->fixed != 0) *amax = w->fixed;
  else *amax = d[0] > 0 ? 0.9 * (1 - x[0]) / d[0] : INFINITY;
  return 0;
}

static int wall_value(const double *x, double *E, void *ctx) { return cb_value(x, E, &((wall_ctx *)ctx)->f); }
static int wall_gradient(const double *x, double *E, double *g, void *ctx) {
  return cb_gradient(x, E, g, &((wall_ctx *)ctx)->f);
}
static int wall_hessian(const double *x, bs_bsr *H, void *ctx) { return cb_hessian(x, H, &((wall_ctx *)ctx)->f); }
static void wall_trace(const bs_min_iter *it, void *ctx) {
  wall_ctx *w = ctx;
  if (!(it->alpha <= it->alpha_bound) || (w->fixed == 0 && !(it->y[0] < 1))) w->beyond++;
  w->f.n_rec++;
}

static bs_objective wall_obj(wall_ctx *w, int hook) {
  bs_objective o;
  memset(&o, 0, sizeof o);
  o.n = w->f.n;
  o.value = wall_value;
  o.gradient = wall_gradient;
  o.hessian = wall_hessian;
  o.trace = wall_trace;
  o.max_step = hook ? wall_step : NULL;
  o.ctx = w;
  return o;
}

/* Without the bound the first Newton step jumps the wall and the solve ends
 * on its far side; with it every step stays in [0, alpha_max], no iterate
 * crosses, and the solve converges to the minimum near the wall. */
Test(minimize, step_bound_keeps_the_iterates_behind_the_wall) {
  for (int tr = 0; tr < 2; ++tr) {
    bs_bsr *P = pattern_chain(2);
    bs_minimize_opts o;
    bs_minimize_opts_default(&o);
    o.tol = 1e-10;
    o.globalization = tr ? BS_GLOBAL_TRUST_REGION : BS_GLOBAL_LINE_SEARCH;
    for (int hook = 0; hook < 2; ++hook) {
      wall_ctx w;
      memset(&w, 0, sizeof w);
      fx_init(&w.f, 2, ev_wall);
      bs_objective obj = wall_obj(&w, hook);
      double x[6] = {0, 0, 0, 0, 0, 0};
      bs_minimize_stats st;
      min_run_obj(P, &o, &obj, x, &st);
      cr_assert(bs_min_reason_converged(st.reason), "tr %d hook %d: %s", tr, hook, st.reason_text);
      for (int k = 1; k < 6; ++k) cr_assert_float_eq(x[k], 0.5, 1e-9);
      if (!hook) {
        if (!tr) cr_assert_gt(x[0], 1.0, "without the bound the solve tunnels (u = %g)", x[0]);
        cr_assert_eq(st.ccd_limited, 0);
        continue;
      }
      cr_assert_lt(x[0], 1.0, "tr %d: u = %.17g crossed the wall", tr, x[0]);
      /* the minimum behind the wall: (u - 3)(1 - u) + 2 mu = 0 */
      cr_assert_float_eq(x[0], 2 - sqrt(1 + 0.02), 1e-9, "tr %d: u = %.17g", tr, x[0]);
      cr_assert_eq(w.beyond, 0, "tr %d: %d steps beyond the bound or the wall", tr, w.beyond);
      cr_assert_gt(st.ccd_limited, 0, "tr %d", tr);
      cr_assert_gt(w.calls, 0);
    }
    bs_bsr_destroy(&P);
  }
}

/* A bound above 1 stops the extrapolation: the step the undershooting
 * Hessian needs (alpha ~ 20) is cut at alpha_max = 2, taken as the bound
 * itself (E still falls steeply there), and the solve still converges. */
Test(minimize, step_bound_stops_the_extrapolation) {
  const int32_t n = 3;
  const int64_t N = 3 * n;
  bs_bsr *P = pattern_chain(n);
  double *A = quad_matrix(n), b[9], x[9] = {0};
  for (int64_t i = 0; i < N; ++i) b[i] = cos(2.0 * i);
  wall_ctx w;
  memset(&w, 0, sizeof w);
  fx_init(&w.f, n, ev_quad);
  w.f.A = A;
  w.f.b = b;
  w.f.hess_scale = 20;
  w.fixed = 2.0;
  bs_objective obj = wall_obj(&w, 1);
  bs_minimize_opts o;
  bs_minimize_opts_default(&o);
  o.tol = 1e-6;
  o.max_iter = 2000;
  bs_minimize_stats st;
  min_run_obj(P, &o, &obj, x, &st);
  cr_assert_eq(st.reason, BS_MIN_CONVERGED, "%s", st.reason_text);
  cr_assert_leq(st.alpha_max, 2.0, "alpha_max = %g", st.alpha_max);
  cr_assert_eq(st.alpha_max, 2.0, "the bound itself was taken");
  cr_assert_gt(st.ccd_limited, 0);
  cr_assert_eq(w.beyond, 0);
  cr_assert_str_eq(bs_lsearch_status_name(BS_LSEARCH_BOUND), "bound");
  bs_bsr_destroy(&P);
  free(A);
}

/* A bound of 0 (the CCD certifies no motion) takes no step and says why. */
Test(minimize, step_bound_zero_stops_with_a_reason) {
  bs_bsr *P = pattern_chain(1);
  wall_ctx w;
  memset(&w, 0, sizeof w);
  fx_init(&w.f, 1, ev_wall);
  w.fixed = -1; /* negative: counted as 0 */
  bs_objective obj = wall_obj(&w, 1);
  double x[3] = {0, 0, 0};
  bs_minimize_stats st;
  min_run_obj(P, NULL, &obj, x, &st);
  cr_assert_eq(st.reason, BS_MIN_LINE_SEARCH, "%s", st.reason_text);
  cr_assert(strstr(st.reason_text, "max_step"), "%s", st.reason_text);
  cr_assert_eq(x[0], 0.0);
  cr_assert_eq(st.ls_evaluations, 0);
  bs_bsr_destroy(&P);
}

/* A hook that never bounds (+Inf) changes nothing, bit for bit: Rosenbrock
 * (line searches that extrapolate and zoom) with and without it. */
static int no_bound(const double *x, const double *d, double *amax, void *ctx) {
  (void)x, (void)d, (void)ctx;
  *amax = INFINITY;
  return 0;
}

Test(minimize, step_bound_without_effect_is_bit_for_bit) {
  const int32_t n = 4;
  bs_bsr *P = pattern_chain(n);
  double xs[2][12];
  bs_minimize_stats st[2];
  for (int hook = 0; hook < 2; ++hook) {
    fx f;
    fx_init(&f, n, ev_rosenN);
    bs_objective obj = make_obj(&f, NULL);
    obj.max_step = hook ? no_bound : NULL;
    for (int k = 0; k < 12; ++k) xs[hook][k] = k % 2 ? 1.0 : -1.2;
    bs_minimize_opts o;
    bs_minimize_opts_default(&o);
    o.tol = 1e-10;
    min_run_obj(P, &o, &obj, xs[hook], &st[hook]);
  }
  cr_assert_eq(memcmp(xs[0], xs[1], sizeof xs[0]), 0);
  cr_assert_eq(st[0].iterations, st[1].iterations);
  cr_assert_eq(st[0].ls_evaluations, st[1].ls_evaluations);
  cr_assert_eq(st[0].E, st[1].E);
  cr_assert_eq(st[1].ccd_limited, 0);
  bs_bsr_destroy(&P);
}
