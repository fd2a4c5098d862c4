/* svd.c — signed 3x3 SVD (one-sided Jacobi) and polar decomposition. See
 * bs_svd.h for the contracts (the symmetric 3x3 eigen-decomposition is
 * base/sym3.c). */
#include "bs_svd.h"
#include "polar_avx2.h"
#include "bs_vec3.h"

#include <float.h>
#include <math.h>
#include <stddef.h>
#include <stdint.h>

enum { SVD_MAX_SWEEPS = 24 };

/* Off-diagonal Gram entries below this multiple of eps |b_p||b_q| count as
 * zero. A dot product of 3-vectors is only computed to ~3 eps, so a bound of
 * one eps could keep rotating on round-off; 8 eps leaves U orthogonal to ~1e-15.
 * Typical F take 3 or 4 sweeps (the last one only checks). */
#define SVD_TOL (8.0 * DBL_EPSILON)

static const int pair_p[3] = {0, 0, 1}, pair_q[3] = {1, 2, 2};

/* One-sided Jacobi: rotates column pairs (p, q) of B = F V (and of V) until
 * they are orthogonal (bs_svd3's scaled B, entries <= 1). */
static void one_sided_jacobi(double B[9], double V[9]) {
  for (int sweep = 0; sweep < SVD_MAX_SWEEPS; sweep++) {
    int rotated = 0;
    for (int k = 0; k < 3; k++) {
      const int p = pair_p[k], q = pair_q[k];
      double a = 0, b = 0, g = 0;
      for (int r = 0; r < 3; r++) {
        a += B[3 * r + p] * B[3 * r + p];
        b += B[3 * r + q] * B[3 * r + q];
        g += B[3 * r + p] * B[3 * r + q];
      }
      if (g * g <= SVD_TOL * SVD_TOL * a * b) continue;
      /* The rotation [c s; -s c] diagonalizes the Gram block [a g; g b]:
       * t = s / c is the smaller root of t^2 + 2 zeta t - 1 = 0, zeta =
       * (b - a) / 2g, i.e. t = 2g sgn(b - a) / D with r = sqrt((b - a)^2 + 4g^2),
       * D = |b - a| + r; and 1 + t^2 = 2 r D / D^2. (Entries are <= 1 after
       * the scaling: nothing overflows; D underflows only for columns below
       * 1e-150, which are then left alone.) */
      const double dab = b - a, r = sqrt(dab * dab + 4.0 * g * g);
      const double D = fabs(dab) + r;
      if (!(D > 0)) continue;
      const double iq = 1.0 / sqrt(2.0 * r * D);
      const double c = D * iq, s = (dab >= 0 ? 2.0 * g : -2.0 * g) * iq;
      for (int r = 0; r < 3; r++) {
        double bp = B[3 * r + p], bq = B[3 * r + q];
        B[3 * r + p] = c * bp - s * bq;
        B[3 * r + q] = s * bp + c * bq;
        double vp = V[3 * r + p], vq = V[3 * r + q];
        V[3 * r + p] = c * vp - s * vq;
        V[3 * r + q] = s * vp + c * vq;
      }
      rotated = 1;
    }
    if (!rotated) break;
  }
}

/* U = [b0/|b0|, Gram-Schmidt of b1 (or any unit vector orthogonal to u0 when
 * b1 vanishes), u0 x u1] from the sorted, oriented columns of B (squared
 * lengths n), and the singular values of B: |b0|, |b1|, u2 . b2 (clamped to
 * |b1|, with the sign of det F). */
static void left_vectors(const double B[9], const double n[3], double U[9], double *s0_out, double *s1_out,
                         double *s2_out) {
  double u0[3], u1[3], u2[3];
  const double s0 = *s0_out = sqrt(n[0]); /* >= 0.5: the column holding fm */
  for (int r = 0; r < 3; r++) u0[r] = B[3 * r] / s0;
  /* u1: b1 made orthogonal to u0 (it already is to ~eps); when b1 is
   * negligible, any unit vector orthogonal to u0. */
  double d = u0[0] * B[1] + u0[1] * B[4] + u0[2] * B[7], nw2 = 0;
  for (int r = 0; r < 3; r++) {
    u1[r] = B[3 * r + 1] - d * u0[r];
    nw2 += u1[r] * u1[r];
  }
  if (!(nw2 > 1e-300)) {
    int k = 0;
    if (fabs(u0[1]) < fabs(u0[k])) k = 1;
    if (fabs(u0[2]) < fabs(u0[k])) k = 2;
    nw2 = 0;
    for (int r = 0; r < 3; r++) {
      u1[r] = (r == k ? 1.0 : 0.0) - u0[k] * u0[r];
      nw2 += u1[r] * u1[r];
    }
  }
  const double inw = 1.0 / sqrt(nw2);
  for (int r = 0; r < 3; r++) u1[r] *= inw;
  u2[0] = u0[1] * u1[2] - u0[2] * u1[1];
  u2[1] = u0[2] * u1[0] - u0[0] * u1[2];
  u2[2] = u0[0] * u1[1] - u0[1] * u1[0];

  const double s1 = *s1_out = sqrt(n[1]);
  double s2 = u2[0] * B[2] + u2[1] * B[5] + u2[2] * B[8];
  if (fabs(s2) > s1) s2 = copysign(s1, s2);
  *s2_out = s2;
  for (int r = 0; r < 3; r++) {
    U[3 * r] = u0[r];
    U[3 * r + 1] = u1[r];
    U[3 * r + 2] = u2[r];
  }
}

void bs_svd3(const double F[9], double U[9], double sigma[3], double V[9]) {
  /* Scale by an exact power of two so that the largest entry is in [0.5, 1). */
  double fm = 0.0, bad = 0.0;
  for (int i = 0; i < 9; i++) {
    const double a = fabs(F[i]);
    if (a > fm) fm = a;
    bad += F[i] - F[i]; /* 0, or NaN when some entry is Inf or NaN */
  }
  if (bad != 0.0 || bad != bad) {
    for (int i = 0; i < 9; i++) U[i] = V[i] = NAN;
    sigma[0] = sigma[1] = sigma[2] = NAN;
    return;
  }
  if (fm == 0.0) {
    bs_mat3_identity(U);
    bs_mat3_identity(V);
    sigma[0] = sigma[1] = sigma[2] = 0.0;
    return;
  }
  int ex;
  frexp(fm, &ex);
  double B[9];
  if (ex > -1000 && ex < 1000) {
    const double sc = ldexp(1.0, -ex);
    for (int i = 0; i < 9; i++) B[i] = F[i] * sc;
  } else
    for (int i = 0; i < 9; i++) B[i] = ldexp(F[i], -ex);
  bs_mat3_identity(V);

  one_sided_jacobi(B, V);

  /* Sort the columns by length, descending. */
  double n[3];
  for (int j = 0; j < 3; j++) n[j] = B[j] * B[j] + B[3 + j] * B[3 + j] + B[6 + j] * B[6 + j];
  bs_mat3_sort_cols_desc(n, B, V);
  /* V a rotation: a reflection moves into the last column (and into sigma2). */
  if (bs_mat3_det(V) < 0.0)
    for (int r = 0; r < 3; r++) {
      V[3 * r + 2] = -V[3 * r + 2];
      B[3 * r + 2] = -B[3 * r + 2];
    }

  double s0, s1, s2;
  left_vectors(B, n, U, &s0, &s1, &s2);
  if (ex > -1000 && ex < 1000) {
    const double sc = ldexp(1.0, ex);
    sigma[0] = s0 * sc;
    sigma[1] = s1 * sc;
    sigma[2] = s2 * sc;
  } else {
    sigma[0] = ldexp(s0, ex);
    sigma[1] = ldexp(s1, ex);
    sigma[2] = ldexp(s2, ex);
  }
}

/* ---- polar rotation (bs_polar3) --------------------------------------------
 * Each helper below has an AVX2 twin that does the same operations in the same
 * order per lane, so that the batch is bit for bit the scalar result. */

/* The range bs_polar3 takes: finite, 1e-30 <= ||F||^2 <= 1e30 and
 * det F > 1e-9 ||F||^3. */
static inline int polar_admissible(const double F[9]) {
  double n2 = 0.0;
  for (int i = 0; i < 9; i++) n2 += F[i] * F[i];
  const double det = (F[0] * (F[4] * F[8] - F[5] * F[7]) + F[1] * (F[5] * F[6] - F[3] * F[8])) +
                     F[2] * (F[3] * F[7] - F[4] * F[6]);
  return n2 >= 1e-30 && n2 <= 1e30 && det > 1e-9 * (n2 * sqrt(n2));
}

/* One Newton step Xn = (g X + cof(X) / (g det X)) / 2, scaled (g as in
 * bs_svd.h) or not (g = 1); returns |Xn - X|^2. */
static inline double polar_step(const double X[9], double Xn[9], int scaled) {
  const double c[9] = {X[4] * X[8] - X[5] * X[7], X[5] * X[6] - X[3] * X[8], X[3] * X[7] - X[4] * X[6],
                       X[2] * X[7] - X[1] * X[8], X[0] * X[8] - X[2] * X[6], X[1] * X[6] - X[0] * X[7],
                       X[1] * X[5] - X[2] * X[4], X[2] * X[3] - X[0] * X[5], X[0] * X[4] - X[1] * X[3]};
  const double det = (X[0] * c[0] + X[1] * c[1]) + X[2] * c[2];
  double g = 1.0;
  if (scaled) {
    double nx = 0.0, nc = 0.0;
    for (int i = 0; i < 9; i++) {
      nx += X[i] * X[i];
      nc += c[i] * c[i];
    }
    g = sqrt(sqrt(nc / ((det * det) * nx)));
  }
  const double a = 0.5 * g, b = 0.5 / (g * det);
  double dd = 0.0;
  for (int i = 0; i < 9; i++) {
    Xn[i] = a * X[i] + b * c[i];
    const double d = Xn[i] - X[i];
    dd += d * d;
  }
  return dd;
}

int bs_polar3(const double F[9], double R[9]) {
  if (!polar_admissible(F)) return 0;
  double X[9], Xn[9], dd = 1.0;
  for (int i = 0; i < 9; i++) X[i] = F[i];
  for (int it = 0; it < POLAR_MAX_ITERS; it++) {
    dd = polar_step(X, Xn, dd > POLAR_SCALE2);
    for (int i = 0; i < 9; i++) X[i] = Xn[i];
    if (dd <= POLAR_TOL2) {
      for (int i = 0; i < 9; i++) R[i] = X[i];
      return 1;
    }
  }
  return 0;
}

/* ---- bs_svd3_batch: bs_svd3 on 4 matrices at a time in AVX2 registers ----
 *
 * The arithmetic of bs_svd3, operation for operation, with the 4 matrices in
 * the 4 lanes of ymm registers (intrinsics; no FMA, so every product and sum
 * is rounded as in the scalar code and the results are bit for bit those of
 * bs_svd3): every "if" of bs_svd3 becomes a select, and a sweep runs while
 * any lane still rotates (a lane whose sweep rotated nothing is unchanged by
 * the next one: it rotates nothing again). Lanes that bs_svd3 treats
 * specially (non-finite, zero, or scaled with |exponent| >= 1000) go through
 * bs_svd3 itself; so does every matrix on a CPU without AVX2, and the last
 * n mod 4. Two or three groups of four run together (svd3_avx2_groups): a
 * sweep is a chain of square roots and divisions whose latency, not the
 * arithmetic, bounds a single group, and independent chains overlap
 * (two groups are much faster than one; three, on batches of 12, were
 * hardly faster than two, so the batches of BS_MATERIAL_BATCH = 8 use two,
 * and a last 4 to 7 one). (A portable version
 * written for the compiler's auto-vectorizer got two lanes per register in
 * the sweeps and none in the epilogue.) */
#define L 4

static inline double pow2i(int e) { /* 2^e for -1022 <= e <= 1023 */
  union {
    uint64_t u;
    double d;
  } v;
  v.u = (uint64_t)(e + 1023) << 52;
  return v.d;
}

/* One lane's scale: 2^-e and 2^e with e the exponent of max |F_ij| (from
 * its bits: exact for the normal maxima of the lanes that stay in the batch,
 * 2^-1000 <= max < 2^1000); returns 1 for a lane bs_svd3 must take instead
 * (non-finite, zero, or out of that range), whose scales are then 1. */
static inline int lane_scale(const double *F, double *sc, double *isc) {
  double fm = 0.0, bad = 0.0;
  for (int i = 0; i < 9; i++) {
    const double a = fabs(F[i]);
    fm = a > fm ? a : fm;
    bad += F[i] - F[i];
  }
  union {
    double d;
    uint64_t u;
  } b = {fm};
  const int ex = (int)((b.u >> 52) & 0x7ff) - 1022; /* frexp's exponent */
  const int special = !(bad == 0.0) | !(ex > -1000) | !(ex < 1000) | (fm == 0.0);
  const int ec = special ? 0 : ex;
  *sc = pow2i(-ec);
  *isc = pow2i(ec);
  return special;
}

#ifdef BS_POLAR_AVX2
#define BS_SVD_AVX2 1
#define AVX2_FN BS_AVX2_FN
typedef __m256d v4;

AVX2_FN static inline v4 vsel(v4 m, v4 a, v4 b) { return bs_avx2_sel(m, a, b); } /* m ? a : b */
AVX2_FN static inline v4 vabs(v4 a) { return _mm256_andnot_pd(_mm256_set1_pd(-0.0), a); }
AVX2_FN static inline v4 vdot3(v4 a0, v4 a1, v4 a2, v4 b0, v4 b1, v4 b2) {
  return _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(a0, b0), _mm256_mul_pd(a1, b1)), _mm256_mul_pd(a2, b2));
}

/* Loads 4 matrices of F into lanes (scaled as bs_svd3 does; special lanes
 * hold 0) and W = I. */
AVX2_FN static inline void avx2_load(const double *restrict F, v4 B[9], v4 W[9], double isc[L], int special[L]) {
  double sc[L];
  for (int l = 0; l < L; l++) special[l] = lane_scale(F + 9 * l, &sc[l], &isc[l]);
  for (int i = 0; i < 9; i++) {
    double b[L];
    for (int l = 0; l < L; l++) b[l] = special[l] ? 0.0 : F[9 * l + i] * sc[l];
    B[i] = _mm256_loadu_pd(b);
    W[i] = _mm256_set1_pd(i % 4 == 0 ? 1.0 : 0.0);
  }
}

/* The Jacobi rotation of the column pair (p, q) in every lane: its cosine
 * and sine, and the mask of the lanes where it applies (act). */
AVX2_FN static inline v4 avx2_rot_coef(const v4 B[9], int p, int q, v4 *c, v4 *s) {
  const v4 zero = _mm256_setzero_pd(), two = _mm256_set1_pd(2.0);
  const v4 a = vdot3(B[p], B[3 + p], B[6 + p], B[p], B[3 + p], B[6 + p]);
  const v4 b = vdot3(B[q], B[3 + q], B[6 + q], B[q], B[3 + q], B[6 + q]);
  const v4 g = vdot3(B[p], B[3 + p], B[6 + p], B[q], B[3 + q], B[6 + q]);
  const v4 dab = _mm256_sub_pd(b, a);
  const v4 rr = _mm256_sqrt_pd(
      _mm256_add_pd(_mm256_mul_pd(dab, dab), _mm256_mul_pd(_mm256_mul_pd(_mm256_set1_pd(4.0), g), g)));
  const v4 D = _mm256_add_pd(vabs(dab), rr);
  const v4 act =
      _mm256_and_pd(_mm256_cmp_pd(_mm256_mul_pd(g, g),
                                  _mm256_mul_pd(_mm256_mul_pd(_mm256_set1_pd(SVD_TOL * SVD_TOL), a), b), _CMP_NLE_UQ),
                    _mm256_cmp_pd(D, zero, _CMP_GT_OQ));
  const v4 iq = _mm256_div_pd(_mm256_set1_pd(1.0), _mm256_sqrt_pd(_mm256_mul_pd(_mm256_mul_pd(two, rr), D)));
  *c = _mm256_mul_pd(D, iq);
  *s = _mm256_mul_pd(
      vsel(_mm256_cmp_pd(dab, zero, _CMP_GE_OQ), _mm256_mul_pd(two, g), _mm256_mul_pd(_mm256_set1_pd(-2.0), g)), iq);
  return act;
}

/* Applies the rotation (c, s) to columns p, q of B and W in the lanes of act. */
AVX2_FN static inline void avx2_rot_apply(v4 B[9], v4 W[9], int p, int q, v4 c, v4 s, v4 act) {
  for (int r = 0; r < 3; r++) {
    v4 *X[2] = {B, W};
    for (int m = 0; m < 2; m++) {
      const v4 xp = X[m][3 * r + p], xq = X[m][3 * r + q];
      const v4 nxp = _mm256_sub_pd(_mm256_mul_pd(c, xp), _mm256_mul_pd(s, xq));
      const v4 nxq = _mm256_add_pd(_mm256_mul_pd(s, xp), _mm256_mul_pd(c, xq));
      X[m][3 * r + p] = vsel(act, nxp, xp);
      X[m][3 * r + q] = vsel(act, nxq, xq);
    }
  }
}

/* After the sweeps: sort, make V a rotation, build U and sigma (bs_svd3's
 * epilogue), and store the 4 lanes. */
AVX2_FN static inline void avx2_finish(v4 B[9], v4 W[9], const double isc[L], double *restrict U,
                                       double *restrict sigma, double *restrict V) {
  const v4 zero = _mm256_setzero_pd(), one = _mm256_set1_pd(1.0);
  /* column lengths, then the compare-exchanges (2,1), (1,0), (2,1) */
  v4 n[3];
  for (int j = 0; j < 3; j++) n[j] = vdot3(B[j], B[3 + j], B[6 + j], B[j], B[3 + j], B[6 + j]);
  static const int sj[3] = {2, 1, 2};
  for (int e = 0; e < 3; e++) {
    const int j = sj[e];
    const v4 sw = _mm256_cmp_pd(n[j], n[j - 1], _CMP_GT_OQ);
    const v4 t = n[j], t1 = n[j - 1];
    n[j] = vsel(sw, t1, t);
    n[j - 1] = vsel(sw, t, t1);
    for (int r = 0; r < 3; r++) {
      const v4 x0 = B[3 * r + j], x1 = B[3 * r + j - 1], y0 = W[3 * r + j], y1 = W[3 * r + j - 1];
      B[3 * r + j] = vsel(sw, x1, x0);
      B[3 * r + j - 1] = vsel(sw, x0, x1);
      W[3 * r + j] = vsel(sw, y1, y0);
      W[3 * r + j - 1] = vsel(sw, y0, y1);
    }
  }
  /* det V < 0: the last columns change sign (bs_mat3_det's order, as bs_svd3) */
  const v4 det = _mm256_add_pd(
      _mm256_sub_pd(_mm256_mul_pd(W[0], _mm256_sub_pd(_mm256_mul_pd(W[4], W[8]), _mm256_mul_pd(W[5], W[7]))),
                    _mm256_mul_pd(W[1], _mm256_sub_pd(_mm256_mul_pd(W[3], W[8]), _mm256_mul_pd(W[5], W[6])))),
      _mm256_mul_pd(W[2], _mm256_sub_pd(_mm256_mul_pd(W[3], W[7]), _mm256_mul_pd(W[4], W[6]))));
  const v4 refl = _mm256_and_pd(_mm256_cmp_pd(det, zero, _CMP_LT_OQ), _mm256_set1_pd(-0.0));
  for (int r = 0; r < 3; r++) {
    W[3 * r + 2] = _mm256_xor_pd(W[3 * r + 2], refl);
    B[3 * r + 2] = _mm256_xor_pd(B[3 * r + 2], refl);
  }
  v4 u0[3], u1[3], w1[3], u2[3];
  const v4 s0 = _mm256_sqrt_pd(n[0]);
  for (int r = 0; r < 3; r++) u0[r] = _mm256_div_pd(B[3 * r], s0);
  const v4 d = vdot3(u0[0], u0[1], u0[2], B[1], B[4], B[7]);
  for (int r = 0; r < 3; r++) u1[r] = _mm256_sub_pd(B[3 * r + 1], _mm256_mul_pd(d, u0[r]));
  v4 nw2 = vdot3(u1[0], u1[1], u1[2], u1[0], u1[1], u1[2]);
  /* fallback: any unit vector orthogonal to u0 (the k of bs_svd3) */
  const v4 a0 = vabs(u0[0]), a1 = vabs(u0[1]), a2 = vabs(u0[2]);
  const v4 k1 = _mm256_cmp_pd(a1, a0, _CMP_LT_OQ);
  const v4 k2 = _mm256_cmp_pd(a2, vsel(k1, a1, a0), _CMP_LT_OQ); /* k = 2 */
  const v4 ek[3] = {_mm256_andnot_pd(_mm256_or_pd(k1, k2), one), _mm256_and_pd(_mm256_andnot_pd(k2, k1), one),
                    _mm256_and_pd(k2, one)};
  const v4 uk = vsel(k2, u0[2], vsel(k1, u0[1], u0[0]));
  for (int r = 0; r < 3; r++) w1[r] = _mm256_sub_pd(ek[r], _mm256_mul_pd(uk, u0[r]));
  const v4 mw2 = vdot3(w1[0], w1[1], w1[2], w1[0], w1[1], w1[2]);
  const v4 fb = _mm256_cmp_pd(nw2, _mm256_set1_pd(1e-300), _CMP_NGT_UQ);
  nw2 = vsel(fb, mw2, nw2);
  for (int r = 0; r < 3; r++) u1[r] = vsel(fb, w1[r], u1[r]);
  const v4 inw = _mm256_div_pd(one, _mm256_sqrt_pd(nw2));
  for (int r = 0; r < 3; r++) u1[r] = _mm256_mul_pd(u1[r], inw);
  u2[0] = _mm256_sub_pd(_mm256_mul_pd(u0[1], u1[2]), _mm256_mul_pd(u0[2], u1[1]));
  u2[1] = _mm256_sub_pd(_mm256_mul_pd(u0[2], u1[0]), _mm256_mul_pd(u0[0], u1[2]));
  u2[2] = _mm256_sub_pd(_mm256_mul_pd(u0[0], u1[1]), _mm256_mul_pd(u0[1], u1[0]));
  const v4 s1 = _mm256_sqrt_pd(n[1]);
  v4 s2 = vdot3(u2[0], u2[1], u2[2], B[2], B[5], B[8]);
  const v4 sgn = _mm256_and_pd(s2, _mm256_set1_pd(-0.0));
  s2 = vsel(_mm256_cmp_pd(vabs(s2), s1, _CMP_GT_OQ), _mm256_or_pd(s1, sgn), s2);
  double o[21][L];
  for (int r = 0; r < 3; r++) {
    _mm256_storeu_pd(o[3 * r], u0[r]);
    _mm256_storeu_pd(o[3 * r + 1], u1[r]);
    _mm256_storeu_pd(o[3 * r + 2], u2[r]);
  }
  for (int i = 0; i < 9; i++) _mm256_storeu_pd(o[9 + i], W[i]);
  _mm256_storeu_pd(o[18], s0);
  _mm256_storeu_pd(o[19], s1);
  _mm256_storeu_pd(o[20], s2);
  for (int l = 0; l < L; l++) {
    for (int i = 0; i < 9; i++) {
      U[9 * l + i] = o[i][l];
      V[9 * l + i] = o[9 + i][l];
    }
    for (int i = 0; i < 3; i++) sigma[3 * l + i] = o[18 + i][l] * isc[l];
  }
}

/* G groups of 4 matrices (B[g], W[g]) together: their independent chains of
 * square roots and divisions overlap. One Jacobi rotation of the column pair
 * (p, q) in every active lane of every group; returns the mask of the lanes
 * that rotated (of any group). */
AVX2_FN static inline __attribute__((always_inline)) v4 avx2_rotate_groups(v4 B[][9], v4 W[][9], const int G, int p,
                                                                           int q) {
  v4 c[3], s[3], act[3], any = _mm256_setzero_pd();
  for (int g = 0; g < G; g++) {
    act[g] = avx2_rot_coef(B[g], p, q, &c[g], &s[g]);
    any = _mm256_or_pd(any, act[g]);
  }
  if (_mm256_movemask_pd(any) == 0) return any;
  for (int g = 0; g < G; g++) avx2_rot_apply(B[g], W[g], p, q, c[g], s[g], act[g]);
  return any;
}

/* G (1 to 3) groups of four matrices: load,
 * sweeps while any lane of any group still rotates (a converged lane is
 * unchanged by them), finish. */
AVX2_FN static inline __attribute__((always_inline)) void svd3_avx2_groups(const double *restrict F,
                                                                           double *restrict U, double *restrict sigma,
                                                                           double *restrict V, int *restrict special,
                                                                           const int G) {
  v4 B[3][9], W[3][9];
  double isc[3 * L];
  for (int g = 0; g < G; g++) avx2_load(F + 9 * L * g, B[g], W[g], isc + L * g, special + L * g);
  for (int sweep = 0; sweep < SVD_MAX_SWEEPS; sweep++) {
    v4 rot = avx2_rotate_groups(B, W, G, 0, 1);
    rot = _mm256_or_pd(rot, avx2_rotate_groups(B, W, G, 0, 2));
    rot = _mm256_or_pd(rot, avx2_rotate_groups(B, W, G, 1, 2));
    if (_mm256_movemask_pd(rot) == 0) break; /* no lane rotated: every lane converged */
  }
  for (int g = 0; g < G; g++)
    avx2_finish(B[g], W[g], isc + L * g, U + 9 * L * g, sigma + 3 * L * g, V + 9 * L * g);
}

/* 12, 8 or 4 matrices (G = 3, 2, 1 groups). */
AVX2_FN static void svd3_avx2_12(const double *F, double *U, double *sigma, double *V, int *special) {
  svd3_avx2_groups(F, U, sigma, V, special, 3);
}
AVX2_FN static void svd3_avx2_8(const double *F, double *U, double *sigma, double *V, int *special) {
  svd3_avx2_groups(F, U, sigma, V, special, 2);
}
AVX2_FN static void svd3_avx2_4(const double *F, double *U, double *sigma, double *V, int *special) {
  svd3_avx2_groups(F, U, sigma, V, special, 1);
}

/* bs_polar3 on 4 matrices (bs_polar_avx2). */
AVX2_FN static void polar3_avx2(const double *restrict F, double *restrict R, int *restrict ok) {
  v4 X[9];
  for (int i = 0; i < 9; i++) X[i] = _mm256_set_pd(F[27 + i], F[18 + i], F[9 + i], F[i]);
  const int m = _mm256_movemask_pd(bs_polar_avx2(X));
  double o[9][L];
  for (int i = 0; i < 9; i++) _mm256_storeu_pd(o[i], X[i]);
  for (int l = 0; l < L; l++) {
    ok[l] = (m >> l) & 1;
    if (ok[l])
      for (int i = 0; i < 9; i++) R[9 * l + i] = o[i][l];
  }
}
#undef AVX2_FN
#endif

void bs_svd3_batch(int n, const double *F, double *U, double *sigma, double *V) {
  int i = 0;
#ifdef BS_SVD_AVX2
  if (__builtin_cpu_supports("avx2"))
    while (i + L <= n) {
      const int G = n - i >= 3 * L ? 3 : n - i >= 2 * L ? 2 : 1;
      int special[3 * L];
      double *Ui = U + 9 * (size_t)i, *si = sigma + 3 * (size_t)i, *Vi = V + 9 * (size_t)i;
      if (G == 3) svd3_avx2_12(F + 9 * (size_t)i, Ui, si, Vi, special);
      else if (G == 2) svd3_avx2_8(F + 9 * (size_t)i, Ui, si, Vi, special);
      else svd3_avx2_4(F + 9 * (size_t)i, Ui, si, Vi, special);
      for (int l = 0; l < G * L; l++)
        if (special[l])
          bs_svd3(F + 9 * (size_t)(i + l), U + 9 * (size_t)(i + l), sigma + 3 * (size_t)(i + l),
                  V + 9 * (size_t)(i + l));
      i += G * L;
    }
#endif
  for (; i < n; i++) bs_svd3(F + 9 * (size_t)i, U + 9 * (size_t)i, sigma + 3 * (size_t)i, V + 9 * (size_t)i);
}

void bs_polar3_batch(int n, const double *F, double *R, int *ok) {
  int i = 0;
#ifdef BS_SVD_AVX2
  if (__builtin_cpu_supports("avx2"))
    for (; i + L <= n; i += L) polar3_avx2(F + 9 * (size_t)i, R + 9 * (size_t)i, ok + i);
#endif
  for (; i < n; i++) ok[i] = bs_polar3(F + 9 * (size_t)i, R + 9 * (size_t)i);
}
#undef L

