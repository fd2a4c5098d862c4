/* fem10.c — the fem cache over quadratic tets (bs_fem.h, "Quadratic tets"):
 * the rest gradients at the quadrature points, the HRZ-lumped mass, the
 * weights of the consistent body load, the block pattern over the 10 nodes,
 * and the elastic energy, gradient and Hessian assembled in parallel over
 * the chunks of fem.c's colouring (of the corners: tets that share a node
 * share a corner), each chunk's tets in order and the partial sums added in
 * a fixed order, so that the results do not depend on the thread count. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bs_tet10.h"
#include "fem_internal.h"

/* Gathers the 30 coordinates of tet t's nodes from x. */
static void gather10(const bs_fem *f, const double *x, int32_t t, double xt[30]) {
  const int32_t *tv = f->mesh->tets10 + 10 * (size_t)t;
  for (int a = 0; a < 10; a++)
    for (int k = 0; k < 3; k++) xt[3 * a + k] = x[3 * (size_t)tv[a] + k];
}

/* Tet t's rest cache rebuilt from the fem's compact arrays. */
static void rest_of(const bs_fem *f, int32_t t, bs_tet10_rest *r) {
  const int32_t p0 = f->q_ptr[t], n = f->q_ptr[t + 1] - p0;
  r->rule = bs_tet10_rule_get(n == 4 ? BS_TET10_RULE_4PT_DEG2 : BS_TET10_RULE_14PT_DEG5);
  r->n_points = n;
  memcpy(r->dNdX, f->q_dNdX + 30 * (size_t)p0, sizeof(double) * 30 * (size_t)n);
  memcpy(r->wdetJ, f->q_wdetJ + p0, sizeof(double) * (size_t)n);
  r->volume = f->volume[t];
}

/* 1 when every midside node of the tet with nodes X sits at its edge's
 * midpoint (to 1e-12 of the longest edge): a straight tet10. */
static int straight(const double X[30]) {
  double L = 0, d = 0;
  for (int k = 0; k < 6; k++) {
    const double *p = X + 3 * bs_tet10_edges[k][0], *q = X + 3 * bs_tet10_edges[k][1], *m = X + 3 * (4 + k);
    for (int i = 0; i < 3; i++) {
      L = fmax(L, fabs(q[i] - p[i]));
      d = fmax(d, fabs(m[i] - 0.5 * (p[i] + q[i])));
    }
  }
  return d <= 1e-12 * L;
}

/* Tet t: its rest cache into the compact arrays (points from f->q_ptr[t]),
 * its volume, its HRZ masses and body-load weights added to the nodes'. */
static int rest_tet(bs_fem *f, int32_t t, double density, bs_error *err) {
  double X[30];
  gather10(f, f->mesh->x, t, X);
  bs_tet10_rest r, r14;
  const int rule = straight(X) ? BS_TET10_RULE_4PT_DEG2 : BS_TET10_RULE_14PT_DEG5;
  int st = bs_tet10_rest_init(X, rule, &r, err);
  if (!st) st = bs_tet10_rest_init(X, BS_TET10_RULE_14PT_DEG5, &r14, err);
  double m[10], w[30];
  const double e1[3] = {1, 0, 0};
  if (!st) st = bs_tet10_mass_hrz(&r14, density, m, err);
  if (st) {
    bs_error_prefix(err, "tet %d", t);
    return st;
  }
  bs_tet10_body_load(&r14, density, e1, w);
  const int32_t p0 = f->q_ptr[t];
  f->q_ptr[t + 1] = p0 + r.n_points;
  for (int q = 0; q < r.n_points; q++) {
    memcpy(f->q_dNdX + 30 * (size_t)(p0 + q), r.dNdX[q], sizeof(double) * 30);
    f->q_wdetJ[p0 + q] = r.wdetJ[q];
  }
  f->volume[t] = r14.volume;
  const int32_t *tv = f->mesh->tets10 + 10 * (size_t)t;
  for (int a = 0; a < 10; a++) {
    f->mass[tv[a]] += m[a];
    f->load[tv[a]] += w[3 * a];
  }
  f->total_mass += density * r14.volume;
  return 0;
}

/* The node graph through the quadratic tets (each node's row: the nodes of
 * every tet it belongs to, itself and duplicates included) as the pattern,
 * and each tet's 100 block slots. */
static int make_pattern(bs_fem *f, bs_error *err) {
  const bs_mesh *m = f->mesh;
  const int32_t nn = m->n_vertices, nt = m->n_tets;
  int32_t *ptr = bs_calloc((size_t)nn + 1, sizeof(int32_t), "tet10 node graph", err);
  int32_t *adj = bs_calloc((size_t)nt * 100 + 1, sizeof(int32_t), "tet10 node graph", err);
  int st = (ptr && adj) ? 0 : BS_ENOMEM;
  if (!st) {
    for (size_t i = 0; i < 10 * (size_t)nt; i++) ptr[m->tets10[i] + 1] += 10;
    for (int32_t v = 0; v < nn; v++) ptr[v + 1] += ptr[v];
    int32_t *fill = bs_calloc((size_t)nn + 1, sizeof(int32_t), "tet10 node graph", err);
    if (!fill) st = BS_ENOMEM;
    for (int32_t t = 0; !st && t < nt; t++) {
      const int32_t *tv = m->tets10 + 10 * (size_t)t;
      for (int a = 0; a < 10; a++)
        for (int b = 0; b < 10; b++) adj[ptr[tv[a]] + fill[tv[a]]++] = tv[b];
    }
    free(fill);
  }
  if (!st) st = bs_bsr_create(nn, ptr, adj, &f->pattern, err);
  free(ptr);
  free(adj);
  for (int32_t t = 0; !st && t < nt; t++) {
    const int32_t *tv = m->tets10 + 10 * (size_t)t;
    for (int a = 0; a < 10; a++)
      for (int b = 0; b < 10; b++) f->slots[100 * (size_t)t + 10 * a + b] = bs_bsr_slot(f->pattern, tv[a], tv[b]);
  }
  return st;
}

int bs__fem10_create(bs_fem *f, const int32_t *tet_material, bs_error *err) {
  const bs_mesh *m = f->mesh;
  const size_t nt = (size_t)m->n_tets, nn = (size_t)m->n_vertices;
  f->order = 2;
  f->volume = bs_calloc(nt, sizeof(double), "tet10 volumes", err);
  f->mass = bs_calloc(nn, sizeof(double), "tet10 masses", err);
  f->load = bs_calloc(nn, sizeof(double), "tet10 load weights", err);
  f->tet_material = bs_calloc(nt, sizeof(int32_t), "tet10 materials", err);
  f->slots = bs_calloc(100 * nt, sizeof(int32_t), "tet10 block slots", err);
  f->q_ptr = bs_calloc(nt + 1, sizeof(int32_t), "tet10 quadrature pointers", err);
  f->q_dNdX = bs_calloc(30 * BS_TET10_MAX_POINTS * nt, sizeof(double), "tet10 rest gradients", err);
  f->q_wdetJ = bs_calloc(BS_TET10_MAX_POINTS * nt, sizeof(double), "tet10 quadrature weights", err);
  if (!f->volume || !f->mass || !f->load || !f->tet_material || !f->slots || !f->q_ptr || !f->q_dNdX || !f->q_wdetJ)
    return BS_ENOMEM;
  for (size_t t = 0; t < nt; t++) {
    const int32_t mi = tet_material ? tet_material[t] : 0;
    if (mi < 0 || mi >= f->n_materials)
      return bs_error_set(err, BS_EINPUT, "tet %zu has material index %d, outside 0..%d", t, mi, f->n_materials - 1);
    f->tet_material[t] = mi;
    const int st = rest_tet(f, (int32_t)t, f->materials[mi].density, err);
    if (st) return st;
  }
  /* the points in use only (4 per straight tet) */
  const size_t np = (size_t)f->q_ptr[nt];
  double *d = realloc(f->q_dNdX, sizeof(double) * 30 * (np ? np : 1)), *w = realloc(f->q_wdetJ, sizeof(double) * (np ? np : 1));
  if (d) f->q_dNdX = d;
  if (w) f->q_wdetJ = w;
  int st = make_pattern(f, err);
  if (!st) st = bs__fem_color_chunks(f, err);
  if (st) return st;
  f->partial = bs_calloc((size_t)f->n_chunks + 1, sizeof(double), "the energy partial sums", err);
  if (!f->partial) return BS_ENOMEM;
  free(f->pattern->val);
  f->pattern->val = NULL;
  return 0;
}

/* A colour's chunks (or the chunks, for the energy) run on several threads
 * when there are at least this many: as in fem.c. */
enum { PAR_CHUNKS10 = 4 };

/* The energy (and when g is not NULL, the gradient added into g) of the tets
 * of chunk c, in chunk order. */
static double chunk_energy(const bs_fem *f, const double *x, int32_t c, double *g) {
  double E = 0, xt[30], ge[30];
  bs_tet10_rest r;
  for (int32_t q = f->chunk_ptr[c]; q < f->chunk_ptr[c + 1]; q++) {
    const int32_t t = f->chunk_tets[q];
    gather10(f, x, t, xt);
    rest_of(f, t, &r);
    if (!g) {
      E += bs_tet10_energy(&f->materials[f->tet_material[t]], &r, xt);
      continue;
    }
    E += bs_tet10_energy_grad(&f->materials[f->tet_material[t]], &r, xt, ge);
    const int32_t *tv = f->mesh->tets10 + 10 * (size_t)t;
    for (int a = 0; a < 10; a++)
      for (int k = 0; k < 3; k++) g[3 * (size_t)tv[a] + k] += ge[3 * a + k];
  }
  return E;
}

double bs__fem10_energy(const bs_fem *f, const double *x) {
  double *part = f->partial;
  const int32_t nk = f->n_chunks;
#pragma omp parallel for schedule(dynamic, 1) if (nk >= PAR_CHUNKS10)
  for (int32_t c = 0; c < nk; c++) part[c] = chunk_energy(f, x, c, NULL);
  double E = 0;
  for (int32_t c = 0; c < nk; c++) E += part[c];
  return E;
}

/* Colour by colour: the chunks of a colour share no node (they share no
 * corner, and a midside node belongs to the tets of its edge), so they add
 * into g at once; the sums are in a fixed order whatever the thread count. */
double bs__fem10_gradient(const bs_fem *f, const double *x, double *g) {
  double *part = f->partial; /* part[q]: the chunk at position q of color_chunks */
  for (int c = 0; c < f->n_colors; c++) {
    const int32_t lo = f->color_ptr[c], hi = f->color_ptr[c + 1];
#pragma omp parallel for schedule(dynamic, 1) if (hi - lo >= PAR_CHUNKS10)
    for (int32_t q = lo; q < hi; q++) part[q] = chunk_energy(f, x, f->color_chunks[q], g);
  }
  double E = 0;
  for (int32_t q = 0; q < f->n_chunks; q++) E += part[q];
  return E;
}

static void hessian_tet(const bs_fem *f, const double *x, int32_t t, int project_psd, const double *vmax, double s,
                        const double *material_scale, bs_bsr *H) {
  double xt[30], He[900];
  bs_tet10_rest r;
  const int32_t mi = f->tet_material[t];
  const double sc = material_scale ? material_scale[mi] : s;
  if (material_scale && sc == 0) return;
  const int mode = vmax ? (f->volume[t] <= vmax[mi] ? BS_PSD_INVERTED : BS_PSD_NONE) : project_psd;
  gather10(f, x, t, xt);
  rest_of(f, t, &r);
  bs_tet10_hessian(&f->materials[mi], &r, xt, mode, He);
  const int32_t *sl = f->slots + 100 * (size_t)t;
  for (int a = 0; a < 10; a++)
    for (int b = 0; b < 10; b++) {
      double *blk = H->val + 9 * (size_t)sl[10 * a + b];
      for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) blk[3 * i + j] += sc * He[30 * (3 * a + i) + 3 * b + j];
    }
}

void bs__fem10_hessian(const bs_fem *f, const double *x, int project_psd, const double *vmax, double s,
                       const double *material_scale, bs_bsr *H) {
  for (int c = 0; c < f->n_colors; c++) {
    const int32_t lo = f->color_ptr[c], hi = f->color_ptr[c + 1];
#pragma omp parallel for schedule(dynamic, 1) if (hi - lo >= PAR_CHUNKS10)
    for (int32_t q = lo; q < hi; q++) {
      const int32_t k = f->color_chunks[q];
      for (int32_t p = f->chunk_ptr[k]; p < f->chunk_ptr[k + 1]; p++)
        hessian_tet(f, x, f->chunk_tets[p], project_psd, vmax, s, material_scale, H);
    }
  }
}

int32_t bs__fem10_count_inverted(const bs_fem *f, const double *x, double *min_detF) {
  int32_t n = 0;
  double mn = INFINITY;
#pragma omp parallel for schedule(static) reduction(+ : n) reduction(min : mn) if (f->n_tets > 512)
  for (int32_t t = 0; t < f->n_tets; t++) {
    double xt[30], F[9];
    bs_tet10_rest r;
    gather10(f, x, t, xt);
    rest_of(f, t, &r);
    int bad = 0;
    for (int q = 0; q < r.n_points; q++) {
      bs_tet10_F(&r, q, xt, F);
      const double J = F[0] * (F[4] * F[8] - F[5] * F[7]) - F[1] * (F[3] * F[8] - F[5] * F[6]) +
                       F[2] * (F[3] * F[7] - F[4] * F[6]);
      if (!(J > 0)) bad = 1;
      if (J < mn) mn = J;
    }
    n += bad;
  }
  if (min_detF) *min_detF = mn;
  return n;
}

int bs_fem_tet10_rest(const bs_fem *f, int32_t t, bs_tet10_rest *r) {
  if (f->order != 2 || t < 0 || t >= f->n_tets) return BS_EINPUT;
  rest_of(f, t, r);
  return 0;
}

void bs_fem_tet10_gather(const bs_fem *f, const double *x, int32_t t, double xt[30]) { gather10(f, x, t, xt); }
