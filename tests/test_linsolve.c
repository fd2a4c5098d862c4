/* test_linsolve.c — CG, PCG, MINRES and CHOLMOD against a dense solve on
 * random symmetric block matrices; masks; negative curvature exits; error
 * paths; preconditioning on a badly scaled matrix. */
#include <criterion/criterion.h>
#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bs_linsolve.h"

static uint64_t rng_state = 0x9E3779B97F4A7C15ull;
static double urand(void) { /* xorshift64, uniform in [-1, 1) */
  rng_state ^= rng_state << 13;
  rng_state ^= rng_state >> 7;
  rng_state ^= rng_state << 17;
  return (double)(rng_state >> 11) / 9007199254740992.0 * 2.0 - 1.0;
}

/* 7-point grid graph on g^3 vertices. */
static bs_bsr *grid_matrix(int g) {
  const int32_t n = g * g * g;
  int32_t *ptr = calloc((size_t)n + 1, sizeof *ptr), *adj = malloc(sizeof *adj * 6 * (size_t)n);
  int m = 0;
  for (int k = 0; k < g; ++k)
    for (int j = 0; j < g; ++j)
      for (int i = 0; i < g; ++i) {
        const int v = i + g * (j + g * k);
        if (i > 0) adj[m++] = v - 1;
        if (i < g - 1) adj[m++] = v + 1;
        if (j > 0) adj[m++] = v - g;
        if (j < g - 1) adj[m++] = v + g;
        if (k > 0) adj[m++] = v - g * g;
        if (k < g - 1) adj[m++] = v + g * g;
        ptr[v + 1] = m;
      }
  bs_bsr *A = NULL;
  bs_error err = {0};
  cr_assert_eq(bs_bsr_create(n, ptr, adj, &A, &err), 0, "%s", err.msg);
  free(ptr);
  free(adj);
  return A;
}

/* Random symmetric values: off-diagonal blocks B_ij random in [-1,1] with
 * A_ji = B_ij^T; diagonal blocks (d_i + shift) I + a small symmetric random
 * part, d_i the absolute off-diagonal row sum. shift > 0: SPD (Gershgorin);
 * shift < 0: indefinite. */
static void fill_spd(bs_bsr *A, double shift) {
  for (int32_t i = 0; i < A->n; ++i)
    for (int32_t s = A->row_ptr[i]; s < A->row_ptr[i + 1]; ++s) {
      const int32_t j = A->col[s];
      if (j <= i) continue;
      const int32_t t = bs_bsr_slot(A, j, i);
      for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b) {
          const double v = urand();
          A->val[9 * s + 3 * a + b] = v;
          A->val[9 * t + 3 * b + a] = v;
        }
    }
  for (int32_t i = 0; i < A->n; ++i) {
    double rs[3] = {0, 0, 0};
    for (int32_t s = A->row_ptr[i]; s < A->row_ptr[i + 1]; ++s)
      if (A->col[s] != i)
        for (int a = 0; a < 3; ++a)
          for (int b = 0; b < 3; ++b) rs[a] += fabs(A->val[9 * s + 3 * a + b]);
    double *D = A->val + 9 * A->diag[i];
    const double e01 = 0.1 * urand(), e02 = 0.1 * urand(), e12 = 0.1 * urand();
    D[1] = D[3] = e01;
    D[2] = D[6] = e02;
    D[5] = D[7] = e12;
    for (int a = 0; a < 3; ++a) D[4 * a] = rs[a] + 0.2 + shift;
  }
}

/* Dense solve of the free system by Gaussian elimination with partial
 * pivoting; x gets 0 on constrained dofs. */
static void dense_solve(const bs_bsr *A, const uint8_t *mask, const double *b, double *x) {
  const int64_t N = 3 * (int64_t)A->n;
  int64_t *idx = malloc(sizeof *idx * N), *pos = malloc(sizeof *pos * N);
  int64_t m = 0;
  for (int64_t k = 0; k < N; ++k) {
    pos[k] = (!mask || mask[k / 3]) ? m : -1;
    if (pos[k] >= 0) idx[m++] = k;
  }
  double *D = calloc((size_t)(m * (m + 1)), sizeof *D); /* augmented m x (m+1) */
  for (int32_t i = 0; i < A->n; ++i)
    for (int32_t s = A->row_ptr[i]; s < A->row_ptr[i + 1]; ++s)
      for (int a = 0; a < 3; ++a)
        for (int c = 0; c < 3; ++c) {
          const int64_t r = pos[3 * i + a], q = pos[3 * (int64_t)A->col[s] + c];
          if (r >= 0 && q >= 0) D[r * (m + 1) + q] = A->val[9 * s + 3 * a + c];
        }
  for (int64_t r = 0; r < m; ++r) D[r * (m + 1) + m] = b[idx[r]];
  for (int64_t c = 0; c < m; ++c) {
    int64_t piv = c;
    for (int64_t r = c + 1; r < m; ++r)
      if (fabs(D[r * (m + 1) + c]) > fabs(D[piv * (m + 1) + c])) piv = r;
    if (piv != c)
      for (int64_t q = 0; q <= m; ++q) {
        double t = D[c * (m + 1) + q];
        D[c * (m + 1) + q] = D[piv * (m + 1) + q];
        D[piv * (m + 1) + q] = t;
      }
    for (int64_t r = c + 1; r < m; ++r) {
      const double f = D[r * (m + 1) + c] / D[c * (m + 1) + c];
      if (f != 0.0)
        for (int64_t q = c; q <= m; ++q) D[r * (m + 1) + q] -= f * D[c * (m + 1) + q];
    }
  }
  for (int64_t k = 0; k < N; ++k) x[k] = 0.0;
  for (int64_t r = m - 1; r >= 0; --r) {
    double s = D[r * (m + 1) + m];
    for (int64_t q = r + 1; q < m; ++q) s -= D[r * (m + 1) + q] * x[idx[q]];
    x[idx[r]] = s / D[r * (m + 1) + r];
  }
  free(D);
  free(idx);
  free(pos);
}

static double rel_diff(int64_t N, const double *x, const double *y) {
  double d = 0, s = 0;
  for (int64_t k = 0; k < N; ++k) {
    d += (x[k] - y[k]) * (x[k] - y[k]);
    s += y[k] * y[k];
  }
  return sqrt(d / s);
}

static double *random_vec(int64_t N) {
  double *v = malloc(sizeof *v * N);
  for (int64_t k = 0; k < N; ++k) v[k] = urand();
  return v;
}

static const bs_lin_kind all_kinds[] = {BS_LIN_CG, BS_LIN_PCG, BS_LIN_MINRES, BS_LIN_CHOLMOD};

Test(linsolve, kind_names) {
  bs_error err = {0};
  for (int k = 0; k < 4; ++k) {
    bs_lin_kind out = BS_LIN_CG;
    cr_assert_eq(bs_lin_kind_parse(bs_lin_kind_name(all_kinds[k]), &out, &err), 0, "%s", err.msg);
    cr_assert_eq(out, all_kinds[k]);
  }
  bs_lin_kind out;
  cr_assert_eq(bs_lin_kind_parse("gmres", &out, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "\"gmres\""), "%s", err.msg);
  cr_assert_str_eq(bs_lin_kind_name((bs_lin_kind)42), "unknown");
}

Test(linsolve, spd_all_solvers_agree_with_dense) {
  bs_bsr *A = grid_matrix(5);
  fill_spd(A, 0.5);
  bs_error err = {0};
  cr_assert_eq(bs_bsr_check(A, 0.0, &err), 0, "%s", err.msg);
  const int64_t N = 3 * (int64_t)A->n;
  double *b = random_vec(N), *xd = malloc(sizeof *xd * N), *x = malloc(sizeof *x * N);
  dense_solve(A, NULL, b, xd);
  for (int k = 0; k < 4; ++k) {
    bs_linsolve *ls = NULL;
    cr_assert_eq(bs_linsolve_create(A, all_kinds[k], &ls, &err), 0, "%s", err.msg);
    bs_lin_stats st;
    for (int rep = 0; rep < 2; ++rep) { /* the second call reuses the workspace */
      cr_assert_eq(bs_linsolve_solve(ls, A, NULL, b, 1e-10, 1000, x, &st, &err), 0, "%s",
                   err.msg);
      const char *name = bs_lin_kind_name(all_kinds[k]);
      cr_assert_eq(st.converged, 1, "%s", name);
      cr_assert_eq(st.indefinite, 0, "%s", name);
      cr_assert_eq(st.not_pd, 0, "%s", name);
      cr_assert_leq(st.rel_residual, 1e-10, "%s: residual %g", name, st.rel_residual);
      cr_assert_lt(rel_diff(N, x, xd), 1e-8, "%s: error %g", name, rel_diff(N, x, xd));
      if (all_kinds[k] == BS_LIN_CHOLMOD)
        cr_assert_eq(st.iterations, 0);
      else
        cr_assert_gt(st.iterations, 1, "%s", name);
    }
    /* New values on the same pattern: 2A x = b gives x / 2. */
    for (int64_t e = 0; e < 9 * A->nnzb; ++e) A->val[e] *= 2;
    cr_assert_eq(bs_linsolve_solve(ls, A, NULL, b, 1e-10, 1000, x, &st, &err), 0, "%s", err.msg);
    for (int64_t e = 0; e < N; ++e) x[e] *= 2;
    cr_assert_lt(rel_diff(N, x, xd), 1e-8, "%s after new values", bs_lin_kind_name(all_kinds[k]));
    for (int64_t e = 0; e < 9 * A->nnzb; ++e) A->val[e] /= 2;
    /* b = 0 gives x = 0 at once. */
    double *zero = calloc((size_t)N, sizeof *zero);
    cr_assert_eq(bs_linsolve_solve(ls, A, NULL, zero, 1e-10, 1000, x, &st, &err), 0);
    cr_assert_eq(st.converged, 1);
    for (int64_t e = 0; e < N; ++e) cr_assert_eq(x[e], 0.0);
    free(zero);
    bs_linsolve_destroy(&ls);
    cr_assert_null(ls);
    bs_linsolve_destroy(&ls);
  }
  free(b);
  free(xd);
  free(x);
  bs_bsr_destroy(&A);
}

Test(linsolve, masked_solve) {
  bs_bsr *A = grid_matrix(5);
  fill_spd(A, 0.5);
  const int64_t N = 3 * (int64_t)A->n;
  uint8_t *mask = malloc((size_t)A->n), *mask2 = malloc((size_t)A->n);
  for (int32_t i = 0; i < A->n; ++i) {
    mask[i] = (uint8_t)(i % 4 != 0);
    mask2[i] = (uint8_t)(i % 5 != 2);
  }
  double *b = random_vec(N), *xd = malloc(sizeof *xd * N), *x = malloc(sizeof *x * N);
  double *xd2 = malloc(sizeof *xd2 * N);
  dense_solve(A, mask, b, xd);
  dense_solve(A, mask2, b, xd2);
  bs_error err = {0};
  for (int k = 0; k < 4; ++k) {
    const char *name = bs_lin_kind_name(all_kinds[k]);
    bs_linsolve *ls = NULL;
    cr_assert_eq(bs_linsolve_create(A, all_kinds[k], &ls, &err), 0, "%s", err.msg);
    /* Two masks in turn (CHOLMOD redoes its analysis when the mask changes). */
    for (int rep = 0; rep < 3; ++rep) {
      const uint8_t *mk = rep == 1 ? mask2 : mask;
      const double *want = rep == 1 ? xd2 : xd;
      for (int64_t e = 0; e < N; ++e) x[e] = 123.0;
      bs_lin_stats st;
      cr_assert_eq(bs_linsolve_solve(ls, A, mk, b, 1e-10, 1000, x, &st, &err), 0, "%s", err.msg);
      cr_assert_eq(st.converged, 1, "%s", name);
      for (int64_t e = 0; e < N; ++e)
        if (!mk[e / 3]) cr_assert_eq(x[e], 0.0, "%s: constrained dof %lld", name, (long long)e);
      cr_assert_lt(rel_diff(N, x, want), 1e-8, "%s: error %g", name, rel_diff(N, x, want));
    }
    bs_linsolve_destroy(&ls);
  }
  free(b);
  free(x);
  free(xd);
  free(xd2);
  free(mask);
  free(mask2);
  bs_bsr_destroy(&A);
}

/* Negative definite A = -(SPD): b^T A b < 0, so CG stops on the first
 * iteration and returns b itself (masked). */
Test(linsolve, cg_first_iteration_returns_rhs) {
  bs_bsr *A = grid_matrix(4);
  fill_spd(A, 0.5);
  for (int64_t e = 0; e < 9 * A->nnzb; ++e) A->val[e] = -A->val[e];
  const int64_t N = 3 * (int64_t)A->n;
  uint8_t *mask = malloc((size_t)A->n);
  for (int32_t i = 0; i < A->n; ++i) mask[i] = (uint8_t)(i % 7 != 3);
  double *b = random_vec(N), *x = malloc(sizeof *x * N);
  bs_error err = {0};
  for (int k = 0; k < 2; ++k) {
    bs_linsolve *ls = NULL;
    cr_assert_eq(bs_linsolve_create(A, all_kinds[k], &ls, &err), 0);
    bs_lin_stats st;
    cr_assert_eq(bs_linsolve_solve(ls, A, NULL, b, 1e-8, 100, x, &st, &err), 0, "%s", err.msg);
    cr_assert_eq(st.indefinite, 1);
    cr_assert_eq(st.converged, 0);
    cr_assert_eq(st.iterations, 0);
    cr_assert_eq(memcmp(x, b, sizeof *x * N), 0, "%s must return b", bs_lin_kind_name(all_kinds[k]));
    cr_assert_gt(st.rel_residual, 1.0);
    cr_assert_eq(bs_linsolve_solve(ls, A, mask, b, 1e-8, 100, x, &st, &err), 0, "%s", err.msg);
    cr_assert_eq(st.indefinite, 1);
    for (int64_t e = 0; e < N; ++e) cr_assert_eq(x[e], mask[e / 3] ? b[e] : 0.0);
    bs_linsolve_destroy(&ls);
  }
  free(b);
  free(x);
  free(mask);
  bs_bsr_destroy(&A);
}

/* Indefinite A (a shifted SPD matrix with eigenvalues of both signs): CG and
 * PCG exit with indefinite = 1 after some iterations, and x is a descent
 * direction of 1/2 x^T A x - b^T x at 0, i.e. b . x > 0. MINRES solves it;
 * CHOLMOD reports not_pd and leaves x untouched. */
Test(linsolve, indefinite) {
  bs_bsr *A = grid_matrix(5);
  fill_spd(A, 0.0);
  /* Shift down by about a third of the spread of the diagonal. */
  double dmax = 0;
  for (int32_t i = 0; i < A->n; ++i) dmax = fmax(dmax, A->val[9 * A->diag[i]]);
  for (int32_t i = 0; i < A->n; ++i)
    for (int a = 0; a < 3; ++a) A->val[9 * A->diag[i] + 4 * a] -= 0.4 * dmax;
  const int64_t N = 3 * (int64_t)A->n;
  double *b = random_vec(N), *x = malloc(sizeof *x * N), *xd = malloc(sizeof *xd * N);
  bs_error err = {0};
  for (int k = 0; k < 2; ++k) {
    bs_linsolve *ls = NULL;
    cr_assert_eq(bs_linsolve_create(A, all_kinds[k], &ls, &err), 0);
    bs_lin_stats st;
    cr_assert_eq(bs_linsolve_solve(ls, A, NULL, b, 1e-10, 1000, x, &st, &err), 0, "%s", err.msg);
    const char *name = bs_lin_kind_name(all_kinds[k]);
    cr_assert_eq(st.indefinite, 1, "%s", name);
    cr_assert_eq(st.converged, 0, "%s", name);
    cr_assert_geq(st.iterations, 1, "%s: expected an exit after some iterations", name);
    double bx = 0;
    for (int64_t e = 0; e < N; ++e) bx += b[e] * x[e];
    cr_assert_gt(bx, 0.0, "%s: b . x = %g is not a descent direction", name, bx);
    bs_linsolve_destroy(&ls);
  }
  dense_solve(A, NULL, b, xd);
  bs_linsolve *ls = NULL;
  cr_assert_eq(bs_linsolve_create(A, BS_LIN_MINRES, &ls, &err), 0);
  bs_lin_stats st;
  cr_assert_eq(bs_linsolve_solve(ls, A, NULL, b, 1e-10, 5000, x, &st, &err), 0, "%s", err.msg);
  cr_assert_eq(st.converged, 1, "minres residual %g after %d", st.rel_residual, st.iterations);
  cr_assert_leq(st.rel_residual, 1e-10);
  cr_assert_lt(rel_diff(N, x, xd), 1e-6, "minres error %g", rel_diff(N, x, xd));
  bs_linsolve_destroy(&ls);
  cr_assert_eq(bs_linsolve_create(A, BS_LIN_CHOLMOD, &ls, &err), 0);
  for (int64_t e = 0; e < N; ++e) x[e] = 7.0;
  cr_assert_eq(bs_linsolve_solve(ls, A, NULL, b, 1e-10, 0, x, &st, &err), 0, "%s", err.msg);
  cr_assert_eq(st.not_pd, 1);
  cr_assert_eq(st.converged, 0);
  for (int64_t e = 0; e < N; ++e) cr_assert_eq(x[e], 7.0, "x touched at %lld", (long long)e);
  /* The same workspace then factors an SPD matrix on the same pattern. */
  fill_spd(A, 0.5);
  dense_solve(A, NULL, b, xd);
  cr_assert_eq(bs_linsolve_solve(ls, A, NULL, b, 1e-10, 0, x, &st, &err), 0, "%s", err.msg);
  cr_assert_eq(st.not_pd, 0);
  cr_assert_lt(rel_diff(N, x, xd), 1e-8);
  bs_linsolve_destroy(&ls);
  free(b);
  free(x);
  free(xd);
  bs_bsr_destroy(&A);
}

Test(linsolve, nonfinite_input_is_an_error) {
  bs_bsr *A = grid_matrix(3);
  fill_spd(A, 0.5);
  const int64_t N = 3 * (int64_t)A->n;
  double *b = random_vec(N), *x = malloc(sizeof *x * N);
  uint8_t *mask = malloc((size_t)A->n);
  for (int32_t i = 0; i < A->n; ++i) mask[i] = (uint8_t)(i != 4);
  bs_error err = {0};
  for (int k = 0; k < 4; ++k) {
    const char *name = bs_lin_kind_name(all_kinds[k]);
    bs_linsolve *ls = NULL;
    cr_assert_eq(bs_linsolve_create(A, all_kinds[k], &ls, &err), 0);
    bs_lin_stats st;
    b[5] = NAN; /* vertex 1, component 2 */
    cr_assert_eq(bs_linsolve_solve(ls, A, NULL, b, 1e-8, 100, x, &st, &err), BS_ENUMERIC, "%s",
                 name);
    cr_assert(strstr(err.msg, "entry 5 (vertex 1, component 2)"), "%s: %s", name, err.msg);
    b[5] = 0.5;
    /* A NaN in a constrained entry of b is ignored. */
    b[13] = NAN; /* vertex 4 */
    cr_assert_eq(bs_linsolve_solve(ls, A, mask, b, 1e-8, 100, x, &st, &err), 0, "%s: %s", name,
                 err.msg);
    b[13] = 0.5;
    /* A NaN in a free block of A. */
    const int32_t s = bs_bsr_slot(A, 2, 5);
    cr_assert_geq(s, 0);
    const double keep = A->val[9 * s + 7];
    A->val[9 * s + 7] = NAN;
    cr_assert_eq(bs_linsolve_solve(ls, A, NULL, b, 1e-8, 100, x, &st, &err), BS_ENUMERIC, "%s",
                 name);
    cr_assert(strstr(err.msg, "block (2,5) entry (2,1)"), "%s: %s", name, err.msg);
    A->val[9 * s + 7] = keep;
    bs_linsolve_destroy(&ls);
  }
  /* A matrix of another pattern, a negative tolerance. */
  bs_bsr *B = grid_matrix(2);
  bs_linsolve *ls = NULL;
  cr_assert_eq(bs_linsolve_create(A, BS_LIN_CG, &ls, &err), 0);
  cr_assert_eq(bs_linsolve_solve(ls, B, NULL, b, 1e-8, 100, x, NULL, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "n = 8"), "%s", err.msg);
  cr_assert_eq(bs_linsolve_solve(ls, A, NULL, b, -1.0, 100, x, NULL, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "rel_tol"), "%s", err.msg);
  bs_linsolve_destroy(&ls);
  bs_bsr_destroy(&B);
  free(b);
  free(x);
  free(mask);
  bs_bsr_destroy(&A);
}

/* SPD matrix with vertex scales spanning 10^-1.5 .. 10^1.5 (A = S A0 S): block
 * Jacobi removes the scaling, so PCG needs no more (here far fewer) iterations
 * than CG; both converge. */
Test(linsolve, pcg_beats_cg_on_badly_scaled_matrix) {
  bs_bsr *A = grid_matrix(6);
  fill_spd(A, 0.5);
  double *scale = malloc(sizeof *scale * A->n);
  for (int32_t i = 0; i < A->n; ++i) scale[i] = pow(10.0, 1.5 * urand());
  for (int32_t i = 0; i < A->n; ++i)
    for (int32_t s = A->row_ptr[i]; s < A->row_ptr[i + 1]; ++s)
      for (int e = 0; e < 9; ++e) A->val[9 * s + e] *= scale[i] * scale[A->col[s]];
  const int64_t N = 3 * (int64_t)A->n;
  double *b = random_vec(N), *x = malloc(sizeof *x * N), *xd = malloc(sizeof *xd * N);
  dense_solve(A, NULL, b, xd);
  bs_error err = {0};
  int its[2];
  for (int k = 0; k < 2; ++k) {
    bs_linsolve *ls = NULL;
    cr_assert_eq(bs_linsolve_create(A, all_kinds[k], &ls, &err), 0);
    bs_lin_stats st;
    cr_assert_eq(bs_linsolve_solve(ls, A, NULL, b, 1e-8, 100000, x, &st, &err), 0, "%s", err.msg);
    cr_assert_eq(st.converged, 1, "%s", bs_lin_kind_name(all_kinds[k]));
    cr_assert_eq(st.indefinite, 0);
    its[k] = st.iterations;
    bs_linsolve_destroy(&ls);
  }
  cr_assert_leq(its[1], its[0], "pcg %d iterations, cg %d", its[1], its[0]);
  cr_assert_lt(2 * its[1], its[0], "pcg %d iterations, cg %d: preconditioner ineffective", its[1],
               its[0]);
  free(scale);
  free(b);
  free(x);
  free(xd);
  bs_bsr_destroy(&A);
}

/* Results are bitwise the same with 1 and 4 threads, masked or not (an 18^3
 * grid: more than 4096 rows and 16384 dofs, so the parallel branches run). */
Test(linsolve, thread_count_independence) {
  bs_bsr *A = grid_matrix(18);
  fill_spd(A, 0.5);
  const int64_t N = 3 * (int64_t)A->n;
  double *b = random_vec(N), *x1 = malloc(sizeof *x1 * N), *x2 = malloc(sizeof *x2 * N);
  uint8_t *mask = malloc((size_t)A->n);
  for (int32_t i = 0; i < A->n; ++i) mask[i] = i % 7 != 0;
  bs_error err = {0};
  const int nt = omp_get_max_threads();
  const bs_lin_kind kinds[] = {BS_LIN_CG, BS_LIN_PCG, BS_LIN_MINRES, BS_LIN_CHOLMOD, BS_LIN_AMG};
  for (int k = 0; k < 10; ++k) {
    const uint8_t *mk = k % 2 ? mask : NULL;
    bs_linsolve *ls = NULL;
    cr_assert_eq(bs_linsolve_create(A, kinds[k / 2], &ls, &err), 0);
    bs_lin_stats s1, s2;
    omp_set_num_threads(1);
    cr_assert_eq(bs_linsolve_solve(ls, A, mk, b, 1e-10, 1000, x1, &s1, &err), 0, "%s", err.msg);
    omp_set_num_threads(4);
    cr_assert_eq(bs_linsolve_solve(ls, A, mk, b, 1e-10, 1000, x2, &s2, &err), 0, "%s", err.msg);
    omp_set_num_threads(nt);
    cr_assert(s1.iterations > 0 || kinds[k / 2] == BS_LIN_CHOLMOD);
    cr_assert(memcmp(x1, x2, sizeof *x1 * N) == 0, "%s%s: x differs (relative %g)", bs_lin_kind_name(kinds[k / 2]),
              mk ? " masked" : "", rel_diff(N, x2, x1));
    cr_assert_eq(s1.iterations, s2.iterations, "%s: %d vs %d iterations", bs_lin_kind_name(kinds[k / 2]),
                 s1.iterations, s2.iterations);
    cr_assert(s1.rel_residual == s2.rel_residual);
    bs_linsolve_destroy(&ls);
  }
  free(mask);
  free(b);
  free(x1);
  free(x2);
  bs_bsr_destroy(&A);
}

/* A block-diagonal matrix of two vertices (no off-diagonal block; values for
 * the caller to set) and a PCG workspace for it. */
static void two_blocks_pcg(bs_bsr **A, bs_linsolve **ls) {
  const int32_t ptr[] = {0, 0, 0};
  bs_error err = {0};
  cr_assert_eq(bs_bsr_create(2, ptr, NULL, A, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_linsolve_create(*A, BS_LIN_PCG, ls, &err), 0, "%s", err.msg);
}

/* Block Jacobi on block-diagonal matrices: with exact inverses PCG converges
 * in one iteration; a diagonal block that is not positive definite gets the
 * pseudo-inverse of its absolute value (exact here for the directions used),
 * and a zero block the identity. */
Test(linsolve, pcg_block_jacobi_fallbacks) {
  bs_bsr *A = NULL;
  bs_linsolve *ls = NULL;
  bs_error err = {0};
  two_blocks_pcg(&A, &ls);
  bs_lin_stats st;
  double x[6], Mi[9];
  /* Exact: two SPD blocks of very different scale. */
  const double spd0[9] = {4, 1, 0, 1, 3, 1, 0, 1, 2}, spd1[9] = {1e-3, 0, 0, 0, 2e-3, 0, 0, 0, 1e-3};
  memcpy(A->val, spd0, sizeof spd0);
  memcpy(A->val + 9, spd1, sizeof spd1);
  const double b1[6] = {1, -2, 3, 1, 1, -1};
  cr_assert_eq(bs_linsolve_solve(ls, A, NULL, b1, 1e-12, 10, x, &st, &err), 0, "%s", err.msg);
  cr_assert_eq(st.iterations, 1);
  cr_assert_eq(st.converged, 1);
  /* Indefinite block 0 (eigenvalues 9, -1, 4, the -1 along (1, -1, 0)/sqrt 2),
   * b along its eigenvectors of 4 and -1: M^-1 = |S|^-1 gives the solution's
   * scale on both, but the direction of -1 is one of negative curvature, so
   * PCG stops there; along the eigenvector of 4 alone it converges at once. */
  const double ind0[9] = {4, 5, 0, 5, 4, 0, 0, 0, 4}, s1[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  cr_assert_eq(bs_linsolve_block_inverse(ind0, Mi), 1);
  const double r2 = sqrt(0.5);
  /* |S|^-1 (1, -1, 0)/sqrt 2 = (1, -1, 0)/sqrt 2 (|lambda| = 1); e3 -> e3/4. */
  cr_assert_float_eq(Mi[0] * r2 - Mi[1] * r2, r2, 1e-14);
  cr_assert_float_eq(Mi[3] * r2 - Mi[4] * r2, -r2, 1e-14);
  cr_assert_float_eq(Mi[8], 0.25, 1e-15);
  memcpy(A->val, ind0, sizeof ind0);
  memcpy(A->val + 9, s1, sizeof s1);
  const double b2[6] = {0, 0, 1, 1, 0, 0};
  cr_assert_eq(bs_linsolve_solve(ls, A, NULL, b2, 1e-12, 10, x, &st, &err), 0, "%s", err.msg);
  cr_assert_eq(st.iterations, 1, "indefinite block: %d iterations", st.iterations);
  cr_assert_float_eq(x[2], 0.25, 1e-15);
  cr_assert_float_eq(x[3], 1.0, 1e-15);
  /* A negative diagonal entry: |S|^-1 = diag(1, 1/4, 1/4), exact for b here
   * (the identity, before, took two iterations for the two scales). */
  const double neg0[9] = {-1, 0, 0, 0, 4, 0, 0, 0, 4}, two[9] = {2, 0, 0, 0, 2, 0, 0, 0, 2};
  memcpy(A->val, neg0, sizeof neg0);
  memcpy(A->val + 9, two, sizeof two);
  const double b3[6] = {0, 1, 0, 1, 0, 0};
  cr_assert_eq(bs_linsolve_solve(ls, A, NULL, b3, 1e-12, 10, x, &st, &err), 0, "%s", err.msg);
  cr_assert_eq(st.iterations, 1, "negative diagonal entry: %d iterations", st.iterations);
  cr_assert_eq(st.converged, 1);
  cr_assert_eq(st.indefinite, 0);
  cr_assert_float_eq(x[1], 0.25, 1e-14);
  cr_assert_float_eq(x[3], 0.5, 1e-14);
  /* A zero block: the identity. */
  const double zero[9] = {0};
  cr_assert_eq(bs_linsolve_block_inverse(zero, Mi), 2);
  cr_assert(Mi[0] == 1 && Mi[4] == 1 && Mi[8] == 1 && Mi[1] == 0 && Mi[2] == 0 && Mi[5] == 0);
  bs_linsolve_destroy(&ls);
  bs_bsr_destroy(&A);
}

/* A vertex on a constraint obstacle: its block is P S P (P = I - n n^T, S SPD
 * at a stiffness of 2e4 to 3e4), singular along n, and its residual has no
 * normal part. Block Jacobi must invert it in
 * the tangent plane: PCG converges in one iteration on the block-diagonal
 * system with no normal component in x, for an axis normal (a zero row and
 * column) and for an oblique one (rounding along n). Before, such a block got
 * the identity, 1e4 times off its scale (fig14's ground: 26x plain CG's
 * iterations). */
Test(linsolve, pcg_block_jacobi_constrained_vertex) {
  bs_bsr *A = NULL;
  bs_linsolve *ls = NULL;
  bs_error err = {0};
  two_blocks_pcg(&A, &ls);
  /* the third: the block of a vertex of fig12 on its torus (a tangent block
   * with a Cholesky pivot of 38 after 8e3) and a normal almost in the xy
   * plane, for which Cholesky's last pivot is rounding amplified to 5e-8 of
   * the diagonal: positive, so that a pivot floor of 1e-14 took it for
   * definite and inverted it (PCG then stalled on fig12) */
  const double S0[9] = {3e4, 4e3, 1e3, 4e3, 2.5e4, -2e3, 1e3, -2e3, 2e4};
  const double S12[9] = {8.047e3, -6.623e3, 2.217e3, -6.623e3, 5.489e3, -1.144e3, 2.217e3, -1.144e3, 1.254e4};
  const double *Ss[3] = {S0, S0, S12};
  const double s3 = 1.0 / sqrt(3.0);
  const double normals[3][3] = {
      {0, 1, 0}, {s3, s3, s3}, {0.75993535957892966, 0.64999865291034864, 2.1826017016860337e-05}};
  for (int c = 0; c < 3; ++c) {
    const double *n = normals[c], *S = Ss[c];
    double P[9], PS[9], B[9];
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) P[3 * a + b] = (a == b) - n[a] * n[b];
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) PS[3 * a + b] = P[3 * a] * S[b] + P[3 * a + 1] * S[3 + b] + P[3 * a + 2] * S[6 + b];
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b)
        B[3 * a + b] = PS[3 * a] * P[b] + PS[3 * a + 1] * P[3 + b] + PS[3 * a + 2] * P[6 + b];
    double Mi[9];
    cr_assert_eq(bs_linsolve_block_inverse(B, Mi), 1, "normal %d: not the eigen fallback", c);
    memcpy(A->val, B, sizeof B);
    const double other[9] = {5e3, 0, 0, 0, 5e3, 0, 0, 0, 5e3};
    memcpy(A->val + 9, other, sizeof other);
    /* b = P (1, 2, -1): tangent. */
    const double v[3] = {1, 2, -1}, vn = v[0] * n[0] + v[1] * n[1] + v[2] * n[2];
    const double b[6] = {v[0] - vn * n[0], v[1] - vn * n[1], v[2] - vn * n[2], 1, 1, 1};
    double x[6];
    bs_lin_stats st;
    cr_assert_eq(bs_linsolve_solve(ls, A, NULL, b, 1e-10, 20, x, &st, &err), 0, "%s", err.msg);
    cr_assert_eq(st.converged, 1, "normal %d: not converged", c);
    cr_assert_eq(st.iterations, 1, "normal %d: %d iterations", c, st.iterations);
    const double xn = x[0] * n[0] + x[1] * n[1] + x[2] * n[2];
    cr_assert(fabs(xn) <= 1e-12 * sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]), "normal %d: x.n = %g", c, xn);
    /* The answer solves the tangent system: B x = b. */
    for (int a = 0; a < 3; ++a) {
      const double Bx = B[3 * a] * x[0] + B[3 * a + 1] * x[1] + B[3 * a + 2] * x[2];
      cr_assert_float_eq(Bx, b[a], 1e-9, "normal %d row %d: %g vs %g", c, a, Bx, b[a]);
    }
  }
  bs_linsolve_destroy(&ls);
  bs_bsr_destroy(&A);
}

/* An empty system (no vertices) and a fully constrained one are solved
 * trivially by every solver. */
Test(linsolve, empty_and_fully_constrained) {
  bs_error err = {0};
  const int32_t ptr0[] = {0};
  bs_bsr *E = NULL;
  cr_assert_eq(bs_bsr_create(0, ptr0, NULL, &E, &err), 0, "%s", err.msg);
  bs_bsr *A = grid_matrix(2);
  fill_spd(A, 0.5);
  uint8_t none[8] = {0};
  double b[24], x[24], dummy = 0;
  for (int e = 0; e < 24; ++e) b[e] = 1.0, x[e] = 5.0;
  for (int k = 0; k < 4; ++k) {
    bs_linsolve *ls = NULL;
    bs_lin_stats st;
    cr_assert_eq(bs_linsolve_create(E, all_kinds[k], &ls, &err), 0, "%s", err.msg);
    cr_assert_eq(bs_linsolve_solve(ls, E, NULL, &dummy, 1e-8, 10, &dummy, &st, &err), 0, "%s",
                 err.msg);
    cr_assert_eq(st.converged, 1);
    bs_linsolve_destroy(&ls);
    cr_assert_eq(bs_linsolve_create(A, all_kinds[k], &ls, &err), 0, "%s", err.msg);
    cr_assert_eq(bs_linsolve_solve(ls, A, none, b, 1e-8, 10, x, &st, &err), 0, "%s", err.msg);
    cr_assert_eq(st.converged, 1);
    for (int e = 0; e < 24; ++e) cr_assert_eq(x[e], 0.0);
    bs_linsolve_destroy(&ls);
  }
  bs_bsr_destroy(&A);
  bs_bsr_destroy(&E);
}

/* Single-precision values (bs_linsolve_set_single): CG and PCG, masked or not,
 * on an SPD matrix with entries near 1e7 (unevenly scaled), converge to 1e-10
 * of the matrix rounded to float (after 5 products with A itself). Their
 * answer is within the distance between the dense solutions of A and of the
 * rounded matrix of both, and it is not the double solve's. A solve of 4
 * iterations or fewer is the double one bit for bit. A value beyond FLT_MAX
 * makes the solve run in double (single_overflow) and still converge. */
Test(linsolve, single_precision_values) {
  bs_bsr *A = grid_matrix(8), *R = grid_matrix(8);
  fill_spd(A, 0.5);
  for (int32_t i = 0; i < A->n; ++i)
    for (int32_t s = A->row_ptr[i]; s < A->row_ptr[i + 1]; ++s)
      for (int e = 0; e < 9; ++e) A->val[9 * s + e] *= 1e7 * (1 + 0.5 * sin(i) * sin(A->col[s]));
  for (int64_t k = 0; k < 9 * A->nnzb; ++k) R->val[k] = (double)(float)A->val[k];
  const int64_t N = 3 * (int64_t)A->n;
  double *b = random_vec(N), *x = malloc(sizeof *x * N), *xr = malloc(sizeof *xr * N), *xd = malloc(sizeof *xd * N);
  uint8_t *mask = malloc((size_t)A->n);
  for (int32_t i = 0; i < A->n; ++i) mask[i] = (uint8_t)(i % 7 != 3);
  bs_error err = {0};
  for (int k = 0; k < 2; ++k)
    for (int masked = 0; masked < 2; ++masked) {
      const uint8_t *mk = masked ? mask : NULL;
      bs_linsolve *ls = NULL;
      cr_assert_eq(bs_linsolve_create(A, all_kinds[k], &ls, &err), 0);
      cr_assert_eq(bs_linsolve_set_single(ls, 1, &err), 0, "%s", err.msg);
      bs_lin_stats st;
      cr_assert_eq(bs_linsolve_solve(ls, A, mk, b, 1e-10, 10000, x, &st, &err), 0, "%s", err.msg);
      cr_assert(st.converged && st.iterations > 10 && !st.single_overflow, "%s masked %d: %d iterations",
                bs_lin_kind_name(all_kinds[k]), masked, st.iterations);
      /* R x = b would be met to ~kappa 1e-10; the products before the copy are
         A's, so x lies between the two solutions, within their distance */
      dense_solve(R, mk, b, xr);
      dense_solve(A, mk, b, xd);
      const double er = rel_diff(N, x, xr), ed = rel_diff(N, x, xd), rd = rel_diff(N, xr, xd);
      cr_assert(rd > 1e-9 && er < 2 * rd && ed < 2 * rd, "%s masked %d: %g and %g from the rounded and double solutions (%g apart)",
                bs_lin_kind_name(all_kinds[k]), masked, er, ed, rd);
      /* and it is not the double solve */
      cr_assert_eq(bs_linsolve_set_single(ls, 0, &err), 0);
      cr_assert_eq(bs_linsolve_solve(ls, A, mk, b, 1e-10, 10000, xr, &st, &err), 0, "%s", err.msg);
      cr_assert_neq(memcmp(x, xr, sizeof *x * N), 0);
      cr_assert_eq(bs_linsolve_set_single(ls, 1, &err), 0);
      /* short solves never read the copy */
      double *x4 = malloc(sizeof *x4 * N), *x4d = malloc(sizeof *x4d * N);
      bs_lin_stats s4;
      cr_assert_eq(bs_linsolve_solve(ls, A, mk, b, 0.0, 4, x4, &s4, &err), 0);
      cr_assert_eq(bs_linsolve_set_single(ls, 0, &err), 0);
      cr_assert_eq(bs_linsolve_solve(ls, A, mk, b, 0.0, 4, x4d, &s4, &err), 0);
      cr_assert_eq(memcmp(x4, x4d, sizeof *x4 * N), 0);
      free(x4);
      free(x4d);
      bs_linsolve_destroy(&ls);
    }
  /* a value beyond single precision: the solve is the double one */
  for (int32_t i = 0; i < A->n; ++i)
    for (int32_t s = A->row_ptr[i]; s < A->row_ptr[i + 1]; ++s)
      for (int e = 0; e < 9; ++e) A->val[9 * s + e] *= 1e35;
  bs_linsolve *ls = NULL;
  cr_assert_eq(bs_linsolve_create(A, BS_LIN_PCG, &ls, &err), 0);
  bs_lin_stats st, sd;
  cr_assert_eq(bs_linsolve_solve(ls, A, NULL, b, 1e-10, 10000, xd, &sd, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_linsolve_set_single(ls, 1, &err), 0);
  cr_assert_eq(bs_linsolve_solve(ls, A, NULL, b, 1e-10, 10000, x, &st, &err), 0, "%s", err.msg);
  cr_assert(st.single_overflow && st.converged);
  cr_assert_eq(st.iterations, sd.iterations);
  cr_assert_eq(memcmp(x, xd, sizeof *x * N), 0);
  /* not for MINRES or CHOLMOD */
  bs_linsolve *lm = NULL;
  cr_assert_eq(bs_linsolve_create(A, BS_LIN_MINRES, &lm, &err), 0);
  cr_assert_eq(bs_linsolve_set_single(lm, 1, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "minres"), "%s", err.msg);
  bs_linsolve_destroy(&lm);
  bs_linsolve_destroy(&ls);
  free(mask);
  free(b);
  free(x);
  free(xr);
  free(xd);
  bs_bsr_destroy(&A);
  bs_bsr_destroy(&R);
}

/* bs_linsolve_set_downhill: a CG answer that fails b.x >= kappa ||b|| ||x||
 * is replaced by the last iterate that passed. One vertex, A = diag(1, eps,
 * c), b = (1, 1e-3, bz): the first iterate is nearly parallel to b; the
 * second goes far along the eps direction (nearly orthogonal to b). With c =
 * 1 (SPD, bz = 0) the second iterate is the exact solution; with c = -1 the
 * third direction has negative curvature and CG exits indefinite. */
Test(linsolve, downhill_iterate) {
  const int32_t ptr[2] = {0, 0};
  bs_bsr *A = NULL;
  bs_error err = {0};
  cr_assert_eq(bs_bsr_create(1, ptr, NULL, &A, &err), 0, "%s", err.msg);
  const double kappa = 1e-2;
  for (int c = 0; c < 2; ++c) {
    double *D = A->val + 9 * A->diag[0];
    memset(D, 0, 9 * sizeof *D);
    D[0] = 1.0;
    D[4] = 1e-6;
    D[8] = c == 0 ? 1.0 : -1.0;
    const double b[3] = {1.0, 1e-3, c == 0 ? 0.0 : 1e-7};
    bs_linsolve *ls = NULL;
    cr_assert_eq(bs_linsolve_create(A, BS_LIN_CG, &ls, &err), 0, "%s", err.msg);
    double x[3], x1[3];
    bs_lin_stats st;
    /* Off (the default): the answer fails the test. */
    cr_assert_eq(bs_linsolve_solve(ls, A, NULL, b, 1e-8, 10, x, &st, &err), 0, "%s", err.msg);
    cr_assert_eq(st.iterations, 2, "case %d: %d iterations", c, st.iterations);
    cr_assert_eq(st.indefinite, c, "case %d", c);
    cr_assert_eq(st.downhill_iterate, 0);
    const double bn = sqrt(b[0] * b[0] + b[1] * b[1] + b[2] * b[2]);
    double bx = b[0] * x[0] + b[1] * x[1] + b[2] * x[2], xn = sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]);
    cr_assert_lt(bx, kappa * bn * xn, "case %d: the plain answer passes (%g >= %g)", c, bx, kappa * bn * xn);
    /* The first iterate. */
    cr_assert_eq(bs_linsolve_solve(ls, A, NULL, b, 1e-12, 1, x1, &st, &err), 0, "%s", err.msg);
    /* On: the first iterate comes back, with its residual. */
    cr_assert_eq(bs_linsolve_set_downhill(ls, kappa, &err), 0, "%s", err.msg);
    cr_assert_eq(bs_linsolve_solve(ls, A, NULL, b, 1e-8, 10, x, &st, &err), 0, "%s", err.msg);
    cr_assert_eq(st.iterations, 2);
    cr_assert_eq(st.downhill_iterate, 1, "case %d", c);
    cr_assert_eq(st.converged, c == 0, "case %d", c); /* the solve's own exit is kept */
    /* (recovered as x_2 - alpha p: x_2 is ~1e3 along eps, so ~1e-13 off) */
    for (int e = 0; e < 3; ++e) cr_assert_float_eq(x[e], x1[e], 1e-11, "case %d x[%d]: %g vs %g", c, e, x[e], x1[e]);
    bx = b[0] * x[0] + b[1] * x[1] + b[2] * x[2];
    xn = sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]);
    cr_assert_geq(bx, kappa * bn * xn);
    double r2 = 0;
    for (int e = 0; e < 3; ++e) r2 += (b[e] - D[4 * e] * x[e]) * (b[e] - D[4 * e] * x[e]);
    cr_assert_float_eq(st.rel_residual, sqrt(r2) / bn, 1e-9, "residual %g vs %g", st.rel_residual, sqrt(r2) / bn);
    /* A small kappa that the answer passes changes nothing. */
    cr_assert_eq(bs_linsolve_set_downhill(ls, 1e-9, &err), 0, "%s", err.msg);
    cr_assert_eq(bs_linsolve_solve(ls, A, NULL, b, 1e-8, 10, x, &st, &err), 0, "%s", err.msg);
    cr_assert_eq(st.downhill_iterate, 0);
    cr_assert_gt(fabs(x[1]), 100.0);
    bs_linsolve_destroy(&ls);
  }
  /* Errors: kappa out of [0, 1), a workspace that is not CG. */
  bs_linsolve *ls = NULL;
  cr_assert_eq(bs_linsolve_create(A, BS_LIN_CG, &ls, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_linsolve_set_downhill(ls, 1.0, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "kappa"), "%s", err.msg);
  cr_assert_eq(bs_linsolve_set_downhill(ls, NAN, &err), BS_EINPUT);
  bs_linsolve_destroy(&ls);
  cr_assert_eq(bs_linsolve_create(A, BS_LIN_MINRES, &ls, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_linsolve_set_downhill(ls, kappa, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "minres"), "%s", err.msg);
  cr_assert_eq(bs_linsolve_set_downhill(ls, 0.0, &err), 0);
  bs_linsolve_destroy(&ls);
  bs_bsr_destroy(&A);
}

/* The quadratic model m(x) = -b.x + x.A x / 2 (A x into ax). */
static double model(const bs_bsr *A, const double *b, const double *x, double *ax, int64_t N) {
  bs_bsr_mul(A, NULL, x, ax);
  double v = 0;
  for (int64_t e = 0; e < N; ++e) v += -b[e] * x[e] + 0.5 * x[e] * ax[e];
  return v;
}

/* The Cauchy point: the minimizer of m along b inside the ball of radius r. */
static double cauchy_model(const bs_bsr *A, const double *b, double r, double *x, double *ax, int64_t N) {
  double bb = 0, bab = 0;
  bs_bsr_mul(A, NULL, b, ax);
  for (int64_t e = 0; e < N; ++e) bb += b[e] * b[e], bab += b[e] * ax[e];
  const double tmax = r / sqrt(bb), t = bab > 0 ? fmin(bb / bab, tmax) : tmax;
  for (int64_t e = 0; e < N; ++e) x[e] = t * b[e];
  return model(A, b, x, ax, N);
}

/* Steihaug's CG (bs_linsolve_set_radius), for cg and pcg: on an SPD matrix
 * a radius larger than the solution changes nothing; a smaller one ends on
 * the boundary. On an indefinite matrix (the negative-curvature exit) the
 * answer is on the boundary too. Every boundary answer is a descent
 * direction and, for CG, lowers the model at least as much as the Cauchy
 * point (Steihaug's first iterate). */
Test(linsolve, trust_region_steihaug) {
  bs_bsr *A = grid_matrix(5);
  const int64_t N = 3 * (int64_t)A->n;
  double *b = random_vec(N), *x = malloc(sizeof *x * N), *xd = malloc(sizeof *xd * N), *ax = malloc(sizeof *ax * N),
         *xc = malloc(sizeof *xc * N);
  bs_error err = {0};
  for (int indef = 0; indef < 2; ++indef) {
    fill_spd(A, 0.0);
    if (indef)
      for (int32_t i = 0; i < A->n; ++i)
        for (int a = 0; a < 3; ++a) A->val[9 * A->diag[i] + 4 * a] -= 3.0;
    dense_solve(A, NULL, b, xd);
    double xdn = 0;
    for (int64_t e = 0; e < N; ++e) xdn += xd[e] * xd[e];
    xdn = sqrt(xdn);
    for (int k = 0; k < 2; ++k) {
      bs_linsolve *ls = NULL;
      cr_assert_eq(bs_linsolve_create(A, all_kinds[k], &ls, &err), 0);
      const char *name = bs_lin_kind_name(all_kinds[k]);
      bs_lin_stats st;
      for (int small = 0; small < 2; ++small) {
        const double r = small ? 0.3 * xdn : 10 * xdn;
        cr_assert_eq(bs_linsolve_set_radius(ls, r, &err), 0, "%s", err.msg);
        cr_assert_eq(bs_linsolve_solve(ls, A, NULL, b, 1e-10, 1000, x, &st, &err), 0, "%s", err.msg);
        double xn = 0, bx = 0;
        for (int64_t e = 0; e < N; ++e) xn += x[e] * x[e], bx += b[e] * x[e];
        xn = sqrt(xn);
        cr_assert_gt(bx, 0.0, "%s indef %d small %d: b.x = %g", name, indef, small, bx);
        if (!indef && !small) {
          cr_assert_eq(st.boundary, 0, "%s: the solution lies inside the ball", name);
          cr_assert_lt(rel_diff(N, x, xd), 1e-8, "%s: error %g", name, rel_diff(N, x, xd));
          continue;
        }
        cr_assert_eq(st.boundary, 1, "%s indef %d small %d", name, indef, small);
        if (!indef || !small) /* (in the small ball of the indefinite matrix either exit can come first) */
          cr_assert_eq(st.indefinite, indef, "%s indef %d small %d", name, indef, small);
        cr_assert_float_eq(xn, r, 1e-10 * r, "%s indef %d small %d: ||x|| = %.15g, radius %.15g", name, indef,
                           small, xn, r);
        /* (PCG's path starts along M^-1 b: its guarantee is in M's norm, so only a decrease is asserted) */
        const double mx = model(A, b, x, ax, N), mc = k == 0 ? cauchy_model(A, b, r, xc, ax, N) : 0.0;
        cr_assert_leq(mx, mc + 1e-12 * fabs(mc), "%s indef %d small %d: model %.15g above the Cauchy point's %.15g",
                      name, indef, small, mx, mc);
      }
      cr_assert_eq(bs_linsolve_set_radius(ls, 0.0, &err), 0);
      cr_assert_eq(bs_linsolve_solve(ls, A, NULL, b, 1e-10, 1000, x, &st, &err), 0, "%s", err.msg);
      cr_assert_eq(st.boundary, 0);
      cr_assert_neq(bs_linsolve_set_radius(ls, -1.0, &err), 0);
      cr_assert(strstr(err.msg, "radius"), "%s", err.msg);
      bs_linsolve_destroy(&ls);
    }
  }
  bs_linsolve *ls = NULL;
  cr_assert_eq(bs_linsolve_create(A, BS_LIN_MINRES, &ls, &err), 0);
  cr_assert_neq(bs_linsolve_set_radius(ls, 1.0, &err), 0);
  cr_assert(strstr(err.msg, "minres"), "%s", err.msg);
  bs_linsolve_destroy(&ls);
  free(b);
  free(x);
  free(xd);
  free(ax);
  free(xc);
  bs_bsr_destroy(&A);
}
