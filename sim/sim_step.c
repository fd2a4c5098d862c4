/* sim_step.c — stepping a simulation: one frame, the static solve, a whole
 * run with a callback per frame, and the run's totals. Time is advanced here
 * only: step k of frame f ends at (f - 1)/fps + (k + 1) dt, and the frame at
 * exactly f/fps. */
#include <stdio.h>
#include <string.h>

#include "sim_internal.h"

/* The frame's sums from its step records. */
static void frame_sums(const bs_sim *s, int n, bs_frame_stats *fs) {
  memset(fs, 0, sizeof *fs);
  fs->frame = s->frame;
  fs->time = s->time;
  fs->n_steps = n;
  fs->steps = s->steps;
  for (int k = 0; k < n; k++) {
    const bs_step_stats *st = &s->steps[k].st;
    fs->iterations += st->min.iterations;
    fs->cg_iterations += st->min.cg_iterations;
    fs->failed += st->failed;
    fs->seconds += st->seconds;
    if (st->min.grad_norm > fs->grad_max) fs->grad_max = st->min.grad_norm;
  }
}

/* The step's record: its time, inverted tets and its own copy of the reason
 * (the minimizer's text is overwritten by the next solve). */
static void record(const bs_sim *s, bs_sim_step *rec) {
  rec->time = s->time;
  rec->inverted = bs_fem_count_inverted(s->fem, s->x, NULL);
  snprintf(rec->reason, sizeof rec->reason, "%s", rec->st.min.reason_text ? rec->st.min.reason_text : "");
  rec->st.min.reason_text = rec->reason;
}

int bs_sim_advance_frame(bs_sim *s, bs_frame_stats *fs, bs_error *err) {
  const bs_scene *sc = s->scene;
  const int f = s->frame + 1;
  if (sc->mode != BS_MODE_DYNAMIC) return bs_error_set(err, BS_EINPUT, "%s: a static scene has no frames to advance (bs_sim_statics)", sc->path);
  for (int k = 0; k < sc->steps_per_frame; k++) {
    bs_sim_step *rec = &s->steps[k];
    int st = bs_integrator_step(s->integrator, s->time, sc->dt, s->x, s->v, &rec->st, err);
    if (st) {
      bs_error_prefix(err, "frame %d step %d", f, k);
      return st;
    }
    s->time = (f - 1) / sc->fps + (k + 1) * sc->dt;
    record(s, rec);
  }
  s->time = f / sc->fps;
  s->frame = f;
  frame_sums(s, sc->steps_per_frame, fs);
  return 0;
}

int bs_sim_statics(bs_sim *s, bs_frame_stats *fs, bs_error *err) {
  const bs_scene *sc = s->scene;
  bs_sim_step *rec = &s->steps[0];
  int st = bs_integrator_static(s->integrator, 0.0, sc->load_steps, s->x, &rec->st, err);
  if (st) {
    bs_error_prefix(err, "static solve");
    return st;
  }
  record(s, rec);
  s->frame = 1;
  frame_sums(s, 1, fs);
  return 0;
}

void bs_run_totals_add(bs_run_totals *T, const bs_frame_stats *fs) {
  for (int k = 0; k < fs->n_steps; k++) {
    const bs_step_stats *st = &fs->steps[k].st;
    if (st->failed && !T->failed) {
      T->first_fail_frame = fs->frame;
      T->first_fail_step = k;
      snprintf(T->first_fail_reason, sizeof T->first_fail_reason, "%s", st->min.reason_text ? st->min.reason_text : "?");
    }
    T->steps++;
    T->failed += st->failed;
    T->iterations += st->min.iterations;
    T->cg += st->min.cg_iterations;
    T->ls += st->min.ls_evaluations;
    T->indefinite += st->min.indefinite_exits;
    T->downhill += st->min.downhill_iterates;
    T->fb_dx += st->min.fallback_neg_dx;
    T->fb_grad += st->min.fallback_neg_grad;
    T->clamps += st->min.clamps;
    T->chol_fb += st->min.cholmod_fallbacks;
    T->seconds += st->seconds;
    if (st->min.grad_norm > T->max_grad) T->max_grad = st->min.grad_norm;
  }
}

int bs_sim_run(bs_sim *s, bs_frame_fn on_frame, void *ctx, bs_run_totals *totals, bs_error *err) {
  const bs_scene *sc = s->scene;
  bs_frame_stats fs;
  bs_run_totals local;
  if (!totals) totals = &local;
  memset(totals, 0, sizeof *totals);
  frame_sums(s, 0, &fs);
  int st = on_frame ? on_frame(s, &fs, ctx, err) : 0;
  if (st) return st;
  if (sc->mode == BS_MODE_STATIC) {
    if ((st = bs_sim_statics(s, &fs, err))) return st;
    bs_run_totals_add(totals, &fs);
    return on_frame ? on_frame(s, &fs, ctx, err) : 0;
  }
  while (s->frame < sc->frames) {
    if ((st = bs_sim_advance_frame(s, &fs, err))) return st;
    bs_run_totals_add(totals, &fs);
    if (on_frame && (st = on_frame(s, &fs, ctx, err))) return st;
  }
  return 0;
}
