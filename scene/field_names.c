/* field_names.c — the names of the output fields (bs_field_names.h) and the scene
 * key output.fields parsed into a set, once. */
#include <stdio.h>
#include <string.h>

#include <cJSON.h>

#include "bs_field_names.h"
#include "fields_json.h"

const char *const bs__field_names[BS_FIELD_COUNT + 1] = {
    [BS_FIELD_DISPLACEMENT] = "displacement", [BS_FIELD_VELOCITY] = "velocity",
    [BS_FIELD_SCRIPTED] = "scripted",         [BS_FIELD_BODY] = "body",
    [BS_FIELD_MATERIAL] = "material",         [BS_FIELD_DETF] = "detF",
    [BS_FIELD_INVERTED] = "inverted",         [BS_FIELD_FIRST_PIOLA] = "first_piola",
    [BS_FIELD_CAUCHY] = "cauchy",             [BS_FIELD_VON_MISES] = "von_mises",
    [BS_FIELD_GREEN_STRAIN] = "green_strain", [BS_FIELD_STRETCHES] = "stretches",
    [BS_FIELD_ENERGY_DENSITY] = "energy_density", [BS_FIELD_ELASTIC_FORCE] = "elastic_force",
    [BS_FIELD_CONTACT_FORCE] = "contact_force",   [BS_FIELD_FRICTION_IMPULSE] = "friction_impulse",
    [BS_FIELD_COUNT] = NULL};

const char *bs_field_name(bs_field f) { return (unsigned)f < BS_FIELD_COUNT ? bs__field_names[f] : "unknown"; }

int bs_field_parse(const char *name, bs_field *out, bs_error *err) {
  for (int i = 0; name && i < BS_FIELD_COUNT; i++)
    if (!strcmp(name, bs__field_names[i])) {
      *out = (bs_field)i;
      return 0;
    }
  char list[512] = "";
  for (int i = 0; i < BS_FIELD_COUNT; i++) {
    strncat(list, bs__field_names[i], sizeof list - strlen(list) - 1);
    if (i + 1 < BS_FIELD_COUNT) strncat(list, ", ", sizeof list - strlen(list) - 1);
  }
  return bs_error_set(err, BS_EINPUT, "unknown field \"%s\" (allowed: %s)", name ? name : "(null)", list);
}

int bs_fields_parse_names(int n, const char *const *list, uint32_t *set, bs_error *err) {
  uint32_t s = 0;
  for (int i = 0; i < n; i++) {
    bs_field f;
    int st = bs_field_parse(list[i], &f, err);
    if (st) {
      bs_error_prefix(err, "output.fields.%d", i);
      return st;
    }
    s |= BS_FIELD_BIT(f);
  }
  *set = s;
  return 0;
}

int bs__fields_parse_json(const cJSON *arr, const char *file, uint32_t *set, bs_error *err) {
  if (!arr) return 0;
  if (!cJSON_IsArray(arr)) return bs_error_set(err, BS_EINPUT, "%s: output.fields: must be an array of field names", file);
  enum { MAX = 64 };
  const char *list[MAX];
  int n = 0;
  for (const cJSON *it = arr->child; it; it = it->next, n++) {
    if (n == MAX) return bs_error_set(err, BS_EINPUT, "%s: output.fields: more than %d names", file, MAX);
    if (!cJSON_IsString(it)) return bs_error_set(err, BS_EINPUT, "%s: output.fields.%d: must be a string", file, n);
    list[n] = it->valuestring;
  }
  int st = bs_fields_parse_names(n, list, set, err);
  if (st) bs_error_prefix(err, "%s", file);
  return st;
}
