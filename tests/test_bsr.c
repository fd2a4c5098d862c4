/* test_bsr.c — 3x3 block CSR: pattern from a graph, product against a dense
 * product (plain and masked), thread-count independence, the checker, and
 * error paths of create. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

#include "bs_bsr.h"

static uint64_t rng_state = 88172645463325252ull;
static double urand(void) { /* xorshift64, uniform in [-1, 1) */
  rng_state ^= rng_state << 13;
  rng_state ^= rng_state >> 7;
  rng_state ^= rng_state << 17;
  return (double)(rng_state >> 11) / 9007199254740992.0 * 2.0 - 1.0;
}

/* A symmetric random graph on n vertices, about deg neighbours each, with
 * duplicate entries on purpose. */
static void random_graph(int32_t n, int deg, int32_t **ptr, int32_t **adj) {
  int32_t *ei = malloc(sizeof(int32_t) * (size_t)n * deg * 3);
  int32_t *ej = malloc(sizeof(int32_t) * (size_t)n * deg * 3);
  int m = 0;
  for (int32_t i = 0; i < n; ++i)
    for (int k = 0; k < deg; ++k) {
      int32_t j = (int32_t)((urand() + 1.0) * 0.5 * n) % n;
      if (j == i) continue;
      ei[m] = i, ej[m] = j, ++m;
      ei[m] = j, ej[m] = i, ++m;
      if (k == 0) { /* a duplicate */
        ei[m] = i, ej[m] = j, ++m;
      }
    }
  *ptr = calloc((size_t)n + 1, sizeof(int32_t));
  *adj = malloc(sizeof(int32_t) * (size_t)(m > 0 ? m : 1));
  for (int e = 0; e < m; ++e) (*ptr)[ei[e] + 1]++;
  for (int32_t i = 0; i < n; ++i) (*ptr)[i + 1] += (*ptr)[i];
  int32_t *fill = calloc((size_t)n, sizeof(int32_t));
  for (int e = 0; e < m; ++e) (*adj)[(*ptr)[ei[e]] + fill[ei[e]]++] = ej[e];
  free(fill);
  free(ei);
  free(ej);
}

static void fill_random(bs_bsr *A) {
  for (int64_t k = 0; k < 9 * A->nnzb; ++k) A->val[k] = urand();
}

/* Symmetrize values: A_ji = A_ij^T. */
static void symmetrize(bs_bsr *A) {
  for (int32_t i = 0; i < A->n; ++i)
    for (int32_t s = A->row_ptr[i]; s < A->row_ptr[i + 1]; ++s) {
      int32_t j = A->col[s];
      if (j < i) continue;
      int32_t t = bs_bsr_slot(A, j, i);
      cr_assert(t >= 0);
      for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b) A->val[9 * t + 3 * b + a] = A->val[9 * s + 3 * a + b];
    }
}

static double *dense_of(const bs_bsr *A) {
  int64_t N = 3 * (int64_t)A->n;
  double *D = calloc((size_t)(N * N), sizeof *D);
  for (int32_t i = 0; i < A->n; ++i)
    for (int32_t s = A->row_ptr[i]; s < A->row_ptr[i + 1]; ++s)
      for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b)
          D[(3 * i + a) * N + 3 * A->col[s] + b] = A->val[9 * s + 3 * a + b];
  return D;
}

Test(bsr, pattern_from_graph) {
  /* 0: {2, 1, 2}, 1: {0}, 2: {0, 0}, 3: {} (isolated), 4: {4, 1} (self loop). */
  const int32_t ptr[] = {0, 3, 4, 6, 6, 8};
  const int32_t adj[] = {2, 1, 2, 0, 0, 0, 4, 1};
  bs_bsr *A = NULL;
  bs_error err = {0};
  cr_assert_eq(bs_bsr_create(5, ptr, adj, &A, &err), 0, "%s", err.msg);
  const int32_t rp[] = {0, 3, 5, 7, 8, 10};
  const int32_t col[] = {0, 1, 2, 0, 1, 0, 2, 3, 1, 4};
  const int32_t diag[] = {0, 4, 6, 7, 9};
  cr_assert_eq(A->n, 5);
  cr_assert_eq(A->nnzb, 10);
  for (int i = 0; i <= 5; ++i) cr_assert_eq(A->row_ptr[i], rp[i], "row_ptr[%d]", i);
  for (int s = 0; s < 10; ++s) cr_assert_eq(A->col[s], col[s], "col[%d]", s);
  for (int i = 0; i < 5; ++i) cr_assert_eq(A->diag[i], diag[i], "diag[%d]", i);
  for (int64_t k = 0; k < 9 * A->nnzb; ++k) cr_assert_eq(A->val[k], 0.0);
  cr_assert_eq(bs_bsr_slot(A, 0, 2), 2);
  cr_assert_eq(bs_bsr_slot(A, 4, 1), 8);
  cr_assert_eq(bs_bsr_slot(A, 3, 3), 7);
  cr_assert_eq(bs_bsr_slot(A, 3, 0), -1);
  cr_assert_eq(bs_bsr_slot(A, 1, 4), -1);
  cr_assert_eq(bs_bsr_slot(A, 5, 0), -1);
  cr_assert_eq(bs_bsr_slot(A, 0, -1), -1);
  /* (4,1) stored but (1,4) not: the checker names the pair. */
  cr_assert_eq(bs_bsr_check(A, 0.0, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "(4,1)") && strstr(err.msg, "(1,4)"), "%s", err.msg);
  fill_random(A);
  bs_bsr_zero(A);
  for (int64_t k = 0; k < 9 * A->nnzb; ++k) cr_assert_eq(A->val[k], 0.0);
  bs_bsr_destroy(&A);
  cr_assert_null(A);
  bs_bsr_destroy(&A); /* NULL is fine */
  bs_bsr_destroy(NULL);
}

Test(bsr, empty_matrix) {
  const int32_t ptr[] = {0};
  bs_bsr *A = NULL;
  bs_error err = {0};
  cr_assert_eq(bs_bsr_create(0, ptr, NULL, &A, &err), 0, "%s", err.msg);
  cr_assert_eq(A->nnzb, 0);
  cr_assert_eq(bs_bsr_check(A, 0.0, &err), 0, "%s", err.msg);
  bs_bsr_destroy(&A);
}

Test(bsr, create_errors) {
  bs_bsr *A = NULL;
  bs_error err = {0};
  const int32_t ptr[] = {0, 1, 2, 3};
  const int32_t bad[] = {1, 7, 0};
  cr_assert_eq(bs_bsr_create(3, ptr, bad, &A, &err), BS_EINPUT);
  cr_assert_null(A);
  cr_assert(strstr(err.msg, "neighbour 7 of vertex 1"), "%s", err.msg);
  const int32_t ptr2[] = {0, 2, 1, 3};
  const int32_t ok[] = {1, 2, 0};
  cr_assert_eq(bs_bsr_create(3, ptr2, ok, &A, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "vertex 1"), "%s", err.msg);
  cr_assert_eq(bs_bsr_create(-1, ptr, ok, &A, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "-1"), "%s", err.msg);
}

Test(bsr, product_matches_dense) {
  int32_t *ptr, *adj;
  const int32_t n = 60;
  random_graph(n, 4, &ptr, &adj);
  bs_bsr *A = NULL;
  bs_error err = {0};
  cr_assert_eq(bs_bsr_create(n, ptr, adj, &A, &err), 0, "%s", err.msg);
  /* Sorted, diagonal present, pattern symmetric (values need not be). */
  for (int32_t i = 0; i < n; ++i) {
    cr_assert_eq(A->col[A->diag[i]], i);
    for (int32_t s = A->row_ptr[i] + 1; s < A->row_ptr[i + 1]; ++s)
      cr_assert_lt(A->col[s - 1], A->col[s]);
    for (int32_t k = ptr[i]; k < ptr[i + 1]; ++k) cr_assert_geq(bs_bsr_slot(A, i, adj[k]), 0);
  }
  fill_random(A);
  const int64_t N = 3 * n;
  double *D = dense_of(A), *x = malloc(N * sizeof *x), *y = malloc(N * sizeof *y);
  for (int64_t k = 0; k < N; ++k) x[k] = urand();
  bs_bsr_mul(A, NULL, x, y);
  for (int64_t r = 0; r < N; ++r) {
    double s = 0;
    for (int64_t c = 0; c < N; ++c) s += D[r * N + c] * x[c];
    cr_assert_float_eq(y[r], s, 1e-12, "row %lld: %g vs %g", (long long)r, y[r], s);
  }
  /* Masked: y_i = sum over free j of A_ij x_j for free i, 0 for constrained i. */
  uint8_t *mask = malloc((size_t)n);
  for (int32_t i = 0; i < n; ++i) mask[i] = (uint8_t)(i % 3 != 1);
  for (int64_t k = 0; k < N; ++k) y[k] = NAN;
  bs_bsr_mul(A, mask, x, y);
  for (int64_t r = 0; r < N; ++r) {
    double s = 0;
    if (mask[r / 3])
      for (int64_t c = 0; c < N; ++c)
        if (mask[c / 3]) s += D[r * N + c] * x[c];
    if (!mask[r / 3])
      cr_assert_eq(y[r], 0.0, "constrained row %lld", (long long)r);
    else
      cr_assert_float_eq(y[r], s, 1e-12, "masked row %lld: %g vs %g", (long long)r, y[r], s);
  }
  /* Constrained entries of x do not matter. */
  double *y2 = malloc(N * sizeof *y2);
  for (int64_t k = 0; k < N; ++k)
    if (!mask[k / 3]) x[k] = 1e30;
  bs_bsr_mul(A, mask, x, y2);
  cr_assert_eq(memcmp(y, y2, N * sizeof *y), 0);
  /* The fused product and dot: the same y, and x . y over the free entries (the
     1e30 in constrained entries of x stay out of it). */
  for (int masked = 0; masked < 2; ++masked) {
    const uint8_t *mk = masked ? mask : NULL;
    if (!masked)
      for (int64_t k = 0; k < N; ++k) x[k] = urand();
    bs_bsr_mul(A, mk, x, y);
    double ref = 0;
    for (int64_t k = 0; k < N; ++k)
      if (!mk || mk[k / 3]) ref += x[k] * y[k];
    for (int64_t k = 0; k < N; ++k) y2[k] = NAN;
    const double xy = bs_bsr_mul_dot(A, mk, x, y2);
    cr_assert_eq(memcmp(y, y2, N * sizeof *y), 0, "masked %d: the fused product differs", masked);
    cr_assert(fabs(xy - ref) <= 1e-13 * (1 + fabs(ref)), "masked %d: x.y %.17g vs %.17g", masked, xy, ref);
    if (!masked)
      for (int64_t k = 0; k < N; ++k)
        if (!mask[k / 3]) x[k] = 1e30;
  }
  free(y2);
  free(mask);
  free(D);
  free(x);
  free(y);
  free(ptr);
  free(adj);
  bs_bsr_destroy(&A);
}

Test(bsr, product_independent_of_threads) {
  int32_t *ptr, *adj;
  const int32_t n = 5000;
  random_graph(n, 6, &ptr, &adj);
  bs_bsr *A = NULL;
  bs_error err = {0};
  cr_assert_eq(bs_bsr_create(n, ptr, adj, &A, &err), 0, "%s", err.msg);
  fill_random(A);
  const int64_t N = 3 * n;
  double *x = malloc(N * sizeof *x), *y1 = malloc(N * sizeof *y1), *y2 = malloc(N * sizeof *y2);
  for (int64_t k = 0; k < N; ++k) x[k] = urand();
  int nt = omp_get_max_threads();
  omp_set_num_threads(1);
  bs_bsr_mul(A, NULL, x, y1);
  omp_set_num_threads(3);
  bs_bsr_mul(A, NULL, x, y2);
  omp_set_num_threads(nt);
  cr_assert_eq(memcmp(y1, y2, N * sizeof *y1), 0, "product depends on the thread count");
  free(x);
  free(y1);
  free(y2);
  free(ptr);
  free(adj);
  bs_bsr_destroy(&A);
}

Test(bsr, check_catches_asymmetry_and_names_block) {
  int32_t *ptr, *adj;
  const int32_t n = 40;
  random_graph(n, 3, &ptr, &adj);
  bs_bsr *A = NULL;
  bs_error err = {0};
  cr_assert_eq(bs_bsr_create(n, ptr, adj, &A, &err), 0, "%s", err.msg);
  fill_random(A);
  symmetrize(A);
  cr_assert_eq(bs_bsr_check(A, 0.0, &err), 0, "%s", err.msg);
  /* Pick an off-diagonal block (i,j), i < j, and break A_ji = A_ij^T there. */
  int32_t i = -1, j = -1, s = -1;
  for (int32_t r = 0; r < n && s < 0; ++r)
    for (int32_t t = A->row_ptr[r]; t < A->row_ptr[r + 1]; ++t)
      if (A->col[t] > r) {
        i = r, j = A->col[t], s = t;
        break;
      }
  cr_assert_geq(s, 0);
  const int32_t t = bs_bsr_slot(A, j, i);
  A->val[9 * t + 5] += 1e-6; /* entry (1,2) of block (j,i): mirrors (2,1) of (i,j) */
  cr_assert_eq(bs_bsr_check(A, 1e-9, &err), BS_EINPUT);
  char want[64];
  snprintf(want, sizeof want, "block (%d,%d) entry (2,1)", (int)i, (int)j);
  cr_assert(strstr(err.msg, want), "message \"%s\" lacks \"%s\"", err.msg, want);
  snprintf(want, sizeof want, "block (%d,%d) entry (1,2)", (int)j, (int)i);
  cr_assert(strstr(err.msg, want), "message \"%s\" lacks \"%s\"", err.msg, want);
  /* Within a looser relative tolerance it passes. */
  cr_assert_eq(bs_bsr_check(A, 1e-5, &err), 0, "%s", err.msg);
  /* An asymmetric diagonal block is caught too. */
  A->val[9 * t + 5] -= 1e-6;
  A->val[9 * A->diag[7] + 1] += 0.5;
  cr_assert_eq(bs_bsr_check(A, 1e-9, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "block (7,7) entry (0,1)"), "%s", err.msg);
  A->val[9 * A->diag[7] + 1] -= 0.5;
  cr_assert_eq(bs_bsr_check(A, 1e-12, &err), 0, "%s", err.msg);
  /* Non-finite value. */
  A->val[9 * s + 4] = NAN;
  cr_assert_eq(bs_bsr_check(A, 1e-9, &err), BS_ENUMERIC);
  snprintf(want, sizeof want, "block (%d,%d) entry (1,1)", (int)i, (int)j);
  cr_assert(strstr(err.msg, want), "message \"%s\" lacks \"%s\"", err.msg, want);
  A->val[9 * s + 4] = A->val[9 * t + 4];
  /* Broken structure: unsorted columns, wrong diagonal slot. */
  int32_t r0 = A->row_ptr[i];
  int32_t c0 = A->col[r0];
  A->col[r0] = A->col[r0 + 1];
  A->col[r0 + 1] = c0;
  cr_assert_eq(bs_bsr_check(A, 1e-9, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "not strictly increasing"), "%s", err.msg);
  A->col[r0 + 1] = A->col[r0];
  A->col[r0] = c0;
  int32_t d = A->diag[3];
  A->diag[3] = d == A->row_ptr[3] ? d + 1 : d - 1;
  cr_assert_eq(bs_bsr_check(A, 1e-9, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "block (3,3)"), "%s", err.msg);
  A->diag[3] = d;
  cr_assert_eq(bs_bsr_check(A, 1e-12, &err), 0, "%s", err.msg);
  free(ptr);
  free(adj);
  bs_bsr_destroy(&A);
}

/* Extra blocks (outside the pattern): add_block routes to the slot or the
 * list, the product (plain and masked) matches a dense product that includes
 * them, the checker catches an unmatched transpose, zero empties the list. */
Test(bsr, extra_blocks_enter_the_product_and_the_checker) {
  const int32_t n = 6;
  /* A path graph 0-1-2-3-4-5: (0,5) and (1,4) are not in the pattern. */
  int32_t ptr[7] = {0, 1, 3, 5, 7, 9, 10}, adj[10] = {1, 0, 2, 1, 3, 2, 4, 3, 5, 4};
  bs_bsr *A;
  bs_error err = {0};
  cr_assert_eq(bs_bsr_create(n, ptr, adj, &A, &err), 0, "%s", err.msg);
  fill_random(A);
  symmetrize(A);
  double D[18][18];
  memset(D, 0, sizeof D);
  for (int32_t i = 0; i < n; ++i)
    for (int32_t s = A->row_ptr[i]; s < A->row_ptr[i + 1]; ++s)
      for (int e = 0; e < 9; ++e) D[3 * i + e / 3][3 * A->col[s] + e % 3] = A->val[9 * s + e];
  double B[9];
  for (int e = 0; e < 9; ++e) B[e] = urand();
  cr_assert_eq(bs_bsr_add_block(A, 0, 5, B), BS_BSR_DROPPED, "no room reserved: the block must be dropped");
  cr_assert_eq(bs_bsr_reserve_extra(A, 3, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_bsr_reserve_extra(A, -1, &err), BS_EINPUT);
  cr_assert_eq(bs_bsr_add_block(A, 0, 5, B), BS_BSR_EXTRA);
  double Bt[9];
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b) Bt[3 * a + b] = B[3 * b + a];
  /* the checker sees (0,5) without its transpose */
  cr_assert_eq(bs_bsr_check(A, 1e-12, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "extra blocks (0,5)"), "%s", err.msg);
  cr_assert_eq(bs_bsr_add_block(A, 5, 0, Bt), BS_BSR_EXTRA);
  cr_assert_eq(bs_bsr_check(A, 1e-12, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_bsr_add_block(A, 1, 2, B), BS_BSR_SLOT, "(1,2) is in the pattern: into its slot");
  cr_assert_eq(bs_bsr_add_block(A, 2, 1, Bt), BS_BSR_SLOT);
  cr_assert_eq(bs_bsr_add_block(A, 0, 5, B), BS_BSR_EXTRA, "duplicates add up in the list");
  cr_assert_eq(bs_bsr_add_block(A, 5, 0, Bt), BS_BSR_DROPPED, "the list is full");
  for (int e = 0; e < 9; ++e) {
    D[e / 3][15 + e % 3] += 2 * B[e];
    D[15 + e / 3][e % 3] += Bt[e];
    D[3 + e / 3][6 + e % 3] += B[e];
    D[6 + e / 3][3 + e % 3] += Bt[e];
  }
  double x[18], y[18];
  for (int k = 0; k < 18; ++k) x[k] = urand();
  uint8_t mask[6] = {1, 1, 1, 1, 1, 0};
  for (int masked = 0; masked < 2; ++masked) {
    bs_bsr_mul(A, masked ? mask : NULL, x, y);
    for (int r = 0; r < 18; ++r) {
      double ref = 0;
      if (!masked || mask[r / 3])
        for (int c = 0; c < 18; ++c)
          if (!masked || mask[c / 3]) ref += D[r][c] * x[c];
      cr_assert(fabs(y[r] - ref) <= 1e-13 * (1 + fabs(ref)), "masked %d row %d: %.17g vs %.17g", masked, r,
                y[r], ref);
    }
    /* with extra blocks the dot of bs_bsr_mul_dot comes after them */
    double y2[18], dref = 0;
    for (int k = 0; k < 18; ++k)
      if (!masked || mask[k / 3]) dref += x[k] * y[k];
    const double xy = bs_bsr_mul_dot(A, masked ? mask : NULL, x, y2);
    cr_assert_eq(memcmp(y, y2, sizeof y), 0, "masked %d: the fused product differs", masked);
    cr_assert(fabs(xy - dref) <= 1e-13 * (1 + fabs(dref)), "masked %d: x.y %.17g vs %.17g", masked, xy, dref);
  }
  bs_bsr_zero(A);
  cr_assert_eq(A->n_extra, 0);
  cr_assert_eq(bs_bsr_add_block(A, 1, 4, B), BS_BSR_EXTRA, "room is back after zero");
  cr_assert_str_eq(bs_bsr_placement_name(BS_BSR_DROPPED), "dropped");
  cr_assert_str_eq(bs_bsr_placement_name(BS_BSR_SLOT), "slot");
  cr_assert_str_eq(bs_bsr_placement_name(BS_BSR_EXTRA), "extra");
  bs_bsr_destroy(&A);
}

/* Single-precision values: the rounding product is bs_bsr_mul_dot bit for bit;
 * the single product equals the product with the values rounded to float
 * (computed here in double from a rounded copy), to the rounding of the sums;
 * constrained rows and columns (NaN in their blocks) and the extra blocks as in
 * bs_bsr_mul_dot; a value beyond FLT_MAX gives a non-finite dot. */
Test(bsr, single_precision_values) {
  int32_t *ptr, *adj;
  const int32_t n = 5000;
  random_graph(n, 6, &ptr, &adj);
  bs_bsr *A = NULL, *R = NULL;
  bs_error err = {0};
  cr_assert_eq(bs_bsr_create(n, ptr, adj, &A, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_bsr_create(n, ptr, adj, &R, &err), 0, "%s", err.msg);
  fill_random(A);
  for (int64_t k = 0; k < 9 * A->nnzb; ++k) A->val[k] *= 1e6; /* far from 1: an exponent to keep */
  const int64_t N = 3 * n;
  double *x = malloc(N * sizeof *x), *y = malloc(N * sizeof *y), *y32 = malloc(N * sizeof *y32);
  float *v32 = malloc((size_t)bs_bsr_val32_count(A) * sizeof *v32);
  for (int64_t k = 0; k < N; ++k) x[k] = urand();
  uint8_t *mask = malloc((size_t)n);
  for (int32_t i = 0; i < n; ++i) mask[i] = (uint8_t)(i % 5 != 2);
  double B[9];
  for (int e = 0; e < 9; ++e) B[e] = 1e6 * urand();
  for (int extras = 0; extras < 2; ++extras) {
    if (extras) { /* a block outside the pattern (random graphs of degree 6 miss most pairs) */
      int32_t i = 0, j = 1;
      while (bs_bsr_slot(A, i, j) >= 0) ++j;
      cr_assert_eq(bs_bsr_reserve_extra(A, 1, &err), 0, "%s", err.msg);
      cr_assert_eq(bs_bsr_reserve_extra(R, 1, &err), 0, "%s", err.msg);
      cr_assert_eq(bs_bsr_add_block(A, i, j, B), BS_BSR_EXTRA);
      cr_assert_eq(bs_bsr_add_block(R, i, j, B), BS_BSR_EXTRA);
    }
    for (int masked = 0; masked < 2; ++masked) {
      const uint8_t *mk = masked ? mask : NULL;
      if (masked) /* constrained columns' blocks never enter, even as NaN */
        for (int32_t i = 0; i < n; ++i)
          for (int32_t s = A->row_ptr[i]; s < A->row_ptr[i + 1]; ++s)
            if (!mask[A->col[s]]) A->val[9 * s + 4] = NAN;
      const double ref = bs_bsr_mul_dot(A, mk, x, y);
      for (int64_t k = 0; k < N; ++k) y32[k] = NAN;
      const double d = bs_bsr_mul_dot_round32(A, mk, x, y32, v32);
      cr_assert_eq(memcmp(y, y32, N * sizeof *y), 0, "extras %d masked %d: the rounding product differs", extras,
                   masked);
      cr_assert_eq(d, ref);
      /* R: A's values rounded to float, in double */
      for (int64_t k = 0; k < 9 * A->nnzb; ++k) R->val[k] = (double)(float)A->val[k];
      const double rref = bs_bsr_mul_dot(R, mk, x, y);
      const double d32 = bs_bsr_mul_dot32(A, v32, mk, x, y32);
      double ymax = 0;
      for (int64_t k = 0; k < N; ++k) ymax = fmax(ymax, fabs(y[k]));
      for (int64_t k = 0; k < N; ++k) {
        cr_assert(isfinite(y32[k]), "extras %d masked %d: entry %lld not finite", extras, masked, (long long)k);
        cr_assert(fabs(y32[k] - y[k]) <= 1e-13 * ymax, "extras %d masked %d entry %lld: %.17g vs %.17g", extras,
                  masked, (long long)k, y32[k], y[k]);
        if (mk && !mk[k / 3]) cr_assert_eq(y32[k], 0.0);
      }
      cr_assert(fabs(d32 - rref) <= 1e-12 * fabs(rref), "extras %d masked %d: x.y %.17g vs %.17g", extras, masked,
                d32, rref);
      /* and it is not the double product: the values did change */
      cr_assert(fabs(d32 - ref) > 0.0);
    }
    for (int64_t k = 0; k < 9 * A->nnzb; ++k)
      if (isnan(A->val[k])) A->val[k] = 1e6 * urand();
  }
  /* beyond single precision */
  A->val[9 * A->diag[7] + 4] = 1e39;
  cr_assert(isfinite(bs_bsr_mul_dot_round32(A, NULL, x, y, v32)));
  cr_assert(!isfinite(bs_bsr_mul_dot32(A, v32, NULL, x, y)));
  free(v32);
  free(mask);
  free(x);
  free(y);
  free(y32);
  free(ptr);
  free(adj);
  bs_bsr_destroy(&A);
  bs_bsr_destroy(&R);
}

/* Indexed extras (bs_bsr_index_extra): the list sorted by rows with each
 * row's blocks in their list order, and every product (plain, masked, with a
 * dot, the single-precision ones) bit for bit the one of the unindexed list
 * (added serially after the rows), with 1 and 3 threads; a block added after
 * the index voids it and still enters the product; zero empties both. */
static void products(const bs_bsr *A, const uint8_t *mask, const double *x, double *y, float *v32, double *dots) {
  const int64_t N = 3 * (int64_t)A->n;
  bs_bsr_mul(A, mask, x, y);
  dots[0] = bs_bsr_mul_dot(A, mask, x, y + N);
  dots[1] = bs_bsr_mul_dot_round32(A, mask, x, y + 2 * N, v32);
  dots[2] = bs_bsr_mul_dot32(A, v32, mask, x, y + 3 * N);
}

static void extra_list_copy(const bs_bsr *A, int32_t *ij, double *val) {
  memcpy(ij, A->extra_ij, 2 * (size_t)A->n_extra * sizeof *ij);
  memcpy(val, A->extra_val, 9 * (size_t)A->n_extra * sizeof *val);
}

/* A's list is ij/val stably sorted by row. */
static void assert_sorted_copy(const bs_bsr *A, const int32_t *ij, const double *val) {
  int64_t k = 0;
  for (int32_t i = 0; i < A->n; ++i) {
    cr_assert_eq(A->extra_ptr[i], k, "row %d starts at %d, not %lld", i, A->extra_ptr[i], (long long)k);
    for (int64_t e = 0; e < A->n_extra; ++e)
      if (ij[2 * e] == i) {
        cr_assert(A->extra_ij[2 * k] == i && A->extra_ij[2 * k + 1] == ij[2 * e + 1], "position %lld", (long long)k);
        cr_assert_eq(memcmp(A->extra_val + 9 * k, val + 9 * e, 9 * sizeof *val), 0, "position %lld", (long long)k);
        ++k;
      }
  }
  cr_assert_eq(k, A->n_extra);
}

Test(bsr, indexed_extras_keep_every_product) {
  int32_t *ptr, *adj;
  const int32_t n = 3000, ne = 4000;
  random_graph(n, 6, &ptr, &adj);
  bs_bsr *A = NULL;
  bs_error err = {0};
  cr_assert_eq(bs_bsr_create(n, ptr, adj, &A, &err), 0, "%s", err.msg);
  fill_random(A);
  cr_assert_eq(bs_bsr_reserve_extra(A, ne + 1, &err), 0, "%s", err.msg);
  double B[9];
  while (A->n_extra < ne) { /* rows and columns at random, duplicates included */
    const int32_t i = (int32_t)((urand() + 1.0) * 0.5 * n) % n, j = (int32_t)((urand() + 1.0) * 0.25 * n) % n;
    for (int e = 0; e < 9; ++e) B[e] = urand();
    if (i != j && bs_bsr_slot(A, i, j) < 0) cr_assert_eq(bs_bsr_add_block(A, i, j, B), BS_BSR_EXTRA);
  }
  const int64_t N = 3 * (int64_t)n;
  double *x = malloc(N * sizeof *x), *y0 = malloc(4 * N * sizeof *y0), *y1 = malloc(4 * N * sizeof *y1);
  float *v32 = malloc((size_t)bs_bsr_val32_count(A) * sizeof *v32);
  int32_t *ij = malloc(2 * (size_t)ne * sizeof *ij);
  double *val = malloc(9 * (size_t)ne * sizeof *val);
  uint8_t *mask = malloc((size_t)n);
  for (int64_t k = 0; k < N; ++k) x[k] = urand();
  for (int32_t i = 0; i < n; ++i) mask[i] = (uint8_t)(i % 7 != 3);
  extra_list_copy(A, ij, val);
  const int nt = omp_get_max_threads();
  for (int masked = 0; masked < 2; ++masked) {
    double d0[3], d1[3];
    A->n_indexed = -1; /* not indexed (the first pass: in list order; the second: sorted already) */
    omp_set_num_threads(1);
    products(A, masked ? mask : NULL, x, y0, v32, d0);
    bs_bsr_index_extra(A);
    omp_set_num_threads(3);
    products(A, masked ? mask : NULL, x, y1, v32, d1);
    omp_set_num_threads(nt);
    cr_assert_eq(memcmp(y0, y1, 4 * N * sizeof *y0), 0, "masked %d: the indexed products differ", masked);
    cr_assert_eq(memcmp(d0, d1, sizeof d0), 0, "masked %d: the dots differ", masked);
  }
  assert_sorted_copy(A, ij, val);
  /* the block added after the index enters the product */
  bs_bsr_index_extra(A);
  bs_bsr_mul(A, NULL, x, y0);
  for (int e = 0; e < 9; ++e) B[e] = 0.0;
  B[0] = 1.0;
  cr_assert_eq(bs_bsr_add_block(A, 0, n - 1, B), BS_BSR_EXTRA);
  bs_bsr_mul(A, NULL, x, y1);
  cr_assert(fabs(y1[0] - y0[0] - x[3 * (n - 1)]) <= 1e-14 * (1 + fabs(y1[0])), "%.17g vs %.17g", y1[0] - y0[0],
            x[3 * (n - 1)]);
  /* zero voids the index: as many blocks again (ne + 1), in other rows, not
     indexed */
  bs_bsr_index_extra(A);
  bs_bsr_zero(A);
  cr_assert_eq(A->n_extra, 0);
  bs_bsr_index_extra(A);
  bs_bsr_mul(A, NULL, x, y0);
  for (int64_t k = 0; k < N; ++k) cr_assert_eq(y0[k], 0.0);
  for (int64_t e = ne - 1; e >= 0; --e) cr_assert_eq(bs_bsr_add_block(A, ij[2 * e + 1], ij[2 * e], B), BS_BSR_EXTRA);
  cr_assert_eq(bs_bsr_add_block(A, n - 1, 0, B), BS_BSR_EXTRA);
  cr_assert_eq(A->n_extra, ne + 1);
  bs_bsr_mul(A, NULL, x, y0);
  bs_bsr_index_extra(A);
  bs_bsr_mul(A, NULL, x, y1);
  cr_assert_eq(memcmp(y0, y1, N * sizeof *y0), 0, "a stale index was used after zero");
  free(mask);
  free(val);
  free(ij);
  free(v32);
  free(x);
  free(y0);
  free(y1);
  free(ptr);
  free(adj);
  bs_bsr_destroy(&A);
}
