/* sim_step.c — stepping a simulation: one frame and the static solve (the
 * frame loop of bs_frame_loop.h, shared with the petsc backend), a whole run
 * with a callback per frame, and the run's totals. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bs_frame_loop.h"
#include "sim_internal.h"

void bs_frame_sums(int frame, double time, int n, const bs_sim_step *steps, bs_frame_stats *fs) {
  memset(fs, 0, sizeof *fs);
  fs->frame = frame;
  fs->time = time;
  fs->n_steps = n;
  fs->steps = steps;
  for (int k = 0; k < n; k++) {
    const bs_step_stats *st = &steps[k].st;
    fs->iterations += st->min.iterations;
    fs->cg_iterations += st->min.cg_iterations;
    fs->failed += st->failed;
    fs->seconds += st->seconds;
    if (st->min.grad_norm > fs->grad_max) fs->grad_max = st->min.grad_norm;
  }
}

static void frame_sums(const bs_sim *s, int n, bs_frame_stats *fs) { bs_frame_sums(s->frame, s->time, n, s->steps, fs); }

/* The frame loop (bs_frame_loop.h) over s. */
static bs_frame_loop loop_of(bs_sim *s) {
  return (bs_frame_loop){s->scene, s->integrator, s->x, s->v, &s->frame, &s->time, s->steps, &s->substep};
}

int bs_sim_advance_frame(bs_sim *s, bs_frame_stats *fs, bs_error *err) {
  const bs_frame_loop L = loop_of(s);
  return bs_frame_advance(&L, NULL, NULL, fs, err);
}

int bs_sim_take_step(bs_sim *s, int *frame_done, bs_frame_stats *fs, bs_error *err) {
  const bs_frame_loop L = loop_of(s);
  bs_frame_stats local;
  return bs_frame_step(&L, frame_done, fs ? fs : &local, err);
}

int bs_sim_restore(bs_sim *s, int frame, const double *x, const double *v, bs_error *err) {
  const bs_scene *sc = s->scene;
  const size_t n3 = 3 * (size_t)s->mesh->n_vertices;
  if (sc->mode != BS_MODE_DYNAMIC)
    return bs_error_set(err, BS_EINPUT, "%s: a static scene has no frame to restore", sc->path);
  if (frame < 0 || frame > sc->frames)
    return bs_error_set(err, BS_EINPUT, "%s: frame %d is outside the scene's 0..%d", sc->path, frame, sc->frames);
  for (size_t i = 0; i < n3; i++)
    if (!isfinite(x[i]) || !isfinite(v[i]))
      return bs_error_set(err, BS_EINPUT, "%s: the state to restore is not finite at vertex %zu", sc->path, i / 3);
  memcpy(s->x, x, sizeof(double) * n3);
  memcpy(s->v, v, sizeof(double) * n3);
  s->frame = frame;
  s->substep = 0;
  s->time = frame / sc->fps;
  return 0;
}

int bs_sim_statics(bs_sim *s, bs_frame_stats *fs, bs_error *err) {
  const bs_frame_loop L = loop_of(s);
  return bs_frame_statics(&L, NULL, fs, err);
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
    T->floor += st->min.reason == BS_MIN_FLOOR;
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
  const bs_sim_run_opts o = {.on_frame = on_frame, .ctx = ctx};
  return bs_sim_run_with(s, &o, totals, err);
}

/* The frames from s->frame to the scene's last; snap: bs_frame_advance's. */
static int run_frames(bs_sim *s, const bs_sim_run_opts *o, bs_frame_snap *snap, bs_run_totals *totals, bs_error *err) {
  const bs_frame_loop L = loop_of(s);
  bs_frame_stats fs;
  while (s->frame < s->scene->frames) {
    int st = bs_frame_advance(&L, o->stop, snap, &fs, err);
    if (st) return st;
    bs_run_totals_add(totals, &fs);
    if (o->on_frame && (st = o->on_frame(s, &fs, o->ctx, err))) return st;
  }
  return 0;
}

int bs_sim_run_with(bs_sim *s, const bs_sim_run_opts *o, bs_run_totals *totals, bs_error *err) {
  const bs_scene *sc = s->scene;
  const bs_frame_loop L = loop_of(s);
  bs_frame_stats fs;
  bs_run_totals local;
  if (!totals) totals = &local;
  if (!o->resume || totals == &local) memset(totals, 0, sizeof *totals);
  int st = 0;
  if (!o->resume) {
    frame_sums(s, 0, &fs);
    if (o->on_frame && (st = o->on_frame(s, &fs, o->ctx, err))) return st;
  }
  if (sc->mode == BS_MODE_STATIC && o->resume)
    return bs_error_set(err, BS_EINPUT, "%s: a static scene cannot be continued", sc->path);
  if (o->stop && *o->stop) return BS_SIM_STOPPED;
  bs_frame_snap snap = {0};
  if (o->stop && (st = bs_frame_snap_alloc(&L, &snap, err))) return st;
  bs_integrator_set_stop(s->integrator, o->stop);
  if (sc->mode == BS_MODE_STATIC) {
    st = bs_frame_statics(&L, snap.xv ? &snap : NULL, &fs, err);
    if (!st) bs_run_totals_add(totals, &fs);
    if (!st && o->on_frame) st = o->on_frame(s, &fs, o->ctx, err);
  } else {
    st = run_frames(s, o, snap.xv ? &snap : NULL, totals, err);
  }
  bs_integrator_set_stop(s->integrator, NULL);
  bs_frame_snap_free(&snap);
  return st;
}
