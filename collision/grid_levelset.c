/* grid_levelset.c — level sets sampled on a regular grid: cubic B-spline
 * (default) or trilinear interpolation with exact derivatives, extrapolation
 * outside the grid, sampling of analytic level sets, and the BSLS1 file
 * format (see bs_levelset.h).
 *
 * Trilinear. In a cell with corner values c_abc (a, b, c in {0, 1}) and local
 * coordinates f in [0, 1]^3, with weights w_0(f) = 1 - f, w_1(f) = f and
 * their derivatives w'_0 = -1, w'_1 = 1:
 *   phi      = sum c_abc w_a(fx) w_b(fy) w_c(fz),
 *   dphi/dx  = sum c_abc w'_a w_b w_c / h            (and y, z alike),
 *   d2phi/dxdy = sum c_abc w'_a w'_b w_c / h^2       (and xz, yz alike),
 * and d2phi/dx2 = 0 (each weight is linear in its own variable). The
 * gradient jumps across cell faces.
 *
 * Cubic B-spline (C2). phi(u) = sum_ijk C_ijk B(u_x - i) B(u_y - j) B(u_z - k),
 * u = (p - origin) / h, B the uniform cubic B-spline (support [-2, 2]). In
 * the cell [c, c + 1] with f = u - c the four nonzero basis functions, on
 * nodes c - 1 .. c + 2, are
 *   b0 = (1 - f)^3 / 6,          b1 = (3 f^3 - 6 f^2 + 4) / 6,
 *   b2 = (-3 f^3 + 3 f^2 + 3 f + 1) / 6,          b3 = f^3 / 6,
 * and the gradient and Hessian use their exact first and second derivatives
 * (divided by h and h^2). The coefficients C are not the samples: they are
 * PREFILTERED once at creation so that the spline interpolates every node,
 *   (C_{i-1} + 4 C_i + C_{i+1}) / 6 = v_i,
 * solved by separable tridiagonal (Thomas) sweeps along x, then y, then z.
 * Boundary: the stencil of a cell next to the grid boundary reaches one node
 * past it; that ghost coefficient is the LINEAR EXTRAPOLATION of the two
 * nearest, C_{-1} = 2 C_0 - C_1 (and C_n = 2 C_{n-1} - C_{n-2}), i.e. the
 * ghost's basis function is folded onto its two neighbours. Then the node
 * equation at the boundary reads C_0 = v_0 and phi'' = 0 there (the natural
 * spline): linear functions along each axis, hence every trilinear function,
 * are reproduced exactly, which plain index clamping (C_{-1} = C_0) would not.
 * For a smooth phi the interpolation error is O(h^4) in the interior and
 * O(h^2) within a few cells of the grid boundary (the natural end condition).
 *
 * Outside the box (either mode), p is clamped to its nearest box point q and
 *   phi(p) = phi(q) + |p - q|;
 * on a clamped axis k, q_k does not depend on p_k, so the interpolant's
 * derivatives along k drop out (gradient entry and Hessian row/column), and
 * the distance adds r/|r| to the gradient and (P - u u^T)/|r| to the Hessian
 * (r = p - q, u = r/|r|, P the diagonal projector on the clamped axes).
 *
 * Storage: ls->values holds 2 N + 2 B doubles in one allocation (freed with
 * ls->values by bs_levelset_destroy): the N samples, the N B-spline
 * coefficients (ls->coef = ls->values + N), then the min and max of the
 * coefficients each block of BS_GRID_BLOCK^3 cells reads (ls->coef_range,
 * B blocks; bs_levelset_grid_sign_certain).
 */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bs_levelset.h"
#include "bs_limits.h"

#define HEADER_BYTES 56
static const char MAGIC[8] = {'B', 'S', 'L', 'S', '1', 0, 0, 0};

/* Position of p in the grid, per axis: the clamped parameter's cell c (0 <=
 * c <= n - 2), f in [0, 1], whether the axis is clamped and the offset
 * r = p - q (m). */
typedef struct {
  int32_t c[3];
  double f[3], r[3];
  int clamped[3];
} grid_locus;

static void locate(const bs_levelset *ls, const double p[3], grid_locus *L) {
  for (int k = 0; k < 3; k++) {
    double u = (p[k] - ls->origin[k]) / ls->h, umax = (double)(ls->n[k] - 1);
    double q = u < 0 ? 0 : (u > umax ? umax : u);
    L->clamped[k] = (q != u);
    L->r[k] = (u - q) * ls->h;
    int32_t c = (int32_t)floor(q);
    if (c > ls->n[k] - 2) c = ls->n[k] - 2;
    L->c[k] = c;
    L->f[k] = q - c;
  }
}

/* Trilinear interpolant at the locus: value, gradient d/du (not yet / h) and
 * the mixed second derivatives d2/du2 (row-major, diagonal zero). */
static double interp_linear(const bs_levelset *ls, const grid_locus *L, double gu[3], double Hu[9]) {
  const int32_t *n = ls->n;
  const double *f = L->f;
  const size_t sx = 1, sy = (size_t)n[0], sz = (size_t)n[0] * (size_t)n[1];
  const double *c0 = ls->values + L->c[0] * sx + L->c[1] * sy + L->c[2] * sz;
  double val = 0, gx = 0, gy = 0, gz = 0, hxy = 0, hxz = 0, hyz = 0;
  for (int c = 0; c < 2; c++) {
    double wz = c ? f[2] : 1 - f[2], dz = c ? 1.0 : -1.0;
    for (int b = 0; b < 2; b++) {
      double wy = b ? f[1] : 1 - f[1], dy = b ? 1.0 : -1.0;
      for (int a = 0; a < 2; a++) {
        double wx = a ? f[0] : 1 - f[0], dx = a ? 1.0 : -1.0;
        double v = c0[a * sx + b * sy + c * sz];
        val += v * wx * wy * wz;
        gx += v * dx * wy * wz;
        gy += v * wx * dy * wz;
        gz += v * wx * wy * dz;
        hxy += v * dx * dy * wz;
        hxz += v * dx * wy * dz;
        hyz += v * wx * dy * dz;
      }
    }
  }
  gu[0] = gx, gu[1] = gy, gu[2] = gz;
  Hu[0] = Hu[4] = Hu[8] = 0;
  Hu[1] = Hu[3] = hxy;
  Hu[2] = Hu[6] = hxz;
  Hu[5] = Hu[7] = hyz;
  return val;
}

/* The cubic B-spline weights of one axis (value, and when need > 0 first and second
 * derivatives in f) on the stencil nodes c - 1 .. c + 2, with a ghost node
 * (index -1 or n) folded onto its two neighbours: C_{-1} = 2 C_0 - C_1 gives
 * w_0 += 2 w_{-1}, w_1 -= w_{-1}. Slots lo .. hi are the in-grid ones. */
typedef struct {
  double w[4], d[4], dd[4];
  int lo, hi;
} axis_weights;

static void fold(double a[4], int ghost, int near, int next) {
  a[near] += 2 * a[ghost];
  a[next] -= a[ghost];
  a[ghost] = 0;
}

static void bspline_weights(double f, int32_t c, int32_t n, int need, axis_weights *A) {
  double g = 1 - f, f2 = f * f;
  A->w[0] = g * g * g / 6;
  A->w[1] = (3 * f2 * f - 6 * f2 + 4) / 6;
  A->w[2] = (-3 * f2 * f + 3 * f2 + 3 * f + 1) / 6;
  A->w[3] = f2 * f / 6;
  if (need > 0) {
    A->d[0] = -0.5 * g * g;
    A->d[1] = 1.5 * f2 - 2 * f;
    A->d[2] = -1.5 * f2 + f + 0.5;
    A->d[3] = 0.5 * f2;
    A->dd[0] = g;
    A->dd[1] = 3 * f - 2;
    A->dd[2] = 1 - 3 * f;
    A->dd[3] = f;
  }
  A->lo = 0, A->hi = 3;
  if (c == 0) { /* node -1 is a ghost */
    fold(A->w, 0, 1, 2);
    if (need > 0) fold(A->d, 0, 1, 2), fold(A->dd, 0, 1, 2);
    A->lo = 1;
  }
  if (c + 2 >= n) { /* node n is a ghost */
    fold(A->w, 3, 2, 1);
    if (need > 0) fold(A->d, 3, 2, 1), fold(A->dd, 3, 2, 1);
    A->hi = 2;
  }
}

/* The value alone of the cubic B-spline at the locus: the sums of
 * interp_cubic that make it, in the same order (the same bits). */
static double interp_cubic_value(const bs_levelset *ls, const grid_locus *L) {
  const int32_t *n = ls->n;
  axis_weights X, Y, Z;
  bspline_weights(L->f[0], L->c[0], n[0], 0, &X);
  bspline_weights(L->f[1], L->c[1], n[1], 0, &Y);
  bspline_weights(L->f[2], L->c[2], n[2], 0, &Z);
  const size_t sy = (size_t)n[0], sz = (size_t)n[0] * (size_t)n[1];
  double val = 0;
  for (int c = Z.lo; c <= Z.hi; c++) {
    size_t kz = (size_t)(L->c[2] - 1 + c) * sz;
    double t00 = 0;
    for (int b = Y.lo; b <= Y.hi; b++) {
      const double *row = ls->coef + kz + (size_t)(L->c[1] - 1 + b) * sy + L->c[0];
      double r0 = 0;
      for (int a = X.lo; a <= X.hi; a++) r0 += row[a - 1] * X.w[a];
      t00 += r0 * Y.w[b];
    }
    val += t00 * Z.w[c];
  }
  return val;
}

/* Cubic B-spline at the locus: value, gradient d/du and Hessian d2/du2. The
 * 4 x 4 x 4 sum is contracted axis by axis: x first (three sums per row),
 * then y (six), then z (ten outputs). */
static double interp_cubic(const bs_levelset *ls, const grid_locus *L, double gu[3], double Hu[9]) {
  const int32_t *n = ls->n;
  axis_weights X, Y, Z;
  bspline_weights(L->f[0], L->c[0], n[0], 2, &X);
  bspline_weights(L->f[1], L->c[1], n[1], 2, &Y);
  bspline_weights(L->f[2], L->c[2], n[2], 2, &Z);
  const size_t sy = (size_t)n[0], sz = (size_t)n[0] * (size_t)n[1];
  double val = 0, gx = 0, gy = 0, gz = 0, hxx = 0, hyy = 0, hzz = 0, hxy = 0, hxz = 0, hyz = 0;
  for (int c = Z.lo; c <= Z.hi; c++) {
    size_t kz = (size_t)(L->c[2] - 1 + c) * sz;
    /* y-contractions of the x-contractions: T_ab = sum_j (x-sum a) (y-weight b) */
    double t00 = 0, t10 = 0, t01 = 0, t20 = 0, t11 = 0, t02 = 0;
    for (int b = Y.lo; b <= Y.hi; b++) {
      const double *row = ls->coef + kz + (size_t)(L->c[1] - 1 + b) * sy + L->c[0]; /* node c: slot 1 */
      double r0 = 0, r1 = 0, r2 = 0;
      for (int a = X.lo; a <= X.hi; a++) {
        double v = row[a - 1];
        r0 += v * X.w[a];
        r1 += v * X.d[a];
        r2 += v * X.dd[a];
      }
      t00 += r0 * Y.w[b];
      t10 += r1 * Y.w[b];
      t01 += r0 * Y.d[b];
      t20 += r2 * Y.w[b];
      t11 += r1 * Y.d[b];
      t02 += r0 * Y.dd[b];
    }
    double wz = Z.w[c], dz = Z.d[c], ddz = Z.dd[c];
    val += t00 * wz;
    gx += t10 * wz;
    gy += t01 * wz;
    gz += t00 * dz;
    hxx += t20 * wz;
    hyy += t02 * wz;
    hzz += t00 * ddz;
    hxy += t11 * wz;
    hxz += t10 * dz;
    hyz += t01 * dz;
  }
  gu[0] = gx, gu[1] = gy, gu[2] = gz;
  Hu[0] = hxx, Hu[4] = hyy, Hu[8] = hzz;
  Hu[1] = Hu[3] = hxy;
  Hu[2] = Hu[6] = hxz;
  Hu[5] = Hu[7] = hyz;
  return val;
}

double bs_levelset_grid_interp(const bs_levelset *ls, const double p[3], double g[3], double H[9]) {
  if (isnan(p[0]) || isnan(p[1]) || isnan(p[2])) { /* no cell to look up: NaN out */
    if (g) g[0] = g[1] = g[2] = NAN;
    if (H)
      for (int k = 0; k < 9; k++) H[k] = NAN;
    return NAN;
  }
  grid_locus L;
  locate(ls, p, &L);
  double gu[3], Hu[9];
  double val = ls->grid_interp == BS_GRID_LINEAR ? interp_linear(ls, &L, gu, Hu)
               : g || H                          ? interp_cubic(ls, &L, gu, Hu)
                                                 : interp_cubic_value(ls, &L);
  const double h = ls->h, *r = L.r;
  const int *clamped = L.clamped;
  double dist = sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
  if (g)
    for (int k = 0; k < 3; k++) g[k] = clamped[k] ? 0 : gu[k] / h;
  if (H) {
    double h2 = h * h;
    for (int i = 0; i < 3; i++)
      for (int j = 0; j < 3; j++) H[3 * i + j] = (clamped[i] || clamped[j]) ? 0 : Hu[3 * i + j] / h2;
  }
  if (dist > 0) {
    double u[3] = {r[0] / dist, r[1] / dist, r[2] / dist};
    if (g)
      for (int k = 0; k < 3; k++) g[k] += u[k];
    if (H)
      for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) H[3 * i + j] += ((i == j && clamped[i]) - u[i] * u[j]) / dist;
  }
  return val + dist;
}

/* ---- prefilter: the B-spline coefficients that interpolate the samples ---- */

/* Solves, along every grid line of axis a, the tridiagonal system
 *   C_0 = v_0,  C_{i-1} + 4 C_i + C_{i+1} = 6 v_i (0 < i < m - 1),  C_{m-1} = v_{m-1}
 * in place (Thomas algorithm; strictly diagonally dominant, so stable without
 * pivoting). The data are viewed as [outer][m][inner] with inner = the stride
 * of axis a, so each sweep step runs over a contiguous block. im holds the
 * m inverse pivots (workspace, m doubles). */
static void prefilter_axis(double *C, const int32_t n[3], int a, double *im) {
  const size_t m = (size_t)n[a];
  size_t inner = 1, outer = 1;
  for (int k = 0; k < a; k++) inner *= (size_t)n[k];
  for (int k = a + 1; k < 3; k++) outer *= (size_t)n[k];
  if (m < 3) return; /* only boundary rows: C = v */
  /* pivots: m_1 = 4, m_i = 4 - 1 / m_{i-1}; the super-diagonal over the
   * pivot (cp_i) equals 1 / m_i on the interior rows, and the last row has
   * a zero sub-diagonal */
  im[0] = 1;
  double piv = 4;
  for (size_t i = 1; i + 1 < m; i++) {
    im[i] = 1 / piv;
    piv = 4 - im[i];
  }
  for (size_t o = 0; o < outer; o++) {
    double *base = C + o * m * inner;
    for (size_t i = 1; i + 1 < m; i++) { /* forward: d_i = (6 v_i - d_{i-1}) / m_i */
      double *cur = base + i * inner, *prev = cur - inner;
      for (size_t s = 0; s < inner; s++) cur[s] = (6 * cur[s] - prev[s]) * im[i];
    }
    for (size_t i = m - 2; i >= 1; i--) { /* back: C_i = d_i - C_{i+1} / m_i */
      double *cur = base + i * inner, *next = cur + inner;
      for (size_t s = 0; s < inner; s++) cur[s] -= next[s] * im[i];
    }
  }
}

/* Blocks of BS_GRID_BLOCK cells along each axis (n - 1 cells). */
static void grid_blocks(const int32_t n[3], int32_t nb[3]) {
  for (int k = 0; k < 3; k++) nb[k] = (n[k] - 1 + BS_GRID_BLOCK - 1) / BS_GRID_BLOCK;
}

/* The min and max of the coefficients read by the cells of block (bi, bj,
 * bk): nodes c - 1 .. c + 2 of each of its cells c, clipped to the grid. */
static void block_range(const bs_levelset *ls, const int32_t b[3], double *mn, double *mx) {
  int32_t lo[3], hi[3];
  for (int k = 0; k < 3; k++) {
    lo[k] = BS_GRID_BLOCK * b[k] - 1;
    hi[k] = BS_GRID_BLOCK * b[k] + BS_GRID_BLOCK + 1;
    if (lo[k] < 0) lo[k] = 0;
    if (hi[k] > ls->n[k] - 1) hi[k] = ls->n[k] - 1;
  }
  const size_t sy = (size_t)ls->n[0], sz = sy * (size_t)ls->n[1];
  double a = INFINITY, z = -INFINITY;
  for (int32_t k = lo[2]; k <= hi[2]; k++)
    for (int32_t j = lo[1]; j <= hi[1]; j++)
      for (int32_t i = lo[0]; i <= hi[0]; i++) {
        const double c = ls->coef[(size_t)k * sz + (size_t)j * sy + (size_t)i];
        a = c < a ? c : a;
        z = c > z ? c : z;
      }
  *mn = a, *mx = z;
}

static void grid_ranges(bs_levelset *ls) {
  int32_t nb[3], b[3];
  grid_blocks(ls->n, nb);
  size_t q = 0;
  for (b[2] = 0; b[2] < nb[2]; b[2]++)
    for (b[1] = 0; b[1] < nb[1]; b[1]++)
      for (b[0] = 0; b[0] < nb[0]; b[0]++, q++)
        block_range(ls, b, &ls->coef_range[2 * q], &ls->coef_range[2 * q + 1]);
}

int bs_levelset_grid_sign_certain(const bs_levelset *ls, const double p[3], int sign) {
  if (ls->kind != BS_LS_GRID || ls->grid_interp != BS_GRID_CUBIC) return 0;
  grid_locus L; /* the cell the interpolation reads */
  locate(ls, p, &L);
  const int32_t *c = L.c;
  for (int k = 0; k < 3; k++) /* clamped (or NaN), or a cell whose B-spline folds at the boundary */
    if (L.clamped[k] || c[k] < 1 || c[k] > ls->n[k] - 3) return 0;
  int32_t nb[3];
  grid_blocks(ls->n, nb);
  const size_t q = ((size_t)(c[2] / BS_GRID_BLOCK) * (size_t)nb[1] + (size_t)(c[1] / BS_GRID_BLOCK)) * (size_t)nb[0] +
                   (size_t)(c[0] / BS_GRID_BLOCK);
  return sign > 0 ? ls->coef_range[2 * q] > 0 : ls->coef_range[2 * q + 1] < 0;
}

/* Fills ls->coef from ls->values, then ls->coef_range. */
static int grid_prefilter(bs_levelset *ls, bs_error *err) {
  int32_t mmax = ls->n[0];
  if (ls->n[1] > mmax) mmax = ls->n[1];
  if (ls->n[2] > mmax) mmax = ls->n[2];
  double *im = bs_calloc((size_t)mmax, sizeof(double), "grid prefilter pivots", err);
  if (!im) return BS_ENOMEM;
  memcpy(ls->coef, ls->values, (size_t)ls->n[0] * (size_t)ls->n[1] * (size_t)ls->n[2] * sizeof(double));
  for (int a = 0; a < 3; a++) prefilter_axis(ls->coef, ls->n, a, im);
  free(im);
  grid_ranges(ls);
  return 0;
}

int bs_levelset_grid_set_interp(bs_levelset *ls, bs_grid_interp mode, bs_error *err) {
  if (!ls || ls->kind != BS_LS_GRID)
    return bs_error_set(err, BS_EINPUT, "grid interpolation: the level set is %s, not a grid",
                        ls ? bs_levelset_kind_name(ls->kind) : "NULL");
  if (mode != BS_GRID_CUBIC && mode != BS_GRID_LINEAR)
    return bs_error_set(err, BS_EINPUT, "grid interpolation mode = %d: must be BS_GRID_CUBIC or BS_GRID_LINEAR",
                        (int)mode);
  ls->grid_interp = mode;
  return 0;
}

bs_grid_interp bs_levelset_grid_get_interp(const bs_levelset *ls) { return (bs_grid_interp)ls->grid_interp; }

const char *bs_grid_interp_name(bs_grid_interp mode) {
  return mode == BS_GRID_CUBIC ? "cubic" : mode == BS_GRID_LINEAR ? "linear" : "unknown";
}

/* Validates the geometry and allocates a grid level set with room for its
 * values and its B-spline coefficients (neither filled); cubic by default. */
static int grid_new(const double origin[3], double h, const int32_t n[3], bs_levelset **out, bs_error *err) {
  for (int k = 0; k < 3; k++)
    if (!isfinite(origin[k]))
      return bs_error_set(err, BS_EINPUT, "grid origin[%d] = %g: must be finite", k, origin[k]);
  if (!isfinite(h) || !(h > 0)) return bs_error_set(err, BS_EINPUT, "grid spacing h = %g: must be finite and > 0 (m)", h);
  double total = 1;
  for (int k = 0; k < 3; k++) {
    if (n[k] < 2) return bs_error_set(err, BS_EINPUT, "grid n[%d] = %d: need at least 2 nodes per axis", k, (int)n[k]);
    total *= n[k];
  }
  if (total > (double)INT32_MAX)
    return bs_error_set(err, BS_EINPUT, "grid %d x %d x %d: more than 2^31 - 1 nodes", (int)n[0], (int)n[1],
                        (int)n[2]);
  bs_levelset *ls = bs_calloc(1, sizeof *ls, "a grid level set", err);
  if (!ls) return BS_ENOMEM;
  int32_t nb[3];
  grid_blocks(n, nb);
  const size_t blocks = (size_t)nb[0] * (size_t)nb[1] * (size_t)nb[2];
  ls->values = bs_calloc(2 * (size_t)total + 2 * blocks, sizeof(double), "grid level set values", err);
  if (!ls->values) {
    free(ls);
    return BS_ENOMEM;
  }
  ls->coef = ls->values + (size_t)total;
  ls->coef_range = ls->coef + (size_t)total;
  ls->grid_interp = BS_GRID_CUBIC;
  ls->kind = BS_LS_GRID;
  ls->motion = BS_LS_STATIC;
  ls->Q0[0] = ls->Q0[4] = ls->Q0[8] = 1;
  memcpy(ls->n, n, sizeof ls->n);
  memcpy(ls->origin, origin, sizeof ls->origin);
  ls->h = h;
  for (int k = 0; k < 3; k++) ls->c0[k] = origin[k] + 0.5 * h * (n[k] - 1);
  *out = ls;
  return 0;
}

static size_t grid_count(const bs_levelset *ls) { return (size_t)ls->n[0] * (size_t)ls->n[1] * (size_t)ls->n[2]; }

/* A non-finite value names its node (i, j, k). */
static int check_values(const bs_levelset *ls, const char *where, bs_error *err) {
  size_t total = grid_count(ls);
  for (size_t s = 0; s < total; s++)
    if (!isfinite(ls->values[s])) {
      size_t i = s % (size_t)ls->n[0], j = (s / (size_t)ls->n[0]) % (size_t)ls->n[1],
             k = s / ((size_t)ls->n[0] * (size_t)ls->n[1]);
      return bs_error_set(err, BS_EINPUT, "%sgrid value at node (%zu, %zu, %zu) = %g: must be finite", where, i, j, k,
                          ls->values[s]);
    }
  return 0;
}

int bs_levelset_grid_from_values(const double origin[3], double h, const int32_t n[3], const double *values,
                                 bs_levelset **out, bs_error *err) {
  if (!origin || !n || !values) return bs_error_set(err, BS_EINPUT, "grid: origin, n and values must be non-NULL");
  bs_levelset *ls = NULL;
  int st = grid_new(origin, h, n, &ls, err);
  if (st) return st;
  memcpy(ls->values, values, grid_count(ls) * sizeof(double));
  if ((st = check_values(ls, "", err)) || (st = grid_prefilter(ls, err))) {
    bs_levelset_destroy(&ls);
    return st;
  }
  *out = ls;
  return 0;
}

int bs_levelset_grid_sample(const bs_levelset *src, double t, const double lo[3], const double hi[3], double h,
                            bs_levelset **out, bs_error *err) {
  if (!src || !lo || !hi) return bs_error_set(err, BS_EINPUT, "grid sample: src, lo and hi must be non-NULL");
  if (!isfinite(t)) return bs_error_set(err, BS_EINPUT, "grid sample: time t = %g: must be finite", t);
  if (!isfinite(h) || !(h > 0)) return bs_error_set(err, BS_EINPUT, "grid spacing h = %g: must be finite and > 0 (m)", h);
  int32_t n[3];
  for (int k = 0; k < 3; k++) {
    if (!isfinite(lo[k]) || !isfinite(hi[k]) || !(hi[k] > lo[k]))
      return bs_error_set(err, BS_EINPUT, "grid box: lo[%d] = %g, hi[%d] = %g: need finite lo < hi", k, lo[k], k,
                          hi[k]);
    double cells = ceil((hi[k] - lo[k]) / h * (1 - 1e-12));
    if (cells > (double)INT32_MAX - 1)
      return bs_error_set(err, BS_EINPUT, "grid box axis %d: %g cells of h = %g is too many", k, cells, h);
    n[k] = (int32_t)cells + 1;
    if (n[k] < 2) n[k] = 2;
  }
  bs_levelset *ls = NULL;
  int st = grid_new(lo, h, n, &ls, err);
  if (st) return st;
  bs_levelset_frame f;
  bs_levelset_frame_at(src, t, &f);
  double *v = ls->values;
#pragma omp parallel for schedule(static)
  for (int32_t k = 0; k < n[2]; k++)
    for (int32_t j = 0; j < n[1]; j++)
      for (int32_t i = 0; i < n[0]; i++) {
        double x[3] = {lo[0] + h * i, lo[1] + h * j, lo[2] + h * k};
        v[i + (size_t)n[0] * (j + (size_t)n[1] * k)] = bs_levelset_eval_frame(src, &f, x, NULL, NULL);
      }
  if ((st = check_values(ls, "sampled ", err)) || (st = grid_prefilter(ls, err))) {
    bs_levelset_destroy(&ls);
    return st;
  }
  *out = ls;
  return 0;
}

const double *bs_levelset_grid_values(const bs_levelset *ls, int32_t n[3], double origin[3], double *h) {
  if (!ls || ls->kind != BS_LS_GRID) return NULL;
  if (n) memcpy(n, ls->n, sizeof ls->n);
  if (origin) memcpy(origin, ls->origin, sizeof ls->origin);
  if (h) *h = ls->h;
  return ls->values;
}

/* ---- the BSLS1 file, little-endian whatever the host ------------------ */

static void put_u32(unsigned char *b, uint32_t v) {
  for (int i = 0; i < 4; i++) b[i] = (unsigned char)(v >> (8 * i));
}
static uint32_t get_u32(const unsigned char *b) {
  uint32_t v = 0;
  for (int i = 0; i < 4; i++) v |= (uint32_t)b[i] << (8 * i);
  return v;
}
static void put_f64(unsigned char *b, double d) {
  uint64_t v;
  memcpy(&v, &d, 8);
  for (int i = 0; i < 8; i++) b[i] = (unsigned char)(v >> (8 * i));
}
static double get_f64(const unsigned char *b) {
  uint64_t v = 0;
  for (int i = 0; i < 8; i++) v |= (uint64_t)b[i] << (8 * i);
  double d;
  memcpy(&d, &v, 8);
  return d;
}

enum { CHUNK = 4096 }; /* values converted per buffered read/write */

int bs_levelset_grid_save(const bs_levelset *ls, const char *path, bs_error *err) {
  if (!path) return bs_error_set(err, BS_EINPUT, "level set save: path is NULL");
  if (!ls || ls->kind != BS_LS_GRID)
    return bs_error_set(err, BS_EINPUT, "level set file '%s': only grid level sets can be saved (this one is %s)",
                        path, ls ? bs_levelset_kind_name(ls->kind) : "NULL");
  FILE *fp = fopen(path, "wb");
  if (!fp) return bs_error_set(err, BS_EIO, "level set file '%s': cannot open for writing: %s", path, strerror(errno));
  unsigned char hdr[HEADER_BYTES], buf[8 * CHUNK];
  memcpy(hdr, MAGIC, 8);
  for (int k = 0; k < 3; k++) put_u32(hdr + 8 + 4 * k, (uint32_t)ls->n[k]);
  put_u32(hdr + 20, 0);
  for (int k = 0; k < 3; k++) put_f64(hdr + 24 + 8 * k, ls->origin[k]);
  put_f64(hdr + 48, ls->h);
  int ok = fwrite(hdr, 1, HEADER_BYTES, fp) == HEADER_BYTES;
  size_t total = grid_count(ls);
  for (size_t s = 0; ok && s < total; s += CHUNK) {
    size_t m = total - s < CHUNK ? total - s : CHUNK;
    for (size_t i = 0; i < m; i++) put_f64(buf + 8 * i, ls->values[s + i]);
    ok = fwrite(buf, 8, m, fp) == m;
  }
  if (fclose(fp) != 0) ok = 0;
  if (!ok) return bs_error_set(err, BS_EIO, "level set file '%s': write failed", path);
  return 0;
}

/* The header's node count against BS_MAX_GRID_NODES and the file's size,
 * before anything is allocated (a 56-byte file may claim 2^31 nodes). */
static int check_file_size(FILE *fp, const char *path, const int32_t n[3], bs_error *err) {
  uint64_t total = 1;
  for (int k = 0; k < 3; k++) {
    if (n[k] < 2)
      return bs_error_set(err, BS_EINPUT, "level set file '%s': n[%d] = %d in the header: need at least 2 nodes per axis",
                          path, k, (int)n[k]);
    total *= (uint64_t)n[k]; /* < 2^93 would overflow: stop early */
    if (total > (uint64_t)BS_MAX_GRID_NODES)
      return bs_error_set(err, BS_EINPUT,
                          "level set file '%s': the header's grid %d x %d x %d exceeds bigstep's limit of %ld nodes",
                          path, (int)n[0], (int)n[1], (int)n[2], (long)BS_MAX_GRID_NODES);
  }
  long here = ftell(fp);
  if (here < 0 || fseek(fp, 0, SEEK_END) != 0) return bs_error_set(err, BS_EIO, "level set file '%s': cannot seek", path);
  long size = ftell(fp);
  if (size < 0 || fseek(fp, here, SEEK_SET) != 0) return bs_error_set(err, BS_EIO, "level set file '%s': cannot seek", path);
  uint64_t want = HEADER_BYTES + 8 * total;
  if ((uint64_t)size < want)
    return bs_error_set(err, BS_EIO,
                        "level set file '%s': truncated: %ld bytes, but its header's grid %d x %d x %d needs %llu "
                        "(%d + 8 per node)",
                        path, size, (int)n[0], (int)n[1], (int)n[2], (unsigned long long)want, HEADER_BYTES);
  if ((uint64_t)size > want)
    return bs_error_set(err, BS_EINPUT, "level set file '%s': trailing bytes after %llu values (%ld bytes, %llu expected)",
                        path, (unsigned long long)total, size, (unsigned long long)want);
  return 0;
}

int bs_levelset_grid_load(const char *path, bs_levelset **out, bs_error *err) {
  if (!path) return bs_error_set(err, BS_EINPUT, "level set load: path is NULL");
  FILE *fp = fopen(path, "rb");
  if (!fp) return bs_error_set(err, BS_EIO, "level set file '%s': cannot open: %s", path, strerror(errno));
  unsigned char hdr[HEADER_BYTES], buf[8 * CHUNK];
  bs_levelset *ls = NULL;
  int st = 0;
  size_t got = fread(hdr, 1, HEADER_BYTES, fp);
  if (got >= 8 && memcmp(hdr, MAGIC, 8) != 0) {
    st = bs_error_set(err, BS_EINPUT, "level set file '%s': bad magic (not a BSLS1 grid level set)", path);
    goto done;
  }
  if (got < HEADER_BYTES) {
    st = bs_error_set(err, BS_EIO, "level set file '%s': truncated header (%zu of %d bytes)", path, got,
                      HEADER_BYTES);
    goto done;
  }
  int32_t n[3];
  double origin[3], h;
  for (int k = 0; k < 3; k++) {
    uint32_t v = get_u32(hdr + 8 + 4 * k);
    n[k] = v > (uint32_t)INT32_MAX ? -1 : (int32_t)v;
    origin[k] = get_f64(hdr + 24 + 8 * k);
  }
  h = get_f64(hdr + 48);
  if ((st = check_file_size(fp, path, n, err))) goto done;
  if ((st = grid_new(origin, h, n, &ls, err))) {
    bs_error_prefix(err, "level set file '%s'", path);
    goto done;
  }
  size_t total = grid_count(ls);
  for (size_t s = 0; s < total; s += CHUNK) {
    size_t m = total - s < CHUNK ? total - s : CHUNK;
    size_t r = fread(buf, 8, m, fp);
    for (size_t i = 0; i < r; i++) ls->values[s + i] = get_f64(buf + 8 * i);
    if (r < m) {
      st = bs_error_set(err, BS_EIO, "level set file '%s': truncated (%zu of %zu values)", path, s + r, total);
      goto done;
    }
  }
  if (fgetc(fp) != EOF) {
    st = bs_error_set(err, BS_EINPUT, "level set file '%s': trailing bytes after %zu values", path, total);
    goto done;
  }
  if ((st = check_values(ls, "", err)) || (st = grid_prefilter(ls, err)))
    bs_error_prefix(err, "level set file '%s'", path);
done:
  fclose(fp);
  if (st) bs_levelset_destroy(&ls);
  else *out = ls;
  return st;
}
