/* bs_sim.h — a scene turned into a simulation, and stepping it.
 *
 * bs_sim_create builds, from a scene (bs_scene.h): the merged mesh of all
 * bodies (transformed, vertex blocks in body order), the fem cache with one
 * material per scene material, the energy terms the scene asks for
 * (inertia, gravity, elasticity, damping, drag, penalty obstacles,
 * self-collision: a term exists only when the scene asks for it), the
 * scripted vertices, the obstacles' projection and friction hooks, and the
 * integrator (bs_step.h). Then:
 *   bs_sim_advance_frame   one frame: steps_per_frame time steps;
 *   bs_sim_take_step       one time step (a frame taken step by step);
 *   bs_sim_statics         the static solve (scene mode "static");
 *   bs_sim_run             every frame of the scene (or the static solve),
 *                          calling a callback after each for whoever prints
 *                          or writes (bs_runfolder.h writes run folders).
 * Time is advanced in one place: a frame ends at exactly frame / fps.
 *
 * Units: SI. x, v: 3 doubles per vertex (m, m/s), vertex i of body b at
 * vertex_offset[b] + i.
 *
 * Ownership: the simulation borrows its scene (which must outlive it and not
 * change) and owns everything else it creates, including terms added with
 * bs_sim_add_term; free it with bs_sim_destroy. The struct's fields are for
 * reading; change the state only through the functions below (x and v may be
 * written between frames, e.g. to restart from a saved state).
 *
 * Status: every function returns 0 or a negative BS_E* code with a message
 * naming the scene key, group or vertex at fault. A step that ran but did not
 * converge is not an error: it is counted in the statistics (failed), with
 * the minimizer's reason.
 *
 * Threads: the integrator's kernels use OpenMP; call from one thread.
 *
 * Example:
 *     bs_scene *sc; bs_sim *s; bs_frame_stats fs; bs_error err;
 *     if (bs_scene_load("scene.json", 0, NULL, &sc, &err) || bs_sim_create(sc, &s, &err)) ...
 *     for (int f = 1; f <= sc->frames; f++) {
 *       if (bs_sim_advance_frame(s, &fs, &err)) ...        (an error, e.g. NaN in the state)
 *       printf("t %g: %ld Newton iterations%s\n", s->time, fs.iterations, fs.failed ? " (failed)" : "");
 *     }
 *     bs_sim_destroy(&s); bs_scene_destroy(&sc);
 */
#ifndef BS_SIM_H
#define BS_SIM_H

#include <signal.h>
#include <stdint.h>

#include "bs_fem.h"
#include "bs_mesh.h"
#include "bs_obstacles.h"
#include "bs_scene.h"
#include "bs_step.h"
#include "bs_terms.h"

#ifdef __cplusplus
extern "C" {
#endif

#define BS_SIM_MAX_TERMS 64
/* contact.dhat when the scene does not give it: this fraction of the
 * diagonal of the bodies' bounding box at t = 0 (IPC's usual 1e-3). */
#define BS_SIM_DHAT_FRACTION 1e-3

typedef struct bs_sim_script {
  const bs_scene_script *script;
  int32_t n;           /* vertices scripted by it            */
  int32_t *vertices;
} bs_sim_script;

/* One time step as the simulation records it. */
typedef struct bs_sim_step {
  bs_step_stats st;    /* the integrator's statistics (bs_step.h); st.min.reason_text */
                       /* points at `reason` below                                     */
  double time;         /* s, at the end of the step                        */
  int32_t inverted;    /* tets with det F <= 0 after the step              */
  char reason[256];    /* the minimizer's reason_text of this step, copied  */
} bs_sim_step;

/* A frame: its steps and their sums. `steps` points into the simulation
 * (valid until the next frame). Frame 0 is the initial state (no steps). */
typedef struct bs_frame_stats {
  int frame;           /* 0: the initial state; 1..frames; 1 for statics   */
  double time;         /* s, at the end of the frame                        */
  int n_steps;
  const bs_sim_step *steps;
  long iterations, cg_iterations, failed; /* summed over the frame's steps */
  double seconds;      /* solver time of the frame's steps                 */
  double grad_max;     /* largest final ||grad E|| of its steps (N)         */
} bs_frame_stats;

/* The frame's sums (iterations, CG iterations, failed steps, seconds, the
 * largest final |grad E|) from its n step records; fs->steps = steps. */
void bs_frame_sums(int frame, double time, int n, const bs_sim_step *steps, bs_frame_stats *fs);

/* Sums over a whole run, and its first failed step. */
typedef struct bs_run_totals {
  long steps, failed, iterations, cg, ls, indefinite, fb_dx, fb_grad, clamps, chol_fb, downhill;
  long floor; /* steps converged at the rounding floor of E (BS_MIN_FLOOR) */
  double seconds, max_grad;
  int first_fail_frame, first_fail_step;
  char first_fail_reason[256];
} bs_run_totals;

/* Adds a frame's steps into the totals. */
void bs_run_totals_add(bs_run_totals *T, const bs_frame_stats *fs);

typedef struct bs_sim {
  const bs_scene *scene;
  bs_mesh *mesh;        /* all bodies merged                  */
  int n_bodies;
  int32_t *vertex_offset; /* n_bodies + 1: body b's vertices start here */
  double *x0;           /* 3n: positions at t = 0 (transformed rest) */
  double size;          /* m: diagonal of the bounding box of x0 */
  double memory_bytes;  /* the run's estimated peak memory (bs_memory.h) */
  double *x, *v;        /* 3n: current state                   */
  uint8_t *mask;        /* n: 1 free, 0 scripted               */
  int32_t n_free;       /* free vertices (dofs = 3 n_free)     */
  int n_scripts;
  bs_sim_script *scripts;
  int n_materials;
  bs_material *materials;
  int32_t *tet_material;
  bs_fem *fem;
  int n_terms;
  bs_term *terms[BS_SIM_MAX_TERMS]; /* the scene's terms (penalty terms are the obstacles') */
  bs_obstacles *obstacles; /* NULL when the scene has none                  */
  bs_term *self;           /* the self-collision term (in terms[]) or NULL  */
  bs_term *barrier;        /* the barrier contact term (in terms[]; self_collision.model */
                           /* "barrier", bs_ipc_term.h) or NULL              */
  bs_term *obstacle_barrier; /* the barrier against the obstacles with collision */
                           /* "barrier" (in terms[]; bs_ipc_obstacle.h) or NULL */
  bs_term *barrier_friction; /* friction of the barrier self-contact (in terms[],  */
                           /* after barrier; self_collision.friction > 0 with     */
                           /* the barrier model, bs_ipc_friction.h) or NULL       */
  bs_step_hooks obstacle_hooks;
  double *friction_impulse; /* 3n (N s): what post-solve Coulomb friction       */
                          /* (obstacles but barrier ones, penalty self-contact) */
                          /* gave each vertex in the last step, m_p dv_p; NULL  */
                          /* when the scene has no such friction (the barrier   */
                          /* models' friction is a force of the solve)          */
  double *v_pre;          /* 3n work: velocities before self-contact friction */
  bs_step_data step;    /* filled by the integrator each step */
  bs_integrator *integrator;
  int frame;            /* frames completed                   */
  int substep;          /* steps of frame `frame` + 1 taken (bs_sim_take_step); */
                        /* 0 between frames                                  */
  double time;          /* s                                  */
  bs_sim_step *steps;   /* steps_per_frame records of the last frame */
} bs_sim;

/* Checks the scene (bs_scene_check), reads or builds the meshes, and sets up
 * everything listed at the top. */
int bs_sim_create(const bs_scene *scene, bs_sim **out, bs_error *err);
void bs_sim_destroy(bs_sim **s);

/* Adds an energy term of the caller's (created on s->fem and &s->step, see
 * bs_terms.h) to the objective; the simulation owns it from then on (also on
 * error). Call before the first step. */
int bs_sim_add_term(bs_sim *s, bs_term *t, bs_error *err);

/* One frame of the dynamic scene: steps_per_frame steps from s->time (the
 * rest of the frame when bs_sim_take_step began it). */
int bs_sim_advance_frame(bs_sim *s, bs_frame_stats *fs, bs_error *err);

/* One time step of the dynamic scene: step s->substep of frame s->frame + 1,
 * its record in s->steps[k]. After the frame's last step the frame is
 * complete (s->frame advances, s->substep is 0, s->time is exactly
 * frame / fps): *frame_done = 1 and *fs (may be NULL) holds the frame's sums;
 * otherwise *frame_done = 0. Steps taken one at a time give the state and
 * the statistics of bs_sim_advance_frame, bit for bit. BS_EINPUT for a
 * static scene. Example:
 *     int done = 0;
 *     while (!done) if (bs_sim_take_step(s, &done, &fs, &err)) ...;   (one frame)
 */
int bs_sim_take_step(bs_sim *s, int *frame_done, bs_frame_stats *fs, bs_error *err);

/* The static solve of a scene in mode "static" (frame 1, at time 0). */
int bs_sim_statics(bs_sim *s, bs_frame_stats *fs, bs_error *err);

/* Called with frame 0 (the initial state) and after every frame; a nonzero
 * return stops the run and is returned by bs_sim_run (set err). */
typedef int (*bs_frame_fn)(const bs_sim *s, const bs_frame_stats *fs, void *ctx, bs_error *err);

/* Every frame of the scene (or its static solve), with on_frame (may be
 * NULL) after each; totals (may be NULL) summed over the run. */
int bs_sim_run(bs_sim *s, bs_frame_fn on_frame, void *ctx, bs_run_totals *totals, bs_error *err);

/* bs_sim_run with a way to be asked to stop and to continue a run. */
typedef struct bs_sim_run_opts {
  bs_frame_fn on_frame;        /* may be NULL                                         */
  void *ctx;
  /* NULL, or a flag (a signal handler's, say) read before every step: when it is
     nonzero the run stops there and returns BS_SIM_STOPPED, with the simulation
     at the end of its last complete frame (a frame cut short is undone: x, v and
     time are put back as they were at its start; on_frame has seen every
     complete frame). The library installs no signal handler. */
  volatile sig_atomic_t *stop;
  /* 1: continue from s->frame (after bs_sim_restore): no on_frame call for the
     current frame, and totals added to rather than cleared. */
  int resume;
} bs_sim_run_opts;

/* Returned by bs_sim_run_with when it stopped on opts->stop (not an error). */
#define BS_SIM_STOPPED 1

int bs_sim_run_with(bs_sim *s, const bs_sim_run_opts *opts, bs_run_totals *totals, bs_error *err);

/* Puts the simulation at the end of frame `frame` of a dynamic scene, at time
 * frame / fps, with positions x and velocities v (3n each, copied): to
 * continue a run from a saved state (bs_runfolder.h, checkpoint.bin).
 * BS_EINPUT when the frame is outside [0, frames], the scene is static or a
 * value is not finite; s->substep is 0 after it. */
int bs_sim_restore(bs_sim *s, int frame, const double *x, const double *v, bs_error *err);

/* What a frame row records of the current state. */
typedef struct bs_sim_measures {
  double kinetic, elastic, gravity, total; /* J: 1/2 sum m|v|^2, Phi_e, -sum m g.x */
  int32_t inverted;       /* tets with det F <= 0                                  */
  double min_detF;
  int32_t penetrating;    /* free vertices inside obstacles deeper than 1e-10 size */
  double max_depth;       /* m                                                     */
  int64_t self_intersections; /* intersecting boundary triangle pairs (exact, CGAL), */
                          /* counted up to BS_SIM_SELF_CAP; -1 if not computed        */
  double contact_min_distance; /* barrier contact: the smallest distance between     */
                          /* surface primitives within dhat (m; +Inf: none, or no  */
                          /* barrier model)                                        */
  int64_t contact_pairs;  /* barrier contact: pairs within dhat (0 without)        */
  double kappa;           /* barrier contact: the stiffness in force (0 without)   */
  double obstacle_min_distance; /* barrier obstacles: the smallest phi of a free     */
                          /* surface vertex (m; +Inf: no barrier obstacle)         */
} bs_sim_measures;

#define BS_SIM_SELF_CAP 100000

/* The measures of a state x, v (3 per vertex of fem's mesh) that need no
 * obstacle or surface: energies (gravity g, m/s^2), inverted tets, min det F;
 * penetrating and max_depth 0, self_intersections -1 (not computed). */
void bs_measure_state(const bs_fem *fem, const double *x, const double *v, const double g[3], bs_sim_measures *m);

/* Measures the current state; intersections only when `intersections`. */
void bs_sim_measure(const bs_sim *s, int intersections, bs_sim_measures *m);

/* Vertices inside obstacles at the current state deeper than 1e-10 of the
 * bodies' size (the constraint guarantee: a projection lands on phi = 0 up to
 * rounding), and the largest depth (m, over all vertices). */
void bs_sim_penetration(const bs_sim *s, int32_t *count, double *max_depth);

/* Body b of the scene alone, as bs_sim_create makes it: read (or built),
 * refined, reordered, scaled, rotated, translated, and for bodies[].element
 * tet10 made quadratic (bs_tet10_mesh: edge midpoints appended as vertices,
 * bs_mesh.tets10). The caller owns it. */
int bs_sim_body_mesh(const bs_scene *sc, int b, bs_mesh **out, bs_error *err);

/* Free dofs (3 per free vertex). */
long bs_sim_dofs(const bs_sim *s);

#ifdef __cplusplus
}
#endif
#endif
