/* bs_vec3.h — the small 3-vector helpers every C module shares: dot, difference,
 * cross product and length of double[3] (geometry in metres, but nothing here
 * has units); and three of 3x3 row-major matrices, double[9] with A[3*r + c]
 * (identity, determinant, column swap) for the small decompositions.
 *
 * Conventions: vectors are plain double[3]; outputs come last and may alias
 * the inputs only where noted. Each helper is one fixed expression, written
 * out term by term in the order below, so that every caller rounds the same
 * way (the results are bit-for-bit those of the open-coded arithmetic they
 * replace). Nothing allocates, prints or fails.
 *
 * The C++ shim (shim/) keeps its own copies: it is built as C++ against CGAL
 * and does not include this header.
 */
#ifndef BS_VEC3_H
#define BS_VEC3_H

#include <math.h>

#ifdef __cplusplus
extern "C" {
#endif

/* a . b = a0 b0 + a1 b1 + a2 b2 (summed left to right). */
static inline double bs_dot3(const double *a, const double *b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

/* o = a - b (o may alias a or b). */
static inline void bs_sub3(const double *a, const double *b, double *o) {
  o[0] = a[0] - b[0];
  o[1] = a[1] - b[1];
  o[2] = a[2] - b[2];
}

/* o = a x b (o must not alias a or b). */
static inline void bs_cross3(const double *a, const double *b, double *o) {
  o[0] = a[1] * b[2] - a[2] * b[1];
  o[1] = a[2] * b[0] - a[0] * b[2];
  o[2] = a[0] * b[1] - a[1] * b[0];
}

/* |a| = sqrt(a . a), no scaling against overflow (as bs_dot3). */
static inline double bs_norm3(const double *a) { return sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]); }

/* |a| scaled by the largest component, so that neither overflows nor
 * underflows for any finite a (1e200 or 1e-200 components); inf or NaN in a
 * gives inf or NaN. */
static inline double bs_norm3_scaled(const double *a) {
  if (!isfinite(a[0]) || !isfinite(a[1]) || !isfinite(a[2])) return fabs(a[0]) + fabs(a[1]) + fabs(a[2]);
  const double m = fmax(fabs(a[0]), fmax(fabs(a[1]), fabs(a[2])));
  if (m == 0) return 0;
  const double b[3] = {a[0] / m, a[1] / m, a[2] / m};
  return m * bs_norm3(b);
}

/* A = I. */
static inline void bs_mat3_identity(double *A) {
  for (int i = 0; i < 9; i++) A[i] = (i % 4 == 0) ? 1.0 : 0.0;
}

/* det A, by the first row's cofactors. */
static inline double bs_mat3_det(const double *A) {
  return A[0] * (A[4] * A[8] - A[5] * A[7]) - A[1] * (A[3] * A[8] - A[5] * A[6]) +
         A[2] * (A[3] * A[7] - A[4] * A[6]);
}

/* Swaps columns i and j of A. */
static inline void bs_mat3_swap_cols(double *A, int i, int j) {
  for (int r = 0; r < 3; r++) {
    const double t = A[3 * r + i];
    A[3 * r + i] = A[3 * r + j];
    A[3 * r + j] = t;
  }
}

/* Sorts key[0..2] descending (a stable bubble sort), swapping the columns of
 * A, and of B when not NULL, with their keys. */
static inline void bs_mat3_sort_cols_desc(double key[3], double *A, double *B) {
  for (int i = 0; i < 2; i++)
    for (int j = 2; j > i; j--)
      if (key[j] > key[j - 1]) {
        const double t = key[j];
        key[j] = key[j - 1];
        key[j - 1] = t;
        bs_mat3_swap_cols(A, j, j - 1);
        if (B) bs_mat3_swap_cols(B, j, j - 1);
      }
}

#ifdef __cplusplus
}
#endif
#endif
