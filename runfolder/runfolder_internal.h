/* runfolder_internal.h — what the run folder's files share (not installed). */
#ifndef BS_RUNFOLDER_INTERNAL_H
#define BS_RUNFOLDER_INTERNAL_H

#include <stdint.h>

#include "bs_fields.h"
#include "bs_obstacle_output.h"
#include "bs_qoi.h"
#include "bs_runfolder.h"
#include "outfile.h"

struct bs_runfolder {
  char dir[BS_MAX_PATH];
  bs_runfolder_run run;            /* the scene (borrowed), dofs, obstacles: the summary's */
  bs_outfile frames, stats, state; /* open when .f is not NULL */
  int32_t n_state;                 /* state.bin's vertices                 */
  int n_vtu, cap_vtu;              /* the VTU frames of frames.pvd */
  char **vtu_names;
  double *vtu_times;
  bs_fields *fields; /* the VTU frames' fields (buffers made once)   */
  bs_obstacle_output *obstacles; /* the obstacles beside the VTU frames */
  bs_outfile qoi_csv; /* qoi.csv, when the scene names quantities     */
  bs_qoi *qoi;
  double *qoi_values;
  bs_run_totals totals; /* of the frames written (the partial summary, checkpoints) */
  double t_open;        /* bs_seconds() at the open, less a resumed run's earlier wall time */
  int lock_fd;          /* holds the folder's lock (bs_runfolder_lock)       */
  uint64_t scene_hash;  /* of bs__scene_identity (checkpoints)               */
};

/* runfolder.c: a writer for dir with the folder made and locked and the
 * run's scene hash (BS_EINPUT for a negative output.checkpoint_every); the
 * files every backend appends to (frames.csv, stats.csv) opened (append: a
 * resumed run's, at their end; else new, with their headers); bs_sim's own
 * outputs (state.bin, the VTU fields, the obstacles, qoi.csv) opened the same
 * way; a VTU frame added to frames.pvd's list; frames.pvd. */
int bs__runfolder_begin(const char *dir, const bs_runfolder_run *run, bs_runfolder **out, bs_error *err);
int bs__runfolder_rows_open(bs_runfolder *rf, int append, bs_error *err);
int bs__runfolder_outputs(bs_runfolder *rf, const bs_sim *s, int append, bs_error *err);
/* The run description of a bs_sim (its scene, dofs, obstacles). */
bs_runfolder_run bs__runfolder_run_of(const bs_sim *s);
int bs__runfolder_add_vtu(bs_runfolder *rf, const char *name, double t, bs_error *err);
int bs__runfolder_write_pvd(const bs_runfolder *rf, bs_error *err);

/* The scene as the run folder compares it: its resolved JSON
 * (bs_scene_write_json) without output.dir and description, which may differ
 * between a run and its resumption. *text is malloc'd. */
int bs__scene_identity(const bs_scene *sc, char **text, bs_error *err);

#endif
