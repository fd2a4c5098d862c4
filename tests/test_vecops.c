/* test_vecops.c — the minimizer through a vector-operations interface
 * (bs_vecops.h): with operations that do what the minimizer does on its own
 * (local dots, the flag itself, the CG of bs_linsolve.h as the solve), a
 * solve gives the same iterates, counts and answer; a missing callback is
 * refused; the solve callback's error comes back. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdlib.h>
#include <stdio.h>
#include <string.h>

#include "bs_minimize.h"
#include "bs_vecops.h"

#define N 12 /* vertices of the chain */

/* A chain of springs x_{i+1} - x_i with quartic stiffening, pulled at the
 * last vertex: E = sum_i (|d_i|^2 / 2 + |d_i|^4 / 4) - f.x_{N-1}. */
static int energy(const double *x, double *E, double *g) {
  const double f[3] = {1.0, 0.5, -0.25};
  double e = 0;
  if (g) memset(g, 0, sizeof(double) * 3 * N);
  for (int i = 0; i + 1 < N; i++) {
    double d[3], d2 = 0;
    for (int k = 0; k < 3; k++) d[k] = x[3 * (i + 1) + k] - x[3 * i + k], d2 += d[k] * d[k];
    e += d2 / 2 + d2 * d2 / 4;
    for (int k = 0; g && k < 3; k++) {
      double gk = d[k] * (1 + d2);
      g[3 * (i + 1) + k] += gk;
      g[3 * i + k] -= gk;
    }
  }
  for (int k = 0; k < 3; k++) {
    e -= f[k] * x[3 * (N - 1) + k];
    if (g) g[3 * (N - 1) + k] -= f[k];
  }
  *E = e;
  return 0;
}

static int value(const double *x, double *E, void *ctx) { return energy(x, E, NULL); }
static int gradient(const double *x, double *E, double *g, void *ctx) { return energy(x, E, g); }

typedef struct ctx {
  bs_bsr *H;         /* the Hessian the last hessian callback filled */
  bs_linsolve *cg;
  int dots, solves, fail;
} ctx;

static int hessian(const double *x, bs_bsr *H, void *c) {
  ((ctx *)c)->H = H;
  for (int i = 0; i + 1 < N; i++) {
    double d[3], d2 = 0, B[9];
    for (int k = 0; k < 3; k++) d[k] = x[3 * (i + 1) + k] - x[3 * i + k], d2 += d[k] * d[k];
    for (int a = 0; a < 3; a++)
      for (int b = 0; b < 3; b++) B[3 * a + b] = (a == b) * (1 + d2) + 2 * d[a] * d[b];
    double nB[9];
    for (int k = 0; k < 9; k++) nB[k] = -B[k];
    bs_bsr_add_block(H, i, i, B), bs_bsr_add_block(H, i + 1, i + 1, B);
    bs_bsr_add_block(H, i, i + 1, nB), bs_bsr_add_block(H, i + 1, i, nB);
  }
  return 0;
}

static double vo_dot(int64_t n, const double *a, const double *b, void *c) {
  ((ctx *)c)->dots++;
  double s = 0;
  for (int64_t i = 0; i < n; i++) s += a[i] * b[i];
  return s;
}
static int vo_any(int flag, void *c) { return flag != 0; }
static void vo_sum(double *v, int n, void *c) {}
static int vo_solve(const uint8_t *mask, const double *r, double rel, int max_it, double kappa, double *d,
                    bs_lin_stats *ls, bs_error *err, void *c) {
  ctx *k = c;
  k->solves++;
  if (k->fail) return bs_error_set(err, BS_ENUMERIC, "the solve failed on purpose");
  int rc = bs_linsolve_set_downhill(k->cg, kappa, err);
  return rc ? rc : bs_linsolve_solve(k->cg, k->H, mask, r, rel, max_it, d, ls, err);
}

static bs_bsr *chain(void) {
  int32_t ptr[N + 1], adj[2 * N], m = 0;
  for (int i = 0; i < N; i++) {
    if (i > 0) adj[m++] = i - 1;
    if (i < N - 1) adj[m++] = i + 1;
    ptr[i + 1] = m;
  }
  ptr[0] = 0;
  bs_bsr *A = NULL;
  bs_error err = {0};
  cr_assert_eq(bs_bsr_create(N, ptr, adj, &A, &err), 0, "%s", err.msg);
  return A;
}

/* One solve from the rest chain with vertex 0 fixed, with or without ops. */
static void solve(int with_ops, ctx *c, double *x, bs_minimize_stats *st, int *status, bs_error *err) {
  bs_bsr *P = chain();
  bs_minimize_opts o;
  bs_minimize_opts_default(&o);
  o.tol = 1e-6;
  bs_minimizer *m = NULL;
  cr_assert_eq(bs_minimizer_create(P, &o, &m, err), 0, "%s", err->msg);
  cr_assert_eq(bs_linsolve_create(P, BS_LIN_CG, &c->cg, err), 0, "%s", err->msg);
  bs_vecops ops = {vo_dot, vo_any, vo_sum, vo_solve, c};
  if (with_ops) cr_assert_eq(bs_minimizer_set_vecops(m, &ops, err), 0, "%s", err->msg);
  uint8_t mask[N];
  memset(mask, 1, sizeof mask);
  mask[0] = 0;
  for (int i = 0; i < N; i++) x[3 * i] = i, x[3 * i + 1] = x[3 * i + 2] = 0;
  bs_objective obj = {.n = N, .mask = mask, .value = value, .gradient = gradient, .hessian = hessian, .ctx = c};
  *status = bs_minimize(m, &obj, x, st, err);
  static char why[2][512]; /* reason_text lives in the minimizer: keep a copy */
  snprintf(why[with_ops], sizeof why[with_ops], "%s", st->reason_text ? st->reason_text : "");
  st->reason_text = why[with_ops];
  bs_linsolve_destroy(&c->cg);
  bs_minimizer_destroy(&m);
  bs_bsr_destroy(&P);
}

Test(vecops, local_operations_give_the_same_solve) {
  ctx a = {0}, b = {0};
  double xa[3 * N], xb[3 * N];
  bs_minimize_stats sa, sb;
  bs_error err = {0};
  int ra, rb;
  solve(0, &a, xa, &sa, &ra, &err);
  solve(1, &b, xb, &sb, &rb, &err);
  cr_assert_eq(ra, 0, "%s", err.msg);
  cr_assert_eq(rb, 0, "%s", err.msg);
  cr_assert_eq(sb.reason, BS_MIN_CONVERGED, "%s", sb.reason_text);
  cr_assert_eq(sa.iterations, sb.iterations, "%d vs %d iterations", sa.iterations, sb.iterations);
  cr_assert_eq(sa.cg_iterations, sb.cg_iterations, "%d vs %d CG iterations", sa.cg_iterations, sb.cg_iterations);
  cr_assert_eq(sa.ls_evaluations, sb.ls_evaluations);
  cr_assert(b.solves == sb.iterations && b.dots > sb.iterations, "%d solves, %d dots", b.solves, b.dots);
  cr_assert_eq(a.solves, 0, "the plain minimizer called the hook");
  for (int i = 0; i < 3 * N; i++) cr_assert(fabs(xa[i] - xb[i]) <= 1e-12 * (1 + fabs(xa[i])), "x[%d]", i);
  cr_assert(xb[0] == 0 && xb[1] == 0 && xb[2] == 0, "the fixed vertex moved");
}

Test(vecops, missing_callback_and_solve_error) {
  bs_bsr *P = chain();
  bs_minimizer *m = NULL;
  bs_error err = {0};
  cr_assert_eq(bs_minimizer_create(P, NULL, &m, &err), 0, "%s", err.msg);
  bs_vecops ops = {vo_dot, vo_any, vo_sum, NULL, NULL};
  cr_assert_eq(bs_minimizer_set_vecops(m, &ops, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "solve"), "%s", err.msg);
  cr_assert_eq(bs_minimizer_set_vecops(m, NULL, &err), 0, "clearing");
  bs_minimizer_destroy(&m);
  bs_bsr_destroy(&P);
  ctx c = {.fail = 1};
  double x[3 * N];
  bs_minimize_stats st;
  int rc;
  solve(1, &c, x, &st, &rc, &err);
  cr_assert(rc < 0 || st.reason == BS_MIN_NONFINITE, "status %d, reason %s", rc, st.reason_text);
  cr_assert(strstr(err.msg, "on purpose") || (st.reason_text && strstr(st.reason_text, "on purpose")), "%s", err.msg);
}
