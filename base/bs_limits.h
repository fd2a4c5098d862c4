/* bs_limits.h — the largest inputs bigstep's readers accept.
 *
 * Every reader (.msh, .vtu/.pvd, .bsls, .off/.stl/.obj/.ply surfaces, scene
 * JSON) checks a count it finds in a file against two things before the count
 * sizes an allocation: the bytes the file still has (a node needs at least a
 * few bytes, so a header that claims more nodes than the file can hold is
 * malformed) and the limit below (so that even a file that is as large as its
 * header claims cannot make bigstep ask for more memory than a simulation of
 * that size could use). Above a limit the reader returns BS_EINPUT with a
 * message that names the file, the count and the limit.
 *
 * The limits are far above what a simulation on one machine runs (the
 * largest bench scene has ~10^5 vertices) and below the 32-bit index range
 * (int32_t indices, METIS's idx_t): 4 * BS_MAX_TETS still fits in int32_t.
 */
#ifndef BS_LIMITS_H
#define BS_LIMITS_H

/* Vertices (nodes) of a volume mesh: .msh nodes, .vtu points. */
#define BS_MAX_VERTICES 100000000L

/* Elements of a .msh file (of all dimensions) and cells of a .vtu file. */
#define BS_MAX_ELEMENTS 500000000L

/* Tetrahedra of a mesh (4 * BS_MAX_TETS < 2^31). */
#define BS_MAX_TETS 500000000L

/* Points and polygons of a surface file (.off, .stl, .obj, .ply). */
#define BS_MAX_SURFACE_POINTS 100000000L
#define BS_MAX_SURFACE_FACES 200000000L

/* Vertices of one polygon of a surface file (it is split into k - 2 triangles). */
#define BS_MAX_POLYGON_VERTICES 65536L

/* Nodes of a grid level set (.bsls): 2 doubles each in memory (samples and
 * B-spline coefficients), so 2^28 nodes are 4 GiB. */
#define BS_MAX_GRID_NODES 268435456L

/* Bytes of a scene JSON file. */
#define BS_MAX_SCENE_BYTES (64L * 1024 * 1024)

/* Entities (points, curves, surfaces, volumes) and physical groups of a .msh
 * file, and the tags one entity may list. */
#define BS_MAX_MSH_ENTITIES 10000000L
#define BS_MAX_MSH_PHYSICALS 1000000L

#endif
