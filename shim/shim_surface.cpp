// shim_surface.cpp — triangulated surfaces read by CGAL, handed to C.
//
// The file becomes a polygon soup (points + polygons of point indices, no
// topology): .off through bigstep's own reader (shim_off.cpp), .obj, .ply,
// .stl and .ts through CGAL::IO::read_polygon_soup, after shim_surface_check
// has checked a .stl's or .ply's counts against the file's size (see
// shim_soup.hpp for what CGAL's readers would do otherwise). Polygons of
// k > 3 vertices are split into k - 2 triangles on their own vertices: a fan
// from the first vertex when the polygon is convex (every turn the same way
// about its Newell normal), else the triangulation of the polygon as a
// polyline that CGAL's hole filling finds (Liepa's dynamic programme, worst
// dihedral angle first, then area: a triangle outside a planar non-convex
// polygon folds back onto the others, the worst angle there is, so none is
// chosen). A fan of an L-shaped hexagon has a triangle outside it, which
// overlaps the faces next to it (corner_poly.off: 12 intersecting pairs, and
// a repaired surface that Mesh_3 pinched).
//
// Every entry point catches every exception; nothing is printed (the readers
// run with verbose = false).

#include <CGAL/IO/polygon_soup_io.h>
#include <CGAL/Polygon_mesh_processing/triangulate_hole.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <new>
#include <string>
#include <vector>

#include "bs_limits.h"
#include "bs_shim.h"
#include "shim_soup.hpp"

namespace {

using bs_shim::Kernel;
using bs_shim::Point;
using bs_shim::Polygon;

// The soup of the file: OFF by bigstep, the rest by CGAL after the checks.
int read_soup(const char *path, const std::string &ext, std::vector<Point> &points, std::vector<Polygon> &polygons,
              bs_error *err) {
  if (ext == "off") return bs_shim::read_off_soup(path, points, polygons, err);
  if (ext == "stl" || ext == "ply") {
    std::string bytes;
    int rc = bs_shim::read_bytes(path, bytes, err);
    if (!rc) rc = ext == "stl" ? bs_shim::check_stl(path, bytes, err) : bs_shim::check_ply(path, bytes, err);
    if (rc) return rc;
  }
  bool ok = CGAL::IO::read_polygon_soup(std::string(path), points, polygons, CGAL::parameters::verbose(false));
  if (!ok) return bs_error_set(err, BS_EINPUT, "%s: CGAL could not read the file as .%s", path, ext.c_str());
  return BS_OK;
}

// Polygons of more vertices than this that are not convex are split as fans
// all the same: the hole filling is cubic in the vertex count.
constexpr std::size_t MAX_FILLED_POLYGON = 256;

// Whether poly turns the same way at every vertex about its Newell normal.
bool convex(const std::vector<Point> &pts, const Polygon &poly) {
  const std::size_t k = poly.size();
  double n[3] = {0, 0, 0};
  for (std::size_t i = 0; i < k; i++) {
    const Point &a = pts[poly[i]], &b = pts[poly[(i + 1) % k]];
    n[0] += (a.y() - b.y()) * (a.z() + b.z());
    n[1] += (a.z() - b.z()) * (a.x() + b.x());
    n[2] += (a.x() - b.x()) * (a.y() + b.y());
  }
  for (std::size_t i = 0; i < k; i++) {
    const Point &a = pts[poly[i]], &b = pts[poly[(i + 1) % k]], &c = pts[poly[(i + 2) % k]];
    const Kernel::Vector_3 t = CGAL::cross_product(b - a, c - b);
    if (t.x() * n[0] + t.y() * n[1] + t.z() * n[2] < 0) return false;
  }
  return true;
}

// The k - 2 triangles of poly (k vertices) into t, 3 indices each.
void split_polygon(const std::vector<Point> &pts, const Polygon &poly, int32_t *t) {
  const std::size_t k = poly.size();
  if (k > 3 && k <= MAX_FILLED_POLYGON && !convex(pts, poly)) {
    std::vector<Point> line;
    for (std::size_t v : poly) line.push_back(pts[v]);
    std::vector<CGAL::Triple<int, int, int>> tris;
    CGAL::Polygon_mesh_processing::triangulate_hole_polyline(line, std::back_inserter(tris));
    bool inside = tris.size() == k - 2;
    for (const auto &tr : tris)
      inside = inside && tr.first >= 0 && tr.second >= 0 && tr.third >= 0 && (std::size_t)tr.first < k &&
               (std::size_t)tr.second < k && (std::size_t)tr.third < k;
    if (inside) { // k - 2 triangles on the polygon's own vertices, else the fan
      for (std::size_t j = 0; j < tris.size(); j++) {
        t[3 * j + 0] = (int32_t)poly[(std::size_t)tris[j].first];
        t[3 * j + 1] = (int32_t)poly[(std::size_t)tris[j].second];
        t[3 * j + 2] = (int32_t)poly[(std::size_t)tris[j].third];
      }
      return;
    }
  }
  for (std::size_t j = 1; j + 1 < k; j++) { // fan (v0, vj, vj+1)
    t[3 * (j - 1) + 0] = (int32_t)poly[0];
    t[3 * (j - 1) + 1] = (int32_t)poly[j];
    t[3 * (j - 1) + 2] = (int32_t)poly[j + 1];
  }
}

std::string lower_extension(const char *path) {
  std::string p(path);
  std::size_t dot = p.find_last_of('.');
  std::size_t slash = p.find_last_of('/');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return std::string();
  std::string ext = p.substr(dot + 1);
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return (char)std::tolower(c); });
  return ext;
}

int read_surface(const char *path, double **points_out, int64_t *n_points_out, int32_t **tris_out,
                 int64_t *n_tris_out, bs_error *err) {
  std::FILE *f = std::fopen(path, "rb");
  if (!f) return bs_error_set(err, BS_EIO, "%s: cannot open the surface file", path);
  std::fclose(f);

  const std::string ext = lower_extension(path);
  std::vector<Point> points;
  std::vector<Polygon> polygons;
  if (ext != "off" && ext != "obj" && ext != "ply" && ext != "stl" && ext != "ts")
    return bs_error_set(err, BS_EINPUT,
                        "%s: unsupported surface format '.%s' (expected .off, .obj, .ply, .stl or .ts)", path,
                        ext.c_str());
  int rc = read_soup(path, ext, points, polygons, err);
  if (rc) return rc;
  if (points.empty() || polygons.empty())
    return bs_error_set(err, BS_EINPUT, "%s: the surface is empty (%zu points, %zu polygons)", path, points.size(),
                        polygons.size());
  if (points.size() > (std::size_t)BS_MAX_SURFACE_POINTS)
    return bs_error_set(err, BS_EINPUT, "%s: %zu points exceed bigstep's limit of %ld", path, points.size(),
                        (long)BS_MAX_SURFACE_POINTS);

  for (std::size_t i = 0; i < points.size(); i++) {
    const Point &p = points[i];
    if (!std::isfinite(p.x()) || !std::isfinite(p.y()) || !std::isfinite(p.z()))
      return bs_error_set(err, BS_EINPUT, "%s: point %zu has a non-finite coordinate", path, i);
  }
  std::size_t n_tris = 0;
  for (std::size_t i = 0; i < polygons.size(); i++) {
    const Polygon &poly = polygons[i];
    if (poly.size() < 3 || poly.size() > (std::size_t)BS_MAX_POLYGON_VERTICES)
      return bs_error_set(err, BS_EINPUT, "%s: polygon %zu has %zu vertices (3 to %ld accepted)", path, i,
                          poly.size(), (long)BS_MAX_POLYGON_VERTICES);
    for (std::size_t k = 0; k < poly.size(); k++)
      if (poly[k] >= points.size())
        return bs_error_set(err, BS_EINPUT, "%s: polygon %zu refers to point %lld, but there are %zu points", path,
                            i, (long long)(int64_t)poly[k], points.size());
    n_tris += poly.size() - 2;
  }
  if (n_tris > (std::size_t)BS_MAX_SURFACE_FACES)
    return bs_error_set(err, BS_EINPUT, "%s: %zu triangles exceed bigstep's limit of %ld", path, n_tris,
                        (long)BS_MAX_SURFACE_FACES);

  std::vector<int32_t> split(3 * n_tris); // before the C arrays: nothing to free if it throws
  std::size_t k = 0;
  for (const Polygon &poly : polygons) {
    split_polygon(points, poly, split.data() + 3 * k);
    k += poly.size() - 2;
  }
  double *x = (double *)std::malloc(3 * points.size() * sizeof(double));
  int32_t *t = (int32_t *)std::malloc(3 * n_tris * sizeof(int32_t));
  if (!x || !t) {
    std::free(x);
    std::free(t);
    return bs_error_set(err, BS_ENOMEM, "%s: out of memory for %zu points and %zu triangles", path, points.size(),
                        n_tris);
  }
  for (std::size_t i = 0; i < points.size(); i++) {
    x[3 * i + 0] = points[i].x();
    x[3 * i + 1] = points[i].y();
    x[3 * i + 2] = points[i].z();
  }
  std::copy(split.begin(), split.end(), t);
  *points_out = x;
  *n_points_out = (int64_t)points.size();
  *tris_out = t;
  *n_tris_out = (int64_t)n_tris;
  return BS_OK;
}

} // namespace

extern "C" void bs_shim_free(void *p) { std::free(p); }

extern "C" int bs_shim_check_stl(const char *path, bs_error *err) {
  if (!path) return bs_error_set(err, BS_EINPUT, "bs_shim_check_stl: NULL path");
  try {
    std::string bytes;
    int rc = bs_shim::read_bytes(path, bytes, err);
    return rc ? rc : bs_shim::check_stl(path, bytes, err);
  } catch (const std::bad_alloc &) {
    return bs_error_set(err, BS_ENOMEM, "%s: out of memory while reading the surface", path);
  } catch (...) {
    return bs_error_set(err, BS_EINPUT, "%s: could not check the STL file", path);
  }
}

extern "C" int bs_shim_read_surface(const char *path, double **points, int64_t *n_points, int32_t **tris,
                                    int64_t *n_tris, bs_error *err) {
  if (!path || !points || !n_points || !tris || !n_tris)
    return bs_error_set(err, BS_EINPUT, "bs_shim_read_surface: NULL argument");
  *points = NULL;
  *tris = NULL;
  *n_points = 0;
  *n_tris = 0;
  try {
    return read_surface(path, points, n_points, tris, n_tris, err);
  } catch (const std::bad_alloc &) {
    return bs_error_set(err, BS_ENOMEM, "%s: out of memory while reading the surface", path);
  } catch (const std::exception &e) {
    return bs_error_set(err, BS_EINPUT, "%s: CGAL failed to read the surface: %s", path, e.what());
  } catch (...) {
    return bs_error_set(err, BS_EINPUT, "%s: CGAL failed to read the surface (unknown exception)", path);
  }
}
