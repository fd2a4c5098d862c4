/* bs_ls_sample.h — grid level sets (bs_levelset.h) sampled from the signed
 * distance to a closed triangle surface: what `bigstep levelset` makes.
 *
 * The surface (bs_ls_soup): points and triangles, 0-based, read from a
 * triangle file as is (bs_ls_soup_read: .off, .obj, .ply, .stl) or taken from
 * the boundary triangles of a tet mesh (bs_ls_soup_from_mesh). It must be
 * closed (bs_ls_soup_check_closed): after merging points with identical
 * coordinates, every edge must be shared by an even number (>= 2) of
 * triangles; an edge that collapses to a point bounds nothing and is not
 * counted. Closedness is what makes the ray-parity sign of the signed
 * distance meaningful.
 *
 * The grid (bs_ls_grid_plan_make) covers the box of the points the triangles
 * use (a soup may carry unused points), grown by the margin on every side:
 * origin = lo - margin, n[k] = max(1, ceil((hi[k] - lo[k] + 2 margin) / h))
 * + 1 nodes of spacing h. Defaults: h = (largest box edge) / 40 when h <= 0,
 * margin = max(0.1 largest box edge, 2 h) when margin < 0. At most 2^31 - 1
 * nodes.
 *
 * Sampling (bs_ls_sample_grid): phi at node (i, j, k) = the signed distance
 * from origin + h (i, j, k) to the surface, negative inside (the CGAL shim's
 * exact-predicate tree: Euclidean distance to the closest triangle, the sign
 * by ray parity), values x fastest (the layout of bs_levelset.h), one z
 * slice at a time over OpenMP threads. The node values are the distances
 * to the triangles themselves (up to rounding): against the analytic
 * distance of the body the triangles approximate, the only error is the
 * triangulation's. For a convex body, the node error is at most the Hausdorff
 * distance between body and polyhedron; e.g. a sphere of radius r whose
 * triangle corners lie on it: r - sqrt(r^2 - rho^2), rho the largest
 * circumradius of a triangle (about rho^2 / (2 r)). Between nodes, a grid
 * level set adds its interpolation error (bs_levelset.h).
 * bs_ls_from_surface does the whole job (closedness, plan, sampling, the
 * grid level set); bs_ls_sample_write writes a grid level set.
 *
 * Units: metres. Ownership: bs_ls_soup_read and bs_ls_soup_from_mesh fill a
 * soup whose arrays the caller frees with bs_ls_soup_free; values arrays are
 * the caller's; bs_ls_from_surface returns a level set the caller frees with
 * bs_levelset_destroy. Nothing prints; only the files named are read or
 * written. Status: 0; BS_EINPUT (an open surface, naming the file and one
 * odd edge; no triangles; a surface of no extent; a grid of too many nodes,
 * naming h); BS_EIO (a file that cannot be read or written: named);
 * BS_ENOMEM; the shim's codes.
 *
 * Example:
 *   bs_ls_soup s; bs_ls_grid_plan g; bs_ls_sample_info info; bs_levelset *ls = NULL;
 *   if (bs_ls_soup_read("part.stl", &s, &err)) return ...;
 *   int rc = bs_ls_from_surface(&s, "part.stl", 0.01, -1, &g, &info, &ls, &err);
 *   if (!rc) rc = bs_ls_sample_write(ls, "part.bsls", &err);
 *   bs_levelset_destroy(&ls);
 *   bs_ls_soup_free(&s);
 */
#ifndef BS_LS_SAMPLE_H
#define BS_LS_SAMPLE_H

#include <stdint.h>

#include "bs_base.h"
#include "bs_levelset.h"
#include "bs_mesh.h"

#ifdef __cplusplus
extern "C" {
#endif

/* A triangle surface. */
typedef struct bs_ls_soup {
  int64_t n_points;
  double *x;       /* 3 per point (m)                 */
  int64_t n_tris;
  int32_t *tris;   /* 3 per triangle, 0-based indices */
} bs_ls_soup;

/* 1 when path ends in .off, .obj, .ply or .stl (lower or upper case): the
 * files bs_ls_soup_read reads. */
int bs_ls_soup_is_file(const char *path);

/* Reads a triangle file as is (no repair). */
int bs_ls_soup_read(const char *path, bs_ls_soup *out, bs_error *err);

/* A copy of m's vertices and boundary triangles. */
int bs_ls_soup_from_mesh(const bs_mesh *m, bs_ls_soup *out, bs_error *err);

/* Frees the arrays and zeroes s (NULL accepted). */
void bs_ls_soup_free(bs_ls_soup *s);

/* 0 when s is closed (see the top), else BS_EINPUT naming `name` (the file,
 * for the message), the count of odd edges and one of them. */
int bs_ls_soup_check_closed(const bs_ls_soup *s, const char *name, bs_error *err);

/* A grid over a surface. */
typedef struct bs_ls_grid_plan {
  double lo[3], hi[3];     /* the box of the points the triangles use */
  double origin[3], h, margin;
  int32_t n[3];            /* nodes per axis                          */
  int64_t total;           /* n[0] n[1] n[2]                          */
} bs_ls_grid_plan;

/* The grid over s (see the top; h <= 0 and margin < 0: the defaults). */
int bs_ls_grid_plan_make(const bs_ls_soup *s, const char *name, double h, double margin, bs_ls_grid_plan *g,
                         bs_error *err);

/* What sampling found and cost. */
typedef struct bs_ls_sample_info {
  double phi_min, phi_max; /* over the nodes (m)                          */
  int64_t n_inside;        /* nodes with phi < 0                          */
  int threads;             /* OpenMP threads available to the sampling    */
  double t_tree;           /* s: checks, plan and the distance tree       */
  double t_sample;         /* s: the sampling                             */
} bs_ls_sample_info;

/* The signed distance to s at every node of g into values (g->total
 * doubles, the caller's); info (may be NULL) gets the values' range. */
int bs_ls_sample_grid(const bs_ls_soup *s, const bs_ls_grid_plan *g, double *values, bs_ls_sample_info *info,
                      bs_error *err);

/* The grid level set of s: at least one triangle, closed, planned (h,
 * margin as bs_ls_grid_plan_make), sampled. g and info (may be NULL) get the
 * plan and what sampling found; name names the surface in messages. */
int bs_ls_from_surface(const bs_ls_soup *s, const char *name, double h, double margin, bs_ls_grid_plan *g,
                       bs_ls_sample_info *info, bs_levelset **out, bs_error *err);

/* Writes a grid level set: path ending in ".vti" as VTK image data (point
 * data "phi", bs_vti_write), any other as the .bsls file of
 * bs_levelset_grid_save. BS_EINPUT for a level set that is not a grid. */
int bs_ls_sample_write(const bs_levelset *ls, const char *path, bs_error *err);

#ifdef __cplusplus
}
#endif
#endif
