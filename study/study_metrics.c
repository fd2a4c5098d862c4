/* study_metrics.c — the study's metrics as pure functions on arrays: order
 * fits, the Pareto front, the cheapest point within a threshold, energy drift
 * (formulas: bs_study.h). Nothing reads files or prints. */
#include <math.h>
#include <stdlib.h>

#include "bs_study.h"

double bs_study_fit_order(int n, const double *h, const double *err, double *logc, int *used) {
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  int m = 0;
  for (int i = 0; i < n; i++) {
    if (!(h[i] > 0) || !(err[i] > 0) || !isfinite(err[i])) continue;
    double lx = log(h[i]), ly = log(err[i]);
    sx += lx;
    sy += ly;
    sxx += lx * lx;
    sxy += lx * ly;
    m++;
  }
  *used = m;
  double d = m * sxx - sx * sx;
  if (m < 2 || d <= 0) {
    *logc = NAN;
    return NAN;
  }
  double p = (m * sxy - sx * sy) / d;
  *logc = (sy - p * sx) / m;
  return p;
}

/* The fixed point p = fit(h, d / (1 - rho^p)), from the plain fit of d. */
double bs_study_successive_fit(int n, const double *h, const double *d, const double *rho, int *used) {
  double logc, p = bs_study_fit_order(n, h, d, &logc, used);
  double *y = malloc(sizeof(double) * (size_t)(n > 0 ? n : 1));
  if (!y) return NAN;
  for (int it = 0; it < 100 && isfinite(p) && p > 0; it++) {
    for (int j = 0; j < n; j++) y[j] = d[j] / (1 - pow(rho[j], p));
    double q = bs_study_fit_order(n, h, y, &logc, used);
    if (!isfinite(q) || !(q > 0)) break;
    int done = fabs(q - p) < 1e-10;
    p = q;
    if (done) break;
  }
  free(y);
  return p;
}

static int usable(const double *cost, const double *error, const int *ok, int i) {
  return ok[i] && isfinite(error[i]) && isfinite(cost[i]);
}

void bs_study_pareto(int n, const double *cost, const double *error, const int *ok, int *front) {
  for (int i = 0; i < n; i++) {
    front[i] = 0;
    if (!usable(cost, error, ok, i)) continue;
    int dominated = 0;
    for (int j = 0; j < n && !dominated; j++) {
      if (j == i || !usable(cost, error, ok, j)) continue;
      if (cost[j] <= cost[i] && error[j] <= error[i] && (cost[j] < cost[i] || error[j] < error[i])) dominated = 1;
    }
    front[i] = !dominated;
  }
}

int bs_study_cheapest_within(int n, const double *cost, const double *error, const int *ok, double threshold) {
  int best = -1;
  for (int i = 0; i < n; i++) {
    if (!ok[i] || !(error[i] <= threshold) || !isfinite(cost[i])) continue;
    if (best < 0 || cost[i] < cost[best]) best = i;
  }
  return best;
}

double bs_study_energy_drift(const bs_frames_table *t) {
  if (t->n <= 0) return NAN;
  double scale = fabs(t->total[0]), d = 0;
  for (int i = 0; i < t->n; i++) {
    if (t->kinetic[i] > scale) scale = t->kinetic[i];
    double q = fabs(t->total[i] - t->total[0]);
    if (q > d || !isfinite(q)) d = q;
  }
  return d / (scale > 0 ? scale : 1.0);
}
