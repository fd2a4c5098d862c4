/* dsim_step.c — a dsim's frames and statics (bs_dsim.h): the frame loop of
 * sim/bs_frame_loop.h (shared with bs_sim) on the dsim's integrator, with
 * the stop request: a frame or static solve cut short is undone from the
 * snapshot taken at its start. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bs_dsim.h"
#include "bs_frame_loop.h"
#include "bs_dist.h"

static bs_frame_loop loop_of(bs_dsim *s) {
  return (bs_frame_loop){s->scene, bs_dintegrator_integrator(s->integrator), s->x, s->v, &s->frame, &s->time,
                         s->steps, NULL};
}

int bs_dsim_set_stop(bs_dsim *s, volatile sig_atomic_t *stop, bs_error *err) {
  if (stop && !s->snap.xv) {
    const bs_frame_loop L = loop_of(s);
    int rc = bs_frame_snap_alloc(&L, &s->snap, err);
    if (rc) return rc;
  }
  s->stop = stop;
  bs_dintegrator_set_stop(s->integrator, stop);
  return BS_OK;
}

int bs_dsim_statics(bs_dsim *s, bs_frame_stats *fs, bs_error *err) {
  const bs_frame_loop L = loop_of(s);
  int asked = 0, rc = s->stop ? bs_integrator_any(L.integ, *s->stop != 0, &asked, err) : 0;
  if (rc || asked) return rc ? rc : BS_SIM_STOPPED;
  return bs_frame_statics(&L, s->stop ? &s->snap : NULL, fs, err);
}

int bs_dsim_advance_frame(bs_dsim *s, bs_frame_stats *fs, bs_error *err) {
  const bs_frame_loop L = loop_of(s);
  return bs_frame_advance(&L, s->stop, s->stop ? &s->snap : NULL, fs, err);
}
