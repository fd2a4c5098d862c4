/* study_verdict.c — a study's one verdict (bs_study.h): which quantity is
 * judged (the quantities of interest, against their Richardson extrapolation
 * where the refinement or time sequence gives one, else against the
 * reference; the position error when there is none), each run's error in
 * it, and the cheapest run within 1%, 0.1%, 0.01% across every knob. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "study_internal.h"

static const double thresholds[BS_STUDY_N_THRESHOLDS] = {1e-2, 1e-3, 1e-4};

/* The method whose convergence groups give the extrapolations: the
 * reference run's, else the first run's. */
static void verdict_method(const bs_study *S, char *m, size_t n) {
  const char *src = S->ref >= 0 ? S->runs[S->ref].method : S->n_runs > 0 ? S->runs[0].method : "";
  snprintf(m, n, "%s", src);
}

/* The GCI of quantity q along the first refinement knob (then the first
 * time knob) whose three finest levels converge (monotone or converged)
 * into j->gci, j->knob; else along the first with three levels (j->knob -1
 * when there is none). Returns 1 when the one found converges. */
static int quantity_gci(const bs_study *S, const char *method, int q, bs_study_judged *j) {
  for (int pass = 0; pass < 2; pass++)
    for (int k = 0; k < S->n_knobs; k++) {
      const bs_study_knob *v = &S->knobs[k];
      if (pass == 0 ? v->kind != BS_KNOB_REFINE : !bs_study_knob_is_time(v)) continue;
      bs_gci g;
      int used[3], skipped;
      bs_gci_status st = bs_study_qoi_gci(S, k, method, q, &g, used, &skipped);
      if (st == BS_GCI_BAD_INPUT) continue;
      int ok = (st == BS_GCI_OK || st == BS_GCI_CONVERGED) && isfinite(g.extrapolated);
      if (j->knob < 0 || ok) {
        j->gci = g;
        j->knob = k;
      }
      if (ok) return 1;
    }
  return 0;
}

/* Quantity q's target: its extrapolation (quantity_gci) when the order p is
 * at least BS_STUDY_MIN_ORDER (or the levels agree: converged); else the
 * reference's value. 0, or -1 when q cannot be judged (neither). */
static int judge_quantity(const bs_study *S, const char *method, int q, bs_study_judged *j) {
  memset(j, 0, sizeof *j);
  j->qoi = q;
  j->knob = -1;
  j->gci.status = BS_GCI_BAD_INPUT;
  int conv = quantity_gci(S, method, q, j);
  if (conv && (j->gci.status == BS_GCI_CONVERGED || j->gci.p >= BS_STUDY_MIN_ORDER)) {
    j->extrapolated = 1;
    j->target = j->gci.extrapolated;
    double d = fabs(j->target - S->q_origin[q]);
    j->scale = d > 0 ? d : S->q_ref_scale[q];
    return 0;
  }
  j->target = S->q_ref_last[q];
  j->scale = S->q_ref_scale[q];
  return S->q_ref_ok[q] ? 0 : -1;
}

/* Run r's error in the judged quantities (the largest; *by the quantity
 * that set it, -1 for the position error); NAN when one is not measured. */
static double run_error(const bs_study_verdict *v, const bs_study_run *r, int *by) {
  *by = -1;
  if (!v->on_qoi) return r->pos_max;
  double e = -1;
  for (int i = 0; i < v->n_judged; i++) {
    const bs_study_judged *j = &v->judged[i];
    double ei = j->extrapolated ? fabs(r->q_last[j->qoi] - j->target) / j->scale : r->q_err_last[j->qoi];
    if (!isfinite(ei)) {
      *by = j->qoi;
      return NAN;
    }
    if (ei > e) {
      e = ei;
      *by = j->qoi;
    }
  }
  return e;
}

/* Whether run i competes in the ranking. */
static int candidate(const bs_study *S, const bs_study_verdict *v, int i) {
  const bs_study_run *r = &S->runs[i];
  if (r->exit_code != 0 || r->timed_out || (r->is_ref && !v->ref_competes)) return 0;
  return isfinite(r->verdict_err) && isfinite(r->s_per_frame);
}

/* The cheapest candidates within each threshold and the most accurate. */
static void rank(const bs_study *S, bs_study_verdict *v) {
  v->most_accurate = -1;
  v->n_candidates = 0;
  for (int t = 0; t < BS_STUDY_N_THRESHOLDS; t++) {
    v->threshold[t] = thresholds[t];
    v->cheapest[t] = -1;
  }
  for (int i = 0; i < S->n_runs; i++) {
    if (!candidate(S, v, i)) continue;
    const bs_study_run *r = &S->runs[i];
    v->n_candidates++;
    if (v->most_accurate < 0 || r->verdict_err < S->runs[v->most_accurate].verdict_err) v->most_accurate = i;
    for (int t = 0; t < BS_STUDY_N_THRESHOLDS; t++) {
      int *b = &v->cheapest[t];
      if (r->verdict_err <= v->threshold[t] && (*b < 0 || r->s_per_frame < S->runs[*b].s_per_frame)) *b = i;
    }
  }
}

void bs_study_verdict_make(bs_study *S, bs_study_verdict *v) {
  memset(v, 0, sizeof *v);
  verdict_method(S, v->method, sizeof v->method);
  int any_extrapolated = 0;
  for (int q = 0; q < S->n_qoi; q++) {
    bs_study_judged *j = &v->judged[v->n_judged];
    if (judge_quantity(S, v->method, q, j)) continue;
    any_extrapolated |= j->extrapolated;
    v->n_judged++;
  }
  v->on_qoi = v->n_judged > 0;
  v->ref_competes = v->on_qoi && any_extrapolated;
  for (int i = 0; i < S->n_runs; i++) S->runs[i].verdict_err = run_error(v, &S->runs[i], &S->runs[i].verdict_by);
  rank(S, v);
}
