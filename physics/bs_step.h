/* bs_step.h — the time step (backward Euler, BDF2, Newmark) and statics
 * handed to the minimizer.
 *
 * One step from (xⁿ, vⁿ) at tⁿ to tⁿ⁺¹ = tⁿ + Δt (paper, sections 2 and 3.1):
 *  1. step data: x̂ = xⁿ + Δt vⁿ (x̃ and c of the integrator, below); each
 *     term's begin_step (lagged damping);
 *  2. scripted (constrained) vertices placed at their positions at tⁿ⁺¹;
 *  3. the paper's two initial guesses, xⁿ + Δt vⁿ and xⁿ + Δt vⁿ + Δt² M⁻¹ f(xⁿ),
 *     with opts.guess_xn a third, xⁿ, keeping the one with the smallest E (the
 *     first and third are "naive": at least one iteration is then taken); each
 *     is projected when a projection hook is set (constraint collisions);
 *     with post-solve hooks (friction, which changes vⁿ after the solve) a
 *     fourth, xⁿ + d, d the last step's displacement before its hooks, when
 *     (xⁿ, vⁿ) is the state that step left and its E is the smallest: where
 *     a kinematic obstacle pushes a body along a frictional floor, x̂ lags
 *     the obstacle by what friction took from vⁿ, and this one does not;
 *  4. the solve: the optimization integrator (bs_minimize), or the Newton
 *     baseline (bs_newton, to convergence or k steps);
 *  5. vⁿ⁺¹ = (xⁿ⁺¹ − xⁿ)/Δt (the integrator's update, below), then the
 *     post-solve hooks (friction).
 *
 * Moving obstacles. A term whose domain moves in time (bs_terms.h: sweep
 * and carry; barrier obstacles that move) is evaluated at step->time, which
 * is tⁿ⁺¹ for the solve. When its domain at tⁿ⁺¹ no longer holds xⁿ (a
 * moving obstacle passes over a vertex within the step), the step is swept
 * before step 3: f(xⁿ) is taken with the obstacles at tⁿ; then from
 * (x, τ) = (xⁿ, tⁿ), each stage moves x along a predictor z while the time
 * goes from τ to tⁿ⁺¹, as far as every term certifies the path
 * (x + a z, τ + a (tⁿ⁺¹ − τ)) (sweep for the moving terms, max_step for
 * the others), and, when it stops short of tⁿ⁺¹ with something pushed,
 * minimizes the step's objective with step->time at the τ reached, for at
 * most 8 iterations (the stage only has to make room for the next one). z
 * carries the vertices within dhat of a moving obstacle with it (the
 * terms' carry); then each body with a carried vertex (a connected
 * component of the pattern's graph; none with a vertex that is not free)
 * moves rigidly, by the mean displacement of its carried vertices, and so
 * does, until none is added, each body that a term carries along with a
 * carried one (barrier contact: in an active pair with it); the other free
 * vertices move by the linear response, H_ff z_f = −H_fc z_c (H the
 * convexified Hessian at x; PCG). When that predictor is limited, the one
 * without rigid bodies (the moving domains' vertices and the linear
 * response) is tried too, and the one certified further is taken (a body
 * carried whole can be blocked where its parts give). The guesses of step 3 are then
 * clipped from where the sweep ends instead of from xⁿ, so every point the
 * step stops at and every path between them is in the domains at their own
 * times. st->sweep_stages counts the stages and st->min includes their
 * solves. A sweep that cannot move (a vertex closer to a moving obstacle
 * than the CCD certifies) or that has not reached tⁿ⁺¹ after 256 stages is
 * BS_ENUMERIC, naming the times.
 *
 * Time integrators (opts.integrator, the scene's solver.integrator): each
 * step minimizes one incremental potential
 *     E(x) = 1/(2 c Δt²) ‖x − x̃‖²_M + Φ(x),
 * Φ every term but inertia (bs_terms.h: the inertia term reads c from
 * bs_step_data.c and x̃ from its x_hat), with the integrator's c and x̃ (its
 * stationarity condition is M (x − x̃) / (c Δt²) = f(x)):
 *  - backward Euler (BS_INTEGRATOR_BACKWARD_EULER, the default): c = 1,
 *    x̃ = xⁿ + Δt vⁿ; vⁿ⁺¹ = (xⁿ⁺¹ − xⁿ)/Δt. First order.
 *  - BDF2 (BS_INTEGRATOR_BDF2): xⁿ⁺¹ = 4/3 xⁿ − 1/3 xⁿ⁻¹ + 2/3 Δt vⁿ⁺¹ and
 *    vⁿ⁺¹ = 4/3 vⁿ − 1/3 vⁿ⁻¹ + 2/3 Δt aⁿ⁺¹ with M aⁿ⁺¹ = f(xⁿ⁺¹); putting
 *    the second in the first, xⁿ⁺¹ = x̃ + 4/9 Δt² aⁿ⁺¹, so
 *        c = 4/9,  x̃ = 4/3 xⁿ − 1/3 xⁿ⁻¹ + 2/3 Δt (4/3 vⁿ − 1/3 vⁿ⁻¹)
 *    (the BDF incremental potential of IPC and PolyFEM: x̃ = Σ αᵢ x + β Δt
 *    Σ αᵢ v, c = β², α = (4/3, −1/3), β = 2/3); after the solve
 *    vⁿ⁺¹ = (3 xⁿ⁺¹ − 4 xⁿ + xⁿ⁻¹)/(2Δt) (equal to the velocity form above
 *    for any vⁿ, vⁿ⁻¹). The step carries (xⁿ⁻¹, vⁿ⁻¹) in its history
 *    (bs_step_history below); a step without one (the first, after
 *    statics, from a state the last step did not leave, or with another Δt)
 *    is a backward Euler step, whose local error O(Δt²) keeps the order 2.
 *  - Newmark, average acceleration (BS_INTEGRATOR_NEWMARK, β = 1/4,
 *    γ = 1/2): c = β = 1/4, x̃ = xⁿ + Δt vⁿ + Δt² (1/2 − β) aⁿ; after the
 *    solve aⁿ⁺¹ = (xⁿ⁺¹ − x̃)/(β Δt²) (so M aⁿ⁺¹ = f(xⁿ⁺¹)),
 *    vⁿ⁺¹ = vⁿ + Δt ((1 − γ) aⁿ + γ aⁿ⁺¹). The history carries aⁿ; without
 *    one, M aⁿ = f(xⁿ) (lumped M; 0 on scripted and fixed vertices and
 *    vertices without mass). Second order; on a linear problem it conserves
 *    the energy (the trapezoidal rule).
 * What the other parts of a step become with c and x̃: the guesses are x̃
 * (BS_GUESS_XHAT) and x̃ + c Δt² M⁻¹ f(xⁿ) (explicit); xⁿ and the previous
 * step as above. The lagged damping and the drag keep their form
 * 1/(2Δt) (x − xⁿ)ᵀ D (x − xⁿ): a force −D (xⁿ⁺¹ − xⁿ)/Δt, first order in
 * Δt under every integrator (the integrators' order 2 is that of undamped
 * problems). Friction (post-solve hooks that change v) acts on vⁿ⁺¹ as an
 * impulse, which the next x̃ carries. Postprocess collisions, which move x
 * after the solve, are refused with bdf2 and newmark (bs_step_refuse).
 *
 * Statics minimizes Φ alone (terms marked dynamic_only are left out), under
 * the same constraints, optionally in load steps (gravity scaled by i/L).
 *
 * The integrator owns its minimizer and work vectors; it borrows the fem, the
 * terms and the step data (bs_step_data, which the terms were created with
 * and read, and which the integrator fills before each solve); it copies the
 * mask.
 */
#ifndef BS_STEP_H
#define BS_STEP_H

#include <stdint.h>
#include <stdio.h>

#include "bs_base.h"
#include "bs_fem.h"
#include "bs_minimize.h"
#include "bs_terms.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum { BS_METHOD_OPTIMIZATION = 0, BS_METHOD_NEWTON, BS_METHOD_NEWTON_K } bs_method;

/* The time integrator (top of this header; the scene's solver.integrator). */
typedef enum {
  BS_INTEGRATOR_BACKWARD_EULER = 0,
  BS_INTEGRATOR_BDF2 = 1,
  BS_INTEGRATOR_NEWMARK = 2
} bs_time_integrator;

/* "backward_euler", "bdf2", "newmark"; parse: BS_EINPUT naming the unknown
 * name and the known ones; name: "?" outside the enum. */
int bs_time_integrator_parse(const char *name, bs_time_integrator *out, bs_error *err);
const char *bs_time_integrator_name(bs_time_integrator k);

int bs_method_parse(const char *name, bs_method *out, bs_error *err); /* optimization|newton|newton_k */
const char *bs_method_name(bs_method m);

/* bs_integrator_opts.penalty_secant; the scene's solver.penalty_hessian
 * "exact", "obstacles", "all". */
typedef enum { BS_PENALTY_EXACT = 0, BS_PENALTY_SECANT_OBSTACLES = 1, BS_PENALTY_SECANT_ALL = 2 } bs_penalty_hessian;

typedef struct bs_integrator_opts {
  bs_method method;
  int newton_k;           /* steps for BS_METHOD_NEWTON_K (1: linearized backward Euler) */
  bs_minimize_opts min;   /* tolerance, caps, linear solver                          */
  /* For min.linear = amg: the matrix the AMG is built from is the Hessian of the
     dynamic terms (inertia, damping, drag: all PSD) plus the PSD-projected elastic
     Hessian, at the rest positions (amg_at_rest = 1, the default: rebuilt only when
     dt changes, between dynamic and static solves, or on min.amg_rebuild_every;
     min.amg_rebuild_factor is ignored since P does not depend on x) or at the iterate
     where a setup happens (amg_at_rest = 0; min.amg_rebuild_factor applies).
     Measurements: docs/design/linear-solvers.md. */
  int amg_at_rest;
  /* NULL (default): silent. Else one line per accepted iteration of every solve is
     written there (iteration, ||grad E||, E, Krylov iterations, step length, line-search
     trials): to follow a slow step. */
  FILE *trace;
  /* Default 0: also try xⁿ as the initial guess (step 3 above). For scenes with
     self-collision: when bodies close in fast, both of the paper's guesses can put a
     vertex through the middle of another body, where the penalty pushes it out on the
     far side; from xⁿ the descent meets the penalty on the near side. Not for scenes
     without contact (it can lead into a local minimum that keeps a tet inverted).
     bs_sim_create (sim/) sets it for the optimization integrator when the scene has
     self_collision. Measurements: docs/design/contact-models.md. */
  int guess_xn;
  /* Default BS_PENALTY_EXACT: with another value, the Newton model of the terms that
     offer hessian_g (bs_terms.h: the obstacle penalties' secant model, bs_penalty.h;
     the self-collision term's, bs_selfcollide.h, when switched on there) instead of
     their Hessians, wherever the minimizer hands over the gradient. E and its gradient
     are unchanged. Why: the penalty k depth³ has a gradient quadratic in the depth, on
     which Newton halves a deep vertex's depth per iteration until it is near the depth
     where the penalty balances the other forces. bs_sim_create sets it from the scene's
     solver.penalty_hessian for the optimization method (the Newton baseline keeps the
     exact Hessian), and switches the self-collision term's model on for
     BS_PENALTY_SECANT_ALL. */
  bs_penalty_hessian penalty_secant;
  /* The time integrator (top of this header), default
     BS_INTEGRATOR_BACKWARD_EULER. */
  bs_time_integrator integrator;
} bs_integrator_opts;

void bs_integrator_opts_default(bs_integrator_opts *o);

/* Scripted vertices: sets x of the constrained vertices (mask 0) at time t. */
typedef void (*bs_script_fn)(double t, double *x, void *ctx);

/* Hooks of the constrained formulation and friction (collision/ sets them). */
typedef struct bs_step_hooks {
  void (*project)(double *x, void *ctx);                             /* P(x) in place     */
  void (*register_active)(const double *x, const double *g, void *ctx);
  /* g <- J_P(x)^T g at a feasible x for the active pairs (bs_objective's project_gradient) */
  void (*project_gradient)(const double *x, double *g, void *ctx);
  /* H <- Hessian of E'(P(x)) from H' = Hessian of E' and g' = grad E' at a feasible x
     (section 3.2, "Derivatives"); called after the terms' Hessians are assembled */
  void (*project_hessian)(const double *x, const double *g, bs_bsr *H, void *ctx);
  /* After the solve, with g = grad E'(x^{n+1}) (unprojected, all terms): may change v
     (friction); may change x only for the `postprocess` collision baseline. */
  int (*post_solve)(const double *x_n, double *x, const double *g, double *v, double dt, void *ctx,
                    bs_error *err);
  void *ctx;
} bs_step_hooks;

/* The initial guess a step's solve started from (step 3 above). The numbers
 * are the ones the run folder writes (stats.csv, column guess; bs_runfolder.h). */
typedef enum {
  BS_GUESS_XHAT = 0,     /* x̂ = xⁿ + Δt vⁿ                                        */
  BS_GUESS_EXPLICIT = 1, /* x̂ + Δt² M⁻¹ f(xⁿ) (an explicit step)                  */
  BS_GUESS_XN = 2,       /* xⁿ (opts.guess_xn)                                    */
  BS_GUESS_PREVIOUS = 3  /* xⁿ + the last step's displacement (post-solve hooks)  */
} bs_guess;

/* "x_hat", "explicit", "x_n", "previous"; "?" for a value outside the enum. */
const char *bs_guess_name(bs_guess g);

typedef struct bs_step_stats {
  bs_minimize_stats min;  /* of the solve                                        */
  bs_guess guess;         /* the initial guess taken (statics: BS_GUESS_XHAT)    */
  int failed;             /* the solve did not converge (reason in min)          */
  double seconds;         /* the whole step                                      */
  int32_t sweep_stages;   /* stages of the sweep of moving obstacles (0: none;   */
                          /* "Moving obstacles" above); its solves are in min    */
} bs_step_stats;

typedef struct bs_integrator bs_integrator;

/* mask: n_vertices bytes, 1 free / 0 scripted or fixed (NULL: all free);
 * script: positions of the masked vertices in time (NULL: they stay put). */
int bs_integrator_create(const bs_fem *fem, bs_step_data *step, int n_terms, bs_term *const *terms, const uint8_t *mask,
                         bs_script_fn script, void *script_ctx, const bs_integrator_opts *opts,
                         bs_integrator **out, bs_error *err);
void bs_integrator_destroy(bs_integrator **I);
void bs_integrator_set_hooks(bs_integrator *I, const bs_step_hooks *hooks);

/* The vertices of the integrator's vectors (its backend's). */
int32_t bs_integrator_vertices(const bs_integrator *I);
/* Tets with det F <= 0 at x, over the backend's processes (collective). */
int bs_integrator_count_inverted(bs_integrator *I, const double *x, int64_t *n, bs_error *err);
/* *any = 1 when flag is nonzero on some process of the backend (collective). */
int bs_integrator_any(bs_integrator *I, int flag, int *any, bs_error *err);

/* One step of size dt from time t of the time integrator (opts.integrator;
 * top of this header: its history is read when (x, v) is the state the last
 * step left, and updated): x, v in/out (3 per vertex).
 * Returns 0 when the step ran (st->failed says whether it converged), a
 * negative code on errors (NaN in the state: refused before the solve;
 * BS_ENUMERIC naming the term when one is not evaluable, bs_terms.h, at xⁿ,
 * or at the step's answer when post-solve hooks need the gradient there). A
 * term not evaluable at a trial point or an iterate is the minimizer's to
 * handle: the line search shrinks the step, an iterate ends the solve
 * (BS_MIN_NONFINITE). An initial guess where a term is not evaluable counts
 * as E = +Inf: it is taken only when no guess is evaluable, and the solve then
 * stops at once (BS_MIN_NONFINITE). */
int bs_integrator_step(bs_integrator *I, double t, double dt, double *x, double *v, bs_step_stats *st,
                       bs_error *err);

/* Statics: minimizes Φ from x (in/out) at time t (scripted positions at t),
 * in load_steps load increments (>= 1). */
int bs_integrator_static(bs_integrator *I, double t, int load_steps, double *x, bs_step_stats *st,
                         bs_error *err);

/* Helpers of the integrator. Nothing allocates, prints or fails. */

/* bs_objective.quadratic of a solve over the terms: 1 when every term active
 * in it (statics = 1: those not dynamic_only) is quadratic and nothing
 * projects (projected = 1: constraint hooks are set, which make E piecewise). */
int bs_step_objective_quadratic(int n_terms, bs_term *const *terms, int statics, int projected);

/* The forcing_ew (bs_minimize_opts) of a solve whose step starts with
 * `inverted` tets: the adaptive forcing (2, scene cg_forcing "adaptive")
 * becomes the paper's forcing term (0) while the step starts tangled
 * (inverted > 0), where its loose solves untangle best (README, Scenes); any
 * other value is returned as it is. */
bs_forcing bs_step_forcing(bs_forcing forcing_ew, int64_t inverted);

/* Adds the statistics of one solve (a load step of statics) into st: the
 * counts summed; reason, reason_text, grad_norm, E and tol_used sub's;
 * failed or-ed. */
void bs_step_stats_add(bs_step_stats *st, const bs_step_stats *sub);

/* The objective value E at x for the current step data (for tests/diagnostics);
 * NaN when a term is not evaluable at x. */
double bs_integrator_energy(bs_integrator *I, const double *x);

/* The minimizer's state carried from one solve to the next (bs_min_carry in
 * bs_minimize.h), for checkpoints. */
void bs_integrator_get_carry(const bs_integrator *I, bs_min_carry *c);
void bs_integrator_set_carry(bs_integrator *I, const bs_min_carry *c);

/* What the previous-step guess (step 3) needs, for checkpoints and for
 * undoing a stopped frame: have = 0 when there is none (no step yet, after
 * statics, or without post-solve hooks). get copies d when p->d is not NULL
 * (3n doubles, the caller's); set copies d (have is kept only with d and
 * dt > 0). A state restored bit for bit with its mark gets the guess back;
 * any other state simply does not. */
typedef struct bs_previous_step {
  int have;
  double dt;     /* that step's Δt                                 */
  uint64_t mark; /* of the (x, v) that step left                    */
  double *d;     /* 3n: its displacement before the post-solve hooks */
} bs_previous_step;
void bs_integrator_get_previous(const bs_integrator *I, bs_previous_step *p);
void bs_integrator_set_previous(bs_integrator *I, const bs_previous_step *p);

/* The time integrator's history (top of this header), for checkpoints and
 * for undoing a stopped frame: have = 0 when there is none (no step yet,
 * after statics, backward Euler); dt and mark those of the step that left
 * it (mark: of the (x, v) it left; the history is used only from that
 * state, and BDF2's only with the same Δt). h: bs_integrator_history_doubles
 * doubles (the caller's; get copies into it when not NULL, set copies from
 * it): BDF2 xⁿ⁻¹ then vⁿ⁻¹ (3n each), Newmark aⁿ (3n), backward Euler none.
 * set keeps have only with h and dt > 0. */
typedef struct bs_step_history {
  int have;
  double dt;
  uint64_t mark;
  double *h;
} bs_step_history;
size_t bs_integrator_history_doubles(const bs_integrator *I);
void bs_integrator_get_history(const bs_integrator *I, bs_step_history *hs);
void bs_integrator_set_history(bs_integrator *I, const bs_step_history *hs);

/* The stop flag of the integrator's solves (bs_minimizer_set_stop; NULL:
 * none): a step whose solve it stops ends with reason BS_MIN_STOPPED and
 * failed = 1, at a state that is not the step's solution (undo it). */
void bs_integrator_set_stop(bs_integrator *I, volatile sig_atomic_t *stop);

#ifdef __cplusplus
}
#endif
#endif
