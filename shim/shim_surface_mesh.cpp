// shim_surface_mesh.cpp — a soup from C checked and turned into a closed,
// outward Surface_mesh (bs_shim::soup_to_closed_surface, see
// shim_surface_mesh.hpp). The callers catch CGAL's exceptions.

#include <CGAL/Polygon_mesh_processing/orient_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/orientation.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>

#include <array>
#include <cmath>
#include <cstddef>
#include <vector>

#include "bs_limits.h"
#include "shim_surface_mesh.hpp"

namespace PMP = CGAL::Polygon_mesh_processing;

namespace bs_shim {

namespace {

// The soup's points and triangles, checked (indices, finiteness, repeats).
int copy_soup(const char *name, const double *pts, int64_t np, const int32_t *tris, int64_t nt,
              std::vector<Epick::Point_3> &P, std::vector<std::array<std::size_t, 3>> &F, bs_error *err) {
  if (np <= 0 || nt <= 0)
    return bs_error_set(err, BS_EINPUT, "%s: the surface is empty (%lld points, %lld triangles)", name, (long long)np,
                        (long long)nt);
  if (np > BS_MAX_SURFACE_POINTS || nt > BS_MAX_SURFACE_FACES)
    return bs_error_set(err, BS_EINPUT, "%s: %lld points and %lld triangles exceed bigstep's limits", name,
                        (long long)np, (long long)nt);
  P.reserve((std::size_t)np);
  for (int64_t i = 0; i < np; i++) {
    const double *p = pts + 3 * i;
    if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2]))
      return bs_error_set(err, BS_ENUMERIC, "%s: point %lld has a non-finite coordinate", name, (long long)i);
    P.emplace_back(p[0], p[1], p[2]);
  }
  F.reserve((std::size_t)nt);
  for (int64_t t = 0; t < nt; t++) {
    const int32_t *v = tris + 3 * t;
    for (int k = 0; k < 3; k++)
      if (v[k] < 0 || v[k] >= np)
        return bs_error_set(err, BS_EINPUT, "%s: triangle %lld refers to point %d, but there are %lld points", name,
                            (long long)t, v[k], (long long)np);
    if (v[0] == v[1] || v[1] == v[2] || v[2] == v[0])
      return bs_error_set(err, BS_EINPUT, "%s: triangle %lld repeats a vertex (%d %d %d)", name, (long long)t, v[0],
                          v[1], v[2]);
    F.push_back({(std::size_t)v[0], (std::size_t)v[1], (std::size_t)v[2]});
  }
  return BS_OK;
}

} // namespace

int soup_to_closed_surface(const char *name, const double *pts, int64_t np, const int32_t *tris, int64_t nt,
                           Surface &sm, bs_error *err) {
  std::vector<Epick::Point_3> P;
  std::vector<std::array<std::size_t, 3>> F;
  int rc = copy_soup(name, pts, np, tris, nt, P, F, err);
  if (rc) return rc;
  if (!PMP::is_polygon_soup_a_polygon_mesh(F) && !PMP::orient_polygon_soup(P, F))
    return bs_error_set(err, BS_EINPUT,
                        "%s: the surface is not an orientable 2-manifold (an edge is shared by more than two "
                        "triangles, or the triangles cannot be oriented consistently)",
                        name);
  PMP::polygon_soup_to_polygon_mesh(P, F, sm);
  std::size_t border = 0;
  for (auto h : sm.halfedges())
    if (sm.is_border(h)) border++;
  if (border > 0)
    return bs_error_set(err, BS_EINPUT,
                        "%s: the surface is not closed: %zu edges lie on a hole (a volume can be meshed only inside "
                        "a closed surface)",
                        name, border);
  if (PMP::does_self_intersect(sm))
    return bs_error_set(err, BS_EINPUT, "%s: the surface intersects itself (a volume needs a surface that does not)",
                        name);
  if (!PMP::is_outward_oriented(sm)) PMP::reverse_face_orientations(sm);
  return BS_OK;
}

} // namespace bs_shim
