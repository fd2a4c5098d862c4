/* json_print.h — JSON text for people (not installed): two-space indents,
 * one member per line, arrays of numbers, strings and booleans on one line
 * (cJSON_Print indents with tabs and puts a tab after each colon). Used for
 * the JSON Schema (scene_schema_json.c) and the resolved scene
 * (scene_write.c). */
#ifndef BS_JSON_PRINT_H
#define BS_JSON_PRINT_H

#include <cJSON.h>

/* The text of v ending in a newline, malloc'd (free it); NULL when out of
 * memory. Numbers and strings are printed as cJSON prints them (numbers to
 * 17 significant digits when 15 do not give the value back). */
char *bs__json_print(const cJSON *v);

#endif
