/* study_gci.c — Richardson extrapolation and the grid convergence index of
 * three levels (Roache; the procedure of Celik et al. 2008, J. Fluids Eng.
 * 130, 078001), as a pure function (formulas: bs_study.h). */
#include <math.h>

#include "bs_study.h"

const char *bs_gci_status_name(bs_gci_status s) {
  switch (s) {
  case BS_GCI_OK: return "monotone";
  case BS_GCI_OSCILLATORY: return "oscillatory";
  case BS_GCI_DIVERGENT: return "divergent";
  case BS_GCI_CONVERGED: return "converged";
  case BS_GCI_NO_ORDER: return "no_order";
  case BS_GCI_BAD_INPUT: return "bad_input";
  }
  return "?";
}

/* ln of e32/e21 as the power law h^p predicts it:
 * ln(r21^p (r32^p - 1) / (r21^p - 1)), increasing in p. */
static double log_ratio(double p, double l21, double l32) {
  return p * l21 + log(expm1(p * l32)) - log(expm1(p * l21));
}

/* The order p > 0 with log_ratio(p) = ln(e32/e21) (Celik's eq. (4) with
 * s = 1), by bisection on (0, 64]; NAN when there is none. */
static double order_root(double r21, double r32, double e21, double e32) {
  const double l21 = log(r21), l32 = log(r32), want = log(e32 / e21);
  double lo = 1e-9, hi = 64;
  if (!(log_ratio(lo, l21, l32) < want) || !(log_ratio(hi, l21, l32) > want)) return NAN;
  for (int it = 0; it < 200 && hi - lo > 1e-14 * hi; it++) {
    double mid = 0.5 * (lo + hi);
    if (log_ratio(mid, l21, l32) < want) lo = mid;
    else hi = mid;
  }
  return 0.5 * (lo + hi);
}

static void gci_of(const double h[3], const double f[3], double p, bs_gci *g) {
  const double r21 = h[1] / h[0], r32 = h[2] / h[1];
  const double a21 = pow(r21, p), a32 = pow(r32, p);
  g->p = p;
  g->extrapolated = (a21 * f[0] - f[1]) / (a21 - 1);
  g->e_a = f[0] != 0 ? fabs((f[0] - f[1]) / f[0]) : NAN;
  g->e_ext = g->extrapolated != 0 ? fabs((g->extrapolated - f[0]) / g->extrapolated) : NAN;
  g->gci_fine = 1.25 * g->e_a / (a21 - 1);
  double e32 = f[1] != 0 ? fabs((f[1] - f[2]) / f[1]) : NAN;
  g->gci_coarse = 1.25 * e32 / (a32 - 1);
  g->asymptotic = g->gci_coarse / (a21 * g->gci_fine);
}

bs_gci_status bs_study_gci(const double h[3], const double f[3], bs_gci *g) {
  *g = (bs_gci){.p = NAN, .extrapolated = NAN, .e_a = NAN, .e_ext = NAN, .gci_fine = NAN, .gci_coarse = NAN,
                .asymptotic = NAN};
  for (int i = 0; i < 3; i++)
    if (!isfinite(h[i]) || !(h[i] > 0) || !isfinite(f[i])) return g->status = BS_GCI_BAD_INPUT;
  if (!(h[0] < h[1] && h[1] < h[2])) return g->status = BS_GCI_BAD_INPUT;
  const double e21 = f[1] - f[0], e32 = f[2] - f[1];
  const double scale = fabs(f[0]) + fabs(f[1]) + fabs(f[2]);
  if (fabs(e21) <= 1e-12 * scale && fabs(e32) <= 1e-12 * scale) {
    g->p = NAN;
    g->extrapolated = f[0];
    g->e_a = g->e_ext = g->gci_fine = g->gci_coarse = 0;
    return g->status = BS_GCI_CONVERGED;
  }
  if (e21 == 0 || e32 == 0) return g->status = BS_GCI_NO_ORDER;
  if (e32 / e21 < 0) return g->status = BS_GCI_OSCILLATORY;
  if (fabs(e21) >= fabs(e32)) return g->status = BS_GCI_DIVERGENT;
  double p = order_root(h[1] / h[0], h[2] / h[1], e21, e32);
  if (!isfinite(p) || !(p > 0)) return g->status = BS_GCI_NO_ORDER;
  gci_of(h, f, p, g);
  return g->status = BS_GCI_OK;
}
