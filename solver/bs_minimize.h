/* bs_minimize.h — the stabilized Newton minimizer of Gast & Schroeder (paper,
 * sections 3.1–3.3) and the plain Newton root-finder it is compared against
 * (section 2).
 *
 * The minimizer knows no physics: it sees an objective E through callbacks
 * (value, gradient, Hessian into a 3x3 block CSR matrix, optional projection
 * hooks) and a vector x of 3n doubles (3 per vertex, dof 3i+a is component a
 * of vertex i).
 *
 * Units: x has whatever unit the objective gives it (metres in bigstep); E and
 * its derivatives are in the objective's units (J, N, N/m). opts.tol is on the
 * masked 2-norm of grad E (N); opts.clamp is on the 2-norm of the step (units
 * of x); opts.sigma has units of grad E^-1/2 (the paper's sigma, usually 1;
 * with opts.sigma_auto it is unitless and divided by the square root of the
 * gradient's norm at the first iterate).
 *
 * Each iteration of bs_minimize (paper 3.1, steps 1–9):
 *   1. register_active(x, g') with g' = grad E'(x), the gradient the objective
 *      returned at the feasible iterate x (constrained problems only).
 *   2. g = grad E(x): g' with fixed dofs zeroed, then project_gradient(x, g)
 *      when given (section 3.2: E = E'∘P, so grad E = J_P^T grad E' at a
 *      feasible x). Hessian H at x (objective's hessian callback; its
 *      hessian_convexified after negative curvature, see "Convexified model").
 *   3. stop when ||g|| < tol (at least one iteration when opts.naive_guess).
 *   4. solve H dx = -g from a zero guess to relative tolerance
 *      min(1/2, sigma sqrt(max(||g||, tol))) (opts.sigma_auto and
 *      opts.forcing_ew below change it) with opts.linear. CG/PCG exit on
 *      indefiniteness with their last iterate (the rhs on the first step);
 *      CHOLMOD reporting "not positive definite" falls back to CG for that
 *      iteration (counted in cholmod_fallbacks). opts.linear = amg: the
 *      same PCG with one BoomerAMG V-cycle (bs_amg.h) as preconditioner,
 *      built from the matrix P of the objective's precond_matrix callback
 *      (SPD on the free dofs: e.g. PSD-projected stiffness plus M/dt^2), or
 *      from H itself when the callback is NULL (H must then be SPD). The
 *      setup is reused across iterations and calls (see "AMG reuse").
 *   5. downhill: keep dx if dx.g < -kappa ||dx|| ||g||, else -dx if that
 *      passes (fallback_neg_dx), else -g (fallback_neg_grad). With
 *      opts.cg_downhill (the default), a CG/PCG/AMG answer that fails the
 *      test is first replaced, inside the solve, by the last CG iterate that
 *      passed it (bs_linsolve_set_downhill; counted in downhill_iterates),
 *      so -g is used only when no iterate passed.
 *   6. clamp ||dx|| to opts.clamp (clamps).
 *   7. strong Wolfe line search (Nocedal & Wright, Algorithms 3.5 and 3.6) on
 *      phi(a) = E(P(x + a dx)), phi'(a) = grad E(P(x + a dx)).dx, where grad E
 *      is the gradient as in step 2 (masked, project_gradient with the active
 *      set registered in step 1). a = 1 is tried first; a grows beyond 1 when
 *      the curvature condition fails with a negative slope. A non-evaluable or
 *      non-finite point counts as phi = +Inf (the step shrinks). When
 *      value_lower_bound is given and exceeds phi(0), value() and gradient()
 *      are not called at that point (section 3.3). If no Wolfe point is found
 *      within opts.max_ls trial points, the lowest trial point with
 *      phi < phi(0) is taken (ls_failures); if there is none along a Newton
 *      direction (dx or -dx) not parallel to -g, whose predicted decrease is
 *      above the rounding floor, the search is made again along -g (counted
 *      in fallback_neg_grad: a kink of E, such as a self-collision
 *      contact switching primitives, can block the Newton direction and not
 *      -g); if there is still none the solve stops with BS_MIN_LINE_SEARCH. An accepted step never increases E (except,
 *      by at most the rounding level of E, with opts.accept_noise; off by
 *      default).
 *   8–9. x <- P(x + a dx), which is the point the line search evaluated.
 * The initial guess is projected too. Fixed dofs (mask 0) never move: they are
 * restored after every projection, and directions are zero there.
 *
 * Rounding floor (beyond the paper, whose 3.3 notes that E is noisy): E is known to
 * about its rounding level, noise(E) = 64 eps |E|, and grad E to its own
 * rounding level, which the minimizer cannot see. An iteration is at the
 * noise level when its direction is Newton's (dx or -dx, not -grad E) and
 * the decrease it predicts, |g.d|, is at most noise(E): E can no longer
 * tell whether the step helps. The solve stops with BS_MIN_FLOOR, a
 * converged state, when (a) such an iteration's line search finds no
 * decrease, or (b) BS_FLOOR_WINDOW noise-level iterations in a row (1 for
 * obj->quadratic) have not halved the ||g|| of the first of
 * them: ||g|| has reached the rounding level of the gradient (with
 * opts.accept_noise the steps of those iterations are taken; they go on
 * lowering ||g|| while the gradient still resolves it). The reason text
 * gives ||g||, E and noise(E). A tolerance below the floor thus ends as
 * "converged at the rounding floor of E", never as a failure; where a
 * larger ||g|| is not acceptable, compare stats.grad_norm with what you
 * need.
 *
 * Convexified model (beyond the paper; opts.convexify, obj->hessian_convexified): the
 * paper's CG returns its last iterate when it meets negative curvature
 * (step 4). Where that curvature comes from penalty contacts pressed deep
 * (self-collision: the distance to a triangle falls as the triangle tilts,
 * a negative stiffness of about 3 k depth^3 / h^2 against elastic
 * stiffnesses of about E h), CG stops after a few iterations with a
 * direction far too long, which the line search cuts short, and an impact
 * takes many such iterations (docs/design/contact-models.md). So once
 * a system of the solve has met negative curvature, the following
 * iterations solve with the convexified Hessian, and the exact one comes
 * back after an iteration that took the full Newton step (a Newton
 * direction, no negative curvature, alpha = 1 at the first trial) from a
 * solve of at least 2 Krylov iterations (one CG iteration is a scaled
 * gradient step, which says nothing of the model): near the solution the
 * exact Hessian keeps Newton's fast convergence, which the convexified
 * one loses (its clamped curvature is of the order of the elastic one at
 * resting contacts). The direction of the iteration that met negative
 * curvature is kept (the paper's rule). E and its gradient never change,
 * only the model: the line search and the convergence test are as before.
 *
 * Step bound (obj->max_step, e.g. a barrier contact term's continuous
 * collision detection): before each line search (also the one made again
 * along -g) the hook gives alpha_max along the search direction d, and the
 * search is the strong Wolfe search of step 7 on [0, alpha_max]: the first
 * trial point is min(1, alpha_max), extrapolation stops at alpha_max, and at
 * alpha_max, when sufficient decrease holds but the slope is still steep and
 * negative, alpha_max itself is taken (BS_LSEARCH_BOUND: the best point of
 * the interval). No trial point beyond alpha_max is ever evaluated; a bound
 * of 0 means no step (BS_MIN_LINE_SEARCH, the reason text says so). The
 * indefinite-CG exit, the downhill check and the clamp come first,
 * unchanged. A search some of whose trial points the bound shortened is
 * counted in stats.ccd_limited. Trust region: a trial step longer than its
 * bound is scaled to it (before the model's decrease is computed); bs_newton
 * takes min(1, alpha_max) of its step. Without the hook every result is bit
 * for bit what it was before the hook existed. The projection hook P is
 * applied after the bound: an objective with both must keep P's moves
 * feasible itself.
 *
 * Line-search constants: c1 = 1e-4 (sufficient decrease) and c2 = 0.9
 * (curvature) by default, Nocedal & Wright's choice for Newton-type methods.
 * Extrapolation (a > 1): the minimizer of the cubic through the last two trial
 * points, kept within [a_i + (a_i - a_{i-1})/2, a_i + 10 (a_i - a_{i-1})]
 * (a_i + 4 (a_i - a_{i-1}) when the cubic has no minimizer), up to a = 1e10.
 * Zoom: the cubic through the bracket ends when both slopes are known, else
 * the quadratic through phi(lo), phi'(lo), phi(hi) when phi(hi) is finite,
 * kept at least 10% of the bracket away from its ends, else bisection. Trial
 * points of the first phase call gradient() (the slope is needed when they
 * satisfy sufficient decrease, which is the usual case); trial points of the
 * zoom call value() first and gradient() only when sufficient decrease holds.
 *
 * Constrained problems (section 3.2): the objective's `gradient` and `hessian`
 * describe E' (the unconstrained objective); `project` is P (active or
 * violated pairs projected), `register_active` labels the active set from
 * grad E' at a feasible x, and `project_gradient` turns grad E' into grad E
 * for the labeled pairs. The `hessian` callback should return the Hessian of
 * E (projected rows/columns of active pairs, plus the curvature term of P)
 * for fast convergence; any symmetric matrix still gives a descent method
 * through step 5.
 *
 * Trust region (beyond the paper; opts.globalization = trust_region, Nocedal & Wright
 * Algorithms 4.1 and 7.2): steps 4-9 become: solve H p = -g by Steihaug's
 * truncated CG in the ball ||p|| <= Delta (bs_linsolve_set_radius: negative
 * curvature and an iterate leaving the ball both end on the boundary, so the
 * curvature CG finds is followed, not discarded); if p is not a descent
 * direction, the Cauchy-like step -Delta g / ||g||; the trial point y =
 * P(x + p) and rho = (E(x) - E(y)) / m, m = -(g.p + p.H p / 2) the decrease
 * the quadratic model predicts. rho < 1/4 (or E(y) not evaluable): Delta =
 * min(Delta, ||p||) / 4; rho > 3/4 with p on the boundary: Delta = min(2
 * Delta, clamp). y is accepted when rho > 1e-4, else the same system is
 * solved again in the smaller ball, up to max_ls trial steps per iteration
 * (then BS_MIN_LINE_SEARCH, or BS_MIN_FLOOR when the predicted decrease is
 * below the rounding level of E). Each solve starts at Delta_0
 * (opts.tr_radius). The forcing terms, the tolerances and the floor watch
 * are those of the line search; trial steps count as ls_evaluations, a step
 * taken has alpha 1 and trace's ls_status WOLFE.
 *
 * The baseline bs_newton (section 2): x <- x - H^-1 g with MINRES to relative
 * tolerance opts.newton_rel_tol (default 1e-10), no line search, no clamp.
 * The hooks, when given, are applied as in bs_minimize (projection of the
 * initial guess and of every iterate, registration, projected gradient); pass
 * them NULL for the pure root-finder. It stops when ||g|| < tol (converged),
 * after min(newton_max_iter, max_iter) iterations (BS_MIN_MAX_ITER), when an iterate, E or
 * the gradient becomes non-finite (BS_MIN_NONFINITE; x keeps the last finite
 * iterate), or as soon as it diverges (BS_MIN_DIVERGED, x the last iterate):
 * ||g|| more than BS_NEWTON_GROWTH times the smallest ||g|| of the solve, or
 * the smallest ||g|| not halved over BS_NEWTON_WINDOW iterations. MINRES
 * takes at most cg_max_iter iterations, or by default min(2 N + 100,
 * 100 + 20 sqrt(N)) for N free dofs: a solve that needs more than that is
 * not converging and the Newton step takes its best iterate. With k_steps > 0 it takes exactly k_steps iterations (the "k
 * Newton steps and stop" variant) and reports BS_MIN_CONVERGED if ||g|| < tol
 * after them, else BS_MIN_STEPS_DONE with grad_norm: not reaching tol is
 * by design there and is not a max-iteration failure.
 *
 * AMG reuse: the hierarchy is built (precond_matrix called at the current
 * iterate x, then bs_linsolve_amg_setup) before the first solve, when the
 * mask changes, after bs_minimizer_amg_reset, when opts.amg_rebuild_every > 0
 * calls of bs_minimize have started since the last setup, and after a solve
 * whose cost per decade of residual reduction (iterations / log10(1 /
 * relative residual), of solves that converged without a negative-curvature
 * exit) exceeds opts.amg_rebuild_factor times that of the first such solve
 * after the setup (amg_rebuild_factor 0: never), or whose V-cycle was not
 * positive definite. Setups are counted in stats.amg_setups and timed in
 * stats.t_amg_setup (also part of t_linear).
 *
 * Ownership: bs_minimizer_create copies opts and sizes every work buffer (a
 * Hessian with the pattern's sparsity, vectors, the linear-solver workspaces:
 * CG, MINRES and opts.linear) once for (n, pattern); bs_minimize and
 * bs_newton allocate nothing (CHOLMOD's numeric factorization aside). The
 * pattern is read during create only. The AMG setup allocates inside hypre. The caller owns the minimizer
 * (bs_minimizer_destroy accepts NULL and nulls the pointer). The objective and
 * its ctx are borrowed for the duration of one call. One solve at a time per
 * minimizer. stats.reason_text points into the minimizer (valid until its
 * next solve or its destruction).
 *
 * Status: bs_minimize and bs_newton return 0 when they ran, converged or not
 * (stats.reason says how it ended, stats.reason_text in words, naming the
 * iteration and, for non-finite values, the vertex). Negative codes: BS_EINPUT
 * (bad options naming the field, objective of the wrong size, a missing
 * required callback), BS_ENUMERIC (the initial x holds NaN/Inf on a free dof:
 * the message names the vertex), BS_ENOMEM, or a linear solver's error.
 *
 * Timing (seconds, stats): t_eval = value, gradient, lower-bound and hook
 * calls (project, register_active, project_gradient) wherever they happen;
 * t_assembly = hessian calls; t_linear = linear solves; t_line_search = wall
 * time of the line searches including the evaluations they make (also counted
 * in t_eval); t_total = the whole call.
 *
 * Threads: vector kernels use OpenMP with static schedules; the callbacks are
 * called from the calling thread.
 */
#ifndef BS_MINIMIZE_H
#define BS_MINIMIZE_H

#include <signal.h>
#include <stdint.h>

#include "bs_base.h"
#include "bs_bsr.h"
#include "bs_linsolve.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The search direction of an iteration (step 5 above). */
typedef enum {
  BS_DIR_NEWTON = 0,  /* the Newton direction dx (the downhill check passed)      */
  BS_DIR_NEG_DX = 1,  /* -dx (fallback_neg_dx)                                      */
  BS_DIR_NEG_GRAD = 2 /* -grad E (fallback_neg_grad)                                */
} bs_direction;

/* "newton", "neg_dx", "neg_grad"; "unknown" for a value outside the enum. */
const char *bs_direction_name(bs_direction d);

/* How a line search (step 7 above) ended. Every value but NO_DECREASE takes
 * a step. ("ls" is the line search here, as in ls_evaluations.) */
typedef enum {
  BS_LSEARCH_NO_DECREASE = -1, /* no trial point decreased E: no step (BS_MIN_LINE_SEARCH) */
  BS_LSEARCH_CAPPED = 0,       /* no Wolfe point within max_ls: the lowest trial point     */
                               /* below phi(0) (ls_failures)                              */
  BS_LSEARCH_WOLFE = 1,        /* a point that satisfies the strong Wolfe conditions       */
  BS_LSEARCH_NOISE = 2,        /* a rounding-level step of opts.accept_noise (noise_steps) */
  BS_LSEARCH_BOUND = 3         /* the step bound alpha_max (obj->max_step) itself: E still */
                               /* decreases steeply there (sufficient decrease, phi' < 0)  */
} bs_lsearch_status;

/* "no_decrease", "capped", "wolfe", "noise", "bound"; "unknown" for a value outside the enum. */
const char *bs_lsearch_status_name(bs_lsearch_status s);

/* One accepted iteration of bs_minimize (or a full step of bs_newton: alpha
 * 1, no line search, so phi, dphi0 and dphi are NaN), handed to
 * bs_objective.trace. The pointers are valid during the callback only. */
typedef struct bs_min_iter {
  int iteration;         /* 0-based index of the iteration that produced this step    */
  bs_direction direction; /* Newton dx, or a fallback (-dx, -grad E)                  */
  int clamped;           /* 1: ||dx|| was clamped to opts.clamp                      */
  int lin_iterations;    /* Krylov iterations of the Newton solve                     */
  int lin_indefinite;    /* 1: CG/PCG stopped on negative curvature                   */
  int lin_downhill_iterate; /* k > 0: dx is CG's iterate k (opts.cg_downhill)          */
  int lin_boundary;      /* 1: trust_region's CG answer lies on the boundary            */
  int cholmod_fallback;  /* 1: CHOLMOD found H not positive definite, CG was used     */
  int convexified;       /* 1: the Newton system was the convexified Hessian           */
                         /* (opts.convexify, obj->hessian_convexified)                */
  bs_lsearch_status ls_status; /* WOLFE, CAPPED (best decreasing point) or NOISE     */
                         /* (bs_newton has no line search and leaves it 0)           */
  int ls_evaluations;    /* trial points of this line search                          */
  double grad_norm;      /* ||grad E(x)|| before the step                             */
  double lin_rel_tol;    /* relative tolerance asked of the linear solver            */
  double alpha_bound;    /* obj->max_step's bound along d (+Inf without the hook)     */
  double alpha;          /* step length taken                                         */
  double phi0, dphi0;    /* E(x) and grad E(x).d                                      */
  double phi, dphi;      /* E(y) and grad E(y).d at the accepted point y             */
  const double *x;       /* 3n: the iterate before the step                          */
  const double *d;       /* 3n: the search direction (after downhill check, clamp)   */
  const double *y;       /* 3n: the accepted point P(x + alpha d)                    */
} bs_min_iter;

typedef struct bs_objective {
  int32_t n;           /* blocks (vertices); vectors have 3n doubles                   */
  const uint8_t *mask; /* n: 1 free, 0 fixed (NULL: all free). Fixed dofs never move.  */
  /* E(x). Return 0, or nonzero if x is not evaluable (the line search treats it as +Inf). */
  int (*value)(const double *x, double *E, void *ctx);
  /* E(x) and g = dE/dx (all 3n entries; the minimizer masks). Nonzero: not evaluable. */
  int (*gradient)(const double *x, double *E, double *g, void *ctx);
  /* Hessian at x assembled into H (the objective zeroes it first). Pattern fixed.
     Nonzero: not evaluable (the solve stops with BS_MIN_NONFINITE). */
  int (*hessian)(const double *x, bs_bsr *H, void *ctx);
  /* Optional (NULL): P(x) in place (section 3.2 projection onto the feasible set). */
  void (*project)(double *x, void *ctx);
  /* Optional (NULL): register the active set at feasible x with gradient g of E' (step 1). */
  void (*register_active)(const double *x, const double *g, void *ctx);
  /* Optional (NULL): an E estimate that is a lower bound of value(x), used by the line
     search to skip expensive terms (section 3.3 self-collision shortcut): if
     lower_bound > E(x_i), value() need not be called. Nonzero: not evaluable. */
  int (*value_lower_bound)(const double *x, double *E_lb, void *ctx);
  /* Optional (NULL): g <- J_P(x)^T g in place at a feasible x, i.e. grad E from
     grad E' for the pairs labeled active by the last register_active (for a level-set
     constraint with normal n at an active vertex: g_v <- g_v - (g_v.n) n). */
  void (*project_gradient)(const double *x, double *g, void *ctx);
  /* Optional (NULL): called instead of hessian, with g_raw = the unprojected gradient the
     minimizer has just computed at the same x (saves the objective recomputing it). */
  int (*hessian_g)(const double *x, const double *g_raw, bs_bsr *H, void *ctx);
  /* Optional (NULL): the convexified Hessian at x (see "Convexified model"), as
     hessian_g (g_raw given, H zeroed by the objective): the Hessian with the negative
     curvature of the terms that offer a convexified form removed (self-collision: each
     contact's Hessian projected onto the positive semidefinite cone). Nonzero: not
     evaluable (BS_MIN_NONFINITE). */
  int (*hessian_convexified)(const double *x, const double *g_raw, bs_bsr *H, void *ctx);
  /* Optional (NULL): with opts.linear = amg, the matrix the AMG preconditioner
     is built from, at x, assembled into P (the fem pattern, zeroed by the minimizer;
     extras are ignored): symmetric positive definite on the free dofs. Called only when
     a setup is due (see "AMG reuse"). Nonzero: not evaluable (BS_MIN_NONFINITE). */
  int (*precond_matrix)(const double *x, bs_bsr *P, void *ctx);
  /* Optional (NULL): called after every accepted step of bs_minimize
     and every step of bs_newton. */
  void (*trace)(const bs_min_iter *it, void *ctx);
  void *ctx;
  /* The 2-norm of the external load on the free dofs (N; e.g. gravity's forces),
     the scale of opts.load_rtol; 0 when there is none. */
  double load_norm;
  /* 1 when E is exactly quadratic in x (constant Hessian, no projection): a
     full Newton step then leaves the linear solve's residual as the gradient, so step 4
     asks the solver for min(forcing term, max(tau_eff / (4 ||g||), 1e-13)) and the
     solve ends in one or two iterations; and the rounding floor (BS_MIN_FLOOR) is
     declared after one noise-level iteration that does not halve ||g||, not three. */
  int quadratic;
  /* Optional (NULL): the step bound (see "Step bound"). The largest alpha
     such that every point x + a d, a in [0, alpha], is feasible (contact: every
     pair of surface primitives stays apart), written to *alpha_max (>= 0; +Inf
     or >= 1e10: no bound; a bound that certifies the motion x -> x + d only
     returns at most 1). Nonzero, or a NaN or negative alpha: counted as 0 (no
     step along d). With vecops every rank must return the same value. */
  int (*max_step)(const double *x, const double *d, double *alpha_max, void *ctx);
} bs_objective;

/* How an iteration finds its step from the Newton direction (bs_minimize). */
typedef enum {
  BS_GLOBAL_LINE_SEARCH = 0, /* the paper's: downhill check, clamp, strong Wolfe line search */
  BS_GLOBAL_TRUST_REGION = 1 /* Steihaug's truncated CG in a trust region (see "Trust region") */
} bs_globalization;

/* "line_search", "trust_region"; "unknown" for a value outside the enum. */
const char *bs_globalization_name(bs_globalization g);
/* The names above into *out; BS_EINPUT naming the string otherwise. */
int bs_globalization_parse(const char *name, bs_globalization *out, bs_error *err);

/* The CG forcing terms (bs_minimize_opts.forcing_ew; the scene's
 * solver.cg_forcing "paper", "eisenstat_walker", "adaptive"). */
typedef enum {
  BS_FORCING_PAPER = 0,    /* the paper's tolerance alone                                  */
  BS_FORCING_EW = 1,       /* also capped by Eisenstat & Walker's choice 2 from iteration 2 */
  BS_FORCING_ADAPTIVE = 2  /* the same cap only after an iteration that took a full step   */
} bs_forcing;

typedef struct bs_minimize_opts { /* paper defaults via bs_minimize_opts_default() */
  double tol;          /* tau, on ||grad E|| (masked 2-norm); default 1e-3 (scenes set it) */
  double rtol;         /* default 0 (off): also converged when ||g|| < rtol ||g_0||,        */
                       /* g_0 the gradient at the solve's first iterate (unitless, >= 0)    */
  double load_rtol;    /* default 0 (off): also converged when ||g|| < load_rtol *          */
                       /* obj->load_norm, the external load (unitless, >= 0). The solve's  */
                       /* tolerance is tau_eff = max(tol, rtol ||g_0||, load_rtol load)    */
                       /* (stats.tol_used); every "tol" below means tau_eff                */
  int max_iter;        /* Newton iterations cap, default 500 (>= 0)                        */
  double sigma;        /* CG tolerance scale, default 1 (> 0)                              */
  int sigma_auto;      /* default 0. 1: the tolerance's scale is sigma/sqrt(||g_0||),       */
                       /* g_0 the gradient at the solve's first iterate, so that          */
                       /* min(1/2, sigma sqrt(max(||g||, tol)/||g_0||)) has no units       */
                       /* (sigma is then a pure number: 1 gives 1/2 at the first solve)    */
  double kappa;        /* downhill check, default 1e-2 (in [0, 1))                          */
  double clamp;        /* length clamp ell, default 1e3 (> 0)                               */
  double c1, c2;       /* Wolfe constants, default 1e-4 and 0.9 (0 < c1 < c2 < 1)           */
  int max_ls;          /* line-search trial points cap per iteration, default 40 (>= 1)     */
  int naive_guess;     /* 1: take at least one iteration even if ||g|| < tol                */
  bs_lin_kind linear;  /* cg (default), pcg, amg, cholmod (minres accepted too)            */
  int cg_max_iter;     /* Krylov iterations cap per solve; 0 (default): 2 x free dofs + 100 */
  int cg_single;       /* default 0. 1: cg, pcg and amg solves read the Hessian's           */
                       /* values in single precision from their 6th product on             */
                       /* (bs_linsolve_set_single): 40 bytes per block, not 76             */
  bs_forcing forcing_ew; /* default PAPER. EW: from the second iteration on, the CG        */
                       /* tolerance of step 4 is also capped by Eisenstat & Walker's       */
                       /* (1996) choice 2, eta_k = 0.9 (||g_k|| / ||g_k-1||)^2, kept >=    */
                       /* 0.9 eta_k-1^2 when that exceeds 0.1: solves tighten where Newton */
                       /* converges fast and stay loose where it does not. ADAPTIVE: the   */
                       /* same cap */
                       /* only after an iteration that took the full Newton step (Newton   */
                       /* direction, no negative curvature, alpha = 1 at its first trial) */
  int cg_downhill;      /* default 1. 1: a Krylov answer that fails step 5's test            */
                       /* is replaced by the last CG iterate that passed it (step 5);      */
                       /* 0: the paper's rule (-g when neither dx nor -dx passes)          */
  double newton_rel_tol; /* bs_newton's MINRES relative tolerance, default 1e-10 (> 0)    */
  int newton_max_iter;  /* bs_newton's iteration cap, default 50 (the paper's baseline takes */
                       /* 15-50; >= 1); max_iter is the optimization integrator's           */
  int accept_noise;    /* default 0 (the paper's rule: stop). 1: when the decrease a         */
                       /* step predicts, |g.d|, is below the rounding level of E            */
                       /* (64 eps |E|) and a = 1 fails sufficient decrease, search on the   */
                       /* slope for an approximate Wolfe point (Hager & Zhang 2005):        */
                       /* E(y) <= E(x) + 64 eps |E|, c2 phi'(0) <= phi'(a) <= -0.8 phi'(0), */
                       /* so that tol can go below what E resolves; counted in noise_steps */
  int64_t hessian_extra; /* room for Hessian blocks outside the pattern (bs_bsr            */
                       /* extra list, e.g. self-collision couplings), default 0; read by   */
                       /* bs_minimizer_create only                                          */
  double amg_rebuild_factor; /* AMG rebuild when the cost per decade grows past this        */
                       /* factor times the post-setup one (see "AMG reuse"); default 3;     */
                       /* 0: never (>= 0, else 0 or >= 1)                                   */
  int amg_rebuild_every; /* AMG rebuild every N bs_minimize calls; 0 (default): no         */
  bs_globalization globalization; /* default line_search (the paper's); trust_region        */
                       /* needs linear cg, pcg or amg and no vecops (see "Trust region")   */
  int convexify;       /* default 1: after a Newton system met negative curvature,        */
                       /* later iterations solve with obj->hessian_convexified (when given) */
                       /* until one takes the full Newton step of a solve of 2 or more      */
                       /* Krylov iterations (see "Convexified model"); 0: always the        */
                       /* Hessian (the paper's rule alone). Line-search globalization only */
  double tr_radius;    /* trust_region's radius at each solve's start, as an RMS          */
                       /* length per free vertex (units of x): Delta_0 = tr_radius sqrt(free */
                       /* vertices), at most clamp; default 0.1 (> 0)                      */
} bs_minimize_opts;

/* Fills the defaults listed above. */
void bs_minimize_opts_default(bs_minimize_opts *opts);

typedef enum {
  BS_MIN_CONVERGED = 0, /* ||grad E|| < tol                                                 */
  BS_MIN_MAX_ITER,      /* max_iter iterations without convergence                           */
  BS_MIN_STALLED,       /* an accepted step left every free dof unchanged (no progress)     */
  BS_MIN_LINE_SEARCH,   /* no trial point decreased E within max_ls (x unchanged)          */
  BS_MIN_NONFINITE,     /* E, grad E or H not finite / not evaluable at an iterate         */
  BS_MIN_STEPS_DONE,    /* bs_newton with k_steps > 0 took its k steps, ||g|| >= tol        */
  BS_MIN_DIVERGED,      /* bs_newton: ||g|| grew BS_NEWTON_GROWTH-fold, or did not halve    */
                        /* over BS_NEWTON_WINDOW iterations                                 */
  BS_MIN_FLOOR,         /* converged at the rounding floor of E: a CONVERGED state (see     */
                        /* "Rounding floor" above), ||g|| >= tol                            */
  BS_MIN_STOPPED        /* the stop flag (bs_minimizer_set_stop) was set: x is the iterate  */
                        /* reached, E no higher than at the start, not a solution          */
} bs_min_reason;
#define BS_FLOOR_WINDOW 3
#define BS_NEWTON_GROWTH 1e2
#define BS_NEWTON_WINDOW 20

/* "converged", "max_iter", "stalled", "line_search", "nonfinite", "steps_done",
 * "diverged", "converged_floor", "stopped". */
const char *bs_min_reason_name(bs_min_reason r);

/* 1 for the reasons that mean x is a solution: CONVERGED and FLOOR. */
int bs_min_reason_converged(bs_min_reason r);

/* iterations: accepted steps (Newton steps for bs_newton); cg_iterations: Krylov
 * iterations summed over the solves (MINRES for bs_newton); ls_evaluations: line-search
 * trial points (each one value() and/or gradient() call, or only the lower bound). */
typedef struct bs_minimize_stats {
  int iterations, cg_iterations, indefinite_exits, fallback_neg_dx, fallback_neg_grad,
      clamps, ls_evaluations, cholmod_fallbacks;
  int ls_failures;                           /* steps taken without a Wolfe point         */
  int noise_steps;                           /* steps taken by opts.accept_noise          */
  int amg_setups;                            /* AMG hierarchies built (linear = amg)        */
  int downhill_iterates;                     /* Newton directions that are an earlier        */
                                             /* CG iterate (opts.cg_downhill)              */
  int convexified;                           /* iterations that solved with the            */
                                             /* convexified Hessian (opts.convexify)       */
  int tr_rejections;                         /* trust_region trial steps rejected          */
  int tr_boundary;                           /* accepted steps on the boundary             */
  int ccd_limited;                           /* line searches (trust-region trials, Newton */
                                             /* steps) whose trial steps the bound of      */
                                             /* obj->max_step shortened                    */
  double tr_radius;                          /* trust_region radius at the end             */
  double t_amg_setup;                        /* seconds in AMG setups (in t_linear)        */
  double alpha_last, alpha_min, alpha_max;   /* alphas chosen (0 when no step was taken)   */
  double grad_norm, E;                       /* final                                      */
  double tol_used;                           /* tau_eff of this solve (N)                  */
  double t_eval, t_assembly, t_linear, t_line_search, t_total; /* seconds per phase        */
  bs_min_reason reason;
  const char *reason_text;
} bs_minimize_stats;

typedef struct bs_minimizer bs_minimizer; /* work buffers sized once for (n, pattern) */

/* opts NULL: defaults. BS_EINPUT names the offending option or pattern field. */
int bs_minimizer_create(const bs_bsr *pattern, const bs_minimize_opts *opts, bs_minimizer **out,
                        bs_error *err);
void bs_minimizer_destroy(bs_minimizer **m);

/* Replaces the options (validated as in create; on error the old ones stay). Creates
 * the workspace of a linear solver kind not used before (allocation happens here, never
 * inside bs_minimize). */
int bs_minimizer_set_opts(bs_minimizer *m, const bs_minimize_opts *opts, bs_error *err);
/* Forces an AMG setup before the next solve (e.g. when the preconditioner matrix the
 * objective provides has changed: a new dt). No-op for NULL. */
void bs_minimizer_amg_reset(bs_minimizer *m);

/* The options in force. */
const bs_minimize_opts *bs_minimizer_opts(const bs_minimizer *m);

/* A flag (a signal handler's, say; NULL: none, the default) that bs_minimize
 * and bs_newton read before every iteration: when it is nonzero the solve
 * ends there with BS_MIN_STOPPED, x the last accepted iterate. A solve of
 * hundreds of Newton iterations (a tangled start at 824k dofs: minutes)
 * can so be stopped between two of them instead of at its end. The flag is
 * the caller's and must outlive the minimizer or be unset. With vecops
 * (bs_vecops.h) the check is collective (vecops.any): every rank must set a
 * flag or none, and a flag raised on one rank stops all ranks at the same
 * iteration. */
void bs_minimizer_set_stop(bs_minimizer *m, volatile sig_atomic_t *stop);

/* What one bs_minimize call hands the next (opts.forcing_ew = 2): whether it
 * converged by full Newton steps only, and its last forcing term. A run that
 * is stopped and continued (a checkpoint) saves and restores it so that the
 * continued solves are those of an uninterrupted run. */
typedef struct bs_min_carry {
  int full;   /* 0 or 1 */
  double eta; /* in [0, 1/2] */
} bs_min_carry;
void bs_minimizer_get_carry(const bs_minimizer *m, bs_min_carry *c);
/* Values outside the ranges above are ignored (full 0 is set). */
void bs_minimizer_set_carry(bs_minimizer *m, const bs_min_carry *c);

/* Minimizes from x (in/out). Returns 0 when it ran (converged or not: see stats.reason),
   negative on errors. st may be NULL. */
int bs_minimize(bs_minimizer *m, const bs_objective *obj, double *x, bs_minimize_stats *st,
                bs_error *err);

/* The baseline of section 2: x <- x - H^-1 g with MINRES to a tight tolerance, no line
   search; stops at ||g|| < tol (converged), after max_iter (failure recorded), or after
   exactly k_steps iterations when k_steps > 0 (the "k Newton steps and stop" variant). */
int bs_newton(bs_minimizer *m, const bs_objective *obj, int k_steps, double *x,
              bs_minimize_stats *st, bs_error *err);

#ifdef __cplusplus
}
#endif
#endif
