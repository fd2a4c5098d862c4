// shim_local_size.cpp — the thickness sizing field (see shim_local_size.hpp).

#include <CGAL/AABB_face_graph_triangle_primitive.h>
#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/Orthogonal_k_neighbor_search.h>
#include <CGAL/Polygon_mesh_processing/compute_normal.h>
#include <CGAL/Search_traits_3.h>
#include <CGAL/Search_traits_adapter.h>
#include <CGAL/property_map.h>
#include <boost/iterator/counting_iterator.hpp>

#include <algorithm>
#include <cmath>
#include <functional>
#include <queue>
#include <utility>
#include <vector>

#include "shim_local_size.hpp"

namespace bs_shim {

namespace {

typedef Epick::Point_3 Point;
typedef Epick::Vector_3 Vector;
typedef CGAL::AABB_face_graph_triangle_primitive<Surface> Primitive;
typedef CGAL::AABB_tree<CGAL::AABB_traits<Epick, Primitive>> Face_tree;
typedef CGAL::Pointer_property_map<Point>::const_type Point_map;
typedef CGAL::Search_traits_3<Epick> Base_traits;
typedef CGAL::Search_traits_adapter<std::size_t, Point_map, Base_traits> Traits;
typedef CGAL::Distance_adapter<std::size_t, Point_map, CGAL::Euclidean_distance<Base_traits>> Distance;
typedef CGAL::Orthogonal_k_neighbor_search<Traits, Distance> Knn;
typedef Knn::Tree Kd_tree;

// Neighbours searched per query in space and per sample for the grading graph.
const unsigned K_QUERY = 6, K_GRAPH = 10;

// Distance from p inward along -n (n outward, unit) to the first face of the
// tree the ray leaves the solid through (its normal against n by more than
// 120 degrees: the opposite side of a slab, not a neighbouring face or the
// other face of a re-entrant corner); +inf when none.
double thickness_at(const Face_tree &tree, const Surface &sm, const Point &p, const Vector &n) {
  std::vector<std::pair<Face_tree::Intersection_and_primitive_id<Epick::Ray_3>::Type::first_type, Surface::Face_index>>
      hits;
  tree.all_intersections(Epick::Ray_3(p, -n), std::back_inserter(hits));
  double best = HUGE_VAL;
  for (const auto &hit : hits) {
    const Point *q = boost::get<Point>(&hit.first);
    if (!q) continue; // a segment: the ray runs in a face's plane
    const Vector m = CGAL::Polygon_mesh_processing::compute_face_normal(hit.second, sm);
    if (m * n > -0.5) continue;
    best = std::min(best, std::sqrt(CGAL::squared_distance(p, *q)));
  }
  return best;
}

} // namespace

struct Local_size::Data {
  std::vector<Point> pts;
  std::vector<double> size;
  Local_size_opts o;
  Kd_tree tree;
  Data(std::vector<Point> &&p, const Local_size_opts &opts)
      : pts(std::move(p)), o(opts),
        tree(boost::counting_iterator<std::size_t>(0), boost::counting_iterator<std::size_t>(pts.size()),
             Kd_tree::Splitter(), Traits(CGAL::make_property_map(std::as_const(pts)))) {
    tree.build();
  }
};

namespace {

// s(q) <= s(q') + g |q - q'| over the graph of each sample's K_GRAPH nearest
// neighbours (Dijkstra from the smallest sizes).
void grade(const Kd_tree &tree, const std::vector<Point> &pts, double g, std::vector<double> &s) {
  const std::size_t n = pts.size();
  std::vector<std::vector<std::pair<std::size_t, double>>> adj(n);
  Distance dist(CGAL::make_property_map(pts));
  for (std::size_t i = 0; i < n; i++) {
    Knn search(tree, pts[i], K_GRAPH + 1, 0, true, dist);
    for (const auto &nb : search)
      if (nb.first != i) {
        const double d = std::sqrt(nb.second);
        adj[i].emplace_back(nb.first, d);
        adj[nb.first].emplace_back(i, d);
      }
  }
  typedef std::pair<double, std::size_t> Item;
  std::priority_queue<Item, std::vector<Item>, std::greater<Item>> heap;
  for (std::size_t i = 0; i < n; i++) heap.emplace(s[i], i);
  while (!heap.empty()) {
    const Item top = heap.top();
    heap.pop();
    if (top.first > s[top.second]) continue;
    for (const auto &e : adj[top.second]) {
      const double v = top.first + g * e.second;
      if (v < s[e.first]) s[e.first] = v, heap.emplace(v, e.first);
    }
  }
}

} // namespace

Local_size::Local_size(const Surface &sm, const Local_size_opts &o) {
  namespace PMP = CGAL::Polygon_mesh_processing;
  Face_tree faces(CGAL::faces(sm).first, CGAL::faces(sm).second, sm);
  faces.accelerate_distance_queries();
  std::vector<Point> pts;
  std::vector<double> s;
  pts.reserve(sm.number_of_vertices() + sm.number_of_faces());
  s.reserve(pts.capacity());
  auto add = [&](const Point &p, const Vector &n) {
    pts.push_back(p);
    s.push_back(std::min(o.h, std::max(o.floor, thickness_at(faces, sm, p, n) / o.across)));
  };
  for (auto v : sm.vertices()) add(sm.point(v), PMP::compute_vertex_normal(v, sm));
  for (auto f : sm.faces()) {
    const auto h = sm.halfedge(f);
    add(CGAL::centroid(sm.point(sm.source(h)), sm.point(sm.target(h)), sm.point(sm.target(sm.next(h)))),
        PMP::compute_face_normal(f, sm));
  }
  auto d = std::make_shared<Data>(std::move(pts), o);
  grade(d->tree, d->pts, o.gradation, s);
  d->size = std::move(s);
  d_ = d;
}

double Local_size::operator()(const Epick::Point_3 &p) const {
  const Data &d = *d_;
  Distance dist(CGAL::make_property_map(d.pts));
  Knn search(d.tree, p, K_QUERY, 0, true, dist);
  double best = d.o.h;
  for (const auto &nb : search) best = std::min(best, d.size[nb.first] + d.o.gradation * std::sqrt(nb.second));
  return best;
}

double Local_size::min_sample_size() const {
  return d_->size.empty() ? d_->o.h : *std::min_element(d_->size.begin(), d_->size.end());
}

double Local_size::fraction_refined() const {
  if (d_->size.empty()) return 0;
  std::size_t k = 0;
  for (double v : d_->size) k += v < d_->o.h;
  return (double)k / (double)d_->size.size();
}

} // namespace bs_shim
