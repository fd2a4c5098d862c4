/* bs_dfem.h — the energy terms of physics/ evaluated on a distributed mesh:
 * energy (summed over the ranks), gradient (assembled with ADD_VALUES, then
 * made consistent on ghosts) and Hessian (a MATBAIJ of block size 3 from
 * DMCreateMatrix, preallocated from the DMPlex).
 *
 * Each rank holds a serial bs_fem of the cells it owns (bs_dmesh.local), so
 * the terms of physics/bs_terms.h (inertia, gravity, elasticity in every
 * model, damping, drag: all sums over tets or over lumped vertex masses,
 * which are sums over tets) run unchanged on it: the sum over the ranks of
 * the per-rank values is the serial value, and ADD_VALUES assembly of the
 * per-rank gradients and Hessians is the serial gradient and Hessian.
 *
 * Vectors ("local vectors") are 3 doubles per local vertex of the bs_dmesh
 * (owned and ghost, in local vertex order), CONSISTENT: a ghost entry holds
 * its owner's value. Gradients come back consistent. Dot products over local
 * vectors count owned entries only (bs_dfem_dot).
 * A mask (1 free, 0 fixed; one byte per local vertex, consistent) makes the
 * Hessian's rows and columns of fixed vertices the identity; the gradient is
 * returned unmasked (the minimizer masks).
 *
 * Ownership: the dfem borrows the bs_dmesh and the terms (which the caller
 * creates on dfem->fem and destroys after the dfem or before it, once unset);
 * it owns its fem, matrix and work vectors. Collective: every evaluation.
 * Status: BS_OK, BS_EINPUT (a material tag with no material, naming it),
 * BS_EINTERNAL (PETSc), BS_ENOMEM; evaluation returns BS_TERM_NOT_EVALUABLE (1)
 * on every rank when a term is not evaluable on some rank.
 */
#ifndef BS_DFEM_H
#define BS_DFEM_H

#include <petscmat.h>

#include "bs_dmesh.h"
#include "bs_fem.h"
#include "bs_terms.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct bs_dfem {
  const bs_dmesh *mesh;
  bs_fem *fem;           /* over mesh->local (the owned cells)                  */
  int n_terms;
  bs_term *const *terms; /* borrowed (bs_dfem_set_terms)                         */
  int statics;           /* 1: terms marked dynamic_only are skipped             */
  int64_t n3;            /* 3 * mesh->n_vertices: the length of local vectors    */
  PetscInt *gblock;      /* per local vertex: its global block (vertex) index    */
  Mat H;                 /* the Hessian (MATBAIJ, bs 3)                          */
  Vec xg, xl;            /* global and DM-local work vectors                     */
  double *xm, *gm;       /* 3 per local-mesh vertex                               */
  bs_bsr *Hm;            /* the local fem's Hessian                              */
} bs_dfem;

/* The fem of the owned cells: material i has 3-D group tag material_tags[i]
 * (a cell's material is the tag of its 3-D group); a cell of no listed tag
 * takes the first material of tag -1 (the default), or the only material
 * when n_materials = 1. */
int bs_dfem_create(const bs_dmesh *mesh, int n_materials, const bs_material *materials, const int *material_tags,
                   bs_dfem **out, bs_error *err);
void bs_dfem_destroy(bs_dfem **df);

/* The terms evaluated (borrowed: they must outlive their use here). statics =
 * 1 leaves out terms marked dynamic_only. */
void bs_dfem_set_terms(bs_dfem *df, int n_terms, bs_term *const *terms, int statics);

/* E(x) over the ranks. */
int bs_dfem_value(bs_dfem *df, const double *x, double *E, bs_error *err);
/* E(x) and g = dE/dx (written, consistent). */
int bs_dfem_gradient(bs_dfem *df, const double *x, double *E, double *g, bs_error *err);
/* df->H = d2E/dx2 at x, fixed vertices' rows and columns the identity (mask
 * NULL: none fixed). */
int bs_dfem_hessian(bs_dfem *df, const double *x, const uint8_t *mask, bs_error *err);

/* As bs_dfem_hessian, with fn(Hm, ctx) applied to this rank's partial
 * Hessian (dfem->Hm: the terms' Hessian over the owned cells, in the order
 * of dfem->fem's mesh) before its blocks are assembled into df->H. fn NULL:
 * bs_dfem_hessian. The sum over the ranks of what fn leaves is what df->H
 * holds: a linear map of Hm (J^T Hm J) gives the map of the whole Hessian;
 * a block that fn adds must be added on one rank only. Not called when a
 * term is not evaluable. */
typedef void (*bs_dfem_hessian_fn)(bs_bsr *Hm, void *ctx);
int bs_dfem_hessian_with(bs_dfem *df, const double *x, const uint8_t *mask, bs_dfem_hessian_fn fn, void *ctx,
                         bs_error *err);
/* The same with the Newton model of the terms that offer hessian_g
 * (bs_terms.h) in place of their Hessians, given g, grad E(x) assembled (as
 * bs_dfem_gradient gives it); g NULL: bs_dfem_hessian_with. */
int bs_dfem_hessian_model(bs_dfem *df, const double *x, const double *g, const uint8_t *mask, bs_dfem_hessian_fn fn,
                          void *ctx, bs_error *err);

/* Sum over the ranks of a.b over owned entries. */
int bs_dfem_dot(const bs_dfem *df, const double *a, const double *b, double *out, bs_error *err);

/* Local vector <-> global Vec (owned entries; ghosts filled by the scatter). */
int bs_dfem_to_global(const bs_dfem *df, const double *x, Vec xg, bs_error *err);
int bs_dfem_from_global(const bs_dfem *df, Vec xg, double *x, bs_error *err);

/* The local vector x in the vertex order of dfem->fem's mesh (mesh->local),
 * the order of the arrays terms read (bs_step_data x_hat, x_n): xm has 3 per
 * local-mesh vertex. Not collective. */
void bs_dfem_mesh_vector(const bs_dfem *df, const double *x, double *xm);

/* The inverse of bs_dfem_mesh_vector: the entries of x of the local-mesh
 * vertices set from xm (the other local vertices' left as they are). Not
 * collective. */
void bs_dfem_from_mesh_vector(const bs_dfem *df, const double *xm, double *x);

/* x made consistent: every ghost entry set to its owner's value (through
 * the global Vec). */
int bs_dfem_consistent(const bs_dfem *df, double *x, bs_error *err);

/* Sum over the ranks of a local contribution c (3 per local vertex, ghost
 * entries partial) into the consistent vector out (may alias c). */
int bs_dfem_assemble(const bs_dfem *df, const double *c, double *out, bs_error *err);

#ifdef __cplusplus
}
#endif
#endif
