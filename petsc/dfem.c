/* dfem.c — physics/'s terms on the owned cells of a distributed mesh, summed
 * and assembled over the ranks (bs_dfem.h). */
#include <stdlib.h>
#include <string.h>

#include "bs_dfem.h"
#include "bs_dist.h"
#include "dist_internal.h"

/* Per owned tet, the index of its material (tag -> index). */
static int tet_materials(const bs_mesh *local, int n, const int *tags, int32_t *out, bs_error *err) {
  for (int32_t t = 0; t < local->n_tets; t++) {
    int k = -1;
    for (int i = 0; i < n && k < 0; i++)
      if (tags[i] >= 0 && tags[i] == local->material[t]) k = i;
    for (int i = 0; i < n && k < 0; i++)
      if (tags[i] < 0 || n == 1) k = i;
    if (k < 0) return bs_error_set(err, BS_EINPUT, "cells of material tag %d have no material", local->material[t]);
    out[t] = k;
  }
  return BS_OK;
}

/* Global block index of each local vertex (from the global section). */
static int global_blocks(bs_dfem *df, bs_error *err) {
  const bs_dmesh *m = df->mesh;
  PetscSection gs;
  BS_PETSC_TRY(DMGetGlobalSection(m->dm, &gs), err);
  df->gblock = bs_calloc((size_t)m->n_vertices + 1, sizeof *df->gblock, "global block indices", err);
  if (!df->gblock) return BS_ENOMEM;
  for (int32_t i = 0; i < m->n_vertices; i++) {
    PetscInt off;
    BS_PETSC_TRY(PetscSectionGetOffset(gs, m->vstart + i, &off), err);
    df->gblock[i] = (off >= 0 ? off : -(off + 1)) / 3;
  }
  return BS_OK;
}

static int petsc_objects(bs_dfem *df, bs_error *err) {
  DM dm = df->mesh->dm;
  BS_PETSC_TRY(DMSetMatType(dm, MATBAIJ), err);
  BS_PETSC_TRY(DMCreateMatrix(dm, &df->H), err);
  PetscInt bs = 0;
  BS_PETSC_TRY(MatGetBlockSize(df->H, &bs), err);
  if (bs != 3) return bs_error_set(err, BS_EINTERNAL, "DMCreateMatrix made block size %d, not 3", (int)bs);
  BS_PETSC_TRY(MatSetOption(df->H, MAT_NEW_NONZERO_ALLOCATION_ERR, PETSC_FALSE), err);
  BS_PETSC_TRY(DMCreateGlobalVector(dm, &df->xg), err);
  BS_PETSC_TRY(DMCreateLocalVector(dm, &df->xl), err);
  return BS_OK;
}

int bs_dfem_create(const bs_dmesh *mesh, int n_materials, const bs_material *materials, const int *material_tags,
                   bs_dfem **out, bs_error *err) {
  if (!out || !mesh || n_materials < 1 || !materials || !material_tags)
    return bs_error_set(err, BS_EINPUT, "bs_dfem_create: a NULL argument or no material");
  *out = NULL;
  bs_dfem *df = bs_calloc(1, sizeof *df, "distributed fem", err);
  int32_t *tm = bs_calloc((size_t)mesh->local->n_tets, sizeof *tm, "tet materials", err);
  int rc = df && tm ? BS_OK : BS_ENOMEM;
  if (df) df->mesh = mesh, df->n3 = 3 * (int64_t)mesh->n_vertices;
  if (!rc) rc = tet_materials(mesh->local, n_materials, material_tags, tm, err);
  if (!rc) rc = bs_fem_create(mesh->local, n_materials, materials, tm, &df->fem, err);
  free(tm);
  if (!rc) rc = bs_fem_matrix(df->fem, &df->Hm, err);
  if (!rc) {
    size_t nm = 3 * (size_t)mesh->local->n_vertices;
    df->xm = bs_calloc(nm, sizeof *df->xm, "local mesh vector", err);
    df->gm = bs_calloc(nm, sizeof *df->gm, "local mesh vector", err);
    if (!df->xm || !df->gm) rc = BS_ENOMEM;
  }
  if (!rc) rc = global_blocks(df, err);
  if (!rc) rc = petsc_objects(df, err);
  /* Every rank fails if one does (the callers go on collectively). */
  int64_t bad = rc != 0;
  if (!bs_dist_sum_i64(&bad, 1, NULL) && bad && !rc) rc = bs_error_set(err, BS_EINPUT, "another rank failed");
  if (rc) bs_dfem_destroy(&df);
  *out = df;
  return rc;
}

void bs_dfem_destroy(bs_dfem **dp) {
  if (!dp || !*dp) return;
  bs_dfem *df = *dp;
  MatDestroy(&df->H);
  VecDestroy(&df->xg);
  VecDestroy(&df->xl);
  bs_fem_destroy(&df->fem);
  bs_bsr_destroy(&df->Hm);
  free(df->xm);
  free(df->gm);
  free(df->gblock);
  free(df);
  *dp = NULL;
}

void bs_dfem_set_terms(bs_dfem *df, int n_terms, bs_term *const *terms, int statics) {
  df->n_terms = n_terms;
  df->terms = terms;
  df->statics = statics;
}

static int active(const bs_dfem *df, int i) { return !(df->statics && df->terms[i]->dynamic_only); }

void bs_dfem_mesh_vector(const bs_dfem *df, const double *x, double *xm) {
  const bs_mesh *lm = df->mesh->local;
  for (int32_t i = 0; i < lm->n_vertices; i++)
    memcpy(xm + 3 * (size_t)i, x + 3 * (size_t)df->mesh->local_vertex[i], 3 * sizeof(double));
}

void bs_dfem_from_mesh_vector(const bs_dfem *df, const double *xm, double *x) {
  const bs_mesh *lm = df->mesh->local;
  for (int32_t i = 0; i < lm->n_vertices; i++)
    memcpy(x + 3 * (size_t)df->mesh->local_vertex[i], xm + 3 * (size_t)i, 3 * sizeof(double));
}

static void to_mesh(bs_dfem *df, const double *x) { bs_dfem_mesh_vector(df, x, df->xm); }

/* NOT_EVALUABLE on every rank if on one. */
static int agree(int status, bs_error *err) {
  int64_t s = status != BS_TERM_OK;
  int rc = bs_dist_sum_i64(&s, 1, err);
  return rc ? rc : (s ? BS_TERM_NOT_EVALUABLE : BS_TERM_OK);
}

int bs_dfem_value(bs_dfem *df, const double *x, double *E, bs_error *err) {
  to_mesh(df, x);
  double e = 0;
  int st = BS_TERM_OK;
  for (int i = 0; i < df->n_terms && st == BS_TERM_OK; i++) {
    double ei = 0;
    if (active(df, i)) st = df->terms[i]->ops->value(df->terms[i], df->xm, &ei);
    e += ei;
  }
  int rc = agree(st, err);
  if (rc) return rc;
  rc = bs_dist_sum(&e, 1, err);
  *E = e;
  return rc;
}

int bs_dfem_assemble(const bs_dfem *df, const double *c, double *out, bs_error *err) {
  PetscScalar *a;
  BS_PETSC_TRY(VecGetArray(df->xl, &a), err);
  memcpy(a, c, (size_t)df->n3 * sizeof(double));
  BS_PETSC_TRY(VecRestoreArray(df->xl, &a), err);
  BS_PETSC_TRY(VecZeroEntries(df->xg), err);
  BS_PETSC_TRY(DMLocalToGlobal(df->mesh->dm, df->xl, ADD_VALUES, df->xg), err);
  return bs_dfem_from_global(df, df->xg, out, err);
}

int bs_dfem_gradient(bs_dfem *df, const double *x, double *E, double *g, bs_error *err) {
  to_mesh(df, x);
  const bs_mesh *lm = df->mesh->local;
  memset(df->gm, 0, 3 * (size_t)lm->n_vertices * sizeof(double));
  double e = 0;
  int st = BS_TERM_OK;
  for (int i = 0; i < df->n_terms && st == BS_TERM_OK; i++) {
    double ei = 0;
    if (active(df, i)) st = df->terms[i]->ops->gradient(df->terms[i], df->xm, &ei, df->gm);
    e += ei;
  }
  int rc = agree(st, err);
  if (rc) return rc;
  if ((rc = bs_dist_sum(&e, 1, err))) return rc;
  *E = e;
  memset(g, 0, (size_t)df->n3 * sizeof(double));
  for (int32_t i = 0; i < lm->n_vertices; i++)
    memcpy(g + 3 * (size_t)df->mesh->local_vertex[i], df->gm + 3 * (size_t)i, 3 * sizeof(double));
  return bs_dfem_assemble(df, g, g, err);
}

/* The local fem Hessian's blocks into df->H (fixed rows / columns left out),
 * with an identity block for each owned fixed vertex. */
static int scatter_hessian(bs_dfem *df, const uint8_t *mask, bs_error *err) {
  const bs_bsr *A = df->Hm;
  const int32_t *lv = df->mesh->local_vertex;
  for (int32_t i = 0; i < A->n; i++) {
    if (mask && !mask[lv[i]]) continue;
    PetscInt gi = df->gblock[lv[i]];
    for (int32_t s = A->row_ptr[i]; s < A->row_ptr[i + 1]; s++) {
      if (mask && !mask[lv[A->col[s]]]) continue;
      PetscInt gj = df->gblock[lv[A->col[s]]];
      BS_PETSC_TRY(MatSetValuesBlocked(df->H, 1, &gi, 1, &gj, A->val + 9 * (size_t)s, ADD_VALUES), err);
    }
  }
  static const double eye[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  for (int32_t v = 0; mask && v < df->mesh->n_vertices; v++)
    if (!mask[v] && df->mesh->owned[v])
      BS_PETSC_TRY(MatSetValuesBlocked(df->H, 1, &df->gblock[v], 1, &df->gblock[v], eye, ADD_VALUES), err);
  return BS_OK;
}

int bs_dfem_hessian(bs_dfem *df, const double *x, const uint8_t *mask, bs_error *err) {
  return bs_dfem_hessian_with(df, x, mask, NULL, NULL, err);
}

int bs_dfem_hessian_with(bs_dfem *df, const double *x, const uint8_t *mask, bs_dfem_hessian_fn fn, void *ctx,
                         bs_error *err) {
  return bs_dfem_hessian_model(df, x, NULL, mask, fn, ctx, err);
}

int bs_dfem_hessian_model(bs_dfem *df, const double *x, const double *g, const uint8_t *mask, bs_dfem_hessian_fn fn,
                          void *ctx, bs_error *err) {
  to_mesh(df, x);
  if (g) bs_dfem_mesh_vector(df, g, df->gm); /* df->gm: free between gradients */
  bs_bsr_zero(df->Hm);
  int st = BS_TERM_OK;
  for (int i = 0; i < df->n_terms && st == BS_TERM_OK; i++) {
    const bs_term *t = df->terms[i];
    if (!active(df, i)) continue;
    st = g && t->ops->hessian_g ? t->ops->hessian_g(t, df->xm, df->gm, df->Hm) : t->ops->hessian(t, df->xm, df->Hm);
  }
  int rc = agree(st, err);
  if (rc) return rc;
  if (fn) fn(df->Hm, ctx);
  BS_PETSC_TRY(MatZeroEntries(df->H), err);
  rc = scatter_hessian(df, mask, err);
  if (rc) return rc;
  BS_PETSC_TRY(MatAssemblyBegin(df->H, MAT_FINAL_ASSEMBLY), err);
  BS_PETSC_TRY(MatAssemblyEnd(df->H, MAT_FINAL_ASSEMBLY), err);
  return BS_OK;
}

int bs_dfem_dot(const bs_dfem *df, const double *a, const double *b, double *out, bs_error *err) {
  double s = 0;
  for (int32_t v = 0; v < df->mesh->n_vertices; v++)
    if (df->mesh->owned[v])
      for (int k = 0; k < 3; k++) s += a[3 * (size_t)v + k] * b[3 * (size_t)v + k];
  int rc = bs_dist_sum(&s, 1, err);
  *out = s;
  return rc;
}

int bs_dfem_to_global(const bs_dfem *df, const double *x, Vec xg, bs_error *err) {
  PetscScalar *a;
  BS_PETSC_TRY(VecGetArray(df->xl, &a), err);
  memcpy(a, x, (size_t)df->n3 * sizeof(double));
  BS_PETSC_TRY(VecRestoreArray(df->xl, &a), err);
  BS_PETSC_TRY(DMLocalToGlobal(df->mesh->dm, df->xl, INSERT_VALUES, xg), err);
  return BS_OK;
}

int bs_dfem_from_global(const bs_dfem *df, Vec xg, double *x, bs_error *err) {
  BS_PETSC_TRY(DMGlobalToLocal(df->mesh->dm, xg, INSERT_VALUES, df->xl), err);
  const PetscScalar *a;
  BS_PETSC_TRY(VecGetArrayRead(df->xl, &a), err);
  memcpy(x, a, (size_t)df->n3 * sizeof(double));
  BS_PETSC_TRY(VecRestoreArrayRead(df->xl, &a), err);
  return BS_OK;
}

int bs_dfem_consistent(const bs_dfem *df, double *x, bs_error *err) {
  int rc = bs_dfem_to_global(df, x, df->xg, err);
  return rc ? rc : bs_dfem_from_global(df, df->xg, x, err);
}
