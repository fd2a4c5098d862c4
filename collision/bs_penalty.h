/* bs_penalty.h — object penalty collisions (paper section 5.2) as an energy
 * term (bs_terms.h).
 *
 * For each vertex p of a set (all vertices of the mesh by default) against
 * one level set phi (bs_levelset.h, inside negative), evaluated at the step's
 * time t = step->time (0 when step is NULL):
 *     Phi_p(x) = k (-phi(x_p))^3   if phi(x_p) < 0,   0 otherwise.
 * The paper writes k phi^3; with phi < 0 inside that is negative, so it must
 * be read as k |phi|^3 = -k phi^3: the energy is >= 0 and grows with depth.
 * Derivatives (exact, from the exact grad and Hessian of phi):
 *     dPhi/dx   = -3 k phi^2 grad phi,
 *     d2Phi/dx2 = -6 k phi grad phi grad phi^T - 3 k phi^2 Hess phi,
 * all three vanishing at phi = 0, so the energy is C^2 across the surface
 * (for a C^2 phi). The penalty force on a vertex, f = -dPhi/dx =
 * 3 k phi^2 grad phi, points out of the obstacle. Each vertex's Hessian is a
 * 3x3 block on the diagonal of H.
 *
 * Secant model (the term's hessian_g, bs_terms.h; used by the integrator with
 * bs_integrator_opts.penalty_secant): given g, the whole objective's gradient
 * at x, the coefficient -6 k phi = 6 k depth of grad phi grad phi^T is
 * replaced by 3 k (depth + depth*), the slope of the penalty's force between
 * the vertex's depth and depth* = sqrt(F / (3 k |grad phi|)), where the
 * penalty balances F, the other terms' push into the obstacle along grad phi
 * (F = (g_v - dPhi/dx_v) . grad phi / |grad phi|; depth* = 0 when they pull
 * outwards). Why: along the normal the penalty's gradient is 3 k depth^2, and
 * Newton on it from depth >> depth* goes half-way (the gradient falls 4x per
 * iteration: a vertex that entered 20 times its resting depth takes 4-5
 * iterations to come back); the secant goes to depth* in one when F stays.
 * At a minimizer (g_v = 0) depth* = depth, so the model is the Hessian there
 * and Newton's local convergence is kept. The -3 k phi^2 Hess phi part stays.
 *
 * Units: k in J/m^3 (N/m^2), phi in m, energy in J, force in N.
 *
 * Threads: OpenMP over vertices; each gradient entry and diagonal block is
 * written by one thread; the energy is summed in the fixed order of bs_sum.h
 * (chunks of vertices cut by their number only, the chunk sums added in
 * order), so results are bitwise the same with any thread count.
 *
 * Ownership: the term (free with bs_term_destroy) keeps pointers to the fem,
 * the step data and the level set, which must outlive it; it copies the
 * vertex set.
 *
 * Status: 0, BS_EINPUT for a bad argument (named: k, a vertex index out of
 * range or repeated, a term that is not a penalty term), BS_ENOMEM.
 */
#ifndef BS_PENALTY_H
#define BS_PENALTY_H

#include <stdint.h>

#include "bs_base.h"
#include "bs_fem.h"
#include "bs_levelset.h"
#include "bs_terms.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The penalty of every vertex of the fem's mesh against ls; k finite > 0.
 * step may be NULL (time 0). */
int bs_term_penalty_create(const bs_fem *fem, const bs_step_data *step, const bs_levelset *ls, double k,
                           bs_term **out, bs_error *err);
/* The same over n_vertices distinct vertices (e.g. the boundary vertices). */
int bs_term_penalty_create_subset(const bs_fem *fem, const bs_step_data *step, const bs_levelset *ls, double k,
                                  int32_t n_vertices, const int32_t *vertices, bs_term **out, bs_error *err);

/* 1 if t was made by bs_term_penalty_create*, else 0. */
int bs_term_is_penalty(const bs_term *t);
/* The level set and stiffness of a penalty term (NULL / 0 for another term). */
const bs_levelset *bs_term_penalty_levelset(const bs_term *t);
double bs_term_penalty_stiffness(const bs_term *t);

/* Penalty force at a point x (3 k phi^2 grad phi when phi < 0, else 0) for
 * level set ls with stiffness k at time time; returns phi(x). */
double bs_penalty_point_force(const bs_levelset *ls, double k, double time, const double x[3], double f[3]);

/* The penalty force on every vertex at x (3 per mesh vertex, OVERWRITTEN:
 * zero for vertices outside the set or not penetrating), at step->time. */
int bs_term_penalty_forces(const bs_term *t, const double *x, double *f, bs_error *err);

/* The number of penetrating vertices (phi < 0) of the set at x and the largest
 * depth max(-phi) among them (0 when none); either output may be NULL. */
int bs_term_penalty_stats(const bs_term *t, const double *x, int32_t *count, double *max_depth, bs_error *err);

#ifdef __cplusplus
}
#endif
#endif
