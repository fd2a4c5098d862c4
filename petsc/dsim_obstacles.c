/* dsim_obstacles.c — a petsc-backend scene's obstacles: collision/'s
 * bs_obstacles on each rank's fem of its owned cells, its vertices owned or
 * not marked, the touching tolerance of the whole mesh (bs_dsim.h,
 * bs_obstacles.h). */
#include <stdlib.h>

#include "bs_dist.h"
#include "dsim_internal.h"

/* The rest bounding box of the whole mesh (over the ranks). */
static int global_bounds(const bs_dmesh *m, double lo[3], double hi[3], bs_error *err) {
  bs_bbox(m->n_vertices, m->x, lo, hi);
  double e[6] = {-lo[0], -lo[1], -lo[2], hi[0], hi[1], hi[2]};
  int rc = bs_dist_max(e, 6, err);
  for (int k = 0; k < 3; k++) lo[k] = -e[k], hi[k] = e[3 + k];
  return rc;
}

/* The obstacles over df->fem: the mask and the owned vertices in the local
 * mesh's order. */
static int create(bs_dsim *s, bs_error *err) {
  const bs_dmesh *dm = s->mesh;
  const int32_t n = dm->local->n_vertices;
  uint8_t *mask = bs_calloc(2 * (size_t)n + 1, 1, "obstacle masks", err);
  if (!mask) return BS_ENOMEM;
  uint8_t *own = mask + n;
  int64_t missing = dm->n_owned; /* owned vertices outside the owned cells */
  for (int32_t i = 0; i < n; i++) {
    mask[i] = s->mask[dm->local_vertex[i]];
    own[i] = dm->owned[dm->local_vertex[i]];
    missing -= own[i];
  }
  double lo[3], hi[3];
  int rc = global_bounds(dm, lo, hi, err);
  if (!rc) rc = bs_dist_sum_i64(&missing, 1, err);
  if (!rc && missing)
    rc = bs_error_set(err, BS_EINTERNAL, "obstacles: %lld owned vertices are in no owned cell (the projections need "
                      "each vertex on its owner's mesh)", (long long)missing);
  if (!rc) rc = bs_obstacles_create(s->df->fem, &s->step, mask, &s->obstacles, err);
  if (!rc) rc = bs_obstacles_set_owned(s->obstacles, own, err);
  free(mask);
  if (!rc) bs_obstacles_set_bounds(s->obstacles, lo, hi);
  s->size = bs_bbox_diagonal(lo, hi);
  return rc;
}

int bs__dsim_make_obstacles(bs_dsim *s, bs_error *err) {
  const bs_scene *sc = s->scene;
  if (sc->n_obstacles == 0) return BS_OK;
  int rc = create(s, err);
  static const double zero[3] = {0, 0, 0};
  for (int i = 0; i < sc->n_obstacles && !rc; i++) {
    const bs_scene_obstacle *o = &sc->obstacles[i];
    bs_levelset *ls = NULL;
    rc = bs_scene_obstacle_levelset(o, zero, zero, 0, &ls, err);
    if (!rc) rc = bs_obstacles_add(s->obstacles, ls, o->collision, o->stiffness, o->friction, err);
    if (rc) bs_error_prefix(err, "%s: obstacles.%d", sc->path, i);
  }
  if (rc) return rc;
  bs_term *const *pt = NULL;
  const int np = bs_obstacles_terms(s->obstacles, &pt);
  if (s->n_terms + np > BS_DSIM_MAX_TERMS) return bs_error_set(err, BS_EINPUT, "%s: too many terms", sc->path);
  for (int i = 0; i < np; i++) s->terms[s->n_terms++] = pt[i];
  return BS_OK;
}

int bs__dsim_set_hooks(bs_dsim *s, bs_error *err) {
  if (!s->obstacles) return BS_OK;
  bs_step_hooks h;
  bs_obstacles_hooks(s->obstacles, &h);
  /* Its post_solve is friction (refused by bs_dsim_check; with friction 0 it
     only forgets the labels, which the next step's first projection does). */
  h.post_solve = NULL;
  return h.project ? bs_dintegrator_set_hooks(s->integrator, &h, err) : BS_OK;
}

int bs_dsim_penetration(bs_dsim *s, int64_t *count, double *max_depth, bs_error *err) {
  int32_t c = 0;
  double d = 0;
  if (s->obstacles) {
    bs_dfem_mesh_vector(s->df, s->x, s->xm);
    bs_obstacles_penetration(s->obstacles, s->time, s->xm, 1e-10 * s->size, &c, &d);
  }
  *count = c;
  int rc = bs_dist_sum_i64(count, 1, err);
  if (!rc) rc = bs_dist_max(&d, 1, err);
  *max_depth = d;
  return rc;
}

int bs_dsim_active_pairs(const bs_dsim *s, int64_t *n, bs_error *err) {
  *n = s->obstacles ? bs_obstacles_active_count(s->obstacles) : 0;
  return bs_dist_sum_i64(n, 1, err);
}
