/* scene.c — strict JSON scene parsing (cJSON): keys and types here, values in
 * scene_check.c (shared with scenes built in C). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cJSON.h>

#include "bs_scene.h"
#include "scene_internal.h"

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

#include <stdarg.h>
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

/* Every key of obj must be in allowed (NULL-terminated). */
static int check_keys(ctx *c, const cJSON *obj, const char *where, const char *const *allowed) {
  if (!cJSON_IsObject(obj)) return fail(c, where[0] ? where : "(top level)", "must be an object");
  for (const cJSON *it = obj->child; it; it = it->next) {
    int ok = 0;
    for (int i = 0; allowed[i]; i++)
      if (strcmp(it->string, allowed[i]) == 0) ok = 1;
    if (!ok) {
      char w[512], list[512] = "";
      join(w, sizeof w, where, it->string);
      for (int i = 0; allowed[i]; i++) {
        strncat(list, allowed[i], sizeof list - strlen(list) - 1);
        if (allowed[i + 1]) strncat(list, ", ", sizeof list - strlen(list) - 1);
      }
      return fail(c, w, "unknown key (allowed here: %s)", list);
    }
  }
  return 0;
}

static int get_num(ctx *c, const cJSON *obj, const char *where, const char *key, int required, double *out) {
  const cJSON *it = cJSON_GetObjectItemCaseSensitive(obj, key);
  char w[512];
  join(w, sizeof w, where, key);
  if (!it) return required ? fail(c, w, "missing (a number is required)") : 0;
  if (!cJSON_IsNumber(it)) return fail(c, w, "must be a number");
  if (!isfinite(it->valuedouble)) return fail(c, w, "must be finite, got %g", it->valuedouble);
  *out = it->valuedouble;
  return 0;
}

static int get_int(ctx *c, const cJSON *obj, const char *where, const char *key, int required, long lo, long hi,
                   int *out) {
  double v = *out;
  char w[512];
  join(w, sizeof w, where, key);
  if (!cJSON_GetObjectItemCaseSensitive(obj, key) && !required) return 0;
  int st = get_num(c, obj, where, key, required, &v);
  if (st) return st;
  if (v != floor(v) || v < lo || v > hi) return fail(c, w, "must be an integer in [%ld, %ld], got %g", lo, hi, v);
  *out = (int)v;
  return 0;
}

static int get_str(ctx *c, const cJSON *obj, const char *where, const char *key, int required, char *out,
                   size_t n) {
  const cJSON *it = cJSON_GetObjectItemCaseSensitive(obj, key);
  char w[512];
  join(w, sizeof w, where, key);
  if (!it) return required ? fail(c, w, "missing (a string is required)") : 0;
  if (!cJSON_IsString(it)) return fail(c, w, "must be a string");
  if (strlen(it->valuestring) >= n) return fail(c, w, "string too long");
  snprintf(out, n, "%s", it->valuestring);
  return 0;
}

/* An optional string key with two allowed values: *out = 0 for a, 1 for b;
 * untouched when the key is absent. */
static int get_choice(ctx *c, const cJSON *obj, const char *where, const char *key, const char *a, const char *b,
                      int *out) {
  char buf[64] = "", w[512];
  int st = get_str(c, obj, where, key, 0, buf, sizeof buf);
  if (st || !buf[0]) return st;
  if (!strcmp(buf, a)) *out = 0;
  else if (!strcmp(buf, b)) *out = 1;
  else {
    join(w, sizeof w, where, key);
    return fail(c, w, "must be \"%s\" or \"%s\", got \"%s\"", a, b, buf);
  }
  return 0;
}

static int get_bool(ctx *c, const cJSON *obj, const char *where, const char *key, int *out) {
  const cJSON *it = cJSON_GetObjectItemCaseSensitive(obj, key);
  char w[512];
  join(w, sizeof w, where, key);
  if (!it) return 0;
  if (!cJSON_IsBool(it)) return fail(c, w, "must be true or false");
  *out = cJSON_IsTrue(it);
  return 0;
}

static int get_vec3(ctx *c, const cJSON *obj, const char *where, const char *key, int required, double out[3]) {
  const cJSON *it = cJSON_GetObjectItemCaseSensitive(obj, key);
  char w[512];
  join(w, sizeof w, where, key);
  if (!it) return required ? fail(c, w, "missing (an array of 3 numbers is required)") : 0;
  if (!cJSON_IsArray(it) || cJSON_GetArraySize(it) != 3) return fail(c, w, "must be an array of 3 numbers");
  for (int k = 0; k < 3; k++) {
    const cJSON *e = cJSON_GetArrayItem(it, k);
    if (!cJSON_IsNumber(e) || !isfinite(e->valuedouble)) return fail(c, w, "element %d must be a finite number", k);
    out[k] = e->valuedouble;
  }
  return 0;
}

/* ---- sections ------------------------------------------------------------ */

static int parse_material(ctx *c, const cJSON *o, const char *where, bs_scene_material *m) {
  static const char *const keys[] = {"model", "youngs", "poisson", "density", "rayleigh", NULL};
  int st;
  if ((st = check_keys(c, o, where, keys))) return st;
  char model[64] = "fixed_corotated";
  if ((st = get_str(c, o, where, "model", 0, model, sizeof model))) return st;
  bs_error e2;
  if (bs_model_parse(model, &m->model, &e2)) {
    char w[512];
    join(w, sizeof w, where, "model");
    return fail(c, w, "%s", e2.msg);
  }
  m->rayleigh = 0;
  if ((st = get_num(c, o, where, "youngs", 1, &m->youngs)) || (st = get_num(c, o, where, "poisson", 1, &m->poisson)) ||
      (st = get_num(c, o, where, "density", 1, &m->density)) || (st = get_num(c, o, where, "rayleigh", 0, &m->rayleigh)))
    return st;
  return 0;
}

static int parse_script(ctx *c, const cJSON *o, const char *where, bs_scene_script *s) {
  static const char *const keys[] = {"group", "velocity", "fixed", "keyframes", NULL};
  int st;
  if ((st = check_keys(c, o, where, keys))) return st;
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
    const cJSON *arr = cJSON_GetObjectItemCaseSensitive(o, "keyframes");
    if (!cJSON_IsArray(arr) || cJSON_GetArraySize(arr) < 1) return fail(c, w, "must be a non-empty array");
    s->n_keys = cJSON_GetArraySize(arr);
    s->key_t = calloc((size_t)s->n_keys, sizeof(double));
    s->key_offset = calloc(3 * (size_t)s->n_keys, sizeof(double));
    if (!s->key_t || !s->key_offset) return bs_error_set(c->err, BS_ENOMEM, "out of memory reading %s", w);
    for (int i = 0; i < s->n_keys; i++) {
      char wi[600];
      snprintf(wi, sizeof wi, "%s.%d", w, i);
      const cJSON *k = cJSON_GetArrayItem(arr, i);
      static const char *const kk[] = {"t", "offset", NULL};
      if ((st = check_keys(c, k, wi, kk)) || (st = get_num(c, k, wi, "t", 1, &s->key_t[i])) ||
          (st = get_vec3(c, k, wi, "offset", 1, s->key_offset + 3 * i)))
        return st;
    }
  }
  return 0;
}

/* "material" (the default, required) and "materials": {group: {...}}. */
static int parse_body_materials(ctx *c, const cJSON *o, const char *where, bs_scene_body *b) {
  int st;
  char w[512];
  const cJSON *mats = cJSON_GetObjectItemCaseSensitive(o, "materials");
  int nm = 1 + (mats ? cJSON_GetArraySize(mats) : 0);
  b->materials = calloc((size_t)nm, sizeof(bs_scene_material));
  if (!b->materials) return bs_error_set(c->err, BS_ENOMEM, "out of memory");
  b->n_materials = nm;
  for (int i = 0; i < nm; i++) bs_scene_material_defaults_(&b->materials[i]);
  const cJSON *mat = cJSON_GetObjectItemCaseSensitive(o, "material");
  join(w, sizeof w, where, "material");
  if (!mat) return fail(c, w, "missing (an object with model, youngs, poisson, density is required)");
  if ((st = parse_material(c, mat, w, &b->materials[0]))) return st;
  if (mats) {
    join(w, sizeof w, where, "materials");
    if (!cJSON_IsObject(mats)) return fail(c, w, "must be an object {group name: material}");
    int i = 1;
    for (const cJSON *it = mats->child; it; it = it->next, i++) {
      char wi[600];
      snprintf(wi, sizeof wi, "%s.%s", w, it->string);
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
  if (is) {
    join(w, sizeof w, where, "initial_state");
    static const char *const ik[] = {"type", "lo", "hi", "point", "seed", NULL};
    if ((st = check_keys(c, is, w, ik))) return st;
    char type[32];
    if ((st = get_str(c, is, w, "type", 1, type, sizeof type))) return st;
    int seed = 1;
    if ((st = get_int(c, is, w, "seed", 0, 0, 2147483647L, &seed))) return st;
    b->init_seed = (unsigned)seed;
    if (!strcmp(type, "rest")) b->init = BS_INIT_REST;
    else if (!strcmp(type, "random")) {
      b->init = BS_INIT_RANDOM;
      if ((st = get_vec3(c, is, w, "lo", 1, b->init_lo)) || (st = get_vec3(c, is, w, "hi", 1, b->init_hi))) return st;
    } else if (!strcmp(type, "point")) {
      b->init = BS_INIT_POINT;
      if ((st = get_vec3(c, is, w, "point", 0, b->init_lo))) return st;
    } else {
      char wt[600];
      snprintf(wt, sizeof wt, "%s.type", w);
      return fail(c, wt, "must be \"rest\", \"random\" or \"point\", got \"%s\"", type);
    }
  }
  return 0;
}

/* "scripted": [{group, velocity | keyframes | fixed}]. */
static int parse_body_scripts(ctx *c, const cJSON *o, const char *where, bs_scene_body *b) {
  int st;
  char w[512];
  const cJSON *scr = cJSON_GetObjectItemCaseSensitive(o, "scripted");
  if (scr) {
    join(w, sizeof w, where, "scripted");
    if (!cJSON_IsArray(scr)) return fail(c, w, "must be an array");
    b->n_scripts = cJSON_GetArraySize(scr);
    b->scripts = calloc((size_t)(b->n_scripts ? b->n_scripts : 1), sizeof(bs_scene_script));
    if (!b->scripts) return bs_error_set(c->err, BS_ENOMEM, "out of memory");
    for (int i = 0; i < b->n_scripts; i++) {
      char wi[600];
      snprintf(wi, sizeof wi, "%s.%d", w, i);
      if ((st = parse_script(c, cJSON_GetArrayItem(scr, i), wi, &b->scripts[i]))) return st;
    }
  }
  return 0;
}

static int parse_body(ctx *c, const cJSON *o, const char *where, bs_scene_body *b) {
  static const char *const keys[] = {"mesh", "box", "mesh_size", "refine", "reorder", "translate", "rotate", "scale",
                                     "material", "materials", "velocity", "angular_velocity", "initial_state",
                                     "scripted", NULL};
  int st;
  if ((st = check_keys(c, o, where, keys))) return st;
  if ((st = get_str(c, o, where, "mesh", 1, b->mesh, sizeof b->mesh))) return st;
  char w[512];
  bs_scene_body_defaults_(b);
  const cJSON *box = cJSON_GetObjectItemCaseSensitive(o, "box");
  join(w, sizeof w, where, "box");
  if (strcmp(b->mesh, "box") == 0) {
    if (!box) return fail(c, w, "missing: \"mesh\": \"box\" needs \"box\": {\"cells\": [nx, ny, nz], \"size\": [lx, ly, lz]}");
    static const char *const bk[] = {"cells", "size", NULL};
    if ((st = check_keys(c, box, w, bk))) return st;
    double cells[3];
    if ((st = get_vec3(c, box, w, "cells", 1, cells)) || (st = get_vec3(c, box, w, "size", 0, b->box_size))) return st;
    for (int k = 0; k < 3; k++) {
      if (cells[k] != floor(cells[k]) || cells[k] < 1 || cells[k] > 4096) return fail(c, w, "cells must be integers in [1, 4096]");
      b->box_cells[k] = (int)cells[k];
    }
  } else if (box) {
    return fail(c, w, "only allowed with \"mesh\": \"box\"");
  }
  if ((st = get_num(c, o, where, "mesh_size", 0, &b->mesh_size))) return st;
  if ((st = get_int(c, o, where, "refine", 0, 0, 6, &b->refine))) return st;
  char reorder[32] = "none";
  if ((st = get_str(c, o, where, "reorder", 0, reorder, sizeof reorder))) return st;
  if (!strcmp(reorder, "none")) b->reorder = BS_ORDER_NONE;
  else if (!strcmp(reorder, "metis")) b->reorder = BS_ORDER_METIS;
  else if (!strcmp(reorder, "rcm")) b->reorder = BS_ORDER_RCM;
  else {
    join(w, sizeof w, where, "reorder");
    return fail(c, w, "must be \"none\", \"metis\" or \"rcm\", got \"%s\"", reorder);
  }
  const cJSON *sc = cJSON_GetObjectItemCaseSensitive(o, "scale");
  if (cJSON_IsNumber(sc)) b->scale[0] = b->scale[1] = b->scale[2] = sc->valuedouble;
  else if ((st = get_vec3(c, o, where, "scale", 0, b->scale))) return st;
  if ((st = get_vec3(c, o, where, "translate", 0, b->translate)) || (st = get_vec3(c, o, where, "rotate", 0, b->rotate)) ||
      (st = get_vec3(c, o, where, "velocity", 0, b->velocity)) ||
      (st = get_vec3(c, o, where, "angular_velocity", 0, b->angular_velocity)))
    return st;

  if ((st = parse_body_materials(c, o, where, b)) || (st = parse_body_init(c, o, where, b))) return st;
  return parse_body_scripts(c, o, where, b);
}

/* An optional string key parsed by `parse` into an enum (untouched when absent). */
static int get_enum(ctx *c, const cJSON *obj, const char *where, const char *key, int required,
                    int (*parse)(const char *, int *, bs_error *), int *out) {
  char buf[64] = "", w[512];
  int st = get_str(c, obj, where, key, required, buf, sizeof buf);
  if (st || !buf[0]) return st;
  bs_error e2;
  if (parse(buf, out, &e2)) {
    join(w, sizeof w, where, key);
    return fail(c, w, "%s", e2.msg);
  }
  return 0;
}

static int parse_shape(const char *name, int *out, bs_error *err) {
  bs_shape s;
  int st = bs_shape_parse(name, &s, err);
  *out = (int)s;
  return st;
}

static int parse_collide(const char *name, int *out, bs_error *err) {
  bs_collide_mode m;
  if (bs_collide_mode_parse(name, &m, err))
    return bs_error_set(err, BS_EINPUT, "must be constraint, penalty or postprocess, got \"%s\"", name);
  *out = (int)m;
  return 0;
}

static int parse_obstacle_keys(ctx *c, const cJSON *o, const char *where, bs_scene_obstacle *b) {
  const cJSON *keysj = cJSON_GetObjectItemCaseSensitive(o, "keyframes");
  if (!keysj) return 0;
  char w[512];
  int st;
  join(w, sizeof w, where, "keyframes");
  if (!cJSON_IsArray(keysj) || cJSON_GetArraySize(keysj) < 1) return fail(c, w, "must be a non-empty array");
  b->n_keys = cJSON_GetArraySize(keysj);
  b->key_t = calloc((size_t)b->n_keys, sizeof(double));
  b->key_translate = calloc(3 * (size_t)b->n_keys, sizeof(double));
  b->key_rotate = calloc(3 * (size_t)b->n_keys, sizeof(double));
  if (!b->key_t || !b->key_translate || !b->key_rotate) return bs_error_set(c->err, BS_ENOMEM, "out of memory");
  for (int i = 0; i < b->n_keys; i++) {
    char wi[600];
    snprintf(wi, sizeof wi, "%s.%d", w, i);
    const cJSON *k = cJSON_GetArrayItem(keysj, i);
    static const char *const kk[] = {"t", "translate", "rotate", NULL};
    if ((st = check_keys(c, k, wi, kk)) || (st = get_num(c, k, wi, "t", 1, &b->key_t[i])) ||
        (st = get_vec3(c, k, wi, "translate", 0, b->key_translate + 3 * i)) ||
        (st = get_vec3(c, k, wi, "rotate", 0, b->key_rotate + 3 * i)))
      return st;
  }
  return 0;
}

static int parse_obstacle(ctx *c, const cJSON *o, const char *where, bs_scene_obstacle *b) {
  static const char *const keys[] = {"shape", "normal", "offset", "center", "radius", "half_extents", "axis",
                                     "half_height", "major", "minor", "inside_out", "file", "grid_h", "collision",
                                     "stiffness", "friction", "velocity", "angular_velocity", "keyframes", NULL};
  int st, shape = 0, collision = BS_COLLIDE_CONSTRAINT;
  if ((st = check_keys(c, o, where, keys))) return st;
  bs_scene_obstacle_defaults_(b);
  if ((st = get_enum(c, o, where, "shape", 1, parse_shape, &shape))) return st;
  b->shape = (bs_shape)shape;
  if ((st = get_vec3(c, o, where, "normal", 0, b->normal)) || (st = get_num(c, o, where, "offset", 0, &b->offset)) ||
      (st = get_vec3(c, o, where, "center", 0, b->center)) || (st = get_num(c, o, where, "radius", 0, &b->radius)) ||
      (st = get_vec3(c, o, where, "half_extents", 0, b->half_extents)) ||
      (st = get_vec3(c, o, where, "axis", 0, b->axis)) ||
      (st = get_num(c, o, where, "half_height", 0, &b->half_height)) ||
      (st = get_num(c, o, where, "major", 0, &b->major)) || (st = get_num(c, o, where, "minor", 0, &b->minor)) ||
      (st = get_bool(c, o, where, "inside_out", &b->inside_out)) ||
      (st = get_str(c, o, where, "file", 0, b->grid_file, sizeof b->grid_file)) ||
      (st = get_num(c, o, where, "grid_h", 0, &b->grid_h)) ||
      (st = get_enum(c, o, where, "collision", 0, parse_collide, &collision)) ||
      (st = get_num(c, o, where, "stiffness", 0, &b->stiffness)) ||
      (st = get_num(c, o, where, "friction", 0, &b->friction)) ||
      (st = get_vec3(c, o, where, "velocity", 0, b->velocity)) ||
      (st = get_vec3(c, o, where, "angular_velocity", 0, b->angular_velocity)))
    return st;
  b->collision = (bs_collide_mode)collision;
  return parse_obstacle_keys(c, o, where, b);
}

static int parse_self_collision(ctx *c, const cJSON *root, bs_scene *s) {
  int st;
  const cJSON *sc = cJSON_GetObjectItemCaseSensitive(root, "self_collision");
  if (sc) {
    static const char *const sk[] = {"stiffness", "friction", NULL};
    if ((st = check_keys(c, sc, "self_collision", sk))) return st;
    s->self_collision = 1;
    s->self_stiffness = 1e5;
    s->self_friction = 0;
    if ((st = get_num(c, sc, "self_collision", "stiffness", 0, &s->self_stiffness)) ||
        (st = get_num(c, sc, "self_collision", "friction", 0, &s->self_friction)))
      return st;
  }
  return 0;
}

static int parse_time(ctx *c, const cJSON *root, bs_scene *s) {
  int st;
  const cJSON *t = cJSON_GetObjectItemCaseSensitive(root, "time");
  if (t) {
    static const char *const tk[] = {"fps", "frames", "steps_per_frame", "dt", NULL};
    if ((st = check_keys(c, t, "time", tk)) || (st = get_num(c, t, "time", "fps", 0, &s->fps)) ||
        (st = get_int(c, t, "time", "frames", 0, 0, 10000000, &s->frames)) ||
        (st = get_int(c, t, "time", "steps_per_frame", 0, 1, 1000000, &s->steps_per_frame)))
      return st;
    if (!(s->fps > 0)) return fail(c, "time.fps", "must be > 0, got %g", s->fps);
    double dt = 0;
    if ((st = get_num(c, t, "time", "dt", 0, &dt))) return st;
    if (cJSON_HasObjectItem(t, "dt")) {
      if (!(dt > 0)) return fail(c, "time.dt", "must be > 0, got %g", dt);
      if (cJSON_HasObjectItem(t, "steps_per_frame")) return fail(c, "time.dt", "give either dt or steps_per_frame, not both");
      double spf = 1.0 / (s->fps * dt);
      if (fabs(spf - floor(spf + 0.5)) > 1e-9 * spf || floor(spf + 0.5) < 1)
        return fail(c, "time.dt", "1/(fps*dt) must be a whole number of steps per frame, got %g", spf);
      s->steps_per_frame = (int)floor(spf + 0.5);
    }
  }
  return 0;
}

/* solver.cg_sigma ("auto" or a number) and solver.cg_sigma_scale. */
static int parse_sigma(ctx *c, const cJSON *so, bs_scene *s) {
  int st;
  const cJSON *sg = cJSON_GetObjectItemCaseSensitive(so, "cg_sigma");
  const int has_scale = cJSON_GetObjectItemCaseSensitive(so, "cg_sigma_scale") != NULL;
  if (cJSON_IsString(sg)) {
    if (strcmp(sg->valuestring, "auto") != 0)
      return fail(c, "solver.cg_sigma", "must be a number > 0 or \"auto\", got \"%s\"", sg->valuestring);
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
  if (so) {
    static const char *const sk[] = {"method", "linear", "tolerance", "max_iterations", "cg_max_iterations",
                                     "newton_k", "mode", "load_steps", "project_hessian", "cg_sigma",
                                     "amg_matrix", "amg_rebuild_factor", "amg_rebuild_every", "cg_precision",
                                     "cg_sigma_scale", "cg_downhill", "cg_forcing", NULL};
    if ((st = check_keys(c, so, "solver", sk))) return st;
    char buf[64];
    bs_error e2;
    buf[0] = 0;
    if ((st = get_str(c, so, "solver", "method", 0, buf, sizeof buf))) return st;
    if (buf[0] && bs_method_parse(buf, &s->solver.method, &e2)) return fail(c, "solver.method", "%s", e2.msg);
    buf[0] = 0;
    if ((st = get_str(c, so, "solver", "linear", 0, buf, sizeof buf))) return st;
    if (buf[0] && (bs_lin_kind_parse(buf, &s->solver.min.linear, &e2) || s->solver.min.linear == BS_LIN_MINRES))
      return fail(c, "solver.linear", "must be \"cg\", \"pcg\", \"amg\" or \"cholmod\", got \"%s\"", buf);
    int current = !s->solver.amg_at_rest;
    if ((st = get_choice(c, so, "solver", "cg_precision", "double", "single", &s->solver.min.cg_single)) ||
        (st = get_choice(c, so, "solver", "amg_matrix", "rest", "current", &current)))
      return st;
    s->solver.amg_at_rest = !current;
    if ((st = get_num(c, so, "solver", "amg_rebuild_factor", 0, &s->solver.min.amg_rebuild_factor))) return st;
    if ((st = get_int(c, so, "solver", "amg_rebuild_every", 0, 0, 100000000, &s->solver.min.amg_rebuild_every)))
      return st;
    if ((st = get_num(c, so, "solver", "tolerance", 0, &s->solver.min.tol))) return st;
    if ((st = parse_sigma(c, so, s))) return st;
    if ((st = get_bool(c, so, "solver", "cg_downhill", &s->solver.min.cg_downhill))) return st;
    if ((st = get_choice(c, so, "solver", "cg_forcing", "paper", "eisenstat_walker", &s->solver.min.forcing_ew)))
      return st;
    if ((st = get_int(c, so, "solver", "max_iterations", 0, 1, 100000000, &s->solver.min.max_iter)) ||
        (st = get_int(c, so, "solver", "cg_max_iterations", 0, 1, 100000000, &s->solver.min.cg_max_iter)) ||
        (st = get_int(c, so, "solver", "newton_k", 0, 1, 1000000, &s->solver.newton_k)) ||
        (st = get_int(c, so, "solver", "load_steps", 0, 1, 100000, &s->load_steps)) ||
        (st = get_bool(c, so, "solver", "project_hessian", &s->project_hessian)))
      return st;
    int stat = s->mode == BS_MODE_STATIC;
    if ((st = get_choice(c, so, "solver", "mode", "dynamic", "static", &stat))) return st;
    s->mode = stat ? BS_MODE_STATIC : BS_MODE_DYNAMIC;
  }
  return 0;
}

static int parse_bodies(ctx *c, const cJSON *root, bs_scene *s) {
  int st;
  const cJSON *bodies = cJSON_GetObjectItemCaseSensitive(root, "bodies");
  if (!bodies) return fail(c, "bodies", "missing (an array of at least one body is required)");
  if (!cJSON_IsArray(bodies) || cJSON_GetArraySize(bodies) < 1) return fail(c, "bodies", "must be a non-empty array");
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
  const cJSON *obs = cJSON_GetObjectItemCaseSensitive(root, "obstacles");
  if (obs) {
    if (!cJSON_IsArray(obs)) return fail(c, "obstacles", "must be an array");
    s->n_obstacles = cJSON_GetArraySize(obs);
    s->obstacles = calloc((size_t)(s->n_obstacles ? s->n_obstacles : 1), sizeof(bs_scene_obstacle));
    if (!s->obstacles) return bs_error_set(c->err, BS_ENOMEM, "out of memory");
    for (int i = 0; i < s->n_obstacles; i++) {
      char w[64];
      snprintf(w, sizeof w, "obstacles.%d", i);
      if ((st = parse_obstacle(c, cJSON_GetArrayItem(obs, i), w, &s->obstacles[i]))) return st;
    }
  }
  return 0;
}

static int parse_output(ctx *c, const cJSON *root, bs_scene *s) {
  int st;
  const cJSON *out = cJSON_GetObjectItemCaseSensitive(root, "output");
  if (out) {
    static const char *const ok[] = {"dir", "vtu_every", "stats", "states", NULL};
    if ((st = check_keys(c, out, "output", ok)) || (st = get_str(c, out, "output", "dir", 0, s->out_dir, sizeof s->out_dir)) ||
        (st = get_int(c, out, "output", "vtu_every", 0, 0, 1000000, &s->vtu_every)) ||
        (st = get_bool(c, out, "output", "stats", &s->stats_csv)) ||
        (st = get_bool(c, out, "output", "states", &s->states)))
      return st;
  }
  return 0;
}

static int parse_scene(ctx *c, const cJSON *root, bs_scene *s) {
  static const char *const keys[] = {"time", "solver", "gravity", "drag", "bodies", "output", "obstacles",
                                     "self_collision", "description", NULL};
  int st;
  if ((st = check_keys(c, root, "", keys)) || (st = parse_self_collision(c, root, s))) return st;
  const cJSON *desc = cJSON_GetObjectItemCaseSensitive(root, "description");
  if (desc && !cJSON_IsString(desc)) return fail(c, "description", "must be a string");

  if ((st = parse_time(c, root, s))) return st;
  s->dt = 1.0 / (s->fps * s->steps_per_frame);
  if ((st = parse_solver(c, root, s)) || (st = get_vec3(c, root, "", "gravity", 0, s->gravity)) ||
      (st = get_num(c, root, "", "drag", 0, &s->drag)) || (st = parse_bodies(c, root, s)) ||
      (st = parse_obstacles(c, root, s)))
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

int bs_scene_parse(const char *text, const char *name, int n_sets, const char *const *sets, bs_scene **out,
                   bs_error *err) {
  *out = NULL;
  if (!name) name = "<scene>";
  cJSON *root = cJSON_ParseWithOpts(text, NULL, 1);
  if (!root) {
    const char *at = cJSON_GetErrorPtr();
    int line = 1;
    if (at)
      for (const char *p = text; p < at && *p; p++) line += (*p == '\n');
    return bs_error_set(err, BS_EINPUT, "%s: line %d: malformed JSON", name, line);
  }
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
  FILE *f = fopen(path, "rb");
  if (!f) return bs_error_set(err, BS_EIO, "cannot open scene '%s'", path);
  fseek(f, 0, SEEK_END);
  long n = ftell(f);
  fseek(f, 0, SEEK_SET);
  if (n < 0) {
    fclose(f);
    return bs_error_set(err, BS_EIO, "cannot read scene '%s'", path);
  }
  char *text = malloc((size_t)n + 1);
  if (!text) {
    fclose(f);
    return bs_error_set(err, BS_ENOMEM, "out of memory reading '%s'", path);
  }
  size_t got = fread(text, 1, (size_t)n, f);
  fclose(f);
  text[got] = '\0';
  int st = bs_scene_parse(text, path, n_sets, sets, out, err);
  free(text);
  return st;
}
