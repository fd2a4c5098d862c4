/* study_orders.c — observed orders of convergence of a study: the runs of a
 * convergence group (every other knob at its finest value), fitted against
 * the reference or level against level (bs_study.h). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "study_internal.h"

int bs__study_group(const bs_study *S, int k, const char *method, int *out) {
  int n = 0;
  for (int i = 0; i < S->n_runs; i++) {
    const bs_study_run *r = &S->runs[i];
    int ok = !strcmp(r->method, method);
    for (int q = 0; ok && q < S->n_knobs; q++)
      if (q != k && S->knobs[q].kind != BS_KNOB_METHOD && r->idx[q] != S->knobs[q].finest) ok = 0;
    if (ok) out[n++] = i;
  }
  return n;
}

double bs_study_knob_h(const bs_study *S, const bs_study_run *r, int k) {
  const bs_study_knob *v = &S->knobs[k];
  if (v->kind == BS_KNOB_REFINE) return pow(2.0, -v->num[r->idx[k]]);
  return 1.0 / (r->fps * r->spf);
}

int bs_study_methods(const bs_study *S, const char **names, int max) {
  int n = 0;
  for (int i = 0; i < S->n_runs && n < max; i++) {
    int seen = 0;
    for (int j = 0; j < n; j++) seen |= !strcmp(names[j], S->runs[i].method);
    if (!seen) names[n++] = S->runs[i].method;
  }
  return n;
}

/* A run enters the fit when it finished and is not at the reference's level
 * of knob k (there the error measures the solver or method difference, not
 * the discretization). */
int bs__study_fit_point(const bs_study *S, const bs_study_run *r, int k) {
  if (r->is_ref || r->exit_code != 0) return 0;
  return S->ref_dir[0] || r->idx[k] != S->knobs[k].finest;
}

bs_study_order bs__study_order_fit(const bs_study *S, int k, const char *method) {
  bs_study_order o = {NAN, NAN, 0};
  int *grp = malloc(sizeof(int) * ((size_t)S->n_runs + 1));
  double *x = malloc(sizeof(double) * ((size_t)S->n_runs + 1)), *y = malloc(sizeof(double) * ((size_t)S->n_runs + 1));
  if (grp && x && y) {
    int ng = bs__study_group(S, k, method, grp), m = 0;
    for (int i = 0; i < ng; i++) {
      const bs_study_run *r = &S->runs[grp[i]];
      if (!bs__study_fit_point(S, r, k)) continue;
      x[m] = bs_study_knob_h(S, r, k);
      y[m] = r->pos_max;
      m++;
    }
    o.p = bs_study_fit_order(m, x, y, &o.logc, &o.used);
  }
  free(grp);
  free(x);
  free(y);
  return o;
}

/* The group of knob k sorted coarse to fine (largest h first, stable). */
static int sorted_group(const bs_study *S, int k, const char *method, int *grp) {
  int ng = bs__study_group(S, k, method, grp);
  for (int i = 1; i < ng; i++)
    for (int j = i; j > 0 && bs_study_knob_h(S, &S->runs[grp[j]], k) > bs_study_knob_h(S, &S->runs[grp[j - 1]], k);
         j--) {
      int t = grp[j];
      grp[j] = grp[j - 1];
      grp[j - 1] = t;
    }
  return ng;
}

/* Each finished run of the group against the next finer one: h, the
 * position error d and the ratio rho of the pairs; returns how many. */
static int level_pairs(const bs_study *S, int k, const int *grp, int ng, double *h, double *d, double *rho,
                       FILE *pts) {
  int m = 0;
  for (int i = 0; i + 1 < ng; i++) {
    const bs_study_run *a = &S->runs[grp[i]], *b = &S->runs[grp[i + 1]];
    double ha = bs_study_knob_h(S, a, k), hb = bs_study_knob_h(S, b, k);
    if (a->exit_code != 0 || b->exit_code != 0 || !(hb < ha)) continue;
    bs_study_run tmp = *a;
    int64_t off_b[BS_STUDY_MAX_BODIES];
    bs__study_offsets(S, b->body_refine, off_b);
    if (bs__study_compare_run(S, &tmp, b->dir, off_b) || !(tmp.pos_max > 0) || !isfinite(tmp.pos_max)) continue;
    h[m] = ha;
    d[m] = tmp.pos_max;
    if (pts) fprintf(pts, "%s %.9g\n", S->knobs[k].vals[a->idx[k]], tmp.pos_max);
    rho[m] = hb / ha;
    m++;
  }
  return m;
}

double bs__study_order_successive(const bs_study *S, int k, const char *method, int *used, FILE *pts) {
  size_t n = (size_t)S->n_runs + 1;
  int *grp = malloc(sizeof(int) * n);
  double *h = malloc(sizeof(double) * n), *d = malloc(sizeof(double) * n), *rho = malloc(sizeof(double) * n);
  double p = NAN;
  *used = 0;
  if (grp && h && d && rho) {
    int ng = sorted_group(S, k, method, grp);
    int m = level_pairs(S, k, grp, ng, h, d, rho, pts);
    p = bs_study_successive_fit(m, h, d, rho, used);
  }
  free(grp);
  free(h);
  free(d);
  free(rho);
  return p;
}
