/* ipc_friction.c — the kernels of IPC's lagged smoothed friction (bs_ipc.h,
 * "Friction"): f0 and its derivatives, a tangent basis, one contact's
 * energy, gradient and Hessian in its relative displacement, and the
 * closest-point weights of point-triangle and edge-edge pairs. */
#include <math.h>

#include "bs_ipc.h"
#include "bs_vec3.h"

void bs_ipc_friction_f(double y, double eps, double *f0, double *f1, double *f1p) {
  if (y < eps) {
    *f0 = -y * y * y / (3 * eps * eps) + y * y / eps + eps / 3;
    *f1 = 2 * y / eps - y * y / (eps * eps);
    *f1p = 2 / eps - 2 * y / (eps * eps);
  } else {
    *f0 = y, *f1 = 1, *f1p = 0;
  }
}

void bs_ipc_tangent_basis(const double n[3], double T[6]) {
  double a[3] = {0, 0, 0}, t1[3], t2[3];
  int m = 0; /* the axis least aligned with n */
  for (int k = 1; k < 3; k++)
    if (fabs(n[k]) < fabs(n[m])) m = k;
  a[m] = 1;
  bs_cross3(n, a, t1);
  const double l = sqrt(bs_dot3(t1, t1));
  for (int k = 0; k < 3; k++) t1[k] /= l;
  bs_cross3(n, t1, t2);
  for (int k = 0; k < 3; k++) T[2 * k] = t1[k], T[2 * k + 1] = t2[k];
}

double bs_ipc_friction_eval(const double T[6], const double dx[3], double mul, double eps, double g[3],
                            double H[9]) {
  double u[2];
  for (int j = 0; j < 2; j++) u[j] = T[j] * dx[0] + T[2 + j] * dx[1] + T[4 + j] * dx[2];
  const double y = hypot(u[0], u[1]);
  double f0, f1, f1p;
  bs_ipc_friction_f(y, eps, &f0, &f1, &f1p);
  if (g) { /* mul f1(y)/y T u; f1/y -> 2/eps at y = 0 */
    const double w = y > 0 ? f1 / y : 2 / eps;
    for (int k = 0; k < 3; k++) g[k] = mul * w * (T[2 * k] * u[0] + T[2 * k + 1] * u[1]);
  }
  if (H) { /* H2 = (f1' - f1/y) u u^T / y^2 + f1/y I: eigenvalues f1' (along u), f1/y */
    double H2[4];
    if (f1p < 0) f1p = 0; /* PSD projection; never with this f0 (bs_ipc.h) */
    if (y > 0) {
      const double a = (f1p - f1 / y) / (y * y), b = f1 / y;
      H2[0] = a * u[0] * u[0] + b, H2[1] = H2[2] = a * u[0] * u[1], H2[3] = a * u[1] * u[1] + b;
    } else {
      H2[0] = H2[3] = 2 / eps, H2[1] = H2[2] = 0;
    }
    for (int i = 0; i < 3; i++)
      for (int k = 0; k < 3; k++) {
        double s = 0;
        for (int a = 0; a < 2; a++)
          for (int b = 0; b < 2; b++) s += T[2 * i + a] * H2[2 * a + b] * T[2 * k + b];
        H[3 * i + k] = mul * s;
      }
  }
  return mul * f0;
}

static double clamp01(double s) { return s > 0 ? (s < 1 ? s : 1) : 0; }

/* The parameter in [0, 1] of the point of segment ab nearest p. */
static double seg_param(const double p[3], const double a[3], const double b[3]) {
  double e[3], r[3];
  bs_sub3(b, a, e);
  bs_sub3(p, a, r);
  const double ee = bs_dot3(e, e);
  return ee > 0 ? clamp01(bs_dot3(r, e) / ee) : 0;
}

void bs_ipc_pt_closest_weights(const double p[3], const double t0[3], const double t1[3], const double t2[3],
                               double w[4]) {
  const double *t[3] = {t0, t1, t2};
  double b[3] = {0, 0, 0}; /* the barycentric coordinates of c on (t0, t1, t2) */
  const bs_ipc_pt_type type = bs_ipc_pt_classify(p, t0, t1, t2);
  if (type <= BS_IPC_P_T2) {
    b[type - BS_IPC_P_T0] = 1;
  } else if (type <= BS_IPC_P_E2) {
    const int i = type - BS_IPC_P_E0, j = (i + 1) % 3;
    const double s = seg_param(p, t[i], t[j]);
    b[i] = 1 - s, b[j] = s;
  } else { /* the projection onto the plane: [e1.e1 e1.e2; e1.e2 e2.e2] (b1, b2) = (e1.r, e2.r) */
    double e1[3], e2[3], r[3];
    bs_sub3(t1, t0, e1);
    bs_sub3(t2, t0, e2);
    bs_sub3(p, t0, r);
    const double a11 = bs_dot3(e1, e1), a12 = bs_dot3(e1, e2), a22 = bs_dot3(e2, e2), r1 = bs_dot3(e1, r),
                 r2 = bs_dot3(e2, r), det = a11 * a22 - a12 * a12;
    b[1] = (a22 * r1 - a12 * r2) / det;
    b[2] = (a11 * r2 - a12 * r1) / det;
    b[0] = 1 - b[1] - b[2];
  }
  w[0] = 1, w[1] = -b[0], w[2] = -b[1], w[3] = -b[2];
}

void bs_ipc_ee_closest_weights(const double ea0[3], const double ea1[3], const double eb0[3], const double eb1[3],
                               double w[4]) {
  double a = 0, b = 0; /* the closest points' parameters on edge a and edge b */
  const bs_ipc_ee_type type = bs_ipc_ee_classify(ea0, ea1, eb0, eb1);
  switch (type) {
    case BS_IPC_EA0_EB0: a = 0, b = 0; break;
    case BS_IPC_EA0_EB1: a = 0, b = 1; break;
    case BS_IPC_EA1_EB0: a = 1, b = 0; break;
    case BS_IPC_EA1_EB1: a = 1, b = 1; break;
    case BS_IPC_EA0_EB: a = 0, b = seg_param(ea0, eb0, eb1); break;
    case BS_IPC_EA1_EB: a = 1, b = seg_param(ea1, eb0, eb1); break;
    case BS_IPC_EA_EB0: a = seg_param(eb0, ea0, ea1), b = 0; break;
    case BS_IPC_EA_EB1: a = seg_param(eb1, ea0, ea1), b = 1; break;
    case BS_IPC_EA_EB: { /* min |r + a ea - b eb|^2, r = ea0 - eb0 */
      double ea[3], eb[3], r[3];
      bs_sub3(ea1, ea0, ea);
      bs_sub3(eb1, eb0, eb);
      bs_sub3(ea0, eb0, r);
      const double aa = bs_dot3(ea, ea), ab = bs_dot3(ea, eb), bb = bs_dot3(eb, eb), ar = bs_dot3(ea, r),
                   br = bs_dot3(eb, r), det = aa * bb - ab * ab;
      a = clamp01((ab * br - bb * ar) / det);
      b = clamp01((aa * br - ab * ar) / det);
      break;
    }
  }
  w[0] = 1 - a, w[1] = a, w[2] = -(1 - b), w[3] = -b;
}
