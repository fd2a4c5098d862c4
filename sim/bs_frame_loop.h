/* bs_frame_loop.h — the frame loop of a simulation on any backend of the
 * integrator (bs_step.h, bs_step_backend.h): one frame of steps_per_frame
 * steps, the static solve, and the snapshot that undoes a frame (or static
 * solve) cut short by a stop request. bs_sim (sim_step.c) and bs_dsim
 * (petsc/dsim_step.c) both step through it.
 *
 * Time is advanced here only: step k of frame f ends at (f - 1)/fps +
 * (k + 1) dt, and the frame at exactly f/fps. A stop request (*stop, read
 * over the backend's processes before every step: bs_integrator_any) undoes
 * the frame from the snapshot (x, v, time, frame, the minimizer's carry and
 * the previous-step guess, the time integrator's history, bit for bit) and
 * returns BS_SIM_STOPPED.
 *
 * Ownership: the loop borrows everything it points at; a snapshot owns xv
 * (bs_frame_snap_alloc, bs_frame_snap_free). Collective on the backend's
 * processes. Status: 0, BS_SIM_STOPPED, or the integrator's error (prefixed
 * "frame F step K" / "static solve"); BS_EINPUT for a frame of a static
 * scene; BS_ENOMEM (the snapshot).
 */
#ifndef BS_FRAME_LOOP_H
#define BS_FRAME_LOOP_H

#include "bs_scene.h"
#include "bs_sim.h"
#include "bs_step.h"

typedef struct bs_frame_loop {
  const bs_scene *scene;
  bs_integrator *integ;
  double *x, *v;       /* the state: the integrator's vectors              */
  int *frame;          /* frames completed                                 */
  double *time;        /* s                                                */
  bs_sim_step *steps;  /* steps_per_frame records of the last frame       */
  int *substep;        /* steps of frame *frame + 1 already taken (between  */
                       /* frames 0); NULL: frames are taken whole only      */
} bs_frame_loop;

typedef struct bs_frame_snap {
  double *xv; /* 9 per vertex: x, v and the previous step's displacement,
                 then the integrator's history (bs_integrator_history_doubles) */
  double time;
  int frame, substep;
  bs_min_carry carry;
  bs_previous_step prev;
  bs_step_history hist; /* hist.h points into xv */
} bs_frame_snap;

int bs_frame_snap_alloc(const bs_frame_loop *L, bs_frame_snap *sn, bs_error *err);
void bs_frame_snap_free(bs_frame_snap *sn);
void bs_frame_snap_take(const bs_frame_loop *L, bs_frame_snap *sn);
/* Puts the snapshot back and returns BS_SIM_STOPPED. */
int bs_frame_snap_undo(const bs_frame_loop *L, const bs_frame_snap *sn);

/* One frame (the rest of it, after steps taken with bs_frame_step); stop
 * (may be NULL) and sn (NULL when no stop can come) as at the top. fs: the
 * frame's sums (fs->steps points into L->steps). */
int bs_frame_advance(const bs_frame_loop *L, volatile sig_atomic_t *stop, bs_frame_snap *sn, bs_frame_stats *fs,
                     bs_error *err);

/* One step: step *substep of frame *frame + 1 (L->substep must be set).
 * After the frame's last step the frame is complete as bs_frame_advance
 * completes it: *done = 1 and *fs its sums; otherwise *done = 0 and fs is
 * untouched. k steps one at a time give bs_frame_advance's state bit for
 * bit. */
int bs_frame_step(const bs_frame_loop *L, int *done, bs_frame_stats *fs, bs_error *err);

/* The static solve (load_steps from the scene) as frame 1; with sn, a solve
 * stopped by the integrator's stop flag is undone (BS_SIM_STOPPED). */
int bs_frame_statics(const bs_frame_loop *L, bs_frame_snap *sn, bs_frame_stats *fs, bs_error *err);

#endif
