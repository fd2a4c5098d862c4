/* study_summary.c — a study's summary text (bs_study.h): the runs that
 * failed or timed out, each quantity of interest per run with its Richardson
 * extrapolation and GCI along each refinement or time knob, and the observed
 * orders. The verdict (the cheapest run within 1%, 0.1%, 0.01%) is not here:
 * it is S->verdict (study_verdict.c), for the caller to print, once. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "study_internal.h"

#define MAX_METHODS 256

/* ---- the summary ------------------------------------------------------------ */

/* The orders of knob k for one method: against the reference, and from successive levels. */
static void summary_order(const bs_study *S, int k, const char *method, FILE *f) {
  const bs_study_knob *v = &S->knobs[k];
  int is_t = bs_study_knob_is_time(v);
  bs_study_order o = bs__study_order_fit(S, k, method);
  if (isfinite(o.p))
    fprintf(f, "order in %s (error ~ %s^p, vs %s): method %s p = %.3f over %d runs\n", is_t ? "time" : "space",
            is_t ? "dt" : "h", v->key, method, o.p, o.used);
  else
    fprintf(f, "order in %s (vs %s): method %s: not measurable (fewer than 2 runs with a positive error)\n",
            is_t ? "time" : "space", v->key, method);
  if (isfinite(o.p) && o.used < 3)
    fprintf(f, "  (only %d runs: a line through them, not a fit; read the order from successive levels)\n", o.used);
  int used = 0;
  double ps = bs__study_order_successive(S, k, method, &used, NULL);
  if (isfinite(ps))
    fprintf(f, "  from successive levels (each run against the next finer): p = %.3f over %d pairs\n", ps, used);
}

/* The runs that failed or timed out, never dropped silently. */
static void summary_not_ok(const bs_study *S, FILE *f) {
  for (int i = 0; i < S->n_runs; i++) {
    const bs_study_run *r = &S->runs[i];
    if (r->exit_code == 0 && !r->timed_out) continue;
    fprintf(f, "  %s %s", bs_study_run_status(r), r->name);
    if (!r->timed_out) fprintf(f, " (exit %d)", r->exit_code);
    fprintf(f, ": left out of the errors, fits and GCI%s; its log: %s/run.log\n",
            r->is_ref ? " (it is the reference: nothing is compared)" : "", r->dir);
  }
}

/* Each run's value of each quantity and its error against the reference. */
static void summary_qoi_runs(const bs_study *S, FILE *f) {
  fprintf(f, "quantities of interest at the last frame (error against the reference: |q - q_ref| / max over its "
             "frames of |q_ref - o|, o its first value for a position, else 0):\n");
  for (int i = 0; i < S->n_runs; i++) {
    const bs_study_run *r = &S->runs[i];
    fprintf(f, "  %-40s %-7s", r->name, bs_study_run_status(r));
    for (int q = 0; q < S->n_qoi; q++) fprintf(f, "  %s %.9g (error %.3g)", S->qoi[q], r->q_last[q], r->q_err_last[q]);
    fprintf(f, "%s\n", r->is_ref ? "  [reference]" : "");
  }
}

/* The GCI of quantity q along knob k for method. */
static void summary_gci(const bs_study *S, int k, const char *method, int q, FILE *f) {
  bs_gci g;
  int used[3], skipped;
  bs_gci_status st = bs_study_qoi_gci(S, k, method, q, &g, used, &skipped);
  fprintf(f, "  %s along %s (%s), method %s: ", S->qoi[q], S->knobs[k].key,
          bs_study_knob_is_time(&S->knobs[k]) ? "h = dt" : "h = 2^-level", method);
  if (used[2] < 0) {
    fprintf(f, "fewer than three complete levels (%d skipped: failed or timeout): no GCI\n", skipped);
    return;
  }
  fprintf(f, "levels %s, %s, %s: %.9g, %.9g, %.9g\n", S->knobs[k].vals[S->runs[used[0]].idx[k]],
          S->knobs[k].vals[S->runs[used[1]].idx[k]], S->knobs[k].vals[S->runs[used[2]].idx[k]],
          S->runs[used[0]].q_last[q], S->runs[used[1]].q_last[q], S->runs[used[2]].q_last[q]);
  if (st != BS_GCI_OK && st != BS_GCI_CONVERGED) {
    fprintf(f, "    %s convergence: no order, extrapolation or GCI fitted\n", bs_gci_status_name(st));
    return;
  }
  fprintf(f, "    observed order p = %.4g, Richardson extrapolated %.9g, GCI_fine = %.3g%%, GCI_coarse = %.3g%%, "
             "asymptotic ratio %.4g (%s)%s\n",
          g.p, g.extrapolated, 100 * g.gci_fine, 100 * g.gci_coarse, g.asymptotic,
          fabs(g.asymptotic - 1) < 0.1 ? "in the asymptotic range" : "not yet asymptotic",
          skipped ? " [failed or timed-out levels skipped]" : "");
}

/* Each quantity per run, and its GCI along each refinement or time knob. */
static void summary_qoi(const bs_study *S, const char **methods, int nm, FILE *f) {
  summary_qoi_runs(S, f);
  for (int q = 0; q < S->n_qoi; q++)
    for (int m = 0; m < nm; m++)
      for (int k = 0; k < S->n_knobs; k++)
        if (S->knobs[k].kind == BS_KNOB_REFINE || bs_study_knob_is_time(&S->knobs[k])) summary_gci(S, k, methods[m], q, f);
}

void bs_study_summary_write(const bs_study *S, FILE *f) {
  const char *methods[MAX_METHODS];
  int nm = bs_study_methods(S, methods, MAX_METHODS);
  int n_failed = 0, n_timeout = 0;
  for (int i = 0; i < S->n_runs; i++) {
    n_failed += S->runs[i].exit_code != 0 && !S->runs[i].timed_out;
    n_timeout += S->runs[i].timed_out;
  }
  char ref_desc[sizeof "the run in " + BS_MAX_PATH];
  if (S->ref_dir[0]) snprintf(ref_desc, sizeof ref_desc, "the run in %s", S->ref_dir);
  else snprintf(ref_desc, sizeof ref_desc, "%s", S->ref >= 0 ? S->runs[S->ref].name : "?");
  fprintf(f, "\nstudy %s: %d runs (%d failed, %d timed out); reference: %s\n", S->name, S->n_runs, n_failed,
          n_timeout, ref_desc);
  if (S->disp > 1e-12 * S->size)
    fprintf(f, "position error: RMS |x - x_ref| over what the reference moved (RMS displacement from its first "
               "frame, max over frames: %.4g m; body size %.4g m)\n", S->disp, S->size);
  else
    fprintf(f, "position error: RMS |x - x_ref| over the body size %.4g m (the reference did not move)\n", S->size);
  summary_not_ok(S, f);
  if (S->n_qoi) summary_qoi(S, methods, nm, f);
  int any_t = 0, any_s = 0;
  for (int k = 0; k < S->n_knobs; k++) {
    int is_t = bs_study_knob_is_time(&S->knobs[k]), is_s = S->knobs[k].kind == BS_KNOB_REFINE;
    if (!is_t && !is_s) continue;
    any_t |= is_t;
    any_s |= is_s;
    for (int m = 0; m < nm; m++) summary_order(S, k, methods[m], f);
  }
  if (!any_t) fprintf(f, "order in time: steps_per_frame not varied\n");
  if (!any_s) fprintf(f, "order in space: refine not varied\n");
}
