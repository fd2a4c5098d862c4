/* mesh_internal.h — helpers shared by the files of mesh/ (not public API).
 *
 * Ownership: a bs_group array is one malloc'ed block of n groups, each owning
 * its name, elems and vertices (all malloc'ed). bs__groups_free releases the
 * lot; bs__groups_copy makes an independent deep copy.
 *
 * Status: functions return BS_OK or a negative BS_E* code and fill err.
 */
#ifndef BS_MESH_INTERNAL_H
#define BS_MESH_INTERNAL_H

#include <stdint.h>

#include "bs_mesh.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Number of int32 entries per element of a group of dimension dim:
 * dim + 1 vertex indices for dim < 3, one tet index for dim 3. */
static inline int bs__group_elem_size(int dim) { return dim < 3 ? dim + 1 : 1; }

/* Frees every group's name, elems and vertices, then the array (g may be NULL). */
void bs__groups_free(bs_group *g, int n);

/* Refuses a Gmsh script (.geo) that runs programs, unless the process allows
 * them (geo_guard.c has the rule). BS_EINPUT naming the file and line. */
int bs__geo_check(const char *path, bs_error *err);

/* mesh_limits.c: BS_EINPUT (the message starts with `what`) when n_tets
 * refined `refine` times, or a Gmsh mesh of `volume` (m^3) at `size` (m),
 * would make more tets than bs_mesh_max_tets(opts). */
int bs__check_refined_count(double n_tets, int refine, const bs_mesh_read_opts *opts, const char *what,
                            bs_error *err);
int bs__check_mesh_size(double volume, double size, const bs_mesh_read_opts *opts, const char *what, bs_error *err);

/* Inside a Gmsh session (gmsh_io.c): records "<path>: Gmsh could not <what>:
 * <Gmsh's last error>" with code and returns it. */
int bs__gmsh_fail(bs_error *err, int code, const char *path, const char *what);

/* Inside a Gmsh session, after a CAD file (STEP, IGES, BREP) is opened: an
 * assembly of several solids with no physical groups is fragmented into a
 * conformal model with one named 3-D group per part (cad_assembly.c has the
 * rules), and *assembly = 1; size <= 0 (the file's size) also turns on
 * curvature sizing. A model of one solid is left alone (*assembly = 0).
 * BS_OK, or BS_EGMSH / BS_ENOMEM naming path. */
int bs__cad_assembly(const char *path, double size, int *assembly, bs_error *err);

/* Inside a Gmsh session whose assembly (bs__cad_assembly, at the file's own
 * size) is meshed: meshes it again whole with Mesh.MeshSizeMax lowered to
 * a fraction of the bounding-box diagonal (cad_assembly.c has it), and sets
 * *done = 1; *done = 0 and the mesh untouched when the sizes are bounded
 * that tightly already. BS_OK, or BS_EGMSH naming path. */
int bs__cad_assembly_finer(const char *path, int *done, bs_error *err);

/* Deep copy of n groups into a new array *out (NULL when n == 0). A NULL
 * name is copied as "". Vertex sets are copied as they are (possibly NULL). */
int bs__groups_copy(const bs_group *src, int n, bs_group **out, bs_error *err);

/* Recomputes g->vertices / g->n_vertices (sorted, unique) from g->elems:
 * the element vertices for dim < 3, the vertices of the tets m->tets[elems]
 * for dim 3. Indices are assumed in range (bs_mesh_check verifies them). */
int bs__group_update_vertices(const bs_mesh *m, bs_group *g, bs_error *err);

/* Copy of a C string into malloc'ed memory ("" for NULL); NULL on ENOMEM. */
char *bs__strdup(const char *s);

/* Checks the .msh file at path before Gmsh parses it (msh_check.c): format,
 * sections, every count against the file's bytes and bs_limits.h, tags,
 * coordinates, element types and nodes. 0, or BS_EINPUT / BS_EIO / BS_ENOMEM
 * naming the file, the line (or byte) and what is wrong. */
int bs__msh_check(const char *path, bs_error *err);

/* Coincident vertices: rep[i] = the smallest j with x[3 j .. 3 j + 2]
 * bitwise equal to x[3 i .. 3 i + 2] (rep[i] = i for the first of each
 * position). Returns the number of i with rep[i] != i, or -1 (BS_ENOMEM in
 * err) when the work array cannot be allocated. */
int64_t bs__coincident(int64_t n, const double *x, int32_t *rep, bs_error *err);

/* mesh.c: 1 when the tet tv (4 indices into x) has zero volume: |V| <=
 * 1e-14 l^3, l its longest edge (bs_mesh_create refuses such a tet). */
int bs__tet_flat(const double *x, const int32_t *tv);

/* quality.c: the measures of one tet (p[0..3] its vertices), as defined in
 * quality.c's comment: signed volume, extreme dihedral angles (degrees) and
 * signed radius ratio. */
typedef struct bs__tet_measures {
  double volume, dihedral_min, dihedral_max, radius_ratio;
} bs__tet_measures;
void bs__tet_quality(const double *const p[4], bs__tet_measures *out);

/* Volume enclosed by the soup's nt triangles (divergence theorem; its sign
 * follows their orientation; surface_mesh.c). */
double bs__soup_volume(const double *p, const int32_t *t, int64_t nt);

/* surface_mesh.c: the mesh of nv vertices x and nt tets (copied) with the
 * groups of Gmsh's discrete surfaces, (3, 1, "body") every tet and (2, 1,
 * "surface_1") its whole boundary; errors (bs_mesh_create's) name path. */
int bs__mesh_default_groups(const char *path, int32_t nv, const double *x, int32_t nt, const int32_t *tets,
                            bs_mesh **out, bs_error *err);

/* surface_mesh.c: the volume inside a closed surface soup (from a file
 * `path`, already read) meshed at opts->size > 0 by CGAL's Mesh_3 or the
 * remesh path (opts->surface_mesher; auto: see surface_mesh.c), then held
 * to the quality gate (bs_mesh_dihedral_gate). Groups (3, 1, "body") and
 * (2, 1, "surface_1"). BS_EINPUT naming path: size absurd for the
 * surface's bounding box, too many tets, the shim's refusals, the gate. */
int bs__mesh_closed_surface(const char *path, const double *pts, int64_t np, const int32_t *tris, int64_t nt,
                            const bs_mesh_read_opts *opts, bs_mesh **out, bs_error *err);

/* surface_parts.c: a closed soup of several separate solids, one soup per
 * solid. */
typedef struct bs_soup_part {
  double *x;       /* 3 np */
  int32_t *tris;   /* 3 nt, 0-based into x */
  int64_t np, nt;
  double volume;   /* enclosed (signed: > 0 outward) */
  double diag;     /* bounding-box diagonal */
} bs_soup_part;

/* surface_parts.c: the soup's connected components as parts (*parts, *n
 * >= 2) when it has two or more and each encloses a positive (outward)
 * volume: separate solids, to be meshed one at a time so that no tet joins
 * two of them. Else *parts NULL and *n 0 (one solid, or a solid with a
 * cavity: meshed whole). BS_ENOMEM naming path. Free with
 * bs__soup_parts_free. */
int bs__soup_solids(const char *path, const double *x, int64_t np, const int32_t *tris, int64_t nt,
                    bs_soup_part **parts, int64_t *n, bs_error *err);
void bs__soup_parts_free(bs_soup_part *parts, int64_t n);

/* surface_parts.c: the n meshes as one (their vertices and tets in order,
 * the default groups: bs__mesh_default_groups). */
int bs__mesh_concat(const char *path, bs_mesh *const *meshes, int64_t n, bs_mesh **out, bs_error *err);

/* surface_remesh.c: the "remesh" mesher (BS_SURFACE_REMESH): the closed
 * soup remeshed by CGAL at opts->size (bs_shim_remesh_surface), its volume
 * meshed by Gmsh's HXT (one thread) from those triangles
 * (bs__gmsh_surface_volume), optimised and held to the gate. The size has
 * been checked (as bs__mesh_closed_surface does). Groups (3, 1, "body") and
 * (2, 1, "surface_1"). Errors name path: the shim's refusals (a surface
 * that folds through itself once remeshed), Gmsh's failure, the gate. */
int bs__mesh_remeshed_surface(const char *path, const double *pts, int64_t np, const int32_t *tris, int64_t nt,
                              const bs_mesh_read_opts *opts, bs_mesh **out, bs_error *err);

/* An edge (a, b) as one sortable key, the smaller index in the high half,
 * and qsort's comparison of such keys. */
static inline uint64_t bs__edge_key(int32_t a, int32_t b) {
  return a < b ? (uint64_t)a << 32 | (uint32_t)b : (uint64_t)b << 32 | (uint32_t)a;
}
static inline int bs__cmp_u64(const void *a, const void *b) {
  uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
  return x < y ? -1 : x > y;
}

/* manifold.c: each point's connected component among the soup's triangles
 * (0 .. k - 1; -1 for a point in no triangle) into label (np entries);
 * returns k, -1 when out of memory. */
int64_t bs__soup_label_components(const int32_t *tris, int64_t nt, int64_t np, int32_t *label);

/* manifold.c: the number of connected components of a soup's triangles
 * (points joined by triangle edges; points in no triangle not counted)
 * whose enclosed |volume| is at least min_volume; parent: np scratch
 * entries. -1 when out of memory. */
int64_t bs__soup_components(const double *x, int64_t np, const int32_t *tris, int64_t nt, double min_volume,
                            int32_t *parent);

/* manifold.c: BS_EINPUT naming path, the counts and the first place of
 * each fault, unless m's boundary is a closed 2-manifold (every boundary
 * edge in exactly two boundary triangles, every boundary vertex's triangles
 * one fan) with `components` connected components (<= 0: not checked);
 * BS_ENOMEM. */
int bs__boundary_manifold(const bs_mesh *m, const char *path, int64_t components, bs_error *err);

/* manifold.c: bs__boundary_manifold with the soup's components of at least
 * min_volume (bs__soup_components) as the count; BS_ENOMEM naming path. */
int bs__boundary_like_soup(const bs_mesh *m, const char *path, const double *pts, int64_t np, const int32_t *tris,
                           int64_t nt, double min_volume, bs_error *err);

/* surface_remesh.c: the volume inside a closed soup whose triangles are
 * kept as its boundary, meshed by Gmsh's HXT (one thread) and optimised
 * (bs__gmsh_surface_volume), the caps under the gate that no optimiser
 * moves removed (four boundary vertices, two boundary faces: the surface
 * edge between them flipped), its boundary checked to be a closed
 * 2-manifold with the soup's components (bs__boundary_manifold), then held
 * to the gate. HXT's mesh depends on the heap's addresses (Gmsh 4.8.4), so
 * a refused mesh (Gmsh's failure or void, the manifold check, the gate) is
 * made again, up to three attempts in all; the last refusal is returned.
 * Groups (3, 1, "body") and (2, 1, "surface_1"). Errors name path: Gmsh's
 * failure, the manifold check, the gate. */
int bs__mesh_hxt_inside(const char *path, const double *pts, int64_t np, const int32_t *tris, int64_t nt,
                        const bs_mesh_read_opts *opts, bs_mesh **out, bs_error *err);

/* gmsh_io.c: the volume inside a closed soup (outward triangles) meshed by
 * Gmsh with the soup's triangles as its boundary (a discrete surface; sizes
 * interpolated from the boundary), Mesh.Algorithm3D = algo3d (1 Delaunay,
 * 10 HXT) and General.NumThreads = threads, then Gmsh's optimisers towards
 * bs__mesh_gate(opts) (the caller holds the mesh to the gate). Refuses
 * (BS_EGMSH) a mesh whose boundary has another number of triangles than the
 * soup (a void inside). Takes the Gmsh lock. */
int bs__gmsh_surface_volume(const char *path, const double *pts, int64_t np, const int32_t *tris, int64_t nt,
                            const bs_mesh_read_opts *opts, int algo3d, int threads, bs_mesh **out, bs_error *err);

/* gmsh_optimize.c: inside a Gmsh session whose model has a 3-D mesh, runs
 * gmshModelMeshOptimize ("" then "Netgen", Mesh.OptimizeThreshold raised each
 * round) until the smallest dihedral angle of its tets reaches gate degrees
 * or a round brings no progress, then meshes the volume again with HXT
 * and optimises again if the gate still fails. *achieved (may be NULL): the
 * smallest angle of the mesh left in the model (not the best one seen). */
int bs__gmsh_optimize_to_gate(const char *path, double gate, double *achieved, bs_error *err);

/* The gate the options ask for, in degrees (0: none): opts->min_dihedral
 * when > 0, BS_MESH_MIN_DIHEDRAL when 0, none when < 0. */
double bs__mesh_gate(const bs_mesh_read_opts *opts);

/* mesh_budget.c: the meshing time budget (bs_mesh_read_opts.time_budget)
 * of this thread's bs_mesh_read. bs__budget_begin starts it
 * (BS_MESH_TIME_BUDGET when opts->time_budget is 0, none when it is < 0),
 * bs__budget_end clears it. bs__budget_deadline:
 * the bs_seconds() time it ends (0: none), for the shim's loops.
 * bs__budget_check: BS_OK, or BS_EINPUT "<path>: the meshing time budget of
 * B s (...) was exceeded before <stage>" once past it. bs__budget_exceeded:
 * whether err holds such a message (a budget refusal, from here or from the
 * shim, which no fallback may retry). */
void bs__budget_begin(const bs_mesh_read_opts *opts);
void bs__budget_end(void);
double bs__budget_deadline(void);
int bs__budget_check(const char *path, const char *stage, bs_error *err);
int bs__budget_exceeded(const bs_error *err);
/* Appends the budget's value and where it is set to a budget refusal that
 * came from the shim (which knows only the deadline). */
void bs__budget_note(bs_error *err);
/* The report of this thread's bs_mesh_read (opts->report; NULL: none or no
 * read running). */
struct bs_surface_report *bs__read_report(void);

/* surface_wrap.c: the soup (x, nx; t, nt: any triangles) replaced by its
 * alpha wrap at element size h (bs_shim_alpha_wrap, the rule of bs_shim.h),
 * held to the volume check when the input is closed once oriented:
 * |V_wrap - V_in| <= 2 offset area + BS_WRAP_VOLUME_TOL V_in; and, for an
 * input the repair refused as open (open = 1), to the solid check: V_wrap
 * >= BS_WRAP_SOLID x 2 offset area (else the ball went in through a hole
 * wider than 2 alpha and the wrap is only a shell around the surface; when
 * its openings are all narrower, a soup of facets with gaps, the wrap is
 * the solid they bound). *pts, *tris
 * allocated by the shim (bs_shim_free). rep (may be NULL) gets wrapped =
 * how (1 or 2), the wrap's alpha, offset, volume change and seconds, and
 * points_out, tris_out, volume. Errors name path: the shim's, the budget,
 * BS_EINPUT for a wrap that fails the volume check (the change and the bound). */
#define BS_WRAP_SOLID 10.0
int bs__surface_wrap(const char *path, const double *x, int64_t nx, const int32_t *t, int64_t nt, double h, int how,
                     int open, double **pts, int64_t *np, int32_t **tris, int64_t *ntri, struct bs_surface_report *rep,
                     bs_error *err);

/* tet_lift.c: the quality back end (CGAL's tetrahedral remeshing, the rule
 * in tet_lift.c's comment). bs__tets_lift: the raw tets (any orientation,
 * zero-volume ones allowed; sub: subdomain >= 1 per tet or NULL) remeshed
 * at h (<= 0: their mean edge length) towards gate, boundary kept, then
 * (allow_boundary) with the boundary remeshed and sharp edges constrained
 * when still under it; *out (free its arrays with bs_shim_free) holds the
 * best, which may still be under the gate (the caller holds it to the
 * gate). bs__mesh_lift: *m replaced by its lift (the boundary remeshed only
 * when its groups are the default "body" and "surface_1"; other groups are
 * kept: 3-D ones by material, lower ones by position). Errors name path:
 * the shim's, the budget, the volume check (BS_EINPUT). */
#define BS_LIFT_VOLUME_TOL 0.005
#define BS_LIFT_ROUNDS 8
struct bs_shim_tet_remesh_out;
int bs__tets_lift(const char *path, int32_t nv, const double *x, int32_t nt, const int32_t *tets, const int32_t *sub,
                  double h, double gate, int allow_boundary, struct bs_shim_tet_remesh_out *out, bs_error *err);
int bs__mesh_lift(const char *path, bs_mesh **m, double h, double gate, bs_error *err);

/* Mean edge length of the nt tets (each tet's six edges; shared edges count
 * once per tet); 0 without tets (tet_lift.c). */
double bs__mean_tet_edge(const double *x, int32_t nt, const int32_t *tets);

/* cad_surface.c: a geometry's mesh *m that misses the gate (err holds the
 * gate's message) and could not be lifted, meshed again from its boundary
 * by bs__mesh_closed_surface at h (<= 0: the mean tet edge), its groups
 * carried over (one 3-D group; 2-D groups by the closest old boundary
 * triangle), its volume within BS_FROM_BOUNDARY_VOLUME_TOL of *m's; not
 * tried (BS_EINPUT, err untouched) on a part whose mean thickness 2V/A is
 * under BS_FROM_BOUNDARY_MIN_THICKNESS h. BS_OK with *m replaced; BS_EINPUT with err untouched when the
 * groups cannot be carried (several 3-D groups, 0-D or 1-D groups, faces in
 * two 2-D groups), or with the surface path's message appended to err;
 * the budget's error or BS_ENOMEM as they are. */
#define BS_FROM_BOUNDARY_VOLUME_TOL 0.01
#define BS_FROM_BOUNDARY_MIN_THICKNESS 0.25 /* mean thickness 2V/A over h below which it is not tried */
int bs__mesh_cad_by_surface(const char *path, bs_mesh **m, double h, const bs_mesh_read_opts *opts, bs_error *err);
/* tet_lift.c: appends "; CGAL's tetrahedral remeshing of it reached D
 * degrees" (m's smallest angle) to the gate's message in err; BS_EINPUT. */
int bs__lift_note(const bs_mesh *m, bs_error *err);

/* surface_mesh.c: bs__mesh_closed_surface at the size bigstep chooses
 * (bs_surface_auto_size, attempt 0 then 1 when refused); (*out)->auto_size
 * is the size used. Errors: the first attempt's, prefixed with the size. */
int bs__mesh_surface_auto(const char *path, const double *pts, int64_t np, const int32_t *tris, int64_t nt,
                          const bs_mesh_read_opts *opts, bs_mesh **out, bs_error *err);

#ifdef __cplusplus
}
#endif
#endif
