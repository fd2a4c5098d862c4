// shim_tet_remesh.cpp — a tetrahedral mesh lifted in quality by CGAL's
// tetrahedral isotropic remeshing (bs_shim_tet_remesh, see bs_shim.h).
//
// The tets (any orientation; flat ones, of zero volume, are taken too: the
// remesher's flips and collapses remove them) become a
// Remeshing_triangulation_3 through CGAL::build_triangulation (the loader
// CGAL's own remesher uses for non-convex domains: every tet of subdomain 1,
// an infinite cell on each boundary face). Then rounds of
// CGAL::tetrahedral_isotropic_remeshing at the target edge length, one
// iteration each, until the smallest dihedral angle reaches the target, the
// rounds run out or two rounds in a row have not raised it; the best state
// seen (largest smallest angle) is kept.
//
// Protection: BS_SHIM_TET_PROTECT_BOUNDARY keeps every boundary triangle as
// it is (remesh_boundaries(false): the surface, its volume and its distance
// to the input unchanged); BS_SHIM_TET_PROTECT_FEATURES lets the remesher
// split, collapse and move boundary vertices (re-projected onto the input
// boundary) but constrains the sharp edges (boundary edges whose two faces
// turn by more than feature_angle) so that they are split or collapsed
// only along their chains and never flipped.
//
// CGAL 5.5's remesher prints "Resolution reached" on std::cout
// unconditionally (tetrahedral_adaptive_remeshing_impl.h:284): std::cout's
// buffer is swapped for a null one while it runs (Quiet_cout; process-wide,
// restored on every exit).
//
// A deadline (bs_seconds() time) is checked in the remesher's visitor every
// 256 splits or flips, and between rounds: past it, BS_EINPUT naming the
// budget. Deterministic; sequential. Every extern "C" entry catches every
// exception; nothing is printed.

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Mesh_3/tet_soup_to_c3t3.h>
#include <CGAL/Tetrahedral_remeshing/Remeshing_triangulation_3.h>
#include <CGAL/tetrahedral_remeshing.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <exception>
#include <iostream>
#include <sstream>
#include <map>
#include <new>
#include <set>
#include <type_traits>
#include <unordered_set>
#include <unordered_map>
#include <vector>

#include "bs_limits.h"
#include "bs_shim.h"

namespace {

typedef CGAL::Exact_predicates_inexact_constructions_kernel K;
typedef CGAL::Tetrahedral_remeshing::Remeshing_triangulation_3<K> Tr;
typedef Tr::Vertex_handle Vh;
typedef Tr::Cell_handle Ch;
typedef std::pair<Vh, Vh> Edge_vv;

} // namespace

// CGAL 5.5's edge collapse (collapse_short_edges.h) copies the stars of the
// edge's two vertices into a local triangulation (CollapseTriangulation) to
// try the collapse there first. When those cells do not make a valid
// triangulation (build_triangulation fails: their union is not a ball, e.g.
// the stars of two boundary vertices meet again across a thin part; femur.off
// at diagonal / 25 has one), the constructor returns without setting its
// member not_an_edge, and collapse() reads it uninitialised: it then works
// on a default Edge and crashes (SIGSEGV) or corrupts the mesh. This is the
// same constructor for the remesher's complex with not_an_edge set first,
// so that such a collapse is refused (E_PROBLEM) as CGAL means it to be;
// each refusal is counted (bs_shim_tet_remesh_out.collapses_refused).
namespace {
thread_local int64_t refused_collapses = 0;
} // namespace

namespace CGAL {
namespace Tetrahedral_remeshing {
namespace internal {
typedef CGAL::Mesh_complex_3_in_triangulation_3<::Tr::Base, int, int> Bs_remesh_c3t3;
template <>
CollapseTriangulation<Bs_remesh_c3t3>::CollapseTriangulation(const Edge &e,
                                                             const std::unordered_set<Cell_handle> &cells_to_insert,
                                                             Collapse_type _collapse_type)
    : collapse_type(_collapse_type), v0_init(e.first->vertex(e.second)), v1_init(e.first->vertex(e.third)),
      not_an_edge(true) {
  std::unordered_map<Vertex_handle, int> v2i;
  std::vector<Point_3> points;
  std::vector<std::array<int, 5>> finite_cells;
  for (Cell_handle ch : cells_to_insert) {
    std::array<int, 5> t;
    for (int i = 0; i < 4; ++i) {
      auto it = v2i.emplace(ch->vertex(i), (int)points.size());
      if (it.second) points.push_back(ch->vertex(i)->point());
      t[i] = it.first->second;
    }
    t[4] = ch->subdomain_index();
    finite_cells.push_back(t);
  }
  if (!v2i.count(v0_init) || !v2i.count(v1_init)) return;
  std::vector<Vertex_handle> new_vertices;
  std::map<std::array<int, 3>, Surface_patch_index> border_facets;
  if (!CGAL::build_triangulation<Tr, false>(triangulation, points, finite_cells, border_facets, new_vertices, false)) {
    refused_collapses++;
    return;
  }
  vh0 = new_vertices[v2i.at(v0_init) + 1];
  vh1 = new_vertices[v2i.at(v1_init) + 1];
  Cell_handle ch;
  int i0, i1;
  if (triangulation.is_edge(vh0, vh1, ch, i0, i1)) {
    edge = Edge(ch, i0, i1);
    not_an_edge = false;
  }
}
} // namespace internal
} // namespace Tetrahedral_remeshing
} // namespace CGAL

namespace {

static_assert(std::is_same<Tr::Base, CGAL::Triangulation_3<K, Tr::Tds>>::value,
              "the remesher's complex is Mesh_complex_3_in_triangulation_3<Tr::Base, int, int>");

struct budget_exceeded {};

// The remesher's visitor: throws budget_exceeded past the deadline.
struct Deadline_visitor : CGAL::Tetrahedral_remeshing::internal::Default_remeshing_visitor {
  double deadline = 0;
  std::size_t calls = 0;
  void tick() {
    if (deadline > 0 && (++calls & 255) == 0 && bs_seconds() > deadline) throw budget_exceeded();
  }
  template <typename T> void before_split(const T &, const typename T::Edge &) { tick(); }
  template <typename C> void before_flip(const C) { tick(); }
};

// Constrained (sharp) edges: a read-write property map over a shared set.
struct Constrained_edges {
  typedef Edge_vv key_type;
  typedef bool value_type;
  typedef bool reference;
  typedef boost::read_write_property_map_tag category;
  std::set<Edge_vv> *edges = nullptr;
  static Edge_vv ordered(const Edge_vv &e) { return e.second < e.first ? Edge_vv(e.second, e.first) : e; }
  friend bool get(const Constrained_edges &m, const key_type &k) { return m.edges && m.edges->count(ordered(k)); }
  friend void put(Constrained_edges &m, const key_type &k, bool b) {
    if (!m.edges) return;
    if (b) m.edges->insert(ordered(k));
    else m.edges->erase(ordered(k));
  }
};

// std::cout silenced for the lifetime of the object.
// (sink is declared first: members are built in declaration order.)
struct Quiet_cout {
  std::ostringstream sink;
  std::streambuf *saved;
  Quiet_cout() : saved(std::cout.rdbuf(sink.rdbuf())) {}
  ~Quiet_cout() { std::cout.rdbuf(saved); }
};

bool in_domain(const Tr &tr, Ch c) { return !tr.is_infinite(c) && c->subdomain_index() != 0; }

// The smallest dihedral angle (degrees) of a tet.
double min_dihedral(const K::Point_3 &a, const K::Point_3 &b, const K::Point_3 &c, const K::Point_3 &d) {
  const K::Point_3 p[4] = {a, b, c, d};
  static const int e[6][4] = {{0, 1, 2, 3}, {0, 2, 1, 3}, {0, 3, 1, 2}, {1, 2, 0, 3}, {1, 3, 0, 2}, {2, 3, 0, 1}};
  double worst = 180;
  for (int k = 0; k < 6; k++) {
    double ang = std::fabs(CGAL::to_double(CGAL::approximate_dihedral_angle(p[e[k][0]], p[e[k][1]], p[e[k][2]], p[e[k][3]])));
    worst = std::min(worst, ang);
  }
  return worst;
}

double tr_min_dihedral(const Tr &tr, double *volume) {
  double worst = 180, v = 0;
  for (Ch c : tr.finite_cell_handles()) {
    if (!in_domain(tr, c)) continue;
    const K::Point_3 &a = c->vertex(0)->point(), &b = c->vertex(1)->point(), &p = c->vertex(2)->point(),
                     &d = c->vertex(3)->point();
    worst = std::min(worst, min_dihedral(a, b, p, d));
    v += CGAL::volume(a, b, p, d);
  }
  if (volume) *volume = v;
  return worst;
}

// The facet of cell c opposite vertex i, in CGAL's order
// (Triangulation_utils_3::vertex_triple_index): two cells sharing a facet
// induce opposite orientations on it when both are positively oriented.
std::array<int, 3> facet(const std::array<int, 5> &c, int i) {
  static const int T[4][3] = {{1, 3, 2}, {0, 2, 3}, {0, 3, 1}, {0, 1, 2}};
  return {c[T[i][0]], c[T[i][1]], c[T[i][2]]};
}

bool same_turn(const std::array<int, 3> &a, const std::array<int, 3> &b) {
  for (int r = 0; r < 3; r++)
    if (a[0] == b[r] && a[1] == b[(r + 1) % 3] && a[2] == b[(r + 2) % 3]) return true;
  return false;
}

// Flat cells (flat[k]) have no geometric orientation: each gets the
// combinatorial one its oriented neighbours ask for (the facet they share
// seen the other way round), flat neighbours of flat cells in turn.
void orient_flat(std::vector<std::array<int, 5>> &cells, std::vector<char> &flat) {
  std::map<std::array<int, 3>, std::vector<std::pair<std::size_t, int>>> faces;
  for (std::size_t k = 0; k < cells.size(); k++)
    for (int i = 0; i < 4; i++) {
      std::array<int, 3> f = facet(cells[k], i);
      std::sort(f.begin(), f.end());
      faces[f].push_back({k, i});
    }
  for (bool changed = true; changed;) {
    changed = false;
    for (std::size_t k = 0; k < cells.size(); k++) {
      for (int i = 0; flat[k] && i < 4; i++) {
        std::array<int, 3> f = facet(cells[k], i), key = f;
        std::sort(key.begin(), key.end());
        for (const auto &n : faces[key]) {
          if (n.first == k || flat[n.first]) continue;
          if (same_turn(f, facet(cells[n.first], n.second))) std::swap(cells[k][0], cells[k][1]);
          flat[k] = 0, changed = true;
          break;
        }
      }
    }
  }
}

// Whether every finite vertex's star (its cells, the infinite ones
// included) is one piece joined across facets: where two parts of the body
// touch at a vertex it is two, which the remesher cannot work on.
bool stars_connected(const Tr &tr) {
  std::unordered_map<Vh, std::size_t, CGAL::Handle_hash_function> in_cells;
  for (auto c = tr.tds().cells_begin(); c != tr.tds().cells_end(); ++c)
    for (int k = 0; k < 4; k++) in_cells[c->vertex(k)]++;
  std::vector<Ch> star;
  for (Vh v : tr.finite_vertex_handles()) {
    star.clear();
    tr.tds().incident_cells(v, std::back_inserter(star));
    if (star.size() != in_cells[v]) return false;
  }
  return true;
}

// The tets from C into tr (subdomain sub[t], 1 without), each positively
// oriented (flat ones as their neighbours ask: orient_flat).
int build(const char *name, const double *x, int64_t nv, const int32_t *tets, int64_t nt, const int32_t *sub, Tr &tr,
          bs_error *err) {
  if (!x || !tets || nv < 4 || nt < 1)
    return bs_error_set(err, BS_EINPUT, "%s: the mesh is empty (%lld vertices, %lld tets)", name, (long long)nv,
                        (long long)nt);
  if (nv > BS_MAX_VERTICES || nt > BS_MAX_TETS)
    return bs_error_set(err, BS_EINPUT, "%s: %lld vertices and %lld tets exceed bigstep's limits", name,
                        (long long)nv, (long long)nt);
  std::vector<K::Point_3> pts;
  pts.reserve((std::size_t)nv);
  for (int64_t i = 0; i < nv; i++) {
    const double *p = x + 3 * i;
    if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2]))
      return bs_error_set(err, BS_ENUMERIC, "%s: vertex %lld has a non-finite coordinate", name, (long long)i);
    pts.emplace_back(p[0], p[1], p[2]);
  }
  std::vector<std::array<int, 5>> cells;
  std::vector<char> flat((std::size_t)nt, 0);
  bool any_flat = false;
  cells.reserve((std::size_t)nt);
  for (int64_t t = 0; t < nt; t++) {
    std::array<int, 5> c = {tets[4 * t], tets[4 * t + 1], tets[4 * t + 2], tets[4 * t + 3], sub ? sub[t] : 1};
    if (c[4] < 1)
      return bs_error_set(err, BS_EINPUT, "%s: tet %lld has subdomain %d (must be >= 1)", name, (long long)t, c[4]);
    for (int k = 0; k < 4; k++)
      if (c[k] < 0 || c[k] >= nv)
        return bs_error_set(err, BS_EINPUT, "%s: tet %lld refers to vertex %d of %lld", name, (long long)t, c[k],
                            (long long)nv);
    const CGAL::Orientation turn = CGAL::orientation(pts[c[0]], pts[c[1]], pts[c[2]], pts[c[3]]);
    if (turn == CGAL::NEGATIVE) std::swap(c[0], c[1]);
    if (turn == CGAL::ZERO) flat[(std::size_t)t] = 1, any_flat = true;
    cells.push_back(c);
  }
  if (any_flat) orient_flat(cells, flat);
  std::map<std::array<int, 3>, Tr::Cell::Surface_patch_index> border;
  std::vector<Vh> handles;
  /* <Tr, true>: without the final tds().is_valid(), whose Euler relation
     holds only when the boundary is one sphere (coned to the infinite
     vertex); a part with a hole through it (rotor.off) was refused by it.
     The faces are checked by the build (each in two cells, the infinite
     ones included), the vertices by stars_connected. */
  if (!CGAL::build_triangulation<Tr, true>(tr, pts, cells, border, handles, false) || !stars_connected(tr))
    return bs_error_set(err, BS_EINPUT,
                        "%s: the tets do not form a valid triangulation for the remesher (a face in more than two "
                        "tets, or a boundary that pinches at a vertex or an edge)",
                        name);
  return BS_OK;
}

// Boundary edges where the two boundary faces turn by more than angle
// degrees (normals further apart than that), into edges.
void sharp_edges(const Tr &tr, double angle, std::set<Edge_vv> &edges) {
  std::map<Edge_vv, std::vector<K::Vector_3>> normals;
  for (Ch c : tr.finite_cell_handles()) {
    if (!in_domain(tr, c)) continue;
    for (int f = 0; f < 4; f++) {
      if (in_domain(tr, c->neighbor(f))) continue;
      Vh v[3] = {c->vertex((f + 1) & 3), c->vertex((f + 2) & 3), c->vertex((f + 3) & 3)};
      K::Vector_3 n = CGAL::normal(v[0]->point(), v[1]->point(), v[2]->point());
      const double len = std::sqrt(n.squared_length());
      if (len > 0) n = n / len;
      for (int k = 0; k < 3; k++) normals[Constrained_edges::ordered(Edge_vv(v[k], v[(k + 1) % 3]))].push_back(n);
    }
  }
  const double cos_limit = std::cos(angle * CGAL_PI / 180.0);
  for (const auto &e : normals)
    if (e.second.size() == 2 && std::fabs(e.second[0] * e.second[1]) < cos_limit) edges.insert(e.first);
    else if (e.second.size() != 2) edges.insert(e.first);
}

// The cells of the domain into C arrays (malloc), vertices renumbered.
int extract(const Tr &tr, bs_shim_tet_remesh_out *out, bs_error *err) {
  std::unordered_map<Vh, int32_t, CGAL::Handle_hash_function> id;
  std::vector<int32_t> tets, sub;
  std::vector<double> x;
  for (Ch c : tr.finite_cell_handles()) {
    if (!in_domain(tr, c)) continue;
    for (int k = 0; k < 4; k++) {
      auto it = id.emplace(c->vertex(k), (int32_t)id.size());
      if (it.second)
        for (int j = 0; j < 3; j++) x.push_back(c->vertex(k)->point()[j]);
      tets.push_back(it.first->second);
    }
    sub.push_back((int32_t)c->subdomain_index());
  }
  out->x = (double *)std::malloc(x.size() * sizeof(double) + 1);
  out->tets = (int32_t *)std::malloc(tets.size() * sizeof(int32_t) + 1);
  out->subdomain = (int32_t *)std::malloc(sub.size() * sizeof(int32_t) + 1);
  if (!out->x || !out->tets || !out->subdomain) return bs_error_set(err, BS_ENOMEM, "out of memory for the remeshed tets");
  std::copy(sub.begin(), sub.end(), out->subdomain);
  std::copy(x.begin(), x.end(), out->x);
  std::copy(tets.begin(), tets.end(), out->tets);
  out->n_vertices = (int64_t)(x.size() / 3);
  out->n_tets = (int64_t)(tets.size() / 4);
  return BS_OK;
}

// Rounds that do not raise the smallest angle, in a row, after which the
// remeshing stops. In every lift measured, no round beat the best after one
// that did not (the camel's two Mesh_3 meshes at diagonal / 50: 7.07 and
// 9.05 degrees in, 0.0001 to 5.35 over 8 rounds of each protection, 62 s
// for nothing), and the lifts that pass (test_mesh_lift's) reach the target
// in their first round.
constexpr int STALL_ROUNDS = 2;

// Rounds of one remeshing iteration until the target, the last round or
// STALL_ROUNDS rounds in a row with no gain; the best triangulation seen is
// left in best.
void rounds(Tr &tr, const bs_shim_tet_remesh_opts *o, Tr &best, bs_shim_tet_remesh_out *out) {
  std::set<Edge_vv> constrained;
  Constrained_edges cmap;
  cmap.edges = &constrained;
  const bool features = o->protect == BS_SHIM_TET_PROTECT_FEATURES;
  if (features) sharp_edges(tr, o->feature_angle > 0 ? o->feature_angle : 60.0, constrained);
  Deadline_visitor vis;
  vis.deadline = o->deadline;
  const int n = o->iterations > 0 ? o->iterations : 8;
  Quiet_cout quiet;
  best = tr;
  int stalled = 0;
  for (int it = 0; it < n && out->dihedral < o->target_dihedral && stalled < STALL_ROUNDS; it++) {
    if (o->deadline > 0 && bs_seconds() > o->deadline) throw budget_exceeded();
    CGAL::tetrahedral_isotropic_remeshing(tr, o->size,
                                          CGAL::parameters::number_of_iterations(1)
                                              .remesh_boundaries(features)
                                              .edge_is_constrained_map(cmap)
                                              .visitor(vis));
    out->rounds = it + 1;
    const double d = tr_min_dihedral(tr, nullptr);
    if (d > out->dihedral) {
      out->dihedral = d;
      best = tr;
      stalled = 0;
    } else stalled++;
  }
}

int remesh(const char *name, const double *x, int64_t nv, const int32_t *tets, int64_t nt, const int32_t *sub,
           const bs_shim_tet_remesh_opts *o, bs_shim_tet_remesh_out *out, bs_error *err) {
  if (!o || !(o->size > 0) || !std::isfinite(o->size))
    return bs_error_set(err, BS_EINPUT, "%s: the tetrahedral remeshing needs a size > 0 (got %g)", name,
                        o ? o->size : 0.0);
  Tr tr, best;
  int rc = build(name, x, nv, tets, nt, sub, tr, err);
  if (rc) return rc;
  out->dihedral_in = out->dihedral = tr_min_dihedral(tr, &out->volume_in);
  const double t0 = bs_seconds();
  refused_collapses = 0;
  try {
    rounds(tr, o, best, out);
  } catch (const budget_exceeded &) {
    return bs_error_set(err, BS_EINPUT,
                        "%s: the meshing time budget was exceeded during the tetrahedral remeshing (%.3g s in it)",
                        name, bs_seconds() - t0);
  }
  out->seconds = bs_seconds() - t0;
  out->collapses_refused = refused_collapses;
  tr_min_dihedral(best, &out->volume);
  return extract(best, out, err);
}

} // namespace

extern "C" int bs_shim_tet_remesh(const char *name, const double *x, int64_t n_vertices, const int32_t *tets,
                                  int64_t n_tets, const int32_t *subdomain, const bs_shim_tet_remesh_opts *opts,
                                  bs_shim_tet_remesh_out *out, bs_error *err) {
  if (!out) return bs_error_set(err, BS_EINPUT, "bs_shim_tet_remesh: NULL output");
  *out = bs_shim_tet_remesh_out{};
  if (!name) name = "mesh";
  int rc;
  try {
    rc = remesh(name, x, n_vertices, tets, n_tets, subdomain, opts, out, err);
  } catch (const std::bad_alloc &) {
    rc = bs_error_set(err, BS_ENOMEM, "%s: out of memory in the tetrahedral remeshing", name);
  } catch (const std::exception &e) {
    rc = bs_error_set(err, BS_EINTERNAL, "%s: CGAL failed in the tetrahedral remeshing: %s", name, e.what());
  } catch (...) {
    rc = bs_error_set(err, BS_EINTERNAL, "%s: CGAL failed in the tetrahedral remeshing (unknown exception)", name);
  }
  if (rc) {
    bs_shim_free(out->x);
    bs_shim_free(out->tets);
    bs_shim_free(out->subdomain);
    *out = bs_shim_tet_remesh_out{};
  }
  return rc;
}
