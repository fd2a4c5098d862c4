/* levelset.c — analytic signed distance functions, rigid motions, and the
 * evaluation dispatcher of every level set (see bs_levelset.h).
 *
 * Each shape is evaluated in its local frame y = M^T (x - c) where it is
 * centred at the origin with its axis along z, returning phi_l, g_l and H_l;
 * the dispatcher maps them back: grad = M g_l, Hess = M H_l M^T (phi is
 * invariant under rigid motions), and negates all three for a complement.
 *
 * The smooth pieces and their derivatives (rho = |(y_x, y_y)|, e = (y_x,
 * y_y, 0)/rho the radial unit vector, ez = (0, 0, 1)):
 *   d rho = e,   Hess rho = (I_xy - e e^T)/rho,   I_xy = diag(1, 1, 0);
 *   a 2-D distance d = |(a, b)| in the (rho, z) half-plane has gradient
 *   n = (a, b)/d and 2-D Hessian (I - n n^T)/d; by the chain rule
 *   grad = n_1 e + n_2 ez,
 *   Hess = (1 - n_1^2)/d e e^T - n_1 n_2/d (e ez^T + ez e^T)
 *          + (1 - n_2^2)/d ez ez^T + n_1 Hess rho.
 */
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bs_levelset.h"
#include "bs_vec3.h"

/* Distances below this are treated as zero where a derivative divides by
 * them (the undefined-derivative fallback documented in the header). */
#define TINY 1e-200

/* ---- small vector and rotation helpers ------------------------------- */

static void matvec(const double A[9], const double x[3], double y[3]) {
  for (int i = 0; i < 3; i++) y[i] = A[3 * i] * x[0] + A[3 * i + 1] * x[1] + A[3 * i + 2] * x[2];
}
static void matTvec(const double A[9], const double x[3], double y[3]) {
  for (int i = 0; i < 3; i++) y[i] = A[i] * x[0] + A[3 + i] * x[1] + A[6 + i] * x[2];
}
static void matmul(const double A[9], const double B[9], double C[9]) {
  for (int i = 0; i < 3; i++)
    for (int j = 0; j < 3; j++) C[3 * i + j] = A[3 * i] * B[j] + A[3 * i + 1] * B[3 + j] + A[3 * i + 2] * B[6 + j];
}
static void identity(double A[9]) {
  memset(A, 0, 9 * sizeof(double));
  A[0] = A[4] = A[8] = 1;
}

/* Unit quaternion (w, x, y, z) of the axis-angle vector r (angle |r|). */
static void quat_from_aa(const double r[3], double q[4]) {
  double th = bs_norm3(r);
  if (th < TINY) {
    q[0] = 1, q[1] = q[2] = q[3] = 0;
    return;
  }
  double s = sin(0.5 * th) / th;
  q[0] = cos(0.5 * th), q[1] = s * r[0], q[2] = s * r[1], q[3] = s * r[2];
}
static void quat_mul(const double a[4], const double b[4], double c[4]) {
  double w = a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3];
  double x = a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2];
  double y = a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1];
  double z = a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0];
  c[0] = w, c[1] = x, c[2] = y, c[3] = z;
}
static void quat_to_mat(const double q[4], double R[9]) {
  double w = q[0], x = q[1], y = q[2], z = q[3];
  R[0] = 1 - 2 * (y * y + z * z), R[1] = 2 * (x * y - z * w), R[2] = 2 * (x * z + y * w);
  R[3] = 2 * (x * y + z * w), R[4] = 1 - 2 * (x * x + z * z), R[5] = 2 * (y * z - x * w);
  R[6] = 2 * (x * z - y * w), R[7] = 2 * (y * z + x * w), R[8] = 1 - 2 * (x * x + y * y);
}
/* Axis-angle vector u of the unit quaternion q along the shortest arc
 * (angle in [0, pi]). */
static void quat_log(const double q_in[4], double u[3]) {
  double q[4] = {q_in[0], q_in[1], q_in[2], q_in[3]};
  if (q[0] < 0)
    for (int i = 0; i < 4; i++) q[i] = -q[i];
  double s = sqrt(q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
  if (s < TINY) {
    u[0] = u[1] = u[2] = 0;
    return;
  }
  double th = 2 * atan2(s, q[0]);
  for (int i = 0; i < 3; i++) u[i] = th * q[i + 1] / s;
}

/* Rotation taking ez to the unit vector a (Rodrigues about ez x a). */
static void rot_z_to(const double a[3], double R[9]) {
  double k[3] = {-a[1], a[0], 0}; /* ez x a */
  double s2 = k[0] * k[0] + k[1] * k[1], c = a[2];
  identity(R);
  if (s2 < 1e-24) {
    if (c < 0) R[4] = R[8] = -1; /* half turn about x */
    return;
  }
  double K[9] = {0, -k[2], k[1], k[2], 0, -k[0], -k[1], k[0], 0}, K2[9];
  matmul(K, K, K2);
  double f = (1 - c) / s2;
  for (int i = 0; i < 9; i++) R[i] += K[i] + f * K2[i];
}

/* ---- validation ------------------------------------------------------- */

static int check_vec(const char *name, const double v[3], bs_error *err) {
  if (!v) return bs_error_set(err, BS_EINPUT, "%s is NULL", name);
  for (int k = 0; k < 3; k++)
    if (!isfinite(v[k]))
      return bs_error_set(err, BS_EINPUT, "%s[%d] = %g: must be finite", name, k, v[k]);
  return 0;
}
static int check_pos(const char *name, double v, bs_error *err) {
  if (!isfinite(v) || !(v > 0)) return bs_error_set(err, BS_EINPUT, "%s = %g: must be finite and > 0 (m)", name, v);
  return 0;
}
static int check_axis(const char *name, const double a[3], double unit[3], bs_error *err) {
  int st = check_vec(name, a, err);
  if (st) return st;
  /* Scaled (bs_norm3_scaled): (1e200, 0, 0) squares to inf and (1e-200, 0,
   * 0) to 0, both of which would normalize to a zero vector. */
  const double n = bs_norm3_scaled(a);
  if (!(n > 0))
    return bs_error_set(err, BS_EINPUT, "%s = (%g, %g, %g): must be nonzero", name, a[0], a[1], a[2]);
  for (int k = 0; k < 3; k++) unit[k] = a[k] / n;
  return 0;
}

static int new_levelset(bs_ls_kind kind, const double c0[3], bs_levelset **out, bs_error *err) {
  bs_levelset *ls = bs_calloc(1, sizeof *ls, "a level set", err);
  if (!ls) return BS_ENOMEM;
  ls->kind = kind;
  if (c0) memcpy(ls->c0, c0, sizeof ls->c0);
  identity(ls->Q0);
  ls->motion = BS_LS_STATIC;
  *out = ls;
  return 0;
}

/* ---- creation --------------------------------------------------------- */

int bs_levelset_create_halfspace(const double normal[3], double offset, bs_levelset **out, bs_error *err) {
  double n[3];
  int st = check_axis("normal", normal, n, err);
  if (st) return st;
  if (!isfinite(offset)) return bs_error_set(err, BS_EINPUT, "offset = %g: must be finite (m)", offset);
  double c = offset / bs_norm3_scaled(normal), c0[3] = {c * n[0], c * n[1], c * n[2]};
  if ((st = new_levelset(BS_LS_HALFSPACE, c0, out, err))) return st;
  rot_z_to(n, (*out)->Q0);
  return 0;
}

int bs_levelset_create_sphere(const double centre[3], double radius, bs_levelset **out, bs_error *err) {
  int st = check_vec("centre", centre, err);
  if (!st) st = check_pos("radius", radius, err);
  if (!st) st = new_levelset(BS_LS_SPHERE, centre, out, err);
  if (!st) (*out)->param[0] = radius;
  return st;
}

int bs_levelset_create_box(const double centre[3], const double half[3], bs_levelset **out, bs_error *err) {
  int st = check_vec("centre", centre, err);
  if (!st) st = check_vec("half_extents", half, err);
  if (st) return st;
  for (int k = 0; k < 3; k++)
    if (!(half[k] > 0))
      return bs_error_set(err, BS_EINPUT, "half_extents[%d] = %g: must be > 0 (m)", k, half[k]);
  if ((st = new_levelset(BS_LS_BOX, centre, out, err))) return st;
  memcpy((*out)->param, half, 3 * sizeof(double));
  return 0;
}

int bs_levelset_create_cylinder(const double centre[3], const double axis[3], double radius, double half_height,
                                bs_levelset **out, bs_error *err) {
  double a[3];
  int st = check_vec("centre", centre, err);
  if (!st) st = check_axis("axis", axis, a, err);
  if (!st) st = check_pos("radius", radius, err);
  if (!st) st = check_pos("half_height", half_height, err);
  if (!st) st = new_levelset(BS_LS_CYLINDER, centre, out, err);
  if (st) return st;
  (*out)->param[0] = radius;
  (*out)->param[1] = half_height;
  rot_z_to(a, (*out)->Q0);
  return 0;
}

int bs_levelset_create_torus(const double centre[3], const double axis[3], double major, double minor,
                             bs_levelset **out, bs_error *err) {
  double a[3];
  int st = check_vec("centre", centre, err);
  if (!st) st = check_axis("axis", axis, a, err);
  if (!st) st = check_pos("major", major, err);
  if (!st) st = check_pos("minor", minor, err);
  if (st) return st;
  if (!(minor < major))
    return bs_error_set(err, BS_EINPUT,
                        "minor = %g: must be < major = %g (a self-intersecting torus has no exact distance here)",
                        minor, major);
  if ((st = new_levelset(BS_LS_TORUS, centre, out, err))) return st;
  (*out)->param[0] = major;
  (*out)->param[1] = minor;
  rot_z_to(a, (*out)->Q0);
  return 0;
}

void bs_levelset_destroy(bs_levelset **pls) {
  if (!pls || !*pls) return;
  bs_levelset *ls = *pls;
  free(ls->key_t);
  free(ls->key_d);
  free(ls->key_q);
  free(ls->values);
  free(ls);
  *pls = NULL;
}

/* ---- modifiers --------------------------------------------------------- */

void bs_levelset_set_complement(bs_levelset *ls, int complement) { ls->complement = complement ? 1 : 0; }

static void clear_motion(bs_levelset *ls) {
  free(ls->key_t);
  free(ls->key_d);
  free(ls->key_q);
  ls->key_t = ls->key_d = ls->key_q = NULL;
  ls->n_keys = 0;
  memset(ls->vel, 0, sizeof ls->vel);
  memset(ls->omega, 0, sizeof ls->omega);
  ls->motion = BS_LS_STATIC;
}

int bs_levelset_set_velocity(bs_levelset *ls, const double v[3], const double w[3], bs_error *err) {
  int st = check_vec("velocity", v, err);
  if (!st) st = check_vec("angular_velocity", w, err);
  if (st) return st;
  clear_motion(ls);
  memcpy(ls->vel, v, sizeof ls->vel);
  memcpy(ls->omega, w, sizeof ls->omega);
  ls->motion = BS_LS_VELOCITY;
  return 0;
}

int bs_levelset_set_keyframes(bs_levelset *ls, int n, const double *times, const double *translations,
                              const double *rotations, bs_error *err) {
  if (n < 1) return bs_error_set(err, BS_EINPUT, "keyframes: n = %d: need at least one keyframe", n);
  if (!times || !translations || !rotations)
    return bs_error_set(err, BS_EINPUT, "keyframes: times, translations and rotations must be non-NULL");
  char name[64];
  for (int i = 0; i < n; i++) {
    if (!isfinite(times[i]))
      return bs_error_set(err, BS_EINPUT, "keyframes[%d].time = %g: must be finite (s)", i, times[i]);
    if (i > 0 && !(times[i] > times[i - 1]))
      return bs_error_set(err, BS_EINPUT, "keyframes[%d].time = %g: must be > keyframes[%d].time = %g", i,
                          times[i], i - 1, times[i - 1]);
    snprintf(name, sizeof name, "keyframes[%d].translation", i);
    int st = check_vec(name, translations + 3 * i, err);
    if (st) return st;
    snprintf(name, sizeof name, "keyframes[%d].rotation", i);
    if ((st = check_vec(name, rotations + 3 * i, err))) return st;
  }
  double *t = malloc((size_t)n * sizeof *t), *d = malloc(3 * (size_t)n * sizeof *d),
         *q = malloc(4 * (size_t)n * sizeof *q);
  if (!t || !d || !q) {
    free(t), free(d), free(q);
    return bs_error_set(err, BS_ENOMEM, "out of memory storing %d keyframes", n);
  }
  memcpy(t, times, (size_t)n * sizeof *t);
  memcpy(d, translations, 3 * (size_t)n * sizeof *d);
  for (int i = 0; i < n; i++) quat_from_aa(rotations + 3 * i, q + 4 * i);
  clear_motion(ls);
  ls->key_t = t, ls->key_d = d, ls->key_q = q, ls->n_keys = n;
  ls->motion = BS_LS_KEYFRAMES;
  return 0;
}

/* ---- queries ---------------------------------------------------------- */

bs_ls_kind bs_levelset_kind(const bs_levelset *ls) { return ls->kind; }

const char *bs_levelset_kind_name(bs_ls_kind kind) {
  switch (kind) {
    case BS_LS_HALFSPACE: return "halfspace";
    case BS_LS_SPHERE: return "sphere";
    case BS_LS_BOX: return "box";
    case BS_LS_CYLINDER: return "cylinder";
    case BS_LS_TORUS: return "torus";
    case BS_LS_GRID: return "grid";
  }
  return "unknown";
}

int bs_levelset_is_complement(const bs_levelset *ls) { return ls->complement; }
int bs_levelset_is_analytic(const bs_levelset *ls) { return ls->kind != BS_LS_GRID; }
bs_ls_motion bs_levelset_motion(const bs_levelset *ls) { return ls->motion; }

/* ---- motion ----------------------------------------------------------- */

void bs_levelset_frame_at(const bs_levelset *ls, double t, bs_levelset_frame *f) {
  double R[9], d[3] = {0, 0, 0};
  identity(R);
  memset(f->v, 0, sizeof f->v);
  memset(f->w, 0, sizeof f->w);
  if (ls->motion == BS_LS_VELOCITY) {
    double r[3] = {ls->omega[0] * t, ls->omega[1] * t, ls->omega[2] * t}, q[4];
    quat_from_aa(r, q);
    quat_to_mat(q, R);
    for (int k = 0; k < 3; k++) d[k] = ls->vel[k] * t, f->v[k] = ls->vel[k], f->w[k] = ls->omega[k];
  } else if (ls->motion == BS_LS_KEYFRAMES) {
    int n = ls->n_keys;
    const double *kt = ls->key_t;
    if (n == 1 || t <= kt[0] || t >= kt[n - 1]) { /* held: no velocity */
      int i = (n == 1 || t <= kt[0]) ? 0 : n - 1;
      memcpy(d, ls->key_d + 3 * i, sizeof d);
      quat_to_mat(ls->key_q + 4 * i, R);
    } else {
      int lo = 0, hi = n - 1; /* kt[lo] <= t < kt[hi] */
      while (hi - lo > 1) {
        int mid = (lo + hi) / 2;
        if (kt[mid] <= t) lo = mid;
        else hi = mid;
      }
      double span = kt[hi] - kt[lo], s = (t - kt[lo]) / span;
      const double *da = ls->key_d + 3 * lo, *db = ls->key_d + 3 * hi, *qa = ls->key_q + 4 * lo,
                   *qb = ls->key_q + 4 * hi;
      for (int k = 0; k < 3; k++) d[k] = da[k] + s * (db[k] - da[k]), f->v[k] = (db[k] - da[k]) / span;
      /* slerp: q(s) = qa exp(s u), u = log(qa^-1 qb) (body frame); the world
       * angular velocity is Ra u / span. */
      double qa_inv[4] = {qa[0], -qa[1], -qa[2], -qa[3]}, qr[4], u[3], us[3], qs[4], q[4], Ra[9];
      quat_mul(qa_inv, qb, qr);
      quat_log(qr, u);
      for (int k = 0; k < 3; k++) us[k] = s * u[k];
      quat_from_aa(us, qs);
      quat_mul(qa, qs, q);
      quat_to_mat(q, R);
      quat_to_mat(qa, Ra);
      matvec(Ra, u, f->w);
      for (int k = 0; k < 3; k++) f->w[k] /= span;
    }
  }
  matmul(R, ls->Q0, f->M);
  for (int k = 0; k < 3; k++) f->c[k] = ls->c0[k] + d[k];
}

/* ---- the shapes, in their local frames ------------------------------- */

/* need: 0 phi only, 1 also g, 2 also H (g and H are always valid arrays). */

static double sdf_sphere(double r, const double y[3], int need, double g[3], double H[9]) {
  double d = bs_norm3(y);
  if (need) {
    if (d > TINY) {
      for (int k = 0; k < 3; k++) g[k] = y[k] / d;
      if (need > 1)
        for (int i = 0; i < 3; i++)
          for (int j = 0; j < 3; j++) H[3 * i + j] = ((i == j) - g[i] * g[j]) / d;
    } else {
      g[0] = g[1] = 0, g[2] = 1;
    }
  }
  return d - r;
}

static double sdf_box(const double b[3], const double y[3], int need, double g[3], double H[9]) {
  double q[3], s[3], r[3];
  int outside = 0;
  for (int k = 0; k < 3; k++) {
    s[k] = y[k] >= 0 ? 1.0 : -1.0;
    q[k] = fabs(y[k]) - b[k];
    r[k] = q[k] > 0 ? s[k] * q[k] : 0.0;
    if (q[k] > 0) outside = 1;
  }
  if (outside) { /* distance to the nearest box point; r = y - nearest */
    double d = bs_norm3(r);
    if (need) {
      for (int k = 0; k < 3; k++) g[k] = r[k] / d;
      if (need > 1)
        for (int i = 0; i < 3; i++)
          for (int j = 0; j < 3; j++) H[3 * i + j] = ((i == j && q[i] > 0) - g[i] * g[j]) / d;
    }
    return d;
  }
  int m = 0; /* nearest face: the largest q (first on ties) */
  for (int k = 1; k < 3; k++)
    if (q[k] > q[m]) m = k;
  if (need) g[m] = s[m];
  return q[m];
}

/* Radial unit vector e and Hess rho (added with weight w into H). */
static double radial(const double y[3], double e[3]) {
  double rho = hypot(y[0], y[1]);
  if (rho > TINY) e[0] = y[0] / rho, e[1] = y[1] / rho;
  else e[0] = 1, e[1] = 0;
  e[2] = 0;
  return rho;
}
static void add_hess_rho(double rho, const double e[3], double w, double H[9]) {
  if (!(rho > TINY) || w == 0) return;
  for (int i = 0; i < 2; i++)
    for (int j = 0; j < 2; j++) H[3 * i + j] += w * ((i == j) - e[i] * e[j]) / rho;
}
/* A 2-D distance d = |(a, b)| in the (rho, z') half-plane, z' = sz z. */
static void dist2d_derivs(double a, double b, double d, double sz, double rho, const double e[3], int need, double g[3],
                          double H[9]) {
  double n1 = 1, n2 = 0;
  if (d > TINY) n1 = a / d, n2 = b / d;
  for (int k = 0; k < 3; k++) g[k] = n1 * e[k];
  g[2] += n2 * sz;
  if (need < 2) return;
  if (d > TINY) {
    double ee = (1 - n1 * n1) / d, ez = -n1 * n2 * sz / d, zz = (1 - n2 * n2) / d;
    for (int i = 0; i < 3; i++)
      for (int j = 0; j < 3; j++) H[3 * i + j] = ee * e[i] * e[j] + ez * (e[i] * (j == 2) + (i == 2) * e[j]);
    H[8] += zz;
  }
  add_hess_rho(rho, e, n1, H);
}

static double sdf_cylinder(double r, double hh, const double y[3], int need, double g[3], double H[9]) {
  double e[3], rho = radial(y, e), sz = y[2] >= 0 ? 1.0 : -1.0;
  double d1 = rho - r, d2 = fabs(y[2]) - hh;
  if (d1 > 0 && d2 > 0) { /* nearest point on a rim circle */
    double d = hypot(d1, d2);
    if (need) dist2d_derivs(d1, d2, d, sz, rho, e, need, g, H);
    return d;
  }
  if (d1 >= d2) { /* the side is nearest (outside beside it, or inside) */
    if (need) {
      memcpy(g, e, 3 * sizeof(double));
      if (need > 1) add_hess_rho(rho, e, 1.0, H);
    }
    return d1;
  }
  if (need) g[2] = sz; /* a cap */
  return d2;
}

static double sdf_torus(double R, double r, const double y[3], int need, double g[3], double H[9]) {
  double e[3], rho = radial(y, e);
  double a = rho - R, d = hypot(a, y[2]);
  if (need) dist2d_derivs(a, y[2], d, 1.0, rho, e, need, g, H);
  return d - r;
}

/* A grid's rest-frame point of the local point y (the local origin is the
 * centre of the grid box, c0). */
static void grid_point(const bs_levelset *ls, const double y[3], double q[3]) {
  for (int k = 0; k < 3; k++) q[k] = ls->c0[k] + y[k];
}

/* The local point y = M^T (x - c) of x in frame f. */
static void to_local(const bs_levelset_frame *f, const double x[3], double y[3]) {
  double dx[3] = {x[0] - f->c[0], x[1] - f->c[1], x[2] - f->c[2]};
  matTvec(f->M, dx, y);
}

static double eval_local(const bs_levelset *ls, const double y[3], int need, double g[3], double H[9]) {
  const double *p = ls->param;
  switch (ls->kind) {
    case BS_LS_HALFSPACE:
      if (need) g[2] = 1;
      return y[2];
    case BS_LS_SPHERE: return sdf_sphere(p[0], y, need, g, H);
    case BS_LS_BOX: return sdf_box(p, y, need, g, H);
    case BS_LS_CYLINDER: return sdf_cylinder(p[0], p[1], y, need, g, H);
    case BS_LS_TORUS: return sdf_torus(p[0], p[1], y, need, g, H);
    case BS_LS_GRID: {
      double q[3];
      grid_point(ls, y, q);
      return bs_levelset_grid_interp(ls, q, need ? g : NULL, need > 1 ? H : NULL);
    }
  }
  return NAN;
}

/* ---- evaluation ------------------------------------------------------- */

double bs_levelset_eval_frame(const bs_levelset *ls, const bs_levelset_frame *f, const double x[3], double grad[3],
                              double hess[9]) {
  double y[3];
  to_local(f, x, y);
  double gl[3] = {0, 0, 0}, Hl[9] = {0};
  int need = hess ? 2 : grad ? 1 : 0;
  double phi = eval_local(ls, y, need, gl, Hl);
  double sgn = ls->complement ? -1.0 : 1.0;
  if (grad) {
    matvec(f->M, gl, grad);
    for (int k = 0; k < 3; k++) grad[k] *= sgn;
  }
  if (hess) { /* M Hl M^T */
    double T[9];
    for (int i = 0; i < 3; i++)
      for (int j = 0; j < 3; j++)
        T[3 * i + j] = Hl[3 * i] * f->M[3 * j] + Hl[3 * i + 1] * f->M[3 * j + 1] + Hl[3 * i + 2] * f->M[3 * j + 2];
    for (int i = 0; i < 3; i++)
      for (int j = 0; j < 3; j++)
        hess[3 * i + j] =
            sgn * (f->M[3 * i] * T[j] + f->M[3 * i + 1] * T[3 + j] + f->M[3 * i + 2] * T[6 + j]);
  }
  return sgn * phi;
}

int bs_levelset_surely_outside_frame(const bs_levelset *ls, const bs_levelset_frame *f, const double x[3]) {
  if (ls->kind != BS_LS_GRID) return 0;
  double y[3], q[3]; /* the point eval_frame's interpolation reads */
  to_local(f, x, y);
  grid_point(ls, y, q);
  return bs_levelset_grid_sign_certain(ls, q, ls->complement ? -1 : 1);
}

double bs_levelset_eval(const bs_levelset *ls, double t, const double x[3], double grad[3], double hess[9]) {
  bs_levelset_frame f;
  bs_levelset_frame_at(ls, t, &f);
  return bs_levelset_eval_frame(ls, &f, x, grad, hess);
}

void bs_levelset_local_point(const bs_levelset *ls, double t, const double x[3], double y[3]) {
  bs_levelset_frame f;
  bs_levelset_frame_at(ls, t, &f);
  to_local(&f, x, y);
}

void bs_levelset_velocity(const bs_levelset *ls, double t, const double x[3], double v[3]) {
  bs_levelset_frame f;
  bs_levelset_frame_at(ls, t, &f);
  double r[3] = {x[0] - f.c[0], x[1] - f.c[1], x[2] - f.c[2]}, wr[3];
  bs_cross3(f.w, r, wr);
  for (int k = 0; k < 3; k++) v[k] = f.v[k] + wr[k];
}

void bs_levelset_motion_bound_over(const bs_levelset *ls, double t0, double t1, bs_levelset_motion_bound *b) {
  memset(b, 0, sizeof *b);
  const double lo = fmin(t0, t1), hi = fmax(t0, t1);
  if (ls->motion == BS_LS_VELOCITY) {
    b->v = sqrt(bs_dot3(ls->vel, ls->vel));
    b->w = sqrt(bs_dot3(ls->omega, ls->omega));
    return;
  }
  if (ls->motion != BS_LS_KEYFRAMES || ls->n_keys < 2) return;
  const int n = ls->n_keys;
  const double *kt = ls->key_t;
  int pieces = (lo <= kt[0]) + (hi >= kt[n - 1]); /* the holds, at rest */
  for (int i = 0; i + 1 < n; i++) {
    if (kt[i + 1] < lo || kt[i] > hi) continue;
    bs_levelset_frame f; /* the segment's (constant) velocities: its frame at its middle */
    bs_levelset_frame_at(ls, 0.5 * (kt[i] + kt[i + 1]), &f);
    b->v = fmax(b->v, sqrt(bs_dot3(f.v, f.v)));
    b->w = fmax(b->w, sqrt(bs_dot3(f.w, f.w)));
    pieces++;
  }
  if (pieces > 1) b->dv = 2 * b->v, b->dw = 2 * b->w;
}

double bs_levelset_project_frame(const bs_levelset *ls, const bs_levelset_frame *f, const double x[3],
                                 double xp[3]) {
  double g[3];
  double phi = bs_levelset_eval_frame(ls, f, x, g, NULL);
  for (int k = 0; k < 3; k++) xp[k] = x[k] - phi * g[k];
  return phi;
}

double bs_levelset_project(const bs_levelset *ls, double t, const double x[3], double xp[3]) {
  bs_levelset_frame f;
  bs_levelset_frame_at(ls, t, &f);
  return bs_levelset_project_frame(ls, &f, x, xp);
}
