/* bs_tet10.h — the P2 (quadratic, 10-node) tetrahedron kernel: shape
 * functions, quadrature rules, the rest-shape cache of one element (curved
 * edges allowed), its elastic energy, gradient and Hessian for any
 * bs_material, its mass and body load, stresses at the quadrature points,
 * and the tet4 -> tet10 conversion of a linear mesh (edge midpoints).
 *
 * Node ordering (VTK_QUADRATIC_TETRA, the order of this module)
 *   0..3  the vertices, at xi = (0,0,0), (1,0,0), (0,1,0), (0,0,1);
 *   4..9  the midside nodes of the edges (0,1), (1,2), (0,2), (0,3), (1,3), (2,3).
 * Gmsh's 10-node tetrahedron (MSH element type 11) lists the same nodes
 * except that its 8 is the edge (2,3) and its 9 the edge (1,3): nodes 8 and 9
 * swapped. bs_tet10_swap_gmsh_vtk converts either way (the swap is its own
 * inverse).
 *
 * Reference element and shape functions
 *   The reference tet {xi, eta, zeta >= 0, xi + eta + zeta <= 1} (volume 1/6),
 *   barycentric L0 = 1 - xi - eta - zeta, L1 = xi, L2 = eta, L3 = zeta:
 *     vertex a:        N_a = L_a (2 L_a - 1)
 *     edge (i, j):     N   = 4 L_i L_j
 *   They interpolate (N_a(node b) = delta_ab), sum to 1 and reproduce every
 *   polynomial of degree <= 2. The geometry is isoparametric: X(xi) =
 *   sum_a N_a(xi) X_a, so a midside node off its edge's midpoint curves the
 *   element.
 *
 * Quadrature (bs_tet10_rule_get; weights sum to 1/6, the reference volume)
 *   BS_TET10_RULE_4PT_DEG2    4 points, degree 2 (Hammer, Marlowe, Stroud 1956;
 *                             Keast 1986 rule 2): the 4 permutations of the
 *                             barycentric point (a, b, b, b), a = (5 + 3 sqrt 5)/20
 *                             = 0.5854101966249685, b = (5 - sqrt 5)/20 =
 *                             0.1381966011250105, each with weight 1/24.
 *                             Exact for the linear model's stiffness on a
 *                             straight-edged tet10 (B^T C B: dN/dX is of degree 1,
 *                             the integrand of degree 2) and for the consistent body
 *                             load (N_a: degree 2). Under-integrates the mass
 *                             N_a N_b (degree 4): its mass matrix would have rank
 *                             <= 4, so bs_tet10_mass refuses it.
 *   BS_TET10_RULE_14PT_DEG5   14 points, degree 5, all weights positive
 *                             (Walkington 2000, "Quadrature on simplices of arbitrary
 *                             dimension"; the same rule as in Jaskowiec & Sukumar
 *                             2020 and Keast 1986 rule 6), barycentric orbits:
 *                               4 x (b, b, b, 1 - 3b), b = 0.09273525031089123,
 *                                   weight 0.01224884051939366
 *                               4 x (b, b, b, 1 - 3b), b = 0.3108859192633006,
 *                                   weight 0.01878132095300264
 *                               6 x (a, a, 1/2 - a, 1/2 - a), a = 0.04550370412564965,
 *                                   weight 0.007091003462846911
 *                             (digits re-derived from the moment equations to 40
 *                             places). For the consistent mass (degree 4) and for
 *                             curved elements (det J of degree 3, rational dN/dX).
 *   Keast's 11-point degree-4 rule was not taken: it has a negative weight.
 *   tests/test_tet10.c shows each rule exact on every monomial up to its degree
 *   (to 1e-14) and not exact on some monomial of degree + 1.
 *
 * The rest cache (bs_tet10_rest_init)
 *   At each quadrature point q: J = dX/dxi from the 10 rest nodes, det J, the
 *   rest gradients dN_a/dX = J^-T dN_a/dxi, and w_q det J. An element whose
 *   det J is <= 0 (or not finite) at any quadrature point or at any of its 10
 *   nodes is refused (BS_ENUMERIC, with fault BS_TET10_FOLDED_AT_POINT or
 *   BS_TET10_FOLDED_AT_NODE naming where): a midside node pushed too far along
 *   or across its edge folds the map X(xi). Since det J is a cubic in xi on a
 *   curved element, these 10 + n_points samples are a screen, not a proof of
 *   positivity everywhere (a proof needs its Bernstein coefficients). When
 *   one midside node alone is moved off a straight tet10 (the usual way to
 *   curve an element to a boundary), J is a rank-one update of the straight
 *   J0, det J is affine in xi and the screen at the vertices is exact.
 *
 * Kinematics, energy, derivatives (x: current positions, 30 doubles, node a at
 * x[3a .. 3a+2]; 3x3 matrices row-major, as in bs_material.h)
 *   F_q = sum_a x_a (dN_a/dX)^T                   (F_ij = sum_a x_{a,i} dN_a/dX_j)
 *   E   = sum_q w_q detJ_q Psi(F_q)               (J)
 *   g   = dE/dx,  g_{a,i} = sum_q w_q detJ_q sum_j P_ij(F_q) dN_a/dX_j    (N, 30)
 *   H   = d2E/dx2, H[(a,i),(b,k)] = sum_q w_q detJ_q sum_{j,l} dN_a/dX_j
 *         dP_ij/dF_kl dN_b/dX_l   (N/m, 30x30 row-major, H[30 r + c], row r =
 *         3a + i, symmetric bit for bit). project_psd (a bs_psd_mode) is applied
 *         to dP/dF per quadrature point, as on the tet4 path: with BS_PSD_ALL
 *         every term, hence H, is positive semidefinite.
 *
 * Mass and loads (density rho in kg/m^3, g in m/s^2)
 *   Consistent mass M_ab = rho int N_a N_b dX (kg, 10x10, the same for each of
 *   the 3 components). Its vertex rows sum to -rho V / 20 on a straight tet10
 *   (and its edge rows to rho V / 5): row-sum lumping would give the vertices
 *   NEGATIVE mass. The lumped mass here is HRZ (Hinton, Rock, Zienkiewicz 1976):
 *   the diagonal of M scaled so that it sums to the element mass rho V, which
 *   is positive (on a straight tet10: rho V/36 per vertex, 4 rho V/27 per edge
 *   node). The consistent body load f_a = int N_a rho g dX is likewise
 *   -rho g V / 20 at the vertices and rho g V / 5 at the edge nodes.
 *
 * Units: SI (m, kg, s, Pa, N, J). Ownership: everything here is plain values;
 * only bs_tet10_from_tet4 allocates (its outputs, freed by the caller with
 * free()). No kernel allocates, prints or exits. Status (bs_base.h): BS_OK,
 * or a negative BS_E* code with the caller's bs_error filled.
 *
 * Example (one element):
 *     bs_error err = {0};
 *     bs_material m;
 *     bs_material_init(BS_MODEL_NEO_HOOKEAN, 1e6, 0.3, 1000, &m, &err);
 *     double X[30] = {...};                     // rest nodes, VTK order
 *     bs_tet10_rest r;
 *     if (bs_tet10_rest_init(X, BS_TET10_RULE_14PT_DEG5, &r, &err) != BS_OK)
 *       return err.code;                        // r.fault says why (folded...)
 *     double g[30], H[900], M[100];
 *     double E = bs_tet10_energy_grad(&m, &r, x, g);  // x: current nodes
 *     bs_tet10_hessian(&m, &r, x, BS_PSD_ALL, H);
 *     bs_tet10_mass(&r, m.density, M, &err);
 */
#ifndef BS_TET10_H
#define BS_TET10_H

#include <stdint.h>

#include "bs_base.h"
#include "bs_material.h"
#include "bs_mesh.h"
#include "bs_stress.h"

#ifdef __cplusplus
extern "C" {
#endif

#define BS_TET10_NODES 10
#define BS_TET10_MAX_POINTS 14 /* the most points of any rule below */

/* The edges of the midside nodes 4..9, VTK order: bs_tet10_edges[k] is the
 * vertex pair of node 4 + k. */
extern const int bs_tet10_edges[6][2];
/* Reference coordinates of the 10 nodes. */
extern const double bs_tet10_ref_nodes[10][3];

/* ---- shape functions ---- */

/* N[a] = N_a(xi), a = 0..9. */
void bs_tet10_shape(const double xi[3], double N[10]);
/* dN[3a + k] = dN_a / dxi_k. */
void bs_tet10_shape_grad(const double xi[3], double dN[30]);
/* p = X(xi) = sum_a N_a(xi) X_a (a point of the element with nodes X). */
void bs_tet10_map(const double X[30], const double xi[3], double p[3]);

/* ---- quadrature ---- */

typedef enum bs_tet10_rule_id {
  BS_TET10_RULE_4PT_DEG2 = 0,  /* 4 points, degree 2 */
  BS_TET10_RULE_14PT_DEG5 = 1  /* 14 points, degree 5, positive weights */
} bs_tet10_rule_id;

typedef struct bs_tet10_rule {
  const char *name;                      /* "4pt_deg2", "14pt_deg5"          */
  int n_points, degree;                  /* exact for polynomials of degree <= degree */
  double xi[BS_TET10_MAX_POINTS][3];     /* reference coordinates            */
  double w[BS_TET10_MAX_POINTS];         /* weights (sum 1/6)                */
} bs_tet10_rule;

/* The rule id; NULL for an id outside the enum. */
const bs_tet10_rule *bs_tet10_rule_get(bs_tet10_rule_id id);

/* ---- the rest cache ---- */

/* Why bs_tet10_rest_init refused an element. */
typedef enum bs_tet10_fault {
  BS_TET10_SOUND = 0,          /* accepted                                   */
  BS_TET10_BAD_RULE,           /* the rule id is not one of the enum         */
  BS_TET10_NOT_FINITE,         /* a rest coordinate is NaN or infinite       */
  BS_TET10_FOLDED_AT_NODE,     /* det J <= 0 (or not finite) at a node       */
  BS_TET10_FOLDED_AT_POINT     /* det J <= 0 (or not finite) at a quadrature point */
} bs_tet10_fault;

/* "sound", "bad_rule", "not_finite", "folded_at_node", "folded_at_point";
 * "unknown" outside the enum. */
const char *bs_tet10_fault_name(bs_tet10_fault f);

typedef struct bs_tet10_rest {
  const bs_tet10_rule *rule;                  /* the rule (static data)       */
  int n_points;                               /* rule->n_points               */
  double dNdX[BS_TET10_MAX_POINTS][10][3];    /* dN_a/dX_j at point q (1/m)   */
  double detJ[BS_TET10_MAX_POINTS];           /* det dX/dxi at q (m^3)        */
  double wdetJ[BS_TET10_MAX_POINTS];          /* w_q det J_q (m^3)            */
  double volume;                              /* sum_q w_q det J_q (m^3)      */
  bs_tet10_fault fault;                       /* BS_TET10_SOUND when accepted */
  int fault_where;                            /* node or point of the fault; -1 */
  double fault_detJ;                          /* det J found there            */
} bs_tet10_rest;

/* Fills *out for the element with rest nodes X (30 doubles, VTK order) under
 * the rule id. BS_OK; BS_EINPUT for an unknown rule; BS_ENUMERIC for a
 * non-finite coordinate or a folded element (out->fault, out->fault_where,
 * out->fault_detJ say which and where; the message too). A refused cache has
 * n_points = 0 and volume 0: the kernels below then add nothing. */
int bs_tet10_rest_init(const double X[30], bs_tet10_rule_id rule, bs_tet10_rest *out, bs_error *err);

/* ---- kinematics and elastic energy ---- */

/* F at quadrature point q (0 <= q < r->n_points) of the configuration x. */
void bs_tet10_F(const bs_tet10_rest *r, int q, const double x[30], double F[9]);

/* E = sum_q w_q det J_q Psi(F_q). */
double bs_tet10_energy(const bs_material *m, const bs_tet10_rest *r, const double x[30]);

/* E returned; g = dE/dx (30 doubles). */
double bs_tet10_energy_grad(const bs_material *m, const bs_tet10_rest *r, const double x[30], double g[30]);

/* H = d2E/dx2 (30x30 row-major, symmetric bit for bit); project_psd: a
 * bs_psd_mode applied to dP/dF at each quadrature point. */
void bs_tet10_hessian(const bs_material *m, const bs_tet10_rest *r, const double x[30], bs_psd_mode project_psd,
                      double H[900]);

/* Stress and strain measures (bs_stress.h) at each quadrature point:
 * out[q] for q < r->n_points (the caller gives r->n_points entries). The
 * points' rest positions are bs_tet10_map(X, r->rule->xi[q]). */
void bs_tet10_stress(const bs_material *m, const bs_tet10_rest *r, const double x[30], bs_stress_fields *out);

/* ---- mass and body load ---- */

/* Consistent mass M_ab = density int N_a N_b dX (kg, 10x10 row-major).
 * BS_EINPUT if the rule's degree is < 4 (N_a N_b is of degree 4; the 4-point
 * rule makes M singular) or density is not finite and > 0. Exact on a
 * straight-edged tet10 with the 14-point rule. */
int bs_tet10_mass(const bs_tet10_rest *r, double density, double M[100], bs_error *err);

/* HRZ lumped mass (kg, 10): the diagonal of the consistent mass scaled to
 * sum to density * volume; every entry positive. Same errors as bs_tet10_mass. */
int bs_tet10_mass_hrz(const bs_tet10_rest *r, double density, double m[10], bs_error *err);

/* Consistent body load f_{a,i} = density g_i int N_a dX (N, 30 doubles);
 * exact with either rule on a straight-edged tet10 (N_a is of degree 2). */
void bs_tet10_body_load(const bs_tet10_rest *r, double density, const double g[3], double f[30]);

/* ---- node orderings and the linear -> quadratic mesh ---- */

/* Swaps nodes 8 and 9 of each of the n_tets tets of conn (10 per tet, in
 * place): Gmsh's 10-node order to VTK's, or VTK's to Gmsh's. */
void bs_tet10_swap_gmsh_vtk(int64_t n_tets, int32_t *conn);

/* The tet10 mesh of a tet4 mesh: the n_vertices vertices (3 doubles each)
 * are kept, in order, as nodes 0 .. n_vertices-1; each unique edge of the
 * tets (4 per tet) gets one node at its midpoint, numbered from n_vertices
 * in the order of the edges' sorted vertex pairs (lo, hi); tets10 lists each
 * tet's 4 vertices then its 6 edge nodes in VTK order. On success *n_nodes,
 * *nodes (3 * *n_nodes doubles) and *tets10 (10 * n_tets) are the caller's,
 * to free(). Errors (outputs then NULL / 0): BS_EINPUT for negative counts,
 * NULL arrays, a vertex index out of range, a tet with a repeated vertex, or
 * more than INT32_MAX nodes; BS_ENOMEM. */
int bs_tet10_from_tet4(int32_t n_vertices, const double *vertices, int32_t n_tets, const int32_t *tets,
                       int32_t *n_nodes, double **nodes, int32_t **tets10, bs_error *err);

/* ---- quadratic meshes (bs_mesh.tets10) ---- */

/* Makes the linear mesh m quadratic in place: bs_tet10_from_tet4's nodes
 * (the n_vertices vertices first, kept as the corners, then one node per
 * unique edge at its midpoint) become m's vertices, m->tets10 its tets in
 * VTK order, m->n_corners the old vertex count; v2t_ptr is extended (the
 * midside nodes belong to no entry of tets); every group keeps its vertices
 * and gains the midside nodes of its elements' edges (a 3-D group: the 6
 * edges of each of its tets; a 2-D group: the 3 edges of each triangle; a
 * 1-D group: each segment; a 0-D group: none), so that a face group holds
 * all 6 nodes of each of its quadratic triangles. faces, edges and v2t keep
 * naming corners only. A mesh read from a .msh of 10-node tets carries the
 * file's midside nodes (bs_mesh.midside_x): they take the place of the edge
 * midpoints (curved edges), and the list is freed. Errors: BS_EINPUT (NULL, quadratic already, not
 * finalized), those of bs_tet10_from_tet4, BS_ENOMEM; after an error m is
 * only fit to be destroyed. */
int bs_tet10_mesh(bs_mesh *m, bs_error *err);

#ifdef __cplusplus
}
#endif
#endif
