/* sim.c — from a validated scene to a runnable simulation: create, destroy,
 * the scene's energy terms, the integrator, and what is measured of a state. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bs_ipc_obstacle.h"
#include "bs_ipc_term.h"
#include "bs_penalty.h"
#include "bs_selfcollide.h"
#include "bs_shim.h"
#include "bs_step_backend.h"
#include "sim_internal.h"

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
  free(s->vertex_offset);
  free(s->steps);
  free(s->friction_impulse);
  free(s->v_pre);
  bs_mesh_destroy(&s->mesh);
  free(s);
  *ps = NULL;
}

/* Rayleigh damping, when a material of a dynamic scene asks for it. */
static int damping_term(bs_sim *s, bs_error *err) {
  const bs_scene *sc = s->scene;
  double *k = calloc((size_t)s->n_materials, sizeof(double));
  int any = 0, m = 0;
  if (!k) return bs_error_set(err, BS_ENOMEM, "out of memory");
  for (int b = 0; b < sc->n_bodies; b++)
    for (int i = 0; i < sc->bodies[b].n_materials; i++, m++) {
      k[m] = sc->bodies[b].materials[i].rayleigh;
      if (k[m] > 0) any = 1;
    }
  int st = 0;
  if (any && sc->mode == BS_MODE_DYNAMIC) st = bs_term_damping_create(s->fem, &s->step, k, &s->terms[s->n_terms++], err);
  free(k);
  return st;
}

/* The terms the scene asks for, in a fixed order: inertia, gravity,
 * elasticity, damping, drag, penalty obstacles, self-collision. */
static int make_terms(bs_sim *s, bs_error *err) {
  const bs_scene *sc = s->scene;
  bs_term **T = s->terms;
  int dyn = sc->mode == BS_MODE_DYNAMIC, st;
  if (dyn && (st = bs_term_inertia_create(s->fem, &s->step, &T[s->n_terms++], err))) return st;
  if ((sc->gravity[0] != 0 || sc->gravity[1] != 0 || sc->gravity[2] != 0) &&
      (st = bs_term_gravity_create(s->fem, &s->step, sc->gravity, &T[s->n_terms++], err)))
    return st;
  if ((st = bs_term_elastic_create_step(s->fem, &s->step, sc->project_hessian, &T[s->n_terms++], err))) return st;
  if ((st = damping_term(s, err))) return st;
  if (sc->drag > 0 && dyn && (st = bs_term_drag_create(s->fem, &s->step, sc->drag, &T[s->n_terms++], err))) return st;
  if (sc->n_obstacles > 0 && ((st = bs__sim_make_obstacles(s, err)) || (st = bs__sim_make_obstacle_barrier(s, err))))
    return st;
  if (sc->self_collision && sc->self_model == BS_SELF_MODEL_BARRIER) {
    if ((st = bs__sim_make_barrier(s, err))) return st;
  } else if (sc->self_collision) {
    if ((st = bs_term_self_create(s->fem, &s->step, sc->self_stiffness, &s->self, err)) ||
        (st = bs_term_self_set_secant(s->self, sc->solver.penalty_secant == BS_PENALTY_SECANT_ALL, err)))
      return st;
    s->terms[s->n_terms++] = s->self;
  }
  return bs__sim_make_friction(s, err);
}

/* What the scene asks of the serial integrator that bs_step_refuse may
 * refuse with any backend (postprocess collisions with solver.integrator
 * bdf2 or newmark). */
static int refuse_scene(const bs_scene *sc, bs_error *err) {
  bs_step_features f;
  memset(&f, 0, sizeof f);
  f.postprocess_obstacle = f.friction_obstacle = -1;
  for (int i = sc->n_obstacles - 1; i >= 0; i--)
    if (sc->obstacles[i].collision == BS_COLLIDE_POSTPROCESS) f.postprocess_obstacle = i;
  f.method = sc->solver.method;
  f.linear = sc->solver.min.linear;
  f.globalization = sc->solver.min.globalization;
  f.amg_at_rest = sc->solver.amg_at_rest;
  f.integrator = sc->solver.integrator;
  return bs_step_refuse(&f, BS_STEP_CAN_ALL, sc->path, "serial", err);
}

/* The integrator over the current terms, with the hooks. */
static int make_integrator(bs_sim *s, bs_error *err) {
  const bs_scene *sc = s->scene;
  bs_integrator_destroy(&s->integrator);
  int rc = refuse_scene(sc, err);
  if (rc) return rc;
  bs_integrator_opts io = sc->solver;
  io.guess_xn = sc->self_collision && sc->solver.method == BS_METHOD_OPTIMIZATION; /* bs_step.h */
  io.penalty_secant = sc->solver.method == BS_METHOD_OPTIMIZATION ? sc->solver.penalty_secant : BS_PENALTY_EXACT;
  int st = bs_integrator_create(s->fem, &s->step, s->n_terms, s->terms, s->mask,
                                s->n_scripts ? bs__sim_script_positions : NULL, s, &io, &s->integrator, err);
  if (st) return st;
  bs_step_hooks hooks;
  bs__sim_hooks(s, &hooks);
  bs_integrator_set_hooks(s->integrator, &hooks);
  return 0;
}

int bs_sim_create(const bs_scene *sc, bs_sim **out, bs_error *err) {
  *out = NULL;
  int st = bs_scene_check(sc, err);
  if (st) return st;
  bs_sim *s = calloc(1, sizeof *s);
  if (!s) return bs_error_set(err, BS_ENOMEM, "out of memory");
  s->scene = sc;
  s->steps = calloc((size_t)sc->steps_per_frame, sizeof *s->steps);
  if (!s->steps) st = bs_error_set(err, BS_ENOMEM, "out of memory (%d steps per frame)", sc->steps_per_frame);
  bs_memory_estimate me;
  if (!st) st = bs_scene_memory_estimate(sc, &me, err);
  if (!st) st = bs__sim_make_bodies(s, err);
  if (!st) st = bs_memory_check(sc, s->mesh->n_vertices, s->mesh->n_tets, &me, err);
  if (!st) s->memory_bytes = me.bytes;
  if (!st) st = bs_fem_create(s->mesh, s->n_materials, s->materials, s->tet_material, &s->fem, err);
  if (!st) st = make_terms(s, err);
  if (!st) st = make_integrator(s, err);
  if (st) {
    bs_sim_destroy(&s);
    return st;
  }
  *out = s;
  return 0;
}

int bs_sim_add_term(bs_sim *s, bs_term *t, bs_error *err) {
  if (!t) return bs_error_set(err, BS_EINPUT, "bs_sim_add_term: no term");
  if (s->frame > 0) {
    bs_term_destroy(&t);
    return bs_error_set(err, BS_EINPUT, "bs_sim_add_term: terms are added before the first frame (%d done)", s->frame);
  }
  if (s->n_terms >= BS_SIM_MAX_TERMS) {
    bs_term_destroy(&t);
    return bs_error_set(err, BS_EINPUT, "bs_sim_add_term: at most %d terms", BS_SIM_MAX_TERMS);
  }
  if (t->fem != s->fem || (t->step && t->step != &s->step)) {
    char name[64];
    snprintf(name, sizeof name, "%s", t->name ? t->name : "?");
    bs_term_destroy(&t);
    return bs_error_set(err, BS_EINPUT, "bs_sim_add_term: the term '%s' must be created on the simulation's fem and step data",
                        name);
  }
  s->terms[s->n_terms++] = t;
  return make_integrator(s, err);
}

long bs_sim_dofs(const bs_sim *s) { return 3L * s->n_free; }

void bs_sim_penetration(const bs_sim *s, int32_t *count, double *max_depth) {
  *count = 0;
  *max_depth = 0;
  if (s->obstacles) bs_obstacles_penetration(s->obstacles, s->time, s->x, 1e-10 * s->size, count, max_depth);
}

/* Pairs of boundary triangles that intersect at the current state (exact,
 * CGAL), counted up to BS_SIM_SELF_CAP (a tangled state, e.g. the random
 * 65^3 cube, has ~1e9 candidate pairs: the count stops there and reads as
 * "at least"); -1 if the test could not run. */
static int64_t surface_self_intersections(const bs_sim *s) {
  int64_t n = 0;
  int truncated = 0;
  bs_error err;
  if (bs_shim_count_self_intersections(s->x, s->mesh->n_vertices, s->mesh->faces, s->mesh->n_faces, BS_SIM_SELF_CAP,
                                       &n, &truncated, &err))
    return -1;
  return n;
}

void bs_measure_state(const bs_fem *fem, const double *x, const double *v, const double g[3], bs_sim_measures *m) {
  double k = 0, gp = 0;
  for (int32_t i = 0; i < fem->n_vertices; i++) {
    const double *vv = v + 3 * i, *xx = x + 3 * i;
    k += 0.5 * fem->mass[i] * (vv[0] * vv[0] + vv[1] * vv[1] + vv[2] * vv[2]);
    gp -= (fem->load ? fem->load[i] : fem->mass[i]) * (g[0] * xx[0] + g[1] * xx[1] + g[2] * xx[2]);
  }
  m->kinetic = k;
  m->gravity = gp;
  m->elastic = bs_fem_elastic_energy(fem, x);
  m->total = m->kinetic + m->elastic + m->gravity;
  m->inverted = bs_fem_count_inverted(fem, x, &m->min_detF);
  m->penetrating = 0;
  m->max_depth = 0;
  m->self_intersections = -1;
  m->contact_min_distance = INFINITY;
  m->contact_pairs = 0;
  m->kappa = 0;
  m->obstacle_min_distance = INFINITY;
}

void bs_sim_measure(const bs_sim *s, int intersections, bs_sim_measures *m) {
  bs_measure_state(s->fem, s->x, s->v, s->scene->gravity, m);
  bs_sim_penetration(s, &m->penetrating, &m->max_depth);
  m->self_intersections = intersections ? surface_self_intersections(s) : -1;
  bs_ipc_stats is;
  bs_error err;
  if (s->barrier && bs_term_ipc_detect(s->barrier, s->x, &is, &err) == 0) {
    m->contact_min_distance = is.pairs_pt + is.pairs_ee > 0 ? is.min_distance : INFINITY;
    m->contact_pairs = is.pairs_pt + is.pairs_ee;
    m->kappa = is.kappa;
  }
  bs_ipc_obstacle_stats os;
  if (s->obstacle_barrier && bs_term_ipc_obstacle_detect(s->obstacle_barrier, s->x, &os, &err) == 0)
    m->obstacle_min_distance = os.min_distance;
}
