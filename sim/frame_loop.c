/* frame_loop.c — frames, statics and the stop snapshot on any backend of the
 * integrator (bs_frame_loop.h). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bs_frame_loop.h"

int bs_frame_snap_alloc(const bs_frame_loop *L, bs_frame_snap *sn, bs_error *err) {
  memset(sn, 0, sizeof *sn);
  const size_t n = (size_t)bs_integrator_vertices(L->integ);
  sn->xv = bs_calloc(9 * n + 9 + bs_integrator_history_doubles(L->integ), sizeof(double), "the frame snapshot", err);
  return sn->xv ? 0 : BS_ENOMEM;
}

void bs_frame_snap_free(bs_frame_snap *sn) {
  free(sn->xv);
  sn->xv = NULL;
}

void bs_frame_snap_take(const bs_frame_loop *L, bs_frame_snap *sn) {
  const size_t n3 = 3 * (size_t)bs_integrator_vertices(L->integ);
  memcpy(sn->xv, L->x, sizeof(double) * n3);
  memcpy(sn->xv + n3, L->v, sizeof(double) * n3);
  sn->time = *L->time;
  sn->frame = *L->frame;
  sn->substep = L->substep ? *L->substep : 0;
  bs_integrator_get_carry(L->integ, &sn->carry);
  sn->prev.d = sn->xv + 2 * n3;
  bs_integrator_get_previous(L->integ, &sn->prev);
  sn->hist.h = sn->xv + 3 * n3;
  bs_integrator_get_history(L->integ, &sn->hist);
}

int bs_frame_snap_undo(const bs_frame_loop *L, const bs_frame_snap *sn) {
  const size_t n3 = 3 * (size_t)bs_integrator_vertices(L->integ);
  memcpy(L->x, sn->xv, sizeof(double) * n3);
  memcpy(L->v, sn->xv + n3, sizeof(double) * n3);
  *L->time = sn->time;
  *L->frame = sn->frame;
  if (L->substep) *L->substep = sn->substep;
  bs_integrator_set_carry(L->integ, &sn->carry);
  bs_integrator_set_previous(L->integ, &sn->prev);
  bs_integrator_set_history(L->integ, &sn->hist);
  return BS_SIM_STOPPED;
}

/* The step's record: its time, inverted tets and its own copy of the reason
 * (the minimizer's text is overwritten by the next solve). */
static int record(const bs_frame_loop *L, bs_sim_step *rec, bs_error *err) {
  int64_t inv = 0;
  int rc = bs_integrator_count_inverted(L->integ, L->x, &inv, err);
  rec->time = *L->time;
  rec->inverted = (int32_t)inv;
  snprintf(rec->reason, sizeof rec->reason, "%s", rec->st.min.reason_text ? rec->st.min.reason_text : "");
  rec->st.min.reason_text = rec->reason;
  return rc;
}

/* Whether a stop was asked on any process (collective when stop is set). */
static int stop_asked(const bs_frame_loop *L, volatile sig_atomic_t *stop, int *asked, bs_error *err) {
  *asked = 0;
  return stop ? bs_integrator_any(L->integ, *stop != 0, asked, err) : 0;
}

/* Step k of frame f: the integrator's step, the time at its end, its record. */
static int take_step(const bs_frame_loop *L, int f, int k, bs_error *err) {
  const bs_scene *sc = L->scene;
  bs_sim_step *rec = &L->steps[k];
  int rc = bs_integrator_step(L->integ, *L->time, sc->dt, L->x, L->v, &rec->st, err);
  if (rc) {
    bs_error_prefix(err, "frame %d step %d", f, k);
    return rc;
  }
  *L->time = (f - 1) / sc->fps + (k + 1) * sc->dt;
  return record(L, rec, err);
}

/* The frame's end after its last step: time exactly f / fps, its sums. */
static void end_frame(const bs_frame_loop *L, int f, bs_frame_stats *fs) {
  const bs_scene *sc = L->scene;
  *L->time = f / sc->fps;
  *L->frame = f;
  if (L->substep) *L->substep = 0;
  bs_frame_sums(*L->frame, *L->time, sc->steps_per_frame, L->steps, fs);
}

static int dynamic_only(const bs_frame_loop *L, bs_error *err) {
  const bs_scene *sc = L->scene;
  if (sc->mode != BS_MODE_DYNAMIC)
    return bs_error_set(err, BS_EINPUT, "%s: a static scene has no frames to advance (bs_sim_statics)", sc->path);
  return 0;
}

int bs_frame_advance(const bs_frame_loop *L, volatile sig_atomic_t *stop, bs_frame_snap *sn, bs_frame_stats *fs,
                     bs_error *err) {
  const bs_scene *sc = L->scene;
  const int f = *L->frame + 1;
  int rc = dynamic_only(L, err);
  if (rc) return rc;
  if (sn) bs_frame_snap_take(L, sn);
  for (int k = L->substep ? *L->substep : 0; k < sc->steps_per_frame; k++) {
    int asked = 0;
    if (sn && (rc = stop_asked(L, stop, &asked, err))) return rc;
    if (asked) return bs_frame_snap_undo(L, sn);
    if ((rc = take_step(L, f, k, err))) return rc;
    if (L->steps[k].st.min.reason == BS_MIN_STOPPED && sn) return bs_frame_snap_undo(L, sn);
  }
  end_frame(L, f, fs);
  return 0;
}

int bs_frame_step(const bs_frame_loop *L, int *done, bs_frame_stats *fs, bs_error *err) {
  const int f = *L->frame + 1, k = *L->substep;
  *done = 0;
  int rc = dynamic_only(L, err);
  if (rc || (rc = take_step(L, f, k, err))) return rc;
  if (k + 1 < L->scene->steps_per_frame) {
    *L->substep = k + 1;
    return 0;
  }
  end_frame(L, f, fs);
  *done = 1;
  return 0;
}

int bs_frame_statics(const bs_frame_loop *L, bs_frame_snap *sn, bs_frame_stats *fs, bs_error *err) {
  bs_sim_step *rec = &L->steps[0];
  if (sn) bs_frame_snap_take(L, sn);
  int rc = bs_integrator_static(L->integ, 0.0, L->scene->load_steps, L->x, &rec->st, err);
  if (rc) {
    bs_error_prefix(err, "static solve");
    return rc;
  }
  if (sn && rec->st.min.reason == BS_MIN_STOPPED) return bs_frame_snap_undo(L, sn);
  if ((rc = record(L, rec, err))) return rc;
  *L->frame = 1;
  bs_frame_sums(*L->frame, *L->time, 1, L->steps, fs);
  return 0;
}
