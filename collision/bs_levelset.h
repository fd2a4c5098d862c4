/* bs_levelset.h — collision objects as level sets (paper sections 5.1, 5.2).
 *
 * Convention: phi(x) < 0 inside the obstacle, phi > 0 outside, phi = 0 on its
 * surface (paper 5.1). Every analytic shape is an exact signed distance
 * function (|grad phi| = 1 wherever it is differentiable). Units: metres,
 * seconds; phi in metres, grad phi dimensionless, Hessian in 1/m.
 *
 * Evaluation returns phi and, on request, grad phi (3) and the Hessian (9,
 * row-major), both EXACT derivatives of the function evaluated (analytic
 * formulas; for grids, the derivatives of the interpolant). On the
 * non-smooth sets (medial axes, box edges and faces' bisector planes, the
 * sphere centre, the torus axis and core circle) phi is still exact and the
 * derivatives are those of one of the adjoining smooth pieces; where a
 * derivative is undefined outright (distance 0 to an axis or centre) a unit
 * gradient is chosen and the 1/distance Hessian term is dropped, so that
 * nothing returns NaN or Inf.
 *
 * Shapes, each given in its LOCAL frame (centred at the origin, axis z):
 *   half-space  phi = n.x - c (n normalized, c divided by |n|): the ground;
 *   sphere      phi = |y| - r;
 *   box         exact SDF with sharp edges: outside the distance to the box,
 *               inside minus the distance to the nearest face;
 *   cylinder    capped, radius r and half-height hh along its axis, exact SDF;
 *   torus       major radius R (core circle, around the axis), minor radius
 *               r < R (tube), phi = |(rho - R, z)| - r, rho = |(y_x, y_y)|;
 *   grid        cubic B-spline (default) or trilinear interpolation of
 *               sampled values (see below);
 * and the COMPLEMENT of any of them (phi -> -phi: a bowl, a hole, a room).
 *
 * Placement and motion. A shape has a rest placement: a centre c0 and a
 * rotation Q0 (the rotation taking local z to the given axis; identity for
 * boxes and grids). A motion is a rigid transform of time applied about the
 * rest centre: at time t the shape sits at centre c(t) = c0 + d(t) with
 * orientation M(t) = R(t) Q0, and
 *     phi(t, x) = phi_local(M(t)^T (x - c(t))),
 *     grad = M grad_local,  Hess = M Hess_local M^T.
 * Motions: none (static); constant linear velocity v and angular velocity w
 * (axis-angle rate, rad/s, world frame) from t = 0: d(t) = v t,
 * R(t) = exp([w] t); or keyframes (t_k, translation d_k, rotation axis-angle
 * r_k) with d linearly interpolated and R interpolated by slerp along the
 * shortest arc (so consecutive keys must differ by less than a half turn),
 * held constant before the first and after the last key.
 * The obstacle velocity at a point is  v(x) = d'(t) + w(t) x (x - c(t)).
 *
 * Grid level sets: nodes origin + h (i, j, k), 0 <= i < nx (and so on),
 * nx, ny, nz >= 2, values stored x fastest: values[i + nx (j + ny k)].
 * Inside the grid box phi is an interpolant of the node values, chosen with
 * bs_levelset_grid_set_interp:
 *   BS_GRID_CUBIC (the default for every grid, created or loaded): the
 *     uniform cubic B-spline whose coefficients are prefiltered at creation
 *     (separable tridiagonal solves) so that it INTERPOLATES the nodes. It is
 *     C2 everywhere inside the box: gradient and Hessian are continuous
 *     across cell faces, so penalty forces have no kinks (paper 5.2). At the
 *     grid boundary the stencil's ghost coefficient is linearly extrapolated
 *     (natural end condition: trilinear functions are reproduced exactly).
 *     Error O(h^4) for smooth phi in the interior, O(h^2) near the boundary
 *     and near kinks of phi (medial axes), where it may overshoot slightly.
 *   BS_GRID_LINEAR: the trilinear interpolant (the Hessian has a zero
 *     diagonal and nonzero mixed terms inside a cell; the gradient jumps
 *     across cell faces).
 * Gradient and Hessian are the interpolant's exact derivatives (on a cell
 * face in linear mode, those of the cell above). Outside the box phi is
 * extrapolated as phi(q) + |p - q| with q the point of the box nearest to p:
 * continuous, growing at unit rate away from the box. The extrapolation is
 * meaningful only when the grid encloses the obstacle with some margin (phi
 * > 0 on the whole grid boundary). A grid is placed at rest with c0 at the
 * centre of its box and Q0 = I, so motions apply to it too.
 * File format (bs_levelset_grid_save / _load), all little-endian:
 *     8 bytes  "BSLS1" and three zero bytes (magic)
 *     4 x int32  nx, ny, nz, 0 (reserved)
 *     4 x double origin[3], h
 *     nx ny nz doubles, x fastest.
 * Only the grid is stored (not the motion, the complement flag or the
 * interpolation mode: a loaded grid is cubic).
 *
 * Projection (paper 5.1): P(x) = x - phi(x) grad phi(x). For an analytic
 * SDF, away from the medial axis, grad phi(x) is the unit direction from the
 * nearest surface point to x and phi(x) the signed distance to it, so P(x) IS
 * that nearest surface point: phi(P(x)) = 0 and P(P(x)) = P(x) (idempotent)
 * up to round-off. The complement has the same projection. For grids neither
 * holds exactly (paper 5.1: use grids with penalties, not constraints).
 *
 * Ownership: bs_levelset_create_* and _grid_* return an object owned by the caller, freed
 * with bs_levelset_destroy (accepts NULL, nulls the pointer). Setters modify
 * it in place. Evaluation functions are pure and thread-safe on a shared
 * level set.
 *
 * Status: 0, or BS_EINPUT for a bad parameter (the message names the
 * parameter and its value: "radius = -1: ..."), BS_EIO for a file that cannot
 * be opened, read or written or is truncated (the message names the file),
 * BS_ENOMEM.
 */
#ifndef BS_LEVELSET_H
#define BS_LEVELSET_H

#include <stdint.h>

#include "bs_base.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum {
  BS_LS_HALFSPACE = 0,
  BS_LS_SPHERE,
  BS_LS_BOX,
  BS_LS_CYLINDER,
  BS_LS_TORUS,
  BS_LS_GRID
} bs_ls_kind;

typedef enum { BS_LS_STATIC = 0, BS_LS_VELOCITY, BS_LS_KEYFRAMES } bs_ls_motion;

/* Grid interpolation (see the header comment). */
typedef enum { BS_GRID_CUBIC = 0, BS_GRID_LINEAR = 1 } bs_grid_interp;

/* The level set. Fields are read-only for users: create with the
 * constructors below and change only through the setters. */
typedef struct bs_levelset {
  bs_ls_kind kind;
  int complement;       /* 1: phi -> -phi                                     */
  double param[3];      /* sphere r; box half-extents; cylinder r, hh;
                           torus R, r; half-space: unused                    */
  double c0[3];         /* rest centre (half-space: the plane point c n)      */
  double Q0[9];         /* rest rotation, local to world                      */
  bs_ls_motion motion;
  double vel[3], omega[3]; /* BS_LS_VELOCITY                                  */
  int n_keys;           /* BS_LS_KEYFRAMES: times, translations (3 per key),  */
  double *key_t, *key_d, *key_q; /* rotations as unit quaternions (4: w x y z) */
  int32_t n[3];         /* grid: nodes per axis                               */
  double origin[3], h;  /* grid: first node, spacing                          */
  double *values;       /* grid: n[0] n[1] n[2] = N values, x fastest; the one
                           allocation also holds the coefficients and ranges */
  double *coef;         /* grid: N cubic B-spline coefficients (values + N)   */
  double *coef_range;   /* grid: per block of BS_GRID_BLOCK^3 cells, the min
                           and max of the coefficients its interior cells'
                           B-splines read (2 per block, after coef)          */
  int grid_interp;      /* grid: a bs_grid_interp (BS_GRID_CUBIC by default)  */
} bs_levelset;

/* The placement of a level set at one time (computed once, reused for many
 * points): local-to-world rotation M, centre c, centre velocity v, angular
 * velocity w (world frame). */
typedef struct bs_levelset_frame {
  double M[9];
  double c[3];
  double v[3];
  double w[3];
} bs_levelset_frame;

/* ---- creation --------------------------------------------------------- */

/* phi = (n.x - c)/|n|: n nonzero (need not be unit), c finite. */
int bs_levelset_create_halfspace(const double normal[3], double offset, bs_levelset **out, bs_error *err);
int bs_levelset_create_sphere(const double centre[3], double radius, bs_levelset **out, bs_error *err);
/* Axis-aligned box (at rest) of half-extents half[3] > 0. */
int bs_levelset_create_box(const double centre[3], const double half[3], bs_levelset **out, bs_error *err);
/* Capped cylinder: axis direction (nonzero, normalized), radius > 0, half_height > 0. */
int bs_levelset_create_cylinder(const double centre[3], const double axis[3], double radius, double half_height,
                                bs_levelset **out, bs_error *err);
/* Torus around axis (nonzero): 0 < minor < major. */
int bs_levelset_create_torus(const double centre[3], const double axis[3], double major, double minor,
                             bs_levelset **out, bs_error *err);

/* Grid from caller's values (copied; layout above): n[k] >= 2, h > 0, all
 * finite (a NaN names its node). This is what a signed distance to a closed
 * surface (the CGAL shim) feeds. */
int bs_levelset_grid_from_values(const double origin[3], double h, const int32_t n[3], const double *values,
                                 bs_levelset **out, bs_error *err);
/* Grid sampling src at time t at the nodes origin = lo + h (i, j, k) with
 * n[k] = ceil((hi[k] - lo[k]) / h) + 1 (so the grid covers [lo, hi]); lo < hi,
 * h > 0, at most 2^31 - 1 nodes. The source's complement flag is sampled with
 * it; the new grid is static. */
int bs_levelset_grid_sample(const bs_levelset *src, double t, const double lo[3], const double hi[3], double h,
                            bs_levelset **out, bs_error *err);

void bs_levelset_destroy(bs_levelset **ls);

/* ---- modifiers --------------------------------------------------------- */

/* complement != 0: phi -> -phi (inside-out). */
void bs_levelset_set_complement(bs_levelset *ls, int complement);
/* Constant velocity v (m/s) and angular velocity w (rad/s, axis-angle rate,
 * about the moving centre) from t = 0. Replaces any earlier motion. */
int bs_levelset_set_velocity(bs_levelset *ls, const double v[3], const double w[3], bs_error *err);
/* n >= 1 keyframes: times strictly increasing, translations 3 per key (m),
 * rotations 3 per key (axis-angle, rad). Copied. Replaces any earlier motion. */
int bs_levelset_set_keyframes(bs_levelset *ls, int n, const double *times, const double *translations,
                              const double *rotations, bs_error *err);

/* ---- queries ---------------------------------------------------------- */

bs_ls_kind bs_levelset_kind(const bs_levelset *ls);
const char *bs_levelset_kind_name(bs_ls_kind kind); /* "halfspace", "sphere", ... */
int bs_levelset_is_complement(const bs_levelset *ls);
/* 1 for the analytic shapes (for which projection is exact), 0 for grids. */
int bs_levelset_is_analytic(const bs_levelset *ls);
bs_ls_motion bs_levelset_motion(const bs_levelset *ls);

/* The placement at time t. */
void bs_levelset_frame_at(const bs_levelset *ls, double t, bs_levelset_frame *f);

/* phi at x and time t; grad (3) and hess (9, row-major) filled when non-NULL. */
double bs_levelset_eval(const bs_levelset *ls, double t, const double x[3], double grad[3], double hess[9]);
/* The same with a precomputed frame (no trigonometry per point). */
double bs_levelset_eval_frame(const bs_levelset *ls, const bs_levelset_frame *f, const double x[3], double grad[3],
                              double hess[9]);

/* 1 when the phi bs_levelset_eval_frame computes at x is certainly not
 * negative, found without evaluating it: a cubic grid whose coefficients
 * around x (the range of x's block of cells, coef_range) all have phi's
 * outside sign, x in an interior cell (no folded or clamped axis), where the
 * B-spline's weights are >= 0, so every term of the computed sum has that
 * sign too. 0 means unknown (analytic shapes, linear grids, cells near the
 * grid's boundary, the surface within the block's reach, NaN). */
int bs_levelset_surely_outside_frame(const bs_levelset *ls, const bs_levelset_frame *f, const double x[3]);

/* x in the shape's local frame at time t: y = M^T (x - c(t)) (for grids the
 * local origin is the centre of the grid box). */
void bs_levelset_local_point(const bs_levelset *ls, double t, const double x[3], double y[3]);

/* Velocity of the obstacle's material point at x and time t (m/s). */
void bs_levelset_velocity(const bs_levelset *ls, double t, const double x[3], double v[3]);

/* Bounds of the motion over the times between t0 and t1 (either order):
 * v and w the largest |centre velocity| (m/s) and |angular velocity|
 * (rad/s), dv and dw the largest change of each between two of those times
 * (0 when the interval lies within one piece of the motion: constant
 * velocity, one keyframe segment, or a hold; else 2 v and 2 w). All 0 for a
 * static shape. With them, a material point's velocity at p and time t
 * differs from the one at p0 and t0 by at most
 * dv + dw |p - c(t)| + w (|p - p0| + v |t - t0|). */
typedef struct bs_levelset_motion_bound {
  double v, w, dv, dw;
} bs_levelset_motion_bound;
void bs_levelset_motion_bound_over(const bs_levelset *ls, double t0, double t1, bs_levelset_motion_bound *b);

/* P(x) = x - phi(x) grad phi(x) into xp (may alias x); returns phi(x). See
 * the header comment for when it lands on phi = 0 and is idempotent. */
double bs_levelset_project(const bs_levelset *ls, double t, const double x[3], double xp[3]);
double bs_levelset_project_frame(const bs_levelset *ls, const bs_levelset_frame *f, const double x[3],
                                 double xp[3]);

/* ---- grids ------------------------------------------------------------- */

/* The grid interpolant (with the extrapolation outside the box) at a point p
 * of the grid's rest frame (world coordinates at rest: no motion, no
 * complement); g and H filled when non-NULL. */
double bs_levelset_grid_interp(const bs_levelset *ls, const double p[3], double g[3], double H[9]);

/* The grid's values (layout above) and geometry, or NULL for analytic
 * shapes. Any output pointer may be NULL. */
const double *bs_levelset_grid_values(const bs_levelset *ls, int32_t n[3], double origin[3], double *h);

/* Cells per axis of a coef_range block. */
enum { BS_GRID_BLOCK = 2 };

/* 1 when the cubic interpolant at p (the grid's rest frame, as
 * bs_levelset_grid_interp computes it) is certainly >= 0 (sign +1) or <= 0
 * (sign -1): p in an interior cell whose block's coefficients are all > 0,
 * or all < 0 (see bs_levelset_surely_outside_frame). */
int bs_levelset_grid_sign_certain(const bs_levelset *ls, const double p[3], int sign);

/* Selects the grid interpolant (both are ready from creation: switching is
 * free). BS_EINPUT for an analytic level set (naming its kind) or an unknown
 * mode (naming its value). */
int bs_levelset_grid_set_interp(bs_levelset *ls, bs_grid_interp mode, bs_error *err);
/* The grid's interpolation mode (meaningless for analytic shapes). */
bs_grid_interp bs_levelset_grid_get_interp(const bs_levelset *ls);
/* "cubic", "linear" (or "unknown"). */
const char *bs_grid_interp_name(bs_grid_interp mode);

/* Writes a grid level set to path (format above). An analytic level set is
 * BS_EINPUT; a file that cannot be written is BS_EIO naming it. */
int bs_levelset_grid_save(const bs_levelset *ls, const char *path, bs_error *err);
/* Reads a grid written by bs_levelset_grid_save. Errors name the file:
 * missing or unreadable and truncated (BS_EIO), bad magic, bad dimensions or
 * spacing, non-finite values, trailing bytes (BS_EINPUT). */
int bs_levelset_grid_load(const char *path, bs_levelset **out, bs_error *err);

#ifdef __cplusplus
}
#endif
#endif
