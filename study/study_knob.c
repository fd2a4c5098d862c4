/* study_knob.c — a study knob: "KEY=v1,v2,..." parsed into its kind, scene
 * key path, values and finest value (bs_study.h). */
#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bs_study.h"

static int valid_key(const char *k) {
  if (!*k || *k == '.') return 0;
  for (const char *p = k; *p; p++)
    if (!(isalnum((unsigned char)*p) || *p == '_' || *p == '.')) return 0;
  return k[strlen(k) - 1] != '.';
}

/* Copies a key (snprintf from a sibling field of the same struct trips -Wrestrict). */
static void copy_key(char *dst, size_t n, const char *src) {
  size_t l = strlen(src);
  if (l >= n) l = n - 1;
  memmove(dst, src, l);
  dst[l] = '\0';
}

/* The kind and scene key path of k->key (shorthands expanded). */
static void knob_kind(bs_study_knob *k) {
  static const struct {
    const char *a, *b, *path;
    bs_knob_kind kind;
  } named[] = {{"steps_per_frame", "time.steps_per_frame", "time.steps_per_frame", BS_KNOB_STEPS_PER_FRAME},
               {"tolerance", "solver.tolerance", "solver.tolerance", BS_KNOB_TOLERANCE},
               {"method", "solver.method", "solver.method", BS_KNOB_METHOD},
               {"refine", "refine", "", BS_KNOB_REFINE},
               {"element", "bodies.*.element", "bodies.*.element", BS_KNOB_OTHER},
               {"integrator", "solver.integrator", "solver.integrator", BS_KNOB_OTHER},
               {"time.dt", "time.dt", "time.dt", BS_KNOB_DT},
               {"time.fps", "time.fps", "time.fps", BS_KNOB_FPS}};
  k->body = -1;
  for (size_t i = 0; i < sizeof named / sizeof named[0]; i++)
    if (!strcmp(k->key, named[i].a) || !strcmp(k->key, named[i].b)) {
      k->kind = named[i].kind;
      snprintf(k->path, sizeof k->path, "%s", named[i].path);
      return;
    }
  int b, len = 0;
  k->kind = BS_KNOB_OTHER;
  if (sscanf(k->key, "bodies.%d.refine%n", &b, &len) == 1 && len == (int)strlen(k->key) && b >= 0) {
    k->kind = BS_KNOB_REFINE;
    k->body = b;
  }
  copy_key(k->path, sizeof k->path, k->key);
}

/* The comma-separated values after '=': none empty, none twice. */
static int knob_values(const char *spec, const char *list, bs_study_knob *k, bs_error *err) {
  int cap = 1;
  for (const char *p = list; *p; p++) cap += *p == ',';
  k->vals = calloc((size_t)cap, sizeof(char *));
  k->num = malloc(sizeof(double) * (size_t)cap);
  if (!k->vals || !k->num) return bs_error_set(err, BS_ENOMEM, "'%s': out of memory", spec);
  for (const char *p = list; k->n < cap;) {
    size_t len = strcspn(p, ",");
    if (len == 0) return bs_error_set(err, BS_EINPUT, "'%s': empty value in the list", spec);
    for (int j = 0; j < k->n; j++)
      if (strlen(k->vals[j]) == len && !strncmp(k->vals[j], p, len))
        return bs_error_set(err, BS_EINPUT, "'%s': value '%.*s' listed twice", spec, (int)len, p);
    if (!(k->vals[k->n] = malloc(len + 1))) return bs_error_set(err, BS_ENOMEM, "'%s': out of memory", spec);
    memcpy(k->vals[k->n], p, len);
    k->vals[k->n++][len] = 0;
    p += len + (p[len] == ',');
  }
  return 0;
}

/* The numbers of a numeric knob, and the index of its finest value. */
static int knob_finest(const char *spec, bs_study_knob *k, bs_error *err) {
  int numeric = k->kind != BS_KNOB_METHOD && k->kind != BS_KNOB_OTHER;
  for (int j = 0; j < k->n; j++) {
    k->num[j] = NAN;
    if (numeric && bs_parse_double(k->vals[j], &k->num[j]))
      return bs_error_set(err, BS_EINPUT, "'%s': '%s' is not a number", spec, k->vals[j]);
  }
  k->finest = k->n - 1;
  for (int j = 0; j < k->n; j++) {
    double d = k->num[j], f = k->num[k->finest];
    switch (k->kind) {
      case BS_KNOB_STEPS_PER_FRAME: case BS_KNOB_REFINE: case BS_KNOB_FPS:
        if (d > f) k->finest = j;
        break;
      case BS_KNOB_TOLERANCE: case BS_KNOB_DT:
        if (d < f) k->finest = j;
        break;
      default: break;
    }
  }
  if (k->kind == BS_KNOB_METHOD) {
    k->finest = 0;
    for (int j = 0; j < k->n; j++)
      if (!strcmp(k->vals[j], "optimization")) k->finest = j;
  }
  return 0;
}

int bs_study_knob_parse(const char *spec, bs_study_knob *k, bs_error *err) {
  memset(k, 0, sizeof *k);
  const char *eq = strchr(spec, '=');
  if (!eq || eq == spec || !eq[1]) return bs_error_set(err, BS_EINPUT, "'%s': expected KEY=v1,v2,...", spec);
  snprintf(k->key, sizeof k->key, "%.*s", (int)(eq - spec), spec);
  if (!valid_key(k->key)) return bs_error_set(err, BS_EINPUT, "'%s': '%s' is not a key path", spec, k->key);
  knob_kind(k);
  int st = knob_values(spec, eq + 1, k, err);
  if (!st) st = knob_finest(spec, k, err);
  if (st) bs_study_knob_free(k);
  return st;
}

void bs_study_knob_free(bs_study_knob *k) {
  for (int j = 0; k->vals && j < k->n; j++) free(k->vals[j]);
  free(k->vals);
  free(k->num);
  k->vals = NULL;
  k->num = NULL;
  k->n = 0;
}

int bs_study_knob_same(const bs_study_knob *a, const bs_study_knob *b) {
  return !strcmp(a->path, b->path) && !(b->kind == BS_KNOB_REFINE && b->body != a->body);
}

int bs_study_knob_is_time(const bs_study_knob *k) {
  return k->kind == BS_KNOB_STEPS_PER_FRAME || k->kind == BS_KNOB_DT || k->kind == BS_KNOB_FPS;
}
