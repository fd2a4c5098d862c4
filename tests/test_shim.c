/* test_shim.c — the CGAL geometry of the shim, through its C API: exact
 * predicates, the AABB tree (closest point, box query, update), signed
 * distance, surface self-intersection, and their error paths. Reference values
 * come from brute force over all triangles with an independent algorithm. */
#include <criterion/criterion.h>
#include <math.h>
#include <omp.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "bs_shim.h"
#include "bs_vec3.h"

/* ------------------------------------------------------------------------ */
/* Helpers */

static uint64_t rng_state = 88172645463325252ull;
static double urand(void) { /* xorshift64*, uniform in [0, 1) */
  rng_state ^= rng_state >> 12;
  rng_state ^= rng_state << 25;
  rng_state ^= rng_state >> 27;
  return (double)((rng_state * 0x2545F4914F6CDD1Dull) >> 11) * (1.0 / 9007199254740992.0);
}
static double urange(double lo, double hi) { return lo + (hi - lo) * urand(); }

static double dist(const double *u, const double *v) {
  double e[3] = {u[0] - v[0], u[1] - v[1], u[2] - v[2]};
  return sqrt(bs_dot3(e, e));
}

/* Distance from p to triangle (a, b, c) by Ericson's Voronoi-region method
 * (Real-Time Collision Detection, 5.1.5), a different formulation from the
 * shim's (perpendicular foot or nearest side). Non-degenerate triangles only. */
static double tri_dist(const double *p, const double *a, const double *b, const double *c) {
  double ab[3], ac[3], ap[3], bp[3], cp[3], q[3];
  for (int k = 0; k < 3; k++) {
    ab[k] = b[k] - a[k], ac[k] = c[k] - a[k], ap[k] = p[k] - a[k], bp[k] = p[k] - b[k], cp[k] = p[k] - c[k];
  }
  double d1 = bs_dot3(ab, ap), d2 = bs_dot3(ac, ap), d3 = bs_dot3(ab, bp), d4 = bs_dot3(ac, bp), d5 = bs_dot3(ab, cp), d6 = bs_dot3(ac, cp);
  double vc = d1 * d4 - d3 * d2, vb = d5 * d2 - d1 * d6, va = d3 * d6 - d5 * d4, s = 0, t = 0;
  if (d1 <= 0 && d2 <= 0) s = 0, t = 0;
  else if (d3 >= 0 && d4 <= d3) s = 1, t = 0;
  else if (vc <= 0 && d1 >= 0 && d3 <= 0) s = d1 / (d1 - d3), t = 0;
  else if (d6 >= 0 && d5 <= d6) s = 0, t = 1;
  else if (vb <= 0 && d2 >= 0 && d6 <= 0) s = 0, t = d2 / (d2 - d6);
  else if (va <= 0 && d4 - d3 >= 0 && d5 - d6 >= 0) {
    double u = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    s = 1 - u, t = u;
  } else s = vb / (va + vb + vc), t = vc / (va + vb + vc);
  for (int k = 0; k < 3; k++) q[k] = a[k] + s * ab[k] + t * ac[k];
  return dist(p, q);
}

typedef struct {
  int64_t np, nt;
  double *x;
  int32_t *t;
} soup;

static void soup_free(soup *s) {
  free(s->x);
  free(s->t);
  memset(s, 0, sizeof *s);
}

static double brute_dist(const soup *s, const double *p, int32_t *tri) {
  double best = INFINITY;
  for (int64_t i = 0; i < s->nt; i++) {
    const int32_t *v = s->t + 3 * i;
    double d = tri_dist(p, s->x + 3 * v[0], s->x + 3 * v[1], s->x + 3 * v[2]);
    if (d < best) {
      best = d;
      if (tri) *tri = (int32_t)i;
    }
  }
  return best;
}

/* Surface of the box [lo, hi]^3: 8 corners (corner k has x = bit 0, y = bit
 * 1, z = bit 2 of k), 12 outward triangles; each face is split along the
 * diagonal through its corner of lowest index. */
static soup make_cube(double lo, double hi) {
  static const int32_t quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                                      {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  soup s = {8, 12, malloc(24 * sizeof(double)), malloc(36 * sizeof(int32_t))};
  for (int k = 0; k < 8; k++)
    for (int d = 0; d < 3; d++) s.x[3 * k + d] = (k >> d) & 1 ? hi : lo;
  for (int f = 0; f < 6; f++) {
    const int32_t *q = quads[f];
    int32_t t[6] = {q[0], q[1], q[2], q[0], q[2], q[3]};
    memcpy(s.t + 6 * f, t, sizeof t);
  }
  return s;
}

/* Unit icosphere: the icosahedron subdivided `level` times, projected on the
 * sphere (10 4^level + 2 points, 20 4^level triangles). */
static soup make_icosphere(int level) {
  const double g = (1.0 + sqrt(5.0)) / 2.0;
  const double v0[12][3] = {{-1, g, 0}, {1, g, 0}, {-1, -g, 0}, {1, -g, 0}, {0, -1, g}, {0, 1, g},
                            {0, -1, -g}, {0, 1, -g}, {g, 0, -1}, {g, 0, 1}, {-g, 0, -1}, {-g, 0, 1}};
  const int32_t f0[20][3] = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                             {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
                             {3, 8, 9},  {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  int64_t np_final = 10 * (1LL << (2 * level)) + 2, nt_final = 20 * (1LL << (2 * level));
  soup s = {12, 20, malloc(3 * np_final * sizeof(double)), malloc(3 * nt_final * sizeof(int32_t))};
  for (int i = 0; i < 12; i++) {
    double n = sqrt(bs_dot3(v0[i], v0[i]));
    for (int d = 0; d < 3; d++) s.x[3 * i + d] = v0[i][d] / n;
  }
  memcpy(s.t, f0, sizeof f0);
  int32_t *mid = malloc(np_final * np_final * sizeof(int32_t));
  for (int l = 0; l < level; l++) {
    for (int64_t i = 0; i < np_final * np_final; i++) mid[i] = -1;
    int32_t *nt = malloc(3 * 4 * s.nt * sizeof(int32_t));
    for (int64_t f = 0; f < s.nt; f++) {
      int32_t v[3] = {s.t[3 * f], s.t[3 * f + 1], s.t[3 * f + 2]}, m[3];
      for (int e = 0; e < 3; e++) {
        int32_t a = v[e], b = v[(e + 1) % 3];
        int32_t *slot = &mid[(int64_t)(a < b ? a : b) * np_final + (a < b ? b : a)];
        if (*slot < 0) {
          double p[3], n;
          for (int d = 0; d < 3; d++) p[d] = 0.5 * (s.x[3 * a + d] + s.x[3 * b + d]);
          n = sqrt(bs_dot3(p, p));
          for (int d = 0; d < 3; d++) s.x[3 * s.np + d] = p[d] / n;
          *slot = (int32_t)s.np++;
        }
        m[e] = *slot;
      }
      int32_t q[12] = {v[0], m[0], m[2], v[1], m[1], m[0], v[2], m[2], m[1], m[0], m[1], m[2]};
      memcpy(nt + 12 * f, q, sizeof q);
    }
    free(s.t);
    s.t = nt;
    s.nt *= 4;
  }
  free(mid);
  cr_assert_eq(s.np, np_final);
  cr_assert_eq(s.nt, nt_final);
  return s;
}

static bs_shim_tree *tree_of(const soup *s) {
  bs_shim_tree *t = NULL;
  bs_error err = {0};
  cr_assert_eq(bs_shim_tree_create(s->x, s->np, s->t, s->nt, &t, &err), BS_OK, "%s", err.msg);
  cr_assert_not_null(t);
  return t;
}

/* Checks one closest-point answer against brute force and for consistency:
 * its distance, its triangle's distance, the barycentric reconstruction and
 * the zero weights off the feature. */
static void check_closest(const soup *s, const double *q, const double *cp, int32_t tri, const double *w, int f) {
  double ref = brute_dist(s, q, NULL);
  double d = dist(q, cp);
  cr_assert(fabs(d - ref) <= 1e-12 * (1 + ref), "q = (%g %g %g): tree %.17g, brute force %.17g", q[0], q[1], q[2], d,
            ref);
  cr_assert(tri >= 0 && tri < s->nt);
  const int32_t *v = s->t + 3 * tri;
  double dt = tri_dist(q, s->x + 3 * v[0], s->x + 3 * v[1], s->x + 3 * v[2]);
  cr_assert(fabs(dt - d) <= 1e-12 * (1 + d), "triangle %d is at %.17g, not %.17g", tri, dt, d);
  cr_assert(fabs(w[0] + w[1] + w[2] - 1.0) <= 1e-14);
  for (int k = 0; k < 3; k++) {
    double r = w[0] * s->x[3 * v[0] + k] + w[1] * s->x[3 * v[1] + k] + w[2] * s->x[3 * v[2] + k];
    cr_assert(fabs(r - cp[k]) <= 1e-13, "barycentric weights do not give the point");
    cr_assert(w[k] >= 0.0 && w[k] <= 1.0);
  }
  cr_assert(f >= 0 && f <= 6);
  if (f == 0) cr_assert(w[0] > 0 && w[1] > 0 && w[2] > 0, "face feature with a zero weight");
  if (f >= 1 && f <= 3) { /* edge f joins vertices f-1 and f%3; the third weight is 0 */
    int off = (f + 1) % 3;
    cr_assert(w[off] == 0.0 && w[f - 1] > 0 && w[f % 3] > 0, "edge feature %d with weights %g %g %g", f, w[0], w[1],
              w[2]);
  }
  if (f >= 4) cr_assert(w[f - 4] == 1.0, "vertex feature %d with weights %g %g %g", f, w[0], w[1], w[2]);
}

/* ------------------------------------------------------------------------ */
/* Exact predicates */

Test(shim_predicates, orient3d_sign_convention) {
  const double o[3] = {0, 0, 0}, e1[3] = {1, 0, 0}, e2[3] = {0, 1, 0}, e3[3] = {0, 0, 1}, m3[3] = {0, 0, -1};
  /* det[b-a, c-a, d-a] = det[e1, e2, e3] = 1 > 0: +1 (CGAL::orientation;
   * the opposite of Shewchuk's orient3d) */
  cr_assert_eq(bs_shim_orient3d(o, e1, e2, e3), 1);
  cr_assert_eq(bs_shim_orient3d(o, e2, e1, e3), -1);
  cr_assert_eq(bs_shim_orient3d(o, e1, e2, m3), -1);
  const double p[3] = {0.25, 0.5, 0}; /* in the plane z = 0 */
  cr_assert_eq(bs_shim_orient3d(o, e1, e2, p), 0);
  /* the same sign under even permutations, the opposite under odd ones */
  cr_assert_eq(bs_shim_orient3d(e1, e2, o, e3), 1);
  cr_assert_eq(bs_shim_orient3d(e3, e2, e1, o), 1);
  cr_assert_eq(bs_shim_orient3d(e3, e1, e2, o), -1);
}

Test(shim_predicates, orient3d_exact_near_degenerate) {
  /* Points of the plane z = x, exactly representable: a, b, c, d coplanar
   * exactly, whatever the magnitudes, so the exact answer is 0; moving d by
   * one ulp off the plane gives a fixed nonzero sign, of opposite signs for
   * the two directions. A double-precision determinant gets many of these
   * wrong (counted below). */
  int naive_wrong = 0;
  for (int scale = 0; scale < 3; scale++) {
    double off = scale == 0 ? 0.0 : (scale == 1 ? 1e6 : 1e12);
    double a[3] = {off + 0.1, 0.2, off + 0.1}, b[3] = {off + 0.7, 0.3, off + 0.7}, c[3] = {off + 0.3, 0.9, off + 0.3};
    int ref = 0;
    for (int i = 0; i < 300; i++) {
      double x = off + urange(-2, 2), y = urange(-2, 2);
      double d[3] = {x, y, x};
      cr_assert_eq(bs_shim_orient3d(a, b, c, d), 0, "coplanar point (%.17g %.17g %.17g) off %g", x, y, x, off);
      double up[3] = {x, y, nextafter(x, INFINITY)}, down[3] = {x, y, nextafter(x, -INFINITY)};
      int su = bs_shim_orient3d(a, b, c, up), sd = bs_shim_orient3d(a, b, c, down);
      cr_assert(su != 0 && sd == -su, "one ulp above/below: %d %d", su, sd);
      if (ref == 0) ref = su;
      cr_assert_eq(su, ref, "the side of the plane changed with the point");
      /* naive determinant, for the record */
      double u[3], v[3], w[3];
      for (int k = 0; k < 3; k++) u[k] = b[k] - a[k], v[k] = c[k] - a[k], w[k] = up[k] - a[k];
      double det = u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0]) +
                   u[2] * (v[0] * w[1] - v[1] * w[0]);
      if ((det > 0) - (det < 0) != su) naive_wrong++;
    }
    /* (b-a) x (c-a) = D (-1, 0, 1) with D > 0 for this a, b, c: a point
     * with z > x is on the positive side */
    cr_assert_eq(ref, 1);
  }
  cr_assert_gt(naive_wrong, 0, "the near-degenerate cases should defeat a double determinant");
  /* four collinear points, and a point repeated: coplanar */
  const double l0[3] = {0.1, 0.2, 0.3}, l1[3] = {0.2, 0.4, 0.6}, l2[3] = {0.4, 0.8, 1.2}, q[3] = {5, -3, 2};
  cr_assert_eq(bs_shim_orient3d(l0, l1, l2, q), 0);
  cr_assert_eq(bs_shim_orient3d(l0, l0, l2, q), 0);
}

Test(shim_predicates, orient3d_bad_input) {
  const double o[3] = {0, 0, 0}, e1[3] = {1, 0, 0}, e2[3] = {0, 1, 0}, bad[3] = {0, NAN, 1};
  cr_assert_eq(bs_shim_orient3d(NULL, e1, e2, o), BS_EINPUT);
  cr_assert_eq(bs_shim_orient3d(o, e1, e2, bad), BS_EINPUT);
  const double inf[3] = {INFINITY, 0, 0};
  cr_assert_eq(bs_shim_orient3d(inf, e1, e2, o), BS_EINPUT);
}

Test(shim_predicates, point_in_tet) {
  const double a[3] = {0, 0, 0}, b[3] = {1, 0, 0}, c[3] = {0, 1, 0}, d[3] = {0, 0, 1};
  const double inside[3] = {0.25, 0.25, 0.25}, outside[3] = {1, 1, 1};
  const double on_face[3] = {0.25, 0.25, 0.5}; /* x + y + z = 1 exactly */
  const double on_face0[3] = {0, 0.2, 0.3}, on_edge[3] = {0.5, 0, 0};
  const double just_out[3] = {0.25, 0.25, nextafter(0.5, 1)}, just_in[3] = {0.25, 0.25, nextafter(0.5, 0)};
  const double below[3] = {0.2, 0.2, -1e-300};
  for (int inv = 0; inv < 2; inv++) { /* the same answers for the inverted tet (b and c swapped) */
    const double *B = inv ? c : b, *C = inv ? b : c;
    cr_assert_eq(bs_shim_point_in_tet(inside, a, B, C, d), 1);
    cr_assert_eq(bs_shim_point_in_tet(outside, a, B, C, d), -1);
    cr_assert_eq(bs_shim_point_in_tet(on_face, a, B, C, d), 0);
    cr_assert_eq(bs_shim_point_in_tet(on_face0, a, B, C, d), 0);
    cr_assert_eq(bs_shim_point_in_tet(on_edge, a, B, C, d), 0);
    cr_assert_eq(bs_shim_point_in_tet(d, a, B, C, d), 0);
    cr_assert_eq(bs_shim_point_in_tet(a, a, B, C, d), 0);
    cr_assert_eq(bs_shim_point_in_tet(just_out, a, B, C, d), -1);
    cr_assert_eq(bs_shim_point_in_tet(just_in, a, B, C, d), 1);
    cr_assert_eq(bs_shim_point_in_tet(below, a, B, C, d), -1);
  }
  /* flat tet (a square in z = 0): no interior */
  const double f3[3] = {1, 1, 0};
  const double in_hull[3] = {0.9, 0.9, 0}, off_plane[3] = {0.5, 0.5, 1e-300}, far[3] = {2, 2, 0};
  cr_assert_eq(bs_shim_point_in_tet(in_hull, a, b, c, f3), 0);
  cr_assert_eq(bs_shim_point_in_tet(off_plane, a, b, c, f3), -1);
  cr_assert_eq(bs_shim_point_in_tet(far, a, b, c, f3), -1);
  /* flat and collinear (four points on the x axis) */
  const double x1[3] = {1, 0, 0}, x2[3] = {2, 0, 0}, x3[3] = {3, 0, 0};
  const double on_line[3] = {2.5, 0, 0}, beyond[3] = {4, 0, 0}, off_line[3] = {1, 1e-300, 0};
  cr_assert_eq(bs_shim_point_in_tet(on_line, a, x1, x3, x2), 0);
  cr_assert_eq(bs_shim_point_in_tet(beyond, a, x1, x3, x2), -1);
  cr_assert_eq(bs_shim_point_in_tet(off_line, a, x1, x3, x2), -1);
  /* errors */
  cr_assert_eq(bs_shim_point_in_tet(NULL, a, b, c, d), BS_EINPUT);
  const double nan3[3] = {NAN, 0, 0};
  cr_assert_eq(bs_shim_point_in_tet(nan3, a, b, c, d), BS_EINPUT);
}

Test(shim_predicates, point_in_tet_random_against_barycentric) {
  /* Away from the boundary, the exact answer agrees with barycentric
   * coordinates computed in doubles. */
  for (int i = 0; i < 500; i++) {
    double v[4][3], p[3];
    for (int k = 0; k < 4; k++)
      for (int j = 0; j < 3; j++) v[k][j] = urange(-1, 1);
    for (int j = 0; j < 3; j++) p[j] = urange(-1, 1);
    double e[3][3], r[3];
    for (int k = 0; k < 3; k++)
      for (int j = 0; j < 3; j++) e[k][j] = v[k + 1][j] - v[0][j];
    for (int j = 0; j < 3; j++) r[j] = p[j] - v[0][j];
    /* Cramer's rule for p - v0 = sum l_k e_k */
    double det = e[0][0] * (e[1][1] * e[2][2] - e[1][2] * e[2][1]) - e[0][1] * (e[1][0] * e[2][2] - e[1][2] * e[2][0]) +
                 e[0][2] * (e[1][0] * e[2][1] - e[1][1] * e[2][0]);
    if (fabs(det) < 1e-3) continue;
    double l[4];
    for (int k = 0; k < 3; k++) {
      double m[3][3];
      memcpy(m, e, sizeof m);
      for (int j = 0; j < 3; j++) m[k][j] = r[j];
      l[k + 1] = (m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
                  m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])) /
                 det;
    }
    l[0] = 1 - l[1] - l[2] - l[3];
    double mn = fmin(fmin(l[0], l[1]), fmin(l[2], l[3]));
    if (fabs(mn) < 1e-9) continue;
    int expect = mn > 0 ? 1 : -1;
    cr_assert_eq(bs_shim_point_in_tet(p, v[0], v[1], v[2], v[3]), expect, "case %d", i);
  }
}

/* ------------------------------------------------------------------------ */
/* AABB tree: closest point */

Test(shim_tree, closest_on_cube_features) {
  soup s = make_cube(0, 1);
  bs_shim_tree *t = tree_of(&s);
  double cp[3], w[3];
  int32_t tri;
  int f;
  /* a face point from outside and from inside (off the faces' diagonals) */
  const double qf[3] = {0.3, 0.6, -0.5}, qi[3] = {0.3, 0.6, 0.1};
  for (int k = 0; k < 2; k++) {
    const double *q = k ? qi : qf;
    cr_assert_eq(bs_shim_tree_closest(t, q, cp, &tri, w, &f), BS_OK);
    cr_assert_float_eq(cp[0], 0.3, 1e-15);
    cr_assert_float_eq(cp[1], 0.6, 1e-15);
    cr_assert_eq(cp[2], 0.0);
    cr_assert_eq(f, BS_SHIM_FACE);
    cr_assert_lt(tri, 2, "a triangle of the face z = 0");
    check_closest(&s, q, cp, tri, w, f);
  }
  /* an edge point: the cube edge y = z = 0 */
  const double qe[3] = {0.4, -0.5, -0.5};
  cr_assert_eq(bs_shim_tree_closest(t, qe, cp, &tri, w, &f), BS_OK);
  cr_assert(f >= BS_SHIM_EDGE01 && f <= BS_SHIM_EDGE20, "feature %d", f);
  cr_assert_float_eq(cp[0], 0.4, 1e-15);
  cr_assert_eq(cp[1], 0.0);
  cr_assert_eq(cp[2], 0.0);
  check_closest(&s, qe, cp, tri, w, f);
  /* a corner, from outside */
  const double qc[3] = {1.5, 1.75, 2};
  cr_assert_eq(bs_shim_tree_closest(t, qc, cp, &tri, w, &f), BS_OK);
  cr_assert(f >= BS_SHIM_VERTEX0 && f <= BS_SHIM_VERTEX2, "feature %d", f);
  cr_assert(cp[0] == 1 && cp[1] == 1 && cp[2] == 1);
  cr_assert_eq(s.t[3 * tri + f - 4], 7, "the corner (1,1,1) is point 7");
  check_closest(&s, qc, cp, tri, w, f);
  /* outputs are optional */
  cr_assert_eq(bs_shim_tree_closest(t, qc, NULL, NULL, NULL, NULL), BS_OK);
  cr_assert_eq(bs_shim_tree_closest(t, qc, NULL, &tri, NULL, NULL), BS_OK);
  cr_assert(tri >= 0 && tri < 12);
  bs_shim_tree_destroy(&t);
  cr_assert_null(t);
  soup_free(&s);
}

Test(shim_tree, closest_matches_brute_force) {
  soup shapes[2] = {make_cube(-0.5, 1.5), make_icosphere(3)};
  for (int sh = 0; sh < 2; sh++) {
    soup *s = &shapes[sh];
    bs_shim_tree *t = tree_of(s);
    for (int i = 0; i < 400; i++) {
      double q[3] = {urange(-2, 2), urange(-2, 2), urange(-2, 2)}, cp[3], w[3], cp2[3], w2[3];
      int32_t tri, tri2;
      int f, f2;
      cr_assert_eq(bs_shim_tree_closest(t, q, cp, &tri, w, &f), BS_OK);
      check_closest(s, q, cp, tri, w, f);
      /* with a hint (random, or the answer itself): the same distance */
      int32_t hint = (i % 2) ? tri : (int32_t)(urand() * (double)s->nt);
      cr_assert_eq(bs_shim_tree_closest_hint(t, q, hint, cp2, &tri2, w2, &f2), BS_OK);
      check_closest(s, q, cp2, tri2, w2, f2);
      cr_assert(fabs(dist(q, cp) - dist(q, cp2)) <= 1e-14 * (1 + dist(q, cp)));
    }
    /* a surface point of the icosphere: distance 0 (to round-off), at a vertex */
    double cp[3], w[3];
    int32_t tri;
    int f;
    cr_assert_eq(bs_shim_tree_closest(t, s->x + 3 * 5, cp, &tri, w, &f), BS_OK);
    cr_assert_eq(dist(cp, s->x + 3 * 5), 0.0);
    cr_assert(f >= BS_SHIM_VERTEX0);
    int32_t hint_bad = (int32_t)s->nt;
    cr_assert_eq(bs_shim_tree_closest_hint(t, s->x, hint_bad, cp, &tri, w, &f), BS_EINPUT);
    cr_assert_eq(bs_shim_tree_closest_hint(t, s->x, -1, cp, &tri, w, &f), BS_OK);
    bs_shim_tree_destroy(&t);
    soup_free(s);
  }
}

Test(shim_tree, closest_small_and_degenerate_trees) {
  /* one triangle (CGAL's single-primitive path), then a triangle and a
   * degenerate one (collinear vertices) */
  double x[] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 2, 2, 2, 3, 3, 3, 4, 4, 4};
  int32_t tr[] = {0, 1, 2, 3, 5, 4};
  soup s1 = {3, 1, x, tr}, s2 = {6, 2, x, tr};
  bs_shim_tree *t = tree_of(&s1);
  double q[3] = {0.2, 0.2, 3}, cp[3], w[3];
  int32_t tri;
  int f;
  cr_assert_eq(bs_shim_tree_closest(t, q, cp, &tri, w, &f), BS_OK);
  cr_assert(tri == 0 && f == BS_SHIM_FACE && cp[2] == 0.0);
  bs_shim_tree_destroy(&t);
  t = tree_of(&s2);
  double q2[3] = {3.5, 3.5, 3.6}; /* nearest: the degenerate triangle's side */
  cr_assert_eq(bs_shim_tree_closest(t, q2, cp, &tri, w, &f), BS_OK);
  cr_assert_eq(tri, 1);
  cr_assert(f >= BS_SHIM_EDGE01 && f <= BS_SHIM_EDGE20, "feature %d", f);
  cr_assert_float_eq(dist(q2, cp), sqrt(2.0 / 3.0) * 0.1, 1e-14);
  double q3[3] = {5, 5, 5};
  cr_assert_eq(bs_shim_tree_closest(t, q3, cp, &tri, w, &f), BS_OK);
  cr_assert(tri == 1 && cp[0] == 4 && f >= BS_SHIM_VERTEX0);
  cr_assert_eq(w[f - 4], 1.0);
  bs_shim_tree_destroy(&t);
}

/* ------------------------------------------------------------------------ */
/* AABB tree: box query and update */

static int cmp_i32(const void *a, const void *b) {
  int32_t x = *(const int32_t *)a, y = *(const int32_t *)b;
  return (x > y) - (x < y);
}

/* Triangles of s whose boxes meet [lo, hi], sorted; returns the count. */
static int64_t brute_within(const soup *s, const double *lo, const double *hi, int32_t *out) {
  int64_t n = 0;
  for (int64_t i = 0; i < s->nt; i++) {
    int ok = 1;
    for (int k = 0; k < 3; k++) {
      double a = s->x[3 * s->t[3 * i] + k], b = s->x[3 * s->t[3 * i + 1] + k], c = s->x[3 * s->t[3 * i + 2] + k];
      if (fmax(a, fmax(b, c)) < lo[k] || fmin(a, fmin(b, c)) > hi[k]) ok = 0;
    }
    if (ok) out[n++] = (int32_t)i;
  }
  return n;
}

Test(shim_tree, within_matches_brute_force) {
  soup s = make_icosphere(3);
  bs_shim_tree *t = tree_of(&s);
  int32_t *got = malloc(s.nt * sizeof(int32_t)), *ref = malloc(s.nt * sizeof(int32_t));
  int64_t total = 0;
  for (int i = 0; i < 300; i++) {
    double c[3] = {urange(-1.2, 1.2), urange(-1.2, 1.2), urange(-1.2, 1.2)}, h = urange(0, 0.5);
    double lo[3] = {c[0] - h, c[1] - h, c[2] - h}, hi[3] = {c[0] + h, c[1] + 0.5 * h, c[2] + h};
    int64_t n = -1, nref = brute_within(&s, lo, hi, ref);
    cr_assert_eq(bs_shim_tree_within(t, lo, hi, got, s.nt, &n), BS_OK);
    cr_assert_eq(n, nref, "box %d: %lld found, brute force %lld", i, (long long)n, (long long)nref);
    qsort(got, (size_t)n, sizeof(int32_t), cmp_i32);
    cr_assert(memcmp(got, ref, (size_t)n * sizeof(int32_t)) == 0, "box %d: different triangles", i);
    total += n;
    if (n >= 2) { /* a short buffer: the full count, and cap valid entries */
      int64_t cap = n / 2, n2 = -1;
      for (int64_t k = 0; k < s.nt; k++) got[k] = -7;
      cr_assert_eq(bs_shim_tree_within(t, lo, hi, got, cap, &n2), BS_OK);
      cr_assert_eq(n2, n);
      cr_assert_eq(got[cap], -7, "wrote past cap");
      for (int64_t k = 0; k < cap; k++)
        cr_assert_not_null(bsearch(&got[k], ref, (size_t)nref, sizeof(int32_t), cmp_i32));
      cr_assert_eq(bs_shim_tree_within(t, lo, hi, NULL, 0, &n2), BS_OK);
      cr_assert_eq(n2, n);
    }
  }
  cr_assert_gt(total, 1000, "the boxes should catch triangles");
  /* a box touching a vertex's coordinate exactly counts (closed boxes) */
  double v[3] = {s.x[0], s.x[1], s.x[2]};
  int64_t n = -1;
  cr_assert_eq(bs_shim_tree_within(t, v, v, got, s.nt, &n), BS_OK);
  cr_assert_geq(n, 5, "every triangle at vertex 0 (5 or 6) touches the point box");
  /* an empty box (lo > hi) and errors */
  double lo[3] = {0, 0, 0}, hi[3] = {1, -1, 1};
  cr_assert_eq(bs_shim_tree_within(t, lo, hi, got, s.nt, &n), BS_OK);
  cr_assert_eq(n, 0);
  cr_assert_eq(bs_shim_tree_within(t, lo, hi, got, -1, &n), BS_EINPUT);
  cr_assert_eq(bs_shim_tree_within(t, lo, hi, NULL, 3, &n), BS_EINPUT);
  cr_assert_eq(bs_shim_tree_within(t, lo, hi, got, 3, NULL), BS_EINPUT);
  cr_assert_eq(bs_shim_tree_within(NULL, lo, hi, got, 3, &n), BS_EINPUT);
  double nan_hi[3] = {1, NAN, 1};
  cr_assert_eq(bs_shim_tree_within(t, lo, nan_hi, got, 3, &n), BS_EINPUT);
  free(got);
  free(ref);
  bs_shim_tree_destroy(&t);
  soup_free(&s);
}

Test(shim_tree, update_moves_the_surface) {
  soup s = make_icosphere(2);
  bs_shim_tree *t = tree_of(&s);
  bs_error err = {0};
  for (int step = 0; step < 3; step++) {
    /* a new configuration: stretch, shear and move every point */
    for (int64_t i = 0; i < s.np; i++) {
      double *p = s.x + 3 * i;
      p[0] = 1.3 * p[0] + 0.2 * p[1] + 0.5;
      p[1] = 0.8 * p[1] - 0.1;
      p[2] = p[2] + 0.05 * sin(7.0 * p[0]);
    }
    cr_assert_eq(bs_shim_tree_update(t, s.x, &err), BS_OK, "%s", err.msg);
    for (int i = 0; i < 100; i++) {
      double q[3] = {urange(-2, 3), urange(-2, 2), urange(-2, 2)}, cp[3], w[3];
      int32_t tri;
      int f;
      cr_assert_eq(bs_shim_tree_closest(t, q, cp, &tri, w, &f), BS_OK);
      check_closest(&s, q, cp, tri, w, f);
    }
  }
  /* a NaN position is refused, names the point, and leaves the tree as it was */
  double keep = s.x[3 * 17 + 1];
  s.x[3 * 17 + 1] = NAN;
  cr_assert_eq(bs_shim_tree_update(t, s.x, &err), BS_ENUMERIC);
  cr_assert(strstr(err.msg, "point 17"), "%s", err.msg);
  s.x[3 * 17 + 1] = keep;
  double q[3] = {3, 0.1, 0.2}, cp[3], w[3];
  int32_t tri;
  int f;
  cr_assert_eq(bs_shim_tree_closest(t, q, cp, &tri, w, &f), BS_OK);
  check_closest(&s, q, cp, tri, w, f);
  cr_assert_eq(bs_shim_tree_update(t, NULL, &err), BS_EINPUT);
  cr_assert_eq(bs_shim_tree_update(NULL, s.x, &err), BS_EINPUT);
  bs_shim_tree_destroy(&t);
  soup_free(&s);
}

Test(shim_tree, concurrent_queries_agree_with_serial) {
  /* The queries are read-only: OpenMP threads on one tree give the serial
   * answers bit for bit. */
  soup s = make_icosphere(3);
  bs_shim_tree *t = tree_of(&s);
  enum { N = 2000 };
  double *q = malloc(3 * N * sizeof(double)), *ser = malloc(4 * N * sizeof(double)),
         *par = malloc(4 * N * sizeof(double));
  for (int i = 0; i < 3 * N; i++) q[i] = urange(-1.5, 1.5);
  for (int i = 0; i < N; i++) { /* the serial reference */
    bs_error e = {0};
    cr_assert_eq(bs_shim_tree_closest(t, q + 3 * i, ser + 4 * i, NULL, NULL, NULL), BS_OK);
    cr_assert_eq(bs_shim_signed_distance(t, q + 3 * i, 1, ser + 4 * i + 3, &e), BS_OK, "%s", e.msg);
  }
  int bad = 0;
#pragma omp parallel for schedule(dynamic, 16) num_threads(4) reduction(+ : bad)
  for (int i = 0; i < N; i++) {
    bs_error e = {0};
    if (bs_shim_tree_closest(t, q + 3 * i, par + 4 * i, NULL, NULL, NULL) != BS_OK) bad++;
    if (bs_shim_signed_distance(t, q + 3 * i, 1, par + 4 * i + 3, &e) != BS_OK) bad++;
  }
  cr_assert_eq(bad, 0);
  cr_assert(memcmp(ser, par, 4 * N * sizeof(double)) == 0, "threads changed an answer");
  free(q);
  free(ser);
  free(par);
  bs_shim_tree_destroy(&t);
  soup_free(&s);
}

Test(shim_tree, create_errors) {
  soup s = make_cube(0, 1);
  bs_shim_tree *t = (bs_shim_tree *)&s; /* must be reset to NULL on failure */
  bs_error err = {0};
  cr_assert_eq(bs_shim_tree_create(NULL, 8, s.t, 12, &t, &err), BS_EINPUT);
  cr_assert_null(t);
  cr_assert(strstr(err.msg, "points"), "%s", err.msg);
  cr_assert_eq(bs_shim_tree_create(s.x, 8, NULL, 12, &t, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "tris"), "%s", err.msg);
  cr_assert_eq(bs_shim_tree_create(s.x, -8, s.t, 12, &t, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "n_points = -8"), "%s", err.msg);
  cr_assert_eq(bs_shim_tree_create(s.x, 8, s.t, -1, &t, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "n_tris = -1"), "%s", err.msg);
  cr_assert_eq(bs_shim_tree_create(s.x, 8, s.t, 0, &t, &err), BS_EINPUT);
  cr_assert_eq(bs_shim_tree_create(s.x, 8, s.t, 12, NULL, &err), BS_EINPUT);
  s.t[3 * 5 + 2] = 8; /* out of range */
  cr_assert_eq(bs_shim_tree_create(s.x, 8, s.t, 12, &t, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "triangle 5") && strstr(err.msg, "point 8"), "%s", err.msg);
  s.t[3 * 5 + 2] = -1;
  cr_assert_eq(bs_shim_tree_create(s.x, 8, s.t, 12, &t, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "triangle 5"), "%s", err.msg);
  s.t[3 * 5 + 2] = 3;
  s.x[3 * 6] = INFINITY;
  cr_assert_eq(bs_shim_tree_create(s.x, 8, s.t, 12, &t, &err), BS_ENUMERIC);
  cr_assert(strstr(err.msg, "point 6"), "%s", err.msg);
  cr_assert_null(t);
  bs_shim_tree_destroy(&t); /* NULL is fine */
  bs_shim_tree_destroy(NULL);
  /* closest on bad arguments */
  s.x[3 * 6] = 0;
  t = tree_of(&s);
  double q[3] = {NAN, 0, 0}, cp[3];
  cr_assert_eq(bs_shim_tree_closest(t, q, cp, NULL, NULL, NULL), BS_EINPUT);
  cr_assert_eq(bs_shim_tree_closest(t, NULL, cp, NULL, NULL, NULL), BS_EINPUT);
  cr_assert_eq(bs_shim_tree_closest(NULL, cp, cp, NULL, NULL, NULL), BS_EINPUT);
  bs_shim_tree_destroy(&t);
  soup_free(&s);
}

/* ------------------------------------------------------------------------ */
/* Signed distance */

Test(shim_sdf, cube_known_values) {
  soup s = make_cube(0, 1);
  bs_shim_tree *t = tree_of(&s);
  bs_error err = {0};
  /* centre (its vertical ray meets a face diagonal: a retry), near a face,
   * outside a face, outside a corner, on a face, an edge, a corner, in the
   * plane of a face but outside, inside near a corner */
  const double q[][3] = {{0.5, 0.5, 0.5}, {0.3, 0.6, 0.1}, {2, 0.5, 0.5}, {2, 2, 2},   {0.3, 0.6, 0},
                         {0.5, 0, 0},     {1, 1, 1},       {0, 0.5, 2}, {0.1, 0.2, 0.05}};
  const double expect[] = {-0.5, -0.1, 1, sqrt(3.0), 0, 0, 0, 1, -0.05};
  const int n = (int)(sizeof expect / sizeof expect[0]);
  double out[16];
  cr_assert_eq(bs_shim_signed_distance(t, &q[0][0], n, out, &err), BS_OK, "%s", err.msg);
  for (int i = 0; i < n; i++)
    cr_assert(fabs(out[i] - expect[i]) <= 1e-15, "point %d: %.17g, expected %.17g", i, out[i], expect[i]);
  /* the orientation of the triangles does not matter */
  for (int64_t i = 0; i < s.nt; i++) {
    int32_t k = s.t[3 * i + 1];
    s.t[3 * i + 1] = s.t[3 * i + 2];
    s.t[3 * i + 2] = k;
  }
  bs_shim_tree *tf = tree_of(&s);
  double out2[16];
  cr_assert_eq(bs_shim_signed_distance(tf, &q[0][0], n, out2, &err), BS_OK, "%s", err.msg);
  for (int i = 0; i < n; i++) cr_assert(fabs(out2[i] - out[i]) <= 1e-15, "point %d: %.17g vs %.17g", i, out2[i], out[i]);
  /* n = 0 is fine; errors name the culprit */
  cr_assert_eq(bs_shim_signed_distance(t, NULL, 0, NULL, &err), BS_OK);
  cr_assert_eq(bs_shim_signed_distance(t, &q[0][0], -1, out, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "n = -1"), "%s", err.msg);
  cr_assert_eq(bs_shim_signed_distance(NULL, &q[0][0], 1, out, &err), BS_EINPUT);
  cr_assert_eq(bs_shim_signed_distance(t, &q[0][0], 1, NULL, &err), BS_EINPUT);
  double bad[6] = {0.5, 0.5, 0.5, 0.2, NAN, 0.1};
  cr_assert_eq(bs_shim_signed_distance(t, bad, 2, out, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "point 1"), "%s", err.msg);
  bs_shim_tree_destroy(&t);
  bs_shim_tree_destroy(&tf);
  soup_free(&s);
}

Test(shim_sdf, icosphere_and_two_cubes_against_brute_force) {
  /* The icosphere is convex: inside iff below every face plane (faces are
   * outward: their normals point away from the origin). */
  soup s = make_icosphere(3);
  bs_shim_tree *t = tree_of(&s);
  bs_error err = {0};
  enum { N = 600 };
  double *q = malloc(3 * N * sizeof(double)), *out = malloc(N * sizeof(double));
  for (int i = 0; i < 3 * N; i++) q[i] = urange(-1.5, 1.5);
  cr_assert_eq(bs_shim_signed_distance(t, q, N, out, &err), BS_OK, "%s", err.msg);
  int n_in = 0;
  for (int i = 0; i < N; i++) {
    double d = brute_dist(&s, q + 3 * i, NULL);
    cr_assert(fabs(fabs(out[i]) - d) <= 1e-12, "point %d: |%.17g| vs %.17g", i, out[i], d);
    if (d < 1e-9) continue;
    int inside = 1;
    for (int64_t f = 0; f < s.nt; f++) {
      const double *a = s.x + 3 * s.t[3 * f], *b = s.x + 3 * s.t[3 * f + 1], *c = s.x + 3 * s.t[3 * f + 2];
      double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
      double nrm[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
      double r[3] = {q[3 * i] - a[0], q[3 * i + 1] - a[1], q[3 * i + 2] - a[2]};
      cr_assert_gt(bs_dot3(nrm, a), 0.0, "face %lld is not outward", (long long)f);
      if (bs_dot3(nrm, r) > 0) inside = 0;
    }
    n_in += inside;
    cr_assert_eq(out[i] < 0, inside, "point %d: %.17g but inside = %d", i, out[i], inside);
  }
  cr_assert(n_in > 50 && n_in < N - 50, "%d points inside", n_in);
  /* vertices of the icosphere are on the surface */
  cr_assert_eq(bs_shim_signed_distance(t, s.x, 10, out, &err), BS_OK, "%s", err.msg);
  for (int i = 0; i < 10; i++) cr_assert_eq(out[i], 0.0);
  bs_shim_tree_destroy(&t);
  soup_free(&s);

  /* Two disjoint cubes in one surface: inside either is inside, between
   * them is outside (rays cross both). */
  soup a = make_cube(0, 1), b = make_cube(0, 1);
  soup two = {16, 24, malloc(48 * sizeof(double)), malloc(72 * sizeof(int32_t))};
  memcpy(two.x, a.x, 24 * sizeof(double));
  for (int i = 0; i < 8; i++) {
    two.x[24 + 3 * i] = b.x[3 * i] + 3.0;
    two.x[24 + 3 * i + 1] = b.x[3 * i + 1];
    two.x[24 + 3 * i + 2] = b.x[3 * i + 2];
  }
  memcpy(two.t, a.t, 36 * sizeof(int32_t));
  for (int i = 0; i < 36; i++) two.t[36 + i] = b.t[i] + 8;
  t = tree_of(&two);
  const double p[][3] = {{0.5, 0.5, 0.5}, {3.5, 0.5, 0.5}, {2.0, 0.5, 0.5}, {1.5, 0.25, 0.75}, {3.25, 0.25, 0.9}};
  const double e[] = {-0.5, -0.5, 1.0, 0.5, -0.1};
  double o[5];
  cr_assert_eq(bs_shim_signed_distance(t, &p[0][0], 5, o, &err), BS_OK, "%s", err.msg);
  for (int i = 0; i < 5; i++) cr_assert(fabs(o[i] - e[i]) <= 1e-15, "point %d: %.17g, expected %g", i, o[i], e[i]);
  bs_shim_tree_destroy(&t);
  soup_free(&a);
  soup_free(&b);
  soup_free(&two);
  free(q);
  free(out);
}

/* ------------------------------------------------------------------------ */
/* Self-intersection */

static int64_t self_pairs(const double *x, int64_t np, const int32_t *t, int64_t nt, int32_t **pairs) {
  bs_error err = {0};
  int64_t n = -1;
  int32_t *p = NULL;
  cr_assert_eq(bs_shim_self_intersections(x, np, t, nt, &p, &n, &err), BS_OK, "%s", err.msg);
  cr_assert_geq(n, 0);
  cr_assert((n == 0) == (p == NULL));
  if (pairs) *pairs = p;
  else bs_shim_free(p);
  return n;
}

Test(shim_self, cube_and_pushed_vertex) {
  soup s = make_cube(0, 1);
  cr_assert_eq(self_pairs(s.x, s.np, s.t, s.nt, NULL), 0, "a closed cube surface does not self-intersect");
  /* push corner 4 (0,0,1) down through the bottom face z = 0 */
  s.x[3 * 4 + 0] = 0.3, s.x[3 * 4 + 1] = 0.4, s.x[3 * 4 + 2] = -0.5;
  int32_t *p = NULL;
  int64_t n = self_pairs(s.x, s.np, s.t, s.nt, &p);
  cr_assert_gt(n, 0);
  int through_bottom = 0;
  for (int64_t k = 0; k < n; k++) {
    cr_assert_lt(p[2 * k], p[2 * k + 1], "pairs are (i < j)");
    if (k > 0) cr_assert(p[2 * k - 2] < p[2 * k] || (p[2 * k - 2] == p[2 * k] && p[2 * k - 1] < p[2 * k + 1]));
    /* one triangle of each pair uses the pushed corner */
    const int32_t *ti = s.t + 3 * p[2 * k], *tj = s.t + 3 * p[2 * k + 1];
    int uses = 0;
    for (int c = 0; c < 3; c++) uses += (ti[c] == 4) + (tj[c] == 4);
    cr_assert_eq(uses, 1, "pair (%d, %d)", p[2 * k], p[2 * k + 1]);
    if (p[2 * k] < 2) through_bottom = 1; /* triangles 0, 1 are the bottom face */
  }
  cr_assert(through_bottom, "the corner went through the bottom face");
  bs_shim_free(p);
  soup_free(&s);
}

Test(shim_self, pairs_of_triangles) {
  int32_t *p = NULL;
  /* two triangles crossing (no shared vertex): exactly one pair */
  double cross[] = {0, 0, 0, 2, 0, 0, 0, 2, 0, 0.5, 0.5, -1, 0.5, 0.5, 1, 3, 3, 0};
  int32_t t2[] = {0, 1, 2, 3, 4, 5};
  cr_assert_eq(self_pairs(cross, 6, t2, 2, &p), 1);
  cr_assert(p[0] == 0 && p[1] == 1);
  bs_shim_free(p);
  /* the same geometry through separate points that coincide: touching
   * counts (a vertex of one lying on the other, no shared index) */
  double touch[] = {0, 0, 0, 2, 0, 0, 0, 2, 0, 0.5, 0.5, 0, 0.5, 0.5, 1, 1, 1, 1};
  cr_assert_eq(self_pairs(touch, 6, t2, 2, NULL), 1);
  /* apart */
  double apart[] = {0, 0, 0, 2, 0, 0, 0, 2, 0, 0.5, 0.5, 1e-12, 0.5, 0.5, 1, 1, 1, 1};
  cr_assert_eq(self_pairs(apart, 6, t2, 2, NULL), 0);

  /* sharing an edge (points 0 and 1), bent: adjacency, no pair */
  double edge[] = {0, 0, 0, 1, 0, 0, 0.5, 1, 0, 0.5, -1, 0.3};
  int32_t te[] = {0, 1, 2, 1, 0, 3};
  cr_assert_eq(self_pairs(edge, 4, te, 2, NULL), 0);
  /* sharing an edge, flat and on opposite sides: no pair */
  edge[11] = 0;
  cr_assert_eq(self_pairs(edge, 4, te, 2, NULL), 0);
  /* sharing an edge, flat and folded onto the same side: one pair */
  edge[10] = 0.5;
  cr_assert_eq(self_pairs(edge, 4, te, 2, NULL), 1);

  /* sharing one vertex (point 0), touching only there: no pair */
  double vtx[] = {0, 0, 0, 1, 0, 0, 0, 1, 0, -1, 0, 0.5, 0, -1, 0.5};
  int32_t tv[] = {0, 1, 2, 0, 3, 4};
  cr_assert_eq(self_pairs(vtx, 5, tv, 2, NULL), 0);
  /* sharing one vertex and crossing elsewhere: one pair */
  double vx2[] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0.4, 0.4, -0.5, 0.4, 0.4, 0.5};
  cr_assert_eq(self_pairs(vx2, 5, tv, 2, NULL), 1);

  /* a degenerate triangle is reported as (i, i); a duplicate triangle as a pair */
  double dg[] = {0, 0, 0, 1, 0, 0, 2, 0, 0, 0, 1, 0};
  int32_t td[] = {0, 1, 3, 0, 1, 2, 3, 1, 0};
  cr_assert_eq(self_pairs(dg, 4, td, 3, &p), 2);
  cr_assert(p[0] == 0 && p[1] == 2, "duplicate (0, 2)");
  cr_assert(p[2] == 1 && p[3] == 1, "degenerate (1, 1)");
  bs_shim_free(p);
  int32_t trep[] = {0, 0, 3};
  cr_assert_eq(self_pairs(dg, 4, trep, 1, &p), 1);
  cr_assert(p[0] == 0 && p[1] == 0);
  bs_shim_free(p);
  /* no triangles */
  cr_assert_eq(self_pairs(NULL, 0, NULL, 0, NULL), 0);
}

Test(shim_self, random_soup_matches_pairwise_tests) {
  /* The box culling loses nothing: on a soup of random small triangles
   * (no shared points), the pairs found equal those of every pair tested
   * alone. */
  enum { NT = 250 };
  double *x = malloc(9 * NT * sizeof(double));
  int32_t *t = malloc(3 * NT * sizeof(int32_t));
  for (int i = 0; i < NT; i++) {
    double c[3] = {urand(), urand(), urand()};
    for (int k = 0; k < 3; k++)
      for (int d = 0; d < 3; d++) x[9 * i + 3 * k + d] = c[d] + urange(-0.08, 0.08);
    for (int k = 0; k < 3; k++) t[3 * i + k] = 3 * i + k;
  }
  int32_t *p = NULL;
  int64_t n = self_pairs(x, 3 * NT, t, NT, &p);
  cr_assert_gt(n, 10, "the soup should have crossings");
  int64_t k = 0;
  int32_t t01[6] = {0, 1, 2, 3, 4, 5};
  for (int i = 0; i < NT; i++)
    for (int j = i + 1; j < NT; j++) {
      double xy[18];
      memcpy(xy, x + 9 * i, 9 * sizeof(double));
      memcpy(xy + 9, x + 9 * j, 9 * sizeof(double));
      if (self_pairs(xy, 6, t01, 2, NULL)) {
        cr_assert(k < n && p[2 * k] == i && p[2 * k + 1] == j, "pair (%d, %d) missing", i, j);
        k++;
      }
    }
  cr_assert_eq(k, n);
  /* the count: exact without a cap, stopped at the cap with it */
  bs_error err = {0};
  int64_t cnt = -1;
  int trunc = -1;
  cr_assert_eq(bs_shim_count_self_intersections(x, 3 * NT, t, NT, 0, &cnt, &trunc, &err), BS_OK, "%s", err.msg);
  cr_assert(cnt == n && trunc == 0, "count %lld (truncated %d), pairs %lld", (long long)cnt, trunc, (long long)n);
  cr_assert_eq(bs_shim_count_self_intersections(x, 3 * NT, t, NT, n, &cnt, &trunc, &err), BS_OK, "%s", err.msg);
  cr_assert(cnt == n && trunc == 1, "cap = n: count %lld truncated %d", (long long)cnt, trunc);
  cr_assert_eq(bs_shim_count_self_intersections(x, 3 * NT, t, NT, 3, &cnt, &trunc, &err), BS_OK, "%s", err.msg);
  cr_assert(cnt == 3 && trunc == 1, "cap = 3: count %lld truncated %d", (long long)cnt, trunc);
  cr_assert_eq(bs_shim_count_self_intersections(x, 3 * NT, t, NT, n + 1, &cnt, &trunc, &err), BS_OK, "%s", err.msg);
  cr_assert(cnt == n && trunc == 0, "cap above the count: %lld truncated %d", (long long)cnt, trunc);
  cr_assert_eq(bs_shim_count_self_intersections(x, 3 * NT, t, NT, -1, &cnt, &trunc, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "cap"), "%s", err.msg);
  bs_shim_free(p);
  free(x);
  free(t);
}

/* Box-overlap candidates by a sweep along x (the test's own search), each
 * decided by the shim on the pair alone: the reference for large soups. */
typedef struct {
  double lo[3], hi[3];
  int32_t id;
} sweep_box;

static int sweep_cmp(const void *a, const void *b) {
  const sweep_box *p = a, *q = b;
  return p->lo[0] < q->lo[0] ? -1 : p->lo[0] > q->lo[0] ? 1 : (p->id > q->id) - (p->id < q->id);
}

static int64_t sweep_pairs(const double *x, const int32_t *t, int nt) {
  sweep_box *b = malloc((size_t)nt * sizeof *b);
  for (int i = 0; i < nt; i++) {
    b[i].id = i;
    for (int d = 0; d < 3; d++) {
      b[i].lo[d] = INFINITY, b[i].hi[d] = -INFINITY;
      for (int k = 0; k < 3; k++) {
        b[i].lo[d] = fmin(b[i].lo[d], x[3 * t[3 * i + k] + d]);
        b[i].hi[d] = fmax(b[i].hi[d], x[3 * t[3 * i + k] + d]);
      }
    }
  }
  qsort(b, (size_t)nt, sizeof *b, sweep_cmp);
  int64_t n = 0;
  int32_t t01[6] = {0, 1, 2, 3, 4, 5};
  for (int i = 0; i < nt; i++)
    for (int j = i + 1; j < nt && b[j].lo[0] <= b[i].hi[0]; j++) {
      if (b[j].lo[1] > b[i].hi[1] || b[j].hi[1] < b[i].lo[1] || b[j].lo[2] > b[i].hi[2] || b[j].hi[2] < b[i].lo[2])
        continue;
      double xy[18];
      for (int k = 0; k < 3; k++) {
        memcpy(xy + 3 * k, x + 3 * t[3 * b[i].id + k], 3 * sizeof(double));
        memcpy(xy + 9 + 3 * k, x + 3 * t[3 * b[j].id + k], 3 * sizeof(double));
      }
      n += self_pairs(xy, 6, t01, 2, NULL);
    }
  free(b);
  return n;
}

Test(shim_self, large_soup_in_slabs_matches_a_sweep_on_any_thread_count) {
  /* 70,000 small triangles and 40 long ones across the whole soup in x (each
   * in every slab of the search): the pairs are the sweep's, each once, and
   * the same on 1 and 2 threads; the cap stops the count at the cap. */
  enum { NS = 70000, NL = 40, NT = NS + NL };
  double *x = malloc(9 * (size_t)NT * sizeof(double));
  int32_t *t = malloc(3 * (size_t)NT * sizeof(int32_t));
  for (int i = 0; i < NT; i++) {
    double c[3] = {urand(), urand(), urand()};
    for (int k = 0; k < 3; k++)
      for (int d = 0; d < 3; d++) x[9 * i + 3 * k + d] = c[d] + urange(-0.01, 0.01);
    if (i >= NS) x[9 * i] = -0.1, x[9 * i + 3] = 1.1; /* two vertices at the ends in x */
    for (int k = 0; k < 3; k++) t[3 * i + k] = 3 * i + k;
  }
  const int64_t want = sweep_pairs(x, t, NT);
  cr_assert_gt(want, 1000, "the soup should have crossings (%lld)", (long long)want);
  int32_t *p[2] = {NULL, NULL};
  int64_t n[2];
  for (int th = 1; th <= 2; th++) {
    omp_set_num_threads(th);
    n[th - 1] = self_pairs(x, 3 * NT, t, NT, &p[th - 1]);
    cr_assert_eq(n[th - 1], want, "%d threads: %lld pairs, the sweep %lld", th, (long long)n[th - 1],
                 (long long)want);
    for (int64_t k = 1; k < n[th - 1]; k++) {
      const int32_t *a = p[th - 1] + 2 * (k - 1), *b = a + 2;
      cr_assert(a[0] < b[0] || (a[0] == b[0] && a[1] < b[1]), "pair %lld not after the one before", (long long)k);
    }
  }
  cr_assert_eq(memcmp(p[0], p[1], 2 * (size_t)want * sizeof(int32_t)), 0, "1 and 2 threads differ");
  bs_error err = {0};
  int64_t cnt = -1;
  int trunc = -1;
  cr_assert_eq(bs_shim_count_self_intersections(x, 3 * NT, t, NT, 5, &cnt, &trunc, &err), BS_OK, "%s", err.msg);
  cr_assert(cnt == 5 && trunc == 1, "cap = 5: count %lld truncated %d", (long long)cnt, trunc);
  bs_shim_free(p[0]);
  bs_shim_free(p[1]);
  free(x);
  free(t);
}

Test(shim_self, errors_name_the_culprit) {
  soup s = make_cube(0, 1);
  bs_error err = {0};
  int32_t *p = (int32_t *)&s;
  int64_t n = -1;
  cr_assert_eq(bs_shim_self_intersections(NULL, 8, s.t, 12, &p, &n, &err), BS_EINPUT);
  cr_assert(p == NULL && n == 0);
  cr_assert(strstr(err.msg, "points is NULL"), "%s", err.msg);
  cr_assert_eq(bs_shim_self_intersections(s.x, 8, NULL, 12, &p, &n, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "tris is NULL"), "%s", err.msg);
  cr_assert_eq(bs_shim_self_intersections(s.x, -1, s.t, 12, &p, &n, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "n_points = -1"), "%s", err.msg);
  cr_assert_eq(bs_shim_self_intersections(s.x, 8, s.t, -12, &p, &n, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "n_tris = -12"), "%s", err.msg);
  cr_assert_eq(bs_shim_self_intersections(s.x, 8, s.t, 12, NULL, &n, &err), BS_EINPUT);
  cr_assert_eq(bs_shim_self_intersections(s.x, 8, s.t, 12, &p, NULL, &err), BS_EINPUT);
  s.t[3 * 9 + 1] = 42;
  cr_assert_eq(bs_shim_self_intersections(s.x, 8, s.t, 12, &p, &n, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "triangle 9") && strstr(err.msg, "point 42"), "%s", err.msg);
  cr_assert(p == NULL && n == 0);
  s.t[3 * 9 + 1] = 1;
  s.x[3 * 2 + 2] = NAN;
  cr_assert_eq(bs_shim_self_intersections(s.x, 8, s.t, 12, &p, &n, &err), BS_ENUMERIC);
  cr_assert(strstr(err.msg, "point 2"), "%s", err.msg);
  soup_free(&s);
  bs_shim_free(NULL);
}
