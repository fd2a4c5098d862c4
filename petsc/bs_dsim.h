/* bs_dsim.h — a scene run on the petsc backend (solver.backend = "petsc"):
 * the scene's body as a distributed mesh (bs_dmesh.h), its terms on the
 * owned cells (bs_dfem.h), its scripted and fixed groups, and the
 * distributed integrator (bs_dstep.h), stepped frame by frame or solved
 * statically as bs_sim does (sim/bs_sim.h).
 *
 * What the backend runs (bs_dsim_check refuses anything else, naming the
 * key): one body; mesh "box" or a .msh file (bodies.0.mesh), refined
 * (bodies.0.refine); materials by 3-D group, every model, Rayleigh damping;
 * gravity, drag; scripted groups (fixed, velocity, keyframes); an initial
 * velocity; statics with load steps; solver.method optimization with
 * solver.linear cg, pcg or amg, solver.rtol and solver.load_rtol; analytic
 * obstacles (plane, sphere, box, cylinder, torus, moving or not) with
 * constraint collisions (collision/bs_obstacles.h on each rank's owned cells:
 * every rank that holds a vertex projects it alike, the curvature term of
 * the Hessian added by its owner) and penalty collisions (each vertex once,
 * on its owner). Refused: self_collision, postprocess collisions, friction
 * (obstacles.N.friction > 0), grid level sets (shape grid, grid_h), body
 * transforms (translate, rotate, scale), angular velocity, random or point
 * initial states, qoi, several bodies, other mesh files.
 *
 * Collective (PETSC_COMM_WORLD). Ownership: bs_dsim_create borrows the scene
 * (it must outlive the dsim) and owns everything else. State (x, v, mask)
 * is in local vectors (3 per local vertex of mesh, consistent).
 *
 * Usage (every rank, after bs_dist_init):
 *   bs_dsim *d;
 *   if (bs_dsim_create(sc, &d, &err)) ...;          // err names the key refused
 *   bs_dsim_set_stop(d, &flag, &err);               // optional: a signal handler's flag
 *   for (int f = 0; f < sc->frames; f++) {
 *     int rc = bs_dsim_advance_frame(d, &fs, &err);
 *     if (rc == BS_SIM_STOPPED) break;             // d is at the end of frame f, bit for bit
 *     if (rc) ...;                                  // an error, the same on every rank
 *   }
 *   bs_dsim_destroy(&d);
 */
#ifndef BS_DSIM_H
#define BS_DSIM_H

#include "bs_scene.h"
#include "bs_frame_loop.h"
#include "bs_sim.h"
#include "bs_dstep.h"
#include "bs_field_names.h"

#ifdef __cplusplus
extern "C" {
#endif

#define BS_DSIM_MAX_OBSTACLES 8
#define BS_DSIM_MAX_TERMS (8 + BS_DSIM_MAX_OBSTACLES)

typedef struct bs_dsim {
  const bs_scene *scene;
  bs_dmesh *mesh;
  bs_dfem *df;
  int n_terms;
  bs_term *terms[BS_DSIM_MAX_TERMS];
  bs_step_data step;
  bs_obstacles *obstacles; /* the scene's obstacles on df->fem (NULL: none)   */
  double size;          /* m: the rest mesh's bounding-box diagonal           */
  double *x, *v;        /* local vectors: the state                       */
  uint8_t *mask;        /* per local vertex: 1 free, 0 scripted           */
  int n_scripts;
  bs_sim_script *scripts; /* vertices: local vertices (the mesh's group arrays) */
  int64_t n_free;       /* free vertices over the ranks                   */
  bs_dintegrator *integrator;
  int frame;            /* frames completed                               */
  double time;          /* s                                              */
  bs_sim_step *steps;   /* steps_per_frame records of the last frame      */
  double *xm;           /* work: 3 per local-mesh vertex                  */
  volatile sig_atomic_t *stop; /* bs_dsim_set_stop's flag (NULL: none)     */
  bs_frame_snap snap;   /* with a flag: the state at the frame's start    */
} bs_dsim;

/* 0, or BS_EINPUT naming the first key of sc the backend does not run. Not
 * collective (the same answer on every rank). */
int bs_dsim_check(const bs_scene *sc, bs_error *err);

/* The fields of the backend's VTU pieces (bs_doutput.h): with output.fields
 * at its default, these of it are written (the serial run writes them all). */
#define BS_DSIM_FIELDS                                                                                      \
  (BS_FIELD_BIT(BS_FIELD_DISPLACEMENT) | BS_FIELD_BIT(BS_FIELD_VELOCITY) | BS_FIELD_BIT(BS_FIELD_MATERIAL) | \
   BS_FIELD_BIT(BS_FIELD_DETF) | BS_FIELD_BIT(BS_FIELD_INVERTED))

/* The one list of what the backend does not write into a run folder (the
 * files every backend writes are runfolder/'s, bs_runfolder_open_run; its
 * own are bs_doutput.h's): 0, or BS_EINPUT naming the key of sc (or
 * "--resume" when resume, the run to continue a stopped one) and why:
 * --resume, output.states (state.bin) but with a box mesh without refine or
 * reorder (whose serial vertex order is known), output.checkpoint_every > 0
 * in a dynamic scene (checkpoint.bin), output.fields other than the default
 * that asks for a field outside BS_DSIM_FIELDS; qoi.csv is refused with the scene
 * (bs_dsim_check: qoi). bs_dout_open calls it; a caller that refuses early
 * (bigstep run) may too. Not collective. */
int bs_dsim_check_output(const bs_scene *sc, int resume, bs_error *err);

int bs_dsim_create(const bs_scene *sc, bs_dsim **out, bs_error *err);
void bs_dsim_destroy(bs_dsim **s);

/* Statics (scene mode static), as bs_sim_statics: fs of the one step. */
int bs_dsim_statics(bs_dsim *s, bs_frame_stats *fs, bs_error *err);

/* One frame of steps_per_frame steps, as bs_sim_advance_frame (fs->steps
 * points into s, valid until the next frame). */
int bs_dsim_advance_frame(bs_dsim *s, bs_frame_stats *fs, bs_error *err);

/* A stop request (as bs_sim_run_with's opts.stop; a signal handler's flag,
 * say; NULL: none, the default): bs_dsim_advance_frame and bs_dsim_statics
 * read it over the ranks before every step and, through the integrator
 * (bs_dintegrator_set_stop), before every Newton iteration. Raised on any
 * rank, it stops every rank at the same point: the frame (or static solve)
 * cut short is undone (x, v, time, frame and the minimizer's carry as at its
 * start, bit for bit) and they return BS_SIM_STOPPED (not an error; fs is not
 * written), so that the next call does that frame again as if never stopped.
 * Every rank must pass a flag or none; the flag must outlive its use.
 * Allocates the snapshot (9 doubles per local vertex) at the first flag:
 * BS_ENOMEM. Not collective. */
int bs_dsim_set_stop(bs_dsim *s, volatile sig_atomic_t *stop, bs_error *err);

/* Tets with det F <= 0 at s->x over the ranks. */
int bs_dsim_inverted(bs_dsim *s, int64_t *n, bs_error *err);

/* Free vertices inside obstacles at s->x deeper than 1e-10 of the mesh's
 * size, over the ranks (each vertex once), and the largest depth (m), as
 * bs_sim_penetration. */
int bs_dsim_penetration(bs_dsim *s, int64_t *count, double *max_depth, bs_error *err);

/* The (constraint obstacle, vertex) pairs labeled active by the last
 * registration of the last solve, over the ranks (each vertex once). Unlike
 * bs_obstacles_active_count on the serial backend (0 after a step: its
 * post-solve hook forgets them), the labels of the last solve stay until
 * the next step's first projection. */
int bs_dsim_active_pairs(const bs_dsim *s, int64_t *n, bs_error *err);

/* Unknowns over the ranks: 3 per free vertex. */
long bs_dsim_dofs(const bs_dsim *s);

#ifdef __cplusplus
}
#endif
#endif
