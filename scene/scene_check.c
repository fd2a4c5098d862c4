/* scene_check.c — the value checks of a scene, one home for both the JSON
 * loader and scenes built in C. Messages: "FILE: key.path: what is wrong". */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include "bs_scene.h"
#include "bs_vec3.h"

static int bad(const bs_scene *s, bs_error *err, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;

static int bad(const bs_scene *s, bs_error *err, const char *fmt, ...) {
  char msg[900];
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(msg, sizeof msg, fmt, ap);
  va_end(ap);
  return bs_error_set(err, BS_EINPUT, "%s: %s", s->path, msg);
}

static int check_material(const bs_scene *s, const bs_scene_material *m, const char *where, bs_error *err) {
  bs_material tmp;
  bs_error e2;
  if (bs_material_init(m->model, m->youngs, m->poisson, m->density, &tmp, &e2)) return bad(s, err, "%s: %s", where, e2.msg);
  if (!(m->rayleigh >= 0)) return bad(s, err, "%s.rayleigh: must be >= 0, got %g", where, m->rayleigh);
  return 0;
}

static int check_keys_increase(const bs_scene *s, int n, const double *t, const char *where, bs_error *err) {
  for (int i = 0; i < n; i++) {
    if (!isfinite(t[i])) return bad(s, err, "%s.%d.t: must be finite, got %g", where, i, t[i]);
    if (i > 0 && !(t[i] > t[i - 1])) return bad(s, err, "%s.%d: keyframe times must increase", where, i);
  }
  return 0;
}

static int check_script(const bs_scene *s, const bs_scene_script *sc, const char *where, bs_error *err) {
  if (!sc->group[0]) return bad(s, err, "%s.group: missing (a string is required)", where);
  if ((unsigned)sc->kind > BS_SCRIPT_KEYFRAMES) return bad(s, err, "%s: unknown script kind %d", where, (int)sc->kind);
  if (sc->kind != BS_SCRIPT_KEYFRAMES) return 0;
  char w[600];
  snprintf(w, sizeof w, "%s.keyframes", where);
  if (sc->n_keys < 1 || !sc->key_t || !sc->key_offset) return bad(s, err, "%s: must be a non-empty array", w);
  return check_keys_increase(s, sc->n_keys, sc->key_t, w, err);
}

/* A rotation vector (axis x angle, degrees): finite, at most the limit. */
static int check_rotation(const bs_scene *s, const double r[3], const char *where, bs_error *err) {
  const double a = bs_norm3_scaled(r);
  if (!(a <= BS_SCENE_MAX_ANGLE))
    return bad(s, err, "%s: a rotation of %g degrees, above the limit of %g", where, a, BS_SCENE_MAX_ANGLE);
  return 0;
}

static int check_body(const bs_scene *s, const bs_scene_body *b, int i, bs_error *err) {
  char w[600];
  int st;
  if (!b->mesh[0]) return bad(s, err, "bodies.%d.mesh: missing (a string is required)", i);
  if (!strcmp(b->mesh, "box"))
    for (int k = 0; k < 3; k++) {
      if (b->box_cells[k] < 1 || b->box_cells[k] > 4096)
        return bad(s, err, "bodies.%d.box: cells must be integers in [1, 4096]", i);
      if (!(b->box_size[k] > 0) || !isfinite(b->box_size[k])) return bad(s, err, "bodies.%d.box: size must be positive", i);
    }
  if (!(b->mesh_size >= 0)) return bad(s, err, "bodies.%d.mesh_size: must be > 0, got %g", i, b->mesh_size);
  if (!(b->min_dihedral >= 0 && b->min_dihedral < 70.5))
    return bad(s, err, "bodies.%d.min_dihedral: must be in [0, 70.5) degrees (0: no gate), got %g", i, b->min_dihedral);
  if (b->refine < 0 || b->refine > 6) return bad(s, err, "bodies.%d.refine: must be an integer in [0, 6], got %d", i, b->refine);
  for (int k = 0; k < 3; k++)
    if (!(b->scale[k] > 0) || !isfinite(b->scale[k])) return bad(s, err, "bodies.%d.scale: must be positive and finite", i);
  snprintf(w, sizeof w, "bodies.%d.rotate", i);
  if ((st = check_rotation(s, b->rotate, w, err))) return st;
  if (b->n_materials < 1 || !b->materials)
    return bad(s, err, "bodies.%d.material: missing (an object with model, youngs, poisson, density is required)", i);
  for (int m = 0; m < b->n_materials; m++) {
    if (m == 0) snprintf(w, sizeof w, "bodies.%d.material", i);
    else snprintf(w, sizeof w, "bodies.%d.materials.%s", i, b->materials[m].group);
    if ((st = check_material(s, &b->materials[m], w, err))) return st;
  }
  if (b->init == BS_INIT_RANDOM)
    for (int k = 0; k < 3; k++)
      if (!(b->init_hi[k] >= b->init_lo[k]))
        return bad(s, err, "bodies.%d.initial_state: hi must be >= lo in every component", i);
  for (int k = 0; k < b->n_scripts; k++) {
    snprintf(w, sizeof w, "bodies.%d.scripted.%d", i, k);
    if ((st = check_script(s, &b->scripts[k], w, err))) return st;
  }
  return 0;
}

static int check_obstacle(const bs_scene *s, const bs_scene_obstacle *o, int i, bs_error *err) {
  if ((unsigned)o->shape > BS_SHAPE_GRID) return bad(s, err, "obstacles.%d.shape: unknown shape %d", i, (int)o->shape);
  if (o->shape == BS_SHAPE_GRID && !o->grid_file[0])
    return bad(s, err, "obstacles.%d.file: missing: shape \"grid\" needs the grid level-set file", i);
  if ((unsigned)o->collision > BS_COLLIDE_BARRIER)
    return bad(s, err, "obstacles.%d.collision: unknown collision mode %d", i, (int)o->collision);
  if (!(o->stiffness > 0)) return bad(s, err, "obstacles.%d.stiffness: must be > 0, got %g", i, o->stiffness);
  if (!(o->friction >= 0)) return bad(s, err, "obstacles.%d.friction: must be >= 0, got %g", i, o->friction);
  if (!(o->grid_h >= 0)) return bad(s, err, "obstacles.%d.grid_h: must be > 0, got %g", i, o->grid_h);
  char w[64];
  for (int k = 0; k < o->n_keys; k++) {
    snprintf(w, sizeof w, "obstacles.%d.keyframes.%d.rotate", i, k);
    int st = check_rotation(s, o->key_rotate + 3 * k, w, err);
    if (st) return st;
  }
  snprintf(w, sizeof w, "obstacles.%d.keyframes", i);
  return o->n_keys > 0 ? check_keys_increase(s, o->n_keys, o->key_t, w, err) : 0;
}

static int check_solver(const bs_scene *s, bs_error *err) {
  const bs_minimize_opts *m = &s->solver.min;
  if (!(m->tol > 0)) return bad(s, err, "solver.tolerance: must be > 0, got %g", m->tol);
  if (!(m->rtol >= 0 && m->rtol < 1)) return bad(s, err, "solver.rtol: must be in [0, 1), got %g", m->rtol);
  if (!(m->load_rtol >= 0 && m->load_rtol < 1))
    return bad(s, err, "solver.load_rtol: must be in [0, 1), got %g", m->load_rtol);
  if (!(m->amg_rebuild_factor == 0 || (m->amg_rebuild_factor >= 1 && isfinite(m->amg_rebuild_factor))))
    return bad(s, err, "solver.amg_rebuild_factor: must be 0 (never) or a finite value >= 1, got %g",
               m->amg_rebuild_factor);
  if (!(m->sigma > 0) || !isfinite(m->sigma))
    return bad(s, err, "solver.%s: must be > 0, got %g", m->sigma_auto ? "cg_sigma_scale" : "cg_sigma", m->sigma);
  if (!(m->tr_radius > 0) || !isfinite(m->tr_radius))
    return bad(s, err, "solver.tr_radius: must be > 0 (m), got %g", m->tr_radius);
  if (m->globalization == BS_GLOBAL_TRUST_REGION && m->linear != BS_LIN_CG && m->linear != BS_LIN_PCG &&
      m->linear != BS_LIN_AMG)
    return bad(s, err, "solver.globalization: trust_region needs solver.linear cg, pcg or amg (Steihaug's CG), got %s",
               bs_lin_kind_name(m->linear));
  if (s->load_steps < 1) return bad(s, err, "solver.load_steps: must be an integer in [1, 100000], got %d", s->load_steps);
  if ((unsigned)s->solver.integrator > BS_INTEGRATOR_NEWMARK)
    return bad(s, err, "solver.integrator: must be backward_euler, bdf2 or newmark, got %d", s->solver.integrator);
  return 0;
}

static int check_time(const bs_scene *s, bs_error *err) {
  if (!(s->fps >= BS_SCENE_MIN_FPS && s->fps <= BS_SCENE_MAX_FPS))
    return bad(s, err, "time.fps: must be in [%g, %g], got %g", BS_SCENE_MIN_FPS, BS_SCENE_MAX_FPS, s->fps);
  if (s->frames < 0) return bad(s, err, "time.frames: must be an integer in [0, 10000000], got %d", s->frames);
  if (s->steps_per_frame < 1 || s->steps_per_frame > BS_SCENE_MAX_STEPS_PER_FRAME)
    return bad(s, err, "time.steps_per_frame: must be an integer in [1, %d], got %d", BS_SCENE_MAX_STEPS_PER_FRAME,
               s->steps_per_frame);
  const long long steps = (long long)s->frames * s->steps_per_frame;
  if (steps > BS_SCENE_MAX_STEPS)
    return bad(s, err, "time: %d frames x %d steps per frame = %lld time steps, above the limit of %lld", s->frames,
               s->steps_per_frame, steps, BS_SCENE_MAX_STEPS);
  return 0;
}

/* bodies[].element: tet4 or tet10; tet10 on the serial backend (the
 * simulation refuses the rest: bs_sim_create). */
static int check_elements(const bs_scene *s, bs_error *err) {
  for (int i = 0; i < s->n_bodies; i++) {
    const int e = s->bodies[i].element;
    if (e != BS_ELEMENT_TET4 && e != BS_ELEMENT_TET10)
      return bad(s, err, "bodies.%d.element: must be tet4 or tet10, got %d", i, e);
    if (e == BS_ELEMENT_TET10 && s->backend != BS_BACKEND_SERIAL)
      return bad(s, err, "bodies.%d.element: tet10 is not supported with solver.backend petsc", i);
  }
  return 0;
}

int bs_scene_check(const bs_scene *s, bs_error *err) {
  int st;
  if ((st = check_time(s, err))) return st;
  if (s->dt != 1.0 / (s->fps * s->steps_per_frame))
    return bad(s, err, "time.dt: must be 1 / (fps * steps_per_frame) = %g, got %g (bs_scene_validate sets it)",
               1.0 / (s->fps * s->steps_per_frame), s->dt);
  if ((st = check_solver(s, err))) return st;
  for (int k = 0; k < 3; k++)
    if (!isfinite(s->gravity[k])) return bad(s, err, "gravity: element %d must be a finite number", k);
  if (!(s->drag >= 0)) return bad(s, err, "drag: must be >= 0, got %g", s->drag);
  if (s->self_collision && !(s->self_stiffness > 0))
    return bad(s, err, "self_collision.stiffness: must be > 0, got %g", s->self_stiffness);
  if (s->self_collision && !(s->self_friction >= 0))
    return bad(s, err, "self_collision.friction: must be >= 0, got %g", s->self_friction);
  if (!(s->contact_dhat >= 0) || !isfinite(s->contact_dhat))
    return bad(s, err, "contact.dhat: must be > 0 (m; 0 in the struct: automatic), got %g", s->contact_dhat);
  if (!(s->contact_eps_v > 0) || !isfinite(s->contact_eps_v))
    return bad(s, err, "contact.eps_v: must be > 0 (m/s), got %g", s->contact_eps_v);
  if (!(s->contact_kappa >= 0) || !isfinite(s->contact_kappa))
    return bad(s, err, "contact.kappa: must be > 0 (J/m^4; 0 in the struct: automatic), got %g", s->contact_kappa);
  if (s->self_model != BS_SELF_MODEL_PENALTY && s->self_model != BS_SELF_MODEL_BARRIER)
    return bad(s, err, "self_collision.model: must be penalty or barrier, got %d", s->self_model);
  if (s->n_bodies < 1) return bad(s, err, "bodies: must be a non-empty array");
  for (int i = 0; i < s->n_bodies; i++)
    if ((st = check_body(s, &s->bodies[i], i, err))) return st;
  if ((st = check_elements(s, err))) return st;
  for (int i = 0; i < s->n_obstacles; i++)
    if ((st = check_obstacle(s, &s->obstacles[i], i, err))) return st;
  if (s->vtu_every < 0) return bad(s, err, "output.vtu_every: must be an integer in [0, 1000000], got %d", s->vtu_every);
  return 0;
}

int bs_scene_validate(bs_scene *s, bs_error *err) {
  if (s->fps > 0 && s->steps_per_frame >= 1) s->dt = 1.0 / (s->fps * s->steps_per_frame);
  return bs_scene_check(s, err);
}
