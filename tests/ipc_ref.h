/* ipc_ref.h — reference distances for the IPC tests (test_ipc_distance.c,
 * test_ccd.c): Ericson's closest-point routines (Real-Time Collision
 * Detection, 5.1.5 and 5.1.9), written independently of collision/ipc_distance.c. */
#ifndef BS_TEST_IPC_REF_H
#define BS_TEST_IPC_REF_H

#include <math.h>

static double dot3(const double *a, const double *b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

/* Ericson 5.1.5: squared distance from p to triangle abc. */
static double ericson_pt(const double *p, const double *a, const double *b, const double *c) {
  double ab[3], ac[3], ap[3], bp[3], cp[3], q[3];
  for (int k = 0; k < 3; k++)
    ab[k] = b[k] - a[k], ac[k] = c[k] - a[k], ap[k] = p[k] - a[k], bp[k] = p[k] - b[k], cp[k] = p[k] - c[k];
  const double d1 = dot3(ab, ap), d2 = dot3(ac, ap), d3 = dot3(ab, bp), d4 = dot3(ac, bp), d5 = dot3(ab, cp),
               d6 = dot3(ac, cp);
  double v, w;
  const double vc = d1 * d4 - d3 * d2, vb = d5 * d2 - d1 * d6, va = d3 * d6 - d5 * d4;
  if (d1 <= 0 && d2 <= 0) v = 0, w = 0;
  else if (d3 >= 0 && d4 <= d3) v = 1, w = 0;
  else if (vc <= 0 && d1 >= 0 && d3 <= 0) v = d1 / (d1 - d3), w = 0;
  else if (d6 >= 0 && d5 <= d6) v = 0, w = 1;
  else if (vb <= 0 && d2 >= 0 && d6 <= 0) v = 0, w = d2 / (d2 - d6);
  else if (va <= 0 && d4 - d3 >= 0 && d5 - d6 >= 0) w = (d4 - d3) / ((d4 - d3) + (d5 - d6)), v = 1 - w;
  else v = vb / (va + vb + vc), w = vc / (va + vb + vc);
  for (int k = 0; k < 3; k++) q[k] = p[k] - a[k] - v * ab[k] - w * ac[k];
  return dot3(q, q);
}

/* Squared distance from p to segment ab. */
static double seg_d2(const double *p, const double *a, const double *b) {
  double e[3], r[3];
  for (int k = 0; k < 3; k++) e[k] = b[k] - a[k], r[k] = p[k] - a[k];
  const double ee = dot3(e, e);
  const double t = ee > 0 ? fmin(fmax(dot3(r, e) / ee, 0), 1) : 0;
  for (int k = 0; k < 3; k++) r[k] -= t * e[k];
  return dot3(r, r);
}

/* Ericson 5.1.9 (segments p1q1, p2q2), with the four endpoint-segment
 * distances as a guard for near-parallel segments. */
static double ericson_ee(const double *p1, const double *q1, const double *p2, const double *q2) {
  double d1[3], d2[3], r[3], c1[3];
  for (int k = 0; k < 3; k++) d1[k] = q1[k] - p1[k], d2[k] = q2[k] - p2[k], r[k] = p1[k] - p2[k];
  const double a = dot3(d1, d1), e = dot3(d2, d2), f = dot3(d2, r), c = dot3(d1, r), b = dot3(d1, d2);
  const double den = a * e - b * b;
  double s = den > 0 ? fmin(fmax((b * f - c * e) / den, 0), 1) : 0, t = (b * s + f) / e;
  if (t < 0) t = 0, s = fmin(fmax(-c / a, 0), 1);
  else if (t > 1) t = 1, s = fmin(fmax((b - c) / a, 0), 1);
  for (int k = 0; k < 3; k++) c1[k] = p1[k] + s * d1[k] - p2[k] - t * d2[k];
  const double m = fmin(fmin(seg_d2(p1, p2, q2), seg_d2(q1, p2, q2)), fmin(seg_d2(p2, p1, q1), seg_d2(q2, p1, q1)));
  return fmin(dot3(c1, c1), m);
}

#endif
