/* ipc_barrier.c — the IPC log barrier, the contact energy of a
 * point-triangle or edge-edge pair with its gradient and (projected) Hessian
 * by the chain rule, and the barrier stiffness heuristics (bs_ipc.h). */
#include <math.h>
#include <string.h>

#include "bs_ipc.h"
#include "bs_svd.h"

int bs_ipc_barrier(double d, double dhat2, double out[3]) {
  out[0] = out[1] = out[2] = 0;
  if (!isfinite(d) || !isfinite(dhat2) || !(dhat2 > 0)) return BS_EINPUT;
  if (!(d > 0)) return BS_IPC_ECONTACT;
  if (d >= dhat2) return BS_OK;
  /* L = ln(d / dhat2); log1p near dhat2, where d / dhat2 - 1 is exact */
  const double L = d > 0.5 * dhat2 ? log1p((d - dhat2) / dhat2) : log(d / dhat2), r = dhat2 / d, dd = d - dhat2;
  out[0] = -dd * dd * L;
  out[1] = -dd * (2 * L - r + 1);
  out[2] = (r + 2) * r - 2 * L - 3;
  return BS_OK;
}

static int finite_points(int n, const double *const x[]) {
  for (int k = 0; k < n; k++)
    for (int c = 0; c < 3; c++)
      if (!isfinite(x[k][c])) return 0;
  return 1;
}

static void zero_out(double *E, double *g, double *H) {
  if (E) *E = 0;
  if (g) memset(g, 0, 12 * sizeof(double));
  if (H) memset(H, 0, 144 * sizeof(double));
}

/* Arguments shared by both energies; BS_OK or BS_EINPUT with a message. */
static int check_args(const double *const x[], double dhat, double kappa, const char *what, bs_error *err) {
  if (!finite_points(4, x)) return bs_error_set(err, BS_EINPUT, "%s: a coordinate is not finite", what);
  if (!isfinite(dhat) || !(dhat > 0)) return bs_error_set(err, BS_EINPUT, "%s: dhat %g is not > 0", what, dhat);
  if (!isfinite(kappa) || !(kappa >= 0))
    return bs_error_set(err, BS_EINPUT, "%s: kappa %g is not >= 0", what, kappa);
  return BS_OK;
}

/* E, g, H of kappa m b(D) from D's derivatives (gD, HD) and the mollifier's
 * (m, gm, Hm; gm == NULL for m = 1 constant); the caller has checked that
 * 0 < D < dhat2. */
static void chain(double kappa, const double bb[3], const double *gD, const double *HD, double m, const double *gm,
                  const double *Hm, double *E, double *g, double *H) {
  if (E) *E = kappa * m * bb[0];
  if (g)
    for (int i = 0; i < 12; i++) g[i] = kappa * (m * bb[1] * gD[i] + (gm ? bb[0] * gm[i] : 0));
  if (!H) return;
  for (int i = 0; i < 12; i++)
    for (int j = i; j < 12; j++) {
      double h = m * (bb[2] * gD[i] * gD[j] + bb[1] * HD[i * 12 + j]);
      if (gm) h += bb[1] * (gD[i] * gm[j] + gm[i] * gD[j]) + bb[0] * Hm[i * 12 + j];
      H[i * 12 + j] = H[j * 12 + i] = kappa * h;
    }
}

int bs_ipc_pt_energy(const double p[3], const double t0[3], const double t1[3], const double t2[3], double dhat,
                     double kappa, int project, double *E, double g[12], double H[144], bs_error *err) {
  const double *x[4] = {p, t0, t1, t2};
  zero_out(E, g, H);
  int st = check_args(x, dhat, kappa, "point-triangle energy", err);
  if (st) return st;
  const bs_ipc_pt_type type = bs_ipc_pt_classify(p, t0, t1, t2);
  const double D = bs_ipc_pt_d2_typed(type, p, t0, t1, t2, NULL, NULL);
  double bb[3], gD[12], HD[144];
  if ((st = bs_ipc_barrier(D, dhat * dhat, bb)) == BS_IPC_ECONTACT)
    return bs_error_set(err, st, "point-triangle energy: squared distance %g <= 0 (type %d)", D, (int)type);
  if (st || D >= dhat * dhat) return st;
  bs_ipc_pt_d2_typed(type, p, t0, t1, t2, gD, H ? HD : NULL);
  chain(kappa, bb, gD, HD, 1, NULL, NULL, E, g, H);
  if (H && project) bs_sym_psd_project(12, H);
  return BS_OK;
}

int bs_ipc_ee_energy(const double ea0[3], const double ea1[3], const double eb0[3], const double eb1[3],
                     double eps_x, double dhat, double kappa, int project, double *E, double g[12], double H[144],
                     bs_error *err) {
  const double *x[4] = {ea0, ea1, eb0, eb1};
  zero_out(E, g, H);
  int st = check_args(x, dhat, kappa, "edge-edge energy", err);
  if (st) return st;
  if (!isfinite(eps_x) || !(eps_x > 0))
    return bs_error_set(err, BS_EINPUT, "edge-edge energy: mollifier eps_x %g is not > 0", eps_x);
  const bs_ipc_ee_type type = bs_ipc_ee_classify(ea0, ea1, eb0, eb1);
  const double D = bs_ipc_ee_d2_typed(type, ea0, ea1, eb0, eb1, NULL, NULL);
  double bb[3], gD[12], HD[144], gm[12], Hm[144];
  if ((st = bs_ipc_barrier(D, dhat * dhat, bb)) == BS_IPC_ECONTACT)
    return bs_error_set(err, st, "edge-edge energy: squared distance %g <= 0 (type %d)", D, (int)type);
  if (st || D >= dhat * dhat) return st;
  bs_ipc_ee_d2_typed(type, ea0, ea1, eb0, eb1, gD, H ? HD : NULL);
  const double m = bs_ipc_mollifier(ea0, ea1, eb0, eb1, eps_x, gm, H ? Hm : NULL);
  chain(kappa, bb, gD, HD, m, m < 1 ? gm : NULL, Hm, E, g, H);
  if (H && project) bs_sym_psd_project(12, H);
  return BS_OK;
}

int bs_ipc_kappa_bounds(double avg_mass, double dhat, double bbox_diag, double scale, double *kappa_min,
                        double *kappa_max, bs_error *err) {
  const double v[4] = {avg_mass, dhat, bbox_diag, scale};
  static const char *names[4] = {"average mass", "dhat", "bounding-box diagonal", "scale"};
  for (int i = 0; i < 4; i++)
    if (!isfinite(v[i]) || !(v[i] > 0))
      return bs_error_set(err, BS_EINPUT, "kappa bounds: %s %g is not finite > 0", names[i], v[i]);
  const double dhat2 = dhat * dhat;
  double d0 = 1e-8 * bbox_diag, bb[3];
  d0 *= d0;
  if (d0 >= dhat2) d0 = 0.5 * dhat2;
  bs_ipc_barrier(d0, dhat2, bb);
  const double kmin = scale * avg_mass / (4 * d0 * bb[2]);
  if (!isfinite(kmin) || !(kmin > 0))
    return bs_error_set(err, BS_EINPUT, "kappa bounds: kappa_min %g is not finite > 0", kmin);
  *kappa_min = kmin;
  *kappa_max = 100 * kmin;
  return BS_OK;
}

double bs_ipc_kappa_initial(size_t n, const double *grad_energy, const double *grad_barrier, double kappa_min,
                            double kappa_max) {
  double gb2 = 0, gbe = 0;
  for (size_t i = 0; i < n; i++) gb2 += grad_barrier[i] * grad_barrier[i], gbe += grad_barrier[i] * grad_energy[i];
  const double k = gb2 > 0 ? -gbe / gb2 : 1;
  return k < kappa_min ? kappa_min : k > kappa_max ? kappa_max : k;
}

double bs_ipc_kappa_update(double kappa, double kappa_max, double d2_prev, double d2_min, double d2_eps) {
  if (d2_prev < d2_eps && d2_min < d2_eps && d2_min < d2_prev) return 2 * kappa < kappa_max ? 2 * kappa : kappa_max;
  return kappa;
}

double bs_ipc_kappa_d2_eps(double bbox_diag) { return 1e-18 * bbox_diag * bbox_diag; }
