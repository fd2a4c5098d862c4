/* polar_avx2.h — internal to physics/: bs_polar3's constants, and its
 * iteration on 4 matrices in the lanes of AVX2 registers, shared by svd.c
 * (bs_polar3_batch) and element.c (the fused kernels of the corotated
 * models). Each lane does bs_polar3's operations (svd.c) in the same order,
 * without FMA, so it is bs_polar3 bit for bit. */
#ifndef BS_POLAR_AVX2_H
#define BS_POLAR_AVX2_H

/* The iteration ends at the first iterate with |X_new - X|^2 <= POLAR_TOL2.
 * Iterates converge to a rotation (|R|^2 = 3), so this is a relative step of
 * 1e-8, and by the quadratic convergence X_new is exact to rounding. */
#define POLAR_TOL2 3e-16
/* Steps after one with |X_new - X|^2 below this are unscaled (g = 1: no
 * sqrt, no norms), which converge as fast from there (Higham 1986). */
#define POLAR_SCALE2 1e-2
enum { POLAR_MAX_ITERS = 20 };

#if defined(__GNUC__) && defined(__x86_64__)
#define BS_POLAR_AVX2 1
#include <immintrin.h>

#define BS_AVX2_FN __attribute__((target("avx2")))

BS_AVX2_FN static inline __m256d bs_avx2_sel(__m256d m, __m256d a, __m256d b) { return _mm256_blendv_pd(b, a, m); }

/* c = cof(X) (X^-T det X), in bs_polar3's order. */
BS_AVX2_FN static inline void bs_avx2_cof(const __m256d X[9], __m256d c[9]) {
  c[0] = _mm256_sub_pd(_mm256_mul_pd(X[4], X[8]), _mm256_mul_pd(X[5], X[7]));
  c[1] = _mm256_sub_pd(_mm256_mul_pd(X[5], X[6]), _mm256_mul_pd(X[3], X[8]));
  c[2] = _mm256_sub_pd(_mm256_mul_pd(X[3], X[7]), _mm256_mul_pd(X[4], X[6]));
  c[3] = _mm256_sub_pd(_mm256_mul_pd(X[2], X[7]), _mm256_mul_pd(X[1], X[8]));
  c[4] = _mm256_sub_pd(_mm256_mul_pd(X[0], X[8]), _mm256_mul_pd(X[2], X[6]));
  c[5] = _mm256_sub_pd(_mm256_mul_pd(X[1], X[6]), _mm256_mul_pd(X[0], X[7]));
  c[6] = _mm256_sub_pd(_mm256_mul_pd(X[1], X[5]), _mm256_mul_pd(X[2], X[4]));
  c[7] = _mm256_sub_pd(_mm256_mul_pd(X[2], X[3]), _mm256_mul_pd(X[0], X[5]));
  c[8] = _mm256_sub_pd(_mm256_mul_pd(X[0], X[4]), _mm256_mul_pd(X[1], X[3]));
}

/* X: 4 matrices F in lanes (X[i] holds entry i). Lanes in bs_polar3's range
 * end holding R, the others I; returns the mask of the lanes that converged
 * (bs_polar3 returned 1). Call only where the CPU has AVX2. */
BS_AVX2_FN static inline __m256d bs_polar_avx2(__m256d X[9]) {
  typedef __m256d v4;
  const v4 one = _mm256_set1_pd(1.0), zero = _mm256_setzero_pd(), half = _mm256_set1_pd(0.5);
  v4 n2 = zero;
  for (int i = 0; i < 9; i++) n2 = _mm256_add_pd(n2, _mm256_mul_pd(X[i], X[i]));
  const v4 det0 = _mm256_add_pd(
      _mm256_add_pd(_mm256_mul_pd(X[0], _mm256_sub_pd(_mm256_mul_pd(X[4], X[8]), _mm256_mul_pd(X[5], X[7]))),
                    _mm256_mul_pd(X[1], _mm256_sub_pd(_mm256_mul_pd(X[5], X[6]), _mm256_mul_pd(X[3], X[8])))),
      _mm256_mul_pd(X[2], _mm256_sub_pd(_mm256_mul_pd(X[3], X[7]), _mm256_mul_pd(X[4], X[6]))));
  v4 active = _mm256_and_pd(
      _mm256_and_pd(_mm256_cmp_pd(n2, _mm256_set1_pd(1e-30), _CMP_GE_OQ),
                    _mm256_cmp_pd(n2, _mm256_set1_pd(1e30), _CMP_LE_OQ)),
      _mm256_cmp_pd(det0, _mm256_mul_pd(_mm256_set1_pd(1e-9), _mm256_mul_pd(n2, _mm256_sqrt_pd(n2))), _CMP_GT_OQ));
  for (int i = 0; i < 9; i++) X[i] = bs_avx2_sel(active, X[i], i % 4 == 0 ? one : zero);
  v4 done = zero, dd = one; /* dd: each lane's last |X_new - X|^2 */
  for (int it = 0; it < POLAR_MAX_ITERS && _mm256_movemask_pd(active); it++) {
    v4 c[9];
    bs_avx2_cof(X, c);
    const v4 det = _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(X[0], c[0]), _mm256_mul_pd(X[1], c[1])),
                                 _mm256_mul_pd(X[2], c[2]));
    v4 g = one;
    const v4 scaled = _mm256_and_pd(active, _mm256_cmp_pd(dd, _mm256_set1_pd(POLAR_SCALE2), _CMP_GT_OQ));
    if (_mm256_movemask_pd(scaled)) {
      v4 nx = zero, nc = zero;
      for (int i = 0; i < 9; i++) {
        nx = _mm256_add_pd(nx, _mm256_mul_pd(X[i], X[i]));
        nc = _mm256_add_pd(nc, _mm256_mul_pd(c[i], c[i]));
      }
      g = bs_avx2_sel(scaled, _mm256_sqrt_pd(_mm256_sqrt_pd(_mm256_div_pd(nc, _mm256_mul_pd(_mm256_mul_pd(det, det), nx)))),
               one);
    }
    const v4 a = _mm256_mul_pd(half, g), b = _mm256_div_pd(half, _mm256_mul_pd(g, det));
    v4 d2 = zero;
    for (int i = 0; i < 9; i++) {
      const v4 xn = _mm256_add_pd(_mm256_mul_pd(a, X[i]), _mm256_mul_pd(b, c[i]));
      const v4 d = _mm256_sub_pd(xn, X[i]);
      d2 = _mm256_add_pd(d2, _mm256_mul_pd(d, d));
      X[i] = bs_avx2_sel(active, xn, X[i]);
    }
    dd = bs_avx2_sel(active, d2, dd);
    const v4 conv = _mm256_and_pd(active, _mm256_cmp_pd(d2, _mm256_set1_pd(POLAR_TOL2), _CMP_LE_OQ));
    done = _mm256_or_pd(done, conv);
    active = _mm256_andnot_pd(conv, active);
  }
  return done;
}
#endif
#endif
