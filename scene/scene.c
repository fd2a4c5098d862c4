/* scene.c — strict JSON scene parsing (cJSON): keys and types here, values in
 * scene_check.c (shared with scenes built in C). The keys allowed in each
 * object, the integer ranges and the allowed strings come from the schema
 * table (scene_schema.c). */
#define _POSIX_C_SOURCE 200809L

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include <cJSON.h>

#include "bs_limits.h"
#include "bs_scene.h"
#include "fields_json.h"
#include "json_locate.h"
#include "scene_internal.h"
#include "scene_schema.h"

/* ---- small strict accessors -------------------------------------------- */

typedef struct ctx {
  const char *file;
  bs_error *err;
} ctx;

static int fail(ctx *c, const char *where, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;

static int fail(ctx *c, const char *where, const char *fmt, ...) {
  char msg[768];
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(msg, sizeof msg, fmt, ap);
  va_end(ap);
  return bs_error_set(c->err, BS_EINPUT, "%s: %s: %s", c->file, where, msg);
}

static void join(char *out, size_t n, const char *where, const char *key) {
  if (where[0]) snprintf(out, n, "%s.%s", where, key);
  else snprintf(out, n, "%s", key);
}

/* What a value is, for "got ..." in messages: string "abc", 3, inf, true,
 * false, null, array of 2, object. */
static const char *got(const cJSON *it, char *buf, size_t n) {
  if (cJSON_IsString(it)) snprintf(buf, n, "string \"%.40s%s\"", it->valuestring, strlen(it->valuestring) > 40 ? "..." : "");
  else if (cJSON_IsNumber(it)) snprintf(buf, n, "%.17g", it->valuedouble);
  else if (cJSON_IsBool(it)) snprintf(buf, n, "%s", cJSON_IsTrue(it) ? "true" : "false");
  else if (cJSON_IsNull(it)) snprintf(buf, n, "null");
  else if (cJSON_IsArray(it)) snprintf(buf, n, "array of %d", cJSON_GetArraySize(it));
  else if (cJSON_IsObject(it)) snprintf(buf, n, "object");
  else snprintf(buf, n, "an invalid value");
  return buf;
}

/* The table's row of section.key (a key the parser reads must be there). */
static const bs_schema_key *row(ctx *c, const char *where, const char *section, const char *key) {
  const bs_schema_key *k = bs__schema_find(section, key);
  if (!k) bs_error_set(c->err, BS_EINTERNAL, "%s: %s.%s: not in the schema table (a bug)", c->file, where, key);
  return k;
}

/* "unknown key; did you mean 'X'? (allowed here: ...)" for the key `bad`. */
static int unknown_key(ctx *c, const char *where, const char *bad, const char *const *keys, int n) {
  char w[512], list[768] = "", hint[128] = "";
  join(w, sizeof w, where, bad);
  for (int i = 0; i < n; i++) {
    strncat(list, keys[i], sizeof list - strlen(list) - 1);
    if (i + 1 < n) strncat(list, ", ", sizeof list - strlen(list) - 1);
  }
  const char *near = bs__schema_nearest(bad, keys, n);
  if (near) snprintf(hint, sizeof hint, "; did you mean '%s'?", near);
  return fail(c, w, "unknown key%s (allowed here: %s)", hint, list);
}

/* "must be "a", "b" or "c", got "x"; did you mean "a"?" for the value v of
 * the key k (its path w). */
static int bad_choice(ctx *c, const char *w, const bs_schema_key *k, const char *v) {
  char list[512] = "", hint[128] = "";
  for (int i = 0; k->choices[i]; i++) {
    char one[96];
    snprintf(one, sizeof one, "%s\"%s\"", i == 0 ? "" : k->choices[i + 1] ? ", " : " or ", k->choices[i]);
    strncat(list, one, sizeof list - strlen(list) - 1);
  }
  const char *near = bs__schema_nearest(v, k->choices, -1);
  if (near) snprintf(hint, sizeof hint, "; did you mean \"%s\"?", near);
  return fail(c, w, "must be %s, got \"%.64s\"%s", list, v, hint);
}

static int is_finite_number(const cJSON *v) { return cJSON_IsNumber(v) && isfinite(v->valuedouble); }

/* 1 when v is an array of 3 finite numbers. */
static int is_vec3(const cJSON *v) {
  if (!cJSON_IsArray(v) || cJSON_GetArraySize(v) != 3) return 0;
  for (const cJSON *e = v->child; e; e = e->next)
    if (!is_finite_number(e)) return 0;
  return 1;
}

/* What v must be for the table's type of its key (into want), or NULL when
 * it fits. */
static const char *type_misfit(const bs_schema_key *k, const cJSON *v, char *want, size_t n) {
  bs_schema_range r;
  char rt[96] = "";
  if (bs__schema_range(k, &r)) bs__schema_range_text(&r, rt, sizeof rt);
  int ok = 1;
  switch (k->type) {
  case BS_SCHEMA_NUMBER:
    ok = is_finite_number(v);
    snprintf(want, n, "%s", cJSON_IsNumber(v) ? "finite" : "a number");
    break;
  case BS_SCHEMA_INTEGER:
    ok = is_finite_number(v) && v->valuedouble == floor(v->valuedouble);
    snprintf(want, n, "an integer%s%s", rt[0] ? " in " : "", rt);
    break;
  case BS_SCHEMA_STRING: ok = cJSON_IsString(v), snprintf(want, n, "a string"); break;
  case BS_SCHEMA_BOOLEAN: ok = cJSON_IsBool(v), snprintf(want, n, "true or false"); break;
  case BS_SCHEMA_VEC3: ok = is_vec3(v), snprintf(want, n, "an array of 3 numbers"); break;
  case BS_SCHEMA_IVEC3: ok = is_vec3(v), snprintf(want, n, "an array of 3 integers"); break;
  case BS_SCHEMA_NUM_OR_VEC3: ok = is_finite_number(v) || is_vec3(v), snprintf(want, n, "a number or an array of 3 numbers"); break;
  case BS_SCHEMA_NUM_OR_CHOICE:
    ok = is_finite_number(v) || (cJSON_IsString(v) && bs__schema_choice(k, v->valuestring) >= 0);
    snprintf(want, n, "a number%s%s or \"%s\"", rt[0] ? " " : "", rt, k->choices ? k->choices[0] : "");
    break;
  case BS_SCHEMA_OBJECT: ok = cJSON_IsObject(v), snprintf(want, n, "an object"); break;
  case BS_SCHEMA_ARRAY: ok = cJSON_IsArray(v), snprintf(want, n, "an array"); break;
  case BS_SCHEMA_MAP: ok = cJSON_IsObject(v), snprintf(want, n, "an object {name: object}"); break;
  case BS_SCHEMA_STRINGS:
    ok = cJSON_IsArray(v);
    for (const cJSON *e = ok ? v->child : NULL; e; e = e->next) ok &= cJSON_IsString(e);
    snprintf(want, n, "an array of strings");
    break;
  }
  return ok ? NULL : want;
}

/* The value v of key k (at path w) against the table: its type, and for
 * STRINGS with choices each element. */
static int check_value(ctx *c, const char *w, const bs_schema_key *k, const cJSON *v) {
  char want[160], g[96];
  if (!type_misfit(k, v, want, sizeof want)) {
    if (k->type != BS_SCHEMA_STRINGS || !k->choices) return 0;
    int i = 0;
    for (const cJSON *e = v->child; e; e = e->next, i++)
      if (bs__schema_choice(k, e->valuestring) < 0) {
        char wi[600];
        snprintf(wi, sizeof wi, "%s.%d", w, i);
        return bad_choice(c, wi, k, e->valuestring);
      }
    return 0;
  }
  if (cJSON_IsArray(v) && cJSON_GetArraySize(v) == 3 && strstr(want, "array of 3")) /* name the element */
    for (int e = 0; e < 3; e++)
      if (!is_finite_number(cJSON_GetArrayItem(v, e)))
        return fail(c, w, "element %d must be a finite number, got %s", e, got(cJSON_GetArrayItem(v, e), g, sizeof g));
  return fail(c, w, "must be %s, got %s", want, got(v, g, sizeof g));
}

/* obj must be an object whose keys are all keys of the table's `section`,
 * each given once, each value of its key's type. */
static int check_keys(ctx *c, const cJSON *obj, const char *where, const char *section) {
  char g[96], w[512];
  if (!cJSON_IsObject(obj)) return fail(c, where[0] ? where : "(top level)", "must be an object, got %s", got(obj, g, sizeof g));
  const char *keys[128];
  int n = bs__schema_section_keys(section, keys, 128);
  for (const cJSON *it = obj->child; it; it = it->next) {
    int ok = 0;
    for (int i = 0; i < n && !ok; i++) ok = !strcmp(it->string, keys[i]);
    if (!ok) return unknown_key(c, where, it->string, keys, n);
    join(w, sizeof w, where, it->string);
    for (const cJSON *p = obj->child; p != it; p = p->next)
      if (!strcmp(p->string, it->string)) return fail(c, w, "given twice");
    int st = check_value(c, w, bs__schema_find(section, it->string), it);
    if (st) return st;
  }
  return 0;
}

static int get_num(ctx *c, const cJSON *obj, const char *where, const char *key, int required, double *out) {
  const cJSON *it = cJSON_GetObjectItemCaseSensitive(obj, key);
  char w[512], g[96];
  join(w, sizeof w, where, key);
  if (!it) return required ? fail(c, w, "missing (a number is required)") : 0;
  if (!cJSON_IsNumber(it)) return fail(c, w, "must be a number, got %s", got(it, g, sizeof g));
  if (!isfinite(it->valuedouble)) return fail(c, w, "must be finite, got %g", it->valuedouble);
  *out = it->valuedouble;
  return 0;
}

/* An integer in the table's range for section.key (required as the table
 * says); untouched when absent. */
static int get_int(ctx *c, const cJSON *obj, const char *where, const char *section, const char *key, int *out) {
  const bs_schema_key *k = row(c, where, section, key);
  if (!k) return BS_EINTERNAL;
  double v = *out;
  char w[512], rt[96];
  join(w, sizeof w, where, key);
  if (!cJSON_GetObjectItemCaseSensitive(obj, key) && !k->required) return 0;
  int st = get_num(c, obj, where, key, k->required, &v);
  if (st) return st;
  bs_schema_range r;
  bs__schema_range(k, &r);
  bs__schema_range_text(&r, rt, sizeof rt);
  if (v != floor(v) || !bs__schema_in_range(&r, v) || fabs(v) > 2147483647.0)
    return fail(c, w, "must be an integer in %s, got %.17g", rt, v);
  *out = (int)v;
  return 0;
}

static int get_str(ctx *c, const cJSON *obj, const char *where, const char *key, int required, char *out,
                   size_t n) {
  const cJSON *it = cJSON_GetObjectItemCaseSensitive(obj, key);
  char w[512], g[96];
  join(w, sizeof w, where, key);
  if (!it) return required ? fail(c, w, "missing (a string is required)") : 0;
  if (!cJSON_IsString(it)) return fail(c, w, "must be a string, got %s", got(it, g, sizeof g));
  if (strlen(it->valuestring) >= n) return fail(c, w, "string too long (at most %zu characters)", n - 1);
  snprintf(out, n, "%s", it->valuestring);
  return 0;
}

/* A string key that must be one of the table's choices for section.key:
 * buf holds it ("" when absent and not required). */
static int get_choice_str(ctx *c, const cJSON *obj, const char *where, const char *section, const char *key,
                          char *buf, size_t n) {
  const bs_schema_key *k = row(c, where, section, key);
  if (!k) return BS_EINTERNAL;
  buf[0] = 0;
  int st = get_str(c, obj, where, key, k->required, buf, n);
  if (st || !buf[0] || bs__schema_choice(k, buf) >= 0) return st;
  char w[512];
  join(w, sizeof w, where, key);
  return bad_choice(c, w, k, buf);
}

/* The same as an index into the choices: *out untouched when absent. */
static int get_choice(ctx *c, const cJSON *obj, const char *where, const char *section, const char *key, int *out) {
  char buf[64];
  int st = get_choice_str(c, obj, where, section, key, buf, sizeof buf);
  if (!st && buf[0]) *out = bs__schema_choice(bs__schema_find(section, key), buf);
  return st;
}

static int get_bool(ctx *c, const cJSON *obj, const char *where, const char *key, int *out) {
  const cJSON *it = cJSON_GetObjectItemCaseSensitive(obj, key);
  char w[512], g[96];
  join(w, sizeof w, where, key);
  if (!it) return 0;
  if (!cJSON_IsBool(it)) return fail(c, w, "must be true or false, got %s", got(it, g, sizeof g));
  *out = cJSON_IsTrue(it);
  return 0;
}

static int get_vec3(ctx *c, const cJSON *obj, const char *where, const char *key, int required, double out[3]) {
  const cJSON *it = cJSON_GetObjectItemCaseSensitive(obj, key);
  char w[512], g[96];
  join(w, sizeof w, where, key);
  if (!it) return required ? fail(c, w, "missing (an array of 3 numbers is required)") : 0;
  if (!cJSON_IsArray(it) || cJSON_GetArraySize(it) != 3)
    return fail(c, w, "must be an array of 3 numbers, got %s", got(it, g, sizeof g));
  for (int k = 0; k < 3; k++) {
    const cJSON *e = cJSON_GetArrayItem(it, k);
    if (!cJSON_IsNumber(e) || !isfinite(e->valuedouble))
      return fail(c, w, "element %d must be a finite number, got %s", k, got(e, g, sizeof g));
    out[k] = e->valuedouble;
  }
  return 0;
}

/* An array value (NULL when absent): *arr, or a message naming what it got;
 * non_empty: at least one element. */
static int get_array(ctx *c, const cJSON *obj, const char *where, const char *key, int non_empty, const cJSON **arr) {
  const cJSON *it = cJSON_GetObjectItemCaseSensitive(obj, key);
  char w[512], g[96];
  join(w, sizeof w, where, key);
  *arr = it;
  if (!it) return 0;
  if (!cJSON_IsArray(it) || (non_empty && cJSON_GetArraySize(it) < 1))
    return fail(c, w, "must be a%s array, got %s", non_empty ? " non-empty" : "n", got(it, g, sizeof g));
  return 0;
}

/* ---- keys bound to struct fields (scene_schema.h) ------------------------ */

/* An IVEC3 key (bodies[].box.cells): integers in the table's range. */
static int get_ivec3(ctx *c, const cJSON *obj, const char *where, const bs_schema_key *k, int out[3]) {
  double v[3];
  int st = get_vec3(c, obj, where, k->key, k->required, v);
  if (st || !cJSON_GetObjectItemCaseSensitive(obj, k->key)) return st;
  bs_schema_range r;
  char w[600], rt[96];
  bs__schema_range(k, &r);
  bs__schema_range_text(&r, rt, sizeof rt);
  join(w, sizeof w, where, k->key);
  for (int i = 0; i < 3; i++)
    if (v[i] != floor(v[i]) || !bs__schema_in_range(&r, v[i]))
      return fail(c, w, "element %d must be an integer in %s, got %.17g", i, rt, v[i]);
  for (int i = 0; i < 3; i++) out[i] = (int)v[i];
  return 0;
}

/* A number (the same for x, y, z) or an array of 3 (a NUM_OR_VEC3 key). */
static int get_num_or_vec3(ctx *c, const cJSON *obj, const char *where, const bs_schema_key *k, double out[3]) {
  const cJSON *it = cJSON_GetObjectItemCaseSensitive(obj, k->key);
  if (!cJSON_IsNumber(it)) return get_vec3(c, obj, where, k->key, k->required, out);
  out[0] = out[1] = out[2] = it->valuedouble;
  return 0;
}

/* One key bound to a struct field (scene_schema.h), read into `field` as its
 * type says; untouched when absent. */
static int get_bound(ctx *c, const cJSON *obj, const char *where, const bs_schema_key *k, char *field) {
  int *ip = (int *)(void *)field, idx = -1, st;
  switch (k->type) {
  case BS_SCHEMA_NUMBER: return get_num(c, obj, where, k->key, k->required, (double *)(void *)field);
  case BS_SCHEMA_INTEGER: return get_int(c, obj, where, k->section, k->key, ip);
  case BS_SCHEMA_BOOLEAN: return get_bool(c, obj, where, k->key, ip);
  case BS_SCHEMA_VEC3: return get_vec3(c, obj, where, k->key, k->required, (double *)(void *)field);
  case BS_SCHEMA_NUM_OR_VEC3: return get_num_or_vec3(c, obj, where, k, (double *)(void *)field);
  case BS_SCHEMA_IVEC3: return get_ivec3(c, obj, where, k, ip);
  case BS_SCHEMA_STRING:
    if (!k->choices) return get_str(c, obj, where, k->key, k->required, field, k->size);
    if (!(st = get_choice(c, obj, where, k->section, k->key, &idx)) && idx >= 0) *ip = bs__schema_choice_value(k, idx);
    return st;
  default: return fail(c, where, "%s: the schema binds a key of a type it cannot read (a bug)", k->key);
  }
}

/* Every key of `section` bound to a field of the struct at base, in the
 * table's order. */
static int get_section(ctx *c, const cJSON *obj, const char *where, const char *section, void *base) {
  for (int i = 0; i < bs__schema_n_keys; i++) {
    const bs_schema_key *k = &bs__schema_keys[i];
    if (!bs__schema_bound(k) || strcmp(k->section, section)) continue;
    int st = get_bound(c, obj, where, k, (char *)base + k->offset);
    if (st) return st;
  }
  return 0;
}

/* ---- sections ------------------------------------------------------------ */

static int parse_material(ctx *c, const cJSON *o, const char *where, bs_scene_material *m) {
  int st;
  if ((st = check_keys(c, o, where, "bodies[].material"))) return st;
  m->rayleigh = 0;
  return get_section(c, o, where, "bodies[].material", m);
}

static int parse_script_keys(ctx *c, const cJSON *arr, const char *w, bs_scene_script *s) {
  int st;
  s->n_keys = cJSON_GetArraySize(arr);
  s->key_t = calloc((size_t)s->n_keys, sizeof(double));
  s->key_offset = calloc(3 * (size_t)s->n_keys, sizeof(double));
  if (!s->key_t || !s->key_offset) return bs_error_set(c->err, BS_ENOMEM, "out of memory reading %s", w);
  for (int i = 0; i < s->n_keys; i++) {
    char wi[600];
    snprintf(wi, sizeof wi, "%s.%d", w, i);
    const cJSON *k = cJSON_GetArrayItem(arr, i);
    if ((st = check_keys(c, k, wi, "bodies[].scripted[].keyframes[]")) ||
        (st = get_num(c, k, wi, "t", 1, &s->key_t[i])) || (st = get_vec3(c, k, wi, "offset", 1, s->key_offset + 3 * i)))
      return st;
  }
  return 0;
}

static int parse_script(ctx *c, const cJSON *o, const char *where, bs_scene_script *s) {
  int st;
  if ((st = check_keys(c, o, where, "bodies[].scripted[]"))) return st;
  if ((st = get_str(c, o, where, "group", 1, s->group, sizeof s->group))) return st;
  int has_v = cJSON_HasObjectItem(o, "velocity"), has_k = cJSON_HasObjectItem(o, "keyframes");
  int fixed = 0;
  if ((st = get_bool(c, o, where, "fixed", &fixed))) return st;
  if (has_v + has_k + fixed != 1)
    return fail(c, where, "give exactly one of \"velocity\", \"keyframes\" or \"fixed\": true");
  if (fixed) s->kind = BS_SCRIPT_FIXED;
  if (has_v) {
    s->kind = BS_SCRIPT_VELOCITY;
    if ((st = get_vec3(c, o, where, "velocity", 1, s->velocity))) return st;
  }
  if (has_k) {
    s->kind = BS_SCRIPT_KEYFRAMES;
    char w[512];
    join(w, sizeof w, where, "keyframes");
    const cJSON *arr;
    if ((st = get_array(c, o, where, "keyframes", 1, &arr))) return st;
    return parse_script_keys(c, arr, w, s);
  }
  return 0;
}

/* "material" (the default, required) and "materials": {group: {...}}. */
static int parse_body_materials(ctx *c, const cJSON *o, const char *where, bs_scene_body *b) {
  int st;
  char w[512], g[96];
  const cJSON *mats = cJSON_GetObjectItemCaseSensitive(o, "materials");
  join(w, sizeof w, where, "materials");
  if (mats && !cJSON_IsObject(mats))
    return fail(c, w, "must be an object {group name: material}, got %s", got(mats, g, sizeof g));
  int nm = 1 + (mats ? cJSON_GetArraySize(mats) : 0);
  b->materials = calloc((size_t)nm, sizeof(bs_scene_material));
  if (!b->materials) return bs_error_set(c->err, BS_ENOMEM, "out of memory");
  b->n_materials = nm;
  for (int i = 0; i < nm; i++) bs__scene_material_defaults(&b->materials[i]);
  const cJSON *mat = cJSON_GetObjectItemCaseSensitive(o, "material");
  join(w, sizeof w, where, "material");
  if (!mat) return fail(c, w, "missing (an object with model, youngs, poisson, density is required)");
  if ((st = parse_material(c, mat, w, &b->materials[0]))) return st;
  if (mats) {
    join(w, sizeof w, where, "materials");
    int i = 1;
    for (const cJSON *it = mats->child; it; it = it->next, i++) {
      char wi[600];
      snprintf(wi, sizeof wi, "%s.%s", w, it->string);
      if (strlen(it->string) >= sizeof b->materials[i].group) return fail(c, wi, "group name too long");
      snprintf(b->materials[i].group, sizeof b->materials[i].group, "%s", it->string);
      if ((st = parse_material(c, it, wi, &b->materials[i]))) return st;
    }
  }
  return 0;
}

/* "initial_state": rest, random in a box, or a point. */
static int parse_body_init(ctx *c, const cJSON *o, const char *where, bs_scene_body *b) {
  int st;
  char w[512];
  const cJSON *is = cJSON_GetObjectItemCaseSensitive(o, "initial_state");
  if (!is) return 0;
  join(w, sizeof w, where, "initial_state");
  int type = 0, seed = 1;
  if ((st = check_keys(c, is, w, "bodies[].initial_state")) ||
      (st = get_choice(c, is, w, "bodies[].initial_state", "type", &type)) ||
      (st = get_int(c, is, w, "bodies[].initial_state", "seed", &seed)))
    return st;
  b->init_seed = (unsigned)seed;
  b->init = (bs_init_kind)type; /* the table's order: rest, random, point */
  if (b->init == BS_INIT_RANDOM)
    return (st = get_vec3(c, is, w, "lo", 1, b->init_lo)) ? st : get_vec3(c, is, w, "hi", 1, b->init_hi);
  if (b->init == BS_INIT_POINT) return get_vec3(c, is, w, "point", 0, b->init_lo);
  return 0;
}

/* "scripted": [{group, velocity | keyframes | fixed}]. */
static int parse_body_scripts(ctx *c, const cJSON *o, const char *where, bs_scene_body *b) {
  int st;
  char w[512];
  const cJSON *scr;
  if ((st = get_array(c, o, where, "scripted", 0, &scr)) || !scr) return st;
  join(w, sizeof w, where, "scripted");
  b->n_scripts = cJSON_GetArraySize(scr);
  b->scripts = calloc((size_t)(b->n_scripts ? b->n_scripts : 1), sizeof(bs_scene_script));
  if (!b->scripts) return bs_error_set(c->err, BS_ENOMEM, "out of memory");
  for (int i = 0; i < b->n_scripts; i++) {
    char wi[600];
    snprintf(wi, sizeof wi, "%s.%d", w, i);
    if ((st = parse_script(c, cJSON_GetArrayItem(scr, i), wi, &b->scripts[i]))) return st;
  }
  return 0;
}

static int parse_body(ctx *c, const cJSON *o, const char *where, bs_scene_body *b) {
  int st;
  if ((st = check_keys(c, o, where, "bodies[]"))) return st;
  bs__scene_body_defaults(b);
  char w[512];
  const cJSON *box = cJSON_GetObjectItemCaseSensitive(o, "box");
  join(w, sizeof w, where, "box");
  if ((st = get_section(c, o, where, "bodies[]", b))) return st;
  if (strcmp(b->mesh, "box") == 0) {
    if (!box) return fail(c, w, "missing: \"mesh\": \"box\" needs \"box\": {\"cells\": [nx, ny, nz], \"size\": [lx, ly, lz]}");
    if ((st = check_keys(c, box, w, "bodies[].box")) || (st = get_section(c, box, w, "bodies[].box", b))) return st;
  } else if (box) {
    return fail(c, w, "only allowed with \"mesh\": \"box\"");
  }
  if ((st = parse_body_materials(c, o, where, b)) || (st = parse_body_init(c, o, where, b))) return st;
  return parse_body_scripts(c, o, where, b);
}

static int parse_obstacle_keys(ctx *c, const cJSON *o, const char *where, bs_scene_obstacle *b) {
  const cJSON *keysj;
  char w[512];
  int st;
  if ((st = get_array(c, o, where, "keyframes", 1, &keysj)) || !keysj) return st;
  join(w, sizeof w, where, "keyframes");
  b->n_keys = cJSON_GetArraySize(keysj);
  b->key_t = calloc((size_t)b->n_keys, sizeof(double));
  b->key_translate = calloc(3 * (size_t)b->n_keys, sizeof(double));
  b->key_rotate = calloc(3 * (size_t)b->n_keys, sizeof(double));
  if (!b->key_t || !b->key_translate || !b->key_rotate) return bs_error_set(c->err, BS_ENOMEM, "out of memory");
  for (int i = 0; i < b->n_keys; i++) {
    char wi[600];
    snprintf(wi, sizeof wi, "%s.%d", w, i);
    const cJSON *k = cJSON_GetArrayItem(keysj, i);
    if ((st = check_keys(c, k, wi, "obstacles[].keyframes[]")) || (st = get_num(c, k, wi, "t", 1, &b->key_t[i])) ||
        (st = get_vec3(c, k, wi, "translate", 0, b->key_translate + 3 * i)) ||
        (st = get_vec3(c, k, wi, "rotate", 0, b->key_rotate + 3 * i)))
      return st;
  }
  return 0;
}

static int parse_obstacle(ctx *c, const cJSON *o, const char *where, bs_scene_obstacle *b) {
  int st;
  if ((st = check_keys(c, o, where, "obstacles[]"))) return st;
  bs__scene_obstacle_defaults(b);
  if ((st = get_section(c, o, where, "obstacles[]", b))) return st;
  return parse_obstacle_keys(c, o, where, b);
}

static int parse_self_collision(ctx *c, const cJSON *root, bs_scene *s) {
  int st;
  const cJSON *sc = cJSON_GetObjectItemCaseSensitive(root, "self_collision");
  if (!sc) return 0;
  if ((st = check_keys(c, sc, "self_collision", "self_collision"))) return st;
  s->self_collision = 1;
  return get_section(c, sc, "self_collision", "self_collision", s);
}

/* contact: dhat and kappa, each > 0 when given (absent: automatic, 0). */
static int parse_contact(ctx *c, const cJSON *root, bs_scene *s) {
  int st;
  const cJSON *o = cJSON_GetObjectItemCaseSensitive(root, "contact");
  if (!o) return 0;
  if ((st = check_keys(c, o, "contact", "contact")) || (st = get_section(c, o, "contact", "contact", s))) return st;
  if (cJSON_GetObjectItemCaseSensitive(o, "dhat") && !(s->contact_dhat > 0))
    return fail(c, "contact.dhat", "must be > 0 (m), got %g", s->contact_dhat);
  if (cJSON_GetObjectItemCaseSensitive(o, "kappa") && !(s->contact_kappa > 0))
    return fail(c, "contact.kappa", "must be > 0 (J/m^4), got %g", s->contact_kappa);
  return 0;
}

static int parse_time(ctx *c, const cJSON *root, bs_scene *s) {
  int st;
  const cJSON *t = cJSON_GetObjectItemCaseSensitive(root, "time");
  if (!t) return 0;
  if ((st = check_keys(c, t, "time", "time")) || (st = get_section(c, t, "time", "time", s))) return st;
  if (!(s->fps > 0)) return fail(c, "time.fps", "must be > 0, got %g", s->fps);
  double dt = 0;
  if ((st = get_num(c, t, "time", "dt", 0, &dt))) return st;
  if (cJSON_HasObjectItem(t, "dt")) {
    if (!(dt > 0)) return fail(c, "time.dt", "must be > 0, got %g", dt);
    if (cJSON_HasObjectItem(t, "steps_per_frame")) return fail(c, "time.dt", "give either dt or steps_per_frame, not both");
    double spf = 1.0 / (s->fps * dt);
    if (!(spf <= BS_SCENE_MAX_STEPS_PER_FRAME + 0.5))
      return fail(c, "time.dt", "%g s is %.3g steps per frame at %g fps, above the limit of %d", dt, spf, s->fps,
                  BS_SCENE_MAX_STEPS_PER_FRAME);
    if (fabs(spf - floor(spf + 0.5)) > 1e-9 * spf || floor(spf + 0.5) < 1)
      return fail(c, "time.dt", "1/(fps*dt) must be a whole number of steps per frame, got %g", spf);
    s->steps_per_frame = (int)floor(spf + 0.5);
  }
  return 0;
}

/* solver.cg_sigma ("auto" or a number) and solver.cg_sigma_scale. */
static int parse_sigma(ctx *c, const cJSON *so, bs_scene *s) {
  int st;
  char g[96];
  const cJSON *sg = cJSON_GetObjectItemCaseSensitive(so, "cg_sigma");
  const int has_scale = cJSON_GetObjectItemCaseSensitive(so, "cg_sigma_scale") != NULL;
  if (sg && !cJSON_IsNumber(sg) && !(cJSON_IsString(sg) && !strcmp(sg->valuestring, "auto")))
    return fail(c, "solver.cg_sigma", "must be a number > 0 or \"auto\", got %s", got(sg, g, sizeof g));
  if (cJSON_IsString(sg)) {
    s->solver.min.sigma_auto = 1;
  } else if (sg) {
    if (has_scale)
      return fail(c, "solver.cg_sigma_scale", "applies to cg_sigma \"auto\" only (cg_sigma is a number here)");
    if ((st = get_num(c, so, "solver", "cg_sigma", 0, &s->solver.min.sigma))) return st;
    s->solver.min.sigma_auto = 0;
  }
  if (has_scale) {
    if ((st = get_num(c, so, "solver", "cg_sigma_scale", 0, &s->solver.min.sigma))) return st;
  }
  return 0;
}

static int parse_solver(ctx *c, const cJSON *root, bs_scene *s) {
  int st;
  const cJSON *so = cJSON_GetObjectItemCaseSensitive(root, "solver");
  if (!so) return 0;
  if ((st = check_keys(c, so, "solver", "solver")) || (st = get_section(c, so, "solver", "solver", s))) return st;
  return parse_sigma(c, so, s);
}

static int parse_bodies(ctx *c, const cJSON *root, bs_scene *s) {
  int st;
  const cJSON *bodies;
  if ((st = get_array(c, root, "", "bodies", 1, &bodies))) return st;
  if (!bodies) return fail(c, "bodies", "missing (an array of at least one body is required)");
  s->n_bodies = cJSON_GetArraySize(bodies);
  s->bodies = calloc((size_t)s->n_bodies, sizeof(bs_scene_body));
  if (!s->bodies) return bs_error_set(c->err, BS_ENOMEM, "out of memory");
  for (int i = 0; i < s->n_bodies; i++) {
    char w[64];
    snprintf(w, sizeof w, "bodies.%d", i);
    if ((st = parse_body(c, cJSON_GetArrayItem(bodies, i), w, &s->bodies[i]))) return st;
  }
  return 0;
}

static int parse_obstacles(ctx *c, const cJSON *root, bs_scene *s) {
  int st;
  const cJSON *obs;
  if ((st = get_array(c, root, "", "obstacles", 0, &obs)) || !obs) return st;
  s->n_obstacles = cJSON_GetArraySize(obs);
  s->obstacles = calloc((size_t)(s->n_obstacles ? s->n_obstacles : 1), sizeof(bs_scene_obstacle));
  if (!s->obstacles) return bs_error_set(c->err, BS_ENOMEM, "out of memory");
  for (int i = 0; i < s->n_obstacles; i++) {
    char w[64];
    snprintf(w, sizeof w, "obstacles.%d", i);
    if ((st = parse_obstacle(c, cJSON_GetArrayItem(obs, i), w, &s->obstacles[i]))) return st;
  }
  return 0;
}

/* One quantity of interest: its keys, then the kind's own requirements. */
static int parse_one_qoi(ctx *c, const cJSON *o, const char *where, bs_scene *s) {
  int st;
  bs_scene_qoi q0 = {0}, *q;
  bs__scene_qoi_defaults(&q0);
  if ((st = check_keys(c, o, where, "qoi[]")) || (st = get_section(c, o, where, "qoi[]", &q0))) return st;
  for (int i = 0; i < s->n_qoi; i++)
    if (!strcmp(s->qoi[i].name, q0.name)) return fail(c, where, "name '%s' is used by qoi.%d too", q0.name, i);
  if ((st = bs_scene_add_qoi(s, q0.name, q0.kind, &q, c->err))) return st;
  *q = q0;
  q->has_at = cJSON_HasObjectItem(o, "at");
  int kinematic = q->kind <= BS_QOI_VELOCITY;
  if (kinematic && !!q->group[0] + q->has_at != 1) return fail(c, where, "give exactly one of \"group\" or \"at\"");
  if (q->kind == BS_QOI_REACTION && !q->group[0]) return fail(c, where, "a reaction needs the scripted \"group\"");
  return 0;
}

static int parse_qoi(ctx *c, const cJSON *root, bs_scene *s) {
  int st;
  const cJSON *arr;
  if ((st = get_array(c, root, "", "qoi", 0, &arr)) || !arr) return st;
  for (int i = 0; i < cJSON_GetArraySize(arr); i++) {
    char w[64];
    snprintf(w, sizeof w, "qoi.%d", i);
    if ((st = parse_one_qoi(c, cJSON_GetArrayItem(arr, i), w, s))) return st;
  }
  return 0;
}

static int parse_output(ctx *c, const cJSON *root, bs_scene *s) {
  int st;
  const cJSON *out = cJSON_GetObjectItemCaseSensitive(root, "output");
  if (!out) return 0;
  if ((st = check_keys(c, out, "output", "output")) || (st = get_section(c, out, "output", "output", s)) ||
      (st = bs__fields_parse_json(cJSON_GetObjectItemCaseSensitive(out, "fields"), c->file, &s->out_fields, c->err)))
    return st;
  return 0;
}

/* "$schema" (for editors) and "description" (kept in the scene). */
static int parse_notes(ctx *c, const cJSON *root, bs_scene *s) {
  char g[96];
  const cJSON *sch = cJSON_GetObjectItemCaseSensitive(root, "$schema");
  if (sch && !cJSON_IsString(sch)) return fail(c, "$schema", "must be a string, got %s", got(sch, g, sizeof g));
  const cJSON *desc = cJSON_GetObjectItemCaseSensitive(root, "description");
  if (!desc) return 0;
  if (!cJSON_IsString(desc)) return fail(c, "description", "must be a string, got %s", got(desc, g, sizeof g));
  free(s->description);
  s->description = strdup(desc->valuestring);
  return s->description ? 0 : bs_error_set(c->err, BS_ENOMEM, "out of memory");
}

static int parse_scene(ctx *c, const cJSON *root, bs_scene *s) {
  int st;
  if ((st = check_keys(c, root, "", "")) || (st = parse_notes(c, root, s)) || (st = parse_self_collision(c, root, s)) ||
      (st = parse_contact(c, root, s)))
    return st;
  if ((st = parse_time(c, root, s))) return st;
  s->dt = 1.0 / (s->fps * s->steps_per_frame);
  if ((st = parse_solver(c, root, s)) || (st = get_section(c, root, "", "", s)) || (st = parse_bodies(c, root, s)) ||
      (st = parse_obstacles(c, root, s)) || (st = parse_qoi(c, root, s)))
    return st;
  return parse_output(c, root, s);
}

/* ---- --set overrides ------------------------------------------------------ */

static int apply_set(ctx *c, cJSON *root, const char *set) {
  const char *eq = strchr(set, '=');
  if (!eq || eq == set) return bs_error_set(c->err, BS_EINPUT, "--set '%s': expected key.path=value", set);
  char path[512];
  snprintf(path, sizeof path, "%.*s", (int)(eq - set), set);
  const char *val = eq + 1;
  cJSON *v = cJSON_Parse(val);
  if (!v) v = cJSON_CreateString(val);
  if (!v) return bs_error_set(c->err, BS_ENOMEM, "out of memory");
  cJSON *node = root;
  char *save = NULL, *tok = strtok_r(path, ".", &save);
  while (tok) {
    char *next = strtok_r(NULL, ".", &save);
    char *end;
    long idx = strtol(tok, &end, 10);
    int is_index = (*end == '\0' && end != tok);
    if (cJSON_IsArray(node)) {
      if (!is_index || idx < 0 || idx >= cJSON_GetArraySize(node)) {
        cJSON_Delete(v);
        return bs_error_set(c->err, BS_EINPUT, "--set %.*s: '%s' is not an index of an array of %d elements",
                            (int)(eq - set), set, tok, cJSON_GetArraySize(node));
      }
      if (!next) {
        cJSON_ReplaceItemInArray(node, (int)idx, v);
        return 0;
      }
      node = cJSON_GetArrayItem(node, (int)idx);
    } else if (cJSON_IsObject(node)) {
      cJSON *child = cJSON_GetObjectItemCaseSensitive(node, tok);
      if (!next) {
        if (child) cJSON_ReplaceItemInObjectCaseSensitive(node, tok, v);
        else cJSON_AddItemToObject(node, tok, v);
        return 0;
      }
      if (!child) {
        child = cJSON_CreateObject();
        cJSON_AddItemToObject(node, tok, child);
      }
      node = child;
    } else {
      cJSON_Delete(v);
      return bs_error_set(c->err, BS_EINPUT, "--set %.*s: '%s' is inside a value that is neither an object nor an array",
                          (int)(eq - set), set, tok);
    }
    tok = next;
  }
  cJSON_Delete(v);
  return bs_error_set(c->err, BS_EINPUT, "--set '%s': empty key path", set);
}

/* ---- load ----------------------------------------------------------------- */

/* A relative path that does not open as given is tried against the scene's
 * folder; 0 when one of them opens (path updated), else -1. */
static int resolve(const char *scene, char *path, size_t n) {
  FILE *f = fopen(path, "rb");
  if (f) {
    fclose(f);
    return 0;
  }
  const char *slash = strrchr(scene, '/');
  if (!slash || path[0] == '/') return -1;
  char alt[2 * BS_MAX_PATH + 2];
  snprintf(alt, sizeof alt, "%.*s/%s", (int)(slash - scene), scene, path);
  f = fopen(alt, "rb");
  if (!f || strlen(alt) >= n) {
    if (f) fclose(f);
    return -1;
  }
  fclose(f);
  snprintf(path, n, "%s", alt);
  return 0;
}

static int resolve_files(bs_scene *s, bs_error *err) {
  for (int i = 0; i < s->n_obstacles; i++) {
    bs_scene_obstacle *o = &s->obstacles[i];
    if (o->grid_file[0] && resolve(s->path, o->grid_file, sizeof o->grid_file))
      return bs_error_set(err, BS_EIO, "%s: obstacles.%d.file: cannot open grid level-set file '%s'", s->path, i,
                          o->grid_file);
  }
  for (int i = 0; i < s->n_bodies; i++) {
    bs_scene_body *b = &s->bodies[i];
    if (strcmp(b->mesh, "box") && resolve(s->path, b->mesh, sizeof b->mesh))
      return bs_error_set(err, BS_EIO, "%s: bodies.%d.mesh: cannot open mesh file '%s'", s->path, i, b->mesh);
  }
  return 0;
}

/* "FILE: line L, column C: malformed JSON: expected X near '...'" at the
 * first character that cannot continue the text (json_locate.h; cJSON's own
 * position when that check finds nothing). Columns count characters, not
 * bytes, from 1. */
static int malformed(const char *text, const char *at, const char *name, bs_error *err) {
  size_t len = strlen(text);
  const char *what = NULL;
  if (!bs__json_locate(text, &at, &what) && (!at || at < text || at > text + len)) at = text + len;
  int line = 1, col = 1;
  for (const char *p = text; p < at; p++) {
    if (*p == '\n') line++, col = 1;
    else if (((unsigned char)*p & 0xC0) != 0x80) col++;
  }
  char expect[160] = "";
  if (what) snprintf(expect, sizeof expect, ": expected %s", what);
  if (!*at) return bs_error_set(err, BS_EINPUT, "%s: line %d, column %d: malformed JSON%s at the end of the text", name, line, col, expect);
  int n = 0;
  while (n < 24 && at[n] && at[n] != '\n' && at[n] != '\r') n++;
  while (n > 0 && ((unsigned char)at[n] & 0xC0) == 0x80) n--; /* whole characters */
  return bs_error_set(err, BS_EINPUT, "%s: line %d, column %d: malformed JSON%s, found '%.*s'", name, line, col, expect, n, at);
}

int bs_scene_parse(const char *text, const char *name, int n_sets, const char *const *sets, bs_scene **out,
                   bs_error *err) {
  *out = NULL;
  if (!name) name = "<scene>";
  const char *at = NULL;
  cJSON *root = cJSON_ParseWithOpts(text, &at, 1);
  if (!root) return malformed(text, at, name, err);
  ctx c = {name, err};
  int st = 0;
  for (int i = 0; i < n_sets && !st; i++) st = apply_set(&c, root, sets[i]);
  bs_scene *s = NULL;
  if (!st) st = bs_scene_create(&s, err);
  if (!st) {
    snprintf(s->path, sizeof s->path, "%s", name);
    st = parse_scene(&c, root, s);
  }
  cJSON_Delete(root);
  if (!st) st = bs_scene_check(s, err);
  if (!st) st = resolve_files(s, err);
  if (st) {
    bs_scene_destroy(&s);
    return st;
  }
  *out = s;
  return 0;
}

int bs_scene_load(const char *path, int n_sets, const char *const *sets, bs_scene **out, bs_error *err) {
  *out = NULL;
  struct stat sb;
  if (stat(path, &sb) == 0 && !S_ISREG(sb.st_mode))
    return bs_error_set(err, BS_EIO, "cannot read scene '%s': not a regular file", path);
  FILE *f = fopen(path, "rb");
  if (!f) return bs_error_set(err, BS_EIO, "cannot open scene '%s'", path);
  long n = fseek(f, 0, SEEK_END) == 0 ? ftell(f) : -1; /* a folder gives -1 or LONG_MAX */
  if (n < 0 || fseek(f, 0, SEEK_SET) != 0) {
    fclose(f);
    return bs_error_set(err, BS_EIO, "cannot read scene '%s' (not a regular file?)", path);
  }
  if (n > BS_MAX_SCENE_BYTES) {
    fclose(f);
    return bs_error_set(err, BS_EINPUT, "scene '%s': %ld bytes exceed bigstep's limit of %ld for a scene file", path, n,
                        (long)BS_MAX_SCENE_BYTES);
  }
  char *text = malloc((size_t)n + 1);
  if (!text) {
    fclose(f);
    return bs_error_set(err, BS_ENOMEM, "out of memory reading '%s'", path);
  }
  size_t got = fread(text, 1, (size_t)n, f);
  fclose(f);
  text[got] = '\0';
  if (strlen(text) != got) { /* the parser would stop there and drop the rest */
    size_t at = strlen(text);
    free(text);
    return bs_error_set(err, BS_EINPUT, "scene '%s': a NUL byte at offset %zu (not a JSON text file)", path, at);
  }
  int st = bs_scene_parse(text, path, n_sets, sets, out, err);
  free(text);
  return st;
}
