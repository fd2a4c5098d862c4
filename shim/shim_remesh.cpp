// shim_remesh.cpp — a closed triangle surface remeshed isotropically at a
// target edge length by CGAL (bs_shim_remesh_surface, see bs_shim.h).
//
// The soup becomes a closed, outward Surface_mesh (shim_surface_mesh.cpp);
// when the surface is CAD-like (shim_features.cpp) its sharp edges are split
// to at most 4/3 h and constrained; then
// CGAL::Polygon_mesh_processing::isotropic_remeshing (split, collapse, flip,
// tangential relaxation, projection onto the input) for a few iterations.
// Constrained edges are split and collapsed only along their chains and never
// flipped (protect_constraints(false)); protect_constraints(true), which
// leaves them untouched, made the fandisk at diagonal / 36 fold through
// itself.
// The result is checked again: closed by construction, and free of
// self-intersections (a part thinner than about h can fold through itself).
// Deterministic; sequential. Every extern "C" entry catches every exception;
// nothing is printed.

#include <CGAL/Polygon_mesh_processing/detect_features.h>
#include <CGAL/Polygon_mesh_processing/remesh.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <exception>
#include <new>
#include <vector>

#include "bs_shim.h"
#include "shim_features.hpp"
#include "shim_surface_mesh.hpp"

namespace PMP = CGAL::Polygon_mesh_processing;

namespace {

typedef bs_shim::Surface Surface;

// sm's vertices and triangles as C arrays (sm has no removed elements).
int export_soup(const Surface &sm, const char *name, bs_shim_remesh_out *out, bs_error *err) {
  const std::size_t nv = sm.number_of_vertices(), nf = sm.number_of_faces();
  if (nv > (std::size_t)INT32_MAX || nf > (std::size_t)INT32_MAX)
    return bs_error_set(err, BS_EINPUT, "%s: the remeshed surface has %zu triangles, beyond 32-bit indices", name, nf);
  double *x = (double *)std::malloc(3 * nv * sizeof(double));
  int32_t *t = (int32_t *)std::malloc(3 * nf * sizeof(int32_t));
  if (!x || !t) {
    std::free(x);
    std::free(t);
    return bs_error_set(err, BS_ENOMEM, "%s: out of memory for the remeshed surface (%zu triangles)", name, nf);
  }
  for (auto v : sm.vertices()) {
    const auto &p = sm.point(v);
    x[3 * (std::size_t)v] = p.x(), x[3 * (std::size_t)v + 1] = p.y(), x[3 * (std::size_t)v + 2] = p.z();
  }
  std::size_t k = 0;
  for (auto f : sm.faces()) {
    for (auto v : CGAL::vertices_around_face(sm.halfedge(f), sm)) t[k++] = (int32_t)(std::size_t)v;
  }
  out->points = x;
  out->n_points = (int64_t)nv;
  out->tris = t;
  out->n_tris = (int64_t)nf;
  return BS_OK;
}

int remesh(const char *name, const double *pts, int64_t np, const int32_t *tris, int64_t nt,
           const bs_shim_remesh_opts &o, bs_shim_remesh_out *out, bs_error *err) {
  Surface sm;
  int rc = bs_shim::soup_to_closed_surface(name, pts, np, tris, nt, sm, err);
  if (rc) return rc;
  const double h = o.size;
  if (!(h > 0) || !std::isfinite(h)) return bs_error_set(err, BS_EINPUT, "%s: mesh size %g must be > 0", name, h);
  int64_t n_long = 0;
  const bool cad = o.feature_angle > 0 &&
                   bs_shim::cad_like(sm, o.feature_angle, o.feature_min_length > 0 ? o.feature_min_length : 2 * h,
                                     &n_long);
  out->n_features = cad ? n_long : 0;
  auto sharp = sm.add_property_map<Surface::Edge_index, bool>("e:bs_protect", false).first;
  auto corner = sm.add_property_map<Surface::Vertex_index, bool>("v:bs_corner", false).first;
  if (cad) {
    PMP::detect_sharp_edges(sm, o.feature_angle, sharp);
    std::vector<Surface::Edge_index> constrained;
    for (auto e : sm.edges())
      if (sharp[e]) constrained.push_back(e);
    PMP::split_long_edges(constrained, 4.0 / 3.0 * h, sm, CGAL::parameters::edge_is_constrained_map(sharp));
    for (auto v : sm.vertices()) { // where chains end or meet: kept where they are
      int k = 0;
      for (auto g : CGAL::halfedges_around_source(v, sm)) k += sharp[sm.edge(g)] ? 1 : 0;
      corner[v] = k != 0 && k != 2;
    }
  }
  const unsigned iters = o.iterations > 0 ? (unsigned)o.iterations : 3u;
  PMP::isotropic_remeshing(faces(sm), h, sm,
                           CGAL::parameters::number_of_iterations(iters)
                               .edge_is_constrained_map(sharp)
                               .vertex_is_constrained_map(corner)
                               .protect_constraints(false));
  sm.remove_property_map(sharp);
  sm.remove_property_map(corner);
  sm.collect_garbage();
  if (PMP::does_self_intersect(sm))
    return bs_error_set(err, BS_EINPUT,
                        "%s: the surface remeshed at h = %g intersects itself (a part of it is thinner than about "
                        "h): use a smaller size, or CGAL Mesh_3 (--mesher cgal)",
                        name, h);
  return export_soup(sm, name, out, err);
}

} // namespace

extern "C" int bs_shim_remesh_surface(const char *name, const double *points, int64_t n_points, const int32_t *tris,
                                      int64_t n_tris, const bs_shim_remesh_opts *opts, bs_shim_remesh_out *out,
                                      bs_error *err) {
  if (!name) name = "(surface)";
  if (!points || !tris || !opts || !out)
    return bs_error_set(err, BS_EINPUT, "%s: bs_shim_remesh_surface: NULL argument", name);
  *out = bs_shim_remesh_out{};
  try {
    return remesh(name, points, n_points, tris, n_tris, *opts, out, err);
  } catch (const std::bad_alloc &) {
    bs_shim_free(out->points), bs_shim_free(out->tris), *out = bs_shim_remesh_out{};
    return bs_error_set(err, BS_ENOMEM, "%s: out of memory while CGAL remeshed the surface", name);
  } catch (const std::exception &e) {
    bs_shim_free(out->points), bs_shim_free(out->tris), *out = bs_shim_remesh_out{};
    return bs_error_set(err, BS_EINPUT, "%s: CGAL isotropic remeshing failed: %s", name, e.what());
  } catch (...) {
    bs_shim_free(out->points), bs_shim_free(out->tris), *out = bs_shim_remesh_out{};
    return bs_error_set(err, BS_EINPUT, "%s: CGAL isotropic remeshing failed (unknown exception)", name);
  }
}
