/* bs_ipc_friction.h — friction between surfaces in barrier self-contact
 * (self_collision.model "barrier" with self_collision.friction mu > 0):
 * IPC's lagged, smoothed Coulomb friction (Li et al. 2020, section 5) as an
 * energy term (bs_terms.h) beside the barrier term (bs_ipc_term.h), whose
 * contact pairs it lags.
 *
 * Lagging, at begin_step when the step data has x_n and dt > 0 (else the
 * term is empty for the step): the barrier term's active pairs at xⁿ
 * (bs_term_ipc_pairs: d < dhat), each recorded with, at xⁿ,
 *  - its 4 vertices' positions yⁿ and its closest points as weights w
 *    (bs_ipc_pt_closest_weights: (1, -(1 - b1 - b2), -b1, -b2);
 *    bs_ipc_ee_closest_weights: (1 - a, a, -(1 - b), -b)), so that
 *    sum_i w_i y_i is the vector from the triangle's (edge b's) closest
 *    point to the point (to edge a's);
 *  - the contact normal n = sum_i w_i yⁿ_i / |.| and a tangent basis T of
 *    its plane (3 x 2, bs_ipc_tangent_basis);
 *  - the normal force lambda = kappa |b'(d^2, dhat^2)| 2 d (N): the
 *    barrier's kappa b(d^2) differentiated along the distance d (b' of
 *    bs_ipc_barrier, d^2 the pair's bs_ipc_pt_d2_full / bs_ipc_ee_d2_full,
 *    kappa the barrier term's at that moment), times the edge-edge mollifier
 *    m(xⁿ) for an edge-edge pair (its barrier is kappa m b, as IPC's
 *    edge-edge friction);
 * all fixed for the step (a pair with lambda <= 0, e.g. parallel edges
 * where m = 0, or no normal is left out).
 *
 * Energy at x (J):
 *     E = sum_k mu lambda_k f0(|u_k|),  u_k = T_k^T sum_i w_ki (x_i - yⁿ_ki),
 * f0 and eps = eps_v dt (m) as bs_ipc.h ("Friction"): when a contact slides
 * more than eps in the step its force is Coulomb's mu lambda against the
 * sliding; below eps it is a stiff spring (2 mu lambda / eps), the smoothed
 * static friction (a contact held by friction creeps at up to eps_v). With
 * g_k, H_k = bs_ipc_friction_eval of pair k, pair k adds w_ki g_k to the
 * gradient at its vertex i and w_ki w_kj H_k to the Hessian block (i, j):
 * the exact Hessian, PSD (H_k is; the clamp of bs_ipc_friction_eval never
 * acts with IPC's f0), so hessian_convexified is the same. E is C^2 in x
 * and finite everywhere: value, gradient and hessian return
 * BS_TERM_NOT_EVALUABLE only for a non-finite result.
 *
 * Hessian blocks: a pair couples 4 vertices that need not share a tet:
 * blocks outside the fem pattern go to the matrix's extra list
 * (term->hessian_extra = the barrier term's, BS_IPC_EXTRA_PER_VERTEX per
 * surface vertex, reserved by the integrator besides the barrier's); blocks
 * that find no room are dropped and counted (stats.missing_blocks).
 *
 * Order: the friction term's begin_step must run after the barrier term's
 * in the same step (the kappa it lags is the one adapted there): list it
 * after the barrier (bs_sim does).
 *
 * Threads: the lagging and each evaluation run over the pairs in parallel
 * into per-pair buffers, summed (scattered) in pair order afterwards, and
 * the pair order is the barrier's (the same on any thread count): E, the
 * gradient and the Hessian are the same bits on 1 and 2 threads. Memory:
 * the pair list and its buffers grow (amortised doubling) at begin_step
 * only; nothing allocates during evaluation.
 *
 * Ownership: the term borrows the barrier term (and through it the fem and
 * the step data), which must outlive its use; free it with
 * bs_term_destroy. One thread evaluates a term at a time.
 *
 * Status: 0; BS_EINPUT naming the argument (mu, eps_v, a barrier that is
 * not one, a term that is not this one); BS_ENUMERIC from begin_step when
 * the surfaces touch or cross at xⁿ; BS_ENOMEM.
 */
#ifndef BS_IPC_FRICTION_H
#define BS_IPC_FRICTION_H

#include <stdint.h>

#include "bs_base.h"
#include "bs_terms.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The friction term of barrier (made by bs_term_ipc_create; borrowed), mu
 * finite > 0, eps_v finite > 0 (m/s, contact.eps_v). Its step data is the
 * barrier's; dynamic_only (skipped in static solves, where dt = 0 lags
 * nothing anyway). */
int bs_term_ipc_friction_create(bs_term *barrier, double mu, double eps_v, bs_term **out, bs_error *err);

/* 1 if t was made by bs_term_ipc_friction_create, else 0. */
int bs_term_is_ipc_friction(const bs_term *t);

typedef struct bs_ipc_friction_stats {
  int64_t pairs_pt, pairs_ee; /* pairs lagged at the last begin_step          */
  double normal_force;        /* sum of their lambda (N)                      */
  double mu, eps;             /* mu; eps = eps_v dt of the last lag (m; 0: none) */
  int64_t missing_blocks;     /* Hessian blocks dropped by the last Hessian   */
} bs_ipc_friction_stats;

/* The statistics; BS_EINPUT when t is not a friction term. */
int bs_term_ipc_friction_stats(const bs_term *t, bs_ipc_friction_stats *out, bs_error *err);

#ifdef __cplusplus
}
#endif
#endif
