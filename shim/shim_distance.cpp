// shim_distance.cpp — measures between surfaces, for tests and reports:
// the one-sided (sampled) distance from one triangle surface to another, and
// the sharp edges of a closed surface (see bs_shim.h).
//
// Every extern "C" entry catches every exception; nothing is printed.

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Polygon_mesh_processing/detect_features.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <exception>
#include <new>
#include <vector>

#include "bs_limits.h"
#include "bs_shim.h"
#include "shim_surface_mesh.hpp"

namespace {

typedef bs_shim::Epick K;
typedef K::Point_3 Point;
typedef K::Triangle_3 Triangle;
typedef std::vector<Triangle>::const_iterator Tri_iter;
typedef CGAL::AABB_triangle_primitive<K, Tri_iter> Primitive;
typedef CGAL::AABB_tree<CGAL::AABB_traits<K, Primitive>> Tree;

// The triangles of a soup, indices and coordinates checked.
int triangles(const char *what, const double *p, int64_t np, const int32_t *t, int64_t nt, std::vector<Triangle> &out,
              bs_error *err) {
  if (!p || !t || np <= 0 || nt <= 0 || np > BS_MAX_SURFACE_POINTS || nt > BS_MAX_SURFACE_FACES)
    return bs_error_set(err, BS_EINPUT, "bs_shim_surface_distance: %s surface is empty or too large (%lld points, %lld triangles)",
                        what, (long long)np, (long long)nt);
  for (int64_t i = 0; i < 3 * np; i++)
    if (!std::isfinite(p[i]))
      return bs_error_set(err, BS_ENUMERIC, "bs_shim_surface_distance: %s surface: point %lld is not finite", what,
                          (long long)(i / 3));
  out.reserve((std::size_t)nt);
  for (int64_t f = 0; f < nt; f++) {
    const int32_t *v = t + 3 * f;
    for (int k = 0; k < 3; k++)
      if (v[k] < 0 || v[k] >= np)
        return bs_error_set(err, BS_EINPUT, "bs_shim_surface_distance: %s surface: triangle %lld refers to point %d of %lld",
                            what, (long long)f, v[k], (long long)np);
    const double *a = p + 3 * v[0], *b = p + 3 * v[1], *c = p + 3 * v[2];
    out.emplace_back(Point(a[0], a[1], a[2]), Point(b[0], b[1], b[2]), Point(c[0], c[1], c[2]));
  }
  return BS_OK;
}

// Largest distance to the tree over the points of a barycentric grid on tri
// with about `spacing` between them (its vertices included).
void sample_triangle(const Tree &tree, const Triangle &tri, double spacing, double *best, double where[3]) {
  double longest = 0;
  for (int e = 0; e < 3; e++)
    longest = std::max(longest, std::sqrt(CGAL::squared_distance(tri[e], tri[(e + 1) % 3])));
  const int n = std::max(1, std::min(1000, (int)std::ceil(longest / spacing)));
  for (int i = 0; i <= n; i++)
    for (int j = 0; i + j <= n; j++) {
      const double u = (double)i / n, v = (double)j / n, w = 1.0 - u - v;
      const Point q(w * tri[0].x() + u * tri[1].x() + v * tri[2].x(), w * tri[0].y() + u * tri[1].y() + v * tri[2].y(),
                    w * tri[0].z() + u * tri[1].z() + v * tri[2].z());
      const double d = std::sqrt(tree.squared_distance(q));
      if (d > *best) {
        *best = d;
        where[0] = q.x();
        where[1] = q.y();
        where[2] = q.z();
      }
    }
}

int surface_distance(const double *pa, int64_t na, const int32_t *ta, int64_t nta, const double *pb, int64_t nb,
                     const int32_t *tb, int64_t ntb, double spacing, double *max_dist, double where[3], bs_error *err) {
  if (!(spacing > 0) || !std::isfinite(spacing))
    return bs_error_set(err, BS_EINPUT, "bs_shim_surface_distance: spacing %g must be > 0", spacing);
  std::vector<Triangle> A, B;
  int rc = triangles("the first", pa, na, ta, nta, A, err);
  if (!rc) rc = triangles("the second", pb, nb, tb, ntb, B, err);
  if (rc) return rc;
  Tree tree(B.begin(), B.end());
  tree.accelerate_distance_queries();
  double best = 0, at[3] = {pa[0], pa[1], pa[2]};
  for (const Triangle &tri : A) sample_triangle(tree, tri, spacing, &best, at);
  *max_dist = best;
  if (where) std::copy(at, at + 3, where);
  return BS_OK;
}

int sharp_edges(const double *p, int64_t np, const int32_t *t, int64_t nt, double angle, double **segments,
                int64_t *n_edges, bs_error *err) {
  bs_shim::Surface sm;
  int rc = bs_shim::soup_to_closed_surface("bs_shim_sharp_edges", p, np, t, nt, sm, err);
  if (rc) return rc;
  auto sharp = sm.add_property_map<bs_shim::Surface::Edge_index, bool>("e:sharp", false).first;
  CGAL::Polygon_mesh_processing::detect_sharp_edges(sm, angle, sharp);
  std::vector<double> out;
  for (auto e : sm.edges())
    if (sharp[e])
      for (auto v : {sm.source(sm.halfedge(e)), sm.target(sm.halfedge(e))}) {
        const Point &q = sm.point(v);
        out.insert(out.end(), {q.x(), q.y(), q.z()});
      }
  double *o = (double *)std::malloc((out.size() + 1) * sizeof(double));
  if (!o) return bs_error_set(err, BS_ENOMEM, "bs_shim_sharp_edges: out of memory");
  std::copy(out.begin(), out.end(), o);
  *segments = o;
  *n_edges = (int64_t)(out.size() / 6);
  return BS_OK;
}

} // namespace

extern "C" int bs_shim_surface_distance(const double *pa, int64_t na, const int32_t *ta, int64_t nta, const double *pb,
                                        int64_t nb, const int32_t *tb, int64_t ntb, double spacing, double *max_dist,
                                        double where[3], bs_error *err) {
  if (!max_dist) return bs_error_set(err, BS_EINPUT, "bs_shim_surface_distance: NULL output");
  *max_dist = 0;
  try {
    return surface_distance(pa, na, ta, nta, pb, nb, tb, ntb, spacing, max_dist, where, err);
  } catch (const std::bad_alloc &) {
    return bs_error_set(err, BS_ENOMEM, "bs_shim_surface_distance: out of memory");
  } catch (const std::exception &e) {
    return bs_error_set(err, BS_EINPUT, "bs_shim_surface_distance: CGAL failed: %s", e.what());
  } catch (...) {
    return bs_error_set(err, BS_EINPUT, "bs_shim_surface_distance: CGAL failed (unknown exception)");
  }
}

extern "C" int bs_shim_sharp_edges(const double *points, int64_t n_points, const int32_t *tris, int64_t n_tris,
                                   double angle, double **segments, int64_t *n_edges, bs_error *err) {
  if (!points || !tris || !segments || !n_edges)
    return bs_error_set(err, BS_EINPUT, "bs_shim_sharp_edges: NULL argument");
  *segments = NULL;
  *n_edges = 0;
  try {
    return sharp_edges(points, n_points, tris, n_tris, angle, segments, n_edges, err);
  } catch (const std::bad_alloc &) {
    return bs_error_set(err, BS_ENOMEM, "bs_shim_sharp_edges: out of memory");
  } catch (const std::exception &e) {
    return bs_error_set(err, BS_EINPUT, "bs_shim_sharp_edges: CGAL failed: %s", e.what());
  } catch (...) {
    return bs_error_set(err, BS_EINPUT, "bs_shim_sharp_edges: CGAL failed (unknown exception)");
  }
}
