/* bs_fem.h — the per-mesh finite element cache of bigstep (deal.II's FEValues
 * and DoFHandler for P1 tets, 3 dofs per vertex).
 *
 * A bs_fem is built once per mesh and holds:
 *  - per tet: the rest-shape inverse Dm⁻¹ (row-major 3x3, Dm = [X1-X0, X2-X0,
 *    X3-X0]) and the rest volume V; F = Ds Dm⁻¹ at a configuration;
 *  - per tet: its material index into the materials given at creation;
 *  - the per-tet arrays are stored in POSITION order, the order of the chunks
 *    below (chunk_tets[k]: the tet at position k; tet_pos[t]: the position of
 *    tet t), with the tets' vertices copied in that order (tets), so that the
 *    kernels read a chunk's data contiguously;
 *  - per vertex: the lumped mass m_v = Σ ρ V / 4 over the tets around v;
 *  - the 3x3-block sparsity pattern of the vertex graph (solver's bs_bsr),
 *    built once, and for each tet the 16 block slots (a, b) it adds into, so
 *    that assembly is a scatter with no search;
 *  - the tets grouped into chunks of at most BS_FEM_CHUNK tets that are
 *    close in the mesh (each grown breadth-first through shared vertices from
 *    the first tet not yet taken), and a colouring of the chunks (no two
 *    chunks of a colour share a vertex). Assembly runs the colours in
 *    sequence and the chunks of a colour in parallel, each chunk's tets in
 *    ascending order: no race, and a summation order that does not depend on
 *    the thread count, so gradients and Hessians are bitwise identical with 1
 *    or N threads. A chunk's scatter stays within a few cache-resident matrix
 *    rows whatever the numbering; a reordered mesh (bs_mesh_reorder) also
 *    keeps those rows close in memory.
 *
 * Quadratic tets (mesh->tets10 set, bs_tet10.h): order 2, 3 dofs per node
 * (mesh->n_vertices nodes, corners and midside nodes). Per tet in MESH order
 * (no chunks or colours: n_chunks = n_colors = 0; Dm_inv, tets, tet_pos are
 * NULL): its rest gradients and weights at its quadrature points (q_ptr,
 * q_dNdX, q_wdetJ), the 4-point degree-2 rule for a straight tet (every
 * midside node at its edge's midpoint, as bs_tet10_mesh makes them; the rule
 * integrates the linear model's stiffness B^T C B exactly there), the
 * 14-point degree-5 rule for a curved one; its rest volume; 100 block slots
 * (10 a + b). The mass per node is HRZ-lumped (bs_tet10_mass_hrz: the
 * diagonal of the consistent mass scaled to the element's mass, positive;
 * row-sum lumping would give the vertices negative mass, -rho V / 20 on a
 * straight tet10); load[v] = sum over tets of rho int N_v dX (kg), the
 * weights of the consistent body load (gravity: f_v = load[v] g; per
 * straight tet10, -rho V/20 at each vertex and rho V/5 at each edge node).
 * Energy, gradient and Hessian go tet by tet in mesh order on one thread
 * (the same sums whatever the thread count), each tet through
 * bs_tet10_energy_grad / bs_tet10_hessian with the fem's psd modes (auto:
 * by the tet10's rest volume, as for tet4). bs_fem_scatter_hessian and
 * bs_fem_gather are for tet4 only.
 *
 * Ownership: bs_fem_create returns an object owned by the caller (free with
 * bs_fem_destroy); it keeps a pointer to the mesh and a copy of the materials,
 * and the mesh must outlive it. Evaluation allocates nothing: the energy's
 * partial sums go to a scratch array of the fem, so one energy or gradient
 * evaluation runs at a time per fem (each is parallel inside). Units: SI
 * (kg, m, s, Pa).
 */
#ifndef BS_FEM_H
#define BS_FEM_H

#include <stdint.h>

#include "bs_base.h"
#include "bs_bsr.h"
#include "bs_material.h"
#include "bs_mesh.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct bs_fem {
  const bs_mesh *mesh;
  int32_t n_vertices, n_tets;
  double *Dm_inv;       /* 9 per position                                    */
  double *volume;       /* per position, rest volume (> 0)                   */
  double *mass;         /* per vertex, lumped                                */
  double total_mass;
  int n_materials;
  bs_material *materials;
  int32_t *tet_material;/* per position: index into materials                 */
  bs_bsr *pattern;      /* the block pattern: structure only, val is NULL
                           (make matrices with bs_fem_matrix)                */
  int32_t *slots;       /* 16 per position: slot of block (a, b) at 4*a + b  */
  int32_t *tets;        /* 4 per position: the tet's vertices (mesh order)   */
  int32_t *tet_pos;     /* per tet: its position                             */
  int32_t n_chunks;
  int32_t *chunk_ptr;   /* n_chunks + 1, positions of each chunk             */
  int32_t *chunk_tets;  /* per position: its tet; tets grouped by chunk,
                           ascending in a chunk                              */
  int n_colors;
  int32_t *color_ptr;   /* n_colors + 1, into color_chunks                   */
  int32_t *color_chunks;/* chunks grouped by colour, ascending in a colour   */
  double *partial;      /* scratch: per-block / per-chunk energy sums of one */
                        /* evaluation (so one evaluation at a time per fem)  */
  int order;            /* 1: tet4; 2: quadratic tets (above)               */
  double *load;         /* order 2: per node, rho int N_v dX (kg), gravity's */
                        /* weights; NULL for order 1 (gravity weighs by mass) */
  int32_t *q_ptr;       /* order 2: n_tets + 1, each tet's first point       */
  double *q_dNdX;       /* order 2: 30 per point, dN_a/dX_j at [3 a + j]     */
  double *q_wdetJ;      /* order 2: per point, w_q det J_q (m^3)             */
} bs_fem;

/* Most tets in a chunk (a multiple of BS_MATERIAL_BATCH). */
#define BS_FEM_CHUNK 512

/* Builds the cache. tet_material[t] (NULL: all 0) indexes materials[0..n_materials).
 * Errors: a material index out of range names the tet; a tet with
 * non-positive rest volume names the tet. */
int bs_fem_create(const bs_mesh *mesh, int n_materials, const bs_material *materials,
                  const int32_t *tet_material, bs_fem **out, bs_error *err);
void bs_fem_destroy(bs_fem **fem);

/* A new matrix with the fem's pattern (zeroed). */
int bs_fem_matrix(const bs_fem *fem, bs_bsr **out, bs_error *err);

/* Gathers the 12 coordinates of tet t from x (3 per vertex). */
static inline void bs_fem_gather(const bs_fem *fem, const double *x, int32_t t, double xt[12]) {
  const int32_t *tv = fem->mesh->tets + 4 * t;
  for (int a = 0; a < 4; a++)
    for (int k = 0; k < 3; k++) xt[3 * a + k] = x[3 * tv[a] + k];
}

/* Adds tet t's 12x12 (row-major) matrix into H through its slots (t a tet of
 * the mesh, not a position). */
void bs_fem_scatter_hessian(const bs_fem *fem, int32_t t, const double He[144], double scale, bs_bsr *H);

/* Elastic energy Φ_e(x) (sum over tets, in an order that does not depend on
 * the thread count: the value is bitwise the same with 1 or N threads). */
double bs_fem_elastic_energy(const bs_fem *fem, const double *x);

/* Φ_e(x) returned and its gradient ADDED into g (3 per vertex); both bitwise
 * the same with 1 or N threads (Φ_e may differ from bs_fem_elastic_energy's
 * in the last bits: another summation order). */
double bs_fem_elastic_gradient(const bs_fem *fem, const double *x, double *g);

/* scale * ∂²Φ_e/∂x² ADDED into H (fem pattern). project_psd: the
 * definiteness fix of every tet's Hessian (a bs_psd_mode, bs_material.h:
 * BS_PSD_NONE exact, BS_PSD_ALL projected onto the PSD cone, ...). */
void bs_fem_elastic_hessian(const bs_fem *fem, const double *x, bs_psd_mode project_psd, double scale, bs_bsr *H);

/* As bs_fem_elastic_hessian (scale applied) with the definiteness fix by
 * tet: BS_PSD_INVERTED for a tet of material m whose rest volume is <=
 * vmax[m] (n_materials entries; INFINITY: all of them), BS_PSD_NONE for the
 * others. */
void bs_fem_elastic_hessian_auto(const bs_fem *fem, const double *x, const double *vmax, double scale, bs_bsr *H);

/* As bs_fem_elastic_hessian with one scale per material: material_scale[m] *
 * ∂²Φ_e/∂x² over the tets of material m ADDED into H; tets of a material with
 * scale 0 are skipped (not evaluated). */
void bs_fem_elastic_hessian_scaled(const bs_fem *fem, const double *x, bs_psd_mode project_psd,
                                   const double *material_scale, bs_bsr *H);

/* Number of tets with det F <= 0 at x (order 2: at some quadrature point);
 * min det F in *min_detF (may be NULL). */
int32_t bs_fem_count_inverted(const bs_fem *fem, const double *x, double *min_detF);

/* Order 2: tet t's rest cache (bs_tet10.h, an internal header; the rule of
 * the fem, its points' gradients and weights) into *r: BS_OK, or BS_EINPUT
 * for an order-1 fem or t out of range. */
struct bs_tet10_rest;
int bs_fem_tet10_rest(const bs_fem *fem, int32_t t, struct bs_tet10_rest *r);
/* Order 2: the 30 coordinates of tet t's 10 nodes (VTK order) from x. */
void bs_fem_tet10_gather(const bs_fem *fem, const double *x, int32_t t, double xt[30]);

#ifdef __cplusplus
}
#endif
#endif
