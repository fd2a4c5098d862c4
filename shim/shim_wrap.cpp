// shim_wrap.cpp — a triangle soup wrapped into a closed 2-manifold surface by
// CGAL's 3D Alpha Wrapping (bs_shim_alpha_wrap), and the audit of a surface
// (bs_shim_surface_audit) with CGAL's Polygon_mesh_processing. See bs_shim.h
// for the contracts and the rule that picks alpha and the offset.
//
// CGAL::alpha_wrap_3 (CGAL 5.5) carves a Delaunay triangulation from the
// outside with a ball of radius alpha and inserts Steiner points on the
// offset surface at distance `offset` from the input: its output is closed,
// 2-manifold and free of self-intersections by construction, whatever the
// input (non-manifold edges, overlapping or nearly overlapping facets, small
// holes, a soup). The output is audited anyway (an audit failure is
// BS_EINTERNAL). The deadline is checked in the wrap's visitor before each
// facet it treats; past it, the wrap stops with BS_EINPUT naming the budget.
//
// Every extern "C" entry catches every exception; nothing is printed.

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/manifoldness.h>
#include <CGAL/Polygon_mesh_processing/measure.h>
#include <CGAL/Polygon_mesh_processing/orient_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/orientation.h>
#include <CGAL/Polygon_mesh_processing/polygon_mesh_to_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/alpha_wrap_3.h>

#include <algorithm>
#include <array>
#include <map>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <exception>
#include <new>
#include <vector>

#include "bs_limits.h"
#include "bs_shim.h"

namespace {

typedef CGAL::Exact_predicates_inexact_constructions_kernel K;
typedef K::Point_3 P;
typedef CGAL::Surface_mesh<P> Mesh;
typedef std::array<std::size_t, 3> Tri;
namespace PMP = CGAL::Polygon_mesh_processing;

struct budget_exceeded {};

// Stops the wrap (throws budget_exceeded) once bs_seconds() passes the
// deadline; checked every 256 facets (a facet is microseconds).
struct Deadline_visitor : CGAL::Alpha_wraps_3::internal::Wrapping_default_visitor {
  double deadline = 0;
  std::size_t calls = 0;
  template <typename Wrapper, typename Gate> void before_facet_treatment(const Wrapper &, const Gate &) {
    if (deadline > 0 && (++calls & 255) == 0 && bs_seconds() > deadline) throw budget_exceeded();
  }
};

// The soup from C, checked: indices in range, finite coordinates, limits.
int copy_soup(const char *name, const double *x, int64_t np, const int32_t *t, int64_t nt, std::vector<P> &pts,
              std::vector<Tri> &tris, bs_error *err) {
  if (!x || !t || np <= 0 || nt <= 0)
    return bs_error_set(err, BS_EINPUT, "%s: the surface is empty (%lld points, %lld triangles)", name,
                        (long long)np, (long long)nt);
  if (np > BS_MAX_SURFACE_POINTS || nt > BS_MAX_SURFACE_FACES)
    return bs_error_set(err, BS_EINPUT, "%s: %lld points and %lld triangles exceed bigstep's limits", name,
                        (long long)np, (long long)nt);
  pts.reserve((std::size_t)np);
  for (int64_t i = 0; i < np; i++) {
    const double *p = x + 3 * i;
    if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2]))
      return bs_error_set(err, BS_ENUMERIC, "%s: point %lld has a non-finite coordinate", name, (long long)i);
    pts.emplace_back(p[0], p[1], p[2]);
  }
  tris.reserve((std::size_t)nt);
  for (int64_t e = 0; e < nt; e++) {
    const int32_t *v = t + 3 * e;
    for (int k = 0; k < 3; k++)
      if (v[k] < 0 || v[k] >= np)
        return bs_error_set(err, BS_EINPUT, "%s: triangle %lld refers to point %d, but there are %lld points", name,
                            (long long)e, v[k], (long long)np);
    tris.push_back({(std::size_t)v[0], (std::size_t)v[1], (std::size_t)v[2]});
  }
  return BS_OK;
}

// Whether every edge of the polygons is in exactly two of them.
bool soup_closed(const std::vector<std::vector<std::size_t>> &polys) {
  std::map<std::pair<std::size_t, std::size_t>, int> count;
  for (const auto &f : polys)
    for (int k = 0; k < 3; k++) count[std::minmax(f[k], f[(k + 1) % 3])]++;
  for (const auto &e : count)
    if (e.second != 2) return false;
  return !polys.empty();
}

// |enclosed volume| of the soup once consistently oriented (divergence
// theorem; exact for a closed orientable surface), its area, and whether
// it is closed then.
void soup_measures(std::vector<P> pts, std::vector<Tri> tris, double *volume, double *area, int *closed) {
  std::vector<std::vector<std::size_t>> polys;
  polys.reserve(tris.size());
  for (const Tri &f : tris)
    if (f[0] != f[1] && f[1] != f[2] && f[2] != f[0]) polys.push_back({f[0], f[1], f[2]});
  PMP::orient_polygon_soup(pts, polys);
  double v = 0, a = 0;
  for (const auto &f : polys) {
    const P &p = pts[f[0]], &q = pts[f[1]], &r = pts[f[2]];
    v += CGAL::scalar_product(p - CGAL::ORIGIN, CGAL::cross_product(q - CGAL::ORIGIN, r - CGAL::ORIGIN)) / 6.0;
    a += std::sqrt(CGAL::squared_area(p, q, r));
  }
  *volume = std::fabs(v);
  *area = a;
  *closed = soup_closed(polys) ? 1 : 0;
}

// The mesh as C arrays allocated with malloc (freed by bs_shim_free).
int mesh_out(Mesh &m, double **x, int64_t *np, int32_t **t, int64_t *nt, bs_error *err) {
  m.collect_garbage();
  std::size_t nv = m.number_of_vertices(), nf = m.number_of_faces();
  *x = (double *)std::malloc(3 * nv * sizeof(double) + 1);
  *t = (int32_t *)std::malloc(3 * nf * sizeof(int32_t) + 1);
  if (!*x || !*t) {
    std::free(*x), std::free(*t);
    *x = nullptr, *t = nullptr;
    return bs_error_set(err, BS_ENOMEM, "out of memory for the wrap's %zu points and %zu triangles", nv, nf);
  }
  for (Mesh::Vertex_index v : m.vertices())
    for (int k = 0; k < 3; k++) (*x)[3 * (std::size_t)v + k] = m.point(v)[k];
  std::size_t e = 0;
  for (Mesh::Face_index f : m.faces()) {
    int k = 0;
    for (Mesh::Vertex_index v : CGAL::vertices_around_face(m.halfedge(f), m)) (*t)[3 * e + k++] = (int32_t)v;
    e++;
  }
  *np = (int64_t)nv;
  *nt = (int64_t)nf;
  return BS_OK;
}

// The audit of a soup (see bs_shim_surface_audit).
void audit(std::vector<P> pts, std::vector<Tri> tris, bs_shim_surface_audit_out *a) {
  *a = bs_shim_surface_audit_out{};
  std::vector<std::vector<std::size_t>> polys;
  for (const Tri &f : tris) polys.push_back({f[0], f[1], f[2]});
  a->manifold = PMP::is_polygon_soup_a_polygon_mesh(polys) ? 1 : 0;
  if (!a->manifold) return;
  Mesh m;
  PMP::polygon_soup_to_polygon_mesh(pts, polys, m);
  for (auto h : m.halfedges()) a->border_edges += m.is_border(h) ? 1 : 0;
  a->closed = a->border_edges == 0;
  a->self_intersecting = PMP::does_self_intersect(m) ? 1 : 0;
  if (a->closed) a->volume = PMP::volume(m);
  a->components = (int64_t)PMP::connected_components(
      m, m.add_property_map<Mesh::Face_index, std::size_t>("f:cc", 0).first);
}

int wrap(const char *name, const double *x, int64_t np, const int32_t *t, int64_t nt, const bs_shim_wrap_opts *o,
         bs_shim_wrap_out *out, bs_error *err) {
  if (!o || !(o->size > 0) || !std::isfinite(o->size))
    return bs_error_set(err, BS_EINPUT, "%s: the wrap needs a size > 0 (got %g)", name, o ? o->size : 0.0);
  std::vector<P> pts;
  std::vector<Tri> tris;
  int rc = copy_soup(name, x, np, t, nt, pts, tris, err);
  if (rc) return rc;
  std::size_t solid = 0;
  for (const Tri &f : tris) solid += !CGAL::collinear(pts[f[0]], pts[f[1]], pts[f[2]]);
  if (solid == 0)
    return bs_error_set(err, BS_EINPUT, "%s: nothing to wrap: all its %lld triangles are degenerate", name,
                        (long long)nt);
  out->alpha = o->alpha > 0 ? o->alpha : BS_WRAP_ALPHA * o->size;
  out->offset = o->offset > 0 ? o->offset : BS_WRAP_OFFSET * o->size;
  soup_measures(pts, tris, &out->volume_in, &out->area_in, &out->input_closed);
  const double t0 = bs_seconds();
  Mesh m;
  Deadline_visitor vis;
  vis.deadline = o->deadline;
  try {
    CGAL::alpha_wrap_3(pts, tris, out->alpha, out->offset, m, CGAL::parameters::default_values(),
                       CGAL::parameters::visitor(vis));
  } catch (const budget_exceeded &) {
    return bs_error_set(err, BS_EINPUT, "%s: the meshing time budget was exceeded during the alpha wrap (%.3g s in it)",
                        name, bs_seconds() - t0);
  }
  out->seconds = bs_seconds() - t0;
  if (m.number_of_faces() == 0)
    return bs_error_set(err, BS_EINPUT, "%s: the alpha wrap (alpha %g, offset %g) is empty", name, out->alpha,
                        out->offset);
  if (!PMP::is_outward_oriented(m)) PMP::reverse_face_orientations(m);
  out->volume = PMP::volume(m);
  return mesh_out(m, &out->points, &out->n_points, &out->tris, &out->n_tris, err);
}

// The wrap's output audited: closed, 2-manifold, no self-intersection.
int check_wrap(const char *name, const bs_shim_wrap_out *out, bs_error *err) {
  std::vector<P> pts;
  std::vector<Tri> tris;
  int rc = copy_soup(name, out->points, out->n_points, out->tris, out->n_tris, pts, tris, err);
  if (rc) return rc;
  bs_shim_surface_audit_out a;
  audit(pts, tris, &a);
  if (a.closed && a.manifold && !a.self_intersecting) return BS_OK;
  return bs_error_set(err, BS_EINTERNAL, "%s: the alpha wrap is not sound (closed %d, manifold %d, self-intersecting %d)",
                      name, a.closed, a.manifold, a.self_intersecting);
}

template <typename F> int guarded(const char *what, F f, bs_error *err) {
  try {
    return f();
  } catch (const std::bad_alloc &) {
    return bs_error_set(err, BS_ENOMEM, "out of memory %s", what);
  } catch (const std::exception &e) {
    return bs_error_set(err, BS_EINTERNAL, "CGAL failed %s: %s", what, e.what());
  } catch (...) {
    return bs_error_set(err, BS_EINTERNAL, "CGAL failed %s (unknown exception)", what);
  }
}

} // namespace

extern "C" int bs_shim_alpha_wrap(const char *name, const double *points, int64_t n_points, const int32_t *tris,
                                  int64_t n_tris, const bs_shim_wrap_opts *opts, bs_shim_wrap_out *out,
                                  bs_error *err) {
  if (!out) return bs_error_set(err, BS_EINPUT, "bs_shim_alpha_wrap: NULL output");
  *out = bs_shim_wrap_out{};
  if (!name) name = "surface";
  int rc = guarded("while wrapping the surface", [&] { return wrap(name, points, n_points, tris, n_tris, opts, out, err); },
                   err);
  if (!rc) rc = guarded("while auditing the wrap", [&] { return check_wrap(name, out, err); }, err);
  if (rc) {
    bs_shim_free(out->points);
    bs_shim_free(out->tris);
    const double a = out->alpha, o = out->offset;
    *out = bs_shim_wrap_out{};
    out->alpha = a, out->offset = o;
  }
  return rc;
}

extern "C" int bs_shim_surface_audit(const double *points, int64_t n_points, const int32_t *tris, int64_t n_tris,
                                     bs_shim_surface_audit_out *out, bs_error *err) {
  if (!out) return bs_error_set(err, BS_EINPUT, "bs_shim_surface_audit: NULL output");
  *out = bs_shim_surface_audit_out{};
  return guarded("while auditing the surface",
                 [&] {
                   std::vector<P> pts;
                   std::vector<Tri> t;
                   int rc = copy_soup("surface", points, n_points, tris, n_tris, pts, t, err);
                   if (!rc) audit(pts, t, out);
                   return rc;
                 },
                 err);
}
