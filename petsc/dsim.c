/* dsim.c — a scene on the petsc backend: what it may use, and its mesh,
 * materials, terms, scripts and integrator (bs_dsim.h); its obstacles are
 * dsim_obstacles.c's, its frames and statics dsim_step.c's. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bs_dist.h"
#include "bs_dsim.h"
#include "bs_step_backend.h"
#include "bs_penalty.h"
#include "dsim_internal.h"

static int refuse(const bs_scene *sc, bs_error *err, const char *key, const char *why) {
  return bs_error_set(err, BS_EINPUT, "%s: %s: %s with solver.backend petsc", sc->path, key, why);
}

static int nonzero3(const double v[3]) { return v[0] != 0 || v[1] != 0 || v[2] != 0; }

static int check_body(const bs_scene *sc, const bs_scene_body *b, bs_error *err) {
  const char *dot = strrchr(b->mesh, '.');
  if (strcmp(b->mesh, "box") != 0 && !(dot && !strcmp(dot, ".msh")))
    return refuse(sc, err, "bodies.0.mesh", "only \"box\" or a .msh file is read");
  if (nonzero3(b->translate)) return refuse(sc, err, "bodies.0.translate", "body transforms are not supported");
  if (nonzero3(b->rotate)) return refuse(sc, err, "bodies.0.rotate", "body transforms are not supported");
  if (b->scale[0] != 1 || b->scale[1] != 1 || b->scale[2] != 1)
    return refuse(sc, err, "bodies.0.scale", "body transforms are not supported");
  if (nonzero3(b->angular_velocity)) return refuse(sc, err, "bodies.0.angular_velocity", "not supported");
  if (b->init != BS_INIT_REST) return refuse(sc, err, "bodies.0.init", "only the rest state is supported");
  return BS_OK;
}

/* Obstacles: analytic shapes (what the integrator runs of their collisions
 * is bs_step_refuse's). */
static int check_obstacles(const bs_scene *sc, bs_error *err) {
  char key[64];
  for (int i = 0; i < sc->n_obstacles; i++) {
    const bs_scene_obstacle *o = &sc->obstacles[i];
    const char *why = NULL;
    if (o->shape == BS_SHAPE_GRID) snprintf(key, sizeof key, "obstacles.%d.shape", i), why = "grid level sets are not supported";
    else if (o->grid_h > 0) snprintf(key, sizeof key, "obstacles.%d.grid_h", i), why = "grid level sets are not supported";
    if (why) return refuse(sc, err, key, why);
  }
  if (sc->n_obstacles > BS_DSIM_MAX_OBSTACLES) return refuse(sc, err, "obstacles", "too many obstacles");
  return BS_OK;
}

/* What the scene asks of the integrator (bs_step_refuse). */
static void scene_features(const bs_scene *sc, bs_step_features *f) {
  memset(f, 0, sizeof *f);
  f->self_collision = sc->self_collision;
  f->postprocess_obstacle = f->friction_obstacle = -1;
  for (int i = sc->n_obstacles - 1; i >= 0; i--) {
    if (sc->obstacles[i].collision == BS_COLLIDE_POSTPROCESS) f->postprocess_obstacle = i;
    if (sc->obstacles[i].friction > 0) f->friction_obstacle = i;
  }
  f->method = sc->solver.method;
  f->linear = sc->solver.min.linear;
  f->globalization = sc->solver.min.globalization;
  f->amg_at_rest = sc->solver.amg_at_rest;
  f->integrator = sc->solver.integrator;
}

int bs_dsim_check(const bs_scene *sc, bs_error *err) {
  bs_step_features f;
  scene_features(sc, &f);
  int rc = bs_step_refuse(&f, BS_DSTEP_CAPS, sc->path, "petsc", err);
  if (!rc) rc = check_obstacles(sc, err);
  if (rc) return rc;
  if (sc->n_qoi > 0) return refuse(sc, err, "qoi", "quantities of interest are not supported yet");
  if (sc->n_bodies != 1) return refuse(sc, err, "bodies", "exactly one body is run");
  return check_body(sc, &sc->bodies[0], err);
}

int bs_dsim_check_output(const bs_scene *sc, int resume, bs_error *err) {
  if (resume)
    return refuse(sc, err, "--resume",
                  "no checkpoint is written to continue from (run the scene again with --replace, or on the serial "
                  "backend)");
  const bs_scene_body *b = sc->n_bodies >= 1 ? &sc->bodies[0] : NULL;
  const int known_order = b && !strcmp(b->mesh, "box") && b->refine == 0 && b->reorder == BS_ORDER_NONE;
  if (sc->states && !known_order)
    return refuse(sc, err, "output.states",
                  "state.bin is written in the serial vertex order, known for a box mesh without refine or reorder only "
                  "(set false)");
  if (sc->mode == BS_MODE_DYNAMIC && sc->checkpoint_every > 0)
    return refuse(sc, err, "output.checkpoint_every",
                  "checkpoints (checkpoint.bin, for bigstep run --resume) are not written (set 0)");
  if (sc->vtu_every > 0 && sc->out_fields != BS_FIELDS_DEFAULT && (sc->out_fields & ~BS_DSIM_FIELDS))
    return refuse(sc, err, "output.fields",
                  "the VTU pieces hold displacement, velocity, material, detF and inverted only");
  return BS_OK;
}

/* Material i's 3-D group tag (-1: the body's default, every other cell). */
static int material_tags(const bs_dsim *s, const bs_scene_body *b, bs_material *mats, int *tags, bs_error *err) {
  for (int i = 0; i < b->n_materials; i++) {
    const bs_scene_material *sm = &b->materials[i];
    int rc = bs_material_init(sm->model, sm->youngs, sm->poisson, sm->density, &mats[i], err);
    if (rc) return rc;
    tags[i] = -1;
    if (!sm->group[0]) continue;
    const bs_dgroup *g = bs_dmesh_group(s->mesh, sm->group);
    if (!g || g->dim != 3)
      return bs_error_set(err, BS_EINPUT, "%s: bodies.0.materials.%d.group: the mesh has no 3-D group named '%s'",
                          s->scene->path, i, sm->group);
    tags[i] = g->tag;
  }
  return BS_OK;
}

static int make_mesh(bs_dsim *s, bs_error *err) {
  const bs_scene_body *b = &s->scene->bodies[0];
  char spec[BS_MAX_PATH + 64];
  if (!strcmp(b->mesh, "box"))
    snprintf(spec, sizeof spec, "box:%dx%dx%d:%.17gx%.17gx%.17g", b->box_cells[0], b->box_cells[1], b->box_cells[2],
             b->box_size[0], b->box_size[1], b->box_size[2]);
  else snprintf(spec, sizeof spec, "%s", b->mesh);
  int rc = bs_dmesh_load(spec, b->refine, &s->mesh, err);
  if (rc) {
    bs_error_prefix(err, "%s: bodies.0.mesh", s->scene->path);
    return rc;
  }
  bs_material mats[64];
  int tags[64];
  if (b->n_materials > 64) return bs_error_set(err, BS_EINPUT, "%s: bodies.0.materials: more than 64", s->scene->path);
  if ((rc = material_tags(s, b, mats, tags, err))) return rc;
  return bs_dfem_create(s->mesh, b->n_materials, mats, tags, &s->df, err);
}

/* The terms the scene asks for, in bs_sim's order: inertia, gravity,
 * elasticity, damping, drag, penalty obstacles (the obstacles' terms). */
static int make_terms(bs_dsim *s, bs_error *err) {
  const bs_scene *sc = s->scene;
  const bs_fem *fem = s->df->fem;
  bs_term **T = s->terms;
  int dyn = sc->mode == BS_MODE_DYNAMIC, rc = BS_OK;
  if (dyn) rc = bs_term_inertia_create(fem, &s->step, &T[s->n_terms++], err);
  if (!rc && nonzero3(sc->gravity)) rc = bs_term_gravity_create(fem, &s->step, sc->gravity, &T[s->n_terms++], err);
  if (!rc) rc = bs_term_elastic_create_step(fem, &s->step, sc->project_hessian, &T[s->n_terms++], err);
  const bs_scene_body *b = &sc->bodies[0];
  double k[64];
  int any = 0;
  for (int i = 0; i < b->n_materials; i++) any |= (k[i] = b->materials[i].rayleigh) > 0;
  if (!rc && any && dyn) rc = bs_term_damping_create(fem, &s->step, k, &T[s->n_terms++], err);
  if (!rc && sc->drag > 0 && dyn) rc = bs_term_drag_create(fem, &s->step, sc->drag, &T[s->n_terms++], err);
  if (!rc) rc = bs__dsim_make_obstacles(s, err);
  if (!rc) bs_dfem_set_terms(s->df, s->n_terms, s->terms, !dyn);
  return rc;
}

/* Scripted groups: their local vertices, masked out. */
static int make_scripts(bs_dsim *s, bs_error *err) {
  const bs_scene_body *b = &s->scene->bodies[0];
  s->scripts = bs_calloc((size_t)b->n_scripts + 1, sizeof *s->scripts, "scripts", err);
  if (!s->scripts) return BS_ENOMEM;
  for (int i = 0; i < b->n_scripts; i++) {
    const bs_dgroup *g = bs_dmesh_group(s->mesh, b->scripts[i].group);
    if (!g)
      return bs_error_set(err, BS_EINPUT, "%s: bodies.0.scripted.%d.group: the mesh has no physical group named '%s'",
                          s->scene->path, i, b->scripts[i].group);
    bs_sim_script *q = &s->scripts[s->n_scripts++];
    q->script = &b->scripts[i];
    q->n = g->n_vertices;
    q->vertices = g->vertices; /* the mesh's array: borrowed, never freed here */
    for (int32_t j = 0; j < g->n_vertices; j++) s->mask[g->vertices[j]] = 0;
  }
  int64_t nf = 0;
  for (int32_t v = 0; v < s->mesh->n_vertices; v++) nf += s->mesh->owned[v] && s->mask[v];
  int rc = bs_dist_sum_i64(&nf, 1, err);
  s->n_free = nf;
  return rc;
}

static void script_positions(double t, double *x, void *ctx) {
  const bs_dsim *s = ctx;
  for (int i = 0; i < s->n_scripts; i++) {
    double off[3];
    bs_scene_script_offset(s->scripts[i].script, t, off);
    for (int32_t q = 0; q < s->scripts[i].n; q++) {
      int32_t v = s->scripts[i].vertices[q];
      for (int k = 0; k < 3; k++) x[3 * v + k] = s->mesh->x[3 * v + k] + off[k];
    }
  }
}

static int make_state(bs_dsim *s, bs_error *err) {
  int32_t n = s->mesh->n_vertices;
  s->x = bs_calloc(3 * (size_t)n + 3, sizeof *s->x, "positions", err);
  s->v = bs_calloc(3 * (size_t)n + 3, sizeof *s->v, "velocities", err);
  s->mask = bs_calloc((size_t)n + 1, 1, "mask", err);
  s->steps = bs_calloc((size_t)s->scene->steps_per_frame, sizeof *s->steps, "step records", err);
  s->xm = bs_calloc(3 * (size_t)s->mesh->local->n_vertices + 3, sizeof *s->xm, "positions", err);
  if (!s->x || !s->v || !s->mask || !s->steps || !s->xm) return BS_ENOMEM;
  memcpy(s->x, s->mesh->x, 3 * (size_t)n * sizeof(double));
  memset(s->mask, 1, (size_t)n);
  const double *v0 = s->scene->bodies[0].velocity;
  for (int32_t v = 0; v < n; v++)
    for (int k = 0; k < 3; k++) s->v[3 * v + k] = v0[k];
  return BS_OK;
}

int bs_dsim_create(const bs_scene *sc, bs_dsim **out, bs_error *err) {
  *out = NULL;
  int rc = bs_dsim_check(sc, err);
  if (rc) return rc;
  bs_dsim *s = bs_calloc(1, sizeof *s, "distributed sim", err);
  if (!s) return BS_ENOMEM;
  s->scene = sc;
  rc = make_mesh(s, err);
  if (!rc) rc = make_state(s, err);
  if (!rc) rc = make_scripts(s, err); /* the mask, before the obstacles copy it */
  if (!rc) rc = make_terms(s, err);
  if (!rc)
    rc = bs_dintegrator_create(s->df, &s->step, s->mask, s->n_scripts ? script_positions : NULL, s, &sc->solver,
                               &s->integrator, err);
  if (!rc) rc = bs__dsim_set_hooks(s, err);
  if (rc) bs_dsim_destroy(&s);
  *out = s;
  return rc;
}

void bs_dsim_destroy(bs_dsim **sp) {
  if (!sp || !*sp) return;
  bs_dsim *s = *sp;
  bs_dintegrator_destroy(&s->integrator);
  for (int i = 0; i < s->n_terms; i++)
    if (!bs_term_is_penalty(s->terms[i])) bs_term_destroy(&s->terms[i]); /* those are the obstacles' */
  bs_obstacles_destroy(&s->obstacles);
  bs_dfem_destroy(&s->df);
  bs_dmesh_destroy(&s->mesh);
  free(s->x), free(s->v), free(s->mask), free(s->scripts), free(s->steps), free(s->xm);
  bs_frame_snap_free(&s->snap);
  free(s);
  *sp = NULL;
}

int bs_dsim_inverted(bs_dsim *s, int64_t *n, bs_error *err) {
  bs_dfem_mesh_vector(s->df, s->x, s->xm);
  *n = bs_fem_count_inverted(s->df->fem, s->xm, NULL);
  return bs_dist_sum_i64(n, 1, err);
}

long bs_dsim_dofs(const bs_dsim *s) { return 3 * (long)s->n_free; }
