/* ccd.c — additive continuous collision detection (ACCD; Li, Kaufman, Jiang,
 * "Codimensional Incremental Potential Contact", 2021) for point-triangle
 * and edge-edge linear trajectories, on certified lower bounds of the
 * distance (bs_ipc.h explains the algorithm and why it is conservative under
 * rounding).
 *
 * Error bounds. u = 2^-53. Norms written |v|_1 are 1-norms (>= the 2-norm),
 * used for cheap upper bounds. For a point and a segment r = p - e0,
 * e = e1 - e0, the computed clamped parameter is off the exact one by at most
 * ~4u |r| / |e|, which moves the computed foot by ~4u |r| along the segment
 * (still on it), plus the rounding of r, e, n = r - alpha e and |n|: 16u
 * (|r|_1 + |e|_1) covers it. For the plane (line-line) distance |r.N| / |N|,
 * N = a x b: |N_computed - N| <= nerr = 8u |a|_1 |b|_1 (rounding of a, b and
 * the cross product), so the distance is off by at most
 * 32u |r|_1 |a|_1 |b|_1 / (|N| - 2 nerr). Inside tests (the foot in the
 * triangle; the lines' closest points in both segments) accept with a
 * tolerance twice their rounding bound: a wrong acceptance only adds a
 * candidate that is below the true distance (the plane is nearer than the
 * triangle, the lines nearer than the segments).
 */
#include <math.h>

#include "bs_ipc.h"

#define U 0x1p-53

static double dot3(const double a[3], const double b[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
static void sub3(const double a[3], const double b[3], double o[3]) {
  o[0] = a[0] - b[0], o[1] = a[1] - b[1], o[2] = a[2] - b[2];
}
static void cross3(const double a[3], const double b[3], double o[3]) {
  o[0] = a[1] * b[2] - a[2] * b[1];
  o[1] = a[2] * b[0] - a[0] * b[2];
  o[2] = a[0] * b[1] - a[1] * b[0];
}
static double norm1(const double v[3]) { return fabs(v[0]) + fabs(v[1]) + fabs(v[2]); }

/* A lower bound of the distance from p to the segment (e0, e1). */
static double seg_lo(const double p[3], const double e0[3], const double e1[3]) {
  double r[3], e[3], n[3];
  sub3(p, e0, r);
  sub3(e1, e0, e);
  const double ee = dot3(e, e);
  double al = ee > 0 ? dot3(r, e) / ee : 0;
  al = al < 0 ? 0 : al > 1 ? 1 : al;
  for (int c = 0; c < 3; c++) n[c] = r[c] - al * e[c];
  /* ee == 0 with e != 0 (an underflow): the foot is e0, off by <= |e| */
  return sqrt(dot3(n, n)) - 16 * U * (norm1(r) + norm1(e)) - (ee == 0 ? norm1(e) : 0);
}

/* The plane (line-line) part: r, a, b as in the file comment. *plane_ok is
 * set when its rounding bound *err is below the geometric bound *h of the
 * degenerate treatment (hdiv: the length h divides |N| by). */
typedef struct plane_part {
  double N[3], nN, AB, err, h;
  int ok;
} plane_part;

static plane_part plane_part_of(const double r[3], const double a[3], const double b[3], double hdiv) {
  plane_part pp;
  cross3(a, b, pp.N);
  pp.nN = sqrt(dot3(pp.N, pp.N));
  pp.AB = norm1(a) * norm1(b);
  const double nerr = 8 * U * pp.AB;
  pp.h = hdiv > 0 ? (pp.nN + 2 * nerr) / (hdiv * (1 - 16 * U)) : 0; /* hdiv = 0: all points coincide */
  pp.ok = pp.nN > 4 * nerr;
  pp.err = pp.ok ? 32 * U * norm1(r) * pp.AB / (pp.nN - 2 * nerr) : INFINITY;
  pp.ok = pp.ok && pp.err < pp.h;
  return pp;
}

double bs_ccd_pt_dist_lower(const double x[12]) {
  const double *p = x, *T[3] = {x + 3, x + 6, x + 9};
  double lo = INFINITY, a[3], b[3], r[3], e[3], w[3], v[3], lmax = 0;
  for (int k = 0; k < 3; k++) {
    lo = fmin(lo, seg_lo(p, T[k], T[(k + 1) % 3]));
    sub3(T[(k + 1) % 3], T[k], e);
    lmax = fmax(lmax, sqrt(dot3(e, e)));
  }
  sub3(T[1], T[0], a);
  sub3(T[2], T[0], b);
  sub3(p, T[0], r);
  /* degenerate: the triangle is within h = |N| / (longest edge) of that edge */
  const plane_part pp = plane_part_of(r, a, b, lmax);
  if (!pp.ok) return lo - pp.h;
  int inside = 1;
  for (int k = 0; k < 3 && inside; k++) { /* (e_k x (p - t_k)) . N >= 0 */
    sub3(T[(k + 1) % 3], T[k], e);
    sub3(p, T[k], w);
    cross3(e, w, v);
    inside = dot3(v, pp.N) >= -32 * U * norm1(e) * norm1(w) * pp.AB;
  }
  if (inside) lo = fmin(lo, fabs(dot3(r, pp.N)) / pp.nN - pp.err);
  return lo;
}

double bs_ccd_ee_dist_lower(const double x[12]) {
  const double *a0 = x, *a1 = x + 3, *b0 = x + 6, *b1 = x + 9;
  double lo = fmin(fmin(seg_lo(a0, b0, b1), seg_lo(a1, b0, b1)), fmin(seg_lo(b0, a0, a1), seg_lo(b1, a0, a1)));
  double a[3], b[3], r[3], w[3];
  sub3(a1, a0, a);
  sub3(b1, b0, b);
  sub3(b0, a0, r);
  /* near-parallel: the interior minimum is within
   * |N| / (sqrt2 max(|a|, |b|)) of the endpoint-segment distances */
  const double lmax = fmax(sqrt(dot3(a, a)), sqrt(dot3(b, b)));
  const plane_part pp = plane_part_of(r, a, b, sqrt(2.0) * lmax * (1 - 4 * U));
  if (!pp.ok) return lo - pp.h;
  const double q = dot3(pp.N, pp.N), qerr = 24 * U * pp.AB * pp.AB;
  cross3(r, b, w);
  const double sa = dot3(w, pp.N), tola = 32 * U * norm1(r) * norm1(b) * pp.AB;
  cross3(r, a, w);
  const double sb = dot3(w, pp.N), tolb = 32 * U * norm1(r) * norm1(a) * pp.AB;
  if (sa >= -tola && sa <= q + qerr + tola && sb >= -tolb && sb <= q + qerr + tolb)
    lo = fmin(lo, fabs(dot3(r, pp.N)) / pp.nN - pp.err);
  return lo;
}

/* The trajectory relative to a common origin and a common displacement:
 * X = x0 - x0[0..2], P = (x1 - x0) - mean; S bounds the coordinates' and
 * displacements' magnitudes the rounding is charged to. */
typedef struct rel_motion {
  double X[12], P[12], S, lp_up, pos_err;
} rel_motion;

static void relative_motion(const double x0[12], const double x1[12], int is_pt, rel_motion *m) {
  double D[12], mean[3] = {0, 0, 0}, len[4];
  for (int i = 0; i < 12; i++) {
    m->X[i] = x0[i] - x0[i % 3];
    D[i] = x1[i] - x0[i];
    mean[i % 3] += 0.25 * D[i];
  }
  m->S = 0;
  for (int i = 0; i < 12; i++) {
    m->P[i] = D[i] - mean[i % 3];
    m->S = fmax(m->S, fabs(m->X[i]) + fabs(D[i]) + fabs(m->P[i]));
  }
  for (int k = 0; k < 4; k++) len[k] = sqrt(dot3(m->P + 3 * k, m->P + 3 * k));
  const double lp = is_pt ? len[0] + fmax(fmax(len[1], len[2]), len[3]) : fmax(len[0], len[1]) + fmax(len[2], len[3]);
  m->lp_up = lp * (1 + 8 * U) + 16 * U * m->S;
  m->pos_err = 32 * U * m->S;
}

static double lower_at(const rel_motion *m, int is_pt, double t) {
  double x[12];
  for (int i = 0; i < 12; i++) x[i] = m->X[i] + t * m->P[i];
  return (is_pt ? bs_ccd_pt_dist_lower(x) : bs_ccd_ee_dist_lower(x)) - m->pos_err;
}

static int accd(const double x0[12], const double x1[12], int is_pt, double s, int max_iter, double *t,
                bs_error *err) {
  const char *what = is_pt ? "point-triangle CCD" : "edge-edge CCD";
  *t = 0;
  for (int i = 0; i < 12; i++)
    if (!isfinite(x0[i]) || !isfinite(x1[i])) return bs_error_set(err, BS_EINPUT, "%s: a coordinate is not finite", what);
  if (!(s > 0 && s <= 0.999)) return bs_error_set(err, BS_EINPUT, "%s: gap fraction s %g is not in (0, 0.999]", what, s);
  if (max_iter < 1) return bs_error_set(err, BS_EINPUT, "%s: max_iter %d < 1", what, max_iter);
  rel_motion m;
  relative_motion(x0, x1, is_pt, &m);
  const double lo0 = lower_at(&m, is_pt, 0), g = s * lo0, eta = (1 - s) * (1 - 1e-9);
  if (!(lo0 > 0) || !(s * g > 64 * U * (m.S + m.lp_up)))
    return bs_error_set(err, BS_IPC_ECONTACT, "%s: start distance %g is within rounding of contact", what, lo0);
  double tc = 0, cert = lo0; /* the last accepted time and its certified distance */
  for (int it = 0; it < max_iter; it++) {
    const double tl = eta * cert / m.lp_up, tn = tc + tl;
    if (tn >= 1) { /* [tc, 1] is within the safe step */
      *t = 1;
      return BS_OK;
    }
    /* at tn: evaluated, or by the bound from tc (tn's rounding included) */
    const double lip = cert - m.lp_up * (tl * (1 + 4 * U) + 2 * U * tn);
    const double cn = fmax(lower_at(&m, is_pt, tn), lip);
    if (!(cn >= g)) break;
    tc = tn, cert = cn;
    if (it == max_iter - 1) {
      *t = tc;
      return BS_IPC_CCD_CAPPED;
    }
  }
  *t = tc;
  return BS_OK;
}

int bs_ccd_pt(const double x0[12], const double x1[12], double s, int max_iter, double *t, bs_error *err) {
  return accd(x0, x1, 1, s, max_iter, t, err);
}

int bs_ccd_ee(const double x0[12], const double x1[12], double s, int max_iter, double *t, bs_error *err) {
  return accd(x0, x1, 0, s, max_iter, t, err);
}
