/* sim_step.c — stepping a simulation: one frame, the static solve, a whole
 * run with a callback per frame, and the run's totals. Time is advanced here
 * only: step k of frame f ends at (f - 1)/fps + (k + 1) dt, and the frame at
 * exactly f/fps. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

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

/* The step's record: its time, inverted tets and its own copy of the reason
 * (the minimizer's text is overwritten by the next solve). */
static void record(const bs_sim *s, bs_sim_step *rec) {
  rec->time = s->time;
  rec->inverted = bs_fem_count_inverted(s->fem, s->x, NULL);
  snprintf(rec->reason, sizeof rec->reason, "%s", rec->st.min.reason_text ? rec->st.min.reason_text : "");
  rec->st.min.reason_text = rec->reason;
}

/* The state at a frame's start (or before a static solve): x, v and the
 * previous step's displacement (9n doubles: xv, prev.d = xv + 6n), the
 * frame, the time, the minimizer's carry and the previous-step guess's. */
typedef struct frame_snap {
  double *xv, time;
  int frame;
  bs_min_carry carry;
  bs_previous_step prev;
} frame_snap;

static void snap_take(const bs_sim *s, frame_snap *sn) {
  const size_t n3 = 3 * (size_t)s->mesh->n_vertices;
  memcpy(sn->xv, s->x, sizeof(double) * n3);
  memcpy(sn->xv + n3, s->v, sizeof(double) * n3);
  sn->time = s->time;
  sn->frame = s->frame;
  bs_integrator_get_carry(s->integrator, &sn->carry);
  sn->prev.d = sn->xv + 2 * n3;
  bs_integrator_get_previous(s->integrator, &sn->prev);
}

/* Puts the snapshot back and returns BS_SIM_STOPPED. */
static int snap_undo(bs_sim *s, const frame_snap *sn) {
  const size_t n3 = 3 * (size_t)s->mesh->n_vertices;
  memcpy(s->x, sn->xv, sizeof(double) * n3);
  memcpy(s->v, sn->xv + n3, sizeof(double) * n3);
  s->time = sn->time;
  s->frame = sn->frame;
  bs_integrator_set_carry(s->integrator, &sn->carry);
  bs_integrator_set_previous(s->integrator, &sn->prev);
  return BS_SIM_STOPPED;
}

/* One frame, checking *stop (may be NULL) before every step, and through the
 * integrator's stop flag between Newton iterations; a frame cut short is
 * undone from the snapshot (sn NULL when no stop can come) and
 * BS_SIM_STOPPED returned. */
static int advance_frame(bs_sim *s, volatile sig_atomic_t *stop, frame_snap *sn, bs_frame_stats *fs, bs_error *err) {
  const bs_scene *sc = s->scene;
  const int f = s->frame + 1;
  if (sc->mode != BS_MODE_DYNAMIC) return bs_error_set(err, BS_EINPUT, "%s: a static scene has no frames to advance (bs_sim_statics)", sc->path);
  if (sn) snap_take(s, sn);
  for (int k = 0; k < sc->steps_per_frame; k++) {
    if (stop && *stop && sn) return snap_undo(s, sn);
    bs_sim_step *rec = &s->steps[k];
    int st = bs_integrator_step(s->integrator, s->time, sc->dt, s->x, s->v, &rec->st, err);
    if (st) {
      bs_error_prefix(err, "frame %d step %d", f, k);
      return st;
    }
    if (rec->st.min.reason == BS_MIN_STOPPED && sn) return snap_undo(s, sn);
    s->time = (f - 1) / sc->fps + (k + 1) * sc->dt;
    record(s, rec);
  }
  s->time = f / sc->fps;
  s->frame = f;
  frame_sums(s, sc->steps_per_frame, fs);
  return 0;
}

int bs_sim_advance_frame(bs_sim *s, bs_frame_stats *fs, bs_error *err) { return advance_frame(s, NULL, NULL, fs, err); }

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
  s->time = frame / sc->fps;
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

/* The frames from s->frame to the scene's last; snap: advance_frame's. */
static int run_frames(bs_sim *s, const bs_sim_run_opts *o, frame_snap *snap, bs_run_totals *totals, bs_error *err) {
  bs_frame_stats fs;
  while (s->frame < s->scene->frames) {
    int st = advance_frame(s, o->stop, snap, &fs, err);
    if (st) return st;
    bs_run_totals_add(totals, &fs);
    if (o->on_frame && (st = o->on_frame(s, &fs, o->ctx, err))) return st;
  }
  return 0;
}

int bs_sim_run_with(bs_sim *s, const bs_sim_run_opts *o, bs_run_totals *totals, bs_error *err) {
  const bs_scene *sc = s->scene;
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
  frame_snap snap = {NULL, 0, 0, {0, 0}, {0, 0, 0, NULL}};
  if (o->stop && !(snap.xv = bs_calloc(9 * (size_t)s->mesh->n_vertices, sizeof(double), "the frame snapshot", err)))
    return BS_ENOMEM;
  bs_integrator_set_stop(s->integrator, o->stop);
  if (sc->mode == BS_MODE_STATIC) {
    if (snap.xv) snap_take(s, &snap);
    st = bs_sim_statics(s, &fs, err);
    if (!st && snap.xv && s->steps[0].st.min.reason == BS_MIN_STOPPED) st = snap_undo(s, &snap);
    if (!st) bs_run_totals_add(totals, &fs);
    if (!st && o->on_frame) st = o->on_frame(s, &fs, o->ctx, err);
  } else {
    st = run_frames(s, o, snap.xv ? &snap : NULL, totals, err);
  }
  bs_integrator_set_stop(s->integrator, NULL);
  free(snap.xv);
  return st;
}
