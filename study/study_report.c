/* study_report.c — a study's report: study.csv, the gnuplot data files and
 * plots.gp, and the summary text (bs_study.h). Running gnuplot and choosing
 * where the summary goes is the caller's. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "study_internal.h"

#define MAX_METHODS 256

int bs_study_file_path(const char *dir, const char *name, char p[BS_STUDY_FILE_PATH], bs_error *err) {
  size_t dl = strlen(dir), nl = strlen(name);
  if (dl >= BS_MAX_PATH || nl >= BS_STUDY_FILE_NAME_MAX) {
    p[0] = 0;
    return bs_error_set(err, BS_EINPUT,
                        "'%.100s%s/%.80s': the path is too long (a folder of %zu bytes, at most %d; a file name of "
                        "%zu, at most %d)",
                        dir, dl > 100 ? "..." : "", name, dl, BS_MAX_PATH - 1, nl, BS_STUDY_FILE_NAME_MAX - 1);
  }
  memcpy(p, dir, dl);
  p[dl] = '/';
  memcpy(p + dl + 1, name, nl + 1);
  return 0;
}

/* A file of the study's folder opened for writing, or NULL (a path too long
 * or a file that cannot be opened). */
static FILE *open_out(const bs_study *S, const char *name, char p[BS_STUDY_FILE_PATH]) {
  bs_error e;
  if (bs_study_file_path(S->out, name, p, &e)) return NULL;
  return fopen(p, "w");
}

int bs_study_csv_write(const bs_study *S, bs_error *err) {
  char p[BS_STUDY_FILE_PATH];
  int st = bs_study_file_path(S->out, "study.csv", p, err);
  if (st) return st;
  FILE *f = fopen(p, "w");
  if (!f) return bs_error_set(err, BS_EIO, "cannot write '%s'", p);
  fprintf(f, "run");
  /* the shorthand "method" would repeat the method column's name: its path instead */
  for (int k = 0; k < S->n_knobs; k++)
    fprintf(f, ",%s", !strcmp(S->knobs[k].key, "method") ? S->knobs[k].path : S->knobs[k].key);
  fprintf(f, ",method,status,exit,failed,failed_steps,frames,s_per_frame,newton_per_step,cg_per_step,peak_mib,"
             "pos_err_max,pos_err_last,vel_err_max,vel_err_last,energy_drift,inverted_max,penetration_max,reference,"
             "pareto,verdict_error,verdict_by");
  for (int q = 0; q < S->n_qoi; q++) fprintf(f, ",%s,%s_err_last,%s_err_max", S->qoi[q], S->qoi[q], S->qoi[q]);
  fputc('\n', f);
  for (int i = 0; i < S->n_runs; i++) {
    const bs_study_run *r = &S->runs[i];
    fprintf(f, "%s", r->name);
    for (int k = 0; k < S->n_knobs; k++) fprintf(f, ",%s", S->knobs[k].vals[r->idx[k]]);
    fprintf(f, ",%s,%s,%d,%d,%ld,%d,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%d,%.6g,%d,%d", r->method,
            bs_study_run_status(r), r->exit_code, r->exit_code != 0, r->failed_steps, r->n_rows > 0 ? r->n_rows - 1 : 0, r->s_per_frame, r->newton_per_step,
            r->cg_per_step, r->peak_mib, r->pos_max, r->pos_last, r->vel_max, r->vel_last, r->drift, r->inv_max,
            r->pen_max, r->is_ref, r->pareto);
    fprintf(f, ",%.6g,%s", r->verdict_err,
            !S->verdict.on_qoi ? "position" : r->verdict_by >= 0 ? S->qoi[r->verdict_by] : "-");
    for (int q = 0; q < S->n_qoi; q++) fprintf(f, ",%.12g,%.6g,%.6g", r->q_last[q], r->q_err_last[q], r->q_err_max[q]);
    fputc('\n', f);
  }
  if (fclose(f)) return bs_error_set(err, BS_EIO, "cannot write '%s'", p);
  return 0;
}

/* ---- plots ------------------------------------------------------------------ */

/* plot_pareto.dat: the front (error > 0) sorted by cost. */
static void pareto_data(const bs_study *S) {
  char p[BS_STUDY_FILE_PATH];
  FILE *d = open_out(S, "plot_pareto.dat", p);
  if (!d) return;
  fprintf(d, "# Pareto front (error > 0): s_per_frame verdict_error\n");
  int *ord = malloc(sizeof(int) * ((size_t)S->n_runs + 1)), no = 0;
  for (int i = 0; ord && i < S->n_runs; i++)
    if (S->runs[i].pareto && S->runs[i].verdict_err > 0) ord[no++] = i;
  for (int i = 1; i < no; i++)
    for (int j = i; j > 0 && S->runs[ord[j]].s_per_frame < S->runs[ord[j - 1]].s_per_frame; j--) {
      int t = ord[j];
      ord[j] = ord[j - 1];
      ord[j - 1] = t;
    }
  for (int i = 0; i < no; i++) fprintf(d, "%.9g %.9g\n", S->runs[ord[i]].s_per_frame, S->runs[ord[i]].verdict_err);
  if (no == 0) fprintf(d, "nan nan\n");
  free(ord);
  fclose(d);
}

/* The smallest positive finite verdict error of the runs (1e-6 if none):
 * failed and timed-out runs are drawn at half of it. */
static double error_floor(const bs_study *S) {
  double m = INFINITY;
  for (int i = 0; i < S->n_runs; i++)
    if (S->runs[i].verdict_err > 0 && S->runs[i].verdict_err < m) m = S->runs[i].verdict_err;
  return isfinite(m) ? 0.5 * m : 1e-6;
}

/* A run's cost for the plots: s/frame, else its wall seconds per frame. */
static double plot_cost_of(const bs_study_run *r) {
  if (r->s_per_frame > 0 && isfinite(r->s_per_frame)) return r->s_per_frame;
  return r->wall > 0 && r->frames > 0 ? r->wall / r->frames : NAN;
}

/* plot_cost.dat: per method the runs with a positive verdict error (cost, error,
 * label), then one block of the failed and timed-out runs; the points written. */
static int cost_data(const bs_study *S, const char **methods, int nm) {
  char p[BS_STUDY_FILE_PATH];
  FILE *d = open_out(S, "plot_cost.dat", p);
  int n = 0;
  for (int m = 0; d && m <= nm; m++) {
    fprintf(d, m < nm ? "# method %s: s_per_frame verdict_error setting\n" : "# failed or timeout%s: cost floor\n",
            m < nm ? methods[m] : "");
    for (int i = 0; i < S->n_runs; i++) {
      const bs_study_run *r = &S->runs[i];
      int bad = r->exit_code != 0 || r->timed_out;
      if (m < nm && !bad && !strcmp(r->method, methods[m]) && r->verdict_err > 0 && isfinite(r->verdict_err) &&
          r->s_per_frame > 0)
        n += fprintf(d, "%.9g %.9g \"%s\"\n", r->s_per_frame, r->verdict_err, r->name) > 0;
      if (m == nm && bad && isfinite(plot_cost_of(r)))
        fprintf(d, "%.9g %.9g \"%s (%s)\"\n", plot_cost_of(r), error_floor(S), r->name, bs_study_run_status(r));
    }
    fprintf(d, "%s\n\n", m == nm ? "nan nan \"\"" : "");
  }
  if (d) fclose(d);
  return n;
}

/* Fixed ranges and a note when a plot has no point (gnuplot refuses an
 * empty log-scale range). */
static void empty_guard(FILE *gp, int n_points, const char *what) {
  if (n_points == 0)
    fprintf(gp, "set xrange [1e-3:1]\nset yrange [1e-6:1]\nset label 1 'no run with a positive %s' at graph 0.2,0.5\n",
            what);
}

static void empty_unguard(FILE *gp) { fprintf(gp, "set autoscale xy\nunset label 1\n"); }

/* The cost plot's y label: the verdict's quantity. */
static const char *verdict_label(const bs_study *S, char *buf, size_t n) {
  const bs_study_verdict *v = &S->verdict;
  if (!v->on_qoi) {
    snprintf(buf, n, "position error: max over frames of RMS |x - x_ref| / %s (1)",
             S->disp > 1e-12 * S->size ? "what the reference moved" : "body size");
    return buf;
  }
  size_t k = (size_t)snprintf(buf, n, "verdict error:");
  for (int i = 0; i < v->n_judged && k < n; i++)
    k += (size_t)snprintf(buf + k, n - k, "%s %s", i ? "," : "", S->qoi[v->judged[i].qoi]);
  if (k < n) snprintf(buf + k, n - k, " at the last frame (1)");
  return buf;
}

/* 1. the verdict's error against cost, the Pareto front marked, points labelled. */
static void plot_cost(const bs_study *S, const char **methods, int nm, FILE *gp) {
  char label[512];
  int n = cost_data(S, methods, nm);
  pareto_data(S);
  fprintf(gp, "set output 'error_vs_cost.png'\nset logscale xy\nset xlabel 'cost: solver seconds per frame (s)'\n"
              "set ylabel '%s'\n"
              "set title 'Error against cost (%s; a run of error 0 is not drawn)'\n",
          verdict_label(S, label, sizeof label), S->name);
  empty_guard(gp, n, "error");
  fprintf(gp, "plot ");
  for (int m = 0; m < nm; m++)
    fprintf(gp, "'plot_cost.dat' index %d using 1:2 with points pt 7 ps 1.3 title '%s', "
                "'plot_cost.dat' index %d using 1:2:3 with labels offset 0,0.8 font ',7' notitle, ",
            m, methods[m], m);
  fprintf(gp, "'plot_cost.dat' index %d using 1:2 with points pt 2 ps 2 lc rgb 'red' title 'failed or timeout (no "
              "error; drawn at the floor)', 'plot_cost.dat' index %d using 1:2:3 with labels offset 0,-0.8 font ',7' "
              "tc rgb 'red' notitle, ",
          nm, nm);
  fprintf(gp, "'plot_pareto.dat' using 1:2 with linespoints lw 2 lc rgb 'black' pt 6 ps 2.2 title 'Pareto front'\n"
              "unset logscale\n");
  empty_unguard(gp);
}

/* One method's curves of the convergence plot of knob k: level (space) or
 * dt (time) against the position error. */
static void plot_refine_method(const bs_study *S, int k, int m, const char *method, int *grp, FILE *d, FILE *ds,
                               FILE *gp) {
  const int is_t = bs_study_knob_is_time(&S->knobs[k]);
  bs_study_order o = bs__study_order_fit(S, k, method);
  int ng = bs__study_group(S, k, method, grp);
  if (d) {
    fprintf(d, "# method %s: %s pos_err_max\n", method, is_t ? "dt" : "level");
    for (int i = 0; i < ng; i++) {
      const bs_study_run *r = &S->runs[grp[i]];
      if (!bs__study_fit_point(S, r, k) || !(r->pos_max > 0)) continue;
      if (is_t) fprintf(d, "%.9g %.9g\n", bs_study_knob_h(S, r, k), r->pos_max);
      else fprintf(d, "%s %.9g\n", S->knobs[k].vals[r->idx[k]], r->pos_max);
    }
    fprintf(d, "\n\n");
  }
  fprintf(gp, "'plot_refine_%d.dat' index %d using 1:2 with points pt 7 ps 1.3 title '%s: against the reference', ", k,
          m, method);
  if (isfinite(o.p) && is_t)
    fprintf(gp, "exp(%.9g) * x**%.9g with lines dt 2 title '%s fit: slope %.2f (%d runs)', ", o.logc, o.p, method, o.p,
            o.used);
  else if (isfinite(o.p))
    fprintf(gp, "exp(%.9g) * 2**(-%.9g * x) with lines dt 2 title '%s fit: order %.2f (%d runs)', ", o.logc, o.p,
            method, o.p, o.used);
  int used = 0;
  if (ds) fprintf(ds, "# method %s: level, position error against the next finer level\n", method);
  double ps = is_t ? NAN : bs__study_order_successive(S, k, method, &used, ds);
  if (ds) fprintf(ds, "\n\n");
  if (ds && used > 0) {
    char ord[64] = "";
    if (isfinite(ps)) snprintf(ord, sizeof ord, " (order %.2f)", ps);
    fprintf(gp, "'plot_refine_successive_%d.dat' index %d using 1:2 with linespoints pt 5 ps 1.1 title "
                "'%s: against the next finer level%s', ",
            k, m, method, ord);
  }
}

/* Points the convergence plot of knob k will hold. */
static int refine_points(const bs_study *S, int k, const char **methods, int nm, int *grp) {
  int n = 0;
  for (int m = 0; m < nm; m++) {
    int ng = bs__study_group(S, k, methods[m], grp);
    for (int i = 0; i < ng; i++) n += bs__study_fit_point(S, &S->runs[grp[i]], k) && S->runs[grp[i]].pos_max > 0;
  }
  return n;
}

/* 2. error against refinement level (log-log in h = 2^-level) or against dt
 * (log-log), with the fitted order. */
static void plot_refine(const bs_study *S, int k, const char **methods, int nm, int *grp, FILE *gp) {
  const int is_t = bs_study_knob_is_time(&S->knobs[k]);
  char p[BS_STUDY_FILE_PATH], name[BS_STUDY_FILE_NAME_MAX];
  snprintf(name, sizeof name, "plot_refine_%d.dat", k);
  FILE *d = open_out(S, name, p);
  snprintf(name, sizeof name, "plot_refine_successive_%d.dat", k);
  FILE *ds = open_out(S, name, p);
  if (is_t)
    fprintf(gp, "set output 'error_vs_dt%s%s.png'\nset logscale xy\nset key inside top left\n"
                "set xlabel 'time step dt (s) [%s]'\n",
            k ? "_" : "", k ? S->knobs[k].key : "", S->knobs[k].key);
  else
    fprintf(gp, "set output 'error_vs_refine%s%s.png'\nset logscale y\nset key inside top right\nset xtics 1\n"
                "set xlabel '%s: refinement level (cell size h ~ 2^-level, so log-log in h)'\n",
            k ? "_" : "", k ? S->knobs[k].key : "", S->knobs[k].key);
  fprintf(gp, "set ylabel 'position error: max over frames of RMS |x - x_ref| / what the reference moved (1)'\n"
              "set title 'Error against %s (other knobs at the reference)'\n",
          is_t ? "time step" : "refinement");
  empty_guard(gp, refine_points(S, k, methods, nm, grp), "position error");
  fprintf(gp, "plot ");
  for (int m = 0; m < nm; m++) plot_refine_method(S, k, m, methods[m], grp, d, ds, gp);
  fprintf(gp, "1/0 notitle\nunset logscale\nset key outside right\nset xtics autofreq\n");
  empty_unguard(gp);
  if (d) fclose(d);
  if (ds) fclose(ds);
}

/* 3. iterations per step against steps per frame (knob k). */
static void plot_iterations(const bs_study *S, int k, const char **methods, int nm, int *grp, FILE *gp) {
  char p[BS_STUDY_FILE_PATH];
  FILE *d = open_out(S, "plot_iterations.dat", p);
  for (int m = 0; d && m < nm; m++) {
    int ng = bs__study_group(S, k, methods[m], grp);
    fprintf(d, "# method %s: steps_per_frame newton_per_step cg_per_step\n", methods[m]);
    for (int i = 0; i < ng; i++) {
      const bs_study_run *r = &S->runs[grp[i]];
      fprintf(d, "%d %.9g %.9g\n", r->spf, r->newton_per_step, r->cg_per_step);
    }
    fprintf(d, "\n\n");
  }
  if (d) fclose(d);
  fprintf(gp, "set output 'iterations_vs_steps.png'\nset format y '%%g'\nset logscale x 2\nset xlabel 'steps per frame'\n"
              "set ylabel 'Newton iterations per step'\nset y2label 'CG iterations per step'\n"
              "set ytics nomirror\nset y2tics\nset logscale y2\nset format y2 '%%g'\n"
              "set title 'Iterations per step (other knobs at the reference)'\nplot ");
  for (int m = 0; m < nm; m++)
    fprintf(gp, "'plot_iterations.dat' index %d using 1:2 with linespoints pt 7 lw 2 title '%s Newton', "
                "'plot_iterations.dat' index %d using 1:3 axes x1y2 with linespoints pt 6 dt 2 title '%s CG', ",
            m, methods[m], m, methods[m]);
  fprintf(gp, "1/0 notitle\nunset logscale\nunset y2tics\nunset y2label\n");
}

int bs_study_plots_write(const bs_study *S, bs_error *err) {
  const char *methods[MAX_METHODS];
  int nm = bs_study_methods(S, methods, MAX_METHODS);
  char p[BS_STUDY_FILE_PATH];
  int st = bs_study_file_path(S->out, "plots.gp", p, err);
  if (st) return st;
  int *grp = malloc(sizeof(int) * ((size_t)S->n_runs + 1));
  if (!grp) return bs_error_set(err, BS_ENOMEM, "out of memory (study plots)");
  FILE *gp = fopen(p, "w");
  if (!gp) {
    free(grp);
    return bs_error_set(err, BS_EIO, "cannot write '%s'", p);
  }
  fprintf(gp, "# written by bigstep study; run with: gnuplot plots.gp (in this folder)\n"
              "if (strstrt(GPVAL_TERMINALS, 'pngcairo') > 0) { set terminal pngcairo size 900,600 } "
              "else { set terminal png size 900,600 }\n"
              "set termoption noenhanced\n"
              "set grid\nset key outside right\nset format y '%%.0e'\n");
  plot_cost(S, methods, nm, gp);
  for (int k = 0; k < S->n_knobs; k++)
    if (S->knobs[k].kind == BS_KNOB_REFINE || bs_study_knob_is_time(&S->knobs[k]))
      plot_refine(S, k, methods, nm, grp, gp);
  for (int k = 0; k < S->n_knobs; k++)
    if (S->knobs[k].kind == BS_KNOB_STEPS_PER_FRAME) {
      plot_iterations(S, k, methods, nm, grp, gp);
      break;
    }
  free(grp);
  if (fclose(gp)) return bs_error_set(err, BS_EIO, "cannot write '%s'", p);
  return 0;
}

