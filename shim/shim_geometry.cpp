// shim_geometry.cpp — CGAL geometry behind bs_shim.h: exact predicates, an AABB
// tree over surface triangles (closest point, box query), signed distance to a
// closed surface, surface self-intersection.
//
// Kernel: Exact_predicates_inexact_constructions_kernel (Epick). Every sign or
// yes/no answer below is made of Epick predicates evaluated on the input
// doubles themselves (orientation, collinear, coplanar_orientation,
// collinear_are_ordered_along_line, do_intersect of triangles and segments),
// which CGAL filters and falls back to exact arithmetic: no tolerance. No
// decision rests on a constructed (rounded) point.
//
// Every extern "C" entry catches every exception; nothing is printed.

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Intersections_3/Bbox_3_Ray_3.h>
#include <CGAL/Intersections_3/Segment_3_Triangle_3.h>
#include <CGAL/Intersections_3/Triangle_3_Triangle_3.h>
#include <CGAL/box_intersection_d.h>

#include <boost/iterator/counting_iterator.hpp>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <exception>
#include <limits>
#include <new>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "bs_shim.h"

namespace {

typedef CGAL::Exact_predicates_inexact_constructions_kernel K;
typedef K::Point_3 Point;
typedef K::Segment_3 Segment;
typedef K::Triangle_3 Triangle;
typedef K::Ray_3 Ray;

// ---------------------------------------------------------------------------
// Small helpers

inline Point pt(const double *p) { return Point(p[0], p[1], p[2]); }

inline bool finite3(const double *p) { return std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]); }

// Closed segment [u, v] contains p (u == v allowed: then p == u). Exact.
bool on_segment(const Point &p, const Point &u, const Point &v) {
  if (u == v) return p == u;
  return CGAL::collinear(u, v, p) && CGAL::collinear_are_ordered_along_line(u, p, v);
}

// p lies in the closed triangle (a, b, c), given that p lies in the plane of
// a, b, c whenever they are not collinear. A collinear triangle is the union
// of its three sides. Exact.
bool in_closed_triangle_coplanar(const Point &p, const Point &a, const Point &b, const Point &c) {
  if (CGAL::collinear(a, b, c)) return on_segment(p, a, b) || on_segment(p, b, c) || on_segment(p, a, c);
  // coplanar_orientation(a, b, c, p): POSITIVE when p is on c's side of ab
  // within the plane, COLLINEAR on the line ab, NEGATIVE beyond it.
  return CGAL::coplanar_orientation(a, b, c, p) != CGAL::NEGATIVE &&
         CGAL::coplanar_orientation(b, c, a, p) != CGAL::NEGATIVE &&
         CGAL::coplanar_orientation(c, a, b, p) != CGAL::NEGATIVE;
}

// Exact position of p w.r.t. the closed tetrahedron (a, b, c, d).
int point_in_tet(const Point &p, const Point &a, const Point &b, const Point &c, const Point &d) {
  const int o = (int)CGAL::orientation(a, b, c, d);
  if (o != 0) {
    // Barycentric weight k of p has the sign of (orientation with p put in
    // place of vertex k) times o.
    const int s[4] = {(int)CGAL::orientation(p, b, c, d), (int)CGAL::orientation(a, p, c, d),
                      (int)CGAL::orientation(a, b, p, d), (int)CGAL::orientation(a, b, c, p)};
    bool all = true;
    for (int k = 0; k < 4; k++) {
      if (s[k] == -o) return -1;
      if (s[k] != o) all = false;
    }
    return all ? 1 : 0;
  }
  // Flat: no interior. Its convex hull is the union of the four triangles of
  // three of its points (Caratheodory in the plane).
  const Point *v[4] = {&a, &b, &c, &d};
  const int tri[4][3] = {{0, 1, 2}, {0, 1, 3}, {0, 2, 3}, {1, 2, 3}};
  int plane = -1;
  for (int k = 0; k < 4 && plane < 0; k++)
    if (!CGAL::collinear(*v[tri[k][0]], *v[tri[k][1]], *v[tri[k][2]])) plane = k;
  if (plane < 0) { // all four collinear: the hull is a segment (or a point)
    for (int i = 0; i < 4; i++)
      for (int j = i; j < 4; j++)
        if (on_segment(p, *v[i], *v[j])) return 0;
    return -1;
  }
  if (CGAL::orientation(*v[tri[plane][0]], *v[tri[plane][1]], *v[tri[plane][2]], p) != CGAL::COPLANAR) return -1;
  for (int k = 0; k < 4; k++)
    if (in_closed_triangle_coplanar(p, *v[tri[k][0]], *v[tri[k][1]], *v[tri[k][2]])) return 0;
  return -1;
}

// Checks a triangle soup given to the shim; `fn` names the entry point.
int check_soup(const char *fn, const double *x, int64_t n_points, const int32_t *t, int64_t n_tris,
               int64_t min_tris, bs_error *err) {
  if (n_points < 0) return bs_error_set(err, BS_EINPUT, "%s: n_points = %lld is negative", fn, (long long)n_points);
  if (n_tris < 0) return bs_error_set(err, BS_EINPUT, "%s: n_tris = %lld is negative", fn, (long long)n_tris);
  if (n_tris < min_tris)
    return bs_error_set(err, BS_EINPUT, "%s: n_tris = %lld (at least %lld triangle needed)", fn, (long long)n_tris,
                        (long long)min_tris);
  if (n_points > (int64_t)INT32_MAX)
    return bs_error_set(err, BS_EINPUT, "%s: n_points = %lld exceeds the 32-bit index range", fn,
                        (long long)n_points);
  if (n_points > 0 && !x) return bs_error_set(err, BS_EINPUT, "%s: points is NULL", fn);
  if (n_tris > 0 && !t) return bs_error_set(err, BS_EINPUT, "%s: tris is NULL", fn);
  for (int64_t i = 0; i < n_tris; i++)
    for (int k = 0; k < 3; k++) {
      const int32_t v = t[3 * i + k];
      if (v < 0 || (int64_t)v >= n_points)
        return bs_error_set(err, BS_EINPUT,
                            "%s: triangle %lld (%d, %d, %d) refers to point %d, outside [0, %lld)", fn,
                            (long long)i, t[3 * i], t[3 * i + 1], t[3 * i + 2], v, (long long)n_points);
    }
  for (int64_t i = 0; i < n_points; i++)
    if (!finite3(x + 3 * i))
      return bs_error_set(err, BS_ENUMERIC, "%s: point %lld has a non-finite coordinate (%g, %g, %g)", fn,
                          (long long)i, x[3 * i], x[3 * i + 1], x[3 * i + 2]);
  return BS_OK;
}

// ---------------------------------------------------------------------------
// Closest point on one triangle. The candidates are the foot of the
// perpendicular on the plane, kept when its barycentric weights are all > 0,
// and the closest points of the three sides (clamped projections); the
// nearest candidate wins, the foot on ties. Every candidate is a point of the
// triangle, so that thin or degenerate triangles, where the foot is
// ill-conditioned or undefined, still give a point of the triangle whose
// distance is the minimum over its sides. Returns the squared distance; fills
// the point, its barycentric weights (w[k] for vertex k, exactly 0 off the
// feature) and the feature code of bs_shim.h.

inline double dot3(const double *u, const double *v) { return u[0] * v[0] + u[1] * v[1] + u[2] * v[2]; }

inline void cross3(const double *u, const double *v, double *o) {
  o[0] = u[1] * v[2] - u[2] * v[1];
  o[1] = u[2] * v[0] - u[0] * v[2];
  o[2] = u[0] * v[1] - u[1] * v[0];
}

// Closest point of side [u, v] (local vertices iu, iv) to p.
double closest_on_side(const double *p, const double *u, const double *v, int iu, int iv, double out[3],
                       double w[3], int *feature) {
  double uv[3], up[3];
  for (int k = 0; k < 3; k++) {
    uv[k] = v[k] - u[k];
    up[k] = p[k] - u[k];
  }
  const double l2 = dot3(uv, uv), s0 = dot3(up, uv);
  const double s = (l2 > 0.0 && s0 > 0.0) ? (s0 >= l2 ? 1.0 : s0 / l2) : 0.0;
  w[0] = w[1] = w[2] = 0.0;
  if (s == 0.0) {
    w[iu] = 1.0;
    *feature = 4 + iu;
  } else if (s == 1.0) {
    w[iv] = 1.0;
    *feature = 4 + iv;
  } else {
    w[iu] = 1.0 - s;
    w[iv] = s;
    *feature = 1 + iu; // sides are (0,1) -> 1, (1,2) -> 2, (2,0) -> 3
  }
  double d2 = 0.0;
  for (int k = 0; k < 3; k++) {
    out[k] = s == 0.0 ? u[k] : (s == 1.0 ? v[k] : u[k] + s * uv[k]);
    const double e = p[k] - out[k];
    d2 += e * e;
  }
  return d2;
}

double closest_on_triangle(const double *p, const double *a, const double *b, const double *c, double out[3],
                           double w[3], int *feature) {
  const double *v[3] = {a, b, c};
  double best = std::numeric_limits<double>::infinity();
  // The foot: with n = ab x ac, its weights are
  //   w1 = ((ap x ac) . n) / |n|^2,  w2 = ((ab x ap) . n) / |n|^2,  w0 = 1 - w1 - w2.
  double ab[3], ac[3], ap[3], n[3], m[3];
  for (int k = 0; k < 3; k++) {
    ab[k] = b[k] - a[k];
    ac[k] = c[k] - a[k];
    ap[k] = p[k] - a[k];
  }
  cross3(ab, ac, n);
  const double n2 = dot3(n, n);
  if (n2 > 0.0) {
    cross3(ap, ac, m);
    const double w1 = dot3(m, n) / n2;
    cross3(ab, ap, m);
    const double w2 = dot3(m, n) / n2;
    const double w0 = 1.0 - w1 - w2;
    if (w0 > 0.0 && w1 > 0.0 && w2 > 0.0) {
      best = 0.0;
      for (int k = 0; k < 3; k++) {
        out[k] = w0 * a[k] + w1 * b[k] + w2 * c[k];
        const double e = p[k] - out[k];
        best += e * e;
      }
      w[0] = w0, w[1] = w1, w[2] = w2;
      *feature = 0;
    }
  }
  for (int i = 0; i < 3; i++) {
    double o[3], ww[3];
    int f;
    const double d2 = closest_on_side(p, v[i], v[(i + 1) % 3], i, (i + 1) % 3, o, ww, &f);
    if (d2 < best) {
      best = d2;
      std::copy(o, o + 3, out);
      std::copy(ww, ww + 3, w);
      *feature = f;
    }
  }
  return best;
}

// ---------------------------------------------------------------------------
// The AABB tree: a primitive is a triangle index; the points and triangles
// are the tree's shared data (CGAL's AABBPrimitiveWithSharedData), so that a
// new set of positions only needs a rebuild of the hierarchy.

struct Soup {
  const double *x;
  const int32_t *t;
};

class Tri_primitive {
public:
  typedef int32_t Id;
  typedef K::Point_3 Point;
  typedef K::Triangle_3 Datum;
  typedef const Soup *Shared_data;

  Tri_primitive() : m_id(0) {}
  template <class Iterator> Tri_primitive(Iterator it, const Soup *) : m_id((Id)*it) {}

  Id id() const { return m_id; }
  Datum datum(Shared_data s) const {
    const int32_t *v = s->t + 3 * (std::size_t)m_id;
    return Datum(pt(s->x + 3 * (std::size_t)v[0]), pt(s->x + 3 * (std::size_t)v[1]),
                 pt(s->x + 3 * (std::size_t)v[2]));
  }
  Point reference_point(Shared_data s) const { return pt(s->x + 3 * (std::size_t)s->t[3 * (std::size_t)m_id]); }
  static Shared_data construct_shared_data(const Soup *s) { return s; }

private:
  Id m_id;
};

typedef CGAL::AABB_traits<K, Tri_primitive> Traits;
typedef CGAL::AABB_tree<Traits> Tree;
typedef CGAL::AABB_node<Traits> Node;

// Squared distance from p to a box (0 inside).
inline double box_dist2(const double *p, const CGAL::Bbox_3 &b) {
  double d2 = 0.0;
  for (int k = 0; k < 3; k++) {
    const double e = p[k] < b.min(k) ? b.min(k) - p[k] : (p[k] > b.max(k) ? p[k] - b.max(k) : 0.0);
    d2 += e * e;
  }
  return d2;
}

inline const double *vtx(const Soup &s, int32_t tri, int k) {
  return s.x + 3 * (std::size_t)s.t[3 * (std::size_t)tri + k];
}

// Closest-point traversal: children are visited nearer box first (priority
// = minus the squared box distance) and a box farther than the best
// distance so far is pruned.
struct Closest_traits {
  typedef double Priority;
  const Soup *s;
  const double *q;
  double best_d2;
  int32_t best_tri;
  double point[3], w[3];
  int feature;

  Closest_traits(const Soup *soup, const double *query)
      : s(soup), q(query), best_d2(std::numeric_limits<double>::infinity()), best_tri(-1), feature(0) {
    point[0] = point[1] = point[2] = 0.0;
    w[0] = 1.0, w[1] = w[2] = 0.0;
  }
  void visit(int32_t tri) {
    double o[3], ww[3];
    int f;
    const double d2 = closest_on_triangle(q, vtx(*s, tri, 0), vtx(*s, tri, 1), vtx(*s, tri, 2), o, ww, &f);
    if (d2 < best_d2 || best_tri < 0) {
      best_d2 = d2, best_tri = tri, feature = f;
      std::copy(o, o + 3, point);
      std::copy(ww, ww + 3, w);
    }
  }
  bool go_further() const { return true; }
  template <class Query> void intersection(const Query &, const Tri_primitive &p) { visit(p.id()); }
  template <class Query> bool do_intersect(const Query &, const Node &node) const {
    return box_dist2(q, node.bbox()) < best_d2;
  }
  template <class Query> std::pair<bool, double> do_intersect_with_priority(const Query &, const Node &node) const {
    const double d2 = box_dist2(q, node.bbox());
    return std::make_pair(d2 < best_d2, -d2);
  }
};

// Box query: triangles whose bounding boxes meet a closed box.
struct Within_traits {
  const Soup *s;
  CGAL::Bbox_3 box;
  int32_t *out;
  int64_t cap, count;

  bool go_further() const { return true; }
  template <class Query> void intersection(const Query &, const Tri_primitive &p) {
    const int32_t tri = p.id();
    const double *a = vtx(*s, tri, 0), *b = vtx(*s, tri, 1), *c = vtx(*s, tri, 2);
    for (int k = 0; k < 3; k++) {
      const double lo = std::min(a[k], std::min(b[k], c[k])), hi = std::max(a[k], std::max(b[k], c[k]));
      if (hi < box.min(k) || lo > box.max(k)) return;
    }
    if (count < cap) out[count] = tri;
    count++;
  }
  template <class Query> bool do_intersect(const Query &, const Node &node) const {
    return CGAL::do_overlap(box, node.bbox());
  }
};

// ---------------------------------------------------------------------------
// Ray parity (inside/outside), from exact predicates on the input points: the
// ray is {p + s (r - p), s >= 0} for the double points p (the query) and r.

// u lies on the ray (p, r). Exact.
bool on_ray(const Point &p, const Point &r, const Point &u) {
  return CGAL::collinear(p, r, u) && !CGAL::collinear_are_strictly_ordered_along_line(u, p, r);
}

// The ray (p, r) meets the closed segment [u, v], u != v. Exact.
bool ray_meets_segment(const Point &p, const Point &r, const Point &u, const Point &v) {
  if (CGAL::orientation(p, r, u, v) != CGAL::COPLANAR) return false;
  const bool cu = CGAL::collinear(p, r, u), cv = CGAL::collinear(p, r, v);
  if (cu || cv) return (cu && on_ray(p, r, u)) || (cv && on_ray(p, r, v));
  // u and v off the line pr: the segment crosses the line iff they are on
  // opposite sides; then the crossing is on the ray iff r is on v's side of
  // the line pu (the ray points into the angle u p v).
  if (CGAL::coplanar_orientation(p, r, u, v) != CGAL::NEGATIVE) return false;
  if (CGAL::collinear(p, u, v)) return true; // p itself is the crossing point
  return CGAL::coplanar_orientation(p, u, v, r) == CGAL::POSITIVE;
}

enum Ray_state { RAY_OK = 0, RAY_ON_SURFACE = 1, RAY_INCONCLUSIVE = 2 };

struct Parity_traits {
  const Soup *s;
  Point p, r;
  int64_t crossings;
  int state;

  bool go_further() const { return state == RAY_OK; }
  template <class Query> bool do_intersect(const Query &ray, const Node &node) const {
    return CGAL::do_intersect(ray, node.bbox());
  }
  template <class Query> void intersection(const Query &, const Tri_primitive &prim) {
    const int32_t tri = prim.id();
    const Point a = pt(vtx(*s, tri, 0)), b = pt(vtx(*s, tri, 1)), c = pt(vtx(*s, tri, 2));
    if (CGAL::collinear(a, b, c)) {
      // A degenerate triangle is the segment between its extreme points; a
      // ray that meets it passes through an edge or vertex of the surface.
      Point u = a, v = b;
      if (CGAL::collinear_are_ordered_along_line(a, c, b)) u = a, v = b;
      else if (CGAL::collinear_are_ordered_along_line(b, a, c)) u = b, v = c;
      else u = a, v = c;
      if (u == v) {
        if (p == u) state = RAY_ON_SURFACE;
        else if (on_ray(p, r, u)) state = RAY_INCONCLUSIVE;
      } else if (on_segment(p, u, v)) {
        state = RAY_ON_SURFACE;
      } else if (ray_meets_segment(p, r, u, v)) {
        state = RAY_INCONCLUSIVE;
      }
      return;
    }
    const CGAL::Orientation op = CGAL::orientation(a, b, c, p);
    if (op == CGAL::COPLANAR) {
      if (in_closed_triangle_coplanar(p, a, b, c)) state = RAY_ON_SURFACE;
      else if (CGAL::orientation(a, b, c, r) == CGAL::COPLANAR) state = RAY_INCONCLUSIVE; // ray in the plane
      return;
    }
    // The line pr passes through the closed triangle iff the three signs
    // orientation(p, r, edge) do not disagree; their common sign is the sign
    // of n . (r - p) with n = (b - a) x (c - a).
    const int e0 = (int)CGAL::orientation(p, r, a, b), e1 = (int)CGAL::orientation(p, r, b, c),
              e2 = (int)CGAL::orientation(p, r, c, a);
    const int sgn = e0 != 0 ? e0 : (e1 != 0 ? e1 : e2);
    if ((e0 != 0 && e0 != sgn) || (e1 != 0 && e1 != sgn) || (e2 != 0 && e2 != sgn)) return; // line misses
    // sgn != 0 here: all three zero would put the line in the plane, p too.
    if ((int)op != -sgn) return; // the ray leaves the plane behind it
    if (e0 == 0 || e1 == 0 || e2 == 0) state = RAY_INCONCLUSIVE; // through an edge or a vertex
    else crossings++;
  }
};

} // namespace

struct bs_shim_tree {
  std::vector<double> x;
  std::vector<int32_t> t;
  Soup soup;
  Tree tree;
};

namespace {

// Closest point to q (finite) with an optional hint triangle.
void tree_closest(const bs_shim_tree *t, const double *q, int32_t hint, double out_point[3], int32_t *out_tri,
                  double bary[3], int *feature, double *dist2) {
  Closest_traits tr(&t->soup, q);
  if (hint >= 0) tr.visit(hint);
  t->tree.traversal_with_priority(pt(q), tr);
  if (out_point) std::copy(tr.point, tr.point + 3, out_point);
  if (out_tri) *out_tri = tr.best_tri;
  if (bary) std::copy(tr.w, tr.w + 3, bary);
  if (feature) *feature = tr.feature;
  if (dist2) *dist2 = tr.best_d2;
}

// Inside (-1), on the surface (0) or outside (+1) by ray parity; BS_ENUMERIC
// when no conclusive ray was found.
int side_of_surface(const bs_shim_tree *t, const double *q, int *side) {
  const Point p = pt(q);
  const CGAL::Bbox_3 box = t->tree.bbox();
  // First ray: along the axis towards the nearest face of the tree's box
  // (cheap: few boxes on the way out). Then pseudo-random directions from a
  // fixed-seed generator, so that results are reproducible.
  int axis = 0, dir = -1;
  double best = std::numeric_limits<double>::infinity();
  for (int k = 0; k < 3; k++) {
    if (q[k] - box.min(k) < best) best = q[k] - box.min(k), axis = k, dir = -1;
    if (box.max(k) - q[k] < best) best = box.max(k) - q[k], axis = k, dir = +1;
  }
  uint64_t state = 0x9E3779B97F4A7C15ull;
  auto uniform = [&state]() { // xorshift64*, in [0, 1)
    state ^= state >> 12, state ^= state << 25, state ^= state >> 27;
    return (double)((state * 0x2545F4914F6CDD1Dull) >> 11) * (1.0 / 9007199254740992.0);
  };
  const int max_rays = 64;
  for (int attempt = 0; attempt < max_rays; attempt++) {
    double d[3] = {0.0, 0.0, 0.0};
    if (attempt == 0) {
      d[axis] = dir;
    } else { // uniform on the unit sphere
      const double z = 2.0 * uniform() - 1.0, phi = 6.283185307179586 * uniform();
      const double rho = std::sqrt(std::max(0.0, 1.0 - z * z));
      d[0] = rho * std::cos(phi), d[1] = rho * std::sin(phi), d[2] = z;
    }
    // r = p + scale d, a double point distinct from p (the ray is exactly
    // the half-line from p through r, whatever the rounding of r).
    double scale = std::max(1.0, std::max(std::fabs(q[0]), std::max(std::fabs(q[1]), std::fabs(q[2]))));
    Point r = Point(q[0] + scale * d[0], q[1] + scale * d[1], q[2] + scale * d[2]);
    if (r == p) continue;
    Parity_traits tr;
    tr.s = &t->soup, tr.p = p, tr.r = r, tr.crossings = 0, tr.state = RAY_OK;
    t->tree.traversal(Ray(p, r), tr);
    if (tr.state == RAY_ON_SURFACE) {
      *side = 0;
      return BS_OK;
    }
    if (tr.state == RAY_OK) {
      *side = (tr.crossings % 2 == 1) ? -1 : 1;
      return BS_OK;
    }
  }
  return BS_ENUMERIC;
}

// Exact test of two non-degenerate triangles i, j (vertex indices ti, tj)
// with the adjacency rule of bs_shim.h.
bool triangles_intersect(const Soup &s, int32_t i, int32_t j) {
  const int32_t *ti = s.t + 3 * (std::size_t)i, *tj = s.t + 3 * (std::size_t)j;
  int shared = 0, si[3], sj[3];
  for (int a = 0; a < 3; a++)
    for (int b = 0; b < 3; b++)
      if (ti[a] == tj[b]) si[shared] = a, sj[shared] = b, shared++;
  const Point A[3] = {pt(vtx(s, i, 0)), pt(vtx(s, i, 1)), pt(vtx(s, i, 2))};
  const Point B[3] = {pt(vtx(s, j, 0)), pt(vtx(s, j, 1)), pt(vtx(s, j, 2))};
  if (shared == 0) return CGAL::do_intersect(Triangle(A[0], A[1], A[2]), Triangle(B[0], B[1], B[2]));
  if (shared == 1) { // the opposite edge of one meets the other triangle
    const int a = si[0], b = sj[0];
    const Segment ei(A[(a + 1) % 3], A[(a + 2) % 3]), ej(B[(b + 1) % 3], B[(b + 2) % 3]);
    return CGAL::do_intersect(Triangle(A[0], A[1], A[2]), ej) || CGAL::do_intersect(Triangle(B[0], B[1], B[2]), ei);
  }
  if (shared == 2) { // a fold: coplanar, third vertices on the same side of the edge
    const Point &u = A[si[0]], &v = A[si[1]];
    const Point &c = A[3 - si[0] - si[1]], &d = B[3 - sj[0] - sj[1]];
    return CGAL::coplanar(u, v, c, d) && CGAL::coplanar_orientation(u, v, c, d) == CGAL::POSITIVE;
  }
  return true; // the same three vertices
}

typedef CGAL::Box_intersection_d::Box_with_info_d<double, 3, int32_t, CGAL::Box_intersection_d::ID_FROM_BOX_ADDRESS>
    Box;

struct CapReached {}; // thrown by the callback to stop the search at the cap

// The box search runs in slabs along the axis of the boxes' longest extent,
// cut at quantiles of their centres, one slab per task: a box goes to every
// slab it meets (closed), and a pair of boxes found in several slabs is kept
// in the one holding the lower end of their overlap along the axis, which
// both boxes meet: each pair is tested once. The slab count depends on the
// number of boxes only (not on the threads); the pairs are sorted at the end,
// so the result does not depend on the thread count either.
enum { SLAB_BOXES = 16384, MAX_SLABS = 64 };

struct Slabs {
  int axis = 0;
  std::vector<double> cut; // slab k is [cut[k], cut[k+1]); cut[0] = -inf, back = +inf
  int of(double v) const { // the slab holding v
    return (int)(std::upper_bound(cut.begin() + 1, cut.end() - 1, v) - (cut.begin() + 1));
  }
};

Slabs make_slabs(const std::vector<Box> &boxes) {
  Slabs sl;
  const std::size_t n = boxes.size();
  const int ns = (int)std::max<std::size_t>(1, std::min<std::size_t>(MAX_SLABS, n / SLAB_BOXES));
  double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
  for (const Box &b : boxes)
    for (int k = 0; k < 3; k++) lo[k] = std::min(lo[k], b.min_coord(k)), hi[k] = std::max(hi[k], b.max_coord(k));
  for (int k = 1; k < 3; k++)
    if (hi[k] - lo[k] > hi[sl.axis] - lo[sl.axis]) sl.axis = k;
  std::vector<double> c(n);
  for (std::size_t i = 0; i < n; i++) c[i] = 0.5 * (boxes[i].min_coord(sl.axis) + boxes[i].max_coord(sl.axis));
  std::sort(c.begin(), c.end());
  sl.cut.push_back(-INFINITY);
  for (int k = 1; k < ns; k++) sl.cut.push_back(c[(std::size_t)k * n / (std::size_t)ns]);
  sl.cut.push_back(INFINITY);
  return sl;
}

// The candidate boxes of each slab.
std::vector<std::vector<const Box *>> slab_members(const std::vector<Box> &boxes, const Slabs &sl) {
  std::vector<std::vector<const Box *>> in(sl.cut.size() - 1);
  for (const Box &b : boxes)
    for (int k = sl.of(b.min_coord(sl.axis)), e = sl.of(b.max_coord(sl.axis)); k <= e; k++) in[k].push_back(&b);
  return in;
}

// The intersecting pairs whose boxes' overlap starts in slab k, into out;
// found counts the pairs of all slabs (with the degenerate ones) for the cap.
void slab_pairs(const Soup &s, const Slabs &sl, int k, std::vector<const Box *> &in, int64_t cap,
                std::atomic<int64_t> &found, std::vector<std::pair<int32_t, int32_t>> &out) {
  const int a = sl.axis;
  auto callback = [&](const Box *b1, const Box *b2) {
    if (sl.of(std::max(b1->min_coord(a), b2->min_coord(a))) != k) return; // another slab's pair
    const int32_t i = b1->info(), j = b2->info();
    if (triangles_intersect(s, i, j)) {
      out.emplace_back(std::min(i, j), std::max(i, j));
      if (cap > 0) found++;
    }
    if (cap > 0 && found.load(std::memory_order_relaxed) >= cap) throw CapReached(); // this slab's or another's
  };
  CGAL::box_self_intersection_d(in.begin(), in.end(), callback); // closed boxes: touching triangles are candidates
}

// cap > 0: stop once cap pairs are found (*truncated = 1, the first cap pairs
// in order kept); cap = 0: all pairs. Slabs on OpenMP threads (above).
int self_intersections(const double *x, int64_t n_points, const int32_t *t, int64_t n_tris, int64_t cap,
                       int32_t **pairs_out, int64_t *n_pairs_out, int *truncated, bs_error *err) {
  if (truncated) *truncated = 0;
  *pairs_out = NULL;
  *n_pairs_out = 0;
  int rc = check_soup("bs_shim_self_intersections", x, n_points, t, n_tris, 0, err);
  if (rc) return rc;
  const Soup s = {x, t};
  std::vector<std::pair<int32_t, int32_t>> pairs;
  std::vector<Box> boxes;
  boxes.reserve((std::size_t)n_tris);
  for (int64_t i = 0; i < n_tris; i++) {
    const double *a = vtx(s, (int32_t)i, 0), *b = vtx(s, (int32_t)i, 1), *c = vtx(s, (int32_t)i, 2);
    if (CGAL::collinear(pt(a), pt(b), pt(c))) { // degenerate: reported as (i, i)
      pairs.emplace_back((int32_t)i, (int32_t)i);
      continue;
    }
    double lo[3], hi[3];
    for (int k = 0; k < 3; k++) {
      lo[k] = std::min(a[k], std::min(b[k], c[k]));
      hi[k] = std::max(a[k], std::max(b[k], c[k]));
    }
    boxes.push_back(Box(CGAL::Bbox_3(lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]), (int32_t)i));
  }
  std::atomic<int64_t> found((int64_t)pairs.size());
  int stopped = cap > 0 && found >= cap, failed = 0; // failed: 1 out of memory, 2 another exception
  if (!stopped && !boxes.empty()) {
    const Slabs sl = make_slabs(boxes);
    std::vector<std::vector<const Box *>> in = slab_members(boxes, sl);
    std::vector<std::vector<std::pair<int32_t, int32_t>>> got(in.size());
    const int ns = (int)in.size();
    std::string what; // the first exception's message
#pragma omp parallel for schedule(dynamic, 1) reduction(| : stopped, failed) if (ns > 1)
    for (int k = 0; k < ns; k++) {
      try {
        slab_pairs(s, sl, k, in[k], cap, found, got[k]);
      } catch (const CapReached &) {
        stopped = 1;
      } catch (const std::bad_alloc &) {
        failed |= 1;
      } catch (const std::exception &e) {
        failed |= 2;
#pragma omp critical(bs_shim_slab_error)
        if (what.empty()) what = e.what();
      } catch (...) {
        failed |= 2;
      }
    }
    if (failed & 1) throw std::bad_alloc();
    if (failed) throw std::runtime_error(what.empty() ? "unknown exception in the box search" : what);
    for (const auto &g : got) pairs.insert(pairs.end(), g.begin(), g.end());
  }
  std::sort(pairs.begin(), pairs.end());
  if (stopped && cap > 0 && (int64_t)pairs.size() > cap) pairs.resize((std::size_t)cap);
  if (truncated) *truncated = stopped;
  if (!pairs.empty()) {
    int32_t *out = (int32_t *)std::malloc(2 * pairs.size() * sizeof(int32_t));
    if (!out)
      return bs_error_set(err, BS_ENOMEM, "bs_shim_self_intersections: out of memory for %zu pairs", pairs.size());
    for (std::size_t k = 0; k < pairs.size(); k++) out[2 * k] = pairs[k].first, out[2 * k + 1] = pairs[k].second;
    *pairs_out = out;
    *n_pairs_out = (int64_t)pairs.size();
  }
  return BS_OK;
}

inline bool any_null(const void *a, const void *b, const void *c, const void *d) { return !a || !b || !c || !d; }

} // namespace

// ---------------------------------------------------------------------------
// The C API

extern "C" int bs_shim_orient3d(const double a[3], const double b[3], const double c[3], const double d[3]) {
  if (any_null(a, b, c, d) || !finite3(a) || !finite3(b) || !finite3(c) || !finite3(d)) return BS_EINPUT;
  try {
    return (int)CGAL::orientation(pt(a), pt(b), pt(c), pt(d));
  } catch (...) {
    return BS_EINTERNAL;
  }
}

extern "C" int bs_shim_point_in_tet(const double p[3], const double a[3], const double b[3], const double c[3],
                                    const double d[3]) {
  if (!p || any_null(a, b, c, d) || !finite3(p) || !finite3(a) || !finite3(b) || !finite3(c) || !finite3(d))
    return BS_EINPUT;
  try {
    return point_in_tet(pt(p), pt(a), pt(b), pt(c), pt(d));
  } catch (...) {
    return BS_EINTERNAL;
  }
}

extern "C" int bs_shim_tree_create(const double *points, int64_t n_points, const int32_t *tris, int64_t n_tris,
                                   bs_shim_tree **out, bs_error *err) {
  if (!out) return bs_error_set(err, BS_EINPUT, "bs_shim_tree_create: out is NULL");
  *out = NULL;
  bs_shim_tree *t = NULL;
  try {
    int rc = check_soup("bs_shim_tree_create", points, n_points, tris, n_tris, 1, err);
    if (rc) return rc;
    t = new bs_shim_tree();
    t->x.assign(points, points + 3 * n_points);
    t->t.assign(tris, tris + 3 * n_tris);
    t->soup.x = t->x.data();
    t->soup.t = t->t.data();
    t->tree.do_not_accelerate_distance_queries(); // our closest-point search needs no k-d tree
    t->tree.insert(boost::counting_iterator<int32_t>(0), boost::counting_iterator<int32_t>((int32_t)n_tris),
                   (const Soup *)&t->soup);
    t->tree.build();
    *out = t;
    return BS_OK;
  } catch (const std::bad_alloc &) {
    delete t;
    return bs_error_set(err, BS_ENOMEM, "bs_shim_tree_create: out of memory for %lld triangles",
                        (long long)n_tris);
  } catch (const std::exception &e) {
    delete t;
    return bs_error_set(err, BS_EINTERNAL, "bs_shim_tree_create: CGAL failed: %s", e.what());
  } catch (...) {
    delete t;
    return bs_error_set(err, BS_EINTERNAL, "bs_shim_tree_create: CGAL failed (unknown exception)");
  }
}

extern "C" void bs_shim_tree_destroy(bs_shim_tree **t) {
  if (!t) return;
  try {
    delete *t;
  } catch (...) {
  }
  *t = NULL;
}

extern "C" int bs_shim_tree_update(bs_shim_tree *t, const double *points, bs_error *err) {
  if (!t || !points) return bs_error_set(err, BS_EINPUT, "bs_shim_tree_update: %s is NULL", t ? "points" : "tree");
  const std::size_t n = t->x.size() / 3;
  for (std::size_t i = 0; i < n; i++)
    if (!finite3(points + 3 * i))
      return bs_error_set(err, BS_ENUMERIC, "bs_shim_tree_update: point %zu has a non-finite coordinate (%g, %g, %g)",
                          i, points[3 * i], points[3 * i + 1], points[3 * i + 2]);
  try {
    std::copy(points, points + 3 * n, t->x.begin());
    t->tree.build(); // reuses the node storage; primitives read the new points
    return BS_OK;
  } catch (const std::exception &e) {
    return bs_error_set(err, BS_EINTERNAL, "bs_shim_tree_update: CGAL failed: %s", e.what());
  } catch (...) {
    return bs_error_set(err, BS_EINTERNAL, "bs_shim_tree_update: CGAL failed (unknown exception)");
  }
}

extern "C" int bs_shim_tree_closest_hint(const bs_shim_tree *t, const double q[3], int32_t hint, double out_point[3],
                                         int32_t *out_tri, double bary[3], int *feature) {
  if (!t || !q || !finite3(q)) return BS_EINPUT;
  if (hint >= 0 && (std::size_t)hint >= t->t.size() / 3) return BS_EINPUT;
  try {
    tree_closest(t, q, hint, out_point, out_tri, bary, feature, NULL);
    return BS_OK;
  } catch (...) {
    return BS_EINTERNAL;
  }
}

extern "C" int bs_shim_tree_closest(const bs_shim_tree *t, const double q[3], double out_point[3], int32_t *out_tri,
                                    double bary[3], int *feature) {
  return bs_shim_tree_closest_hint(t, q, -1, out_point, out_tri, bary, feature);
}

extern "C" int bs_shim_tree_within(const bs_shim_tree *t, const double lo[3], const double hi[3], int32_t *out,
                                   int64_t cap, int64_t *count) {
  if (!t || !lo || !hi || !count || cap < 0 || (cap > 0 && !out)) return BS_EINPUT;
  for (int k = 0; k < 3; k++)
    if (std::isnan(lo[k]) || std::isnan(hi[k])) return BS_EINPUT;
  *count = 0;
  for (int k = 0; k < 3; k++)
    if (lo[k] > hi[k]) return BS_OK; // empty box
  try {
    Within_traits tr;
    tr.s = &t->soup;
    tr.box = CGAL::Bbox_3(lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]);
    tr.out = out, tr.cap = cap, tr.count = 0;
    t->tree.traversal(tr.box, tr);
    *count = tr.count;
    return BS_OK;
  } catch (...) {
    return BS_EINTERNAL;
  }
}

extern "C" int bs_shim_signed_distance(const bs_shim_tree *t, const double *q, int64_t n, double *out, bs_error *err) {
  if (!t) return bs_error_set(err, BS_EINPUT, "bs_shim_signed_distance: tree is NULL");
  if (n < 0) return bs_error_set(err, BS_EINPUT, "bs_shim_signed_distance: n = %lld is negative", (long long)n);
  if (n > 0 && (!q || !out))
    return bs_error_set(err, BS_EINPUT, "bs_shim_signed_distance: %s is NULL", q ? "out" : "q");
  try {
    for (int64_t i = 0; i < n; i++) {
      const double *p = q + 3 * i;
      if (!finite3(p))
        return bs_error_set(err, BS_EINPUT, "bs_shim_signed_distance: point %lld has a non-finite coordinate (%g, %g, %g)",
                            (long long)i, p[0], p[1], p[2]);
      double d2;
      tree_closest(t, p, -1, NULL, NULL, NULL, NULL, &d2);
      int side;
      if (side_of_surface(t, p, &side))
        return bs_error_set(err, BS_ENUMERIC,
                            "bs_shim_signed_distance: point %lld (%g, %g, %g): no ray gave a conclusive inside/outside "
                            "answer",
                            (long long)i, p[0], p[1], p[2]);
      out[i] = side == 0 ? 0.0 : side * std::sqrt(d2);
    }
    return BS_OK;
  } catch (const std::exception &e) {
    return bs_error_set(err, BS_EINTERNAL, "bs_shim_signed_distance: CGAL failed: %s", e.what());
  } catch (...) {
    return bs_error_set(err, BS_EINTERNAL, "bs_shim_signed_distance: CGAL failed (unknown exception)");
  }
}

extern "C" int bs_shim_self_intersections(const double *points, int64_t n_points, const int32_t *tris, int64_t n_tris,
                                          int32_t **pairs, int64_t *n_pairs, bs_error *err) {
  if (!pairs || !n_pairs)
    return bs_error_set(err, BS_EINPUT, "bs_shim_self_intersections: %s is NULL", pairs ? "n_pairs" : "pairs");
  *pairs = NULL;
  *n_pairs = 0;
  try {
    return self_intersections(points, n_points, tris, n_tris, 0, pairs, n_pairs, NULL, err);
  } catch (const std::bad_alloc &) {
    return bs_error_set(err, BS_ENOMEM, "bs_shim_self_intersections: out of memory (%lld triangles)",
                        (long long)n_tris);
  } catch (const std::exception &e) {
    return bs_error_set(err, BS_EINTERNAL, "bs_shim_self_intersections: CGAL failed: %s", e.what());
  } catch (...) {
    return bs_error_set(err, BS_EINTERNAL, "bs_shim_self_intersections: CGAL failed (unknown exception)");
  }
}

extern "C" int bs_shim_count_self_intersections(const double *points, int64_t n_points, const int32_t *tris,
                                                int64_t n_tris, int64_t cap, int64_t *count, int *truncated,
                                                bs_error *err) {
  if (!count || !truncated)
    return bs_error_set(err, BS_EINPUT, "bs_shim_count_self_intersections: %s is NULL", count ? "truncated" : "count");
  *count = 0;
  *truncated = 0;
  if (cap < 0)
    return bs_error_set(err, BS_EINPUT, "bs_shim_count_self_intersections: cap = %lld is negative", (long long)cap);
  try {
    int32_t *pairs = NULL;
    int rc = self_intersections(points, n_points, tris, n_tris, cap, &pairs, count, truncated, err);
    std::free(pairs);
    return rc;
  } catch (const std::bad_alloc &) {
    return bs_error_set(err, BS_ENOMEM, "bs_shim_count_self_intersections: out of memory (%lld triangles)",
                        (long long)n_tris);
  } catch (const std::exception &e) {
    return bs_error_set(err, BS_EINTERNAL, "bs_shim_count_self_intersections: CGAL failed: %s", e.what());
  } catch (...) {
    return bs_error_set(err, BS_EINTERNAL, "bs_shim_count_self_intersections: CGAL failed (unknown exception)");
  }
}
