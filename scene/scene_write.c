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
  const bs_schema_key *k = bs__schema_find(section, key);
  int n = 0;
  while (k && k->choices && k->choices[n]) n++;
  return i >= 0 && i < n ? k->choices[i] : "?";
}

/* A path made absolute when it names an existing file. */
static void path(writer *w, cJSON *o, const char *key, const char *p) {
  char abs[PATH_MAX];
  str(w, o, key, p[0] && realpath(p, abs) ? abs : p);
}

/* One key bound to a struct field (scene_schema.h), written as its type says. */
static void write_bound(writer *w, cJSON *o, const bs_schema_key *k, const char *field) {
  const int *ip = (const int *)(const void *)field;
  const char *name;
  switch (k->type) {
  case BS_SCHEMA_NUMBER: num(w, o, k->key, *(const double *)(const void *)field); break;
  case BS_SCHEMA_INTEGER: num(w, o, k->key, *ip); break;
  case BS_SCHEMA_BOOLEAN: boolean(w, o, k->key, *ip); break;
  case BS_SCHEMA_VEC3:
  case BS_SCHEMA_NUM_OR_VEC3: vec3(w, o, k->key, (const double *)(const void *)field); break;
  case BS_SCHEMA_IVEC3: put(w, o, k->key, cJSON_CreateIntArray(ip, 3)); break;
  case BS_SCHEMA_STRING:
    if (k->choices) {
      name = bs__schema_choice_name(k, *ip);
      str(w, o, k->key, name ? name : "?");
    } else if (k->path && strcmp(field, "box")) {
      path(w, o, k->key, field);
    } else {
      str(w, o, k->key, field);
    }
    break;
  default: break;
  }
}

/* What a section writes by hand: its unbound keys (objects, arrays, keys
 * with rules) and the bound keys with neither a default nor `required`
 * (optional values, written only when set); called with each such key in
 * the table's order. */
typedef void (*hand_fn)(writer *w, cJSON *o, const char *key, const void *base);

/* Every key of `section`, in the table's order: bound keys from the struct
 * at base, the others through hand (NULL: none). */
static void write_section(writer *w, cJSON *o, const char *section, const void *base, hand_fn hand) {
  if (!o) return;
  for (int i = 0; i < bs__schema_n_keys; i++) {
    const bs_schema_key *k = &bs__schema_keys[i];
    if (strcmp(k->section, section)) continue;
    if (bs__schema_bound(k) && (k->def || k->required)) write_bound(w, o, k, (const char *)base + k->offset);
    else if (hand) hand(w, o, k->key, base);
  }
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

static void write_initial_state(writer *w, cJSON *is, const bs_scene_body *b) {
  if (!is) return;
  str(w, is, "type", choice("bodies[].initial_state", "type", (int)b->init));
  if (b->init == BS_INIT_RANDOM) {
    vec3(w, is, "lo", b->init_lo);
    vec3(w, is, "hi", b->init_hi);
  }
  if (b->init == BS_INIT_POINT) vec3(w, is, "point", b->init_lo);
  num(w, is, "seed", b->init_seed);
}

/* A body's keys that are not bound: box, materials, initial state, scripts. */
static void body_hand(writer *w, cJSON *o, const char *key, const void *base) {
  const bs_scene_body *b = base;
  if (!strcmp(key, "box") && !strcmp(b->mesh, "box")) {
    write_section(w, object(w, o, "box"), "bodies[].box", b, NULL);
  } else if (!strcmp(key, "material") && b->n_materials > 0) {
    write_section(w, object(w, o, "material"), "bodies[].material", &b->materials[0], NULL);
  } else if (!strcmp(key, "materials")) {
    cJSON *mats = object(w, o, "materials");
    for (int m = 1; m < b->n_materials && mats; m++)
      write_section(w, object(w, mats, b->materials[m].group), "bodies[].material", &b->materials[m], NULL);
  } else if (!strcmp(key, "initial_state")) {
    write_initial_state(w, object(w, o, "initial_state"), b);
  } else if (!strcmp(key, "scripted")) {
    cJSON *scr = array(w, o, "scripted");
    for (int k = 0; k < b->n_scripts; k++) write_script(w, element(w, scr), &b->scripts[k]);
  }
}

/* An obstacle's keyframes (its only key that is not bound). */
static void obstacle_hand(writer *w, cJSON *o, const char *key, const void *base) {
  const bs_scene_obstacle *b = base;
  if (strcmp(key, "keyframes") || b->n_keys < 1) return;
  cJSON *keys = array(w, o, "keyframes");
  for (int i = 0; i < b->n_keys; i++) {
    cJSON *k = element(w, keys);
    if (!k) return;
    num(w, k, "t", b->key_t[i]);
    vec3(w, k, "translate", b->key_translate + 3 * i);
    vec3(w, k, "rotate", b->key_rotate + 3 * i);
  }
}

/* A quantity's group or point, written when it has one. */
static void qoi_hand(writer *w, cJSON *o, const char *key, const void *base) {
  const bs_scene_qoi *q = base;
  if (!strcmp(key, "group") && q->group[0]) str(w, o, "group", q->group);
  if (!strcmp(key, "at") && q->has_at) vec3(w, o, "at", q->at);
}

/* cg_sigma: "auto" with its scale, or a number; integrator when not
 * backward Euler (so that the resolved scene, and the scene hash of
 * checkpoints, of a scene without it stay as they were). */
static void solver_hand(writer *w, cJSON *o, const char *key, const void *base) {
  const bs_integrator_opts *so = &((const bs_scene *)base)->solver;
  const bs_minimize_opts *m = &so->min;
  if (!strcmp(key, "integrator") && so->integrator != BS_INTEGRATOR_BACKWARD_EULER) {
    str(w, o, "integrator", bs_time_integrator_name((bs_time_integrator)so->integrator));
  } else if (!strcmp(key, "cg_sigma")) {
    if (m->sigma_auto) str(w, o, "cg_sigma", "auto");
    else num(w, o, "cg_sigma", m->sigma);
  } else if (!strcmp(key, "cg_sigma_scale") && m->sigma_auto) {
    num(w, o, "cg_sigma_scale", m->sigma);
  }
}

/* output.fields, as the names of the set. */
static void output_hand(writer *w, cJSON *o, const char *key, const void *base) {
  const bs_scene *s = base;
  if (strcmp(key, "fields")) return;
  const char *names[BS_FIELD_COUNT];
  int n = 0;
  for (int f = 0; f < BS_FIELD_COUNT; f++)
    if (s->out_fields & BS_FIELD_BIT(f)) names[n++] = bs_field_name((bs_field)f);
  put(w, o, "fields", cJSON_CreateStringArray(names, n));
}

/* contact's keys (bound, no default): written when given (> 0). */
static void contact_hand(writer *w, cJSON *o, const char *key, const void *base) {
  const bs_scene *s = base;
  if (!strcmp(key, "dhat") && s->contact_dhat > 0) num(w, o, "dhat", s->contact_dhat);
  if (!strcmp(key, "kappa") && s->contact_kappa > 0) num(w, o, "kappa", s->contact_kappa);
}

/* The top level's keys that are not bound: the notes and the sections. */
static void root_hand(writer *w, cJSON *root, const char *key, const void *base) {
  const bs_scene *s = base;
  if (!strcmp(key, "description") && s->description) str(w, root, "description", s->description);
  else if (!strcmp(key, "time")) write_section(w, object(w, root, "time"), "time", s, NULL);
  else if (!strcmp(key, "solver")) write_section(w, object(w, root, "solver"), "solver", s, solver_hand);
  else if (!strcmp(key, "bodies")) {
    cJSON *bodies = array(w, root, "bodies");
    for (int i = 0; i < s->n_bodies; i++) write_section(w, element(w, bodies), "bodies[]", &s->bodies[i], body_hand);
  } else if (!strcmp(key, "obstacles")) {
    cJSON *obs = array(w, root, "obstacles");
    for (int i = 0; i < s->n_obstacles; i++)
      write_section(w, element(w, obs), "obstacles[]", &s->obstacles[i], obstacle_hand);
  } else if (!strcmp(key, "self_collision") && s->self_collision) {
    write_section(w, object(w, root, "self_collision"), "self_collision", s, NULL);
  } else if (!strcmp(key, "contact") && (s->contact_dhat > 0 || s->contact_kappa > 0 || s->contact_eps_v != 1e-3)) {
    write_section(w, object(w, root, "contact"), "contact", s, contact_hand);
  } else if (!strcmp(key, "output")) {
    write_section(w, object(w, root, "output"), "output", s, output_hand);
  } else if (!strcmp(key, "qoi") && s->n_qoi > 0) {
    cJSON *qa = array(w, root, "qoi");
    for (int i = 0; i < s->n_qoi; i++) write_section(w, element(w, qa), "qoi[]", &s->qoi[i], qoi_hand);
  }
}

int bs_scene_write_json(const bs_scene *s, char **out, bs_error *err) {
  *out = NULL;
  writer w = {0};
  cJSON *root = cJSON_CreateObject();
  if (!root) return bs_error_set(err, BS_ENOMEM, "out of memory writing the resolved scene");
  write_section(&w, root, "", s, root_hand);
  *out = w.oom ? NULL : bs__json_print(root);
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
