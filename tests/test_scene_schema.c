/* The scene schema table (scene/scene_schema.c) against everything that must
 * agree with it: the published JSON Schema (data/scene.schema.json, byte for
 * byte), the loader (types, ranges, required keys, allowed strings, each
 * tried key by key on a scene that holds every section), the defaults of
 * scenes (a resolved minimal scene), and the shipped scenes (each loads).
 * The resolved scene (bs_scene_write_json): load -> write -> parse -> write
 * gives the same text for every shipped scene, and the same struct for a
 * scene built in C. */
#define _POSIX_C_SOURCE 200809L
#include <cJSON.h>
#include <criterion/criterion.h>
#include <glob.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "bs_scene.h"
#include "cli_util.h"
#include "scene_full.h"
#include "scene_schema.h"

static char *read_text(const char *path) {
  FILE *f = fopen(path, "rb");
  cr_assert_not_null(f, "cannot open %s", path);
  fseek(f, 0, SEEK_END);
  long n = ftell(f);
  fseek(f, 0, SEEK_SET);
  char *t = malloc((size_t)n + 1);
  cr_assert_not_null(t);
  cr_assert_eq(fread(t, 1, (size_t)n, f), (size_t)n);
  t[n] = '\0';
  fclose(f);
  return t;
}

static int is_section(const char *name) {
  for (int i = 0; i < bs__schema_n_sections; i++)
    if (!strcmp(bs__schema_sections[i].name, name)) return 1;
  return 0;
}

/* ---- the table and the published file ------------------------------------ */

Test(scene_schema, published_file_is_generated_from_the_table) {
  char *text = NULL;
  bs_error err;
  cr_assert_eq(bs_scene_schema_json(&text, &err), 0, "%s", err.msg);
  char *file = read_text(BS_SOURCE_DIR "/data/scene.schema.json");
  cr_expect(strcmp(text, file) == 0,
            "data/scene.schema.json is not the table's schema: regenerate it with "
            "`bigstep schema -o data/scene.schema.json`");
  cJSON *j = cJSON_Parse(text);
  cr_expect_not_null(j, "the schema is not JSON");
  cr_expect_str_eq(cJSON_GetObjectItem(j, "$schema")->valuestring, "http://json-schema.org/draft-07/schema#");
  cJSON_Delete(j);
  free(file);
  free(text);
}

/* `bigstep schema` prints the same text, and -o writes it. */
Test(scene_schema, command_prints_the_published_file) {
  char *out, *file = read_text(BS_SOURCE_DIR "/data/scene.schema.json");
  cr_expect_eq(bs_test_run(BS_BIGSTEP_EXE " schema", &out), 0, "%s", out);
  cr_expect(strcmp(out, file) == 0, "`bigstep schema` differs from data/scene.schema.json");
  free(out);
  cr_expect_eq(bs_test_run(BS_BIGSTEP_EXE " schema -o /tmp/bs_test_scene.schema.json", &out), 0, "%s", out);
  free(out);
  char *written = read_text("/tmp/bs_test_scene.schema.json");
  cr_expect(strcmp(written, file) == 0, "`bigstep schema -o` differs from data/scene.schema.json");
  unlink("/tmp/bs_test_scene.schema.json");
  cr_expect_eq(bs_test_run(BS_BIGSTEP_EXE " schema --bogus", &out), 2, "%s", out);
  cr_expect(strstr(out, "bigstep schema: unexpected argument '--bogus'") != NULL, "%s", out);
  free(out);
  free(written);
  free(file);
}

/* A default fits its key's type, range and choices. */
static void expect_default_fits(const bs_schema_key *k) {
  cJSON *d = cJSON_Parse(k->def);
  cr_assert_not_null(d, "%s.%s: default %s is not JSON", k->section, k->key, k->def);
  bs_schema_range r;
  int ranged = bs__schema_range(k, &r);
  switch (k->type) {
  case BS_SCHEMA_NUMBER:
  case BS_SCHEMA_INTEGER:
    cr_expect(cJSON_IsNumber(d) && (!ranged || bs__schema_in_range(&r, d->valuedouble)), "%s.%s: default %s",
              k->section, k->key, k->def);
    break;
  case BS_SCHEMA_STRING:
    cr_expect(cJSON_IsString(d) && (!k->choices || bs__schema_choice(k, d->valuestring) >= 0), "%s.%s: default %s",
              k->section, k->key, k->def);
    break;
  case BS_SCHEMA_BOOLEAN: cr_expect(cJSON_IsBool(d), "%s.%s: default %s", k->section, k->key, k->def); break;
  case BS_SCHEMA_VEC3:
  case BS_SCHEMA_NUM_OR_VEC3:
    cr_expect(cJSON_IsArray(d) && cJSON_GetArraySize(d) == 3, "%s.%s: default %s", k->section, k->key, k->def);
    for (int i = 0; ranged && i < cJSON_GetArraySize(d); i++)
      cr_expect(bs__schema_in_range(&r, cJSON_GetArrayItem(d, i)->valuedouble), "%s.%s", k->section, k->key);
    break;
  case BS_SCHEMA_NUM_OR_CHOICE:
    cr_expect(cJSON_IsNumber(d) || bs__schema_choice(k, d->valuestring) >= 0, "%s.%s", k->section, k->key);
    break;
  case BS_SCHEMA_STRINGS:
    cr_expect(cJSON_IsArray(d), "%s.%s: default %s", k->section, k->key, k->def);
    for (const cJSON *e = d->child; e; e = e->next)
      cr_expect(cJSON_IsString(e) && (!k->choices || bs__schema_choice(k, e->valuestring) >= 0), "%s.%s: default %s",
                k->section, k->key, k->def);
    break;
  default: cr_expect(0, "%s.%s: a default on an object or array key", k->section, k->key);
  }
  cJSON_Delete(d);
}

Test(scene_schema, table_is_consistent) {
  for (int i = 0; i < bs__schema_n_keys; i++) {
    const bs_schema_key *k = &bs__schema_keys[i];
    cr_expect(is_section(k->section), "%s.%s: section not in the sections list", k->section, k->key);
    cr_expect(k->doc && k->doc[0], "%s.%s: no description", k->section, k->key);
    int nested = k->type == BS_SCHEMA_OBJECT || k->type == BS_SCHEMA_ARRAY || k->type == BS_SCHEMA_MAP;
    cr_expect(nested ? k->sub && is_section(k->sub) : !k->sub, "%s.%s: sub", k->section, k->key);
    cr_expect(!k->choices || k->type == BS_SCHEMA_STRING || k->type == BS_SCHEMA_NUM_OR_CHOICE ||
                  k->type == BS_SCHEMA_STRINGS,
              "%s.%s: choices", k->section, k->key);
    cr_expect(k->type != BS_SCHEMA_NUM_OR_CHOICE || k->choices, "%s.%s: no choices", k->section, k->key);
    bs_schema_range r;
    if (bs__schema_range(k, &r)) cr_expect(r.has_lo || r.has_hi, "%s.%s: range %s", k->section, k->key, k->range);
    if (k->def) expect_default_fits(k);
    cr_expect(!(k->required && k->def), "%s.%s: required with a default", k->section, k->key);
    for (int j = 0; j < i; j++)
      cr_expect(strcmp(k->section, bs__schema_keys[j].section) || strcmp(k->key, bs__schema_keys[j].key),
                "%s.%s: twice", k->section, k->key);
  }
  for (int s = 1; s < bs__schema_n_sections; s++) { /* every section but the top is some key's value */
    int used = 0;
    for (int i = 0; i < bs__schema_n_keys; i++) used |= bs__schema_keys[i].sub && !strcmp(bs__schema_keys[i].sub, bs__schema_sections[s].name);
    cr_expect(used, "section %s is no key's value", bs__schema_sections[s].name);
  }
}

/* The size of the field a bound key of this type fills (0: no such key). */
static size_t bound_size(const bs_schema_key *k) {
  switch (k->type) {
  case BS_SCHEMA_NUMBER: return sizeof(double);
  case BS_SCHEMA_INTEGER:
  case BS_SCHEMA_BOOLEAN: return sizeof(int);
  case BS_SCHEMA_VEC3:
  case BS_SCHEMA_NUM_OR_VEC3: return 3 * sizeof(double);
  case BS_SCHEMA_IVEC3: return 3 * sizeof(int);
  case BS_SCHEMA_STRING: return k->choices ? sizeof(int) : k->size;
  default: return 0;
  }
}

/* Every bound key fills a field of its type's size inside its section's
 * struct; a choice's stored values are distinct; paths are strings. */
Test(scene_schema, bound_keys_fit_their_fields) {
  int n_bound = 0;
  for (int i = 0; i < bs__schema_n_keys; i++) {
    const bs_schema_key *k = &bs__schema_keys[i];
    cr_expect(!k->path || (k->type == BS_SCHEMA_STRING && !k->choices), "%s.%s: path", k->section, k->key);
    if (!bs__schema_bound(k)) continue;
    n_bound++;
    size_t want = bound_size(k);
    cr_expect(want > 0 && k->size == want, "%s.%s: a field of %zu bytes, the type needs %zu", k->section, k->key,
              k->size, want);
    const char *sec = k->section;
    size_t whole = !strcmp(sec, "bodies[].material") ? sizeof(bs_scene_material)
                   : !strncmp(sec, "bodies[]", 8)     ? sizeof(bs_scene_body)
                   : !strcmp(sec, "obstacles[]")      ? sizeof(bs_scene_obstacle)
                   : !strcmp(sec, "qoi[]")            ? sizeof(bs_scene_qoi)
                                                      : sizeof(bs_scene);
    cr_expect(k->offset + k->size <= whole, "%s.%s: outside its struct", k->section, k->key);
    for (int a = 0; k->choices && k->choices[a]; a++)
      for (int b = 0; b < a; b++)
        cr_expect(bs__schema_choice_value(k, a) != bs__schema_choice_value(k, b), "%s.%s: %s and %s store the same",
                  k->section, k->key, k->choices[a], k->choices[b]);
  }
  cr_expect(n_bound >= 80, "only %d keys are bound to fields", n_bound);
}

/* A key bound to a field is read into it, written from it, and starts at
 * its default: solver.tolerance and bodies[].mesher (a choice whose stored
 * values are not its index) through a load, and a scene built in C. */
Test(scene_schema, bound_keys_are_read_written_and_defaulted) {
  bs_scene *s = NULL;
  bs_error err;
  const char *sets[] = {"solver.tolerance=0.25", "bodies.0.mesher=\"cgal\"", "solver.amg_matrix=\"current\""};
  cr_assert_eq(bs_scene_parse(bs_test_full_scene, "full.json", 3, sets, &s, &err), 0, "%s", err.msg);
  cr_expect_eq(s->solver.min.tol, 0.25);
  cr_expect_eq(s->bodies[0].mesher, BS_SURFACE_CGAL);
  cr_expect_eq(s->solver.amg_at_rest, 0);
  char *text = NULL;
  cr_assert_eq(bs_scene_write_json(s, &text, &err), 0, "%s", err.msg);
  cr_expect(strstr(text, "\"mesher\": \"cgal\"") != NULL, "%s", text);
  cr_expect(strstr(text, "\"amg_matrix\": \"current\"") != NULL, "%s", text);
  free(text);
  bs_scene_destroy(&s);
  cr_assert_eq(bs_scene_create(&s, &err), 0);
  cr_expect_eq(s->solver.min.tol, 1e-3);
  cr_expect_eq(s->self_stiffness, 1e5);
  cr_expect_eq(s->solver.amg_at_rest, 1);
  bs_scene_destroy(&s);
}

/* ---- the table against the loader, key by key ---------------------------- */

/* The full scene with overrides: the status, the message in err. */
static int load_full(int n, const char *const *sets, bs_error *err) {
  bs_scene *s = NULL;
  int st = bs_scene_parse(bs_test_full_scene, "full.json", n, sets, &s, err);
  bs_scene_destroy(&s);
  return st;
}

static void expect_refused(const char *set, const char *parent, const char *key, const char *also) {
  bs_error err;
  int st = load_full(1, &set, &err);
  cr_expect_eq(st, BS_EINPUT, "--set %s: status %d (%s)", set, st, st ? err.msg : "loaded");
  if (!st) return;
  cr_expect(strstr(err.msg, "full.json: ") == err.msg, "--set %s: %s", set, err.msg);
  cr_expect(strstr(err.msg, parent) && strstr(err.msg, key), "--set %s: message should name %s and %s: %s", set,
            parent, key, err.msg);
  if (also) cr_expect(strstr(err.msg, also) != NULL, "--set %s: message should hold '%s': %s", set, also, err.msg);
}

static void expect_loads(const char *set) {
  bs_error err;
  int st = load_full(1, &set, &err);
  cr_expect_eq(st, 0, "--set %s: %s", set, err.msg);
}

Test(scene_schema, full_scene_loads) {
  expect_loads("description=\"every section\"");
}

/* A value of the wrong JSON type for each key is refused, naming the key
 * and what it got. */
Test(scene_schema, types_agree_with_the_loader) {
  static const char *const wrong[] = {
      [BS_SCHEMA_NUMBER] = "\"abc\"", [BS_SCHEMA_INTEGER] = "2.5", [BS_SCHEMA_STRING] = "5",
      [BS_SCHEMA_BOOLEAN] = "1", [BS_SCHEMA_VEC3] = "[1, 2]", [BS_SCHEMA_IVEC3] = "\"x\"",
      [BS_SCHEMA_NUM_OR_VEC3] = "[1, 2]", [BS_SCHEMA_NUM_OR_CHOICE] = "true", [BS_SCHEMA_OBJECT] = "5",
      [BS_SCHEMA_ARRAY] = "{}", [BS_SCHEMA_MAP] = "[1]", [BS_SCHEMA_STRINGS] = "[\"a\", 1]"};
  for (int i = 0; i < bs__schema_n_keys; i++) {
    const bs_schema_key *k = &bs__schema_keys[i];
    char path[256], set[512], parent[256];
    bs_test_key_path(k->section, k->key, path, sizeof path);
    bs_test_section_path(k->section, parent, sizeof parent);
    snprintf(set, sizeof set, "%s=%s", path, wrong[k->type]);
    expect_refused(set, path, k->key, "got ");
  }
}

/* The outside of each range is refused (naming the key), a closed bound is
 * accepted. */
static void range_cases(const bs_schema_key *k, const char *path, const char *parent) {
  bs_schema_range r;
  bs__schema_range(k, &r);
  char set[512];
  int vec = k->type == BS_SCHEMA_VEC3 || k->type == BS_SCHEMA_IVEC3 || k->type == BS_SCHEMA_NUM_OR_VEC3;
  double mid = r.has_lo ? r.lo + 1 : r.has_hi ? r.hi - 1 : 0;
  if (r.has_lo && r.has_hi) mid = 0.5 * (r.lo + r.hi);
  if (k->type == BS_SCHEMA_IVEC3) mid = (double)(long)mid;
  for (int side = 0; side < 2; side++) {
    if (!(side ? r.has_hi : r.has_lo)) continue;
    double bound = side ? r.hi : r.lo, step = side ? 1 : -1;
    int open = side ? r.hi_open : r.lo_open;
    double outside = open ? bound : bound + step * (k->type == BS_SCHEMA_NUMBER ? 1e-3 * (fabs(bound) + 1) : 1);
    if (k->type == BS_SCHEMA_ARRAY) {
      if (!side) {
        snprintf(set, sizeof set, "%s=[]", path);
        expect_refused(set, parent, k->key, NULL);
      }
      continue;
    }
    if (vec) snprintf(set, sizeof set, "%s=[%.10g, %.10g, %.10g]", path, outside, mid, mid);
    else snprintf(set, sizeof set, "%s=%.10g", path, outside);
    expect_refused(set, parent, k->key, NULL);
    if (open) continue;
    if (vec) snprintf(set, sizeof set, "%s=[%.17g, %.17g, %.17g]", path, bound, mid, mid);
    else snprintf(set, sizeof set, "%s=%.17g", path, bound);
    expect_loads(set);
  }
}

Test(scene_schema, ranges_agree_with_the_loader) {
  int n = 0;
  for (int i = 0; i < bs__schema_n_keys; i++) {
    const bs_schema_key *k = &bs__schema_keys[i];
    bs_schema_range r;
    if (!bs__schema_range(k, &r)) continue;
    char path[256], parent[256];
    bs_test_key_path(k->section, k->key, path, sizeof path);
    bs_test_section_path(k->section, parent, sizeof parent);
    range_cases(k, path, parent[0] ? parent : k->key);
    n++;
  }
  cr_expect_geq(n, 30, "only %d ranged keys", n);
}

/* Every allowed string loads; a near miss is refused with the right guess. */
Test(scene_schema, choices_agree_with_the_loader) {
  for (int i = 0; i < bs__schema_n_keys; i++) {
    const bs_schema_key *k = &bs__schema_keys[i];
    if (!k->choices) continue;
    char path[256], set[2][600], hint[128];
    bs_test_key_path(k->section, k->key, path, sizeof path);
    const char *open = k->type == BS_SCHEMA_STRINGS ? "[" : "", *close = k->type == BS_SCHEMA_STRINGS ? "]" : "";
    for (int c = 0; k->choices[c]; c++) {
      snprintf(set[0], sizeof set[0], "%s=%s\"%s\"%s", path, open, k->choices[c], close);
      snprintf(set[1], sizeof set[1], "obstacles.0.file=\"%s\"", BS_SOURCE_DIR "/data/levelsets/bowl.bsls");
      bs_error err;
      const char *sets[2] = {set[0], set[1]};
      int st = load_full(!strcmp(k->choices[c], "grid") ? 2 : 1, sets, &err);
      cr_expect_eq(st, 0, "--set %s: %s", set[0], err.msg);
      if (k->type == BS_SCHEMA_NUM_OR_CHOICE) continue;
      snprintf(set[0], sizeof set[0], "%s=%s\"%sx\"%s", path, open, k->choices[c], close);
      snprintf(hint, sizeof hint, "did you mean \"%s\"?", k->choices[c]);
      expect_refused(set[0], path, k->key, hint);
    }
  }
}

/* cJSON helpers: the member at a dotted path ("bodies.0.box"), its parent. */
static cJSON *at_path(cJSON *root, const char *path, cJSON **parent) {
  char buf[256];
  snprintf(buf, sizeof buf, "%s", path);
  cJSON *node = root, *up = NULL;
  for (char *save = NULL, *tok = strtok_r(buf, ".", &save); tok && node; tok = strtok_r(NULL, ".", &save)) {
    up = node;
    node = cJSON_IsArray(node) ? cJSON_GetArrayItem(node, atoi(tok)) : cJSON_GetObjectItemCaseSensitive(node, tok);
  }
  if (parent) *parent = up;
  return node;
}

/* Without a required key the scene is refused ("missing"); without any
 * other key of the full scene it loads, but for keys another key needs. */
Test(scene_schema, required_keys_agree_with_the_loader) {
  static const char *const needed[] = {"bodies.0.box", "bodies.0.initial_state.lo", "bodies.0.initial_state.hi",
                                       "bodies.0.scripted.0.keyframes", NULL};
  for (int i = 0; i < bs__schema_n_keys; i++) {
    const bs_schema_key *k = &bs__schema_keys[i];
    char path[256];
    bs_test_key_path(k->section, k->key, path, sizeof path);
    cJSON *root = cJSON_Parse(bs_test_full_scene), *parent;
    if (!at_path(root, path, &parent)) { /* not in the full scene */
      cr_expect(!k->required, "%s: required but not in the full scene", path);
      cJSON_Delete(root);
      continue;
    }
    cJSON_DeleteItemFromObjectCaseSensitive(parent, k->key);
    char *text = cJSON_Print(root);
    bs_scene *s = NULL;
    bs_error err;
    int st = bs_scene_parse(text, "full.json", 0, NULL, &s, &err);
    int needed_by_another = 0;
    for (int j = 0; needed[j]; j++) needed_by_another |= !strcmp(needed[j], path);
    if (k->required)
      cr_expect(st == BS_EINPUT && strstr(err.msg, path) && strstr(err.msg, "missing"), "without %s: %s", path,
                st ? err.msg : "loaded");
    else if (needed_by_another) cr_expect_eq(st, BS_EINPUT, "without %s: loaded", path);
    else cr_expect_eq(st, 0, "without %s: %s", path, err.msg);
    bs_scene_destroy(&s);
    free(text);
    cJSON_Delete(root);
  }
}
