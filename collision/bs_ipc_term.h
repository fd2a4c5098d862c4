/* bs_ipc_term.h — barrier self-contact (Incremental Potential Contact, Li et
 * al. 2020) as an energy term (bs_terms.h) with its continuous collision
 * detection as the term's max_step (the line search's bound).
 *
 * Surface: the boundary triangles of fem->mesh (all bodies merged), their
 * edges (each listed once, from the triangles) and their vertices.
 *
 * Energy at x:
 *     E = kappa * ( sum_PT b(d_PT^2, dhat^2) + sum_EE m_EE b(d_EE^2, dhat^2) )
 * over the point-triangle pairs (a surface vertex and a boundary triangle of
 * which it is not a vertex) and the edge-edge pairs (two edges sharing no
 * vertex, each unordered pair once) whose distance is below dhat: d^2 from
 * bs_ipc_pt_d2_full / bs_ipc_ee_d2_full (exact point-triangle and
 * segment-segment distances), b the log barrier of bs_ipc_barrier, m_EE the
 * edge-edge mollifier (eps_x from the rest positions mesh->x). Gradient and
 * Hessian are bs_ipc_pt_energy's / bs_ipc_ee_energy's, the Hessian of each
 * pair projected onto the PSD cone (bs_term_ipc_set_project: the exact one
 * for tests; hessian_convexified is always projected). Units: dhat m, kappa J/m^4 (E in J).
 *
 * Candidates: two bounding-volume hierarchies (bs_bvh.h, arity 4) over a
 * doubled position array X2 = (x, x + d): the surface vertices (v, v + n, v,
 * v + n) and the edges (a, b, a + n, b + n), so a leaf's box is the box swept
 * over the motion. For the energy d = 0 (X2 = (x, x)); for each triangle,
 * its box grown by dhat is queried in both trees (a box gap never exceeds
 * the distance, so every pair within dhat is found). An edge-edge pair is
 * enumerated from the lower-indexed triangle of its first edge (its "owner").
 * The pairs are found in parallel over contiguous ranges of triangles (as
 * many as threads at creation) and concatenated in range order, so their
 * list, and every sum over it, is the same on any thread count (test:
 * ipc_term/same_bits_on_1_and_2_threads).
 * The trees are built at creation (rest shape) and rebuilt at begin_step
 * when their cost (bs_bvh_cost) at xⁿ exceeds 1.25 times the last rebuild's.
 *
 * Detection along a motion: max_step(x, d) queries each triangle's swept box
 * over (x, x + d) grown by dhat and keeps what it finds. A later detection
 * at a y whose every surface vertex lies in its own box over that motion
 * (the line search's trial points x + a d, a in [0, 1], and any projection
 * of them that stays there; checked vertex by vertex, exactly) runs only the
 * narrow phase on those candidates: every primitive's box at y is then
 * inside its swept box, so a pair within dhat at y is among them; each list
 * is filtered by the very box test the trees' query at y makes and is in
 * the trees' leaf order, so the pairs, their order and every statistic are
 * those of the trees' detection, bit for bit (test:
 * ipc_term/detection_on_max_step_candidates_is_the_trees_detection). Any
 * other y refits the trees to (y, y) and queries them; a rebuild drops the
 * candidates.
 *
 * Domain: where some pair's d^2 <= 0 or some edge crosses a triangle it
 * shares no vertex with (tested on the same candidates; an intersecting
 * state need not have a zero distance), value, gradient and hessian return
 * BS_TERM_NOT_EVALUABLE (no NaN): the line search counts the point as +Inf.
 * The CCD keeps the solver's iterates away from there.
 *
 * max_step(x, d): the swept boxes of (x, x + d) in the same trees, each
 * triangle's swept box queried, narrow phase bs_ccd_pt / bs_ccd_ee
 * (additive CCD, gap s = BS_IPC_CCD_S of the start distance, at most
 * BS_IPC_CCD_ITER iterations: a capped answer is still safe); alpha is the
 * smallest t over the pairs (1 when none). A pair that starts within the
 * rounding of touching certifies nothing: alpha 0.
 *
 * kappa: given (bs_term_ipc_set_kappa) or chosen as IPC does: the caller
 * computes the bounds (bs_ipc_kappa_bounds) and the initial value
 * (bs_term_ipc_kappa_init, from the rest of the objective's gradient), and
 * with bs_term_ipc_set_adaptive the term doubles kappa (up to kappa_max) at
 * each begin_step where bs_ipc_kappa_update says so, from the smallest d^2 at
 * xⁿ of this step and the last.
 *
 * Hessian blocks: a pair couples up to 4 vertices that need not share a tet;
 * blocks outside the fem pattern go to the matrix's extra list
 * (term->hessian_extra = BS_IPC_EXTRA_PER_VERTEX per surface vertex,
 * reserved by the integrator); blocks that find no room are dropped and
 * counted (stats.missing_blocks).
 *
 * Memory: the trees, per-thread query buffers and the doubled positions are
 * sized at creation; the pair list and its per-pair gradient/Hessian buffers
 * grow (amortised doubling) when a detection finds more pairs than ever
 * before, and max_step's candidate lists when it finds more candidates:
 * nothing else allocates during evaluation.
 *
 * Friction: not in this term. bs_ipc_friction.h is a separate term that
 * lags this term's pairs (bs_term_ipc_pairs) at each step's start.
 *
 * Ownership: the term keeps pointers to the fem (and its mesh) and the step
 * data, which must outlive it; free it with bs_term_destroy. One thread
 * evaluates a term at a time.
 *
 * Status: 0; BS_EINPUT naming the argument (dhat, kappa, a mesh with no
 * boundary, a term that is not this one); BS_ENOMEM.
 */
#ifndef BS_IPC_TERM_H
#define BS_IPC_TERM_H

#include <stdint.h>

#include "bs_base.h"
#include "bs_fem.h"
#include "bs_terms.h"

#ifdef __cplusplus
extern "C" {
#endif

#define BS_IPC_CCD_S 0.1        /* additive CCD's gap: 10% of the start distance */
#define BS_IPC_CCD_ITER 2000    /* its iteration cap per pair                     */
#define BS_IPC_EXTRA_PER_VERTEX 36 /* Hessian blocks reserved outside the pattern */
#define BS_IPC_REBUILD_GROWTH 1.25 /* tree rebuild at begin_step past this cost ratio */

/* The barrier term over fem->mesh's boundary; dhat finite > 0 (m), kappa
 * finite >= 0 (J/m^4; 0 is allowed until set). step may be NULL (then
 * begin_step neither rebuilds nor adapts). */
int bs_term_ipc_create(const bs_fem *fem, const bs_step_data *step, double dhat, double kappa, bs_term **out,
                       bs_error *err);

/* 1 if t was made by bs_term_ipc_create, else 0. */
int bs_term_is_ipc(const bs_term *t);

/* kappa finite >= 0. */
int bs_term_ipc_set_kappa(bs_term *t, double kappa, bs_error *err);

/* on = 1 (at creation): each pair's Hessian projected onto the PSD cone;
 * 0: the exact Hessian (tests against finite differences). The convexified
 * Hessian (bs_terms.h) is projected either way. */
int bs_term_ipc_set_project(bs_term *t, int on, bs_error *err);

/* Adaptive kappa per step (above): on with kappa_max > 0 finite and d2_eps
 * > 0 finite (bs_ipc_kappa_d2_eps); kappa_max = 0 turns it off. */
int bs_term_ipc_set_adaptive(bs_term *t, double kappa_max, double d2_eps, bs_error *err);

/* IPC's initial kappa at x: bs_ipc_kappa_initial from grad_energy (3n, the
 * gradient of the objective's other terms at x) and the barrier's gradient
 * at x with kappa = 1, clamped to [kappa_min, kappa_max]; set and written to
 * *kappa (may be NULL). BS_ENUMERIC when the term is not evaluable at x
 * (surfaces touching or crossing). */
int bs_term_ipc_kappa_init(bs_term *t, const double *x, const double *grad_energy, double kappa_min,
                           double kappa_max, double *kappa, bs_error *err);

typedef struct bs_ipc_stats {
  int64_t pairs_pt, pairs_ee; /* active pairs (d < dhat) at the last detection   */
  int64_t intersecting;       /* touching pairs and edge-triangle crossings then */
  double min_distance;        /* smallest pair distance then (m; +Inf: none)     */
  double kappa, dhat;         /* in force                                        */
  int64_t missing_blocks;     /* Hessian blocks dropped by the last Hessian      */
  int64_t detections;         /* detections since creation                       */
  int64_t detections_swept;   /* of which on max_step's candidates (no query)    */
  int64_t ccd_calls;          /* max_step calls since creation                   */
  int64_t ccd_limited;        /* of which returned alpha < 1                     */
  int64_t rebuilds;           /* tree rebuilds (creation counts one)             */
} bs_ipc_stats;

/* The statistics; BS_EINPUT when t is not a barrier term. */
int bs_term_ipc_stats(const bs_term *t, bs_ipc_stats *out, bs_error *err);

/* Detects at x and fills out (may be NULL): the pairs, the smallest
 * distance, the intersecting count. BS_ENUMERIC for a non-finite x. */
int bs_term_ipc_detect(bs_term *t, const double *x, bs_ipc_stats *out, bs_error *err);

/* The term's max_step (above) as a function: *alpha in [0, 1]. BS_ENUMERIC
 * for a non-finite x or d. */
int bs_term_ipc_max_step(bs_term *t, const double *x, const double *d, double *alpha, bs_error *err);

/* An active pair (d < dhat): its 4 vertices, (p, t0, t1, t2) for a
 * point-triangle pair, (ea0, ea1, eb0, eb1) for an edge-edge pair. */
typedef struct bs_ipc_pair {
  int32_t v[4];
  int32_t ee; /* 1: edge-edge, 0: point-triangle */
} bs_ipc_pair;

/* The active pairs at x (a detection, or the last one's when x is bitwise
 * its positions), in the term's order (the same on any thread count):
 * *pairs points into the term and stays valid until its next detection
 * (any evaluation, max_step, detect or begin_step of the term). What the
 * self-contact friction (bs_ipc_friction.h) lags at each step's start.
 * BS_ENUMERIC for a non-finite x or touching or crossing surfaces;
 * BS_ENOMEM. */
int bs_term_ipc_pairs(bs_term *t, const double *x, const bs_ipc_pair **pairs, int64_t *n, bs_error *err);

#ifdef __cplusplus
}
#endif
#endif
