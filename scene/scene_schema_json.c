/* scene_schema_json.c — the JSON Schema (draft-07, what editors such as VS
 * Code complete and check with) generated from the schema table
 * (scene_schema.h). Subschemas are inlined, so that every property carries
 * its own description and default. */
#include <stdio.h>
#include <string.h>

#include <cJSON.h>

#include "bs_scene.h"
#include "json_print.h"
#include "scene_schema.h"

/* Adds the range's bounds of r to a number (or integer) schema. */
static void add_range(cJSON *o, const bs_schema_range *r) {
  if (r->has_lo) cJSON_AddNumberToObject(o, r->lo_open ? "exclusiveMinimum" : "minimum", r->lo);
  if (r->has_hi) cJSON_AddNumberToObject(o, r->hi_open ? "exclusiveMaximum" : "maximum", r->hi);
}

static cJSON *scalar(const char *type, const bs_schema_range *r) {
  cJSON *o = cJSON_CreateObject();
  cJSON_AddStringToObject(o, "type", type);
  if (r) add_range(o, r);
  return o;
}

/* An array of 3 elements of the given type, each in r. */
static cJSON *triple(const char *type, const bs_schema_range *r) {
  cJSON *o = scalar("array", NULL);
  cJSON_AddItemToObject(o, "items", scalar(type, r));
  cJSON_AddNumberToObject(o, "minItems", 3);
  cJSON_AddNumberToObject(o, "maxItems", 3);
  return o;
}

static cJSON *choices(const char *const *c) {
  cJSON *a = cJSON_CreateArray();
  for (int i = 0; c[i]; i++) cJSON_AddItemToArray(a, cJSON_CreateString(c[i]));
  return a;
}

static cJSON *section_schema(const char *name);

/* Moves every member of `from` to the end of `to`, then frees `from`. */
static void move_members(cJSON *to, cJSON *from) {
  while (from->child) {
    cJSON *m = cJSON_DetachItemViaPointer(from, from->child);
    cJSON_AddItemToObject(to, m->string, m);
  }
  cJSON_Delete(from);
}

/* The value schema of one key, without description and default. */
static cJSON *value_schema(const bs_schema_key *k) {
  bs_schema_range r;
  bs__schema_range(k, &r);
  cJSON *o = NULL;
  switch (k->type) {
  case BS_SCHEMA_NUMBER: return scalar("number", &r);
  case BS_SCHEMA_INTEGER: return scalar("integer", &r);
  case BS_SCHEMA_BOOLEAN: return scalar("boolean", NULL);
  case BS_SCHEMA_STRING:
    o = scalar("string", NULL);
    if (k->choices) cJSON_AddItemToObject(o, "enum", choices(k->choices));
    return o;
  case BS_SCHEMA_VEC3: return triple("number", &r);
  case BS_SCHEMA_IVEC3: return triple("integer", &r);
  case BS_SCHEMA_NUM_OR_VEC3: /* "type" ["number", "array"]: items apply to arrays only */
    o = triple("number", &r);
    cJSON_ReplaceItemInObject(o, "type", cJSON_CreateStringArray((const char *const[]){"number", "array"}, 2));
    add_range(o, &r);
    return o;
  case BS_SCHEMA_NUM_OR_CHOICE: {
    cJSON *strings = cJSON_CreateObject();
    cJSON_AddItemToObject(strings, "enum", choices(k->choices));
    o = cJSON_CreateObject();
    cJSON *any = cJSON_AddArrayToObject(o, "anyOf");
    cJSON_AddItemToArray(any, scalar("number", &r));
    cJSON_AddItemToArray(any, strings);
    return o;
  }
  case BS_SCHEMA_OBJECT: return section_schema(k->sub);
  case BS_SCHEMA_ARRAY:
    o = scalar("array", NULL);
    cJSON_AddItemToObject(o, "items", section_schema(k->sub));
    if (r.has_lo) cJSON_AddNumberToObject(o, "minItems", r.lo);
    return o;
  case BS_SCHEMA_STRINGS:
    o = scalar("array", NULL);
    cJSON *item = scalar("string", NULL);
    if (k->choices) cJSON_AddItemToObject(item, "enum", choices(k->choices));
    cJSON_AddItemToObject(o, "items", item);
    if (r.has_lo) cJSON_AddNumberToObject(o, "minItems", r.lo);
    if (r.has_hi) cJSON_AddNumberToObject(o, "maxItems", r.hi);
    if (k->choices) cJSON_AddTrueToObject(o, "uniqueItems");
    return o;
  case BS_SCHEMA_MAP:
    o = scalar("object", NULL);
    cJSON_AddItemToObject(o, "additionalProperties", section_schema(k->sub));
    return o;
  }
  return cJSON_CreateObject();
}

/* description first, then the value schema's members, then the default. */
static cJSON *key_schema(const bs_schema_key *k) {
  cJSON *o = cJSON_CreateObject(), *v = value_schema(k);
  cJSON_AddStringToObject(o, "description", k->doc);
  move_members(o, v);
  if (k->def) cJSON_AddItemToObject(o, "default", cJSON_Parse(k->def));
  return o;
}

/* "oneOf": [{"required": [a]}, {"required": [b]}, ...] for "a|b|...". */
static void add_one_of(cJSON *o, const char *one_of) {
  cJSON *alts = cJSON_AddArrayToObject(o, "oneOf");
  for (const char *p = one_of; *p;) {
    size_t n = strcspn(p, "|");
    char name[64];
    snprintf(name, sizeof name, "%.*s", (int)n, p);
    cJSON *alt = cJSON_CreateObject(), *req = cJSON_AddArrayToObject(alt, "required");
    cJSON_AddItemToArray(req, cJSON_CreateString(name));
    cJSON_AddItemToArray(alts, alt);
    p += n + (p[n] == '|');
  }
}

static cJSON *section_schema(const char *name) {
  cJSON *o = scalar("object", NULL), *props = cJSON_AddObjectToObject(o, "properties");
  cJSON *req = cJSON_CreateArray();
  for (int i = 0; i < bs__schema_n_keys; i++) {
    const bs_schema_key *k = &bs__schema_keys[i];
    if (strcmp(k->section, name)) continue;
    cJSON_AddItemToObject(props, k->key, key_schema(k));
    if (k->required) cJSON_AddItemToArray(req, cJSON_CreateString(k->key));
  }
  if (cJSON_GetArraySize(req)) cJSON_AddItemToObject(o, "required", req);
  else cJSON_Delete(req);
  cJSON_AddFalseToObject(o, "additionalProperties");
  for (int i = 0; i < bs__schema_n_sections; i++)
    if (!strcmp(bs__schema_sections[i].name, name) && bs__schema_sections[i].one_of)
      add_one_of(o, bs__schema_sections[i].one_of);
  return o;
}

int bs_scene_schema_json(char **out, bs_error *err) {
  *out = NULL;
  cJSON *root = cJSON_CreateObject();
  if (!root) return bs_error_set(err, BS_ENOMEM, "out of memory writing the scene schema");
  cJSON_AddStringToObject(root, "$schema", "http://json-schema.org/draft-07/schema#");
  cJSON_AddStringToObject(root, "title", "bigstep scene");
  cJSON_AddStringToObject(root, "description",
                          "A bigstep scene (SI units). Generated by `bigstep schema` from the table the loader "
                          "checks scenes with (scene/scene_schema.c); the loader also checks values this schema "
                          "cannot express.");
  cJSON *body = section_schema("");
  move_members(root, body);
  *out = bs__json_print(root);
  cJSON_Delete(root);
  return *out ? 0 : bs_error_set(err, BS_ENOMEM, "out of memory writing the scene schema");
}
