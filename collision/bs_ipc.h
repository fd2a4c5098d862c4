/* bs_ipc.h — the math kernels of Incremental Potential Contact (IPC; Li et
 * al., "Incremental Potential Contact", SIGGRAPH 2020): squared distances
 * between surface primitives with their closed-form gradients and Hessians,
 * the edge-edge mollifier, the log barrier and the contact energy of one
 * point-triangle or edge-edge pair, the barrier stiffness (kappa) heuristics,
 * and continuous collision detection (bs_ccd_pt, bs_ccd_ee: additive CCD).
 * A standalone module: no mesh, no term, no allocation.
 *
 * Conventions
 *  - Points are double[3]. A gradient lists the derivatives with respect to
 *    the arguments' coordinates in argument order: for (p, t0, t1, t2),
 *    g[3 k + c] is d/d(coordinate c of the k-th point). A Hessian is the
 *    dense, row-major, exactly symmetric n x n matrix over the same
 *    coordinates (n = 6, 9 or 12): H[n i + j].
 *  - Every gradient or Hessian pointer may be NULL (not computed).
 *  - "d2" is a SQUARED distance (m^2), as IPC uses it: the barrier is a
 *    function of d^2 with the threshold dhat^2.
 *  - Nothing allocates, prints or exits. The distance kernels are total
 *    functions; the barrier, energy, kappa and CCD functions return a status
 *    (0 = BS_OK, else a named code below) and fill err (may be NULL) on error.
 *
 * Usage (one point-triangle pair in a Newton step):
 *     double E, g[12], H[144];
 *     int st = bs_ipc_pt_energy(p, t0, t1, t2, dhat, kappa, 1, &E, g, H, &err);
 *     if (st == BS_IPC_ECONTACT) ... the pair touches: the step that got
 *                                    here should have been cut by the CCD
 *     ... scatter g and H into the global system ...
 *     // x0: p, t0, t1, t2 at the step's start (12 doubles), x1: the same at
 *     // the end of the Newton step; t: the fraction of it known safe
 *     double t;
 *     bs_ccd_pt(x0, x1, 0.1, 10000, &t, &err);
 */
#ifndef BS_IPC_H
#define BS_IPC_H

#include <stddef.h>

#include "bs_base.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Status codes of this module (besides BS_OK and BS_EINPUT, which names a
 * non-finite or out-of-range argument). */
enum {
  /* A squared distance <= 0 (the primitives touch or cross), where the
   * barrier is not defined; or a CCD start closer than the rounding bound of
   * its distance evaluation, from which no motion can be certified. Nothing
   * NaN is written: the energy outputs are zeroed, the CCD's t is 0. Equal
   * to BS_ENUMERIC, so bs_status_name calls it "numeric". */
  BS_IPC_ECONTACT = BS_ENUMERIC,
  /* Warning (positive): the CCD hit its iteration cap; the returned t is
   * still safe (certified contact-free), only smaller than it could be. */
  BS_IPC_CCD_CAPPED = 1
};

/* ---------------------------------------------------------------------------
 * Distances. Each type's d^2 is a smooth (rational) function of the
 * coordinates where it is the distance:
 *   PP: |p - q|^2;  PE: from p to the LINE through e0, e1;
 *   PT: from p to the PLANE of t0, t1, t2;  EE: between the two LINES.
 * The "full" functions below classify which feature pair is closest and
 * evaluate that type; d^2 is then the true distance between the point and the
 * triangle (the two segments), C^1 in the coordinates (C^inf inside a
 * region; the Hessian jumps across region boundaries). */

/* Closest-feature types of a point and a triangle (t0, t1, t2): the point and
 * vertex tK (P_TK), the point and edge EK (P_EK: E0 = t0t1, E1 = t1t2,
 * E2 = t2t0), or the point and the triangle's interior (P_T). */
typedef enum bs_ipc_pt_type {
  BS_IPC_P_T0, BS_IPC_P_T1, BS_IPC_P_T2,
  BS_IPC_P_E0, BS_IPC_P_E1, BS_IPC_P_E2,
  BS_IPC_P_T
} bs_ipc_pt_type;

/* Closest-feature types of edges a = (ea0, ea1) and b = (eb0, eb1): two
 * endpoints (EAi_EBj), an endpoint and the other edge's interior (EAi_EB:
 * endpoint ai of a against edge b; EA_EBj likewise), or both interiors
 * (EA_EB, the line-line distance). */
typedef enum bs_ipc_ee_type {
  BS_IPC_EA0_EB0, BS_IPC_EA0_EB1, BS_IPC_EA1_EB0, BS_IPC_EA1_EB1,
  BS_IPC_EA0_EB, BS_IPC_EA1_EB, BS_IPC_EA_EB0, BS_IPC_EA_EB1,
  BS_IPC_EA_EB
} bs_ipc_ee_type;

/* Edges whose |ea x eb|^2 is below this times |ea|^2 |eb|^2 (sin^2 of their
 * angle below 1e-20) are classified as parallel: their distance is taken on
 * the endpoints (an EA_EB type would divide by ~0). */
#define BS_IPC_PARALLEL_SIN2 1e-20

/* |p - q|^2; g[6], H[36] over (p, q). */
double bs_ipc_pp_d2(const double p[3], const double q[3], double g[6], double H[36]);

/* Squared distance from p to the line through e0, e1; g[9], H[81] over
 * (p, e0, e1). Needs e0 != e1; for e0 == e1 it returns |p - e0|^2 with the
 * derivatives of that (the limit has none). */
double bs_ipc_pe_d2(const double p[3], const double e0[3], const double e1[3], double g[9], double H[81]);

/* Squared distance from p to the plane through t0, t1, t2:
 * ((p - t0) . n)^2 / |n|^2 with n = (t1 - t0) x (t2 - t0); g[12], H[144]
 * over (p, t0, t1, t2). Needs a non-degenerate triangle; for n = 0 it returns
 * bs_ipc_pe_d2(p, t0, t1) (or |p - t0|^2 if t1 = t0) and its derivatives,
 * scattered. */
double bs_ipc_pt_plane_d2(const double p[3], const double t0[3], const double t1[3], const double t2[3],
                          double g[12], double H[144]);

/* Squared distance between the lines through (ea0, ea1) and (eb0, eb1):
 * ((eb0 - ea0) . n)^2 / |n|^2 with n = (ea1 - ea0) x (eb1 - eb0); g[12],
 * H[144] over (ea0, ea1, eb0, eb1). Needs non-parallel edges; for n = 0 it
 * returns bs_ipc_pe_d2(eb0, ea0, ea1) (or |eb0 - ea0|^2 if ea1 = ea0) and
 * its derivatives, scattered. */
double bs_ipc_ee_line_d2(const double ea0[3], const double ea1[3], const double eb0[3], const double eb1[3],
                         double g[12], double H[144]);

/* The closest-feature type of p and triangle (t0, t1, t2): P_T when p's
 * projection onto the plane lies in the closed triangle (and the triangle is
 * not degenerate: |n|^2 > 1e-20 |t1 - t0|^2 |t2 - t0|^2), else the type of the
 * nearest of the three edges (segment distance: PP at a clamped end, PE
 * inside; the first in the order E0, E1, E2 on ties). */
bs_ipc_pt_type bs_ipc_pt_classify(const double p[3], const double t0[3], const double t1[3], const double t2[3]);

/* The closest-feature type of two segments: EA_EB when the lines' closest
 * points are in both (closed) segments and the edges are not parallel
 * (BS_IPC_PARALLEL_SIN2), else the nearest of the four endpoint-segment
 * pairs (ea0-b, ea1-b, eb0-a, eb1-a, first on ties). */
bs_ipc_ee_type bs_ipc_ee_classify(const double ea0[3], const double ea1[3], const double eb0[3],
                                  const double eb1[3]);

/* The squared distance of p to the triangle: bs_ipc_pt_classify's type
 * (written to *type when non-NULL) evaluated with its kernel above, gradient
 * and Hessian scattered into the 4-point layout (p, t0, t1, t2): the entries
 * of points the type does not involve are 0. */
double bs_ipc_pt_d2_full(const double p[3], const double t0[3], const double t1[3], const double t2[3],
                         bs_ipc_pt_type *type, double g[12], double H[144]);

/* The squared distance between the segments, likewise (layout ea0, ea1, eb0,
 * eb1). */
double bs_ipc_ee_d2_full(const double ea0[3], const double ea1[3], const double eb0[3], const double eb1[3],
                         bs_ipc_ee_type *type, double g[12], double H[144]);

/* The same with a given type (no classification): the type's smooth d^2,
 * e.g. to keep a type fixed along a line search. */
double bs_ipc_pt_d2_typed(bs_ipc_pt_type type, const double p[3], const double t0[3], const double t1[3],
                          const double t2[3], double g[12], double H[144]);
double bs_ipc_ee_d2_typed(bs_ipc_ee_type type, const double ea0[3], const double ea1[3], const double eb0[3],
                          const double eb1[3], double g[12], double H[144]);

/* ---------------------------------------------------------------------------
 * Edge-edge mollifier (IPC section 4.3): near-parallel edges switch between
 * EA_EB and endpoint types, so the edge-edge barrier is multiplied by
 *     m(c) = -c^2/eps_x^2 + 2 c/eps_x  for c < eps_x,  1 otherwise,
 *     c = |(ea1 - ea0) x (eb1 - eb0)|^2,
 * which is 0 for parallel edges (c = 0), where the type switches and the
 * line-line distance degenerates, and joins 1 with a zero slope at c = eps_x
 * (m is C^1 in c, so the energy is C^1 in x). */

/* eps_x = 1e-3 |ea1 - ea0|^2 |eb1 - eb0|^2 of the REST positions (m^4). */
double bs_ipc_mollifier_eps(const double ea0_rest[3], const double ea1_rest[3], const double eb0_rest[3],
                            const double eb1_rest[3]);

/* m(c(x)) and its gradient g[12] and Hessian H[144] over (ea0, ea1, eb0,
 * eb1); eps_x > 0 (for eps_x <= 0, m = 1 with zero derivatives). */
double bs_ipc_mollifier(const double ea0[3], const double ea1[3], const double eb0[3], const double eb1[3],
                        double eps_x, double g[12], double H[144]);

/* ---------------------------------------------------------------------------
 * Barrier and contact energy. */

/* The IPC log barrier of a squared distance d against dhat2 (> 0, m^2):
 *     b(d) = -(d - dhat2)^2 ln(d / dhat2)   for 0 < d < dhat2,  0 for d >= dhat2,
 * with b' = (dhat2 - d)(2 ln(d/dhat2) - dhat2/d + 1) and
 * b'' = (dhat2/d + 2) dhat2/d - 2 ln(d/dhat2) - 3 (both 0 for d >= dhat2;
 * b is C^2 at dhat2). out[0..2] = b, b', b'' (units m^4, m^2, 1).
 * Status: BS_OK; BS_IPC_ECONTACT for d <= 0 (out zeroed); BS_EINPUT for a
 * non-finite d or dhat2 <= 0 (out zeroed). */
int bs_ipc_barrier(double d, double dhat2, double out[3]);

/* The contact energy of a point and a triangle,
 *     E = kappa b(d^2(x), dhat^2),  d^2 = bs_ipc_pt_d2_full,
 * its gradient g[12] = kappa b' grad d^2 and Hessian
 * H[144] = kappa (b'' grad d^2 grad d^2^T + b' Hess d^2), projected onto the
 * positive semidefinite cone (bs_sym_psd_project, bs_svd.h) when project != 0
 * (untouched, bit for bit, when it is already PSD). dhat in m (> 0, the
 * activation distance, NOT squared), kappa >= 0 (J/m^4, or whatever unit per
 * m^4 the objective it joins has). Outputs may be NULL; beyond dhat all are 0.
 * Status: BS_OK; BS_IPC_ECONTACT when d^2 <= 0 (outputs zeroed);
 * BS_EINPUT for a non-finite coordinate, dhat <= 0, kappa < 0. */
int bs_ipc_pt_energy(const double p[3], const double t0[3], const double t1[3], const double t2[3], double dhat,
                     double kappa, int project, double *E, double g[12], double H[144], bs_error *err);

/* The contact energy of two edges, with the mollifier (eps_x from
 * bs_ipc_mollifier_eps on the rest positions, > 0):
 *     E = kappa m(x) b(d^2(x), dhat^2),
 *     g = kappa (m b' grad d^2 + b grad m),
 *     H = kappa (m (b'' grad d^2 grad d^2^T + b' Hess d^2)
 *                + b' (grad d^2 grad m^T + grad m grad d^2^T) + b Hess m),
 * projected as above. Status as bs_ipc_pt_energy (BS_EINPUT also for
 * eps_x <= 0). */
int bs_ipc_ee_energy(const double ea0[3], const double ea1[3], const double eb0[3], const double eb1[3],
                     double eps_x, double dhat, double kappa, int project, double *E, double g[12], double H[144],
                     bs_error *err);

/* ---------------------------------------------------------------------------
 * Friction (IPC section 5: lagged, smoothed Coulomb friction). A contact
 * lagged at the step's start xⁿ has a normal force lambda (N), an
 * orthonormal tangent basis T (3 x 2, row-major: T[2 k + j] is component k
 * of basis vector j) and a linear map from the positions to a relative
 * displacement dx (3); its tangential part u = T^T dx (2) enters
 *     D = mul f0(|u|),  mul = mu lambda (N),
 *     f0(y) = -y^3 / (3 eps^2) + y^2 / eps + eps / 3  (y < eps),  y  (y >= eps),
 * eps = eps_v dt (m): f1 = f0' = 2y/eps - y^2/eps^2 below eps, 1 above, so
 * the force -mul f1(|u|) T u/|u| is Coulomb's mu lambda when the contact
 * slides more than eps in the step and a stiff spring (2 mul / eps) when it
 * sticks. Implemented in ipc_friction.c; used by the obstacles' term
 * (bs_ipc_obstacle.h: dx = x_v - r) and by self-contact friction
 * (bs_ipc_friction.h: dx = sum_i w_i x_i - r over a pair's 4 vertices). */

/* f0(y), f1(y) = f0'(y) and f1'(y) above at y >= 0, eps > 0. */
void bs_ipc_friction_f(double y, double eps, double *f0, double *f1, double *f1p);

/* An orthonormal basis T (3 x 2, row-major as above) of the plane
 * perpendicular to the unit vector n (n's least aligned axis crossed with n,
 * then n crossed with that). */
void bs_ipc_tangent_basis(const double n[3], double T[6]);

/* One lagged contact: returns D = mul f0(|u|), u = T^T dx, and sets (not
 * adds; each may be NULL) g[3] = dD/d(dx) = mul f1(y)/y T u (f1/y -> 2/eps
 * at y = 0) and H[9] = d2D/d(dx)2 = mul T H2 T^T with
 *     H2 = (f1'(y) - f1(y)/y) u u^T / y^2 + f1(y)/y I   (2/eps I at y = 0),
 * whose eigenvalues are f1'(y) along u and f1(y)/y across it: H2 is used as
 * it stands when both are >= 0, which holds for every y with the f0 above
 * (f1' = 2 (eps - y) / eps^2 >= 0 below eps, 0 above), and a negative f1' is
 * clamped to 0 (IPC's PSD projection of the 2 x 2) otherwise. mul >= 0,
 * eps > 0. */
double bs_ipc_friction_eval(const double T[6], const double dx[3], double mul, double eps, double g[3],
                            double H[9]);

/* The closest points of a point-triangle pair (p, t0, t1, t2) at these
 * positions as weights w[4] such that sum_i w_i y_i = p - c, c the point of
 * the triangle nearest p: w = (1, -(1 - b1 - b2), -b1, -b2) with c = t0 +
 * b1 (t1 - t0) + b2 (t2 - t0), by bs_ipc_pt_classify's type (a vertex, the
 * nearest point of an edge, or the projection into the triangle). */
void bs_ipc_pt_closest_weights(const double p[3], const double t0[3], const double t1[3], const double t2[3],
                               double w[4]);

/* The same for two edges (ea0, ea1, eb0, eb1): w = (1 - a, a, -(1 - b), -b),
 * sum_i w_i y_i = ca - cb with ca = ea0 + a (ea1 - ea0), cb = eb0 + b (eb1 -
 * eb0) the closest points of the segments, by bs_ipc_ee_classify's type. */
void bs_ipc_ee_closest_weights(const double ea0[3], const double ea1[3], const double eb0[3], const double eb1[3],
                               double w[4]);

/* ---------------------------------------------------------------------------
 * Barrier stiffness (Li et al. 2020, supplement, "adaptive barrier
 * stiffness"; the defaults of ipc-toolkit). All pure functions. */

/* The admissible range of kappa:
 *     d0 = (1e-8 bbox_diag)^2 (dhat^2 / 2 if that is not below dhat^2),
 *     kappa_min = scale * avg_mass / (4 d0 b''(d0, dhat^2)),
 *     kappa_max = 100 kappa_min,
 * i.e. kappa_min makes the barrier's stiffness along a distance at d0
 * comparable to the mass (scale, recommended 1e11 as ipc-toolkit's
 * min_barrier_stiffness_scale, in the units that make kappa's). avg_mass (kg),
 * dhat (m), bbox_diag (m, the scene's bounding-box diagonal), scale: finite
 * > 0. Status: BS_OK or BS_EINPUT. */
int bs_ipc_kappa_bounds(double avg_mass, double dhat, double bbox_diag, double scale, double *kappa_min,
                        double *kappa_max, bs_error *err);

/* The initial kappa: the one that best balances the barrier's gradient
 * against the rest of the objective's, argmin_k |grad_energy + k grad_barrier|,
 * i.e. -grad_barrier . grad_energy / |grad_barrier|^2 (1 when grad_barrier is
 * zero), clamped to [kappa_min, kappa_max]. grad_energy: the gradient of the
 * objective without contact; grad_barrier: the gradient of the sum of the
 * barriers b (kappa = 1, no mollifier scaling beyond the energy's own), both
 * of length n, at the same configuration. */
double bs_ipc_kappa_initial(size_t n, const double *grad_energy, const double *grad_barrier, double kappa_min,
                            double kappa_max);

/* The adaptive rule, applied once per Newton iteration: kappa doubles (capped
 * at kappa_max) when the smallest squared distance of the whole contact set is
 * below d2_eps now (d2_min) and was at the previous iteration (d2_prev), and
 * it decreased (the barrier struggles to keep the surfaces apart); otherwise
 * kappa is returned unchanged. d2_eps: a small squared distance, far below
 * dhat^2: ipc-toolkit's default is (1e-9 bbox_diag)^2 (bs_ipc_kappa_d2_eps). */
double bs_ipc_kappa_update(double kappa, double kappa_max, double d2_prev, double d2_min, double d2_eps);

/* (1e-9 bbox_diag)^2: the d2_eps of ipc-toolkit. */
double bs_ipc_kappa_d2_eps(double bbox_diag);

/* ---------------------------------------------------------------------------
 * Continuous collision detection: additive CCD (ACCD; Li, Kaufman, Jiang,
 * "Codimensional Incremental Potential Contact", SIGGRAPH 2021, Algorithm 1).
 *
 * The vertices move linearly: x(t) = x0 + t (x1 - x0), t in [0, 1]. x0, x1
 * are 4 points each (12 doubles): (p, t0, t1, t2) for bs_ccd_pt, (ea0, ea1,
 * eb0, eb1) for bs_ccd_ee. The result *t is a SAFE step fraction: over all
 * of [0, *t] the distance stays >= s^2 d_lo(0) > 0 (d_lo(0): the certified
 * lower bound of the start distance, which is the start distance up to
 * rounding), and at *t < 1 it is >= s d_lo(0) (the gap). *t = 1 when the
 * whole motion is certified contact-free (the end may then be nearer than the
 * gap, but by the same certificate never nearer than s^2 d_lo(0)). *t is not
 * the time of impact: it is below it by at least what the gap costs.
 *
 * Algorithm. Displacements are made relative (their mean subtracted: a common
 * translation does not change distances), and lp = max |displacement| over
 * the point (edge a) + max over the triangle (edge b) bounds the rate at which
 * the distance can shrink. From a certified lower bound D of the distance at
 * t, the distance stays >= D - lp tau over [t, t + tau]: the step
 * tau = (1 - s) D / lp is safe and ends above s D. ACCD takes such steps and
 * evaluates the distance after each; it stops, returning the last accepted t,
 * when a step's end is below the gap g = s d_lo(0), and returns 1 when a step
 * passes t = 1. The first step needs no evaluation (it ends at >= g by the
 * bound); every later accepted t has its distance evaluated >= g.
 *
 * Why it stays conservative under floating point:
 *  - Every distance is a CERTIFIED lower bound d_lo = d_computed - E, where E
 *    bounds the rounding error of the evaluation: of the positions (computed
 *    relative to a common origin, the start of the first point, so their
 *    magnitude S is the primitives' size plus their motion, not the scene's
 *    coordinates: E ~ 32 u S with u = 2^-53), of the point-segment distances
 *    (~16 u (|r| + |e|)), and of the plane (line-line) distance
 *    |r . n| / |n| (~32 u |r||a||b| / |n|, large for slivers and near-parallel
 *    edges). When that last bound exceeds the geometric one, the triangle
 *    (pair of lines) is treated as degenerate: every point of a triangle is
 *    within h = |n| / (longest edge) of its edges, and two near-parallel
 *    segments' distance is within |n| / (sqrt2 max(|a|, |b|)) of their
 *    endpoint-segment distances, so min(those) - h is a lower bound; the
 *    smaller of the two errors is at worst ~sqrt(32 u) (~6e-8) times the
 *    primitives' size (slivers, edges ~1e-7 rad from parallel), and ~32 u
 *    times it for well-shaped ones. The interior feature is included
 *    with a tolerance on its inside test covering that test's rounding:
 *    including it wrongly only lowers the bound (the plane is nearer than the
 *    triangle).
 *  - lp is rounded up (and covers the rounding of the displacements), and the
 *    safe step uses (1 - s) of the certified distance: the remaining s D is
 *    far above what the rounding of t + tau can add (checked: the start
 *    distance must exceed E and ~64 u (S + lp) / s^2; otherwise nothing is
 *    certified, *t = 0, BS_IPC_ECONTACT).
 *  - Positions are recomputed as x0 + t dx at each step (no accumulated sum).
 *  - The iteration cap returns the last accepted t: smaller, never larger.
 * So a contact at time t* implies *t < t*, and the distance at *t is > 0.
 *
 * s in (0, 1) (0.1 recommended: gap 10% of the start distance); max_iter >= 1
 * (e.g. 10000; head-on motions take 2-3 steps, grazing ones about
 * lp / (s (1 - s) d0)). Status: BS_OK; BS_IPC_CCD_CAPPED (t safe);
 * BS_IPC_ECONTACT (t = 0) when the start distance is not certifiably > 0;
 * BS_EINPUT (t = 0) for non-finite coordinates or s, max_iter out of range. */
int bs_ccd_pt(const double x0[12], const double x1[12], double s, int max_iter, double *t, bs_error *err);
int bs_ccd_ee(const double x0[12], const double x1[12], double s, int max_iter, double *t, bs_error *err);

/* The certified lower bound of the distance (not squared) between the point
 * and the triangle (the two segments) given as 4 points x[12] in the layouts
 * above, as the CCD uses it: <= the exact distance of the given coordinates
 * (their own rounding aside), and below it by at most the error bound
 * described above (it may be <= 0 when the primitives are within rounding of
 * touching). Rounding grows with the coordinates' magnitude: pass them
 * relative to a nearby origin. */
double bs_ccd_pt_dist_lower(const double x[12]);
double bs_ccd_ee_dist_lower(const double x[12]);

#ifdef __cplusplus
}
#endif
#endif
