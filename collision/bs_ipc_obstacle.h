/* bs_ipc_obstacle.h — the IPC barrier against scripted obstacles
 * (obstacles[].collision "barrier"), with IPC's lagged smoothed Coulomb
 * friction, as one energy term (bs_terms.h) whose max_step is a continuous
 * collision detection against the obstacles' level sets.
 *
 * Vertices: the FREE surface vertices of fem->mesh (a boundary triangle's
 * vertex with mask 1; scripted vertices are never constrained by it).
 * Obstacles: added with bs_term_ipc_obstacle_add, borrowed (the level sets
 * must outlive the term), all evaluated at t = step->time (tⁿ⁺¹; 0 without
 * step data).
 *
 * Barrier. With phi_b the obstacle's level set (bs_levelset.h, phi < 0
 * inside) and s = phi_b(x_v)^2,
 *     E_B = kappa * sum_{b, v: 0 < phi_b(x_v) < dhat} b(s, dhat^2)
 * (b the log barrier of bs_ipc_barrier), gradient kappa b'(s) 2 phi grad phi,
 * Hessian kappa (4 phi^2 b''(s) grad phi grad phi^T + 2 b'(s) (grad phi
 * grad phi^T + phi Hess phi)), each vertex's 3x3 block projected onto the
 * PSD cone (bs_term_ipc_obstacle_set_project: off for finite-difference
 * tests). Where some phi_b(x_v) <= 0 (or x is not finite) value, gradient
 * and hessian return BS_TERM_NOT_EVALUABLE.
 *
 * What phi is. For every analytic shape (half-space, sphere, box, cylinder,
 * torus, and their complements) phi is the exact signed distance to the
 * surface (levelset.c: the box's and the capped cylinder's outside branches
 * are the distance to the nearest point of the solid, their inside branches
 * minus the distance to the nearest face; the torus with r < R is the
 * distance to the tube), so dhat is a distance in metres and
 * |phi(x) - phi(y)| <= |x - y|. For a grid, phi is the cubic (or trilinear)
 * interpolant of sampled distances: it differs from the true distance by the
 * interpolation error (O(h^4) in smooth regions, O(h^2) near the grid's
 * boundary and near kinks of the distance, up to a few percent of h there),
 * so the barrier keeps the INTERPOLANT positive: a vertex may lie up to that
 * error inside the true sampled surface, and dhat is measured in the
 * interpolant. A grid whose node differences exceed BS_IPC_OBSTACLE_MAX_SLOPE
 * h along an axis is not a distance (its phi is not in metres) and is
 * refused. Only vertices are tested: a surface edge or triangle may cut into
 * a convex-cornered obstacle (a sphere, a box's edge, a cylinder's rim) while
 * its vertices stay outside; against a half-space (and inside a room, the
 * complement of a convex shape) that cannot happen, since a triangle lies in
 * the convex hull of its vertices.
 *
 * CCD (max_step(x, d)): for every free surface vertex v with d_v != 0 and
 * every obstacle b, the largest fraction certified by a Lipschitz bound of
 * phi along the segment x_v + a d_v (obstacle fixed at t = step->time):
 * with L_b a bound of |grad phi_b| (1 for an analytic shape, the grid's
 * bs_ipc_obstacle_lipschitz otherwise), the rate D = L_b |d_v| (for a
 * half-space the exact rate max(0, -n.d_v)), rounded up, bounds how fast phi
 * can fall, so from a point where phi >= P the step tau = (1 - s) P / D keeps
 * phi >= s P over it. As additive CCD (bs_ccd_pt): the first step is taken
 * without evaluation, each later end is evaluated and accepted when its
 * certified lower bound phi - delta is >= the gap s phi_lo(0); the result is
 * the last accepted fraction (1 when a step passes 1; at most
 * BS_IPC_CCD_ITER steps, the cap returning the last accepted fraction).
 * delta(y) = 2^-40 (|y| + |c_b| + size_b) bounds the rounding of phi at
 * the point y evaluated (about 2000 ulps of the magnitudes involved; a
 * grid's size_b is its extent, which bounds its node values), and a start
 * with phi_lo(0) <= delta(x_v) / s^2 certifies nothing: fraction 0 (the
 * length of d does not enter: a long search direction does not make a
 * small gap uncertifiable). Over [0, result] phi stays >= s^2 phi_lo(0) > 0:
 * between accepted points by the Lipschitz bound, which holds for the true
 * function; the evaluated ends are lowered by their rounding bound. The
 * alpha of max_step is the smallest over (b, v); 1 when nothing moves.
 *
 * Moving obstacles: the energy and max_step use the obstacles at
 * step->time. The term also offers the two operations of a swept domain
 * (bs_terms.h): sweep(x, d, t0, t1), the certified fraction of the path
 * (x_v + a d_v, time t0 + a (t1 - t0)) against every obstacle, and carry,
 * which moves each free surface vertex within dhat of a moving obstacle
 * with that obstacle's material point. The integrator (bs_step.h, "Moving
 * obstacles") uses them to sweep a step whose start a moving obstacle
 * passes over, so that every point it stops at, and every path between
 * them, is certified outside the obstacles at its own time. The moving
 * CCD (bs_ccd_levelset_moving) is the additive CCD above with the rate
 * D = lip R, R a bound of the point's speed in the obstacle's frame along
 * the path: |d - dt v_b(x0, t0)| (v_b the obstacle's material velocity,
 * dt = t1 - t0) plus |dt| (dv + dw r + w (|d| + v |dt|)) with the motion's
 * bounds of bs_levelset_motion_bound_over and r = |x0 - c(t0)| + |d| +
 * v |dt|, so a point carried with the obstacle has R = 0 for a translation;
 * phi is evaluated with the frame at t0 + a dt.
 *
 * Friction (IPC, Li et al. 2020, section 5: lagged, smoothed Coulomb), for
 * obstacles added with mu > 0 and when step->dt > 0: at begin_step, from xⁿ
 * with the obstacle at tⁿ = step->time - dt, every pair (b, v) with
 * 0 < phi < dhat is listed with its normal force
 * lambda = -2 kappa phi b'(phi^2) (N), its normal n = grad phi (unit), a
 * tangent basis T (3x2, orthonormal, perpendicular to n) and the point
 * r = xⁿ_v + dt v_b(xⁿ_v) (the obstacle's material point carried over the
 * step); all fixed during the step. Then
 *     E_F = sum mu_b lambda f0(|u|),  u = T^T (x_v - r),
 *     f0(y) = -y^3 / (3 eps^2) + y^2 / eps + eps / 3  (y < eps),  y  (y >= eps),
 * eps = eps_v dt (bs_term_ipc_obstacle_set_friction; m), so that
 * f1 = f0' = 2y/eps - y^2/eps^2 below eps and 1 above: the force is
 * -mu lambda f1(|u|) T u / |u| (Coulomb's mu lambda when sliding faster than
 * eps_v, a stiff spring below). Its Hessian, mu lambda T H2 T^T with
 * H2 = (f1'(y) - f1(y)/y) u u^T / y^2 + f1(y)/y I, is PSD as it stands
 * (eigenvalues f1' and f1/y >= 0 for y <= eps; 0 and 1/y above; (2/eps) I
 * at u = 0); the kernels are bs_ipc.h's ("Friction"), shared with the
 * self-contact friction (bs_ipc_friction.h). The post-solve friction of
 * bs_obstacles.h is skipped for barrier obstacles.
 *
 * kappa: given, or IPC's initial value (bs_term_ipc_obstacle_kappa_init)
 * adapted at begin_step (bs_term_ipc_obstacle_set_adaptive) from the
 * smallest phi^2 at xⁿ of this step and the last, as bs_ipc_term.h.
 *
 * Threads: the per-vertex loops run in parallel with per-vertex results
 * summed in vertex order afterwards, so E, g and H are the same bits on any
 * thread count. Memory: everything is sized at create and add except the
 * friction pair list, which grows (amortised doubling) in begin_step only.
 *
 * Status: 0; BS_EINPUT naming the argument (dhat, kappa, eps_v, mu, a mesh
 * with no boundary, a grid that is not a distance, a term that is not this
 * one); BS_ENUMERIC for a non-finite x; BS_ENOMEM.
 */
#ifndef BS_IPC_OBSTACLE_H
#define BS_IPC_OBSTACLE_H

#include <stdint.h>

#include "bs_base.h"
#include "bs_fem.h"
#include "bs_levelset.h"
#include "bs_terms.h"

#ifdef __cplusplus
extern "C" {
#endif

#define BS_IPC_OBSTACLE_MAX_SLOPE 1.5   /* a grid's node differences / h above this: not a distance */
#define BS_IPC_OBSTACLE_EPS_V 1e-3      /* default friction smoothing speed eps_v (m/s)            */

/* The barrier term over fem->mesh's free surface vertices (mask: n_vertices
 * bytes, 1 free; NULL: all free; copied); dhat finite > 0 (m), kappa finite
 * >= 0 (J/m^4). step may be NULL (time 0, no friction, no adaptation). */
int bs_term_ipc_obstacle_create(const bs_fem *fem, const bs_step_data *step, const uint8_t *mask, double dhat,
                                double kappa, bs_term **out, bs_error *err);

/* 1 if t was made by bs_term_ipc_obstacle_create, else 0. */
int bs_term_is_ipc_obstacle(const bs_term *t);

/* Adds an obstacle (borrowed), friction mu >= 0 finite; index names it in
 * messages ("obstacle 2 (grid): ..."). A grid that is not a distance
 * (above) is BS_EINPUT. */
int bs_term_ipc_obstacle_add(bs_term *t, const bs_levelset *ls, double mu, int index, bs_error *err);

/* A bound of |grad phi| over all of space: 1 for analytic shapes; for a grid,
 * sqrt(Lx^2 + Ly^2 + Lz^2) + 1 with Lk the largest |difference| / h of
 * consecutive node values or B-spline coefficients along axis k (the
 * interpolant's derivative along k is a convex combination of those
 * differences / h, trilinear: of the values, cubic: of the coefficients,
 * whose prefilter amplifies the kinks of a sampled distance, e.g. a
 * sphere's centre, up to about 4 h: a loose bound there, making the CCD's
 * steps shorter; the +1 covers the unit-rate extrapolation outside the grid
 * box). *slope (may be NULL) gets the largest |value difference| / h over
 * the axes (0 for analytic shapes): at most 1 for sampled distances. */
double bs_ipc_obstacle_lipschitz(const bs_levelset *ls, double *slope);

/* The single-vertex CCD above: the certified fraction of the segment
 * x0 + a d, a in [0, 1], against ls at frame f with |grad phi| <= lip;
 * s in (0, 1), max_iter >= 1. Returns the fraction (0 when x0 is not
 * certifiably outside, or for non-finite input). */
double bs_ccd_levelset(const bs_levelset *ls, const bs_levelset_frame *f, double lip, const double x0[3],
                       const double d[3], double s, int max_iter);

/* The same against ls moving from time t0 to t1 along the path: the point
 * at x0 + a d meets the obstacle at time t0 + a (t1 - t0) (above, "Moving
 * obstacles"). */
double bs_ccd_levelset_moving(const bs_levelset *ls, double lip, const double x0[3], const double d[3], double t0,
                              double t1, double s, int max_iter);

int bs_term_ipc_obstacle_set_kappa(bs_term *t, double kappa, bs_error *err);
/* on = 1 (at creation): each vertex's barrier block projected onto the PSD
 * cone; 0: the exact Hessian. */
int bs_term_ipc_obstacle_set_project(bs_term *t, int on, bs_error *err);
/* Adaptive kappa per step: kappa_max > 0 and d2_eps > 0 finite; kappa_max = 0: off. */
int bs_term_ipc_obstacle_set_adaptive(bs_term *t, double kappa_max, double d2_eps, bs_error *err);
/* Friction's smoothing speed eps_v > 0 finite (m/s; BS_IPC_OBSTACLE_EPS_V at creation). */
int bs_term_ipc_obstacle_set_friction(bs_term *t, double eps_v, bs_error *err);

/* IPC's initial kappa at x from grad_energy (3n: the other terms' gradient),
 * clamped to [kappa_min, kappa_max] (as bs_term_ipc_kappa_init); set and
 * written to *kappa (may be NULL). BS_ENUMERIC when a vertex is inside. */
int bs_term_ipc_obstacle_kappa_init(bs_term *t, const double *x, const double *grad_energy, double kappa_min,
                                    double kappa_max, double *kappa, bs_error *err);

typedef struct bs_ipc_obstacle_stats {
  int64_t pairs;          /* (obstacle, vertex) pairs with phi < dhat at the last detection */
  int64_t inside;         /* of the free surface vertices, those with phi <= 0 then          */
  double min_distance;    /* smallest phi over every free surface vertex and obstacle then
                             (m; +Inf when there is no obstacle or vertex)                  */
  int64_t friction_pairs; /* pairs lagged at the last begin_step                            */
  double kappa, dhat, eps_v;
  int64_t ccd_calls, ccd_limited; /* max_step calls; of which alpha < 1                    */
} bs_ipc_obstacle_stats;

int bs_term_ipc_obstacle_stats(const bs_term *t, bs_ipc_obstacle_stats *out, bs_error *err);
/* Detects at x (time step->time) and fills out (may be NULL). */
int bs_term_ipc_obstacle_detect(bs_term *t, const double *x, bs_ipc_obstacle_stats *out, bs_error *err);
/* The term's max_step as a function: *alpha in [0, 1]. */
int bs_term_ipc_obstacle_max_step(bs_term *t, const double *x, const double *d, double *alpha, bs_error *err);

#ifdef __cplusplus
}
#endif
#endif
