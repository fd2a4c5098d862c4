// shim_mesh3.cpp — a closed triangle surface meshed into tetrahedra by CGAL's
// Mesh_3 (bs_shim_mesh_surface, see bs_shim.h).
//
// The soup becomes a CGAL::Surface_mesh (oriented, closed, free of
// self-intersections: checked), the domain a
// Polyhedral_mesh_domain_with_features_3 whose sharp edges (detect_features)
// are protected, so that a CAD part keeps its creases. make_mesh_3 refines
// to the criteria of one target size h; then ODT or Lloyd smoothing and
// rounds of sliver perturbation and exudation while the smallest dihedral
// angle is below the target and improves.
//
// Sequential (CGAL::Sequential_tag) and seeded (CGAL::Random(0)): the same
// input and options give the same mesh. Every extern "C" entry catches
// every exception; nothing is printed.

// GCC 12 -O3 reports boost::detail::edge_desc_impl (the Boost graph in
// Mesh_3's feature polylines) as maybe uninitialized inside std::allocator:
// a false positive in the system headers, silenced for this file only.
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Mesh_complex_3_in_triangulation_3.h>
#include <CGAL/Mesh_criteria_3.h>
#include <CGAL/Mesh_triangulation_3.h>
#include <CGAL/Polyhedral_mesh_domain_with_features_3.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/exude_mesh_3.h>
#include <CGAL/lloyd_optimize_mesh_3.h>
#include <CGAL/make_mesh_3.h>
#include <CGAL/odt_optimize_mesh_3.h>
#include <CGAL/perturb_mesh_3.h>
#include <CGAL/Mesh_3/min_dihedral_angle.h>
#include <CGAL/Polygon_mesh_processing/detect_features.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <mutex>
#include <new>
#include <thread>
#include <unordered_map>
#include <unordered_set>
#include <vector>

#include "bs_child.h"
#include "bs_shim.h"
#include "shim_local_size.hpp"
#include "shim_features.hpp"
#include "shim_surface_mesh.hpp"

namespace {

typedef bs_shim::Epick K;
typedef bs_shim::Surface Surface;
typedef CGAL::Polyhedral_mesh_domain_with_features_3<K, Surface> Domain;
typedef CGAL::Mesh_triangulation_3<Domain, CGAL::Default, CGAL::Sequential_tag>::type Tr;
typedef CGAL::Mesh_complex_3_in_triangulation_3<Tr, Domain::Corner_index, Domain::Curve_index> C3t3;
typedef CGAL::Mesh_criteria_3<Tr> Criteria;

// Smallest dihedral angle (degrees) of the complex's cells; 90 when empty.
double min_dihedral(const C3t3 &c3t3) { return CGAL::to_double(CGAL::Mesh_3::minimum_dihedral_angle_in_c3t3(c3t3)); }

// The optimisers after refinement: smoothing once, then rounds of sliver
// perturbation, then rounds of exudation (CGAL's order; exuding first was
// measured worse on the fandisk, 7.9 against 10.1 degrees), each while the
// smallest angle is below the target and improves.
// The budget ran out `stage` ("during Mesh_3's refinement", ...); the
// refinement's vertices when it was stopped there.
struct budget_exceeded {
  const char *stage;
  std::size_t vertices;
};

// The time left before o.deadline as an optimiser's time_limit (0: no
// limit); throws budget_exceeded (at `stage`) once it has passed.
double time_left(const bs_shim_mesh3_opts &o, const char *stage = "during Mesh_3's optimisers") {
  if (!(o.deadline > 0)) return 0;
  const double left = o.deadline - bs_seconds();
  if (left <= 0) throw budget_exceeded{stage, 0};
  return left;
}

// Mesh_3's refinement stops when the atomic flag it is given
// (mesh_3_options(pointer_to_stop_atomic_boolean), checked before each
// point it inserts: Refine_facets_3 / Refine_cells_3, and in the
// protection of sharp edges) is set. The watchdog is a thread that sets it
// at the deadline (a bs_seconds() time, CLOCK_MONOTONIC as steady_clock on
// Linux) unless it is let go first; the refinement returns a partial
// complex, which refine() then refuses by the budget. With no deadline
// there is no thread.
class Watchdog {
public:
  explicit Watchdog(double deadline) {
    if (!(deadline > 0)) return;
    const auto wait = std::chrono::duration<double>(std::max(0.0, deadline - bs_seconds()));
    thread_ = std::thread([this, wait] {
      std::unique_lock<std::mutex> lock(mutex_);
      if (!cv_.wait_for(lock, wait, [this] { return done_; })) stop_.store(true, std::memory_order_release);
    });
  }
  ~Watchdog() {
    if (!thread_.joinable()) return;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      done_ = true;
    }
    cv_.notify_one();
    thread_.join();
  }
  Watchdog(const Watchdog &) = delete;
  Watchdog &operator=(const Watchdog &) = delete;
  std::atomic<bool> *flag() { return &stop_; }
  bool fired() const { return stop_.load(std::memory_order_acquire); }

private:
  std::atomic<bool> stop_{false};
  std::mutex mutex_;
  std::condition_variable cv_;
  bool done_ = false;
  std::thread thread_;
};

void optimise(C3t3 &c3t3, const Domain &domain, const bs_shim_mesh3_opts &o, double *achieved) {
  namespace P = CGAL::parameters;
  const int iters = o.smooth_iterations > 0 ? o.smooth_iterations : 0;
  if (o.smoother == BS_SHIM_SMOOTH_ODT && iters > 0)
    CGAL::odt_optimize_mesh_3(c3t3, domain, P::max_iteration_number = iters, P::time_limit = time_left(o));
  else if (o.smoother == BS_SHIM_SMOOTH_LLOYD && iters > 0)
    CGAL::lloyd_optimize_mesh_3(c3t3, domain, P::max_iteration_number = iters, P::time_limit = time_left(o));
  const double target = o.target_dihedral > 0 ? o.target_dihedral : 0.0;
  double best = min_dihedral(c3t3);
  const int rounds = o.max_rounds > 0 ? o.max_rounds : 1;
  /* Perturbation first, in rounds, then exudation in rounds: exudation gives
     the vertices weights, and perturb_mesh_3 requires a triangulation
     without weights other than the features' protecting balls (its
     precondition has_non_protecting_weights; a perturbation after an
     exudation violated it). */
  for (int pass = 0; pass < 2; pass++) {
    if (!(pass == 0 ? o.perturb : o.exude)) continue;
    for (int r = 0; r < rounds && (r == 0 || best < target); r++) {
      if (pass == 0) CGAL::perturb_mesh_3(c3t3, domain, P::sliver_bound = target, P::time_limit = time_left(o));
      else CGAL::exude_mesh_3(c3t3, P::sliver_bound = target, P::time_limit = time_left(o));
      const double now = min_dihedral(c3t3);
      const bool progress = now > best + 1e-3;
      best = now;
      if (!progress) break;
    }
  }
  *achieved = best;
}

// The cells outside the complex that leave its boundary other than a closed
// 2-manifold, added to it (Mesh_3 keeps the cells whose circumcentre is
// inside; at a coarse size a flat cell just under a curved scan's surface
// can have its circumcentre outside): small enclosed cavities (an
// outside component of cells reaching no infinite cell), and at an edge or
// a vertex whose outside cells form several separate wedges (two parts of
// the body touching along the edge, or at the vertex), every wedge but the
// one reaching the outside (or the largest). Only wedges of at most
// max_cells cells are filled (a larger one is a gap of the input), and
// cavities of at most cavity_cells (a larger one may be a void of the
// input; a one-piece surface has none, and there a cavity of any size is
// Mesh_3's: the camel at diagonal / 50 with facet distance h / 40 left 7,
// of 2 to 52 cells, in a 3 mm sheet on its head). Filling can close new
// cavities; they are filled in turn. Returns the count of cells added.
typedef std::unordered_set<Tr::Cell_handle> Cell_set;

bool outside(const C3t3 &c3t3, Tr::Cell_handle c) { return !c3t3.is_in_complex(c); }

// The outside cells (inside ones, with out = false) of `cells` in groups
// joined by a facet whose cells are both in `cells` and on the same side
// (their star around an edge or a vertex).
std::vector<std::vector<Tr::Cell_handle>> outside_groups(const C3t3 &c3t3, const std::vector<Tr::Cell_handle> &cells,
                                                         bool out = true) {
  std::vector<std::vector<Tr::Cell_handle>> groups;
  const auto n_out = std::count_if(cells.begin(), cells.end(), [&](Tr::Cell_handle c) { return outside(c3t3, c); });
  if (n_out == 0 || n_out == (long)cells.size()) return groups; /* not on the boundary */
  Cell_set in_star(cells.begin(), cells.end()), seen;
  for (Tr::Cell_handle c0 : cells) {
    if (outside(c3t3, c0) != out || seen.count(c0)) continue;
    std::vector<Tr::Cell_handle> g{c0}, stack{c0};
    seen.insert(c0);
    while (!stack.empty()) {
      Tr::Cell_handle c = stack.back();
      stack.pop_back();
      for (int i = 0; i < 4; i++) {
        Tr::Cell_handle n = c->neighbor(i);
        if (in_star.count(n) && outside(c3t3, n) == out && seen.insert(n).second) g.push_back(n), stack.push_back(n);
      }
    }
    groups.push_back(std::move(g));
  }
  return groups;
}

bool has_infinite(const Tr &tr, const std::vector<Tr::Cell_handle> &g) {
  return std::any_of(g.begin(), g.end(), [&](Tr::Cell_handle c) { return tr.is_infinite(c); });
}

// Fills the group if it is small and has no infinite cell.
int fill_all(C3t3 &c3t3, const std::vector<Tr::Cell_handle> &g, C3t3::Subdomain_index sd, std::size_t max_cells) {
  const Tr &tr = c3t3.triangulation();
  if (g.size() > max_cells || has_infinite(tr, g)) return 0;
  for (Tr::Cell_handle c : g) c3t3.add_to_complex(c, sd);
  return (int)g.size();
}

// Fills every group but one (the one with an infinite cell, else the
// largest) if all those are small; returns the cells added.
int fill_groups(C3t3 &c3t3, const std::vector<std::vector<Tr::Cell_handle>> &groups, C3t3::Subdomain_index sd,
                std::size_t max_cells) {
  if (groups.size() < 2) return 0;
  const Tr &tr = c3t3.triangulation();
  std::size_t keep = 0;
  for (std::size_t k = 1; k < groups.size(); k++)
    if (has_infinite(tr, groups[k]) || (!has_infinite(tr, groups[keep]) && groups[k].size() > groups[keep].size()))
      keep = k;
  for (std::size_t k = 0; k < groups.size(); k++)
    if (k != keep && (groups[k].size() > max_cells || has_infinite(tr, groups[k]))) return 0;
  int added = 0;
  for (std::size_t k = 0; k < groups.size(); k++)
    if (k != keep) added += fill_all(c3t3, groups[k], sd, max_cells);
  return added;
}

// Enclosed outside components (no infinite cell) of at most max_cells cells.
int fill_cavities(C3t3 &c3t3, C3t3::Subdomain_index sd, std::size_t max_cells) {
  const Tr &tr = c3t3.triangulation();
  Cell_set seen;
  int added = 0;
  for (auto c0 = tr.finite_cells_begin(); c0 != tr.finite_cells_end(); ++c0) {
    Tr::Cell_handle h = c0;
    if (!outside(c3t3, h) || !seen.insert(h).second) continue;
    std::vector<Tr::Cell_handle> g{h}, stack{h};
    bool open = false;
    while (!stack.empty()) {
      Tr::Cell_handle c = stack.back();
      stack.pop_back();
      for (int i = 0; i < 4; i++) {
        Tr::Cell_handle n = c->neighbor(i);
        if (!outside(c3t3, n) || !seen.insert(n).second) continue;
        open = open || tr.is_infinite(n);
        stack.push_back(n);
        if (g.size() <= max_cells) g.push_back(n);
      }
    }
    if (open || g.size() > max_cells) continue;
    for (Tr::Cell_handle c : g) c3t3.add_to_complex(c, sd), added++;
  }
  return added;
}

// Cavities of at most cavity_cells cells filled (fill_cavities), then the
// pinches' smaller wedges of at most max_cells.
int fill_pinches(C3t3 &c3t3, std::size_t max_cells, std::size_t cavity_cells) {
  Tr &tr = c3t3.triangulation();
  if (c3t3.number_of_cells_in_complex() == 0) return 0;
  const C3t3::Subdomain_index sd = c3t3.subdomain_index(c3t3.cells_in_complex_begin());
  int total = fill_cavities(c3t3, sd, cavity_cells);
  for (int pass = 0; pass < 4; pass++) {
    int added = 0;
    for (auto e = tr.finite_edges_begin(); e != tr.finite_edges_end(); ++e) {
      std::vector<Tr::Cell_handle> star;
      Tr::Cell_circulator cc = tr.incident_cells(*e), end = cc;
      do star.push_back(cc); while (++cc != end);
      auto groups = outside_groups(c3t3, star);
      added += fill_groups(c3t3, groups, sd, max_cells);
    }
    for (auto v = tr.finite_vertices_begin(); v != tr.finite_vertices_end(); ++v) {
      std::vector<Tr::Cell_handle> star;
      tr.incident_cells(v, std::back_inserter(star));
      auto groups = outside_groups(c3t3, star);
      /* two inside cones touching at v, the outside around them one group:
         filled whole when small (v becomes an inner vertex) */
      if (groups.size() == 1 && outside_groups(c3t3, star, false).size() > 1) added += fill_all(c3t3, groups[0], sd, max_cells);
      else added += fill_groups(c3t3, groups, sd, max_cells);
    }
    if (added) added += fill_cavities(c3t3, sd, cavity_cells); /* the fills can close new ones */
    total += added;
    if (!added) break;
  }
  return total;
}

// The surface's connected components (faces joined across edges).
std::size_t surface_components(const Surface &sm) {
  std::vector<char> seen(sm.num_faces(), 0);
  std::size_t n = 0;
  for (Surface::Face_index f0 : sm.faces()) {
    if (seen[f0]) continue;
    n++;
    std::vector<Surface::Face_index> stack{f0};
    seen[f0] = 1;
    while (!stack.empty()) {
      const Surface::Face_index f = stack.back();
      stack.pop_back();
      for (Surface::Halfedge_index h : CGAL::halfedges_around_face(sm.halfedge(f), sm)) {
        const Surface::Face_index g = sm.face(sm.opposite(h));
        if (g != Surface::null_face() && !seen[g]) seen[g] = 1, stack.push_back(g);
      }
    }
  }
  return n;
}

// The complex's vertices and cells as C arrays (cells oriented as CGAL's
// triangulation keeps them: positive, CGAL::orientation(p0, p1, p2, p3) > 0).
int export_mesh(const C3t3 &c3t3, const char *name, double **xo, int64_t *nvo, int32_t **to, int64_t *nto,
                bs_error *err) {
  std::unordered_map<Tr::Vertex_handle, int32_t> index;
  std::vector<Tr::Vertex_handle> order;
  const std::size_t nc = c3t3.number_of_cells_in_complex();
  if (nc == 0) return bs_error_set(err, BS_EINPUT, "%s: CGAL Mesh_3 made no tetrahedra inside the surface", name);
  if (nc > (std::size_t)BS_SHIM_MAX_TETS)
    return bs_error_set(err, BS_EINPUT, "%s: CGAL Mesh_3 made %zu tets, more than %ld", name, nc,
                        (long)BS_SHIM_MAX_TETS);
  int32_t *t = (int32_t *)std::malloc(4 * nc * sizeof(int32_t));
  if (!t) return bs_error_set(err, BS_ENOMEM, "%s: out of memory for %zu tets", name, nc);
  std::size_t k = 0;
  for (auto c = c3t3.cells_in_complex_begin(); c != c3t3.cells_in_complex_end(); ++c, ++k)
    for (int i = 0; i < 4; i++) {
      Tr::Vertex_handle v = c->vertex(i);
      auto it = index.find(v);
      if (it == index.end()) {
        it = index.emplace(v, (int32_t)order.size()).first;
        order.push_back(v);
      }
      t[4 * k + i] = it->second;
    }
  double *x = (double *)std::malloc(3 * order.size() * sizeof(double));
  if (!x) {
    std::free(t);
    return bs_error_set(err, BS_ENOMEM, "%s: out of memory for %zu vertices", name, order.size());
  }
  auto cp = c3t3.triangulation().geom_traits().construct_point_3_object();
  for (std::size_t i = 0; i < order.size(); i++) {
    const K::Point_3 p = cp(c3t3.triangulation().point(order[i]));
    x[3 * i + 0] = p.x();
    x[3 * i + 1] = p.y();
    x[3 * i + 2] = p.z();
  }
  *xo = x;
  *nvo = (int64_t)order.size();
  *to = t;
  *nto = (int64_t)nc;
  return BS_OK;
}

// Mesh_3's refinement of the domain to the criteria of o: sizes h, or for a
// scan (not cad) its own criteria and the thickness field
// (shim_local_size.hpp) when o.thickness_elements > 0.
C3t3 refine(const Surface &sm, const Domain &domain, bool cad, const bs_shim_mesh3_opts &o, bs_shim_mesh3_out *out) {
  namespace P = CGAL::parameters;
  const double h = o.size;
  double dist = o.facet_distance > 0 ? o.facet_distance : h / 10.0, fa = 25, re = 3;
  const double fs = o.facet_size > 0 ? o.facet_size : h;
  if (!cad) {
    if (o.scan_facet_distance > 0) dist = o.scan_facet_distance;
    if (o.scan_facet_angle > 0) fa = o.scan_facet_angle;
    if (o.scan_radius_edge > 0) re = o.scan_radius_edge;
  }
  out->local_size_min = h;
  out->local_fraction = 0;
  time_left(o, "before Mesh_3's refinement");
  Watchdog watchdog(o.deadline);
  const auto options = P::mesh_3_options(P::pointer_to_stop_atomic_boolean = watchdog.flag());
  if (cad || !(o.thickness_elements > 0)) {
    Criteria criteria(P::edge_size = fs, P::facet_angle = fa, P::facet_size = fs, P::facet_distance = dist,
                      P::cell_radius_edge_ratio = re, P::cell_size = h);
    C3t3 c3t3 = CGAL::make_mesh_3<C3t3>(domain, criteria, P::no_perturb(), P::no_exude(), P::no_odt(), P::no_lloyd(),
                                        options);
    if (watchdog.fired())
      throw budget_exceeded{"during Mesh_3's refinement", c3t3.triangulation().number_of_vertices()};
    return c3t3;
  }
  const double floor = o.min_size > 0 ? std::min(o.min_size, h) : h / 8;
  const bs_shim::Local_size field(sm, {h, o.thickness_elements, o.size_gradation > 0 ? o.size_gradation : 0.5, floor});
  out->local_size_min = field.min_sample_size();
  out->local_fraction = field.fraction_refined();
  const bs_shim::Scaled_size facet{field, fs / h};
  Criteria criteria(P::edge_size = facet, P::facet_angle = fa, P::facet_size = facet, P::facet_distance = dist,
                    P::cell_radius_edge_ratio = re, P::cell_size = field);
  C3t3 c3t3 = CGAL::make_mesh_3<C3t3>(domain, criteria, P::no_perturb(), P::no_exude(), P::no_odt(), P::no_lloyd(),
                                      options);
  if (watchdog.fired())
    throw budget_exceeded{"during Mesh_3's refinement", c3t3.triangulation().number_of_vertices()};
  return c3t3;
}

int mesh_surface(const char *name, const double *pts, int64_t np, const int32_t *tris, int64_t nt,
                 const bs_shim_mesh3_opts &o, bs_shim_mesh3_out *out, bs_error *err) {
  Surface sm;
  int rc = bs_shim::soup_to_closed_surface(name, pts, np, tris, nt, sm, err);
  if (rc) return rc;
  const double h = o.size;
  if (!(h > 0) || !std::isfinite(h)) return bs_error_set(err, BS_EINPUT, "%s: mesh size %g must be > 0", name, h);
  CGAL::get_default_random() = CGAL::Random(0);
  int64_t n_long = 0;
  const bool cad = o.feature_angle > 0 &&
                   bs_shim::cad_like(sm, o.feature_angle, o.feature_min_length > 0 ? o.feature_min_length : 2 * h, &n_long);
  Domain domain(sm);
  if (cad) domain.detect_features(o.feature_angle);
  out->n_features = cad ? n_long : 0;
  C3t3 c3t3 = refine(sm, domain, cad, o, out);
  out->refined_dihedral = min_dihedral(c3t3);
  optimise(c3t3, domain, o, &out->dihedral);
  time_left(o);
  /* a one-piece closed surface encloses no void: every cavity is Mesh_3's */
  const std::size_t cavity_cells = surface_components(sm) == 1 ? SIZE_MAX : BS_SHIM_MESH3_FILL_CELLS;
  out->n_filled = fill_pinches(c3t3, BS_SHIM_MESH3_FILL_CELLS, cavity_cells);
  if (out->n_filled) out->dihedral = min_dihedral(c3t3);
  return export_mesh(c3t3, name, &out->x, &out->n_vertices, &out->tets, &out->n_tets, err);
}

} // namespace

namespace {

// mesh_surface with every exception turned into a status and a message.
int mesh_surface_caught(const char *name, const double *points, int64_t n_points, const int32_t *tris,
                        int64_t n_tris, const bs_shim_mesh3_opts &o, bs_shim_mesh3_out *out, bs_error *err) {
  try {
    return mesh_surface(name, points, n_points, tris, n_tris, o, out, err);
  } catch (const budget_exceeded &b) {
    if (b.vertices)
      return bs_error_set(err, BS_EINPUT, "%s: the meshing time budget was exceeded %s (stopped at %zu vertices)", name,
                          b.stage, b.vertices);
    return bs_error_set(err, BS_EINPUT, "%s: the meshing time budget was exceeded %s", name, b.stage);
  } catch (const std::bad_alloc &) {
    return bs_error_set(err, BS_ENOMEM, "%s: out of memory while CGAL meshed the volume", name);
  } catch (const std::exception &e) {
    return bs_error_set(err, BS_EINPUT, "%s: CGAL Mesh_3 failed: %s", name, e.what());
  } catch (...) {
    return bs_error_set(err, BS_EINPUT, "%s: CGAL Mesh_3 failed (unknown exception)", name);
  }
}

// One meshing run in a child process (bs_run_in_child): the inputs, and the
// output the child fills and the parent receives.
struct Job {
  const char *name;
  const double *points;
  int64_t n_points;
  const int32_t *tris;
  int64_t n_tris;
  const bs_shim_mesh3_opts *o;
  bs_shim_mesh3_out out;
};

int job_run(void *c, bs_error *err) {
  Job &j = *static_cast<Job *>(c);
  return mesh_surface_caught(j.name, j.points, j.n_points, j.tris, j.n_tris, *j.o, &j.out, err);
}

int job_send(void *c, int fd) {
  const bs_shim_mesh3_out &r = static_cast<Job *>(c)->out;
  if (bs_write_all(fd, &r, sizeof r)) return BS_EIO;
  if (bs_write_all(fd, r.x, 3 * sizeof(double) * (size_t)r.n_vertices)) return BS_EIO;
  return bs_write_all(fd, r.tets, 4 * sizeof(int32_t) * (size_t)r.n_tets);
}

int job_receive(void *c, int fd, bs_error *err) {
  Job &j = *static_cast<Job *>(c);
  bs_shim_mesh3_out r;
  int rc = bs_read_all(fd, &r, sizeof r, j.name, err);
  if (rc) return rc;
  if (r.n_vertices < 0 || r.n_tets < 0 || r.n_tets > (int64_t)BS_SHIM_MAX_TETS || r.n_vertices > 4 * r.n_tets)
    return bs_error_set(err, BS_EINTERNAL, "%s: the meshing process sent %lld vertices and %lld tets", j.name,
                        (long long)r.n_vertices, (long long)r.n_tets);
  r.x = static_cast<double *>(std::malloc(3 * sizeof(double) * (size_t)std::max<int64_t>(r.n_vertices, 1)));
  r.tets = static_cast<int32_t *>(std::malloc(4 * sizeof(int32_t) * (size_t)std::max<int64_t>(r.n_tets, 1)));
  if (!r.x || !r.tets) rc = bs_error_set(err, BS_ENOMEM, "%s: out of memory for %lld tets", j.name, (long long)r.n_tets);
  if (!rc) rc = bs_read_all(fd, r.x, 3 * sizeof(double) * (size_t)r.n_vertices, j.name, err);
  if (!rc) rc = bs_read_all(fd, r.tets, 4 * sizeof(int32_t) * (size_t)r.n_tets, j.name, err);
  if (rc) {
    std::free(r.x);
    std::free(r.tets);
    return rc;
  }
  j.out = r;
  return BS_OK;
}

} // namespace

extern "C" int bs_shim_mesh_surface(const char *name, const double *points, int64_t n_points, const int32_t *tris,
                                    int64_t n_tris, const bs_shim_mesh3_opts *opts, bs_shim_mesh3_out *out,
                                    bs_error *err) {
  if (!name) name = "(surface)";
  if (!points || !tris || !opts || !out) return bs_error_set(err, BS_EINPUT, "%s: bs_shim_mesh_surface: NULL argument", name);
  *out = bs_shim_mesh3_out{};
  Job job{name, points, n_points, tris, n_tris, opts, bs_shim_mesh3_out{}};
  char what[BS_ERROR_MSG / 2];
  std::snprintf(what, sizeof what, "%s: CGAL Mesh_3", name);
  const int rc = bs_run_in_child(what, job_run, job_send, job_receive, &job, err);
  if (rc == BS_OK) *out = job.out;
  return rc;
}
