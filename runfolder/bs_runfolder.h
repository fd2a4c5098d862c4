/* bs_runfolder.h — a run's output folder: the one home of each file format,
 * for writing and for reading back.
 *
 * A run folder holds (all optional but frames.csv):
 *   frames.csv   one row per frame (frame 0 the initial state): time,
 *                energies (J), inverted tets, min det F, Newton and CG
 *                iterations, failed steps, solver seconds, vertices inside
 *                obstacles and their depth, intersecting surface triangle
 *                pairs (columns: BS_FRAMES_CSV_HEADER);
 *   stats.csv    one row per time step (BS_STATS_CSV_HEADER);
 *   state.bin    x and v of every frame, little-endian doubles:
 *                header "BSST" (4 bytes), uint32 version (2), int32
 *                n_vertices, int32 0; then per frame: time, x (3n), v (3n).
 *                Version 1 ("BSST1\0\0\0", int32 n, int32 0) is read too;
 *   summary.txt  the summary in the columns of the paper's Figure 11
 *                (bs_summary_format), read back by bs_summary_read: written
 *                after every frame, of the frames so far and marked partial
 *                (a last line "partial: N of M frames (...)"), and at the end
 *                by bs_runfolder_finish with the caller's text;
 *   frame_NNNNN.vtu and frames.pvd  the frames for ParaView (mesh/ writes
 *                the VTU and PVD files); frames.pvd is rewritten after every
 *                VTU frame; a distributed run's frames are frame_NNNNN.pvtu
 *                over pieces frame_NNNNN_pRRRR.vtu (bs_doutput.h);
 *                obstacle_K[_NNNNN].vtu|vti and obstacles_K.pvd the
 *                obstacles (bs_obstacle_output.h);
 *   scene.json   the resolved scene (bs_scene_write_json: every key, the
 *                defaults filled in, absolute paths), which loads again;
 *   run.txt      the run's record: "version: bigstep X.Y.Z", "command: ...",
 *                "cwd: ...", "started: ISO 8601 UTC", and a line "resumed:
 *                ISO 8601 UTC at frame K: COMMAND" per continuation;
 *   checkpoint.bin  the state the run continues from (see below);
 *   .bigstep.lock   the folder's lock (BS_RUNFOLDER_LOCK; not a run file).
 *
 * Consistency: every file whose content is replaced (the VTU and VTI frames,
 * the PVD collections, summary.txt, scene.json, run.txt) is written to
 * NAME.tmp in the folder and renamed over NAME; the appended files
 * (frames.csv, stats.csv, state.bin, qoi.csv) are flushed after every frame.
 * After every frame, then, the folder is consistent: the rows of every frame
 * so far, frames.pvd listing exactly the complete VTU files, a partial
 * summary. A kill leaves at most a NAME.tmp (a run file, removed with the
 * run's files) and a last row or state record cut short (bs_state_open skips
 * a partial record). Every write is checked: a failure is BS_EIO naming the
 * file and the OS reason (strerror).
 *
 * Writing: bs_runfolder_open makes the folder, takes its lock (one run per
 * folder: a second run into a folder in use is refused at once, naming the
 * folder and the holder's pid; see bs_runfolder_lock), refuses it when it holds an
 * earlier run (any file named above; BS_EINPUT naming the folder and a file)
 * unless opts->replace, in which case those files (and only those) are
 * removed first, writes scene.json and run.txt and opens the files the scene's output
 * section asks for; bs_runfolder_frame (a bs_frame_fn for bs_sim_run) writes
 * a frame's rows, state and VTU; bs_runfolder_finish writes summary.txt;
 * bs_runfolder_destroy closes what is open (also after an error). Rows are
 * flushed after every frame.
 *
 * Ownership: the writer owns its open files; readers return tables and
 * readers that the caller frees with the matching free/close function.
 * Status: 0, BS_EIO (a file that cannot be opened, read or written: the
 * message names it), BS_EINPUT (a file that is not in the format: the
 * message says what is wrong), BS_ENOMEM.
 */
#ifndef BS_RUNFOLDER_H
#define BS_RUNFOLDER_H

#include <stdint.h>
#include <stdio.h>

#include "bs_base.h"
#include "bs_sim.h"

#ifdef __cplusplus
extern "C" {
#endif

#define BS_FRAMES_CSV_HEADER                                                                            \
  "frame,time,kinetic,elastic,gravity,total,inverted,min_detF,newton,cg,failed,seconds,penetrating,max_depth," \
  "self_intersections,contact_min_distance,contact_pairs,ccd_limited,kappa,obstacle_min_distance"
#define BS_STATS_CSV_HEADER                                                                             \
  "frame,step,time,guess,iterations,cg_iterations,ls_evaluations,indefinite,fallback_neg_dx,"                \
  "fallback_neg_grad,clamps,cholmod_fallbacks,alpha_min,alpha_max,grad_norm,E,reason,inverted,"             \
  "t_eval,t_assembly,t_linear,t_line_search,seconds"
#define BS_STATE_VERSION 2

/* One frames.csv row (BS_FRAMES_CSV_HEADER's columns, newline ended) of
 * frame fs at time (s) with the state's measures m, into buf (512 bytes
 * hold any row); returns snprintf's length. */
int bs_frames_csv_row(char *buf, size_t n, double time, const bs_frame_stats *fs, const bs_sim_measures *m);

/* ---- writing ------------------------------------------------------------ */

typedef struct bs_runfolder bs_runfolder;
typedef struct bs_summary bs_summary;

typedef struct bs_runfolder_opts {
  int replace;              /* 1: remove an earlier run's files; 0: refuse the folder */
  const char *command_line; /* for run.txt; NULL: "(library call)"                  */
} bs_runfolder_opts;

/* What the folder's shared files need of a run, whatever its backend. */
typedef struct bs_runfolder_run {
  const bs_scene *scene; /* borrowed: outlives the writer                       */
  long dofs;             /* the summary's                                       */
  int obstacles;         /* the run has obstacles: the summary's penetration    */
} bs_runfolder_run;

/* Makes dir (and its parents), takes its lock, checks it (see the top),
 * writes run.txt and scene.json and opens frames.csv, stats.csv (scene
 * output.stats), state.bin (output.states) and qoi.csv for the simulation s.
 * opts NULL: all zero. BS_EINPUT for a folder in use or holding an earlier
 * run, or a negative output.checkpoint_every. */
int bs_runfolder_open(const char *dir, const bs_sim *s, const bs_runfolder_opts *opts, bs_runfolder **out,
                      bs_error *err);

/* The files of a run folder that every backend writes alike: bs_runfolder_open
 * less what it makes from a bs_sim (state.bin, qoi.csv, the VTU frames, the
 * obstacles' files): the lock, the check of the folder, run.txt, scene.json,
 * frames.csv and stats.csv (output.stats). A backend that is not bs_sim (the
 * petsc backend, bs_doutput.h) writes through it: state.bin opened with
 * bs_runfolder_state_open; after each frame bs_runfolder_rows,
 * bs_runfolder_state, its own frame files (and the obstacles',
 * bs_obstacle_output_create_for) listed by bs_runfolder_add_frame_file, then
 * bs_runfolder_frame_done; at the end bs_runfolder_finish. */
int bs_runfolder_open_run(const char *dir, const bs_runfolder_run *run, const bs_runfolder_opts *opts,
                          bs_runfolder **out, bs_error *err);

/* bs_runfolder_open with opts NULL (an earlier run is refused). */
int bs_runfolder_create(const char *dir, const bs_sim *s, bs_runfolder **out, bs_error *err);

/* Whether a file name is one a run folder holds (the list at the top). */
int bs_runfolder_is_run_file(const char *name);

/* Refuses dir when it holds a run's files (BS_EINPUT), or with replace
 * removes them (*n_removed: how many; may be NULL). A missing dir is fine. */
int bs_runfolder_prepare(const char *dir, int replace, int *n_removed, bs_error *err);

/* The lock file of a run folder (not a run file: it stays, empty, after the run). */
#define BS_RUNFOLDER_LOCK ".bigstep.lock"

/* Takes dir's lock: dir/.bigstep.lock, created if missing, flock'ed
 * exclusively without waiting, holding this process's pid; *fd is the open
 * descriptor that holds the lock until bs_runfolder_unlock (or the process's
 * end: a killed run leaves no stale lock). BS_EINPUT naming the folder and
 * the holder's pid when another process holds it; BS_EIO when the file cannot
 * be made. bs_runfolder_open takes it first, for the whole run. */
int bs_runfolder_lock(const char *dir, int *fd, bs_error *err);
void bs_runfolder_unlock(int *fd);

/* Writes dir/run.txt (see the top). */
int bs_runfolder_write_record(const char *dir, const char *command_line, bs_error *err);

/* Writes frame fs of s: its stats.csv rows, its frames.csv row, its state,
 * its qoi.csv row and, every output.vtu_every frames, frame_NNNNN.vtu (with
 * the obstacles and frames.pvd); then summary.txt of the frames so far and,
 * when due (output.checkpoint_every, frame 0, the last frame), checkpoint.bin.
 * ctx is the bs_runfolder (so that it can be handed to bs_sim_run). */
int bs_runfolder_frame(const bs_sim *s, const bs_frame_stats *fs, void *ctx, bs_error *err);

/* The same with the frame's measures given (m: bs_sim_measure of the current
 * state, with intersections), for a caller that measures the frame anyway. */
int bs_runfolder_write(bs_runfolder *rf, const bs_sim *s, const bs_frame_stats *fs, const bs_sim_measures *m,
                       bs_error *err);

/* A frame's rows: stats.csv's (fs's steps; when open) and frames.csv's (the
 * state at time with the measures m), flushed. */
int bs_runfolder_rows(bs_runfolder *rf, double time, const bs_frame_stats *fs, const bs_sim_measures *m,
                      bs_error *err);

/* state.bin (output.states) of a backend that is not bs_sim: opened with its
 * header for n_vertices (after bs_runfolder_open_run); bs_runfolder_state
 * appends a frame's record (x, v: 3 n_vertices each, in the serial run's
 * vertex order), flushed; nothing (0) while state.bin is not open. */
int bs_runfolder_state_open(bs_runfolder *rf, int32_t n_vertices, bs_error *err);
int bs_runfolder_state(bs_runfolder *rf, double time, const double *x, const double *v, bs_error *err);

/* A frame file (name: in the folder, e.g. "frame_00006.vtu") of the state at
 * time t, complete on disk: listed in frames.pvd, which is rewritten. */
int bs_runfolder_add_frame_file(bs_runfolder *rf, const char *name, double t, bs_error *err);

/* After a frame's other files: fs added to the writer's totals and summary.txt
 * of the frames so far (frames done: as bs_summary_init's; m: the state's
 * measures), marked partial. */
int bs_runfolder_frame_done(bs_runfolder *rf, const bs_frame_stats *fs, int frames, const bs_sim_measures *m,
                            bs_error *err);

/* The summary of the run written so far (bs_summary_make_run with the run's
 * scene, dofs and obstacles and the writer's wall seconds). */
void bs_runfolder_summary(const bs_runfolder *rf, int frames, const bs_run_totals *T, const bs_sim_measures *m,
                          bs_summary *out);

/* Writes checkpoint.bin of s now (as after a frame when output.checkpoint_every
 * says so): for a run stopped on request. A static scene: nothing, 0. */
int bs_runfolder_checkpoint(bs_runfolder *rf, const bs_sim *s, bs_error *err);

/* Wall seconds of the run so far (a resumed run's earlier part included). */
double bs_runfolder_wall(const bs_runfolder *rf);

/* Continues the run in dir (bigstep run --resume) for the simulation s, made
 * from the same scene: takes the folder's lock; refuses (BS_EINPUT, naming
 * the file and the first difference) a scene whose resolved content, less
 * output.dir and description, is not that of dir/scene.json, a static scene,
 * and one that no checkpoint repeats bit for bit (see checkpoint.bin); reads
 * the checkpoint (bs_checkpoint_read: every check) and puts s at its frame
 * (bs_sim_restore); cuts frames.csv, stats.csv, qoi.csv and state.bin after
 * the checkpoint's frame (BS_EINPUT when one holds fewer rows than that) and
 * removes the later VTU and obstacle frames and any NAME.tmp; opens those
 * files at their end, rewrites the PVD collections of the frames kept, adds
 * a "resumed:" line to run.txt. *totals gets the run's totals up to the
 * checkpoint, for bs_sim_run_with (opts.resume). opts: command_line only. */
int bs_runfolder_resume(const char *dir, bs_sim *s, const bs_runfolder_opts *opts, bs_runfolder **out,
                        bs_run_totals *totals, bs_error *err);

/* Writes summary.txt (when summary is not NULL) and closes the appended files
 * (checked: BS_EIO naming one that cannot be written). */
int bs_runfolder_finish(bs_runfolder *rf, const char *summary, bs_error *err);

void bs_runfolder_destroy(bs_runfolder **rf);

/* ---- the summary ---------------------------------------------------------- */

/* Whether the summary is of a whole run: complete; running (written after
 * every frame; left so when the run was killed); interrupted (stopped on a
 * request, e.g. Ctrl-C: bigstep run --resume continues it). */
typedef enum { BS_SUMMARY_COMPLETE = 0, BS_SUMMARY_RUNNING, BS_SUMMARY_INTERRUPTED } bs_summary_state;

struct bs_summary {
  char method[32];
  bs_summary_state partial;  /* not complete: a last line "partial: N of M frames (...)" */
  int no_resume;             /* interrupted, by a run that cannot be continued (petsc)  */
  int frames, frames_total;  /* frames done (statics: 1 once solved), scene's   */
  int steps_per_frame;
  double s_per_frame;        /* wall seconds per frame done (NaN: none done)   */
  long dofs;
  double solves_per_step;    /* Newton iterations per step (NaN: no step)       */
  long failed;               /* steps that did not converge                     */
  double max_grad;           /* largest final ||grad E|| (N)                    */
  int32_t inverted;          /* at the last frame                               */
  int64_t self_intersections;/* at the last frame (BS_SIM_SELF_CAP: at least; <0: not computed) */
  int obstacles;             /* 1: the penetration figures apply                */
  int32_t penetrating;
  double max_depth;
  bs_run_totals totals;      /* the solver health counts                        */
  double peak_mib;           /* peak resident memory (MiB)                      */
};

/* Fills a summary from the run so far: totals, wall seconds, the sim's
 * current state (measured here: bs_sim_measure with intersections); partial
 * is BS_SUMMARY_RUNNING when s->frame is short of the scene's frames (the
 * caller may set BS_SUMMARY_INTERRUPTED). */
void bs_summary_make(const bs_sim *s, const bs_run_totals *T, double wall_seconds, bs_summary *out);

/* The fields every backend's summary shares: the scene's method, steps per
 * frame and frame count; frames done (statics: 0 or 1); s/frame (NaN when no
 * frame is done) and solves/step (NaN when no step is) from the wall seconds
 * and the totals; partial RUNNING when frames < the scene's; the peak memory
 * of this process. The state's figures (inverted, ...) are left 0. */
void bs_summary_init(const bs_scene *sc, int frames, long dofs, const bs_run_totals *T, double wall_seconds,
                     bs_summary *out);

/* bs_summary_init with the state's figures from its measures m (obstacles:
 * the penetration figures apply), for any backend. */
void bs_summary_make_run(const bs_scene *sc, int frames, long dofs, int obstacles, const bs_run_totals *T,
                         double wall_seconds, const bs_sim_measures *m, bs_summary *out);

/* The same with the current state's measures given. */
void bs_summary_make_measured(const bs_sim *s, const bs_run_totals *T, double wall_seconds, const bs_sim_measures *m,
                              bs_summary *out);

/* The summary as text (four lines, the first a header, and the partial line
 * when not complete); returns the length. */
int bs_summary_format(const bs_summary *sum, char *buf, size_t n);

/* Reads the summary row (method, steps_per_frame, s_per_frame and, when
 * present, dofs, solves_per_step, failed), peak_mib (NAN when absent) and the
 * partial line (partial, frames, frames_total; 0 when absent) back from
 * dir/summary.txt. BS_EINPUT when the row has not its first three. */
int bs_summary_read(const char *dir, bs_summary *out, bs_error *err);

/* ---- checkpoint.bin ---------------------------------------------------------
 * The state a run continues from (bigstep run --resume; bs_runfolder_resume):
 * written after a frame's other files every output.checkpoint_every frames,
 * at frame 0 and the last frame, and when a run stops on request
 * (bs_runfolder_checkpoint), through checkpoint.bin.tmp and a rename, so the
 * file always holds one whole checkpoint. Native (little-endian) layout,
 * version BS_CHECKPOINT_VERSION:
 *   "BSCK", uint32 version, int32 n_vertices, int32 frame, double time
 *   (= frame / fps), uint64 scene hash (FNV-1a of the resolved scene without
 *   output.dir and description), double wall seconds of the run so far,
 *   int32 the scene's frames, int32 0 (48 bytes);
 *   the run's totals so far: 12 int64 (steps, failed, iterations, cg, ls,
 *   indefinite, fb_dx, fb_grad, clamps, chol_fb, downhill, floor), 2 doubles
 *   (seconds, max_grad), 2 int32 (first failed frame and step), the first
 *   failure's reason (256 bytes); the minimizer's carry (bs_min_carry: int64
 *   full, double eta); the previous-step guess's state (bs_previous_step:
 *   int64 have, double dt, uint64 mark); the time integrator's history
 *   (bs_step_history: int64 solver.integrator, int64 have, double dt,
 *   uint64 mark; since version 4);
 *   x (3n doubles), v (3n doubles), the previous step's displacement d (3n
 *   doubles, zeros when have is 0), the integrator's history h
 *   (bs_integrator_history_doubles: 6n BDF2 xⁿ⁻¹ and vⁿ⁻¹, 3n Newmark aⁿ,
 *   none for backward Euler; zeros when have is 0; since version 4); a
 *   uint64 FNV-1a of every byte before. Version 3 (without the history's
 *   fields) is still read: a backward Euler run continues from it as from
 *   version 4.
 * x, v, d and the time are everything the next step reads: the lagged Rayleigh
 * damping, the initial guesses and x̂ are made from xⁿ, vⁿ; scripted
 * vertices and obstacles move as functions of time; the obstacles' active
 * sets start empty every step; the self-collision caches (the last detection,
 * search hints) only spare work, and the minimizer starts every solve afresh
 * but for its carry (cg_forcing adaptive), which the checkpoint holds; with
 * friction the previous-step guess (bs_step.h) starts from d; BDF2 and
 * Newmark from their history.
 * One exception: solver.linear "amg" with solver.amg_matrix "current" builds
 * its preconditioner at an earlier iterate, which no checkpoint holds:
 * bs_runfolder_resume refuses such a scene. */
#define BS_CHECKPOINT_VERSION 4

typedef struct bs_checkpoint {
  int frame;
  double time, wall_seconds;
  bs_run_totals totals;
  bs_min_carry carry;        /* the minimizer's state between solves (bs_minimize.h) */
  bs_previous_step prev;     /* the previous-step guess's (prev.d: 3n, in x's allocation) */
  bs_step_history hist;      /* the integrator's (hist.h in x's allocation; have 0 from version 3) */
  int version;               /* of the file: 3 or BS_CHECKPOINT_VERSION */
  double *x, *v;             /* 3n each (one allocation, freed by bs_checkpoint_free) */
} bs_checkpoint;

/* Writes dir/checkpoint.bin of s at its current frame. */
int bs_checkpoint_write(const char *dir, const bs_sim *s, const bs_run_totals *T, double wall_seconds,
                        uint64_t scene_hash, bs_error *err);

/* Reads and checks dir/checkpoint.bin for the simulation s of the scene with
 * this hash: BS_EIO when missing, BS_EINPUT (naming the file and what is
 * wrong) for another magic or version, a vertex count or scene hash not s's,
 * a size not the one of its counts (truncated), a bad checksum, a frame
 * outside the scene or at another time, non-finite values. */
int bs_checkpoint_read(const char *dir, const bs_sim *s, uint64_t scene_hash, bs_checkpoint *ck, bs_error *err);
void bs_checkpoint_free(bs_checkpoint *ck);

/* ---- reading frames.csv --------------------------------------------------- */

typedef struct bs_frames_table {
  int n;                     /* rows (frames, frame 0 included)                */
  double *time, *kinetic, *total, *max_depth; /* per row                       */
  int has_depth;             /* the file has the max_depth column              */
  long newton, cg, failed;   /* sums over the rows                             */
  int inverted_max;
  double seconds;            /* summed solver seconds                          */
} bs_frames_table;

int bs_frames_csv_read(const char *dir, bs_frames_table *t, bs_error *err);
void bs_frames_table_free(bs_frames_table *t);

/* Lines of dir/frames.csv (the header included; a last line without its
 * newline counts); -1 when the file is missing. */
int bs_frames_csv_lines(const char *dir);

/* ---- reading qoi.csv ------------------------------------------------------- */

/* qoi.csv: the scene's quantities of interest, one row per frame written
 * (frame 0 included): header "frame,time,NAME1,NAME2,...", rows
 * "%d,%.17g,%.17g,..." (the values in the scene's order; units those of the
 * quantity: m, m/s, N, J). */
typedef struct bs_qoi_table {
  int n_qoi, n_rows;
  char **names;              /* n_qoi                                          */
  double *time;              /* n_rows (s)                                     */
  double *values;            /* n_rows * n_qoi, row-major                      */
} bs_qoi_table;

/* Reads dir/qoi.csv: BS_EIO when it cannot be opened, BS_EINPUT (naming the
 * line) for a bad header, a row without 2 + n_qoi finite numbers. */
int bs_qoi_csv_read(const char *dir, bs_qoi_table *t, bs_error *err);
void bs_qoi_table_free(bs_qoi_table *t);
/* The column of a name, or -1. */
int bs_qoi_table_column(const bs_qoi_table *t, const char *name);

/* ---- reading state.bin ---------------------------------------------------- */

typedef struct bs_state_reader {
  FILE *f;
  int version;
  int32_t n;                 /* vertices                                       */
  long frames;               /* whole frame records in the file                */
  double time;               /* of the current frame                           */
  double *x, *v;             /* 3n each: the current frame (into buf)          */
  double *buf;
} bs_state_reader;

/* Opens dir/state.bin and checks its header and size. r->frames counts the
 * whole frame records: a run interrupted during a write leaves a partial last
 * record, which is not read; a file with a header and no frame (a run that
 * wrote none) has 0 frames. */
int bs_state_open(const char *dir, bs_state_reader *r, bs_error *err);
/* The next frame into r->time, r->x, r->v: 0, or 1 at the end of the file. */
int bs_state_next(bs_state_reader *r);
void bs_state_close(bs_state_reader *r);

#ifdef __cplusplus
}
#endif
#endif
