/* dmesh.c — a bs_dmesh from a .msh, a box or a bs_mesh: the DMPlex made on
 * rank 0, distributed with overlap 1, refined (bs_dmesh.h). The local data
 * after that are dmesh_local.c's, the groups dmesh_groups.c's. */
#include <stdlib.h>
#include <string.h>

#include "bs_dist.h"
#include "bs_dmesh.h"
#include "dist_internal.h"
#include "dmesh_internal.h"

/* The serial DMPlex of m on rank 0 (empty elsewhere). PETSc's reference tet
 * has det[v1-v0, v2-v0, v3-v0] < 0: vertices 1 and 2 are swapped. */
static int dm_from_cells(const bs_mesh *m, DM *out, bs_error *err) {
  int root = bs_dist_rank() == 0;
  PetscInt nc = root ? m->n_tets : 0, nv = root ? m->n_vertices : 0;
  PetscInt *cells = bs_calloc((size_t)4 * nc + 4, sizeof *cells, "DMPlex cells", err);
  if (!cells) return BS_ENOMEM;
  for (PetscInt t = 0; t < nc; t++) {
    const int32_t *tv = m->tets + 4 * t;
    PetscInt *c = cells + 4 * t;
    c[0] = tv[0], c[1] = tv[2], c[2] = tv[1], c[3] = tv[3];
  }
  static const double none[3] = {0, 0, 0};
  PetscErrorCode ierr = DMPlexCreateFromCellListPetsc(PETSC_COMM_WORLD, 3, nc, nv, 4, PETSC_TRUE, cells, 3,
                                                      root ? m->x : none, out);
  free(cells);
  return ierr ? bs__petsc_error(ierr, "DMPlexCreateFromCellListPetsc", err) : BS_OK;
}

/* The point of dimension dim that has these dim+1 vertices (dim 0: the vertex). */
static int element_point(DM dm, int dim, const int32_t *ev, PetscInt vstart, PetscInt *point, bs_error *err) {
  PetscInt pts[4];
  for (int a = 0; a <= dim; a++) pts[a] = vstart + ev[a];
  if (dim == 0) {
    *point = pts[0];
    return BS_OK;
  }
  PetscInt nj = 0;
  const PetscInt *join = NULL;
  BS_PETSC_TRY(DMPlexGetFullJoin(dm, dim + 1, pts, &nj, &join), err);
  *point = nj == 1 ? join[0] : -1;
  BS_PETSC_TRY(DMPlexRestoreJoin(dm, dim + 1, pts, &nj, &join), err);
  if (*point < 0) return bs_error_set(err, BS_EINPUT, "a %d-D group element is not a face of the mesh", dim);
  return BS_OK;
}

/* The groups of m as labels named by the groups, value = tag, on the points
 * of the group's dimension (rank 0; every rank creates every label). */
static int labels_from_groups(DM dm, const bs_mesh *m, int n_groups, bs_error *err) {
  int root = bs_dist_rank() == 0;
  PetscInt vstart, vend;
  BS_PETSC_TRY(DMPlexGetDepthStratum(dm, 0, &vstart, &vend), err);
  for (int i = 0; i < n_groups; i++) {
    char name[256] = "";
    if (root) snprintf(name, sizeof name, "%s", m->groups[i].name[0] ? m->groups[i].name : "unnamed");
    if (MPI_Bcast(name, sizeof name, MPI_CHAR, 0, PETSC_COMM_WORLD) != MPI_SUCCESS)
      return bs_error_set(err, BS_EINTERNAL, "MPI_Bcast of a group name failed");
    BS_PETSC_TRY(DMCreateLabel(dm, name), err);
    if (!root) continue;
    const bs_group *g = &m->groups[i];
    for (int32_t e = 0; e < g->n_elems; e++) {
      PetscInt p = g->elems[e];
      if (g->dim < 3) {
        int rc = element_point(dm, g->dim, g->elems + (size_t)e * (g->dim + 1), vstart, &p, err);
        if (rc) return rc;
      }
      BS_PETSC_TRY(DMSetLabelValue(dm, name, p, g->tag), err);
    }
  }
  return BS_OK;
}

/* Original vertex ids of the serial DM as a field (1 dof per vertex). */
static int id_field(DM dm, PetscSection *sec, Vec *ids, bs_error *err) {
  PetscInt ps, pe, vs, ve;
  BS_PETSC_TRY(DMPlexGetChart(dm, &ps, &pe), err);
  BS_PETSC_TRY(DMPlexGetDepthStratum(dm, 0, &vs, &ve), err);
  BS_PETSC_TRY(PetscSectionCreate(PETSC_COMM_WORLD, sec), err);
  BS_PETSC_TRY(PetscSectionSetChart(*sec, ps, pe), err);
  for (PetscInt v = vs; v < ve; v++) BS_PETSC_TRY(PetscSectionSetDof(*sec, v, 1), err);
  BS_PETSC_TRY(PetscSectionSetUp(*sec), err);
  BS_PETSC_TRY(VecCreateSeq(PETSC_COMM_SELF, ve - vs, ids), err);
  for (PetscInt v = vs; v < ve; v++) BS_PETSC_TRY(VecSetValue(*ids, v - vs, (PetscScalar)(v - vs), INSERT_VALUES), err);
  BS_PETSC_TRY(VecAssemblyBegin(*ids), err);
  BS_PETSC_TRY(VecAssemblyEnd(*ids), err);
  return BS_OK;
}

/* Distributes *dm (overlap 1) in place; with ids (sec, *ids) also moves the
 * id field along (replaced by the distributed one). */
static int distribute(DM *dm, PetscSection *sec, Vec *ids, bs_error *err) {
  PetscPartitioner part;
  BS_PETSC_TRY(DMPlexGetPartitioner(*dm, &part), err);
  BS_PETSC_TRY(PetscPartitionerSetFromOptions(part), err);
  DM dist = NULL;
  PetscSF sf = NULL;
  BS_PETSC_TRY(DMPlexDistribute(*dm, 1, &sf, &dist), err);
  if (!dist) return BS_OK; /* one rank */
  if (sec && *sec) {
    PetscSection nsec;
    Vec nids;
    BS_PETSC_TRY(PetscSectionCreate(PETSC_COMM_WORLD, &nsec), err);
    BS_PETSC_TRY(VecCreate(PETSC_COMM_SELF, &nids), err);
    BS_PETSC_TRY(DMPlexDistributeField(*dm, sf, *sec, *ids, nsec, nids), err);
    PetscSectionDestroy(sec);
    VecDestroy(ids);
    *sec = nsec;
    *ids = nids;
  }
  PetscSFDestroy(&sf);
  DMDestroy(dm);
  *dm = dist;
  return BS_OK;
}

static int refine(DM *dm, int times, bs_error *err) {
  for (int r = 0; r < times; r++) {
    DM fine = NULL;
    BS_PETSC_TRY(DMRefine(*dm, PETSC_COMM_WORLD, &fine), err);
    DMDestroy(dm);
    *dm = fine;
  }
  return BS_OK;
}

/* Distribution, refinement and the local data of a serial DM (consumed). */
static int finish(DM dm, PetscSection sec, Vec ids, int refine_times, bs_dmesh **out, bs_error *err) {
  int rc = distribute(&dm, &sec, &ids, err);
  if (!rc && refine_times > 0) {
    PetscSectionDestroy(&sec);
    VecDestroy(&ids);
    rc = refine(&dm, refine_times, err);
  }
  if (!rc) rc = bs__dmesh_setup(dm, sec, ids, out, err);
  else DMDestroy(&dm);
  PetscSectionDestroy(&sec);
  VecDestroy(&ids);
  return rc;
}

int bs_dmesh_from_mesh(const bs_mesh *m, int refine_times, bs_dmesh **out, bs_error *err) {
  if (!out) return bs_error_set(err, BS_EINPUT, "bs_dmesh_from_mesh: out is NULL");
  *out = NULL;
  int n_groups = bs_dist_rank() == 0 && m ? m->n_groups : 0, ok = bs_dist_rank() != 0 || m;
  if (MPI_Bcast(&n_groups, 1, MPI_INT, 0, PETSC_COMM_WORLD) != MPI_SUCCESS ||
      MPI_Bcast(&ok, 1, MPI_INT, 0, PETSC_COMM_WORLD) != MPI_SUCCESS)
    return bs_error_set(err, BS_EINTERNAL, "MPI_Bcast of the mesh's group count failed");
  if (!ok) return bs_error_set(err, BS_EINPUT, "bs_dmesh_from_mesh: no mesh on rank 0");
  DM dm = NULL;
  PetscSection sec = NULL;
  Vec ids = NULL;
  int rc = dm_from_cells(m, &dm, err);
  if (!rc) rc = labels_from_groups(dm, m, n_groups, err);
  if (!rc) rc = id_field(dm, &sec, &ids, err);
  if (rc) {
    DMDestroy(&dm);
    PetscSectionDestroy(&sec);
    VecDestroy(&ids);
    return rc;
  }
  return finish(dm, sec, ids, refine_times, out, err);
}

int bs_dmesh_read_msh(const char *path, int refine_times, bs_dmesh **out, bs_error *err) {
  if (!out || !path) return bs_error_set(err, BS_EINPUT, "bs_dmesh_read_msh: path or out is NULL");
  *out = NULL;
  int readable = 0;
  if (bs_dist_rank() == 0) {
    FILE *f = fopen(path, "rb");
    readable = f != NULL;
    if (f) fclose(f);
  }
  MPI_Bcast(&readable, 1, MPI_INT, 0, PETSC_COMM_WORLD);
  if (!readable) return bs_error_set(err, BS_EIO, "%s: cannot open the mesh file", path);
  BS_PETSC_TRY(PetscOptionsSetValue(NULL, "-dm_plex_gmsh_use_regions", "true"), err);
  DM dm = NULL;
  PetscErrorCode ierr = DMPlexCreateGmshFromFile(PETSC_COMM_WORLD, path, PETSC_TRUE, &dm);
  PetscOptionsClearValue(NULL, "-dm_plex_gmsh_use_regions");
  if (ierr) {
    int rc = bs__petsc_error(ierr, "DMPlexCreateGmshFromFile", err);
    bs_error_prefix(err, "%s", path);
    return rc == BS_EINTERNAL ? BS_EINPUT : rc;
  }
  int rc = finish(dm, NULL, NULL, refine_times, out, err);
  if (rc) bs_error_prefix(err, "%s", path);
  return rc;
}

int bs_dmesh_load(const char *spec, int refine_times, bs_dmesh **out, bs_error *err) {
  if (!out || !spec) return bs_error_set(err, BS_EINPUT, "bs_dmesh_load: spec or out is NULL");
  *out = NULL;
  if (refine_times < 0) return bs_error_set(err, BS_EINPUT, "%s: refine = %d, need >= 0", spec, refine_times);
  if (strncmp(spec, "box:", 4) != 0 && strcmp(spec, "box") != 0) return bs_dmesh_read_msh(spec, refine_times, out, err);
  int cells[3];
  double size[3];
  int rc = bs_mesh_box_spec_parse(spec, cells, size, err);
  if (rc) return rc;
  bs_mesh *m = NULL;
  if (bs_dist_rank() == 0) {
    const double lo[3] = {0, 0, 0};
    rc = bs_mesh_create_box(lo, size, cells[0], cells[1], cells[2], &m, err);
  }
  MPI_Bcast(&rc, 1, MPI_INT, 0, PETSC_COMM_WORLD);
  if (rc) {
    if (bs_dist_rank() != 0) bs_error_set(err, rc, "%s: the box could not be built on rank 0", spec);
    return rc;
  }
  rc = bs_dmesh_from_mesh(m, refine_times, out, err);
  bs_mesh_destroy(&m);
  return rc;
}

void bs_dmesh_destroy(bs_dmesh **mp) {
  if (!mp || !*mp) return;
  bs_dmesh *m = *mp;
  DMDestroy(&m->dm);
  free(m->owned);
  free(m->orig_id);
  free(m->x);
  bs_mesh_destroy(&m->local);
  free(m->local_vertex);
  for (int i = 0; i < m->n_groups; i++) {
    free(m->groups[i].name);
    free(m->groups[i].vertices);
  }
  free(m->groups);
  free(m);
  *mp = NULL;
}
