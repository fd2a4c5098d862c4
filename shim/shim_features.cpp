// shim_features.cpp — is a surface CAD-like (bs_shim::cad_like, see
// shim_features.hpp). The callers catch CGAL's exceptions.

#include <CGAL/Polygon_mesh_processing/detect_features.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "shim_features.hpp"

namespace bs_shim {

namespace {

// The smallest angle (degrees) between two sharp edges leaving the same
// vertex (180 when no vertex has two).
double sharp_corner_angle(const Surface &sm, const Surface::Property_map<Surface::Edge_index, bool> &sharp) {
  double worst = 180;
  for (auto v : sm.vertices()) {
    std::vector<Epick::Vector_3> dirs;
    for (auto g : CGAL::halfedges_around_source(v, sm))
      if (sharp[sm.edge(g)]) dirs.push_back(sm.point(sm.target(g)) - sm.point(v));
    for (std::size_t i = 0; i < dirs.size(); i++)
      for (std::size_t j = i + 1; j < dirs.size(); j++) {
        const double c = dirs[i] * dirs[j] / std::sqrt(dirs[i].squared_length() * dirs[j].squared_length());
        worst = std::min(worst, std::acos(std::max(-1.0, std::min(1.0, c))) * 180.0 / CGAL_PI);
      }
  }
  return worst;
}

} // namespace

bool cad_like(Surface &sm, double angle, double min_length, int64_t *n_long) {
  auto sharp = sm.add_property_map<Surface::Edge_index, bool>("e:bs_sharp_chain", false).first;
  CGAL::Polygon_mesh_processing::detect_sharp_edges(sm, angle, sharp);
  *n_long = 0;
  if (sharp_corner_angle(sm, sharp) < BS_SHIM_FEATURE_MIN_CORNER) {
    sm.remove_property_map(sharp);
    return false;
  }
  std::vector<int> degree(sm.number_of_vertices(), 0);
  for (auto e : sm.edges())
    if (sharp[e]) degree[sm.source(sm.halfedge(e))]++, degree[sm.target(sm.halfedge(e))]++;
  std::vector<char> used(sm.number_of_edges(), 0);
  double long_len = 0, all_len = 0;
  // Walks from halfedge h (a sharp edge leaving its source) until a vertex of degree != 2 or the start.
  auto walk = [&](Surface::Halfedge_index h) {
    double len = 0;
    for (;;) {
      used[sm.edge(h)] = 1;
      len += std::sqrt(CGAL::squared_distance(sm.point(sm.source(h)), sm.point(sm.target(h))));
      const auto v = sm.target(h);
      if (degree[v] != 2) break;
      Surface::Halfedge_index next;
      bool found = false;
      for (auto g : CGAL::halfedges_around_source(v, sm))
        if (sharp[sm.edge(g)] && !used[sm.edge(g)]) next = g, found = true;
      if (!found) break; // a closed loop is back at its start
      h = next;
    }
    all_len += len;
    if (len >= min_length) long_len += len, ++*n_long;
  };
  for (auto v : sm.vertices())
    if (degree[v] != 0 && degree[v] != 2)
      for (auto g : CGAL::halfedges_around_source(v, sm))
        if (sharp[sm.edge(g)] && !used[sm.edge(g)]) walk(g);
  for (auto e : sm.edges())
    if (sharp[e] && !used[e]) walk(sm.halfedge(e));
  sm.remove_property_map(sharp);
  return all_len > 0 && long_len >= 0.8 * all_len;
}

} // namespace bs_shim
