/* summary.c — the closing summary of a run (summary.txt): made from the
 * run's totals, formatted, and read back (format: bs_runfolder.h). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bs_runfolder.h"

void bs_summary_make(const bs_sim *s, const bs_run_totals *T, double wall, bs_summary *out) {
  bs_sim_measures m;
  bs_sim_measure(s, 1, &m);
  bs_summary_make_measured(s, T, wall, &m, out);
}

void bs_summary_init(const bs_scene *sc, int frames, long dofs, const bs_run_totals *T, double wall,
                     bs_summary *out) {
  memset(out, 0, sizeof *out);
  snprintf(out->method, sizeof out->method, "%s", bs_method_name(sc->solver.method));
  out->steps_per_frame = sc->steps_per_frame;
  out->frames = frames;
  out->frames_total = sc->mode == BS_MODE_STATIC ? 1 : sc->frames;
  out->partial = out->frames < out->frames_total ? BS_SUMMARY_RUNNING : BS_SUMMARY_COMPLETE;
  out->s_per_frame = out->frames > 0 ? wall / out->frames : NAN; /* no frame done: not measured */
  out->dofs = dofs;
  out->solves_per_step = T->steps ? (double)T->iterations / T->steps : NAN; /* no step: not measured */
  out->failed = T->failed;
  out->max_grad = T->max_grad;
  out->totals = *T;
  out->peak_mib = bs_peak_rss() / 1048576.0;
}

void bs_summary_make_run(const bs_scene *sc, int frames, long dofs, int obstacles, const bs_run_totals *T,
                         double wall, const bs_sim_measures *m, bs_summary *out) {
  bs_summary_init(sc, frames, dofs, T, wall, out);
  out->inverted = m->inverted;
  out->self_intersections = m->self_intersections;
  out->obstacles = obstacles;
  out->penetrating = m->penetrating;
  out->max_depth = m->max_depth;
}

void bs_summary_make_measured(const bs_sim *s, const bs_run_totals *T, double wall, const bs_sim_measures *m,
                              bs_summary *out) {
  /* statics: frame 1 once solved, 0 before (or stopped in its solve) */
  bs_summary_make_run(s->scene, s->frame, bs_sim_dofs(s), s->obstacles != NULL, T, wall, m, out);
}

int bs_summary_format(const bs_summary *u, char *buf, size_t n) {
  const bs_run_totals *T = &u->totals;
  int len = snprintf(buf, n, "%-13s %6s %10s %9s %11s %8s %9s %9s\n", "method", "steps", "s/frame", "dofs",
                     "solves/step", "failed", "|gradE|", "inverted");
#define REST buf + (len < (int)n ? len : (int)n), (size_t)(len < (int)n ? (int)n - len : 0)
  len += snprintf(REST, "%-13s %6d %10.4f %9ld %11.2f %8ld %9.2e %9d\n", u->method, u->steps_per_frame, u->s_per_frame,
                  u->dofs, u->solves_per_step, u->failed, u->max_grad, u->inverted);
  if (u->self_intersections < 0) /* not computed (the petsc backend) */
    len += snprintf(REST, "at the last frame: %d inverted tets, intersecting surface triangle pairs not computed",
                    u->inverted);
  else
    len += snprintf(REST, "at the last frame: %d inverted tets, %s%lld intersecting surface triangle pairs",
                    u->inverted, u->self_intersections >= BS_SIM_SELF_CAP ? "at least " : "",
                    (long long)u->self_intersections);
  if (u->obstacles)
    len += snprintf(REST, ", %d vertices inside obstacles (max depth %.3e m)", u->penetrating, u->max_depth);
  len += snprintf(REST, "\n");
  len += snprintf(REST,
                  "solver health: %ld CG iterations (%.1f per solve), %ld line-search evaluations, %ld indefinite CG "
                  "exits, %ld earlier CG iterates, %ld -dx and %ld -grad fallbacks, %ld clamps, %ld CHOLMOD "
                  "fallbacks, %ld steps converged at the rounding floor of E; peak memory %.1f MiB\n",
                  T->cg, T->iterations ? (double)T->cg / T->iterations : 0.0, T->ls, T->indefinite, T->downhill,
                  T->fb_dx, T->fb_grad, T->clamps, T->chol_fb, T->floor, u->peak_mib);
  if (u->partial == BS_SUMMARY_RUNNING)
    len += snprintf(REST, "partial: %d of %d frames (the run has not finished, or was killed)\n", u->frames,
                    u->frames_total);
  if (u->partial == BS_SUMMARY_INTERRUPTED)
    len += snprintf(REST, "partial: %d of %d frames (interrupted; %s)\n", u->frames, u->frames_total,
                    u->no_resume ? "this backend writes no checkpoint to continue from"
                                 : "bigstep run --resume continues it");
#undef REST
  return len;
}

int bs_summary_read(const char *dir, bs_summary *out, bs_error *err) {
  memset(out, 0, sizeof *out);
  out->s_per_frame = out->solves_per_step = out->peak_mib = NAN;
  char p[BS_MAX_PATH + 64];
  snprintf(p, sizeof p, "%s/summary.txt", dir);
  FILE *f = fopen(p, "r");
  if (!f) return bs_error_set(err, BS_EIO, "cannot open '%s'", p);
  char line[4096];
  int got = 0, ln = 0;
  while (fgets(line, sizeof line, f)) {
    ln++;
    if (ln == 2 && sscanf(line, "%31s %d %lf %ld %lf %ld", out->method, &out->steps_per_frame, &out->s_per_frame,
                          &out->dofs, &out->solves_per_step, &out->failed) >= 3)
      got = 1;
    const char *pk = strstr(line, "peak memory ");
    if (pk) out->peak_mib = atof(pk + 12);
    if (!strncmp(line, "partial: ", 9) && sscanf(line + 9, "%d of %d", &out->frames, &out->frames_total) == 2)
      out->partial = strstr(line, "(interrupted") ? BS_SUMMARY_INTERRUPTED : BS_SUMMARY_RUNNING;
  }
  fclose(f);
  return got ? 0 : bs_error_set(err, BS_EINPUT, "'%s': no summary row (method, steps, s/frame, ...)", p);
}
