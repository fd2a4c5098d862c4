/* study_qoi.c — a study's quantities of interest: each run's qoi.csv against
 * the reference's, and their convergence (GCI) along a knob (bs_study.h). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "study_internal.h"

const char *bs_study_run_status(const bs_study_run *r) {
  return r->timed_out ? "timeout" : r->exit_code != 0 ? "failed" : "ok";
}

/* The reference's folder; NULL when the reference run failed or timed out. */
static const char *ref_dir(const bs_study *S) {
  if (S->ref_dir[0]) return S->ref_dir;
  if (S->ref < 0 || S->runs[S->ref].exit_code != 0 || S->runs[S->ref].timed_out) return NULL;
  return S->runs[S->ref].dir;
}

/* The columns of S->qoi in t (-1: absent). */
static void columns(const bs_study *S, const bs_qoi_table *t, int *col) {
  for (int q = 0; q < S->n_qoi; q++) col[q] = bs_qoi_table_column(t, S->qoi[q]);
}

/* The reference's scale Q of each quantity (from the origin o: its first
 * value for a position, else 0) and its last value. */
static void reference_scales(bs_study *S, const bs_qoi_table *ref, const int *col) {
  for (int q = 0; q < S->n_qoi; q++) {
    double m = 0;
    S->q_ref_ok[q] = col[q] >= 0 && ref->n_rows > 0;
    S->q_origin[q] = S->q_ref_ok[q] && S->q_kind[q] == BS_QOI_POSITION ? ref->values[col[q]] : 0.0;
    for (int i = 0; S->q_ref_ok[q] && i < ref->n_rows; i++) {
      double v = fabs(ref->values[(size_t)i * ref->n_qoi + col[q]] - S->q_origin[q]);
      if (v > m) m = v;
    }
    S->q_ref_scale[q] = m > 0 ? m : 1.0;
    S->q_ref_last[q] = S->q_ref_ok[q] ? ref->values[(size_t)(ref->n_rows - 1) * ref->n_qoi + col[q]] : NAN;
  }
}

/* Run r's values and errors from its table t against ref (rc: ref's columns). */
static void run_errors(const bs_study *S, bs_study_run *r, const bs_qoi_table *t, const bs_qoi_table *ref,
                       const int *rc) {
  int col[BS_STUDY_MAX_QOI];
  columns(S, t, col);
  for (int q = 0; q < S->n_qoi; q++) {
    if (col[q] < 0 || t->n_rows == 0) continue;
    r->q_last[q] = t->values[(size_t)(t->n_rows - 1) * t->n_qoi + col[q]];
    if (!ref || !S->q_ref_ok[q]) continue;
    double emax = 0, elast = NAN;
    for (int i = 0, j = 0; i < t->n_rows && j < ref->n_rows;) {
      double ta = t->time[i], tb = ref->time[j];
      if (fabs(ta - tb) <= 1e-9 * (1 + fabs(tb))) {
        double a = t->values[(size_t)i * t->n_qoi + col[q]], b = ref->values[(size_t)j * ref->n_qoi + rc[q]];
        elast = fabs(a - b) / S->q_ref_scale[q];
        if (elast > emax) emax = elast;
        i++, j++;
      } else if (ta < tb) i++;
      else j++;
    }
    r->q_err_last[q] = elast;
    r->q_err_max[q] = isfinite(elast) ? emax : NAN;
  }
}

int bs__study_read_qoi(bs_study *S) {
  int n_bad = 0;
  for (int i = 0; i < S->n_runs; i++)
    for (int q = 0; q < BS_STUDY_MAX_QOI; q++) S->runs[i].q_last[q] = S->runs[i].q_err_last[q] = S->runs[i].q_err_max[q] = NAN;
  for (int q = 0; q < BS_STUDY_MAX_QOI; q++) {
    S->q_ref_ok[q] = 0;
    S->q_ref_scale[q] = 1.0;
    S->q_origin[q] = 0;
    S->q_ref_last[q] = NAN;
  }
  if (S->n_qoi == 0) return 0;
  bs_qoi_table ref = {0}, t;
  bs_error err;
  int rc[BS_STUDY_MAX_QOI];
  const char *rd = ref_dir(S);
  int have_ref = rd && bs_qoi_csv_read(rd, &ref, &err) == 0;
  if (have_ref) {
    columns(S, &ref, rc);
    reference_scales(S, &ref, rc);
  }
  for (int i = 0; i < S->n_runs; i++) {
    bs_study_run *r = &S->runs[i];
    if (bs_qoi_csv_read(r->dir, &t, &err)) {
      n_bad += r->exit_code == 0 && !r->timed_out;
      continue;
    }
    run_errors(S, r, &t, have_ref ? &ref : NULL, rc);
    for (int q = 0; q < S->n_qoi; q++)
      if (bs_qoi_table_column(&t, S->qoi[q]) < 0) {
        n_bad++;
        break;
      }
    bs_qoi_table_free(&t);
  }
  if (have_ref) bs_qoi_table_free(&ref);
  return n_bad;
}

bs_gci_status bs_study_qoi_gci(const bs_study *S, int k, const char *method, int q, bs_gci *g, int used[3],
                               int *n_skipped) {
  int *grp = malloc(sizeof(int) * ((size_t)S->n_runs + 1));
  used[0] = used[1] = used[2] = -1;
  *n_skipped = 0;
  int ng = grp ? bs__study_group(S, k, method, grp) : 0, m = 0;
  /* the three finest (smallest h) complete runs, fine to coarse */
  for (int pass = 0; pass < 3; pass++) {
    int best = -1;
    double hb = INFINITY, hprev = pass ? bs_study_knob_h(S, &S->runs[used[pass - 1]], k) : 0;
    for (int i = 0; i < ng; i++) {
      const bs_study_run *r = &S->runs[grp[i]];
      double h = bs_study_knob_h(S, r, k), v = r->q_last[q];
      if (pass == 0 && (r->exit_code != 0 || r->timed_out)) (*n_skipped)++;
      if (r->exit_code != 0 || r->timed_out || !isfinite(v) || !(h > hprev * (1 + 1e-12)) || !(h < hb)) continue;
      best = grp[i], hb = h;
    }
    if (best < 0) break;
    used[m++] = best;
  }
  free(grp);
  double h[3], f[3];
  for (int i = 0; i < m; i++) {
    h[i] = bs_study_knob_h(S, &S->runs[used[i]], k);
    f[i] = S->runs[used[i]].q_last[q];
  }
  if (m < 3) {
    bs_study_gci((double[3]){0, 0, 0}, (double[3]){0, 0, 0}, g);
    return g->status;
  }
  return bs_study_gci(h, f, g);
}
