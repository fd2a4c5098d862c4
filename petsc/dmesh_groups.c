/* dmesh_groups.c — the physical groups of a distributed DMPlex: one per
 * (label, value) of the labels that name groups, the same table on every rank
 * (label names from rank 0, values united over the ranks, dimension the
 * largest depth of a labelled point); and the group and volume sums of
 * bs_dmesh.h. */
#include <stdlib.h>
#include <string.h>

#include "bs_dist.h"
#include "dist_internal.h"
#include "dmesh_internal.h"

/* Labels PETSc makes for itself (or for unnamed Gmsh groups), not groups. */
static int internal_label(const char *name) {
  static const char *names[] = {"depth", "celltype", "Cell Sets", "Face Sets", "Vertex Sets", "Edge Sets", "marker"};
  for (size_t i = 0; i < sizeof names / sizeof *names; i++)
    if (!strcmp(name, names[i])) return 1;
  return 0;
}

/* Rank 0's group label names, '\0'-separated in buf (every rank). */
static int label_names(DM dm, char *buf, int cap, int *n_names, bs_error *err) {
  int len = 0, n = 0;
  if (bs_dist_rank() == 0) {
    PetscInt nl;
    BS_PETSC_TRY(DMGetNumLabels(dm, &nl), err);
    for (PetscInt i = 0; i < nl; i++) {
      const char *name;
      BS_PETSC_TRY(DMGetLabelName(dm, i, &name), err);
      int l = (int)strlen(name) + 1;
      if (internal_label(name)) continue;
      if (len + l > cap) return bs_error_set(err, BS_EINPUT, "more group names than %d bytes hold", cap);
      memcpy(buf + len, name, (size_t)l);
      len += l;
      n++;
    }
  }
  int hdr[2] = {len, n};
  MPI_Bcast(hdr, 2, MPI_INT, 0, PETSC_COMM_WORLD);
  MPI_Bcast(buf, hdr[0], MPI_CHAR, 0, PETSC_COMM_WORLD);
  *n_names = hdr[1];
  return BS_OK;
}

/* The values of label lab over all ranks, sorted and unique (caller frees). */
static int united_values(DMLabel lab, int **vals, int *n, bs_error *err) {
  IS is = NULL;
  PetscInt nl = 0;
  const PetscInt *lv = NULL;
  if (lab) BS_PETSC_TRY(DMLabelGetNonEmptyStratumValuesIS(lab, &is), err);
  if (is) BS_PETSC_TRY(ISGetLocalSize(is, &nl), err);
  if (is) BS_PETSC_TRY(ISGetIndices(is, &lv), err);
  int size = bs_dist_size(), mine = (int)nl, total = 0;
  int *counts = calloc((size_t)size, sizeof *counts), *displs = calloc((size_t)size, sizeof *displs);
  int *local = calloc((size_t)mine + 1, sizeof *local);
  if (!counts || !displs || !local) return bs_error_set(err, BS_ENOMEM, "out of memory uniting label values");
  for (int i = 0; i < mine; i++) local[i] = (int)lv[i];
  if (is) ISRestoreIndices(is, &lv);
  ISDestroy(&is);
  MPI_Allgather(&mine, 1, MPI_INT, counts, 1, MPI_INT, PETSC_COMM_WORLD);
  for (int r = 0; r < size; r++) displs[r] = total, total += counts[r];
  *vals = calloc((size_t)total + 1, sizeof **vals);
  if (*vals) MPI_Allgatherv(local, mine, MPI_INT, *vals, counts, displs, MPI_INT, PETSC_COMM_WORLD);
  free(counts), free(displs), free(local);
  if (!*vals) return bs_error_set(err, BS_ENOMEM, "out of memory uniting label values");
  qsort(*vals, (size_t)total, sizeof **vals, bs_cmp_i32);
  int u = 0;
  for (int i = 0; i < total; i++)
    if (u == 0 || (*vals)[u - 1] != (*vals)[i]) (*vals)[u++] = (*vals)[i];
  *n = u;
  return BS_OK;
}

/* Group membership on every local vertex as its owner sees it. The owner
 * holds the vertex's whole star (overlap 1), hence every labelled face or
 * edge through it; a ghost in the overlap's outer layer may hold none of them
 * (a cell that meets the group's surface at that vertex only), and would
 * otherwise leave the group: then the group's vertex set, the scripted mask,
 * and the vectors built from them would differ between owner and ghost. */
static int owner_flags(const bs_dmesh *m, uint8_t *in, bs_error *err) {
  Vec l, g;
  PetscScalar *a;
  BS_PETSC_TRY(DMGetLocalVector(m->dm, &l), err);
  BS_PETSC_TRY(DMGetGlobalVector(m->dm, &g), err);
  BS_PETSC_TRY(VecGetArray(l, &a), err);
  for (int32_t v = 0; v < m->n_vertices; v++) a[3 * v] = a[3 * v + 1] = a[3 * v + 2] = in[v];
  BS_PETSC_TRY(VecRestoreArray(l, &a), err);
  BS_PETSC_TRY(DMLocalToGlobal(m->dm, l, INSERT_VALUES, g), err);
  BS_PETSC_TRY(DMGlobalToLocal(m->dm, g, INSERT_VALUES, l), err);
  BS_PETSC_TRY(VecGetArray(l, &a), err);
  for (int32_t v = 0; v < m->n_vertices; v++) in[v] = a[3 * v] > 0.5;
  BS_PETSC_TRY(VecRestoreArray(l, &a), err);
  BS_PETSC_TRY(DMRestoreGlobalVector(m->dm, &g), err);
  BS_PETSC_TRY(DMRestoreLocalVector(m->dm, &l), err);
  return BS_OK;
}

/* Dimension (largest depth over the ranks) and local vertices of (lab, value). */
static int group_points(const bs_dmesh *m, DMLabel lab, int value, bs_dgroup *g, bs_error *err) {
  IS is = NULL;
  PetscInt np = 0, depth = -1;
  const PetscInt *pts = NULL;
  if (lab) BS_PETSC_TRY(DMLabelGetStratumIS(lab, value, &is), err);
  if (is) BS_PETSC_TRY(ISGetLocalSize(is, &np), err);
  if (is) BS_PETSC_TRY(ISGetIndices(is, &pts), err);
  uint8_t *in = bs_calloc((size_t)m->n_vertices + 1, 1, "group vertex flags", err);
  int rc = in ? BS_OK : BS_ENOMEM;
  for (PetscInt k = 0; !rc && k < np; k++) {
    PetscInt d, n = 0, *cl = NULL;
    BS_PETSC_GOTO(DMPlexGetPointDepth(m->dm, pts[k], &d), rc, err);
    depth = d > depth ? d : depth;
    BS_PETSC_GOTO(DMPlexGetTransitiveClosure(m->dm, pts[k], PETSC_TRUE, &n, &cl), rc, err);
    for (PetscInt i = 0; i < n; i++)
      if (cl[2 * i] >= m->vstart && cl[2 * i] < m->vstart + m->n_vertices) in[cl[2 * i] - m->vstart] = 1;
    BS_PETSC_GOTO(DMPlexRestoreTransitiveClosure(m->dm, pts[k], PETSC_TRUE, &n, &cl), rc, err);
  }
  int dim = (int)depth;
  MPI_Allreduce(MPI_IN_PLACE, &dim, 1, MPI_INT, MPI_MAX, PETSC_COMM_WORLD);
  if (!rc) rc = owner_flags(m, in, err);
  g->dim = dim;
  for (int32_t v = 0; !rc && v < m->n_vertices; v++) g->n_vertices += in[v];
  g->vertices = rc ? NULL : bs_calloc((size_t)g->n_vertices + 1, sizeof *g->vertices, "group vertices", err);
  if (!rc && !g->vertices) rc = BS_ENOMEM;
  for (int32_t v = 0, k = 0; !rc && v < m->n_vertices; v++)
    if (in[v]) g->vertices[k++] = v;
fail:
  free(in);
  if (is) ISRestoreIndices(is, &pts);
  ISDestroy(&is);
  return rc;
}

static int group_cmp(const void *a, const void *b) {
  const bs_dgroup *x = a, *y = b;
  if (x->dim != y->dim) return x->dim < y->dim ? -1 : 1;
  if (x->tag != y->tag) return x->tag < y->tag ? -1 : 1;
  return strcmp(x->name, y->name);
}

/* One group per value of the named label. */
static int label_groups(bs_dmesh *m, const char *name, bs_error *err) {
  DMLabel lab = NULL;
  BS_PETSC_TRY(DMGetLabel(m->dm, name, &lab), err);
  int *vals = NULL, nv = 0;
  int rc = united_values(lab, &vals, &nv, err);
  bs_dgroup *grown = rc ? NULL : realloc(m->groups, (size_t)(m->n_groups + nv + 1) * sizeof *grown);
  if (!rc && !grown) rc = bs_error_set(err, BS_ENOMEM, "out of memory for the groups of label \"%s\"", name);
  if (grown) m->groups = grown;
  for (int i = 0; !rc && i < nv; i++) {
    bs_dgroup *g = &m->groups[m->n_groups];
    memset(g, 0, sizeof *g);
    g->tag = vals[i];
    g->name = malloc(strlen(name) + 1);
    if (!g->name) rc = bs_error_set(err, BS_ENOMEM, "out of memory for group \"%s\"", name);
    else strcpy(g->name, name);
    m->n_groups++;
    if (!rc) rc = group_points(m, lab, vals[i], g, err);
  }
  free(vals);
  return rc;
}

int bs__dmesh_groups(bs_dmesh *m, bs_error *err) {
  char buf[8192];
  int n = 0, rc = label_names(m->dm, buf, (int)sizeof buf, &n, err);
  const char *name = buf;
  for (int i = 0; !rc && i < n; i++, name += strlen(name) + 1) rc = label_groups(m, name, err);
  if (!rc && m->n_groups > 1) qsort(m->groups, (size_t)m->n_groups, sizeof *m->groups, group_cmp);
  return rc;
}

const bs_dgroup *bs_dmesh_group(const bs_dmesh *m, const char *name) {
  for (int i = 0; m && name && i < m->n_groups; i++)
    if (!strcmp(m->groups[i].name, name)) return &m->groups[i];
  return NULL;
}

int bs_dmesh_volume(const bs_dmesh *m, double *volume, bs_error *err) {
  double v = bs_mesh_volume(m->local);
  int rc = bs_dist_sum(&v, 1, err);
  *volume = v;
  return rc;
}

int bs_dmesh_group_count(const bs_dmesh *m, const bs_dgroup *g, int64_t *count, bs_error *err) {
  int64_t n = 0;
  for (int32_t i = 0; i < g->n_vertices; i++) n += m->owned[g->vertices[i]];
  int rc = bs_dist_sum_i64(&n, 1, err);
  *count = n;
  return rc;
}

int bs_dmesh_group_cells(const bs_dmesh *m, const bs_dgroup *g, int64_t *count, bs_error *err) {
  int64_t n = 0;
  for (int32_t t = 0; g->dim == 3 && t < m->local->n_tets; t++) n += m->local->material[t] == g->tag;
  int rc = bs_dist_sum_i64(&n, 1, err);
  *count = n;
  return rc;
}
