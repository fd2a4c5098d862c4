/* bs_step_backend.h — where the integrator's vectors live: what the one
 * integrator of bs_step.h (x̂, the guesses, scripted vertices, projection,
 * the choice of the initial guess, the solve, the statistics) asks of a
 * backend. The serial backend (bs_step_backend_serial: physics/fem.c's
 * terms on the whole mesh, solver/'s linear solvers) and the petsc backend
 * (petsc/bs_dstep.h: the terms on each rank's owned cells, sums over the
 * ranks, PETSc's Krylov solvers) both fill a bs_step_backend; the integrator
 * is written once over it.
 *
 * Vectors: 3 doubles per vertex of the backend (n_vertices; petsc: the
 * rank's local vertices, owned and ghost, consistent). Term lists: the
 * integrator picks the terms (active in the solve, cheap or expensive, the
 * potential, the external loads) and hands the backend a list, evaluated
 * in list order on the backend's mesh (the terms read the step data's x_n
 * and x_hat, which `publish` fills in the terms' vertex order).
 *
 * Statuses of the evaluations: 0; a term's BS_TERM_NOT_EVALUABLE (> 0, on
 * every rank when on one; *bad, when bad is not NULL, set to the term's name
 * when the backend knows it, else left as it is); a negative BS_E* with err
 * filled (communication, PETSc).
 *
 * Ownership: the integrator copies the struct; ctx is the backend's. When
 * destroy is not NULL, the integrator calls it on ctx when it is destroyed
 * (it then owns ctx).
 */
#ifndef BS_STEP_BACKEND_H
#define BS_STEP_BACKEND_H

#include <stdint.h>

#include "bs_base.h"
#include "bs_step.h"
#include "bs_bsr.h"
#include "bs_linsolve.h"
#include "bs_minimize.h"
#include "bs_terms.h"
#include "bs_vecops.h"

#ifdef __cplusplus
extern "C" {
#endif

struct bs_step_hooks; /* bs_step.h */

/* What a backend runs beyond the optimization integrator with line search
 * (bs_step_backend.caps; bs_step_refuse). */
enum {
  BS_STEP_CAN_SELF_COLLISION = 1 << 0, /* expensive and convexified terms    */
  BS_STEP_CAN_POST_SOLVE = 1 << 1,     /* post-solve hooks: friction, postprocess collisions */
  BS_STEP_CAN_NEWTON = 1 << 2,         /* the Newton baseline (newton, newton_k) */
  BS_STEP_CAN_TRACE = 1 << 3,          /* opts.trace                          */
  BS_STEP_CAN_DIRECT = 1 << 4,         /* solver.linear cholmod, minres       */
  BS_STEP_CAN_TRUST_REGION = 1 << 5,   /* solver.globalization trust_region    */
  BS_STEP_CAN_AMG_CURRENT = 1 << 6,    /* the AMG built at the iterate (amg_at_rest 0) */
  BS_STEP_CAN_ALL = (1 << 7) - 1
};

/* What a run asks of the integrator, from a scene (the backend's scene
 * check) or from the integrator's options, terms and hooks. */
typedef struct bs_step_features {
  int self_collision;       /* 1: self-collision (an expensive or convexified term)  */
  int postprocess_obstacle; /* index of an obstacle with postprocess collisions, -1 none */
  int friction_obstacle;    /* index of an obstacle with friction, -1 none           */
  int post_solve;           /* 1: post-solve hooks of any origin                      */
  int method;               /* bs_method (bs_step.h)                                  */
  bs_lin_kind linear;
  bs_globalization globalization;
  int amg_at_rest;          /* with linear amg                                        */
  int trace;                /* 1: opts.trace                                          */
  int integrator;           /* bs_time_integrator (bs_step.h)                         */
} bs_step_features;

/* THE list of what a backend of capabilities caps (BS_STEP_CAN_*) does not
 * run: 0, or BS_EINPUT with "WHERE: KEY: WHY with solver.backend NAME",
 * KEY the scene key of the first feature of f refused (self_collision,
 * obstacles.N.collision, obstacles.N.friction, solver.method, solver.linear,
 * solver.globalization, solver.amg_matrix, output trace). where and name
 * are the caller's (the scene's path, the backend's name).
 * Also what no backend runs with a time integrator (caps or not): "WHERE:
 * obstacles.N.collision: ... with solver.integrator NAME" for postprocess
 * collisions with bdf2 or newmark (they move x after the solve, which the
 * integrator's history and acceleration do not follow). */
int bs_step_refuse(const bs_step_features *f, unsigned caps, const char *where, const char *name, bs_error *err);

typedef struct bs_step_backend {
  int32_t n_vertices;     /* vertices of the vectors                                  */
  const double *mass;     /* per vertex: lumped mass (kg), the whole body's           */
  const bs_bsr *pattern;  /* the minimizer's Hessian pattern (bs_minimizer_create)    */
  const bs_vecops *vecops;/* NULL: the minimizer's own (one process); else its ops    */
  unsigned caps;          /* BS_STEP_CAN_*                                            */
  const char *name;       /* in messages: "serial", "petsc"                            */
  /* step->x_n and step->x_hat made what the terms read from the vectors
     x_n and x_hat (serial: pointed at them; petsc: copied in the terms'
     vertex order). */
  void (*publish)(void *ctx, bs_step_data *step, const double *x_n, const double *x_hat);
  /* *E = the sum of the n terms' energies at x (NaN when one is not evaluable). */
  int (*energy)(void *ctx, int n, bs_term *const *terms, const double *x, double *E, const char **bad,
                bs_error *err);
  /* *E as energy, and g (written) = their gradient, consistent. */
  int (*gradient)(void *ctx, int n, bs_term *const *terms, const double *x, double *E, double *g,
                  const char **bad, bs_error *err);
  /* H = the n terms' Hessians at x (zeroed first unless add; the backend's
     own matrix where it has one: H then unused): a term's hessian_convexified
     with convex, its hessian_g with g_model not NULL; then, with hooks not
     NULL, hooks->project_hessian at (x, g_raw) (g_raw NULL: the backend
     computes the terms' gradient); mask (1 free per vertex; may be NULL):
     the backend's own matrix gets identity rows for fixed vertices. */
  int (*hessian)(void *ctx, int n, bs_term *const *terms, const double *x, const double *g_model, int convex,
                 int add, const struct bs_step_hooks *hooks, const double *g_raw, const uint8_t *mask, bs_bsr *H,
                 bs_error *err);
  /* The constraint hooks (written for the terms' mesh) applied to vectors;
     what project and project_gradient change is made consistent. */
  int (*project)(void *ctx, const struct bs_step_hooks *h, double *x, bs_error *err);
  void (*register_active)(void *ctx, const struct bs_step_hooks *h, const double *x, const double *g);
  int (*project_gradient)(void *ctx, const struct bs_step_hooks *h, const double *x, double *g, bs_error *err);
  /* v[0..n) summed over the processes in place (one process: nothing). */
  int (*sum_i64)(void *ctx, int64_t *v, int n, bs_error *err);
  /* *s = the sum of g_i^2 over the free dofs (mask: 1 free per vertex). */
  int (*free_sq)(void *ctx, const double *g, const uint8_t *mask, double *s, bs_error *err);
  /* *n = tets with det F <= 0 at x, over the processes. */
  int (*count_inverted)(void *ctx, const double *x, int64_t *n, bs_error *err);
  /* Before a solve: the linear solver's options set in *mo and its
     preconditioner made ready: pdt the dt of the solve (0: statics), the n
     active terms, mask, amg_at_rest (bs_integrator_opts). pdt is
     sqrt(c) Δt with the integrator's c (bs_step.h): it changes with the
     inertia M/(c Δt²), e.g. on BDF2's first step. */
  int (*prepare_solve)(void *ctx, bs_minimizer *min, bs_minimize_opts *mo, double pdt, int n,
                       bs_term *const *terms, const uint8_t *mask, int amg_at_rest, bs_error *err);
  /* May be NULL: the AMG matrix of bs_objective.precond_matrix, added into P
     (the n dynamic terms' Hessians at x and the PSD-projected elastic Hessian
     at the rest positions when at_rest, else at x). */
  int (*precond)(void *ctx, int n, bs_term *const *terms, const double *x, int at_rest, bs_bsr *P);
  /* May be NULL: after a solve, the first error of the vector operations
     (vecops) during it (0: none; then reset). */
  int (*solve_error)(void *ctx, bs_error *err);
  void (*destroy)(void *ctx); /* may be NULL */
  void *ctx;
} bs_step_backend;

/* The serial backend on fem (borrowed): the whole mesh in one process. */
int bs_step_backend_serial(const bs_fem *fem, bs_step_backend *out, bs_error *err);

/* ---- the integrator on a backend (bs_step.h) ---- */

/* The same integrator on another backend (bs_step_backend.h; the serial one
 * is bs_integrator_create's): vectors, mask (per vertex of B) and the
 * script's vectors are the backend's. B is copied; its ctx is the
 * integrator's from this call when B->destroy is set (destroyed on failure
 * too). BS_EINPUT (bs_step_refuse) for what the backend does not run:
 * self-collision terms, the Newton baseline, opts.trace, ... */
int bs_integrator_create_on(const bs_step_backend *B, bs_step_data *step, int n_terms, bs_term *const *terms,
                            const uint8_t *mask, bs_script_fn script, void *script_ctx, const bs_integrator_opts *opts,
                            bs_integrator **out, bs_error *err);
/* bs_integrator_set_hooks, refusing (BS_EINPUT, bs_step_refuse) post-solve
 * hooks on a backend that does not run them. */
int bs_integrator_set_hooks_checked(bs_integrator *integ, const bs_step_hooks *hooks, bs_error *err);


#ifdef __cplusplus
}
#endif
#endif
