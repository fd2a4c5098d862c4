/* study_results.c — a study's results once its runs have run: each run's
 * costs from its folder (frames.csv, summary.txt), the errors against the
 * reference (study_compare.c), the quantities (study_qoi.c), the verdict
 * (study_verdict.c) and the Pareto front of cost against the verdict's
 * error (bs_study.h). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "study_internal.h"

/* s/frame from summary.txt's row and the peak memory (MiB). */
static int read_summary(const char *dir, double *spf_s, double *peak) {
  bs_summary u;
  bs_error err;
  if (bs_summary_read(dir, &u, &err)) return -1;
  *spf_s = u.s_per_frame;
  if (isfinite(u.peak_mib)) *peak = u.peak_mib;
  return 0;
}

/* Cost and energy columns of a finished run. */
static void read_costs(bs_study_run *r) {
  bs_frames_table F;
  bs_error err;
  r->s_per_frame = r->newton_per_step = r->cg_per_step = r->drift = r->pen_max = NAN;
  r->peak_mib = r->maxrss_kib > 0 ? r->maxrss_kib / 1024.0 : NAN;
  r->complete = bs_study_run_complete(r);
  if (bs_frames_csv_read(r->dir, &F, &err)) return;
  r->n_rows = F.n;
  r->newton = F.newton;
  r->cg = F.cg;
  r->failed_steps = F.failed;
  r->inv_max = F.inverted_max;
  int fr = F.n - 1;
  long steps = r->is_static ? (fr > 0 ? 1 : 0) : (long)fr * r->spf;
  double sum_s, peak = NAN;
  /* s/frame: the solver's time per frame (frames.csv, microsecond resolution);
     summary.txt's wall-clock figure when frames.csv has no timing */
  int have_sum = read_summary(r->dir, &sum_s, &peak) == 0;
  if (fr > 0 && F.seconds > 0) r->s_per_frame = F.seconds / fr;
  else if (have_sum) r->s_per_frame = sum_s;
  if (!isfinite(r->peak_mib) && isfinite(peak)) r->peak_mib = peak;
  if (steps > 0) {
    r->newton_per_step = (double)F.newton / steps;
    r->cg_per_step = (double)F.cg / steps;
  }
  if (F.n > 0) {
    r->drift = bs_study_energy_drift(&F);
    if (F.has_depth) {
      r->pen_max = 0;
      for (int i = 0; i < F.n; i++)
        if (F.max_depth[i] > r->pen_max) r->pen_max = F.max_depth[i];
    }
  }
  bs_frames_table_free(&F);
}

void bs__study_read_costs(bs_study *S) {
  for (int i = 0; i < S->n_runs; i++) read_costs(&S->runs[i]);
}

void bs__study_mark_pareto(bs_study *S) {
  int n = S->n_runs;
  double *cost = calloc((size_t)n + 1, sizeof(double)), *error = calloc((size_t)n + 1, sizeof(double));
  int *ok = calloc((size_t)n + 1, sizeof(int)), *front = calloc((size_t)n + 1, sizeof(int));
  if (cost && error && ok && front) {
    for (int i = 0; i < n; i++) {
      cost[i] = S->runs[i].s_per_frame;
      error[i] = S->runs[i].verdict_err;
      ok[i] = S->runs[i].exit_code == 0 && !S->runs[i].timed_out;
    }
    bs_study_pareto(n, cost, error, ok, front);
    for (int i = 0; i < n; i++) S->runs[i].pareto = front[i];
  }
  free(cost);
  free(error);
  free(ok);
  free(front);
}

int bs_study_evaluate(bs_study *S) {
  bs__study_read_costs(S);
  int n_bad = bs__study_compare(S);
  n_bad += bs__study_read_qoi(S);
  bs_study_verdict_make(S, &S->verdict);
  bs__study_mark_pareto(S);
  return n_bad;
}
