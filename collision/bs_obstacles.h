/* bs_obstacles.h — collisions of the simulated body with scripted obstacles
 * (paper sections 3.2, 3.3, 5.1, 5.2, Figure 10): constraints by gradient
 * projection, penalties, the post-process baseline, and Coulomb friction.
 *
 * An obstacle is a level set phi_b (bs_levelset.h, phi < 0 inside) and a mode:
 *
 *  constraint (5.1, 3.2)  phi_b(x_p) >= 0 is enforced by the minimizer through
 *      the integrator hooks. All obstacles are evaluated at t = step->time
 *      (t^{n+1}). With P_bp(x) = x - phi_b(x) grad phi_b(x):
 *      - project: P(x) applies, for every free vertex p and every constraint
 *        obstacle b IN THE ORDER THEY WERE ADDED, P_bp to x_p when (b, p) is
 *        labeled active or violated (phi_b(x_p) < 0); P = P_B o ... o P_1.
 *        Beyond the paper: an active pair outside the obstacle is projected
 *        only while grad phi_b there is within 45 degrees of its normal at
 *        registration; past an edge or corner (a box) it is released, left
 *        free, because projecting would pull a vertex sliding off a face back
 *        onto the edge, where it stays stuck and the line search fails (the
 *        paper-scale figure 13 failed 6 of its first 9 steps that way, a
 *        constraint box striker 6 of 30). Scripted vertices (mask 0) are
 *        never moved. Each call also records which pairs it projected.
 *      - register_active(x, g'): at a feasible x, with g' = grad E'(x), the
 *        pair (b, p) is active when it touches, |phi_b(x_p)| <= tol_b, and
 *        g'_p . grad phi_b(x_p) >= 0; every other pair is inactive.
 *        tol_b = 1e-12 (L + |c_b(t)| + s_b): L is the scene size (the rest
 *        mesh's bounding-box diagonal plus its largest coordinate), c_b the
 *        obstacle's centre and s_b its largest shape parameter, i.e. about
 *        4500 ulps of the coordinates involved, well above the round-off of
 *        phi(P(x)) and far below any physical gap. It also forgets the pairs
 *        recorded by the last projection.
 *      - project_gradient(x, g): g <- J_P(x)^T g, with J_P = J_B ... J_1 and
 *        J_b = I - n n^T (n = grad phi_b(x_p)) for the pairs that were
 *        projected by the last call of project (a released pair was not), or,
 *        right after register_active, the active pairs (applied from B down
 *        to 1, the transpose of the composition). At a registered iterate only
 *        the active pairs count (register_active has just forgotten the
 *        projected ones); at a line-search point y = P(x + a d) the pairs the
 *        projection moved count (active pairs it kept on the surface among
 *        them), so that the slope grad E(y).d of the curved search path sees
 *        the constraint (the curvature term phi Hess phi of J_P at the
 *        unprojected point is dropped there).
 *      - project_hessian(x, g', H): the Hessian of E = E' o P at a feasible x.
 *        For one projection at a touching vertex (phi = 0, so the third
 *        derivatives of phi drop, paper 3.2 "Derivatives"):
 *            d^2 P_i / dx_j dx_k = -(n_i A_jk + n_j A_ik + n_k A_ij),
 *        A = Hess phi, hence
 *            H = J^T H' J + C,   C_jk = -[(g'.n) A_jk + n_j (A g')_k + (A g')_j n_k]
 *        with J block diagonal (J_p = I - n n^T at active vertices, I
 *        elsewhere). Several obstacles active at one vertex compose: from
 *        b = B down to 1, C <- J_b C J_b + C_b(g_b), g_{b-1} = J_b g_b,
 *        J <- J J_b. The hook returns this Hessian on the tangent space of
 *        the active pairs: each block (p, q) becomes J_p^T H'_pq J_q and
 *        J_p^T C_p J_p is added to the diagonal block (for one obstacle
 *        -(g'.n) J A J, the curvature term of the Hessian on the constraint
 *        surface); the block pattern is unchanged, and the rows and columns
 *        along an active normal are zero, so a linear solve stays in the
 *        tangent space. d^T H d is E's exact second derivative along every d
 *        with J d = d (and H d = J^T H_E d, H_E the full Hessian, for one
 *        obstacle per vertex: the test's FD check). Why not C itself (the paper's formula): E is constant along
 *        the normal line of a touching vertex (P maps it to one point), yet
 *        C n = -A g' couples the normal to the tangent plane wherever the
 *        tangential force A g' is not zero on a curved obstacle, so the full
 *        Hessian is indefinite (a zero n-n entry beside that coupling) in a
 *        direction whose only effect is to rescale the tangential motion
 *        through the curvature. On a plane A = 0 and both agree.
 *      Friction (5.1): the collision force on a vertex of an active pair at
 *      x^{n+1} is grad E'(x) - grad E(x) = n (g'_p . n), of magnitude
 *      |f| = g'_p . n (the pairs are re-labeled at x^{n+1} with the rule above).
 *      Needs an analytic level set (projection exact and idempotent).
 *
 *  penalty (5.2)  the energy term k (-phi)^3 of bs_penalty.h for every vertex,
 *      handed to the integrator by bs_obstacles_terms. Friction: |f| is the
 *      penalty force 3 k phi^2 at x^{n+1} on each penetrating vertex, n its
 *      direction. The paper applies friction opposite the component of the
 *      discrete acceleration perpendicular to f. The solve has no tangential
 *      contact force, so the tangential part of (x^{n+1} - x^n - dt v^n)/dt^2
 *      is nearly zero for a sliding vertex; we take the discrete acceleration
 *      that would bring the vertex to rest relative to the obstacle,
 *      (x^{n+1} - x^n - dt v_obs)/dt^2, whose tangential part is v_t/dt
 *      (v_t: relative tangential velocity), and apply the Coulomb impulse
 *      opposite it, clamped so that it only removes tangential velocity.
 *
 *  barrier  IPC's barrier on phi and its friction, inside the minimization:
 *      not this module's (bs_ipc_obstacle.h; the caller builds the term and
 *      calls bs_obstacles_allow_barrier before adding one). Here a barrier
 *      obstacle has no hook, no term and no post-solve friction; it counts in
 *      bs_obstacles_penetration.
 *
 *  postprocess (the Figure 10 baseline)  ignored by the solve; after it,
 *      every free vertex with phi_b(x_p) < 0 is pushed to P_bp(x_p) (depth
 *      d = -phi), and the normal component of its velocity relative to the
 *      obstacle is set to zero if it points inward (no inward velocity).
 *      Friction: |f| is estimated from the push, m_p d / dt^2.
 *
 * Friction (all modes, Coulomb, coefficient mu_b >= 0, after the solve, in
 * the post_solve hook, obstacles in the order added): with v_t the tangential
 * part (perpendicular to n) of v_p - v_obs(x_p) (bs_levelset_velocity),
 *     v_p <- v_p - min(1, mu |f| dt / (m_p |v_t|)) v_t,
 * i.e. the tangential speed drops by mu |f| dt / m_p, clamped at zero. It
 * never moves a vertex (only the postprocess push does), and against a static
 * obstacle it never increases the kinetic energy. mu = 0 changes nothing.
 *
 * Units: SI (m, s, kg); stiffness k in J/m^3; friction mu dimensionless.
 *
 * Ownership: bs_obstacles_create returns an object owned by the caller (free
 * with bs_obstacles_destroy: NULL accepted, pointer nulled). It borrows the
 * fem and the step data (which must outlive it and are those of the
 * integrator) and copies the mask. bs_obstacles_add takes ownership of the
 * level set, also when it fails. The penalty terms belong to the obstacles.
 * The hooks (bs_obstacles_hooks) point at o: call it after the last add.
 * Work buffers are sized at create and add: the hooks allocate nothing.
 * The active set lives in o and is cleared after each step (post_solve) and
 * whenever step->time changes, so that a step never starts from the last
 * step's labels. One integrator per bs_obstacles.
 *
 * Part of a distributed mesh (the petsc backend, petsc/): a process whose fem
 * covers only its own cells marks the vertices it owns (bs_obstacles_set_owned,
 * each shared vertex owned by one process) and gives the whole scene's rest
 * box (bs_obstacles_set_bounds, so that tol_b is the serial one). With x and
 * g' consistent over the processes, project, register_active and
 * project_gradient then give the same values on every process that holds a
 * vertex, and project_hessian, applied to each process's partial Hessian
 * H'_r (J^T H' J is linear in H'), adds C_p only where p is owned, so that
 * the sum over the processes is the serial H. Counts and penalty terms take
 * the owned vertices only. Without set_owned (the default) every vertex is
 * owned and nothing changes.
 *
 * Status: 0; BS_EINPUT for a bad argument (the message names the obstacle by
 * index and shape: "obstacle 1 (grid): ..." and the value), BS_ENOMEM.
 */
#ifndef BS_OBSTACLES_H
#define BS_OBSTACLES_H

#include <stdint.h>

#include "bs_base.h"
#include "bs_fem.h"
#include "bs_levelset.h"
#include "bs_step.h"
#include "bs_terms.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum { BS_COLLIDE_CONSTRAINT = 0, BS_COLLIDE_PENALTY, BS_COLLIDE_POSTPROCESS, BS_COLLIDE_BARRIER } bs_collide_mode;

/* "constraint", "penalty", "postprocess", "barrier"; anything else is
 * BS_EINPUT naming it. */
int bs_collide_mode_parse(const char *name, bs_collide_mode *out, bs_error *err);
const char *bs_collide_mode_name(bs_collide_mode mode);

typedef struct bs_obstacles bs_obstacles;

/* mask: n_vertices bytes, 1 free / 0 scripted (NULL: all free), copied. */
int bs_obstacles_create(const bs_fem *fem, const bs_step_data *step, const uint8_t *mask, bs_obstacles **out,
                        bs_error *err);
void bs_obstacles_destroy(bs_obstacles **o);

/* owned: n_vertices bytes, 1 for the vertices this process counts (copied;
 * NULL: all, the default). A vertex that is not owned is still projected,
 * labeled and its gradient and Hessian blocks transformed, but
 * project_hessian does not add its curvature block C, the penalty terms of
 * later adds leave it out (bs_term_penalty_create_subset over the owned
 * vertices), and bs_obstacles_active_count and the count of
 * bs_obstacles_penetration skip it. BS_EINPUT once an obstacle was added,
 * BS_ENOMEM. */
int bs_obstacles_set_owned(bs_obstacles *o, const uint8_t *owned, bs_error *err);

/* The scene size L of the touching tolerance from the rest box [lo, hi] (m)
 * of the whole scene instead of the fem's mesh (a process's part of it). */
void bs_obstacles_set_bounds(bs_obstacles *o, const double lo[3], const double hi[3]);

/* Adds obstacle number bs_obstacles_count(o) (0-based). Takes ownership of
 * ls. constraint needs an analytic level set (error naming the obstacle
 * otherwise); stiffness k > 0 is the penalty's (ignored otherwise); friction
 * mu >= 0 and finite. barrier (IPC's barrier: bs_ipc_obstacle.h) is only
 * recorded here (no hook, no term, no post-solve friction: the caller builds
 * the barrier term over bs_obstacles_levelset) and needs
 * bs_obstacles_allow_barrier first: a caller that builds no barrier term
 * gets BS_EINPUT naming the obstacle rather than an obstacle nothing
 * enforces. */
int bs_obstacles_add(bs_obstacles *o, bs_levelset *ls, bs_collide_mode mode, double stiffness, double friction,
                     bs_error *err);
int bs_obstacles_count(const bs_obstacles *o);
/* Declares that the caller builds the barrier term of the barrier obstacles. */
void bs_obstacles_allow_barrier(bs_obstacles *o);
/* Obstacle i's mode (BS_COLLIDE_CONSTRAINT when i is out of range) and friction (0 then). */
bs_collide_mode bs_obstacles_mode(const bs_obstacles *o, int i);
double bs_obstacles_friction(const bs_obstacles *o, int i);
/* Obstacle i's level set (owned by o), or NULL when i is out of range. */
const bs_levelset *bs_obstacles_levelset(const bs_obstacles *o, int i);

/* The penalty terms to hand to the integrator (owned by o); returns their
 * number, *terms pointing at them (valid until the next add). */
int bs_obstacles_terms(const bs_obstacles *o, bs_term *const **terms);

/* Fills the integrator hooks with o as ctx: project, register_active,
 * project_gradient and project_hessian when there is a constraint obstacle
 * (NULL otherwise), post_solve when there is any obstacle (NULL otherwise). */
void bs_obstacles_hooks(bs_obstacles *o, bs_step_hooks *hooks);

/* Audit: the free vertices deeper than tol >= 0 (m) inside some obstacle at
 * time t (phi_b < -tol for some b) and the largest depth max(-phi_b) over all
 * free vertices (0 when none is inside; it may be below tol, e.g. the
 * rounding of a projection onto phi = 0). Either output may be NULL. */
void bs_obstacles_penetration(const bs_obstacles *o, double t, const double *x, double tol, int32_t *count,
                              double *max_depth);

/* Where post_solve records friction's velocity change (3 per vertex, m/s;
 * the caller's array, which must outlive o; NULL stops it): zeroed at the
 * start of each post_solve, then the sum over obstacles of what friction
 * removed from each vertex's velocity (the postprocess push is not in it). */
void bs_obstacles_friction_output(bs_obstacles *o, double *dv);

/* The number of (obstacle, vertex) pairs labeled active by the last
 * register_active (0 after a step ends, i.e. after post_solve), over the
 * owned vertices. */
int32_t bs_obstacles_active_count(const bs_obstacles *o);

/* The hooks themselves (ctx = the bs_obstacles), exposed for tests and for
 * callers that chain several post-solve actions. */
void bs_obstacles_project(double *x, void *ctx);
void bs_obstacles_register_active(const double *x, const double *g, void *ctx);
void bs_obstacles_project_gradient(const double *x, double *g, void *ctx);
void bs_obstacles_project_hessian(const double *x, const double *g, bs_bsr *H, void *ctx);
int bs_obstacles_post_solve(const double *x_n, double *x, const double *g, double *v, double dt, void *ctx,
                            bs_error *err);

#ifdef __cplusplus
}
#endif
#endif
