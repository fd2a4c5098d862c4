// shim_surface_mesh.hpp — a triangle soup from C as a closed, outward
// CGAL::Surface_mesh (not public API; C++ only). Used by the volume mesher
// (shim_mesh3.cpp) and the surface measures (shim_distance.cpp).
#ifndef BS_SHIM_SURFACE_MESH_HPP
#define BS_SHIM_SURFACE_MESH_HPP

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Surface_mesh.h>

#include <cstdint>

#include "bs_shim.h"

namespace bs_shim {

typedef CGAL::Exact_predicates_inexact_constructions_kernel Epick;
typedef CGAL::Surface_mesh<Epick::Point_3> Surface;

// The soup (np points, nt triangles of 0-based indices) into sm: every index
// in range, no triangle with a repeated vertex, an orientable 2-manifold
// (the soup is oriented consistently when it is not), closed (no border
// edge), free of self-intersections, faces turned outward. BS_OK, or
// BS_EINPUT naming `name` and what is wrong (BS_ENUMERIC: a non-finite point).
int soup_to_closed_surface(const char *name, const double *pts, int64_t np, const int32_t *tris, int64_t nt,
                           Surface &sm, bs_error *err);

} // namespace bs_shim

#endif
