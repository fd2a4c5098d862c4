/* fields_json.h — the scene loader's hook for output.fields (private: not
 * installed; the public names and sets are in bs_field_names.h). */
#ifndef BS_FIELDS_JSON_H
#define BS_FIELDS_JSON_H

#include <stdint.h>

#include <cJSON.h>

#include "bs_base.h"

/* The field names in bs_field order, NULL-terminated (the schema table's
 * choices for output.fields). */
extern const char *const bs__field_names[];

/* output.fields (arr: the JSON value; NULL when absent: *set untouched) as a
 * set of bs_field bits. BS_EINPUT, naming file and the key path, for a value
 * that is not an array of strings or for an unknown name (listing the
 * allowed ones). */
int bs__fields_parse_json(const cJSON *arr, const char *file, uint32_t *set, bs_error *err);

#endif
