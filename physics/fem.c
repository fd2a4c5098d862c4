/* fem.c — per-tet cache, lumped masses, block slots, colouring, and the
 * parallel elastic energy / gradient / Hessian assembly. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bs_element.h"
#include "bs_fem.h"

void bs_fem_destroy(bs_fem **pf) {
  if (!pf || !*pf) return;
  bs_fem *f = *pf;
  free(f->Dm_inv);
  free(f->volume);
  free(f->mass);
  free(f->materials);
  free(f->tet_material);
  bs_bsr_destroy(&f->pattern);
  free(f->slots);
  free(f->color_ptr);
  free(f->color_tets);
  free(f);
  *pf = NULL;
}

/* Greedy colouring: each tet takes the smallest colour that no tet sharing a
 * vertex with it has taken yet. */
static int color_tets(bs_fem *f, bs_error *err) {
  const bs_mesh *m = f->mesh;
  int32_t nt = m->n_tets;
  int32_t *color = malloc(sizeof(int32_t) * (size_t)(nt ? nt : 1));
  int cap = 64;
  int32_t *used = malloc(sizeof(int32_t) * (size_t)cap); /* used[c] == t: taken for tet t */
  if (!color || !used) {
    free(color);
    free(used);
    return bs_error_set(err, BS_ENOMEM, "out of memory colouring %d tets", nt);
  }
  for (int c = 0; c < cap; c++) used[c] = -1;
  for (int32_t t = 0; t < nt; t++) color[t] = -1;
  int nc = 0;
  for (int32_t t = 0; t < nt; t++) {
    for (int a = 0; a < 4; a++) {
      int32_t v = m->tets[4 * t + a];
      for (int32_t k = m->v2t_ptr[v]; k < m->v2t_ptr[v + 1]; k++) {
        int32_t c = color[m->v2t[k]];
        if (c >= 0) used[c] = t;
      }
    }
    int c = 0;
    while (c < cap && used[c] == t) c++;
    if (c == cap) {
      int ncap = 2 * cap;
      int32_t *nu = realloc(used, sizeof(int32_t) * (size_t)ncap);
      if (!nu) {
        free(color);
        free(used);
        return bs_error_set(err, BS_ENOMEM, "out of memory colouring tets");
      }
      used = nu;
      for (int i = cap; i < ncap; i++) used[i] = -1;
      cap = ncap;
    }
    color[t] = c;
    if (c + 1 > nc) nc = c + 1;
  }
  f->n_colors = nc;
  f->color_ptr = calloc((size_t)nc + 1, sizeof(int32_t));
  f->color_tets = malloc(sizeof(int32_t) * (size_t)(nt ? nt : 1));
  if (!f->color_ptr || !f->color_tets) {
    free(color);
    free(used);
    return bs_error_set(err, BS_ENOMEM, "out of memory colouring tets");
  }
  for (int32_t t = 0; t < nt; t++) f->color_ptr[color[t] + 1]++;
  for (int c = 0; c < nc; c++) f->color_ptr[c + 1] += f->color_ptr[c];
  int32_t *fill = malloc(sizeof(int32_t) * (size_t)(nc ? nc : 1));
  if (!fill) {
    free(color);
    free(used);
    return bs_error_set(err, BS_ENOMEM, "out of memory colouring tets");
  }
  memcpy(fill, f->color_ptr, sizeof(int32_t) * (size_t)nc);
  for (int32_t t = 0; t < nt; t++) f->color_tets[fill[color[t]]++] = t;
  free(fill);
  free(color);
  free(used);
  return 0;
}

int bs_fem_create(const bs_mesh *mesh, int n_materials, const bs_material *materials,
                  const int32_t *tet_material, bs_fem **out, bs_error *err) {
  *out = NULL;
  if (n_materials < 1 || !materials) return bs_error_set(err, BS_EINPUT, "bs_fem_create: no material given");
  bs_fem *f = calloc(1, sizeof *f);
  if (!f) return bs_error_set(err, BS_ENOMEM, "out of memory creating the fem cache");
  f->mesh = mesh;
  f->n_vertices = mesh->n_vertices;
  f->n_tets = mesh->n_tets;
  size_t nt = (size_t)mesh->n_tets, nv = (size_t)mesh->n_vertices;
  f->Dm_inv = malloc(sizeof(double) * 9 * (nt ? nt : 1));
  f->volume = malloc(sizeof(double) * (nt ? nt : 1));
  f->mass = calloc(nv ? nv : 1, sizeof(double));
  f->materials = malloc(sizeof(bs_material) * (size_t)n_materials);
  f->tet_material = calloc(nt ? nt : 1, sizeof(int32_t));
  f->slots = malloc(sizeof(int32_t) * 16 * (nt ? nt : 1));
  int st = 0;
  if (!f->Dm_inv || !f->volume || !f->mass || !f->materials || !f->tet_material || !f->slots) {
    st = bs_error_set(err, BS_ENOMEM, "out of memory creating the fem cache (%zu tets)", nt);
    goto fail;
  }
  f->n_materials = n_materials;
  memcpy(f->materials, materials, sizeof(bs_material) * (size_t)n_materials);
  for (size_t t = 0; t < nt; t++) {
    int32_t mi = tet_material ? tet_material[t] : 0;
    if (mi < 0 || mi >= n_materials) {
      st = bs_error_set(err, BS_EINPUT, "tet %zu has material index %d, outside 0..%d", t, mi, n_materials - 1);
      goto fail;
    }
    f->tet_material[t] = mi;
    double X[12];
    bs_fem_gather(f, mesh->x, (int32_t)t, X);
    bs_tet_rest(X, f->Dm_inv + 9 * t, &f->volume[t]);
    if (!(f->volume[t] > 0) || !isfinite(f->volume[t])) {
      const int32_t *tv = mesh->tets + 4 * t;
      st = bs_error_set(err, BS_EINPUT, "tet %zu (vertices %d %d %d %d) has rest volume %g: not positive", t, tv[0],
                        tv[1], tv[2], tv[3], f->volume[t]);
      goto fail;
    }
    double mq = materials[mi].density * f->volume[t] / 4.0;
    for (int a = 0; a < 4; a++) f->mass[mesh->tets[4 * t + a]] += mq;
    f->total_mass += 4 * mq;
  }
  {
    int32_t *ptr = NULL, *adj = NULL;
    if ((st = bs_mesh_vertex_graph(mesh, &ptr, &adj, err))) goto fail;
    st = bs_bsr_create(mesh->n_vertices, ptr, adj, &f->pattern, err);
    free(ptr);
    free(adj);
    if (st) goto fail;
  }
  for (size_t t = 0; t < nt; t++) {
    const int32_t *tv = mesh->tets + 4 * t;
    for (int a = 0; a < 4; a++)
      for (int b = 0; b < 4; b++) {
        int32_t s = bs_bsr_slot(f->pattern, tv[a], tv[b]);
        if (s < 0) {
          st = bs_error_set(err, BS_EINTERNAL, "tet %zu: block (%d, %d) missing from the pattern", t, tv[a], tv[b]);
          goto fail;
        }
        f->slots[16 * t + 4 * a + b] = s;
      }
  }
  if ((st = color_tets(f, err))) goto fail;
  /* The pattern is structure only: matrices are made with bs_fem_matrix. */
  free(f->pattern->val);
  f->pattern->val = NULL;
  *out = f;
  return 0;
fail:
  bs_fem_destroy(&f);
  return st;
}

int bs_fem_matrix(const bs_fem *fem, bs_bsr **out, bs_error *err) {
  /* the pattern's own rows as the graph (self loops are allowed): same blocks */
  return bs_bsr_create(fem->n_vertices, fem->pattern->row_ptr, fem->pattern->col, out, err);
}

void bs_fem_scatter_hessian(const bs_fem *fem, int32_t t, const double He[144], double scale, bs_bsr *H) {
  const int32_t *sl = fem->slots + 16 * t;
  for (int a = 0; a < 4; a++)
    for (int b = 0; b < 4; b++) {
      double *blk = H->val + 9 * (size_t)sl[4 * a + b];
      for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) blk[3 * i + j] += scale * He[12 * (3 * a + i) + 3 * b + j];
    }
}

/* The kernel loops work on batches of up to NB tets (BS_MATERIAL_BATCH: the
 * SVDs of a batch run in SIMD lanes, bs_svd3_batch), split into runs of one
 * material. Results are bit for bit those of the per-tet kernels, and the
 * scatter order within a colour is unchanged. */
enum { NB = BS_MATERIAL_BATCH };

/* Gathers tets idx[0..n) (through map, or idx itself when map is NULL):
 * coordinates, Dm_inv and volumes, packed. */
static void gather_batch(const bs_fem *fem, const double *x, const int32_t *map, int32_t k0, int n, int32_t *tt,
                         double *xt, double *Dm, double *vol) {
  for (int i = 0; i < n; i++) {
    const int32_t t = map ? map[k0 + i] : k0 + i;
    tt[i] = t;
    bs_fem_gather(fem, x, t, xt + 12 * i);
    memcpy(Dm + 9 * i, fem->Dm_inv + 9 * (size_t)t, 9 * sizeof(double));
    vol[i] = fem->volume[t];
  }
}

/* Prefetches the vertex data (x, and out when not NULL) and the rest shape
 * of the tets map[k0 .. min(k0 + NB, hi)): a colour's tets share no vertex, so
 * consecutive ones are far apart in memory. */
static void prefetch_batch(const bs_fem *fem, const double *x, const double *out, const int32_t *map, int32_t k0,
                           int32_t hi) {
  for (int32_t k = k0; k < hi && k < k0 + NB; k++) {
    const int32_t t = map[k];
    const int32_t *tv = fem->mesh->tets + 4 * (size_t)t;
    __builtin_prefetch(fem->Dm_inv + 9 * (size_t)t, 0, 1);
    for (int a = 0; a < 4; a++) {
      __builtin_prefetch(x + 3 * (size_t)tv[a], 0, 1);
      if (out) __builtin_prefetch(out + 3 * (size_t)tv[a], 1, 1);
    }
  }
}

/* Length of the run of tets tt[i..n) with the material of tt[i]. */
static int material_run(const bs_fem *fem, const int32_t *tt, int i, int n) {
  const int32_t mi = fem->tet_material[tt[i]];
  int j = i + 1;
  while (j < n && fem->tet_material[tt[j]] == mi) j++;
  return j - i;
}

double bs_fem_elastic_energy(const bs_fem *fem, const double *x) {
  double E = 0;
  const int32_t nt = fem->n_tets;
#pragma omp parallel for schedule(static) reduction(+ : E) if (nt > 2048)
  for (int32_t k0 = 0; k0 < nt; k0 += NB) {
    const int n = nt - k0 < NB ? (int)(nt - k0) : NB;
    int32_t tt[NB];
    double xt[12 * NB], Dm[9 * NB], vol[NB], e[NB];
    gather_batch(fem, x, NULL, k0, n, tt, xt, Dm, vol);
    for (int i = 0; i < n;) {
      const int r = material_run(fem, tt, i, n);
      bs_tet_energy_batch(&fem->materials[fem->tet_material[tt[i]]], r, xt + 12 * i, Dm + 9 * i, vol + i, e + i);
      i += r;
    }
    for (int i = 0; i < n; i++) E += e[i];
  }
  return E;
}

double bs_fem_elastic_gradient(const bs_fem *fem, const double *x, double *g) {
  double E = 0;
  const int32_t *tets = fem->mesh->tets;
  for (int c = 0; c < fem->n_colors; c++) {
    int32_t lo = fem->color_ptr[c], hi = fem->color_ptr[c + 1];
#pragma omp parallel for schedule(static) reduction(+ : E) if (hi - lo > 512)
    for (int32_t k0 = lo; k0 < hi; k0 += NB) {
      const int n = hi - k0 < NB ? (int)(hi - k0) : NB;
      int32_t tt[NB];
      double xt[12 * NB], Dm[9 * NB], vol[NB], e[NB], ge[12 * NB];
      gather_batch(fem, x, fem->color_tets, k0, n, tt, xt, Dm, vol);
      prefetch_batch(fem, x, g, fem->color_tets, k0 + NB, hi);
      for (int i = 0; i < n;) {
        const int r = material_run(fem, tt, i, n);
        bs_tet_energy_grad_batch(&fem->materials[fem->tet_material[tt[i]]], r, xt + 12 * i, Dm + 9 * i, vol + i,
                                 e + i, ge + 12 * i);
        i += r;
      }
      for (int i = 0; i < n; i++) {
        E += e[i];
        for (int a = 0; a < 4; a++) {
          double *gv = g + 3 * (size_t)tets[4 * tt[i] + a];
          gv[0] += ge[12 * i + 3 * a];
          gv[1] += ge[12 * i + 3 * a + 1];
          gv[2] += ge[12 * i + 3 * a + 2];
        }
      }
    }
  }
  return E;
}

void bs_fem_elastic_hessian(const bs_fem *fem, const double *x, int project_psd, double scale, bs_bsr *H) {
  for (int c = 0; c < fem->n_colors; c++) {
    int32_t lo = fem->color_ptr[c], hi = fem->color_ptr[c + 1];
#pragma omp parallel for schedule(static) if (hi - lo > 512)
    for (int32_t k0 = lo; k0 < hi; k0 += NB) {
      const int n = hi - k0 < NB ? (int)(hi - k0) : NB;
      int32_t tt[NB];
      double xt[12 * NB], Dm[9 * NB], vol[NB], He[144 * NB];
      gather_batch(fem, x, fem->color_tets, k0, n, tt, xt, Dm, vol);
      prefetch_batch(fem, x, NULL, fem->color_tets, k0 + NB, hi);
      /* The blocks of the next batch are scattered over the whole matrix (a
       * colour's tets share no vertex): fetch them while this batch computes. */
      for (int32_t k = k0 + NB; k < hi && k < k0 + 2 * NB; k++) {
        const int32_t *sl = fem->slots + 16 * (size_t)fem->color_tets[k];
        for (int b = 0; b < 16; b++) {
          const double *blk = H->val + 9 * (size_t)sl[b];
          __builtin_prefetch(blk, 1, 1);
          __builtin_prefetch(blk + 8, 1, 1);
        }
      }
      for (int i = 0; i < n;) {
        const int r = material_run(fem, tt, i, n);
        bs_tet_hessian_batch(&fem->materials[fem->tet_material[tt[i]]], r, xt + 12 * i, Dm + 9 * i, vol + i,
                             project_psd, He + 144 * i);
        i += r;
      }
      for (int i = 0; i < n; i++) bs_fem_scatter_hessian(fem, tt[i], He + 144 * i, scale, H);
    }
  }
}

int32_t bs_fem_count_inverted(const bs_fem *fem, const double *x, double *min_detF) {
  int32_t n = 0;
  double mn = INFINITY;
#pragma omp parallel for schedule(static) reduction(+ : n) reduction(min : mn) if (fem->n_tets > 2048)
  for (int32_t t = 0; t < fem->n_tets; t++) {
    double xt[12], F[9];
    bs_fem_gather(fem, x, t, xt);
    bs_tet_F(xt, fem->Dm_inv + 9 * (size_t)t, F);
    double J = F[0] * (F[4] * F[8] - F[5] * F[7]) - F[1] * (F[3] * F[8] - F[5] * F[6]) +
               F[2] * (F[3] * F[7] - F[4] * F[6]);
    if (!(J > 0)) n++;
    if (J < mn) mn = J;
  }
  if (min_detF) *min_detF = mn;
  return n;
}
