/* ls_sample.c — a grid level set sampled from the signed distance to a
 * closed triangle surface (bs_ls_sample.h): the plan, the sampling over
 * OpenMP threads with the shim's tree, the level set and its file. */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "bs_ls_sample.h"
#include "bs_shim.h"

#ifdef _OPENMP
#include <omp.h>
#endif

/* The box of the points triangles use (a soup may carry unused points). */
static void soup_box(const bs_ls_soup *s, double lo[3], double hi[3]) {
  for (int k = 0; k < 3; k++) {
    lo[k] = 1e300;
    hi[k] = -1e300;
  }
  for (int64_t t = 0; t < 3 * s->n_tris; t++)
    for (int k = 0; k < 3; k++) {
      double c = s->x[3 * (int64_t)s->tris[t] + k];
      lo[k] = fmin(lo[k], c);
      hi[k] = fmax(hi[k], c);
    }
}

int bs_ls_grid_plan_make(const bs_ls_soup *s, const char *name, double h, double margin, bs_ls_grid_plan *g,
                         bs_error *err) {
  memset(g, 0, sizeof *g);
  soup_box(s, g->lo, g->hi);
  const double *lo = g->lo, *hi = g->hi;
  double ext = fmax(hi[0] - lo[0], fmax(hi[1] - lo[1], hi[2] - lo[2]));
  if (!(ext > 0)) return bs_error_set(err, BS_EINPUT, "'%s': the surface has no extent", name);
  g->h = h > 0 ? h : ext / 40;
  g->margin = margin >= 0 ? margin : fmax(0.1 * ext, 2 * g->h);
  g->total = 1;
  for (int k = 0; k < 3; k++) {
    g->origin[k] = lo[k] - g->margin;
    double cells = ceil((hi[k] - lo[k] + 2 * g->margin) / g->h);
    if (cells < 1) cells = 1;
    if (cells + 1 > 1e9)
      return bs_error_set(err, BS_EINPUT, "grid spacing h = %g m: too many grid nodes along axis %d", g->h, k);
    g->n[k] = (int32_t)cells + 1;
    g->total *= g->n[k];
    if (g->total > INT32_MAX)
      return bs_error_set(err, BS_EINPUT, "grid spacing h = %g m: the grid would have more than 2^31 - 1 nodes",
                          g->h);
  }
  return BS_OK;
}

/* Samples the signed distance at every node: one z slice per task. */
static int sample_tree(const bs_shim_tree *tree, const bs_ls_grid_plan *g, double *values, bs_error *err) {
  const int32_t *n = g->n;
  const int64_t slice = (int64_t)n[0] * n[1];
  int st = 0;
#pragma omp parallel
  {
    double *q = malloc(sizeof(double) * 3 * (size_t)slice);
    bs_error e;
    int my = q ? 0 : BS_ENOMEM;
    e.msg[0] = 0;
#pragma omp for schedule(dynamic, 1)
    for (int32_t k = 0; k < n[2]; k++) {
      if (my) continue;
      for (int32_t j = 0; j < n[1]; j++)
        for (int32_t i = 0; i < n[0]; i++) {
          double *p = q + 3 * ((int64_t)i + (int64_t)n[0] * j);
          p[0] = g->origin[0] + g->h * i;
          p[1] = g->origin[1] + g->h * j;
          p[2] = g->origin[2] + g->h * k;
        }
      my = bs_shim_signed_distance(tree, q, slice, values + slice * k, &e);
    }
#pragma omp critical
    if (my && !st) {
      st = my;
      if (my == BS_ENOMEM) bs_error_set(err, BS_ENOMEM, "out of memory sampling the grid");
      else *err = e;
    }
    free(q);
  }
  return st;
}

static void value_range(const double *values, int64_t total, bs_ls_sample_info *info) {
  double vmin = values[0], vmax = values[0];
  int64_t n_inside = 0;
  for (int64_t i = 0; i < total; i++) {
    vmin = fmin(vmin, values[i]);
    vmax = fmax(vmax, values[i]);
    n_inside += values[i] < 0;
  }
  info->phi_min = vmin;
  info->phi_max = vmax;
  info->n_inside = n_inside;
}

int bs_ls_sample_grid(const bs_ls_soup *s, const bs_ls_grid_plan *g, double *values, bs_ls_sample_info *info,
                      bs_error *err) {
  bs_ls_sample_info local;
  if (!info) info = &local;
  memset(info, 0, sizeof *info);
  info->threads = 1;
#ifdef _OPENMP
  info->threads = omp_get_max_threads();
#endif
  double t0 = bs_seconds();
  bs_shim_tree *tree = NULL;
  int st = bs_shim_tree_create(s->x, s->n_points, s->tris, s->n_tris, &tree, err);
  if (st) return st;
  double t1 = bs_seconds();
  st = sample_tree(tree, g, values, err);
  bs_shim_tree_destroy(&tree);
  if (st) return st;
  info->t_tree = t1 - t0;
  info->t_sample = bs_seconds() - t1;
  value_range(values, g->total, info);
  return BS_OK;
}

int bs_ls_from_surface(const bs_ls_soup *s, const char *name, double h, double margin, bs_ls_grid_plan *g,
                       bs_ls_sample_info *info, bs_levelset **out, bs_error *err) {
  *out = NULL;
  bs_ls_grid_plan local_g;
  bs_ls_sample_info local_i;
  if (!g) g = &local_g;
  if (!info) info = &local_i;
  double t0 = bs_seconds();
  if (s->n_tris < 1) return bs_error_set(err, BS_EINPUT, "'%s': no triangles", name);
  int st = bs_ls_soup_check_closed(s, name, err);
  if (st || (st = bs_ls_grid_plan_make(s, name, h, margin, g, err))) return st;
  double t_checks = bs_seconds() - t0;
  double *values = malloc(sizeof(double) * (size_t)g->total);
  if (!values) return bs_error_set(err, BS_ENOMEM, "out of memory: a grid of %lld nodes", (long long)g->total);
  if (!(st = bs_ls_sample_grid(s, g, values, info, err))) {
    info->t_tree += t_checks;
    st = bs_levelset_grid_from_values(g->origin, g->h, g->n, values, out, err);
  }
  free(values);
  return st;
}

int bs_ls_sample_write(const bs_levelset *ls, const char *path, bs_error *err) {
  bs_vti_grid g = {.name = "phi"};
  g.values = bs_levelset_grid_values(ls, g.n, g.origin, &g.h);
  if (!g.values) return bs_error_set(err, BS_EINPUT, "'%s': the level set is not a grid", path);
  const char *dot = strrchr(path, '.');
  if (!dot || strchr(dot, '/') || strcmp(dot, ".vti")) return bs_levelset_grid_save(ls, path, err);
  return bs_vti_write(&g, path, err);
}
