/* dmesh_local.c — what a rank needs of its part of a distributed DMPlex: the
 * dof section (3 per vertex), the local vertices with their owner flags and
 * original ids, and the bs_mesh of the cells it owns (bs_dmesh.h). */
#include <stdlib.h>
#include <string.h>

#include "bs_dist.h"
#include "dist_internal.h"
#include "dmesh_internal.h"

int bs__dmesh_ghost_points(DM dm, PetscInt pstart, PetscInt pend, uint8_t **ghost, bs_error *err) {
  *ghost = bs_calloc((size_t)(pend - pstart) + 1, 1, "ghost point flags", err);
  if (!*ghost) return BS_ENOMEM;
  PetscSF sf;
  PetscInt nroots, nleaves;
  const PetscInt *ilocal;
  const PetscSFNode *iremote;
  BS_PETSC_TRY(DMGetPointSF(dm, &sf), err);
  BS_PETSC_TRY(PetscSFGetGraph(sf, &nroots, &nleaves, &ilocal, &iremote), err);
  if (nroots < 0) return BS_OK; /* no graph: one rank */
  for (PetscInt i = 0; i < nleaves; i++) {
    PetscInt p = ilocal ? ilocal[i] : i;
    if (p >= pstart && p < pend) (*ghost)[p - pstart] = 1;
  }
  return BS_OK;
}

/* 3 dofs per vertex as the DM's local section; offsets are 3 (v - vstart). */
static int dof_section(bs_dmesh *m, PetscInt pstart, PetscInt pend, bs_error *err) {
  PetscSection s;
  BS_PETSC_TRY(PetscSectionCreate(PETSC_COMM_WORLD, &s), err);
  BS_PETSC_TRY(PetscSectionSetChart(s, pstart, pend), err);
  for (PetscInt v = m->vstart; v < m->vstart + m->n_vertices; v++) BS_PETSC_TRY(PetscSectionSetDof(s, v, 3), err);
  BS_PETSC_TRY(PetscSectionSetUp(s), err);
  BS_PETSC_TRY(DMSetLocalSection(m->dm, s), err);
  PetscSectionDestroy(&s);
  PetscSection ls;
  BS_PETSC_TRY(DMGetLocalSection(m->dm, &ls), err);
  for (PetscInt v = m->vstart; v < m->vstart + m->n_vertices; v++) {
    PetscInt off;
    BS_PETSC_TRY(PetscSectionGetOffset(ls, v, &off), err);
    if (off != 3 * (v - m->vstart))
      return bs_error_set(err, BS_EINTERNAL, "dof section: vertex point %d at offset %d, expected %d", (int)v,
                          (int)off, (int)(3 * (v - m->vstart)));
  }
  return BS_OK;
}

/* Positions, owner flags and original ids of the local vertices. */
static int vertices(bs_dmesh *m, PetscSection sec, Vec ids, const uint8_t *ghost, PetscInt pstart, bs_error *err) {
  int32_t n = m->n_vertices;
  m->owned = bs_calloc((size_t)n + 1, 1, "vertex owner flags", err);
  m->orig_id = bs_calloc((size_t)n + 1, sizeof *m->orig_id, "vertex ids", err);
  m->x = bs_calloc(3 * (size_t)n + 3, sizeof *m->x, "vertex positions", err);
  if (!m->owned || !m->orig_id || !m->x) return BS_ENOMEM;
  Vec coords;
  PetscSection cs;
  const PetscScalar *c, *id = NULL;
  BS_PETSC_TRY(DMGetCoordinatesLocal(m->dm, &coords), err);
  BS_PETSC_TRY(DMGetCoordinateSection(m->dm, &cs), err);
  BS_PETSC_TRY(VecGetArrayRead(coords, &c), err);
  if (ids) BS_PETSC_TRY(VecGetArrayRead(ids, &id), err);
  for (int32_t i = 0; i < n; i++) {
    PetscInt v = m->vstart + i, off;
    BS_PETSC_TRY(PetscSectionGetOffset(cs, v, &off), err);
    memcpy(m->x + 3 * (size_t)i, c + off, 3 * sizeof(double));
    m->owned[i] = !ghost[v - pstart];
    m->n_owned += m->owned[i];
    m->orig_id[i] = -1;
    if (id) {
      BS_PETSC_TRY(PetscSectionGetOffset(sec, v, &off), err);
      m->orig_id[i] = (int64_t)id[off];
    }
  }
  if (ids) BS_PETSC_TRY(VecRestoreArrayRead(ids, &id), err);
  BS_PETSC_TRY(VecRestoreArrayRead(coords, &c), err);
  return BS_OK;
}

/* The four local vertices of cell c (closure order). */
static int cell_vertices(const bs_dmesh *m, PetscInt c, int32_t tv[4], bs_error *err) {
  PetscInt n = 0, *pts = NULL, k = 0;
  BS_PETSC_TRY(DMPlexGetTransitiveClosure(m->dm, c, PETSC_TRUE, &n, &pts), err);
  for (PetscInt i = 0; i < n; i++) {
    PetscInt p = pts[2 * i];
    if (p >= m->vstart && p < m->vstart + m->n_vertices && k < 4) tv[k++] = (int32_t)(p - m->vstart);
  }
  BS_PETSC_TRY(DMPlexRestoreTransitiveClosure(m->dm, c, PETSC_TRUE, &n, &pts), err);
  if (k != 4) return bs_error_set(err, BS_EINPUT, "cell %d has %d vertices: only tetrahedra are supported", (int)c, (int)k);
  return BS_OK;
}

/* The 3-D groups as tet lists of the owned cells (owned_of[c - cstart]: the
 * owned index of cell c, or -1). */
static int material_groups(const bs_dmesh *m, PetscInt cstart, PetscInt cend, const int32_t *owned_of, bs_group *g3,
                           int *n3, bs_error *err) {
  *n3 = 0;
  for (int i = 0; i < m->n_groups; i++) {
    const bs_dgroup *g = &m->groups[i];
    if (g->dim != 3) continue;
    bs_group *o = &g3[(*n3)++];
    o->dim = 3, o->tag = g->tag, o->name = g->name;
    DMLabel lab;
    BS_PETSC_TRY(DMGetLabel(m->dm, g->name, &lab), err);
    IS is = NULL;
    if (lab) BS_PETSC_TRY(DMLabelGetStratumIS(lab, g->tag, &is), err);
    PetscInt np = 0;
    const PetscInt *pts = NULL;
    if (is) BS_PETSC_TRY(ISGetLocalSize(is, &np), err);
    if (is) BS_PETSC_TRY(ISGetIndices(is, &pts), err);
    o->elems = bs_calloc((size_t)np + 1, sizeof *o->elems, "material group", err);
    if (!o->elems) return BS_ENOMEM;
    for (PetscInt k = 0; k < np; k++)
      if (pts[k] >= cstart && pts[k] < cend && owned_of[pts[k] - cstart] >= 0)
        o->elems[o->n_elems++] = owned_of[pts[k] - cstart];
    if (is) ISRestoreIndices(is, &pts);
    ISDestroy(&is);
  }
  return BS_OK;
}

/* The owned cells: their vertices (renumbered over the vertices they use,
 * ascending) and material groups, as m->local. */
static int local_mesh(bs_dmesh *m, PetscInt cstart, PetscInt cend, int32_t *owned_of, int32_t n_own, bs_error *err) {
  int rc = BS_OK, n3 = 0;
  int32_t *tets = bs_calloc(4 * (size_t)n_own + 4, sizeof *tets, "owned cells", err);
  int32_t *newid = bs_calloc((size_t)m->n_vertices + 1, sizeof *newid, "local vertex map", err);
  double *xm = bs_calloc(3 * (size_t)m->n_vertices + 3, sizeof *xm, "local mesh vertices", err);
  bs_group *g3 = bs_calloc((size_t)m->n_groups + 1, sizeof *g3, "material groups", err);
  m->local_vertex = bs_calloc((size_t)m->n_vertices + 1, sizeof *m->local_vertex, "local vertex map", err);
  if (!tets || !newid || !xm || !g3 || !m->local_vertex) rc = BS_ENOMEM;
  for (PetscInt c = cstart; !rc && c < cend; c++)
    if (owned_of[c - cstart] >= 0) rc = cell_vertices(m, c, tets + 4 * (size_t)owned_of[c - cstart], err);
  int32_t nv = 0;
  if (!rc) {
    for (size_t i = 0; i < 4 * (size_t)n_own; i++) newid[tets[i]] = 1;
    for (int32_t v = 0; v < m->n_vertices; v++)
      if (newid[v]) {
        memcpy(xm + 3 * (size_t)nv, m->x + 3 * (size_t)v, 3 * sizeof(double));
        m->local_vertex[nv] = v;
        newid[v] = nv++;
      }
    for (size_t i = 0; i < 4 * (size_t)n_own; i++) tets[i] = newid[tets[i]];
    rc = material_groups(m, cstart, cend, owned_of, g3, &n3, err);
  }
  if (!rc) rc = bs_mesh_create(nv, xm, n_own, tets, n3, g3, &m->local, err);
  for (int i = 0; i < n3; i++) free(g3[i].elems);
  free(g3);
  free(tets);
  free(newid);
  free(xm);
  return rc;
}

/* Owned cells counted and indexed; a rank with none is refused on every rank. */
static int owned_cells(bs_dmesh *m, const uint8_t *ghost, PetscInt pstart, bs_error *err) {
  PetscInt cs, ce;
  BS_PETSC_TRY(DMPlexGetHeightStratum(m->dm, 0, &cs, &ce), err);
  int32_t *owned_of = bs_calloc((size_t)(ce - cs) + 1, sizeof *owned_of, "owned cell map", err);
  if (!owned_of) return BS_ENOMEM;
  int32_t n_own = 0;
  for (PetscInt c = cs; c < ce; c++) owned_of[c - cs] = ghost[c - pstart] ? -1 : n_own++;
  int64_t counts[2] = {n_own, n_own > 0 ? 0 : 1};
  int rc = bs_dist_sum_i64(counts, 2, err);
  m->n_global_cells = counts[0];
  if (!rc && counts[1] > 0)
    rc = bs_error_set(err, BS_EINPUT, "%lld of %d ranks hold no cell of the %lld-cell mesh: use fewer ranks",
                      (long long)counts[1], bs_dist_size(), (long long)counts[0]);
  if (!rc) rc = local_mesh(m, cs, ce, owned_of, n_own, err);
  free(owned_of);
  /* A rank whose local mesh failed makes every rank fail. */
  int64_t bad = rc != 0;
  if (bs_dist_sum_i64(&bad, 1, NULL) == 0 && bad && !rc)
    rc = bs_error_set(err, BS_EINPUT, "another rank could not build its part of the mesh");
  return rc;
}

int bs__dmesh_setup(DM dm, PetscSection sec, Vec ids, bs_dmesh **out, bs_error *err) {
  bs_dmesh *m = bs_calloc(1, sizeof *m, "distributed mesh", err);
  if (!m) {
    DMDestroy(&dm);
    return BS_ENOMEM;
  }
  m->dm = dm;
  PetscInt ps, pe, vs, ve;
  uint8_t *ghost = NULL;
  int rc = BS_OK;
  BS_PETSC_GOTO(DMPlexGetChart(dm, &ps, &pe), rc, err);
  BS_PETSC_GOTO(DMPlexGetDepthStratum(dm, 0, &vs, &ve), rc, err);
  m->vstart = vs;
  m->n_vertices = (int32_t)(ve - vs);
  rc = bs__dmesh_ghost_points(dm, ps, pe, &ghost, err);
  if (!rc) rc = dof_section(m, ps, pe, err);
  if (!rc) rc = vertices(m, sec, ids, ghost, ps, err);
  if (!rc) rc = bs__dmesh_groups(m, err);
  if (!rc) rc = owned_cells(m, ghost, ps, err);
  if (!rc) {
    int64_t nv = m->n_owned;
    rc = bs_dist_sum_i64(&nv, 1, err);
    m->n_global_vertices = nv;
  }
fail:
  free(ghost);
  if (rc) bs_dmesh_destroy(&m);
  *out = m;
  return rc;
}
