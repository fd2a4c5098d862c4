/* obstacle_output.c — the obstacles of a run written each frame (see
 * bs_obstacle_output.h): analytic shapes as triangle surfaces, grids as
 * image data, one PVD collection per obstacle. */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bs_ls_surface.h"
#include "bs_obstacle_output.h"
#include "outfile.h"

typedef struct obs_out {
  const bs_levelset *ls;
  int grid, moving, written;
  double *phi;       /* a complemented grid's values, negated (else NULL) */
  int n, cap;        /* the PVD's entries                                  */
  double *times;
  char **files;
} obs_out;

struct bs_obstacle_output {
  char dir[BS_MAX_PATH];
  double lo[3], hi[3]; /* the bodies' box at t = 0: a plane's patch */
  int compress;
  int n;
  obs_out *o;
};

void bs_obstacle_output_destroy(bs_obstacle_output **po) {
  if (!po || !*po) return;
  bs_obstacle_output *w = *po;
  for (int k = 0; k < w->n; k++) {
    obs_out *o = &w->o[k];
    for (int i = 0; i < o->n; i++) free(o->files[i]);
    free(o->files);
    free(o->times);
    free(o->phi);
  }
  free(w->o);
  free(w);
  *po = NULL;
}

/* A complemented grid's values, negated once (phi -> -phi). */
static int grid_values(obs_out *o, bs_error *err) {
  int32_t n[3];
  const double *v = bs_levelset_grid_values(o->ls, n, NULL, NULL);
  if (!bs_levelset_is_complement(o->ls)) return 0;
  size_t N = (size_t)n[0] * n[1] * n[2];
  if (!(o->phi = malloc(sizeof(double) * N))) return bs_error_set(err, BS_ENOMEM, "out of memory (a grid of %zu nodes)", N);
  for (size_t i = 0; i < N; i++) o->phi[i] = -v[i];
  return 0;
}

int bs_obstacle_output_create(const char *dir, const bs_sim *s, bs_obstacle_output **out, bs_error *err) {
  double lo[3], hi[3];
  bs_bbox(s->mesh->n_vertices, s->x0, lo, hi);
  return bs_obstacle_output_create_for(dir, s->obstacles, lo, hi, s->scene->out_compress, out, err);
}

int bs_obstacle_output_create_for(const char *dir, const bs_obstacles *obs, const double lo[3], const double hi[3],
                                  int compress, bs_obstacle_output **out, bs_error *err) {
  *out = NULL;
  const int n = obs ? bs_obstacles_count(obs) : 0;
  if (n == 0) return 0;
  bs_obstacle_output *w = calloc(1, sizeof *w);
  if (w) w->o = calloc((size_t)n, sizeof *w->o);
  if (!w || !w->o) {
    free(w);
    return bs_error_set(err, BS_ENOMEM, "out of memory");
  }
  snprintf(w->dir, sizeof w->dir, "%s", dir);
  memcpy(w->lo, lo, sizeof w->lo);
  memcpy(w->hi, hi, sizeof w->hi);
  w->compress = compress;
  w->n = n;
  int st = 0;
  for (int k = 0; k < n && !st; k++) {
    obs_out *o = &w->o[k];
    o->ls = bs_obstacles_levelset(obs, k);
    o->grid = !bs_levelset_is_analytic(o->ls);
    o->moving = bs_levelset_motion(o->ls) != BS_LS_STATIC;
    if (o->grid) st = grid_values(o, err);
  }
  if (st) bs_obstacle_output_destroy(&w);
  *out = w;
  return st;
}

/* The grid at its pose at t: origin c + M (origin0 - c0), axes M. */
static int write_grid(const obs_out *o, double t, const char *path, bs_error *err) {
  bs_vti_grid g = {.name = "phi"};
  double origin0[3];
  g.values = bs_levelset_grid_values(o->ls, g.n, origin0, &g.h);
  if (o->phi) g.values = o->phi;
  bs_levelset_frame f;
  bs_levelset_frame_at(o->ls, t, &f);
  double d[3] = {origin0[0] - o->ls->c0[0], origin0[1] - o->ls->c0[1], origin0[2] - o->ls->c0[2]};
  for (int k = 0; k < 3; k++) g.origin[k] = f.c[k] + f.M[3 * k] * d[0] + f.M[3 * k + 1] * d[1] + f.M[3 * k + 2] * d[2];
  g.direction = f.M;
  return bs_vti_write(&g, path, err);
}

static int write_surface(const bs_obstacle_output *w, const obs_out *o, double t, const char *path, bs_error *err) {
  bs_ls_surface sf;
  int st = bs_ls_surface_make(o->ls, t, w->lo, w->hi, &sf, err);
  if (st) return st;
  bs_vtu_surface v = {.n_points = sf.n_points, .x = sf.x, .n_tris = sf.n_tris, .tris = sf.tris, .compress = w->compress};
  st = bs_surface_write_vtu(&v, path, err);
  bs_ls_surface_free(&sf);
  return st;
}

/* Appends (t, name) to an obstacle's collection. */
static int add_entry(obs_out *o, double t, const char *name, bs_error *err) {
  if (o->n == o->cap) {
    int cap = o->cap ? 2 * o->cap : 64;
    char **nf = realloc(o->files, sizeof(char *) * (size_t)cap);
    if (nf) o->files = nf;
    double *nt = nf ? realloc(o->times, sizeof(double) * (size_t)cap) : NULL;
    if (!nf || !nt) return bs_error_set(err, BS_ENOMEM, "out of memory");
    o->times = nt;
    o->cap = cap;
  }
  if (!(o->files[o->n] = strdup(name))) return bs_error_set(err, BS_ENOMEM, "out of memory");
  o->times[o->n++] = t;
  return 0;
}

/* Rewrites obstacles_K.pvd through a temporary file (obstacles_K.pvd.tmp, a
 * run file too). */
static int write_pvd(const bs_obstacle_output *w, int k, const obs_out *o, bs_error *err) {
  char p[BS_MAX_PATH + 64], tmp[BS_MAX_PATH + 72];
  snprintf(p, sizeof p, "%s/obstacles_%d.pvd", w->dir, k);
  bs_tmp_path(tmp, sizeof tmp, p);
  int st = bs_pvd_write(tmp, o->n, o->times, (const char *const *)o->files, err);
  return st ? st : bs_tmp_commit(tmp, p, err);
}

/* The file name of obstacle k at frame `frame`. */
static void file_name(const obs_out *o, int k, int frame, char *name, size_t n) {
  const char *ext = o->grid ? "vti" : "vtu";
  if (o->moving) snprintf(name, n, "obstacle_%d_%05d.%s", k, frame, ext);
  else snprintf(name, n, "obstacle_%d.%s", k, ext);
}

/* Frame `frame` of obstacle k: its file (with write), its entry. */
static int obstacle_frame(bs_obstacle_output *w, int k, int frame, double t, int write, bs_error *err) {
  obs_out *o = &w->o[k];
  char name[64], path[BS_MAX_PATH + 64], tmp[BS_MAX_PATH + 72];
  file_name(o, k, frame, name, sizeof name);
  snprintf(path, sizeof path, "%s/%s", w->dir, name);
  bs_tmp_path(tmp, sizeof tmp, path);
  int st = 0;
  if (write && (o->moving || !o->written)) {
    st = o->grid ? write_grid(o, t, tmp, err) : write_surface(w, o, t, tmp, err);
    if (!st) st = bs_tmp_commit(tmp, path, err);
  }
  if (!st) st = add_entry(o, t, name, err);
  if (!st && write) st = write_pvd(w, k, o, err);
  if (st) bs_error_prefix(err, "obstacle %d", k);
  else o->written = 1;
  return st;
}

int bs_obstacle_output_frame(bs_obstacle_output *w, const bs_sim *s, int frame, bs_error *err) {
  return bs_obstacle_output_frame_at(w, s->time, frame, err);
}

int bs_obstacle_output_frame_at(bs_obstacle_output *w, double t, int frame, bs_error *err) {
  if (!w) return 0;
  int st = 0;
  for (int k = 0; k < w->n && !st; k++) st = obstacle_frame(w, k, frame, t, 1, err);
  return st;
}

int bs_obstacle_output_skip(bs_obstacle_output *w, int frame, double t, bs_error *err) {
  if (!w) return 0;
  int st = 0;
  for (int k = 0; k < w->n && !st; k++) st = obstacle_frame(w, k, frame, t, 0, err);
  return st;
}

int bs_obstacle_output_write_pvds(bs_obstacle_output *w, bs_error *err) {
  int st = 0;
  for (int k = 0; w && k < w->n && !st; k++) st = write_pvd(w, k, &w->o[k], err);
  return st;
}
