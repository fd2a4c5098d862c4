/* Additive CCD (bs_ccd_pt, bs_ccd_ee; bs_ipc.h) against brute force on the
 * exact linear trajectories: the distance sampled on a fine grid of t with
 * golden-section refinement around every sampled local minimum, from
 * Ericson's closed forms (Real-Time Collision Detection 5.1.5, 5.1.9;
 * independent of the library). For every motion:
 *   - over [0, t_ccd] the distance never falls below s^2 d0 (so no contact,
 *     in particular none at a time t* where brute force finds the distance
 *     below a tiny threshold, is passed over: t_ccd < t*), and at t_ccd < 1
 *     it is at least s d0 (both with a 1% allowance for the bound's
 *     rounding);
 *   - when the distance stays above 1.2 s d0 over [0, 1], t_ccd = 1 (the gap
 *     is the only cost).
 * Named motions: a point through a triangle, crossing edges, grazing
 * motions, a rotating edge (per-vertex linear sub-steps), parallel edges
 * sliding; then 50000 random point-triangle and 50000 random edge-edge
 * trajectories (seeded), most built to pass at a chosen time within
 * 0, 1e-12 ... 1e-2 of contact, inside or just outside the features. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "bs_ipc.h"
#define BS_TEST_SEED 0x5DEECE66Dull
#include "test_random.h"

#define S_GAP 0.1
#define MAX_ITER 100000
#define HALF_PI 1.5707963267948966

#include "ipc_ref.h"

/* The distance at time t of the linear motion x0 -> x1. */
static double dist_at(const double *x0, const double *x1, int is_pt, double t) {
  double x[12];
  for (int i = 0; i < 12; i++) x[i] = x0[i] + t * (x1[i] - x0[i]);
  return sqrt(is_pt ? ericson_pt(x, x + 3, x + 6, x + 9) : ericson_ee(x, x + 3, x + 6, x + 9));
}

/* Golden-section minimum of the distance on [a, b]. */
static double golden(const double *x0, const double *x1, int is_pt, double a, double b) {
  const double r = 0.6180339887498949;
  double c = b - r * (b - a), d = a + r * (b - a), fc = dist_at(x0, x1, is_pt, c), fd = dist_at(x0, x1, is_pt, d);
  for (int it = 0; it < 60 && b - a > 1e-15; it++) {
    if (fc < fd) b = d, d = c, fd = fc, c = b - r * (b - a), fc = dist_at(x0, x1, is_pt, c);
    else a = c, c = d, fc = fd, d = a + r * (b - a), fd = dist_at(x0, x1, is_pt, d);
  }
  return fmin(fmin(fc, fd), fmin(dist_at(x0, x1, is_pt, a), dist_at(x0, x1, is_pt, b)));
}

/* Brute-force minimum of the distance over [0, T]: n samples, each sampled
 * local minimum refined between its neighbours. */
static double min_dist(const double *x0, const double *x1, int is_pt, double T, int n) {
  double f[1025], m = INFINITY;
  for (int i = 0; i <= n; i++) f[i] = dist_at(x0, x1, is_pt, T * i / n), m = fmin(m, f[i]);
  for (int i = 0; i <= n; i++)
    if ((i == 0 || f[i] <= f[i - 1]) && (i == n || f[i] <= f[i + 1]))
      m = fmin(m, golden(x0, x1, is_pt, T * (i > 0 ? i - 1 : 0) / n, T * (i < n ? i + 1 : n) / n));
  return m;
}

typedef struct stats {
  long n, contact_starts, capped, full, collide, near_miss;
  double min_ratio; /* smallest (min distance over [0, t]) / (s^2 d0) */
} stats;

/* CCD of the motion c0 -> c1 checked against brute force on x0 -> x1, the
 * same motion (translated back exactly, when c is translated; file comment). */
static double check_ccd(const double *c0, const double *c1, const double *x0, const double *x1, int is_pt, stats *st,
                        const char *what) {
  double t = -1, size = 0;
  bs_error err;
  const int rc = (is_pt ? bs_ccd_pt : bs_ccd_ee)(c0, c1, S_GAP, MAX_ITER, &t, &err);
  const double d0 = dist_at(x0, x1, is_pt, 0);
  for (int i = 0; i < 12; i++) size = fmax(size, fabs(x0[i] - x0[i % 3]) + fabs(x1[i] - x0[i]));
  st->n++;
  if (rc == BS_IPC_ECONTACT) { /* only for starts within rounding of contact */
    cr_assert(t == 0 && d0 < 1e-9 * size, "%s: contact status at start distance %g: %s", what, d0, err.msg);
    st->contact_starts++;
    return t;
  }
  cr_assert(rc == BS_OK || rc == BS_IPC_CCD_CAPPED, "%s: status %d", what, rc);
  cr_assert(t >= 0 && t <= 1, "%s: t %g", what, t);
  st->capped += rc == BS_IPC_CCD_CAPPED;
  const double g = S_GAP * d0, whole = min_dist(x0, x1, is_pt, 1, 400);
  st->collide += whole < 1e-12, st->near_miss += whole >= 1e-12 && whole < 1e-3 * d0;
  if (t > 0) {
    const double before = min_dist(x0, x1, is_pt, t, 200), at = dist_at(x0, x1, is_pt, t);
    st->min_ratio = fmin(st->min_ratio, before / (S_GAP * g));
    cr_assert(before >= 0.99 * S_GAP * g && before > 0, "%s: distance %g over [0, %.17g] (s^2 d0 = %g)", what,
              before, t, S_GAP * g);
    if (t < 1) cr_assert(at >= 0.99 * g, "%s: distance %g at t = %.17g below the gap %g", what, at, t, g);
  }
  if (whole > 1.2 * g && rc == BS_OK) cr_assert(t == 1, "%s: t = %.17g though the distance stays >= %g", what, t, whole);
  st->full += t == 1;
  return t;
}

static double check_motion(const double *x0, const double *x1, int is_pt, stats *st, const char *what) {
  return check_ccd(x0, x1, x0, x1, is_pt, st, what);
}

static stats new_stats(void) {
  stats s = {0};
  s.min_ratio = INFINITY;
  return s;
}

/* ---- named motions ---- */
Test(ccd, point_through_triangle) {
  const double x0[12] = {0.2, 0.2, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0};
  double x1[12];
  memcpy(x1, x0, sizeof x1);
  x1[2] = -1;
  stats st = new_stats();
  const double t = check_motion(x0, x1, 1, &st, "point through triangle");
  cr_assert(t >= 0.4 && t < 0.5, "t = %g (time of impact 0.5)", t);
  x1[0] = 2; /* the same point passing beside the triangle at 0.6 */
  x1[1] = -1.5;
  check_motion(x0, x1, 1, &st, "point beside triangle");
}

Test(ccd, crossing_edges) {
  const double x0[12] = {-1, 0, 1, 1, 0, 1, 0.3, -1, 0, 0.3, 1, 0};
  double x1[12];
  memcpy(x1, x0, sizeof x1);
  x1[2] = x1[5] = -1;
  stats st = new_stats();
  const double t = check_motion(x0, x1, 0, &st, "crossing edges");
  cr_assert(t >= 0.4 && t < 0.5, "t = %g (time of impact 0.5)", t);
}

Test(ccd, grazing) {
  stats st = new_stats();
  const double heights[] = {0, 1e-9, 1e-3, 0.05, 0.5};
  for (int k = 0; k < 5; k++) { /* a point sliding over the triangle's plane */
    const double x0[12] = {-1, 0.2, heights[k], 0, 0, 0, 1, 0, 0, 0, 1, 0};
    double x1[12];
    memcpy(x1, x0, sizeof x1);
    x1[0] = 2;
    const double t = check_motion(x0, x1, 1, &st, "grazing point");
    if (heights[k] > 0.11) cr_assert(t == 1, "high pass: t = %g", t);
    else cr_assert(t < 1.0 / 3, "low pass: t = %g (over the triangle from t = 1/3)", t);
    /* an edge sliding along the other's plane, crossing it at height h */
    const double e0[12] = {-1, -2, heights[k], -1, 2, heights[k], 0, 0, 0, 1, 0, 0};
    double e1[12];
    memcpy(e1, e0, sizeof e1);
    e1[0] = e1[3] = 2;
    check_motion(e0, e1, 0, &st, "grazing edge");
  }
}

/* Edge a (length 2, centred at the origin) turns in the xz-plane from angle 0
 * to pi/2 in 64 per-vertex linear sub-steps; edge b, along y at x = z = 0.5,
 * is hit at pi/4 (by a's point at radius sqrt(0.5)). */
Test(ccd, rotating_edge) {
  stats st = new_stats();
  const int n = 64;
  int hit = -1;
  for (int k = 0; k < n && hit < 0; k++) {
    const double a0 = HALF_PI * k / n, a1 = HALF_PI * (k + 1) / n;
    const double x0[12] = {-cos(a0), 0, -sin(a0), cos(a0), 0, sin(a0), 0.5, -1, 0.5, 0.5, 1, 0.5};
    const double x1[12] = {-cos(a1), 0, -sin(a1), cos(a1), 0, sin(a1), 0.5, -1, 0.5, 0.5, 1, 0.5};
    const double t = check_motion(x0, x1, 0, &st, "rotating edge");
    if (t < 1) hit = k;
  }
  cr_assert(hit >= 0 && hit <= n / 2, "the sub-step stopped in: %d (contact in sub-step %d)", hit, n / 2 - 1);
  cr_assert(hit >= n / 2 - 3, "stopped far too early: sub-step %d", hit);
}

Test(ccd, parallel_edges_sliding) {
  stats st = new_stats();
  /* exactly parallel, sliding at a constant distance 1e-3: never closer */
  const double x0[12] = {0, 0, 0, 1, 0, 0, -0.5, 0, 1e-3, 0.5, 0, 1e-3};
  double x1[12];
  memcpy(x1, x0, sizeof x1);
  x1[6] += 1.2, x1[9] += 1.2;
  cr_assert_eq(check_motion(x0, x1, 0, &st, "parallel sliding"), 1);
  /* sliding and coming down through: parallel contact at t = 0.5 */
  const double y0[12] = {0, 0, 0, 1, 0, 0, -0.5, 0, 0.3, 0.5, 0, 0.3};
  double y1[12];
  memcpy(y1, y0, sizeof y1);
  y1[6] += 1.2, y1[9] += 1.2, y1[8] = y1[11] = -0.3;
  const double t = check_motion(y0, y1, 0, &st, "parallel descending");
  cr_assert(t >= 0.4 && t < 0.5, "t = %g (contact at 0.5)", t);
  /* nearly parallel (1e-7 rad) */
  y1[11] += 1e-7;
  check_motion(y0, y1, 0, &st, "nearly parallel descending");
}

Test(ccd, statuses) {
  double t = 5;
  bs_error err;
  const double touch[12] = {0.2, 0.2, 0, 0, 0, 0, 1, 0, 0, 0, 1, 0};
  double x1[12];
  memcpy(x1, touch, sizeof x1);
  x1[2] = 1;
  cr_assert_eq(bs_ccd_pt(touch, x1, S_GAP, 100, &t, &err), BS_IPC_ECONTACT);
  cr_assert(t == 0);
  const double x0[12] = {0.2, 0.2, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0};
  cr_assert_eq(bs_ccd_pt(x0, x1, 0, 100, &t, &err), BS_EINPUT);
  cr_assert_eq(bs_ccd_pt(x0, x1, 1, 100, &t, &err), BS_EINPUT);
  cr_assert_eq(bs_ccd_pt(x0, x1, S_GAP, 0, &t, &err), BS_EINPUT);
  x1[4] = NAN;
  cr_assert_eq(bs_ccd_ee(x0, x1, S_GAP, 100, &t, &err), BS_EINPUT);
  cr_assert(t == 0);
  /* no relative motion: t = 1 in one step */
  cr_assert_eq(bs_ccd_pt(x0, x0, S_GAP, 1, &t, &err), BS_OK);
  cr_assert(t == 1);
  /* the cap: a pass at 0.5 over the triangle (~7 steps), 3 allowed: a safe t < 1 */
  const double g0[12] = {-1, 0.2, 0.5, 0, 0, 0, 1, 0, 0, 0, 1, 0};
  double g1[12];
  memcpy(g1, g0, sizeof g1);
  g1[0] = 2;
  cr_assert_eq(bs_ccd_pt(g0, g1, S_GAP, 3, &t, &err), BS_IPC_CCD_CAPPED);
  cr_assert(t > 0 && t < 1 && dist_at(g0, g1, 1, t) >= S_GAP * dist_at(g0, g1, 1, 0));
  /* tiny start distances on a unit-size triangle: 1e-10 certifies a (small)
   * step; 1e-13 is within the rounding bound (~3.5e-12 here): t = 0 */
  double c0[12], c1[12];
  memcpy(c0, x0, sizeof c0);
  memcpy(c1, x0, sizeof c1);
  c0[2] = 1e-10, c1[2] = -1;
  cr_assert_eq(bs_ccd_pt(c0, c1, S_GAP, 100, &t, &err), BS_OK);
  cr_assert(t > 0 && t < 1e-10 && c0[2] + t * (c1[2] - c0[2]) >= S_GAP * 1e-10 * 0.99, "t = %g", t);
  c0[2] = 1e-13;
  cr_assert_eq(bs_ccd_pt(c0, c1, S_GAP, 100, &t, &err), BS_IPC_ECONTACT);
  cr_assert(t == 0);
}

/* ---- random motions ---- */
/* A uniformly random point of [-1, 1]^3, scaled. */
static void rpt(double *p, double scale) {
  for (int c = 0; c < 3; c++) p[c] = scale * (2 * urand() - 1);
}

/* The closest-approach offset of a built near-contact: 0, or +-10^-k. */
static double offset(void) {
  static const double mags[] = {0, 1e-12, 1e-9, 1e-6, 1e-4, 1e-3, 1e-2, 5e-2};
  return mags[(int)(urand() * 8)] * (urand() < 0.5 ? -1 : 1);
}

/* A point-triangle motion: random (1 in 5), else built so that the point is
 * at distance ~offset from a feature of the triangle at a random time t*:
 * barycentric coordinates inside, on an edge, or just outside it. */
static void random_pt(double *x0, double *x1) {
  for (int k = 1; k < 4; k++) rpt(x0 + 3 * k, 1), rpt(x1 + 3 * k, 1), x1[3 * k] += 0.3 * x0[3 * k];
  rpt(x0, 1.5);
  if (urand() < 0.2) {
    rpt(x1, 1.5);
    return;
  }
  const double ts = 0.02 + 0.96 * urand();
  double T[9], l[3] = {urand(), urand(), urand()}, n[3], a[3], b[3], y[3];
  for (int i = 0; i < 9; i++) T[i] = x0[3 + i] + ts * (x1[3 + i] - x0[3 + i]);
  const int mode = (int)(urand() * 3); /* inside, on an edge, just outside */
  if (mode > 0) l[(int)(urand() * 3)] = mode == 1 ? 0 : -0.02 * urand();
  const double sum = l[0] + l[1] + l[2];
  for (int c = 0; c < 3; c++) a[c] = T[3 + c] - T[c], b[c] = T[6 + c] - T[c];
  n[0] = a[1] * b[2] - a[2] * b[1], n[1] = a[2] * b[0] - a[0] * b[2], n[2] = a[0] * b[1] - a[1] * b[0];
  const double nn = sqrt(dot3(n, n)), off = offset();
  for (int c = 0; c < 3; c++) y[c] = (l[0] * T[c] + l[1] * T[3 + c] + l[2] * T[6 + c]) / sum + off * n[c] / nn;
  for (int c = 0; c < 3; c++) x1[c] = x0[c] + (y[c] - x0[c]) / ts;
}

/* An edge-edge motion, likewise: edge b passes at ~offset from a point of
 * edge a (inside, at an end, just beyond it) at t*, sometimes nearly parallel
 * to it. */
static void random_ee(double *x0, double *x1) {
  for (int k = 0; k < 2; k++) rpt(x0 + 3 * k, 1), rpt(x1 + 3 * k, 1);
  for (int k = 2; k < 4; k++) rpt(x0 + 3 * k, 1.5);
  if (urand() < 0.2) {
    rpt(x1 + 6, 1.5), rpt(x1 + 9, 1.5);
    return;
  }
  const double ts = 0.02 + 0.96 * urand(), mode = urand();
  const double sa = mode < 0.4 ? urand() : mode < 0.7 ? (urand() < 0.5 ? 0 : 1) : -0.02 * urand(), sb = urand();
  double A[6], ea[3], dir[3], n[3], y[3];
  for (int i = 0; i < 6; i++) A[i] = x0[i] + ts * (x1[i] - x0[i]);
  for (int c = 0; c < 3; c++) ea[c] = A[3 + c] - A[c];
  rpt(dir, 1);
  if (urand() < 0.25) /* nearly parallel */
    for (int c = 0; c < 3; c++) dir[c] = ea[c] + 1e-6 * pow(10, 5 * urand()) * dir[c];
  n[0] = ea[1] * dir[2] - ea[2] * dir[1], n[1] = ea[2] * dir[0] - ea[0] * dir[2], n[2] = ea[0] * dir[1] - ea[1] * dir[0];
  const double nn = sqrt(dot3(n, n)), off = offset(), len = 0.3 + urand();
  const double dl = sqrt(dot3(dir, dir));
  for (int c = 0; c < 3; c++) y[c] = A[c] + sa * ea[c] + (nn > 0 ? off * n[c] / nn : 0);
  for (int c = 0; c < 3; c++) {
    const double b0 = y[c] - sb * len * dir[c] / dl, b1 = b0 + len * dir[c] / dl;
    x1[6 + c] = x0[6 + c] + (b0 - x0[6 + c]) / ts;
    x1[9 + c] = x0[9 + c] + (b1 - x0[9 + c]) / ts;
  }
}

static void report(const char *what, const stats *st) {
  fprintf(stderr,
          "%s: %ld motions: %ld touching to 1e-12, %ld near misses (< 1e-3 d0), %ld contact-free (t = 1), %ld "
          "starts within rounding, %ld capped; min distance before t / (s^2 d0) >= %.3g\n",
          what, st->n, st->collide, st->near_miss, st->full, st->contact_starts, st->capped, st->min_ratio);
}

Test(ccd, random_point_triangle, .timeout = 120) {
  stats st = new_stats();
  double x0[12], x1[12];
  for (int it = 0; it < 50000; it++) {
    random_pt(x0, x1);
    char what[64];
    snprintf(what, sizeof what, "random point-triangle %d", it);
    check_motion(x0, x1, 1, &st, what);
  }
  report("point-triangle", &st);
  cr_assert(st.collide > 5000 && st.near_miss > 5000 && st.capped == 0);
}

/* Random motions scaled by 1e-6 or 1e3 and translated by 2^10 ... 2^30
 * (coordinates rounded to the translated grid: the CCD sees those; brute
 * force takes them minus the translation, which is exact). */
Test(ccd, random_translated_scaled, .timeout = 120) {
  stats st = new_stats();
  double x0[12], x1[12], c0[12], c1[12];
  const double scales[2] = {1e-6, 1e3}, shifts[3] = {0x1p10, 0x1p20, 0x1p30};
  for (int it = 0; it < 20000; it++) {
    const int is_pt = it % 2;
    const double sc = scales[(it / 2) % 2], T = shifts[(it / 4) % 3] * sc;
    if (is_pt) random_pt(x0, x1);
    else random_ee(x0, x1);
    for (int i = 0; i < 12; i++) {
      c0[i] = sc * x0[i] + T, c1[i] = sc * x1[i] + T;
      x0[i] = c0[i] - T, x1[i] = c1[i] - T;
    }
    char what[96];
    snprintf(what, sizeof what, "translated %s %d (scale %g, shift %g)", is_pt ? "point-triangle" : "edge-edge", it,
             sc, T);
    check_ccd(c0, c1, x0, x1, is_pt, &st, what);
  }
  report("translated and scaled", &st);
}

Test(ccd, random_edge_edge, .timeout = 120) {
  stats st = new_stats();
  double x0[12], x1[12];
  for (int it = 0; it < 50000; it++) {
    random_ee(x0, x1);
    char what[64];
    snprintf(what, sizeof what, "random edge-edge %d", it);
    check_motion(x0, x1, 0, &st, what);
  }
  report("edge-edge", &st);
  cr_assert(st.collide > 5000 && st.near_miss > 5000 && st.capped == 0);
}
