/* bs_shim.h — CGAL behind a plain C interface (the only C++ in bigstep).
 *
 * In the style of Gmsh's C API: plain C types, (pointer, count) pairs, a
 * try/catch at every entry so that no C++ exception crosses into C, and
 * bs_shim_free for every array the shim allocates.
 *
 * Status: 0 on success, a negative BS_E* code on failure with err filled
 * (the message names the file or the argument at fault).
 */
#ifndef BS_SHIM_H
#define BS_SHIM_H

#include <stdint.h>

#include "bs_base.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Frees an array returned by the shim (NULL is fine). */
void bs_shim_free(void *p);

/* Reads a triangulated surface in any format CGAL reads as a polygon soup
 * (.off, .obj, .ply, .stl); polygons with more than three vertices are
 * triangulated. Returns *n_points points (3 doubles each) and *n_tris
 * triangles (3 indices each), both allocated by the shim. */
int bs_shim_read_surface(const char *path, double **points, int64_t *n_points, int32_t **tris,
                         int64_t *n_tris, bs_error *err);

/* Checks an STL file's layout before another reader (Gmsh) parses it: a
 * binary STL's size must match its triangle count (at most
 * BS_MAX_SURFACE_FACES) and its coordinates be finite; any other file must
 * start with "solid". 0, or BS_EINPUT / BS_EIO naming the file. */
int bs_shim_check_stl(const char *path, bs_error *err);


/* ==========================================================================
 * Geometry (shim_geometry.cpp; helper "shim"): exact predicates, an AABB tree
 * over surface triangles with closest-point and box queries, signed distance
 * to a closed surface, surface self-intersection.
 *
 * Kernel: CGAL::Exact_predicates_inexact_constructions_kernel. Every YES/NO
 * or SIGN answer (orientation, point in tetrahedron, inside/outside, whether
 * two triangles intersect) is exact for the double inputs as given: no
 * tolerance, no round-off. Constructed numbers (closest points, distances,
 * barycentric weights) are computed in double precision, and so is the
 * feature (face, edge, vertex) of a closest point, which follows them.
 *
 * Data: points are 3 doubles each (x[3*i + k]); triangles are 3 int32_t
 * 0-based point indices each; lengths are in the units of the points
 * (metres in bigstep). Coordinates must be finite.
 *
 * Ownership: the tree copies the points and triangles it is given; arrays
 * returned by bs_shim_self_intersections are freed with bs_shim_free.
 *
 * Threads: the tree's query functions (closest, within, signed distance) are
 * read-only and may run concurrently on one tree; bs_shim_tree_update must
 * not run concurrently with anything else on that tree.
 * ========================================================================== */

/* Orientation of the tetrahedron (a, b, c, d): the exact sign of
 *     det[b - a, c - a, d - a] = ((b - a) x (c - a)) . (d - a),
 * i.e. +1 when d lies on the side of the plane (a, b, c) into which the
 * normal (b - a) x (c - a) points (a, b, c counterclockwise seen from d; a
 * tet of positive volume in bs_mesh's convention), 0 when the four points
 * are coplanar, -1 otherwise. This is CGAL::orientation(a, b, c, d); it is
 * the OPPOSITE sign of Shewchuk's orient3d. Returns BS_EINPUT (< -1) when an
 * argument is NULL or a coordinate is not finite. */
int bs_shim_orient3d(const double a[3], const double b[3], const double c[3], const double d[3]);

/* Exact position of p with respect to the closed tetrahedron (a, b, c, d),
 * of either orientation: 1 strictly inside, 0 on its boundary (a face, an
 * edge or a vertex), -1 outside. A flat tetrahedron (four coplanar points)
 * has no interior: 0 when p lies in the convex hull of the four points, -1
 * otherwise. Returns BS_EINPUT (< -1) for a NULL argument or a non-finite
 * coordinate. */
int bs_shim_point_in_tet(const double p[3], const double a[3], const double b[3], const double c[3],
                         const double d[3]);

/* Bounding-volume hierarchy (CGAL::AABB_tree) over the triangles of a
 * surface; each primitive holds its triangle index. */
typedef struct bs_shim_tree bs_shim_tree;

/* Builds the tree over n_tris >= 1 triangles of n_points points (both
 * copied). Errors: BS_EINPUT for NULL arrays, counts out of range, or a
 * triangle whose index is outside [0, n_points) (the message names the
 * triangle); BS_ENUMERIC for a non-finite coordinate (names the point).
 * Degenerate (zero-area) triangles are allowed. */
int bs_shim_tree_create(const double *points, int64_t n_points, const int32_t *tris, int64_t n_tris,
                        bs_shim_tree **out, bs_error *err);

/* Destroys the tree (NULL or *t == NULL is fine) and sets *t = NULL. */
void bs_shim_tree_destroy(bs_shim_tree **t);

/* New positions for the same points (3 * n_points doubles, the connectivity
 * is kept), then a rebuild of the hierarchy. It reuses the tree's storage
 * (no allocation) and does not build CGAL's k-d tree of reference points,
 * which the queries below do not need: O(n log n) time. On error
 * (BS_EINPUT: NULL; BS_ENUMERIC: a non-finite coordinate, named) the tree
 * keeps its previous positions. */
int bs_shim_tree_update(bs_shim_tree *t, const double *points, bs_error *err);

/* Features of a triangle (v0, v1, v2) reported by the closest-point queries:
 * 0 its interior; 1 edge v0v1, 2 edge v1v2, 3 edge v2v0 (the closest point
 * is in the edge's relative interior); 4, 5, 6 vertex v0, v1, v2. These are
 * the triangle's own edges and vertices, creased on the surface or not. */
enum {
  BS_SHIM_FACE = 0,
  BS_SHIM_EDGE01 = 1,
  BS_SHIM_EDGE12 = 2,
  BS_SHIM_EDGE20 = 3,
  BS_SHIM_VERTEX0 = 4,
  BS_SHIM_VERTEX1 = 5,
  BS_SHIM_VERTEX2 = 6
};

/* Closest point of the surface to q: out_point (3), its triangle, the
 * barycentric weights of out_point in that triangle (bary[k] for vertex k,
 * summing to 1, exactly 0 for the vertices off the feature) and the feature
 * (above). When several triangles are equally close, one of them is
 * returned. Every output may be NULL when not wanted. The search visits the
 * nearer child box first and prunes boxes farther than the best so far.
 * Returns BS_OK, or BS_EINPUT for a NULL t or q or a non-finite q. */
int bs_shim_tree_closest(const bs_shim_tree *t, const double q[3], double out_point[3], int32_t *out_tri,
                         double bary[3], int *feature);

/* The same, starting the search from triangle `hint` (e.g. the triangle the
 * point was closest to at the previous iteration), which tightens the search
 * radius from the start (as CGAL's closest_point(query, hint) does). The result is
 * the same as without a hint, up to ties. hint < 0 means no hint; a hint >=
 * the number of triangles is BS_EINPUT. Neither search builds or uses
 * CGAL's k-d tree of reference points. */
int bs_shim_tree_closest_hint(const bs_shim_tree *t, const double q[3], int32_t hint, double out_point[3],
                              int32_t *out_tri, double bary[3], int *feature);

/* Triangles whose axis-aligned bounding boxes intersect the closed box
 * [lo, hi] (touching counts), in no particular order. Up to cap indices are
 * written to out (out may be NULL when cap is 0); *count receives the TOTAL
 * number found, which may exceed cap: then only the first cap were written
 * and the caller should retry with a buffer of *count entries. A box with
 * lo > hi on some axis is empty (count 0). No allocation. Returns BS_OK, or
 * BS_EINPUT for NULL t, lo, hi or count, a NULL out with cap > 0, a
 * negative cap, or a NaN bound. */
int bs_shim_tree_within(const bs_shim_tree *t, const double lo[3], const double hi[3], int32_t *out, int64_t cap,
                        int64_t *count);

/* Signed distance from each of the n points q (3 n doubles) to the surface
 * of the tree, which must be closed (watertight; its triangles' orientation
 * does not matter): out[i] = -d inside, +d outside, 0 on the surface, with d
 * the Euclidean distance to the closest point (as bs_shim_tree_closest).
 * Inside/outside is decided exactly by ray parity, as CGAL's
 * Side_of_triangle_mesh does: a ray from the point crosses the surface an
 * odd number of times iff the point is inside; a ray that meets an edge or a
 * vertex, or lies in a triangle's plane, is discarded and another
 * direction drawn (deterministic sequence). For a surface that is not closed
 * the sign is meaningless. Errors: BS_EINPUT (NULL arguments, n < 0, a
 * non-finite point, named); BS_ENUMERIC when no conclusive ray is found for
 * a point (names it). */
int bs_shim_signed_distance(const bs_shim_tree *t, const double *q, int64_t n, double *out, bs_error *err);

/* Pairs of triangles of the surface that intersect, found with CGAL's
 * box_intersection_d and decided by exact predicates (CGAL::do_intersect on
 * triangles and segments). Triangles are closed sets (touching counts), with
 * this rule for triangles that share vertices (by index), as in CGAL's
 * Polygon_mesh_processing::self_intersections:
 *   - sharing one vertex: adjacency; they intersect only if, in one of
 *     them, the edge opposite the shared vertex meets the other triangle
 *     (then they overlap beyond that vertex);
 *   - sharing an edge: adjacency; they intersect only if they are coplanar
 *     and lie on the same side of the edge (a fold that overlaps);
 *   - sharing three vertices (a duplicated triangle): they intersect.
 * A degenerate triangle (collinear vertices, exact test, including repeated
 * indices) is reported once as the pair (i, i) and not tested against
 * others. *pairs receives 2 * *n_pairs indices (i < j within a pair, pairs
 * sorted), allocated by the shim (free with bs_shim_free; NULL when there
 * are none). The box search runs in slabs (a number set by n_tris alone) on
 * the caller's OpenMP threads; the pairs do not depend on the thread count.
 * Errors: BS_EINPUT for NULL arrays with positive counts, negative counts, or
 * an index outside [0, n_points) (names the triangle); BS_ENUMERIC for a
 * non-finite coordinate (names the point); BS_ENOMEM. */
int bs_shim_self_intersections(const double *points, int64_t n_points, const int32_t *tris, int64_t n_tris,
                               int32_t **pairs, int64_t *n_pairs, bs_error *err);

/* The number of those pairs, the search stopping once cap > 0 pairs are found
 * (then *count = cap and *truncated = 1; cap = 0: no limit). For audits of
 * states that may be tangled (a random 65^3 cube: ~1e9 overlapping boxes),
 * where the exact count would take hours and "at least cap" says enough.
 * Errors as bs_shim_self_intersections, and BS_EINPUT for cap < 0 or NULL
 * outputs. */
int bs_shim_count_self_intersections(const double *points, int64_t n_points, const int32_t *tris, int64_t n_tris,
                                     int64_t cap, int64_t *count, int *truncated, bs_error *err);

/* ==========================================================================
 * Surface repair (shim_repair.cpp; helper "repair"): a triangle soup that
 * is not clean (duplicates, zero-area triangles, holes, self-intersections)
 * made into a closed, outward, self-intersection-free surface, with CGAL's
 * Polygon_mesh_processing. The steps, in order:
 *   1. soup: points at bitwise-equal positions merged; triangles with a
 *      repeated vertex dropped (degenerate); copies of a triangle (the same
 *      three vertices, either orientation) dropped; unused points dropped;
 *      orientation made consistent (orient_polygon_soup, which duplicates
 *      the points where the surface is not manifold);
 *   2. zero-area (collinear) triangles removed by edge collapses and flips
 *      (remove_degenerate_faces);
 *   3. holes (boundary loops): with close_holes, every loop whose diameter
 *      (largest distance between two of its points) is at most max_hole
 *      times the bounding-box diagonal is triangulated and refined
 *      (triangulate_and_refine_hole: a membrane across the hole) and
 *      kept so; the report gives the fills' area, their volume beyond flat
 *      caps over the holes, and the volume the same fills would enclose
 *      more if faired (PMP::fair: meeting the surface with a continuous
 *      tangent plane), which the surface returned does not contain; an open
 *      surface is refused otherwise;
 *   4. self-intersections: first autorefine_and_remove_self_intersections
 *      (exact intersection curves, keeps the outer hull), kept only if the
 *      result is closed, free of intersections and encloses 50% to 105% of
 *      the volume before (it misreads folded regions of some scans and then
 *      keeps almost nothing); else remove_self_intersections (local
 *      smoothing and re-filling of the intersecting regions), followed by the
 *      autorefinement again for what it left; after the local removal, the
 *      folds it leaves (two neighbouring triangles at a dihedral angle below
 *      BS_SURFACE_FOLD_DEGREES, which Gmsh takes for overlapping facets) are
 *      cut out with the ring of triangles around them and re-filled;
 *   5. oriented to bound a volume (normals outward: positive enclosed volume).
 * Lengths are in the units of the points; volumes in those units cubed.
 * ========================================================================== */

/* The largest hole closed by default, as a fraction of the bbox diagonal. */
#define BS_SURFACE_MAX_HOLE_DEFAULT 0.2
/* A fold: neighbouring triangles at a dihedral angle below this (degrees). */
#define BS_SURFACE_FOLD_DEGREES 3.0

typedef struct bs_surface_repair_opts {
  int close_holes;   /* 1: close holes up to max_hole (0: an open surface is refused) */
  double max_hole;   /* fraction of the bounding-box diagonal; <= 0: BS_SURFACE_MAX_HOLE_DEFAULT */
} bs_surface_repair_opts;

typedef struct bs_surface_report {
  int64_t points_in, tris_in;    /* as given                                     */
  int64_t points_out, tris_out;  /* the clean surface                            */
  int64_t duplicate_points;      /* merged into an earlier point at the same position */
  int64_t duplicate_tris;        /* copies of another triangle, dropped          */
  int64_t degenerate_tris;       /* zero-area triangles (repeated vertex or collinear), removed */
  int64_t split_points;          /* points duplicated to make the surface manifold */
  int holes;                     /* boundary loops found (after steps 1-2)       */
  int holes_closed;              /* of them, closed                              */
  int holes_fair_estimated;      /* of the closed, those counted in
                                    hole_fair_volume (their fairing solve succeeded;
                                    a fill with no inner vertex has nothing to fair) */
  int64_t hole_tris;             /* triangles added to close them                */
  double hole_max_diameter;      /* the largest diameter and the largest         */
  double hole_max_perimeter;     /* perimeter of the closed holes (0: none)      */
  double hole_area;              /* the fills' area (units^2)                    */
  double hole_cap_volume;        /* the volume between the fills and the fans from
                                    each loop's centroid to its edges, > 0 where the
                                    fills bulge outward (units^3; about 0 for a
                                    membrane over a flat hole)                   */
  double hole_fair_volume;       /* what faired fills would enclose beyond the fills
                                    kept, > 0 outward (units^3; compare with volume):
                                    the volume the closing may have left out     */
  int64_t self_intersections;    /* pairs of intersecting triangles found        */
  int self_intersection_fix;     /* 0 none needed, 1 autorefinement, 2 local removal,
                                    3 local removal then autorefinement          */
  int64_t fold_tris;             /* triangles cut out around folds and re-filled */
  double volume_before;          /* enclosed (signed) before step 4, 0 if open   */
  double volume;                 /* enclosed by the clean surface (> 0)          */
  double area;                   /* of the clean surface (units^2)               */
  double bbox_diagonal;          /* of the input points                          */
  int open_refused;              /* 1: refused as an open surface (holes not closed on
                                    request, or larger than max_hole)           */
  /* Filled by bigstep's callers (mesh/surface_wrap.c), not by the repair:    */
  int wrapped;                   /* 1: the repair could not make the surface clean and
                                    its alpha wrap replaced it; 2: the meshes of the
                                    clean surface were refused and its wrap was meshed */
  double wrap_alpha, wrap_offset;/* the wrap's parameters (bs_shim_alpha_wrap)    */
  double wrap_volume_change;     /* (V_wrap - V_in) / V_in, V_in the input's volume */
  double wrap_seconds;           /* the wrap's wall time                          */
  int lifted;                    /* tetrahedral remeshing runs (mesh/tet_lift.c) on
                                    meshes under the gate or with flat tets      */
  double lift_dihedral_in;       /* the last one's smallest dihedral angle before */
  double lift_dihedral;          /* ... and after (degrees)                        */
  double lift_seconds;           /* their wall time in all                         */
  int from_boundary;             /* 1: a geometry's Gmsh mesh missed the gate, the
                                    lift could not take it, and its boundary was
                                    meshed again by the surface path
                                    (mesh/cad_surface.c)                          */
  double from_boundary_dihedral_in; /* the Gmsh mesh's smallest dihedral (degrees) */
  double from_boundary_volume_change; /* (V_new - V_gmsh) / V_gmsh              */
} bs_surface_report;

/* Repairs the surface (points, n_points; tris, n_tris: see Data above) into
 * a new soup (*points_out, *tris_out, allocated by the shim: free with
 * bs_shim_free) that is closed (every edge in exactly two triangles),
 * consistently oriented outward, with no zero-area triangle and no two
 * triangles intersecting (bs_shim_self_intersections finds none). opts may
 * be NULL (no hole closed). report (may be NULL) gets the counts; it is filled
 * as far as the repair went when it fails. Errors (the message says what and
 * where, not the file: the caller adds it):
 *   BS_EINPUT  an index out of range or a non-finite coordinate; an open
 *              surface without close_holes, or with a hole larger than
 *              max_hole (the message gives the number of loops and the
 *              largest one's diameter, perimeter, edges and centre); self-
 *              intersections that neither method removes (count and a place);
 *              nothing left (everything degenerate) or no enclosed volume;
 *   BS_ENOMEM; BS_EINTERNAL when CGAL fails in an unexpected way. */
int bs_shim_repair_surface(const double *points, int64_t n_points, const int32_t *tris, int64_t n_tris,
                           const bs_surface_repair_opts *opts, double **points_out, int64_t *n_points_out,
                           int32_t **tris_out, int64_t *n_tris_out, bs_surface_report *report, bs_error *err);

/* ==========================================================================
 * Volume meshing of closed surfaces (shim_mesh3.cpp, shim_surface_mesh.cpp)
 * and surface measures (shim_distance.cpp): CGAL's Mesh_3 and its mesh
 * optimisers; the sampled distance between two surfaces; sharp edges.
 *
 * Data as above: points 3 doubles each, triangles 3 int32_t 0-based indices
 * each, lengths in the points' units (metres). Arrays returned are
 * allocated by the shim and freed with bs_shim_free.
 * ========================================================================== */

/* Sharp edges are protected (Mesh_3, the surface remesher) only when no two
 * of them leave a vertex at less than this angle (degrees): Mesh_3 protects
 * a sharp edge with balls that must not meet the balls of another sharp
 * edge, so at distance r from a corner of angle a they are about r a
 * across, and the corner costs about 1 / a balls per e-fold of r (mpi.off,
 * a corner of 7e-5 degrees from non-planar polygons: millions of balls,
 * 528 s past a 20 s budget, inside the one stage CGAL checks no stop flag
 * in). A surface with such a corner is meshed as a smooth one. */
#define BS_SHIM_FEATURE_MIN_CORNER 1.0

/* Smoothing after Mesh_3's refinement (CGAL::odt_optimize_mesh_3 or
 * CGAL::lloyd_optimize_mesh_3), or none. */
enum { BS_SHIM_SMOOTH_NONE = 0, BS_SHIM_SMOOTH_ODT = 1, BS_SHIM_SMOOTH_LLOYD = 2 };

/* The most tets bs_shim_mesh_surface returns (int32 indices, 4 per tet). */
#define BS_SHIM_MAX_TETS (INT32_MAX / 8)

typedef struct bs_shim_mesh3_opts {
  double size;            /* target size h (> 0): Mesh_3's edge_size, facet_size and cell_size */
  double facet_distance;  /* surface approximation bound; <= 0: h / 10                   */
  double facet_size;      /* boundary triangles' and sharp edges' size; <= 0: h          */
  double feature_angle;   /* degrees: edges whose faces meet at a dihedral angle further
                             than this from flat are protected (detect_features);
                             <= 0: no features. They are kept only when the surface
                             is CAD-like: chains of such edges at least
                             feature_min_length long make >= 80% of their length (a
                             scan's creases are many short chains, which Mesh_3 would
                             protect with tiny balls and slivers; they are ignored) and
                             no two meet at less than BS_SHIM_FEATURE_MIN_CORNER        */
  double feature_min_length; /* <= 0: 2 h                                                */
  int smoother;           /* BS_SHIM_SMOOTH_*                                            */
  int smooth_iterations;  /* iterations of the smoother (0: none)                       */
  int perturb, exude;     /* 1: sliver perturbation / exudation after smoothing         */
  double target_dihedral; /* degrees: the perturber's and exuder's sliver bound         */
  int max_rounds;         /* perturb + exude rounds while below target and improving (>= 1) */
  /* A surface that is not CAD-like (a scan: meshed without features) has
     its own criteria: its thin parts and curved regions lose volume at
     facet distance h / 10 and radius-edge 3. All zero: as a CAD part. */
  double scan_facet_distance; /* <= 0: facet_distance                                   */
  double scan_facet_angle;    /* degrees, boundary triangles' smallest-angle bound; <= 0: 25 */
  double scan_radius_edge;    /* cells' circumradius / shortest-edge bound; <= 0: 3 */
  double thickness_elements;  /* > 0: a local size from the scan's thickness t (inward along
                                 the normal to the opposite side): cell, facet and edge size
                                 min(h, max(min_size, t / this)), graded; <= 0: h everywhere */
  double size_gradation;      /* the local size grows at most this much per unit length
                                 away from thin parts; <= 0: 0.5                         */
  double min_size;            /* the local size's floor; <= 0: h / 8                     */
  double deadline;            /* > 0: a bs_seconds() time: Mesh_3's refinement is stopped
                                 there (a watchdog thread sets its stop flag), the
                                 optimisers get the time left as their time_limit, and past
                                 it the mesh is refused (BS_EINPUT "the meshing time budget
                                 was exceeded during Mesh_3"); <= 0: none. Not stoppable:
                                 building the domain's search tree, detecting its sharp
                                 edges and the thickness field (before the refinement)     */
} bs_shim_mesh3_opts;

typedef struct bs_shim_mesh3_out {
  double *x;              /* 3 * n_vertices                                              */
  int64_t n_vertices;
  int32_t *tets;          /* 4 * n_tets, CGAL::orientation(p0, p1, p2, p3) > 0 (positive
                             volume in bs_mesh's convention, see bs_shim_orient3d)      */
  int64_t n_tets;
  double refined_dihedral;/* smallest dihedral angle (degrees) after refinement         */
  double dihedral;        /* ... after the optimisers                                    */
  int64_t n_features;     /* sharp-edge chains kept (0: meshed as a smooth surface)      */
  double local_size_min;  /* the local size's smallest value on the surface (h without it) */
  double local_fraction;  /* fraction of the surface samples where it is under h        */
  int64_t n_filled;       /* cells outside Mesh_3's complex added to it so that its
                             boundary is a closed 2-manifold (see bs_shim_mesh_surface) */
} bs_shim_mesh3_out;

/* The most cells filled at once by bs_shim_mesh_surface's manifold repair
 * (a wedge; a cavity of a surface in several pieces). */
#define BS_SHIM_MESH3_FILL_CELLS 16

/* Meshes the volume inside the closed surface (points, tris) at opts->size
 * with CGAL's Mesh_3 on a Polyhedral_mesh_domain_with_features_3, its
 * features detected (detect_features) when the surface is CAD-like: criteria
 * edge_size = facet_size = cell_size = h, facet_angle 25 degrees,
 * facet_distance, cell_radius_edge_ratio 3 (a scan: the scan_* criteria and
 * the thickness size field when asked); then the optimisers of opts; then
 * the complex is made a closed 2-manifold: outside cells enclosed by it (a
 * cavity Mesh_3 leaves where a flat cell under a curved surface has its
 * circumcentre outside: of any size when the surface is in one piece, which
 * encloses no void, else of at most BS_SHIM_MESH3_FILL_CELLS cells), and
 * the smaller outside wedges (at most that many cells) around an edge or a
 * vertex where two parts of the body touch, are added to it
 * (out->n_filled).
 * Sequential and seeded: the same input gives the same mesh. The surface
 * must be an orientable, closed 2-manifold without self-intersections (an
 * inconsistently oriented soup is oriented first). `name` (the file) starts
 * every message.
 * It runs in a child process (bs_run_in_child, bs_child.h), which sends the
 * mesh back: a crash inside CGAL ends the child, and the call returns
 * BS_EINPUT "NAME: CGAL Mesh_3 crashed (signal 11, Segmentation fault) and
 * sent no result" (CGAL 5.5's ODT smoother crashes in
 * C3T3_helpers::move_point_topo_change on the corpus's cheese.off at 1/50
 * of its diagonal, sharp edges protected; CGAL's pull request 9541, after
 * 5.5, stops its global optimisers from hiding points, a likely cause).
 * Its memory is the child's (bs_peak_rss counts the largest child).
 * Errors: BS_EINPUT (empty, an index out of range, a
 * triangle repeating a vertex, non-manifold, not closed: the count of hole
 * edges, self-intersecting, size <= 0, CGAL's failure with its text, a crash
 * inside CGAL),
 * BS_ENUMERIC (a non-finite point), BS_ENOMEM (also: no child process could
 * be started). On success *out holds the arrays (free x and tets with
 * bs_shim_free); on error it is zeroed.
 * Example:
 *   bs_shim_mesh3_opts o = {.size = 0.01, .feature_angle = 60, .smoother = BS_SHIM_SMOOTH_ODT,
 *                           .smooth_iterations = 10, .perturb = 1, .exude = 1, .target_dihedral = 10,
 *                           .max_rounds = 3};
 *   bs_shim_mesh3_out r;
 *   if (!bs_shim_mesh_surface("part.off", x, nx, t, nt, &o, &r, &err)) { ...; bs_shim_free(r.x); bs_shim_free(r.tets); } */
int bs_shim_mesh_surface(const char *name, const double *points, int64_t n_points, const int32_t *tris,
                         int64_t n_tris, const bs_shim_mesh3_opts *opts, bs_shim_mesh3_out *out, bs_error *err);

/* One-sided distance from surface A to surface B: the largest distance from
 * the points of a barycentric grid on every triangle of A (about `spacing`
 * apart, the vertices included) to B's closest point (CGAL AABB tree). The
 * Hausdorff distance is the larger of the two directions; the sampling
 * underestimates it by at most about spacing / 2. where (may be NULL)
 * receives the sample that is farthest. Errors: BS_EINPUT (NULL, empty,
 * index out of range, spacing <= 0), BS_ENUMERIC, BS_ENOMEM. */
int bs_shim_surface_distance(const double *pa, int64_t na, const int32_t *ta, int64_t nta, const double *pb,
                             int64_t nb, const int32_t *tb, int64_t ntb, double spacing, double *max_dist,
                             double where[3], bs_error *err);

/* Sharp edges of a closed surface (as bs_shim_mesh_surface requires): edges
 * whose two faces' normals differ by more than `angle` degrees
 * (CGAL::Polygon_mesh_processing::detect_sharp_edges). *segments receives 6
 * doubles (both end points) per edge, *n_edges of them. */
int bs_shim_sharp_edges(const double *points, int64_t n_points, const int32_t *tris, int64_t n_tris, double angle,
                        double **segments, int64_t *n_edges, bs_error *err);

/* ==========================================================================
 * Isotropic surface remeshing (shim_remesh.cpp, shim_features.cpp): a closed
 * surface's triangles replaced by near-equilateral ones of a target edge
 * length, the first step of the "remesh" volume mesher (mesh/surface_remesh.c
 * hands the result to Gmsh as a discrete surface).
 * ========================================================================== */

typedef struct bs_shim_remesh_opts {
  double size;            /* target edge length h (> 0), in the points' units            */
  double feature_angle;   /* degrees: sharp edges (faces turning by more than this) are
                             kept when the surface is CAD-like (as
                             bs_shim_mesh3_opts.feature_angle): remeshed only along
                             their chains, never flipped; <= 0: none                    */
  double feature_min_length; /* <= 0: 2 h (see bs_shim_mesh3_opts)                      */
  int iterations;         /* isotropic_remeshing iterations; <= 0: 3                    */
} bs_shim_remesh_opts;

typedef struct bs_shim_remesh_out {
  double *points;         /* 3 * n_points (free with bs_shim_free)                       */
  int64_t n_points;
  int32_t *tris;          /* 3 * n_tris, 0-based, outward (counter-clockwise seen from
                             outside), a closed 2-manifold (free with bs_shim_free)     */
  int64_t n_tris;
  int64_t n_features;     /* sharp-edge chains protected (0: remeshed as a smooth surface) */
} bs_shim_remesh_out;

/* Remeshes the closed surface (points, tris; the same requirements as
 * bs_shim_mesh_surface: orientable, closed, 2-manifold, no
 * self-intersection) with CGAL::Polygon_mesh_processing::isotropic_remeshing
 * at edge length opts->size for opts->iterations iterations, its vertices
 * projected back onto the input; the sharp edges of a CAD-like surface are
 * protected. Deterministic and sequential. Errors (the message starts with
 * `name`): BS_EINPUT (the input refusals of bs_shim_mesh_surface; size <= 0;
 * the remeshed surface intersects itself, which happens where the part is
 * thinner than about h; CGAL's failure with its text), BS_ENUMERIC,
 * BS_ENOMEM. On error *out is zeroed.
 * Example:
 *   bs_shim_remesh_opts o = {.size = 1.0, .feature_angle = 60, .iterations = 3};
 *   bs_shim_remesh_out r;
 *   if (!bs_shim_remesh_surface("scan.off", x, nx, t, nt, &o, &r, &err)) {
 *     ...; bs_shim_free(r.points); bs_shim_free(r.tris); } */
int bs_shim_remesh_surface(const char *name, const double *points, int64_t n_points, const int32_t *tris,
                           int64_t n_tris, const bs_shim_remesh_opts *opts, bs_shim_remesh_out *out, bs_error *err);

/* ==========================================================================
 * Alpha wrapping (shim_wrap.cpp): any triangle soup (non-manifold edges,
 * overlapping or nearly overlapping facets, small holes, several touching
 * parts) made into a closed, 2-manifold, self-intersection-free, outward
 * surface by construction (CGAL::alpha_wrap_3, CGAL 5.5), and the audit of
 * a surface with CGAL's Polygon_mesh_processing.
 *
 * The rule for a target element size h: alpha = BS_WRAP_ALPHA h (a ball of
 * radius alpha carves the space from outside: cavities, gaps and holes
 * narrower than about 2 alpha = h are closed, which at element size h
 * cannot be meshed apart anyway; the wrap's triangles are about alpha long)
 * and offset = BS_WRAP_OFFSET h (the wrap lies at that distance outside
 * the input). The volume grows by about offset x area(input) (the offset's
 * share: 6 h / 100 of a unit cube at h), plus the concave corners and gaps
 * the ball cannot enter (about (1 - pi/4) alpha^2 per unit length of a
 * right-angled concave edge); callers accept a wrap when
 * |V_wrap - V_in| <= 2 offset area + BS_WRAP_VOLUME_TOL V_in (the volume
 * check).
 * ========================================================================== */
#define BS_WRAP_ALPHA 0.5
#define BS_WRAP_OFFSET 0.01
#define BS_WRAP_VOLUME_TOL 0.02

typedef struct bs_shim_wrap_opts {
  double size;     /* target element size h (> 0), in the points' units            */
  double alpha;    /* > 0: this alpha instead of BS_WRAP_ALPHA h                     */
  double offset;   /* > 0: this offset instead of BS_WRAP_OFFSET h                   */
  double deadline; /* > 0: a bs_seconds() time past which the wrap stops (BS_EINPUT
                      naming the budget); <= 0: none                                */
} bs_shim_wrap_opts;

typedef struct bs_shim_wrap_out {
  double *points;  /* 3 * n_points (free with bs_shim_free)                          */
  int64_t n_points;
  int32_t *tris;   /* 3 * n_tris, outward, closed 2-manifold (bs_shim_free)          */
  int64_t n_tris;
  double alpha, offset; /* as used                                                   */
  double volume_in;/* |volume| enclosed by the input once consistently oriented
                      (exact for a closed orientable input, an estimate otherwise) */
  int input_closed;/* 1: the input, once oriented, is closed (every edge in exactly two
                      triangles): volume_in is its enclosed volume                   */
  double area_in;  /* the input's area                                               */
  double volume;   /* enclosed by the wrap (> 0)                                     */
  double seconds;  /* the wrap's wall time                                           */
} bs_shim_wrap_out;

/* Wraps the soup (points, tris: any triangles; degenerate ones are ignored)
 * at opts (see the rule above) and audits the result (closed, 2-manifold,
 * no self-intersection: else BS_EINTERNAL). `name` starts every message.
 * Deterministic and sequential. Errors: BS_EINPUT (empty, an index out of
 * range, size <= 0, the deadline passed: "the meshing time budget was
 * exceeded during the alpha wrap"), BS_ENUMERIC (a non-finite point),
 * BS_ENOMEM, BS_EINTERNAL. On error *out is zeroed except alpha and offset.
 * Example:
 *   bs_shim_wrap_opts o = {.size = 0.01};
 *   bs_shim_wrap_out w;
 *   if (!bs_shim_alpha_wrap("part.stl", x, nx, t, nt, &o, &w, &err)) {
 *     ...; bs_shim_free(w.points); bs_shim_free(w.tris); } */
int bs_shim_alpha_wrap(const char *name, const double *points, int64_t n_points, const int32_t *tris,
                       int64_t n_tris, const bs_shim_wrap_opts *opts, bs_shim_wrap_out *out, bs_error *err);

typedef struct bs_shim_surface_audit_out {
  int manifold;            /* an orientable 2-manifold (edges in at most 2 triangles,
                              vertices with one fan: is_polygon_soup_a_polygon_mesh) */
  int closed;              /* manifold and no border edge                           */
  int self_intersecting;   /* manifold and PMP::does_self_intersect                  */
  int64_t border_edges;    /* manifold: edges in one triangle only                   */
  int64_t components;      /* manifold: connected components                         */
  double volume;           /* closed: the enclosed signed volume (PMP::volume)       */
} bs_shim_surface_audit_out;

/* Audits the soup with CGAL's Polygon_mesh_processing (fields above; those
 * that need a manifold are 0 when it is not). Errors: BS_EINPUT (empty, an
 * index out of range), BS_ENUMERIC, BS_ENOMEM, BS_EINTERNAL. */
int bs_shim_surface_audit(const double *points, int64_t n_points, const int32_t *tris, int64_t n_tris,
                          bs_shim_surface_audit_out *out, bs_error *err);

/* ==========================================================================
 * Tetrahedral remeshing (shim_tet_remesh.cpp): a tet mesh that misses the
 * quality gate (slivers, flat or zero-volume tets) lifted by CGAL's
 * tetrahedral_isotropic_remeshing (CGAL 5.5: edge splits, collapses, flips,
 * smoothing) at a target edge length, its boundary kept.
 * ========================================================================== */

enum {
  BS_SHIM_TET_PROTECT_BOUNDARY = 0, /* every boundary triangle kept as it is              */
  BS_SHIM_TET_PROTECT_FEATURES = 1  /* the boundary remeshed too (topology kept, vertices
                                       re-projected onto it), its sharp edges constrained  */
};

typedef struct bs_shim_tet_remesh_opts {
  double size;            /* target edge length (> 0), in the points' units            */
  int protect;            /* BS_SHIM_TET_PROTECT_*                                      */
  double feature_angle;   /* FEATURES: boundary edges whose faces' normals differ by more
                             than this (degrees) are sharp; <= 0: 60                     */
  double target_dihedral; /* degrees: stop once every tet's smallest dihedral angle is at
                             least this                                                 */
  int iterations;         /* at most this many remeshing rounds; <= 0: 8                */
  double deadline;        /* > 0: a bs_seconds() time past which it stops (BS_EINPUT
                             naming the budget); <= 0: none                             */
} bs_shim_tet_remesh_opts;

typedef struct bs_shim_tet_remesh_out {
  double *x;              /* 3 * n_vertices (free with bs_shim_free)                    */
  int64_t n_vertices;
  int32_t *tets;          /* 4 * n_tets, CGAL::orientation > 0 (bs_shim_free)           */
  int64_t n_tets;
  int32_t *subdomain;     /* n_tets: each tet's subdomain (as given; bs_shim_free)      */
  double dihedral_in;     /* smallest dihedral angle (degrees) of the input             */
  double dihedral;        /* ... of the output (the best round)                         */
  double volume_in, volume; /* total tet volume before and after                        */
  int rounds;             /* remeshing rounds run                                       */
  double seconds;         /* wall time of the rounds                                    */
  int64_t collapses_refused; /* edge collapses refused because the cells around the edge's
                             two vertices do not make a valid triangulation (they touch
                             only at a vertex: thin parts); CGAL 5.5 itself crashed on
                             them (shim_tet_remesh.cpp)                                 */
} bs_shim_tet_remesh_out;

/* Remeshes the tets (4 int32_t 0-based vertex indices each, any orientation,
 * zero-volume ones allowed) of the vertices x (3 doubles each), each in the
 * subdomain subdomain[t] >= 1 (NULL: all 1; the faces between subdomains are
 * kept as boundaries are, and every output tet gets its subdomain) with
 * CGAL::tetrahedral_isotropic_remeshing at opts->size, one iteration per
 * round, until the smallest dihedral angle reaches opts->target_dihedral,
 * opts->iterations rounds have run, or two rounds in a row have not raised
 * it; the round with the largest smallest
 * angle is returned (the input itself when none improves it). Deterministic;
 * sequential. `name` starts every message. Errors: BS_EINPUT (empty, an
 * index out of range, size <= 0, tets that are not a valid triangulation: a
 * face in three tets, a pinched boundary; the deadline passed: "the meshing
 * time budget was exceeded during the tetrahedral remeshing"), BS_ENUMERIC,
 * BS_ENOMEM, BS_EINTERNAL. On error *out is zeroed.
 * Example:
 *   bs_shim_tet_remesh_opts o = {.size = h, .target_dihedral = 10};
 *   bs_shim_tet_remesh_out r;
 *   if (!bs_shim_tet_remesh("part", x, nv, tets, nt, &o, &r, &err)) {
 *     ...; bs_shim_free(r.x); bs_shim_free(r.tets); } */
int bs_shim_tet_remesh(const char *name, const double *x, int64_t n_vertices, const int32_t *tets, int64_t n_tets,
                       const int32_t *subdomain, const bs_shim_tet_remesh_opts *opts, bs_shim_tet_remesh_out *out,
                       bs_error *err);

#ifdef __cplusplus
}
#endif
#endif
