/* bsr.c — 3x3 block CSR matrices: pattern from a graph, product, checker. */
#include "bs_bsr.h"
#include "bs_sum.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Sorts a short int32 array in place (rows hold tens of entries: insertion
 * sort beats qsort there; long rows fall back to qsort). */

static void sort_i32(int32_t *v, int64_t m) {
  if (m > 32) {
    qsort(v, (size_t)m, sizeof *v, bs_cmp_i32);
    return;
  }
  for (int64_t k = 1; k < m; ++k) {
    int32_t t = v[k];
    int64_t l = k - 1;
    while (l >= 0 && v[l] > t) {
      v[l + 1] = v[l];
      --l;
    }
    v[l + 1] = t;
  }
}

void bs_bsr_destroy(bs_bsr **A) {
  if (!A || !*A) return;
  free((*A)->row_ptr);
  free((*A)->col);
  free((*A)->diag);
  free((*A)->val);
  free((*A)->extra_ij);
  free((*A)->extra_val);
  free((*A)->extra_ptr);
  free((*A)->extra_perm);
  free(*A);
  *A = NULL;
}

int bs_bsr_create(int32_t n, const int32_t *adj_ptr, const int32_t *adj, bs_bsr **out,
                  bs_error *err) {
  if (!out) return bs_error_set(err, BS_EINPUT, "bs_bsr_create: out is NULL");
  *out = NULL;
  if (n < 0) return bs_error_set(err, BS_EINPUT, "bs_bsr_create: negative size n = %d", (int)n);
  if (n > 0 && !adj_ptr)
    return bs_error_set(err, BS_EINPUT, "bs_bsr_create: adj_ptr is NULL for n = %d", (int)n);
  /* Validate the graph and bound the number of blocks (degree + diagonal). */
  int64_t bound = 0;
  for (int32_t i = 0; i < n; ++i) {
    if (adj_ptr[i] < 0 || adj_ptr[i + 1] < adj_ptr[i])
      return bs_error_set(err, BS_EINPUT,
                          "bs_bsr_create: adj_ptr not nondecreasing at vertex %d (%d, %d)",
                          (int)i, (int)adj_ptr[i], (int)adj_ptr[i + 1]);
    bound += (int64_t)(adj_ptr[i + 1] - adj_ptr[i]) + 1;
  }
  if (n > 0 && adj_ptr[n] > adj_ptr[0] && !adj)
    return bs_error_set(err, BS_EINPUT, "bs_bsr_create: adj is NULL with %d neighbours",
                        (int)(adj_ptr[n] - adj_ptr[0]));
  for (int32_t i = 0; i < n; ++i)
    for (int32_t k = adj_ptr[i]; k < adj_ptr[i + 1]; ++k)
      if (adj[k] < 0 || adj[k] >= n)
        return bs_error_set(err, BS_EINPUT,
                            "bs_bsr_create: neighbour %d of vertex %d (adj[%d]) out of range [0, %d)",
                            (int)adj[k], (int)i, (int)k, (int)n);
  if (bound > INT32_MAX)
    return bs_error_set(err, BS_EINPUT,
                        "bs_bsr_create: %lld blocks exceed the int32 row_ptr range",
                        (long long)bound);

  bs_bsr *A = bs_calloc(1, sizeof *A, "bs_bsr", err);
  if (!A) return BS_ENOMEM;
  A->n = n;
  A->row_ptr = bs_calloc((size_t)n + 1, sizeof *A->row_ptr, "bs_bsr row_ptr", err);
  A->diag = bs_calloc(n > 0 ? (size_t)n : 1, sizeof *A->diag, "bs_bsr diag", err);
  int32_t *tmp = bs_calloc(bound > 0 ? (size_t)bound : 1, sizeof *tmp, "bs_bsr columns", err);
  if (!A->row_ptr || !A->diag || !tmp) {
    free(tmp);
    bs_bsr_destroy(&A);
    return BS_ENOMEM;
  }
  /* Each row: neighbours plus i, sorted, duplicates merged, compacted in place
   * (the write position never passes the read position). */
  int64_t w = 0, r = 0;
  for (int32_t i = 0; i < n; ++i) {
    int64_t m = (int64_t)(adj_ptr[i + 1] - adj_ptr[i]);
    int32_t *row = tmp + r;
    if (m > 0) memcpy(row, adj + adj_ptr[i], (size_t)m * sizeof *row);
    row[m] = i;
    sort_i32(row, m + 1);
    A->row_ptr[i] = (int32_t)w;
    for (int64_t k = 0; k <= m; ++k) {
      if (k > 0 && row[k] == row[k - 1]) continue;
      if (row[k] == i) A->diag[i] = (int32_t)w;
      tmp[w++] = row[k];
    }
    r += m + 1;
  }
  A->row_ptr[n] = (int32_t)w;
  A->nnzb = w;
  int32_t *shrunk = realloc(tmp, (w > 0 ? (size_t)w : 1) * sizeof *tmp);
  A->col = shrunk ? shrunk : tmp; /* if shrinking fails, keep the larger block */
  A->val = bs_calloc_large(w > 0 ? 9 * (size_t)w : 1, sizeof *A->val, "bs_bsr values", err);
  if (!A->val) {
    bs_bsr_destroy(&A);
    return BS_ENOMEM;
  }
  *out = A;
  return BS_OK;
}

int32_t bs_bsr_slot(const bs_bsr *A, int32_t i, int32_t j) {
  if (!A || i < 0 || i >= A->n || j < 0 || j >= A->n) return -1;
  int32_t lo = A->row_ptr[i], hi = A->row_ptr[i + 1] - 1;
  while (lo <= hi) {
    int32_t mid = lo + (hi - lo) / 2;
    if (A->col[mid] == j) return mid;
    if (A->col[mid] < j)
      lo = mid + 1;
    else
      hi = mid - 1;
  }
  return -1;
}

void bs_bsr_zero(bs_bsr *A) {
  if (!A) return;
  const int32_t n = A->n;
  double *v = A->val;
  const int32_t *rp = A->row_ptr;
  /* Row by row, so that the pages of a row end up near the thread that uses
   * them in the product (first touch). */
#pragma omp parallel for schedule(static) if (n > 4096)
  for (int32_t i = 0; i < n; ++i)
    memset(v + 9 * (int64_t)rp[i], 0, 9 * (size_t)(rp[i + 1] - rp[i]) * sizeof *v);
  A->n_extra = 0;
  A->n_indexed = -1;
}

static void free_extra(bs_bsr *A) {
  free(A->extra_ij);
  free(A->extra_val);
  free(A->extra_ptr);
  free(A->extra_perm);
  A->extra_ij = A->extra_ptr = A->extra_perm = NULL;
  A->extra_val = NULL;
  A->n_extra = A->cap_extra = A->n_indexed = 0;
}

int bs_bsr_reserve_extra(bs_bsr *A, int64_t cap, bs_error *err) {
  if (!A) return bs_error_set(err, BS_EINPUT, "bs_bsr_reserve_extra: matrix is NULL");
  if (cap < 0 || cap > INT32_MAX)
    return bs_error_set(err, BS_EINPUT, "bs_bsr_reserve_extra: cap = %lld is negative or 2^31 or more",
                        (long long)cap);
  free_extra(A);
  if (cap == 0) return BS_OK;
  A->extra_ij = bs_calloc(2 * (size_t)cap, sizeof *A->extra_ij, "bs_bsr extra blocks", err);
  A->extra_val = bs_calloc(9 * (size_t)cap, sizeof *A->extra_val, "bs_bsr extra blocks", err);
  A->extra_perm = bs_calloc((size_t)cap, sizeof *A->extra_perm, "bs_bsr extra blocks", err);
  A->extra_ptr = bs_calloc((size_t)A->n + 1, sizeof *A->extra_ptr, "bs_bsr extra blocks", err);
  if (!A->extra_ij || !A->extra_val || !A->extra_perm || !A->extra_ptr) {
    free_extra(A);
    return BS_ENOMEM;
  }
  A->cap_extra = cap;
  return BS_OK;
}

/* Moves the extras into the order of perm (position k gets the block at
 * perm[k]) by following its cycles; perm is spent (its entries end negative). */
static void permute_extra(bs_bsr *A, int32_t *perm) {
  int32_t *ij = A->extra_ij;
  double *val = A->extra_val;
  for (int32_t k = 0; k < (int32_t)A->n_extra; ++k) {
    if (perm[k] < 0) continue; /* placed */
    int32_t tij[2] = {ij[2 * k], ij[2 * k + 1]};
    double tval[9];
    memcpy(tval, val + 9 * (int64_t)k, sizeof tval);
    for (int32_t cur = k;;) {
      const int32_t src = perm[cur];
      perm[cur] = -1 - src;
      if (src == k) {
        ij[2 * cur] = tij[0], ij[2 * cur + 1] = tij[1];
        memcpy(val + 9 * (int64_t)cur, tval, sizeof tval);
        break;
      }
      ij[2 * cur] = ij[2 * src], ij[2 * cur + 1] = ij[2 * src + 1];
      memcpy(val + 9 * (int64_t)cur, val + 9 * (int64_t)src, sizeof tval);
      cur = src;
    }
  }
}

void bs_bsr_index_extra(bs_bsr *A) {
  if (!A || A->n_extra == 0) return;
  int32_t *ptr = A->extra_ptr, *perm = A->extra_perm;
  memset(ptr, 0, ((size_t)A->n + 1) * sizeof *ptr);
  for (int64_t e = 0; e < A->n_extra; ++e) ptr[A->extra_ij[2 * e] + 1]++;
  for (int32_t i = 0; i < A->n; ++i) ptr[i + 1] += ptr[i];
  for (int64_t e = 0; e < A->n_extra; ++e) perm[ptr[A->extra_ij[2 * e]]++] = (int32_t)e; /* ptr[i]: row i's end */
  for (int32_t i = A->n; i > 0; --i) ptr[i] = ptr[i - 1];
  ptr[0] = 0;
  permute_extra(A, perm);
  A->n_indexed = A->n_extra;
}

const char *bs_bsr_placement_name(bs_bsr_placement p) {
  return p == BS_BSR_SLOT ? "slot" : p == BS_BSR_EXTRA ? "extra" : p == BS_BSR_DROPPED ? "dropped" : "?";
}

bs_bsr_placement bs_bsr_add_block(bs_bsr *A, int32_t i, int32_t j, const double B[9]) {
  const int32_t s = i == j && i >= 0 && i < A->n ? A->diag[i] : bs_bsr_slot(A, i, j);
  if (s >= 0) {
    double *a = A->val + 9 * (int64_t)s;
    for (int e = 0; e < 9; ++e) a[e] += B[e];
    return BS_BSR_SLOT;
  }
  if (i < 0 || i >= A->n || j < 0 || j >= A->n || A->n_extra >= A->cap_extra) return BS_BSR_DROPPED;
  const int64_t e = A->n_extra++;
  A->n_indexed = -1; /* the index, if any, misses this block */
  A->extra_ij[2 * e] = i;
  A->extra_ij[2 * e + 1] = j;
  memcpy(A->extra_val + 9 * e, B, 9 * sizeof *B);
  return BS_BSR_EXTRA;
}

/* y_i (3 doubles) += A's extra block e times x_j (block (i, j)), unless
 * column j is masked. */
static inline __attribute__((always_inline)) void add_extra(const bs_bsr *A, const uint8_t *mask, const double *x,
                                                            int64_t e, double *yi) {
  const int32_t j = A->extra_ij[2 * e + 1];
  if (mask && !mask[j]) return;
  const double *a = A->extra_val + 9 * e, *xj = x + 3 * (int64_t)j;
  yi[0] += a[0] * xj[0] + a[1] * xj[1] + a[2] * xj[2];
  yi[1] += a[3] * xj[0] + a[4] * xj[1] + a[5] * xj[2];
  yi[2] += a[6] * xj[0] + a[7] * xj[1] + a[8] * xj[2];
}

/* Whether the extras go row by row: the list is indexed (bs_bsr_index_extra). */
static inline int rows_have_extra(const bs_bsr *A) { return A->n_extra > 0 && A->n_indexed == A->n_extra; }

/* Whether row i has extras to add in the row loop. */
static inline int extra_of(const bs_bsr *A, int32_t i) {
  return rows_have_extra(A) && A->extra_ptr[i + 1] > A->extra_ptr[i];
}

/* y_i += row i's extras (consecutive in the indexed list), in list order (row
 * i is free: the caller zeroes a constrained one). Not inlined, so that its
 * arithmetic is serial_extra's (no contraction into the AVX2 callers' FMA). */
static __attribute__((noinline)) void row_extra(const bs_bsr *A, const uint8_t *mask, const double *x, int32_t i,
                                                double *yi) {
  for (int32_t e = A->extra_ptr[i]; e < A->extra_ptr[i + 1]; ++e) add_extra(A, mask, x, e, yi);
}

/* The extras of a list that is not indexed: serially, in list order, after
 * the rows (a masked row's y_i is 0 and stays so). */
static void serial_extra(const bs_bsr *A, const uint8_t *mask, const double *x, double *y) {
  if (A->n_extra == 0 || rows_have_extra(A)) return;
  for (int64_t e = 0; e < A->n_extra; ++e) {
    const int32_t i = A->extra_ij[2 * e];
    if (!mask || mask[i]) add_extra(A, mask, x, e, y + 3 * (int64_t)i);
  }
}

/* The dot of a product with extra blocks: a separate pass over the 3n
 * entries (the row loops fuse it only when there are none). */
static double mul_tail(const bs_bsr *A, const uint8_t *mask, const double *x, double *y, double xy) {
  if (A->n_extra == 0) return xy;
  serial_extra(A, mask, x, y);
  const int64_t N = 3 * (int64_t)A->n;
  double part[BS_SUM_CHUNKS];
  const bs_sum_plan P = bs_sum_plan_of(N);
#pragma omp parallel for schedule(static) if (N > 16384)
  for (int c = 0; c < P.count; ++c) {
    double s = 0.0;
    for (int64_t m = bs_sum_lo(P, c); m < bs_sum_hi(P, c); ++m) s += (mask && !mask[m / 3]) ? 0.0 : x[m] * y[m];
    part[c] = s;
  }
  return bs_sum_parts(P.count, part);
}

/* Row i of y = A x; returns x_i . y_i when fuse, else 0. */
static inline __attribute__((always_inline)) double row_plain(const bs_bsr *A, const double *x, double *y,
                                                              int fuse, int32_t i) {
  const int32_t *rp = A->row_ptr, *col = A->col;
  const double *val = A->val;
  double y0 = 0.0, y1 = 0.0, y2 = 0.0;
  for (int32_t s = rp[i]; s < rp[i + 1]; ++s) {
    const double *a = val + 9 * (int64_t)s;
    const double *xj = x + 3 * (int64_t)col[s];
    const double x0 = xj[0], x1 = xj[1], x2 = xj[2];
    y0 += a[0] * x0 + a[1] * x1 + a[2] * x2;
    y1 += a[3] * x0 + a[4] * x1 + a[5] * x2;
    y2 += a[6] * x0 + a[7] * x1 + a[8] * x2;
  }
  if (extra_of(A, i)) {
    double t[3] = {y0, y1, y2};
    row_extra(A, NULL, x, i, t);
    y0 = t[0], y1 = t[1], y2 = t[2];
  }
  y[3 * (int64_t)i] = y0;
  y[3 * (int64_t)i + 1] = y1;
  y[3 * (int64_t)i + 2] = y2;
  if (!fuse) return 0.0;
  return x[3 * (int64_t)i] * y0 + x[3 * (int64_t)i + 1] * y1 + x[3 * (int64_t)i + 2] * y2;
}

/* The same, masked: written without data-dependent branches (selects
 * instead), because a mispredicted branch on a scattered mask flushes the
 * loads in flight and halves the bandwidth; constrained rows are computed and
 * then dropped. Selects (not multiplications by 0/1) keep the contract exact:
 * the blocks of constrained columns never enter the sum, even if they hold
 * NaN. Returns 0 for a constrained row (0 * x_i is NaN for a non-finite x_i). */
static inline __attribute__((always_inline)) double row_masked(const bs_bsr *A, const uint8_t *mask, const double *x,
                                                               double *y, int fuse, int32_t i) {
  const int32_t *rp = A->row_ptr, *col = A->col;
  const double *val = A->val;
  double y0 = 0.0, y1 = 0.0, y2 = 0.0;
  for (int32_t s = rp[i]; s < rp[i + 1]; ++s) {
    const int32_t j = col[s];
    const double *a = val + 9 * (int64_t)s;
    const double *xj = x + 3 * (int64_t)j;
    const double x0 = xj[0], x1 = xj[1], x2 = xj[2];
    const double t0 = a[0] * x0 + a[1] * x1 + a[2] * x2;
    const double t1 = a[3] * x0 + a[4] * x1 + a[5] * x2;
    const double t2 = a[6] * x0 + a[7] * x1 + a[8] * x2;
    const int f = mask[j] != 0;
    y0 = f ? y0 + t0 : y0;
    y1 = f ? y1 + t1 : y1;
    y2 = f ? y2 + t2 : y2;
  }
  const int f = mask[i] != 0;
  if (f && extra_of(A, i)) {
    double t[3] = {y0, y1, y2};
    row_extra(A, mask, x, i, t);
    y0 = t[0], y1 = t[1], y2 = t[2];
  }
  y0 = f ? y0 : 0.0;
  y1 = f ? y1 : 0.0;
  y2 = f ? y2 : 0.0;
  y[3 * (int64_t)i] = y0;
  y[3 * (int64_t)i + 1] = y1;
  y[3 * (int64_t)i + 2] = y2;
  if (!fuse) return 0.0;
  return f ? x[3 * (int64_t)i] * y0 + x[3 * (int64_t)i + 1] * y1 + x[3 * (int64_t)i + 2] * y2 : 0.0;
}

#if defined(__GNUC__) && defined(__x86_64__)
#include <immintrin.h>
#define BS_BSR_AVX2 1
/* Row i of y = A x with AVX2 and FMA, masked or not as row_plain and
 * row_masked: acc_r gathers, lane by lane, a_r0 x0, a_r1 x1, a_r2 x2 of
 * block row r over the row's blocks (lane 3 reads the next entry of val,
 * times x_j's lane 3, which the masked load makes 0; the last block's third
 * row is a masked load too, so nothing past val is read), and the lanes 0-2
 * are summed at the end; y_i is written by a masked store (never the next
 * row's entries, which another thread may own). With val32, each block is
 * also written there rounded to float (bs_bsr_mul_dot_round32's layout). */
__attribute__((target("avx2,fma"), always_inline)) static inline double row_avx2(const bs_bsr *A, const uint8_t *mask,
                                                                               const double *x, double *y, int fuse,
                                                                               float *val32, int32_t i) {
  const int32_t *rp = A->row_ptr, *col = A->col;
  const double *val = A->val;
  const __m256i m3 = _mm256_set_epi64x(0, -1, -1, -1);
  const int64_t last = A->nnzb - 1;
  __m256d acc0 = _mm256_setzero_pd(), acc1 = acc0, acc2 = acc0;
  for (int32_t s = rp[i]; s < rp[i + 1]; ++s) {
    const int32_t j = col[s];
    const double *a = val + 9 * (int64_t)s;
    if (val32)
      for (int b = 0; b < 3; ++b)
        for (int e = 0; e < 3; ++e) val32[9 * (int64_t)s + 3 * b + e] = (float)a[3 * e + b];
    const __m256d xv = _mm256_maskload_pd(x + 3 * (int64_t)j, m3);
    const __m256d a2 = s < last ? _mm256_loadu_pd(a + 6) : _mm256_maskload_pd(a + 6, m3);
    if (!mask) {
      acc0 = _mm256_fmadd_pd(_mm256_loadu_pd(a), xv, acc0);
      acc1 = _mm256_fmadd_pd(_mm256_loadu_pd(a + 3), xv, acc1);
      acc2 = _mm256_fmadd_pd(a2, xv, acc2);
    } else { /* a constrained column's block never enters, even if it holds NaN */
      const __m256d keep = _mm256_castsi256_pd(_mm256_set1_epi64x(mask[j] ? -1 : 0));
      acc0 = _mm256_add_pd(acc0, _mm256_and_pd(_mm256_mul_pd(_mm256_loadu_pd(a), xv), keep));
      acc1 = _mm256_add_pd(acc1, _mm256_and_pd(_mm256_mul_pd(_mm256_loadu_pd(a + 3), xv), keep));
      acc2 = _mm256_add_pd(acc2, _mm256_and_pd(_mm256_mul_pd(a2, xv), keep));
    }
  }
  const __m256d z = _mm256_setzero_pd();
  acc0 = _mm256_blend_pd(acc0, z, 8);
  acc1 = _mm256_blend_pd(acc1, z, 8);
  acc2 = _mm256_blend_pd(acc2, z, 8);
  const __m256d h01 = _mm256_hadd_pd(acc0, acc1), h22 = _mm256_hadd_pd(acc2, acc2);
  __m256d r = _mm256_add_pd(_mm256_permute2f128_pd(h01, h22, 0x20), _mm256_permute2f128_pd(h01, h22, 0x31));
  const int f = !mask || mask[i] != 0;
  if (!f) r = z;
  if (f && extra_of(A, i)) {
    double t[4];
    _mm256_storeu_pd(t, r);
    row_extra(A, mask, x, i, t);
    r = _mm256_loadu_pd(t);
  }
  _mm256_maskstore_pd(y + 3 * (int64_t)i, m3, r);
  if (!fuse || !f) return 0.0;
  double yi[4];
  _mm256_storeu_pd(yi, r);
  return x[3 * (int64_t)i] * yi[0] + x[3 * (int64_t)i + 1] * yi[1] + x[3 * (int64_t)i + 2] * yi[2];
}

/* mul_impl's row loop with row_avx2 (mask and val32 tested once, outside). */
__attribute__((target("avx2,fma"))) static void rows_avx2(const bs_bsr *A, const uint8_t *mask, const double *x,
                                                         double *y, int fuse, float *val32, double *part) {
  const bs_sum_plan P = bs_sum_plan_of(A->n);
#pragma omp parallel for schedule(static) if (A->n > 4096)
  for (int c = 0; c < P.count; ++c) {
    const int32_t lo = (int32_t)bs_sum_lo(P, c), hi = (int32_t)bs_sum_hi(P, c);
    double xy = 0.0;
    if (!mask && !val32)
      for (int32_t i = lo; i < hi; ++i) xy += row_avx2(A, NULL, x, y, fuse, NULL, i);
    else if (!val32)
      for (int32_t i = lo; i < hi; ++i) xy += row_avx2(A, mask, x, y, fuse, NULL, i);
    else if (!mask)
      for (int32_t i = lo; i < hi; ++i) xy += row_avx2(A, NULL, x, y, fuse, val32, i);
    else
      for (int32_t i = lo; i < hi; ++i) xy += row_avx2(A, mask, x, y, fuse, val32, i);
    part[c] = xy;
  }
}

/* bs_bsr_mul_dot_round32's AVX2 path: 0 when the CPU lacks AVX2 or FMA (the
 * caller then takes the portable one), else 1 with *xy set. */
static int round32_avx2(const bs_bsr *A, const uint8_t *mask, const double *x, double *y, float *val32, double *xy) {
  if (A->nnzb == 0 || !__builtin_cpu_supports("avx2") || !__builtin_cpu_supports("fma")) return 0;
  const int fuse = A->n_extra == 0;
  double part[BS_SUM_CHUNKS];
  rows_avx2(A, mask, x, y, fuse, val32, part);
  *xy = mul_tail(A, mask, x, y, fuse ? bs_sum_parts(bs_sum_plan_of(A->n).count, part) : 0.0);
  return 1;
}
#endif

/* y = A x, and x . y when dot (the fused dot reads each x_i, y_i while the
 * row is in registers, summed as in bs_sum.h; with extra blocks y changes
 * afterwards, so the dot is then a separate pass). */
static double mul_impl(const bs_bsr *A, const uint8_t *mask, const double *x, double *y, const int dot) {
  const int32_t n = A->n;
  const int fuse = dot && A->n_extra == 0;
  double part[BS_SUM_CHUNKS];
  const bs_sum_plan P = bs_sum_plan_of(n);
#ifdef BS_BSR_AVX2
  if (A->nnzb > 0 && __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma")) {
    rows_avx2(A, mask, x, y, fuse, NULL, part);
  } else
#endif
  {
#pragma omp parallel for schedule(static) if (n > 4096)
    for (int c = 0; c < P.count; ++c) {
      const int32_t lo = (int32_t)bs_sum_lo(P, c), hi = (int32_t)bs_sum_hi(P, c);
      double xy = 0.0;
      if (!mask)
        for (int32_t i = lo; i < hi; ++i) xy += row_plain(A, x, y, fuse, i);
      else
        for (int32_t i = lo; i < hi; ++i) xy += row_masked(A, mask, x, y, fuse, i);
      part[c] = xy;
    }
  }
  if (!dot) {
    serial_extra(A, mask, x, y);
    return 0.0;
  }
  return mul_tail(A, mask, x, y, fuse ? bs_sum_parts(P.count, part) : 0.0);
}

void bs_bsr_mul(const bs_bsr *A, const uint8_t *mask, const double *x, double *y) { (void)mul_impl(A, mask, x, y, 0); }

double bs_bsr_mul_dot(const bs_bsr *A, const uint8_t *mask, const double *x, double *y) {
  return mul_impl(A, mask, x, y, 1);
}

/* ---- single-precision values (bs_bsr_mul_dot_round32, bs_bsr_mul_dot32) ----
 * val32 holds each block column-major: val32[9 s + 3 b + a] = A(3i+a, 3j+b),
 * so that column b of a block is 3 consecutive floats, and 4 floats of padding
 * at the end. One product is then, per block, three 4-float loads widened to
 * double and three fused multiply-adds with x_j's broadcast components (lane
 * 3 of each load is the next column's first entry, multiplied and dropped).
 * The OpenMP regions are in separate functions with constant arguments: GCC
 * outlines a parallel region before it inlines, so a region inside an
 * always_inline function would test its arguments in the inner loop. */

int64_t bs_bsr_val32_count(const bs_bsr *A) { return 9 * A->nnzb + 4; }

/* The row loop over blocks, masked or not (selects as in row_masked), with
 * BLOCK(s, j, t0, t1, t2) computing the block's product into t0..t2. */
#define BS_ROWS32(BLOCK)                                                                               \
  const int32_t n = A->n;                                                                              \
  const int32_t *rp = A->row_ptr, *col = A->col;                                                       \
  const int fuse = A->n_extra == 0;                                                                    \
  double part[BS_SUM_CHUNKS];                                                                          \
  const bs_sum_plan P = bs_sum_plan_of(n);                                                             \
  _Pragma("omp parallel for schedule(static) if (n > 4096)")                                           \
  for (int c = 0; c < P.count; ++c) {                                                                  \
    double xy = 0.0;                                                                                   \
    for (int32_t i = (int32_t)bs_sum_lo(P, c); i < (int32_t)bs_sum_hi(P, c); ++i) {                    \
      double y0 = 0.0, y1 = 0.0, y2 = 0.0;                                                             \
      for (int32_t s = rp[i]; s < rp[i + 1]; ++s) {                                                    \
        const int32_t j = col[s];                                                                      \
        double t0, t1, t2;                                                                             \
        BLOCK(s, j, t0, t1, t2);                                                                       \
        const int f = !mask || mask[j] != 0;                                                           \
        y0 = f ? y0 + t0 : y0;                                                                         \
        y1 = f ? y1 + t1 : y1;                                                                         \
        y2 = f ? y2 + t2 : y2;                                                                         \
      }                                                                                                \
      const int f = !mask || mask[i] != 0;                                                             \
      if (f && extra_of(A, i)) {                                                                  \
        double t_[3] = {y0, y1, y2};                                                                   \
        row_extra(A, mask, x, i, t_);                                                                  \
        y0 = t_[0], y1 = t_[1], y2 = t_[2];                                                            \
      }                                                                                                \
      y0 = f ? y0 : 0.0;                                                                               \
      y1 = f ? y1 : 0.0;                                                                               \
      y2 = f ? y2 : 0.0;                                                                               \
      y[3 * (int64_t)i] = y0;                                                                          \
      y[3 * (int64_t)i + 1] = y1;                                                                      \
      y[3 * (int64_t)i + 2] = y2;                                                                      \
      if (fuse) xy += f ? x[3 * (int64_t)i] * y0 + x[3 * (int64_t)i + 1] * y1 + x[3 * (int64_t)i + 2] * y2 : 0.0; \
    }                                                                                                  \
    part[c] = xy;                                                                                      \
  }                                                                                                    \
  return mul_tail(A, mask, x, y, fuse ? bs_sum_parts(P.count, part) : 0.0)

/* double values, rounded into val32 on the way */
#define BS_BLOCK_ROUND(s, j, t0, t1, t2)                                                               \
  const double *a = A->val + 9 * (int64_t)(s), *xj = x + 3 * (int64_t)(j);                             \
  float *c = val32 + 9 * (int64_t)(s);                                                                 \
  for (int b_ = 0; b_ < 3; ++b_)                                                                       \
    for (int a_ = 0; a_ < 3; ++a_) c[3 * b_ + a_] = (float)a[3 * a_ + b_];                             \
  t0 = a[0] * xj[0] + a[1] * xj[1] + a[2] * xj[2];                                                     \
  t1 = a[3] * xj[0] + a[4] * xj[1] + a[5] * xj[2];                                                     \
  t2 = a[6] * xj[0] + a[7] * xj[1] + a[8] * xj[2]

/* single values, scalar */
#define BS_BLOCK_32(s, j, t0, t1, t2)                                                                  \
  const float *c = val32 + 9 * (int64_t)(s);                                                           \
  const double *xj = x + 3 * (int64_t)(j);                                                             \
  const double x0 = xj[0], x1 = xj[1], x2 = xj[2];                                                     \
  t0 = (double)c[0] * x0 + (double)c[3] * x1 + (double)c[6] * x2;                                      \
  t1 = (double)c[1] * x0 + (double)c[4] * x1 + (double)c[7] * x2;                                      \
  t2 = (double)c[2] * x0 + (double)c[5] * x1 + (double)c[8] * x2

double bs_bsr_mul_dot_round32(const bs_bsr *A, const uint8_t *mask, const double *x, double *y, float *val32) {
  val32[9 * A->nnzb] = val32[9 * A->nnzb + 1] = val32[9 * A->nnzb + 2] = val32[9 * A->nnzb + 3] = 0.0f;
#ifdef BS_BSR_AVX2
  double xy;
  if (round32_avx2(A, mask, x, y, val32, &xy)) return xy; /* bs_bsr_mul_dot's arithmetic, bit for bit */
#endif
  BS_ROWS32(BS_BLOCK_ROUND);
}

static double mul32_scalar(const bs_bsr *A, const float *val32, const uint8_t *mask, const double *x, double *y) {
  BS_ROWS32(BS_BLOCK_32);
}

#if defined(__GNUC__) && defined(__x86_64__)
#include <immintrin.h>
/* Row i of the product into y; returns x_i . y_i (0 when not fuse or row i is
 * constrained). */
__attribute__((target("avx2,fma"), always_inline)) static inline double row32_avx2(const bs_bsr *A, const float *val32,
                                                                                 const uint8_t *mask, const double *x,
                                                                                 double *y, int fuse, int32_t i) {
  const int32_t *rp = A->row_ptr, *col = A->col;
  __m256d acc = _mm256_setzero_pd();
  if (!mask) {
    for (int32_t s = rp[i]; s < rp[i + 1]; ++s) {
      const float *c = val32 + 9 * (int64_t)s;
      const double *xj = x + 3 * (int64_t)col[s];
      acc = _mm256_fmadd_pd(_mm256_cvtps_pd(_mm_loadu_ps(c)), _mm256_broadcast_sd(xj), acc);
      acc = _mm256_fmadd_pd(_mm256_cvtps_pd(_mm_loadu_ps(c + 3)), _mm256_broadcast_sd(xj + 1), acc);
      acc = _mm256_fmadd_pd(_mm256_cvtps_pd(_mm_loadu_ps(c + 6)), _mm256_broadcast_sd(xj + 2), acc);
    }
  } else {
    for (int32_t s = rp[i]; s < rp[i + 1]; ++s) {
      const int32_t j = col[s];
      const float *c = val32 + 9 * (int64_t)s;
      const double *xj = x + 3 * (int64_t)j;
      __m256d t = _mm256_mul_pd(_mm256_cvtps_pd(_mm_loadu_ps(c)), _mm256_broadcast_sd(xj));
      t = _mm256_fmadd_pd(_mm256_cvtps_pd(_mm_loadu_ps(c + 3)), _mm256_broadcast_sd(xj + 1), t);
      t = _mm256_fmadd_pd(_mm256_cvtps_pd(_mm_loadu_ps(c + 6)), _mm256_broadcast_sd(xj + 2), t);
      const __m256d keep = _mm256_castsi256_pd(_mm256_set1_epi64x(mask[j] ? -1 : 0));
      acc = _mm256_add_pd(acc, _mm256_and_pd(t, keep));
    }
  }
  double yi[4];
  _mm256_storeu_pd(yi, acc);
  const int f = !mask || mask[i] != 0;
  if (f && extra_of(A, i)) row_extra(A, mask, x, i, yi);
  const double y0 = f ? yi[0] : 0.0, y1 = f ? yi[1] : 0.0, y2 = f ? yi[2] : 0.0;
  y[3 * (int64_t)i] = y0;
  y[3 * (int64_t)i + 1] = y1;
  y[3 * (int64_t)i + 2] = y2;
  return fuse && f ? x[3 * (int64_t)i] * y0 + x[3 * (int64_t)i + 1] * y1 + x[3 * (int64_t)i + 2] * y2 : 0.0;
}

/* The same with AVX2 and FMA: lanes 0-2 of acc are y_i's three entries. The
 * mask select is an and with all-ones or all-zeros lanes (a NaN of a
 * constrained column's block never enters). */
__attribute__((target("avx2,fma"))) static double mul32_avx2(const bs_bsr *A, const float *val32,
                                                             const uint8_t *mask, const double *x, double *y) {
  const int32_t n = A->n;
  const int fuse = A->n_extra == 0;
  double part[BS_SUM_CHUNKS];
  const bs_sum_plan P = bs_sum_plan_of(n);
#pragma omp parallel for schedule(static) if (n > 4096)
  for (int c = 0; c < P.count; ++c) {
    double xy = 0.0;
    for (int32_t i = (int32_t)bs_sum_lo(P, c); i < (int32_t)bs_sum_hi(P, c); ++i)
      xy += row32_avx2(A, val32, mask, x, y, fuse, i);
    part[c] = xy;
  }
  return mul_tail(A, mask, x, y, fuse ? bs_sum_parts(P.count, part) : 0.0);
}
#endif

double bs_bsr_mul_dot32(const bs_bsr *A, const float *val32, const uint8_t *mask, const double *x, double *y) {
#if defined(__GNUC__) && defined(__x86_64__)
  if (__builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma")) return mul32_avx2(A, val32, mask, x, y);
#endif
  return mul32_scalar(A, val32, mask, x, y);
}
#undef BS_ROWS32
#undef BS_BLOCK_ROUND
#undef BS_BLOCK_32

/* The extra list: indices, finiteness, and symmetry of the summed blocks. */
static int check_extra(const bs_bsr *A, double tol, double amax, bs_error *err) {
  if (A->n_extra < 0 || A->n_extra > A->cap_extra || (A->n_extra > 0 && (!A->extra_ij || !A->extra_val)))
    return bs_error_set(err, BS_EINPUT, "bs_bsr_check: extra list holds %lld blocks with room for %lld",
                        (long long)A->n_extra, (long long)A->cap_extra);
  for (int64_t e = 0; e < A->n_extra; ++e) {
    const int32_t i = A->extra_ij[2 * e], j = A->extra_ij[2 * e + 1];
    if (i < 0 || i >= A->n || j < 0 || j >= A->n || i == j)
      return bs_error_set(err, BS_EINPUT, "bs_bsr_check: extra block %lld is (%d,%d): out of range or diagonal",
                          (long long)e, (int)i, (int)j);
    for (int k = 0; k < 9; ++k) {
      const double v = A->extra_val[9 * e + k];
      if (!isfinite(v))
        return bs_error_set(err, BS_ENUMERIC, "bs_bsr_check: extra block (%d,%d) entry (%d,%d) is not finite (%g)",
                            (int)i, (int)j, k / 3, k % 3, v);
      if (fabs(v) > amax) amax = fabs(v);
    }
  }
  const double bound = tol * amax;
  for (int64_t e = 0; e < A->n_extra; ++e) {
    const int32_t i = A->extra_ij[2 * e], j = A->extra_ij[2 * e + 1];
    double s[9] = {0}, t[9] = {0};
    for (int64_t f = 0; f < A->n_extra; ++f) {
      const int32_t p = A->extra_ij[2 * f], q = A->extra_ij[2 * f + 1];
      const double *b = A->extra_val + 9 * f;
      if (p == i && q == j)
        for (int k = 0; k < 9; ++k) s[k] += b[k];
      if (p == j && q == i)
        for (int k = 0; k < 9; ++k) t[k] += b[k];
    }
    for (int p = 0; p < 3; ++p)
      for (int q = 0; q < 3; ++q)
        if (fabs(s[3 * p + q] - t[3 * q + p]) > bound)
          return bs_error_set(err, BS_EINPUT,
                              "bs_bsr_check: extra blocks (%d,%d) entry (%d,%d) = %.17g differ from the transpose of "
                              "extra blocks (%d,%d) (%.17g)",
                              (int)i, (int)j, p, q, s[3 * p + q], (int)j, (int)i, t[3 * q + p]);
  }
  return BS_OK;
}

int bs_bsr_check(const bs_bsr *A, double tol, bs_error *err) {
  if (!A) return bs_error_set(err, BS_EINPUT, "bs_bsr_check: matrix is NULL");
  const int32_t n = A->n;
  if (n < 0) return bs_error_set(err, BS_EINPUT, "bs_bsr_check: negative size n = %d", (int)n);
  if (!A->row_ptr || !A->col || !A->diag || !A->val)
    return bs_error_set(err, BS_EINPUT, "bs_bsr_check: an array of the matrix is NULL");
  if (A->row_ptr[0] != 0)
    return bs_error_set(err, BS_EINPUT, "bs_bsr_check: row_ptr[0] = %d, expected 0",
                        (int)A->row_ptr[0]);
  if ((int64_t)A->row_ptr[n] != A->nnzb)
    return bs_error_set(err, BS_EINPUT, "bs_bsr_check: row_ptr[n] = %d but nnzb = %lld",
                        (int)A->row_ptr[n], (long long)A->nnzb);
  /* Structure: rows monotone, columns in range and strictly increasing, diag. */
  for (int32_t i = 0; i < n; ++i) {
    if (A->row_ptr[i + 1] < A->row_ptr[i])
      return bs_error_set(err, BS_EINPUT, "bs_bsr_check: row_ptr decreases at block row %d",
                          (int)i);
    for (int32_t s = A->row_ptr[i]; s < A->row_ptr[i + 1]; ++s) {
      const int32_t j = A->col[s];
      if (j < 0 || j >= n)
        return bs_error_set(err, BS_EINPUT,
                            "bs_bsr_check: block (%d,%d) at slot %d: column out of range [0, %d)",
                            (int)i, (int)j, (int)s, (int)n);
      if (s > A->row_ptr[i] && A->col[s - 1] >= j)
        return bs_error_set(err, BS_EINPUT,
                            "bs_bsr_check: block (%d,%d) at slot %d: columns not strictly "
                            "increasing (previous column %d)",
                            (int)i, (int)j, (int)s, (int)A->col[s - 1]);
    }
    const int32_t d = A->diag[i];
    if (d < A->row_ptr[i] || d >= A->row_ptr[i + 1] || A->col[d] != i)
      return bs_error_set(err, BS_EINPUT,
                          "bs_bsr_check: block (%d,%d): diagonal block missing or diag[%d] = %d "
                          "wrong",
                          (int)i, (int)i, (int)i, (int)d);
  }
  /* Values finite; the largest magnitude sets the symmetry scale. */
  double amax = 0.0;
  for (int32_t i = 0; i < n; ++i)
    for (int32_t s = A->row_ptr[i]; s < A->row_ptr[i + 1]; ++s)
      for (int e = 0; e < 9; ++e) {
        const double v = A->val[9 * (int64_t)s + e];
        if (!isfinite(v))
          return bs_error_set(err, BS_ENUMERIC,
                              "bs_bsr_check: block (%d,%d) entry (%d,%d) is not finite (%g)",
                              (int)i, (int)A->col[s], e / 3, e % 3, v);
        if (fabs(v) > amax) amax = fabs(v);
      }
  /* Pattern and values symmetric: A_ij == A_ji^T within tol * max|A|. */
  const double bound = tol * amax;
  for (int32_t i = 0; i < n; ++i)
    for (int32_t s = A->row_ptr[i]; s < A->row_ptr[i + 1]; ++s) {
      const int32_t j = A->col[s];
      const int32_t t = bs_bsr_slot(A, j, i);
      if (t < 0)
        return bs_error_set(err, BS_EINPUT,
                            "bs_bsr_check: block (%d,%d) is stored but block (%d,%d) is not "
                            "(pattern not symmetric)",
                            (int)i, (int)j, (int)j, (int)i);
      if (j < i) continue; /* values: each pair once, the diagonal against itself */
      const double *a = A->val + 9 * (int64_t)s, *b = A->val + 9 * (int64_t)t;
      for (int p = 0; p < 3; ++p)
        for (int q = 0; q < 3; ++q) {
          const double diff = fabs(a[3 * p + q] - b[3 * q + p]);
          if (diff > bound)
            return bs_error_set(err, BS_EINPUT,
                                "bs_bsr_check: block (%d,%d) entry (%d,%d) = %.17g differs from "
                                "block (%d,%d) entry (%d,%d) = %.17g by %g > tol %g * max|A| %g",
                                (int)i, (int)j, p, q, a[3 * p + q], (int)j, (int)i, q, p,
                                b[3 * q + p], diff, tol, amax);
        }
    }
  return check_extra(A, tol, amax, err);
}
