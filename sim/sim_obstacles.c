/* sim_obstacles.c — the scene's obstacles (level sets, their motion, how they
 * collide), the hooks the integrator calls (projection, friction), and the
 * positions of scripted vertices in time. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bs_penalty.h"
#include "bs_selfcollide.h"
#include "sim_internal.h"

void bs_scene_script_offset(const bs_scene_script *sc, double t, double off[3]) {
  off[0] = off[1] = off[2] = 0;
  if (sc->kind == BS_SCRIPT_VELOCITY) {
    for (int k = 0; k < 3; k++) off[k] = sc->velocity[k] * t;
  } else if (sc->kind == BS_SCRIPT_KEYFRAMES) {
    int n = sc->n_keys;
    if (t <= sc->key_t[0]) memcpy(off, sc->key_offset, 3 * sizeof(double));
    else if (t >= sc->key_t[n - 1]) memcpy(off, sc->key_offset + 3 * (n - 1), 3 * sizeof(double));
    else
      for (int j = 0; j + 1 < n; j++)
        if (t >= sc->key_t[j] && t <= sc->key_t[j + 1]) {
          double w = (t - sc->key_t[j]) / (sc->key_t[j + 1] - sc->key_t[j]);
          for (int k = 0; k < 3; k++)
            off[k] = (1 - w) * sc->key_offset[3 * j + k] + w * sc->key_offset[3 * (j + 1) + k];
          break;
        }
  }
}

void bs__sim_script_positions(double t, double *x, void *ctx) {
  bs_sim *s = ctx;
  for (int i = 0; i < s->n_scripts; i++) {
    const bs_sim_script *ss = &s->scripts[i];
    double off[3];
    bs_scene_script_offset(ss->script, t, off);
    for (int32_t q = 0; q < ss->n; q++) {
      int32_t v = ss->vertices[q];
      for (int k = 0; k < 3; k++) x[3 * v + k] = s->x0[3 * v + k] + off[k];
    }
  }
}

/* With self-collision or friction, the hooks go through the sim so that
 * post_solve can apply the obstacles' friction and then self-contact
 * friction, and record the friction impulse. */
static void sim_project(double *x, void *ctx) {
  bs_sim *s = ctx;
  s->obstacle_hooks.project(x, s->obstacle_hooks.ctx);
}
static void sim_register_active(const double *x, const double *g, void *ctx) {
  bs_sim *s = ctx;
  s->obstacle_hooks.register_active(x, g, s->obstacle_hooks.ctx);
}
static void sim_project_gradient(const double *x, double *g, void *ctx) {
  bs_sim *s = ctx;
  s->obstacle_hooks.project_gradient(x, g, s->obstacle_hooks.ctx);
}
static void sim_project_hessian(const double *x, const double *g, bs_bsr *H, void *ctx) {
  bs_sim *s = ctx;
  s->obstacle_hooks.project_hessian(x, g, H, s->obstacle_hooks.ctx);
}
static int sim_post_solve(const double *x_n, double *x, const double *g, double *v, double dt, void *ctx,
                          bs_error *err) {
  bs_sim *s = ctx;
  int st = 0;
  const size_t n3 = 3 * (size_t)s->mesh->n_vertices;
  if (s->friction_impulse && !s->obstacle_hooks.post_solve) memset(s->friction_impulse, 0, sizeof(double) * n3);
  if (s->obstacle_hooks.post_solve && (st = s->obstacle_hooks.post_solve(x_n, x, g, v, dt, s->obstacle_hooks.ctx, err)))
    return st;
  if (s->self && s->scene->self_friction > 0) { /* penalty self-contact (barrier: a term of the solve) */
    int32_t n = 0;
    memcpy(s->v_pre, v, sizeof(double) * n3);
    if ((st = bs_self_friction(s->self, x, s->scene->self_friction, dt, s->mask, v, &n, err))) return st;
    for (size_t i = 0; i < n3; i++) s->friction_impulse[i] += v[i] - s->v_pre[i];
  }
  if (s->friction_impulse)
    for (size_t i = 0; i < n3; i++) s->friction_impulse[i] *= s->fem->mass[i / 3];
  return 0;
}

int bs__sim_make_friction(bs_sim *s, bs_error *err) {
  const bs_scene *sc = s->scene;
  /* barrier self-contact friction is a term of the solve (bs_ipc_friction.h), not a post-solve pass */
  const int self = sc->self_collision && sc->self_model != BS_SELF_MODEL_BARRIER && sc->self_friction > 0;
  int any = self;
  for (int i = 0; i < sc->n_obstacles; i++) any |= sc->obstacles[i].friction > 0;
  if (!any || sc->mode != BS_MODE_DYNAMIC) return 0;
  const size_t n3 = 3 * (size_t)s->mesh->n_vertices;
  s->friction_impulse = calloc(n3 ? n3 : 1, sizeof(double));
  if (self) s->v_pre = malloc(sizeof(double) * (n3 ? n3 : 1));
  if (!s->friction_impulse || (self && !s->v_pre)) return bs_error_set(err, BS_ENOMEM, "out of memory (friction)");
  if (s->obstacles) bs_obstacles_friction_output(s->obstacles, s->friction_impulse);
  return 0;
}

void bs__sim_hooks(bs_sim *s, bs_step_hooks *hooks) {
  memset(hooks, 0, sizeof *hooks);
  if (s->obstacles) bs_obstacles_hooks(s->obstacles, &s->obstacle_hooks);
  *hooks = s->obstacle_hooks;
  if (!s->self && !s->friction_impulse) return;
  hooks->post_solve = sim_post_solve; /* friction of both kinds after the solve, its impulse */
  hooks->ctx = s;
  if (s->obstacle_hooks.project) hooks->project = sim_project;
  if (s->obstacle_hooks.register_active) hooks->register_active = sim_register_active;
  if (s->obstacle_hooks.project_gradient) hooks->project_gradient = sim_project_gradient;
  if (s->obstacle_hooks.project_hessian) hooks->project_hessian = sim_project_hessian;
}

/* The analytic shape or grid file of an obstacle. */
static int obstacle_shape(const bs_scene_obstacle *o, bs_levelset **ls, bs_error *err) {
  switch (o->shape) {
    case BS_SHAPE_PLANE: return bs_levelset_create_halfspace(o->normal, o->offset, ls, err);
    case BS_SHAPE_SPHERE: return bs_levelset_create_sphere(o->center, o->radius, ls, err);
    case BS_SHAPE_BOX: return bs_levelset_create_box(o->center, o->half_extents, ls, err);
    case BS_SHAPE_CYLINDER: return bs_levelset_create_cylinder(o->center, o->axis, o->radius, o->half_height, ls, err);
    case BS_SHAPE_TORUS: return bs_levelset_create_torus(o->center, o->axis, o->major, o->minor, ls, err);
    case BS_SHAPE_GRID: return bs_levelset_grid_load(o->grid_file, ls, err);
  }
  return bs_error_set(err, BS_EINPUT, "unknown shape %d", (int)o->shape);
}

/* Its motion: a constant velocity and spin, or keyframes (rotations in degrees). */
static int obstacle_motion(const bs_scene_obstacle *o, bs_levelset *ls, bs_error *err) {
  int st = 0;
  if (o->velocity[0] || o->velocity[1] || o->velocity[2] || o->angular_velocity[0] || o->angular_velocity[1] ||
      o->angular_velocity[2])
    st = bs_levelset_set_velocity(ls, o->velocity, o->angular_velocity, err);
  if (st || o->n_keys <= 0) return st;
  double *rot = malloc(sizeof(double) * 3 * (size_t)o->n_keys);
  if (!rot) return bs_error_set(err, BS_ENOMEM, "out of memory");
  for (int k = 0; k < 3 * o->n_keys; k++) rot[k] = o->key_rotate[k] * M_PI / 180.0;
  st = bs_levelset_set_keyframes(ls, o->n_keys, o->key_t, o->key_translate, rot, err);
  free(rot);
  return st;
}

int bs_scene_obstacle_levelset(const bs_scene_obstacle *o, const double lo[3], const double hi[3], double margin,
                               bs_levelset **out, bs_error *err) {
  bs_levelset *ls = NULL;
  int st = obstacle_shape(o, &ls, err);
  if (!st && o->inside_out) bs_levelset_set_complement(ls, 1);
  if (!st) st = obstacle_motion(o, ls, err);
  if (!st && o->grid_h > 0 && o->shape != BS_SHAPE_GRID) {
    double glo[3], ghi[3];
    for (int k = 0; k < 3; k++) {
      glo[k] = lo[k] - margin;
      ghi[k] = hi[k] + margin;
    }
    bs_levelset *g = NULL;
    st = bs_levelset_grid_sample(ls, 0.0, glo, ghi, o->grid_h, &g, err);
    bs_levelset_destroy(&ls);
    ls = g;
  }
  if (st) bs_levelset_destroy(&ls);
  *out = ls;
  return st;
}

/* Obstacle i as a level set, a grid sampled around the bodies with one
 * diagonal of margin. */
static int obstacle_levelset(const bs_sim *s, int i, bs_levelset **out, bs_error *err) {
  double lo[3], hi[3];
  bs_bbox(s->mesh->n_vertices, s->x0, lo, hi);
  return bs_scene_obstacle_levelset(&s->scene->obstacles[i], lo, hi, s->size, out, err);
}

int bs__sim_make_obstacles(bs_sim *s, bs_error *err) {
  const bs_scene *sc = s->scene;
  int st = bs_obstacles_create(s->fem, &s->step, s->mask, &s->obstacles, err);
  if (st) return st;
  bs_obstacles_allow_barrier(s->obstacles); /* bs__sim_make_obstacle_barrier builds its term */
  for (int i = 0; i < sc->n_obstacles; i++) {
    const bs_scene_obstacle *o = &sc->obstacles[i];
    bs_levelset *ls = NULL;
    if ((st = obstacle_levelset(s, i, &ls, err)) ||
        (st = bs_obstacles_add(s->obstacles, ls, o->collision, o->stiffness, o->friction, err))) {
      bs_error_prefix(err, "%s: obstacles.%d", sc->path, i);
      return st;
    }
  }
  bs_term *const *pt = NULL;
  int np = bs_obstacles_terms(s->obstacles, &pt);
  if (s->n_terms + np > BS_SIM_MAX_TERMS)
    return bs_error_set(err, BS_EINPUT, "%s: too many penalty obstacles (%d)", sc->path, np);
  for (int i = 0; i < np; i++) s->terms[s->n_terms++] = pt[i];
  return 0;
}
