/* scene_write.c — the resolved scene as JSON (bs_scene_write_json): every key
 * the loader reads, in the schema table's order and layout, with the value
 * the scene holds, so that loading the text gives the same scene back. */
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cJSON.h>

#include "bs_field_names.h"
#include "bs_scene.h"
#include "json_print.h"
#include "outfile.h"
#include "scene_schema.h"

/* Adding members; a failed allocation sets oom (checked once at the end). */
typedef struct writer {
  int oom;
} writer;

static cJSON *put(writer *w, cJSON *o, const char *key, cJSON *v) {
  if (!v || !cJSON_AddItemToObject(o, key, v)) {
    cJSON_Delete(v);
    w->oom = 1;
    return NULL;
  }
  return v;
}

static void num(writer *w, cJSON *o, const char *key, double v) { put(w, o, key, cJSON_CreateNumber(v)); }
static void str(writer *w, cJSON *o, const char *key, const char *v) { put(w, o, key, cJSON_CreateString(v)); }
static void boolean(writer *w, cJSON *o, const char *key, int v) { put(w, o, key, cJSON_CreateBool(v != 0)); }
static void vec3(writer *w, cJSON *o, const char *key, const double v[3]) {
  put(w, o, key, cJSON_CreateDoubleArray(v, 3));
}
static cJSON *object(writer *w, cJSON *o, const char *key) { return put(w, o, key, cJSON_CreateObject()); }
static cJSON *array(writer *w, cJSON *o, const char *key) { return put(w, o, key, cJSON_CreateArray()); }

/* An element appended to an array (NULL when arr is). */
static cJSON *element(writer *w, cJSON *arr) {
  cJSON *e = arr ? cJSON_CreateObject() : NULL;
  if (!e || !cJSON_AddItemToArray(arr, e)) {
    cJSON_Delete(e);
    w->oom = 1;
    return NULL;
  }
  return e;
}

/* The table's name of choice i of section.key ("?" outside the list). */
static const char *choice(const char *section, const char *key, int i) {
  const bs_schema_key *k = bs_schema_find_(section, key);
  int n = 0;
  while (k && k->choices && k->choices[n]) n++;
  return i >= 0 && i < n ? k->choices[i] : "?";
}

/* A path made absolute when it names an existing file. */
static void path(writer *w, cJSON *o, const char *key, const char *p) {
  char abs[PATH_MAX];
  str(w, o, key, p[0] && realpath(p, abs) ? abs : p);
}

static void write_solver(writer *w, cJSON *o, const bs_scene *s) {
  const bs_minimize_opts *m = &s->solver.min;
  str(w, o, "method", bs_method_name(s->solver.method));
  str(w, o, "linear", bs_lin_kind_name(m->linear));
  num(w, o, "tolerance", m->tol);
  num(w, o, "rtol", m->rtol);
  num(w, o, "load_rtol", m->load_rtol);
  num(w, o, "max_iterations", m->max_iter);
  num(w, o, "newton_max_iterations", m->newton_max_iter);
  num(w, o, "cg_max_iterations", m->cg_max_iter);
  num(w, o, "newton_k", s->solver.newton_k);
  str(w, o, "mode", choice("solver", "mode", s->mode == BS_MODE_STATIC));
  str(w, o, "backend", choice("solver", "backend", (int)s->backend));
  num(w, o, "load_steps", s->load_steps);
  str(w, o, "project_hessian", choice("solver", "project_hessian", s->project_hessian));
  if (m->sigma_auto) {
    str(w, o, "cg_sigma", "auto");
    num(w, o, "cg_sigma_scale", m->sigma);
  } else {
    num(w, o, "cg_sigma", m->sigma);
  }
  str(w, o, "cg_forcing", choice("solver", "cg_forcing", m->forcing_ew));
  str(w, o, "globalization", choice("solver", "globalization", (int)m->globalization));
  num(w, o, "tr_radius", m->tr_radius);
  str(w, o, "contact_hessian", choice("solver", "contact_hessian", m->convexify));
  str(w, o, "penalty_hessian", choice("solver", "penalty_hessian", s->solver.penalty_secant));
  boolean(w, o, "cg_downhill", m->cg_downhill);
  str(w, o, "cg_precision", choice("solver", "cg_precision", m->cg_single != 0));
  str(w, o, "amg_matrix", choice("solver", "amg_matrix", !s->solver.amg_at_rest));
  num(w, o, "amg_rebuild_factor", m->amg_rebuild_factor);
  num(w, o, "amg_rebuild_every", m->amg_rebuild_every);
}

static void write_material(writer *w, cJSON *o, const bs_scene_material *m) {
  if (!o) return;
  str(w, o, "model", bs_model_name(m->model));
  num(w, o, "youngs", m->youngs);
  num(w, o, "poisson", m->poisson);
  num(w, o, "density", m->density);
  num(w, o, "rayleigh", m->rayleigh);
}

static void write_script(writer *w, cJSON *o, const bs_scene_script *sc) {
  if (!o) return;
  str(w, o, "group", sc->group);
  if (sc->kind == BS_SCRIPT_FIXED) boolean(w, o, "fixed", 1);
  else if (sc->kind == BS_SCRIPT_VELOCITY) vec3(w, o, "velocity", sc->velocity);
  else {
    cJSON *keys = array(w, o, "keyframes");
    for (int i = 0; i < sc->n_keys; i++) {
      cJSON *k = element(w, keys);
      if (!k) return;
      num(w, k, "t", sc->key_t[i]);
      vec3(w, k, "offset", sc->key_offset + 3 * i);
    }
  }
}

/* box, materials, initial state and scripts of a body. */
static void write_body_parts(writer *w, cJSON *o, const bs_scene_body *b) {
  cJSON *mats = object(w, o, "materials");
  for (int m = 1; m < b->n_materials && mats; m++) write_material(w, object(w, mats, b->materials[m].group), &b->materials[m]);
  vec3(w, o, "velocity", b->velocity);
  vec3(w, o, "angular_velocity", b->angular_velocity);
  cJSON *is = object(w, o, "initial_state");
  if (is) {
    str(w, is, "type", choice("bodies[].initial_state", "type", (int)b->init));
    if (b->init == BS_INIT_RANDOM) {
      vec3(w, is, "lo", b->init_lo);
      vec3(w, is, "hi", b->init_hi);
    }
    if (b->init == BS_INIT_POINT) vec3(w, is, "point", b->init_lo);
    num(w, is, "seed", b->init_seed);
  }
  cJSON *scr = array(w, o, "scripted");
  for (int k = 0; k < b->n_scripts; k++) write_script(w, element(w, scr), &b->scripts[k]);
}

static void write_body(writer *w, cJSON *o, const bs_scene_body *b) {
  if (!o) return;
  int box = !strcmp(b->mesh, "box");
  if (box) str(w, o, "mesh", b->mesh);
  else path(w, o, "mesh", b->mesh);
  cJSON *bx = box ? object(w, o, "box") : NULL;
  if (bx) {
    put(w, bx, "cells", cJSON_CreateIntArray(b->box_cells, 3));
    vec3(w, bx, "size", b->box_size);
  }
  num(w, o, "mesh_size", b->mesh_size);
  num(w, o, "min_dihedral", b->min_dihedral);
  num(w, o, "refine", b->refine);
  boolean(w, o, "close_holes", b->close_holes);
  str(w, o, "mesher", bs_mesh_mesher_name(b->mesher));
  str(w, o, "reorder", choice("bodies[]", "reorder", (int)b->reorder));
  vec3(w, o, "scale", b->scale);
  vec3(w, o, "rotate", b->rotate);
  vec3(w, o, "translate", b->translate);
  if (b->n_materials > 0) write_material(w, object(w, o, "material"), &b->materials[0]);
  write_body_parts(w, o, b);
}

static void write_obstacle(writer *w, cJSON *o, const bs_scene_obstacle *b) {
  if (!o) return;
  str(w, o, "shape", bs_shape_name(b->shape));
  vec3(w, o, "normal", b->normal);
  num(w, o, "offset", b->offset);
  vec3(w, o, "center", b->center);
  num(w, o, "radius", b->radius);
  vec3(w, o, "half_extents", b->half_extents);
  vec3(w, o, "axis", b->axis);
  num(w, o, "half_height", b->half_height);
  num(w, o, "major", b->major);
  num(w, o, "minor", b->minor);
  boolean(w, o, "inside_out", b->inside_out);
  path(w, o, "file", b->grid_file);
  num(w, o, "grid_h", b->grid_h);
  str(w, o, "collision", bs_collide_mode_name(b->collision));
  num(w, o, "stiffness", b->stiffness);
  num(w, o, "friction", b->friction);
  vec3(w, o, "velocity", b->velocity);
  vec3(w, o, "angular_velocity", b->angular_velocity);
  if (b->n_keys < 1) return;
  cJSON *keys = array(w, o, "keyframes");
  for (int i = 0; i < b->n_keys; i++) {
    cJSON *k = element(w, keys);
    if (!k) return;
    num(w, k, "t", b->key_t[i]);
    vec3(w, k, "translate", b->key_translate + 3 * i);
    vec3(w, k, "rotate", b->key_rotate + 3 * i);
  }
}

/* Sections after the bodies: obstacles, self_collision, output. */
static void write_qoi(writer *w, cJSON *o, const bs_scene_qoi *q) {
  if (!o) return;
  str(w, o, "name", q->name);
  str(w, o, "quantity", choice("qoi[]", "quantity", (int)q->kind));
  str(w, o, "component", choice("qoi[]", "component", q->component));
  str(w, o, "reduce", choice("qoi[]", "reduce", (int)q->reduce));
  num(w, o, "body", q->body);
  if (q->group[0]) str(w, o, "group", q->group);
  if (q->has_at) vec3(w, o, "at", q->at);
  num(w, o, "obstacle", q->obstacle);
  str(w, o, "term", choice("qoi[]", "term", (int)q->energy));
}

static void write_tail(writer *w, cJSON *root, const bs_scene *s) {
  if (s->n_qoi > 0) {
    cJSON *qa = array(w, root, "qoi");
    for (int i = 0; i < s->n_qoi; i++) write_qoi(w, element(w, qa), &s->qoi[i]);
  }
  cJSON *obs = array(w, root, "obstacles");
  for (int i = 0; i < s->n_obstacles; i++) write_obstacle(w, element(w, obs), &s->obstacles[i]);
  cJSON *sc = s->self_collision ? object(w, root, "self_collision") : NULL;
  if (sc) {
    num(w, sc, "stiffness", s->self_stiffness);
    num(w, sc, "friction", s->self_friction);
  }
  cJSON *out = object(w, root, "output");
  if (out) {
    str(w, out, "dir", s->out_dir);
    num(w, out, "vtu_every", s->vtu_every);
    num(w, out, "checkpoint_every", s->checkpoint_every);
    boolean(w, out, "stats", s->stats_csv);
    boolean(w, out, "states", s->states);
    const char *names[BS_FIELD_COUNT];
    int n = 0;
    for (int f = 0; f < BS_FIELD_COUNT; f++)
      if (s->out_fields & BS_FIELD_BIT(f)) names[n++] = bs_field_name((bs_field)f);
    put(w, out, "fields", cJSON_CreateStringArray(names, n));
    boolean(w, out, "compress", s->out_compress);
  }
}

int bs_scene_write_json(const bs_scene *s, char **out, bs_error *err) {
  *out = NULL;
  writer w = {0};
  cJSON *root = cJSON_CreateObject();
  if (!root) return bs_error_set(err, BS_ENOMEM, "out of memory writing the resolved scene");
  if (s->description) str(&w, root, "description", s->description);
  cJSON *t = object(&w, root, "time");
  if (t) {
    num(&w, t, "fps", s->fps);
    num(&w, t, "frames", s->frames);
    num(&w, t, "steps_per_frame", s->steps_per_frame);
  }
  cJSON *so = object(&w, root, "solver");
  if (so) write_solver(&w, so, s);
  vec3(&w, root, "gravity", s->gravity);
  num(&w, root, "drag", s->drag);
  cJSON *bodies = array(&w, root, "bodies");
  for (int i = 0; i < s->n_bodies; i++) write_body(&w, element(&w, bodies), &s->bodies[i]);
  write_tail(&w, root, s);
  *out = w.oom ? NULL : bs_json_print_(root);
  cJSON_Delete(root);
  return *out ? 0 : bs_error_set(err, BS_ENOMEM, "out of memory writing the resolved scene");
}

int bs_scene_write_json_file(const bs_scene *s, const char *file, bs_error *err) {
  char *text;
  int st = bs_scene_write_json(s, &text, err);
  if (st) return st;
  st = bs_outfile_replace_text(NULL, file, text, err);
  free(text);
  if (st) bs_error_prefix(err, "the resolved scene");
  return st;
}
