/* dlinsolve.c — CG with the minimizer's exits on PETSc vectors, with block
 * Jacobi or GAMG from PETSc (bs_dlinsolve.h). Follows run_cg of
 * solver/linsolve.c step by step. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bs_dist.h"
#include "bs_dlinsolve.h"
#include "dist_internal.h"

struct bs_dlin {
  bs_dfem *df;
  bs_dpc kind;
  PC pc;
  int ready;             /* GAMG: a hierarchy was built               */
  int levels;
  double setup_seconds;
  Mat P;                 /* GAMG: the AIJ copy the hierarchy was built from */
  Vec x, r, p, q, z, xs;
  Vec free;              /* 1 on free dofs, 0 on fixed: z is masked with it */
  double *ones;          /* local vector work                           */
  PetscInt bstart, nb;   /* BJACOBI: the owned blocks of the global Vecs */
  double *minv;          /* BJACOBI: 9 per owned block, the serial pcg's inverses */
};

int bs_dlin_create(bs_dfem *df, bs_dpc kind, bs_dlin **out, bs_error *err) {
  *out = NULL;
  bs_dlin *s = bs_calloc(1, sizeof *s, "distributed linear solver", err);
  if (!s) return BS_ENOMEM;
  s->df = df;
  s->kind = kind;
  *out = s;
  Vec *v[] = {&s->x, &s->r, &s->p, &s->q, &s->z, &s->xs, &s->free};
  for (size_t i = 0; i < sizeof v / sizeof *v; i++) BS_PETSC_TRY(VecDuplicate(df->xg, v[i]), err);
  s->ones = bs_calloc((size_t)df->n3 + 1, sizeof *s->ones, "mask vector", err);
  if (!s->ones) return BS_ENOMEM;
  if (kind == BS_DPC_NONE) return BS_OK;
  if (kind == BS_DPC_BJACOBI) {
    PetscInt lo, hi;
    BS_PETSC_TRY(VecGetOwnershipRange(df->xg, &lo, &hi), err);
    s->bstart = lo / 3, s->nb = (hi - lo) / 3;
    s->minv = bs_calloc(9 * (size_t)s->nb + 9, sizeof *s->minv, "block Jacobi", err);
    return s->minv ? BS_OK : BS_ENOMEM;
  }
  BS_PETSC_TRY(PCCreate(PETSC_COMM_WORLD, &s->pc), err);
  BS_PETSC_TRY(PCSetType(s->pc, PCGAMG), err);
  BS_PETSC_TRY(PCSetOptionsPrefix(s->pc, "bs_"), err);
  BS_PETSC_TRY(PCSetFromOptions(s->pc), err);
  return BS_OK;
}

void bs_dlin_destroy(bs_dlin **sp) {
  if (!sp || !*sp) return;
  bs_dlin *s = *sp;
  PCDestroy(&s->pc);
  MatDestroy(&s->P);
  Vec *v[] = {&s->x, &s->r, &s->p, &s->q, &s->z, &s->xs, &s->free};
  for (size_t i = 0; i < sizeof v / sizeof *v; i++) VecDestroy(v[i]);
  free(s->ones);
  free(s->minv);
  free(s);
  *sp = NULL;
}

/* The rigid-body modes of the rest positions, as P's near-null space. */
static int near_null_space(bs_dlin *s, Mat P, bs_error *err) {
  Vec c;
  BS_PETSC_TRY(VecDuplicate(s->df->xg, &c), err);
  int rc = bs_dfem_to_global(s->df, s->df->mesh->x, c, err);
  MatNullSpace nns = NULL;
  if (!rc) BS_PETSC_TRY(VecSetBlockSize(c, 3), err);
  if (!rc) BS_PETSC_TRY(MatNullSpaceCreateRigidBody(c, &nns), err);
  if (!rc) BS_PETSC_TRY(MatSetNearNullSpace(P, nns), err);
  MatNullSpaceDestroy(&nns);
  VecDestroy(&c);
  return rc;
}

int bs_dlin_setup(bs_dlin *s, Mat P, bs_error *err) {
  if (s->kind != BS_DPC_GAMG) return BS_OK;
  double t = bs_seconds();
  MatDestroy(&s->P);
  /* GAMG's graph and Galerkin products want AIJ (block size 3 kept). */
  BS_PETSC_TRY(MatConvert(P, MATAIJ, MAT_INITIAL_MATRIX, &s->P), err);
  int rc = near_null_space(s, s->P, err);
  if (rc) return rc;
  BS_PETSC_TRY(PCSetOperators(s->pc, s->P, s->P), err);
  BS_PETSC_TRY(PCSetUp(s->pc), err);
  PetscInt lv = 0;
  BS_PETSC_TRY(PCMGGetLevels(s->pc, &lv), err);
  s->levels = (int)lv;
  s->ready = 1;
  s->setup_seconds = bs_seconds() - t;
  return BS_OK;
}

int bs_dlin_ready(const bs_dlin *s) { return s->kind != BS_DPC_GAMG || s->ready; }

void bs_dlin_info(const bs_dlin *s, int *levels, double *setup_seconds) {
  if (levels) *levels = s->levels;
  if (setup_seconds) *setup_seconds = s->setup_seconds;
}

/* The point-block Jacobi of H: each owned diagonal block's inverse as the
 * serial pcg makes it (bs_linsolve_block_inverse: a block left singular by
 * an active constraint is inverted in its tangent plane). */
static int block_jacobi_setup(bs_dlin *s, bs_error *err) {
  for (PetscInt i = 0; i < s->nb; i++) {
    const PetscInt b = 3 * (s->bstart + i), idx[3] = {b, b + 1, b + 2};
    double D[9];
    BS_PETSC_TRY(MatGetValues(s->df->H, 3, idx, 3, idx, D), err);
    (void)bs_linsolve_block_inverse(D, s->minv + 9 * (size_t)i);
  }
  return BS_OK;
}

/* z = M r, block by block over the owned blocks. */
static int block_jacobi_apply(bs_dlin *s, bs_error *err) {
  const PetscScalar *r;
  PetscScalar *z;
  BS_PETSC_TRY(VecGetArrayRead(s->r, &r), err);
  BS_PETSC_TRY(VecGetArray(s->z, &z), err);
  for (PetscInt i = 0; i < s->nb; i++) {
    const double *M = s->minv + 9 * (size_t)i, *ri = r + 3 * i;
    for (int a = 0; a < 3; a++) z[3 * i + a] = M[3 * a] * ri[0] + M[3 * a + 1] * ri[1] + M[3 * a + 2] * ri[2];
  }
  BS_PETSC_TRY(VecRestoreArray(s->z, &z), err);
  BS_PETSC_TRY(VecRestoreArrayRead(s->r, &r), err);
  return BS_OK;
}

/* z = M^-1 r and r.z (z = r, r.z = rr without a preconditioner). */
static int precond(bs_dlin *s, double rr, double *rz, bs_error *err) {
  if (s->kind == BS_DPC_NONE) {
    *rz = rr;
    return BS_OK;
  }
  if (s->kind == BS_DPC_BJACOBI) {
    int rc = block_jacobi_apply(s, err);
    if (rc) return rc;
  } else {
    BS_PETSC_TRY(PCApply(s->pc, s->r, s->z), err);
  }
  /* A multigrid cycle can write fixed dofs (its coarse correction): the
     iterates must stay zero there, as the serial masked solvers keep them. */
  BS_PETSC_TRY(VecPointwiseMult(s->z, s->z, s->free), err);
  BS_PETSC_TRY(VecDot(s->r, s->z, rz), err);
  return isfinite(*rz) ? BS_OK : bs_error_set(err, BS_ENUMERIC, "preconditioner gave a non-finite r.z");
}

/* Negative curvature on the first iteration: the answer is r itself, and
 * the residual ||r - H r||^2. */
static int answer_rhs(bs_dlin *s, double *rr, bs_error *err) {
  BS_PETSC_TRY(VecCopy(s->r, s->x), err);
  BS_PETSC_TRY(MatMult(s->df->H, s->x, s->q), err);
  BS_PETSC_TRY(VecAYPX(s->q, -1.0, s->r), err);
  BS_PETSC_TRY(VecDot(s->q, s->q, rr), err);
  return BS_OK;
}

typedef struct cg_state {
  double rr, rz, bx, kappa2, xs_rr, target;
  int last_ok, xs_holds, k;
} cg_state;

/* One CG iteration after q = H p, pq = p.q > 0: x, r, the downhill
 * bookkeeping (run_cg's), the convergence test (1: converged). */
static int cg_update(bs_dlin *s, cg_state *c, double pq, bs_lin_stats *st, int *done, bs_error *err) {
  const double alpha = c->rz / pq, rr_k = c->rr;
  double xx;
  BS_PETSC_TRY(VecAXPY(s->x, alpha, s->p), err);
  BS_PETSC_TRY(VecAXPY(s->r, -alpha, s->q), err);
  BS_PETSC_TRY(VecDot(s->r, s->r, &c->rr), err);
  BS_PETSC_TRY(VecDot(s->x, s->x, &xx), err);
  st->iterations = c->k + 1;
  if (!isfinite(c->rr)) return bs_error_set(err, BS_ENUMERIC, "cg: non-finite residual at iteration %d", c->k + 1);
  c->bx += alpha * c->rz;
  if (c->kappa2 > 0.0) {
    if (c->bx > 0.0 && c->bx * c->bx >= c->kappa2 * xx) {
      c->last_ok = c->k + 1;
    } else if (c->last_ok == c->k && c->k > 0) { /* x_k passed, x_{k+1} fails: keep x_k */
      BS_PETSC_TRY(VecWAXPY(s->xs, -alpha, s->p, s->x), err);
      c->xs_rr = rr_k;
      c->xs_holds = 1;
    }
  }
  *done = sqrt(c->rr) <= c->target;
  if (*done) st->converged = 1;
  return BS_OK;
}

/* The CG loop from x = 0, r = b (st filled). */
static int cg_loop(bs_dlin *s, cg_state *c, int max_it, bs_lin_stats *st, bs_error *err) {
  int rc = precond(s, c->rr, &c->rz, err);
  if (rc) return rc;
  BS_PETSC_TRY(VecCopy(s->kind == BS_DPC_NONE ? s->r : s->z, s->p), err);
  for (c->k = 0; c->k < max_it; c->k++) {
    double pq;
    BS_PETSC_TRY(MatMult(s->df->H, s->p, s->q), err);
    BS_PETSC_TRY(VecDot(s->p, s->q, &pq), err);
    if (!isfinite(pq)) return bs_error_set(err, BS_ENUMERIC, "cg: non-finite p.Hp at iteration %d", c->k + 1);
    if (pq <= 0.0) {
      st->indefinite = 1;
      return c->k == 0 ? answer_rhs(s, &c->rr, err) : BS_OK;
    }
    int done = 0;
    if ((rc = cg_update(s, c, pq, st, &done, err)) || done) return rc;
    double rz_new;
    if ((rc = precond(s, c->rr, &rz_new, err))) return rc;
    const double beta = rz_new / c->rz;
    c->rz = rz_new;
    BS_PETSC_TRY(VecAYPX(s->p, beta, s->kind == BS_DPC_NONE ? s->r : s->z), err);
  }
  return BS_OK;
}

/* s->free from the mask (NULL: all free). */
static int load_mask(bs_dlin *s, const uint8_t *mask, bs_error *err) {
  for (int64_t i = 0; i < s->df->n3; i++) s->ones[i] = !mask || mask[i / 3] ? 1.0 : 0.0;
  return bs_dfem_to_global(s->df, s->ones, s->free, err);
}

int bs_dlin_solve(bs_dlin *s, const uint8_t *mask, const double *r, double rel, int max_it, double kappa, double *d, bs_lin_stats *st,
                  bs_error *err) {
  memset(st, 0, sizeof *st);
  double t0 = bs_seconds();
  if (s->kind == BS_DPC_GAMG && !s->ready) return bs_error_set(err, BS_EINTERNAL, "GAMG used before its setup");
  int rc = s->kind == BS_DPC_BJACOBI ? block_jacobi_setup(s, err) : BS_OK;
  if (!rc) rc = load_mask(s, mask, err);
  if (!rc) rc = bs_dfem_to_global(s->df, r, s->r, err);
  if (rc) return rc;
  BS_PETSC_TRY(VecSet(s->x, 0.0), err);
  cg_state c = {0};
  BS_PETSC_TRY(VecDot(s->r, s->r, &c.rr), err);
  if (!isfinite(c.rr)) return bs_error_set(err, BS_ENUMERIC, "cg: the right-hand side is not finite");
  const double rr0 = c.rr, bnorm = sqrt(rr0);
  if (bnorm == 0.0) {
    st->converged = 1;
    memset(d, 0, (size_t)s->df->n3 * sizeof(double));
    return BS_OK;
  }
  c.target = rel * bnorm;
  c.kappa2 = kappa * kappa * rr0;
  c.xs_rr = rr0;
  if ((rc = cg_loop(s, &c, max_it, st, err))) return rc;
  if (c.kappa2 > 0.0 && st->iterations > 0 && c.last_ok != st->iterations && c.xs_holds) {
    BS_PETSC_TRY(VecCopy(s->xs, s->x), err);
    c.rr = c.xs_rr;
    st->downhill_iterate = c.last_ok;
  }
  st->rel_residual = sqrt(c.rr) / bnorm;
  rc = bs_dfem_from_global(s->df, s->x, d, err);
  st->seconds = bs_seconds() - t0;
  return rc;
}
