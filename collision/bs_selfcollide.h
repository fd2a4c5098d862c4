/* bs_selfcollide.h — penalty self-collisions (paper section 5.3) as an energy
 * term (bs_terms.h), and self-contact friction applied after the solve.
 *
 * Detection at a configuration x (every evaluation of the term):
 *  - a surface vertex p (a vertex of a boundary triangle) collides when it
 *    lies in a closed tet none of whose vertices is p or an edge neighbour
 *    of p (exact test, bs_shim_point_in_tet >= 0). The paper (5.3) excludes
 *    only the tets that have p as a vertex; excluding the neighbours' tets
 *    too keeps a vertex that inverts its own tets clear of collisions.
 *    Contact between parts of a body closer than that (in the mesh) is left
 *    to the elastic energy. Tets are found through a bounding-volume
 *    hierarchy over tet boxes (bs_bvh.h): its topology is built at creation
 *    and rebuilt at a begin_step (at xⁿ) when its cost (bs_bvh_cost) there
 *    exceeds BS_SELF_REBUILD_GROWTH times its cost at the last rebuild, its
 *    boxes are refit at every evaluation. Which tet a vertex is found in
 *    only seeds the primitive search: the contacts do not depend on the
 *    hierarchy, so neither do the results on when it was rebuilt (a resumed
 *    run rebuilds at its first step);
 *  - the primitive of a colliding p is the feature (triangle interior, edge
 *    or vertex) of the closest triangle among the boundary triangles none of
 *    whose vertices is p or an edge neighbour of p (the others lie on p's
 *    excluded tets) and p's interface faces: the faces of p's excluded tets
 *    that they share with a tet outside that set, listed once at creation
 *    (about 100 per vertex). So the distance is to the boundary of the
 *    region where p collides, and it is 0 wherever p enters that region:
 *    through the surface, or through its own excluded neighbourhood (a
 *    vertex pushed through its own body meets Phi = 0 at the crossing and
 *    is pushed back towards its neighbourhood). More than about two edges
 *    inside another body, p can be measured to its own surface beyond its
 *    neighbours. The search starts from the distance to the triangle p
 *    collided with last (hint) or, for a new collision, to the triangle
 *    closest in the rest shape to p's rest-shape image (barycentric in the
 *    tet it is in), and gathers every triangle within that distance from a
 *    hierarchy of the boundary triangles (bs_bvh.h; built with the tets',
 *    refit to x when some vertex collides); the radius doubles when no
 *    admissible triangle is within it. The result is the exact minimum over
 *    admissible primitives (ties: the smallest triangle index), whatever
 *    the start: the hint only makes the search faster.
 *    Why this rule and not the paper's, with the tests and runs that chose
 *    it: docs/design/self-collision.md.
 *
 * Energy per colliding vertex: Phi = k d sqrt(d + eps), eps = 1e-15 m^2,
 * d = squared distance from p to its primitive, differentiated exactly with
 * respect to p and the 1, 2 or 3 primitive vertices in the primitive's region:
 *   vertex a:       d = |u|^2,                          u = p - a;
 *   edge (a, b):    d = |u|^2 - (u.e)^2/(e.e),           e = b - a;
 *   face (a, b, c): d = (u.n)^2/(n.n),                  n = (b - a) x (c - a).
 * With psi(d) = d sqrt(d + eps): grad Phi = k psi'(d) grad d,
 * Hess Phi = k (psi''(d) grad d grad d^T + psi'(d) Hess d). Phi ~ k depth^3.
 *
 * Choice within a Newton solve: the colliding set and the primitives are
 * re-detected at every evaluation (value, gradient, Hessian), as in the
 * paper, so E, grad E and H describe one function. That function is
 * continuous wherever the colliding set changes at d = 0, because the
 * primitive is the exact closest admissible one (a minimum of continuous
 * distances) and every face through which p can enter a colliding tet from a
 * non-colliding place is a primitive: a boundary triangle or an interface
 * face. It can still jump where tets overlap (inverted tets): p leaving a
 * colliding tet through a face into an inverted one that does not contain it. The term is "expensive"
 * (section 3.3): the line search may skip it when the other terms already
 * exceed E(x_i).
 *
 * Hessian blocks: a colliding vertex couples with its primitive's vertices,
 * which need not share a tet with it, so block (p, q) may be missing from the
 * fem's pattern (which the minimizer's matrix copies). bs_term hessian adds
 * every block that exists (diagonal blocks always) and puts the others in the
 * matrix's extra list (bs_bsr_add_block; the term asks for room for them in
 * term->hessian_extra = 6 per boundary vertex, which the integrator reserves
 * in the minimizer's Hessian), so that the Newton system holds the whole
 * Hessian. Blocks that find no room are dropped and counted
 * (stats.missing_blocks); bs_term_self_missing_blocks returns the off-pattern
 * blocks at x, and bs_self_coupling_pairs lists the vertex pairs a collision
 * within a distance margin may couple.
 *
 * Secant model (the term's hessian_g, bs_terms.h; used with
 * bs_integrator_opts.penalty_secant), off by default
 * (bs_term_self_set_secant): each contact's Hessian with the secant
 * correction of bs_self_pair_secant, given the objective's gradient; off,
 * hessian_g is the Hessian. The convexified Hessian below projects the exact
 * one.
 *
 * Convexified Hessian (the term's hessian_convexified, bs_terms.h): each
 * contact's (3 (nv + 1))^2 Hessian projected onto the positive semidefinite
 * cone (bs_sym_psd_project, bs_svd.h) before it is added. The exact one is
 * indefinite where the primitive is a face or an edge: tilting the triangle
 * about the closest point shortens the distance, a negative stiffness of
 * about 3 k depth^3 / h^2 (h the triangle's size) that dwarfs the elastic
 * one at impact depths and stops CG early (bs_minimize.h, "Convexified
 * model", which uses this Hessian after such a stop).
 *
 * Friction (section 5.3): for each colliding p with primitive vertices n_i
 * and closest-point barycentric weights w_i (w_0 = -1 for p), force f =
 * -dPhi/dp on p with normal n = f/|f|, Q = I - n n^T, relative velocity
 * vbar = sum w_i v_i, mbar^-1 = sum w_i^2 m_i^-1: the impulse j = -mbar Q vbar
 * (which minimizes the kinetic energy over tangential impulses) is clipped to
 * length mu |f| dt (the force's impulse over the step; the paper writes mu
 * |f|) and applied as v_i += w_i m_i^-1 j'. Contacts are processed one after
 * the other in vertex order; each one lowers (never raises) the kinetic
 * energy and conserves linear momentum. Positions are never touched.
 *
 * Units: k in J/m^3 (N/m^2), d in m^2, energy in J, margin and depths in m,
 * mu dimensionless, dt in s, v in m/s.
 *
 * Threads: detection, the closest-primitive searches, the box refit and the
 * contacts' local Hessians (with their PSD projections, in batches of 256)
 * run in OpenMP (independent results); sums and scatters are sequential in
 * vertex order, so results do not depend on the thread count. One term is
 * evaluated by one thread at a time.
 *
 * Ownership: the term (free with bs_term_destroy) keeps pointers to the fem
 * (and its mesh) and the step data, which must outlive it. It owns its
 * hierarchies and buffers, all sized at creation: evaluation allocates
 * nothing.
 *
 * Status: 0; BS_EINPUT for bad arguments (named: k, margin, mu, dt, a term
 * that is not a self-collision term, a mesh with no boundary); BS_ENUMERIC for
 * a non-finite coordinate (names the vertex); BS_ENOMEM. The term's value,
 * gradient and hessian return BS_TERM_NOT_EVALUABLE (bs_terms.h), leaving
 * their outputs untouched, where detection cannot run: a non-finite x, or a
 * geometric query of the shim that failed.
 */
#ifndef BS_SELFCOLLIDE_H
#define BS_SELFCOLLIDE_H

#include <stdint.h>

#include "bs_base.h"
#include "bs_fem.h"
#include "bs_terms.h"

#ifdef __cplusplus
extern "C" {
#endif

#define BS_SELF_EPS 1e-15 /* eps in Phi = k d sqrt(d + eps), m^2 */
#define BS_SELF_SECANT_MIN_D 1e-13 /* d below which the secant model is the Hessian (100 eps), m^2 */

/* Growth of a hierarchy's cost (bs_bvh_cost) over its value at the last
 * rebuild beyond which begin_step rebuilds it: a factor of the expected nodes
 * a query visits. Bodies falling together keep the cost; a pile that
 * rearranges grows it. */
#define BS_SELF_REBUILD_GROWTH 1.25

/* The self-collision term over all boundary vertices of fem->mesh; k finite
 * > 0. step may be NULL (then begin_step does not rebuild the hierarchy). */
int bs_term_self_create(const bs_fem *fem, const bs_step_data *step, double k, bs_term **out, bs_error *err);

/* 1 if t was made by bs_term_self_create, else 0. */
int bs_term_is_self(const bs_term *t);

/* on = 1: the term's hessian_g is the secant model (above); 0 (at creation):
 * the Hessian. BS_EINPUT when t is not a self-collision term. */
int bs_term_self_set_secant(bs_term *t, int on, bs_error *err);

typedef struct bs_self_stats {
  int32_t colliding;      /* colliding vertices at the last evaluation          */
  double max_depth;       /* largest distance to the primitive then (m)         */
  int64_t missing_blocks; /* coupling blocks the last Hessian dropped (no room)  */
  int64_t evaluations;    /* evaluations since creation or the last reset       */
  int64_t reused;         /* of which answered by the last detection (the same  */
                          /* positions, bitwise: value, gradient, Hessian at one */
                          /* iterate, f(xⁿ) after the last step's friction)     */
  int64_t rebuilds;       /* hierarchy rebuilds (creation, begin_step when the  */
                          /* cost grew by BS_SELF_REBUILD_GROWTH)              */
  double t_rebuild;       /* seconds: hierarchy topology rebuilds               */
  double t_refit;         /* seconds: box refits                                */
  double t_detect;        /* seconds: point-in-tet detection                    */
  double t_closest;       /* seconds: tree update and closest primitives        */
} bs_self_stats;

/* Statistics (cumulative since creation or reset, plus the last evaluation). */
int bs_term_self_stats(const bs_term *t, bs_self_stats *out, bs_error *err);
void bs_term_self_reset_stats(bs_term *t);

/* Detects at x: the number of colliding vertices and the largest distance to
 * their primitives (either output may be NULL). Updates the last-evaluation
 * fields of the stats. */
int bs_term_self_detect(bs_term *t, const double *x, int32_t *count, double *max_depth, bs_error *err);

/* The Hessian blocks (i, j), i != j, that the self-collision Hessian at x has
 * and the fem's pattern lacks: pairs[2 s], pairs[2 s + 1] and the row-major
 * block blocks[9 s .. 9 s + 8] for entry s. Both (i, j) and (j, i) are
 * listed; a pair coupled by several collisions appears once per collision
 * (sum them). Writes at most cap entries (pairs, blocks may be NULL when cap
 * is 0); *count receives the total, which may exceed cap. */
int bs_term_self_missing_blocks(bs_term *t, const double *x, int64_t cap, int32_t *pairs, double *blocks,
                                int64_t *count, bs_error *err);

/* Friction after the solve (see the top of this file) at x = xⁿ⁺¹: v (3 per
 * vertex) is updated in place. mask (n_vertices bytes, 1 free, 0 fixed; NULL:
 * all free): fixed vertices act as infinitely heavy (their v is unchanged).
 * mu >= 0 and dt > 0 finite. n_contacts (may be NULL) receives the number of
 * contacts that received an impulse. */
int bs_self_friction(bs_term *t, const double *x, double mu, double dt, const uint8_t *mask, double *v,
                     int32_t *n_contacts, bs_error *err);

/* Vertex pairs (i < j), sorted and unique, that self-collision at x (NULL:
 * rest positions) within distance margin >= 0 may couple and that the fem's
 * pattern lacks: i a boundary vertex, j a vertex of a boundary triangle
 * within margin of x_i that does not have i as a vertex. *pairs (2 per pair)
 * is malloc'ed (free with free(); NULL when there are none). */
int bs_self_coupling_pairs(const bs_fem *fem, const double *x, double margin, int32_t **pairs, int64_t *n_pairs,
                           bs_error *err);

/* ---- kernels (exposed for tests and reuse) --------------------------- */

/* Features of a closest point on a triangle (a, b, c). */
enum { BS_SELF_FACE = 0, BS_SELF_EDGE = 1, BS_SELF_VERTEX = 2 };

/* Closest point of the closed triangle (a, b, c) to p: returns its squared
 * distance, its barycentric weights w (exactly 0 off the feature), the
 * feature kind and the feature's vertices as local indices 0..2 (loc[0..nv),
 * nv = 3, 2, 1 for face, edge, vertex), the weights of those in wf. A
 * degenerate (collinear) triangle is treated through its edges. */
double bs_self_closest_triangle(const double p[3], const double a[3], const double b[3], const double c[3],
                                double w[3], int *feature, int *nv, int loc[3], double wf[3]);

/* Squared distance d from p to a primitive in its region's formula (above):
 * y = (p, then the nv = 1, 2 or 3 primitive vertices), 3 (nv + 1) doubles.
 * Gradient g (3 (nv + 1)) and Hessian H ((3 (nv + 1))^2, row-major) are
 * OVERWRITTEN when non-NULL. */
double bs_self_sqdist(int nv, const double *y, double *g, double *H);

/* Phi = k d sqrt(d + eps) for the same y, with gradient and Hessian
 * (overwritten when non-NULL). */
double bs_self_pair_energy(int nv, const double *y, double k, double *g, double *H);

/* The secant model (the term's hessian_g, as the object penalty's in
 * bs_penalty.h) of the same pair: with r = sqrt(d) the depth, Phi is about
 * k r^3, and the coefficient 6 k r of grad r grad r^T in the pair's Hessian H
 * (as bs_self_pair_energy gives it) becomes 3 k (r + r*), where
 * r* = sqrt(F / (3 k)) balances F, the other terms' push along grad r
 * (F = dPhi/dr - g . grad r / |grad r|^2, g the objective's whole gradient at
 * the pair's 3 (nv + 1) dofs; r* = 0 when F <= 0): ADDS
 * 3 k (r* - r) grad r grad r^T into H. At a minimizer (g = 0) r* = r and H is
 * unchanged. Nothing is added for d <= BS_SELF_SECANT_MIN_D. */
void bs_self_pair_secant(int nv, const double *y, double k, const double *g, double *H);

#ifdef __cplusplus
}
#endif
#endif
