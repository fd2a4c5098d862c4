/* bs_ls_surface.h — the zero level set of an analytic obstacle as a
 * triangle surface, at the obstacle's pose at a time t: what a run writes so
 * that the obstacle can be seen beside the bodies (runfolder/bs_obstacle_output.h).
 *
 * Shapes (bs_levelset.h), tessellated in the shape's local frame and placed
 * by its frame at t (x = M y + c):
 *   half-space  a square patch of the plane, 8 x 8 cells of two triangles,
 *               centred at the projection of the centre of the box [lo, hi]
 *               (e.g. the bodies' bounding box) onto the plane, of half side
 *               the box's diagonal (at least 1e-3 m); without a box, around
 *               the plane's point c;
 *   sphere      16 rings of constant polar angle by 32 azimuths, and the two
 *               poles (482 points, 960 triangles);
 *   box         its 6 faces, two triangles each (8 points, 12 triangles);
 *   cylinder    64 sides and two capping fans (130 points, 256 triangles);
 *   torus       64 x 32 quads in the (major, minor) angles, two triangles each.
 * Every point lies on phi = 0 up to rounding (the shapes' exact SDFs vanish
 * there: polygon corners on circles, sphere points normalised to the radius).
 * Orientation: every triangle (a, b, c) has (b - a) x (c - a) pointing to
 * phi > 0, i.e. out of the obstacle into the free space, so the complement
 * (inside-out) flips the triangles. The closed shapes give closed surfaces in
 * which every edge is shared by two triangles of opposite orientation.
 *
 * Units: metres. Ownership: bs_ls_surface_make fills *out with arrays the
 * caller frees with bs_ls_surface_free. Status: 0; BS_EINPUT for a grid
 * level set (write it as image data instead); BS_ENOMEM. */
#ifndef BS_LS_SURFACE_H
#define BS_LS_SURFACE_H

#include <stdint.h>

#include "bs_base.h"
#include "bs_levelset.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct bs_ls_surface {
  int32_t n_points;
  double *x;        /* 3 per point, world coordinates at time t */
  int32_t n_tris;
  int32_t *tris;    /* 3 per triangle, oriented as above        */
} bs_ls_surface;

/* The surface of ls at time t; lo, hi size a half-space's patch (ignored by
 * the other shapes; may be NULL for them). */
int bs_ls_surface_make(const bs_levelset *ls, double t, const double lo[3], const double hi[3], bs_ls_surface *out,
                       bs_error *err);

/* Frees the arrays and zeroes s (NULL accepted). */
void bs_ls_surface_free(bs_ls_surface *s);

#ifdef __cplusplus
}
#endif
#endif
