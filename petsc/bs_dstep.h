/* bs_dstep.h — the integrator of physics/bs_step.h (one integrator: its
 * steps, guesses, scripted vertices, projection, choice of the initial guess
 * and statistics are bs_integrator's) on a distributed mesh: this module is
 * its petsc backend (bs_step_backend.h): the terms of a dfem summed and
 * assembled over the ranks, dot products over owned dofs, the Newton system
 * solved by bs_dlinsolve.h's CG (min.linear picks the preconditioner: cg
 * none, pcg point-block Jacobi, amg GAMG, built at rest).
 *
 * x, v: bs_dfem local vectors (3 per local vertex, consistent). The terms
 * (set on the dfem with bs_dfem_set_terms) were created with `step`, whose
 * x_hat and x_n the backend points at its own arrays in the local mesh's
 * order. mask: 1 free, 0 scripted or fixed, per local vertex (consistent).
 * script: the positions of the masked vertices at a time, on a local vector.
 * What the backend does not run is refused by bs_step_refuse (BS_EINPUT):
 * self-collision, post-solve hooks (friction, postprocess collisions), the
 * Newton baseline, opts.trace, solver.linear other than cg, pcg, amg, the
 * trust region, the AMG built at the iterate.
 *
 * Collective. Ownership: borrows dfem, step, the terms and the hooks' ctx;
 * the integrator copies the mask.
 * Status: as bs_step.h.
 */
#ifndef BS_DSTEP_H
#define BS_DSTEP_H

/* bs_step.h first: <complex.h>, which PETSc includes, defines I. */
#include "bs_step.h"
#include "bs_step_backend.h"
#include "bs_dfem.h"
#include "bs_dlinsolve.h"

#ifdef __cplusplus
extern "C" {
#endif

/* What the petsc backend runs beyond the optimization integrator
 * (bs_step_backend.h, BS_STEP_CAN_*): nothing more. */
#define BS_DSTEP_CAPS 0u

typedef struct bs_dintegrator bs_dintegrator;

int bs_dintegrator_create(bs_dfem *df, bs_step_data *step, const uint8_t *mask, bs_script_fn script, void *script_ctx,
                          const bs_integrator_opts *opts, bs_dintegrator **out, bs_error *err);
void bs_dintegrator_destroy(bs_dintegrator **D);

/* The constraint hooks of bs_step.h made for dfem->fem (e.g. bs_obstacles_hooks
 * on it, with bs_obstacles_set_owned and _set_bounds): each call gets copies
 * of the local vectors x and g in the local mesh's order (dfem->fem's, the
 * order the hooks index), and what project and project_gradient change is
 * written back and made consistent on the ghosts (every rank must compute
 * the same for a vertex it shares: x and g are consistent). project_hessian
 * gets each rank's partial Hessian over its owned cells before the assembly
 * (bs_dfem_hessian_with), so a block it adds per vertex must be added on one
 * rank only. hooks NULL: none. BS_EINPUT for a post_solve hook
 * (bs_step_refuse). Not collective; call before a step. */
int bs_dintegrator_set_hooks(bs_dintegrator *D, const bs_step_hooks *hooks, bs_error *err);

/* Statics in load_steps increments (as bs_integrator_static). */
int bs_dintegrator_static(bs_dintegrator *D, double t, int load_steps, double *x, bs_step_stats *st, bs_error *err);

/* One step of size dt from t (as bs_integrator_step). */
int bs_dintegrator_step(bs_dintegrator *D, double t, double dt, double *x, double *v, bs_step_stats *st,
                        bs_error *err);

/* The minimizer's state carried from one solve to the next (bs_min_carry in
 * bs_minimize.h): a frame that is undone puts it back. Not collective. */
void bs_dintegrator_get_carry(const bs_dintegrator *D, bs_min_carry *c);
void bs_dintegrator_set_carry(bs_dintegrator *D, const bs_min_carry *c);

/* The stop flag of the integrator's solves (as bs_integrator_set_stop; NULL:
 * none), read before every Newton iteration collectively: set it on every
 * rank or on none; raised on any rank, it ends every rank's solve at the
 * same iteration with reason BS_MIN_STOPPED and failed = 1, at a state that
 * is not the step's solution (undo it); statics take no further load step.
 * Not collective. */
void bs_dintegrator_set_stop(bs_dintegrator *D, volatile sig_atomic_t *stop);

/* The integrator itself (bs_step.h; its vectors are local vectors). */
bs_integrator *bs_dintegrator_integrator(bs_dintegrator *D);

/* The linear solver (GAMG figures: bs_dlin_info). */
const bs_dlin *bs_dintegrator_linsolve(const bs_dintegrator *D);

#ifdef __cplusplus
}
#endif
#endif
