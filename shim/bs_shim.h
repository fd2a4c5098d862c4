/* bs_shim.h — CGAL behind a plain C interface (the only C++ in bigstep).
 *
 * In the style of Gmsh's C API: plain C types, (pointer, count) pairs, a
 * try/catch at every entry so that no C++ exception crosses into C, and
 * bs_shim_free for every array the shim allocates.
 *
 * Status: 0 on success, a negative BS_E* code on failure with err filled
 * (the message names the file or the argument at fault).
 */
#ifndef BS_SHIM_H
#define BS_SHIM_H

#include <stdint.h>

#include "bs_base.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Frees an array returned by the shim (NULL is fine). */
void bs_shim_free(void *p);

/* Reads a triangulated surface in any format CGAL reads as a polygon soup
 * (.off, .obj, .ply, .stl); polygons with more than three vertices are
 * triangulated. Returns *n_points points (3 doubles each) and *n_tris
 * triangles (3 indices each), both allocated by the shim. */
int bs_shim_read_surface(const char *path, double **points, int64_t *n_points, int32_t **tris,
                         int64_t *n_tris, bs_error *err);

#ifdef __cplusplus
}
#endif
#endif
