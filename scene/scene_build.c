/* scene_build.c — scenes built in C: the schema's defaults (one home for them:
 * the JSON loader starts from these too), appending parts, and the value
 * checks shared by both ways of making a scene. */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bs_field_names.h"
#include "bs_scene.h"
#include "scene_internal.h"
#include "scene_schema.h"

static const char *const shape_names[] = {"plane", "sphere", "box", "cylinder", "torus", "grid"};

const char *bs_shape_name(bs_shape s) {
  return (unsigned)s < sizeof shape_names / sizeof shape_names[0] ? shape_names[s] : "?";
}

int bs_shape_parse(const char *name, bs_shape *out, bs_error *err) {
  for (int i = 0; i < (int)(sizeof shape_names / sizeof shape_names[0]); i++)
    if (!strcmp(name, shape_names[i])) {
      *out = (bs_shape)i;
      return 0;
    }
  return bs_error_set(err, BS_EINPUT, "must be plane, sphere, box, cylinder, torus or grid, got \"%s\"", name);
}

/* The defaults are the schema table's (scene_schema.c); set here by hand are
 * only what the table does not bind: the integrator's options that are no
 * scene key, cg_sigma (a number or "auto"), the derived dt, the output
 * fields and the box's cells (required with mesh "box"). */
void bs__scene_defaults(bs_scene *s) {
  bs_integrator_opts_default(&s->solver);
  static const char *const scene_sections[] = {"", "time", "solver", "self_collision", "contact", "output"};
  for (int i = 0; i < 6; i++) bs__schema_defaults(scene_sections[i], s);
  s->dt = 1.0 / (s->fps * s->steps_per_frame);
  s->solver.min.sigma_auto = 1; /* cg_sigma "auto" (docs/design/cg-forcing.md) */
  s->solver.min.sigma = BS_SCENE_SIGMA_SCALE;
  s->out_fields = BS_FIELDS_DEFAULT;
}

void bs__scene_body_defaults(bs_scene_body *b) {
  bs__schema_defaults("bodies[]", b);
  bs__schema_defaults("bodies[].box", b);
  b->box_cells[0] = b->box_cells[1] = b->box_cells[2] = 4;
  b->init = BS_INIT_REST;
  b->init_seed = 1;
}

void bs__scene_material_defaults(bs_scene_material *m) { bs__schema_defaults("bodies[].material", m); }

void bs__scene_obstacle_defaults(bs_scene_obstacle *b) { bs__schema_defaults("obstacles[]", b); }

void bs__scene_qoi_defaults(bs_scene_qoi *q) { bs__schema_defaults("qoi[]", q); }

int bs_scene_create(bs_scene **out, bs_error *err) {
  *out = calloc(1, sizeof **out);
  if (!*out) return bs_error_set(err, BS_ENOMEM, "out of memory");
  snprintf((*out)->path, sizeof (*out)->path, "<scene>");
  bs__scene_defaults(*out);
  return 0;
}

/* Grows an array of n elements of `size` bytes by one zeroed element. */
static void *grow(void *p, int n, size_t size, bs_error *err) {
  char *q = realloc(p, size * (size_t)(n + 1));
  if (!q) {
    bs_error_set(err, BS_ENOMEM, "out of memory");
    return NULL;
  }
  memset(q + size * (size_t)n, 0, size);
  return q;
}

int bs_scene_add_body(bs_scene *s, const char *mesh, bs_scene_body **out, bs_error *err) {
  if (!mesh || !*mesh) return bs_error_set(err, BS_EINPUT, "%s: bodies.%d.mesh: empty", s->path, s->n_bodies);
  if (strlen(mesh) >= BS_MAX_PATH)
    return bs_error_set(err, BS_EINPUT, "%s: bodies.%d.mesh: path too long", s->path, s->n_bodies);
  bs_scene_body *b = grow(s->bodies, s->n_bodies, sizeof *b, err);
  if (!b) return BS_ENOMEM;
  s->bodies = b;
  b += s->n_bodies;
  bs__scene_body_defaults(b);
  snprintf(b->mesh, sizeof b->mesh, "%s", mesh);
  b->materials = calloc(1, sizeof *b->materials);
  if (!b->materials) return bs_error_set(err, BS_ENOMEM, "out of memory");
  b->n_materials = 1;
  bs__scene_material_defaults(&b->materials[0]);
  s->n_bodies++;
  *out = b;
  return 0;
}

int bs_scene_body_add_material(bs_scene_body *b, const char *group, bs_scene_material **out, bs_error *err) {
  if (!group || !*group || strlen(group) >= BS_MAX_NAME)
    return bs_error_set(err, BS_EINPUT, "materials: a group name of 1 to %d characters is needed", BS_MAX_NAME - 1);
  bs_scene_material *m = grow(b->materials, b->n_materials, sizeof *m, err);
  if (!m) return BS_ENOMEM;
  b->materials = m;
  m[b->n_materials] = m[0];
  snprintf(m[b->n_materials].group, sizeof m->group, "%s", group);
  *out = &m[b->n_materials++];
  return 0;
}

int bs_scene_body_add_script(bs_scene_body *b, const char *group, bs_script_kind kind, bs_scene_script **out,
                             bs_error *err) {
  if (!group || !*group || strlen(group) >= BS_MAX_NAME)
    return bs_error_set(err, BS_EINPUT, "scripted: a group name of 1 to %d characters is needed", BS_MAX_NAME - 1);
  bs_scene_script *sc = grow(b->scripts, b->n_scripts, sizeof *sc, err);
  if (!sc) return BS_ENOMEM;
  b->scripts = sc;
  sc += b->n_scripts++;
  snprintf(sc->group, sizeof sc->group, "%s", group);
  sc->kind = kind;
  *out = sc;
  return 0;
}

int bs_scene_script_set_keyframes(bs_scene_script *sc, int n, const double *t, const double *offset, bs_error *err) {
  if (n < 1) return bs_error_set(err, BS_EINPUT, "keyframes: must be a non-empty array");
  double *kt = malloc(sizeof(double) * (size_t)n), *ko = malloc(sizeof(double) * 3 * (size_t)n);
  if (!kt || !ko) {
    free(kt);
    free(ko);
    return bs_error_set(err, BS_ENOMEM, "out of memory");
  }
  memcpy(kt, t, sizeof(double) * (size_t)n);
  memcpy(ko, offset, sizeof(double) * 3 * (size_t)n);
  free(sc->key_t);
  free(sc->key_offset);
  sc->key_t = kt;
  sc->key_offset = ko;
  sc->n_keys = n;
  sc->kind = BS_SCRIPT_KEYFRAMES;
  return 0;
}

int bs_scene_add_obstacle(bs_scene *s, bs_shape shape, bs_scene_obstacle **out, bs_error *err) {
  if ((unsigned)shape > BS_SHAPE_GRID)
    return bs_error_set(err, BS_EINPUT, "%s: obstacles.%d.shape: unknown shape %d", s->path, s->n_obstacles, (int)shape);
  bs_scene_obstacle *o = grow(s->obstacles, s->n_obstacles, sizeof *o, err);
  if (!o) return BS_ENOMEM;
  s->obstacles = o;
  o += s->n_obstacles++;
  bs__scene_obstacle_defaults(o);
  o->shape = shape;
  *out = o;
  return 0;
}

int bs_scene_add_qoi(bs_scene *s, const char *name, bs_qoi_kind kind, bs_scene_qoi **out, bs_error *err) {
  if (!name || !name[0] || strlen(name) >= BS_MAX_NAME || strchr(name, ','))
    return bs_error_set(err, BS_EINPUT, "%s: qoi.%d.name: must be 1 to %d characters without a comma", s->path,
                        s->n_qoi, BS_MAX_NAME - 1);
  if ((unsigned)kind > BS_QOI_ENERGY)
    return bs_error_set(err, BS_EINPUT, "%s: qoi.%d.quantity: unknown kind %d", s->path, s->n_qoi, (int)kind);
  bs_scene_qoi *q = grow(s->qoi, s->n_qoi, sizeof *q, err);
  if (!q) return BS_ENOMEM;
  s->qoi = q;
  q += s->n_qoi++;
  bs__scene_qoi_defaults(q);
  q->kind = kind;
  snprintf(q->name, sizeof q->name, "%s", name);
  *out = q;
  return 0;
}

void bs_scene_destroy(bs_scene **ps) {
  if (!ps || !*ps) return;
  bs_scene *s = *ps;
  for (int i = 0; i < s->n_bodies; i++) {
    bs_scene_body *b = &s->bodies[i];
    free(b->materials);
    for (int k = 0; k < b->n_scripts; k++) {
      free(b->scripts[k].key_t);
      free(b->scripts[k].key_offset);
    }
    free(b->scripts);
  }
  free(s->bodies);
  for (int i = 0; i < s->n_obstacles; i++) {
    free(s->obstacles[i].key_t);
    free(s->obstacles[i].key_translate);
    free(s->obstacles[i].key_rotate);
  }
  free(s->obstacles);
  free(s->qoi);
  free(s->description);
  free(s);
  *ps = NULL;
}
