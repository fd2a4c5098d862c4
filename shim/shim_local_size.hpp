// shim_local_size.hpp — a sizing field for Mesh_3 from a closed surface's
// thickness (not public API; C++ only; used by shim_mesh3.cpp).
//
// At sample points of the surface (its vertices and its faces' centroids)
// the thickness t is the distance from the point, inward along the negated
// normal, to the nearest face the ray crosses whose normal is turned more
// than 120 degrees from the sample's (the opposite side of a slab; not a
// neighbouring face, nor the other face of a re-entrant corner), found with
// a CGAL AABB tree; +inf (size h) when there is none. The size
// there is s = clamp(t / across, floor, h): `across` elements through a
// part thinner than across * h. The samples' sizes are then graded: s(q) <=
// s(q') + g |q - q'| over a graph of each sample's nearest neighbours
// (Dijkstra), so that sizes grow at most g per unit length away from thin
// parts. In space the field is
//   size(p) = min(h, min over the k nearest samples q of s(q) + g |p - q|),
// which Mesh_3 evaluates as cell_size, facet_size and edge_size.
//
// Lengths in the surface's units. Copies share the samples (Mesh_3 copies
// its criteria); queries are const and thread-compatible.
#ifndef BS_SHIM_LOCAL_SIZE_HPP
#define BS_SHIM_LOCAL_SIZE_HPP

#include <memory>

#include "shim_surface_mesh.hpp"

namespace bs_shim {

struct Local_size_opts {
  double h;         // the size where the surface is thick (> 0)
  double across;    // elements across a thin part (> 0)
  double gradation; // |grad size| bound (> 0), e.g. 0.5
  double floor;     // the smallest size (> 0, <= h)
};

class Local_size {
public:
  // Thickness and graded sizes of sm (closed, outward: as
  // soup_to_closed_surface makes it). Throws std::bad_alloc.
  Local_size(const Surface &sm, const Local_size_opts &o);
  // The field at p (floor <= size <= h).
  double operator()(const Epick::Point_3 &p) const;
  // Mesh_3's field signature (dimension and index unused).
  template <class Index> double operator()(const Epick::Point_3 &p, int, const Index &) const { return (*this)(p); }
  // The samples' smallest size and the fraction of samples under h.
  double min_sample_size() const;
  double fraction_refined() const;

private:
  struct Data;
  std::shared_ptr<const Data> d_;
};

// A field scaled by a constant (facet_distance proportional to the size).
struct Scaled_size {
  Local_size f;
  double scale;
  template <class Index> double operator()(const Epick::Point_3 &p, int, const Index &) const { return scale * f(p); }
};

} // namespace bs_shim

#endif
