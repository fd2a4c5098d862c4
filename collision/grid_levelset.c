/* grid_levelset.c — level sets sampled on a regular grid: trilinear
 * interpolation with its exact derivatives, extrapolation outside the grid,
 * sampling of analytic level sets, and the BSLS1 file format (see
 * bs_levelset.h).
 *
 * In a cell with corner values c_abc (a, b, c in {0, 1}) and local
 * coordinates f in [0, 1]^3, with weights w_0(f) = 1 - f, w_1(f) = f and
 * their derivatives w'_0 = -1, w'_1 = 1:
 *   phi      = sum c_abc w_a(fx) w_b(fy) w_c(fz),
 *   dphi/dx  = sum c_abc w'_a w_b w_c / h            (and y, z alike),
 *   d2phi/dxdy = sum c_abc w'_a w'_b w_c / h^2       (and xz, yz alike),
 * and d2phi/dx2 = 0 (each weight is linear in its own variable).
 * Outside the box, p is clamped to its nearest box point q and
 *   phi(p) = phi(q) + |p - q|;
 * on a clamped axis k, q_k does not depend on p_k, so the interpolant's
 * derivative along k drops out, and the distance adds r/|r| to the gradient
 * and (P - u u^T)/|r| to the Hessian (r = p - q, u = r/|r|, P the diagonal
 * projector on the clamped axes).
 */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bs_levelset.h"

#define HEADER_BYTES 56
static const char MAGIC[8] = {'B', 'S', 'L', 'S', '1', 0, 0, 0};

double bs_levelset_grid_interp(const bs_levelset *ls, const double p[3], double g[3], double H[9]) {
  const int32_t *n = ls->n;
  const double h = ls->h;
  if (isnan(p[0]) || isnan(p[1]) || isnan(p[2])) { /* no cell to look up: NaN out */
    if (g) g[0] = g[1] = g[2] = NAN;
    if (H)
      for (int k = 0; k < 9; k++) H[k] = NAN;
    return NAN;
  }
  double f[3], r[3];
  int32_t i0[3];
  int clamped[3];
  for (int k = 0; k < 3; k++) {
    double u = (p[k] - ls->origin[k]) / h, umax = (double)(n[k] - 1);
    double q = u < 0 ? 0 : (u > umax ? umax : u);
    clamped[k] = (q != u);
    r[k] = (u - q) * h;
    int32_t c = (int32_t)floor(q);
    if (c > n[k] - 2) c = n[k] - 2;
    i0[k] = c;
    f[k] = q - c;
  }
  const size_t sx = 1, sy = (size_t)n[0], sz = (size_t)n[0] * (size_t)n[1];
  const double *c0 = ls->values + i0[0] * sx + i0[1] * sy + i0[2] * sz;
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
  double dist = sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
  if (g) {
    g[0] = clamped[0] ? 0 : gx / h;
    g[1] = clamped[1] ? 0 : gy / h;
    g[2] = clamped[2] ? 0 : gz / h;
  }
  if (H) {
    double h2 = h * h;
    memset(H, 0, 9 * sizeof(double));
    H[1] = H[3] = (clamped[0] || clamped[1]) ? 0 : hxy / h2;
    H[2] = H[6] = (clamped[0] || clamped[2]) ? 0 : hxz / h2;
    H[5] = H[7] = (clamped[1] || clamped[2]) ? 0 : hyz / h2;
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

/* Validates the geometry and allocates a grid level set with room for its
 * values (not filled). */
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
  ls->values = bs_calloc((size_t)total, sizeof(double), "grid level set values", err);
  if (!ls->values) {
    free(ls);
    return BS_ENOMEM;
  }
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
  if ((st = check_values(ls, "", err))) {
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
  if ((st = check_values(ls, "sampled ", err))) {
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
  if ((st = check_values(ls, "", err))) bs_error_prefix(err, "level set file '%s'", path);
done:
  fclose(fp);
  if (st) bs_levelset_destroy(&ls);
  else *out = ls;
  return st;
}
