/* sim.c — from a validated scene to a runnable simulation. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "app.h"
#include "bs_penalty.h"
#include "bs_selfcollide.h"
#include "sim.h"

void bs_sim_destroy(bs_sim **ps) {
  if (!ps || !*ps) return;
  bs_sim *s = *ps;
  bs_integrator_destroy(&s->integrator);
  for (int i = 0; i < s->n_terms; i++)
    if (!bs_term_is_penalty(s->terms[i])) bs_term_destroy(&s->terms[i]);
  bs_obstacles_destroy(&s->obstacles);
  bs_fem_destroy(&s->fem);
  for (int i = 0; i < s->n_scripts; i++) free(s->scripts[i].vertices);
  free(s->scripts);
  free(s->materials);
  free(s->tet_material);
  free(s->mask);
  free(s->x0);
  free(s->x);
  free(s->v);
  bs_mesh_destroy(&s->mesh);
  free(s);
  *ps = NULL;
}

/* Rotation matrix from an axis-angle vector given in degrees. */
static void axis_angle(const double r[3], double R[9]) {
  double th = sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]) * M_PI / 180.0;
  for (int i = 0; i < 9; i++) R[i] = (i % 4 == 0);
  if (th == 0) return;
  double n = th * 180.0 / M_PI, k[3] = {r[0] / n, r[1] / n, r[2] / n};
  double c = cos(th), s = sin(th), C = 1 - c;
  R[0] = c + k[0] * k[0] * C;
  R[1] = k[0] * k[1] * C - k[2] * s;
  R[2] = k[0] * k[2] * C + k[1] * s;
  R[3] = k[1] * k[0] * C + k[2] * s;
  R[4] = c + k[1] * k[1] * C;
  R[5] = k[1] * k[2] * C - k[0] * s;
  R[6] = k[2] * k[0] * C - k[1] * s;
  R[7] = k[2] * k[1] * C + k[0] * s;
  R[8] = c + k[2] * k[2] * C;
}

/* Uniform random in [0,1) from a 64-bit LCG/xorshift (repeatable across platforms). */
static double rnd(uint64_t *s) {
  *s ^= *s << 13;
  *s ^= *s >> 7;
  *s ^= *s << 17;
  return (double)(*s >> 11) * (1.0 / 9007199254740992.0);
}

static void script_positions(double t, double *x, void *ctx) {
  bs_sim *s = ctx;
  for (int i = 0; i < s->n_scripts; i++) {
    const bs_sim_script *ss = &s->scripts[i];
    const bs_scene_script *sc = ss->script;
    double off[3] = {0, 0, 0};
    if (sc->kind == BS_SCRIPT_VELOCITY) {
      for (int k = 0; k < 3; k++) off[k] = sc->velocity[k] * t;
    } else if (sc->kind == BS_SCRIPT_KEYFRAMES) {
      int n = sc->n_keys;
      if (t <= sc->key_t[0]) memcpy(off, sc->key_offset, sizeof off);
      else if (t >= sc->key_t[n - 1]) memcpy(off, sc->key_offset + 3 * (n - 1), sizeof off);
      else
        for (int j = 0; j + 1 < n; j++)
          if (t >= sc->key_t[j] && t <= sc->key_t[j + 1]) {
            double w = (t - sc->key_t[j]) / (sc->key_t[j + 1] - sc->key_t[j]);
            for (int k = 0; k < 3; k++)
              off[k] = (1 - w) * sc->key_offset[3 * j + k] + w * sc->key_offset[3 * (j + 1) + k];
            break;
          }
    }
    for (int32_t q = 0; q < ss->n; q++) {
      int32_t v = ss->vertices[q];
      for (int k = 0; k < 3; k++) x[3 * v + k] = s->x0[3 * v + k] + off[k];
    }
  }
}

/* With self-collision, the hooks go through the sim so that post_solve can
 * apply the obstacles' friction and then self-contact friction. */
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
  if (s->obstacle_hooks.post_solve && (st = s->obstacle_hooks.post_solve(x_n, x, g, v, dt, s->obstacle_hooks.ctx, err)))
    return st;
  if (s->scene->self_friction > 0) {
    int32_t n = 0;
    st = bs_self_friction(s->self, x, s->scene->self_friction, dt, s->mask, v, &n, err);
  }
  return st;
}

void bs_sim_self_contacts(bs_sim *s, int32_t *count, double *max_depth) {
  *count = 0;
  *max_depth = 0;
  bs_error err;
  if (s->self) bs_term_self_detect(s->self, s->x, count, max_depth, &err);
}

void bs_sim_penetration(const bs_sim *s, int32_t *count, double *max_depth) {
  *count = 0;
  *max_depth = 0;
  if (s->obstacles) bs_obstacles_penetration(s->obstacles, s->time, s->x, 1e-10 * s->size, count, max_depth);
}

/* The scene's obstacles: level sets, their motion, the collision way. */
static int make_obstacles(bs_sim *s, bs_error *err) {
  const bs_scene *sc = s->scene;
  int st = bs_obstacles_create(s->fem, &s->step, s->mask, &s->obstacles, err);
  if (st) return st;
  double lo[3] = {1e300, 1e300, 1e300}, hi[3] = {-1e300, -1e300, -1e300};
  for (int32_t v = 0; v < s->mesh->n_vertices; v++)
    for (int k = 0; k < 3; k++) {
      lo[k] = fmin(lo[k], s->x0[3 * v + k]);
      hi[k] = fmax(hi[k], s->x0[3 * v + k]);
    }
  double diag = sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                     (hi[2] - lo[2]) * (hi[2] - lo[2]));
  s->size = diag;
  for (int i = 0; i < sc->n_obstacles; i++) {
    const bs_scene_obstacle *o = &sc->obstacles[i];
    bs_levelset *ls = NULL;
    if (!strcmp(o->shape, "plane")) st = bs_levelset_create_halfspace(o->normal, o->offset, &ls, err);
    else if (!strcmp(o->shape, "sphere")) st = bs_levelset_create_sphere(o->center, o->radius, &ls, err);
    else if (!strcmp(o->shape, "box")) st = bs_levelset_create_box(o->center, o->half_extents, &ls, err);
    else if (!strcmp(o->shape, "cylinder"))
      st = bs_levelset_create_cylinder(o->center, o->axis, o->radius, o->half_height, &ls, err);
    else if (!strcmp(o->shape, "torus")) st = bs_levelset_create_torus(o->center, o->axis, o->major, o->minor, &ls, err);
    else st = bs_levelset_grid_load(o->grid_file, &ls, err);
    if (!st && o->inside_out) bs_levelset_set_complement(ls, 1);
    if (!st && (o->velocity[0] || o->velocity[1] || o->velocity[2] || o->angular_velocity[0] ||
                o->angular_velocity[1] || o->angular_velocity[2]))
      st = bs_levelset_set_velocity(ls, o->velocity, o->angular_velocity, err);
    if (!st && o->n_keys > 0) {
      double *rot = malloc(sizeof(double) * 3 * (size_t)o->n_keys);
      if (!rot) st = bs_error_set(err, BS_ENOMEM, "out of memory");
      for (int k = 0; !st && k < 3 * o->n_keys; k++) rot[k] = o->key_rotate[k] * M_PI / 180.0;
      if (!st) st = bs_levelset_set_keyframes(ls, o->n_keys, o->key_t, o->key_translate, rot, err);
      free(rot);
    }
    if (!st && o->grid_h > 0 && strcmp(o->shape, "grid")) {
      /* sample the analytic shape onto a grid around the bodies (one diagonal of margin) */
      double glo[3], ghi[3];
      for (int k = 0; k < 3; k++) {
        glo[k] = lo[k] - diag;
        ghi[k] = hi[k] + diag;
      }
      bs_levelset *g = NULL;
      st = bs_levelset_grid_sample(ls, 0.0, glo, ghi, o->grid_h, &g, err);
      bs_levelset_destroy(&ls);
      ls = g;
    }
    if (st) {
      bs_levelset_destroy(&ls);
      bs_error_prefix(err, "%s: obstacles.%d", sc->path, i);
      return st;
    }
    bs_collide_mode mode;
    if ((st = bs_collide_mode_parse(o->collision, &mode, err)) ||
        (st = bs_obstacles_add(s->obstacles, ls, mode, o->stiffness, o->friction, err))) {
      bs_error_prefix(err, "%s: obstacles.%d", sc->path, i);
      return st;
    }
  }
  bs_term *const *pt = NULL;
  int np = bs_obstacles_terms(s->obstacles, &pt);
  if (s->n_terms + np > (int)(sizeof s->terms / sizeof s->terms[0]))
    return bs_error_set(err, BS_EINPUT, "%s: too many penalty obstacles (%d)", sc->path, np);
  for (int i = 0; i < np; i++) s->terms[s->n_terms++] = pt[i];
  return 0;
}

/* Appends mesh b into the arrays of the merged mesh. */
typedef struct merged {
  int32_t nv, nt;
  double *x;
  int32_t *tets;
} merged;

int bs_sim_create(const bs_scene *sc, bs_sim **out, bs_error *err) {
  *out = NULL;
  int st = 0;
  bs_sim *s = calloc(1, sizeof *s);
  if (!s) return bs_error_set(err, BS_ENOMEM, "out of memory");
  s->scene = sc;
  int nb = sc->n_bodies;
  bs_mesh **meshes = calloc((size_t)nb, sizeof(bs_mesh *));
  int32_t *voff = calloc((size_t)nb + 1, sizeof(int32_t)), *toff = calloc((size_t)nb + 1, sizeof(int32_t));
  int *moff = calloc((size_t)nb + 1, sizeof(int));
  if (!meshes || !voff || !toff || !moff) {
    st = bs_error_set(err, BS_ENOMEM, "out of memory");
    goto done;
  }
  /* 1. meshes, transformed */
  for (int b = 0; b < nb; b++) {
    const bs_scene_body *bd = &sc->bodies[b];
    if (!strcmp(bd->mesh, "box")) {
      double lo[3] = {0, 0, 0};
      st = bs_mesh_create_box(lo, bd->box_size, bd->box_cells[0], bd->box_cells[1], bd->box_cells[2], &meshes[b], err);
      for (int r = 0; !st && r < bd->refine; r++) {
        bs_mesh *f = NULL;
        st = bs_mesh_refine(meshes[b], &f, err);
        bs_mesh_destroy(&meshes[b]);
        meshes[b] = f;
      }
    } else {
      bs_mesh_read_opts o = {.size = bd->mesh_size, .refine = bd->refine};
      st = bs_mesh_read(bd->mesh, &o, &meshes[b], err);
    }
    if (!st && bd->reorder != BS_ORDER_NONE) st = bs_mesh_reorder(meshes[b], bd->reorder, NULL, err);
    if (st) {
      bs_error_prefix(err, "%s: bodies.%d", sc->path, b);
      goto done;
    }
    double R[9];
    axis_angle(bd->rotate, R);
    bs_mesh *m = meshes[b];
    for (int32_t v = 0; v < m->n_vertices; v++) {
      double p[3];
      for (int k = 0; k < 3; k++) p[k] = m->x[3 * v + k] * bd->scale[k];
      for (int k = 0; k < 3; k++) m->x[3 * v + k] = R[3 * k] * p[0] + R[3 * k + 1] * p[1] + R[3 * k + 2] * p[2] + bd->translate[k];
    }
    voff[b + 1] = voff[b] + m->n_vertices;
    toff[b + 1] = toff[b] + m->n_tets;
    moff[b + 1] = moff[b] + bd->n_materials;
  }
  /* 2. merged mesh (a single body is used as is) */
  if (nb == 1) {
    s->mesh = meshes[0];
    meshes[0] = NULL;
  } else {
    double *x = calloc(3 * (size_t)voff[nb], sizeof(double));
    int32_t *tets = calloc(4 * (size_t)toff[nb], sizeof(int32_t));
    if (!x || !tets) {
      free(x);
      free(tets);
      st = bs_error_set(err, BS_ENOMEM, "out of memory merging bodies");
      goto done;
    }
    for (int b = 0; b < nb; b++) {
      memcpy(x + 3 * (size_t)voff[b], meshes[b]->x, sizeof(double) * 3 * (size_t)meshes[b]->n_vertices);
      for (int64_t i = 0; i < 4 * (int64_t)meshes[b]->n_tets; i++) tets[4 * (size_t)toff[b] + i] = meshes[b]->tets[i] + voff[b];
    }
    st = bs_mesh_create(voff[nb], x, toff[nb], tets, 0, NULL, &s->mesh, err);
    free(x);
    free(tets);
    if (st) goto done;
    if (s->mesh->n_vertices != voff[nb]) {
      st = bs_error_set(err, BS_EINTERNAL, "merging bodies changed the vertex count");
      goto done;
    }
  }
  int32_t nv = s->mesh->n_vertices, nt = s->mesh->n_tets;
  size_t n3 = 3 * (size_t)nv;
  s->x0 = malloc(sizeof(double) * n3);
  s->x = malloc(sizeof(double) * n3);
  s->v = calloc(n3, sizeof(double));
  s->mask = malloc((size_t)nv);
  s->tet_material = calloc((size_t)nt, sizeof(int32_t));
  s->materials = calloc((size_t)moff[nb], sizeof(bs_material));
  if (!s->x0 || !s->x || !s->v || !s->mask || !s->tet_material || !s->materials) {
    st = bs_error_set(err, BS_ENOMEM, "out of memory (%d vertices)", nv);
    goto done;
  }
  memcpy(s->x0, s->mesh->x, sizeof(double) * n3);
  memset(s->mask, 1, (size_t)nv);
  s->n_materials = moff[nb];
  /* 3. materials per tet, scripts, initial state: per body */
  int total_scripts = 0;
  for (int b = 0; b < nb; b++) total_scripts += sc->bodies[b].n_scripts;
  s->scripts = calloc((size_t)(total_scripts ? total_scripts : 1), sizeof(bs_sim_script));
  if (!s->scripts) {
    st = bs_error_set(err, BS_ENOMEM, "out of memory");
    goto done;
  }
  for (int b = 0; b < nb; b++) {
    const bs_scene_body *bd = &sc->bodies[b];
    const bs_mesh *bm = meshes[b] ? meshes[b] : s->mesh;
    for (int i = 0; i < bd->n_materials; i++) {
      const bs_scene_material *sm = &bd->materials[i];
      if ((st = bs_material_init(sm->model, sm->youngs, sm->poisson, sm->density, &s->materials[moff[b] + i], err))) {
        bs_error_prefix(err, "%s: bodies.%d.material%s%s", sc->path, b, sm->group[0] ? "s." : "", sm->group);
        goto done;
      }
      if (i == 0) continue;
      const bs_group *g = bs_mesh_group(bm, sm->group);
      if (!g || g->dim != 3) {
        st = bs_error_set(err, BS_EINPUT, "%s: bodies.%d.materials.%s: the mesh has no 3-D physical group named '%s'",
                          sc->path, b, sm->group, sm->group);
        goto done;
      }
      for (int32_t e = 0; e < g->n_elems; e++) s->tet_material[toff[b] + g->elems[e]] = moff[b] + i;
    }
    for (int32_t t = 0; t < bm->n_tets; t++)
      if (s->tet_material[toff[b] + t] == 0 && b > 0) s->tet_material[toff[b] + t] = moff[b];
    for (int i = 0; i < bd->n_scripts; i++) {
      const bs_scene_script *ss = &bd->scripts[i];
      const bs_group *g = bs_mesh_group(bm, ss->group);
      if (!g) {
        st = bs_error_set(err, BS_EINPUT, "%s: bodies.%d.scripted.%d.group: the mesh has no physical group named '%s'",
                          sc->path, b, i, ss->group);
        goto done;
      }
      bs_sim_script *q = &s->scripts[s->n_scripts++];
      q->script = ss;
      q->n = g->n_vertices;
      q->vertices = malloc(sizeof(int32_t) * (size_t)(g->n_vertices ? g->n_vertices : 1));
      if (!q->vertices) {
        st = bs_error_set(err, BS_ENOMEM, "out of memory");
        goto done;
      }
      for (int32_t k = 0; k < g->n_vertices; k++) {
        q->vertices[k] = g->vertices[k] + voff[b];
        s->mask[q->vertices[k]] = 0;
      }
    }
    /* velocity: v + ω × (x − centroid) */
    double cen[3] = {0, 0, 0};
    for (int32_t v = voff[b]; v < voff[b + 1]; v++)
      for (int k = 0; k < 3; k++) cen[k] += s->x0[3 * v + k] / (voff[b + 1] - voff[b]);
    const double *w = bd->angular_velocity;
    for (int32_t v = voff[b]; v < voff[b + 1]; v++) {
      const double *p = s->x0 + 3 * v;
      double r[3] = {p[0] - cen[0], p[1] - cen[1], p[2] - cen[2]};
      s->v[3 * v + 0] = bd->velocity[0] + w[1] * r[2] - w[2] * r[1];
      s->v[3 * v + 1] = bd->velocity[1] + w[2] * r[0] - w[0] * r[2];
      s->v[3 * v + 2] = bd->velocity[2] + w[0] * r[1] - w[1] * r[0];
    }
  }
  memcpy(s->x, s->x0, sizeof(double) * n3);
  for (int b = 0; b < nb; b++) {
    const bs_scene_body *bd = &sc->bodies[b];
    uint64_t seed = 0x9E3779B97F4A7C15ull ^ ((uint64_t)bd->init_seed * 2654435761u + 1);
    for (int32_t v = voff[b]; v < voff[b + 1]; v++) {
      if (!s->mask[v]) continue;
      for (int k = 0; k < 3; k++) {
        if (bd->init == BS_INIT_RANDOM) s->x[3 * v + k] = bd->init_lo[k] + (bd->init_hi[k] - bd->init_lo[k]) * rnd(&seed);
        else if (bd->init == BS_INIT_POINT) s->x[3 * v + k] = bd->init_lo[k];
      }
    }
  }
  /* 4. fem, terms, integrator */
  if ((st = bs_fem_create(s->mesh, s->n_materials, s->materials, s->tet_material, &s->fem, err))) goto done;
  {
    bs_term **T = s->terms;
    if (sc->mode == BS_MODE_DYNAMIC && (st = bs_term_inertia_create(s->fem, &s->step, &T[s->n_terms++], err))) goto done;
    if ((sc->gravity[0] != 0 || sc->gravity[1] != 0 || sc->gravity[2] != 0) &&
        (st = bs_term_gravity_create(s->fem, &s->step, sc->gravity, &T[s->n_terms++], err)))
      goto done;
    if ((st = bs_term_elastic_create(s->fem, sc->project_hessian, &T[s->n_terms++], err))) goto done;
    double *k = calloc((size_t)s->n_materials, sizeof(double));
    int any = 0;
    if (!k) {
      st = bs_error_set(err, BS_ENOMEM, "out of memory");
      goto done;
    }
    for (int b = 0; b < nb; b++)
      for (int i = 0; i < sc->bodies[b].n_materials; i++) {
        k[moff[b] + i] = sc->bodies[b].materials[i].rayleigh;
        if (k[moff[b] + i] > 0) any = 1;
      }
    if (any && sc->mode == BS_MODE_DYNAMIC) st = bs_term_damping_create(s->fem, &s->step, k, &T[s->n_terms++], err);
    free(k);
    if (st) goto done;
    if (sc->drag > 0 && sc->mode == BS_MODE_DYNAMIC &&
        (st = bs_term_drag_create(s->fem, &s->step, sc->drag, &T[s->n_terms++], err)))
      goto done;
    if (sc->n_obstacles > 0 && (st = make_obstacles(s, err))) goto done;
    if (sc->self_collision) {
      if ((st = bs_term_self_create(s->fem, &s->step, sc->self_stiffness, &s->self, err))) goto done;
      s->terms[s->n_terms++] = s->self;
    }
    bs_integrator_opts io = sc->solver;
    io.guess_xn = sc->self_collision && sc->solver.method == BS_METHOD_OPTIMIZATION; /* bs_step.h */
    if ((st = bs_integrator_create(s->fem, &s->step, s->n_terms, s->terms, s->mask,
                                   s->n_scripts ? script_positions : NULL, s, &io, &s->integrator, err)))
      goto done;
    bs_step_hooks hooks;
    memset(&hooks, 0, sizeof hooks);
    if (s->obstacles) bs_obstacles_hooks(s->obstacles, &s->obstacle_hooks);
    hooks = s->obstacle_hooks;
    if (s->self) { /* friction of both kinds after the solve */
      hooks.post_solve = sim_post_solve;
      hooks.ctx = s;
      if (s->obstacle_hooks.project) hooks.project = sim_project;
      if (s->obstacle_hooks.register_active) hooks.register_active = sim_register_active;
      if (s->obstacle_hooks.project_gradient) hooks.project_gradient = sim_project_gradient;
      if (s->obstacle_hooks.project_hessian) hooks.project_hessian = sim_project_hessian;
    }
    bs_integrator_set_hooks(s->integrator, &hooks);
  }
  st = 0;
done:
  if (meshes)
    for (int b = 0; b < nb; b++) bs_mesh_destroy(&meshes[b]);
  free(meshes);
  free(voff);
  free(toff);
  free(moff);
  if (st) {
    bs_sim_destroy(&s);
    return st;
  }
  *out = s;
  return st;
}
