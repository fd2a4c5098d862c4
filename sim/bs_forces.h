/* bs_forces.h — forces of a simulation's current state, per vertex (N): the
 * elastic force, the contact force of the obstacles and of self-collision,
 * and the reaction a scripted group's support supplies.
 *
 * Definitions (E the step's objective as the integrator minimizes it, in J,
 * its gradient in N; bs_terms.h; in a static solve the dynamic-only terms,
 * inertia, damping and drag, are left out):
 *   elastic   f_e = -dPhi_e/dx (the terms named "elasticity"); sums to zero
 *             over a body (translation invariance);
 *   residual  r = dE/dx over every term: zero at the free vertices of a
 *             converged step (to the tolerance); at a scripted vertex the
 *             force its support must apply to keep it on its path;
 *   contact   penalty obstacles and self-collision: minus the gradient of
 *             their terms; a constraint obstacle b: at a free vertex p that
 *             touches it (|phi_b(x_p)| <= 1e-8 of the scene size) with
 *             r'_p . n > 0, r' the residual without the contact terms and
 *             n = grad phi_b / |grad phi_b|, the force (r'_p . n) n: the
 *             constraint's multiplier, which balances the normal part of
 *             the other forces at the converged step (paper 5.1);
 *   reaction  R = sum over the group's vertices of r_i (the force the
 *             support applies to the body: in a static clamped beam, the
 *             body's weight, upwards).
 * Friction is applied after the solve as a velocity change, not as a force
 * of the objective: it is not in these figures.
 *
 * The caller owns every output (3 n_vertices doubles; the reaction 3). The
 * functions allocate one 3n scratch vector per call (they are for output,
 * once per frame, not for the Newton loop). Status: 0, BS_ENUMERIC when a
 * term is not evaluable at the state (the message names it), BS_ENOMEM.
 *
 * Example:
 *     double *f = malloc(sizeof(double) * 3 * s->mesh->n_vertices), R[3];
 *     if (bs_sim_force_elastic(s, f, &err)) ...;
 *     if (bs_sim_reaction(s, &s->scripts[0], R, &err)) ...; R[1]: the clamp's vertical force
 */
#ifndef BS_FORCES_H
#define BS_FORCES_H

#include "bs_base.h"
#include "bs_sim.h"

#ifdef __cplusplus
extern "C" {
#endif

int bs_sim_force_elastic(const bs_sim *s, double *f, bs_error *err);
int bs_sim_force_residual(const bs_sim *s, double *r, bs_error *err);
/* obstacle: an obstacle index, or -1 for every obstacle and self-collision. */
int bs_sim_force_contact(const bs_sim *s, int obstacle, double *f, bs_error *err);
int bs_sim_reaction(const bs_sim *s, const bs_sim_script *group, double R[3], bs_error *err);

#ifdef __cplusplus
}
#endif
#endif
