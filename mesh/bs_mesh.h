/* bs_mesh.h — the tetrahedral mesh of bigstep (deal.II's Triangulation).
 *
 * A bs_mesh holds first-order tetrahedra (P1) and what is derived from them:
 * boundary triangles (outward), boundary edges, vertex-to-tet adjacency, and
 * the Gmsh physical groups, keyed by (dimension, tag) and kept with names.
 *
 * Conventions
 *  - SI units; coordinates are doubles, x[3*v + k].
 *  - Indices are int32_t (METIS uses 32-bit idx_t), 0-based.
 *  - Every tet is oriented so that its rest volume
 *      V = det[x1-x0, x2-x0, x3-x0] / 6
 *    is positive. A zero-volume tet is an error (it names the tet).
 *  - Tet local faces: face f is opposite vertex f; bs_tet_face[f] lists its
 *    three local vertices in the order whose normal points out of the tet.
 *  - Boundary faces are oriented outward: (b-a) x (c-a) points out.
 *  - Groups: a 3-D group is a material (each tet's material id is the tag of
 *    its 3-D group, 0 when in none); a 2-D group is a boundary part (each
 *    boundary face's boundary id is the tag of its 2-D group, 0 when in none)
 *    and names a vertex set; 0-D and 1-D groups name vertex sets. Every group
 *    stores its elements as vertex tuples of dim+1 vertices (for dim 3, as
 *    tet indices instead), and the sorted set of vertices they touch.
 *  - Ownership: bs_mesh_create* returns a mesh that the caller owns and frees
 *    with bs_mesh_destroy. Every array inside is owned by the mesh.
 *
 * Status: functions return BS_OK (0) or a negative BS_E* code and fill the
 * bs_error, whose message names the file, the element or the group at fault.
 */
#ifndef BS_MESH_H
#define BS_MESH_H

#include <stdint.h>

#include "bs_base.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Local faces of a tet, face f opposite local vertex f, outward orientation. */
extern const int bs_tet_face[4][3];

typedef struct bs_group {
  int dim;      /* 0, 1, 2 or 3                                          */
  int tag;      /* Gmsh physical tag (positive)                          */
  char *name;   /* Gmsh physical name; never NULL (may be "")            */
  int32_t n_elems;
  int32_t *elems;      /* dim < 3: (dim+1) vertex indices per element;
                          dim = 3: one tet index per element            */
  int32_t n_vertices;
  int32_t *vertices;   /* sorted, unique: the vertices the elements use  */
} bs_group;

typedef struct bs_mesh {
  int32_t n_vertices;
  double *x;           /* 3 * n_vertices, rest positions                 */

  int32_t n_tets;
  int32_t *tets;       /* 4 * n_tets, positively oriented                */
  int32_t *material;   /* n_tets: tag of the tet's 3-D group, 0 if none  */

  int32_t n_faces;     /* boundary triangles                             */
  int32_t *faces;      /* 3 * n_faces, outward                           */
  int32_t *face_tet;   /* n_faces: the tet each face belongs to          */
  int32_t *boundary;   /* n_faces: tag of the face's 2-D group, 0 if none */

  int32_t n_edges;     /* boundary edges (edges of boundary faces)       */
  int32_t *edges;      /* 2 * n_edges, smaller index first               */

  int32_t *v2t_ptr;    /* n_vertices + 1: CSR vertex -> tets             */
  int32_t *v2t;        /* v2t_ptr[n_vertices]                            */

  int n_groups;
  bs_group *groups;

  int32_t n_dropped;   /* vertices of the input that no tet used (not
                          counting merged coincident nodes)              */
  int32_t n_coincident;/* bs_mesh_read: nodes of the input at exactly the
                          position of another node with a different tag
                          (0 in a sound mesh). Kept as distinct vertices,
                          they split the body into pieces there, unless
                          merged (bs_mesh_read_opts.merge_coincident)    */
  int coincident_merged; /* 1: those nodes were merged into one vertex   */
  double auto_size;    /* bs_mesh_read of a closed surface given no size
                          (opts->size <= 0): the element size it chose
                          (bs_surface_auto_size); 0 otherwise            */

  /* Quadratic tets (bodies[].element tet10; bs_tet10_mesh, bs_tet10.h made
   * them). NULL for a linear mesh. Else 10 * n_tets node indices per tet in
   * VTK order (bs_tet10.h), nodes 0..3 the tet's vertices tets[4t..4t+3];
   * the vertices 0..n_corners-1 are the corners (the vertices tets use) and
   * n_corners..n_vertices-1 the midside nodes, which no entry of tets, faces,
   * edges or v2t names; every group's vertices include the midside nodes of
   * its elements' edges. bs_mesh_finalize, bs_mesh_refine and
   * bs_mesh_permute / bs_mesh_reorder work on linear meshes only (BS_EINPUT
   * for a quadratic one). */
  int32_t *tets10;
  int32_t n_corners;   /* a quadratic mesh's corner count (0 when linear) */

  /* bs_mesh_read of a .msh of 10-node tets (Gmsh type 11): the mesh is the
   * linear mesh of their corners, and these are the file's midside nodes,
   * one per tet edge (repeated for shared edges): midside_edge[2i],
   * midside_edge[2i+1] the edge's corners, midside_x[3i..3i+2] the node's
   * position. bs_tet10_mesh puts them in place of the edge midpoints (then
   * frees them); bs_mesh_permute renumbers them; a refinement drops them
   * (its quadratic mesh has straight edges). NULL / 0 otherwise. */
  int32_t n_midside;
  int32_t *midside_edge;
  double *midside_x;
} bs_mesh;

/* ---- creation -------------------------------------------------------- */

/* Options for reading through Gmsh. */
typedef struct bs_mesh_read_opts {
  double size;   /* target mesh size for geometry inputs (.geo, .step, .stl,
                    ...); <= 0 means the file's own settings            */
  int refine;    /* uniform 1->8 refinements after reading (>= 0)        */
  int64_t max_tets; /* refuse (BS_EINPUT, before allocating) a mesh, a
                    refinement or a Gmsh size that would make more tets;
                    <= 0: bs_mesh_max_tets's default                      */
  int merge_coincident; /* 1: nodes at exactly the same position (bitwise
                    equal coordinates) under distinct tags become one
                    vertex (the one of the smallest tag); 0: they are kept
                    and only counted in bs_mesh.n_coincident           */
  int close_holes;  /* surfaces (.off .obj .ply): 1 closes holes up to
                    max_hole (bs_surface_prepare); 0 refuses an open surface */
  double max_hole;  /* the largest hole closed, as a fraction of the
                    bounding-box diagonal; <= 0: BS_SURFACE_MAX_HOLE_DEFAULT */
  struct bs_surface_report *report; /* if not NULL: the surface repair's
                    counts (bs_shim.h), zeroed for inputs that are not a
                    .off/.obj/.ply surface                               */
  double min_dihedral; /* the quality gate, degrees, for the meshes bigstep
                    makes (.geo, .step/.stp, .brep, .iges, closed surfaces;
                    not a .msh, which is taken as is): they are optimised
                    until every tet's smallest dihedral angle reaches it, and
                    a mesh that does not is refused (BS_EINPUT, naming the
                    angle reached and the worst region). 0: the default
                    BS_MESH_MIN_DIHEDRAL; < 0: no gate                   */
  double feature_angle; /* closed surfaces at size > 0: edges where the
                    surface turns by more than this (degrees) are kept as
                    sharp edges when the surface is CAD-like (its sharp
                    edges are long chains, bs_shim_mesh3_opts; a scan's
                    short creases are ignored); 0: BS_MESH_FEATURE_ANGLE;
                    < 0: none                                           */
  int surface_mesher; /* closed surfaces at size > 0: BS_SURFACE_AUTO (0:
                    the remesh path when the size asks for more than about
                    2e5 tets (6 V / h^3), Mesh_3 otherwise or when the
                    remesh path is refused; and the remesh path when Mesh_3's
                    mesh fails the gate), BS_SURFACE_CGAL (CGAL's
                    Mesh_3), BS_SURFACE_REMESH (CGAL's isotropic remeshing
                    of the surface at the size, then Gmsh's HXT volume
                    mesher and Gmsh's optimisers) or
                    BS_SURFACE_GMSH (Gmsh reparametrises and remeshes the
                    surface; kept for comparison)                       */
  int element_order; /* 2: geometry inputs (.geo, STEP, BREP, IGES) get
                    Gmsh's second-order nodes (Mesh.ElementOrder 2, then
                    Mesh.HighOrderOptimize), placed on the geometry: the
                    curved boundary kept in bs_mesh.midside_x for
                    bs_tet10_mesh. Dropped (straight edges) when the mesh
                    is remeshed to pass the gate or refined. 0 or 1: linear */
  double time_budget; /* seconds of wall time bs_mesh_read may spend
                    making a mesh (> 0), checked between its stages and
                    inside the CGAL loops that allow it (Mesh_3, alpha
                    wrap, tetrahedral remeshing); past it the read stops
                    with BS_EINPUT "... the meshing time budget of B s ...
                    was exceeded ..." naming the stage. 0: the default,
                    BS_MESH_TIME_BUDGET; < 0: no budget                 */
} bs_mesh_read_opts;

#define BS_MESH_MIN_DIHEDRAL 10.0
/* The meshing time budget when none is given (s): no read runs unbounded. */
#define BS_MESH_TIME_BUDGET 600.0
#define BS_MESH_FEATURE_ANGLE 60.0
enum { BS_SURFACE_AUTO = 0, BS_SURFACE_GMSH = 1, BS_SURFACE_REMESH = 2, BS_SURFACE_CGAL = 3 };
/* The mesher named by s ("auto", "cgal" or "remesh": the --mesher option and
 * the scene key bodies[].mesher) into *mesher (BS_SURFACE_*); 0, or -1 (s
 * NULL or another word; *mesher untouched).
 * Example: int m; if (bs_mesh_parse_mesher(arg, &m)) usage(); o.surface_mesher = m; */
int bs_mesh_parse_mesher(const char *s, int *mesher);
/* The name bs_mesh_parse_mesher reads for mesher ("auto" for any other value). */
const char *bs_mesh_mesher_name(int mesher);

/* Limits of a mesh job: at most BS_MESH_MAX_TETS tets (indices are int32 and
 * refinement multiplies by 8), and by default no more than this machine's
 * memory holds at BS_MESH_BYTES_PER_TET (Gmsh's peak while meshing, 600 to
 * 800 bytes a tet for 0.15M-0.7M tets, plus the mesh itself). */
#define BS_MESH_MAX_TETS (INT32_MAX / 8)
#define BS_MESH_BYTES_PER_TET 1000.0
/* opts->max_tets when > 0, else min(BS_MESH_MAX_TETS, memory / BS_MESH_BYTES_PER_TET). */
double bs_mesh_max_tets(const bs_mesh_read_opts *opts);

/* Reads FILE: .msh (v2/v4, ASCII/binary) as is; .geo, .step/.stp, .brep
 * meshed through Gmsh; closed surfaces (.stl .off .obj .ply, read by the
 * shim) meshed into a volume: at opts->size > 0 by CGAL's Mesh_3 (sharp edges
 * kept, optimised: surface_mesh.c), with size <= 0 at the size
 * bs_surface_auto_size chooses (reported in m->auto_size; with no gate
 * either, opts->min_dihedral < 0, Gmsh meshes inside the surface's own
 * triangles, which it keeps as they are). Meshes bigstep
 * makes are held to opts->min_dihedral; one under it (Gmsh's or Mesh_3's),
 * or with a tet of zero volume, is first lifted by CGAL's tetrahedral
 * remeshing, its boundary and groups kept (mesh/tet_lift.c). A surface the
 * repair cannot make clean, or whose meshes are all refused, is replaced by
 * its alpha wrap at the size (mesh/surface_wrap.c, the rule in bs_shim.h),
 * held to the wrap's volume check; what was done goes to *opts->report.
 * opts->time_budget bounds the whole (mesh/mesh_budget.c). Only
 * 4-node tets, or 10-node tets alone (read as their corners' linear mesh and
 * the midside list above; groups' 6-node triangles and 3-node lines as their
 * corners), are read: other 3-D elements are an error naming their type and
 * count. opts may be NULL (defaults).
 *
 * A .msh file is checked before Gmsh parses it (mesh/msh_check.c): its
 * format (2.x or 4.1, ASCII or binary, little-endian, 8-byte doubles), its
 * sections (only MeshFormat, PhysicalNames, Entities, Nodes, Elements and
 * Comments), every count against the bytes that follow it and against
 * bs_limits.h, every node coordinate (finite), every node and element tag
 * (in the range the header states; a node tag defined twice is an error
 * naming it) and every element's nodes (defined). Coincident nodes under
 * distinct tags are counted in m->n_coincident (a warning for the caller to
 * print) and merged when opts->merge_coincident. A surface (.off, .obj,
 * .ply, .stl) is repaired first (bs_surface_prepare; what was done goes to
 * *opts->report). A CAD file (STEP, IGES, BREP) of several solids is
 * fragmented into a conformal model, one 3-D group per part named after the
 * part (mesh/cad_assembly.c), surface groups "surface_<tag>". */
int bs_mesh_read(const char *path, const bs_mesh_read_opts *opts, bs_mesh **out, bs_error *err);

/* A surface file (.off, .obj, .ply, .stl: bs_shim_read_surface) read and
 * repaired (bs_shim_repair_surface: duplicates and zero-area triangles
 * removed, holes closed when opts->close_holes and no larger than
 * opts->max_hole, self-intersections removed, oriented outward). *pts (3 per
 * point) and *tris (3 per triangle) are allocated by the shim: free them with
 * bs_surface_free. A surface the repair refuses is replaced by its alpha wrap
 * at opts->size (<= 0: bs_surface_auto_size's first) when it passes its volume
 * check (an open one only when the wrap is solid: surface_repair.c);
 * rep->wrapped says so. opts (may be NULL: no hole closed) supplies
 * close_holes, max_hole and size only; rep (may be NULL) gets the counts.
 * Errors name the file: BS_EIO (unreadable), BS_EINPUT (a malformed file,
 * or a surface the repair and the wrap refuse: open, or self-intersections
 * it cannot remove; the message says how many, where and how large, and
 * why the wrap was refused), BS_ENOMEM, BS_EINTERNAL. Example:
 *     double *x; int32_t *t; int64_t np, nt; bs_surface_report r;
 *     bs_mesh_read_opts o = {.close_holes = 1};
 *     if (bs_surface_prepare("scan.off", &x, &np, &t, &nt, &o, &r, &err)) ...
 *     bs_surface_free(x); bs_surface_free(t); */
int bs_surface_prepare(const char *path, double **pts, int64_t *np, int32_t **tris, int64_t *nt,
                       const bs_mesh_read_opts *opts, struct bs_surface_report *rep, bs_error *err);

/* Frees an array bs_surface_prepare returned (NULL accepted). */
void bs_surface_free(void *p);

/* The element size bigstep chooses for a closed surface given none: the
 * bounding-box diagonal / BS_SURFACE_AUTO_CELLS[k] for attempt k (0, 1; a
 * mesh refused at the first, e.g. by the gate, is made again at the finer
 * second), never under the size whose 6 V / h^3 tets exceed the machine
 * (bs_mesh_max_tets). Thin parts get their own local size inside Mesh_3
 * (two elements across them: bs_shim_mesh3_opts.thickness_elements), which
 * is the local feature size's share of the rule. 0 for an empty soup. */
#define BS_SURFACE_AUTO_ATTEMPTS 2
double bs_surface_auto_size(const double *pts, int64_t np, const int32_t *tris, int64_t nt, int attempt,
                            const bs_mesh_read_opts *opts);

/* The security rule for Gmsh scripts: a .geo file (with what it includes or
 * merges, and FILE.opt beside it) that runs a program (SystemCall,
 * NonBlockingSystemCall, OnelabRun) or includes a computed file name is
 * refused by bs_mesh_read (BS_EINPUT naming the file and line) unless the
 * process allows it: bs_mesh_set_geo_system_calls(1), which the command line
 * does for --allow-geo-system only. Process-wide (default 0). */
void bs_mesh_set_geo_system_calls(int allow);
int bs_mesh_geo_system_calls(void);

/* Builds a mesh from raw arrays (copied): vertices, tets (any orientation:
 * they are reoriented) and optional groups (may be NULL / 0). Derives the
 * boundary, edges and adjacency; drops unused vertices. */
int bs_mesh_create(int32_t n_vertices, const double *x, int32_t n_tets, const int32_t *tets,
                   int n_groups, const bs_group *groups, bs_mesh **out, bs_error *err);

/* Structured box [lo, hi] of nx x ny x nz cells (so (nx+1)(ny+1)(nz+1)
 * vertices), each cell split into 6 tets (Kuhn split, conforming). Groups:
 * 2-D boundary groups "xmin" (tag 1), "xmax" (2), "ymin" (3), "ymax" (4),
 * "zmin" (5), "zmax" (6) and the 3-D group "body" (tag 1). */
int bs_mesh_create_box(const double lo[3], const double hi[3], int nx, int ny, int nz,
                       bs_mesh **out, bs_error *err);

/* The box [0, size] of cells[0] x cells[1] x cells[2] cells (as
 * bs_mesh_create_box), refined `refine` times (bs_mesh_refine). */
int bs_mesh_create_box_refined(const double size[3], const int cells[3], int refine, bs_mesh **out,
                               bs_error *err);

/* Parses a structured-box spec "box:NX[xNYxNZ][:LX[xLYxLZ]]" (cells 1..4096,
 * then edge lengths in metres, default 1): 0, or BS_EINPUT naming the spec. */
int bs_mesh_box_spec_parse(const char *spec, int cells[3], double size[3], bs_error *err);

/* A mesh from a file (bs_mesh_read, with opts) or from a box spec "box:..."
 * (then refined opts->refine times; opts->size is ignored). opts may be NULL. */
int bs_mesh_load(const char *spec, const bs_mesh_read_opts *opts, bs_mesh **out, bs_error *err);

/* Axis-aligned bounding box of n points (3 doubles each); 0 for n = 0. */
void bs_bbox(int64_t n, const double *x, double lo[3], double hi[3]);

/* Length of the box's diagonal, |hi - lo|. */
double bs_bbox_diagonal(const double lo[3], const double hi[3]);

/* Copies a mesh. */
int bs_mesh_copy(const bs_mesh *m, bs_mesh **out, bs_error *err);

void bs_mesh_destroy(bs_mesh **m);

/* ---- derived topology ------------------------------------------------ */

/* (Re)derives faces, face_tet, boundary, edges, v2t from vertices, tets and
 * groups; reorients tets to positive volume (error on zero volume). Called
 * by every creator; exposed for code that edits tets in place. */
int bs_mesh_finalize(bs_mesh *m, bs_error *err);

/* The group with this name (any dimension; the first by (dim, tag) order if
 * several share it), or NULL. */
const bs_group *bs_mesh_group(const bs_mesh *m, const char *name);

/* The group with this (dim, tag), or NULL. */
const bs_group *bs_mesh_group_by_tag(const bs_mesh *m, int dim, int tag);

/* The midside node of the edge (a, b) of the quadratic mesh m (a, b
 * corners), or -1 when m is linear or no tet has that edge. */
int32_t bs_mesh_edge_node(const bs_mesh *m, int32_t a, int32_t b);

/* Signed volume of tet t at positions x (3 * n_vertices). */
double bs_mesh_tet_volume(const bs_mesh *m, const double *x, int32_t t);

/* Total rest volume (sum over tets). */
double bs_mesh_volume(const bs_mesh *m);

/* Volume enclosed by the boundary triangles (divergence theorem). */
double bs_mesh_boundary_volume(const bs_mesh *m);

/* Invariant checker (CHOLMOD's Check): positive volumes, every interior face
 * shared by exactly two tets and no face by more, a closed boundary (every
 * boundary edge in an even number >= 2 of boundary faces, consistently
 * oriented), groups in range, adjacency consistent. */
int bs_mesh_check(const bs_mesh *m, bs_error *err);

/* ---- refinement, reordering ------------------------------------------ */

/* Uniform 1 -> 8 red refinement, interior octahedron split along its shortest
 * diagonal; new vertices at edge midpoints, appended after the old ones in a
 * deterministic order (so coarse vertex i is fine vertex i). Children inherit
 * their parent's material; groups of every dimension are refined with the
 * mesh. Volume is preserved exactly (up to round-off). */
int bs_mesh_refine(const bs_mesh *m, bs_mesh **out, bs_error *err);

typedef enum { BS_ORDER_NONE = 0, BS_ORDER_METIS = 1, BS_ORDER_RCM = 2 } bs_order;

/* Bandwidth (max |i - j| over vertex-graph edges) and profile (sum over rows
 * of i - min neighbour) of the vertex graph. */
void bs_mesh_bandwidth(const bs_mesh *m, int64_t *bandwidth, int64_t *profile);

/* Renumbers vertices by `order` (METIS_NodeND or reverse Cuthill-McKee on the
 * vertex graph) and tets by their smallest new vertex; groups, faces and
 * adjacency follow. If perm is non-NULL it receives new -> old vertex ids. */
int bs_mesh_reorder(bs_mesh *m, bs_order order, int32_t *perm, bs_error *err);

/* Applies an explicit vertex permutation (perm[new] = old). */
int bs_mesh_permute(bs_mesh *m, const int32_t *perm, bs_error *err);

/* Vertex graph in CSR (no self loops, sorted rows): the neighbours of each
 * vertex through tets. Arrays are malloc'ed; the caller frees them. */
int bs_mesh_vertex_graph(const bs_mesh *m, int32_t **ptr, int32_t **adj, bs_error *err);

/* ---- quality --------------------------------------------------------- */

typedef struct bs_mesh_quality {
  double vol_min, vol_max;          /* signed volumes                      */
  double dihedral_min, dihedral_max;/* degrees                             */
  double radius_ratio_min;          /* 3 r_in / r_circ, 1 for regular       */
  double radius_ratio_mean;
  int32_t n_inverted;               /* volume <= 0                         */
  int32_t n_degenerate;             /* radius ratio < 1e-2 or dihedral < 1 deg */
  int32_t n_sliver;                 /* min dihedral angle below 1 degree   */
} bs_mesh_quality;

/* Quality of the mesh at positions x (NULL: rest positions). */
void bs_mesh_quality_compute(const bs_mesh *m, const double *x, bs_mesh_quality *q);

/* The quality gate: BS_OK when every tet's smallest dihedral angle is at
 * least gate degrees (gate <= 0: always), else BS_EINPUT with a message
 * that starts with `what` (the file) and gives the angle reached, how many
 * tets are under the gate, the centre of the worst tet and the box around
 * the tets under the gate, e.g.
 *   "part.off: the mesh's smallest dihedral angle is 4.21 degrees, under
 *    the gate of 10: 37 of 81234 tets are under it, the worst at (0.1, 0.2,
 *    0.3), all in [..] x [..] x [..] (relax the gate with --min-dihedral
 *    or bodies[].min_dihedral)". */
int bs_mesh_dihedral_gate(const bs_mesh *m, double gate, const char *what, bs_error *err);

/* ---- output ----------------------------------------------------------
 *
 * VTK XML files for ParaView. Every array goes into one
 * <AppendedData encoding="raw"> block after a '_' marker, header_type
 * "UInt64", in the machine's byte order (stated in byte_order). Uncompressed
 * (compress = 0) each array is a UInt64 byte count and the raw values;
 * compressed (compress = 1) the file says compressor="vtkZLibDataCompressor"
 * and each array is VTK's zlib block layout: UInt64 words [n_blocks,
 * block_size (32768), size of a partial last block (0: full), the n_blocks
 * compressed sizes], then the zlib streams of the blocks (VTK's default
 * level 5). ParaView, VTK and meshio read both. Files are written whole or
 * removed: a failed write leaves no partial file behind. */

/* A caller-given data array: ncomp values per point (or per cell), tuple
 * after tuple. Ids and flags go as Int32 / UInt8. */
typedef enum { BS_VTU_FLOAT64 = 0, BS_VTU_INT32, BS_VTU_UINT8 } bs_vtu_type;

typedef struct bs_vtu_data {
  const char *name;    /* the DataArray's Name (escaped as needed)        */
  bs_vtu_type type;
  int ncomp;           /* >= 1 (ParaView shows 9 as a 3x3 tensor)         */
  const void *data;    /* ncomp * n_points (or n_cells) values             */
} bs_vtu_data;

/* What a tet-mesh VTU holds besides Points and Cells; any pointer may be
 * NULL (and the counts 0). */
typedef struct bs_vtu_fields {
  const double *x;             /* current positions (NULL: rest)          */
  const double *velocity;      /* 3 per vertex                            */
  const double *cell_detF;     /* per tet; computed from x when NULL     */
  int custom_cells;            /* 1: none of the cell data below but cell_data */
  int n_point_data;            /* more point data, after the above        */
  const bs_vtu_data *point_data;
  int n_cell_data;             /* more cell data, after the above         */
  const bs_vtu_data *cell_data;
  int compress;                /* 1: zlib (see above)                     */
} bs_vtu_fields;

/* VTU (XML UnstructuredGrid of VTK_TETRA cells, or of VTK_QUADRATIC_TETRA
 * cells (type 24, the 10 nodes of m->tets10) for a quadratic mesh, whose
 * built-in detF is that of the corner tet): points at f->x; point data
 * "displacement" (x - rest: always written, it gives back the rest shape),
 * "velocity" (when given), then f->point_data; cell data "material" (Int32,
 * the mesh's material tags), "detF" (given, or the signed current over rest
 * volume) and "inverted" (UInt8, detF <= 0 or NaN) unless f->custom_cells,
 * then f->cell_data. f may be NULL (rest positions, nothing else). An array
 * with no name, ncomp < 1, no data or an unknown type is BS_EINPUT naming it. */
int bs_mesh_write_vtu(const bs_mesh *m, const bs_vtu_fields *f, const char *path, bs_error *err);

/* A triangle surface (VTK_TRIANGLE cells), e.g. an obstacle's. */
typedef struct bs_vtu_surface {
  int32_t n_points;
  const double *x;             /* 3 per point                              */
  int32_t n_tris;
  const int32_t *tris;         /* 3 per triangle, 0-based                  */
  int n_point_data;
  const bs_vtu_data *point_data;
  int n_cell_data;
  const bs_vtu_data *cell_data;
  int compress;
} bs_vtu_surface;

/* Writes s as a VTU; a triangle index out of range is BS_EINPUT naming it. */
int bs_surface_write_vtu(const bs_vtu_surface *s, const char *path, bs_error *err);

/* A scalar field on a regular grid: VTK ImageData (.vti), point data `name`
 * (Float64, raw appended). Nodes origin + direction (h (i, j, k)), i fastest:
 * values[i + n[0] (j + n[1] k)]; direction (row-major 3x3, columns the grid
 * axes in world coordinates) NULL for the identity. */
typedef struct bs_vti_grid {
  int32_t n[3];                /* nodes per axis, >= 1                    */
  double origin[3], h;         /* m; h > 0                                */
  const double *direction;     /* 9 or NULL                               */
  const char *name;            /* e.g. "phi"                              */
  const double *values;
} bs_vti_grid;

/* Writes g to path (.vti). Bad sizes, h or a missing array: BS_EINPUT. */
int bs_vti_write(const bs_vti_grid *g, const char *path, bs_error *err);

/* PVD collection: n entries (time, file relative to the PVD's folder). */
int bs_pvd_write(const char *path, int n, const double *times, const char *const *files, bs_error *err);

/* A parallel VTU (.pvtu): the pieces (VTU file names relative to the PVTU's
 * folder, one per process, as bs_mesh_write_vtu writes them) and the point
 * and cell arrays each of them holds (name, type, components; "Points" is
 * declared by the writer). A missing name, an unknown type or no piece is
 * BS_EINPUT naming it; a write failure BS_EIO. */
typedef struct bs_pvtu_array {
  const char *name;
  bs_vtu_type type;
  int ncomp;
} bs_pvtu_array;
int bs_pvtu_write(const char *path, int n_point, const bs_pvtu_array *point, int n_cell, const bs_pvtu_array *cell,
                  int n_pieces, const char *const *pieces, bs_error *err);

/* .msh (Gmsh format 4.1) through the Gmsh API, with the groups, so results
 * open in Gmsh; x may be NULL (rest). A quadratic mesh (m->tets10) is
 * written with Gmsh's second-order elements: 10-node tets (type 11, Gmsh's
 * node order: VTK's with nodes 8 and 9 swapped), its groups' 6-node
 * triangles (type 9) and 3-node lines (type 8). */
int bs_mesh_write_msh(const bs_mesh *m, const double *x, const char *path, bs_error *err);

#ifdef __cplusplus
}
#endif
#endif
