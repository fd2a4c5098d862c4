/* bs_terms.h — the objective as a list of energy terms.
 *
 * A scene becomes a list of terms; a term exists only when the scene asks for
 * it. Each term offers, at a configuration x (3 doubles per vertex, metres):
 *   value(x, &E)              its energy (J) into E;
 *   gradient(x, &E, g)        its energy into E, and its gradient ADDED into g;
 *   hessian(x, H)             its Hessian ADDED into the block matrix H (the
 *                             fem pattern);
 *   begin_step(step)          optional: refresh what it lags on (xⁿ, Δt);
 *   hessian_g(x, g, H)        optional: a Newton model added into H in place
 *                             of hessian's, given g = ∇E(x) of the whole
 *                             objective (every term, unprojected); used by
 *                             the integrator only when asked
 *                             (bs_integrator_opts.penalty_secant).
 * value, gradient and hessian return a bs_term_status (as libCEED's
 * QFunctions return int): BS_TERM_OK, or BS_TERM_NOT_EVALUABLE when x lies
 * outside the term's domain, so that it has no value there (self-collision:
 * a non-finite x, or a detection that could not run). After NOT_EVALUABLE the
 * outputs (E, g, H) are unspecified (partly written, or not at all) and must
 * not be used. A term never signals "cannot evaluate" by a NaN in E, g or H;
 * a non-finite result that its arithmetic produces is returned with
 * BS_TERM_OK as it came out (the terms of this module and the penalty term
 * are defined for every x: a non-finite x, or an overflow, gives NaN/Inf).
 * The integrator (bs_step.h) passes NOT_EVALUABLE to the minimizer as an
 * objective that is not evaluable: a line search counts the point as
 * E = +Inf and shrinks the step; at an iterate the solve stops with
 * BS_MIN_NONFINITE (as it does for a non-finite E).
 * Terms read the step data (Δt, x̂, xⁿ) through the bs_step_data pointer
 * given at creation, which the integrator owns and updates each step.
 *
 * The terms of this module (paper sections 2.1, 4.1, 4.2):
 *   inertia     1/(2cΔt²) (x − x̂)ᵀ M (x − x̂) (c: step->c, 1 for backward
 *               Euler; x̂ the integrator's x̃, bs_step.h)
 *   gravity     −Σ m_v gᵀ x_v (tet10: −Σ (ρ ∫ N_v) gᵀ x_v, the consistent body load)
 *   elasticity  Σ_tets V Ψ(F), one model and parameter set per material group
 *   damping     1/(2Δt) (x − xⁿ)ᵀ D (x − xⁿ), D = Σ_tets k_material H_tet⁺(xⁿ),
 *               H⁺ the PSD-projected elastic Hessian at xⁿ (lagged Rayleigh
 *               damping, refreshed each step; k in seconds)
 *   drag        k/(2Δt) (x − xⁿ)ᵀ M (x − xⁿ)
 *
 * Ownership: a term is created by its bs_term_*_create, owned by the caller
 * and freed with bs_term_destroy. It keeps pointers to the fem cache and the
 * step data, which must outlive it.
 */
#ifndef BS_TERMS_H
#define BS_TERMS_H

#include <stdint.h>

#include "bs_base.h"
#include "bs_bsr.h"
#include "bs_fem.h"

#ifdef __cplusplus
extern "C" {
#endif

/* What the integrator sets before each solve. */
typedef struct bs_step_data {
  double dt;           /* time step (s); 0 in a static solve                   */
  const double *x_hat; /* x̃: xⁿ + Δt vⁿ (backward Euler; bs_step.h for others) */
  const double *x_n;   /* positions at the start of the step                    */
  double time;         /* tⁿ⁺¹                                                  */
  double load;         /* load factor on external loads (gravity); 1 normally  */
  /* The integrator's c (bs_step.h): inertia is 1/(2 c Δt²) ‖x − x_hat‖²_M,
     x_hat the integrator's x̃. 0 (step data made without it) reads as 1,
     backward Euler's. */
  double c;
} bs_step_data;

typedef struct bs_term bs_term;

/* What a term is, set by its constructor (bs_term_create: BS_TERM_CUSTOM):
 * the integrator and the force reports pick terms by kind, never by name. */
typedef enum {
  BS_TERM_CUSTOM = 0, /* a caller's term (bs_term_create)         */
  BS_TERM_INERTIA,
  BS_TERM_GRAVITY,
  BS_TERM_ELASTICITY,
  BS_TERM_DAMPING,
  BS_TERM_DRAG,
  BS_TERM_PENALTY,    /* an obstacle's penalty (bs_penalty.h)      */
  BS_TERM_SELF_COLLISION,
  BS_TERM_BARRIER_CONTACT /* IPC's barrier between surfaces (bs_ipc_term.h) */
} bs_term_kind;

/* What value, gradient and hessian return (see the top of this header). */
typedef enum {
  BS_TERM_OK = 0,           /* evaluated: the outputs hold the term's value(s)           */
  BS_TERM_NOT_EVALUABLE = 1 /* x is outside the term's domain: the outputs are unspecified */
} bs_term_status;

/* "ok", "not_evaluable"; "?" for a value outside the enum. */
const char *bs_term_status_name(bs_term_status s);

typedef struct bs_term_ops {
  int (*value)(const bs_term *t, const double *x, double *E);              /* E out           */
  int (*gradient)(const bs_term *t, const double *x, double *E, double *g); /* E out, g added */
  int (*hessian)(const bs_term *t, const double *x, bs_bsr *H);             /* H added        */
  int (*begin_step)(bs_term *t, bs_error *err); /* may be NULL */
  void (*destroy_data)(void *data);             /* may be NULL */
  /* May be NULL: the Hessian with its negative curvature removed, added into H
     (self-collision: each contact's Hessian projected onto the positive
     semidefinite cone). The minimizer's convexified model (bs_minimize.h,
     "Convexified model") takes it in place of hessian. */
  int (*hessian_convexified)(const bs_term *t, const double *x, bs_bsr *H);
  /* May be NULL: a Newton model that uses the other terms' forces, added into
     H in place of hessian's, given g = grad E(x) of the whole objective at x
     (the penalty's secant model: bs_penalty.h). Not a second derivative, so
     not checked against differences of the gradient; it must tend to the
     Hessian as x tends to a minimizer. */
  int (*hessian_g)(const bs_term *t, const double *x, const double *g, bs_bsr *H);
  /* May be NULL: the largest alpha such that x + a d stays in the term's domain
     for every a in [0, alpha] (barrier contact: continuous collision detection
     certifies that no two surface primitives touch), written to *alpha (in
     [0, 1]: 1 when the whole motion x -> x + d is certified). The integrator
     hands the smallest over its terms to the minimizer as the line search's
     bound (bs_minimize.h, obj->max_step, "Step bound") and clips its initial
     guesses with it. A bs_term_status: NOT_EVALUABLE when it cannot run (a
     non-finite x or d). */
  int (*max_step)(const bs_term *t, const double *x, const double *d, double *alpha);
  /* May be NULL (a term that does not depend on scripted motion in time):
     for a term whose domain moves with time (barrier obstacles: a moving
     obstacle), the largest s in [0, 1] such that the path
     a -> (x + a d, time t0 + a (t1 - t0)), a in [0, s], stays in the
     domain (d NULL: x fixed), certified as max_step is, into *s. The
     integrator sweeps such terms from tⁿ to tⁿ⁺¹ within a step (bs_step.h,
     "Moving obstacles"). A bs_term_status, as max_step. */
  int (*sweep)(const bs_term *t, const double *x, const double *d, double t0, double t1, double *s);
  /* May be NULL. For the sweep's predictor (bs_step.h, "Moving
     obstacles"). A term with sweep: the vertices its moving domain carries
     from time t0 to t1 (barrier obstacles: each free surface vertex within
     dhat of a moving obstacle at t0, moved with the obstacle's material
     point), their displacement written into z (3n) and carried[v] set to 1;
     other entries untouched. A term without sweep: the vertices it carries
     along with those already carried (barrier contact: every vertex of an
     active pair at x that has a carried vertex gets that vertex's z and is
     marked), other entries untouched; called again while the integrator's
     closure adds vertices. A bs_term_status. */
  int (*carry)(const bs_term *t, const double *x, double t0, double t1, double *z, uint8_t *carried);
} bs_term_ops;

struct bs_term {
  const char *name;          /* "inertia", "gravity", ... (for messages)           */
  bs_term_kind kind;
  const bs_term_ops *ops;
  const bs_fem *fem;
  const bs_step_data *step;
  int dynamic_only;          /* 1: skipped in static solves (inertia, damping, drag) */
  int expensive;             /* 1: may be skipped in line searches (section 3.3)    */
  int quadratic;             /* 1: E is a polynomial of degree <= 2 in x (constant   */
                             /* Hessian): inertia, gravity, damping, drag, and      */
                             /* elasticity when every material is linear            */
  int external;              /* 1: an external load (gradient independent of x:     */
                             /* gravity); its force sets the load of load_rtol      */
  int64_t hessian_extra;     /* most Hessian blocks it adds outside the fem pattern  */
                             /* (bs_bsr extra list; 0 for every term but self-collision) */
  void *data;
};

int bs_term_inertia_create(const bs_fem *fem, const bs_step_data *step, bs_term **out, bs_error *err);
/* Gravity scaled by step->load (step may be NULL: factor 1). */
int bs_term_gravity_create(const bs_fem *fem, const bs_step_data *step, const double g[3], bs_term **out,
                           bs_error *err);
/* project_psd (a bs_psd_mode, bs_material.h): BS_PSD_NONE the exact element
 * Hessians, BS_PSD_ALL every one projected onto the PSD cone (an option for
 * Newton), BS_PSD_INVERTED those of inverted tets only (det F <= 0: a tangle's
 * indefiniteness removed where it is worst, the exact Hessian elsewhere).
 * BS_EINPUT for another value, and for BS_PSD_AUTO, which needs the step
 * (below). */
int bs_term_elastic_create(const bs_fem *fem, bs_psd_mode project_psd, bs_term **out, bs_error *err);
/* The same with the step data (borrowed; may be NULL but for BS_PSD_AUTO):
 * BS_PSD_AUTO gives a tet BS_PSD_INVERTED at every Hessian when its
 * mu dt^2 / (rho h^2) >= BS_PSD_AUTO_RATIO (dt = step->dt then, h =
 * (6 sqrt 2 V)^(1/3) the edge of the regular tet of its rest volume V; a
 * static solve, dt = 0: every tet), BS_PSD_NONE otherwise: a rule of the tet
 * alone, so a distributed mesh gives the serial choice. Where inertia
 * dominates the step's Hessian (M / dt^2 against the elastic stiffness), the
 * exact Hessian with CG's negative-curvature exit does better than any fix;
 * where stiffness dominates, the inverted tets' indefiniteness sends CG out
 * after a few iterations (docs/design/project-hessian.md: the measurements). */
int bs_term_elastic_create_step(const bs_fem *fem, const bs_step_data *step, bs_psd_mode project_psd, bs_term **out,
                                bs_error *err);
/* k: one coefficient per fem material (seconds, >= 0). */
int bs_term_damping_create(const bs_fem *fem, const bs_step_data *step, const double *k, bs_term **out,
                           bs_error *err);
int bs_term_drag_create(const bs_fem *fem, const bs_step_data *step, double k, bs_term **out, bs_error *err);

/* A term of the caller's: `name` (kept as a pointer: a string literal or one
 * that outlives the term), the callbacks `ops` (value, gradient and hessian
 * required; kept as a pointer too), the fem cache and step data it reads, and
 * its data (freed by ops->destroy_data when the term is destroyed, and also
 * when this fails). dynamic_only, expensive, quadratic, external and hessian_extra start at 0: set
 * them on the term before it is used. The Hessian callback adds into the
 * fem's pattern (bs_fem_scatter_hessian, or H->diag[v] for a vertex's own
 * block). Example: examples/02_spring. */
int bs_term_create(const char *name, const bs_term_ops *ops, const bs_fem *fem, const bs_step_data *step, void *data,
                   bs_term **out, bs_error *err);

void bs_term_destroy(bs_term **t);

#ifdef __cplusplus
}
#endif
#endif
