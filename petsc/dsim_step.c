/* dsim_step.c — a dsim's frames and statics (bs_dsim.h), as bs_sim's
 * (sim/sim_step.c), with the stop request: a frame or static solve cut
 * short is undone from the snapshot taken at its start. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bs_dist.h"
#include "bs_dsim.h"

int bs_dsim_set_stop(bs_dsim *s, volatile sig_atomic_t *stop, bs_error *err) {
  if (stop && !s->snap) {
    const int32_t n = s->mesh->n_vertices;
    if (!(s->snap = bs_calloc(6 * (size_t)n + 6, sizeof *s->snap, "the frame snapshot", err))) return BS_ENOMEM;
  }
  s->stop = stop;
  bs_dintegrator_set_stop(s->integrator, stop);
  return BS_OK;
}

/* Whether a stop was asked on any rank (collective when s has a flag). */
static int stop_asked(bs_dsim *s, int *asked, bs_error *err) {
  *asked = 0;
  if (!s->stop) return BS_OK;
  int64_t any = *s->stop != 0;
  int rc = bs_dist_sum_i64(&any, 1, err);
  *asked = any > 0;
  return rc;
}

static void snap_take(bs_dsim *s) {
  const size_t n3 = 3 * (size_t)s->mesh->n_vertices;
  memcpy(s->snap, s->x, n3 * sizeof(double));
  memcpy(s->snap + n3, s->v, n3 * sizeof(double));
  s->snap_time = s->time;
  s->snap_frame = s->frame;
  bs_dintegrator_get_carry(s->integrator, &s->snap_carry);
}

/* Puts the snapshot back and returns BS_SIM_STOPPED. */
static int snap_undo(bs_dsim *s) {
  const size_t n3 = 3 * (size_t)s->mesh->n_vertices;
  memcpy(s->x, s->snap, n3 * sizeof(double));
  memcpy(s->v, s->snap + n3, n3 * sizeof(double));
  s->time = s->snap_time;
  s->frame = s->snap_frame;
  bs_dintegrator_set_carry(s->integrator, &s->snap_carry);
  return BS_SIM_STOPPED;
}

/* The step's record, as bs_sim's: time, inverted tets, its reason's copy. */
static int record(bs_dsim *s, bs_sim_step *rec, bs_error *err) {
  int64_t inv = 0;
  int rc = bs_dsim_inverted(s, &inv, err);
  rec->time = s->time;
  rec->inverted = (int32_t)inv;
  snprintf(rec->reason, sizeof rec->reason, "%s", rec->st.min.reason_text ? rec->st.min.reason_text : "");
  rec->st.min.reason_text = rec->reason;
  return rc;
}

int bs_dsim_statics(bs_dsim *s, bs_frame_stats *fs, bs_error *err) {
  bs_sim_step *rec = &s->steps[0];
  int asked, rc = stop_asked(s, &asked, err);
  if (rc || asked) return rc ? rc : BS_SIM_STOPPED;
  if (s->stop) snap_take(s);
  rc = bs_dintegrator_static(s->integrator, 0.0, s->scene->load_steps, s->x, &rec->st, err);
  if (rc) {
    bs_error_prefix(err, "static solve");
    return rc;
  }
  if (rec->st.min.reason == BS_MIN_STOPPED && s->stop) return snap_undo(s);
  s->frame = 1;
  rc = record(s, rec, err);
  bs_frame_sums(s->frame, s->time, 1, s->steps, fs);
  return rc;
}

/* Times as bs_sim's (sim/sim_step.c): step k of frame f ends at
 * (f - 1) / fps + (k + 1) dt, the frame at f / fps. */
int bs_dsim_advance_frame(bs_dsim *s, bs_frame_stats *fs, bs_error *err) {
  const bs_scene *sc = s->scene;
  if (sc->mode != BS_MODE_DYNAMIC)
    return bs_error_set(err, BS_EINPUT, "%s: a static scene has no frames to advance", sc->path);
  const int f = s->frame + 1;
  if (s->stop) snap_take(s);
  for (int k = 0; k < sc->steps_per_frame; k++) {
    int asked, rc = stop_asked(s, &asked, err);
    if (rc) return rc;
    if (asked) return snap_undo(s);
    bs_sim_step *rec = &s->steps[k];
    rc = bs_dintegrator_step(s->integrator, s->time, sc->dt, s->x, s->v, &rec->st, err);
    if (rc) {
      bs_error_prefix(err, "frame %d step %d", f, k);
      return rc;
    }
    if (rec->st.min.reason == BS_MIN_STOPPED && s->stop) return snap_undo(s);
    s->time = (f - 1) / sc->fps + (k + 1) * sc->dt;
    if ((rc = record(s, rec, err))) return rc;
  }
  s->time = f / sc->fps;
  s->frame = f;
  bs_frame_sums(s->frame, s->time, sc->steps_per_frame, s->steps, fs);
  return BS_OK;
}
