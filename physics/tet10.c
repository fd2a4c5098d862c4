/* tet10.c — the P2 tetrahedron kernel (see bs_tet10.h). */
#include "bs_tet10.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

const int bs_tet10_edges[6][2] = {{0, 1}, {1, 2}, {0, 2}, {0, 3}, {1, 3}, {2, 3}};

const double bs_tet10_ref_nodes[10][3] = {{0, 0, 0},     {1, 0, 0},     {0, 1, 0},     {0, 0, 1},
                                          {0.5, 0, 0},   {0.5, 0.5, 0}, {0, 0.5, 0},   {0, 0, 0.5},
                                          {0.5, 0, 0.5}, {0, 0.5, 0.5}};

/* ---- shape functions ---- */

void bs_tet10_shape(const double xi[3], double N[10]) {
  const double L[4] = {1.0 - xi[0] - xi[1] - xi[2], xi[0], xi[1], xi[2]};
  for (int a = 0; a < 4; a++) N[a] = L[a] * (2.0 * L[a] - 1.0);
  for (int k = 0; k < 6; k++) N[4 + k] = 4.0 * L[bs_tet10_edges[k][0]] * L[bs_tet10_edges[k][1]];
}

void bs_tet10_shape_grad(const double xi[3], double dN[30]) {
  const double L[4] = {1.0 - xi[0] - xi[1] - xi[2], xi[0], xi[1], xi[2]};
  /* dL[a][k] = dL_a / dxi_k */
  static const double dL[4][3] = {{-1, -1, -1}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  for (int a = 0; a < 4; a++)
    for (int k = 0; k < 3; k++) dN[3 * a + k] = (4.0 * L[a] - 1.0) * dL[a][k];
  for (int e = 0; e < 6; e++) {
    const int i = bs_tet10_edges[e][0], j = bs_tet10_edges[e][1];
    for (int k = 0; k < 3; k++) dN[3 * (4 + e) + k] = 4.0 * (dL[i][k] * L[j] + L[i] * dL[j][k]);
  }
}

void bs_tet10_map(const double X[30], const double xi[3], double p[3]) {
  double N[10];
  bs_tet10_shape(xi, N);
  for (int k = 0; k < 3; k++) {
    p[k] = 0.0;
    for (int a = 0; a < 10; a++) p[k] += N[a] * X[3 * a + k];
  }
}

/* ---- quadrature (the values and sources are in bs_tet10.h) ---- */

#define R4A 0.58541019662496845446 /* (5 + 3 sqrt 5) / 20 */
#define R4B 0.13819660112501051518 /* (5 - sqrt 5) / 20   */
#define R14B1 0.09273525031089122640
#define R14C1 0.72179424906732632079 /* 1 - 3 R14B1 */
#define R14W1 0.01224884051939365826
#define R14B2 0.31088591926330060980
#define R14C2 0.06734224221009817061 /* 1 - 3 R14B2 */
#define R14W2 0.01878132095300264180
#define R14A3 0.04550370412564964949
#define R14D3 0.45449629587435035051 /* 1/2 - R14A3 */
#define R14W3 0.00709100346284691107

static const bs_tet10_rule rules[2] = {
    {"4pt_deg2",
     4,
     2,
     {{R4B, R4B, R4B}, {R4A, R4B, R4B}, {R4B, R4A, R4B}, {R4B, R4B, R4A}},
     {1.0 / 24, 1.0 / 24, 1.0 / 24, 1.0 / 24}},
    {"14pt_deg5",
     14,
     5,
     {/* (b, b, b, 1-3b) orbits: xi = (L1, L2, L3), L0 = 1 - xi - eta - zeta */
      {R14B1, R14B1, R14B1},
      {R14C1, R14B1, R14B1},
      {R14B1, R14C1, R14B1},
      {R14B1, R14B1, R14C1},
      {R14B2, R14B2, R14B2},
      {R14C2, R14B2, R14B2},
      {R14B2, R14C2, R14B2},
      {R14B2, R14B2, R14C2},
      /* (a, a, 1/2-a, 1/2-a) orbit: L0 = L1 = a (three), L0 = L1 = 1/2 - a (three) */
      {R14A3, R14D3, R14D3},
      {R14D3, R14A3, R14D3},
      {R14D3, R14D3, R14A3},
      {R14D3, R14A3, R14A3},
      {R14A3, R14D3, R14A3},
      {R14A3, R14A3, R14D3}},
     {R14W1, R14W1, R14W1, R14W1, R14W2, R14W2, R14W2, R14W2, R14W3, R14W3, R14W3, R14W3, R14W3, R14W3}},
};

const bs_tet10_rule *bs_tet10_rule_get(bs_tet10_rule_id id) {
  if ((int)id < 0 || (int)id >= (int)(sizeof rules / sizeof rules[0])) return NULL;
  return &rules[id];
}

/* ---- the rest cache ---- */

const char *bs_tet10_fault_name(bs_tet10_fault f) {
  switch (f) {
  case BS_TET10_SOUND: return "sound";
  case BS_TET10_BAD_RULE: return "bad_rule";
  case BS_TET10_NOT_FINITE: return "not_finite";
  case BS_TET10_FOLDED_AT_NODE: return "folded_at_node";
  case BS_TET10_FOLDED_AT_POINT: return "folded_at_point";
  }
  return "unknown";
}

/* J = dX/dxi (J[3m + k] = dX_m/dxi_k) from the reference gradients dN; its determinant returned. */
static double jacobian(const double X[30], const double dN[30], double J[9]) {
  for (int m = 0; m < 3; m++)
    for (int k = 0; k < 3; k++) {
      double s = 0.0;
      for (int a = 0; a < 10; a++) s += X[3 * a + m] * dN[3 * a + k];
      J[3 * m + k] = s;
    }
  return J[0] * (J[4] * J[8] - J[5] * J[7]) - J[1] * (J[3] * J[8] - J[5] * J[6]) +
         J[2] * (J[3] * J[7] - J[4] * J[6]);
}

/* Records the fault and its message; returns BS_ENUMERIC. */
static int refuse(bs_tet10_rest *out, bs_tet10_fault f, int where, double detJ, bs_error *err) {
  out->n_points = 0; /* a refused cache evaluates to nothing */
  out->volume = 0.0;
  out->fault = f;
  out->fault_where = where;
  out->fault_detJ = detJ;
  if (f == BS_TET10_NOT_FINITE)
    return bs_error_set(err, BS_ENUMERIC, "tet10: rest coordinate %d of node %d is not finite", where % 3, where / 3);
  return bs_error_set(err, BS_ENUMERIC, "tet10: det J = %g <= 0 at %s %d: the element is folded (a midside node "
                      "lies too far along or across its edge)", detJ,
                      f == BS_TET10_FOLDED_AT_NODE ? "node" : "quadrature point", where);
}

/* dNdX[a][j] = sum_k dN[3a + k] (J^-1)_kj, with det J = det given. */
static void rest_gradients(const double J[9], double det, const double dN[30], double dNdX[10][3]) {
  const double id = 1.0 / det;
  const double Ji[9] = {(J[4] * J[8] - J[5] * J[7]) * id, (J[2] * J[7] - J[1] * J[8]) * id,
                        (J[1] * J[5] - J[2] * J[4]) * id, (J[5] * J[6] - J[3] * J[8]) * id,
                        (J[0] * J[8] - J[2] * J[6]) * id, (J[2] * J[3] - J[0] * J[5]) * id,
                        (J[3] * J[7] - J[4] * J[6]) * id, (J[1] * J[6] - J[0] * J[7]) * id,
                        (J[0] * J[4] - J[1] * J[3]) * id};
  for (int a = 0; a < 10; a++)
    for (int j = 0; j < 3; j++)
      dNdX[a][j] = dN[3 * a] * Ji[j] + dN[3 * a + 1] * Ji[3 + j] + dN[3 * a + 2] * Ji[6 + j];
}

int bs_tet10_rest_init(const double X[30], bs_tet10_rule_id rule, bs_tet10_rest *out, bs_error *err) {
  memset(out, 0, sizeof *out);
  out->fault_where = -1;
  out->rule = bs_tet10_rule_get(rule);
  if (!out->rule) {
    out->fault = BS_TET10_BAD_RULE; /* n_points stays 0 */
    return bs_error_set(err, BS_EINPUT, "tet10: unknown quadrature rule %d", (int)rule);
  }
  out->n_points = out->rule->n_points;
  for (int i = 0; i < 30; i++)
    if (!isfinite(X[i])) return refuse(out, BS_TET10_NOT_FINITE, i, NAN, err);
  double dN[30], J[9];
  for (int b = 0; b < 10; b++) { /* det J at the nodes: a fold shows first at a vertex or midside node */
    bs_tet10_shape_grad(bs_tet10_ref_nodes[b], dN);
    const double det = jacobian(X, dN, J);
    if (!(det > 0.0) || !isfinite(det)) return refuse(out, BS_TET10_FOLDED_AT_NODE, b, det, err);
  }
  for (int q = 0; q < out->n_points; q++) {
    bs_tet10_shape_grad(out->rule->xi[q], dN);
    const double det = jacobian(X, dN, J);
    if (!(det > 0.0) || !isfinite(det)) return refuse(out, BS_TET10_FOLDED_AT_POINT, q, det, err);
    rest_gradients(J, det, dN, out->dNdX[q]);
    out->detJ[q] = det;
    out->wdetJ[q] = out->rule->w[q] * det;
    out->volume += out->wdetJ[q];
  }
  return BS_OK;
}

/* ---- kinematics and elastic energy ---- */

void bs_tet10_F(const bs_tet10_rest *r, int q, const double x[30], double F[9]) {
  const double(*d)[3] = r->dNdX[q];
  for (int i = 0; i < 3; i++)
    for (int j = 0; j < 3; j++) {
      double s = 0.0;
      for (int a = 0; a < 10; a++) s += x[3 * a + i] * d[a][j];
      F[3 * i + j] = s;
    }
}

double bs_tet10_energy(const bs_material *m, const bs_tet10_rest *r, const double x[30]) {
  double E = 0.0, F[9];
  for (int q = 0; q < r->n_points; q++) {
    bs_tet10_F(r, q, x, F);
    E += r->wdetJ[q] * bs_material_psi(m, F);
  }
  return E;
}

double bs_tet10_energy_grad(const bs_material *m, const bs_tet10_rest *r, const double x[30], double g[30]) {
  double E = 0.0, F[9], P[9];
  for (int i = 0; i < 30; i++) g[i] = 0.0;
  for (int q = 0; q < r->n_points; q++) {
    bs_tet10_F(r, q, x, F);
    const double w = r->wdetJ[q];
    E += w * bs_material_psi_P(m, F, P);
    const double(*d)[3] = r->dNdX[q];
    for (int a = 0; a < 10; a++)
      for (int i = 0; i < 3; i++) g[3 * a + i] += w * (P[3 * i] * d[a][0] + P[3 * i + 1] * d[a][1] + P[3 * i + 2] * d[a][2]);
  }
  return E;
}

/* Adds w G^T K G of one quadrature point to the canonical entries of H: rows
 * (a, c), columns (b, e) with c < e, or c == e and a <= b (mirrored later). */
static void add_point_hessian(const double K[81], const double d[10][3], double w, double H[900]) {
  for (int c = 0; c < 3; c++)
    for (int e = c; e < 3; e++) {
      double T[10][3]; /* T[a][l] = w sum_j d[a][j] K[(c,j),(e,l)] */
      for (int a = 0; a < 10; a++)
        for (int l = 0; l < 3; l++)
          T[a][l] = w * (d[a][0] * K[9 * (3 * c) + 3 * e + l] + d[a][1] * K[9 * (3 * c + 1) + 3 * e + l] +
                         d[a][2] * K[9 * (3 * c + 2) + 3 * e + l]);
      for (int a = 0; a < 10; a++)
        for (int b = (c == e ? a : 0); b < 10; b++)
          H[30 * (3 * a + c) + 3 * b + e] += T[a][0] * d[b][0] + T[a][1] * d[b][1] + T[a][2] * d[b][2];
    }
}

void bs_tet10_hessian(const bs_material *m, const bs_tet10_rest *r, const double x[30], bs_psd_mode project_psd,
                      double H[900]) {
  for (int i = 0; i < 900; i++) H[i] = 0.0;
  double F[9], K[81];
  for (int q = 0; q < r->n_points; q++) {
    bs_tet10_F(r, q, x, F);
    bs_material_dPdF(m, F, project_psd, K);
    add_point_hessian(K, r->dNdX[q], r->wdetJ[q], H);
  }
  /* mirror the canonical entries: symmetric bit for bit */
  for (int c = 0; c < 3; c++)
    for (int e = c; e < 3; e++)
      for (int a = 0; a < 10; a++)
        for (int b = (c == e ? a : 0); b < 10; b++) H[30 * (3 * b + e) + 3 * a + c] = H[30 * (3 * a + c) + 3 * b + e];
}

void bs_tet10_stress(const bs_material *m, const bs_tet10_rest *r, const double x[30], bs_stress_fields *out) {
  double F[9];
  for (int q = 0; q < r->n_points; q++) {
    bs_tet10_F(r, q, x, F);
    bs_stress_eval(m, F, &out[q]);
  }
}

/* ---- mass and body load ---- */

static int mass_check(const bs_tet10_rest *r, double density, bs_error *err) {
  if (!(density > 0.0) || !isfinite(density))
    return bs_error_set(err, BS_EINPUT, "tet10 mass: density %g must be finite and > 0", density);
  if (r->rule->degree < 4)
    return bs_error_set(err, BS_EINPUT,
                        "tet10 mass: the %s rule (degree %d) under-integrates N_a N_b (degree 4) and makes the "
                        "mass matrix singular; build the rest cache with BS_TET10_RULE_14PT_DEG5",
                        r->rule->name, r->rule->degree);
  return BS_OK;
}

int bs_tet10_mass(const bs_tet10_rest *r, double density, double M[100], bs_error *err) {
  const int st = mass_check(r, density, err);
  if (st != BS_OK) return st;
  for (int i = 0; i < 100; i++) M[i] = 0.0;
  double N[10];
  for (int q = 0; q < r->n_points; q++) {
    bs_tet10_shape(r->rule->xi[q], N);
    const double w = density * r->wdetJ[q];
    for (int a = 0; a < 10; a++)
      for (int b = a; b < 10; b++) M[10 * a + b] += w * N[a] * N[b];
  }
  for (int a = 0; a < 10; a++)
    for (int b = 0; b < a; b++) M[10 * a + b] = M[10 * b + a];
  return BS_OK;
}

int bs_tet10_mass_hrz(const bs_tet10_rest *r, double density, double m[10], bs_error *err) {
  double M[100];
  const int st = bs_tet10_mass(r, density, M, err);
  if (st != BS_OK) return st;
  double diag = 0.0;
  for (int a = 0; a < 10; a++) diag += M[11 * a];
  const double scale = density * r->volume / diag;
  for (int a = 0; a < 10; a++) m[a] = M[11 * a] * scale;
  return BS_OK;
}

void bs_tet10_body_load(const bs_tet10_rest *r, double density, const double g[3], double f[30]) {
  double N[10], s[10] = {0};
  for (int q = 0; q < r->n_points; q++) {
    bs_tet10_shape(r->rule->xi[q], N);
    for (int a = 0; a < 10; a++) s[a] += r->wdetJ[q] * N[a];
  }
  for (int a = 0; a < 10; a++)
    for (int i = 0; i < 3; i++) f[3 * a + i] = density * g[i] * s[a];
}

/* ---- node orderings and the linear -> quadratic mesh ---- */

void bs_tet10_swap_gmsh_vtk(int64_t n_tets, int32_t *conn) {
  for (int64_t t = 0; t < n_tets; t++) {
    const int32_t tmp = conn[10 * t + 8];
    conn[10 * t + 8] = conn[10 * t + 9];
    conn[10 * t + 9] = tmp;
  }
}

typedef struct edge_rec {
  int32_t lo, hi;
  int64_t slot; /* 10 t + 4 + k: where its node goes in tets10 */
} edge_rec;

static int cmp_edge(const void *pa, const void *pb) {
  const edge_rec *a = pa, *b = pb;
  if (a->lo != b->lo) return a->lo < b->lo ? -1 : 1;
  if (a->hi != b->hi) return a->hi < b->hi ? -1 : 1;
  return (a->slot > b->slot) - (a->slot < b->slot);
}

/* Checks the tet4 input; fills the edge records (6 per tet) and the vertex
 * part of tets10. */
static int collect_edges(int32_t n_vertices, int32_t n_tets, const int32_t *tets, edge_rec *E, int32_t *tets10,
                         bs_error *err) {
  for (int64_t t = 0; t < n_tets; t++) {
    const int32_t *v = tets + 4 * t;
    for (int a = 0; a < 4; a++) {
      if (v[a] < 0 || v[a] >= n_vertices)
        return bs_error_set(err, BS_EINPUT, "tet10 from tet4: tet %lld vertex %d is %d, outside [0, %d)",
                            (long long)t, a, (int)v[a], (int)n_vertices);
      for (int b = 0; b < a; b++)
        if (v[a] == v[b])
          return bs_error_set(err, BS_EINPUT, "tet10 from tet4: tet %lld repeats vertex %d", (long long)t,
                              (int)v[a]);
      tets10[10 * t + a] = v[a];
    }
    for (int k = 0; k < 6; k++) {
      const int32_t p = v[bs_tet10_edges[k][0]], q = v[bs_tet10_edges[k][1]];
      E[6 * t + k] = (edge_rec){p < q ? p : q, p < q ? q : p, 10 * t + 4 + k};
    }
  }
  return BS_OK;
}

/* Numbers the sorted edges from n_vertices (one node per run of equal pairs)
 * into tets10; returns the number of unique edges, or -1 past INT32_MAX nodes. */
static int64_t number_edges(int32_t n_vertices, int64_t n_rec, const edge_rec *E, int32_t *tets10) {
  int64_t n_unique = 0;
  for (int64_t i = 0; i < n_rec; i++) {
    if (i == 0 || E[i].lo != E[i - 1].lo || E[i].hi != E[i - 1].hi) n_unique++;
    if ((int64_t)n_vertices + n_unique > INT32_MAX) return -1;
    tets10[E[i].slot] = (int32_t)(n_vertices + n_unique - 1);
  }
  return n_unique;
}

int bs_tet10_from_tet4(int32_t n_vertices, const double *vertices, int32_t n_tets, const int32_t *tets,
                       int32_t *n_nodes, double **nodes, int32_t **tets10, bs_error *err) {
  *n_nodes = 0, *nodes = NULL, *tets10 = NULL;
  if (n_vertices < 0 || n_tets < 0 || (n_vertices > 0 && !vertices) || (n_tets > 0 && !tets))
    return bs_error_set(err, BS_EINPUT, "tet10 from tet4: %d vertices, %d tets, or a NULL array", (int)n_vertices,
                        (int)n_tets);
  const int64_t n_rec = 6 * (int64_t)n_tets;
  edge_rec *E = bs_calloc((size_t)n_rec, sizeof *E, "tet10 edges", err);
  int32_t *T = bs_calloc((size_t)(10 * (int64_t)n_tets), sizeof *T, "tet10 connectivity", err);
  int st = (E && T) ? collect_edges(n_vertices, n_tets, tets, E, T, err) : BS_ENOMEM;
  int64_t n_unique = 0;
  if (st == BS_OK) {
    qsort(E, (size_t)n_rec, sizeof *E, cmp_edge);
    n_unique = number_edges(n_vertices, n_rec, E, T);
    if (n_unique < 0) st = bs_error_set(err, BS_EINPUT, "tet10 from tet4: more than %d nodes", (int)INT32_MAX);
  }
  double *P = NULL;
  if (st == BS_OK) {
    P = bs_calloc((size_t)(3 * (n_vertices + n_unique)), sizeof *P, "tet10 nodes", err);
    if (!P) st = BS_ENOMEM;
  }
  if (st == BS_OK) {
    if (n_vertices > 0) memcpy(P, vertices, sizeof(double) * 3 * (size_t)n_vertices);
    for (int64_t i = 0, u = -1; i < n_rec; i++) {
      if (i > 0 && E[i].lo == E[i - 1].lo && E[i].hi == E[i - 1].hi) continue;
      u++;
      for (int k = 0; k < 3; k++)
        P[3 * (n_vertices + u) + k] = 0.5 * (vertices[3 * (int64_t)E[i].lo + k] + vertices[3 * (int64_t)E[i].hi + k]);
    }
    *n_nodes = (int32_t)(n_vertices + n_unique), *nodes = P, *tets10 = T;
    T = NULL;
  }
  free(E);
  free(T);
  return st;
}
