/* fem.c — per-tet cache, lumped masses, block slots, chunks and their
 * colouring, and the parallel elastic energy / gradient / Hessian assembly. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bs_element.h"
#include "bs_fem.h"
#include "fem_internal.h"

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
  free(f->chunk_ptr);
  free(f->chunk_tets);
  free(f->tets);
  free(f->tet_pos);
  free(f->color_chunks);
  free(f->partial);
  free(f->load);
  free(f->q_ptr);
  free(f->q_dNdX);
  free(f->q_wdetJ);
  free(f);
  *pf = NULL;
}

enum { EBLOCK = 1024 }; /* tets per partial sum of bs_fem_elastic_energy */

/* Chunks: from the first tet not yet taken, breadth first through shared
 * vertices over the tets not yet taken, until BS_FEM_CHUNK tets (fewer when
 * the search runs out); then sorted. chunk_of[t] receives t's chunk. */
static int make_chunks(bs_fem *f, int32_t *chunk_of, bs_error *err) {
  const bs_mesh *m = f->mesh;
  const int32_t nt = m->n_tets;
  f->chunk_tets = malloc(sizeof(int32_t) * (size_t)(nt ? nt : 1));
  f->chunk_ptr = malloc(sizeof(int32_t) * ((size_t)nt + 1));
  if (!f->chunk_tets || !f->chunk_ptr) return bs_error_set(err, BS_ENOMEM, "out of memory chunking %d tets", nt);
  int32_t *out = f->chunk_tets;
  for (int32_t t = 0; t < nt; t++) chunk_of[t] = -1;
  int32_t pos = 0, k = 0, seed = 0;
  f->chunk_ptr[0] = 0;
  while (pos < nt) {
    while (chunk_of[seed] >= 0) seed++;
    const int32_t start = pos;
    chunk_of[seed] = k;
    out[pos++] = seed;
    for (int32_t head = start; head < pos && pos - start < BS_FEM_CHUNK; head++) {
      const int32_t *tv = m->tets + 4 * (size_t)out[head];
      for (int a = 0; a < 4 && pos - start < BS_FEM_CHUNK; a++)
        for (int32_t p = m->v2t_ptr[tv[a]]; p < m->v2t_ptr[tv[a] + 1] && pos - start < BS_FEM_CHUNK; p++) {
          const int32_t u = m->v2t[p];
          if (chunk_of[u] < 0) {
            chunk_of[u] = k;
            out[pos++] = u;
          }
        }
    }
    qsort(out + start, (size_t)(pos - start), sizeof(int32_t), bs_cmp_i32);
    f->chunk_ptr[++k] = pos;
  }
  f->n_chunks = k;
  return 0;
}

/* Greedy colouring of the chunks, in order: each chunk takes the smallest
 * colour that no chunk sharing a vertex with it has taken yet. */
int bs__fem_color_chunks(bs_fem *f, bs_error *err) {
  const bs_mesh *m = f->mesh;
  const int32_t nt = m->n_tets, nv = m->n_vertices;
  const int32_t ns = nv > nt ? nv : nt;
  int32_t *chunk_of = malloc(sizeof(int32_t) * (size_t)(nt ? nt : 1));
  int32_t *color = malloc(sizeof(int32_t) * (size_t)(nt ? nt : 1));
  int32_t *stamp = malloc(sizeof(int32_t) * (size_t)(ns ? ns : 1)); /* stamp[v] == k: v seen for chunk k */
  int cap = 64;
  int32_t *used = malloc(sizeof(int32_t) * (size_t)cap); /* used[c] == k: taken for chunk k */
  int st = 0;
  if (!chunk_of || !color || !stamp || !used) {
    st = bs_error_set(err, BS_ENOMEM, "out of memory colouring %d tets", nt);
    goto done;
  }
  if ((st = make_chunks(f, chunk_of, err))) goto done;
  const int32_t nk = f->n_chunks;
  for (int c = 0; c < cap; c++) used[c] = -1;
  for (int32_t v = 0; v < nv; v++) stamp[v] = -1;
  for (int32_t k = 0; k < nk; k++) color[k] = -1;
  int nc = 0;
  for (int32_t k = 0; k < nk; k++) {
    for (int32_t q = f->chunk_ptr[k]; q < f->chunk_ptr[k + 1]; q++)
      for (int a = 0; a < 4; a++) {
        const int32_t v = m->tets[4 * (size_t)f->chunk_tets[q] + a];
        if (stamp[v] == k) continue;
        stamp[v] = k;
        for (int32_t p = m->v2t_ptr[v]; p < m->v2t_ptr[v + 1]; p++) {
          const int32_t c = color[chunk_of[m->v2t[p]]];
          if (c >= 0) used[c] = k;
        }
      }
    int c = 0;
    while (c < cap && used[c] == k) c++;
    if (c == cap) {
      int ncap = 2 * cap;
      int32_t *nu = realloc(used, sizeof(int32_t) * (size_t)ncap);
      if (!nu) {
        st = bs_error_set(err, BS_ENOMEM, "out of memory colouring tets");
        goto done;
      }
      used = nu;
      for (int i = cap; i < ncap; i++) used[i] = -1;
      cap = ncap;
    }
    color[k] = c;
    if (c + 1 > nc) nc = c + 1;
  }
  f->n_colors = nc;
  f->color_ptr = calloc((size_t)nc + 1, sizeof(int32_t));
  f->color_chunks = malloc(sizeof(int32_t) * (size_t)(nk ? nk : 1));
  if (!f->color_ptr || !f->color_chunks) {
    st = bs_error_set(err, BS_ENOMEM, "out of memory colouring tets");
    goto done;
  }
  for (int32_t k = 0; k < nk; k++) f->color_ptr[color[k] + 1]++;
  for (int c = 0; c < nc; c++) f->color_ptr[c + 1] += f->color_ptr[c];
  /* stamp is free now: reuse it as the fill pointers (nc <= nk <= nt <= ns) */
  memcpy(stamp, f->color_ptr, sizeof(int32_t) * (size_t)nc);
  for (int32_t k = 0; k < nk; k++) f->color_chunks[stamp[color[k]]++] = k;
done:
  free(chunk_of);
  free(color);
  free(stamp);
  free(used);
  return st;
}

/* Stores the per-tet data in position order (chunk_tets: position -> tet),
 * so that a chunk's tets are contiguous in memory; tet_pos is the inverse. */
static int permute_to_positions(bs_fem *f, bs_error *err) {
  const size_t nt = (size_t)f->n_tets;
  const size_t n1 = nt ? nt : 1;
  double *Dm = malloc(sizeof(double) * 9 * n1), *vol = malloc(sizeof(double) * n1);
  int32_t *mat = malloc(sizeof(int32_t) * n1), *sl = malloc(sizeof(int32_t) * 16 * n1);
  f->tets = malloc(sizeof(int32_t) * 4 * n1);
  f->tet_pos = malloc(sizeof(int32_t) * n1);
  if (!Dm || !vol || !mat || !sl || !f->tets || !f->tet_pos) {
    free(Dm);
    free(vol);
    free(mat);
    free(sl);
    return bs_error_set(err, BS_ENOMEM, "out of memory ordering %zu tets", nt);
  }
  for (size_t k = 0; k < nt; k++) {
    const size_t t = (size_t)f->chunk_tets[k];
    f->tet_pos[t] = (int32_t)k;
    memcpy(Dm + 9 * k, f->Dm_inv + 9 * t, 9 * sizeof(double));
    vol[k] = f->volume[t];
    mat[k] = f->tet_material[t];
    memcpy(sl + 16 * k, f->slots + 16 * t, 16 * sizeof(int32_t));
    memcpy(f->tets + 4 * k, f->mesh->tets + 4 * t, 4 * sizeof(int32_t));
  }
  free(f->Dm_inv);
  free(f->volume);
  free(f->tet_material);
  free(f->slots);
  f->Dm_inv = Dm;
  f->volume = vol;
  f->tet_material = mat;
  f->slots = sl;
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
  f->order = 1;
  if (mesh->tets10) { /* quadratic tets: fem10.c */
    int st = (f->materials = bs_calloc((size_t)n_materials, sizeof(bs_material), "materials", err)) ? 0 : BS_ENOMEM;
    if (!st) {
      f->n_materials = n_materials;
      memcpy(f->materials, materials, sizeof(bs_material) * (size_t)n_materials);
      st = bs__fem10_create(f, tet_material, err);
    }
    if (st) {
      bs_fem_destroy(&f);
      return st;
    }
    *out = f;
    return 0;
  }
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
  if ((st = bs__fem_color_chunks(f, err))) goto fail;
  if ((st = permute_to_positions(f, err))) goto fail;
  /* Partial energy sums: one per chunk (gradient) or per EBLOCK tets (energy). */
  const int32_t n_part = f->n_chunks > f->n_tets / EBLOCK + 1 ? f->n_chunks : f->n_tets / EBLOCK + 1;
  f->partial = bs_calloc((size_t)n_part, sizeof(double), "the energy partial sums", err);
  if (!f->partial) {
    st = BS_ENOMEM;
    goto fail;
  }
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

/* blk += s * the 3x3 block at he (row stride 12); restrict: the block and
 * the element matrix do not overlap. */
static inline void scatter_block(double *restrict blk, const double *restrict he, double s) {
  for (int i = 0; i < 3; i++) {
    blk[3 * i + 0] += s * he[12 * i + 0];
    blk[3 * i + 1] += s * he[12 * i + 1];
    blk[3 * i + 2] += s * he[12 * i + 2];
  }
}

static void scatter_at(const bs_fem *fem, int32_t k, const double He[144], double scale, bs_bsr *H) {
  const int32_t *sl = fem->slots + 16 * (size_t)k;
  double *val = H->val;
  for (int a = 0; a < 4; a++)
    for (int b = 0; b < 4; b++) scatter_block(val + 9 * (size_t)sl[4 * a + b], He + 12 * 3 * a + 3 * b, scale);
}

void bs_fem_scatter_hessian(const bs_fem *fem, int32_t t, const double He[144], double scale, bs_bsr *H) {
  scatter_at(fem, fem->tet_pos[t], He, scale, H);
}

/* The kernel loops work on batches of up to NB tets (BS_MATERIAL_BATCH: the
 * SVDs of a batch run in SIMD lanes, bs_svd3_batch), split into runs of one
 * material. Results are bit for bit those of the per-tet kernels. */
enum { NB = BS_MATERIAL_BATCH };
_Static_assert(BS_FEM_CHUNK % BS_MATERIAL_BATCH == 0, "BS_FEM_CHUNK must be a multiple of BS_MATERIAL_BATCH");

/* Gathers the coordinates of the tets at positions k0..k0+n (their Dm_inv
 * and volumes are contiguous at the same positions). */
static void gather_batch(const bs_fem *fem, const double *x, int32_t k0, int n, double *restrict xt) {
  const int32_t *tv = fem->tets + 4 * (size_t)k0;
  for (int i = 0; i < 4 * n; i++) {
    const double *xv = x + 3 * (size_t)tv[i];
    xt[3 * i] = xv[0];
    xt[3 * i + 1] = xv[1];
    xt[3 * i + 2] = xv[2];
  }
}

/* Length of the run of positions k0..k0+n with the material of k0. */
static int material_run(const bs_fem *fem, int32_t k0, int n) {
  const int32_t mi = fem->tet_material[k0];
  int j = 1;
  while (j < n && fem->tet_material[k0 + j] == mi) j++;
  return j;
}

/* A colour's chunks run on several threads when it holds at least
 * PAR_CHUNKS chunks (up to 4 BS_FEM_CHUNK tets). */
enum { PAR_CHUNKS = 4 };
static int colour_parallel(const bs_fem *fem, int c) { return fem->color_ptr[c + 1] - fem->color_ptr[c] >= PAR_CHUNKS; }

/* Energies are summed in a fixed order whatever the thread count: per block
 * of EBLOCK positions (energy) or per chunk (gradient) into fem->partial,
 * then the partial sums in order. */

static double energy_block(const bs_fem *fem, const double *x, int32_t lo, int32_t hi) {
  double E = 0;
  for (int32_t k0 = lo; k0 < hi; k0 += NB) {
    const int n = hi - k0 < NB ? (int)(hi - k0) : NB;
    double xt[12 * NB], e[NB];
    gather_batch(fem, x, k0, n, xt);
    for (int i = 0; i < n;) {
      const int32_t k = k0 + i;
      const int r = material_run(fem, k, n - i);
      bs_tet_energy_batch(&fem->materials[fem->tet_material[k]], r, xt + 12 * i, fem->Dm_inv + 9 * (size_t)k,
                          fem->volume + k, e + i);
      i += r;
    }
    for (int i = 0; i < n; i++) E += e[i];
  }
  return E;
}

double bs_fem_elastic_energy(const bs_fem *fem, const double *x) {
  if (fem->order == 2) return bs__fem10_energy(fem, x);
  const int32_t nt = fem->n_tets, nb = (int32_t)(((int64_t)nt + EBLOCK - 1) / EBLOCK);
  double *part = fem->partial;
#pragma omp parallel for schedule(static) if (nb > 2)
  for (int32_t b = 0; b < nb; b++) {
    const int32_t lo = b * EBLOCK;
    part[b] = energy_block(fem, x, lo, nt - lo < EBLOCK ? nt : lo + EBLOCK);
  }
  double E = 0;
  for (int32_t b = 0; b < nb; b++) E += part[b];
  return E;
}

/* One chunk of the gradient: its tets in order, batch by batch. */
static double gradient_chunk(const bs_fem *fem, const double *x, int32_t c, double *g) {
  const int32_t lo = fem->chunk_ptr[c], hi = fem->chunk_ptr[c + 1];
  double E = 0;
  for (int32_t k0 = lo; k0 < hi; k0 += NB) {
    const int n = hi - k0 < NB ? (int)(hi - k0) : NB;
    double xt[12 * NB], e[NB], ge[12 * NB];
    gather_batch(fem, x, k0, n, xt);
    for (int i = 0; i < n;) {
      const int32_t k = k0 + i;
      const int r = material_run(fem, k, n - i);
      bs_tet_energy_grad_batch(&fem->materials[fem->tet_material[k]], r, xt + 12 * i, fem->Dm_inv + 9 * (size_t)k,
                               fem->volume + k, e + i, ge + 12 * i);
      i += r;
    }
    const int32_t *tv = fem->tets + 4 * (size_t)k0;
    for (int i = 0; i < n; i++) {
      E += e[i];
      for (int a = 0; a < 4; a++) {
        double *gv = g + 3 * (size_t)tv[4 * i + a];
        gv[0] += ge[12 * i + 3 * a];
        gv[1] += ge[12 * i + 3 * a + 1];
        gv[2] += ge[12 * i + 3 * a + 2];
      }
    }
  }
  return E;
}

double bs_fem_elastic_gradient(const bs_fem *fem, const double *x, double *g) {
  if (fem->order == 2) return bs__fem10_gradient(fem, x, g);
  double *part = fem->partial; /* part[q]: the chunk at position q of color_chunks */
  for (int c = 0; c < fem->n_colors; c++) {
    const int32_t lo = fem->color_ptr[c], hi = fem->color_ptr[c + 1];
#pragma omp parallel for schedule(dynamic, 1) if (colour_parallel(fem, c))
    for (int32_t q = lo; q < hi; q++) part[q] = gradient_chunk(fem, x, fem->color_chunks[q], g);
  }
  double E = 0;
  for (int32_t q = 0; q < fem->n_chunks; q++) E += part[q];
  return E;
}

/* One chunk of the Hessian: its tets in order, batch by batch; scale s (or
 * material_scale[m] when not NULL, tets with 0 skipped); the definiteness
 * fix project_psd, or when vmax is not NULL BS_PSD_INVERTED for the tets of
 * material m of rest volume <= vmax[m] and BS_PSD_NONE for the others. */
static void hessian_chunk(const bs_fem *fem, const double *x, bs_psd_mode project_psd, const double *vmax, double s,
                          const double *material_scale, int32_t c, bs_bsr *H) {
  const int32_t lo = fem->chunk_ptr[c], hi = fem->chunk_ptr[c + 1];
  for (int32_t k0 = lo; k0 < hi; k0 += NB) {
    const int n = hi - k0 < NB ? (int)(hi - k0) : NB;
    double xt[12 * NB], He[144 * NB];
    gather_batch(fem, x, k0, n, xt);
    /* fetch the batch's blocks while its Hessians are computed */
    for (int i = 0; i < n; i++) {
      const int32_t *sl = fem->slots + 16 * (size_t)(k0 + i);
      for (int b = 0; b < 16; b++) {
        const double *blk = H->val + 9 * (size_t)sl[b];
        __builtin_prefetch(blk, 1, 3);
        __builtin_prefetch(blk + 8, 1, 3);
      }
    }
    for (int i = 0; i < n;) {
      const int32_t k = k0 + i, mi = fem->tet_material[k];
      int r = material_run(fem, k, n - i), mode = project_psd;
      if (vmax) { /* the run's first tets on the same side of vmax */
        const int small = fem->volume[k] <= vmax[mi];
        int q = 1;
        while (q < r && (fem->volume[k + q] <= vmax[mi]) == small) q++;
        r = q;
        mode = small ? BS_PSD_INVERTED : BS_PSD_NONE;
      }
      const double sc = material_scale ? material_scale[mi] : s;
      if (sc != 0 || !material_scale) {
        bs_tet_hessian_batch(&fem->materials[mi], r, xt + 12 * i, fem->Dm_inv + 9 * (size_t)k, fem->volume + k, mode,
                             He + 144 * i);
        for (int j = i; j < i + r; j++) scatter_at(fem, k0 + j, He + 144 * j, sc, H);
      }
      i += r;
    }
  }
}

static void hessian_all(const bs_fem *fem, const double *x, bs_psd_mode project_psd, const double *vmax, double s,
                        const double *material_scale, bs_bsr *H) {
  if (fem->order == 2) {
    bs__fem10_hessian(fem, x, project_psd, vmax, s, material_scale, H);
    return;
  }
  for (int c = 0; c < fem->n_colors; c++) {
    const int32_t lo = fem->color_ptr[c], hi = fem->color_ptr[c + 1];
#pragma omp parallel for schedule(dynamic, 1) if (colour_parallel(fem, c))
    for (int32_t q = lo; q < hi; q++) hessian_chunk(fem, x, project_psd, vmax, s, material_scale, fem->color_chunks[q], H);
  }
}

void bs_fem_elastic_hessian(const bs_fem *fem, const double *x, bs_psd_mode project_psd, double scale, bs_bsr *H) {
  hessian_all(fem, x, project_psd, NULL, scale, NULL, H);
}

void bs_fem_elastic_hessian_auto(const bs_fem *fem, const double *x, const double *vmax, double scale, bs_bsr *H) {
  hessian_all(fem, x, 0, vmax, scale, NULL, H);
}

void bs_fem_elastic_hessian_scaled(const bs_fem *fem, const double *x, bs_psd_mode project_psd,
                                   const double *material_scale, bs_bsr *H) {
  hessian_all(fem, x, project_psd, NULL, 0, material_scale, H);
}

int32_t bs_fem_count_inverted(const bs_fem *fem, const double *x, double *min_detF) {
  if (fem->order == 2) return bs__fem10_count_inverted(fem, x, min_detF);
  int32_t n = 0;
  double mn = INFINITY;
#pragma omp parallel for schedule(static) reduction(+ : n) reduction(min : mn) if (fem->n_tets > 2048)
  for (int32_t t = 0; t < fem->n_tets; t++) {
    double xt[12], F[9];
    gather_batch(fem, x, t, 1, xt); /* t: a position */
    bs_tet_F(xt, fem->Dm_inv + 9 * (size_t)t, F);
    double J = F[0] * (F[4] * F[8] - F[5] * F[7]) - F[1] * (F[3] * F[8] - F[5] * F[6]) +
               F[2] * (F[3] * F[7] - F[4] * F[6]);
    if (!(J > 0)) n++;
    if (J < mn) mn = J;
  }
  if (min_detF) *min_detF = mn;
  return n;
}
