/* bs_dmesh.h — a tetrahedral mesh distributed over the MPI ranks (PETSc
 * DMPlex), with the Gmsh physical groups kept, for the petsc backend.
 *
 * A bs_dmesh is a DMPlex (interpolated: cells, faces, edges, vertices),
 * partitioned by PETSc's partitioner and distributed with an overlap of one
 * cell, plus what each rank needs to assemble P1 terms:
 *  - the local vertices (owned and ghost: every vertex of the rank's DMPlex),
 *    their rest positions, which of them this rank owns (a shared vertex has
 *    exactly one owner over the ranks), and a PetscSection of 3 dofs per vertex
 *    set as the DM's local section (global vectors hold the owned dofs);
 *  - `local`: a bs_mesh of the cells this rank OWNS (the overlap cells are
 *    another rank's), over the vertices those cells use, in ascending DMPlex
 *    order, positively oriented (bs_mesh's convention), with the 3-D groups
 *    as its materials; local_vertex maps its vertices to local vertices. Each
 *    cell is owned by one rank, so a sum over the ranks of per-cell
 *    quantities (volume, energy) counts every cell once;
 *  - groups: the physical groups by (dim, tag, name), the same table on every
 *    rank: 3-D groups are materials (cells), groups of lower dimension are
 *    vertex sets (the vertices of the closure of their faces / edges /
 *    vertices), here as local vertex indices.
 *
 * Sources (bs_dmesh_load):
 *  - a Gmsh .msh file, read by PETSc (DMPlexCreateGmshFromFile with
 *    -dm_plex_gmsh_use_regions: one DMLabel per physical name, value = tag);
 *  - a structured box "box:NXxNYxNZ[:LXxLYxLZ]": the serial bs_mesh of
 *    bs_mesh_create_box, built on rank 0 and handed to DMPlex cell by cell, so
 *    that vertices, tets and groups are the serial ones (bs_dmesh_from_mesh
 *    does that for any bs_mesh);
 *  - then `refine` uniform refinements by DMPlex's own regular refinement
 *    (DMRefine: every tet into 8, labels inherited by the children).
 * Meshes built from a bs_mesh and not refined know each local vertex's index
 * in that bs_mesh (orig_id); otherwise orig_id is -1.
 *
 * Every function is collective over PETSC_COMM_WORLD (bs_dist_init first).
 * Ownership: bs_dmesh_* creators return a mesh the caller frees with
 * bs_dmesh_destroy (NULL accepted). Status: BS_OK, BS_EINPUT (a bad spec, a
 * rank left with no cell: the message says how many ranks and cells), BS_EIO
 * (an unreadable .msh, naming it), BS_ENOMEM, BS_EINTERNAL (a PETSc error, with
 * its message). Units: SI (metres, m^3).
 *
 * Example
 *   bs_dmesh *dm = NULL;
 *   if (bs_dmesh_load("box:20x2x2:1x0.1x0.1", 0, &dm, &err)) ...
 *   double vol;
 *   bs_dmesh_volume(dm, &vol, &err);           // 0.01 on every rank
 *   bs_dmesh_destroy(&dm);
 */
#ifndef BS_DMESH_H
#define BS_DMESH_H

#include <petscdmplex.h>
#include <stdint.h>

#include "bs_base.h"
#include "bs_mesh.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct bs_dgroup {
  char *name;          /* physical name (never NULL)                              */
  int dim, tag;        /* 0..3 and the Gmsh physical tag                          */
  int32_t n_vertices;  /* local vertices in the group (owned and ghost)           */
  int32_t *vertices;   /* sorted local vertex indices                             */
} bs_dgroup;

typedef struct bs_dmesh {
  DM dm;                   /* the distributed DMPlex (owned by the bs_dmesh)       */
  PetscInt vstart;         /* DMPlex points of the vertices: vstart .. +n_vertices */
  int32_t n_vertices;      /* local vertices (owned and ghost)                     */
  int32_t n_owned;         /* of which this rank owns                              */
  uint8_t *owned;          /* n_vertices: 1 owned here                             */
  int64_t *orig_id;        /* n_vertices: index in the source bs_mesh, or -1       */
  double *x;               /* 3 n_vertices: rest positions (m)                     */
  bs_mesh *local;          /* the owned cells (NULL never: a rank with no cell is  */
                           /* refused)                                             */
  int32_t *local_vertex;   /* local->n_vertices: the local vertex of each          */
  int64_t n_global_vertices, n_global_cells;
  int n_groups;
  bs_dgroup *groups;       /* sorted by (dim, tag), the same on every rank         */
} bs_dmesh;

/* "box:..." (bs_mesh_box_spec_parse) or a .msh path, refined `refine` times. */
int bs_dmesh_load(const char *spec, int refine, bs_dmesh **out, bs_error *err);

/* A Gmsh .msh (2.2 or 4.1) through DMPlexCreateGmshFromFile, refined. */
int bs_dmesh_read_msh(const char *path, int refine, bs_dmesh **out, bs_error *err);

/* The bs_mesh m (read on rank 0 only; other ranks pass NULL), groups kept,
 * distributed, then refined. */
int bs_dmesh_from_mesh(const bs_mesh *m, int refine, bs_dmesh **out, bs_error *err);

void bs_dmesh_destroy(bs_dmesh **m);

/* The group named `name` (the first by (dim, tag) if several), or NULL. Not
 * collective. */
const bs_dgroup *bs_dmesh_group(const bs_dmesh *m, const char *name);

/* Total rest volume over the ranks (each owned cell once). */
int bs_dmesh_volume(const bs_dmesh *m, double *volume, bs_error *err);

/* Number of distinct vertices in group g over the ranks (owned ones summed). */
int bs_dmesh_group_count(const bs_dmesh *m, const bs_dgroup *g, int64_t *count, bs_error *err);

/* Owned cells of 3-D group g over the ranks (its material's cells). */
int bs_dmesh_group_cells(const bs_dmesh *m, const bs_dgroup *g, int64_t *count, bs_error *err);

#ifdef __cplusplus
}
#endif
#endif
